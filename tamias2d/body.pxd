# Rigid Body module (MIS section 6): cpBody functions (cpBody.c) and the Python
# Body. The class layout below is shared with shape, collision and space;
# change it only together with them.
from tamias2d._config cimport cpFloat, cpBool
from tamias2d._structs cimport (cpBody, cpShape, cpSpace, cpArbiter, cpBodyType,
    cpBodyVelocityFunc, cpBodyPositionFunc)
from tamias2d.vector cimport cpVect, cpTransform

cdef class Body:
    cdef cpBody _body            # the C body, embedded; C code uses &self._body
    cdef object _space           # weakref.ref to the Space holding it, or None
    cdef dict _shapes            # Shape -> None, the shapes attached (insertion order)
    cdef object _velocity_func   # Python override of the velocity integrator, or None
    cdef object _position_func   # Python override of the position integrator, or None
    cdef dict __dict__           # user attributes, as pymunk allows
    cdef object __weakref__
