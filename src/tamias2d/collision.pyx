"""Collision Solver (MIS section 10): the narrow phase and the contact helpers.

The C part is a port of Munk2D's cpCollision.c and cpRobust.c: a 9-slot table
of collision functions indexed by the sorted shape types, analytic tests for
circles, GJK (warm-started from a cached feature id) and EPA for everything
with corners, and clipping of the two support edges into at most two
contacts. The arithmetic follows Munk2D operation by operation so the results
are bitwise equal to pymunk's.

The Python part offers :func:`shapes_collide` (what ``Shape.shapes_collide``
calls), :class:`ContactPoint` and :class:`ContactPointSet` as pymunk has them,
and wrappers of the impulse helpers for tests and experiments. The test and
benchmark hooks that run cpCollide or single table slots on Python shapes are
in ``_testing``.
"""
import warnings

from libc.math cimport sqrt, INFINITY
from libc.float cimport DBL_MIN

from tamias2d._config cimport (cpFloat, cpHashValue, cpCollisionID, cpBool,
    CP_HASH_PAIR, CP_MAX_CONTACTS_PER_ARBITER, MAX_GJK_ITERATIONS,
    MAX_EPA_ITERATIONS, WARN_GJK_ITERATIONS, WARN_EPA_ITERATIONS)
from tamias2d._structs cimport (cpBody, cpShape, cpShapeType, cpCircleShape,
    cpSegmentShape, cpPolyShape, cpSplittingPlane, cpContact, cpCollisionInfo,
    cpContactPoint, cpContactPointSet, CP_CIRCLE_SHAPE, CP_SEGMENT_SHAPE,
    CP_POLY_SHAPE, CP_NUM_SHAPES)
from tamias2d.vector cimport (cpVect, cpBB, cpv, cpveql, cpvadd, cpvsub, cpvneg,
    cpvmult, cpvdot, cpvcross, cpvperp, cpvrperp, cpvrotate, cpvlengthsq,
    cpvlength, cpvnormalize, cpvlerp, cpfmax, cpfclamp, cpfclamp01, cpBBCenter,
    vec2d_from_cpv, cpv_from_object_finite)
from tamias2d.body cimport Body
# Aliases of this module's own inline helpers, so the Python wrappers below
# can carry the same names.
from tamias2d.collision cimport (relative_velocity as c_relative_velocity,
    normal_relative_velocity as c_normal_relative_velocity,
    apply_impulse as c_apply_impulse, apply_impulses as c_apply_impulses,
    apply_bias_impulse as c_apply_bias_impulse,
    apply_bias_impulses as c_apply_bias_impulses,
    k_scalar_body as c_k_scalar_body, k_scalar as c_k_scalar)
from tamias2d.shape cimport Shape

from tamias2d.errors import (CollisionError, CollisionContactOverflow,
    HighIterWarning, UnsolvableCollision)

__all__ = [
    "ContactPoint", "ContactPointSet", "shapes_collide",
    "relative_velocity", "normal_relative_velocity", "apply_impulse",
    "apply_impulses", "apply_bias_impulse", "apply_bias_impulses",
    "k_scalar_body", "k_scalar",
]

# -- per-thread diagnostics ---------------------------------------------------------
# The step runs without the GIL, possibly on several threads of a free-threaded
# interpreter; flags are per thread so a thread reads back what its own call did.
cdef extern from *:
    """
    #if defined(_MSC_VER)
    #define TAMIAS_TLS __declspec(thread)
    #else
    #define TAMIAS_TLS __thread
    #endif
    static TAMIAS_TLS unsigned int tamias_collision_flags = 0;
    static TAMIAS_TLS int tamias_collision_gjk_iter = 0;
    static TAMIAS_TLS int tamias_collision_epa_iter = 0;
    """
    unsigned int tamias_collision_flags
    int tamias_collision_gjk_iter
    int tamias_collision_epa_iter

cdef inline void flag_gjk(int iteration) noexcept nogil:
    global tamias_collision_flags, tamias_collision_gjk_iter
    tamias_collision_flags |= CP_COLLISION_FLAG_GJK_WARN
    if iteration > tamias_collision_gjk_iter:
        tamias_collision_gjk_iter = iteration

cdef inline void flag_epa(int iteration) noexcept nogil:
    global tamias_collision_flags, tamias_collision_epa_iter
    tamias_collision_flags |= CP_COLLISION_FLAG_EPA_WARN
    if iteration > tamias_collision_epa_iter:
        tamias_collision_epa_iter = iteration

cdef unsigned int cpCollisionTakeFlags() noexcept nogil:
    global tamias_collision_flags
    cdef unsigned int flags = tamias_collision_flags
    tamias_collision_flags = 0
    return flags

cdef unsigned int cpCollisionPeekFlags() noexcept nogil:
    return tamias_collision_flags

cdef CollisionDiagnostics cpCollisionTakeDiagnostics() noexcept nogil:
    global tamias_collision_flags, tamias_collision_gjk_iter, tamias_collision_epa_iter
    cdef CollisionDiagnostics d
    d.flags = tamias_collision_flags
    d.gjk_iter = tamias_collision_gjk_iter
    d.epa_iter = tamias_collision_epa_iter
    tamias_collision_flags = 0
    tamias_collision_gjk_iter = 0
    tamias_collision_epa_iter = 0
    return d

cdef void cpCollisionPutDiagnostics(CollisionDiagnostics d) noexcept nogil:
    global tamias_collision_flags, tamias_collision_gjk_iter, tamias_collision_epa_iter
    tamias_collision_flags |= d.flags
    if d.gjk_iter > tamias_collision_gjk_iter:
        tamias_collision_gjk_iter = d.gjk_iter
    if d.epa_iter > tamias_collision_epa_iter:
        tamias_collision_epa_iter = d.epa_iter

cdef int collision_check_flags() except -1:
    global tamias_collision_gjk_iter, tamias_collision_epa_iter
    cdef unsigned int flags = cpCollisionTakeFlags()
    cdef int gjk_iter = tamias_collision_gjk_iter
    cdef int epa_iter = tamias_collision_epa_iter
    if flags == 0:
        return 0
    tamias_collision_gjk_iter = 0
    tamias_collision_epa_iter = 0
    if flags & CP_COLLISION_FLAG_GJK_WARN:
        warnings.warn("High GJK iterations: %d" % gjk_iter, HighIterWarning, stacklevel=1)
    if flags & CP_COLLISION_FLAG_EPA_WARN:
        warnings.warn("High EPA iterations: %d" % epa_iter, HighIterWarning, stacklevel=1)
    if flags & CP_COLLISION_FLAG_UNSORTED:
        raise CollisionError()
    if flags & CP_COLLISION_FLAG_OVERFLOW:
        raise CollisionContactOverflow()
    return 0

# -- contacts ----------------------------------------------------------------------------

