"""Cross-validation of the constraints (joints) against pymunk 7.3, bit for bit.

Each scene below is built in both engines with the same calls in the same
order, then stepped side by side. After every step, every body's position,
angle, velocity and angular velocity, and every constraint's impulse (and a
ratchet's notch angle), must be equal with ``==``. A failure names the first
step and the body or constraint where the engines part.

The scenes cover every joint kind: a pin-joint chain, pivot pendulums (both
constructor forms), grooves clamping at both ends, damped and rotary springs
(with max_force clamping and Python force/torque functions), motors with
gears, ratchets, rotary limits and slide joints, ragdolls falling on stairs,
joints removed and added between steps, sleeping components held together by
joints, and the Tumbler scene of pymunk's benchmark suite.
"""
import math

import pytest

pymunk = pytest.importorskip("pymunk")
import tamias2d

DT = 1.0 / 60.0


# -- scene builders: `mod` is pymunk or tamias2d ---------------------------------------------

def _box(mod, space, mass, w, h, pos, angle=0.0, friction=0.7):
    body = mod.Body(mass, mod.moment_for_box(mass, (w, h)))
    body.position = pos
    body.angle = angle
    shape = mod.Poly.create_box(body, (w, h))
    shape.friction = friction
    space.add(body, shape)
    return body, shape


def _ball(mod, space, mass, r, pos, friction=0.7):
    body = mod.Body(mass, mod.moment_for_circle(mass, 0, r))
    body.position = pos
    shape = mod.Circle(body, r)
    shape.friction = friction
    space.add(body, shape)
    return body, shape


def _ground(mod, space, y=0.0, half=600.0):
    seg = mod.Segment(space.static_body, (-half, y), (half, y), 3.0)
    seg.friction = 0.9
    space.add(seg)
    return seg


def pin_chain(mod):
    """A chain of balls on pin joints hanging from the static body; the free
    end is thrown sideways and the chain swings onto two posts."""
    space = mod.Space()
    space.gravity = 0, -900
    _ground(mod, space, y=-400.0)
    for x in (-120.0, 150.0):
        post = mod.Segment(space.static_body, (x, -400), (x, -150), 6.0)
        space.add(post)
    prev = space.static_body
    prev_anchor = (0.0, 0.0)
    for i in range(14):
        body, shape = _ball(mod, space, 1.0 + 0.1 * (i % 3), 6.0, (20.0 * (i + 1), -3.0 * i))
        j = mod.PinJoint(prev, body, prev_anchor, (-4.0, 0.0))
        j.collide_bodies = False
        space.add(j)
        prev = body
        prev_anchor = (4.0, 0.0)
    prev.velocity = (0.0, -300.0)
    return space


def pivot_pendulums(mod):
    """A single pendulum (world-pivot form) and a double pendulum
    (anchor form), the latter chaotic: any lost bit shows quickly."""
    space = mod.Space()
    space.gravity = 0, -981
    b1, _ = _box(mod, space, 2.0, 60.0, 8.0, (30.0, 0.0))
    space.add(mod.PivotJoint(space.static_body, b1, (0.0, 0.0)))
    upper, _ = _box(mod, space, 1.0, 80.0, 6.0, (240.0, 40.0), angle=0.4)
    lower, _ = _box(mod, space, 1.5, 70.0, 6.0, (310.0, 70.0), angle=-0.3)
    j1 = mod.PivotJoint(space.static_body, upper, (200.0, 20.0), (-40.0, 0.0))
    j2 = mod.PivotJoint(upper, lower, (40.0, 0.0), (-35.0, 0.0))
    j2.collide_bodies = False
    space.add(j1, j2)
    lower.angular_velocity = 3.0
    return space


