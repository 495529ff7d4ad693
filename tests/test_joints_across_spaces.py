"""A joint and its bodies share one space.

Space.add refuses (IllegalConstraint, a ValueError and an AssertionError) a
joint one of whose bodies belongs to another space, and a body one of whose
joints lives in another space. Bodies in no space are fine, as in pymunk (a
joint to a body never added, a static Body() of one's own). pymunk accepts
the mixed case and then corrupts memory once the other space's body falls
asleep (the joint gets threaded into a space that never had it); every test
that could show that runs in a forked child with a timeout.
"""
import gc

import pytest

from tamias2d import Body, Circle, Segment, Space
from tamias2d.constraints import PinJoint, PivotJoint, SimpleMotor
from tamias2d.errors import AlreadyInSpace, IllegalConstraint

from isolated import isolated


def two_bodies():
    a, b = Body(1, 1), Body(1, 1)
    b.position = (3, 0)
    return a, b


def settle(space, steps=200):
    for _ in range(steps):
        space.step(1 / 60)


def sleepy_space():
    s = Space()
    s.sleep_time_threshold = 0.2
    s.gravity = (0, -10)
    ground = Segment(s.static_body, (-50, 0), (50, 0), 0)
    s.add(ground)
    return s


@isolated(timeout=60)
def test_the_reported_case_is_refused_and_both_spaces_live_on():
    # A: sleeping off; B: sleeping on. The joint in A joining a body of B
    # would be threaded into B's sleeping component when that body sleeps.
    A, B = Space(), sleepy_space()
    a = Body(1, 1)
    A.add(a)
    b = Body(1, 1)
    b.position = (0, 1)
    B.add(b, Circle(b, 1))
    j = PinJoint(a, b)
    with pytest.raises(IllegalConstraint, match="same space"):
        A.add(j)
    with pytest.raises(ValueError):
        A.add(j)
    with pytest.raises(AssertionError):
        A.add(j)
    assert list(A.constraints) == []
    settle(A)
    settle(B)
    assert b.is_sleeping
    del A, B, j
    gc.collect()


def test_bodies_first_then_joint():
    A, B = Space(), Space()
    a, b = two_bodies()
    A.add(a)
    B.add(b)
    j = PinJoint(a, b)
    for space in (A, B):
        with pytest.raises(IllegalConstraint):
            space.add(j)
    assert list(A.constraints) == [] and list(B.constraints) == []
    B.remove(b)
    A.add(j)                          # b is in no space now
    A.add(b)
    assert list(A.constraints) == [j]
    settle(A, 10)


def test_joint_first_then_bodies():
    A, B = Space(), Space()
    a, b = two_bodies()
    j = PinJoint(a, b)
    A.add(j)                          # bodies in no space: fine (pymunk allows it)
    with pytest.raises(IllegalConstraint, match="joint"):
        B.add(b)
    assert b.space is None and list(B.bodies) == []
    with pytest.raises(IllegalConstraint):
        B.add(a, b)                   # nothing of the call after the refusal is added
    A.add(a, b)
    assert set(A.bodies) == {a, b}
    settle(A, 10)


def test_same_call_adds_bodies_before_the_joint():
    A = Space()
    a, b = two_bodies()
    j = PinJoint(a, b)
    A.add(j, a, b)
    assert list(A.constraints) == [j]


def test_remove_and_readd():
    A, B = Space(), Space()
    a, b = two_bodies()
    j = PinJoint(a, b)
    A.add(a, b, j)
    A.remove(j)
    with pytest.raises(IllegalConstraint):
        B.add(j)
    A.add(j)                          # back into its own space
    A.remove(j, a, b)
    B.add(j)
    B.add(a, b)
    with pytest.raises(AlreadyInSpace):
        A.add(a)
    settle(B, 10)


def test_body_moved_to_another_space():
    A, B = Space(), Space()
    a, b = two_bodies()
    j = PinJoint(a, b)
    A.add(a, b, j)
    A.remove(b)                       # the joint stays in A, b in no space: fine
    settle(A, 5)
    with pytest.raises(IllegalConstraint, match="joint"):
        B.add(b)
    assert b.space is None
    A.remove(j)
    B.add(b)                          # the joint is in no space now
    with pytest.raises(IllegalConstraint):
        A.add(j)                      # b is in B
    A.remove(a)
    B.add(a, j)
    settle(B, 10)


def test_body_with_shapes_left_in_another_space():
    # remove(body) may leave its shapes in the space: the body still belongs
    # there (sleeping would move those shapes between trees).
    A, B = Space(), Space()
    a, b = two_bodies()
    c = Circle(b, 1)
    B.add(b, c)
    B.remove(b)
    with pytest.raises(IllegalConstraint):
        A.add(a, PinJoint(a, b))      # a goes in first, then the joint is refused
    assert a in A.bodies and list(A.constraints) == []
    B.add(PinJoint(Body(1, 1), b))    # b's own space: fine


def test_static_bodies():
    A, B = Space(), Space()
    b = Body(1, 1)
    A.add(b, PivotJoint(A.static_body, b, (0, 0)))     # the usual pattern
    c = Body(1, 1)
    B.add(c)
    with pytest.raises(IllegalConstraint):
        B.add(PivotJoint(A.static_body, c, (0, 0)))    # A's static body is A's
    B.add(PivotJoint(B.static_body, c, (0, 0)))
    # A static body in no space may hold joints of several spaces.
    ground = Body(body_type=Body.STATIC)
    A.add(PinJoint(ground, b))
    B.add(PinJoint(ground, c))
    settle(A, 10)
    settle(B, 10)


@isolated(timeout=60)
def test_shared_free_static_body_with_sleeping_spaces():
    ground = Body(body_type=Body.STATIC)
    spaces = []
    for i in range(2):
        s = sleepy_space()
        b = Body(1, 1)
        b.position = (0, 1)
        s.add(b, Circle(b, 1), PivotJoint(ground, b, (0, 1)))
        spaces.append((s, b))
    for s, b in spaces:
        settle(s)
        assert b.is_sleeping
    for s, b in spaces:
        b.activate()
        settle(s, 5)
    del spaces
    gc.collect()


def test_deferred_add_from_a_callback_is_checked():
    A, B = Space(), Space()
    a, b = two_bodies()
    A.add(a)
    B.add(b)
    j = SimpleMotor(a, b, 1)
    pre = []
    c = Body(1, 1)
    A.add(c)
    trigger = PinJoint(a, c)
    A.add(trigger)

    def pre_solve(constraint, space):
        if not pre:
            pre.append(1)
            space.add(j)              # deferred to the end of the step

    trigger.pre_solve = pre_solve
    with pytest.raises(IllegalConstraint):
        A.step(1 / 60)
    assert j not in A.constraints
    A.step(1 / 60)


@isolated(timeout=60)
def test_sleeping_in_both_spaces_with_legal_joints():
    A, B = sleepy_space(), sleepy_space()
    for s in (A, B):
        a, b = two_bodies()
        a.position = (0, 1)
        b.position = (2.5, 1)
        s.add(a, b, Circle(a, 1), Circle(b, 1), PinJoint(a, b))
    settle(A, 400)
    settle(B, 400)
    assert all(body.is_sleeping for body in A.bodies)
    assert all(body.is_sleeping for body in B.bodies)
    del A, B
    gc.collect()
