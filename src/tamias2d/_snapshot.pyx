"""Copy and pickle of spaces, bodies and shapes.

A copied or unpickled space steps on bit for bit as the original would: the
C state that decides the next steps is carried over exactly, not rebuilt.
That state is

* every body and shape struct (positions, velocities, accumulated mass,
  cached bounding boxes, shape hash ids, ...), as raw struct bytes with the
  pointers taken out;
* the links between them (body shape lists, per-body arbiter lists, sleeping
  components) and the order of the space's arrays (dynamic, static and
  sleeping bodies, the last step's arbiters);
* the arbiter cache: every arbiter with its contacts (accumulated impulses
  included), state, stamp, handlers and its place in the contact buffer ring;
* the broad phase as it is: both BB trees node by node (boxes, stamps, the
  pair lists with their narrow-phase ids) and the leaf hash sets bucket by
  bucket, or both spatial hashes cell by cell; the structure of the trees,
  not only their contents, decides the order of collision pairs and so the
  solver order;
* the space's counters: stamp, current dt, shape id counter.

Pointers never leave the process: objects are numbered (bodies in
``Space.bodies`` order then the static body, shapes in ``Space.shapes``
order, arbiters, tree nodes, pairs, handles) and links are written as
numbers. The records are fixed-size C structs written back to back into one
``bytes`` object (see ``Header``: a pickle only loads into a build with the
same record sizes).

The snapshot is a sequence of sections, one per record type. Each has a
writer and a reader, side by side below and in the order they appear:

======================  =========================================================
section                 records
======================  =========================================================
header                  magic, format version, record sizes of this build
space                   SpaceRec: settings, counters, the count of every section
soft solver             SoftRec: Space.solver and the soft solver's settings
body links              BodyRec per body (lists, component links), Body.shapes orders
shape links             ShapeRec per shape (its place in its body's shape list)
body structs            cpBody per body
shapes                  kind per shape, then the struct of its kind (circle,
                        segment, polygon with its planes)
constraints             ConstraintRec, the joint struct of its kind, the solver's
                        constraint array
body arrays             the dynamic and static body arrays, the sleeping roots
handlers                HandlerRec per collision handler of the space
contact buffers         BufferRec per buffer of the ring, oldest first
arbiters                ArbRec, their contacts, this step's array, the cache order
indexes                 IndexRec for the static and the dynamic index
tree nodes              NodeRec per node of both BB trees
pairs                   PairRec per pair of the dynamic tree
handles                 HandleRec per spatial hash handle
sets and cells          per index: the leaf or handle set, the hash cells
======================  =========================================================

A reader checks its own records as it reads them: indices in range, the
numbers the step needs finite, the rules of one record (an arbiter has
collision handlers, a sleeping body's idle time does not make it static,
...). The rules that tie records together (lists, sleeping components, the
contact graph, the broad phase) are checked by the ``_check_*`` function
next to the reader of the record that holds the link, once the whole
snapshot is read and matched with the objects given with it. Nothing is
linked before every check has passed, and a broken rule is refused with a
``CopyError`` that names it. :func:`snapshot_sections` lists the sections
of a snapshot (for debugging and for the mutation fuzzer).

Bodies and shapes pickle on their own in a compact form (struct bytes, the
user attributes, the integrator functions); a space's state lists its bodies
and shapes as objects (so references to them elsewhere keep their identity)
plus the snapshot bytes. ``Space.copy()`` / ``copy.deepcopy`` make the new
objects directly, without going through pickle.

What is not kept, as in pymunk: post-step callbacks, and Python callbacks
(collision handlers, integrators) that cannot be pickled make the pickle fail
(they are shared by reference in a deep copy). The arbiter cache of a copy is
a hash set keyed by the new shapes' addresses, so when several pairs separate
in the same step their ``separate`` callbacks may come in another order than
in the original (Munk2D's order there depends on addresses in any case); the
physics does not depend on it.

>>> import pickle, tamias2d
>>> space = tamias2d.Space()
>>> space.gravity = 0, -10
>>> b = tamias2d.Body(1, 10)
>>> space.add(b, tamias2d.Circle(b, 1))
>>> space.step(0.1)
>>> twin = pickle.loads(pickle.dumps(space))
>>> space.step(0.1); twin.step(0.1)
>>> next(iter(twin.bodies)).position == b.position
True
"""
from libc.stdlib cimport malloc, free, qsort
from libc.string cimport memcpy, memset, memcmp
from libc.stdint cimport uintptr_t, int32_t, int64_t, uint32_t, uint64_t, uint8_t
from libc.math cimport INFINITY, floor, fabs, sqrt
from cpython.bytes cimport PyBytes_FromStringAndSize, PyBytes_AS_STRING, PyBytes_GET_SIZE

import copy as _copy
import copyreg
import weakref

from tamias2d._config cimport (cpFloat, cpHashValue, cpCollisionType, CP_HASH_PAIR,
    CP_BUFFER_BYTES, CP_POLY_SHAPE_INLINE_ALLOC, CP_WILDCARD_COLLISION_TYPE)
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArbiter, cpContact, cpArray,
    cpHashSet, cpHashSetBin, cpHashSetEqlFunc, cpCollisionHandler, cpContactBufferHeader,
    cpSpatialIndex, cpShapeClass, cpConstraint, cpCircleShape, cpSegmentShape, cpPolyShape,
    cpSplittingPlane, cpArbiterState, CP_BODY_TYPE_DYNAMIC, CP_BODY_TYPE_KINEMATIC,
    CP_BODY_TYPE_STATIC)
from tamias2d.vector cimport cpVect, cpBB, vec2d_from_cpv
from tamias2d._containers cimport (cpcalloc, cprealloc, cpArrayPush, cpHashSetNew,
    cpHashSetFree, cpHashSetInsert, cpTakeOutOfMemory, next_prime)
from tamias2d._bbtree cimport cpBBTree, Node, Pair, cpBBTreeClass
from tamias2d._spacehash cimport cpSpaceHash, cpHandle, cpSpaceHashBin, cpSpaceHashClass
from tamias2d.body cimport (Body, cpBodyUpdateVelocity, cpBodyUpdatePosition,
    tamias_body_velocity_trampoline, tamias_body_position_trampoline, cpBodyGetType,
    cpBodyGetPosition)
from tamias2d.shape cimport Shape, Circle, Segment, Poly, cpShapeDestroy
from tamias2d.arbiter cimport cpCollisionHandlerDoNothing, cpArbiterNext
# What this module needs of the space: the struct's life cycle (a failed
# restore resets it), adding the static body and the collision handlers.
from tamias2d.space cimport (Space, cpSpaceInit, cpSpaceDestroy, cpSpaceAddBody,
    cpSpaceAddCollisionHandler)
from tamias2d.constraints cimport (Constraint, PinJoint, SlideJoint, PivotJoint, GrooveJoint,
    DampedSpring, DampedRotarySpring, RotaryLimitJoint, RatchetJoint, GearJoint, SimpleMotor,
    cpPinJoint, cpSlideJoint, cpPivotJoint, cpGrooveJoint, cpDampedSpring, cpDampedRotarySpring,
    cpRotaryLimitJoint, cpRatchetJoint, cpGearJoint, cpSimpleMotor)

from tamias2d.errors import CopyError, SpaceLocked

__all__ = []


# -- fixed layout ----------------------------------------------------------------------------

# Contacts per contact buffer, as the space module computes it.
cdef enum:
    CONTACTS_PER_BUFFER = (CP_BUFFER_BYTES - 24) // 96

cdef struct ContactBuffer:
    cpContactBufferHeader header
    cpContact contacts[CONTACTS_PER_BUFFER]

DEF FORMAT_VERSION = 5

# Records. Only 8- and 4-byte fields, widest first, so there is no padding.

# The soft solver's settings (Space.solver and its attributes, _soft_step.pxd),
# the section right after the space record. The soft solver keeps no other
# state across steps: its warm start is the contacts' jnAcc / jtAcc, which the
# arbiter records carry already.
cdef struct SoftRec:
    cpFloat contactHertz
    cpFloat contactDampingRatio
    cpFloat jointHertz
    cpFloat jointDampingRatio
    cpFloat pushOut
    cpFloat speculative
    int32_t solver
    int32_t substeps

cdef struct SpaceRec:
    cpFloat gx
    cpFloat gy
    cpFloat damping
    cpFloat idleSpeedThreshold
    cpFloat sleepTimeThreshold
    cpFloat collisionSlop
    cpFloat collisionBias
    cpFloat curr_dt
    uint64_t shapeIDCounter
    int32_t iterations
    uint32_t collisionPersistence
    uint32_t stamp
    int32_t nbodies            # the whole body table
    int32_t nspace_bodies      # of which the first ones are Space.bodies
    int32_t has_static         # then the static body
    int32_t nshapes
    int32_t ndynamic
    int32_t nstatic
    int32_t nsleeping
    int32_t nhandlers
    int32_t nbuffers
    int32_t narbiters
    int32_t nstep_arbiters
    int32_t ncached
    uint32_t cached_size
    int32_t nshape_order       # total entries of the bodies' shape orders
    int32_t ncontacts          # contacts stored after the arbiter records
    int32_t nconstraints       # Space.constraints
    int32_t nstep_constraints  # the space's constraint array (sleeping ones are out)

cdef struct BodyRec:
    int32_t in_space
    int32_t shapeList
    int32_t arbiterList
    int32_t root
    int32_t next
    int32_t nshapes_view       # entries of Body.shapes order that follow
    int32_t constraintList
    int32_t pad

cdef struct ShapeRec:
    int32_t in_space
    int32_t next
    int32_t prev
    int32_t pad

cdef struct ConstraintRec:
    int32_t kind               # index in _JOINTS
    int32_t a
    int32_t b
    int32_t next_a
    int32_t next_b
    int32_t in_space

cdef struct HandlerRec:
    uint64_t typeA
    uint64_t typeB

cdef struct BufferRec:
    uint32_t stamp
    uint32_t numContacts

cdef struct ArbRec:
    cpFloat e
    cpFloat u
    cpFloat svr_x
    cpFloat svr_y
    cpFloat n_x
    cpFloat n_y
    int32_t a
    int32_t b
    int32_t body_a
    int32_t body_b
    int32_t ta_next
    int32_t ta_prev
    int32_t tb_next
    int32_t tb_prev
    int32_t count
    int32_t ckind              # 0 no contacts, 1 in a contact buffer, 2 on the heap
    int32_t cbuf
    int32_t coff
    int32_t handlerAB
    int32_t handlerBA
    int32_t handlerA
    int32_t handlerB
    uint32_t stamp
    uint32_t state
    int32_t swapped
    int32_t processCollision

cdef struct IndexRec:
    cpFloat celldim            # spatial hash
    cpFloat reach              # tree: staticReach (the soft solver's)
    uint32_t kind              # 1 BB tree, 2 spatial hash
    uint32_t stamp
    int32_t root               # tree: root node (global number)
    int32_t first              # first node / handle number of this index
    int32_t count              # nodes / handles of this index
    uint32_t set_size          # the leaves / handle hash set
    int32_t set_count
    int32_t numcells           # spatial hash
    int32_t ncells             # non-empty cells
    int32_t nbins              # bins in all cells
    int32_t has_velocity
    int32_t pad

cdef struct NodeRec:
    cpFloat l
    cpFloat b
    cpFloat r
    cpFloat t
    int32_t obj                # shape, or -1 for an internal node
    int32_t parent
    int32_t a                  # internal: children
    int32_t bchild
    uint32_t stamp             # leaf: stamp and first pair
    int32_t pairs

cdef struct PairRec:
    int32_t a_leaf
    int32_t a_prev
    int32_t a_next
    int32_t b_leaf
    int32_t b_prev
    int32_t b_next
    uint32_t id
    int32_t pad

cdef struct SetEntry:
    uint64_t hash
    int32_t elt
    int32_t pad

cdef struct HandleRec:
    int32_t obj
    int32_t retain
    uint32_t stamp
    int32_t pad

cdef struct CellRec:
    int32_t cell
    int32_t length

cdef struct Header:
    char magic[8]
    uint32_t version
    uint32_t ptr_size
    uint32_t sizes[16]


cdef void _fill_header(Header *h) noexcept nogil:
    memset(h, 0, sizeof(Header))
    memcpy(h.magic, b"T2DSNAP\0", 8)
    h.version = FORMAT_VERSION
    h.ptr_size = sizeof(void *)
    h.sizes[0] = sizeof(SpaceRec) ^ (sizeof(SoftRec) << 16)
    h.sizes[1] = sizeof(BodyRec)
    h.sizes[2] = sizeof(ShapeRec)
    h.sizes[3] = sizeof(HandlerRec)
    h.sizes[4] = sizeof(BufferRec)
    h.sizes[5] = sizeof(ArbRec)
    h.sizes[6] = sizeof(IndexRec)
    h.sizes[7] = sizeof(NodeRec)
    h.sizes[8] = sizeof(PairRec)
    h.sizes[9] = sizeof(SetEntry)
    h.sizes[10] = sizeof(HandleRec)
    h.sizes[11] = sizeof(CellRec)
    h.sizes[12] = sizeof(cpContact)
    h.sizes[13] = CONTACTS_PER_BUFFER
    h.sizes[14] = sizeof(cpBody)
    h.sizes[15] = sizeof(cpPolyShape) ^ (sizeof(ConstraintRec) << 16)




# -- a growable byte buffer and a bounds-checked reader ----------------------------------------

cdef struct Writer:
    char *data
    size_t len
    size_t cap
    bint failed

cdef void w_init(Writer *w, size_t cap) noexcept nogil:
    w.data = <char *>malloc(cap if cap > 0 else 64)
    w.len = 0
    w.cap = cap if cap > 0 else 64
    w.failed = w.data == NULL

cdef void w_put(Writer *w, const void *p, size_t n) noexcept nogil:
    cdef size_t cap
    cdef char *grown
    if w.failed:
        return
    if w.len + n > w.cap:
        cap = w.cap * 2
        while cap < w.len + n:
            cap *= 2
        grown = <char *>cprealloc(w.data, cap)
        if grown == NULL:
            w.failed = True
            return
        w.data = grown
        w.cap = cap
    memcpy(w.data + w.len, p, n)
    w.len += n

cdef inline void w_i32(Writer *w, int32_t v) noexcept nogil:
    w_put(w, &v, sizeof(int32_t))


cdef struct Reader:
    const char *data
    size_t len
    size_t pos
    void *log                  # a list of sections for snapshot_sections(), or NULL

