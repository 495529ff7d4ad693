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

Needs valgrind on PATH. ``--inner`` is how the script runs itself under
callgrind (build the scene, step it N times).
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


def count(name, steps, solver, iterations):
    """Instructions of a whole run of `steps` steps under callgrind."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + os.path.join(tmp, "out"),
               sys.executable, os.path.abspath(__file__), "--inner", name, str(steps),
               "--solver", solver]
        if iterations is not None:
            cmd += ["--iterations", str(iterations)]
        env = dict(os.environ, PYTHONHASHSEED="0")
        run = subprocess.run(cmd, env=env, capture_output=True, text=True)
        found = re.search(r"Collected : (\d+)", run.stderr)
        if run.returncode != 0 or not found:
            sys.exit(f"callgrind run failed ({' '.join(cmd)}):\n{run.stderr[-2000:]}")
        return int(found.group(1))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="+", help="tests/scenes.py scene names (pyramid, rain, drum, ...)")
    ap.add_argument("--solver", default="soft", choices=("soft", "chipmunk"))
    ap.add_argument("--iterations", type=int, help="the chipmunk solver's iterations")
    ap.add_argument("--short", type=int, default=30, help="steps of the first run (default 30)")
    ap.add_argument("--long", type=int, default=60, help="steps of the second run (default 60)")
    ap.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.inner:
        step_scene(args.scenes[0], int(args.scenes[1]), args.solver, args.iterations)
        # Out without freeing the space: a scene that grows as it steps (the
        # rain) would otherwise count the freeing of more bodies in the
        # longer run.
        sys.stdout.flush()
        os._exit(0)
    if args.long <= args.short:
        ap.error("--long must be more than --short")
    if shutil.which("valgrind") is None:
        sys.exit("valgrind is not on PATH")
    for name in args.scenes:
        short = count(name, args.short, args.solver, args.iterations)
        long_ = count(name, args.long, args.solver, args.iterations)
        per_step = (long_ - short) / (args.long - args.short)
        print(f"{name} {args.solver}: {per_step / 1e6:.3f} M instructions per step", flush=True)


if __name__ == "__main__":
    main()
