# Shape module (MIS section 7) with Circle (7.5), Poly (7.9) and Segment:
# cpShape / cpPolyShape functions and the Python shapes. The class layout below
# is shared with collision and space; change it only together with them.
from tamias2d._config cimport cpFloat, cpBool, cpHashValue
from tamias2d._structs cimport (cpShape, cpShapeClass, cpCircleShape, cpSegmentShape,
    cpPolyShape, cpShapeMassInfo, cpShapeFilter, cpPointQueryInfo, cpSegmentQueryInfo)
from tamias2d._config cimport cpCollisionType
from tamias2d._structs cimport cpBody
from tamias2d.vector cimport cpVect, cpBB, cpTransform
from tamias2d.body cimport Body

cdef class Shape:
    cdef cpShape *_shape         # points at the subclass's embedded struct
    cdef Body _body_obj          # the body (strong reference) or None
    cdef object _space           # weakref.ref to the Space holding it, or None
    cdef dict __dict__           # user attributes (pymunk's draw code reads .color)
    cdef object __weakref__

cdef class Circle(Shape):
    cdef cpCircleShape _circle

cdef class Segment(Shape):
    cdef cpSegmentShape _segment

cdef class Poly(Shape):
    cdef cpPolyShape _poly

# A C copy of a Python vertex list, freed with the object; _verts_arg makes it
# (TypeError / IllegalShape for what is not a non-empty list of pairs; with
# finite, IllegalVector for non-finite components).
cdef class _VertBuffer:
    cdef cpVect *verts
    cdef int count

cdef _VertBuffer _verts_arg(object vertices, bint finite)


# -- C level (cpShape.c, cpPolyShape.c, chipmunk.c, chipmunk_private.h) ------
# The three class tables. A shape's kind is told by comparing shape.klass with
# their addresses, or by reading klass.type.
cdef cpShapeClass cpCircleShapeClass
cdef cpShapeClass cpSegmentShapeClass
cdef cpShapeClass cpPolyShapeClass

# chipmunk_private.h helpers.
cdef inline cpBool cpShapeActive(const cpShape *shape) noexcept nogil:
    # Linked into its body's shape list (which only happens inside a space).
    return shape.prev != NULL or (shape.body != NULL and shape.body.shapeList == shape)

cdef inline cpBool cpShapeFilterReject(cpShapeFilter a, cpShapeFilter b) noexcept nogil:
    # Same non-zero group, or either category/mask pair does not match.
    return ((a.group != 0 and a.group == b.group)
            or (a.categories & b.mask) == 0
            or (b.categories & a.mask) == 0)

cdef void CircleSegmentQuery(const cpShape *shape, cpVect center, cpFloat r1, cpVect a, cpVect b,
                             cpFloat r2, cpSegmentQueryInfo *info) noexcept nogil

# Generic shape.
cdef cpShape *cpShapeInit(cpShape *shape, const cpShapeClass *klass, cpBody *body,
                          cpShapeMassInfo massInfo) noexcept nogil
cdef void cpShapeDestroy(cpShape *shape) noexcept nogil
cdef void cpShapeFree(cpShape *shape) noexcept nogil
cdef void cpShapeSetBody(cpShape *shape, cpBody *body) noexcept nogil
cdef void cpShapeSetMass(cpShape *shape, cpFloat mass) noexcept nogil
cdef cpFloat cpShapeGetDensity(const cpShape *shape) noexcept nogil
cdef void cpShapeSetDensity(cpShape *shape, cpFloat density) noexcept nogil
cdef cpFloat cpShapeGetMoment(const cpShape *shape) noexcept nogil
cdef void cpShapeSetSensor(cpShape *shape, cpBool sensor) noexcept nogil
cdef void cpShapeSetElasticity(cpShape *shape, cpFloat elasticity) noexcept nogil
cdef void cpShapeSetFriction(cpShape *shape, cpFloat friction) noexcept nogil
cdef void cpShapeSetSurfaceVelocity(cpShape *shape, cpVect surfaceVelocity) noexcept nogil
cdef void cpShapeSetCollisionType(cpShape *shape, cpCollisionType collisionType) noexcept nogil
cdef void cpShapeSetFilter(cpShape *shape, cpShapeFilter filter) noexcept nogil
cdef cpBB cpShapeCacheBB(cpShape *shape) noexcept nogil
cdef cpBB cpShapeUpdate(cpShape *shape, cpTransform transform) noexcept nogil
cdef cpFloat cpShapePointQuery(const cpShape *shape, cpVect p, cpPointQueryInfo *info) noexcept nogil
cdef cpBool cpShapeSegmentQuery(const cpShape *shape, cpVect a, cpVect b, cpFloat radius,
                                cpSegmentQueryInfo *info) noexcept nogil

# Circle.
cdef cpShapeMassInfo cpCircleShapeMassInfo(cpFloat mass, cpFloat radius, cpVect center) noexcept nogil
cdef cpCircleShape *cpCircleShapeInit(cpCircleShape *circle, cpBody *body, cpFloat radius,
                                      cpVect offset) noexcept nogil
