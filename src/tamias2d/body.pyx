# Rigid Body module (MIS section 6): the C body of Munk2D's cpBody.c and the
# body half of cpSpaceComponent.c, then the Python Body with pymunk 7.3's API.
# Arithmetic keeps the C association exactly, so results match pymunk bit for
# bit; see munk2d-inventory.md, group 4. The test hooks that run the integrators
# through the C function pointers (_run_velocity_func, _run_position_func) are
# in _testing.
"""Rigid bodies: mass, moment of inertia, position, angle and their rates.

A :class:`Body` is one of three types. A dynamic body (the default) is moved
by forces, gravity and collisions; a kinematic body moves only at the
velocity the program gives it and pushes dynamic bodies without being pushed
back; a static body does not move (each space has one, ``space.static_body``,
for the ground and walls). Shapes attached to a body give it its collision
geometry and, when they have a density or mass, its mass and moment.

>>> import tamias2d
>>> body = tamias2d.Body(2, tamias2d.moment_for_circle(2, 0, 1))
>>> body.body_type == tamias2d.Body.DYNAMIC
True
>>> body.apply_impulse_at_local_point((4, 0))
>>> body.velocity
Vec2d(2.0, 0.0)
"""
import copyreg
import weakref

from tamias2d._weakkeysview import WeakKeysView

from cpython.ref cimport PyObject, Py_INCREF
from libc.math cimport INFINITY, isfinite
from libc.stdint cimport uintptr_t
from libc.string cimport memset

from tamias2d._config cimport cpFloat, cpBool
from tamias2d._pickle cimport (snapshot_module as _snapshot, pymunk_getstate, pymunk_setstate,
    pymunk_reduce, deep_copy)
from tamias2d._structs cimport (cpBody, cpShape, cpSpace, cpArbiter, cpBodyType,
    cpConstraint, cpArbiterThread, cpShapeMassInfo,
    CP_BODY_TYPE_DYNAMIC, CP_BODY_TYPE_KINEMATIC, CP_BODY_TYPE_STATIC)
from tamias2d.vector cimport (cpVect, cpTransform, cpv, cpvadd, cpvsub, cpvneg,
    cpvmult, cpvcross, cpvforangle, cpvdistsq, cpvlerp, cpTransformNewTranspose,
    cpTransformPoint, cpTransformVect, vec2d_from_cpv, cpv_from_object)

from tamias2d.errors import IllegalBody, SpaceLocked, NotInSpace

cdef extern from "Python.h":
    void PyErr_Restore(PyObject *type, PyObject *value, PyObject *tb)
    void PyErr_WriteUnraisable(object obj)

__all__ = ["Body"]

# pymunk keeps these on the class only; the module-level names are a
# convenience for `from tamias2d.body import DYNAMIC`.
DYNAMIC = <int>CP_BODY_TYPE_DYNAMIC
KINEMATIC = <int>CP_BODY_TYPE_KINEMATIC
STATIC = <int>CP_BODY_TYPE_STATIC


# The helpers of chipmunk_private.h are in _private.pxd.
from tamias2d._threadguard cimport tamias_wait_body
from tamias2d._private cimport cpArbiterNext, cpConstraintNext, apply_impulse
from tamias2d._containers cimport cpArrayContains


# -- space hooks ---------------------------------------------------------------------
# Zero until the space module installs its table (C statics start zeroed).
cdef tamias_BodySpaceHooks _hooks

cdef void tamias_set_body_space_hooks(const tamias_BodySpaceHooks *hooks) noexcept nogil:
    global _hooks
    _hooks = hooks[0]


# -- cpBody.c --------------------------------------------------------------------------
cdef cpBody *cpBodyInit(cpBody *body, cpFloat mass, cpFloat moment) noexcept nogil:
    body.space = NULL
    body.shapeList = NULL
    body.arbiterList = NULL
    body.constraintList = NULL

    body.velocity_func = cpBodyUpdateVelocity
    body.position_func = cpBodyUpdatePosition

    body.sleeping.root = NULL
    body.sleeping.next = NULL
    body.sleeping.idleTime = 0.0

    body.p = cpv(0.0, 0.0)
    body.v = cpv(0.0, 0.0)
    body.f = cpv(0.0, 0.0)
    body.w = 0.0
    body.t = 0.0
    body.v_bias = cpv(0.0, 0.0)
    body.w_bias = 0.0
    body.userData = NULL

    # As in Munk2D, the setters come last; cog is left as it was (zeroed
    # memory for a new body) and the angle setter builds the transform.
    cpBodySetMass(body, mass)
    cpBodySetMoment(body, moment)
    cpBodySetAngle(body, 0.0)
    return body


cdef void cpBodySetType(cpBody *body, cpBodyType type) noexcept nogil:
    cdef cpBodyType oldType = cpBodyGetType(body)
    if oldType == type:
        return

    # Static bodies are marked by an infinite idle time; the others restart it.
    body.sleeping.idleTime = INFINITY if type == CP_BODY_TYPE_STATIC else 0.0

    if type == CP_BODY_TYPE_DYNAMIC:
        body.m = 0.0
        body.i = 0.0
        body.m_inv = INFINITY
        body.i_inv = INFINITY
        cpBodyAccumulateMassFromShapes(body)
    else:
        body.m = INFINITY
        body.i = INFINITY
        body.m_inv = 0.0
        body.i_inv = 0.0
        body.v = cpv(0.0, 0.0)
        body.w = 0.0

    cdef cpSpace *space = body.space
    if space != NULL:
        # Munk2D leaves a body that was static asleep-free: no activation.
        if oldType != CP_BODY_TYPE_STATIC:
            cpBodyActivate(body)
        if _hooks.body_type_changed != NULL:
            _hooks.body_type_changed(space, body, oldType, type)


cdef void cpBodyAccumulateMassFromShapes(cpBody *body) noexcept nogil:
    if body == NULL or cpBodyGetType(body) != CP_BODY_TYPE_DYNAMIC:
        return

    body.m = 0.0
    body.i = 0.0
    body.cog = cpv(0.0, 0.0)

    # The origin must not move, so remember it and put it back at the end.
    cdef cpVect pos = cpBodyGetPosition(body)
    cdef cpShape *shape = body.shapeList
    cdef const cpShapeMassInfo *info
    cdef cpFloat m, msum
    while shape != NULL:
        info = &shape.massInfo
        m = info.m
        if m > 0.0:
            msum = body.m + m
            # Parallel-axis merge of the shape into the running total.
            body.i += m * info.i + cpvdistsq(body.cog, info.cog) * (m * body.m) / msum
            body.cog = cpvlerp(body.cog, info.cog, m / msum)
            body.m = msum
        shape = shape.next

    body.m_inv = 1.0 / body.m
    body.i_inv = 1.0 / body.i

    cpBodySetPosition(body, pos)


cdef void cpBodySetMass(cpBody *body, cpFloat mass) noexcept nogil:
    cpBodyActivate(body)
    body.m = mass
    body.m_inv = INFINITY if mass == 0.0 else 1.0 / mass


