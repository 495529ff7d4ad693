"""Collision shapes: circles, segments and convex polygons.

The C half ports Munk2D's cpShape.c, cpPolyShape.c and the geometry helpers of
chipmunk.c (moments, areas, centroid, QuickHull) with the same arithmetic, so
every number matches pymunk 7.3. The Python half is pymunk's shape API. The
test hooks for C functions that API does not reach (cpConvexHull,
cpMomentForBox2, cpShapeFilterReject, the cp*ShapeNew constructors) are in
``_testing``.

>>> import tamias2d
>>> c = tamias2d.Circle(None, 2.0)
>>> c.area
12.566370614359172
"""
import weakref as _weakref
from typing import NamedTuple

from libc.math cimport sqrt, INFINITY, M_PI, isfinite, isnan
from libc.stdlib cimport malloc, calloc, free
from libc.string cimport memcpy, memset
from libc.limits cimport INT_MAX

from tamias2d._threadguard cimport tamias_wait_shape
from tamias2d._config cimport (cpFloat, cpBool, cpHashValue, cpCollisionType, cpGroup,
    cpBitmask, CP_POLY_SHAPE_INLINE_ALLOC, CP_ALL_CATEGORIES, CP_NO_GROUP, MAGIC_EPSILON)
from tamias2d._structs cimport (cpBody, cpShape, cpShapeClass, cpCircleShape,
    cpSegmentShape, cpPolyShape, cpSplittingPlane, cpShapeMassInfo, cpShapeFilter,
    cpPointQueryInfo, cpSegmentQueryInfo, cpShapeType, CP_CIRCLE_SHAPE,
    CP_SEGMENT_SHAPE, CP_POLY_SHAPE, cpShapeCacheDataImpl, cpShapeDestroyImpl,
    cpShapePointQueryImpl, cpShapeSegmentQueryImpl)
from tamias2d.vector cimport (cpVect, cpBB, cpTransform, cpv, cpvadd, cpvsub, cpvneg,
    cpvmult, cpvdot, cpvcross, cpvperp, cpvrperp, cpvlength, cpvlengthsq, cpvlerp,
    cpvnormalize, cpvdist, cpvdistsq, cpfmin, cpfmax, cpfabs, cpClosetPointOnSegment,
    cpBBNew, cpBBNewForCircle, cpTransformPoint, cpTransformVect, cpTransformIdentity,
    vec2d_from_cpv, cpv_from_object, cpv_from_object_finite, bb_from_cpbb,
    cpbb_from_object, cptransform_from_object)
from tamias2d.body cimport Body, cpBodyActivate, cpBodyAccumulateMassFromShapes
from tamias2d._pickle cimport (snapshot_module as _snapshot, pymunk_getstate, pymunk_setstate,
    pymunk_reduce, deep_copy)

from tamias2d.errors import IllegalShape, IllegalBody, IndexOutOfBounds, AlreadyInSpace

__all__ = [
    "Shape", "Circle", "Segment", "Poly", "ShapeFilter", "PointQueryInfo",
    "SegmentQueryInfo", "ShapeQueryInfo", "moment_for_circle", "moment_for_segment",
    "moment_for_box", "moment_for_poly", "area_for_circle", "area_for_segment",
    "area_for_poly", "centroid_for_poly",
]


# =============================================================================
# C level
# =============================================================================

# -- chipmunk.c: moments, areas, centroid -------------------------------------
cdef cpFloat cpMomentForCircle(cpFloat m, cpFloat r1, cpFloat r2, cpVect offset) noexcept nogil:
    return m * (0.5 * (r1 * r1 + r2 * r2) + cpvlengthsq(offset))

cdef cpFloat cpAreaForCircle(cpFloat r1, cpFloat r2) noexcept nogil:
    return M_PI * cpfabs(r1 * r1 - r2 * r2)

cdef cpFloat cpMomentForSegment(cpFloat m, cpVect a, cpVect b, cpFloat r) noexcept nogil:
    cdef cpVect offset = cpvlerp(a, b, 0.5)
    # A rounded segment is treated as a box of length |b - a| + 2r (Munk2D's
    # approximation).
    cdef cpFloat length = cpvdist(b, a) + 2.0 * r
    return m * ((length * length + 4.0 * r * r) / 12.0 + cpvlengthsq(offset))

cdef cpFloat cpAreaForSegment(cpVect a, cpVect b, cpFloat r) noexcept nogil:
    return r * (M_PI * r + 2.0 * cpvdist(a, b))

cdef cpFloat cpMomentForPoly(cpFloat m, int count, const cpVect *verts, cpVect offset,
                             cpFloat r) noexcept nogil:
    # The radius is ignored, as in Munk2D.
    if count == 2:
        return cpMomentForSegment(m, verts[0], verts[1], 0.0)
    cdef cpFloat sum1 = 0.0
    cdef cpFloat sum2 = 0.0
    cdef cpFloat a, b
    cdef cpVect v1, v2
    cdef int i
    for i in range(count):
        v1 = cpvadd(verts[i], offset)
        v2 = cpvadd(verts[(i + 1) % count], offset)
        a = cpvcross(v2, v1)
        b = cpvdot(v1, v1) + cpvdot(v1, v2) + cpvdot(v2, v2)
        sum1 += a * b
        sum2 += a
    return (m * sum1) / (6.0 * sum2)

cdef cpFloat cpAreaForPoly(int count, const cpVect *verts, cpFloat r) noexcept nogil:
    cdef cpFloat area = 0.0
    cdef cpFloat perimeter = 0.0
    cdef cpVect v1, v2
    cdef int i
    for i in range(count):
        v1 = verts[i]
        v2 = verts[(i + 1) % count]
        area += cpvcross(v1, v2)
        perimeter += cpvdist(v1, v2)
    return r * (M_PI * cpfabs(r) + perimeter) + area / 2.0

cdef cpVect cpCentroidForPoly(int count, const cpVect *verts) noexcept nogil:
    cdef cpFloat sum = 0.0
    cdef cpVect vsum = cpv(0.0, 0.0)
    cdef cpVect v1, v2
    cdef cpFloat cross
    cdef int i
    for i in range(count):
        v1 = verts[i]
        v2 = verts[(i + 1) % count]
        cross = cpvcross(v1, v2)
        sum += cross
        vsum = cpvadd(vsum, cpvmult(cpvadd(v1, v2), cross))
    return cpvmult(vsum, 1.0 / (3.0 * sum))

cdef cpFloat cpMomentForBox(cpFloat m, cpFloat width, cpFloat height) noexcept nogil:
    return m * (width * width + height * height) / 12.0

cdef cpFloat cpMomentForBox2(cpFloat m, cpBB box) noexcept nogil:
    cdef cpFloat width = box.r - box.l
    cdef cpFloat height = box.t - box.b
    cdef cpVect offset = cpvmult(cpv(box.l + box.r, box.b + box.t), 0.5)
    return cpMomentForBox(m, width, height) + m * cpvlengthsq(offset)

# -- chipmunk.c: QuickHull -------------------------------------------------------
cdef void cpLoopIndexes(const cpVect *verts, int count, int *start, int *end) noexcept nogil:
    # Index of the lowest (x, then y) vertex in start, of the highest in end.
    # The max test only runs when the min test failed, as in Munk2D.
    start[0] = 0
    end[0] = 0
    cdef cpVect vmin = verts[0]
    cdef cpVect vmax = vmin
    cdef cpVect v
    cdef int i
    for i in range(1, count):
        v = verts[i]
        if v.x < vmin.x or (v.x == vmin.x and v.y < vmin.y):
            vmin = v
            start[0] = i
        elif v.x > vmax.x or (v.x == vmax.x and v.y > vmax.y):
            vmax = v
            end[0] = i

cdef inline void _swap(cpVect *a, cpVect *b) noexcept nogil:
    cdef cpVect tmp = a[0]
    a[0] = b[0]
    b[0] = tmp

cdef int QHullPartition(cpVect *verts, int count, cpVect a, cpVect b, cpFloat tol) noexcept nogil:
    # Moves the points strictly left of a->b to the front (their count is
    # returned) with the farthest one first; the rest go to the back.
    if count == 0:
        return 0
    cdef cpFloat vmax = 0
    cdef int pivot = 0
    cdef cpVect delta = cpvsub(b, a)
    cdef cpFloat valueTol = tol * cpvlength(delta)
    cdef int head = 0
    cdef int tail = count - 1
    cdef cpFloat value
    while head <= tail:
        value = cpvcross(cpvsub(verts[head], a), delta)
        if value > valueTol:
            if value > vmax:
                vmax = value
                pivot = head
            head += 1
        else:
            _swap(&verts[head], &verts[tail])
            tail -= 1
    if pivot != 0:
        _swap(&verts[0], &verts[pivot])
    return head

cdef int QHullReduce(cpFloat tol, cpVect *verts, int count, cpVect a, cpVect pivot, cpVect b,
                     cpVect *result) noexcept nogil:
    # Writes the hull points strictly between a and b (pivot included) to
    # result, in order, and returns how many.
    cdef int left_count, index, right_count
    if count < 0:
        return 0
    elif count == 0:
        result[0] = pivot
        return 1
    left_count = QHullPartition(verts, count, a, pivot, tol)
    index = QHullReduce(tol, verts + 1, left_count - 1, a, verts[0], pivot, result)
    result[index] = pivot
    index += 1
    right_count = QHullPartition(verts + left_count, count - left_count, pivot, b, tol)
    return index + QHullReduce(tol, verts + left_count + 1, right_count - 1, pivot,
                               verts[left_count], b, result + index)

cdef int cpConvexHull(int count, const cpVect *verts, cpVect *result, int *first,
                      cpFloat tol) noexcept nogil:
    # QuickHull in place in result (count >= 1). The hull is counter-clockwise
    # and starts at the lowest-x (then lowest-y) point; all points equal
    # gives a hull of 1.
    cdef int start, end
    if verts != result:
        memcpy(result, verts, count * sizeof(cpVect))
    cpLoopIndexes(verts, count, &start, &end)
    if start == end:
        if first != NULL:
            first[0] = 0
        return 1
    _swap(&result[0], &result[start])
    _swap(&result[1], &result[start if end == 0 else end])
    cdef cpVect a = result[0]
    cdef cpVect b = result[1]
    if first != NULL:
        first[0] = start
    return QHullReduce(tol, result + 2, count - 2, a, b, a, result + 1) + 1

