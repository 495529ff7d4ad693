"""The space: the world that bodies, shapes and collision callbacks live in.

A :class:`Space` holds bodies and their shapes and moves them forward in
time with :meth:`Space.step`. The C part here is a port of Munk2D's
cpSpace.c (life cycle, adding and removing objects, handlers, reindexing)
and cpSpaceDebug.c; the step and the sleeping code (cpSpaceStep.c,
cpSpaceComponent.c) are in ``_space_step.pyx`` and the queries
(cpSpaceQuery.c) in ``_space_query.pyx``. Together they keep Munk2D's order
of everything (broad phase callbacks, arbiter array, solver passes), so a
scene gives the same numbers as in pymunk. The Python part follows pymunk
7.3's ``Space``.

A step with no Python callback installed (no collision handler, no Python
integrator, no post-step callback) runs entirely without the GIL.
"""
cimport cython
from libc.math cimport INFINITY, pow, atan2, isfinite
from libc.string cimport memcpy, memset
from libc.stdint cimport uintptr_t
from cpython.ref cimport PyObject

cdef extern from "Python.h":
    # A macro reading the dict's count; used without the GIL only on dicts
    # that no other thread can change at the time.
    Py_ssize_t PyDict_GET_SIZE(PyObject *d) nogil

import copyreg
import math
import platform
import weakref

from tamias2d._config cimport (tamias_prefetch, cpFloat, cpBool, cpHashValue, cpCollisionType,
    cpCollisionID, cpTimestamp, TAMIAS_FLOAT_0_1F, TAMIAS_FLOAT_0_9F,
    CP_HASH_PAIR, CP_HASH_PAIR_ORDERED, CP_WILDCARD_COLLISION_TYPE,
    CP_MAX_CONTACTS_PER_ARBITER, CP_BUFFER_BYTES)
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArbiter, cpContact,
    cpArray, cpCollisionInfo, cpCollisionHandler, cpContactBufferHeader,
    cpPostStepCallback, cpPostStepFunc, cpConstraint, cpBodyType,
    cpCircleShape, cpSegmentShape, cpPolyShape, cpSplittingPlane, cpShapeFilter,
    cpPointQueryInfo, cpSegmentQueryInfo, cpContactPointSet,
    cpSpatialIndex, cpSpatialIndexIteratorFunc, cpSpatialIndexQueryFunc,
    cpHashSetFilterFunc, cpHashSetIteratorFunc, cpHashSetEqlFunc, cpHashSetTransFunc,
    CP_BODY_TYPE_DYNAMIC, CP_BODY_TYPE_KINEMATIC, CP_BODY_TYPE_STATIC,
    CP_CIRCLE_SHAPE, CP_SEGMENT_SHAPE, CP_POLY_SHAPE,
    CP_ARBITER_STATE_FIRST_COLLISION, CP_ARBITER_STATE_NORMAL,
    CP_ARBITER_STATE_IGNORE, CP_ARBITER_STATE_CACHED, CP_ARBITER_STATE_INVALIDATED)
from tamias2d._containers cimport (cpcalloc, cprealloc, cpfree, cpArrayNew, cpArrayFree, cpArrayPush,
    cpArrayPop, cpArrayDeleteObj, cpArrayFreeEach, cpArrayContains, cpHashSetNew,
    cpHashSetFree, cpHashSetInsert, cpHashSetRemove, cpHashSetFind, cpHashSetEach,
    cpHashSetFilter, cpTakeOutOfMemory, cpOutOfMemory)
from tamias2d._spatialindex cimport (cpSpatialIndexFree, cpSpatialIndexEach,
    cpSpatialIndexInsert, cpSpatialIndexRemove, cpSpatialIndexReindex,
    cpSpatialIndexReindexObject, cpSpatialIndexReindexQuery, cpSpatialIndexQuery,
    cpSpatialIndexSegmentQuery)
from tamias2d._bbtree cimport (cpBBTreeNew, cpBBTreeSetVelocityFunc, cpBBTreeVelocityFunc,
    cpBBTreeSetFetchFunc, cpBBTreeSetFatFunc,
    cpBBTreeClass, cpBBTreeGetStaticReach)
from tamias2d._spacehash cimport cpSpaceHashNew
from tamias2d.vector cimport (cpVect, cpBB, cpTransform, cpv, cpvadd, cpvsub, cpvmult,
    cpvlengthsq, cpvlength, cpvdist, cpfmax, cpfmin, cpBBNew, cpBBIntersects, cpBBNewForCircle, cpTransformPoint,
    vec2d_from_cpv, cpv_from_object, cpv_from_object_finite, cptransform_from_object,
    cpbb_from_object)
from tamias2d.body cimport (Body, cpBodyInit, cpBodySetType, cpBodyActivate,
    cpBodyActivateStatic, cpBodyAddShape, cpBodyRemoveShape, cpBodyGetType,
    cpBodyIsSleeping, cpBodyKineticEnergy, tamias_BodySpaceHooks, tamias_set_body_space_hooks)
from tamias2d.shape cimport (Shape, cpShapeUpdate, cpShapeCacheBB, cpShapeFilterReject,
    cpShapePointQuery, cpShapeSegmentQuery)
from tamias2d.collision cimport (cpCollide, cpShapesCollide, collision_check_flags,
    contact_point_set_from_cp, cpCollisionPeekFlags)
from tamias2d.arbiter cimport (Arbiter, arbiter_wrap, cpArbiterInit, cpArbiterUpdate,
    cpArbiterPreStep, cpArbiterApplyCachedImpulse, cpArbiterApplyImpulse,
    cpArbiterUnthread, cpArbiterDropThreads, cpCollisionHandlerDoNothing, cpCollisionDoNothing,
    cpArbiterThreadForBody, cpArbiterNext)
from tamias2d.body cimport cpBodyRemoveConstraint, tamias_body_drop_stale_root
from tamias2d._pickle cimport snapshot_module as _snapshot
from tamias2d.constraints cimport (Constraint, tamias_constraint_detach,
    tamias_space_detach_constraints, tamias_check_constraints, tamias_constraint_debug_draw,
    tamias_constraint_clear_impulse, tamias_check_joint_space, tamias_check_body_joints,
    tamias_constraints_ok)

from tamias2d.shape import PointQueryInfo, SegmentQueryInfo, ShapeQueryInfo
from tamias2d.errors import (IllegalBody, IllegalShape, SpaceLocked, AlreadyInSpace,
    NotInSpace, IllegalCollisionType)

from tamias2d._threadguard cimport (tamias_wait_for_step, tamias_begin_step,
    tamias_end_step, tamias_step_lock_new, tamias_step_lock_free)
from tamias2d._private cimport (cpConstraintNext, cpSpaceArrayForBodyType,
    cpCallHandlers, PHASE_SEPARATE, cpSpaceArbiterLeavesCache)
from tamias2d._space_step cimport (cpSpaceLock, cpSpaceUnlock, cpSpaceGetPostStepCallback,
    cpSpaceAddPostStepCallback, cpSpaceStep, cpShapeUpdateFunc, cpSpaceWakeComponent, _bodyNonFinite,
    _firstNonFiniteBody, tamias_first_non_finite_body, tamias_first_non_finite_unawake,
    _forgetNonFiniteImpulses, OrphanScan,
    _scanOrphans)
from tamias2d._soft_step cimport (cpSoftStep, SoftSettingsInit, SoftScratchFree, SoftPushOut,
    SoftSpeculative, SoftPoolEnsure)
from tamias2d._structs cimport TAMIAS_SOLVER_CHIPMUNK, TAMIAS_SOLVER_SOFT
from tamias2d._space_query cimport (QueryHit, QueryHits, ShapeQueryHits, cpSpacePointQuery,
    cpSpacePointQueryNearest, cpSpaceSegmentQuery, cpSpaceSegmentQueryFirst, cpSpaceBBQuery,
    cpSpaceShapeQuery)



# -- small helpers of cpSpace.c --------------------------------------------------------

cdef cpBool arbiterSetEql(const void *ptr, const void *elt) noexcept nogil:
    cdef cpShape **shapes = <cpShape **>ptr
    cdef cpArbiter *arb = <cpArbiter *>elt
    cdef cpShape *a = shapes[0]
    cdef cpShape *b = shapes[1]
    return (a == arb.a and b == arb.b) or (b == arb.a and a == arb.b)

cdef cpBool handlerSetEql(const void *ptr, const void *elt) noexcept nogil:
    # ptr is a handler or a (typeA, typeB) pair laid out like its first fields.
    cdef cpCollisionHandler *check = <cpCollisionHandler *>ptr
    cdef cpCollisionHandler *pair = <cpCollisionHandler *>elt
    return check.typeA == pair.typeA and check.typeB == pair.typeB

cdef void *handlerSetTrans(const void *ptr, void *unused) noexcept nogil:
    cdef cpCollisionHandler *copy = <cpCollisionHandler *>cpcalloc(1, sizeof(cpCollisionHandler))
    if copy != NULL:
        memcpy(copy, ptr, sizeof(cpCollisionHandler))
    return copy

cdef cpBB _shapeGetBB(void *obj) noexcept nogil:
    cdef cpShape *shape = <cpShape *>obj
    cdef cpSpace *space = shape.space
    cdef cpBody *body = shape.body
    cdef cpBB bb = shape.bb
    cdef cpFloat m
    if space == NULL or space.collideMargin == 0.0:
        return bb    # the chipmunk solver: the box as it is
    # The soft solver pairs shapes up to its speculative distance, and a
    # pair with a static, kinematic or bullet body also as far apart as
    # its bodies could close in the step (cpSpaceRejectPair), so the
    # broad phase must look that far.
    m = space.collideMargin
    if space.dynamicShapes.klass != cpBBTreeClass():
        # A spatial hash has no static reach: grown by the step's travel on
        # every side (its contacts may turn it within the step).
        m += cpvlength(cpvmult(body.v, space.curr_dt))
        return cpBBNew(bb.l - m, bb.b - m, bb.r + m, bb.t + m)
    # In the tree, a plain dynamic box is its shape's box and the margin:
    # two plain dynamic bodies pair on the margin alone, and a static pair
    # is found by searching the static tree a reach around the leaf (at
    # least the fastest body's travel, _soft_step.pyx SoftSetReach). A
    # kinematic or bullet shape pairs with dynamic ones as far as the two
    # close in the step, at most its own travel and the other's (which the
    # reach covers), so its box grows by both.
    if body.isBullet or cpBodyGetType(body) == CP_BODY_TYPE_KINEMATIC:
        m += cpvlength(cpvmult(body.v, space.curr_dt)) + cpBBTreeGetStaticReach(space.dynamicShapes)
    return cpBBNew(bb.l - m, bb.b - m, bb.r + m, bb.t + m)

cdef void _shapeFetchBody(void *obj) noexcept nogil:
    # What _shapeGetBB and the tree's fattening read of a shape's body (its
    # mass, velocity and bullet flag, on three lines), fetched ahead by the
    # tree's refresh of its leaves.
    cdef cpBody *body = (<cpShape *>obj).body
    tamias_prefetch(&body.m)
    tamias_prefetch(&body.v)
    tamias_prefetch(&body.isBullet)

cdef void _shapeSetFat(void *obj, cpBB fat) noexcept nogil:
    # The box of the shape's leaf in the dynamic tree (cpShape.softFat).
    (<cpShape *>obj).softFat = fat

# The dynamic tree predicts a shape's motion from its body's velocity.
cdef cpVect ShapeVelocityFunc(void *obj) noexcept nogil:
    return (<cpShape *>obj).body.v

cdef void FreeWrap(void *ptr, void *unused) noexcept nogil:
    cpfree(ptr)

cdef void _freeWrap1(void *ptr) noexcept nogil:
    cpfree(ptr)


# -- life cycle -------------------------------------------------------------------------

