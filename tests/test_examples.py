"""Every program in examples/ runs, headless and in a (dummy) window.

The examples are found by glob (files starting with ``_`` are helpers), so a
new one is tested without touching this file. Each is run in a subprocess,
from a temporary folder, for a few frames; it must exit with 0 and write a
picture with something drawn in it. An example that imports a package not
installed here (matplotlib, say) is skipped.
"""
import ast
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

import tamias2d

Image = pytest.importorskip("PIL.Image")

EXAMPLES_DIR = Path(__file__).resolve().parent.parent / "examples"
EXAMPLES = sorted(p for p in EXAMPLES_DIR.glob("*.py") if not p.name.startswith("_"))
# The folder holding the tamias2d package this process uses.
PACKAGE_ROOT = Path(tamias2d.__file__).resolve().parent.parent
FRAMES = "4"


def missing_imports(path):
    """Top-level modules the example imports that are not installed."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    local = {p.stem for p in EXAMPLES_DIR.glob("*.py")}
    return sorted(n for n in names - local if importlib.util.find_spec(n) is None)


def run_example(path, args, cwd):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(PACKAGE_ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env.update(SDL_VIDEODRIVER="dummy", SDL_AUDIODRIVER="dummy", MPLBACKEND="Agg",
               PYGAME_HIDE_SUPPORT_PROMPT="1")
    return subprocess.run([sys.executable, str(path), *args], cwd=str(cwd), env=env,
                          capture_output=True, text=True, timeout=120,
                          stdin=subprocess.DEVNULL)


def check_picture(path):
    """The picture exists and is not one flat colour: at least 1% of its
    pixels differ from the commonest colour."""
    assert path.exists(), f"{path.name} was not written"
    with Image.open(path) as image:
        rgb = image.convert("RGB")
    counts = sorted(rgb.getcolors(maxcolors=1 << 24), reverse=True)
    pixels = rgb.width * rgb.height
    assert rgb.width >= 200 and rgb.height >= 200, rgb.size
    assert len(counts) >= 3, f"{path.name} has {len(counts)} colours"
    assert pixels - counts[0][0] > 0.01 * pixels, f"{path.name} is nearly blank"


def test_examples_are_found():
    assert len(EXAMPLES) >= 11
    assert not any(p.name.startswith("_") for p in EXAMPLES)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_headless(path, tmp_path):
    missing = missing_imports(path)
    if missing:
        pytest.skip(f"needs {', '.join(missing)}")
    result = run_example(path, ["--headless", "--frames", FRAMES, "--out", "out.png"],
                         tmp_path)
    assert result.returncode == 0, result.stderr
    check_picture(tmp_path / "out.png")


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_window(path, tmp_path):
    # The pygame path: a window on SDL's dummy driver, closed after a few
    # frames, with a screenshot at the end.
    pytest.importorskip("pygame")
    if "_common.run(" not in path.read_text():
        pytest.skip("opens no pygame window (speed_vs_error.py shows a matplotlib plot)")
    missing = missing_imports(path)
    if missing:
        pytest.skip(f"needs {', '.join(missing)}")
    result = run_example(path, ["--frames", FRAMES, "--out", "shot.png"], tmp_path)
    assert result.returncode == 0, result.stderr
    check_picture(tmp_path / "shot.png")


def test_gif(tmp_path):
    result = run_example(EXAMPLES_DIR / "chain.py",
                         ["--headless", "--frames", "12", "--gif", "--out", "a.gif"], tmp_path)
    assert result.returncode == 0, result.stderr
    with Image.open(tmp_path / "a.gif") as gif:
        assert gif.format == "GIF" and gif.n_frames == 12


def test_default_output_name(tmp_path):
    result = run_example(EXAMPLES_DIR / "bullets.py", ["--headless", "--frames", "2"], tmp_path)
    assert result.returncode == 0, result.stderr
    check_picture(tmp_path / "bullets.png")


def test_bad_frame_count(tmp_path):
    result = run_example(EXAMPLES_DIR / "chain.py", ["--headless", "--frames", "0"], tmp_path)
    assert result.returncode == 2
    assert "at least 1" in result.stderr and "Traceback" not in result.stderr


def test_readme_lists_every_example():
    readme = (EXAMPLES_DIR / "README.md").read_text()
    unlisted = [p.name for p in EXAMPLES if f"`{p.name}`" not in readme]
    assert not unlisted, f"add {unlisted} to examples/README.md"


def test_rollback_replays_exactly(tmp_path):
    # rollback.py checks its own replays and exits 1 on any difference.
    result = run_example(EXAMPLES_DIR / "rollback.py",
                         ["--headless", "--frames", "130", "--out", "r.png"], tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "2 rollbacks, 120 frames replayed, 0 differed" in result.stdout


def test_playground_mouse(monkeypatch):
    # The window's mouse handling, fed pygame events in this process.
    pygame = pytest.importorskip("pygame")
    import runpy

    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.syspath_prepend(str(EXAMPLES_DIR))
    pygame.display.init()
    try:
        g = runpy.run_path(str(EXAMPLES_DIR / "playground.py"), run_name="playground")
        space, on_event = g["space"], g["on_event"]
        height = g["HEIGHT"]

        def click(kind, world, button=1):
            on_event(pygame.event.Event(kind, pos=(world[0], height - world[1]),
                                        button=button))

        n = len(space.bodies)
        click(pygame.MOUSEBUTTONDOWN, (600, 400))          # empty: adds a box
        assert len(space.bodies) == n + 1
        toy = g["toy"]
        click(pygame.MOUSEBUTTONDOWN, tuple(toy.position))  # on a body: grabs it
        drag = on_event.__globals__["drag"]
        assert drag is not None and drag.b is toy and drag in space.constraints
        click(pygame.MOUSEBUTTONUP, (0, 0))
        assert on_event.__globals__["drag"] is None and drag not in space.constraints
        click(pygame.MOUSEBUTTONDOWN, tuple(toy.position))  # grabbed again ...
        drag = on_event.__globals__["drag"]
        click(pygame.MOUSEBUTTONDOWN, tuple(toy.position), button=3)  # ... and deleted
        assert on_event.__globals__["drag"] is None and drag not in space.constraints
        assert toy not in space.bodies and len(space.bodies) == n
        click(pygame.MOUSEBUTTONUP, (0, 0))                 # releasing then is harmless
    finally:
        pygame.display.quit()
