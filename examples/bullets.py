"""Fast small balls fired at a thin wall: tunnelling, and how to avoid it.

Each ball moves 60 px per frame; the wall is 4 px thick. Chipmunk's solver
(top) only sees overlaps that exist at the end of a step, so a ball that
jumps from one side of the wall to the other in one step never touches it.
The soft solver (bottom) makes speculative contacts: a pair that could close
its gap during the step gets a contact before it touches, so the ball stops
at the wall. (tamias2d has no per-body ``is_bullet`` flag; the soft
solver's speculative contacts apply to every body.)

Not every ball is stopped in the soft lane: contacts are made once per
step, from the velocities at its start, so a ball resting by the wall that
is hit from behind during a step gains speed no contact knew about, and can
still be knocked through (one is, in the default run). Thicker walls, or
smaller steps, cover that case.

    python examples/bullets.py
    python examples/bullets.py --headless --frames 240
"""
import random

import _common
import tamias2d

WIDTH, LANE = 900, 250
WALL_X = 620
SPEED = 3600.0  # px/s: 60 px per 1/60 s step


def build(solver):
    space = tamias2d.Space(solver=solver)
    space.gravity = (0, -600)
    static = space.static_body
    walls = [
        tamias2d.Segment(static, (WALL_X, 20), (WALL_X, 230), 2),  # the thin wall
        tamias2d.Segment(static, (0, 20), (WIDTH, 20), 4),           # the floor
        # A backstop thicker than a frame's travel, which even Chipmunk's
        # solver catches: the balls that got through pile up against it.
        tamias2d.Poly(static, [(860, 20), (960, 20), (960, 240), (860, 240)]),
    ]
    for shape in walls:
        shape.friction = 0.5
        shape.color = _common.GROUND
    space.add(*walls)
    return space


lanes = {"chipmunk": build("chipmunk"), "soft": build("soft")}
crossed = {name: set() for name in lanes}  # balls seen beyond the wall
fired = 0
previous = {}  # body -> where it was a frame ago, to draw its motion
rng = random.Random(4)


def fire():
    """One ball into each lane, with the same random aim in both."""
    global fired
    # Aimed so that every ball meets the wall (none flies over it).
    y = rng.uniform(70, 190)
    angle_up = rng.uniform(-0.04, 0.04)
    for space in lanes.values():
        body = tamias2d.Body(1, tamias2d.moment_for_circle(1, 0, 3))
        body.position = 40, y
        body.velocity = SPEED, SPEED * angle_up
        shape = tamias2d.Circle(body, 3)
        shape.elasticity = 0.2
        shape.color = _common.PALETTE[1]
        space.add(body, shape)
    fired += 1


def update(frame):
    if frame % 8 == 0 and fired < 40:
        fire()
    for name, space in lanes.items():
        for body in space.bodies:
            previous[body] = body.position
        space.step(_common.DT)
        crossed[name].update(b for b in space.bodies if b.position.x > WALL_X)


def draw(canvas):
    # The chipmunk lane on top, the soft lane below.
    for (name, space), dy in zip(lanes.items(), (LANE, 0)):
        for body in space.bodies:
            if body in previous:  # a streak from the last frame's position
                a, b = previous[body], body.position
                canvas.line((a.x, a.y + dy), (b.x, b.y + dy), (240, 170, 160), 2)
        canvas.space(space, offset=(0, dy))
        canvas.text(f'solver = "{name}": {fired} fired, {len(crossed[name])} '
                    f'went through the wall', at=(10, (LANE - dy) + 8))
    canvas.line((0, LANE), (WIDTH, LANE), (200, 200, 200))


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: bullets and a thin wall",
                size=(WIDTH, 2 * LANE), frames=240)
    for name, space in lanes.items():
        print(f"{name}: {fired} fired, {len(crossed[name])} went through the wall")
