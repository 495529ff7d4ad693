# The step of the chipmunk solver (Munk2D's cpSpaceStep.c) and the space side
# of the contact graph and sleeping (cpSpaceComponent.c). The world itself,
# cpSpace.c, is in space.pxd; the queries are in _space_query.pxd.
#
# cpSpaceStep is a pipeline of the stages below, in this order:
#   StageResetArbiters       last step's arbiters: normal again, unthreaded
#   StageIntegratePositions  body.position_func of every awake body
#   StageCollide             broad phase -> cpSpaceCollideShapes (narrow phase,
#                            arbiter cache, begin / pre-solve callbacks)
#   cpSpaceProcessComponents contact graph, idle times, sleeping
#   StageFilterArbiterCache  separate callbacks, expiry of cached arbiters
#   StagePreStep             arbiters and constraints prepared for this dt
#   StageIntegrateVelocities body.velocity_func (gravity, damping)
#   StageWarmStart           last step's impulses applied again
#   StageSolve               `iterations` sequential impulse passes
#   StagePostSolve           post-solve callbacks
#   cpSpaceUnlock(space, 1)  post-step callbacks, objects woken meanwhile
from tamias2d._config cimport (cpFloat, cpBool, cpCollisionID, CP_BUFFER_BYTES,
    CP_MAX_CONTACTS_PER_ARBITER)
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArray, cpContact, cpCollisionInfo,
    cpArbiter, cpContactBufferHeader,
    cpPostStepCallback, cpPostStepFunc, CP_BODY_TYPE_DYNAMIC)
from tamias2d.body cimport cpBodyGetType

# -- locking and post-step callbacks ---------------------------------------------------
cdef void cpSpaceLock(cpSpace *space) noexcept nogil
# At the last unlock: activates the bodies woken while locked, then (if
# runPostStep) runs and frees the post-step callbacks.
cdef void cpSpaceUnlock(cpSpace *space, cpBool runPostStep) noexcept nogil
cdef cpPostStepCallback *cpSpaceGetPostStepCallback(cpSpace *space, void *key) noexcept nogil
cdef cpBool cpSpaceAddPostStepCallback(cpSpace *space, cpPostStepFunc func, void *key,
                                       void *data) noexcept nogil

# -- contact buffers --------------------------------------------------------------------
# Contacts per 32 KiB contact buffer, as Munk2D computes CP_CONTACTS_BUFFER_SIZE
# (_space_step.pyx checks the two sizes at import).
cdef enum:
    CP_CONTACTS_BUFFER_SIZE = (CP_BUFFER_BYTES - 24) // 96

cdef struct cpContactBuffer:
    cpContactBufferHeader header
    cpContact contacts[CP_CONTACTS_BUFFER_SIZE]

cdef void cpSpacePushFreshContactBuffer(cpSpace *space) noexcept nogil
# Room for CP_MAX_CONTACTS_PER_ARBITER contacts, or NULL when out of memory.
cdef cpContact *cpContactBufferGetArray(cpSpace *space) noexcept nogil
cdef void cpSpacePushContacts(cpSpace *space, int count) noexcept nogil

# cpContactBufferGetArray where the head buffer has room (no call: the soft
# step's serial pass takes one per touching pair).
cdef inline cpContact *cpContactBufferRoom(cpSpace *space) noexcept nogil:
    cdef cpContactBufferHeader *head = space.contactBuffersHead
    if head != NULL and head.numContacts + CP_MAX_CONTACTS_PER_ARBITER <= CP_CONTACTS_BUFFER_SIZE:
        return (<cpContactBuffer *>head).contacts + head.numContacts
    return cpContactBufferGetArray(space)

# -- the step and its stages --------------------------------------------------------------
cdef void cpSpaceStep(cpSpace *space, cpFloat dt) noexcept nogil
cdef void StageResetArbiters(cpSpace *space) noexcept nogil
cdef void StageIntegratePositions(cpSpace *space, cpFloat dt) noexcept nogil
cdef void StageCollide(cpSpace *space) noexcept nogil
cdef void StageFilterArbiterCache(cpSpace *space) noexcept nogil
cdef void StagePreStep(cpSpace *space, cpFloat dt) noexcept nogil
cdef void StageIntegrateVelocities(cpSpace *space, cpFloat dt) noexcept nogil
cdef void StageWarmStart(cpSpace *space, cpFloat dt, cpFloat prev_dt) noexcept nogil
cdef void StageSolve(cpSpace *space, cpFloat dt) noexcept nogil
cdef void StagePostSolve(cpSpace *space) noexcept nogil

