"""Where the soft solver's step spends its time, stage by stage.

Runs each scene at the soft solver's defaults on one thread and on two
(``Space(threaded=True)``, ``threads = 2``) and prints the wall time per
step of each stage of cpSoftStep (the median of --repeats runs) (the stage profile of ``_soft_step``, one
clock read per stage). Wall time, not instruction counts: the narrow phase
is bound by memory latency (pointer chasing through the broad phase's pairs,
the arbiter hash set, shapes and bodies), which instruction counts hide.
`valgrind --tool=callgrind` counts and `perf record` samples of the same
scenes are in docs/benchmarks.md.

    PYTHONPATH=src:tests python benchmarks/soft_profile.py [--steps 120] [--quick]
        [--scenes large_pyramid ...] [--sleep 0.5]

Scenes: large_pyramid (built here as Box2D's benchmark builds it),
many_pyramids, tumbler and rain_1000 (built by benchmarks/against_box2d.py),
a 20-row pyramid, and tests/scenes.py's rain and drum. The default runs all
of them; many_pyramids (22,000 boxes) takes about a minute.

--sleep sets every scene's sleep_time_threshold (off by default, as in
benchmarks/against_box2d.py), for the cost of sleeping while a pile is
still awake.
"""
import argparse
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))
sys.path.insert(0, HERE)

import tamias2d  # noqa: E402
from tamias2d import _soft_step  # noqa: E402
import scenes  # noqa: E402
import against_box2d  # noqa: E402


def large_pyramid(base=100):
    """Box2D's large_pyramid benchmark (tests/scenes.py touching_pyramid),
    as benchmarks/against_box2d.py builds it."""
    return scenes.touching_pyramid(tamias2d, base)


def box2d_scene(name):
    """A scene of benchmarks/against_box2d.py, built there as tamias2d's."""
    def build():
        engine = against_box2d.ChipmunkEngine(tamias2d, "tamias2d", solver="soft")
        builder, args = against_box2d.SCENES[name][:2]
        builder(engine, *args)
        return engine.s
    return build


SCENES = {
    "large_pyramid": large_pyramid,
    "many_pyramids": box2d_scene("many_pyramids"),
    "tumbler": box2d_scene("tumbler"),
    "pyramid_20": lambda: large_pyramid(20),
    "rain_1000": box2d_scene("rain_1000"),
    "rain": lambda: scenes.rain(tamias2d),
    "drum": lambda: scenes.drum(tamias2d),
}


def profile(build, threads, steps, warm, sleep=None):
    space = build()
    space.solver = "soft"
    if sleep is not None:
        space.sleep_time_threshold = sleep
    space.threaded = True
    space.threads = threads
    hook = getattr(space, "scene_hook", None)
    for i in range(warm + steps):
        if i == warm:
            _soft_step._profile(True)
        if hook is not None:
            hook(i)
        space.step(1 / 60)
    return _soft_step._profile(False)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=120)
    ap.add_argument("--warm", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=3, help="runs per row; the median of each stage")
    ap.add_argument("--quick", action="store_true", help="a few steps of the small scenes")
    ap.add_argument("--scenes", nargs="+", choices=list(SCENES), default=list(SCENES))
    ap.add_argument("--sleep", type=float, default=None,
                    help="sleep_time_threshold of every scene (default: sleeping off)")
    args = ap.parse_args()
    names = args.scenes
    if args.quick:
        names = ["pyramid_20", "drum"]
        args.steps, args.warm, args.repeats = 10, 5, 1
    stages = list(_soft_step.SOFT_STAGE_NAMES)
    print("| scene | threads | " + " | ".join(stages) + " | step ms |")
    print("|---|---|" + "---|" * (len(stages) + 1))
    for name in names:
        for threads in (1, 2):
            runs = [profile(SCENES[name], threads, args.steps, args.warm, args.sleep)
                    for _ in range(args.repeats)]
            ms = {s: statistics.median(r[s] for r in runs) for s in stages}
            cells = " | ".join(f"{ms[s]:.3f}" for s in stages)
            print(f"| {name} | {threads} | {cells} | {sum(ms.values()):.3f} |", flush=True)


if __name__ == "__main__":
    main()
