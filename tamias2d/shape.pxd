# Shape module (MIS section 7) with Circle (7.5), Poly (7.9) and Segment:
# cpShape / cpPolyShape functions and the Python shapes. The class layout below
# is shared with collision and space; change it only together with them.
from tamias2d._config cimport cpFloat, cpBool, cpHashValue
from tamias2d._structs cimport (cpShape, cpShapeClass, cpCircleShape, cpSegmentShape,
    cpPolyShape, cpShapeMassInfo, cpShapeFilter, cpPointQueryInfo, cpSegmentQueryInfo)
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