# The broad phase callback of StageCollide, and the cache filter of
# StageFilterArbiterCache.
cdef cpCollisionID cpSpaceCollideShapes(void *a, void *b, cpCollisionID id, void *space) noexcept nogil
# cpSpaceCollideShapes in parts, for a narrow phase run apart (the soft
# solver's, on several threads): the rejection test and the pair's margin,
# then (the contacts on the contact buffer) arbiter, callbacks, this step's list.
cdef cpBool cpSpaceRejectPair(cpSpace *space, cpShape *a, cpShape *b, cpFloat *margin) noexcept nogil
cdef cpArbiter *cpSpaceAcceptCollision(cpSpace *space, cpShape *a, cpShape *b,
                                       cpCollisionInfo *info, cpArbiter *found,
                                       bint updated, int solid) noexcept nogil
# cpSpaceAcceptCollision's test of a pair's shapes and bodies (not a sensor,
# not both of infinite mass), which a caller may make beforehand.
cdef bint cpSpacePairIsSolid(const cpShape *a, const cpShape *b) noexcept nogil
# Whether any collision handler of the space acts in one of these phases.
cdef bint cpSpaceHasHandlers(cpSpace *space, bint begin, bint preSolve,
                             bint postSolve) noexcept nogil
cdef cpBool cpSpaceArbiterSetFilter(void *arb, void *space) noexcept nogil
# cpShapeCacheBB as a spatial-index iterator.
cdef void cpShapeUpdateFunc(void *shape, void *unused) noexcept nogil

# -- components and sleeping ----------------------------------------------------------------
cdef void cpSpaceActivateBody(cpSpace *space, cpBody *body) noexcept nogil
cdef void cpSpaceDeactivateBody(cpSpace *space, cpBody *body) noexcept nogil
# Wakes every body of the sleeping component rooted at `root` and drops the
# component (cpBodyActivate's space half).
cdef void cpSpaceWakeComponent(cpSpace *space, cpBody *root) noexcept nogil
# Threads this step's first `count` arbiters into the contact graph (unless
# `threaded`: they are already), wakes what they touch, updates idle times
# and puts idle components to sleep. `links` (NULL, or room for twice
# space.dynamicBodies.num + 2 ints) lets it skip the flood fill where it
# can tell that no component would sleep (the soft step; it overwrites the
# bodies' solverIndex), and returns whether it did.
cdef bint cpSpaceProcessComponents(cpSpace *space, cpFloat dt, int count, bint threaded,
                                   int *links) noexcept nogil

# A dynamic body removed from the space while its shapes stayed (pymunk
# allows it). The space no longer integrates it, so, like a kinematic body, it
# never joins a component and keeps what it touches awake: a component put to
# sleep against it would keep their shared arbiter threaded, and the next
# step would thread it again.
cdef inline bint _orphanBody(cpBody *body, cpSpace *space) noexcept nogil:
    return (body.space != space and body.shapeList != NULL
            and cpBodyGetType(body) == CP_BODY_TYPE_DYNAMIC)

# -- guards of the step (not in Munk2D: pymunk goes NaN where these raise) --------------------
# x - x is 0 for a finite x and NaN for inf or NaN: one test for all.
cdef inline bint _bodyNonFinite(cpBody *body) noexcept nogil:
    return (body.p.x - body.p.x + body.p.y - body.p.y + body.v.x - body.v.x + body.v.y
            - body.v.y + body.a - body.a + body.w - body.w) != 0.0

cdef cpBody *_firstNonFiniteBody(cpArray *bodies) noexcept nogil
# The first non-finite body among all a step can change but orphans (see the
# definition); NULL if none.
cdef cpBody *tamias_first_non_finite_body(cpSpace *space) noexcept nogil
# After a step that overflowed, drop the non-finite warm-start impulses.
cdef void _forgetNonFiniteImpulses(cpSpace *space) noexcept nogil

cdef struct OrphanScan:
    cpSpace *space
    cpBody *bad      # the first orphan whose mass or moment cannot be inverted
    cpBody *nonFinite  # the first orphan with a non-finite state
    int orphans      # shapes seen whose body is an orphan (see _orphanBody)

# A spatial-index iterator filling an OrphanScan.
cdef void _scanOrphans(void *obj, void *data) noexcept nogil
