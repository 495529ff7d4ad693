"""Box2D's own "Card House" sample (after PEEL) in tamias2d beside Box2D v3.

Forty cards 0.002 x 0.4 (metres, density 1), leaning pairs at 25 degrees
with flat cards across them, five levels, on a static ground; gravity 10,
dt 1/60, 600 steps, sleeping off. The layout is the sample's: its flat
cards overlap their neighbours by 0.05 and every level starts a few
millimetres above the one below, so the house settles by about 0.035
before it stands.

Friction is given as what a contact gets: Box2D mixes two shapes' friction
by the geometric mean, Chipmunk (so tamias2d and pymunk) multiplies them,
so each shape gets the square root in tamias2d and the value in Box2D. The
sample's own 0.7 is the first column; a port that sets 0.7 on every shape
in tamias2d gets 0.49, the last one.

"Stands": over the run no card moves more than a quarter of its length
(0.1) and none turns more than 0.1 rad; a house that falls moves its cards
by metres and turns them by radians.

    PYTHONPATH=src python benchmarks/card_houses.py [--verbose]
"""
import argparse
import math
import sys

import tamias2d

from harness import box2d_shape_def

HALF_HEIGHT, HALF_THICK = 0.2, 0.001
FRICTIONS = (0.7, 0.6, 0.49)
SUBSTEPS = (4, 8)
STEPS = 600


def layout():
    """(x, y, angle) of each card, in the sample's order."""
    cards = []
    count, x0, y = 5, 0.0, HALF_HEIGHT - 0.02
    while count:
        x = x0
        for i in range(count):
            if i != count - 1:
                cards.append((x + 0.25, y + HALF_HEIGHT - 0.015, 0.5 * math.pi))
            cards.append((x, y, -math.radians(25)))
            x += 0.175
            cards.append((x, y, math.radians(25)))
            x += 0.175
        y += 2 * HALF_HEIGHT - 0.03
        x0 += 0.175
        count -= 1
    return cards


def tamias(solver, friction, substeps):
    space = tamias2d.Space(solver=solver)
    space.gravity = 0, -10
    space.collision_slop = 0.005     # Box2D's linear slop, as in against_box2d.py
    if solver == "soft":
        space.substeps = substeps
    else:
        space.iterations = 10 * substeps // 4
    ground = tamias2d.Poly(space.static_body, [(-40, -4), (40, -4), (40, 0), (-40, 0)])
    ground.friction = math.sqrt(friction)
    space.add(ground)
    w, h = 2 * HALF_THICK, 2 * HALF_HEIGHT
    mass = w * h
    bodies = []
    for x, y, angle in layout():
        body = tamias2d.Body(mass, tamias2d.moment_for_box(mass, (w, h)))
        body.position = x, y
        body.angle = angle
        shape = tamias2d.Poly.create_box(body, (w, h))
        shape.friction = math.sqrt(friction)
        space.add(body, shape)
        bodies.append(body)
    return (lambda: space.step(1 / 60)), bodies


def box2d(friction, substeps):
    import pyb2d3 as b2
    world = b2.World(gravity=(0, -10))
    world.sleeping_enabled = False
    shape_def = box2d_shape_def(b2, friction=friction)
    ground = world.create_static_body(position=(0, -2))
    ground.create_polygon_shape(shape_def, b2.box(40, 2))
    bodies = []
    for x, y, angle in layout():
        body = world.create_dynamic_body(position=(x, y), rotation=angle)
        body.create_polygon_shape(shape_def, b2.box(HALF_THICK, HALF_HEIGHT))
        bodies.append(body)
    return (lambda: world.step(1 / 60, substeps)), bodies


def pose(body):
    # Either engine's body: its position as a tuple, and its angle.
    return tuple(body.position), body.angle


def run(engine, friction, substeps):
    if engine == "box2d":
        step, bodies = box2d(friction, substeps)
    else:
        step, bodies = tamias(engine, friction, substeps)
    home = [pose(b) for b in bodies]
    moved = turned = 0.0
    for _ in range(STEPS):
        step()
        for b, (p, a) in zip(bodies, home):
            q, angle = pose(b)
            moved = max(moved, math.dist(q, p))
            turned = max(turned, abs(angle - a))
    stands = moved < 0.1 and turned < 0.1
    return stands, moved, turned


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--verbose", action="store_true", help="print each run's largest move and turn")
    args = ap.parse_args()
    engines = ["soft", "chipmunk"]
    try:
        import pyb2d3  # noqa: F401
        engines.insert(0, "box2d")
    except ImportError:
        print("pyb2d3 is not installed (pip install pyb2d3): tamias2d only", file=sys.stderr)
    columns = [(f, n) for f in FRICTIONS for n in SUBSTEPS]
    print("| engine | " + " | ".join(f"friction {f:g}, {n} substeps" for f, n in columns) + " |")
    print("|---|" + "---|" * len(columns))
    for engine in engines:
        cells = []
        for f, n in columns:
            stands, moved, turned = run(engine, f, n)
            cells.append("stands" if stands else "falls")
            if args.verbose:
                print(f"  {engine} {f:g} {n}: moved {moved:.3f}, turned {turned:.3f}", file=sys.stderr)
        name = {"soft": "tamias2d soft", "chipmunk": "tamias2d chipmunk (10 or 20 iterations)",
                "box2d": "Box2D v3"}[engine]
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
