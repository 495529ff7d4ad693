"""The spatial hash broad phase, ported from Munk2D's cpSpaceHash.c.

Space.use_spatial_hash(dim, count) replaces the space's two BB trees with two
of these. Each object is entered in every cell its box covers; cells map to
table buckets through ``(x*1640531513 ^ y*2654435789) % numcells`` in unsigned
64-bit arithmetic. Objects are reached through handles with a reference
count; a removed object's handle stays in the cells until a query meets it
there and unlinks it. The broad phase rebuilds the table every step, visiting
objects in the order of the handle hash set (keyed by hashid), then collides
the dynamic objects with the static hash.

Out of memory raises the sticky flag of _containers and leaves the operation
incomplete (an object missing from some cells), never a crash.

The hash plugs into the interface of ``_spatialindex`` (cpSpatialIndex.c/.h),
as the tree of ``_bbtree`` does; it does not depend on the tree. The tests
drive it through ``_testing._TestTree(spatial_hash=(dim, count))``.
"""
from libc.stdlib cimport free
from libc.math cimport floor, fabs, INFINITY
from tamias2d._config cimport cpHashValue, cpCollisionID, cpBool, CP_BUFFER_BYTES
from tamias2d.vector cimport cpVect, cpBB, cpvmult, cpfmin, cpfabs
from tamias2d._containers cimport (cpcalloc, cpSetOutOfMemory, cpArrayNew, cpArrayFree,
    cpArrayPush, cpArrayPop, next_prime, cpHashSetNew, cpHashSetFree, cpHashSetInsert,
    cpHashSetRemove, cpHashSetFind, cpHashSetCount, cpHashSetEach)
from tamias2d._structs cimport (cpSpatialIndexIteratorFunc, cpSpatialIndexQueryFunc,
    cpSpatialIndexSegmentQueryFunc)
from tamias2d._spatialindex cimport cpSpatialIndexInit, cpSpatialIndexCollideStatic


cdef cpSpatialIndexClass klass


cdef cpSpatialIndexClass *cpSpaceHashClass() noexcept nogil:
    return &klass


# -- handles ---------------------------------------------------------------------------
cdef inline cpHandle *cpHandleInit(cpHandle *hand, void *obj) noexcept nogil:
    hand.obj = obj
    hand.retain = 0
    hand.stamp = 0
    return hand


cdef inline void cpHandleRetain(cpHandle *hand) noexcept nogil:
    hand.retain += 1


cdef inline void cpHandleRelease(cpHandle *hand, cpArray *pooledHandles) noexcept nogil:
    hand.retain -= 1
    if hand.retain == 0:
        # If the pool cannot grow the handle is only leaked into its block,
        # which is freed with the hash.
        cpArrayPush(pooledHandles, hand)


cdef cpBool handleSetEql(const void *obj, const void *elt) noexcept nogil:
    return obj == (<cpHandle *>elt).obj


cdef void *handleSetTrans(const void *obj, void *data) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>data
    cdef int count, i
    cdef cpHandle *block
    cdef cpHandle *hand
    if hash.pooledHandles.num == 0:
        # Pool empty: one 32 KiB block of handles, pushed in address order.
        count = CP_BUFFER_BYTES // sizeof(cpHandle)
        block = <cpHandle *>cpcalloc(1, CP_BUFFER_BYTES)
        if block == NULL:
            return NULL
        if not cpArrayPush(hash.allocatedBuffers, block):
            free(block)
            return NULL
        for i in range(count):
            if not cpArrayPush(hash.pooledHandles, block + i):
                break
        if hash.pooledHandles.num == 0:
            return NULL
    hand = cpHandleInit(<cpHandle *>cpArrayPop(hash.pooledHandles), <void *>obj)
    cpHandleRetain(hand)
    return hand


# -- bins ------------------------------------------------------------------------------
cdef inline void recycleBin(cpSpaceHash *hash, cpSpaceHashBin *bin) noexcept nogil:
    bin.next = hash.pooledBins
    hash.pooledBins = bin


