"""Joint and spring parameters that would make a step non-finite are refused
when they are set (constructor or setter), with IllegalConstraint (a
ValueError and an AssertionError); every other value keeps a small scene
finite.

How the refused classes were found: every parameter of every joint was set,
in the scene below (bodies a and b, a dynamic or static, gravity, dt 1/60),
to 1e308, -1e308, 1e200, 1e154, 1e150, 1e100, 1e50, 1e20, 5e-324, -5e-324,
1e-300, 0, -1, 1, inf, -inf and NaN (points: each coordinate), and the
scene stepped 20 times (what docs/stability.md, "Joint parameters", lists).
The property at the end checks the rule: anything accepted, from the
extremes the search used and ordinary values, leaves the scene finite.
"""
import math
import os

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings, seed, strategies as st  # noqa: E402

import tamias2d  # noqa: E402
from tamias2d import Body, Space  # noqa: E402
from tamias2d.constraints import (DampedRotarySpring, DampedSpring, GearJoint,  # noqa: E402
                                  GrooveJoint, PARAMETER_LIMIT, PinJoint, PivotJoint,
                                  RatchetJoint, RotaryLimitJoint, SimpleMotor, SlideJoint)
from tamias2d.errors import IllegalConstraint, IllegalVector  # noqa: E402

from isolated import isolated  # noqa: E402

FULL = os.environ.get("TAMIAS2D_FULL", "") not in ("", "0")
SEED = int(os.environ.get("TAMIAS2D_SEED", "20240607"))
EXAMPLES = 1000 if FULL else 150
STEPS = 10

nan, inf = math.nan, math.inf

# The constructor arguments after the bodies, by name, of an ordinary joint.
ORDINARY = {
    "PinJoint": {"anchor_a": (0.5, 0), "anchor_b": (0, 0.5)},
    "SlideJoint": {"anchor_a": (0.5, 0), "anchor_b": (0, 0.5), "min": 1, "max": 2},
    "PivotJoint": {"anchor_a": (0.5, 0), "anchor_b": (0, 0.5)},
    "GrooveJoint": {"groove_a": (0, 0), "groove_b": (5, 0), "anchor_b": (0, 0.5)},
    "DampedSpring": {"anchor_a": (0.5, 0), "anchor_b": (0, 0.5), "rest_length": 2,
                     "stiffness": 50, "damping": 1},
    "DampedRotarySpring": {"rest_angle": 0.3, "stiffness": 50, "damping": 1},
    "RotaryLimitJoint": {"min": -0.2, "max": 0.2},
    "RatchetJoint": {"phase": 0.1, "ratchet": 0.3},
    "GearJoint": {"phase": 0.1, "ratio": 2},
    "SimpleMotor": {"rate": 2},
}
# Parameters set only through a property.
EXTRA = {"PinJoint": ["distance"], "RatchetJoint": ["angle"]}
COMMON = ["max_force", "error_bias", "max_bias"]
POINTS = {"anchor_a", "anchor_b", "groove_a", "groove_b"}


def scene(kind, static_a=False, **args):
    s = Space()
    s.gravity = (0, -100)
    a = s.static_body if static_a else Body(1, 1)
    b = Body(2, 3)
    b.position = (3, 1)
    b.velocity = (1, 2)
    b.angular_velocity = 0.5
    s.add(b) if static_a else s.add(a, b)
    kw = dict(ORDINARY[kind], **args)
    j = getattr(tamias2d, kind)(a, b, *kw.values())
    s.add(j)
    return s, a, b, j


def body_finite(body):
    return all(math.isfinite(x) for x in (*body.position, *body.velocity, body.angle,
                                          body.angular_velocity))


def steps_finitely(s, a, b):
    for _ in range(STEPS):
        try:
            s.step(1 / 60)
        except IllegalConstraint as e:
            # A ratio, ratchet or groove length of 0 is allowed when set and
            # refused in a step (pymunk's own tests build such joints).
            assert "must not be 0 in a step" in str(e), e
            return
        assert body_finite(a) and body_finite(b)


# -- the refused classes, one by one --------------------------------------------------------

