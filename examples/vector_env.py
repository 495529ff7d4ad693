"""A vectorised pushing environment: N top-down scenes, one call steps them all.

Each scene is a walled arena with a round pusher and a square block; the
pusher must push the block onto a goal. The pusher is a dynamic body whose
velocity is the action (it stops at the walls and is pushed back by the
block); the block slides with top-down friction (two joints to the static
body with a force limit and no bias).

``PushVectorEnv`` follows Gymnasium's ``VectorEnv`` API (``reset`` ->
``(obs, info)``, ``step(actions)`` -> ``(obs, rewards, terminations,
truncations, infos)``, NumPy arrays with the environments on the first axis,
``next_step`` autoreset) and is a ``gymnasium.vector.VectorEnv`` when
Gymnasium is installed; without it, it works the same, minus the ``spaces``
objects. Its step is three calls, whatever N:

    tamias2d.batch.set_spaces_bodies(...)   # write the actions
    tamias2d.step_spaces(...)               # step every scene, on every core
    tamias2d.batch.get_spaces_bodies(...)   # read the observations

with no Python per scene (only scenes being reset are touched one by one).
``PushEnv`` is one scene as a ``gymnasium.Env``, for Gymnasium's own vector
wrappers: ``SyncVectorEnv([PushEnv] * N)`` gives bit for bit what
``PushVectorEnv(N)`` gives with the same seed.

    python examples/vector_env.py --headless --frames 300
    python examples/vector_env.py --headless --frames 300 --envs 256 --png push.png
    python examples/vector_env.py           # a window (pygame) with four scenes

Without ``--headless`` a pygame window shows the first four scenes; with it,
the throughput is printed and ``--png`` writes a picture of them.
"""
import argparse
import math
import pickle
import sys
import time

import numpy as np

import tamias2d
import tamias2d.batch

try:
    import gymnasium
    from gymnasium import spaces as _gym_spaces
    from gymnasium.vector import VectorEnv as _VectorBase
    from gymnasium.vector.utils import batch_space as _batch_space
    _EnvBase = gymnasium.Env
except ImportError:  # the environment works without Gymnasium
    gymnasium = None
    _VectorBase = object
    _EnvBase = object

# The scene, in metres, kilograms and seconds.
ARENA = 4.0              # square arena side
WALL = 0.05              # wall radius
PUSHER_RADIUS = 0.15
BLOCK_SIZE = 0.5
BLOCK_FRICTION_FORCE = 5.0    # the floor's friction on the block (N)
BLOCK_FRICTION_TORQUE = 1.0   # and its torque (N m)
MAX_SPEED = 1.5          # pusher speed for an action of length 1 (m/s)
DT = 1 / 100             # physics step
FRAME_SKIP = 5           # physics steps per environment step (20 Hz control)
GOAL_TOLERANCE = 0.1     # block centre within this of the goal: success
MAX_EPISODE_STEPS = 200

OBS_SIZE = 13            # see PushVectorEnv._observe
FIELDS = ("position", "angle", "velocity", "angular_velocity")   # 6 columns a body
PUSHER, BLOCK = 0, 1     # the bodies of a scene, in space.bodies order


def make_scene():
    """The scene at rest, pusher and block at the centre (reset moves them)."""
    space = tamias2d.Space()
    space.gravity = 0, 0
    lo, hi = 0.0, ARENA
    for a, b in (((lo, lo), (hi, lo)), ((hi, lo), (hi, hi)),
                 ((hi, hi), (lo, hi)), ((lo, hi), (lo, lo))):
        wall = tamias2d.Segment(space.static_body, a, b, WALL)
        wall.friction = 0.5
        space.add(wall)
    pusher = tamias2d.Body(1.0, tamias2d.moment_for_circle(1.0, 0, PUSHER_RADIUS))
    ball = tamias2d.Circle(pusher, PUSHER_RADIUS)
    ball.friction = 0.7
    block = tamias2d.Body(1.0, tamias2d.moment_for_box(1.0, (BLOCK_SIZE, BLOCK_SIZE)))
    box = tamias2d.Poly.create_box(block, (BLOCK_SIZE, BLOCK_SIZE), 0.01)
    box.friction = 0.7
    space.add(pusher, ball, block, box)       # space.bodies: pusher, block
    # Top-down friction: joints to the static body that only resist motion
    # (no bias), up to the friction force and torque.
    slide = tamias2d.PivotJoint(space.static_body, block, (0, 0), (0, 0))
    spin = tamias2d.GearJoint(space.static_body, block, 0.0, 1.0)
    slide.max_bias = spin.max_bias = 0
    slide.max_force = BLOCK_FRICTION_FORCE
    spin.max_force = BLOCK_FRICTION_TORQUE
    space.add(slide, spin)
    return space


