"""tamias2d.matplotlib_util and tamias2d.pyglet_util against pymunk's, on
the same scene drawn by both engines.

- matplotlib (skipped without it): both draw into Agg figures; every artist
  (kind, geometry, colours, widths, cap and join styles) and the rendered
  pixels must be equal.
- pyglet, through a fake ``pyglet`` module that records every shape and
  group made (runs without pyglet and without a display): the calls must be
  equal.
- pyglet for real (skipped without pyglet or without EGL): headless, in a
  child process; the shapes' vertices, colours and groups, and the pixels of
  the drawn frame, must be equal.
"""
import importlib
import json
import os
import subprocess
import sys
import textwrap
import types

import pytest

pymunk = pytest.importorskip("pymunk")
import tamias2d  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def build_scene(m):
    """The same scene in pymunk or tamias2d: every primitive the debug draw
    uses (circles, thin and fat segments, plain and rounded polygons,
    joint dots and lines, contact points, a custom colour)."""
    space = m.Space()
    space.gravity = 0, -100
    ground = m.Segment(space.static_body, (-50, 0), (50, 0), 2)
    line = m.Segment(space.static_body, (-50, 30), (-20, 60), 0)
    space.add(ground, line)
    ball = m.Body(1, 10)
    ball.position = 0, 5
    ball.angle = 0.7
    circle = m.Circle(ball, 4)
    circle.color = (200, 30, 40, 255)
    box = m.Body(2, 20)
    box.position = 15, 3
    poly = m.Poly.create_box(box, (6, 4), 1)
    tri = m.Body(1, 5)
    tri.position = -15, 10
    plain = m.Poly(tri, [(0, 0), (6, 0), (3, 5)])
    space.add(ball, circle, box, poly, tri, plain)
    space.add(m.PinJoint(ball, box, (1, 0), (0, 1)),
              m.DampedSpring(box, tri, (0, 0), (0, 0), 20, 10, 1),
              m.SlideJoint(tri, space.static_body, (0, 0), (-15, 40), 5, 20))
    for _ in range(3):
        space.step(1 / 60)
    return space


# -- matplotlib ------------------------------------------------------------------------

def _artists(ax):
    import numpy as np
    out = []
    for p in ax.patches:
        kind = type(p).__name__
        geometry = (tuple(map(float, p.center)) + (float(p.radius),) if kind == "Circle"
                    else tuple(map(tuple, np.asarray(p.get_xy(), dtype=float).tolist())))
        out.append((kind, geometry, tuple(p.get_facecolor()), tuple(p.get_edgecolor()),
                    p.get_linewidth(), p.get_joinstyle()))
    for line in ax.lines:
        out.append(("Line2D", tuple(map(float, line.get_xdata())),
                    tuple(map(float, line.get_ydata())), line.get_color(),
                    line.get_linewidth(), line.get_solid_capstyle()))
    return out


def test_matplotlib_util_draws_what_pymunk_draws():
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    import pymunk.matplotlib_util
    from tamias2d import matplotlib_util

    images, artists = [], []
    for engine, util in ((pymunk, pymunk.matplotlib_util), (tamias2d, matplotlib_util)):
        fig = Figure(figsize=(4, 3), dpi=50)
        canvas = FigureCanvasAgg(fig)
        ax = fig.add_subplot()
        ax.set_xlim(-60, 60)
        ax.set_ylim(-10, 70)
        with pytest.warns(DeprecationWarning):
            options = util.DrawOptions(ax)
        build_scene(engine).debug_draw(options)
        artists.append(_artists(ax))
        canvas.draw()
        images.append(bytes(canvas.buffer_rgba()))
    assert len(artists[1]) > 15
    assert {a[0] for a in artists[1]} == {"Circle", "Polygon", "Line2D"}
    assert artists[1] == artists[0]
    assert images[1] == images[0]


# -- pyglet through a recording fake -----------------------------------------------------

def _fake_pyglet(log):
    def recorder(kind):
        class Recorded:
            def __init__(self, *args, **kwargs):
                kwargs = dict(kwargs)
                batch = kwargs.pop("batch", None)
                group = kwargs.pop("group", None)
                log.append((kind, args, sorted(kwargs.items()),
                            None if batch is None else batch.name,
                            None if group is None else group.order))
        Recorded.__name__ = kind
        return Recorded

    class Group:
        def __init__(self, order=0, parent=None):
            self.order = order

    class Batch:
        made = 0

        def __init__(self):
            Batch.made += 1
            self.name = f"batch{Batch.made}"

        def draw(self):
            log.append(("draw", self.name))

    fake = types.ModuleType("pyglet")
    fake.version = "2.1.0"
    fake.graphics = types.SimpleNamespace(Group=Group, Batch=Batch)
    fake.shapes = types.SimpleNamespace(Circle=recorder("Circle"), Line=recorder("Line"),
                                        Polygon=recorder("Polygon"))
    return fake


