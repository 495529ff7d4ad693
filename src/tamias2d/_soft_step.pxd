# The soft solver (Space.solver = "soft"): Box2D v3's "soft step" re-thought
# for Chipmunk's API and units. See _soft_step.pyx for the step; the shared
# stages (collision, arbiter cache, components and sleeping, callbacks) are
# _space_step's.
#
# cpSoftStep is a pipeline, in this order (* : on the pool of a threaded
# space, see "threads within one step" in _soft_step.pyx):
#   SoftResetArbiters       StageResetArbiters (shared), or last step's
#                           arbiters left threaded on their bodies
#   SoftKeysMayBeCounted    on one thread, without handlers: SoftGatherBodies
#                           here, and the count in the narrow phase
#                           (SoftKeyAccepted) instead of below
#   SoftCollide             broad phase lists the pairs (speculative margin;
#                           or the last walk's, kept); * cheap rejection,
#                           narrow phase and the lookup of cached arbiters;
#                           arbiters and begin / pre_solve callbacks in the
#                           broad phase's order (on one thread without those
#                           callbacks, within the narrow phase, pair by pair)
#   SoftRethreadArbiters    unthread last step's arbiters if this step's differ
#   cpSpaceProcessComponents, StageFilterArbiterCache       (shared)
#   SoftGatherBodies        * awake bodies into SoftBody / SoftState / SoftMotion
#                           arrays (velocity; acceleration and position)
#   SoftPrepareJoints       joint pre-solve callbacks, warm-start rescale
#   SoftPrepareContacts     * each body's contact count, each contact's
#                           bodies and colouring key (SoftCountRange)
#   SoftColorContacts       the constraint graph's colours; which contact
#                           goes in which slot of SoftLanes (_soft_lanes.h)
#   SoftPrepareLanes        * each coloured contact prepared (SoftPrepareContact:
#                           each point's softness for its load, the 2x2
#                           block matrices) straight into its lane slot; the
#                           others into a SoftContact array
#   per substep (h = dt / substeps), colour by colour for the contacts:
#     SoftIntegrateVelocities  * gravity, damping, forces, velocity_func
#     SoftWarmStart            last substep's impulses (joints, * contacts)
#     SoftSolve(useBias=1)     joints, * soft contacts (normal rows only)
#     SoftIntegratePositions   * position_func, delta position / rotation
#     SoftRelax x2             SoftSolve without bias (rigid), with friction;
#                              the last adds the impulses to the step's totals
#   * SoftUnpackLanes, SoftApplyRestitution, * SoftStoreImpulses (without
#   restitution: * SoftUnpackLanes straight into the arbiters),
#   * SoftFinishBodies (velocities, positions, transforms to the cpBodies;
#   each checked for non-finite numbers), SoftFinishJoints
#   StagePostSolve, unlock (post-step callbacks)            (shared)
from tamias2d._config cimport cpFloat, cpBool
from tamias2d._structs cimport (cpSpace, cpBody, cpArbiter, cpContact, cpSoftSettings, cpSoftScratch,
    cpSoftness)
from tamias2d.vector cimport cpVect

# Defaults (DESIGN.md "Two solvers"; Box2D v3's values, lengths expressed in
# collision_slop so that a scaled scene behaves the same).
cdef enum:
    SOFT_DEFAULT_SUBSTEPS = 4
cdef const cpFloat SOFT_DEFAULT_CONTACT_HERTZ = 30.0
cdef const cpFloat SOFT_DEFAULT_CONTACT_DAMPING_RATIO = 10.0
# Joints: Box2D v3's world defaults (jointHertz, jointDampingRatio).
cdef const cpFloat SOFT_DEFAULT_JOINT_HERTZ = 60.0
cdef const cpFloat SOFT_DEFAULT_JOINT_DAMPING_RATIO = 2.0
# Max push-out speed = this x collision_slop per second (60 units/s for the
# default slop 0.1; Box2D's 3 m/s is 600 of its 0.005 m slops per second).
cdef const cpFloat SOFT_PUSH_OUT_PER_SLOP = 600.0
# Speculative distance = this x collision_slop (Box2D: 4 linear slops).
cdef const cpFloat SOFT_SPECULATIVE_PER_SLOP = 4.0
# Relax passes (rigid, no bias) per substep. Box2D runs one; a second one
# takes out the push-out velocity that one Gauss-Seidel pass leaves in big
# pyramids and under heavy bodies, where it shows as jitter, and holds
# stacks, arches and card houses that a nudge would rock over. Inside a web
# of contacts (a contact whose bodies are each immovable or in more than
# SOFT_INNER_CONTACTS contacts: the inside of a pyramid of touching boxes or
# of a pile) the extra pass is needed only in a step's first substep, where
# the narrow phase's new separations come in (SoftRelax). (More than three
# contacts was the same for the hard cases, but let one card house of the
# sweep in benchmarks/card_house_sweep.py fall.)
cdef enum:
    SOFT_RELAX_ITERATIONS = 2
    SOFT_INNER_CONTACTS = 4