cdef cpShape *cpCircleShapeNew(cpBody *body, cpFloat radius, cpVect offset) noexcept nogil
cdef cpVect cpCircleShapeGetOffset(const cpShape *shape) noexcept nogil
cdef cpFloat cpCircleShapeGetRadius(const cpShape *shape) noexcept nogil
cdef void cpCircleShapeSetRadius(cpShape *shape, cpFloat radius) noexcept nogil
cdef void cpCircleShapeSetOffset(cpShape *shape, cpVect offset) noexcept nogil

# Segment.
cdef cpShapeMassInfo cpSegmentShapeMassInfo(cpFloat mass, cpVect a, cpVect b, cpFloat r) noexcept nogil
cdef cpSegmentShape *cpSegmentShapeInit(cpSegmentShape *seg, cpBody *body, cpVect a, cpVect b,
                                        cpFloat r) noexcept nogil
cdef cpShape *cpSegmentShapeNew(cpBody *body, cpVect a, cpVect b, cpFloat r) noexcept nogil
cdef cpVect cpSegmentShapeGetA(const cpShape *shape) noexcept nogil
cdef cpVect cpSegmentShapeGetB(const cpShape *shape) noexcept nogil
cdef cpVect cpSegmentShapeGetNormal(const cpShape *shape) noexcept nogil
cdef cpFloat cpSegmentShapeGetRadius(const cpShape *shape) noexcept nogil
cdef void cpSegmentShapeSetNeighbors(cpShape *shape, cpVect prev, cpVect next) noexcept nogil
cdef void cpSegmentShapeSetEndpoints(cpShape *shape, cpVect a, cpVect b) noexcept nogil
cdef void cpSegmentShapeSetRadius(cpShape *shape, cpFloat radius) noexcept nogil

# Poly. The Init/New/SetVerts functions allocate (hull scratch space, planes
# of more than CP_POLY_SHAPE_INLINE_ALLOC vertices); they return NULL / 0 when
# memory runs out, where Munk2D would abort. count must be >= 1.
cdef cpShapeMassInfo cpPolyShapeMassInfo(cpFloat mass, int count, const cpVect *verts,
                                         cpFloat radius) noexcept nogil
cdef cpPolyShape *cpPolyShapeInit(cpPolyShape *poly, cpBody *body, int count, const cpVect *verts,
                                  cpTransform transform, cpFloat radius) noexcept nogil
cdef cpPolyShape *cpPolyShapeInitRaw(cpPolyShape *poly, cpBody *body, int count, const cpVect *verts,
                                     cpFloat radius) noexcept nogil
cdef cpShape *cpPolyShapeNew(cpBody *body, int count, const cpVect *verts, cpTransform transform,
                             cpFloat radius) noexcept nogil
cdef cpShape *cpPolyShapeNewRaw(cpBody *body, int count, const cpVect *verts,
                                cpFloat radius) noexcept nogil
cdef cpPolyShape *cpBoxShapeInit(cpPolyShape *poly, cpBody *body, cpFloat width, cpFloat height,
                                 cpFloat radius) noexcept nogil
cdef cpPolyShape *cpBoxShapeInit2(cpPolyShape *poly, cpBody *body, cpBB box, cpFloat radius) noexcept nogil
cdef cpShape *cpBoxShapeNew(cpBody *body, cpFloat width, cpFloat height, cpFloat radius) noexcept nogil
cdef cpShape *cpBoxShapeNew2(cpBody *body, cpBB box, cpFloat radius) noexcept nogil
cdef int cpPolyShapeGetCount(const cpShape *shape) noexcept nogil
cdef cpVect cpPolyShapeGetVert(const cpShape *shape, int i) noexcept nogil
cdef cpFloat cpPolyShapeGetRadius(const cpShape *shape) noexcept nogil
cdef cpBool cpPolyShapeSetVerts(cpShape *shape, int count, const cpVect *verts,
                                cpTransform transform) noexcept nogil
cdef cpBool cpPolyShapeSetVertsRaw(cpShape *shape, int count, const cpVect *verts) noexcept nogil
cdef void cpPolyShapeSetRadius(cpShape *shape, cpFloat radius) noexcept nogil

# Moments, areas, centroid, convex hull (chipmunk.c).
cdef cpFloat cpMomentForCircle(cpFloat m, cpFloat r1, cpFloat r2, cpVect offset) noexcept nogil
cdef cpFloat cpAreaForCircle(cpFloat r1, cpFloat r2) noexcept nogil
cdef cpFloat cpMomentForSegment(cpFloat m, cpVect a, cpVect b, cpFloat r) noexcept nogil
cdef cpFloat cpAreaForSegment(cpVect a, cpVect b, cpFloat r) noexcept nogil
cdef cpFloat cpMomentForPoly(cpFloat m, int count, const cpVect *verts, cpVect offset,
                             cpFloat r) noexcept nogil
cdef cpFloat cpAreaForPoly(int count, const cpVect *verts, cpFloat r) noexcept nogil
cdef cpVect cpCentroidForPoly(int count, const cpVect *verts) noexcept nogil
cdef cpFloat cpMomentForBox(cpFloat m, cpFloat width, cpFloat height) noexcept nogil
cdef cpFloat cpMomentForBox2(cpFloat m, cpBB box) noexcept nogil
cdef void cpLoopIndexes(const cpVect *verts, int count, int *start, int *end) noexcept nogil
cdef int cpConvexHull(int count, const cpVect *verts, cpVect *result, int *first,
                      cpFloat tol) noexcept nogil
