"""Test-only scaffolding of tamias2d: C functions that pymunk's API does not
reach, wrapped for the tests (and the collision benchmark). Not part of the API.

Nothing here is used by the engine; the engine modules keep no test hooks of
their own except the allocation-failure hook of ``_containers``, which has to
write that module's thread-local C state and is re-exported here. By the
module each section exercises:

- ``_containers``: ``_TestArray`` (cpArray), ``_TestHashSet`` (cpHashSet),
  ``_next_prime`` (prime.h), ``_set_alloc_failure`` and
  ``_take_out_of_memory`` (re-exported);
- ``_bbtree`` and ``_spacehash``: ``_TestTree``, a static and a dynamic index
  of plain boxes (two trees, or two spatial hashes), driven through the
  cpSpatialIndex dispatchers of ``_spatialindex``;
- ``vector``: the round trips of the C boundary helpers, ``_mis_constants``
  and ``_kernel`` (every inline kernel of vector.pxd, by name);
- ``shape``: ``_convex_hull``, ``_moment_for_box2``, ``_filter_reject``,
  ``_new_shape_summary``;
- ``collision``: ``_bias_velocity``, ``_collide``, ``_collision_table_call``,
  ``_collide_loop``;
- ``body``: ``_run_velocity_func``, ``_run_position_func``;
- ``_step_spaces``: ``_step_spaces_c``, the bare C loop of steps.

The inline C functions called here are compiled into this module with the
same flags as the engine modules, so they give the engine's bits.
"""
from libc.stdlib cimport malloc, free
from libc.stdint cimport uintptr_t, uint32_t
from cpython.ref cimport PyObject

from tamias2d._config cimport cpFloat, cpHashValue, cpCollisionID, cpBool, CP_MAX_CONTACTS_PER_ARBITER
from tamias2d._structs cimport (cpArray, cpHashSet, cpHashSetBin, cpSpatialIndex, cpShape, cpSpace,
    cpShapeFilter, cpContact, cpCollisionInfo, CP_NUM_SHAPES)
from tamias2d.vector cimport (cpVect, cpBB, cpTransform, cpMat2x2, cpfmax, cpfmin, cpfabs,
    cpfclamp, cpfclamp01, cpflerp, cpflerpconst, cpv, cpvzero, VECT_ERR, CP_PI, cpveql,
    cpvadd, cpvsub, cpvneg, cpvmult, cpvdot, cpvcross, cpvperp, cpvrperp, cpvproject,
    cpvforangle, cpvtoangle, cpvrotate, cpvunrotate, cpvlengthsq, cpvlength, cpvlerp,
    cpvnormalize, cpvslerp, cpvslerpconst, cpvclamp, cpvlerpconst, cpvdist, cpvdistsq,
    cpvnear, cpMat2x2New, cpMat2x2Transform, cpClosetPointOnSegment, cpBBNew,
    cpBBNewForExtents, cpBBNewForCircle, cpBBIntersects, cpBBContainsBB, cpBBContainsVect,
    cpBBMerge, cpBBExpand, cpBBCenter, cpBBArea, cpBBMergedArea, cpBBSegmentQuery,
    cpBBIntersectsSegment, cpBBClampVect, cpBBWrapVect, cpBBOffset, cpTransformNew,
    cpTransformNewTranspose, cpTransformIdentity, cpTransformInverse, cpTransformMult,
    cpTransformPoint, cpTransformVect, cpTransformbBB, cpTransformTranslate,
    cpTransformScale, cpTransformRotate, cpTransformRigid, cpTransformRigidInverse,
    cpTransformWrap, cpTransformWrapInverse, vec2d_from_cpv, cpv_from_object,
    cpv_from_object_finite, bb_from_cpbb, cpbb_from_object, transform_from_cp,
    cptransform_from_object)
from tamias2d._containers cimport (cpcalloc, cpTakeOutOfMemory, cpArrayNew, cpArrayFree,
    cpArrayPush, cpArrayPop, cpArrayDeleteObj, cpArrayFreeEach, cpArrayContains, next_prime,
    cpHashSetNew, cpHashSetFree, cpHashSetSetDefaultValue, cpHashSetCount, cpHashSetInsert,
    cpHashSetRemove, cpHashSetFind, cpHashSetEach, cpHashSetFilter)
from tamias2d._spatialindex cimport (cpSpatialIndexFree, cpSpatialIndexCount,
    cpSpatialIndexEach, cpSpatialIndexContains, cpSpatialIndexInsert, cpSpatialIndexRemove,
    cpSpatialIndexReindex, cpSpatialIndexReindexObject, cpSpatialIndexReindexQuery,
    cpSpatialIndexQuery, cpSpatialIndexSegmentQuery)
from tamias2d._bbtree cimport (cpBBTree, Node, Pair, cpBBTreeNew, cpBBTreeSetVelocityFunc,
    cpBBTreeOptimize, cpBBTreeClass)
from tamias2d._spacehash cimport cpSpaceHashNew
from tamias2d.body cimport Body
from tamias2d.space cimport Space, tamias_space_step
from tamias2d.shape cimport (_VertBuffer, _verts_arg, cpShapeFilterReject, cpShapeUpdate,
    cpShapeFree, cpConvexHull, cpMomentForBox2, cpCircleShapeClass, cpSegmentShapeClass,
    cpCircleShapeNew, cpSegmentShapeNew, cpPolyShapeNew, cpPolyShapeNewRaw, cpBoxShapeNew,
    cpBoxShapeNew2, cpCircleShapeGetRadius, cpSegmentShapeGetRadius, cpPolyShapeGetRadius,
    cpPolyShapeGetCount, cpPolyShapeGetVert)
from tamias2d.collision cimport (cpCollide, cpCollideSoft, collision_check_flags,
    shape_pointer, CollisionFuncs)