# Restitution passes at most (SoftApplyRestitution), Chipmunk's default
# iterations; a pass after the first applies only impulses above this
# fraction of the step's largest bounce (times the point's mass).
cdef enum:
    SOFT_RESTITUTION_PASSES = 10
cdef const cpFloat SOFT_RESTITUTION_TOLERANCE = 1e-6
# A point whose approach speed is within this fraction of the step's
# largest bounce was at rest (resting contacts keep from closing in the
# restitution passes); so was one within the speed gravity gives a body in
# one step, where a body falls under it (SoftRestingSpeed).
cdef const cpFloat SOFT_RESTING_FRACTION = 1e-3
# A loaded contact point is preloaded: its soft spring holds this fraction of
# its (filtered) load at no depth (SoftPreload) in a chain, where both bodies
# have at most two contacts (stacks, arches, a box on a box) ...
cdef const cpFloat SOFT_PRELOAD_CHAIN = 1.0
# ... where a chain's contact has two points, their preloads keep this much
# of the difference between the two points' loads (SoftPrepareContact). Each
# point's preload follows its own load, which makes it an integral action on
# the box's tilt, and that, lagging, rocked stacks that did not stand exactly
# on centre: a 10-box stack with its boxes 0.1% of a box off centre rocked
# itself over. The mean load, which holds the weight, is kept whole.
cdef const cpFloat SOFT_PRELOAD_TILT = 0.5
# ... and this fraction in a web of contacts (a pyramid's), whose loads are
# not fixed by the bodies' weights: with all of it there the loads wander
# from contact to contact and a 40-row pyramid never comes to rest ...
cdef const cpFloat SOFT_PRELOAD_WEB = 0.7
# ... and none between bodies whose masses differ more than this where they
# are solved one contact after the other (a block too large for
# SoftSolveBlock): a heavy body on a light one bounces on a preloaded
# contact, as Gauss-Seidel does not converge there within a step. Such a
# point is stiffened instead so that its load sinks it at most
# SOFT_MAX_LOAD_DEFLECTION of the smaller body's size, up to
# SOFT_RATIO_STIFFENING times (SoftPointSoftness).
cdef const cpFloat SOFT_PRELOAD_MAX_RATIO = 300.0
# The web preload (SOFT_PRELOAD_WEB) gives way where a body carries more
# than this many times its own weight: there each contact that holds it up
# is preloaded with its share of the weights above, worked out from the top
# of the pile down (SoftEstimateLoads), a load that follows no contact's
# impulse and so cannot wander. That takes away the rest of a tall
# pyramid's sag (0.3 of its springs' under the web preload): a 60-row
# pyramid of 20-unit boxes under g 900 sank 0.69 box, and 0.02 with it.
# The estimate takes over by degrees, all of the preload from
# SOFT_ESTIMATE_FULL_CARRY: switched at once, the boxes at the boundary (a
# 40-row pyramid's left flank) kept rocking, where they now come to rest
# sooner than before. Below, a card house's flat card keeps the web
# preload: the estimate shares the card's load equally among its supports,
# though one of them only nearly touches, and tipped it over.
cdef const cpFloat SOFT_ESTIMATE_MIN_CARRY = 3.0
cdef const cpFloat SOFT_ESTIMATE_FULL_CARRY = 6.0
# A contact holds a body up (SoftEstimateLoads) where its push on it points
# within 60 degrees of up (this cosine) and its bodies are within the slop.
cdef const cpFloat SOFT_HOLD_MIN_LIFT = 0.5
# A body with a movable neighbour this many times heavier is light: the
# rows of all the contacts of the light bodies that touch (a block) are
# solved together, exactly (SoftSolveBlock), in place of one contact after
# the other, which takes about the ratio in passes to carry a heavy body's
# weight through a light one (and meanwhile the heavy body sinks into it).
# A block's contacts are fully preloaded (SoftPreload).
cdef const cpFloat SOFT_BLOCK_RATIO = 30.0
# Blocks of up to this many rows (a normal and a tangent row per contact
# point); the contacts of a larger one are solved one by one, as any.
cdef enum:
    SOFT_BLOCK_ROWS = 48