# A pointer into the reader for `count` records of `size` bytes (checked),
# noted as a section of the snapshot when a log is kept.
cdef const char *r_take(Reader *r, Py_ssize_t count, size_t size, str name=None) except NULL:
    if count < 0 or (count > 0 and <size_t>count > (r.len - r.pos) // size):
        raise CopyError("the snapshot of the space is truncated or corrupt")
    cdef const char *p = r.data + r.pos
    if r.log != NULL and name is not None:
        (<list>r.log).append((name, r.pos, size, count))
    r.pos += <size_t>count * size
    return p

cdef int r_rec(Reader *r, void *out, size_t size, str name) except -1:
    # One record, copied out (for the space and index records).
    memcpy(out, r_take(r, 1, size, name), size)
    return 0


# -- refusals ----------------------------------------------------------------------------------

cdef int _bad(str what) except -1:
    # Every refusal of the restore: the message names the broken rule.
    raise CopyError(f"the snapshot of the space is corrupt: {what}")

# An index of record `rec` number k, field `field`: the message is only
# made when the check fails (these run for every link of every record).
cdef inline int _check_index(int32_t i, Py_ssize_t n, str rec, Py_ssize_t k, str field,
                             bint allow_none=True) except -1:
    if (i == -1 and allow_none) or (0 <= i < n):
        return 0
    return _bad(f"{rec} {k}: {field} {i} is out of range (0..{n - 1})")

cdef inline int _check_range(int32_t i, int32_t first, int32_t count, str rec, Py_ssize_t k,
                             str field) except -1:
    if first <= i < first + count:
        return 0
    return _bad(f"{rec} {k}: {field} {i} is out of range ({first}..{first + count - 1})")

# x - x is 0 for a finite x and NaN for inf or NaN: one test for both.
cdef inline bint _fin(double x) noexcept nogil:
    return x - x == 0.0

cdef inline bint _finv(cpVect v) noexcept nogil:
    return _fin(v.x) and _fin(v.y)

cdef inline bint _finbb(cpBB bb) noexcept nogil:
    return _fin(bb.l) and _fin(bb.b) and _fin(bb.r) and _fin(bb.t) and bb.l <= bb.r and bb.b <= bb.t

cdef inline bint _modest(double x) noexcept nogil:
    # Finite, and small enough that its square is finite too: the joints
    # square their offsets and lengths (a mass matrix, a spring's force).
    return fabs(x) <= 1e150

cdef inline bint _modestv(cpVect v) noexcept nogil:
    return _modest(v.x) and _modest(v.y)

cdef inline double _arm(cpVect r1, cpVect r2) noexcept nogil:
    # The longest lever arm of two offsets (at least 1).
    cdef double m = 1.0
    m = fabs(r1.x) if fabs(r1.x) > m else m
    m = fabs(r1.y) if fabs(r1.y) > m else m
    m = fabs(r2.x) if fabs(r2.x) > m else m
    m = fabs(r2.y) if fabs(r2.y) > m else m
    return m

cdef inline bint _impulse(double j, double arm) noexcept nogil:
    # An accumulated impulse the warm start can apply: its moment about the
    # lever arm stays finite (a static body's zero inverse inertia times an
    # infinite moment is NaN).
    return _fin(j) and fabs(j) * arm <= 1e300

# A joint's parameters as its constructor and setters accept them
# (constraints.pyx, PARAMETER_LIMIT): a copy rebuilds each joint through
# them, so a snapshot whose joint the setters refuse would restore but not
# copy (the mutation fuzzer's seed 4040: an error_bias or a phase of 1e150).
JOINT_PARAMETER_LIMIT = 1e100
cdef double _JOINT_LIMIT = 1e100

cdef inline bint _param(double x) noexcept nogil:
    return fabs(x) <= _JOINT_LIMIT

cdef inline bint _paramv(cpVect v) noexcept nogil:
    return _param(v.x) and _param(v.y)

cdef inline bint _divisor(double x) noexcept nogil:
    # A ratio or notch the solver divides by: 0, or an inverse within the limit.
    return _param(x) and (x == 0.0 or fabs(x) >= 1.0 / _JOINT_LIMIT)

cdef inline bint _limits(double lo, double hi) noexcept nogil:
    # A joint's range: a lower end up to the limit (-inf: none), an upper end
    # from minus the limit (inf: none); min > max is the setters' to allow
    # (pymunk does), and a step solves it.
    return lo <= _JOINT_LIMIT and hi >= -_JOINT_LIMIT

cdef inline double _inverse(double x) noexcept nogil:
    # How the body setters store an inverse mass or moment.
    return INFINITY if x == 0.0 else 1.0 / x

cdef int _check_set_size(uint32_t size, int32_t entries, uint64_t most, str what) except -1:
    # A hash set restored with `entries` must have the size it had: a prime
    # of the table the set grows through, larger than its entries (it grows
    # when they reach it), and no larger than a set that never held more
    # than `most` entries can have grown to (its every bucket is walked at
    # each step).
    if size > 1610612741 or next_prime(<int>size) != <int>size:
        _bad(f"{what} has size {size}, not one a hash set can have")
    if entries < 0 or <uint32_t>entries >= size:
        _bad(f"{what} holds {entries} entries in {size} buckets (a set grows before it is full)")
    if most < 1610612741 and size > <uint32_t>next_prime(<int>most + 1):
        _bad(f"{what} has {size} buckets, more than it can grow to with at most {most} entries")
    return 0

cdef int _check_unlocked(Space sp) except -1:
    if sp._locked or sp._space.locked:
        raise SpaceLocked("a space cannot be copied or pickled during a step or a query; "
                          "use a post-step callback")
    return 0

cdef int _reserve(cpArray *arr, int n) except -1:
    cdef void **grown
    if arr.max >= n:
        return 0
    grown = <void **>cprealloc(arr.arr, n * sizeof(void *))
    if grown == NULL:
        cpTakeOutOfMemory()
        raise MemoryError()
    arr.arr = grown
    arr.max = n
    return 0

cdef dict _custom(object obj):
    # pymunk keeps the attributes set by the user whose names do not start
    # with an underscore.
    cdef dict d = getattr(obj, "__dict__", None)
    if not d:
        return None
    out = {k: v for k, v in d.items() if k[0] != "_"}
    return out if out else None


# -- pointer -> number map (open addressing) ---------------------------------------------------

cdef struct PtrMap:
    uintptr_t *keys
    int32_t *vals
    size_t mask
    int32_t count
    void **items               # number -> pointer, in order of numbering
    int32_t cap_items

cdef int pm_init(PtrMap *m, Py_ssize_t n) except -1:
    cdef size_t cap = 16
    while cap < <size_t>(2 * n + 2):
        cap *= 2
    m.keys = <uintptr_t *>cpcalloc(cap, sizeof(uintptr_t))
    m.vals = <int32_t *>malloc(cap * sizeof(int32_t))
    m.items = <void **>malloc((n + 1) * sizeof(void *))
    m.cap_items = <int32_t>(n + 1)
    m.mask = cap - 1
    m.count = 0
    if m.keys == NULL or m.vals == NULL or m.items == NULL:
        pm_free(m)
        cpTakeOutOfMemory()
        raise MemoryError()
    return 0

cdef void pm_free(PtrMap *m) noexcept nogil:
    free(m.keys)
    free(m.vals)
    free(m.items)
    m.keys = NULL
    m.vals = NULL
    m.items = NULL

cdef inline size_t _slot(uintptr_t key, size_t mask) noexcept nogil:
    return <size_t>((<uint64_t>key * <uint64_t>0x9E3779B97F4A7C15ULL) >> 17) & mask

cdef inline int32_t pm_get(PtrMap *m, const void *p) noexcept nogil:
    cdef uintptr_t key = <uintptr_t>p
    cdef size_t i
    if key == 0:
        return -1
    i = _slot(key, m.mask)
    while m.keys[i] != 0:
        if m.keys[i] == key:
            return m.vals[i]
        i = (i + 1) & m.mask
    return -1

cdef int _pm_grow(PtrMap *m) except -1:
    cdef PtrMap bigger
    cdef size_t i
    cdef int32_t k
    pm_init(&bigger, 2 * m.cap_items)
    for k in range(m.count):
        _pm_add_new(&bigger, m.items[k])
    pm_free(m)
    m[0] = bigger
    return 0

cdef inline int32_t _pm_add_new(PtrMap *m, void *p) noexcept nogil:
    cdef uintptr_t key = <uintptr_t>p
    cdef size_t i = _slot(key, m.mask)
    while m.keys[i] != 0:
        i = (i + 1) & m.mask
    m.keys[i] = key
    m.vals[i] = m.count
    m.items[m.count] = p
    m.count += 1
    return m.count - 1

# The number of p, numbering it if new. p must not be NULL.
cdef int32_t pm_add(PtrMap *m, void *p) except -1:
    cdef int32_t k = pm_get(m, p)
    if k >= 0:
        return k
    if m.count + 1 >= m.cap_items or <size_t>(2 * (m.count + 1)) > m.mask:
        _pm_grow(m)
    return _pm_add_new(m, p)


# ================================================================================================
# Bodies and shapes on their own
# ================================================================================================

BODY_TAG = "tamias2d.Body/1"
SHAPE_TAG = "tamias2d.Shape/1"

cdef bytes _body_bytes(Body b):
    cdef cpBody copy = b._body
    copy.velocity_func = NULL
    copy.position_func = NULL
    copy.userData = NULL
    copy.space = NULL
    copy.shapeList = NULL
    copy.arbiterList = NULL
    copy.constraintList = NULL
    copy.sleeping.root = NULL
    copy.sleeping.next = NULL
    return PyBytes_FromStringAndSize(<char *>&copy, sizeof(cpBody))

cdef void _set_body_funcs(Body b) noexcept:
    b._body.velocity_func = (cpBodyUpdateVelocity if b._velocity_func is None
                             else tamias_body_velocity_trampoline)
    b._body.position_func = (cpBodyUpdatePosition if b._position_func is None
                             else tamias_body_position_trampoline)

cdef int _body_check_free(Body b) except -1:
    if b._body.space != NULL:
        from tamias2d.errors import IllegalBody
        raise IllegalBody("Cannot re-initialise a body that is in a space.")
    return 0

# The C struct of src into dst (dst not in a space); links cleared.
cdef void _body_copy_struct(Body dst, const cpBody *src) noexcept:
    memcpy(&dst._body, src, sizeof(cpBody))
    dst._body.userData = <void *>dst
    dst._body.space = NULL
    dst._body.shapeList = NULL
    dst._body.arbiterList = NULL
    dst._body.constraintList = NULL
    dst._body.sleeping.root = NULL
    dst._body.sleeping.next = NULL


def body_reduce(Body b not None):
    """``Body.__reduce_ex__``: the compact state (struct bytes, user
    attributes, integrators), or pymunk's layout for a subclass that
    overrides ``__getstate__`` / ``__setstate__``.

    >>> import tamias2d
    >>> from tamias2d._snapshot import body_reduce
    >>> body_reduce(tamias2d.Body(1, 2))[2][0]
    'tamias2d.Body/1'
    """
    cls = type(b)
    if (cls.__getstate__ is not Body.__getstate__ or cls.__setstate__ is not Body.__setstate__
            or cls._pickle_attrs_general is not Body._pickle_attrs_general
            or cls._pickle_attrs_init is not Body._pickle_attrs_init):
        return (copyreg.__newobj__, (cls,), b.__getstate__())
    return (copyreg.__newobj__, (cls,),
            (BODY_TAG, _body_bytes(b), _custom(b), b._velocity_func, b._position_func))


def body_setstate(Body b not None, tuple state):
    """Restore a body from :func:`body_reduce`'s compact state the way
    pymunk restores a pickled body: ``Body(mass, moment, body_type)``, then
    force, angle, position, centre of gravity, velocity, angular velocity and
    torque through their setters (so the numbers are pymunk's: the hidden
    centre-of-gravity position and the bias velocities are not kept, and a
    sleeping body comes back awake). A space's own state restores its bodies
    exactly, on top of this.

    >>> import tamias2d
    >>> from tamias2d._snapshot import body_reduce, body_setstate
    >>> src = tamias2d.Body(1, 2)
    >>> src.position = 3, 4
    >>> dst = tamias2d.Body()
    >>> body_setstate(dst, body_reduce(src)[2])
    >>> dst.position, dst.mass
    (Vec2d(3.0, 4.0), 1.0)
    """
    cdef cpBody src
    if len(state) != 5 or state[0] != BODY_TAG:
        raise CopyError("not a tamias2d body state (or one from another tamias2d version)")
    _, data, custom, vfunc, pfunc = state
    if custom is not None and not isinstance(custom, dict):
        raise CopyError("the body state's attributes are not a dict")
    if not isinstance(data, bytes) or len(<bytes>data) != sizeof(cpBody):
        raise CopyError("the body state does not match this build of tamias2d")
    _body_check_free(b)
    if vfunc is not None and not callable(vfunc) or pfunc is not None and not callable(pfunc):
        raise CopyError("the body state holds an integrator that is not callable")
    memcpy(&src, PyBytes_AS_STRING(data), sizeof(cpBody))
    # Shapes attached while this pickle was being loaded (a shape reached
    # before its body's state) stay attached.
    attached = b._shapes
    Body.__init__(b, src.m, src.i, <int>cpBodyGetType(&src))
    if attached:
        b._shapes = attached
    values = {"force": vec2d_from_cpv(src.f), "angle": src.a,
              "position": vec2d_from_cpv(cpBodyGetPosition(&src)),
              "center_of_gravity": vec2d_from_cpv(src.cog), "velocity": vec2d_from_cpv(src.v),
              "angular_velocity": src.w, "torque": src.t}
    for name in Body._pickle_attrs_general:
        setattr(b, name, values[name])
    b._body.isBullet = 1 if src.isBullet else 0   # tamias2d's own flag
    if custom:
        for k, v in (<dict>custom).items():
            setattr(b, k, v)
    if vfunc is not None:
        b.velocity_func = vfunc
    if pfunc is not None:
        b.position_func = pfunc


cdef int _shape_kind(Shape s) except -1:
    if isinstance(s, Circle):
        return 0
    if isinstance(s, Segment):
        return 1
    if isinstance(s, Poly):
        return 2
    raise TypeError(f"unknown shape class {type(s).__name__}")

cdef void *_shape_struct(Shape s, int kind, size_t *size) noexcept:
    if kind == 0:
        size[0] = sizeof(cpCircleShape)
        return &(<Circle>s)._circle
    if kind == 1:
        size[0] = sizeof(cpSegmentShape)
        return &(<Segment>s)._segment
    size[0] = sizeof(cpPolyShape)
    return &(<Poly>s)._poly

cdef tuple _shape_bytes(Shape s, int kind):
    cdef size_t size
    cdef void *src = _shape_struct(s, kind, &size)
    cdef bytes data = PyBytes_FromStringAndSize(<char *>src, size)
    cdef cpShape *c = <cpShape *>PyBytes_AS_STRING(data)
    cdef cpPolyShape *poly
    planes = None
    c.klass = NULL
    c.space = NULL
    c.body = NULL
    c.userData = NULL
    c.next = NULL
    c.prev = NULL
    if kind == 2:
        poly = <cpPolyShape *>c
        if poly.count > CP_POLY_SHAPE_INLINE_ALLOC:
            planes = PyBytes_FromStringAndSize(<char *>(<Poly>s)._poly.planes,
                                               2 * poly.count * sizeof(cpSplittingPlane))
        poly.planes = NULL
    return data, planes

# Detach a shape (not in a space) from its old body before its struct is replaced.
cdef int _shape_prepare(Shape s) except -1:
    from tamias2d.errors import AlreadyInSpace
    if s._shape.space != NULL or s._shape.prev != NULL or (
            s._shape.body != NULL and s._shape.body.shapeList == s._shape):
        raise AlreadyInSpace("cannot re-initialise a shape that is in a space; remove it first")
    if s._body_obj is not None:
        if s._body_obj._shapes is not None:
            s._body_obj._shapes.pop(s, None)
        s._body_obj = None
    return 0

# Copy a shape struct (src: raw bytes laid out as the kind's struct; planes:
# the heap planes of a big polygon) into s, attached to body.
cdef int _shape_copy_struct(Shape s, int kind, const void *src, const void *planes,
                            Py_ssize_t planes_len, Body body) except -1:
    cdef size_t size
    cdef void *dst = _shape_struct(s, kind, &size)
    cdef const cpPolyShape *psrc
    cdef cpPolyShape *poly
    cdef cpSplittingPlane *heap = NULL
    cdef int count = 0
    if kind == 2:
        psrc = <const cpPolyShape *>src
        count = psrc.count
        if count < 1 or count > (1 << 24):
            raise CopyError("the polygon state is corrupt (vertex count)")
        if count > CP_POLY_SHAPE_INLINE_ALLOC:
            if planes == NULL or planes_len != <Py_ssize_t>(2 * count * sizeof(cpSplittingPlane)):
                raise CopyError("the polygon state is corrupt (planes)")
            heap = <cpSplittingPlane *>malloc(2 * count * sizeof(cpSplittingPlane))
            if heap == NULL:
                raise MemoryError()
            memcpy(heap, planes, 2 * count * sizeof(cpSplittingPlane))
    _shape_prepare(s)
    cdef const cpShapeClass *klass = s._shape.klass
    if kind == 2:
        cpShapeDestroy(&(<Poly>s)._poly.shape)     # frees big planes of the old polygon
    memcpy(dst, src, size)
    s._shape.klass = klass
    s._shape.space = NULL
    s._shape.userData = <void *>s
    s._shape.next = NULL
    s._shape.prev = NULL
    s._shape.body = &body._body if body is not None else NULL
    if kind == 2:
        poly = &(<Poly>s)._poly
        poly.planes = heap if heap != NULL else poly._planes
    s._body_obj = body
    if body is not None:
        if body._shapes is None:
            body._shapes = {}
        body._shapes[s] = None
    return 0


def shape_reduce(Shape s not None):
    """``Shape.__reduce_ex__``: the compact state (kind, body, struct bytes,
    user attributes), or pymunk's layout for a subclass that overrides
    ``__getstate__`` / ``__setstate__``.

    >>> import tamias2d
    >>> from tamias2d._snapshot import shape_reduce
    >>> shape_reduce(tamias2d.Circle(None, 1))[2][:2]
    ('tamias2d.Shape/1', 0)
    """
    cls = type(s)
    cdef int kind = _shape_kind(s)
    base = (Circle, Segment, Poly)[kind]
    if (cls.__getstate__ is not base.__getstate__ or cls.__setstate__ is not base.__setstate__
            or cls._pickle_attrs_general is not base._pickle_attrs_general
            or cls._pickle_attrs_init is not base._pickle_attrs_init):
        return (copyreg.__newobj__, (cls,), s.__getstate__())
    data, planes = _shape_bytes(s, kind)
    return (copyreg.__newobj__, (cls,), (SHAPE_TAG, kind, s._body_obj, data, planes, _custom(s)))


def shape_setstate(Shape s not None, tuple state):
    """Restore a shape from :func:`shape_reduce`'s compact state.

    >>> import tamias2d
    >>> from tamias2d._snapshot import shape_reduce, shape_setstate
    >>> c = tamias2d.Circle(None, 3, (1, 2))
    >>> d = tamias2d.Circle(None, 1)
    >>> shape_setstate(d, shape_reduce(c)[2])
    >>> d.radius, d.offset
    (3.0, Vec2d(1.0, 2.0))
    """
    cdef size_t size
    if len(state) != 6 or state[0] != SHAPE_TAG:
        raise CopyError("not a tamias2d shape state (or one from another tamias2d version)")
    _, kind, body, data, planes, custom = state
    if custom is not None and not isinstance(custom, dict):
        raise CopyError("the shape state's attributes are not a dict")
    if kind != _shape_kind(s):
        raise CopyError(f"a shape state of another kind cannot restore a {type(s).__name__}")
    _shape_struct(s, kind, &size)
    if not isinstance(data, bytes) or len(<bytes>data) != <Py_ssize_t>size:
        raise CopyError("the shape state does not match this build of tamias2d")
    if body is not None and not isinstance(body, Body):
        raise CopyError("the shape state's body is not a Body")
    if planes is not None and not isinstance(planes, bytes):
        raise CopyError("the polygon state is corrupt (planes)")
    _shape_copy_struct(s, kind, PyBytes_AS_STRING(data),
                       PyBytes_AS_STRING(planes) if planes is not None else NULL,
                       len(planes) if planes is not None else 0, body)
    # Then what pymunk's restore does with these values: the shape is made
    # again from its init arguments and its attributes set (a polygon's
    # vertices are hulled again, a mass is set then its density). A space's
    # own state restores its shapes exactly, on top of this.
    base = (Circle, Segment, Poly)[kind]
    Shape.__setstate__(s, base.__getstate__(s))
    if custom:
        for k, v in (<dict>custom).items():
            setattr(s, k, v)




# ================================================================================================
# The space snapshot: what the writers and the readers share
# ================================================================================================

# -- capture: the objects of the space, numbered ---------------------------------------------

cdef struct BufRange:
    uintptr_t base
    int index

cdef struct Capture:
    cpSpace *space
    PtrMap bodies              # the body table, in snapshot order
    PtrMap shapes
    PtrMap cons
    PtrMap handlers            # the space's handler set (the global one is never an arbiter's)
    PtrMap arbs                # the cache in its order, those threaded on bodies, this step's
    PtrMap nodes               # both trees, depth first, static first
    PtrMap pairs
    PtrMap handles             # both spatial hashes, static first
    ContactBuffer **bufs       # the contact buffer ring, oldest first, the head last
    int nbufs
    BufRange *sorted_bufs      # buffers by address, to find where contacts are
    int32_t *cached            # arbiter numbers in cache order
    int ncached
    cpSpatialIndex *index[2]   # static, dynamic
    int32_t first[2]           # first node or handle number of each index

cdef void _capture_free(Capture *cap) noexcept nogil:
    free(cap.bufs)
    free(cap.sorted_bufs)
    free(cap.cached)
    pm_free(&cap.bodies)
    pm_free(&cap.shapes)
    pm_free(&cap.cons)
    pm_free(&cap.handlers)
    pm_free(&cap.arbs)
    pm_free(&cap.nodes)
    pm_free(&cap.pairs)
    pm_free(&cap.handles)

cdef inline int32_t _num(PtrMap *m, const void *p) except -2:
    # The number of a pointer that must be known (NULL is -1).
    cdef int32_t k
    if p == NULL:
        return -1
    k = pm_get(m, p)
    if k < 0:
        raise CopyError("internal error: the space links to an object it does not hold")
    return k


# -- restore: everything read from a snapshot, before anything is changed -------------------

cdef enum:
    # What a body is to the space (Parsed.role), from the body arrays.
    ROLE_NONE = 0              # in no array: outside the space (a joint's or an orphan's body)
    ROLE_DYNAMIC = 1           # in the dynamic body array (awake)
    ROLE_STATIC = 2            # in the static body array
    ROLE_ASLEEP = 3            # in the chain of a listed sleeping component

    # What an arbiter is to the space (Parsed.arb_flags).
    ARB_A = 1                  # in body_a's arbiter list
    ARB_B = 2                  # in body_b's arbiter list
    ARB_STEP = 4               # in this step's arbiter array
    ARB_CACHE = 8              # in the arbiter cache

    # Constraint flags (Parsed.con_flags).
    CON_A = 1                  # in body a's constraint list
    CON_B = 2
    CON_STEP = 4               # in the solver's constraint array

cdef struct Parsed:
    SpaceRec s
    SoftRec soft
    const BodyRec *bodies
    const int32_t *views
    const ShapeRec *shapes
    const cpBody *body_structs
    const int32_t *shape_kinds
    const char **shape_at      # each shape's struct in the snapshot (owned)
    const ConstraintRec *cons
    const char **cons_at       # each joint's struct in the snapshot (owned)
    const int32_t *step_cons
    const int32_t *dynamic
    const int32_t *statics
    const int32_t *sleeping
    const HandlerRec *handlers
    const BufferRec *buffers
    const ArbRec *arbs
    const cpContact **contacts_at  # each arbiter's contacts in the snapshot, or NULL (owned)
    const int32_t *step_arbs
    const int32_t *cached
    IndexRec index[2]
    const NodeRec *nodes
    int32_t nnodes
    int32_t npairs
    const PairRec *pairs
    const HandleRec *handles
    int32_t nhandles
    const SetEntry *sets[2]
    const char *cells[2]       # CellRec + handle numbers, back to back
    # Filled by the readers and the checks (owned):
    uint8_t *btype             # body type as its struct reads
    uint8_t *role              # ROLE_* per body
    int32_t *comp              # the root of a sleeping body's component
    int32_t *shape_body        # each shape's body (from the objects given with the snapshot)
    uint8_t *arb_flags         # ARB_* per arbiter
    uint8_t *con_flags         # CON_* per constraint

cdef void _parsed_free(Parsed *p) noexcept nogil:
    free(p.shape_at)
    free(p.cons_at)
    free(p.contacts_at)
    free(p.btype)
    free(p.role)
    free(p.comp)
    free(p.shape_body)
    free(p.arb_flags)
    free(p.con_flags)
    p.shape_at = NULL
    p.cons_at = NULL
    p.contacts_at = NULL
    p.btype = NULL
    p.role = NULL
    p.comp = NULL
    p.shape_body = NULL
    p.arb_flags = NULL
    p.con_flags = NULL

cdef void *_scratch(Py_ssize_t count, size_t size) except NULL:
    # Zeroed scratch for `count` records (count was bounded by the snapshot's
    # length before this is called).
    cdef void *p = cpcalloc(count + 1, size)
    if p == NULL:
        cpTakeOutOfMemory()
        raise MemoryError()
    return p


# Memory the restore takes before it links anything: either all of it is
# handed to the space, or none (and it is freed here).
cdef struct Blocks:
    cpArbiter *arbs
    ContactBuffer **bufs
    cpContact **heap           # per arbiter, the heap contacts of a sleeping one
    Node *nodes[2]
    Pair *pairs
    cpHandle *handles[2]
    cpSpaceHashBin *bins[2]
    cpHashSet *sets[2]
    cpHashSet *cache
    int nbufs
    int narbs
    bint handed                # the blocks belong to the space now

# The objects of the new space, as C pointers in snapshot order.
cdef struct Objects:
    cpBody **bodies
    cpShape **shapes
    cpConstraint **cons
    cpCollisionHandler **handlers




# ================================================================================================
# Sections: one writer and one reader per record type, in snapshot order
# ================================================================================================

# -- header ------------------------------------------------------------------------------------

cdef void _write_header(Writer *w) noexcept nogil:
    cdef Header h
    _fill_header(&h)
    w_put(w, &h, sizeof(Header))

cdef int _read_header(Reader *r) except -1:
    cdef Header expected
    _fill_header(&expected)
    if memcmp(r_take(r, 1, sizeof(Header), "header"), &expected, sizeof(Header)):
        raise CopyError("the snapshot was made by another version or build of tamias2d "
                        "(record layout differs)")
    return 0


# -- space: settings, counters and the count of every section ------------------------------------

cdef int _write_space(Writer *w, Capture *cap, Space sp, list table, int32_t nview,
                      Py_ssize_t nconstraints) except -1:
    cdef cpSpace *space = cap.space
    cdef SpaceRec s
    cdef cpArbiter *arb
    cdef int32_t k
    memset(&s, 0, sizeof(SpaceRec))
    s.gx = space.gravity.x
    s.gy = space.gravity.y
    s.damping = space.damping
    s.idleSpeedThreshold = space.idleSpeedThreshold
    s.sleepTimeThreshold = space.sleepTimeThreshold
    s.collisionSlop = space.collisionSlop
    s.collisionBias = space.collisionBias
    s.curr_dt = space.curr_dt
    s.shapeIDCounter = space.shapeIDCounter
    s.iterations = space.iterations
    s.collisionPersistence = space.collisionPersistence
    s.stamp = space.stamp
    s.nbodies = <int32_t>len(table)
    s.nspace_bodies = <int32_t>len(sp._bodies)
    s.has_static = sp._static_body is not None
    s.nshapes = cap.shapes.count
    s.ndynamic = space.dynamicBodies.num
    s.nstatic = space.staticBodies.num
    s.nsleeping = space.sleepingComponents.num
    s.nhandlers = cap.handlers.count
    s.nbuffers = cap.nbufs
    s.narbiters = cap.arbs.count
    s.nstep_arbiters = space.arbiters.num
    s.ncached = cap.ncached
    s.cached_size = space.cachedArbiters.size
    s.nshape_order = nview
    for k in range(cap.arbs.count):
        arb = <cpArbiter *>cap.arbs.items[k]
        if arb.contacts != NULL:
            s.ncontacts += arb.count
    s.nconstraints = <int32_t>nconstraints
    s.nstep_constraints = space.constraints.num
    w_put(w, &s, sizeof(SpaceRec))
    return 0

cdef enum:
    MAX_ITERATIONS = 100000
    MAX_HASH_TABLE = 1 << 25     # spatial hash buckets (256 MiB, all cleared at every step)

cdef int _read_space(Reader *r, Parsed *p) except -1:
    cdef SpaceRec *s = &p.s
    cdef uint64_t pairs
    r_rec(r, s, sizeof(SpaceRec), "space")
    if (s.nbodies < 0 or s.nspace_bodies < 0 or s.nshapes < 0 or s.ndynamic < 0
            or s.nstatic < 0 or s.nsleeping < 0 or s.nhandlers < 0 or s.nbuffers < 0
            or s.narbiters < 0 or s.nstep_arbiters < 0 or s.ncached < 0 or s.nshape_order < 0
            or s.ncontacts < 0 or s.nconstraints < 0 or s.nstep_constraints < 0
            or s.has_static not in (0, 1)):
        _bad("a count of the space record is negative")
    if s.nspace_bodies + s.has_static > s.nbodies:
        _bad("the space holds more bodies than the snapshot lists")
    if <int64_t>s.ndynamic + s.nstatic + s.nsleeping > s.nbodies:
        _bad("the body arrays hold more entries than there are bodies")
    if s.nstep_arbiters > s.narbiters or s.ncached > s.narbiters:
        _bad("the arbiter arrays hold more entries than there are arbiters")
    if s.nstep_constraints > s.nconstraints:
        _bad("the solver's constraint array holds more entries than there are constraints")
    # The settings as the setters (and the step) need them.
    # The setter takes up to 2**31 - 1; a step then takes minutes. Refused
    # beyond what any scene uses, so that a flipped bit cannot hang the copy.
    if s.iterations < 1 or s.iterations > MAX_ITERATIONS:
        _bad(f"iterations is {s.iterations} (1 to {MAX_ITERATIONS})")
    if not (_modest(s.gx) and _modest(s.gy)):
        _bad(f"gravity ({s.gx}, {s.gy}) is not finite or beyond 1e150")
    if not (_fin(s.damping) and s.damping >= 0.0):
        _bad(f"damping {s.damping} is not a finite number >= 0")
    if not (s.idleSpeedThreshold >= 0.0):
        _bad(f"idle_speed_threshold {s.idleSpeedThreshold} is not a number >= 0")
    if not (s.sleepTimeThreshold >= 0.0):
        _bad(f"sleep_time_threshold {s.sleepTimeThreshold} is not a number >= 0")
    if not _fin(s.collisionSlop):
        _bad(f"collision_slop {s.collisionSlop} is not finite")
    # 1 - pow(bias, dt) is the contacts' bias coefficient: NaN for a
    # negative or non-finite bias.
    if not (_fin(s.collisionBias) and s.collisionBias >= 0.0):
        _bad(f"collision_bias {s.collisionBias} is not a finite number >= 0")
    if not (_fin(s.curr_dt) and s.curr_dt >= 0.0):
        _bad(f"the last time step {s.curr_dt} is not a finite number >= 0")
    if s.sleepTimeThreshold == INFINITY and s.nsleeping:
        # Turning sleeping off wakes every body; the step never wakes them
        # otherwise and threads their arbiters again and again.
        _bad("sleeping is off (sleep_time_threshold is inf) but bodies sleep")
    # The cache holds arbiters of pairs of shapes that existed together.
    pairs = s.shapeIDCounter * (s.shapeIDCounter - 1) // 2 if s.shapeIDCounter < (1 << 31) \
        else (1 << 62)
    _check_set_size(s.cached_size, s.ncached, pairs, "the arbiter cache")
    return 0


cdef void _link_space(cpSpace *space, Parsed *p) noexcept nogil:
    space.iterations = p.s.iterations
    space.gravity.x = p.s.gx
    space.gravity.y = p.s.gy
    space.damping = p.s.damping
    space.idleSpeedThreshold = p.s.idleSpeedThreshold
    space.sleepTimeThreshold = p.s.sleepTimeThreshold
    space.collisionSlop = p.s.collisionSlop
    space.collisionBias = p.s.collisionBias
    space.collisionPersistence = p.s.collisionPersistence
    space.stamp = p.s.stamp
    space.curr_dt = p.s.curr_dt
    space.shapeIDCounter = <cpHashValue>p.s.shapeIDCounter


# -- soft solver settings -----------------------------------------------------------------------

cdef int _write_soft(Writer *w, const cpSpace *space) except -1:
    cdef SoftRec rec
    memset(&rec, 0, sizeof(SoftRec))
    rec.contactHertz = space.soft.contactHertz
    rec.contactDampingRatio = space.soft.contactDampingRatio
    rec.jointHertz = space.soft.jointHertz
    rec.jointDampingRatio = space.soft.jointDampingRatio
    rec.pushOut = space.soft.pushOut
    rec.speculative = space.soft.speculative
    rec.solver = space.soft.solver
    rec.substeps = space.soft.substeps
    w_put(w, &rec, sizeof(SoftRec))
    return 0

cdef enum:
    MAX_SUBSTEPS = 1000000     # what the substeps setter takes

cdef int _read_soft(Reader *r, Parsed *p) except -1:
    cdef SoftRec *rec = &p.soft
    r_rec(r, rec, sizeof(SoftRec), "soft solver settings")
    if rec.solver not in (0, 1):
        _bad(f"the solver is {rec.solver} (0 chipmunk, 1 soft)")
    # As the setters take them; a huge substep count would hang the step.
    if rec.substeps < 1 or rec.substeps > MAX_SUBSTEPS:
        _bad(f"substeps is {rec.substeps} (1 to {MAX_SUBSTEPS})")
    for name, value in (("contact_hertz", rec.contactHertz),
                        ("contact_damping_ratio", rec.contactDampingRatio),
                        ("joint_hertz", rec.jointHertz),
                        ("joint_damping_ratio", rec.jointDampingRatio)):
        if not (_fin(value) and value >= 0.0):
            _bad(f"{name} {value} is not a finite number >= 0")
    # -1 is "derived from collision_slop" (the setters' None).
    if not (rec.pushOut == -1.0 or (_fin(rec.pushOut) and rec.pushOut >= 0.0)):
        _bad(f"contact_push_out {rec.pushOut} is not a finite number >= 0")
    if not (rec.speculative == -1.0 or (_fin(rec.speculative) and rec.speculative >= 0.0)):
        _bad(f"speculative_distance {rec.speculative} is not a finite number >= 0")
    return 0

cdef void _link_soft(cpSpace *space, Parsed *p) noexcept nogil:
    space.soft.contactHertz = p.soft.contactHertz
    space.soft.contactDampingRatio = p.soft.contactDampingRatio
    space.soft.jointHertz = p.soft.jointHertz
    space.soft.jointDampingRatio = p.soft.jointDampingRatio
    space.soft.pushOut = p.soft.pushOut
    space.soft.speculative = p.soft.speculative
    space.soft.solver = p.soft.solver
    space.soft.substeps = p.soft.substeps


# -- body links: lists and component links per body, then the Body.shapes orders ------------

cdef int32_t _view_count(Capture *cap, Body b) noexcept:
    cdef int32_t n = 0
    for s in b._shapes:
        if pm_get(&cap.shapes, (<Shape>s)._shape) >= 0:
            n += 1
    return n

cdef int _write_body_links(Writer *w, Capture *cap, list table) except -1:
    cdef BodyRec rec
    cdef cpBody *body
    cdef int32_t j
    rec.pad = 0
    for obj in table:
        body = &(<Body>obj)._body
        rec.in_space = body.space == cap.space
        rec.shapeList = _num(&cap.shapes, body.shapeList)
        rec.arbiterList = _num(&cap.arbs, body.arbiterList)
        rec.root = _num(&cap.bodies, body.sleeping.root)
        rec.next = _num(&cap.bodies, body.sleeping.next)
        rec.nshapes_view = _view_count(cap, <Body>obj)
        rec.constraintList = _num(&cap.cons, body.constraintList)
        w_put(w, &rec, sizeof(BodyRec))
    for obj in table:
        for s in (<Body>obj)._shapes:
            j = pm_get(&cap.shapes, (<Shape>s)._shape)
            if j >= 0:
                w_i32(w, j)
    return 0

cdef int _read_body_links(Reader *r, Parsed *p) except -1:
    cdef Py_ssize_t nb = p.s.nbodies
    cdef Py_ssize_t n_in = p.s.nspace_bodies + p.s.has_static
    cdef Py_ssize_t total = 0
    cdef int32_t k
    cdef const BodyRec *b
    p.bodies = <const BodyRec *>r_take(r, nb, sizeof(BodyRec), "body links")
    p.btype = <uint8_t *>_scratch(nb, 1)
    p.role = <uint8_t *>_scratch(nb, 1)
    p.comp = <int32_t *>_scratch(nb, sizeof(int32_t))
    for k in range(nb):
        b = &p.bodies[k]
        # Space.bodies and the static body come first, the bodies outside
        # the space (of joints, or of shapes left in the space) after.
        if b.in_space != (1 if k < n_in else 0):
            _bad(f"body {k} is {'outside' if k < n_in else 'in'} the space, "
                 f"but listed {'with' if k < n_in else 'after'} the space's bodies")
        if b.nshapes_view < 0:
            _bad(f"body {k} has a negative count of shapes")
        _check_index(b.shapeList, p.s.nshapes, "body", k, "first shape")
        _check_index(b.arbiterList, p.s.narbiters, "body", k, "first arbiter")
        _check_index(b.root, nb, "body", k, "sleeping root")
        _check_index(b.next, nb, "body", k, "next body in its sleeping component")
        _check_index(b.constraintList, p.s.nconstraints, "body", k, "first constraint")
        total += b.nshapes_view
    if total != p.s.nshape_order:
        _bad("the Body.shapes orders do not add up to their count")
    p.views = <const int32_t *>r_take(r, total, sizeof(int32_t), "Body.shapes orders")
    for k in range(total):
        _check_index(p.views[k], p.s.nshapes, "Body.shapes order entry", k, "the shape", False)
    return 0

cdef void _link_bodies(Parsed *p, Objects *o, cpArbiter *arbs, cpSpace *space) noexcept nogil:
    cdef const BodyRec *br
    cdef cpBody *body
    cdef int32_t i
    for i in range(p.s.nbodies):
        br = &p.bodies[i]
        body = o.bodies[i]
        body.space = space if br.in_space else NULL
        body.shapeList = o.shapes[br.shapeList] if br.shapeList >= 0 else NULL
        body.arbiterList = &arbs[br.arbiterList] if br.arbiterList >= 0 else NULL
        body.constraintList = o.cons[br.constraintList] if br.constraintList >= 0 else NULL
        body.sleeping.root = o.bodies[br.root] if br.root >= 0 else NULL
        body.sleeping.next = o.bodies[br.next] if br.next >= 0 else NULL


# -- shape links: each shape's place in its body's shape list ------------------------------------

cdef int _write_shape_links(Writer *w, Capture *cap) except -1:
    cdef ShapeRec rec
    cdef cpShape *shape
    cdef int32_t i
    rec.pad = 0
    for i in range(cap.shapes.count):
        shape = <cpShape *>cap.shapes.items[i]
        rec.in_space = shape.space == cap.space
        rec.next = _num(&cap.shapes, shape.next)
        rec.prev = _num(&cap.shapes, shape.prev)
        w_put(w, &rec, sizeof(ShapeRec))
    return 0

cdef int _read_shape_links(Reader *r, Parsed *p) except -1:
    cdef int32_t k
    p.shapes = <const ShapeRec *>r_take(r, p.s.nshapes, sizeof(ShapeRec), "shape links")
    for k in range(p.s.nshapes):
        if p.shapes[k].in_space != 1:
            _bad(f"shape {k} is listed by the space but not in it")
        _check_index(p.shapes[k].next, p.s.nshapes, "shape", k, "next shape")
        _check_index(p.shapes[k].prev, p.s.nshapes, "shape", k, "previous shape")
    return 0

# Each shape is in the shape list of its own body, exactly once, with the
# back links of a doubly linked list (removing a shape relinks its
# neighbours, or the head of its body's list).
cdef int _check_shape_lists(Parsed *p) except -1:
    cdef uint8_t *seen = <uint8_t *>_scratch(p.s.nshapes, 1)
    cdef int32_t i, cur, prev
    try:
        for i in range(p.s.nbodies):
            prev = -1
            cur = p.bodies[i].shapeList
            while cur >= 0:
                if seen[cur]:
                    _bad(f"shape {cur} is twice in the shape lists (body {i}'s list loops "
                         f"or runs into another's)")
                if p.shape_body[cur] != i:
                    _bad(f"shape {cur} is in the shape list of body {i}, not of its own body "
                         f"{p.shape_body[cur]}")
                if p.shapes[cur].prev != prev:
                    _bad(f"shape {cur} in body {i}'s shape list has a wrong back link")
                seen[cur] = 1
                prev = cur
                cur = p.shapes[cur].next
        for i in range(p.s.nshapes):
            if not seen[i]:
                _bad(f"shape {i} is missing from the shape list of its body {p.shape_body[i]}")
    finally:
        free(seen)
    return 0

cdef void _link_shapes(Parsed *p, Objects *o, cpSpace *space) noexcept nogil:
    cdef const ShapeRec *sr
    cdef cpShape *shape
    cdef int32_t i
    for i in range(p.s.nshapes):
        sr = &p.shapes[i]
        shape = o.shapes[i]
        shape.space = space if sr.in_space else NULL
        shape.next = o.shapes[sr.next] if sr.next >= 0 else NULL
        shape.prev = o.shapes[sr.prev] if sr.prev >= 0 else NULL


# -- body structs --------------------------------------------------------------------------------

cdef void _put_body(Writer *w, const cpBody *body) noexcept nogil:
    cdef cpBody copy = body[0]
    copy.velocity_func = NULL
    copy.position_func = NULL
    copy.userData = NULL
    copy.space = NULL
    copy.shapeList = NULL
    copy.arbiterList = NULL
    copy.constraintList = NULL
    copy.sleeping.root = NULL
    copy.sleeping.next = NULL
    w_put(w, &copy, sizeof(cpBody))

cdef int _write_body_structs(Writer *w, list table) except -1:
    for obj in table:
        _put_body(w, &(<Body>obj)._body)
    return 0

cdef int _read_body_structs(Reader *r, Parsed *p) except -1:
    cdef int32_t k
    p.body_structs = <const cpBody *>r_take(r, p.s.nbodies, sizeof(cpBody), "body structs")
    for k in range(p.s.nbodies):
        _check_body_struct(k, &p.body_structs[k])
        p.btype[k] = <uint8_t>cpBodyGetType(&p.body_structs[k])
    if p.s.has_static and p.btype[p.s.nspace_bodies] != CP_BODY_TYPE_STATIC:
        _bad(f"the space's static body (body {p.s.nspace_bodies}) is not static")
    return 0

# The numbers of one body: what the setters would accept, and what the
# step keeps finite (it integrates them and divides by the masses).
cdef int _check_body_struct(int32_t k, const cpBody *b) except -1:
    cdef bint static = b.sleeping.idleTime == INFINITY
    if not (b.m >= 0.0):
        _bad(f"body {k} has mass {b.m}")
    if not (b.i >= 0.0):
        _bad(f"body {k} has moment {b.i}")
    if b.m_inv != _inverse(b.m) or b.i_inv != _inverse(b.i):
        _bad(f"body {k}\'s inverse mass or moment ({b.m_inv}, {b.i_inv}) does not match its "
             f"mass and moment ({b.m}, {b.i})")
    # What the setters refuse: a positive mass or moment whose inverse overflows.
    if (0.0 < b.m < INFINITY and not (b.m_inv < INFINITY)) or \
            (0.0 < b.i < INFINITY and not (b.i_inv < INFINITY)):
        _bad(f"body {k} has a mass or moment ({b.m}, {b.i}) too small to invert")
    if static:
        if b.m != INFINITY:
            _bad(f"body {k} is static (its idle time is infinite) but has a finite mass {b.m}")
    elif not (_fin(b.sleeping.idleTime) and b.sleeping.idleTime >= 0.0):
        _bad(f"body {k} has idle time {b.sleeping.idleTime} (a finite number >= 0, or "
             f"infinite for a static body)")
    if not (_finv(b.p) and _finv(b.v) and _finv(b.f) and _fin(b.a) and _fin(b.w)
            and _fin(b.t) and _finv(b.v_bias) and _fin(b.w_bias)):
        _bad(f"body {k} has a position, velocity, force, angle, angular velocity, torque or "
             f"bias velocity that is not finite")
    # The centre of gravity is a lever arm (the shapes hang from it), held
    # to what its square can take, as joint anchors and shape offsets are.
    # (Velocities may be huge: a moment of 1e-300 is valid and spins fast.)
    if not _modestv(b.cog):
        _bad(f"body {k}'s centre of gravity ({b.cog.x}, {b.cog.y}) is not finite or beyond "
             f"1e150")
    # The transform is always a rotation plus a translation (the angle's
    # cosine and sine); the shapes' world geometry is made from it.
    if not (_fin(b.transform.a) and _fin(b.transform.b) and _fin(b.transform.tx)
            and _fin(b.transform.ty) and b.transform.d == b.transform.a
            and b.transform.c == -b.transform.b
            and fabs(b.transform.a * b.transform.a + b.transform.b * b.transform.b - 1.0)
            <= 1e-9):
        _bad(f"body {k}\'s transform is not a finite rotation and translation")
    return 0

# Overwrite a body's struct with exact bytes (links and pointers kept).
cdef void _set_body_struct(Body b, const cpBody *src) noexcept:
    _body_copy_struct(b, src)
    _set_body_funcs(b)




# -- shapes: the kind of each, then its struct (circle, segment, polygon and its planes) ----------

cdef int _write_shapes(Writer *w, list shapes) except -1:
    for obj in shapes:
        w_i32(w, _shape_kind(<Shape>obj))
    for obj in shapes:
        _put_shape(w, <Shape>obj)
    return 0

cdef void _put_shape(Writer *w, Shape s) noexcept:
    # The kind's struct, then a big polygon's planes.
    cdef int kind = _shape_kind(s)
    cdef size_t size
    cdef void *src = _shape_struct(s, kind, &size)
    cdef cpPolyShape poly
    cdef cpCircleShape circle
    cdef cpSegmentShape seg
    cdef cpShape *c
    if kind == 0:
        circle = (<cpCircleShape *>src)[0]
        c = &circle.shape
    elif kind == 1:
        seg = (<cpSegmentShape *>src)[0]
        c = &seg.shape
    else:
        poly = (<cpPolyShape *>src)[0]
        poly.planes = NULL
        c = &poly.shape
    c.klass = NULL
    c.space = NULL
    c.body = NULL
    c.userData = NULL
    c.next = NULL
    c.prev = NULL
    w_put(w, c, size)
    if kind == 2 and poly.count > CP_POLY_SHAPE_INLINE_ALLOC:
        w_put(w, (<Poly>s)._poly.planes, 2 * poly.count * sizeof(cpSplittingPlane))

cdef int _read_shapes(Reader *r, Parsed *p) except -1:
    cdef Py_ssize_t ns = p.s.nshapes
    cdef int32_t k, kind
    cdef const cpPolyShape *poly
    cdef const cpSplittingPlane *planes
    cdef PtrMap ids
    p.shape_kinds = <const int32_t *>r_take(r, ns, sizeof(int32_t), "shape kinds")
    p.shape_at = <const char **>_scratch(ns, sizeof(char *))
    memset(&ids, 0, sizeof(PtrMap))
    pm_init(&ids, ns)
    try:
        for k in range(ns):
            kind = p.shape_kinds[k]
            if kind == 0:
                p.shape_at[k] = r_take(r, 1, sizeof(cpCircleShape), "circle")
                _check_circle(k, <const cpCircleShape *>p.shape_at[k])
            elif kind == 1:
                p.shape_at[k] = r_take(r, 1, sizeof(cpSegmentShape), "segment")
                _check_segment(k, <const cpSegmentShape *>p.shape_at[k])
            elif kind == 2:
                p.shape_at[k] = r_take(r, 1, sizeof(cpPolyShape), "polygon")
                poly = <const cpPolyShape *>p.shape_at[k]
                if poly.count < 1 or poly.count > (1 << 24):
                    _bad(f"polygon {k} has {poly.count} vertices")
                if poly.count > CP_POLY_SHAPE_INLINE_ALLOC:
                    planes = <const cpSplittingPlane *>r_take(
                        r, 2 * poly.count, sizeof(cpSplittingPlane), "polygon planes")
                else:
                    planes = <const cpSplittingPlane *>poly._planes
                _check_poly(k, poly, planes)
            else:
                _bad(f"shape {k} is of an unknown kind {kind}")
            _check_shape_base(k, <const cpShape *>p.shape_at[k], p.s.shapeIDCounter)
            # Ids come from the space's counter and are never handed out twice;
            # key + 1 because 0 marks an empty slot of the map.
            if pm_add(&ids, <void *>(<uintptr_t>(<const cpShape *>p.shape_at[k]).hashid + 1)) != k:
                _bad(f"shape {k} has the hash id of another shape")
    finally:
        pm_free(&ids)
    return 0

# What every shape needs: the numbers the setters refuse, a mass the body
# can accumulate, a cached box the broad phase can use (the spatial hash
# walks its cells), an id the counter has handed out.
cdef int _check_shape_base(int32_t k, const cpShape *s, uint64_t counter) except -1:
    if not (_fin(s.massInfo.m) and s.massInfo.m >= 0.0):
        _bad(f"shape {k} has mass {s.massInfo.m}")
    if s.massInfo.m > 0.0 and not (1.0 / s.massInfo.m < INFINITY):
        _bad(f"shape {k}'s mass {s.massInfo.m} is too small to invert")
    if s.massInfo.m > 0.0 and not (_fin(s.massInfo.i) and _finv(s.massInfo.cog)):
        _bad(f"shape {k} has a mass but its moment or centre of gravity is not finite")
    if not _finbb(s.bb):
        _bad(f"shape {k}\'s cached bounding box ({s.bb.l}, {s.bb.b}, {s.bb.r}, {s.bb.t}) is "
             f"not finite or is inverted")
    if not (_fin(s.e) and s.e >= 0.0 and _fin(s.u) and s.u >= 0.0):
        _bad(f"shape {k} has elasticity {s.e} and friction {s.u} (finite numbers >= 0)")
    if not _finv(s.surfaceV):
        _bad(f"shape {k}\'s surface velocity is not finite")
    if <uint64_t>s.hashid >= counter:
        _bad(f"shape {k} has hash id {s.hashid}, not handed out by the space's counter "
             f"({counter})")
    return 0

# Local geometry (offsets from the body, radii) becomes the contacts' lever
# arms: finite with finite squares, as for joint anchors.
cdef int _check_circle(int32_t k, const cpCircleShape *c) except -1:
    if not (_modestv(c.c) and _finv(c.tc) and _modest(c.r) and c.r >= 0.0):
        _bad(f"circle {k} has a centre or radius ({c.r}) that is not finite or beyond 1e150 "
             f"(or a negative radius)")
    return 0

cdef inline cpVect _edge_normal(cpVect a, cpVect b) noexcept nogil:
    # normalize(rperp(b - a)), as the shape setters compute it ((0, 0) for a == b).
    cdef double dx = b.x - a.x, dy = b.y - a.y
    cdef double f = 1.0 / (sqrt(dx * dx + dy * dy) + 2.2250738585072014e-308)
    cdef cpVect n
    n.x = dy * f
    n.y = -dx * f
    return n

cdef inline bint _near(cpVect u, cpVect v) noexcept nogil:
    return fabs(u.x - v.x) <= 1e-9 and fabs(u.y - v.y) <= 1e-9

cdef int _check_segment(int32_t k, const cpSegmentShape *s) except -1:
    cdef cpVect n = _edge_normal(s.a, s.b), m
    if not (_modestv(s.a) and _modestv(s.b) and _finv(s.n) and _finv(s.ta) and _finv(s.tb)
            and _finv(s.tn) and _finv(s.a_tangent) and _finv(s.b_tangent)
            and _modest(s.r) and s.r >= 0.0):
        _bad(f"segment {k} has an end point, normal or radius ({s.r}) that is not finite or "
             f"beyond 1e150 (or a negative radius)")
    # The collision code takes the normal as given: it must be the end
    # points' (either sign: the constructor and the setter differ).
    m.x = -n.x
    m.y = -n.y
    if not (_near(s.n, n) or _near(s.n, m)):
        _bad(f"segment {k}'s normal does not match its end points")
    return 0

cdef int _check_poly(int32_t k, const cpPolyShape *poly, const cpSplittingPlane *planes) except -1:
    cdef int i
    if not (_modest(poly.r) and poly.r >= 0.0):
        _bad(f"polygon {k} has radius {poly.r}")
    for i in range(2 * poly.count):
        if not (_finv(planes[i].v0) and _finv(planes[i].n)
                and (i < poly.count or _modestv(planes[i].v0))):
            _bad(f"polygon {k} has a vertex or edge normal that is not finite (or a vertex "
                 f"beyond 1e150)")
    # The local planes: each edge's normal is its end points' (the world
    # planes are made from these at every step).
    for i in range(poly.count):
        if not _near(planes[poly.count + i].n,
                     _edge_normal(planes[poly.count + (i + poly.count - 1) % poly.count].v0,
                                  planes[poly.count + i].v0)):
            _bad(f"polygon {k}'s edge normal {i} does not match its vertices")
    return 0

cdef inline bint _near_body(cpVect v, const cpBody *b) noexcept nogil:
    return fabs(v.x - b.p.x) <= 1e150 and fabs(v.y - b.p.y) <= 1e150

# The world geometry a static or sleeping shape keeps (what the narrow phase
# reads until it is reindexed) lies within lever-arm reach of its body.
cdef int _check_shape_geometry(Parsed *p) except -1:
    cdef int32_t k, i
    cdef const cpBody *b
    cdef const cpPolyShape *poly
    cdef const cpSplittingPlane *planes
    cdef bint ok
    for k in range(p.s.nshapes):
        b = &p.body_structs[p.shape_body[k]]
        if p.shape_kinds[k] == 0:
            ok = _near_body((<const cpCircleShape *>p.shape_at[k]).tc, b)
        elif p.shape_kinds[k] == 1:
            ok = (_near_body((<const cpSegmentShape *>p.shape_at[k]).ta, b)
                  and _near_body((<const cpSegmentShape *>p.shape_at[k]).tb, b))
        else:
            poly = <const cpPolyShape *>p.shape_at[k]
            planes = (<const cpSplittingPlane *>(p.shape_at[k] + sizeof(cpPolyShape))
                      if poly.count > CP_POLY_SHAPE_INLINE_ALLOC
                      else <const cpSplittingPlane *>poly._planes)
            ok = True
            for i in range(poly.count):
                ok = ok and _near_body(planes[i].v0, b)
        if not ok:
            _bad(f"shape {k}'s world geometry is more than 1e150 away from its body")
    return 0

# Overwrite a shape's struct with the exact bytes at data (its body, class
# and Python links kept).
cdef int _set_shape_struct(Shape s, int kind, const char *data) except -1:
    cdef size_t size
    cdef void *dst = _shape_struct(s, kind, &size)
    cdef const cpShapeClass *klass = s._shape.klass
    cdef cpBody *body = s._shape.body
    cdef const cpPolyShape *src
    cdef cpPolyShape *poly
    cdef cpSplittingPlane *heap = NULL
    cdef int count
    if kind == 2:
        src = <const cpPolyShape *>data
        count = src.count
        if count > CP_POLY_SHAPE_INLINE_ALLOC:
            heap = <cpSplittingPlane *>malloc(2 * count * sizeof(cpSplittingPlane))
            if heap == NULL:
                raise MemoryError()
            memcpy(heap, data + size, 2 * count * sizeof(cpSplittingPlane))
        cpShapeDestroy(&(<Poly>s)._poly.shape)
    memcpy(dst, data, size)
    s._shape.klass = klass
    s._shape.body = body
    s._shape.userData = <void *>s
    s._shape.space = NULL
    s._shape.next = NULL
    s._shape.prev = NULL
    if kind == 2:
        poly = &(<Poly>s)._poly
        poly.planes = heap if heap != NULL else poly._planes
    return 0


# -- constraints: the link record, the joint struct of its kind, the solver's array --------------

# A joint's struct is copied whole, its pointers aside.
_JOINTS = (PinJoint, SlideJoint, PivotJoint, GrooveJoint, DampedSpring, DampedRotarySpring,
           RotaryLimitJoint, RatchetJoint, GearJoint, SimpleMotor)

cdef int _constraint_kind(Constraint c) except -1:
    cdef int k
    for k in range(10):
        if isinstance(c, _JOINTS[k]):
            return k
    raise TypeError(f"unknown constraint class {type(c).__name__}")

cdef size_t _constraint_size(int kind) noexcept nogil:
    if kind == 0:
        return sizeof(cpPinJoint)
    if kind == 1:
        return sizeof(cpSlideJoint)
    if kind == 2:
        return sizeof(cpPivotJoint)
    if kind == 3:
        return sizeof(cpGrooveJoint)
    if kind == 4:
        return sizeof(cpDampedSpring)
    if kind == 5:
        return sizeof(cpDampedRotarySpring)
    if kind == 6:
        return sizeof(cpRotaryLimitJoint)
    if kind == 7:
        return sizeof(cpRatchetJoint)
    if kind == 8:
        return sizeof(cpGearJoint)
    return sizeof(cpSimpleMotor)

cdef union JointStruct:
    cpConstraint base
    cpPinJoint pin
    cpSlideJoint slide
    cpPivotJoint pivot
    cpGrooveJoint groove
    cpDampedSpring spring
    cpDampedRotarySpring rotary_spring
    cpRotaryLimitJoint rotary_limit
    cpRatchetJoint ratchet
    cpGearJoint gear
    cpSimpleMotor motor

# Copy src's joint struct over dst's, keeping dst's pointers (class, bodies,
# callbacks, user data, spring functions); links cleared.
cdef void _joint_overwrite(cpConstraint *dst, const void *src, int kind) noexcept nogil:
    cdef JointStruct saved
    cdef size_t size = _constraint_size(kind)
    memcpy(&saved, dst, size)
    memcpy(dst, src, size)
    dst.klass = saved.base.klass
    dst.a = saved.base.a
    dst.b = saved.base.b
    dst.preSolve = saved.base.preSolve
    dst.postSolve = saved.base.postSolve
    dst.userData = saved.base.userData
    dst.space = NULL
    dst.next_a = NULL
    dst.next_b = NULL
    if kind == 4:
        (<cpDampedSpring *>dst).springForceFunc = saved.spring.springForceFunc
    elif kind == 5:
        (<cpDampedRotarySpring *>dst).springTorqueFunc = saved.rotary_spring.springTorqueFunc

cdef void _put_joint(Writer *w, const cpConstraint *c, int kind) noexcept nogil:
    cdef JointStruct copy
    cdef size_t size = _constraint_size(kind)
    memcpy(&copy, c, size)
    copy.base.klass = NULL
    copy.base.space = NULL
    copy.base.a = NULL
    copy.base.b = NULL
    copy.base.next_a = NULL
    copy.base.next_b = NULL
    copy.base.preSolve = NULL
    copy.base.postSolve = NULL
    copy.base.userData = NULL
    if kind == 4:
        copy.spring.springForceFunc = NULL
    elif kind == 5:
        copy.rotary_spring.springTorqueFunc = NULL
    w_put(w, &copy, size)



cdef int _write_constraints(Writer *w, Capture *cap, list constraints) except -1:
    cdef ConstraintRec rec
    cdef cpConstraint *con
    cdef int j
    for obj in constraints:
        con = (<Constraint>obj)._constraint
        rec.kind = _constraint_kind(<Constraint>obj)
        rec.a = _num(&cap.bodies, con.a)
        rec.b = _num(&cap.bodies, con.b)
        rec.next_a = _num(&cap.cons, con.next_a)
        rec.next_b = _num(&cap.cons, con.next_b)
        rec.in_space = con.space == cap.space
        w_put(w, &rec, sizeof(ConstraintRec))
    for obj in constraints:
        _put_joint(w, (<Constraint>obj)._constraint, _constraint_kind(<Constraint>obj))
    for j in range(cap.space.constraints.num):
        w_i32(w, _num(&cap.cons, cap.space.constraints.arr[j]))
    return 0

cdef int _read_constraints(Reader *r, Parsed *p) except -1:
    cdef Py_ssize_t nc = p.s.nconstraints
    cdef int32_t k, c
    cdef const ConstraintRec *rec
    p.cons = <const ConstraintRec *>r_take(r, nc, sizeof(ConstraintRec), "constraint links")
    p.cons_at = <const char **>_scratch(nc, sizeof(char *))
    p.con_flags = <uint8_t *>_scratch(nc, 1)
    for k in range(nc):
        rec = &p.cons[k]
        if rec.kind < 0 or rec.kind >= 10:
            _bad(f"constraint {k} is of an unknown kind {rec.kind}")
        _check_index(rec.a, p.s.nbodies, "constraint", k, "body a", False)
        _check_index(rec.b, p.s.nbodies, "constraint", k, "body b", False)
        if rec.a == rec.b:
            _bad(f"constraint {k} joins body {rec.a} to itself")
        _check_index(rec.next_a, nc, "constraint", k, "next constraint of body a")
        _check_index(rec.next_b, nc, "constraint", k, "next constraint of body b")
        if rec.in_space != 1:
            _bad(f"constraint {k} is listed by the space but not in it")
    for k in range(nc):
        p.cons_at[k] = r_take(r, 1, _constraint_size(p.cons[k].kind), _JOINT_NAMES[p.cons[k].kind])
        _check_joint(k, p.cons[k].kind, p.cons_at[k])
    p.step_cons = <const int32_t *>r_take(r, p.s.nstep_constraints, sizeof(int32_t),
                                          "solver constraint array")
    for k in range(p.s.nstep_constraints):
        c = p.step_cons[k]
        _check_index(c, nc, "solver constraint array entry", k, "the constraint", False)
        if p.con_flags[c] & CON_STEP:
            # Freeing the space would loop on it (detaching it once leaves it in the array).
            _bad(f"the solver's constraint array names constraint {c} twice")
        p.con_flags[c] |= CON_STEP
    return 0

_JOINT_NAMES = ("pin joint", "slide joint", "pivot joint", "groove joint", "damped spring",
                "damped rotary spring", "rotary limit joint", "ratchet joint", "gear joint",
                "simple motor")

# The numbers of one joint. Parameters: what its setters accept (within
# +-1e100, above), which a step solves without a NaN (the values the issue
# of finite-but-hopeless parameters lists: a groove of no length, a range
# from inf to inf, a rest length of 1e308, a gear ratio whose inverse
# overflows, a motor rate of 1e308, all refused).
# Accumulated impulses warm-start the next step: finite, with moments that
# stay finite. The other cached values are recomputed by the joint's
# pre-step before they are used.
cdef int _check_joint(int32_t k, int kind, const char *data) except -1:
    cdef const cpConstraint *c = <const cpConstraint *>data
    cdef const cpPinJoint *pin
    cdef const cpSlideJoint *slide
    cdef const cpPivotJoint *pivot
    cdef const cpGrooveJoint *groove
    cdef const cpDampedSpring *spring
    cdef const cpDampedRotarySpring *rspring
    cdef const cpRotaryLimitJoint *limit
    cdef const cpRatchetJoint *ratchet
    cdef const cpGearJoint *gear
    cdef const cpSimpleMotor *motor
    cdef cpVect n
    cdef bint ok = True
    if not (c.maxForce >= 0.0 and _param(c.errorBias) and c.errorBias >= 0.0
            and c.maxBias >= 0.0):
        _bad(f"constraint {k} has max_force {c.maxForce}, error_bias {c.errorBias}, max_bias "
             f"{c.maxBias} (each >= 0, error_bias at most {_JOINT_LIMIT:g})")
    if kind == 0:
        pin = <const cpPinJoint *>data
        ok = (_paramv(pin.anchorA) and _paramv(pin.anchorB) and _param(pin.dist)
              and _impulse(pin.jnAcc, _arm(pin.anchorA, pin.anchorB)))
    elif kind == 1:
        slide = <const cpSlideJoint *>data
        ok = (_paramv(slide.anchorA) and _paramv(slide.anchorB)
              and _limits(slide.min, slide.max)
              and _impulse(slide.jnAcc, _arm(slide.anchorA, slide.anchorB)))
    elif kind == 2:
        pivot = <const cpPivotJoint *>data
        ok = (_paramv(pivot.anchorA) and _paramv(pivot.anchorB)
              and _impulse(pivot.jAcc.x, _arm(pivot.anchorA, pivot.anchorB))
              and _impulse(pivot.jAcc.y, _arm(pivot.anchorA, pivot.anchorB)))
    elif kind == 3:
        groove = <const cpGrooveJoint *>data
        ok = (_paramv(groove.grv_a) and _paramv(groove.grv_b) and _paramv(groove.anchorB)
              and _finv(groove.grv_tn)
              and _impulse(groove.jAcc.x, _arm(groove.grv_a, groove.anchorB))
              and _impulse(groove.jAcc.y, _arm(groove.grv_b, groove.anchorB)))
        if ok:
            if groove.grv_a.x == groove.grv_b.x and groove.grv_a.y == groove.grv_b.y:
                _bad(f"constraint {k} (groove joint) has a groove of no length")
            # The setters keep the groove's normal, perp(normalize(b - a)).
            n = _edge_normal(groove.grv_a, groove.grv_b)
            n.x = -n.x
            n.y = -n.y
            if not _near(groove.grv_n, n):
                _bad(f"constraint {k} (groove joint)'s normal does not match its groove")
    elif kind == 4:
        spring = <const cpDampedSpring *>data
        ok = (_paramv(spring.anchorA) and _paramv(spring.anchorB)
              and _param(spring.restLength) and _param(spring.stiffness)
              and _param(spring.damping) and spring.damping >= 0.0
              and _impulse(spring.jAcc, _arm(spring.anchorA, spring.anchorB)))
    elif kind == 5:
        rspring = <const cpDampedRotarySpring *>data
        ok = (_param(rspring.restAngle) and _param(rspring.stiffness)
              and _param(rspring.damping) and rspring.damping >= 0.0 and _impulse(rspring.jAcc, 1.0))
    elif kind == 6:
        limit = <const cpRotaryLimitJoint *>data
        ok = _limits(limit.min, limit.max) and _impulse(limit.jAcc, 1.0)
    elif kind == 7:
        ratchet = <const cpRatchetJoint *>data
        ok = (_param(ratchet.angle) and _param(ratchet.phase) and _divisor(ratchet.ratchet)
              and _impulse(ratchet.jAcc, 1.0))
    elif kind == 8:
        gear = <const cpGearJoint *>data
        # The setter keeps 1 / ratio beside the ratio; the pre-step uses both
        # (a ratio of 0 is the step's to refuse, as for a gear made so).
        ok = (_param(gear.phase) and _divisor(gear.ratio)
              and gear.ratio_inv == _inverse(gear.ratio) and _impulse(gear.jAcc, 1.0))
    else:
        motor = <const cpSimpleMotor *>data
        ok = _param(motor.rate) and _impulse(motor.jAcc, 1.0)
    if not ok:
        _bad(f"constraint {k} ({_JOINT_NAMES[kind]}) has a parameter the step cannot solve "
             f"(as its setters refuse: not finite, beyond {_JOINT_LIMIT:g}, a negative "
             f"damping) or an accumulated impulse whose moment would overflow")
    return 0

# Every constraint is in the constraint lists of both its bodies, once
# (cpConstraintNext follows next_a where the body is a); a body outside the
# space may have lost it (a body re-initialised while jointed). The solver's
# array holds exactly the constraints whose owner (body a, or b when a is
# static) is awake: sleeping took the others out and waking puts them back.
cdef int _check_constraint_links(Parsed *p) except -1:
    cdef Py_ssize_t n_in = p.s.nspace_bodies + p.s.has_static
    cdef int32_t i, cur, owner
    cdef int side = 0
    cdef const ConstraintRec *c
    for i in range(p.s.nbodies):
        cur = p.bodies[i].constraintList
        while cur >= 0:
            c = &p.cons[cur]
            if c.a == i:
                side = CON_A
            elif c.b == i:
                side = CON_B
            else:
                _bad(f"body {i}'s constraint list holds constraint {cur}, which joins other bodies")
            if p.con_flags[cur] & side:
                _bad(f"body {i}'s constraint list loops (constraint {cur} again)")
            p.con_flags[cur] |= side
            cur = c.next_a if side == CON_A else c.next_b
    for cur in range(p.s.nconstraints):
        c = &p.cons[cur]
        if (not (p.con_flags[cur] & CON_A) and c.a < n_in) or \
                (not (p.con_flags[cur] & CON_B) and c.b < n_in):
            _bad(f"constraint {cur} is missing from the constraint list of body "
                 f"{c.a if not (p.con_flags[cur] & CON_A) else c.b}")
        owner = c.a if p.btype[c.a] != CP_BODY_TYPE_STATIC else c.b
        if p.con_flags[cur] & CON_STEP:
            if p.role[owner] == ROLE_ASLEEP:
                _bad(f"the solver's constraint array names constraint {cur}, whose body "
                     f"{owner} sleeps")
        elif p.role[owner] != ROLE_ASLEEP:
            _bad(f"constraint {cur} is awake (its body {owner} does not sleep) but missing from "
                 f"the solver's constraint array")
    return 0

cdef void _link_constraints(Parsed *p, Objects *o, cpSpace *space) noexcept nogil:
    cdef cpConstraint *con
    cdef const ConstraintRec *rec
    cdef int32_t i
    for i in range(p.s.nconstraints):
        rec = &p.cons[i]
        con = o.cons[i]
        con.space = space if rec.in_space else NULL
        con.next_a = o.cons[rec.next_a] if rec.next_a >= 0 else NULL
        con.next_b = o.cons[rec.next_b] if rec.next_b >= 0 else NULL
    for i in range(p.s.nstep_constraints):
        cpArrayPush(space.constraints, o.cons[p.step_cons[i]])


# -- body arrays: the dynamic and the static body array, the sleeping components' roots -----------

cdef int _write_body_arrays(Writer *w, Capture *cap) except -1:
    cdef cpArray *arr
    cdef int i, j
    for i in range(3):
        arr = (cap.space.dynamicBodies if i == 0 else
               cap.space.staticBodies if i == 1 else cap.space.sleepingComponents)
        for j in range(arr.num):
            w_i32(w, _num(&cap.bodies, arr.arr[j]))
    return 0

cdef int _read_body_arrays(Reader *r, Parsed *p) except -1:
    cdef int32_t k
    p.dynamic = <const int32_t *>r_take(r, p.s.ndynamic, sizeof(int32_t), "dynamic bodies")
    p.statics = <const int32_t *>r_take(r, p.s.nstatic, sizeof(int32_t), "static bodies")
    p.sleeping = <const int32_t *>r_take(r, p.s.nsleeping, sizeof(int32_t), "sleeping roots")
    for k in range(p.s.ndynamic):
        _check_index(p.dynamic[k], p.s.nbodies, "dynamic body array entry", k, "the body", False)
    for k in range(p.s.nstatic):
        _check_index(p.statics[k], p.s.nbodies, "static body array entry", k, "the body", False)
    for k in range(p.s.nsleeping):
        _check_index(p.sleeping[k], p.s.nbodies, "sleeping component root entry", k, "the body", False)
    return 0

# The sleeping code's rules (cpSpaceProcessComponents, FloodFillComponent,
# cpSpaceActivateBody, cpBodyActivate):
# * each body of the space is in exactly one place: the dynamic array
#   (awake dynamic or kinematic), the static array, or the chain of one
#   sleeping component; a body outside the space is in none, or in the
#   dynamic array or a chain when a joint put it there;
# * an awake body has no component links (only sleeping bodies keep them);
# * a sleeping component's root is in the space (waking uses root->space),
#   names itself as root, and its chain (root, next, next, ... NULL) holds
#   dynamic bodies with a valid mass that name it as root; no chain runs
#   into another or loops;
# * a body outside the space whose root is stale (a joint's body the flood
#   fill met once) points at itself (what the step leaves), an awake body or
#   a listed root (what older versions left): waking it from a body that
#   sleeps but is no root would wake half a component.
cdef int _check_components(Parsed *p) except -1:
    cdef Py_ssize_t n_in = p.s.nspace_bodies + p.s.has_static
    cdef int32_t k, i, root, cur
    cdef const cpBody *b
    cdef str where
    for k in range(p.s.ndynamic):
        i = p.dynamic[k]
        if p.role[i] != ROLE_NONE:
            _bad(f"body {i} is twice in the dynamic body array")
        p.role[i] = ROLE_DYNAMIC
        if p.btype[i] == CP_BODY_TYPE_STATIC:
            _bad(f"body {i} is static (its idle time is infinite) but in the dynamic body array")
        if p.bodies[i].root >= 0 or p.bodies[i].next >= 0:
            _bad(f"body {i} is awake (in the dynamic body array) but claims to be in a "
                 f"sleeping component (root {p.bodies[i].root})")
    for k in range(p.s.nstatic):
        i = p.statics[k]
        if p.role[i] != ROLE_NONE:
            _bad(f"body {i} is twice in the body arrays")
        p.role[i] = ROLE_STATIC
        if i >= n_in:
            _bad(f"body {i} is in the static body array but not in the space")
        if p.btype[i] != CP_BODY_TYPE_STATIC:
            _bad(f"body {i} is in the static body array but is not static")
        if p.bodies[i].root >= 0 or p.bodies[i].next >= 0:
            _bad(f"static body {i} claims to be in a sleeping component")
    # The roots first, so that a chain running into another component is
    # told apart from one naming a wrong root.
    for k in range(p.s.nsleeping):
        root = p.sleeping[k]
        if p.role[root] != ROLE_NONE:
            _bad(f"sleeping component root {root} is listed twice, or is in a body array")
        if root >= n_in:
            _bad(f"sleeping component root {root} is not in the space")
        if p.bodies[root].root != root:
            _bad(f"body {root} is listed as a sleeping component's root but names body "
                 f"{p.bodies[root].root} as its root")
        p.role[root] = ROLE_ASLEEP
        p.comp[root] = root
    for k in range(p.s.nsleeping):
        root = p.sleeping[k]
        cur = root
        while cur >= 0:
            if cur != root:
                if p.role[cur] != ROLE_NONE:
                    where = ("another sleeping component (or loops in this one)"
                             if p.role[cur] == ROLE_ASLEEP else "a body array")
                    _bad(f"the sleeping component of body {root} runs into body {cur}, which "
                         f"is in {where}")
                if p.bodies[cur].root != root:
                    _bad(f"body {cur} is in the sleeping component of body {root} but names "
                         f"body {p.bodies[cur].root} as its root")
                p.role[cur] = ROLE_ASLEEP
                p.comp[cur] = root
            b = &p.body_structs[cur]
            if p.btype[cur] != CP_BODY_TYPE_DYNAMIC:
                _bad(f"body {cur} sleeps but reads as "
                     f"{'static (its idle time is infinite)' if p.btype[cur] == CP_BODY_TYPE_STATIC else 'kinematic (its mass is infinite)'}")
            if not (b.m > 0.0 and b.m < INFINITY and b.i > 0.0):
                _bad(f"sleeping body {cur} has mass {b.m} and moment {b.i} (a dynamic body needs "
                     f"0 < mass < inf and moment > 0)")
            cur = p.bodies[cur].next
            if cur == root:
                _bad(f"the sleeping component of body {root} loops back to its root")
    for i in range(p.s.nbodies):
        if p.role[i] != ROLE_NONE:
            continue
        if i < n_in:
            _bad(f"body {i} is in the space but in none of its body arrays or sleeping "
                 f"components")
        root = p.bodies[i].root
        # (A root naming the body itself is the engine's stale root, see
        # _settleOutsideMembers in _space_step.pyx.)
        if root >= 0 and root != i and p.bodies[root].root >= 0 and not (
                p.role[root] == ROLE_ASLEEP and p.comp[root] == root):
            _bad(f"body {i} (outside the space) names body {root} as its sleeping root, which "
                 f"sleeps but is not a component's root")
    return 0

cdef void _link_body_arrays(Parsed *p, Objects *o, cpSpace *space) noexcept nogil:
    cdef int32_t k
    for k in range(p.s.ndynamic):
        cpArrayPush(space.dynamicBodies, o.bodies[p.dynamic[k]])
    for k in range(p.s.nstatic):
        cpArrayPush(space.staticBodies, o.bodies[p.statics[k]])
    for k in range(p.s.nsleeping):
        cpArrayPush(space.sleepingComponents, o.bodies[p.sleeping[k]])




# -- collision handlers: the space's handler set (their callbacks come from Python) -------------

cdef int _number_handlers(Capture *cap) except -1:
    cdef cpHashSetBin *hbin
    cdef unsigned int i
    pm_init(&cap.handlers, 16)
    for i in range(cap.space.collisionHandlers.size):
        hbin = cap.space.collisionHandlers.table[i]
        while hbin != NULL:
            pm_add(&cap.handlers, hbin.elt)
            hbin = hbin.next
    return 0

cdef int _write_handlers(Writer *w, Capture *cap) except -1:
    cdef HandlerRec rec
    cdef cpCollisionHandler *h
    cdef int32_t k
    for k in range(cap.handlers.count):
        h = <cpCollisionHandler *>cap.handlers.items[k]
        rec.typeA = h.typeA
        rec.typeB = h.typeB
        w_put(w, &rec, sizeof(HandlerRec))
    return 0

cdef int _cmp_handler(const void *a, const void *b) noexcept nogil:
    cdef const HandlerRec *x = <const HandlerRec *>a
    cdef const HandlerRec *y = <const HandlerRec *>b
    if x.typeA != y.typeA:
        return -1 if x.typeA < y.typeA else 1
    if x.typeB != y.typeB:
        return -1 if x.typeB < y.typeB else 1
    return 0

cdef int _read_handlers(Reader *r, Parsed *p) except -1:
    cdef Py_ssize_t n = p.s.nhandlers
    cdef HandlerRec *sorted_recs
    cdef int32_t k
    p.handlers = <const HandlerRec *>r_take(r, n, sizeof(HandlerRec), "collision handlers")
    for k in range(n):
        if (p.handlers[k].typeA == <uint64_t>CP_WILDCARD_COLLISION_TYPE
                and p.handlers[k].typeB == <uint64_t>CP_WILDCARD_COLLISION_TYPE):
            _bad(f"handler {k} is the global handler, which is not in the handler set")
    # One handler per ordered pair of types (sorted copy: the count is the
    # snapshot's, a pairwise comparison could take forever).
    sorted_recs = <HandlerRec *>_scratch(n, sizeof(HandlerRec))
    try:
        memcpy(sorted_recs, p.handlers, n * sizeof(HandlerRec))
        qsort(sorted_recs, n, sizeof(HandlerRec), _cmp_handler)
        for k in range(1, n):
            if _cmp_handler(&sorted_recs[k - 1], &sorted_recs[k]) == 0:
                _bad(f"two handlers are for the same collision types ({sorted_recs[k].typeA}, "
                     f"{sorted_recs[k].typeB})")
    finally:
        free(sorted_recs)
    return 0

cdef int _link_handlers(Parsed *p, Objects *o, cpSpace *space) except -1:
    # Before the point of no return: creating a handler can run out of memory.
    cdef int32_t k
    for k in range(p.s.nhandlers):
        o.handlers[k] = cpSpaceAddCollisionHandler(space, <cpCollisionType>p.handlers[k].typeA,
                                                   <cpCollisionType>p.handlers[k].typeB)
        if o.handlers[k] == NULL:
            cpTakeOutOfMemory()
            raise MemoryError()
    return 0

# -1: the do-nothing handler, -2: none (NULL; never in a valid snapshot),
# else a handler of the set.
cdef inline int32_t _handler_num(PtrMap *handlers, cpCollisionHandler *h,
                                 cpCollisionHandler *nothing) except -3:
    if h == NULL:
        return -2
    if h == nothing:
        return -1
    return _num(handlers, h)

cdef inline cpCollisionHandler *_handler_ptr(Objects *o, int32_t i,
                                             cpCollisionHandler *nothing) noexcept nogil:
    return nothing if i == -1 else o.handlers[i]


# -- contact buffers: the ring, oldest first, the head last ---------------------------------------

cdef int _number_buffers(Capture *cap) except -1:
    cdef cpContactBufferHeader *head = cap.space.contactBuffersHead
    cdef cpContactBufferHeader *buf
    cdef int j, n
    if head != NULL:
        n = cap.space.allocatedBuffers.num + 1
        cap.bufs = <ContactBuffer **>malloc(n * sizeof(ContactBuffer *))
        if cap.bufs == NULL:
            raise MemoryError()
        buf = head.next
        while True:
            if cap.nbufs >= n:
                raise CopyError("internal error: the contact buffer ring is broken")
            cap.bufs[cap.nbufs] = <ContactBuffer *>buf
            cap.nbufs += 1
            if buf == head:
                break
            buf = buf.next
    # By address, for finding where an arbiter's contacts are.
    cap.sorted_bufs = <BufRange *>malloc((cap.nbufs + 1) * sizeof(BufRange))
    if cap.sorted_bufs == NULL:
        raise MemoryError()
    for j in range(cap.nbufs):
        cap.sorted_bufs[j].base = <uintptr_t>&cap.bufs[j].contacts[0]
        cap.sorted_bufs[j].index = j
    qsort(cap.sorted_bufs, cap.nbufs, sizeof(BufRange), _cmp_range)
    return 0

cdef int _write_buffers(Writer *w, Capture *cap) except -1:
    cdef BufferRec rec
    cdef int j
    for j in range(cap.nbufs):
        rec.stamp = cap.bufs[j].header.stamp
        rec.numContacts = cap.bufs[j].header.numContacts
        w_put(w, &rec, sizeof(BufferRec))
    return 0

cdef int _read_buffers(Reader *r, Parsed *p) except -1:
    cdef int32_t k
    p.buffers = <const BufferRec *>r_take(r, p.s.nbuffers, sizeof(BufferRec), "contact buffers")
    for k in range(p.s.nbuffers):
        if p.buffers[k].numContacts > CONTACTS_PER_BUFFER:
            _bad(f"contact buffer {k} holds {p.buffers[k].numContacts} contacts, more than fit")
    return 0

cdef void _link_buffers(Parsed *p, Blocks *m, cpSpace *space) noexcept nogil:
    cdef ContactBuffer *buf
    cdef int j
    for j in range(m.nbufs):
        buf = m.bufs[j]
        buf.header.stamp = p.buffers[j].stamp
        buf.header.numContacts = p.buffers[j].numContacts
        buf.header.next = &m.bufs[(j + 1) % m.nbufs].header
    space.contactBuffersHead = &m.bufs[m.nbufs - 1].header if m.nbufs > 0 else NULL


# -- arbiters: the records, their contacts, this step's array, the cache order --------------------

cdef int _cmp_range(const void *a, const void *b) noexcept nogil:
    cdef uintptr_t x = (<const BufRange *>a).base
    cdef uintptr_t y = (<const BufRange *>b).base
    return -1 if x < y else (1 if x > y else 0)

# The number of the buffer whose contacts hold addr, or -1.
cdef int _find_buffer(const BufRange *r, int n, uintptr_t addr) noexcept nogil:
    cdef int lo = 0, hi = n - 1, mid
    while lo <= hi:
        mid = (lo + hi) // 2
        if addr < r[mid].base:
            hi = mid - 1
        elif addr >= r[mid].base + CONTACTS_PER_BUFFER * sizeof(cpContact):
            lo = mid + 1
        else:
            return r[mid].index
    return -1

cdef int _number_arbiters(Capture *cap) except -1:
    # The cache (in its order), those threaded on bodies (sleeping ones are
    # out of the cache), and this step's array.
    cdef cpSpace *space = cap.space
    cdef cpHashSetBin *hbin
    cdef cpArbiter *arb
    cdef cpBody *body
    cdef unsigned int i
    cdef int32_t k
    pm_init(&cap.arbs, 64 + space.cachedArbiters.entries)
    cap.cached = <int32_t *>malloc((space.cachedArbiters.entries + 1) * sizeof(int32_t))
    if cap.cached == NULL:
        raise MemoryError()
    for i in range(space.cachedArbiters.size):
        hbin = space.cachedArbiters.table[i]
        while hbin != NULL:
            if cap.ncached >= <int>space.cachedArbiters.entries:
                raise CopyError("internal error: the arbiter cache is inconsistent")
            cap.cached[cap.ncached] = pm_add(&cap.arbs, hbin.elt)
            cap.ncached += 1
            hbin = hbin.next
    for k in range(cap.bodies.count):
        body = <cpBody *>cap.bodies.items[k]
        arb = body.arbiterList
        while arb != NULL:
            pm_add(&cap.arbs, arb)
            arb = cpArbiterNext(arb, body)
    for k in range(space.arbiters.num):
        pm_add(&cap.arbs, space.arbiters.arr[k])
    return 0

cdef int _write_arbiters(Writer *w, Capture *cap) except -1:
    cdef ArbRec rec
    cdef cpArbiter *arb
    cdef cpCollisionHandler *nothing = cpCollisionHandlerDoNothing()
    cdef uintptr_t addr, base
    cdef int32_t k
    cdef int j
    for k in range(cap.arbs.count):
        arb = <cpArbiter *>cap.arbs.items[k]
        rec.e = arb.e
        rec.u = arb.u
        rec.svr_x = arb.surface_vr.x
        rec.svr_y = arb.surface_vr.y
        rec.n_x = arb.n.x
        rec.n_y = arb.n.y
        rec.a = _num(&cap.shapes, arb.a)
        rec.b = _num(&cap.shapes, arb.b)
        rec.body_a = _num(&cap.bodies, arb.body_a)
        rec.body_b = _num(&cap.bodies, arb.body_b)
        rec.ta_next = _num(&cap.arbs, arb.thread_a.next)
        rec.ta_prev = _num(&cap.arbs, arb.thread_a.prev)
        rec.tb_next = _num(&cap.arbs, arb.thread_b.next)
        rec.tb_prev = _num(&cap.arbs, arb.thread_b.prev)
        rec.count = arb.count
        rec.ckind = 0
        rec.cbuf = -1
        rec.coff = 0
        if arb.contacts != NULL:
            # In a buffer of the ring (awake), else on the heap (asleep).
            rec.ckind = 2
            addr = <uintptr_t>arb.contacts
            j = _find_buffer(cap.sorted_bufs, cap.nbufs, addr)
            if j >= 0:
                base = <uintptr_t>&cap.bufs[j].contacts[0]
                if (addr - base) % sizeof(cpContact) != 0:
                    raise CopyError("internal error: misaligned contacts")
                rec.ckind = 1
                rec.cbuf = j
                rec.coff = <int32_t>((addr - base) // sizeof(cpContact))
                if rec.coff + arb.count > CONTACTS_PER_BUFFER:
                    raise CopyError("internal error: contacts overrun their buffer")
        rec.handlerAB = _handler_num(&cap.handlers, arb.handlerAB, nothing)
        rec.handlerBA = _handler_num(&cap.handlers, arb.handlerBA, nothing)
        rec.handlerA = _handler_num(&cap.handlers, arb.handlerA, nothing)
        rec.handlerB = _handler_num(&cap.handlers, arb.handlerB, nothing)
        rec.stamp = arb.stamp
        rec.state = <uint32_t>arb.state
        rec.swapped = arb.swapped
        rec.processCollision = arb.processCollision
        w_put(w, &rec, sizeof(ArbRec))
    for k in range(cap.arbs.count):
        arb = <cpArbiter *>cap.arbs.items[k]
        if arb.contacts != NULL and arb.count > 0:
            w_put(w, arb.contacts, arb.count * sizeof(cpContact))
    for j in range(cap.space.arbiters.num):
        w_i32(w, _num(&cap.arbs, cap.space.arbiters.arr[j]))
    w_put(w, cap.cached, cap.ncached * sizeof(int32_t))
    return 0

cdef int _read_arbiters(Reader *r, Parsed *p) except -1:
    cdef Py_ssize_t na = p.s.narbiters
    cdef Py_ssize_t total = 0
    cdef const char *contacts
    cdef const cpContact *con
    cdef int32_t k, i, c
    p.arbs = <const ArbRec *>r_take(r, na, sizeof(ArbRec), "arbiters")
    p.contacts_at = <const cpContact **>_scratch(na, sizeof(cpContact *))
    p.arb_flags = <uint8_t *>_scratch(na, 1)
    for k in range(na):
        _check_arbiter(k, &p.arbs[k], p)
        if p.arbs[k].ckind != 0:
            total += p.arbs[k].count
    if total != p.s.ncontacts:
        _bad("the arbiters' contacts do not add up to their count")
    contacts = r_take(r, total, sizeof(cpContact), "contacts")
    for k in range(na):
        if p.arbs[k].ckind == 0:
            continue
        p.contacts_at[k] = <const cpContact *>contacts
        for i in range(p.arbs[k].count):
            con = <const cpContact *>contacts + i
            # The solver's inputs. The warm start applies the impulses at the
            # offsets, to static bodies too (whose zero inverse mass times an
            # overflowed product is NaN): offsets and impulses whose products
            # stay finite.
            if not (_modestv(con.r1) and _modestv(con.r2) and _fin(con.nMass)
                    and _fin(con.tMass) and _fin(con.bounce) and _fin(con.jBias)
                    and _fin(con.bias)
                    and _impulse(con.jnAcc, _arm(con.r1, con.r2))
                    and _impulse(con.jtAcc, _arm(con.r1, con.r2))):
                _bad(f"contact {i} of arbiter {k} has a number that is not finite, an offset "
                     f"beyond 1e150 or an impulse whose moment would overflow")
        contacts += p.arbs[k].count * sizeof(cpContact)
    p.step_arbs = <const int32_t *>r_take(r, p.s.nstep_arbiters, sizeof(int32_t),
                                          "step arbiter array")
    for k in range(p.s.nstep_arbiters):
        c = p.step_arbs[k]
        _check_index(c, na, "step arbiter array entry", k, "the arbiter", False)
        if p.arb_flags[c] & ARB_STEP:
            _bad(f"this step's arbiter array names arbiter {c} twice")
        p.arb_flags[c] |= ARB_STEP
    p.cached = <const int32_t *>r_take(r, p.s.ncached, sizeof(int32_t), "arbiter cache")
    for k in range(p.s.ncached):
        c = p.cached[k]
        _check_index(c, na, "arbiter cache entry", k, "the arbiter", False)
        if p.arb_flags[c] & ARB_CACHE:
            _bad(f"the arbiter cache holds arbiter {c} twice")
        p.arb_flags[c] |= ARB_CACHE
    return 0

# One arbiter on its own: the shapes and bodies it joins, its handlers (the
# step calls all four), where its contacts are, numbers the solver uses.
cdef int _check_arbiter(int32_t k, const ArbRec *a, Parsed *p) except -1:
    cdef int32_t h
    cdef int32_t hs[4]
    cdef int j
    _check_index(a.a, p.s.nshapes, "arbiter", k, "shape a", False)
    _check_index(a.b, p.s.nshapes, "arbiter", k, "shape b", False)
    if a.a == a.b:
        _bad(f"arbiter {k} is between shape {a.a} and itself")
    _check_index(a.body_a, p.s.nbodies, "arbiter", k, "body a", False)
    _check_index(a.body_b, p.s.nbodies, "arbiter", k, "body b", False)
    if a.body_a == a.body_b:
        _bad(f"arbiter {k} is between body {a.body_a} and itself")
    _check_index(a.ta_next, p.s.narbiters, "arbiter", k, "next arbiter of body a")
    _check_index(a.ta_prev, p.s.narbiters, "arbiter", k, "previous arbiter of body a")
    _check_index(a.tb_next, p.s.narbiters, "arbiter", k, "next arbiter of body b")
    _check_index(a.tb_prev, p.s.narbiters, "arbiter", k, "previous arbiter of body b")
    hs[0] = a.handlerAB
    hs[1] = a.handlerBA
    hs[2] = a.handlerA
    hs[3] = a.handlerB
    for j in range(4):
        h = hs[j]
        if h == -2:
            _bad(f"arbiter {k} has no collision handler (the step calls every one of its "
                 f"handlers)")
        if h < -1 or h >= p.s.nhandlers:
            _bad(f"arbiter {k}\'s collision handler {h} is out of range")
    if a.count < 0 or a.count > 2:
        _bad(f"arbiter {k} has {a.count} contacts")
    if a.ckind < 0 or a.ckind > 2:
        _bad(f"arbiter {k} has its contacts in an unknown place ({a.ckind})")
    if a.ckind == 0 and a.count != 0:
        _bad(f"arbiter {k} has {a.count} contacts but no contact storage")
    if a.state > 4:
        _bad(f"arbiter {k} is in an unknown state {a.state}")
    if a.ckind == 1:
        _check_index(a.cbuf, p.s.nbuffers, "arbiter", k, "contact buffer", False)
        if a.coff < 0 or a.coff + a.count > CONTACTS_PER_BUFFER:
            _bad(f"arbiter {k}\'s contacts overrun their contact buffer")
    if not (_fin(a.e) and a.e >= 0.0 and _fin(a.u) and a.u >= 0.0 and _fin(a.svr_x)
            and _fin(a.svr_y)):
        _bad(f"arbiter {k} has restitution {a.e}, friction {a.u} or a surface velocity that "
             f"is not finite (or negative)")
    if not (_fin(a.n_x) and _fin(a.n_y) and a.n_x * a.n_x + a.n_y * a.n_y <= 1.0 + 1e-6):
        _bad(f"arbiter {k}\'s normal ({a.n_x}, {a.n_y}) is not a unit (or zero) vector")
    return 0

cdef inline uint8_t _arb_side(const ArbRec *a, int32_t body) noexcept nogil:
    return ARB_A if a.body_a == body else (ARB_B if a.body_b == body else 0)

cdef int _check_sleeping_contact(Parsed *p, int32_t k, int32_t x, int32_t y) except -1:
    if p.role[x] == ROLE_ASLEEP and p.btype[y] != CP_BODY_TYPE_STATIC and not (
            p.role[y] == ROLE_ASLEEP and p.comp[y] == p.comp[x]):
        _bad(f"sleeping body {x} touches body {y} (arbiter {k}), which is neither static nor "
             f"in its sleeping component")
    return 0

cdef int _cmp_pair(const void *a, const void *b) noexcept nogil:
    cdef const int64_t *x = <const int64_t *>a
    cdef const int64_t *y = <const int64_t *>b
    return -1 if x[0] < y[0] else (1 if x[0] > y[0] else 0)

# The contact graph, as the step, the sleeping code and the arbiter cache use it:
# * an arbiter's bodies are its shapes' bodies;
# * each body's arbiter list is a proper doubly linked list of arbiters of
#   that body (cpArbiterNext, and unthreading relinks the neighbours); an
#   arbiter is in both its bodies' lists or in neither, and one in neither
#   has no links (threading it again keeps a stale back link);
# * a threaded arbiter with a sleeping body: the other body is static or
#   sleeps in the same component; it is out of the cache and of this step's
#   array, and its contacts are on the heap (waking copies them back to a
#   buffer and frees them);
# * a threaded arbiter of awake bodies is in this step's array (the next
#   step unthreads only those; another would be threaded twice and the
#   flood fill would never end);
# * this step's array holds threaded arbiters of awake bodies (usually in
#   the cache too, but a step run with a persistence of 0 lets them go from
#   it at once);
# * only a sleeping arbiter keeps its contacts on the heap;
# * the cache holds each pair of shapes once (a second one would not be inserted).
cdef int _check_arbiter_links(Parsed *p) except -1:
    cdef int32_t i, k, cur, prev, nxt, x, y
    cdef const ArbRec *a
    cdef uint8_t side, f
    cdef bint asleep_a, asleep_b
    cdef int64_t *keys
    for k in range(p.s.narbiters):
        a = &p.arbs[k]
        if p.shape_body[a.a] != a.body_a or p.shape_body[a.b] != a.body_b:
            _bad(f"arbiter {k}\'s bodies are not the bodies of its shapes")
    for i in range(p.s.nbodies):
        prev = -1
        cur = p.bodies[i].arbiterList
        while cur >= 0:
            a = &p.arbs[cur]
            side = _arb_side(a, i)
            if side == 0:
                _bad(f"body {i}'s arbiter list holds arbiter {cur}, which is between other bodies")
            if p.arb_flags[cur] & side:
                _bad(f"body {i}'s arbiter list loops (arbiter {cur} again)")
            p.arb_flags[cur] |= side
            if (a.ta_prev if side == ARB_A else a.tb_prev) != prev:
                _bad(f"arbiter {cur} in body {i}'s arbiter list has a wrong back link")
            nxt = a.ta_next if side == ARB_A else a.tb_next
            prev = cur
            cur = nxt
    for i in range(p.s.nstep_arbiters):
        k = p.step_arbs[i]
        a = &p.arbs[k]
        f = p.arb_flags[k]
        if p.role[a.body_a] == ROLE_ASLEEP or p.role[a.body_b] == ROLE_ASLEEP:
            _bad(f"this step's arbiter array names arbiter {k}, whose bodies sleep")
        if not (f & ARB_A and f & ARB_B):
            _bad(f"this step's arbiter array names arbiter {k}, which is not in its bodies' "
                 f"arbiter lists")
    for k in range(p.s.narbiters):
        a = &p.arbs[k]
        f = p.arb_flags[k]
        if not (f & ARB_A) and (a.ta_prev != -1 or a.ta_next != -1):
            _bad(f"arbiter {k} links into body {a.body_a}'s arbiter list but is not in it")
        if not (f & ARB_B) and (a.tb_prev != -1 or a.tb_next != -1):
            _bad(f"arbiter {k} links into body {a.body_b}'s arbiter list but is not in it")
        if bool(f & ARB_A) != bool(f & ARB_B):
            _bad(f"arbiter {k} is in the arbiter list of only one of its bodies")
        asleep_a = p.role[a.body_a] == ROLE_ASLEEP
        asleep_b = p.role[a.body_b] == ROLE_ASLEEP
        if f & ARB_A:
            if asleep_a or asleep_b:
                _check_sleeping_contact(p, k, a.body_a, a.body_b)
                _check_sleeping_contact(p, k, a.body_b, a.body_a)
                if f & ARB_CACHE:
                    _bad(f"the arbiter cache holds arbiter {k}, whose bodies sleep")
                if a.ckind == 1:
                    _bad(f"arbiter {k} sleeps but keeps its contacts in a contact buffer (waking "
                         f"frees them: they must be on the heap)")
            elif not (f & ARB_STEP):
                _bad(f"arbiter {k} of awake bodies is in their arbiter lists but not in this "
                     f"step's arbiter array (the next step would thread it twice)")
        if a.ckind == 2 and not ((f & ARB_A) and (asleep_a or asleep_b)):
            _bad(f"arbiter {k} keeps its contacts on the heap but does not sleep")
    keys = <int64_t *>_scratch(p.s.ncached, sizeof(int64_t))
    try:
        for k in range(p.s.ncached):
            a = &p.arbs[p.cached[k]]
            x = a.a if a.a < a.b else a.b
            y = a.b if a.a < a.b else a.a
            keys[k] = (<int64_t>x << 32) | y
        qsort(keys, p.s.ncached, sizeof(int64_t), _cmp_pair)
        for k in range(1, p.s.ncached):
            if keys[k] == keys[k - 1]:
                _bad(f"the arbiter cache holds two arbiters of shapes {keys[k] >> 32} and "
                     f"{keys[k] & 0xFFFFFFFF}")
    finally:
        free(keys)
    return 0

cdef void _link_arbiters(Parsed *p, Objects *o, Blocks *m, cpSpace *space) noexcept nogil:
    cdef cpCollisionHandler *nothing = cpCollisionHandlerDoNothing()
    cdef const ArbRec *ar
    cdef cpArbiter *arb
    cdef cpArbiter *arbs = m.arbs
    cdef cpShape *pair_key[2]
    cdef int32_t k
    for k in range(m.narbs):
        ar = &p.arbs[k]
        arb = &arbs[k]
        arb.e = ar.e
        arb.u = ar.u
        arb.surface_vr.x = ar.svr_x
        arb.surface_vr.y = ar.svr_y
        arb.n.x = ar.n_x
        arb.n.y = ar.n_y
        arb.data = NULL
        arb.a = o.shapes[ar.a]
        arb.b = o.shapes[ar.b]
        arb.body_a = o.bodies[ar.body_a]
        arb.body_b = o.bodies[ar.body_b]
        arb.thread_a.next = &arbs[ar.ta_next] if ar.ta_next >= 0 else NULL
        arb.thread_a.prev = &arbs[ar.ta_prev] if ar.ta_prev >= 0 else NULL
        arb.thread_b.next = &arbs[ar.tb_next] if ar.tb_next >= 0 else NULL
        arb.thread_b.prev = &arbs[ar.tb_prev] if ar.tb_prev >= 0 else NULL
        arb.count = ar.count
        if ar.ckind == 0:
            arb.contacts = NULL
        else:
            if ar.ckind == 1:
                arb.contacts = &m.bufs[ar.cbuf].contacts[ar.coff]
            else:
                arb.contacts = m.heap[k]
                m.heap[k] = NULL
            memcpy(arb.contacts, p.contacts_at[k], ar.count * sizeof(cpContact))
        arb.handlerAB = _handler_ptr(o, ar.handlerAB, nothing)
        arb.handlerBA = _handler_ptr(o, ar.handlerBA, nothing)
        arb.handlerA = _handler_ptr(o, ar.handlerA, nothing)
        arb.handlerB = _handler_ptr(o, ar.handlerB, nothing)
        arb.swapped = ar.swapped
        arb.stamp = ar.stamp
        arb.state = <cpArbiterState>ar.state
        arb.processCollision = ar.processCollision
    for k in range(p.s.nstep_arbiters):
        cpArrayPush(space.arbiters, &arbs[p.step_arbs[k]])
    for k in range(p.s.ncached):
        arb = &arbs[p.cached[k]]
        pair_key[0] = <cpShape *>arb.a
        pair_key[1] = <cpShape *>arb.b
        if cpHashSetInsert(space.cachedArbiters, CP_HASH_PAIR(<cpHashValue>arb.a, <cpHashValue>arb.b),
                           pair_key, NULL, arb) == arb:
            arb.cached = 1




# -- indexes: the static and the dynamic broad phase (both BB trees or both spatial hashes) --------

cdef int _number_indexes(Capture *cap) except -1:
    # Nodes (depth first, static tree first) or handles (cells, then the
    # set's order), then the pairs of the tree leaves.
    cdef cpSpaceHash *hsh
    cdef cpSpaceHashBin *sbin
    cdef cpHashSetBin *hbin
    cdef Node *node
    cdef Pair *pair
    cdef int j
    cdef Py_ssize_t i, ns = cap.shapes.count
    cap.index[0] = cap.space.staticShapes
    cap.index[1] = cap.space.dynamicShapes
    if cap.index[0].klass != cap.index[1].klass:
        raise CopyError("internal error: the static and dynamic indexes differ in kind")
    pm_init(&cap.nodes, 2 * ns + 16)
    pm_init(&cap.handles, ns + 16)
    for j in range(2):
        if cap.index[j].klass == cpBBTreeClass():
            cap.first[j] = cap.nodes.count
            _number_tree(<cpBBTree *>cap.index[j], &cap.nodes)
        elif cap.index[j].klass == cpSpaceHashClass():
            hsh = <cpSpaceHash *>cap.index[j]
            cap.first[j] = cap.handles.count
            for i in range(hsh.numcells):
                sbin = hsh.table[i]
                while sbin != NULL:
                    pm_add(&cap.handles, sbin.handle)
                    sbin = sbin.next
            for i in range(hsh.handleSet.size):
                hbin = hsh.handleSet.table[i]
                while hbin != NULL:
                    pm_add(&cap.handles, hbin.elt)
                    hbin = hbin.next
        else:
            raise CopyError("unknown spatial index")
    pm_init(&cap.pairs, cap.nodes.count + 16)
    for i in range(cap.nodes.count):
        node = <Node *>cap.nodes.items[i]
        if node.obj == NULL:
            continue
        pair = node.node.leaf.pairs
        while pair != NULL:
            pm_add(&cap.pairs, pair)
            pair = pair.a.next if pair.a.leaf == node else pair.b.next
    return 0

cdef int _write_indexes(Writer *w, Capture *cap) except -1:
    cdef IndexRec rec
    cdef cpBBTree *tree
    cdef cpSpaceHash *hsh
    cdef cpSpaceHashBin *sbin
    cdef Py_ssize_t i
    cdef int j
    for j in range(2):
        memset(&rec, 0, sizeof(IndexRec))
        rec.first = cap.first[j]
        if cap.index[j].klass == cpBBTreeClass():
            tree = <cpBBTree *>cap.index[j]
            rec.kind = 1
            rec.stamp = tree.stamp
            rec.root = _num(&cap.nodes, tree.root)
            rec.count = (cap.nodes.count if j == 1 else cap.first[1]) - cap.first[j]
            rec.set_size = tree.leaves.size
            rec.set_count = tree.leaves.entries
            rec.has_velocity = tree.velocityFunc != NULL
            rec.reach = tree.staticReach
        else:
            hsh = <cpSpaceHash *>cap.index[j]
            rec.kind = 2
            rec.celldim = hsh.celldim
            rec.stamp = hsh.stamp
            rec.root = -1
            rec.count = (cap.handles.count if j == 1 else cap.first[1]) - cap.first[j]
            rec.set_size = hsh.handleSet.size
            rec.set_count = hsh.handleSet.entries
            rec.numcells = hsh.numcells
            for i in range(hsh.numcells):
                sbin = hsh.table[i]
                if sbin != NULL:
                    rec.ncells += 1
                while sbin != NULL:
                    rec.nbins += 1
                    sbin = sbin.next
        w_put(w, &rec, sizeof(IndexRec))
    return 0

cdef int _read_indexes(Reader *r, Parsed *p) except -1:
    cdef Py_ssize_t nnodes = 0, nhandles = 0
    cdef IndexRec *x
    cdef str name
    cdef int j
    r_rec(r, &p.index[0], sizeof(IndexRec), "static index")
    r_rec(r, &p.index[1], sizeof(IndexRec), "dynamic index")
    if p.index[0].kind != p.index[1].kind or p.index[0].kind not in (1, 2):
        _bad("the broad phase is of an unknown kind, or the two indexes differ in kind")
    for j in range(2):
        x = &p.index[j]
        name = "the static index" if j == 0 else "the dynamic index"
        if x.count < 0 or x.set_count < 0 or x.ncells < 0 or x.nbins < 0:
            _bad(f"{name} has a negative count")
        if x.first != (nnodes if x.kind == 1 else nhandles):
            _bad(f"{name}'s nodes or handles do not follow the other index's")
        if x.kind == 1:
            nnodes += x.count
        else:
            nhandles += x.count
        if nnodes > 0x7FFFFFFF or nhandles > 0x7FFFFFFF:
            _bad("the broad phase counts overflow")
        # Every shape in the index is in its set, keyed by its hash id; ids
        # are never handed out twice, so a set held at most that many.
        _check_set_size(x.set_size, x.set_count, p.s.shapeIDCounter,
                        f"the {'leaf' if x.kind == 1 else 'handle'} set of {name}")
        if x.kind == 1 and not (_fin(x.reach) and x.reach >= 0.0):
            _bad(f"{name} reaches {x.reach} into the static tree (a finite number >= 0)")
        if x.kind == 2:
            # use_spatial_hash(celldim, numcells) makes them again.
            if not (_fin(x.celldim) and x.celldim > 0.0):
                _bad(f"{name} has cell size {x.celldim}")
            if x.numcells < 1 or next_prime(x.numcells) != x.numcells \
                    or x.numcells > MAX_HASH_TABLE:
                _bad(f"{name} has {x.numcells} cells, not a size a spatial hash can have "
                     f"(a table prime up to {MAX_HASH_TABLE})")
            if x.ncells > x.numcells:
                _bad(f"{name} has more non-empty cells than cells")
    if p.index[0].kind == 2 and (p.index[0].celldim != p.index[1].celldim
                                 or p.index[0].numcells != p.index[1].numcells):
        _bad("the two spatial hashes differ in cell size or cell count")
    p.nnodes = <int32_t>nnodes
    p.nhandles = <int32_t>nhandles
    return 0

# Each shape is in exactly one index, and the right one: the static index
# holds the shapes of static and of sleeping bodies, the dynamic index the
# others (shape removal and waking look for a shape only where it belongs).
cdef int _check_index_membership(Parsed *p) except -1:
    cdef uint8_t *where = <uint8_t *>_scratch(p.s.nshapes, 1)
    cdef int32_t k, s, b, first, count
    cdef int j
    cdef bint static
    try:
        for j in range(2):
            first = p.index[j].first
            count = p.index[j].count
            if p.index[j].kind == 1:
                for k in range(first, first + count):
                    s = p.nodes[k].obj
                    if s >= 0:
                        if where[s]:
                            _bad(f"shape {s} is twice in the broad phase")
                        where[s] = 1 + j
            else:
                for k in range(p.index[j].set_count):
                    s = p.handles[p.sets[j][k].elt].obj
                    if where[s]:
                        _bad(f"shape {s} is twice in the broad phase")
                    where[s] = 1 + j
        for s in range(p.s.nshapes):
            b = p.shape_body[s]
            static = p.btype[b] == CP_BODY_TYPE_STATIC or p.role[b] == ROLE_ASLEEP
            if where[s] == 0:
                _bad(f"shape {s} is in neither index of the broad phase")
            if (where[s] == 1) != static:
                _bad(f"shape {s} is in the {'static' if where[s] == 1 else 'dynamic'} index, but "
                     f"its body {b} is {'static or asleep' if static else 'awake and not static'}")
    finally:
        free(where)
    return 0


# -- tree nodes ------------------------------------------------------------------------------------

# Nodes of a BB tree in depth-first order (A before B), appended to `nodes`.
cdef int _number_tree(cpBBTree *tree, PtrMap *nodes) except -1:
    cdef Node **stack = NULL
    cdef int top = 0, cap = 64
    cdef Node *node
    cdef Node **grown
    if tree.root == NULL:
        return 0
    stack = <Node **>malloc(cap * sizeof(Node *))
    if stack == NULL:
        raise MemoryError()
    try:
        stack[0] = tree.root
        top = 1
        while top > 0:
            top -= 1
            node = stack[top]
            pm_add(nodes, node)
            if node.obj == NULL:
                if top + 2 > cap:
                    cap *= 2
                    grown = <Node **>cprealloc(stack, cap * sizeof(Node *))
                    if grown == NULL:
                        cpTakeOutOfMemory()
                        raise MemoryError()
                    stack = grown
                stack[top] = node.node.children.b
                stack[top + 1] = node.node.children.a
                top += 2
    finally:
        free(stack)
    return 0

cdef int _write_nodes(Writer *w, Capture *cap) except -1:
    cdef NodeRec rec
    cdef Node *node
    cdef int32_t k
    for k in range(cap.nodes.count):
        node = <Node *>cap.nodes.items[k]
        rec.l = node.bb.l
        rec.b = node.bb.b
        rec.r = node.bb.r
        rec.t = node.bb.t
        rec.parent = _num(&cap.nodes, node.parent)
        if node.obj != NULL:
            rec.obj = _num(&cap.shapes, node.obj)
            rec.a = -1
            rec.bchild = -1
            rec.stamp = node.node.leaf.stamp
            rec.pairs = _num(&cap.pairs, node.node.leaf.pairs)
        else:
            rec.obj = -1
            rec.a = _num(&cap.nodes, node.node.children.a)
            rec.bchild = _num(&cap.nodes, node.node.children.b)
            rec.stamp = 0
            rec.pairs = -1
        w_put(w, &rec, sizeof(NodeRec))
    return 0

cdef inline bint _contains(const NodeRec *n, const NodeRec *c) noexcept nogil:
    return n.l <= c.l and n.b <= c.b and n.r >= c.r and n.t >= c.t

cdef int _read_nodes(Reader *r, Parsed *p) except -1:
    cdef int32_t k, first, count
    cdef const NodeRec *n
    cdef int j
    cdef uint32_t master = p.index[1].stamp
    p.nodes = <const NodeRec *>r_take(r, p.nnodes, sizeof(NodeRec), "tree nodes")
    for j in range(2):
        if p.index[j].kind != 1:
            continue
        first = p.index[j].first
        count = p.index[j].count
        if p.index[j].root != -1:
            _check_range(p.index[j].root, first, count, "tree", j, "root")
            if p.nodes[p.index[j].root].parent != -1:
                _bad(f"the root of tree {j} has a parent")
        elif count:
            _bad(f"tree {j} has nodes but no root")
        for k in range(first, first + count):
            n = &p.nodes[k]
            if not (_fin(n.l) and _fin(n.b) and _fin(n.r) and _fin(n.t) and n.l <= n.r
                    and n.b <= n.t):
                _bad(f"tree node {k}'s box is not finite or is inverted")
            if n.parent != -1:
                _check_range(n.parent, first, count, "tree node", k, "parent")
            if n.obj >= 0:
                _check_index(n.obj, p.s.nshapes, "tree leaf", k, "shape", False)
                # A leaf's stamp is the dynamic tree's stamp when it moved;
                # the tree's stamp moves on after every pass.
                if n.stamp >= master:
                    _bad(f"tree leaf {k}'s stamp {n.stamp} is not behind its tree's ({master})")
            elif n.obj != -1:
                _bad(f"tree node {k} has shape {n.obj}")
            else:
                _check_range(n.a, first, count, "tree node", k, "child a")
                _check_range(n.bchild, first, count, "tree node", k, "child b")
                if n.a == n.bchild or p.nodes[n.a].parent != k or p.nodes[n.bchild].parent != k:
                    _bad(f"tree node {k}'s children do not name it as their parent")
                # Queries only descend into nodes whose box they meet.
                if not (_contains(n, &p.nodes[n.a]) and _contains(n, &p.nodes[n.bchild])):
                    _bad(f"tree node {k}'s box does not contain its children's")
    return 0

# A tree is one binary tree: every node reachable from the root once, and
# its leaf set holds exactly its leaves, keyed by their shapes' hash ids
# (removal finds a leaf by its shape's id), bucket by bucket.
cdef int _check_tree(Parsed *p, int j) except -1:
    cdef int32_t first = p.index[j].first, count = p.index[j].count
    cdef int32_t *stack = <int32_t *>_scratch(count + 2, sizeof(int32_t))
    cdef uint8_t *seen = <uint8_t *>_scratch(count, 1)
    cdef int32_t top = 0, found = 0, cur, k
    cdef const NodeRec *n
    cdef const SetEntry *e
    try:
        if p.index[j].root >= 0:
            stack[0] = p.index[j].root
            top = 1
        while top > 0:
            top -= 1
            cur = stack[top]
            found += 1
            if found > count or seen[cur - first]:
                _bad(f"tree {j} is not a tree (node {cur} is reached twice)")
            seen[cur - first] = 1
            n = &p.nodes[cur]
            if n.obj < 0:
                stack[top] = n.a
                stack[top + 1] = n.bchild
                top += 2
        if found != count:
            _bad(f"tree {j} has nodes its root does not reach")
        memset(seen, 0, count)
        for k in range(p.index[j].set_count):
            e = &p.sets[j][k]
            if seen[e.elt - first]:
                _bad(f"the leaf set of tree {j} holds leaf {e.elt} twice")
            seen[e.elt - first] = 1
            if <uint64_t>e.hash != <uint64_t>(<const cpShape *>p.shape_at[p.nodes[e.elt].obj]).hashid:
                _bad(f"the leaf set of tree {j} files leaf {e.elt} under another hash id than "
                     f"its shape's")
            if k > 0 and e.hash % p.index[j].set_size < p.sets[j][k - 1].hash % p.index[j].set_size:
                _bad(f"the leaf set of tree {j} is out of bucket order")
        for k in range(first, first + count):
            if p.nodes[k].obj >= 0 and not seen[k - first]:
                _bad(f"tree leaf {k} is missing from its tree's leaf set")
    finally:
        free(stack)
        free(seen)
    return 0

cdef void _link_tree(cpBBTree *tree, Parsed *p, int j, Node *block, Pair *pairs,
                     cpShape **shapes) noexcept nogil:
    cdef int32_t first = p.index[j].first
    cdef int32_t k
    cdef const NodeRec *r
    cdef Node *node
    cdef const SetEntry *e
    for k in range(p.index[j].count):
        r = &p.nodes[first + k]
        node = &block[k]
        node.bb.l = r.l
        node.bb.b = r.b
        node.bb.r = r.r
        node.bb.t = r.t
        node.parent = &block[r.parent - first] if r.parent >= 0 else NULL
        if r.obj >= 0:
            node.obj = shapes[r.obj]
            node.node.leaf.stamp = r.stamp
            node.node.leaf.pairs = &pairs[r.pairs] if r.pairs >= 0 else NULL
        else:
            node.obj = NULL
            node.node.children.a = &block[r.a - first]
            node.node.children.b = &block[r.bchild - first]
    tree.root = &block[p.index[j].root - first] if p.index[j].root >= 0 else NULL
    # (Its leaves' boxes were not told to its fat-box function.)
    tree.fatSynced = 0
    tree.stamp = p.index[j].stamp
    tree.staticReach = p.index[j].reach
    # Head insertion reverses: insert each bucket's chain backwards.
    for k in range(p.index[j].set_count - 1, -1, -1):
        e = &p.sets[j][k]
        node = &block[e.elt - first]
        cpHashSetInsert(tree.leaves, <cpHashValue>e.hash, node.obj, NULL, node)


# -- pairs: the dynamic tree's cache of leaf pairs -------------------------------------------------

cdef int _write_pairs(Writer *w, Capture *cap) except -1:
    cdef PairRec rec
    cdef Pair *pair
    cdef int32_t k
    rec.pad = 0
    w_i32(w, cap.pairs.count)
    for k in range(cap.pairs.count):
        pair = <Pair *>cap.pairs.items[k]
        rec.a_leaf = _num(&cap.nodes, pair.a.leaf)
        rec.a_prev = _num(&cap.pairs, pair.a.prev)
        rec.a_next = _num(&cap.pairs, pair.a.next)
        rec.b_leaf = _num(&cap.nodes, pair.b.leaf)
        rec.b_prev = _num(&cap.pairs, pair.b.prev)
        rec.b_next = _num(&cap.pairs, pair.b.next)
        rec.id = pair.slot.id
        w_put(w, &rec, sizeof(PairRec))
    return 0

cdef int _read_pairs(Reader *r, Parsed *p) except -1:
    cdef int32_t k
    cdef const PairRec *q
    r_rec(r, &p.npairs, sizeof(int32_t), "pair count")
    if p.npairs < 0 or (p.npairs and p.index[0].kind != 1):
        _bad(f"the broad phase has {p.npairs} pairs")
    p.pairs = <const PairRec *>r_take(r, p.npairs, sizeof(PairRec), "pairs")
    for k in range(p.nnodes):
        if p.nodes[k].obj >= 0:
            _check_index(p.nodes[k].pairs, p.npairs, "tree leaf", k, "first pair")
    for k in range(p.npairs):
        q = &p.pairs[k]
        _check_index(q.a_leaf, p.nnodes, "pair", k, "leaf a", False)
        _check_index(q.b_leaf, p.nnodes, "pair", k, "leaf b", False)
        if p.nodes[q.a_leaf].obj < 0 or p.nodes[q.b_leaf].obj < 0 or q.a_leaf == q.b_leaf:
            _bad(f"pair {k} is not between two leaves")
        _check_index(q.a_prev, p.npairs, "pair", k, "previous pair of leaf a")
        _check_index(q.a_next, p.npairs, "pair", k, "next pair of leaf a")
        _check_index(q.b_prev, p.npairs, "pair", k, "previous pair of leaf b")
        _check_index(q.b_next, p.npairs, "pair", k, "next pair of leaf b")
    return 0

# Each leaf's pairs form a doubly linked list (side a or b of each pair,
# as ThreadUnlink relinks them), and every pair is in the lists of its two
# leaves, once each.
cdef int _check_pairs(Parsed *p) except -1:
    cdef Py_ssize_t steps = 0
    cdef int32_t k, cur, prev, nxt = -1
    cdef const PairRec *q
    for k in range(p.nnodes):
        if p.nodes[k].obj < 0:
            continue
        prev = -1
        cur = p.nodes[k].pairs
        while cur >= 0:
            q = &p.pairs[cur]
            steps += 1
            if steps > 2 * p.npairs:
                _bad(f"the pair list of leaf {k} loops")
            if q.a_leaf == k:
                if q.a_prev != prev:
                    _bad(f"pair {cur} in leaf {k}'s list has a wrong back link")
                nxt = q.a_next
            elif q.b_leaf == k:
                if q.b_prev != prev:
                    _bad(f"pair {cur} in leaf {k}'s list has a wrong back link")
                nxt = q.b_next
            else:
                _bad(f"leaf {k}'s pair list holds pair {cur} of other leaves")
            prev = cur
            cur = nxt
    if steps != 2 * p.npairs:
        _bad("a pair is missing from its leaves' pair lists")
    return 0

cdef inline Node *_node_at(Parsed *p, Node **blocks, int32_t g) noexcept nogil:
    # Node number -> node, whichever tree it is in.
    if g >= p.index[1].first and g - p.index[1].first < p.index[1].count:
        return &blocks[1][g - p.index[1].first]
    return &blocks[0][g - p.index[0].first]

cdef void _link_pairs(Parsed *p, Node **blocks, Pair *pairs) noexcept nogil:
    cdef int32_t k
    cdef const PairRec *r
    cdef Pair *q
    for k in range(p.npairs):
        r = &p.pairs[k]
        q = &pairs[k]
        q.a.leaf = _node_at(p, blocks, r.a_leaf)
        q.a.prev = &pairs[r.a_prev] if r.a_prev >= 0 else NULL
        q.a.next = &pairs[r.a_next] if r.a_next >= 0 else NULL
        q.b.leaf = _node_at(p, blocks, r.b_leaf)
        q.b.prev = &pairs[r.b_prev] if r.b_prev >= 0 else NULL
        q.b.next = &pairs[r.b_next] if r.b_next >= 0 else NULL
        q.slot.id = r.id
        q.slot.arbiter = NULL   # a guess, not state: the copy looks its arbiters up


# -- handles: the spatial hashes' reference-counted handles ---------------------------------------

cdef int _write_handles(Writer *w, Capture *cap) except -1:
    cdef HandleRec rec
    cdef cpHandle *hand
    cdef int32_t k
    rec.pad = 0
    for k in range(cap.handles.count):
        hand = <cpHandle *>cap.handles.items[k]
        rec.obj = _num(&cap.shapes, hand.obj)
        rec.retain = hand.retain
        rec.stamp = hand.stamp
        w_put(w, &rec, sizeof(HandleRec))
    return 0

cdef int _read_handles(Reader *r, Parsed *p) except -1:
    cdef int32_t k
    p.handles = <const HandleRec *>r_take(r, p.nhandles, sizeof(HandleRec), "handles")
    for k in range(p.nhandles):
        # -1: a removed shape's handle, left in its cells until a query unlinks it.
        _check_index(p.handles[k].obj, p.s.nshapes, "handle", k, "shape")
    return 0


# -- sets and cells: per index, the leaf or handle set bucket by bucket, then the hash cells ------

cdef int _write_set(Writer *w, cpHashSet *set, PtrMap *elts) except -1:
    # Entries in iteration order (bucket by bucket, chain order) with their hash.
    cdef unsigned int i
    cdef cpHashSetBin *bin
    cdef SetEntry e
    memset(&e, 0, sizeof(SetEntry))
    for i in range(set.size):
        bin = set.table[i]
        while bin != NULL:
            e.hash = bin.hash
            e.elt = _num(elts, bin.elt)
            w_put(w, &e, sizeof(SetEntry))
            bin = bin.next
    return 0

cdef int _write_sets(Writer *w, Capture *cap) except -1:
    cdef cpSpaceHash *hsh
    cdef cpSpaceHashBin *sbin
    cdef CellRec rec
    cdef Py_ssize_t i
    cdef int j
    for j in range(2):
        if cap.index[j].klass == cpBBTreeClass():
            _write_set(w, (<cpBBTree *>cap.index[j]).leaves, &cap.nodes)
            continue
        hsh = <cpSpaceHash *>cap.index[j]
        _write_set(w, hsh.handleSet, &cap.handles)
        for i in range(hsh.numcells):
            sbin = hsh.table[i]
            if sbin == NULL:
                continue
            rec.cell = <int32_t>i
            rec.length = 0
            while sbin != NULL:
                rec.length += 1
                sbin = sbin.next
            w_put(w, &rec, sizeof(CellRec))
            sbin = hsh.table[i]
            while sbin != NULL:
                w_i32(w, _num(&cap.handles, sbin.handle))
                sbin = sbin.next
    return 0

cdef int _read_sets(Reader *r, Parsed *p) except -1:
    cdef int32_t k, c, first, count, prev_cell
    cdef Py_ssize_t total
    cdef const CellRec *cell
    cdef const int32_t *ids
    cdef const SetEntry *e
    cdef int j
    for j in range(2):
        first = p.index[j].first
        count = p.index[j].count
        p.sets[j] = <const SetEntry *>r_take(r, p.index[j].set_count, sizeof(SetEntry),
                                             "leaf set" if p.index[j].kind == 1 else "handle set")
        for k in range(p.index[j].set_count):
            e = &p.sets[j][k]
            _check_range(e.elt, first, count, "set entry", k, "element")
            if p.index[j].kind == 1 and p.nodes[e.elt].obj < 0:
                _bad(f"the leaf set of tree {j} holds internal node {e.elt}")
            if p.index[j].kind == 2 and p.handles[e.elt].obj < 0:
                _bad(f"the handle set of hash {j} holds the handle of a removed shape")
        p.cells[j] = r.data + r.pos
        if p.index[j].kind != 2:
            continue
        total = 0
        prev_cell = -1
        for c in range(p.index[j].ncells):
            cell = <const CellRec *>r_take(r, 1, sizeof(CellRec), "hash cell")
            if cell.cell < 0 or cell.cell >= p.index[j].numcells or cell.length <= 0:
                _bad(f"hash cell record {c} of hash {j} is out of range or empty")
            # One record per non-empty cell, in table order (a second record
            # for a cell would replace the first one's chain).
            if cell.cell <= prev_cell:
                _bad(f"hash {j} lists cell {cell.cell} twice or out of order")
            prev_cell = cell.cell
            total += cell.length
            ids = <const int32_t *>r_take(r, cell.length, sizeof(int32_t), "hash cell handles")
            for k in range(cell.length):
                _check_range(ids[k], first, count, "hash cell", cell.cell, "handle")
        if total != p.index[j].nbins:
            _bad(f"the cells of hash {j} do not add up to their count")
    return 0

# A spatial hash: each handle's count is the cells it is in plus one for
# the set (releasing it to 0 pools it: a count off by one frees a handle
# still in use, or never); a handle is in a cell once; the set holds each
# live handle keyed by its shape's hash id, bucket by bucket; and hashing
# the shapes visits a bounded number of cells (every step rehashes the
# dynamic shapes, waking a body hashes its shapes with their cached boxes:
# a box spanning millions of cells would hang the step or the destructor).
cdef int _check_hash(Parsed *p, int j) except -1:
    cdef int32_t first = p.index[j].first, count = p.index[j].count
    cdef int32_t *cells = <int32_t *>_scratch(count, sizeof(int32_t))
    cdef int32_t *last = <int32_t *>_scratch(count, sizeof(int32_t))
    cdef uint8_t *inset = <uint8_t *>_scratch(count, 1)
    cdef const char *cur = p.cells[j]
    cdef const CellRec *cell
    cdef const int32_t *ids
    cdef const SetEntry *e
    cdef int32_t c, k, h, s
    try:
        for c in range(p.index[j].ncells):
            cell = <const CellRec *>cur
            ids = <const int32_t *>(cur + sizeof(CellRec))
            cur += sizeof(CellRec) + cell.length * sizeof(int32_t)
            for k in range(cell.length):
                h = ids[k] - first
                if last[h] == cell.cell + 1:
                    _bad(f"handle {ids[k]} is twice in cell {cell.cell} of hash {j}")
                last[h] = cell.cell + 1
                cells[h] += 1
        for k in range(p.index[j].set_count):
            e = &p.sets[j][k]
            h = e.elt - first
            if inset[h]:
                _bad(f"the handle set of hash {j} holds handle {e.elt} twice")
            inset[h] = 1
            s = p.handles[e.elt].obj
            if <uint64_t>e.hash != <uint64_t>(<const cpShape *>p.shape_at[s]).hashid:
                _bad(f"the handle set of hash {j} files shape {s} under another hash id than its own")
            if k > 0 and e.hash % p.index[j].set_size < p.sets[j][k - 1].hash % p.index[j].set_size:
                _bad(f"the handle set of hash {j} is out of bucket order")
        for k in range(count):
            if inset[k] != (p.handles[first + k].obj >= 0):
                _bad(f"handle {first + k} of hash {j} is {'in' if inset[k] else 'out of'} the set "
                     f"but its shape is {'removed' if inset[k] else 'live'}")
            if p.handles[first + k].retain != cells[k] + inset[k]:
                _bad(f"handle {first + k} of hash {j} counts {p.handles[first + k].retain} "
                     f"references but is in {cells[k]} cells{' and the set' if inset[k] else ''}")
    finally:
        free(cells)
        free(last)
        free(inset)
    return 0

# Cells of the spatial hash's grid a box spans (what hashHandle walks),
# as a float so that no count overflows.
cdef inline double _grid_cells(double l, double b, double r, double t, double dim) noexcept nogil:
    return (floor(r / dim) - floor(l / dim) + 1.0) * (floor(t / dim) - floor(b / dim) + 1.0)

cdef double _shape_cells(Parsed *p, int32_t s, double dim) noexcept nogil:
    # The larger of its cached box and the box its geometry has at its
    # body's transform (what the next rehash computes).
    cdef const cpShape *shape = <const cpShape *>p.shape_at[s]
    cdef const cpBody *body = &p.body_structs[p.shape_body[s]]
    cdef double l, b, r, t, x, y, rad, cached
    cdef const cpCircleShape *circle
    cdef const cpSegmentShape *seg
    cdef const cpPolyShape *poly
    cdef const cpSplittingPlane *planes
    cdef int i, kind = p.shape_kinds[s]
    cached = _grid_cells(shape.bb.l, shape.bb.b, shape.bb.r, shape.bb.t, dim)
    if kind == 0:
        circle = <const cpCircleShape *>shape
        l = r = body.transform.a * circle.c.x + body.transform.c * circle.c.y + body.transform.tx
        b = t = body.transform.b * circle.c.x + body.transform.d * circle.c.y + body.transform.ty
        rad = circle.r
    elif kind == 1:
        seg = <const cpSegmentShape *>shape
        l = r = body.transform.a * seg.a.x + body.transform.c * seg.a.y + body.transform.tx
        b = t = body.transform.b * seg.a.x + body.transform.d * seg.a.y + body.transform.ty
        x = body.transform.a * seg.b.x + body.transform.c * seg.b.y + body.transform.tx
        y = body.transform.b * seg.b.x + body.transform.d * seg.b.y + body.transform.ty
        l = x if x < l else l
        r = x if x > r else r
        b = y if y < b else b
        t = y if y > t else t
        rad = seg.r
    else:
        poly = <const cpPolyShape *>shape
        planes = (<const cpSplittingPlane *>(p.shape_at[s] + sizeof(cpPolyShape))
                  if poly.count > CP_POLY_SHAPE_INLINE_ALLOC
                  else <const cpSplittingPlane *>poly._planes)
        l = b = INFINITY
        r = t = -INFINITY
        for i in range(poly.count, 2 * poly.count):
            x = body.transform.a * planes[i].v0.x + body.transform.c * planes[i].v0.y + body.transform.tx
            y = body.transform.b * planes[i].v0.x + body.transform.d * planes[i].v0.y + body.transform.ty
            l = x if x < l else l
            r = x if x > r else r
            b = y if y < b else b
            t = y if y > t else t
        rad = poly.r
    x = _grid_cells(l - rad, b - rad, r + rad, t + rad, dim)
    return x if x > cached else cached

cdef enum:
    # Grid cells all shapes of a spatial hash may span together: at a few
    # nanoseconds a cell, a rehash stays well under a second.
    MAX_HASH_CELLS = 1 << 24

cdef int _check_hash_cost(Parsed *p) except -1:
    cdef double total = 0.0
    cdef int32_t k
    cdef int j
    for j in range(2):
        for k in range(p.index[j].set_count):
            total += _shape_cells(p, p.handles[p.sets[j][k].elt].obj, p.index[j].celldim)
    if not (total <= MAX_HASH_CELLS):
        _bad(f"the spatial hash's shapes span {total:.3g} cells of {p.index[0].celldim} "
             f"(more than {MAX_HASH_CELLS}: hashing them would not end in reasonable time)")
    return 0

cdef void _link_hash(cpSpaceHash *hsh, Parsed *p, int j, cpHandle *handles,
                     cpSpaceHashBin *bins, cpShape **shapes) noexcept nogil:
    cdef int32_t first = p.index[j].first
    cdef int32_t k, c, nbin = 0
    cdef const HandleRec *r
    cdef cpHandle *hand
    cdef const SetEntry *e
    cdef const char *cur = p.cells[j]
    cdef const CellRec *cell
    cdef const int32_t *ids
    cdef cpSpaceHashBin *prev
    for k in range(p.index[j].count):
        r = &p.handles[first + k]
        hand = &handles[k]
        hand.obj = shapes[r.obj] if r.obj >= 0 else NULL
        hand.retain = r.retain
        hand.stamp = r.stamp
    hsh.stamp = p.index[j].stamp
    for k in range(p.index[j].set_count - 1, -1, -1):
        e = &p.sets[j][k]
        hand = &handles[e.elt - first]
        cpHashSetInsert(hsh.handleSet, <cpHashValue>e.hash, hand.obj, NULL, hand)
    for c in range(p.index[j].ncells):
        cell = <const CellRec *>cur
        ids = <const int32_t *>(cur + sizeof(CellRec))
        cur += sizeof(CellRec) + cell.length * sizeof(int32_t)
        prev = NULL
        for k in range(cell.length):
            bins[nbin].handle = &handles[ids[k] - first]
            bins[nbin].next = NULL
            if prev == NULL:
                hsh.table[cell.cell] = &bins[nbin]
            else:
                prev.next = &bins[nbin]
            prev = &bins[nbin]
            nbin += 1




# ================================================================================================
# Capture: number the objects, then every writer in snapshot order
# ================================================================================================

cdef int _number_objects(Capture *cap, list table, list shapes, list constraints) except -1:
    cdef cpConstraint *con
    pm_init(&cap.bodies, len(table))
    for obj in table:
        pm_add(&cap.bodies, &(<Body>obj)._body)
    pm_init(&cap.shapes, len(shapes))
    for obj in shapes:
        pm_add(&cap.shapes, (<Shape>obj)._shape)
        if pm_get(&cap.bodies, (<Shape>obj)._shape.body) < 0:
            raise CopyError("internal error: a shape's body is missing from the table")
    pm_init(&cap.cons, len(constraints))
    for obj in constraints:
        con = (<Constraint>obj)._constraint
        pm_add(&cap.cons, con)
        if pm_get(&cap.bodies, con.a) < 0 or pm_get(&cap.bodies, con.b) < 0:
            raise CopyError("internal error: a constraint's body is missing from the table")
    return 0

cdef bytes _capture(Space sp, list table, list shapes, list constraints):
    cdef Capture cap
    cdef Writer w
    cdef int32_t nview = 0
    memset(&cap, 0, sizeof(Capture))
    cap.space = &sp._space
    w_init(&w, 4096 + 300 * len(table) + 100 * len(shapes))
    try:
        if cap.space.rousedBodies.num != 0:
            raise SpaceLocked("a space cannot be copied while bodies are being woken")
        _number_objects(&cap, table, shapes, constraints)
        _number_handlers(&cap)
        _number_buffers(&cap)
        _number_arbiters(&cap)
        _number_indexes(&cap)
        for obj in table:
            nview += _view_count(&cap, <Body>obj)

        _write_header(&w)
        _write_space(&w, &cap, sp, table, nview, len(constraints))
        _write_soft(&w, cap.space)
        _write_body_links(&w, &cap, table)
        _write_shape_links(&w, &cap)
        _write_body_structs(&w, table)
        _write_shapes(&w, shapes)
        _write_constraints(&w, &cap, constraints)
        _write_body_arrays(&w, &cap)
        _write_handlers(&w, &cap)
        _write_buffers(&w, &cap)
        _write_arbiters(&w, &cap)
        _write_indexes(&w, &cap)
        _write_nodes(&w, &cap)
        _write_pairs(&w, &cap)
        _write_handles(&w, &cap)
        _write_sets(&w, &cap)
        if w.failed:
            cpTakeOutOfMemory()
            raise MemoryError()
        return PyBytes_FromStringAndSize(w.data, w.len)
    finally:
        free(w.data)
        _capture_free(&cap)


# ================================================================================================
# Restore: every reader, the objects, every cross-record check, then the links
# ================================================================================================

cdef int _parse(bytes blob, Parsed *p, list log) except -1:
    # Reads and checks each section; changes nothing.
    cdef Reader r
    cdef int j
    r.data = PyBytes_AS_STRING(blob)
    r.len = <size_t>PyBytes_GET_SIZE(blob)
    r.pos = 0
    r.log = <void *>log if log is not None else NULL
    _read_header(&r)
    _read_space(&r, p)
    _read_soft(&r, p)
    _read_body_links(&r, p)
    _read_shape_links(&r, p)
    _read_body_structs(&r, p)
    _read_shapes(&r, p)
    _read_constraints(&r, p)
    _read_body_arrays(&r, p)
    _read_handlers(&r, p)
    _read_buffers(&r, p)
    _read_arbiters(&r, p)
    _read_indexes(&r, p)
    _read_nodes(&r, p)
    _read_pairs(&r, p)
    _read_handles(&r, p)
    _read_sets(&r, p)
    if r.pos != r.len:
        _bad("data follows the last section")
    return 0

# The objects given with the snapshot (the new space's bodies, shapes and
# constraints, their own states restored, no links yet) must be what the
# snapshot describes.
cdef int _match_objects(Space sp, Parsed *p, Objects *o, list table, list shapes,
                        list constraints) except -1:
    cdef Py_ssize_t nb = len(table), ns = len(shapes), nc = len(constraints)
    cdef PtrMap bodymap, seen
    cdef Py_ssize_t i
    cdef cpShape *shape
    cdef cpConstraint *con
    memset(&bodymap, 0, sizeof(PtrMap))
    memset(&seen, 0, sizeof(PtrMap))
    o.bodies = <cpBody **>_scratch(nb, sizeof(cpBody *))
    o.shapes = <cpShape **>_scratch(ns, sizeof(cpShape *))
    o.cons = <cpConstraint **>_scratch(nc, sizeof(cpConstraint *))
    o.handlers = <cpCollisionHandler **>_scratch(p.s.nhandlers, sizeof(cpCollisionHandler *))
    p.shape_body = <int32_t *>_scratch(ns, sizeof(int32_t))
    try:
        pm_init(&bodymap, nb)
        for i in range(nb):
            obj = table[i]
            if not isinstance(obj, Body):
                raise CopyError("the space state lists a body that is not a Body")
            if (<Body>obj)._shapes is None:
                raise CopyError(
                    "a body of the space is not restored yet: the space is reached from "
                    "the body's own state (a circular reference), which cannot be copied")
            if (<Body>obj)._body.space != NULL or (<Body>obj).space is not None:
                raise CopyError("a body of the space state is already in a space")
            o.bodies[i] = &(<Body>obj)._body
            if pm_add(&bodymap, o.bodies[i]) != i:
                raise CopyError("the space state lists a body twice")
        pm_init(&seen, ns + nc)
        for i in range(ns):
            obj = shapes[i]
            if not isinstance(obj, Shape):
                raise CopyError("the space state lists a shape that is not a Shape")
            shape = (<Shape>obj)._shape
            if (<Shape>obj)._body_obj is None or pm_get(&bodymap, shape.body) < 0:
                raise CopyError(
                    "a shape of the space is not restored yet or its body is not in the "
                    "space state (a circular reference cannot be copied)")
            if shape.space != NULL or shape.prev != NULL or shape.next != NULL \
                    or shape.body.shapeList != NULL:
                raise CopyError("a shape of the space state is already in a space")
            if pm_add(&seen, shape) != i:
                raise CopyError("the space state lists a shape twice")
            if p.shape_kinds[i] != _shape_kind(<Shape>obj):
                raise CopyError("the snapshot does not match the shapes given with it")
            o.shapes[i] = shape
            p.shape_body[i] = pm_get(&bodymap, shape.body)
        for i in range(nc):
            obj = constraints[i]
            if not isinstance(obj, Constraint) or (<Constraint>obj)._constraint == NULL \
                    or (<Constraint>obj)._a is None:
                raise CopyError("a constraint of the space is not restored yet (a circular "
                                "reference cannot be copied) or is not a Constraint")
            con = (<Constraint>obj)._constraint
            if _constraint_kind(<Constraint>obj) != p.cons[i].kind \
                    or con.a != o.bodies[p.cons[i].a] or con.b != o.bodies[p.cons[i].b]:
                raise CopyError("the snapshot does not match the constraints given with it")
            if con.space != NULL:
                raise CopyError("a constraint of the space state is already in a space")
            if pm_add(&seen, con) != ns + i:
                raise CopyError("the space state lists a constraint twice")
            o.cons[i] = con
    finally:
        pm_free(&bodymap)
        pm_free(&seen)
    return 0

cdef int _check_links(Parsed *p) except -1:
    # The rules between records, each next to the reader of the record
    # that holds the link (see there); in this order, as later ones use the
    # roles the first one finds.
    cdef int j
    _check_components(p)
    _check_shape_lists(p)
    _check_shape_geometry(p)
    _check_constraint_links(p)
    _check_arbiter_links(p)
    for j in range(2):
        if p.index[j].kind == 1:
            _check_tree(p, j)
        else:
            _check_hash(p, j)
    if p.index[0].kind == 1:
        _check_pairs(p)
    else:
        _check_hash_cost(p)
    _check_index_membership(p)
    return 0


cdef void _blocks_free(Blocks *m) noexcept nogil:
    # Frees what the space does not own (after the hand-over: the two pointer
    # arrays and heap contacts not yet given to an arbiter).
    cdef int i
    if m.bufs != NULL:
        if not m.handed:
            for i in range(m.nbufs):
                free(m.bufs[i])
        free(m.bufs)
    if m.heap != NULL:
        for i in range(m.narbs):
            free(m.heap[i])
        free(m.heap)
    if not m.handed:
        free(m.arbs)
        for i in range(2):
            free(m.nodes[i])
            free(m.handles[i])
            free(m.bins[i])
        free(m.pairs)
    for i in range(2):
        if m.sets[i] != NULL:
            cpHashSetFree(m.sets[i])
    if m.cache != NULL:
        cpHashSetFree(m.cache)
    memset(m, 0, sizeof(Blocks))

cdef inline cpSpatialIndex *_index(cpSpace *space, int j) noexcept nogil:
    return space.staticShapes if j == 0 else space.dynamicShapes

cdef int _alloc_blocks(cpSpace *space, Parsed *p, Blocks *m) except -1:
    cdef int i, j
    cdef cpHashSetEqlFunc eql
    cdef cpArray *buffers
    memset(m, 0, sizeof(Blocks))
    m.narbs = p.s.narbiters
    m.nbufs = p.s.nbuffers
    try:
        if m.narbs > 0:
            m.arbs = <cpArbiter *>cpcalloc(m.narbs, sizeof(cpArbiter))
            m.heap = <cpContact **>cpcalloc(m.narbs, sizeof(cpContact *))
            if m.arbs == NULL or m.heap == NULL:
                raise MemoryError()
            for i in range(m.narbs):
                if p.arbs[i].ckind == 2:
                    m.heap[i] = <cpContact *>cpcalloc(p.arbs[i].count if p.arbs[i].count > 0
                                                      else 1, sizeof(cpContact))
                    if m.heap[i] == NULL:
                        raise MemoryError()
        if m.nbufs > 0:
            m.bufs = <ContactBuffer **>cpcalloc(m.nbufs, sizeof(ContactBuffer *))
            if m.bufs == NULL:
                raise MemoryError()
            for i in range(m.nbufs):
                m.bufs[i] = <ContactBuffer *>cpcalloc(1, sizeof(ContactBuffer))
                if m.bufs[i] == NULL:
                    raise MemoryError()
        for j in range(2):
            if p.index[j].kind == 1:
                if p.index[j].count > 0:
                    m.nodes[j] = <Node *>cpcalloc(p.index[j].count, sizeof(Node))
                    if m.nodes[j] == NULL:
                        raise MemoryError()
                eql = (<cpBBTree *>_index(space, j)).leaves.eql
                buffers = (<cpBBTree *>_index(space, j)).allocatedBuffers
            else:
                if p.index[j].count > 0:
                    m.handles[j] = <cpHandle *>cpcalloc(p.index[j].count, sizeof(cpHandle))
                    if m.handles[j] == NULL:
                        raise MemoryError()
                if p.index[j].nbins > 0:
                    m.bins[j] = <cpSpaceHashBin *>cpcalloc(p.index[j].nbins,
                                                           sizeof(cpSpaceHashBin))
                    if m.bins[j] == NULL:
                        raise MemoryError()
                eql = (<cpSpaceHash *>_index(space, j)).handleSet.eql
                buffers = (<cpSpaceHash *>_index(space, j)).allocatedBuffers
            m.sets[j] = cpHashSetNew(<int>p.index[j].set_size, eql)
            if m.sets[j] == NULL:
                raise MemoryError()
            # Room in every array the blocks go to, so that no push below can fail.
            _reserve(buffers, buffers.num + 2)
        if p.npairs > 0:
            m.pairs = <Pair *>cpcalloc(p.npairs, sizeof(Pair))
            if m.pairs == NULL:
                raise MemoryError()
        m.cache = cpHashSetNew(<int>p.s.cached_size, space.cachedArbiters.eql)
        if m.cache == NULL:
            raise MemoryError()
        _reserve(space.allocatedBuffers, space.allocatedBuffers.num + m.nbufs + 1)
        _reserve(space.dynamicBodies, p.s.ndynamic)
        _reserve(space.staticBodies, p.s.nstatic)
        _reserve(space.sleepingComponents, p.s.nsleeping)
        _reserve(space.arbiters, p.s.nstep_arbiters)
        _reserve(space.constraints, p.s.nstep_constraints)
    except BaseException:
        cpTakeOutOfMemory()
        _blocks_free(m)
        raise
    return 0

cdef void _hand_over(cpSpace *space, Parsed *p, Blocks *m) noexcept nogil:
    # The blocks go to their owners (room was reserved: nothing fails).
    cdef cpBBTree *tree
    cdef cpSpaceHash *hsh
    cdef int i, j
    m.handed = True
    for i in range(m.nbufs):
        cpArrayPush(space.allocatedBuffers, m.bufs[i])
    if m.arbs != NULL:
        cpArrayPush(space.allocatedBuffers, m.arbs)
    for j in range(2):
        if p.index[j].kind == 1:
            tree = <cpBBTree *>_index(space, j)
            if m.nodes[j] != NULL:
                cpArrayPush(tree.allocatedBuffers, m.nodes[j])
            cpHashSetFree(tree.leaves)
            tree.leaves = m.sets[j]
        else:
            hsh = <cpSpaceHash *>_index(space, j)
            if m.handles[j] != NULL:
                cpArrayPush(hsh.allocatedBuffers, m.handles[j])
            if m.bins[j] != NULL:
                cpArrayPush(hsh.allocatedBuffers, m.bins[j])
            cpHashSetFree(hsh.handleSet)
            hsh.handleSet = m.sets[j]
        m.sets[j] = NULL
    if m.pairs != NULL:
        # The dynamic tree owns the pair pool of both trees.
        cpArrayPush((<cpBBTree *>space.dynamicShapes).allocatedBuffers, m.pairs)
    cpHashSetFree(space.cachedArbiters)
    space.cachedArbiters = m.cache
    m.cache = NULL

# After a failure half way through linking: a new empty C space again, and
# bodies, shapes and constraints without links.
cdef void _reset_space(Space sp, Parsed *p, Objects *o) noexcept:
    cdef Py_ssize_t i
    for i in range(p.s.nbodies):
        o.bodies[i].space = NULL
        o.bodies[i].shapeList = NULL
        o.bodies[i].arbiterList = NULL
        o.bodies[i].constraintList = NULL
        o.bodies[i].sleeping.root = NULL
        o.bodies[i].sleeping.next = NULL
    for i in range(p.s.nshapes):
        o.shapes[i].space = NULL
        o.shapes[i].next = NULL
        o.shapes[i].prev = NULL
    for i in range(p.s.nconstraints):
        o.cons[i].space = NULL
        o.cons[i].next_a = NULL
        o.cons[i].next_b = NULL
    cpSpaceDestroy(&sp._space)
    if cpSpaceInit(&sp._space) == NULL:
        sp._initialized = False
    sp._space.userData = <void *>sp
    cpTakeOutOfMemory()

# The restore proper. table/shapes/constraints: the new space's objects, in
# snapshot order, with their own state in place and no links.
cdef int _restore(Space sp, list table, list shapes, list constraints, bytes blob) except -1:
    cdef Parsed p
    cdef Blocks m
    cdef Objects o
    cdef cpSpace *space = &sp._space
    cdef bint linked = False
    cdef Py_ssize_t i, n
    cdef int j
    cdef int32_t k
    cdef cpSpaceHash *hsh
    memset(&p, 0, sizeof(Parsed))
    memset(&m, 0, sizeof(Blocks))
    memset(&o, 0, sizeof(Objects))
    try:
        _parse(blob, &p, None)
        if p.s.nbodies != len(table) or p.s.nshapes != len(shapes) \
                or p.s.nconstraints != len(constraints):
            raise CopyError("the snapshot does not match the bodies, shapes and constraints "
                            "given with it")
        if sp._bodies or sp._shapes or sp._static_body is not None or space.stamp != 0 \
                or space.arbiters.num or space.cachedArbiters.entries:
            raise CopyError("a space state can only be restored into a new, empty Space")
        _match_objects(sp, &p, &o, table, shapes, constraints)
        _check_links(&p)

        if p.index[0].kind == 2:
            sp.use_spatial_hash(p.index[0].celldim, p.index[0].numcells)
        for j in range(2):
            if p.index[j].kind == 2:
                hsh = <cpSpaceHash *>_index(space, j)
                if hsh.spatialIndex.klass != cpSpaceHashClass() \
                        or hsh.numcells != p.index[j].numcells or hsh.celldim != p.index[j].celldim:
                    raise CopyError("the spatial hash of the snapshot cannot be rebuilt")
            elif _index(space, j).klass != cpBBTreeClass():
                raise CopyError("a space state can only be restored into a new, empty Space")
        _alloc_blocks(space, &p, &m)

        # The exact structs (their own states may have been restored the way
        # pymunk restores them, which loses some bits).
        for i in range(p.s.nbodies):
            _set_body_struct(<Body>table[i], &p.body_structs[i])
        for i in range(p.s.nshapes):
            _set_shape_struct(<Shape>shapes[i], p.shape_kinds[i], p.shape_at[i])
        for i in range(p.s.nconstraints):
            _joint_overwrite(o.cons[i], p.cons_at[i], p.cons[i].kind)
        # Handlers first (arbiters point at them); their Python callbacks come later.
        _link_handlers(&p, &o, space)

        # -- from here on nothing can fail ------------------------------------------------------
        linked = True
        _hand_over(space, &p, &m)
        _link_space(space, &p)
        _link_soft(space, &p)
        _link_buffers(&p, &m, space)
        _link_arbiters(&p, &o, &m, space)
        _link_bodies(&p, &o, m.arbs, space)
        _link_shapes(&p, &o, space)
        _link_body_arrays(&p, &o, space)
        _link_constraints(&p, &o, space)
        for j in range(2):
            if p.index[j].kind == 1:
                _link_tree(<cpBBTree *>_index(space, j), &p, j, m.nodes[j], m.pairs, o.shapes)
            else:
                _link_hash(<cpSpaceHash *>_index(space, j), &p, j, m.handles[j], m.bins[j],
                           o.shapes)
        if m.pairs != NULL:
            _link_pairs(&p, m.nodes, m.pairs)
        if cpTakeOutOfMemory():
            raise MemoryError()
    except BaseException:
        if linked:
            _reset_space(sp, &p, &o)
        _blocks_free(&m)
        free(o.bodies)
        free(o.shapes)
        free(o.cons)
        free(o.handlers)
        _parsed_free(&p)
        raise
    _blocks_free(&m)
    free(o.bodies)
    free(o.shapes)
    free(o.cons)
    free(o.handlers)
    _parsed_free(&p)

    # -- the Python side ------------------------------------------------------------------------
    ref = weakref.ref(sp)
    n_in = p.s.nspace_bodies
    sp._bodies = dict.fromkeys(table[:n_in])
    if p.s.has_static:
        sp._static_body = table[n_in]
    for i in range(p.s.nbodies):
        (<Body>table[i])._space = ref if p.bodies[i].in_space else None
    sp._shapes = dict.fromkeys(shapes)
    sp._constraints = dict.fromkeys(constraints)
    for i in range(p.s.nshapes):
        (<Shape>shapes[i])._space = ref if p.shapes[i].in_space else None
    # Body.shapes in the original order.
    k = 0
    for i in range(p.s.nbodies):
        obj = table[i]
        n = p.bodies[i].nshapes_view
        if n:
            order = [shapes[p.views[k + j]] for j in range(n)]
            k += n
            old = (<Body>obj)._shapes
            if list(old) != order:
                new = dict.fromkeys(s for s in order if old.get(s, 0) is None)
                for s in old:
                    if s not in new:
                        new[s] = None
                (<Body>obj)._shapes = new
    return 0


def snapshot_sections(bytes blob not None):
    """The sections of a snapshot (the bytes in a space's
    ``tamias2d_snapshot`` state), as ``(name, offset, record size, count)``,
    after reading and checking them as a restore would (CopyError if a
    record is corrupt). A debugging aid, and the map the mutation fuzzer
    (tests/test_snapshot_fuzz.py) aims by.

    >>> import tamias2d
    >>> from tamias2d._snapshot import space_getstate, snapshot_sections
    >>> blob = dict(space_getstate(tamias2d.Space())["special"])["tamias2d_snapshot"][1]
    >>> [name for name, offset, size, count in snapshot_sections(blob)][:3]
    ['header', 'space', 'soft solver settings']
    """
    cdef Parsed p
    cdef list log = []
    memset(&p, 0, sizeof(Parsed))
    try:
        _parse(blob, &p, log)
    finally:
        _parsed_free(&p)
    return log




# ================================================================================================
# The space: Python entry points
# ================================================================================================

_GENERAL = ("iterations", "gravity", "damping", "idle_speed_threshold", "sleep_time_threshold",
            "collision_slop", "collision_bias", "collision_persistence", "threads")


cdef list _handler_state(Space sp):
    handlers = []
    for key, h in sp._handlers.items():
        handlers.append((key, {"_data": h.data, "_begin": h.begin, "_pre_solve": h.pre_solve,
                               "_post_solve": h.post_solve, "_separate": h.separate}))
    return handlers


cdef _restore_handlers(Space sp, handlers):
    if not isinstance(handlers, (list, tuple)):
        raise CopyError("the space state's collision handlers are not a list")
    for entry in handlers:
        if not (isinstance(entry, tuple) and len(entry) == 2 and isinstance(entry[1], dict)):
            raise CopyError("a collision handler of the space state is not a (types, dict) pair")
        key, hd = entry
        if key is None:
            a = b = None
        elif isinstance(key, tuple) and len(key) == 2:
            a, b = key
        else:
            a, b = key, None
        sp.on_collision(a, b, begin=hd.get("_begin"), pre_solve=hd.get("_pre_solve"),
                        post_solve=hd.get("_post_solve"), separate=hd.get("_separate"))
        data = hd.get("_data", {})
        if not isinstance(data, dict):
            raise CopyError("a collision handler's data in the space state is not a dict")
        sp._handlers[(a, b)].data.update(data)


cdef list _joint_funcs(list constraints):
    # The Python force / torque functions of springs: pymunk does not pickle
    # them with the spring, but the space's next steps depend on them.
    funcs = []
    for i, c in enumerate(constraints):
        if isinstance(c, DampedSpring) and (<DampedSpring>c)._force_func is not None:
            funcs.append((i, (<DampedSpring>c)._force_func))
        elif isinstance(c, DampedRotarySpring) and (<DampedRotarySpring>c)._torque_func is not None:
            funcs.append((i, (<DampedRotarySpring>c)._torque_func))
    return funcs


cdef _set_joint_funcs(list constraints, funcs):
    if not isinstance(funcs, (list, tuple)):
        raise CopyError("the snapshot's spring functions are not a list")
    for entry in funcs:
        if not (isinstance(entry, tuple) and len(entry) == 2 and isinstance(entry[0], int)
                and 0 <= entry[0] < len(constraints)):
            raise CopyError("the snapshot names a spring function of no constraint")
        i, f = entry
        c = constraints[i]
        if isinstance(c, DampedSpring):
            c.force_func = f
        elif isinstance(c, DampedRotarySpring):
            c.torque_func = f
        else:
            raise CopyError("the snapshot gives a spring function to a constraint that is not "
                            "a spring")


cdef list _entries(dict state, str key):
    # One part of a pymunk-layout state: a list of (name, value) pairs.
    part = state.get(key)
    if not isinstance(part, (list, tuple)) or not all(
            isinstance(e, tuple) and len(e) == 2 for e in part):
        raise CopyError(f"the space state's {key!r} entries are not (name, value) pairs")
    return list(part)


cdef list _object_list(v, str what):
    if not isinstance(v, (list, tuple)):
        raise CopyError(f"the space state's {what} are not a list")
    return list(v)


cdef list _extra_bodies(list table, list shapes, list constraints):
    # Bodies of shapes and constraints of the space that are not in the space
    # themselves (pymunk lets a constraint's bodies stay out).
    seen = {id(b) for b in table}
    extra = []
    linked = [(<Shape>s)._body_obj for s in shapes]
    for c in constraints:
        linked.append((<Constraint>c)._a)
        linked.append((<Constraint>c)._b)
    for b in linked:
        if b is not None and id(b) not in seen:
            seen.add(id(b))
            extra.append(b)
    return extra


def space_getstate(Space sp not None):
    """``Space.__getstate__``: pymunk's layout (init, general, custom and
    special entries) with one more special entry, ``tamias2d_snapshot``,
    that carries the C state.

    >>> import tamias2d
    >>> from tamias2d._snapshot import space_getstate
    >>> [k for k, v in space_getstate(tamias2d.Space())["special"]][-1]
    'tamias2d_snapshot'
    """
    import tamias2d
    _check_unlocked(sp)
    state = {"init": [("threaded", sp.threaded)],
             "general": [(a, getattr(sp, a)) for a in _GENERAL],
             "custom": list((_custom(sp) or {}).items()),
             "special": []}
    special = state["special"]
    special.append(("pymunk_version", tamias2d.version))
    bodies = list(sp._bodies)
    special.append(("bodies", bodies))
    table = list(bodies)
    if sp._static_body is not None:
        special.append(("_static_body", sp._static_body))
        table.append(sp._static_body)
    shapes = list(sp._shapes)
    special.append(("shapes", shapes))
    special.append(("constraints", list(sp._constraints)))
    special.append(("_handlers", _handler_state(sp)))
    special.append(("shapeIDCounter", sp._space.shapeIDCounter))
    special.append(("stamp", sp._space.stamp))
    special.append(("currentTimeStep", sp._space.curr_dt))
    constraints = list(sp._constraints)
    extra = _extra_bodies(table, shapes, constraints)
    special.append(("tamias2d_snapshot", (extra, _capture(sp, table + extra, shapes, constraints),
                                          _joint_funcs(constraints))))
    return state


def space_setstate(Space sp not None, dict state):
    """``Space.__setstate__``: restore a state made by :func:`space_getstate`
    (bit for bit), or a plain pymunk-layout state (objects re-added).

    >>> import tamias2d
    >>> from tamias2d._snapshot import space_getstate, space_setstate
    >>> s = tamias2d.Space()
    >>> s.gravity = 0, -5
    >>> t = tamias2d.Space.__new__(tamias2d.Space)
    >>> space_setstate(t, space_getstate(s))
    >>> t.gravity
    Vec2d(0.0, -5.0)
    """
    import tamias2d
    if sp._bodies or sp._shapes or sp._static_body is not None or sp._space.stamp != 0:
        raise CopyError("a space state can only be restored into a new, empty Space")
    init = _entries(state, "init")
    general = _entries(state, "general")
    custom = _entries(state, "custom")
    special = _entries(state, "special")
    sp.__init__(*[v for k, v in init])
    for k, v in general:
        if not isinstance(k, str):
            raise CopyError("a setting of the space state is not named by a string")
        setattr(sp, k, v)
    for k, v in custom:
        if not isinstance(k, str):
            raise CopyError("a custom attribute of the space state is not named by a string")
        setattr(sp, k, v)
    bodies = shapes = constraints = handlers = static = snapshot = None
    counters = {}
    for k, v in special:
        if k == "pymunk_version":
            if v != tamias2d.version:
                raise CopyError(f"Pymunk version {v} of pickled object does not match current "
                                f"Pymunk version {tamias2d.version} (tamias2d)")
        elif k == "bodies":
            bodies = _object_list(v, "bodies")
        elif k == "_static_body":
            static = v
        elif k == "shapes":
            shapes = _object_list(v, "shapes")
        elif k == "constraints":
            constraints = _object_list(v, "constraints")
        elif k == "_handlers":
            handlers = v
        elif k in ("shapeIDCounter", "stamp", "currentTimeStep"):
            counters[k] = v
        elif k == "tamias2d_snapshot":
            snapshot = v
    if snapshot is not None:
        if not isinstance(snapshot, tuple) or len(snapshot) != 3:
            raise CopyError("the snapshot of the space is corrupt")
        extra, blob, jfuncs = snapshot
        if not isinstance(blob, bytes):
            raise CopyError("the snapshot of the space is not bytes")
        table = (list(bodies or ()) + ([static] if static is not None else [])
                 + _object_list(extra, "bodies outside the space"))
        constraints = list(constraints or ())
        _set_joint_funcs(constraints, jfuncs)
        _restore(sp, table, list(shapes or ()), constraints, blob)
    else:
        # A pymunk-layout state without the C state: add everything again.
        if bodies:
            sp.add(*bodies)
        if static is not None:
            _adopt_static_body(sp, static)
        if shapes:
            sp.add(*shapes)
        if constraints:
            sp.add(*constraints)
        if "stamp" in counters:
            sp._space.stamp = counters["stamp"]
        if "shapeIDCounter" in counters:
            sp._space.shapeIDCounter = counters["shapeIDCounter"]
        if "currentTimeStep" in counters:
            sp._space.curr_dt = counters["currentTimeStep"]
    if handlers:
        _restore_handlers(sp, handlers)


cdef _adopt_static_body(Space sp, Body static):
    if static.space is not None or static._body.space != NULL:
        raise CopyError("the static body of the space state is already in a space")
    static._space = weakref.ref(sp)
    if cpSpaceAddBody(&sp._space, &static._body) == NULL:
        static._space = None
        cpTakeOutOfMemory()
        raise MemoryError()
    sp._static_body = static


cdef Body _clone_body(Body src):
    cdef Body b = type(src).__new__(type(src))
    _body_copy_struct(b, &src._body)
    b._shapes = {}
    return b


cdef Shape _clone_shape(Shape src, Body body):
    cdef Shape s = type(src).__new__(type(src))
    cdef int kind = _shape_kind(src)
    cdef size_t size
    cdef void *data = _shape_struct(src, kind, &size)
    cdef cpPolyShape *poly
    if kind == 2:
        poly = &(<Poly>src)._poly
        _shape_copy_struct(s, kind, data, poly.planes,
                           2 * poly.count * sizeof(cpSplittingPlane)
                           if poly.count > CP_POLY_SHAPE_INLINE_ALLOC else 0, body)
    else:
        _shape_copy_struct(s, kind, data, NULL, 0, body)
    return s


def space_deepcopy(Space src not None, dict memo):
    """``Space.__deepcopy__`` (and ``Space.copy``): a new space with new
    bodies and shapes in the same C state, user attributes and collision
    callbacks deep-copied with ``memo`` (as ``copy.deepcopy`` would).

    >>> import copy, tamias2d
    >>> s = tamias2d.Space()
    >>> b = tamias2d.Body(1, 1)
    >>> s.add(b)
    >>> t = copy.deepcopy(s)
    >>> len(t.bodies), next(iter(t.bodies)) is b
    (1, False)
    """
    cdef Body b, nb
    cdef Shape s, ns
    _check_unlocked(src)
    cls = type(src)
    cdef Space dst = cls.__new__(cls)
    memo[id(src)] = dst
    dst.threaded = src.threaded
    if src.threaded:
        dst.threads = src.threads

    table = list(src._bodies)
    if src._static_body is not None:
        table.append(src._static_body)
    shapes = list(src._shapes)
    constraints = list(src._constraints)
    table += _extra_bodies(table, shapes, constraints)
    new_table = []
    made_bodies = []
    for obj in table:
        b = <Body>obj
        got = memo.get(id(b))
        if got is None:
            nb = _clone_body(b)
            memo[id(b)] = nb
            made_bodies.append((b, nb))
        else:
            nb = got
        new_table.append(nb)
    new_shapes = []
    made_shapes = []
    for obj in shapes:
        s = <Shape>obj
        got = memo.get(id(s))
        if got is None:
            ns = _clone_shape(s, memo[id(s._body_obj)])
            memo[id(s)] = ns
            made_shapes.append((s, ns))
        else:
            ns = got
        new_shapes.append(ns)
    # Keep the originals alive as long as the memo (ids must not be reused).
    memo.setdefault(id(memo), []).extend(table + shapes)
    # Constraints go through their own copy (pymunk's state: made again on
    # the copied bodies); their C state is set exactly below.
    new_constraints = [_copy.deepcopy(c, memo) for c in constraints]
    _set_joint_funcs(new_constraints, _copy.deepcopy(_joint_funcs(constraints), memo))

    # User-level state, deep-copied through the memo (copies of the bodies and
    # shapes are found there).
    for b, nb in made_bodies:
        custom = _custom(b)
        if custom:
            for k, v in _copy.deepcopy(custom, memo).items():
                setattr(nb, k, v)
        if b._velocity_func is not None:
            nb._velocity_func = _copy.deepcopy(b._velocity_func, memo)
        if b._position_func is not None:
            nb._position_func = _copy.deepcopy(b._position_func, memo)
        _set_body_funcs(nb)
    for s, ns in made_shapes:
        custom = _custom(s)
        if custom:
            for k, v in _copy.deepcopy(custom, memo).items():
                setattr(ns, k, v)
    custom = _custom(src)
    if custom:
        for k, v in _copy.deepcopy(custom, memo).items():
            setattr(dst, k, v)
    handlers = _copy.deepcopy(_handler_state(src), memo) if src._handlers else None

    _restore(dst, new_table, new_shapes, new_constraints,
             _capture(src, table, shapes, constraints))
    if handlers:
        _restore_handlers(dst, handlers)
    return dst
