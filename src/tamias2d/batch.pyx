# Batch access to the bodies and arbiters of a space as NumPy arrays, and
# pymunk's batch API (pymunk.batch: flag enums and buffers that the caller
# wraps in NumPy) beside it, sharing the per-body C loops.
#
# NumPy is imported on first use, never at module import, so the engine runs
# without it. The loops are C loops over the Python dicts of the space
# (PyDict_Next hands out borrowed pointers, no Python object is made per body)
# and over the C arrays of the space.
"""Read and write the state of every body of a space, and read the contacts
of the last step, as NumPy arrays in one call each.

Bodies come in the order of ``space.bodies`` (the order they were added; the
space's own ``static_body`` is not part of it). A field is one of
``"position"`` (2 columns: x, y), ``"angle"`` (1), ``"velocity"`` (2),
``"angular_velocity"`` (1), ``"force"`` (2) and ``"torque"`` (1); the columns
of several fields follow each other in the order the fields are given.

>>> import tamias2d, tamias2d.batch
>>> space = tamias2d.Space()
>>> for i in range(3):
...     body = tamias2d.Body(1, 10)
...     body.position = i, 2 * i
...     space.add(body, tamias2d.Circle(body, 0.5))
>>> tamias2d.batch.get_bodies(space, ("position", "angle"))
array([[0., 0., 0.],
       [1., 2., 0.],
       [2., 4., 0.]])
>>> tamias2d.batch.set_bodies(space, [[0, 1], [0, 2], [0, 3]], "velocity")
>>> [tuple(b.velocity) for b in space.bodies]
[(0.0, 1.0), (0.0, 2.0), (0.0, 3.0)]

Writes go through the same C functions as the Body setters: a position moves
the body's origin (the centre of gravity follows), every write wakes a
sleeping body, and the fields are written in the order given. Values must be
finite; nothing is written when one is not.

pymunk's batch API is here as well, with pymunk 7.3's names and numbers, so
programs written for ``pymunk.batch`` run unchanged: the flags
:class:`BodyFields` and :class:`ArbiterFields` choose the fields, a
:class:`Buffer` collects C doubles and ``uintptr_t`` integers, and
:func:`get_space_bodies`, :func:`set_space_bodies` and
:func:`get_space_arbiters` append to it or read it, in Munk2D's order of the
bodies (all of them, ``space.static_body`` too once used) and of its arbiter
cache. Continuing the example above:

>>> from tamias2d.batch import Buffer, BodyFields, get_space_bodies, set_space_bodies
>>> data = Buffer()
>>> get_space_bodies(space, BodyFields.BODY_ID | BodyFields.POSITION, data)
>>> list(memoryview(data.int_buf()).cast("P")) == [b.id for b in space.bodies]
True
>>> list(memoryview(data.float_buf()).cast("d"))
[0.0, 0.0, 1.0, 2.0, 2.0, 4.0]
>>> import numpy
>>> data.set_float_buf(numpy.array([5.0, 0.0, 6.0, 0.0, 7.0, 0.0]))
>>> set_space_bodies(space, BodyFields.VELOCITY, data)
>>> [b.velocity.x for b in space.bodies]
[5.0, 6.0, 7.0]
"""
from cpython.dict cimport PyDict_Next
from cpython.pythread cimport PyThread_get_thread_ident
from cpython.object cimport PyObject
from libc.stdint cimport uintptr_t, int64_t, uint64_t
from libc.stdlib cimport malloc, calloc, realloc, free
from libc.string cimport memcpy, memset
from libc.math cimport NAN
from cpython.buffer cimport (PyObject_GetBuffer, PyBuffer_Release, PyBuffer_FillInfo,
    PyBUF_C_CONTIGUOUS, PyBUF_WRITABLE)
cimport cython

from tamias2d._structs cimport cpBody, cpShape, cpSpace, cpArbiter, cpArray, cpContactPointSet
from tamias2d.vector cimport cpVect, cpv
from tamias2d.body cimport (Body, cpBodyGetPosition, cpBodySetPosition, cpBodySetAngle,
    cpBodySetVelocity, cpBodySetAngularVelocity, cpBodySetForce, cpBodySetTorque)
from tamias2d.shape cimport Shape
from tamias2d.space cimport Space, cpSpaceEachBody
from tamias2d._containers cimport cpHashSetEach
from tamias2d._threadguard cimport tamias_wait_for_step
from tamias2d.arbiter cimport (cpArbiterGetBodies, cpArbiterGetShapes,
    cpArbiterGetContactPointSet, cpArbiterTotalImpulse, cpArbiterTotalKE,
    cpArbiterIsFirstContact, cpArbiterGetCount, cpArbiterGetNormal, cpArbiterGetPointA,
    cpArbiterGetPointB, cpArbiterGetDepth)

import enum as _enum
import sys

from tamias2d.errors import IllegalBody

__all__ = ["BODY_FIELDS", "ARBITER_FIELDS", "get_bodies", "set_bodies", "body_columns",
           "get_body_ids", "get_arbiters", "arbiter_dtype", "get_spaces_bodies",
           "set_spaces_bodies",
           # pymunk's batch API
           "BodyFields", "ArbiterFields", "Buffer", "get_space_bodies", "set_space_bodies",
           "get_space_arbiters"]

# -- body fields ---------------------------------------------------------------------

cdef enum:
    F_POSITION = 0
    F_ANGLE = 1
    F_VELOCITY = 2
    F_ANGULAR_VELOCITY = 3
    F_FORCE = 4
    F_TORQUE = 5
    MAX_FIELDS = 6

BODY_FIELDS = {"position": 2, "angle": 1, "velocity": 2,
               "angular_velocity": 1, "force": 2, "torque": 1}
"""Name -> number of columns of each body field, in a fixed order."""

_FIELD_CODES = {"position": F_POSITION, "angle": F_ANGLE, "velocity": F_VELOCITY,
                "angular_velocity": F_ANGULAR_VELOCITY, "force": F_FORCE, "torque": F_TORQUE}
_FIELD_WIDTH = (2, 1, 2, 1, 2, 1)
_FIELD_NAMES = ("position", "angle", "velocity", "angular_velocity", "force", "torque")

_numpy = None


cdef object _np():
    # NumPy on first use: the rest of tamias2d never needs it.
    global _numpy
    if _numpy is None:
        import numpy
        _numpy = numpy
    return _numpy


cdef int _code_array(tuple codes, int *code) except -1:
    # The parsed field codes as the C array the body loops read; their count.
    cdef int k
    for k in range(len(codes)):
        code[k] = codes[k]
    return len(codes)


cdef tuple _parse_fields(object fields):
    """The field codes of `fields` (a name or a sequence of names)."""
    if isinstance(fields, str):
        fields = (fields,)
    try:
        names = tuple(fields)
    except TypeError:
        raise TypeError(f"fields must be a field name or a sequence of names, not {fields!r}") from None
    if not names:
        raise ValueError("fields is empty: name at least one of " + ", ".join(BODY_FIELDS))
    codes = []
    for name in names:
        code = _FIELD_CODES.get(name) if isinstance(name, str) else None
        if code is None:
            raise ValueError(f"unknown body field {name!r}; the fields are " + ", ".join(BODY_FIELDS))
        if code in codes:
            raise ValueError(f"body field {name!r} is named twice")
        codes.append(code)
    return tuple(codes)


