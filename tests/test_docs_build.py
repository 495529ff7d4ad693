"""The documentation site builds with warnings as errors, and its API
reference covers the public API.

Needs Sphinx and MyST (the ``docs`` and ``test`` extras); skipped without
them. The build is the documented command,
``python -m sphinx -W -b html docs docs/_build/html``, into a temporary
folder, with the examples gallery's runs turned off (they are tested on
small examples of this file's own below).
"""
import ast
import doctest
import importlib
import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("sphinx")
pytest.importorskip("myst_parser")

import tamias2d  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS / "_ext"))
import tamias2d_sphinx  # noqa: E402

# The public modules: each has a section of the API reference.
PUBLIC_MODULES = [
    "tamias2d", "tamias2d.vector", "tamias2d.body", "tamias2d.shape", "tamias2d.collision",
    "tamias2d.arbiter", "tamias2d.space", "tamias2d.constraints", "tamias2d.batch",
    "tamias2d.autogeometry", "tamias2d.util", "tamias2d.errors",
    "tamias2d.space_debug_draw_options", "tamias2d.pygame_util", "tamias2d.pyglet_util",
    "tamias2d.matplotlib_util", "tamias2d.pillow_util", "tamias2d.demo",
]

KEY_PAGES = ["index", "tutorial", "coming-from-pymunk", "coming-from-box2d", "examples",
             "api/index", "api/package", "api/space", "api/constraints",
             "architecture", "benchmarks", "stability", "demo", "mis-map"]


def _env():
    env = dict(os.environ)
    # The build documents the tamias2d this test imports (installed, or a
    # development build under PYTHONPATH).
    env["PYTHONPATH"] = os.pathsep.join(
        p for p in [str(Path(tamias2d.__file__).resolve().parent.parent), env.get("PYTHONPATH")] if p)
    return env


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("html")
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "-b", "html", "-q",
         "-D", "tamias2d_gallery_run=0", str(DOCS), str(out)],
        capture_output=True, text=True, env=_env(), timeout=300)
    assert proc.returncode == 0, f"the docs build failed:\n{proc.stderr[-6000:]}"
    return out


def _inventory(site):
    from sphinx.util.inventory import InventoryFile
    with open(site / "objects.inv", "rb") as f:
        inventory = InventoryFile.load(f, "", lambda base, uri: uri)
    items = inventory.data.items() if hasattr(inventory, "data") else inventory.items()
    names = {}
    for kind, entries in items:
        if kind.startswith("py:"):
            for name in entries:
                names.setdefault(name, set()).add(kind)
    return names


def test_key_pages_exist(site):
    for page in KEY_PAGES:
        assert (site / f"{page}.html").is_file(), page
    index = (site / "index.html").read_text(encoding="utf-8")
    for page in KEY_PAGES[1:]:
        assert f'href="{page}.html' in index, f"index does not link to {page}"
    assert (site / "_images" / "tutorial.png").is_file()
    assert (site / "_images" / "demo-scenes.png").is_file()


def test_markdown_pages_render_their_tables_and_headings(site):
    # MyST, not plain text: the tables and headings of the docs/*.md pages.
    bench = (site / "benchmarks.html").read_text(encoding="utf-8")
    assert "<table" in bench and 'id="running-the-benchmarks"' in bench
    stability = (site / "stability.html").read_text(encoding="utf-8")
    assert 'href="#snapshots"' in stability


def test_every_public_name_is_in_the_api_reference(site):
    names = _inventory(site)
    for modname in PUBLIC_MODULES:
        assert "py:module" in names.get(modname, ()), f"module {modname} is not documented"
    missing = []
    for modname in PUBLIC_MODULES:
        module = importlib.import_module(modname)
        public = getattr(module, "__all__", None) or [
            n for n, v in vars(module).items()
            if not n.startswith("_") and getattr(v, "__module__", None) == modname]
        for name in public:
            obj = getattr(module, name)
            where = {f"{modname}.{name}", f"tamias2d.{name}",
                     f"{getattr(obj, '__module__', modname)}.{name}"} & set(names)
            if not where:
                missing.append(f"{modname}.{name}")
                continue
            if inspect.isclass(obj):
                for member in vars(obj):
                    if member.startswith("_"):
                        continue
                    if not any(f"{w}.{member}" in names for w in where):
                        missing.append(f"{modname}.{name}.{member}")
    assert not missing, "not in the API reference: " + ", ".join(missing)
    # the package's own list, every name of it
    for name in tamias2d.__all__:
        assert f"tamias2d.{name}" in names or any(
            n.endswith("." + name) and n.startswith("tamias2d.") for n in names), name