# -- chipmunk_private.h: swept circle against a circle ------------------------------
cdef void CircleSegmentQuery(const cpShape *shape, cpVect center, cpFloat r1, cpVect a, cpVect b,
                             cpFloat r2, cpSegmentQueryInfo *info) noexcept nogil:
    # Solves |lerp(a, b, t) - center| = r1 + r2 for the first root in [0, 1].
    cdef cpVect da = cpvsub(a, center)
    cdef cpVect db = cpvsub(b, center)
    cdef cpFloat rsum = r1 + r2
    cdef cpFloat qa = cpvdot(da, da) - 2.0 * cpvdot(da, db) + cpvdot(db, db)
    cdef cpFloat qb = cpvdot(da, db) - cpvdot(da, da)
    cdef cpFloat det = qb * qb - qa * (cpvdot(da, da) - rsum * rsum)
    cdef cpFloat t
    cdef cpVect n
    if det >= 0.0:
        t = (-qb - sqrt(det)) / qa
        if 0.0 <= t and t <= 1.0:
            n = cpvnormalize(cpvlerp(da, db, t))
            info.shape = shape
            info.point = cpvsub(cpvlerp(a, b, t), cpvmult(n, r2))
            info.normal = n
            info.alpha = t

# -- cpShape.c: the generic shape ---------------------------------------------------
cdef cpShape *cpShapeInit(cpShape *shape, const cpShapeClass *klass, cpBody *body,
                          cpShapeMassInfo massInfo) noexcept nogil:
    # bb and hashid are left alone: zero on a fresh (zeroed) shape.
    shape.klass = klass
    shape.body = body
    shape.massInfo = massInfo
    shape.sensor = 0
    shape.softSlot = 0
    shape.e = 0.0
    shape.u = 0.0
    shape.surfaceV = cpv(0.0, 0.0)
    shape.type = 0
    shape.filter.group = CP_NO_GROUP
    shape.filter.categories = CP_ALL_CATEGORIES
    shape.filter.mask = CP_ALL_CATEGORIES
    shape.userData = NULL
    shape.space = NULL
    shape.next = NULL
    shape.prev = NULL
    return shape

cdef void cpShapeDestroy(cpShape *shape) noexcept nogil:
    if shape.klass != NULL and shape.klass.destroy != NULL:
        shape.klass.destroy(shape)

cdef void cpShapeFree(cpShape *shape) noexcept nogil:
    # For shapes made by the cp*ShapeNew functions only (the Python shapes
    # embed their struct).
    if shape != NULL:
        cpShapeDestroy(shape)
        free(shape)

cdef void cpShapeSetBody(cpShape *shape, cpBody *body) noexcept nogil:
    # The caller checks the shape is not active (Munk2D's hard assert).
    shape.body = body

cdef void cpShapeSetMass(cpShape *shape, cpFloat mass) noexcept nogil:
    cdef cpBody *body = shape.body
    if body != NULL:
        cpBodyActivate(body)
    shape.massInfo.m = mass
    if body != NULL:
        cpBodyAccumulateMassFromShapes(body)

cdef cpFloat cpShapeGetDensity(const cpShape *shape) noexcept nogil:
    return shape.massInfo.m / shape.massInfo.area

cdef void cpShapeSetDensity(cpShape *shape, cpFloat density) noexcept nogil:
    cpShapeSetMass(shape, density * shape.massInfo.area)

cdef cpFloat cpShapeGetMoment(const cpShape *shape) noexcept nogil:
    return shape.massInfo.m * shape.massInfo.i

# The setters below wake the body, as Munk2D's do.
cdef inline void _activate(cpShape *shape) noexcept nogil:
    if shape.body != NULL:
        cpBodyActivate(shape.body)

cdef void cpShapeSetSensor(cpShape *shape, cpBool sensor) noexcept nogil:
    _activate(shape)
    shape.sensor = sensor

cdef void cpShapeSetElasticity(cpShape *shape, cpFloat elasticity) noexcept nogil:
    _activate(shape)
    shape.e = elasticity

cdef void cpShapeSetFriction(cpShape *shape, cpFloat friction) noexcept nogil:
    _activate(shape)
    shape.u = friction

cdef void cpShapeSetSurfaceVelocity(cpShape *shape, cpVect surfaceVelocity) noexcept nogil:
    _activate(shape)
    shape.surfaceV = surfaceVelocity

cdef void cpShapeSetCollisionType(cpShape *shape, cpCollisionType collisionType) noexcept nogil:
    _activate(shape)
    shape.type = collisionType

cdef void cpShapeSetFilter(cpShape *shape, cpShapeFilter filter) noexcept nogil:
    _activate(shape)
    shape.filter = filter

cdef cpBB cpShapeCacheBB(cpShape *shape) noexcept nogil:
    return cpShapeUpdate(shape, shape.body.transform)

cdef cpBB cpShapeUpdate(cpShape *shape, cpTransform transform) noexcept nogil:
    shape.bb = shape.klass.cacheData(shape, transform)
    return shape.bb

cdef cpFloat cpShapePointQuery(const cpShape *shape, cpVect p, cpPointQueryInfo *info) noexcept nogil:
    cdef cpPointQueryInfo blank
    blank.shape = NULL
    blank.point = cpv(0.0, 0.0)
    blank.distance = INFINITY
    blank.gradient = cpv(0.0, 0.0)
    if info != NULL:
        info[0] = blank
    else:
        info = &blank
    shape.klass.pointQuery(shape, p, info)
    return info.distance

cdef cpBool cpShapeSegmentQuery(const cpShape *shape, cpVect a, cpVect b, cpFloat radius,
                                cpSegmentQueryInfo *info) noexcept nogil:
    cdef cpSegmentQueryInfo blank
    blank.shape = NULL
    blank.point = b
    blank.normal = cpv(0.0, 0.0)
    blank.alpha = 1.0
    if info != NULL:
        info[0] = blank
    else:
        info = &blank
    cdef cpPointQueryInfo nearest
    shape.klass.pointQuery(shape, a, &nearest)
    if nearest.distance <= radius:
        # The query starts inside: a hit at alpha 0. The point stays b, as in
        # Munk2D.
        info.shape = shape
        info.alpha = 0.0
        info.normal = cpvnormalize(cpvsub(a, nearest.point))
    else:
        shape.klass.segmentQuery(shape, a, b, radius, info)
    return info.shape != NULL

# -- cpShape.c: circles -----------------------------------------------------------------
cdef cpBB cpCircleShapeCacheData(cpShape *shape, cpTransform transform) noexcept nogil:
    cdef cpCircleShape *circle = <cpCircleShape *>shape
    circle.tc = cpTransformPoint(transform, circle.c)
    return cpBBNewForCircle(circle.tc, circle.r)

cdef void cpCircleShapePointQuery(const cpShape *shape, cpVect p, cpPointQueryInfo *info) noexcept nogil:
    cdef const cpCircleShape *circle = <const cpCircleShape *>shape
    cdef cpVect delta = cpvsub(p, circle.tc)
    cdef cpFloat d = cpvlength(delta)
    cdef cpFloat r = circle.r
    info.shape = shape
    cdef cpFloat r_over_d = r / d if d > 0.0 else r
    info.point = cpvadd(circle.tc, cpvmult(delta, r_over_d))
    info.distance = d - r
    # Straight up when the point is (nearly) at the centre.
    info.gradient = cpvmult(delta, 1.0 / d) if d > MAGIC_EPSILON else cpv(0.0, 1.0)

cdef void cpCircleShapeSegmentQuery(const cpShape *shape, cpVect a, cpVect b, cpFloat radius,
                                    cpSegmentQueryInfo *info) noexcept nogil:
    cdef const cpCircleShape *circle = <const cpCircleShape *>shape
    CircleSegmentQuery(shape, circle.tc, circle.r, a, b, radius, info)

cdef cpShapeMassInfo cpCircleShapeMassInfo(cpFloat mass, cpFloat radius, cpVect center) noexcept nogil:
    cdef cpShapeMassInfo info
    info.m = mass
    info.i = cpMomentForCircle(1.0, 0.0, radius, cpv(0.0, 0.0))
    info.cog = center
    info.area = cpAreaForCircle(0.0, radius)
    return info

cdef cpShapeClass cpCircleShapeClass
cpCircleShapeClass.type = CP_CIRCLE_SHAPE
cpCircleShapeClass.cacheData = cpCircleShapeCacheData
cpCircleShapeClass.destroy = NULL
cpCircleShapeClass.pointQuery = cpCircleShapePointQuery
cpCircleShapeClass.segmentQuery = cpCircleShapeSegmentQuery

cdef cpCircleShape *cpCircleShapeInit(cpCircleShape *circle, cpBody *body, cpFloat radius,
                                      cpVect offset) noexcept nogil:
    circle.c = offset
    circle.r = radius
    cpShapeInit(&circle.shape, &cpCircleShapeClass, body, cpCircleShapeMassInfo(0.0, radius, offset))
    return circle

cdef cpShape *cpCircleShapeNew(cpBody *body, cpFloat radius, cpVect offset) noexcept nogil:
    cdef cpCircleShape *circle = <cpCircleShape *>calloc(1, sizeof(cpCircleShape))
    if circle == NULL:
        return NULL
    return &cpCircleShapeInit(circle, body, radius, offset).shape

# The getters and unsafe setters of the three kinds expect a shape of their
# kind (Munk2D hard-asserts it); the Python classes guarantee it by type.
cdef cpVect cpCircleShapeGetOffset(const cpShape *shape) noexcept nogil:
    return (<const cpCircleShape *>shape).c

cdef cpFloat cpCircleShapeGetRadius(const cpShape *shape) noexcept nogil:
    return (<const cpCircleShape *>shape).r

cdef void cpCircleShapeSetRadius(cpShape *shape, cpFloat radius) noexcept nogil:
    cdef cpCircleShape *circle = <cpCircleShape *>shape
    circle.r = radius
    cdef cpFloat mass = shape.massInfo.m
    shape.massInfo = cpCircleShapeMassInfo(mass, circle.r, circle.c)
    if mass > 0.0:
        cpBodyAccumulateMassFromShapes(shape.body)

