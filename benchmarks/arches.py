"""Arches held by friction alone (tests/hard_cases.py's `arch`) in tamias2d's
two solvers beside Box2D v3 (pyb2d3, the `bench` extra).

A semicircular arch of N trapezoids between radii 80 and 100 (the hard
case has 11), standing on a static ground, in the hard cases' units
(gravity 900, slop 0.1; Box2D gets the scene scaled by 1/20, its slop 0.005
m then being the same), dt 1/60, 1800 steps, sleeping off. It stands if no
block moves more than 0.05 of the arch's thickness and none turns more
than 0.02 rad (the hard case's criterion). Friction is given as what a
contact gets: Chipmunk multiplies two shapes' friction, Box2D takes their
geometric mean, so each shape gets the square root in tamias2d and the
value in Box2D. The 10-unit arch (radii 90 to 100) is below the least
thickness a semicircular arch needs to stand at all (about 0.107 of its
mean radius, Heyman's), so every engine should let it fall: a control.

    PYTHONPATH=src python benchmarks/arches.py
"""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))

import tamias2d  # noqa: E402
import hard_cases  # noqa: E402

from harness import box2d_hard_case_world, box2d_shape_def, largest_motion  # noqa: E402

STEPS = 1800
SCALE = 1.0 / 20.0
ARCHES = ((7, 80.0, 100.0), (11, 80.0, 100.0), (15, 80.0, 100.0), (21, 80.0, 100.0),
          (11, 90.0, 100.0))
FRICTIONS = (0.36, 0.6)


def tamias(solver, count, inner, outer, friction):
    # The hard case's own builder (friction on each shape: the square root).
    scene = hard_cases.build_arch(tamias2d, count, inner, outer, math.sqrt(friction))
    scene.space.solver = solver
    return (lambda: scene.space.step(1.0 / 60.0)), scene.watch["stones"], 1.0


def box2d(count, inner, outer, friction):
    import pyb2d3 as b2
    world = box2d_hard_case_world(b2, SCALE, friction)
    stones = []
    for (cx, cy), verts in hard_cases.arch_blocks(count, inner, outer):
        pts = [(x * SCALE, y * SCALE) for x, y in verts]
        area = 0.5 * abs(sum(pts[k][0] * pts[k - 3][1] - pts[k - 3][0] * pts[k][1]
                             for k in range(4)))
        body = world.create_dynamic_body(position=(cx * SCALE, cy * SCALE))
        # Density 1 / area: mass 1, as the tamias2d blocks.
        body.create_polygon_shape(box2d_shape_def(b2, 1.0 / area, friction), b2.polygon(points=pts))
        stones.append(body)
    return (lambda: world.step(1.0 / 60.0, 4)), stones, SCALE


def run(engine, count, inner, outer, friction):
    step, stones, scale = engine(count, inner, outer, friction)
    moved, turned = largest_motion(step, stones, scale, STEPS, 10.0 * (outer - inner))
    return moved < 0.05 * (outer - inner) and turned < 0.02, moved, turned


def main():
    engines = [("tamias2d soft", lambda *a: tamias("soft", *a)),
               ("tamias2d chipmunk", lambda *a: tamias("chipmunk", *a))]
    try:
        import pyb2d3  # noqa: F401
        engines.insert(0, ("Box2D v3", box2d))
    except ImportError:
        print("(pyb2d3 is not installed: Box2D left out; pip install .[bench])", file=sys.stderr)
    heads = [f"{n} blocks, {outer - inner:g} thick, friction {f}"
             for n, inner, outer in ARCHES for f in FRICTIONS]
    print("| engine | " + " | ".join(heads) + " |")
    print("|---|" + "---|" * len(heads))
    for name, engine in engines:
        cells = []
        for n, inner, outer in ARCHES:
            for f in FRICTIONS:
                ok, moved, turned = run(engine, n, inner, outer, f)
                cells.append(f"{'stands' if ok else 'falls'} ({moved:.3g}, {turned:.2g})")
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    print("\n(largest move in the arch's units, largest turn in rad)")


if __name__ == "__main__":
    main()