REFUSED = [
    # (kind, parameter, value)
    ("SlideJoint", "min", inf),                           # with max = inf: min = max = inf
    ("SlideJoint", "min", 1e308),
    ("SlideJoint", "max", -inf),
    ("SlideJoint", "max", -1e308),
    ("RotaryLimitJoint", "min", inf),
    ("RotaryLimitJoint", "min", 1e308),
    ("RotaryLimitJoint", "max", -inf),
    ("RotaryLimitJoint", "max", -1e308),
    ("DampedSpring", "rest_length", 1e308),
    ("DampedSpring", "rest_length", -1e200),
    ("DampedSpring", "stiffness", 1e308),
    ("DampedSpring", "stiffness", -1e308),
    ("DampedSpring", "damping", -1e308),
    ("DampedSpring", "damping", -1.0),
    ("DampedRotarySpring", "rest_angle", 1e308),
    ("DampedRotarySpring", "stiffness", -1e308),
    ("DampedRotarySpring", "damping", -1e-3),
    ("GearJoint", "ratio", 5e-324),
    ("GearJoint", "ratio", -1e-300),
    ("GearJoint", "ratio", 1e308),
    ("GearJoint", "phase", -1e308),
    ("RatchetJoint", "ratchet", 5e-324),
    ("RatchetJoint", "ratchet", -5e-324),
    ("RatchetJoint", "phase", -1e308),
    ("SimpleMotor", "rate", 1e308),
    ("SimpleMotor", "rate", -1e308),
    ("PinJoint", "anchor_a", (1e308, 0)),
    ("PivotJoint", "anchor_b", (0, -1e200)),
    ("DampedSpring", "anchor_a", (1e101, 0)),
    ("GrooveJoint", "groove_a", (-1e308, 0)),
]


@pytest.mark.parametrize("kind,name,value", REFUSED)
def test_refused_in_the_constructor(kind, name, value):
    if name not in ORDINARY[kind]:
        pytest.skip("not a constructor argument")
    with pytest.raises(IllegalConstraint) as info:
        scene(kind, **{name: value})
    assert isinstance(info.value, ValueError) and isinstance(info.value, AssertionError)
    assert name in str(info.value) or "groove" in str(info.value)


@pytest.mark.parametrize("kind,name,value", REFUSED)
def test_refused_by_the_setter_and_nothing_changes(kind, name, value):
    s, a, b, j = scene(kind)
    before = getattr(j, name)
    with pytest.raises(IllegalConstraint):
        setattr(j, name, value)
    assert getattr(j, name) == before
    steps_finitely(s, a, b)


def test_the_reported_cases():
    a, b = Body(1, 1), Body(1, 1)
    with pytest.raises(IllegalConstraint, match="min"):
        SlideJoint(a, b, (0, 0), (0, 0), inf, inf)
    with pytest.raises(IllegalConstraint, match="rest_length"):
        DampedSpring(a, b, (0, 0), (0, 0), 1e308, 1, 1)
    with pytest.raises(IllegalConstraint, match="ratio"):
        GearJoint(a, b, 0, 5e-324)
    with pytest.raises(IllegalConstraint, match="rate"):
        SimpleMotor(a, b, 1e308)
    with pytest.raises(AssertionError):  # pymunk-style code catching asserts
        SimpleMotor(a, b, -1e308)


@pytest.mark.parametrize("groove_b", [(0, 0), (5e-324, 0), (0, -1e-320)])
def test_a_groove_of_zero_length_is_refused_in_a_step(groove_b):
    # pymunk's own tests build GrooveJoint(a, b, (0, 0), (0, 0), ...), so the
    # joint can be made and set; a step refuses it before moving anything.
    for build in ("constructor", "setter"):
        s, a, b, j = scene("GrooveJoint")
        if build == "constructor":
            s.remove(j)
            j = GrooveJoint(a, b, (0, 0), groove_b, (0, 0.5))
            s.add(j)
        else:
            j.groove_a = groove_b
            j.groove_b = groove_b
        p = b.position
        with pytest.raises(IllegalConstraint, match="groove"):
            s.step(1 / 60)
        assert b.position == p
        j.groove_b = (5, 0)
        j.groove_a = (0, 0)
        steps_finitely(s, a, b)


