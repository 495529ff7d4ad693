# Rigid Body module (MIS section 6): cpBody functions (cpBody.c) and the Python
# Body. The class layout below is shared with shape, collision and space;
# change it only together with them.
from libc.math cimport INFINITY
from tamias2d._config cimport cpFloat, cpBool
from tamias2d._structs cimport (cpBody, cpShape, cpSpace, cpArbiter, cpBodyType,
    cpConstraint, cpBodyVelocityFunc, cpBodyPositionFunc,
    CP_BODY_TYPE_DYNAMIC, CP_BODY_TYPE_KINEMATIC, CP_BODY_TYPE_STATIC)
from tamias2d.vector cimport (cpVect, cpTransform, cpv, cpvadd, cpvsub, cpvmult,
    cpvperp, cpvdot, cpTransformPoint, cpTransformVect, cpTransformRigidInverse)

cdef class Body:
    cdef cpBody _body            # the C body, embedded; C code uses &self._body
    cdef object _space           # weakref.ref to the Space holding it, or None
    cdef dict _shapes            # Shape -> None, the shapes attached (insertion order)
    cdef object _velocity_func   # Python override of the velocity integrator, or None
    cdef object _position_func   # Python override of the position integrator, or None
    cdef dict __dict__           # user attributes, as pymunk allows
    cdef object __weakref__

# Notes on the Python side of the layout, for the shape and space modules:
#   * _body.userData is a borrowed pointer to the Body itself (set in
#     __cinit__); `id` is that pointer as an int.
#   * _shapes is None until __init__ (or unpickling) has run, {} after.
#     Shapes add and remove themselves: body._shapes[shape] = None.
#   * _space is set by the space module: weakref.ref(space) on add, None on
#     remove; the space also sets/clears _body.space. body->space->userData
#     must be a borrowed pointer to the Python Space (the integrator
#     trampolines report callback errors through it).

# -- hooks installed by the space module ------------------------------------------
# The body sits below the space, yet a few body operations reach into space
# internals. Munk2D calls those functions directly; here the space module fills
# this table once at import with tamias_set_body_space_hooks(&hooks). A NULL
# entry (or a body whose space is NULL) means the body-only part runs alone,
# which is exactly Munk2D's behaviour for a body outside any space.
#
# wake_component(space, root)
#     Called by cpBodyActivate when the body's component root is asleep, i.e.
#     Munk2D's inner block of cpBodyActivate: walk the chain from `root`
#     following sleeping.next (read next before touching a body); for each
#     body set sleeping.idleTime = 0, sleeping.root = sleeping.next = NULL and
#     call cpSpaceActivateBody(space, body); then
#     cpArrayDeleteObj(space->sleepingComponents, root). `space` is root->space.
#     cpBodyActivate itself resets the body's idle time before, and the idle
#     times of non-static bodies it touches after (body-only work).
#
# body_type_changed(space, body, old_type, new_type)
#     The in-space half of cpBodySetType, called after the body's fields were
#     updated and after cpBodyActivate(body) ran (skipped when old_type was
#     STATIC, as Munk2D does): move the body between the arrays given by
#     cpSpaceArrayForBodyType (cpArrayDeleteObj from the old, cpArrayPush to the
#     new) when they differ, then, when the static/dynamic index differs, for
#     each shape in shapeList order remove it from the old index and insert it
#     into the new one. The Python setter has already checked the space is
#     unlocked (Munk2D's cpAssertSpaceUnlocked).
#
# sleep_with_group(body, group)
#     cpBodySleepWithGroup after its hard asserts, which Body.sleep_with_group
#     checks in Python first (dynamic body, in a space, space unlocked,
#     sleeping enabled, group NULL or sleeping, a sleeping body's group
#     unchanged). `group` may be NULL (cpBodySleep).
#
# Every hook runs with or without the GIL and must not raise.
ctypedef void (*tamias_WakeComponentFunc)(cpSpace *space, cpBody *root) noexcept nogil
ctypedef void (*tamias_BodyTypeChangedFunc)(cpSpace *space, cpBody *body,
        cpBodyType old_type, cpBodyType new_type) noexcept nogil