cdef void cpBodySetMoment(cpBody *body, cpFloat moment) noexcept nogil:
    cpBodyActivate(body)
    body.i = moment
    body.i_inv = INFINITY if moment == 0.0 else 1.0 / moment


cdef void cpBodyAddShape(cpBody *body, cpShape *shape) noexcept nogil:
    # Head insertion: the list runs in reverse add order, and so does the
    # mass accumulation.
    cdef cpShape *next = body.shapeList
    if next != NULL:
        next.prev = shape
    shape.next = next
    body.shapeList = shape
    if shape.massInfo.m > 0.0:
        cpBodyAccumulateMassFromShapes(body)


cdef void cpBodyRemoveShape(cpBody *body, cpShape *shape) noexcept nogil:
    cdef cpShape *prev = shape.prev
    cdef cpShape *next = shape.next
    if prev != NULL:
        prev.next = next
    else:
        body.shapeList = next
    if next != NULL:
        next.prev = prev
    shape.prev = NULL
    shape.next = NULL
    if cpBodyGetType(body) == CP_BODY_TYPE_DYNAMIC and shape.massInfo.m > 0.0:
        cpBodyAccumulateMassFromShapes(body)


cdef cpConstraint *_filter_constraints(cpConstraint *node, cpBody *body,
                                       cpConstraint *filter) noexcept nogil:
    if node == NULL:
        return NULL  # not in the list (the body was re-initialised): nothing to unlink
    if node == filter:
        return cpConstraintNext(node, body)
    elif node.a == body:
        node.next_a = _filter_constraints(node.next_a, body, filter)
    else:
        node.next_b = _filter_constraints(node.next_b, body, filter)
    return node


cdef void cpBodyRemoveConstraint(cpBody *body, cpConstraint *constraint) noexcept nogil:
    body.constraintList = _filter_constraints(body.constraintList, body, constraint)


# p is the world position of the centre of gravity; the origin follows from it.
cdef inline void _set_transform(cpBody *body, cpVect p, cpFloat a) noexcept nogil:
    cdef cpVect rot = cpvforangle(a)
    cdef cpVect c = body.cog
    body.transform = cpTransformNewTranspose(
        rot.x, -rot.y, p.x - (c.x * rot.x - c.y * rot.y),
        rot.y, rot.x, p.y - (c.x * rot.y + c.y * rot.x))


cdef void cpBodySetPosition(cpBody *body, cpVect position) noexcept nogil:
    cdef cpVect offset
    cpBodyActivate(body)
    offset = cpTransformVect(body.transform, body.cog)
    if not (isfinite(offset.x) and isfinite(offset.y)):
        # A body that an overflowed step left non-finite (its angle NaN):
        # its centre of gravity is taken at angle 0, so that the position
        # set is the one kept; Munk2D's would stay NaN whatever is set, and
        # the space would refuse to step on (the angle is set next).
        offset = body.cog
    body.p = cpvadd(offset, position)
    _set_transform(body, body.p, body.a)


cdef void cpBodySetCenterOfGravity(cpBody *body, cpVect cog) noexcept nogil:
    # The transform is not rebuilt: the origin jumps at the next position
    # update, as in Munk2D.
    cpBodyActivate(body)
    body.cog = cog


cdef void cpBodySetVelocity(cpBody *body, cpVect velocity) noexcept nogil:
    cpBodyActivate(body)
    body.v = velocity


cdef void cpBodySetForce(cpBody *body, cpVect force) noexcept nogil:
    cpBodyActivate(body)
    body.f = force


cdef void cpBodySetAngle(cpBody *body, cpFloat angle) noexcept nogil:
    # Rotates about the centre of gravity, which stays in place.
    cpBodyActivate(body)
    body.a = angle
    _set_transform(body, body.p, angle)


cdef void cpBodySetAngularVelocity(cpBody *body, cpFloat angularVelocity) noexcept nogil:
    cpBodyActivate(body)
    body.w = angularVelocity


cdef void cpBodySetTorque(cpBody *body, cpFloat torque) noexcept nogil:
    cpBodyActivate(body)
    body.t = torque


cdef void cpBodyUpdateVelocity(cpBody *body, cpVect gravity, cpFloat damping, cpFloat dt) noexcept nogil:
    # Kinematic bodies move only by the velocity they are given.
    if cpBodyGetType(body) == CP_BODY_TYPE_KINEMATIC:
        return
    body.v = cpvadd(cpvmult(body.v, damping),
                    cpvmult(cpvadd(gravity, cpvmult(body.f, body.m_inv)), dt))
    body.w = body.w * damping + body.t * body.i_inv * dt
    body.f = cpv(0.0, 0.0)
    body.t = 0.0


cdef void cpBodyUpdatePosition(cpBody *body, cpFloat dt) noexcept nogil:
    body.p = cpvadd(body.p, cpvmult(cpvadd(body.v, body.v_bias), dt))
    body.a = body.a + (body.w + body.w_bias) * dt
    _set_transform(body, body.p, body.a)
    body.v_bias = cpv(0.0, 0.0)
    body.w_bias = 0.0


cdef void cpBodyApplyForceAtWorldPoint(cpBody *body, cpVect force, cpVect point) noexcept nogil:
    cpBodyActivate(body)
    body.f = cpvadd(body.f, force)
    cdef cpVect r = cpvsub(point, cpTransformPoint(body.transform, body.cog))
    body.t += cpvcross(r, force)


cdef void cpBodyApplyForceAtLocalPoint(cpBody *body, cpVect force, cpVect point) noexcept nogil:
    cpBodyApplyForceAtWorldPoint(body, cpTransformVect(body.transform, force),
                                 cpTransformPoint(body.transform, point))


cdef void cpBodyApplyImpulseAtWorldPoint(cpBody *body, cpVect impulse, cpVect point) noexcept nogil:
    cpBodyActivate(body)
    cdef cpVect r = cpvsub(point, cpTransformPoint(body.transform, body.cog))
    apply_impulse(body, impulse, r)


cdef void cpBodyApplyImpulseAtLocalPoint(cpBody *body, cpVect impulse, cpVect point) noexcept nogil:
    cpBodyApplyImpulseAtWorldPoint(body, cpTransformVect(body.transform, impulse),
                                   cpTransformPoint(body.transform, point))


# -- cpSpaceComponent.c, body side ----------------------------------------------------

# A body outside every space is reached by the flood fill through its joints
# and joins the component of the bodies it is jointed to. If that component
# falls asleep the body is one of its chain and its root is the component's.
# If it stays awake the body keeps a root (itself, see _settleOutsideMembers
# in _space_step.pyx): Munk2D keeps the component's root there, which may
# later be awake, in another component or freed, and the flood fill passes
# the body over from then on. Such a stale root is never followed: waking
# the body wakes instead what it is jointed to that sleeps, which is what
# Munk2D's root stood for (the component it had joined).
cdef cpBool _rootStillSleeps(cpBody *body, cpBody *root) noexcept nogil:
    cdef cpConstraint *c = body.constraintList
    while c != NULL:
        if c.space != NULL and cpArrayContains(c.space.sleepingComponents, root):
            return 1
        c = cpConstraintNext(c, body)
    return 0