cdef int _width(tuple codes):
    cdef int w = 0
    for c in codes:
        w += <int>_FIELD_WIDTH[c]
    return w


cdef Space _space_arg(object space):
    if not isinstance(space, Space):
        raise TypeError(f"space must be a tamias2d.Space, not {type(space).__name__}")
    return <Space>space


# The C loops of one body, shared by get_bodies/set_bodies and pymunk's
# get_space_bodies/set_space_bodies: the fields code[0..ncodes) in that order,
# to or from consecutive doubles. They return the number of doubles used.

cdef int _read_body(const cpBody *body, const int *code, int ncodes, double *out) noexcept nogil:
    cdef int k, col = 0
    cdef cpVect p
    for k in range(ncodes):
        if code[k] == F_POSITION:
            p = cpBodyGetPosition(body)
            out[col] = p.x
            out[col + 1] = p.y
            col += 2
        elif code[k] == F_ANGLE:
            out[col] = body.a
            col += 1
        elif code[k] == F_VELOCITY:
            out[col] = body.v.x
            out[col + 1] = body.v.y
            col += 2
        elif code[k] == F_ANGULAR_VELOCITY:
            out[col] = body.w
            col += 1
        elif code[k] == F_FORCE:
            out[col] = body.f.x
            out[col + 1] = body.f.y
            col += 2
        else:
            out[col] = body.t
            col += 1
    return col


cdef int _write_body(cpBody *body, const int *code, int ncodes, const double *src) noexcept nogil:
    # Through the C functions of the Body setters (they wake the body).
    cdef int k, col = 0
    for k in range(ncodes):
        if code[k] == F_POSITION:
            cpBodySetPosition(body, cpv(src[col], src[col + 1]))
            col += 2
        elif code[k] == F_ANGLE:
            cpBodySetAngle(body, src[col])
            col += 1
        elif code[k] == F_VELOCITY:
            cpBodySetVelocity(body, cpv(src[col], src[col + 1]))
            col += 2
        elif code[k] == F_ANGULAR_VELOCITY:
            cpBodySetAngularVelocity(body, src[col])
            col += 1
        elif code[k] == F_FORCE:
            cpBodySetForce(body, cpv(src[col], src[col + 1]))
            col += 2
        else:
            cpBodySetTorque(body, src[col])
            col += 1
    return col


def body_columns(fields):
    """The column names of the array :func:`get_bodies` returns for `fields`.

    >>> import tamias2d.batch
    >>> tamias2d.batch.body_columns(("position", "angle", "velocity"))
    ['position.x', 'position.y', 'angle', 'velocity.x', 'velocity.y']
    """
    cols = []
    for c in _parse_fields(fields):
        name = _FIELD_NAMES[c]
        if _FIELD_WIDTH[c] == 2:
            cols += [name + ".x", name + ".y"]
        else:
            cols.append(name)
    return cols


def get_bodies(space, fields, out=None):
    """The fields of every body of `space` as a float64 array of shape
    (len(space.bodies), columns), one row per body in ``space.bodies`` order.

    `fields` is a field name or a sequence of them (see the module help);
    :func:`body_columns` names the columns. Pass `out` (a C-contiguous
    float64 array of the right shape) to fill it instead of a new array.

    >>> import tamias2d, tamias2d.batch
    >>> space = tamias2d.Space()
    >>> body = tamias2d.Body(2, 5)
    >>> body.velocity = 3, 4
    >>> body.angular_velocity = 0.5
    >>> space.add(body)
    >>> tamias2d.batch.get_bodies(space, ["velocity", "angular_velocity"])
    array([[3. , 4. , 0.5]])
    """
    cdef Space sp = _space_arg(space)
    tamias_wait_for_step(&sp._space)
    cdef tuple codes = _parse_fields(fields)
    cdef Py_ssize_t n = len(sp._bodies)
    cdef int width = _width(codes)
    np = _np()
    if out is None:
        out = np.empty((n, width), dtype=np.float64)
    else:
        if not isinstance(out, np.ndarray) or out.dtype != np.float64:
            raise TypeError("out must be a float64 numpy array")
        if out.shape != (n, width):
            raise ValueError(f"out has shape {out.shape}; {(n, width)} is needed")
        if not out.flags.c_contiguous or not out.flags.writeable:
            raise ValueError("out must be C-contiguous and writeable")
    if n == 0:
        return out
    cdef double[:, ::1] view = out
    cdef int code[MAX_FIELDS]
    cdef int ncodes = _code_array(codes, code)
    cdef Py_ssize_t pos = 0, row = 0
    cdef PyObject *key
    cdef PyObject *value
    tamias_wait_for_step(&sp._space)
    while PyDict_Next(sp._bodies, &pos, &key, &value):
        if row >= n:   # cannot happen while we hold the GIL; keeps the writes in bounds
            break
        _read_body(&(<Body>key)._body, code, ncodes, &view[row, 0])
        row += 1
    return out


cdef inline bint _finite(double x) noexcept nogil:
    return x - x == 0.0


def set_bodies(space, values, fields):
    """Write the fields of every body of `space` from `values`, an array of
    shape (len(space.bodies), columns) in ``space.bodies`` order (shape (n,)
    is accepted for a single one-column field such as ``"angle"``).

    Each value goes through the C function of its Body setter, so the result
    is exactly that of ``body.position = ...`` etc. in the order the fields
    are given: bodies wake up, positions place the origin. Values must be
    finite (IllegalBody otherwise) and nothing is written if one is not.

    >>> import tamias2d, tamias2d.batch
    >>> space = tamias2d.Space()
    >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    >>> space.add(a, b)
    >>> tamias2d.batch.set_bodies(space, [0.5, -0.5], "angle")
    >>> a.angle, b.angle
    (0.5, -0.5)
    >>> tamias2d.batch.set_bodies(space, [[1, 2, 0], [3, 4, 0]], ("position", "torque"))
    >>> b.position
    Vec2d(3.0, 4.0)
    """
    cdef Space sp = _space_arg(space)
    tamias_wait_for_step(&sp._space)
    cdef tuple codes = _parse_fields(fields)
    cdef Py_ssize_t n = len(sp._bodies)
    cdef int width = _width(codes)
    np = _np()
    arr = np.asarray(values)
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"values must be numbers, not an array of dtype {arr.dtype}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if arr.ndim == 1 and width == 1:
        arr = arr.reshape((arr.shape[0], 1))
    if arr.shape != (n, width):
        raise ValueError(f"values have shape {arr.shape}; fields {[_FIELD_NAMES[c] for c in codes]} "
                         f"of {n} bodies need {(n, width)}")
    if n == 0:
        return
    cdef const double[:, ::1] view = arr
    cdef Py_ssize_t i, j
    for i in range(n):
        for j in range(width):
            if not _finite(view[i, j]):
                names = body_columns([_FIELD_NAMES[c] for c in codes])
                raise IllegalBody(f"values[{i}, {j}] ({names[j]} of body {i}) must be finite, "
                                  f"got {view[i, j]!r}; no body was changed")
    cdef int code[MAX_FIELDS]
    cdef int ncodes = _code_array(codes, code)
    cdef Py_ssize_t pos = 0, row = 0
    cdef PyObject *key
    cdef PyObject *value
    tamias_wait_for_step(&sp._space)
    while PyDict_Next(sp._bodies, &pos, &key, &value):
        if row >= n:
            break
        _write_body(&(<Body>key)._body, code, ncodes, &view[row, 0])
        row += 1


