"""The soft solver: an opt-in second solver (``Space.solver = "soft"``).

Box2D v3's soft step (Catto's Solver2D study) re-thought for Chipmunk's API
and units: the narrow phase runs once per step (with a speculative margin);
then each of ``substeps`` substeps integrates velocities, warm-starts, solves
soft contacts (a mass-spring-damper with a stiffness in hertz and a damping
ratio) with a bias, integrates positions and relaxes without the bias; after
the substeps restitution is applied and the impulses are stored for the next
step's warm start. Within the step a contact's separation follows the
bodies' relative motion (anchors relative to the centres, Box2D's adjusted
separation), without running the narrow phase again.

Scene meaning is Chipmunk's: friction and elasticity multiply, surface
velocity, handlers and sleeping are the shared stages of ``_space_step``.
collision_slop is the scene's unit of length here (speculative distance and
push-out speed follow it); overlap is pushed out softly, as in Box2D, not left
alone up to the slop, down to the depth at which a contact carries the part of
its load that is not preloaded (SoftPreload).

Beyond Box2D's soft step (docs/stability.md measures each):
  * a two-point manifold's normal rows are solved together (SoftSolve),
    so tall stacks do not buckle from the order the corners are solved in;
  * a loaded point's spring is preloaded with its load (SoftPreload), so a
    tall stack or a box under a heavier one stands at no depth, and a
    pyramid's bottom sinks half as deep as without;
  * two relax passes per substep (SOFT_RELAX_ITERATIONS) for two-point
    manifolds; one-point contacts take part in the last only, and so do
    those inside a web after a step's first substep (SoftRelax).

Layout: bodies are gathered into one contiguous SoftBody array (slot 0 is the
immovable body), contacts into one contiguous SoftContact array, once per
step; the substep loops touch only those arrays (and the joints' structs), no
allocation, no Python except user integrators and joints' callbacks. Graph
colouring and SIMD lanes can partition these arrays later.
"""
from libc.math cimport INFINITY, pow, sqrt, cos, sin, fabs, fmin, fmax, hypot
from libc.stdint cimport uint32_t, uint64_t
from libc.limits cimport INT_MAX
from libc.string cimport memset, memcmp
from tamias2d._config cimport cpFloat, cpBool, cpTimestamp
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArbiter, cpContact, cpArray, cpConstraint,
    cpSoftSettings, cpSoftScratch, TAMIAS_SOLVER_CHIPMUNK, TAMIAS_SOLVER_SOFT,
    CP_BODY_TYPE_KINEMATIC, CP_ARBITER_STATE_FIRST_COLLISION, CP_ARBITER_STATE_NORMAL,
    CP_ARBITER_STATE_IGNORE)
from tamias2d._containers cimport cprealloc, cpfree, cpHashSetFind, cpArrayPush, cpSetOutOfMemory
from tamias2d._threads cimport (tamias_take_next, tamias_load, tamias_store, tamias_add,
    tamias_exchange, tamias_cpu_relax, tamias_yield, tamias_now_ns)
from cpython.pythread cimport (PyThread_type_lock, PyThread_allocate_lock,
    PyThread_acquire_lock, PyThread_release_lock, WAIT_LOCK)

cdef extern from "pythread.h" nogil:
    unsigned long PyThread_start_new_thread(void (*func)(void *) noexcept nogil, void *arg)
from tamias2d.vector cimport cpVect, cpv, cpTransformNewTranspose, cpfmin, cpfmax, cpBBContainsBB
from tamias2d.body cimport cpBodyGetType, cpBodyIsSleeping, cpBodyUpdateVelocity, cpBodyUpdatePosition
from tamias2d.constraints cimport tamias_constraint_scale_impulse
from tamias2d._space_step cimport (cpSpaceLock, cpSpaceUnlock, StageResetArbiters,
    cpSpaceProcessComponents, StageFilterArbiterCache, StagePostSolve,
    cpSpaceRejectPair, cpSpaceAcceptCollision, cpSpacePairIsSolid, cpSpacePushFreshContactBuffer,
    cpContactBufferGetArray, cpContactBufferRoom, cpSpacePushContacts, cpSpaceCollideShapes,
    cpArbiterIsSolved, cpSpaceAcceptUpdated,
    cpContactBuffer, CP_CONTACTS_BUFFER_SIZE,
    cpShapeUpdateFunc,
    cpSpaceHasHandlers, _bodyNonFinite)
from tamias2d.arbiter cimport cpArbiterUpdate, cpArbiterUnthread, cpArbiterPushThreads
from tamias2d._spatialindex cimport (cpSpatialIndexEach, cpSpatialIndexReindexQuery,
    cpSpatialIndexCount)
from tamias2d.shape cimport cpShapeCacheBB
from tamias2d._bbtree cimport (cpBBTreeReindexCollect, cpPairCollector, cpCollectedPair, cpPairSlot, cpBBTreeGetStaticReach,
    cpBBTreeSetStaticReach, cpBBTreeSyncFat)
from tamias2d.collision cimport (cpCollideSoftInto, CollisionDiagnostics, cpCollisionTakeDiagnostics,
    cpCollisionPutDiagnostics)
from tamias2d._config cimport (cpCollisionID, cpHashValue, CP_MAX_CONTACTS_PER_ARBITER,
    CP_HASH_PAIR, tamias_prefetch, tamias_prefetch_write, tamias_lowest_bit,
    CP_POLY_SHAPE_INLINE_ALLOC)
from tamias2d._structs cimport (cpCollisionInfo, cpHashSet, cpSegmentShape, CP_SEGMENT_SHAPE,
    cpSpatialIndexBBFunc,
    cpContactBufferHeader,
    cpPolyShape, cpSplittingPlane)
from libc.string cimport memcpy


# -- settings ------------------------------------------------------------------------

cdef void SoftSettingsInit(cpSoftSettings *settings) noexcept nogil:
    settings.solver = TAMIAS_SOLVER_CHIPMUNK
    settings.substeps = SOFT_DEFAULT_SUBSTEPS
    settings.threads = 1
    settings.contactHertz = SOFT_DEFAULT_CONTACT_HERTZ
    settings.contactDampingRatio = SOFT_DEFAULT_CONTACT_DAMPING_RATIO
    settings.jointHertz = SOFT_DEFAULT_JOINT_HERTZ
    settings.jointDampingRatio = SOFT_DEFAULT_JOINT_DAMPING_RATIO
    settings.pushOut = -1.0
    settings.speculative = -1.0

cdef void SoftScratchFree(cpSoftScratch *scratch) noexcept nogil:
    cdef int i
    for i in range(SOFT_SCRATCH_COUNT):
        cpfree(scratch.buf[i])
        scratch.buf[i] = NULL
        scratch.cap[i] = 0
    scratch.pairCount = 0
    scratch.pairsVersion = 0

cdef cpFloat SoftPushOut(const cpSpace *space) noexcept nogil:
    if space.soft.pushOut >= 0.0:
        return space.soft.pushOut
    return SOFT_PUSH_OUT_PER_SLOP * space.collisionSlop

cdef cpFloat SoftSpeculative(const cpSpace *space) noexcept nogil:
    if space.soft.speculative >= 0.0:
        return space.soft.speculative
    return SOFT_SPECULATIVE_PER_SLOP * space.collisionSlop

cdef SoftSoftness SoftMakeSoft(cpFloat hertz, cpFloat zeta, cpFloat h) noexcept nogil:
    # The implicit (backward Euler) mass-spring-damper as a velocity
    # constraint: biasRate turns a separation into a target speed, massScale
    # and impulseScale soften the effective mass and the accumulated impulse.
    cdef SoftSoftness s
    cdef cpFloat omega, a1, a2, a3
    if hertz == 0.0:
        s.biasRate = 0.0
        s.massScale = 1.0
        s.impulseScale = 0.0
        return s
    omega = 2.0 * 3.14159265358979323846 * hertz
    a1 = 2.0 * zeta + h * omega
    a2 = h * omega * a1
    a3 = 1.0 / (1.0 + a2)
    s.biasRate = omega / a1
    s.massScale = a2 * a3
    s.impulseScale = a3
    return s


# -- scratch memory (grown, never shrunk) ---------------------------------------------

cdef enum:
    SOFT_SCRATCH_BODIES = 0
    SOFT_SCRATCH_STATES
    SOFT_SCRATCH_CONTACTS
    SOFT_SCRATCH_LANES
    SOFT_SCRATCH_COLORS       # each contact's colour, then its lane slot
    SOFT_SCRATCH_BITS         # the colours of each body, as bits
    SOFT_SCRATCH_OVERFLOW
    SOFT_SCRATCH_JOINT_BODIES
    SOFT_SCRATCH_SOURCE       # each contact's index in space.arbiters
    SOFT_SCRATCH_CANDIDATES   # the narrow phase of each pair (SoftCollide)
    SOFT_SCRATCH_PAIRS        # the broad phase's pairs, kept between steps
    SOFT_SCRATCH_TOUCHING     # each pair's narrow phase found contacts
    SOFT_SCRATCH_KEYS         # what the colouring reads of each contact (SoftColorKey)
    SOFT_SCRATCH_THREADED     # last step's arbiters, still threaded (SoftResetArbiters)
    SOFT_SCRATCH_MOTION       # SoftMotion of each body slot
    SOFT_SCRATCH_LANE_LINKS   # SoftLaneLinks of each lane
    SOFT_SCRATCH_CHANGED_IN   # restitution: the pass that last changed each body, which bounced, the contacts of the later passes
    SOFT_SCRATCH_DESTINATIONS # where each pair's contacts go in the contact buffers (SoftCollide)
    SOFT_SCRATCH_PAIR_ARBITERS  # each updated pair's arbiter, packed (SoftCollide)
    SOFT_SCRATCH_BLOCKS       # the light bodies and their contacts (SoftFindBlocks)
    SOFT_SCRATCH_BLOCK_CACHE  # each block's matrix and factors for the step (SoftBlockCache)
    SOFT_SCRATCH_COMPONENTS   # the sleeping components' union-find (cpSpaceProcessComponents)
    SOFT_SCRATCH_LOADS        # the piles' loads from their weights (SoftEstimateLoads)
    SOFT_SCRATCH_GROUPS       # the contact groups solved one after the other (SoftFindGroups)
    SOFT_SCRATCH_OLD_KEYS     # the colouring keys last coloured (SoftKeepColors)
    SOFT_SCRATCH_ISLANDS      # the components kept between steps (cpSpaceProcessComponents)
    SOFT_SCRATCH_COUNT

# cpSoftScratch's arrays must have room for them all (checked on import).
cdef cpSoftScratch _scratch_probe
if SOFT_SCRATCH_COUNT > sizeof(_scratch_probe.buf) // sizeof(void *):
    raise ImportError("cpSoftScratch (_structs.pxd) has fewer buffers than SOFT_SCRATCH_COUNT")

cdef void *_reserve(cpSpace *space, int which, int need, size_t size) noexcept nogil:
    # Room for `need` elements of `size` bytes in scratch buffer `which`, or
    # NULL (the out-of-memory flag is up; the step solves nothing).
    cdef cpSoftScratch *scratch = &space.softScratch
    cdef int n
    cdef void *grown
    if need <= scratch.cap[which] and scratch.buf[which] != NULL:
        return scratch.buf[which]
    n = scratch.cap[which] * 2 if scratch.cap[which] > 0 else 64
    while n < need:
        n *= 2
    grown = cprealloc(scratch.buf[which], <size_t>n * size)
    if grown == NULL:
        return NULL
    scratch.buf[which] = grown
    scratch.cap[which] = n
    return grown

cdef void *_reserve_lines(cpSpace *space, int which, int need, size_t size) noexcept nogil:
    # As _reserve, starting on a cache line (64 bytes), for the arrays the
    # substeps walk: a 64-byte SoftState then fills one line instead of
    # straddling two. Their contents are rebuilt every step, so the shift
    # of the start when the buffer grows does not matter.
    cdef size_t extra = (64 + size - 1) // size
    cdef char *raw = <char *>_reserve(space, which, need + <int>extra, size)
    if raw == NULL:
        return NULL
    return <void *>(raw + ((64 - (<size_t>raw & 63)) & 63))


# -- the step's context -----------------------------------------------------------------

# A pair the broad phase reported (kept for the next steps while the tree
# stays as it was: cpCollectedPair, its shapes as a and b), and its narrow
# phase (SoftCollide), in arrays of the same index. Only a pair that is not
# rejected writes its SoftCandidate.
ctypedef cpCollectedPair SoftPair

cdef struct SoftCandidate:
    cpCollisionID id
    cpArbiter *guess          # the slot's arbiter from an earlier step, unchecked
    cpFloat margin            # the pair's (cpSpaceRejectPair)
    cpArbiter *arb            # its arbiter if cached (looked up with the narrow phase)
    bint updated              # arb has this step's contacts (cpArbiterUpdate done)
    bint solid                # with updated: cpSpacePairIsSolid, read while the shapes are at hand
    cpCollisionInfo info
    cpContact contacts[CP_MAX_CONTACTS_PER_ARBITER]

# What the colouring needs of a contact, packed (it reads them in order,
# one after the other): its movable bodies' slots (0: immovable) and its
# lane kind (points - 1; -1: solved one by one, in the overflow). Beside
# them, for its preparation, its bodies' slots and its size, found by the
# count in arbiter order (from what the narrow phase noted in the arbiter).
cdef struct SoftColorKey:
    # (The six ints first, in three 64-bit words: SoftSameColorKeys.)
    int a
    int b
    int kind
    int ia
    int ib
    int block                 # it touches a light body solved as a block (SoftFindBlocks)
    cpFloat size              # SoftContactSize

# A block's matrix for the step (its rows' arms and masses are the step's)
# and the last Cholesky factor of each kind of pass with the free rows it
# was made for: a block at rest keeps its free rows from pass to pass, and
# each pass after the first of its kind then costs a substitution.
cdef struct SoftBlockCache:
    bint built
    cpFloat K[SOFT_BLOCK_ROWS][SOFT_BLOCK_ROWS]   # J W J', regularized, all rows
    cpFloat keff[SOFT_BLOCK_ROWS]                 # the normal rows' effective k
    int factorCount[2]                            # soft pass, relax pass; -1: none
    int factorRows[2][SOFT_BLOCK_ROWS]
    bint stateKept[2]                             # the last pass's row states (SoftBlockPivot)
    int state[2][SOFT_BLOCK_ROWS]
    cpFloat factorExtra[2][SOFT_BLOCK_ROWS]       # the diagonal added to K in it
    cpFloat L[2][SOFT_BLOCK_ROWS][SOFT_BLOCK_ROWS]

cdef struct SoftContext:
    cpSpace *space
    SoftBody *bodies
    SoftState *states         # the bodies' solver state, same slots
    SoftMotion *motion        # their accelerations and positions, same slots
    bint livePositions        # every body's position and transform written each substep (a Python velocity_func may read them)
    int bodyCount             # slots, the immovable slot 0 included
    SoftContact *contacts
    int contactCount
    int *contactSource        # contact i is arbiter contactSource[i] of space.arbiters
    cpFloat warmCoef, loadCoef   # last step's impulses to this substep's, to a load
    SoftLanes *lanes          # the coloured contacts, colour by colour
    SoftLaneLinks *laneLinks  # beside each lane: its contacts' sources and destinations
    SoftLaneBiasRates laneBiasRates   # the lanes' bias rates, by their sides (SoftPrepareLanes)
    int colorLanes[SOFT_GRAPH_COLORS + 1]   # colour c: lanes[colorLanes[c]:colorLanes[c+1]]
    int colorPairEnd[SOFT_GRAPH_COLORS]     # its two-point lanes end here, its one-point ones follow
    int groupCount            # 0: one plan of colours for all lanes; else the lanes group by group (SoftColorGroups)
    int *groupLanes           # group g's colorLanes: groupLanes[g * (SOFT_GRAPH_COLORS + 1):]
    int *groupPairEnd         # ... and its colorPairEnd: groupPairEnd[g * SOFT_GRAPH_COLORS:]
    int *groupBodies          # the body slots, group by group, then those of no group
    int *groupBodyStart       # group g's: groupBodies[groupBodyStart[g]:groupBodyStart[g + 1]] (g <= groupCount)
    int *groupContacts        # the contacts, group by group (arbiter order within each)
    int *groupContactStart    # group g's: groupContacts[groupContactStart[g]:groupContactStart[g + 1]]
    int *overflow             # SoftContact indices solved one by one
    volatile long shapesUpdated   # by SoftUpdateShapes
    volatile long shapesEscaped   # nonzero: one of them left its leaf's box (counted with fatKnown)
    bint fatKnown             # every dynamic shape's softFat is its leaf's box: shapesEscaped is counted
    int *contactSlots         # each contact's lane slot (lane * SOFT_LANES + k; -1: the overflow)
    SoftColorKey *colorKeys   # by SoftCountRange, for SoftColorContacts and the preparation
    int overflowCount
    SoftPair *pairs           # this step's pairs from the broad phase (or the last walk's)
    int pairCount
    SoftCandidate *candidates # their narrow phase
    unsigned char *touching   # the pair's SOFT_PAIR_* flags (0: no contacts)
    cpContact **destinations  # on threads, with updateInNarrow: where each pair's contacts go
    bint placedInNarrow       # ... reserved before the narrow phase, which writes them there
    cpArbiter **pairArbiters  # ... and each updated pair's arbiter (the candidate's, packed)
    bint updateInNarrow       # no begin or pre-solve callbacks: arbiters updated in parallel
    bint acceptInNarrow       # ... and one thread: the narrow phase also does SoftAcceptPair's part
    bint keysInNarrow         # ... and the bodies gathered before it: it also counts each arbiter it accepts (SoftKeyAccepted)
    int keyed                 # ... how many (the first of space.arbiters)
    int keySeen               # ... their SOFT_SEEN_* bits
    volatile long narrowSeen[2]   # ... on threads, the pairs' keys' SOFT_SEEN_RATIO and _ELASTIC (SoftNarrowPhase)
    bint innerApart           # the colouring gave the inner two-point contacts lanes of their own (SoftLaneClass)
    volatile long elastic     # a contact has restitution (set by SoftCountRange)
    volatile long customVelocity  # a body has its own velocity_func (SoftGatherRange)
    volatile long customPosition  # ... position_func
    volatile long emptyArbiter    # an arbiter has no contacts (SoftCountRange)
    volatile long uncachedArbiter # last step's arbiters include a pooled one (SoftMarkThreaded)
    volatile long bodiesFinished  # bodies written back (SoftFinishBodies) ...
    volatile long bodiesNonFinite # ... and of those, non-finite ones
    volatile long ratioPairs      # a contact's bodies' masses differ SOFT_BLOCK_RATIO times or more
    int *blockBodies          # each block's root body (SoftFindBlocks), in slot order
    int blockBodyCount
    int *blockHead            # per root body slot: its block's first contact, -1: none
    int *blockNext            # per contact: the next one of its block
    SoftBlockCache *blockCache    # per block (blockBodies' order), built by its first pass
    int threadedCount         # last step's arbiters left threaded (-1: unthreaded as Munk2D)
    bint threadsEmptied       # sleeping on, and the reset left no arbiter threaded
    bint threaded             # stages may run on the pool (SoftRun)
    bint serialVelocities     # a body has its own velocity_func (Python: one thread)
    bint serialPositions      # a body has its own position_func
    int *jointBodies          # slots touched by joints
    int jointBodyCount
    int substeps
    cpFloat h, inv_h
    int youngPairs            # touching pairs whose first point is under SOFT_YOUNG_AGE steps old
    int touchingPairs
    cpFloat gx, gy
    cpFloat damping           # per substep
    cpFloat pushOut
    SoftSoftness contactSoft  # between two movable bodies
    SoftSoftness staticSoft   # against an immovable one (twice as stiff)
    cpFloat contactCompliance[2]  # contactSoft's compliance, and over SOFT_RATIO_STIFFENING
    cpFloat staticCompliance[2]   # the same of staticSoft
    SoftSoftness jointSoft    # the joints' position correction
    bint estimating           # SoftEstimateLoads runs this step (gravity, and on)
    bint fetchAhead           # the passes fetch their records ahead (SOFT_FETCH_MIN_CONTACTS)
    bint estimatePending      # ... beside the colouring (SOFT_TASK_ESTIMATE_AND_COLOR)
    bint colored              # SoftColorContacts' answer, when run as that task
    cpFloat gravity           # |g|, and up (against it):
    cpFloat upx, upy
    int *loadHeld             # per contact: the body slot it holds up, 0: none (SoftCountContact)
    int *loadOther            # ... and the slot it holds it up from (0: immovable)
    cpFloat *loadLift         # ... the upward part of its normal; after SoftEstimateLoads, how much of its preload the estimate gives
    cpFloat *loadEstimates    # ... the normal force the weights above put on it (<= 0: none)

cdef inline int SoftIndex(cpBody *body, SoftBody *bodies, int count) noexcept nogil:
    # The slot of an awake body, or 0 (static, sleeping, removed).
    cdef int i = body.solverIndex
    if i > 0 and i < count and bodies[i].body == body:
        return i
    return 0

cdef inline void SoftSetTransform(cpBody *body) noexcept nogil:
    # body.transform from body.p (the centre of gravity) and body.a, as
    # cpBodySetTransform computes it.
    cdef cpFloat c = cos(body.a)
    cdef cpFloat s = sin(body.a)
    cdef cpVect g = body.cog
    body.transform = cpTransformNewTranspose(
        c, -s, body.p.x - (g.x * c - g.y * s),
        s, c, body.p.y - (g.x * s + g.y * c))


# -- a profile of the step, stage by stage (benchmarks/soft_profile.py) ---------------

cdef enum:
    SOFT_STAGE_BROAD_PHASE = 0    # shapes' boxes, the tree's pairs listed
    SOFT_STAGE_NARROW_PHASE       # contacts of each pair, cached arbiters found
    SOFT_STAGE_ARBITERS           # arbiters updated or made, begin / pre_solve
    SOFT_STAGE_COMPONENTS         # contact graph, sleeping, the arbiter cache's filter
    SOFT_STAGE_PREPARE            # last step's arbiters reset; bodies, joints and contacts gathered;
                                  # contacts prepared into lanes
    SOFT_STAGE_COLOR              # the constraint graph's colours (which lane slot each contact takes),
                                  # and the load estimate where it runs beside them
    SOFT_STAGE_INTEGRATE          # velocities and positions, every substep
    SOFT_STAGE_WARM_START
    SOFT_STAGE_SOLVE              # the biased (soft) pass
    SOFT_STAGE_RELAX              # the relax passes
    SOFT_STAGE_FINISH             # restitution, impulses stored, bodies written back, post_solve
    SOFT_STAGE_COUNT

SOFT_STAGE_NAMES = ("broad phase", "narrow phase", "arbiters", "components", "prepare", "color",
                    "integrate", "warm start", "solve", "relax", "finish")

# Off unless a profile is asked for (a process-wide switch: profile one
# space at a time). On, each stage costs one clock read.
cdef bint _profiling = 0
cdef long long _profile_ns[SOFT_STAGE_COUNT]
cdef long long _profile_last = 0
cdef long _profile_steps = 0

cdef inline void SoftProfileMark(int stage) noexcept nogil:
    # The time since the last mark goes to `stage` (-1: a step begins).
    global _profile_last, _profile_steps
    cdef long long now
    if not _profiling:
        return
    now = tamias_now_ns()
    if stage < 0:
        _profile_steps += 1
    else:
        _profile_ns[stage] += now - _profile_last
    _profile_last = now

def _profile(on):
    """Switch the stage profile of soft steps on or off; returns what was
    collected since the last call, {stage: ms per step}, and resets it."""
    global _profiling, _profile_steps
    cdef int i
    steps = _profile_steps
    out = {SOFT_STAGE_NAMES[i]: (_profile_ns[i] / 1e6 / steps if steps else 0.0)
           for i in range(SOFT_STAGE_COUNT)}
    for i in range(SOFT_STAGE_COUNT):
        _profile_ns[i] = 0
    _profile_steps = 0
    _profiling = bool(on)
    return out


# -- collision: the broad phase, then the narrow phase on the pool ---------------------
# The chipmunk solver runs the narrow phase of each pair as the broad phase
# reports it (StageCollide). Here the broad phase first lists the pairs
# (cpBBTreeReindexCollect: same pairs, same order), then the narrow phase
# of every pair runs, on the pool when the step is threaded (it only reads
# shapes and bodies, and writes the pair's own contacts and id), then, in the
# broad phase's order on this thread, the pairs that touch get their
# arbiters and callbacks (cpSpaceAcceptCollision). A step's contacts are the
# same whoever ran which pair. A begin or pre-solve callback therefore sees
# every pair's narrow phase done.

cdef void SoftGrowPairs(cpPairCollector *collector) noexcept nogil:
    # Room for the broad phase's next pair (the tree calls this when the
    # array is full), or the out-of-memory flag up.
    cdef cpSpace *space = <cpSpace *>collector.data
    cdef SoftPair *grown = <SoftPair *>_reserve(space, SOFT_SCRATCH_PAIRS, collector.count + 1,
                                                sizeof(SoftPair))
    if grown != NULL:
        collector.pairs = grown
        collector.cap = space.softScratch.cap[SOFT_SCRATCH_PAIRS]


# Off only in tests, which check that the guesses change nothing.
cdef bint _use_guesses = 1
# The same for keeping the broad phase's walk.
cdef bint _keep_pairs = 1
# Steps whose walk was kept, in all spaces (for tests: that it happens).
cdef volatile long _kept_walks = 0
# Whether the leaves' refresh is skipped when no shape left its leaf's box
# (off only in tests), and the steps so far (all spaces) that skipped it.
cdef bint _skip_refresh = 1
# SoftKeysMayBeCounted (off only in tests, which compare).
cdef bint _count_in_narrow = 1
cdef volatile long _narrow_counts = 0
cdef volatile long _skipped_refreshes = 0
# Contacts solved one by one so far, outside the colours (for tests).
cdef volatile long _overflow_total = 0
# The same for the bodies' arbiter lists (SoftResetArbiters).
cdef bint _keep_threads = 1
cdef bint _use_blocks = 1
# SoftRelaxSkipsInner (off only in tests, which compare).
cdef bint _skip_inner = 1
# SOFT_PRELOAD_TILT, but for tests and benchmarks (_chain_preload_tilt).
cdef cpFloat _preload_tilt = SOFT_PRELOAD_TILT
cdef volatile long _kept_threads = 0
# The same for the components found by union-find instead of the flood fill
# (SoftProcessComponents).
cdef bint _link_components = 1
# ... and the components kept from the last step instead of the union-find.
cdef bint _keep_islands = 1
cdef volatile long _kept_islands = 0
# SoftEstimateLoads (off only in tests and benchmarks, which compare).
cdef bint _estimate_loads = 1
cdef volatile long _linked_components = 0

cdef inline bint SoftGuessHolds(const cpArbiter *arb, const cpCollisionInfo *info) noexcept nogil:
    # The guess is the pair's cached arbiter: in the cache and of these two
    # shapes (the cache keeps one arbiter per pair, in either order). An
    # arbiter's memory lives as long as the space, so a stale guess is safe
    # to read.
    return arb != NULL and arb.cached and (
        (arb.a == info.a and arb.b == info.b) or (arb.a == info.b and arb.b == info.a))

cdef inline void SoftNoteShapes(const cpSpace *space, cpArbiter *arb, const cpShape *a,
                                const cpShape *b) noexcept nogil:
    # What the count (SoftCountContact) reads of a pair's shapes, noted in
    # its arbiter while they are in cache; a and b in the arbiter's order
    # (the collision's, which cpArbiterUpdate gives it).
    arb.softSideA = SoftShapeSide(a)
    arb.softSideB = SoftShapeSide(b)
    arb.softSlotA = a.softSlot
    arb.softSlotB = b.softSlot
    arb.softNoted = space.stamp

cdef inline bint SoftFlatSegment(const cpShape *shape) noexcept nogil:
    # A segment of radius 0 has no inside: its contact normal says which
    # side the other shape is on, and nothing else can.
    return (shape.klass.type == CP_SEGMENT_SHAPE
            and (<const cpSegmentShape *>shape).r == 0.0)

cdef inline void SoftKeepSide(const cpSpace *space, const cpArbiter *arb,
                              cpCollisionInfo *info) noexcept nogil:
    # A pair with a radius-0 segment that touched last step keeps last
    # step's normal if the new one turned over (or is none): the shapes
    # crossed within the step (a speculative contact lets them meet exactly,
    # and rounding puts one a hair past the other), which the normal of
    # where they now are would let them finish. With the old one the solver
    # pushes them back.
    cdef cpVect n
    if (arb == NULL or arb.count == 0 or arb.stamp + 1 != space.stamp
            or not (SoftFlatSegment(info.a) or SoftFlatSegment(info.b))):
        return
    n = arb.n if arb.a == info.a else cpv(-arb.n.x, -arb.n.y)
    if n.x * info.n.x + n.y * info.n.y <= 0.0:
        info.n = n

