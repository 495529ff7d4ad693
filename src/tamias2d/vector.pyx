"""Vectors, bounding boxes and affine transforms: ``Vec2d``, ``BB``, ``Transform``.

The three types are immutable tuples with named fields, as in pymunk 7.3, so
they compare equal to plain tuples, hash like them, unpack, pickle and can be
passed wherever a tuple is expected:

>>> v = Vec2d(3, 4)
>>> v.x, v.y, v.length
(3, 4, 5.0)
>>> v == (3, 4), isinstance(v, tuple)
(True, True)
>>> v + (1, -1)
Vec2d(4, 3)
>>> BB(0, 0, 4, 2).center()
Vec2d(2.0, 1.0)
>>> Transform.translation(5, 0) @ v
Vec2d(8, 4)

Arithmetic on ``Vec2d`` and ``Transform`` is Python arithmetic on the stored
items (integers stay integers), done in the same order as pymunk does it; the
``BB`` methods and the C side of the engine work on doubles through the inline
kernels of ``vector.pxd``. The tests reach those kernels and the C boundary
helpers through ``_testing._kernel`` and the round trips of ``_testing``.
"""
import math
import numbers as _numbers
import warnings as _warnings

from cpython.object cimport PyTypeObject
from cpython.ref cimport Py_INCREF
from cpython.tuple cimport PyTuple_Check, PyTuple_GET_SIZE, PyTuple_SET_ITEM
from cpython.list cimport PyList_Check, PyList_GET_SIZE
from cpython.float cimport PyFloat_CheckExact, PyFloat_AS_DOUBLE
from cpython.long cimport PyLong_CheckExact
from cpython.number cimport (PyNumber_Add, PyNumber_Subtract, PyNumber_Multiply,
                             PyNumber_TrueDivide, PyNumber_FloorDivide, PyNumber_Negative,
                             PyNumber_Positive, PyNumber_Power)
from libc.math cimport sqrt, isfinite, isnan

from tamias2d.errors import IllegalVector

try:
    # The C accessor that collections.namedtuple uses for its fields: fast,
    # read-only, and raises AttributeError on assignment.
    from collections import _tuplegetter
except ImportError:  # pragma: no cover - other Python implementations
    from operator import itemgetter as _itemgetter

    def _tuplegetter(index, doc):
        return property(_itemgetter(index), doc=doc)

__all__ = ["Vec2d", "BB", "Transform"]

cdef extern from *:
    """
    /* A new instance of a tuple subclass with n empty slots, made the way
       tuple.__new__ makes subclass instances (through the type's tp_alloc),
       without building and copying an argument tuple first. Python 3.14
       caches tuple hashes in the object; tp_alloc zeroes that field, so it is
       reset to "not computed". */
    static PyObject *tamias2d_tuple_alloc(PyTypeObject *tp, Py_ssize_t n) {
        PyObject *o = tp->tp_alloc(tp, n);
    #if PY_VERSION_HEX >= 0x030E0000 && !defined(Py_LIMITED_API)
        if (o != NULL) ((PyTupleObject *)o)->ob_hash = -1;
    #endif
        return o;
    }

    /* A (float, float) instance of tuple subclass tp: the hot path of every
       vector-valued property read. */
    static PyObject *tamias2d_pair_from_doubles(PyTypeObject *tp, double x, double y) {
        PyObject *o = tamias2d_tuple_alloc(tp, 2);
        PyObject *f;
        if (o == NULL) return NULL;
        f = PyFloat_FromDouble(x);
        if (f == NULL) { Py_DECREF(o); return NULL; }
        PyTuple_SET_ITEM(o, 0, f);
        f = PyFloat_FromDouble(y);
        if (f == NULL) { Py_DECREF(o); return NULL; }
        PyTuple_SET_ITEM(o, 1, f);
        return o;
    }
    """
    object tamias2d_tuple_alloc(PyTypeObject *tp, Py_ssize_t n)
    object tamias2d_pair_from_doubles(PyTypeObject *tp, double x, double y)


# Python's math functions, called where pymunk calls them, so that error
# behaviour (math domain error on cos(inf), ...) and results are Python's.
cdef object _cos = math.cos
cdef object _sin = math.sin
cdef object _atan2 = math.atan2
cdef object _degrees = math.degrees
cdef object _radians = math.radians
cdef object _Real = _numbers.Real

# Set once the classes exist (end of module).
cdef PyTypeObject *_vec2d_tp = NULL
cdef object _Vec2d = None
cdef object _BB = None
cdef object _Transform = None


# -- small helpers -----------------------------------------------------------
# Python arithmetic on the stored items, through the C-API number protocol.
# Cython's inlined fast paths for "object + object" and "object * object"
# return an operand unchanged when the other is an int zero (or the float is
# zero), which loses the sign of zero (0.0 * -3 gives 0.0, Python gives -0.0).
# These calls are exactly what the interpreter does for the same expression.
cdef object _TWO = 2

cdef inline object _add(object a, object b):
    return PyNumber_Add(a, b)

cdef inline object _sub(object a, object b):
    return PyNumber_Subtract(a, b)

cdef inline object _mul(object a, object b):
    return PyNumber_Multiply(a, b)

cdef inline object _div(object a, object b):
    return PyNumber_TrueDivide(a, b)

cdef inline object _fdiv(object a, object b):
    return PyNumber_FloorDivide(a, b)

cdef inline object _neg(object a):
    return PyNumber_Negative(a)

cdef inline object _pos(object a):
    return PyNumber_Positive(a)

