"""The demo: a few scenes built with tamias2d, stepped headless and drawn.

``python -m tamias2d demo`` (see :mod:`tamias2d.__main__`) is the command;
this module holds the scene builders and the run, so that they can be used
and tested from Python as well:

>>> scene = build_scene("pyramid", steps=10)
>>> len(scene.space.bodies)
55
>>> result = run(scene, steps=10, dt=1 / 60)
>>> result.steps
10

Every builder takes the physics module as ``engine`` (tamias2d by default;
pymunk, whose API tamias2d copies, gives the same scene), so the same scene
can be run on both and compared number by number.
"""
import math
import random
import sys
import time
from typing import Callable, List, Optional, Tuple

__all__ = ["SCENES", "Scene", "Result", "build_scene", "run", "kinetic_energy",
           "render", "Progress"]

__docformat__ = "reStructuredText"

# Fill colours (r, g, b, a) the scenes give their shapes through the shape's
# ``color`` attribute, which the debug drawing honours.
PALETTE = [
    (52, 152, 219, 255),   # blue
    (231, 76, 60, 255),    # red
    (241, 196, 15, 255),   # yellow
    (46, 204, 113, 255),   # green
    (155, 89, 182, 255),   # purple
    (230, 126, 34, 255),   # orange
    (26, 188, 156, 255),   # teal
]
GROUND = (127, 140, 141, 255)
BACKGROUND = (248, 249, 250, 255)
OUTLINE = (44, 62, 80, 255)


def _default_engine():
    import tamias2d

    return tamias2d


class Scene:
    """A space ready to step, with what the demo needs around it.

    :ivar name: the scene's name (a key of :data:`SCENES`).
    :ivar description: one line saying what is in it.
    :ivar space: the Space.
    :ivar view: the world box (left, bottom, right, top) to draw.
    :ivar before_step: None, or a function ``f(scene, i)`` called before
        step i (0-based); scenes that add bodies over time use it.

    >>> import pymunk
    >>> Scene("empty", "nothing", pymunk.Space(), (0, 0, 1, 1)).view
    (0, 0, 1, 1)
    """

    def __init__(self, name, description, space, view, before_step=None):
        self.name = name
        self.description = description
        self.space = space
        self.view = view
        self.before_step = before_step


def _box(engine, space, size, position, mass=1.0, friction=0.7, color=None, radius=0.0):
    w, h = size
    body = engine.Body(mass, engine.moment_for_box(mass, (w, h)))
    body.position = position
    shape = engine.Poly.create_box(body, (w, h), radius)
    shape.friction = friction
    if color is not None:
        shape.color = color
    space.add(body, shape)
    return body


def _ball(engine, space, radius, position, mass=1.0, friction=0.7, elasticity=0.0, color=None):
    body = engine.Body(mass, engine.moment_for_circle(mass, 0, radius))
    body.position = position
    shape = engine.Circle(body, radius)
    shape.friction = friction
    shape.elasticity = elasticity
    if color is not None:
        shape.color = color
    space.add(body, shape)
    return body


def _static_segments(engine, space, points, radius, friction=1.0, elasticity=0.0):
    """A chain of static segments through the given points."""
    for a, b in zip(points, points[1:]):
        seg = engine.Segment(space.static_body, a, b, radius)
        seg.friction = friction
        seg.elasticity = elasticity
        seg.color = GROUND
        space.add(seg)


def build_pyramid(engine=None, rows=10, steps=600):
    """A pyramid of boxes (``rows`` on the ground row) on a ground segment.

    >>> len(build_pyramid(rows=3).space.bodies)
    6
    """
    engine = engine or _default_engine()
    space = engine.Space()
    space.gravity = (0, -900)
    ground_r = 5.0
    _static_segments(engine, space, [(-400, 0), (400, 0)], ground_r)
    size = 30.0
    gap = 2.0
    for row in range(rows):
        n = rows - row
        y = ground_r + size / 2 + row * size
        for j in range(n):
            x = (j - (n - 1) / 2) * (size + gap)
            _box(engine, space, (size, size), (x, y), color=PALETTE[row % len(PALETTE)])
    top = ground_r + rows * size
    half = max(rows * (size + gap) / 2, top * 0.75)
    return Scene("pyramid", f"a pyramid of {rows * (rows + 1) // 2} boxes on a ground segment",
                 space, (-half - 40, -30, half + 40, top + 60))


