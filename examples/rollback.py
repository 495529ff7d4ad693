"""Snapshot and rollback, as a networked game does it.

A rollback netcode keeps a snapshot of the world from a moment ago; when a
late input arrives it restores that snapshot and re-simulates up to now.
That only works if the replay is exactly the original run, bit for bit, or
the players' worlds drift apart.

Here a "player" ball is pushed around a pile of boxes by a fixed sequence
of inputs. Every 60 frames the world is pickled (the bytes a game would
keep, or send to a peer). Every 60 frames after that, the snapshot is
restored, the 60 frames are replayed with the same inputs, and each frame's
state is checked against the original run's, bit for bit; the game then
carries on from the restored copy. (tamias2d's snapshots keep the contact
state, the broad phase and sleeping, which is what makes this exact. Run on
pymunk 7.3, whose copies start the contacts afresh, 180 of the 240 replayed
frames of the default run differ from the original.)

    python examples/rollback.py
    python examples/rollback.py --headless --frames 300
"""
import hashlib
import pickle
import random

import _common
import tamias2d
import tamias2d.batch

space = tamias2d.Space()
space.gravity = (0, -900)
for a, b in [((20, 30), (780, 30)), ((20, 30), (20, 480)), ((780, 30), (780, 480))]:
    wall = tamias2d.Segment(space.static_body, a, b, 5)
    wall.friction, wall.color = 0.8, _common.GROUND
    space.add(wall)
for row in range(8):
    for i in range(8 - row):
        box = tamias2d.Body(1, tamias2d.moment_for_box(1, (30, 30)))
        box.position = 300 + i * 31 + row * 15.5, 51 + row * 30
        shape = tamias2d.Poly.create_box(box, (30, 30))
        shape.friction, shape.color = 0.7, _common.PALETTE[row % 7]
        space.add(box, shape)
player = tamias2d.Body(5, tamias2d.moment_for_circle(5, 0, 20))
player.position = 100, 60
shape = tamias2d.Circle(player, 20)
shape.friction, shape.color = 0.9, _common.PALETTE[1]
space.add(player, shape)


def player_input(frame):
    """The input of a frame: where the player steers to. The same whenever
    the frame is simulated; a new target every third of a second."""
    r = random.Random(frame // 20)
    return tamias2d.Vec2d(r.uniform(60, 740), r.uniform(40, 300))


def simulate(world, ball, frame):
    # Steer like a spring towards the target, damped, against gravity.
    pull = (player_input(frame) - ball.position) * 30 - ball.velocity * 6 + (0, 900)
    if pull.length > 4000:
        pull = pull.scale_to_length(4000)
    ball.apply_impulse_at_local_point(pull * ball.mass * _common.DT)
    world.step(_common.DT)


def digest(world):
    """A fingerprint of every body's position, angle and velocities."""
    state = tamias2d.batch.get_bodies(world, ["position", "angle", "velocity",
                                               "angular_velocity"])
    return hashlib.sha256(state.tobytes()).hexdigest()


snapshot = None           # (frame, pickled bytes of (space, player))
history = {}              # frame -> digest after that frame, in the original run
rollbacks, mismatches = 0, 0


def update(frame):
    global space, player, snapshot, rollbacks, mismatches
    if frame % 60 == 0:
        if snapshot is not None:
            # Roll back: restore the old world and replay the frames since.
            start, data = snapshot
            world, ball = pickle.loads(data)
            for f in range(start, frame):
                simulate(world, ball, f)
                mismatches += digest(world) != history[f]
            rollbacks += 1
            space, player = world, ball  # carry on in the restored world
        # Pickle the world and the player together, so that the copy's player
        # is the copy's body.
        snapshot = (frame, pickle.dumps((space, player)))
    simulate(space, player, frame)
    history[frame] = digest(space)


def draw(canvas):
    canvas.space(space)
    size = len(snapshot[1]) / 1024 if snapshot else 0
    canvas.text([f"snapshot: {size:.1f} KiB of pickle; {rollbacks} rollbacks of 60 frames",
                 f"frames that differed from the original run: {mismatches}"], at=(30, 8))


if __name__ == "__main__":
    args = _common.parse_args(__doc__)
    _common.run(args, update, draw, title="tamias2d: snapshot and rollback", size=(800, 500),
                frames=300)
    print(f"{rollbacks} rollbacks, {rollbacks * 60} frames replayed, "
          f"{mismatches} differed from the original run")
    raise SystemExit(1 if mismatches else 0)
