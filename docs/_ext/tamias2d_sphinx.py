"""Sphinx support for the tamias2d documentation.

Two parts:

- Signatures of compiled functions. Cython's ``embedsignature`` writes a
  signature line at the top of every docstring, which autodoc reads. It is in
  Cython's own notation: C-typed parameters (``Body body``, ``double dt``)
  and, for a class whose ``__init__`` has keyword-only parameters, a bare
  ``*`` in the wrong place. :func:`python_signature` turns such a line into a
  Python signature; where it cannot, the signature is taken from the type
  stub (``.pyi``) beside the module, which ``tests/test_stubs.py`` keeps equal
  to the runtime.

- The examples gallery: the ``tamias2d-gallery`` directive lists every
  ``examples/*.py`` with its module docstring, the picture it draws and its
  source, at build time, so the page follows whatever examples exist.
"""
import ast
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.util import logging

logger = logging.getLogger(__name__)

# C types that Cython writes into signatures, as Python annotations.
_C_TYPES = {"double": "float", "float": "float", "int": "int", "long": "int",
            "bint": "bool", "size_t": "int", "Py_ssize_t": "int", "cpFloat": "float"}

_TYPED_PARAM = re.compile(r"^(?P<type>[A-Za-z_]\w*)\s+(?P<name>[A-Za-z_]\w*)(?P<rest>\s*=.*)?$")


def _split_params(text):
    """Split a parameter list at top-level commas."""
    parts, depth, start, quote = [], 0, 0, None
    for i, ch in enumerate(text):
        if quote:
            if ch == quote and text[i - 1] != "\\":
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:i].strip())
            start = i + 1
    tail = text[start:].strip()
    if tail:
        parts.append(tail)
    return parts


def _valid(args, retann):
    source = f"def f{args}{' -> ' + retann if retann else ''}: pass"
    try:
        ast.parse(source)
    except SyntaxError:
        return False
    return True


def python_signature(args, retann=None, drop_self=False):
    """Cython's signature text ``args`` (with its parentheses) in Python's
    notation, or None if it cannot be made valid Python.

    >>> python_signature("(Body body, gravity, double damping, double dt)")
    '(body: Body, gravity, damping: float, dt: float)'
    >>> python_signature("(self, int index=0)", drop_self=True)
    '(index: int = 0)'
    >>> python_signature("(threaded=False, solver='chipmunk', *)") is None
    True
    """
    if not (args.startswith("(") and args.endswith(")")):
        return None
    params = []
    for param in _split_params(args[1:-1]):
        match = _TYPED_PARAM.match(param)
        if match:
            ctype = _C_TYPES.get(match["type"], match["type"])
            rest = match["rest"]
            param = f"{match['name']}: {ctype}" + (f" = {rest.split('=', 1)[1].strip()}" if rest else "")
        params.append(param)
    if drop_self and params and params[0] in ("self", "cls"):
        params = params[1:]
    result = "(" + ", ".join(params) + ")"
    if not _valid(result, retann):
        return None
    return result


def _stub_signature(obj):
    """The parameters of ``obj`` (a function, method or class: a class gives
    its ``__init__``) as the ``.pyi`` stub of its module declares them,
    without ``self`` and without annotations (the docstrings say what each
    parameter is). None if there is no stub or no such definition."""
    module = sys.modules.get(getattr(obj, "__module__", None) or "")
    qualname = getattr(obj, "__qualname__", None)
    if module is None or not qualname or not getattr(module, "__file__", None):
        return None
    stub = Path(re.sub(r"(\.cpython[^.]*)?\.(so|pyd|py)$", "", module.__file__) + ".pyi")
    if not stub.is_file():
        return None
    node = ast.parse(stub.read_text(encoding="utf-8"))
    for name in qualname.split("."):
        found = [n for n in getattr(node, "body", []) if getattr(n, "name", None) == name]
        if not found:
            return None
        node = found[0]
    if isinstance(node, ast.ClassDef):
        init = [n for n in node.body if isinstance(n, ast.FunctionDef) and n.name == "__init__"]
        if not init:
            return None
        node = init[0]
    if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
        return None
    args = node.args
    if args.posonlyargs and args.posonlyargs[0].arg in ("self", "cls"):
        args.posonlyargs = args.posonlyargs[1:]
    elif args.args and args.args[0].arg in ("self", "cls"):
        args.args = args.args[1:]
    for arg in args.posonlyargs + args.args + args.kwonlyargs + [args.vararg, args.kwarg]:
        if arg is not None:
            arg.annotation = None
    return "(" + ast.unparse(args) + ")"