cdef cpSpace *cpSpaceInit(cpSpace *space) noexcept nogil:
    space.iterations = 10
    space.gravity = cpv(0.0, 0.0)
    space.damping = 1.0
    # Munk2D writes these as float literals: 0.1f and pow(1.0f - 0.1f, 60.0f).
    space.collisionSlop = TAMIAS_FLOAT_0_1F
    space.collisionBias = pow(TAMIAS_FLOAT_0_9F, 60.0)
    space.collisionPersistence = 3
    space.locked = 0
    space.stamp = 0
    space.handlerVersion = 1
    space.curr_dt = 0.0
    space.userData = NULL
    # Not in Munk2D: the second solver's settings (off: solver "chipmunk").
    SoftSettingsInit(&space.soft)
    memset(&space.softScratch, 0, sizeof(space.softScratch))
    space.collideMargin = 0.0

    space.shapeIDCounter = 0
    space.staticShapes = cpBBTreeNew(_shapeGetBB, NULL)
    space.dynamicShapes = cpBBTreeNew(_shapeGetBB, space.staticShapes)
    if space.dynamicShapes != NULL:
        cpBBTreeSetVelocityFunc(space.dynamicShapes, ShapeVelocityFunc)
        cpBBTreeSetFetchFunc(space.dynamicShapes, _shapeFetchBody)
        cpBBTreeSetFatFunc(space.dynamicShapes, _shapeSetFat)

    space.allocatedBuffers = cpArrayNew(0)
    space.dynamicBodies = cpArrayNew(0)
    space.staticBodies = cpArrayNew(0)
    space.sleepingComponents = cpArrayNew(0)
    space.rousedBodies = cpArrayNew(0)

    space.sleepTimeThreshold = INFINITY
    space.idleSpeedThreshold = 0.0

    space.arbiters = cpArrayNew(0)
    space.pooledArbiters = cpArrayNew(0)

    space.contactBuffersHead = NULL
    space.cachedArbiters = cpHashSetNew(0, arbiterSetEql)

    space.constraints = cpArrayNew(0)

    memcpy(&space.globalHandler, cpCollisionHandlerDoNothing(), sizeof(cpCollisionHandler))
    space.collisionHandlers = cpHashSetNew(0, handlerSetEql)

    space.postStepCallbacks = cpArrayNew(0)
    space.skipPostStep = 0

    space.staticBody = NULL
    cdef cpBody *staticBody = cpBodyInit(&space._staticBody, 0.0, 0.0)
    cpBodySetType(staticBody, CP_BODY_TYPE_STATIC)
    cpSpaceSetStaticBody(space, staticBody)

    if (space.staticShapes == NULL or space.dynamicShapes == NULL
            or space.allocatedBuffers == NULL or space.dynamicBodies == NULL
            or space.staticBodies == NULL or space.sleepingComponents == NULL
            or space.rousedBodies == NULL or space.arbiters == NULL
            or space.pooledArbiters == NULL or space.cachedArbiters == NULL
            or space.constraints == NULL or space.collisionHandlers == NULL
            or space.postStepCallbacks == NULL):
        cpSpaceDestroy(space)
        return NULL
    return space

cdef void cpSpaceSetStaticBody(cpSpace *space, cpBody *body) noexcept nogil:
    if space.staticBody != NULL:
        space.staticBody.space = NULL
    space.staticBody = body
    body.space = space

cdef void cpSpaceDestroy(cpSpace *space) noexcept nogil:
    # Munk2D wakes every body first so that sleeping arbiters give their heap
    # contacts back; here the Python layer has already removed every object.
    SoftScratchFree(&space.softScratch)
    if space.staticShapes != NULL:
        cpSpatialIndexFree(space.staticShapes)
    if space.dynamicShapes != NULL:
        cpSpatialIndexFree(space.dynamicShapes)
    space.staticShapes = NULL
    space.dynamicShapes = NULL

    if space.sleepingComponents != NULL:
        cpArrayFree(space.sleepingComponents)
    if space.dynamicBodies != NULL:
        cpArrayFree(space.dynamicBodies)
    if space.staticBodies != NULL:
        cpArrayFree(space.staticBodies)
    if space.rousedBodies != NULL:
        cpArrayFree(space.rousedBodies)
    if space.constraints != NULL:
        cpArrayFree(space.constraints)
    if space.cachedArbiters != NULL:
        cpHashSetFree(space.cachedArbiters)
    if space.arbiters != NULL:
        cpArrayFree(space.arbiters)
    if space.pooledArbiters != NULL:
        cpArrayFree(space.pooledArbiters)
    if space.allocatedBuffers != NULL:
        cpArrayFreeEach(space.allocatedBuffers, _freeWrap1)
        cpArrayFree(space.allocatedBuffers)
    if space.postStepCallbacks != NULL:
        cpArrayFreeEach(space.postStepCallbacks, _freeWrap1)
        cpArrayFree(space.postStepCallbacks)
    if space.collisionHandlers != NULL:
        cpHashSetEach(space.collisionHandlers, FreeWrap, NULL)
        cpHashSetFree(space.collisionHandlers)
    space.sleepingComponents = NULL
    space.dynamicBodies = NULL
    space.staticBodies = NULL
    space.rousedBodies = NULL
    space.constraints = NULL
    space.cachedArbiters = NULL
    space.arbiters = NULL
    space.pooledArbiters = NULL
    space.allocatedBuffers = NULL
    space.postStepCallbacks = NULL
    space.collisionHandlers = NULL
    space.contactBuffersHead = NULL


# -- properties -------------------------------------------------------------------------

cdef void cpSpaceSetGravity(cpSpace *space, cpVect gravity) noexcept nogil:
    space.gravity = gravity
    # Wake every sleeping component: gravity changed under them. (Munk2D's
    # loop advances while waking removes entries; kept as is.)
    cdef cpArray *components = space.sleepingComponents
    cdef int i = 0
    while i < components.num:
        cpBodyActivate(<cpBody *>components.arr[i])
        i += 1

cdef cpBool cpSpaceIsLocked(cpSpace *space) noexcept nogil:
    return space.locked > 0


# -- collision handlers -------------------------------------------------------------------

cdef cpCollisionHandler *cpSpaceAddCollisionHandler(cpSpace *space, cpCollisionType a,
                                                    cpCollisionType b) noexcept nogil:
    if a == b and a == CP_WILDCARD_COLLISION_TYPE:
        return &space.globalHandler
    cdef cpHashValue hash = CP_HASH_PAIR_ORDERED(a, b)
    cdef cpCollisionHandler handler
    handler.typeA = a
    handler.typeB = b
    handler.beginFunc = cpCollisionDoNothing
    handler.preSolveFunc = cpCollisionDoNothing
    handler.postSolveFunc = cpCollisionDoNothing
    handler.separateFunc = cpCollisionDoNothing
    handler.userData = NULL
    space.handlerVersion += 1   # an arbiter may now have another handler
    return <cpCollisionHandler *>cpHashSetInsert(space.collisionHandlers, hash, &handler,
                                                 handlerSetTrans, NULL)

cdef cpCollisionHandler *cpSpaceAddWildcardHandler(cpSpace *space, cpCollisionType type) noexcept nogil:
    cdef cpHashValue hash = CP_HASH_PAIR_ORDERED(type, CP_WILDCARD_COLLISION_TYPE)
    cdef cpCollisionHandler handler
    handler.typeA = type
    handler.typeB = CP_WILDCARD_COLLISION_TYPE
    handler.beginFunc = cpCollisionDoNothing
    handler.preSolveFunc = cpCollisionDoNothing
    handler.postSolveFunc = cpCollisionDoNothing
    handler.separateFunc = cpCollisionDoNothing
    handler.userData = NULL
    space.handlerVersion += 1   # an arbiter may now have another handler
    return <cpCollisionHandler *>cpHashSetInsert(space.collisionHandlers, hash, &handler,
                                                 handlerSetTrans, NULL)


# -- bodies and shapes --------------------------------------------------------------------

cdef cpShape *cpSpaceAddShape(cpSpace *space, cpShape *shape) noexcept nogil:
    cdef cpBody *body = shape.body
    cdef cpBool isStatic = cpBodyGetType(body) == CP_BODY_TYPE_STATIC
    if not isStatic:
        cpBodyActivate(body)
    cpBodyAddShape(body, shape)
    # Ids come from a counter and are never reused: they order the broad phase.
    shape.hashid = space.shapeIDCounter
    space.shapeIDCounter += 1
    cpShapeUpdate(shape, body.transform)
    cpSpatialIndexInsert(space.staticShapes if isStatic else space.dynamicShapes, shape, shape.hashid)
    shape.space = space
    return shape

cdef cpBody *cpSpaceAddBody(cpSpace *space, cpBody *body) noexcept nogil:
    if body.sleeping.root != NULL:
        # A body outside every space with component links: asleep in the
        # component of bodies it is jointed to (woken here, as adding wakes),
        # or left over from a component that stayed awake, which resets only
        # the links of the bodies in its array (Munk2D keeps the stale root,
        # and the body then counts as asleep in the space it joins: the step
        # never unthreads its arbiters and the next contact loops; pymunk
        # hangs). cpBodyActivate follows the root only if it still sleeps.
        cpBodyActivate(body)
        body.sleeping.root = NULL
        body.sleeping.next = NULL
    if not cpArrayPush(cpSpaceArrayForBodyType(space, cpBodyGetType(body)), body):
        return NULL
    body.space = space
    # (The soft step's kept components hold for the bodies they were made of.)
    space.softScratch.islandsStamp = 0
    return body

cdef struct arbiterFilterContext:
    cpSpace *space
    cpBody *body
    cpShape *shape


cdef cpBool cachedArbitersFilter(void *elt, void *data) noexcept nogil:
    cdef cpArbiter *arb = <cpArbiter *>elt
    cdef arbiterFilterContext *context = <arbiterFilterContext *>data
    cdef cpShape *shape = context.shape
    cdef cpBody *body = context.body
    if ((body == arb.body_a and (shape == arb.a or shape == NULL))
            or (body == arb.body_b and (shape == arb.b or shape == NULL))):
        if shape != NULL and arb.state != CP_ARBITER_STATE_CACHED:
            # One of the shapes is going away: the arbiter is invalidated.
            arb.state = CP_ARBITER_STATE_INVALIDATED
            cpCallHandlers(arb, context.space, PHASE_SEPARATE, False)
        cpArbiterUnthread(arb)
        cpArrayDeleteObj(context.space.arbiters, arb)
        # (The array's order changed: see cpSoftScratch.threadsClean.)
        context.space.softScratch.threadsClean = 0
        cpArrayPush(context.space.pooledArbiters, arb)
        cpSpaceArbiterLeavesCache(context.space, arb)
        arb.cached = 0
        # A pooled arbiter forgets its shapes so that a stale Python Arbiter
        # view can tell (the removed shape may be freed).
        arb.a = NULL
        arb.b = NULL
        return 0
    return 1

cdef void cpSpaceFilterArbiters(cpSpace *space, cpBody *body, cpShape *filter) noexcept nogil:
    cpSpaceLock(space)
    cdef arbiterFilterContext context
    context.space = space
    context.body = body
    context.shape = filter
    cpHashSetFilter(space.cachedArbiters, cachedArbitersFilter, &context)
    cpSpaceUnlock(space, 1)

# With a collision persistence of 0, the last step's arbiters left the cache
# (back to the pool) when that step ended, but stay in its arbiter array and
# threaded in their bodies' lists until the next step. The cache filter above
# does not see them: Munk2D leaves the removed shape in them (a copy of the
# space then finds a shape it does not hold). No separate callback, as
# Munk2D, whose pair was never seen again. With a persistence > 0 every
# arbiter of the array is cached, so nothing is found here.
cdef void _dropExpiredArbiters(cpSpace *space, cpShape *shape) noexcept nogil:
    cdef cpArray *arbiters = space.arbiters
    cdef cpArbiter *arb
    cdef int i = 0
    while i < arbiters.num:
        arb = <cpArbiter *>arbiters.arr[i]
        if arb.a == shape or arb.b == shape:
            cpArbiterUnthread(arb)
            cpArrayDeleteObj(arbiters, arb)
            space.softScratch.threadsClean = 0
            if not cpArrayContains(space.pooledArbiters, arb):
                cpArrayPush(space.pooledArbiters, arb)
            arb.a = NULL
            arb.b = NULL
            arb.contacts = NULL
            arb.count = 0
            continue  # swap-removed: the same index holds the next one
        i += 1

cdef void cpSpaceRemoveShape(cpSpace *space, cpShape *shape) noexcept nogil:
    cdef cpBody *body = shape.body
    cdef cpBool isStatic = cpBodyGetType(body) == CP_BODY_TYPE_STATIC
    if isStatic:
        cpBodyActivateStatic(body, shape)
    else:
        cpBodyActivate(body)
    cpBodyRemoveShape(body, shape)
    cpSpaceFilterArbiters(space, body, shape)
    _dropExpiredArbiters(space, shape)
    cpSpatialIndexRemove(space.staticShapes if isStatic else space.dynamicShapes, shape, shape.hashid)
    shape.space = NULL
    shape.hashid = 0

# -- a space freed ----------------------------------------------------------------------
# Removing shapes one by one, as Munk2D's and pymunk's teardown does, filters
# the whole arbiter cache for each: a space of 5,000 boxes took half a second
# to free. A space being freed runs no callback (__dealloc__ silences them
# all first), so its arbiters can all go at once and each shape then only
# leaves its body and its index.

cdef inline void _forgetArbiter(cpArbiter *arb) noexcept nogil:
    # Off its bodies' lists (every list is emptied, see below) and
    # forgetting its shapes, as a pooled arbiter does.
    cpArbiterDropThreads(arb)
    arb.a = NULL
    arb.b = NULL
    arb.contacts = NULL
    arb.count = 0
    arb.cached = 0

cdef cpBool _forgetCachedArbiter(void *elt, void *data) noexcept nogil:
    _forgetArbiter(<cpArbiter *>elt)
    return 0

