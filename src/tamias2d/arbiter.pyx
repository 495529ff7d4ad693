"""Arbiters: the persistent record of two touching shapes.

An arbiter lives from the step two shapes start to touch until a few steps
after they part (the space's collision persistence). It holds their contacts,
the accumulated impulses that warm-start the next step, and the combined
material values. The space creates, caches and recycles arbiters; Python code
sees them only as :class:`Arbiter` views handed to collision callbacks and
``Body.each_arbiter``.
"""
from libc.math cimport INFINITY, isfinite
from tamias2d._config cimport (cpFloat, cpBool, cpHashValue, cpCollisionType,
    CP_HASH_PAIR_ORDERED, CP_WILDCARD_COLLISION_TYPE, CP_MAX_CONTACTS_PER_ARBITER)
from tamias2d._structs cimport (cpArbiter, cpArbiterThread, cpBody, cpShape, cpSpace,
    cpContact, cpCollisionInfo, cpCollisionHandler, cpContactPointSet,
    CP_ARBITER_STATE_FIRST_COLLISION, CP_ARBITER_STATE_NORMAL,
    CP_ARBITER_STATE_CACHED, CP_ARBITER_STATE_INVALIDATED)
from tamias2d._containers cimport cpHashSetFind
from tamias2d.vector cimport (cpVect, cpv, cpvadd, cpvsub, cpvneg, cpvmult, cpvdot,
    cpvperp, cpvrotate, cpfmin, cpfmax, cpfclamp, vec2d_from_cpv, cpv_from_object)
from tamias2d.collision cimport (k_scalar, normal_relative_velocity, relative_velocity,
    apply_impulses, apply_bias_impulses, ContactPointSet, contact_point_set_from_cp)
from tamias2d.errors import Tamias2DError


cdef cpFloat _coefficient_arg(object value, str what) except? -1.0:
    # Finite and >= 0, as Shape.friction / Shape.elasticity: NaN or inf here
    # turns into NaN impulses, a negative friction pushes a resting body.
    cdef cpFloat x = value
    if not (x >= 0.0 and x < INFINITY):
        raise ValueError(f"{what} must be a finite number >= 0, got {value!r}")
    return x


# -- the empty handler ----------------------------------------------------------

cdef void cpCollisionDoNothing(cpArbiter *arb, cpSpace *space, void *data) noexcept nogil:
    pass

cdef cpCollisionHandler _do_nothing_handler
_do_nothing_handler.typeA = CP_WILDCARD_COLLISION_TYPE
_do_nothing_handler.typeB = CP_WILDCARD_COLLISION_TYPE
_do_nothing_handler.beginFunc = cpCollisionDoNothing
_do_nothing_handler.preSolveFunc = cpCollisionDoNothing
_do_nothing_handler.postSolveFunc = cpCollisionDoNothing
_do_nothing_handler.separateFunc = cpCollisionDoNothing
_do_nothing_handler.userData = NULL

cdef cpCollisionHandler *cpCollisionHandlerDoNothing() noexcept nogil:
    return &_do_nothing_handler


# -- per-body arbiter lists ------------------------------------------------------

cdef inline void unthreadHelper(cpArbiter *arb, cpBody *body) noexcept nogil:
    cdef cpArbiterThread *thread = cpArbiterThreadForBody(arb, body)
    cdef cpArbiter *prev = thread.prev
    cdef cpArbiter *next = thread.next
    if prev != NULL:
        cpArbiterThreadForBody(prev, body).next = next
    elif body.arbiterList == arb:
        # Only the head may reset the list: an arbiter that was never threaded
        # has prev == NULL too.
        body.arbiterList = next
    if next != NULL:
        cpArbiterThreadForBody(next, body).prev = prev
    thread.prev = NULL
    thread.next = NULL

cdef void cpArbiterUnthread(cpArbiter *arb) noexcept nogil:
    unthreadHelper(arb, arb.body_a)
    unthreadHelper(arb, arb.body_b)

