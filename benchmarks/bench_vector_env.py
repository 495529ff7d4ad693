"""Throughput of many small scenes: the pushing environment of
examples/vector_env.py (64 scenes by default, 5 physics steps per env step,
random actions) run five ways, and the per-space cost of step_spaces.

Environment steps per second of:

- ``SyncVectorEnv``: Gymnasium's loop over single-scene envs (``PushEnv``),
  Python for every scene;
- ``Python loop``: ``PushVectorEnv`` with its batch reads and writes, the
  scenes stepped by a Python loop over ``space.step``;
- ``step_spaces, 1 thread`` and ``2 threads``: ``PushVectorEnv`` as it is;
- ``AsyncVectorEnv``: Gymnasium's subprocess vector env, one process per
  ``PushEnv`` (as Gymnasium runs it).

The Gymnasium rows need gymnasium (the ``bench`` extra) and are left out
without it. Then the per-space overhead of ``step_spaces`` against a bare C
loop of the same steps (``tamias2d._testing._step_spaces_c``), for the push
scene and for empty spaces, one step and five steps per call.

Rounds alternate between the variants; the median of `--repeat` rounds is
reported. The machine may be shared: the load average before and after is
printed beside the figures.

    PYTHONPATH=src python benchmarks/bench_vector_env.py [--envs 64] [--frames 200] [--repeat 5] [--no-async]
"""
import argparse
import importlib.util
import os
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "examples"))

import tamias2d  # noqa: E402
from tamias2d._testing import _step_spaces_c  # noqa: E402

import vector_env as V  # noqa: E402

HAVE_GYM = importlib.util.find_spec("gymnasium") is not None


class LoopPushVectorEnv(V.PushVectorEnv):
    """PushVectorEnv stepping its scenes with a Python loop over space.step."""

    def _physics(self, spaces):
        for space in spaces:
            for _ in range(self.frame_skip):
                space.step(V.DT)


def actions(envs, frames, seed=1):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, (frames, envs, 2)).astype(np.float32)


def run_env(env, acts):
    env.reset(seed=0)
    t0 = time.perf_counter()
    for a in acts:
        env.step(a)
    return time.perf_counter() - t0


def variants(n, args):
    out = {}
    if HAVE_GYM:
        import gymnasium
        out["SyncVectorEnv (Python per scene)"] = lambda: gymnasium.vector.SyncVectorEnv(
            [V.PushEnv for _ in range(n)])
    out["Python loop over space.step"] = lambda: LoopPushVectorEnv(n)
    out["step_spaces, 1 thread"] = lambda: V.PushVectorEnv(n, threads=1)
    out["step_spaces, 2 threads"] = lambda: V.PushVectorEnv(n, threads=2)
    if HAVE_GYM and not args.no_async:
        import gymnasium
        out[f"AsyncVectorEnv ({n} processes)"] = lambda: gymnasium.vector.AsyncVectorEnv(
            [V.PushEnv for _ in range(n)])
    return out


def overhead(n, repeat):
    """Microseconds per space-step: step_spaces (1 thread) minus the bare C loop."""
    rows = []
    env = V.PushVectorEnv(n, threads=1)
    env.reset(seed=0)
    for a in actions(n, 20):            # under way, with contacts
        env.step(a)
    for label, spaces in (("push scene", env.spaces),
                          ("empty space", [tamias2d.Space() for _ in range(n)])):
        for steps in (1, 5):
            calls = max(1, 200 // steps)
            ts, tc = [], []
            for _ in range(repeat):
                t0 = time.perf_counter()
                for _ in range(calls):
                    tamias2d.step_spaces(spaces, V.DT, threads=1, steps=steps)
                ts.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                for _ in range(calls):
                    _step_spaces_c(spaces, V.DT, steps)
                tc.append(time.perf_counter() - t0)
            per = 1e6 / (calls * steps * n)
            s, c = statistics.median(ts) * per, statistics.median(tc) * per
            rows.append((label, steps, s, c))
    return rows, batch_io(env, repeat)


def batch_io(env, repeat, calls=500):
    """Microseconds per call: reading and writing the bodies of all the
    scenes with the across-spaces batch calls, and with a loop of the
    one-space calls."""
    import tamias2d.batch as B
    spaces, rows = env.spaces, env._rows
    vel = np.ascontiguousarray(rows[:, 3:5])
    offsets = B.get_spaces_bodies(spaces, V.FIELDS)[1]

    def loop_get():
        for i, s in enumerate(spaces):
            B.get_bodies(s, V.FIELDS, rows[offsets[i]:offsets[i + 1]])

    def loop_set():
        for i, s in enumerate(spaces):
            B.set_bodies(s, vel[offsets[i]:offsets[i + 1]], "velocity")

    cases = {"get_spaces_bodies": lambda: B.get_spaces_bodies(spaces, V.FIELDS, out=rows),
             "loop of get_bodies": loop_get,
             "set_spaces_bodies": lambda: B.set_spaces_bodies(spaces, vel, "velocity"),
             "loop of set_bodies": loop_set}
    out = {}
    for name, fn in cases.items():
        ts = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            for _ in range(calls):
                fn()
            ts.append(time.perf_counter() - t0)
        out[name] = statistics.median(ts) / calls * 1e6
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--envs", type=int, default=64)
    ap.add_argument("--frames", type=int, default=200, help="env steps per round")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--no-async", action="store_true", help="leave AsyncVectorEnv out")
    args = ap.parse_args(argv)
    n = args.envs
    load0 = os.getloadavg()
    acts = actions(n, args.frames)
    makers = variants(n, args)
    envs = {name: make() for name, make in makers.items()}
    for env in envs.values():          # warm up (imports, worker pool, processes)
        run_env(env, acts[:5])
    times = {name: [] for name in envs}
    for _ in range(args.repeat):
        for name, env in envs.items():
            times[name].append(run_env(env, acts))
    for env in envs.values():
        env.close()
    rows, io = overhead(n, args.repeat)
    load1 = os.getloadavg()
    work = n * args.frames
    print(f"{n} push scenes x {args.frames} env steps ({V.FRAME_SKIP} physics steps each), "
          f"random actions, median of {args.repeat}; load average {load0[0]:.2f} before, "
          f"{load1[0]:.2f} after, {os.cpu_count()} cores")
    one = statistics.median(times["step_spaces, 1 thread"])
    for name in envs:
        t = statistics.median(times[name])
        print(f"  {name:34s} {work / t:10.0f} env steps/s   x{one / t:5.2f} of 1 thread")
    if not HAVE_GYM:
        print("  (gymnasium is not installed: no SyncVectorEnv / AsyncVectorEnv rows)")
    print("per-space cost of step_spaces (1 thread) against the bare C loop, us per space-step:")
    for label, steps, s, c in rows:
        print(f"  {label:12s} steps={steps}:  step_spaces {s:6.2f}   C loop {c:6.2f}   "
              f"overhead {s - c:5.2f}")
    print(f"reading and writing the bodies of the {n} scenes ({2 * n} bodies), us per call:")
    for name, us in io.items():
        print(f"  {name:20s} {us:8.1f}")


if __name__ == "__main__":
    main()
