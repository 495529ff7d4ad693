"""Hard cases for the stability suite, built the same way for any engine.

Each :class:`Case` builds a scene with the pymunk 7.3 API from an engine
module (``pymunk`` or ``tamias2d``), steps it, samples it and judges it
against a stated pass criterion. The same code runs both engines, so
tests/test_hard_cases.py can compare tamias2d with pymunk number for number
and benchmarks/stability_report.py can print the two side by side.

Settings that may rescue a case are passed to :func:`run_case`:
``iterations`` (solver iterations), ``substeps`` (each step of ``dt`` is
taken as ``substeps`` steps of ``dt / substeps``, so simulated time is the
same) and ``slop`` (``collision_slop``).

>>> import pymunk
>>> r = run_case(pymunk, CASES["coincident_circles"])
>>> r.passed, r.nan
(True, False)
>>> len(r.hash)
64
"""
import hashlib
import math
import struct
import time
from dataclasses import dataclass, field

DT = 1.0 / 60.0


# -- state helpers -------------------------------------------------------------------

def body_state(body):
    """The six doubles that define a body's motion, in a fixed order."""
    p, v = body.position, body.velocity
    return (p.x, p.y, body.angle, v.x, v.y, body.angular_velocity)


def state_hash(space):
    """sha256 (hex) of the packed little-endian doubles of every body's
    position, angle, velocity and angular velocity, in ``space.bodies`` order.

    >>> import pymunk
    >>> s = pymunk.Space()
    >>> state_hash(s) == hashlib.sha256(b"").hexdigest()
    True
    """
    h = hashlib.sha256()
    for b in space.bodies:
        h.update(struct.pack("<6d", *body_state(b)))
    return h.hexdigest()


def all_finite(space):
    return all(math.isfinite(x) for b in space.bodies for x in body_state(b))


def energy(space):
    """Kinetic (translational and rotational) plus gravitational potential
    energy of the dynamic bodies."""
    gx, gy = space.gravity
    e = 0.0
    for b in space.bodies:
        if b.body_type != b.DYNAMIC:
            continue
        v = b.velocity
        p = b.position
        e += 0.5 * b.mass * (v.x * v.x + v.y * v.y)
        e += 0.5 * b.moment * b.angular_velocity * b.angular_velocity
        e -= b.mass * (gx * p.x + gy * p.y)
    return e


def kinetic(space):
    e = 0.0
    for b in space.bodies:
        if b.body_type == b.DYNAMIC:
            v = b.velocity
            e += 0.5 * b.mass * (v.x * v.x + v.y * v.y)
            e += 0.5 * b.moment * b.angular_velocity * b.angular_velocity
    return e


def box_moment(mass, w, h):
    return mass * (w * w + h * h) / 12.0


# -- scene pieces ----------------------------------------------------------------------

class Scene:
    """A space and the objects a case watches (``watch``, a dict)."""

    def __init__(self, space, **watch):
        self.space = space
        self.watch = watch


def _ground(mod, space, y_top=0.0, half=2000.0, radius=5.0, friction=0.6, s=1.0, off=(0, 0)):
    """A static segment whose top surface is at y_top."""
    y = y_top - radius
    seg = mod.Segment(space.static_body, ((-half) * s + off[0], y * s + off[1]),
                      (half * s + off[0], y * s + off[1]), radius * s)
    seg.friction = friction
    space.add(seg)
    return seg


def _box(mod, space, x, y, w, h, mass=1.0, friction=0.6, s=1.0, off=(0, 0)):
    body = mod.Body(mass, box_moment(mass, w * s, h * s))
    body.position = x * s + off[0], y * s + off[1]
    shape = mod.Poly.create_box(body, (w * s, h * s))
    shape.friction = friction
    space.add(body, shape)
    return body


def _space(mod, gravity=-900.0, s=1.0):
    space = mod.Space()
    space.gravity = 0.0, gravity * s
    return space


def build_stack(mod, count=10, size=20.0):
    """A column of `count` size x size boxes, mass 1, friction 0.6, each
    resting exactly on the one below (no gap), on a static segment."""
    space = _space(mod)
    _ground(mod, space)
    boxes = [_box(mod, space, 0.0, size / 2.0 + i * size, size, size) for i in range(count)]
    return Scene(space, boxes=boxes, size=size)


def build_pyramid(mod, rows=20, size=20.0, s=1.0, off=(0.0, 0.0)):
    """Box2D's pyramid: `rows` rows of size x size boxes, mass 1, friction
    0.6, touching, on a static segment; `s` scales every length (and gravity),
    `off` moves the whole scene."""
    space = _space(mod, s=s)
    _ground(mod, space, s=s, off=off)
    boxes = []
    for i in range(rows):
        y = size / 2.0 + i * size
        for j in range(rows - i):
            x = (j - (rows - 1 - i) / 2.0) * size * 1.05
            boxes.append(_box(mod, space, x, y, size, size, s=s, off=off))
    return Scene(space, boxes=boxes, size=size, scale=s, offset=off)


def build_mass_ratio(mod, ratio=10.0, size=20.0):
    """A light box (mass 1) on the ground with a heavy box (mass `ratio`)
    resting on it."""
    space = _space(mod)
    _ground(mod, space)
    light = _box(mod, space, 0.0, size / 2.0, size, size, mass=1.0)
    heavy = _box(mod, space, 0.0, size * 1.5, size, size, mass=ratio)
    return Scene(space, light=light, heavy=heavy, size=size)


def build_tunnel(mod, speed=1200.0, wall=1.0, radius=0.5):
    """A circle of radius `radius` shot at `speed` at a static wall `wall`
    thick (its near face at x = 0), no gravity."""
    space = _space(mod, gravity=0.0)
    w = mod.Poly.create_box(space.static_body, (wall, 200.0))
    space.static_body.position = wall / 2.0, 0.0
    space.add(w)
    body = mod.Body(1.0, 0.5 * radius * radius)
    # 23.7 before the wall: at 20 per step the ball is never caught overlapping
    body.position = -23.7, 0.0
    body.velocity = speed, 0.0
    ball = mod.Circle(body, radius)
    space.add(body, ball)
    return Scene(space, ball=body, wall=wall, radius=radius)


def build_scaled(mod, scale=1.0):
    """A 5-row pyramid with every length and gravity multiplied by `scale`."""
    return build_pyramid(mod, rows=5, s=scale)


def build_far(mod, offset=1e6):
    """The 5-row pyramid moved to (offset, offset)."""
    return build_pyramid(mod, rows=5, off=(offset, offset))


def _poly_body(mod, space, verts, x, y, mass=1.0, moment=None, friction=0.6):
    body = mod.Body(mass, moment if moment is not None else 100.0)
    body.position = x, y
    shape = mod.Poly(body, verts)
    shape.friction = friction
    if moment is None:
        # the moment of the shape's bounding box: sane even for a sliver
        bb = shape.cache_bb()
        body.moment = box_moment(mass, max(bb.right - bb.left, 1.0), max(bb.top - bb.bottom, 1.0))
    space.add(body, shape)
    return body, shape


