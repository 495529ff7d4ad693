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
push-out speed follow it); overlap is pushed out softly down to the depth at
which a contact carries its load, as in Box2D, not left alone up to the slop.

Beyond Box2D's soft step (docs/stability.md measures each):
  * a two-point manifold's normal rows are solved together (SoftSolve),
    so tall stacks do not buckle from the order the corners are solved in;
  * a loaded point is stiffened for its load (SoftPointSoftness), so the
    bottom of a tall stack or pyramid sinks no deeper than the top;
  * two relax passes per substep (SOFT_RELAX_ITERATIONS).

Layout: bodies are gathered into one contiguous SoftBody array (slot 0 is the
immovable body), contacts into one contiguous SoftContact array, once per
step; the substep loops touch only those arrays (and the joints' structs), no
allocation, no Python except user integrators and joints' callbacks. Graph
colouring and SIMD lanes can partition these arrays later.
"""
from libc.math cimport INFINITY, pow, sqrt, cos, sin, fabs, fmin, fmax
from tamias2d._config cimport cpFloat, cpBool
from tamias2d._structs cimport (cpSpace, cpBody, cpShape, cpArbiter, cpContact, cpArray, cpConstraint,
    cpSoftSettings, cpSoftScratch, TAMIAS_SOLVER_CHIPMUNK, TAMIAS_SOLVER_SOFT,
    CP_BODY_TYPE_KINEMATIC, CP_ARBITER_STATE_FIRST_COLLISION)
from tamias2d._containers cimport cprealloc, cpfree
from tamias2d.vector cimport cpVect, cpv, cpTransformNewTranspose
from tamias2d.body cimport cpBodyGetType, cpBodyUpdateVelocity, cpBodyUpdatePosition
from tamias2d.constraints cimport tamias_constraint_scale_impulse
from tamias2d._space_step cimport (cpSpaceLock, cpSpaceUnlock, StageResetArbiters,
    StageCollide, cpSpaceProcessComponents, StageFilterArbiterCache, StagePostSolve)


# -- settings ------------------------------------------------------------------------

cdef void SoftSettingsInit(cpSoftSettings *settings) noexcept nogil:
    settings.solver = TAMIAS_SOLVER_CHIPMUNK
    settings.substeps = SOFT_DEFAULT_SUBSTEPS
    settings.contactHertz = SOFT_DEFAULT_CONTACT_HERTZ
    settings.contactDampingRatio = SOFT_DEFAULT_CONTACT_DAMPING_RATIO
    settings.pushOut = -1.0
    settings.speculative = -1.0

cdef void SoftScratchFree(cpSoftScratch *scratch) noexcept nogil:
    cpfree(scratch.bodies)
    cpfree(scratch.contacts)
    cpfree(scratch.jointBodies)
    scratch.bodies = NULL
    scratch.contacts = NULL
    scratch.jointBodies = NULL
    scratch.bodyCap = 0
    scratch.contactCap = 0
    scratch.jointBodyCap = 0

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

cdef bint _reserve(void **ptr, int *cap, int need, size_t size) noexcept nogil:
    cdef int n
    cdef void *grown
    if need <= cap[0]:
        return 1
    n = cap[0] * 2 if cap[0] > 0 else 64
    while n < need:
        n *= 2
    grown = cprealloc(ptr[0], <size_t>n * size)
    if grown == NULL:
        return 0  # the out-of-memory flag is up; the step solves nothing
    ptr[0] = grown
    cap[0] = n
    return 1


# -- the step's context -----------------------------------------------------------------

cdef struct SoftContext:
    cpSpace *space
    SoftBody *bodies
    int bodyCount             # slots, the immovable slot 0 included
    SoftContact *contacts
    int contactCount
    int *jointBodies          # slots touched by joints
    int jointBodyCount
    int substeps
    cpFloat h, inv_h
    cpFloat gx, gy
    cpFloat damping           # per substep
    cpFloat pushOut
    SoftSoftness contactSoft  # between two movable bodies
    SoftSoftness staticSoft   # against an immovable one (twice as stiff)

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


# -- gather ----------------------------------------------------------------------------

cdef bint SoftGatherBodies(SoftContext *ctx) noexcept nogil:
    cdef cpSpace *space = ctx.space
    cdef cpArray *arr = space.dynamicBodies
    cdef int n = arr.num + 1
    cdef int i
    cdef SoftBody *sb
    cdef cpBody *body
    if not _reserve(&space.softScratch.bodies, &space.softScratch.bodyCap, n, sizeof(SoftBody)):
        return 0
    ctx.bodies = <SoftBody *>space.softScratch.bodies
    ctx.bodyCount = n
    sb = &ctx.bodies[0]
    sb.vx = sb.vy = sb.w = 0.0
    sb.m_inv = sb.i_inv = 0.0
    sb.dpx = sb.dpy = 0.0
    sb.qc = 1.0
    sb.qs = 0.0
    sb.body = NULL
    sb.flags = 0
    sb.contacts = 0
    for i in range(1, n):
        body = <cpBody *>arr.arr[i - 1]
        body.solverIndex = i
        sb = &ctx.bodies[i]
        sb.vx = body.v.x
        sb.vy = body.v.y
        sb.w = body.w
        sb.m_inv = body.m_inv
        sb.i_inv = body.i_inv
        sb.dpx = sb.dpy = 0.0
        sb.qc = 1.0
        sb.qs = 0.0
        sb.body = body
        sb.flags = 0
        sb.contacts = 0
        if body.velocity_func == cpBodyUpdateVelocity:
            sb.flags |= SOFT_BODY_DEFAULT_VELOCITY
        if body.position_func == cpBodyUpdatePosition:
            sb.flags |= SOFT_BODY_DEFAULT_POSITION
        if cpBodyGetType(body) == CP_BODY_TYPE_KINEMATIC:
            sb.flags |= SOFT_BODY_KINEMATIC
    return 1


# -- joints ------------------------------------------------------------------------------
# The joints are Chipmunk's own, stepped with the substep h: preStep,
# applyCachedImpulse and applyImpulse work on the cpBody structs, so the
# bodies they touch are written out of the arrays before and read back after
# (only those: the contact loops never leave the arrays).

cdef bint SoftPrepareJoints(SoftContext *ctx, cpFloat prev_dt) noexcept nogil:
    cdef cpSpace *space = ctx.space
    cdef cpArray *constraints = space.constraints
    cdef cpConstraint *c
    cdef int i, k, slot
    cdef cpBody *ends[2]
    cdef cpFloat coef = ctx.h / prev_dt if prev_dt != 0.0 else 0.0
    ctx.jointBodyCount = 0
    ctx.jointBodies = NULL
    if constraints.num == 0:
        return 1
    if not _reserve(&space.softScratch.jointBodies, &space.softScratch.jointBodyCap,
                    2 * constraints.num, sizeof(int)):
        return 0
    ctx.jointBodies = <int *>space.softScratch.jointBodies
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        if c.preSolve != NULL:
            c.preSolve(c, space)
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
    return 1

cdef inline void SoftScatterJointBodies(SoftContext *ctx) noexcept nogil:
    cdef int i
    cdef SoftBody *sb
    for i in range(ctx.jointBodyCount):
        sb = &ctx.bodies[ctx.jointBodies[i]]
        sb.body.v.x = sb.vx
        sb.body.v.y = sb.vy
        sb.body.w = sb.w

cdef inline void SoftGatherJointBodies(SoftContext *ctx) noexcept nogil:
    cdef int i
    cdef SoftBody *sb
    for i in range(ctx.jointBodyCount):
        sb = &ctx.bodies[ctx.jointBodies[i]]
        sb.vx = sb.body.v.x
        sb.vy = sb.body.v.y
        sb.w = sb.body.w

cdef void SoftJointsWarmStart(SoftContext *ctx) noexcept nogil:
    cdef cpArray *constraints = ctx.space.constraints
    cdef cpConstraint *c
    cdef int i
    if constraints.num == 0:
        return
    SoftScatterJointBodies(ctx)
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        c.klass.preStep(c, ctx.h)
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        c.klass.applyCachedImpulse(c, 1.0)
    SoftGatherJointBodies(ctx)

cdef void SoftJointsSolve(SoftContext *ctx) noexcept nogil:
    cdef cpArray *constraints = ctx.space.constraints
    cdef cpConstraint *c
    cdef int i
    if constraints.num == 0:
        return
    SoftScatterJointBodies(ctx)
    for i in range(constraints.num):
        c = <cpConstraint *>constraints.arr[i]
        c.klass.applyImpulse(c, ctx.h)
    SoftGatherJointBodies(ctx)

cdef void SoftFinishJoints(SoftContext *ctx) noexcept nogil:
    # Back to a per-step impulse (what Constraint.impulse reports and the
    # next step, of either solver, warm-starts from).
    cdef cpArray *constraints = ctx.space.constraints
    cdef int i
    for i in range(constraints.num):
        tamias_constraint_scale_impulse(<cpConstraint *>constraints.arr[i], <cpFloat>ctx.substeps)


# -- contacts ------------------------------------------------------------------------------

cdef inline cpFloat SoftShapeSize(cpShape *shape) noexcept nogil:
    # The smaller side of the bounding box of a movable body's shape; 0 for
    # an immovable one (a ground segment's thickness says nothing).
    if shape.body.m_inv == 0.0 and shape.body.i_inv == 0.0:
        return 0.0
    return fmin(shape.bb.r - shape.bb.l, shape.bb.t - shape.bb.b)

cdef inline cpFloat SoftContactSize(cpArbiter *arb) noexcept nogil:
    cdef cpFloat sa = SoftShapeSize(arb.a)
    cdef cpFloat sb = SoftShapeSize(arb.b)
    if sa == 0.0:
        return sb
    if sb == 0.0:
        return sa
    return fmin(sa, sb)

cdef inline cpFloat SoftMaxStiffening(SoftBody *a, SoftBody *b) noexcept nogil:
    # How much stiffer than the base a loaded contact may become: in a
    # chain, between bodies of alike mass (or against an immovable one) a
    # lot; where a
    # light body carries a heavy one the Gauss-Seidel passes no longer
    # converge on a stiff contact and the pair starts to bounce, so little.
    cdef cpFloat lo, hi
    if (a.body != NULL and a.contacts > 2) or (b.body != NULL and b.contacts > 2):
        # Not in a chain (a stack, an arch, a body on a body): in a web of
        # contacts, a pyramid's, stiff contacts make Gauss-Seidel shake it
        # apart (stiffness alone settles pyramids; a chain converges).
        return 1.0
    if a.m_inv == 0.0 or b.m_inv == 0.0:
        return SOFT_MAX_STIFFENING
    lo = fmin(a.m_inv, b.m_inv)
    hi = fmax(a.m_inv, b.m_inv)
    return fmax(SOFT_MIN_STIFFENING_CAP, SOFT_MAX_STIFFENING * (lo / hi))

cdef inline void SoftPointSoftness(SoftPoint *sp, SoftSoftness *base, cpFloat load,
                                   cpFloat size, cpFloat maxStiffening, cpFloat h) noexcept nogil:
    # A soft contact settles where its bias balances the impulse it leaks:
    # (compliance / normalMass) * impulse = biasRate * depth. Under a load F
    # (impulse F h per substep) it sinks compliance F h / (normalMass
    # biasRate) deep, so the bottom of a tall stack or
    # pyramid, or a light body under a heavy one, would sink far more than
    # the top. A point whose (filtered) load would sink it deeper than
    # SOFT_MAX_LOAD_DEFLECTION x `size` leaks less (a smaller compliance); its bias
    # rate, which sets how fast overlap is pushed out, stays. That is the
    # implicit spring-damper with stiffness and damping both scaled up by
    # the same factor, so its damping ratio is kept.
    cdef cpFloat c, need
    cdef SoftSoftness s = base[0]
    c = s.impulseScale / s.massScale if s.massScale > 0.0 else 0.0
    if load > 0.0 and c > 0.0 and size > 0.0:
        need = SOFT_MAX_LOAD_DEFLECTION * size * sp.normalMass * s.biasRate / (load * h)
        if need < c / maxStiffening:
            need = c / maxStiffening
        if need < c:
            c = need
            s.massScale = 1.0 / (1.0 + c)
            s.impulseScale = c / (1.0 + c)
    sp.biasRate = s.biasRate
    sp.massScale = s.massScale
    sp.impulseScale = s.impulseScale
    sp.compliance = c


cdef bint SoftPrepareContacts(SoftContext *ctx, cpFloat prev_dt) noexcept nogil:
    cdef cpSpace *space = ctx.space
    cdef cpArray *arbiters = space.arbiters
    cdef int i, j, n = 0
    cdef cpArbiter *arb
    cdef cpContact *con
    cdef SoftContact *sc
    cdef SoftPoint *sp
    cdef SoftBody *a
    cdef SoftBody *b
    cdef SoftSoftness soft
    cdef cpFloat nx, ny, rnA, rnB, rtA, rtB, kN, kT, sep, warm, size, load
    cdef cpFloat maxStiffening
    cdef cpFloat warmCoef = ctx.h / prev_dt if prev_dt != 0.0 else 0.0
    cdef cpFloat loadCoef = 1.0 / prev_dt if prev_dt != 0.0 else 0.0
    if not _reserve(&space.softScratch.contacts, &space.softScratch.contactCap,
                    arbiters.num, sizeof(SoftContact)):
        return 0
    ctx.contacts = <SoftContact *>space.softScratch.contacts
    # Each body's number of contacts: a contact is stiffened for its load
    # only where both of its bodies have at most two (SoftMaxStiffening).
    for i in range(arbiters.num):
        arb = <cpArbiter *>arbiters.arr[i]
        if arb.count <= 0 or arb.contacts == NULL:
            continue
        ctx.bodies[SoftIndex(arb.body_a, ctx.bodies, ctx.bodyCount)].contacts += 1
        ctx.bodies[SoftIndex(arb.body_b, ctx.bodies, ctx.bodyCount)].contacts += 1
    for i in range(arbiters.num):
        arb = <cpArbiter *>arbiters.arr[i]
        if arb.count <= 0 or arb.contacts == NULL:
            continue
        sc = &ctx.contacts[n]
        sc.arb = arb
        sc.ia = SoftIndex(arb.body_a, ctx.bodies, ctx.bodyCount)
        sc.ib = SoftIndex(arb.body_b, ctx.bodies, ctx.bodyCount)
        a = &ctx.bodies[sc.ia]
        b = &ctx.bodies[sc.ib]
        sc.count = arb.count if arb.count <= 2 else 2
        size = SoftContactSize(arb)
        maxStiffening = SoftMaxStiffening(a, b)
        nx = arb.n.x
        ny = arb.n.y
        sc.nx = nx
        sc.ny = ny
        sc.friction = arb.u
        sc.restitution = arb.e
        # Chipmunk adds surface_vr to the relative velocity; only its
        # tangential part is used for friction.
        sc.surfaceT = -arb.surface_vr.x * ny + arb.surface_vr.y * nx
        soft = (ctx.staticSoft if (a.m_inv == 0.0 and a.i_inv == 0.0)
                or (b.m_inv == 0.0 and b.i_inv == 0.0) else ctx.contactSoft)
        sc.block = 0
        # Chipmunk skips the warm start of an arbiter's first step.
        warm = 0.0 if arb.state == CP_ARBITER_STATE_FIRST_COLLISION else warmCoef
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
            load = con.jBias + SOFT_LOAD_SMOOTHING * (con.jnAcc * loadCoef - con.jBias)
            if warm == 0.0:
                load = 0.0
            SoftPointSoftness(sp, &soft, load, size, maxStiffening, ctx.h)
            # Separation now, less the anchors' part, which the solver adds
            # back from the bodies' motion within the step.
            sep = ((sp.rBx - sp.rAx + arb.body_b.p.x - arb.body_a.p.x) * nx
                   + (sp.rBy - sp.rAy + arb.body_b.p.y - arb.body_a.p.y) * ny)
            sp.baseSeparation = sep - ((sp.rBx - sp.rAx) * nx + (sp.rBy - sp.rAy) * ny)
            sp.relativeVelocity = ((b.vx - b.w * sp.rBy - a.vx + a.w * sp.rAy) * nx
                                   + (b.vy + b.w * sp.rBx - a.vy - a.w * sp.rAx) * ny)
            sp.normalImpulse = con.jnAcc * warm
            sp.tangentImpulse = con.jtAcc * warm
            sp.totalNormal = 0.0
            sp.totalTangent = 0.0
            sp.maxNormalImpulse = 0.0
            # Chipmunk's fields, for Arbiter.total_ke and the like.
            con.nMass = sp.normalMass
            con.tMass = sp.tangentMass
            con.bias = 0.0
            con.jBias = load
            con.bounce = sp.relativeVelocity * arb.e
        if sc.count == 2:
            SoftPrepareBlock(sc, a, b)
        n += 1
    ctx.contactCount = n
    return 1

# Above this condition number the two normal rows are nearly dependent (the
# points almost coincide) and are solved one after the other instead.
cdef const cpFloat SOFT_BLOCK_MAX_CONDITION = 1000.0

cdef inline void SoftPrepareBlock(SoftContact *sc, SoftBody *a, SoftBody *b) noexcept nogil:
    # The 2x2 normal mass matrix. Solving both points of a manifold at once
    # (as Box2D 2.x's block solver) keeps a box resting on two corners from
    # being tipped by the order in which they are solved: the sequential
    # order is what lets tall stacks buckle.
    cdef SoftPoint *p1 = &sc.p[0]
    cdef SoftPoint *p2 = &sc.p[1]
    cdef cpFloat rnA1 = p1.rnA
    cdef cpFloat rnB1 = p1.rnB
    cdef cpFloat rnA2 = p2.rnA
    cdef cpFloat rnB2 = p2.rnB
    cdef cpFloat mm = a.m_inv + b.m_inv
    sc.k11 = mm + a.i_inv * rnA1 * rnA1 + b.i_inv * rnB1 * rnB1
    sc.k22 = mm + a.i_inv * rnA2 * rnA2 + b.i_inv * rnB2 * rnB2
    sc.k12 = mm + a.i_inv * rnA1 * rnA2 + b.i_inv * rnB1 * rnB2
    sc.block = (sc.k11 > 0.0 and sc.k22 > 0.0 and
                sc.k11 * sc.k11 < SOFT_BLOCK_MAX_CONDITION * (sc.k11 * sc.k22 - sc.k12 * sc.k12))

cdef void SoftWarmStart(SoftContext *ctx) noexcept nogil:
    cdef int i, j
    cdef SoftContact *sc
    cdef SoftPoint *sp
    cdef SoftBody *a
    cdef SoftBody *b
    cdef cpFloat px, py, nx, ny
    for i in range(ctx.contactCount):
        sc = &ctx.contacts[i]
        a = &ctx.bodies[sc.ia]
        b = &ctx.bodies[sc.ib]
        nx = sc.nx
        ny = sc.ny
        for j in range(sc.count):
            sp = &sc.p[j]
            # P = normalImpulse n + tangentImpulse perp(n)
            px = sp.normalImpulse * nx - sp.tangentImpulse * ny
            py = sp.normalImpulse * ny + sp.tangentImpulse * nx
            a.vx -= a.m_inv * px
            a.vy -= a.m_inv * py
            a.w -= a.i_inv * (sp.rAx * py - sp.rAy * px)
            b.vx += b.m_inv * px
            b.vy += b.m_inv * py
            b.w += b.i_inv * (sp.rBx * py - sp.rBy * px)

cdef void SoftSolve(SoftContext *ctx, bint useBias) noexcept nogil:
    # One Gauss-Seidel pass over the contacts: with useBias the soft,
    # biased solve; without it the rigid relax pass, which also solves
    # friction. Velocities along n and t are a shared linear part plus each
    # point's angular part (cross products prepared once per step).
    cdef int i, j
    cdef SoftContact *sc
    cdef SoftPoint *sp
    cdef SoftPoint *p1
    cdef SoftPoint *p2
    cdef SoftBody *a
    cdef SoftBody *b
    cdef cpFloat nx, ny, dx, dy, s, lin, vn, vt, imp, newImp, maxF
    cdef cpFloat prAx, prAy, prBx, prBy
    cdef cpFloat inv_h = ctx.inv_h
    cdef cpFloat pushOut = ctx.pushOut
    cdef cpFloat vax, vay, wa, vbx, vby, wb, mA, iA, mB, iB
    cdef cpFloat a11, a22, a12, x01, x02, q1, q2, det, x1, x2, d1, d2
    cdef cpFloat bias[2]
    cdef cpFloat gamma[2]      # a soft row's compliance (0: rigid)
    for i in range(ctx.contactCount):
        sc = &ctx.contacts[i]
        a = &ctx.bodies[sc.ia]
        b = &ctx.bodies[sc.ib]
        vax = a.vx
        vay = a.vy
        wa = a.w
        vbx = b.vx
        vby = b.vy
        wb = b.w
        mA = a.m_inv
        iA = a.i_inv
        mB = b.m_inv
        iB = b.i_inv
        nx = sc.nx
        ny = sc.ny
        for j in range(sc.count):
            sp = &sc.p[j]
            # The current separation from the bodies' motion in this step.
            prAx = a.qc * sp.rAx - a.qs * sp.rAy
            prAy = a.qs * sp.rAx + a.qc * sp.rAy
            prBx = b.qc * sp.rBx - b.qs * sp.rBy
            prBy = b.qs * sp.rBx + b.qc * sp.rBy
            dx = (b.dpx - a.dpx) + (prBx - prAx)
            dy = (b.dpy - a.dpy) + (prBy - prAy)
            s = dx * nx + dy * ny + sp.baseSeparation
            if s > 0.0:
                # Speculative: let the gap close within the substep, no push.
                bias[j] = s * inv_h
                gamma[j] = 0.0
            elif useBias:
                # Overlap is pushed out softly, at most at pushOut.
                bias[j] = sp.biasRate * s
                if bias[j] < -pushOut:
                    bias[j] = -pushOut
                gamma[j] = sp.compliance
            else:
                bias[j] = 0.0
                gamma[j] = 0.0
        if sc.block:
            # Both normal rows at once: the linear complementarity problem
            # w = A x + q, x >= 0, w >= 0, x.w = 0 for the accumulated
            # impulses x, with A = K + diag(k_ii gamma_i) and
            # q = vn + bias - K x0. A soft row's added diagonal is the soft
            # constraint written as a compliance: (k + k gamma) dx =
            # -(vn + bias) - k gamma x0 is the sequential massScale /
            # impulseScale update exactly. Cases in Box2D 2.x's order.
            p1 = &sc.p[0]
            p2 = &sc.p[1]
            lin = (vbx - vax) * nx + (vby - vay) * ny
            x01 = p1.normalImpulse
            x02 = p2.normalImpulse
            a12 = sc.k12
            a11 = sc.k11 * (1.0 + gamma[0])
            a22 = sc.k22 * (1.0 + gamma[1])
            q1 = (lin + wb * p1.rnB - wa * p1.rnA + bias[0]
                  - (sc.k11 * x01 + a12 * x02))
            q2 = (lin + wb * p2.rnB - wa * p2.rnA + bias[1]
                  - (a12 * x01 + sc.k22 * x02))
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
        else:
            for j in range(sc.count):
                sp = &sc.p[j]
                # (k + k gamma) dx = -(vn + bias) - k gamma x0, k = 1 / normalMass
                vn = ((vbx - vax) * nx + (vby - vay) * ny) + wb * sp.rnB - wa * sp.rnA
                imp = (-(sp.normalMass * (vn + bias[j]) + gamma[j] * sp.normalImpulse)
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
        # Slot 0 (immovable) takes no impulse: its inverse masses are 0.
        a.vx = vax
        a.vy = vay
        a.w = wa
        b.vx = vbx
        b.vy = vby
        b.w = wb

cdef inline void SoftRelax(SoftContext *ctx) noexcept nogil:
    SoftSolve(ctx, 0)

cdef void SoftAccumulate(SoftContext *ctx) noexcept nogil:
    # The impulse a substep applied is its accumulated impulse after the
    # relax pass (the warm start re-applies the previous one).
    cdef int i, j
    cdef SoftContact *sc
    for i in range(ctx.contactCount):
        sc = &ctx.contacts[i]
        for j in range(sc.count):
            sc.p[j].totalNormal += sc.p[j].normalImpulse
            sc.p[j].totalTangent += sc.p[j].tangentImpulse

cdef void SoftApplyRestitution(SoftContext *ctx) noexcept nogil:
    # After the substeps: points that were approaching at the step's start
    # and took an impulse get e times that approach speed back, in one pass.
    # No threshold: Chipmunk bounces at any speed.
    cdef int i, j
    cdef SoftContact *sc
    cdef SoftPoint *sp
    cdef SoftBody *a
    cdef SoftBody *b
    cdef cpFloat nx, ny, e, vn, imp, newImp, px, py
    for i in range(ctx.contactCount):
        sc = &ctx.contacts[i]
        e = sc.restitution
        if e == 0.0:
            continue
        a = &ctx.bodies[sc.ia]
        b = &ctx.bodies[sc.ib]
        nx = sc.nx
        ny = sc.ny
        for j in range(sc.count):
            sp = &sc.p[j]
            if sp.relativeVelocity >= 0.0 or sp.maxNormalImpulse == 0.0:
                continue
            vn = ((b.vx - b.w * sp.rBy - a.vx + a.w * sp.rAy) * nx
                  + (b.vy + b.w * sp.rBx - a.vy - a.w * sp.rAx) * ny)
            imp = -sp.normalMass * (vn + e * sp.relativeVelocity)
            newImp = sp.normalImpulse + imp
            if newImp < 0.0:
                newImp = 0.0
            imp = newImp - sp.normalImpulse
            sp.normalImpulse = newImp
            sp.totalNormal += imp
            px = imp * nx
            py = imp * ny
            a.vx -= a.m_inv * px
            a.vy -= a.m_inv * py
            a.w -= a.i_inv * (sp.rAx * py - sp.rAy * px)
            b.vx += b.m_inv * px
            b.vy += b.m_inv * py
            b.w += b.i_inv * (sp.rBx * py - sp.rBy * px)

cdef void SoftStoreImpulses(SoftContext *ctx) noexcept nogil:
    # jnAcc / jtAcc hold the impulse of the whole step, as in the chipmunk
    # solver: Arbiter.total_impulse reads them, and the next step warm-starts
    # each substep with (h / dt) of them.
    cdef int i, j
    cdef SoftContact *sc
    cdef cpContact *con
    for i in range(ctx.contactCount):
        sc = &ctx.contacts[i]
        for j in range(sc.count):
            con = &sc.arb.contacts[j]
            con.jnAcc = sc.p[j].totalNormal
            con.jtAcc = sc.p[j].totalTangent


# -- integration ---------------------------------------------------------------------------

cdef void SoftIntegrateVelocities(SoftContext *ctx, bint last) noexcept nogil:
    cdef int i
    cdef SoftBody *sb
    cdef cpBody *body
    cdef cpFloat damping = ctx.damping
    cdef cpFloat h = ctx.h
    cdef cpVect f
    cdef cpFloat t
    for i in range(1, ctx.bodyCount):
        sb = &ctx.bodies[i]
        body = sb.body
        if sb.flags & SOFT_BODY_DEFAULT_VELOCITY:
            if sb.flags & SOFT_BODY_KINEMATIC:
                continue
            # cpBodyUpdateVelocity's arithmetic; the force applies in every
            # substep and is cleared when the step ends.
            sb.vx = sb.vx * damping + (ctx.gx + body.f.x * sb.m_inv) * h
            sb.vy = sb.vy * damping + (ctx.gy + body.f.y * sb.m_inv) * h
            sb.w = sb.w * damping + body.t * sb.i_inv * h
        else:
            body.v.x = sb.vx
            body.v.y = sb.vy
            body.w = sb.w
            f = body.f
            t = body.t
            body.velocity_func(body, cpv(ctx.gx, ctx.gy), damping, h)
            sb.vx = body.v.x
            sb.vy = body.v.y
            sb.w = body.w
            if not last:
                # Body.update_velocity clears the force: keep it for the
                # remaining substeps.
                body.f = f
                body.t = t

cdef void SoftIntegratePositions(SoftContext *ctx) noexcept nogil:
    cdef int i
    cdef SoftBody *sb
    cdef cpBody *body
    cdef cpFloat h = ctx.h
    cdef cpFloat dx, dy, da, qc, qs, mag, px0, py0, a0
    for i in range(1, ctx.bodyCount):
        sb = &ctx.bodies[i]
        body = sb.body
        if sb.flags & SOFT_BODY_DEFAULT_POSITION:
            dx = sb.vx * h
            dy = sb.vy * h
            da = sb.w * h
            body.p.x = body.p.x + dx
            body.p.y = body.p.y + dy
            body.a = body.a + da
        else:
            body.v.x = sb.vx
            body.v.y = sb.vy
            body.w = sb.w
            px0 = body.p.x
            py0 = body.p.y
            a0 = body.a
            body.position_func(body, h)
            dx = body.p.x - px0
            dy = body.p.y - py0
            da = body.a - a0
            sb.vx = body.v.x
            sb.vy = body.v.y
            sb.w = body.w
        sb.dpx += dx
        sb.dpy += dy
        # The step's rotation, advanced by da and renormalised (no trig).
        qc = sb.qc - da * sb.qs
        qs = sb.qs + da * sb.qc
        mag = sqrt(qc * qc + qs * qs)
        if mag > 0.0:
            mag = 1.0 / mag
        sb.qc = qc * mag
        sb.qs = qs * mag
        if sb.flags & SOFT_BODY_JOINTED:
            # The joints' preStep reads the transform.
            SoftSetTransform(body)

cdef void SoftFinishBodies(SoftContext *ctx) noexcept nogil:
    cdef int i
    cdef SoftBody *sb
    cdef cpBody *body
    for i in range(1, ctx.bodyCount):
        sb = &ctx.bodies[i]
        body = sb.body
        body.v.x = sb.vx
        body.v.y = sb.vy
        body.w = sb.w
        body.v_bias = cpv(0.0, 0.0)
        body.w_bias = 0.0
        if (sb.flags & SOFT_BODY_DEFAULT_VELOCITY) and not (sb.flags & SOFT_BODY_KINEMATIC):
            body.f = cpv(0.0, 0.0)
            body.t = 0.0
        SoftSetTransform(body)


# -- the step -----------------------------------------------------------------------------

cdef void cpSoftStep(cpSpace *space, cpFloat dt) noexcept nogil:
    cdef SoftContext ctx
    cdef cpFloat prev_dt
    cdef cpFloat hertz, staticHertz
    cdef int collided, k, r
    cdef bint ready
    if dt == 0.0:
        return
    space.stamp += 1
    prev_dt = space.curr_dt
    space.curr_dt = dt

    ctx.space = space
    ctx.substeps = space.soft.substeps if space.soft.substeps >= 1 else 1
    ctx.h = dt / ctx.substeps
    ctx.inv_h = 1.0 / ctx.h
    ctx.gx = space.gravity.x
    ctx.gy = space.gravity.y
    ctx.damping = pow(space.damping, ctx.h)
    ctx.pushOut = SoftPushOut(space)
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
    ctx.contactCount = 0
    ctx.jointBodyCount = 0
    space.collideMargin = SoftSpeculative(space)

    StageResetArbiters(space)
    cpSpaceLock(space)
    # No position update before the narrow phase: this solver moves the
    # bodies inside its substeps.
    StageCollide(space)
    collided = space.arbiters.num
    cpSpaceUnlock(space, 0)

    cpSpaceProcessComponents(space, dt, collided)

    cpSpaceLock(space)
    StageFilterArbiterCache(space)
    ready = (SoftGatherBodies(&ctx) and SoftPrepareJoints(&ctx, prev_dt)
             and SoftPrepareContacts(&ctx, prev_dt))
    if ready:
        for k in range(ctx.substeps):
            SoftIntegrateVelocities(&ctx, k == ctx.substeps - 1)
            SoftJointsWarmStart(&ctx)
            SoftWarmStart(&ctx)
            SoftJointsSolve(&ctx)
            SoftSolve(&ctx, 1)
            SoftIntegratePositions(&ctx)
            for r in range(SOFT_RELAX_ITERATIONS):
                SoftJointsSolve(&ctx)
                SoftRelax(&ctx)
            SoftAccumulate(&ctx)
        SoftApplyRestitution(&ctx)
        SoftStoreImpulses(&ctx)
        SoftFinishBodies(&ctx)
        SoftFinishJoints(&ctx)
    StagePostSolve(space)
    cpSpaceUnlock(space, 1)
