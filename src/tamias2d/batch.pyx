# Batch access to the bodies and arbiters of a space as NumPy arrays.
#
# pymunk offers the same service in pymunk.batch (flag enums and cffi buffers
# that the caller wraps in NumPy); here the arrays are NumPy from the start.
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
"""
from cpython.dict cimport PyDict_Next
from cpython.object cimport PyObject
from libc.stdint cimport uintptr_t, int64_t, uint64_t
from libc.stdlib cimport malloc, free
from libc.math cimport NAN

from tamias2d._structs cimport cpBody, cpShape, cpArbiter, cpArray, cpContactPointSet
from tamias2d.vector cimport cpVect, cpv
from tamias2d.body cimport (Body, cpBodyGetPosition, cpBodySetPosition, cpBodySetAngle,
    cpBodySetVelocity, cpBodySetAngularVelocity, cpBodySetForce, cpBodySetTorque)
from tamias2d.shape cimport Shape
from tamias2d.space cimport Space
from tamias2d._threadguard cimport tamias_wait_for_step
from tamias2d.arbiter cimport (cpArbiterGetBodies, cpArbiterGetShapes,
    cpArbiterGetContactPointSet, cpArbiterTotalImpulse, cpArbiterTotalKE,
    cpArbiterIsFirstContact)

from tamias2d.errors import IllegalBody

__all__ = ["BODY_FIELDS", "ARBITER_FIELDS", "get_bodies", "set_bodies", "body_columns",
           "get_body_ids", "get_arbiters", "arbiter_dtype", "get_spaces_bodies",
           "set_spaces_bodies"]

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
    cdef int ncodes = len(codes)
    cdef int code[MAX_FIELDS]
    cdef int k
    for k in range(ncodes):
        code[k] = codes[k]
    cdef Py_ssize_t pos = 0, row = 0
    cdef PyObject *key
    cdef PyObject *value
    cdef cpBody *body
    cdef cpVect p
    cdef int col
    tamias_wait_for_step(&sp._space)
    while PyDict_Next(sp._bodies, &pos, &key, &value):
        if row >= n:   # cannot happen while we hold the GIL; keeps the writes in bounds
            break
        body = &(<Body>key)._body
        col = 0
        for k in range(ncodes):
            if code[k] == F_POSITION:
                p = cpBodyGetPosition(body)
                view[row, col] = p.x
                view[row, col + 1] = p.y
                col += 2
            elif code[k] == F_ANGLE:
                view[row, col] = body.a
                col += 1
            elif code[k] == F_VELOCITY:
                view[row, col] = body.v.x
                view[row, col + 1] = body.v.y
                col += 2
            elif code[k] == F_ANGULAR_VELOCITY:
                view[row, col] = body.w
                col += 1
            elif code[k] == F_FORCE:
                view[row, col] = body.f.x
                view[row, col + 1] = body.f.y
                col += 2
            else:
                view[row, col] = body.t
                col += 1
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
    cdef int ncodes = len(codes)
    cdef int code[MAX_FIELDS]
    cdef int k, col
    for k in range(ncodes):
        code[k] = codes[k]
    cdef Py_ssize_t pos = 0, row = 0
    cdef PyObject *key
    cdef PyObject *value
    cdef cpBody *body
    tamias_wait_for_step(&sp._space)
    while PyDict_Next(sp._bodies, &pos, &key, &value):
        if row >= n:
            break
        body = &(<Body>key)._body
        col = 0
        for k in range(ncodes):
            if code[k] == F_POSITION:
                cpBodySetPosition(body, cpv(view[row, col], view[row, col + 1]))
                col += 2
            elif code[k] == F_ANGLE:
                cpBodySetAngle(body, view[row, col])
                col += 1
            elif code[k] == F_VELOCITY:
                cpBodySetVelocity(body, cpv(view[row, col], view[row, col + 1]))
                col += 2
            elif code[k] == F_ANGULAR_VELOCITY:
                cpBodySetAngularVelocity(body, view[row, col])
                col += 1
            elif code[k] == F_FORCE:
                cpBodySetForce(body, cpv(view[row, col], view[row, col + 1]))
                col += 2
            else:
                cpBodySetTorque(body, view[row, col])
                col += 1
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

def get_spaces_bodies(spaces, fields, out=None):
    """The bodies of every space of `spaces`, stacked: a float64 array of
    shape (total bodies, columns), the bodies of ``spaces[0]`` first (each
    space's in ``space.bodies`` order), and the row offsets, an int64 array of
    ``len(spaces) + 1`` entries: the bodies of ``spaces[i]`` are rows
    ``offsets[i]:offsets[i + 1]``. With :func:`tamias2d.step_spaces` an RL
    loop is "write actions, step all, read observations" in three calls.

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
    spaces = [_space_arg(s) for s in spaces]
    cdef tuple codes = _parse_fields(fields)
    cdef int width = _width(codes)
    counts = [len((<Space>s)._bodies) for s in spaces]
    offsets = np.zeros(len(spaces) + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    total = int(offsets[-1])
    if out is None:
        out = np.empty((total, width), dtype=np.float64)
    elif not isinstance(out, np.ndarray) or out.shape != (total, width):
        raise ValueError(f"out must be a float64 array of shape {(total, width)}")
    for i, s in enumerate(spaces):
        get_bodies(s, fields, out[offsets[i]:offsets[i + 1]])
    return out, offsets


def set_spaces_bodies(spaces, values, fields):
    """Write the stacked rows of :func:`get_spaces_bodies` back: ``values``
    has one row per body of every space, in the same order. Every value is
    checked before any body changes.

    >>> import tamias2d, tamias2d.batch
    >>> spaces = [tamias2d.Space() for _ in range(2)]
    >>> for s in spaces:
    ...     s.add(tamias2d.Body(1, 1))
    >>> tamias2d.batch.set_spaces_bodies(spaces, [[1, 2], [3, 4]], "velocity")
    >>> [next(iter(s.bodies)).velocity for s in spaces]
    [Vec2d(1.0, 2.0), Vec2d(3.0, 4.0)]
    """
    np = _np()
    spaces = [_space_arg(s) for s in spaces]
    cdef tuple codes = _parse_fields(fields)
    cdef int width = _width(codes)
    arr = np.ascontiguousarray(np.asarray(values, dtype=np.float64))
    if arr.ndim == 1 and width == 1:
        arr = arr.reshape((arr.shape[0], 1))
    counts = [len((<Space>s)._bodies) for s in spaces]
    total = sum(counts)
    if arr.shape != (total, width):
        raise ValueError(f"values have shape {arr.shape}; {total} bodies need {(total, width)}")
    if not np.isfinite(arr).all():
        raise IllegalBody("values must be finite; no body was changed")
    start = 0
    for s, n in zip(spaces, counts):
        set_bodies(s, arr[start:start + n], fields)
        start += n
