"""Benchmarks of tamias2d against pymunk 7.3, in one process.

    python benchmarks/run.py                     # everything, a few minutes
    python benchmarks/run.py --quick             # tiny sizes, 1 repeat: seconds
    python benchmarks/run.py --json out.json --plots docs --markdown tables.md
    python benchmarks/run.py --clock cpu         # CPU time: steadier on a busy machine

Sections (``--only`` picks some, comma-separated):
  scenes      step time of eight scenes at several sizes (pyramid, stack,
              rain, drum, static field, sparse field, sleeping wall,
              callback rain);
  scaling     step time against body count, 100 to 30,000 bodies;
  accuracy    speed against error: scenes with known answers swept over the
              time step and the solver iterations;
  operations  per-body and batch reads and writes of 10,000 bodies, Python
              velocity_func and collision callbacks, copy and pickle.

Every timing alternates the engines (which one goes first switches at each
repeat) and reports medians; the ratio is tamias2d time / pymunk time, so
below 1.0 tamias2d is faster. Progress goes to stderr (one line rewritten in
place on a terminal), tables to stdout.

Needs pymunk 7.3 and NumPy (``pip install ".[bench]"``), and matplotlib for
``--plots``. tamias2d is used as installed, else from this checkout (built
in place).
"""
import argparse
import datetime
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import harness  # noqa: E402

SECTIONS = ("scenes", "scaling", "accuracy", "operations")


def parse_args(argv):
    parser = argparse.ArgumentParser(
        description="Benchmarks of tamias2d against pymunk (speed, scaling, speed against "
                    "error, user-facing operations).",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="See docs/benchmarks.md for the results of a full run.")
    parser.add_argument("--quick", action="store_true",
                        help="tiny sizes and one repeat: runs in seconds (for tests)")
    parser.add_argument("--json", metavar="PATH", help="write all results as JSON to PATH")
    parser.add_argument("--plots", metavar="DIR", help="write PNG plots into DIR (needs matplotlib)")
    parser.add_argument("--markdown", metavar="PATH", help="write the Markdown tables to PATH")
    parser.add_argument("--only", metavar="SECTIONS",
                        help="comma-separated sections to run: " + ", ".join(SECTIONS))
    parser.add_argument("--repeat", type=int, default=None,
                        help="timed repeats per item (default: 7 for scenes and operations, "
                             "5 for accuracy, 7 or 3 for scaling; 1 with --quick)")
    parser.add_argument("--clock", choices=sorted(harness.CLOCKS), default="wall",
                        help="what the timings measure: elapsed wall time (default) or the CPU "
                             "time of this process (steadier on a machine shared with other work)")
    parser.add_argument("--no-progress", action="store_true", help="no progress display on stderr")
    args = parser.parse_args(argv)
    if args.only:
        chosen = [s.strip() for s in args.only.split(",") if s.strip()]
        unknown = [s for s in chosen if s not in SECTIONS]
        if unknown:
            parser.error(f"unknown section(s) {', '.join(unknown)}; choose from {', '.join(SECTIONS)}")
        args.sections = [s for s in SECTIONS if s in chosen]
    else:
        args.sections = list(SECTIONS)
    if args.repeat is not None and args.repeat < 1:
        parser.error("--repeat must be at least 1")
    return args


def _clean(obj):
    """JSON-safe copy: non-finite floats become None."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    return obj


def _load():
    """The 1, 5 and 15 minute load averages (other work on the machine skews timings)."""
    try:
        return list(os.getloadavg())
    except (OSError, AttributeError):
        return None


def main(argv=None):
    args = parse_args(argv)
    harness.set_clock(args.clock)
    tamias2d, pymunk = harness.import_engines()
    scenes = harness.import_scenes()
    import accuracy
    import operations
    import report
    import speed

    mods = {"tamias2d": tamias2d, "pymunk": pymunk}
    total = 0
    if "scenes" in args.sections:
        total += len(speed.scene_specs(scenes, args.quick))
    if "scaling" in args.sections:
        total += speed.scaling_count(args.quick)
    if "accuracy" in args.sections:
        total += accuracy.task_count(args.quick)
    if "operations" in args.sections:
        total += operations.task_count()
    progress = harness.Progress(total, enabled=not args.no_progress)

    started = time.time()
    results = {"meta": {
        "command": " ".join(["python benchmarks/run.py"]
                            + list(sys.argv[1:] if argv is None else argv)),
        "started": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "quick": args.quick,
        "clock": args.clock,
        "sections": args.sections,
        "machine": harness.machine_info(tamias2d, pymunk),
        "ratio": "tamias2d time / pymunk time (below 1: tamias2d faster)",
        "load_average_start": _load(),
    }}
    if "scenes" in args.sections:
        progress.note("== scenes: ms per step (median), ratio tamias2d/pymunk")
        results["scenes"] = speed.run_scenes(mods, scenes, args.quick, progress, args.repeat)
    if "scaling" in args.sections:
        progress.note("== scaling: ms per step against body count")
        results["scaling"] = speed.run_scaling(mods, scenes, args.quick, progress, args.repeat)
    if "accuracy" in args.sections:
        progress.note("== speed against error")
        rows, front, meta = accuracy.run_accuracy(mods, scenes, args.quick, progress, args.repeat)
        results["accuracy"] = {"rows": rows, "front": front, "meta": meta}
    if "operations" in args.sections:
        progress.note("== operations")
        results["operations"] = operations.run_operations(mods, scenes, args.quick, progress,
                                                          args.repeat)
    progress.finish()
    results["meta"]["duration_s"] = time.time() - started
    results["meta"]["load_average_end"] = _load()

    text = report.markdown(results)
    sys.stdout.write(text)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(text)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(_clean(results), f, indent=1)
            f.write("\n")
    if args.plots:
        import plots
        for path in plots.write_all(results, args.plots):
            print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