cdef void cpArbiterDropThreads(cpArbiter *arb) noexcept nogil:
    # Every list arb is on is being emptied (all their arbiters go): clear
    # both bodies' heads and arb's links instead of unlinking neighbours.
    if arb.body_a != NULL:
        arb.body_a.arbiterList = NULL
    if arb.body_b != NULL:
        arb.body_b.arbiterList = NULL
    arb.thread_a.prev = arb.thread_a.next = NULL
    arb.thread_b.prev = arb.thread_b.next = NULL


# -- accessors -------------------------------------------------------------------

cdef cpBool cpArbiterIsFirstContact(const cpArbiter *arb) noexcept nogil:
    return arb.state == CP_ARBITER_STATE_FIRST_COLLISION

cdef cpBool cpArbiterIsRemoval(const cpArbiter *arb) noexcept nogil:
    return arb.state == CP_ARBITER_STATE_INVALIDATED

cdef int cpArbiterGetCount(const cpArbiter *arb) noexcept nogil:
    # No contacts in a separate callback (CACHED or INVALIDATED).
    return arb.count if arb.state < CP_ARBITER_STATE_CACHED else 0

cdef cpVect cpArbiterGetNormal(const cpArbiter *arb) noexcept nogil:
    return cpvmult(arb.n, -1.0 if arb.swapped else 1.0)

cdef cpVect cpArbiterGetPointA(const cpArbiter *arb, int i) noexcept nogil:
    return cpvadd(arb.body_a.p, arb.contacts[i].r1)

cdef cpVect cpArbiterGetPointB(const cpArbiter *arb, int i) noexcept nogil:
    return cpvadd(arb.body_b.p, arb.contacts[i].r2)

cdef cpFloat cpArbiterGetDepth(const cpArbiter *arb, int i) noexcept nogil:
    cdef cpContact *con = &arb.contacts[i]
    return cpvdot(cpvadd(cpvsub(con.r2, con.r1), cpvsub(arb.body_b.p, arb.body_a.p)), arb.n)

cdef cpContactPointSet cpArbiterGetContactPointSet(const cpArbiter *arb) noexcept nogil:
    cdef cpContactPointSet set
    cdef int i
    cdef cpVect p1, p2
    cdef cpBool swapped = arb.swapped
    cdef cpVect n = arb.n
    set.count = cpArbiterGetCount(arb)
    set.normal = cpvneg(n) if swapped else n
    for i in range(set.count):
        # Offsets are kept relative to the bodies' centres of gravity.
        p1 = cpvadd(arb.body_a.p, arb.contacts[i].r1)
        p2 = cpvadd(arb.body_b.p, arb.contacts[i].r2)
        set.points[i].pointA = p2 if swapped else p1
        set.points[i].pointB = p1 if swapped else p2
        set.points[i].distance = cpvdot(cpvsub(p2, p1), n)
    return set

cdef cpBool cpArbiterSetContactPointSet(cpArbiter *arb, cpContactPointSet *set) noexcept nogil:
    cdef int i
    cdef int count = set.count
    cdef cpVect p1, p2
    cdef cpBool swapped = arb.swapped
    if count != arb.count:
        return 0
    arb.n = cpvneg(set.normal) if swapped else set.normal
    for i in range(count):
        p1 = set.points[i].pointA
        p2 = set.points[i].pointB
        arb.contacts[i].r1 = cpvsub(p2 if swapped else p1, arb.body_a.p)
        arb.contacts[i].r2 = cpvsub(p1 if swapped else p2, arb.body_b.p)
    return 1

cdef cpVect cpArbiterTotalImpulse(const cpArbiter *arb) noexcept nogil:
    cdef cpContact *contacts = arb.contacts
    cdef cpVect n = arb.n
    cdef cpVect sum = cpv(0.0, 0.0)
    cdef int i
    cdef int count = cpArbiterGetCount(arb)
    for i in range(count):
        sum = cpvadd(sum, cpvrotate(n, cpv(contacts[i].jnAcc, contacts[i].jtAcc)))
    return sum if arb.swapped else cpvneg(sum)

