"""The chipmunk solver's step: Munk2D's cpSpaceStep.c and the space side of
cpSpaceComponent.c (contact graph, sleeping).

``cpSpaceStep`` reads as the pipeline of named stages listed in
``_space_step.pxd``. Everything here is C (``noexcept nogil``); the only
way into Python is through the callbacks the Python layer installs (collision
handlers, Python integrators, post-step callbacks), which take the GIL
themselves. The world (cpSpace.c) and the ``Space`` class are in
``space.pyx``; the queries in ``_space_query.pyx``; the contact solver of one
arbiter in ``arbiter.pyx`` and the joints' in ``constraints.pyx``.
"""
from libc.math cimport INFINITY, pow
from libc.string cimport memcpy, memset

from tamias2d._config cimport (cpFloat, cpBool, cpHashValue, cpCollisionID, cpTimestamp,
    CP_HASH_PAIR, CP_MAX_CONTACTS_PER_ARBITER, CP_BUFFER_BYTES, tamias_prefetch)
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArbiter, cpContact, cpArray, cpCollisionHandler,
    cpCollisionInfo, cpContactBufferHeader, cpPostStepCallback, cpPostStepFunc,
    cpConstraint, cpBodyType, cpSpatialIndex,
    CP_BODY_TYPE_DYNAMIC, CP_BODY_TYPE_KINEMATIC, CP_BODY_TYPE_STATIC,
    CP_ARBITER_STATE_FIRST_COLLISION, CP_ARBITER_STATE_NORMAL,
    CP_ARBITER_STATE_IGNORE, CP_ARBITER_STATE_CACHED)
from tamias2d._containers cimport (cpcalloc, cpfree, cpArrayPush, cpArrayPop,
    cpArrayDeleteObj, cpArrayContains, cpHashSetInsert, cpHashSetFind, cpHashSetEach,
    cpHashSetFilter, cpHashSetCount)
from tamias2d._spatialindex cimport (cpSpatialIndexEach, cpSpatialIndexInsert, cpSpatialIndexRemove,
    cpSpatialIndexReindexQuery)
from tamias2d.vector cimport cpVect, cpvlengthsq
from tamias2d.body cimport (cpBodyActivate, cpBodyGetType, cpBodyIsSleeping,
    cpBodyKineticEnergy, tamias_BodySpaceHooks, tamias_set_body_space_hooks)
from tamias2d.shape cimport cpShapeCacheBB
from tamias2d.collision cimport cpCollide
from tamias2d._bbtree cimport cpBBTreeSetStaticReach
from tamias2d.arbiter cimport (cpArbiterInit, cpArbiterUpdate, cpArbiterPreStep,
    cpArbiterApplyCachedImpulse, cpArbiterApplyImpulse, cpArbiterUnthread, cpCollisionDoNothing,
    cpArbiterPushThreads)
from tamias2d.constraints cimport tamias_constraint_clear_impulse
from tamias2d._private cimport (cpArbiterThreadForBody, cpArbiterNext, cpConstraintNext,
    cpSpaceArrayForBodyType, cpSpaceUncacheArbiter, cpCallHandlers, cpSpaceStampArbiter,
    PHASE_BEGIN, PHASE_PRE_SOLVE, PHASE_POST_SOLVE, PHASE_SEPARATE)


if sizeof(cpContactBufferHeader) != 24 or sizeof(cpContact) != 96:  # pragma: no cover
    raise ImportError("tamias2d._space_step: unexpected contact struct sizes")


cdef void cpShapeUpdateFunc(void *shape, void *unused) noexcept nogil:
    cpShapeCacheBB(<cpShape *>shape)


# -- post-step callbacks and locking (cpSpaceStep.c) ------------------------------------------

cdef cpPostStepCallback *cpSpaceGetPostStepCallback(cpSpace *space, void *key) noexcept nogil:
    cdef cpArray *arr = space.postStepCallbacks
    cdef int i
    cdef cpPostStepCallback *callback
    for i in range(arr.num):
        callback = <cpPostStepCallback *>arr.arr[i]
        if callback != NULL and callback.key == key:
            return callback
    return NULL

cdef void PostStepDoNothing(cpSpace *space, void *obj, void *data) noexcept nogil:
    pass

cdef cpBool cpSpaceAddPostStepCallback(cpSpace *space, cpPostStepFunc func, void *key,
                                       void *data) noexcept nogil:
    cdef cpPostStepCallback *callback
    if cpSpaceGetPostStepCallback(space, key) == NULL:
        callback = <cpPostStepCallback *>cpcalloc(1, sizeof(cpPostStepCallback))
        if callback == NULL:
            return 0
        callback.func = func if func != NULL else PostStepDoNothing
        callback.key = key
        callback.data = data
        if not cpArrayPush(space.postStepCallbacks, callback):
            cpfree(callback)
            return 0
        return 1
    return 0

cdef void cpSpaceLock(cpSpace *space) noexcept nogil:
    space.locked += 1

cdef void cpSpaceUnlock(cpSpace *space, cpBool runPostStep) noexcept nogil:
    cdef cpArray *waking
    cdef cpArray *arr
    cdef int i, count
    cdef cpPostStepCallback *callback
    cdef cpPostStepFunc func
    space.locked -= 1
    if space.locked == 0:
        waking = space.rousedBodies
        count = waking.num
        for i in range(count):
            cpSpaceActivateBody(space, <cpBody *>waking.arr[i])
            waking.arr[i] = NULL
        waking.num = 0

        if space.locked == 0 and runPostStep and not space.skipPostStep:
            space.skipPostStep = 1
            arr = space.postStepCallbacks
            i = 0
            while i < arr.num:
                callback = <cpPostStepCallback *>arr.arr[i]
                func = callback.func
                # Cleared first in case the callback runs the callbacks again.
                callback.func = NULL
                if func != NULL:
                    func(space, callback.key, callback.data)
                arr.arr[i] = NULL
                cpfree(callback)
                i += 1
            arr.num = 0
            space.skipPostStep = 0


# -- contact buffers -------------------------------------------------------------------------

cdef cpContactBufferHeader *cpSpaceAllocContactBuffer(cpSpace *space) noexcept nogil:
    cdef cpContactBuffer *buffer = <cpContactBuffer *>cpcalloc(1, sizeof(cpContactBuffer))
    if buffer == NULL:
        return NULL
    if not cpArrayPush(space.allocatedBuffers, buffer):
        cpfree(buffer)
        return NULL
    return <cpContactBufferHeader *>buffer

cdef cpContactBufferHeader *cpContactBufferHeaderInit(cpContactBufferHeader *header,
        cpTimestamp stamp, cpContactBufferHeader *splice) noexcept nogil:
    header.stamp = stamp
    header.next = splice.next if splice != NULL else header
    header.numContacts = 0
    return header

