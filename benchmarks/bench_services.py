"""Space services against pymunk, in the same process: copy, pickle and
unpickle of a 1,000-body space, and stepping on several threads.

Scene: 1,000 circles falling into an open box (tests/scenes.py ``rain``),
built the same way in both engines and stepped ``--warmup`` steps first, so
that contacts, cached arbiters and a grown broad phase exist.

1. Copy and pickle. Each operation is timed ``--repeat`` times, alternating
   which engine goes first; the median is printed with the ratio pymunk /
   tamias2d (above 1: tamias2d is faster). tamias2d's copies carry the whole
   C state (they step on bit for bit); pymunk's re-add the objects.

2. Threads. ``--steps`` steps of one space on one thread, against two spaces
   (copies of it) stepped at the same time on two threads. The throughput
   ratio is 2 * t(one space) / t(two spaces in two threads): 2.0 is perfect
   scaling on two cores, 1.0 no gain. Measured for tamias2d (the step runs
   without the GIL) and for pymunk stepped from two Python threads. pymunk's
   own threaded solver (``Space(threaded=True)``, ``threads=2``, one space)
   is timed against ``threads=1`` too. The machine may be shared: the
   blocks are repeated (engines taking turns) and medians reported, with the
   load average, the process's CPU time over wall time in the two-thread
   runs (above 1 only when the threads really ran at the same time), and the
   same ratio for two processes (each stepping its own space): the parallel
   capacity the machine gave at that time, which no thread can beat.

    PYTHONPATH=src:. python benchmarks/bench_services.py [--bodies N] [--repeat R]
        [--steps K] [--warmup W] [--only copy|threads] [--json out.json]
"""
import argparse
import copy
import json
import multiprocessing
import os
import pickle
import platform
import statistics
import sys
import threading
import time

import pymunk
import tamias2d

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
import scenes  # noqa: E402

DT = 1.0 / 60.0


def build(mod, bodies, warmup):
    space = scenes.rain(mod, count=bodies)
    for _ in range(warmup):
        space.step(DT)
    return space


def _load():
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:  # pragma: no cover - not on every platform
        return "n/a"


def timed(f, *args):
    t0 = time.perf_counter()
    result = f(*args)
    return time.perf_counter() - t0, result


def bench_copy_pickle(spaces, repeat):
    ops = {
        "copy()": lambda s: s.copy(),
        "copy.deepcopy": lambda s: copy.deepcopy(s),
        "pickle.dumps": lambda s: pickle.dumps(s, protocol=pickle.HIGHEST_PROTOCOL),
    }
    data = {name: pickle.dumps(s, protocol=pickle.HIGHEST_PROTOCOL) for name, s in spaces.items()}
    times = {(op, eng): [] for op in list(ops) + ["pickle.loads"] for eng in spaces}
    engines = list(spaces)
    for r in range(repeat):
        for eng in engines if r % 2 == 0 else engines[::-1]:
            for op, f in ops.items():
                times[(op, eng)].append(timed(f, spaces[eng])[0])
            times[("pickle.loads", eng)].append(timed(pickle.loads, data[eng])[0])
    rows = []
    for op in list(ops) + ["pickle.loads"]:
        p = statistics.median(times[(op, "pymunk")])
        t = statistics.median(times[(op, "tamias2d")])
        rows.append({"operation": op, "pymunk_s": p, "tamias2d_s": t, "ratio": p / t})
    sizes = {eng: len(d) for eng, d in data.items()}
    return rows, sizes


def check_copies_step_on(space, steps=30):
    """tamias2d's copy and pickle continue exactly as the original (the
    benchmark times the real thing)."""
    copies = [space.copy(), pickle.loads(pickle.dumps(space))]
    ref = space.copy()
    for _ in range(steps):
        for s in [ref] + copies:
            s.step(DT)
    want = [(b.position, b.velocity) for b in ref.bodies]
    return all([(b.position, b.velocity) for b in c.bodies] == want for c in copies)


def steps_of(space, steps):
    step = space.step
    for _ in range(steps):
        step(DT)


