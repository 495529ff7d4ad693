"""Tests of the Arbiter view and the contact solver behind it.

The base scene is pymunk's test_arbiter one: a dynamic Body(1, 30) with a
Circle of radius 10 at (5, 3) on a static Circle of radius 10 at the origin,
gravity (0, -100), one step of 0.1. Each value is compared with pymunk's
live value with ``==``, and with pymunk's published golden number.
"""
import functools

import pytest

import tamias2d
from tamias2d import Body, Space, Vec2d
from tamias2d.shape import Circle, Poly, Segment

pymunk = pytest.importorskip("pymunk")


def base_scene(mod, dynamic_pos=(5, 3), moment=30, friction=(0.5, 0.8), types=(1, 2)):
    s = mod.Space()
    s.gravity = 0, -100
    b1 = mod.Body(1, moment)
    c1 = mod.Circle(b1, 10)
    b1.position = dynamic_pos
    c1.collision_type = types[0]
    c1.friction = friction[0]
    b2 = mod.Body(body_type=mod.Body.STATIC)
    c2 = mod.Circle(b2, 10)
    c2.collision_type = types[1]
    c2.friction = friction[1]
    s.add(b1, c1, b2, c2)
    return s, b1, c1, b2, c2


def collect(mod, phase, reader, handler=(1, 2), steps=1, **scene):
    s, *objs = base_scene(mod, **scene)
    out = []
    s.on_collision(*handler, **{phase: lambda arb, space, data: out.append(reader(arb))})
    for _ in range(steps):
        s.step(0.1)
    return out


def both(phase, reader, **kw):
    p = collect(pymunk, phase, reader, **kw)
    t = collect(tamias2d, phase, reader, **kw)
    assert p == t
    assert p, "the callback never ran"
    return t


def test_total_impulse():
    (imp,) = both("post_solve", lambda arb: arb.total_impulse)
    assert imp == pytest.approx((3.3936651583, 4.3438914027))


def test_total_ke():
    (ke,) = both("post_solve", lambda arb: arb.total_ke)
    assert ke == pytest.approx(43.438914027)


def test_contact_point_set():
    def read(arb):
        ps = arb.contact_point_set
        return ps.normal, [(p.point_a, p.point_b, p.distance) for p in ps.points]

    ((n, pts),) = both("pre_solve", read, handler=(2, 1))
    assert n == pytest.approx((0.8574929257, 0.5144957554))
    (pa, pb, d), = pts
    assert pa == pytest.approx((8.574929257, 5.144957554))
    assert pb == pytest.approx((-3.574929257, -2.144957554))
    assert d == pytest.approx(-14.16904810)


def test_contact_point_set_setter():
    s, b1, c1, b2, c2 = base_scene(tamias2d)
    out = {}

    def pre_solve(arb, space, data):
        ps = arb.contact_point_set
        ps.normal = Vec2d(1, 0)
        ps.points[0].point_a = Vec2d(9, 10)
        ps.points[0].point_b = Vec2d(-2, -3)
        ps.points[0].distance = -10  # recomputed from the points on read
        arb.contact_point_set = ps
        ps2 = arb.contact_point_set
        out["n"] = ps2.normal
        out["p"] = ps2.points[0]
        ps2.points = ()
        with pytest.raises(ValueError):
            arb.contact_point_set = ps2

    s.on_collision(2, 1, pre_solve=pre_solve)
    s.step(0.1)
    assert out["n"] == (1, 0)
    assert out["p"].point_a == pytest.approx((9, 10))
    assert out["p"].point_b == pytest.approx((-2, -3))
    assert out["p"].distance == pytest.approx(-11)


def test_contact_point_set_setter_two_points():
    # pymunk 7.3 copies point 0 into every slot (a bug); tamias2d sets each
    # point from its own slot.
    s = Space()
    s.add(Segment(s.static_body, (-50, 0), (50, 0), 1))
    b = Body(1, 100)
    b.position = 0, 5.5
    s.add(b, Poly.create_box(b, (10, 10)))
    out = []

    def pre_solve(arb, space, data):
        ps = arb.contact_point_set
        assert len(ps.points) == 2
        ps.points[0].point_a = ps.points[0].point_a + (0, 1)
        ps.points[1].point_b = ps.points[1].point_b + (0, -1)
        arb.contact_point_set = ps
        out.append((ps, arb.contact_point_set))

    s.on_collision(pre_solve=pre_solve)
    s.step(0.01)
    want, got = out[0]
    for w, g in zip(want.points, got.points):
        assert g.point_a == pytest.approx(w.point_a)
        assert g.point_b == pytest.approx(w.point_b)


