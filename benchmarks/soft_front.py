"""The speed-against-error front of the soft solver (substeps 1, 2, 4, 8)
beside the chipmunk solver's (iterations 2, 5, 10, 20), for
docs/benchmarks.md.

The scenes and the error are examples/speed_vs_error.py's: a stack of 8
and a pyramid of 10 rows built exactly touching, 3 s at 60 Hz; the error is
the farthest any box moved from its place (px), the cost the stepping time
per simulated second (fastest of 3 runs: the least disturbed on a shared
machine).

    PYTHONPATH=src python benchmarks/soft_front.py [--frames 180]
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))
import speed_vs_error as sve  # noqa: E402

SETTINGS = (("chipmunk", "iterations", (2, 5, 10, 20)), ("soft", "substeps", (1, 2, 4, 8)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=180)
    args = ap.parse_args()
    scenes = ("stack of 8", "pyramid of 10")
    print("| solver | setting | " + " | ".join(f"{s}: ms per s / error px" for s in scenes) + " |")
    print("|---|---|" + "---|" * len(scenes))
    for solver, name, values in SETTINGS:
        for v in values:
            cells = []
            for scene in scenes:
                ms, err = sve.measure(scene, solver, v, args.frames)
                cells.append(f"{ms:.1f} / {err:.3g}")
            print(f"| {solver} | {name} {v} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