cdef inline void cpCollisionInfoPushContact(cpCollisionInfo *info, cpVect p1, cpVect p2,
                                            cpHashValue hash) noexcept nogil:
    global tamias_collision_flags
    cdef cpContact *con
    # Munk2D's check is compiled out in pymunk; here an overflow is refused
    # (it would write past the caller's array) and reported.
    if info.count >= CP_MAX_CONTACTS_PER_ARBITER:
        tamias_collision_flags |= CP_COLLISION_FLAG_OVERFLOW
        return
    con = &info.arr[info.count]
    con.r1 = p1
    con.r2 = p2
    con.hash = hash
    info.count += 1

# -- support points (the farthest point of a shape along an axis) ---------------------

cdef struct SupportPoint:
    cpVect p
    cpCollisionID index      # feature index, cached for next frame's GJK start

ctypedef SupportPoint (*SupportPointFunc)(const cpShape *shape, const cpVect n) noexcept nogil

cdef inline int PolySupportPointIndex(const int count, const cpSplittingPlane *planes,
                                      const cpVect n) noexcept nogil:
    cdef cpFloat max = -INFINITY
    cdef int index = 0
    cdef int i
    cdef cpFloat d
    for i in range(count):
        d = cpvdot(planes[i].v0, n)
        if d > max:
            max = d
            index = i
    return index

cdef inline SupportPoint SupportPointNew(cpVect p, cpCollisionID index) noexcept nogil:
    cdef SupportPoint point
    point.p = p
    point.index = index
    return point

cdef SupportPoint CircleSupportPoint(const cpShape *shape, const cpVect n) noexcept nogil:
    return SupportPointNew((<const cpCircleShape *>shape).tc, 0)

cdef SupportPoint SegmentSupportPoint(const cpShape *shape, const cpVect n) noexcept nogil:
    cdef const cpSegmentShape *seg = <const cpSegmentShape *>shape
    if cpvdot(seg.ta, n) > cpvdot(seg.tb, n):
        return SupportPointNew(seg.ta, 0)
    return SupportPointNew(seg.tb, 1)

cdef SupportPoint PolySupportPoint(const cpShape *shape, const cpVect n) noexcept nogil:
    cdef const cpPolyShape *poly = <const cpPolyShape *>shape
    cdef int i = PolySupportPointIndex(poly.count, poly.planes, n)
    return SupportPointNew(poly.planes[i].v0, i)

# A point of the Minkowski difference shape2 - shape1, with the two support
# points it came from and their indices packed into one id.
cdef struct MinkowskiPoint:
    cpVect a
    cpVect b
    cpVect ab
    cpCollisionID id

cdef inline MinkowskiPoint MinkowskiPointNew(const SupportPoint a, const SupportPoint b) noexcept nogil:
    cdef MinkowskiPoint point
    point.a = a.p
    point.b = b.p
    point.ab = cpvsub(b.p, a.p)
    point.id = (a.index & 0xFF) << 8 | (b.index & 0xFF)
    return point

cdef struct SupportContext:
    const cpShape *shape1
    const cpShape *shape2
    SupportPointFunc func1
    SupportPointFunc func2

# Support of the Minkowski difference along n: shape1 along -n, shape2 along n.
cdef inline MinkowskiPoint Support(const SupportContext *ctx, const cpVect n) noexcept nogil:
    cdef SupportPoint a = ctx.func1(ctx.shape1, cpvneg(n))
    cdef SupportPoint b = ctx.func2(ctx.shape2, n)
    return MinkowskiPointNew(a, b)

# -- support edges (the edge of a segment or polygon facing a direction) ------------------

cdef struct EdgePoint:
    cpVect p
    cpHashValue hash         # contact feature hash for warm starting

cdef struct Edge:
    EdgePoint a
    EdgePoint b
    cpFloat r
    cpVect n

cdef inline Edge EdgeNew(cpVect pa, cpHashValue ha, cpVect pb, cpHashValue hb, cpFloat r,
                         cpVect n) noexcept nogil:
    cdef Edge edge
    edge.a.p = pa
    edge.a.hash = ha
    edge.b.p = pb
    edge.b.hash = hb
    edge.r = r
    edge.n = n
    return edge

cdef Edge SupportEdgeForPoly(const cpPolyShape *poly, const cpVect n) noexcept nogil:
    if poly.count == 4:
        # A quadrilateral (a box): the same with the count known, which the
        # compiler unrolls (and its modulo becomes a mask).
        return SupportEdgeForPolyOf(poly, 4, n)
    return SupportEdgeForPolyOf(poly, poly.count, n)

cdef inline Edge SupportEdgeForPolyOf(const cpPolyShape *poly, const int count,
                                      const cpVect n) noexcept nogil:
    cdef int i1 = PolySupportPointIndex(count, poly.planes, n)
    cdef int i0 = (i1 - 1 + count) % count
    cdef int i2 = (i1 + 1) % count
    cdef const cpSplittingPlane *planes = poly.planes
    cdef cpHashValue hashid = poly.shape.hashid
    # Of the two edges meeting at the support vertex, take the one whose normal
    # is closer to n; a tie goes to the following edge.
    if cpvdot(n, planes[i1].n) > cpvdot(n, planes[i2].n):
        return EdgeNew(planes[i0].v0, CP_HASH_PAIR(hashid, <cpHashValue>i0),
                       planes[i1].v0, CP_HASH_PAIR(hashid, <cpHashValue>i1),
                       poly.r, planes[i1].n)
    return EdgeNew(planes[i1].v0, CP_HASH_PAIR(hashid, <cpHashValue>i1),
                   planes[i2].v0, CP_HASH_PAIR(hashid, <cpHashValue>i2),
                   poly.r, planes[i2].n)

cdef Edge SupportEdgeForSegment(const cpSegmentShape *seg, const cpVect n) noexcept nogil:
    cdef cpHashValue hashid = seg.shape.hashid
    if cpvdot(seg.tn, n) > 0.0:
        return EdgeNew(seg.ta, CP_HASH_PAIR(hashid, 0), seg.tb, CP_HASH_PAIR(hashid, 1),
                       seg.r, seg.tn)
    return EdgeNew(seg.tb, CP_HASH_PAIR(hashid, 1), seg.ta, CP_HASH_PAIR(hashid, 0),
                   seg.r, cpvneg(seg.tn))

# -- closest points on a Minkowski edge ---------------------------------------------------

# Parameter t in [-1, 1] of the point of a*(1-t)/2 + b*(1+t)/2 nearest the
# origin. Munk2D tests the squared length for exactly zero (no DBL_MIN guard).
cdef inline cpFloat ClosestT(const cpVect a, const cpVect b) noexcept nogil:
    cdef cpVect delta = cpvsub(b, a)
    cdef cpFloat d2 = cpvlengthsq(delta)
    if d2 != 0.0:
        return -cpfclamp(cpvdot(delta, cpvadd(a, b)) / d2, -1.0, 1.0)
    return 0.0

