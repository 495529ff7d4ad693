"""Scenes built the same way in pymunk and in tamias2d.

Every builder takes the engine module (``pymunk`` or ``tamias2d``, or any
object with the same names) and returns a ready Space. Builders use only the
pymunk 7.3 API and make every object in the same order, so the two engines
get the same input; the cross-validation tests and the benchmarks compare
them step by step.

A builder may attach ``space.scene_hook``: a function ``hook(step_index)``
to call before each step (used to add and remove objects between steps).
:func:`run` does that. ``SCENES`` lists each scene with its time step and the
number of steps the tests run.

>>> import pymunk
>>> space = circles_on_segment(pymunk, count=3)
>>> len(space.bodies)
3
"""
import math
from collections import namedtuple

Scene = namedtuple("Scene", "build dt steps")


def box_moment(mass, w, h):
    """Moment of a w x h box about its centre (the same float in both engines)."""
    return mass * (w * w + h * h) / 12.0


def circle_moment(mass, r):
    """Moment of a solid disc of radius r about its centre."""
    return mass * 0.5 * r * r


def run(space, dt, steps, on_step=None):
    """Step `space` `steps` times, calling space.scene_hook(i) before step i
    and on_step(i) after it.

    >>> import pymunk
    >>> s = pymunk.Space()
    >>> run(s, 0.1, 3)
    """
    hook = getattr(space, "scene_hook", None)
    for i in range(steps):
        if hook is not None:
            hook(i)
        space.step(dt)
        if on_step is not None:
            on_step(i)


def _ground(mod, space, half_width=400.0, y=0.0, radius=2.0, friction=1.0):
    seg = mod.Segment(space.static_body, (-half_width, y), (half_width, y), radius)
    seg.friction = friction
    space.add(seg)
    return seg