def _random_layout(rng):
    """Pusher position, block position and angle, goal: one row of 7."""
    m = 0.5
    while True:
        pusher = rng.uniform(m, ARENA - m, 2)
        block = rng.uniform(2 * m, ARENA - 2 * m, 2)
        goal = rng.uniform(2 * m, ARENA - 2 * m, 2)
        if (np.sqrt(((pusher - block) ** 2).sum()) > BLOCK_SIZE + PUSHER_RADIUS
                and np.sqrt(((goal - block) ** 2).sum()) > 4 * GOAL_TOLERANCE):
            return np.concatenate([pusher, block, [rng.uniform(-math.pi, math.pi)], goal])


class PushVectorEnv(_VectorBase):
    """`num_envs` pushing scenes stepped together by ``tamias2d.step_spaces``.

    :param num_envs: how many scenes.
    :param threads: native threads for the step (default: every core).
    :param frame_skip: physics steps per ``step`` call.
    :param max_episode_steps: an episode is truncated after this many steps.
    :param render_mode: ``"rgb_array"`` makes :meth:`render` return a picture
        of the first scenes (needs Pillow).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": round(1 / (DT * FRAME_SKIP)),
                "autoreset_mode": "next_step"}

    def __init__(self, num_envs=64, *, threads=None, frame_skip=FRAME_SKIP,
                 max_episode_steps=MAX_EPISODE_STEPS, render_mode=None):
        if not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be an int >= 1, not {num_envs!r}")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', not {render_mode!r}")
        self.num_envs = num_envs
        self.threads = threads
        self.frame_skip = frame_skip
        self.max_episode_steps = max_episode_steps
        self.render_mode = render_mode
        if gymnasium is not None:
            # Gymnasium's own enum when it has one (1.1 and later).
            mode = getattr(gymnasium.vector, "AutoresetMode", None)
            if mode is not None:
                self.metadata = dict(self.metadata, autoreset_mode=mode.NEXT_STEP)
            low = np.full(OBS_SIZE, -np.inf, dtype=np.float32)
            high = -low
            for k in (0, 1, 4, 5, 11, 12):      # positions, within the arena
                low[k], high[k] = 0.0, ARENA
            low[6:8], high[6:8] = -1.0, 1.0       # the block's cos and sin
            self.single_observation_space = _gym_spaces.Box(low, high, dtype=np.float32)
            self.single_action_space = _gym_spaces.Box(-1.0, 1.0, (2,), np.float32)
            self.observation_space = _batch_space(self.single_observation_space, num_envs)
            self.action_space = _batch_space(self.single_action_space, num_envs)
        # Resets unpickle the scene at rest: a fresh copy, faster than copy().
        self._template = pickle.dumps(make_scene(), protocol=pickle.HIGHEST_PROTOCOL)
        self.spaces = [pickle.loads(self._template) for _ in range(num_envs)]
        n = num_envs
        self._rows = np.zeros((2 * n, 6))            # get_spaces_bodies fills it
        self._velocity = np.zeros((2 * n, 2))        # set_spaces_bodies reads it
        self._goal = np.zeros((n, 2))
        self._distance = np.zeros(n)
        self._elapsed = np.zeros(n, dtype=np.int64)
        self._needs_reset = np.zeros(n, dtype=bool)
        self._rngs = [np.random.default_rng() for _ in range(n)]

    # -- Gymnasium's API ------------------------------------------------------------------

    def reset(self, *, seed=None, options=None):
        """Reset every scene; `seed` (an int, or a list of one per scene)
        seeds scene i with ``seed + i`` as Gymnasium's vector envs do."""
        if seed is not None:
            seeds = [seed + i for i in range(self.num_envs)] if isinstance(seed, int) else list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} environments")
            self._rngs = [np.random.default_rng(s) for s in seeds]
        self._reset_envs(np.arange(self.num_envs))
        self._read()
        self._distance[:] = self._block_distance()
        return self._observe(), {}

    def step(self, actions):
        """Push with `actions` (shape (num_envs, 2), each in [-1, 1]: the
        pusher's velocity over MAX_SPEED). A scene that ended in the last
        step is reset instead (its action is ignored): Gymnasium's
        ``next_step`` autoreset."""
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != (self.num_envs, 2):
            raise ValueError(f"actions must have shape {(self.num_envs, 2)}, not {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError("actions must be finite")
        a = np.clip(a, -1.0, 1.0)
        resetting = self._needs_reset.copy()
        # Write: the pusher's velocity from the action, the block's as it is.
        self._velocity[PUSHER::2] = a * MAX_SPEED
        self._velocity[BLOCK::2] = self._rows[BLOCK::2, 3:5]
        if resetting.any():
            # Only the scenes being reset are handled one by one.
            keep = np.flatnonzero(~resetting)
            active = [self.spaces[i] for i in keep]
            rows = np.stack([2 * keep, 2 * keep + 1], axis=1).ravel()
            tamias2d.batch.set_spaces_bodies(active, self._velocity[rows], "velocity")
            self._physics(active)
            self._reset_envs(np.flatnonzero(resetting))
        else:
            tamias2d.batch.set_spaces_bodies(self.spaces, self._velocity, "velocity")
            self._physics(self.spaces)
        self._read()
        distance = self._block_distance()
        terminated = distance < GOAL_TOLERANCE
        reward = (self._distance - distance) + terminated
        self._elapsed += 1
        truncated = (self._elapsed >= self.max_episode_steps) & ~terminated
        # A scene reset in this step starts afresh: reward 0, not done.
        reward[resetting] = 0.0
        terminated[resetting] = False
        truncated[resetting] = False
        self._elapsed[resetting] = 0
        self._distance[:] = distance
        self._needs_reset[:] = terminated | truncated
        return self._observe(), reward, terminated, truncated, {}

    def render(self):
        """A picture (an RGB array) of the first four scenes, side by side."""
        if self.render_mode != "rgb_array":
            return None
        return np.asarray(self.picture(4))

    def close(self, **kwargs):
        self.spaces = []

    # -- the scenes -----------------------------------------------------------------------

    def _reset_envs(self, which):
        # A fresh copy of the scene at rest (no contacts or joint impulses
        # from the last episode), then the random layout, in one batch write.
        if len(which) == 0:
            return
        layouts = np.array([_random_layout(self._rngs[i]) for i in which])
        chosen = []
        for i in which:
            self.spaces[i] = pickle.loads(self._template)
            chosen.append(self.spaces[i])
        pose = np.zeros((2 * len(which), 3))
        pose[0::2, 0:2] = layouts[:, 0:2]
        pose[1::2, 0:2] = layouts[:, 2:4]
        pose[1::2, 2] = layouts[:, 4]
        tamias2d.batch.set_spaces_bodies(chosen, pose, ("position", "angle"))
        self._goal[which] = layouts[:, 5:7]
        self._elapsed[which] = 0
        self._needs_reset[which] = False
        # Their rows, for the block velocities written at the next step.
        rows = np.stack([2 * which, 2 * which + 1], axis=1).ravel()
        self._rows[rows] = tamias2d.batch.get_spaces_bodies(chosen, FIELDS)[0]
        d = self._rows[2 * which + 1, 0:2] - self._goal[which]
        self._distance[which] = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])

    def _physics(self, spaces):
        tamias2d.step_spaces(spaces, DT, threads=self.threads, steps=self.frame_skip)

    def _read(self):
        tamias2d.batch.get_spaces_bodies(self.spaces, FIELDS, out=self._rows)

    def _block_distance(self):
        d = self._rows[BLOCK::2, 0:2] - self._goal
        return np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])

    def _observe(self):
        # pusher x, y, vx, vy; block x, y, cos, sin, vx, vy, w; goal x, y
        p = self._rows[PUSHER::2]
        b = self._rows[BLOCK::2]
        obs = np.empty((self.num_envs, OBS_SIZE), dtype=np.float32)
        obs[:, 0:2] = p[:, 0:2]
        obs[:, 2:4] = p[:, 3:5]
        obs[:, 4:6] = b[:, 0:2]
        obs[:, 6] = np.cos(b[:, 2])
        obs[:, 7] = np.sin(b[:, 2])
        obs[:, 8:11] = b[:, 3:6]
        obs[:, 11:13] = self._goal
        return obs

    def picture(self, count=4, size=200):
        """A Pillow image of the first `count` scenes in a row, goals in green."""
        from PIL import Image, ImageDraw
        from tamias2d.pillow_util import DrawOptions
        count = min(count, self.num_envs)
        strip = Image.new("RGB", (size * count, size), "white")
        for k in range(count):
            options = DrawOptions((size, size), bb=(0, 0, ARENA, ARENA), margin=4)
            options.flags = DrawOptions.DRAW_SHAPES    # not the friction joints
            gx, gy = options.to_image(tuple(self._goal[k]))
            r = GOAL_TOLERANCE * size / ARENA + 3
            ImageDraw.Draw(options.image).ellipse((gx - r, gy - r, gx + r, gy + r),
                                                  fill=(120, 220, 120))
            self.spaces[k].debug_draw(options)
            strip.paste(options.image, (size * k, 0))
        return strip