def _exact(log):
    # floats by their bits, so the two logs must agree to the last digit
    def conv(v):
        if isinstance(v, float):
            return v.hex()
        if isinstance(v, (list, tuple)):
            return [conv(x) for x in v]
        return v
    return conv(log)


@pytest.fixture
def fresh_modules():
    """Modules imported during the test (against the fake) are forgotten
    afterwards, so that later imports get the real pyglet."""
    before = set(sys.modules)
    yield
    for name in set(sys.modules) - before:
        if name.endswith("pyglet_util"):
            del sys.modules[name]
            parent, _, child = name.rpartition(".")
            if hasattr(sys.modules.get(parent), child):
                delattr(sys.modules[parent], child)


def test_pyglet_util_makes_the_shapes_pymunk_makes(monkeypatch, fresh_modules):
    logs = {}
    for name in ("pymunk.pyglet_util", "tamias2d.pyglet_util"):
        log = []
        fake = _fake_pyglet(log)
        if name not in sys.modules:
            # importable without pyglet installed
            with monkeypatch.context() as m:
                m.setitem(sys.modules, "pyglet", fake)
                module = importlib.import_module(name)
        else:
            module = sys.modules[name]
        monkeypatch.setattr(module, "pyglet", fake)
        engine = pymunk if name.startswith("pymunk") else tamias2d
        space = build_scene(engine)
        space.debug_draw(module.DrawOptions())          # a batch of its own, drawn
        own = fake.graphics.Batch()
        options = module.DrawOptions(batch=own)
        before = len(log)
        space.debug_draw(options)                       # the caller's batch, not drawn
        assert len(options.draw_shapes) == len(log) - before    # every shape is kept
        logs[name] = log
    ours, theirs = logs["tamias2d.pyglet_util"], logs["pymunk.pyglet_util"]
    assert {e[0] for e in ours} == {"Circle", "Line", "Polygon", "draw"}
    assert len(ours) > 30
    assert _exact(ours) == _exact(theirs)


# -- pyglet for real, headless -------------------------------------------------------------

CHILD = textwrap.dedent(r"""
    import json, sys, warnings
    sys.path.insert(0, sys.argv[1])
    import pyglet
    pyglet.options["headless"] = True
    try:
        window = pyglet.window.Window(240, 160, visible=False)
    except Exception as e:
        print(json.dumps({"skip": f"no headless pyglet here: {e!r}"}))
        sys.exit(0)
    from pyglet import gl
    import pymunk, pymunk.pyglet_util, tamias2d, tamias2d.pyglet_util
    from test_plot_backends import build_scene

    def shape_info(s):
        group = getattr(s, "_user_group", None)
        return [type(s).__name__, [float(v).hex() for v in s._get_vertices()],
                list(s.color), None if group is None else group.order]

    out = {}
    for name, engine, util in (("pymunk", pymunk, pymunk.pyglet_util),
                               ("tamias2d", tamias2d, tamias2d.pyglet_util)):
        space = build_scene(engine)
        window.switch_to()
        gl.glClearColor(0, 0, 0, 1)
        window.clear()
        window.projection = pyglet.math.Mat4.orthogonal_projection(-60, 60, -10, 70, -255, 255)
        options = util.DrawOptions()
        space.debug_draw(options)      # draws its own batch
        pixels = pyglet.image.get_buffer_manager().get_color_buffer().get_image_data()
        data = bytes(pixels.get_data("RGBA", pixels.width * 4))
        out[name] = {"shapes": [shape_info(s) for s in options.draw_shapes],
                     "pixels": data.hex(), "lit": sum(1 for i in range(0, len(data), 4)
                                                      if data[i:i + 3] != b"\0\0\0")}
        batch = pyglet.graphics.Batch()
        mine = util.DrawOptions(batch=batch)
        space.debug_draw(mine)
        out[name]["batched"] = len(mine.draw_shapes)
    print(json.dumps(out))
""")


def test_pyglet_util_headless_draws_what_pymunk_draws(tmp_path):
    pytest.importorskip("pyglet")
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [HERE, os.path.dirname(os.path.dirname(tamias2d.__file__))]))
    proc = subprocess.run([sys.executable, str(script), HERE], capture_output=True, text=True,
                          timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    if "skip" in result:
        pytest.skip(result["skip"])
    ours, theirs = result["tamias2d"], result["pymunk"]
    assert len(ours["shapes"]) > 15 and ours["lit"] > 500
    assert ours["shapes"] == theirs["shapes"]
    assert ours["pixels"] == theirs["pixels"]
    assert ours["batched"] == theirs["batched"] == len(ours["shapes"])