def circles_on_segment(mod, count=30):
    """Circles dropped in a staggered column onto a static segment."""
    space = mod.Space()
    space.gravity = 0, -900
    _ground(mod, space, radius=10.0, friction=0.7)
    for x in (-250.0, 250.0):
        wall = mod.Segment(space.static_body, (x, 0), (x, 900), 10.0)
        wall.elasticity = 0.5
        space.add(wall)
    for i in range(count):
        r = 6.0 + (i % 4)
        body = mod.Body(1.0 + 0.1 * (i % 3), circle_moment(1.0 + 0.1 * (i % 3), r))
        body.position = -120.0 + 17.0 * (i % 15) + 3.0 * (i // 15), 30.0 + 23.0 * i
        shape = mod.Circle(body, r)
        shape.friction = 0.6
        shape.elasticity = 0.2
        space.add(body, shape)
    return space


def pyramid(mod, rows=20, size=20.0):
    """A box2d-style pyramid of `rows` rows of size x size boxes, friction 1."""
    space = mod.Space()
    space.gravity = 0, -900
    _ground(mod, space, half_width=1000.0, friction=1.0)
    gap = 0.25
    for i in range(rows):
        y = size / 2.0 + 2.0 + i * (size + gap)
        for j in range(rows - i):
            x = -rows * (size + gap) / 2.0 + i * (size + gap) / 2.0 + j * (size + gap)
            body = mod.Body(1.0, box_moment(1.0, size, size))
            body.position = x, y
            shape = mod.Poly.create_box(body, (size, size))
            shape.friction = 1.0
            space.add(body, shape)
    return space


def touching_pyramid(mod, base=100):
    """Box2D's large_pyramid benchmark (base 100: 5,050 boxes 1x1, side by
    side and touching, so that a box inside it is in six contacts) on a
    200x2 ground, gravity 10, friction 0.6 (the ground's 1: the engines
    multiply the two), in metres: Box2D's linear slop as collision_slop."""
    space = mod.Space()
    space.gravity = 0, -10
    space.collision_slop = 0.005
    ground = mod.Poly(space.static_body, [(-100, -2), (100, -2), (100, 0), (-100, 0)])
    ground.friction = 1.0
    space.add(ground)
    for i in range(base):
        for j in range(i, base):
            body = mod.Body(1.0, mod.moment_for_box(1.0, (1.0, 1.0)))
            body.position = (i + 1) / 2 + (j - i) - base / 2, i + 0.5
            box = mod.Poly.create_box(body, (1.0, 1.0))
            box.friction = 0.6
            space.add(body, box)
    return space


def vertical_stack(mod, count=10, size=20.0):
    """A single column of `count` boxes, mass 10, friction 0.3."""
    space = mod.Space()
    space.gravity = 0, -900
    _ground(mod, space, friction=0.3)
    for i in range(count):
        body = mod.Body(10.0, box_moment(10.0, size, size))
        body.position = 0.0, size / 2.0 + 1.0 + i * (size + 0.5)
        shape = mod.Poly.create_box(body, (size, size))
        shape.friction = 0.3
        space.add(body, shape)
    return space


def rain(mod, count=520):
    """`count` circles of several radii falling into an open box."""
    space = mod.Space()
    space.gravity = 0, -900
    walls = [((-200, 0), (200, 0)), ((-200, 0), (-200, 500)), ((200, 0), (200, 500))]
    for a, b in walls:
        seg = mod.Segment(space.static_body, a, b, 3.0)
        seg.friction = 0.8
        space.add(seg)
    per_row = 30
    for i in range(count):
        row, col = divmod(i, per_row)
        r = 3.0 + (i % 5) * 0.75
        mass = 0.5 + 0.1 * (i % 7)
        body = mod.Body(mass, circle_moment(mass, r))
        body.position = -174.0 + col * 12.0 + (row % 2) * 6.0, 40.0 + row * 13.0
        body.velocity = (i % 11) - 5.0, -50.0
        shape = mod.Circle(body, r)
        shape.friction = 0.5
        shape.elasticity = 0.1
        space.add(body, shape)
    return space


def drum(mod, count=120, box=14.0, radius=200.0, spin=0.6, wall=4.0):
    """A kinematic octagonal drum turning slowly, full of boxes (placed on a
    grid inside the drum, row by row from the bottom)."""
    space = mod.Space()
    space.gravity = 0, -900
    drum_body = mod.Body(body_type=mod.Body.KINEMATIC)
    drum_body.position = 0, 0
    drum_body.angular_velocity = spin
    space.add(drum_body)
    n = 8
    corners = [(radius * math.cos(2 * math.pi * k / n), radius * math.sin(2 * math.pi * k / n))
               for k in range(n)]
    for k in range(n):
        seg = mod.Segment(drum_body, corners[k], corners[(k + 1) % n], wall)
        seg.friction = 0.9
        space.add(seg)
    pitch = box + 4.0
    inner = radius * math.cos(math.pi / n) - wall - 2.0 - box  # inside the flat sides
    cells = []
    y = -inner + box / 2.0
    while y < inner and len(cells) < count:
        half = math.sqrt(max(inner * inner - y * y, 0.0))
        x = -half + box / 2.0
        while x < half - box / 2.0 and len(cells) < count:
            cells.append((x, y))
            x += pitch
        y += pitch
    if len(cells) < count:
        raise ValueError(f"{count} boxes of {box} do not fit in a drum of radius {radius}")
    for i, (x, y) in enumerate(cells):
        body = mod.Body(1.0, box_moment(1.0, box, box))
        body.position = x, y
        body.angle = 0.1 * (i % 5)
        shape = mod.Poly.create_box(body, (box, box), 0.5)
        shape.friction = 0.7
        space.add(body, shape)
    return space


def mixed(mod):
    """Circles, dynamic segments and rounded polygons of many materials on
    sloped static ground, with a conveyor belt (surface velocity)."""
    space = mod.Space()
    space.gravity = 0, -600
    space.damping = 0.95
    static = space.static_body
    ground = [
        ((-400, 100), (-100, 0), 0.9, 0.3, (0, 0)),
        ((-100, 0), (150, 0), 0.8, 0.0, (-80, 0)),   # conveyor
        ((150, 0), (400, 150), 1.0, 0.5, (0, 0)),
    ]
    for a, b, friction, elasticity, sv in ground:
        seg = mod.Segment(static, a, b, 5.0)
        seg.friction = friction
        seg.elasticity = elasticity
        seg.surface_velocity = sv
        space.add(seg)
    polys = [
        [(-10, -8), (12, -6), (9, 10), (-7, 11)],
        [(0, -12), (11, 0), (0, 12), (-11, 0)],
        [(-14, -5), (14, -5), (0, 15)],
        [(-8, -8), (8, -8), (12, 0), (8, 8), (-8, 8), (-12, 0)],
    ]
    for i in range(36):
        kind = i % 4
        x = -300.0 + (i % 12) * 50.0
        y = 200.0 + (i // 12) * 60.0
        if kind == 0:
            body = mod.Body(2.0, circle_moment(2.0, 10.0))
            shape = mod.Circle(body, 10.0, (1.0, 0.5))
        elif kind == 1:
            body = mod.Body()
            shape = mod.Segment(body, (-15, 0), (15, 3), 4.0)
            shape.density = 0.02
        elif kind == 2:
            body = mod.Body()
            shape = mod.Poly(body, polys[(i // 4) % 4], None, 2.0)
            shape.density = 0.01
        else:
            body = mod.Body(3.0, box_moment(3.0, 20.0, 16.0))
            shape = mod.Poly(body, polys[(i // 4) % 4],
                             mod.Transform.rotation(0.3 * i), 1.0)
        body.position = x, y
        body.angle = 0.2 * i
        body.angular_velocity = 0.5 * ((i % 5) - 2)
        shape.friction = 0.2 + 0.1 * (i % 8)
        shape.elasticity = 0.1 * (i % 6)
        if i % 7 == 3:
            shape.surface_velocity = (20.0, 0.0)
        space.add(body, shape)
    # A body with two shapes: mass from both densities.
    body = mod.Body()
    body.position = 0, 400
    c = mod.Circle(body, 8.0, (-10, 0))
    c.density = 0.05
    p = mod.Poly.create_box(body, (12, 30), 1.5)
    p.density = 0.02
    p.friction = 0.6
    space.add(body, c, p)
    return space


def add_remove(mod):
    """Bodies and shapes added and removed between steps (a hook does it)."""
    space = mod.Space()
    space.gravity = 0, -900
    floor = _ground(mod, space, friction=0.8)
    extra_static = mod.Segment(space.static_body, (-100, 60), (0, 40), 3.0)
    extra_static.friction = 0.5
    space.add(extra_static)
    live = []

    def spawn(i):
        body = mod.Body(1.0, circle_moment(1.0, 7.0))
        body.position = -60.0 + (i * 13) % 120, 150.0 + (i % 3) * 20.0
        shape = mod.Circle(body, 7.0)
        shape.friction = 0.5
        if i % 4 == 1:
            shape2 = mod.Poly.create_box(body, (10, 10))
            shape2.friction = 0.4
            space.add(body, shape, shape2)
            live.append((body, shape, shape2))
        else:
            space.add(body, shape)
            live.append((body, shape))

    for i in range(10):
        spawn(i)

    def hook(step):
        if step % 10 == 5:
            spawn(step)
        if step % 25 == 20 and len(live) > 4:
            objs = live.pop(3)
            # shapes first, then the body, as a game would
            space.remove(*objs[1:])
            space.remove(objs[0])
        if step % 40 == 33 and live:
            body, shape = live[-1][0], live[-1][1]
            space.remove(shape)
            new_shape = mod.Circle(body, 5.0, (2.0, 0.0))
            new_shape.friction = 0.9
            space.add(new_shape)
            live[-1] = (body, new_shape) + tuple(live[-1][2:])
        if step == 300:
            space.remove(extra_static)

    space.scene_hook = hook
    space.scene_floor = floor
    return space


def type_changes(mod):
    """The add_remove scene, plus a sensor and bodies switching between
    dynamic, kinematic and static while in contact."""
    space = add_remove(mod)
    list(space.shapes)[5].sensor = True
    base_hook = space.scene_hook

    def hook(step):
        base_hook(step)
        bodies = list(space.bodies)
        if step == 100:
            bodies[2].body_type = mod.Body.KINEMATIC
            bodies[2].velocity = (5, 0)
        if step == 150:
            bodies[3].body_type = mod.Body.STATIC
        if step == 200:
            bodies[2].body_type = mod.Body.DYNAMIC
            bodies[2].mass = 1
            bodies[2].moment = 30
        if step == 260:
            bodies[3].body_type = mod.Body.DYNAMIC
            bodies[3].mass = 2
            bodies[3].moment = 50
        if step == 300:
            bodies[4].body_type = mod.Body.STATIC
            space.reindex_shapes_for_body(bodies[4])

    space.scene_hook = hook
    return space


SCENES = {
    "circles_on_segment": Scene(circles_on_segment, 1.0 / 60.0, 600),
    "pyramid_20": Scene(pyramid, 1.0 / 60.0, 600),
    "vertical_stack_10": Scene(vertical_stack, 1.0 / 120.0, 600),
    "rain_520": Scene(rain, 1.0 / 60.0, 600),
    "drum": Scene(drum, 1.0 / 60.0, 600),
    "mixed": Scene(mixed, 1.0 / 60.0, 600),
    "add_remove": Scene(add_remove, 1.0 / 60.0, 600),
    "type_changes": Scene(type_changes, 1.0 / 60.0, 500),
}