cdef bint _teardownArbiters(cpSpace *space) noexcept nogil:
    # Sleeping arbiters are out of the cache with their contacts on the heap:
    # waking every component gives those back and caches them again. Then
    # every arbiter of the space is in the cache or the arbiter array, and
    # every arbiter on a body's list is one of them. False (nothing dropped)
    # if a component would not wake: the caller removes shapes one by one.
    cdef cpArray *arbiters = space.arbiters
    cdef cpArray *components = space.sleepingComponents
    cdef int i, left
    while components.num > 0:
        left = components.num
        cpBodyActivate(<cpBody *>components.arr[left - 1])
        if components.num >= left:
            return 0
    cpHashSetFilter(space.cachedArbiters, _forgetCachedArbiter, NULL)
    for i in range(arbiters.num):
        _forgetArbiter(<cpArbiter *>arbiters.arr[i])
    arbiters.num = 0
    return 1

cdef void _teardownShape(cpSpace *space, cpShape *shape) noexcept nogil:
    # cpSpaceRemoveShape after _teardownArbiters: nothing sleeps and no
    # arbiter is left, so only the body's list and the index hold the shape.
    cdef cpBool isStatic = cpBodyGetType(shape.body) == CP_BODY_TYPE_STATIC
    cpBodyRemoveShape(shape.body, shape)
    cpSpatialIndexRemove(space.staticShapes if isStatic else space.dynamicShapes, shape, shape.hashid)
    shape.space = NULL
    shape.hashid = 0

cdef void cpSpaceRemoveBody(cpSpace *space, cpBody *body) noexcept nogil:
    cpBodyActivate(body)
    # Munk2D does not filter the body's arbiters here (only shape removal does).
    cpArrayDeleteObj(cpSpaceArrayForBodyType(space, cpBodyGetType(body)), body)
    body.space = NULL
    space.softScratch.islandsStamp = 0

# Callers check Munk2D's hard asserts (not in a space, unlocked, both bodies
# set). NULL when out of memory (nothing changed).
cdef cpConstraint *cpSpaceAddConstraint(cpSpace *space, cpConstraint *constraint) noexcept nogil:
    cdef cpBody *a = constraint.a
    cdef cpBody *b = constraint.b
    cpBodyActivate(a)
    cpBodyActivate(b)
    if not cpArrayPush(space.constraints, constraint):
        return NULL
    space.softScratch.islandsStamp = 0
    # Head insertion into both bodies' lists.
    constraint.next_a = a.constraintList
    a.constraintList = constraint
    constraint.next_b = b.constraintList
    b.constraintList = constraint
    constraint.space = space
    return constraint

cdef void cpSpaceRemoveConstraint(cpSpace *space, cpConstraint *constraint) noexcept nogil:
    # Waking first puts a sleeping constraint back in the array.
    cpBodyActivate(constraint.a)
    cpBodyActivate(constraint.b)
    cpArrayDeleteObj(space.constraints, constraint)
    space.softScratch.islandsStamp = 0
    cpBodyRemoveConstraint(constraint.a, constraint)
    cpBodyRemoveConstraint(constraint.b, constraint)
    constraint.space = NULL
    # Waking above followed the roots that still sleep; a body outside the
    # space that this joint held keeps a stale one (body.pyx).
    tamias_body_drop_stale_root(constraint.a)
    tamias_body_drop_stale_root(constraint.b)


# -- iteration ----------------------------------------------------------------------------

cdef void cpSpaceEachBody(cpSpace *space, cpSpaceBodyIteratorFunc func, void *data) noexcept nogil:
    cdef int i
    cdef cpArray *bodies
    cdef cpBody *body
    cdef cpBody *next
    cpSpaceLock(space)
    bodies = space.dynamicBodies
    i = 0
    while i < bodies.num:
        func(<cpBody *>bodies.arr[i], data)
        i += 1
    bodies = space.staticBodies
    i = 0
    while i < bodies.num:
        func(<cpBody *>bodies.arr[i], data)
        i += 1
    bodies = space.sleepingComponents
    i = 0
    while i < bodies.num:
        body = <cpBody *>bodies.arr[i]
        while body != NULL:
            next = body.sleeping.next
            func(body, data)
            body = next
        i += 1
    cpSpaceUnlock(space, 1)

cdef void cpSpaceEachShape(cpSpace *space, cpSpatialIndexIteratorFunc func, void *data) noexcept nogil:
    # Dynamic tree first, then the static one, each in leaf-set order.
    cpSpaceLock(space)
    cpSpatialIndexEach(space.dynamicShapes, func, data)
    cpSpatialIndexEach(space.staticShapes, func, data)
    cpSpaceUnlock(space, 1)


# -- reindexing ---------------------------------------------------------------------------

cdef void cpSpaceReindexStatic(cpSpace *space) noexcept nogil:
    cpSpatialIndexEach(space.staticShapes, cpShapeUpdateFunc, NULL)
    cpSpatialIndexReindex(space.staticShapes)

cdef void cpSpaceReindexShape(cpSpace *space, cpShape *shape) noexcept nogil:
    cpShapeCacheBB(shape)
    # The shape is in one of the two trees; reindexing in the other is a no-op.
    cpSpatialIndexReindexObject(space.dynamicShapes, shape, shape.hashid)
    cpSpatialIndexReindexObject(space.staticShapes, shape, shape.hashid)

cdef void cpSpaceReindexShapesForBody(cpSpace *space, cpBody *body) noexcept nogil:
    cdef cpShape *shape = body.shapeList
    while shape != NULL:
        cpSpaceReindexShape(space, shape)
        shape = shape.next


cdef void copyShapes(void *obj, void *data) noexcept nogil:
    cdef cpShape *shape = <cpShape *>obj
    cpSpatialIndexInsert(<cpSpatialIndex *>data, shape, shape.hashid)

# Replaces both trees with spatial hashes. Returns 0 (and changes nothing)
# when the hashes cannot be made.
cdef cpBool cpSpaceUseSpatialHash(cpSpace *space, cpFloat dim, int count) noexcept nogil:
    cdef cpSpatialIndex *staticShapes = cpSpaceHashNew(dim, count, _shapeGetBB, NULL)
    if staticShapes == NULL:
        return 0
    cdef cpSpatialIndex *dynamicShapes = cpSpaceHashNew(dim, count, _shapeGetBB, staticShapes)
    if dynamicShapes == NULL:
        cpSpatialIndexFree(staticShapes)
        return 0
    cpSpatialIndexEach(space.staticShapes, copyShapes, staticShapes)
    cpSpatialIndexEach(space.dynamicShapes, copyShapes, dynamicShapes)
    cpSpatialIndexFree(space.staticShapes)
    cpSpatialIndexFree(space.dynamicShapes)
    space.staticShapes = staticShapes
    space.dynamicShapes = dynamicShapes
    return 1



cdef void _collectShapeAddress(void *obj, void *data) noexcept with gil:
    (<list>data).append(<uintptr_t>obj)


cdef void _collectShape(void *obj, void *data) noexcept with gil:
    (<list>data).append(<object>(<cpShape *>obj).userData)



# The C part of Space.step: the solver's step, then the first body it made
# non-finite (NULL if none). Runs without the GIL.
cdef cpBody *tamias_space_step(cpSpace *space, cpFloat dt) noexcept nogil:
    if space.soft.solver == TAMIAS_SOLVER_SOFT:
        if cpSoftStep(space, dt):
            # (It checked the awake bodies as it wrote them back.)
            return tamias_first_non_finite_unawake(space)
    else:
        cpSpaceStep(space, dt)
    return tamias_first_non_finite_body(space)


# ================================================================================================
# Python
# ================================================================================================

def empty_callback(*args, **kwargs):
    """A callback that does nothing; pass it to :meth:`Space.on_collision` to
    reset a collision callback to the default.

    >>> import tamias2d
    >>> space = tamias2d.Space()
    >>> space.on_collision(1, 2, begin=tamias2d.empty_callback)
    """
    return None


def bisection_order(objs):
    """The items of ``objs`` in bisection order: the middle one, then the
    middles of both halves, and so on, breadth first.

    The order :meth:`Space.add_static_bulk` adds shapes in. The bounding-box
    tree (Munk2D's, and so pymunk's) inserts each shape where its cost
    heuristic says; shapes added in spatial order (a row of segments, a
    grid) each go to the bottom of one ever longer branch, so adding n of
    them takes O(n^2) time. In bisection order the tree stays about
    2 log2(n) deep. ``pymunk_space.add(*bisection_order(shapes))`` builds
    the same tree in pymunk, so a scene made this way still steps bit for
    bit as in pymunk.

    >>> from tamias2d.space import bisection_order
    >>> bisection_order(range(7))
    [3, 1, 5, 0, 2, 4, 6]
    """
    items = list(objs)
    order = []
    ranges = [(0, len(items))]
    i = 0
    while i < len(ranges):
        lo, hi = ranges[i]
        i += 1
        if lo < hi:
            mid = (lo + hi) // 2
            order.append(items[mid])
            ranges.append((lo, mid))
            ranges.append((mid + 1, hi))
    return order


cdef enum:
    _BEGIN = 0
    _PRE_SOLVE = 1
    _POST_SOLVE = 2
    _SEPARATE = 3


@cython.final
cdef class CollisionHandler:
    """The four callbacks (and their data) of one collision type pair.

    Made by :meth:`Space.on_collision`; kept in ``Space._handlers`` under the
    key ``(collision_type_a, collision_type_b)`` (None for a wildcard).

    >>> import tamias2d
    >>> space = tamias2d.Space()
    >>> space.on_collision(1, 2, pre_solve=tamias2d.empty_callback)
    >>> space._handlers[(1, 2)].begin is None
    True
    """
    cdef cpCollisionHandler *_handler   # in the space's handler set (or its global one)
    cdef object _begin
    cdef object _pre_solve
    cdef object _post_solve
    cdef object _separate
    cdef dict _data

    def __init__(self, *args, **kwargs):
        raise TypeError("CollisionHandler objects are made by Space.on_collision")

    @property
    def data(self):
        """The data passed to each callback, per phase name ("begin",
        "pre_solve", "post_solve", "separate")."""
        return self._data

    @property
    def begin(self):
        """The begin callback, or None."""
        return self._begin

    @property
    def pre_solve(self):
        """The pre_solve callback, or None."""
        return self._pre_solve

    @property
    def post_solve(self):
        """The post_solve callback, or None."""
        return self._post_solve

    @property
    def separate(self):
        """The separate callback, or None."""
        return self._separate

    cdef void _set(self, int which, object func):
        cdef cpCollisionHandler *h = self._handler
        if which == _BEGIN:
            self._begin = func
            h.beginFunc = cpCollisionDoNothing if func is None else _pyBegin
        elif which == _PRE_SOLVE:
            self._pre_solve = func
            h.preSolveFunc = cpCollisionDoNothing if func is None else _pyPreSolve
        elif which == _POST_SOLVE:
            self._post_solve = func
            h.postSolveFunc = cpCollisionDoNothing if func is None else _pyPostSolve
        else:
            self._separate = func
            h.separateFunc = cpCollisionDoNothing if func is None else _pySeparate


cdef void _callPyHandler(cpArbiter *arb, cpSpace *space, void *data, int which) noexcept with gil:
    cdef Space pyspace = <Space>space.userData
    cdef CollisionHandler handler = <CollisionHandler>data
    cdef bint orig_locked = pyspace._locked
    try:
        if which == _BEGIN:
            func = handler._begin
            arg = handler._data.get("begin")
        elif which == _PRE_SOLVE:
            func = handler._pre_solve
            arg = handler._data.get("pre_solve")
        elif which == _POST_SOLVE:
            func = handler._post_solve
            arg = handler._data.get("post_solve")
        else:
            func = handler._separate
            arg = handler._data.get("separate")
            # A separate callback can run outside a step (shape removal):
            # removals inside it are deferred like those inside a step.
            pyspace._locked = True
        if func is not None:
            func(arbiter_wrap(arb, pyspace), pyspace, arg)
    except BaseException as exc:
        pyspace._store_callback_error(exc)
    finally:
        pyspace._locked = orig_locked

cdef void _pyBegin(cpArbiter *arb, cpSpace *space, void *data) noexcept nogil:
    _callPyHandler(arb, space, data, _BEGIN)

cdef void _pyPreSolve(cpArbiter *arb, cpSpace *space, void *data) noexcept nogil:
    _callPyHandler(arb, space, data, _PRE_SOLVE)

cdef void _pyPostSolve(cpArbiter *arb, cpSpace *space, void *data) noexcept nogil:
    _callPyHandler(arb, space, data, _POST_SOLVE)

cdef void _pySeparate(cpArbiter *arb, cpSpace *space, void *data) noexcept nogil:
    _callPyHandler(arb, space, data, _SEPARATE)


def _arbiter_for_body(arb_ptr, space):
    """Factory used by Body.each_arbiter: an Arbiter view of a C arbiter.

    >>> import tamias2d
    >>> s = tamias2d.Space()
    >>> b = tamias2d.Body(1, 10)
    >>> s.add(b, tamias2d.Circle(b, 5), tamias2d.Circle(s.static_body, 5))
    >>> s.step(0.01)
    >>> arbs = []
    >>> b.each_arbiter(lambda arb: arbs.append(arb.shapes[0].body is b))
    >>> arbs
    [True]
    """
    return arbiter_wrap(<cpArbiter *><uintptr_t>arb_ptr, space)


cdef inline object _shape_obj(const cpShape *shape):
    return <object>shape.userData

