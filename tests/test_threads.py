"""Stepping spaces on several threads.

``Space.step`` runs without the GIL, so spaces stepped by different threads
run at the same time on different cores. These tests check that this gives
exactly the same results as stepping the spaces one after the other (nothing
in the step shares mutable state between spaces), also with Python callbacks
(which take the GIL back) in one of the threads, and that the out-of-memory
flag of the C containers is per thread. No timing is asserted here; the
throughput is measured by benchmarks/bench_services.py.
"""
import threading

import pytest

import tamias2d
import tamias2d.batch
from tamias2d import _testing

import scenes

pytest.importorskip("numpy")   # the comparisons read bodies through tamias2d.batch

FIELDS = ("position", "angle", "velocity", "angular_velocity", "force", "torque")


def snapshot(space):
    arbs = tamias2d.batch.get_arbiters(space, ("count", "normal", "total_impulse", "distance"))
    return (tamias2d.batch.get_bodies(space, FIELDS).tobytes(),
            [b.is_sleeping for b in space.bodies],
            b"".join(arbs[f].tobytes() for f in arbs.dtype.names))


def run_in_threads(spaces, dt, steps, rounds=3):
    """Step each space in its own thread; all threads start together and
    meet again every `steps` steps (`rounds` times), so they overlap."""
    barrier = threading.Barrier(len(spaces))
    errors = []

    def work(space):
        try:
            for _ in range(rounds):
                barrier.wait()
                for _ in range(steps):
                    space.step(dt)
        except BaseException as e:  # reported by the test
            errors.append(e)
            barrier.abort()

    threads = [threading.Thread(target=work, args=(s,)) for s in spaces]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors


def run_serially(spaces, dt, steps, rounds=3):
    for space in spaces:
        for _ in range(rounds * steps):
            space.step(dt)


def test_two_threads_give_the_serial_results():
    rain = scenes.rain(tamias2d, count=400)
    pyramid = scenes.pyramid(tamias2d, rows=16)
    pyramid.sleep_time_threshold = 0.3
    for space in (rain, pyramid):
        for _ in range(30):
            space.step(1 / 60)
    threaded = [rain.copy(), pyramid.copy()]
    serial = [rain.copy(), pyramid.copy()]
    run_in_threads(threaded, 1 / 60, 100)
    run_serially(serial, 1 / 60, 100)
    for a, b in zip(threaded, serial):
        assert snapshot(a) == snapshot(b)
    assert any(b.is_sleeping for b in threaded[1].bodies)


def test_two_copies_of_one_scene_in_two_threads():
    base = scenes.rain(tamias2d, count=300)
    for _ in range(20):
        base.step(1 / 60)
    spaces = [base.copy() for _ in range(3)]
    run_in_threads(spaces[:2], 1 / 60, 80)
    run_serially(spaces[2:], 1 / 60, 80)
    assert snapshot(spaces[0]) == snapshot(spaces[2]) == snapshot(spaces[1])


def count_contacts(arbiter, space, data):
    space.contacts += len(arbiter.contact_point_set.points)


def test_callbacks_in_one_thread_do_not_disturb_the_other():
    base = scenes.circles_on_segment(tamias2d, count=40)
    base.contacts = 0
    with_cb = base.copy()
    with_cb.on_collision(post_solve=count_contacts)
    plain = scenes.pyramid(tamias2d, rows=12)
    ref_cb, ref_plain = with_cb.copy(), plain.copy()
    run_in_threads([with_cb, plain], 1 / 60, 60)
    run_serially([ref_cb, ref_plain], 1 / 60, 60)
    assert snapshot(with_cb) == snapshot(ref_cb)
    assert snapshot(plain) == snapshot(ref_plain)
    assert with_cb.contacts == ref_cb.contacts > 0


