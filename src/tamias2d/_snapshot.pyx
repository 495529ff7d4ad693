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
``bytes`` object (see ``_HEADER_SIZES``: a pickle only loads into a build
with the same record sizes).

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
from libc.math cimport INFINITY
from libc.string cimport memcpy, memset, memcmp
from libc.stdint cimport uintptr_t, int32_t, uint32_t, uint64_t
from cpython.bytes cimport PyBytes_FromStringAndSize, PyBytes_AS_STRING, PyBytes_GET_SIZE

import copy as _copy
import copyreg
import weakref

from tamias2d._config cimport (cpFloat, cpHashValue, cpCollisionType, CP_HASH_PAIR,
    CP_BUFFER_BYTES, CP_POLY_SHAPE_INLINE_ALLOC)
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArbiter, cpContact, cpArray,
    cpHashSet, cpHashSetBin, cpHashSetEqlFunc, cpCollisionHandler, cpContactBufferHeader,
    cpSpatialIndex, cpShapeClass, cpConstraint, cpCircleShape, cpSegmentShape, cpPolyShape, cpSplittingPlane,
    cpArbiterState)
from tamias2d.vector cimport vec2d_from_cpv
from tamias2d._containers cimport (cpcalloc, cprealloc, cpArrayPush, cpHashSetNew,
    cpHashSetFree, cpHashSetInsert, cpTakeOutOfMemory)
from tamias2d._bbtree cimport cpBBTree, Node, Pair, cpBBTreeClass
from tamias2d._spacehash cimport cpSpaceHash, cpHandle, cpSpaceHashBin, cpSpaceHashClass
from tamias2d.body cimport (Body, cpBodyUpdateVelocity, cpBodyUpdatePosition,
    tamias_body_velocity_trampoline, tamias_body_position_trampoline, cpBodyGetType,
    cpBodyGetPosition)
from tamias2d.shape cimport Shape, Circle, Segment, Poly, cpShapeDestroy
from tamias2d.arbiter cimport cpCollisionHandlerDoNothing, cpArbiterNext
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

DEF FORMAT_VERSION = 2

# Records. Only 8- and 4-byte fields, widest first, so there is no padding.
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

# The soft solver's settings (Space.solver and its attributes; see
# _soft_step.pxd), written right after the SpaceRec. The soft solver keeps no
# other state across steps: its warm start is the contacts' jnAcc / jtAcc,
# which the arbiter records carry already.
cdef struct SoftRec:
    cpFloat contactHertz
    cpFloat contactDampingRatio
    cpFloat pushOut
    cpFloat speculative
    int32_t solver
    int32_t substeps

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

cdef int r_get(Reader *r, void *out, size_t n) except -1:
    if n > r.len - r.pos:
        raise CopyError("the snapshot of the space is truncated or corrupt")
    memcpy(out, r.data + r.pos, n)
    r.pos += n
    return 0

