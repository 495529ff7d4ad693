"""Instructions per step under callgrind, for the cost tables of docs/benchmarks.md.

Runs a tests/scenes.py scene under ``valgrind --tool=callgrind`` twice, for
SHORT and LONG steps, and prints (instructions(LONG) - instructions(SHORT)) /
(LONG - SHORT): the cost of a step once the scene is built and settling,
without the interpreter's start-up and the scene's construction. Instruction
counts do not depend on the machine's load, so two builds compare exactly
(their cache misses, which instruction counts hide, are another matter: see
benchmarks/soft_profile.py for wall time).

    PYTHONPATH=src python benchmarks/callgrind_steps.py pyramid --solver soft
    PYTHONPATH=src python benchmarks/callgrind_steps.py rain drum --solver chipmunk --iterations 10

With ``--box2d``, the scenes are benchmarks/against_box2d.py's (large_pyramid,
many_pyramids, tumbler, pyramid_20, rain_1000, built as there) and each is
counted in Box2D v3 (pyb2d3, 4 substeps, one thread) and in tamias2d's soft
solver at its defaults; ``--top N`` also lists the N functions that took the
most instructions of their own per step (Box2D's wheel has no symbols: its
functions are addresses):

    PYTHONPATH=src python benchmarks/callgrind_steps.py large_pyramid --box2d --short 60 --long 70 --top 12

Needs valgrind on PATH (and callgrind_annotate for ``--top``). ``--inner``
is how the script runs itself under callgrind (build the scene, step it N
times).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))


def step_scene(name, steps, solver, iterations):
    import tamias2d
    import scenes
    space = getattr(scenes, name)(tamias2d)
    space.solver = solver
    if iterations is not None:
        space.iterations = iterations
    hook = getattr(space, "scene_hook", None)
    for i in range(steps):
        if hook is not None:
            hook(i)
        space.step(1 / 60)


def step_box2d_scene(name, steps, solver):
    """An against_box2d.py scene in `solver`: "box2d" or a tamias2d solver."""
    sys.path.insert(0, HERE)
    import against_box2d
    import tamias2d
    build, full = against_box2d.SCENES[name][:2]
    if solver == "box2d":
        engine = against_box2d.Box2DEngine()
    else:
        engine = against_box2d.ChipmunkEngine(tamias2d, "tamias2d", solver=solver)
    build(engine, *full)
    engine.step(steps)


def self_costs(out):
    """Instructions each function took itself in a callgrind output file."""
    run = subprocess.run(["callgrind_annotate", "--threshold=100", out],
                         capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"callgrind_annotate failed:\n{run.stderr[-2000:]}")
    costs = {}
    for line in run.stdout.splitlines():
        found = re.match(r"\s*([\d,]+) \([^)]*\)\s+(\S+?)(?: \[.*)?$", line)
        if found:
            name = found.group(2).split(":")[-1]
            costs[name] = costs.get(name, 0) + int(found.group(1).replace(",", ""))
    return costs


def count(name, steps, solver, iterations, box2d=False, functions=False):
    """Instructions of a whole run of `steps` steps under callgrind (and,
    with `functions`, each function's own)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out")
        cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out,
               sys.executable, os.path.abspath(__file__), "--inner", name, str(steps),
               "--solver", solver]
        if iterations is not None:
            cmd += ["--iterations", str(iterations)]
        if box2d:
            cmd += ["--box2d"]
        # (numpy, which pyb2d3 imports, would start OpenBLAS's threads, whose
        # waiting adds a varying count.)
        env = dict(os.environ, PYTHONHASHSEED="0", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
        run = subprocess.run(cmd, env=env, capture_output=True, text=True)
        found = re.search(r"Collected : (\d+)", run.stderr)
        if run.returncode != 0 or not found:
            sys.exit(f"callgrind run failed ({' '.join(cmd)}):\n{run.stderr[-2000:]}")
        return int(found.group(1)), (self_costs(out) if functions else None)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="+", help="tests/scenes.py scene names (pyramid, rain, drum, ...)")
    ap.add_argument("--solver", default="soft", choices=("soft", "chipmunk", "box2d"))
    ap.add_argument("--box2d", action="store_true",
                    help="against_box2d.py's scenes, in Box2D v3 and in the soft solver")
    ap.add_argument("--top", type=int, default=0,
                    help="also list the N functions with the most instructions of their own")
    ap.add_argument("--iterations", type=int, help="the chipmunk solver's iterations")
    ap.add_argument("--short", type=int, default=30, help="steps of the first run (default 30)")
    ap.add_argument("--long", type=int, default=60, help="steps of the second run (default 60)")
    ap.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.inner:
        if args.box2d:
            step_box2d_scene(args.scenes[0], int(args.scenes[1]), args.solver)
        else:
            step_scene(args.scenes[0], int(args.scenes[1]), args.solver, args.iterations)
        # Out without freeing the space: a scene that grows as it steps (the
        # rain) would otherwise count the freeing of more bodies in the
        # longer run.
        sys.stdout.flush()
        os._exit(0)
    if args.solver == "box2d" and not args.box2d:
        ap.error("--solver box2d needs --box2d (against_box2d.py's scenes)")
    if args.long <= args.short:
        ap.error("--long must be more than --short")
    if shutil.which("valgrind") is None:
        sys.exit("valgrind is not on PATH")
    steps = args.long - args.short
    for name in args.scenes:
        for solver in (("box2d", "soft") if args.box2d else (args.solver,)):
            short, short_fns = count(name, args.short, solver, args.iterations, args.box2d,
                                     args.top > 0)
            long_, long_fns = count(name, args.long, solver, args.iterations, args.box2d,
                                    args.top > 0)
            per_step = (long_ - short) / steps
            print(f"{name} {solver}: {per_step / 1e6:.3f} M instructions per step", flush=True)
            if args.top > 0:
                own = {f: (c - short_fns.get(f, 0)) / steps for f, c in long_fns.items()}
                for f, c in sorted(own.items(), key=lambda fc: -fc[1])[:args.top]:
                    print(f"    {c / 1e6:8.3f} M  {f}")


if __name__ == "__main__":
    main()