def test_common_parameters():
    j = PivotJoint(Body(1, 1), Body(1, 1), (0, 0))
    for name in ("max_force", "max_bias"):
        setattr(j, name, inf)           # the default: no limit
        setattr(j, name, 1e308)
        for bad in (-1.0, -inf, nan):
            with pytest.raises(IllegalConstraint):
                setattr(j, name, bad)
    j.error_bias = 3                    # pymunk's own pickle test sets it
    for bad in (nan, inf, -0.5, 1e101):
        with pytest.raises(IllegalConstraint):
            j.error_bias = bad
    assert j.error_bias == 3


def test_values_programs_use_are_accepted():
    a, b = Body(1, 1), Body(1, 1)
    SlideJoint(a, b, (0, 0), (0, 0), 0, inf)
    SlideJoint(a, b, (0, 0), (0, 0), -inf, inf)
    SlideJoint(a, b, (0, 0), (0, 0), -1e308, 1e308)
    RotaryLimitJoint(a, b, -inf, inf)
    RatchetJoint(a, b, 0, 0)            # pymunk's tests; refused only in a step
    GearJoint(a, b, 0, 0)
    DampedSpring(a, b, (0, 0), (0, 0), -1, -10, 0)   # negative rest length and stiffness
    limit = PARAMETER_LIMIT
    assert limit == 1e100
    j = DampedSpring(a, b, (limit, -limit), (0, 0), limit, limit, limit)
    assert j.anchor_a == (limit, -limit)
    g = GearJoint(a, b, limit, 1 / limit)
    assert g.ratio == 1 / limit
    PivotJoint(a, b, (limit, limit))


def test_pivot_far_from_a_body_is_refused():
    a, b = Body(1, 1), Body(1, 1)
    a.position = (-9e99, 0)
    with pytest.raises(IllegalConstraint, match="pivot"):
        PivotJoint(a, b, (9e99, 0))


def test_pickle_and_copy_keep_working():
    import pickle
    for kind in ORDINARY:
        s, a, b, j = scene(kind)
        j2 = pickle.loads(pickle.dumps(j))
        assert type(j2) is type(j)
        j.copy()


# -- the property ------------------------------------------------------------------------------

EXTREMES = [1e308, -1e308, 1e200, -1e200, 5e-324, -5e-324, 1e-320, -1e-300, 0.0, -0.0,
            inf, -inf, nan]
scalars = st.one_of(st.sampled_from(EXTREMES), st.floats(-1e3, 1e3))
points = st.one_of(st.tuples(scalars, scalars), st.just("equal"))


def _params(kind):
    return list(ORDINARY[kind]) + EXTRA.get(kind, []) + COMMON


@st.composite
def settings_of_a_joint(draw):
    kind = draw(st.sampled_from(sorted(ORDINARY)))
    names = draw(st.lists(st.sampled_from(_params(kind)), min_size=1, max_size=3, unique=True))
    values = {}
    for name in names:
        v = draw(points if name in POINTS else scalars)
        if v == "equal":
            v = ORDINARY[kind].get("groove_a" if name == "groove_b" else "groove_b", (0, 0))
        values[name] = v
    return kind, values, draw(st.booleans()), draw(st.booleans())


@isolated(timeout=600, note=lambda: f"(hypothesis seed {SEED}; rerun with TAMIAS2D_SEED={SEED})")
@seed(SEED)
@settings(max_examples=EXAMPLES, deadline=None, database=None, print_blob=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(case=settings_of_a_joint())
def test_accepted_parameters_keep_the_scene_finite(case):
    kind, values, in_constructor, static_a = case
    ctor = {k: v for k, v in values.items() if in_constructor and k in ORDINARY[kind]}
    try:
        s, a, b, j = scene(kind, static_a, **ctor)
    except (IllegalConstraint, IllegalVector):
        return
    for name, v in values.items():
        if name in ctor:
            continue
        try:
            setattr(j, name, v)
        except (IllegalConstraint, IllegalVector):
            pass
    steps_finitely(s, a, b)