# cpvlerp with t measured over [-1, 1].
cdef inline cpVect LerpT(const cpVect a, const cpVect b, const cpFloat t) noexcept nogil:
    cdef cpFloat ht = 0.5 * t
    return cpvadd(cpvmult(a, 0.5 - ht), cpvmult(b, 0.5 + ht))

cdef struct ClosestPoints:
    cpVect a                 # surface point on shape 1 (absolute)
    cpVect b                 # surface point on shape 2 (absolute)
    cpVect n                 # minimum separating axis
    cpFloat d                # signed distance
    cpCollisionID id         # both Minkowski ids, for the next GJK start

cdef inline ClosestPoints ClosestPointsMake(cpVect a, cpVect b, cpVect n, cpFloat d,
                                            cpCollisionID id) noexcept nogil:
    cdef ClosestPoints points
    points.a = a
    points.b = b
    points.n = n
    points.d = d
    points.id = id
    return points

cdef inline ClosestPoints ClosestPointsNew(const MinkowskiPoint v0, const MinkowskiPoint v1) noexcept nogil:
    cdef cpFloat t = ClosestT(v0.ab, v1.ab)
    cdef cpVect p = LerpT(v0.ab, v1.ab, t)
    # The same t on the original support points gives the surface points.
    cdef cpVect pa = LerpT(v0.a, v1.a, t)
    cdef cpVect pb = LerpT(v0.b, v1.b, t)
    cdef cpCollisionID id = (v0.id & 0xFFFF) << 16 | (v1.id & 0xFFFF)
    cdef cpVect delta = cpvsub(v1.ab, v0.ab)
    cdef cpVect n = cpvnormalize(cpvrperp(delta))
    cdef cpFloat d = cpvdot(n, p)
    cdef cpFloat d2
    if d <= 0.0 or (-1.0 < t and t < 1.0):
        return ClosestPointsMake(pa, pb, n, d, id)
    # Vertex against vertex: the axis is the direction between the two points,
    # not an edge normal of the difference.
    d2 = cpvlength(p)
    return ClosestPointsMake(pa, pb, cpvmult(p, 1.0 / (d2 + DBL_MIN)), d2, id)

cdef inline cpFloat ClosestDist(const cpVect v0, const cpVect v1) noexcept nogil:
    return cpvlengthsq(LerpT(v0, v1, ClosestT(v0, v1)))

# -- robust predicates (cpRobust.c) --------------------------------------------------------

cdef inline cpBool cpCheckPointGreater(const cpVect a, const cpVect b, const cpVect c) noexcept nogil:
    return (b.y - a.y) * (a.x + b.x - 2 * c.x) > (b.x - a.x) * (a.y + b.y - 2 * c.y)

cdef inline cpBool cpCheckAxis(cpVect v0, cpVect v1, cpVect p, cpVect n) noexcept nogil:
    return cpvdot(p, n) <= cpfmax(cpvdot(v0, n), cpvdot(v1, n))

# -- EPA -------------------------------------------------------------------------------------

# Room for EPA's hull: 3 points, then at most one more per iteration.
cdef enum:
    EPA_HULL_CAPACITY = 64

# Munk2D recurses once per added hull point; this loop does the same steps
# with two alternating stack buffers (the hull grows by at most one point).
cdef ClosestPoints EPARecurse(const SupportContext *ctx, int count, const MinkowskiPoint *start,
                              int iteration) noexcept nogil:
    global tamias_collision_flags
    cdef MinkowskiPoint buf1[EPA_HULL_CAPACITY]
    cdef MinkowskiPoint buf2[EPA_HULL_CAPACITY]
    cdef MinkowskiPoint *hull = buf1
    cdef MinkowskiPoint *hull2 = buf2
    cdef MinkowskiPoint *swap
    cdef MinkowskiPoint v0, v1, p
    cdef int mini, i, j, count2, index
    cdef cpFloat minDist, d
    cdef cpVect h0, h1, h2
    cdef cpBool duplicate
    for i in range(count):
        hull[i] = start[i]
    while True:
        # The hull edge hull[i] - hull[i + 1] nearest the origin.
        mini = 0
        minDist = INFINITY
        i = count - 1
        for j in range(count):
            d = ClosestDist(hull[i].ab, hull[j].ab)
            if d < minDist:
                minDist = d
                mini = i
            i = j
        v0 = hull[mini]
        v1 = hull[(mini + 1) % count]
        if cpveql(v0.ab, v1.ab):
            # Munk2D's soft assert (compiled out in pymunk): go on, but record it.
            tamias_collision_flags |= CP_COLLISION_FLAG_SAME_VERTICES
        # Is there a point of the difference beyond that edge?
        p = Support(ctx, cpvperp(cpvsub(v1.ab, v0.ab)))
        # Usually the search ends on a point already in the hull; ids are a
        # cheap way to notice.
        duplicate = p.id == v0.id or p.id == v1.id
        if not duplicate and cpCheckPointGreater(v0.ab, v1.ab, p.ab) and iteration < MAX_EPA_ITERATIONS:
            # Rebuild the convex hull starting from p.
            count2 = 1
            hull2[0] = p
            for i in range(count):
                index = (mini + 1 + i) % count
                h0 = hull2[count2 - 1].ab
                h1 = hull[index].ab
                h2 = hull[(index + 1) % count].ab if i + 1 < count else p.ab
                if cpCheckPointGreater(h0, h2, h1):
                    hull2[count2] = hull[index]
                    count2 += 1
            swap = hull
            hull = hull2
            hull2 = swap
            count = count2
            iteration += 1
        else:
            # No point beyond it: this edge is the closest one of the difference.
            if not (iteration < WARN_EPA_ITERATIONS):
                flag_epa(iteration)
            return ClosestPointsNew(v0, v1)

# Closest points of two overlapping shapes, from the GJK triangle.
cdef ClosestPoints EPA(const SupportContext *ctx, const MinkowskiPoint v0, const MinkowskiPoint v1,
                       const MinkowskiPoint v2) noexcept nogil:
    cdef MinkowskiPoint hull[3]
    hull[0] = v0
    hull[1] = v1
    hull[2] = v2
    return EPARecurse(ctx, 3, hull, 1)

# -- GJK -------------------------------------------------------------------------------------