# A pointer into the reader for `count` records of `size` bytes (checked).
cdef const char *r_take(Reader *r, Py_ssize_t count, size_t size) except NULL:
    if count < 0 or (count > 0 and <size_t>count > (r.len - r.pos) // size):
        raise CopyError("the snapshot of the space is truncated or corrupt")
    cdef const char *p = r.data + r.pos
    r.pos += <size_t>count * size
    return p


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


# -- small helpers -------------------------------------------------------------------------------

cdef inline int32_t _num(PtrMap *m, const void *p) except -2:
    # The number of a pointer that must be known (NULL is -1).
    cdef int32_t k
    if p == NULL:
        return -1
    k = pm_get(m, p)
    if k < 0:
        raise CopyError("internal error: the space links to an object it does not hold")
    return k

cdef int _check_index(int32_t i, Py_ssize_t n, bint allow_none=True) except -1:
    if (i == -1 and allow_none) or (0 <= i < n):
        return 0
    raise CopyError("the snapshot of the space is corrupt (an index is out of range)")

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

cdef int _check_unlocked(Space sp) except -1:
    if sp._locked or sp._space.locked:
        raise SpaceLocked("a space cannot be copied or pickled during a step or a query; "
                          "use a post-step callback")
    return 0


# -- joints: their structs are copied whole, pointers aside -------------------------------------

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

cdef dict _custom(object obj):
    # pymunk keeps the attributes set by the user whose names do not start
    # with an underscore.
    cdef dict d = getattr(obj, "__dict__", None)
    if not d:
        return None
    out = {k: v for k, v in d.items() if k[0] != "_"}
    return out if out else None


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
# The space: capture
# ================================================================================================

# Nodes of a BB tree in depth-first order (A before B), appended to `nodes`.
cdef int _collect_tree(cpBBTree *tree, PtrMap *nodes) except -1:
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


cdef struct BufRange:
    uintptr_t base
    int index

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


# -- the soft solver's settings (one record; kept apart from the rest) -----------------------

cdef void _put_soft(Writer *w, const cpSpace *space) noexcept nogil:
    cdef SoftRec rec
    memset(&rec, 0, sizeof(SoftRec))
    rec.contactHertz = space.soft.contactHertz
    rec.contactDampingRatio = space.soft.contactDampingRatio
    rec.pushOut = space.soft.pushOut
    rec.speculative = space.soft.speculative
    rec.solver = space.soft.solver
    rec.substeps = space.soft.substeps
    w_put(w, &rec, sizeof(SoftRec))

cdef int _check_soft(const SoftRec *rec) except -1:
    if not (rec.solver in (0, 1) and rec.substeps >= 1
            and rec.contactHertz >= 0.0 and rec.contactDampingRatio >= 0.0
            and rec.contactHertz < INFINITY and rec.contactDampingRatio < INFINITY
            and rec.pushOut < INFINITY and rec.speculative < INFINITY
            and rec.pushOut == rec.pushOut and rec.speculative == rec.speculative):
        raise CopyError("the snapshot of the space is corrupt (solver settings)")
    return 0

cdef void _apply_soft(cpSpace *space, const SoftRec *rec) noexcept nogil:
    space.soft.contactHertz = rec.contactHertz
    space.soft.contactDampingRatio = rec.contactDampingRatio
    space.soft.pushOut = rec.pushOut
    space.soft.speculative = rec.speculative
    space.soft.solver = rec.solver
    space.soft.substeps = rec.substeps


cdef bytes _capture(Space sp, list table, list shapes, list constraints):
    cdef cpSpace *space = &sp._space
    cdef Writer w
    cdef Header header
    cdef SpaceRec srec
    cdef BodyRec brec
    cdef ShapeRec shrec
    cdef HandlerRec hrec
    cdef BufferRec bufrec
    cdef ArbRec arec
    cdef IndexRec irec
    cdef NodeRec nrec
    cdef PairRec prec
    cdef HandleRec hdrec
    cdef CellRec crec
    cdef PtrMap bodies, shapemap, arbs, handlers, nodes, pairs, handles, cons
    cdef ConstraintRec crec2
    cdef cpConstraint *con
    cdef Py_ssize_t nc = len(constraints)
    cdef Py_ssize_t nb = len(table), ns = len(shapes)
    cdef Py_ssize_t i, k
    cdef int j, n
    cdef cpBody *body
    cdef cpShape *shape
    cdef cpArbiter *arb
    cdef cpArray *arr
    cdef cpHashSetBin *hbin
    cdef cpCollisionHandler *h
    cdef cpCollisionHandler *nothing = cpCollisionHandlerDoNothing()
    cdef cpContactBufferHeader *buf
    cdef cpContactBufferHeader *head
    cdef ContactBuffer **bufs = NULL
    cdef BufRange *sorted_bufs = NULL
    cdef int nbufs = 0
    cdef int32_t *cached = NULL
    cdef int ncached = 0
    cdef cpSpatialIndex *index
    cdef cpSpatialIndex *indexes[2]
    cdef cpBBTree *tree
    cdef cpSpaceHash *hsh
    cdef Node *node
    cdef Pair *pair
    cdef cpSpaceHashBin *sbin
    cdef int first[2]
    cdef int ncontacts = 0
    cdef uintptr_t addr, base
    cdef int nview = 0

    memset(&bodies, 0, sizeof(PtrMap))
    memset(&shapemap, 0, sizeof(PtrMap))
    memset(&arbs, 0, sizeof(PtrMap))
    memset(&handlers, 0, sizeof(PtrMap))
    memset(&nodes, 0, sizeof(PtrMap))
    memset(&pairs, 0, sizeof(PtrMap))
    memset(&handles, 0, sizeof(PtrMap))
    memset(&cons, 0, sizeof(PtrMap))
    w_init(&w, 4096 + 300 * nb + 100 * ns)
    try:
        pm_init(&bodies, nb)
        for obj in table:
            pm_add(&bodies, &(<Body>obj)._body)
        pm_init(&shapemap, ns)
        for obj in shapes:
            pm_add(&shapemap, (<Shape>obj)._shape)
        for obj in shapes:
            if pm_get(&bodies, (<Shape>obj)._shape.body) < 0:
                raise CopyError("internal error: a shape's body is missing from the table")
        pm_init(&cons, nc)
        for obj in constraints:
            con = (<Constraint>obj)._constraint
            pm_add(&cons, con)
            if pm_get(&bodies, con.a) < 0 or pm_get(&bodies, con.b) < 0:
                raise CopyError("internal error: a constraint's body is missing from the table")
        if space.rousedBodies.num != 0:
            raise SpaceLocked("a space cannot be copied while bodies are being woken")

        # Handlers of the space's set (the global handler is never an arbiter's).
        pm_init(&handlers, 16)
        for i in range(space.collisionHandlers.size):
            hbin = space.collisionHandlers.table[i]
            while hbin != NULL:
                pm_add(&handlers, hbin.elt)
                hbin = hbin.next

        # The contact buffer ring, oldest first, the head last.
        head = space.contactBuffersHead
        if head != NULL:
            n = space.allocatedBuffers.num + 1
            bufs = <ContactBuffer **>malloc(n * sizeof(ContactBuffer *))
            if bufs == NULL:
                raise MemoryError()
            buf = head.next
            while True:
                if nbufs >= n:
                    raise CopyError("internal error: the contact buffer ring is broken")
                bufs[nbufs] = <ContactBuffer *>buf
                nbufs += 1
                if buf == head:
                    break
                buf = buf.next

        # Buffer numbers by address, for finding where an arbiter's contacts are.
        sorted_bufs = <BufRange *>malloc((nbufs + 1) * sizeof(BufRange))
        if sorted_bufs == NULL:
            raise MemoryError()
        for j in range(nbufs):
            sorted_bufs[j].base = <uintptr_t>&bufs[j].contacts[0]
            sorted_bufs[j].index = j
        qsort(sorted_bufs, nbufs, sizeof(BufRange), _cmp_range)

        # Arbiters: the cache (in its order), those threaded on bodies (asleep
        # ones are out of the cache), and the last step's array.
        pm_init(&arbs, 64 + space.cachedArbiters.entries)
        cached = <int32_t *>malloc((space.cachedArbiters.entries + 1) * sizeof(int32_t))
        if cached == NULL:
            raise MemoryError()
        for i in range(space.cachedArbiters.size):
            hbin = space.cachedArbiters.table[i]
            while hbin != NULL:
                if ncached >= <int>space.cachedArbiters.entries:
                    raise CopyError("internal error: the arbiter cache is inconsistent")
                cached[ncached] = pm_add(&arbs, hbin.elt)
                ncached += 1
                hbin = hbin.next
        for i in range(nb):
            body = <cpBody *>bodies.items[i]
            arb = body.arbiterList
            while arb != NULL:
                pm_add(&arbs, arb)
                arb = cpArbiterNext(arb, body)
        for j in range(space.arbiters.num):
            pm_add(&arbs, space.arbiters.arr[j])

        # Broad phase nodes (static index first) and pairs.
        indexes[0] = space.staticShapes
        indexes[1] = space.dynamicShapes
        if indexes[0].klass != indexes[1].klass:
            raise CopyError("internal error: the static and dynamic indexes differ in kind")
        pm_init(&nodes, 2 * ns + 16)
        pm_init(&handles, ns + 16)
        for j in range(2):
            index = indexes[j]
            if index.klass == cpBBTreeClass():
                first[j] = nodes.count
                _collect_tree(<cpBBTree *>index, &nodes)
            elif index.klass == cpSpaceHashClass():
                hsh = <cpSpaceHash *>index
                first[j] = handles.count
                for i in range(hsh.numcells):
                    sbin = hsh.table[i]
                    while sbin != NULL:
                        pm_add(&handles, sbin.handle)
                        sbin = sbin.next
                for i in range(hsh.handleSet.size):
                    hbin = hsh.handleSet.table[i]
                    while hbin != NULL:
                        pm_add(&handles, hbin.elt)
                        hbin = hbin.next
            else:
                raise CopyError("unknown spatial index")
        pm_init(&pairs, nodes.count + 16)
        for k in range(nodes.count):
            node = <Node *>nodes.items[k]
            if node.obj == NULL:
                continue
            pair = node.node.leaf.pairs
            while pair != NULL:
                pm_add(&pairs, pair)
                pair = pair.a.next if pair.a.leaf == node else pair.b.next

        # -- header and space ------------------------------------------------------------
        _fill_header(&header)
        w_put(&w, &header, sizeof(Header))
        memset(&srec, 0, sizeof(SpaceRec))
        srec.gx = space.gravity.x
        srec.gy = space.gravity.y
        srec.damping = space.damping
        srec.idleSpeedThreshold = space.idleSpeedThreshold
        srec.sleepTimeThreshold = space.sleepTimeThreshold
        srec.collisionSlop = space.collisionSlop
        srec.collisionBias = space.collisionBias
        srec.curr_dt = space.curr_dt
        srec.shapeIDCounter = space.shapeIDCounter
        srec.iterations = space.iterations
        srec.collisionPersistence = space.collisionPersistence
        srec.stamp = space.stamp
        srec.nbodies = <int32_t>nb
        srec.nspace_bodies = <int32_t>len(sp._bodies)
        srec.has_static = sp._static_body is not None
        srec.nshapes = <int32_t>ns
        srec.ndynamic = space.dynamicBodies.num
        srec.nstatic = space.staticBodies.num
        srec.nsleeping = space.sleepingComponents.num
        srec.nhandlers = handlers.count
        srec.nbuffers = nbufs
        srec.narbiters = arbs.count
        srec.nstep_arbiters = space.arbiters.num
        srec.ncached = ncached
        srec.cached_size = space.cachedArbiters.size
        for obj in table:
            for s in (<Body>obj)._shapes:
                if pm_get(&shapemap, (<Shape>s)._shape) >= 0:
                    nview += 1
        srec.nshape_order = nview
        for k in range(arbs.count):
            arb = <cpArbiter *>arbs.items[k]
            if arb.contacts != NULL:
                ncontacts += arb.count
        srec.ncontacts = ncontacts
        srec.nconstraints = <int32_t>nc
        srec.nstep_constraints = space.constraints.num
        w_put(&w, &srec, sizeof(SpaceRec))
        _put_soft(&w, space)

        # -- bodies, then the Body.shapes orders ---------------------------------------------
        for i in range(nb):
            obj = table[i]
            body = &(<Body>obj)._body
            brec.in_space = body.space == space
            brec.shapeList = _num(&shapemap, body.shapeList)
            brec.arbiterList = _num(&arbs, body.arbiterList)
            brec.root = _num(&bodies, body.sleeping.root)
            brec.next = _num(&bodies, body.sleeping.next)
            n = 0
            for s in (<Body>obj)._shapes:
                if pm_get(&shapemap, (<Shape>s)._shape) >= 0:
                    n += 1
            brec.nshapes_view = n
            brec.constraintList = _num(&cons, body.constraintList)
            brec.pad = 0
            w_put(&w, &brec, sizeof(BodyRec))
        for obj in table:
            for s in (<Body>obj)._shapes:
                j = pm_get(&shapemap, (<Shape>s)._shape)
                if j >= 0:
                    w_i32(&w, j)

        # -- shapes ---------------------------------------------------------------------------
        shrec.pad = 0
        for i in range(ns):
            shape = <cpShape *>shapemap.items[i]
            shrec.in_space = shape.space == space
            shrec.next = _num(&shapemap, shape.next)
            shrec.prev = _num(&shapemap, shape.prev)
            w_put(&w, &shrec, sizeof(ShapeRec))

        # -- the structs of bodies and shapes, exact (pointers out) --------------------------
        for obj in table:
            _put_body(&w, &(<Body>obj)._body)
        for obj in shapes:
            w_i32(&w, _shape_kind(<Shape>obj))
        for obj in shapes:
            _put_shape(&w, <Shape>obj)

        # -- constraints ----------------------------------------------------------------------
        for obj in constraints:
            con = (<Constraint>obj)._constraint
            crec2.kind = _constraint_kind(<Constraint>obj)
            crec2.a = _num(&bodies, con.a)
            crec2.b = _num(&bodies, con.b)
            crec2.next_a = _num(&cons, con.next_a)
            crec2.next_b = _num(&cons, con.next_b)
            crec2.in_space = con.space == space
            w_put(&w, &crec2, sizeof(ConstraintRec))
        for obj in constraints:
            _put_joint(&w, (<Constraint>obj)._constraint, _constraint_kind(<Constraint>obj))
        for j in range(space.constraints.num):
            w_i32(&w, _num(&cons, space.constraints.arr[j]))

        # -- body arrays ----------------------------------------------------------------------
        for i in range(3):
            arr = (space.dynamicBodies if i == 0 else
                   space.staticBodies if i == 1 else space.sleepingComponents)
            for j in range(arr.num):
                w_i32(&w, _num(&bodies, arr.arr[j]))

        # -- handlers -------------------------------------------------------------------------
        for k in range(handlers.count):
            h = <cpCollisionHandler *>handlers.items[k]
            hrec.typeA = h.typeA
            hrec.typeB = h.typeB
            w_put(&w, &hrec, sizeof(HandlerRec))

        # -- contact buffers ------------------------------------------------------------------
        for j in range(nbufs):
            bufrec.stamp = bufs[j].header.stamp
            bufrec.numContacts = bufs[j].header.numContacts
            w_put(&w, &bufrec, sizeof(BufferRec))

        # -- arbiters, then their contacts ----------------------------------------------------
        for k in range(arbs.count):
            arb = <cpArbiter *>arbs.items[k]
            arec.e = arb.e
            arec.u = arb.u
            arec.svr_x = arb.surface_vr.x
            arec.svr_y = arb.surface_vr.y
            arec.n_x = arb.n.x
            arec.n_y = arb.n.y
            arec.a = _num(&shapemap, arb.a)
            arec.b = _num(&shapemap, arb.b)
            arec.body_a = _num(&bodies, arb.body_a)
            arec.body_b = _num(&bodies, arb.body_b)
            arec.ta_next = _num(&arbs, arb.thread_a.next)
            arec.ta_prev = _num(&arbs, arb.thread_a.prev)
            arec.tb_next = _num(&arbs, arb.thread_b.next)
            arec.tb_prev = _num(&arbs, arb.thread_b.prev)
            arec.count = arb.count
            arec.ckind = 0
            arec.cbuf = -1
            arec.coff = 0
            if arb.contacts != NULL:
                arec.ckind = 2
                addr = <uintptr_t>arb.contacts
                j = _find_buffer(sorted_bufs, nbufs, addr)
                if j >= 0:
                    base = <uintptr_t>&bufs[j].contacts[0]
                    if (addr - base) % sizeof(cpContact) != 0:
                        raise CopyError("internal error: misaligned contacts")
                    arec.ckind = 1
                    arec.cbuf = j
                    arec.coff = <int32_t>((addr - base) // sizeof(cpContact))
                    if arec.coff + arb.count > CONTACTS_PER_BUFFER:
                        raise CopyError("internal error: contacts overrun their buffer")
            arec.handlerAB = _handler_num(&handlers, arb.handlerAB, nothing)
            arec.handlerBA = _handler_num(&handlers, arb.handlerBA, nothing)
            arec.handlerA = _handler_num(&handlers, arb.handlerA, nothing)
            arec.handlerB = _handler_num(&handlers, arb.handlerB, nothing)
            arec.stamp = arb.stamp
            arec.state = <uint32_t>arb.state
            arec.swapped = arb.swapped
            arec.processCollision = arb.processCollision
            w_put(&w, &arec, sizeof(ArbRec))
        for k in range(arbs.count):
            arb = <cpArbiter *>arbs.items[k]
            if arb.contacts != NULL and arb.count > 0:
                w_put(&w, arb.contacts, arb.count * sizeof(cpContact))
        for j in range(space.arbiters.num):
            w_i32(&w, _num(&arbs, space.arbiters.arr[j]))
        w_put(&w, cached, ncached * sizeof(int32_t))

        # -- broad phase ----------------------------------------------------------------------
        for j in range(2):
            index = indexes[j]
            memset(&irec, 0, sizeof(IndexRec))
            if index.klass == cpBBTreeClass():
                tree = <cpBBTree *>index
                irec.kind = 1
                irec.stamp = tree.stamp
                irec.root = _num(&nodes, tree.root)
                irec.first = first[j]
                irec.count = (nodes.count if j == 1 else first[1]) - first[j]
                irec.set_size = tree.leaves.size
                irec.set_count = tree.leaves.entries
                irec.has_velocity = tree.velocityFunc != NULL
            else:
                hsh = <cpSpaceHash *>index
                irec.kind = 2
                irec.celldim = hsh.celldim
                irec.stamp = hsh.stamp
                irec.root = -1
                irec.first = first[j]
                irec.count = (handles.count if j == 1 else first[1]) - first[j]
                irec.set_size = hsh.handleSet.size
                irec.set_count = hsh.handleSet.entries
                irec.numcells = hsh.numcells
                for i in range(hsh.numcells):
                    sbin = hsh.table[i]
                    if sbin != NULL:
                        irec.ncells += 1
                    while sbin != NULL:
                        irec.nbins += 1
                        sbin = sbin.next
            w_put(&w, &irec, sizeof(IndexRec))
        # nodes
        for k in range(nodes.count):
            node = <Node *>nodes.items[k]
            nrec.l = node.bb.l
            nrec.b = node.bb.b
            nrec.r = node.bb.r
            nrec.t = node.bb.t
            nrec.parent = _num(&nodes, node.parent)
            if node.obj != NULL:
                nrec.obj = _num(&shapemap, node.obj)
                nrec.a = -1
                nrec.bchild = -1
                nrec.stamp = node.node.leaf.stamp
                nrec.pairs = _num(&pairs, node.node.leaf.pairs)
            else:
                nrec.obj = -1
                nrec.a = _num(&nodes, node.node.children.a)
                nrec.bchild = _num(&nodes, node.node.children.b)
                nrec.stamp = 0
                nrec.pairs = -1
            w_put(&w, &nrec, sizeof(NodeRec))
        # pairs
        prec.pad = 0
        w_i32(&w, pairs.count)
        for k in range(pairs.count):
            pair = <Pair *>pairs.items[k]
            prec.a_leaf = _num(&nodes, pair.a.leaf)
            prec.a_prev = _num(&pairs, pair.a.prev)
            prec.a_next = _num(&pairs, pair.a.next)
            prec.b_leaf = _num(&nodes, pair.b.leaf)
            prec.b_prev = _num(&pairs, pair.b.prev)
            prec.b_next = _num(&pairs, pair.b.next)
            prec.id = pair.id
            w_put(&w, &prec, sizeof(PairRec))
        # handles
        hdrec.pad = 0
        for k in range(handles.count):
            hdrec.obj = _num(&shapemap, (<cpHandle *>handles.items[k]).obj)
            hdrec.retain = (<cpHandle *>handles.items[k]).retain
            hdrec.stamp = (<cpHandle *>handles.items[k]).stamp
            w_put(&w, &hdrec, sizeof(HandleRec))
        # leaf / handle sets and hash cells, per index
        for j in range(2):
            index = indexes[j]
            if index.klass == cpBBTreeClass():
                _write_set(&w, (<cpBBTree *>index).leaves, &nodes)
            else:
                hsh = <cpSpaceHash *>index
                _write_set(&w, hsh.handleSet, &handles)
                for i in range(hsh.numcells):
                    sbin = hsh.table[i]
                    if sbin == NULL:
                        continue
                    crec.cell = <int32_t>i
                    crec.length = 0
                    while sbin != NULL:
                        crec.length += 1
                        sbin = sbin.next
                    w_put(&w, &crec, sizeof(CellRec))
                    sbin = hsh.table[i]
                    while sbin != NULL:
                        w_i32(&w, _num(&handles, sbin.handle))
                        sbin = sbin.next

        if w.failed:
            cpTakeOutOfMemory()
            raise MemoryError()
        return PyBytes_FromStringAndSize(w.data, w.len)
    finally:
        free(w.data)
        free(bufs)
        free(sorted_bufs)
        free(cached)
        pm_free(&bodies)
        pm_free(&shapemap)
        pm_free(&arbs)
        pm_free(&handlers)
        pm_free(&nodes)
        pm_free(&pairs)
        pm_free(&handles)
        pm_free(&cons)


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


# Overwrite a body's struct with exact bytes (links and pointers kept).
cdef void _set_body_struct(Body b, const cpBody *src) noexcept:
    _body_copy_struct(b, src)
    _set_body_funcs(b)


# -1: the do-nothing handler, -2: none (NULL), else a handler of the set.
cdef inline int32_t _handler_num(PtrMap *handlers, cpCollisionHandler *h,
                                 cpCollisionHandler *nothing) except -3:
    if h == NULL:
        return -2
    if h == nothing:
        return -1
    return _num(handlers, h)


# ================================================================================================
# The space: restore
# ================================================================================================

# Everything parsed from a snapshot, before anything is changed.
cdef struct Parsed:
    SpaceRec s
    SoftRec soft
    const BodyRec *bodies
    const int32_t *views
    const ShapeRec *shapes
    const cpBody *body_structs
    const int32_t *shape_kinds
    const char *shape_structs  # back to back, big polygons followed by their planes
    const ConstraintRec *cons
    const char *cons_structs
    const int32_t *step_cons
    const int32_t *dynamic
    const int32_t *statics
    const int32_t *sleeping
    const HandlerRec *handlers
    const BufferRec *buffers
    const ArbRec *arbs
    const char *contacts
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


cdef int _parse(bytes blob, Parsed *p) except -1:
    cdef Reader r
    cdef Header expected, got
    cdef Py_ssize_t nb, ns, na, total
    cdef int j, c
    cdef int32_t k
    cdef CellRec cell
    cdef const cpPolyShape *poly
    r.data = PyBytes_AS_STRING(blob)
    r.len = <size_t>PyBytes_GET_SIZE(blob)
    r.pos = 0
    _fill_header(&expected)
    memset(&got, 0, sizeof(Header))
    r_get(&r, &got, sizeof(Header))
    if memcmp(&got, &expected, sizeof(Header)):
        raise CopyError("the snapshot was made by another version or build of tamias2d "
                        "(record layout differs)")
    r_get(&r, &p.s, sizeof(SpaceRec))
    r_get(&r, &p.soft, sizeof(SoftRec))
    _check_soft(&p.soft)
    nb = p.s.nbodies
    ns = p.s.nshapes
    na = p.s.narbiters
    if nb < 0 or ns < 0 or na < 0 or p.s.nspace_bodies < 0 or \
            p.s.nspace_bodies + (1 if p.s.has_static else 0) > nb:
        raise CopyError("the snapshot of the space is corrupt (counts)")
    p.bodies = <const BodyRec *>r_take(&r, nb, sizeof(BodyRec))
    total = 0
    for k in range(nb):
        if p.bodies[k].nshapes_view < 0:
            raise CopyError("the snapshot of the space is corrupt (counts)")
        total += p.bodies[k].nshapes_view
        _check_index(p.bodies[k].shapeList, ns)
        _check_index(p.bodies[k].arbiterList, na)
        _check_index(p.bodies[k].root, nb)
        _check_index(p.bodies[k].next, nb)
        _check_index(p.bodies[k].constraintList, p.s.nconstraints)
    if total != p.s.nshape_order:
        raise CopyError("the snapshot of the space is corrupt (shape order)")
    p.views = <const int32_t *>r_take(&r, total, sizeof(int32_t))
    for k in range(total):
        _check_index(p.views[k], ns, False)
    p.shapes = <const ShapeRec *>r_take(&r, ns, sizeof(ShapeRec))
    for k in range(ns):
        _check_index(p.shapes[k].next, ns)
        _check_index(p.shapes[k].prev, ns)
    p.body_structs = <const cpBody *>r_take(&r, nb, sizeof(cpBody))
    p.shape_kinds = <const int32_t *>r_take(&r, ns, sizeof(int32_t))
    p.shape_structs = r.data + r.pos
    for k in range(ns):
        c = p.shape_kinds[k]
        if c == 0:
            r_take(&r, 1, sizeof(cpCircleShape))
        elif c == 1:
            r_take(&r, 1, sizeof(cpSegmentShape))
        elif c == 2:
            poly = <const cpPolyShape *>r_take(&r, 1, sizeof(cpPolyShape))
            if poly.count < 1 or poly.count > (1 << 24):
                raise CopyError("the snapshot of the space is corrupt (polygon)")
            if poly.count > CP_POLY_SHAPE_INLINE_ALLOC:
                r_take(&r, 2 * poly.count, sizeof(cpSplittingPlane))
        else:
            raise CopyError("the snapshot of the space is corrupt (shape kind)")
    p.cons = <const ConstraintRec *>r_take(&r, p.s.nconstraints, sizeof(ConstraintRec))
    p.cons_structs = r.data + r.pos
    for k in range(p.s.nconstraints):
        if p.cons[k].kind < 0 or p.cons[k].kind >= 10:
            raise CopyError("the snapshot of the space is corrupt (constraint kind)")
        _check_index(p.cons[k].a, nb, False)
        _check_index(p.cons[k].b, nb, False)
        _check_index(p.cons[k].next_a, p.s.nconstraints)
        _check_index(p.cons[k].next_b, p.s.nconstraints)
    for k in range(p.s.nconstraints):
        r_take(&r, 1, _constraint_size(p.cons[k].kind))
    p.step_cons = <const int32_t *>r_take(&r, p.s.nstep_constraints, sizeof(int32_t))
    for k in range(p.s.nstep_constraints):
        _check_index(p.step_cons[k], p.s.nconstraints, False)
    p.dynamic = <const int32_t *>r_take(&r, p.s.ndynamic, sizeof(int32_t))
    p.statics = <const int32_t *>r_take(&r, p.s.nstatic, sizeof(int32_t))
    p.sleeping = <const int32_t *>r_take(&r, p.s.nsleeping, sizeof(int32_t))
    for k in range(p.s.ndynamic):
        _check_index(p.dynamic[k], nb, False)
    for k in range(p.s.nstatic):
        _check_index(p.statics[k], nb, False)
    for k in range(p.s.nsleeping):
        _check_index(p.sleeping[k], nb, False)
    p.handlers = <const HandlerRec *>r_take(&r, p.s.nhandlers, sizeof(HandlerRec))
    p.buffers = <const BufferRec *>r_take(&r, p.s.nbuffers, sizeof(BufferRec))
    for k in range(p.s.nbuffers):
        if p.buffers[k].numContacts > CONTACTS_PER_BUFFER:
            raise CopyError("the snapshot of the space is corrupt (contact buffer)")
    p.arbs = <const ArbRec *>r_take(&r, na, sizeof(ArbRec))
    total = 0
    for k in range(na):
        _check_arb(&p.arbs[k], p, nb, ns, na)
        if p.arbs[k].ckind != 0:
            total += p.arbs[k].count
    if total != p.s.ncontacts:
        raise CopyError("the snapshot of the space is corrupt (contacts)")
    p.contacts = r_take(&r, total, sizeof(cpContact))
    p.step_arbs = <const int32_t *>r_take(&r, p.s.nstep_arbiters, sizeof(int32_t))
    for k in range(p.s.nstep_arbiters):
        _check_index(p.step_arbs[k], na, False)
    p.cached = <const int32_t *>r_take(&r, p.s.ncached, sizeof(int32_t))
    for k in range(p.s.ncached):
        _check_index(p.cached[k], na, False)
    r_get(&r, &p.index[0], sizeof(IndexRec))
    r_get(&r, &p.index[1], sizeof(IndexRec))
    if p.index[0].kind != p.index[1].kind or p.index[0].kind not in (1, 2):
        raise CopyError("the snapshot of the space is corrupt (broad phase kind)")
    p.nnodes = 0
    p.nhandles = 0
    for j in range(2):
        if p.index[j].count < 0 or p.index[j].set_count < 0 or p.index[j].ncells < 0:
            raise CopyError("the snapshot of the space is corrupt (broad phase counts)")
        if p.index[j].first != (p.nnodes if p.index[j].kind == 1 else p.nhandles):
            raise CopyError("the snapshot of the space is corrupt (broad phase ranges)")
        if p.index[j].kind == 1:
            p.nnodes += p.index[j].count
        else:
            p.nhandles += p.index[j].count
    p.nodes = <const NodeRec *>r_take(&r, p.nnodes, sizeof(NodeRec))
    r_get(&r, &p.npairs, sizeof(int32_t))
    p.pairs = <const PairRec *>r_take(&r, p.npairs, sizeof(PairRec))
    p.handles = <const HandleRec *>r_take(&r, p.nhandles, sizeof(HandleRec))
    for j in range(2):
        p.sets[j] = <const SetEntry *>r_take(&r, p.index[j].set_count, sizeof(SetEntry))
        p.cells[j] = r.data + r.pos
        if p.index[j].kind == 2:
            total = 0
            for c in range(p.index[j].ncells):
                r_get(&r, &cell, sizeof(CellRec))
                if cell.cell < 0 or cell.cell >= p.index[j].numcells or cell.length <= 0:
                    raise CopyError("the snapshot of the space is corrupt (hash cells)")
                total += cell.length
                ids = <const int32_t *>r_take(&r, cell.length, sizeof(int32_t))
                for k in range(cell.length):
                    _check_range(ids[k], p.index[j].first, p.index[j].count)
            if total != p.index[j].nbins:
                raise CopyError("the snapshot of the space is corrupt (hash cells)")
    if r.pos != r.len:
        raise CopyError("the snapshot of the space is corrupt (trailing data)")
    _check_broadphase(p, ns)
    return 0


cdef int _check_range(int32_t i, int32_t first, int32_t count) except -1:
    if first <= i < first + count:
        return 0
    raise CopyError("the snapshot of the space is corrupt (an index is out of range)")


cdef int _check_arb(const ArbRec *a, Parsed *p, Py_ssize_t nb, Py_ssize_t ns,
                    Py_ssize_t na) except -1:
    cdef int32_t h
    _check_index(a.a, ns)
    _check_index(a.b, ns)
    _check_index(a.body_a, nb, False)
    _check_index(a.body_b, nb, False)
    _check_index(a.ta_next, na)
    _check_index(a.ta_prev, na)
    _check_index(a.tb_next, na)
    _check_index(a.tb_prev, na)
    for h in (a.handlerAB, a.handlerBA, a.handlerA, a.handlerB):
        if h < -2 or h >= p.s.nhandlers:
            raise CopyError("the snapshot of the space is corrupt (handler)")
    if a.count < 0 or a.count > 2 or a.ckind < 0 or a.ckind > 2 or a.state > 4:
        raise CopyError("the snapshot of the space is corrupt (arbiter)")
    if a.ckind == 1:
        _check_index(a.cbuf, p.s.nbuffers, False)
        if a.coff < 0 or a.coff + a.count > CONTACTS_PER_BUFFER:
            raise CopyError("the snapshot of the space is corrupt (contact offset)")
    return 0


cdef int _check_broadphase(Parsed *p, Py_ssize_t ns) except -1:
    cdef int j
    cdef int32_t k, first, count, c
    cdef const NodeRec *n
    cdef const PairRec *q
    for j in range(2):
        first = p.index[j].first
        count = p.index[j].count
        if p.index[j].kind == 1:
            if p.index[j].root != -1:
                _check_range(p.index[j].root, first, count)
                if p.nodes[p.index[j].root].parent != -1:
                    raise CopyError("the snapshot of the space is corrupt (tree root)")
            for k in range(first, first + count):
                n = &p.nodes[k]
                if n.parent != -1:
                    _check_range(n.parent, first, count)
                if n.obj >= 0:
                    _check_index(n.obj, ns, False)
                    _check_index(n.pairs, p.npairs)
                else:
                    if n.obj != -1:
                        raise CopyError("the snapshot of the space is corrupt (tree node)")
                    _check_range(n.a, first, count)
                    _check_range(n.bchild, first, count)
                    if p.nodes[n.a].parent != k or p.nodes[n.bchild].parent != k:
                        raise CopyError("the snapshot of the space is corrupt (tree links)")
            for k in range(p.index[j].set_count):
                _check_range(p.sets[j][k].elt, first, count)
                if p.nodes[p.sets[j][k].elt].obj < 0:
                    raise CopyError("the snapshot of the space is corrupt (tree leaves)")
        else:
            if p.index[j].numcells <= 0:
                raise CopyError("the snapshot of the space is corrupt (hash size)")
            for k in range(first, first + count):
                _check_index(p.handles[k].obj, ns)
            for k in range(p.index[j].set_count):
                _check_range(p.sets[j][k].elt, first, count)
                if p.handles[p.sets[j][k].elt].obj < 0:
                    raise CopyError("the snapshot of the space is corrupt (hash handles)")
    for k in range(p.npairs):
        q = &p.pairs[k]
        for c in (q.a_leaf, q.b_leaf):
            _check_index(c, p.nnodes, False)
            if p.nodes[c].obj < 0:
                raise CopyError("the snapshot of the space is corrupt (pair leaf)")
        for c in (q.a_prev, q.a_next, q.b_prev, q.b_next):
            _check_index(c, p.npairs)
    return 0


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


cdef int _alloc_blocks(cpSpace *space, Parsed *p, Blocks *m) except -1:
    cdef int i, j
    cdef const ArbRec *a
    cdef cpHashSetEqlFunc eql
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
                a = &p.arbs[i]
                if a.ckind == 2:
                    m.heap[i] = <cpContact *>cpcalloc(a.count if a.count > 0 else 1,
                                                      sizeof(cpContact))
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
                eql = (<cpBBTree *>(space.staticShapes if j == 0 else space.dynamicShapes)).leaves.eql
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
                eql = (<cpSpaceHash *>(space.staticShapes if j == 0
                                       else space.dynamicShapes)).handleSet.eql
            m.sets[j] = cpHashSetNew(<int>p.index[j].set_size, eql)
            if m.sets[j] == NULL or m.sets[j].size != p.index[j].set_size:
                raise CopyError("the snapshot of the space is corrupt (hash set size)") \
                    if m.sets[j] != NULL else MemoryError()
        if p.npairs > 0:
            m.pairs = <Pair *>cpcalloc(p.npairs, sizeof(Pair))
            if m.pairs == NULL:
                raise MemoryError()
        m.cache = cpHashSetNew(<int>p.s.cached_size, space.cachedArbiters.eql)
        if m.cache == NULL:
            raise MemoryError()
        # Room in every array the blocks go to, so that no push below can fail.
        _reserve(space.allocatedBuffers, space.allocatedBuffers.num + m.nbufs + 1)
        for j in range(2):
            if p.index[j].kind == 1:
                _reserve((<cpBBTree *>(space.staticShapes if j == 0
                                       else space.dynamicShapes)).allocatedBuffers,
                         (<cpBBTree *>(space.staticShapes if j == 0
                                       else space.dynamicShapes)).allocatedBuffers.num + 2)
            else:
                _reserve((<cpSpaceHash *>(space.staticShapes if j == 0
                                          else space.dynamicShapes)).allocatedBuffers,
                         (<cpSpaceHash *>(space.staticShapes if j == 0
                                          else space.dynamicShapes)).allocatedBuffers.num + 2)
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


# The restore proper. table/shapes: the new space's objects, in snapshot
# order, with their own struct state already in place and no links.
cdef int _restore(Space sp, list table, list shapes, list constraints, bytes blob) except -1:
    cdef Parsed p
    cdef Blocks m
    cdef cpSpace *space = &sp._space
    cdef Py_ssize_t nb = len(table), ns = len(shapes)
    cdef cpBody **bptr = NULL
    cdef cpShape **sptr = NULL
    cdef cpCollisionHandler **hptr = NULL
    cdef cpCollisionHandler *nothing = cpCollisionHandlerDoNothing()
    cdef PtrMap bodymap
    cdef Py_ssize_t i
    cdef int j
    cdef int32_t k
    cdef const char *cdata
    cdef const BodyRec *br
    cdef const ShapeRec *sr
    cdef const ArbRec *ar
    cdef cpArbiter *arb
    cdef cpBody *body
    cdef cpShape *shape
    cdef ContactBuffer *buf
    cdef cpShape *pair_key[2]
    cdef bint linked = False
    cdef cpSpatialIndex *index
    cdef cpBBTree *tree
    cdef cpSpaceHash *hsh
    cdef Py_ssize_t n
    cdef cpConstraint *con

    memset(&bodymap, 0, sizeof(PtrMap))
    memset(&m, 0, sizeof(Blocks))
    _parse(blob, &p)
    if p.s.nbodies != nb or p.s.nshapes != ns or p.s.nconstraints != len(constraints):
        raise CopyError("the snapshot does not match the bodies, shapes and constraints "
                        "given with it")
    if sp._bodies or sp._shapes or sp._static_body is not None or space.stamp != 0 \
            or space.arbiters.num or space.cachedArbiters.entries:
        raise CopyError("a space state can only be restored into a new, empty Space")
    if p.index[0].kind == 2:
        sp.use_spatial_hash(p.index[0].celldim, p.index[0].numcells)
    for j in range(2):
        if p.index[j].kind == 2:
            hsh = <cpSpaceHash *>(space.staticShapes if j == 0 else space.dynamicShapes)
            if hsh.numcells != p.index[j].numcells or hsh.celldim != p.index[j].celldim:
                raise CopyError("the spatial hash of the snapshot cannot be rebuilt")
        elif (<cpSpatialIndex *>(space.staticShapes if j == 0 else space.dynamicShapes)).klass \
                != cpBBTreeClass():
            raise CopyError("a space state can only be restored into a new, empty Space")

    try:
        # -- the objects --------------------------------------------------------------------
        bptr = <cpBody **>malloc((nb + 1) * sizeof(cpBody *))
        sptr = <cpShape **>malloc((ns + 1) * sizeof(cpShape *))
        hptr = <cpCollisionHandler **>malloc((p.s.nhandlers + 1) * sizeof(cpCollisionHandler *))
        if bptr == NULL or sptr == NULL or hptr == NULL:
            raise MemoryError()
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
            bptr[i] = &(<Body>obj)._body
            if pm_add(&bodymap, bptr[i]) != i:
                raise CopyError("the space state lists a body twice")
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
            sptr[i] = shape
        _check_shapes_distinct(sptr, ns)
        _validate(&p, bptr, sptr, nb, ns)

        for i in range(ns):
            if p.shape_kinds[i] != _shape_kind(<Shape>shapes[i]):
                raise CopyError("the snapshot does not match the shapes given with it")
        for i in range(len(constraints)):
            obj = constraints[i]
            if not isinstance(obj, Constraint) or (<Constraint>obj)._constraint == NULL \
                    or (<Constraint>obj)._a is None:
                raise CopyError("a constraint of the space is not restored yet (a circular "
                                "reference cannot be copied) or is not a Constraint")
            if _constraint_kind(<Constraint>obj) != p.cons[i].kind \
                    or (<Constraint>obj)._constraint.a != bptr[p.cons[i].a] \
                    or (<Constraint>obj)._constraint.b != bptr[p.cons[i].b]:
                raise CopyError("the snapshot does not match the constraints given with it")
            if (<Constraint>obj)._constraint.space != NULL:
                raise CopyError("a constraint of the space state is already in a space")

        _alloc_blocks(space, &p, &m)

        # The exact structs of bodies and shapes (their own states may have
        # been restored the way pymunk restores them, which loses some bits).
        for i in range(nb):
            _set_body_struct(<Body>table[i], &p.body_structs[i])
        cdata = p.shape_structs
        for i in range(ns):
            cdata = _set_shape_struct(<Shape>shapes[i], p.shape_kinds[i], cdata)
        cdata = p.cons_structs
        for i in range(len(constraints)):
            _joint_overwrite((<Constraint>constraints[i])._constraint, cdata, p.cons[i].kind)
            cdata += _constraint_size(p.cons[i].kind)

        # Handlers first (arbiters point at them); the Python wrappers come later.
        for k in range(p.s.nhandlers):
            hptr[k] = cpSpaceAddCollisionHandler(space, <cpCollisionType>p.handlers[k].typeA,
                                                 <cpCollisionType>p.handlers[k].typeB)
            if hptr[k] == NULL:
                raise MemoryError()

        # -- from here on nothing can fail: hand the blocks to their owners ------------------
        linked = True
        m.handed = True
        for i in range(m.nbufs):
            cpArrayPush(space.allocatedBuffers, m.bufs[i])
        if m.arbs != NULL:
            cpArrayPush(space.allocatedBuffers, m.arbs)
        for j in range(2):
            index = space.staticShapes if j == 0 else space.dynamicShapes
            if p.index[j].kind == 1:
                tree = <cpBBTree *>index
                if m.nodes[j] != NULL:
                    cpArrayPush(tree.allocatedBuffers, m.nodes[j])
                cpHashSetFree(tree.leaves)
                tree.leaves = m.sets[j]
            else:
                hsh = <cpSpaceHash *>index
                if m.handles[j] != NULL:
                    cpArrayPush(hsh.allocatedBuffers, m.handles[j])
                if m.bins[j] != NULL:
                    cpArrayPush(hsh.allocatedBuffers, m.bins[j])
                cpHashSetFree(hsh.handleSet)
                hsh.handleSet = m.sets[j]
            m.sets[j] = NULL
        if m.pairs != NULL:
            cpArrayPush((<cpBBTree *>space.dynamicShapes).allocatedBuffers, m.pairs)
        cpHashSetFree(space.cachedArbiters)
        space.cachedArbiters = m.cache
        m.cache = NULL

        # -- space scalars --------------------------------------------------------------------
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
        _apply_soft(space, &p.soft)

        # -- contact buffers (a ring, the last one is the head) ---------------------------
        for j in range(m.nbufs):
            buf = m.bufs[j]
            buf.header.stamp = p.buffers[j].stamp
            buf.header.numContacts = p.buffers[j].numContacts
            buf.header.next = &m.bufs[(j + 1) % m.nbufs].header
        space.contactBuffersHead = &m.bufs[m.nbufs - 1].header if m.nbufs > 0 else NULL

        # -- arbiters ---------------------------------------------------------------------------
        cdata = p.contacts
        for k in range(m.narbs):
            ar = &p.arbs[k]
            arb = &m.arbs[k]
            arb.e = ar.e
            arb.u = ar.u
            arb.surface_vr.x = ar.svr_x
            arb.surface_vr.y = ar.svr_y
            arb.n.x = ar.n_x
            arb.n.y = ar.n_y
            arb.data = NULL
            arb.a = sptr[ar.a] if ar.a >= 0 else NULL
            arb.b = sptr[ar.b] if ar.b >= 0 else NULL
            arb.body_a = bptr[ar.body_a]
            arb.body_b = bptr[ar.body_b]
            arb.thread_a.next = &m.arbs[ar.ta_next] if ar.ta_next >= 0 else NULL
            arb.thread_a.prev = &m.arbs[ar.ta_prev] if ar.ta_prev >= 0 else NULL
            arb.thread_b.next = &m.arbs[ar.tb_next] if ar.tb_next >= 0 else NULL
            arb.thread_b.prev = &m.arbs[ar.tb_prev] if ar.tb_prev >= 0 else NULL
            arb.count = ar.count
            if ar.ckind == 0:
                arb.contacts = NULL
            else:
                if ar.ckind == 1:
                    arb.contacts = &m.bufs[ar.cbuf].contacts[ar.coff]
                else:
                    arb.contacts = m.heap[k]
                    m.heap[k] = NULL
                memcpy(arb.contacts, cdata, ar.count * sizeof(cpContact))
                cdata += ar.count * sizeof(cpContact)
            arb.handlerAB = _handler_ptr(hptr, ar.handlerAB, nothing)
            arb.handlerBA = _handler_ptr(hptr, ar.handlerBA, nothing)
            arb.handlerA = _handler_ptr(hptr, ar.handlerA, nothing)
            arb.handlerB = _handler_ptr(hptr, ar.handlerB, nothing)
            arb.swapped = ar.swapped
            arb.stamp = ar.stamp
            arb.state = <cpArbiterState>ar.state
            arb.processCollision = ar.processCollision
        for k in range(p.s.nstep_arbiters):
            cpArrayPush(space.arbiters, &m.arbs[p.step_arbs[k]])
        for k in range(p.s.ncached):
            arb = &m.arbs[p.cached[k]]
            pair_key[0] = <cpShape *>arb.a
            pair_key[1] = <cpShape *>arb.b
            cpHashSetInsert(space.cachedArbiters,
                            CP_HASH_PAIR(<cpHashValue>arb.a, <cpHashValue>arb.b),
                            pair_key, NULL, arb)

        # -- bodies and shapes ------------------------------------------------------------------
        for i in range(nb):
            br = &p.bodies[i]
            body = bptr[i]
            body.space = space if br.in_space else NULL
            body.shapeList = sptr[br.shapeList] if br.shapeList >= 0 else NULL
            body.arbiterList = &m.arbs[br.arbiterList] if br.arbiterList >= 0 else NULL
            body.constraintList = NULL
            body.sleeping.root = bptr[br.root] if br.root >= 0 else NULL
            body.sleeping.next = bptr[br.next] if br.next >= 0 else NULL
        for i in range(ns):
            sr = &p.shapes[i]
            shape = sptr[i]
            shape.space = space if sr.in_space else NULL
            shape.next = sptr[sr.next] if sr.next >= 0 else NULL
            shape.prev = sptr[sr.prev] if sr.prev >= 0 else NULL
        for k in range(p.s.ndynamic):
            cpArrayPush(space.dynamicBodies, bptr[p.dynamic[k]])
        for k in range(p.s.nstatic):
            cpArrayPush(space.staticBodies, bptr[p.statics[k]])
        for k in range(p.s.nsleeping):
            cpArrayPush(space.sleepingComponents, bptr[p.sleeping[k]])
        for i in range(len(constraints)):
            con = (<Constraint>constraints[i])._constraint
            con.space = space if p.cons[i].in_space else NULL
            con.next_a = (<Constraint>constraints[p.cons[i].next_a])._constraint \
                if p.cons[i].next_a >= 0 else NULL
            con.next_b = (<Constraint>constraints[p.cons[i].next_b])._constraint \
                if p.cons[i].next_b >= 0 else NULL
        for i in range(nb):
            k = p.bodies[i].constraintList
            bptr[i].constraintList = (<Constraint>constraints[k])._constraint if k >= 0 else NULL
        for k in range(p.s.nstep_constraints):
            cpArrayPush(space.constraints, (<Constraint>constraints[p.step_cons[k]])._constraint)

        # -- broad phase --------------------------------------------------------------------------
        for j in range(2):
            index = space.staticShapes if j == 0 else space.dynamicShapes
            if p.index[j].kind == 1:
                _link_tree(<cpBBTree *>index, &p, j, m.nodes[j], m.nodes, m.pairs, sptr)
            else:
                _link_hash(<cpSpaceHash *>index, &p, j, m.handles[j], m.bins[j], sptr)
        if m.pairs != NULL:
            _link_pairs(&p, m.nodes, m.pairs)

        if cpTakeOutOfMemory():
            raise MemoryError()
    except BaseException:
        if linked:
            _reset_space(sp, bptr, nb, sptr, ns, constraints)
        _blocks_free(&m)
        raise
    finally:
        free(bptr)
        free(sptr)
        free(hptr)
        pm_free(&bodymap)
    _blocks_free(&m)

    # -- the Python side ------------------------------------------------------------------------
    ref = weakref.ref(sp)
    n_in = p.s.nspace_bodies
    sp._bodies = dict.fromkeys(table[:n_in])
    if p.s.has_static:
        sp._static_body = table[n_in]
    for i in range(nb):
        (<Body>table[i])._space = ref if p.bodies[i].in_space else None
    sp._shapes = dict.fromkeys(shapes)
    sp._constraints = dict.fromkeys(constraints)
    for i in range(ns):
        (<Shape>shapes[i])._space = ref if p.shapes[i].in_space else None
    # Body.shapes in the original order.
    k = 0
    for i in range(nb):
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


cdef int _corrupt(str what) except -1:
    raise CopyError(f"the snapshot of the space is corrupt ({what})")


# The linked structures of a parsed snapshot must be proper lists and trees,
# so that a corrupt state is refused here instead of hanging or crashing a
# later step: shape lists, per-body arbiter lists, sleeping chains, trees
# reachable from their roots, pair lists, spatial hash reference counts.
cdef int _validate(Parsed *p, cpBody **bptr, cpShape **sptr, Py_ssize_t nb,
                   Py_ssize_t ns) except -1:
    cdef int32_t *mark = NULL
    cdef int32_t *stack = NULL
    cdef Py_ssize_t i, steps, big
    cdef int32_t k, j, first, count, top, found
    cdef int32_t cur = -1, prev = -1, nxt = -1
    cdef const ArbRec *a
    cdef const NodeRec *n
    cdef const PairRec *q
    cdef Py_ssize_t n_in = p.s.nspace_bodies + (1 if p.s.has_static else 0)
    big = nb + ns + p.s.narbiters + p.nnodes + p.npairs + p.nhandles + 1
    mark = <int32_t *>cpcalloc(big, sizeof(int32_t))
    stack = <int32_t *>malloc((2 * p.nnodes + 2) * sizeof(int32_t))
    if mark == NULL or stack == NULL:
        free(mark)
        free(stack)
        cpTakeOutOfMemory()
        raise MemoryError()
    try:
        # bodies and shapes in the space
        for i in range(nb):
            if p.bodies[i].in_space != (1 if i < n_in else 0):
                _corrupt("body in or out of the space")
        for i in range(ns):
            if p.shapes[i].in_space != 1:
                _corrupt("shape outside the space")
        for k in range(p.s.ndynamic):
            if p.dynamic[k] >= n_in:
                _corrupt("body array")
        for k in range(p.s.nstatic):
            if p.statics[k] >= n_in:
                _corrupt("body array")
        for k in range(p.s.nsleeping):
            if p.sleeping[k] >= n_in:
                _corrupt("body array")
        # shape lists: each shape in at most one list, its own body's
        for i in range(nb):
            prev = -1
            cur = p.bodies[i].shapeList
            while cur >= 0:
                if mark[cur] or p.shapes[cur].prev != prev or sptr[cur].body != bptr[i]:
                    _corrupt("shape list")
                mark[cur] = 1
                prev = cur
                cur = p.shapes[cur].next
        # arbiters: bodies are their shapes' bodies; per-body lists are proper
        for k in range(p.s.narbiters):
            a = &p.arbs[k]
            if a.body_a == a.body_b:
                _corrupt("arbiter bodies")
            if (a.a >= 0 and sptr[a.a].body != bptr[a.body_a]) or \
                    (a.b >= 0 and sptr[a.b].body != bptr[a.body_b]):
                _corrupt("arbiter bodies")
        for i in range(nb):
            prev = -1
            cur = p.bodies[i].arbiterList
            steps = 0
            while cur >= 0:
                a = &p.arbs[cur]
                steps += 1
                if steps > p.s.narbiters:
                    _corrupt("arbiter list")
                if a.body_a == i:
                    if a.ta_prev != prev:
                        _corrupt("arbiter list")
                    nxt = a.ta_next
                elif a.body_b == i:
                    if a.tb_prev != prev:
                        _corrupt("arbiter list")
                    nxt = a.tb_next
                else:
                    _corrupt("arbiter list")
                prev = cur
                cur = nxt
        # constraint lists (cpConstraintNext: next_a when the body is a)
        for i in range(nb):
            cur = p.bodies[i].constraintList
            steps = 0
            while cur >= 0:
                steps += 1
                if steps > p.s.nconstraints or (p.cons[cur].a != i and p.cons[cur].b != i):
                    _corrupt("constraint list")
                cur = p.cons[cur].next_a if p.cons[cur].a == i else p.cons[cur].next_b
        # sleeping chains end
        for i in range(nb):
            cur = p.bodies[i].root
            if cur < 0:
                continue
            steps = 0
            while cur >= 0:
                steps += 1
                if steps > nb:
                    _corrupt("sleeping component")
                cur = p.bodies[cur].next
        # trees: every node reachable from the root, the leaves set = the
        # leaves, each shape in one leaf or handle at most
        memset(mark, 0, big * sizeof(int32_t))
        for j in range(2):
            first = p.index[j].first
            count = p.index[j].count
            if p.index[j].kind == 1:
                found = 0
                top = 0
                if p.index[j].root >= 0:
                    stack[0] = p.index[j].root
                    top = 1
                while top > 0:
                    top -= 1
                    cur = stack[top]
                    found += 1
                    if found > count:
                        _corrupt("tree")
                    n = &p.nodes[cur]
                    if n.obj >= 0:
                        if mark[n.obj]:
                            _corrupt("a shape in two leaves")
                        mark[n.obj] = 1
                    else:
                        stack[top] = n.a
                        stack[top + 1] = n.bchild
                        top += 2
                if found != count:
                    _corrupt("tree")
                for k in range(p.index[j].set_count):
                    if mark[ns + p.sets[j][k].elt] :
                        _corrupt("tree leaves")
                    mark[ns + p.sets[j][k].elt] = 1
            else:
                for k in range(p.index[j].set_count):
                    cur = p.sets[j][k].elt
                    if mark[ns + p.nnodes + cur] & 1 or mark[p.handles[cur].obj]:
                        _corrupt("hash handles")
                    mark[ns + p.nnodes + cur] |= 1
                    mark[p.handles[cur].obj] = 1
        # leaves counted: each leaf in the set exactly once
        for j in range(2):
            if p.index[j].kind == 1:
                for k in range(p.index[j].first, p.index[j].first + p.index[j].count):
                    if (p.nodes[k].obj >= 0) != (mark[ns + k] == 1):
                        _corrupt("tree leaves")
        # pair lists
        steps = 0
        for k in range(p.nnodes):
            if p.nodes[k].obj < 0:
                continue
            prev = -1
            cur = p.nodes[k].pairs
            while cur >= 0:
                q = &p.pairs[cur]
                steps += 1
                if steps > 2 * p.npairs or q.a_leaf == q.b_leaf:
                    _corrupt("pair list")
                if q.a_leaf == k:
                    if q.a_prev != prev:
                        _corrupt("pair list")
                    nxt = q.a_next
                elif q.b_leaf == k:
                    if q.b_prev != prev:
                        _corrupt("pair list")
                    nxt = q.b_next
                else:
                    _corrupt("pair list")
                prev = cur
                cur = nxt
        if steps != 2 * p.npairs:
            _corrupt("pair list")
        # spatial hash: a handle's count = its cells + the set
        for j in range(2):
            if p.index[j].kind != 2:
                continue
            _check_retain(p, j, mark, ns + p.nnodes)
    finally:
        free(mark)
        free(stack)
    return 0


cdef int _check_retain(Parsed *p, int j, int32_t *mark, Py_ssize_t base) except -1:
    # mark[base + h] bit 0: in the set; the rest counts cells.
    cdef const char *cur = p.cells[j]
    cdef const CellRec *cell
    cdef const int32_t *ids
    cdef int32_t c, k, first = p.index[j].first
    for c in range(p.index[j].ncells):
        cell = <const CellRec *>cur
        ids = <const int32_t *>(cur + sizeof(CellRec))
        cur += sizeof(CellRec) + cell.length * sizeof(int32_t)
        for k in range(cell.length):
            mark[base + ids[k]] += 2
    for k in range(first, first + p.index[j].count):
        if (mark[base + k] & 1) != (p.handles[k].obj >= 0):
            _corrupt("hash handles")
        if p.handles[k].retain != (mark[base + k] >> 1) + (mark[base + k] & 1):
            _corrupt("hash handle counts")
    return 0


# Overwrite a shape's struct with the exact bytes at data (its body, class
# and Python links kept); returns the end of what it read.
cdef const char *_set_shape_struct(Shape s, int kind, const char *data) except NULL:
    cdef size_t size
    cdef void *dst = _shape_struct(s, kind, &size)
    cdef const cpShapeClass *klass = s._shape.klass
    cdef cpBody *body = s._shape.body
    cdef const cpPolyShape *src
    cdef cpPolyShape *poly
    cdef cpSplittingPlane *heap = NULL
    cdef int count
    cdef const char *end = data + size
    if kind == 2:
        src = <const cpPolyShape *>data
        count = src.count
        if count > CP_POLY_SHAPE_INLINE_ALLOC:
            heap = <cpSplittingPlane *>malloc(2 * count * sizeof(cpSplittingPlane))
            if heap == NULL:
                raise MemoryError()
            memcpy(heap, end, 2 * count * sizeof(cpSplittingPlane))
            end += 2 * count * sizeof(cpSplittingPlane)
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
    return end


cdef int _check_shapes_distinct(cpShape **sptr, Py_ssize_t ns) except -1:
    cdef PtrMap mp
    cdef Py_ssize_t i
    pm_init(&mp, ns)
    try:
        for i in range(ns):
            if pm_add(&mp, sptr[i]) != i:
                raise CopyError("the space state lists a shape twice")
    finally:
        pm_free(&mp)
    return 0


cdef inline cpCollisionHandler *_handler_ptr(cpCollisionHandler **hptr, int32_t i,
                                             cpCollisionHandler *nothing) noexcept nogil:
    if i == -1:
        return nothing
    if i == -2:
        return NULL
    return hptr[i]


cdef void _link_tree(cpBBTree *tree, Parsed *p, int j, Node *block, Node **blocks,
                     Pair *pairs, cpShape **sptr) noexcept nogil:
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
            node.obj = sptr[r.obj]
            node.node.leaf.stamp = r.stamp
            node.node.leaf.pairs = &pairs[r.pairs] if r.pairs >= 0 else NULL
        else:
            node.obj = NULL
            node.node.children.a = &block[r.a - first]
            node.node.children.b = &block[r.bchild - first]
    tree.root = &block[p.index[j].root - first] if p.index[j].root >= 0 else NULL
    tree.stamp = p.index[j].stamp
    # Head insertion reverses: insert each bucket's chain backwards.
    for k in range(p.index[j].set_count - 1, -1, -1):
        e = &p.sets[j][k]
        node = &block[e.elt - first]
        cpHashSetInsert(tree.leaves, <cpHashValue>e.hash, node.obj, NULL, node)


cdef inline Node *_node_at(Parsed *p, Node **blocks, int32_t g) noexcept nogil:
    # Node number -> node, whichever tree it is in.
    if g >= p.index[1].first and p.index[1].kind == 1 and p.index[0].kind == 1 \
            and g - p.index[1].first < p.index[1].count:
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
        q.id = r.id


cdef void _link_hash(cpSpaceHash *hsh, Parsed *p, int j, cpHandle *handles,
                     cpSpaceHashBin *bins, cpShape **sptr) noexcept nogil:
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
        hand.obj = sptr[r.obj] if r.obj >= 0 else NULL
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


# After a failure half way through linking: a new empty C space again, and
# bodies and shapes without links.
cdef void _reset_space(Space sp, cpBody **bptr, Py_ssize_t nb, cpShape **sptr,
                       Py_ssize_t ns, list constraints) noexcept:
    cdef Py_ssize_t i
    cdef cpArbiter *arb
    for i in range(nb):
        bptr[i].space = NULL
        bptr[i].shapeList = NULL
        bptr[i].arbiterList = NULL
        bptr[i].constraintList = NULL
        bptr[i].sleeping.root = NULL
        bptr[i].sleeping.next = NULL
    for i in range(ns):
        sptr[i].space = NULL
        sptr[i].next = NULL
        sptr[i].prev = NULL
    for obj in constraints:
        (<Constraint>obj)._constraint.space = NULL
        (<Constraint>obj)._constraint.next_a = NULL
        (<Constraint>obj)._constraint.next_b = NULL
    cpSpaceDestroy(&sp._space)
    if cpSpaceInit(&sp._space) == NULL:
        sp._initialized = False
    sp._space.userData = <void *>sp
    cpTakeOutOfMemory()


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
    for key, hd in handlers:
        if key is None:
            a = b = None
        elif isinstance(key, tuple):
            a, b = key
        else:
            a, b = key, None
        sp.on_collision(a, b, begin=hd.get("_begin"), pre_solve=hd.get("_pre_solve"),
                        post_solve=hd.get("_post_solve"), separate=hd.get("_separate"))
        sp._handlers[(a, b)].data.update(hd.get("_data", {}))


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
    for i, f in funcs:
        c = constraints[i]
        if isinstance(c, DampedSpring):
            c.force_func = f
        elif isinstance(c, DampedRotarySpring):
            c.torque_func = f
        else:
            raise CopyError("the snapshot of the space is corrupt (spring function)")


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
    sp.__init__(*[v for k, v in state["init"]])
    for k, v in state["general"]:
        setattr(sp, k, v)
    for k, v in state["custom"]:
        setattr(sp, k, v)
    bodies = shapes = constraints = handlers = static = snapshot = None
    counters = {}
    for k, v in state["special"]:
        if k == "pymunk_version":
            if v != tamias2d.version:
                raise CopyError(f"Pymunk version {v} of pickled object does not match current "
                                f"Pymunk version {tamias2d.version} (tamias2d)")
        elif k == "bodies":
            bodies = list(v)
        elif k == "_static_body":
            static = v
        elif k == "shapes":
            shapes = list(v)
        elif k == "constraints":
            constraints = list(v)
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
        table = list(bodies or ()) + ([static] if static is not None else []) + list(extra)
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