def get_body_ids(space):
    """The ``Body.id`` of every body of `space`, in ``space.bodies`` order,
    as an unsigned integer array.

    >>> import tamias2d, tamias2d.batch
    >>> space = tamias2d.Space()
    >>> body = tamias2d.Body(1, 1)
    >>> space.add(body)
    >>> tamias2d.batch.get_body_ids(space).tolist() == [body.id]
    True
    """
    cdef Space sp = _space_arg(space)
    tamias_wait_for_step(&sp._space)
    cdef Py_ssize_t n = len(sp._bodies)
    np = _np()
    out = np.empty(n, dtype=np.uintp)
    if n == 0:
        return out
    cdef uintptr_t[::1] view = out
    cdef Py_ssize_t pos = 0, row = 0
    cdef PyObject *key
    cdef PyObject *value
    tamias_wait_for_step(&sp._space)
    while PyDict_Next(sp._bodies, &pos, &key, &value):
        if row >= n:
            break
        view[row] = <uintptr_t>(<Body>key)._body.userData
        row += 1
    return out


# -- pointer -> index tables ------------------------------------------------------------
# An open-addressing hash table from a C pointer to its position in a dict of
# the space (bodies or shapes): arbiters hold pointers, users want indices.

cdef struct PtrIndex:
    uintptr_t *keys
    int64_t *values
    uint64_t mask
    int bits


cdef inline uint64_t _slot(uintptr_t key, int bits) noexcept nogil:
    # Fibonacci hashing of the pointer (its low bits are alignment zeros).
    return ((<uint64_t>key >> 3) * <uint64_t>11400714819323198485ULL) >> (64 - bits)


cdef int _index_init(PtrIndex *table, Py_ssize_t n) except -1:
    cdef int bits = 4
    while (<uint64_t>1 << bits) < <uint64_t>(2 * n + 2):
        bits += 1
    cdef uint64_t size = <uint64_t>1 << bits
    table.bits = bits
    table.mask = size - 1
    table.keys = <uintptr_t *>malloc(size * sizeof(uintptr_t))
    table.values = <int64_t *>malloc(size * sizeof(int64_t))
    if table.keys == NULL or table.values == NULL:
        free(table.keys)
        free(table.values)
        table.keys = NULL
        table.values = NULL
        raise MemoryError()
    cdef uint64_t i
    for i in range(size):
        table.keys[i] = 0
    return 0


cdef void _index_free(PtrIndex *table) noexcept nogil:
    free(table.keys)
    free(table.values)
    table.keys = NULL
    table.values = NULL


cdef void _index_put(PtrIndex *table, uintptr_t key, int64_t value) noexcept nogil:
    cdef uint64_t i = _slot(key, table.bits)
    while table.keys[i] != 0 and table.keys[i] != key:
        i = (i + 1) & table.mask
    table.keys[i] = key
    table.values[i] = value


cdef int64_t _index_get(const PtrIndex *table, uintptr_t key) noexcept nogil:
    if key == 0:
        return -1
    cdef uint64_t i = _slot(key, table.bits)
    while table.keys[i] != 0:
        if table.keys[i] == key:
            return table.values[i]
        i = (i + 1) & table.mask
    return -1


cdef int _index_bodies(PtrIndex *table, Space sp) except -1:
    _index_init(table, len(sp._bodies))
    cdef Py_ssize_t pos = 0
    cdef int64_t row = 0
    cdef PyObject *key
    cdef PyObject *value
    tamias_wait_for_step(&sp._space)
    while PyDict_Next(sp._bodies, &pos, &key, &value):
        _index_put(table, <uintptr_t>&(<Body>key)._body, row)
        row += 1
    return 0


cdef int _index_shapes(PtrIndex *table, Space sp) except -1:
    _index_init(table, len(sp._shapes))
    cdef Py_ssize_t pos = 0
    cdef int64_t row = 0
    cdef PyObject *key
    cdef PyObject *value
    while PyDict_Next(sp._shapes, &pos, &key, &value):
        _index_put(table, <uintptr_t>(<Shape>key)._shape, row)
        row += 1
    return 0


# -- arbiters -------------------------------------------------------------------------------

cdef struct ArbiterRecord:
    int64_t body_a            # index in space.bodies, -1 if not there (static_body)
    int64_t body_b
    uintptr_t body_a_id       # Body.id
    uintptr_t body_b_id
    int64_t shape_a           # index in space.shapes
    int64_t shape_b
    int64_t count             # contact points, 1 or 2
    double normal[2]          # from shape a to shape b
    double total_impulse[2]   # as Arbiter.total_impulse
    double total_ke
    double point_a[4]         # (2, 2): contact i, x/y; NaN for a missing second point
    double point_b[4]
    double distance[2]        # negative when the shapes overlap
    unsigned char first_contact


ARBITER_FIELDS = ("body_a", "body_b", "body_a_id", "body_b_id", "shape_a", "shape_b",
                  "count", "first_contact", "normal", "total_impulse", "total_ke",
                  "point_a", "point_b", "distance")
"""The fields of the record array :func:`get_arbiters` returns."""

_arbiter_dtype = None


def arbiter_dtype():
    """The NumPy record type of :func:`get_arbiters` (the C record's layout).

    >>> import tamias2d.batch
    >>> dt = tamias2d.batch.arbiter_dtype()
    >>> dt["normal"].shape, dt["point_a"].shape
    ((2,), (2, 2))
    """
    global _arbiter_dtype
    if _arbiter_dtype is not None:
        return _arbiter_dtype
    np = _np()
    cdef ArbiterRecord r
    cdef char *base = <char *>&r
    offsets = {
        "body_a": <char *>&r.body_a - base, "body_b": <char *>&r.body_b - base,
        "body_a_id": <char *>&r.body_a_id - base, "body_b_id": <char *>&r.body_b_id - base,
        "shape_a": <char *>&r.shape_a - base, "shape_b": <char *>&r.shape_b - base,
        "count": <char *>&r.count - base, "first_contact": <char *>&r.first_contact - base,
        "normal": <char *>&r.normal[0] - base, "total_impulse": <char *>&r.total_impulse[0] - base,
        "total_ke": <char *>&r.total_ke - base, "point_a": <char *>&r.point_a[0] - base,
        "point_b": <char *>&r.point_b[0] - base, "distance": <char *>&r.distance[0] - base,
    }
    formats = {
        "body_a": np.int64, "body_b": np.int64, "body_a_id": np.uintp, "body_b_id": np.uintp,
        "shape_a": np.int64, "shape_b": np.int64, "count": np.int64, "first_contact": np.bool_,
        "normal": (np.float64, (2,)), "total_impulse": (np.float64, (2,)),
        "total_ke": np.float64, "point_a": (np.float64, (2, 2)),
        "point_b": (np.float64, (2, 2)), "distance": (np.float64, (2,)),
    }
    _arbiter_dtype = np.dtype({
        "names": list(ARBITER_FIELDS),
        "formats": [formats[f] for f in ARBITER_FIELDS],
        "offsets": [offsets[f] for f in ARBITER_FIELDS],
        "itemsize": sizeof(ArbiterRecord),
    })
    return _arbiter_dtype