# Munk2D's tail recursion as a loop; `iteration` counts exactly as there (the
# flip of an edge whose far side holds the origin is not an iteration).
cdef ClosestPoints GJKRecurse(const SupportContext *ctx, MinkowskiPoint v0, MinkowskiPoint v1,
                              int iteration) noexcept nogil:
    cdef MinkowskiPoint p, tmp
    cdef cpFloat t
    cdef cpVect n
    cdef cpVect zero = cpv(0.0, 0.0)
    while True:
        if iteration > MAX_GJK_ITERATIONS:
            if not (iteration < WARN_GJK_ITERATIONS):
                flag_gjk(iteration)
            return ClosestPointsNew(v0, v1)
        if cpCheckPointGreater(v1.ab, v0.ab, zero):
            # The origin is behind the edge: flip it and look again.
            tmp = v0
            v0 = v1
            v1 = tmp
            continue
        t = ClosestT(v0.ab, v1.ab)
        if -1.0 < t and t < 1.0:
            n = cpvperp(cpvsub(v1.ab, v0.ab))
        else:
            n = cpvneg(LerpT(v0.ab, v1.ab, t))
        p = Support(ctx, n)
        if cpCheckPointGreater(p.ab, v0.ab, zero) and cpCheckPointGreater(v1.ab, p.ab, zero):
            # The triangle v0, p, v1 holds the origin: the shapes overlap.
            if not (iteration < WARN_GJK_ITERATIONS):
                flag_gjk(iteration)
            return EPA(ctx, v0, p, v1)
        if cpCheckAxis(v0.ab, v1.ab, p.ab, n):
            # p is no closer than the edge we have: that edge is the answer.
            if not (iteration < WARN_GJK_ITERATIONS):
                flag_gjk(iteration)
            return ClosestPointsNew(v0, v1)
        # Keep p and the old point whose edge with p is nearer the origin.
        if ClosestDist(v0.ab, p.ab) < ClosestDist(p.ab, v1.ab):
            v1 = p
        else:
            v0 = p
        iteration += 1

# Support point of a shape by cached feature index.
cdef SupportPoint ShapePoint(const cpShape *shape, const int i) noexcept nogil:
    cdef cpShapeType kind = shape.klass.type
    cdef const cpSegmentShape *seg
    cdef const cpPolyShape *poly
    cdef int index
    if kind == CP_CIRCLE_SHAPE:
        return SupportPointNew((<const cpCircleShape *>shape).tc, 0)
    elif kind == CP_SEGMENT_SHAPE:
        seg = <const cpSegmentShape *>shape
        return SupportPointNew(seg.ta if i == 0 else seg.tb, i)
    elif kind == CP_POLY_SHAPE:
        poly = <const cpPolyShape *>shape
        # The vertex count may have changed since the id was cached.
        index = i if i < poly.count else 0
        return SupportPointNew(poly.planes[index].v0, index)
    return SupportPointNew(cpv(0.0, 0.0), 0)

cdef ClosestPoints GJK(const SupportContext *ctx, cpCollisionID *id) noexcept nogil:
    cdef MinkowskiPoint v0, v1
    cdef cpVect axis
    cdef ClosestPoints points
    if id[0]:
        # Start from last frame's Minkowski points (four byte-sized indices).
        v0 = MinkowskiPointNew(ShapePoint(ctx.shape1, (id[0] >> 24) & 0xFF),
                               ShapePoint(ctx.shape2, (id[0] >> 16) & 0xFF))
        v1 = MinkowskiPointNew(ShapePoint(ctx.shape1, (id[0] >> 8) & 0xFF),
                               ShapePoint(ctx.shape2, id[0] & 0xFF))
    else:
        # No cache: the line between the bounding box centres is a fair first guess.
        axis = cpvperp(cpvsub(cpBBCenter(ctx.shape1.bb), cpBBCenter(ctx.shape2.bb)))
        v0 = Support(ctx, axis)
        v1 = Support(ctx, cpvneg(axis))
    points = GJKRecurse(ctx, v0, v1, 1)
    id[0] = points.id
    return points

# -- contact clipping --------------------------------------------------------------------------

# Clip the two support edges against each other along the normal: up to two
# contacts, (1a-2b) first, then (1b-2a), each kept only where they overlap.
cdef inline void ContactPoints(const Edge e1, const Edge e2, const ClosestPoints points,
                               cpCollisionInfo *info) noexcept nogil:
    cdef cpFloat mindist = e1.r + e2.r
    cdef cpFloat margin = info.margin
    cdef cpVect n, p1, p2
    cdef cpFloat d_e1_a, d_e1_b, d_e2_a, d_e2_b, e1_denom, e2_denom, dist
    if points.d <= mindist + margin:
        n = points.n
        info.n = n
        # Positions across the normal.
        d_e1_a = cpvcross(e1.a.p, n)
        d_e1_b = cpvcross(e1.b.p, n)
        d_e2_a = cpvcross(e2.a.p, n)
        d_e2_b = cpvcross(e2.b.p, n)
        # DBL_MIN keeps a zero-length projection finite (as Munk2D; not a full fix).
        e1_denom = 1.0 / (d_e1_b - d_e1_a + DBL_MIN)
        e2_denom = 1.0 / (d_e2_b - d_e2_a + DBL_MIN)

        p1 = cpvadd(cpvmult(n, e1.r), cpvlerp(e1.a.p, e1.b.p, cpfclamp01((d_e2_b - d_e1_a) * e1_denom)))
        p2 = cpvadd(cpvmult(n, -e2.r), cpvlerp(e2.a.p, e2.b.p, cpfclamp01((d_e1_a - d_e2_a) * e2_denom)))
        dist = cpvdot(cpvsub(p2, p1), n)
        if dist <= margin:
            cpCollisionInfoPushContact(info, p1, p2, CP_HASH_PAIR(e1.a.hash, e2.b.hash))

        p1 = cpvadd(cpvmult(n, e1.r), cpvlerp(e1.a.p, e1.b.p, cpfclamp01((d_e2_a - d_e1_a) * e1_denom)))
        p2 = cpvadd(cpvmult(n, -e2.r), cpvlerp(e2.a.p, e2.b.p, cpfclamp01((d_e1_b - d_e2_a) * e2_denom)))
        dist = cpvdot(cpvsub(p2, p1), n)
        if dist <= margin:
            cpCollisionInfoPushContact(info, p1, p2, CP_HASH_PAIR(e1.b.hash, e2.a.hash))

# -- collision functions ------------------------------------------------------------------------

cdef inline cpVect body_rotation(const cpShape *shape) noexcept nogil:
    # cpBodyGetRotation, or no rotation for a shape without a body.
    if shape.body != NULL:
        return cpv(shape.body.transform.a, shape.body.transform.b)
    return cpv(1.0, 0.0)