cdef inline object _sq(object a):
    """``a ** 2`` as Python computes it (for floats: libm pow, not a * a)."""
    return PyNumber_Power(a, _TWO, None)

cdef inline object _len_sq(tuple t):
    """``t[0] ** 2 + t[1] ** 2``."""
    return PyNumber_Add(PyNumber_Power(t[0], _TWO, None), PyNumber_Power(t[1], _TWO, None))


cdef inline object _vec(object x, object y):
    """A Vec2d holding the two objects as they are."""
    cdef object o = tamias2d_tuple_alloc(_vec2d_tp, 2)
    Py_INCREF(x)
    PyTuple_SET_ITEM(o, 0, x)
    Py_INCREF(y)
    PyTuple_SET_ITEM(o, 1, y)
    return o


cdef object _new_tuple(object cls, object base, tuple items):
    """An instance of ``cls`` (``base`` or a subclass of it) holding ``items``."""
    cdef Py_ssize_t i, n
    cdef object o, item
    if cls is not base and not (isinstance(cls, type) and issubclass(cls, base)):
        raise TypeError(f"{base.__name__}.__new__({cls!r}): not a subtype of {base.__name__}")
    n = len(items)
    o = tamias2d_tuple_alloc(<PyTypeObject *>cls, n)
    for i in range(n):
        item = items[i]
        Py_INCREF(item)
        PyTuple_SET_ITEM(o, i, item)
    return o


cdef str _safe_repr(object o):
    """repr that does not call our own __repr__ (which would reject a tuple
    subclass of the wrong size and recurse)."""
    if PyTuple_Check(o) and type(o) is not tuple:
        return type(o).__name__ + tuple.__repr__(o)
    return repr(o)


cdef inline tuple _self_items(object self, Py_ssize_t n, str name):
    """``self`` of a method, checked to be a tuple of ``n`` items."""
    if not PyTuple_Check(self) or PyTuple_GET_SIZE(self) != n:
        raise TypeError(f"expected a {name} of {n} items, got {_safe_repr(self)}")
    return <tuple>self


cdef tuple _seq_items(object o, Py_ssize_t n, str what):
    """The items of a Python sequence of length ``n`` (kept as they are)."""
    cdef Py_ssize_t m
    if PyTuple_Check(o):
        if PyTuple_GET_SIZE(o) == n:
            return <tuple>o
        m = PyTuple_GET_SIZE(o)
    else:
        try:
            m = len(o)
        except TypeError:
            raise TypeError(
                f"{what} must be a sequence of {n} numbers, got {type(o).__name__}") from None
        if m == n:
            try:
                return tuple([o[i] for i in range(n)])
            except (TypeError, KeyError, IndexError) as e:
                raise TypeError(
                    f"{what} must be a sequence of {n} numbers, "
                    f"got an unindexable {type(o).__name__}") from e
    raise IllegalVector(f"{what} must be a sequence of {n} numbers, got {m} items: {_safe_repr(o)}")


cdef inline tuple _pair(object o):
    """A 2-sequence argument of a Vec2d method, as a tuple of its two items."""
    if PyTuple_Check(o) and PyTuple_GET_SIZE(o) == 2:
        return <tuple>o
    return _seq_items(o, 2, "the other vector")


cdef inline object _check_real(object s):
    """Raise unless ``s`` is a real number (what pymunk accepts as a scale)."""
    if PyFloat_CheckExact(s) or PyLong_CheckExact(s) or isinstance(s, _Real):
        return s
    raise TypeError(f"a Vec2d can only be scaled by a real number, not {type(s).__name__}")


cdef object _sqrt(object s):
    """``math.sqrt`` of a number: same value (IEEE square root), same errors."""
    cdef double d = s
    if d < 0.0:
        raise ValueError("math domain error")
    return sqrt(d)


cdef double _component_slow(object item, object seq, str what) except? -1.0:
    try:
        return item
    except TypeError:
        raise TypeError(
            f"{what} must hold numbers, got {type(item).__name__} in {_safe_repr(seq)}") from None


cdef inline double _component(object item, object seq, str what) except? -1.0:
    if PyFloat_CheckExact(item):
        return PyFloat_AS_DOUBLE(item)
    return _component_slow(item, seq, what)


# -- boundary helpers declared in vector.pxd ----------------------------------

cdef object vec2d_from_cpv(cpVect v):
    return tamias2d_pair_from_doubles(_vec2d_tp, v.x, v.y)


cdef cpVect cpv_from_object(object o) except *:
    cdef tuple t
    if PyTuple_Check(o) and PyTuple_GET_SIZE(o) == 2:
        t = <tuple>o
    elif PyList_Check(o) and PyList_GET_SIZE(o) == 2:
        return cpv(_component((<list>o)[0], o, "a vector"), _component((<list>o)[1], o, "a vector"))
    else:
        t = _seq_items(o, 2, "a vector")
    return cpv(_component(t[0], o, "a vector"), _component(t[1], o, "a vector"))


cdef cpVect cpv_from_object_finite(object o, str what) except *:
    cdef cpVect v
    try:
        v = cpv_from_object(o)
    except IllegalVector:
        raise IllegalVector(f"{what} must be a sequence of 2 numbers, got {_safe_repr(o)}") from None
    except TypeError:
        raise TypeError(f"{what} must be a sequence of 2 numbers, got {_safe_repr(o)}") from None
    if not (isfinite(v.x) and isfinite(v.y)):
        raise IllegalVector(f"{what} must be finite, got ({v.x!r}, {v.y!r})")
    return v