def get_arbiters(space, fields=None):
    """The contact pairs the last step solved, as a NumPy record array (one
    record per arbiter, in the order the solver ran them, which is also the
    order of the ``post_solve`` callbacks).

    Record fields (see :data:`ARBITER_FIELDS`): ``body_a``/``body_b`` (index
    in ``space.bodies``, -1 for ``space.static_body``), ``body_a_id``/
    ``body_b_id`` (``Body.id``), ``shape_a``/``shape_b`` (index in
    ``space.shapes``), ``count`` (1 or 2 contact points), ``first_contact``,
    ``normal``, ``total_impulse``, ``total_ke``, ``point_a`` and ``point_b``
    (shape (2, 2): the points of contact 0 and 1) and ``distance`` (2). The
    values are those of the ``Arbiter`` properties of the same names; the
    second point and distance are NaN when there is one contact. Sleeping
    bodies' contacts are not solved, so they are not listed.

    `fields`, a sequence of field names, selects fields (a view of the full
    records); the body and shape index lookups run only when asked for.

    >>> import tamias2d, tamias2d.batch
    >>> space = tamias2d.Space()
    >>> space.gravity = 0, -10
    >>> space.add(tamias2d.Segment(space.static_body, (-10, 0), (10, 0), 1))
    >>> ball = tamias2d.Body(1, 10)
    >>> ball.position = 0, 1.9
    >>> space.add(ball, tamias2d.Circle(ball, 1))
    >>> space.step(0.01)
    >>> arbs = tamias2d.batch.get_arbiters(space)
    >>> len(arbs), int(arbs[0]["count"])
    (1, 1)
    >>> sorted([int(arbs[0]["body_a"]), int(arbs[0]["body_b"])])
    [-1, 0]
    """
    cdef Space sp = _space_arg(space)
    tamias_wait_for_step(&sp._space)
    np = _np()
    dtype = arbiter_dtype()
    if fields is not None:
        if isinstance(fields, str):
            fields = [fields]
        fields = list(fields)
        for f in fields:
            if f not in ARBITER_FIELDS:
                raise ValueError(f"unknown arbiter field {f!r}; the fields are " + ", ".join(ARBITER_FIELDS))
        if len(set(fields)) != len(fields):
            raise ValueError("an arbiter field is named twice")
    cdef bint want_bodies = fields is None or "body_a" in fields or "body_b" in fields
    cdef bint want_shapes = fields is None or "shape_a" in fields or "shape_b" in fields
    cdef cpArray *arbiters = sp._space.arbiters
    cdef Py_ssize_t m = arbiters.num if arbiters != NULL else 0
    out = np.zeros(m, dtype=dtype)
    if m == 0:
        return out if fields is None else out[fields]
    cdef unsigned char[::1] raw = out.view(np.uint8)
    cdef ArbiterRecord *rec = <ArbiterRecord *>&raw[0]
    cdef PtrIndex bodies, shapes
    bodies.keys = NULL
    bodies.values = NULL
    shapes.keys = NULL
    shapes.values = NULL
    cdef Py_ssize_t i
    cdef int j
    cdef cpArbiter *arb
    cdef cpBody *ba
    cdef cpBody *bb
    cdef cpShape *sa
    cdef cpShape *sb
    cdef cpContactPointSet cps
    cdef cpVect v
    try:
        if want_bodies:
            _index_bodies(&bodies, sp)
        if want_shapes:
            _index_shapes(&shapes, sp)
        # Python ran since m was read (the array, the indexes): if another
        # thread stepped the space meanwhile, start again.
        tamias_wait_for_step(&sp._space)
        if arbiters.num != m:
            return get_arbiters(space, fields)
        for i in range(m):
            arb = <cpArbiter *>arbiters.arr[i]
            cpArbiterGetShapes(arb, &sa, &sb)
            cpArbiterGetBodies(arb, &ba, &bb)
            rec[i].body_a = _index_get(&bodies, <uintptr_t>ba) if want_bodies else -1
            rec[i].body_b = _index_get(&bodies, <uintptr_t>bb) if want_bodies else -1
            rec[i].body_a_id = <uintptr_t>ba.userData
            rec[i].body_b_id = <uintptr_t>bb.userData
            rec[i].shape_a = _index_get(&shapes, <uintptr_t>sa) if want_shapes else -1
            rec[i].shape_b = _index_get(&shapes, <uintptr_t>sb) if want_shapes else -1
            cps = cpArbiterGetContactPointSet(arb)
            rec[i].count = cps.count
            rec[i].first_contact = cpArbiterIsFirstContact(arb)
            rec[i].normal[0] = cps.normal.x
            rec[i].normal[1] = cps.normal.y
            v = cpArbiterTotalImpulse(arb)
            rec[i].total_impulse[0] = v.x
            rec[i].total_impulse[1] = v.y
            rec[i].total_ke = cpArbiterTotalKE(arb)
            for j in range(2):
                if j < cps.count:
                    rec[i].point_a[2 * j] = cps.points[j].pointA.x
                    rec[i].point_a[2 * j + 1] = cps.points[j].pointA.y
                    rec[i].point_b[2 * j] = cps.points[j].pointB.x
                    rec[i].point_b[2 * j + 1] = cps.points[j].pointB.y
                    rec[i].distance[j] = cps.points[j].distance
                else:
                    rec[i].point_a[2 * j] = NAN
                    rec[i].point_a[2 * j + 1] = NAN
                    rec[i].point_b[2 * j] = NAN
                    rec[i].point_b[2 * j + 1] = NAN
                    rec[i].distance[j] = NAN
    finally:
        _index_free(&bodies)
        _index_free(&shapes)
    return out if fields is None else out[fields]


# -- many spaces at once (with tamias2d.step_spaces) ------------------------------------------

cdef bint _others_stepping(list spaces):
    # Whether another thread steps one of `spaces` (a callback of a step
    # itself may read its own space).
    cdef unsigned long me = PyThread_get_thread_ident()
    cdef Space sp
    for s in spaces:
        sp = <Space>s
        if sp._space.stepThread != 0 and sp._space.stepThread != me:
            return True
    return False


cdef int _wait_spaces(list spaces) except -1:
    # Waiting for one space lets the GIL go, so another may start a step
    # meanwhile: look again until no space is stepped by another thread.
    cdef Space sp
    while _others_stepping(spaces):
        for s in spaces:
            sp = <Space>s
            tamias_wait_for_step(&sp._space)
    return 0


cdef object _stack_offsets(list spaces):
    np = _np()
    cdef Py_ssize_t i, m = len(spaces)
    offsets = np.empty(m + 1, dtype=np.int64)
    cdef int64_t[::1] off = offsets
    cdef int64_t total = 0
    off[0] = 0
    for i in range(m):
        total += len((<Space>spaces[i])._bodies)
        off[i + 1] = total
    return offsets