def build_stack(engine=None, heights=(8, 10, 12, 10, 8), steps=600):
    """Vertical stacks of 20 x 20 boxes (one column per entry of
    ``heights``), dropped from a small gap each so that they settle.

    The solver gets 30 iterations: with Chipmunk's default of 10, tall
    stacks creep sideways and fall at a 1/60 s step.

    >>> len(build_stack(heights=(2, 3)).space.bodies)
    5
    """
    engine = engine or _default_engine()
    space = engine.Space()
    space.gravity = (0, -900)
    space.iterations = 30
    ground_r = 1.0
    ground = engine.Segment(space.static_body, (-300, 0), (300, 0), ground_r)
    ground.friction = 0.3
    ground.color = GROUND
    space.add(ground)
    size = 20.0
    gap = 2.0
    spacing = 50.0
    x0 = -spacing * (len(heights) - 1) / 2
    for col, height in enumerate(heights):
        for row in range(height):
            _box(engine, space, (size, size),
                 (x0 + col * spacing, ground_r + size / 2 + gap + row * (size + gap)),
                 mass=10.0, friction=0.3, color=PALETTE[col % len(PALETTE)])
    top = ground_r + max(heights, default=1) * (size + gap)
    return Scene("stack", f"{len(heights)} stacks of {min(heights, default=0)} to "
                 f"{max(heights, default=0)} boxes, settling", space,
                 (-200, -20, 200, top + 40))