def _process_signature(app, what, name, obj, options, signature, return_annotation):
    if not signature:
        return None
    fixed = python_signature(signature, return_annotation, drop_self=what in ("method", "class"))
    if fixed is None:
        fixed = _stub_signature(obj)
        if fixed is None:
            logger.warning("cannot read the signature %s%s of %s as Python (and its stub has "
                           "none)", signature, return_annotation or "", name)
            return None
    return fixed, return_annotation


def _process_docstring(app, what, name, obj, options, lines):
    # Cython starts the docstring of a cdef attribute with "name: type" (its
    # C type, "object" for most); the API reference shows the text alone.
    short = name.rsplit(".", 1)[-1]
    if what == "attribute" and lines and re.match(rf"^{re.escape(short)}: [\w.]+$", lines[0]):
        del lines[0]
        while lines and not lines[0].strip():
            del lines[0]


# ---------------------------------------------------------------------------
# The examples gallery
# ---------------------------------------------------------------------------

def _module_docstring(path):
    try:
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    except (SyntaxError, UnicodeDecodeError, OSError) as exc:
        return None, f"could not be read: {exc}"
    return ast.get_docstring(tree), None


def _committed_picture(path):
    """A picture kept beside the example: ``X.png`` or ``images/X.png``."""
    for candidate in (path.with_suffix(".png"), path.parent / "images" / (path.stem + ".png")):
        if candidate.is_file():
            return candidate
    return None


def _tamias2d_path():
    """The folder holding the tamias2d package the docs describe, so that an
    example run from the build uses the same build."""
    import tamias2d
    return str(Path(tamias2d.__file__).resolve().parent.parent)


