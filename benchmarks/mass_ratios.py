"""Heavy bodies on light ones in the soft solver, with and without its blocks.

A body with a movable neighbour 30 times heavier or more has its contacts
solved together with its light neighbours' (`SoftSolveBlock` in
`_soft_step.pyx`); `_soft_step._mass_ratio_blocks(False)` solves them one by
one instead, as every other contact. Both are run here in one process, in
the hard cases' units (boxes of 20 under a gravity of 900, mass 1 for a
light box):

  resting    a heavy box on light ones, built at rest: the largest move of
             any body in 10 s, in boxes (a heavy box on one light box at
             100, 1000 and 10,000 times its mass; at 1000 on two side by
             side, on two stacked, on a pyramid of six, a plank on four)
  solver2d   Solver2D's "high mass ratio 1" scene (three pyramids of base
             10, boxes of 2 under 10, their tops 100, 200 and 300 times
             denser, dropped 2 units): how far each top rests below where
             it lands, in units, and the cost of a step
  impacts    three heavy balls (1000x) and a heavy plank dropped on 60
             light boxes, 10 seeds: in how many a light box is driven
             through the floor, and the median cost of a step; the same
             scene in Box2D v3 beside them when pyb2d3 is installed

    PYTHONPATH=src python benchmarks/mass_ratios.py [--seeds 10]
"""
import argparse
import math
import random
import statistics
import time

import tamias2d
from tamias2d import _soft_step

from harness import box2d_shape_def

G, S = 900.0, 20.0


def _space(gravity=G, friction=1.0):
    space = tamias2d.Space(solver="soft")
    space.gravity = 0.0, -gravity
    ground = tamias2d.Segment(space.static_body, (-2000, 0), (2000, 0), 0.0)
    ground.friction = friction
    space.add(ground)
    return space


def _box(space, x, y, mass, w=S, h=S, friction=0.6, elasticity=0.0):
    body = tamias2d.Body(mass, tamias2d.moment_for_box(mass, (w, h)))
    body.position = x, y
    shape = tamias2d.Poly.create_box(body, (w, h))
    shape.friction = friction
    shape.elasticity = elasticity
    space.add(body, shape)
    return body


def _on_one(ratio):
    def build(space):
        return [_box(space, 0, S / 2, 1.0), _box(space, 0, 1.5 * S, ratio)]
    return build


def _two_side_by_side(space):
    return [_box(space, -0.55 * S, S / 2, 1.0), _box(space, 0.55 * S, S / 2, 1.0),
            _box(space, 0, 1.5 * S, 1000.0, w=2 * S)]


def _two_stacked(space):
    return [_box(space, 0, S / 2, 1.0), _box(space, 0, 1.5 * S, 1.0), _box(space, 0, 2.5 * S, 1000.0)]


def _light_pyramid(space):
    boxes = [_box(space, (c - (3 - r - 1) / 2) * S * 1.05, S / 2 + r * S, 1.0)
             for r in range(3) for c in range(3 - r)]
    return boxes + [_box(space, 0, 3.5 * S, 1000.0)]


def _plank_on_four(space):
    return ([_box(space, x, S / 2, 1.0) for x in (-60.0, -20.0, 20.0, 60.0)]
            + [_box(space, 0, 1.25 * S, 1000.0, w=160.0, h=S / 2)])


RESTING = [("on one, 100x", _on_one(100.0)), ("on one, 1000x", _on_one(1000.0)),
           ("on one, 10000x", _on_one(1e4)), ("on two side by side", _two_side_by_side),
           ("on two stacked", _two_stacked), ("on a pyramid of six", _light_pyramid),
           ("plank on four", _plank_on_four)]


def resting(build):
    space = _space()
    bodies = build(space)
    home = [tuple(b.position) for b in bodies]
    t0 = time.perf_counter()
    for _ in range(600):
        space.step(1 / 60)
    us = (time.perf_counter() - t0) / 600 * 1e6
    return max(math.dist(b.position, h) for b, h in zip(bodies, home)) / S, us


def solver2d():
    # Solver2D's HighMassRatio1, boxes of half extent 1 (its units).
    space = _space(gravity=10.0)
    space.collision_slop = 0.005
    tops, landed = [], []
    for j in range(3):
        count, offset, y = 10, -20.0 + 2 * 11 * j, 1.0
        while count > 0:
            for i in range(count):
                heavy = count == 1
                mass = ((j + 1) * 100 if heavy else 1) * 4.0
                b = _box(space, 2 * (i - 0.5 * count) + offset, y + 2 if heavy else y, mass,
                         w=2.0, h=2.0)
                if heavy:
                    tops.append(b)
                    landed.append(y)
            count -= 1
            y += 2.0
    for _ in range(300):
        space.step(1 / 60)
    t0 = time.perf_counter()
    for _ in range(300):
        space.step(1 / 60)
    us = (time.perf_counter() - t0) / 300 * 1e6
    return [h - t.position.y for t, h in zip(tops, landed)], us