cdef inline void clearTableCell(cpSpaceHash *hash, int idx) noexcept nogil:
    cdef cpSpaceHashBin *bin = hash.table[idx]
    cdef cpSpaceHashBin *next_bin
    while bin != NULL:
        next_bin = bin.next
        cpHandleRelease(bin.handle, hash.pooledHandles)
        recycleBin(hash, bin)
        bin = next_bin
    hash.table[idx] = NULL


cdef void clearTable(cpSpaceHash *hash) noexcept nogil:
    cdef int i
    for i in range(hash.numcells):
        clearTableCell(hash, i)


cdef inline cpSpaceHashBin *getEmptyBin(cpSpaceHash *hash) noexcept nogil:
    cdef cpSpaceHashBin *bin = hash.pooledBins
    cdef int count, i
    cdef cpSpaceHashBin *block
    if bin != NULL:
        hash.pooledBins = bin.next
        return bin
    count = CP_BUFFER_BYTES // sizeof(cpSpaceHashBin)
    block = <cpSpaceHashBin *>cpcalloc(1, CP_BUFFER_BYTES)
    if block == NULL:
        return NULL
    if not cpArrayPush(hash.allocatedBuffers, block):
        free(block)
        return NULL
    for i in range(1, count):
        recycleBin(hash, block + i)
    return block


# -- memory management -------------------------------------------------------------------
cdef cpSpaceHash *cpSpaceHashAlloc() noexcept nogil:
    return <cpSpaceHash *>cpcalloc(1, sizeof(cpSpaceHash))


cdef bint cpSpaceHashAllocTable(cpSpaceHash *hash, int numcells) noexcept nogil:
    # The new table is made before the old one is freed, so a failure keeps
    # the hash usable (Munk2D frees first).
    cdef cpSpaceHashBin **table = <cpSpaceHashBin **>cpcalloc(numcells, sizeof(cpSpaceHashBin *))
    if table == NULL:
        return False
    free(hash.table)
    hash.numcells = numcells
    hash.table = table
    return True


cdef cpSpatialIndex *cpSpaceHashInit(cpSpaceHash *hash, cpFloat celldim, int numcells,
                                     cpSpatialIndexBBFunc bbfunc,
                                     cpSpatialIndex *staticIndex) noexcept nogil:
    cdef int cells = next_prime(numcells)
    if hash == NULL or cells == 0:
        return NULL
    if cpSpatialIndexInit(<cpSpatialIndex *>hash, &klass, bbfunc, staticIndex) == NULL:
        return NULL
    hash.table = NULL
    hash.numcells = 0
    hash.celldim = celldim
    hash.handleSet = cpHashSetNew(0, handleSetEql)
    hash.pooledHandles = cpArrayNew(0)
    hash.pooledBins = NULL
    hash.allocatedBuffers = cpArrayNew(0)
    hash.stamp = 1
    if (not cpSpaceHashAllocTable(hash, cells) or hash.handleSet == NULL
            or hash.pooledHandles == NULL or hash.allocatedBuffers == NULL):
        free(hash.table)
        cpHashSetFree(hash.handleSet)
        cpArrayFree(hash.pooledHandles)
        cpArrayFree(hash.allocatedBuffers)
        hash.table = NULL
        hash.handleSet = NULL
        hash.pooledHandles = NULL
        hash.allocatedBuffers = NULL
        if staticIndex != NULL:
            staticIndex.dynamicIndex = NULL
        hash.spatialIndex.klass = NULL
        return NULL
    return <cpSpatialIndex *>hash


cdef cpSpatialIndex *cpSpaceHashNew(cpFloat celldim, int cells, cpSpatialIndexBBFunc bbfunc,
                                    cpSpatialIndex *staticIndex) noexcept nogil:
    cdef cpSpaceHash *hash = cpSpaceHashAlloc()
    if hash == NULL:
        return NULL
    if cpSpaceHashInit(hash, celldim, cells, bbfunc, staticIndex) == NULL:
        free(hash)
        return NULL
    return <cpSpatialIndex *>hash


