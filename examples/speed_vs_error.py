"""Speed against error: Chipmunk's iterations against the soft solver's substeps.

Two small scenes whose right answer is known: a stack of 8 boxes and a
pyramid of 10 rows, both built exactly touching, so that every box should
stay where it was built. Each is simulated for --frames frames (3 s by
default) at 60 Hz with each setting of each solver; the error is the
farthest any box moved from its place (sinking into the box below,
creeping sideways, or falling), the cost the time the steps took per
simulated second. Points nearer the bottom left are better.

What it shows here: Chipmunk's error keeps falling as iterations are added;
the soft solver holds the stack from one substep (its contacts are springs
preloaded with the weight above them, so a stack stands at no depth), and
on the pyramid levels off at about a fifth of a pixel: there its contacts
are preloaded with 0.7 of their load, and the springs
(``space.contact_hertz``) give a little under the rest whatever the
substeps; raising contact_hertz lowers that floor.

The result is a plot, written to a PNG headless and shown in a window
otherwise (needs matplotlib: pip install matplotlib). Here --frames is
the length of each run.

    python examples/speed_vs_error.py
    python examples/speed_vs_error.py --headless --out speed_vs_error.png
"""
import time

import _common
import tamias2d

BOX = 20.0
SETTINGS = {"chipmunk": ("iterations", [2, 4, 8, 16, 32, 64]),
            "soft": ("substeps", [1, 2, 4, 8, 16])}


def build(scene, solver, setting):
    space = tamias2d.Space(solver=solver)
    space.gravity = (0, -900)
    name, _ = SETTINGS[solver]
    setattr(space, name, setting)  # space.iterations = n, or space.substeps = n
    ground = tamias2d.Segment(space.static_body, (-400, 0), (400, 0), 0)
    ground.friction = 0.6
    space.add(ground)
    if scene == "stack of 8":
        places = [(0.0, BOX / 2 + BOX * i) for i in range(8)]
    else:  # the pyramid, boxes side by side with no gap
        places = [(BOX * (i - (10 - row - 1) / 2), BOX / 2 + BOX * row)
                  for row in range(10) for i in range(10 - row)]
    for x, y in places:
        body = tamias2d.Body(1, tamias2d.moment_for_box(1, (BOX, BOX)))
        body.position = x, y
        box = tamias2d.Poly.create_box(body, (BOX, BOX))
        box.friction = 0.6
        space.add(body, box)
    return space, places


def measure(scene, solver, setting, frames, repeats=3):
    """(ms of stepping per simulated second, the largest move in px)."""
    best = float("inf")
    for _ in range(repeats):  # the fastest of a few runs: the least disturbed
        space, places = build(scene, solver, setting)
        t0 = time.perf_counter()
        for _ in range(frames):
            space.step(_common.DT)
        best = min(best, time.perf_counter() - t0)
    error = max((b.position - p).length for b, p in zip(space.bodies, places))
    return best / (frames * _common.DT) * 1e3, error


def plot(results, frames, out=None, show=False):
    import matplotlib
    if not show:
        matplotlib.use("Agg")  # no display needed to write a file
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(11, 4.5))
    for ax, (scene, curves) in zip(axes, results.items()):
        for solver, points in curves.items():
            name, values = SETTINGS[solver]
            costs, errors = zip(*points)
            ax.plot(costs, errors, "o-", label=f'solver="{solver}" ({name})')
            for v, c, e in zip(values, costs, errors):
                ax.annotate(str(v), (c, e), textcoords="offset points", xytext=(4, 4),
                            fontsize=8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{scene}, {frames / _common.FPS:.1f} s at 60 Hz")
        ax.set_xlabel("ms of stepping per simulated second")
        ax.set_ylabel("largest move from the built place (px)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    if out is not None:
        fig.savefig(out, dpi=90)
        print(f"wrote {out}")
    if show:
        plt.show()


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    frames = args.frames or 180
    results = {}
    for scene in ("stack of 8", "pyramid of 10 rows"):
        results[scene] = {}
        for solver, (name, values) in SETTINGS.items():
            results[scene][solver] = [measure(scene, solver, v, frames) for v in values]
            for v, (cost, error) in zip(values, results[scene][solver]):
                print(f"{scene:>18}  {solver:>8}  {name} {v:>2}: "
                      f"{cost:7.2f} ms/s  error {error:9.4f} px")
    # Headless: write the picture. In a window: show it (and write it too
    # if --out is given).
    out = _common.default_out(args, ".png") if args.headless or args.out else None
    plot(results, frames, out, show=not args.headless)
