"""Regression tests for sleeping, collision persistence 0 and the step's
overflow check: kinematic bodies put to sleep, a body outside the space that
woke into it and crashed activate(), arbiters left on removed shapes, bodies
that went NaN where the check did not look.

Each test failed (or crashed, or hung) before its fix. Those that crashed or
hung run in a forked child (tests/isolated.py), so that a regression fails
the one test. What pymunk 7.3.1 does with the same script is said beside
each; where pymunk neither crashes nor hangs, tamias2d gives its numbers.
"""
import copy
import math
import pickle

import pytest

import tamias2d
from tamias2d import Body, Circle, PinJoint, PivotJoint, Poly, Segment, Space
from tamias2d.errors import IllegalBody

from isolated import isolated

DT = 1 / 60


def state(b):
    return (*b.position, b.angle, *b.velocity, b.angular_velocity)


def finite(b):
    return all(map(math.isfinite, state(b)))


def sound(space):
    problem = space._contact_graph_problem()
    assert not problem, problem


# -- kinematic bodies and sleep_time_threshold <= 0 ----------------------------------------
# Munk2D finds the empty component of a kinematic body idle once the threshold
# is <= 0 (its idle time stays 0, and 0 < 0 is false) and deactivates it:
# pymunk aborts ("Attempting to deactivate a non-dynamic body"); tamias2d put
# the body to sleep, so it stopped moving and its shapes went to the static
# index.

@pytest.mark.parametrize("threshold", [0.0, 1e-300, 1e-9, 0.5])
def test_kinematic_bodies_never_sleep(threshold):
    s = Space()
    s.sleep_time_threshold = threshold
    k = Body(body_type=Body.KINEMATIC)
    k.velocity = (10, 0)
    k.angular_velocity = 1
    s.add(k, Circle(k, 1))
    bare = Body(body_type=Body.KINEMATIC)
    bare.velocity = (0, 5)
    s.add(bare)
    for i in range(20):
        s.step(0.1)
        assert not k.is_sleeping and not bare.is_sleeping
        sound(s)
    assert k.position.x == pytest.approx(20.0)
    assert bare.position.y == pytest.approx(10.0)


@isolated(timeout=60)
def test_a_box_on_a_kinematic_platform_stays_awake_at_threshold_0():
    # The box touches the platform: Munk2D wakes it (idle time 0), which at a
    # threshold of 0 is idle enough, so it slept with its arbiter owned by
    # the platform still threaded; the next step threaded it again.
    for platform_first in (True, False):
        s = Space()
        s.gravity = 0, -100
        s.sleep_time_threshold = 0.0
        platform = Body(body_type=Body.KINEMATIC)
        platform.velocity = (5, 0)
        box = Body(1, 10)
        box.position = (0, 0.99)   # touching from the start (else it sleeps in mid-air)
        pshape = Poly.create_box(platform, (10, 1))
        bshape = Poly.create_box(box, (1, 1))
        pshape.friction = bshape.friction = 1.0
        if platform_first:
            s.add(platform, pshape, box, bshape)
        else:
            s.add(box, bshape, platform, pshape)
        for _ in range(120):
            s.step(DT)
            sound(s)
            assert not platform.is_sleeping
        assert not box.is_sleeping
        # carried along by friction, resting on the platform
        assert box.position.x > 5
        assert box.position.y == pytest.approx(1.0, abs=0.2)


@isolated(timeout=60)
def test_a_body_jointed_to_a_kinematic_body_stays_awake_at_threshold_0():
    s = Space()
    s.sleep_time_threshold = 0.0
    k = Body(body_type=Body.KINEMATIC)
    k.velocity = (10, 0)
    b = Body(1, 10)
    b.position = (0, -5)
    s.add(k, b, PinJoint(k, b))
    for _ in range(60):
        s.step(DT)
        sound(s)
    assert not b.is_sleeping
    assert b.position.x > 5      # pulled along