cdef void cpSpaceHashDestroy(cpSpatialIndex *index) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>index
    cdef int i
    if hash.table != NULL:
        clearTable(hash)
    free(hash.table)
    cpHashSetFree(hash.handleSet)
    if hash.allocatedBuffers != NULL:
        for i in range(hash.allocatedBuffers.num):
            free(hash.allocatedBuffers.arr[i])
    cpArrayFree(hash.allocatedBuffers)
    cpArrayFree(hash.pooledHandles)


# -- helpers ------------------------------------------------------------------------------
cdef inline bint containsHandle(cpSpaceHashBin *bin, cpHandle *hand) noexcept nogil:
    while bin != NULL:
        if bin.handle == hand:
            return True
        bin = bin.next
    return False


cdef inline cpHashValue hash_func(cpHashValue x, cpHashValue y, cpHashValue n) noexcept nogil:
    return (x * <cpHashValue>1640531513UL ^ y * <cpHashValue>2654435789UL) % n


cdef inline int floor_int(cpFloat f) noexcept nogil:
    cdef int i = <int>f
    return i - 1 if (f < 0.0 and f != i) else i


# A box covering more cells than this (and more than the table has) is
# taken as covering every cell of the table: Munk2D walks its cells one by
# one, which for a box a few thousand cells wide takes minutes (a soft-solver
# shape whose box grows by its body's travel in the step, at a speed of
# 1e7 per second over 10-unit cells), and past 2**31 cells the cell numbers
# overflow. Every bucket once instead holds the box wherever it reaches;
# queries only report candidates, whose boxes the callers test. Smaller
# boxes keep Munk2D's order of cells, and with it pymunk's order of pairs.
cdef const cpFloat SPACE_HASH_MAX_CELLS = 4194304.0

cdef inline bint cellRange(const cpSpaceHash *hash, cpBB bb, int *l, int *r, int *b,
                           int *t) noexcept nogil:
    # The cells bb covers, or 0 if it covers too many (or is not finite):
    # then every bucket (SPACE_HASH_MAX_CELLS).
    cdef cpFloat dim = hash.celldim
    cdef cpFloat fl = floor(bb.l / dim)
    cdef cpFloat fr = floor(bb.r / dim)
    cdef cpFloat fb = floor(bb.b / dim)
    cdef cpFloat ft = floor(bb.t / dim)
    cdef cpFloat cells = (fr - fl + 1.0) * (ft - fb + 1.0)
    if not (cells <= SPACE_HASH_MAX_CELLS or cells <= 4.0 * hash.numcells):
        return 0    # (NaN too)
    if not (fl >= -2147483647.0 and fr < 2147483647.0 and fb >= -2147483647.0
            and ft < 2147483647.0):
        return 0
    l[0] = floor_int(bb.l / dim)
    r[0] = floor_int(bb.r / dim)
    b[0] = floor_int(bb.b / dim)
    t[0] = floor_int(bb.t / dim)
    return 1

cdef inline void hashHandleIn(cpSpaceHash *hash, cpHandle *hand, cpHashValue idx) noexcept nogil:
    cdef cpSpaceHashBin *bin = hash.table[idx]
    cdef cpSpaceHashBin *newBin
    if containsHandle(bin, hand):
        return          # never twice in the same cell
    newBin = getEmptyBin(hash)
    if newBin == NULL:
        return
    cpHandleRetain(hand)
    newBin.handle = hand
    newBin.next = bin
    hash.table[idx] = newBin

cdef inline void hashHandle(cpSpaceHash *hash, cpHandle *hand, cpBB bb) noexcept nogil:
    cdef int l, r, b, t
    cdef int n = hash.numcells
    cdef int i, j
    if not cellRange(hash, bb, &l, &r, &b, &t):
        for i in range(n):
            hashHandleIn(hash, hand, <cpHashValue>i)
        return
    for i in range(l, r + 1):
        for j in range(b, t + 1):
            hashHandleIn(hash, hand, hash_func(<cpHashValue>i, <cpHashValue>j, <cpHashValue>n))