# How many pairs ahead the narrow phase fetches a pair's slot and shapes.
cdef enum:
    SOFT_NARROW_PREFETCH = 8
    SOFT_ARBITER_PREFETCH = 8     # the same for the passes over the arbiters
    SOFT_BODY_PREFETCH = 4        # and over the bodies
    # Below this many contacts (last step's arbiters) a step's records stay
    # in the core's caches and fetching them ahead only adds instructions:
    # 4% of a 20-row pyramid's. Fetching on and off, alternated on one
    # scene: 2% slower with it at 600 and 1,100 contacts, even at 1,300,
    # 1-1.5% faster at 1,800-2,200, 10% at 2,800, 18% on Box2D's large
    # pyramid (15,000).
    SOFT_FETCH_MIN_CONTACTS = 1536
    # About this many contacts make a group (SoftFindGroups): their lanes and
    # their bodies' states, about 0.6 MB, stay in a core's L2 cache through
    # the 16 passes of the step's substeps. (On many_pyramids 2,048 was 3%
    # faster than 4,096 or 8,192; 1,024 no faster.)
    SOFT_GROUP_CONTACTS = 2048

# What the narrow phase found of a pair (SoftContext.touching), so that the
# serial pass after it reads one byte per pair, not the pair's candidate.
cdef enum:
    SOFT_PAIR_TOUCHING = 1    # it has contacts
    SOFT_PAIR_UPDATED = 2     # its cached arbiter has them (cpArbiterUpdate done)
    SOFT_PAIR_ACCEPTED = 4    # ... and is solved (cpSpaceAcceptCollision would push it)
    SOFT_PAIR_YOUNG = 8       # ... and its first point is under SOFT_YOUNG_AGE steps old

cdef inline void SoftFetchLines(const void *p, int size) noexcept nogil:
    # Every cache line of `size` bytes from p (p need not be aligned, so one
    # line more). For records scattered in memory, fetched a few items
    # ahead of the pass that reads them; prefetching an address past an
    # object is harmless.
    cdef int k
    for k in range(0, size + 64, 64):
        tamias_prefetch(<const char *>p + k)

cdef inline void SoftFetchShape(const cpShape *shape) noexcept nogil:
    # What the narrow phase reads of a shape: its box and filter, and an
    # inline polygon's world planes after them (not the local half of its
    # planes; a smaller shape's lines past its end are harmless).
    SoftFetchLines(shape, sizeof(cpPolyShape)
                   - CP_POLY_SHAPE_INLINE_ALLOC * sizeof(cpSplittingPlane))

cdef inline void SoftFetchKeySlot(SoftContext *ctx, int slot) noexcept nogil:
    if 0 < slot < ctx.bodyCount:
        tamias_prefetch(&ctx.bodies[slot])
        if ctx.estimating:
            tamias_prefetch(&ctx.motion[slot].px)