cdef object bb_from_cpbb(cpBB bb):
    cdef object o = tamias2d_tuple_alloc(<PyTypeObject *>_BB, 4)
    cdef object f
    f = bb.l
    Py_INCREF(f)
    PyTuple_SET_ITEM(o, 0, f)
    f = bb.b
    Py_INCREF(f)
    PyTuple_SET_ITEM(o, 1, f)
    f = bb.r
    Py_INCREF(f)
    PyTuple_SET_ITEM(o, 2, f)
    f = bb.t
    Py_INCREF(f)
    PyTuple_SET_ITEM(o, 3, f)
    return o


cdef cpBB cpbb_from_object(object o) except *:
    cdef tuple t = _seq_items(o, 4, "a bounding box")
    return cpBBNew(_component(t[0], o, "a bounding box"), _component(t[1], o, "a bounding box"),
                   _component(t[2], o, "a bounding box"), _component(t[3], o, "a bounding box"))


cdef object transform_from_cp(cpTransform t):
    return _new_tuple(_Transform, _Transform, (t.a, t.b, t.c, t.d, t.tx, t.ty))


cdef cpTransform cptransform_from_object(object o) except *:
    cdef tuple t = _seq_items(o, 6, "a transform")
    cdef str w = "a transform"
    return cpTransformNew(_component(t[0], o, w), _component(t[1], o, w), _component(t[2], o, w),
                          _component(t[3], o, w), _component(t[4], o, w), _component(t[5], o, w))


# -- Vec2d --------------------------------------------------------------------