cdef cpFloat cpArbiterTotalKE(const cpArbiter *arb) noexcept nogil:
    cdef cpFloat eCoef = (1 - arb.e) / (1 + arb.e)
    cdef cpFloat sum = 0.0
    cdef cpFloat jnAcc, jtAcc
    cdef int i
    cdef int count = cpArbiterGetCount(arb)
    cdef cpContact *con
    for i in range(count):
        con = &arb.contacts[i]
        jnAcc = con.jnAcc
        jtAcc = con.jtAcc
        sum += eCoef * jnAcc * jnAcc / con.nMass + jtAcc * jtAcc / con.tMass
    return sum

cdef cpVect cpArbiterGetSurfaceVelocity(cpArbiter *arb) noexcept nogil:
    return cpvmult(arb.surface_vr, -1.0 if arb.swapped else 1.0)

cdef void cpArbiterSetSurfaceVelocity(cpArbiter *arb, cpVect vr) noexcept nogil:
    arb.surface_vr = cpvmult(vr, -1.0 if arb.swapped else 1.0)

cdef void cpArbiterGetShapes(const cpArbiter *arb, cpShape **a, cpShape **b) noexcept nogil:
    if arb.swapped:
        a[0] = <cpShape *>arb.b
        b[0] = <cpShape *>arb.a
    else:
        a[0] = <cpShape *>arb.a
        b[0] = <cpShape *>arb.b

cdef void cpArbiterGetBodies(const cpArbiter *arb, cpBody **a, cpBody **b) noexcept nogil:
    cdef cpShape *shape_a
    cdef cpShape *shape_b
    cpArbiterGetShapes(arb, &shape_a, &shape_b)
    a[0] = shape_a.body
    b[0] = shape_b.body


# -- life cycle --------------------------------------------------------------------

cdef cpArbiter *cpArbiterInit(cpArbiter *arb, cpShape *a, cpShape *b) noexcept nogil:
    arb.swapped = 0
    arb.handlerAB = NULL
    arb.handlerBA = NULL
    arb.handlerA = NULL
    arb.handlerB = NULL
    arb.e = 0.0
    arb.u = 0.0
    arb.surface_vr = cpv(0.0, 0.0)
    arb.count = 0
    arb.contacts = NULL
    arb.a = a
    arb.body_a = a.body
    arb.b = b
    arb.body_b = b.body
    arb.thread_a.next = NULL
    arb.thread_b.next = NULL
    arb.thread_a.prev = NULL
    arb.thread_b.prev = NULL
    arb.stamp = 0
    arb.state = CP_ARBITER_STATE_FIRST_COLLISION
    arb.processCollision = 1
    arb.cached = 0
    arb.data = NULL
    arb.handlerVersion = 0
    arb.softThreaded = 0
    arb.softNoted = 0
    return arb

cdef inline cpCollisionHandler *cpSpaceLookupHandler(cpSpace *space, cpCollisionType a,
                                                    cpCollisionType b) noexcept nogil:
    cdef cpCollisionType types[2]
    types[0] = a
    types[1] = b
    cdef cpCollisionHandler *handler = <cpCollisionHandler *>cpHashSetFind(
        space.collisionHandlers, CP_HASH_PAIR_ORDERED(a, b), types)
    return handler if handler != NULL else &_do_nothing_handler

