# The engine's C structures in one place, as Munk2D's chipmunk_structs.h keeps
# them: bodies, shapes, arbiters and the space point at each other, so their
# definitions cannot live in separate modules. Field names follow Munk2D so the
# port can be read beside its source. Functions live in the module of their
# struct (body.pxd, shape.pxd, collision.pxd, space.pxd, _spatialindex.pxd, ...).
from tamias2d._config cimport (cpFloat, cpHashValue, cpCollisionID, cpBool,
    cpDataPointer, cpCollisionType, cpGroup, cpBitmask, cpTimestamp,
    CP_MAX_CONTACTS_PER_ARBITER, CP_POLY_SHAPE_INLINE_ALLOC)
from tamias2d.vector cimport cpVect, cpBB, cpTransform, cpMat2x2

cdef struct cpBody
cdef struct cpShape
cdef struct cpArbiter
cdef struct cpSpace
cdef struct cpConstraint
cdef struct cpSpatialIndex
cdef struct cpContactBufferHeader

# -- containers (cpArray.c, cpHashSet.c; functions in _containers.pxd) --------
cdef struct cpArray:
    int num
    int max
    void **arr

ctypedef cpBool (*cpHashSetEqlFunc)(const void *ptr, const void *elt) noexcept nogil
ctypedef void *(*cpHashSetTransFunc)(const void *ptr, void *data) noexcept nogil
ctypedef void (*cpHashSetIteratorFunc)(void *elt, void *data) noexcept nogil
ctypedef cpBool (*cpHashSetFilterFunc)(void *elt, void *data) noexcept nogil

cdef struct cpHashSetBin:
    void *elt
    cpHashValue hash
    cpHashSetBin *next

cdef struct cpHashSet:
    unsigned int entries
    unsigned int size
    cpHashSetEqlFunc eql
    void *default_value
    cpHashSetBin **table
    cpHashSetBin *pooledBins
    cpArray *allocatedBuffers

# -- body (cpBody.c) ------------------------------------------------------------
ctypedef void (*cpBodyVelocityFunc)(cpBody *body, cpVect gravity, cpFloat damping, cpFloat dt) noexcept nogil
ctypedef void (*cpBodyPositionFunc)(cpBody *body, cpFloat dt) noexcept nogil

cpdef enum cpBodyType:
    CP_BODY_TYPE_DYNAMIC = 0
    CP_BODY_TYPE_KINEMATIC = 1
    CP_BODY_TYPE_STATIC = 2

cdef struct cpBodySleeping:
    cpBody *root
    cpBody *next
    cpFloat idleTime

cdef struct cpBody:
    cpBodyVelocityFunc velocity_func
    cpBodyPositionFunc position_func
    cpFloat m
    cpFloat m_inv
    cpFloat i
    cpFloat i_inv
    cpVect cog
    cpVect p
    cpVect v
    cpVect f
    cpFloat a
    cpFloat w
    cpFloat t
    cpTransform transform
    cpDataPointer userData      # borrowed pointer to the Python Body
    cpVect v_bias
    cpFloat w_bias
    cpSpace *space
    cpShape *shapeList
    cpArbiter *arbiterList
    cpConstraint *constraintList
    cpBodySleeping sleeping
    # Not in Munk2D (the soft solver, _soft_step.pxd): the body's slot in the
    # solver's body array during a soft step (scratch, valid only then), and
    # Body.is_bullet (continuous collision against dynamic bodies too).
    int solverIndex
    cpBool isBullet

# -- shapes (cpShape.c, cpPolyShape.c) ---------------------------------------------
cdef struct cpShapeFilter:
    cpGroup group
    cpBitmask categories
    cpBitmask mask

cdef struct cpShapeMassInfo:
    cpFloat m
    cpFloat i        # moment per unit mass about the shape's own centroid
    cpVect cog
    cpFloat area

cdef struct cpPointQueryInfo:
    const cpShape *shape
    cpVect point
    cpFloat distance
    cpVect gradient

cdef struct cpSegmentQueryInfo:
    const cpShape *shape
    cpVect point
    cpVect normal
    cpFloat alpha

cpdef enum cpShapeType:
    CP_CIRCLE_SHAPE = 0
    CP_SEGMENT_SHAPE = 1
    CP_POLY_SHAPE = 2
    CP_NUM_SHAPES = 3

