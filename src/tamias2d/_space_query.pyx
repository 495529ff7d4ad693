"""Queries of the space: Munk2D's cpSpaceQuery.c (point, nearest point,
segment, first segment hit, bounding box and shape queries).

The C functions walk both spatial indexes in Munk2D's order and gather the
hits in C buffers (``_space_query.pxd``); ``Space`` in ``space.pyx`` turns
them into pymunk's query-info objects.
"""
from tamias2d._config cimport cpFloat, cpBool, cpCollisionID
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpShapeFilter, cpPointQueryInfo,
    cpSegmentQueryInfo, cpContactPointSet)
from tamias2d._containers cimport cprealloc
from tamias2d._spatialindex cimport cpSpatialIndexQuery, cpSpatialIndexSegmentQuery
from tamias2d.vector cimport cpVect, cpBB, cpv, cpfmax, cpBBIntersects, cpBBNewForCircle
from tamias2d.shape cimport (cpShapeUpdate, cpShapeFilterReject, cpShapePointQuery,
    cpShapeSegmentQuery)
from tamias2d.collision cimport cpShapesCollide
from tamias2d._space_step cimport cpSpaceLock, cpSpaceUnlock

# Munk2D reports each hit through a user callback. Here hits are gathered in
# a C buffer (in the same order) and turned into Python objects after the
# query, so no Python runs while the indexes are being walked.

cdef inline void _hitsPush(QueryHits *out, cpShape *shape, cpVect point, cpVect vect,
                           cpFloat value) noexcept nogil:
    cdef int cap
    cdef QueryHit *grown
    if out.count == out.capacity:
        cap = 8 if out.capacity == 0 else 2 * out.capacity
        grown = <QueryHit *>cprealloc(out.hits, cap * sizeof(QueryHit))
        if grown == NULL:
            out.failed = 1
            return
        out.hits = grown
        out.capacity = cap
    out.hits[out.count].shape = shape
    out.hits[out.count].point = point
    out.hits[out.count].vect = vect
    out.hits[out.count].value = value
    out.count += 1

cdef struct PointQueryContext:
    cpVect point
    cpFloat maxDistance
    cpShapeFilter filter

cdef cpCollisionID NearestPointQuery(void *ctx, void *obj, cpCollisionID id, void *data) noexcept nogil:
    cdef PointQueryContext *context = <PointQueryContext *>ctx
    cdef cpShape *shape = <cpShape *>obj
    cdef cpPointQueryInfo info
    if not cpShapeFilterReject(shape.filter, context.filter):
        cpShapePointQuery(shape, context.point, &info)
        if info.shape != NULL and info.distance < context.maxDistance:
            _hitsPush(<QueryHits *>data, shape, info.point, info.gradient, info.distance)
    return id

cdef void cpSpacePointQuery(cpSpace *space, cpVect point, cpFloat maxDistance, cpShapeFilter filter,
                            QueryHits *out) noexcept nogil:
    cdef PointQueryContext context
    context.point = point
    context.maxDistance = maxDistance
    context.filter = filter
    cdef cpBB bb = cpBBNewForCircle(point, cpfmax(maxDistance, 0.0))
    cpSpaceLock(space)
    cpSpatialIndexQuery(space.dynamicShapes, &context, bb, NearestPointQuery, out)
    cpSpatialIndexQuery(space.staticShapes, &context, bb, NearestPointQuery, out)
    cpSpaceUnlock(space, 1)

cdef cpCollisionID NearestPointQueryNearest(void *ctx, void *obj, cpCollisionID id,
                                            void *data) noexcept nogil:
    cdef PointQueryContext *context = <PointQueryContext *>ctx
    cdef cpShape *shape = <cpShape *>obj
    cdef cpPointQueryInfo *out = <cpPointQueryInfo *>data
    cdef cpPointQueryInfo info
    if not cpShapeFilterReject(shape.filter, context.filter):
        cpShapePointQuery(shape, context.point, &info)
        if info.distance < out.distance:
            out[0] = info
    return id

cdef cpShape *cpSpacePointQueryNearest(cpSpace *space, cpVect point, cpFloat maxDistance,
                                       cpShapeFilter filter, cpPointQueryInfo *out) noexcept nogil:
    out.shape = NULL
    out.point = cpv(0.0, 0.0)
    out.distance = maxDistance
    out.gradient = cpv(0.0, 0.0)
    cdef PointQueryContext context
    context.point = point
    context.maxDistance = maxDistance
    context.filter = filter
    cdef cpBB bb = cpBBNewForCircle(point, cpfmax(maxDistance, 0.0))
    cpSpatialIndexQuery(space.dynamicShapes, &context, bb, NearestPointQueryNearest, out)
    cpSpatialIndexQuery(space.staticShapes, &context, bb, NearestPointQueryNearest, out)
    return <cpShape *>out.shape

cdef struct SegmentQueryContext:
    cpVect start
    cpVect end
    cpFloat radius
    cpShapeFilter filter

cdef cpFloat SegmentQuery(void *ctx, void *obj, void *data) noexcept nogil:
    cdef SegmentQueryContext *context = <SegmentQueryContext *>ctx
    cdef cpShape *shape = <cpShape *>obj
    cdef cpSegmentQueryInfo info
    if (not cpShapeFilterReject(shape.filter, context.filter)
            and cpShapeSegmentQuery(shape, context.start, context.end, context.radius, &info)):
        _hitsPush(<QueryHits *>data, shape, info.point, info.normal, info.alpha)
    return 1.0

