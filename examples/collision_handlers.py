"""Collision handlers: a sensor zone, one-way platforms and breakable joints.

* Left: a fountain shoots balls up through one-way platforms; a ``begin``
  handler lets a ball through when it comes from below
  (``arbiter.process_collision = False``, which holds until the shapes
  separate), so the balls land on top.
* Middle: a sensor (``shape.sensor = True``) over the bottom of a bin
  counts the balls in it with ``begin`` and ``separate``.
* Right: a bridge of planks on pivot joints; after each step, a joint whose
  force (``constraint.impulse / dt``) went over a limit is removed.

    python examples/collision_handlers.py
    python examples/collision_handlers.py --headless --frames 600
"""
import random

import _common
import tamias2d

BALL, PLATFORM, ZONE = 1, 2, 3  # collision types
BREAK_FORCE = 30000.0  # a force, in the scene's units (kg px / s^2)

space = tamias2d.Space()
space.gravity = (0, -900)
static = space.static_body
rng = random.Random(1)


def segment(a, b, color=_common.GROUND, radius=3):
    shape = tamias2d.Segment(static, a, b, radius)
    shape.friction = 0.8
    shape.color = color
    space.add(shape)
    return shape


def ball(position, velocity, radius=7):
    body = tamias2d.Body(1, tamias2d.moment_for_circle(1, 0, radius))
    body.position = position
    body.velocity = velocity
    shape = tamias2d.Circle(body, radius)
    shape.friction = 0.8
    shape.collision_type = BALL
    shape.color = _common.PALETTE[rng.randrange(len(_common.PALETTE))]
    space.add(body, shape)


# -- one-way platforms -------------------------------------------------------
segment((0, 20), (900, 20))
for y in (160, 260, 360):
    segment((60, y), (250, y), color=(46, 204, 113, 255)).collision_type = PLATFORM


def one_way(arbiter, space, data):
    # The normal points from the ball (shape a) to the platform: up means
    # the ball is below the platform, so let it through.
    if arbiter.normal.y > 0:
        arbiter.process_collision = False


space.on_collision(BALL, PLATFORM, begin=one_way)

# -- a sensor zone in a bin --------------------------------------------------
segment((340, 160), (360, 20))
segment((540, 20), (560, 160))
zone = tamias2d.Poly(static, [(350, 20), (550, 20), (550, 90), (350, 90)])
zone.sensor = True  # reports contacts, never pushes
zone.collision_type = ZONE
zone.color = (241, 196, 15, 90)
space.add(zone)
in_zone = set()
space.on_collision(BALL, ZONE,
                   begin=lambda arb, space, data: in_zone.add(arb.shapes[0]),
                   separate=lambda arb, space, data: in_zone.discard(arb.shapes[0]))

# -- a bridge of planks on breakable joints ----------------------------------
segment((620, 20), (620, 300), radius=6)
segment((880, 20), (880, 300), radius=6)
# 12 planks 25 px long over a 240 px gap: built sagging in a V (each half
# 150 px long), so that the bridge hangs slack instead of pulling itself tight.
half_gap, half_len = 120.0, 150.0
sag = (half_len ** 2 - half_gap ** 2) ** 0.5
ends = [(630 + half_gap * k / 6, 300 - sag * k / 6) for k in range(7)]
ends += [(750 + half_gap * k / 6, 300 - sag + sag * k / 6) for k in range(1, 7)]
joints, previous = [], static
for a, b in zip(ends, ends[1:]):
    plank = tamias2d.Body(0.5, tamias2d.moment_for_box(0.5, (25, 6)))
    plank.position = (a[0] + b[0]) / 2, (a[1] + b[1]) / 2
    plank.angle = tamias2d.Vec2d(b[0] - a[0], b[1] - a[1]).angle
    shape = tamias2d.Poly.create_box(plank, (25, 6))
    shape.friction = 0.8
    shape.color = (160, 110, 70, 255)
    space.add(plank, shape)
    joints.append(tamias2d.PivotJoint(previous, plank, a))
    previous = plank
joints.append(tamias2d.PivotJoint(previous, static, ends[-1]))
for joint in joints:
    joint.collide_bodies = False  # neighbouring planks overlap at the joint
space.add(*joints)
broken = 0


def update(frame):
    global broken
    if frame % 10 == 0:  # a fountain under the platforms
        ball((rng.uniform(80, 220), 30), (rng.uniform(-40, 40), rng.uniform(650, 900)))
    if frame % 12 == 0:  # rain over the bin and the bridge
        ball((rng.choice([rng.uniform(380, 520), rng.uniform(650, 850)]), 520), (0, 0),
             radius=rng.uniform(6, 11))
    space.step(_common.DT)
    for joint in [j for j in joints if j.impulse / _common.DT > BREAK_FORCE]:
        space.remove(joint)
        joints.remove(joint)
        broken += 1
    for body in [b for b in space.bodies if b.position.y < -100]:
        space.remove(body, *body.shapes)


def draw(canvas):
    canvas.space(space)
    canvas.text("one-way platforms", at=(60, 8))
    canvas.text(f"balls in the sensor zone: {len(in_zone)}", at=(340, 8))
    canvas.text(f"joints broken: {broken} of 13", at=(640, 8))


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: collision handlers",
                size=(900, 500), frames=600)
    print(f"{len(in_zone)} balls in the zone, {broken} joints broken")