cdef void cpCircleShapeSetOffset(cpShape *shape, cpVect offset) noexcept nogil:
    cdef cpCircleShape *circle = <cpCircleShape *>shape
    circle.c = offset
    cdef cpFloat mass = shape.massInfo.m
    shape.massInfo = cpCircleShapeMassInfo(shape.massInfo.m, circle.r, circle.c)
    if mass > 0.0:
        cpBodyAccumulateMassFromShapes(shape.body)

# -- cpShape.c: segments -------------------------------------------------------------------
cdef cpBB cpSegmentShapeCacheData(cpShape *shape, cpTransform transform) noexcept nogil:
    cdef cpSegmentShape *seg = <cpSegmentShape *>shape
    seg.ta = cpTransformPoint(transform, seg.a)
    seg.tb = cpTransformPoint(transform, seg.b)
    seg.tn = cpTransformVect(transform, seg.n)
    cdef cpFloat l, r, b, t
    if seg.ta.x < seg.tb.x:
        l = seg.ta.x
        r = seg.tb.x
    else:
        l = seg.tb.x
        r = seg.ta.x
    if seg.ta.y < seg.tb.y:
        b = seg.ta.y
        t = seg.tb.y
    else:
        b = seg.tb.y
        t = seg.ta.y
    cdef cpFloat rad = seg.r
    return cpBBNew(l - rad, b - rad, r + rad, t + rad)

cdef void cpSegmentShapePointQuery(const cpShape *shape, cpVect p, cpPointQueryInfo *info) noexcept nogil:
    cdef const cpSegmentShape *seg = <const cpSegmentShape *>shape
    cdef cpVect closest = cpClosetPointOnSegment(p, seg.ta, seg.tb)
    cdef cpVect delta = cpvsub(p, closest)
    cdef cpFloat d = cpvlength(delta)
    cdef cpFloat r = seg.r
    cdef cpVect g = cpvmult(delta, 1.0 / d)
    info.shape = shape
    info.point = cpvadd(closest, cpvmult(g, r)) if d != 0.0 else closest
    info.distance = d - r
    # Munk2D falls back to the local (not the world) normal here.
    info.gradient = g if d > MAGIC_EPSILON else seg.n

cdef void cpSegmentShapeSegmentQuery(const cpShape *shape, cpVect a, cpVect b, cpFloat r2,
                                     cpSegmentQueryInfo *info) noexcept nogil:
    cdef const cpSegmentShape *seg = <const cpSegmentShape *>shape
    cdef cpVect n = seg.tn
    cdef cpFloat d = cpvdot(cpvsub(seg.ta, a), n)
    cdef cpFloat r = seg.r + r2
    cdef cpVect flipped_n = cpvneg(n) if d > 0.0 else n
    cdef cpVect seg_offset = cpvsub(cpvmult(flipped_n, r), a)
    # Endpoints relative to a, pushed out by the combined thickness.
    cdef cpVect seg_a = cpvadd(seg.ta, seg_offset)
    cdef cpVect seg_b = cpvadd(seg.tb, seg_offset)
    cdef cpVect delta = cpvsub(b, a)
    cdef cpFloat d_offset, ad, bd, t
    cdef cpSegmentQueryInfo info1, info2
    if cpvcross(delta, seg_a) * cpvcross(delta, seg_b) <= 0.0:
        d_offset = d + (-r if d > 0.0 else r)
        ad = -d_offset
        bd = cpvdot(delta, n) - d_offset
        if ad * bd < 0.0:
            t = ad / (ad - bd)
            info.shape = shape
            info.point = cpvsub(cpvlerp(a, b, t), cpvmult(flipped_n, r2))
            info.normal = flipped_n
            info.alpha = t
    elif r != 0.0:
        info1.shape = NULL
        info1.point = b
        info1.normal = cpv(0.0, 0.0)
        info1.alpha = 1.0
        info2 = info1
        CircleSegmentQuery(shape, seg.ta, seg.r, a, b, r2, &info1)
        CircleSegmentQuery(shape, seg.tb, seg.r, a, b, r2, &info2)
        if info1.alpha < info2.alpha:
            info[0] = info1
        else:
            info[0] = info2

cdef cpShapeMassInfo cpSegmentShapeMassInfo(cpFloat mass, cpVect a, cpVect b, cpFloat r) noexcept nogil:
    cdef cpShapeMassInfo info
    info.m = mass
    # Munk2D's box approximation of the capsule.
    info.i = cpMomentForBox(1.0, cpvdist(a, b) + 2.0 * r, 2.0 * r)
    info.cog = cpvlerp(a, b, 0.5)
    info.area = cpAreaForSegment(a, b, r)
    return info

cdef cpShapeClass cpSegmentShapeClass
cpSegmentShapeClass.type = CP_SEGMENT_SHAPE
cpSegmentShapeClass.cacheData = cpSegmentShapeCacheData
cpSegmentShapeClass.destroy = NULL
cpSegmentShapeClass.pointQuery = cpSegmentShapePointQuery
cpSegmentShapeClass.segmentQuery = cpSegmentShapeSegmentQuery

cdef cpSegmentShape *cpSegmentShapeInit(cpSegmentShape *seg, cpBody *body, cpVect a, cpVect b,
                                        cpFloat r) noexcept nogil:
    seg.a = a
    seg.b = b
    seg.n = cpvrperp(cpvnormalize(cpvsub(b, a)))
    seg.r = r
    seg.a_tangent = cpv(0.0, 0.0)
    seg.b_tangent = cpv(0.0, 0.0)
    cpShapeInit(&seg.shape, &cpSegmentShapeClass, body, cpSegmentShapeMassInfo(0.0, a, b, r))
    return seg

cdef cpShape *cpSegmentShapeNew(cpBody *body, cpVect a, cpVect b, cpFloat r) noexcept nogil:
    cdef cpSegmentShape *seg = <cpSegmentShape *>calloc(1, sizeof(cpSegmentShape))
    if seg == NULL:
        return NULL
    return &cpSegmentShapeInit(seg, body, a, b, r).shape

cdef cpVect cpSegmentShapeGetA(const cpShape *shape) noexcept nogil:
    return (<const cpSegmentShape *>shape).a

cdef cpVect cpSegmentShapeGetB(const cpShape *shape) noexcept nogil:
    return (<const cpSegmentShape *>shape).b

cdef cpVect cpSegmentShapeGetNormal(const cpShape *shape) noexcept nogil:
    return (<const cpSegmentShape *>shape).n

cdef cpFloat cpSegmentShapeGetRadius(const cpShape *shape) noexcept nogil:
    return (<const cpSegmentShape *>shape).r

cdef void cpSegmentShapeSetNeighbors(cpShape *shape, cpVect prev, cpVect next) noexcept nogil:
    cdef cpSegmentShape *seg = <cpSegmentShape *>shape
    seg.a_tangent = cpvsub(prev, seg.a)
    seg.b_tangent = cpvsub(next, seg.b)

cdef void cpSegmentShapeSetEndpoints(cpShape *shape, cpVect a, cpVect b) noexcept nogil:
    cdef cpSegmentShape *seg = <cpSegmentShape *>shape
    seg.a = a
    seg.b = b
    # perp here, rperp in Init: the normal flips sign, as in Munk2D.
    seg.n = cpvperp(cpvnormalize(cpvsub(b, a)))
    cdef cpFloat mass = shape.massInfo.m
    shape.massInfo = cpSegmentShapeMassInfo(shape.massInfo.m, seg.a, seg.b, seg.r)
    if mass > 0.0:
        cpBodyAccumulateMassFromShapes(shape.body)

cdef void cpSegmentShapeSetRadius(cpShape *shape, cpFloat radius) noexcept nogil:
    cdef cpSegmentShape *seg = <cpSegmentShape *>shape
    seg.r = radius
    cdef cpFloat mass = shape.massInfo.m
    shape.massInfo = cpSegmentShapeMassInfo(shape.massInfo.m, seg.a, seg.b, seg.r)
    if mass > 0.0:
        cpBodyAccumulateMassFromShapes(shape.body)

# -- cpPolyShape.c ---------------------------------------------------------------------------
cdef void cpPolyShapeDestroy(cpShape *shape) noexcept nogil:
    cdef cpPolyShape *poly = <cpPolyShape *>shape
    if poly.count > CP_POLY_SHAPE_INLINE_ALLOC:
        free(poly.planes)
    # Left pointing at the inline buffer so a second destroy is harmless.
    poly.planes = poly._planes
    poly.count = 0

cdef cpBB cpPolyShapeCacheData(cpShape *shape, cpTransform transform) noexcept nogil:
    cdef cpPolyShape *poly = <cpPolyShape *>shape
    cdef int count = poly.count
    cdef cpSplittingPlane *dst = poly.planes
    cdef cpSplittingPlane *src = dst + count
    cdef cpFloat l = INFINITY
    cdef cpFloat r = -INFINITY
    cdef cpFloat b = INFINITY
    cdef cpFloat t = -INFINITY
    cdef cpVect v, n
    cdef int i
    for i in range(count):
        v = cpTransformPoint(transform, src[i].v0)
        n = cpTransformVect(transform, src[i].n)
        dst[i].v0 = v
        dst[i].n = n
        l = cpfmin(l, v.x)
        r = cpfmax(r, v.x)
        b = cpfmin(b, v.y)
        t = cpfmax(t, v.y)
    cdef cpFloat radius = poly.r
    poly.shape.bb = cpBBNew(l - radius, b - radius, r + radius, t + radius)
    return poly.shape.bb

cdef void cpPolyShapePointQuery(const cpShape *shape, cpVect p, cpPointQueryInfo *info) noexcept nogil:
    cdef const cpPolyShape *poly = <const cpPolyShape *>shape
    cdef int count = poly.count
    cdef const cpSplittingPlane *planes = poly.planes
    cdef cpFloat r = poly.r
    cdef cpVect v0 = planes[count - 1].v0
    cdef cpFloat minDist = INFINITY
    cdef cpVect closestPoint = cpv(0.0, 0.0)
    cdef cpVect closestNormal = cpv(0.0, 0.0)
    cdef cpBool outside = 0
    cdef cpVect v1, closest
    cdef cpFloat dist
    cdef int i
    for i in range(count):
        v1 = planes[i].v0
        outside = outside or (cpvdot(planes[i].n, cpvsub(p, v1)) > 0.0)
        closest = cpClosetPointOnSegment(p, v0, v1)
        dist = cpvdist(p, closest)
        if dist < minDist:
            minDist = dist
            closestPoint = closest
            closestNormal = planes[i].n
        v0 = v1
    dist = minDist if outside else -minDist
    cdef cpVect g = cpvmult(cpvsub(p, closestPoint), 1.0 / dist)
    info.shape = shape
    info.point = cpvadd(closestPoint, cpvmult(g, r))
    info.distance = dist - r
    # The closest edge's normal when the point is (nearly) on the surface.
    info.gradient = g if minDist > MAGIC_EPSILON else closestNormal