cdef void cpSpacePushFreshContactBuffer(cpSpace *space) noexcept nogil:
    cdef cpTimestamp stamp = space.stamp
    cdef cpContactBufferHeader *head = space.contactBuffersHead
    cdef cpContactBufferHeader *tail
    cdef cpContactBufferHeader *buffer
    if head == NULL:
        buffer = cpSpaceAllocContactBuffer(space)
        if buffer != NULL:
            space.contactBuffersHead = cpContactBufferHeaderInit(buffer, stamp, NULL)
    elif <cpTimestamp>(stamp - head.next.stamp) > space.collisionPersistence:
        # The oldest buffer of the ring has expired: reuse it.
        tail = head.next
        space.contactBuffersHead = cpContactBufferHeaderInit(tail, stamp, tail)
    else:
        buffer = cpSpaceAllocContactBuffer(space)
        if buffer != NULL:
            buffer = cpContactBufferHeaderInit(buffer, stamp, head)
            head.next = buffer
            space.contactBuffersHead = buffer
        # Out of memory: keep filling the current head (the caller checks room).

cdef cpContact *cpContactBufferGetArray(cpSpace *space) noexcept nogil:
    cdef cpContactBufferHeader *head
    if (space.contactBuffersHead == NULL or space.contactBuffersHead.numContacts
            + CP_MAX_CONTACTS_PER_ARBITER > CP_CONTACTS_BUFFER_SIZE):
        # The next collision could overflow this buffer: start a fresh one.
        cpSpacePushFreshContactBuffer(space)
    head = space.contactBuffersHead
    if head == NULL or head.numContacts + CP_MAX_CONTACTS_PER_ARBITER > CP_CONTACTS_BUFFER_SIZE:
        return NULL  # out of memory
    return (<cpContactBuffer *>head).contacts + head.numContacts


# -- collision detection ------------------------------------------------------------------------

cdef void *cpSpaceArbiterSetTrans(const void *ptr, void *data) noexcept nogil:
    cdef cpShape **shapes = <cpShape **>ptr
    cdef cpSpace *space = <cpSpace *>data
    cdef int count, i
    cdef cpArbiter *buffer
    if space.pooledArbiters.num == 0:
        # The pool is empty: carve a fresh 32 KiB block into arbiters.
        count = CP_BUFFER_BYTES // sizeof(cpArbiter)
        buffer = <cpArbiter *>cpcalloc(1, CP_BUFFER_BYTES)
        if buffer == NULL:
            return NULL
        if not cpArrayPush(space.allocatedBuffers, buffer):
            cpfree(buffer)
            return NULL
        for i in range(count):
            cpArrayPush(space.pooledArbiters, buffer + i)
        if space.pooledArbiters.num == 0:
            return NULL
    return cpArbiterInit(<cpArbiter *>cpArrayPop(space.pooledArbiters), shapes[0], shapes[1])

# The broad phase callback: narrow phase, arbiter lookup, handlers.
cdef cpCollisionID cpSpaceCollideShapes(void *obj_a, void *obj_b, cpCollisionID id,
                                        void *data) noexcept nogil:
    cdef cpShape *a = <cpShape *>obj_a
    cdef cpShape *b = <cpShape *>obj_b
    cdef cpSpace *space = <cpSpace *>data
    cdef cpContact *contacts
    cdef cpCollisionInfo info
    cdef cpFloat margin
    if cpSpaceRejectPair(space, a, b, &margin):
        return id

    contacts = cpContactBufferGetArray(space)
    if contacts == NULL:
        return id  # out of memory: the flag is up, the pair is skipped
    info = cpCollide(a, b, id, contacts, margin)
    if info.count == 0:
        return info.id
    cpSpacePushContacts(space, info.count)
    cpSpaceAcceptCollision(space, a, b, &info, NULL, 0, -1)
    return info.id

# What follows the narrow phase for a pair that touches (its contacts pushed
# on the space's contact buffer): the persistent arbiter (`found` if the
# caller looked it up already, else looked up or made here), begin and
# pre-solve callbacks, the arbiter into this step's list. `updated`: the
# caller ran cpArbiterUpdate on `found` already, which it does only when no
# handler acts on begin or pre-solve. `solid`: cpSpacePairIsSolid of the
# pair, when the caller knows it (it can only change in a callback, and none
# ran: `updated`), else -1. Returns the arbiter (NULL out of memory).
cdef cpArbiter *cpSpaceAcceptCollision(cpSpace *space, cpShape *a, cpShape *b,
                                       cpCollisionInfo *info, cpArbiter *found,
                                       bint updated, int solid) noexcept nogil:
    cdef const cpShape *shape_pair[2]
    cdef cpHashValue arbHashID
    cdef cpArbiter *arb

    # The persistent arbiter of the pair, keyed by the two shape pointers.
    shape_pair[0] = info.a
    shape_pair[1] = info.b
    arb = found
    if arb == NULL:
        arbHashID = CP_HASH_PAIR(<cpHashValue>info.a, <cpHashValue>info.b)
        arb = <cpArbiter *>cpHashSetInsert(space.cachedArbiters, arbHashID, shape_pair,
                                           cpSpaceArbiterSetTrans, space)
        if arb != NULL:
            arb.cached = 1      # (a `found` arbiter came from the cache: set already)
    if arb == NULL or arb.stamp == space.stamp:
        # (Or the pair was handled already in this step: the spatial hash
        # reports a pair again when a callback runs a query in the middle of
        # its pass, as a query moves the hash's stamp on. Munk2D pushes the
        # arbiter twice; threaded twice, it makes the flood fill loop.)
        cpSpacePopContacts(space, info.count)
        return arb
    if not updated:
        cpArbiterUpdate(arb, info, space)
        if arb.state == CP_ARBITER_STATE_FIRST_COLLISION:
            cpCallHandlers(arb, space, PHASE_BEGIN, True)
        cpCallHandlers(arb, space, PHASE_PRE_SOLVE, True)
    # (Else no handler acts on begin or pre-solve, see `updated`: the calls
    # would only flip `swapped` an even number of times.)

    if cpArbiterIsSolved(arb, solid > 0 or (solid < 0 and cpSpacePairIsSolid(a, b))):
        if not cpArrayPush(space.arbiters, arb):
            pass  # out of memory: the flag is up, the pair goes unsolved
    else:
        cpSpacePopContacts(space, info.count)
        arb.contacts = NULL
        arb.count = 0
        # Rejected, sensor and infinite-mass arbiters skip post-solve; mark
        # them used here instead.
        if arb.state != CP_ARBITER_STATE_IGNORE:
            arb.state = CP_ARBITER_STATE_NORMAL

    cpSpaceStampArbiter(space, arb)
    return arb