def grooves(mod):
    """A slider in a groove on a spinning bar (it reaches both ends) and a
    ball falling along a tilted static groove onto its end stop."""
    space = mod.Space()
    space.gravity = 0, -600
    bar, _ = _box(mod, space, 5.0, 200.0, 10.0, (0.0, 0.0))
    space.add(mod.PivotJoint(space.static_body, bar, (0.0, 0.0)))
    bar.angular_velocity = 1.5
    slider, shape = _ball(mod, space, 0.5, 8.0, (30.0, 10.0))
    shape.filter = mod.ShapeFilter(group=1)
    bar_shapes = list(bar.shapes)
    bar_shapes[0].filter = mod.ShapeFilter(group=1)
    space.add(mod.GrooveJoint(bar, slider, (-90.0, 0.0), (90.0, 0.0), (0.0, 0.0)))
    ball, _ = _ball(mod, space, 1.0, 5.0, (300.0, 100.0))
    g = mod.GrooveJoint(space.static_body, ball, (250.0, 150.0), (350.0, 40.0), (0.0, 0.0))
    g.max_force = 5000.0
    space.add(g)
    # A groove given end-first (the axis points the other way).
    ball2, _ = _ball(mod, space, 1.0, 5.0, (-300.0, 100.0))
    space.add(mod.GrooveJoint(space.static_body, ball2, (-250.0, 20.0), (-350.0, 150.0),
                              (0.0, 2.0)))
    return space


def _soft_force(spring, dist):
    # A nonlinear spring written in Python: both engines call it with the
    # same floats and get the same result.
    stretch = dist - spring.rest_length
    return -spring.stiffness * stretch * (1.0 + 0.001 * abs(stretch))


def _soft_torque(spring, relative_angle):
    return -spring.stiffness * math.sin(relative_angle - spring.rest_angle)


def springs(mod):
    """Damped springs (one clamped by max_force, one with a Python force
    function) and rotary springs (one clamped, one with a Python torque
    function)."""
    space = mod.Space()
    space.gravity = 0, -300
    _ground(mod, space, y=-300.0)
    top = space.static_body
    prev = top
    for i in range(4):
        body, _ = _box(mod, space, 1.0 + 0.5 * i, 20.0, 20.0, (40.0 * i, -60.0 * (i + 1)))
        s = mod.DampedSpring(prev, body, (0.0, 0.0) if prev is top else (0.0, -10.0),
                             (0.0, 10.0), 50.0, 60.0 + 20.0 * i, 0.5 + 0.3 * i)
        if i == 1:
            s.max_force = 150.0
        if i == 3:
            s.force_func = _soft_force
        space.add(s)
        prev = body
    w1, _ = _ball(mod, space, 2.0, 15.0, (200.0, 0.0))
    w2, _ = _ball(mod, space, 1.0, 10.0, (260.0, 0.0))
    w3, _ = _ball(mod, space, 1.0, 10.0, (320.0, 0.0))
    for w in (w1, w2, w3):
        space.add(mod.PivotJoint(space.static_body, w, w.position))
    r1 = mod.DampedRotarySpring(w1, w2, 0.5, 3000.0, 40.0)
    r2 = mod.DampedRotarySpring(w2, w3, -1.0, 8000.0, 10.0)
    r2.max_force = 2000.0
    r3 = mod.DampedRotarySpring(space.static_body, w3, 0.0, 500.0, 5.0)
    r3.torque_func = _soft_torque
    space.add(r1, r2, r3)
    w1.angular_velocity = 6.0
    return space