cdef void cpPolyShapeSegmentQuery(const cpShape *shape, cpVect a, cpVect b, cpFloat r2,
                                  cpSegmentQueryInfo *info) noexcept nogil:
    cdef const cpPolyShape *poly = <const cpPolyShape *>shape
    cdef const cpSplittingPlane *planes = poly.planes
    cdef int count = poly.count
    cdef cpFloat r = poly.r
    cdef cpFloat rsum = r + r2
    cdef cpVect n, point
    cdef cpFloat an, bn, d, t, dt, dtMin, dtMax
    cdef cpSegmentQueryInfo circle_info
    cdef int i
    for i in range(count):
        n = planes[i].n
        an = cpvdot(a, n)
        d = an - cpvdot(planes[i].v0, n) - rsum
        if d < 0.0:
            continue
        bn = cpvdot(b, n)
        # Munk2D skips a face whose divisor is nearly zero (10e-6 in its
        # source, the same double as 1e-5).
        if an - bn < 1e-5 and an - bn > -1e-5:
            continue
        t = d / (an - bn)
        if t < 0.0 or 1.0 < t:
            continue
        point = cpvlerp(a, b, t)
        dt = cpvcross(n, point)
        dtMin = cpvcross(n, planes[(i - 1 + count) % count].v0)
        dtMax = cpvcross(n, planes[i].v0)
        if dtMin <= dt and dt <= dtMax:
            info.shape = shape
            info.point = cpvsub(cpvlerp(a, b, t), cpvmult(n, r2))
            info.normal = n
            info.alpha = t
    # The rounded corners.
    if rsum > 0.0:
        for i in range(count):
            circle_info.shape = NULL
            circle_info.point = b
            circle_info.normal = cpv(0.0, 0.0)
            circle_info.alpha = 1.0
            CircleSegmentQuery(shape, planes[i].v0, r, a, b, r2, &circle_info)
            if circle_info.alpha < info.alpha:
                info[0] = circle_info

cdef cpBool SetVerts(cpPolyShape *poly, int count, const cpVect *verts) noexcept nogil:
    # Local planes go to planes[count:2*count]; cacheData fills [0:count].
    # Returns 0 when the heap block could not be allocated.
    if count <= CP_POLY_SHAPE_INLINE_ALLOC:
        poly.planes = poly._planes
    else:
        poly.planes = <cpSplittingPlane *>calloc(2 * count, sizeof(cpSplittingPlane))
        if poly.planes == NULL:
            poly.planes = poly._planes
            poly.count = 0
            return 0
    poly.count = count
    cdef cpVect a, b, n
    cdef int i
    for i in range(count):
        a = verts[(i - 1 + count) % count]
        b = verts[i]
        n = cpvnormalize(cpvrperp(cpvsub(b, a)))
        poly.planes[i + count].v0 = b
        poly.planes[i + count].n = n
    return 1

cdef cpShapeMassInfo cpPolyShapeMassInfo(cpFloat mass, int count, const cpVect *verts,
                                         cpFloat radius) noexcept nogil:
    # The moment ignores the radius (Munk2D's approximation).
    cdef cpVect centroid = cpCentroidForPoly(count, verts)
    cdef cpShapeMassInfo info
    info.m = mass
    info.i = cpMomentForPoly(1.0, count, verts, cpvneg(centroid), radius)
    info.cog = centroid
    info.area = cpAreaForPoly(count, verts, radius)
    return info

cdef cpShapeClass cpPolyShapeClass
cpPolyShapeClass.type = CP_POLY_SHAPE
cpPolyShapeClass.cacheData = cpPolyShapeCacheData
cpPolyShapeClass.destroy = cpPolyShapeDestroy
cpPolyShapeClass.pointQuery = cpPolyShapePointQuery
cpPolyShapeClass.segmentQuery = cpPolyShapeSegmentQuery

# Scratch space for the transformed vertices and their hull (alloca in Munk2D).
cdef enum:
    _HULL_STACK = 32

cdef int _transformed_hull(int count, const cpVect *verts, cpTransform transform,
                           cpVect *hull) noexcept nogil:
    cdef int i
    # Transform first, so a mirroring transform still gives a CCW hull.
    for i in range(count):
        hull[i] = cpTransformPoint(transform, verts[i])
    return cpConvexHull(count, hull, hull, NULL, 0.0)

cdef cpPolyShape *cpPolyShapeInit(cpPolyShape *poly, cpBody *body, int count, const cpVect *verts,
                                  cpTransform transform, cpFloat radius) noexcept nogil:
    cdef cpVect stack_buf[_HULL_STACK]
    cdef cpVect *hull = stack_buf
    cdef cpPolyShape *ret
    if count > _HULL_STACK:
        hull = <cpVect *>malloc(count * sizeof(cpVect))
        if hull == NULL:
            return NULL
    cdef int hullCount = _transformed_hull(count, verts, transform, hull)
    ret = cpPolyShapeInitRaw(poly, body, hullCount, hull, radius)
    if hull != stack_buf:
        free(hull)
    return ret

cdef cpPolyShape *cpPolyShapeInitRaw(cpPolyShape *poly, cpBody *body, int count, const cpVect *verts,
                                     cpFloat radius) noexcept nogil:
    cpShapeInit(&poly.shape, &cpPolyShapeClass, body, cpPolyShapeMassInfo(0.0, count, verts, radius))
    if not SetVerts(poly, count, verts):
        return NULL
    poly.r = radius
    return poly

cdef cpShape *cpPolyShapeNew(cpBody *body, int count, const cpVect *verts, cpTransform transform,
                             cpFloat radius) noexcept nogil:
    cdef cpPolyShape *poly = <cpPolyShape *>calloc(1, sizeof(cpPolyShape))
    if poly == NULL:
        return NULL
    if cpPolyShapeInit(poly, body, count, verts, transform, radius) == NULL:
        free(poly)
        return NULL
    return &poly.shape

cdef cpShape *cpPolyShapeNewRaw(cpBody *body, int count, const cpVect *verts,
                                cpFloat radius) noexcept nogil:
    cdef cpPolyShape *poly = <cpPolyShape *>calloc(1, sizeof(cpPolyShape))
    if poly == NULL:
        return NULL
    if cpPolyShapeInitRaw(poly, body, count, verts, radius) == NULL:
        free(poly)
        return NULL
    return &poly.shape

cdef cpPolyShape *cpBoxShapeInit(cpPolyShape *poly, cpBody *body, cpFloat width, cpFloat height,
                                 cpFloat radius) noexcept nogil:
    cdef cpFloat hw = width / 2.0
    cdef cpFloat hh = height / 2.0
    return cpBoxShapeInit2(poly, body, cpBBNew(-hw, -hh, hw, hh), radius)

cdef cpPolyShape *cpBoxShapeInit2(cpPolyShape *poly, cpBody *body, cpBB box, cpFloat radius) noexcept nogil:
    # No hull: the order is (r,b), (r,t), (l,t), (l,b).
    cdef cpVect verts[4]
    verts[0] = cpv(box.r, box.b)
    verts[1] = cpv(box.r, box.t)
    verts[2] = cpv(box.l, box.t)
    verts[3] = cpv(box.l, box.b)
    return cpPolyShapeInitRaw(poly, body, 4, verts, radius)

cdef cpShape *cpBoxShapeNew(cpBody *body, cpFloat width, cpFloat height, cpFloat radius) noexcept nogil:
    cdef cpPolyShape *poly = <cpPolyShape *>calloc(1, sizeof(cpPolyShape))
    if poly == NULL:
        return NULL
    return &cpBoxShapeInit(poly, body, width, height, radius).shape

cdef cpShape *cpBoxShapeNew2(cpBody *body, cpBB box, cpFloat radius) noexcept nogil:
    cdef cpPolyShape *poly = <cpPolyShape *>calloc(1, sizeof(cpPolyShape))
    if poly == NULL:
        return NULL
    return &cpBoxShapeInit2(poly, body, box, radius).shape

cdef int cpPolyShapeGetCount(const cpShape *shape) noexcept nogil:
    return (<const cpPolyShape *>shape).count

cdef cpVect cpPolyShapeGetVert(const cpShape *shape, int i) noexcept nogil:
    # 0 <= i < count is the caller's check (Munk2D hard-asserts it).
    cdef const cpPolyShape *poly = <const cpPolyShape *>shape
    return poly.planes[i + poly.count].v0

cdef cpFloat cpPolyShapeGetRadius(const cpShape *shape) noexcept nogil:
    return (<const cpPolyShape *>shape).r

cdef cpBool cpPolyShapeSetVerts(cpShape *shape, int count, const cpVect *verts,
                                cpTransform transform) noexcept nogil:
    cdef cpVect stack_buf[_HULL_STACK]
    cdef cpVect *hull = stack_buf
    cdef cpBool ok
    if count > _HULL_STACK:
        hull = <cpVect *>malloc(count * sizeof(cpVect))
        if hull == NULL:
            return 0
    cdef int hullCount = _transformed_hull(count, verts, transform, hull)
    ok = cpPolyShapeSetVertsRaw(shape, hullCount, hull)
    if hull != stack_buf:
        free(hull)
    return ok

cdef cpBool cpPolyShapeSetVertsRaw(cpShape *shape, int count, const cpVect *verts) noexcept nogil:
    cdef cpPolyShape *poly = <cpPolyShape *>shape
    cpPolyShapeDestroy(shape)
    if not SetVerts(poly, count, verts):
        return 0
    cdef cpFloat mass = shape.massInfo.m
    shape.massInfo = cpPolyShapeMassInfo(shape.massInfo.m, count, verts, poly.r)
    if mass > 0.0:
        cpBodyAccumulateMassFromShapes(shape.body)
    return 1