# A body no heavier than a light one it touches is light too (it carries the
# heavy load), up to this many contacts from a heavy body.
cdef enum:
    SOFT_BLOCK_SPREAD = 4
# Solves a block's pivoting may take before it gives up (SoftBlockPivot):
# the pass then solves that block's contacts one by one.
cdef enum:
    SOFT_BLOCK_PIVOTS = 64
cdef const cpFloat SOFT_MAX_LOAD_DEFLECTION = 0.005
cdef const cpFloat SOFT_RATIO_STIFFENING = 5.0
# The load moves this fraction of the way to the last step's load per step
# (a low-pass filter).
cdef const cpFloat SOFT_LOAD_SMOOTHING = 0.1
# A point's first steps average its loads instead (1 / age), up to this age.
cdef const cpFloat SOFT_LOAD_AGE = 10.0
# A step where at least SOFT_YOUNG_MIN_PAIRS touching pairs, and more than
# half of them, are younger than SOFT_YOUNG_AGE steps takes SOFT_YOUNG_SUBSTEPS
# times the substeps (cpSoftStep; the pairs are counted with the bounding-box
# tree, the default index, not with a spatial hash).
cdef const cpFloat SOFT_YOUNG_AGE = 3.0
cdef enum:
    SOFT_YOUNG_MIN_PAIRS = 64
    SOFT_YOUNG_SUBSTEPS = 4
# The broad phase's reach (SoftSetReach) is set to SOFT_REACH_ROOM times the
# fastest body's travel in a step when that travel outgrows it, and brought
# down again when the travel is less than 1 / SOFT_REACH_SHRINK of it.
cdef const cpFloat SOFT_REACH_ROOM = 1.5
cdef const cpFloat SOFT_REACH_SHRINK = 6.0

# Flags of a SoftBody.
cdef enum:
    SOFT_BODY_DEFAULT_VELOCITY = 1   # velocity_func is cpBodyUpdateVelocity
    SOFT_BODY_DEFAULT_POSITION = 2   # position_func is cpBodyUpdatePosition
    SOFT_BODY_KINEMATIC = 4
    SOFT_BODY_JOINTED = 8            # in a joint: cpBody kept current per substep
    SOFT_BODY_MOVABLE = 16           # of finite mass or moment: contacts write to it (SoftMovable)

# Contacts are coloured so that no two of one colour share a movable body
# (Box2D's constraint graph, b2_graphColorCount); those that fit no colour,
# and two-point manifolds too ill-conditioned for the block solve, are the
# overflow, solved one by one after the colours.
cdef enum:
    SOFT_GRAPH_COLORS = 24
    SOFT_GRAPH_COLOR_MASK = (1 << SOFT_GRAPH_COLORS) - 1   # fits a body's uint32_t of colours

# The kernels over lanes of contacts (SoftState, SoftLanes): _soft_lanes.h.
cdef extern from "_soft_lanes.h" nogil:
    enum: SOFT_LANES
    ctypedef struct SoftState:
        cpFloat vx, vy, w
        cpFloat m_inv
        cpFloat dpx, dpy
        cpFloat qc, qs
    ctypedef struct SoftLanes:
        int points
        unsigned char inner[SOFT_LANES]
        int ia[SOFT_LANES]
        int ib[SOFT_LANES]
        unsigned char wa[SOFT_LANES]
        unsigned char wb[SOFT_LANES]
        cpFloat iA[SOFT_LANES]
        cpFloat iB[SOFT_LANES]
        cpFloat nx[SOFT_LANES]
        cpFloat ny[SOFT_LANES]
        cpFloat friction[SOFT_LANES]
        cpFloat surfaceT[SOFT_LANES]
        cpFloat k11[SOFT_LANES]
        cpFloat rAx[2][SOFT_LANES]
        cpFloat rAy[2][SOFT_LANES]
        cpFloat rBx[2][SOFT_LANES]
        cpFloat rBy[2][SOFT_LANES]
        cpFloat base[2][SOFT_LANES]
        cpFloat compliance[2][SOFT_LANES]
        cpFloat preload[2][SOFT_LANES]
        cpFloat normalImpulse[2][SOFT_LANES]
        cpFloat tangentImpulse[2][SOFT_LANES]
        cpFloat totalNormal[2][SOFT_LANES]
        cpFloat totalTangent[2][SOFT_LANES]
    ctypedef struct SoftLaneLinks:
        int src[SOFT_LANES]
        void *dst[SOFT_LANES]
        cpFloat maxNormalImpulse[2][SOFT_LANES]
    ctypedef struct SoftLaneBiasRates:
        cpFloat rate[16][SOFT_LANES]
    void SoftLaneBiasRatesFill(SoftLaneBiasRates *t, cpFloat contactRate, cpFloat staticRate)
    unsigned int soft_lane_rate_index(const SoftLanes *c)
    void SoftLanesClear(SoftLanes *c, SoftLaneLinks *x, int k)
    # n lanes from c (trackMax: keep maxNormalImpulse, which only restitution
    # reads; fetch: fetch the bodies' states a few lanes ahead)
    void SoftLanesWarmStart(SoftLanes *c, int n, SoftState *st, int fetch)
    void SoftLanesSolve(SoftLanes *c, SoftLaneLinks *x, int n, SoftState *st,
                        const SoftLaneBiasRates *rates, cpFloat inv_h,
                        cpFloat pushOut, int useBias, int accumulate, int trackMax, int fetch,
                        int skipInner)
    enum: SOFT_PATH_SCALAR, SOFT_PATH_SIMD, SOFT_PATH_AVX2
    void SoftLanesInit()
    int SoftLanesPathAvailable(int path)
    int SoftLanesGetPath()
    int SoftLanesSetPath(int path)