def motors(mod):
    """A motor-driven wheel geared to a second wheel, a ratchet on a third
    wheel driven back and forth, a rotary limit, a slide joint and a
    kinematic driver pulling a body by a pivot."""
    space = mod.Space()
    space.gravity = 0, -200
    w1, _ = _ball(mod, space, 3.0, 20.0, (0.0, 0.0))
    w2, _ = _ball(mod, space, 1.0, 10.0, (60.0, 0.0))
    w3, _ = _ball(mod, space, 1.0, 12.0, (140.0, 0.0))
    for w in (w1, w2, w3):
        space.add(mod.PivotJoint(space.static_body, w, w.position))
    motor = mod.SimpleMotor(space.static_body, w1, 2.0)
    motor.max_force = 50000.0
    gear = mod.GearJoint(w1, w2, 0.3, 2.0)
    ratchet = mod.RatchetJoint(space.static_body, w3, 0.1, math.pi / 4)
    driver = mod.SimpleMotor(w2, w3, -3.0)
    driver.max_force = 4000.0
    space.add(motor, gear, ratchet, driver)
    arm, _ = _box(mod, space, 1.0, 60.0, 6.0, (0.0, 120.0))
    space.add(mod.PivotJoint(space.static_body, arm, (-30.0, 120.0)))
    space.add(mod.RotaryLimitJoint(space.static_body, arm, -0.5, 0.7))
    hanging, _ = _ball(mod, space, 1.0, 6.0, (30.0, 60.0))
    space.add(mod.SlideJoint(arm, hanging, (30.0, 0.0), (0.0, 0.0), 20.0, 70.0))
    kin = mod.Body(body_type=mod.Body.KINEMATIC)
    kin.position = (-200.0, 0.0)
    kin.velocity = (30.0, 0.0)
    kin.angular_velocity = 0.5
    space.add(kin)
    towed, _ = _box(mod, space, 1.0, 15.0, 15.0, (-240.0, 0.0))
    space.add(mod.PivotJoint(kin, towed, (-20.0, 0.0), (10.0, 0.0)))

    def hook(i):
        # Reverse and change the motors now and then (same calls in both).
        if i % 150 == 75:
            driver.rate = -driver.rate
            motor.rate = motor.rate * -0.75
        if i == 300:
            gear.ratio = -1.5
            gear.phase = 0.0
        if i == 420:
            ratchet.ratchet = -ratchet.ratchet
    space.scene_hook = hook
    return space


def _ragdoll(mod, space, x, y, group):
    """Torso, head, arms and legs on pivot joints with rotary limits; the
    parts of one ragdoll do not collide with each other."""
    f = mod.ShapeFilter(group=group)
    torso, ts = _box(mod, space, 4.0, 20.0, 40.0, (x, y))
    head, hs = _ball(mod, space, 1.0, 9.0, (x, y + 31.0))
    parts = [(torso, ts), (head, hs)]
    neck = mod.PivotJoint(torso, head, (x, y + 21.0))
    space.add(neck, mod.RotaryLimitJoint(torso, head, -0.4, 0.4))
    for side in (-1.0, 1.0):
        arm, s = _box(mod, space, 0.8, 24.0, 6.0, (x + side * 22.0, y + 15.0))
        parts.append((arm, s))
        space.add(mod.PivotJoint(torso, arm, (x + side * 10.0, y + 15.0)),
                  mod.RotaryLimitJoint(torso, arm, -1.2, 1.2))
        leg, s = _box(mod, space, 1.5, 8.0, 30.0, (x + side * 6.0, y - 35.0))
        parts.append((leg, s))
        space.add(mod.PivotJoint(torso, leg, (side * 6.0, -20.0), (0.0, 15.0)),
                  mod.RotaryLimitJoint(torso, leg, -0.8, 0.8))
    for _, s in parts:
        s.filter = f
    return parts


def ragdolls(mod):
    """Three ragdolls dropped onto stairs (joints and contacts together), one
    of them tied to the static body by a slide joint."""
    space = mod.Space()
    space.gravity = 0, -900
    _ground(mod, space, y=-200.0)
    for k in range(5):
        step = mod.Poly.create_box_bb(space.static_body,
                                      mod.BB(-300.0 + 60.0 * k, -200.0, -240.0 + 60.0 * k,
                                             -180.0 + 25.0 * k))
        step.friction = 0.8
        space.add(step)
    dolls = []
    for n, x in enumerate((-250.0, -120.0, 30.0)):
        dolls.append(_ragdoll(mod, space, x, 150.0 + 40.0 * n, n + 1))
    torso = dolls[2][0][0]
    space.add(mod.SlideJoint(space.static_body, torso, (100.0, 300.0), (0.0, 20.0), 0.0, 180.0))
    dolls[0][0][0].angular_velocity = 2.0
    dolls[1][0][0].velocity = (60.0, 0.0)
    return space