# Per-step filter of the arbiter cache: separate callbacks and expiry.
cdef cpBool cpSpaceArbiterSetFilter(void *elt, void *data) noexcept nogil:
    cdef cpArbiter *arb = <cpArbiter *>elt
    cdef cpSpace *space = <cpSpace *>data
    cdef cpTimestamp ticks = space.stamp - arb.stamp
    cdef cpBody *a = arb.body_a
    cdef cpBody *b = arb.body_b

    # Keep arbiters between static or sleeping bodies untouched.
    if ((cpBodyGetType(a) == CP_BODY_TYPE_STATIC or cpBodyIsSleeping(a))
            and (cpBodyGetType(b) == CP_BODY_TYPE_STATIC or cpBodyIsSleeping(b))):
        return 1

    # Touched last step but not this one: the shapes separated.
    if ticks >= 1 and arb.state != CP_ARBITER_STATE_CACHED:
        arb.state = CP_ARBITER_STATE_CACHED
        cpCallHandlers(arb, space, PHASE_SEPARATE, True)

    if ticks >= space.collisionPersistence:
        arb.contacts = NULL
        arb.count = 0
        cpArrayPush(space.pooledArbiters, arb)
        arb.cached = 0
        if ticks >= 1:
            # Not in this step's arbiter array: forget the shapes (see
            # cachedArbitersFilter).
            arb.a = NULL
            arb.b = NULL
        return 0
    return 1


# -- the step: a pipeline of named stages (cpSpaceStep) -----------------------------------------
# cpSpaceStep is the chipmunk solver's pipeline. Each stage is a function of
# its own, declared in _space_step.pxd, so that another solver can be another
# list of stages that reuses the ones it shares (collision, components, the
# arbiter cache, callbacks) instead of a fork of this file. The stages keep
# Munk2D's order and arithmetic exactly: that order is what makes the
# Gauss-Seidel solver give pymunk's bits.

cdef void cpSpaceStep(cpSpace *space, cpFloat dt) noexcept nogil:
    if dt == 0.0:
        return
    space.stamp += 1
    space.arbitersStamped = 0
    cdef cpFloat prev_dt = space.curr_dt
    space.curr_dt = dt
    cdef int collided
    # Touching contacts only, as Munk2D (the soft solver widens it, and
    # reaches further into the static tree).
    space.collideMargin = 0.0
    cpBBTreeSetStaticReach(space.dynamicShapes, 0.0)

    StageResetArbiters(space)
    cpSpaceLock(space)
    StageIntegratePositions(space, dt)
    StageCollide(space)
    # A callback of the collide stage may have woken sleeping bodies; the
    # unlock activates them and appends their arbiters, which stayed
    # threaded in the contact graph while they slept. Only the arbiters
    # found by the collide stage are threaded again (Munk2D threads both: a
    # loop in a body's arbiter list, and the next flood fill never ends).
    collided = space.arbiters.num
    cpSpaceUnlock(space, 0)

    cpSpaceProcessComponents(space, dt, collided, 0, NULL, NULL)

    cpSpaceLock(space)
    StageFilterArbiterCache(space)
    StagePreStep(space, dt)
    StageIntegrateVelocities(space, dt)
    StageWarmStart(space, dt, prev_dt)
    StageSolve(space, dt)
    StagePostSolve(space)
    # Unlocking runs the post-step callbacks.
    cpSpaceUnlock(space, 1)

# Last step's arbiters go back to normal; those between awake bodies are
# taken out of the contact graph (the components stage threads them again).
cdef int StageResetArbiters(cpSpace *space) noexcept nogil:
    # Returns how many stay threaded, having a sleeping body (the soft
    # step's union-find of the components needs none: SoftResetArbiters).
    cdef cpArray *arbiters = space.arbiters
    cdef cpArbiter *arb
    cdef int i, kept = 0
    for i in range(arbiters.num):
        arb = <cpArbiter *>arbiters.arr[i]
        arb.state = CP_ARBITER_STATE_NORMAL
        if not cpBodyIsSleeping(arb.body_a) and not cpBodyIsSleeping(arb.body_b):
            cpArbiterUnthread(arb)
        else:
            kept += 1
    arbiters.num = 0
    return kept

cdef void StageIntegratePositions(cpSpace *space, cpFloat dt) noexcept nogil:
    cdef cpArray *bodies = space.dynamicBodies
    cdef cpBody *body
    cdef int i
    for i in range(bodies.num):
        body = <cpBody *>bodies.arr[i]
        body.position_func(body, dt)

# Broad and narrow phase in one pass: refresh the dynamic shapes' boxes, then
# the dynamic index reports every candidate pair to cpSpaceCollideShapes
# (narrow phase, arbiter lookup, begin and pre-solve callbacks).
cdef void StageCollide(cpSpace *space) noexcept nogil:
    cpSpacePushFreshContactBuffer(space)
    cpSpatialIndexEach(space.dynamicShapes, cpShapeUpdateFunc, NULL)
    cpSpatialIndexReindexQuery(space.dynamicShapes, cpSpaceCollideShapes, space)

# Separate callbacks for pairs no longer touching; expired arbiters return
# to the pool.
# Off only in tests, which check that skipping the filter changes nothing.
cdef bint _skip_idle_filter = 1

cdef void StageFilterArbiterCache(cpSpace *space) noexcept nogil:
    # Not when every cached arbiter was touched in this step (a pile at
    # rest): the filter would neither separate nor expire any of them.
    if (_skip_idle_filter and space.collisionPersistence > 0
            and space.arbitersStamped == <int>cpHashSetCount(space.cachedArbiters)):
        return
    cpHashSetFilter(space.cachedArbiters, cpSpaceArbiterSetFilter, space)

cdef void StagePreStep(cpSpace *space, cpFloat dt) noexcept nogil:
    cdef cpArray *arbiters = space.arbiters
    cdef cpArray *constraints = space.constraints
    cdef cpConstraint *constraint
    cdef cpFloat slop = space.collisionSlop
    cdef cpFloat biasCoef = 1.0 - pow(space.collisionBias, dt)
    cdef int i
    for i in range(arbiters.num):
        cpArbiterPreStep(<cpArbiter *>arbiters.arr[i], dt, slop, biasCoef)
    for i in range(constraints.num):
        constraint = <cpConstraint *>constraints.arr[i]
        if constraint.preSolve != NULL:
            constraint.preSolve(constraint, space)
        constraint.klass.preStep(constraint, dt)

cdef void StageIntegrateVelocities(cpSpace *space, cpFloat dt) noexcept nogil:
    cdef cpArray *bodies = space.dynamicBodies
    cdef cpFloat damping = pow(space.damping, dt)
    cdef cpVect gravity = space.gravity
    cdef cpBody *body
    cdef int i
    for i in range(bodies.num):
        body = <cpBody *>bodies.arr[i]
        body.velocity_func(body, gravity, damping, dt)

# Warm start from last step's impulses, scaled by dt / prev_dt (never on the
# first step).
cdef void StageWarmStart(cpSpace *space, cpFloat dt, cpFloat prev_dt) noexcept nogil:
    cdef cpArray *arbiters = space.arbiters
    cdef cpArray *constraints = space.constraints
    cdef cpConstraint *constraint
    cdef cpFloat dt_coef = 0.0 if prev_dt == 0.0 else dt / prev_dt
    cdef int i
    for i in range(arbiters.num):
        cpArbiterApplyCachedImpulse(<cpArbiter *>arbiters.arr[i], dt_coef)
    for i in range(constraints.num):
        constraint = <cpConstraint *>constraints.arr[i]
        constraint.klass.applyCachedImpulse(constraint, dt_coef)