ctypedef cpBB (*cpShapeCacheDataImpl)(cpShape *shape, cpTransform transform) noexcept nogil
ctypedef void (*cpShapeDestroyImpl)(cpShape *shape) noexcept nogil
ctypedef void (*cpShapePointQueryImpl)(const cpShape *shape, cpVect p, cpPointQueryInfo *info) noexcept nogil
ctypedef void (*cpShapeSegmentQueryImpl)(const cpShape *shape, cpVect a, cpVect b, cpFloat radius, cpSegmentQueryInfo *info) noexcept nogil

cdef struct cpShapeClass:
    cpShapeType type
    cpShapeCacheDataImpl cacheData
    cpShapeDestroyImpl destroy
    cpShapePointQueryImpl pointQuery
    cpShapeSegmentQueryImpl segmentQuery

cdef struct cpShape:
    const cpShapeClass *klass
    cpSpace *space
    cpBody *body
    cpShapeMassInfo massInfo
    cpBB bb
    cpBool sensor
    # Not Munk2D's (in the padding after `sensor`): the soft step's guess of
    # its body's slot, set with its box (_soft_step.pyx, SoftUpdateShapes).
    int softSlot
    cpFloat e
    cpFloat u
    cpVect surfaceV
    cpDataPointer userData      # borrowed pointer to the Python Shape
    cpCollisionType type
    cpShapeFilter filter
    cpShape *next
    cpShape *prev
    cpHashValue hashid
    # Not Munk2D's: the box of its leaf in the dynamic tree, kept by the tree
    # (its fat-box function, _bbtree.pyx), against which the soft step tests
    # the shape's new box so as to skip the leaves' refresh when none left
    # its box (SoftUpdateShapes).
    cpBB softFat

cdef struct cpCircleShape:
    cpShape shape
    cpVect c
    cpVect tc
    cpFloat r

cdef struct cpSegmentShape:
    cpShape shape
    cpVect a
    cpVect b
    cpVect n
    cpVect ta
    cpVect tb
    cpVect tn
    cpFloat r
    cpVect a_tangent
    cpVect b_tangent

cdef struct cpSplittingPlane:
    cpVect v0
    cpVect n

cdef struct cpPolyShape:
    cpShape shape
    cpFloat r
    int count
    # planes[0:count] hold world data (refreshed by cacheData), planes[count:2*count]
    # the local data. Points at _planes when count <= CP_POLY_SHAPE_INLINE_ALLOC,
    # else at a malloc'd block freed by the class destroy hook.
    cpSplittingPlane *planes
    cpSplittingPlane _planes[2 * CP_POLY_SHAPE_INLINE_ALLOC]

# -- narrow phase results (cpCollision.c) -----------------------------------------
cdef struct cpContact:
    cpVect r1
    cpVect r2
    cpFloat nMass
    cpFloat tMass
    cpFloat bounce
    cpFloat jnAcc
    cpFloat jtAcc
    cpFloat jBias
    cpFloat bias
    cpHashValue hash

cdef struct cpCollisionInfo:
    const cpShape *a
    const cpShape *b
    cpCollisionID id
    cpVect n
    int count
    cpContact *arr
    # Not in Munk2D: points are kept up to this separation (0 for the
    # chipmunk solver, which keeps only touching points; the soft solver's
    # speculative distance).
    cpFloat margin

cdef struct cpContactPoint:
    cpVect pointA
    cpVect pointB
    cpFloat distance

cdef struct cpContactPointSet:
    int count
    cpVect normal
    cpContactPoint points[CP_MAX_CONTACTS_PER_ARBITER]

# -- arbiters and collision handlers (cpArbiter.c, cpSpace.c) -------------------
ctypedef void (*cpCollisionBeginFunc)(cpArbiter *arb, cpSpace *space, cpDataPointer userData) noexcept nogil
ctypedef void (*cpCollisionPreSolveFunc)(cpArbiter *arb, cpSpace *space, cpDataPointer userData) noexcept nogil
ctypedef void (*cpCollisionPostSolveFunc)(cpArbiter *arb, cpSpace *space, cpDataPointer userData) noexcept nogil
ctypedef void (*cpCollisionSeparateFunc)(cpArbiter *arb, cpSpace *space, cpDataPointer userData) noexcept nogil