def breakable(mod):
    """A bridge of planks on pivot joints; joints whose impulse passes a
    limit are removed between steps, and new joints are added later."""
    space = mod.Space()
    space.gravity = 0, -900
    _ground(mod, space, y=-300.0)
    planks = []
    prev = space.static_body
    for i in range(10):
        plank, _ = _box(mod, space, 1.0, 30.0, 6.0, (-150.0 + 30.0 * i + 15.0, 0.0))
        j = mod.PivotJoint(prev, plank, (-150.0 + 30.0 * i, 0.0))
        j.collide_bodies = False
        space.add(j)
        planks.append(plank)
        prev = plank
    last = mod.PivotJoint(prev, space.static_body, (150.0, 0.0))
    space.add(last)
    for k in range(6):
        _box(mod, space, 3.0, 14.0, 14.0, (-60.0 + 25.0 * k, 40.0 + 20.0 * k))

    def hook(i):
        if i % 10 == 0 and i > 0:
            for c in list(space.constraints):
                if c.impulse * 60.0 > 9000.0:
                    space.remove(c)
        if i == 200:
            # A rope of slide joints catching two planks.
            for p in planks[3:5]:
                space.add(mod.SlideJoint(space.static_body, p, (p.position.x, 150.0),
                                         (0.0, 0.0), 0.0, 160.0))
    space.scene_hook = hook
    return space


def tumbler(mod, size=300):
    """pymunk's benchmark "Tumbler": a square box of four segments spun by
    a motor about a pin at its centre, filled with one small box per step."""
    space = mod.Space()
    space.gravity = 0, -10
    b = mod.Body()
    b.position = 0, 10
    walls = []
    for p, q in (((-10, 10), (10, 10)), ((10, 10), (10, -10)),
                 ((10, -10), (-10, -10)), ((-10, -10), (-10, 10))):
        s = mod.Segment(b, p, q, 0.5)
        s.density = 5
        walls.append(s)
    j1 = mod.SimpleMotor(space.static_body, b, 0.05 * math.pi)
    j2 = mod.PinJoint(space.static_body, b, (0, 10), (0, 0))
    space.add(b, *walls, j1, j2)
    added = [0]

    def hook(i):
        if added[0] < size:
            box = mod.Body()
            box.position = 0, 10
            shape = mod.Poly.create_box(box, (0.25, 0.25))
            shape.density = 1
            space.add(box, shape)
            added[0] += 1
    space.scene_hook = hook
    return space


SCENES = {
    "pin_chain": (pin_chain, 700),
    "pivot_pendulums": (pivot_pendulums, 900),
    "grooves": (grooves, 700),
    "springs": (springs, 800),
    "motors": (motors, 700),
    "ragdolls": (ragdolls, 700),
    "breakable": (breakable, 600),
    "tumbler": (tumbler, 700),
}


# -- the comparison ----------------------------------------------------------------------------

def _state(space, sleeping=False):
    bodies = [(b.position, b.angle, b.velocity, b.angular_velocity)
              + ((b.is_sleeping,) if sleeping else ()) for b in space.bodies]
    joints = [(type(c).__name__, c.impulse) + ((c.angle,) if type(c).__name__ == "RatchetJoint"
                                               else ())
              for c in space.constraints]
    return bodies, joints