def build_poly_collinear(mod):
    """Polygons with collinear vertices: a square with a midpoint on each
    side (the hull drops them) and a 'polygon' whose points all lie on one
    line (the hull keeps 2 vertices), each with a box dropped on top."""
    space = _space(mod)
    _ground(mod, space)
    sq = [(-10, -10), (0, -10), (10, -10), (10, 0), (10, 10), (0, 10), (-10, 10), (-10, 0)]
    line = [(-20, 0), (-10, 0), (0, 0), (10, 0), (20, 0)]
    a, _ = _poly_body(mod, space, sq, -100.0, 10.5)
    b, _ = _poly_body(mod, space, line, 100.0, 0.5)
    caps = [_box(mod, space, -100.0, 31.0, 20, 20), _box(mod, space, 100.0, 11.5, 20, 20)]
    return Scene(space, polys=[a, b], caps=caps, rest=[10.0, 0.0], cap_rest=[30.0, 10.0])


def build_poly_duplicate(mod):
    """Polygons given with repeated vertices (a square with every corner
    twice; a triangle with one corner three times), boxes on top."""
    space = _space(mod)
    _ground(mod, space)
    sq = [(-10, -10), (-10, -10), (10, -10), (10, 10), (10, 10), (-10, 10), (-10, -10)]
    tri = [(-15, -5), (15, -5), (15, -5), (15, -5), (0, 10)]
    a, _ = _poly_body(mod, space, sq, -100.0, 10.5)
    b, _ = _poly_body(mod, space, tri, 100.0, 5.5)
    caps = [_box(mod, space, -100.0, 31.0, 20, 20), _box(mod, space, 300.0, 10.0, 20, 20)]
    return Scene(space, polys=[a, b], caps=caps[:1], rest=[10.0, 5.0], cap_rest=[30.0])


def build_poly_sliver(mod):
    """Near-zero-area polygons: a 40-wide triangle 1e-9 high and a 40 x 1e-6
    quad, each lying on the ground with a box dropped on it."""
    space = _space(mod)
    _ground(mod, space)
    tri = [(-20, 0), (20, 0), (0, 1e-9)]
    quad = [(-20, 0), (20, 0), (20, 1e-6), (-20, 1e-6)]
    a, _ = _poly_body(mod, space, tri, -100.0, 0.5)
    b, _ = _poly_body(mod, space, quad, 100.0, 0.5)
    caps = [_box(mod, space, -100.0, 11.0, 20, 20), _box(mod, space, 100.0, 11.0, 20, 20)]
    return Scene(space, polys=[a, b], caps=caps, rest=[0.0, 0.0], cap_rest=[10.0, 10.0])


def _ngon(count, radius=20.0):
    return [(radius * math.cos(2 * math.pi * k / count), radius * math.sin(2 * math.pi * k / count))
            for k in range(count)]


def build_poly_many(mod, count=1000):
    """Two regular `count`-gons of radius 20 (more vertices than the 256 the
    GJK cache id can index) stacked in a vertical tube 42 wide."""
    space = _space(mod)
    _ground(mod, space)
    for x in (-21.0, 21.0):
        wall = mod.Segment(space.static_body, (x, 0.0), (x, 200.0), 1.0)
        wall.friction = 0.6
        space.add(wall)
    verts = _ngon(count)
    lower, _ = _poly_body(mod, space, verts, 0.0, 20.0, moment=200.0)
    upper, _ = _poly_body(mod, space, verts, 0.0, 60.5, moment=200.0)
    return Scene(space, polys=[lower, upper])


def build_poly_floor(mod, count=1000):
    """A regular `count`-gon of radius 20 let go at rest just above a flat
    floor."""
    space = _space(mod)
    _ground(mod, space)
    body, _ = _poly_body(mod, space, _ngon(count), 0.0, 20.5, moment=200.0)
    return Scene(space, polys=[body])


def build_zero_radius(mod):
    """A static segment of radius 0 as the floor, with a box, a circle and a
    segment of radius 1 dropped on it."""
    space = _space(mod)
    floor = mod.Segment(space.static_body, (-2000, 0), (2000, 0), 0.0)
    floor.friction = 0.6
    space.add(floor)
    box = _box(mod, space, -200.0, 15.0, 20, 20)
    cb = mod.Body(1.0, 0.5 * 100.0)
    cb.position = -100.0, 15.0
    c = mod.Circle(cb, 10.0)
    c.friction = 0.6
    space.add(cb, c)
    sb = mod.Body(1.0, box_moment(1.0, 42.0, 2.0))
    sb.position = 0.0, 6.0
    sh = mod.Segment(sb, (-20, 0), (20, 0), 1.0)
    sh.friction = 0.6
    space.add(sb, sh)
    return Scene(space, resting=[box, cb, sb], rest=[10.0, 10.0, 1.0])


def build_zero_radius_pair(mod):
    """Radius-0 segments dropped on a radius-0 floor: one parallel to it, one
    tilted, and one of zero length (a point)."""
    space = _space(mod)
    floor = mod.Segment(space.static_body, (-2000, 0), (2000, 0), 0.0)
    floor.friction = 0.6
    space.add(floor)
    bodies = []
    for x, (a, b) in ((0.0, ((-20, 0), (20, 0))), (100.0, ((-20, -5), (20, 5))),
                      (200.0, ((0, 0), (0, 0)))):
        sb = mod.Body(1.0, box_moment(1.0, 40.0, 1.0))
        sb.position = x, 10.0
        sh = mod.Segment(sb, a, b, 0.0)
        sh.friction = 0.6
        space.add(sb, sh)
        bodies.append(sb)
    # At rest all three lie on the floor. (The tilted one's height was first
    # written as 5, its centre with one end down; but nothing holds a rigid
    # segment on one end with its centre 19 units to the side: it tips flat.)
    return Scene(space, resting=bodies, rest=[0.0, 0.0, 0.0])


def build_coincident_circles(mod):
    """Two dynamic circles of radius 10 created at exactly the same place, no
    gravity (Munk2D picks the normal (1, 0) for them)."""
    space = _space(mod, gravity=0.0)
    bodies = []
    for j in range(2):
        body = mod.Body(1.0, 50.0)
        space.add(body, mod.Circle(body, 10.0))
        bodies.append(body)
    return Scene(space, pairs=[bodies], touch=[20.0])


def build_coincident_polys(mod, nudge=0.0):
    """Pairs created at the same place, no gravity: two 20 x 20 boxes, a box
    and a circle of radius 10 with the same centre, and a dynamic box inside
    a static one of the same size. `nudge` moves the second of each pair by
    (nudge, nudge / 2)."""
    space = _space(mod, gravity=0.0)
    pairs = []
    for k, kind in enumerate(("box", "circle", "static")):
        x = k * 200.0
        first = mod.Body(1.0, box_moment(1.0, 20.0, 20.0))
        if kind == "static":
            first.body_type = mod.Body.STATIC
        first.position = x, 0.0
        space.add(first, mod.Poly.create_box(first, (20, 20)))
        second = mod.Body(1.0, box_moment(1.0, 20.0, 20.0))
        second.position = x + nudge, nudge / 2.0
        shape = mod.Circle(second, 10.0) if kind == "circle" else mod.Poly.create_box(second, (20, 20))
        space.add(second, shape)
        pairs.append([first, second])
    return Scene(space, pairs=pairs, touch=[20.0, 20.0, 20.0])