cdef void cpSpaceSegmentQuery(cpSpace *space, cpVect start, cpVect end, cpFloat radius,
                              cpShapeFilter filter, QueryHits *out) noexcept nogil:
    cdef SegmentQueryContext context
    context.start = start
    context.end = end
    context.radius = radius
    context.filter = filter
    cpSpaceLock(space)
    cpSpatialIndexSegmentQuery(space.staticShapes, &context, start, end, 1.0, SegmentQuery, out)
    cpSpatialIndexSegmentQuery(space.dynamicShapes, &context, start, end, 1.0, SegmentQuery, out)
    cpSpaceUnlock(space, 1)

cdef cpFloat SegmentQueryFirst(void *ctx, void *obj, void *data) noexcept nogil:
    cdef SegmentQueryContext *context = <SegmentQueryContext *>ctx
    cdef cpShape *shape = <cpShape *>obj
    cdef cpSegmentQueryInfo *out = <cpSegmentQueryInfo *>data
    cdef cpSegmentQueryInfo info
    if (not cpShapeFilterReject(shape.filter, context.filter)
            and cpShapeSegmentQuery(shape, context.start, context.end, context.radius, &info)
            and info.alpha < out.alpha):
        out[0] = info
    return out.alpha

cdef cpShape *cpSpaceSegmentQueryFirst(cpSpace *space, cpVect start, cpVect end, cpFloat radius,
                                       cpShapeFilter filter, cpSegmentQueryInfo *out) noexcept nogil:
    out.shape = NULL
    out.point = end
    out.normal = cpv(0.0, 0.0)
    out.alpha = 1.0
    cdef SegmentQueryContext context
    context.start = start
    context.end = end
    context.radius = radius
    context.filter = filter
    cpSpatialIndexSegmentQuery(space.staticShapes, &context, start, end, 1.0, SegmentQueryFirst, out)
    # The static hit bounds the search of the dynamic tree.
    cpSpatialIndexSegmentQuery(space.dynamicShapes, &context, start, end, out.alpha,
                               SegmentQueryFirst, out)
    return <cpShape *>out.shape

cdef struct BBQueryContext:
    cpBB bb
    cpShapeFilter filter

cdef cpCollisionID BBQuery(void *ctx, void *obj, cpCollisionID id, void *data) noexcept nogil:
    cdef BBQueryContext *context = <BBQueryContext *>ctx
    cdef cpShape *shape = <cpShape *>obj
    if (not cpShapeFilterReject(shape.filter, context.filter)
            and cpBBIntersects(context.bb, shape.bb)):
        _hitsPush(<QueryHits *>data, shape, cpv(0.0, 0.0), cpv(0.0, 0.0), 0.0)
    return id

cdef void cpSpaceBBQuery(cpSpace *space, cpBB bb, cpShapeFilter filter, QueryHits *out) noexcept nogil:
    cdef BBQueryContext context
    context.bb = bb
    context.filter = filter
    cpSpaceLock(space)
    cpSpatialIndexQuery(space.dynamicShapes, &context, bb, BBQuery, out)
    cpSpatialIndexQuery(space.staticShapes, &context, bb, BBQuery, out)
    cpSpaceUnlock(space, 1)

cdef cpCollisionID ShapeQuery(void *obj_a, void *obj_b, cpCollisionID id, void *data) noexcept nogil:
    cdef cpShape *a = <cpShape *>obj_a
    cdef cpShape *b = <cpShape *>obj_b
    cdef ShapeQueryHits *out = <ShapeQueryHits *>data
    cdef cpContactPointSet set
    cdef int cap
    cdef cpShape **shapes
    cdef cpContactPointSet *sets
    if cpShapeFilterReject(a.filter, b.filter) or a == b:
        return id
    set = cpShapesCollide(a, b)
    if set.count:
        if out.count == out.capacity:
            cap = 8 if out.capacity == 0 else 2 * out.capacity
            shapes = <cpShape **>cprealloc(out.shapes, cap * sizeof(cpShape *))
            if shapes != NULL:
                out.shapes = shapes
                sets = <cpContactPointSet *>cprealloc(out.sets, cap * sizeof(cpContactPointSet))
                if sets != NULL:
                    out.sets = sets
                    out.capacity = cap
        if out.count < out.capacity:
            out.shapes[out.count] = b
            out.sets[out.count] = set
            out.count += 1
        else:
            out.failed = 1
        out.anyCollision |= not (a.sensor or b.sensor)
    return id

cdef cpBool cpSpaceShapeQuery(cpSpace *space, cpShape *shape, ShapeQueryHits *out) noexcept nogil:
    cdef cpBody *body = shape.body
    # The query shape's cached data is refreshed from its body, as Munk2D does.
    cdef cpBB bb = cpShapeUpdate(shape, body.transform) if body != NULL else shape.bb
    cpSpaceLock(space)
    cpSpatialIndexQuery(space.dynamicShapes, shape, bb, ShapeQuery, out)
    cpSpatialIndexQuery(space.staticShapes, shape, bb, ShapeQuery, out)
    cpSpaceUnlock(space, 1)
    return out.anyCollision