def _first_difference(sp, st):
    (bp, jp), (bt, jt) = sp, st
    if len(bp) != len(bt):
        return f"body count {len(bp)} (pymunk) != {len(bt)} (tamias2d)"
    names = ("position", "angle", "velocity", "angular_velocity", "is_sleeping")
    for k, (x, y) in enumerate(zip(bp, bt)):
        if x != y:
            what = [f"{n}: {u!r} != {v!r}" for n, u, v in zip(names, x, y) if u != v]
            return f"body {k}: " + "; ".join(what)
    if len(jp) != len(jt):
        return f"constraint count {len(jp)} (pymunk) != {len(jt)} (tamias2d)"
    for k, (x, y) in enumerate(zip(jp, jt)):
        if x != y:
            return f"constraint {k} ({x[0]}): {x[1:]!r} (pymunk) != {y[1:]!r} (tamias2d)"
    return None


def run_side_by_side(name, build, steps, setup=None, poke=None, sleeping=False):
    sp = build(pymunk)
    st = build(tamias2d)
    if setup is not None:
        setup(sp)
        setup(st)
    hp = getattr(sp, "scene_hook", None)
    ht = getattr(st, "scene_hook", None)
    diff = _first_difference(_state(sp, sleeping), _state(st, sleeping))
    assert diff is None, f"{name}: the scenes differ before the first step: {diff}"
    for i in range(steps):
        if hp is not None:
            hp(i)
            ht(i)
        if poke is not None:
            poke(sp, i)
            poke(st, i)
        sp.step(DT)
        st.step(DT)
        diff = _first_difference(_state(sp, sleeping), _state(st, sleeping))
        if diff is not None:
            pytest.fail(f"{name}: first difference after step {i + 1} (of {steps}): {diff}")
    return sp, st


@pytest.mark.parametrize("name", list(SCENES))
def test_scene_bitwise(name):
    build, steps = SCENES[name]
    sp, st = run_side_by_side(name, build, steps)
    assert len(st.constraints) > 0


def test_every_joint_kind_is_exercised():
    kinds = set()
    for build, _ in SCENES.values():
        kinds.update(type(c).__name__ for c in build(tamias2d).constraints)
    assert kinds == {"PinJoint", "SlideJoint", "PivotJoint", "GrooveJoint", "DampedSpring",
                     "DampedRotarySpring", "RotaryLimitJoint", "RatchetJoint", "GearJoint",
                     "SimpleMotor"}


def test_breakable_scene_really_breaks_and_adds():
    # The breakable scene must remove joints and add new ones, or it tests less
    # than it claims.
    sp, st = run_side_by_side("breakable", breakable, 260)
    kinds = [type(c).__name__ for c in st.constraints]
    assert kinds.count("SlideJoint") == 2
    assert kinds.count("PivotJoint") < 11


@pytest.mark.parametrize("name,poke_at,steps", [("ragdolls", 500, 900), ("pin_chain", 800, 1000),
                                               ("breakable", 500, 900)])
