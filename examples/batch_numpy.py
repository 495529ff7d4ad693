"""Thousands of bodies read and written as NumPy arrays, one call each.

2016 balls float in a grid, each held near its home by a spring that NumPy
computes for all of them at once, while a travelling wave moves the homes.
A kinematic paddle ploughs through and the springs close its wake. Every
frame ``tamias2d.batch.get_bodies`` reads every position and velocity into
one array and ``tamias2d.batch.set_bodies`` writes the new velocities back:
no Python loop over the bodies. At the end the example times that against
the same work done body by body.

(pymunk 7.3's ``pymunk.batch`` API is there too, with the same names:
``Buffer``, ``BodyFields``, ``get_space_bodies``, ``set_space_bodies``; see
the module's help. Its rows come in Chipmunk's order of the bodies.)

    python examples/batch_numpy.py
    python examples/batch_numpy.py --headless --frames 240
"""
import math
import time

import numpy as np

import _common
import tamias2d
from tamias2d import batch

WIDTH, HEIGHT = 800, 500
space = tamias2d.Space()  # no gravity: the springs do everything

# The balls' homes: a 56 x 36 grid, 14 px apart.
xs, ys = np.meshgrid(np.arange(56) * 14.0 + 15, np.arange(36) * 13.0 + 30)
homes = np.stack([xs.ravel(), ys.ravel()], axis=1)
for i, (x, y) in enumerate(homes):
    body = tamias2d.Body(1, tamias2d.moment_for_circle(1, 0, 4))
    body.position = float(x), float(y)
    ball = tamias2d.Circle(body, 4)
    ball.color = _common.PALETTE[(i // 56 // 4 + i % 56 // 8) % 7]  # a patchwork
    space.add(body, ball)

# The paddle is added last, so it is the last row of the arrays.
paddle = tamias2d.Body(body_type=tamias2d.Body.KINEMATIC)
paddle.position = 400, 250
blade = tamias2d.Poly.create_box(paddle, (120, 24), 4)
blade.color = _common.INK + (255,)
space.add(paddle, blade)


def spring_velocities(state, t):
    """New velocities for every row of `state` (x, y, vx, vy): a damped
    spring pulls each ball towards its home, the homes rippled by a wave
    travelling to the right; the last row, the paddle's, is kept."""
    pos, vel = state[:-1, 0:2], state[:-1, 2:4]
    wave = np.stack([np.zeros(len(pos)), 6 * np.sin(homes[:, 0] / 40 - 3 * t)], axis=1)
    stiffness, damping = 40.0, 4.0
    accel = stiffness * (homes + wave - pos) - damping * vel
    return np.vstack([vel + accel * _common.DT, state[-1:, 2:4]])


def update(frame):
    t = frame * _common.DT
    # The paddle sweeps a figure of eight, turning as it goes.
    paddle.velocity = 300 * math.cos(t * 0.8), 180 * math.cos(t * 1.6)
    paddle.angular_velocity = 1.5
    state = batch.get_bodies(space, ["position", "velocity"])  # shape (2017, 4)
    batch.set_bodies(space, spring_velocities(state, t), "velocity")
    space.step(_common.DT)


def draw(canvas):
    canvas.space(space)
    moved = np.hypot(*(batch.get_bodies(space, "position")[:-1] - homes).T)
    canvas.text(f"{len(space.bodies) - 1} balls on NumPy springs; "
                f"farthest from home: {moved.max():.0f} px", at=(10, 4))


def time_it(frames=20):
    """Milliseconds per frame for reading, computing and writing, both ways."""
    t0 = time.perf_counter()
    for _ in range(frames):
        state = batch.get_bodies(space, ["position", "velocity"])
        batch.set_bodies(space, spring_velocities(state, 0), "velocity")
    t1 = time.perf_counter()
    for _ in range(frames):
        bodies = list(space.bodies)
        state = np.array([(*b.position, *b.velocity) for b in bodies])
        for body, v in zip(bodies, spring_velocities(state, 0)):
            body.velocity = tuple(v)
    t2 = time.perf_counter()
    return (t1 - t0) / frames * 1e3, (t2 - t1) / frames * 1e3


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: NumPy batch API", size=(WIDTH, HEIGHT),
                frames=240)
    fast, slow = time_it()
    print(f"read, compute and write {len(space.bodies)} bodies: {fast:.2f} ms a frame "
          f"with tamias2d.batch, {slow:.2f} ms body by body")