# The impulse solver: `iterations` sequential passes over the arbiters, then
# the constraints.
cdef void StageSolve(cpSpace *space, cpFloat dt) noexcept nogil:
    cdef cpArray *arbiters = space.arbiters
    cdef cpArray *constraints = space.constraints
    cdef cpConstraint *constraint
    cdef int i, j
    for i in range(space.iterations):
        for j in range(arbiters.num):
            cpArbiterApplyImpulse(<cpArbiter *>arbiters.arr[j])
        for j in range(constraints.num):
            constraint = <cpConstraint *>constraints.arr[j]
            constraint.klass.applyImpulse(constraint, dt)

cdef struct HandlerSearch:
    bint begin, preSolve, postSolve, separate     # the phases asked about
    bint found

cdef inline bint _handlerActs(const cpCollisionHandler *h, const HandlerSearch *search) noexcept nogil:
    return ((search.begin and h.beginFunc != cpCollisionDoNothing)
            or (search.preSolve and h.preSolveFunc != cpCollisionDoNothing)
            or (search.postSolve and h.postSolveFunc != cpCollisionDoNothing)
            or (search.separate and h.separateFunc != cpCollisionDoNothing))

cdef void _noteHandler(void *elt, void *data) noexcept nogil:
    cdef HandlerSearch *search = <HandlerSearch *>data
    if _handlerActs(<cpCollisionHandler *>elt, search):
        search.found = 1

cdef bint cpSpaceHasHandlers(cpSpace *space, bint begin, bint preSolve,
                             bint postSolve, bint separate) noexcept nogil:
    # Whether any handler does something in one of these phases (a handful
    # of handlers to look at, against a pass over every arbiter).
    cdef HandlerSearch search
    search.begin = begin
    search.preSolve = preSolve
    search.postSolve = postSolve
    search.separate = separate
    search.found = _handlerActs(&space.globalHandler, &search)
    if not search.found:
        cpHashSetEach(space.collisionHandlers, _noteHandler, &search)
    return search.found

# Post-solve callbacks: constraints, then arbiters.
cdef void StagePostSolve(cpSpace *space) noexcept nogil:
    cdef cpArray *arbiters = space.arbiters
    cdef cpArray *constraints = space.constraints
    cdef cpConstraint *constraint
    cdef int i
    for i in range(constraints.num):
        constraint = <cpConstraint *>constraints.arr[i]
        if constraint.postSolve != NULL:
            constraint.postSolve(constraint, space)
    if not cpSpaceHasHandlers(space, 0, 0, 1, 0):
        # Nothing to call: the pass would only flip `swapped` an even number
        # of times per arbiter.
        return
    for i in range(arbiters.num):
        cpCallHandlers(<cpArbiter *>arbiters.arr[i], space, PHASE_POST_SOLVE, True)


# -- components and sleeping (cpSpaceComponent.c, space side) ---------------------------------


cdef void cpSpaceActivateBody(cpSpace *space, cpBody *body) noexcept nogil:
    cdef cpShape *shape
    cdef cpArbiter *arb
    cdef cpBody *bodyA
    cdef int numContacts
    cdef cpContact *contacts
    cdef const cpShape *shape_pair[2]
    cdef cpHashValue arbHashID
    cdef cpConstraint *constraint

    if space.locked:
        # Done again when the space unlocks.
        if not cpArrayContains(space.rousedBodies, body):
            cpArrayPush(space.rousedBodies, body)
        return

    cpArrayPush(space.dynamicBodies, body)
    # (Its arbiters join the step's array, threaded: the lists are no longer
    # the array's alone.)
    space.softScratch.threadsClean = 0
    space.softScratch.islandsStamp = 0

    shape = body.shapeList
    while shape != NULL:
        cpSpatialIndexRemove(space.staticShapes, shape, shape.hashid)
        cpSpatialIndexInsert(space.dynamicShapes, shape, shape.hashid)
        shape = shape.next

    arb = body.arbiterList
    while arb != NULL:
        bodyA = arb.body_a
        # Both bodies of an arbiter wake together; body_a owns it (or body_b
        # when body_a is static, as static bodies never sleep).
        if body == bodyA or cpBodyGetType(bodyA) == CP_BODY_TYPE_STATIC:
            numContacts = arb.count
            contacts = arb.contacts
            # Copy the contacts back from the heap into the contact buffer.
            arb.contacts = cpContactBufferGetArray(space)
            if arb.contacts != NULL:
                memcpy(arb.contacts, contacts, numContacts * sizeof(cpContact))
                cpSpacePushContacts(space, numContacts)
            else:
                arb.count = 0
            shape_pair[0] = arb.a
            shape_pair[1] = arb.b
            arbHashID = CP_HASH_PAIR(<cpHashValue>arb.a, <cpHashValue>arb.b)
            if cpHashSetInsert(space.cachedArbiters, arbHashID, shape_pair, NULL, arb) == arb:
                arb.cached = 1
            cpSpaceStampArbiter(space, arb)
            cpArrayPush(space.arbiters, arb)
            cpfree(contacts)
        arb = cpArbiterNext(arb, body)

    _pushOwnedConstraints(space, body)

# The joints a body owns (it is their body a, or their body a is static) go
# back into the solver's array as the body wakes.
cdef void _pushOwnedConstraints(cpSpace *space, cpBody *body) noexcept nogil:
    cdef cpConstraint *constraint = body.constraintList
    cdef cpBody *bodyA
    while constraint != NULL:
        bodyA = constraint.a
        if body == bodyA or cpBodyGetType(bodyA) == CP_BODY_TYPE_STATIC:
            cpArrayPush(space.constraints, constraint)
        constraint = cpConstraintNext(constraint, body)

cdef void cpSpaceDeactivateBody(cpSpace *space, cpBody *body) noexcept nogil:
    cdef cpShape *shape
    cdef cpArbiter *arb
    cdef cpBody *bodyA
    cdef size_t count
    cdef cpContact *contacts
    cdef cpConstraint *constraint

    cpArrayDeleteObj(space.dynamicBodies, body)
    space.softScratch.threadsClean = 0
    space.softScratch.islandsStamp = 0

    shape = body.shapeList
    while shape != NULL:
        cpSpatialIndexRemove(space.dynamicShapes, shape, shape.hashid)
        cpSpatialIndexInsert(space.staticShapes, shape, shape.hashid)
        shape = shape.next

    arb = body.arbiterList
    while arb != NULL:
        bodyA = arb.body_a
        if body == bodyA or cpBodyGetType(bodyA) == CP_BODY_TYPE_STATIC:
            cpSpaceUncacheArbiter(space, arb)
            # Keep the contacts on the heap so that the buffer ring cannot
            # recycle them while the body sleeps.
            count = arb.count
            contacts = <cpContact *>cpcalloc(count if count > 0 else 1, sizeof(cpContact))
            if contacts != NULL:
                memcpy(contacts, arb.contacts, count * sizeof(cpContact))
            else:
                arb.count = 0
            arb.contacts = contacts
        arb = cpArbiterNext(arb, body)

    constraint = body.constraintList
    while constraint != NULL:
        bodyA = constraint.a
        if body == bodyA or cpBodyGetType(bodyA) == CP_BODY_TYPE_STATIC:
            cpArrayDeleteObj(space.constraints, constraint)
        constraint = cpConstraintNext(constraint, body)