def test_normal():
    (n,) = both("pre_solve", lambda arb: arb.normal, dynamic_pos=(5, 10))
    assert n == pytest.approx((-0.44721359, -0.89442719))


def test_surface_velocity():
    def build_and_read(mod):
        s = mod.Space()
        s.gravity = 0, -100
        b1 = mod.Body(1, float("inf"))
        c1 = mod.Circle(b1, 10)
        b1.position = 10, 25
        c1.collision_type = 1
        c1.surface_velocity = (3, 0)
        b2 = mod.Body(body_type=mod.Body.STATIC)
        c2 = mod.Circle(b2, 10)
        c2.collision_type = 2
        c2.surface_velocity = (5, 0)
        s.add(b1, c1, b2, c2)
        out = []

        def pre_solve(arb, space, data):
            out.append(arb.surface_velocity)
            arb.surface_velocity = (10, 10)
            out.append(arb.surface_velocity)

        s.on_collision(1, 2, pre_solve=pre_solve)
        for _ in range(5):
            s.step(0.1)
        return out, b1.position, b1.velocity

    p, t = build_and_read(pymunk), build_and_read(tamias2d)
    assert p == t
    assert t[0][0] == pytest.approx((1.38461538462, -0.923076923077))
    assert t[0][1] == (10, 10)


def test_restitution_override():
    def run(mod):
        s = mod.Space()
        s.gravity = 0, -100
        b1 = mod.Body(1, 1)
        c1 = mod.Circle(b1, 10)
        b1.position = 0, 25
        c1.elasticity = 0.6
        b2 = mod.Body(body_type=mod.Body.STATIC)
        c2 = mod.Circle(b2, 10)
        c2.elasticity = 0.3
        s.add(b1, c1, b2, c2)
        seen = []

        def pre_solve(arb, space, data):
            seen.append(arb.restitution)
            arb.restitution = 1

        s.on_collision(pre_solve=pre_solve)
        for _ in range(10):
            s.step(0.1)
        return seen, b1.position

    p, t = run(pymunk), run(tamias2d)
    assert p == t
    assert t[0][0] == pytest.approx(0.18)
    assert t[1].y == pytest.approx(22.42170317, abs=1e-6)


def test_friction_override():
    def run(mod):
        s = mod.Space()
        s.gravity = 0, -100
        b1 = mod.Body(1, float("inf"))
        c1 = mod.Circle(b1, 10)
        b1.position = 10, 25
        c1.friction = 0.6
        b2 = mod.Body(body_type=mod.Body.STATIC)
        c2 = mod.Circle(b2, 10)
        c2.friction = 0.3
        s.add(b1, c1, b2, c2)
        seen = []

        def pre_solve(arb, space, data):
            seen.append(arb.friction)
            arb.friction = 1

        s.on_collision(pre_solve=pre_solve)
        for _ in range(10):
            s.step(0.1)
        return seen, b1.position

    p, t = run(pymunk), run(tamias2d)
    assert p == t
    assert t[0][0] == pytest.approx(0.18)
    assert t[1].x == pytest.approx(10.99450928394)


def test_is_first_contact():
    firsts = both("pre_solve", lambda arb: arb.is_first_contact, steps=3)
    assert firsts == [True, False, False]


def test_is_removal():
    def run(mod):
        s, b1, c1, b2, c2 = base_scene(mod)
        seen = []
        s.on_collision(1, 2, separate=lambda arb, space, data: seen.append(arb.is_removal))
        s.on_collision(1, 2, pre_solve=lambda arb, space, data: seen.append(arb.is_removal))
        s.step(0.1)
        s.remove(c1)
        return seen

    assert run(pymunk) == run(tamias2d) == [False, True]


def test_shapes_and_bodies_follow_the_handler_order():
    for handler, want in (((1, 2), (0, 1)), ((2, 1), (1, 0))):
        s, b1, c1, b2, c2 = base_scene(tamias2d)
        seen = []
        s.on_collision(*handler, begin=lambda arb, space, data: seen.append(
            (arb.shapes, arb.bodies)))
        s.step(0.1)
        shapes, bodies = seen[0]
        expected = [(c1, b1), (c2, b2)]
        assert shapes == (expected[want[0]][0], expected[want[1]][0])
        assert bodies == (expected[want[0]][1], expected[want[1]][1])