cdef void cpPolyShapeSetRadius(cpShape *shape, cpFloat radius) noexcept nogil:
    # Area and moment are left as they were, as in Munk2D.
    (<cpPolyShape *>shape).r = radius


# =============================================================================
# Python level
# =============================================================================

class ShapeFilter(NamedTuple):
    """Collision filter of a shape: a group and category/mask bit sets.

    Two shapes do not collide when they share a non-zero ``group``, or when
    the ``categories`` of either has no bit in common with the ``mask`` of
    the other. By default a shape is in every category and collides with
    every category.

    >>> ShapeFilter()
    ShapeFilter(group=0, categories=4294967295, mask=4294967295)
    >>> ShapeFilter(group=1).rejects_collision(ShapeFilter(group=1))
    True
    """

    group: int = 0
    categories: int = 0xFFFFFFFF
    mask: int = 0xFFFFFFFF

    @staticmethod
    def ALL_MASKS():
        """A mask with every bit set.

        >>> hex(ShapeFilter.ALL_MASKS())
        '0xffffffff'
        """
        return 0xFFFFFFFF

    @staticmethod
    def ALL_CATEGORIES():
        """A category set with every bit set.

        >>> hex(ShapeFilter.ALL_CATEGORIES())
        '0xffffffff'
        """
        return 0xFFFFFFFF

    def rejects_collision(self, other):
        """True if shapes with these two filters would never collide.

        >>> f1 = ShapeFilter(categories=0b01, mask=0b11)
        >>> f2 = ShapeFilter(categories=0b01, mask=0b10)
        >>> f1.rejects_collision(f2)
        True
        >>> ShapeFilter(group=1).rejects_collision(ShapeFilter(group=2))
        False
        """
        return ((self.group != 0 and self.group == other.group)
                or (self.categories & other.mask) == 0
                or (other.categories & self.mask) == 0)


class PointQueryInfo(NamedTuple):
    """Result of a point query: the shape, the nearest surface point, the
    signed distance (negative inside) and the distance gradient.

    >>> import tamias2d
    >>> c = tamias2d.Circle(None, 1)
    >>> _ = c.update(tamias2d.Transform.identity())
    >>> c.point_query((3, 0)).distance
    2.0
    """

    shape: object
    point: object
    distance: float
    gradient: object


class SegmentQueryInfo(NamedTuple):
    """Result of a segment query: the shape hit, the point of impact, the
    surface normal there and alpha, the fraction of the query segment.

    >>> import tamias2d
    >>> c = tamias2d.Circle(None, 1)
    >>> _ = c.update(tamias2d.Transform.identity())
    >>> c.segment_query((-4, 0), (4, 0)).alpha
    0.375
    """

    shape: object
    point: object
    normal: object
    alpha: float


class ShapeQueryInfo(NamedTuple):
    """Result of a space shape query: the shape touched and the contact
    point set between it and the query shape.

    >>> ShapeQueryInfo(None, None)
    ShapeQueryInfo(shape=None, contact_point_set=None)
    """

    shape: object
    contact_point_set: object


def _field_docs(cls, **docs):
    # Field descriptors of a NamedTuple say "Alias for field number N";
    # say what each field holds instead (help() and the API reference show it).
    for name, doc in docs.items():
        getattr(cls, name).__doc__ = doc


_field_docs(ShapeFilter,
    group="Shapes with the same non-zero group never collide (the parts of one "
          "ragdoll, for instance); 0 is no group.",
    categories="The categories (a 32-bit set) this shape belongs to.",
    mask="The categories (a 32-bit set) this shape collides with.")
_field_docs(PointQueryInfo,
    shape="The shape queried.",
    point="The point on the shape's surface nearest to the query point (a Vec2d).",
    distance="Distance from the query point to that surface point; negative "
             "when the query point is inside the shape.",
    gradient="The gradient of that signed distance: a unit Vec2d pointing out of "
             "the shape, whether the query point is inside or outside.")
_field_docs(SegmentQueryInfo,
    shape="The shape hit.",
    point="The point where the segment first touches the shape (a Vec2d).",
    normal="The shape's surface normal at that point (a unit Vec2d).",
    alpha="Where along the query segment the hit is: 0 at its start, 1 at its end.")
_field_docs(ShapeQueryInfo,
    shape="A shape that the query shape overlaps.",
    contact_point_set="Their contacts, as a :class:`~tamias2d.ContactPointSet`.")


# -- argument checks ---------------------------------------------------------------
cdef cpFloat _radius_arg(object value, str what) except? -1.0:
    cdef cpFloat r
    try:
        r = value
    except TypeError:
        raise TypeError(f"{what} must be a number, not {type(value).__name__}") from None
    if not (r >= 0.0 and r < INFINITY):
        raise IllegalShape(f"{what} must be a finite number >= 0, got {value!r}")
    return r

cdef cpFloat _nonneg_arg(object value, str what) except? -1.0:
    # Finite and >= 0. Infinity is refused too: the solver multiplies these
    # coefficients (u = ua*ub, e = ea*eb, jtMax = u*jn, bounce = e*vrn), and
    # inf*0 makes the NaN that then reaches the body state.
    cdef cpFloat x
    try:
        x = value
    except TypeError:
        raise TypeError(f"{what} must be a number, not {type(value).__name__}") from None
    if not (x >= 0.0 and x < INFINITY):
        raise IllegalShape(f"{what} must be a finite number >= 0 (use a large value such as "
                           f"1e9 rather than infinity), got {value!r}")
    return x

cdef cpFloat _mass_arg(object value, str what) except? -1.0:
    cdef cpFloat x
    try:
        x = value
    except TypeError:
        raise TypeError(f"{what} must be a number, not {type(value).__name__}") from None
    if not (x >= 0.0 and x < INFINITY):
        raise IllegalShape(f"{what} must be a finite number >= 0, got {value!r}")
    return x

cdef Body _body_arg(object body):
    cdef Body b
    if body is None:
        return None
    if not isinstance(body, Body):
        raise IllegalBody(f"body must be a tamias2d.Body or None, not {type(body).__module__}."
                          f"{type(body).__qualname__}")
    b = <Body>body
    if b._shapes is None:
        raise IllegalBody("body is not initialised (Body.__init__ has not run)")
    return b

cdef inline cpBool _mass_info_finite(const cpShapeMassInfo *info) noexcept nogil:
    return isfinite(info.i) and isfinite(info.cog.x) and isfinite(info.cog.y)

cdef int _check_massive(const cpShapeMassInfo *info, cpFloat mass) except -1:
    # A degenerate shape (zero-area polygon) has no centre of gravity; giving
    # it mass would turn its body's mass data into NaN.
    if mass > 0.0 and not _mass_info_finite(info):
        raise IllegalShape("a degenerate shape (a polygon without area) cannot carry mass: "
                           "its moment or center of gravity is undefined")
    # The body's inverse mass comes from this: an infinite mass (a huge
    # density times the area overflows) would make the body kinematic, one
    # whose inverse overflows (5e-324) a NaN body at its first contact.
    if not (mass < INFINITY):
        raise IllegalShape("the shape's mass would not be finite (density x area overflows)")
    if mass > 0.0 and not (1.0 / mass < INFINITY):
        raise IllegalShape("the shape's mass %r is too small: its inverse is not finite" % mass)
    return 0


cdef class _VertBuffer:
    # Owns a C copy of a Python vertex list (fields in shape.pxd).
    def __dealloc__(self):
        free(self.verts)


cdef _VertBuffer _verts_arg(object vertices, bint finite):
    cdef _VertBuffer buf = _VertBuffer.__new__(_VertBuffer)
    cdef Py_ssize_t n, i
    if isinstance(vertices, (str, bytes)):
        raise TypeError("vertices must be a sequence of (x, y) pairs, not a string")
    try:
        items = list(vertices)
    except TypeError:
        raise TypeError(f"vertices must be a sequence of (x, y) pairs, not "
                        f"{type(vertices).__name__}") from None
    n = len(items)
    if n == 0:
        raise IllegalShape("a polygon needs at least one vertex, got none")
    if n > INT_MAX // 2:
        raise IllegalShape(f"too many vertices ({n})")
    buf.verts = <cpVect *>malloc(n * sizeof(cpVect))
    if buf.verts == NULL:
        raise MemoryError()
    buf.count = <int>n
    for i in range(n):
        if finite:
            buf.verts[i] = cpv_from_object_finite(items[i], "vertex")
        else:
            buf.verts[i] = cpv_from_object(items[i])
    return buf

cdef int _check_transform_finite(const cpTransform *t) except -1:
    if not (isfinite(t.a) and isfinite(t.b) and isfinite(t.c) and isfinite(t.d)
            and isfinite(t.tx) and isfinite(t.ty)):
        raise IllegalShape("transform must have finite components")
    return 0


cdef object _shape_from_ptr(const cpShape *shape):
    if shape == NULL or shape.userData == NULL:
        return None
    return <object>shape.userData


