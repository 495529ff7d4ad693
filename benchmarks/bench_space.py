"""Step time of whole scenes: tamias2d against pymunk in the same process.

Scenes (built by tests/scenes.py with the same calls in both engines, so the
two simulations stay bitwise equal and every timed block covers the same
motion):
  * pyramid 20     210 boxes in a 20-row pyramid;
  * pyramid 40     820 boxes in a 40-row pyramid;
  * circles 1000   1,000 circles of mixed sizes piling up in an open box;
  * drum 1000      1,000 boxes tumbling in a turning kinematic drum.

Each scene is built in both engines and warmed up (``--warmup`` steps, so
that contacts exist), then ``--repeat`` blocks of ``--steps`` steps are
timed, alternating which engine goes first. The median time per step of
each engine and the ratio tamias2d/pymunk are printed (lower is better;
below 1.0 tamias2d is faster).

    PYTHONPATH=src:. python benchmarks/bench_space.py [--repeat R] [--steps K] [--warmup W] [--only NAME]
"""
import argparse
import os
import statistics
import sys
import time

import pymunk
import tamias2d

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
import scenes  # noqa: E402

SCENES = [
    ("pyramid 20", lambda m: scenes.pyramid(m, rows=20), 1.0 / 60.0),
    ("pyramid 40", lambda m: scenes.pyramid(m, rows=40), 1.0 / 60.0),
    ("circles 1000", lambda m: scenes.rain(m, count=1000), 1.0 / 60.0),
    ("drum 1000", lambda m: scenes.drum(m, count=1000, box=10.0, radius=400.0, wall=10.0),
     1.0 / 60.0),
]


def time_steps(space, dt, steps):
    step = space.step
    t0 = time.perf_counter()
    for _ in range(steps):
        step(dt)
    return (time.perf_counter() - t0) / steps


def bench_scene(build, dt, repeat, steps, warmup):
    spaces = {"pymunk": build(pymunk), "tamias2d": build(tamias2d)}
    for space in spaces.values():
        for _ in range(warmup):
            space.step(dt)
    times = {"pymunk": [], "tamias2d": []}
    order = ["pymunk", "tamias2d"]
    for r in range(repeat):
        for name in order if r % 2 == 0 else order[::-1]:
            times[name].append(time_steps(spaces[name], dt, steps))
    # Both engines ran the same motion: check it, so a timing is never of a
    # different simulation.
    a = [(b.position, b.angle) for b in spaces["pymunk"].bodies]
    b = [(b.position, b.angle) for b in spaces["tamias2d"].bodies]
    same = a == b
    return statistics.median(times["pymunk"]), statistics.median(times["tamias2d"]), same


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=11)
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--warmup", type=int, default=60)
    parser.add_argument("--only", default=None, help="run only scenes whose name contains this")
    args = parser.parse_args(argv)

    print(f"pymunk {pymunk.version}, tamias2d {tamias2d.version}; median of {args.repeat} "
          f"blocks of {args.steps} steps after {args.warmup} warm-up steps")
    print(f"{'scene':<14} {'bodies':>7} {'pymunk ms/step':>15} {'tamias2d ms/step':>17} "
          f"{'ratio':>7}  same motion")
    ratios = []
    for name, build, dt in SCENES:
        if args.only and args.only not in name:
            continue
        n = len(build(pymunk).bodies)
        tp, tt, same = bench_scene(build, dt, args.repeat, args.steps, args.warmup)
        ratios.append(tt / tp)
        print(f"{name:<14} {n:>7} {tp * 1e3:>15.3f} {tt * 1e3:>17.3f} {tt / tp:>7.3f}  {same}")
    if ratios:
        print(f"geometric mean ratio: {statistics.geometric_mean(ratios):.3f}")


if __name__ == "__main__":
    main()