def run_example(path, cache_dir, frames, timeout):
    """Run ``python X.py --headless --frames N`` in a fresh folder and return
    (picture, None) with the PNG it wrote (copied into ``cache_dir``, keyed
    on the example's source, so an unchanged example runs once), or
    (None, reason)."""
    source = path.read_bytes()
    key = hashlib.sha256(source + f"frames={frames}".encode()).hexdigest()[:16]
    cached = Path(cache_dir) / f"{path.stem}-{key}.png"
    if cached.is_file():
        return cached, None
    Path(cache_dir).mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (_tamias2d_path(), env.get("PYTHONPATH")) if p)
    env.setdefault("SDL_VIDEODRIVER", "dummy")  # pygame examples: no window
    env.setdefault("SDL_AUDIODRIVER", "dummy")
    env.setdefault("MPLBACKEND", "Agg")
    # PNGs beside the example before the run: one written there by the run is
    # new or newer.
    before = {p: p.stat().st_mtime_ns for p in path.parent.glob("*.png")}
    with tempfile.TemporaryDirectory(prefix="tamias2d-example-") as cwd:
        try:
            proc = subprocess.run(
                [sys.executable, str(path.resolve()), "--headless", "--frames", str(frames)],
                cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return None, f"it did not end within {timeout} s"
        if proc.returncode != 0:
            last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
            return None, f"it exited with status {proc.returncode}: {last}"
        # The example may write into the folder it runs in or next to itself.
        written = [p for p in Path(cwd).rglob("*.png")]
        written += [p for p in path.parent.glob("*.png") if before.get(p) != p.stat().st_mtime_ns]
        if not written:
            return None, "it wrote no PNG"
        named = [p for p in written if p.stem.startswith(path.stem)]
        picture = max(named or written, key=lambda p: p.stat().st_mtime)
        shutil.copyfile(picture, cached)
    return cached, None


def collect_examples(examples_dir, cache_dir, run=True, frames=60, timeout=120):
    """One dict per ``examples_dir/*.py`` (sorted by name): name, path,
    docstring, picture (a Path or None), note (why there is no picture, or
    None). Files whose name starts with ``_`` are helpers, not examples."""
    examples_dir = Path(examples_dir)
    if not examples_dir.is_dir():
        return []
    entries = []
    for path in sorted(examples_dir.glob("*.py")):
        if path.name.startswith("_"):
            continue
        doc, problem = _module_docstring(path)
        picture, note, command = _committed_picture(path), problem, None
        if picture is None and problem is None:
            if run:
                command = f"python examples/{path.name} --headless --frames {frames}"
                picture, note = run_example(path, cache_dir, frames, timeout)
            else:
                note = "not run in this build (tamias2d_gallery_run is off)"
        entries.append({"name": path.stem, "path": path, "docstring": doc,
                        "picture": picture, "note": note, "picture_command": command})
    return entries


def _paragraphs(text):
    """Plain-text paragraphs: example docstrings are shown as written, not
    parsed as reStructuredText, so a docstring can never break the build."""
    result = []
    for block in re.split(r"\n\s*\n", text.strip()):
        lines = block.splitlines()
        if all(line.startswith(("    ", "$ ", ">>> ")) for line in lines) or block.lstrip().startswith(("$ ", "python ")):
            code = textwrap.dedent(block)
            result.append(nodes.literal_block(code, code, language="text"))
        else:
            result.append(nodes.paragraph(text=" ".join(line.strip() for line in lines)))
    return result


class GalleryDirective(Directive):
    """``.. tamias2d-gallery::``: a section per example."""
    has_content = False

    def run(self):
        env = self.state.document.settings.env
        config = env.config
        examples_dir = Path(config.tamias2d_examples_dir)
        if not examples_dir.is_absolute():
            examples_dir = (Path(env.srcdir) / examples_dir).resolve()
        env.note_dependency(str(examples_dir))  # a new or removed example
        cache_dir = Path(env.app.doctreedir) / "tamias2d-gallery"
        entries = collect_examples(examples_dir, cache_dir, run=config.tamias2d_gallery_run,
                                   frames=config.tamias2d_gallery_frames,
                                   timeout=config.tamias2d_gallery_timeout)
        if not entries:
            where = "does not exist" if not examples_dir.is_dir() else "holds no example (*.py)"
            note = nodes.note()
            note += nodes.paragraph(text=f"No examples in this build: the folder {examples_dir.name}/ "
                                         f"of the checkout {where}. Each examples/*.py appears "
                                         "here once it is there.")
            return [note]
        docdir = Path(env.doc2path(env.docname)).parent
        result = []
        for entry in entries:
            env.note_dependency(str(entry["path"]))
            section = nodes.section(ids=[nodes.make_id("example-" + entry["name"])],
                                    names=[nodes.fully_normalize_name(entry["name"])])
            section += nodes.title(text=entry["path"].name)
            if entry["docstring"]:
                section.extend(_paragraphs(entry["docstring"]))
            else:
                section += nodes.paragraph(text="(no module docstring)")
            if entry["picture"] is not None:
                uri = os.path.relpath(entry["picture"], docdir)
                section += nodes.image(uri=Path(uri).as_posix(), alt=f"{entry['name']} drawn headless")
            elif entry["note"]:
                para = nodes.paragraph()
                para += nodes.emphasis(text="No picture: ")
                if entry["picture_command"]:
                    para += nodes.Text("the build ran ")
                    para += nodes.literal(text=entry["picture_command"])
                    para += nodes.Text(" and ")
                para += nodes.Text(entry["note"] + ".")
                section += para
            command = f"python examples/{entry['path'].name}"
            section += nodes.paragraph(text="Run it from a checkout:")
            section += nodes.literal_block(command, command, language="sh")
            source = entry["path"].read_text(encoding="utf-8")
            container = nodes.container(classes=["tamias2d-example-source"])
            container += nodes.rubric(text="Source")
            container += nodes.literal_block(source, source, language="python")
            section += container
            result.append(section)
        return result


def setup(app):
    app.setup_extension("sphinx.ext.autodoc")  # its events are connected below
    app.add_config_value("tamias2d_examples_dir", "../examples", "env")
    app.add_config_value("tamias2d_gallery_run", True, "env")
    app.add_config_value("tamias2d_gallery_frames", 60, "env")
    app.add_config_value("tamias2d_gallery_timeout", 120, "env")
    app.add_directive("tamias2d-gallery", GalleryDirective)
    app.connect("autodoc-process-signature", _process_signature)
    app.connect("autodoc-process-docstring", _process_docstring)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