def get_spaces_bodies(spaces, fields, out=None):
    """The bodies of every space of `spaces`, stacked: a float64 array of
    shape (total bodies, columns), the bodies of ``spaces[0]`` first (each
    space's in ``space.bodies`` order), and the row offsets, an int64 array of
    ``len(spaces) + 1`` entries: the bodies of ``spaces[i]`` are rows
    ``offsets[i]:offsets[i + 1]``. With :func:`tamias2d.step_spaces` an RL
    loop is "write actions, step all, read observations" in three calls.
    One C loop reads every body; pass `out` (a C-contiguous float64 array of
    the right shape) to fill it instead of a new array.

    >>> import tamias2d, tamias2d.batch
    >>> spaces = [tamias2d.Space() for _ in range(3)]
    >>> for i, s in enumerate(spaces):
    ...     for k in range(i + 1):
    ...         b = tamias2d.Body(1, 1)
    ...         b.position = i, k
    ...         s.add(b)
    >>> rows, offsets = tamias2d.batch.get_spaces_bodies(spaces, "position")
    >>> offsets.tolist(), rows[offsets[2]:offsets[3]].tolist()
    ([0, 1, 3, 6], [[2.0, 0.0], [2.0, 1.0], [2.0, 2.0]])
    """
    np = _np()
    cdef list items = [_space_arg(s) for s in spaces]
    cdef tuple codes = _parse_fields(fields)
    cdef int width = _width(codes)
    cdef int code[MAX_FIELDS]
    cdef int ncodes = _code_array(codes, code)
    while True:
        _wait_spaces(items)
        offsets = _stack_offsets(items)
        total = int(offsets[-1])
        if out is None:
            result = np.empty((total, width), dtype=np.float64)
        else:
            if not isinstance(out, np.ndarray) or out.dtype != np.float64:
                raise TypeError("out must be a float64 numpy array")
            if out.shape != (total, width):
                raise ValueError(f"out has shape {out.shape}; {(total, width)} is needed")
            if not out.flags.c_contiguous or not out.flags.writeable:
                raise ValueError("out must be C-contiguous and writeable")
            result = out
        if not _others_stepping(items):
            break   # and none can start: this thread keeps the GIL to the end
    if total == 0:
        return result, offsets
    cdef double[:, ::1] view = result
    cdef Py_ssize_t pos, row = 0
    cdef PyObject *key
    cdef PyObject *value
    cdef Space sp
    for s in items:
        sp = <Space>s
        pos = 0
        while PyDict_Next(sp._bodies, &pos, &key, &value):
            _read_body(&(<Body>key)._body, code, ncodes, &view[row, 0])
            row += 1
    return result, offsets


def set_spaces_bodies(spaces, values, fields):
    """Write the stacked rows of :func:`get_spaces_bodies` back: ``values``
    has one row per body of every space, in the same order (shape (n,) is
    accepted for a single one-column field). One C loop writes every body,
    through the C functions of the Body setters; every value is checked
    before any body changes.

    >>> import tamias2d, tamias2d.batch
    >>> spaces = [tamias2d.Space() for _ in range(2)]
    >>> for s in spaces:
    ...     s.add(tamias2d.Body(1, 1))
    >>> tamias2d.batch.set_spaces_bodies(spaces, [[1, 2], [3, 4]], "velocity")
    >>> [next(iter(s.bodies)).velocity for s in spaces]
    [Vec2d(1.0, 2.0), Vec2d(3.0, 4.0)]
    """
    np = _np()
    cdef list items = [_space_arg(s) for s in spaces]
    cdef tuple codes = _parse_fields(fields)
    cdef int width = _width(codes)
    cdef int code[MAX_FIELDS]
    cdef int ncodes = _code_array(codes, code)
    arr = np.asarray(values)
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"values must be numbers, not an array of dtype {arr.dtype}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if arr.ndim == 1 and width == 1:
        arr = arr.reshape((arr.shape[0], 1))
    if not np.isfinite(arr).all():
        bad = np.argwhere(~np.isfinite(arr))[0] if arr.ndim == 2 else None
        where = f"values[{bad[0]}, {bad[1]}]" if bad is not None else "values"
        raise IllegalBody(f"{where} must be finite; no body was changed")
    while True:
        _wait_spaces(items)
        total = int(_stack_offsets(items)[-1])
        if arr.shape != (total, width):
            raise ValueError(f"values have shape {arr.shape}; fields "
                             f"{[_FIELD_NAMES[c] for c in codes]} of {total} bodies need "
                             f"{(total, width)}")
        if not _others_stepping(items):
            break
    if total == 0:
        return
    cdef const double[:, ::1] view = arr
    cdef Py_ssize_t pos, row = 0
    cdef PyObject *key
    cdef PyObject *value
    cdef Space sp
    for s in items:
        sp = <Space>s
        pos = 0
        while PyDict_Next(sp._bodies, &pos, &key, &value):
            _write_body(&(<Body>key)._body, code, ncodes, &view[row, 0])
            row += 1


# -- pymunk's batch API ------------------------------------------------------------------
# pymunk.batch as pymunk 7.3 has it: flag enums name the fields, a Buffer
# holds an array of C doubles and one of uintptr_t, and the three functions
# append to them (or read the doubles) in the order Munk2D visits the space:
# cpSpaceEachBody (dynamic bodies, static bodies, then each sleeping
# component) for bodies, the cached-arbiter hash set for arbiters. pymunk's
# C iterators grow the arrays one value at a time; here the room is made
# first (the count is known) and the C loop only stores. Unlike pymunk, no
# call reads or writes outside the arrays.

class BodyFields(_enum.Flag):
    """The body fields :func:`get_space_bodies` and :func:`set_space_bodies`
    handle, combined with ``|``. For each body, the fields set are taken in
    the order of the members: BODY_ID (``Body.id``) goes to the int buffer,
    the rest to the float buffer (POSITION, VELOCITY and FORCE as x, y;
    ANGLE, ANGULAR_VELOCITY and TORQUE as one value). ALL is every field.
    """
    BODY_ID = 1
    POSITION = 2
    ANGLE = 4
    VELOCITY = 8
    ANGULAR_VELOCITY = 16
    FORCE = 32
    TORQUE = 64
    ALL = 0xFFFF


class ArbiterFields(_enum.Flag):
    """The arbiter fields :func:`get_space_arbiters` reads, combined with
    ``|``. For each arbiter, in the order of the members: to the int buffer
    BODY_A_ID and BODY_B_ID (``Body.id`` of ``arbiter.bodies``),
    IS_FIRST_CONTACT (1 or 0) and CONTACT_COUNT (0, 1 or 2); to the float
    buffer TOTAL_IMPULSE (x, y), TOTAL_KE, NORMAL (x, y), and for contact 1
    and 2 POINT_A_n (x, y), POINT_B_n (x, y) and DISTANCE_n, each 0 when the
    arbiter has no such contact. ALL is every field.
    """
    BODY_A_ID = 1
    BODY_B_ID = 2
    TOTAL_IMPULSE = 4
    TOTAL_KE = 8
    IS_FIRST_CONTACT = 16
    NORMAL = 32
    CONTACT_COUNT = 64
    POINT_A_1 = 128
    POINT_B_1 = 256
    DISTANCE_1 = 512
    POINT_A_2 = 1024
    POINT_B_2 = 2048
    DISTANCE_2 = 4096
    ALL = 0xFFFF


# The body flags after BODY_ID, in member order, and their codes above.
cdef int _BODY_FLAG_BITS[MAX_FIELDS]
_BODY_FLAG_BITS[:] = [2, 4, 8, 16, 32, 64]
cdef int _BODY_FLAG_CODES[MAX_FIELDS]
_BODY_FLAG_CODES[:] = [F_POSITION, F_ANGLE, F_VELOCITY, F_ANGULAR_VELOCITY, F_FORCE, F_TORQUE]


