# Inline helpers of Munk2D's chipmunk_private.h, one copy for every module
# that needs them (body, arbiter, collision, constraints, the space and its
# step). Nothing here allocates or touches Python; all of it inlines.
#
# It sits just above _structs and _containers, beneath body, so every engine
# module can cimport it. The MIS puts the contact impulse helpers in the
# Collision Solver module: collision.pxd re-exports them from here.
from tamias2d._config cimport cpFloat, cpHashValue, CP_HASH_PAIR
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArbiter, cpArbiterThread,
    cpConstraint, cpArray, cpBodyType, cpCollisionHandler, CP_BODY_TYPE_STATIC)
from tamias2d._containers cimport cpHashSetRemove, cpArrayDeleteObj
from tamias2d.vector cimport cpVect, cpvadd, cpvsub, cpvneg, cpvmult, cpvdot, cpvcross, cpvperp

# -- per-body threading of arbiters and constraints (CP_BODY_FOREACH_*) -------------
cdef inline cpArbiterThread *cpArbiterThreadForBody(cpArbiter *arb, cpBody *body) noexcept nogil:
    return &arb.thread_a if arb.body_a == body else &arb.thread_b

cdef inline cpArbiter *cpArbiterNext(cpArbiter *node, cpBody *body) noexcept nogil:
    return node.thread_a.next if node.body_a == body else node.thread_b.next

cdef inline cpConstraint *cpConstraintNext(cpConstraint *node, cpBody *body) noexcept nogil:
    return node.next_a if node.a == body else node.next_b

# -- the space's body arrays and arbiter cache ---------------------------------------
cdef inline cpArray *cpSpaceArrayForBodyType(cpSpace *space, cpBodyType type) noexcept nogil:
    return space.staticBodies if type == CP_BODY_TYPE_STATIC else space.dynamicBodies

# Every stamp and every removal from the cache goes through these two, so
# that space.arbitersStamped stays the number of cached arbiters touched in
# this step (an arbiter uncached when stamped would leave it too high).
cdef inline void cpSpaceStampArbiter(cpSpace *space, cpArbiter *arb) noexcept nogil:
    if arb.stamp != space.stamp and arb.cached:
        space.arbitersStamped += 1
    arb.stamp = space.stamp

cdef inline void cpSpaceArbiterLeavesCache(cpSpace *space, cpArbiter *arb) noexcept nogil:
    if arb.stamp == space.stamp and arb.cached:
        space.arbitersStamped -= 1

cdef inline void cpSpaceUncacheArbiter(cpSpace *space, cpArbiter *arb) noexcept nogil:
    cdef const cpShape *shape_pair[2]
    shape_pair[0] = arb.a
    shape_pair[1] = arb.b
    cdef cpHashValue arbHashID = CP_HASH_PAIR(<cpHashValue>arb.a, <cpHashValue>arb.b)
    cdef cpArbiter *removed = <cpArbiter *>cpHashSetRemove(space.cachedArbiters, arbHashID, shape_pair)
    if removed != NULL:
        cpSpaceArbiterLeavesCache(space, removed)
        removed.cached = 0
    cpArrayDeleteObj(space.arbiters, arb)

# -- collision handler dispatch ------------------------------------------------------
# The four handler phases. The callback typedefs share one signature, so one
# caller serves all of them.
cdef enum HandlerPhase:
    PHASE_BEGIN
    PHASE_PRE_SOLVE
    PHASE_POST_SOLVE
    PHASE_SEPARATE

cdef inline void cpCallHandler(cpCollisionHandler *h, HandlerPhase phase, cpArbiter *arb,
                               cpSpace *space) noexcept nogil:
    if phase == PHASE_BEGIN:
        h.beginFunc(arb, space, h.userData)
    elif phase == PHASE_PRE_SOLVE:
        h.preSolveFunc(arb, space, h.userData)
    elif phase == PHASE_POST_SOLVE:
        h.postSolveFunc(arb, space, h.userData)
    else:
        h.separateFunc(arb, space, h.userData)

# The five handlers of an arbiter in Munk2D's order. In the step, `toggle`
# flips `swapped` around BA and B so each handler sees the shapes in its own
# type order; shape removal calls separate without toggling.
cdef inline void cpCallHandlers(cpArbiter *arb, cpSpace *space, HandlerPhase phase,
                                bint toggle) noexcept nogil:
    cpCallHandler(arb.handlerAB, phase, arb, space)
    if toggle:
        arb.swapped = not arb.swapped
    cpCallHandler(arb.handlerBA, phase, arb, space)
    if toggle:
        arb.swapped = not arb.swapped
    cpCallHandler(arb.handlerA, phase, arb, space)
    if toggle:
        arb.swapped = not arb.swapped
    cpCallHandler(arb.handlerB, phase, arb, space)
    if toggle:
        arb.swapped = not arb.swapped
    cpCallHandler(&space.globalHandler, phase, arb, space)

# -- contact impulse helpers ---------------------------------------------------------
# Same expressions and association as Munk2D, so the solver gives the same bits.

cdef inline cpVect relative_velocity(cpBody *a, cpBody *b, cpVect r1, cpVect r2) noexcept nogil:
    cdef cpVect v1_sum = cpvadd(a.v, cpvmult(cpvperp(r1), a.w))
    cdef cpVect v2_sum = cpvadd(b.v, cpvmult(cpvperp(r2), b.w))
    return cpvsub(v2_sum, v1_sum)

cdef inline cpFloat normal_relative_velocity(cpBody *a, cpBody *b, cpVect r1, cpVect r2,
                                             cpVect n) noexcept nogil:
    return cpvdot(relative_velocity(a, b, r1, r2), n)

cdef inline void apply_impulse(cpBody *body, cpVect j, cpVect r) noexcept nogil:
    body.v = cpvadd(body.v, cpvmult(j, body.m_inv))
    body.w += body.i_inv * cpvcross(r, j)

cdef inline void apply_impulses(cpBody *a, cpBody *b, cpVect r1, cpVect r2, cpVect j) noexcept nogil:
    apply_impulse(a, cpvneg(j), r1)
    apply_impulse(b, j, r2)

cdef inline void apply_bias_impulse(cpBody *body, cpVect j, cpVect r) noexcept nogil:
    body.v_bias = cpvadd(body.v_bias, cpvmult(j, body.m_inv))
    body.w_bias += body.i_inv * cpvcross(r, j)

cdef inline void apply_bias_impulses(cpBody *a, cpBody *b, cpVect r1, cpVect r2, cpVect j) noexcept nogil:
    apply_bias_impulse(a, cpvneg(j), r1)
    apply_bias_impulse(b, j, r2)

cdef inline cpFloat k_scalar_body(cpBody *body, cpVect r, cpVect n) noexcept nogil:
    cdef cpFloat rcn = cpvcross(r, n)
    return body.m_inv + body.i_inv * rcn * rcn

# Effective-mass denominator of a contact. A zero result (both bodies
# infinitely heavy along n) is returned as is: pymunk builds Munk2D without
# its soft asserts, so the solver then divides by zero. The Python wrapper
# collision.k_scalar() raises UnsolvableCollision instead.
cdef inline cpFloat k_scalar(cpBody *a, cpBody *b, cpVect r1, cpVect r2, cpVect n) noexcept nogil:
    return k_scalar_body(a, r1, n) + k_scalar_body(b, r2, n)