def test_signatures_are_python_not_cython(site):
    # embedsignature's C notation ("Body body", "double dt", "self") is
    # rewritten by docs/_ext/tamias2d_sphinx.py
    for page in ("body", "collision", "shapes", "space", "arbiter"):
        path = site / "api" / f"{page}.html"
        if not path.exists():
            continue
        html = path.read_text(encoding="utf-8")
        signatures = re.findall(r'<dt class="sig sig-object py"[^>]*>(.*?)</dt>', html, re.S)
        assert signatures, page
        text = [re.sub(r"<[^>]+>", "", s) for s in signatures]
        for sig in text:
            assert "(self" not in sig and "double " not in sig and "Body body" not in sig, sig
    body = re.sub(r"<[^>]+>", "", (site / "api" / "body.html").read_text(encoding="utf-8"))
    assert "update_velocity(body: Body, gravity, damping: float, dt: float)" in body
    space = re.sub(r"<[^>]+>", "", (site / "api" / "space.html").read_text(encoding="utf-8"))
    assert "Space(threaded=False, *, solver='chipmunk')" in space


def test_batch_constants_on_the_page_are_the_modules():
    # docs/api/batch.rst writes the two constants out (no docstring survives
    # compilation for a module-level value)
    import tamias2d.batch as batch
    text = (DOCS / "api" / "batch.rst").read_text(encoding="utf-8")
    for name in ("BODY_FIELDS", "ARBITER_FIELDS"):
        match = re.search(rf"py:data:: {name}\n\s+:value: (.*)\n", text)
        assert match, name
        assert ast.literal_eval(match.group(1)) == getattr(batch, name)


def test_gallery_page_matches_the_examples_folder(site):
    page = (site / "examples.html").read_text(encoding="utf-8")
    examples = sorted(p for p in (ROOT / "examples").glob("*.py") if not p.name.startswith("_")) \
        if (ROOT / "examples").is_dir() else []
    if not examples:
        assert "No examples in this build" in page
    for path in examples:
        assert f'id="example-{path.stem.replace("_", "-").lower()}"' in page, path.name


def test_signature_helpers():
    results = doctest.testmod(tamias2d_sphinx)
    assert results.attempted > 0 and results.failed == 0
    assert tamias2d_sphinx.python_signature("(Body body, int n=3)") == "(body: Body, n: int = 3)"
    assert tamias2d_sphinx._stub_signature(tamias2d.Space) == "(threaded=False, *, solver='chipmunk')"


# -- the gallery on examples of its own ---------------------------------------------

_DRAWING_EXAMPLE = '''"""A box on a floor, drawn headless."""
import argparse, tamias2d
from tamias2d import pillow_util
parser = argparse.ArgumentParser()
parser.add_argument("--headless", action="store_true")
parser.add_argument("--frames", type=int, default=600)
args = parser.parse_args()
assert args.headless
space = tamias2d.Space()
space.gravity = 0, -900
space.add(tamias2d.Segment(space.static_body, (0, 10), (200, 10), 3))
body = tamias2d.Body(1, 100)
body.position = 100, 100
space.add(body, tamias2d.Poly.create_box(body, (20, 20)))
for _ in range(args.frames):
    space.step(1 / 60)
options = pillow_util.DrawOptions((64, 48), bb=(0, 0, 200, 150))
space.debug_draw(options)
options.image.save("box.png")
with open(COUNTER, "a") as f:
    f.write("ran\\n")
'''