cdef struct cpCollisionHandler:
    cpCollisionType typeA
    cpCollisionType typeB
    cpCollisionBeginFunc beginFunc
    cpCollisionPreSolveFunc preSolveFunc
    cpCollisionPostSolveFunc postSolveFunc
    cpCollisionSeparateFunc separateFunc
    cpDataPointer userData

cpdef enum cpArbiterState:
    CP_ARBITER_STATE_FIRST_COLLISION = 0
    CP_ARBITER_STATE_NORMAL = 1
    CP_ARBITER_STATE_IGNORE = 2
    CP_ARBITER_STATE_CACHED = 3
    CP_ARBITER_STATE_INVALIDATED = 4

cdef struct cpArbiterThread:
    cpArbiter *next
    cpArbiter *prev

cdef struct cpArbiter:
    cpFloat e
    cpFloat u
    cpVect surface_vr
    cpDataPointer data
    const cpShape *a
    const cpShape *b
    cpBody *body_a
    cpBody *body_b
    cpArbiterThread thread_a
    cpArbiterThread thread_b
    int count
    cpContact *contacts
    cpVect n
    # Not Munk2D's: what the soft step noted of the two shapes in its narrow
    # phase (their bodies' guessed slots and their boxes' smaller sides),
    # valid in the step whose stamp softNoted holds (SoftNoteShapes).
    cpFloat softSideA
    cpFloat softSideB
    int softSlotA
    int softSlotB
    cpTimestamp softNoted
    cpCollisionHandler *handlerAB
    cpCollisionHandler *handlerBA
    cpCollisionHandler *handlerA
    cpCollisionHandler *handlerB
    cpBool swapped
    cpTimestamp stamp
    cpArbiterState state
    cpBool processCollision
    # In space.cachedArbiters (the soft solver checks its guesses against it).
    cpBool cached
    # Not Munk2D's: the collision types and space.handlerVersion the four
    # handlers were looked up for (0: not yet), so that an update finds them
    # again only when one of those changed.
    unsigned int handlerVersion
    cpCollisionType handlerTypeA
    cpCollisionType handlerTypeB
    # Not Munk2D's: the soft step marks last step's arbiters with the step's
    # stamp while it works out which to unthread and which to thread (only
    # within a step: SoftResetArbiters to SoftRethreadArbiters).
    cpTimestamp softThreaded

# -- constraints (declared for the body lists; joints are not ported yet) -------
ctypedef void (*cpConstraintPreStepImpl)(cpConstraint *constraint, cpFloat dt) noexcept nogil
ctypedef void (*cpConstraintApplyCachedImpulseImpl)(cpConstraint *constraint, cpFloat dt_coef) noexcept nogil
ctypedef void (*cpConstraintApplyImpulseImpl)(cpConstraint *constraint, cpFloat dt) noexcept nogil
ctypedef cpFloat (*cpConstraintGetImpulseImpl)(cpConstraint *constraint) noexcept nogil
ctypedef void (*cpConstraintPreSolveFunc)(cpConstraint *constraint, cpSpace *space) noexcept nogil
ctypedef void (*cpConstraintPostSolveFunc)(cpConstraint *constraint, cpSpace *space) noexcept nogil

# The soft solver's joints (constraints.pyx, called by _soft_step.pyx): a
# joint's position error is corrected by a mass-spring-damper, as Box2D v3's
# soft step does. softPreStep computes what preStep does but keeps the error
# itself in the joint's `bias` field; softApplyImpulse turns it into a target
# speed with the substep's softness (NULL: the relax pass, no correction).
cdef struct cpSoftness:
    cpFloat biasRate             # error -> target speed (1/s)
    cpFloat massScale
    cpFloat impulseScale

ctypedef void (*cpConstraintSoftApplyImpulseImpl)(cpConstraint *constraint, cpFloat dt,
                                                  const cpSoftness *soft) noexcept nogil

cdef struct cpConstraintClass:
    cpConstraintPreStepImpl preStep
    cpConstraintApplyCachedImpulseImpl applyCachedImpulse
    cpConstraintApplyImpulseImpl applyImpulse
    cpConstraintGetImpulseImpl getImpulse
    cpConstraintPreStepImpl softPreStep
    cpConstraintSoftApplyImpulseImpl softApplyImpulse

