"""Vec2d, BB and Transform against pymunk 7.3.

Every operation runs on the same inputs in both libraries and the results must
be identical: same types (Vec2d for Vec2d, int for int, ...) and the same float
bits (-0.0 differs from 0.0; NaN matches NaN). When pymunk raises, tamias2d
must raise the same exception class (or a subclass of it).
"""
import copy
import math
import pickle
import struct
import warnings

import numpy as np
import pytest
from hypothesis import given, settings, HealthCheck
from hypothesis import strategies as st

import pymunk
from pymunk.vec2d import Vec2d as PVec2d
from pymunk.bb import BB as PBB
from pymunk.transform import Transform as PTransform

import tamias2d
from tamias2d import Vec2d, BB, Transform
from tamias2d import vector as tvector
from tamias2d import _testing
from tamias2d.errors import IllegalVector

SETTINGS = settings(max_examples=150, derandomize=True, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

# Numbers as a game script or the engine would produce them: small ints,
# ordinary floats, and the special values.
special = st.sampled_from([0, 1, -1, 0.0, -0.0, 1.0, -2.5, 1e-300, 5e-324, 1e300,
                           math.inf, -math.inf, math.nan])
numbers = st.one_of(st.integers(-1000, 1000), st.floats(-1e6, 1e6), special,
                    st.floats(allow_nan=True, allow_infinity=True))
finite = st.one_of(st.integers(-1000, 1000), st.floats(-1e6, 1e6))
pairs = st.tuples(numbers, numbers)
finite_pairs = st.tuples(finite, finite)


# -- exact comparison ------------------------------------------------------------

def _bits(f):
    return struct.pack("<d", f)


def assert_same(ours, theirs, where=""):
    """Identical structure, types and float bits (any NaN matches any NaN)."""
    kinds = ((PVec2d, Vec2d), (PBB, BB), (PTransform, Transform))
    for theirs_type, ours_type in kinds:
        if isinstance(theirs, theirs_type):
            assert type(ours) is ours_type, f"{where}: {ours!r} is not a {ours_type.__name__}"
            assert len(ours) == len(theirs), where
            for i, (a, b) in enumerate(zip(ours, theirs)):
                assert_same(a, b, f"{where}[{i}]")
            return
    if isinstance(theirs, float):
        assert type(ours) is float, f"{where}: {ours!r} ({type(ours).__name__}) is not a float"
        if math.isnan(theirs):
            assert math.isnan(ours), f"{where}: {ours!r} != nan"
        else:
            assert _bits(ours) == _bits(theirs), f"{where}: {ours!r} != {theirs!r}"
        return
    if isinstance(theirs, (tuple, list)):
        assert type(ours) is type(theirs), f"{where}: {type(ours)} is not {type(theirs)}"
        assert len(ours) == len(theirs), where
        for i, (a, b) in enumerate(zip(ours, theirs)):
            assert_same(a, b, f"{where}[{i}]")
        return
    if isinstance(theirs, dict):
        assert type(ours) is dict and list(ours) == list(theirs), where
        for k in theirs:
            assert_same(ours[k], theirs[k], f"{where}[{k!r}]")
        return
    assert type(ours) is type(theirs), f"{where}: {type(ours)} is not {type(theirs)}"
    assert ours == theirs, f"{where}: {ours!r} != {theirs!r}"


def outcome(fn, *args):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        try:
            return ("ok", fn(*args))
        except Exception as e:  # the comparison is the test
            return ("raised", e)


def compare(fn, ours_args, theirs_args, where):
    ours = outcome(fn, *ours_args)
    theirs = outcome(fn, *theirs_args)
    if theirs[0] == "raised":
        assert ours[0] == "raised", f"{where}: pymunk raised {theirs[1]!r}, tamias2d gave {ours[1]!r}"
        assert isinstance(ours[1], type(theirs[1])), (
            f"{where}: pymunk raised {theirs[1]!r}, tamias2d raised {ours[1]!r}")
    else:
        assert ours[0] == "ok", f"{where}: tamias2d raised {ours[1]!r}, pymunk gave {theirs[1]!r}"
        assert_same(ours[1], theirs[1], where)


# -- Vec2d -------------------------------------------------------------------------

# Each operation gets the library's Vec2d class first, then the vectors/numbers.
VEC_UNARY = {
    "repr": lambda V, v: repr(v),
    "str": lambda V, v: str(v),
    "x, y": lambda V, v: (v.x, v.y),
    "index": lambda V, v: (v[0], v[1], v[-1], v[:1]),
    "tuple": lambda V, v: tuple(v),
    "list": lambda V, v: list(v),
    "len": lambda V, v: len(v),
    "hash": lambda V, v: hash(v),
    "eq tuple": lambda V, v: (v == tuple(v), v != tuple(v)),
    "asdict": lambda V, v: v._asdict(),
    "replace": lambda V, v: v._replace(y=7),
    "make": lambda V, v: V._make(iter(v)),
    "getnewargs": lambda V, v: v.__getnewargs__(),
    "length": lambda V, v: v.length,
    "length_squared": lambda V, v: v.length_squared,
    "get_length_sqrd": lambda V, v: v.get_length_sqrd(),
    "angle": lambda V, v: v.angle,
    "angle_degrees": lambda V, v: v.angle_degrees,
    "normalized": lambda V, v: v.normalized(),
    "normalized_and_length": lambda V, v: v.normalized_and_length(),
    "perpendicular": lambda V, v: v.perpendicular(),
    "perpendicular_normal": lambda V, v: v.perpendicular_normal(),
    "int_tuple": lambda V, v: v.int_tuple,
    "polar_tuple": lambda V, v: v.polar_tuple,
    "neg": lambda V, v: -v,
    "pos": lambda V, v: +v,
    "abs": lambda V, v: abs(v),
    "bool": lambda V, v: bool(v),
}

VEC_SCALAR = {
    "mul": lambda V, v, s: v * s,
    "rmul": lambda V, v, s: s * v,
    "truediv": lambda V, v, s: v / s,
    "floordiv": lambda V, v, s: v // s,
    "rotated": lambda V, v, s: v.rotated(s),
    "rotated_degrees": lambda V, v, s: v.rotated_degrees(s),
    "scale_to_length": lambda V, v, s: v.scale_to_length(s),
    "from_polar": lambda V, v, s: V.from_polar(v[0], s),
}

VEC_BINARY = {
    "add": lambda V, v, w: v + w,
    "add tuple": lambda V, v, w: v + tuple(w),
    "add list": lambda V, v, w: v + list(w),
    "radd tuple": lambda V, v, w: tuple(w) + v,
    "radd list": lambda V, v, w: list(w) + v,
    "sub": lambda V, v, w: v - w,
    "sub tuple": lambda V, v, w: v - tuple(w),
    "rsub tuple": lambda V, v, w: tuple(w) - v,
    "rsub list": lambda V, v, w: list(w) - v,
    "eq": lambda V, v, w: (v == w, v != w),
    "dot": lambda V, v, w: v.dot(w),
    "cross": lambda V, v, w: v.cross(tuple(w)),
    "get_distance": lambda V, v, w: v.get_distance(w),
    "get_distance_squared": lambda V, v, w: v.get_distance_squared(w),
    "get_dist_sqrd": lambda V, v, w: v.get_dist_sqrd(w),
    "get_angle_between": lambda V, v, w: v.get_angle_between(w),
    "get_angle_degrees_between": lambda V, v, w: v.get_angle_degrees_between(w),
    "projection": lambda V, v, w: v.projection(w),
    "cpvrotate": lambda V, v, w: v.cpvrotate(w),
    "cpvunrotate": lambda V, v, w: v.cpvunrotate(list(w)),
}

VEC_TERNARY = {
    "interpolate_to": lambda V, v, w, s: v.interpolate_to(w, s),
    "convert_to_basis": lambda V, v, w, s: v.convert_to_basis(w, (s, 1)),
}


@pytest.mark.parametrize("name", sorted(VEC_UNARY))
@SETTINGS
@given(xy=pairs)
def test_vec2d_unary(name, xy):
    fn = VEC_UNARY[name]
    compare(fn, (Vec2d, Vec2d(*xy)), (PVec2d, PVec2d(*xy)), f"Vec2d{xy}.{name}")


@pytest.mark.parametrize("name", sorted(VEC_SCALAR))
@SETTINGS
@given(xy=pairs, s=numbers)
def test_vec2d_scalar(name, xy, s):
    fn = VEC_SCALAR[name]
    compare(fn, (Vec2d, Vec2d(*xy), s), (PVec2d, PVec2d(*xy), s), f"Vec2d{xy}.{name}({s!r})")


@pytest.mark.parametrize("name", sorted(VEC_BINARY))
@SETTINGS
@given(xy=pairs, uv=pairs)
def test_vec2d_binary(name, xy, uv):
    fn = VEC_BINARY[name]
    compare(fn, (Vec2d, Vec2d(*xy), Vec2d(*uv)), (PVec2d, PVec2d(*xy), PVec2d(*uv)),
            f"Vec2d{xy}.{name}({uv!r})")


@pytest.mark.parametrize("name", sorted(VEC_TERNARY))
@SETTINGS
@given(xy=pairs, uv=pairs, s=numbers)
def test_vec2d_ternary(name, xy, uv, s):
    fn = VEC_TERNARY[name]
    compare(fn, (Vec2d, Vec2d(*xy), Vec2d(*uv), s), (PVec2d, PVec2d(*xy), PVec2d(*uv), s),
            f"Vec2d{xy}.{name}({uv!r}, {s!r})")


def test_vec2d_constants():
    for name in ("zero", "unit", "ones"):
        assert_same(getattr(Vec2d, name)(), getattr(PVec2d, name)(), name)


def test_vec2d_numpy_operands():
    row = np.array([[1.5, -2.0], [3, 4]])[0]
    for fn in (lambda V: V(1, 2) + row, lambda V: V(1, 2) - row, lambda V: V(1, 2).dot(row),
               lambda V: V(1, 2) * np.float64(0.5), lambda V: V(1, 2).cross(row)):
        ours, theirs = fn(Vec2d), fn(PVec2d)
        assert ours == theirs
        assert [type(a) for a in np.atleast_1d(ours)] == [type(a) for a in np.atleast_1d(theirs)]


def test_vec2d_is_a_tuple():
    v = Vec2d(1, 2.5)
    assert isinstance(v, tuple)
    assert Vec2d.__mro__ == (Vec2d, tuple, object)
    assert v == (1, 2.5) and (1, 2.5) == v and v != (1, 2.5, 3) and v != 5
    assert hash(v) == hash((1, 2.5))
    assert {v: 1}[(1, 2.5)] == 1
    assert Vec2d._fields == ("x", "y") and Vec2d.__match_args__ == ("x", "y")
    assert Vec2d.__match_args__ == PVec2d.__match_args__ == ("x", "y")
    x, y = v
    assert (x, y) == (1, 2.5)
    assert Vec2d(x=3, y=4) == (3, 4)
    assert not hasattr(v, "__dict__")


def test_vec2d_immutable():
    v = Vec2d(1, 2)
    with pytest.raises(TypeError):
        v[0] = 3
    for attr in ("x", "y", "length", "angle", "foo"):
        with pytest.raises(AttributeError):
            setattr(v, attr, 3)


@pytest.mark.parametrize("protocol", range(pickle.HIGHEST_PROTOCOL + 1))
def test_pickle(protocol):
    for obj in (Vec2d(1, 2.5), Vec2d(-0.0, math.inf), BB(1, 2, 3.5, 4), BB(),
                Transform(1, 2, 3, 4, 5, 6.5), Transform.identity()):
        back = pickle.loads(pickle.dumps(obj, protocol))
        assert type(back) is type(obj)
        assert_same(back, obj)
    for obj in (Vec2d(1, 2), BB(0, 1, 2, 3), Transform(tx=3)):
        assert_same(copy.copy(obj), obj)
        assert_same(copy.deepcopy(obj), obj)


def test_subclass():
    class V(Vec2d):
        pass
    v = V(1, 2)
    assert type(v) is V and v == (1, 2) and v.x == 1
    # pymunk returns plain Vec2d from operations, whatever the operand class
    assert type(v + (1, 1)) is Vec2d
    assert type(v._replace(x=0)) is V


def test_vec2d_deprecations_warn():
    with pytest.warns(DeprecationWarning):
        Vec2d(1, 2).get_length_sqrd()
    with pytest.warns(DeprecationWarning):
        Vec2d(1, 2).get_dist_sqrd((0, 0))


# -- bad input ----------------------------------------------------------------------

def test_vec2d_bad_operands():
    v = Vec2d(1, 2)
    # pymunk asserts on the length: the error is an AssertionError there too
    for bad in ((1, 2, 3), [1], ()):
        for fn in (lambda: v + bad, lambda: bad + v, lambda: v - bad, lambda: bad - v,
                   lambda: v.dot(bad), lambda: v.cross(bad), lambda: v.get_distance(bad),
                   lambda: v.projection(bad), lambda: v.interpolate_to(bad, 0.5),
                   lambda: v.cpvrotate(bad), lambda: v.get_angle_between(bad)):
            with pytest.raises(IllegalVector) as info:
                fn()
            assert isinstance(info.value, (ValueError, AssertionError))
    for bad in (None, 5, 1.5, object()):
        with pytest.raises(TypeError):
            v + bad
        with pytest.raises(TypeError):
            v.dot(bad)
    # pymunk raises AssertionError for a non-real scale; tamias2d a TypeError
    for bad in ((1, 2), "a", None, 1j, Vec2d(1, 1)):
        with pytest.raises(TypeError, match="real number"):
            v * bad
        with pytest.raises(TypeError, match="real number"):
            v / bad
        with pytest.raises(TypeError, match="real number"):
            v // bad
    with pytest.raises(ZeroDivisionError):
        v / 0
    with pytest.raises(ZeroDivisionError):
        Vec2d(0, 0).scale_to_length(1)
    with pytest.raises(TypeError):
        Vec2d(1)
    with pytest.raises(TypeError):
        Vec2d(1, 2, 3)
    with pytest.raises(TypeError):
        Vec2d._make([1, 2, 3])
    with pytest.raises(ValueError):
        v._replace(z=1)
    with pytest.raises(TypeError):
        Vec2d.__new__(int, 1, 2)


def test_methods_on_malformed_self_raise():
    # A tuple.__new__ built Vec2d of the wrong size must not crash.
    bad = tuple.__new__(Vec2d, (1,))
    with pytest.raises(TypeError):
        bad.length
    with pytest.raises(TypeError):
        bad + (1, 2)
    with pytest.raises(TypeError):
        Vec2d.dot(5, (1, 2))
    bad_bb = tuple.__new__(BB, (1, 2))
    with pytest.raises(IllegalVector):
        bad_bb.area()
    with pytest.raises(TypeError):
        Transform.inverted((1, 2))


# -- C boundary helpers -----------------------------------------------------------

@SETTINGS
@given(xy=st.tuples(st.floats(allow_nan=False), st.floats(allow_nan=False)))
def test_cpv_from_object_accepts_2_sequences(xy):
    x, y = xy
    expect = Vec2d(float(x), float(y))
    for o in (Vec2d(x, y), (x, y), [x, y], np.array([x, y]), np.array([[x, y]])[0]):
        assert_same(_testing._cpv_roundtrip(o), expect)


def test_cpv_from_object_conversions():
    assert_same(_testing._cpv_roundtrip((1, True)), Vec2d(1.0, 1.0))
    assert_same(_testing._cpv_roundtrip(np.array([3, 4], dtype=np.int32)), Vec2d(3.0, 4.0))
    assert_same(_testing._cpv_roundtrip((np.float32(0.1), 2)), Vec2d(float(np.float32(0.1)), 2.0))
    nan = _testing._cpv_roundtrip((math.nan, -math.inf))
    assert math.isnan(nan.x) and nan.y == -math.inf


@pytest.mark.parametrize("bad, exc", [
    ((1, 2, 3), IllegalVector), ([1], IllegalVector), ((), IllegalVector),
    (np.zeros(3), IllegalVector),
    (None, TypeError), (5, TypeError), (1.5, TypeError), ({1, 2}, TypeError),
    ("ab", TypeError), ((1, "a"), TypeError), (["a", 2], TypeError), ((1, None), TypeError),
    ((1j, 0), TypeError), ((10**400, 0), OverflowError),
])
def test_cpv_from_object_rejects(bad, exc):
    with pytest.raises(exc) as info:
        _testing._cpv_roundtrip(bad)
    assert str(info.value)


def test_cpv_from_object_finite():
    assert_same(_testing._cpv_finite_roundtrip((1, 2), "gravity"), Vec2d(1.0, 2.0))
    for bad in ((math.nan, 0), (0, math.inf), (-math.inf, 1), [0, math.nan]):
        with pytest.raises(IllegalVector, match="gravity must be finite") as info:
            _testing._cpv_finite_roundtrip(bad, "gravity")
        assert isinstance(info.value, ValueError)
    with pytest.raises(IllegalVector, match="position"):
        _testing._cpv_finite_roundtrip((1, 2, 3), "position")
    with pytest.raises(TypeError, match="position"):
        _testing._cpv_finite_roundtrip(None, "position")


def test_bb_and_transform_conversions():
    assert_same(_testing._cpbb_roundtrip(BB(1, 2, 3, 4)), BB(1.0, 2.0, 3.0, 4.0))
    assert_same(_testing._cpbb_roundtrip(np.arange(4)), BB(0.0, 1.0, 2.0, 3.0))
    assert_same(_testing._cptransform_roundtrip([1, 2, 3, 4, 5, 6]),
                Transform(1.0, 2.0, 3.0, 4.0, 5.0, 6.0))
    with pytest.raises(IllegalVector):
        _testing._cpbb_roundtrip((1, 2, 3))
    with pytest.raises(IllegalVector):
        _testing._cptransform_roundtrip(BB())
    with pytest.raises(TypeError):
        _testing._cpbb_roundtrip((1, 2, 3, "x"))


# -- BB -------------------------------------------------------------------------------

bbs = st.tuples(numbers, numbers, numbers, numbers)
# BB methods pass through C doubles in both libraries; huge ints are not
# something either accepts in the same way, so the coordinates are floats or
# small ints.

BB_OPS = {
    "repr": lambda B, V, bb, o, p, q, r: repr(bb),
    "fields": lambda B, V, bb, o, p, q, r: (bb.left, bb.bottom, bb.right, bb.top),
    "asdict": lambda B, V, bb, o, p, q, r: bb._asdict(),
    "replace": lambda B, V, bb, o, p, q, r: bb._replace(top=r),
    "hash": lambda B, V, bb, o, p, q, r: hash(bb),
    "newForCircle": lambda B, V, bb, o, p, q, r: B.newForCircle(p, r),
    "newForCircle Vec2d": lambda B, V, bb, o, p, q, r: B.newForCircle(V(*p), r),
    "intersects": lambda B, V, bb, o, p, q, r: bb.intersects(o),
    "intersects tuple": lambda B, V, bb, o, p, q, r: bb.intersects(tuple(o)),
    "intersects_segment": lambda B, V, bb, o, p, q, r: bb.intersects_segment(p, V(*q)),
    "contains": lambda B, V, bb, o, p, q, r: bb.contains(o),
    "contains_vect": lambda B, V, bb, o, p, q, r: bb.contains_vect(V(*p)),
    "merge": lambda B, V, bb, o, p, q, r: bb.merge(o),
    "merged_area": lambda B, V, bb, o, p, q, r: bb.merged_area(o),
    "area": lambda B, V, bb, o, p, q, r: bb.area(),
    "center": lambda B, V, bb, o, p, q, r: bb.center(),
    "expand": lambda B, V, bb, o, p, q, r: bb.expand(p),
    "expand Vec2d": lambda B, V, bb, o, p, q, r: bb.expand(V(*p)),
    "segment_query": lambda B, V, bb, o, p, q, r: bb.segment_query(p, q),
    "clamp_vect": lambda B, V, bb, o, p, q, r: bb.clamp_vect(V(*p)),
}


@pytest.mark.parametrize("name", sorted(BB_OPS))
@SETTINGS
@given(bb=bbs, other=bbs, p=pairs, q=pairs, r=numbers)
def test_bb(name, bb, other, p, q, r):
    fn = BB_OPS[name]
    compare(fn, (BB, Vec2d, BB(*bb), BB(*other), p, q, r),
            (PBB, PVec2d, PBB(*bb), PBB(*other), p, q, r), f"BB{bb}.{name}({other}, {p}, {q}, {r})")


def test_bb_segment_query_axis_parallel():
    # delta == 0 on one axis takes the exact-zero branch of the slab test
    for a, b in (((-1, 1), (99, 1)), ((5, -3), (5, 20)), ((5, 5), (5, 5)), ((11, 5), (11, 6)),
                 ((10, 10), (20, 10)), ((-0.0, 0), (0.0, 10))):
        assert_same(BB(0, 0, 10, 10).segment_query(a, b), PBB(0, 0, 10, 10).segment_query(a, b))


def test_bb_defaults_and_tuple_behaviour():
    assert_same(BB(), PBB())
    assert_same(BB(right=5, top=10), PBB(right=5, top=10))
    assert BB._fields == PBB._fields and BB._field_defaults == PBB._field_defaults
    assert BB.__mro__ == (BB, tuple, object)
    assert BB(1, 2, 3, 4) == (1, 2, 3, 4) and hash(BB(1, 2, 3, 4)) == hash((1, 2, 3, 4))
    assert_same(BB._make([1, 2, 3, 4]), PBB._make([1, 2, 3, 4]))
    with pytest.raises(TypeError):
        BB(1, 2, 3, 4, 5)
    with pytest.raises(IllegalVector):
        BB(0, 0, 1, 1).contains_vect((1, 2, 3))
    with pytest.raises(IllegalVector):
        BB(0, 0, 1, 1).intersects((0, 0, 1))
    with pytest.raises(TypeError):
        BB(0, 0, 1, 1).segment_query(None, (1, 1))
    with pytest.raises(TypeError):
        BB.newForCircle((0, 0), "r")


# -- Transform ------------------------------------------------------------------------

transforms = st.tuples(numbers, numbers, numbers, numbers, numbers, numbers)

TRANSFORM_OPS = {
    "repr": lambda T, V, t, u, p, s: repr(t),
    "fields": lambda T, V, t, u, p, s: (t.a, t.b, t.c, t.d, t.tx, t.ty),
    "asdict": lambda T, V, t, u, p, s: t._asdict(),
    "replace": lambda T, V, t, u, p, s: t._replace(c=s),
    "matmul Vec2d": lambda T, V, t, u, p, s: t @ V(*p),
    "matmul tuple": lambda T, V, t, u, p, s: t @ p,
    "matmul list": lambda T, V, t, u, p, s: t @ list(p),
    "matmul Transform": lambda T, V, t, u, p, s: t @ u,
    "matmul 6-tuple": lambda T, V, t, u, p, s: t @ tuple(u),
    "inverted": lambda T, V, t, u, p, s: t.inverted(),
    "translated": lambda T, V, t, u, p, s: t.translated(p[0], p[1]),
    "scaled": lambda T, V, t, u, p, s: t.scaled(s),
    "rotated": lambda T, V, t, u, p, s: t.rotated(s),
    "translation": lambda T, V, t, u, p, s: T.translation(*p),
    "scaling": lambda T, V, t, u, p, s: T.scaling(s),
    "rotation": lambda T, V, t, u, p, s: T.rotation(s),
    "identity": lambda T, V, t, u, p, s: T.identity(),
}


@pytest.mark.parametrize("name", sorted(TRANSFORM_OPS))
@SETTINGS
@given(t=transforms, u=transforms, p=pairs, s=numbers)
def test_transform(name, t, u, p, s):
    fn = TRANSFORM_OPS[name]
    compare(fn, (Transform, Vec2d, Transform(*t), Transform(*u), p, s),
            (PTransform, PVec2d, PTransform(*t), PTransform(*u), p, s),
            f"Transform{t}.{name}({u}, {p}, {s})")


def test_transform_defaults_and_errors():
    assert_same(Transform(), PTransform())
    assert_same(Transform(b=3, ty=5), PTransform(b=3, ty=5))
    assert Transform._fields == PTransform._fields
    assert Transform._field_defaults == PTransform._field_defaults
    assert Transform.__mro__ == (Transform, tuple, object)
    with pytest.raises(ValueError, match="singular"):
        Transform(1, 2, 2, 4).inverted()
    for bad in ((1, 2, 3), BB(), []):
        with pytest.raises(IllegalVector) as info:
            Transform() @ bad
        assert isinstance(info.value, AssertionError)
    with pytest.raises(TypeError):
        Transform() @ 5


def test_exports():
    assert tamias2d.Vec2d is Vec2d and tamias2d.BB is BB and tamias2d.Transform is Transform
    assert Vec2d.__module__ == "tamias2d.vector"


# -- the C kernels of vector.pxd ------------------------------------------------------
#
# The BB kernels are compared with Chipmunk itself (pymunk's compiled library
# exports them). The vector and transform kernels are not exported by pymunk,
# so they are compared with the C expressions evaluated in Python floats
# (IEEE doubles, same libm), written with the C association.

from pymunk._chipmunk_cffi import lib as cp_lib  # noqa: E402

DBL_MIN = 2.2250738585072014e-308


def _div(a, b):
    """C division of doubles (no ZeroDivisionError)."""
    with np.errstate(all="ignore"):
        return float(np.float64(a) / np.float64(b))


def _cos(a):
    return math.nan if math.isinf(a) else math.cos(a)


def _sin(a):
    return math.nan if math.isinf(a) else math.sin(a)


def _acos(a):
    return math.acos(a) if -1.0 <= a <= 1.0 else math.nan


def r_fmax(a, b): return a if a > b else b
def r_fmin(a, b): return a if a < b else b
def r_fabs(f): return -f if f < 0 else f
def r_fclamp(f, lo, hi): return r_fmin(r_fmax(f, lo), hi)
def r_fclamp01(f): return r_fmax(0.0, r_fmin(f, 1.0))
def r_add(a, b): return (a[0] + b[0], a[1] + b[1])
def r_sub(a, b): return (a[0] - b[0], a[1] - b[1])
def r_mult(v, s): return (v[0] * s, v[1] * s)
def r_dot(a, b): return a[0] * b[0] + a[1] * b[1]
def r_length(v): return math.sqrt(r_dot(v, v))
def r_lerp(a, b, t): return r_add(r_mult(a, 1.0 - t), r_mult(b, t))
def r_normalize(v): return r_mult(v, _div(1.0, r_length(v) + DBL_MIN))
def r_forangle(a): return (_cos(a), _sin(a))


def r_slerp(a, b, t):
    omega = _acos(r_fclamp(r_dot(r_normalize(a), r_normalize(b)), -1.0, 1.0))
    if omega < 1e-3:
        return r_lerp(a, b, t)
    denom = _div(1.0, _sin(omega))
    return r_add(r_mult(a, _sin((1.0 - t) * omega) * denom), r_mult(b, _sin(t * omega) * denom))


def r_slerpconst(a, b, angle):
    omega = _acos(r_fclamp(r_dot(r_normalize(a), r_normalize(b)), -1.0, 1.0))
    return r_slerp(a, b, _div(r_fmin(angle, omega), omega))


def r_clamp(v, length):
    return r_mult(r_normalize(v), length) if r_dot(v, v) > length * length else v


def r_bbcenter(bb): return r_lerp((bb[0], bb[1]), (bb[2], bb[3]), 0.5)
def r_extents(c, hw, hh): return (c[0] - hw, c[1] - hh, c[0] + hw, c[1] + hh)
def r_tt(a, c, tx, b, d, ty): return (a, b, c, d, tx, ty)
def r_tpoint(t, p): return (t[0] * p[0] + t[2] * p[1] + t[4], t[1] * p[0] + t[3] * p[1] + t[5])


def r_tinverse(t):
    a, b, c, d, tx, ty = t
    inv = _div(1.0, a * d - c * b)
    return r_tt(d * inv, -c * inv, (c * ty - tx * d) * inv, -b * inv, a * inv, (tx * b - a * ty) * inv)


def r_tmult(t1, t2):
    a1, b1, c1, d1, tx1, ty1 = t1
    a2, b2, c2, d2, tx2, ty2 = t2
    return r_tt(a1 * a2 + c1 * b2, a1 * c2 + c1 * d2, a1 * tx2 + c1 * ty2 + tx1,
                b1 * a2 + d1 * b2, b1 * c2 + d1 * d2, b1 * tx2 + d1 * ty2 + ty1)


def r_tbbb(t, bb):
    center = r_bbcenter(bb)
    hw = (bb[2] - bb[0]) * 0.5
    hh = (bb[3] - bb[1]) * 0.5
    a, b, d, e = t[0] * hw, t[2] * hh, t[1] * hw, t[3] * hh
    return r_extents(r_tpoint(t, center), r_fmax(r_fabs(a + b), r_fabs(a - b)),
                     r_fmax(r_fabs(d + e), r_fabs(d - e)))


def r_rotate_t(angle):
    rx, ry = r_forangle(angle)
    return r_tt(rx, -ry, 0.0, ry, rx, 0.0)


def r_rigid(rot, v):
    return r_tt(rot[0], -rot[1], v[0], rot[1], rot[0], v[1])


def r_closest(p, a, b):
    delta = r_sub(a, b)
    t = r_fclamp01(_div(r_dot(delta, r_sub(p, b)), r_dot(delta, delta)))
    return r_add(b, r_mult(delta, t))


# name -> (argument kinds, reference); kinds: s scalar, v vector, b box, t transform, m 2x2
KERNEL_REFERENCES = {
    "cpfmax": ("ss", r_fmax),
    "cpfmin": ("ss", r_fmin),
    "cpfabs": ("s", r_fabs),
    "cpfclamp": ("sss", r_fclamp),
    "cpfclamp01": ("s", r_fclamp01),
    "cpflerp": ("sss", lambda f1, f2, t: f1 * (1.0 - t) + f2 * t),
    "cpflerpconst": ("sss", lambda f1, f2, d: f1 + r_fclamp(f2 - f1, -d, d)),
    "cpv": ("ss", lambda x, y: (x, y)),
    "cpveql": ("vv", lambda a, b: a[0] == b[0] and a[1] == b[1]),
    "cpvadd": ("vv", r_add),
    "cpvsub": ("vv", r_sub),
    "cpvneg": ("v", lambda v: (-v[0], -v[1])),
    "cpvmult": ("vs", r_mult),
    "cpvdot": ("vv", r_dot),
    "cpvcross": ("vv", lambda a, b: a[0] * b[1] - a[1] * b[0]),
    "cpvperp": ("v", lambda v: (-v[1], v[0])),
    "cpvrperp": ("v", lambda v: (v[1], -v[0])),
    "cpvproject": ("vv", lambda a, b: r_mult(b, _div(r_dot(a, b), r_dot(b, b)))),
    "cpvforangle": ("s", r_forangle),
    "cpvtoangle": ("v", lambda v: math.atan2(v[1], v[0])),
    "cpvrotate": ("vv", lambda a, b: (a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0])),
    "cpvunrotate": ("vv", lambda a, b: (a[0] * b[0] + a[1] * b[1], a[1] * b[0] - a[0] * b[1])),
    "cpvlengthsq": ("v", lambda v: r_dot(v, v)),
    "cpvlength": ("v", r_length),
    "cpvlerp": ("vvs", r_lerp),
    "cpvnormalize": ("v", r_normalize),
    "cpvslerp": ("vvs", r_slerp),
    "cpvslerpconst": ("vvs", r_slerpconst),
    "cpvclamp": ("vs", r_clamp),
    "cpvlerpconst": ("vvs", lambda a, b, d: r_add(a, r_clamp(r_sub(b, a), d))),
    "cpvdist": ("vv", lambda a, b: r_length(r_sub(a, b))),
    "cpvdistsq": ("vv", lambda a, b: r_dot(r_sub(a, b), r_sub(a, b))),
    "cpvnear": ("vvs", lambda a, b, d: r_dot(r_sub(a, b), r_sub(a, b)) < d * d),
    "cpMat2x2New": ("ssss", lambda a, b, c, d: (a, b, c, d)),
    "cpMat2x2Transform": ("mv", lambda m, v: (v[0] * m[0] + v[1] * m[1], v[0] * m[2] + v[1] * m[3])),
    "cpClosetPointOnSegment": ("vvv", r_closest),
    "cpTransformNew": ("ssssss", lambda *t: t),
    "cpTransformNewTranspose": ("ssssss", r_tt),
    "cpTransformIdentity": ("", lambda: (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)),
    "cpTransformInverse": ("t", r_tinverse),
    "cpTransformMult": ("tt", r_tmult),
    "cpTransformPoint": ("tv", r_tpoint),
    "cpTransformVect": ("tv", lambda t, v: (t[0] * v[0] + t[2] * v[1], t[1] * v[0] + t[3] * v[1])),
    "cpTransformbBB": ("tb", r_tbbb),
    "cpTransformTranslate": ("v", lambda v: r_tt(1.0, 0.0, v[0], 0.0, 1.0, v[1])),
    "cpTransformScale": ("ss", lambda sx, sy: r_tt(sx, 0.0, 0.0, 0.0, sy, 0.0)),
    "cpTransformRotate": ("s", r_rotate_t),
    "cpTransformRigid": ("vs", lambda v, a: r_rigid(r_forangle(a), v)),
    "cpTransformRigidInverse": ("t", lambda t: r_tt(t[3], -t[2], (t[2] * t[5] - t[4] * t[3]),
                                                    -t[1], t[0], (t[4] * t[1] - t[0] * t[5]))),
    "cpTransformWrap": ("tt", lambda o, i: r_tmult(r_tinverse(o), r_tmult(i, o))),
    "cpTransformWrapInverse": ("tt", lambda o, i: r_tmult(o, r_tmult(i, r_tinverse(o)))),
}