cdef void CircleToCircle(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil:
    cdef const cpCircleShape *c1 = <const cpCircleShape *>a
    cdef const cpCircleShape *c2 = <const cpCircleShape *>b
    # + margin: exact for the chipmunk solver's 0, so its bits are Munk2D's.
    cdef cpFloat mindist = c1.r + c2.r + info.margin
    cdef cpVect delta = cpvsub(c2.tc, c1.tc)
    cdef cpFloat distsq = cpvlengthsq(delta)
    cdef cpFloat dist
    cdef cpVect n
    if distsq < mindist * mindist:
        dist = sqrt(distsq)
        # Coincident centres: any direction will do, Munk2D picks +x.
        n = cpvmult(delta, 1.0 / dist) if dist != 0.0 else cpv(1.0, 0.0)
        info.n = n
        cpCollisionInfoPushContact(info, cpvadd(c1.tc, cpvmult(n, c1.r)),
                                   cpvadd(c2.tc, cpvmult(n, -c2.r)), 0)

cdef void CircleToSegment(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil:
    cdef const cpCircleShape *circle = <const cpCircleShape *>a
    cdef const cpSegmentShape *segment = <const cpSegmentShape *>b
    cdef cpVect seg_a = segment.ta
    cdef cpVect seg_b = segment.tb
    cdef cpVect center = circle.tc
    # Closest point of the segment to the circle's centre.
    cdef cpVect seg_delta = cpvsub(seg_b, seg_a)
    cdef cpFloat closest_t = cpfclamp01(cpvdot(seg_delta, cpvsub(center, seg_a)) / cpvlengthsq(seg_delta))
    cdef cpVect closest = cpvadd(seg_a, cpvmult(seg_delta, closest_t))
    cdef cpFloat mindist = circle.r + segment.r + info.margin
    cdef cpVect delta = cpvsub(closest, center)
    cdef cpFloat distsq = cpvlengthsq(delta)
    cdef cpFloat dist
    cdef cpVect n, rot
    if distsq < mindist * mindist:
        dist = sqrt(distsq)
        # Coincident: fall back to the segment's normal.
        n = cpvmult(delta, 1.0 / dist) if dist != 0.0 else segment.tn
        info.n = n
        # An end-cap contact is dropped when a neighbour's tangent says the
        # chain of segments continues that way.
        rot = body_rotation(&segment.shape)
        if ((closest_t != 0.0 or cpvdot(n, cpvrotate(segment.a_tangent, rot)) >= 0.0) and
                (closest_t != 1.0 or cpvdot(n, cpvrotate(segment.b_tangent, rot)) >= 0.0)):
            cpCollisionInfoPushContact(info, cpvadd(center, cpvmult(n, circle.r)),
                                       cpvadd(closest, cpvmult(n, -segment.r)), 0)

cdef void SegmentToSegment(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil:
    cdef const cpSegmentShape *seg1 = <const cpSegmentShape *>a
    cdef const cpSegmentShape *seg2 = <const cpSegmentShape *>b
    cdef SupportContext context
    context.shape1 = a
    context.shape2 = b
    context.func1 = SegmentSupportPoint
    context.func2 = SegmentSupportPoint
    cdef ClosestPoints points = GJK(&context, &info.id)
    cdef cpVect n = points.n
    cdef cpVect rot1 = body_rotation(a)
    cdef cpVect rot2 = body_rotation(b)
    if (points.d <= (seg1.r + seg2.r) + info.margin and (
            (not cpveql(points.a, seg1.ta) or cpvdot(n, cpvrotate(seg1.a_tangent, rot1)) <= 0.0) and
            (not cpveql(points.a, seg1.tb) or cpvdot(n, cpvrotate(seg1.b_tangent, rot1)) <= 0.0) and
            (not cpveql(points.b, seg2.ta) or cpvdot(n, cpvrotate(seg2.a_tangent, rot2)) >= 0.0) and
            (not cpveql(points.b, seg2.tb) or cpvdot(n, cpvrotate(seg2.b_tangent, rot2)) >= 0.0))):
        ContactPoints(SupportEdgeForSegment(seg1, n), SupportEdgeForSegment(seg2, cpvneg(n)), points, info)

cdef void PolyToPoly(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil:
    cdef const cpPolyShape *poly1 = <const cpPolyShape *>a
    cdef const cpPolyShape *poly2 = <const cpPolyShape *>b
    cdef SupportContext context
    context.shape1 = a
    context.shape2 = b
    context.func1 = PolySupportPoint
    context.func2 = PolySupportPoint
    cdef ClosestPoints points = GJK(&context, &info.id)
    if points.d - poly1.r - poly2.r <= info.margin:
        ContactPoints(SupportEdgeForPoly(poly1, points.n), SupportEdgeForPoly(poly2, cpvneg(points.n)),
                      points, info)

cdef void SegmentToPoly(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil:
    cdef const cpSegmentShape *seg = <const cpSegmentShape *>a
    cdef const cpPolyShape *poly = <const cpPolyShape *>b
    cdef SupportContext context
    context.shape1 = a
    context.shape2 = b
    context.func1 = SegmentSupportPoint
    context.func2 = PolySupportPoint
    cdef ClosestPoints points = GJK(&context, &info.id)
    cdef cpVect n = points.n
    cdef cpVect rot = body_rotation(a)
    if (points.d - seg.r - poly.r <= info.margin and (
            (not cpveql(points.a, seg.ta) or cpvdot(n, cpvrotate(seg.a_tangent, rot)) <= 0.0) and
            (not cpveql(points.a, seg.tb) or cpvdot(n, cpvrotate(seg.b_tangent, rot)) <= 0.0))):
        ContactPoints(SupportEdgeForSegment(seg, n), SupportEdgeForPoly(poly, cpvneg(n)), points, info)

cdef void CircleToPoly(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil:
    cdef const cpCircleShape *circle = <const cpCircleShape *>a
    cdef const cpPolyShape *poly = <const cpPolyShape *>b
    cdef SupportContext context
    context.shape1 = a
    context.shape2 = b
    context.func1 = CircleSupportPoint
    context.func2 = PolySupportPoint
    cdef ClosestPoints points = GJK(&context, &info.id)
    cdef cpVect n
    if points.d <= circle.r + poly.r + info.margin:
        n = points.n
        info.n = n
        cpCollisionInfoPushContact(info, cpvadd(points.a, cpvmult(n, circle.r)),
                                   cpvadd(points.b, cpvmult(n, -poly.r)), 0)

# -- the soft solver's polygon pairs: separating axes ---------------------------------------
# Where two polygons' cores (their vertices, radius aside) overlap, the axis
# of least penetration is a face normal of one of them: what EPA converges
# to, found here with count1*count2 dot products and no iterations (Box2D's
# polygon collider does the same for overlapping cores). Cores apart by more
# than the margin along a face normal have no contact; closer, they go to
# GJK as before, since their closest features may be two corners, which no
# face normal describes. Not Munk2D's, so not the chipmunk solver's.

# Up to two octagons; beyond, GJK's few support searches cost less.
cdef enum:
    SEPARATING_AXES_MAX_WORK = 64

cdef inline cpFloat PolyFaceSeparationOf(const cpPolyShape *ref, const cpPolyShape *inc,
                                         int refCount, int incCount, cpFloat stop,
                                         int *face) noexcept nogil:
    # The face of `ref` along whose normal `inc` reaches least far in, and how
    # far out that is (negative: overlap). Stops at the first beyond `stop`.
    cdef cpFloat best = -INFINITY
    cdef cpFloat reach, x, sep
    cdef cpVect n
    cdef int i, j
    face[0] = 0
    for i in range(refCount):
        n = ref.planes[i].n
        reach = INFINITY
        for j in range(incCount):
            x = cpvdot(n, inc.planes[j].v0)
            if x < reach:
                reach = x
        sep = reach - cpvdot(n, ref.planes[i].v0)
        if sep > best:
            best = sep
            face[0] = i
            if sep > stop:
                break
    return best

cdef inline cpFloat PolyFaceSeparation(const cpPolyShape *ref, const cpPolyShape *inc,
                                       cpFloat stop, int *face) noexcept nogil:
    if ref.count == 4 and inc.count == 4:
        # Two quadrilaterals (boxes, the commonest pair): the same loops with
        # their lengths known, which the compiler unrolls.
        return PolyFaceSeparationOf(ref, inc, 4, 4, stop, face)
    return PolyFaceSeparationOf(ref, inc, ref.count, inc.count, stop, face)

cdef inline void PolyContactsAlong(const cpPolyShape *poly1, const cpPolyShape *poly2,
                                   const cpVect n, const cpFloat d,
                                   cpCollisionInfo *info) noexcept nogil:
    # The contacts of two polygons whose cores are d apart along n (from
    # poly1 to poly2): ContactPoints reads only the normal and the distance.
    cdef ClosestPoints points
    points.n = n
    points.d = d
    points.a = cpv(0.0, 0.0)
    points.b = cpv(0.0, 0.0)
    points.id = info.id
    ContactPoints(SupportEdgeForPoly(poly1, n), SupportEdgeForPoly(poly2, cpvneg(n)), points, info)

cdef inline int PolyIncidentFace(const cpPolyShape *poly, const cpVect n) noexcept nogil:
    # The face of `poly` whose normal points most against n.
    cdef int i, face = 0
    cdef cpFloat d, least = INFINITY
    for i in range(poly.count):
        d = cpvdot(n, poly.planes[i].n)
        if d < least:
            least = d
            face = i
    return face

cdef inline cpVect ClosestOnSegment(const cpVect p, const cpVect a, const cpVect b,
                                    bint *atEnd) noexcept nogil:
    # The point of segment ab nearest p, and whether it is an end (what
    # cpClosetPointOnSegment does not tell).
    cdef cpVect ab = cpvsub(b, a)
    cdef cpFloat len2 = cpvlengthsq(ab)
    cdef cpFloat t = cpvdot(cpvsub(p, a), ab) / len2 if len2 > 0.0 else 0.0
    atEnd[0] = t <= 0.0 or t >= 1.0
    return cpvadd(a, cpvmult(ab, cpfclamp01(t)))

cdef void PolyToPolyApart(const cpPolyShape *poly1, const cpPolyShape *poly2,
                          cpFloat sep1, int face1, cpFloat sep2, int face2,
                          cpCollisionInfo *info) noexcept nogil:
    # Cores apart but within the margin (a speculative contact). The nearest
    # features are on the reference face (the one that separates most) and
    # the other polygon's face most against it (Box2D's polygon collider
    # finds them the same way): if both nearest points are corners, the
    # normal runs corner to corner, else it is the reference face's. Then
    # the contacts as for any normal. No GJK iterations.
    cdef const cpPolyShape *ref = poly1
    cdef const cpPolyShape *inc = poly2
    cdef int refFace = face1
    cdef int incFace, k
    cdef cpFloat sep = sep1
    cdef cpFloat sign = 1.0
    cdef cpFloat best = INFINITY
    cdef cpFloat d2
    cdef cpVect ends[4]
    cdef cpVect onRef, onInc, nearRef, nearInc, n
    cdef cpFloat d
    cdef bint corner = 0
    cdef bint atEnd
    if sep2 > sep1:
        ref = poly2
        inc = poly1
        refFace = face2
        sep = sep2
        sign = -1.0       # the normal points from poly1 to poly2
    incFace = PolyIncidentFace(inc, ref.planes[refFace].n)
    ends[0] = ref.planes[(refFace - 1 + ref.count) % ref.count].v0
    ends[1] = ref.planes[refFace].v0
    ends[2] = inc.planes[(incFace - 1 + inc.count) % inc.count].v0
    ends[3] = inc.planes[incFace].v0
    # The segments do not cross (the cores are apart): the nearest pair has
    # an end of one of them. Ties go to the first found.
    for k in range(4):
        if k < 2:
            onRef = ends[k]
            onInc = ClosestOnSegment(onRef, ends[2], ends[3], &atEnd)
        else:
            onInc = ends[k]
            onRef = ClosestOnSegment(onInc, ends[0], ends[1], &atEnd)
        d2 = cpvlengthsq(cpvsub(onInc, onRef))
        if d2 < best:
            best = d2
            corner = atEnd
            nearRef = onRef
            nearInc = onInc
    d = sqrt(best)
    n = ref.planes[refFace].n
    # Corner to corner, and farther than the face's separation (else the
    # face normal is as good, and safe to use when the corners nearly touch).
    if corner and d > sep * (1.0 + 1e-9):
        n = cpvmult(cpvsub(nearInc, nearRef), 1.0 / d)
    PolyContactsAlong(poly1, poly2, cpvmult(n, sign), d, info)

cdef void PolyToPolySeparatingAxes(const cpShape *a, const cpShape *b,
                                   cpCollisionInfo *info) noexcept nogil:
    cdef const cpPolyShape *poly1 = <const cpPolyShape *>a
    cdef const cpPolyShape *poly2 = <const cpPolyShape *>b
    cdef int face1, face2
    cdef cpFloat sep1, sep2
    # Apart by more than this along any axis: no contact within the margin
    # (the distance is at least any axis's separation).
    cdef cpFloat reach = info.margin + poly1.r + poly2.r
    if (poly1.count < 3 or poly2.count < 3
            or poly1.count * poly2.count > SEPARATING_AXES_MAX_WORK):
        # Degenerate polygons have no faces to test; big ones are GJK's.
        PolyToPoly(a, b, info)
        return
    sep1 = PolyFaceSeparation(poly1, poly2, reach, &face1)
    if sep1 > reach:
        return
    sep2 = PolyFaceSeparation(poly2, poly1, reach, &face2)
    if sep2 > reach:
        return
    if sep1 > 0.0 or sep2 > 0.0:
        PolyToPolyApart(poly1, poly2, sep1, face1, sep2, face2, info)
        return
    # The shallower of the two (a tie to poly1's face); the normal points
    # from poly1 to poly2 either way. Only n and d are read by the clipping.
    if sep2 > sep1:
        PolyContactsAlong(poly1, poly2, cpvneg(poly2.planes[face2].n), sep2, info)
    else:
        PolyContactsAlong(poly1, poly2, poly1.planes[face1].n, sep1, info)

# The soft solver's circle-polygon pairs: where the circle's centre is
# inside the polygon's core, the face it is least deep behind gives the
# normal (what EPA converges to for a point, with no iterations; Box2D's
# circle-polygon collider does the same). GJK/EPA finds no normal for a
# centre exactly at the polygon's (a circle created inside a box), so no
# impulse could part them. A centre outside the core goes to GJK as before.
cdef void CircleToPolyFaces(const cpShape *a, const cpShape *b,
                            cpCollisionInfo *info) noexcept nogil:
    cdef const cpCircleShape *circle = <const cpCircleShape *>a
    cdef const cpPolyShape *poly = <const cpPolyShape *>b
    cdef cpVect center = circle.tc
    cdef cpFloat best = -INFINITY
    cdef cpFloat sep
    cdef cpVect n, inner
    cdef int i, face = 0
    if poly.count < 3:
        CircleToPoly(a, b, info)
        return
    for i in range(poly.count):
        sep = cpvdot(poly.planes[i].n, cpvsub(center, poly.planes[i].v0))
        if sep > best:
            best = sep
            face = i
    if best > 0.0:
        CircleToPoly(a, b, info)
        return
    # From the circle to the polygon: against the face's outward normal.
    n = cpvneg(poly.planes[face].n)
    info.n = n
    inner = cpvadd(center, cpvmult(n, best))  # the centre moved onto the face
    cpCollisionInfoPushContact(info, cpvadd(center, cpvmult(n, circle.r)),
                               cpvadd(inner, cpvmult(n, -poly.r)), 0)

cdef void CollisionError_(const cpShape *a, const cpShape *b, cpCollisionInfo *info) noexcept nogil:
    # Munk2D aborts the process here. The slot is reached only with unsorted
    # types; the caller raises CollisionError once back in Python.
    global tamias_collision_flags
    tamias_collision_flags |= CP_COLLISION_FLAG_UNSORTED

# Indexed by a.type + b.type*CP_NUM_SHAPES with a.type <= b.type (declared in collision.pxd).
CollisionFuncs[0] = CircleToCircle
CollisionFuncs[1] = CollisionError_
CollisionFuncs[2] = CollisionError_
CollisionFuncs[3] = CircleToSegment
CollisionFuncs[4] = SegmentToSegment
CollisionFuncs[5] = CollisionError_
CollisionFuncs[6] = CircleToPoly
CollisionFuncs[7] = SegmentToPoly
CollisionFuncs[8] = PolyToPoly

cdef cpCollisionInfo cpCollide(const cpShape *a, const cpShape *b, cpCollisionID id,
                               cpContact *contacts, cpFloat margin) noexcept nogil:
    cdef cpCollisionInfo info
    CollideInto(CollisionFuncs, a, b, id, contacts, margin, &info)
    return info

# The soft solver's table: Munk2D's, but polygon pairs by separating axes
# and circles inside polygons by their faces.
for _i in range(9):
    SoftCollisionFuncs[_i] = CollisionFuncs[_i]
SoftCollisionFuncs[6] = CircleToPolyFaces
SoftCollisionFuncs[8] = PolyToPolySeparatingAxes

cdef cpCollisionInfo cpCollideSoft(const cpShape *a, const cpShape *b, cpCollisionID id,
                                   cpContact *contacts, cpFloat margin) noexcept nogil:
    cdef cpCollisionInfo info
    CollideInto(SoftCollisionFuncs, a, b, id, contacts, margin, &info)
    return info

cdef cpContactPointSet cpShapesCollide(const cpShape *a, const cpShape *b) noexcept nogil:
    cdef cpContact contacts[CP_MAX_CONTACTS_PER_ARBITER]
    cdef cpCollisionInfo info = cpCollide(a, b, 0, contacts, 0.0)
    cdef cpContactPointSet set
    cdef cpBool swapped
    cdef cpVect p1, p2
    cdef int i
    set.count = info.count
    # cpCollide may have swapped the pair to sort the types: turn the normal back.
    swapped = a != info.a
    set.normal = cpvneg(info.n) if swapped else info.n
    for i in range(info.count):
        p1 = contacts[i].r1
        p2 = contacts[i].r2
        set.points[i].pointA = p2 if swapped else p1
        set.points[i].pointB = p1 if swapped else p2
        set.points[i].distance = cpvdot(cpvsub(p2, p1), set.normal)
    return set

# =====================================================================================
# Python layer
# =====================================================================================

cdef class ContactPoint:
    """One contact of two shapes: a point on the surface of each, and their
    signed distance along the normal (negative when they overlap).

    >>> from tamias2d import Vec2d
    >>> ContactPoint(Vec2d(1.0, 0.0), Vec2d(0.0, 0.0), -1.0)
    ContactPoint(point_a=Vec2d(1.0, 0.0), point_b=Vec2d(0.0, 0.0), distance=-1.0)
    """

    def __init__(self, point_a, point_b, distance):
        self.point_a = point_a
        self.point_b = point_b
        self.distance = distance

    def __repr__(self):
        return "ContactPoint(point_a={}, point_b={}, distance={})".format(
            self.point_a, self.point_b, self.distance)

    def __reduce__(self):
        return (ContactPoint, (self.point_a, self.point_b, self.distance))


cdef class ContactPointSet:
    """The contacts of two shapes: the collision normal (from the first shape
    towards the second) and a tuple of at most two :class:`ContactPoint`.

    >>> from tamias2d import Vec2d
    >>> p = ContactPoint(Vec2d(1.0, 0.0), Vec2d(0.0, 0.0), -1.0)
    >>> s = ContactPointSet(Vec2d(1.0, 0.0), (p,))
    >>> s.normal, len(s.points)
    (Vec2d(1.0, 0.0), 1)
    """

    def __init__(self, normal, points):
        self.normal = normal
        self.points = points

    def __repr__(self):
        return "ContactPointSet(normal={}, points={})".format(self.normal, self.points)

    def __reduce__(self):
        return (ContactPointSet, (self.normal, self.points))


cdef ContactPointSet contact_point_set_from_cp(const cpContactPointSet *cps):
    cdef ContactPointSet result = ContactPointSet.__new__(ContactPointSet)
    cdef ContactPoint point
    cdef int i
    cdef list points = []
    for i in range(cps.count):
        point = ContactPoint.__new__(ContactPoint)
        point.point_a = vec2d_from_cpv(cps.points[i].pointA)
        point.point_b = vec2d_from_cpv(cps.points[i].pointB)
        point.distance = cps.points[i].distance
        points.append(point)
    result.normal = vec2d_from_cpv(cps.normal)
    result.points = tuple(points)
    return result


cdef const cpShape *shape_pointer(object shape, str what) except NULL:
    if not isinstance(shape, Shape):
        raise TypeError("%s must be a Shape (Circle, Segment or Poly), not %s"
                        % (what, type(shape).__name__))
    cdef const cpShape *s = (<Shape>shape)._shape
    if s == NULL or s.klass == NULL:
        raise TypeError("%s is a bare Shape; use Circle, Segment or Poly" % what)
    if s.klass.type == CP_POLY_SHAPE and (<const cpPolyShape *>s).count < 1:
        raise ValueError("%s is a polygon without vertices" % what)
    return s


def shapes_collide(shape_a, shape_b):
    """Contact information of two shapes, as ``shape_a.shapes_collide(shape_b)``.

    The shapes' cached world geometry is used (as pymunk does): call
    ``cache_bb()`` on shapes that are not in a space after moving their
    bodies. The normal points from shape_a towards shape_b; each point's
    distance is negative when the shapes overlap.

    As in Munk2D and pymunk, when shape_a's type sorts after shape_b's
    (circle < segment < polygon), e.g. a polygon against a circle, each
    point's distance comes out with the opposite sign (the pair is swapped to
    collide it and only the normal is turned back).

    When the shapes do not touch, the set has no points. (pymunk 7.3 raises
    AssertionError with "This is likely a bug in Pymunk" in that case; the
    normal and points of touching shapes are the same as pymunk's, bit for
    bit.)

    >>> import tamias2d
    >>> b1, b2 = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    >>> b2.position = 10, 0
    >>> c1, c2 = tamias2d.Circle(b1, 10), tamias2d.Circle(b2, 10)
    >>> _ = c1.cache_bb(), c2.cache_bb()
    >>> s = shapes_collide(c1, c2)
    >>> s.normal, s.points[0].point_a, s.points[0].point_b, s.points[0].distance
    (Vec2d(1.0, 0.0), Vec2d(10.0, 0.0), Vec2d(0.0, 0.0), -10.0)
    """
    cdef const cpShape *a = shape_pointer(shape_a, "shape_a")
    cdef const cpShape *b = shape_pointer(shape_b, "shape_b")
    # Called with the GIL held: releasing it costs more than the call itself.
    cdef cpContactPointSet cps = cpShapesCollide(a, b)
    collision_check_flags()
    return contact_point_set_from_cp(&cps)


# -- impulse helpers on Python bodies ---------------------------------------------------------

def relative_velocity(Body body_a not None, Body body_b not None, r1, r2):
    """Velocity of body_b's point at offset r2 relative to body_a's point at
    offset r1 (offsets from each body's centre of gravity, world axes).

    >>> import tamias2d
    >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    >>> b.velocity = (2, 0)
    >>> a.angular_velocity = 1
    >>> relative_velocity(a, b, (1, 0), (0, 0))
    Vec2d(2.0, -1.0)
    """
    cdef cpVect v = c_relative_velocity(&body_a._body, &body_b._body,
                                      cpv_from_object_finite(r1, "r1"),
                                      cpv_from_object_finite(r2, "r2"))
    return vec2d_from_cpv(v)


def normal_relative_velocity(Body body_a not None, Body body_b not None, r1, r2, n):
    """The relative velocity of :func:`relative_velocity` projected on n.

    >>> import tamias2d
    >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    >>> b.velocity = (2, 3)
    >>> normal_relative_velocity(a, b, (0, 0), (0, 0), (0, 1))
    3.0
    """
    return c_normal_relative_velocity(&body_a._body, &body_b._body,
                                    cpv_from_object_finite(r1, "r1"),
                                    cpv_from_object_finite(r2, "r2"),
                                    cpv_from_object_finite(n, "n"))


def apply_impulse(Body body not None, j, r):
    """Change body's velocity and angular velocity by impulse j applied at
    offset r from its centre of gravity (world axes). The solver's raw
    update: the body is not woken and j is not checked against body type.

    >>> import tamias2d
    >>> b = tamias2d.Body(2, 4)
    >>> apply_impulse(b, (0, 4), (2, 0))
    >>> b.velocity, b.angular_velocity
    (Vec2d(0.0, 2.0), 2.0)
    """
    c_apply_impulse(&body._body, cpv_from_object_finite(j, "j"), cpv_from_object_finite(r, "r"))


def apply_impulses(Body body_a not None, Body body_b not None, r1, r2, j):
    """Apply -j to body_a at offset r1 and j to body_b at offset r2.

    >>> import tamias2d
    >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    >>> apply_impulses(a, b, (0, 0), (0, 0), (1, 0))
    >>> a.velocity, b.velocity
    (Vec2d(-1.0, 0.0), Vec2d(1.0, 0.0))
    """
    c_apply_impulses(&body_a._body, &body_b._body, cpv_from_object_finite(r1, "r1"),
                   cpv_from_object_finite(r2, "r2"), cpv_from_object_finite(j, "j"))


def apply_bias_impulse(Body body not None, j, r):
    """As :func:`apply_impulse`, on the body's bias (position correction)
    velocities, which the solver uses to push overlapping shapes apart.

    >>> import tamias2d
    >>> b = tamias2d.Body(2, 4)
    >>> apply_bias_impulse(b, (0, 4), (2, 0))
    >>> from tamias2d._testing import _bias_velocity    # (v_bias, w_bias)
    >>> _bias_velocity(b)
    (Vec2d(0.0, 2.0), 2.0)
    """
    c_apply_bias_impulse(&body._body, cpv_from_object_finite(j, "j"), cpv_from_object_finite(r, "r"))


def apply_bias_impulses(Body body_a not None, Body body_b not None, r1, r2, j):
    """As :func:`apply_impulses`, on the bias velocities.

    >>> import tamias2d
    >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    >>> apply_bias_impulses(a, b, (0, 0), (0, 0), (1, 0))
    >>> from tamias2d._testing import _bias_velocity    # (v_bias, w_bias)
    >>> _bias_velocity(a)[0], _bias_velocity(b)[0]
    (Vec2d(-1.0, 0.0), Vec2d(1.0, 0.0))
    """
    c_apply_bias_impulses(&body_a._body, &body_b._body, cpv_from_object_finite(r1, "r1"),
                        cpv_from_object_finite(r2, "r2"), cpv_from_object_finite(j, "j"))


def k_scalar_body(Body body not None, r, n):
    """One body's share of a contact's effective-mass denominator:
    1/m + cross(r, n)**2 / I.

    >>> import tamias2d
    >>> k_scalar_body(tamias2d.Body(2, 4), (1, 0), (0, 1))
    0.75
    """
    return c_k_scalar_body(&body._body, cpv_from_object_finite(r, "r"), cpv_from_object_finite(n, "n"))


def k_scalar(Body body_a not None, Body body_b not None, r1, r2, n):
    """Effective-mass denominator of a contact between two bodies along n.
    Raises UnsolvableCollision when it is zero (both bodies infinitely heavy
    along n), where the C solver would divide by zero.

    >>> import tamias2d
    >>> k_scalar(tamias2d.Body(2, 4), tamias2d.Body(1, 1), (1, 0), (0, 0), (0, 1))
    1.75
    """
    cdef cpFloat value = c_k_scalar(&body_a._body, &body_b._body, cpv_from_object_finite(r1, "r1"),
                                  cpv_from_object_finite(r2, "r2"), cpv_from_object_finite(n, "n"))
    if value == 0.0:
        raise UnsolvableCollision()
    return value
