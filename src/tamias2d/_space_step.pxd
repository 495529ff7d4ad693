# The step of the chipmunk solver (Munk2D's cpSpaceStep.c) and the space side
# of the contact graph and sleeping (cpSpaceComponent.c). The world itself,
# cpSpace.c, is in space.pxd; the queries are in _space_query.pxd.
#
# cpSpaceStep is a pipeline of the stages below, in this order:
#   StageResetArbiters       last step's arbiters: normal again, unthreaded (but
#                            those with a sleeping body: counted)
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
    cpArbiter, cpContactBufferHeader, cpConstraint,
    cpPostStepCallback, cpPostStepFunc, CP_BODY_TYPE_DYNAMIC, CP_ARBITER_STATE_IGNORE)
from tamias2d.body cimport cpBodyGetType
from libc.math cimport sqrt, fmax, INFINITY
from tamias2d.vector cimport cpVect, cpBB, cpvsub, cpvlengthsq
from tamias2d.shape cimport cpShapeFilterReject
from tamias2d._bbtree cimport cpBBTreeGetStaticReach
from tamias2d._private cimport cpConstraintNext, cpSpaceStampArbiter

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
# The last collision's `count` contacts onto (or back off) the head buffer.
cdef inline void cpSpacePushContacts(cpSpace *space, int count) noexcept nogil:
    space.contactBuffersHead.numContacts += count

cdef inline void cpSpacePopContacts(cpSpace *space, int count) noexcept nogil:
    space.contactBuffersHead.numContacts -= count

# cpContactBufferGetArray where the head buffer has room (no call: the soft
# step's serial pass takes one per touching pair).
cdef inline cpContact *cpContactBufferRoom(cpSpace *space) noexcept nogil:
    cdef cpContactBufferHeader *head = space.contactBuffersHead
    if head != NULL and head.numContacts + CP_MAX_CONTACTS_PER_ARBITER <= CP_CONTACTS_BUFFER_SIZE:
        return (<cpContactBuffer *>head).contacts + head.numContacts
    return cpContactBufferGetArray(space)

# -- the step and its stages --------------------------------------------------------------
cdef void cpSpaceStep(cpSpace *space, cpFloat dt) noexcept nogil
cdef int StageResetArbiters(cpSpace *space) noexcept nogil
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
# (Inline, below: the soft step calls it for every pair of the broad phase.)
cdef cpArbiter *cpSpaceAcceptCollision(cpSpace *space, cpShape *a, cpShape *b,
                                       cpCollisionInfo *info, cpArbiter *found,
                                       bint updated, int solid) noexcept nogil
# cpSpaceAcceptCollision's test of a pair's shapes and bodies (not a sensor,
# not both of infinite mass), which a caller may make beforehand.
cdef inline bint cpSpacePairIsSolid(const cpShape *a, const cpShape *b) noexcept nogil:
    return not (a.sensor or b.sensor) and not (a.body.m == INFINITY and b.body.m == INFINITY)

# Whether cpSpaceAcceptCollision puts an arbiter of a `solid` pair on the
# step's list to be solved (not ignored, and its handlers let it).
cdef inline bint cpArbiterIsSolved(const cpArbiter *arb, bint solid) noexcept nogil:
    return arb.state != CP_ARBITER_STATE_IGNORE and arb.processCollision and solid

# cpSpaceAcceptCollision's common path, inline (the soft step takes it for
# most touching pairs): `arb`, found in the cache and updated already (no
# begin or pre-solve handler), its contacts pushed, goes on the step's list
# if it is solved and the list has room. False, with nothing done,
# otherwise: then cpSpaceAcceptCollision(space, a, b, info, arb, 1, solid).
cdef inline bint cpSpaceAcceptUpdated(cpSpace *space, cpArbiter *arb, bint solid) noexcept nogil:
    cdef cpArray *arbiters = space.arbiters
    if (arb.stamp == space.stamp or not cpArbiterIsSolved(arb, solid)
            or arbiters.num >= arbiters.max):
        return 0
    arbiters.arr[arbiters.num] = arb
    arbiters.num += 1
    cpSpaceStampArbiter(space, arb)
    return 1
# Whether any collision handler of the space acts in one of these phases.
cdef bint cpSpaceHasHandlers(cpSpace *space, bint begin, bint preSolve,
                             bint postSolve, bint separate) noexcept nogil