# Defined in _containers, next to the thread-local C state they set and read.
from tamias2d._containers import _set_alloc_failure, _take_out_of_memory


# -- _containers: cpArray, cpHashSet, prime.h --------------------------------------------
cdef void _noop_free(void *ptr) noexcept nogil:
    pass


cdef class _TestArray:
    """Test-only view of a cpArray holding small integers as pointers.

    >>> a = _TestArray()
    >>> for i in (1, 2, 3, 4): a.push(i)
    >>> a.delete(1); a.to_list()
    [4, 2, 3]
    """
    cdef cpArray *arr

    def __cinit__(self, int size=0):
        self.arr = cpArrayNew(size)
        if self.arr == NULL:
            cpTakeOutOfMemory()
            raise MemoryError("cpArrayNew failed")

    def __dealloc__(self):
        cpArrayFree(self.arr)

    def push(self, uintptr_t value):
        if not cpArrayPush(self.arr, <void *>value):
            cpTakeOutOfMemory()
            raise MemoryError("cpArrayPush failed")

    def pop(self):
        if self.arr.num == 0:
            raise IndexError("pop from an empty array")
        return <uintptr_t>cpArrayPop(self.arr)

    def delete(self, uintptr_t value):
        cpArrayDeleteObj(self.arr, <void *>value)

    def contains(self, uintptr_t value):
        return bool(cpArrayContains(self.arr, <void *>value))

    def free_each_noop(self):
        cpArrayFreeEach(self.arr, _noop_free)

    def to_list(self):
        return [<uintptr_t>self.arr.arr[i] for i in range(self.arr.num)]

    def slots(self):
        """Every slot up to the capacity (cleared slots read 0)."""
        return [<uintptr_t>self.arr.arr[i] for i in range(self.arr.max)]

    @property
    def num(self):
        return self.arr.num

    @property
    def max(self):
        return self.arr.max


cdef cpBool _int_eql(const void *ptr, const void *elt) noexcept nogil:
    return ptr == elt


cdef void *_int_trans(const void *ptr, void *data) noexcept nogil:
    (<long *>data)[0] += 1
    return <void *>ptr


cdef void _int_collect(void *elt, void *data) noexcept nogil:
    cdef cpArray *out = <cpArray *>data
    cpArrayPush(out, elt)


cdef struct _RemoveCtx:
    cpHashSet *set
    cpArray *out


cdef void _int_collect_remove(void *elt, void *data) noexcept nogil:
    # Removes the element being visited, as cpSpace's iterators may.
    cdef _RemoveCtx *ctx = <_RemoveCtx *>data
    cpArrayPush(ctx.out, elt)
    cpHashSetRemove(ctx.set, <cpHashValue>elt, elt)


cdef struct _FilterCtx:
    cpArray *visited
    uintptr_t modulus
    uintptr_t drop_residue


cdef cpBool _int_filter(void *elt, void *data) noexcept nogil:
    cdef _FilterCtx *ctx = <_FilterCtx *>data
    cpArrayPush(ctx.visited, elt)
    return (<uintptr_t>elt) % ctx.modulus != ctx.drop_residue


cdef class _TestHashSet:
    """Test-only view of a cpHashSet whose elements are nonzero integers.

    The element's own value is the key compared by the set; the hash is given
    separately, so tests control the bucket of every element.

    >>> s = _TestHashSet()
    >>> s.size
    5
    >>> for k in (1, 6, 2): _ = s.insert(k, k)
    >>> s.items()   # bucket 1 holds 6 then 1 (head insertion), bucket 2 holds 2
    [6, 1, 2]
    """
    cdef cpHashSet *set
    cdef long trans_calls

    def __cinit__(self, int size=0):
        self.set = cpHashSetNew(size, _int_eql)
        if self.set == NULL:
            cpTakeOutOfMemory()
            raise MemoryError("cpHashSetNew failed")

    def __dealloc__(self):
        cpHashSetFree(self.set)

    def insert(self, cpHashValue hash, uintptr_t key, bint use_trans=False):
        """Insert key (stored through a trans func if use_trans); return the stored element."""
        cdef const void *out
        if key == 0:
            raise ValueError("keys must be nonzero")
        if use_trans:
            out = cpHashSetInsert(self.set, hash, <void *>key, _int_trans, &self.trans_calls)
        else:
            out = cpHashSetInsert(self.set, hash, <void *>key, NULL, <void *>key)
        if out == NULL:
            cpTakeOutOfMemory()
            raise MemoryError("cpHashSetInsert failed")
        return <uintptr_t>out

    def remove(self, cpHashValue hash, uintptr_t key):
        return <uintptr_t>cpHashSetRemove(self.set, hash, <void *>key)

    def find(self, cpHashValue hash, uintptr_t key):
        return <uintptr_t>cpHashSetFind(self.set, hash, <void *>key)

    def set_default(self, uintptr_t value):
        cpHashSetSetDefaultValue(self.set, <void *>value)

    def items(self):
        """Elements in cpHashSetEach order."""
        cdef cpArray *out = cpArrayNew(0)
        cpHashSetEach(self.set, _int_collect, out)
        result = [<uintptr_t>out.arr[i] for i in range(out.num)]
        cpArrayFree(out)
        return result

    def items_removing(self):
        """Visit in cpHashSetEach order, removing each element (hash = key) as it is visited."""
        cdef _RemoveCtx ctx
        ctx.set = self.set
        ctx.out = cpArrayNew(0)
        cpHashSetEach(self.set, _int_collect_remove, &ctx)
        result = [<uintptr_t>ctx.out.arr[i] for i in range(ctx.out.num)]
        cpArrayFree(ctx.out)
        return result

    def filter(self, uintptr_t modulus, uintptr_t drop_residue):
        """Drop elements with key % modulus == drop_residue; return the visit order."""
        cdef _FilterCtx ctx
        ctx.visited = cpArrayNew(0)
        ctx.modulus = modulus
        ctx.drop_residue = drop_residue
        cpHashSetFilter(self.set, _int_filter, &ctx)
        result = [<uintptr_t>ctx.visited.arr[i] for i in range(ctx.visited.num)]
        cpArrayFree(ctx.visited)
        return result

    def buckets(self):
        """The table as a list of chains (head first)."""
        cdef cpHashSetBin *bin
        table = []
        for i in range(self.set.size):
            chain = []
            bin = self.set.table[i]
            while bin != NULL:
                chain.append(<uintptr_t>bin.elt)
                bin = bin.next
            table.append(chain)
        return table

    def pooled_bins(self):
        cdef long n = 0
        cdef cpHashSetBin *bin = self.set.pooledBins
        while bin != NULL:
            n += 1
            bin = bin.next
        return n

    @property
    def size(self):
        return self.set.size

    @property
    def count(self):
        return cpHashSetCount(self.set)

    @property
    def blocks(self):
        return self.set.allocatedBuffers.num

    @property
    def trans_calls(self):
        return self.trans_calls