def build_long_run(mod):
    """A closed box holding 10 circles and 5 boxes thrown around under
    gravity, elasticity 0.5: the energy can only go down."""
    space = _space(mod)
    walls = [((-200, 0), (200, 0)), ((200, 0), (200, 400)), ((200, 400), (-200, 400)),
             ((-200, 400), (-200, 0))]
    for a, b in walls:
        seg = mod.Segment(space.static_body, a, b, 5.0)
        seg.friction = 0.5
        seg.elasticity = 0.5
        space.add(seg)
    for i in range(15):
        if i < 10:
            body = mod.Body(1.0, 0.5 * 100.0)
            shape = mod.Circle(body, 10.0)
        else:
            body = mod.Body(2.0, box_moment(2.0, 24.0, 16.0))
            shape = mod.Poly.create_box(body, (24, 16))
        body.position = -120.0 + 60.0 * (i % 5), 60.0 + 100.0 * (i // 5) + 7.0 * (i % 2)
        body.velocity = 150.0 * math.cos(i), 150.0 * math.sin(i)
        body.angular_velocity = (i % 3) - 1.0
        shape.friction = 0.5
        shape.elasticity = 0.5
        space.add(body, shape)
    return Scene(space)


def build_elastic_gas(mod):
    """20 frictionless, perfectly elastic circles bouncing in a closed box
    without gravity: the energy should stay about constant."""
    space = _space(mod, gravity=0.0)
    walls = [((-200, -200), (200, -200)), ((200, -200), (200, 200)), ((200, 200), (-200, 200)),
             ((-200, 200), (-200, -200))]
    for a, b in walls:
        seg = mod.Segment(space.static_body, a, b, 5.0)
        seg.elasticity = 1.0
        space.add(seg)
    for i in range(20):
        body = mod.Body(1.0, 0.5 * 100.0)
        body.position = -150.0 + 75.0 * (i % 5), -150.0 + 75.0 * (i // 5)
        body.velocity = 100.0 * math.cos(1.7 * i), 100.0 * math.sin(1.7 * i)
        shape = mod.Circle(body, 10.0)
        shape.elasticity = 1.0
        space.add(body, shape)
    return Scene(space)


def build_determinism(mod, count=60, spatial_hash=False, sleeping=False):
    """The scene of tests/test_determinism.py: `count` circles, boxes,
    rounded polygons and segments with seeded random sizes, materials and
    velocities, tumbling in a closed box stirred by a turning kinematic
    paddle (contacts of every shape pair, restitution, friction)."""
    import random
    rng = random.Random(7)
    space = _space(mod)
    if spatial_hash:
        space.use_spatial_hash(30.0, 2000)
    if sleeping:
        space.sleep_time_threshold = 0.5
    for a, b in (((-250, 0), (250, 0)), ((250, 0), (250, 500)), ((-250, 500), (-250, 0)),
                 ((-250, 500), (250, 500))):
        seg = mod.Segment(space.static_body, a, b, 4.0)
        seg.friction = 0.7
        seg.elasticity = 0.3
        space.add(seg)
    paddle = mod.Body(body_type=mod.Body.KINEMATIC)
    paddle.position = 0, 120
    paddle.angular_velocity = 1.3
    blade = mod.Poly.create_box(paddle, (220, 10), 2.0)
    blade.friction = 0.5
    space.add(paddle, blade)
    for i in range(count):
        kind = i % 4
        mass = rng.uniform(0.5, 3.0)
        size = rng.uniform(6.0, 16.0)
        body = mod.Body(mass, box_moment(mass, size, size))
        if kind == 0:
            shape = mod.Circle(body, size / 2, (rng.uniform(-1, 1), 0.0))
        elif kind == 1:
            shape = mod.Poly.create_box(body, (size, size * rng.uniform(0.5, 1.5)))
        elif kind == 2:
            n = rng.randint(3, 8)
            shape = mod.Poly(body, [(size * math.cos(6.283185307179586 * k / n + rng.random() * 0.3),
                                     size * math.sin(6.283185307179586 * k / n))
                                    for k in range(n)], None, rng.choice([0.0, 1.0]))
        else:
            shape = mod.Segment(body, (-size, 0), (size, rng.uniform(-3, 3)), rng.uniform(1, 3))
        body.position = rng.uniform(-220, 220), rng.uniform(220, 480)
        body.angle = rng.uniform(-3, 3)
        body.velocity = rng.uniform(-100, 100), rng.uniform(-100, 100)
        body.angular_velocity = rng.uniform(-2, 2)
        shape.friction = rng.uniform(0.2, 1.0)
        shape.elasticity = rng.uniform(0.0, 0.6)
        space.add(body, shape)
    return Scene(space)


# -- judging ----------------------------------------------------------------------------

@dataclass
class Case:
    """One hard case.

    build(mod) -> Scene; probe(scene) -> dict of numbers, taken every
    `sample_every` steps; judge(scene, samples) -> (passed, metrics).
    `steps` is the CI length, `full_steps` the full one. `fix` lists the
    settings found to make the case pass when the defaults do not (None if
    the defaults pass). `exact` says whether tests compare tamias2d's final
    state with pymunk's bit for bit. `reference(mod)`, if set, builds a
    scene that run_case runs first with the same steps and settings (its
    slop divided by `ref_scale`); its final positions go to
    ``scene.watch["reference"]`` for the judge. `abort(sample)` may say
    that a sample already fails the case, so the run can stop there (only
    when run_case is called with stop_early=True). `note` says what helps
    when no solver setting does.
    """
    name: str
    title: str
    criterion: str
    build: object
    judge: object
    steps: int
    full_steps: int
    dt: float = DT
    probe: object = None
    sample_every: int = 10
    fix: dict = None
    exact: bool = True
    group: str = ""
    reference: object = None
    ref_scale: float = 1.0
    abort: object = None
    note: str = ""
    extra_fixes: list = field(default_factory=list)


@dataclass
class Result:
    """The outcome of :func:`run_case` for one engine and one setting."""
    case: str
    engine: str
    passed: bool
    metrics: dict
    nan: bool
    hash: str
    seconds: float
    steps: int
    settings: dict = field(default_factory=dict)
    error: str = ""
    stopped_at: int = 0


def run_case(mod, case, steps=None, iterations=None, substeps=1, slop=None, full=False,
             stop_early=False, solver=None):
    """Build `case` in engine `mod`, run it and judge it.

    `steps` defaults to case.steps (or case.full_steps with full=True).
    Never raises for an engine exception: it becomes ``Result.error`` and a
    failed result. With stop_early, a run whose sample already fails stops
    there (``Result.stopped_at`` is the step; the hash is of that state).
    `solver` (tamias2d only) sets ``Space.solver`` of the scene and of its
    reference scene.
    """
    if steps is None:
        steps = case.full_steps if full else case.steps
    settings = {"iterations": iterations or 10, "substeps": substeps}
    if slop is not None:
        settings["slop"] = slop
    if solver is not None:
        settings["solver"] = solver
    dt = case.dt / substeps
    reference = None
    if case.reference is not None:
        ref = case.reference(mod)
        if solver is not None:
            ref.space.solver = solver
        if iterations is not None:
            ref.space.iterations = iterations
        if slop is not None:
            ref.space.collision_slop = slop / case.ref_scale
        for i in range(steps * substeps):
            ref.space.step(dt)
        reference = [tuple(b.position) for b in ref.watch["boxes"]]
    scene = case.build(mod)
    scene.watch["reference"] = reference
    space = scene.space
    if solver is not None:
        space.solver = solver
    if iterations is not None:
        space.iterations = iterations
    if slop is not None:
        space.collision_slop = slop
    samples = []
    nan = False
    error = ""
    stopped_at = 0
    t0 = time.perf_counter()
    elapsed = 0.0
    try:
        for i in range(steps):
            for _ in range(substeps):
                space.step(dt)
            if (i + 1) % case.sample_every == 0 or i + 1 == steps:
                elapsed += time.perf_counter() - t0
                if not all_finite(space):
                    nan = True
                    break
                if case.probe is not None:
                    samples.append(case.probe(scene))
                    if stop_early and case.abort is not None and case.abort(samples[-1]):
                        stopped_at = i + 1
                        break
                t0 = time.perf_counter()
    except Exception as exc:  # an engine error is a failed case, reported
        error = f"{type(exc).__name__}: {exc}"
    metrics = {}
    passed = False
    if not nan and not error:
        passed, metrics = case.judge(scene, samples)
    if stopped_at:
        passed = False
    return Result(case.name, getattr(mod, "__name__", str(mod)), bool(passed), metrics, nan,
                  state_hash(space), elapsed, steps, settings, error, stopped_at)


def _stack_probe(scene):
    top = scene.watch["boxes"][-1]
    return {"dx": abs(top.position.x),
            "angle": max(abs(b.angle) for b in scene.watch["boxes"])}


def _stack_judge(scene, samples):
    boxes = scene.watch["boxes"]
    size = scene.watch["size"]
    top = boxes[-1]
    sag = (len(boxes) - 0.5) * size - top.position.y
    m = {"top drift": max(s["dx"] for s in samples),
         "max angle": max(s["angle"] for s in samples),
         "top sag": sag}
    ok = m["top drift"] < 0.1 * size and m["max angle"] < 0.1 and abs(sag) < 0.25 * size
    return ok, m


def _pyramid_judge(scene, samples):
    size = scene.watch["size"]
    m = {"max sideways": max(s["dx"] for s in samples),
         "top sink": max(s["sink"] for s in samples)}
    ok = m["max sideways"] < 0.25 * size and m["top sink"] < 0.25 * size
    return ok, m


def _pyramid_probe(scene):
    boxes = scene.watch["boxes"]
    home = scene.watch["home"]
    return {"dx": max(abs(b.position.x - h[0]) for b, h in zip(boxes, home)),
            "sink": home[-1][1] - boxes[-1].position.y}


def _with_home(build):
    def wrapped(mod):
        scene = build(mod)
        scene.watch["home"] = [tuple(b.position) for b in scene.watch["boxes"]]
        return scene
    wrapped.__doc__ = build.__doc__
    return wrapped


def _mass_ratio_probe(scene):
    light, heavy = scene.watch["light"], scene.watch["heavy"]
    size = scene.watch["size"]
    return {"overlap": size - (heavy.position.y - light.position.y),
            "sink": size / 2.0 - light.position.y,
            "dx": max(abs(light.position.x), abs(heavy.position.x))}


def _mass_ratio_judge(scene, samples):
    size = scene.watch["size"]
    last = samples[-1]
    m = {"overlap": last["overlap"], "sink": last["sink"],
         "max drift": max(s["dx"] for s in samples)}
    # abs: a heavy box apart from the light one at the end is bouncing, not
    # resting (a gap would pass a one-sided test).
    ok = abs(m["overlap"]) < 0.05 * size and m["sink"] < 0.05 * size and m["max drift"] < 0.05 * size
    return ok, m


def _tunnel_probe(scene):
    return {"x": scene.watch["ball"].position.x}


def _tunnel_judge(scene, samples):
    r = scene.watch["radius"]
    worst = max(s["x"] for s in samples)
    m = {"max x": worst, "final x": samples[-1]["x"]}
    return worst < 0.0 + r, m


def _scaled_judge_factory(kind):
    def judge(scene, samples):
        boxes = scene.watch["boxes"]
        s = scene.watch["scale"]
        ox, oy = scene.watch["offset"]
        ref = scene.watch["reference"]
        worst = 0.0
        for b, r in zip(boxes, ref):
            x = (b.position.x - ox) / s
            y = (b.position.y - oy) / s
            worst = max(worst, math.hypot(x - r[0], y - r[1]))
        m = {"max deviation (unscaled units)": worst,
             "max displacement": max(smp["max"] / s for smp in samples)}
        size = scene.watch["size"]
        return worst < 0.05 * size and m["max displacement"] < 0.25 * size, m
    return judge


def _with_home_and_reference(build):
    def wrapped(mod):
        scene = build(mod)
        scene.watch["home"] = [tuple(b.position) for b in scene.watch["boxes"]]
        return scene
    wrapped.__doc__ = build.__doc__
    return wrapped


def _scaled_probe(scene):
    boxes = scene.watch["boxes"]
    home = scene.watch["home"]
    d = [math.hypot(b.position.x - h[0], b.position.y - h[1]) for b, h in zip(boxes, home)]
    scene.watch["count"] = scene.watch.get("count", 0) + 1
    return {"max": max(d)}


def _polys_probe(scene):
    bodies = scene.watch["polys"] + scene.watch.get("caps", [])
    return {"y": [b.position.y for b in bodies], "ke": kinetic(scene.space)}


def _polys_judge(scene, samples):
    polys = scene.watch["polys"]
    caps = scene.watch.get("caps", [])
    rest = scene.watch["rest"] + scene.watch.get("cap_rest", [])
    last = samples[-1]["y"]
    dev = max(abs(y - r) for y, r in zip(last, rest))
    m = {"max rest deviation": dev, "final KE": samples[-1]["ke"],
         "lowest y": min(min(s["y"]) for s in samples)}
    return dev < 2.0 and m["final KE"] < 1.0, m


def _many_judge(scene, samples):
    lower, upper = scene.watch["polys"]
    gap = math.hypot(upper.position.x - lower.position.x, upper.position.y - lower.position.y)
    m = {"centre distance": gap, "lower y": lower.position.y, "final KE": kinetic(scene.space)}
    ok = 39.0 < gap < 41.0 and abs(lower.position.y - 20.0) < 1.0 and m["final KE"] < 1.0
    return ok, m


def _floor_probe(scene):
    body = scene.watch["polys"][0]
    return {"dx": abs(body.position.x), "ke": kinetic(scene.space)}


def _floor_judge(scene, samples):
    m = {"max dx": max(s["dx"] for s in samples), "final KE": samples[-1]["ke"]}
    return m["max dx"] < 1.0 and m["final KE"] < 1.0, m


def _zero_radius_probe(scene):
    return {"y": [b.position.y for b in scene.watch["resting"]]}


def _zero_radius_judge(scene, samples):
    lowest = min(min(s["y"]) for s in samples)
    final = samples[-1]["y"]
    dev = max(abs(y - r) for y, r in zip(final, scene.watch["rest"]))
    m = {"lowest y": lowest, "max rest deviation": dev}
    return lowest > -2.0 and dev < 2.0, m


def _coincident_judge(scene, samples):
    sep = [math.hypot(a.position.x - b.position.x, a.position.y - b.position.y)
           for a, b in scene.watch["pairs"]]
    short = min(d / t for d, t in zip(sep, scene.watch["touch"]))
    speed = max(math.hypot(*b.velocity) for b in scene.space.bodies)
    m = {"min distance / touching distance": short, "max speed": speed}
    return short >= 0.95 and speed < 1000.0, m


def _energy_probe(scene):
    return {"e": energy(scene.space), "ke": kinetic(scene.space)}


def _max_rise(values):
    """The largest increase from any value to a later one."""
    low = math.inf
    rise = 0.0
    for v in values:
        low = min(low, v)
        rise = max(rise, v - low)
    return rise


def _energy_down_judge(scene, samples):
    e0 = scene.watch["e0"]
    es = [s["e"] for s in samples]
    m = {"max E / E0": max(es) / e0, "max rise / E0": _max_rise(es) / e0,
         "final KE / E0": samples[-1]["ke"] / e0}
    ok = m["max E / E0"] <= 1.0 and m["max rise / E0"] < 1e-3 and m["final KE / E0"] < 1e-6
    return ok, m


def _energy_flat_judge(scene, samples):
    e0 = scene.watch["e0"]
    es = [s["e"] for s in samples]
    m = {"min E / E0": min(es) / e0, "max E / E0": max(es) / e0, "final E / E0": es[-1] / e0}
    return m["max E / E0"] < 1.05 and m["min E / E0"] > 0.5, m


def _with_e0(build):
    def wrapped(mod):
        scene = build(mod)
        scene.watch["e0"] = energy(scene.space)
        return scene
    wrapped.__doc__ = build.__doc__
    return wrapped


# -- classic scenes (the soft solver's issue) -----------------------------------------------
# Criteria fixed before the scenes were first run.

def _card(mod, space, x, y, angle, length, thick, friction):
    body = mod.Body(1.0, box_moment(1.0, thick, length))
    body.position = x, y
    body.angle = angle
    shape = mod.Poly.create_box(body, (thick, length))
    shape.friction = friction
    space.add(body, shape)
    return body


def build_card_house(mod, levels=3, length=40.0, thick=1.0, lean=0.3, pitch=30.0,
                     friction=0.8):
    """A house of cards: `levels` levels of A-frames (two cards `thick` x
    `length` leaning `lean` rad from the vertical, top corners touching),
    flat cards bridging neighbouring A-frames, the next level on the flats.
    Everything touches exactly; mass 1 per card."""
    space = _space(mod)
    _ground(mod, space, friction=friction)
    c, s = math.cos(lean), math.sin(lean)
    apex = length * c + thick * s          # the cards' highest corners
    cx = length / 2.0 * s + thick / 2.0 * c
    cy = length / 2.0 * c + thick / 2.0 * s
    cards = []
    base = 0.0
    for level in range(levels):
        count = levels - level
        xs = [(i - (count - 1) / 2.0) * pitch for i in range(count)]
        for x in xs:
            cards.append(_card(mod, space, x - cx, base + cy, -lean, length, thick, friction))
            cards.append(_card(mod, space, x + cx, base + cy, lean, length, thick, friction))
        top = base + apex
        if count > 1:
            for a, b in zip(xs, xs[1:]):
                cards.append(_card(mod, space, (a + b) / 2.0, top + thick / 2.0, math.pi / 2.0,
                                   length, thick, friction))
        base = top + thick
    return Scene(space, cards=cards, length=length,
                 home=[(tuple(b.position), b.angle) for b in cards])


def _moved_probe(key):
    """A probe of the farthest move and largest turn of the bodies
    ``scene.watch[key]`` since ``scene.watch["home"]``."""
    def probe(scene):
        pairs = list(zip(scene.watch[key], scene.watch["home"]))
        return {"d": max(math.hypot(b.position.x - p[0], b.position.y - p[1])
                         for b, (p, a) in pairs),
                "turn": max(abs(b.angle - a) for b, (p, a) in pairs)}
    return probe


_card_probe = _moved_probe("cards")


def _card_judge(scene, samples):
    m = {"max move": max(s["d"] for s in samples), "max turn": max(s["turn"] for s in samples)}
    return m["max move"] < 0.05 * scene.watch["length"] and m["max turn"] < 0.05, m


def arch_blocks(blocks, inner, outer):
    """The blocks of a semicircular arch between radii `inner` and `outer`:
    each one's centre of gravity (its area centroid) and its corners about it
    (benchmarks/arches.py builds the same arch in Box2D)."""
    out = []
    for i in range(blocks):
        a0 = math.pi * i / blocks
        a1 = math.pi * (i + 1) / blocks
        corners = [(inner * math.cos(a0), inner * math.sin(a0)),
                   (outer * math.cos(a0), outer * math.sin(a0)),
                   (outer * math.cos(a1), outer * math.sin(a1)),
                   (inner * math.cos(a1), inner * math.sin(a1))]
        # The centre of gravity: the area centroid (a trapezoid's lies
        # toward its wider, outer side of the mean of its corners).
        area = cx = cy = 0.0
        for (x0, y0), (x1, y1) in zip(corners, corners[1:] + corners[:1]):
            cross = x0 * y1 - x1 * y0
            area += cross
            cx += (x0 + x1) * cross
            cy += (y0 + y1) * cross
        cx /= 3.0 * area
        cy /= 3.0 * area
        out.append(((cx, cy), [(x - cx, y - cy) for x, y in corners]))
    return out


def build_arch(mod, blocks=11, inner=80.0, outer=100.0, friction=0.6):
    """A semicircular arch of `blocks` trapezoids (the sectors' corners)
    between radii `inner` and `outer`, standing on the ground, held by
    friction alone: no joints. Mass 1 per block."""
    space = _space(mod)
    _ground(mod, space, friction=friction)
    stones = []
    for (cx, cy), verts in arch_blocks(blocks, inner, outer):
        body = mod.Body(1.0, mod.moment_for_poly(1.0, verts))
        body.position = cx, cy
        shape = mod.Poly(body, verts)
        shape.friction = friction
        space.add(body, shape)
        stones.append(body)
    return Scene(space, stones=stones, thick=outer - inner,
                 home=[(tuple(b.position), b.angle) for b in stones])


_arch_probe = _moved_probe("stones")


def _arch_judge(scene, samples):
    m = {"max move": max(s["d"] for s in samples), "max turn": max(s["turn"] for s in samples)}
    return m["max move"] < 0.05 * scene.watch["thick"] and m["max turn"] < 0.02, m


def build_light_on_heavy(mod, ratio=1000.0, size=20.0):
    """A light box (mass 1) resting on a box `ratio` times heavier, on the
    ground."""
    space = _space(mod)
    _ground(mod, space)
    heavy = _box(mod, space, 0.0, size / 2.0, size, size, mass=ratio)
    light = _box(mod, space, 0.0, size * 1.5, size, size, mass=1.0)
    return Scene(space, light=light, heavy=heavy, size=size)


def _light_on_heavy_probe(scene):
    light, heavy = scene.watch["light"], scene.watch["heavy"]
    size = scene.watch["size"]
    return {"gap": abs(size - (light.position.y - heavy.position.y)),
            "sink": abs(size / 2.0 - heavy.position.y),
            "dx": max(abs(light.position.x), abs(heavy.position.x))}


def _light_on_heavy_judge(scene, samples):
    size = scene.watch["size"]
    m = {"max |gap|": max(s["gap"] for s in samples[1:] or samples),
         "max |sink|": max(s["sink"] for s in samples[1:] or samples),
         "max drift": max(s["dx"] for s in samples)}
    return all(v < 0.05 * size for v in m.values()), m


RAMP_ANGLE = 0.35   # tan = 0.365


def build_ramp(mod, size=20.0, angle=RAMP_ANGLE, sticky=0.6, slippery=0.2):
    """Two boxes resting on a long static ramp of friction 1 at `angle`:
    one with friction `sticky` (above tan(angle): it must stay), one with
    `slippery` (below: it must slide with a = g (sin - mu cos))."""
    space = _space(mod)
    c, s = math.cos(angle), math.sin(angle)
    # the ramp's top surface is the line through the origin along (c, s)
    seg = mod.Segment(space.static_body, (-4000.0 * c + 5.0 * s, -4000.0 * s - 5.0 * c),
                      (400.0 * c + 5.0 * s, 400.0 * s - 5.0 * c), 5.0)
    seg.friction = 1.0
    space.add(seg)
    boxes = []
    # the slippery one below the sticky one, sliding away from it
    for along, mu in ((40.0, sticky), (-200.0, slippery)):
        body = mod.Body(1.0, box_moment(1.0, size, size))
        body.position = along * c - size / 2.0 * s, along * s + size / 2.0 * c
        body.angle = angle
        shape = mod.Poly.create_box(body, (size, size))
        shape.friction = mu
        space.add(body, shape)
        boxes.append(body)
    return Scene(space, sticky=boxes[0], slippery=boxes[1], size=size, angle=angle,
                 mu=slippery, g=900.0, home=[tuple(b.position) for b in boxes])


def _ramp_probe(scene):
    c, s = math.cos(scene.watch["angle"]), math.sin(scene.watch["angle"])
    out = []
    for b, h in zip((scene.watch["sticky"], scene.watch["slippery"]), scene.watch["home"]):
        out.append(-((b.position.x - h[0]) * c + (b.position.y - h[1]) * s))  # down the slope
    return {"sticky": out[0], "slippery": out[1]}


def _ramp_judge(scene, samples):
    a = scene.watch["angle"]
    accel = scene.watch["g"] * (math.sin(a) - scene.watch["mu"] * math.cos(a))
    t = len(samples) * 10 * DT   # sampled every 10 steps
    expect = 0.5 * accel * t * t
    m = {"sticky moved": max(abs(s["sticky"]) for s in samples),
         "slippery moved / 0.5 a t^2": samples[-1]["slippery"] / expect}
    return (m["sticky moved"] < 0.05 * scene.watch["size"]
            and abs(m["slippery moved / 0.5 a t^2"] - 1.0) < 0.1), m


def build_overlapping(mod, count=12, size=20.0, seed=7):
    """`count` boxes created deep inside each other (centres within half a
    box of one another) just above the ground: they must come apart
    gently."""
    import random
    rng = random.Random(seed)
    space = _space(mod)
    _ground(mod, space)
    boxes = [_box(mod, space, rng.uniform(-0.25, 0.25) * size,
                  size * (0.5 + rng.uniform(0.0, 0.5)), size, size) for _ in range(count)]
    return Scene(space, boxes=boxes, size=size)


def _deepest_overlap(space):
    deepest = [0.0]

    def visit(arbiter):
        for p in arbiter.contact_point_set.points:
            deepest[0] = min(deepest[0], p.distance)
    for b in space.bodies:
        b.each_arbiter(visit)
    return -deepest[0]


def _overlapping_probe(scene):
    return {"speed": max(math.hypot(*b.velocity) for b in scene.watch["boxes"]),
            "far": max(math.hypot(*b.position) for b in scene.watch["boxes"]),
            "overlap": _deepest_overlap(scene.space)}


def _overlapping_judge(scene, samples):
    size = scene.watch["size"]
    m = {"max speed": max(s["speed"] for s in samples),
         "farthest": max(s["far"] for s in samples),
         "final deepest overlap": samples[-1]["overlap"]}
    return (m["max speed"] < 20.0 * size and m["farthest"] < 20.0 * size
            and m["final deepest overlap"] < 0.05 * size), m


def build_overfilled(mod, columns=20, rows=30, radius=5.0, width=200.0, height=150.0):
    """A static open box `width` x `height` (walls 10 thick) under
    `columns` x `rows` circles of radius `radius`, about twice what it
    holds: they pile up and spill over the walls onto a fenced floor 200
    below."""
    space = _space(mod)
    half = width / 2.0
    for a, b in (((-half - 5.0, -5.0), (half + 5.0, -5.0)),
                 ((-half - 5.0, -5.0), (-half - 5.0, height)),
                 ((half + 5.0, -5.0), (half + 5.0, height))):
        seg = mod.Segment(space.static_body, a, b, 5.0)
        seg.friction = 0.5
        space.add(seg)
    # a fenced floor 200 below catches what spills over; the box stands on
    # a solid pedestal, so nothing rolls under it
    catch = mod.Segment(space.static_body, (-600.0, -205.0), (600.0, -205.0), 5.0)
    for x in (-600.0, 600.0):
        fence = mod.Segment(space.static_body, (x, -205.0), (x, -100.0), 5.0)
        space.add(fence)
    pedestal = mod.Poly(space.static_body, [(-half - 10.0, -200.0), (half + 10.0, -200.0),
                                            (half + 10.0, -10.0), (-half - 10.0, -10.0)])
    catch.friction = pedestal.friction = 0.5
    space.add(catch, pedestal)
    balls = []
    for i in range(rows):
        for j in range(columns):
            body = mod.Body(1.0, mod.moment_for_circle(1.0, 0.0, radius))
            body.position = (j - (columns - 1) / 2.0) * 2.1 * radius, height + 20.0 + i * 2.1 * radius
            shape = mod.Circle(body, radius)
            shape.friction = 0.5
            space.add(body, shape)
            balls.append(body)
    return Scene(space, balls=balls, half=half, height=height, radius=radius)


def _overfilled_probe(scene):
    half, height, r = scene.watch["half"], scene.watch["height"], scene.watch["radius"]
    through = 0
    for b in scene.watch["balls"]:
        x, y = b.position
        if abs(x) < half + 10.0 and y < -0.5 * r:
            through += 1                     # in the floor or the pedestal
        elif half - 0.5 * r < abs(x) < half + 10.0 + 0.5 * r and y < height:
            through += 1                     # inside a wall
    return {"through": through,
            "speed": max(math.hypot(*b.velocity) for b in scene.watch["balls"])}


def _overfilled_judge(scene, samples):
    m = {"max inside floor or walls": max(s["through"] for s in samples),
         "max speed": max(s["speed"] for s in samples)}
    return m["max inside floor or walls"] == 0 and m["max speed"] < 2000.0, m


def build_thin_wall(mod, speed=100.0, radius=0.25, thick=0.1):
    """A small circle shot at `speed` at a static wall `thick` thick (near
    face at x = 0), no gravity."""
    space = _space(mod, gravity=0.0)
    wall = mod.Poly(space.static_body, [(0.0, -20.0), (thick, -20.0), (thick, 20.0), (0.0, 20.0)])
    space.add(wall)
    body = mod.Body(1.0, 0.5 * radius * radius)
    body.position = -10.3, 0.0
    body.velocity = speed, 0.0
    ball = mod.Circle(body, radius)
    space.add(body, ball)
    return Scene(space, ball=body, radius=radius)


def _thin_wall_judge(scene, samples):
    worst = max(s["x"] for s in samples)
    return worst < 0.0, {"max x": worst, "final x": samples[-1]["x"]}


def build_scaled_slop(mod, scale=1.0):
    """The 5-row pyramid with every length, gravity and collision_slop
    multiplied by `scale`."""
    scene = build_pyramid(mod, rows=5, s=scale)
    scene.space.collision_slop = 0.1 * scale
    return scene


def _bind(fn, **kw):
    def built(mod):
        return fn(mod, **kw)
    built.__doc__ = fn.__doc__
    return built


def _make_cases():
    cases = []
    for n in (10, 20, 40):
        cases.append(Case(
            f"stack_{n}", f"vertical stack of {n} boxes",
            "top box drifts < 0.1 box sideways, no box tilts > 0.1 rad, top sags < 0.25 box",
            _bind(build_stack, count=n), _stack_judge, steps=300, full_steps=3600,
            probe=_stack_probe, group="stacks",
            abort=lambda s: s["dx"] >= 2.0 or s["angle"] >= 0.1))
    for rows, steps, full in ((20, 300, 3600), (40, 120, 1800)):
        cases.append(Case(
            f"pyramid_{rows}", f"pyramid of {rows} rows",
            "no box moves > 0.25 box sideways, the top box sinks < 0.25 box",
            _with_home(_bind(build_pyramid, rows=rows)), _pyramid_judge, steps=steps,
            full_steps=full, probe=_pyramid_probe, group="stacks",
            abort=lambda s: s["dx"] >= 5.0 or s["sink"] >= 5.0))
    for ratio in (10, 100, 1000):
        cases.append(Case(
            f"mass_ratio_{ratio}", f"light box under one {ratio}x heavier",
            "overlap (or gap) of the two boxes, sink into the ground and drift all < 0.05 box",
            _bind(build_mass_ratio, ratio=float(ratio)), _mass_ratio_judge, steps=300,
            full_steps=3600, probe=_mass_ratio_probe, group="mass ratio",
            abort=lambda s: s["dx"] >= 1.0 or s["overlap"] >= 10.0 or s["sink"] >= 10.0))
    cases.append(Case(
        "tunnel", "ball r 0.5 at 1200/s (20 per step) at a wall 1 thick",
        "the ball's centre never gets past the wall's near face + r",
        build_tunnel, _tunnel_judge, steps=120, full_steps=600, probe=_tunnel_probe,
        sample_every=1, group="tunnelling", abort=lambda s: s["x"] >= 0.5))
    for name, s in (("scale_1e-3", 1e-3), ("scale_1e3", 1e3)):
        cases.append(Case(
            name, f"5-row pyramid scaled by {s:g} (lengths and gravity)",
            "positions / scale within 0.05 box of the unscaled run; nothing moves > 0.25 box",
            _with_home_and_reference(_bind(build_scaled, scale=s)), _scaled_judge_factory("scale"),
            steps=300, full_steps=3600, probe=_scaled_probe, group="scale",
            reference=_bind(build_pyramid, rows=5), ref_scale=s,
            extra_fixes=[{"slop": 0.1 * s}]))
    cases.append(Case(
        "far_1e6", "5-row pyramid at (1e6, 1e6)",
        "positions - offset within 0.05 box of the run at the origin; nothing moves > 0.25 box",
        _with_home_and_reference(build_far), _scaled_judge_factory("far"), steps=300,
        full_steps=3600, probe=_scaled_probe, group="scale",
        reference=_bind(build_pyramid, rows=5)))
    for name, build, title in (
            ("poly_collinear", build_poly_collinear, "polygons with collinear vertices"),
            ("poly_duplicate", build_poly_duplicate, "polygons with duplicate vertices"),
            ("poly_sliver", build_poly_sliver, "polygons of near-zero area")):
        cases.append(Case(
            name, title + ", boxes on top",
            "all rest within 2 of their rest height, final KE < 1, no NaN",
            build, _polys_judge, steps=300, full_steps=3600, probe=_polys_probe,
            group="degenerate"))
    cases.append(Case(
        "poly_1000_tube", "two 1000-vertex polygons stacked in a tube",
        "centre distance 40 +- 1, the lower one at y 20 +- 1, final KE < 1, no NaN",
        _bind(build_poly_many, count=1000), _many_judge, steps=120, full_steps=1200,
        group="degenerate"))
    for count in (256, 1000):
        cases.append(Case(
            f"poly_{count}_floor", f"{count}-vertex polygon let go at rest on a flat floor",
            "it stays put: dx < 1 throughout, final KE < 1 (energy does not grow)",
            _bind(build_poly_floor, count=count), _floor_judge, steps=600, full_steps=3600,
            probe=_floor_probe, group="degenerate", abort=lambda s: s["dx"] >= 1.0))
    cases.append(Case(
        "zero_radius_floor", "radius-0 floor; a box, a circle, a segment dropped on it",
        "nothing below y -2; all rest within 2 of their rest height; no NaN",
        build_zero_radius, _zero_radius_judge, steps=300, full_steps=3600,
        probe=_zero_radius_probe, group="degenerate"))
    cases.append(Case(
        "zero_radius_pair", "radius-0 segments (flat, tilted, zero length) on a radius-0 floor",
        "nothing below y -2; all rest within 2 of their rest height; no NaN",
        build_zero_radius_pair, _zero_radius_judge, steps=300, full_steps=3600,
        probe=_zero_radius_probe, group="degenerate",
        note="two radius-0 segments have no area to overlap, so the narrow phase "
             "never reports a contact; give one of them a radius (>= 1 here)"))
    cases.append(Case(
        "coincident_circles", "two circles created at the same point",
        "they end >= 0.95 touching distance apart, speed < 1000, no NaN",
        build_coincident_circles, _coincident_judge, steps=120, full_steps=1200,
        group="degenerate"))
    cases.append(Case(
        "coincident_polys", "box/box, box/circle and box/static box created at the same point",
        "they end >= 0.95 touching distance apart, speed < 1000, no NaN",
        build_coincident_polys, _coincident_judge, steps=120, full_steps=1200,
        group="degenerate",
        note="GJK/EPA on exactly coincident polygons returns a zero normal and "
             "distance 0, so no impulse acts; any offset (1e-3 in the next case) "
             "lets them separate (the soft solver's narrow phase uses face normals "
             "there and parts them)"))
    cases.append(Case(
        "near_coincident_polys", "the same pairs, the second moved by (1e-3, 5e-4)",
        "they end >= 0.95 touching distance apart, speed < 1000, no NaN",
        _bind(build_coincident_polys, nudge=1e-3), _coincident_judge, steps=120,
        full_steps=1200, group="degenerate"))
    cases.append(Case(
        "long_run", "15 bodies in a closed box, e 0.5, gravity, 100,000 steps",
        "E = KE + PE never above E0, never rises > 1e-3 E0 between samples, final KE < 1e-6 E0",
        _with_e0(build_long_run), _energy_down_judge, steps=100_000, full_steps=100_000,
        probe=_energy_probe, sample_every=100, group="long run"))
    cases.append(Case(
        "elastic_gas", "20 elastic frictionless circles, no gravity",
        "energy stays within [0.5, 1.05] of its start, no NaN",
        _with_e0(build_elastic_gas), _energy_flat_judge, steps=20_000, full_steps=100_000,
        probe=_energy_probe, sample_every=100, group="long run"))
    # Classic scenes of the soft solver's issue; the criteria were written
    # before the first run.
    cases.append(Case(
        "card_house", "house of cards: 3 levels of leaning card pairs (40 x 1) and flat cards",
        "no card moves > 0.05 card length or turns > 0.05 rad",
        build_card_house, _card_judge, steps=300, full_steps=1800, probe=_card_probe,
        group="classic", abort=lambda s: s["d"] >= 10.0))
    cases.append(Case(
        "arch", "semicircular arch of 11 trapezoids, friction only (radii 80-100)",
        "no block moves > 0.05 arch thickness or turns > 0.02 rad",
        build_arch, _arch_judge, steps=300, full_steps=1800, probe=_arch_probe,
        group="classic", abort=lambda s: s["d"] >= 10.0))
    cases.append(Case(
        "light_on_heavy_1000", "light box resting on one 1000x heavier",
        "gap between the boxes, sink into the ground and drift all < 0.05 box",
        _bind(build_light_on_heavy, ratio=1000.0), _light_on_heavy_judge, steps=300,
        full_steps=3600, probe=_light_on_heavy_probe, group="mass ratio"))
    cases.append(Case(
        "friction_ramp", "boxes on a 0.35 rad ramp: friction 0.6 (> tan) and 0.2 (< tan)",
        "the 0.6 box moves < 0.05 box; the 0.2 box slides 0.5 a t^2 within 10%",
        build_ramp, _ramp_judge, steps=120, full_steps=300, probe=_ramp_probe,
        group="classic"))
    cases.append(Case(
        "overlapping_start", "12 boxes created deep inside each other on the ground",
        "they separate gently: speed < 20 boxes/s, none goes > 20 boxes away, "
        "final deepest overlap < 0.05 box",
        build_overlapping, _overlapping_judge, steps=300, full_steps=1800,
        probe=_overlapping_probe, group="classic"))
    cases.append(Case(
        "overfilled_box", "600 circles poured into a box that holds about 300",
        "no circle ever inside the floor or a wall; speed < 2000",
        build_overfilled, _overfilled_judge, steps=300, full_steps=1200,
        probe=_overfilled_probe, group="classic",
        note="no iterations / substeps setting of the chipmunk solver keeps the circles "
             "out of the walls under the pile's pressure; Space.solver = 'soft' does"))
    for name, speed, radius in (("thin_wall", 100.0, 0.25), ("thin_wall_fast", 5000.0, 0.1)):
        cases.append(Case(
            name, f"ball r {radius:g} at {speed:g}/s at a static wall 0.1 thick",
            "the ball's centre never gets past the wall's near face",
            _bind(build_thin_wall, speed=speed, radius=radius), _thin_wall_judge, steps=60,
            full_steps=600, probe=_tunnel_probe, sample_every=1, group="tunnelling",
            abort=lambda s: s["x"] >= 0.0,
            note="" if speed < 1000.0 else
            "83 units a step against a 0.1 wall: only continuous collision stops it "
            "(Space.solver = 'soft')"))
    for name, s in (("scale_1e-3_slop", 1e-3), ("scale_1e3_slop", 1e3)):
        cases.append(Case(
            name, f"5-row pyramid scaled by {s:g} (lengths, gravity and collision_slop)",
            "positions / scale within 0.05 box of the unscaled run; nothing moves > 0.25 box",
            _with_home_and_reference(_bind(build_scaled_slop, scale=s)),
            _scaled_judge_factory("scale"), steps=300, full_steps=3600, probe=_scaled_probe,
            group="scale", reference=_bind(build_pyramid, rows=5), ref_scale=s))
    cases.append(Case(
        "pyramid_60", "pyramid of 60 rows (1,830 boxes)",
        "no box moves > 0.25 box sideways, the top box sinks < 0.25 box",
        _with_home(_bind(build_pyramid, rows=60)), _pyramid_judge, steps=60, full_steps=900,
        probe=_pyramid_probe, group="stacks", abort=lambda s: s["dx"] >= 5.0 or s["sink"] >= 5.0))
    return {c.name: c for c in cases}


CASES = _make_cases()

# Settings tried, in this order, on a case that fails with the defaults:
# solver iterations and substeps (each 1/60 s step taken as `substeps`
# steps), ordered by the work they add (about substeps * (iterations + 10)).
FIX_GRID = [dict(iterations=i, substeps=s) for i, s in (
    (20, 1), (10, 2), (40, 1), (20, 2), (10, 4), (40, 2), (20, 4), (10, 8), (40, 4),
    (20, 8), (10, 16), (40, 8), (20, 16), (10, 32), (40, 16), (10, 64))]

# Fixes found by benchmarks/stability_report.py on the full runs (recorded
# here so tests/test_hard_cases.py can check that they still work).
FIXES = {
    'stack_10': {'iterations': 10, 'substeps': 2},
    'stack_20': {'iterations': 10, 'substeps': 8},
    'stack_40': {'iterations': 20, 'substeps': 16},
    'pyramid_20': {'iterations': 20, 'substeps': 1},
    'pyramid_40': {'iterations': 20, 'substeps': 2},
    'mass_ratio_100': {'iterations': 40, 'substeps': 1},
    'mass_ratio_1000': {'iterations': 40, 'substeps': 8},
    'tunnel': {'iterations': 10, 'substeps': 16},
    'scale_1e3': {'slop': 100.0},
    'poly_256_floor': {'iterations': 10, 'substeps': 2},
    'poly_1000_floor': {'iterations': 20, 'substeps': 4},
    'card_house': {'iterations': 40, 'substeps': 1},
    'arch': {'iterations': 10, 'substeps': 2},
    'thin_wall': {'iterations': 10, 'substeps': 8},
    'pyramid_60': {'iterations': 20, 'substeps': 4},
}

# The outcome of every case with the default settings in the full runs
# (True: passes), as docs/stability.md reports it.
FULL_DEFAULT = {
    'stack_10': False,
    'stack_20': False,
    'stack_40': False,
    'pyramid_20': False,
    'pyramid_40': False,
    'mass_ratio_10': True,
    'mass_ratio_100': False,
    'mass_ratio_1000': False,
    'tunnel': False,
    'scale_1e-3': True,
    'scale_1e3': False,
    'far_1e6': True,
    'poly_collinear': True,
    'poly_duplicate': True,
    'poly_sliver': True,
    'poly_1000_tube': True,
    'poly_256_floor': False,
    'poly_1000_floor': False,
    'zero_radius_floor': True,
    'zero_radius_pair': False,
    'coincident_circles': True,
    'coincident_polys': False,
    'near_coincident_polys': True,
    'long_run': True,
    'elastic_gas': True,
    'card_house': False,
    'arch': False,
    'light_on_heavy_1000': True,
    'friction_ramp': True,
    'overlapping_start': True,
    'overfilled_box': False,
    'thin_wall': False,
    'thin_wall_fast': False,
    'scale_1e-3_slop': True,
    'scale_1e3_slop': True,
    'pyramid_60': False,
}