# -- Shape ----------------------------------------------------------------------------------
cdef class Shape:
    """Base class of the collision shapes :class:`Circle`, :class:`Segment`
    and :class:`Poly`; it is not instantiated directly.

    A shape is attached to a body (or to none, for queries) and carries the
    surface properties used by the collision solver. Shapes can be copied and
    pickled; their body is copied with them.

    >>> import tamias2d
    >>> s = tamias2d.Circle(None, 1)
    >>> isinstance(s, tamias2d.Shape)
    True
    """

    _pickle_attrs_init = ["body"]
    _pickle_attrs_general = ["sensor", "collision_type", "filter", "elasticity",
                             "friction", "surface_velocity", "_hashid"]
    _pickle_attrs_skip = ["mass", "density"]

    def __cinit__(self, *args, **kwargs):
        if not isinstance(self, (Circle, Segment, Poly)):
            raise TypeError("Shape is abstract: create a Circle, Segment or Poly")
        self._space = None
        self._body_obj = None

    @property
    def mass(self):
        """The mass of the shape, used when the body's mass is computed from
        its shapes (which happens when they are in a space).

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c.mass = 2
        >>> c.mass
        2.0
        """
        return self._shape.massInfo.m

    @mass.setter
    def mass(self, mass):
        cdef cpFloat m = _mass_arg(mass, "mass")
        _check_massive(&self._shape.massInfo, m)
        tamias_wait_shape(self._shape)
        cpShapeSetMass(self._shape, m)

    @property
    def density(self):
        """The density of the shape: mass / area. Setting it sets the mass.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c.density = 2
        >>> c.mass == 2 * c.area
        True
        """
        return cpShapeGetDensity(self._shape)

    @density.setter
    def density(self, density):
        cdef cpFloat d = _mass_arg(density, "density")
        _check_massive(&self._shape.massInfo, d * self._shape.massInfo.area)
        tamias_wait_shape(self._shape)
        cpShapeSetDensity(self._shape, d)

    @property
    def moment(self):
        """The moment of inertia of the shape about its own center of gravity.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 5)
        >>> c.mass = 2
        >>> c.moment
        25.0
        """
        return cpShapeGetMoment(self._shape)

    @property
    def area(self):
        """The area of the shape.

        >>> import tamias2d
        >>> tamias2d.Poly.create_box(None, (2, 3)).area
        6.0
        """
        return self._shape.massInfo.area

    @property
    def center_of_gravity(self):
        """The center of gravity of the shape, in body coordinates.

        >>> import tamias2d
        >>> tamias2d.Circle(None, 5, (10, 5)).center_of_gravity
        Vec2d(10.0, 5.0)
        """
        return vec2d_from_cpv(self._shape.massInfo.cog)

    @property
    def sensor(self):
        """A sensor shape reports collisions to the callbacks but never
        produces contact forces.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c.sensor = True
        >>> c.sensor
        True
        """
        return bool(self._shape.sensor)

    @sensor.setter
    def sensor(self, is_sensor):
        cdef cpBool value = 1 if is_sensor else 0
        tamias_wait_shape(self._shape)
        cpShapeSetSensor(self._shape, value)

    @property
    def collision_type(self):
        """A user-defined type (an int >= 0) that selects collision handlers.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c.collision_type = 3
        >>> c.collision_type
        3
        """
        return self._shape.type

    @collision_type.setter
    def collision_type(self, t):
        cdef cpCollisionType value = t
        tamias_wait_shape(self._shape)
        cpShapeSetCollisionType(self._shape, value)

    @property
    def filter(self):
        """The :class:`ShapeFilter` of the shape.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c.filter = tamias2d.ShapeFilter(group=2)
        >>> c.filter.group
        2
        """
        cdef cpShapeFilter f = self._shape.filter
        return ShapeFilter(f.group, f.categories, f.mask)

    @filter.setter
    def filter(self, f):
        cdef cpShapeFilter cf
        try:
            group, categories, mask = f
        except (TypeError, ValueError):
            raise TypeError("filter must be a ShapeFilter (group, categories, mask)") from None
        cf.group = group
        cf.categories = categories
        cf.mask = mask
        tamias_wait_shape(self._shape)
        cpShapeSetFilter(self._shape, cf)

    @property
    def elasticity(self):
        """Elasticity (restitution) of the surface, finite and >= 0. 0 gives
        no bounce, 1 a perfect bounce.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c.elasticity = 0.5
        >>> c.elasticity
        0.5
        """
        return self._shape.e

    @elasticity.setter
    def elasticity(self, e):
        cdef cpFloat value = _nonneg_arg(e, "elasticity")
        tamias_wait_shape(self._shape)
        cpShapeSetElasticity(self._shape, value)

    @property
    def friction(self):
        """Coulomb friction coefficient of the surface, finite and >= 0.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c.friction = 0.7
        >>> c.friction
        0.7
        """
        return self._shape.u

    @friction.setter
    def friction(self, u):
        cdef cpFloat value = _nonneg_arg(u, "friction")
        tamias_wait_shape(self._shape)
        cpShapeSetFriction(self._shape, value)

    @property
    def surface_velocity(self):
        """Velocity of the surface itself (conveyor belts); used for friction
        only.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c.surface_velocity = (1, 2)
        >>> c.surface_velocity
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(self._shape.surfaceV)

    @surface_velocity.setter
    def surface_velocity(self, surface_v):
        cdef cpVect value = cpv_from_object_finite(surface_v, "surface_velocity")
        tamias_wait_shape(self._shape)
        cpShapeSetSurfaceVelocity(self._shape, value)

    @property
    def body(self):
        """The body the shape is attached to, or None.

        The shape keeps its body alive. It can be moved to another body (or
        None) while it is not in a space.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> c = tamias2d.Circle(b, 1)
        >>> c.body is b, c in b.shapes
        (True, True)
        >>> c.body = None
        >>> c in b.shapes
        False
        """
        return self._body_obj

    @body.setter
    def body(self, body):
        cdef Body b = _body_arg(body)
        if self._shape.space != NULL or cpShapeActive(self._shape):
            raise AlreadyInSpace("cannot change the body of a shape that is in a space; "
                                 "remove the shape from the space first")
        if self._body_obj is not None and self._body_obj._shapes is not None:
            self._body_obj._shapes.pop(self, None)
        tamias_wait_shape(self._shape)
        cpShapeSetBody(self._shape, NULL if b is None else &b._body)
        if b is not None:
            b._shapes[self] = None
        self._body_obj = b

    @property
    def space(self):
        """The space the shape has been added to, or None.

        >>> import tamias2d
        >>> tamias2d.Circle(None, 1).space is None
        True
        """
        if self._space is None:
            return None
        return self._space()

    @property
    def bb(self):
        """The bounding box cached by the last :meth:`cache_bb`,
        :meth:`update` or space step.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 5)
        >>> _ = c.update(tamias2d.Transform.identity())
        >>> c.bb
        BB(left=-5.0, bottom=-5.0, right=5.0, top=5.0)
        """
        return bb_from_cpbb(self._shape.bb)

    def cache_bb(self):
        """Recompute the world geometry and bounding box from the body's
        position and angle, store and return the box.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.position = 10, 0
        >>> tamias2d.Circle(b, 2).cache_bb()
        BB(left=8.0, bottom=-2.0, right=12.0, top=2.0)
        """
        if self._shape.body == NULL:
            raise IllegalBody("cache_bb needs a body; use update(transform) for a shape without one")
        tamias_wait_shape(self._shape)
        return bb_from_cpbb(cpShapeCacheBB(self._shape))

    def update(self, transform):
        """Recompute the world geometry and bounding box with an explicit
        :class:`Transform` (for shapes without a body), store and return it.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 5)
        >>> c.update(tamias2d.Transform(1, 2, 3, 4, 5, 6))
        BB(left=0.0, bottom=1.0, right=10.0, top=11.0)
        """
        cdef cpTransform t = cptransform_from_object(transform)
        tamias_wait_shape(self._shape)
        return bb_from_cpbb(cpShapeUpdate(self._shape, t))

    def point_query(self, p):
        """Distance from point p to the shape (negative inside) with the
        nearest surface point and the gradient, as a :class:`PointQueryInfo`.

        Uses the cached world geometry: call :meth:`cache_bb` or
        :meth:`update` first.

        >>> import tamias2d
        >>> c = tamias2d.Circle(tamias2d.Body(1, 1), 5)
        >>> _ = c.cache_bb()
        >>> info = c.point_query((11, 0))
        >>> info.point, info.distance, info.gradient
        (Vec2d(5.0, 0.0), 6.0, Vec2d(1.0, 0.0))
        """
        cdef cpVect cp = cpv_from_object(p)
        cdef cpPointQueryInfo info
        cpShapePointQuery(self._shape, cp, &info)
        return PointQueryInfo(_shape_from_ptr(info.shape), vec2d_from_cpv(info.point),
                              info.distance, vec2d_from_cpv(info.gradient))

    def segment_query(self, start, end, radius=0):
        """First hit of the segment start-end (swept with a radius) against
        the shape, as a :class:`SegmentQueryInfo`, or None if it misses.

        Uses the cached world geometry: call :meth:`cache_bb` or
        :meth:`update` first.

        >>> import tamias2d
        >>> c = tamias2d.Circle(tamias2d.Body(1, 1), 5)
        >>> _ = c.cache_bb()
        >>> c.segment_query((0, -50), (0, 50)).alpha
        0.45
        >>> c.segment_query((10, -50), (10, 50)) is None
        True
        """
        cdef cpVect a = cpv_from_object(start)
        cdef cpVect b = cpv_from_object(end)
        cdef cpFloat r = radius
        cdef cpSegmentQueryInfo info
        if cpShapeSegmentQuery(self._shape, a, b, r, &info):
            return SegmentQueryInfo(_shape_from_ptr(info.shape), vec2d_from_cpv(info.point),
                                    vec2d_from_cpv(info.normal), info.alpha)
        return None

    def shapes_collide(self, b):
        """Contact information between this shape and shape b, as a
        ContactPointSet (from the cached world geometry of both).

        >>> import tamias2d
        >>> s1 = tamias2d.Circle(tamias2d.Body(1, 1), 10)
        >>> b2 = tamias2d.Body(1, 1)
        >>> b2.position = 15, 0
        >>> s2 = tamias2d.Circle(b2, 10)
        >>> _ = s1.cache_bb(), s2.cache_bb()
        >>> s1.shapes_collide(s2).points[0].distance
        -5.0
        """
        if not isinstance(b, Shape):
            raise TypeError(f"shapes_collide needs a Shape, not {type(b).__name__}")
        from tamias2d.collision import shapes_collide
        return shapes_collide(self, b)

    @property
    def _hashid(self):
        return self._shape.hashid

    @_hashid.setter
    def _hashid(self, v):
        self._shape.hashid = <cpHashValue>v

    def __getstate__(self):
        """The state used by copy and pickle, in pymunk's layout.

        >>> import tamias2d
        >>> sorted(tamias2d.Circle(None, 1).__getstate__())
        ['custom', 'general', 'init', 'special']
        """
        cdef dict d = pymunk_getstate(self)
        if self.mass > 0:
            d["general"].append(("mass", self.mass))
        density = self.density
        # pymunk also stores an infinite density (mass on a zero-area
        # shape), which would turn the mass into NaN when restored.
        if density > 0 and density < INFINITY:
            d["general"].append(("density", density))
        return d

    def __setstate__(self, state):
        """Restore a state made by :meth:`__getstate__`.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 1)
        >>> c2 = tamias2d.Circle(None, 5)
        >>> c2.__setstate__(c.__getstate__())
        >>> c2.radius
        1.0
        """
        if isinstance(state, tuple):
            # The compact state of __reduce_ex__ (see tamias2d._snapshot).
            _snapshot().shape_setstate(self, state)
            return
        pymunk_setstate(self, state)

    def __reduce__(self):
        return pymunk_reduce(self)

    def __reduce_ex__(self, protocol):
        """What copy and pickle use: the kind, the body, the C struct as bytes
        and the user attributes (pymunk's layout for a subclass that overrides
        ``__getstate__`` or ``__setstate__``). A shape restored on its own
        comes back as pymunk restores it; inside a space's state it comes
        back bit for bit (see tamias2d._snapshot).

        >>> import pickle, tamias2d
        >>> c = tamias2d.Circle(tamias2d.Body(1, 1), 0.3)
        >>> pickle.loads(pickle.dumps(c)).radius
        0.3
        """
        return _snapshot().shape_reduce(self)

    def copy(self):
        """A deep copy of the shape (and of its body).

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 3, (1, 2))
        >>> c.copy().offset
        Vec2d(1.0, 2.0)
        """
        return deep_copy(self)


# -- Circle ----------------------------------------------------------------------------------
cdef class Circle(Shape):
    """A circle of a given radius, centred at offset in body coordinates.
    The fastest shape.

    >>> import tamias2d
    >>> c = tamias2d.Circle(None, 5, (1, 2))
    >>> c.radius, c.offset
    (5.0, Vec2d(1.0, 2.0))
    """

    _pickle_attrs_init = Shape._pickle_attrs_init + ["radius", "offset"]

    def __cinit__(self, *args, **kwargs):
        self._shape = &self._circle.shape
        cpCircleShapeInit(&self._circle, NULL, 0.0, cpv(0.0, 0.0))
        self._shape.userData = <void *>self

    def __init__(self, body, radius, offset=(0, 0)):
        cdef Body b = _body_arg(body)
        cdef cpFloat r = _radius_arg(radius, "radius")
        cdef cpVect c = cpv_from_object_finite(offset, "offset")
        _prepare_reinit(self)
        memset(&self._circle, 0, sizeof(cpCircleShape))
        cpCircleShapeInit(&self._circle, NULL if b is None else &b._body, r, c)
        _attach(self, b)

    @property
    def radius(self):
        """The radius of the circle.

        >>> import tamias2d
        >>> tamias2d.Circle(None, 5).radius
        5.0
        """
        return cpCircleShapeGetRadius(self._shape)

    @property
    def offset(self):
        """The centre of the circle in body coordinates.

        >>> import tamias2d
        >>> tamias2d.Circle(None, 5, (1, 2)).offset
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(cpCircleShapeGetOffset(self._shape))

    def unsafe_set_radius(self, r):
        """Change the radius (and the mass data). Unsafe: the change is not
        seen as a motion by the solver.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 5)
        >>> c.unsafe_set_radius(3)
        >>> c.radius
        3.0
        """
        cdef cpFloat radius = _radius_arg(r, "radius")
        tamias_wait_shape(self._shape)
        cpCircleShapeSetRadius(self._shape, radius)

    def unsafe_set_offset(self, o):
        """Change the offset (and the mass data). Unsafe: the change is not
        seen as a motion by the solver.

        >>> import tamias2d
        >>> c = tamias2d.Circle(None, 5)
        >>> c.unsafe_set_offset((3, 4))
        >>> c.offset
        Vec2d(3.0, 4.0)
        """
        cdef cpVect c = cpv_from_object_finite(o, "offset")
        tamias_wait_shape(self._shape)
        cpCircleShapeSetOffset(self._shape, c)


