"""Stacks whose boxes are not exactly on centre, in the soft solver and in
Box2D v3 (pyb2d3, the `bench` extra, when installed).

The hard cases' stacks (tests/hard_cases.py) stand each box exactly on the
one below, which no hand-built stack does: a stack that only stands because
it is exactly symmetric falls at the first nudge. Two tests here, each in
three gravities (10, 22.5 and 45 box sizes per s^2: Box2D's 1 m boxes under
10 m/s^2, and pymunk's 20-unit boxes under 450 and 900), on stacks of 10, 20
and 40 boxes of mass 1 and friction 0.6, 3600 steps of 1/60 s (the hard
cases' full length: a stack may rock for many seconds before it falls), 4
substeps:

  built off centre   each box placed up to 0.1% or 1% of its size to the side
                     at random (seeds 1, 2, 3)
  nudged             the stack built on centre, left to settle for 3600
                     steps, then its top box moved 0.01%, 0.1% or 1% of a
                     box to the side (tamias2d only)

A stack stands if no box ever moves more than 0.1 box sideways (after a
nudge, in the 3600 steps that follow: more than 0.1 box plus the nudge). The soft solver is run as it is
and with each two-point chain contact's preloads following each point's own
load (`_soft_step._chain_preload_tilt(1.0)`, as before stop 39).

    PYTHONPATH=src python benchmarks/offset_stacks.py [--quick] [--steps 3600]
"""
import argparse
import random

import tamias2d
from tamias2d import _soft_step

from harness import box2d_shape_def

SIZE = 20.0
STEPS = 3600
GRAVITIES = (10.0, 22.5, 45.0)     # box sizes per s^2
COUNTS = (10, 20, 40)


def _soft_column(count, gravity, offsets):
    """A soft-solver space with a column of `count` boxes on a static floor,
    box i `offsets[i]` boxes to the side."""
    space = tamias2d.Space(solver="soft")
    space.gravity = 0, -gravity * SIZE
    ground = tamias2d.Segment(space.static_body, (-2000, -5), (2000, -5), 5)
    ground.friction = 0.6
    space.add(ground)
    boxes = []
    for i in range(count):
        body = tamias2d.Body(1, tamias2d.moment_for_box(1, (SIZE, SIZE)))
        body.position = offsets[i] * SIZE, SIZE / 2 + i * SIZE
        box = tamias2d.Poly.create_box(body, (SIZE, SIZE))
        box.friction = 0.6
        space.add(body, box)
        boxes.append(body)
    return space, boxes


def _largest_move(space, boxes, home):
    """Steps STEPS times; the largest sideways move of any box from `home`,
    in boxes."""
    moved = 0.0
    for _ in range(STEPS):
        space.step(1 / 60)
        moved = max(moved, max(abs(b.position.x - x) for b, x in zip(boxes, home)))
    return moved / SIZE


def soft_stack(count, offset, gravity, seed):
    """The largest sideways move of any box, in boxes, of a stack built up to
    `offset` boxes off centre."""
    rng = random.Random(seed)
    space, boxes = _soft_column(count, gravity, [rng.uniform(-offset, offset) for _ in range(count)])
    return _largest_move(space, boxes, [b.position.x for b in boxes])


def soft_nudged(count, nudge, gravity):
    """The largest sideways move of any box, in boxes, after the settled
    stack's top box is moved `nudge` boxes to the side."""
    space, boxes = _soft_column(count, gravity, [0.0] * count)
    for _ in range(STEPS):
        space.step(1 / 60)
    boxes[-1].position = boxes[-1].position + (nudge * SIZE, 0)
    return _largest_move(space, boxes, [0.0] * count)


def box2d_stack(b2, count, offset, gravity, seed):
    rng = random.Random(seed)
    world = b2.World(gravity=(0, -gravity))
    world.sleeping_enabled = False
    ground = world.create_static_body(position=(0, -0.5))
    ground.create_polygon_shape(box2d_shape_def(b2, 1.0, 0.6), b2.box(100, 0.5))
    boxes = []
    for i in range(count):
        body = world.create_dynamic_body(position=(rng.uniform(-offset, offset), 0.5 + i))
        body.create_polygon_shape(box2d_shape_def(b2, 1.0, 0.6), b2.box(0.5, 0.5))
        boxes.append(body)
    home = [b.position[0] for b in boxes]
    moved = 0.0
    for _ in range(STEPS):
        world.step(1 / 60, 4)
        moved = max(moved, max(abs(b.position[0] - x) for b, x in zip(boxes, home)))
    return moved


def main():
    global STEPS
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="10-box stacks only, one seed")
    ap.add_argument("--steps", type=int, default=STEPS, help="steps of each run (and to settle)")
    args = ap.parse_args()
    STEPS = args.steps
    try:
        import pyb2d3 as b2
    except ImportError:
        b2 = None
    counts = (10,) if args.quick else COUNTS
    seeds = (1,) if args.quick else (1, 2, 3)
    shares = (_soft_step._chain_preload_tilt(), 1.0)
    default = shares[0]
    totals = {"soft": 0, "before": 0, "box2d": 0}
    cells = 0

    def soft(share, fn, *a):
        _soft_step._chain_preload_tilt(share)
        try:
            return fn(*a)
        finally:
            _soft_step._chain_preload_tilt(default)

    print("Built off centre: stacks standing of the seeds run\n")
    print("| boxes | gravity (boxes/s^2) | off centre | tamias2d soft | soft, preloads per point "
          "(before) | Box2D v3 |")
    print("|---|---|---|---|---|---|")
    for gravity in GRAVITIES:
        for count in counts:
            for offset in (0.0, 0.001, 0.01):
                runs = (1,) if offset == 0.0 else seeds
                row = []
                for key, share in (("soft", shares[0]), ("before", shares[1])):
                    ok = sum(soft(share, soft_stack, count, offset, gravity, s) < 0.1 for s in runs)
                    totals[key] += ok
                    row.append(f"{ok}/{len(runs)}")
                if b2 is not None:
                    ok = sum(box2d_stack(b2, count, offset, gravity, s) < 0.1 for s in runs)
                    totals["box2d"] += ok
                    row.append(f"{ok}/{len(runs)}")
                else:
                    row.append("-")
                cells += len(runs)
                print(f"| {count} | {gravity:g} | {offset:.1%} | " + " | ".join(row) + " |",
                      flush=True)
    print(f"\nstanding: soft {totals['soft']}, before {totals['before']}, "
          f"Box2D {totals['box2d'] if b2 is not None else '-'} of {cells}\n")
    print("Nudged after settling: the largest sideways move, in boxes\n")
    print("| boxes | gravity (boxes/s^2) | nudge | tamias2d soft | soft, preloads per point "
          "(before) |")
    print("|---|---|---|---|---|")
    stood = {"soft": 0, "before": 0}
    cells = 0
    for gravity in GRAVITIES:
        for count in counts:
            for nudge in (0.0001, 0.001, 0.01):
                row = []
                for key, share in (("soft", shares[0]), ("before", shares[1])):
                    moved = soft(share, soft_nudged, count, nudge, gravity)
                    ok = moved < 0.1 + nudge
                    stood[key] += ok
                    row.append(f"{moved:.3g}" + ("" if ok else " (falls)"))
                cells += 1
                print(f"| {count} | {gravity:g} | {nudge:.2%} | " + " | ".join(row) + " |",
                      flush=True)
    print(f"\nstanding: soft {stood['soft']}, before {stood['before']} of {cells}")


if __name__ == "__main__":
    main()