cdef struct cpConstraint:
    const cpConstraintClass *klass
    cpSpace *space
    cpBody *a
    cpBody *b
    cpConstraint *next_a
    cpConstraint *next_b
    cpFloat maxForce
    cpFloat errorBias
    cpFloat maxBias
    cpBool collideBodies
    cpConstraintPreSolveFunc preSolve
    cpConstraintPostSolveFunc postSolve
    cpDataPointer userData

# -- spatial index interface (cpSpatialIndex.h; dispatchers in _spatialindex.pxd) --
ctypedef cpBB (*cpSpatialIndexBBFunc)(void *obj) noexcept nogil
ctypedef void (*cpSpatialIndexIteratorFunc)(void *obj, void *data) noexcept nogil
ctypedef cpCollisionID (*cpSpatialIndexQueryFunc)(void *obj1, void *obj2, cpCollisionID id, void *data) noexcept nogil
ctypedef cpFloat (*cpSpatialIndexSegmentQueryFunc)(void *obj1, void *obj2, void *data) noexcept nogil

ctypedef void (*cpSpatialIndexDestroyImpl)(cpSpatialIndex *index) noexcept nogil
ctypedef int (*cpSpatialIndexCountImpl)(cpSpatialIndex *index) noexcept nogil
ctypedef void (*cpSpatialIndexEachImpl)(cpSpatialIndex *index, cpSpatialIndexIteratorFunc func, void *data) noexcept nogil
ctypedef cpBool (*cpSpatialIndexContainsImpl)(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil
ctypedef void (*cpSpatialIndexInsertImpl)(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil
ctypedef void (*cpSpatialIndexRemoveImpl)(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil
ctypedef void (*cpSpatialIndexReindexImpl)(cpSpatialIndex *index) noexcept nogil
ctypedef void (*cpSpatialIndexReindexObjectImpl)(cpSpatialIndex *index, void *obj, cpHashValue hashid) noexcept nogil
ctypedef void (*cpSpatialIndexReindexQueryImpl)(cpSpatialIndex *index, cpSpatialIndexQueryFunc func, void *data) noexcept nogil
ctypedef void (*cpSpatialIndexQueryImpl)(cpSpatialIndex *index, void *obj, cpBB bb, cpSpatialIndexQueryFunc func, void *data) noexcept nogil
ctypedef void (*cpSpatialIndexSegmentQueryImpl)(cpSpatialIndex *index, void *obj, cpVect a, cpVect b, cpFloat t_exit, cpSpatialIndexSegmentQueryFunc func, void *data) noexcept nogil

cdef struct cpSpatialIndexClass:
    cpSpatialIndexDestroyImpl destroy
    cpSpatialIndexCountImpl count
    cpSpatialIndexEachImpl each
    cpSpatialIndexContainsImpl contains
    cpSpatialIndexInsertImpl insert
    cpSpatialIndexRemoveImpl remove
    cpSpatialIndexReindexImpl reindex
    cpSpatialIndexReindexObjectImpl reindexObject
    cpSpatialIndexReindexQueryImpl reindexQuery
    cpSpatialIndexQueryImpl query
    cpSpatialIndexSegmentQueryImpl segmentQuery

cdef struct cpSpatialIndex:
    cpSpatialIndexClass *klass
    cpSpatialIndexBBFunc bbfunc
    cpSpatialIndex *staticIndex
    cpSpatialIndex *dynamicIndex

# -- space (cpSpace.c, cpSpaceStep.c) ---------------------------------------------
ctypedef void (*cpPostStepFunc)(cpSpace *space, void *key, void *data) noexcept nogil

cdef struct cpPostStepCallback:
    cpPostStepFunc func
    void *key
    void *data

# The soft solver's settings (Space.solver = "soft"; _soft_step.pxd). Lengths
# and speeds here are in scene units; a negative pushOut or speculative means
# "derived from collisionSlop" (see _soft_step.pxd for the factors).
cdef enum:
    TAMIAS_SOLVER_CHIPMUNK = 0
    TAMIAS_SOLVER_SOFT = 1

cdef struct cpSoftSettings:
    cpFloat contactHertz         # contact stiffness (Hz)
    cpFloat contactDampingRatio  # contact damping ratio (1 = critical)
    cpFloat jointHertz           # joint stiffness (Hz)
    cpFloat jointDampingRatio    # joint damping ratio
    cpFloat pushOut              # max push-out speed, units/s (< 0: auto)
    cpFloat speculative          # speculative distance, units (< 0: auto)
    int solver                   # TAMIAS_SOLVER_*
    int substeps                 # >= 1
    int threads                  # a threaded space's Space.threads (1 or 2)

# Per-step scratch of the soft solver, owned by the space (grown, never
# shrunk; freed by cpSpaceDestroy; never copied).
cdef struct cpSoftScratch:
    void *buf[26]                # indexed by _soft_step's SOFT_SCRATCH_* (< 26)
    int cap[26]                  # elements each buffer has room for
    # The broad phase's last walk, kept in the SOFT_SCRATCH_PAIRS buffer: its
    # pair count and the dynamic tree's version after it (0: no walk kept).
    int pairCount
    unsigned long long pairsVersion
    # With sleeping on: the stamp of the last soft step after whose contact
    # graph stage every awake body's arbiter list held exactly that step's
    # arbiters, threaded in array order, none with a sleeping body, and
    # nothing woke or slept in it (0: not known).
    # Waking, sleeping and dropping arbiters reset it (_space_step.pyx,
    # space.pyx); the next step may then leave those lists as they are.
    cpTimestamp threadsClean
    # With sleeping on: the awake components that the last union-find found
    # (the soft step's persistent islands, cpSpaceProcessComponents), kept in
    # the SOFT_SCRATCH_ISLANDS buffer: the step they hold after (0: none;
    # adding or removing a body or a joint, and a body's type change, reset
    # it), the dynamic bodies then, their components and the bodies that
    # step's contacts with kinematic or orphan bodies kept awake.
    cpTimestamp islandsStamp
    int islandBodies
    int islandCount
    int islandWakes
    # The soft step's last colouring of its contacts (SoftColorContacts),
    # which the next step takes over when its contacts' colouring keys are
    # those it was made from (kept in a scratch buffer): colorsKnown 0 when
    # there is none; colorPlan holds _soft_step's SoftColorPlan.
    bint colorsKnown
    unsigned long long colorPlan[40]

cdef struct cpContactBufferHeader:
    cpTimestamp stamp
    cpContactBufferHeader *next
    unsigned int numContacts

cdef struct cpSpace:
    int iterations
    cpVect gravity
    cpFloat damping
    cpFloat idleSpeedThreshold
    cpFloat sleepTimeThreshold
    cpFloat collisionSlop
    cpFloat collisionBias
    cpTimestamp collisionPersistence
    cpDataPointer userData      # borrowed pointer to the Python Space
    cpTimestamp stamp
    # Not Munk2D's: +1 whenever a collision handler is added (from 1), see
    # cpArbiter.handlerVersion.
    unsigned int handlerVersion
    # Not Munk2D's: how many cached arbiters have this step's stamp (see
    # cpSpaceStampArbiter), so that the cache filter can tell it has no work.
    int arbitersStamped
    cpFloat curr_dt
    cpArray *dynamicBodies
    cpArray *staticBodies
    cpArray *rousedBodies
    cpArray *sleepingComponents
    cpHashValue shapeIDCounter
    cpSpatialIndex *staticShapes
    cpSpatialIndex *dynamicShapes
    cpArray *constraints
    cpArray *arbiters
    cpContactBufferHeader *contactBuffersHead
    cpHashSet *cachedArbiters
    cpArray *pooledArbiters
    cpArray *allocatedBuffers
    int locked
    cpHashSet *collisionHandlers
    cpCollisionHandler globalHandler
    cpBool skipPostStep
    cpArray *postStepCallbacks
    cpBody *staticBody
    cpBody _staticBody
    # Not in Munk2D: the thread stepping this space without the GIL (0 when
    # none), the lock it holds meanwhile and the number of other threads
    # waiting for that step to end (see _threadguard.pxd).
    unsigned long stepThread
    void *stepLock
    int stepWaiters
    # Not in Munk2D: the second solver (see cpSoftSettings), and the margin
    # the narrow phase of this step keeps points within (0 in the chipmunk
    # solver, so its contacts are Munk2D's).
    cpSoftSettings soft
    cpSoftScratch softScratch
    cpFloat collideMargin
