"""tamias2d.step_spaces: many spaces in one call, on several threads.

Each space must end bit for bit where stepping it alone ends, for any number
of threads (1, 2, many), with mixed scenes: sleeping, joints, Python
callbacks. Error paths: bad input is refused before anything steps; an
exception raised while stepping comes out after every space finished its
step, naming the space.
"""
import math

import pytest

import tamias2d
from tamias2d.errors import IllegalBody, SpaceLocked

import scenes
from isolated import isolated


def state(space):
    return [(tuple(b.position), b.angle, tuple(b.velocity), b.angular_velocity, b.is_sleeping)
            for b in space.bodies]


def count_post_solve(arbiter, space, data):
    space.post_solves += 1


def mixed_scenes():
    out = []
    p = scenes.pyramid(tamias2d, rows=8)
    p.sleep_time_threshold = 0.2
    out.append(p)
    out.append(scenes.mixed(tamias2d))
    r = scenes.rain(tamias2d, count=80)
    r.post_solves = 0
    r.on_collision(post_solve=count_post_solve)
    out.append(r)
    out.append(scenes.drum(tamias2d, count=30))
    out.append(scenes.vertical_stack(tamias2d, count=6))
    soft = scenes.pyramid(tamias2d, rows=6)
    soft.solver = "soft"
    out.append(soft)
    out.append(tamias2d.Space())          # empty
    return out


@pytest.mark.parametrize("threads", [1, 2, 7])
def test_same_bits_as_stepping_each_space_alone(threads):
    together = mixed_scenes()
    alone = mixed_scenes()
    for _ in range(3):
        tamias2d.step_spaces(together, 1 / 60, threads=threads, steps=20)
    for s in alone:
        for _ in range(60):
            s.step(1 / 60)
    for a, b in zip(together, alone):
        assert state(a) == state(b)
    assert together[2].post_solves == alone[2].post_solves > 0
    assert any(b.is_sleeping for b in together[0].bodies)


def test_many_small_spaces_on_default_threads():
    base = scenes.circles_on_segment(tamias2d, count=5)
    spaces = [base.copy() for _ in range(64)]
    ref = base.copy()
    tamias2d.step_spaces(spaces, 1 / 60, steps=30)
    for _ in range(30):
        ref.step(1 / 60)
    assert all(state(s) == state(ref) for s in spaces)


def test_bad_input_is_refused_before_anything_steps():
    a, b = tamias2d.Space(), tamias2d.Space()
    a.gravity = b.gravity = 0, -10
    body = tamias2d.Body(1, 1)
    a.add(body, tamias2d.Circle(body, 1))
    with pytest.raises(TypeError, match=r"spaces\[1\]"):
        tamias2d.step_spaces([a, "b"], 0.1)
    with pytest.raises(ValueError, match="twice"):
        tamias2d.step_spaces([a, b, a], 0.1)
    for dt in (math.nan, math.inf, -0.1):
        with pytest.raises(ValueError, match="dt"):
            tamias2d.step_spaces([a], dt)
    with pytest.raises(ValueError, match="steps"):
        tamias2d.step_spaces([a], 0.1, steps=-1)
    with pytest.raises(ValueError, match="threads"):
        tamias2d.step_spaces([a], 0.1, threads=0)
    assert body.velocity == (0, 0) and a.current_time_step == 0


def test_a_space_that_cannot_step_stops_the_call_before_any_step():
    good, broken = tamias2d.Space(), tamias2d.Space()
    good.gravity = 0, -10
    g = tamias2d.Body(1, 1)
    good.add(g, tamias2d.Circle(g, 1))
    tamias2d.step_spaces([good], 0.1)
    before = state(good)
    # A dynamic body with no mass: Space.step refuses it, so does step_spaces.
    broken.add(tamias2d.Body(body_type=tamias2d.Body.DYNAMIC))
    with pytest.raises(IllegalBody) as info:
        tamias2d.step_spaces([good, broken], 0.1)
    assert info.value.space is broken and info.value.space_index == 1
    assert state(good) == before         # nothing stepped
    good.step(0.1)                        # and nothing left locked


def test_an_exception_in_a_callback_comes_after_every_space_stepped():
    spaces = [scenes.circles_on_segment(tamias2d, count=4) for _ in range(4)]
    for _ in range(40):
        for s in spaces:
            s.step(1 / 60)
    refs = [s.copy() for s in spaces]

    def boom(arbiter, space, data):
        raise RuntimeError("boom")

    spaces[2].on_collision(post_solve=boom)
    with pytest.raises(RuntimeError, match="boom") as info:
        tamias2d.step_spaces(spaces, 1 / 60, threads=2, steps=5)
    assert info.value.space is spaces[2] and info.value.space_index == 2
    for i, (s, r) in enumerate(zip(spaces, refs)):
        r.step(1 / 60)                    # every space made exactly the first step
        if i != 2:
            assert state(s) == state(r)
    spaces[2].on_collision(post_solve=tamias2d.empty_callback)
    tamias2d.step_spaces(spaces, 1 / 60)  # consistent and steppable


def test_a_space_inside_its_own_step_is_refused():
    s = tamias2d.Space()
    s.gravity = 0, -10
    ball = tamias2d.Body(1, 1)
    ball.position = 0, 1
    s.add(ball, tamias2d.Circle(ball, 1), tamias2d.Segment(s.static_body, (-5, 0), (5, 0), 1))
    seen = []

    def pre_solve(arbiter, space, data):
        try:
            tamias2d.step_spaces([space], 0.1)
        except SpaceLocked as exc:
            seen.append(str(exc))

    s.on_collision(pre_solve=pre_solve)
    s.step(0.1)
    assert seen and "spaces[0]" in seen[0]


@isolated(timeout=60)   # a regression here is a deadlock, not a failure
def test_callbacks_may_change_their_own_space_on_any_thread():
    # A callback runs on the worker thread that steps its space; it may
    # change that space's bodies (the thread guard lets the stepping thread
    # through) and the result equals stepping alone.
    calls = []

    def push(arbiter, space, data):
        calls.append(1)
        for shape in arbiter.shapes:
            if shape.body.body_type == tamias2d.Body.DYNAMIC:
                shape.body.angular_velocity = 0.25

    def make():
        s = scenes.circles_on_segment(tamias2d, count=6)
        s.on_collision(pre_solve=push)
        return s

    together = [make() for _ in range(6)]
    alone = [make() for _ in range(6)]
    tamias2d.step_spaces(together, 1 / 60, threads=3, steps=60)
    for s in alone:
        for _ in range(60):
            s.step(1 / 60)
    assert all(state(a) == state(b) for a, b in zip(together, alone))
    assert calls   # the callbacks ran (and changed bodies) on the workers
