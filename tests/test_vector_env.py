"""examples/vector_env.py: the vectorised pushing environment on step_spaces.

Its steps must be those of the scenes stepped one by one (any thread count,
through resets), its arrays shaped as Gymnasium's VectorEnv API says, and,
with Gymnasium installed, equal bit for bit to Gymnasium's SyncVectorEnv of
the single-scene PushEnv.
"""
import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest

import tamias2d

EXAMPLE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples",
                       "vector_env.py")


def load():
    spec = importlib.util.spec_from_file_location("vector_env", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules["vector_env"] = module      # PushEnv pickles by module name
    spec.loader.exec_module(module)
    return module


V = load()


class OneByOne(V.PushVectorEnv):
    """The same environment, its scenes stepped by a loop over space.step."""

    def _physics(self, spaces):
        for space in spaces:
            for _ in range(self.frame_skip):
                space.step(V.DT)


def run(env, steps, seed=7, policy=True):
    rng = np.random.default_rng(seed)
    obs, info = env.reset(seed=seed)
    out = [obs]
    for _ in range(steps):
        a = V.push_policy(obs, rng) if policy else rng.uniform(-1, 1, (env.num_envs, 2))
        obs, reward, terminated, truncated, info = env.step(a)
        out.append((obs, reward, terminated, truncated))
    return out


def same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a[1:], b[1:]):
        for u, v in zip(x, y):
            assert np.array_equal(u, v)
    assert np.array_equal(a[0], b[0])


def test_arrays_follow_the_vector_env_api():
    env = V.PushVectorEnv(5, threads=2)
    obs, info = env.reset(seed=1)
    assert obs.shape == (5, V.OBS_SIZE) and obs.dtype == np.float32 and info == {}
    obs, reward, terminated, truncated, info = env.step(np.zeros((5, 2)))
    assert obs.shape == (5, V.OBS_SIZE) and reward.shape == (5,)
    assert terminated.dtype == truncated.dtype == bool and terminated.shape == (5,)
    assert np.isfinite(obs).all()
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="finite"):
        env.step(np.full((5, 2), np.nan))
    with pytest.raises(ValueError, match="num_envs"):
        V.PushVectorEnv(0)


def test_threads_and_a_loop_over_spaces_give_the_same_episodes():
    # The scripted policy ends episodes quickly, so resets come often.
    n, steps = 12, 150
    one = run(V.PushVectorEnv(n, threads=1), steps)
    two = run(V.PushVectorEnv(n, threads=2), steps)
    loop = run(OneByOne(n), steps)
    same(one, two)
    same(one, loop)
    ended = sum(int(x[2].sum()) for x in one[1:])
    assert ended >= n        # episodes reached the goal and were reset


def test_truncation_and_next_step_autoreset():
    env = V.PushVectorEnv(3, threads=2, max_episode_steps=4)
    env.reset(seed=0)
    stay = np.zeros((3, 2))
    for _ in range(3):
        assert not env.step(stay)[3].any()
    obs, reward, terminated, truncated, _ = env.step(stay)
    assert truncated.all() and not terminated.any()
    # The next step resets instead of stepping: fresh layouts, reward 0.
    obs2, reward, terminated, truncated, _ = env.step(np.ones((3, 2)))
    assert (reward == 0).all() and not truncated.any() and not terminated.any()
    assert not np.array_equal(obs2[:, 4:6], obs[:, 4:6])
    assert (obs2[:, 2:4] == 0).all()        # the pusher at rest: its action was not applied


def test_headless_run_writes_a_picture(tmp_path):
    pytest.importorskip("PIL")
    png = tmp_path / "push.png"
    env = dict(os.environ)
    src = os.path.dirname(os.path.dirname(os.path.abspath(tamias2d.__file__)))
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    done = subprocess.run([sys.executable, EXAMPLE, "--headless", "--frames", "20", "--envs", "8",
                           "--png", str(png)], capture_output=True, text=True, env=env,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert "env steps/s" in done.stdout
    from PIL import Image
    with Image.open(png) as image:
        assert image.size == (800, 200)


def test_equal_to_gymnasiums_sync_vector_env():
    gymnasium = pytest.importorskip("gymnasium")
    n = 6
    vec = V.PushVectorEnv(n, threads=2)
    sync = gymnasium.vector.SyncVectorEnv([V.PushEnv for _ in range(n)])
    assert vec.observation_space == sync.observation_space
    assert vec.action_space == sync.action_space
    assert sync.metadata["autoreset_mode"] == vec.metadata["autoreset_mode"]
    o1, _ = vec.reset(seed=3)
    o2, _ = sync.reset(seed=3)
    assert np.array_equal(o1, o2)
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(250):
        a = V.push_policy(o1, rng).astype(np.float32)
        r1, r2 = vec.step(a), sync.step(a)
        for x, y in zip(r1[:4], r2[:4]):
            assert np.array_equal(x, y)
        assert vec.observation_space.contains(r1[0])
        o1 = r1[0]
        ended += int(r1[2].sum() + r1[3].sum())
    assert ended > n
    sync.close()


def test_single_env_passes_gymnasiums_checker():
    gymnasium = pytest.importorskip("gymnasium")
    from gymnasium.utils.env_checker import check_env
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # advice on spaces and specs, not errors
        check_env(V.PushEnv())
    assert isinstance(V.PushVectorEnv(2), gymnasium.vector.VectorEnv)
