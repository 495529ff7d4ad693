# Arbiters (part of the Space module, MIS section 8): the persistent contact
# pair of Munk2D's cpArbiter.c, its impulse solver, and the Python Arbiter view.
# The struct is cpArbiter in _structs.pxd; the space module owns the arbiters
# (pool, cache, per-step array) and calls these functions from its step.
from tamias2d._config cimport cpFloat, cpBool, cpCollisionType
from tamias2d._structs cimport (cpArbiter, cpArbiterThread, cpBody, cpShape, cpSpace,
    cpCollisionInfo, cpCollisionHandler, cpContactPointSet, cpArbiterState)
from tamias2d.vector cimport cpVect

# The handler every unmatched type pair gets: four empty callbacks, typed
# (wildcard, wildcard) so that it never matches a real pair.
cdef cpCollisionHandler *cpCollisionHandlerDoNothing() noexcept nogil
# The empty callback itself (the default of every handler slot).
cdef void cpCollisionDoNothing(cpArbiter *arb, cpSpace *space, void *data) noexcept nogil

# -- per-body threading of arbiters (CP_BODY_FOREACH_ARBITER), from _private.pxd -----
from tamias2d._private cimport cpArbiterThreadForBody, cpArbiterNext

cdef void cpArbiterUnthread(cpArbiter *arb) noexcept nogil
# Pushes arb onto the head of body's arbiter list (arb must not be on it),
# and onto both its bodies' lists (the step's threading, in both solvers).
cdef inline void cpBodyPushArbiter(cpBody *body, cpArbiter *arb) noexcept nogil:
    cdef cpArbiter *next = body.arbiterList
    cpArbiterThreadForBody(arb, body).next = next
    if next != NULL:
        cpArbiterThreadForBody(next, body).prev = arb
    body.arbiterList = arb

cdef inline void cpArbiterPushThreads(cpArbiter *arb) noexcept nogil:
    cpBodyPushArbiter(arb.body_a, arb)
    cpBodyPushArbiter(arb.body_b, arb)

# Clears arb's links and both its bodies' list heads, for when every list arb
# is on is being emptied at once (freeing a space).
cdef void cpArbiterDropThreads(cpArbiter *arb) noexcept nogil

# -- accessors -------------------------------------------------------------------
cdef cpBool cpArbiterIsFirstContact(const cpArbiter *arb) noexcept nogil
cdef cpBool cpArbiterIsRemoval(const cpArbiter *arb) noexcept nogil
cdef int cpArbiterGetCount(const cpArbiter *arb) noexcept nogil
cdef cpVect cpArbiterGetNormal(const cpArbiter *arb) noexcept nogil
cdef cpVect cpArbiterGetPointA(const cpArbiter *arb, int i) noexcept nogil
cdef cpVect cpArbiterGetPointB(const cpArbiter *arb, int i) noexcept nogil
cdef cpFloat cpArbiterGetDepth(const cpArbiter *arb, int i) noexcept nogil
cdef cpContactPointSet cpArbiterGetContactPointSet(const cpArbiter *arb) noexcept nogil
# Returns 0 (and changes nothing) when the point count differs from the arbiter's.
cdef cpBool cpArbiterSetContactPointSet(cpArbiter *arb, cpContactPointSet *set) noexcept nogil
cdef cpVect cpArbiterTotalImpulse(const cpArbiter *arb) noexcept nogil
cdef cpFloat cpArbiterTotalKE(const cpArbiter *arb) noexcept nogil
cdef cpVect cpArbiterGetSurfaceVelocity(cpArbiter *arb) noexcept nogil
cdef void cpArbiterSetSurfaceVelocity(cpArbiter *arb, cpVect vr) noexcept nogil
cdef void cpArbiterGetShapes(const cpArbiter *arb, cpShape **a, cpShape **b) noexcept nogil
cdef void cpArbiterGetBodies(const cpArbiter *arb, cpBody **a, cpBody **b) noexcept nogil

# -- life cycle and solver (called by the space's step) -------------------------
cdef cpArbiter *cpArbiterInit(cpArbiter *arb, cpShape *a, cpShape *b) noexcept nogil
cdef void cpArbiterUpdate(cpArbiter *arb, cpCollisionInfo *info, cpSpace *space) noexcept nogil
# Parameter order as the definition in cpArbiter.c: (dt, slop, bias).
cdef void cpArbiterPreStep(cpArbiter *arb, cpFloat dt, cpFloat slop, cpFloat bias) noexcept nogil
cdef void cpArbiterApplyCachedImpulse(cpArbiter *arb, cpFloat dt_coef) noexcept nogil
cdef void cpArbiterApplyImpulse(cpArbiter *arb) noexcept nogil

# -- Python view ------------------------------------------------------------------
cdef class Arbiter:
    cdef cpArbiter *_arbiter     # borrowed; the space owns it (pool memory)
    cdef object _space           # the Python Space (strong: keeps the pool alive)
    cdef cpArbiter *_get(self) except NULL

# A new Arbiter view of arb inside the Python Space `space`.
cdef Arbiter arbiter_wrap(cpArbiter *arb, object space)