def test_out_of_memory_state_is_per_thread():
    # The allocation-failure hook and the out-of-memory flag are thread
    # locals: a thread armed to fail does not make another thread's
    # allocations fail, and each thread reads back its own flag.
    result = {}
    armed = threading.Event()
    done_main = threading.Event()

    def worker():
        _testing._set_alloc_failure(0)       # this thread's next allocation fails
        armed.set()
        done_main.wait(10)
        try:
            tamias2d.Space()
        except MemoryError:
            result["worker"] = "MemoryError"
        finally:
            _testing._set_alloc_failure(-1)
        result["worker flag"] = _testing._take_out_of_memory()

    t = threading.Thread(target=worker)
    t.start()
    armed.wait(10)
    try:
        space = scenes.pyramid(tamias2d, rows=5)     # many allocations, none fails
        space.step(1 / 60)
        result["main"] = "ok"
    finally:
        done_main.set()
        t.join()
    assert result == {"main": "ok", "worker": "MemoryError", "worker flag": False}
    assert not _testing._take_out_of_memory()


# -- one space, two threads ------------------------------------------------------------------
# While a space steps in one thread (without the GIL), a second thread that
# touches the space or its bodies, shapes and joints waits for the step to
# end (src/tamias2d/_threadguard.pxd). Each test hammers one kind of access
# from a second thread for a while and then checks that the space is sound:
# a consistent contact graph, still able to step and to take new objects.
# Before the guard, each of these crashed, corrupted the heap or left the
# space locked forever; they run in a child process so a crash is a failure.

import time

from isolated import isolated

HAMMER_SECONDS = 1.0


def sleepy_pile(use_spatial_hash=False, sleeping=True):
    """Columns of boxes on the ground that fall asleep quickly (or, with
    sleeping=False, stay awake so that every step does the full work)."""
    s = tamias2d.Space()
    s.gravity = 0, -900
    s.sleep_time_threshold = 0.05
    if use_spatial_hash:
        s.use_spatial_hash(20, 2000)
    ground = tamias2d.Segment(s.static_body, (-1000, 0), (1000, 0), 2)
    ground.friction = 1
    s.add(ground)
    bodies = []
    # Enough work per step (iterations, bodies) that the second thread gets
    # the GIL many times while a step is under way.
    s.iterations = 40
    for col in range(40):
        for row in range(8):
            b = tamias2d.Body(1, tamias2d.moment_for_box(1, (10, 10)))
            b.position = -800 + col * 40, 6 + row * 11
            box = tamias2d.Poly.create_box(b, (10, 10))
            box.friction = 1
            s.add(b, box)
            bodies.append(b)
    for _ in range(120):
        s.step(1 / 60)
    if not sleeping:
        s.sleep_time_threshold = float("inf")
    return s, bodies


def hammer(space, action):
    """Run action(i) in a second thread while this thread steps `space`."""
    stop = threading.Event()
    errors = []
    count = [0]

    def work():
        i = 0
        try:
            while not stop.is_set():
                action(i)
                i += 1
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)
        count[0] = i

    t = threading.Thread(target=work)
    t.start()
    steps = 0
    deadline = time.monotonic() + HAMMER_SECONDS
    try:
        while time.monotonic() < deadline and t.is_alive():
            space.step(1 / 60)
            steps += 1
    finally:
        stop.set()
        t.join()
    if errors:
        raise errors[0]
    assert steps > 0 and count[0] > 0


def check_sound(space):
    assert space._contact_graph_problem() is None
    for _ in range(30):
        space.step(1 / 60)
    assert space._contact_graph_problem() is None
    b = tamias2d.Body(1, 1)
    space.add(b, tamias2d.Circle(b, 1))   # not left locked
    space.step(1 / 60)