# One awake body during a soft step, beside its SoftState (same slot). Slot
# 0 stands for every body the step does not move (static, sleeping,
# removed): zero velocity, infinite mass.
cdef struct SoftBody:
    cpFloat m_inv, i_inv
    cpBody *body
    int flags
    int contacts              # arbiters touching it this step (SoftPrepareContacts)

# What integrating a body with the default velocity and position functions
# needs beside its SoftState (same slot): the step's acceleration (gravity
# plus the force, and the torque, over the mass: constant over the
# substeps) and its position, kept here and written to the cpBody when the
# step ends (or every substep where a joint or a velocity_func reads it),
# so the substeps do not touch the cpBody structs.
cdef struct SoftMotion:
    cpFloat ax, ay, alpha
    cpFloat px, py, a

# One contact point: anchors from the centres of gravity (fixed for the
# step), the separation with the anchors' offset removed (Box2D's adjusted
# separation), masses and impulses.
cdef struct SoftPoint:
    cpFloat rAx, rAy, rBx, rBy
    cpFloat rnA, rnB, rtA, rtB                # cross(r, n), cross(r, tangent) = r . n
    cpFloat baseSeparation
    cpFloat normalMass, tangentMass
    cpFloat normalImpulse, tangentImpulse     # this substep's (warm start)
    cpFloat totalNormal, totalTangent         # over the step (-> jnAcc, jtAcc)
    cpFloat maxNormalImpulse
    cpFloat relativeVelocity                  # normal speed at the step's start
    cpFloat biasRate                          # softness (SoftSoftness) of this point:
    cpFloat compliance                        # impulseScale / massScale
    cpFloat preload                           # the impulse it holds at no depth (SoftPreload)

# One arbiter's contact constraint, prepared once per step.
cdef struct SoftContact:
    int ia, ib                # SoftBody / SoftState slots
    int count                 # 1 or 2 points
    cpContact *dst            # arb.contacts, read with the slots (not through arb)
    cpFloat nx, ny
    cpFloat friction, restitution
    cpFloat surfaceT          # surface velocity along the tangent
    cpFloat k11, k12, k22     # normal effective-mass matrix of a two-point manifold
    bint block                # solve the two normal rows together (well conditioned)
    bint inBlock              # its rows are solved in a block with others (SoftSolveBlock)
    SoftPoint p[2]
    cpArbiter *arb

# b2MakeSoft: stiffness `hertz` and damping ratio `zeta` at step h.
# A soft constraint's coefficients (the same struct the joints take).
ctypedef cpSoftness SoftSoftness

cdef SoftSoftness SoftMakeSoft(cpFloat hertz, cpFloat zeta, cpFloat h) noexcept nogil

cdef void SoftSettingsInit(cpSoftSettings *settings) noexcept nogil
cdef void SoftScratchFree(cpSoftScratch *scratch) noexcept nogil
# The effective settings (the automatic ones derived from collision_slop).
cdef cpFloat SoftPushOut(const cpSpace *space) noexcept nogil
cdef cpFloat SoftSpeculative(const cpSpace *space) noexcept nogil

cdef bint cpSoftStep(cpSpace *space, cpFloat dt) noexcept nogil
# Start the worker thread of threaded soft steps if it is not running (GIL).
cdef int SoftPoolEnsure() except -1
