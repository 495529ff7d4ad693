"""Stacks, pyramids and mass ratios in tamias2d (both solvers) beside
Box2D v3 (pyb2d3, the `bench` extra), in several unit systems.

The same scenes (boxes of mass 1 and friction 0.6 on a static ground, 600
steps of 1/60 s, Box2D at its 4 substeps, sleeping off), judged alike:
  stack N   top drift < 0.1 box, no box turns > 0.1 rad, top sag < 0.25 box
  pyr N     no box moves > 0.25 box sideways, the top sinks < 0.25 box,
            kinetic energy at the end < 0.01 m g L per box (no jitter)
  ratio R   a box R times heavier on a light one: the gap between them and
            the light one's sink both stay within 0.05 box all the time
Box2D's units are fixed (linear slop 0.005 m); tamias2d is run with the
scene's collision_slop given in the table.

    PYTHONPATH=src python benchmarks/box2d_hard.py [--verbose]
"""
import argparse
import sys

import tamias2d

from harness import box2d_shape_def

STEPS = 600
DT = 1.0 / 60.0
SCENES = (("stack 20", "stack", 20), ("stack 40", "stack", 40), ("pyr 20", "pyramid", 20),
          ("pyr 40", "pyramid", 40), ("ratio 100", "ratio", 100), ("ratio 1000", "ratio", 1000))
UNITS = ((20.0, 900.0, 0.1), (50.0, 1000.0, 0.1), (1.0, 10.0, 0.1), (1.0, 10.0, 0.005),
         (1.0, 9.81, 0.01))


class Tamias:
    def __init__(self, solver, g, slop):
        self.s = tamias2d.Space(solver=solver)
        self.s.gravity = 0, -g
        self.s.collision_slop = slop
        ground = tamias2d.Segment(self.s.static_body, (-2000, -0.5), (2000, -0.5), 0.5)
        ground.friction = 0.6
        self.s.add(ground)

    def box(self, x, y, size, mass=1.0):
        b = tamias2d.Body(mass, tamias2d.moment_for_box(mass, (size, size)))
        b.position = x, y
        p = tamias2d.Poly.create_box(b, (size, size))
        p.friction = 0.6
        self.s.add(b, p)
        return b

    def step(self):
        self.s.step(DT)

    @staticmethod
    def pos(b):
        return b.position.x, b.position.y

    @staticmethod
    def angle(b):
        return b.angle

    @staticmethod
    def speed2(b):
        return b.velocity.length ** 2


class Box2D:
    def __init__(self, g):
        import pyb2d3 as b2
        self.b2 = b2
        self.w = b2.World(gravity=(0, -g))
        self.w.sleeping_enabled = False
        ground = self.w.create_static_body(position=(0, -0.5))
        ground.create_polygon_shape(self.sdef(1.0), b2.box(2000, 0.5))

    def sdef(self, density):
        return box2d_shape_def(self.b2, density, 0.6)

    def box(self, x, y, size, mass=1.0):
        b = self.w.create_dynamic_body(position=(x, y))
        b.create_polygon_shape(self.sdef(mass / (size * size)), self.b2.box(size / 2, size / 2))
        return b

    def step(self):
        self.w.step(DT, 4)

    @staticmethod
    def pos(b):
        p = b.position
        return p[0], p[1]

    @staticmethod
    def angle(b):
        return b.angle

    @staticmethod
    def speed2(b):
        v = b.linear_velocity
        return v[0] ** 2 + v[1] ** 2


def stack(e, n, size, g):
    bs = [e.box(0, size / 2 + i * size, size) for i in range(n)]
    drift = ang = 0.0
    for _ in range(STEPS):
        e.step()
        drift = max(drift, abs(e.pos(bs[-1])[0]))
        ang = max(ang, max(abs(e.angle(b)) for b in bs))
    sag = (n - 0.5) * size - e.pos(bs[-1])[1]
    return (drift < 0.1 * size and ang < 0.1 and abs(sag) < 0.25 * size,
            f"drift {drift / size:.3f}, angle {ang:.3f}, sag {sag / size:.3f} box")


def pyramid(e, rows, size, g):
    bs = [e.box((c - (rows - r - 1) / 2) * size, size / 2 + r * size, size)
          for r in range(rows) for c in range(rows - r)]
    home = [e.pos(b) for b in bs]
    side = sink = 0.0
    for i in range(STEPS):
        e.step()
        if i % 10 == 9:
            side = max(side, max(abs(e.pos(b)[0] - h[0]) for b, h in zip(bs, home)))
            sink = max(sink, home[-1][1] - e.pos(bs[-1])[1])
    ke = sum(0.5 * e.speed2(b) for b in bs) / (g * size)
    return (side < 0.25 * size and sink < 0.25 * size and ke < 0.01 * len(bs),
            f"sideways {side / size:.3f}, sink {sink / size:.3f} box, KE/(m g L) {ke:.3g}")


def ratio(e, r, size, g):
    light = e.box(0, size / 2, size)
    heavy = e.box(0, 1.5 * size, size, mass=r)
    worst = 0.0
    for _ in range(STEPS):
        e.step()
        worst = max(worst, abs(size - (e.pos(heavy)[1] - e.pos(light)[1])),
                    abs(size / 2 - e.pos(light)[1]))
    return worst < 0.05 * size, f"worst gap or sink {worst / size:.3f} box"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--verbose", action="store_true", help="print every scene's numbers")
    args = ap.parse_args()
    try:
        import pyb2d3  # noqa: F401
        engines = ("chipmunk", "soft", "box2d")
    except ImportError:
        print("pyb2d3 is not installed (pip install pyb2d3): tamias2d only", file=sys.stderr)
        engines = ("chipmunk", "soft")
    fns = {"stack": stack, "pyramid": pyramid, "ratio": ratio}
    totals = dict.fromkeys(engines, 0)
    print("| box size, gravity, slop | engine | " + " | ".join(n for n, _, _ in SCENES) + " |")
    print("|---|---|" + "---|" * len(SCENES))
    for size, g, slop in UNITS:
        for eng in engines:
            cells = []
            for label, kind, arg in SCENES:
                e = Box2D(g) if eng == "box2d" else Tamias(eng, g, slop)
                ok, numbers = fns[kind](e, arg, size, g)
                totals[eng] += ok
                cells.append("pass" if ok else "FAIL")
                if args.verbose:
                    print(f"  {size:g} {g:g} {slop:g} {eng} {label}: {numbers}", file=sys.stderr)
            where = f"{size:g}, {g:g}, {slop:g}" if eng != "box2d" else f"{size:g}, {g:g}, (0.005 m)"
            print(f"| {where} | {eng} | " + " | ".join(cells) + " |", flush=True)
    n = len(UNITS) * len(SCENES)
    print()
    print("passed: " + ", ".join(f"{eng} {totals[eng]} of {n}" for eng in engines))


if __name__ == "__main__":
    main()
