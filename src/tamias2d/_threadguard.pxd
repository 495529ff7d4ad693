# One space, many threads. Space.step releases the GIL, so while a space
# steps, another thread holding the GIL could reach the structures the step
# mutates (waking a body edits the body arrays and the indexes, a query moves
# the lock counter, new vertices reallocate a shape). Every Python entry
# point that touches a space or one of its bodies, shapes or joints calls
# tamias_wait_for_step first, after converting its arguments and before
# touching C state: if another thread is stepping that space, it waits (GIL
# released) until the step ends. The stepping thread itself (collision and
# post-step callbacks, Python integrators) passes straight through.
#
# The fields it reads (cpSpace.stepThread, stepLock, stepWaiters) are only
# written while holding the GIL, so a thread holding the GIL sees them
# consistently. Cost when no step runs: one load and one branch.
from tamias2d._structs cimport cpSpace, cpBody, cpShape, cpConstraint

cdef int tamias_wait_for_step_slow(cpSpace *space) except -1

cdef inline int tamias_wait_for_step(cpSpace *space) except -1:
    if space != NULL and space.stepThread != 0:
        return tamias_wait_for_step_slow(space)
    return 0

# A body's space, or (a body removed while its shapes stayed) its shapes'.
cdef inline cpSpace *tamias_body_space(const cpBody *body) noexcept nogil:
    if body.space != NULL:
        return body.space
    if body.shapeList != NULL:
        return body.shapeList.space
    return NULL

cdef inline int tamias_wait_body(const cpBody *body) except -1:
    cdef cpSpace *space = tamias_body_space(body)
    if space != NULL and space.stepThread != 0:
        return tamias_wait_for_step_slow(space)
    return 0

# A shape's space, or its body's (a shape not in a space still changes the
# mass of its body).
cdef inline int tamias_wait_shape(const cpShape *shape) except -1:
    cdef cpSpace *space = shape.space
    if space == NULL and shape.body != NULL:
        space = tamias_body_space(shape.body)
    if space != NULL and space.stepThread != 0:
        return tamias_wait_for_step_slow(space)
    return 0

# A joint's space, and its bodies' (changing a joint wakes its bodies, even
# when the joint itself is in no space).
cdef inline int tamias_wait_constraint(const cpConstraint *c) except -1:
    if c.space != NULL and c.space.stepThread != 0:
        tamias_wait_for_step_slow(c.space)
    if c.a != NULL:
        tamias_wait_body(c.a)
    if c.b != NULL:
        tamias_wait_body(c.b)
    return 0

# The stepping side, called with the GIL held around the GIL-free step.
# tamias_begin_step first lets waiting threads in (so a loop of steps cannot
# starve them), then marks the space as stepping in this thread.
cdef int tamias_begin_step(cpSpace *space) except -1
cdef void tamias_end_step(cpSpace *space) noexcept

# The space's lock, made by Space.__cinit__ and freed by its __dealloc__.
cdef int tamias_step_lock_new(cpSpace *space) except -1
cdef void tamias_step_lock_free(cpSpace *space) noexcept