cdef cpBool cpSpaceArbiterSetFilter(void *arb, void *space) noexcept nogil
# cpShapeCacheBB as a spatial-index iterator.
cdef void cpShapeUpdateFunc(void *shape, void *unused) noexcept nogil

# -- the rejection of a pair (inline) ------------------------------------------------------
cdef inline cpBool QueryRejectConstraint(cpBody *a, cpBody *b) noexcept nogil:
    cdef cpConstraint *constraint = a.constraintList
    while constraint != NULL:
        if (not constraint.collideBodies and (
                (constraint.a == a and constraint.b == b)
                or (constraint.a == b and constraint.b == a))):
            return 1
        constraint = cpConstraintNext(constraint, a)
    return 0

# The boxes are compared `margin` apart (the soft solver's speculative
# distance; 0 in the chipmunk solver, where b + 0.0 is b and the test is
# Munk2D's).
cdef inline cpBool BBsWithin(cpBB a, cpBB b, cpFloat margin) noexcept nogil:
    return (a.l <= b.r + margin and b.l <= a.r + margin
            and a.b <= b.t + margin and b.b <= a.t + margin)

cdef inline cpBool QueryReject(cpShape *a, cpShape *b, cpFloat margin) noexcept nogil:
    return (not BBsWithin(a.bb, b.bb, margin)
            or a.body == b.body
            or cpShapeFilterReject(a.filter, b.filter)
            or QueryRejectConstraint(a.body, b.body))

# The margin of a pair (the soft solver's speculative distance, plus, for
# continuous collision, how far the pair closes in this step) and whether
# the broad phase's pair is rejected before the narrow phase.
cdef inline cpBool cpSpaceRejectPair(cpSpace *space, cpShape *a, cpShape *b,
                                     cpFloat *margin_out) noexcept nogil:
    cdef cpFloat margin = space.collideMargin
    cdef cpVect dv
    cdef cpFloat closing
    cdef bint widened
    margin_out[0] = margin
    if margin == 0.0:
        return QueryReject(a, b, margin)
    widened = (a.body.m_inv == 0.0 or b.body.m_inv == 0.0
               or a.body.isBullet or b.body.isBullet)
    if not widened and not BBsWithin(a.bb, b.bb, margin):
        return 1    # (most pairs of a falling pile: their tree boxes reach ahead)
    if widened:
        # The soft solver's continuous collision: against static and
        # kinematic shapes (and for bullets, against anything) the
        # speculative contact also reaches as far as the pair closes in
        # this step, so a fast body stops at the surface instead of passing
        # through. Between two plain dynamic bodies the speculative distance
        # alone, as Box2D: the broad phase and the narrow phase stay cheap
        # in piles.
        dv = cpvsub(b.body.v, a.body.v)
        closing = sqrt(cpvlengthsq(dv)) * space.curr_dt
        if a.body.m_inv == 0.0 or b.body.m_inv == 0.0:
            # At least the tree's static reach (the fastest body's travel,
            # with room): a body at rest may be knocked toward a wall
            # within the step.
            closing = fmax(closing, cpBBTreeGetStaticReach(space.dynamicShapes))
        margin += closing
    margin_out[0] = margin
    return QueryReject(a, b, margin)


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
# bodies' solverIndex); `islands` (NULL, or room for three times that, 3 n +
# 3) keeps the components between steps (see _keepIslands). Returns 0, or
# 1 where it skipped the flood fill, 2 where the kept components did.
cdef int cpSpaceProcessComponents(cpSpace *space, cpFloat dt, int count, bint threaded,
                                  int *links, int *islands) noexcept nogil

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
cdef cpBody *tamias_first_non_finite_unawake(cpSpace *space) noexcept nogil
# After a step that overflowed, drop the non-finite warm-start impulses.
cdef void _forgetNonFiniteImpulses(cpSpace *space) noexcept nogil

cdef struct OrphanScan:
    cpSpace *space
    cpBody *bad      # the first orphan whose mass or moment cannot be inverted
    cpBody *nonFinite  # the first orphan with a non-finite state
    int orphans      # shapes seen whose body is an orphan (see _orphanBody)

# A spatial-index iterator filling an OrphanScan.
cdef void _scanOrphans(void *obj, void *data) noexcept nogil