cdef cpShapeFilter _filter_from_object(object f) except *:
    cdef cpShapeFilter cf
    try:
        group, categories, mask = f
    except (TypeError, ValueError):
        raise TypeError("shape_filter must be a ShapeFilter (group, categories, mask)") from None
    cf.group = group
    cf.categories = categories
    cf.mask = mask
    return cf


cdef list _hits_to_list(QueryHits *hits, int kind):
    # kind 0: PointQueryInfo, 1: SegmentQueryInfo, 2: shapes
    cdef list result = []
    cdef int i
    cdef QueryHit *h
    for i in range(hits.count):
        h = &hits.hits[i]
        shape = <object>h.shape.userData
        if kind == 0:
            result.append(PointQueryInfo(shape, vec2d_from_cpv(h.point), h.value,
                                         vec2d_from_cpv(h.vect)))
        elif kind == 1:
            result.append(SegmentQueryInfo(shape, vec2d_from_cpv(h.point),
                                           vec2d_from_cpv(h.vect), h.value))
        else:
            result.append(shape)
    return result


cdef _add_constraint(Space space, Constraint constraint):
    # pymunk's checks, then Munk2D's hard asserts as exceptions.
    if constraint in space._constraints:
        raise AlreadyInSpace("Constraint already added to space.")
    cdef cpConstraint *c = constraint._constraint
    if c.space != NULL:
        raise AlreadyInSpace("Constraint already added to another space. A constraint can "
                             "only be in one space at a time.")
    if c.a == NULL or c.b == NULL or constraint._a is None or constraint._b is None:
        raise IllegalBody("The constraint's bodies are not set (it was never initialised).")
    if (cpBodyGetType(c.a) != CP_BODY_TYPE_DYNAMIC
            and cpBodyGetType(c.b) != CP_BODY_TYPE_DYNAMIC):
        raise IllegalBody("At least one of a constraint's bodies must be DYNAMIC.")
    tamias_check_joint_space(&space._space, c)
    if cpSpaceIsLocked(&space._space):
        raise SpaceLocked("the space is locked (a query or debug draw is running)")
    space._constraints[constraint] = None
    if cpSpaceAddConstraint(&space._space, c) == NULL:
        del space._constraints[constraint]
        cpTakeOutOfMemory()
        raise MemoryError("not enough memory to add the constraint")


cdef _remove_constraint(Space space, Constraint constraint):
    if constraint not in space._constraints:
        raise NotInSpace("constraint not in space, already removed?")
    if constraint._constraint.space == &space._space:
        cpSpaceRemoveConstraint(&space._space, constraint._constraint)
    del space._constraints[constraint]


cdef double _soft_nonneg(object value, str what) except? -1.0:
    # A soft-solver setting: a finite number >= 0 (NaN, inf and negative
    # values would make the contacts' bias NaN or push the wrong way).
    cdef double x
    if isinstance(value, bool):
        raise ValueError(f"{what} must be a finite number >= 0, not {value!r}")
    try:
        x = value
    except TypeError:
        raise ValueError(f"{what} must be a finite number >= 0, not {value!r}") from None
    if not (isfinite(x) and x >= 0.0):
        raise ValueError(f"{what} must be a finite number >= 0, not {value!r}")
    return x


# The first dynamic body of `bodies` that a step must refuse (a mass not in
# (0, inf), a moment not > 0), or NULL.
cdef cpBody *_firstBadMassBody(cpArray *bodies) noexcept nogil:
    cdef cpBody *body
    cdef int i
    for i in range(bodies.num):
        body = <cpBody *>bodies.arr[i]
        if cpBodyGetType(body) == CP_BODY_TYPE_DYNAMIC and not (
                body.m > 0.0 and body.m < INFINITY and body.i > 0.0):
            return body
    return NULL