def in_threads(spaces, steps):
    barrier = threading.Barrier(len(spaces) + 1)

    def work(s):
        barrier.wait()
        steps_of(s, steps)

    threads = [threading.Thread(target=work, args=(s,)) for s in spaces]
    for t in threads:
        t.start()
    barrier.wait()
    t0 = time.perf_counter()
    c0 = time.process_time()
    for t in threads:
        t.join()
    return time.perf_counter() - t0, time.process_time() - c0


def _child_steps(data, steps, barrier, out):
    space = pickle.loads(data)
    barrier.wait()
    t0 = time.perf_counter()
    steps_of(space, steps)
    out.put(time.perf_counter() - t0)


def in_processes(data, steps):
    """Two processes, each stepping its own copy of the pickled space from a
    common start: how much parallel capacity the machine gives right now."""
    ctx = multiprocessing.get_context("fork")
    barrier = ctx.Barrier(2)
    out = ctx.Queue()
    procs = [ctx.Process(target=_child_steps, args=(data, steps, barrier, out)) for _ in range(2)]
    for p in procs:
        p.start()
    times = [out.get() for _ in procs]
    for p in procs:
        p.join()
    return max(times)


def bench_threads(makers, steps, repeat, process_data=None):
    """Per engine: median one-thread time, two-thread time and throughput
    ratio. The engines take turns in every repeat, so both see the same
    machine load."""
    out = {name: {"ones": [], "twos": [], "ratios": [], "cpu": []} for name in makers}
    procs = []
    names = list(makers)
    for r in range(repeat):
        if process_data is not None:
            # The machine's parallel capacity at this moment: the same work in
            # two processes, against one.
            a = pickle.loads(process_data)
            t1, _ = timed(steps_of, a, steps)
            procs.append(2 * t1 / in_processes(process_data, steps))
        for name in names if r % 2 == 0 else names[::-1]:
            a, b, c = makers[name]()
            t1, _ = timed(steps_of, a, steps)
            t2, cpu2 = in_threads([b, c], steps)
            out[name]["ones"].append(t1)
            out[name]["twos"].append(t2)
            out[name]["ratios"].append(2 * t1 / t2)
            # CPU time of the process over wall time: above 1 only if the two
            # threads ran at the same moment (not possible under the GIL).
            out[name]["cpu"].append(cpu2 / t2)
    result = {name: {"one_space_one_thread_s": statistics.median(v["ones"]),
                     "two_spaces_two_threads_s": statistics.median(v["twos"]),
                     "throughput_ratio": statistics.median(v["ratios"]),
                     "cpu_over_wall_two_threads": statistics.median(v["cpu"]),
                     "ratios": v["ratios"]} for name, v in out.items()}
    if procs:
        result["processes"] = {"throughput_ratio": statistics.median(procs), "ratios": procs}
    return result


def pymunk_hasty(bodies, warmup, steps, repeat):
    """pymunk's threaded space (one space, its solver on 1 or 2 threads)."""
    if platform.system() == "Windows":
        return None
    results = {}
    for threads in (1, 2):
        times = []
        for _ in range(repeat):
            # The rain scene moved into a threaded space through its state.
            state = scenes.rain(pymunk, count=bodies).__getstate__()
            state["init"] = [("threaded", True)]
            state["general"] = [(k, v) for k, v in state["general"] if k != "threads"]
            state["custom"] = [(k, v) for k, v in state["custom"] if k != "threaded"]
            space = pymunk.Space.__new__(pymunk.Space)
            space.__setstate__(copy.deepcopy(state))
            space.threads = threads
            assert space.threaded and space.threads == threads
            for _ in range(warmup):
                space.step(DT)
            times.append(timed(steps_of, space, steps)[0])
        results[threads] = statistics.median(times)
    return {"threads_1_s": results[1], "threads_2_s": results[2],
            "speedup": results[1] / results[2]}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bodies", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--steps", type=int, default=120)
    ap.add_argument("--warmup", type=int, default=120)
    ap.add_argument("--only", choices=("copy", "threads"), help="run one part only")
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args(argv)

    spaces = {"pymunk": build(pymunk, args.bodies, args.warmup),
              "tamias2d": build(tamias2d, args.bodies, args.warmup)}
    results = {"bodies": args.bodies, "warmup": args.warmup, "repeat": args.repeat,
               "steps": args.steps, "cpus": os.cpu_count(),
               "python": platform.python_version(), "pymunk": pymunk.version,
               "tamias2d": tamias2d.version}
    print(f"rain scene, {args.bodies} bodies after {args.warmup} steps; "
          f"median of {args.repeat}; {os.cpu_count()} CPUs; load average {_load()}")
    print(f"tamias2d copies step on bit for bit: {check_copies_step_on(spaces['tamias2d'])}")

    if args.only != "threads":
        bench_copy_part(spaces, args, results)
    if args.only != "copy":
        bench_threads_part(spaces, args, results)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)
    return results