# The BB kernels against Chipmunk's own compiled functions.
BB_KERNELS = {
    "cpBBNew": "ssss", "cpBBNewForExtents": "vss", "cpBBNewForCircle": "vs",
    "cpBBIntersects": "bb", "cpBBContainsBB": "bb", "cpBBContainsVect": "bv",
    "cpBBMerge": "bb", "cpBBExpand": "bv", "cpBBCenter": "b", "cpBBArea": "b",
    "cpBBMergedArea": "bb", "cpBBSegmentQuery": "bvv", "cpBBIntersectsSegment": "bvv",
    "cpBBClampVect": "bv", "cpBBWrapVect": "bv", "cpBBOffset": "bv",
}

floats = st.one_of(st.floats(-1e6, 1e6), st.floats(),
                   st.sampled_from([0.0, -0.0, 1.0, -1.0, 1e-3, math.inf, -math.inf, math.nan]))
_KIND_SIZES = {"s": 0, "v": 2, "b": 4, "t": 6, "m": 4}


def _args(draw, kinds):
    args = []
    for kind in kinds:
        if kind == "s":
            args.append(draw(floats))
        else:
            args.append(tuple(draw(floats) for _ in range(_KIND_SIZES[kind])))
    return args


def _as_plain(x):
    """Kernel results as tuples of floats (or a bool / float)."""
    if isinstance(x, tuple):
        return tuple(x)
    return x


