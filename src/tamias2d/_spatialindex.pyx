"""The spatial index interface of Munk2D (cpSpatialIndex.c).

The few functions of the interface that are not inline dispatchers (those are
in ``_spatialindex.pxd``): freeing an index, initialising the base struct of
an implementation, and colliding a dynamic index with a static one that is
not a tree. The implementations are ``_bbtree`` (the default) and
``_spacehash``; the space reaches either only through this interface.
"""
from libc.stdlib cimport free


cdef void cpSpatialIndexFree(cpSpatialIndex *index) noexcept nogil:
    if index != NULL:
        cpSpatialIndexDestroy(index)
        free(index)


cdef cpSpatialIndex *cpSpatialIndexInit(cpSpatialIndex *index, cpSpatialIndexClass *klass,
                                        cpSpatialIndexBBFunc bbfunc,
                                        cpSpatialIndex *staticIndex) noexcept nogil:
    # Munk2D hard-asserts that a static index has one dynamic partner at most;
    # here the misuse returns NULL and links nothing.
    if staticIndex != NULL and staticIndex.dynamicIndex != NULL:
        return NULL
    index.klass = klass
    index.bbfunc = bbfunc
    index.staticIndex = staticIndex
    if staticIndex != NULL:
        staticIndex.dynamicIndex = index
    return index


cdef struct DynamicToStaticContext:
    cpSpatialIndexBBFunc bbfunc
    cpSpatialIndex *staticIndex
    cpSpatialIndexQueryFunc queryFunc
    void *data


cdef void dynamicToStaticIter(void *obj, void *data) noexcept nogil:
    cdef DynamicToStaticContext *context = <DynamicToStaticContext *>data
    cpSpatialIndexQuery(context.staticIndex, obj, context.bbfunc(obj), context.queryFunc,
                        context.data)


cdef void cpSpatialIndexCollideStatic(cpSpatialIndex *dynamicIndex, cpSpatialIndex *staticIndex,
                                      cpSpatialIndexQueryFunc func, void *data) noexcept nogil:
    # Used when the static index is not a tree (the spatial hash): every
    # dynamic object queries the static index with its own box.
    cdef DynamicToStaticContext context
    if staticIndex != NULL and cpSpatialIndexCount(staticIndex) > 0:
        context.bbfunc = dynamicIndex.bbfunc
        context.staticIndex = staticIndex
        context.queryFunc = func
        context.data = data
        cpSpatialIndexEach(dynamicIndex, dynamicToStaticIter, &context)