cdef unsigned int _flag_bits(object fields, object cls) except? 0xFFFFFFFF:
    if not isinstance(fields, cls):
        raise TypeError(f"fields must be a {cls.__name__} (e.g. {cls.__name__}.ALL), "
                        f"not {type(fields).__name__}")
    return <unsigned int>(<unsigned long>fields.value & 0xFFFF)


cdef int _body_flag_codes(unsigned int bits, int *code) noexcept:
    """The float fields of `bits` as codes, in member order; returns how many."""
    cdef int k, n = 0
    for k in range(MAX_FIELDS):
        if bits & _BODY_FLAG_BITS[k]:
            code[n] = _BODY_FLAG_CODES[k]
            n += 1
    return n


# -- the memory of a Buffer array ------------------------------------------------------------

@cython.final
@cython.auto_pickle(False)
cdef class _Memory:
    # Bytes that a Buffer array lives in: its own (malloc) or those of the
    # object given to set_float_buf/set_int_buf (a held Py_buffer, as pymunk
    # holds it). Exported as unsigned bytes; memoryviews of it keep it alive,
    # so a view handed out stays valid after the Buffer moves to new memory.
    cdef char *data
    cdef Py_ssize_t nbytes
    cdef Py_ssize_t exports
    cdef bint borrowed
    cdef bint readonly
    cdef Py_buffer src

    def __cinit__(self):
        self.data = NULL
        self.nbytes = 0
        self.exports = 0
        self.borrowed = False
        self.readonly = False

    def __dealloc__(self):
        if self.borrowed:
            PyBuffer_Release(&self.src)
        else:
            free(self.data)
        self.data = NULL

    def __getbuffer__(self, Py_buffer *view, int flags):
        PyBuffer_FillInfo(view, self, self.data, self.nbytes, self.readonly, flags)
        self.exports += 1

    def __releasebuffer__(self, Py_buffer *view):
        self.exports -= 1


cdef _Memory _memory_own(Py_ssize_t nbytes):
    cdef _Memory m = _Memory.__new__(_Memory)
    m.data = <char *>calloc(nbytes if nbytes > 0 else 1, 1)
    if m.data == NULL:
        raise MemoryError()
    m.nbytes = nbytes
    return m


cdef _Memory _memory_borrow(object obj):
    cdef _Memory m = _Memory.__new__(_Memory)
    try:
        PyObject_GetBuffer(obj, &m.src, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE)
    except (BufferError, ValueError, TypeError):   # read-only (bytes, a read-only array)
        PyObject_GetBuffer(obj, &m.src, PyBUF_C_CONTIGUOUS)
    m.borrowed = True
    m.readonly = m.src.readonly
    m.data = <char *>m.src.buf
    m.nbytes = m.src.len
    return m


# Buffer formats accepted from set_float_buf and set_int_buf: raw bytes, or
# items of the array's own C type in native order.
_BYTE_FORMATS = ("B", "b", "c")


cdef int _check_format(object buffer, str what, str letters, Py_ssize_t itemsize) except -1:
    # Raises unless `buffer` is one C-contiguous block of items of the array's
    # C type (format letters[0] or one of the same size) or of raw bytes.
    try:
        mv = memoryview(buffer)
    except TypeError:
        raise TypeError(f"{what} needs an object with the buffer protocol (a NumPy array, "
                        f"array.array, bytes, ...), not {type(buffer).__name__}") from None
    fmt = mv.format
    size = mv.itemsize
    contiguous = mv.c_contiguous
    nbytes = mv.nbytes
    mv.release()
    native = "<" if sys.byteorder == "little" else ">"
    letter = fmt[1:] if fmt[:1] in ("@", "=", native) else fmt
    if letter in _BYTE_FORMATS:
        if nbytes % itemsize:
            raise ValueError(f"{what} got {nbytes} bytes, not a whole number of "
                             f"{itemsize}-byte items")
    elif not (len(letter) == 1 and letter in letters and size == itemsize):
        raise TypeError(f"{what} needs items of format {letters[0]!r} ({itemsize} bytes) "
                        f"or raw bytes, got format {fmt!r} ({size} bytes)")
    if not contiguous:
        raise ValueError(f"{what} needs a C-contiguous buffer")
    return 0


@cython.auto_pickle(False)
cdef class Buffer:
    """Two growing arrays for the batch functions, as pymunk's
    ``pymunk.batch.Buffer``: one of C doubles (float_buf) and one of
    ``uintptr_t`` (int_buf). :func:`get_space_bodies` and
    :func:`get_space_arbiters` append to them; :meth:`clear` empties them for
    reuse, which is cheaper than a new Buffer per step.

    >>> import tamias2d.batch
    >>> data = tamias2d.batch.Buffer()
    >>> data.set_float_buf(bytes(16))
    >>> list(memoryview(data.float_buf()).cast("d"))
    [0.0, 0.0]
    >>> data.clear()
    >>> len(data.float_buf()), len(data.int_buf())
    (0, 0)
    """
    cdef _Memory _fmem
    cdef _Memory _imem
    cdef Py_ssize_t _fnum   # doubles in use
    cdef Py_ssize_t _inum   # uintptr_t in use

    def __cinit__(self, *args, **kwargs):
        if args or kwargs:
            raise TypeError("Buffer() takes no arguments")
        self._fmem = _memory_own(4 * sizeof(double))
        self._imem = _memory_own(4 * sizeof(uintptr_t))
        self._fnum = 0
        self._inum = 0

    def clear(self):
        """Empty both arrays (the memory is kept for the next calls)."""
        self._fnum = 0
        self._inum = 0
        # Memory of an object given to set_*_buf is not written to.
        if self._fmem.borrowed:
            self._fmem = _memory_own(4 * sizeof(double))
        if self._imem.borrowed:
            self._imem = _memory_own(4 * sizeof(uintptr_t))

    def float_buf(self):
        """The doubles, as a memoryview of their bytes: use
        ``memoryview(buf).cast("d")`` or ``numpy.frombuffer(buf)``. It is a
        view: it sees writes until the array next grows into new memory."""
        return memoryview(self._fmem)[:self._fnum * <Py_ssize_t>sizeof(double)]

    def set_float_buf(self, buffer):
        """Make the float array the contents of `buffer` (C doubles, or raw
        bytes holding them, in one C-contiguous block, e.g. a float64 NumPy
        array or ``ndarray.tobytes()``). The buffer is used in place, not
        copied, until a batch call appends (that copies) or :meth:`clear`.
        """
        _check_format(buffer, "set_float_buf", "d", sizeof(double))
        cdef _Memory m = _memory_borrow(buffer)
        self._fmem = m
        self._fnum = m.nbytes // <Py_ssize_t>sizeof(double)

    def int_buf(self):
        """The integers (``uintptr_t``), as a memoryview of their bytes: use
        ``memoryview(buf).cast("P")`` or ``numpy.frombuffer(buf, numpy.uintp)``."""
        return memoryview(self._imem)[:self._inum * <Py_ssize_t>sizeof(uintptr_t)]

    def set_int_buf(self, buffer):
        """Make the int array the contents of `buffer` (``uintptr_t``-sized
        integers, or raw bytes holding them, in one C-contiguous block), used
        in place as :meth:`set_float_buf` does."""
        _check_format(buffer, "set_int_buf", "PQqLlNn", sizeof(uintptr_t))
        cdef _Memory m = _memory_borrow(buffer)
        self._imem = m
        self._inum = m.nbytes // <Py_ssize_t>sizeof(uintptr_t)

    # -- for the batch functions --

    cdef bint _room(self, Py_ssize_t floats, Py_ssize_t ints) noexcept:
        # Each array that gets values is in own memory with room for them.
        return ((floats == 0 or (not self._fmem.borrowed and self._fmem.nbytes
                                 >= (self._fnum + floats) * <Py_ssize_t>sizeof(double)))
                and (ints == 0 or (not self._imem.borrowed and self._imem.nbytes
                                   >= (self._inum + ints) * <Py_ssize_t>sizeof(uintptr_t))))

    cdef int _make_room(self, Py_ssize_t floats, Py_ssize_t ints) except -1:
        self._fmem = _grown(self._fmem, self._fnum * <Py_ssize_t>sizeof(double),
                            (self._fnum + floats) * <Py_ssize_t>sizeof(double))
        self._imem = _grown(self._imem, self._inum * <Py_ssize_t>sizeof(uintptr_t),
                            (self._inum + ints) * <Py_ssize_t>sizeof(uintptr_t))
        return 0


