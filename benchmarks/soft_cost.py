"""Cost of the soft solver against the chipmunk solver (issue 13).

Times ``Space.step`` per step on the shared scenes (tests/scenes.py): the
chipmunk solver at 10 iterations (its default) beside the soft solver at
its defaults (4 substeps) and at 1, 2 and 8 substeps. The first `warm`
steps are not timed. Run from the checkout:

    PYTHONPATH=src:tests python benchmarks/soft_cost.py [--steps 300]
"""
import argparse
import statistics
import time

import tamias2d
import scenes

SCENES = {"pyramid": lambda: scenes.pyramid(tamias2d), "rain": lambda: scenes.rain(tamias2d),
          "drum": lambda: scenes.drum(tamias2d)}


def per_step_ms(build, steps, warm, repeats, **settings):
    best = []
    for _ in range(repeats):
        space = build()
        for k, v in settings.items():
            setattr(space, k, v)
        hook = getattr(space, "scene_hook", None)
        for i in range(warm):
            if hook is not None:
                hook(i)
            space.step(1 / 60)
        t0 = time.perf_counter()
        for i in range(warm, warm + steps):
            if hook is not None:
                hook(i)
            space.step(1 / 60)
        best.append((time.perf_counter() - t0) / steps * 1e3)
    return min(best)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--warm", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    rows = [("chipmunk, 10 iterations", {"solver": "chipmunk", "iterations": 10})]
    for n in (1, 2, 4, 8):
        rows.append((f"soft, {n} substeps" + (" (default)" if n == 4 else ""),
                     {"solver": "soft", "substeps": n}))
    print("| solver | " + " | ".join(f"{name} ms/step" for name in SCENES) + " |")
    print("|---|" + "---|" * len(SCENES))
    for label, settings in rows:
        cells = [per_step_ms(b, args.steps, args.warm, args.repeats, **settings) for b in SCENES.values()]
        print(f"| {label} | " + " | ".join(f"{c:.3f}" for c in cells) + " |", flush=True)


if __name__ == "__main__":
    main()
