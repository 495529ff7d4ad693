"""Cross-validation of the space against pymunk 7.3, step by step, bit for bit.

Each scene of tests/scenes.py is built in both engines (same construction
order) and stepped side by side; after every step every body's position,
angle, velocity and angular velocity must be equal with ``==``. A failure
names the first step and body where the engines part.

Collision callbacks are cross-checked too: the sequence of (phase, handler,
shapes, first contact, normal, contact points) must match. Separate
callbacks of one step are compared as a sorted list: Munk2D visits its
arbiter cache in pointer-hash order, which differs between processes (and
between the engines), so only their set per step is defined.
"""
import functools
import importlib
import types

import pytest

pymunk = pytest.importorskip("pymunk")
import tamias2d

import scenes

_NAMES = ("Space", "Body", "Circle", "Segment", "Poly", "Transform", "Vec2d",
          "ShapeFilter", "moment_for_box", "moment_for_circle")


def _engine():
    """tamias2d, or a view of it that also finds names its modules define
    but the package does not export yet."""
    if all(hasattr(tamias2d, n) for n in _NAMES):
        return tamias2d
    shape_module = importlib.import_module("tamias2d.shape")
    ns = types.SimpleNamespace()
    for n in _NAMES:
        for m in (tamias2d, shape_module):
            if hasattr(m, n):
                setattr(ns, n, getattr(m, n))
                break
    return ns


T = _engine()


def _state(space):
    return [(b.position, b.angle, b.velocity, b.angular_velocity) for b in space.bodies]


def _first_difference(a, b):
    if len(a) != len(b):
        return f"body count {len(a)} (pymunk) != {len(b)} (tamias2d)"
    for k, (x, y) in enumerate(zip(a, b)):
        if x != y:
            names = ("position", "angle", "velocity", "angular_velocity", "is_sleeping")
            what = [f"{n}: {u!r} != {v!r}" for n, u, v in zip(names, x, y) if u != v]
            return f"body {k}: " + "; ".join(what)
    return None


def _state_sleeping(space):
    return [(b.position, b.angle, b.velocity, b.angular_velocity, b.is_sleeping)
            for b in space.bodies]


def run_side_by_side(name, build, dt, steps, setup=None, poke=None, state=_state):
    sp = build(pymunk)
    st = build(T)
    if setup is not None:
        setup(sp)
        setup(st)
    hp = getattr(sp, "scene_hook", None)
    ht = getattr(st, "scene_hook", None)
    assert state(sp) == state(st), f"{name}: the scenes differ before the first step"
    for i in range(steps):
        if hp is not None:
            hp(i)
            ht(i)
        if poke is not None:
            poke(sp, i)
            poke(st, i)
        sp.step(dt)
        st.step(dt)
        diff = _first_difference(state(sp), state(st))
        if diff is not None:
            pytest.fail(f"{name}: first difference after step {i + 1} (of {steps}): {diff}")
    return sp, st


@pytest.mark.parametrize("name", list(scenes.SCENES))
def test_scene_bitwise(name):
    sc = scenes.SCENES[name]
    run_side_by_side(name, sc.build, sc.dt, sc.steps)


@pytest.mark.parametrize("name", ["rain_520", "add_remove", "drum"])
def test_scene_bitwise_spatial_hash(name):
    sc = scenes.SCENES[name]
    run_side_by_side(name + "+spatial_hash", sc.build, sc.dt, sc.steps,
                     setup=lambda s: s.use_spatial_hash(25.0, 5000))


@pytest.mark.parametrize("name", ["circles_on_segment", "vertical_stack_10", "mixed",
                                  "add_remove", "type_changes"])