class Vec2d(tuple):
    """An immutable 2D vector: a tuple ``(x, y)`` with vector operations.

    Items keep the type they were given (``Vec2d(1, 2)`` holds two ints), and
    the operators combine them with Python arithmetic. Any sequence of two
    numbers can stand in for the other operand.

    >>> a = Vec2d(1.5, -2)
    >>> a.x, a[1], len(a)
    (1.5, -2, 2)
    >>> a * 2, -a, a - (0.5, 1)
    (Vec2d(3.0, -4), Vec2d(-1.5, 2), Vec2d(1.0, -3))
    >>> x, y = a
    >>> {a: "tuples hash alike"}[(1.5, -2)]
    'tuples hash alike'
    """
    __slots__ = ()
    _fields = ("x", "y")
    _field_defaults = {}
    __match_args__ = ("x", "y")

    x = _tuplegetter(0, "The first (x) item. Read only.")
    y = _tuplegetter(1, "The second (y) item. Read only.")

    def __new__(cls, x, y):
        """Create a vector from its two items.

        >>> Vec2d(2, y=0.5)
        Vec2d(2, 0.5)
        """
        if cls is _Vec2d:
            return _vec(x, y)
        return _new_tuple(cls, _Vec2d, (x, y))

    # -- namedtuple protocol -----------------------------------------------------
    @classmethod
    def _make(cls, iterable):
        """Build a vector from any iterable of exactly two items.

        >>> Vec2d._make(iter([7, 8]))
        Vec2d(7, 8)
        """
        cdef tuple items = tuple(iterable)
        if len(items) != 2:
            raise TypeError(f"a Vec2d takes 2 items, got {len(items)}")
        return _new_tuple(cls, _Vec2d, items)

    def _replace(self, **changes):
        """A copy with some fields replaced by keyword.

        >>> Vec2d(1, 2)._replace(y=5)
        Vec2d(1, 5)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        x = changes.pop("x", t[0])
        y = changes.pop("y", t[1])
        if changes:
            raise ValueError(f"no such field(s): {list(changes)!r}")
        return _new_tuple(type(self), _Vec2d, (x, y))

    def _asdict(self):
        """The fields as a dict.

        >>> Vec2d(1, 2)._asdict()
        {'x': 1, 'y': 2}
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return {"x": t[0], "y": t[1]}

    def __getnewargs__(self):
        """The arguments that rebuild the vector (used by pickle and copy).

        >>> import pickle
        >>> pickle.loads(pickle.dumps(Vec2d(0.25, 3)))
        Vec2d(0.25, 3)
        """
        return tuple(self)

    def __repr__(self):
        """``Vec2d(x, y)`` with the items written by ``str``.

        >>> Vec2d(0.5, 10)
        Vec2d(0.5, 10)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return "Vec2d(%s, %s)" % (t[0], t[1])

    # -- operators ---------------------------------------------------------------
    def __add__(self, other):
        """Item-wise sum with another vector or 2-sequence.

        >>> Vec2d(1, 2) + Vec2d(0.5, 0.5)
        Vec2d(1.5, 2.5)
        >>> Vec2d(1, 2) + [10, 20]
        Vec2d(11, 22)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _vec(_add(t[0], o[0]), _add(t[1], o[1]))

    def __radd__(self, other):
        """Sum with a 2-sequence on the left.

        >>> (10, 20) + Vec2d(1, 2)
        Vec2d(11, 22)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        # pymunk adds in the order self + other here too.
        return _vec(_add(t[0], o[0]), _add(t[1], o[1]))

    def __sub__(self, other):
        """Item-wise difference with another vector or 2-sequence.

        >>> Vec2d(5, 5) - (1, 2)
        Vec2d(4, 3)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _vec(_sub(t[0], o[0]), _sub(t[1], o[1]))

    def __rsub__(self, other):
        """Difference with a 2-sequence on the left.

        >>> (5, 5) - Vec2d(1, 2)
        Vec2d(4, 3)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _vec(_sub(o[0], t[0]), _sub(o[1], t[1]))

    def __mul__(self, other):
        """Scale by a real number.

        >>> Vec2d(1, -2) * 3
        Vec2d(3, -6)
        >>> Vec2d(1, 2) * (1, 2)
        Traceback (most recent call last):
        ...
        TypeError: a Vec2d can only be scaled by a real number, not tuple
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        _check_real(other)
        return _vec(_mul(t[0], other), _mul(t[1], other))

    def __rmul__(self, other):
        """Scale by a real number on the left.

        >>> 0.5 * Vec2d(4, 1)
        Vec2d(2.0, 0.5)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        _check_real(other)
        # pymunk multiplies in the order self * other here too.
        return _vec(_mul(t[0], other), _mul(t[1], other))

    def __floordiv__(self, other):
        """Floor division of both items by a real number.

        >>> Vec2d(7, -7) // 2
        Vec2d(3, -4)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        _check_real(other)
        return _vec(_fdiv(t[0], other), _fdiv(t[1], other))

    def __truediv__(self, other):
        """Division of both items by a real number.

        >>> Vec2d(3, 1) / 2
        Vec2d(1.5, 0.5)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        _check_real(other)
        return _vec(_div(t[0], other), _div(t[1], other))

    def __neg__(self):
        """Both items negated.

        >>> -Vec2d(2, -0.5)
        Vec2d(-2, 0.5)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _vec(_neg(t[0]), _neg(t[1]))

    def __pos__(self):
        """Unary plus applied to both items.

        >>> +Vec2d(2, -0.5)
        Vec2d(2, -0.5)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _vec(_pos(t[0]), _pos(t[1]))

    def __abs__(self):
        """The length of the vector.

        >>> abs(Vec2d(-6, 8))
        10.0
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _sqrt(_len_sq(t))

    def __bool__(self):
        """False only for the zero vector.

        >>> bool(Vec2d(0, 0)), bool(Vec2d(0, 0.1))
        (False, True)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return bool(t[0] != 0 or t[1] != 0)

    # -- length and angle --------------------------------------------------------
    @property
    def length_squared(self):
        """The squared length, ``x**2 + y**2`` (cheaper than ``length``).

        >>> Vec2d(2, 3).length_squared
        13
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _len_sq(t)

    def get_length_sqrd(self):
        """Deprecated spelling of :attr:`length_squared`.

        >>> import warnings
        >>> with warnings.catch_warnings():
        ...     warnings.simplefilter("ignore")
        ...     Vec2d(2, 3).get_length_sqrd()
        13
        """
        # stacklevel 1: a compiled method has no frame of its own, so level 1
        # already names the caller's line.
        _warnings.warn("get_length_sqrd() is deprecated: read the length_squared property",
                       DeprecationWarning, stacklevel=1)
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _len_sq(t)

    @property
    def length(self):
        """The Euclidean length.

        >>> Vec2d(5, 12).length
        13.0
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _sqrt(_len_sq(t))

    def scale_to_length(self, length):
        """A copy pointing the same way with the given length; a zero vector
        raises ZeroDivisionError.

        >>> Vec2d(0, 3).scale_to_length(2)
        Vec2d(0.0, 2.0)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        old = _sqrt(_len_sq(t))
        return _vec(_div(_mul(t[0], length), old), _div(_mul(t[1], length), old))

    def rotated(self, angle_radians):
        """A copy rotated counter-clockwise by ``angle_radians``.

        >>> v = Vec2d(1, 0).rotated(math.pi / 2)
        >>> round(v.x, 12), round(v.y, 12)
        (0.0, 1.0)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        c = _cos(angle_radians)
        s = _sin(angle_radians)
        return _vec(_sub(_mul(t[0], c), _mul(t[1], s)), _add(_mul(t[0], s), _mul(t[1], c)))

    def rotated_degrees(self, angle_degrees):
        """A copy rotated counter-clockwise by ``angle_degrees``.

        >>> Vec2d(0, 2).rotated_degrees(180).int_tuple
        (0, -2)
        """
        return self.rotated(_radians(angle_degrees))

    @property
    def angle(self):
        """The angle from the positive x axis in radians, ``atan2(y, x)``.

        >>> Vec2d(0, 5).angle == math.pi / 2
        True
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _atan2(t[1], t[0])

    @property
    def angle_degrees(self):
        """The angle from the positive x axis in degrees.

        >>> Vec2d(-1, 0).angle_degrees
        180.0
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _degrees(_atan2(t[1], t[0]))

    def get_angle_between(self, other):
        """The signed angle in radians from this vector to ``other``.

        >>> Vec2d(1, 0).get_angle_between((0, -1)) == -math.pi / 2
        True
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        cross = _sub(_mul(t[0], o[1]), _mul(t[1], o[0]))
        dot = _add(_mul(t[0], o[0]), _mul(t[1], o[1]))
        return _atan2(cross, dot)

    def get_angle_degrees_between(self, other):
        """The signed angle in degrees from this vector to ``other``.

        >>> Vec2d(2, 0).get_angle_degrees_between(Vec2d(0, 3))
        90.0
        """
        return _degrees(self.get_angle_between(other))

    def normalized(self):
        """A unit vector in the same direction; the zero vector gives
        ``Vec2d(0.0, 0.0)``.

        >>> Vec2d(0, -4).normalized()
        Vec2d(0.0, -1.0)
        >>> Vec2d(0, 0).normalized()
        Vec2d(0.0, 0.0)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        length = _sqrt(_len_sq(t))
        if length != 0:
            return _vec(_div(t[0], length), _div(t[1], length))
        return _vec(0.0, 0.0)

    def normalized_and_length(self):
        """The unit vector and the length it was scaled by.

        >>> Vec2d(0, 10).normalized_and_length()
        (Vec2d(0.0, 1.0), 10.0)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        length = _sqrt(_len_sq(t))
        if length != 0:
            return _vec(_div(t[0], length), _div(t[1], length)), length
        return _vec(0.0, 0.0), 0.0

    def perpendicular(self):
        """The vector turned 90 degrees counter-clockwise, ``(-y, x)``.

        >>> Vec2d(3, 1).perpendicular()
        Vec2d(-1, 3)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _vec(_neg(t[1]), t[0])

    def perpendicular_normal(self):
        """The unit vector 90 degrees counter-clockwise; the zero vector is
        returned unchanged.

        >>> Vec2d(0, 5).perpendicular_normal()
        Vec2d(-1.0, 0.0)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        length = _sqrt(_len_sq(t))
        if length != 0:
            return _vec(_div(_neg(t[1]), length), _div(t[0], length))
        return _vec(t[0], t[1])

    # -- products and distances --------------------------------------------------
    def dot(self, other):
        """The dot product ``x*ox + y*oy`` as a float.

        >>> Vec2d(2, 3).dot((4, -1))
        5.0
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return float(_add(_mul(t[0], o[0]), _mul(t[1], o[1])))

    def cross(self, other):
        """The z component of the 3D cross product, ``x*oy - y*ox``.

        >>> Vec2d(2, 3).cross((4, -1))
        -14
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _sub(_mul(t[0], o[1]), _mul(t[1], o[0]))

    def get_distance(self, other):
        """The distance between the two points.

        >>> Vec2d(1, 1).get_distance((4, 5))
        5.0
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _sqrt(_add(_sq(_sub(t[0], o[0])), _sq(_sub(t[1], o[1]))))

    def get_distance_squared(self, other):
        """The squared distance between the two points.

        >>> Vec2d(1, 1).get_distance_squared((4, 5))
        25
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _add(_sq(_sub(t[0], o[0])), _sq(_sub(t[1], o[1])))

    def get_dist_sqrd(self, other):
        """Deprecated spelling of :meth:`get_distance_squared`.

        >>> import warnings
        >>> with warnings.catch_warnings():
        ...     warnings.simplefilter("ignore")
        ...     Vec2d(1, 1).get_dist_sqrd((4, 5))
        25
        """
        _warnings.warn("get_dist_sqrd() is deprecated: call get_distance_squared()",
                       DeprecationWarning, stacklevel=1)
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _add(_sq(_sub(t[0], o[0])), _sq(_sub(t[1], o[1])))

    def projection(self, other):
        """The projection of this vector on the line of ``other``; a zero
        ``other`` gives ``Vec2d(0.0, 0.0)``.

        >>> Vec2d(3, 7).projection((2, 0))
        Vec2d(3.0, 0.0)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        o_len_sq = _add(_mul(o[0], o[0]), _mul(o[1], o[1]))
        if o_len_sq == 0.0:
            return _vec(0.0, 0.0)
        scale = _div(float(_add(_mul(t[0], o[0]), _mul(t[1], o[1]))), o_len_sq)
        return _vec(_mul(o[0], scale), _mul(o[1], scale))

    def interpolate_to(self, other, range):
        """The point a fraction ``range`` of the way from here to ``other``.

        >>> Vec2d(0, 10).interpolate_to((10, 0), 0.25)
        Vec2d(2.5, 7.5)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _vec(_add(t[0], _mul(_sub(o[0], t[0]), range)),
                    _add(t[1], _mul(_sub(o[1], t[1]), range)))

    def convert_to_basis(self, x_vector, y_vector):
        """Coordinates in the basis ``(x_vector, y_vector)``, each found by
        projection on one basis vector.

        >>> Vec2d(6, 3).convert_to_basis((2, 0), (0, 3))
        Vec2d(3.0, 1.0)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple xv = _pair(x_vector)
        cdef tuple yv = _pair(y_vector)
        x = _div(float(_add(_mul(t[0], xv[0]), _mul(t[1], xv[1]))), _len_sq(xv))
        y = _div(float(_add(_mul(t[0], yv[0]), _mul(t[1], yv[1]))), _len_sq(yv))
        return _vec(x, y)

    @property
    def int_tuple(self):
        """Both items rounded to the nearest int, as a plain tuple.

        >>> Vec2d(2.6, -0.4).int_tuple
        (3, 0)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return round(t[0]), round(t[1])

    @property
    def polar_tuple(self):
        """``(length, angle)``: the inverse of :meth:`from_polar`.

        >>> Vec2d(0, 2).polar_tuple == (2.0, math.pi / 2)
        True
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        return _sqrt(_len_sq(t)), _atan2(t[1], t[0])

    # -- constructors ------------------------------------------------------------
    @staticmethod
    def zero():
        """``Vec2d(0.0, 0.0)``.

        >>> Vec2d.zero()
        Vec2d(0.0, 0.0)
        """
        return _vec(0.0, 0.0)

    @staticmethod
    def unit():
        """The unit vector along +y, ``Vec2d(0.0, 1.0)``.

        >>> Vec2d.unit()
        Vec2d(0.0, 1.0)
        """
        return _vec(0.0, 1.0)

    @staticmethod
    def ones():
        """``Vec2d(1.0, 1.0)``.

        >>> Vec2d.ones()
        Vec2d(1.0, 1.0)
        """
        return _vec(1.0, 1.0)

    @staticmethod
    def from_polar(length, angle):
        """The vector of the given length at ``angle`` radians from +x.

        >>> Vec2d.from_polar(3, 0)
        Vec2d(3.0, 0.0)
        """
        return _vec(_mul(_cos(angle), length), _mul(_sin(angle), length))

    # -- complex-number style rotation (Chipmunk's cpvrotate / cpvunrotate) --------
    def cpvrotate(self, other):
        """Complex product: rotate (and scale) by ``other``.

        >>> Vec2d(2, 1).cpvrotate((0, 1))
        Vec2d(-1, 2)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _vec(_sub(_mul(t[0], o[0]), _mul(t[1], o[1])), _add(_mul(t[0], o[1]), _mul(t[1], o[0])))

    def cpvunrotate(self, other):
        """Product with the conjugate of ``other``: undoes :meth:`cpvrotate`.

        >>> Vec2d(-1, 2).cpvunrotate((0, 1))
        Vec2d(2, 1)
        """
        cdef tuple t = _self_items(self, 2, "Vec2d")
        cdef tuple o = _pair(other)
        return _vec(_add(_mul(t[0], o[0]), _mul(t[1], o[1])), _sub(_mul(t[1], o[0]), _mul(t[0], o[1])))


