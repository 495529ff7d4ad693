"""The hard case's house of cards (tests/hard_cases.py's `card_house`) over a
sweep of its lean, friction and pitch, in tamias2d's soft solver beside
Box2D v3 (pyb2d3, the `bench` extra).

27 houses of 3 levels: each card 40 x 1, mass 1, leaning 0.2, 0.3 or 0.4
rad from the vertical; contact friction 0.36, 0.49 or 0.64; A-frames 30, 36
or 39 apart (the flat cards, 40 long, bridge two frames and so overlap their
neighbour at the same level by 10, 4 or 1). Gravity 900, slop 0.1, dt 1/60,
600 steps, sleeping off; Box2D gets the scene scaled by 1/20 (its slop
0.005 m is then the same) and 4 substeps. A house stands if no card moves
more than 2 units (0.05 of a card) and none turns more than 0.05 rad, the
hard case's criterion. Friction is given as what a contact gets: tamias2d
multiplies two shapes' friction, Box2D takes their geometric mean, so each
shape gets the square root in tamias2d and the value in Box2D.

    PYTHONPATH=src python benchmarks/card_house_sweep.py [--solver soft]
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))

import tamias2d  # noqa: E402
import hard_cases  # noqa: E402

from harness import box2d_hard_case_world, box2d_shape_def, largest_motion  # noqa: E402

STEPS = 600
SCALE = 1.0 / 20.0
LEANS = (0.2, 0.3, 0.4)
FRICTIONS = (0.36, 0.49, 0.64)
PITCHES = (30.0, 36.0, 39.0)
LENGTH, THICK = 40.0, 1.0


def tamias(solver, lean, friction, pitch):
    scene = hard_cases.build_card_house(tamias2d, lean=lean, pitch=pitch,
                                        friction=math.sqrt(friction))
    scene.space.solver = solver
    return (lambda: scene.space.step(1.0 / 60.0)), scene.watch["cards"], 1.0


def box2d(lean, friction, pitch):
    """The same house, card for card: hard_cases.build_card_house builds it
    in tamias2d and each card's pose is copied, scaled."""
    import pyb2d3 as b2
    scene = hard_cases.build_card_house(tamias2d, lean=lean, pitch=pitch)
    world = box2d_hard_case_world(b2, SCALE, friction)
    cards = []
    for card in scene.watch["cards"]:
        body = world.create_dynamic_body(position=(card.position.x * SCALE,
                                                   card.position.y * SCALE),
                                         rotation=card.angle)
        # Density 1 / area: mass 1, as the tamias2d cards.
        body.create_polygon_shape(
            box2d_shape_def(b2, 1.0 / (LENGTH * THICK * SCALE * SCALE), friction),
            b2.box(THICK * SCALE / 2.0, LENGTH * SCALE / 2.0))
        cards.append(body)
    return (lambda: world.step(1.0 / 60.0, 4)), cards, SCALE


def run(engine, lean, friction, pitch):
    step, cards, scale = engine(lean, friction, pitch)
    moved, turned = largest_motion(step, cards, scale, STEPS, LENGTH)
    return moved < 0.05 * LENGTH and turned < 0.05, moved, turned


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--solver", action="append", choices=("soft", "chipmunk"),
                    help="tamias2d solvers to run (default: soft)")
    args = ap.parse_args()
    engines = [(f"tamias2d {s}", (lambda s: lambda *a: tamias(s, *a))(s))
               for s in (args.solver or ["soft"])]
    try:
        import pyb2d3  # noqa: F401
        engines.insert(0, ("Box2D v3", box2d))
    except ImportError:
        print("(pyb2d3 is not installed: Box2D left out; pip install .[bench])", file=sys.stderr)
    names = [name for name, _ in engines]
    print("| lean | friction | pitch | " + " | ".join(names) + " |")
    print("|---|---|---|" + "---|" * len(names))
    standing = dict.fromkeys(names, 0)
    for lean in LEANS:
        for friction in FRICTIONS:
            for pitch in PITCHES:
                cells = []
                for name, engine in engines:
                    ok, moved, turned = run(engine, lean, friction, pitch)
                    standing[name] += ok
                    cells.append(f"{'stands' if ok else 'falls'} ({moved:.3g}, {turned:.2g})")
                print(f"| {lean} | {friction} | {pitch:g} | " + " | ".join(cells) + " |",
                      flush=True)
    total = len(LEANS) * len(FRICTIONS) * len(PITCHES)
    print("\n(largest move in units, largest turn in rad)\n")
    print("; ".join(f"{name} stands {n} of {total}" for name, n in standing.items()))


if __name__ == "__main__":
    main()
