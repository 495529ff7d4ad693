# Queries of the space (Munk2D's cpSpaceQuery.c). Munk2D reports each hit
# through a user callback; here hits are gathered in a C buffer, in the same
# order, and the Python layer (Space.point_query, ...) turns them into Python
# objects after the query, so no Python runs while an index is walked.
# Each function locks the space while it walks, as Munk2D does.
from tamias2d._config cimport cpFloat, cpBool
from tamias2d._structs cimport (cpSpace, cpShape, cpShapeFilter, cpPointQueryInfo,
    cpSegmentQueryInfo, cpContactPointSet)
from tamias2d.vector cimport cpVect, cpBB

cdef struct QueryHit:
    cpShape *shape
    cpVect point
    cpVect vect          # gradient (point query) or normal (segment query)
    cpFloat value        # distance or alpha

cdef struct QueryHits:
    QueryHit *hits
    int count
    int capacity
    cpBool failed        # out of memory: some hits were lost

cdef struct ShapeQueryHits:
    cpShape **shapes
    cpContactPointSet *sets
    int count
    int capacity
    cpBool failed
    cpBool anyCollision

# Every shape within maxDistance of point, dynamic index first.
cdef void cpSpacePointQuery(cpSpace *space, cpVect point, cpFloat maxDistance, cpShapeFilter filter,
                            QueryHits *out) noexcept nogil
cdef cpShape *cpSpacePointQueryNearest(cpSpace *space, cpVect point, cpFloat maxDistance,
                                       cpShapeFilter filter, cpPointQueryInfo *out) noexcept nogil
# Every shape the segment (swept by radius) touches, static index first.
cdef void cpSpaceSegmentQuery(cpSpace *space, cpVect start, cpVect end, cpFloat radius,
                              cpShapeFilter filter, QueryHits *out) noexcept nogil
cdef cpShape *cpSpaceSegmentQueryFirst(cpSpace *space, cpVect start, cpVect end, cpFloat radius,
                                       cpShapeFilter filter, cpSegmentQueryInfo *out) noexcept nogil
cdef void cpSpaceBBQuery(cpSpace *space, cpBB bb, cpShapeFilter filter, QueryHits *out) noexcept nogil
# Returns whether any non-sensor shape overlaps `shape`.
cdef cpBool cpSpaceShapeQuery(cpSpace *space, cpShape *shape, ShapeQueryHits *out) noexcept nogil