# -- BB -----------------------------------------------------------------------

class BB(tuple):
    """An axis-aligned bounding box ``(left, bottom, right, top)``.

    Fields not given default to 0. The queries run the engine's own box
    functions on doubles, so they answer exactly as the broad phase does.

    >>> box = BB(0, 0, 10, 4)
    >>> box
    BB(left=0, bottom=0, right=10, top=4)
    >>> box.area(), box.contains_vect((10, 2)), box.top
    (40.0, True, 4)
    >>> BB(right=2, top=1)
    BB(left=0, bottom=0, right=2, top=1)
    """
    __slots__ = ()
    _fields = ("left", "bottom", "right", "top")
    _field_defaults = {"left": 0, "bottom": 0, "right": 0, "top": 0}
    __match_args__ = ("left", "bottom", "right", "top")

    left = _tuplegetter(0, "Smallest x. Read only.")
    bottom = _tuplegetter(1, "Smallest y. Read only.")
    right = _tuplegetter(2, "Largest x. Read only.")
    top = _tuplegetter(3, "Largest y. Read only.")

    def __new__(cls, left=0, bottom=0, right=0, top=0):
        """Create a box from its four sides.

        >>> BB(-1, -2, 1, 2).right
        1
        """
        return _new_tuple(cls, _BB, (left, bottom, right, top))

    @classmethod
    def _make(cls, iterable):
        """Build a box from any iterable of exactly four items.

        >>> BB._make(range(4))
        BB(left=0, bottom=1, right=2, top=3)
        """
        cdef tuple items = tuple(iterable)
        if len(items) != 4:
            raise TypeError(f"a BB takes 4 items, got {len(items)}")
        return _new_tuple(cls, _BB, items)

    def _replace(self, **changes):
        """A copy with some sides replaced by keyword.

        >>> BB(0, 0, 1, 1)._replace(top=3)
        BB(left=0, bottom=0, right=1, top=3)
        """
        cdef tuple t = _self_items(self, 4, "BB")
        items = tuple([changes.pop(name, t[i]) for i, name in enumerate(BB._fields)])
        if changes:
            raise ValueError(f"no such field(s): {list(changes)!r}")
        return _new_tuple(type(self), _BB, items)

    def _asdict(self):
        """The fields as a dict.

        >>> BB(1, 2, 3, 4)._asdict()
        {'left': 1, 'bottom': 2, 'right': 3, 'top': 4}
        """
        cdef tuple t = _self_items(self, 4, "BB")
        return dict(zip(BB._fields, t))

    def __getnewargs__(self):
        """The arguments that rebuild the box (used by pickle and copy).

        >>> import copy
        >>> copy.copy(BB(1, 2, 3, 4))
        BB(left=1, bottom=2, right=3, top=4)
        """
        return tuple(self)

    def __repr__(self):
        """``BB(left=..., bottom=..., right=..., top=...)``.

        >>> BB(0.5, 0, 1, 2)
        BB(left=0.5, bottom=0, right=1, top=2)
        """
        cdef tuple t = _self_items(self, 4, "BB")
        return "%s(left=%r, bottom=%r, right=%r, top=%r)" % (
            type(self).__name__, t[0], t[1], t[2], t[3])

    @staticmethod
    def newForCircle(p, r):
        """The smallest box around a circle of radius ``r`` centred at ``p``.

        >>> BB.newForCircle((1, 1), 2)
        BB(left=-1.0, bottom=-1.0, right=3.0, top=3.0)
        """
        return bb_from_cpbb(cpBBNewForCircle(cpv_from_object(p), r))

    def intersects(self, other):
        """True if the two boxes overlap; touching edges count.

        >>> BB(0, 0, 1, 1).intersects(BB(1, 1, 2, 2))
        True
        """
        return bool(cpBBIntersects(cpbb_from_object(self), cpbb_from_object(other)))

    def intersects_segment(self, a, b):
        """True if the segment from ``a`` to ``b`` touches the box.

        >>> BB(0, 0, 1, 1).intersects_segment((-1, 0.5), (2, 0.5))
        True
        """
        return bool(cpBBIntersectsSegment(cpbb_from_object(self), cpv_from_object(a),
                                          cpv_from_object(b)))

    def contains(self, other):
        """True if ``other`` lies completely inside this box (edges included).

        >>> BB(0, 0, 4, 4).contains(BB(1, 1, 4, 2))
        True
        """
        return bool(cpBBContainsBB(cpbb_from_object(self), cpbb_from_object(other)))

    def contains_vect(self, v):
        """True if the point ``v`` is inside the box (edges included).

        >>> BB(0, 0, 4, 4).contains_vect((4, 5))
        False
        """
        return bool(cpBBContainsVect(cpbb_from_object(self), cpv_from_object(v)))

    def merge(self, other):
        """The smallest box holding both boxes.

        >>> BB(0, 0, 1, 1).merge(BB(2, -1, 3, 0))
        BB(left=0.0, bottom=-1.0, right=3.0, top=1.0)
        """
        return bb_from_cpbb(cpBBMerge(cpbb_from_object(self), cpbb_from_object(other)))

    def expand(self, v):
        """The smallest box holding this box and the point ``v``.

        >>> BB(0, 0, 1, 1).expand((3, 0.5))
        BB(left=0.0, bottom=0.0, right=3.0, top=1.0)
        """
        return bb_from_cpbb(cpBBExpand(cpbb_from_object(self), cpv_from_object(v)))

    def center(self):
        """The centre point.

        >>> BB(0, 0, 3, 1).center()
        Vec2d(1.5, 0.5)
        """
        return vec2d_from_cpv(cpBBCenter(cpbb_from_object(self)))

    def area(self):
        """Width times height.

        >>> BB(0, 0, 3, 1.5).area()
        4.5
        """
        return cpBBArea(cpbb_from_object(self))

    def merged_area(self, other):
        """The area of :meth:`merge` without building the merged box.

        >>> BB(0, 0, 1, 1).merged_area(BB(2, 0, 3, 1))
        3.0
        """
        return cpBBMergedArea(cpbb_from_object(self), cpbb_from_object(other))

    def segment_query(self, a, b):
        """The fraction of the way from ``a`` to ``b`` where the segment enters
        the box (0 if it starts inside), or ``inf`` if it misses.

        >>> BB(2, -1, 3, 1).segment_query((0, 0), (4, 0))
        0.5
        >>> BB(2, -1, 3, 1).segment_query((0, 5), (4, 5))
        inf
        """
        return cpBBSegmentQuery(cpbb_from_object(self), cpv_from_object(a), cpv_from_object(b))

    def clamp_vect(self, v):
        """The point of the box nearest to ``v`` (``v`` itself if inside).

        >>> BB(0, 0, 2, 2).clamp_vect((5, -1))
        Vec2d(2.0, 0.0)
        """
        return vec2d_from_cpv(cpBBClampVect(cpbb_from_object(self), cpv_from_object(v)))