cdef void _wakeJointPartners(cpBody *body) noexcept nogil:
    cdef cpConstraint *c = body.constraintList
    cdef cpBody *other
    while c != NULL:
        other = c.b if c.a == body else c.a
        # Only partners in a space: no recursion into another outside body.
        if c.space != NULL and other.space != NULL and cpBodyIsSleeping(other):
            cpBodyActivate(other)
        c = cpConstraintNext(c, body)


# A joint belongs to its body a, or to its body b when a is static: the owner's
# sleeping takes it out of the solver and waking puts it back. A body a that
# turns static or stops being static hands its joints over; a sleeping body b
# is woken first, so that the joint is in the solver exactly while its new
# owner is awake (else it was lost for good or, woken later, pushed twice:
# Munk2D and pymunk).
cdef void _wakeJointsChangingOwner(cpBody *body) noexcept nogil:
    cdef cpConstraint *c = body.constraintList
    while c != NULL:
        if c.a == body and c.space != NULL and cpBodyIsSleeping(c.b):
            cpBodyActivate(c.b)
        c = cpConstraintNext(c, body)


cdef void tamias_body_drop_stale_root(cpBody *body) noexcept nogil:
    # Once the body is jointed into no space the flood fill cannot reach it
    # and its root means nothing: it stops counting as asleep.
    cdef cpConstraint *c
    if body.space != NULL or body.sleeping.root == NULL:
        return
    c = body.constraintList
    while c != NULL:
        if c.space != NULL:
            return
        c = cpConstraintNext(c, body)
    body.sleeping.root = NULL
    body.sleeping.next = NULL


cdef void cpBodyActivate(cpBody *body) noexcept nogil:
    cdef cpBody *root
    cdef cpBody *other
    cdef cpArbiter *arb
    if body == NULL or cpBodyGetType(body) != CP_BODY_TYPE_DYNAMIC:
        return
    body.sleeping.idleTime = 0.0

    root = body.sleeping.root
    if root != NULL and body.space == NULL and not _rootStillSleeps(body, root):
        # A stale root (see _rootStillSleeps).
        root = NULL
        _wakeJointPartners(body)
        tamias_body_drop_stale_root(body)
    if root != NULL and cpBodyIsSleeping(root):
        if _hooks.wake_component != NULL:
            _hooks.wake_component(root.space, root)

    # Restart the idle timers of what the body touches, so nothing is left
    # asleep in mid-air.
    arb = body.arbiterList
    while arb != NULL:
        other = arb.body_b if arb.body_a == body else arb.body_a
        if cpBodyGetType(other) != CP_BODY_TYPE_STATIC:
            other.sleeping.idleTime = 0.0
        arb = cpArbiterNext(arb, body)


cdef void cpBodyActivateStatic(cpBody *body, cpShape *filter) noexcept nogil:
    # Munk2D hard-asserts a static body; callers inside the engine ensure it.
    if cpBodyGetType(body) != CP_BODY_TYPE_STATIC:
        return
    cdef cpArbiter *arb = body.arbiterList
    while arb != NULL:
        if filter == NULL or <const cpShape *>filter == arb.a or <const cpShape *>filter == arb.b:
            cpBodyActivate(arb.body_b if arb.body_a == body else arb.body_a)
        arb = cpArbiterNext(arb, body)


cdef void cpBodySleep(cpBody *body) noexcept nogil:
    cpBodySleepWithGroup(body, NULL)


cdef void cpBodySleepWithGroup(cpBody *body, cpBody *group) noexcept nogil:
    if _hooks.sleep_with_group != NULL:
        _hooks.sleep_with_group(body, group)


# -- integrator trampolines for Python velocity_func / position_func ---------------
cdef void _write_unraisable(object exc, object where) noexcept:
    # Hand the exception to sys.unraisablehook with its traceback.
    cdef object tp = type(exc)
    cdef object tb = exc.__traceback__
    Py_INCREF(tp)
    Py_INCREF(exc)
    if tb is not None:
        Py_INCREF(tb)
    PyErr_Restore(<PyObject *>tp, <PyObject *>exc, <PyObject *>tb if tb is not None else NULL)
    PyErr_WriteUnraisable(where)


cdef void _report_callback_error(cpBody *body, object exc, object where) noexcept:
    # The Python Space keeps the first error and re-raises it from step().
    cdef cpSpace *space = body.space
    if space != NULL and space.userData != NULL:
        try:
            (<object>space.userData)._store_callback_error(exc)
            return
        except BaseException:
            pass
    _write_unraisable(exc, where)


cdef void _call_velocity_func(cpBody *body, cpVect gravity, cpFloat damping, cpFloat dt) noexcept:
    cdef Body py_body
    if body.userData == NULL:
        cpBodyUpdateVelocity(body, gravity, damping, dt)
        return
    py_body = <Body>body.userData
    func = py_body._velocity_func
    if func is None:
        cpBodyUpdateVelocity(body, gravity, damping, dt)
        return
    try:
        func(py_body, vec2d_from_cpv(gravity), damping, dt)
    except BaseException as exc:
        _report_callback_error(body, exc, func)


cdef void _call_position_func(cpBody *body, cpFloat dt) noexcept:
    cdef Body py_body
    if body.userData == NULL:
        cpBodyUpdatePosition(body, dt)
        return
    py_body = <Body>body.userData
    func = py_body._position_func
    if func is None:
        cpBodyUpdatePosition(body, dt)
        return
    try:
        func(py_body, dt)
    except BaseException as exc:
        _report_callback_error(body, exc, func)


cdef void tamias_body_velocity_trampoline(cpBody *body, cpVect gravity, cpFloat damping, cpFloat dt) noexcept nogil:
    with gil:
        _call_velocity_func(body, gravity, damping, dt)


cdef void tamias_body_position_trampoline(cpBody *body, cpFloat dt) noexcept nogil:
    with gil:
        _call_position_func(body, dt)


# -- Python boundary helpers ---------------------------------------------------------
cdef inline bint _finite(double x) noexcept nogil:
    # False for NaN and for both infinities.
    return x - x == 0.0


cdef inline cpVect _finite_vect(object o, str what) except *:
    cdef cpVect v = cpv_from_object(o)
    if not (_finite(v.x) and _finite(v.y)):
        raise IllegalBody("Body %s must be finite, got (%r, %r)." % (what, v.x, v.y))
    return v