cdef inline cpBody *ComponentRoot(cpBody *body) noexcept nogil:
    return body.sleeping.root if body != NULL else NULL

cdef inline void ComponentAdd(cpBody *root, cpBody *body) noexcept nogil:
    body.sleeping.root = root
    if body != root:
        body.sleeping.next = root.sleeping.next
        root.sleeping.next = body

cdef int FloodFillComponent(cpBody *root, cpBody *body) noexcept nogil:
    # Kinematic bodies never sleep and keep what they touch awake; static
    # bodies are asleep all the time; orphans (see _orphanBody) are left out.
    # Recursive as in Munk2D. Returns how many bodies outside the space
    # (held by joints) joined the component.
    cdef cpBody *other_root
    cdef cpArbiter *arb
    cdef cpConstraint *constraint
    cdef int outside = 0
    if cpBodyGetType(body) == CP_BODY_TYPE_DYNAMIC and not _orphanBody(body, root.space):
        other_root = ComponentRoot(body)
        if other_root == NULL:
            ComponentAdd(root, body)
            if body.space != root.space:
                outside = 1
            arb = body.arbiterList
            while arb != NULL:
                outside += FloodFillComponent(root, arb.body_b if body == arb.body_a else arb.body_a)
                arb = cpArbiterNext(arb, body)
            constraint = body.constraintList
            while constraint != NULL:
                outside += FloodFillComponent(root, constraint.b if body == constraint.a
                                              else constraint.a)
                constraint = cpConstraintNext(constraint, body)
    return outside

# A component that stays awake: its bodies in the space lose their links as
# the component loop passes them, but a body outside the space is in no
# array and keeps them (Munk2D keeps the root and the next body, which may
# later leave the space and be freed). The root stays non-NULL, as in
# Munk2D: the flood fill passes such a body over from then on, and the
# chipmunk solver keeps that, bit for bit. It names the body itself, which
# is always there, and the next link goes; cpBodyActivate wakes what the body
# is jointed to in its stead (body.pyx, _rootStillSleeps).
cdef void _settleOutsideMembers(cpBody *root, cpSpace *space) noexcept nogil:
    cdef cpBody *body = root
    cdef cpBody *next
    while body != NULL:
        next = body.sleeping.next
        if body.space != space:
            body.sleeping.root = body
            body.sleeping.next = NULL
        body = next

# Kept awake this step: a body that touches a kinematic body (in the space or
# not: one outside it kept the sleeping body's arbiter on its own list, a
# stale thread, found by the sleeping fuzzer's seeds 2016 and others), is
# jointed to a kinematic body of the space, or touches an orphan body (its
# arbiter's body_a or, since stop 40, body_b: the sleeping fuzzer's seed
# 2466 put a body to sleep with the arbiter, left threaded on the orphan's
# list, out of the step's array). The arbiter or joint then stays with the
# other body, which stays awake; were this body to sleep, the next step would
# thread that arbiter into its list a second time (a loop: the flood fill
# never ends).
# Munk2D keeps such a body awake by waking it, which restarts its idle time at
# 0; with a sleep_time_threshold <= 0 that is idle enough, and the body sleeps
# anyway (pymunk aborts there, on the kinematic body's own component, or goes
# on with the arbiter threaded twice). So at such a threshold the body's idle
# time is -inf for this step: its component stays active, and the mark is
# reset to 0 before the step ends. Idle times are >= 0 otherwise, so nothing
# else holds the mark; at a threshold > 0 this is never called.
cdef inline void _holdAwake(cpBody *body, cpSpace *space) noexcept nogil:
    if (body.space == space and cpBodyGetType(body) == CP_BODY_TYPE_DYNAMIC
            and not cpBodyIsSleeping(body)):
        body.sleeping.idleTime = -INFINITY

cdef void _holdAwakeTouching(cpSpace *space, int threadCount) noexcept nogil:
    cdef cpArray *arbiters = space.arbiters
    cdef cpArray *constraints = space.constraints
    cdef cpArbiter *arb
    cdef cpConstraint *constraint
    cdef cpBody *a
    cdef cpBody *b
    cdef int i
    for i in range(threadCount):
        arb = <cpArbiter *>arbiters.arr[i]
        a = arb.body_a
        b = arb.body_b
        if cpBodyGetType(b) == CP_BODY_TYPE_KINEMATIC or _orphanBody(b, space):
            _holdAwake(a, space)
        if cpBodyGetType(a) == CP_BODY_TYPE_KINEMATIC or _orphanBody(a, space):
            _holdAwake(b, space)
    for i in range(constraints.num):
        constraint = <cpConstraint *>constraints.arr[i]
        a = constraint.a
        b = constraint.b
        if cpBodyGetType(b) == CP_BODY_TYPE_KINEMATIC and b.space == space:
            _holdAwake(a, space)
        if cpBodyGetType(a) == CP_BODY_TYPE_KINEMATIC and a.space == space:
            _holdAwake(b, space)

cdef cpBool _componentNonFinite(cpBody *root) noexcept nogil:
    # A component with a non-finite body stays awake, where the step's
    # overflow check sees it (a NaN speed reads as idle, and at a threshold
    # of 0 everything sleeps: the body slept, unnamed, with its NaN).
    cdef cpBody *body = root
    while body != NULL:
        if _bodyNonFinite(body):
            return 1
        body = body.sleeping.next
    return 0

cdef inline cpBool ComponentActive(cpBody *root, cpFloat threshold) noexcept nogil:
    cdef cpBody *body = root
    while body != NULL:
        if body.sleeping.idleTime < threshold:
            return 1
        body = body.sleeping.next
    return 0

cdef inline void _fetchSleepLines(const cpBody *body) noexcept nogil:
    # The lines of a body that the components stage reads (besides its
    # velocity): its mass, its space, sleeping links, idle time and
    # solverIndex.
    tamias_prefetch(&body.m)
    tamias_prefetch(&body.sleeping.root)
    tamias_prefetch(&body.solverIndex)

# The soft step's shortcut past the flood fill (cpSpaceProcessComponents with
# a `links` array): the components found by union-find over the step's
# arbiter array and the bodies' joints, with each body's slot in
# space.dynamicBodies (+ 1) in its solverIndex. Only where the flood fill
# would see the same graph: every body awake and in the space, the bodies'
# arbiter lists exactly the array (cpSoftScratch.threadsClean).
cdef inline int _linkRoot(int *parent, int i) noexcept nogil:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i

cdef inline int _linkSlot(cpSpace *space, const cpBody *body, int n) noexcept nogil:
    # body's slot, or 0 if it is not one of the first n dynamic bodies.
    cdef int i = body.solverIndex
    if 0 < i <= n and space.dynamicBodies.arr[i - 1] == body:
        return i
    return 0