def _next_prime(int n):
    """Test hook for prime.h's next_prime (0 past the table).

    >>> _next_prime(6)
    13
    """
    return next_prime(n)


# -- _bbtree and _spacehash through the cpSpatialIndex interface -------------------------
cdef struct TestObj:
    long id
    cpBB bb
    cpVect v
    cpFloat t               # what the segment-query callback returns for it
    cpHashValue hashid
    int where               # 0: in no index, 1: dynamic, 2: static


cdef struct TestLogCtx:
    PyObject *log           # borrowed list
    uint32_t counter
    TestObj *query_obj


cdef cpBB _test_bb(void *obj) noexcept nogil:
    return (<TestObj *>obj).bb


cdef cpVect _test_vel(void *obj) noexcept nogil:
    return (<TestObj *>obj).v


cdef inline uint32_t _test_new_id(uint32_t id, long a, long b, uint32_t counter) noexcept nogil:
    # An arbitrary function of everything, so a wrong cached id shows up.
    return <uint32_t>(id * <uint32_t>2654435761u + <uint32_t>a * <uint32_t>40503u
                      + <uint32_t>b * <uint32_t>9973u + counter)


cdef cpCollisionID _test_pair_func(void *obj1, void *obj2, cpCollisionID id, void *data) noexcept nogil:
    cdef TestLogCtx *ctx = <TestLogCtx *>data
    cdef long a = (<TestObj *>obj1).id
    cdef long b = (<TestObj *>obj2).id
    ctx.counter += 1
    with gil:
        (<list>ctx.log).append((a, b, id))
    return _test_new_id(id, a, b, ctx.counter)


cdef cpFloat _test_segment_func(void *obj1, void *obj2, void *data) noexcept nogil:
    cdef TestLogCtx *ctx = <TestLogCtx *>data
    with gil:
        (<list>ctx.log).append((<TestObj *>obj2).id)
    return (<TestObj *>obj2).t


cdef void _test_each_func(void *obj, void *data) noexcept nogil:
    cdef TestLogCtx *ctx = <TestLogCtx *>data
    with gil:
        (<list>ctx.log).append((<TestObj *>obj).id)