cdef int _undo_overflow(cpBody *body, cpVect a0, cpFloat b0, bint impulse) except -1:
    # Finite inputs can still overflow (a huge force times a long lever arm
    # gives an infinite torque); put the body back and refuse, rather than
    # let the next step turn it into NaN.
    cdef cpVect a = body.v if impulse else body.f
    cdef cpFloat b = body.w if impulse else body.t
    if _finite(a.x) and _finite(a.y) and _finite(b):
        return 0
    if impulse:
        body.v = a0
        body.w = b0
    else:
        body.f = a0
        body.t = b0
    raise IllegalBody("Body %s overflows: the resulting %s would not be finite." % (
        "impulse" if impulse else "force",
        "velocity or angular velocity" if impulse else "force or torque"))


cdef int _check_invertible(double x, str what) except -1:
    # 0 (a placeholder until shapes give the mass) and inf (no rotation) are
    # fine; a positive value whose inverse overflows (a subnormal such as
    # 5e-324) would give m_inv = inf and a NaN body at the first contact.
    if 0.0 < x < INFINITY and not (1.0 / x < INFINITY):
        raise IllegalBody("%s %r is too small: its inverse is not finite." % (what, x))
    return 0


cdef bint _in_a_space(cpBody *body) noexcept:
    # The body, or one of its shapes, is in a space. A shape stays in the
    # space when only its body is removed, and the solver then uses the
    # body's inverse mass: a mass or moment of 0 there means m_inv = inf and
    # a NaN body at the first contact (pymunk too).
    cdef cpShape *shape
    if body.space != NULL:
        return True
    shape = body.shapeList
    while shape != NULL:
        if shape.space != NULL:
            return True
        shape = shape.next
    return False


cdef int _check_no_shape_in_a_space(cpBody *body) except -1:
    # Shapes in a space the body is not in (the body was removed, or added
    # to another space): Munk2D files a shape in the static or the dynamic
    # index by its body's type, and cpSpaceRemoveShape looks it up by the
    # type the body has then. Changing the type now would not move those
    # shapes (or would move them in the wrong space's index), so a later
    # removal misses them and leaves a freed shape in an index (pymunk
    # segfaults).
    cdef cpShape *shape = body.shapeList
    while shape != NULL:
        if shape.space != NULL and shape.space != body.space:
            raise IllegalBody("Cannot change the type of a body while some of its shapes are "
                              "in a space the body is not in: add the body to that space "
                              "first, or remove the shapes.")
        shape = shape.next
    return 0


cdef inline double _finite_float(object o, str what) except? -1.0:
    cdef double x = o
    if not _finite(x):
        raise IllegalBody("Body %s must be finite, got %r." % (what, x))
    return x


cdef int _body_type_from_object(object body_type) except -1:
    # Compared as plain ints, as pymunk's == does (so 0.0 and True pass too).
    if body_type == <int>CP_BODY_TYPE_DYNAMIC:
        return CP_BODY_TYPE_DYNAMIC
    elif body_type == <int>CP_BODY_TYPE_KINEMATIC:
        return CP_BODY_TYPE_KINEMATIC
    elif body_type == <int>CP_BODY_TYPE_STATIC:
        return CP_BODY_TYPE_STATIC
    raise ValueError("body_type must be Body.DYNAMIC, Body.KINEMATIC or Body.STATIC, not %r"
                     % (body_type,))


cdef object _arbiter_factory = None
cdef object _get_arbiter_factory():
    # Lazy upward import: the space module sits above this one.
    global _arbiter_factory
    if _arbiter_factory is None:
        from tamias2d.space import _arbiter_for_body
        _arbiter_factory = _arbiter_for_body
    return _arbiter_factory


cdef int _check_can_sleep(Body self, Body group) except -1:
    # Munk2D's hard asserts of cpBodySleepWithGroup, as exceptions.
    cdef cpSpace *space = self._body.space
    cdef cpBody *group_root = NULL
    if self.space is None or space == NULL:
        raise NotInSpace("Body not added to space")
    if cpBodyGetType(&self._body) != CP_BODY_TYPE_DYNAMIC:
        raise IllegalBody("Non-dynamic bodies cannot be put to sleep.")
    if not (self._body.m > 0.0 and self._body.i > 0.0):
        # The step refuses a massless dynamic body, but a sleeping one is out
        # of its reach; woken by a contact it would turn NaN (inverse mass inf).
        raise IllegalBody("A dynamic body with mass or moment 0 cannot be put to sleep.")
    if space.locked:
        raise SpaceLocked("Bodies cannot be put to sleep during a query or a step; "
                          "use a post-step callback.")
    if not (space.sleepTimeThreshold < INFINITY):
        raise RuntimeError("Sleeping is not enabled on the space: set a finite "
                           "Space.sleep_time_threshold first.")
    if group is not None:
        if not cpBodyIsSleeping(&group._body):
            raise IllegalBody("Cannot use a non-sleeping body as a group identifier.")
        group_root = group._body.sleeping.root
        if group._body.space != space or not cpArrayContains(space.sleepingComponents, group_root):
            # A body outside the space, held there by a joint, keeps a root
            # naming itself (it reads as asleep) but sleeps in no component
            # of any space: a group rooted there was woken through a root
            # with no space (a segfault), and one in another space would
            # link the two spaces' bodies.
            raise IllegalBody("The group must be a body asleep in this body's space.")
    if cpBodyIsSleeping(&self._body) and self._body.sleeping.root != group_root:
        raise IllegalBody("The body is already sleeping and its group cannot be reassigned.")
    if _hooks.sleep_with_group == NULL:
        raise RuntimeError("tamias2d.space is not loaded: sleeping needs the space module.")
    return 0


cdef int _check_constraints_allow_type(Body self) except -1:
    # pymunk's rule for a body leaving the dynamic type while jointed: the body
    # must be dynamic now, and so must the other body of each constraint (a
    # joint between two non-dynamic bodies has no mass to solve for).
    d = _user_dict(self).get("_constraints")
    if not d:
        return 0
    for c in list(d):
        other = c.b if c.a is self else c.a
        if (cpBodyGetType(&self._body) != CP_BODY_TYPE_DYNAMIC
                or other is None or other.body_type != <int>CP_BODY_TYPE_DYNAMIC):
            raise IllegalBody(
                f"Cannot set a non-dynamic body type when the body is connected to a "
                f"constraint {c!r} with a non-dynamic other body.")
    return 0


cdef dict _user_dict(Body self):
    # The instance dict is created lazily by the generic __dict__ getter.
    return getattr(self, "__dict__")


