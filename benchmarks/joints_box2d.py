"""A chain carrying a heavy ball in tamias2d (both solvers) beside Box2D v3
(pyb2d3, the `bench` extra): how far its pivots open.

15 links of mass 1 and length 20 (capsules of radius 2, not colliding with
each other), pinned to the world at one end and to a ball of radius 10 and
`ratio` times a link's mass at the other, released horizontal under gravity
900 for 300 steps of 1/60 s. Box2D builds the same scene in metres (lengths
and gravity times 0.01, revolute joints); its gaps are reported in the same
units as tamias2d's. Printed per engine and setting: the largest distance
between the two anchors of any pivot over the whole run, and over its last
second.

Criterion, written before the first run: at ratio 100 the worst gap stays
below 2 (a tenth of a link) and below 1 over the last second.

    PYTHONPATH=src python benchmarks/joints_box2d.py
"""
import math

import tamias2d

from harness import box2d_shape_def

LINKS = 15
STEPS = 300
DT = 1.0 / 60.0


def tamias_chain(ratio, solver, iterations=10, substeps=4):
    s = tamias2d.Space(solver=solver)
    s.iterations = iterations
    s.substeps = substeps
    s.gravity = 0, -900
    apart = tamias2d.ShapeFilter(group=1)
    links = []
    prev = s.static_body
    for i in range(LINKS):
        b = tamias2d.Body(1, tamias2d.moment_for_segment(1, (-10, 0), (10, 0), 2))
        b.position = 20 * i + 10, 0
        link = tamias2d.Segment(b, (-10, 0), (10, 0), 2)
        link.filter = apart
        s.add(b, link)
        s.add(tamias2d.PivotJoint(prev, b, (20 * i, 0)))
        links.append(b)
        prev = b
    ball = tamias2d.Body(ratio, tamias2d.moment_for_circle(ratio, 0, 10))
    ball.position = 20 * LINKS + 10, 0
    shape = tamias2d.Circle(ball, 10)
    shape.filter = apart
    s.add(ball, shape)
    s.add(tamias2d.PivotJoint(prev, ball, (20 * LINKS, 0)))

    def gaps():
        ends = [s.static_body.position] + [b.local_to_world((10, 0)) for b in links]
        starts = [b.local_to_world((-10, 0)) for b in links] + [ball.local_to_world((-10, 0))]
        return max((p - q).length for p, q in zip(ends, starts))
    return lambda: s.step(DT), gaps


def box2d_chain(ratio, substeps=4):
    import pyb2d3 as b2
    scale = 0.01
    w = b2.World(gravity=(0, -900 * scale))
    ground = w.create_static_body(position=(0, 0))
    half = 10 * scale
    links = []
    prev = ground
    for i in range(LINKS):
        b = w.create_dynamic_body(position=((20 * i + 10) * scale, 0))
        d = box2d_shape_def(b2, 1.0, group_index=-1)
        b.create_capsule_shape(d, b2.capsule((-half, 0), (half, 0), 2 * scale))
        anchor = (20 * i * scale, 0) if prev is ground else (half, 0)
        w.create_revolute_joint(body_a=prev, body_b=b, local_anchor_a=anchor,
                                local_anchor_b=(-half, 0))
        links.append(b)
        prev = b
    radius = 10 * scale
    ball = w.create_dynamic_body(position=((20 * LINKS + 10) * scale, 0))
    d = box2d_shape_def(b2, ratio * links[0].mass / (math.pi * radius * radius), group_index=-1)
    ball.create_circle_shape(d, b2.circle(radius=radius))
    w.create_revolute_joint(body_a=prev, body_b=ball, local_anchor_a=(half, 0),
                            local_anchor_b=(-half, 0))

    def world_point(b, p):
        x, y = b.position
        c, s = math.cos(b.angle), math.sin(b.angle)
        return x + c * p[0] - s * p[1], y + s * p[0] + c * p[1]

    def gaps():
        ends = [(0.0, 0.0)] + [world_point(b, (half, 0)) for b in links]
        starts = [world_point(b, (-half, 0)) for b in links] + [world_point(ball, (-half, 0))]
        return max(math.dist(p, q) for p, q in zip(ends, starts)) / scale
    return lambda: w.step(DT, substeps), gaps


def run(step, gaps):
    worst = last = 0.0
    for i in range(STEPS):
        step()
        g = gaps()
        worst = max(worst, g)
        if i >= STEPS - 60:
            last = max(last, g)
    return worst, last


def main():
    engines = [("chipmunk, 10 iterations", lambda r: tamias_chain(r, "chipmunk")),
               ("chipmunk, 30 iterations", lambda r: tamias_chain(r, "chipmunk", iterations=30)),
               ("soft, 4 substeps", lambda r: tamias_chain(r, "soft")),
               ("soft, 8 substeps", lambda r: tamias_chain(r, "soft", substeps=8))]
    try:
        import pyb2d3  # noqa: F401
        engines += [("box2d, 4 substeps", lambda r: box2d_chain(r)),
                    ("box2d, 8 substeps", lambda r: box2d_chain(r, substeps=8))]
    except ImportError:
        print("(pyb2d3 not installed: `pip install .[bench]` for the Box2D rows)")
    ratios = (1.0, 10.0, 100.0)
    print("| engine | " + " | ".join(f"ball {r:g}x: worst / last second" for r in ratios) + " |")
    print("|---|" + "---|" * len(ratios))
    for name, build in engines:
        cells = ["%.3g / %.3g" % run(*build(r)) for r in ratios]
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