ctypedef void (*tamias_SleepWithGroupFunc)(cpBody *body, cpBody *group) noexcept nogil

cdef struct tamias_BodySpaceHooks:
    tamias_WakeComponentFunc wake_component
    tamias_BodyTypeChangedFunc body_type_changed
    tamias_SleepWithGroupFunc sleep_with_group

# Copies the table (the caller's struct need not outlive the call).
cdef void tamias_set_body_space_hooks(const tamias_BodySpaceHooks *hooks) noexcept nogil

# Body.each_arbiter builds its Arbiter objects through a factory of the space
# module, imported lazily on first use:
#     tamias2d.space._arbiter_for_body(arb_ptr: int, space: Space) -> Arbiter
# where arb_ptr is <uintptr_t> of the cpArbiter*. It is called while the
# arbiter's `swapped` flag is set for the iterating body (Munk2D's
# cpBodyEachArbiter), so the Arbiter must read it live, not cache it.
#
# The velocity/position trampolines report a Python exception raised in a
# user integrator through the Python Space: body->space->userData is cast to
# the Space and `space._store_callback_error(exc)` is called (the space keeps
# the first error and re-raises it from step()). Without a space the error is
# printed as an unraisable exception.

# -- C level: cpBody.c ---------------------------------------------------------------
cdef cpBody *cpBodyInit(cpBody *body, cpFloat mass, cpFloat moment) noexcept nogil
cdef void cpBodySetType(cpBody *body, cpBodyType type) noexcept nogil
cdef void cpBodyAccumulateMassFromShapes(cpBody *body) noexcept nogil
# cpBodySetMass/SetMoment have no checks here: Munk2D's hard asserts are the
# Python setters' job (callers inside the engine pass valid values).
cdef void cpBodySetMass(cpBody *body, cpFloat mass) noexcept nogil
cdef void cpBodySetMoment(cpBody *body, cpFloat moment) noexcept nogil
cdef void cpBodyAddShape(cpBody *body, cpShape *shape) noexcept nogil
cdef void cpBodyRemoveShape(cpBody *body, cpShape *shape) noexcept nogil
cdef void cpBodyRemoveConstraint(cpBody *body, cpConstraint *constraint) noexcept nogil
cdef void cpBodySetPosition(cpBody *body, cpVect position) noexcept nogil
cdef void cpBodySetCenterOfGravity(cpBody *body, cpVect cog) noexcept nogil
cdef void cpBodySetVelocity(cpBody *body, cpVect velocity) noexcept nogil
cdef void cpBodySetForce(cpBody *body, cpVect force) noexcept nogil
cdef void cpBodySetAngle(cpBody *body, cpFloat angle) noexcept nogil
cdef void cpBodySetAngularVelocity(cpBody *body, cpFloat angularVelocity) noexcept nogil
cdef void cpBodySetTorque(cpBody *body, cpFloat torque) noexcept nogil
cdef void cpBodyUpdateVelocity(cpBody *body, cpVect gravity, cpFloat damping, cpFloat dt) noexcept nogil
cdef void cpBodyUpdatePosition(cpBody *body, cpFloat dt) noexcept nogil
cdef void cpBodyApplyForceAtWorldPoint(cpBody *body, cpVect force, cpVect point) noexcept nogil
cdef void cpBodyApplyForceAtLocalPoint(cpBody *body, cpVect force, cpVect point) noexcept nogil
cdef void cpBodyApplyImpulseAtWorldPoint(cpBody *body, cpVect impulse, cpVect point) noexcept nogil
cdef void cpBodyApplyImpulseAtLocalPoint(cpBody *body, cpVect impulse, cpVect point) noexcept nogil
# cpSpaceComponent.c, body side (see the hooks above for the space side).
cdef void cpBodyActivate(cpBody *body) noexcept nogil
# A body outside every space and jointed into none forgets a component root
# left over from a component that stayed awake (see body.pyx).
cdef void tamias_body_drop_stale_root(cpBody *body) noexcept nogil
cdef void cpBodyActivateStatic(cpBody *body, cpShape *filter) noexcept nogil
cdef void cpBodySleep(cpBody *body) noexcept nogil
cdef void cpBodySleepWithGroup(cpBody *body, cpBody *group) noexcept nogil
# The integrator trampolines that call a Python velocity_func / position_func
# (installed by the Body setters; exposed so the space can recognise them).
cdef void tamias_body_velocity_trampoline(cpBody *body, cpVect gravity, cpFloat damping, cpFloat dt) noexcept nogil
cdef void tamias_body_position_trampoline(cpBody *body, cpFloat dt) noexcept nogil