def impacts(seed):
    rng = random.Random(seed)
    space = _space()
    for a, b in (((-400, 0), (-400, 800)), ((400, 0), (400, 800))):
        space.add(tamias2d.Segment(space.static_body, a, b, 2.0))
    boxes = [_box(space, rng.uniform(-300, 300), 20 + (i // 10) * 25 + rng.uniform(0, 5), 1.0,
                  elasticity=rng.choice([0.0, 0.3])) for i in range(60)]
    for k in range(3):
        ball = tamias2d.Body(1000.0, tamias2d.moment_for_circle(1000.0, 0, 30))
        ball.position = -200 + 200 * k, 400
        shape = tamias2d.Circle(ball, 30)
        shape.friction, shape.elasticity = 0.6, 0.2
        space.add(ball, shape)
    _box(space, 0, 600, 1000.0, w=120, h=20)
    t0 = time.perf_counter()
    for _ in range(1200):
        space.step(1 / 60)
    us = (time.perf_counter() - t0) / 1200 * 1e6
    return min(b.position.y for b in boxes) < 0.0, us


def impacts_box2d(seed):
    # The same scene and random draws in Box2D v3 (pyb2d3, 4 substeps), in
    # boxes of 1 (Box2D's tolerances are for objects of about a metre).
    import pyb2d3 as b2

    def shape_def(density, friction, restitution=0.0):
        return box2d_shape_def(b2, density, friction, restitution)

    rng = random.Random(seed)
    world = b2.World(gravity=(0, -G / S))
    world.sleeping_enabled = False
    ground = world.create_static_body(position=(0, 0))
    ground.create_segment_shape(shape_def(1.0, 1.0), b2.segment((-100, 0), (100, 0)))
    for x in (-20.0, 20.0):
        ground.create_capsule_shape(shape_def(1.0, 0.6), b2.capsule((x, 0), (x, 40), 0.1))
    boxes = []
    for i in range(60):
        x, y = rng.uniform(-300, 300), 20 + (i // 10) * 25 + rng.uniform(0, 5)
        body = world.create_dynamic_body(position=(x / S, y / S))
        body.create_polygon_shape(shape_def(1.0, 0.6, rng.choice([0.0, 0.3])), b2.box(0.5, 0.5))
        boxes.append(body)
    r = 30 / S
    for k in range(3):
        ball = world.create_dynamic_body(position=((-200 + 200 * k) / S, 400 / S))
        ball.create_circle_shape(shape_def(1000.0 / (math.pi * r * r), 0.6, 0.2), b2.circle((0, 0), r))
    plank = world.create_dynamic_body(position=(0, 600 / S))
    plank.create_polygon_shape(shape_def(1000.0 / 6.0, 0.6), b2.box(3.0, 0.5))
    t0 = time.perf_counter()
    for _ in range(1200):
        world.step(1 / 60, 4)
    us = (time.perf_counter() - t0) / 1200 * 1e6
    return min(b.position[1] for b in boxes) < 0.0, us


def _impacts_cell(run, seeds):
    # In how many seeds a light box ends below the floor, and the median
    # cost of a step.
    runs = [run(seed) for seed in range(1, seeds + 1)]
    through = sum(1 for lost, _ in runs if lost)
    return f"{through} of {len(runs)} ({statistics.median(us for _, us in runs):.0f} us)"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    args = ap.parse_args()
    modes = (("blocks", True), ("one by one", False))
    try:
        import pyb2d3  # noqa: F401
        box2d = True
    except ImportError:
        box2d = False
    try:
        print("| resting (largest move, boxes; us a step) | " + " | ".join(m for m, _ in modes) + " |")
        print("|---|" + "---|" * len(modes))
        for name, build in RESTING:
            cells = []
            for _, on in modes:
                _soft_step._mass_ratio_blocks(on)
                moved, us = resting(build)
                cells.append(f"{moved:.3g} ({us:.0f} us)")
            print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
        cells = []
        for _, on in modes:
            _soft_step._mass_ratio_blocks(on)
            sinks, us = solver2d()
            cells.append(" / ".join(f"{x:.3f}" for x in sinks) + f" ({us:.0f} us)")
        print("| solver2d: tops below landing, units | " + " | ".join(cells) + " |", flush=True)
        cells = []
        for _, on in modes:
            _soft_step._mass_ratio_blocks(on)
            cells.append(_impacts_cell(impacts, args.seeds))
        print("| impacts: seeds with a box through the floor | " + " | ".join(cells) + " |")
        if box2d:
            print(f"| impacts in Box2D v3 (pyb2d3, 4 substeps) | "
                  f"{_impacts_cell(impacts_box2d, args.seeds)} | |")
    finally:
        _soft_step._mass_ratio_blocks(True)


if __name__ == "__main__":
    main()