def test_gallery_runs_examples_and_takes_their_pictures(tmp_path):
    pytest.importorskip("PIL")
    examples, cache = tmp_path / "examples", tmp_path / "cache"
    examples.mkdir()
    counter = tmp_path / "runs.txt"
    (examples / "box.py").write_text(_DRAWING_EXAMPLE.replace("COUNTER", repr(str(counter))))
    (examples / "broken.py").write_text('"""Needs a window."""\nraise SystemExit("no display")\n')
    (examples / "silent.py").write_text('"""Draws nothing."""\n')
    (examples / "kept.py").write_text('"""Has its picture in the repository."""\nraise SystemExit(3)\n')
    (examples / "kept.png").write_bytes((ROOT / "docs" / "tutorial.png").read_bytes())
    (examples / "_helper.py").write_text("x = 1\n")

    entries = {e["name"]: e for e in tamias2d_sphinx.collect_examples(examples, cache, frames=5)}
    assert sorted(entries) == ["box", "broken", "kept", "silent"]
    assert entries["box"]["docstring"] == "A box on a floor, drawn headless."
    assert entries["box"]["picture"].parent == cache and entries["box"]["note"] is None
    assert entries["box"]["picture"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert entries["broken"]["picture"] is None and "no display" in entries["broken"]["note"]
    assert entries["silent"]["picture"] is None and "no PNG" in entries["silent"]["note"]
    assert entries["kept"]["picture"] == examples / "kept.png"

    # an unchanged example is not run again; a changed one is
    tamias2d_sphinx.collect_examples(examples, cache, frames=5)
    assert counter.read_text().count("ran") == 1
    (examples / "box.py").write_text(_DRAWING_EXAMPLE.replace("COUNTER", repr(str(counter))) + "\n")
    tamias2d_sphinx.collect_examples(examples, cache, frames=5)
    assert counter.read_text().count("ran") == 2

    off = {e["name"]: e for e in tamias2d_sphinx.collect_examples(examples, tmp_path / "c2", run=False)}
    assert off["box"]["picture"] is None and "not run" in off["box"]["note"]


def test_gallery_without_examples(tmp_path):
    assert tamias2d_sphinx.collect_examples(tmp_path / "absent", tmp_path / "cache") == []
    (tmp_path / "empty").mkdir()
    assert tamias2d_sphinx.collect_examples(tmp_path / "empty", tmp_path / "cache") == []


def test_gallery_page_with_examples_builds(tmp_path):
    """A whole build whose gallery has one example that runs and one that
    fails: no warning (-W), a picture and a note."""
    examples = tmp_path / "examples"
    examples.mkdir()
    counter = tmp_path / "runs.txt"
    (examples / "box.py").write_text(_DRAWING_EXAMPLE.replace("COUNTER", repr(str(counter))))
    (examples / "broken.py").write_text('"""Needs a window."""\nraise SystemExit("no display")\n')
    out = tmp_path / "html"
    # Only the gallery page and what it needs: the other pages are the
    # fixture's build.
    conf = tmp_path / "src"
    conf.mkdir()
    (conf / "conf.py").write_text(
        "import sys\n"
        f"sys.path.insert(0, {str(DOCS / '_ext')!r})\n"
        "extensions = ['tamias2d_sphinx']\n"
        f"tamias2d_examples_dir = {str(examples)!r}\n"
        "tamias2d_gallery_frames = 5\n")
    (conf / "index.rst").write_text((DOCS / "examples.rst").read_text(encoding="utf-8"))
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-b", "html", "-q", str(conf), str(out)],
                          capture_output=True, text=True, env=_env(), timeout=120)
    assert proc.returncode == 0, proc.stderr[-4000:]
    page = (out / "index.html").read_text(encoding="utf-8")
    assert 'id="example-box"' in page and 'id="example-broken"' in page
    assert re.search(r'<img alt="box drawn headless" src="_images/box-[0-9a-f]+\.png"', page)
    assert "No picture" in page and "no display" in page
    assert list((out / "_images").glob("box-*.png"))
