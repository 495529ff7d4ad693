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


def test_an_exception_in_a_callback_stops_its_space_and_the_others_run_all_steps():
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
    assert info.value.steps_done == 1
    assert any("spaces[2]" in note and "1 of its 5 steps" in note
               for note in getattr(info.value, "__notes__", ["spaces[2] 1 of its 5 steps"]))
    for i, (s, r) in enumerate(zip(spaces, refs)):
        for _ in range(1 if i == 2 else 5):   # the failing space stopped after its first step
            r.step(1 / 60)
        assert state(s) == state(r)
    spaces[2].on_collision(post_solve=tamias2d.empty_callback)
    tamias2d.step_spaces(spaces, 1 / 60)  # consistent and steppable


def test_two_failing_spaces_raise_the_first_and_name_the_other():
    spaces = [scenes.circles_on_segment(tamias2d, count=3) for _ in range(5)]
    for _ in range(40):
        for s in spaces:
            s.step(1 / 60)

    def boom(arbiter, space, data):
        raise KeyError(space.boom)

    for k in (3, 1):
        spaces[k].boom = k
        spaces[k].on_collision(pre_solve=boom)
    with pytest.raises(KeyError) as info:
        tamias2d.step_spaces(spaces, 1 / 60, threads=2, steps=3)
    assert info.value.space_index == 1 and info.value.args == (1,)
    if hasattr(info.value, "__notes__"):
        assert any("spaces[3] (KeyError)" in note for note in info.value.__notes__)
    assert all(s.current_time_step == 1 / 60 for s in spaces)


def test_python_work_between_steps_runs_on_the_worker_as_in_serial_steps():
    # Post-step callbacks and removals deferred by a callback happen between
    # two steps of the same call, as between two calls of Space.step.
    def drop(space, body, shape):
        space.remove(body, shape)

    def make():
        s = scenes.circles_on_segment(tamias2d, count=6)
        s.log = []

        def begin(arbiter, space, data):
            for shape in arbiter.shapes:
                if shape.body.body_type == tamias2d.Body.DYNAMIC and len(space.log) < 3:
                    space.log.append(round(shape.body.position.x, 9))
                    space.add_post_step_callback(drop, shape.body, shape)

        s.on_collision(begin=begin)
        return s

    together = [make() for _ in range(4)]
    alone = [make() for _ in range(4)]
    tamias2d.step_spaces(together, 1 / 60, threads=2, steps=90)
    for s in alone:
        for _ in range(90):
            s.step(1 / 60)
    for a, b in zip(together, alone):
        assert a.log == b.log and len(a.log) == 3
        assert len(a.bodies) == len(b.bodies) == 3
        assert state(a) == state(b)


def test_a_mass_made_bad_by_a_callback_stops_that_space_at_the_next_step():
    spaces = [scenes.circles_on_segment(tamias2d, count=3) for _ in range(3)]

    def zero_mass(arbiter, space, data):
        for shape in arbiter.shapes:
            if shape.body.body_type == tamias2d.Body.DYNAMIC:
                shape.body.moment = 0     # a later step must refuse it
                return

    spaces[1].on_collision(begin=zero_mass)
    with pytest.raises(IllegalBody) as info:
        tamias2d.step_spaces(spaces, 1 / 60, threads=2, steps=120)
    assert info.value.space_index == 1
    done = info.value.steps_done
    assert 0 < done < 120 and spaces[1].current_time_step == 1 / 60
    assert spaces[0].current_time_step == spaces[2].current_time_step == 1 / 60


def test_out_of_memory_is_reported_for_the_space_that_ran_out():
    # Empty spaces stepped a few times allocate nothing more; the first step
    # of a scene with contacts does. The C flag is per thread (so is the
    # failure hook: one thread here); it must come out as the MemoryError of
    # the space that ran out, not of the first space finished.
    from tamias2d._testing import _set_alloc_failure
    quiet = [tamias2d.Space() for _ in range(2)]
    tamias2d.step_spaces(quiet, 1 / 60, threads=1, steps=10)
    spaces = quiet + [scenes.pyramid(tamias2d, rows=4)]
    _set_alloc_failure(0, 1_000_000)
    try:
        with pytest.raises(MemoryError) as info:
            tamias2d.step_spaces(spaces, 1 / 60, threads=1)
    finally:
        _set_alloc_failure(-1)
    assert info.value.space_index == 2
    tamias2d.step_spaces(spaces, 1 / 60, threads=2)   # no flag left behind


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


def test_many_quick_calls_with_changing_thread_counts():
    # Thousands of short calls: workers that wake late (or not at all), join
    # the next call or find it over; every call must still step each space
    # exactly once per step, on no more threads than it asked for.
    seen_threads = set()
    import threading

    def note_thread(arbiter, space, data):
        seen_threads.add((space.call_threads, threading.get_ident()))

    def make():
        s = scenes.circles_on_segment(tamias2d, count=2)
        s.call_threads = 0
        return s

    together = [make() for _ in range(6)]
    alone = [make() for _ in range(6)]
    together[0].on_collision(pre_solve=note_thread)
    alone[0].on_collision(pre_solve=note_thread)
    counts = [1, 2, 3, 2, 1, 4]
    for k in range(3000):
        threads = counts[k % len(counts)]
        for s in together:
            s.call_threads = threads
        tamias2d.step_spaces(together, 1 / 240, threads=threads, steps=1 + k % 3)
    for k in range(3000):
        for s in alone:
            for _ in range(1 + k % 3):
                s.step(1 / 240)
    assert all(state(a) == state(b) for a, b in zip(together, alone))
    main = threading.get_ident()
    assert {t for n, t in seen_threads if n == 1} <= {main}   # threads=1: the caller only


@isolated(timeout=60)   # a regression here is a deadlock
def test_a_callback_may_step_other_spaces_with_step_spaces():
    # The pool is busy with the outer call: the inner one runs on the
    # callback's own thread, whichever thread that is.
    inner = [[scenes.circles_on_segment(tamias2d, count=2) for _ in range(3)] for _ in range(4)]
    inner_alone = [[scenes.circles_on_segment(tamias2d, count=2) for _ in range(3)]
                   for _ in range(4)]

    def make(k):
        s = scenes.circles_on_segment(tamias2d, count=3)
        s.k = k

        def post(arbiter, space, data):
            tamias2d.step_spaces(inner[space.k], 1 / 60, threads=2)

        s.on_collision(post_solve=post)
        return s

    outer = [make(k) for k in range(4)]
    tamias2d.step_spaces(outer, 1 / 60, threads=2, steps=120)
    # The reference: the outer spaces alone, counting their post-solve
    # calls; then as many steps of each inner group.
    ref = [make(k) for k in range(4)]
    counted = [0] * 4

    def count(arbiter, space, data):
        counted[space.k] += 1

    for s in ref:
        s.on_collision(post_solve=count)
        for _ in range(120):
            s.step(1 / 60)
    for k in range(4):
        assert counted[k] > 0
        for _ in range(counted[k]):
            tamias2d.step_spaces(inner_alone[k], 1 / 60, threads=1)
        assert [state(a) for a in inner[k]] == [state(b) for b in inner_alone[k]]
    assert [state(a) for a in outer] == [state(b) for b in ref]