cdef void SoftNarrowPhase(SoftContext *ctx, int begin, int end) noexcept nogil:
    # First the cheap rejection (most pairs of the broad phase, whose boxes
    # are widened for continuous collision, go no further). Also finds a
    # touching pair's cached arbiter: the cache is only read here (pairs new
    # this step get theirs afterwards, on the calling thread). The broad
    # phase's pair remembers it from the last step; the cache is asked only
    # when that guess is wrong (the answer is the same).
    cdef int i
    cdef SoftPair *p
    cdef SoftPair *q
    cdef cpArbiter *guess
    cdef SoftCandidate *c
    cdef SoftCandidate local
    cdef cpPairSlot *slot
    cdef cpFloat margin
    cdef const cpShape *pair[2]
    cdef cpContact *dest
    cdef cpShape *a
    cdef cpShape *b
    cdef int seen = 0
    for i in range(begin, end):
        p = &ctx.pairs[i]
        a = <cpShape *>p.a
        b = <cpShape *>p.b
        if ctx.fetchAhead and i + SOFT_NARROW_PREFETCH < end:
            # The broad phase's pair slots and the shapes are scattered in
            # memory: a cache miss each, which stalled this loop more than
            # the collision itself took.
            q = &ctx.pairs[i + SOFT_NARROW_PREFETCH]
            tamias_prefetch(q.slot)
            SoftFetchShape(<cpShape *>q.a)
            SoftFetchShape(<cpShape *>q.b)
        if ctx.fetchAhead and i + SOFT_NARROW_PREFETCH // 2 < end:
            # The arbiter its slot guesses, now that the slot has arrived.
            q = &ctx.pairs[i + SOFT_NARROW_PREFETCH // 2]
            if q.slot != NULL and q.slot.arbiter != NULL:
                # (All of it: the guess's check reads its shapes and flags,
                # the update and SoftNoteShapes write all four lines.)
                SoftFetchLines(q.slot.arbiter, sizeof(cpArbiter))
            # And, the shapes having arrived, what the rejection reads of
            # their bodies (masses and the bullet flag, two lines apart).
            tamias_prefetch(&(<cpShape *>q.a).body.m_inv)
            tamias_prefetch(&(<cpShape *>q.a).body.isBullet)
            tamias_prefetch(&(<cpShape *>q.b).body.m_inv)
            tamias_prefetch(&(<cpShape *>q.b).body.isBullet)
            if ctx.keysInNarrow:
                # And the two body slots the key will read (SoftKeyAccepted).
                SoftFetchKeySlot(ctx, (<cpShape *>q.a).softSlot)
                SoftFetchKeySlot(ctx, (<cpShape *>q.b).softSlot)
        if cpSpaceRejectPair(ctx.space, a, b, &margin):
            ctx.touching[i] = 0
            continue
        # Accepted here, a pair's candidate is read by nothing after it: on
        # the stack, not written out to the array (a quarter kilobyte a
        # pair, most of the narrow phase's stalls in a large pile).
        c = &local if ctx.acceptInNarrow else &ctx.candidates[i]
        slot = p.slot
        c.margin = margin
        c.arb = NULL
        c.updated = 0
        if slot != NULL:
            c.id = slot.id
            c.guess = <cpArbiter *>slot.arbiter
        else:
            c.id = 0
            c.guess = NULL
        dest = c.contacts
        if ctx.placedInNarrow:
            dest = ctx.destinations[i]
        elif ctx.acceptInNarrow:
            # Straight into the contact buffer (this is the pairs' order):
            # the copy from the candidate, and the candidate's bytes, saved.
            dest = cpContactBufferRoom(ctx.space)
            if dest == NULL:
                dest = c.contacts   # out of memory: the flag is up, the pair is skipped below
        cpCollideSoftInto(a, b, c.id, dest, margin, &c.info)
        ctx.touching[i] = SOFT_PAIR_TOUCHING if c.info.count > 0 else 0
        if slot != NULL:
            slot.id = c.info.id
        if c.info.count > 0:
            if _use_guesses and SoftGuessHolds(c.guess, &c.info):
                c.arb = c.guess
            else:
                pair[0] = c.info.a
                pair[1] = c.info.b
                c.arb = <cpArbiter *>cpHashSetFind(ctx.space.cachedArbiters,
                    CP_HASH_PAIR(<cpHashValue>c.info.a, <cpHashValue>c.info.b), pair)
                if slot != NULL:
                    slot.arbiter = c.arb
            SoftKeepSide(ctx.space, c.arb, &c.info)
            if c.arb != NULL:
                SoftNoteShapes(ctx.space, c.arb, c.info.a, c.info.b)
            if c.arb != NULL and ctx.updateInNarrow:
                # What cpSpaceAcceptCollision would do first, done here as
                # no callback runs before it that could change its inputs
                # (shapes' friction, elasticity, types; the handlers). On
                # threads the contacts are where they stay already
                # (SoftPlaceContacts); otherwise they are the candidate's
                # until the serial pass copies them to the contact buffer.
                cpArbiterUpdate(c.arb, &c.info, ctx.space)
                c.updated = 1
                c.solid = cpSpacePairIsSolid(a, b)
                ctx.touching[i] |= SOFT_PAIR_UPDATED
                if ctx.pairArbiters != NULL:
                    # For the threaded pass after (SoftCollide): what
                    # cpSpaceAcceptCollision decides of it (the tree reports
                    # each pair once a step, so it is not stamped yet).
                    ctx.pairArbiters[i] = c.arb
                    if cpArbiterIsSolved(c.arb, c.solid):
                        ctx.touching[i] |= SOFT_PAIR_ACCEPTED
                        if ctx.keysInNarrow:
                            # Its key, at the pair's index: the serial
                            # pass moves it to its arbiter's (SoftKeyMoved).
                            seen |= SoftCountContact(ctx, c.arb, i)
                    if c.info.arr[0].bias < SOFT_YOUNG_AGE:
                        ctx.touching[i] |= SOFT_PAIR_YOUNG
                    if ctx.placedInNarrow:
                        SoftSettleUpdated(ctx.space, c.arb, ctx.touching[i])
            if ctx.acceptInNarrow:
                if dest != c.contacts:
                    SoftAcceptPlaced(ctx, i, c, dest)
                elif c.updated:
                    c.arb.contacts = NULL
                    c.arb.count = 0
    if seen & SOFT_SEEN_RATIO:
        tamias_store(&ctx.narrowSeen[0], 1)
    if seen & SOFT_SEEN_ELASTIC:
        tamias_store(&ctx.narrowSeen[1], 1)

cdef inline void SoftPrefetchArbiter(cpSpace *space, SoftCandidate *c) noexcept nogil:
    cdef cpHashSet *arbs = space.cachedArbiters
    if c.info.count == 0:
        return
    if c.arb != NULL:
        # (Its contacts pointer, stamp and state lie on different lines.)
        tamias_prefetch(&c.arb.contacts)
        tamias_prefetch(&c.arb.stamp)
    else:
        tamias_prefetch(&arbs.table[CP_HASH_PAIR(<cpHashValue>c.info.a,
                                                 <cpHashValue>c.info.b) % arbs.size])

cdef void SoftUpdateShapes(SoftContext *ctx, int begin, int end) noexcept nogil:
    # The shapes' boxes and world data, body by body (on the pool); counted,
    # to check that they were all the dynamic index holds. With fatKnown,
    # also noted: whether a shape's box (as the tree makes it from the
    # shape) left its leaf's, which the tree's refresh would then move.
    # None did: the refresh, a pass over every leaf in the leaf set's
    # order, is skipped.
    cdef cpArray *bodies = ctx.space.dynamicBodies
    cdef cpSpatialIndexBBFunc treeBox = ctx.space.dynamicShapes.bbfunc
    cdef cpShape *shape
    cdef long count = 0, escaped = 0
    cdef int i
    for i in range(begin, end):
        # The bodies and their shapes are scattered in memory: the body's
        # line with its shape list two bodies ahead of its first shape's
        # lines (all of a polygon's: its local planes are read, its world
        # planes written).
        if ctx.fetchAhead and i + 2 * SOFT_BODY_PREFETCH < end:
            tamias_prefetch(&(<cpBody *>bodies.arr[i + 2 * SOFT_BODY_PREFETCH]).shapeList)
        if ctx.fetchAhead and i + SOFT_BODY_PREFETCH < end:
            shape = (<cpBody *>bodies.arr[i + SOFT_BODY_PREFETCH]).shapeList
            if shape != NULL:
                SoftFetchLines(shape, sizeof(cpPolyShape))
        shape = (<cpBody *>bodies.arr[i]).shapeList
        while shape != NULL:
            cpShapeCacheBB(shape)
            # (One is enough to refresh them all.)
            if ctx.fatKnown and escaped == 0 and not cpBBContainsBB(shape.softFat, treeBox(shape)):
                escaped = 1
            # The slot SoftGatherRange will give the body, unless the
            # components stage wakes or puts to sleep a body (checked).
            shape.softSlot = i + 1
            count += 1
            shape = shape.next
    tamias_add(&ctx.shapesUpdated, count)
    if escaped:
        tamias_add(&ctx.shapesEscaped, escaped)

cdef void SoftSetReach(cpSpace *space) noexcept nogil:
    # How far around a dynamic shape's box the static tree is searched, and
    # kinematic shapes' boxes grown (space.pyx _shapeGetBB): at least as far
    # as the fastest body travels in the step, in any direction, since its
    # contacts may turn it toward a wall within the step. Changed seldom: a
    # larger reach makes every leaf look for its pairs again.
    cdef cpArray *bodies = space.dynamicBodies
    cdef cpFloat fastest = 0.0, v2, travel, reach
    cdef cpVect v
    cdef int i
    for i in range(bodies.num):
        v = (<cpBody *>bodies.arr[i]).v
        v2 = v.x * v.x + v.y * v.y
        if v2 > fastest:
            fastest = v2
    travel = sqrt(fastest) * space.curr_dt
    if not travel < INFINITY:
        # (A non-finite speed: the step refuses it after the integration,
        # and the space must stay copyable, its reach finite.)
        return
    reach = cpBBTreeGetStaticReach(space.dynamicShapes)
    if travel > reach or (SOFT_REACH_SHRINK * travel < reach and reach > space.collideMargin):
        cpBBTreeSetStaticReach(space.dynamicShapes,
                               fmax(SOFT_REACH_ROOM * travel, space.collideMargin))

cdef void SoftCollide(SoftContext *ctx) noexcept nogil:
    cdef cpSpace *space = ctx.space
    cdef unsigned long long known, walked
    cdef cpPairCollector collector
    cdef int i, n, flags, stamped, keyAt
    cdef bint inside, keys
    cpSpacePushFreshContactBuffer(space)
    # (The reach first: the tree's boxes of kinematic and bullet shapes,
    # which the shapes' update tests, take it in. It reads velocities only.)
    SoftSetReach(space)
    # The awake bodies' shapes are the dynamic index's; should they not be
    # (the counts differ), the index's walk does it again, as the chipmunk
    # solver does (the boxes come out the same however often they are made).
    # Each is tested against its leaf's box (its copy: cpBBTreeSyncFat makes
    # sure the copies are current): where none left its box the tree's
    # refresh of its leaves would change nothing, and is skipped.
    ctx.fatKnown = _skip_refresh and cpBBTreeSyncFat(space.dynamicShapes)
    tamias_store(&ctx.shapesUpdated, 0)
    tamias_store(&ctx.shapesEscaped, 0)
    SoftRun(ctx, SOFT_TASK_UPDATE_SHAPES, 0, space.dynamicBodies.num, 0)
    inside = ctx.fatKnown and tamias_load(&ctx.shapesEscaped) == 0
    if tamias_load(&ctx.shapesUpdated) != cpSpatialIndexCount(space.dynamicShapes):
        cpSpatialIndexEach(space.dynamicShapes, cpShapeUpdateFunc, NULL)
        inside = 0
    if inside:
        tamias_add(&_skipped_refreshes, 1)
    # (Room for one pair at least: the walk grows the array as soon as a
    # pair fills it.)
    collector.pairs = <SoftPair *>_reserve(space, SOFT_SCRATCH_PAIRS, 1, sizeof(SoftPair))
    collector.cap = space.softScratch.cap[SOFT_SCRATCH_PAIRS] if collector.pairs != NULL else 0
    collector.count = 0
    collector.complete = 1
    collector.grow = SoftGrowPairs
    collector.data = space
    # The last walk of the tree's pairs is kept: while no leaf leaves its
    # box and nothing is added or removed, the next steps take their pairs
    # from there.
    known = space.softScratch.pairsVersion if _keep_pairs else 0
    walked = known
    if not cpBBTreeReindexCollect(space.dynamicShapes, &collector, &walked, inside):
        # A spatial hash: pair by pair, as the chipmunk solver.
        ctx.keysInNarrow = 0
        space.softScratch.pairsVersion = 0
        cpSpatialIndexReindexQuery(space.dynamicShapes, cpSpaceCollideShapes, space)
        return
    ctx.pairs = collector.pairs
    if walked == known and known != 0:
        tamias_add(&_kept_walks, 1)
        ctx.pairCount = space.softScratch.pairCount
    else:
        ctx.pairCount = collector.count
        space.softScratch.pairsVersion = walked if collector.complete else 0
        space.softScratch.pairCount = ctx.pairCount
    n = ctx.pairCount
    ctx.acceptInNarrow = ctx.updateInNarrow and not ctx.threaded
    keys = ctx.keysInNarrow
    ctx.keysInNarrow = 0
    ctx.candidates = NULL
    if not ctx.acceptInNarrow:
        ctx.candidates = <SoftCandidate *>_reserve(space, SOFT_SCRATCH_CANDIDATES, n,
                                                   sizeof(SoftCandidate))
    ctx.touching = <unsigned char *>_reserve(space, SOFT_SCRATCH_TOUCHING, n, 1)
    if (ctx.candidates == NULL and not ctx.acceptInNarrow) or ctx.touching == NULL:
        return  # out of memory: the flag is up, no pair is collided
    SoftProfileMark(SOFT_STAGE_BROAD_PHASE)
    ctx.pairArbiters = NULL
    ctx.destinations = NULL
    ctx.placedInNarrow = 0
    if ctx.updateInNarrow and ctx.threaded:
        ctx.destinations = <cpContact **>_reserve(space, SOFT_SCRATCH_DESTINATIONS, n,
                                                  sizeof(cpContact *))
        ctx.pairArbiters = <cpArbiter **>_reserve(space, SOFT_SCRATCH_PAIR_ARBITERS, n,
                                                  sizeof(cpArbiter *))
        if ctx.destinations == NULL or ctx.pairArbiters == NULL or not SoftPlaceContacts(ctx, n):
            ctx.destinations = NULL     # (out of memory: the flag is up; the pass below)
        else:
            ctx.placedInNarrow = 1
    # Keys counted as the narrow phase accepts each arbiter (on one thread),
    # or as it updates each (on threads, where the pass after it accepts
    # them in order).
    ctx.keysInNarrow = (keys and (ctx.acceptInNarrow or ctx.placedInNarrow)
                        and SoftReserveKeys(ctx, n))
    tamias_store(&ctx.narrowSeen[0], 0)
    tamias_store(&ctx.narrowSeen[1], 0)
    SoftRun(ctx, SOFT_TASK_NARROW, 0, n, 0)
    SoftProfileMark(SOFT_STAGE_NARROW_PHASE)
    if ctx.acceptInNarrow:
        return
    if not ctx.placedInNarrow:
        # (Handlers, or out of memory.)
        for i in range(n):
            # Fetch the arbiter of a pair a few places on (or, for a pair
            # new this step, its slot of the arbiter cache).
            if i + 4 < n and ctx.touching[i + 4]:
                SoftPrefetchArbiter(space, &ctx.candidates[i + 4])
            if ctx.touching[i]:
                SoftAcceptPair(ctx, i)
        return
    # On threads, with every cached arbiter updated in the narrow phase and
    # its contacts written where SoftPlaceContacts placed them, this pass
    # (in pair order, on this thread) only pushes the solved arbiters, from
    # the pairs' flags and arbiters packed in arrays; the pairs new this
    # step go through cpSpaceAcceptCollision here. The same arbiters, in the
    # same order, with the same contacts, as one thread gives.
    stamped = 0
    for i in range(n):
        flags = ctx.touching[i]
        if not flags & SOFT_PAIR_UPDATED:
            if flags:
                SoftAcceptReserved(ctx, i)
            continue
        ctx.touchingPairs += 1
        if flags & SOFT_PAIR_YOUNG:
            ctx.youngPairs += 1
        stamped += 1
        if flags & SOFT_PAIR_ACCEPTED:
            keyAt = space.arbiters.num
            cpArrayPush(space.arbiters, ctx.pairArbiters[i])   # (failing: the flag is up)
            if ctx.keysInNarrow:
                SoftKeyMoved(ctx, i, keyAt)
    # (Each was cached and not stamped in this step: cpSpaceStampArbiter.)
    space.arbitersStamped += stamped

cdef bint SoftPlaceContacts(SoftContext *ctx, int n) noexcept nogil:
    # Room in the contact buffers for every pair's contacts, the most a pair
    # can have, in pair order (ctx.destinations), before the narrow phase:
    # the threads write each pair's contacts where they stay, while its
    # arbiter is in their cache. Placed after it, pair by pair, they were
    # copied there and every arbiter visited again (a miss each): most of a
    # large pile's serial time on two threads. The room of the pairs that
    # do not touch goes unused until the ring reuses its buffer.
    cdef cpSpace *space = ctx.space
    cdef cpContactBufferHeader *head
    cdef cpContact *base
    cdef int i = 0, j, k, room
    while i < n:
        head = space.contactBuffersHead
        room = 0
        if head != NULL:
            room = (CP_CONTACTS_BUFFER_SIZE - <int>head.numContacts) // CP_MAX_CONTACTS_PER_ARBITER
        if room <= 0:
            cpSpacePushFreshContactBuffer(space)
            head = space.contactBuffersHead
            if head == NULL or head.numContacts != 0:
                return 0    # out of memory: the flag is up
            room = CP_CONTACTS_BUFFER_SIZE // CP_MAX_CONTACTS_PER_ARBITER
        k = room if room < n - i else n - i
        base = (<cpContactBuffer *>head).contacts + head.numContacts
        for j in range(k):
            ctx.destinations[i + j] = base + CP_MAX_CONTACTS_PER_ARBITER * j
        head.numContacts += CP_MAX_CONTACTS_PER_ARBITER * k
        i += k
    return 1

cdef inline void SoftSettleUpdated(cpSpace *space, cpArbiter *arb, int flags) noexcept nogil:
    # What cpSpaceAcceptCollision does to an arbiter the narrow phase
    # updated, its contacts being where they stay (SoftPlaceContacts).
    if not flags & SOFT_PAIR_ACCEPTED:
        arb.contacts = NULL
        arb.count = 0
        if arb.state != CP_ARBITER_STATE_IGNORE:
            arb.state = CP_ARBITER_STATE_NORMAL
    arb.stamp = space.stamp

cdef void SoftAcceptReserved(SoftContext *ctx, int i) noexcept nogil:
    # A pair new this step whose contacts SoftPlaceContacts placed: through
    # cpSpaceAcceptCollision, which counts them onto the head buffer (and
    # off again if it rejects the pair); they are in the room placed.
    cdef cpContactBufferHeader *head = ctx.space.contactBuffersHead
    cdef unsigned int held = head.numContacts
    SoftAcceptPlaced(ctx, i, &ctx.candidates[i], ctx.destinations[i])
    head.numContacts = held

cdef void SoftAcceptPair(SoftContext *ctx, int i) noexcept nogil:
    # Pair i's contacts into the contact buffers, its arbiter through
    # cpSpaceAcceptCollision (made if new, begin / pre-solve handlers).
    cdef cpSpace *space = ctx.space
    cdef SoftCandidate *c = &ctx.candidates[i]
    cdef cpContact *contacts = cpContactBufferGetArray(space)
    if contacts == NULL:
        # Out of memory: the flag is up, the pair is skipped.
        if c.updated:
            c.arb.contacts = NULL
            c.arb.count = 0
        return
    memcpy(contacts, c.contacts, c.info.count * sizeof(cpContact))
    SoftAcceptPlaced(ctx, i, c, contacts)

cdef void SoftAcceptPlaced(SoftContext *ctx, int i, SoftCandidate *c,
                           cpContact *contacts) noexcept nogil:
    # The rest of SoftAcceptPair, pair i's contacts being in the contact
    # buffer at `contacts`.
    cdef cpSpace *space = ctx.space
    cdef cpArbiter *arb = c.arb
    cdef int before = space.arbiters.num
    c.info.arr = contacts
    if c.updated:
        arb.contacts = contacts
    cpSpacePushContacts(space, c.info.count)
    # (Most pairs inline, without two calls into other modules.)
    if not (c.updated and cpSpaceAcceptUpdated(space, arb, c.solid)):
        arb = cpSpaceAcceptCollision(space, <cpShape *>ctx.pairs[i].a, <cpShape *>ctx.pairs[i].b,
                                     &c.info, c.arb, c.updated, c.solid if c.updated else -1)
    if c.arb == NULL and arb != NULL:
        SoftNoteShapes(space, arb, c.info.a, c.info.b)   # (new: not noted in the narrow phase)
    # (The point's age, carried by cpArbiterUpdate; 0 for a new one.)
    ctx.touchingPairs += 1
    if contacts[0].bias < SOFT_YOUNG_AGE:
        ctx.youngPairs += 1
    if ctx.pairs[i].slot != NULL and c.arb == NULL:
        ctx.pairs[i].slot.arbiter = arb    # new this step: next step's guess
    if ctx.keysInNarrow and space.arbiters.num == before + 1:
        SoftKeyAccepted(ctx, before)


# -- the bodies' arbiter lists -----------------------------------------------------------
# Munk2D unthreads every arbiter of the last step from its bodies' lists
# before the collision and threads this step's on again after it (head
# insertion in array order): two passes over every arbiter and its bodies.
# In a pile the step's arbiters are mostly the last step's; so, where
# nothing can look at the lists in between, they stay threaded, and only
# the arbiters that began or ended are threaded or unthreaded
# (SoftRethreadArbiters; a body's list then holds the same arbiters as
# Munk2D's, newest first). Nothing can look when sleeping is off
# (no waking, which walks them), no begin or pre-solve handler runs, and the
# collision persistence is above 0 now and was at the last step (at 0 its
# arbiters went back to the pool, and may be another pair's by now).
# cpArbiterUpdate swaps an arbiter's threads with its bodies, so the lists
# stay consistent whatever order its pair comes in.

cdef void SoftResetArbiters(SoftContext *ctx) noexcept nogil:
    # Last step's arbiters are left threaded until the narrow phase has
    # found this step's (SoftRethreadArbiters), where nothing can look at
    # the lists meanwhile. With sleeping on, only after a step whose lists
    # were exactly its array's, threaded in order, with nothing asleep
    # (cpSoftScratch.threadsClean): the flood fill follows the lists'
    # order, so they are kept only when re-threading would give the same.
    cdef cpSpace *space = ctx.space
    cdef cpArray *arbiters = space.arbiters
    cdef void **saved
    cdef bint sleep = space.sleepTimeThreshold != INFINITY
    cdef bint clean = space.softScratch.threadsClean + 1 == space.stamp
    ctx.threadedCount = -1
    # Anything that wakes or sleeps a body or drops an arbiter from here on
    # resets it (see SoftProcessComponents).
    space.softScratch.threadsClean = space.stamp
    if (_keep_threads and space.collisionPersistence > 0 and ctx.updateInNarrow
            and (not sleep or clean)):
        saved = <void **>_reserve(space, SOFT_SCRATCH_THREADED, arbiters.num, sizeof(void *))
        if saved != NULL:
            tamias_store(&ctx.uncachedArbiter, 0)
            SoftRun(ctx, SOFT_TASK_MARK_THREADED, 0, arbiters.num, 0)
            if not tamias_load(&ctx.uncachedArbiter):
                memcpy(saved, arbiters.arr, arbiters.num * sizeof(void *))
                ctx.threadedCount = arbiters.num
                arbiters.num = 0
                # (After a clean step no arbiter has a sleeping body: one
                # touched would have been woken, and waking or sleeping
                # since would have cleared the mark.)
                ctx.threadsEmptied = sleep
                return
            # (Some were reset before the pooled one was found: NORMAL, as
            # the full reset below makes them.)
    # Munk2D's reset leaves threaded the arbiters that have a sleeping body:
    # with none, the lists will hold this step's arrays alone, whether or
    # not components sleep elsewhere.
    ctx.threadsEmptied = StageResetArbiters(space) == 0 and sleep

cdef void SoftMarkThreaded(SoftContext *ctx, int begin, int end) noexcept nogil:
    # Last step's arbiters [begin, end), kept threaded: their state reset as
    # StageResetArbiters does (on the pool: a cache miss per arbiter, which
    # two cores wait out side by side). Most are NORMAL already and are only
    # read, so their lines are not written back; which of them were
    # threaded is marked only if this step's arbiters turn out to differ
    # (SoftRethreadArbiters).
    cdef cpArray *arbiters = ctx.space.arbiters
    cdef cpArbiter *arb
    cdef int i
    for i in range(begin, end):
        if ctx.fetchAhead and i + SOFT_ARBITER_PREFETCH < end:
            tamias_prefetch(&(<cpArbiter *>arbiters.arr[i + SOFT_ARBITER_PREFETCH]).state)
        arb = <cpArbiter *>arbiters.arr[i]
        if not arb.cached:
            # Pooled while threaded by a step at collision persistence 0
            # (Munk2D's filter): the persistence was raised since, and the
            # pool may hand it to a new pair in this collision, so every
            # thread goes first (SoftResetArbiters).
            tamias_store(&ctx.uncachedArbiter, 1)
            return
        if arb.state != CP_ARBITER_STATE_NORMAL:
            arb.state = CP_ARBITER_STATE_NORMAL

cdef bint SoftRethreadArbiters(SoftContext *ctx, int collided) noexcept nogil:
    # Whether this step's arbiters are threaded already (else
    # cpSpaceProcessComponents threads them). With last step's arbiters
    # still threaded (SoftResetArbiters), they are if they are the same, in
    # the same order. Otherwise, with sleeping on, last step's are unlinked
    # here as Munk2D does before the narrow phase (StageResetArbiters), and
    # the step threads them all. With sleeping off only the difference is
    # done: this step's arbiters that were not last step's are pushed onto
    # their bodies' lists (in array order), then last step's that are not
    # this step's are unlinked. (A full re-threading writes every body's
    # list head and every arbiter's links: most of a settled pile's step
    # when one of its thousands of contacts comes or goes.)
    cdef cpSpace *space = ctx.space
    cdef void **saved = <void **>space.softScratch.buf[SOFT_SCRATCH_THREADED]
    cdef cpArbiter *arb
    cdef int i
    if ctx.threadedCount < 0:
        return 0
    if (ctx.threadedCount == collided and collided == space.arbiters.num
            and memcmp(saved, space.arbiters.arr, collided * sizeof(void *)) == 0):
        tamias_add(&_kept_threads, 1)
        return 1
    if space.sleepTimeThreshold != INFINITY:
        # (Nothing between the reset and here can change it: no handlers.)
        for i in range(ctx.threadedCount):
            arb = <cpArbiter *>saved[i]
            if not cpBodyIsSleeping(arb.body_a) and not cpBodyIsSleeping(arb.body_b):
                cpArbiterUnthread(arb)
        return 0
    # Last step's arbiters, all still threaded, are marked; this step's that
    # are marked stay, the others are threaded; last step's still marked
    # after that are unthreaded.
    for i in range(ctx.threadedCount):
        (<cpArbiter *>saved[i]).softThreaded = space.stamp
    for i in range(collided):
        arb = <cpArbiter *>space.arbiters.arr[i]
        if arb.softThreaded == space.stamp:
            arb.softThreaded = 0         # threaded, and stays
        else:
            cpArbiterPushThreads(arb)
    for i in range(ctx.threadedCount):
        arb = <cpArbiter *>saved[i]
        if arb.softThreaded == space.stamp:
            arb.softThreaded = 0
            cpArbiterUnthread(arb)
    return 1


cdef void SoftProcessComponents(SoftContext *ctx, cpFloat dt, int collided) noexcept nogil:
    # The contact graph stage, and whether its lists end up exactly the
    # step's array, threaded in order, with no arbiter of a sleeping body
    # left on them: then the next step may keep them (SoftResetArbiters).
    # Waking or putting a body to sleep in between resets the mark
    # (cpSpaceActivateBody and the like).
    cdef cpSpace *space = ctx.space
    cdef int *links = NULL
    cdef int *islands = NULL
    cdef int skipped
    # (At a threshold <= 0 the flood fill always runs: _holdAwakeTouching.)
    if ctx.threadsEmptied and _link_components and space.sleepTimeThreshold > 0.0:
        links = <int *>_reserve(space, SOFT_SCRATCH_COMPONENTS, 2 * space.dynamicBodies.num + 2,
                                sizeof(int))
        if links != NULL and _keep_islands:
            islands = <int *>_reserve(space, SOFT_SCRATCH_ISLANDS,
                                      3 * space.dynamicBodies.num + 3, sizeof(int))
    skipped = cpSpaceProcessComponents(space, dt, collided, SoftRethreadArbiters(ctx, collided),
                                       links, islands)
    if skipped:
        tamias_add(&_linked_components, 1)
    if skipped == 2:
        tamias_add(&_kept_islands, 1)
    # (Components that were asleep before the step may stay asleep: their
    # arbiters are not in the array, and none of this step's touches them.
    # One put to sleep here has cleared the mark.)
    if not (ctx.threadsEmptied and space.softScratch.threadsClean == space.stamp
            and space.arbiters.num == collided):
        space.softScratch.threadsClean = 0


# -- gather ----------------------------------------------------------------------------

cdef bint SoftGatherBodies(SoftContext *ctx) noexcept nogil:
    # The awake bodies into slots 1.. (on the pool when threaded); slot 0 is
    # the immovable body every static, sleeping or removed one maps to.
    cdef cpSpace *space = ctx.space
    cdef int n = space.dynamicBodies.num + 1
    cdef SoftBody *sb
    if n > INT_MAX // <int>sizeof(SoftState):
        # The lanes hold slots as byte offsets in an int (SoftPackLane):
        # beyond 33 million bodies, as if out of memory (which a space of
        # that size all but is).
        cpSetOutOfMemory()
        return 0
    ctx.bodies = <SoftBody *>_reserve(space, SOFT_SCRATCH_BODIES, n, sizeof(SoftBody))
    ctx.states = <SoftState *>_reserve_lines(space, SOFT_SCRATCH_STATES, n, sizeof(SoftState))
    ctx.motion = <SoftMotion *>_reserve(space, SOFT_SCRATCH_MOTION, n, sizeof(SoftMotion))
    if ctx.bodies == NULL or ctx.states == NULL or ctx.motion == NULL:
        return 0
    ctx.bodyCount = n
    memset(&ctx.states[0], 0, sizeof(SoftState))
    ctx.states[0].qc = 1.0
    sb = &ctx.bodies[0]
    sb.m_inv = sb.i_inv = 0.0
    sb.body = NULL
    sb.flags = 0
    sb.contacts = 0
    tamias_store(&ctx.customVelocity, 0)
    tamias_store(&ctx.customPosition, 0)
    SoftRun(ctx, SOFT_TASK_GATHER, 1, n, 0)
    ctx.serialVelocities = tamias_load(&ctx.customVelocity) != 0
    ctx.serialPositions = tamias_load(&ctx.customPosition) != 0
    ctx.livePositions = ctx.serialVelocities
    return 1

cdef inline void SoftGatherMotion(SoftContext *ctx, int i, const cpBody *body) noexcept nogil:
    cdef SoftMotion *mo = &ctx.motion[i]
    mo.ax = ctx.gx + body.f.x * body.m_inv
    mo.ay = ctx.gy + body.f.y * body.m_inv
    mo.alpha = body.t * body.i_inv
    mo.px = body.p.x
    mo.py = body.p.y
    mo.a = body.a

cdef void SoftGatherRange(SoftContext *ctx, int begin, int end) noexcept nogil:
    cdef cpArray *arr = ctx.space.dynamicBodies
    cdef int i
    cdef SoftBody *sb
    cdef SoftState *st
    cdef cpBody *body
    for i in range(begin, end):
        if ctx.fetchAhead and i + SOFT_BODY_PREFETCH < end:
            # (Each body lives in its Python object, scattered.)
            SoftFetchLines(arr.arr[i - 1 + SOFT_BODY_PREFETCH], sizeof(cpBody))
        body = <cpBody *>arr.arr[i - 1]
        body.solverIndex = i
        SoftGatherMotion(ctx, i, body)
        st = &ctx.states[i]
        st.vx = body.v.x
        st.vy = body.v.y
        st.w = body.w
        st.dpx = st.dpy = 0.0
        st.qc = 1.0
        st.qs = 0.0
        sb = &ctx.bodies[i]
        sb.m_inv = body.m_inv
        st.m_inv = body.m_inv     # the contact kernels read it there
        sb.i_inv = body.i_inv
        sb.body = body
        sb.flags = 0
        sb.contacts = 0
        if body.velocity_func == cpBodyUpdateVelocity:
            sb.flags |= SOFT_BODY_DEFAULT_VELOCITY
        else:
            tamias_store(&ctx.customVelocity, 1)
        if body.position_func == cpBodyUpdatePosition:
            sb.flags |= SOFT_BODY_DEFAULT_POSITION
        else:
            tamias_store(&ctx.customPosition, 1)
        if cpBodyGetType(body) == CP_BODY_TYPE_KINEMATIC:
            sb.flags |= SOFT_BODY_KINEMATIC
        if body.m_inv != 0.0 or body.i_inv != 0.0:
            sb.flags |= SOFT_BODY_MOVABLE


# -- joints ------------------------------------------------------------------------------
# The joints are soft constraints, as Box2D v3's: each substep their
# softPreStep measures the position error, applyCachedImpulse warm starts,
# softApplyImpulse solves with the joint softness (and rigidly, without
# correction, in the relax pass). Springs and the motor keep Chipmunk's step.
# These work on the cpBody structs (constraints.pyx), so the bodies they
# touch are written out of the arrays before and read back after (only
# those: the contact loops never leave the arrays).

cdef bint SoftPrepareJoints(SoftContext *ctx, cpFloat prev_dt) noexcept nogil:
    cdef cpSpace *space = ctx.space
    cdef cpArray *constraints = space.constraints
    cdef cpConstraint *c
    cdef int i, k, slot
    cdef cpBody *ends[2]
    cdef cpFloat coef = ctx.h / prev_dt if prev_dt != 0.0 else 0.0
    cdef bint called = 0
    ctx.jointBodyCount = 0
    ctx.jointBodies = NULL
    if constraints.num == 0:
        return 1
    ctx.jointBodies = <int *>_reserve(space, SOFT_SCRATCH_JOINT_BODIES, 2 * constraints.num,
                                      sizeof(int))
    if ctx.jointBodies == NULL:
        return 0
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        if c.preSolve != NULL:
            c.preSolve(c, space)
            called = 1
        # Between steps the accumulated impulse is per step (as the chipmunk
        # solver keeps it); inside this step it is per substep.
        tamias_constraint_scale_impulse(c, coef)
        ends[0] = c.a
        ends[1] = c.b
        for k in range(2):
            slot = SoftIndex(ends[k], ctx.bodies, ctx.bodyCount)
            if slot > 0 and not (ctx.bodies[slot].flags & SOFT_BODY_JOINTED):
                ctx.bodies[slot].flags |= SOFT_BODY_JOINTED
                ctx.jointBodies[ctx.jointBodyCount] = slot
                ctx.jointBodyCount += 1
    if called:
        # A pre-solve callback may have pushed or moved a body.
        for i in range(1, ctx.bodyCount):
            SoftGatherMotion(ctx, i, ctx.bodies[i].body)
    return 1

cdef inline void SoftScatterJointBodies(SoftContext *ctx) noexcept nogil:
    cdef int i, slot
    cdef cpBody *body
    for i in range(ctx.jointBodyCount):
        slot = ctx.jointBodies[i]
        body = ctx.bodies[slot].body
        body.v.x = ctx.states[slot].vx
        body.v.y = ctx.states[slot].vy
        body.w = ctx.states[slot].w

cdef inline void SoftGatherJointBodies(SoftContext *ctx) noexcept nogil:
    cdef int i, slot
    cdef cpBody *body
    for i in range(ctx.jointBodyCount):
        slot = ctx.jointBodies[i]
        body = ctx.bodies[slot].body
        ctx.states[slot].vx = body.v.x
        ctx.states[slot].vy = body.v.y
        ctx.states[slot].w = body.w

cdef void SoftJointsWarmStart(SoftContext *ctx) noexcept nogil:
    cdef cpArray *constraints = ctx.space.constraints
    cdef cpConstraint *c
    cdef int i
    if constraints.num == 0:
        return
    SoftScatterJointBodies(ctx)
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        c.klass.softPreStep(c, ctx.h)
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        c.klass.applyCachedImpulse(c, 1.0)
    SoftGatherJointBodies(ctx)

cdef void SoftJointsRefresh(SoftContext *ctx) noexcept nogil:
    # The joints' arms, axes and masses at the bodies' moved positions, for
    # the relax pass (Box2D's joints read the current rotation in every
    # solve; arms a substep old let a light chain open by 40% more). Only
    # the joints with a soft pre-step of their own: that is geometry alone,
    # while Chipmunk's (springs, motor) apply the spring's impulse.
    cdef cpArray *constraints = ctx.space.constraints
    cdef cpConstraint *c
    cdef int i
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        if c.klass.softPreStep != c.klass.preStep:
            c.klass.softPreStep(c, ctx.h)

cdef void SoftJointsSolve(SoftContext *ctx, bint useBias) noexcept nogil:
    cdef cpArray *constraints = ctx.space.constraints
    cdef cpConstraint *c
    cdef const SoftSoftness *soft = &ctx.jointSoft if useBias else NULL
    cdef int i
    if constraints.num == 0:
        return
    SoftScatterJointBodies(ctx)
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        c.klass.softApplyImpulse(c, ctx.h, soft)
    SoftGatherJointBodies(ctx)

cdef void SoftFinishJoints(SoftContext *ctx) noexcept nogil:
    # Back to a per-step impulse (what Constraint.impulse reports and the
    # next step, of either solver, warm-starts from).
    cdef cpArray *constraints = ctx.space.constraints
    cdef int i
    for i in range(constraints.num):
        tamias_constraint_scale_impulse(<cpConstraint *>constraints.arr[i], <cpFloat>ctx.substeps)


# -- contacts ------------------------------------------------------------------------------

cdef inline cpFloat SoftShapeSide(const cpShape *shape) noexcept nogil:
    # The smaller side of a shape's bounding box. (cpfmin, a comparison,
    # where the sizes cannot be NaN or -0: libm's fmin is a call.)
    return cpfmin(shape.bb.r - shape.bb.l, shape.bb.t - shape.bb.b)

cdef inline cpFloat SoftShapeSize(cpFloat side, const cpShape *shape,
                                  const SoftBody *body) noexcept nogil:
    # A movable body's shape's size (its box's smaller side); 0 for an
    # immovable one (a ground segment's thickness says nothing). The body's
    # masses from its slot (the same numbers), or for slot 0 from the body
    # (static or asleep): the shapes' bodies stay out of cache.
    cdef cpFloat m_inv = body.m_inv
    cdef cpFloat i_inv = body.i_inv
    if body.body == NULL:
        m_inv = shape.body.m_inv
        i_inv = shape.body.i_inv
    if m_inv == 0.0 and i_inv == 0.0:
        return 0.0
    return side

cdef inline cpFloat SoftContactSize(const cpArbiter *arb, const SoftBody *a, const SoftBody *b,
                                    bint noted) noexcept nogil:
    # The smaller of its movable shapes' sizes; the sides as the narrow
    # phase noted them if `noted` (the shapes stay out of cache).
    cdef cpFloat sa = SoftShapeSize(arb.softSideA if noted else SoftShapeSide(arb.a), arb.a, a)
    cdef cpFloat sb = SoftShapeSize(arb.softSideB if noted else SoftShapeSide(arb.b), arb.b, b)
    if sa == 0.0:
        return sb
    if sb == 0.0:
        return sa
    return cpfmin(sa, sb)

cdef inline cpFloat SoftPreload(SoftBody *a, SoftBody *b, bint inBlock,
                                cpFloat *maxStiffening) noexcept nogil:
    # The fraction of a point's load its spring holds at no depth. A soft
    # contact settles where its bias balances the impulse it leaks, so under
    # a load it sinks in proportion to the load: the bottom of a tall stack
    # or pyramid, or a light body under a heavy one, far more than the top.
    # The leak is taken from the impulse above the preload instead, so a
    # point carrying its usual load sits at no depth, and the spring and its
    # damping act on the change of load only (stiffness and damping are the
    # base ones: a stiffness that follows the load pumps a tall stack's
    # column into bouncing). Where the preload is not taken (large mass
    # ratios) a loaded point may be stiffened instead: *maxStiffening.
    cdef cpFloat lo, hi
    maxStiffening[0] = 1.0
    if (a.body != NULL and a.contacts > 2) or (b.body != NULL and b.contacts > 2):
        return SOFT_PRELOAD_WEB
    if a.m_inv == 0.0 or b.m_inv == 0.0 or inBlock:
        # (A block's rows carry a heavy body's load through at once.)
        return SOFT_PRELOAD_CHAIN
    lo = cpfmin(a.m_inv, b.m_inv)
    hi = cpfmax(a.m_inv, b.m_inv)
    if lo * SOFT_PRELOAD_MAX_RATIO >= hi:
        return SOFT_PRELOAD_CHAIN
    maxStiffening[0] = SOFT_RATIO_STIFFENING
    return 0.0

# A point's load filter once it is SOFT_LOAD_AGE steps old (SoftPrepareContact).
cdef cpFloat _mature_smoothing = fmax(1.0 / SOFT_LOAD_AGE, SOFT_LOAD_SMOOTHING)

cdef inline cpFloat SoftCompliance(const SoftSoftness *s) noexcept nogil:
    # A softness as the compliance the solvers read: massScale and
    # impulseScale are 1 / (1 + c) and c / (1 + c).
    return s.impulseScale / s.massScale if s.massScale > 0.0 else 0.0

cdef inline void SoftPointSoftness(SoftPoint *sp, cpFloat biasRate, cpFloat c, cpFloat cMin,
                                   cpFloat load, cpFloat size, cpFloat h) noexcept nogil:
    # A soft contact settles where its bias balances the impulse it leaks:
    # (compliance / normalMass) * impulse = biasRate * depth. Under a load F
    # (impulse F h per substep) it sinks compliance F h / (normalMass
    # biasRate) deep. Where it is not preloaded (SoftPreload), a point whose
    # (filtered) load would sink it deeper than
    # SOFT_MAX_LOAD_DEFLECTION x `size` leaks less (a smaller compliance); its bias
    # rate, which sets how fast overlap is pushed out, stays. That is the
    # implicit spring-damper with stiffness and damping both scaled up by
    # the same factor, so its damping ratio is kept. c is the softness's
    # compliance (SoftCompliance), cMin that over the largest stiffening
    # allowed (SoftPreload): both worked out once a step.
    cdef cpFloat need
    if load > 0.0 and c > 0.0 and size > 0.0:
        need = SOFT_MAX_LOAD_DEFLECTION * size * sp.normalMass * biasRate / (load * h)
        if need < cMin:
            need = cMin
        if need < c:
            c = need
    sp.biasRate = biasRate
    sp.compliance = c


cdef bint SoftPrepareContacts(SoftContext *ctx, cpFloat prev_dt) noexcept nogil:
    # The arbiters with contacts, in order, become the step's contacts:
    # here each one's bodies' slots and colouring key are found (and the
    # bodies' contact counts), on the pool when the step is threaded. They
    # are prepared after the colouring, straight into their lanes
    # (SoftPrepareLanes).
    cdef cpSpace *space = ctx.space
    cdef cpArray *arbiters = space.arbiters
    cdef int i, n = 0
    cdef cpArbiter *arb
    ctx.contacts = <SoftContact *>_reserve(space, SOFT_SCRATCH_CONTACTS, arbiters.num,
                                           sizeof(SoftContact))
    if ctx.contacts == NULL:
        return 0
    if not ctx.keysInNarrow:
        ctx.contactSource = <int *>_reserve(space, SOFT_SCRATCH_SOURCE, arbiters.num, sizeof(int))
        ctx.colorKeys = <SoftColorKey *>_reserve(space, SOFT_SCRATCH_KEYS, arbiters.num,
                                                 sizeof(SoftColorKey))
        if ctx.contactSource == NULL or ctx.colorKeys == NULL:
            return 0
        ctx.loadEstimates = NULL
        if ctx.estimating and not SoftReserveLoads(ctx, arbiters.num):
            ctx.estimating = 0      # (out of memory: the flag is up; no estimates)
    # (Else SoftReserveKeys made them, for as many contacts as pairs: the
    # loads' arrays laid out for that many, which SoftEstimateLoads's for
    # fewer fit within.)
    ctx.warmCoef = ctx.h / prev_dt if prev_dt != 0.0 else 0.0
    ctx.loadCoef = 1.0 / prev_dt if prev_dt != 0.0 else 0.0
    # On the pool; an arbiter without contacts (only after a failed
    # allocation) makes it all be done again here, skipping those.
    tamias_store(&ctx.emptyArbiter, 0)
    tamias_store(&ctx.ratioPairs, 0)
    ctx.blockBodyCount = 0
    if ctx.keysInNarrow:
        # (Counted already: SoftKeyAccepted, and on threads SoftNarrowPhase.)
        tamias_add(&_narrow_counts, 1)
        SoftStoreSeen(ctx, ctx.keySeen
                      | (SOFT_SEEN_RATIO if tamias_load(&ctx.narrowSeen[0]) else 0)
                      | (SOFT_SEEN_ELASTIC if tamias_load(&ctx.narrowSeen[1]) else 0))
    else:
        SoftRun(ctx, SOFT_TASK_COUNT, 0, arbiters.num, 0)
    if tamias_load(&ctx.emptyArbiter):
        for i in range(arbiters.num):
            arb = <cpArbiter *>arbiters.arr[i]
            if arb.count <= 0 or arb.contacts == NULL:
                continue
            ctx.contactSource[n] = i
            SoftStoreSeen(ctx, SoftCountContact(ctx, arb, n))
            n += 1
    else:
        n = arbiters.num
    ctx.contactCount = n
    # The estimate runs beside the colouring, which does not read it
    # (cpSoftStep), unless blocks are found, which come after it.
    ctx.estimatePending = ctx.estimating
    if tamias_load(&ctx.ratioPairs) and _use_blocks:
        if ctx.estimating:
            SoftEstimateLoads(ctx)
            ctx.estimatePending = 0
        return SoftFindBlocks(ctx)
    return 1

cdef inline int SoftContactKind(const cpArbiter *arb, const SoftBody *a,
                                const SoftBody *b) noexcept nogil:
    # Its lane kind (SoftColorKey.kind) as its preparation will find it, by
    # the same arithmetic: one point with a normal mass, or two whose rows
    # can be solved together (SoftPrepareBlock); -1 otherwise.
    cdef const cpContact *con = arb.contacts
    cdef cpFloat nx = arb.n.x
    cdef cpFloat ny = arb.n.y
    cdef cpFloat rnA1 = con[0].r1.x * ny - con[0].r1.y * nx
    cdef cpFloat rnB1 = con[0].r2.x * ny - con[0].r2.y * nx
    cdef cpFloat k11, k22, k12
    if arb.count == 1:
        # (The preparation's normal mass, 1 / this, is then above 0.)
        k11 = a.m_inv + b.m_inv + a.i_inv * rnA1 * rnA1 + b.i_inv * rnB1 * rnB1
        return 0 if k11 > 0.0 else -1
    if SoftBlockMatrix(rnA1, rnB1, con[1].r1.x * ny - con[1].r1.y * nx,
                       con[1].r2.x * ny - con[1].r2.y * nx, a, b, &k11, &k22, &k12):
        return 1
    return -1

cdef inline int SoftLighterSide(const SoftBody *a, const SoftBody *b) noexcept nogil:
    # 1 if A is SOFT_BLOCK_RATIO times lighter than B or more, 2 if B than
    # A, else 0 (both movable).
    if a.m_inv >= SOFT_BLOCK_RATIO * b.m_inv:
        return 1
    if b.m_inv >= SOFT_BLOCK_RATIO * a.m_inv:
        return 2
    return 0

cdef inline int SoftUnionRoot(int *parent, int slot) noexcept nogil:
    # A slot's root in a union-find (the blocks', the contact groups'),
    # halving the path on the way.
    while parent[slot] != slot:
        parent[slot] = parent[parent[slot]]
        slot = parent[slot]
    return slot

cdef bint SoftFindBlocks(SoftContext *ctx) noexcept nogil:
    # The light bodies: those with a movable neighbour SOFT_BLOCK_RATIO
    # times heavier or more, then those no heavier than a light body they
    # touch (what a light body rests on carries the heavy load too), up to
    # SOFT_BLOCK_SPREAD contacts away. Light bodies that touch are one
    # block; a block's contacts (all that touch its bodies) go to the
    # overflow, and their rows are solved together (SoftSolveBlock). A
    # block with more than SOFT_BLOCK_ROWS rows is not one: its contacts are
    # solved one by one as any. (Cutting such a block back to the bodies
    # nearest the heavy one carried its load exactly to bodies solved one
    # by one, which it then crushed, faster than with no block at all.)
    # Only in a step with such a pair (ctx.ratioPairs).
    cdef int n = ctx.contactCount
    cdef int nb = ctx.bodyCount
    cdef int *lists = <int *>_reserve(ctx.space, SOFT_SCRATCH_BLOCKS, 5 * nb + n, sizeof(int))
    cdef int *light
    cdef SoftColorKey *key
    cdef int i, side, round
    cdef bint grown
    if lists == NULL:
        return 0
    light = lists
    ctx.blockHead = lists + 2 * nb
    ctx.blockBodies = lists + 3 * nb
    ctx.blockNext = lists + 5 * nb
    memset(light, 0, <size_t>nb * sizeof(int))
    for i in range(n):
        key = &ctx.colorKeys[i]
        if key.a != 0 and key.b != 0:
            side = SoftLighterSide(&ctx.bodies[key.ia], &ctx.bodies[key.ib])
            if side != 0:
                light[key.ia if side == 1 else key.ib] = 1
    # Spread: in round r a body becomes light (light = r + 1) from one that
    # was light before the round (1 <= light <= r).
    for round in range(1, SOFT_BLOCK_SPREAD + 1):
        grown = 0
        for i in range(n):
            key = &ctx.colorKeys[i]
            if key.a == 0 or key.b == 0:
                continue
            if 1 <= light[key.ia] <= round and light[key.ib] == 0:
                if ctx.bodies[key.ib].m_inv >= ctx.bodies[key.ia].m_inv:
                    light[key.ib] = round + 1
                    grown = 1
            elif 1 <= light[key.ib] <= round and light[key.ia] == 0:
                if ctx.bodies[key.ia].m_inv >= ctx.bodies[key.ib].m_inv:
                    light[key.ia] = round + 1
                    grown = 1
        if not grown:
            break
    SoftGroupBlocks(ctx, light, lists + nb, lists + 4 * nb)
    return 1

cdef void SoftGroupBlocks(SoftContext *ctx, const int *light, int *parent,
                          int *rows) noexcept nogil:
    # The blocks of the light bodies (light[slot] != 0, SoftFindBlocks),
    # their roots the lowest slots; one with more than SOFT_BLOCK_ROWS rows
    # (a normal and a tangent row per point) is left out.
    cdef int n = ctx.contactCount
    cdef int nb = ctx.bodyCount
    cdef int i, root, ra, rb
    cdef SoftColorKey *key
    cdef cpArbiter *arb
    for i in range(nb):
        parent[i] = i
        rows[i] = 0
        ctx.blockHead[i] = -1
    for i in range(n):
        key = &ctx.colorKeys[i]
        if key.a != 0 and key.b != 0 and light[key.ia] and light[key.ib]:
            ra = SoftUnionRoot(parent, key.ia)
            rb = SoftUnionRoot(parent, key.ib)
            if ra != rb:
                parent[rb if ra < rb else ra] = ra if ra < rb else rb
    # Each contact's block (ctx.blockNext for now), and each block's rows.
    for i in range(n):
        key = &ctx.colorKeys[i]
        root = -1
        if key.ia != 0 and light[key.ia]:
            root = SoftUnionRoot(parent, key.ia)
        elif key.ib != 0 and light[key.ib]:
            root = SoftUnionRoot(parent, key.ib)
        ctx.blockNext[i] = root
        if root >= 0:
            arb = <cpArbiter *>ctx.space.arbiters.arr[ctx.contactSource[i]]
            rows[root] += 2 * (arb.count if arb.count <= 2 else 2)
    # Each block's contacts, in arbiter order; the blocks in their roots' order.
    for i in range(n - 1, -1, -1):
        key = &ctx.colorKeys[i]
        root = ctx.blockNext[i]
        ctx.blockNext[i] = -1
        if root >= 0 and rows[root] <= SOFT_BLOCK_ROWS:
            ctx.blockNext[i] = ctx.blockHead[root]
            ctx.blockHead[root] = i
            key.kind = -1
            key.block = 1
    ctx.blockBodyCount = 0
    for i in range(1, nb):
        if ctx.blockHead[i] >= 0:
            ctx.blockBodies[ctx.blockBodyCount] = i
            ctx.blockBodyCount += 1
    ctx.blockCache = NULL
    if ctx.blockBodyCount > 0:
        ctx.blockCache = <SoftBlockCache *>_reserve(ctx.space, SOFT_SCRATCH_BLOCK_CACHE,
                                                    ctx.blockBodyCount, sizeof(SoftBlockCache))
        if ctx.blockCache == NULL:
            # (Out of memory: no blocks, the contacts one by one.)
            for i in range(n):
                ctx.colorKeys[i].block = 0
            ctx.blockBodyCount = 0
            return
        for i in range(ctx.blockBodyCount):
            ctx.blockCache[i].built = 0

# -- a pile's loads from its weights ------------------------------------------------------
# (SOFT_ESTIMATE_MIN_CARRY in _soft_step.pxd says why.) Each body's weight,
# and what rests on it, is shared among the contacts that hold it up, each
# taking the same normal force, whose upward parts add up to the load; the
# body below carries its part on. Bodies are taken from the top of the pile
# down: a body once every body it holds up has been (Kahn's order, from the
# contacts alone; bodies in a cycle of holds get nothing). The same pass
# gives each new contact at rest its warm start, so that a pile built at
# rest does not sink into its springs while they learn their loads.

cdef bint SoftReserveLoads(SoftContext *ctx, int n) noexcept nogil:
    # Per contact: held and holding slots, lift, estimate; the holds listed
    # by held body (contact, lift, holding slot); per slot: load, list
    # start, holds left, queue.
    cdef int nb = ctx.bodyCount
    cdef size_t doubles = 3 * <size_t>n + <size_t>nb
    cdef size_t ints = 4 * <size_t>n + 3 * <size_t>nb + 1
    cdef char *buf = <char *>_reserve(ctx.space, SOFT_SCRATCH_LOADS,
                                      <int>((doubles * sizeof(cpFloat) + ints * sizeof(int)
                                             + sizeof(cpFloat) - 1) // sizeof(cpFloat)),
                                      sizeof(cpFloat))
    if buf == NULL:
        return 0
    ctx.loadLift = <cpFloat *>buf
    ctx.loadEstimates = ctx.loadLift + n
    ctx.loadHeld = <int *>(ctx.loadEstimates + 2 * n + nb)
    ctx.loadOther = ctx.loadHeld + n
    return 1

cdef inline void SoftNoteHolding(SoftContext *ctx, cpArbiter *arb, SoftColorKey *key,
                                 int n) noexcept nogil:
    # Whether contact n holds up one of its bodies: its push on it points
    # up (SOFT_HOLD_MIN_LIFT), and the two touch (within the slop), not
    # only within the speculative distance. (Holds that carried a load last
    # step, a test that reads no positions, tipped over one card house of
    # 27 that stands with this one; leaving out the pairs closing or
    # parting faster than two steps of gravity changed none of the hard
    # cases' outcomes nor that sweep's, and its reads of the bodies' speeds
    # missed the cache: 0.6% of a large pile's step.)
    cdef cpFloat w = arb.n.x * ctx.upx + arb.n.y * ctx.upy
    cdef const cpContact *con = arb.contacts
    cdef int held = 0
    cdef int other = 0
    cdef int j
    cdef cpFloat sep = INFINITY
    cdef cpFloat d
    cdef cpVect pa, pb
    ctx.loadHeld[n] = 0
    ctx.loadLift[n] = 0.0
    # The arbiter's normal points from A to B: it pushes B along it.
    if w > SOFT_HOLD_MIN_LIFT:
        held = key.b
        other = key.a
    elif w < -SOFT_HOLD_MIN_LIFT:
        held = key.a
        other = key.b
        w = -w
    if held == 0:
        return
    pa = SoftSlotPosition(ctx, key.ia, arb.body_a)
    pb = SoftSlotPosition(ctx, key.ib, arb.body_b)
    for j in range(arb.count if arb.count <= 2 else 2):
        d = ((con[j].r2.x - con[j].r1.x + pb.x - pa.x) * arb.n.x
             + (con[j].r2.y - con[j].r1.y + pb.y - pa.y) * arb.n.y)
        if d < sep:
            sep = d
    if sep <= ctx.space.collisionSlop:
        ctx.loadHeld[n] = held
        ctx.loadOther[n] = other
        ctx.loadLift[n] = w

cdef void SoftEstimateLoads(SoftContext *ctx) noexcept nogil:
    # Each holding contact's estimate (ctx.loadEstimates): the normal force
    # the weights above put on it, negative where its body carries no more
    # than SOFT_ESTIMATE_MIN_CARRY times its weight (only a new contact's
    # warm start takes it there).
    cdef int n = ctx.contactCount
    cdef int nb = ctx.bodyCount
    cdef int *held = ctx.loadHeld
    cdef int *holding = ctx.loadOther
    cdef cpFloat *lift = ctx.loadLift
    cdef cpFloat *estimate = ctx.loadEstimates
    cdef cpFloat *load = estimate + n
    # (Each held body's holds side by side, so that the pass from the top
    # down reads them in order, not scattered over the contacts' arrays.)
    cdef cpFloat *listedLift = load + nb
    cdef int *listed = holding + n
    cdef int *listedHolding = listed + n
    cdef int *first = listedHolding + n
    cdef int *waiting = first + nb + 1     # holds of a body not yet taken
    cdef int *queue = waiting + nb
    cdef int i, j, slot, other, head, tail
    cdef cpFloat total, share, carry, blend
    cdef cpFloat perWeight = 1.0 / ctx.gravity
    memset(first, 0, (<size_t>nb + 1) * sizeof(int))
    memset(waiting, 0, <size_t>nb * sizeof(int))
    for i in range(n):
        estimate[i] = 0.0   # (here rather than a memset: the loop reads each i anyway)
        if held[i] != 0:
            first[held[i] + 1] += 1
            if holding[i] != 0:
                waiting[holding[i]] += 1
    for slot in range(nb):
        first[slot + 1] += first[slot]
    # (first[slot] walks its list forward, to the next one's start, and is
    # put back after.)
    for i in range(n):
        if held[i] != 0:
            j = first[held[i]]
            listed[j] = i
            listedLift[j] = lift[i]
            listedHolding[j] = holding[i]
            first[held[i]] += 1
    for slot in range(nb, 0, -1):
        first[slot] = first[slot - 1]
    first[0] = 0
    tail = 0
    for slot in range(1, nb):
        load[slot] = (ctx.gravity / ctx.bodies[slot].m_inv
                      if ctx.bodies[slot].m_inv > 0.0 else 0.0)
        if waiting[slot] == 0 and SoftMovable(ctx, slot):
            queue[tail] = slot
            tail += 1
    head = 0
    while head < tail:
        slot = queue[head]
        head += 1
        total = 0.0
        for j in range(first[slot], first[slot + 1]):
            total += listedLift[j]
        share = load[slot] / total if total > 0.0 else 0.0
        if not share < INFINITY:
            share = 0.0     # (weights past the doubles' range: no estimate)
        # How much of its holds' preloads the estimate gives (the rest is
        # their web preload), by the weights it carries.
        carry = load[slot] * ctx.bodies[slot].m_inv * perWeight
        blend = ((carry - SOFT_ESTIMATE_MIN_CARRY)
                 / (SOFT_ESTIMATE_FULL_CARRY - SOFT_ESTIMATE_MIN_CARRY))
        blend = 0.0 if not blend > 0.0 else (1.0 if blend > 1.0 else blend)
        if blend == 0.0:
            share = -share
        for j in range(first[slot], first[slot + 1]):
            i = listed[j]
            estimate[i] = share
            lift[i] = blend     # (its lift is not read again)
            other = listedHolding[j]
            if other != 0:
                load[other] += fabs(share) * listedLift[j]
                waiting[other] -= 1
                if waiting[other] == 0:
                    queue[tail] = other
                    tail += 1


cdef inline int SoftNotedIndex(int guess, cpBody *body, SoftContext *ctx) noexcept nogil:
    # SoftIndex, from the slot the narrow phase noted where it is right (the
    # body itself stays out of cache).
    if guess > 0 and guess < ctx.bodyCount and ctx.bodies[guess].body == body:
        return guess
    return SoftIndex(body, ctx.bodies, ctx.bodyCount)

cdef enum:
    # What SoftCountContact saw, for its caller to store once (ctx.ratioPairs,
    # ctx.elastic): a store for each contact was an atomic exchange each.
    SOFT_SEEN_RATIO = 1
    SOFT_SEEN_ELASTIC = 2

cdef inline int SoftCountContact(SoftContext *ctx, cpArbiter *arb, int n) noexcept nogil:
    # Contact n (of arbiter arb): its key; returns SOFT_SEEN_* bits. (Its
    # bodies' numbers of contacts are counted by the colouring.)
    cdef SoftColorKey *key = &ctx.colorKeys[n]
    cdef bint noted = arb.softNoted == ctx.space.stamp
    cdef int ia = SoftNotedIndex(arb.softSlotA if noted else 0, arb.body_a, ctx)
    cdef int ib = SoftNotedIndex(arb.softSlotB if noted else 0, arb.body_b, ctx)
    cdef int seen = 0
    key.ia = ia
    key.ib = ib
    key.a = ia if SoftMovable(ctx, ia) else 0
    key.b = ib if SoftMovable(ctx, ib) else 0
    key.kind = SoftContactKind(arb, &ctx.bodies[ia], &ctx.bodies[ib])
    key.size = SoftContactSize(arb, &ctx.bodies[ia], &ctx.bodies[ib], noted)
    key.block = 0
    if ctx.estimating:
        SoftNoteHolding(ctx, arb, key, n)
    if key.a != 0 and key.b != 0 and SoftLighterSide(&ctx.bodies[ia], &ctx.bodies[ib]) != 0:
        seen = SOFT_SEEN_RATIO
    if arb.e != 0.0:
        seen |= SOFT_SEEN_ELASTIC
    return seen

cdef inline void SoftStoreSeen(SoftContext *ctx, int seen) noexcept nogil:
    # SoftCountContact's findings over a range of contacts.
    if seen & SOFT_SEEN_RATIO:
        tamias_store(&ctx.ratioPairs, 1)
    if seen & SOFT_SEEN_ELASTIC:
        tamias_store(&ctx.elastic, 1)

cdef inline void SoftFetchMotion(SoftContext *ctx, int slot) noexcept nogil:
    if 0 < slot < ctx.bodyCount:
        tamias_prefetch(&ctx.motion[slot].px)

cdef void SoftCountRange(SoftContext *ctx, int begin, int end) noexcept nogil:
    cdef cpArray *arbiters = ctx.space.arbiters
    cdef cpArbiter *arb
    cdef int i
    cdef int seen = 0
    for i in range(begin, end):
        if ctx.fetchAhead and i + SOFT_ARBITER_PREFETCH < end:
            # (Arbiters are scattered: a cache miss each otherwise.)
            SoftFetchLines(arbiters.arr[i + SOFT_ARBITER_PREFETCH], sizeof(cpArbiter))
        if ctx.fetchAhead and i + SOFT_ARBITER_PREFETCH // 2 < end:
            # Its contacts, now that the arbiter itself has been fetched
            # (SoftContactKind reads both of a two-point manifold's).
            arb = <cpArbiter *>arbiters.arr[i + SOFT_ARBITER_PREFETCH // 2]
            SoftFetchLines(arb.contacts, arb.count * sizeof(cpContact))
            if ctx.estimating:
                # And what the hold's test reads of its bodies' slots (the
                # narrow phase noted them; a wrong guess costs a fetch).
                SoftFetchMotion(ctx, arb.softSlotA)
                SoftFetchMotion(ctx, arb.softSlotB)
        arb = <cpArbiter *>arbiters.arr[i]
        if arb.count <= 0 or arb.contacts == NULL:
            tamias_store(&ctx.emptyArbiter, 1)
            continue
        ctx.contactSource[i] = i
        seen |= SoftCountContact(ctx, arb, i)
    SoftStoreSeen(ctx, seen)

# Counted in the narrow phase. On one thread, where nothing between the
# narrow phase and the preparation can change a body (no collision handler
# that runs Python; with sleeping on, nothing woken or put to sleep: checked),
# the bodies are gathered
# before the narrow phase, and each arbiter's key is found as the narrow
# phase accepts it, with the arbiter and its contacts in cache: the count's
# pass over the arbiters, a cache miss or more each, is not made. The same
# keys from the same arithmetic; checked again before they are used
# (SoftKeysHold), or counted by that pass after all.

cdef bint SoftKeysMayBeCounted(SoftContext *ctx) noexcept nogil:
    # Whether this step's keys can be counted in its narrow phase: then the
    # bodies are gathered now.
    cdef cpSpace *space = ctx.space
    # (At collision persistence 0 the arbiter cache's filter empties this
    # step's arbiters after the narrow phase: the count skips them. With
    # sleeping on, the components stage between may wake a body or put one
    # to sleep, which moves the slots: SoftKeysHold then refuses the keys.)
    if not (_count_in_narrow and space.collisionPersistence > 0
            and (space.sleepTimeThreshold != INFINITY or space.sleepingComponents.num == 0)
            and ctx.updateInNarrow and not cpSpaceHasHandlers(space, 0, 0, 0, 1)):
        return 0
    return SoftGatherBodies(ctx)

cdef bint SoftReserveKeys(SoftContext *ctx, int pairs) noexcept nogil:
    # The count's arrays, before the narrow phase: for as many arbiters as
    # there are pairs (each pair adds one at most).
    cdef cpSpace *space = ctx.space
    ctx.contactSource = <int *>_reserve(space, SOFT_SCRATCH_SOURCE, pairs, sizeof(int))
    ctx.colorKeys = <SoftColorKey *>_reserve(space, SOFT_SCRATCH_KEYS, pairs, sizeof(SoftColorKey))
    if ctx.contactSource == NULL or ctx.colorKeys == NULL:
        return 0
    if ctx.estimating and not SoftReserveLoads(ctx, pairs):
        ctx.estimating = 0      # (out of memory: the flag is up; no estimates)
    ctx.keyed = 0
    ctx.keySeen = 0
    return space.arbiters.num == 0

cdef void SoftKeyAccepted(SoftContext *ctx, int n) noexcept nogil:
    # Arbiter n, just put on the step's list by the narrow phase: its key.
    cdef cpArbiter *arb = <cpArbiter *>ctx.space.arbiters.arr[n]
    if n != ctx.keyed or arb.count <= 0 or arb.contacts == NULL:
        ctx.keysInNarrow = 0    # (the count's pass, which skips an empty one)
        return
    ctx.contactSource[n] = n
    ctx.keySeen |= SoftCountContact(ctx, arb, n)
    ctx.keyed = n + 1

cdef inline void SoftKeyMoved(SoftContext *ctx, int i, int n) noexcept nogil:
    # On threads: pair i's arbiter, just put on the step's list as arbiter
    # n, was counted by the narrow phase at index i (SoftNarrowPhase): its
    # key moves to n. (n <= i, and the pairs are taken in order, so no key
    # of a later pair is overwritten.)
    cdef cpArray *arbiters = ctx.space.arbiters
    if n != ctx.keyed or arbiters.num != n + 1:
        ctx.keysInNarrow = 0    # (the count's pass)
        return
    if i != n:
        ctx.colorKeys[n] = ctx.colorKeys[i]
        if ctx.estimating:
            ctx.loadHeld[n] = ctx.loadHeld[i]
            ctx.loadOther[n] = ctx.loadOther[i]
            ctx.loadLift[n] = ctx.loadLift[i]
    ctx.contactSource[n] = n
    ctx.keyed = n + 1

cdef inline bint SoftKeysHold(SoftContext *ctx) noexcept nogil:
    # The keys counted in the narrow phase are the step's: they cover its
    # arbiters, and its bodies are the ones gathered. (With sleeping on, no
    # body woke or fell asleep since the step began: anything that does
    # clears cpSoftScratch.threadsClean, which SoftResetArbiters set.)
    cdef cpSpace *space = ctx.space
    return (ctx.keysInNarrow and ctx.keyed == space.arbiters.num
            and ctx.bodyCount == space.dynamicBodies.num + 1
            and (space.sleepTimeThreshold == INFINITY
                 or space.softScratch.threadsClean == space.stamp))

cdef inline cpVect SoftSlotPosition(SoftContext *ctx, int slot, const cpBody *body) noexcept nogil:
    # A body's position as gathered (slot 0's from the body: static or
    # asleep), so that the bodies themselves are not read when preparing.
    if slot != 0:
        return cpv(ctx.motion[slot].px, ctx.motion[slot].py)
    return body.p

cdef inline void SoftPrepareContact(SoftContext *ctx, int n, SoftContact *sc) noexcept nogil:
    # Contact n into *sc: its points' arms, masses, softness, separation and
    # warm start, and Chipmunk's fields of its cpContacts.
    cdef cpArbiter *arb = <cpArbiter *>ctx.space.arbiters.arr[ctx.contactSource[n]]
    cdef SoftColorKey *key = &ctx.colorKeys[n]
    cdef int j
    cdef cpContact *con
    cdef SoftPoint *sp
    cdef SoftBody *a
    cdef SoftBody *b
    cdef SoftSoftness soft
    cdef cpFloat nx, ny, rnA, rnB, rtA, rtB, kN, kT, sep, warm, size, load
    cdef cpFloat maxStiffening, preloadFraction, age, smoothing, least, mean
    cdef cpFloat estimate = 0.0, started, share
    cdef cpFloat pointLoad[2]
    cdef cpVect pa, pb
    cdef const cpFloat *compliance
    cdef SoftState *sa
    cdef SoftState *sb
    sc.arb = arb
    sc.ia = key.ia
    sc.ib = key.ib
    a = &ctx.bodies[sc.ia]
    b = &ctx.bodies[sc.ib]
    sa = &ctx.states[sc.ia]
    sb = &ctx.states[sc.ib]
    sc.count = arb.count if arb.count <= 2 else 2
    sc.dst = arb.contacts
    pa = SoftSlotPosition(ctx, sc.ia, arb.body_a)
    pb = SoftSlotPosition(ctx, sc.ib, arb.body_b)
    size = key.size
    sc.inBlock = key.block
    preloadFraction = SoftPreload(a, b, key.block, &maxStiffening)
    nx = arb.n.x
    ny = arb.n.y
    sc.nx = nx
    sc.ny = ny
    sc.friction = arb.u
    sc.restitution = arb.e
    # Chipmunk adds surface_vr to the relative velocity; only its
    # tangential part is used for friction.
    sc.surfaceT = -arb.surface_vr.x * ny + arb.surface_vr.y * nx
    if (a.m_inv == 0.0 and a.i_inv == 0.0) or (b.m_inv == 0.0 and b.i_inv == 0.0):
        soft = ctx.staticSoft
        compliance = ctx.staticCompliance
    else:
        soft = ctx.contactSoft
        compliance = ctx.contactCompliance
    least = compliance[0] if maxStiffening == 1.0 else compliance[1]
    sc.block = 0
    # Chipmunk skips the warm start of an arbiter's first step.
    warm = 0.0 if arb.state == CP_ARBITER_STATE_FIRST_COLLISION else ctx.warmCoef
    if ctx.loadEstimates != NULL:
        estimate = ctx.loadEstimates[n]
    for j in range(sc.count):
        con = &arb.contacts[j]
        sp = &sc.p[j]
        sp.rAx = con.r1.x
        sp.rAy = con.r1.y
        sp.rBx = con.r2.x
        sp.rBy = con.r2.y
        rnA = sp.rAx * ny - sp.rAy * nx
        rnB = sp.rBx * ny - sp.rBy * nx
        sp.rnA = rnA
        sp.rnB = rnB
        kN = a.m_inv + b.m_inv + a.i_inv * rnA * rnA + b.i_inv * rnB * rnB
        # tangent t = perp(n) = (-ny, nx): cross(r, t) = r . n
        rtA = sp.rAx * nx + sp.rAy * ny
        rtB = sp.rBx * nx + sp.rBy * ny
        sp.rtA = rtA
        sp.rtB = rtB
        kT = a.m_inv + b.m_inv + a.i_inv * rtA * rtA + b.i_inv * rtB * rtB
        sp.normalMass = 1.0 / kN if kN > 0.0 else 0.0
        sp.tangentMass = 1.0 / kT if kT > 0.0 else 0.0
        # The load that sets the point's stiffness follows the impulses
        # slowly (con.jBias, unused by this solver, carries it between
        # steps): following every spike and dip makes a loaded stack
        # breathe and a big pyramid shake itself apart.
        # A young point (con.bias counts its steps) averages the loads it
        # has seen, so a scene that starts at rest is stiff within a few
        # steps instead of sagging while the filter catches up.
        age = con.bias if con.bias >= 0.0 else 0.0
        if age > SOFT_LOAD_AGE:
            age = SOFT_LOAD_AGE
        if age == SOFT_LOAD_AGE:
            smoothing = _mature_smoothing   # (the same number, without the division)
        else:
            smoothing = 1.0 / age if age >= 1.0 else 1.0
            if smoothing < SOFT_LOAD_SMOOTHING:
                smoothing = SOFT_LOAD_SMOOTHING
        load = con.jBias + smoothing * (con.jnAcc * ctx.loadCoef - con.jBias)
        started = 0.0
        if warm == 0.0:
            load = 0.0
            age = 0.0
            # A new contact at rest starts from the weights above it
            # (SoftEstimateLoads; 0 where it holds nothing up).
            started = fabs(estimate) / sc.count
            load = started
        pointLoad[j] = load
        SoftPointSoftness(sp, soft.biasRate, compliance[0], least, load, size, ctx.h)
        # The load as a substep's impulse (jnAcc is the step's).
        sp.preload = load * ctx.h * preloadFraction
        # Separation now, less the anchors' part, which the solver adds
        # back from the bodies' motion within the step.
        sep = ((sp.rBx - sp.rAx + pb.x - pa.x) * nx + (sp.rBy - sp.rAy + pb.y - pa.y) * ny)
        sp.baseSeparation = sep - ((sp.rBx - sp.rAx) * nx + (sp.rBy - sp.rAy) * ny)
        # The approach speed, which restitution reads (SoftApplyRestitution)
        # and an inelastic contact's never is: its bodies' speeds unread.
        sp.relativeVelocity = 0.0
        if arb.e != 0.0:
            sp.relativeVelocity = ((sb.vx - sb.w * sp.rBy - sa.vx + sa.w * sp.rAy) * nx
                                   + (sb.vy + sb.w * sp.rBx - sa.vy - sa.w * sp.rAx) * ny)
        sp.normalImpulse = con.jnAcc * warm if started == 0.0 else started * ctx.h
        sp.tangentImpulse = con.jtAcc * warm
        sp.totalNormal = 0.0
        sp.totalTangent = 0.0
        sp.maxNormalImpulse = 0.0
        # Chipmunk's fields, for Arbiter.total_ke and the like.
        con.nMass = sp.normalMass
        con.tMass = sp.tangentMass
        con.bias = age + 1.0
        con.jBias = load
        con.bounce = sp.relativeVelocity * arb.e
    if estimate > 0.0 and preloadFraction == SOFT_PRELOAD_WEB:
        # A web contact under a tall pile: preloaded with its estimate, not
        # with what it carried (SOFT_ESTIMATE_MIN_CARRY), or a blend of the
        # two (ctx.loadLift), shared between two points as their loads are,
        # less the difference's tilt share (SOFT_PRELOAD_TILT's reason).
        for j in range(sc.count):
            share = 1.0
            if sc.count == 2:
                share = (pointLoad[j] / (pointLoad[0] + pointLoad[1])
                         if pointLoad[0] + pointLoad[1] > 0.0 else 0.5)
                share = 0.5 + SOFT_PRELOAD_TILT * (share - 0.5)
            sc.p[j].preload = (ctx.loadLift[n] * estimate * ctx.h * share
                               + (1.0 - ctx.loadLift[n]) * sc.p[j].preload)
    if sc.count == 2 and preloadFraction == SOFT_PRELOAD_CHAIN and _preload_tilt != 1.0:
        # (SOFT_PRELOAD_TILT.)
        mean = 0.5 * (sc.p[0].preload + sc.p[1].preload)
        sc.p[0].preload = mean + _preload_tilt * (sc.p[0].preload - mean)
        sc.p[1].preload = mean + _preload_tilt * (sc.p[1].preload - mean)

# Above this condition number the two normal rows are nearly dependent (the
# points almost coincide) and are solved as one row at their midpoint
# instead (SoftSolveContact). Box2D 2.x's 1000 is for float32; in double
# precision the 2x2 solve keeps about 8 digits at 1e8. With 1000 the two
# corners of a 1000-gon's bottom edge (0.13 apart under a radius of 20, a
# condition of 12,500) were solved one after the other: the first took the
# whole load, off the centre, and the polygon rolled away from rest.
cdef const cpFloat SOFT_BLOCK_MAX_CONDITION = 1e8
# Box2D 2.x's 1000 where both points lie to one side of a body's centre
# along the tangent (the edge a leaning card stands on, or touches another
# card with): there the footing cannot hold the body up by itself, the two
# rows differ by little while their targets (each point's depth) differ, and
# the block's answer swings the load from one point to the other between
# passes, a turning impulse each time. Solved as one row at their midpoint
# (or one after the other where one is apart), Box2D's card house
# (benchmarks/card_houses.py) stands at friction 0.6 as in Box2D, where it
# fell; a 1000-gon's bottom edge straddles its centre and keeps the block.
cdef const cpFloat SOFT_BLOCK_MAX_CONDITION_ONE_SIDE = 1e3

cdef inline void SoftPrepareBlock(SoftContact *sc, SoftBody *a, SoftBody *b) noexcept nogil:
    # The 2x2 normal mass matrix. Solving both points of a manifold at once
    # (as Box2D 2.x's block solver) keeps a box resting on two corners from
    # being tipped by the order in which they are solved: the sequential
    # order is what lets tall stacks buckle.
    sc.block = SoftBlockMatrix(sc.p[0].rnA, sc.p[0].rnB, sc.p[1].rnA, sc.p[1].rnB, a, b,
                               &sc.k11, &sc.k22, &sc.k12)

cdef inline bint SoftBlockMatrix(cpFloat rnA1, cpFloat rnB1, cpFloat rnA2, cpFloat rnB2,
                                 const SoftBody *a, const SoftBody *b, cpFloat *k11,
                                 cpFloat *k22, cpFloat *k12) noexcept nogil:
    # A two-point manifold's 2x2 normal mass matrix from its points' arms
    # crossed with the normal, and whether its rows are solved together (a
    # regular, well-conditioned matrix). The count's lane kind
    # (SoftContactKind) and the preparation both ask here, so they agree.
    cdef cpFloat mm = a.m_inv + b.m_inv
    cdef cpFloat limit = SOFT_BLOCK_MAX_CONDITION
    k11[0] = mm + a.i_inv * rnA1 * rnA1 + b.i_inv * rnB1 * rnB1
    k22[0] = mm + a.i_inv * rnA2 * rnA2 + b.i_inv * rnB2 * rnB2
    k12[0] = mm + a.i_inv * rnA1 * rnA2 + b.i_inv * rnB1 * rnB2
    if (a.i_inv != 0.0 and rnA1 * rnA2 > 0.0) or (b.i_inv != 0.0 and rnB1 * rnB2 > 0.0):
        limit = SOFT_BLOCK_MAX_CONDITION_ONE_SIDE
    return (k11[0] > 0.0 and k22[0] > 0.0 and
            k11[0] * k11[0] < limit * (k11[0] * k22[0] - k12[0] * k12[0]))

# -- the constraint graph: colours and lanes ------------------------------------------

cdef inline bint SoftMovable(SoftContext *ctx, int slot) noexcept nogil:
    # A body a contact writes to: awake and of finite mass. Immovable ones
    # (static, kinematic, sleeping) are shared freely between contacts of a
    # colour; they are read, never written.
    # (A flag of the gather; slot 0's flags are 0.)
    return (ctx.bodies[slot].flags & SOFT_BODY_MOVABLE) != 0

cdef bint SoftReserveColors(SoftContext *ctx) noexcept nogil:
    # Every buffer SoftColorContacts asks for, as large as it can ask (each
    # colour's last lane of a kind may be part full), so that it allocates
    # nothing when it runs on the pool.
    cdef cpSpace *space = ctx.space
    cdef int n = ctx.contactCount
    cdef int lanes = (n + SOFT_LANES - 1) // SOFT_LANES + 2 * SOFT_GRAPH_COLORS
    if SoftMayGroup(ctx):
        # (Each group's colours may end in a part-full lane of each kind.)
        lanes += SoftMostGroups(ctx) * 2 * SOFT_GRAPH_COLORS
        if SoftReserveGroups(ctx) == NULL:
            return 0
    return (_reserve(space, SOFT_SCRATCH_BITS, ctx.bodyCount, sizeof(uint32_t)) != NULL
            and _reserve(space, SOFT_SCRATCH_COLORS, n, sizeof(int)) != NULL
            and _reserve(space, SOFT_SCRATCH_OVERFLOW, n, sizeof(int)) != NULL
            and _reserve_lines(space, SOFT_SCRATCH_LANES, lanes, sizeof(SoftLanes)) != NULL
            and _reserve(space, SOFT_SCRATCH_LANE_LINKS, lanes, sizeof(SoftLaneLinks)) != NULL)

# What a colouring leaves besides its buffers (lane slots, overflow, lanes'
# empty slots, group lists), for the next step to take it over
# (cpSoftScratch.colorPlan): made from `contacts` keys of `bodies` body
# slots, grouped by `groupSize` (0: not grouping), its lanes in the lanes'
# buffer at `lanesBuffer` (moved, their start on a cache line may shift).
cdef struct SoftColorPlan:
    void *lanesBuffer
    int contacts
    int bodies
    int groupSize
    int overflow
    int groups
    bint innerApart           # SoftContext.innerApart when it was made
    int colorLanes[SOFT_GRAPH_COLORS + 1]
    int colorPairEnd[SOFT_GRAPH_COLORS]

cdef cpSoftScratch _plan_probe
assert sizeof(SoftColorPlan) <= sizeof(_plan_probe.colorPlan), "cpSoftScratch.colorPlan is too small"

# Off only in tests, which check that taking over the last colouring
# changes nothing; and the steps (all spaces) that took it over.
cdef bint _reuse_colors = 1
cdef volatile long _reused_colorings = 0

cdef bint SoftSameColorKeys(const SoftColorKey *a, const SoftColorKey *b, int n) noexcept nogil:
    # Whether n keys are the same in what the colouring reads of them: all
    # but the size (the preparation's, which moves with the shapes' boxes),
    # as three 64-bit words a key.
    cdef const uint64_t *x
    cdef const uint64_t *y
    cdef uint64_t diff = 0
    cdef int i
    for i in range(n):
        x = <const uint64_t *>&a[i]
        y = <const uint64_t *>&b[i]
        diff |= (x[0] ^ y[0]) | (x[1] ^ y[1]) | (x[2] ^ y[2])
    return diff == 0

cdef inline int SoftGroupSize(SoftContext *ctx) noexcept nogil:
    return _group_contacts if SoftMayGroup(ctx) else 0

cdef void SoftKeepColors(SoftContext *ctx) noexcept nogil:
    # This step's colouring, made: its keys kept (the keys' buffer and the
    # kept one swap places: the preparation still reads ctx.colorKeys,
    # which nothing reserves before the next colouring) and its plan.
    cdef cpSoftScratch *scratch = &ctx.space.softScratch
    cdef SoftColorPlan *plan = <SoftColorPlan *>scratch.colorPlan
    cdef void *keys = scratch.buf[SOFT_SCRATCH_KEYS]
    cdef int cap = scratch.cap[SOFT_SCRATCH_KEYS]
    cdef int c
    scratch.buf[SOFT_SCRATCH_KEYS] = scratch.buf[SOFT_SCRATCH_OLD_KEYS]
    scratch.cap[SOFT_SCRATCH_KEYS] = scratch.cap[SOFT_SCRATCH_OLD_KEYS]
    scratch.buf[SOFT_SCRATCH_OLD_KEYS] = keys
    scratch.cap[SOFT_SCRATCH_OLD_KEYS] = cap
    plan.lanesBuffer = scratch.buf[SOFT_SCRATCH_LANES]
    plan.contacts = ctx.contactCount
    plan.bodies = ctx.bodyCount
    plan.groupSize = SoftGroupSize(ctx)
    plan.overflow = ctx.overflowCount
    plan.groups = ctx.groupCount
    plan.innerApart = ctx.innerApart
    if ctx.groupCount == 0:
        # (Grouped, the groups' own lists say where their colours are.)
        for c in range(SOFT_GRAPH_COLORS):
            plan.colorLanes[c] = ctx.colorLanes[c]
            plan.colorPairEnd[c] = ctx.colorPairEnd[c]
    plan.colorLanes[SOFT_GRAPH_COLORS] = ctx.colorLanes[SOFT_GRAPH_COLORS]
    scratch.colorsKnown = 1

cdef bint SoftReuseColors(SoftContext *ctx, int *color) noexcept nogil:
    # Last step's colouring taken over where this step's keys are the same
    # (the colouring is a function of them, the body count and the grouping
    # size): its lane slots (color[], still in their buffer), overflow and
    # lanes (their empty slots still cleared: no pass writes them) and
    # group lists as they are. The bodies' contact counts are counted
    # again. False: colour afresh.
    cdef cpSpace *space = ctx.space
    cdef cpSoftScratch *scratch = &space.softScratch
    cdef SoftColorPlan *plan = <SoftColorPlan *>scratch.colorPlan
    cdef int n = ctx.contactCount
    cdef int i, c, total
    cdef SoftColorKey *key
    if not (_reuse_colors and scratch.colorsKnown and plan.contacts == n
            and plan.bodies == ctx.bodyCount and plan.groupSize == SoftGroupSize(ctx)
            and (plan.groups > 0 or plan.innerApart == SoftInnerApart(ctx))
            and scratch.buf[SOFT_SCRATCH_OLD_KEYS] != NULL
            and SoftSameColorKeys(<SoftColorKey *>scratch.buf[SOFT_SCRATCH_OLD_KEYS],
                                  ctx.colorKeys, n)):
        return 0
    total = plan.colorLanes[SOFT_GRAPH_COLORS]
    # (Their sizes are last step's: the same buffers, not grown.)
    ctx.lanes = <SoftLanes *>_reserve_lines(space, SOFT_SCRATCH_LANES, total, sizeof(SoftLanes))
    ctx.laneLinks = <SoftLaneLinks *>_reserve(space, SOFT_SCRATCH_LANE_LINKS, total,
                                              sizeof(SoftLaneLinks))
    if ctx.lanes == NULL or ctx.laneLinks == NULL or scratch.buf[SOFT_SCRATCH_LANES] != plan.lanesBuffer:
        return 0
    for i in range(n):
        key = &ctx.colorKeys[i]
        ctx.bodies[key.ia].contacts += 1
        ctx.bodies[key.ib].contacts += 1
    ctx.overflowCount = plan.overflow
    tamias_add(&_overflow_total, ctx.overflowCount)
    if plan.groups == 0:
        for c in range(SOFT_GRAPH_COLORS):
            ctx.colorLanes[c] = plan.colorLanes[c]
            ctx.colorPairEnd[c] = plan.colorPairEnd[c]
    else:
        SoftGroupLists(ctx, plan.groups)
    ctx.colorLanes[SOFT_GRAPH_COLORS] = total
    ctx.contactSlots = color
    ctx.groupCount = plan.groups
    tamias_add(&_reused_colorings, 1)
    return 1

# A colour's lanes by class, laid out in the order below: two-point
# manifolds, those inside a web (SoftInnerContact: the extra relax pass
# leaves them out after a step's first substep, so on one thread and in
# contact groups they fill lanes of their own and whole lanes are passed
# over: SoftInnerApart), then one-point ones. The contacts of a colour
# share no movable body, so where a lane puts a contact changes nothing
# but which lanes a pass can skip.
cdef enum:
    SOFT_LANE_POINT = 0           # (= the colouring key's kind)
    SOFT_LANE_PAIR = 1
    SOFT_LANE_INNER_PAIR = 2
    SOFT_LANE_CLASSES = 3
    # SoftFindGroups notes a contact's group and class as group << 2 | class.
    SOFT_GROUP_CLASS_BITS = 2
    SOFT_GROUP_CLASS_SLOTS = 1 << SOFT_GROUP_CLASS_BITS

cdef inline int SoftLaneClassAt(int j) noexcept nogil:
    # The class laid out j-th in a colour: pairs, inner pairs, points.
    return (j + 1) % SOFT_LANE_CLASSES

cdef inline bint SoftInnerApart(SoftContext *ctx) noexcept nogil:
    # Whether the inner contacts get lanes of their own outside contact
    # groups: on one thread. On the pool the lanes keep arbiter order
    # (soft_lane_hold_inner says why); within a group, where a thread keeps
    # the whole group, they go apart too.
    return not ctx.threaded

cdef inline int SoftLaneClass(SoftContext *ctx, const SoftColorKey *key) noexcept nogil:
    # (Once every body's contacts are counted.)
    if (ctx.innerApart and key.kind == SOFT_LANE_PAIR and SoftInnerContact(&ctx.bodies[key.ia])
            and SoftInnerContact(&ctx.bodies[key.ib])):
        return SOFT_LANE_INNER_PAIR
    return key.kind

cdef bint SoftColorContacts(SoftContext *ctx) noexcept nogil:
    # Greedy colouring in arbiter order (so a copy continues alike): each
    # contact takes the first colour that holds neither of its movable
    # bodies; then each colour's contacts are packed SOFT_LANES to a lane,
    # two-point manifolds first, then one-point ones (lanes of one kind).
    # Each body keeps the set of its colours as bits, so the first free
    # colour of a pair is the lowest bit clear in both: no search.
    cdef cpSpace *space = ctx.space
    cdef int n = ctx.contactCount
    cdef int i, j, c, col, a, b, total
    cdef uint32_t *used          # per body slot: the colours it is in
    cdef uint32_t taken, bit
    cdef int *color
    cdef SoftColorKey *key
    cdef SoftLanes *ln
    cdef int counts[SOFT_LANE_CLASSES][SOFT_GRAPH_COLORS]   # [class][colour]
    cdef int fill[SOFT_LANE_CLASSES][SOFT_GRAPH_COLORS]
    cdef int start[SOFT_LANE_CLASSES][SOFT_GRAPH_COLORS]    # first lane of each class
    cdef int kind, lanes, groups
    cdef bint grouping
    cdef int *parent = NULL
    cdef int largest = 1
    used = <uint32_t *>_reserve(space, SOFT_SCRATCH_BITS, ctx.bodyCount, sizeof(uint32_t))
    color = <int *>_reserve(space, SOFT_SCRATCH_COLORS, n, sizeof(int))
    ctx.overflow = <int *>_reserve(space, SOFT_SCRATCH_OVERFLOW, n, sizeof(int))
    if used == NULL or color == NULL or ctx.overflow == NULL:
        return 0
    if SoftReuseColors(ctx, color):
        return 1
    space.softScratch.colorsKnown = 0
    memset(used, 0, <size_t>ctx.bodyCount * sizeof(uint32_t))
    for c in range(SOFT_GRAPH_COLORS):
        for kind in range(SOFT_LANE_CLASSES):
            counts[kind][c] = 0
            fill[kind][c] = 0
    ctx.overflowCount = 0
    ctx.groupCount = 0
    grouping = SoftMayGroup(ctx)
    if grouping:
        parent = SoftReserveGroups(ctx)
        if parent == NULL:
            return 0
    for i in range(n):
        key = &ctx.colorKeys[i]
        if grouping:
            grouping = SoftGroupJoin(parent, parent + ctx.bodyCount, key, &largest)
        # Each body's number of contacts (slot 0's is never read): a
        # contact's load is fully preloaded only where both of its bodies
        # have at most two (SoftPreload, in the preparation after this).
        # Here, on one thread, rather than in the count on the pool, where
        # each was an atomic add.
        ctx.bodies[key.ia].contacts += 1
        ctx.bodies[key.ib].contacts += 1
        col = SOFT_GRAPH_COLORS
        if key.kind >= 0:
            a = key.a
            b = key.b
            # Slot 0 (immovable) stays in no colour. As Box2D: a contact
            # with an immovable body never takes colour 0, so the first
            # colour is solved between movable bodies only.
            taken = used[a] | used[b]
            if a == 0 or b == 0:
                taken |= 1
            taken = ~taken & SOFT_GRAPH_COLOR_MASK
            if taken != 0:
                col = tamias_lowest_bit(taken)
                bit = (<uint32_t>1) << col
                used[a] |= bit
                used[b] |= bit
                used[0] = 0
        color[i] = col
        if col == SOFT_GRAPH_COLORS:
            ctx.overflow[ctx.overflowCount] = i
            ctx.overflowCount += 1
    tamias_add(&_overflow_total, ctx.overflowCount)
    # (Not where one pile holds nearly every body: one group, and the
    # contacts' pass to find it for nothing.)
    if grouping and ctx.overflowCount == 0 and 10 * largest < 9 * (ctx.bodyCount - 1):
        ctx.innerApart = 1
        groups = SoftFindGroups(ctx, parent)
        if groups >= 2:
            if not SoftColorGroups(ctx, color, groups):
                return 0
            SoftKeepColors(ctx)
            return 1
    # (Counted now that every body's contacts are: SoftLaneClass.)
    ctx.innerApart = SoftInnerApart(ctx)
    for i in range(n):
        if color[i] != SOFT_GRAPH_COLORS:
            counts[SoftLaneClass(ctx, &ctx.colorKeys[i])][color[i]] += 1
    total = 0
    for c in range(SOFT_GRAPH_COLORS):
        ctx.colorLanes[c] = total
        for j in range(SOFT_LANE_CLASSES):
            kind = SoftLaneClassAt(j)
            start[kind][c] = total
            total += (counts[kind][c] + SOFT_LANES - 1) // SOFT_LANES
        ctx.colorPairEnd[c] = start[SOFT_LANE_POINT][c]
    ctx.colorLanes[SOFT_GRAPH_COLORS] = total
    ctx.lanes = <SoftLanes *>_reserve_lines(space, SOFT_SCRATCH_LANES, total, sizeof(SoftLanes))
    ctx.laneLinks = <SoftLaneLinks *>_reserve(space, SOFT_SCRATCH_LANE_LINKS, total,
                                              sizeof(SoftLaneLinks))
    if ctx.lanes == NULL or ctx.laneLinks == NULL:
        return 0
    # Which lane slot each contact takes (color[] becomes that, -1 for the
    # overflow), colour by colour in arbiter order; the contacts are
    # prepared into them after, on the pool (SoftPackLanes).
    for i in range(n):
        c = color[i]
        if c == SOFT_GRAPH_COLORS:
            color[i] = -1
            continue
        kind = SoftLaneClass(ctx, &ctx.colorKeys[i])
        color[i] = start[kind][c] * SOFT_LANES + fill[kind][c]
        fill[kind][c] += 1
    ctx.contactSlots = color
    # The empty slots of each colour's last lane of a kind (they take no
    # impulse). (Each lane's kind is written by the contact in its slot 0.)
    for c in range(SOFT_GRAPH_COLORS):
        for kind in range(SOFT_LANE_CLASSES):
            lanes = (counts[kind][c] + SOFT_LANES - 1) // SOFT_LANES
            for i in range(counts[kind][c], lanes * SOFT_LANES):
                SoftLanesClear(&ctx.lanes[start[kind][c] + i // SOFT_LANES],
                               &ctx.laneLinks[start[kind][c] + i // SOFT_LANES], i % SOFT_LANES)
    SoftKeepColors(ctx)
    return 1

# -- contact groups: the substeps of a part of the scene at a time ---------------------
# Contacts that share no movable body, directly or through others, do not
# act on each other within a step: their substeps can run one group after
# the other instead of all in step, with the same operations on each
# contact and body in the same order, so the same bits. A scene of many
# separate piles whose lanes do not fit in a core's cache (Box2D's
# many_pyramids: 15 MB) then has each group prepare its lanes, run its 16
# passes over them and store their impulses while they stay in the cache,
# where all in step every pass streamed all the lanes. On two threads each
# takes whole groups, with no wait between the passes. Only where nothing
# else runs between the passes: no joints, no contact solved outside the
# colours or in a mass-ratio block, no Python velocity or position
# function, no kinematic body in a contact (it moves in every substep and
# may touch several piles).

cdef bint SoftMayGroup(SoftContext *ctx) noexcept nogil:
    # (The colouring finds the rest: no kinematic body in a contact, and
    # none in the overflow.)
    return (_group_contacts > 0 and ctx.contactCount >= 2 * _group_contacts
            and ctx.blockBodyCount == 0
            and ctx.space.constraints.num == 0 and not ctx.livePositions
            and not ctx.serialVelocities and not ctx.serialPositions)

cdef inline int SoftMostGroups(SoftContext *ctx) noexcept nogil:
    # (SoftFindGroups starts a group after _group_contacts contacts at least.)
    return ctx.contactCount // _group_contacts + 2

cdef int *SoftReserveGroups(SoftContext *ctx) noexcept nogil:
    # The groups' buffer (NULL: out of memory), each body slot its own
    # root. From its start: each slot's parent, its root's group, each
    # contact's group and kind, then SoftColorGroups' lists.
    cdef int n = ctx.contactCount
    cdef int bodies = ctx.bodyCount
    cdef int most = SoftMostGroups(ctx)
    cdef int i
    cdef int *parent = <int *>_reserve(ctx.space, SOFT_SCRATCH_GROUPS,
                                       4 * bodies + 2 * n + 2 * (most + 2)
                                       + most * ((3 + SOFT_GROUP_CLASS_SLOTS) * SOFT_GRAPH_COLORS + 1),
                                       sizeof(int))
    if parent != NULL:
        for i in range(bodies):
            parent[i] = i
            parent[bodies + i] = 1      # (its component's bodies, while joining)
    return parent

cdef inline bint SoftGroupJoin(int *parent, int *size, const SoftColorKey *key,
                               int *largest) noexcept nogil:
    # Contact key's bodies into one component (the smaller under the
    # larger), the largest component's size kept; 0 where the contacts
    # cannot be grouped (a kinematic body, or none movable).
    cdef int a, b
    if (key.ia != 0 and key.a == 0) or (key.ib != 0 and key.b == 0) or (key.a == 0 and key.b == 0):
        return 0
    if key.a != 0 and key.b != 0:
        a = SoftUnionRoot(parent, key.a)
        b = SoftUnionRoot(parent, key.b)
        if a != b:
            if size[a] < size[b]:
                a, b = b, a
            parent[b] = a
            size[a] += size[b]
            if size[a] > largest[0]:
                largest[0] = size[a]
    return 1

cdef int SoftFindGroups(SoftContext *ctx, int *parent) noexcept nogil:
    # The components the colouring joined (SoftGroupJoin) put in groups of
    # about _group_contacts contacts, in arbiter order; each contact's
    # group and lane class noted (group * SOFT_GROUP_CLASS_SLOTS + class).
    # Returns the number of groups.
    cdef int n = ctx.contactCount
    cdef int *rootGroup = parent + ctx.bodyCount
    cdef int *contactGroup = rootGroup + ctx.bodyCount
    cdef SoftColorKey *key
    cdef int i, r, current = -1, currentContacts = 0
    for i in range(ctx.bodyCount):
        rootGroup[i] = -1
    for i in range(n):
        key = &ctx.colorKeys[i]
        r = SoftUnionRoot(parent, key.a if key.a != 0 else key.b)
        if rootGroup[r] < 0:
            if current < 0 or currentContacts >= _group_contacts:
                current += 1
                currentContacts = 0
            rootGroup[r] = current
        if rootGroup[r] == current:
            currentContacts += 1
        contactGroup[i] = rootGroup[r] * SOFT_GROUP_CLASS_SLOTS + SoftLaneClass(ctx, key)
    return current + 1

cdef void SoftSortByKey(const int *key, int shift, int first, int n, int buckets, int *start,
                        int *order) noexcept nogil:
    # Items first to n - 1 listed in order[] by their bucket, key[i] >> shift
    # (0 to buckets - 1), each bucket's in item order (a counting sort):
    # bucket b is order[start[b]:start[b + 1]].
    cdef int i, b
    for b in range(buckets + 1):
        start[b] = 0
    for i in range(first, n):
        start[(key[i] >> shift) + 1] += 1
    for b in range(buckets):
        start[b + 1] += start[b]
    for i in range(first, n):
        b = key[i] >> shift
        order[start[b]] = i
        start[b] += 1
    for b in range(buckets, 0, -1):
        start[b] = start[b - 1]
    start[0] = 0

cdef void SoftGroupLists(SoftContext *ctx, int groups) noexcept nogil:
    # Where SoftColorGroups leaves the groups' lists in the groups' buffer
    # (after the union-find's parents and roots and the contacts' groups;
    # the contacts' lists after its counts of each group's colours).
    cdef int n = ctx.contactCount
    cdef int bodies = ctx.bodyCount
    cdef int *bodyList = <int *>ctx.space.softScratch.buf[SOFT_SCRATCH_GROUPS] + 2 * bodies + n
    cdef int *bodyStart = bodyList + bodies
    cdef int *lanesOf = bodyStart + (groups + 2)
    cdef int *pairEnd = lanesOf + groups * (SOFT_GRAPH_COLORS + 1)
    cdef int *contactList = (pairEnd + groups * SOFT_GRAPH_COLORS
                             + groups * SOFT_GROUP_CLASS_SLOTS * SOFT_GRAPH_COLORS)
    ctx.groupLanes = lanesOf
    ctx.groupPairEnd = pairEnd
    ctx.groupBodies = bodyList
    ctx.groupBodyStart = bodyStart
    ctx.groupContacts = contactList
    ctx.groupContactStart = contactList + n

cdef bint SoftColorGroups(SoftContext *ctx, int *color, int groups) noexcept nogil:
    # SoftColorContacts' lanes laid out group by group (each group's
    # colours, two-point lanes first), and its lane slots given in arbiter
    # order; the bodies listed group by group. color[] holds each contact's
    # colour (none is in the overflow) and becomes its lane slot.
    cdef int n = ctx.contactCount
    cdef int bodies = ctx.bodyCount
    cdef int *parent = <int *>ctx.space.softScratch.buf[SOFT_SCRATCH_GROUPS]
    cdef int *rootGroup = parent + bodies
    cdef int *contactGroup = rootGroup + bodies
    cdef int *bodyList
    cdef int *bodyStart
    cdef int *lanesOf
    cdef int *pairEnd
    cdef int *next                  # [group][class][colour]
    cdef int *contactList
    cdef int *contactStart
    cdef int *bodyGroup
    cdef int i, j, g, c, kind, idx, total, count, lanes, slot
    SoftGroupLists(ctx, groups)
    bodyList = ctx.groupBodies
    bodyStart = ctx.groupBodyStart
    lanesOf = ctx.groupLanes
    pairEnd = ctx.groupPairEnd
    next = pairEnd + groups * SOFT_GRAPH_COLORS
    contactList = ctx.groupContacts
    contactStart = ctx.groupContactStart
    bodyGroup = contactStart + (groups + 1)
    memset(next, 0, <size_t>groups * SOFT_GROUP_CLASS_SLOTS * SOFT_GRAPH_COLORS * sizeof(int))
    for i in range(n):
        next[contactGroup[i] * SOFT_GRAPH_COLORS + color[i]] += 1
    total = 0
    for idx in range(groups * SOFT_GROUP_CLASS_SLOTS * SOFT_GRAPH_COLORS):
        total += (next[idx] + SOFT_LANES - 1) // SOFT_LANES
    ctx.lanes = <SoftLanes *>_reserve_lines(ctx.space, SOFT_SCRATCH_LANES, total, sizeof(SoftLanes))
    ctx.laneLinks = <SoftLaneLinks *>_reserve(ctx.space, SOFT_SCRATCH_LANE_LINKS, total,
                                              sizeof(SoftLaneLinks))
    if ctx.lanes == NULL or ctx.laneLinks == NULL:
        return 0
    # Each (group, colour, kind)'s first slot in next[], its empty slots
    # cleared (SoftColorContacts' reason).
    total = 0
    for g in range(groups):
        for c in range(SOFT_GRAPH_COLORS):
            lanesOf[g * (SOFT_GRAPH_COLORS + 1) + c] = total
            for j in range(SOFT_LANE_CLASSES):
                kind = SoftLaneClassAt(j)
                if kind == SOFT_LANE_POINT:
                    pairEnd[g * SOFT_GRAPH_COLORS + c] = total
                idx = (g * SOFT_GROUP_CLASS_SLOTS + kind) * SOFT_GRAPH_COLORS + c
                count = next[idx]
                lanes = (count + SOFT_LANES - 1) // SOFT_LANES
                for slot in range(count, lanes * SOFT_LANES):
                    SoftLanesClear(&ctx.lanes[total + slot // SOFT_LANES],
                                   &ctx.laneLinks[total + slot // SOFT_LANES], slot % SOFT_LANES)
                next[idx] = total * SOFT_LANES
                total += lanes
        lanesOf[g * (SOFT_GRAPH_COLORS + 1) + SOFT_GRAPH_COLORS] = total
    ctx.colorLanes[SOFT_GRAPH_COLORS] = total
    for i in range(n):
        idx = contactGroup[i] * SOFT_GRAPH_COLORS + color[i]
        color[i] = next[idx]
        next[idx] += 1
    ctx.contactSlots = color
    # The contacts by group, for each group to prepare its own into its
    # lanes (SoftSubstepGroup); the bodies by group, the last list
    # (`groups`) the bodies in no contact.
    SoftSortByKey(contactGroup, SOFT_GROUP_CLASS_BITS, 0, n, groups, contactStart, contactList)
    for i in range(1, bodies):
        g = rootGroup[SoftUnionRoot(parent, i)]
        bodyGroup[i] = g if g >= 0 else groups
    SoftSortByKey(bodyGroup, 0, 1, bodies, groups + 1, bodyStart, bodyList)
    ctx.groupCount = groups
    return 1

cdef inline bint SoftGroupsFinish(SoftContext *ctx) noexcept nogil:
    # Whether each group also finishes the step for its contacts and bodies:
    # where no contact is elastic (restitution, after every group's
    # substeps, reads them all).
    return tamias_load(&ctx.elastic) == 0

cdef inline void SoftGroupPass(SoftContext *ctx, const int *lanes, const int *ends,
                               bint useBias, bint accumulate, bint trackMax,
                               bint skipInner) noexcept nogil:
    # A biased or relax pass over a group's colours, colour c's lanes from
    # lanes[c] to ends[c] (SoftSolve's and SoftRelax's SoftLanesSolve).
    cdef int c
    for c in range(SOFT_GRAPH_COLORS):
        SoftLanesSolve(&ctx.lanes[lanes[c]], &ctx.laneLinks[lanes[c]], ends[c] - lanes[c], ctx.states,
                       &ctx.laneBiasRates, ctx.inv_h, ctx.pushOut, useBias, accumulate, trackMax,
                       ctx.fetchAhead, skipInner)

cdef void SoftSubstepGroup(SoftContext *ctx, int g, bint marks) noexcept nogil:
    # Group g's substeps: cpSoftStep's loop without joints over the group's
    # bodies and lanes, each pass as SoftWarmStart, SoftSolve and SoftRelax
    # make it (their overflow and blocks are empty here), then, where
    # SoftGroupsFinish, its part of the step's finish. g == groupCount: the
    # bodies in no contact. marks: the stage profile's, on one thread.
    cdef const int *lanes = NULL
    cdef const int *pairEnd = NULL
    cdef int first = ctx.groupBodyStart[g]
    cdef int end = ctx.groupBodyStart[g + 1]
    cdef bint contacts = g < ctx.groupCount
    cdef bint trackMax = tamias_load(&ctx.elastic) != 0
    cdef int k, r, c, i
    if contacts:
        lanes = &ctx.groupLanes[g * (SOFT_GRAPH_COLORS + 1)]
        pairEnd = &ctx.groupPairEnd[g * SOFT_GRAPH_COLORS]
        # Its contacts prepared into its lanes here, not with all the
        # others' (SoftPrepareLanes): the first pass finds them in cache.
        SoftPackContacts(ctx, ctx.groupContacts, ctx.groupContactStart[g],
                         ctx.groupContactStart[g + 1])
        if marks:
            SoftProfileMark(SOFT_STAGE_PREPARE)
    for k in range(ctx.substeps):
        for i in range(first, end):
            SoftIntegrateVelocity(ctx, ctx.groupBodies[i], k == ctx.substeps - 1)
        if marks:
            SoftProfileMark(SOFT_STAGE_INTEGRATE)
        if contacts:
            for c in range(SOFT_GRAPH_COLORS):
                SoftLanesWarmStart(&ctx.lanes[lanes[c]], lanes[c + 1] - lanes[c], ctx.states,
                                   ctx.fetchAhead)
            if marks:
                SoftProfileMark(SOFT_STAGE_WARM_START)
            SoftGroupPass(ctx, lanes, lanes + 1, 1, 0, trackMax, 0)
            if marks:
                SoftProfileMark(SOFT_STAGE_SOLVE)
        for i in range(first, end):
            SoftIntegratePosition(ctx, ctx.groupBodies[i])
        if marks:
            SoftProfileMark(SOFT_STAGE_INTEGRATE)
        if contacts:
            for r in range(SOFT_RELAX_ITERATIONS - 1):
                SoftGroupPass(ctx, lanes, pairEnd, 0, 0, trackMax, SoftRelaxSkipsInner(ctx, k))
            SoftGroupPass(ctx, lanes, lanes + 1, 0, 1, trackMax, 0)
            if marks:
                SoftProfileMark(SOFT_STAGE_RELAX)
    if SoftGroupsFinish(ctx):
        # The step's impulses into the arbiters and the bodies written back
        # while the group's lanes and states are in cache (cpSoftStep's
        # finish, group by group: each writes its own contacts and bodies).
        if contacts:
            SoftUnpackLanes(ctx, lanes[0], lanes[SOFT_GRAPH_COLORS], 1)
        SoftFinishBodies(ctx, ctx.groupBodies, first, end)
        if marks:
            SoftProfileMark(SOFT_STAGE_FINISH)

cdef void SoftSubstepGroups(SoftContext *ctx) noexcept nogil:
    # Every group's substeps, then those of the bodies in no contact: on
    # two threads each takes whole groups (the profile counts all of it as
    # relax passes).
    cdef int g
    tamias_add(&_grouped_steps, 1)
    if ctx.threaded:
        SoftRun(ctx, SOFT_TASK_GROUPS, 0, ctx.groupCount + 1, 0)
        SoftProfileMark(SOFT_STAGE_RELAX)
        return
    for g in range(ctx.groupCount + 1):
        SoftSubstepGroup(ctx, g, 1)

cdef void SoftPrepareLanes(SoftContext *ctx) noexcept nogil:
    # The coloured contacts prepared straight into their lanes (on the
    # pool), the others into ctx.contacts, which keeps a coloured one only
    # where restitution will read it (SoftPackLanes).
    cdef int i
    cdef SoftContact *sc
    # (The two bias rates SoftPrepareContact gives, by the lanes' sides.)
    SoftLaneBiasRatesFill(&ctx.laneBiasRates, ctx.contactSoft.biasRate, ctx.staticSoft.biasRate)
    if ctx.groupCount == 0:
        SoftRun(ctx, SOFT_TASK_PACK, 0, ctx.contactCount, 0)
    # (Else each group prepares its own before its substeps: SoftSubstepGroup.)
    for i in range(ctx.overflowCount):
        sc = &ctx.contacts[ctx.overflow[i]]
        SoftPrepareContact(ctx, ctx.overflow[i], sc)
        if sc.count == 2:
            # Only the one-by-one solve (SoftSolveContact) reads the 2x2
            # matrix: a lane works it out from the arms, and the count's
            # SoftContactKind has already decided the lane's kind.
            SoftPrepareBlock(sc, &ctx.bodies[sc.ia], &ctx.bodies[sc.ib])

cdef inline void SoftFetchSlot(SoftContext *ctx, int i) noexcept nogil:
    # What the preparation reads of a body slot (in a large scene the
    # arrays of the step's bodies are beyond the core's cache).
    tamias_prefetch(&ctx.bodies[i])
    tamias_prefetch(&ctx.states[i])
    tamias_prefetch(&ctx.motion[i].px)

cdef inline int SoftNth(const int *order, int i) noexcept nogil:
    # Item i of a pass over a list (a group's), or i itself without one.
    return order[i] if order != NULL else i

cdef void SoftPackLanes(SoftContext *ctx, int begin, int end) noexcept nogil:
    SoftPackContacts(ctx, NULL, begin, end)

cdef void SoftPackContacts(SoftContext *ctx, const int *order, int begin, int end) noexcept nogil:
    # Contacts begin to end (or order[begin:end], a group's, where order is
    # not NULL), in arbiter order, each prepared and written into its lane
    # slot (contactSlots). The SoftContact goes through the
    # stack unless restitution reads it after the substeps: written to
    # ctx.contacts and read back, it was most of the memory the preparation
    # moved. In arbiter order the arbiters, their contacts and bodies are
    # read in the order they lie in memory, and the lanes being filled are
    # few (about two per colour), so they stay in cache until full.
    cdef int i, n, slot, k
    cdef cpArbiter *arb
    cdef cpArray *arbiters = ctx.space.arbiters
    cdef SoftContact local
    cdef SoftContact *sc
    cdef bint keep = tamias_load(&ctx.elastic) != 0
    for i in range(begin, end):
        if ctx.fetchAhead and i + SOFT_ARBITER_PREFETCH < end:
            # (Up to its state: the handlers and stamps after it are not
            # read.)
            arb = <cpArbiter *>arbiters.arr[ctx.contactSource[SoftNth(order, i + SOFT_ARBITER_PREFETCH)]]
            SoftFetchLines(arb, <char *>&arb.state - <char *>arb + sizeof(arb.state))
        if ctx.fetchAhead and i + SOFT_ARBITER_PREFETCH // 2 < end:
            # Its contacts, now that the arbiter itself has been fetched,
            # and its bodies' slots in the arrays of the step's bodies.
            n = SoftNth(order, i + SOFT_ARBITER_PREFETCH // 2)
            arb = <cpArbiter *>arbiters.arr[ctx.contactSource[n]]
            SoftFetchLines(arb.contacts, arb.count * sizeof(cpContact))
            SoftFetchSlot(ctx, ctx.colorKeys[n].ia)
            SoftFetchSlot(ctx, ctx.colorKeys[n].ib)
        if ctx.fetchAhead and i + SOFT_ARBITER_PREFETCH < end:
            # A lane about to take its first contact: all of its lines (a
            # lane is filled over a stretch of contacts, but each contact
            # writes to every line of it), for writing.
            slot = ctx.contactSlots[SoftNth(order, i + SOFT_ARBITER_PREFETCH)]
            if slot >= 0 and slot % SOFT_LANES == 0:
                for k in range(0, sizeof(SoftLanes), 64):
                    tamias_prefetch_write(<char *>&ctx.lanes[slot // SOFT_LANES] + k)
                tamias_prefetch_write(&ctx.laneLinks[slot // SOFT_LANES])
        n = SoftNth(order, i)
        slot = ctx.contactSlots[n]
        if slot < 0:
            continue
        sc = &ctx.contacts[n] if keep else &local
        SoftPrepareContact(ctx, n, sc)
        ctx.lanes[slot // SOFT_LANES].inner[slot % SOFT_LANES] = (
            SoftInnerContact(&ctx.bodies[sc.ia]) and SoftInnerContact(&ctx.bodies[sc.ib]))
        if slot % SOFT_LANES == 0:
            # (Slot 0 of a lane is never empty: its contact says the kind.)
            ctx.lanes[slot // SOFT_LANES].points = ctx.colorKeys[n].kind + 1
        SoftPackLane(ctx, &ctx.lanes[slot // SOFT_LANES], &ctx.laneLinks[slot // SOFT_LANES],
                     slot % SOFT_LANES, n, sc)

cdef void SoftPackLane(SoftContext *ctx, SoftLanes *ln, SoftLaneLinks *links, int k,
                       int i, const SoftContact *sc) noexcept nogil:
    cdef SoftBody *a = &ctx.bodies[sc.ia]
    cdef SoftBody *b = &ctx.bodies[sc.ib]
    cdef const SoftPoint *sp
    cdef int j
    # (As byte offsets: SOFT_AT in _soft_lanes.h.)
    ln.ia[k] = sc.ia * <int>sizeof(SoftState)
    ln.ib[k] = sc.ib * <int>sizeof(SoftState)
    # (The count found which bodies are movable: SoftCountContact.)
    ln.wa[k] = ctx.colorKeys[i].a != 0
    ln.wb[k] = ctx.colorKeys[i].b != 0
    links.src[k] = i
    links.dst[k] = sc.dst
    ln.iA[k] = a.i_inv
    ln.iB[k] = b.i_inv
    ln.nx[k] = sc.nx
    ln.ny[k] = sc.ny
    ln.friction[k] = sc.friction
    ln.surfaceT[k] = sc.surfaceT
    if sc.count == 1:
        # The one-row solve's effective mass (a two-point lane works its
        # 2x2 matrix out from the arms).
        ln.k11[k] = 1.0 / sc.p[0].normalMass
    for j in range(sc.count):
        sp = &sc.p[j]
        ln.rAx[j][k] = sp.rAx
        ln.rAy[j][k] = sp.rAy
        ln.rBx[j][k] = sp.rBx
        ln.rBy[j][k] = sp.rBy
        ln.base[j][k] = sp.baseSeparation
        ln.compliance[j][k] = sp.compliance
        ln.preload[j][k] = sp.preload
        ln.normalImpulse[j][k] = sp.normalImpulse
        ln.tangentImpulse[j][k] = sp.tangentImpulse
        links.maxNormalImpulse[j][k] = 0.0
        ln.totalNormal[j][k] = 0.0
        ln.totalTangent[j][k] = 0.0

cdef inline void SoftApplyImpulse(SoftContext *ctx, SoftContact *sc, SoftPoint *sp,
                                  cpFloat px, cpFloat py) noexcept nogil:
    # The impulse (px, py) at point sp, on B and against A (slot 0, the
    # immovable body, is never written: contacts on other threads read it).
    cdef SoftBody *a = &ctx.bodies[sc.ia]
    cdef SoftBody *b = &ctx.bodies[sc.ib]
    cdef SoftState *sa = &ctx.states[sc.ia]
    cdef SoftState *sb = &ctx.states[sc.ib]
    if sc.ia != 0:
        sa.vx -= a.m_inv * px
        sa.vy -= a.m_inv * py
        sa.w -= a.i_inv * (sp.rAx * py - sp.rAy * px)
    if sc.ib != 0:
        sb.vx += b.m_inv * px
        sb.vy += b.m_inv * py
        sb.w += b.i_inv * (sp.rBx * py - sp.rBy * px)

cdef void SoftWarmStart(SoftContext *ctx) noexcept nogil:
    # The coloured contacts lane by lane, then the overflow one by one.
    cdef int i, j
    cdef SoftContact *sc
    cdef SoftPoint *sp
    cdef cpFloat px, py, nx, ny
    for i in range(SOFT_GRAPH_COLORS):
        SoftRun(ctx, SOFT_TASK_WARM_START, ctx.colorLanes[i], ctx.colorLanes[i + 1], 0)
    for i in range(ctx.overflowCount):
        sc = &ctx.contacts[ctx.overflow[i]]
        nx = sc.nx
        ny = sc.ny
        for j in range(sc.count):
            sp = &sc.p[j]
            # P = normalImpulse n + tangentImpulse perp(n)
            px = sp.normalImpulse * nx - sp.tangentImpulse * ny
            py = sp.normalImpulse * ny + sp.tangentImpulse * nx
            SoftApplyImpulse(ctx, sc, sp, px, py)

cdef void SoftSolve(SoftContext *ctx, bint useBias) noexcept nogil:
    # One Gauss-Seidel pass over the contacts: with useBias the soft,
    # biased solve; without it the rigid relax pass, which also solves
    # friction. The coloured contacts lane by lane (_soft_lanes_kernels.h,
    # the same arithmetic as below), then the overflow one by one.
    cdef int i
    for i in range(SOFT_GRAPH_COLORS):
        SoftRun(ctx, SOFT_TASK_SOLVE, ctx.colorLanes[i], ctx.colorLanes[i + 1], useBias)
    SoftSolveOverflow(ctx, useBias)

cdef void SoftSolveOverflow(SoftContext *ctx, bint useBias) noexcept nogil:
    # The overflow one by one, then the blocks (SoftSolveBlock).
    cdef int i
    cdef SoftContact *sc
    for i in range(ctx.overflowCount):
        sc = &ctx.contacts[ctx.overflow[i]]
        if not sc.inBlock:
            SoftSolveContact(ctx, sc, useBias)
    for i in range(ctx.blockBodyCount):
        if not SoftSolveBlock(ctx, i, useBias):
            # Too many rows, or no solution found: one by one.
            SoftEachBlockContact(ctx, ctx.blockBodies[i], useBias)

# A block's points: each point of each of its contacts. Its rows are their
# normal rows, then (in the relax passes) their tangent rows.
cdef struct SoftBlockRows:
    int n                     # points
    SoftContact *contact[SOFT_BLOCK_ROWS]
    int point[SOFT_BLOCK_ROWS]

cdef inline bint SoftBlockGather(SoftContext *ctx, int root, SoftBlockRows *rows) noexcept nogil:
    # Block root's points; false beyond SOFT_BLOCK_ROWS rows (a normal and a
    # tangent row per point).
    cdef int c = ctx.blockHead[root]
    cdef int j
    cdef SoftContact *sc
    rows.n = 0
    while c >= 0:
        sc = &ctx.contacts[c]
        if 2 * (rows.n + sc.count) > SOFT_BLOCK_ROWS:
            return 0
        for j in range(sc.count):
            rows.contact[rows.n] = sc
            rows.point[rows.n] = j
            rows.n += 1
        c = ctx.blockNext[c]
    return 1

cdef inline void SoftBlockJacobian(const SoftBlockRows *rows, int r, cpFloat *dx, cpFloat *dy,
                                   cpFloat *armA, cpFloat *armB) noexcept nogil:
    # Row r's direction and arms: a normal row n and cross(r, n), a tangent
    # row (r >= n points) t = perp(n) and cross(r, t) = r . n; on B +J, on
    # A -J.
    cdef bint tangent = r >= rows.n
    cdef const SoftContact *sc = rows.contact[r - rows.n if tangent else r]
    cdef const SoftPoint *sp = &sc.p[rows.point[r - rows.n if tangent else r]]
    if tangent:
        dx[0] = -sc.ny
        dy[0] = sc.nx
        armA[0] = sp.rtA
        armB[0] = sp.rtB
    else:
        dx[0] = sc.nx
        dy[0] = sc.ny
        armA[0] = sp.rnA
        armB[0] = sp.rnB

cdef inline const SoftContact *SoftBlockContact(const SoftBlockRows *rows, int r) noexcept nogil:
    return rows.contact[r - rows.n if r >= rows.n else r]

cdef void SoftBlockDelassus(SoftContext *ctx, const SoftBlockRows *rows, int m,
                            cpFloat M[][SOFT_BLOCK_ROWS]) noexcept nogil:
    # M = J W J' over the first m rows (W the bodies' inverse masses and
    # inertias): rows r and t meet where they share a movable body.
    cdef int r, t, u, v, slot
    cdef int body[2][2]
    cdef cpFloat dx[2]
    cdef cpFloat dy[2]
    cdef cpFloat arm[2][2]
    cdef cpFloat k, sign
    cdef const SoftBody *bd
    for r in range(m):
        SoftBlockJacobian(rows, r, &dx[0], &dy[0], &arm[0][0], &arm[0][1])
        body[0][0] = SoftBlockContact(rows, r).ia
        body[0][1] = SoftBlockContact(rows, r).ib
        for t in range(r + 1):
            SoftBlockJacobian(rows, t, &dx[1], &dy[1], &arm[1][0], &arm[1][1])
            body[1][0] = SoftBlockContact(rows, t).ia
            body[1][1] = SoftBlockContact(rows, t).ib
            k = 0.0
            for u in range(2):
                for v in range(2):
                    slot = body[0][u]
                    if slot == 0 or slot != body[1][v]:
                        continue
                    bd = &ctx.bodies[slot]
                    sign = 1.0 if u == v else -1.0
                    k += sign * (bd.m_inv * (dx[0] * dx[1] + dy[0] * dy[1])
                                 + bd.i_inv * arm[0][u] * arm[1][v])
            M[r][t] = k
            M[t][r] = k

cdef inline cpFloat SoftBlockSpeed(SoftContext *ctx, const SoftBlockRows *rows,
                                   int r) noexcept nogil:
    # B's speed against A at row r's point, along its direction.
    cdef cpFloat dx, dy, armA, armB
    cdef const SoftContact *sc = SoftBlockContact(rows, r)
    cdef const SoftState *sa = &ctx.states[sc.ia]
    cdef const SoftState *sb = &ctx.states[sc.ib]
    SoftBlockJacobian(rows, r, &dx, &dy, &armA, &armB)
    return ((sb.vx - sa.vx) * dx + (sb.vy - sa.vy) * dy) + sb.w * armB - sa.w * armA

cdef void SoftBlockApply(SoftContext *ctx, const SoftBlockRows *rows, int m,
                         const cpFloat *d) noexcept nogil:
    # The impulses d along the first m rows on the bodies (slot 0 never
    # written).
    cdef int r
    cdef cpFloat dx, dy, armA, armB
    cdef const SoftContact *sc
    cdef SoftState *st
    cdef const SoftBody *bd
    for r in range(m):
        sc = SoftBlockContact(rows, r)
        SoftBlockJacobian(rows, r, &dx, &dy, &armA, &armB)
        if sc.ia != 0:
            bd = &ctx.bodies[sc.ia]
            st = &ctx.states[sc.ia]
            st.vx -= bd.m_inv * d[r] * dx
            st.vy -= bd.m_inv * d[r] * dy
            st.w -= bd.i_inv * d[r] * armA
        if sc.ib != 0:
            bd = &ctx.bodies[sc.ib]
            st = &ctx.states[sc.ib]
            st.vx += bd.m_inv * d[r] * dx
            st.vy += bd.m_inv * d[r] * dy
            st.w += bd.i_inv * d[r] * armB

cdef bint SoftSolveBlock(SoftContext *ctx, int block, bint useBias) noexcept nogil:
    # All of a block's contact rows at once: the linear complementarity
    # problem w = M x + q over their accumulated impulses x, with
    # M = K + diag(k_r gamma_r), K = J W J', q = v + bias - K x0
    # - diag(k_r gamma_r) held (a soft row's compliance on its diagonal, as
    # in SoftSolveContact's 2x2 case), normal impulses pushing only, each
    # tangent one within its friction cone. Solved exactly by principal
    # pivoting (SoftBlockPivot), the cones from the normal impulses found
    # the time before. One row after the other takes about the mass ratio
    # in passes to carry a heavy body's load through a light one (or to
    # balance the couple that friction above and below puts on it); this
    # takes one. The soft pass has normal rows only; the relax passes add
    # the tangent rows. K (and each normal row's effective k) is made by
    # the step's first pass of the block (SoftBlockCache). False, with
    # nothing changed, beyond SOFT_BLOCK_ROWS rows or where no solution is
    # found.
    cdef SoftBlockCache *cache = &ctx.blockCache[block]
    cdef SoftBlockRows rows
    cdef cpFloat q[SOFT_BLOCK_ROWS]
    cdef cpFloat x[SOFT_BLOCK_ROWS]
    cdef cpFloat x0[SOFT_BLOCK_ROWS]
    cdef cpFloat lo[SOFT_BLOCK_ROWS]
    cdef cpFloat hi[SOFT_BLOCK_ROWS]
    cdef cpFloat extra[SOFT_BLOCK_ROWS]   # added to K's diagonal in this pass
    cdef cpFloat bias, gamma, held, scale, cone
    cdef int r, t, n, m, rounds, round
    cdef bint settled
    cdef const SoftContact *sc
    cdef SoftPoint *sp
    if not SoftBlockGather(ctx, ctx.blockBodies[block], &rows):
        return 0
    n = rows.n
    m = n if useBias else 2 * n
    if not cache.built:
        SoftBlockDelassus(ctx, &rows, 2 * n, cache.K)
        # Rows can depend on each other: a face contact's two tangent rows
        # are the same row (cross(r, t) = r . n is the face's offset for
        # both points), and a light body wedged among others has more
        # normal rows than it can move in, or two nearly coincident points.
        # A relative 1e-9 on the diagonal (on the change of impulse: M
        # multiplies x - x0) makes the system regular and shares such rows'
        # impulse instead of letting round-off split it into huge opposite
        # parts.
        scale = 0.0
        for r in range(2 * n):
            scale = fmax(scale, cache.K[r][r])
        for r in range(2 * n):
            cache.K[r][r] += 1e-9 * scale
        # Each normal row's softness acts on its effective mass within the
        # block, 1 / (K^-1)_rr, the mass it moves while the other rows hold
        # (under a heavy body on a light one on the ground, about the heavy
        # body's), not on its own pair's (about the light body's: a spring
        # that soft lets the heavy body sink the mass ratio times deeper).
        if not SoftBlockEffectiveK(cache.K, n, cache.keff):
            for r in range(n):
                cache.keff[r] = cache.K[r][r]
        cache.factorCount[0] = -1
        cache.factorCount[1] = -1
        cache.stateKept[0] = 0
        cache.stateKept[1] = 0
        cache.built = 1
    for r in range(n):
        sc = rows.contact[r]
        sp = &rows.contact[r].p[rows.point[r]]
        SoftPointBias(ctx, sc, rows.point[r], &ctx.states[sc.ia], &ctx.states[sc.ib], useBias,
                      cache.keff[r] if useBias else -1.0, &bias, &gamma, &held)
        x0[r] = sp.normalImpulse
        extra[r] = cache.keff[r] * gamma if useBias else 0.0
        q[r] = SoftBlockSpeed(ctx, &rows, r) + bias - extra[r] * held
        lo[r] = 0.0
        hi[r] = INFINITY
    for r in range(n, m):
        sc = rows.contact[r - n]
        sp = &rows.contact[r - n].p[rows.point[r - n]]
        x0[r] = sp.tangentImpulse
        q[r] = SoftBlockSpeed(ctx, &rows, r) + sc.surfaceT
        cone = sc.friction * x0[r - n]
        hi[r] = cone if cone > 0.0 else 0.0
        lo[r] = -hi[r]
        extra[r] = 0.0
    for r in range(m):
        for t in range(m):
            q[r] -= cache.K[r][t] * x0[t]
    rounds = 1 if useBias else 3
    for round in range(rounds):
        if not SoftBlockPivot(cache, 0 if useBias else 1, extra, q, lo, hi, m, x0, x):
            return 0
        # Again only where a tangent impulse the cone held is beyond the
        # new one (sticking became sliding); one at the cone follows it.
        settled = 1
        for r in range(n, m):
            cone = rows.contact[r - n].friction * x[r - n]
            if fabs(x[r]) > cone and fabs(x[r]) < hi[r]:
                settled = 0
            hi[r] = cone
            lo[r] = -cone
        if settled:
            break
    for r in range(n, m):
        # Within the cone of the normal impulse found last.
        x[r] = fmin(hi[r], fmax(lo[r], x[r]))
    for r in range(m):
        sp = &rows.contact[r % n].p[rows.point[r % n]]
        if r < n:
            sp.normalImpulse = x[r]
            if x[r] > sp.maxNormalImpulse:
                sp.maxNormalImpulse = x[r]
        else:
            sp.tangentImpulse = x[r]
        x[r] -= x0[r]
    SoftBlockApply(ctx, &rows, m, x)
    return 1

cdef bint SoftBlockPivot(SoftBlockCache *cache, int kind, const cpFloat *extra,
                         const cpFloat *q, const cpFloat *lo, const cpFloat *hi, int n,
                         const cpFloat *x0, cpFloat *x) noexcept nogil:
    # The bounded complementarity problem w = M x + q, M = K + diag(extra)
    # (the cache's K over the first n rows), lo <= x <= hi, each
    # row either free (w = 0) or at a bound that w pushes it against (at lo
    # with w >= 0, at hi with w <= 0), by principal pivoting: solve for the
    # free rows with the others at their bounds, then move the first row
    # that is wrong (Murty's least-index rule, which ends for a positive
    # definite M) and solve again. Each row starts where the last pass of
    # this kind left it (in the step's first, where x0, the last impulses,
    # has it), so that a block at rest takes one solve, over the free rows
    # it factored before (SoftBlockSolveFree).
    # (Moving every wrong row at once took more solves on the pyramids of
    # benchmarks' high mass ratio scene.) False where no solution is found
    # within SOFT_BLOCK_PIVOTS solves.
    cdef int *state = cache.state[kind]   # 0 free, -1 at lo, 1 at hi
    cdef int r, t, pivot, flip
    cdef cpFloat w
    for r in range(n):
        if lo[r] == hi[r]:
            state[r] = -1
        elif not cache.stateKept[kind]:
            state[r] = -1 if x0[r] <= lo[r] else (1 if x0[r] >= hi[r] else 0)
    cache.stateKept[kind] = 0
    for pivot in range(SOFT_BLOCK_PIVOTS):
        if not SoftBlockSolveFree(cache, kind, extra, q, lo, hi, state, n, x):
            return 0
        flip = -1
        for r in range(n):
            if state[r] == 0:
                if x[r] < lo[r]:
                    state[r] = -1
                    flip = r
                elif x[r] > hi[r]:
                    state[r] = 1
                    flip = r
            elif lo[r] != hi[r]:
                w = q[r] + extra[r] * x[r]
                for t in range(n):
                    w += cache.K[r][t] * x[t]
                if (state[r] < 0 and w < 0.0) or (state[r] > 0 and w > 0.0):
                    state[r] = 0
                    flip = r
            if flip >= 0:
                break
        if flip < 0:
            cache.stateKept[kind] = 1
            return 1
    return 0

cdef bint SoftBlockEffectiveK(cpFloat M[][SOFT_BLOCK_ROWS], int n, cpFloat *keff) noexcept nogil:
    # keff[r] = 1 / (K^-1)_rr of the symmetric K = M (Gauss-Jordan with
    # partial pivoting; a dependent row, held by the others, gets a tiny
    # one); false if K is singular beyond that.
    cdef cpFloat a[SOFT_BLOCK_ROWS][2 * SOFT_BLOCK_ROWS]
    cdef int r, t, col, best
    cdef cpFloat f, big, scale = 0.0
    for r in range(n):
        scale = fmax(scale, M[r][r])
    if not (scale > 0.0):
        return 0
    for r in range(n):
        for t in range(n):
            a[r][t] = M[r][t]
            a[r][n + t] = 1.0 if r == t else 0.0
        # (A relative 1e-9 on the diagonal keeps dependent rows solvable.)
        a[r][r] += 1e-9 * scale
    for col in range(n):
        best = col
        big = fabs(a[col][col])
        for r in range(col + 1, n):
            if fabs(a[r][col]) > big:
                big = fabs(a[r][col])
                best = r
        if not (big > 1e-14 * scale):
            return 0
        if best != col:
            for t in range(2 * n):
                f = a[col][t]
                a[col][t] = a[best][t]
                a[best][t] = f
        f = 1.0 / a[col][col]
        for t in range(2 * n):
            a[col][t] *= f
        for r in range(n):
            if r != col and a[r][col] != 0.0:
                f = a[r][col]
                for t in range(2 * n):
                    a[r][t] -= f * a[col][t]
    for r in range(n):
        if not (a[r][n + r] > 0.0):
            return 0
        keff[r] = 1.0 / a[r][n + r]
    return 1

cdef bint SoftBlockSolveFree(SoftBlockCache *cache, int kind, const cpFloat *extra,
                             const cpFloat *q, const cpFloat *lo, const cpFloat *hi,
                             const int *state, int n, cpFloat *x) noexcept nogil:
    # x of the free rows from their equations M x = -q, the others at their
    # bounds. M is symmetric and (regularized) positive definite: its
    # Cholesky factor over the free rows, L L' = M, is kept in the cache
    # for the step's next solve of this kind, and brought to this solve's
    # free rows by dropping and appending rows (each O(k^2): a pivot that
    # moves one row does not factor again); false where a pivot is not
    # positive.
    cdef cpFloat b[SOFT_BLOCK_ROWS]
    cdef bint inFactor[SOFT_BLOCK_ROWS]
    cdef int *rows = cache.factorRows[kind]   # the factor's rows, in its order
    cdef cpFloat *L = &cache.L[kind][0][0]     # row r from L[r * SOFT_BLOCK_ROWS]
    cdef int k, r, t, u, p
    cdef cpFloat f
    for r in range(n):
        x[r] = 0.0 if state[r] == 0 else (lo[r] if state[r] < 0 else hi[r])
        inFactor[r] = 0
    k = cache.factorCount[kind]
    cache.factorCount[kind] = -1      # (until it is whole again)
    if k < 0:
        k = 0
    p = k - 1
    while p >= 0:
        r = rows[p]
        if state[r] != 0 or cache.factorExtra[kind][p] != extra[r]:
            SoftCholeskyDrop(L, k, p)
            for t in range(p, k - 1):
                rows[t] = rows[t + 1]
                cache.factorExtra[kind][t] = cache.factorExtra[kind][t + 1]
            k -= 1
        p -= 1
    for t in range(k):
        inFactor[rows[t]] = 1
    for r in range(n):
        if state[r] == 0 and not inFactor[r]:
            if not SoftCholeskyAppend(L, cache.K, extra, rows, k, r):
                return 0
            cache.factorExtra[kind][k] = extra[r]
            k += 1
    cache.factorCount[kind] = k
    # L y = b, then L' z = y, over the factor's rows.
    for t in range(k):
        f = -q[rows[t]]
        for u in range(n):
            if state[u] != 0:
                f -= cache.K[rows[t]][u] * x[u]
        for u in range(t):
            f -= L[t * SOFT_BLOCK_ROWS + u] * b[u]
        b[t] = f / L[t * SOFT_BLOCK_ROWS + t]
    for t in range(k - 1, -1, -1):
        f = b[t]
        for u in range(t + 1, k):
            f -= L[u * SOFT_BLOCK_ROWS + t] * b[u]
        b[t] = f / L[t * SOFT_BLOCK_ROWS + t]
    for t in range(k):
        x[rows[t]] = b[t]
    return 1

cdef bint SoftCholeskyAppend(cpFloat *L, cpFloat K[][SOFT_BLOCK_ROWS], const cpFloat *extra,
                             int *rows, int k, int r) noexcept nogil:
    # Row r of M = K + diag(extra) appended to the factor of rows[0:k]: its
    # row of L by forward substitution; false if its pivot is not positive.
    cdef int t, u
    cdef cpFloat f
    cdef cpFloat d = K[r][r] + extra[r]
    for t in range(k):
        f = K[r][rows[t]]
        for u in range(t):
            f -= L[k * SOFT_BLOCK_ROWS + u] * L[t * SOFT_BLOCK_ROWS + u]
        f /= L[t * SOFT_BLOCK_ROWS + t]
        L[k * SOFT_BLOCK_ROWS + t] = f
        d -= f * f
    if not (d > 0.0):
        return 0
    L[k * SOFT_BLOCK_ROWS + k] = sqrt(d)
    rows[k] = r
    return 1

cdef void SoftCholeskyDrop(cpFloat *L, int k, int p) noexcept nogil:
    # Row and column p taken out of the k-row factor: the rows below move
    # up, and their old column p, v, goes into the block below p as the
    # rank-one update L L' + v v' (rotations, which keep it positive).
    cdef cpFloat v[SOFT_BLOCK_ROWS]
    cdef int i, j, a, m = k - 1 - p
    cdef cpFloat d, rr, c, s
    for i in range(p + 1, k):
        v[i - p - 1] = L[i * SOFT_BLOCK_ROWS + p]
        for j in range(p):
            L[(i - 1) * SOFT_BLOCK_ROWS + j] = L[i * SOFT_BLOCK_ROWS + j]
        for j in range(p + 1, i + 1):
            L[(i - 1) * SOFT_BLOCK_ROWS + j - 1] = L[i * SOFT_BLOCK_ROWS + j]
    for a in range(m):
        d = L[(p + a) * SOFT_BLOCK_ROWS + p + a]
        rr = sqrt(d * d + v[a] * v[a])
        c = rr / d
        s = v[a] / d
        L[(p + a) * SOFT_BLOCK_ROWS + p + a] = rr
        for i in range(a + 1, m):
            L[(p + i) * SOFT_BLOCK_ROWS + p + a] = (L[(p + i) * SOFT_BLOCK_ROWS + p + a] + s * v[i]) / c
            v[i] = c * v[i] - s * L[(p + i) * SOFT_BLOCK_ROWS + p + a]

cdef void SoftEachBlockContact(SoftContext *ctx, int body, bint useBias) noexcept nogil:
    # SoftSolveContact over a light body's contacts.
    cdef int c = ctx.blockHead[body]
    while c >= 0:
        SoftSolveContact(ctx, &ctx.contacts[c], useBias)
        c = ctx.blockNext[c]

cdef inline bint SoftPointBias(SoftContext *ctx, const SoftContact *sc, int j,
                               const SoftState *sa, const SoftState *sb, bint useBias,
                               cpFloat rowK, cpFloat *bias, cpFloat *gamma,
                               cpFloat *held) noexcept nogil:
    # Point j's bias, compliance and held impulse for this pass; whether it
    # is apart (speculative). rowK: the row's k (inverse effective mass),
    # below 0 for the contact's own (its 2x2 matrix's or its point's).
    cdef const SoftPoint *sp = &sc.p[j]
    cdef cpFloat nx = sc.nx
    cdef cpFloat ny = sc.ny
    cdef cpFloat prAx, prAy, prBx, prBy, dx, dy, s, limit
    # The current separation from the bodies' motion in this step.
    prAx = sa.qc * sp.rAx - sa.qs * sp.rAy
    prAy = sa.qs * sp.rAx + sa.qc * sp.rAy
    prBx = sb.qc * sp.rBx - sb.qs * sp.rBy
    prBy = sb.qs * sp.rBx + sb.qc * sp.rBy
    dx = (sb.dpx - sa.dpx) + (prBx - prAx)
    dy = (sb.dpy - sa.dpy) + (prBy - prAy)
    s = dx * nx + dy * ny + sp.baseSeparation
    if s > 0.0:
        # Speculative: let the gap close within the substep, no push.
        bias[0] = s * ctx.inv_h
        gamma[0] = 0.0
        held[0] = 0.0
        return 1
    if useBias:
        # Overlap is pushed out softly, at most at pushOut beyond the
        # bias that holds the load the preload does not (the leak).
        gamma[0] = sp.compliance
        held[0] = fmin(sp.normalImpulse, sp.preload)
        bias[0] = sp.biasRate * s
        if rowK < 0.0:
            rowK = (sc.k11 if j == 0 else sc.k22) if sc.block else (
                1.0 / sp.normalMass if sp.normalMass > 0.0 else 0.0)
        limit = -ctx.pushOut - rowK * gamma[0] * (sp.normalImpulse - held[0])
        if bias[0] < limit:
            bias[0] = limit
    else:
        bias[0] = 0.0
        gamma[0] = 0.0
        held[0] = 0.0
    return 0

cdef void SoftSolveContact(SoftContext *ctx, SoftContact *sc, bint useBias) noexcept nogil:
    # One contact of the overflow. Velocities along n and t are a shared
    # linear part plus each point's angular part (cross products prepared
    # once per step).
    cdef int j
    cdef SoftPoint *sp
    cdef SoftPoint *p1
    cdef SoftPoint *p2
    cdef SoftBody *a
    cdef SoftBody *b
    cdef SoftState *sa
    cdef SoftState *sb
    cdef cpFloat nx, ny, lin, vn, vt, imp, newImp, maxF
    cdef cpFloat vax, vay, wa, vbx, vby, wb, mA, iA, mB, iB
    cdef cpFloat a11, a22, a12, x01, x02, q1, q2, det, x1, x2, d1, d2
    cdef cpFloat bias[2]
    cdef cpFloat gamma[2]      # a soft row's compliance (0: rigid)
    cdef cpFloat held[2]       # the part of the warm start a soft row's preload holds
    cdef cpFloat rnA, rnB, kN, meanBias, meanGamma
    cdef int apart = 0         # rows whose points are apart (speculative)
    a = &ctx.bodies[sc.ia]
    b = &ctx.bodies[sc.ib]
    sa = &ctx.states[sc.ia]
    sb = &ctx.states[sc.ib]
    vax = sa.vx
    vay = sa.vy
    wa = sa.w
    vbx = sb.vx
    vby = sb.vy
    wb = sb.w
    mA = a.m_inv
    iA = a.i_inv
    mB = b.m_inv
    iB = b.i_inv
    nx = sc.nx
    ny = sc.ny
    for j in range(sc.count):
        apart += SoftPointBias(ctx, sc, j, sa, sb, useBias, -1.0, &bias[j], &gamma[j],
                               &held[j])
    if sc.block:
        # Both normal rows at once: the linear complementarity problem
        # w = A x + q, x >= 0, w >= 0, x.w = 0 for the accumulated
        # impulses x, with A = K + diag(k_ii gamma_i) and
        # q = vn + bias - K x0 - diag(k_ii gamma_i) held. A soft row's added
        # diagonal is the soft constraint written as a compliance: (k + k
        # gamma) dx = -(vn + bias) - k gamma (x0 - held) is the sequential
        # massScale / impulseScale update exactly (with held 0). Cases in
        # Box2D 2.x's order.
        p1 = &sc.p[0]
        p2 = &sc.p[1]
        lin = (vbx - vax) * nx + (vby - vay) * ny
        x01 = p1.normalImpulse
        x02 = p2.normalImpulse
        a12 = sc.k12
        a11 = sc.k11 * (1.0 + gamma[0])
        a22 = sc.k22 * (1.0 + gamma[1])
        q1 = (lin + wb * p1.rnB - wa * p1.rnA + bias[0]
              - (sc.k11 * x01 + a12 * x02) - sc.k11 * gamma[0] * held[0])
        q2 = (lin + wb * p2.rnB - wa * p2.rnA + bias[1]
              - (a12 * x01 + sc.k22 * x02) - sc.k22 * gamma[1] * held[1])
        det = a11 * a22 - a12 * a12
        x1 = (a12 * q2 - a22 * q1) / det
        x2 = (a12 * q1 - a11 * q2) / det
        if not (x1 >= 0.0 and x2 >= 0.0):
            # Only the first point pushes.
            x1 = -q1 / a11
            x2 = 0.0
            if not (x1 >= 0.0 and a12 * x1 + q2 >= 0.0):
                # Only the second.
                x1 = 0.0
                x2 = -q2 / a22
                if not (x2 >= 0.0 and a12 * x2 + q1 >= 0.0):
                    # Neither: both separate; with no solution at all
                    # (round-off) the impulses stay.
                    x1 = 0.0
                    x2 = 0.0
                    if not (q1 >= 0.0 and q2 >= 0.0):
                        x1 = x01
                        x2 = x02
        d1 = x1 - x01
        d2 = x2 - x02
        p1.normalImpulse = x1
        p2.normalImpulse = x2
        if x1 > p1.maxNormalImpulse:
            p1.maxNormalImpulse = x1
        if x2 > p2.maxNormalImpulse:
            p2.maxNormalImpulse = x2
        imp = d1 + d2
        vax -= mA * imp * nx
        vay -= mA * imp * ny
        wa -= iA * (p1.rnA * d1 + p2.rnA * d2)
        vbx += mB * imp * nx
        vby += mB * imp * ny
        wb += iB * (p1.rnB * d1 + p2.rnB * d2)
    elif sc.count == 2 and apart == 0:
        # Two touching points too close for the block solve (the rows
        # nearly the same): one row at their midpoint, its impulse shared
        # equally. One after the other, the first point would take the
        # whole load wherever it is, and a load off the centre turns the
        # body: a many-sided polygon rolls from rest on it and speeds up.
        # (Where one point is apart, the other alone touches: the rows stay
        # separate.)
        p1 = &sc.p[0]
        p2 = &sc.p[1]
        rnA = 0.5 * (p1.rnA + p2.rnA)
        rnB = 0.5 * (p1.rnB + p2.rnB)
        kN = mA + mB + iA * rnA * rnA + iB * rnB * rnB
        x01 = p1.normalImpulse + p2.normalImpulse
        vn = ((vbx - vax) * nx + (vby - vay) * ny) + wb * rnB - wa * rnA
        meanBias = 0.5 * (bias[0] + bias[1])
        meanGamma = 0.5 * (gamma[0] + gamma[1])
        imp = ((-(vn + meanBias) / kN - meanGamma * (x01 - held[0] - held[1])) / (1.0 + meanGamma)
               if kN > 0.0 else 0.0)
        newImp = x01 + imp
        if newImp < 0.0:
            newImp = 0.0
        imp = newImp - x01
        p1.normalImpulse = 0.5 * newImp
        p2.normalImpulse = 0.5 * newImp
        if p1.normalImpulse > p1.maxNormalImpulse:
            p1.maxNormalImpulse = p1.normalImpulse
        if p2.normalImpulse > p2.maxNormalImpulse:
            p2.maxNormalImpulse = p2.normalImpulse
        vax -= mA * imp * nx
        vay -= mA * imp * ny
        wa -= iA * imp * rnA
        vbx += mB * imp * nx
        vby += mB * imp * ny
        wb += iB * imp * rnB
    else:
        for j in range(sc.count):
            sp = &sc.p[j]
            # (k + k gamma) dx = -(vn + bias) - k gamma (x0 - held), k = 1 / normalMass
            vn = ((vbx - vax) * nx + (vby - vay) * ny) + wb * sp.rnB - wa * sp.rnA
            imp = (-(sp.normalMass * (vn + bias[j]) + gamma[j] * (sp.normalImpulse - held[j]))
                   / (1.0 + gamma[j]))
            newImp = sp.normalImpulse + imp
            if newImp < 0.0:
                newImp = 0.0
            imp = newImp - sp.normalImpulse
            sp.normalImpulse = newImp
            if newImp > sp.maxNormalImpulse:
                sp.maxNormalImpulse = newImp
            vax -= mA * imp * nx
            vay -= mA * imp * ny
            wa -= iA * imp * sp.rnA
            vbx += mB * imp * nx
            vby += mB * imp * ny
            wb += iB * imp * sp.rnB
    if not useBias:
        # Friction only in the relax pass, as Box2D 3.2 does: there the
        # normal impulses that bound it are final for the substep.
        # Tangent t = perp(n) = (-ny, nx).
        for j in range(sc.count):
            sp = &sc.p[j]
            vt = ((vby - vay) * nx - (vbx - vax) * ny) + wb * sp.rtB - wa * sp.rtA + sc.surfaceT
            imp = -sp.tangentMass * vt
            maxF = sc.friction * sp.normalImpulse
            newImp = sp.tangentImpulse + imp
            if newImp < -maxF:
                newImp = -maxF
            elif newImp > maxF:
                newImp = maxF
            imp = newImp - sp.tangentImpulse
            sp.tangentImpulse = newImp
            vax += mA * imp * ny
            vay -= mA * imp * nx
            wa -= iA * imp * sp.rtA
            vbx -= mB * imp * ny
            vby += mB * imp * nx
            wb += iB * imp * sp.rtB
    # Slot 0 (immovable) is never written: contacts on other threads read it.
    if sc.ia != 0:
        sa.vx = vax
        sa.vy = vay
        sa.w = wa
    if sc.ib != 0:
        sb.vx = vbx
        sb.vy = vby
        sb.w = wb

cdef inline bint SoftInnerContact(const SoftBody *body) noexcept nogil:
    # A contact's side inside a web: immovable (slot 0), or a body in more
    # than SOFT_INNER_CONTACTS contacts (counted by the colouring). A
    # contact is inner when both of its sides are.
    return body.body == NULL or body.contacts > SOFT_INNER_CONTACTS

cdef inline bint SoftRelaxSkipsInner(SoftContext *ctx, int substep) noexcept nogil:
    # Whether this substep's extra relax pass leaves out the inner lanes:
    # after the step's first substep, unless a mass-ratio block is solved
    # (its rows converge from pass to pass through the contacts around it).
    return _skip_inner and substep > 0 and ctx.blockBodyCount == 0

cdef void SoftRelax(SoftContext *ctx, bint last, bint skipInner) noexcept nogil:
    # A relax pass: SoftSolve without bias. The substep's last also adds
    # the impulse the substep applied, its accumulated impulse after the
    # relax (the warm start re-applies the previous one), to the step's.
    # The passes before the last leave out the one-point lanes: the extra
    # pass is for the two-point manifolds that carry stacks, pyramids and
    # arches; for points alone (circles, corners) it cost as much and
    # changed no hard case's outcome (docs/stability.md). With skipInner
    # they leave out the inner lanes too (SoftRelaxSkipsInner, the
    # colouring's SOFT_LANE_INNER_PAIR): inside a web, after the first
    # substep, the extra pass changed no hard case's outcome either, nor
    # those of the stacks, arches and card houses of benchmarks/ (stacks and
    # arches have no inner contact), and it is most of a large pyramid's
    # lanes.
    cdef int i, j
    cdef SoftContact *sc
    if not last:
        for i in range(SOFT_GRAPH_COLORS):
            SoftRun(ctx, SOFT_TASK_RELAX_OUTER if skipInner else SOFT_TASK_SOLVE,
                    ctx.colorLanes[i], ctx.colorPairEnd[i], 0)
        SoftSolveOverflow(ctx, 0)
        return
    for i in range(SOFT_GRAPH_COLORS):
        SoftRun(ctx, SOFT_TASK_RELAX_ACCUMULATE, ctx.colorLanes[i], ctx.colorLanes[i + 1], 0)
    SoftSolveOverflow(ctx, 0)
    for i in range(ctx.overflowCount):
        sc = &ctx.contacts[ctx.overflow[i]]
        for j in range(sc.count):
            sc.p[j].totalNormal += sc.p[j].normalImpulse
            sc.p[j].totalTangent += sc.p[j].tangentImpulse

cdef void SoftUnpackLanes(SoftContext *ctx, int begin, int end, bint store) noexcept nogil:
    # The lanes' impulses back into their SoftContacts (restitution and the
    # arbiters read them there); with `store`, for a step without
    # restitution (nothing else reads the SoftContacts' impulses), the step's
    # totals straight into the arbiters' contacts instead (SoftStoreImpulses
    # in the same pass).
    cdef int i, j, k
    cdef SoftLanes *ln
    cdef SoftLaneLinks *links
    cdef SoftContact *sc
    cdef SoftPoint *sp
    cdef cpContact *con
    for i in range(begin, end):
        ln = &ctx.lanes[i]
        links = &ctx.laneLinks[i]
        if ctx.fetchAhead and store and i + 2 < end:
            # The arbiters' contacts two lanes on (scattered in memory): the
            # lines their impulses are written to (a two-point manifold's
            # lie on three).
            for k in range(SOFT_LANES):
                if links[2].src[k] >= 0:
                    con = <cpContact *>links[2].dst[k]
                    tamias_prefetch_write(&con[0].jnAcc)
                    tamias_prefetch_write(&con[0].jtAcc)
                    if ln[2].points == 2:
                        tamias_prefetch_write(&con[1].jnAcc)
                        tamias_prefetch_write(&con[1].jtAcc)
        for k in range(SOFT_LANES):
            if links.src[k] < 0:
                continue
            if store:
                # Through the lane's own pointer: the SoftContact (read in
                # colour order, out of its order) is not touched.
                con = <cpContact *>links.dst[k]
                for j in range(ln.points):
                    con[j].jnAcc = ln.totalNormal[j][k]
                    con[j].jtAcc = ln.totalTangent[j][k]
                continue
            sc = &ctx.contacts[links.src[k]]
            for j in range(sc.count):
                sp = &sc.p[j]
                sp.normalImpulse = ln.normalImpulse[j][k]
                sp.tangentImpulse = ln.tangentImpulse[j][k]
                sp.maxNormalImpulse = links.maxNormalImpulse[j][k]
                sp.totalNormal = ln.totalNormal[j][k]
                sp.totalTangent = ln.totalTangent[j][k]

cdef void SoftStoreOverflow(SoftContext *ctx) noexcept nogil:
    # The contacts solved one by one hold their impulses themselves.
    cdef int i
    for i in range(ctx.overflowCount):
        SoftStoreImpulses(ctx, ctx.overflow[i], ctx.overflow[i] + 1)

cdef inline bint SoftFallsFreely(SoftContext *ctx, int slot) noexcept nogil:
    # A dynamic body that the space's gravity accelerates (its default
    # velocity function).
    return (ctx.bodies[slot].flags & (SOFT_BODY_DEFAULT_VELOCITY | SOFT_BODY_KINEMATIC)
            == SOFT_BODY_DEFAULT_VELOCITY)

cdef inline cpFloat SoftRestingSpeed(SoftContext *ctx, SoftContact *sc, cpFloat fraction,
                                     cpFloat gravityStep) noexcept nogil:
    # The approach speed up to which a point of sc counts as at rest: a
    # small fraction of the step's largest bounce, and for a body under
    # gravity, the speed gravity gives it in one step.
    if gravityStep > fraction and (SoftFallsFreely(ctx, sc.ia) or SoftFallsFreely(ctx, sc.ib)):
        return gravityStep
    return fraction

cdef void SoftApplyRestitution(SoftContext *ctx) noexcept nogil:
    # After the substeps: points that were approaching at the step's start
    # and took an impulse get e times that approach speed back.
    #
    # Box2D makes one pass; where bounces are coupled one pass loses energy:
    # three balls meeting (an elastic gas of 20 balls kept 26% of its energy
    # over 100,000 steps), or a ball resting on a wall struck by another
    # (half the energy: the resting contact was not approaching, so took no
    # part, and the struck ball's bounce drove it into the wall). So further
    # passes follow while a pass still changes something, at most
    # SOFT_RESTITUTION_PASSES, and in them the loaded points that were at
    # rest keep from closing; they push, never pull. (Points that were
    # separating stay out: where a ball already overlapped both a wall and
    # its neighbour, pushing them doubled the energy.)
    #
    # At rest means approaching no faster than SOFT_RESTING_FRACTION of the
    # step's largest bounce, or, where a body falls under gravity, than the
    # speed gravity gives it in one step (Box2D's restitution threshold, in
    # the scene's units): such a bounce is spent within the step, and where
    # it counted, a pile of slightly elastic bodies had every contact
    # bouncing, and the passes became ten more relax passes over the whole
    # pile (a rain of circles of elasticity 0.1 ran ten passes almost every
    # step). Only the resting points next to a bounce (of a body that took
    # one in the first pass) take part in the later passes.
    cdef int i, j, k, n, c
    cdef SoftContact *sc
    cdef SoftPoint *sp
    cdef SoftState *sa
    cdef SoftState *sb
    cdef cpFloat nx, ny, e, vn, imp, newImp, target, restingSpeed
    cdef cpFloat largest = 0.0     # the largest bounce speed of the step
    cdef cpFloat fraction
    cdef cpFloat gravityStep = ctx.gravity * ctx.h * ctx.substeps
    cdef bint changed = 1
    cdef bint resting, bounces, rests
    cdef int *changedIn
    cdef int *members
    cdef int *bounced
    cdef int memberCount = 0
    if not gravityStep < INFINITY:
        gravityStep = 0.0
    for i in range(ctx.contactCount):
        sc = &ctx.contacts[i]
        if sc.restitution == 0.0:
            continue
        restingSpeed = SoftRestingSpeed(ctx, sc, 0.0, gravityStep)
        for j in range(sc.count):
            sp = &sc.p[j]
            if (sc.restitution * -sp.relativeVelocity > largest and sp.maxNormalImpulse != 0.0
                    and -sp.relativeVelocity > restingSpeed):
                largest = sc.restitution * -sp.relativeVelocity
    if largest == 0.0:
        return
    fraction = SOFT_RESTING_FRACTION * largest
    # The first pass visits every elastic contact; the later ones the
    # contacts with a bounce, and those with a resting point on a body that
    # bounced (`bounced`), in their order. From the third pass on, a contact
    # neither of whose bodies changed since the start of the last pass is
    # passed over: it would compute what it did then, and then it changed
    # nothing. (The first two passes differ in what they do with resting
    # points.) Without the arrays (out of memory) every contact is visited
    # in every pass.
    changedIn = <int *>_reserve(ctx.space, SOFT_SCRATCH_CHANGED_IN,
                                2 * ctx.bodyCount + ctx.contactCount, sizeof(int))
    members = bounced = NULL
    if changedIn != NULL:
        bounced = changedIn + ctx.bodyCount
        members = bounced + ctx.bodyCount
        for i in range(ctx.bodyCount):
            changedIn[i] = -1
            bounced[i] = 0
    k = 0
    while changed and k < SOFT_RESTITUTION_PASSES:
        changed = 0
        n = memberCount if k > 0 and members != NULL else ctx.contactCount
        for c in range(n):
            i = members[c] if k > 0 and members != NULL else c
            sc = &ctx.contacts[i]
            e = sc.restitution
            if e == 0.0:
                continue
            if k >= 2 and changedIn != NULL and (changedIn[sc.ia] < k - 1
                                                 and changedIn[sc.ib] < k - 1):
                continue
            restingSpeed = SoftRestingSpeed(ctx, sc, fraction, gravityStep)
            sa = &ctx.states[sc.ia]
            sb = &ctx.states[sc.ib]
            nx = sc.nx
            ny = sc.ny
            bounces = rests = 0
            for j in range(sc.count):
                sp = &sc.p[j]
                if sp.maxNormalImpulse == 0.0:
                    continue
                resting = fabs(sp.relativeVelocity) <= restingSpeed
                if resting:
                    rests = 1
                    if k == 0:
                        continue
                    target = 0.0
                elif sp.relativeVelocity < 0.0:
                    bounces = 1
                    target = -e * sp.relativeVelocity
                else:
                    continue
                vn = ((sb.vx - sb.w * sp.rBy - sa.vx + sa.w * sp.rAy) * nx
                      + (sb.vy + sb.w * sp.rBx - sa.vy - sa.w * sp.rAx) * ny)
                imp = -sp.normalMass * (vn - target)
                # Later passes leave alone what is settled up to rounding, so
                # a lone bounce is the first pass's bits.
                if k > 0 and fabs(imp) <= SOFT_RESTITUTION_TOLERANCE * sp.normalMass * largest:
                    continue
                if resting:
                    if imp < 0.0:
                        continue
                    newImp = sp.normalImpulse + imp
                else:
                    newImp = sp.normalImpulse + imp
                    if newImp < 0.0:
                        newImp = 0.0
                    imp = newImp - sp.normalImpulse
                if imp == 0.0:
                    continue
                changed = 1
                sp.normalImpulse = newImp
                sp.totalNormal += imp
                SoftApplyImpulse(ctx, sc, sp, imp * nx, imp * ny)
                if changedIn != NULL:
                    if sc.ia != 0:
                        changedIn[sc.ia] = k
                    if sc.ib != 0:
                        changedIn[sc.ib] = k
            if k == 0 and members != NULL and (bounces or rests):
                # A candidate for the later passes: -(i + 1) if it bounces.
                members[memberCount] = -(i + 1) if bounces else i
                memberCount += 1
                if bounces:
                    # (Slot 0, the static and sleeping bodies', is not
                    # marked: a pile's every contact with the ground would
                    # come in.)
                    if sc.ia != 0:
                        bounced[sc.ia] = 1
                    if sc.ib != 0:
                        bounced[sc.ib] = 1
        if k == 0 and members != NULL:
            n = 0
            for c in range(memberCount):
                i = members[c]
                if i < 0:
                    members[n] = -i - 1
                    n += 1
                elif bounced[ctx.contacts[i].ia] or bounced[ctx.contacts[i].ib]:
                    members[n] = i
                    n += 1
            memberCount = n
        k += 1

cdef void SoftStoreImpulses(SoftContext *ctx, int begin, int end) noexcept nogil:
    # jnAcc / jtAcc hold the impulse of the whole step, as in the chipmunk
    # solver: Arbiter.total_impulse reads them, and the next step warm-starts
    # each substep with (h / dt) of them.
    cdef int i, j
    cdef SoftContact *sc
    cdef cpContact *con
    for i in range(begin, end):
        sc = &ctx.contacts[i]
        for j in range(sc.count):
            con = &sc.arb.contacts[j]
            con.jnAcc = sc.p[j].totalNormal
            con.jtAcc = sc.p[j].totalTangent


# -- integration ---------------------------------------------------------------------------

cdef void SoftIntegrateVelocities(SoftContext *ctx, int begin, int end, bint last) noexcept nogil:
    # Bodies [begin, end) (slot 0 excluded by the callers).
    cdef int i
    for i in range(begin, end):
        SoftIntegrateVelocity(ctx, i, last)

cdef inline void SoftIntegrateVelocity(SoftContext *ctx, int i, bint last) noexcept nogil:
    cdef SoftBody *sb = &ctx.bodies[i]
    cdef SoftState *st = &ctx.states[i]
    cdef SoftMotion *mo
    cdef cpBody *body
    cdef cpFloat damping = ctx.damping
    cdef cpFloat h = ctx.h
    cdef cpVect f
    cdef cpFloat t
    if sb.flags & SOFT_BODY_DEFAULT_VELOCITY:
        if sb.flags & SOFT_BODY_KINEMATIC:
            return
        # cpBodyUpdateVelocity's arithmetic; the force applies in every
        # substep and is cleared when the step ends.
        mo = &ctx.motion[i]
        if ctx.livePositions:
            # A Python velocity_func may have pushed this body since.
            SoftGatherMotion(ctx, i, sb.body)
        st.vx = st.vx * damping + mo.ax * h
        st.vy = st.vy * damping + mo.ay * h
        st.w = st.w * damping + mo.alpha * h
    else:
        body = sb.body
        body.v.x = st.vx
        body.v.y = st.vy
        body.w = st.w
        f = body.f
        t = body.t
        body.velocity_func(body, cpv(ctx.gx, ctx.gy), damping, h)
        st.vx = body.v.x
        st.vy = body.v.y
        st.w = body.w
        if not last:
            # Body.update_velocity clears the force: keep it for the
            # remaining substeps.
            body.f = f
            body.t = t

cdef void SoftIntegratePositions(SoftContext *ctx, int begin, int end) noexcept nogil:
    cdef int i
    for i in range(begin, end):
        SoftIntegratePosition(ctx, i)

cdef inline void SoftIntegratePosition(SoftContext *ctx, int i) noexcept nogil:
    cdef SoftBody *sb = &ctx.bodies[i]
    cdef SoftState *st = &ctx.states[i]
    cdef SoftMotion *mo
    cdef cpBody *body
    cdef cpFloat h = ctx.h
    cdef cpFloat dx, dy, da, qc, qs, mag, px0, py0, a0
    body = sb.body
    if sb.flags & SOFT_BODY_DEFAULT_POSITION:
        dx = st.vx * h
        dy = st.vy * h
        da = st.w * h
        mo = &ctx.motion[i]
        mo.px = mo.px + dx
        mo.py = mo.py + dy
        mo.a = mo.a + da
        if ctx.livePositions or (sb.flags & SOFT_BODY_JOINTED):
            body.p.x = mo.px
            body.p.y = mo.py
            body.a = mo.a
            if ctx.livePositions and not (sb.flags & SOFT_BODY_JOINTED):
                # As cpBodyUpdatePosition: Body.position is read from the
                # transform (jointed bodies get theirs below).
                SoftSetTransform(body)
    else:
        body.v.x = st.vx
        body.v.y = st.vy
        body.w = st.w
        px0 = body.p.x
        py0 = body.p.y
        a0 = body.a
        body.position_func(body, h)
        dx = body.p.x - px0
        dy = body.p.y - py0
        da = body.a - a0
        st.vx = body.v.x
        st.vy = body.v.y
        st.w = body.w
    st.dpx += dx
    st.dpy += dy
    # The step's rotation, advanced by da and renormalised (no trig).
    qc = st.qc - da * st.qs
    qs = st.qs + da * st.qc
    mag = sqrt(qc * qc + qs * qs)
    if mag > 0.0:
        mag = 1.0 / mag
    st.qc = qc * mag
    st.qs = qs * mag
    if sb.flags & SOFT_BODY_JOINTED:
        # The joints' preStep reads the transform.
        SoftSetTransform(body)

cdef void SoftFinishBodies(SoftContext *ctx, const int *order, int begin, int end) noexcept nogil:
    # Bodies begin to end (or order[begin:end], a group's, where order is
    # not NULL) written back, and counted, with those left non-finite: the
    # step's check for an overflow then need not read every body again
    # (cpSoftStep's answer).
    cdef int i
    cdef long nonFinite = 0
    cdef cpBody *body
    for i in range(begin, end):
        if ctx.fetchAhead and i + SOFT_BODY_PREFETCH < end:
            SoftFetchLines(ctx.bodies[SoftNth(order, i + SOFT_BODY_PREFETCH)].body, sizeof(cpBody))
        body = SoftFinishBody(ctx, SoftNth(order, i))
        if _bodyNonFinite(body):
            nonFinite += 1
    tamias_add(&ctx.bodiesFinished, end - begin)
    if nonFinite:
        tamias_add(&ctx.bodiesNonFinite, nonFinite)

cdef inline cpBody *SoftFinishBody(SoftContext *ctx, int i) noexcept nogil:
    cdef SoftBody *sb = &ctx.bodies[i]
    cdef SoftState *st = &ctx.states[i]
    cdef cpBody *body = sb.body
    if sb.flags & SOFT_BODY_DEFAULT_POSITION:
        body.p.x = ctx.motion[i].px
        body.p.y = ctx.motion[i].py
        body.a = ctx.motion[i].a
    body.v.x = st.vx
    body.v.y = st.vy
    body.w = st.w
    body.v_bias = cpv(0.0, 0.0)
    body.w_bias = 0.0
    if (sb.flags & SOFT_BODY_DEFAULT_VELOCITY) and not (sb.flags & SOFT_BODY_KINEMATIC):
        body.f = cpv(0.0, 0.0)
        body.t = 0.0
    SoftSetTransform(body)
    return body


# -- threads within one step ---------------------------------------------------------
# A threaded space (Space(threaded=True), threads = 2) runs the body and
# contact stages of its soft step on the calling thread and a worker. A
# stage is a range cut into chunks, which the caller takes from the front
# and the worker from the back; the chunks of a stage are independent
# (contacts of one colour share no movable body, each body integrates alone,
# each pair's narrow phase writes only its own results), so the result is
# the same bits whoever runs which chunk, and the same as on one thread. The
# caller never waits for a worker that has not come (a busy machine): it
# takes every chunk the worker does not. A stage costs two cache-line trips
# between the cores, so steps under SOFT_THREADED_MIN_CONTACTS stay serial.

cdef enum:
    SOFT_TASK_INTEGRATE_VELOCITIES = 0
    SOFT_TASK_INTEGRATE_POSITIONS
    SOFT_TASK_WARM_START
    SOFT_TASK_SOLVE
    SOFT_TASK_RELAX_ACCUMULATE
    SOFT_TASK_RELAX_OUTER     # a relax pass over the lanes that are not inner (SoftRelax)
    SOFT_TASK_NARROW
    SOFT_TASK_UNPACK
    SOFT_TASK_STORE
    SOFT_TASK_FINISH_BODIES
    SOFT_TASK_PACK
    SOFT_TASK_UPDATE_SHAPES
    SOFT_TASK_GATHER
    SOFT_TASK_COUNT
    SOFT_TASK_MARK_THREADED
    SOFT_TASK_ESTIMATE_AND_COLOR
    SOFT_TASK_GROUPS          # whole groups' substeps (SoftSubstepGroup)

cdef enum:
    SOFT_CHUNK_LANES = 32         # lanes of contacts per chunk
    SOFT_CHUNK_BODIES = 128
    SOFT_WORKER_SPIN = 1 << 16    # pauses a worker polls for the next stage before it sleeps
    SOFT_THREADED_MIN_CONTACTS = 2048   # last step's arbiters
    # A colour's contact pass with fewer lanes runs on the calling thread:
    # its bodies' states would cross between the cores' caches for each
    # colour, for little work. (The tumbler's colours, a pile of 2,025
    # boxes in a drum, are all under it: on two threads its step took
    # 5.1-5.4 ms with them shared, 4.8 without, as on one thread; the large
    # pyramid's and many_pyramids' steps did not change.)
    SOFT_SHARED_PASS_MIN_LANES = 256
    SOFT_CHUNK_CONTACTS = 64      # contacts counted or stored per chunk
    SOFT_CHUNK_PAIRS = 64         # pairs of the narrow phase per chunk

cdef struct SoftPool:
    volatile long generation      # +1 per stage handed out
    volatile long open            # 1 while the stage's chunks may be taken
    volatile long inside          # workers between their look at `open` and leaving
    volatile long claimed         # chunks claimed so far (atomic)
    volatile long front           # chunks the caller took, from the front
    volatile long back            # chunks the worker took, from the back
    volatile long sleeping        # the worker sleeps on `wake`
    volatile long busy            # a step is using the pool
    SoftContext *ctx              # the stage: task, range, flag
    int task, begin, end, chunk, chunks
    bint flag
    PyThread_type_lock wake
    int workers                   # started (0 or 1)
    CollisionDiagnostics diag     # the worker's narrow-phase notes of this stage

cdef SoftPool _pool
cdef long _pool_pid = -1


cdef void SoftRunRange(SoftContext *ctx, int task, int begin, int end, bint flag) noexcept nogil:
    cdef int i
    if task == SOFT_TASK_INTEGRATE_VELOCITIES:
        SoftIntegrateVelocities(ctx, begin, end, flag)
    elif task == SOFT_TASK_INTEGRATE_POSITIONS:
        SoftIntegratePositions(ctx, begin, end)
    elif task == SOFT_TASK_WARM_START:
        SoftLanesWarmStart(&ctx.lanes[begin], end - begin, ctx.states, ctx.fetchAhead)
    elif task == SOFT_TASK_SOLVE or task == SOFT_TASK_RELAX_OUTER:
        SoftLanesSolve(&ctx.lanes[begin], &ctx.laneLinks[begin], end - begin, ctx.states,
                       &ctx.laneBiasRates, ctx.inv_h, ctx.pushOut, flag, 0, tamias_load(&ctx.elastic) != 0,
                       ctx.fetchAhead, task == SOFT_TASK_RELAX_OUTER)
    elif task == SOFT_TASK_RELAX_ACCUMULATE:
        SoftLanesSolve(&ctx.lanes[begin], &ctx.laneLinks[begin], end - begin, ctx.states,
                       &ctx.laneBiasRates, ctx.inv_h, ctx.pushOut, 0, 1, tamias_load(&ctx.elastic) != 0,
                       ctx.fetchAhead, 0)
    elif task == SOFT_TASK_NARROW:
        SoftNarrowPhase(ctx, begin, end)
    elif task == SOFT_TASK_UNPACK:
        SoftUnpackLanes(ctx, begin, end, flag)
    elif task == SOFT_TASK_STORE:
        SoftStoreImpulses(ctx, begin, end)
    elif task == SOFT_TASK_FINISH_BODIES:
        SoftFinishBodies(ctx, NULL, begin, end)
    elif task == SOFT_TASK_PACK:
        SoftPackLanes(ctx, begin, end)
    elif task == SOFT_TASK_UPDATE_SHAPES:
        SoftUpdateShapes(ctx, begin, end)
    elif task == SOFT_TASK_GATHER:
        SoftGatherRange(ctx, begin, end)
    elif task == SOFT_TASK_COUNT:
        SoftCountRange(ctx, begin, end)
    elif task == SOFT_TASK_MARK_THREADED:
        SoftMarkThreaded(ctx, begin, end)
    elif task == SOFT_TASK_ESTIMATE_AND_COLOR:
        for i in range(begin, end):
            if i == 0:
                SoftEstimateLoads(ctx)
            else:
                ctx.colored = SoftColorContacts(ctx)
    elif task == SOFT_TASK_GROUPS:
        for i in range(begin, end):
            SoftSubstepGroup(ctx, i, 0)

cdef void SoftTakeChunks(bint caller) noexcept nogil:
    # The caller takes chunks from the front, the worker from the back: in
    # every stage each thread starts where it ended the last one, so it
    # works on the same bodies (contacts are in the broad phase's spatial
    # order) and their cache lines stay on its core. A claim first, so that
    # the two ends never take the same chunk.
    cdef long i
    cdef int lo, hi
    while True:
        if tamias_take_next(&_pool.claimed) >= _pool.chunks:
            return
        if caller:
            i = tamias_take_next(&_pool.front)
        else:
            i = _pool.chunks - 1 - tamias_take_next(&_pool.back)
        lo = _pool.begin + <int>i * _pool.chunk
        hi = lo + _pool.chunk
        if hi > _pool.end:
            hi = _pool.end
        SoftRunRange(_pool.ctx, _pool.task, lo, hi, _pool.flag)

cdef void SoftRun(SoftContext *ctx, int task, int begin, int end, bint flag) noexcept nogil:
    # One stage over [begin, end): on the pool when the space is threaded
    # and the stage is big enough to share, else here.
    cdef int chunk = SOFT_CHUNK_LANES
    if (task <= SOFT_TASK_INTEGRATE_POSITIONS or task == SOFT_TASK_FINISH_BODIES
            or task == SOFT_TASK_UPDATE_SHAPES or task == SOFT_TASK_GATHER):
        chunk = SOFT_CHUNK_BODIES
    elif (task == SOFT_TASK_STORE or task == SOFT_TASK_COUNT or task == SOFT_TASK_PACK
            or task == SOFT_TASK_MARK_THREADED):
        chunk = SOFT_CHUNK_CONTACTS
    elif task == SOFT_TASK_NARROW:
        chunk = SOFT_CHUNK_PAIRS
    elif task == SOFT_TASK_ESTIMATE_AND_COLOR or task == SOFT_TASK_GROUPS:
        chunk = 1
    cdef int k
    if end <= begin:
        return
    if task == SOFT_TASK_INTEGRATE_VELOCITIES and ctx.serialVelocities:
        SoftRunRange(ctx, task, begin, end, flag)
        return
    if task == SOFT_TASK_INTEGRATE_POSITIONS and ctx.serialPositions:
        SoftRunRange(ctx, task, begin, end, flag)
        return
    if not ctx.threaded or end - begin <= chunk:
        SoftRunRange(ctx, task, begin, end, flag)
        return
    if (task == SOFT_TASK_WARM_START or task == SOFT_TASK_SOLVE or task == SOFT_TASK_RELAX_ACCUMULATE
            or task == SOFT_TASK_RELAX_OUTER) \
            and end - begin < SOFT_SHARED_PASS_MIN_LANES and _threaded_min_contacts > 0:
        # (Not in the tests' mode, _threaded_min_contacts_set(0), which
        # shares every stage it can.)
        SoftRunRange(ctx, task, begin, end, flag)
        return
    _pool.ctx = ctx
    _pool.task = task
    _pool.begin = begin
    _pool.end = end
    _pool.chunk = chunk
    _pool.chunks = (end - begin + chunk - 1) // chunk
    _pool.flag = flag
    tamias_store(&_pool.claimed, 0)
    tamias_store(&_pool.front, 0)
    tamias_store(&_pool.back, 0)
    tamias_store(&_pool.open, 1)
    tamias_add(&_pool.generation, 1)
    if tamias_exchange(&_pool.sleeping, 0) == 1:
        PyThread_release_lock(_pool.wake)
    SoftTakeChunks(1)
    tamias_store(&_pool.open, 0)
    k = 0
    while tamias_load(&_pool.inside) != 0:
        # The worker is finishing a chunk (or was preempted inside one).
        k += 1
        if k < 4096:
            tamias_cpu_relax()
        else:
            tamias_yield()
    if task == SOFT_TASK_NARROW:
        # What the worker's narrow phase noted (per-thread flags) is the
        # step's, as if this thread had run it.
        cpCollisionPutDiagnostics(_pool.diag)
        memset(&_pool.diag, 0, sizeof(CollisionDiagnostics))

cdef void SoftWorkerMain(void *arg) noexcept nogil:
    cdef long seen = tamias_load(&_pool.generation)
    cdef long spins
    cdef CollisionDiagnostics d
    while True:
        spins = 0
        while tamias_load(&_pool.generation) == seen:
            if spins < SOFT_WORKER_SPIN:
                spins += 1
                tamias_cpu_relax()
                continue
            # Sleep until the next stage; the caller wakes a sleeper once.
            tamias_store(&_pool.sleeping, 1)
            if tamias_load(&_pool.generation) != seen and tamias_exchange(&_pool.sleeping, 0) == 1:
                break
            PyThread_acquire_lock(_pool.wake, WAIT_LOCK)
            spins = 0
        seen = tamias_load(&_pool.generation)
        tamias_add(&_pool.inside, 1)
        if tamias_load(&_pool.open):
            SoftTakeChunks(0)
            if _pool.task == SOFT_TASK_NARROW:
                d = cpCollisionTakeDiagnostics()
                _pool.diag.flags |= d.flags
                if d.gjk_iter > _pool.diag.gjk_iter:
                    _pool.diag.gjk_iter = d.gjk_iter
                if d.epa_iter > _pool.diag.epa_iter:
                    _pool.diag.epa_iter = d.epa_iter
        tamias_add(&_pool.inside, -1)

# SOFT_FETCH_MIN_CONTACTS, but for tests, which check that fetching ahead
# changes no bits, and measurements (_fetch_min_contacts_set).
cdef int _fetch_min_contacts = SOFT_FETCH_MIN_CONTACTS

# SOFT_GROUP_CONTACTS, but for tests, which check that grouping changes no
# bits, and measurements (_group_contacts_set; 0: never group).
cdef int _group_contacts = SOFT_GROUP_CONTACTS
cdef volatile long _grouped_steps = 0

# SOFT_THREADED_MIN_CONTACTS, but for tests and the fuzzer, which run small
# scenes on the pool (_threaded_min_contacts_set).
cdef int _threaded_min_contacts = SOFT_THREADED_MIN_CONTACTS

cdef bint SoftPoolAcquire(cpSpace *space) noexcept nogil:
    # The pool serves one step at a time; another space stepped meanwhile
    # (from another thread) runs on its own thread, with the same result.
    # A small step runs on one thread: below some thousand contacts, two
    # threads trading the bodies' cache lines cost more than they share.
    if space.soft.threads <= 1 or _pool.workers == 0 or space.arbiters.num < _threaded_min_contacts:
        return 0
    return tamias_exchange(&_pool.busy, 1) == 0

cdef inline void SoftPoolRelease() noexcept nogil:
    tamias_store(&_pool.busy, 0)

cdef int SoftPoolEnsure() except -1:
    # Start the worker (with the GIL; once per process, again after a fork).
    global _pool_pid
    import os
    pid = os.getpid()
    if _pool_pid == pid and _pool.workers > 0:
        return 0
    memset(&_pool, 0, sizeof(SoftPool))
    _pool.wake = PyThread_allocate_lock()
    if _pool.wake == NULL:
        raise MemoryError("cannot allocate the lock of the soft solver's worker")
    PyThread_acquire_lock(_pool.wake, WAIT_LOCK)
    if PyThread_start_new_thread(SoftWorkerMain, NULL) == <unsigned long>-1:
        raise RuntimeError("cannot start the soft solver's worker thread")
    _pool.workers = 1
    _pool_pid = pid
    return 0


# -- the step -----------------------------------------------------------------------------

cdef void SoftSetSubsteps(SoftContext *ctx, cpFloat dt, int substeps) noexcept nogil:
    # The substep and what follows from it: the damping per substep and the
    # softness of contacts and joints.
    cdef cpSpace *space = ctx.space
    cdef cpFloat hertz, staticHertz
    ctx.substeps = substeps
    ctx.h = dt / ctx.substeps
    ctx.inv_h = 1.0 / ctx.h
    ctx.damping = pow(space.damping, ctx.h)
    # Stiffer than a quarter of the substep rate would not be resolved.
    hertz = space.soft.contactHertz
    if hertz > 0.25 * ctx.inv_h:
        hertz = 0.25 * ctx.inv_h
    ctx.contactSoft = SoftMakeSoft(hertz, space.soft.contactDampingRatio, ctx.h)
    # Against immovable bodies twice as stiff, within the same cap.
    staticHertz = 2.0 * hertz
    if staticHertz > 0.25 * ctx.inv_h:
        staticHertz = 0.25 * ctx.inv_h
    ctx.staticSoft = SoftMakeSoft(staticHertz, space.soft.contactDampingRatio, ctx.h)
    ctx.contactCompliance[0] = SoftCompliance(&ctx.contactSoft)
    ctx.contactCompliance[1] = ctx.contactCompliance[0] / SOFT_RATIO_STIFFENING
    ctx.staticCompliance[0] = SoftCompliance(&ctx.staticSoft)
    ctx.staticCompliance[1] = ctx.staticCompliance[0] / SOFT_RATIO_STIFFENING
    hertz = space.soft.jointHertz
    if hertz > 0.25 * ctx.inv_h:
        hertz = 0.25 * ctx.inv_h
    ctx.jointSoft = SoftMakeSoft(hertz, space.soft.jointDampingRatio, ctx.h)

cdef bint cpSoftStep(cpSpace *space, cpFloat dt) noexcept nogil:
    # True when every awake body was written back by the step, none of them
    # non-finite: only the bodies it does not write can still be (see
    # tamias_first_non_finite_body).
    cdef SoftContext ctx
    cdef cpFloat prev_dt
    cdef int collided, k, r
    cdef bint ready
    if dt == 0.0:
        return 0
    space.stamp += 1
    space.arbitersStamped = 0
    prev_dt = space.curr_dt
    space.curr_dt = dt

    ctx.space = space
    SoftSetSubsteps(&ctx, dt, space.soft.substeps if space.soft.substeps >= 1 else 1)
    ctx.gx = space.gravity.x
    ctx.gy = space.gravity.y
    ctx.pushOut = SoftPushOut(space)
    ctx.youngPairs = 0
    ctx.touchingPairs = 0
    ctx.contactCount = 0
    ctx.elastic = 0
    ctx.jointBodyCount = 0
    ctx.overflowCount = 0
    ctx.groupCount = 0
    ctx.colorLanes[SOFT_GRAPH_COLORS] = 0
    ctx.serialVelocities = 0
    ctx.serialPositions = 0
    ctx.threaded = 0
    ctx.gravity = hypot(ctx.gx, ctx.gy)
    ctx.estimating = _estimate_loads and 0.0 < ctx.gravity < INFINITY
    ctx.upx = -ctx.gx / ctx.gravity if ctx.estimating else 0.0
    ctx.upy = -ctx.gy / ctx.gravity if ctx.estimating else 0.0
    ctx.loadEstimates = NULL
    ctx.estimatePending = 0
    ctx.colored = 0
    ctx.innerApart = 0
    tamias_store(&ctx.bodiesFinished, 0)
    tamias_store(&ctx.bodiesNonFinite, 0)
    space.collideMargin = SoftSpeculative(space)

    SoftProfileMark(-1)
    # (Last step's contact count decides whether this one is threaded, and
    # whether its passes fetch ahead.)
    ctx.fetchAhead = space.arbiters.num >= _fetch_min_contacts
    ctx.threaded = SoftPoolAcquire(space)
    # (Looked up once: no Python runs before the narrow phase that could
    # change the handlers.)
    ctx.updateInNarrow = not cpSpaceHasHandlers(space, 1, 1, 0, 0)
    SoftResetArbiters(&ctx)
    ctx.keysInNarrow = SoftKeysMayBeCounted(&ctx)
    SoftProfileMark(SOFT_STAGE_PREPARE)
    cpSpaceLock(space)
    # No position update before the narrow phase: this solver moves the
    # bodies inside its substeps.
    SoftCollide(&ctx)
    collided = space.arbiters.num
    cpSpaceUnlock(space, 0)
    SoftProfileMark(SOFT_STAGE_ARBITERS)

    SoftProcessComponents(&ctx, dt, collided)

    cpSpaceLock(space)
    StageFilterArbiterCache(space)
    if ctx.youngPairs >= SOFT_YOUNG_MIN_PAIRS and 2 * ctx.youngPairs > ctx.touchingPairs:
        # Most of the step's contacts are new (a pile built at rest, or
        # dropped at once): none has a warm start or a preload yet, and a
        # tall pile sags while its contacts learn their loads. More
        # substeps carry the load down the pile before it has fallen far.
        SoftSetSubsteps(&ctx, dt, ctx.substeps * SOFT_YOUNG_SUBSTEPS)
    SoftProfileMark(SOFT_STAGE_COMPONENTS)
    if ctx.keysInNarrow and not SoftKeysHold(&ctx):
        ctx.keysInNarrow = 0
    ready = ((ctx.keysInNarrow or SoftGatherBodies(&ctx)) and SoftPrepareJoints(&ctx, prev_dt)
             and SoftPrepareContacts(&ctx, prev_dt))
    SoftProfileMark(SOFT_STAGE_PREPARE)
    if ready and ctx.estimatePending:
        # Two serial passes with nothing in common: on two threads, one
        # each (in order on one). The colouring's buffers are made here
        # first: an allocation's failure is seen by the thread it fails on.
        ready = SoftReserveColors(&ctx)
        if ready:
            SoftRun(&ctx, SOFT_TASK_ESTIMATE_AND_COLOR, 0, 2, 0)
            ready = ctx.colored
    else:
        ready = ready and SoftColorContacts(&ctx)
    SoftProfileMark(SOFT_STAGE_COLOR)
    if ready:
        SoftPrepareLanes(&ctx)
    SoftProfileMark(SOFT_STAGE_PREPARE)
    if ready:
        if ctx.groupCount > 0:
            SoftSubstepGroups(&ctx)
        else:
            for k in range(ctx.substeps):
                SoftRun(&ctx, SOFT_TASK_INTEGRATE_VELOCITIES, 1, ctx.bodyCount, k == ctx.substeps - 1)
                SoftProfileMark(SOFT_STAGE_INTEGRATE)
                SoftJointsWarmStart(&ctx)
                SoftWarmStart(&ctx)
                SoftProfileMark(SOFT_STAGE_WARM_START)
                SoftJointsSolve(&ctx, 1)
                SoftSolve(&ctx, 1)
                SoftProfileMark(SOFT_STAGE_SOLVE)
                SoftRun(&ctx, SOFT_TASK_INTEGRATE_POSITIONS, 1, ctx.bodyCount, 0)
                SoftProfileMark(SOFT_STAGE_INTEGRATE)
                SoftJointsRefresh(&ctx)
                for r in range(SOFT_RELAX_ITERATIONS):
                    SoftJointsSolve(&ctx, 0)
                    SoftRelax(&ctx, r == SOFT_RELAX_ITERATIONS - 1, SoftRelaxSkipsInner(&ctx, k))
                SoftProfileMark(SOFT_STAGE_RELAX)
        if ctx.groupCount > 0 and SoftGroupsFinish(&ctx):
            pass    # (each group finished its own: SoftSubstepGroup)
        elif tamias_load(&ctx.elastic):
            SoftRun(&ctx, SOFT_TASK_UNPACK, 0, ctx.colorLanes[SOFT_GRAPH_COLORS], 0)
            SoftApplyRestitution(&ctx)
            SoftRun(&ctx, SOFT_TASK_STORE, 0, ctx.contactCount, 0)
            SoftRun(&ctx, SOFT_TASK_FINISH_BODIES, 1, ctx.bodyCount, 0)
        else:
            SoftRun(&ctx, SOFT_TASK_UNPACK, 0, ctx.colorLanes[SOFT_GRAPH_COLORS], 1)
            SoftStoreOverflow(&ctx)
            SoftRun(&ctx, SOFT_TASK_FINISH_BODIES, 1, ctx.bodyCount, 0)
        SoftFinishJoints(&ctx)
    if ctx.threaded:
        SoftPoolRelease()
        ctx.threaded = 0
    # (Checked before the post-solve and post-step callbacks, which may add
    # bodies: made from Python, whose setters take finite numbers only.)
    ready = (ready and tamias_load(&ctx.bodiesNonFinite) == 0
             and tamias_load(&ctx.bodiesFinished) == space.dynamicBodies.num)
    StagePostSolve(space)
    cpSpaceUnlock(space, 1)
    SoftProfileMark(SOFT_STAGE_FINISH)
    return ready


# -- test switches -------------------------------------------------------------------------

_LANE_PATHS = {"scalar": SOFT_PATH_SCALAR, "simd": SOFT_PATH_SIMD, "avx2": SOFT_PATH_AVX2}

# The widest kernels this build and this CPU have.
SoftLanesInit()

def _lanes_paths():
    """The contact-kernel paths this build has on this CPU: "scalar" (what
    a compiler without vector extensions builds), "simd" (two doubles:
    SSE2 or NEON) and "avx2" (four doubles, x86-64 CPUs with AVX2)."""
    return tuple(name for name, path in _LANE_PATHS.items() if SoftLanesPathAvailable(path))

def _lane_bias_rates(double contact_rate, double static_rate):
    """For tests: the bias rates the contact kernels take for a lane, by its
    four contacts' write flags (wa, wb: the side is movable), for all 256
    patterns: {(wa, wb): (rate of contact 0, ..., 3)} with wa and wb tuples
    of 0 and 1 (SoftLaneBiasRatesFill's table, soft_lane_rate_index's
    pick)."""
    cdef SoftLaneBiasRates table
    cdef SoftLanes probe
    cdef unsigned int index
    cdef int a, b, k
    SoftLaneBiasRatesFill(&table, contact_rate, static_rate)
    picked = {}
    for a in range(16):
        for b in range(16):
            for k in range(SOFT_LANES):
                probe.wa[k] = (a >> k) & 1
                probe.wb[k] = (b >> k) & 1
            index = soft_lane_rate_index(&probe)
            picked[(tuple((a >> k) & 1 for k in range(SOFT_LANES)),
                    tuple((b >> k) & 1 for k in range(SOFT_LANES)))] = tuple(
                table.rate[index][k] for k in range(SOFT_LANES))
    return picked

def _lanes_path(name=None):
    """The path the contact kernels take (and, given `name`, set it first;
    for tests, which check that all paths give the same bits)."""
    if name is not None:
        if name not in _LANE_PATHS or not SoftLanesSetPath(_LANE_PATHS[name]):
            raise ValueError(f"no contact-kernel path {name!r} here; there are {_lanes_paths()}")
    current = SoftLanesGetPath()
    return next(n for n, p in _LANE_PATHS.items() if p == current)

cdef bint _switch(bint *flag, object on):
    # A test switch: its value, set first to `on` unless that is None.
    if on is not None:
        flag[0] = bool(on)
    return flag[0]

def _arbiter_guesses(on=None):
    """Whether the narrow phase takes a pair's arbiter from the broad
    phase's memory of it (and, given `on`, set it first; for tests, which
    check that without the guesses every step is the same)."""
    return _switch(&_use_guesses, on)

def _relax_skips_inner_lanes(on=None):
    """Whether a substep's extra relax pass leaves out the lanes inside a
    web after the step's first substep (SoftRelaxSkipsInner); with `on`,
    set it (for tests, which compare)."""
    return _switch(&_skip_inner, on)

def _keep_broad_phase_pairs(on=None):
    """Whether the broad phase takes a step's pairs from its last walk over
    the tree when the tree has not changed since (and, given `on`, set it
    first; for tests, which check that walking every step changes nothing)."""
    return _switch(&_keep_pairs, on)

def _reuse_last_colors(on=None):
    """Whether a step takes over the last step's colouring of its contacts
    when their colouring keys are the same (and, given `on`, set it first;
    for tests, which check that colouring every step changes nothing)."""
    return _switch(&_reuse_colors, on)

def _reused_colorings_count():
    """Steps so far (all spaces) that took over the last step's colouring."""
    return tamias_load(&_reused_colorings)

def _skip_leaf_refresh(on=None):
    """Whether the broad phase skips the tree's refresh of its leaves when no
    shape left its leaf's box (and, given `on`, set it first; for tests,
    which check that refreshing every step changes nothing)."""
    return _switch(&_skip_refresh, on)

def _skipped_refreshes_count():
    """Steps so far (all spaces) whose broad phase skipped the leaves' refresh."""
    return tamias_load(&_skipped_refreshes)

def _count_keys_in_narrow(on=None):
    """Whether a soft step on one thread, with no handler that runs before
    the solve, gathers its bodies before the narrow phase and counts the
    colouring keys there (and, given `on`, set it first; for tests, which check that
    the count's own pass gives the same)."""
    return _switch(&_count_in_narrow, on)

def _narrow_counts_count():
    """Steps so far (all spaces) whose keys were counted in the narrow phase."""
    return tamias_load(&_narrow_counts)

def _keep_arbiter_threads(on=None):
    """Whether a soft step leaves last step's arbiters threaded on their
    bodies until it knows whether this step's are the same (and, given `on`,
    set it first; for tests, which check that unthreading every step, as
    Munk2D, changes nothing)."""
    return _switch(&_keep_threads, on)

def _mass_ratio_blocks(on=None):
    """Whether light bodies' contacts are solved as blocks (SoftFindBlocks;
    and, given `on`, set it first; for benchmarks/mass_ratios.py, which
    measures the scenes with and without them in one process)."""
    return _switch(&_use_blocks, on)

def _count_at_least_zero(count):
    # (The test switches' counts.)
    if count < 0:
        raise ValueError("count must be >= 0")
    return count

def _fetch_min_contacts_set(count=None):
    """The fewest arbiters (last step's) with which the soft step's passes
    fetch the records they will read a few items ahead (and, given `count`,
    set it first: 0 always, a huge number never). Returns the value before."""
    global _fetch_min_contacts
    before = _fetch_min_contacts
    if count is not None:
        _fetch_min_contacts = _count_at_least_zero(count)
    return before

def _group_contacts_set(count=None):
    """About how many contacts make a group whose substeps run one group
    after the other (SoftFindGroups; a step groups from twice that many),
    and, given `count`, set it first: 0 never groups, a small number groups
    small scenes (for tests, which check that grouping changes no bits).
    Returns the value before."""
    global _group_contacts
    before = _group_contacts
    if count is not None:
        _group_contacts = _count_at_least_zero(count)
    return before

def _grouped_steps_count():
    """Steps so far (all spaces) whose substeps ran group by group."""
    return tamias_load(&_grouped_steps)

def _threaded_min_contacts_set(count=None):
    """The fewest arbiters (last step's) a threaded space's soft step needs
    to use its second thread (and, given `count`, set it first: 0 runs every
    step of a threaded space on the pool, and every stage of it that can be
    cut in two, however few its lanes, for tests and the fuzzer's
    --threads). Returns the value before."""
    global _threaded_min_contacts
    before = _threaded_min_contacts
    if count is not None:
        _threaded_min_contacts = _count_at_least_zero(count)
    return before

def _link_sleeping_components(on=None):
    """Whether a soft step with sleeping on may tell by union-find that no
    component would fall asleep, and skip the flood fill (and, given `on`,
    set it first; for tests, which check that it changes nothing)."""
    return _switch(&_link_components, on)

def _linked_components_count():
    """Steps so far (all spaces) that skipped the flood fill."""
    return tamias_load(&_linked_components)

def _keep_sleeping_islands(on=None):
    """Whether a soft step with sleeping on may keep the last step's
    components where its contact graph is the same, instead of the
    union-find (and, given `on`, set it first; for tests, which check that
    it changes nothing)."""
    return _switch(&_keep_islands, on)

def _kept_islands_count():
    """Steps so far (all spaces) whose kept components skipped the flood
    fill and the union-find."""
    return tamias_load(&_kept_islands)

def _chain_preload_tilt(share=None):
    """How much of the difference between a two-point chain contact's point
    loads its preloads keep (SOFT_PRELOAD_TILT; and, given `share`, set it
    first; for tests and benchmarks/offset_stacks.py, which compare with 1,
    each point's own load, as before)."""
    global _preload_tilt
    if share is not None:
        if not 0.0 <= share <= 1.0:
            raise ValueError("share must be within [0, 1]")
        _preload_tilt = share
    return _preload_tilt

def _pile_load_estimates(on=None):
    """Whether the soft step works out tall piles' loads from their weights
    (SoftEstimateLoads; and, given `on`, set it first; for tests and
    benchmarks, which compare with the step before it)."""
    return _switch(&_estimate_loads, on)

def _kept_threads_count():
    """Steps so far (all spaces) whose arbiters were left threaded."""
    return tamias_load(&_kept_threads)

def _kept_walks_count():
    """Steps so far (all spaces) that took their pairs from a kept walk."""
    return tamias_load(&_kept_walks)

def _overflow_count():
    """Contacts so far (all spaces) solved one by one, outside the graph's
    colours (a body in more contacts than there are colours, or a contact
    no lane takes)."""
    return tamias_load(&_overflow_total)

def _pool_state():
    """The soft solver's thread pool: (workers started, stages handed out)."""
    return _pool.workers, _pool.generation
