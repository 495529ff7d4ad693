"""Many small scenes stepped at once: a Python loop over ``space.step``
against ``tamias2d.step_spaces`` on 1 and 2 threads.

64 copies of a small scene (a 6-row pyramid of boxes, sleeping off) are
stepped `--steps` steps per round; rounds alternate between the variants and
the median of `--repeat` rounds is reported, in scene-steps per second, with
the speedups, and the best round of each (on a shared machine the best
rounds are those least disturbed). The load average before and after is
printed beside the figures.

    PYTHONPATH=src:tests python benchmarks/bench_step_spaces.py [--scenes 64] [--steps 60] [--repeat 9]
"""
import argparse
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))

import tamias2d  # noqa: E402
import scenes  # noqa: E402


def make(n):
    base = scenes.pyramid(tamias2d, rows=6)
    for _ in range(30):
        base.step(1 / 60)
    return [base.copy() for _ in range(n)]


def loop(spaces, steps):
    for _ in range(steps):
        for s in spaces:
            s.step(1 / 60)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=64)
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--repeat", type=int, default=9)
    args = ap.parse_args(argv)
    variants = {
        "Python loop": lambda sp: loop(sp, args.steps),
        "step_spaces, 1 thread": lambda sp: tamias2d.step_spaces(sp, 1 / 60, threads=1,
                                                                 steps=args.steps),
        "step_spaces, 2 threads": lambda sp: tamias2d.step_spaces(sp, 1 / 60, threads=2,
                                                                  steps=args.steps),
    }
    times = {k: [] for k in variants}
    load0 = os.getloadavg()[0]
    for _ in range(args.repeat):
        for name, fn in variants.items():
            spaces = make(args.scenes)
            t0 = time.perf_counter()
            fn(spaces)
            times[name].append(time.perf_counter() - t0)
    work = args.scenes * args.steps
    print(f"{args.scenes} scenes x {args.steps} steps, median (and best) of {args.repeat}; "
          f"load average {load0:.2f} before, {os.getloadavg()[0]:.2f} after")
    base = statistics.median(times["Python loop"])
    one = statistics.median(times["step_spaces, 1 thread"])
    one_best = min(times["step_spaces, 1 thread"])
    for name in variants:
        t = statistics.median(times[name])
        best = min(times[name])
        print(f"{name:24s} {work / t:10.0f} scene-steps/s   x{base / t:.2f} of the loop   "
              f"x{one / t:.2f} of 1 thread   (best: {work / best:.0f}/s, "
              f"x{one_best / best:.2f} of 1 thread)")


if __name__ == "__main__":
    main()