def bench_copy_part(spaces, args, results):
    rows, sizes = bench_copy_pickle(spaces, args.repeat)
    results["copy_pickle"] = rows
    results["pickle_bytes"] = sizes
    print(f"\n{'operation':16s} {'pymunk':>10s} {'tamias2d':>10s} {'pymunk/tamias2d':>16s}")
    for r in rows:
        print(f"{r['operation']:16s} {r['pymunk_s'] * 1e3:8.1f}ms {r['tamias2d_s'] * 1e3:8.2f}ms "
              f"{r['ratio']:15.1f}x")
    print(f"pickle size: pymunk {sizes['pymunk'] / 1e3:.0f} kB, "
          f"tamias2d {sizes['tamias2d'] / 1e3:.0f} kB")


def bench_threads_part(spaces, args, results):
    tam = spaces["tamias2d"]
    makers = {
        "tamias2d": lambda: (tam.copy(), tam.copy(), tam.copy()),
        # (pymunk's copies are slow to make: its three spaces are built instead.)
        "pymunk": lambda: tuple(build(pymunk, args.bodies, args.warmup) for _ in range(3)),
    }
    both = bench_threads(makers, args.steps, args.repeat, pickle.dumps(tam))
    results["threads_tamias2d"] = both["tamias2d"]
    results["threads_pymunk"] = both["pymunk"]
    results["two_processes_tamias2d"] = both.get("processes")
    results["load_average_after"] = _load()
    print(f"\nload average after the thread runs: {results['load_average_after']} (other "
          f"processes on the machine take cores from the two threads)")
    print(f"\n{'stepping ' + str(args.steps) + ' steps':30s} {'1 space/1 thread':>17s} "
          f"{'2 spaces/2 threads':>19s} {'throughput ratio':>17s}")
    for eng in ("tamias2d", "pymunk"):
        r = results["threads_" + eng]
        print(f"{eng + ' (Python threads)':30s} {r['one_space_one_thread_s']:16.3f}s "
              f"{r['two_spaces_two_threads_s']:18.3f}s {r['throughput_ratio']:17.2f}")
        print(f"{'':30s} ratios: " + " ".join(f"{x:.2f}" for x in r["ratios"]))
        print(f"{'':30s} CPU time / wall time with two threads: "
              f"{r['cpu_over_wall_two_threads']:.2f}")
    if results["two_processes_tamias2d"]:
        r = results["two_processes_tamias2d"]
        print(f"{'tamias2d (two processes)':30s} throughput ratio {r['throughput_ratio']:.2f}: "
              f"what the machine allowed at the time")
        print(f"{'':30s} ratios: " + " ".join(f"{x:.2f}" for x in r["ratios"]))
    try:
        hasty = pymunk_hasty(args.bodies, args.warmup, args.steps, max(3, args.repeat // 3))
    except Exception as e:  # pymunk without its threaded space
        hasty = None
        print(f"pymunk threaded space: not available ({e!r})")
    results["pymunk_threaded_space"] = hasty
    if hasty:
        print(f"{'pymunk Space(threaded=True)':30s} threads=1 {hasty['threads_1_s']:.3f}s, "
              f"threads=2 {hasty['threads_2_s']:.3f}s, speedup {hasty['speedup']:.2f}")


if __name__ == "__main__":
    main()