cdef inline bint _linkBodies(cpSpace *space, int *parent, const cpBody *a, const cpBody *b,
                             int n) noexcept nogil:
    # Joins a's and b's components where the flood fill would cross from one
    # to the other (both dynamic); 0 if one of them has no slot.
    cdef int ia, ib
    if cpBodyGetType(a) != CP_BODY_TYPE_DYNAMIC or cpBodyGetType(b) != CP_BODY_TYPE_DYNAMIC:
        return 1
    ia = _linkSlot(space, a, n)
    ib = _linkSlot(space, b, n)
    if ia == 0 or ib == 0:
        return 0
    ia = _linkRoot(parent, ia)
    ib = _linkRoot(parent, ib)
    if ia < ib:
        parent[ib] = ia
    elif ib < ia:
        parent[ia] = ib
    return 1

cdef bint _everyComponentActive(cpSpace *space, int *parent, int n) noexcept nogil:
    # With the arbiters linked: links the joints, then tells whether every
    # component has a body whose idle time is under the threshold (0 also
    # where a joint leads out of the first n dynamic bodies).
    cdef int *restless = parent + n + 1
    cdef cpBody *body
    cdef cpConstraint *constraint
    cdef int i
    for i in range(1, n + 1):
        if i + 4 <= n:
            _fetchSleepLines(<cpBody *>space.dynamicBodies.arr[i + 3])
        body = <cpBody *>space.dynamicBodies.arr[i - 1]
        # (Kinematic bodies never sleep nor join a component.)
        restless[i] = (cpBodyGetType(body) != CP_BODY_TYPE_DYNAMIC
                       or body.sleeping.idleTime < space.sleepTimeThreshold)
        constraint = body.constraintList
        while constraint != NULL:
            if not _linkBodies(space, parent, constraint.a, constraint.b, n):
                return 0
            constraint = cpConstraintNext(constraint, body)
    for i in range(1, n + 1):
        if restless[i]:
            restless[_linkRoot(parent, i)] = 1
    for i in range(1, n + 1):
        if parent[i] == i and not restless[i]:
            return 0
    return 1

# The soft step's persistent islands: the components of the last union-find
# that found every one active, kept for the next step in `islands` (3 n + 3
# ints for n dynamic bodies): each slot's root (0: not dynamic), then the
# roots, then the slots that the arbiters' pass activated (a dynamic body
# touching a kinematic or orphan one) in order. A step whose arbiter array
# is the last step's (its threads kept: SoftRethreadArbiters), with the same
# bodies and joints and nothing woken or put to sleep, has the same graph:
# it marks the roots of the bodies that are not idle as it updates the idle
# times, activates those slots again, and asks only whether every root is
# marked, without reading the arbiters. Any other step does the union-find
# and may keep its result.

cdef inline void _markIsland(cpSpace *space, const int *islands, int *restless,
                             const cpBody *body, int n) noexcept nogil:
    # After an activation: the body's component is not idle.
    cdef int i = _linkSlot(space, body, n)
    if i != 0:
        restless[islands[i]] = 1

cdef inline bint _recordWake(cpSpace *space, int *islands, int *wakes, const cpBody *body,
                             int n) noexcept nogil:
    # The arbiters' pass activated body (no change unless dynamic): noted
    # for the next step, 0 where it cannot be (no slot, or the list full).
    cdef int i
    if cpBodyGetType(body) != CP_BODY_TYPE_DYNAMIC:
        return 1
    i = _linkSlot(space, body, n)
    if i == 0 or wakes[0] > n:
        return 0
    islands[2 * (n + 1) + wakes[0]] = i
    wakes[0] += 1
    return 1

cdef void _keepIslands(cpSpace *space, int *parent, int *islands, int n, int wakes) noexcept nogil:
    # The union-find's components (every one active) kept for the next step.
    cdef int *roots = islands + n + 1
    cdef int i, count = 0
    islands[0] = 0
    for i in range(1, n + 1):
        if cpBodyGetType(<cpBody *>space.dynamicBodies.arr[i - 1]) != CP_BODY_TYPE_DYNAMIC:
            islands[i] = 0
        else:
            islands[i] = _linkRoot(parent, i)
            if islands[i] == i:
                roots[count] = i
                count += 1
    space.softScratch.islandCount = count
    space.softScratch.islandWakes = wakes
    space.softScratch.islandBodies = n
    space.softScratch.islandsStamp = space.stamp

cdef inline bint _islandsActive(cpSpace *space, const int *islands, const int *restless,
                                int n) noexcept nogil:
    cdef const int *roots = islands + n + 1
    cdef int k
    for k in range(space.softScratch.islandCount):
        if not restless[roots[k]]:
            return 0
    return 1