# pymunk's testProcessCollision matrix: which callbacks run, and the
# process_collision each one sees, for every pattern of values the
# callbacks set (1 True, 0 False, _ not called).
PROCESS_MATRIX = [
    ("111111", ["b", 1, "p", 1, "t", 1, "p", 1, "t", 1, "s", 1]),
    ("111110", ["b", 1, "p", 1, "t", 1, "p", 1, "t", 1, "s", 1]),
    ("111100", ["b", 1, "p", 1, "t", 1, "p", 1, "t", 1, "s", 0]),
    ("11100_", ["b", 1, "p", 1, "t", 1, "p", 1, "s", 0]),
    ("11000_", ["b", 1, "p", 1, "t", 1, "p", 0, "s", 0]),
    ("1000__", ["b", 1, "p", 1, "p", 0, "s", 0]),
    ("0000__", ["b", 1, "p", 0, "p", 0, "s", 0]),
    ("011111", ["b", 1, "p", 0, "t", 1, "p", 1, "t", 1, "s", 1]),
    ("00111_", ["b", 1, "p", 0, "p", 0, "t", 1, "s", 1]),
    ("0001__", ["b", 1, "p", 0, "p", 0, "s", 0]),
    ("10100_", ["b", 1, "p", 1, "p", 0, "t", 1, "s", 0]),
    ("010101", ["b", 1, "p", 0, "t", 1, "p", 0, "t", 1, "s", 0]),
]


@pytest.mark.parametrize("values, expected", PROCESS_MATRIX)
def test_process_collision_matrix(values, expected):
    def run(mod):
        s, b1, *_ = base_scene(mod)
        to_set = [bit == "1" for bit in values if bit in "01"]
        calls = []

        def callback(name, arb, space, data):
            calls.append((name, bool(arb.process_collision)))
            arb.process_collision = to_set.pop(0)

        s.on_collision(1, 2, **{phase: functools.partial(callback, phase[0] if phase != "post_solve" else "t")
                                for phase in ("begin", "pre_solve", "post_solve", "separate")})
        s.step(0.1)
        s.step(0.1)
        b1.position = 100, 100
        s.step(0.1)
        return calls

    want = [(n, bool(v)) for n, v in zip(expected[::2], expected[1::2])]
    assert run(tamias2d) == want
    assert run(pymunk) == want


def test_arbiter_in_each_arbiter_sees_the_body_first():
    s = Space()
    s.gravity = 0, -100
    b = Body(1, 10)
    c = Circle(b, 5)
    ground = Circle(s.static_body, 5)
    s.add(b, c, ground)
    s.step(0.01)
    seen = []
    b.each_arbiter(lambda arb: seen.append(arb.shapes))
    s.static_body.each_arbiter(lambda arb: seen.append(arb.shapes))
    assert seen == [(c, ground), (ground, c)]


def test_values_outside_the_step():
    # After the step the arbiters are still live until the next one: pymunk
    # allows reading them through each_arbiter.
    s, b1, c1, b2, c2 = base_scene(tamias2d)
    s.step(0.1)
    got = []
    b1.each_arbiter(lambda arb: got.append((arb.total_impulse, arb.total_ke,
                                            arb.is_first_contact, arb.restitution)))
    assert got[0][0] == pytest.approx((3.3936651583, 4.3438914027))
    assert got[0][2] is True


@pytest.mark.parametrize("solver", ["chipmunk", "soft"])
@pytest.mark.parametrize("change", ["handler", "wildcard", "collision_type"])
def test_a_handler_added_or_a_type_changed_mid_contact_takes_effect(solver, change):
    # An arbiter keeps the handlers it looked up while the types and the
    # space's handlers stay the same; a handler added while the pair is in
    # contact, or a new collision type, must be found at the next step (and
    # pymunk's solver calls it there too).
    results = {}
    for mod in (tamias2d, pymunk):
        if mod is pymunk and solver == "soft":
            continue
        s = mod.Space()
        s.gravity = 0, -100
        if mod is tamias2d:
            s.solver = solver
        ground = mod.Segment(s.static_body, (-100, 0), (100, 0), 1)
        ground.collision_type = 1
        body = mod.Body(1, 100)
        body.position = 0, 10.5
        ball = mod.Circle(body, 10)
        ball.collision_type = 2
        s.add(ground, body, ball)
        calls = []
        for i in range(20):
            if i == 10:
                if change == "handler":
                    s.on_collision(1, 2, pre_solve=lambda arb, space, data: calls.append(i))
                elif change == "wildcard":
                    s.on_collision(2, None, pre_solve=lambda arb, space, data: calls.append(i))
                else:
                    s.on_collision(1, 3, pre_solve=lambda arb, space, data: calls.append(i))
                    ball.collision_type = 3
            s.step(1 / 60)
        results[mod.__name__] = calls
    assert results["tamias2d"] == list(range(10, 20))
    if "pymunk" in results:
        assert results["pymunk"] == results["tamias2d"]
