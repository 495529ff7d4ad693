"""A playground: drag bodies with the mouse, click to add, right-click to delete.

Left-click on a body and drag it: a PivotJoint ties the point you grabbed to
a kinematic body that follows the mouse, with a capped force, so the body
is pulled along but still collides and can't be forced through walls.
Left-click on empty space adds a box (with Shift: a ball); right-click
deletes the body under the cursor.

Headless, a scripted mouse does the same: it adds a few bodies, deletes one,
then grabs a box and swings it around.

    python examples/playground.py
    python examples/playground.py --headless --frames 200
"""
import math
import random

import _common
import tamias2d

WIDTH, HEIGHT = 800, 500
space = tamias2d.Space()
space.gravity = (0, -900)
for a, b in [((10, 20), (790, 20)), ((10, 20), (10, 490)), ((790, 20), (790, 490))]:
    wall = tamias2d.Segment(space.static_body, a, b, 5)
    wall.friction = 0.8
    wall.color = _common.GROUND
    space.add(wall)

# The mouse: a kinematic body moved by hand; the drag joint hangs off it.
mouse_body = tamias2d.Body(body_type=tamias2d.Body.KINEMATIC)
mouse = tamias2d.Vec2d(WIDTH / 2, HEIGHT / 2)
drag = None
rng = random.Random(3)


def add_body(p, ball=False):
    body = tamias2d.Body()  # mass and moment come from the shape's density
    body.position = p
    if ball:
        shape = tamias2d.Circle(body, rng.uniform(12, 24))
    else:
        shape = tamias2d.Poly.create_box(body, (rng.uniform(30, 60), rng.uniform(20, 40)), 1)
    shape.density = 0.01
    shape.friction = 0.7
    shape.color = _common.PALETTE[rng.randrange(len(_common.PALETTE))]
    space.add(body, shape)
    return body


def body_at(p):
    hit = space.point_query_nearest(p, 0, tamias2d.ShapeFilter())
    if hit is not None and hit.shape.body.body_type == tamias2d.Body.DYNAMIC:
        return hit.shape.body
    return None


def press(p, button, shift=False):
    global drag
    body = body_at(p)
    if button == 1 and body is not None:
        drag = tamias2d.PivotJoint(mouse_body, body, (0, 0), body.world_to_local(p))
        drag.max_force = 200000   # a capped pull: walls and heavy piles still win
        drag.error_bias = (1 - 0.15) ** 60  # close 15% of the gap per frame
        space.add(drag)
    elif button == 1:
        add_body(p, ball=shift)
    elif button == 3 and body is not None:
        if drag is not None and drag.b is body:
            release()  # the drag is the only joint a body here can have
        space.remove(body, *body.shapes)


def release():
    global drag
    if drag is not None:
        space.remove(drag)
        drag = None


def on_event(event):
    import pygame

    global mouse
    if hasattr(event, "pos"):
        mouse = tamias2d.Vec2d(*_common.world_pos(event.pos, HEIGHT))
    if event.type == pygame.MOUSEBUTTONDOWN:
        press(mouse, event.button, shift=bool(pygame.key.get_mods() & pygame.KMOD_SHIFT))
    elif event.type == pygame.MOUSEBUTTONUP and event.button == 1:
        release()


# A few bodies to start with.
for i in range(18):
    add_body((120 + 60 * (i % 6) + 20 * (i // 6), 60 + 60 * (i // 6)), ball=i % 4 == 3)
victim, toy = list(space.bodies)[4], list(space.bodies)[9]


def script(frame):
    """The headless stand-in for a user's mouse."""
    global mouse
    if frame < 40 and frame % 8 == 0:
        press((500 + 12 * frame, 300 + 4 * frame), 1, shift=frame % 16 == 0)
    elif frame == 60:
        press(victim.position, 3)   # right-click: delete
    elif frame == 80:
        mouse = toy.position
        press(mouse, 1)             # grab ...
    elif frame > 80:                # ... and swing it round a circle
        t = (frame - 80) / 40
        mouse = tamias2d.Vec2d(400 + 150 * math.cos(t), 250 + 120 * math.sin(t))


def update(frame):
    if args.headless:
        script(frame)
    mouse_body.position = mouse
    space.step(_common.DT)


def draw(canvas):
    canvas.space(space)
    if drag is not None:  # the rubber band from the mouse to the grabbed point
        canvas.line(mouse, drag.b.local_to_world(drag.anchor_b), (231, 76, 60), 2)
    if args.headless:  # no pointer on a picture: mark the scripted mouse
        canvas.line(mouse - (8, 0), mouse + (8, 0), (44, 62, 80), 2)
        canvas.line(mouse - (0, 8), mouse + (0, 8), (44, 62, 80), 2)
    canvas.text(["drag: left button on a body    add: left click (Shift: ball)",
                 f"delete: right click    bodies: {len(space.bodies)}"], at=(24, 10))


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: playground", size=(WIDTH, HEIGHT),
                frames=200, on_event=on_event)