# -- basic operations -----------------------------------------------------------------------
cdef void cpSpaceHashInsert(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>index
    cdef cpHandle *hand = <cpHandle *>cpHashSetInsert(hash.handleSet, hashid, obj, handleSetTrans, hash)
    if hand == NULL:
        return
    hashHandle(hash, hand, hash.spatialIndex.bbfunc(obj))


cdef void cpSpaceHashRehashObject(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>index
    cdef cpHandle *hand = <cpHandle *>cpHashSetRemove(hash.handleSet, hashid, obj)
    if hand != NULL:
        hand.obj = NULL
        cpHandleRelease(hand, hash.pooledHandles)
        cpSpaceHashInsert(index, obj, hashid)


cdef void rehash_helper(void *elt, void *data) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>data
    cdef cpHandle *hand = <cpHandle *>elt
    hashHandle(hash, hand, hash.spatialIndex.bbfunc(hand.obj))


cdef void cpSpaceHashRehash(cpSpatialIndex *index) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>index
    clearTable(hash)
    cpHashSetEach(hash.handleSet, rehash_helper, hash)


cdef void cpSpaceHashRemove(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>index
    cdef cpHandle *hand = <cpHandle *>cpHashSetRemove(hash.handleSet, hashid, obj)
    if hand != NULL:
        # The cells still point at the handle; queries unlink it lazily.
        hand.obj = NULL
        cpHandleRelease(hand, hash.pooledHandles)


cdef struct EachContext:
    cpSpatialIndexIteratorFunc func
    void *data


cdef void eachHelper(void *elt, void *data) noexcept nogil:
    cdef EachContext *context = <EachContext *>data
    context.func((<cpHandle *>elt).obj, context.data)


cdef void cpSpaceHashEach(cpSpatialIndex *index, cpSpatialIndexIteratorFunc func, void *data) noexcept nogil:
    cdef EachContext context
    context.func = func
    context.data = data
    cpHashSetEach((<cpSpaceHash *>index).handleSet, eachHelper, &context)


cdef void remove_orphaned_handles(cpSpaceHash *hash, cpSpaceHashBin **bin_ptr) noexcept nogil:
    cdef cpSpaceHashBin *bin = bin_ptr[0]
    cdef cpSpaceHashBin *next_bin
    cdef cpHandle *hand
    while bin != NULL:
        hand = bin.handle
        next_bin = bin.next
        if hand.obj == NULL:
            bin_ptr[0] = bin.next
            recycleBin(hash, bin)
            cpHandleRelease(hand, hash.pooledHandles)
        else:
            bin_ptr = &bin.next
        bin = next_bin


# -- queries ----------------------------------------------------------------------------------
cdef inline void query_helper(cpSpaceHash *hash, cpSpaceHashBin **bin_ptr, void *obj,
                              cpSpatialIndexQueryFunc func, void *data) noexcept nogil:
    cdef cpSpaceHashBin *bin
    cdef cpHandle *hand
    cdef void *other
    cdef bint restart = True
    while restart:
        restart = False
        bin = bin_ptr[0]
        while bin != NULL:
            hand = bin.handle
            other = hand.obj
            if hand.stamp == hash.stamp or obj == other:
                pass
            elif other != NULL:
                func(obj, other, 0, data)
                hand.stamp = hash.stamp
            else:
                # A removed object: clean the whole cell, then start it again.
                remove_orphaned_handles(hash, bin_ptr)
                restart = True
                break
            bin = bin.next


cdef void cpSpaceHashQuery(cpSpatialIndex *index, void *obj, cpBB bb, cpSpatialIndexQueryFunc func,
                           void *data) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>index
    cdef int l, r, b, t
    cdef int n = hash.numcells
    cdef cpSpaceHashBin **table = hash.table
    cdef int i, j
    if not cellRange(hash, bb, &l, &r, &b, &t):
        for i in range(n):
            query_helper(hash, &table[i], obj, func, data)
    else:
        for i in range(l, r + 1):
            for j in range(b, t + 1):
                query_helper(hash, &table[hash_func(<cpHashValue>i, <cpHashValue>j, <cpHashValue>n)],
                             obj, func, data)
    hash.stamp += 1


cdef struct QueryRehashContext:
    cpSpaceHash *hash
    cpSpatialIndexQueryFunc func
    void *data


cdef void queryRehash_helper(void *elt, void *data) noexcept nogil:
    cdef cpHandle *hand = <cpHandle *>elt
    cdef QueryRehashContext *context = <QueryRehashContext *>data
    cdef cpSpaceHash *hash = context.hash
    cdef cpSpatialIndexQueryFunc func = context.func
    cdef void *fdata = context.data
    cdef int n = hash.numcells
    cdef void *obj = hand.obj
    cdef cpBB bb = hash.spatialIndex.bbfunc(obj)
    cdef int l, r, b, t
    cdef int i, j
    if not cellRange(hash, bb, &l, &r, &b, &t):
        for i in range(n):
            queryRehashIn(hash, hand, obj, <cpHashValue>i, func, fdata)
    else:
        for i in range(l, r + 1):
            for j in range(b, t + 1):
                queryRehashIn(hash, hand, obj,
                              hash_func(<cpHashValue>i, <cpHashValue>j, <cpHashValue>n), func, fdata)
    # One stamp per object hashed.
    hash.stamp += 1


cdef inline void queryRehashIn(cpSpaceHash *hash, cpHandle *hand, void *obj, cpHashValue idx,
                               cpSpatialIndexQueryFunc func, void *fdata) noexcept nogil:
    # The object's pairs in bucket idx, and the object into it.
    cdef cpSpaceHashBin **table = hash.table
    cdef cpSpaceHashBin *bin = table[idx]
    cdef cpSpaceHashBin *newBin
    if containsHandle(bin, hand):
        return
    # Retain first: func may remove the object.
    cpHandleRetain(hand)
    query_helper(hash, &bin, obj, func, fdata)
    newBin = getEmptyBin(hash)
    if newBin == NULL:
        # Undo the retain; the cell keeps whatever cleanup happened.
        hand.retain -= 1
        table[idx] = bin
        return
    newBin.handle = hand
    newBin.next = bin
    table[idx] = newBin


cdef void cpSpaceHashReindexQuery(cpSpatialIndex *index, cpSpatialIndexQueryFunc func,
                                  void *data) noexcept nogil:
    cdef cpSpaceHash *hash = <cpSpaceHash *>index
    cdef QueryRehashContext context
    clearTable(hash)
    context.hash = hash
    context.func = func
    context.data = data
    cpHashSetEach(hash.handleSet, queryRehash_helper, &context)
    cpSpatialIndexCollideStatic(index, hash.spatialIndex.staticIndex, func, data)


cdef inline cpFloat segmentQuery_helper(cpSpaceHash *hash, cpSpaceHashBin **bin_ptr, void *obj,
                                        cpSpatialIndexSegmentQueryFunc func, void *data) noexcept nogil:
    cdef cpFloat t = 1.0
    cdef cpSpaceHashBin *bin
    cdef cpHandle *hand
    cdef void *other
    cdef bint restart = True
    while restart:
        restart = False
        bin = bin_ptr[0]
        while bin != NULL:
            hand = bin.handle
            other = hand.obj
            if hand.stamp == hash.stamp:
                pass
            elif other != NULL:
                t = cpfmin(t, func(obj, other, data))
                hand.stamp = hash.stamp
            else:
                remove_orphaned_handles(hash, bin_ptr)
                restart = True
                break
            bin = bin.next
    return t


cdef void cpSpaceHashSegmentQuery(cpSpatialIndex *index, void *obj, cpVect a, cpVect b,
                                  cpFloat t_exit, cpSpatialIndexSegmentQueryFunc func,
                                  void *data) noexcept nogil:
    # Walks the cells the segment crosses, in order (a grid ray march).
    cdef cpSpaceHash *hash = <cpSpaceHash *>index
    a = cpvmult(a, 1.0 / hash.celldim)
    b = cpvmult(b, 1.0 / hash.celldim)
    cdef int cell_x, cell_y
    cdef cpFloat t = 0
    cdef int x_inc, y_inc
    cdef cpFloat temp_v, temp_h
    if b.x > a.x:
        x_inc = 1
        temp_h = floor(a.x + 1.0) - a.x
    else:
        x_inc = -1
        temp_h = a.x - floor(a.x)
    if b.y > a.y:
        y_inc = 1
        temp_v = floor(a.y + 1.0) - a.y
    else:
        y_inc = -1
        temp_v = a.y - floor(a.y)
    cdef cpFloat dx = cpfabs(b.x - a.x)
    cdef cpFloat dy = cpfabs(b.y - a.y)
    cdef cpFloat dt_dx = 1.0 / dx if dx else INFINITY
    cdef cpFloat dt_dy = 1.0 / dy if dy else INFINITY
    cdef cpFloat next_h = temp_h * dt_dx if temp_h else dt_dx
    cdef cpFloat next_v = temp_v * dt_dy if temp_v else dt_dy
    cdef int n = hash.numcells
    cdef cpSpaceHashBin **table = hash.table
    cdef cpHashValue idx
    cdef cpFloat crossings = dx + dy + 2.0
    cdef int i
    if (not (crossings <= SPACE_HASH_MAX_CELLS or crossings <= 4.0 * n)
            or not (fabs(a.x) < 2147483647.0 and fabs(a.y) < 2147483647.0)):
        # Across more cells than SPACE_HASH_MAX_CELLS (a segment 1e12 long
        # over 10-unit cells walked for an hour), or from beyond the cells'
        # 32-bit numbers: every bucket once (the callers test each shape).
        for i in range(n):
            t_exit = cpfmin(t_exit, segmentQuery_helper(hash, &table[i], obj, func, data))
        hash.stamp += 1
        return
    cell_x = floor_int(a.x)
    cell_y = floor_int(a.y)
    while t < t_exit:
        idx = hash_func(<cpHashValue>cell_x, <cpHashValue>cell_y, <cpHashValue>n)
        t_exit = cpfmin(t_exit, segmentQuery_helper(hash, &table[idx], obj, func, data))
        if next_v < next_h:
            cell_y += y_inc
            t = next_v
            next_v += dt_dy
        else:
            cell_x += x_inc
            t = next_h
            next_h += dt_dx
    hash.stamp += 1


# -- misc ------------------------------------------------------------------------------------
cdef void cpSpaceHashResize(cpSpaceHash *hash, cpFloat celldim, int numcells) noexcept nogil:
    cdef int cells
    if hash.spatialIndex.klass != &klass:
        return
    cells = next_prime(numcells)
    if cells == 0:
        cpSetOutOfMemory()
        return
    clearTable(hash)
    hash.celldim = celldim
    cpSpaceHashAllocTable(hash, cells)


cdef int cpSpaceHashCount(cpSpatialIndex *index) noexcept nogil:
    return cpHashSetCount((<cpSpaceHash *>index).handleSet)


cdef cpBool cpSpaceHashContains(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil:
    return cpHashSetFind((<cpSpaceHash *>index).handleSet, hashid, obj) != NULL


klass.destroy = cpSpaceHashDestroy
klass.count = cpSpaceHashCount
klass.each = cpSpaceHashEach
klass.contains = cpSpaceHashContains
klass.insert = cpSpaceHashInsert
klass.remove = cpSpaceHashRemove
klass.reindex = cpSpaceHashRehash
klass.reindexObject = cpSpaceHashRehashObject
klass.reindexQuery = cpSpaceHashReindexQuery
klass.query = cpSpaceHashQuery
klass.segmentQuery = cpSpaceHashSegmentQuery