cdef class _TestTree:
    """Test-only pair of trees (static, and dynamic linked to it) over boxes.

    Objects are numbered from 0 in order of creation; each insertion takes a
    fresh hash id from a counter, as the space does with shapes. Boxes are
    (l, b, r, t); the dynamic tree fattens them by 10% and by 0.1 * v.

    >>> t = _TestTree()
    >>> a = t.add((0, 0, 1, 1)); b = t.add((0.5, 0.5, 2, 2))
    >>> t.reindex_query()
    [(1, 0, 0)]
    >>> t.query((1.5, 1.5, 3, 3))
    [1]
    """
    cdef cpSpatialIndex *static_index
    cdef cpSpatialIndex *dynamic_index
    cdef TestObj *objs
    cdef int capacity
    cdef int nobjs
    cdef cpHashValue hash_counter
    cdef uint32_t counter

    def __cinit__(self, int capacity=4096, bint fatten=True, spatial_hash=None):
        cdef double dim
        cdef int cells
        self.objs = <TestObj *>cpcalloc(capacity, sizeof(TestObj))
        if spatial_hash is not None:
            # Two spatial hashes, as Space.use_spatial_hash(dim, count) makes.
            dim, cells = spatial_hash
            self.static_index = cpSpaceHashNew(dim, cells, _test_bb, NULL)
            if self.static_index != NULL:
                self.dynamic_index = cpSpaceHashNew(dim, cells, _test_bb, self.static_index)
        else:
            self.static_index = cpBBTreeNew(_test_bb, NULL)
            if self.static_index != NULL:
                self.dynamic_index = cpBBTreeNew(_test_bb, self.static_index)
        if self.objs == NULL or self.static_index == NULL or self.dynamic_index == NULL:
            cpTakeOutOfMemory()
            raise MemoryError("could not create the trees")
        if fatten:
            cpBBTreeSetVelocityFunc(self.dynamic_index, _test_vel)
        self.capacity = capacity

    def __dealloc__(self):
        cpSpatialIndexFree(self.dynamic_index)
        cpSpatialIndexFree(self.static_index)
        free(self.objs)

    cdef TestObj *_obj(self, long oid) except NULL:
        if oid < 0 or oid >= self.nobjs:
            raise IndexError(f"no object {oid}")
        return &self.objs[oid]

    cdef cpSpatialIndex *_index(self, bint static):
        return self.static_index if static else self.dynamic_index

    cdef cpBBTree *_tree(self, bint static) except NULL:
        cdef cpSpatialIndex *index = self._index(static)
        if index.klass != cpBBTreeClass():
            raise TypeError("this test index is a spatial hash, not a tree")
        return <cpBBTree *>index

    def _check_oom(self):
        if cpTakeOutOfMemory():
            raise MemoryError("the tree ran out of memory")

    def add(self, bb, v=(0.0, 0.0), bint static=False, t=1.0):
        """Create an object with box bb and velocity v, insert it; return its id."""
        if self.nobjs >= self.capacity:
            raise IndexError("test tree is full")
        cdef TestObj *o = &self.objs[self.nobjs]
        o.id = self.nobjs
        o.bb = cpBBNew(bb[0], bb[1], bb[2], bb[3])
        o.v = cpv(v[0], v[1])
        o.t = t
        self.nobjs += 1
        self.insert(o.id, static)
        return o.id

    def insert(self, long oid, bint static=False, hashid=None):
        """(Re)insert an object, with a fresh hash id unless one is given."""
        cdef TestObj *o = self._obj(oid)
        if o.where != 0:
            raise ValueError(f"object {oid} is already in a tree")
        if hashid is None:
            o.hashid = self.hash_counter
            self.hash_counter += 1
        else:
            o.hashid = hashid
        cpSpatialIndexInsert(self._index(static), o, o.hashid)
        self._check_oom()
        o.where = 2 if static else 1

    def remove(self, long oid):
        cdef TestObj *o = self._obj(oid)
        if o.where == 0:
            raise ValueError(f"object {oid} is in no tree")
        cpSpatialIndexRemove(self._index(o.where == 2), o, o.hashid)
        o.where = 0

    def move_to(self, long oid, bint static):
        """Remove and reinsert with the same hash id (what sleeping does)."""
        cdef TestObj *o = self._obj(oid)
        self.remove(oid)
        self.insert(oid, static, o.hashid)

    def set_bb(self, long oid, bb, v=None):
        cdef TestObj *o = self._obj(oid)
        o.bb = cpBBNew(bb[0], bb[1], bb[2], bb[3])
        if v is not None:
            o.v = cpv(v[0], v[1])

    def set_t(self, long oid, double t):
        self._obj(oid).t = t

    def contains(self, long oid, bint static=False):
        cdef TestObj *o = self._obj(oid)
        return bool(cpSpatialIndexContains(self._index(static), o, o.hashid))

    def count(self, bint static=False):
        return cpSpatialIndexCount(self._index(static))

    def each(self, bint static=False):
        cdef list log = []
        cdef TestLogCtx ctx
        ctx.log = <PyObject *>log
        cpSpatialIndexEach(self._index(static), _test_each_func, &ctx)
        return log

    def reindex_query(self):
        """Broad phase of the dynamic tree: [(a, b, cached id passed in), ...]."""
        cdef list log = []
        cdef TestLogCtx ctx
        ctx.log = <PyObject *>log
        ctx.counter = self.counter
        cpSpatialIndexReindexQuery(self.dynamic_index, _test_pair_func, &ctx)
        self.counter = ctx.counter
        self._check_oom()
        return log

    def reindex(self, bint static=True):
        cpSpatialIndexReindex(self._index(static))
        self._check_oom()

    def reindex_object(self, long oid):
        """Reindex one object in both trees, as cpSpaceReindexShape does."""
        cdef TestObj *o = self._obj(oid)
        cpSpatialIndexReindexObject(self.dynamic_index, o, o.hashid)
        cpSpatialIndexReindexObject(self.static_index, o, o.hashid)
        self._check_oom()

    def query(self, bb, static=None):
        """Ids reported by a box query: dynamic then static tree, unless one is chosen."""
        cdef list log = []
        cdef TestLogCtx ctx
        cdef TestObj probe
        cdef cpBB box = cpBBNew(bb[0], bb[1], bb[2], bb[3])
        probe.id = -1
        ctx.log = <PyObject *>log
        ctx.counter = 0
        if static is None or not static:
            cpSpatialIndexQuery(self.dynamic_index, &probe, box, _test_pair_func, &ctx)
        if static is None or static:
            cpSpatialIndexQuery(self.static_index, &probe, box, _test_pair_func, &ctx)
        return [entry[1] for entry in log]

    def segment_query(self, a, b, double t_exit=1.0, static=None):
        """Ids visited by a segment query: static then dynamic tree, as the space does."""
        cdef list log = []
        cdef TestLogCtx ctx
        cdef TestObj probe
        probe.id = -1
        ctx.log = <PyObject *>log
        if static is None or static:
            cpSpatialIndexSegmentQuery(self.static_index, &probe, cpv(a[0], a[1]), cpv(b[0], b[1]),
                                       t_exit, _test_segment_func, &ctx)
        if static is None or not static:
            cpSpatialIndexSegmentQuery(self.dynamic_index, &probe, cpv(a[0], a[1]), cpv(b[0], b[1]),
                                       t_exit, _test_segment_func, &ctx)
        return log

    def optimize(self, bint static=False):
        cpBBTreeOptimize(<cpSpatialIndex *>self._tree(static))
        self._check_oom()

    def leaf_bb(self, long oid):
        """The (fattened) box stored in the object's leaf."""
        cdef TestObj *o = self._obj(oid)
        cdef cpBBTree *tree = self._tree(o.where == 2)
        cdef Node *leaf = <Node *>cpHashSetFind(tree.leaves, o.hashid, o)
        if leaf == NULL:
            return None
        return (leaf.bb.l, leaf.bb.b, leaf.bb.r, leaf.bb.t)

    def pairs(self, long oid):
        """The object's cached pairs, head first: [(a, b, id), ...]."""
        cdef TestObj *o = self._obj(oid)
        cdef cpBBTree *tree = self._tree(o.where == 2)
        cdef Node *leaf = <Node *>cpHashSetFind(tree.leaves, o.hashid, o)
        cdef Pair *pair
        out = []
        if leaf == NULL:
            return out
        pair = leaf.node.leaf.pairs
        while pair != NULL:
            out.append(((<TestObj *>pair.a.leaf.obj).id, (<TestObj *>pair.b.leaf.obj).id, pair.slot.id))
            pair = pair.a.next if pair.a.leaf == leaf else pair.b.next
        return out

    def structure(self, bint static=False):
        """The tree as nested tuples of object ids (A, B), or None when empty."""
        return _structure(self._tree(static).root)

    def check(self, bint static=False):
        """Check parent links and that every internal box is the merge of its children."""
        cdef cpBBTree *tree = self._tree(static)
        if tree.root != NULL and tree.root.parent != NULL:
            raise AssertionError("root has a parent")
        return _check(tree.root)

    @property
    def stamp(self):
        return self._tree(False).stamp


