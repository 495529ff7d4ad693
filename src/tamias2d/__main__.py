"""The command line: ``python -m tamias2d`` (or the ``tamias2d`` script).

Commands:

- ``demo``: build a scene, step it headless, print a summary and draw the
  result to a PNG (and optionally an animated GIF);
- ``run SCRIPT [ARGS...]``: run an unmodified pymunk program on tamias2d
  (``import pymunk`` in it gives tamias2d; see ``tamias2d.install_as_pymunk``);
- ``version``: print the version of tamias2d and of the Chipmunk it follows.

>>> main(["version"])  # doctest: +ELLIPSIS
tamias2d ...
0
"""
import argparse
import math
import os
import sys
from fractions import Fraction

__docformat__ = "reStructuredText"

_SCENE_HELP = {
    "pyramid": "a pyramid of boxes on a ground segment (default)",
    "stack": "five stacks of boxes settling on the ground",
    "rain": "circles raining into an open box",
    "drum": "a spinning kinematic drum with boxes and balls inside",
}

PILLOW_HINT = "pip install 'tamias2d[demo]'"


def _size(text):
    """argparse type for WxH."""
    parts = text.lower().split("x")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 800x600, got {text!r}")
    try:
        w, h = int(parts[0]), int(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 800x600, got {text!r}") from None
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise argparse.ArgumentTypeError(f"width and height must be within 16..8192, got {text!r}")
    return w, h


def _dt(text):
    """argparse type for a positive time step; accepts fractions like 1/60."""
    try:
        value = float(Fraction(text.strip()))
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(f"expected a number such as 0.01 or 1/60, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"dt must be a positive number, got {text!r}")
    return value


def _count(minimum):
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be at least {minimum}, got {value}")
        return value
    return parse


def build_parser():
    """The argument parser of ``python -m tamias2d``.

    >>> build_parser().parse_args(["demo", "--size", "320x240"]).size
    (320, 240)
    """
    parser = argparse.ArgumentParser(
        prog="tamias2d",
        description="tamias2d: a 2D rigid-body physics engine (a Cython port of "
                    "Chipmunk2D with pymunk's API).",
    )
    parser.add_argument("--version", action="store_true", help="print the version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    scenes = "\n".join(f"  {name:8s} {text}" for name, text in _SCENE_HELP.items())
    demo = sub.add_parser(
        "demo",
        help="run a demo scene headless and draw it to a PNG",
        description="Build a scene, step it without a window, print a summary and draw\n"
                    "the final state to a PNG (and optionally an animated GIF).\n"
                    "Pictures need Pillow: " + PILLOW_HINT + ".",
        epilog="scenes:\n" + scenes,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    demo.add_argument("--scene", choices=list(_SCENE_HELP), default="pyramid",
                      help="which scene to run (default: pyramid)")
    demo.add_argument("--steps", type=_count(0), default=600, metavar="N",
                      help="number of steps (default: 600)")
    demo.add_argument("--dt", type=_dt, default=1 / 60,
                      help="time step in seconds, e.g. 0.01 or 1/60 (default: 1/60)")
    demo.add_argument("--out", default="tamias2d-demo.png", metavar="PATH",
                      help="picture of the final state (default: tamias2d-demo.png)")
    demo.add_argument("--gif", metavar="PATH", default=None,
                      help="also write an animated GIF of the run")
    demo.add_argument("--gif-every", type=_count(1), default=None, metavar="N",
                      help="one GIF frame every N steps (default: about 150 frames in all)")
    demo.add_argument("--size", type=_size, default=(800, 600), metavar="WxH",
                      help="picture size in pixels (default: 800x600)")
    demo.add_argument("--contacts", action="store_true",
                      help="also draw the contact points (in red)")
    demo.add_argument("--engine", choices=["tamias2d", "pymunk"], default="tamias2d",
                      help="physics module to run the scene with; pymunk, whose API "
                           "tamias2d copies, gives a comparison (default: tamias2d)")
    demo.add_argument("--quiet", "-q", action="store_true",
                      help="no progress display and no summary")

    run = sub.add_parser(
        "run", help="run a pymunk program on tamias2d",
        description="Run SCRIPT as __main__ with `import pymunk` giving tamias2d "
                    "(tamias2d.install_as_pymunk()); ARGS become its sys.argv[1:].")
    run.add_argument("script", metavar="SCRIPT", help="the pymunk program (a .py file)")
    run.add_argument("script_args", metavar="ARGS", nargs=argparse.REMAINDER,
                     help="arguments passed to the program")

    sub.add_parser("version", help="print the version of tamias2d and of the Chipmunk it follows",
                   description="Print the version of tamias2d and of the Chipmunk it follows.")
    return parser


def _version_text():
    import tamias2d

    return f"tamias2d {tamias2d.version} (Chipmunk {tamias2d.chipmunk_version})"


def _check_writable(path):
    """An error message if a file cannot be written at path, else None."""
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        return f"cannot write {path}: folder {folder} does not exist"
    if os.path.isdir(path):
        return f"cannot write {path}: it is a folder"
    return None


def _format_time(seconds):
    if seconds >= 1:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.3g} ms"
    return f"{seconds * 1e6:.3g} us"


def run_demo(args, stdout=None, stderr=None):
    """Run ``demo`` with parsed arguments; returns the exit status.

    >>> import io
    >>> args = build_parser().parse_args(["demo", "--steps", "2", "--quiet",
    ...                                   "--out", os.devnull + "/x.png"])
    >>> run_demo(args, stderr=io.StringIO())   # the folder /dev/null does not exist
    2
    """
    import importlib

    from . import demo

    stdout = sys.stdout if stdout is None else stdout
    stderr = sys.stderr if stderr is None else stderr

    for path in (args.out, args.gif):
        if path:
            problem = _check_writable(path)
            if problem:
                stderr.write(f"tamias2d demo: {problem}\n")
                return 2

    try:
        engine = importlib.import_module(args.engine)
    except ImportError as exc:
        stderr.write(f"tamias2d demo: cannot import {args.engine}: {exc}\n")
        return 2

    try:
        from . import pillow_util  # noqa: F401  (only to know if pictures can be drawn)
        have_pillow = True
    except ImportError:
        have_pillow = False

    scene = demo.build_scene(args.scene, engine=engine, steps=args.steps)
    width, height = args.size

    frames = None
    frame_options = None
    frame_every = 0
    if args.gif and have_pillow:
        frame_every = args.gif_every or max(1, math.ceil(args.steps / 150))
        # GIF playback in real time (GIF stores hundredths of a second).
        duration = max(20, round(frame_every * args.dt * 100) * 10)
        frames = pillow_util.GifWriter(duration=duration)
        frame_options = demo.make_draw_options((width, height), scene.view, engine,
                                               supersample=2, contacts=args.contacts)

    def on_frame(scene, i):
        frames.add(demo.render(scene, frame_options, _caption(args, scene, i)))

    progress = demo.Progress(args.steps, stream=stderr, enabled=not args.quiet,
                             label=f"{args.scene}")
    result = demo.run(scene, steps=args.steps, dt=args.dt, progress=progress,
                      on_frame=on_frame if frames is not None else None,
                      frame_every=frame_every)

    written = []
    if have_pillow:
        options = demo.make_draw_options((width, height), scene.view, engine,
                                         supersample=3, contacts=args.contacts)
        image = demo.render(scene, options, _caption(args, scene, result.steps))
        image.save(args.out)
        written.append(f"{args.out} ({width}x{height})")
        if frames is not None:
            frames.save(args.gif)
            count = f"{len(frames)} frame" + ("s" if len(frames) != 1 else "")
            every = "every step" if frame_every == 1 else f"one every {frame_every} steps"
            written.append(f"{args.gif} ({count}, {every})")

    if not args.quiet:
        space = scene.space
        n = result.steps
        per_step = result.step_time / n if n else 0.0
        lines = [
            f"{_version_text()}, demo with engine {engine.__name__}",
            f"scene           {scene.name}: {scene.description}",
            f"bodies          {len(space.bodies)}",
            f"shapes          {len(space.shapes)}",
            f"steps           {n} x dt {result.dt:.6g} s ({n * result.dt:.4g} s simulated)",
            f"stepping time   {_format_time(result.step_time)} total, "
            f"{_format_time(per_step)} per step",
            f"kinetic energy  {result.kinetic_energy!r} at the end "
            f"(sum of 1/2 m v^2 + 1/2 I w^2)",
        ]
        if written:
            lines.append("wrote           " + "\n                ".join(written))
        stdout.write("\n".join(lines) + "\n")
        stdout.flush()
    if not have_pillow:
        stderr.write("tamias2d demo: no picture written because Pillow is not installed; "
                     f"to get it: {PILLOW_HINT}\n")
    return 0


def _caption(args, scene, step):
    return f"tamias2d demo: {scene.name}   step {step}   t = {step * args.dt:.2f} s"


def main(argv=None):
    """Entry point of ``python -m tamias2d`` and of the ``tamias2d`` script;
    returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.version or args.command == "version":
        print(_version_text())
        return 0
    if args.command == "demo":
        return run_demo(args)
    if args.command == "run":
        from tamias2d._pymunk_hook import run_script
        if not os.path.isfile(args.script):
            parser.error(f"no such script: {args.script}")
        try:
            run_script(args.script, args.script_args)
        except SystemExit as exc:  # the program's own exit status
            code = exc.code
            if code is None or isinstance(code, int):
                return code or 0
            print(code, file=sys.stderr)
            return 1
        return 0
    parser.print_help()
    return 0


if __name__ == "__main__":
    sys.exit(main())
