"""Determinism: the same scene built the same way gives bitwise the same
state after N steps, in the same process and in a new one.

The state is hashed as hard_cases.state_hash does it: sha256 of the packed
little-endian doubles of every body's position, angle, velocity and angular
velocity, in ``space.bodies`` order. The scene (hard_cases.build_determinism)
mixes every shape pair, friction, restitution and a kinematic paddle. The
hash after 600 steps is pinned below, and the test also asserts that pymunk
7.3 gives that same hash for the same scene: the pinned value is pymunk's
answer, not merely tamias2d's own.

A change that alters these hashes changes the physics: either a fidelity
bug, or (if pymunk agrees) a new reference platform (the values are for
x86-64 with glibc's libm; pymunk built with FMA contraction, as Clang does
on arm64, gives other numbers).
"""
import os
import subprocess
import sys

import pytest

import tamias2d
import hard_cases as hc

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
STEPS = 600

# sha256 of the state after 600 steps of 1/60 s (pymunk 7.3.1 and tamias2d)
PINNED = {
    "default": "d8a6acb4f8f2c16acb4003fa0ed66aa744da2cb442dd45af0307d9936dc36e78",
    "spatial_hash": "18afc6ab741efb9ea055da42caf26a1af63ff1194a3cfcf178df38ab5bfa30c1",
    "sleeping": "509916e2cd2294e1e9570f3f68094a1e078f58cefba38b61fa40f2e9fc9e2a3c",
}
VARIANTS = {"default": {}, "spatial_hash": {"spatial_hash": True}, "sleeping": {"sleeping": True}}


def run(mod, variant, steps=STEPS, every=None):
    """The hash after `steps` steps (and, with `every`, the list of hashes
    every `every` steps)."""
    space = hc.build_determinism(mod, **VARIANTS[variant]).space
    trail = []
    for i in range(steps):
        space.step(1 / 60)
        if every and (i + 1) % every == 0:
            trail.append(hc.state_hash(space))
    return hc.state_hash(space), trail


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_same_process_twice(variant):
    a, ta = run(tamias2d, variant, every=50)
    b, tb = run(tamias2d, variant, every=50)
    for k, (x, y) in enumerate(zip(ta, tb)):
        assert x == y, f"{variant}: the two runs part by step {(k + 1) * 50}"
    assert a == b


_CHILD = """
import sys, random
sys.path[:0] = [{root!r}, {here!r}]
junk = [bytearray(random.randrange(1, 5000)) for _ in range(random.randrange(100, 3000))]
import tamias2d, hard_cases
space = hard_cases.build_determinism(tamias2d, **{kwargs!r}).space
for _ in range({steps}):
    space.step(1 / 60)
print(hard_cases.state_hash(space))
"""


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_new_process(variant):
    # a fresh interpreter, another hash seed, a differently filled heap and
    # (with ASLR) other addresses: the same bits
    code = _CHILD.format(root=ROOT, here=HERE, kwargs=VARIANTS[variant], steps=STEPS)
    outs = []
    for hashseed in ("1", "12345"):
        env = dict(os.environ, PYTHONHASHSEED=hashseed)
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              timeout=300, env=env, cwd=ROOT)
        assert proc.returncode == 0, proc.stderr[-3000:]
        outs.append(proc.stdout.strip())
    here, _ = run(tamias2d, variant)
    assert outs == [here, here]


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_pinned_hash_is_pymunks(variant):
    pymunk = pytest.importorskip("pymunk")
    t, tt = run(tamias2d, variant, every=100)
    p, tp = run(pymunk, variant, every=100)
    for k, (x, y) in enumerate(zip(tt, tp)):
        assert x == y, f"{variant}: tamias2d and pymunk part by step {(k + 1) * 100}"
    assert p == PINNED[variant], f"pymunk itself gives another hash here: {p}"
    assert t == PINNED[variant]


def test_hash_sees_every_field():
    # the hash is not blind to a one-ulp change of any of the six doubles
    import math
    base = run(tamias2d, "default", steps=5)[0]
    for field in ("position", "angle", "velocity", "angular_velocity"):
        space = hc.build_determinism(tamias2d).space
        for _ in range(5):
            space.step(1 / 60)
        b = list(space.bodies)[10]
        v = getattr(b, field)
        if isinstance(v, float):
            setattr(b, field, math.nextafter(v, math.inf))
        else:
            setattr(b, field, (math.nextafter(v.x, math.inf), v.y))
        assert hc.state_hash(space) != base, field