@isolated(timeout=120)
def test_waking_bodies_from_a_second_thread_while_stepping():
    s, bodies = sleepy_pile()
    assert any(b.is_sleeping for b in bodies)

    def wake(i):
        b = bodies[(i * 7) % len(bodies)]
        op = i % 9
        if op == 0:
            b.activate()
        elif op == 1:
            b.velocity = (0, 1)
        elif op == 2:
            b.position = b.position
        elif op == 3:
            b.mass = 1
        elif op == 4:
            next(iter(b.shapes)).friction = 1
        elif op == 5:
            next(iter(b.shapes)).filter = tamias2d.ShapeFilter()
        elif op == 6:
            b.apply_impulse_at_local_point((0, 1))
        elif op == 7:
            s.gravity = (0, -900)
        else:
            s.sleep_time_threshold = 0.05

    hammer(s, wake)
    check_sound(s)


@pytest.mark.parametrize("use_spatial_hash", [False, True])
def test_queries_from_a_second_thread_while_stepping(use_spatial_hash):
    @isolated(timeout=120)
    def run():
        s, bodies = sleepy_pile(use_spatial_hash, sleeping=False)
        probe = tamias2d.Circle(None, 30)
        probe.update(tamias2d.Transform.translation(0, 30))
        f = tamias2d.ShapeFilter()

        def query(i):
            op = i % 5
            if op == 0:
                s.point_query((i % 800 - 400, 20), 15, f)
            elif op == 1:
                s.bb_query(tamias2d.BB(-100, 0, 100, 60), f)
            elif op == 2:
                s.segment_query((-500, 30), (500, 30), 1, f)
            elif op == 3:
                s.segment_query_first((-500, 30), (500, 30), 1, f)
            else:
                s.point_query_nearest((0, 20), 50, f)

        hammer(s, query)
        check_sound(s)

    run()


@isolated(timeout=120)
def test_new_vertices_from_a_second_thread_while_stepping():
    s, bodies = sleepy_pile(sleeping=False)
    polys = [next(iter(b.shapes)) for b in bodies]
    # Polygons with more than a few vertices keep them on the heap: each
    # change of count reallocates them under the narrow phase's feet.
    import math
    shapes = [[(5.5 * math.cos(2 * math.pi * k / n), 5.5 * math.sin(2 * math.pi * k / n))
               for k in range(n)] for n in (3, 9, 16)]

    def reshape(i):
        polys[(i * 13) % len(polys)].unsafe_set_vertices(shapes[i % 3])

    hammer(s, reshape)
    check_sound(s)


@isolated(timeout=60)
def test_a_second_thread_waits_for_the_step_to_end():
    # The step's pre-solve callback (run by the stepping thread) releases
    # the GIL for a while; a second thread's setter issued meanwhile must not
    # complete until the step is over, and the callback's own accesses go
    # through at once.
    s = tamias2d.Space()
    s.gravity = 0, -100
    ball = tamias2d.Body(1, 10)
    ball.position = 0, 4
    s.add(ball, tamias2d.Circle(ball, 5), tamias2d.Segment(s.static_body, (-50, 0), (50, 0), 1))
    inside = threading.Event()
    in_callback = [False]
    seen = []

    def pre_solve(arbiter, space, data):
        in_callback[0] = True
        ball.angular_velocity = 0.5    # the stepping thread itself: no wait
        inside.set()
        time.sleep(0.3)                # releases the GIL
        in_callback[0] = False

    s.on_collision(pre_solve=pre_solve)

    def other():
        inside.wait(10)
        ball.velocity = 1, 0           # waits for the step
        seen.append(in_callback[0])

    t = threading.Thread(target=other)
    t.start()
    s.step(1 / 60)
    t.join()
    assert seen == [False]
    assert ball.velocity == (1, 0)


