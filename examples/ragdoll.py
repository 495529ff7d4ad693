"""Ragdolls tumbling down a staircase.

A ragdoll is nine capsules (segment shapes with a radius) and a round head.
Every joint is a PivotJoint, which holds two parts together at a point, and a
RotaryLimitJoint, which keeps the angle between them in a human range
(elbows and knees bend one way only). The parts of one ragdoll share a
ShapeFilter group so that they don't collide with each other.

    python examples/ragdoll.py
    python examples/ragdoll.py --headless --frames 400
"""
import random

import _common
import tamias2d
from tamias2d import Vec2d

space = tamias2d.Space()
space.gravity = (0, -900)
space.iterations = 20
rng = random.Random(5)

# A staircase: 14 steps, 55 px deep and 26 px high, then a floor.
corners, x, y = [(0, 390)], 0, 390
for _ in range(14):
    x += 55
    corners.append((x, y))
    y -= 26
    corners.append((x, y))
corners.append((900, y))
for a, b in zip(corners, corners[1:]):
    step = tamias2d.Segment(space.static_body, a, b, 3)
    step.friction = 0.5
    step.color = _common.GROUND
    space.add(step)


def ragdoll(x, y, group, color):
    """A ragdoll standing with its hips at (x, y); returns its bodies."""
    parts = tamias2d.ShapeFilter(group=group)
    bodies = []

    def capsule(a, b, radius, mass):
        a, b = Vec2d(*a), Vec2d(*b)
        body = tamias2d.Body(mass, tamias2d.moment_for_segment(mass, a, b, radius))
        body.position = (a + b) / 2
        shape = tamias2d.Segment(body, a - body.position, b - body.position, radius)
        shape.friction, shape.filter, shape.color = 0.5, parts, color
        space.add(body, shape)
        bodies.append(body)
        return body

    def joint(a, b, at, lo, hi):
        # lo..hi bounds b's angle relative to a's, from the pose built here.
        space.add(tamias2d.PivotJoint(a, b, at), tamias2d.RotaryLimitJoint(a, b, lo, hi))

    torso = capsule((x, y + 6), (x, y + 42), 9, 6)
    head = tamias2d.Body(2, tamias2d.moment_for_circle(2, 0, 11))
    head.position = x, y + 64
    shape = tamias2d.Circle(head, 11)
    shape.friction, shape.filter, shape.color = 0.5, parts, color
    space.add(head, shape)
    bodies.append(head)
    joint(torso, head, (x, y + 52), -0.6, 0.6)
    for side in (-1, 1):  # the same limbs on both sides, a little apart
        sx = x + 5 * side
        upper_arm = capsule((sx, y + 44), (sx, y + 20), 4, 1)
        lower_arm = capsule((sx, y + 20), (sx, y - 2), 4, 1)
        joint(torso, upper_arm, (sx, y + 44), -3.0, 3.0)
        joint(upper_arm, lower_arm, (sx, y + 20), 0.0, 2.5)     # elbow
        thigh = capsule((sx, y), (sx, y - 28), 6, 3)
        shin = capsule((sx, y - 28), (sx, y - 56), 5, 2)
        joint(torso, thigh, (sx, y), -2.0, 0.5)                 # hip
        joint(thigh, shin, (sx, y - 28), -2.5, 0.0)             # knee
    return bodies


dolls = 0


def update(frame):
    global dolls
    if frame % 80 == 0 and dolls < 6:
        dolls += 1
        # Thrown forwards and spinning a little, so that it tumbles.
        bodies = ragdoll(40, 455, group=dolls, color=_common.PALETTE[dolls % 7])
        v, spin, centre = Vec2d(rng.uniform(220, 320), 150), rng.uniform(-3, 0), Vec2d(40, 455)
        for body in bodies:  # as one rigid body: v + spin x (p - centre)
            body.velocity = v + (body.position - centre).perpendicular() * spin
            body.angular_velocity = spin
    space.step(_common.DT)


def draw(canvas):
    canvas.space(space)
    canvas.text(f"{dolls} ragdolls: 10 bodies, 9 pivot and 9 rotary limit joints each",
                at=(300, 8))


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: ragdolls", size=(900, 500), frames=400)