@cython.no_gc_clear
cdef class Space:
    """A world of bodies and shapes that steps forward through time.

    Add bodies, shapes and constraints (joints) with :meth:`add`, then call
    :meth:`step` with a fixed time step. Collision callbacks are set with
    :meth:`on_collision`.

    ``threaded`` (with :attr:`threads`) lets the soft solver run a step on
    two threads, with the same bits as on one; the chipmunk solver, like
    pymunk's on one thread, always steps on the calling thread. ``solver`` (keyword only,
    not in pymunk) picks the contact solver: ``"chipmunk"``, pymunk's and the
    default, or ``"soft"``, a soft step with substeps (see :attr:`solver`).

    >>> import tamias2d
    >>> space = tamias2d.Space()
    >>> space.gravity = 0, -10
    >>> body = tamias2d.Body(1, 10)
    >>> space.add(body, tamias2d.Circle(body, 1))
    >>> for _ in range(10):
    ...     space.step(0.01)
    >>> round(body.velocity.y, 6)
    -1.0
    """

    def __cinit__(self, *args, **kwargs):
        if cpSpaceInit(&self._space) == NULL:
            cpTakeOutOfMemory()
            raise MemoryError("not enough memory for a new Space")
        self._initialized = True
        self._space.userData = <void *>self
        tamias_step_lock_new(&self._space)
        self._bodies = {}
        self._shapes = {}
        self._constraints = {}
        self._static_body = None
        self._handlers = {}
        self._post_step_callbacks = {}
        self._add_later = {}
        self._remove_later = {}
        self._locked = False
        self._may_have_orphans = True  # a copy may come with orphans
        self._callback_error = None
        self.threaded = False

    def __init__(self, threaded=False, *, solver="chipmunk"):
        self.threaded = bool(threaded) and platform.system() != "Windows"
        self.solver = solver

    def __dealloc__(self):
        cdef cpCollisionHandler *h
        tamias_step_lock_free(&self._space)
        if not self._initialized:
            return
        # No Python callback may run while the space is torn down.
        self._space.globalHandler.beginFunc = cpCollisionDoNothing
        self._space.globalHandler.preSolveFunc = cpCollisionDoNothing
        self._space.globalHandler.postSolveFunc = cpCollisionDoNothing
        self._space.globalHandler.separateFunc = cpCollisionDoNothing
        if self._handlers is not None:
            for handler in self._handlers.values():
                h = (<CollisionHandler>handler)._handler
                h.beginFunc = cpCollisionDoNothing
                h.preSolveFunc = cpCollisionDoNothing
                h.postSolveFunc = cpCollisionDoNothing
                h.separateFunc = cpCollisionDoNothing
        self._space.locked = 0
        # Detach every shape, constraint and body, as pymunk does when its
        # space is freed.
        cdef cpBody *body
        cdef bint dropped = _teardownArbiters(&self._space)
        if self._shapes is not None:
            for shape in list(self._shapes):
                (<Shape>shape)._space = None
                if (<Shape>shape)._shape.space == &self._space:
                    if dropped:
                        _teardownShape(&self._space, (<Shape>shape)._shape)
                    else:
                        cpSpaceRemoveShape(&self._space, (<Shape>shape)._shape)
        # Constraints are found through the C space too: the dict may have been
        # cleared by the garbage collector while a constraint lives on.
        tamias_space_detach_constraints(&self._space)
        bodies = list(self._bodies) if self._bodies is not None else []
        if self._static_body is not None:
            bodies.append(self._static_body)
        for b in bodies:
            (<Body>b)._space = None
            body = &(<Body>b)._body
            if body.space == &self._space:
                cpSpaceRemoveBody(&self._space, body)
        cpSpaceDestroy(&self._space)
        self._initialized = False

    # -- errors raised inside callbacks ----------------------------------------------------

    def _store_callback_error(self, exc):
        """Keep the first exception raised by a user callback during a C
        call; it is re-raised when that call returns."""
        if self._callback_error is None:
            self._callback_error = exc

    cdef int _raise_callback_error(self) except -1:
        exc = self._callback_error
        if exc is not None:
            self._callback_error = None
            raise exc
        return 0

    cdef int _check_c_errors(self) except -1:
        if cpTakeOutOfMemory():
            raise MemoryError("the space ran out of memory; some contacts were dropped")
        collision_check_flags()
        return 0

    # -- properties ------------------------------------------------------------------------

    @property
    def shapes(self):
        """The shapes in the space, a live view in the order they were added.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.add(tamias2d.Circle(s.static_body, 1))
        >>> len(s.shapes)
        1
        """
        return self._shapes.keys()

    @property
    def bodies(self):
        """The bodies in the space (static ones included, the space's own
        ``static_body`` excluded), a live view in the order they were added.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.add(tamias2d.Body())
        >>> len(s.bodies)
        1
        """
        return self._bodies.keys()

    @property
    def constraints(self):
        """The constraints (joints) in the space, a live view in the order
        they were added.

        >>> import tamias2d
        >>> len(tamias2d.Space().constraints)
        0
        """
        return self._constraints.keys()

    @property
    def static_body(self):
        """A static body owned by the space, made on first use; handy for
        attaching ground and walls.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.static_body.body_type == tamias2d.Body.STATIC
        True
        """
        if self._static_body is None:
            body = Body(body_type=Body.STATIC)
            (<Body>body)._space = weakref.ref(self)
            if cpSpaceAddBody(&self._space, &(<Body>body)._body) == NULL:
                (<Body>body)._space = None
                cpTakeOutOfMemory()
                raise MemoryError("not enough memory to add the static body")
            self._static_body = body
        return self._static_body

    @property
    def iterations(self):
        """Solver iterations per step (default 10). More iterations give
        stiffer contacts at a higher cost.

        >>> import tamias2d
        >>> tamias2d.Space().iterations
        10
        """
        return self._space.iterations

    @iterations.setter
    def iterations(self, value):
        cdef long v = value
        if v <= 0 or v > 2147483647:
            raise ValueError("iterations must be a positive integer")
        tamias_wait_for_step(&self._space)
        self._space.iterations = <int>v

    # -- the solver (not in pymunk: tamias2d has two) ---------------------------------------

    @property
    def solver(self):
        """The contact and joint solver: ``"chipmunk"`` (the default:
        Munk2D's, bitwise pymunk's) or ``"soft"`` (Box2D v3's soft step with
        substeps, soft contacts, relax and restitution passes and speculative
        contacts; see README "Two solvers"). Settable between steps, and as
        ``Space(solver=...)``; changing it from a callback during a step
        raises :class:`~tamias2d.errors.SpaceLocked`. An unknown name is a
        ValueError listing the names.

        The chipmunk solver updates positions at the start of its step (with
        the last step's velocities), the soft solver inside its substeps: a
        switch from chipmunk to soft skips one position update, a switch back
        repeats one.

        Joints in the soft solver are soft constraints, solved every substep
        with ``h = dt / substeps`` (warm start, an impulse pass in the solve
        and one in the relax), their errors corrected by a spring of
        :attr:`joint_hertz` and :attr:`joint_damping_ratio`: ``max_force``
        still bounds the force (an impulse of ``max_force * h`` per substep),
        ``max_bias`` caps the correction speed, ``error_bias`` is not used;
        slide joints, rotary limits and ratchets hold their nearer limit
        before it is reached. Springs and the motor are Chipmunk's own.
        ``Constraint.impulse`` after a step is the last substep's impulse
        times ``substeps``.

        In the soft solver, bodies that meet more slowly than gravity makes
        a body fall in one step (``gravity.length * dt``) do not bounce, as
        under Box2D's restitution threshold, where one of them falls under
        the space's gravity (its default ``velocity_func``).

        >>> import tamias2d
        >>> tamias2d.Space().solver
        'chipmunk'
        >>> s = tamias2d.Space(solver="soft")
        >>> s.solver
        'soft'
        >>> s.solver = "box2d"
        Traceback (most recent call last):
          ...
        ValueError: unknown solver 'box2d': the solvers are 'chipmunk', 'soft'
        """
        return "soft" if self._space.soft.solver == TAMIAS_SOLVER_SOFT else "chipmunk"

    @solver.setter
    def solver(self, value):
        cdef int which
        if value == "chipmunk":
            which = TAMIAS_SOLVER_CHIPMUNK
        elif value == "soft":
            which = TAMIAS_SOLVER_SOFT
        else:
            raise ValueError(f"unknown solver {value!r}: the solvers are 'chipmunk', 'soft'")
        if self._locked or cpSpaceIsLocked(&self._space):
            raise SpaceLocked("the solver cannot be changed during a step (from a callback); "
                              "change it between steps")
        tamias_wait_for_step(&self._space)
        self._space.soft.solver = which

    @property
    def substeps(self):
        """Substeps per step of the soft solver (default 4; the chipmunk
        solver ignores it): each step collides once, then integrates and
        solves ``substeps`` times with ``dt / substeps``. An integer >= 1.
        A step in which most contacts are new (at least 64 touching pairs,
        more than half of them under 3 steps old: a pile built at rest, or
        many bodies landing at once) takes four times as many, so that the
        pile does not sag while its contacts learn their loads; this
        attribute keeps the value set.

        >>> import tamias2d
        >>> s = tamias2d.Space(solver="soft")
        >>> s.substeps
        4
        >>> s.substeps = 8
        >>> s.substeps = 0
        Traceback (most recent call last):
          ...
        ValueError: substeps must be an integer >= 1, not 0
        """
        return self._space.soft.substeps

    @substeps.setter
    def substeps(self, value):
        if isinstance(value, bool) or not isinstance(value, int) or not (1 <= value <= 1000000):
            raise ValueError(f"substeps must be an integer >= 1, not {value!r}")
        tamias_wait_for_step(&self._space)
        self._space.soft.substeps = <int>value

    @property
    def contact_hertz(self):
        """Stiffness of the soft solver's contacts, in hertz (default 30;
        capped at a quarter of the substep rate, and twice as stiff against
        static and kinematic bodies). Time only: the same in any length
        units. 0 turns the push-out off (rigid velocity contacts).

        A contact whose load (its last impulses) would sink it deeper than
        0.5% of the smaller body's size at this stiffness is made stiffer,
        stiffness and damping together, up to 10 times between bodies of
        alike mass and 5 times across large mass ratios: the bottom of a tall
        stack or pyramid then sinks no deeper than its top.

        >>> import tamias2d
        >>> tamias2d.Space().contact_hertz
        30.0
        """
        return self._space.soft.contactHertz

    @contact_hertz.setter
    def contact_hertz(self, value):
        tamias_wait_for_step(&self._space)
        self._space.soft.contactHertz = _soft_nonneg(value, "contact_hertz")

    @property
    def contact_damping_ratio(self):
        """Damping ratio of the soft solver's contacts (default 10: heavily
        over-damped, so overlaps are pushed out without bounce; 1 is
        critical damping). Dimensionless.

        >>> import tamias2d
        >>> tamias2d.Space().contact_damping_ratio
        10.0
        """
        return self._space.soft.contactDampingRatio

    @contact_damping_ratio.setter
    def contact_damping_ratio(self, value):
        tamias_wait_for_step(&self._space)
        self._space.soft.contactDampingRatio = _soft_nonneg(value, "contact_damping_ratio")

    @property
    def joint_hertz(self):
        """Stiffness of the soft solver's joint correction, in hertz
        (default 60; capped at a quarter of the substep rate). A joint pulled
        apart (a pin's distance, a pivot's anchors, a gear's phase, a limit
        passed) is brought back by a spring of this frequency and
        :attr:`joint_damping_ratio`, no faster than the joint's ``max_bias``;
        ``max_force`` caps the joint's force as in the chipmunk solver, and
        ``error_bias`` is not used. 0 turns the correction off (the joints
        still hold velocities). Time only: the same in any length units.
        The chipmunk solver does not use it.

        >>> import tamias2d
        >>> tamias2d.Space().joint_hertz
        60.0
        """
        return self._space.soft.jointHertz

    @joint_hertz.setter
    def joint_hertz(self, value):
        tamias_wait_for_step(&self._space)
        self._space.soft.jointHertz = _soft_nonneg(value, "joint_hertz")

    @property
    def joint_damping_ratio(self):
        """Damping ratio of the soft solver's joint correction (default 2:
        over-damped, so a stretched chain closes without ringing; 1 is
        critical damping). Dimensionless.

        >>> import tamias2d
        >>> tamias2d.Space().joint_damping_ratio
        2.0
        """
        return self._space.soft.jointDampingRatio

    @joint_damping_ratio.setter
    def joint_damping_ratio(self, value):
        tamias_wait_for_step(&self._space)
        self._space.soft.jointDampingRatio = _soft_nonneg(value, "joint_damping_ratio")

    @property
    def contact_push_out(self):
        """The soft solver's maximum speed (scene units per second) at which
        overlapping shapes are pushed apart. By default it follows the scene's
        scale: 600 x ``collision_slop`` per second (60 for the default slop
        0.1, i.e. Box2D's 3 m/s for its 0.005 m slop). Set a number >= 0 to
        fix it, ``None`` to go back to the default.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> round(s.contact_push_out, 6)
        60.000001
        >>> s.collision_slop = 0.001
        >>> round(s.contact_push_out, 6)
        0.6
        >>> s.contact_push_out = 5
        >>> s.contact_push_out
        5.0
        """
        return SoftPushOut(&self._space)

    @contact_push_out.setter
    def contact_push_out(self, value):
        tamias_wait_for_step(&self._space)
        self._space.soft.pushOut = -1.0 if value is None else _soft_nonneg(value, "contact_push_out")

    @property
    def speculative_distance(self):
        """How far apart (scene units) the soft solver's narrow phase still
        reports contact points, so that approaching shapes stop before they
        overlap. Default 4 x ``collision_slop`` (follows it); ``None`` goes
        back to the default. The chipmunk solver always uses 0 (touching
        points only, as pymunk). Points of such contacts may have a positive
        ``distance``; begin and separate callbacks fire when shapes come
        within or leave this distance.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> round(s.speculative_distance, 6)
        0.4
        """
        return SoftSpeculative(&self._space)

    @speculative_distance.setter
    def speculative_distance(self, value):
        tamias_wait_for_step(&self._space)
        self._space.soft.speculative = (-1.0 if value is None
                                        else _soft_nonneg(value, "speculative_distance"))

    @property
    def gravity(self):
        """Gravity applied to every dynamic body, default (0, 0).

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.gravity = 0, -900
        >>> s.gravity
        Vec2d(0.0, -900.0)
        """
        return vec2d_from_cpv(self._space.gravity)

    @gravity.setter
    def gravity(self, gravity_vector):
        cdef cpVect g = cpv_from_object_finite(gravity_vector, "gravity")
        tamias_wait_for_step(&self._space)
        cpSpaceSetGravity(&self._space, g)

    @property
    def damping(self):
        """Fraction of velocity a body keeps per second (default 1: no
        damping). 0.9 loses 10% per second.

        >>> import tamias2d
        >>> tamias2d.Space().damping
        1.0
        """
        return self._space.damping

    @damping.setter
    def damping(self, damping):
        cdef double d = damping
        if not (d >= 0.0) or not isfinite(d):
            raise ValueError("damping must be a finite number >= 0")
        tamias_wait_for_step(&self._space)
        self._space.damping = d

    @property
    def idle_speed_threshold(self):
        """Speed under which a body counts as idle for sleeping; 0 (the
        default) derives it from gravity.

        >>> import tamias2d
        >>> tamias2d.Space().idle_speed_threshold
        0.0
        """
        return self._space.idleSpeedThreshold

    @idle_speed_threshold.setter
    def idle_speed_threshold(self, value):
        cdef double v = value
        # A speed: negative ones (pymunk squares them) mean nothing. inf is
        # kept: every body counts as idle, and sleeps after the idle time.
        if not (v >= 0.0):
            raise ValueError(f"idle_speed_threshold must be a speed >= 0 (0 derives it from "
                             f"gravity), not {value!r}")
        tamias_wait_for_step(&self._space)
        self._space.idleSpeedThreshold = v

    @property
    def sleep_time_threshold(self):
        """Idle time after which a group of bodies falls asleep; ``inf``
        (the default) turns sleeping off. Setting it to ``inf`` wakes every
        sleeping body (pymunk leaves them asleep and its next steps can
        hang). NaN and negative times are refused (ValueError).

        At 0 every dynamic body falls asleep at the end of each step, moving
        or not, as in pymunk (no idle time is below 0), except those that
        touch or are jointed to a kinematic body: they stay awake (pymunk
        aborts there). Kinematic bodies never sleep, at any threshold.

        >>> import tamias2d
        >>> tamias2d.Space().sleep_time_threshold
        inf
        """
        return self._space.sleepTimeThreshold

    @sleep_time_threshold.setter
    def sleep_time_threshold(self, value):
        cdef double v = value
        cdef cpArray *components = self._space.sleepingComponents
        if not (v >= 0.0):
            raise ValueError(f"sleep_time_threshold must be a time >= 0 (inf turns sleeping "
                             f"off), not {value!r}")
        tamias_wait_for_step(&self._space)
        self._space.sleepTimeThreshold = v
        if v == INFINITY:
            # Sleeping off: wake everything that sleeps, as Box2D does. Munk2D
            # leaves the bodies asleep, and with the flood fill off nothing
            # ever wakes them: the step threads arbiters into their lists
            # again and again (a loop in the contact graph, a hang or a heap
            # corruption later). Each wake removes its component.
            while components.num:
                cpSpaceWakeComponent(&self._space, <cpBody *>components.arr[components.num - 1])

    @property
    def collision_slop(self):
        """Overlap allowed between shapes before they are pushed apart
        (default 0.1 as a C float: 0.10000000149011612).

        In the soft solver it is the scene's unit of length instead: the
        speculative distance (4 x slop) and the push-out speed (600 x slop
        per second) follow it, and overlap is pushed out softly all the way
        (a contact settles where its spring carries its load), as in Box2D.
        Scale it with the scene.

        >>> import tamias2d
        >>> tamias2d.Space().collision_slop
        0.10000000149011612
        """
        return self._space.collisionSlop

    @collision_slop.setter
    def collision_slop(self, value):
        cdef double slop = value
        # an infinite slop gives the contacts an infinite bias: NaN bodies
        if not isfinite(slop):
            raise ValueError(f"collision_slop must be a finite number, not {value!r}")
        tamias_wait_for_step(&self._space)
        self._space.collisionSlop = slop

    @property
    def collision_bias(self):
        """Fraction of overlap left uncorrected after one second (default
        ``pow(1 - 0.1, 60)`` in C floats).

        A step corrects ``1 - collision_bias ** dt`` of the overlap: 0
        corrects it all at once, 1 not at all. NaN, inf and negative values
        are refused (ValueError: the correction would be NaN). Values above 1
        are accepted, as pymunk's own tests set them, but they push
        overlapping shapes further in.

        >>> import tamias2d
        >>> tamias2d.Space().collision_bias
        0.0017970074436457143
        """
        return self._space.collisionBias

    @collision_bias.setter
    def collision_bias(self, value):
        cdef double bias = value
        if not (isfinite(bias) and bias >= 0.0):
            raise ValueError(f"collision_bias must be a finite number >= 0 (the fraction of "
                             f"overlap left after a second, 0 to 1), not {value!r}")
        tamias_wait_for_step(&self._space)
        self._space.collisionBias = bias

    @property
    def collision_persistence(self):
        """Steps an arbiter is kept after its shapes separate (default 3).

        At 0, as in pymunk, the arbiters expire in the step that finds them,
        before the solver runs: contacts are reported (``begin`` at every
        step, ``separate`` never) but not solved, and shapes pass through
        each other.

        >>> import tamias2d
        >>> tamias2d.Space().collision_persistence
        3
        """
        return self._space.collisionPersistence

    @collision_persistence.setter
    def collision_persistence(self, value):
        if isinstance(value, float):
            if value != int(value):
                raise ValueError("collision_persistence must be a whole number of steps")
            value = int(value)
        cdef long long v = value
        if v < 0 or v > 4294967295:
            raise ValueError("collision_persistence must be between 0 and 2**32-1")
        tamias_wait_for_step(&self._space)
        self._space.collisionPersistence = <cpTimestamp>v

    @property
    def current_time_step(self):
        """The dt of the step in progress (in a callback) or of the last one.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.step(0.25)
        >>> s.current_time_step
        0.25
        """
        return self._space.curr_dt

    @property
    def threads(self):
        """The thread count asked of a ``threaded`` space (1 or 2, as pymunk
        clamps it; always 1 for a space that is not threaded).

        In the soft solver (:attr:`solver` ``"soft"``) a threaded space
        with ``threads = 2`` runs the step's body and contact stages on the
        calling thread and a worker thread: contacts are coloured so that
        no two of a colour share a body, and each stage's chunks can be
        taken by either thread, so the result is bit for bit the one of
        ``threads = 1`` (and of a space that is not threaded). The narrow
        phase, joints and Python integrators run on the calling thread.
        The chipmunk solver always steps on the calling thread (its results
        are a one-thread pymunk step's). To use more cores, step separate
        spaces at once (:func:`tamias2d.step_spaces`, or threads: the step
        runs without the GIL).

        >>> import tamias2d
        >>> s = tamias2d.Space(threaded=True)
        >>> s.threads = 2
        >>> s.threads
        2
        >>> t = tamias2d.Space()
        >>> t.threads = 2
        >>> t.threads
        1
        """
        if not self.threaded:
            return 1
        return self._space.soft.threads

    @threads.setter
    def threads(self, n):
        cdef long k = n
        if not self.threaded:
            return
        # pymunk's threaded space: 0 means 1, at most 2.
        self._space.soft.threads = 1 if k <= 1 else 2

    # -- adding and removing ---------------------------------------------------------------

    def add(self, *objs):
        """Add bodies, shapes and constraints (in any order: bodies go in
        first, then shapes and constraints in the order given).

        Inside a step (from a callback) the objects are added when the step
        ends, in the order they were passed. A constraint's bodies need not
        be in the space (as in pymunk).

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> b = tamias2d.Body(1, 10)
        >>> c = tamias2d.Circle(b, 5)
        >>> s.add(c, b)
        >>> list(s.bodies) == [b] and list(s.shapes) == [c]
        True
        """
        tamias_wait_for_step(&self._space)
        if self._locked:
            for o in objs:
                self._add_later[o] = None
            return
        if cpSpaceIsLocked(&self._space):
            raise SpaceLocked("the space is locked (a query or debug draw is running)")
        for o in objs:
            if not isinstance(o, (Body, Shape, Constraint)):
                raise TypeError(f"Unsupported type {type(o)} of {o!r}: "
                                "only bodies, shapes and constraints can be added to a Space")
        for o in objs:
            if isinstance(o, Body):
                self._add_body(<Body>o)
        for o in objs:
            if isinstance(o, Shape):
                self._add_shape(<Shape>o)
            elif isinstance(o, Constraint):
                _add_constraint(self, <Constraint>o)

    def add_static_bulk(self, *objs):
        """Add many shapes (typically static: terrain, walls, a level) fast.

        The same as ``add(*bisection_order(objs))``: see
        :func:`bisection_order`. Adding 100,000 segments laid in a row with
        :meth:`add` takes minutes (in pymunk too), since the bounding-box
        tree degenerates into one long branch; this takes a fraction of a
        second. The shapes get their ids in the order they are added, so
        the scene is the one pymunk builds from
        ``space.add(*bisection_order(objs))``, and it steps bit for bit
        like it; it is not the scene ``add(*objs)`` builds (the order of
        query results and of collision pairs with these shapes differs).

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> row = [tamias2d.Segment(s.static_body, (i, 0), (i + 1, 0), 0.5) for i in range(1000)]
        >>> s.add_static_bulk(*row)
        >>> len(s.shapes)
        1000
        """
        self.add(*bisection_order(objs))

    cdef _add_body(self, Body body):
        if body in self._bodies:
            raise AlreadyInSpace("Body already added to this space.")
        if body.space is not None:
            raise AlreadyInSpace("Body already added to another space.")
        # Shapes left in another space by remove(body): once the body sleeps
        # here Munk2D would file them in this space's indexes as well.
        for shape in body.shapes:
            if shape.space is not None and shape.space is not self:
                raise AlreadyInSpace("The body's shapes are in another space: remove them "
                                     "from it before adding the body to this space.")
        tamias_check_body_joints(&self._space, &body._body)
        body._space = weakref.ref(self)
        if cpSpaceAddBody(&self._space, &body._body) == NULL:
            body._space = None
            cpTakeOutOfMemory()
            raise MemoryError("not enough memory to add the body")
        self._bodies[body] = None

    cdef _add_shape(self, Shape shape):
        if shape in self._shapes:
            raise AlreadyInSpace("Shape already added to space.")
        if shape.space is not None:
            raise AlreadyInSpace(
                "Shape already added to another space. A shape can only be in one space at a time.")
        body = shape.body
        if body is None or shape._shape.body == NULL:
            raise IllegalShape("The shape's body is not set.")
        if body.space is not self or (<Body>body)._body.space != &self._space:
            raise NotInSpace("The shape's body must be added to the space before "
                             "(or at the same time) as the shape.")
        shape._space = weakref.ref(self)
        self._shapes[shape] = None
        cpSpaceAddShape(&self._space, shape._shape)
        if cpTakeOutOfMemory():
            raise MemoryError("the space ran out of memory while adding the shape")

    def remove(self, *objs):
        """Remove bodies, shapes and constraints.

        Inside a step (from a callback) the removal happens when the step
        ends. Removing a shape that touches another calls the ``separate``
        callbacks at once.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> b = tamias2d.Body(1, 10)
        >>> c = tamias2d.Circle(b, 5)
        >>> s.add(b, c)
        >>> s.remove(c, b)
        >>> len(s.shapes), len(s.bodies)
        (0, 0)
        """
        tamias_wait_for_step(&self._space)
        if self._locked:
            for o in objs:
                self._remove_later[o] = None
            return
        if cpSpaceIsLocked(&self._space):
            raise SpaceLocked("the space is locked (a query or debug draw is running)")
        self._remove(objs)
        removed = set()
        while self._remove_later:
            to_remove, _ = self._remove_later.popitem()
            if to_remove not in removed:
                self._remove((to_remove,))
                removed.add(to_remove)
        self._raise_callback_error()

    cdef _remove(self, tuple objs):
        for o in objs:
            if isinstance(o, Body):
                self._remove_body(<Body>o)
            elif isinstance(o, Shape):
                self._remove_shape(<Shape>o)
            elif isinstance(o, Constraint):
                _remove_constraint(self, <Constraint>o)
            else:
                raise TypeError(f"Unsupported type {type(o)} of {o!r}")

    cdef _remove_shape(self, Shape shape):
        if shape not in self._shapes:
            raise NotInSpace("shape not in space, already removed?")
        shape._space = None
        if shape._shape.space == &self._space:
            cpSpaceRemoveShape(&self._space, shape._shape)
        del self._shapes[shape]

    cdef _remove_body(self, Body body):
        if body not in self._bodies:
            raise NotInSpace("body not in space, already removed?")
        body._space = None
        if body._body.space == &self._space:
            cpSpaceRemoveBody(&self._space, &body._body)
        if body._body.shapeList != NULL:
            self._may_have_orphans = True  # its shapes stay in the space
        del self._bodies[body]

    # -- reindexing --------------------------------------------------------------------------

    def reindex_shape(self, shape):
        """Update the broad phase data of one shape (after moving a static
        body, for example).

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> c = tamias2d.Circle(s.static_body, 5)
        >>> s.add(c)
        >>> s.static_body.position = 100, 0
        >>> s.reindex_shape(c)
        >>> c.bb.left
        95.0
        """
        cdef Shape sh = shape
        if cpSpaceIsLocked(&self._space):
            raise SpaceLocked("You cannot manually reindex objects while the space is locked. "
                              "Wait until the current query or step is complete.")
        if sh._shape.space != &self._space:
            raise NotInSpace("the shape is not in this space")
        tamias_wait_for_step(&self._space)
        cpSpaceReindexShape(&self._space, sh._shape)

    def reindex_shapes_for_body(self, body):
        """Update the broad phase data of every shape of a body.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> c = tamias2d.Circle(s.static_body, 5)
        >>> s.add(c)
        >>> s.static_body.position = 0, 100
        >>> s.reindex_shapes_for_body(s.static_body)
        >>> c.bb.bottom
        95.0
        """
        cdef Body b = body
        if cpSpaceIsLocked(&self._space):
            raise SpaceLocked("You cannot manually reindex objects while the space is locked. "
                              "Wait until the current query or step is complete.")
        tamias_wait_for_step(&self._space)
        cpSpaceReindexShapesForBody(&self._space, &b._body)

    def reindex_static(self):
        """Update the broad phase data of every static shape (after moving
        static bodies).

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> c = tamias2d.Circle(s.static_body, 5)
        >>> s.add(c)
        >>> s.static_body.position = -50, 0
        >>> s.reindex_static()
        >>> c.bb.right
        -45.0
        """
        if cpSpaceIsLocked(&self._space):
            raise SpaceLocked("You cannot manually reindex objects while the space is locked. "
                              "Wait until the current query or step is complete.")
        tamias_wait_for_step(&self._space)
        cpSpaceReindexStatic(&self._space)

    def use_spatial_hash(self, dim, count):
        """Use a spatial hash instead of the default bounding box trees for
        the broad phase.

        ``dim`` is the cell size (about the size of a typical shape) and
        ``count`` the minimum number of hash cells (about 10 times the number
        of shapes). The hash can beat the trees when there are very many
        shapes of one size; otherwise keep the trees.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.use_spatial_hash(20, 1000)
        >>> s.step(0.01)
        """
        cdef double cdim = dim
        cdef long ccount = count
        if not (cdim > 0.0) or not isfinite(cdim):
            raise ValueError("dim must be a finite number > 0")
        if ccount <= 0 or ccount > 2147483647:
            raise ValueError("count must be a positive integer")
        tamias_wait_for_step(&self._space)
        if self._locked or cpSpaceIsLocked(&self._space):
            raise SpaceLocked("use_spatial_hash cannot be called during a step or a query")
        if not cpSpaceUseSpatialHash(&self._space, cdim, <int>ccount):
            if cpTakeOutOfMemory():
                raise MemoryError("not enough memory for the spatial hash")
            raise ValueError(f"count {count} is too large for the spatial hash")
        if cpTakeOutOfMemory():
            raise MemoryError("the space ran out of memory while filling the spatial hash")

    # -- the step ----------------------------------------------------------------------------

    cdef int _raise_non_finite(self, cpBody *body, double dt) except -1:
        cdef cpArray *bodies
        cdef cpBody *other
        cdef cpConstraint *c
        cdef int i
        cdef Py_ssize_t n
        _forgetNonFiniteImpulses(&self._space)
        b = <object>body.userData if body.userData != NULL else None
        err = IllegalBody(
            f"The step (dt={dt!r}) overflowed: {b!r} has position ({body.p.x}, {body.p.y}), "
            f"velocity ({body.v.x}, {body.v.y}), angle {body.a}, angular velocity {body.w}. "
            f"Some input is too large for double precision (the time step, a velocity, a "
            f"force, a size). The space refuses to step until the bodies in this "
            f"exception's .bodies are set to finite values or removed.")
        # Every body the check of the step looks at (tamias_first_non_finite_body
        # and the orphans): the awake ones, the static ones, joints' bodies
        # outside the space, bodies whose shapes stayed in the space.
        found = {}
        for k in range(2):
            bodies = self._space.dynamicBodies if k == 0 else self._space.staticBodies
            for i in range(bodies.num):
                other = <cpBody *>bodies.arr[i]
                if _bodyNonFinite(other) and other.userData != NULL:
                    found[<object>other.userData] = None
        for i in range(self._space.constraints.num):
            c = <cpConstraint *>self._space.constraints.arr[i]
            other = c.a
            if other.space != &self._space and _bodyNonFinite(other) and other.userData != NULL:
                found[<object>other.userData] = None
            other = c.b
            if other.space != &self._space and _bodyNonFinite(other) and other.userData != NULL:
                found[<object>other.userData] = None
        if self._may_have_orphans:
            for shape in list(self._shapes):
                other = (<Shape>shape)._shape.body
                if (other != NULL and other.space != &self._space and _bodyNonFinite(other)
                        and other.userData != NULL):
                    found[<object>other.userData] = None
        # And the sleeping bodies, which the step's check does not read (a
        # body left NaN asleep was never named, so never reset: the sleeping
        # fuzzer's seeds 2164 and 2174). Chains are bounded by the bodies the
        # space holds.
        for i in range(self._space.sleepingComponents.num):
            other = <cpBody *>self._space.sleepingComponents.arr[i]
            n = len(self._bodies) + 1
            while other != NULL and n > 0:
                if _bodyNonFinite(other) and other.userData != NULL:
                    found[<object>other.userData] = None
                other = other.sleeping.next
                n -= 1
        err.bodies = list(found)
        raise err

    # The first non-finite body of the space, orphans included.
    cdef cpBody *_first_non_finite(self):
        cdef cpBody *body = tamias_first_non_finite_body(&self._space)
        cdef OrphanScan scan
        if body != NULL or not self._may_have_orphans:
            return body
        scan.space = &self._space
        scan.bad = NULL
        scan.nonFinite = NULL
        scan.orphans = 0
        cpSpatialIndexEach(self._space.dynamicShapes, _scanOrphans, &scan)
        cpSpatialIndexEach(self._space.staticShapes, _scanOrphans, &scan)
        return scan.nonFinite

    cdef int _check_bodies(self) except -1:
        cdef cpArray *bodies = self._space.dynamicBodies
        cdef cpBody *body
        if self._overflowed:
            body = self._first_non_finite()
            if body != NULL:
                self._raise_non_finite(body, self._space.curr_dt)
            self._overflowed = False
        body = _firstBadMassBody(bodies)
        if body != NULL:
            b = <object>body.userData if body.userData != NULL else None
            raise IllegalBody(
                f"Dynamic bodies must have a mass > 0 and < inf and moment > 0. "
                f"{b!r} has mass {body.m}, moment {body.i}.")
        # Bodies removed from the space whose shapes stayed still collide
        # through those shapes (a density of 0 can reach them there). Finding
        # them walks every shape, so only while there may be some: after such
        # a removal, or once for a new (or copied) space.
        if not self._may_have_orphans:
            return 0
        cdef OrphanScan scan
        scan.space = &self._space
        scan.bad = NULL
        scan.nonFinite = NULL
        scan.orphans = 0
        cpSpatialIndexEach(self._space.dynamicShapes, _scanOrphans, &scan)
        cpSpatialIndexEach(self._space.staticShapes, _scanOrphans, &scan)
        self._may_have_orphans = scan.orphans > 0
        body = scan.bad
        if body != NULL:
            b = <object>body.userData if body.userData != NULL else None
            raise IllegalBody(
                f"Dynamic bodies must have a mass > 0 and < inf and moment > 0. {b!r} (removed "
                f"from the space, its shapes still in it) has mass {body.m}, moment {body.i}.")
        return 0

    def step(self, dt):
        """Advance the simulation by ``dt`` (a fixed dt gives the most
        stable results).

        Objects added or removed from callbacks are added or removed when
        the step ends, then post-step callbacks run. An exception raised in
        a callback is re-raised here, after the step has finished.

        ``dt`` must be finite and >= 0 (ValueError; 0 does nothing). If the
        step overflows double precision (a huge ``dt``, speed or size), it
        raises :class:`~tamias2d.errors.IllegalBody` naming the bodies it
        made non-finite (in the exception's ``bodies``); the space refuses
        to step until they are set to finite values or removed.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> for _ in range(10):
        ...     s.step(0.01)
        """
        cdef double cdt = dt
        cdef cpBody *bad
        if not (isfinite(cdt) and cdt >= 0.0):
            # pymunk takes a negative dt and integrates backwards, with the
            # damping as pow(damping, dt): inf for a damping of 0.
            raise ValueError(f"dt must be a finite number >= 0, not {dt!r}")
        self._step_begin()
        with nogil:
            bad = tamias_space_step(&self._space, cdt)
        self._step_finish(bad, cdt)

    # Space.step in three parts, so that tamias2d.step_spaces can run the
    # middle one for many spaces on many threads: _step_begin (with the GIL:
    # checks, the space marked as stepping in this thread), the C step
    # (tamias_space_step, without the GIL) and _step_finish (with the GIL:
    # errors, deferred adds and removes, post-step callbacks).
    cdef int _step_begin(self) except -1:
        # Another thread stepping this space: wait for its step to end.
        tamias_wait_for_step(&self._space)
        if cpSpaceIsLocked(&self._space) or self._locked:
            raise SpaceLocked("step() cannot be called from inside a step or a query")
        # From here on other threads wait for this step (beginning may let
        # them run first, so the checks come after it).
        tamias_begin_step(&self._space)
        try:
            if cpSpaceIsLocked(&self._space) or self._locked:
                raise SpaceLocked("step() cannot be called from inside a step or a query")
            self._check_bodies()
            if self._space.constraints.num:
                tamias_check_constraints(&self._space)
            if self._space.soft.threads > 1 and self._space.soft.solver == TAMIAS_SOLVER_SOFT:
                SoftPoolEnsure()
        except BaseException:
            tamias_end_step(&self._space)
            raise
        self._locked = True
        return 0

    # Undoes _step_begin when the C step is not run after all.
    cdef void _step_abort(self) noexcept:
        self._locked = False
        tamias_end_step(&self._space)

    # Between two steps of one space on a step_spaces worker (no GIL): true
    # when _step_finish and the next _step_begin would do nothing but unlock
    # and lock again: no error or C flag of this thread to report, nothing
    # deferred, no post-step callback, no thread waiting for the space, every
    # check of _step_begin passing. The worker then runs the next step at
    # once; otherwise it takes the GIL for the two calls. Keep in step with
    # _step_begin, _step_finish and _after_step.
    cdef bint _quiet_between_steps(self, cpBody *bad) noexcept nogil:
        if bad != NULL or self._overflowed or self._may_have_orphans:
            return False
        if self._space.stepWaiters > 0 or cpOutOfMemory() or cpCollisionPeekFlags() != 0:
            return False
        # Only this thread can change these now: others wait for the step.
        if (PyDict_GET_SIZE(<PyObject *>self._add_later) != 0
                or PyDict_GET_SIZE(<PyObject *>self._remove_later) != 0
                or PyDict_GET_SIZE(<PyObject *>self._post_step_callbacks) != 0
                or <PyObject *>self._callback_error != <PyObject *>None):
            return False
        if _firstBadMassBody(self._space.dynamicBodies) != NULL:
            return False
        return self._space.constraints.num == 0 or tamias_constraints_ok(&self._space)

    cdef int _step_finish(self, cpBody *bad, double dt) except -1:
        cdef object overflow = None
        self._locked = False
        tamias_end_step(&self._space)
        try:
            self._check_c_errors()
            if bad == NULL and self._may_have_orphans:
                # Bodies removed from the space whose shapes stayed: the C
                # check cannot see them (see _first_non_finite).
                bad = self._first_non_finite()
            if bad != NULL:
                self._overflowed = True
                try:
                    self._raise_non_finite(bad, dt)
                except IllegalBody as e:
                    overflow = e
        finally:
            if overflow is None:
                self._after_step()
        if overflow is not None:
            # An overflow and a callback's error in one step: the overflow is
            # raised (the space refuses to step until the bodies it names are
            # reset, which a caller catching it does), the callback's error
            # as its context.
            try:
                self._after_step()
            except BaseException as late:
                overflow.__context__ = late
            raise overflow
        return 0

    cdef _after_step(self):
        cdef list later
        if not (self._add_later or self._remove_later or self._post_step_callbacks
                or self._callback_error is not None):
            return None   # the usual case: nothing deferred, nothing to run
        if self._add_later:
            later = list(self._add_later)
            self._add_later.clear()
            self.add(*later)
        removed = set()
        while self._remove_later:
            to_remove, _ = self._remove_later.popitem()
            if to_remove not in removed:
                removed.add(to_remove)
                self._remove((to_remove,))
        callbacks = self._post_step_callbacks
        self._post_step_callbacks = {}
        try:
            for key in callbacks:
                callbacks[key](self)
        finally:
            self._raise_callback_error()

    # -- callbacks ---------------------------------------------------------------------------

    def on_collision(self, collision_type_a=None, collision_type_b=None, begin=None,
                     pre_solve=None, post_solve=None, separate=None, data=None):
        """Set the callbacks for collisions between shapes of two collision
        types (None is a wildcard; ``(None, None)`` is every collision).

        Each callback is ``f(arbiter, space, data)``; its return value is
        ignored (set ``arbiter.process_collision`` to reject a collision).
        Phases: ``begin`` (first step of contact), ``pre_solve`` (every
        step, before solving), ``post_solve`` (after solving), ``separate``
        (the step the shapes part, or when one is removed). A later call for
        the same types replaces the callbacks it passes; pass
        :func:`empty_callback` to reset one. When several handlers match,
        they run in the order (a, b), (b, a), (a, None), (b, None),
        (None, None).

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> b = tamias2d.Body(1, 10)
        >>> c = tamias2d.Circle(b, 5)
        >>> c.collision_type = 1
        >>> s.add(b, c, tamias2d.Circle(s.static_body, 5))
        >>> log = []
        >>> s.on_collision(1, None, begin=lambda arb, space, data: log.append(data), data="hit")
        >>> s.step(0.01)
        >>> log
        ['hit']
        """
        cdef cpCollisionHandler *h
        cdef cpCollisionType ta, tb
        cdef CollisionHandler ch
        if collision_type_a is None and collision_type_b is not None:
            raise IllegalCollisionType(
                "collision_type_a can not be None if collision_type_b is not None. "
                "Please swap them.")
        tamias_wait_for_step(&self._space)
        key = (collision_type_a, collision_type_b)
        if key not in self._handlers:
            ta = CP_WILDCARD_COLLISION_TYPE if collision_type_a is None else collision_type_a
            tb = CP_WILDCARD_COLLISION_TYPE if collision_type_b is None else collision_type_b
            h = cpSpaceAddCollisionHandler(&self._space, ta, tb)
            if h == NULL:
                cpTakeOutOfMemory()
                raise MemoryError("not enough memory for a collision handler")
            ch = CollisionHandler.__new__(CollisionHandler)
            ch._handler = h
            ch._data = {}
            h.userData = <void *>ch
            self._handlers[key] = ch
        else:
            ch = self._handlers[key]
        for which, func, name in ((_BEGIN, begin, "begin"), (_PRE_SOLVE, pre_solve, "pre_solve"),
                                  (_POST_SOLVE, post_solve, "post_solve"),
                                  (_SEPARATE, separate, "separate")):
            if func is empty_callback:
                ch._set(which, None)
            elif func is not None:
                if not callable(func):
                    raise TypeError(f"{name} must be callable, not {type(func).__name__}")
                ch._set(which, func)
                ch._data[name] = data

    def add_post_step_callback(self, callback_function, key, *args, **kwargs):
        """Call ``callback_function(space, key, *args, **kwargs)`` once, after
        the next step ends. One callback per key; returns False (and adds
        nothing) if the key is already taken.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.add_post_step_callback(lambda space, key: print("after", key), 1)
        True
        >>> s.add_post_step_callback(print, 1)
        False
        >>> s.step(0.01)
        after 1
        """
        if key in self._post_step_callbacks:
            return False

        def f(space):
            callback_function(self, key, *args, **kwargs)

        self._post_step_callbacks[key] = f
        return True

    # -- queries -------------------------------------------------------------------------------

    def point_query(self, point, max_distance, shape_filter):
        """Shapes within ``max_distance`` of ``point`` (0: the point must be
        inside; negative: that deep inside), as a list of
        :class:`PointQueryInfo`. Sensors are included.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> c = tamias2d.Circle(s.static_body, 10)
        >>> s.add(c)
        >>> [(h.shape is c, h.distance) for h in s.point_query((15, 0), 10, tamias2d.ShapeFilter())]
        [(True, 5.0)]
        """
        cdef cpVect p = cpv_from_object(point)
        cdef cpFloat d = max_distance
        cdef cpShapeFilter f = _filter_from_object(shape_filter)
        cdef QueryHits hits
        hits.hits = NULL
        hits.count = hits.capacity = 0
        hits.failed = 0
        try:
            tamias_wait_for_step(&self._space)
            cpSpacePointQuery(&self._space, p, d, f, &hits)
            if hits.failed:
                cpTakeOutOfMemory()
                raise MemoryError("not enough memory for the query results")
            return _hits_to_list(&hits, 0)
        finally:
            cpfree(hits.hits)

    def point_query_nearest(self, point, max_distance, shape_filter):
        """The shape nearest to ``point`` within ``max_distance``, as a
        :class:`PointQueryInfo`, or None. Sensors are included.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.add(tamias2d.Circle(s.static_body, 10))
        >>> s.point_query_nearest((0, 25), 20, tamias2d.ShapeFilter()).point
        Vec2d(0.0, 10.0)
        >>> s.point_query_nearest((0, 25), 5, tamias2d.ShapeFilter()) is None
        True
        """
        cdef cpVect p = cpv_from_object(point)
        cdef cpFloat d = max_distance
        cdef cpShapeFilter f = _filter_from_object(shape_filter)
        cdef cpPointQueryInfo info
        cdef cpShape *shape
        tamias_wait_for_step(&self._space)
        shape = cpSpacePointQueryNearest(&self._space, p, d, f, &info)
        if shape == NULL:
            return None
        return PointQueryInfo(<object>shape.userData, vec2d_from_cpv(info.point), info.distance,
                              vec2d_from_cpv(info.gradient))

    def segment_query(self, start, end, radius, shape_filter):
        """Shapes hit by the segment from ``start`` to ``end`` swept with
        ``radius``, as a list of :class:`SegmentQueryInfo` (static shapes
        first). Sensors are included.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.add(tamias2d.Circle(s.static_body, 10))
        >>> [h.alpha for h in s.segment_query((-20, 0), (20, 0), 0, tamias2d.ShapeFilter())]
        [0.25]
        """
        # non-finite end points: the spatial hash's cell walk never ends
        cdef cpVect a = cpv_from_object_finite(start, "start")
        cdef cpVect b = cpv_from_object_finite(end, "end")
        cdef cpFloat r = radius
        cdef cpShapeFilter f = _filter_from_object(shape_filter)
        cdef QueryHits hits
        hits.hits = NULL
        hits.count = hits.capacity = 0
        hits.failed = 0
        try:
            tamias_wait_for_step(&self._space)
            cpSpaceSegmentQuery(&self._space, a, b, r, f, &hits)
            if hits.failed:
                cpTakeOutOfMemory()
                raise MemoryError("not enough memory for the query results")
            return _hits_to_list(&hits, 1)
        finally:
            cpfree(hits.hits)

    def segment_query_first(self, start, end, radius, shape_filter):
        """The first shape hit by the segment from ``start`` to ``end``
        swept with ``radius``, as a :class:`SegmentQueryInfo`, or None.
        Sensors are included.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.add(tamias2d.Circle(s.static_body, 10))
        >>> s.segment_query_first((-20, 0), (20, 0), 0, tamias2d.ShapeFilter()).point
        Vec2d(-10.0, 0.0)
        """
        # non-finite end points: the spatial hash's cell walk never ends
        cdef cpVect a = cpv_from_object_finite(start, "start")
        cdef cpVect b = cpv_from_object_finite(end, "end")
        cdef cpFloat r = radius
        cdef cpShapeFilter f = _filter_from_object(shape_filter)
        cdef cpSegmentQueryInfo info
        cdef cpShape *shape
        tamias_wait_for_step(&self._space)
        shape = cpSpaceSegmentQueryFirst(&self._space, a, b, r, f, &info)
        if shape == NULL:
            return None
        return SegmentQueryInfo(<object>shape.userData, vec2d_from_cpv(info.point),
                                vec2d_from_cpv(info.normal), info.alpha)

    def bb_query(self, bb, shape_filter):
        """Shapes whose bounding box overlaps ``bb``, as a list. Sensors are
        included.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> c = tamias2d.Circle(s.static_body, 10)
        >>> s.add(c)
        >>> s.bb_query(tamias2d.BB(5, 5, 20, 20), tamias2d.ShapeFilter()) == [c]
        True
        """
        cdef cpBB cbb = cpbb_from_object(bb)
        cdef cpShapeFilter f = _filter_from_object(shape_filter)
        cdef QueryHits hits
        hits.hits = NULL
        hits.count = hits.capacity = 0
        hits.failed = 0
        try:
            tamias_wait_for_step(&self._space)
            cpSpaceBBQuery(&self._space, cbb, f, &hits)
            if hits.failed:
                cpTakeOutOfMemory()
                raise MemoryError("not enough memory for the query results")
            return _hits_to_list(&hits, 2)
        finally:
            cpfree(hits.hits)

    def shape_query(self, shape):
        """Shapes overlapping ``shape`` (which need not be in the space), as
        a list of :class:`ShapeQueryInfo`. Sensors are included. The query
        shape's cached position is refreshed from its body first.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> c = tamias2d.Circle(s.static_body, 10)
        >>> s.add(c)
        >>> probe = tamias2d.Circle(tamias2d.Body(body_type=tamias2d.Body.KINEMATIC), 5)
        >>> [h.shape is c for h in s.shape_query(probe)]
        [True]
        """
        if not isinstance(shape, Shape):
            raise TypeError(f"shape_query needs a Shape, not {type(shape).__name__}")
        cdef Shape sh = <Shape>shape
        cdef ShapeQueryHits hits
        cdef int i
        hits.shapes = NULL
        hits.sets = NULL
        hits.count = hits.capacity = 0
        hits.failed = 0
        hits.anyCollision = 0
        try:
            tamias_wait_for_step(&self._space)
            cpSpaceShapeQuery(&self._space, sh._shape, &hits)
            collision_check_flags()
            if hits.failed:
                cpTakeOutOfMemory()
                raise MemoryError("not enough memory for the query results")
            return [ShapeQueryInfo(<object>hits.shapes[i].userData,
                                   contact_point_set_from_cp(&hits.sets[i]))
                    for i in range(hits.count)]
        finally:
            cpfree(hits.shapes)
            cpfree(hits.sets)

    # -- debug drawing -------------------------------------------------------------------------

    def debug_draw(self, options):
        """Draw the space with a :class:`SpaceDebugDrawOptions` backend:
        shapes, then constraints, then contact points, as the options'
        flags ask.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.add(tamias2d.Circle(s.static_body, 10))
        >>> s.debug_draw(tamias2d.SpaceDebugDrawOptions())  # doctest: +NORMALIZE_WHITESPACE
        draw_circle (Vec2d(0.0, 0.0), 0.0, 10.0,
            SpaceDebugColor(r=44.0, g=62.0, b=80.0, a=255.0),
            SpaceDebugColor(r=149.0, g=165.0, b=166.0, a=255.0))
        """
        if not getattr(options, "_use_chipmunk_debug_draw", True):
            for shape in self.shapes:
                options.draw_shape(shape)
            return
        with options:
            self._debug_draw(options)

    cdef _debug_draw(self, options):
        cdef cpTransform t = cptransform_from_object(options.transform)
        cdef unsigned long flags = options.flags
        cdef list shapes
        cdef Shape sh
        cdef cpShape *shape
        cdef cpBody *body
        cdef cpCircleShape *circle
        cdef cpSegmentShape *seg
        cdef cpPolyShape *poly
        cdef cpVect tc, tc2, pp0, pp1, ta, tb, ta2, p, v2, p1, p2, pa, pb, n
        cdef cpFloat r, angle
        cdef int i, j, count
        cdef cpArbiter *arb
        cdef cpArray *arbiters
        cdef cpArray *carr
        cdef Constraint con

        if flags & 1:
            # Shapes in cpSpaceEachShape order: dynamic tree, then static tree.
            shapes = []
            tamias_wait_for_step(&self._space)
            cpSpaceEachShape(&self._space, _collectShape, <void *>shapes)
            for obj in shapes:
                sh = <Shape>obj
                # The draw calls are Python: another thread may have started
                # a step meanwhile.
                tamias_wait_for_step(&self._space)
                shape = sh._shape
                if shape.space != &self._space:
                    continue  # removed by an earlier draw call
                body = shape.body
                outline = options.shape_outline_color
                fill = options._c(options.color_for_shape(sh))
                if shape.klass.type == CP_CIRCLE_SHAPE:
                    circle = <cpCircleShape *>shape
                    tc = cpTransformPoint(t, circle.tc)
                    tc2 = cpTransformPoint(t, cpv(circle.tc.x + circle.r, circle.tc.y))
                    r = cpvdist(tc, tc2)
                    pp0 = cpTransformPoint(t, cpv(0.0, 0.0))
                    pp1 = cpTransformPoint(t, cpv(1.0, 0.0))
                    angle = body.a + atan2(pp1.y - pp0.y, pp1.x - pp0.x)
                    options.draw_circle(vec2d_from_cpv(tc), angle, r, outline, fill)
                elif shape.klass.type == CP_SEGMENT_SHAPE:
                    seg = <cpSegmentShape *>shape
                    ta = cpTransformPoint(t, seg.ta)
                    tb = cpTransformPoint(t, seg.tb)
                    ta2 = cpTransformPoint(t, cpv(seg.ta.x + seg.r, seg.ta.y))
                    r = cpvdist(ta, ta2)
                    options.draw_fat_segment(vec2d_from_cpv(ta), vec2d_from_cpv(tb), r,
                                             outline, fill)
                elif shape.klass.type == CP_POLY_SHAPE:
                    poly = <cpPolyShape *>shape
                    count = poly.count
                    r = poly.r
                    verts = []
                    for i in range(count):
                        p = cpTransformPoint(t, poly.planes[i].v0)
                        if i == 0:
                            v2 = cpTransformPoint(t, cpv(poly.planes[0].v0.x + r, poly.planes[0].v0.y))
                            r = cpvdist(p, v2)
                        verts.append(vec2d_from_cpv(p))
                    options.draw_polygon(verts, r, outline, fill)

        if flags & 2:
            # cpSpaceEachConstraint order: the space's constraint array.
            tamias_wait_for_step(&self._space)
            carr = self._space.constraints
            constraints = []
            for i in range(carr.num):
                constraints.append(<object>(<cpConstraint *>carr.arr[i]).userData)
            color = options.constraint_color
            for obj in constraints:
                con = <Constraint>obj
                tamias_wait_for_step(&self._space)
                if con._constraint.space != &self._space:
                    continue  # removed by an earlier draw call
                tamias_constraint_debug_draw(con._constraint, t, options, color)

        if flags & 4:
            color = options.collision_point_color
            segments = []
            tamias_wait_for_step(&self._space)
            arbiters = self._space.arbiters
            for i in range(arbiters.num):
                arb = <cpArbiter *>arbiters.arr[i]
                n = arb.n
                for j in range(arb.count):
                    p1 = cpvadd(arb.body_a.p, arb.contacts[j].r1)
                    p2 = cpvadd(arb.body_b.p, arb.contacts[j].r2)
                    pa = cpTransformPoint(t, cpvadd(p1, cpvmult(n, -2.0)))
                    pb = cpTransformPoint(t, cpvadd(p2, cpvmult(n, 2.0)))
                    segments.append((pa.x, pa.y, pb.x, pb.y))
            for ax, ay, bx, by in segments:
                # pymunk skips segments with a NaN end point.
                if math.isnan(ax) or math.isnan(ay) or math.isnan(bx) or math.isnan(by):
                    continue
                options.draw_segment(vec2d_from_cpv(cpv(ax, ay)), vec2d_from_cpv(cpv(bx, by)), color)

    # -- copy and pickle (tamias2d._snapshot) ----------------------------------------------------

    def __getstate__(self):
        """The state used by copy and pickle: pymunk's layout (settings,
        user attributes, bodies, shapes, collision handlers, counters) plus
        the C state, so that a restored space steps on bit for bit as this
        one would. Not allowed during a step or a query.

        >>> import tamias2d
        >>> sorted(tamias2d.Space().__getstate__())
        ['custom', 'general', 'init', 'special']
        """
        tamias_wait_for_step(&self._space)
        return _snapshot().space_getstate(self)

    def __setstate__(self, state):
        """Restore a state made by :meth:`__getstate__` into a new Space.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.iterations = 3
        >>> t = tamias2d.Space.__new__(tamias2d.Space)
        >>> t.__setstate__(s.__getstate__())
        >>> t.iterations
        3
        """
        tamias_wait_for_step(&self._space)
        _snapshot().space_setstate(self, state)

    def __reduce__(self):
        return (copyreg.__newobj__, (type(self),), self.__getstate__())

    def __deepcopy__(self, memo):
        tamias_wait_for_step(&self._space)
        return _snapshot().space_deepcopy(self, memo)

    def copy(self):
        """A deep copy of the space: new bodies, shapes and collision
        handlers in the same state, stepping on bit for bit as this space
        would. Post-step callbacks are not copied (as in pymunk).

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> s.gravity = 0, -10
        >>> b = tamias2d.Body(1, 1)
        >>> s.add(b, tamias2d.Circle(b, 1))
        >>> t = s.copy()
        >>> s.step(0.1); t.step(0.1)
        >>> next(iter(t.bodies)).position == b.position
        True
        """
        tamias_wait_for_step(&self._space)
        return _snapshot().space_deepcopy(self, {})

    def _contact_graph_problem(self):
        """A test aid: walk every body's arbiter list and sleeping component
        and return a description of the first broken link (a loop, an
        arbiter listed on a body it does not touch), or None. The step's
        flood fill would hang on a loop; the fuzzer calls this after every
        step to catch the operation that made one."""
        cdef list found = []
        cdef cpBody *body
        cdef cpArbiter *arb
        cdef cpArbiter *prev
        cdef cpBody *member
        cdef cpBody *other
        cdef cpShape *shape
        cdef int n
        cdef list in_dynamic = [], in_static = []
        cpSpatialIndexEach(self._space.dynamicShapes, _collectShapeAddress, <void *>in_dynamic)
        cpSpatialIndexEach(self._space.staticShapes, _collectShapeAddress, <void *>in_static)
        if set(in_dynamic) & set(in_static):
            return "a shape is in both the dynamic and the static index"
        if len(set(in_dynamic)) != len(in_dynamic) or len(set(in_static)) != len(in_static):
            return "a shape is twice in an index"
        static_set = set(in_static)
        for addr in in_dynamic + in_static:
            shape = <cpShape *><uintptr_t>addr
            if shape.body == NULL:
                continue
            # Awake dynamic and kinematic bodies' shapes are in the dynamic
            # index; static and sleeping bodies' shapes in the static one.
            if (addr in static_set) != (cpBodyGetType(shape.body) == CP_BODY_TYPE_STATIC
                                        or cpBodyIsSleeping(shape.body)):
                return (f"a shape of {<object>shape.userData!r} is in the "
                        f"{'static' if addr in static_set else 'dynamic'} index")
            found.append(<uintptr_t>shape.body)
        for i in range(self._space.dynamicBodies.num):
            found.append(<uintptr_t>self._space.dynamicBodies.arr[i])
        current = {<uintptr_t>self._space.arbiters.arr[i]
                   for i in range(self._space.arbiters.num)}
        for addr in dict.fromkeys(found):
            body = <cpBody *><uintptr_t>addr
            name = repr(<object>body.userData) if body.userData != NULL else hex(addr)
            arb = body.arbiterList
            prev = NULL
            n = 0
            seen = set()
            while arb != NULL:
                if arb.body_a != body and arb.body_b != body:
                    return f"{name}'s arbiter list holds an arbiter of other bodies"
                if cpArbiterThreadForBody(arb, body).prev != prev:
                    return f"{name}'s arbiter list has a wrong back link at entry {n}"
                other = arb.body_b if arb.body_a == body else arb.body_a
                if cpBodyIsSleeping(body):
                    # A sleeping body touches only its component and static bodies.
                    if (cpBodyGetType(other) != CP_BODY_TYPE_STATIC
                            and other.sleeping.root != body.sleeping.root):
                        return f"sleeping {name} is threaded to a body outside its component"
                elif cpBodyGetType(body) != CP_BODY_TYPE_STATIC and <uintptr_t>arb not in current:
                    # The next step unthreads only the arbiters of this step.
                    return f"awake {name} is threaded to an arbiter of an older step"
                n += 1
                if <uintptr_t>arb in seen:
                    return f"{name}'s arbiter list loops (entry {n} again)"
                seen.add(<uintptr_t>arb)
                prev = arb
                arb = cpArbiterNext(arb, body)
            if cpBodyIsSleeping(body):
                # (A component may hold bodies that are in no array and have
                # no shape in an index: shapeless sleeping bodies, bodies
                # outside the space held by a joint. So a loop is a member
                # met twice, not more members than the bodies found.)
                member = body.sleeping.root
                members = set()
                while member != NULL:
                    if <uintptr_t>member in members:
                        return f"{name}'s sleeping component loops"
                    members.add(<uintptr_t>member)
                    member = member.sleeping.next
        return None

    def __repr__(self):
        return f"Space(bodies={len(self._bodies)}, shapes={len(self._shapes)})"