cdef _Memory _grown(_Memory m, Py_ssize_t used, Py_ssize_t need):
    # Own memory of at least `need` bytes that starts with the `used` bytes of
    # m: m itself when it has room, grown in place when nothing views it.
    # Nothing to append: m as it is.
    if need <= used or (not m.borrowed and m.nbytes >= need):
        return m
    cdef Py_ssize_t size = m.nbytes + m.nbytes // 2
    if size < need:
        size = need
    cdef char *data
    if not m.borrowed and m.exports == 0:
        data = <char *>realloc(m.data, size)
        if data == NULL:
            raise MemoryError()
        memset(data + m.nbytes, 0, size - m.nbytes)
        m.data = data
        m.nbytes = size
        return m
    cdef _Memory fresh = _memory_own(size)
    memcpy(fresh.data, m.data, used)
    return fresh


cdef Buffer _buffer_arg(object buffers):
    if not isinstance(buffers, Buffer):
        raise TypeError(f"buffers must be a tamias2d.batch.Buffer, not {type(buffers).__name__}")
    return <Buffer>buffers


cdef Py_ssize_t _count_each_body(const cpSpace *space) noexcept nogil:
    # How many bodies cpSpaceEachBody visits (when nothing wakes meanwhile).
    cdef Py_ssize_t n = space.dynamicBodies.num + space.staticBodies.num
    cdef int i
    cdef cpBody *body
    for i in range(space.sleepingComponents.num):
        body = <cpBody *>space.sleepingComponents.arr[i]
        while body != NULL:
            n += 1
            body = body.sleeping.next
    return n


# -- get_space_bodies --

cdef struct _BodyCursor:
    const int *code
    int ncodes
    int width          # doubles per body
    bint ids           # BODY_ID asked for
    double *f          # next double (get) ...
    double *fend
    const double *src  # ... or next double to read (set)
    const double *send
    uintptr_t *i
    uintptr_t *iend
    bint overflow      # ran out of room: cannot happen, the room is counted first


# The field codes of `bits` (written to `code`) and the doubles per body;
# `ids` says whether body ids go to the int buffer.
cdef void _body_cursor_init(_BodyCursor *c, unsigned int bits, int *code, bint ids) noexcept:
    cdef int k
    c.ncodes = _body_flag_codes(bits, code)
    c.code = code
    c.width = 0
    for k in range(c.ncodes):
        c.width += <int>_FIELD_WIDTH[code[k]]
    c.ids = ids
    c.overflow = False


cdef void _get_body(cpBody *body, void *data) noexcept nogil:
    cdef _BodyCursor *c = <_BodyCursor *>data
    if c.f + c.width > c.fend or (c.ids and c.i >= c.iend):
        c.overflow = True
        return
    if c.ids:
        c.i[0] = <uintptr_t>body.userData
        c.i += 1
    c.f += _read_body(body, c.code, c.ncodes, c.f)


def get_space_bodies(space, fields, buffers):
    """Append the `fields` (a :class:`BodyFields`) of every body of `space`
    to `buffers` (a :class:`Buffer`), as pymunk's function of that name does:
    body after body in Munk2D's order (the dynamic and kinematic bodies, the
    static bodies, ``space.static_body`` included once it was used, then the
    sleeping bodies component by component), each body's fields in
    :class:`BodyFields` order.

    >>> import tamias2d
    >>> from tamias2d.batch import Buffer, BodyFields, get_space_bodies
    >>> space = tamias2d.Space()
    >>> body = tamias2d.Body(1, 1)
    >>> body.position = 3, 4
    >>> body.angle = 0.5
    >>> space.add(body)
    >>> data = Buffer()
    >>> get_space_bodies(space, BodyFields.POSITION | BodyFields.ANGLE, data)
    >>> list(memoryview(data.float_buf()).cast("d"))
    [3.0, 4.0, 0.5]
    """
    cdef Space sp = _space_arg(space)
    cdef unsigned int bits = _flag_bits(fields, BodyFields)
    cdef Buffer buf = _buffer_arg(buffers)
    cdef int code[MAX_FIELDS]
    cdef _BodyCursor c
    _body_cursor_init(&c, bits, code, (bits & 1) != 0)
    cdef Py_ssize_t n
    while True:
        tamias_wait_for_step(&sp._space)
        n = _count_each_body(&sp._space)
        if buf._room(n * c.width, n if c.ids else 0):
            break
        buf._make_room(n * c.width, n if c.ids else 0)   # Python may run: count again
    c.f = <double *>buf._fmem.data + buf._fnum
    c.fend = c.f + n * c.width
    c.i = <uintptr_t *>buf._imem.data + buf._inum
    c.iend = c.i + (n if c.ids else 0)
    c.src = NULL
    c.send = NULL
    cpSpaceEachBody(&sp._space, _get_body, &c)
    buf._fnum = c.f - <double *>buf._fmem.data
    buf._inum = c.i - <uintptr_t *>buf._imem.data
    if c.overflow:
        raise RuntimeError("get_space_bodies: the space changed while it was read")


# -- set_space_bodies --

cdef void _set_body(cpBody *body, void *data) noexcept nogil:
    cdef _BodyCursor *c = <_BodyCursor *>data
    if c.src + c.width > c.send:
        c.overflow = True
        return
    c.src += _write_body(body, c.code, c.ncodes, c.src)