cdef inline bint _node_is_leaf(Node *node) noexcept nogil:
    # As NodeIsLeaf of _bbtree.pyx: only leaves hold an object.
    return node.obj != NULL


cdef object _structure(Node *node):
    if node == NULL:
        return None
    if _node_is_leaf(node):
        return (<TestObj *>node.obj).id
    return (_structure(node.node.children.a), _structure(node.node.children.b))


cdef int _check(Node *node) except -1:
    cdef cpBB m
    if node == NULL or _node_is_leaf(node):
        return 1 if node != NULL else 0
    if node.node.children.a.parent != node or node.node.children.b.parent != node:
        raise AssertionError("broken parent link")
    m = cpBBMerge(node.node.children.a.bb, node.node.children.b.bb)
    if not (m.l == node.bb.l and m.b == node.bb.b and m.r == node.bb.r and m.t == node.bb.t):
        raise AssertionError("internal box is not the merge of its children")
    return _check(node.node.children.a) + _check(node.node.children.b)


# -- vector: the C boundary helpers and the inline kernels -------------------------------
def _cpv_roundtrip(o):
    """``vec2d_from_cpv(cpv_from_object(o))``.

    >>> _cpv_roundtrip([1, 2.5])
    Vec2d(1.0, 2.5)
    """
    return vec2d_from_cpv(cpv_from_object(o))


def _cpv_finite_roundtrip(o, what):
    """``vec2d_from_cpv(cpv_from_object_finite(o, what))``.

    >>> _cpv_finite_roundtrip((1, float("nan")), "position")
    Traceback (most recent call last):
    ...
    tamias2d.errors.IllegalVector: position must be finite, got (1.0, nan)
    """
    return vec2d_from_cpv(cpv_from_object_finite(o, what))


def _cpbb_roundtrip(o):
    """``bb_from_cpbb(cpbb_from_object(o))``.

    >>> _cpbb_roundtrip([0, 1, 2, 3])
    BB(left=0.0, bottom=1.0, right=2.0, top=3.0)
    """
    return bb_from_cpbb(cpbb_from_object(o))


def _cptransform_roundtrip(o):
    """``transform_from_cp(cptransform_from_object(o))``.

    >>> from tamias2d import Transform
    >>> _cptransform_roundtrip(Transform())
    Transform(a=1.0, b=0.0, c=0.0, d=1.0, tx=0.0, ty=0.0)
    """
    return transform_from_cp(cptransform_from_object(o))


def _mis_constants():
    """The MIS 9.3.1 constants as the C side defines them:
    ``(zeroVect, VECT_ERR, PI)``.

    >>> _mis_constants()
    (Vec2d(0.0, 0.0), Vec2d(2147483647.0, -2147483648.0), 3.141592653589793)
    """
    return vec2d_from_cpv(cpvzero()), vec2d_from_cpv(VECT_ERR()), CP_PI


# Every inline kernel of vector.pxd, callable from Python with vectors as
# 2-sequences, boxes as 4-sequences and transforms as 6-sequences, for the
# tests that check the C arithmetic bit for bit.
cdef inline cpVect _cv(object o) except *:
    return cpv_from_object(o)

cdef inline cpBB _cb(object o) except *:
    return cpbb_from_object(o)

cdef inline cpTransform _ct(object o) except *:
    return cptransform_from_object(o)

cdef object _m2(cpMat2x2 m):
    return (m.a, m.b, m.c, m.d)