cdef class Body:
    """A rigid body: mass, moment of inertia, position, angle and their rates.

    ``Body(mass=0, moment=0, body_type=Body.DYNAMIC)``. Mass and moment only
    matter for dynamic bodies; kinematic and static bodies have infinite mass
    and moment. A body with mass 0 can get its mass from the density or mass
    of its shapes once body and shapes are added to a space.

    The position is the body's origin; the body rotates about its centre of
    gravity (``center_of_gravity``, in body coordinates). Copying or
    pickling a body copies its state but none of its shapes, constraints or
    space, and a sleeping body comes back awake.

    >>> import tamias2d
    >>> b = tamias2d.Body(10, 100)
    >>> b.position = (3, 4)
    >>> b.mass, b.moment, b.position
    (10.0, 100.0, Vec2d(3.0, 4.0))
    """

    DYNAMIC = <int>CP_BODY_TYPE_DYNAMIC
    KINEMATIC = <int>CP_BODY_TYPE_KINEMATIC
    STATIC = <int>CP_BODY_TYPE_STATIC

    # The pickled state, in pymunk's layout (the order of "general" matters:
    # the centre of gravity is restored after the position, as pymunk does).
    _pickle_attrs_init = ["mass", "moment", "body_type"]
    _pickle_attrs_general = ["force", "angle", "position", "center_of_gravity",
                             "velocity", "angular_velocity", "torque"]
    _pickle_attrs_skip = ["is_sleeping", "_velocity_func", "_position_func"]

    def __cinit__(self):
        # A usable C body even before __init__ (unpickling creates the object
        # first); _shapes stays None until __init__ has run.
        cpBodyInit(&self._body, 0.0, 0.0)
        self._body.userData = <void *>self
        self._space = None
        self._shapes = None
        self._velocity_func = None
        self._position_func = None

    def __init__(self, mass=0, moment=0, body_type=0):
        cdef int t = _body_type_from_object(body_type)
        cdef double m = 0.0, i = 0.0
        if self._body.space != NULL:
            raise IllegalBody("Cannot re-initialise a body that is in a space.")
        if t == CP_BODY_TYPE_DYNAMIC:
            m = mass
            i = moment
            if not (0.0 <= m < INFINITY):
                raise IllegalBody("Mass must be non-negative and finite, got %r." % m)
            if not (i >= 0.0):
                raise IllegalBody("Moment of inertia must be non-negative, got %r." % i)
            _check_invertible(m, "Mass")
            _check_invertible(i, "Moment of inertia")
        # A fresh body every time, as pymunk allocates a new cpBody.
        memset(&self._body, 0, sizeof(cpBody))
        cpBodyInit(&self._body, m, i)
        if t != CP_BODY_TYPE_DYNAMIC:
            cpBodySetType(&self._body, <cpBodyType>t)
        self._body.userData = <void *>self
        self._space = None
        self._shapes = {}
        self._velocity_func = None
        self._position_func = None

    def __repr__(self):
        cdef cpBodyType t = cpBodyGetType(&self._body)
        if t == CP_BODY_TYPE_DYNAMIC:
            return "Body(%r, %r, Body.DYNAMIC)" % (self._body.m, self._body.i)
        elif t == CP_BODY_TYPE_KINEMATIC:
            return "Body(Body.KINEMATIC)"
        return "Body(Body.STATIC)"

    @property
    def id(self):
        """A number unique to this body while it lives (a copy gets a new one).

        >>> import tamias2d
        >>> a, b = tamias2d.Body(), tamias2d.Body()
        >>> a.id != b.id
        True
        """
        return <uintptr_t>self._body.userData

    # -- mass properties --------------------------------------------------------
    @property
    def mass(self):
        """Mass of the body (infinite for kinematic and static bodies).

        Only dynamic bodies accept a new mass; once the body is in a space the
        mass must be greater than 0.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.mass = 5
        >>> b.mass
        5.0
        """
        return self._body.m

    @mass.setter
    def mass(self, mass):
        cdef double m = mass
        if cpBodyGetType(&self._body) != CP_BODY_TYPE_DYNAMIC:
            raise IllegalBody("You cannot set the mass of kinematic or static bodies.")
        if not (0.0 <= m < INFINITY):
            raise IllegalBody("Mass must be non-negative and finite, got %r." % m)
        if not (m > 0.0) and _in_a_space(&self._body):
            raise IllegalBody("Dynamic bodies must have mass > 0 if they are attached to a Space.")
        _check_invertible(m, "Mass")
        tamias_wait_body(&self._body)
        cpBodySetMass(&self._body, m)

    @property
    def moment(self):
        """Moment of inertia: the body's resistance to angular acceleration.

        ``float('inf')`` makes a body that cannot rotate. Once the body is in
        a space the moment must be greater than 0.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.moment = float("inf")
        >>> b.moment
        inf
        """
        return self._body.i

    @moment.setter
    def moment(self, moment):
        cdef double i = moment
        if not (i >= 0.0):
            raise IllegalBody("Moment of inertia must be non-negative, got %r." % i)
        if not (i > 0.0) and _in_a_space(&self._body):
            raise IllegalBody("Dynamic bodies must have moment > 0 if they are attached to a Space.")
        _check_invertible(i, "Moment of inertia")
        tamias_wait_body(&self._body)
        cpBodySetMoment(&self._body, i)

    @property
    def center_of_gravity(self):
        """Centre of gravity in body coordinates; (0, 0) by default.

        Setting it does not move the body now: the origin shifts at the next
        position update, exactly as in Chipmunk.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.center_of_gravity = (1, 2)
        >>> b.center_of_gravity
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(self._body.cog)

    @center_of_gravity.setter
    def center_of_gravity(self, cog):
        cdef cpVect value = _finite_vect(cog, "center_of_gravity")
        tamias_wait_body(&self._body)
        cpBodySetCenterOfGravity(&self._body, value)

    # -- motion state ------------------------------------------------------------
    @property
    def position(self):
        """Position of the body's origin in world coordinates.

        After moving a body in a space, ``Space.reindex_shapes_for_body``
        brings the shapes' collision data up to date for queries.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.position = 1, 2
        >>> b.position
        Vec2d(1.0, 2.0)
        """
        tamias_wait_body(&self._body)
        return vec2d_from_cpv(cpBodyGetPosition(&self._body))

    @position.setter
    def position(self, pos):
        cdef cpVect value = _finite_vect(pos, "position")
        tamias_wait_body(&self._body)
        cpBodySetPosition(&self._body, value)

    @property
    def velocity(self):
        """Linear velocity of the centre of gravity.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.velocity = 3, 4
        >>> b.velocity
        Vec2d(3.0, 4.0)
        """
        tamias_wait_body(&self._body)
        return vec2d_from_cpv(self._body.v)

    @velocity.setter
    def velocity(self, vel):
        cdef cpVect value = _finite_vect(vel, "velocity")
        tamias_wait_body(&self._body)
        cpBodySetVelocity(&self._body, value)
        if not (isfinite(self._body.v_bias.x) and isfinite(self._body.v_bias.y)):
            # The solver's bias velocity, which no setter reaches, went with
            # the velocity it came with: a body the space never integrates
            # (an orphan: removed while its shapes stayed) keeps the bias
            # that contacts give it from step to step, and once that
            # overflowed, resetting the velocity after an overflowed step
            # did not make the body finite (nor the space copyable).
            self._body.v_bias.x = 0.0
            self._body.v_bias.y = 0.0

    @property
    def force(self):
        """Force applied at the centre of gravity, cleared after every step.

        It holds only the forces applied by hand, not the contact forces.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.force = 4, 5
        >>> b.force
        Vec2d(4.0, 5.0)
        """
        tamias_wait_body(&self._body)
        return vec2d_from_cpv(self._body.f)

    @force.setter
    def force(self, f):
        cdef cpVect value = _finite_vect(f, "force")
        tamias_wait_body(&self._body)
        cpBodySetForce(&self._body, value)

    @property
    def angle(self):
        """Rotation of the body in radians, about its centre of gravity.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.angle = 1.5
        >>> b.angle
        1.5
        """
        tamias_wait_body(&self._body)
        return self._body.a

    @angle.setter
    def angle(self, angle):
        cdef double value = _finite_float(angle, "angle")
        tamias_wait_body(&self._body)
        cpBodySetAngle(&self._body, value)

    @property
    def angular_velocity(self):
        """Angular velocity in radians per second.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.angular_velocity = 2
        >>> b.angular_velocity
        2.0
        """
        tamias_wait_body(&self._body)
        return self._body.w

    @angular_velocity.setter
    def angular_velocity(self, w):
        cdef double value = _finite_float(w, "angular_velocity")
        tamias_wait_body(&self._body)
        cpBodySetAngularVelocity(&self._body, value)
        if not isfinite(self._body.w_bias):
            self._body.w_bias = 0.0     # (as for velocity)

    @property
    def torque(self):
        """Torque applied to the body, cleared after every step.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.torque = 1.25
        >>> b.torque
        1.25
        """
        tamias_wait_body(&self._body)
        return self._body.t

    @torque.setter
    def torque(self, t):
        cdef double value = _finite_float(t, "torque")
        tamias_wait_body(&self._body)
        cpBodySetTorque(&self._body, value)

    @property
    def rotation_vector(self):
        """The unit vector (cos angle, sin angle) of the body's rotation.

        >>> import tamias2d
        >>> tamias2d.Body(1, 1).rotation_vector
        Vec2d(1.0, 0.0)
        """
        tamias_wait_body(&self._body)
        return vec2d_from_cpv(cpBodyGetRotation(&self._body))

    @property
    def kinetic_energy(self):
        """m|v|^2 + I w^2 (Chipmunk's definition, without the one half).

        >>> import tamias2d
        >>> b = tamias2d.Body(2, 1)
        >>> b.velocity = 3, 0
        >>> b.kinetic_energy
        18.0
        """
        tamias_wait_body(&self._body)
        return cpBodyKineticEnergy(&self._body)

    # -- type, space and attached objects ----------------------------------------
    @property
    def body_type(self):
        """Body.DYNAMIC, Body.KINEMATIC or Body.STATIC.

        Turning a body dynamic recomputes its mass and moment from its shapes
        (a hand-set moment is lost); turning it kinematic or static makes them
        infinite and stops it. Not allowed while its space is stepping.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.body_type = tamias2d.Body.KINEMATIC
        >>> b.body_type == tamias2d.Body.KINEMATIC, b.mass
        (True, inf)
        """
        return <int>cpBodyGetType(&self._body)

    @body_type.setter
    def body_type(self, body_type):
        cdef int t = _body_type_from_object(body_type)
        tamias_wait_body(&self._body)
        if self._body.space != NULL and self._body.space.locked:
            raise SpaceLocked("The body type cannot change while the space is locked "
                              "(during a step or a query); use a post-step callback.")
        if t != CP_BODY_TYPE_DYNAMIC:
            _check_constraints_allow_type(self)
        if t != <int>cpBodyGetType(&self._body):
            _check_no_shape_in_a_space(&self._body)
        if (t != <int>cpBodyGetType(&self._body) and cpBodyIsSleeping(&self._body)
                and cpBodyGetType(&self._body) == CP_BODY_TYPE_DYNAMIC):
            # Wake the component first. Munk2D's cpBodySetType changes the
            # type and only then calls cpBodyActivate, which does nothing for
            # a body that is no longer dynamic: the body stays linked in its
            # sleeping component while it moves to another array, and the
            # next step loops forever in FloodFillComponent (pymunk hangs or
            # segfaults there). Waking is what cpBodySetType means to do.
            cpBodyActivate(&self._body)
        if (t != <int>cpBodyGetType(&self._body) and self._body.space != NULL
                and cpBodyGetType(&self._body) == CP_BODY_TYPE_STATIC):
            # A static body stays threaded to the sleeping bodies resting on
            # it; once it can move, that link would outlive the step (Munk2D
            # has the call to cpBodyActivateStatic here commented out; a
            # stale arbiter stays in their lists). Wake them first.
            cpBodyActivateStatic(&self._body, NULL)
        if (t == CP_BODY_TYPE_STATIC) != (cpBodyGetType(&self._body) == CP_BODY_TYPE_STATIC):
            _wakeJointsChangingOwner(&self._body)
        cpBodySetType(&self._body, <cpBodyType>t)
        if t != CP_BODY_TYPE_DYNAMIC and self._body.space == NULL:
            # A body outside the space keeps a stale component root from the
            # flood fill (see _rootStillSleeps); a kinematic or static body
            # is never part of a component.
            self._body.sleeping.root = NULL
            self._body.sleeping.next = NULL

    @property
    def space(self):
        """The Space the body was added to, or None.

        >>> import tamias2d
        >>> tamias2d.Body(1, 1).space is None
        True
        """
        if self._shapes is None:
            raise IllegalBody(
                "The body is not initialised. This can mean a direct or indirect "
                "circular reference between the Body and a Space while copying or "
                "pickling, which is not supported.")
        if self._space is None:
            return None
        return self._space()

    @property
    def shapes(self):
        """A view of the shapes attached to this body.

        >>> import tamias2d
        >>> tamias2d.Body(1, 1).shapes
        dict_keys([])
        """
        if self._shapes is None:
            return {}.keys()
        return self._shapes.keys()

    @property
    def constraints(self):
        """A view of the constraints attached to this body (weakly held).

        >>> import tamias2d
        >>> len(tamias2d.Body(1, 1).constraints)
        0
        """
        cdef dict ud = _user_dict(self)
        d = ud.get("_constraints")
        if d is None:
            d = ud["_constraints"] = weakref.WeakKeyDictionary()
        return WeakKeysView(d)

    @property
    def is_bullet(self):
        """Continuous collision against dynamic bodies too, in the soft
        solver (default False; a tamias2d extension, Box2D's ``isBullet``).

        In ``Space.solver = "soft"`` every body is stopped by static and
        kinematic shapes however fast it moves (its speculative contacts
        reach as far as it travels in the step). A bullet gets the same
        against dynamic bodies, at the cost of more contact pairs while it
        moves fast. The chipmunk solver ignores it.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.is_bullet
        False
        >>> b.is_bullet = True
        >>> b.is_bullet
        True
        """
        return <bint>self._body.isBullet

    @is_bullet.setter
    def is_bullet(self, value):
        cdef bint flag = bool(value)
        tamias_wait_body(&self._body)
        self._body.isBullet = flag

    @property
    def is_sleeping(self):
        """True while the body sleeps.

        >>> import tamias2d
        >>> tamias2d.Body(1, 1).is_sleeping
        False
        """
        tamias_wait_body(&self._body)
        return <bint>cpBodyIsSleeping(&self._body)

    # -- integrators --------------------------------------------------------------
    @property
    def velocity_func(self):
        """The velocity integrator run at every step.

        Called as ``func(body, gravity, damping, dt)``. Set a Python function
        to override it, ``Body.update_velocity`` (or None) to restore the
        built-in one. An exception raised by the function during a step is
        re-raised by ``Space.step``.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> def no_gravity(body, gravity, damping, dt):
        ...     tamias2d.Body.update_velocity(body, (0, 0), damping, dt)
        >>> b.velocity_func = no_gravity
        >>> b.velocity_func is no_gravity
        True
        >>> b.velocity_func = None
        >>> b.velocity_func == tamias2d.Body.update_velocity
        True
        """
        if self._velocity_func is None:
            return Body.update_velocity
        return self._velocity_func

    @velocity_func.setter
    def velocity_func(self, func):
        if func is not None and not callable(func):
            raise TypeError("velocity_func must be callable or None, not %r" % (func,))
        tamias_wait_body(&self._body)
        if func is None or func is _default_update_velocity:
            self._velocity_func = None
            self._body.velocity_func = cpBodyUpdateVelocity
        elif callable(func):
            self._velocity_func = func
            self._body.velocity_func = tamias_body_velocity_trampoline
        else:
            raise TypeError("velocity_func must be callable or None, not %r" % (func,))

    @property
    def position_func(self):
        """The position integrator run at every step.

        Called as ``func(body, dt)``. Set a Python function to override it,
        ``Body.update_position`` (or None) to restore the built-in one.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.position_func == tamias2d.Body.update_position
        True
        """
        if self._position_func is None:
            return Body.update_position
        return self._position_func

    @position_func.setter
    def position_func(self, func):
        if func is not None and not callable(func):
            raise TypeError("position_func must be callable or None, not %r" % (func,))
        tamias_wait_body(&self._body)
        if func is None or func is _default_update_position:
            self._position_func = None
            self._body.position_func = cpBodyUpdatePosition
        elif callable(func):
            self._position_func = func
            self._body.position_func = tamias_body_position_trampoline
        else:
            raise TypeError("position_func must be callable or None, not %r" % (func,))

    @staticmethod
    def update_velocity(Body body not None, gravity, double damping, double dt):
        """The built-in velocity integrator (explicit Euler with damping).

        v = v*damping + (gravity + force/m)*dt, w = w*damping + torque/I*dt,
        then force and torque are cleared. Kinematic bodies are left alone.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> tamias2d.Body.update_velocity(b, (0, -10), 1.0, 0.5)
        >>> b.velocity
        Vec2d(0.0, -5.0)
        """
        cdef cpVect g = _finite_vect(gravity, "gravity")
        if not (_finite(damping) and _finite(dt)):
            raise IllegalBody("damping and dt must be finite, got %r and %r." % (damping, dt))
        tamias_wait_body(&body._body)
        cpBodyUpdateVelocity(&body._body, g, damping, dt)

    @staticmethod
    def update_position(Body body not None, double dt):
        """The built-in position integrator (explicit Euler).

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.velocity = 2, 0
        >>> tamias2d.Body.update_position(b, 0.5)
        >>> b.position
        Vec2d(1.0, 0.0)
        """
        if not _finite(dt):
            raise IllegalBody("dt must be finite, got %r." % dt)
        tamias_wait_body(&body._body)
        cpBodyUpdatePosition(&body._body, dt)

    # -- forces and impulses ---------------------------------------------------------
    def apply_force_at_world_point(self, force, point):
        """Add a force, as if applied at a world point (adds torque too).

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.position = 3, 4
        >>> b.apply_force_at_world_point((10, 0), (0, 10))
        >>> b.force, b.torque
        (Vec2d(10.0, 0.0), -60.0)
        """
        cdef cpVect j = _finite_vect(force, "force")
        cdef cpVect at = _finite_vect(point, "force application point")
        tamias_wait_body(&self._body)
        cdef cpVect a0 = self._body.f
        cdef cpFloat b0 = self._body.t
        cpBodyApplyForceAtWorldPoint(&self._body, j, at)
        _undo_overflow(&self._body, a0, b0, False)

    def apply_force_at_local_point(self, force, point=(0, 0)):
        """Add a force given in body coordinates, at a body-local point.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.apply_force_at_local_point((10, 0), (0, 10))
        >>> b.force, b.torque
        (Vec2d(10.0, 0.0), -100.0)
        """
        cdef cpVect j = _finite_vect(force, "force")
        cdef cpVect at = _finite_vect(point, "force application point")
        tamias_wait_body(&self._body)
        cdef cpVect a0 = self._body.f
        cdef cpFloat b0 = self._body.t
        cpBodyApplyForceAtLocalPoint(&self._body, j, at)
        _undo_overflow(&self._body, a0, b0, False)

    def apply_impulse_at_world_point(self, impulse, point):
        """Apply an impulse at a world point: changes the velocities at once.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.position = 3, 4
        >>> b.apply_impulse_at_world_point((10, 0), (0, 10))
        >>> b.velocity, b.angular_velocity
        (Vec2d(10.0, 0.0), -30.0)
        """
        cdef cpVect j = _finite_vect(impulse, "impulse")
        cdef cpVect at = _finite_vect(point, "impulse application point")
        tamias_wait_body(&self._body)
        cdef cpVect a0 = self._body.v
        cdef cpFloat b0 = self._body.w
        cpBodyApplyImpulseAtWorldPoint(&self._body, j, at)
        _undo_overflow(&self._body, a0, b0, True)

    def apply_impulse_at_local_point(self, impulse, point=(0, 0)):
        """Apply an impulse given in body coordinates at a body-local point.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.apply_impulse_at_local_point((10, 0), (0, 10))
        >>> b.velocity, b.angular_velocity
        (Vec2d(10.0, 0.0), -50.0)
        """
        cdef cpVect j = _finite_vect(impulse, "impulse")
        cdef cpVect at = _finite_vect(point, "impulse application point")
        tamias_wait_body(&self._body)
        cdef cpVect a0 = self._body.v
        cdef cpFloat b0 = self._body.w
        cpBodyApplyImpulseAtLocalPoint(&self._body, j, at)
        _undo_overflow(&self._body, a0, b0, True)

    # -- coordinates ------------------------------------------------------------------
    def local_to_world(self, v):
        """Convert a point from body coordinates to world coordinates.

        >>> import tamias2d
        >>> b = tamias2d.Body(body_type=tamias2d.Body.KINEMATIC)
        >>> b.position = 3, 4
        >>> b.local_to_world((1, 2))
        Vec2d(4.0, 6.0)
        """
        return vec2d_from_cpv(cpBodyLocalToWorld(&self._body, cpv_from_object(v)))

    def world_to_local(self, v):
        """Convert a point from world coordinates to body coordinates.

        >>> import tamias2d
        >>> b = tamias2d.Body(body_type=tamias2d.Body.KINEMATIC)
        >>> b.position = 3, 4
        >>> b.world_to_local((1, 2))
        Vec2d(-2.0, -2.0)
        """
        return vec2d_from_cpv(cpBodyWorldToLocal(&self._body, cpv_from_object(v)))

    def velocity_at_world_point(self, point):
        """Velocity of the body's material at a world point.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.position = 1, 2
        >>> b.angular_velocity = 1.5
        >>> b.velocity_at_world_point((1, 1))
        Vec2d(1.5, 0.0)
        """
        return vec2d_from_cpv(cpBodyGetVelocityAtWorldPoint(&self._body, cpv_from_object(point)))

    def velocity_at_local_point(self, point):
        """Velocity of the body's material at a body-local point.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.angular_velocity = 1.5
        >>> b.velocity_at_local_point((1, 1))
        Vec2d(-1.5, 1.5)
        """
        return vec2d_from_cpv(cpBodyGetVelocityAtLocalPoint(&self._body, cpv_from_object(point)))

    # -- sleeping -----------------------------------------------------------------------
    def activate(self):
        """Restart the idle timer; wake the body (and its group) if it sleeps.

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 1)
        >>> b.activate()
        >>> b.is_sleeping
        False
        """
        tamias_wait_body(&self._body)
        cpBodyActivate(&self._body)

    def sleep(self):
        """Put the body to sleep now, even in mid-air (in a new group).

        The body must be dynamic and in a space with sleeping enabled
        (a finite ``sleep_time_threshold``); not from inside a step. If it
        touches a body that stays awake, that contact wakes it again at
        the next step.

        >>> import tamias2d
        >>> tamias2d.Body(1, 1).sleep()
        Traceback (most recent call last):
        ...
        tamias2d.errors.NotInSpace: Body not added to space
        """
        tamias_wait_body(&self._body)
        _check_can_sleep(self, None)
        cpBodySleepWithGroup(&self._body, NULL)

    def sleep_with_group(self, body):
        """Put the body to sleep now, in the sleeping group of ``body``.

        When any body of a group is woken, the whole group wakes. With
        ``body=None`` this is the same as :meth:`sleep`.

        >>> import tamias2d
        >>> tamias2d.Body(1, 1).sleep_with_group(None)
        Traceback (most recent call last):
        ...
        tamias2d.errors.NotInSpace: Body not added to space
        """
        cdef Body group = None
        if body is not None:
            if not isinstance(body, Body):
                raise TypeError("sleep_with_group expects a Body or None, not %r" % (body,))
            group = <Body>body
        tamias_wait_body(&self._body)
        _check_can_sleep(self, group)
        if cpBodyIsSleeping(&self._body):
            return      # same group, checked above
        cpBodySleepWithGroup(&self._body, &group._body if group is not None else NULL)

    # -- arbiters -----------------------------------------------------------------------
    def each_arbiter(self, func, *args, **kwargs):
        """Call ``func(arbiter, *args, **kwargs)`` for each arbiter of the body.

        The arbiters come in Chipmunk's order (the reverse of the solver
        order; in the soft solver, where a step threads onto the body only
        the arbiters that began and unthreads those that ended, newest
        first), each seen from this body (its first shape is on this body).
        Do not keep an Arbiter after the call. An exception raised by
        ``func`` stops the iteration and propagates.

        >>> import tamias2d
        >>> seen = []
        >>> tamias2d.Body(1, 1).each_arbiter(seen.append)
        >>> seen
        []
        """
        cdef cpBody *body = &self._body
        cdef cpArbiter *arb
        cdef cpArbiter *next_arb
        cdef cpBool swapped
        tamias_wait_body(body)
        arb = body.arbiterList
        if arb == NULL or body.space == NULL:
            return
        space = self.space
        if space is None:
            return
        factory = _get_arbiter_factory()
        while arb != NULL:
            next_arb = cpArbiterNext(arb, body)
            # Seen from this body while the callback runs, as Munk2D does.
            swapped = arb.swapped
            arb.swapped = body == arb.body_b
            try:
                func(factory(<uintptr_t>arb, space), *args, **kwargs)
            finally:
                arb.swapped = swapped
            arb = next_arb

    # -- copy and pickle (pymunk's layout, shared in tamias2d._pickle) ----------------------
    def __getstate__(self):
        """The body's state as pymunk lays it out (used by copy and pickle).

        >>> import tamias2d
        >>> sorted(tamias2d.Body(1, 2).__getstate__())
        ['custom', 'general', 'init', 'special']
        """
        cdef dict d = pymunk_getstate(self)
        d["special"] += [("is_sleeping", self.is_sleeping),
                         ("_velocity_func", self._velocity_func),
                         ("_position_func", self._position_func)]
        if self._body.isBullet:
            # (only when set: a default body keeps pymunk's layout)
            d["special"].append(("is_bullet", True))
        return d

    def __setstate__(self, state):
        """Restore a state made by :meth:`__getstate__` (used by unpickling).

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.__setstate__(tamias2d.Body(3, 4).__getstate__())
        >>> b.mass
        3.0
        """
        if isinstance(state, tuple):
            # The compact state of __reduce_ex__ (see tamias2d._snapshot).
            _snapshot().body_setstate(self, state)
            return
        pymunk_setstate(self, state)
        for k, v in state["special"]:
            # A sleeping body comes back awake.
            if k == "is_bullet":
                self.is_bullet = v
            elif k == "_velocity_func" and v is not None:
                self.velocity_func = v
            elif k == "_position_func" and v is not None:
                self.position_func = v

    def __reduce__(self):
        return pymunk_reduce(self)

    def __reduce_ex__(self, protocol):
        """What copy and pickle use: the C struct as bytes, the user
        attributes and the integrators (pymunk's layout for a subclass that
        overrides ``__getstate__`` or ``__setstate__``). A body restored on
        its own comes back as pymunk restores it; inside a space's state it
        comes back bit for bit (see tamias2d._snapshot).

        >>> import pickle, tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.position = 0.1, 0.2
        >>> pickle.loads(pickle.dumps(b)).position == b.position
        True
        """
        return _snapshot().body_reduce(self)

    def copy(self):
        """A deep copy of the body (without its shapes, constraints or space).

        >>> import tamias2d
        >>> b = tamias2d.Body(1, 2)
        >>> b.position = 5, 6
        >>> c = b.copy()
        >>> c.position, c is b
        (Vec2d(5.0, 6.0), False)
        """
        return deep_copy(self)


# The C defaults behind Body.update_velocity / Body.update_position, for the
# func setters' "restore the default" test.
cdef object _default_update_velocity = Body.update_velocity
cdef object _default_update_position = Body.update_position
