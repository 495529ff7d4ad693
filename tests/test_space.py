"""Tests of the Space module: properties, adding and removing, the step's
checks, deferred changes, post-step callbacks, errors in callbacks,
reindexing, debug drawing and the life cycle of a space.

Numbers are compared with pymunk 7.3 where it defines them; where tamias2d
deliberately differs (a clear exception where pymunk would go on with a NaN
state), the test says so.
"""
import doctest
import gc
import math
import threading
import time
import weakref

import pytest

import tamias2d
import tamias2d.arbiter
import tamias2d.space
from tamias2d import Body, Space
from tamias2d.errors import (AlreadyInSpace, IllegalBody, IllegalShape, NotInSpace,
                             SpaceLocked, Tamias2DError)
from tamias2d.shape import Circle, Poly, Segment

pymunk = pytest.importorskip("pymunk")


def _two_circles(space_cls=Space, body_cls=Body, circle_cls=Circle):
    s = space_cls()
    b = body_cls(1, 10)
    c = circle_cls(b, 5)
    s.add(b, c, circle_cls(s.static_body, 5))
    return s, b, c


# -- doctests ------------------------------------------------------------------------

@pytest.mark.parametrize("module", [tamias2d.space, tamias2d.arbiter])
def test_doctests(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 20
    assert result.failed == 0


# -- properties -----------------------------------------------------------------------

def test_defaults_match_pymunk():
    s, p = Space(), pymunk.Space()
    for name in ("iterations", "gravity", "damping", "idle_speed_threshold",
                 "sleep_time_threshold", "collision_slop", "collision_bias",
                 "collision_persistence", "current_time_step", "threads"):
        assert getattr(s, name) == getattr(p, name), name
    # The float-literal constants of Munk2D, to the bit.
    assert s.collision_slop == 0.10000000149011612
    assert s.collision_bias == 0.0017970074436457143


def test_property_round_trips():
    s = Space()
    s.iterations = 15
    s.gravity = (10, 2)
    s.damping = 0.5
    s.idle_speed_threshold = 4
    s.sleep_time_threshold = 5
    s.collision_slop = 6
    s.collision_bias = 0.2
    s.collision_persistence = 9
    assert (s.iterations, s.gravity, s.damping, s.idle_speed_threshold) == (15, (10, 2), 0.5, 4)
    assert (s.sleep_time_threshold, s.collision_slop, s.collision_bias) == (5, 6, 0.2)
    assert s.collision_persistence == 9
    assert isinstance(s.gravity, tamias2d.Vec2d)


@pytest.mark.parametrize("name, value, exc", [
    ("iterations", 0, ValueError),
    ("iterations", -3, ValueError),
    ("iterations", "x", TypeError),
    ("damping", -0.1, ValueError),
    ("damping", math.nan, ValueError),
    ("damping", math.inf, ValueError),
    ("gravity", (math.nan, 0), ValueError),
    ("gravity", (1, 2, 3), (ValueError, TypeError)),
    ("collision_persistence", -1, ValueError),
    ("collision_persistence", 2.5, ValueError),
])
def test_bad_property_values(name, value, exc):
    s = Space()
    before = getattr(s, name)
    with pytest.raises(exc):
        setattr(s, name, value)
    assert getattr(s, name) == before


def test_threads_as_pymunk_but_one_solver_thread():
    # pymunk's threaded space keeps the count asked (0 -> 1, at most 2); a
    # space that is not threaded stays at 1. tamias2d solves on one thread
    # whatever the count, so the motion is the same.
    s = Space(threaded=True)
    for asked, kept in ((2, 2), (5, 2), (0, 1), (1, 1), (2, 2)):
        s.threads = asked
        assert s.threads == kept
    plain = Space()
    plain.threads = 2
    assert plain.threads == 1
    for space in (s, plain):
        space.gravity = 0, -100
        b = Body(1, 10)
        space.add(b, Circle(b, 1), Segment(space.static_body, (-10, -1), (10, -1), 0.5))
        for _ in range(30):
            space.step(0.02)
    assert list(s.bodies)[0].position == list(plain.bodies)[0].position


def test_static_body():
    s = Space()
    sb = s.static_body
    assert sb is s.static_body
    assert sb.body_type == Body.STATIC
    assert sb.space is s
    assert len(s.bodies) == 0


def test_current_time_step_and_zero_dt():
    s, b, _ = _two_circles()
    s.gravity = 0, -10
    s.step(0.25)
    assert s.current_time_step == 0.25
    pos, vel = b.position, b.velocity
    s.step(0)  # returns at once, as Munk2D does
    assert s.current_time_step == 0.25
    assert (b.position, b.velocity) == (pos, vel)


@pytest.mark.parametrize("dt", [math.inf, -math.inf, math.nan])
def test_step_rejects_non_finite_dt(dt):
    s, b, _ = _two_circles()
    with pytest.raises(ValueError):
        s.step(dt)
    assert b.position == (0, 0)
    s.step(0.01)


# -- adding and removing ---------------------------------------------------------------

def test_add_remove_views_keep_insertion_order():
    s = Space()
    bodies = [Body(1, 2) for _ in range(5)]
    shapes = [Circle(b, 3) for b in bodies]
    s.add(*shapes[::-1], *bodies)  # shapes before their bodies: fine
    assert list(s.bodies) == bodies
    assert list(s.shapes) == shapes[::-1]
    view = s.shapes
    s.remove(shapes[2], bodies[2])
    assert shapes[2] not in view and len(view) == 4
    assert shapes[2].space is None and bodies[2].space is None
    s.add(bodies[2], shapes[2])
    assert list(s.bodies)[-1] is bodies[2]


def test_add_errors():
    s1, s2 = Space(), Space()
    b = Body(1, 2)
    c = Circle(b, 1)
    s1.add(b, c)
    with pytest.raises(AlreadyInSpace):
        s1.add(c)
    with pytest.raises(AlreadyInSpace):
        s2.add(c)
    with pytest.raises(AlreadyInSpace):
        s1.add(b)
    with pytest.raises(AlreadyInSpace):
        s2.add(b)
    with pytest.raises(AlreadyInSpace):
        s2.add(s1.static_body)
    with pytest.raises(IllegalShape):
        s1.add(Circle(None, 1))
    loose = Circle(Body(1, 1), 1)
    with pytest.raises(NotInSpace):
        s1.add(loose)
    with pytest.raises(TypeError):
        s1.add("not a body")
    # pymunk raises AssertionError for these; the tamias2d errors are also
    # AssertionErrors so code written for pymunk keeps working.
    with pytest.raises(AssertionError):
        s2.add(c)
    assert list(s1.shapes) == [c] and list(s2.shapes) == []


def test_remove_errors():
    s = Space()
    b = Body(1, 2)
    c = Circle(b, 1)
    with pytest.raises(NotInSpace):
        s.remove(b)
    with pytest.raises(NotInSpace):
        s.remove(c)
    s.add(b, c)
    s.remove(c)
    with pytest.raises(NotInSpace):
        s.remove(c)
    with pytest.raises(TypeError):
        s.remove(42)


def test_shape_hash_ids_are_never_reused():
    # Munk2D's counter: the broad phase order depends on it, so removing and
    # re-adding must behave as in pymunk.
    def build(mod):
        s = mod.Space()
        s.gravity = 0, -100
        bodies = []
        for i in range(6):
            b = mod.Body(1, 10)
            b.position = i * 7, i * 11
            s.add(b, mod.Circle(b, 6))
            bodies.append(b)
        s.add(mod.Segment(s.static_body, (-100, -20), (100, -20), 5))
        return s, bodies

    sp, bp = build(pymunk)
    st, bt = build(tamias2d)
    for s, bodies in ((sp, bp), (st, bt)):
        for _ in range(20):
            s.step(0.02)
        shape = next(iter(bodies[2].shapes))
        s.remove(shape)
        s.add(shape)
        for _ in range(60):
            s.step(0.02)
    assert [b.position for b in bp] == [b.position for b in bt]


def test_dynamic_body_checks_before_step():
    s = Space()
    b = Body()  # mass 0, moment 0
    s.add(b)
    with pytest.raises(IllegalBody, match="mass > 0"):
        s.step(0.1)
    with pytest.raises(AssertionError):  # pymunk's exception type
        s.step(0.1)
    c = Circle(b, 1)
    c.mass = 2
    s.add(c)
    s.step(0.1)
    # Unlike pymunk (which checks only newly added bodies), every dynamic
    # body is checked at every step, so a body turned dynamic without mass
    # is caught instead of producing NaN.
    k = Body(body_type=Body.KINEMATIC)
    s.add(k)
    s.step(0.1)
    k.body_type = Body.DYNAMIC
    with pytest.raises(IllegalBody):
        s.step(0.1)


# -- deferred add/remove and post-step callbacks ------------------------------------------

def test_add_and_remove_inside_callbacks_are_deferred():
    s, b1, c1 = _two_circles()
    extra = [Body(1, 2) for _ in range(3)]
    shapes = [Circle(b, 1) for b in extra]

    def pre_solve(arb, space, data):
        space.add(shapes[1], extra[1], extra[0], shapes[0])
        assert extra[0] not in space.bodies
        space.remove(c1)
        assert c1 in space.shapes

    s.on_collision(pre_solve=pre_solve)
    s.step(0.01)
    # Applied in the order given (pymunk uses a set here: order unspecified).
    assert list(s.bodies)[1:] == [extra[1], extra[0]]
    assert list(s.shapes)[-2:] == [shapes[1], shapes[0]]
    assert c1 not in s.shapes and c1.space is None


def test_removal_in_separate_outside_step_is_deferred():
    s = Space()
    shape1 = Circle(s.static_body, 1)
    shape1.collision_type = 1
    body2 = Body(1, 1)
    shape2 = Circle(body2, 1)
    s.add(shape1, body2, shape2)
    order = []

    def separate(arb, space, data):
        order.append("separate")
        space.remove(shape2, body2)
        assert shape2 in space.shapes  # deferred until remove() returns

    s.on_collision(1, None, separate=separate)
    s.step(0.1)
    s.remove(shape1)
    assert order == ["separate"]
    assert len(s.shapes) == 0 and len(s.bodies) == 0


def test_post_step_callbacks():
    s = Space()
    calls = []

    def cb(space, key, *args, **kwargs):
        calls.append((space, key, args, kwargs))

    assert s.add_post_step_callback(cb, "k", 1, 2, x=3) is True
    assert s.add_post_step_callback(cb, "k") is False
    assert s.add_post_step_callback(cb, "other") is True
    assert calls == []
    s.step(0.1)
    assert calls == [(s, "k", (1, 2), {"x": 3}), (s, "other", (), {})]
    s.step(0.1)
    assert len(calls) == 2


def test_post_step_callback_removing_touching_shapes():
    # pymunk's testPostStepCallback
    s = Space()
    b1, b2 = Body(1, 3), Body(10, 100)
    s.add(b1, b2)
    b1.position = 10, 0
    b2.position = 20, 0
    s1, s2 = Circle(b1, 5), Circle(b2, 10)
    s.add(s1, s2)
    calls = []

    def callback(space, key, shapes):
        for shape in shapes:
            space.remove(shape)
        calls.append(key)

    def pre_solve(arb, space, data):
        space.add_post_step_callback(callback, 0, arb.shapes)

    s.on_collision(0, 0, pre_solve=pre_solve)
    s.step(0.1)
    assert len(s.shapes) == 0 and calls == [0]
    s.step(0.1)
    assert calls == [0]


# -- exceptions in callbacks ------------------------------------------------------------------

class Boom(Exception):
    pass


@pytest.mark.parametrize("phase", ["begin", "pre_solve", "post_solve", "separate"])
def test_exception_in_collision_callback_is_raised_after_the_step(phase):
    s, b, c = _two_circles()
    s.gravity = 0, -10
    seen = []

    def bad(arb, space, data):
        seen.append(phase)
        raise Boom(phase)

    s.on_collision(**{phase: bad})
    with pytest.raises(Boom):
        for _ in range(3):
            s.step(0.01)
            if phase == "separate" and len(seen) == 0:
                b.position = 100, 100
    # The step finished and the space is consistent: it keeps stepping.
    assert s.current_time_step == 0.01
    s.on_collision(**{phase: tamias2d.empty_callback})
    for _ in range(5):
        s.step(0.01)
    assert all(math.isfinite(v) for v in b.position)


def test_first_callback_error_wins_and_others_still_run():
    s = Space()
    for i in range(3):
        b = Body(1, 10)
        b.position = 30 * i, 0
        s.add(b, Circle(b, 5), Circle(s.static_body, 5, (30 * i, 0)))
    errors = []

    def bad(arb, space, data):
        errors.append(len(errors))
        raise Boom(len(errors))

    s.on_collision(begin=bad)
    with pytest.raises(Boom) as info:
        s.step(0.01)
    assert len(errors) == 3
    assert info.value.args == (1,)
    s.step(0.01)  # no error stored any more


def test_exception_in_integrator_and_post_step():
    s, b, _ = _two_circles()

    def bad_velocity(body, gravity, damping, dt):
        raise Boom("velocity")

    b.velocity_func = bad_velocity
    with pytest.raises(Boom, match="velocity"):
        s.step(0.01)
    b.velocity_func = Body.update_velocity
    s.step(0.01)

    def bad_post(space, key):
        raise Boom("post")

    s.add_post_step_callback(bad_post, 1)
    with pytest.raises(Boom, match="post"):
        s.step(0.01)
    s.step(0.01)


def test_exception_in_separate_during_remove():
    s, b, c = _two_circles()
    s.step(0.01)

    def bad(arb, space, data):
        raise Boom("separate")

    s.on_collision(separate=bad)
    with pytest.raises(Boom):
        s.remove(c)
    assert c not in s.shapes and c.space is None
    s.step(0.01)


def test_step_inside_a_callback_is_refused():
    s, b, c = _two_circles()
    s.on_collision(pre_solve=lambda arb, space, data: space.step(0.01))
    with pytest.raises(SpaceLocked):
        s.step(0.01)


# -- collision handlers -----------------------------------------------------------------------

def test_on_collision_rules():
    s = Space()
    with pytest.raises(ValueError):
        s.on_collision(None, 1)
    with pytest.raises(AssertionError):  # pymunk asserts here
        s.on_collision(None, 1)
    with pytest.raises(TypeError):
        s.on_collision(1, 2, begin=3)
    f = lambda *a: None
    s.on_collision(1, 2, begin=f, data="d")
    h = s._handlers[(1, 2)]
    assert h.begin is f and h.pre_solve is None and h.data == {"begin": "d"}
    s.on_collision(1, 2, pre_solve=f)
    assert h.begin is f and h.pre_solve is f
    s.on_collision(1, 2, begin=tamias2d.empty_callback)
    assert h.begin is None and h.pre_solve is f


def test_data_is_passed_per_phase():
    s, b, c = _two_circles()
    got = []
    s.on_collision(begin=lambda a, sp, d: got.append(d), data=1)
    s.on_collision(pre_solve=lambda a, sp, d: got.append(d), data=2)
    s.step(0.01)
    assert got == [1, 2]


def test_process_collision_false_lets_shapes_pass():
    s, b, c = _two_circles()
    s.gravity = 0, -100
    b.position = 0, 9

    def begin(arb, space, data):
        arb.process_collision = False

    s.on_collision(begin=begin)
    for _ in range(100):
        s.step(0.01)
    assert b.position.y < -30  # fell through the static circle


# -- arbiter views -------------------------------------------------------------------------

def test_stale_arbiter_view_raises_instead_of_reading_garbage():
    s, b, c = _two_circles()
    kept = []
    s.on_collision(pre_solve=lambda arb, space, data: kept.append(arb))
    s.step(0.01)
    arb = kept[-1]
    assert len(arb.shapes) == 2  # still the live arbiter
    b.position = 1000, 0
    for _ in range(5):
        s.step(0.01)  # separated and expired: the arbiter goes back to the pool
    with pytest.raises(Tamias2DError, match="no longer valid"):
        arb.shapes
    with pytest.raises(TypeError):
        tamias2d.Arbiter()


def test_removed_shape_arbiter_view_raises():
    s, b, c = _two_circles()
    kept = []
    s.on_collision(pre_solve=lambda arb, space, data: kept.append(arb))
    s.step(0.01)
    s.remove(c)
    del c
    gc.collect()
    with pytest.raises(Tamias2DError):
        kept[0].normal


# -- sleeping (ported with the components code) ------------------------------------------------

def test_sleeping_matches_pymunk():
    def build(mod):
        s = mod.Space()
        s.gravity = 0, -100
        s.sleep_time_threshold = 0.3
        s.add(mod.Segment(s.static_body, (-100, 0), (100, 0), 2))
        bodies = []
        for i in range(5):
            b = mod.Body(1, 100)
            b.position = 0, 12 + 21 * i
            s.add(b, mod.Poly.create_box(b, (20, 20)))
            bodies.append(b)
        return s, bodies

    (sp, bp), (st, bt) = build(pymunk), build(tamias2d)
    for i in range(400):
        for s, bodies in ((sp, bp), (st, bt)):
            if i == 250:
                bodies[2].apply_impulse_at_local_point((0, 300))
            s.step(1 / 60)
        assert [(b.position, b.velocity, b.is_sleeping) for b in bp] == \
               [(b.position, b.velocity, b.is_sleeping) for b in bt], i
    assert all(b.is_sleeping for b in bt)


# -- reindexing ------------------------------------------------------------------------------

def test_reindex_static_and_shape():
    s = Space()
    b = Body(body_type=Body.STATIC)
    c = Circle(b, 10)
    s.add(b, c)
    b.position = -50, -50
    assert c.bb.left == -10  # not reindexed yet
    s.reindex_static()
    assert c.bb.left == -60
    b.position = 50, 50
    s.reindex_shapes_for_body(b)
    assert c.bb.left == 40
    b.position = 0, 0
    s.reindex_shape(c)
    assert c.bb.left == -10
    with pytest.raises(NotInSpace):
        s.reindex_shape(Circle(Body(1, 1), 1))


def test_reindex_refused_while_locked():
    s, b, c = _two_circles()
    errors = []

    def pre_solve(arb, space, data):
        for f in (space.reindex_static, lambda: space.reindex_shape(c),
                  lambda: space.reindex_shapes_for_body(b)):
            try:
                f()
            except SpaceLocked:
                errors.append(1)

    s.on_collision(pre_solve=pre_solve)
    s.step(0.01)
    assert errors == [1, 1, 1]


# -- debug drawing -------------------------------------------------------------------------------

def _recording_options(base):
    class Rec(base):
        def __init__(self):
            super().__init__()
            self.calls = []

        def draw_circle(self, *args):
            self.calls.append(("circle",) + args)

        def draw_segment(self, *args):
            self.calls.append(("segment",) + args)

        def draw_fat_segment(self, *args):
            self.calls.append(("fat_segment",) + args)

        def draw_polygon(self, verts, *args):
            self.calls.append(("polygon", list(verts)) + args)

        def draw_dot(self, *args):
            self.calls.append(("dot",) + args)

    return Rec()


def test_debug_draw_matches_pymunk():
    def build(mod):
        s = mod.Space()
        s.gravity = 0, -100
        s.add(mod.Segment(s.static_body, (-100, 0), (100, 0), 3))
        for i in range(4):
            b = mod.Body(1, 50)
            b.position = -30 + 20 * i, 8 + 5 * i
            b.angle = 0.3 * i
            shape = mod.Circle(b, 6) if i % 2 else mod.Poly.create_box(b, (10, 8), 1)
            shape.color = (10 * i, 20, 30, 255)
            s.add(b, shape)
        k = mod.Body(body_type=mod.Body.KINEMATIC)
        s.add(k, mod.Segment(k, (50, 50), (70, 60), 2))
        for _ in range(10):
            s.step(0.02)
        return s

    sp, st = build(pymunk), build(tamias2d)
    op = _recording_options(pymunk.SpaceDebugDrawOptions)
    ot = _recording_options(tamias2d.SpaceDebugDrawOptions)
    for o in (op, ot):
        o.transform = (2, 0, 0, 2, 10, -5)
    sp.debug_draw(op)
    st.debug_draw(ot)
    assert any(c[0] == "segment" for c in op.calls)  # collision points
    assert op.calls == ot.calls


def test_debug_draw_flags_and_draw_shape_bypass():
    s, b, c = _two_circles()
    s.step(0.01)
    o = _recording_options(tamias2d.SpaceDebugDrawOptions)
    o.flags = tamias2d.SpaceDebugDrawOptions.DRAW_COLLISION_POINTS
    s.debug_draw(o)
    assert [k[0] for k in o.calls] == ["segment"]
    drawn = []
    o._use_chipmunk_debug_draw = False
    o.draw_shape = drawn.append
    s.debug_draw(o)
    assert drawn == list(s.shapes)


# -- life cycle ------------------------------------------------------------------------------

def test_deleting_a_space_detaches_its_objects():
    s = Space()
    b = Body(1, 10)
    c = Circle(b, 5)
    sb = s.static_body
    ground = Circle(sb, 5)
    s.add(b, c, ground)
    s.step(0.01)
    ref = weakref.ref(s)
    del s
    gc.collect()
    assert ref() is None
    assert b.space is None and c.space is None and ground.space is None
    s2 = Space()
    s2.add(b, c)
    s2.step(0.01)


@pytest.mark.parametrize("solver", ["chipmunk", "soft"])
@pytest.mark.parametrize("persistence", [3, 0])
def test_a_freed_space_leaves_its_objects_as_removing_them_would(solver, persistence):
    # A space being freed drops all its arbiters at once (waking what
    # sleeps) instead of filtering its arbiter cache for each shape, which
    # made freeing quadratic. Its bodies and shapes must come out as
    # removing them one by one leaves them: in a new space their arbiter
    # lists hold the new space's arbiters only, and they step exactly as the
    # removed ones do.
    def scene():
        sp = Space()
        sp.solver = solver
        sp.gravity = 0, -900
        sp.sleep_time_threshold = 0.3
        sp.collision_persistence = persistence
        floor = tamias2d.Segment(sp.static_body, (-300, 0), (300, 0), 2)
        floor.friction = 0.8
        sp.add(floor)
        for i in range(12):
            b = Body(1, 200)
            b.position = -120 + 40 * (i % 6), 12 + 25 * (i // 6)
            shape = tamias2d.Poly.create_box(b, (20, 20)) if i % 2 else Circle(b, 10)
            shape.friction = 0.8
            sp.add(b, shape)
        kicked = Body(1, 200)
        kicked.position = 200, 60
        kicked.velocity = -300, 0
        sp.add(kicked, Circle(kicked, 10))
        for _ in range(90):
            sp.step(1 / 60)
        kicked.activate()   # on the floor, apart: awake beside the sleeping pile
        bodies = list(sp.bodies)
        return sp, bodies, [sh for sh in sp.shapes if sh.body is not sp.static_body]

    def arbiters_of(bodies):
        found = []
        for b in bodies:
            b.each_arbiter(lambda arb: found.append(arb))
        return found

    freed, freed_bodies, freed_shapes = scene()
    if persistence > 0:
        # (At persistence 0 the pile falls through the floor, as in pymunk:
        # nothing sleeps or touches.)
        assert any(b.is_sleeping for b in freed_bodies), "nothing sleeps: the wake-up is not tested"
        assert any(not b.is_sleeping for b in freed_bodies)
        assert arbiters_of(freed_bodies), "no arbiter: nothing is dropped"
    del freed
    gc.collect()
    kept, kept_bodies, kept_shapes = scene()
    kept.remove(*kept_shapes)
    kept.remove(*kept_bodies)
    assert all(b.space is None for b in freed_bodies)
    assert all(sh.space is None for sh in freed_shapes)
    states = []
    for bodies, shapes in ((freed_bodies, freed_shapes), (kept_bodies, kept_shapes)):
        again = Space()
        again.solver = solver
        again.gravity = 0, -900
        again.add(tamias2d.Segment(again.static_body, (-300, 0), (300, 0), 2))
        again.add(*bodies, *shapes)
        for _ in range(60):
            again.step(1 / 60)
        index = {id(sh): i for i, sh in enumerate(shapes)}
        lists = []
        for b in bodies:
            # The new space's arbiters only, on lists that began empty.
            b.each_arbiter(lambda arb: lists.append(tuple(index.get(id(sh), -1) for sh in arb.shapes)))
        states.append((lists, [(tuple(b.position), b.angle, tuple(b.velocity)) for b in bodies]))
    if persistence > 0:
        assert states[0][0], "no arbiter in the new space: the lists are not tested"
    assert repr(states[0]) == repr(states[1])


def test_space_in_reference_cycle_is_collected():
    s, b, c = _two_circles()
    s.me = s
    s.on_collision(begin=lambda arb, space, data: None, data=s)
    s.step(0.01)
    ref = weakref.ref(s)
    del s
    gc.collect()
    assert ref() is None
    assert b.space is None


def test_arbiter_keeps_space_alive():
    s, b, c = _two_circles()
    kept = []
    s.on_collision(pre_solve=lambda arb, space, data: kept.append(arb))
    s.step(0.01)
    ref = weakref.ref(s)
    del s
    gc.collect()
    assert ref() is not None
    assert len(kept[0].shapes) == 2


def test_step_releases_the_gil():
    # While one thread is inside a long step, another thread can run Python
    # code: it sees the step under way (current_time_step already set, step()
    # not returned). Its add() waits for the step to end and then adds at
    # once (see _threadguard.pxd). Decided by the order of events, not by
    # timing.
    s = Space()
    s.gravity = 0, -900
    s.add(Segment(s.static_body, (-500, 0), (500, 0), 5))
    for i in range(600):
        b = Body(1, 10)
        b.position = -300 + (i % 30) * 20, 10 + (i // 30) * 20
        s.add(b, Circle(b, 10.5))  # overlapping: contacts from the first step
    s.iterations = 3000
    late = Body(1, 1)
    seen = []
    returned = [False]

    def worker():
        while s.current_time_step == 0.0:
            time.sleep(0.0001)
        under_way = not returned[0]
        s.add(late)  # waits for the step to end, then adds at once
        seen.append((under_way, late in s.bodies))

    t = threading.Thread(target=worker)
    t.start()
    s.step(1 / 60)
    returned[0] = True
    t.join()
    assert seen == [(True, True)]  # ran during the step; add() waited for its end


# -- queries ------------------------------------------------------------------------------------

def test_queries_include_sensors_and_apply_filters():
    s = Space()
    c = Circle(s.static_body, 10)
    c.sensor = True
    s.add(c)
    f = tamias2d.ShapeFilter()
    assert [h.shape for h in s.point_query((0, 0), 100, f)] == [c]
    assert s.point_query_nearest((0, 0), 100, f).shape is c
    assert [h.shape for h in s.segment_query((-20, 0), (20, 0), 1, f)] == [c]
    assert s.segment_query_first((-20, 0), (20, 0), 1, f).shape is c
    assert s.bb_query(tamias2d.BB(0, 0, 10, 10), f) == [c]
    assert [h.shape for h in s.shape_query(Circle(None, 200))] == [c]
    c.filter = tamias2d.ShapeFilter(categories=0b10, mask=0b10)
    other = tamias2d.ShapeFilter(categories=0b01, mask=0b01)
    assert s.point_query((0, 0), 100, other) == []
    assert s.point_query_nearest((0, 0), 100, other) is None
    assert s.segment_query_first((-20, 0), (20, 0), 1, other) is None
    with pytest.raises(TypeError):
        s.point_query((0, 0), 1, "no filter")
    with pytest.raises(TypeError):
        s.shape_query("no shape")


def test_queries_from_inside_a_callback():
    s, b, c = _two_circles()
    found = []

    def pre_solve(arb, space, data):
        found.append(len(space.point_query((0, 0), 1, tamias2d.ShapeFilter())))
        found.append(len(space.bb_query(tamias2d.BB(-1, -1, 1, 1), tamias2d.ShapeFilter())))

    s.on_collision(pre_solve=pre_solve)
    s.step(0.01)
    assert found == [2, 2]


@pytest.mark.parametrize("types", [(None, None), (1, None), (1, 2), (2, 1)])
def test_post_solve_runs_however_it_is_registered(types):
    # The step skips its post-solve pass when no handler has a post_solve;
    # each way of registering one must still be called, as often as pymunk
    # calls it.
    import pymunk
    counts = []
    for mod in (tamias2d, pymunk):
        s = mod.Space()
        s.gravity = 0, -100
        floor = mod.Segment(s.static_body, (-50, 0), (50, 0), 1)
        floor.collision_type = 2
        s.add(floor)
        for i in range(3):
            b = mod.Body(1, 10)
            b.position = -20 + 20 * i, 5
            c = mod.Circle(b, 4)
            c.collision_type = 1
            s.add(b, c)
        calls = []
        s.on_collision(types[0], types[1], post_solve=lambda arb, space, data: calls.append(1))
        for _ in range(60):
            s.step(1 / 60)
        counts.append(len(calls))
    assert counts[0] == counts[1] > 0