_KERNELS = {
    "cpfmax": lambda a, b: cpfmax(a, b),
    "cpfmin": lambda a, b: cpfmin(a, b),
    "cpfabs": lambda f: cpfabs(f),
    "cpfclamp": lambda f, lo, hi: cpfclamp(f, lo, hi),
    "cpfclamp01": lambda f: cpfclamp01(f),
    "cpflerp": lambda f1, f2, t: cpflerp(f1, f2, t),
    "cpflerpconst": lambda f1, f2, d: cpflerpconst(f1, f2, d),
    "cpv": lambda x, y: vec2d_from_cpv(cpv(x, y)),
    "cpvzero": lambda: vec2d_from_cpv(cpvzero()),
    "VECT_ERR": lambda: vec2d_from_cpv(VECT_ERR()),
    "cpveql": lambda a, b: bool(cpveql(_cv(a), _cv(b))),
    "cpvadd": lambda a, b: vec2d_from_cpv(cpvadd(_cv(a), _cv(b))),
    "cpvsub": lambda a, b: vec2d_from_cpv(cpvsub(_cv(a), _cv(b))),
    "cpvneg": lambda a: vec2d_from_cpv(cpvneg(_cv(a))),
    "cpvmult": lambda a, s: vec2d_from_cpv(cpvmult(_cv(a), s)),
    "cpvdot": lambda a, b: cpvdot(_cv(a), _cv(b)),
    "cpvcross": lambda a, b: cpvcross(_cv(a), _cv(b)),
    "cpvperp": lambda a: vec2d_from_cpv(cpvperp(_cv(a))),
    "cpvrperp": lambda a: vec2d_from_cpv(cpvrperp(_cv(a))),
    "cpvproject": lambda a, b: vec2d_from_cpv(cpvproject(_cv(a), _cv(b))),
    "cpvforangle": lambda a: vec2d_from_cpv(cpvforangle(a)),
    "cpvtoangle": lambda a: cpvtoangle(_cv(a)),
    "cpvrotate": lambda a, b: vec2d_from_cpv(cpvrotate(_cv(a), _cv(b))),
    "cpvunrotate": lambda a, b: vec2d_from_cpv(cpvunrotate(_cv(a), _cv(b))),
    "cpvlengthsq": lambda a: cpvlengthsq(_cv(a)),
    "cpvlength": lambda a: cpvlength(_cv(a)),
    "cpvlerp": lambda a, b, t: vec2d_from_cpv(cpvlerp(_cv(a), _cv(b), t)),
    "cpvnormalize": lambda a: vec2d_from_cpv(cpvnormalize(_cv(a))),
    "cpvslerp": lambda a, b, t: vec2d_from_cpv(cpvslerp(_cv(a), _cv(b), t)),
    "cpvslerpconst": lambda a, b, t: vec2d_from_cpv(cpvslerpconst(_cv(a), _cv(b), t)),
    "cpvclamp": lambda a, l: vec2d_from_cpv(cpvclamp(_cv(a), l)),
    "cpvlerpconst": lambda a, b, d: vec2d_from_cpv(cpvlerpconst(_cv(a), _cv(b), d)),
    "cpvdist": lambda a, b: cpvdist(_cv(a), _cv(b)),
    "cpvdistsq": lambda a, b: cpvdistsq(_cv(a), _cv(b)),
    "cpvnear": lambda a, b, d: bool(cpvnear(_cv(a), _cv(b), d)),
    "cpMat2x2New": lambda a, b, c, d: _m2(cpMat2x2New(a, b, c, d)),
    "cpMat2x2Transform": lambda m, v: vec2d_from_cpv(
        cpMat2x2Transform(cpMat2x2New(m[0], m[1], m[2], m[3]), _cv(v))),
    "cpClosetPointOnSegment": lambda p, a, b: vec2d_from_cpv(
        cpClosetPointOnSegment(_cv(p), _cv(a), _cv(b))),
    "cpBBNew": lambda l, b, r, t: bb_from_cpbb(cpBBNew(l, b, r, t)),
    "cpBBNewForExtents": lambda c, hw, hh: bb_from_cpbb(cpBBNewForExtents(_cv(c), hw, hh)),
    "cpBBNewForCircle": lambda p, r: bb_from_cpbb(cpBBNewForCircle(_cv(p), r)),
    "cpBBIntersects": lambda a, b: bool(cpBBIntersects(_cb(a), _cb(b))),
    "cpBBContainsBB": lambda a, b: bool(cpBBContainsBB(_cb(a), _cb(b))),
    "cpBBContainsVect": lambda bb, v: bool(cpBBContainsVect(_cb(bb), _cv(v))),
    "cpBBMerge": lambda a, b: bb_from_cpbb(cpBBMerge(_cb(a), _cb(b))),
    "cpBBExpand": lambda bb, v: bb_from_cpbb(cpBBExpand(_cb(bb), _cv(v))),
    "cpBBCenter": lambda bb: vec2d_from_cpv(cpBBCenter(_cb(bb))),
    "cpBBArea": lambda bb: cpBBArea(_cb(bb)),
    "cpBBMergedArea": lambda a, b: cpBBMergedArea(_cb(a), _cb(b)),
    "cpBBSegmentQuery": lambda bb, a, b: cpBBSegmentQuery(_cb(bb), _cv(a), _cv(b)),
    "cpBBIntersectsSegment": lambda bb, a, b: bool(cpBBIntersectsSegment(_cb(bb), _cv(a), _cv(b))),
    "cpBBClampVect": lambda bb, v: vec2d_from_cpv(cpBBClampVect(_cb(bb), _cv(v))),
    "cpBBWrapVect": lambda bb, v: vec2d_from_cpv(cpBBWrapVect(_cb(bb), _cv(v))),
    "cpBBOffset": lambda bb, v: bb_from_cpbb(cpBBOffset(_cb(bb), _cv(v))),
    "cpTransformNew": lambda a, b, c, d, tx, ty: transform_from_cp(cpTransformNew(a, b, c, d, tx, ty)),
    "cpTransformNewTranspose": lambda a, c, tx, b, d, ty: transform_from_cp(
        cpTransformNewTranspose(a, c, tx, b, d, ty)),
    "cpTransformIdentity": lambda: transform_from_cp(cpTransformIdentity()),
    "cpTransformInverse": lambda t: transform_from_cp(cpTransformInverse(_ct(t))),
    "cpTransformMult": lambda t1, t2: transform_from_cp(cpTransformMult(_ct(t1), _ct(t2))),
    "cpTransformPoint": lambda t, p: vec2d_from_cpv(cpTransformPoint(_ct(t), _cv(p))),
    "cpTransformVect": lambda t, v: vec2d_from_cpv(cpTransformVect(_ct(t), _cv(v))),
    "cpTransformbBB": lambda t, bb: bb_from_cpbb(cpTransformbBB(_ct(t), _cb(bb))),
    "cpTransformTranslate": lambda v: transform_from_cp(cpTransformTranslate(_cv(v))),
    "cpTransformScale": lambda sx, sy: transform_from_cp(cpTransformScale(sx, sy)),
    "cpTransformRotate": lambda a: transform_from_cp(cpTransformRotate(a)),
    "cpTransformRigid": lambda v, a: transform_from_cp(cpTransformRigid(_cv(v), a)),
    "cpTransformRigidInverse": lambda t: transform_from_cp(cpTransformRigidInverse(_ct(t))),
    "cpTransformWrap": lambda o, i: transform_from_cp(cpTransformWrap(_ct(o), _ct(i))),
    "cpTransformWrapInverse": lambda o, i: transform_from_cp(cpTransformWrapInverse(_ct(o), _ct(i))),
}