# -- small readers, inline so the step and the collision code pay no call ----------
cdef inline cpBool cpBodyIsSleeping(const cpBody *body) noexcept nogil:
    return body.sleeping.root != NULL

# The type is derived, never stored: an infinite idle time marks a static body,
# an infinite mass a kinematic one.
cdef inline cpBodyType cpBodyGetType(const cpBody *body) noexcept nogil:
    if body.sleeping.idleTime == INFINITY:
        return CP_BODY_TYPE_STATIC
    elif body.m == INFINITY:
        return CP_BODY_TYPE_KINEMATIC
    return CP_BODY_TYPE_DYNAMIC

cdef inline cpSpace *cpBodyGetSpace(const cpBody *body) noexcept nogil:
    return body.space

cdef inline cpVect cpBodyGetRotation(const cpBody *body) noexcept nogil:
    return cpv(body.transform.a, body.transform.b)

# The origin of the body, read through the transform as Munk2D does (so a
# -0.0 translation reads back as 0.0 exactly like pymunk's).
cdef inline cpVect cpBodyGetPosition(const cpBody *body) noexcept nogil:
    return cpTransformPoint(body.transform, cpv(0.0, 0.0))

cdef inline cpVect cpBodyLocalToWorld(const cpBody *body, cpVect point) noexcept nogil:
    return cpTransformPoint(body.transform, point)

cdef inline cpVect cpBodyWorldToLocal(const cpBody *body, cpVect point) noexcept nogil:
    return cpTransformPoint(cpTransformRigidInverse(body.transform), point)

cdef inline cpVect cpBodyGetVelocityAtLocalPoint(const cpBody *body, cpVect point) noexcept nogil:
    cdef cpVect r = cpTransformVect(body.transform, cpvsub(point, body.cog))
    return cpvadd(body.v, cpvmult(cpvperp(r), body.w))

cdef inline cpVect cpBodyGetVelocityAtWorldPoint(const cpBody *body, cpVect point) noexcept nogil:
    cdef cpVect r = cpvsub(point, cpTransformPoint(body.transform, body.cog))
    return cpvadd(body.v, cpvmult(cpvperp(r), body.w))

# m|v|^2 + i w^2 without the one-half; a zero square skips its term so an
# infinite mass or moment at rest gives 0 instead of NaN.
cdef inline cpFloat cpBodyKineticEnergy(const cpBody *body) noexcept nogil:
    cdef cpFloat vsq = cpvdot(body.v, body.v)
    cdef cpFloat wsq = body.w * body.w
    return (vsq * body.m if vsq != 0.0 else 0.0) + (wsq * body.i if wsq != 0.0 else 0.0)

# The chipmunk_private.h helpers the body code also needs (apply_impulse,
# cpArbiterNext, cpConstraintNext) are kept private in body.pyx: collision.pxd
# and arbiter.pxd export the shared copies, and body may not cimport them.
