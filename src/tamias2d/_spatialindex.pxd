# The spatial index interface of Munk2D (cpSpatialIndex.h/.c): what the space
# calls for its broad phase, whatever index sits behind it. An index is a
# struct that starts with a cpSpatialIndex (klass table, box callback, the
# static/dynamic partner links); the dispatchers below call through the klass
# table. Two implementations plug in beneath this module: the bounding box
# tree (_bbtree, the default) and the spatial hash (_spacehash); neither
# cimports the other.
#
# The structs and callback types themselves are in _structs.pxd (the space
# struct points at its two indexes). The dispatchers are inline here, as they
# are in cpSpatialIndex.h, so a call costs one indirect call through the table.
from tamias2d._config cimport cpFloat, cpHashValue, cpBool
from tamias2d.vector cimport cpVect, cpBB
from tamias2d._structs cimport (cpSpatialIndex, cpSpatialIndexClass, cpSpatialIndexBBFunc,
    cpSpatialIndexIteratorFunc, cpSpatialIndexQueryFunc, cpSpatialIndexSegmentQueryFunc)

# -- cpSpatialIndex.c -----------------------------------------------------------------
# Destroy through the class table, then free the struct. NULL is a no-op.
cdef void cpSpatialIndexFree(cpSpatialIndex *index) noexcept nogil
# Fill the base struct and link a dynamic index to its static one. NULL (and
# nothing linked) when the static index already has a dynamic partner.
cdef cpSpatialIndex *cpSpatialIndexInit(cpSpatialIndex *index, cpSpatialIndexClass *klass,
                                        cpSpatialIndexBBFunc bbfunc,
                                        cpSpatialIndex *staticIndex) noexcept nogil
# Every object of the dynamic index queries the static index with its box
# (the pairing used when the static index is not a tree).
cdef void cpSpatialIndexCollideStatic(cpSpatialIndex *dynamicIndex, cpSpatialIndex *staticIndex,
                                      cpSpatialIndexQueryFunc func, void *data) noexcept nogil

# -- cpSpatialIndex.h dispatchers --------------------------------------------------------
cdef inline void cpSpatialIndexDestroy(cpSpatialIndex *index) noexcept nogil:
    if index.klass != NULL:
        index.klass.destroy(index)

cdef inline int cpSpatialIndexCount(cpSpatialIndex *index) noexcept nogil:
    return index.klass.count(index)

cdef inline void cpSpatialIndexEach(cpSpatialIndex *index, cpSpatialIndexIteratorFunc func,
                                    void *data) noexcept nogil:
    index.klass.each(index, func, data)

cdef inline cpBool cpSpatialIndexContains(cpSpatialIndex *index, void *obj,
                                          cpHashValue hashid) noexcept nogil:
    return index.klass.contains(index, obj, hashid)

cdef inline void cpSpatialIndexInsert(cpSpatialIndex *index, void *obj,
                                      cpHashValue hashid) noexcept nogil:
    index.klass.insert(index, obj, hashid)

cdef inline void cpSpatialIndexRemove(cpSpatialIndex *index, void *obj,
                                      cpHashValue hashid) noexcept nogil:
    index.klass.remove(index, obj, hashid)

cdef inline void cpSpatialIndexReindex(cpSpatialIndex *index) noexcept nogil:
    index.klass.reindex(index)

cdef inline void cpSpatialIndexReindexObject(cpSpatialIndex *index, void *obj,
                                             cpHashValue hashid) noexcept nogil:
    index.klass.reindexObject(index, obj, hashid)

cdef inline void cpSpatialIndexQuery(cpSpatialIndex *index, void *obj, cpBB bb,
                                     cpSpatialIndexQueryFunc func, void *data) noexcept nogil:
    index.klass.query(index, obj, bb, func, data)

cdef inline void cpSpatialIndexSegmentQuery(cpSpatialIndex *index, void *obj, cpVect a, cpVect b,
                                            cpFloat t_exit, cpSpatialIndexSegmentQueryFunc func,
                                            void *data) noexcept nogil:
    index.klass.segmentQuery(index, obj, a, b, t_exit, func, data)

cdef inline void cpSpatialIndexReindexQuery(cpSpatialIndex *index, cpSpatialIndexQueryFunc func,
                                            void *data) noexcept nogil:
    index.klass.reindexQuery(index, func, data)