def _kernel(name, *args):
    """Call the inline C kernel ``name`` of vector.pxd (a testing hook).

    >>> _kernel("cpvadd", (1, 2), (0.5, 0.5))
    Vec2d(1.5, 2.5)
    >>> _kernel("cpvnormalize", (0, 0))
    Vec2d(0.0, 0.0)
    """
    return _KERNELS[name](*args)


# -- shape: C functions pymunk's API does not reach directly -----------------------------
def _convex_hull(vertices, tol=0.0):
    """cpConvexHull into a separate result array; returns (hull, first).

    >>> _convex_hull([(0, 0), (1, 1), (2, 0), (1, -1), (1, 0)])
    ([Vec2d(0.0, 0.0), Vec2d(1.0, -1.0), Vec2d(2.0, 0.0), Vec2d(1.0, 1.0)], 0)
    """
    cdef _VertBuffer buf = _verts_arg(vertices, False)
    cdef cpVect *result = <cpVect *>malloc(buf.count * sizeof(cpVect))
    cdef int first = -1
    cdef int n, i
    if result == NULL:
        raise MemoryError()
    try:
        n = cpConvexHull(buf.count, buf.verts, result, &first, tol)
        return [vec2d_from_cpv(result[i]) for i in range(n)], first
    finally:
        free(result)

def _moment_for_box2(mass, bb):
    """cpMomentForBox2: moment of a box given by its BB, about the origin.

    >>> _moment_for_box2(12, (0, 0, 2, 2))
    32.0
    """
    return cpMomentForBox2(mass, cpbb_from_object(bb))

def _filter_reject(a, b):
    """cpShapeFilterReject on two (group, categories, mask) triples.

    >>> _filter_reject((1, 1, 1), (1, 1, 1))
    True
    """
    cdef cpShapeFilter fa, fb
    fa.group, fa.categories, fa.mask = a
    fb.group, fb.categories, fb.mask = b
    return bool(cpShapeFilterReject(fa, fb))

def _new_shape_summary(kind, *args):
    """Build a shape with a cp*ShapeNew function (heap allocated), cache it
    with the identity transform and return (type, mass, moment per unit mass,
    cog, area, bb, vertices or None, radius), then free it. kind is one of
    "circle" (radius, offset), "segment" (a, b, radius), "poly" (vertices,
    transform, radius), "poly_raw" (vertices, radius), "box" (width, height,
    radius), "box2" (bb, radius).

    >>> _new_shape_summary("box", 2, 4, 0)[6]
    [Vec2d(1.0, -2.0), Vec2d(1.0, 2.0), Vec2d(-1.0, 2.0), Vec2d(-1.0, -2.0)]
    """
    cdef cpShape *shape = NULL
    cdef _VertBuffer buf
    cdef cpBB bb
    cdef int i
    if kind == "circle":
        shape = cpCircleShapeNew(NULL, args[0], cpv_from_object(args[1]))
    elif kind == "segment":
        shape = cpSegmentShapeNew(NULL, cpv_from_object(args[0]), cpv_from_object(args[1]), args[2])
    elif kind == "poly":
        buf = _verts_arg(args[0], False)
        shape = cpPolyShapeNew(NULL, buf.count, buf.verts, cptransform_from_object(args[1]), args[2])
    elif kind == "poly_raw":
        buf = _verts_arg(args[0], False)
        shape = cpPolyShapeNewRaw(NULL, buf.count, buf.verts, args[1])
    elif kind == "box":
        shape = cpBoxShapeNew(NULL, args[0], args[1], args[2])
    elif kind == "box2":
        shape = cpBoxShapeNew2(NULL, cpbb_from_object(args[0]), args[1])
    else:
        raise ValueError(f"unknown kind {kind!r}")
    if shape == NULL:
        raise MemoryError()
    try:
        bb = cpShapeUpdate(shape, cpTransformIdentity())
        verts = None
        if shape.klass == &cpCircleShapeClass:
            radius = cpCircleShapeGetRadius(shape)
        elif shape.klass == &cpSegmentShapeClass:
            radius = cpSegmentShapeGetRadius(shape)
        else:
            radius = cpPolyShapeGetRadius(shape)
            verts = [vec2d_from_cpv(cpPolyShapeGetVert(shape, i))
                     for i in range(cpPolyShapeGetCount(shape))]
        return (<int>shape.klass.type, shape.massInfo.m, shape.massInfo.i,
                vec2d_from_cpv(shape.massInfo.cog), shape.massInfo.area,
                bb_from_cpbb(bb), verts, radius)
    finally:
        cpShapeFree(shape)


# -- collision: the narrow phase without a space -----------------------------------------
def _bias_velocity(Body body not None):
    """(v_bias, w_bias) of a body, for tests of the bias impulse helpers.

    >>> import tamias2d
    >>> _bias_velocity(tamias2d.Body(1, 1))
    (Vec2d(0.0, 0.0), 0.0)
    """
    return vec2d_from_cpv(body._body.v_bias), body._body.w_bias


def _collide(shape_a, shape_b, collision_id=0, margin=0.0, soft=False):
    """cpCollide on two shapes: returns (a_is_first, id, normal, contacts)
    where contacts is a list of (r1, r2, hash); a_is_first is False when the
    types were sorted by swapping the pair (then r1 is on shape_b).

    >>> import tamias2d
    >>> b = tamias2d.Body(1, 1)
    >>> c1, c2 = tamias2d.Circle(b, 1), tamias2d.Circle(b, 1)
    >>> _ = c1.cache_bb(), c2.cache_bb()
    >>> _collide(c1, c2)
    (True, 0, Vec2d(1.0, 0.0), [(Vec2d(1.0, 0.0), Vec2d(-1.0, 0.0), 0)])
    """
    cdef const cpShape *a = shape_pointer(shape_a, "shape_a")
    cdef const cpShape *b = shape_pointer(shape_b, "shape_b")
    cdef cpContact contacts[CP_MAX_CONTACTS_PER_ARBITER]
    cdef cpCollisionInfo info
    cdef cpCollisionID cid = collision_id
    cdef int i
    # soft: the soft solver's narrow phase (polygons by separating axes).
    if soft:
        info = cpCollideSoft(a, b, cid, contacts, margin)
    else:
        info = cpCollide(a, b, cid, contacts, margin)
    collision_check_flags()
    return (info.a == a, info.id, vec2d_from_cpv(info.n),
            [(vec2d_from_cpv(contacts[i].r1), vec2d_from_cpv(contacts[i].r2), contacts[i].hash)
             for i in range(info.count)])