cdef int cpSpaceProcessComponents(cpSpace *space, cpFloat dt, int count, bint threaded,
                                  int *links, int *islands) noexcept nogil:
    # 1 where the union-find showed that the flood fill would change
    # nothing, and skipped it; 2 where the kept islands did.
    cdef cpBool sleep = space.sleepTimeThreshold != INFINITY
    cdef cpArray *bodies = space.dynamicBodies
    cdef cpArray *arbiters
    cdef cpArray *constraints
    cdef cpFloat dv, dvsq, keThreshold
    cdef int i, outside
    cdef int linked = bodies.num
    cdef cpBody *body
    cdef cpBody *a
    cdef cpBody *b
    cdef cpBody *other
    cdef cpArbiter *arb
    cdef cpConstraint *constraint
    # See _holdAwake: only where Munk2D cannot keep a body awake by waking it.
    cdef cpBool holdAwake = sleep and not (space.sleepTimeThreshold > 0.0)
    # The last step's islands hold (see _keepIslands): with links (no
    # component asleep that this step's graph could reach) and threads kept.
    cdef bint persist = (links != NULL and islands != NULL and threaded
                         and space.softScratch.islandsStamp != 0
                         and space.softScratch.islandsStamp + 1 == space.stamp
                         and space.softScratch.islandBodies == bodies.num)
    cdef int *restless = links + linked + 1 if links != NULL else NULL
    cdef int wakes = 0
    cdef bint keep = islands != NULL
    space.softScratch.islandsStamp = 0
    if persist:
        memset(restless, 0, (linked + 1) * sizeof(int))

    if sleep:
        dv = space.idleSpeedThreshold
        dvsq = dv * dv if dv != 0.0 else cpvlengthsq(space.gravity) * dt * dt
        # Update idle times.
        for i in range(bodies.num):
            if i + 4 < bodies.num:
                # (Bodies are scattered in memory: a few cache misses each
                # otherwise. Fetching changes no result.)
                _fetchSleepLines(<cpBody *>bodies.arr[i + 4])
                tamias_prefetch(&(<cpBody *>bodies.arr[i + 4]).v)
            body = <cpBody *>bodies.arr[i]
            if links != NULL:
                body.solverIndex = i + 1
                links[i + 1] = i + 1
            if cpBodyGetType(body) != CP_BODY_TYPE_DYNAMIC:
                continue
            keThreshold = body.m * dvsq if dvsq != 0.0 else 0.0
            body.sleeping.idleTime = (0.0 if cpBodyKineticEnergy(body) > keThreshold
                                      else body.sleeping.idleTime + dt)
            if persist and body.sleeping.idleTime < space.sleepTimeThreshold:
                restless[islands[i + 1]] = 1

    # Wake sleeping bodies that are touched, and thread the arbiters found
    # this step into their bodies' lists (head insertion, in array order).
    # Arbiters appended from here on, by waking, are threaded already.
    arbiters = space.arbiters
    if persist:
        # The same arbiters, bodies and kinds: the same activations.
        for i in range(space.softScratch.islandWakes):
            body = <cpBody *>bodies.arr[islands[2 * (linked + 1) + i] - 1]
            cpBodyActivate(body)
            restless[islands[body.solverIndex]] = 1
    elif sleep or not threaded:
        for i in range(count):
            if sleep and i + 16 < count:
                # What the waking reads of the arbiters and their bodies,
                # fetched ahead (both are scattered in memory).
                tamias_prefetch(&(<cpArbiter *>arbiters.arr[i + 16]).body_a)
            if sleep and i + 8 < count:
                arb = <cpArbiter *>arbiters.arr[i + 8]
                _fetchSleepLines(arb.body_a)
                _fetchSleepLines(arb.body_b)
            arb = <cpArbiter *>arbiters.arr[i]
            a = arb.body_a
            b = arb.body_b
            if sleep:
                if (cpBodyGetType(b) == CP_BODY_TYPE_KINEMATIC or cpBodyIsSleeping(a)
                        or _orphanBody(b, space)):
                    cpBodyActivate(a)
                    if keep and links != NULL:
                        keep = _recordWake(space, islands, &wakes, a, linked)
                if (cpBodyGetType(a) == CP_BODY_TYPE_KINEMATIC or cpBodyIsSleeping(b)
                        or _orphanBody(a, space)):
                    cpBodyActivate(b)
                    if keep and links != NULL:
                        keep = _recordWake(space, islands, &wakes, b, linked)
                if links != NULL and not _linkBodies(space, links, a, b, linked):
                    links = NULL
            if not threaded:
                cpArbiterPushThreads(arb)

    if sleep:
        # Bodies jointed to a kinematic body stay awake.
        constraints = space.constraints
        i = 0
        while i < constraints.num:
            constraint = <cpConstraint *>constraints.arr[i]
            a = constraint.a
            b = constraint.b
            if cpBodyGetType(b) == CP_BODY_TYPE_KINEMATIC:
                cpBodyActivate(a)
                if persist:
                    _markIsland(space, islands, restless, a, linked)
            if cpBodyGetType(a) == CP_BODY_TYPE_KINEMATIC:
                cpBodyActivate(b)
                if persist:
                    _markIsland(space, islands, restless, b, linked)
            i += 1

        if holdAwake:
            # After all the waking above, which restarts idle times at 0.
            _holdAwakeTouching(space, count)
        elif persist and space.softScratch.threadsClean == space.stamp:
            if _islandsActive(space, islands, restless, linked):
                space.softScratch.islandsStamp = space.stamp
                return 2
            # A component may fall asleep: the flood fill decides.
        elif (links != NULL and space.softScratch.threadsClean == space.stamp
                and _everyComponentActive(space, links, linked)):
            # Nothing sleeps, nothing woke, and the lists are the array's: the
            # flood fill would find every component active and change nothing.
            if keep:
                _keepIslands(space, links, islands, linked, wakes)
            return 1

        # Build the components and put the idle ones to sleep.
        i = 0
        while i < bodies.num:
            body = <cpBody *>bodies.arr[i]
            # Kinematic bodies never sleep. (Munk2D finds a kinematic body's
            # empty component idle once the threshold is <= 0, as its idle
            # time stays 0, and aborts on deactivating it; above 0 the
            # component is always active, so skipping it changes nothing.)
            if ComponentRoot(body) == NULL and cpBodyGetType(body) == CP_BODY_TYPE_DYNAMIC:
                outside = FloodFillComponent(body, body)
                if (not ComponentActive(body, space.sleepTimeThreshold)
                        and not _componentNonFinite(body)):
                    cpArrayPush(space.sleepingComponents, body)
                    other = body
                    while other != NULL:
                        cpSpaceDeactivateBody(space, other)
                        other = other.sleeping.next
                    # Deactivation swap-removed this body: same index again.
                    continue
                if outside:
                    _settleOutsideMembers(body, space)
            i += 1
            # Only sleeping bodies keep their component links.
            body.sleeping.root = NULL
            body.sleeping.next = NULL
            if body.sleeping.idleTime < 0.0:
                body.sleeping.idleTime = 0.0    # the _holdAwake mark, spent
    return 0



# -- hooks for the body module -------------------------------------------------------------------

cdef void cpSpaceWakeComponent(cpSpace *space, cpBody *root) noexcept nogil:
    cdef cpBody *bodyA = root
    cdef cpBody *next
    while bodyA != NULL:
        next = bodyA.sleeping.next
        bodyA.sleeping.idleTime = 0.0
        bodyA.sleeping.root = NULL
        bodyA.sleeping.next = NULL
        if bodyA.space == space:
            cpSpaceActivateBody(space, bodyA)
        else:
            # A body outside the space, held by a joint, joins the component
            # of the bodies it is jointed to (the flood fill follows joints).
            # Munk2D wakes it into the space's body array: the space then
            # integrates a body it does not hold, the body can become the
            # root of a sleeping component, and activate() on that root
            # dereferences its NULL space (pymunk segfaults). Only its joints
            # go back to the solver; it has no shapes here (a body with shapes
            # in the space is an orphan and never joins a component).
            _pushOwnedConstraints(space, bodyA)
        bodyA = next
    cpArrayDeleteObj(space.sleepingComponents, root)

cdef void _hookBodyTypeChanged(cpSpace *space, cpBody *body, cpBodyType oldType,
                               cpBodyType type) noexcept nogil:
    cdef cpArray *fromArray = cpSpaceArrayForBodyType(space, oldType)
    cdef cpArray *toArray = cpSpaceArrayForBodyType(space, type)
    cdef cpSpatialIndex *fromIndex
    cdef cpSpatialIndex *toIndex
    cdef cpShape *shape
    # (A kinematic body joins no component: see _keepIslands.)
    space.softScratch.islandsStamp = 0
    if fromArray != toArray:
        cpArrayDeleteObj(fromArray, body)
        cpArrayPush(toArray, body)
    fromIndex = space.staticShapes if oldType == CP_BODY_TYPE_STATIC else space.dynamicShapes
    toIndex = space.staticShapes if type == CP_BODY_TYPE_STATIC else space.dynamicShapes
    if fromIndex != toIndex:
        shape = body.shapeList
        while shape != NULL:
            cpSpatialIndexRemove(fromIndex, shape, shape.hashid)
            cpSpatialIndexInsert(toIndex, shape, shape.hashid)
            shape = shape.next