def test_threshold_0_without_kinematic_bodies_is_pymunks():
    # Where pymunk does not abort, a threshold of 0 keeps its meaning bit for
    # bit: every body falls asleep at the end of every step, moving or not.
    pymunk = pytest.importorskip("pymunk")

    def run(m):
        s = m.Space()
        s.gravity = 0, -100
        s.sleep_time_threshold = 0.0
        s.add(m.Segment(s.static_body, (-50, 0), (50, 0), 1))
        bodies = []
        for i in range(6):
            b = m.Body(1, 10)
            b.position = (3 * i - 8, 2 + 2.5 * i)
            b.velocity = (i, 0)
            s.add(b, m.Circle(b, 1))
            bodies.append(b)
        out = []
        for step in range(90):
            if step % 15 == 0:
                bodies[step // 15].activate()
            s.step(DT)
            out.append([(tuple(b.position), tuple(b.velocity), b.is_sleeping) for b in bodies])
        return out
    assert run(tamias2d) == run(pymunk)


# -- a body outside the space in a sleeping component ----------------------------------------

@isolated(timeout=60)
def test_activate_a_bare_jointed_body_that_became_a_sleeping_root():
    # A body outside the space, held by a joint, joins its partner's
    # component and sleeps with it. Removing the joint woke the component and
    # Munk2D woke that body into the space's body array; the next step made it
    # the root of a sleeping component of its own, and activate() on it
    # dereferenced its NULL space (pymunk segfaults the same way).
    s = Space()
    s.gravity = 0, -10
    s.sleep_time_threshold = 0.0
    a = Body(1, 1)
    b = Body(1, 1)
    b.position = (10, 0)
    j = PinJoint(a, b)
    s.add(a, Circle(a, 1), j)
    s.step(0.1)
    assert a.is_sleeping and b.is_sleeping
    s.remove(j)
    assert not b.is_sleeping
    s.step(0.1)
    b.activate()
    for _ in range(5):
        s.step(0.1)
        sound(s)
    # The space never integrates a body it does not hold.
    assert b.position == (10, 0)
    assert b.space is None and b not in s.bodies


@isolated(timeout=60)
def test_a_jointed_body_outside_the_space_sleeps_and_wakes_with_its_partner():
    # The joint stays in the solver whichever body owns it (is its body a).
    for outside_first in (False, True):
        s = Space()
        s.sleep_time_threshold = 0.0
        a = Body(1, 1)
        b = Body(1, 1)
        b.position = (10, 0)
        j = PinJoint(b, a) if outside_first else PinJoint(a, b)
        s.add(a, Circle(a, 1), j)
        s.step(DT)
        assert a.is_sleeping and b.is_sleeping
        a.activate()
        assert not a.is_sleeping and not b.is_sleeping
        s.sleep_time_threshold = 1.0    # at 0 the pair would sleep again before the solver
        a.velocity = (-50, 0)
        s.step(DT)
        sound(s)
        assert b.velocity.x < 0          # the joint was solved: b was pulled
        assert b.position == (10, 0)     # but b, outside the space, is not moved
        s.remove(j)
        for _ in range(5):
            s.step(DT)
            sound(s)
        assert b.position == (10, 0)     # still moving, still not integrated


@isolated(timeout=60)
def test_a_stale_component_root_does_not_follow_a_body_into_another_space():
    # At a threshold > 0 the component of a body and a bare jointed body
    # outside the space stays awake (the outside body's idle time is 0), and
    # the step resets the component links of the bodies in its array only:
    # the outside body kept its root (Munk2D too). Added to another space, it
    # counted as asleep there while awake: the step never unthreaded its
    # arbiters and its first contact looped (pymunk hangs).
    s = Space()
    s.sleep_time_threshold = 0.05
    a = Body(1, 1)
    b = Body(1, 1)
    b.position = (10, 0)
    j = PinJoint(a, b)
    s.add(a, Circle(a, 1), j)
    for _ in range(5):
        s.step(0.1)
    s.remove(j)
    assert not b.is_sleeping         # jointed into no space: its root is gone
    s.remove(*a.shapes, a)
    del a, j
    s2 = Space()
    s2.sleep_time_threshold = 0.05
    s2.gravity = 0, -10
    c = Body(1, 1)
    c.position = (10, 1.5)
    s2.add(b, Circle(b, 1), Segment(s2.static_body, (-100, -1), (100, -1), 1), c, Circle(c, 1))
    assert not b.is_sleeping
    for _ in range(100):
        s2.step(0.05)
        sound(s2)
    assert b.is_sleeping and c.is_sleeping   # a resting pile falls asleep


@isolated(timeout=60)
def test_a_stale_component_root_survives_its_body_leaving_and_copies():
    # The outside body b is jointed to a and x; their component stays awake
    # (b's idle time is 0) and b kept a's address as its root. With a
    # removed and freed, a copy found a link to a body it does not hold (the
    # capture refused the space) and waking b read freed memory.
    import gc
    s = Space()
    s.sleep_time_threshold = 0.05
    a, b, x = Body(1, 1), Body(1, 1), Body(1, 1)
    b.position, x.position = (10, 0), (20, 0)
    j1, j2 = PinJoint(a, b), PinJoint(b, x)
    s.add(a, Circle(a, 1), x, Circle(x, 1), j1, j2)
    for _ in range(3):
        s.step(0.1)
    s.remove(j1)
    s.remove(*a.shapes, a)
    del a, j1
    gc.collect()
    for _ in range(5):
        s.step(0.1)
    clone = copy.deepcopy(s)
    pickle.loads(pickle.dumps(s))
    assert x.is_sleeping
    b.activate()                     # wakes x, the body it is jointed to
    assert not x.is_sleeping
    for space in (s, clone):
        for _ in range(5):
            space.step(0.1)
            sound(space)
    s.remove(j2)
    assert not b.is_sleeping         # jointed into no space: no root left


def test_the_partner_of_a_stale_root_still_wakes_with_it():
    # While the joint is in the space, an outside body's root keeps Munk2D's
    # meaning: waking the outside body wakes its partner's component.
    s = Space()
    s.sleep_time_threshold = 0.05
    a = Body(1, 1)
    b = Body(1, 1)
    b.position = (10, 0)
    s.add(a, Circle(a, 1), PinJoint(a, b))
    for _ in range(5):
        s.step(0.1)
    assert a.is_sleeping
    b.activate()
    assert not a.is_sleeping


# -- collision persistence 0 ---------------------------------------------------------------
# With a persistence of 0 a step's arbiters leave the cache (and return to
# the pool) as the step ends, while they stay in its arbiter array and
# threaded in their bodies' lists until the next step.

def resting_pair(persistence=0):
    s = Space()
    s.collision_persistence = persistence
    s.gravity = 0, -100
    floor = Segment(s.static_body, (-100, 0), (100, 0), 1)
    b = Body(1, 10)
    b.position = (0, 1.9)
    c = Circle(b, 1)
    d = Body(1, 10)
    d.position = (1.5, 1.9)
    e = Circle(d, 1)
    s.add(floor, b, c, d, e)
    for _ in range(3):
        s.step(DT)
    return s, b, c, d, e


@pytest.mark.parametrize("how", ["deepcopy", "pickle", "copy"])
def test_persistence_0_then_remove_a_shape_then_copy(how):
    # The removed shape stayed in the arbiters the cache no longer held, and
    # the capture refused the space ("links to an object it does not hold").
    s, b, c, d, e = resting_pair()
    s.remove(c)
    clone = {"deepcopy": copy.deepcopy, "pickle": lambda x: pickle.loads(pickle.dumps(x)),
             "copy": lambda x: x.copy()}[how](s)
    sound(s)
    sound(clone)
    for _ in range(30):
        s.step(DT)
        clone.step(DT)
    assert [state(x) for x in s.bodies] == [state(x) for x in clone.bodies]


def test_persistence_0_remove_a_shape_leaves_no_arbiter_on_it():
    s, b, c, d, e = resting_pair()
    s.remove(c)
    seen = []
    d.each_arbiter(lambda arb: seen.append(arb.shapes))
    assert all(c not in shapes for shapes in seen)
    b.each_arbiter(lambda arb: seen.append(arb.shapes))
    assert all(c not in shapes for shapes in seen)


def test_persistence_0_numbers_are_pymunks():
    # The fix only drops arbiters the next step would drop anyway.
    pymunk = pytest.importorskip("pymunk")

    def run(m):
        s = m.Space()
        s.collision_persistence = 0
        s.gravity = 0, -100
        s.add(m.Segment(s.static_body, (-100, 0), (100, 0), 1))
        bodies, shapes = [], []
        for i in range(5):
            b = m.Body(1, 10)
            b.position = (1.8 * i, 1.5 + 0.3 * i)
            c = m.Circle(b, 1)
            s.add(b, c)
            bodies.append(b)
            shapes.append(c)
        out = []
        for step in range(60):
            if step in (10, 20, 30):
                s.remove(shapes[step // 10])
            s.step(DT)
            out.append([state(b) for b in bodies])
        return out
    assert run(tamias2d) == run(pymunk)


@isolated(timeout=60)
def test_persistence_0_then_sleep_a_touching_body():
    # body.sleep() took over last step's expired arbiters with the body:
    # the pool handed them to other pairs while the sleeping body kept them
    # threaded (pymunk and tamias2d hung in the following steps).
    s = Space()
    s.collision_persistence = 0
    s.sleep_time_threshold = 0.5
    s.gravity = 0, -100
    s.add(Segment(s.static_body, (-100, 0), (100, 0), 1))
    bodies = []
    for i in range(4):
        b = Body(1, 10)
        b.position = (3 * i, 1.9)
        s.add(b, Circle(b, 1))
        bodies.append(b)
    for _ in range(3):
        s.step(DT)
    bodies[0].sleep()
    for _ in range(10):
        s.step(DT)
        sound(s)
    bodies[0].activate()
    for _ in range(10):
        s.step(DT)
        sound(s)
    copy.deepcopy(s)


@isolated(timeout=60)
def test_a_body_outside_the_space_is_no_sleeping_group():
    # A body outside the space, held by a joint to a body that fell asleep,
    # reads as asleep (its root names itself) but sleeps in no component.
    # sleep_with_group() took it as the group: the body joined a component
    # rooted outside the space, and waking it through that root read the
    # root's NULL space (a segfault when the space was freed, or when a
    # joint added to the outside body woke it; the sleeping fuzzer, seed
    # 2085). It is refused now, and the space goes on.
    s = Space()
    s.gravity = 0, -100
    s.sleep_time_threshold = 0.5
    s.add(Segment(s.static_body, (-100, 0), (100, 0), 1))
    a = Body(1, 10)
    a.position = 0, 2
    s.add(a, Circle(a, 1))
    outside = Body(1, 10)
    outside.position = 0, 5
    s.add(PivotJoint(a, outside, (0, 3)))
    for _ in range(120):
        s.step(DT)
    assert a.is_sleeping and outside.is_sleeping
    c = Body(1, 10)
    c.position = 50, 2
    s.add(c, Circle(c, 1))
    s.step(DT)
    with pytest.raises(IllegalBody, match="asleep in this body's space"):
        c.sleep_with_group(outside)
    c.sleep_with_group(a)                   # a group that sleeps here is fine
    s.add(tamias2d.RotaryLimitJoint(outside, s.static_body, -1, 1))
    for _ in range(10):
        s.step(DT)
        sound(s)
    copy.deepcopy(s)


@pytest.mark.parametrize("solver", ["chipmunk", "soft"])
def test_a_body_put_to_sleep_under_another_can_be_copied(solver):
    # body.sleep() on a box with another box on it takes their arbiter out of
    # the contact graph, but left it in the step's arbiter array: copies of
    # the space were refused as corrupt ("names arbiter 0, whose bodies
    # sleep") until the next step. pymunk aborts here (munmap_chunk) once
    # stepped. The copy must continue as the original does.
    s = Space(solver=solver)
    s.gravity = 0, -300
    s.sleep_time_threshold = 0.5
    s.add(Segment(s.static_body, (-100, 0), (100, 0), 1))
    lower, upper = Body(1, 10), Body(1, 10)
    lower.position, upper.position = (0, 6), (0, 16)
    s.add(lower, Poly.create_box(lower, (10, 10)), upper, Poly.create_box(upper, (10, 10)))
    for _ in range(5):
        s.step(DT)
    lower.sleep()
    assert s._contact_graph_problem() is None
    for clone in (s.copy(), copy.deepcopy(s), pickle.loads(pickle.dumps(s))):
        for _ in range(120):
            clone.step(DT)
        sound(clone)
    for _ in range(120):
        s.step(DT)
    sound(s)
    assert [(tuple(b.position), b.is_sleeping) for b in s.bodies] == \
        [(tuple(b.position), b.is_sleeping) for b in clone.bodies]


# -- the overflow check of the step ----------------------------------------------------------
# It looked at the awake body array only; static bodies and joints' bodies
# outside the space went NaN silently, and the space could not be brought
# back by resetting the bodies the exception named.

def reset(bodies):
    for b in bodies:
        b.angle = 0     # first: the position is set through the rotation
        b.position = b.position if all(map(math.isfinite, b.position)) else (0, 0)
        b.velocity = 0, 0
        b.angular_velocity = 0


def overflow(s, steps=3):
    for _ in range(steps):
        try:
            s.step(DT)
        except IllegalBody as e:
            assert "overflowed" in str(e)
            return e
    return None


def test_a_static_body_that_overflows_is_named():
    # The static body moves into the ball at 1e308: the bounce impulse is
    # inf, and inf times the static body's zero inverse mass is NaN.
    s = Space()
    ball = Body(1, 1)
    ball.position = (0, 1.9)
    c = Circle(ball, 1)
    c.elasticity = 1.0
    s.add(ball, c)
    s.static_body.velocity = (0, 1e308)
    seg = Segment(s.static_body, (-10, 0), (10, 0), 1)
    seg.elasticity = 1.0
    s.add(seg)
    e = overflow(s)
    assert e is not None
    assert s.static_body in e.bodies
    assert not finite(s.static_body)
    # refused until it is reset too
    with pytest.raises(IllegalBody):
        s.step(DT)
    reset(e.bodies)
    for _ in range(30):
        s.step(DT)
    assert all(finite(b) for b in [*s.bodies, s.static_body])


@pytest.mark.parametrize("solver", ["chipmunk", "soft"])
def test_an_overflow_and_a_raising_callback_in_one_step(solver):
    # The step both overflowed and had a callback raise: the callback's error
    # surfaced and hid the overflow, so a caller resetting the bodies an
    # IllegalBody names never saw them (the fuzzer's sleeping mode, seed
    # 1919, was left with a NaN body). The overflow is raised, the callback's
    # error as its context.
    class Boom(Exception):
        pass

    def boom(space, key):
        raise Boom("callback")
    s = Space(solver=solver)
    a, b = Body(1, 1), Body(1, 1)      # b outside the space, held by the joint
    a.velocity = (1e300, 0)
    b.position = (10, 0)
    s.add(a, PinJoint(a, b))
    caught = None
    for _ in range(5):
        s.add_post_step_callback(boom, "boom")     # raises after every step
        try:
            s.step(DT)
        except Boom:
            continue
        except IllegalBody as e:
            caught = e
            break
    assert caught is not None and "overflowed" in str(caught)
    assert isinstance(caught.__context__, Boom)
    assert caught.bodies and not all(finite(b) for b in caught.bodies)
    reset(caught.bodies)
    a.position, b.position = (0, 0), (10, 0)
    for _ in range(30):
        s.step(DT)
    assert finite(a) and finite(b)


def test_a_soft_space_that_overflowed_and_was_reset_can_be_copied():
    # The soft step sets how far the broad phase reaches into the static tree
    # from the fastest body's speed, before the step: a speed that overflows
    # made it infinite, and once the bodies were reset the copy of the space
    # still refused it ("reaches inf into the static tree").
    s = Space(solver="soft")
    a, b = Body(1, 1), Body(1, 1)      # b outside the space, held by the joint
    a.velocity = (1e300, 0)
    b.position = (10, 0)
    s.add(a, Circle(a, 1), PinJoint(a, b))
    e = overflow(s)
    assert e is not None
    reset(e.bodies)
    a.position = 0, 0
    clone = s.copy()
    for _ in range(10):
        clone.step(DT)
    assert finite(a) and all(finite(x) for x in clone.bodies)


def test_a_static_body_in_the_space_that_overflows_is_named():
    s = Space()
    ground = Body(body_type=Body.STATIC)
    ground.velocity = (0, 1e308)
    seg = Segment(ground, (-10, 0), (10, 0), 1)
    seg.elasticity = 1.0
    ball = Body(1, 1)
    ball.position = (0, 1.9)
    c = Circle(ball, 1)
    c.elasticity = 1.0
    s.add(ground, seg, ball, c)
    e = overflow(s)
    assert e is not None and ground in e.bodies


def test_a_joints_body_outside_the_space_that_overflows_is_named():
    s = Space()
    a = Body(1, 1)
    a.velocity = (1e300, 0)
    b = Body(1, 1)
    b.position = (10, 0)
    s.add(a, PinJoint(a, b))
    e = overflow(s)
    assert e is not None
    assert b in e.bodies and not finite(b)
    reset(e.bodies)
    a.position, b.position = (0, 0), (10, 0)    # 1e298 apart, the joint overflows again
    for _ in range(10):
        s.step(DT)
    assert finite(a) and finite(b)


@pytest.mark.parametrize("what", ["velocity", "angular_velocity"])
def test_a_kinematic_body_that_overflows_is_named(what):
    for threshold in (math.inf, 0.0):
        s = Space()
        s.sleep_time_threshold = threshold
        k = Body(body_type=Body.KINEMATIC)
        setattr(k, what, (1e308, 0) if what == "velocity" else 1e308)
        s.add(k, Circle(k, 1))
        e = None
        for _ in range(4):
            try:
                s.step(1.0)
            except IllegalBody as exc:
                e = exc
                break
        assert e is not None and e.bodies == [k]
        reset(e.bodies)
        s.step(1.0)


def test_an_orphan_that_overflows_is_named():
    # A body removed from the space whose shape stayed: the ball's bounce on
    # it turns its velocity NaN.
    s = Space()
    o = Body(1, 1)
    box = Poly.create_box(o, (20, 2))
    box.elasticity = 1.0
    s.add(o, box)
    s.remove(o)
    o.velocity = (0, 1e308)
    ball = Body(1, 1)
    ball.position = (0, 1.9)
    c = Circle(ball, 1)
    c.elasticity = 1.0
    s.add(ball, c)
    e = overflow(s)
    assert e is not None
    assert o in e.bodies
    reset(e.bodies)
    for _ in range(10):
        s.step(DT)
    assert finite(o) and finite(ball)


def test_the_check_costs_nothing_in_numbers():
    # Pure reads: the same scene as pymunk, bit for bit, with a static body
    # and joints to a body outside the space.
    pymunk = pytest.importorskip("pymunk")

    def run(m):
        s = m.Space()
        s.gravity = 0, -100
        s.add(m.Segment(s.static_body, (-100, 0), (100, 0), 1))
        outside = m.Body(5, 50)
        outside.position = (0, 20)
        prev = None
        bodies = []
        for i in range(4):
            b = m.Body(1, 10)
            b.position = (2.5 * i, 10)
            s.add(b, m.Circle(b, 1))
            s.add(m.PivotJoint(b, outside if prev is None else prev, b.position))
            prev = b
            bodies.append(b)
        out = []
        for _ in range(120):
            s.step(DT)
            out.append([state(b) for b in bodies] + [state(outside)])
        return out
    assert run(tamias2d) == run(pymunk)


# -- found by the sleeping mode of tests/test_fuzz.py ----------------------------------------
# A joint belongs to its body a, or to its body b when a is static: the
# owner's sleeping takes the joint out of the solver, waking puts it back.

@isolated(timeout=60)
def test_a_static_body_turned_dynamic_keeps_its_joint_to_a_sleeping_body():
    # The joint was the sleeping body's; turned dynamic, the static body
    # owns it, and waking the other body no longer put it back: the joint
    # was lost for good (pymunk too, and it segfaults when the space is freed).
    s = Space()
    s.sleep_time_threshold = 0.5
    st = Body(body_type=Body.STATIC)
    b = Body(1, 10)
    b.position = (0, -5)
    s.add(st, Circle(st, 1), b, Circle(b, 1), PinJoint(st, b))
    for _ in range(10):
        s.step(0.1)
    assert b.is_sleeping
    st.body_type = Body.DYNAMIC
    st.mass, st.moment = 1, 10
    st.velocity = (10, 0)
    assert not b.is_sleeping
    for _ in range(40):
        s.step(0.05)
        sound(s)
    assert (st.position - b.position).length == pytest.approx(5.0, abs=0.2)
    copy.deepcopy(s)


@isolated(timeout=60)
def test_a_body_turned_static_hands_its_joint_to_a_sleeping_body_once():
    # The joint was the awake body's and stayed in the solver; turned static,
    # it belongs to the sleeping body, whose waking pushed it a second time
    # (the copy refused the space; freeing it looped; pymunk segfaults).
    s = Space()
    s.sleep_time_threshold = 0.5
    a = Body(1, 10)
    b = Body(1, 10)
    b.position = (0, -5)
    j = PinJoint(a, b)
    s.add(a, Circle(a, 1), b, Circle(b, 1), j)
    s.step(0.1)
    b.sleep()
    a.body_type = Body.STATIC
    s.step(0.1)
    b.activate()
    s.step(0.1)
    copy.deepcopy(s)
    s.remove(j)
    for _ in range(3):
        s.step(0.1)
    del s      # freeing the space must end


def test_a_body_outside_the_space_turned_kinematic_does_not_sleep():
    s = Space()
    s.sleep_time_threshold = 0.05
    a = Body(1, 1)
    b = Body(1, 1)
    b.position = (10, 0)
    s.add(a, Circle(a, 1), PinJoint(a, b))
    for _ in range(3):
        s.step(0.1)
    assert b.is_sleeping           # the flood fill's mark, as in pymunk
    b.body_type = Body.KINEMATIC
    assert not b.is_sleeping


# -- the spatial hash and boxes covering millions of cells --------------------------------

@isolated(timeout=60)
@pytest.mark.parametrize("solver", ["chipmunk", "soft"])
def test_a_fast_body_in_the_spatial_hash_steps(solver):
    # In the soft solver a shape's box in the spatial hash grows by its
    # body's travel in the step (continuous collision): at 1e7 per second
    # over 10-unit cells, (3e4 cells)^2 a step, which walked cell by cell
    # took minutes (the fuzzer's seed 7005). Such a box now takes every
    # bucket of the table once. The ball must still stop at the wall.
    s = Space(solver=solver)
    s.use_spatial_hash(10.0, 100)
    wall = Poly(s.static_body, [(0, -1e6), (1, -1e6), (1, 1e6), (0, 1e6)])
    b = Body(1.0, 1.0)
    b.position = -10, 0
    b.velocity = 1e7, 0
    ball = Circle(b, 0.5)
    s.add(wall, b, ball)
    for _ in range(3):
        s.step(1 / 60)
        sound(s)
    if solver == "soft":
        assert b.position.x < 0.0
    # Queries over such a box, and one reaching past 2**31 cells.
    assert ball in s.bb_query(tamias2d.BB(-1e6, -1e6, 1e6, 1e6), tamias2d.ShapeFilter())
    assert wall in s.bb_query(tamias2d.BB(-1e300, -1e300, 1e300, 1e300), tamias2d.ShapeFilter())


@isolated(timeout=60)
def test_a_huge_static_shape_in_the_spatial_hash():
    # A static box 1e12 wide over 1-unit cells (past the cells' 32-bit
    # numbers): added, stepped and queried in moments; a box on it rests.
    s = Space()
    s.gravity = 0, -100
    s.use_spatial_hash(1.0, 1000)
    ground = Poly(s.static_body, [(-1e12, -1e12), (1e12, -1e12), (1e12, 0), (-1e12, 0)])
    b = Body(1.0, tamias2d.moment_for_box(1.0, (2, 2)))
    b.position = 0, 1
    s.add(ground, b, Poly.create_box(b, (2, 2)))
    for _ in range(60):
        s.step(1 / 60)
    assert abs(b.position.y - 1.0) < 0.2
    assert [h.shape for h in s.point_query((0, -5), 0, tamias2d.ShapeFilter())] == [ground]


@pytest.mark.parametrize("solver", ["chipmunk", "soft"])
@pytest.mark.parametrize("orphan_first", [True, False])
@pytest.mark.parametrize("threshold", [0.0, 0.5])
def test_a_body_resting_on_an_orphan_stays_awake(solver, orphan_first, threshold):
    # An orphan (a dynamic body removed while its shapes stayed) is not
    # integrated and never sleeps; a body resting on it is kept awake, as on
    # a kinematic body, whichever of their arbiter's two bodies it is (a
    # circle's body comes first). At a threshold of 0 only the orphan as the
    # arbiter's first body held it: as the second, the body slept with their
    # arbiter, which stayed threaded on the orphan's list, out of the step's
    # array (the sleeping fuzzer's seed 2466, both solvers).
    s = Space(solver=solver)
    s.gravity = 0, -100
    s.sleep_time_threshold = threshold
    orphan = Body(10, 100)
    orphan.position = 0, 0
    if orphan_first:
        under = Circle(orphan, 20)
        body = Body(1, tamias2d.moment_for_box(1, (4, 4)))
        body.position = 0, 22
        top = Poly.create_box(body, (4, 4))
    else:
        under = Poly.create_box(orphan, (40, 10))
        body = Body(1, 10)
        body.position = 0, 7
        top = Circle(body, 2)
    s.add(orphan, under, body, top)
    s.step(1 / 60)
    s.remove(orphan)
    touched = 0
    for _ in range(120):
        s.step(1 / 60)
        sound(s)
        arbiters = []
        body.each_arbiter(arbiters.append)
        if arbiters:
            # (The chipmunk solver lets it sink through the orphan, which is
            # not integrated, and then it falls free and, at 0, sleeps.)
            touched += 1
            assert not body.is_sleeping
    assert touched > 0


@isolated(timeout=60)
def test_a_segment_query_across_millions_of_cells():
    # A segment query walks the cells it crosses, in order: one 2e11 long
    # over 10-unit cells crosses 2e10 cells, past the cells' 32-bit numbers
    # (2e9 long took 3 s). Past 4,194,304 cells it visits every bucket once
    # instead, and finds what the tree finds.
    found = {}
    for hashed in (False, True):
        s = Space()
        if hashed:
            s.use_spatial_hash(10.0, 100)
        for i in range(5):
            b = Body(1, 1)
            b.position = 1000 * i, 0
            s.add(b, Circle(b, 5))
        s.add(Segment(s.static_body, (4500, -10), (4500, 10), 1))
        hits = s.segment_query((-1e11, 0), (1e11, 0), 0, tamias2d.ShapeFilter())
        found[hashed] = sorted((h.point.x, h.point.y) for h in hits)
    assert len(found[False]) == 6
    assert found[True] == found[False]
