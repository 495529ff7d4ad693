"""The stability suite: hard cases (tests/hard_cases.py) in tamias2d, checked
against their pass criteria and against pymunk 7.3, bit for bit.

For every case, with the default settings:
  * tamias2d's final state is bitwise equal to pymunk's (sha256 of every
    body's position, angle, velocity and angular velocity), and the two
    engines agree on pass or fail;
  * no NaN and no engine exception;
  * a case that passes in docs/stability.md's full run passes here too; in
    the full form (TAMIAS2D_FULL=1) a case documented as failing must still
    fail, so the documentation cannot go stale silently.
For every case that fails with the defaults, the setting recorded in
hard_cases.FIXES (iterations, substeps, collision_slop) must make it pass,
again bitwise equal to pymunk with the same setting.

CI runs the reduced lengths (Case.steps; the whole file in about 20 s);
TAMIAS2D_FULL=1 runs the full ones (Case.full_steps), as
benchmarks/stability_report.py does for the documentation. Every test runs
in a forked child (tests/isolated.py), so a crash fails one test.
"""
import os

import pytest

pymunk = pytest.importorskip("pymunk")
import tamias2d  # noqa: E402

import hard_cases as hc  # noqa: E402
from isolated import isolated  # noqa: E402

FULL = os.environ.get("TAMIAS2D_FULL", "") not in ("", "0")


def _describe(r):
    return (f"{r.engine} {r.case} {r.settings}: passed={r.passed} nan={r.nan} error={r.error!r} "
            f"metrics={r.metrics}")


def _check_pair(case, **settings):
    t = hc.run_case(tamias2d, case, full=FULL, **settings)
    p = hc.run_case(pymunk, case, full=FULL, **settings)
    assert not t.error, _describe(t)
    assert not t.nan, _describe(t)
    if case.exact:
        assert t.hash == p.hash, (
            f"{case.name}: tamias2d and pymunk end in different states after {t.steps} steps\n"
            f"  {_describe(t)}\n  {_describe(p)}")
    assert t.passed == p.passed, f"{_describe(t)}\n{_describe(p)}"
    return t, p


@pytest.mark.parametrize("name", list(hc.CASES))
@isolated(timeout=600)
def test_default_settings(name):
    case = hc.CASES[name]
    t, _ = _check_pair(case)
    if hc.FULL_DEFAULT[name]:
        assert t.passed, f"documented as passing: {_describe(t)}"
    elif FULL:
        assert not t.passed, (f"documented as failing with the defaults, now passes: update "
                              f"docs/stability.md and hard_cases.FULL_DEFAULT. {_describe(t)}")


@pytest.mark.parametrize("name", list(hc.FIXES))
@isolated(timeout=600)
def test_documented_fix(name):
    case = hc.CASES[name]
    t, _ = _check_pair(case, **hc.FIXES[name])
    assert t.passed, f"the documented fix no longer works: {_describe(t)}"


def test_every_failing_case_has_a_fix_or_a_note():
    for name, passes in hc.FULL_DEFAULT.items():
        if not passes:
            assert name in hc.FIXES or hc.CASES[name].note, name
    assert set(hc.FULL_DEFAULT) == set(hc.CASES)


def test_criteria_can_fail():
    # The judges are not vacuous: a case run for a single step with its
    # pass criterion fed impossible numbers must fail.
    case = hc.CASES["stack_10"]
    scene = case.build(pymunk)
    boxes = scene.watch["boxes"]
    boxes[-1].position = 5.0, boxes[-1].position.y
    ok, m = case.judge(scene, [case.probe(scene)])
    assert not ok and m["top drift"] == 5.0


def test_state_hash_is_of_the_packed_doubles():
    import hashlib
    import struct
    s = tamias2d.Space()
    b = tamias2d.Body(1, 1)
    b.position = 1, 2
    b.angle = 0.5
    b.velocity = 3, 4
    b.angular_velocity = 6
    s.add(b)
    expect = hashlib.sha256(struct.pack("<6d", 1, 2, 0.5, 3, 4, 6)).hexdigest()
    assert hc.state_hash(s) == expect


@pytest.mark.parametrize("setting", [{"iterations": 20}, {"substeps": 3}, {"slop": 0.5}])
def test_settings_reach_the_space(setting):
    # run_case really applies what it is given (else a 'fix' would be
    # measured on the defaults): the state differs from the default run.
    case = hc.CASES["mass_ratio_100"]
    a = hc.run_case(tamias2d, case, steps=30)
    b = hc.run_case(tamias2d, case, steps=30, **setting)
    assert a.hash != b.hash