def test_scene_bitwise_sleeping(name):
    # Sleeping on: components fall asleep, a poke at step 450 wakes one.
    sc = scenes.SCENES[name]

    def setup(space):
        space.sleep_time_threshold = 0.3

    def poke(space, i):
        if i == 450:
            bodies = list(space.bodies)
            bodies[len(bodies) // 2].apply_impulse_at_local_point((40, 40))

    sp, st = run_side_by_side(name + "+sleeping", sc.build, sc.dt, 900, setup=setup,
                              poke=poke, state=_state_sleeping)
    assert any(b.is_sleeping for b in st.bodies)


def test_two_circles_golden():
    # pymunk's test_arbiter base scene; golden numbers from its test suite.
    def build(mod):
        s = mod.Space()
        s.gravity = 0, -100
        b1 = mod.Body(1, 30)
        c1 = mod.Circle(b1, 10)
        b1.position = 5, 3
        c1.friction = 0.5
        b2 = mod.Body(body_type=mod.Body.STATIC)
        c2 = mod.Circle(b2, 10)
        c2.friction = 0.8
        s.add(b1, c1, b2, c2)
        return s
    run_side_by_side("two_circles", build, 0.1, 50)


def _arbiter_record(arb, index):
    ps = arb.contact_point_set
    return (
        tuple(index[s] for s in arb.shapes),
        arb.normal,
        tuple((p.point_a, p.point_b, p.distance) for p in ps.points),
        arb.total_impulse,
        arb.total_ke,
        arb.is_first_contact,
        arb.friction,
        arb.restitution,
        arb.surface_velocity,
    )


def test_each_arbiter_order_on_settled_pyramid():
    sp, st = run_side_by_side("pyramid_10", functools.partial(scenes.pyramid, rows=10),
                              1.0 / 60.0, 240)

    def records(space):
        index = {s: i for i, s in enumerate(space.shapes)}
        index[None] = -1
        out = []
        for body in space.bodies:
            per_body = []
            body.each_arbiter(lambda arb: per_body.append(_arbiter_record(arb, index)))
            out.append(per_body)
        return out

    rp, rt = records(sp), records(st)
    assert sum(len(r) for r in rp) > 50
    for k, (a, b) in enumerate(zip(rp, rt)):
        assert a == b, f"each_arbiter of body {k} differs"
    assert rp == rt


# -- collision handlers ------------------------------------------------------------------

def _handler_scene(mod, log):
    s = mod.Space()
    s.gravity = 0, -400
    index = {}

    def add_shape(shape):
        index[shape] = len(index)
        s.add(shape)

    floor = mod.Segment(s.static_body, (-300, 0), (300, 0), 4)
    floor.collision_type = 2
    floor.friction = 0.8
    add_shape(floor)
    ramp = mod.Segment(s.static_body, (-300, 120), (-80, 60), 4)
    ramp.collision_type = 3
    ramp.friction = 0.2
    add_shape(ramp)

    for i in range(14):
        body = mod.Body(1.0, scenes.box_moment(1.0, 16, 16))
        body.position = -250 + 36 * i, 160 + 25 * (i % 4)
        s.add(body)
        if i % 3 == 0:
            shape = mod.Circle(body, 8)
        elif i % 3 == 1:
            shape = mod.Poly.create_box(body, (16, 16), 1)
        else:
            shape = mod.Segment(body, (-10, 0), (10, 0), 4)
        shape.collision_type = (1, 2, 3, 4)[i % 4]
        shape.friction = 0.5
        shape.elasticity = 0.3
        add_shape(shape)

    step = [0]

    def record(phase, key, arb, space, data):
        # pymunk refuses contact_point_set without contacts (separate).
        points = () if phase == "separate" else tuple(
            (p.point_a, p.point_b, p.distance) for p in arb.contact_point_set.points)
        log.append((
            step[0], phase, key, data,
            tuple(index[x] for x in arb.shapes),
            arb.is_first_contact, arb.is_removal,
            arb.normal,
            points,
            arb.process_collision,
        ))
        a, b = (index[x] for x in arb.shapes)
        if phase == "pre_solve" and key == (1, None) and (a + b) % 5 == 0:
            arb.process_collision = False
        if phase == "pre_solve" and key == (None, None):
            arb.friction = arb.friction * 0.5
            arb.surface_velocity = (3.0, 0.0)
            if (a * b) % 7 == 1:
                arb.restitution = 0.9
        if phase == "post_solve" and key == (2, None):
            log.append(("impulse", arb.total_impulse, arb.total_ke))

    for key in [(1, 2), (2, 1), (1, None), (2, None), (None, None), (3, 3), (3, None), (4, 1)]:
        s.on_collision(
            key[0], key[1],
            begin=functools.partial(record, "begin", key),
            pre_solve=functools.partial(record, "pre_solve", key),
            post_solve=functools.partial(record, "post_solve", key),
            separate=functools.partial(record, "separate", key),
            data=str(key),
        )
    s.step_counter = step
    return s


def _split_separates(log):
    """Keep begin/pre/post in order; sort the separates of each step."""
    ordered, separates = [], {}
    for entry in log:
        if entry[0] != "impulse" and entry[1] == "separate":
            separates.setdefault(entry[0], []).append(entry)
        else:
            ordered.append(entry)
    return ordered, {k: sorted(v, key=repr) for k, v in separates.items()}


def test_collision_handler_sequences():
    log_p, log_t = [], []
    sp = _handler_scene(pymunk, log_p)
    st = _handler_scene(T, log_t)
    for i in range(300):
        sp.step_counter[0] = st.step_counter[0] = i
        sp.step(1.0 / 60.0)
        st.step(1.0 / 60.0)
        diff = _first_difference(_state(sp), _state(st))
        if diff is not None:
            pytest.fail(f"handler scene: first difference after step {i + 1}: {diff}")
    # Shape removal calls separate outside the step.
    for s in (sp, st):
        s.step_counter[0] = "removal"
        s.remove(*list(s.shapes)[:6])
    phases = {e[1] for e in log_p if e[0] != "impulse"}
    assert phases == {"begin", "pre_solve", "post_solve", "separate"}
    assert len(log_p) > 1000
    op, sepp = _split_separates(log_p)
    ot, sept = _split_separates(log_t)
    for k, (a, b) in enumerate(zip(op, ot)):
        assert a == b, f"callback {k} differs:\npymunk   {a}\ntamias2d {b}"
    assert len(op) == len(ot)
    assert sepp == sept


def test_collision_handler_order_pymunk_case():
    # pymunk's testCollisionHandlerOrder, run in both engines.
    def build(mod, calls):
        s = mod.Space()

        def callback(name, types, arb, space, data):
            calls.append((name, types, (arb.shapes[0].collision_type,
                                        arb.shapes[1].collision_type)))

        for t1, t2 in [(1, 2), (2, 1), (1, None), (2, None), (None, None)]:
            s.on_collision(t1, t2,
                           begin=functools.partial(callback, "begin", (t1, t2)),
                           pre_solve=functools.partial(callback, "pre_solve", (t1, t2)),
                           post_solve=functools.partial(callback, "post_solve", (t1, t2)),
                           separate=functools.partial(callback, "separate", (t1, t2)))
        b1 = mod.Body(1, 30)
        c1 = mod.Circle(b1, 10)
        b1.position = 5, 3
        c1.collision_type = 2
        b2 = mod.Body(body_type=mod.Body.STATIC)
        c2 = mod.Circle(b2, 10)
        c2.collision_type = 1
        s.add(b1, c1, b2, c2)
        s.step(0.1)
        b1.position = 100, 100
        s.step(0.1)

    cp, ct = [], []
    build(pymunk, cp)
    build(T, ct)
    assert len(cp) == 20
    assert cp == ct


def test_queries_match_pymunk():
    # Every query on a settled mixed scene (dynamic and static shapes,
    # several kinds): same shapes in the same order, same numbers.
    sc = scenes.SCENES["mixed"]
    sp, st = run_side_by_side("mixed", sc.build, sc.dt, 200)
    ip = {s: i for i, s in enumerate(sp.shapes)}
    it = {s: i for i, s in enumerate(st.shapes)}
    for space, mod in ((sp, pymunk), (st, T)):
        space.add(mod.Segment(space.static_body, (-50, 300), (50, 300), 1))  # static, far

    def norm(result, index):
        if result is None:
            return None
        if isinstance(result, list):
            return [norm(r, index) for r in result]
        if hasattr(result, "contact_point_set"):
            ps = result.contact_point_set
            return (index.get(result.shape, "new"), ps.normal,
                    [(p.point_a, p.point_b, p.distance) for p in ps.points])
        if hasattr(result, "shape"):
            return (index.get(result.shape, "new"),) + tuple(result)[1:]
        return index.get(result, "new")

    def queries(space, mod):
        f = mod.ShapeFilter()
        f2 = mod.ShapeFilter(categories=1, mask=1)
        out = []
        for x in range(-400, 401, 40):
            for y in (-10, 0, 20, 60, 150, 300):
                out.append(space.point_query((x, y), 15, f))
                out.append(space.point_query_nearest((x, y), 40, f))
                out.append(space.point_query((x, y), 0, f2))
        for y in (5, 15, 30, 60, 300):
            out.append(space.segment_query((-420, y), (420, y + 30), 0, f))
            out.append(space.segment_query((-420, y), (420, y + 30), 6, f))
            out.append(space.segment_query_first((-420, y), (420, y + 30), 0, f))
            out.append(space.segment_query_first((420, y), (-420, y - 30), 6, f))
        for l in range(-400, 400, 80):
            out.append(space.bb_query(mod.BB(l, -20, l + 120, 80), f))
        probe_body = mod.Body(body_type=mod.Body.KINEMATIC)
        for pos in ((0, 10), (-200, 60), (250, 90)):
            probe_body.position = pos
            out.append(space.shape_query(mod.Circle(probe_body, 30)))
            out.append(space.shape_query(mod.Poly.create_box(probe_body, (80, 20))))
        return out

    qp = [norm(r, ip) for r in queries(sp, pymunk)]
    qt = [norm(r, it) for r in queries(st, T)]
    assert sum(bool(q) for q in qp) > 50
    for k, (a, b) in enumerate(zip(qp, qt)):
        assert a == b, f"query {k} differs"
    assert len(qp) == len(qt)