cdef void cpArbiterUpdate(cpArbiter *arb, cpCollisionInfo *info, cpSpace *space) noexcept nogil:
    cdef const cpShape *a = info.a
    cdef const cpShape *b = info.b
    cdef cpArbiterThread thread
    cdef int i, j
    cdef cpContact *con
    cdef cpContact *old
    cdef cpVect surface_vr
    cdef cpCollisionType typeA, typeB

    # Same-type pairs may come in the other order than last step. (Not
    # Munk2D's: the threads of the bodies' arbiter lists change places with
    # the bodies, so that an arbiter still in the lists stays consistent;
    # the soft solver keeps its arbiters threaded through the collision
    # when the step's arbiters turn out the same, _soft_step.pyx.)
    if arb.a != a:
        thread = arb.thread_a
        arb.thread_a = arb.thread_b
        arb.thread_b = thread
    arb.a = a
    arb.body_a = a.body
    arb.b = b
    arb.body_b = b.body

    for i in range(info.count):
        con = &info.arr[i]
        # The narrow phase stores absolute points; the solver wants offsets
        # from the centres of gravity.
        con.r1 = cpvsub(con.r1, a.body.p)
        con.r2 = cpvsub(con.r2, b.body.p)
        con.jnAcc = 0.0
        con.jtAcc = 0.0
        # The chipmunk solver sets bias and zeroes jBias in its pre-step; the
        # soft solver keeps a point's age and load in them from step to step.
        con.jBias = 0.0
        con.bias = 0.0
        # Warm start: take the impulses of an old contact with the same
        # feature hash; the last match wins.
        for j in range(arb.count):
            old = &arb.contacts[j]
            if con.hash == old.hash:
                con.jnAcc = old.jnAcc
                con.jtAcc = old.jtAcc
                con.jBias = old.jBias
                con.bias = old.bias

    arb.contacts = info.arr
    arb.count = info.count
    arb.n = info.n

    arb.e = a.e * b.e
    arb.u = a.u * b.u

    surface_vr = cpvsub(b.surfaceV, a.surfaceV)
    arb.surface_vr = cpvsub(surface_vr, cpvmult(info.n, cpvdot(surface_vr, info.n)))

    typeA = info.a.type
    typeB = info.b.type
    if (arb.handlerVersion != space.handlerVersion or arb.handlerTypeA != typeA
            or arb.handlerTypeB != typeB):
        # (Else the same four lookups as last time: no handler was added
        # since and the types are the same.)
        arb.handlerAB = cpSpaceLookupHandler(space, typeA, typeB)
        arb.handlerA = cpSpaceLookupHandler(space, typeA, CP_WILDCARD_COLLISION_TYPE)
        if typeA != typeB:
            arb.handlerBA = cpSpaceLookupHandler(space, typeB, typeA)
        else:
            arb.handlerBA = &_do_nothing_handler
        arb.handlerB = cpSpaceLookupHandler(space, typeB, CP_WILDCARD_COLLISION_TYPE)
        arb.handlerVersion = space.handlerVersion
        arb.handlerTypeA = typeA
        arb.handlerTypeB = typeB
    # (Every time: the handler calls turn `swapped` over and back.)
    arb.swapped = (typeA != arb.handlerAB.typeA
                   and arb.handlerAB.typeA != CP_WILDCARD_COLLISION_TYPE)

    # A cached arbiter touching again is a new collision: re-arm it.
    if arb.state == CP_ARBITER_STATE_CACHED:
        arb.state = CP_ARBITER_STATE_FIRST_COLLISION
        arb.processCollision = 1


# -- solver ------------------------------------------------------------------------

cdef void cpArbiterPreStep(cpArbiter *arb, cpFloat dt, cpFloat slop, cpFloat bias) noexcept nogil:
    cdef cpBody *a = arb.body_a
    cdef cpBody *b = arb.body_b
    cdef cpVect n = arb.n
    cdef cpVect body_delta = cpvsub(b.p, a.p)
    cdef int i
    cdef cpContact *con
    cdef cpFloat dist
    for i in range(arb.count):
        con = &arb.contacts[i]
        con.nMass = 1.0 / k_scalar(a, b, con.r1, con.r2, n)
        con.tMass = 1.0 / k_scalar(a, b, con.r1, con.r2, cpvperp(n))
        dist = cpvdot(cpvadd(cpvsub(con.r2, con.r1), body_delta), n)
        con.bias = -bias * cpfmin(0.0, dist + slop) / dt
        con.jBias = 0.0
        con.bounce = normal_relative_velocity(a, b, con.r1, con.r2, n) * arb.e

cdef void cpArbiterApplyCachedImpulse(cpArbiter *arb, cpFloat dt_coef) noexcept nogil:
    if arb.state == CP_ARBITER_STATE_FIRST_COLLISION:
        return
    cdef cpBody *a = arb.body_a
    cdef cpBody *b = arb.body_b
    cdef cpVect n = arb.n
    cdef int i
    cdef cpContact *con
    cdef cpVect j
    for i in range(arb.count):
        con = &arb.contacts[i]
        j = cpvrotate(n, cpv(con.jnAcc, con.jtAcc))
        apply_impulses(a, b, con.r1, con.r2, cpvmult(j, dt_coef))

