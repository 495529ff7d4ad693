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