# -- Segment ---------------------------------------------------------------------------------
cdef class Segment(Shape):
    """A line segment from a to b (body coordinates), rounded by radius.
    Meant mostly for static geometry.

    >>> import tamias2d
    >>> s = tamias2d.Segment(None, (2, 2), (2, 3), 4)
    >>> s.a, s.b, s.normal, s.radius
    (Vec2d(2.0, 2.0), Vec2d(2.0, 3.0), Vec2d(1.0, -0.0), 4.0)
    """

    _pickle_attrs_init = Shape._pickle_attrs_init + ["a", "b", "radius"]

    def __cinit__(self, *args, **kwargs):
        self._shape = &self._segment.shape
        cpSegmentShapeInit(&self._segment, NULL, cpv(0.0, 0.0), cpv(0.0, 0.0), 0.0)
        self._shape.userData = <void *>self

    def __init__(self, body, a, b, radius):
        cdef Body bd = _body_arg(body)
        cdef cpVect ca = cpv_from_object_finite(a, "a")
        cdef cpVect cb = cpv_from_object_finite(b, "b")
        cdef cpFloat r = _radius_arg(radius, "radius")
        _prepare_reinit(self)
        memset(&self._segment, 0, sizeof(cpSegmentShape))
        cpSegmentShapeInit(&self._segment, NULL if bd is None else &bd._body, ca, cb, r)
        _attach(self, bd)

    @property
    def a(self):
        """The first endpoint, in body coordinates.

        >>> import tamias2d
        >>> tamias2d.Segment(None, (1, 2), (3, 4), 0).a
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(cpSegmentShapeGetA(self._shape))

    @property
    def b(self):
        """The second endpoint, in body coordinates.

        >>> import tamias2d
        >>> tamias2d.Segment(None, (1, 2), (3, 4), 0).b
        Vec2d(3.0, 4.0)
        """
        return vec2d_from_cpv(cpSegmentShapeGetB(self._shape))

    @property
    def normal(self):
        """The unit normal of the segment, in body coordinates.

        >>> import tamias2d
        >>> tamias2d.Segment(None, (0, 0), (0, 1), 0).normal
        Vec2d(1.0, -0.0)
        """
        return vec2d_from_cpv(cpSegmentShapeGetNormal(self._shape))

    @property
    def radius(self):
        """The radius (thickness) of the segment.

        >>> import tamias2d
        >>> tamias2d.Segment(None, (0, 0), (0, 1), 2).radius
        2.0
        """
        return cpSegmentShapeGetRadius(self._shape)

    def set_neighbors(self, prev, next):
        """Tell the segment the endpoints of the segments joined to it, so
        that objects sliding across the joints do not catch on them.

        >>> import tamias2d
        >>> s = tamias2d.Segment(None, (0, 0), (1, 0), 0)
        >>> s.set_neighbors((-1, 0), (2, 0))
        """
        cdef cpVect p = cpv_from_object_finite(prev, "prev")
        cdef cpVect n = cpv_from_object_finite(next, "next")
        tamias_wait_shape(self._shape)
        cpSegmentShapeSetNeighbors(self._shape, p, n)

    def unsafe_set_endpoints(self, a, b):
        """Change both endpoints (and the mass data). As in Munk2D the normal
        is recomputed with the opposite orientation. Unsafe: the change is
        not seen as a motion by the solver.

        >>> import tamias2d
        >>> s = tamias2d.Segment(None, (0, 0), (1, 0), 0)
        >>> s.unsafe_set_endpoints((3, 4), (5, 6))
        >>> s.a, s.b
        (Vec2d(3.0, 4.0), Vec2d(5.0, 6.0))
        """
        cdef cpVect ca = cpv_from_object_finite(a, "a")
        cdef cpVect cb = cpv_from_object_finite(b, "b")
        cdef cpShapeMassInfo info = cpSegmentShapeMassInfo(
            self._shape.massInfo.m, ca, cb, self._segment.r)
        _check_massive(&info, info.m)
        tamias_wait_shape(self._shape)
        cpSegmentShapeSetEndpoints(self._shape, ca, cb)

    def unsafe_set_radius(self, r):
        """Change the radius (and the mass data). Unsafe: the change is not
        seen as a motion by the solver.

        >>> import tamias2d
        >>> s = tamias2d.Segment(None, (0, 0), (1, 0), 1)
        >>> s.unsafe_set_radius(5)
        >>> s.radius
        5.0
        """
        cdef cpFloat radius = _radius_arg(r, "radius")
        tamias_wait_shape(self._shape)
        cpSegmentShapeSetRadius(self._shape, radius)


# -- Poly ------------------------------------------------------------------------------------
cdef class Poly(Shape):
    """A convex polygon, optionally rounded by a radius. The convex hull of
    the given vertices (after the optional transform) is used: it runs
    counter-clockwise from the lowest-x (then lowest-y) vertex.

    >>> import tamias2d
    >>> Poly(None, [(-1, 0), (0, -0.5), (1, 0), (0, -1)]).get_vertices()
    [Vec2d(-1.0, 0.0), Vec2d(0.0, -1.0), Vec2d(1.0, 0.0)]
    """

    def __cinit__(self, *args, **kwargs):
        cdef cpVect origin = cpv(0.0, 0.0)
        self._shape = &self._poly.shape
        # A one-vertex placeholder until __init__ (or create_box) runs, so
        # that no state ever leaves the planes pointer dangling.
        cpPolyShapeInitRaw(&self._poly, NULL, 1, &origin, 0.0)
        self._shape.userData = <void *>self

    def __dealloc__(self):
        cpShapeDestroy(&self._poly.shape)

    def __init__(self, body, vertices, transform=None, radius=0):
        cdef Body b = _body_arg(body)
        cdef _VertBuffer buf = _verts_arg(vertices, True)
        cdef cpTransform t = cpTransformIdentity()
        if transform is not None:
            t = cptransform_from_object(transform)
            _check_transform_finite(&t)
        cdef cpFloat r = _radius_arg(radius, "radius")
        _poly_reset(self)
        if cpPolyShapeInit(&self._poly, NULL if b is None else &b._body,
                           buf.count, buf.verts, t, r) == NULL:
            _poly_init_failed(self)
        _attach(self, b)

    @staticmethod
    def create_box(body, size=(10, 10), radius=0):
        """A box of size (width, height) centred on the body's center of
        gravity. Its vertices are not hulled: (w/2, -h/2), (w/2, h/2),
        (-w/2, h/2), (-w/2, -h/2).

        >>> import tamias2d
        >>> tamias2d.Poly.create_box(None, (4, 2)).get_vertices()
        [Vec2d(2.0, -1.0), Vec2d(2.0, 1.0), Vec2d(-2.0, 1.0), Vec2d(-2.0, -1.0)]
        """
        cdef Body b = _body_arg(body)
        cdef cpFloat w, h
        try:
            sw, sh = size
        except (TypeError, ValueError):
            raise TypeError("size must be a (width, height) pair") from None
        w = _radius_arg(sw, "box width")
        h = _radius_arg(sh, "box height")
        cdef cpFloat r = _radius_arg(radius, "radius")
        cdef Poly self = Poly.__new__(Poly)
        _poly_reset(self)
        cpBoxShapeInit(&self._poly, NULL if b is None else &b._body, w, h, r)
        _attach(self, b)
        return self

    @staticmethod
    def create_box_bb(body, bb, radius=0):
        """A box with the corners of a :class:`BB` (body coordinates). Its
        vertices are not hulled: (r, b), (r, t), (l, t), (l, b).

        >>> import tamias2d
        >>> tamias2d.Poly.create_box_bb(None, tamias2d.BB(1, 2, 3, 4)).get_vertices()
        [Vec2d(3.0, 2.0), Vec2d(3.0, 4.0), Vec2d(1.0, 4.0), Vec2d(1.0, 2.0)]
        """
        cdef Body b = _body_arg(body)
        cdef cpBB box = cpbb_from_object(bb)
        if not (isfinite(box.l) and isfinite(box.b) and isfinite(box.r) and isfinite(box.t)):
            raise IllegalShape(f"box corners must be finite, got {bb!r}")
        if not (box.l <= box.r and box.b <= box.t):
            raise IllegalShape(f"box must have left <= right and bottom <= top, got {bb!r}")
        cdef cpFloat r = _radius_arg(radius, "radius")
        cdef Poly self = Poly.__new__(Poly)
        _poly_reset(self)
        cpBoxShapeInit2(&self._poly, NULL if b is None else &b._body, box, r)
        _attach(self, b)
        return self

    def get_vertices(self):
        """The vertices in body coordinates, in the polygon's order.

        >>> import tamias2d
        >>> tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)]).get_vertices()
        [Vec2d(0.0, 0.0), Vec2d(1.0, 0.0), Vec2d(0.0, 1.0)]
        """
        cdef int n = cpPolyShapeGetCount(self._shape)
        cdef int i
        return [vec2d_from_cpv(cpPolyShapeGetVert(self._shape, i)) for i in range(n)]

    def get_vertex(self, int index):
        """Vertex number index (0 <= index < count) in body coordinates.
        A tamias2d addition (Munk2D's cpPolyShapeGetVert).

        >>> import tamias2d
        >>> p = tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)])
        >>> p.get_vertex(1)
        Vec2d(1.0, 0.0)
        """
        cdef int n = cpPolyShapeGetCount(self._shape)
        if not (0 <= index < n):
            raise IndexOutOfBounds(f"vertex index {index} out of range for a polygon of {n} vertices")
        return vec2d_from_cpv(cpPolyShapeGetVert(self._shape, index))

    @property
    def radius(self):
        """The rounding radius of the polygon.

        >>> import tamias2d
        >>> tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)], radius=2).radius
        2.0
        """
        return cpPolyShapeGetRadius(self._shape)

    def unsafe_set_radius(self, radius):
        """Change the radius. As in Munk2D, area and moment are not updated.
        Unsafe: the change is not seen as a motion by the solver.

        >>> import tamias2d
        >>> p = tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)])
        >>> p.unsafe_set_radius(3)
        >>> p.radius
        3.0
        """
        cdef cpFloat r = _radius_arg(radius, "radius")
        tamias_wait_shape(self._shape)
        cpPolyShapeSetRadius(self._shape, r)

    def unsafe_set_vertices(self, vertices, transform=None):
        """Replace the vertices (and the mass data). Without a transform the
        vertices are used as given, with no convex hull (as pymunk does);
        with one they are transformed and hulled. Unsafe: the change is not
        seen as a motion by the solver.

        >>> import tamias2d
        >>> p = tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)])
        >>> p.unsafe_set_vertices([(-3, 3), (0, 0), (3, 0)])
        >>> p.get_vertices()
        [Vec2d(-3.0, 3.0), Vec2d(0.0, 0.0), Vec2d(3.0, 0.0)]
        """
        cdef _VertBuffer buf = _verts_arg(vertices, True)
        cdef cpTransform t
        cdef cpVect *hull
        cdef int hull_count
        cdef cpShapeMassInfo info
        cdef cpBool ok
        if transform is None:
            info = cpPolyShapeMassInfo(self._shape.massInfo.m, buf.count, buf.verts, self._poly.r)
            _check_massive(&info, info.m)
            tamias_wait_shape(self._shape)
            ok = cpPolyShapeSetVertsRaw(self._shape, buf.count, buf.verts)
        else:
            t = cptransform_from_object(transform)
            _check_transform_finite(&t)
            # Hull into a scratch copy first so the mass check sees the
            # final vertices before the shape is touched.
            hull = <cpVect *>malloc(buf.count * sizeof(cpVect))
            if hull == NULL:
                raise MemoryError()
            try:
                hull_count = _transformed_hull(buf.count, buf.verts, t, hull)
                info = cpPolyShapeMassInfo(self._shape.massInfo.m, hull_count, hull, self._poly.r)
                _check_massive(&info, info.m)
            finally:
                free(hull)
            tamias_wait_shape(self._shape)
            ok = cpPolyShapeSetVerts(self._shape, buf.count, buf.verts, t)
        if not ok:
            _poly_init_failed(self)

    def __getstate__(self):
        """The state used by copy and pickle, in pymunk's layout.

        >>> import tamias2d
        >>> st = tamias2d.Poly(None, [(0, 0), (1, 0), (0, 1)]).__getstate__()
        >>> [k for k, v in st["init"]]
        ['body', 'vertices', 'transform', 'radius']
        """
        d = Shape.__getstate__(self)
        d["init"].append(("vertices", self.get_vertices()))
        d["init"].append(("transform", None))
        d["init"].append(("radius", self.radius))
        return d


# Called by the subclasses once their C struct has been (re)initialised.
cdef int _attach(Shape self, Body body) except -1:
    self._shape.userData = <void *>self
    self._body_obj = body
    if body is not None:
        body._shapes[self] = None
    return 0

# Checks before a subclass re-runs its C init (a second __init__ call or
# unpickling into a used object), and detaches from the old body.
cdef int _prepare_reinit(Shape self) except -1:
    if self._shape.space != NULL or cpShapeActive(self._shape):
        raise AlreadyInSpace("cannot re-initialise a shape that is in a space; remove it first")
    if self._body_obj is not None:
        if self._body_obj._shapes is not None:
            self._body_obj._shapes.pop(self, None)
        self._body_obj = None
    return 0

# Frees the planes and zeroes the struct, as a fresh calloc'd shape.
cdef int _poly_reset(Poly self) except -1:
    _prepare_reinit(self)
    cpShapeDestroy(&self._poly.shape)
    memset(&self._poly, 0, sizeof(cpPolyShape))
    self._poly.planes = self._poly._planes
    return 0

# Out of memory inside the C init: fall back to the placeholder.
cdef int _poly_init_failed(Poly self) except -1:
    cdef cpVect origin = cpv(0.0, 0.0)
    cpPolyShapeInitRaw(&self._poly, NULL, 1, &origin, 0.0)
    self._shape.userData = <void *>self
    raise MemoryError()


# -- module functions (pymunk's signatures) -----------------------------------------------------
def moment_for_circle(mass, inner_radius, outer_radius, offset=(0, 0)):
    """Moment of inertia of a hollow circle (a solid one has inner_radius 0)
    about the body origin, the circle centred at offset.

    >>> moment_for_circle(1, 2, 3, (1, 2))
    11.5
    """
    return cpMomentForCircle(mass, inner_radius, outer_radius, cpv_from_object(offset))

def moment_for_segment(mass, a, b, radius):
    """Moment of inertia of a (rounded) segment about the body origin.

    >>> moment_for_segment(1, (-10, 0), (10, 0), 1)
    40.666666666666664
    """
    return cpMomentForSegment(mass, cpv_from_object(a), cpv_from_object(b), radius)

def moment_for_box(mass, size):
    """Moment of inertia of a solid box of size (width, height) centred on the
    body.

    >>> moment_for_box(12, (2, 3))
    13.0
    """
    try:
        w, h = size
    except (TypeError, ValueError):
        raise TypeError("size must be a (width, height) pair") from None
    return cpMomentForBox(mass, w, h)

def moment_for_poly(mass, vertices, offset=(0, 0), radius=0):
    """Moment of inertia of a solid polygon about the body origin, offset
    added to every vertex. The radius is ignored, as in Munk2D.

    >>> moment_for_poly(1, [(0, 0), (10, 10), (10, 0)], (1, 2), 3)
    98.33333333333333
    """
    cdef _VertBuffer buf = _verts_arg(vertices, False)
    return cpMomentForPoly(mass, buf.count, buf.verts, cpv_from_object(offset), radius)

def area_for_circle(inner_radius, outer_radius):
    """Area of a hollow circle.

    >>> area_for_circle(1, 2)
    9.42477796076938
    """
    return cpAreaForCircle(inner_radius, outer_radius)

def area_for_segment(a, b, radius):
    """Area of a rounded segment (zero when radius is zero).

    >>> area_for_segment((-10, 0), (10, 0), 3)
    148.27433388230813
    """
    return cpAreaForSegment(cpv_from_object(a), cpv_from_object(b), radius)

def area_for_poly(vertices, radius=0):
    """Signed area of a polygon (negative for clockwise winding), grown by
    the rounding radius.

    >>> area_for_poly([(0, 0), (10, 10), (10, 0)], 3)
    80.70074075350098
    """
    cdef _VertBuffer buf = _verts_arg(vertices, False)
    return cpAreaForPoly(buf.count, buf.verts, radius)

def centroid_for_poly(vertices):
    """Centroid (center of gravity) of a polygon.

    >>> centroid_for_poly([(0, 0), (3, 0), (0, 3)])
    Vec2d(1.0, 1.0)
    """
    cdef _VertBuffer buf = _verts_arg(vertices, False)
    return vec2d_from_cpv(cpCentroidForPoly(buf.count, buf.verts))
