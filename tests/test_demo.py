"""The demo command (``python -m tamias2d demo``) and its scenes.

The command runs in a subprocess from a temporary folder, the way a user
runs it, with the tamias2d that this test process imported on its path. The
scenes are also built with pymunk (``--engine pymunk``, and in-process) so
that the demo can be checked against the reference engine step by step.
"""
import doctest
import io
import os
import subprocess
import sys

import pymunk
import pytest

import tamias2d
from tamias2d import demo
from tamias2d.__main__ import build_parser, main


# The folder holding the tamias2d package this process uses (the checkout
# with in-place builds, or site-packages).
PACKAGE_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(tamias2d.__file__)))


def run_cli(args, cwd, extra_code=None):
    """Run ``python -m tamias2d ARGS`` (or code that blocks modules first)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = PACKAGE_ROOT + os.pathsep + env.get("PYTHONPATH", "")
    if extra_code is None:
        cmd = [sys.executable, "-m", "tamias2d", *args]
    else:
        cmd = [sys.executable, "-c",
               extra_code + "\nfrom tamias2d.__main__ import main\nimport sys\n"
               f"sys.exit(main({list(args)!r}))"]
    return subprocess.run(cmd, cwd=str(cwd), env=env, capture_output=True, text=True,
                          timeout=600, stdin=subprocess.DEVNULL)


def check_picture(path, size=(800, 600)):
    from PIL import Image

    assert os.path.exists(path), f"{path} was not written"
    image = Image.open(path)
    image.load()
    assert image.size == size
    rgb = image.convert("RGB")
    background = tuple(demo.BACKGROUND[:3])
    assert rgb.getpixel((size[0] - 1, size[1] - 1)) == background
    data = rgb.tobytes()
    drawn = sum(1 for i in range(0, len(data), 3) if tuple(data[i:i + 3]) != background)
    # Shapes cover a good part of the picture, and not all of it.
    assert 0.02 * size[0] * size[1] < drawn < 0.9 * size[0] * size[1], drawn
    return rgb


# --- the command line, whatever the engine --------------------------------


def test_help_lists_commands_and_scenes(tmp_path):
    top = run_cli(["--help"], tmp_path)
    assert top.returncode == 0
    assert "demo" in top.stdout and "version" in top.stdout
    sub = run_cli(["demo", "--help"], tmp_path)
    assert sub.returncode == 0
    for word in ("pyramid", "stack", "rain", "drum", "--steps", "--dt", "--out", "--gif",
                 "--size", "--quiet"):
        assert word in sub.stdout


def test_version(tmp_path):
    result = run_cli(["version"], tmp_path)
    assert result.returncode == 0
    assert result.stdout.strip() == \
        f"tamias2d {tamias2d.version} (Chipmunk {tamias2d.chipmunk_version})"
    assert run_cli(["--version"], tmp_path).stdout == result.stdout


@pytest.mark.parametrize("args, message", [
    (["demo", "--size", "800"], "WIDTHxHEIGHT"),
    (["demo", "--size", "4x4"], "16..8192"),
    (["demo", "--dt", "0"], "positive"),
    (["demo", "--dt", "fast"], "1/60"),
    (["demo", "--steps", "-1"], "at least 0"),
    (["demo", "--scene", "moon"], "invalid choice"),
    (["demo", "--out", "no/such/folder/x.png"], "does not exist"),
])
def test_bad_arguments_are_reported(tmp_path, args, message):
    result = run_cli(args, tmp_path)
    assert result.returncode == 2
    assert message in result.stderr
    assert "Traceback" not in result.stderr


def test_parser_defaults():
    args = build_parser().parse_args(["demo"])
    assert (args.scene, args.steps, args.dt, args.out, args.gif, args.size, args.quiet) == (
        "pyramid", 600, 1 / 60, "tamias2d-demo.png", None, (800, 600), False)
    assert build_parser().parse_args(["demo", "--dt", "1/120"]).dt == 1 / 120


def test_demo_with_pymunk_engine(tmp_path):
    # The command and the drawing, through pymunk's Space.debug_draw.
    pytest.importorskip("PIL")
    result = run_cli(["demo", "--engine", "pymunk", "--steps", "30", "--out", "p.png"], tmp_path)
    assert result.returncode == 0, result.stderr
    assert "engine pymunk" in result.stdout
    check_picture(str(tmp_path / "p.png"))


def test_progress_display():
    out = io.StringIO()
    p = demo.Progress(50, stream=out, label="x")
    for i in range(50):
        p.update(i + 1)
    p.close()
    lines = out.getvalue().splitlines()
    assert lines[0] == "x: step 5/50 (10%)" and lines[-1] == "x: step 50/50 (100%)"
    assert len(lines) == 10

    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty = Tty()
    p = demo.Progress(200, stream=tty)
    for i in range(200):
        p.update(i + 1)
    p.close()
    text = tty.getvalue()
    assert text.count("\r") == 101            # redrawn once per percent, 0 to 100
    assert "100%" in text and "200/200" in text and text.endswith("\n")
    silent = io.StringIO()
    p = demo.Progress(10, stream=silent, enabled=False)
    p.update(10)
    p.close()
    assert silent.getvalue() == ""


def test_kinetic_energy_matches_definition():
    space = pymunk.Space()
    body = pymunk.Body(2, 3)
    body.velocity = (3, 4)
    body.angular_velocity = 2
    space.add(body, pymunk.Circle(body, 1))
    kinematic = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    kinematic.velocity = (100, 0)
    space.add(kinematic)
    assert demo.kinetic_energy(space) == 0.5 * 2 * 25 + 0.5 * 3 * 4
    assert demo.kinetic_energy(space) * 2 == body.kinetic_energy


@pytest.mark.parametrize("name", sorted(demo.SCENES))
def test_scenes_build_and_run_on_pymunk(name):
    scene = demo.build_scene(name, engine=pymunk, steps=40)
    assert scene.name == name and scene.description
    left, bottom, right, top = scene.view
    assert left < right and bottom < top
    result = demo.run(scene, steps=40, dt=1 / 60)
    assert result.steps == 40 and result.step_time > 0
    assert result.kinetic_energy >= 0
    # Nothing has left the view.
    for body in scene.space.bodies:
        x, y = body.position
        assert left <= x <= right and bottom <= y <= top, (name, body.position)


def test_unknown_scene():
    with pytest.raises(ValueError, match="unknown scene"):
        demo.build_scene("moon")


# --- with tamias2d's own Space ---------------------------------------------


def test_demo_writes_a_picture(tmp_path):
    pytest.importorskip("PIL")
    result = run_cli(["demo", "--steps", "30", "--out", "tmp.png"], tmp_path)
    assert result.returncode == 0, result.stderr
    for word in ("bodies", "shapes", "steps", "per step", "kinetic energy", "tmp.png"):
        assert word in result.stdout
    # Not a terminal: plain progress lines.
    assert "step 30/30 (100%)" in result.stderr and "\r" not in result.stderr
    check_picture(str(tmp_path / "tmp.png"))


@pytest.mark.parametrize("scene", ["stack", "rain", "drum"])
def test_demo_other_scenes_and_size(tmp_path, scene):
    pytest.importorskip("PIL")
    result = run_cli(["demo", "--scene", scene, "--steps", "30", "--size", "320x240",
                      "--out", f"{scene}.png", "--quiet"], tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "" and result.stderr == ""
    check_picture(str(tmp_path / f"{scene}.png"), size=(320, 240))


def test_demo_gif(tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image

    result = run_cli(["demo", "--steps", "30", "--gif", "run.gif", "--gif-every", "10",
                      "--size", "200x150", "--contacts", "--out", "last.png"], tmp_path)
    assert result.returncode == 0, result.stderr
    gif = Image.open(tmp_path / "run.gif")
    assert gif.format == "GIF" and gif.size == (200, 150)
    assert gif.n_frames == 4            # the start and steps 10, 20, 30
    check_picture(str(tmp_path / "last.png"), size=(200, 150))


def test_demo_without_pillow(tmp_path):
    result = run_cli(["demo", "--steps", "10"], tmp_path,
                     extra_code="import sys; sys.modules['PIL'] = None")
    assert result.returncode == 0, result.stderr
    assert "kinetic energy" in result.stdout
    assert "pip install 'tamias2d[demo]'" in result.stderr
    assert not (tmp_path / "tamias2d-demo.png").exists()


def body_states(space):
    return [(tuple(b.position), b.angle, tuple(b.velocity), b.angular_velocity)
            for b in space.bodies]


@pytest.mark.parametrize("name", sorted(demo.SCENES))
def test_scene_matches_pymunk_step_by_step(name):
    # The demo scenes are ordinary pymunk scenes: tamias2d must give the
    # same numbers, bit for bit.
    steps = 120
    ours = demo.build_scene(name, engine=tamias2d, steps=steps)
    ref = demo.build_scene(name, engine=pymunk, steps=steps)
    assert body_states(ours.space) == body_states(ref.space)
    for i in range(steps):
        for scene in (ours, ref):
            if scene.before_step is not None:
                scene.before_step(scene, i)
            scene.space.step(1 / 60)
        a, b = body_states(ours.space), body_states(ref.space)
        assert len(a) == len(b), f"{name}: body count differs after step {i + 1}"
        for k, (sa, sb) in enumerate(zip(a, b)):
            assert sa == sb, f"{name}: body {k} differs after step {i + 1}: {sa} != {sb}"
    assert demo.kinetic_energy(ours.space) == demo.kinetic_energy(ref.space)


@pytest.mark.parametrize("module", ["tamias2d.demo", "tamias2d.__main__"])
def test_doctests(module):
    import importlib

    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0


def test_main_without_command_prints_help(capsys):
    assert main([]) == 0
    assert "demo" in capsys.readouterr().out


def test_demo_extreme_sizes_and_no_steps(tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image

    tiny = run_cli(["demo", "--size", "16x16", "--steps", "2", "--out", "tiny.png", "-q"],
                   tmp_path)
    assert tiny.returncode == 0, tiny.stderr
    assert Image.open(tmp_path / "tiny.png").size == (16, 16)
    none = run_cli(["demo", "--steps", "0", "--gif", "zero.gif", "--out", "zero.png"], tmp_path)
    assert none.returncode == 0, none.stderr
    assert "zero.gif (1 frame," in none.stdout
    assert Image.open(tmp_path / "zero.gif").n_frames == 1
    check_picture(str(tmp_path / "zero.png"))
