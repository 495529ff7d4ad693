"""Chains: a rope bridge that catches falling boxes, and a swinging chain.

Each chain is a row of thin segment bodies joined end to end by PivotJoints.
The links of one chain share a ShapeFilter group, so they never collide with
each other (neighbours overlap at their joints) but still hit everything
else. More solver iterations make a long chain stretch less.

    python examples/chain.py
    python examples/chain.py --headless --frames 300
"""
import random

import _common
import tamias2d

space = tamias2d.Space()
space.gravity = (0, -900)
space.iterations = 30  # long joint chains need more than the default 10
static = space.static_body
rng = random.Random(2)


def chain(points, group, pin_start=True, pin_end=True):
    """A chain whose links run from each point to the next; pinned to the
    world at its first and last points if asked. Returns the link bodies."""
    bodies = []
    for a, b in zip(points, points[1:]):
        a, b = tamias2d.Vec2d(*a), tamias2d.Vec2d(*b)
        length = (b - a).length
        body = tamias2d.Body(1, tamias2d.moment_for_segment(1, (0, 0), (length, 0), 3))
        body.position = a          # the body's origin is the link's first end
        body.angle = (b - a).angle
        link = tamias2d.Segment(body, (0, 0), (length, 0), 3)
        link.friction = 0.9
        link.filter = tamias2d.ShapeFilter(group=group)
        link.color = (90, 100, 110, 255)
        space.add(body, link)
        bodies.append(body)
    # Where two links meet, one pivot (given as a world point) holds them.
    joints = [tamias2d.PivotJoint(p, q, q.position) for p, q in zip(bodies, bodies[1:])]
    if pin_start:
        joints.append(tamias2d.PivotJoint(static, bodies[0], points[0]))
    if pin_end:
        joints.append(tamias2d.PivotJoint(static, bodies[-1], points[-1]))
    space.add(*joints)
    return bodies


# The bridge: 30 links between posts 328 px apart, 10% longer than the gap
# so that it hangs slack. Built in a V (a straight chain would have to
# stretch) and left to settle into its curve.
for post in (80, 420):
    shape = tamias2d.Segment(static, (post, 0), (post, 300), 6)
    shape.color = _common.GROUND
    space.add(shape)
half_gap, half_len = 164.0, 164.0 * 1.1
sag = (half_len ** 2 - half_gap ** 2) ** 0.5
v = [(86 + half_gap * k / 15, 300 - sag * k / 15) for k in range(16)]
v += [(250 + half_gap * k / 15, 300 - sag + sag * k / 15) for k in range(1, 16)]
chain(v, group=1)

# The swinging chain: 16 links held out sideways, pinned at one end only,
# with a heavy ball at the other; it falls and swings.
links = chain([(560 + 14 * k, 460) for k in range(17)], group=2, pin_end=False)
weight = tamias2d.Body(10, tamias2d.moment_for_circle(10, 0, 18))
weight.position = 560 + 14 * 16 + 18, 460
ball = tamias2d.Circle(weight, 18)
ball.color = _common.PALETTE[1]
ball.filter = tamias2d.ShapeFilter(group=2)
space.add(weight, ball, tamias2d.PivotJoint(links[-1], weight, (560 + 14 * 16, 460)))


def update(frame):
    if frame % 15 == 0 and frame < 300:
        body = tamias2d.Body(1, tamias2d.moment_for_box(1, (28, 28)))
        body.position = rng.uniform(150, 350), 520
        body.angle = rng.uniform(0, 3)
        box = tamias2d.Poly.create_box(body, (28, 28))
        box.friction = 0.6
        box.color = _common.PALETTE[rng.randrange(len(_common.PALETTE))]
        space.add(body, box)
    space.step(_common.DT)


def draw(canvas):
    canvas.space(space)
    canvas.text([f"rope bridge: 30 links, {space.iterations} solver iterations",
                 "swinging chain: 16 links and a 10 kg ball"])


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: chains", size=(900, 500), frames=300)