cdef void cpArbiterApplyImpulse(cpArbiter *arb) noexcept nogil:
    cdef cpBody *a = arb.body_a
    cdef cpBody *b = arb.body_b
    cdef cpVect n = arb.n
    cdef cpVect surface_vr = arb.surface_vr
    cdef cpFloat friction = arb.u
    cdef int i
    cdef cpContact *con
    cdef cpFloat nMass, vbn, vrn, vrt, jbn, jbnOld, jn, jnOld, jtMax, jt, jtOld
    cdef cpVect r1, r2, vb1, vb2, vr
    for i in range(arb.count):
        con = &arb.contacts[i]
        nMass = con.nMass
        r1 = con.r1
        r2 = con.r2

        vb1 = cpvadd(a.v_bias, cpvmult(cpvperp(r1), a.w_bias))
        vb2 = cpvadd(b.v_bias, cpvmult(cpvperp(r2), b.w_bias))
        vr = cpvadd(relative_velocity(a, b, r1, r2), surface_vr)

        vbn = cpvdot(cpvsub(vb2, vb1), n)
        vrn = cpvdot(vr, n)
        vrt = cpvdot(vr, cpvperp(n))

        jbn = (con.bias - vbn) * nMass
        jbnOld = con.jBias
        con.jBias = cpfmax(jbnOld + jbn, 0.0)

        jn = -(con.bounce + vrn) * nMass
        jnOld = con.jnAcc
        con.jnAcc = cpfmax(jnOld + jn, 0.0)

        jtMax = friction * con.jnAcc
        jt = -vrt * con.tMass
        jtOld = con.jtAcc
        con.jtAcc = cpfclamp(jtOld + jt, -jtMax, jtMax)

        apply_bias_impulses(a, b, r1, r2, cpvmult(n, con.jBias - jbnOld))
        apply_impulses(a, b, r1, r2, cpvrotate(n, cpv(con.jnAcc - jnOld, con.jtAcc - jtOld)))


# -- Python view ------------------------------------------------------------------

cdef Arbiter arbiter_wrap(cpArbiter *arb, object space):
    cdef Arbiter obj = Arbiter.__new__(Arbiter)
    obj._arbiter = arb
    obj._space = space
    return obj