cdef void _hookSleepWithGroup(cpBody *body, cpBody *group) noexcept nogil:
    cdef cpSpace *space = body.space
    cdef cpShape *shape
    cdef cpBody *root
    cdef cpBody *other
    cdef cpBody *groupRoot
    cdef cpArbiter *arb
    cdef cpArbiter *next_arb
    if cpBodyIsSleeping(body):
        return
    shape = body.shapeList
    while shape != NULL:
        cpShapeCacheBB(shape)
        shape = shape.next
    # Forced to sleep while touching a body outside its new group: take
    # those arbiters out of the contact graph. Munk2D leaves them threaded
    # (and moves the contacts of those it owns to the heap); the next step
    # finds the contact again, threads the arbiter a second time and frees a
    # contact buffer pointer when it wakes the body. Unthreaded, the arbiter
    # is an ordinary cached one: found again, it wakes this body. A neighbour
    # asleep in another group is woken first, so that its own copy of the
    # arbiter goes back to the cache rather than staying on the heap.
    groupRoot = ComponentRoot(group)
    arb = body.arbiterList
    while arb != NULL:
        next_arb = cpArbiterNext(arb, body)
        other = arb.body_b if arb.body_a == body else arb.body_a
        if not _arbiterCached(space, arb):
            # Last step's arbiter, already expired: with a collision
            # persistence of 0 a step's arbiters leave the cache (and go back
            # to the pool) at once, threaded until the next step unthreads
            # them. A sleeping body would keep it threaded while the pool hands
            # it to another pair (pymunk hangs). The next step unthreads it
            # and drops it from the step's array anyway if the body stays
            # awake; here both happen now.
            cpArbiterUnthread(arb)
            cpArrayDeleteObj(space.arbiters, arb)
        elif (cpBodyGetType(other) != CP_BODY_TYPE_STATIC
                and (groupRoot == NULL or other.sleeping.root != groupRoot)):
            if cpBodyIsSleeping(other):
                cpBodyActivate(other)
            cpArbiterUnthread(arb)
            if cpArrayContains(space.arbiters, arb):
                # Out of the contact graph, so out of the step's array too (a
                # copy of the space checks one against the other), in the
                # state the next step would have given it there.
                cpArrayDeleteObj(space.arbiters, arb)
                arb.state = CP_ARBITER_STATE_NORMAL
        arb = next_arb
    cpSpaceDeactivateBody(space, body)
    if group != NULL:
        root = ComponentRoot(group)
        body.sleeping.root = root
        body.sleeping.next = root.sleeping.next
        body.sleeping.idleTime = 0.0
        root.sleeping.next = body
    else:
        body.sleeping.root = body
        body.sleeping.next = NULL
        body.sleeping.idleTime = 0.0
        cpArrayPush(space.sleepingComponents, body)
    cpArrayDeleteObj(space.dynamicBodies, body)

cdef cpBool _arbiterCached(cpSpace *space, cpArbiter *arb) noexcept nogil:
    cdef const cpShape *shape_pair[2]
    shape_pair[0] = arb.a
    shape_pair[1] = arb.b
    return cpHashSetFind(space.cachedArbiters, CP_HASH_PAIR(<cpHashValue>arb.a, <cpHashValue>arb.b),
                         shape_pair) == arb

cdef tamias_BodySpaceHooks _hooks
_hooks.wake_component = cpSpaceWakeComponent
_hooks.body_type_changed = _hookBodyTypeChanged
_hooks.sleep_with_group = _hookSleepWithGroup
tamias_set_body_space_hooks(&_hooks)


cdef cpBody *_firstNonFiniteBody(cpArray *bodies) noexcept nogil:
    # The setters refuse non-finite values, so only an overflow in a step can
    # make one; checked after every step (and before, while one is left).
    cdef cpBody *body
    cdef int i
    for i in range(bodies.num):
        body = <cpBody *>bodies.arr[i]
        if _bodyNonFinite(body):
            return body
    return NULL


cdef cpBody *tamias_first_non_finite_body(cpSpace *space) noexcept nogil:
    # Every body a step can change: the awake array (dynamic and kinematic
    # bodies), the static bodies (a contact or joint impulse of inf times
    # their zero inverse mass is NaN) and joints' bodies outside the space,
    # which the solver pushes but does not integrate. Sleeping bodies are not
    # touched by a step, and orphans (shapes left in the space) are found by
    # the Python side (Space._check_bodies), which knows when there may be
    # some. The static array is short and the joints cost two pointer tests.
    cdef cpBody *body = _firstNonFiniteBody(space.dynamicBodies)
    if body != NULL:
        return body
    return tamias_first_non_finite_unawake(space)


cdef cpBody *tamias_first_non_finite_unawake(cpSpace *space) noexcept nogil:
    # tamias_first_non_finite_body without the awake array: what is left to
    # check after a soft step that found every awake body finite as it wrote
    # it back (cpSoftStep).
    cdef cpBody *body = _firstNonFiniteBody(space.staticBodies)
    cdef cpConstraint *c
    cdef int i
    if body != NULL:
        return body
    for i in range(space.constraints.num):
        c = <cpConstraint *>space.constraints.arr[i]
        if c.a.space != space and _bodyNonFinite(c.a):
            return c.a
        if c.b.space != space and _bodyNonFinite(c.b):
            return c.b
    return NULL


cdef void _clearNonFiniteContactImpulses(void *elt, void *data) noexcept nogil:
    cdef cpArbiter *arb = <cpArbiter *>elt
    cdef cpContact *con
    cdef int i
    for i in range(arb.count if arb.contacts != NULL else 0):
        con = &arb.contacts[i]
        if (con.jnAcc - con.jnAcc + con.jtAcc - con.jtAcc + con.jBias - con.jBias) != 0.0:
            con.jnAcc = con.jtAcc = con.jBias = 0.0

cdef void _forgetNonFiniteImpulses(cpSpace *space) noexcept nogil:
    # After a step that overflowed: the warm-start impulses of contacts and
    # joints may be inf or NaN too, and would make the bodies non-finite again
    # at the next step even after the user resets them.
    cdef cpConstraint *c
    cdef int i
    cpHashSetEach(space.cachedArbiters, _clearNonFiniteContactImpulses, NULL)
    for i in range(space.arbiters.num):
        _clearNonFiniteContactImpulses(space.arbiters.arr[i], NULL)
    for i in range(space.constraints.num):
        c = <cpConstraint *>space.constraints.arr[i]
        if _bodyNonFinite(c.a) or _bodyNonFinite(c.b):
            tamias_constraint_clear_impulse(c)


cdef void _scanOrphans(void *obj, void *data) noexcept nogil:
    cdef cpBody *body = (<cpShape *>obj).body
    cdef OrphanScan *scan = <OrphanScan *>data
    if body == NULL or not _orphanBody(body, scan.space):
        return
    scan.orphans += 1
    if scan.nonFinite == NULL and _bodyNonFinite(body):
        scan.nonFinite = body
    if scan.bad == NULL and not (body.m > 0.0 and body.m < INFINITY and body.i > 0.0):
        scan.bad = body


def _skip_idle_arbiter_filter(on=None):
    """Whether a step whose cached arbiters were all touched skips the
    arbiter cache's filter (and, given `on`, set it first; for tests, which
    check that filtering every step changes nothing)."""
    global _skip_idle_filter
    if on is not None:
        _skip_idle_filter = bool(on)
    return bool(_skip_idle_filter)