def build_rain(engine=None, count=None, steps=600, seed=2024):
    """Circles dropping one after another into an open box.

    One circle is added every other step until ``count`` (by default half the
    steps, at most 400) are in; positions, sizes and colours come from a
    seeded generator, so a run is repeatable.

    >>> scene = build_rain(count=3)
    >>> for i in range(6):
    ...     scene.before_step(scene, i)
    >>> len(scene.space.bodies)
    3
    """
    engine = engine or _default_engine()
    if count is None:
        count = max(1, min(400, steps // 2))
    space = engine.Space()
    space.gravity = (0, -900)
    wall_r = 5.0
    _static_segments(engine, space, [(-200, 300), (-200, 0), (200, 0), (200, 300)], wall_r,
                     friction=0.8, elasticity=0.4)
    rng = random.Random(seed)
    plan = []
    for _ in range(count):
        r = rng.uniform(6.0, 12.0)
        x = rng.uniform(-180.0 + r, 180.0 - r)
        color = PALETTE[rng.randrange(len(PALETTE))]
        plan.append((r, x, color))
    state = {"added": 0}

    def before_step(scene, i):
        if i % 2 == 0 and state["added"] < len(plan):
            r, x, color = plan[state["added"]]
            _ball(engine, scene.space, r, (x, 460.0), mass=r * r / 100.0,
                  friction=0.5, elasticity=0.4, color=color)
            state["added"] += 1

    return Scene("rain", f"{count} circles raining into a box", space,
                 (-230, -30, 230, 480), before_step)


def build_drum(engine=None, boxes=60, steps=600, seed=7):
    """A kinematic drum (a ring of segments with paddles) spinning with
    boxes and balls tumbling inside.

    >>> len(build_drum(boxes=6).space.bodies)   # the drum, 6 boxes, 2 balls
    9
    """
    engine = engine or _default_engine()
    space = engine.Space()
    space.gravity = (0, -900)
    drum = engine.Body(body_type=engine.Body.KINEMATIC)
    drum.angular_velocity = -1.5
    space.add(drum)
    radius = 200.0
    sides = 32
    ring = [(radius * math.cos(2 * math.pi * i / sides), radius * math.sin(2 * math.pi * i / sides))
            for i in range(sides + 1)]
    for a, b in zip(ring, ring[1:]):
        seg = engine.Segment(drum, a, b, 5.0)
        seg.friction = 0.9
        space.add(seg)
    for k in range(4):
        ang = 2 * math.pi * k / 4 + math.pi / 4
        c, s = math.cos(ang), math.sin(ang)
        paddle = engine.Segment(drum, (c * radius, s * radius), (c * (radius - 45), s * (radius - 45)), 5.0)
        paddle.friction = 0.9
        space.add(paddle)
    rng = random.Random(seed)
    balls = boxes // 3
    for i in range(boxes + balls):
        x = -120 + (i % 10) * 26
        y = -110 + (i // 10) * 26
        color = PALETTE[rng.randrange(len(PALETTE))]
        if i < boxes:
            _box(engine, space, (18, 18), (x, y), friction=0.6, color=color)
        else:
            _ball(engine, space, 9, (x, y), friction=0.6, color=color)
    return Scene("drum", f"a spinning kinematic drum with {boxes} boxes and {balls} balls",
                 space, (-225, -225, 225, 225))


SCENES = {
    "pyramid": build_pyramid,
    "stack": build_stack,
    "rain": build_rain,
    "drum": build_drum,
}
"""Scene name -> builder ``f(engine=None, ..., steps=600)`` returning a Scene."""


def build_scene(name, engine=None, steps=600):
    """Build the named scene (one of :data:`SCENES`) with the given engine.

    >>> build_scene("drum").name
    'drum'
    """
    try:
        builder = SCENES[name]
    except KeyError:
        raise ValueError(f"unknown scene {name!r}; choose from {', '.join(SCENES)}") from None
    return builder(engine=engine, steps=steps)


def kinetic_energy(space):
    """Kinetic energy of the dynamic bodies: the sum of 1/2 m v^2 + 1/2 I w^2.

    (``Body.kinetic_energy``, as in Chipmunk, leaves out the 1/2.)

    >>> kinetic_energy(build_scene("pyramid").space)
    0.0
    """
    total = 0.0
    for body in space.bodies:
        if body.body_type != 0:  # only DYNAMIC bodies carry kinetic energy
            continue
        v = body.velocity
        w = body.angular_velocity
        total += 0.5 * body.mass * (v[0] * v[0] + v[1] * v[1]) + 0.5 * body.moment * w * w
    return total


class Progress:
    """A progress display on a text stream.

    On a terminal it is one bar redrawn in place; otherwise it writes a
    plain line at every tenth of the run. Disabled, it writes nothing.

    >>> import io
    >>> out = io.StringIO()
    >>> p = Progress(4, stream=out, label="demo")
    >>> for i in range(4):
    ...     p.update(i + 1)
    >>> p.close()
    >>> print(out.getvalue().splitlines()[-1])
    demo: step 4/4 (100%)
    """

    def __init__(self, total, stream=None, enabled=True, label="", width=30):
        self.total = max(0, int(total))
        self.stream = sys.stderr if stream is None else stream
        self.enabled = enabled
        self.label = label
        self.width = width
        isatty = getattr(self.stream, "isatty", None)
        self.tty = bool(isatty and isatty())
        # A terminal redraws from the first step; plain lines start at 10%.
        self._shown = -1 if self.tty else 0
        self._start = time.perf_counter()

    def update(self, done):
        """Show that ``done`` of the ``total`` steps have run."""
        if not self.enabled or self.total == 0:
            return
        if self.tty:
            # Redraw at most once per percent.
            pct = done * 100 // self.total
            if pct == self._shown and done != self.total:
                return
            self._shown = pct
            filled = done * self.width // self.total
            bar = "#" * filled + "-" * (self.width - filled)
            elapsed = time.perf_counter() - self._start
            prefix = f"{self.label} " if self.label else ""
            self.stream.write(f"\r{prefix}[{bar}] {pct:3d}%  {done}/{self.total} steps  "
                              f"{elapsed:.1f} s")
            self.stream.flush()
        else:
            tenth = done * 10 // self.total
            if tenth == self._shown:
                return
            self._shown = tenth
            prefix = f"{self.label}: " if self.label else ""
            self.stream.write(f"{prefix}step {done}/{self.total} ({done * 100 // self.total}%)\n")
            self.stream.flush()

    def close(self):
        """End the display (on a terminal, move past the bar's line)."""
        if self.enabled and self.tty and self._shown >= 0:
            self.stream.write("\n")
            self.stream.flush()


class Result:
    """What a run did: steps, the time spent stepping, the final state.

    :ivar steps: how many steps were taken.
    :ivar dt: the time step.
    :ivar step_time: seconds spent inside ``Space.step`` (wall clock).
    :ivar kinetic_energy: kinetic energy at the end (see :func:`kinetic_energy`).
    :ivar frames: number of GIF frames collected.

    >>> Result(10, 0.01, 0.002, 0.0).steps
    10
    """

    def __init__(self, steps, dt, step_time, kinetic_energy, frames=0):
        self.steps = steps
        self.dt = dt
        self.step_time = step_time
        self.kinetic_energy = kinetic_energy
        self.frames = frames


def run(scene, steps=600, dt=1 / 60, progress=None, on_frame=None, frame_every=0):
    """Step a scene ``steps`` times by ``dt``.

    :param progress: a :class:`Progress`, or None for none.
    :param on_frame: called as ``on_frame(scene, i)`` for the state before
        the first step and after every ``frame_every``-th step (and after the
        last one), to collect animation frames.
    :returns: a :class:`Result`.

    >>> seen = []
    >>> r = run(build_scene("rain"), steps=6, on_frame=lambda s, i: seen.append(i),
    ...         frame_every=4)
    >>> seen, r.frames
    ([0, 4, 6], 3)
    """
    space = scene.space
    step = space.step
    frames = 0
    want_frames = on_frame is not None and frame_every > 0
    if want_frames:
        on_frame(scene, 0)
        frames += 1
    spent = 0.0
    clock = time.perf_counter
    for i in range(steps):
        if scene.before_step is not None:
            scene.before_step(scene, i)
        t0 = clock()
        step(dt)
        spent += clock() - t0
        if progress is not None:
            progress.update(i + 1)
        if want_frames and ((i + 1) % frame_every == 0 or i + 1 == steps):
            on_frame(scene, i + 1)
            frames += 1
    if progress is not None:
        progress.close()
    return Result(steps, dt, spent, kinetic_energy(space), frames)


def make_draw_options(size, view, engine=None, supersample=3, contacts=False):
    """Pillow draw options for a scene's view; works with tamias2d and, for
    comparison, with pymunk's Space.debug_draw. ``contacts`` adds the
    contact points, drawn wide enough to see.

    >>> make_draw_options((80, 60), (0, 0, 8, 6)).to_image((4, 3))
    (40.0, 30.0)
    """
    from . import pillow_util

    options_class = pillow_util.DrawOptions
    if engine is not None and engine.__name__ != "tamias2d":
        # pymunk's Space.debug_draw needs pymunk's own options base class.
        options_class = type("DrawOptions", (pillow_util.PillowDrawing, engine.SpaceDebugDrawOptions), {})
    width, height = size
    margin = min(16, min(width, height) // 20)
    # Keep the supersampled canvas within about 16 million pixels.
    supersample = max(1, min(supersample, int(math.sqrt(16e6 / (width * height)))))
    options = options_class(size, bb=view, margin=margin, background=BACKGROUND,
                            supersample=supersample, line_width=1.0,
                            segment_width=2.5 if contacts else 1.0)
    options.flags = options.DRAW_SHAPES | options.DRAW_CONSTRAINTS
    if contacts:
        options.flags |= options.DRAW_COLLISION_POINTS
    options.shape_outline_color = OUTLINE
    return options


def render(scene, options, caption=None):
    """Draw the scene's space into the options' image; returns the image.

    >>> scene = build_scene("pyramid")
    >>> render(scene, make_draw_options((80, 60), scene.view)).size
    (80, 60)
    """
    options.clear()
    scene.space.debug_draw(options)
    image = options.image
    if caption and image.width >= 200 and image.height >= 100:  # no room on tiny pictures
        _caption(image, caption)
    return image


def _caption(image, text):
    from PIL import ImageDraw, ImageFont

    size = max(10, image.height // 40)
    try:
        font = ImageFont.load_default(size)
    except (TypeError, OSError):  # Pillow < 10.1 or without FreeType
        font = ImageFont.load_default()
    draw = ImageDraw.Draw(image)
    draw.text((8, 6), text, fill=OUTLINE[:3], font=font)
