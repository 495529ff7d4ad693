# Space module (MIS section 8): the world of Munk2D (cpSpace.c, cpSpaceDebug.c)
# and the Python Space. Its step (cpSpaceStep.c, the space half of
# cpSpaceComponent.c) is _space_step; its queries (cpSpaceQuery.c) _space_query.
# Arbiters and their solver are in arbiter.pxd; the struct is cpSpace in
# _structs.pxd.
from tamias2d._config cimport cpFloat, cpBool, cpCollisionType, cpCollisionID, cpTimestamp
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArbiter, cpContact,
    cpCollisionHandler, cpPostStepCallback, cpPostStepFunc, cpConstraint,
    cpSpatialIndexIteratorFunc)
from tamias2d.vector cimport cpVect
from tamias2d.body cimport Body
from tamias2d.shape cimport Shape

# -- life cycle (cpSpace.c) ----------------------------------------------------------
# NULL when out of memory (the space is then destroyed again).
cdef cpSpace *cpSpaceInit(cpSpace *space) noexcept nogil
cdef void cpSpaceDestroy(cpSpace *space) noexcept nogil

# -- properties that do more than store a field ---------------------------------------
cdef void cpSpaceSetGravity(cpSpace *space, cpVect gravity) noexcept nogil
cdef cpBool cpSpaceIsLocked(cpSpace *space) noexcept nogil

# -- collision handlers ------------------------------------------------------------
# (wildcard, wildcard) is the global handler; any other ordered pair is found or
# created (with empty callbacks). NULL when out of memory.
cdef cpCollisionHandler *cpSpaceAddCollisionHandler(cpSpace *space, cpCollisionType a,
                                                    cpCollisionType b) noexcept nogil
cdef cpCollisionHandler *cpSpaceAddWildcardHandler(cpSpace *space, cpCollisionType type) noexcept nogil

# -- objects (callers check the preconditions Munk2D hard-asserts) --------------------
cdef cpShape *cpSpaceAddShape(cpSpace *space, cpShape *shape) noexcept nogil
cdef cpBody *cpSpaceAddBody(cpSpace *space, cpBody *body) noexcept nogil
cdef void cpSpaceRemoveShape(cpSpace *space, cpShape *shape) noexcept nogil
cdef void cpSpaceRemoveBody(cpSpace *space, cpBody *body) noexcept nogil
cdef void cpSpaceReindexStatic(cpSpace *space) noexcept nogil
cdef void cpSpaceReindexShape(cpSpace *space, cpShape *shape) noexcept nogil
cdef void cpSpaceReindexShapesForBody(cpSpace *space, cpBody *body) noexcept nogil

# -- iteration (locked; the callbacks must not add or remove objects) ----------------------
ctypedef void (*cpSpaceBodyIteratorFunc)(cpBody *body, void *data) noexcept nogil
# Dynamic bodies, static bodies, then each sleeping component.
cdef void cpSpaceEachBody(cpSpace *space, cpSpaceBodyIteratorFunc func, void *data) noexcept nogil
# Dynamic tree, then static tree, each in leaf-set order.
cdef void cpSpaceEachShape(cpSpace *space, cpSpatialIndexIteratorFunc func, void *data) noexcept nogil

# -- arbiter cache ----------------------------------------------------------------------
# Unthreads and pools the cached arbiters of `body` (only those of shape
# `filter` when it is not NULL, calling their separate callbacks).
cdef void cpSpaceFilterArbiters(cpSpace *space, cpBody *body, cpShape *filter) noexcept nogil

# The C part of Space.step (the solver's step and the overflow check); returns
# the first body the step made non-finite, or NULL.
cdef cpBody *tamias_space_step(cpSpace *space, cpFloat dt) noexcept nogil

# The step, the contact graph and sleeping: _space_step.pxd. Queries: _space_query.pxd.

# -- Python ------------------------------------------------------------------------------
cdef class Space:
    cdef cpSpace _space          # the C space, embedded; userData points back here
    cdef bint _initialized       # cpSpaceInit succeeded (and cpSpaceDestroy is due)
    cdef dict _bodies            # Body -> None, insertion order (pymunk's Space.bodies)
    cdef dict _shapes            # Shape -> None
    cdef dict _constraints       # Constraint -> None, insertion order
    cdef object _static_body     # the lazily created Python static body, or None
    cdef readonly dict _handlers # key -> CollisionHandler (keeps the callbacks alive)
    cdef dict _post_step_callbacks
    cdef dict _add_later         # objects added while locked, insertion order
    cdef dict _remove_later      # objects removed while locked (run LIFO, as pymunk)
    cdef bint _locked            # pymunk's Python-level lock (step or separate callback)
    cdef bint _may_have_orphans  # a removed body's shapes may still be in the space
    cdef bint _overflowed        # the last step left a non-finite body (checked again before the next)
    cdef object _callback_error  # the first exception raised in a callback, or None
    cdef public object threaded
    """Whether the space was made with ``threaded=True`` (pymunk's flag; False
    on Windows, as in pymunk). tamias2d always solves on the calling thread,
    so the flag changes no number: see :attr:`threads`."""
    cdef dict __dict__
    cdef object __weakref__

    cdef int _raise_callback_error(self) except -1
    cdef int _check_c_errors(self) except -1
    cdef int _raise_non_finite(self, cpBody *body, double dt) except -1
    cdef int _check_bodies(self) except -1
    cdef cpBody *_first_non_finite(self)
    cdef _add_body(self, Body body)
    cdef _add_shape(self, Shape shape)
    cdef _remove(self, tuple objs)
    cdef _remove_shape(self, Shape shape)
    cdef _remove_body(self, Body body)
    cdef _after_step(self)
    cdef int _step_begin(self) except -1
    cdef void _step_abort(self) noexcept
    cdef int _step_finish(self, cpBody *bad, double dt) except -1
    cdef bint _quiet_between_steps(self, cpBody *bad) noexcept nogil
    cdef _debug_draw(self, options)
