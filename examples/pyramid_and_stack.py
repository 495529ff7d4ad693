"""A pyramid and a tall stack of boxes, in both solvers side by side.

Left: Chipmunk's sequential-impulse solver (the default, pymunk's numbers),
10 iterations. Right: the soft solver (Box2D v3's soft step), 4 substeps.
The scenes are the same; only ``space.solver`` differs.

Resting bodies fall asleep after half a second (``sleep_time_threshold``),
and a sleeping pile stays put. The soft solver's stack comes to rest fast
enough to fall asleep; Chipmunk's starts to sway first, never rests, and
falls. With sleeping off (``sleep_time_threshold = float("inf")``) both
stacks of 16 fall, the soft one about a second later: try it.

    python examples/pyramid_and_stack.py
    python examples/pyramid_and_stack.py --headless --frames 600
"""
import _common
import tamias2d

HALF = 450  # each space gets half of a 900 px wide window
BOX = 24


def build(solver):
    space = tamias2d.Space(solver=solver)
    space.gravity = (0, -900)
    # Let resting boxes sleep: a settled pile then costs nothing to step
    # and can't start to sway.
    space.sleep_time_threshold = 0.5
    ground = tamias2d.Segment(space.static_body, (10, 40), (HALF - 10, 40), 4)
    ground.friction = 0.8
    ground.color = _common.GROUND
    space.add(ground)

    def box(x, y, color):
        body = tamias2d.Body(1, tamias2d.moment_for_box(1, (BOX, BOX)))
        body.position = x, y
        shape = tamias2d.Poly.create_box(body, (BOX, BOX), radius=0.5)
        shape.friction = 0.8
        shape.color = color
        space.add(body, shape)

    # A pyramid of 12 rows on the left of the half...
    rows = 12
    for row in range(rows):
        for i in range(rows - row):
            x = 170 - (rows - row - 1) * (BOX + 1) / 2 + i * (BOX + 1)
            box(x, 44 + BOX / 2 + row * BOX, _common.PALETTE[row % 7])
    # ... and a stack of 16 boxes on its right, each dropped from 1 px up.
    for i in range(16):
        box(380, 44 + BOX / 2 + i * (BOX + 1), _common.PALETTE[5])
    return space


spaces = {"chipmunk": build("chipmunk"), "soft": build("soft")}
# The default settings, written out: 10 solver iterations for Chipmunk,
# 4 substeps per step for the soft solver.
spaces["chipmunk"].iterations = 10
spaces["soft"].substeps = 4


def update(frame):
    for space in spaces.values():
        space.step(_common.DT)


def describe(space):
    top = max(b.position.y for b in space.bodies)
    fallen = sum(1 for b in space.bodies if abs(b.angle) > 0.3)
    return f"top at y={top:.0f}, {fallen} boxes tipped over"


def draw(canvas):
    for i, (name, space) in enumerate(spaces.items()):
        canvas.space(space, offset=(i * HALF, 0))
        settings = (f"{space.iterations} iterations" if name == "chipmunk"
                    else f"{space.substeps} substeps")
        canvas.text([f'solver = "{name}" ({settings})', describe(space)],
                    at=(i * HALF + 10, 8))
    canvas.line((HALF, 0), (HALF, 500), (200, 200, 200))


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: pyramid and stack, two solvers",
                size=(2 * HALF, 500), frames=600)
    for name, space in spaces.items():
        print(f"{name}: {describe(space)}")