def _collision_table_call(shape_a, shape_b):
    """Call the collision table slot of (shape_a.type, shape_b.type) without
    sorting the types, as cpCollide never does; for testing the unsorted
    (error) slots, which raise CollisionError.

    >>> import tamias2d
    >>> b = tamias2d.Body(1, 1)
    >>> _collision_table_call(tamias2d.Segment(b, (0, 0), (1, 0), 1), tamias2d.Circle(b, 1))
    Traceback (most recent call last):
    ...
    tamias2d.errors.CollisionError: Internal Error: Shape types are not sorted.
    """
    cdef const cpShape *a = shape_pointer(shape_a, "shape_a")
    cdef const cpShape *b = shape_pointer(shape_b, "shape_b")
    cdef cpContact contacts[CP_MAX_CONTACTS_PER_ARBITER]
    cdef cpCollisionInfo info
    info.a = a
    info.b = b
    info.id = 0
    info.n = cpv(0.0, 0.0)
    info.count = 0
    info.arr = contacts
    CollisionFuncs[<unsigned int>a.klass.type + <unsigned int>b.klass.type * CP_NUM_SHAPES](a, b, &info)
    collision_check_flags()
    return info.count


def _collide_loop(pairs, long rounds):
    """Run cpCollide over a list of (shape_a, shape_b) pairs `rounds` times
    in C without the GIL; returns the total number of contacts (benchmarks).

    >>> import tamias2d
    >>> b = tamias2d.Body(1, 1)
    >>> _collide_loop([(tamias2d.Circle(b, 1), tamias2d.Circle(b, 1))], 10)
    10
    """
    cdef list keep = [tuple(pair) for pair in pairs]
    cdef Py_ssize_t n = len(keep), k
    cdef long r
    cdef long long total = 0
    cdef cpContact contacts[CP_MAX_CONTACTS_PER_ARBITER]
    cdef cpCollisionInfo info
    cdef const cpShape **ptrs = <const cpShape **>malloc((2 * n + 1) * sizeof(cpShape *))
    if ptrs == NULL:
        raise MemoryError()
    try:
        for k in range(n):
            ptrs[2 * k] = shape_pointer(keep[k][0], "shape_a")
            ptrs[2 * k + 1] = shape_pointer(keep[k][1], "shape_b")
        with nogil:
            for r in range(rounds):
                for k in range(n):
                    info = cpCollide(ptrs[2 * k], ptrs[2 * k + 1], 0, contacts, 0.0)
                    total += info.count
    finally:
        free(ptrs)
    collision_check_flags()
    return total


# -- body: the integrators through the C function pointers -------------------------------
def _run_velocity_func(Body body not None, gravity, double damping, double dt):
    """Call the body's velocity integrator the way a step does (for tests).

    >>> import tamias2d
    >>> from tamias2d._testing import _run_velocity_func
    >>> b = tamias2d.Body(1, 1)
    >>> _run_velocity_func(b, (0, -10), 1.0, 0.1)
    >>> b.velocity
    Vec2d(0.0, -1.0)
    """
    cdef cpVect g = cpv_from_object(gravity)
    body._body.velocity_func(&body._body, g, damping, dt)


def _run_position_func(Body body not None, double dt):
    """Call the body's position integrator the way a step does (for tests).

    >>> import tamias2d
    >>> from tamias2d._testing import _run_position_func
    >>> b = tamias2d.Body(1, 1)
    >>> b.velocity = 1, 0
    >>> _run_position_func(b, 0.5)
    >>> b.position
    Vec2d(0.5, 0.0)
    """
    body._body.position_func(&body._body, dt)


# -- _step_spaces: the bare C loop that step_spaces is measured against ------------------
def _step_spaces_c(spaces, double dt, long steps):
    """Step every space `steps` times (each space's steps in a row) by
    calling the C step in one loop without the GIL, on this thread: none of
    the checks of ``Space.step``, no thread guard, no error reports, nothing
    deferred by a callback is run. For benchmarks/bench_vector_env.py (the
    per-space overhead of ``step_spaces``) on plain scenes only.

    >>> import tamias2d
    >>> from tamias2d._testing import _step_spaces_c
    >>> s = tamias2d.Space()
    >>> s.gravity = 0, -10
    >>> b = tamias2d.Body(1, 1)
    >>> s.add(b, tamias2d.Circle(b, 1))
    >>> _step_spaces_c([s], 0.1, 3)
    >>> round(b.position.y, 6)
    -0.3
    """
    cdef list items = list(spaces)
    cdef Py_ssize_t n = len(items), i
    cdef long k
    for s in items:
        if not isinstance(s, Space) or (<Space>s)._locked or (<Space>s)._space.stepThread != 0:
            raise TypeError("spaces must be tamias2d.Space objects, none locked or stepping")
    cdef cpSpace **cs = <cpSpace **>malloc(n * sizeof(cpSpace *) + 1)
    if cs == NULL:
        raise MemoryError()
    for i in range(n):
        cs[i] = &(<Space>items[i])._space
    with nogil:
        for i in range(n):
            for k in range(steps):
                tamias_space_step(cs[i], dt)
    free(cs)