def test_two_threads_stepping_one_space_take_turns():
    # A second step() of the same space waits for the first instead of
    # running into it; the results equal two steps in a row.
    base = scenes.pyramid(tamias2d, rows=10)
    for _ in range(10):
        base.step(1 / 60)
    a, b = base.copy(), base.copy()
    threads = [threading.Thread(target=lambda: [a.step(1 / 60) for _ in range(20)])
               for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for _ in range(40):
        b.step(1 / 60)
    assert snapshot(a) == snapshot(b)


# -- one soft step on several threads (Space(threaded=True), threads = 2) --------------------

def _soft(build, threads):
    space = build()
    space.solver = "soft"
    space.threaded = True
    space.threads = threads
    return space


def _big_pyramid():
    # Enough bodies and contacts per colour that the stages are shared out.
    return scenes.pyramid(tamias2d, rows=50)


def _run(space, steps):
    hook = getattr(space, "scene_hook", None)
    for i in range(steps):
        if hook is not None:
            hook(i)
        space.step(1 / 60)
    return snapshot(space)


@pytest.mark.parametrize("build", [_big_pyramid, lambda: scenes.rain(tamias2d, count=2500)],
                         ids=["pyramid", "rain"])
def test_soft_step_on_two_threads_gives_the_one_thread_bits(build):
    from tamias2d import _soft_step
    one = _run(_soft(build, 1), 90)
    stages = _soft_step._pool_state()[1]
    two = _run(_soft(build, 2), 90)
    assert _soft_step._pool_state()[0] == 1            # the worker runs
    assert _soft_step._pool_state()[1] > stages         # and stages were shared out
    assert one == two


def test_threaded_soft_step_with_sensors_and_a_handler_gives_the_one_thread_bits():
    # On threads the arbiters the narrow phase updated are pushed from
    # packed flags, their contacts written where they stay by the narrow
    # phase (room placed for each pair before it); a sensor's arbiter
    # is updated but not solved (no contacts, not in space.arbiters). With
    # a begin handler every pair goes through the one serial pass instead.
    def with_sensors():
        space = _big_pyramid()
        for i, shape in enumerate(space.shapes):
            if i % 5 == 3:
                shape.sensor = True
        return space

    def with_handler():
        space = with_sensors()
        seen = []
        space.on_collision(begin=lambda arbiter, space, data: seen.append(1))
        return space
    for build in (with_sensors, with_handler):
        assert _run(_soft(build, 1), 60) == _run(_soft(build, 2), 60)


def test_threaded_soft_step_with_python_integrators_and_joints():
    # A Python velocity_func runs its stage on the calling thread only; the
    # joints are solved there too. Same bits as one thread.
    def build():
        space = _big_pyramid()
        bodies = list(space.bodies)

        def drag(body, gravity, damping, dt):
            tamias2d.Body.update_velocity(body, gravity, 0.999 * damping, dt)

        bodies[7].velocity_func = drag
        space.add(tamias2d.PinJoint(bodies[-1], bodies[-2]))
        return space
    assert _run(_soft(build, 1), 60) == _run(_soft(build, 2), 60)


def test_two_threaded_soft_spaces_stepped_at_once():
    # The worker serves one step at a time; the other space's step runs on
    # its own thread. Both end where stepping them alone ends.
    spaces = [_soft(_big_pyramid, 2) for _ in range(2)]
    alone = [_soft(_big_pyramid, 1) for _ in range(2)]
    run_in_threads(spaces, 1 / 60, 20)
    run_serially(alone, 1 / 60, 20)
    assert [snapshot(s) for s in spaces] == [snapshot(s) for s in alone]


def test_threads_survive_copy_and_pickle_and_the_copy_continues_alike():
    import copy
    import pickle
    space = _soft(_big_pyramid, 2)
    _run(space, 30)
    for twin in (space.copy(), copy.deepcopy(space), pickle.loads(pickle.dumps(space))):
        assert twin.threaded and twin.threads == 2
        twin.threads = 1
        assert _run(twin, 30) == _run(space.copy(), 30)


def test_threads_of_a_space_that_is_not_threaded_stay_one():
    space = _soft(_big_pyramid, 2)
    assert space.threads == 2
    plain = tamias2d.Space(solver="soft")
    plain.threads = 2
    assert plain.threads == 1