def set_space_bodies(space, fields, buffers):
    """Set the `fields` (a :class:`BodyFields`) of the bodies of `space` from
    the float array of `buffers`, read from its start in the layout
    :func:`get_space_bodies` writes, as pymunk's function of that name does.

    Each value goes through the C function of its Body setter (which wakes
    the body), body after body in Munk2D's order. BODY_ID may be given but is
    not set (ids cannot be changed) and the int array is not read. The array
    must hold at least as many values as the space's bodies need, and those
    must be finite (ValueError and IllegalBody; nothing is written then).

    As in pymunk, writing to a sleeping body wakes its whole component in
    the middle of Munk2D's walk over the sleeping components, which upsets
    the walk: of such a component only the first two bodies are written,
    the values meant for its other bodies go to the bodies visited next, and
    about half of the sleeping components are passed over. To write every
    body of a space with sleeping bodies, wake them (``body.activate()``),
    then read with :func:`get_space_bodies` and write.

    >>> import array, tamias2d
    >>> from tamias2d.batch import Buffer, BodyFields, set_space_bodies
    >>> space = tamias2d.Space()
    >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    >>> space.add(a, b)
    >>> data = Buffer()
    >>> data.set_float_buf(array.array("d", [1, 2, 0.5, 3, 4, -0.5]))
    >>> set_space_bodies(space, BodyFields.POSITION | BodyFields.ANGLE, data)
    >>> a.position, b.angle
    (Vec2d(1.0, 2.0), -0.5)
    """
    cdef Space sp = _space_arg(space)
    cdef unsigned int bits = _flag_bits(fields, BodyFields)
    cdef Buffer buf = _buffer_arg(buffers)
    cdef int code[MAX_FIELDS]
    cdef _BodyCursor c
    _body_cursor_init(&c, bits, code, False)
    tamias_wait_for_step(&sp._space)
    cdef Py_ssize_t n = _count_each_body(&sp._space)
    cdef Py_ssize_t need = n * c.width
    if need > buf._fnum:
        raise ValueError(f"set_space_bodies: {n} bodies need {need} floats for "
                         f"{fields!r}, the buffer holds {buf._fnum}")
    cdef const double *src = <const double *>buf._fmem.data
    cdef Py_ssize_t j
    for j in range(need):
        if not _finite(src[j]):
            names = body_columns([_FIELD_NAMES[code[k]] for k in range(c.ncodes)])
            raise IllegalBody(f"set_space_bodies: float {j} ({names[j % c.width]} of body "
                              f"{j // c.width}) must be finite, got {src[j]!r}; "
                              f"no body was changed")
    c.src = src
    c.send = src + need
    c.f = NULL
    c.fend = NULL
    c.i = NULL
    c.iend = NULL
    cpSpaceEachBody(&sp._space, _set_body, &c)
    if c.overflow:
        raise RuntimeError("set_space_bodies: the space changed while it was written")


# -- get_space_arbiters --

cdef struct _ArbiterCursor:
    unsigned int bits
    int fwidth         # doubles per arbiter
    int iwidth         # ints per arbiter
    double *f
    double *fend
    uintptr_t *i
    uintptr_t *iend
    bint overflow


cdef inline double *_put2(double *f, cpVect v) noexcept nogil:
    f[0] = v.x
    f[1] = v.y
    return f + 2


cdef void _get_arbiter(void *elt, void *data) noexcept nogil:
    cdef cpArbiter *arb = <cpArbiter *>elt
    cdef _ArbiterCursor *c = <_ArbiterCursor *>data
    if c.f + c.fwidth > c.fend or c.i + c.iwidth > c.iend:
        c.overflow = True
        return
    cdef unsigned int bits = c.bits
    cdef cpBody *a
    cdef cpBody *b
    cdef int count = cpArbiterGetCount(arb)
    cdef int n
    if bits & 3:
        cpArbiterGetBodies(arb, &a, &b)
        if bits & 1:
            c.i[0] = <uintptr_t>a.userData
            c.i += 1
        if bits & 2:
            c.i[0] = <uintptr_t>b.userData
            c.i += 1
    if bits & 4:
        c.f = _put2(c.f, cpArbiterTotalImpulse(arb))
    if bits & 8:
        c.f[0] = cpArbiterTotalKE(arb)
        c.f += 1
    if bits & 16:
        c.i[0] = 1 if cpArbiterIsFirstContact(arb) else 0
        c.i += 1
    if bits & 32:
        c.f = _put2(c.f, cpArbiterGetNormal(arb))
    if bits & 64:
        c.i[0] = <uintptr_t>count
        c.i += 1
    # Contact n (0 and 1) from bits 128 << 3n: point A, point B, distance;
    # zeros when the arbiter has fewer contacts.
    for n in range(2):
        if bits & (128u << (3 * n)):
            c.f = _put2(c.f, cpArbiterGetPointA(arb, n) if n < count else cpv(0.0, 0.0))
        if bits & (256u << (3 * n)):
            c.f = _put2(c.f, cpArbiterGetPointB(arb, n) if n < count else cpv(0.0, 0.0))
        if bits & (512u << (3 * n)):
            c.f[0] = cpArbiterGetDepth(arb, n) if n < count else 0.0
            c.f += 1


def get_space_arbiters(space, fields, buffers):
    """Append the `fields` (an :class:`ArbiterFields`) of every arbiter the
    space has cached to `buffers` (a :class:`Buffer`), as pymunk's function
    of that name does: arbiter after arbiter in the order of Munk2D's
    arbiter cache (a hash set keyed by shape addresses, so the order differs
    between processes; it includes pairs that stopped touching within
    ``space.collision_persistence`` steps, with CONTACT_COUNT 0, and the
    pairs of sleeping bodies), each arbiter's fields in
    :class:`ArbiterFields` order.

    >>> import tamias2d
    >>> from tamias2d.batch import Buffer, ArbiterFields, get_space_arbiters
    >>> space = tamias2d.Space()
    >>> space.add(tamias2d.Segment(space.static_body, (-10, 0), (10, 0), 1))
    >>> ball = tamias2d.Body(1, 10)
    >>> ball.position = 0, 1.9
    >>> space.add(ball, tamias2d.Circle(ball, 1))
    >>> space.step(0.01)
    >>> data = Buffer()
    >>> get_space_arbiters(space, ArbiterFields.CONTACT_COUNT | ArbiterFields.IS_FIRST_CONTACT, data)
    >>> list(memoryview(data.int_buf()).cast("P"))
    [1, 1]
    """
    cdef Space sp = _space_arg(space)
    cdef unsigned int bits = _flag_bits(fields, ArbiterFields)
    cdef Buffer buf = _buffer_arg(buffers)
    cdef _ArbiterCursor c
    c.bits = bits
    c.overflow = False
    c.iwidth = (bits & 1 != 0) + (bits & 2 != 0) + (bits & 16 != 0) + (bits & 64 != 0)
    # Doubles of the flags from TOTAL_IMPULSE (4) on, bit after bit.
    cdef int widths[11]
    widths[:] = [2, 1, 0, 2, 0, 2, 2, 1, 2, 2, 1]
    c.fwidth = 0
    cdef int k
    for k in range(11):
        if bits & (4u << k):
            c.fwidth += widths[k]
    cdef Py_ssize_t m
    while True:
        tamias_wait_for_step(&sp._space)
        m = sp._space.cachedArbiters.entries
        if buf._room(m * c.fwidth, m * c.iwidth):
            break
        buf._make_room(m * c.fwidth, m * c.iwidth)   # Python may run: count again
    c.f = <double *>buf._fmem.data + buf._fnum
    c.fend = c.f + m * c.fwidth
    c.i = <uintptr_t *>buf._imem.data + buf._inum
    c.iend = c.i + m * c.iwidth
    cpHashSetEach(sp._space.cachedArbiters, _get_arbiter, &c)
    buf._fnum = c.f - <double *>buf._fmem.data
    buf._inum = c.i - <uintptr_t *>buf._imem.data
    if c.overflow:
        raise RuntimeError("get_space_arbiters: the space changed while it was read")