def _cp_result(x):
    if isinstance(x, (bool, float, int)):
        return x
    if hasattr(x, "l"):
        return (x.l, x.b, x.r, x.t)
    return (x.x, x.y)


def test_every_kernel_is_checked():
    assert set(_testing._KERNELS) == (set(KERNEL_REFERENCES) | set(BB_KERNELS)
                                     | {"cpvzero", "VECT_ERR"})


@pytest.mark.parametrize("name", sorted(KERNEL_REFERENCES))
@SETTINGS
@given(data=st.data())
def test_kernel_matches_c_expression(name, data):
    kinds, ref = KERNEL_REFERENCES[name]
    args = _args(data.draw, kinds)
    ours = _as_plain(_testing._kernel(name, *args))
    expected = ref(*args)
    if isinstance(expected, bool):
        assert ours is expected, f"{name}{tuple(args)}"
    else:
        assert_same(ours, expected, f"{name}{tuple(args)}")


@pytest.mark.parametrize("name", sorted(BB_KERNELS))
@SETTINGS
@given(data=st.data())
def test_bb_kernel_matches_chipmunk(name, data):
    args = _args(data.draw, BB_KERNELS[name])
    ours = _as_plain(_testing._kernel(name, *args))
    theirs = _cp_result(getattr(cp_lib, name)(*args))
    if isinstance(ours, bool):
        assert ours == bool(theirs), f"{name}{tuple(args)}"
    else:
        assert_same(ours, theirs, f"{name}{tuple(args)}")


def test_mis_constants():
    zero, err, pi = _testing._mis_constants()
    assert_same(zero, Vec2d(0.0, 0.0))
    assert_same(err, Vec2d(2147483647.0, -2147483648.0))
    assert pi == math.pi
    assert_same(_testing._kernel("cpvzero"), Vec2d(0.0, 0.0))
    assert_same(_testing._kernel("VECT_ERR"), err)