cdef class Arbiter:
    """The collision of two shapes, as a callback sees it.

    The space hands an Arbiter to collision callbacks (``begin``,
    ``pre_solve``, ``post_solve``, ``separate``) and to
    ``Body.each_arbiter``. It is a view of data the space owns and recycles:
    read what you need inside the callback and do not keep it. Once the space
    has dropped the underlying arbiter, reading the view raises an error
    instead of returning stale data from a recycled pair.

    >>> import tamias2d
    >>> space = tamias2d.Space()
    >>> body = tamias2d.Body(1, 10)
    >>> space.add(body, tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5))
    >>> seen = []
    >>> space.on_collision(begin=lambda arb, space, data: seen.append(len(arb.shapes)))
    >>> space.step(0.1)
    >>> seen
    [2]
    """

    def __init__(self, *args, **kwargs):
        raise TypeError("Arbiter objects are created by the Space; they cannot be built directly")

    cdef cpArbiter *_get(self) except NULL:
        cdef cpArbiter *arb = self._arbiter
        # The space clears the shape pointers of an arbiter it recycles.
        if arb == NULL or arb.a == NULL:
            raise Tamias2DError(
                "This Arbiter is no longer valid: the space has recycled it. "
                "Copy what you need out of an Arbiter inside the callback.")
        return arb

    @property
    def process_collision(self):
        """Whether the space solves this collision (``True`` by default).

        Set it to False in ``begin`` or ``pre_solve`` to let the shapes pass
        through each other. The value sticks until the shapes separate; it
        is reset to True the next time they start touching.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> space.add(body, tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5))
        >>> def begin(arb, space, data):
        ...     arb.process_collision = False
        >>> space.on_collision(begin=begin)
        >>> space.step(0.1)
        >>> body.velocity
        Vec2d(0.0, 0.0)
        """
        return bool(self._get().processCollision)

    @process_collision.setter
    def process_collision(self, v):
        self._get().processCollision = 1 if v else 0

    @property
    def contact_point_set(self):
        """The contact points of the collision as a :class:`ContactPointSet`.

        The normal and points are given in the order of :attr:`shapes`.
        Assigning a ContactPointSet with the same number of points moves the
        contacts (in ``pre_solve``, to change how the collision is solved).

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> body.position = 8, 0
        >>> space.add(body, tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5))
        >>> out = []
        >>> space.on_collision(pre_solve=lambda arb, s, d: out.append(arb.contact_point_set))
        >>> space.step(0.01)
        >>> len(out[0].points)
        1
        """
        cdef cpContactPointSet cps = cpArbiterGetContactPointSet(self._get())
        return contact_point_set_from_cp(&cps)

    @contact_point_set.setter
    def contact_point_set(self, point_set):
        cdef cpArbiter *arb = self._get()
        cdef cpContactPointSet cps = cpArbiterGetContactPointSet(arb)
        cdef int i
        points = point_set.points
        if len(points) != cps.count:
            raise ValueError(
                f"Expected {cps.count} points, got {len(points)} points in point_set")
        normal = cpv_from_object(point_set.normal)
        for i in range(cps.count):
            # pymunk 7.3 copies points[0] into every slot here (a bug); each
            # point is taken from its own slot instead.
            cps.points[i].pointA = cpv_from_object(points[i].point_a)
            cps.points[i].pointB = cpv_from_object(points[i].point_b)
            cps.points[i].distance = points[i].distance
        cps.normal = normal
        if not cpArbiterSetContactPointSet(arb, &cps):
            # Only in a separate callback: the arbiter has no contacts to set.
            raise ValueError("The number of contact points cannot be changed.")

    @property
    def bodies(self):
        """The two bodies of the collision, in the order of :attr:`shapes`.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> space.add(body, tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5))
        >>> out = []
        >>> space.on_collision(begin=lambda arb, s, d: out.append(arb.bodies))
        >>> space.step(0.01)
        >>> body in out[0] and space.static_body in out[0]
        True
        """
        a, b = self.shapes
        return a.body, b.body

    @property
    def shapes(self):
        """The two shapes of the collision.

        The order follows the collision handler: for a handler registered
        for types (A, B), the first shape has type A.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> c1 = tamias2d.Circle(body, 5)
        >>> c1.collision_type = 1
        >>> c2 = tamias2d.Circle(space.static_body, 5)
        >>> c2.collision_type = 2
        >>> space.add(body, c1, c2)
        >>> out = []
        >>> space.on_collision(2, 1, begin=lambda arb, s, d: out.append(arb.shapes))
        >>> space.step(0.01)
        >>> out[0] == (c2, c1)
        True
        """
        cdef cpShape *a
        cdef cpShape *b
        cpArbiterGetShapes(self._get(), &a, &b)
        return <object>a.userData, <object>b.userData

    @property
    def restitution(self):
        """The restitution (elasticity) used for this collision.

        By default the product of the two shapes' elasticities; set it in
        ``pre_solve`` to override it for this step.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> c1, c2 = tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5)
        >>> c1.elasticity, c2.elasticity = 0.5, 0.5
        >>> space.add(body, c1, c2)
        >>> out = []
        >>> space.on_collision(pre_solve=lambda arb, s, d: out.append(arb.restitution))
        >>> space.step(0.01)
        >>> out
        [0.25]
        """
        return self._get().e

    @restitution.setter
    def restitution(self, restitution):
        self._get().e = _coefficient_arg(restitution, "restitution")

    @property
    def friction(self):
        """The friction coefficient used for this collision.

        By default the product of the two shapes' frictions; set it in
        ``pre_solve`` to override it for this step.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> c1, c2 = tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5)
        >>> c1.friction, c2.friction = 0.5, 0.5
        >>> space.add(body, c1, c2)
        >>> out = []
        >>> space.on_collision(pre_solve=lambda arb, s, d: out.append(arb.friction))
        >>> space.step(0.01)
        >>> out
        [0.25]
        """
        return self._get().u

    @friction.setter
    def friction(self, friction):
        self._get().u = _coefficient_arg(friction, "friction")

    @property
    def surface_velocity(self):
        """The relative surface velocity used for this collision.

        By default the difference of the shapes' surface velocities, keeping
        only its part along the contact tangent. Set it in ``pre_solve`` to
        override it.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> space.add(body, tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5))
        >>> out = []
        >>> space.on_collision(pre_solve=lambda arb, s, d: out.append(arb.surface_velocity))
        >>> space.step(0.01)
        >>> out
        [Vec2d(0.0, 0.0)]
        """
        return vec2d_from_cpv(cpArbiterGetSurfaceVelocity(self._get()))

    @surface_velocity.setter
    def surface_velocity(self, velocity):
        cdef cpVect v = cpv_from_object(velocity)
        # a non-finite surface velocity reaches the bodies as NaN impulses
        if not (isfinite(v.x) and isfinite(v.y)):
            raise ValueError(f"surface_velocity must be finite, got ({v.x!r}, {v.y!r})")
        cpArbiterSetSurfaceVelocity(self._get(), v)

    @property
    def total_impulse(self):
        """The impulse applied this step to resolve the collision.

        Meaningful in ``post_solve`` or ``Body.each_arbiter`` after a step.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> space.gravity = 0, -10
        >>> body = tamias2d.Body(1, 10)
        >>> body.position = 0, 9
        >>> space.add(body, tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5))
        >>> out = []
        >>> space.on_collision(post_solve=lambda arb, s, d: out.append(arb.total_impulse))
        >>> space.step(0.01)
        >>> out[0].y != 0
        True
        """
        return vec2d_from_cpv(cpArbiterTotalImpulse(self._get()))

    @property
    def total_ke(self):
        """The kinetic energy lost in the collision (including static but
        not dynamic friction). Meaningful in ``post_solve``.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> body.position = 0, 9
        >>> body.velocity = 0, -10
        >>> space.add(body, tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5))
        >>> out = []
        >>> space.on_collision(post_solve=lambda arb, s, d: out.append(arb.total_ke))
        >>> space.step(0.01)
        >>> out[0] > 0
        True
        """
        return cpArbiterTotalKE(self._get())

    @property
    def is_first_contact(self):
        """True in the first step the two shapes touch.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> space.add(body, tamias2d.Circle(body, 5), tamias2d.Circle(space.static_body, 5))
        >>> out = []
        >>> space.on_collision(pre_solve=lambda arb, s, d: out.append(arb.is_first_contact))
        >>> space.step(0.01); space.step(0.01)
        >>> out
        [True, False]
        """
        return bool(cpArbiterIsFirstContact(self._get()))

    @property
    def is_removal(self):
        """True in a ``separate`` callback caused by removing a shape.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> c = tamias2d.Circle(body, 5)
        >>> space.add(body, c, tamias2d.Circle(space.static_body, 5))
        >>> out = []
        >>> space.on_collision(separate=lambda arb, s, d: out.append(arb.is_removal))
        >>> space.step(0.01)
        >>> space.remove(c)
        >>> out
        [True]
        """
        return bool(cpArbiterIsRemoval(self._get()))

    @property
    def normal(self):
        """The collision normal, pointing from the first shape to the second.

        >>> import tamias2d
        >>> space = tamias2d.Space()
        >>> body = tamias2d.Body(1, 10)
        >>> body.position = 8, 0
        >>> space.add(body, tamias2d.Circle(space.static_body, 5), tamias2d.Circle(body, 5))
        >>> out = []
        >>> space.on_collision(pre_solve=lambda arb, s, d: out.append(arb.normal))
        >>> space.step(0.01)
        >>> abs(out[0].x)
        1.0
        """
        return vec2d_from_cpv(cpArbiterGetNormal(self._get()))

    def __repr__(self):
        if self._arbiter == NULL or self._arbiter.a == NULL:
            return "Arbiter(<recycled>)"
        a, b = self.shapes
        return f"Arbiter({a!r}, {b!r})"