class PushEnv(_EnvBase):
    """One pushing scene as a ``gymnasium.Env`` (for Gymnasium's vector
    wrappers): a PushVectorEnv of one scene, stepped on the calling thread."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": PushVectorEnv.metadata["render_fps"]}

    def __init__(self, render_mode=None, **kwargs):
        self._vec = PushVectorEnv(1, threads=1, render_mode=render_mode, **kwargs)
        self.render_mode = render_mode
        if gymnasium is not None:
            self.observation_space = self._vec.single_observation_space
            self.action_space = self._vec.single_action_space

    def reset(self, *, seed=None, options=None):
        if gymnasium is not None:
            super().reset(seed=seed)
        obs, info = self._vec.reset(seed=seed)
        return obs[0], info

    def step(self, action):
        # A single env ends its episode itself; the wrapper around it resets it.
        self._vec._needs_reset[:] = False
        obs, reward, terminated, truncated, info = self._vec.step(np.asarray(action)[None])
        return obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), info

    def render(self):
        return self._vec.render()


def push_policy(obs, rng=None):
    """A scripted policy (vectorised, on observations): get behind the
    block, opposite the goal, going round it if need be, then push."""
    pusher, block, goal = obs[:, 0:2], obs[:, 4:6], obs[:, 11:13]
    ahead = goal - block
    ahead /= np.maximum(np.sqrt((ahead ** 2).sum(axis=1, keepdims=True)), 1e-9)
    side = np.stack([-ahead[:, 1], ahead[:, 0]], axis=1)
    offset = pusher - block
    along = (offset * ahead).sum(axis=1, keepdims=True)
    across = (offset * side).sum(axis=1, keepdims=True)
    clear = BLOCK_SIZE * 0.75 + PUSHER_RADIUS
    behind = block - ahead * clear
    pushing = (along < -0.5 * clear) & (np.abs(across) < 0.12)
    round_it = along > -0.5 * clear
    # Pushing aims through the block; beside or in front of it, the pusher
    # first goes out to the side it is on and back past the block.
    target = np.where(pushing, block + ahead * 0.5, behind)
    flank = block + np.where(across >= 0, 1.0, -1.0) * side * clear * 1.3 - ahead * clear * 0.8
    target = np.where(round_it & ~pushing, flank, target)
    action = (target - pusher) * 4.0
    if rng is not None:
        action += rng.normal(0, 0.05, action.shape)
    length = np.sqrt((action ** 2).sum(axis=1, keepdims=True))
    return action / np.maximum(length, 1.0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--headless", action="store_true", help="no window: print the throughput")
    ap.add_argument("--frames", type=int, default=600, help="environment steps to run")
    ap.add_argument("--envs", type=int, default=64, help="scenes stepped together")
    ap.add_argument("--threads", type=int, default=None, help="threads (default: every core)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", "--png", dest="out", default=None,
                    help="write a picture of the first four scenes here at the end")
    args = ap.parse_args(argv)
    env = PushVectorEnv(args.envs, threads=args.threads)
    rng = np.random.default_rng(args.seed)
    obs, _ = env.reset(seed=args.seed)
    if not args.headless:
        rc = _window(env, obs, rng, args.frames)
        if args.out:
            env.picture(4).save(args.out)
        return rc
    successes = episodes = 0
    t0 = time.perf_counter()
    for _ in range(args.frames):
        obs, reward, terminated, truncated, _ = env.step(push_policy(obs, rng))
        successes += int(terminated.sum())
        episodes += int((terminated | truncated).sum())
    elapsed = time.perf_counter() - t0
    steps = args.frames * args.envs
    print(f"{args.envs} scenes x {args.frames} steps ({env.frame_skip} physics steps each) "
          f"in {elapsed:.2f} s: {steps / elapsed:,.0f} env steps/s, "
          f"{steps * env.frame_skip / elapsed:,.0f} physics steps/s; "
          f"{successes} of {episodes} finished episodes reached the goal")
    if args.out:
        env.picture(4).save(args.out)
        print(f"wrote {args.out}")
    return 0


def _window(env, obs, rng, frames):
    try:
        import pygame
    except ImportError:
        sys.exit("the window needs pygame (pip install pygame), or use --headless")
    pygame.init()
    picture = env.picture(4)
    screen = pygame.display.set_mode(picture.size)
    pygame.display.set_caption(f"tamias2d: {env.num_envs} pushing scenes, four shown")
    clock = pygame.time.Clock()
    for _ in range(frames):
        for event in pygame.event.get():
            if event.type == pygame.QUIT or (event.type == pygame.KEYDOWN
                                             and event.key == pygame.K_ESCAPE):
                pygame.quit()
                return 0
        obs = env.step(push_policy(obs, rng))[0]
        picture = env.picture(4)
        screen.blit(pygame.image.frombuffer(picture.tobytes(), picture.size, "RGB"), (0, 0))
        pygame.display.flip()
        clock.tick(env.metadata["render_fps"])
    pygame.quit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