def test_scene_bitwise_sleeping(name, poke_at, steps):
    # Sleeping on: components joined by constraints fall asleep together
    # (their constraints leave the solver's array) and wake together after a
    # poke, which puts the constraints back in a new order.
    build, _ = SCENES[name]

    def setup(space):
        space.sleep_time_threshold = 0.3
        space.idle_speed_threshold = 15.0
        space.damping = 0.3

    slept = []

    def poke(space, i):
        if isinstance(space, tamias2d.Space):
            slept.append(sum(b.is_sleeping for b in space.bodies))
        if i == poke_at:
            bodies = list(space.bodies)
            bodies[len(bodies) // 2].apply_impulse_at_local_point((300, 300))

    run_side_by_side(name + "+sleeping", build, steps, setup=setup, poke=poke, sleeping=True)
    # Something fell asleep before the poke, and the poke woke something.
    assert max(slept[:poke_at]) > 0
    assert slept[poke_at + 1] < slept[poke_at]


def test_scene_bitwise_spatial_hash():
    run_side_by_side("ragdolls+spatial_hash", ragdolls, 400,
                     setup=lambda s: s.use_spatial_hash(40.0, 2000))


def test_changed_solver_parameters():
    # Non-default error_bias, max_bias, max_force and iterations.
    def setup(space):
        space.iterations = 4
        for k, c in enumerate(space.constraints):
            if k % 3 == 0:
                c.error_bias = 0.2
            if k % 3 == 1:
                c.max_bias = 30.0
            if k % 4 == 2:
                c.max_force = 3000.0
    run_side_by_side("ragdolls+parameters", ragdolls, 600, setup=setup)


def test_callbacks_in_both_engines_see_the_same_values():
    # pre_solve / post_solve run in both engines at the same moments and see
    # the same impulses; a pre_solve that changes a joint changes both.
    logs = {}

    def build(mod):
        space = motors(mod)
        log = logs.setdefault(mod.__name__, [])
        for k, c in enumerate(space.constraints):
            def pre(constraint, sp, k=k):
                log.append(("pre", k, constraint.impulse))
                if k == 3 and sp.current_time_step > 0:
                    constraint.max_force = 1000.0 + len(log) % 7

            def post(constraint, sp, k=k):
                log.append(("post", k, constraint.impulse))
            c.pre_solve = pre
            c.post_solve = post
        return space
    sp, st = run_side_by_side("motors+callbacks", build, 200)
    assert logs["pymunk"] == logs["tamias2d"]
    assert len(logs["tamias2d"]) == 200 * 2 * len(st.constraints)


def test_tumbler_larger():
    # Closer to the benchmark's own size (1000 boxes): 500 boxes, one per step.
    run_side_by_side("tumbler_500", lambda mod: tumbler(mod, size=500), 650)


# -- debug drawing of constraints --------------------------------------------------------------

def _recorder(mod):
    class Rec(mod.SpaceDebugDrawOptions):
        def __init__(self):
            super().__init__()
            self.calls = []
            self.flags = self.DRAW_CONSTRAINTS

        def draw_dot(self, size, pos, color):
            self.calls.append(("dot", size, tuple(pos), tuple(color)))

        def draw_segment(self, a, b, color):
            self.calls.append(("segment", tuple(a), tuple(b), tuple(color)))

        def draw_circle(self, *args):
            self.calls.append(("circle",))

        def draw_fat_segment(self, *args):
            self.calls.append(("fat",))

        def draw_polygon(self, *args):
            self.calls.append(("poly",))
    return Rec()


@pytest.mark.parametrize("name", ["springs", "grooves", "motors", "pin_chain"])
def test_debug_draw_constraints_matches_pymunk(name):
    build, _ = SCENES[name]
    sp, st = build(pymunk), build(tamias2d)
    for i in range(30):
        for s in (sp, st):
            hook = getattr(s, "scene_hook", None)
            if hook is not None:
                hook(i)
            s.step(DT)
    for transform in (None, (2.0, 0.5, -0.5, 2.0, 30.0, -40.0)):
        rp, rt = _recorder(pymunk), _recorder(tamias2d)
        if transform is not None:
            rp.transform = pymunk.Transform(*transform)
            rt.transform = tamias2d.Transform(*transform)
        sp.debug_draw(rp)
        st.debug_draw(rt)
        assert rp.calls, "nothing was drawn"
        assert rp.calls == rt.calls


def test_debug_draw_zero_length_spring_skips_nan_segments():
    # A spring whose ends coincide: the zig-zag is NaN; pymunk skips those
    # segments and so must we.
    calls = {}
    for mod in (pymunk, tamias2d):
        s = mod.Space()
        b = mod.Body(1, 3)
        s.add(b, mod.DampedSpring(b, s.static_body, (0, 0), (0, 0), 0, 10, 1))
        s.step(1)
        r = _recorder(mod)
        s.debug_draw(r)
        calls[mod.__name__] = r.calls
    assert calls["pymunk"] == calls["tamias2d"]
    assert [c[0] for c in calls["tamias2d"]] == ["dot", "dot"]