# -- Transform ----------------------------------------------------------------

class Transform(tuple):
    """A 2D affine transform ``(a, b, c, d, tx, ty)``: the matrix
    ``[[a, c, tx], [b, d, ty], [0, 0, 1]]``.

    Fields not given take the identity's values. ``@`` applies the transform
    to a point or composes it with another transform (right operand first).

    >>> t = Transform(tx=2, ty=1)
    >>> t
    Transform(a=1, b=0, c=0, d=1, tx=2, ty=1)
    >>> t @ (1, 1)
    Vec2d(3, 2)
    >>> (Transform.scaling(3) @ t) @ (0, 0)
    Vec2d(6, 3)
    """
    __slots__ = ()
    _fields = ("a", "b", "c", "d", "tx", "ty")
    _field_defaults = {"a": 1, "b": 0, "c": 0, "d": 1, "tx": 0, "ty": 0}
    __match_args__ = ("a", "b", "c", "d", "tx", "ty")

    a = _tuplegetter(0, "Row 1, column 1 of the matrix. Read only.")
    b = _tuplegetter(1, "Row 2, column 1 of the matrix. Read only.")
    c = _tuplegetter(2, "Row 1, column 2 of the matrix. Read only.")
    d = _tuplegetter(3, "Row 2, column 2 of the matrix. Read only.")
    tx = _tuplegetter(4, "Translation along x. Read only.")
    ty = _tuplegetter(5, "Translation along y. Read only.")

    def __new__(cls, a=1, b=0, c=0, d=1, tx=0, ty=0):
        """Create a transform from its six entries.

        >>> Transform(2, 0, 0, 2).d
        2
        """
        return _new_tuple(cls, _Transform, (a, b, c, d, tx, ty))

    @classmethod
    def _make(cls, iterable):
        """Build a transform from any iterable of exactly six items.

        >>> Transform._make([1, 0, 0, 1, 5, 6]).tx
        5
        """
        cdef tuple items = tuple(iterable)
        if len(items) != 6:
            raise TypeError(f"a Transform takes 6 items, got {len(items)}")
        return _new_tuple(cls, _Transform, items)

    def _replace(self, **changes):
        """A copy with some entries replaced by keyword.

        >>> Transform()._replace(tx=9)
        Transform(a=1, b=0, c=0, d=1, tx=9, ty=0)
        """
        cdef tuple t = _self_items(self, 6, "Transform")
        items = tuple([changes.pop(name, t[i]) for i, name in enumerate(Transform._fields)])
        if changes:
            raise ValueError(f"no such field(s): {list(changes)!r}")
        return _new_tuple(type(self), _Transform, items)

    def _asdict(self):
        """The entries as a dict.

        >>> Transform()._asdict()["d"]
        1
        """
        cdef tuple t = _self_items(self, 6, "Transform")
        return dict(zip(Transform._fields, t))

    def __getnewargs__(self):
        """The arguments that rebuild the transform (used by pickle and copy).

        >>> import pickle
        >>> pickle.loads(pickle.dumps(Transform(ty=3)))
        Transform(a=1, b=0, c=0, d=1, tx=0, ty=3)
        """
        return tuple(self)

    def __repr__(self):
        """``Transform(a=..., b=..., c=..., d=..., tx=..., ty=...)``.

        >>> Transform(0.5)
        Transform(a=0.5, b=0, c=0, d=1, tx=0, ty=0)
        """
        cdef tuple t = _self_items(self, 6, "Transform")
        return "%s(a=%r, b=%r, c=%r, d=%r, tx=%r, ty=%r)" % (
            type(self).__name__, t[0], t[1], t[2], t[3], t[4], t[5])

    def __matmul__(self, other):
        """``T @ p`` maps the point ``p`` (any 2-sequence) to a Vec2d;
        ``T @ U`` (any 6-sequence) is the transform that applies U, then T.

        >>> Transform.scaling(2) @ Vec2d(1, -1)
        Vec2d(2, -2)
        >>> Transform.translation(1, 0) @ Transform.scaling(2)
        Transform(a=2, b=0, c=0, d=2, tx=1, ty=0)
        """
        cdef tuple t = _self_items(self, 6, "Transform")
        cdef Py_ssize_t n
        try:
            n = len(other)
        except TypeError:
            raise TypeError(
                f"a Transform applies to a 2-sequence or a 6-sequence, not {type(other).__name__}"
            ) from None
        sa, sb, sc, sd, stx, sty = t
        if n == 2:
            x, y = other
            return _vec(_add(_add(_mul(sa, x), _mul(sc, y)), stx),
                        _add(_add(_mul(sb, x), _mul(sd, y)), sty))
        if n == 6:
            a, b, c, d, tx, ty = other
            # The "* 0" and "* 1" terms are kept: with inf or NaN entries they
            # change the result, and pymunk has them.
            return _new_tuple(_Transform, _Transform, (
                _add(_add(_mul(sa, a), _mul(sc, b)), _mul(stx, 0)),
                _add(_add(_mul(sb, a), _mul(sd, b)), _mul(sty, 0)),
                _add(_add(_mul(sa, c), _mul(sc, d)), _mul(stx, 0)),
                _add(_add(_mul(sb, c), _mul(sd, d)), _mul(sty, 0)),
                _add(_add(_mul(sa, tx), _mul(sc, ty)), _mul(stx, 1)),
                _add(_add(_mul(sb, tx), _mul(sd, ty)), _mul(sty, 1)),
            ))
        raise IllegalVector(
            f"a Transform applies to a 2-sequence or a 6-sequence, got {n} items: {_safe_repr(other)}")

    @staticmethod
    def identity():
        """The transform that changes nothing.

        >>> Transform.identity() @ (4, 5)
        Vec2d(4, 5)
        """
        return _new_tuple(_Transform, _Transform, (1, 0, 0, 1, 0, 0))

    def translated(self, x, y):
        """This transform applied after a translation by ``(x, y)``.

        >>> Transform.scaling(10).translated(1, 2)
        Transform(a=10, b=0, c=0, d=10, tx=10, ty=20)
        """
        return self @ Transform.translation(x, y)

    def scaled(self, s):
        """This transform applied after a uniform scaling by ``s``.

        >>> Transform.translation(1, 2).scaled(10)
        Transform(a=10, b=0, c=0, d=10, tx=1, ty=2)
        """
        return self @ Transform.scaling(s)

    def rotated(self, t):
        """This transform applied after a rotation by ``t`` radians.

        >>> t = Transform.rotation(math.pi / 2).rotated(math.pi / 2)
        >>> round(t.a, 12), round(t.b, 12)
        (-1.0, 0.0)
        """
        return self @ Transform.rotation(t)

    def inverted(self):
        """The inverse transform; a singular one raises ValueError.

        >>> Transform(2, 0, 0, 4, 1, 1).inverted()
        Transform(a=0.5, b=0.0, c=0.0, d=0.25, tx=-0.5, ty=-0.25)
        >>> Transform(1, 1, 1, 1).inverted()
        Traceback (most recent call last):
        ...
        ValueError: the transform is singular (determinant 0) and has no inverse
        """
        cdef tuple t = _self_items(self, 6, "Transform")
        a, b, c, d, tx, ty = t
        det = _sub(_mul(a, d), _mul(b, c))
        if det == 0:
            raise ValueError("the transform is singular (determinant 0) and has no inverse")
        return _new_tuple(_Transform, _Transform, (
            _div(d, det),
            _div(_neg(b), det),
            _div(_neg(c), det),
            _div(a, det),
            _div(_sub(_mul(c, ty), _mul(d, tx)), det),
            _div(_sub(_mul(b, tx), _mul(a, ty)), det),
        ))

    @staticmethod
    def translation(x, y):
        """A pure translation by ``(x, y)``.

        >>> Transform.translation(3, -1)
        Transform(a=1, b=0, c=0, d=1, tx=3, ty=-1)
        """
        return _new_tuple(_Transform, _Transform, (1, 0, 0, 1, x, y))

    @staticmethod
    def scaling(s):
        """A uniform scaling by ``s``.

        >>> Transform.scaling(0.5)
        Transform(a=0.5, b=0, c=0, d=0.5, tx=0, ty=0)
        """
        return _new_tuple(_Transform, _Transform, (s, 0, 0, s, 0, 0))

    @staticmethod
    def rotation(t):
        """A counter-clockwise rotation by ``t`` radians.

        >>> Transform.rotation(0)
        Transform(a=1.0, b=0.0, c=-0.0, d=1.0, tx=0, ty=0)
        """
        c = _cos(t)
        s = _sin(t)
        return _new_tuple(_Transform, _Transform, (c, s, _neg(s), c, 0, 0))


_Vec2d = Vec2d
_vec2d_tp = <PyTypeObject *>Vec2d
_BB = BB
_Transform = Transform
