"""Constraints (joints): how two bodies are held together or driven.

The ten joints of pymunk 7.3 (``pymunk.constraints``), with the same names,
constructors, properties and defaults: :class:`PinJoint`,
:class:`SlideJoint`, :class:`PivotJoint`, :class:`GrooveJoint`,
:class:`DampedSpring`, :class:`DampedRotarySpring`,
:class:`RotaryLimitJoint`, :class:`RatchetJoint`, :class:`GearJoint` and
:class:`SimpleMotor`, all derived from :class:`Constraint`.

The C part is a port of Munk2D's cpConstraint.c and of its one file per joint
(pre-step, warm start, impulse and impulse read-out of each joint, with the
same arithmetic), so a scene with joints gives the same numbers as pymunk. A
step runs without the GIL unless a Python callback is installed
(``pre_solve``, ``post_solve``, a spring's ``force_func`` / ``torque_func``).

>>> import tamias2d
>>> space = tamias2d.Space()
>>> a, b = tamias2d.Body(10, 10), tamias2d.Body(10, 10)
>>> b.position = 0, -10
>>> joint = tamias2d.constraints.PinJoint(a, b)
>>> space.add(a, b, joint)
>>> joint.distance
10.0
"""
cimport cython
from libc.math cimport INFINITY, pow, exp, floor, isfinite, isnan
from libc.string cimport memset
from libc.stdint cimport uintptr_t
from cpython.ref cimport PyObject, Py_INCREF

import weakref

from tamias2d._config cimport cpFloat, cpBool, TAMIAS_FLOAT_0_9F
from tamias2d._structs cimport (cpBody, cpShape, cpSpace, cpArray, cpConstraint, cpConstraintClass,
    cpSoftness,
    CP_BODY_TYPE_DYNAMIC, CP_BODY_TYPE_KINEMATIC, CP_BODY_TYPE_STATIC)
from tamias2d._containers cimport cpArrayDeleteObj
from tamias2d.vector cimport (cpVect, cpMat2x2, cpTransform, cpv, cpvzero, cpveql, cpvadd,
    cpvsub, cpvneg, cpvmult, cpvdot, cpvcross, cpvperp, cpvlength, cpvnormalize, cpvclamp,
    cpvproject, cpfabs, cpfclamp, cpMat2x2Transform, cpTransformPoint, cpTransformVect,
    vec2d_from_cpv, cpv_from_object_finite)
from tamias2d.body cimport (Body, cpBodyActivate, cpBodyGetType, cpBodyWorldToLocal,
    cpBodyRemoveConstraint)
from tamias2d._threadguard cimport tamias_wait_constraint
from tamias2d._private cimport cpConstraintNext
from tamias2d._pickle cimport pymunk_getstate, pymunk_setstate, pymunk_reduce, deep_copy
from tamias2d.collision cimport (relative_velocity, normal_relative_velocity, apply_impulses,
    k_scalar)

from tamias2d.errors import IllegalBody, IllegalConstraint, UnsolvableCollision

cdef extern from "Python.h":
    void PyErr_Restore(PyObject *type, PyObject *value, PyObject *tb)
    void PyErr_WriteUnraisable(object obj)

__all__ = [
    "Constraint", "PinJoint", "SlideJoint", "PivotJoint", "GrooveJoint", "DampedSpring",
    "DampedRotarySpring", "RotaryLimitJoint", "RatchetJoint", "GearJoint", "SimpleMotor",
]


# == C level ====================================================================================

# -- cpConstraint.c ---------------------------------------------------------------------------
cdef void cpConstraintInit(cpConstraint *constraint, const cpConstraintClass *klass,
                           cpBody *a, cpBody *b) noexcept nogil:
    constraint.klass = klass
    constraint.a = a
    constraint.b = b
    constraint.space = NULL
    constraint.next_a = NULL
    constraint.next_b = NULL
    constraint.maxForce = INFINITY
    # pow(1.0f - 0.1f, 60.0f) in Munk2D: the float literal matters.
    constraint.errorBias = pow(TAMIAS_FLOAT_0_9F, 60.0)
    constraint.maxBias = INFINITY
    constraint.collideBodies = 1
    constraint.preSolve = NULL
    constraint.postSolve = NULL

cdef cpFloat cpConstraintGetImpulse(cpConstraint *constraint) noexcept nogil:
    return constraint.klass.getImpulse(constraint)


# -- the soft solver's joints -------------------------------------------------------------------
# Each joint has a second pre-step and impulse for the soft solver
# (_soft_step.pyx), the way Box2D v3 solves its joints: the pre-step does
# Chipmunk's geometry but keeps the position error itself in `bias` (the
# quantity Chipmunk scales by -bias_coef/dt); the impulse turns it into a
# target speed with the substep's softness, capped by max_bias, and softens
# the effective mass. max_force caps the accumulated impulse as in Chipmunk;
# error_bias is not used. A NULL softness is the relax pass: rigid, no
# correction.
#
# The limits (slide joint, rotary limit, ratchet) are one-sided, and Box2D's
# way with them is kept too: the nearer limit is solved even before it is
# reached, speculatively (the bodies may close the gap C within the substep
# and no further, target speed -C/h), so a body swinging into a limit stops
# at it instead of overshooting for a substep; past it the spring pushes
# back. Their `bias` holds C (negative past the limit).
cdef cpSoftness _RIGID
_RIGID.biasRate = 0.0
_RIGID.massScale = 1.0
_RIGID.impulseScale = 0.0

cdef inline cpFloat _softBias(const cpSoftness *soft, cpFloat error, cpFloat maxBias) noexcept nogil:
    # What Chipmunk's bias would be, from a spring instead of bias_coef.
    return cpfclamp(-soft.biasRate * error, -maxBias, maxBias)

cdef inline cpFloat _softLimitImpulse(const cpSoftness *soft, cpFloat gap, cpFloat gapSpeed,
                                      cpFloat mass, cpFloat accumulated, cpFloat maxBias,
                                      cpFloat h) noexcept nogil:
    # The impulse (>= 0 pushes the gap open) that keeps a limit's gap from
    # closing: speculative and rigid while open, soft once closed.
    if gap > 0.0:
        return -(gapSpeed + gap / h) * mass
    if soft == NULL:
        soft = &_RIGID
    return (-soft.massScale * (gapSpeed + _softBias(soft, -gap, maxBias)) * mass
            - soft.impulseScale * accumulated)


# -- cpPinJoint.c ------------------------------------------------------------------------------
cdef cpConstraintClass _pinJointClass

cdef inline cpFloat _pinGeometry(cpPinJoint *joint, cpBody *a, cpBody *b) noexcept nogil:
    # Anchors, axis and effective mass; returns the anchors' distance.
    joint.r1 = cpTransformVect(a.transform, cpvsub(joint.anchorA, a.cog))
    joint.r2 = cpTransformVect(b.transform, cpvsub(joint.anchorB, b.cog))
    cdef cpVect delta = cpvsub(cpvadd(b.p, joint.r2), cpvadd(a.p, joint.r1))
    cdef cpFloat dist = cpvlength(delta)
    joint.n = cpvmult(delta, 1.0 / (dist if dist != 0.0 else INFINITY))
    joint.nMass = 1.0 / k_scalar(a, b, joint.r1, joint.r2, joint.n)
    return dist

cdef void _pinPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpPinJoint *joint = <cpPinJoint *>c
    cdef cpFloat dist = _pinGeometry(joint, c.a, c.b)
    cdef cpFloat maxBias = c.maxBias
    joint.bias = cpfclamp(-bias_coef(c.errorBias, dt) * (dist - joint.dist) / dt, -maxBias, maxBias)

cdef void _pinSoftPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpPinJoint *joint = <cpPinJoint *>c
    joint.bias = _pinGeometry(joint, c.a, c.b) - joint.dist

cdef void _pinApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    cdef cpPinJoint *joint = <cpPinJoint *>c
    cdef cpVect j = cpvmult(joint.n, joint.jnAcc * dt_coef)
    apply_impulses(c.a, c.b, joint.r1, joint.r2, j)

cdef inline void _pinAccumulate(cpConstraint *c, cpPinJoint *joint, cpFloat jn,
                                cpFloat dt) noexcept nogil:
    cdef cpFloat jnMax = c.maxForce * dt
    cdef cpFloat jnOld = joint.jnAcc
    joint.jnAcc = cpfclamp(jnOld + jn, -jnMax, jnMax)
    jn = joint.jnAcc - jnOld
    apply_impulses(c.a, c.b, joint.r1, joint.r2, cpvmult(joint.n, jn))

cdef void _pinApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpPinJoint *joint = <cpPinJoint *>c
    cdef cpFloat vrn = normal_relative_velocity(c.a, c.b, joint.r1, joint.r2, joint.n)
    _pinAccumulate(c, joint, (joint.bias - vrn) * joint.nMass, dt)

cdef void _pinSoftApplyImpulse(cpConstraint *c, cpFloat dt, const cpSoftness *soft) noexcept nogil:
    cdef cpPinJoint *joint = <cpPinJoint *>c
    if soft == NULL:
        soft = &_RIGID
    cdef cpFloat vrn = normal_relative_velocity(c.a, c.b, joint.r1, joint.r2, joint.n)
    cdef cpFloat bias = _softBias(soft, joint.bias, c.maxBias)
    _pinAccumulate(c, joint, soft.massScale * (bias - vrn) * joint.nMass
                   - soft.impulseScale * joint.jnAcc, dt)

cdef cpFloat _pinGetImpulse(cpConstraint *c) noexcept nogil:
    return cpfabs((<cpPinJoint *>c).jnAcc)

_pinJointClass.preStep = _pinPreStep
_pinJointClass.applyCachedImpulse = _pinApplyCachedImpulse
_pinJointClass.applyImpulse = _pinApplyImpulse
_pinJointClass.getImpulse = _pinGetImpulse
_pinJointClass.softPreStep = _pinSoftPreStep
_pinJointClass.softApplyImpulse = _pinSoftApplyImpulse

cdef cpPinJoint *cpPinJointInit(cpPinJoint *joint, cpBody *a, cpBody *b,
                                cpVect anchorA, cpVect anchorB) noexcept nogil:
    cpConstraintInit(&joint.constraint, &_pinJointClass, a, b)
    joint.anchorA = anchorA
    joint.anchorB = anchorB
    # The rest length is the anchors' distance now (a missing body counts as
    # the world frame).
    cdef cpVect p1 = cpTransformPoint(a.transform, anchorA) if a != NULL else anchorA
    cdef cpVect p2 = cpTransformPoint(b.transform, anchorB) if b != NULL else anchorB
    joint.dist = cpvlength(cpvsub(p2, p1))
    joint.jnAcc = 0.0
    return joint

cdef cpBool cpConstraintIsPinJoint(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_pinJointClass


# -- cpSlideJoint.c ------------------------------------------------------------------------------
cdef cpConstraintClass _slideJointClass

cdef inline cpVect _slideArms(cpSlideJoint *joint, cpBody *a, cpBody *b) noexcept nogil:
    # The anchors' arms; returns the anchors' separation.
    joint.r1 = cpTransformVect(a.transform, cpvsub(joint.anchorA, a.cog))
    joint.r2 = cpTransformVect(b.transform, cpvsub(joint.anchorB, b.cog))
    return cpvsub(cpvadd(b.p, joint.r2), cpvadd(a.p, joint.r1))

cdef void _slidePreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpSlideJoint *joint = <cpSlideJoint *>c
    cdef cpBody *a = c.a
    cdef cpBody *b = c.b
    cdef cpVect delta = _slideArms(joint, a, b)
    cdef cpFloat dist = cpvlength(delta)
    cdef cpFloat pdist = 0.0
    if dist > joint.max:
        pdist = dist - joint.max
        joint.n = cpvnormalize(delta)
    elif dist < joint.min:
        pdist = joint.min - dist
        joint.n = cpvneg(cpvnormalize(delta))
    else:
        joint.n = cpvzero()
        joint.jnAcc = 0.0
    joint.nMass = 1.0 / k_scalar(a, b, joint.r1, joint.r2, joint.n)
    cdef cpFloat maxBias = c.maxBias
    joint.bias = cpfclamp(-bias_coef(c.errorBias, dt) * pdist / dt, -maxBias, maxBias)

cdef void _slideSoftPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    # The nearer limit, whether reached or not; its gap in bias.
    cdef cpSlideJoint *joint = <cpSlideJoint *>c
    cdef cpBody *a = c.a
    cdef cpBody *b = c.b
    cdef cpVect delta = _slideArms(joint, a, b)
    cdef cpFloat dist = cpvlength(delta)
    cdef cpVect n
    if dist - joint.min < joint.max - dist:
        joint.bias = dist - joint.min
        n = cpvneg(cpvnormalize(delta))
    else:
        joint.bias = joint.max - dist
        n = cpvnormalize(delta)
    if cpvdot(n, joint.n) < 0.0:
        joint.jnAcc = 0.0  # the other limit's impulse
    joint.n = n
    joint.nMass = 1.0 / k_scalar(a, b, joint.r1, joint.r2, n)

cdef void _slideApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    cdef cpSlideJoint *joint = <cpSlideJoint *>c
    cdef cpVect j = cpvmult(joint.n, joint.jnAcc * dt_coef)
    apply_impulses(c.a, c.b, joint.r1, joint.r2, j)

cdef inline void _slideAccumulate(cpConstraint *c, cpSlideJoint *joint, cpFloat jn,
                                  cpFloat dt) noexcept nogil:
    # A slide joint only pulls (or only pushes) along its axis.
    cdef cpFloat jnOld = joint.jnAcc
    joint.jnAcc = cpfclamp(jnOld + jn, -c.maxForce * dt, 0.0)
    jn = joint.jnAcc - jnOld
    apply_impulses(c.a, c.b, joint.r1, joint.r2, cpvmult(joint.n, jn))

cdef void _slideApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpSlideJoint *joint = <cpSlideJoint *>c
    if cpveql(joint.n, cpvzero()):
        return  # within the limits: nothing to do
    cdef cpVect vr = relative_velocity(c.a, c.b, joint.r1, joint.r2)
    cdef cpFloat vrn = cpvdot(vr, joint.n)
    _slideAccumulate(c, joint, (joint.bias - vrn) * joint.nMass, dt)

cdef void _slideSoftApplyImpulse(cpConstraint *c, cpFloat dt, const cpSoftness *soft) noexcept nogil:
    cdef cpSlideJoint *joint = <cpSlideJoint *>c
    if cpveql(joint.n, cpvzero()):
        return  # the anchors coincide: no axis
    # (The joint's impulse along n is negative: it holds the gap.)
    cdef cpVect vr = relative_velocity(c.a, c.b, joint.r1, joint.r2)
    cdef cpFloat vrn = cpvdot(vr, joint.n)
    _slideAccumulate(c, joint, -_softLimitImpulse(soft, joint.bias, -vrn, joint.nMass,
                                                  -joint.jnAcc, c.maxBias, dt), dt)

cdef cpFloat _slideGetImpulse(cpConstraint *c) noexcept nogil:
    return cpfabs((<cpSlideJoint *>c).jnAcc)

_slideJointClass.preStep = _slidePreStep
_slideJointClass.applyCachedImpulse = _slideApplyCachedImpulse
_slideJointClass.applyImpulse = _slideApplyImpulse
_slideJointClass.getImpulse = _slideGetImpulse
_slideJointClass.softPreStep = _slideSoftPreStep
_slideJointClass.softApplyImpulse = _slideSoftApplyImpulse

cdef cpSlideJoint *cpSlideJointInit(cpSlideJoint *joint, cpBody *a, cpBody *b, cpVect anchorA,
                                    cpVect anchorB, cpFloat min, cpFloat max) noexcept nogil:
    cpConstraintInit(&joint.constraint, &_slideJointClass, a, b)
    joint.anchorA = anchorA
    joint.anchorB = anchorB
    joint.min = min
    joint.max = max
    joint.jnAcc = 0.0
    return joint

cdef cpBool cpConstraintIsSlideJoint(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_slideJointClass


# -- cpPivotJoint.c ------------------------------------------------------------------------------
cdef cpConstraintClass _pivotJointClass

cdef inline cpVect _pivotGeometry(cpPivotJoint *joint, cpBody *a, cpBody *b) noexcept nogil:
    # Anchors and mass tensor; returns the anchors' separation.
    joint.r1 = cpTransformVect(a.transform, cpvsub(joint.anchorA, a.cog))
    joint.r2 = cpTransformVect(b.transform, cpvsub(joint.anchorB, b.cog))
    joint.k = k_tensor(a, b, joint.r1, joint.r2)
    return cpvsub(cpvadd(b.p, joint.r2), cpvadd(a.p, joint.r1))

cdef void _pivotPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpPivotJoint *joint = <cpPivotJoint *>c
    cdef cpVect delta = _pivotGeometry(joint, c.a, c.b)
    joint.bias = cpvclamp(cpvmult(delta, -bias_coef(c.errorBias, dt) / dt), c.maxBias)

cdef void _pivotSoftPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpPivotJoint *joint = <cpPivotJoint *>c
    joint.bias = _pivotGeometry(joint, c.a, c.b)

cdef void _pivotApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    cdef cpPivotJoint *joint = <cpPivotJoint *>c
    apply_impulses(c.a, c.b, joint.r1, joint.r2, cpvmult(joint.jAcc, dt_coef))

cdef inline void _pivotAccumulate(cpConstraint *c, cpPivotJoint *joint, cpVect j,
                                  cpFloat dt) noexcept nogil:
    cdef cpVect jOld = joint.jAcc
    joint.jAcc = cpvclamp(cpvadd(joint.jAcc, j), c.maxForce * dt)
    j = cpvsub(joint.jAcc, jOld)
    apply_impulses(c.a, c.b, joint.r1, joint.r2, j)

cdef inline cpVect _softVectImpulse(const cpSoftness *soft, cpMat2x2 k, cpVect error,
                                    cpFloat maxBias, cpVect vr, cpVect acc) noexcept nogil:
    # The soft impulse of a point constraint (pivot, groove).
    if soft == NULL:
        return cpMat2x2Transform(k, cpvneg(vr))
    cdef cpVect bias = cpvclamp(cpvmult(error, -soft.biasRate), maxBias)
    return cpvsub(cpvmult(cpMat2x2Transform(k, cpvsub(bias, vr)), soft.massScale),
                  cpvmult(acc, soft.impulseScale))

cdef void _pivotApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpPivotJoint *joint = <cpPivotJoint *>c
    cdef cpVect vr = relative_velocity(c.a, c.b, joint.r1, joint.r2)
    _pivotAccumulate(c, joint, cpMat2x2Transform(joint.k, cpvsub(joint.bias, vr)), dt)

cdef void _pivotSoftApplyImpulse(cpConstraint *c, cpFloat dt, const cpSoftness *soft) noexcept nogil:
    cdef cpPivotJoint *joint = <cpPivotJoint *>c
    cdef cpVect vr = relative_velocity(c.a, c.b, joint.r1, joint.r2)
    _pivotAccumulate(c, joint, _softVectImpulse(soft, joint.k, joint.bias, c.maxBias, vr,
                                                joint.jAcc), dt)

cdef cpFloat _pivotGetImpulse(cpConstraint *c) noexcept nogil:
    return cpvlength((<cpPivotJoint *>c).jAcc)

_pivotJointClass.preStep = _pivotPreStep
_pivotJointClass.applyCachedImpulse = _pivotApplyCachedImpulse
_pivotJointClass.applyImpulse = _pivotApplyImpulse
_pivotJointClass.getImpulse = _pivotGetImpulse
_pivotJointClass.softPreStep = _pivotSoftPreStep
_pivotJointClass.softApplyImpulse = _pivotSoftApplyImpulse

cdef cpPivotJoint *cpPivotJointInit(cpPivotJoint *joint, cpBody *a, cpBody *b,
                                    cpVect anchorA, cpVect anchorB) noexcept nogil:
    cpConstraintInit(&joint.constraint, &_pivotJointClass, a, b)
    joint.anchorA = anchorA
    joint.anchorB = anchorB
    joint.jAcc = cpvzero()
    return joint

cdef cpBool cpConstraintIsPivotJoint(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_pivotJointClass


# -- cpGrooveJoint.c -------------------------------------------------------------------------------
cdef cpConstraintClass _grooveJointClass

cdef inline cpVect _grooveGeometry(cpGrooveJoint *joint, cpBody *a, cpBody *b) noexcept nogil:
    # Anchors, clamping side and mass tensor; returns the anchors' separation.
    # The groove's end points and axis in world coordinates.
    cdef cpVect ta = cpTransformPoint(a.transform, joint.grv_a)
    cdef cpVect tb = cpTransformPoint(a.transform, joint.grv_b)
    cdef cpVect n = cpTransformVect(a.transform, joint.grv_n)
    cdef cpFloat d = cpvdot(ta, n)
    joint.grv_tn = n
    joint.r2 = cpTransformVect(b.transform, cpvsub(joint.anchorB, b.cog))
    # Where the anchor lies along the groove decides r1 and the clamping side.
    cdef cpFloat td = cpvcross(cpvadd(b.p, joint.r2), n)
    if td <= cpvcross(ta, n):
        joint.clamp = 1.0
        joint.r1 = cpvsub(ta, a.p)
    elif td >= cpvcross(tb, n):
        joint.clamp = -1.0
        joint.r1 = cpvsub(tb, a.p)
    else:
        joint.clamp = 0.0
        joint.r1 = cpvsub(cpvadd(cpvmult(cpvperp(n), -td), cpvmult(n, d)), a.p)
    joint.k = k_tensor(a, b, joint.r1, joint.r2)
    return cpvsub(cpvadd(b.p, joint.r2), cpvadd(a.p, joint.r1))

cdef void _groovePreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpGrooveJoint *joint = <cpGrooveJoint *>c
    cdef cpVect delta = _grooveGeometry(joint, c.a, c.b)
    joint.bias = cpvclamp(cpvmult(delta, -bias_coef(c.errorBias, dt) / dt), c.maxBias)

cdef void _grooveSoftPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpGrooveJoint *joint = <cpGrooveJoint *>c
    joint.bias = _grooveGeometry(joint, c.a, c.b)

cdef void _grooveApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    cdef cpGrooveJoint *joint = <cpGrooveJoint *>c
    apply_impulses(c.a, c.b, joint.r1, joint.r2, cpvmult(joint.jAcc, dt_coef))

cdef inline cpVect _grooveConstrain(cpGrooveJoint *joint, cpVect j, cpFloat dt) noexcept nogil:
    cdef cpVect n = joint.grv_tn
    cdef cpVect jClamp = j if joint.clamp * cpvcross(j, n) > 0.0 else cpvproject(j, n)
    return cpvclamp(jClamp, joint.constraint.maxForce * dt)

cdef inline void _grooveAccumulate(cpGrooveJoint *joint, cpVect j, cpFloat dt) noexcept nogil:
    cdef cpVect jOld = joint.jAcc
    joint.jAcc = _grooveConstrain(joint, cpvadd(jOld, j), dt)
    j = cpvsub(joint.jAcc, jOld)
    apply_impulses(joint.constraint.a, joint.constraint.b, joint.r1, joint.r2, j)

cdef void _grooveApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpGrooveJoint *joint = <cpGrooveJoint *>c
    cdef cpVect vr = relative_velocity(c.a, c.b, joint.r1, joint.r2)
    _grooveAccumulate(joint, cpMat2x2Transform(joint.k, cpvsub(joint.bias, vr)), dt)

cdef void _grooveSoftApplyImpulse(cpConstraint *c, cpFloat dt, const cpSoftness *soft) noexcept nogil:
    cdef cpGrooveJoint *joint = <cpGrooveJoint *>c
    cdef cpVect vr = relative_velocity(c.a, c.b, joint.r1, joint.r2)
    _grooveAccumulate(joint, _softVectImpulse(soft, joint.k, joint.bias, c.maxBias, vr,
                                              joint.jAcc), dt)

cdef cpFloat _grooveGetImpulse(cpConstraint *c) noexcept nogil:
    return cpvlength((<cpGrooveJoint *>c).jAcc)

_grooveJointClass.preStep = _groovePreStep
_grooveJointClass.applyCachedImpulse = _grooveApplyCachedImpulse
_grooveJointClass.applyImpulse = _grooveApplyImpulse
_grooveJointClass.getImpulse = _grooveGetImpulse
_grooveJointClass.softPreStep = _grooveSoftPreStep
_grooveJointClass.softApplyImpulse = _grooveSoftApplyImpulse

cdef cpGrooveJoint *cpGrooveJointInit(cpGrooveJoint *joint, cpBody *a, cpBody *b,
                                      cpVect groove_a, cpVect groove_b, cpVect anchorB) noexcept nogil:
    cpConstraintInit(&joint.constraint, &_grooveJointClass, a, b)
    joint.grv_a = groove_a
    joint.grv_b = groove_b
    joint.grv_n = cpvperp(cpvnormalize(cpvsub(groove_b, groove_a)))
    joint.anchorB = anchorB
    joint.jAcc = cpvzero()
    return joint

cdef cpBool cpConstraintIsGrooveJoint(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_grooveJointClass


# -- cpDampedSpring.c ----------------------------------------------------------------------------
cdef cpConstraintClass _dampedSpringClass

cdef cpFloat _defaultSpringForce(cpConstraint *c, cpFloat dist) noexcept nogil:
    cdef cpDampedSpring *spring = <cpDampedSpring *>c
    return (spring.restLength - dist) * spring.stiffness

cdef void _springPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpDampedSpring *spring = <cpDampedSpring *>c
    cdef cpBody *a = c.a
    cdef cpBody *b = c.b
    spring.r1 = cpTransformVect(a.transform, cpvsub(spring.anchorA, a.cog))
    spring.r2 = cpTransformVect(b.transform, cpvsub(spring.anchorB, b.cog))
    cdef cpVect delta = cpvsub(cpvadd(b.p, spring.r2), cpvadd(a.p, spring.r1))
    cdef cpFloat dist = cpvlength(delta)
    spring.n = cpvmult(delta, 1.0 / (dist if dist != 0.0 else INFINITY))
    cdef cpFloat k = k_scalar(a, b, spring.r1, spring.r2, spring.n)
    spring.nMass = 1.0 / k
    spring.target_vrn = 0.0
    spring.v_coef = 1.0 - exp(-spring.damping * dt * k)
    # The spring force, clamped by maxForce (Munk2D), applied as one impulse.
    cdef cpFloat f_spring = spring.springForceFunc(c, dist)
    f_spring = cpfclamp(f_spring, -c.maxForce, c.maxForce)
    spring.jAcc = f_spring * dt
    cdef cpFloat j_spring = spring.jAcc
    apply_impulses(a, b, spring.r1, spring.r2, cpvmult(spring.n, j_spring))

cdef void _springApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    pass

cdef void _springApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpDampedSpring *spring = <cpDampedSpring *>c
    cdef cpBody *a = c.a
    cdef cpBody *b = c.b
    cdef cpVect n = spring.n
    cdef cpFloat vrn = normal_relative_velocity(a, b, spring.r1, spring.r2, n)
    # Velocity lost to the damping this iteration.
    cdef cpFloat v_damp = (spring.target_vrn - vrn) * spring.v_coef
    spring.target_vrn = vrn + v_damp
    cdef cpFloat j_damp = v_damp * spring.nMass
    cdef cpFloat maxImpulse = c.maxForce * dt
    cdef cpFloat jAccClamped = cpfclamp(spring.jAcc + j_damp, -maxImpulse, maxImpulse)
    j_damp = jAccClamped - spring.jAcc
    spring.jAcc += j_damp
    apply_impulses(a, b, spring.r1, spring.r2, cpvmult(spring.n, j_damp))

cdef cpFloat _springGetImpulse(cpConstraint *c) noexcept nogil:
    return (<cpDampedSpring *>c).jAcc

cdef void _springSoftApplyImpulse(cpConstraint *c, cpFloat dt, const cpSoftness *soft) noexcept nogil:
    _springApplyImpulse(c, dt)

_dampedSpringClass.preStep = _springPreStep
_dampedSpringClass.applyCachedImpulse = _springApplyCachedImpulse
_dampedSpringClass.applyImpulse = _springApplyImpulse
_dampedSpringClass.getImpulse = _springGetImpulse
# No position error to correct: the soft solver runs Chipmunk's own step.
_dampedSpringClass.softPreStep = _springPreStep
_dampedSpringClass.softApplyImpulse = _springSoftApplyImpulse

cdef cpDampedSpring *cpDampedSpringInit(cpDampedSpring *spring, cpBody *a, cpBody *b,
                                        cpVect anchorA, cpVect anchorB, cpFloat restLength,
                                        cpFloat stiffness, cpFloat damping) noexcept nogil:
    cpConstraintInit(&spring.constraint, &_dampedSpringClass, a, b)
    spring.anchorA = anchorA
    spring.anchorB = anchorB
    spring.restLength = restLength
    spring.stiffness = stiffness
    spring.damping = damping
    spring.springForceFunc = _defaultSpringForce
    spring.jAcc = 0.0
    return spring

cdef cpBool cpConstraintIsDampedSpring(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_dampedSpringClass


# -- cpDampedRotarySpring.c ------------------------------------------------------------------------
cdef cpConstraintClass _dampedRotarySpringClass

cdef cpFloat _defaultSpringTorque(cpConstraint *c, cpFloat relativeAngle) noexcept nogil:
    cdef cpDampedRotarySpring *spring = <cpDampedRotarySpring *>c
    return (relativeAngle - spring.restAngle) * spring.stiffness

cdef void _rotarySpringPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpDampedRotarySpring *spring = <cpDampedRotarySpring *>c
    cdef cpBody *a = c.a
    cdef cpBody *b = c.b
    cdef cpFloat moment = a.i_inv + b.i_inv
    spring.iSum = 1.0 / moment
    spring.w_coef = 1.0 - exp(-spring.damping * dt * moment)
    spring.target_wrn = 0.0
    # The spring torque, clamped by maxForce (Munk2D), applied as one impulse.
    cdef cpFloat t_spring = spring.springTorqueFunc(c, a.a - b.a)
    t_spring = cpfclamp(t_spring, -c.maxForce, c.maxForce)
    cdef cpFloat j_spring = t_spring * dt
    spring.jAcc = j_spring
    a.w -= j_spring * a.i_inv
    b.w += j_spring * b.i_inv

cdef void _rotarySpringApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    pass

cdef void _rotarySpringApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpDampedRotarySpring *spring = <cpDampedRotarySpring *>c
    cdef cpBody *a = c.a
    cdef cpBody *b = c.b
    cdef cpFloat wrn = a.w - b.w
    cdef cpFloat w_damp = (spring.target_wrn - wrn) * spring.w_coef
    spring.target_wrn = wrn + w_damp
    cdef cpFloat j_damp = w_damp * spring.iSum
    cdef cpFloat maxImpulse = c.maxForce * dt
    cdef cpFloat jAccClamped = cpfclamp(spring.jAcc - j_damp, -maxImpulse, maxImpulse)
    j_damp = spring.jAcc - jAccClamped
    spring.jAcc -= j_damp
    a.w += j_damp * a.i_inv
    b.w -= j_damp * b.i_inv

cdef cpFloat _rotarySpringGetImpulse(cpConstraint *c) noexcept nogil:
    return (<cpDampedRotarySpring *>c).jAcc

cdef void _rotarySpringSoftApplyImpulse(cpConstraint *c, cpFloat dt, const cpSoftness *soft) noexcept nogil:
    _rotarySpringApplyImpulse(c, dt)

_dampedRotarySpringClass.preStep = _rotarySpringPreStep
_dampedRotarySpringClass.applyCachedImpulse = _rotarySpringApplyCachedImpulse
_dampedRotarySpringClass.applyImpulse = _rotarySpringApplyImpulse
_dampedRotarySpringClass.getImpulse = _rotarySpringGetImpulse
# No position error to correct: the soft solver runs Chipmunk's own step.
_dampedRotarySpringClass.softPreStep = _rotarySpringPreStep
_dampedRotarySpringClass.softApplyImpulse = _rotarySpringSoftApplyImpulse

cdef cpDampedRotarySpring *cpDampedRotarySpringInit(cpDampedRotarySpring *spring, cpBody *a,
        cpBody *b, cpFloat restAngle, cpFloat stiffness, cpFloat damping) noexcept nogil:
    cpConstraintInit(&spring.constraint, &_dampedRotarySpringClass, a, b)
    spring.restAngle = restAngle
    spring.stiffness = stiffness
    spring.damping = damping
    spring.springTorqueFunc = _defaultSpringTorque
    spring.jAcc = 0.0
    return spring

cdef cpBool cpConstraintIsDampedRotarySpring(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_dampedRotarySpringClass


# -- cpRotaryLimitJoint.c -------------------------------------------------------------------------
cdef cpConstraintClass _rotaryLimitJointClass

cdef void _rotaryLimitPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpRotaryLimitJoint *joint = <cpRotaryLimitJoint *>c
    # How far past a limit (signed).
    cdef cpFloat dist = c.b.a - c.a.a
    cdef cpFloat pdist = 0.0
    if dist > joint.max:
        pdist = joint.max - dist
    elif dist < joint.min:
        pdist = joint.min - dist
    joint.iSum = 1.0 / (c.a.i_inv + c.b.i_inv)
    cdef cpFloat maxBias = c.maxBias
    joint.bias = cpfclamp(-bias_coef(c.errorBias, dt) * pdist / dt, -maxBias, maxBias)
    # Not at a limit: forget the accumulated impulse.
    if joint.bias == 0.0:
        joint.jAcc = 0.0

cdef void _rotaryLimitSoftPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    # The nearer limit, whether reached or not: its side (+1 the lower
    # limit, -1 the upper) and its gap in bias.
    cdef cpRotaryLimitJoint *joint = <cpRotaryLimitJoint *>c
    cdef cpFloat dist = c.b.a - c.a.a
    if dist - joint.min < joint.max - dist:
        joint.softSide = 1.0
        joint.bias = dist - joint.min
    else:
        joint.softSide = -1.0
        joint.bias = joint.max - dist
    if joint.softSide * joint.jAcc < 0.0:
        joint.jAcc = 0.0  # the other limit's impulse
    joint.iSum = 1.0 / (c.a.i_inv + c.b.i_inv)

cdef void _rotaryLimitApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    cdef cpRotaryLimitJoint *joint = <cpRotaryLimitJoint *>c
    cdef cpFloat j = joint.jAcc * dt_coef
    c.a.w -= j * c.a.i_inv
    c.b.w += j * c.b.i_inv

cdef inline void _rotaryLimitAccumulate(cpConstraint *c, cpRotaryLimitJoint *joint, cpFloat j,
                                        bint belowMin, cpFloat dt) noexcept nogil:
    # At the lower limit the joint only pushes, at the upper one only pulls.
    cdef cpFloat jMax = c.maxForce * dt
    cdef cpFloat jOld = joint.jAcc
    if belowMin:
        joint.jAcc = cpfclamp(jOld + j, 0.0, jMax)
    else:
        joint.jAcc = cpfclamp(jOld + j, -jMax, 0.0)
    j = joint.jAcc - jOld
    c.a.w -= j * c.a.i_inv
    c.b.w += j * c.b.i_inv

cdef void _rotaryLimitApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpRotaryLimitJoint *joint = <cpRotaryLimitJoint *>c
    if joint.bias == 0.0:
        return  # not at a limit
    cdef cpFloat wr = c.b.w - c.a.w
    _rotaryLimitAccumulate(c, joint, -(joint.bias + wr) * joint.iSum, joint.bias < 0.0, dt)

cdef void _rotaryLimitSoftApplyImpulse(cpConstraint *c, cpFloat dt,
                                       const cpSoftness *soft) noexcept nogil:
    cdef cpRotaryLimitJoint *joint = <cpRotaryLimitJoint *>c
    cdef cpFloat side = joint.softSide
    cdef cpFloat j = _softLimitImpulse(soft, joint.bias, side * (c.b.w - c.a.w), joint.iSum,
                                       side * joint.jAcc, c.maxBias, dt)
    _rotaryLimitAccumulate(c, joint, side * j, side > 0.0, dt)

cdef cpFloat _rotaryLimitGetImpulse(cpConstraint *c) noexcept nogil:
    return cpfabs((<cpRotaryLimitJoint *>c).jAcc)

_rotaryLimitJointClass.preStep = _rotaryLimitPreStep
_rotaryLimitJointClass.applyCachedImpulse = _rotaryLimitApplyCachedImpulse
_rotaryLimitJointClass.applyImpulse = _rotaryLimitApplyImpulse
_rotaryLimitJointClass.getImpulse = _rotaryLimitGetImpulse
_rotaryLimitJointClass.softPreStep = _rotaryLimitSoftPreStep
_rotaryLimitJointClass.softApplyImpulse = _rotaryLimitSoftApplyImpulse

cdef cpRotaryLimitJoint *cpRotaryLimitJointInit(cpRotaryLimitJoint *joint, cpBody *a, cpBody *b,
                                                cpFloat min, cpFloat max) noexcept nogil:
    cpConstraintInit(&joint.constraint, &_rotaryLimitJointClass, a, b)
    joint.min = min
    joint.max = max
    joint.jAcc = 0.0
    joint.softSide = 1.0
    return joint

cdef cpBool cpConstraintIsRotaryLimitJoint(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_rotaryLimitJointClass


# -- cpRatchetJoint.c ---------------------------------------------------------------------------------
cdef cpConstraintClass _ratchetJointClass

cdef inline cpFloat _ratchetGeometry(cpRatchetJoint *joint, cpBody *a, cpBody *b) noexcept nogil:
    # The notch and the moment; returns how far back past the pawl.
    cdef cpFloat angle = joint.angle
    cdef cpFloat phase = joint.phase
    cdef cpFloat ratchet = joint.ratchet
    cdef cpFloat delta = b.a - a.a
    cdef cpFloat diff = angle - delta
    cdef cpFloat pdist = 0.0
    if diff * ratchet > 0.0:
        pdist = diff
    else:
        # Moved forward: the pawl drops into the next notch.
        joint.angle = floor((delta - phase) / ratchet) * ratchet + phase
    joint.iSum = 1.0 / (a.i_inv + b.i_inv)
    return pdist

cdef inline cpFloat _ratchetSign(cpRatchetJoint *joint) noexcept nogil:
    return 1.0 if joint.ratchet > 0.0 else -1.0

cdef void _ratchetPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpRatchetJoint *joint = <cpRatchetJoint *>c
    cdef cpFloat pdist = _ratchetGeometry(joint, c.a, c.b)
    cdef cpFloat maxBias = c.maxBias
    joint.bias = cpfclamp(-bias_coef(c.errorBias, dt) * pdist / dt, -maxBias, maxBias)
    if joint.bias == 0.0:
        joint.jAcc = 0.0

cdef void _ratchetSoftPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    # The gap back to the pawl (after it drops into the next notch), in the
    # ratchet's direction.
    cdef cpRatchetJoint *joint = <cpRatchetJoint *>c
    _ratchetGeometry(joint, c.a, c.b)
    joint.bias = _ratchetSign(joint) * ((c.b.a - c.a.a) - joint.angle)

cdef void _ratchetApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    cdef cpRatchetJoint *joint = <cpRatchetJoint *>c
    cdef cpFloat j = joint.jAcc * dt_coef
    c.a.w -= j * c.a.i_inv
    c.b.w += j * c.b.i_inv

cdef inline void _ratchetAccumulate(cpConstraint *c, cpRatchetJoint *joint, cpFloat j,
                                    cpFloat dt) noexcept nogil:
    # The pawl only pushes one way (the sign of ratchet).
    cdef cpFloat ratchet = joint.ratchet
    cdef cpFloat jMax = c.maxForce * dt
    cdef cpFloat jOld = joint.jAcc
    joint.jAcc = cpfclamp((jOld + j) * ratchet, 0.0, jMax * cpfabs(ratchet)) / ratchet
    j = joint.jAcc - jOld
    c.a.w -= j * c.a.i_inv
    c.b.w += j * c.b.i_inv

cdef void _ratchetApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpRatchetJoint *joint = <cpRatchetJoint *>c
    if joint.bias == 0.0:
        return  # not pushing against the pawl
    cdef cpFloat wr = c.b.w - c.a.w
    _ratchetAccumulate(c, joint, -(joint.bias + wr) * joint.iSum, dt)

cdef void _ratchetSoftApplyImpulse(cpConstraint *c, cpFloat dt,
                                   const cpSoftness *soft) noexcept nogil:
    cdef cpRatchetJoint *joint = <cpRatchetJoint *>c
    cdef cpFloat side = _ratchetSign(joint)
    cdef cpFloat j = _softLimitImpulse(soft, joint.bias, side * (c.b.w - c.a.w), joint.iSum,
                                       side * joint.jAcc, c.maxBias, dt)
    _ratchetAccumulate(c, joint, side * j, dt)

cdef cpFloat _ratchetGetImpulse(cpConstraint *c) noexcept nogil:
    return cpfabs((<cpRatchetJoint *>c).jAcc)

_ratchetJointClass.preStep = _ratchetPreStep
_ratchetJointClass.applyCachedImpulse = _ratchetApplyCachedImpulse
_ratchetJointClass.applyImpulse = _ratchetApplyImpulse
_ratchetJointClass.getImpulse = _ratchetGetImpulse
_ratchetJointClass.softPreStep = _ratchetSoftPreStep
_ratchetJointClass.softApplyImpulse = _ratchetSoftApplyImpulse

cdef cpRatchetJoint *cpRatchetJointInit(cpRatchetJoint *joint, cpBody *a, cpBody *b,
                                        cpFloat phase, cpFloat ratchet) noexcept nogil:
    cpConstraintInit(&joint.constraint, &_ratchetJointClass, a, b)
    joint.phase = phase
    joint.ratchet = ratchet
    # The current relative angle (a missing body counts as angle 0).
    joint.angle = (b.a if b != NULL else 0.0) - (a.a if a != NULL else 0.0)
    return joint

cdef cpBool cpConstraintIsRatchetJoint(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_ratchetJointClass


# -- cpGearJoint.c ---------------------------------------------------------------------------------------
cdef cpConstraintClass _gearJointClass

cdef inline cpFloat _gearGeometry(cpGearJoint *joint, cpBody *a, cpBody *b) noexcept nogil:
    # The moment; returns the angle error.
    joint.iSum = 1.0 / (a.i_inv * joint.ratio_inv + joint.ratio * b.i_inv)
    return b.a * joint.ratio - a.a - joint.phase

cdef void _gearPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpGearJoint *joint = <cpGearJoint *>c
    cdef cpFloat error = _gearGeometry(joint, c.a, c.b)
    cdef cpFloat maxBias = c.maxBias
    joint.bias = cpfclamp(-bias_coef(c.errorBias, dt) * error / dt, -maxBias, maxBias)

cdef void _gearSoftPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpGearJoint *joint = <cpGearJoint *>c
    joint.bias = _gearGeometry(joint, c.a, c.b)

cdef void _gearApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    cdef cpGearJoint *joint = <cpGearJoint *>c
    cdef cpFloat j = joint.jAcc * dt_coef
    c.a.w -= j * c.a.i_inv * joint.ratio_inv
    c.b.w += j * c.b.i_inv

cdef inline void _gearAccumulate(cpConstraint *c, cpGearJoint *joint, cpFloat j,
                                 cpFloat dt) noexcept nogil:
    cdef cpFloat jMax = c.maxForce * dt
    cdef cpFloat jOld = joint.jAcc
    joint.jAcc = cpfclamp(jOld + j, -jMax, jMax)
    j = joint.jAcc - jOld
    c.a.w -= j * c.a.i_inv * joint.ratio_inv
    c.b.w += j * c.b.i_inv

cdef void _gearApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpGearJoint *joint = <cpGearJoint *>c
    cdef cpFloat wr = c.b.w * joint.ratio - c.a.w
    _gearAccumulate(c, joint, (joint.bias - wr) * joint.iSum, dt)

cdef void _gearSoftApplyImpulse(cpConstraint *c, cpFloat dt, const cpSoftness *soft) noexcept nogil:
    cdef cpGearJoint *joint = <cpGearJoint *>c
    if soft == NULL:
        soft = &_RIGID
    cdef cpFloat wr = c.b.w * joint.ratio - c.a.w
    cdef cpFloat bias = _softBias(soft, joint.bias, c.maxBias)
    _gearAccumulate(c, joint, soft.massScale * (bias - wr) * joint.iSum
                    - soft.impulseScale * joint.jAcc, dt)

cdef cpFloat _gearGetImpulse(cpConstraint *c) noexcept nogil:
    return cpfabs((<cpGearJoint *>c).jAcc)

_gearJointClass.preStep = _gearPreStep
_gearJointClass.applyCachedImpulse = _gearApplyCachedImpulse
_gearJointClass.applyImpulse = _gearApplyImpulse
_gearJointClass.getImpulse = _gearGetImpulse
_gearJointClass.softPreStep = _gearSoftPreStep
_gearJointClass.softApplyImpulse = _gearSoftApplyImpulse

cdef cpGearJoint *cpGearJointInit(cpGearJoint *joint, cpBody *a, cpBody *b,
                                  cpFloat phase, cpFloat ratio) noexcept nogil:
    cpConstraintInit(&joint.constraint, &_gearJointClass, a, b)
    joint.phase = phase
    joint.ratio = ratio
    joint.ratio_inv = 1.0 / ratio
    joint.jAcc = 0.0
    return joint

cdef cpBool cpConstraintIsGearJoint(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_gearJointClass


# -- cpSimpleMotor.c ----------------------------------------------------------------------------------------
cdef cpConstraintClass _simpleMotorClass

cdef void _motorPreStep(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpSimpleMotor *joint = <cpSimpleMotor *>c
    joint.iSum = 1.0 / (c.a.i_inv + c.b.i_inv)

cdef void _motorApplyCachedImpulse(cpConstraint *c, cpFloat dt_coef) noexcept nogil:
    cdef cpSimpleMotor *joint = <cpSimpleMotor *>c
    cdef cpFloat j = joint.jAcc * dt_coef
    c.a.w -= j * c.a.i_inv
    c.b.w += j * c.b.i_inv

cdef void _motorApplyImpulse(cpConstraint *c, cpFloat dt) noexcept nogil:
    cdef cpSimpleMotor *joint = <cpSimpleMotor *>c
    cdef cpBody *a = c.a
    cdef cpBody *b = c.b
    cdef cpFloat wr = b.w - a.w + joint.rate
    cdef cpFloat jMax = c.maxForce * dt
    cdef cpFloat j = -wr * joint.iSum
    cdef cpFloat jOld = joint.jAcc
    joint.jAcc = cpfclamp(jOld + j, -jMax, jMax)
    j = joint.jAcc - jOld
    a.w -= j * a.i_inv
    b.w += j * b.i_inv

cdef cpFloat _motorGetImpulse(cpConstraint *c) noexcept nogil:
    return cpfabs((<cpSimpleMotor *>c).jAcc)

cdef void _motorSoftApplyImpulse(cpConstraint *c, cpFloat dt, const cpSoftness *soft) noexcept nogil:
    _motorApplyImpulse(c, dt)

_simpleMotorClass.preStep = _motorPreStep
_simpleMotorClass.applyCachedImpulse = _motorApplyCachedImpulse
_simpleMotorClass.applyImpulse = _motorApplyImpulse
_simpleMotorClass.getImpulse = _motorGetImpulse
# No position error to correct: the soft solver runs Chipmunk's own step.
_simpleMotorClass.softPreStep = _motorPreStep
_simpleMotorClass.softApplyImpulse = _motorSoftApplyImpulse

cdef cpSimpleMotor *cpSimpleMotorInit(cpSimpleMotor *joint, cpBody *a, cpBody *b,
                                      cpFloat rate) noexcept nogil:
    cpConstraintInit(&joint.constraint, &_simpleMotorClass, a, b)
    joint.rate = rate
    joint.jAcc = 0.0
    return joint

cdef cpBool cpConstraintIsSimpleMotor(const cpConstraint *constraint) noexcept nogil:
    return constraint.klass == &_simpleMotorClass


# -- helpers for the space ------------------------------------------------------------------------------------
cdef void tamias_constraint_detach(cpConstraint *constraint) noexcept nogil:
    cdef cpSpace *space = constraint.space
    if space == NULL:
        return
    if space.constraints != NULL:
        cpArrayDeleteObj(space.constraints, constraint)
    if constraint.a != NULL:
        cpBodyRemoveConstraint(constraint.a, constraint)
    if constraint.b != NULL:
        cpBodyRemoveConstraint(constraint.b, constraint)
    constraint.space = NULL
    constraint.next_a = NULL
    constraint.next_b = NULL


cdef void _detach_body_constraints(cpSpace *space, cpBody *body) noexcept nogil:
    cdef cpConstraint *c = body.constraintList
    cdef cpConstraint *next
    while c != NULL:
        next = cpConstraintNext(c, body)
        if c.space == space:
            # Unlinking c may change the list but never frees `next`.
            tamias_constraint_detach(c)
        c = next

cdef void tamias_constraint_clear_impulse(cpConstraint *c) noexcept nogil:
    # Forget the accumulated impulse that warm-starts the next step: after a
    # step that overflowed it can be inf or NaN and would poison the bodies
    # again once they are reset.
    cdef cpConstraintClass *k = c.klass
    if k == &_pinJointClass:
        (<cpPinJoint *>c).jnAcc = 0.0
    elif k == &_slideJointClass:
        (<cpSlideJoint *>c).jnAcc = 0.0
    elif k == &_pivotJointClass:
        (<cpPivotJoint *>c).jAcc = cpvzero()
    elif k == &_grooveJointClass:
        (<cpGrooveJoint *>c).jAcc = cpvzero()
    elif k == &_dampedSpringClass:
        (<cpDampedSpring *>c).jAcc = 0.0
    elif k == &_dampedRotarySpringClass:
        (<cpDampedRotarySpring *>c).jAcc = 0.0
    elif k == &_rotaryLimitJointClass:
        (<cpRotaryLimitJoint *>c).jAcc = 0.0
    elif k == &_ratchetJointClass:
        (<cpRatchetJoint *>c).jAcc = 0.0
    elif k == &_gearJointClass:
        (<cpGearJoint *>c).jAcc = 0.0
    elif k == &_simpleMotorClass:
        (<cpSimpleMotor *>c).jAcc = 0.0

cdef void tamias_constraint_scale_impulse(cpConstraint *c, cpFloat factor) noexcept nogil:
    # The soft solver keeps a joint's accumulated impulse per substep inside
    # its step and per step between steps (as the chipmunk solver does): it
    # rescales it at the start and the end of its step.
    cdef cpConstraintClass *k = c.klass
    if k == &_pinJointClass:
        (<cpPinJoint *>c).jnAcc *= factor
    elif k == &_slideJointClass:
        (<cpSlideJoint *>c).jnAcc *= factor
    elif k == &_pivotJointClass:
        (<cpPivotJoint *>c).jAcc = cpvmult((<cpPivotJoint *>c).jAcc, factor)
    elif k == &_grooveJointClass:
        (<cpGrooveJoint *>c).jAcc = cpvmult((<cpGrooveJoint *>c).jAcc, factor)
    elif k == &_dampedSpringClass:
        (<cpDampedSpring *>c).jAcc *= factor
    elif k == &_dampedRotarySpringClass:
        (<cpDampedRotarySpring *>c).jAcc *= factor
    elif k == &_rotaryLimitJointClass:
        (<cpRotaryLimitJoint *>c).jAcc *= factor
    elif k == &_ratchetJointClass:
        (<cpRatchetJoint *>c).jAcc *= factor
    elif k == &_gearJointClass:
        (<cpGearJoint *>c).jAcc *= factor
    elif k == &_simpleMotorClass:
        (<cpSimpleMotor *>c).jAcc *= factor

cdef void tamias_space_detach_constraints(cpSpace *space) noexcept nogil:
    cdef cpArray *arr = space.constraints
    cdef cpArray *components = space.sleepingComponents
    cdef cpBody *body
    cdef int i
    if arr != NULL:
        while arr.num > 0:
            tamias_constraint_detach(<cpConstraint *>arr.arr[arr.num - 1])
    # Sleeping components took their constraints out of the array.
    if components != NULL:
        for i in range(components.num):
            body = <cpBody *>components.arr[i]
            while body != NULL:
                _detach_body_constraints(space, body)
                body = body.sleeping.next


cdef enum:
    _OK = 0
    _BAD_BODY_A = 1
    _BAD_BODY_B = 2
    _ZERO_RATCHET = 3
    _ZERO_RATIO = 4
    _NO_ROTATION = 5
    _NO_BODIES = 6
    _FOREIGN_BODY_A = 7
    _FOREIGN_BODY_B = 8
    _ZERO_GROOVE = 9

cdef inline bint _bad_dynamic_body(cpBody *body) noexcept nogil:
    # The step's own rule for the bodies it integrates, applied to bodies that
    # a joint reaches (they may be outside the space).
    return (cpBodyGetType(body) == CP_BODY_TYPE_DYNAMIC
            and not (body.m > 0.0 and body.m < INFINITY and body.i > 0.0))

cdef inline bint _foreign_body(cpSpace *space, cpBody *body) noexcept nogil:
    # With sleeping on, the flood fill puts every dynamic body reached through
    # a joint into a component and moves its shapes between this space's
    # trees. That is harmless for a bare body outside any space, but a body
    # of another space (or with shapes left in a space) would get its shapes
    # into the wrong tree.
    return (space.sleepTimeThreshold != INFINITY
            and cpBodyGetType(body) == CP_BODY_TYPE_DYNAMIC
            and body.space != space
            and (body.space != NULL or body.shapeList != NULL))

cdef inline bint _groove_too_short(cpGrooveJoint *joint) noexcept nogil:
    # groove_a == groove_b (or a groove too short for its direction to be
    # normalised) leaves a zero normal: the impulse is projected on it as
    # 0 / 0.
    return not (cpvdot(joint.grv_n, joint.grv_n) > 0.25)

cdef int _constraint_problem(cpSpace *space, cpConstraint *c) noexcept nogil:
    if c.a == NULL or c.b == NULL:
        return _NO_BODIES
    if _bad_dynamic_body(c.a):
        return _BAD_BODY_A
    if _bad_dynamic_body(c.b):
        return _BAD_BODY_B
    if _foreign_body(space, c.a):
        return _FOREIGN_BODY_A
    if _foreign_body(space, c.b):
        return _FOREIGN_BODY_B
    if cpConstraintIsRatchetJoint(c) and (<cpRatchetJoint *>c).ratchet == 0.0:
        return _ZERO_RATCHET
    if cpConstraintIsGearJoint(c) and (<cpGearJoint *>c).ratio == 0.0:
        return _ZERO_RATIO
    if cpConstraintIsGrooveJoint(c) and _groove_too_short(<cpGrooveJoint *>c):
        return _ZERO_GROOVE
    if ((cpConstraintIsDampedRotarySpring(c) or cpConstraintIsRotaryLimitJoint(c)
            or cpConstraintIsRatchetJoint(c) or cpConstraintIsGearJoint(c)
            or cpConstraintIsSimpleMotor(c))
            and c.a.i_inv + c.b.i_inv == 0.0):
        return _NO_ROTATION
    return _OK

cdef bint tamias_constraints_ok(cpSpace *space) noexcept nogil:
    cdef cpArray *arr = space.constraints
    cdef int i
    for i in range(arr.num):
        if _constraint_problem(space, <cpConstraint *>arr.arr[i]) != _OK:
            return False
    return True

cdef int tamias_check_constraints(cpSpace *space) except -1:
    cdef cpArray *arr = space.constraints
    cdef int i, problem = _OK
    cdef cpConstraint *c = NULL
    with nogil:
        for i in range(arr.num):
            c = <cpConstraint *>arr.arr[i]
            problem = _constraint_problem(space, c)
            if problem != _OK:
                break
    if problem == _OK:
        return 0
    obj = <object>c.userData if c.userData != NULL else None
    if problem == _NO_BODIES:
        raise IllegalBody(f"{obj!r} has no bodies (it was never initialised).")
    if problem == _BAD_BODY_A or problem == _BAD_BODY_B:
        body = obj.a if problem == _BAD_BODY_A else obj.b
        raise IllegalBody(
            f"Dynamic bodies must have a mass > 0 and < inf and moment > 0. {body!r} "
            f"(body {'a' if problem == _BAD_BODY_A else 'b'} of {obj!r}) has mass "
            f"{body.mass}, moment {body.moment}.")
    if problem == _FOREIGN_BODY_A or problem == _FOREIGN_BODY_B:
        body = obj.a if problem == _FOREIGN_BODY_A else obj.b
        raise ValueError(
            f"{obj!r} joins {body!r}, a dynamic body of another space (or with shapes "
            f"still in a space), and sleeping is on: add the body to this space, or "
            f"turn sleeping off.")
    if problem == _ZERO_RATCHET:
        raise IllegalConstraint(f"{obj!r}: the ratchet distance must not be 0 in a step.")
    if problem == _ZERO_RATIO:
        raise IllegalConstraint(f"{obj!r}: the gear ratio must not be 0 in a step.")
    if problem == _ZERO_GROOVE:
        raise IllegalConstraint(
            f"{obj!r}: the groove has no length (groove_a {obj.groove_a!r}, groove_b "
            f"{obj.groove_b!r}); it must not be 0 in a step.")
    raise UnsolvableCollision(
        f"Unsolvable constraint: {obj!r} joins two bodies that cannot rotate "
        f"(both have an infinite moment of inertia or are not dynamic).")


# -- joints across spaces ----------------------------------------------------------------------------
# Munk2D links a joint into both bodies' constraint lists whatever space the
# bodies are in. A body of another space then drags the joint into that
# space's sleeping components and, when they wake, into its constraint
# array, a joint that space never had (and keeps reading after it is freed).
# So a joint and its bodies share one space (or the bodies are in none).

cdef cpSpace *_space_of_body(cpBody *body) noexcept nogil:
    # The space a body belongs to; for a body removed from its space whose
    # shapes stayed there, that space (sleeping would move those shapes).
    cdef cpShape *shape
    if body.space != NULL:
        return body.space
    shape = body.shapeList
    while shape != NULL:
        if shape.space != NULL:
            return shape.space
        shape = shape.next
    return NULL

cdef object _space_name(cpSpace *space):
    if space != NULL and space.userData != NULL:
        return repr(<object>space.userData)
    return "another space"

cdef int tamias_check_joint_space(cpSpace *space, cpConstraint *c) except -1:
    cdef cpBody *body
    cdef cpSpace *other
    cdef int i
    for i in range(2):
        body = c.a if i == 0 else c.b
        other = _space_of_body(body)
        if other != NULL and other != space:
            obj = <object>c.userData if c.userData != NULL else None
            b = <object>body.userData if body.userData != NULL else None
            raise IllegalConstraint(
                f"{obj!r} joins {b!r} (body {'a' if i == 0 else 'b'}), which belongs to "
                f"{_space_name(other)}: a joint and its bodies must be in the same space "
                f"(or the bodies in none). Remove the body from that space first.")
    return 0

cdef int tamias_check_body_joints(cpSpace *space, cpBody *body) except -1:
    # The body's list holds the joints that are in some space.
    cdef cpConstraint *c = body.constraintList
    while c != NULL:
        if c.space != NULL and c.space != space:
            obj = <object>c.userData if c.userData != NULL else None
            b = <object>body.userData if body.userData != NULL else None
            raise IllegalConstraint(
                f"{b!r} has a joint, {obj!r}, in {_space_name(c.space)}: a body and its "
                f"joints must be in the same space. Remove the joint from that space first.")
        c = cpConstraintNext(c, body)
    return 0


# -- debug drawing (cpSpaceDebug.c) -------------------------------------------------------------------------------
# The zig-zag of a drawn spring, in spring-length units along x and pixels
# across; Munk2D writes the values as float literals.
cdef cpVect _spring_verts[15]
cdef int _spring_count = 15

cdef void _init_spring_verts() noexcept nogil:
    cdef float xs[15]
    cdef float ys[15]
    xs[:] = [0.00, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50, 0.55, 0.60, 0.65, 0.70, 0.75, 0.80, 1.00]
    ys[:] = [0.0, 0.0, 3.0, -6.0, 6.0, -6.0, 6.0, -6.0, 6.0, -6.0, 6.0, -3.0, 6.0, 0.0, 0.0]
    cdef int i
    for i in range(15):
        _spring_verts[i] = cpv(<double>xs[i], <double>ys[i])

_init_spring_verts()

cdef inline int _draw_segment(object options, cpVect a, cpVect b, object color) except -1:
    # pymunk skips segments with a NaN end (a zero-length spring).
    if isnan(a.x) or isnan(a.y) or isnan(b.x) or isnan(b.y):
        return 0
    options.draw_segment(vec2d_from_cpv(a), vec2d_from_cpv(b), color)
    return 0

cdef int tamias_constraint_debug_draw(cpConstraint *constraint, cpTransform t, object options,
                                      object color) except -1:
    cdef cpBody *body_a = constraint.a
    cdef cpBody *body_b = constraint.b
    cdef cpVect a, b, c, delta, r1, r2, v
    cdef cpFloat cos_, sin_, s
    cdef cpVect verts[15]
    cdef int i
    if body_a == NULL or body_b == NULL:
        return 0
    # Dots are not scaled by the transform (Munk2D draws them in pixels).
    if cpConstraintIsPinJoint(constraint):
        a = cpTransformPoint(t, cpTransformPoint(body_a.transform, (<cpPinJoint *>constraint).anchorA))
        b = cpTransformPoint(t, cpTransformPoint(body_b.transform, (<cpPinJoint *>constraint).anchorB))
        options.draw_dot(5.0, vec2d_from_cpv(a), color)
        options.draw_dot(5.0, vec2d_from_cpv(b), color)
        _draw_segment(options, a, b, color)
    elif cpConstraintIsSlideJoint(constraint):
        a = cpTransformPoint(t, cpTransformPoint(body_a.transform, (<cpSlideJoint *>constraint).anchorA))
        b = cpTransformPoint(t, cpTransformPoint(body_b.transform, (<cpSlideJoint *>constraint).anchorB))
        options.draw_dot(5.0, vec2d_from_cpv(a), color)
        options.draw_dot(5.0, vec2d_from_cpv(b), color)
        _draw_segment(options, a, b, color)
    elif cpConstraintIsPivotJoint(constraint):
        a = cpTransformPoint(t, cpTransformPoint(body_a.transform, (<cpPivotJoint *>constraint).anchorA))
        b = cpTransformPoint(t, cpTransformPoint(body_b.transform, (<cpPivotJoint *>constraint).anchorB))
        options.draw_dot(5.0, vec2d_from_cpv(a), color)
        options.draw_dot(5.0, vec2d_from_cpv(b), color)
    elif cpConstraintIsGrooveJoint(constraint):
        a = cpTransformPoint(t, cpTransformPoint(body_a.transform, (<cpGrooveJoint *>constraint).grv_a))
        b = cpTransformPoint(t, cpTransformPoint(body_a.transform, (<cpGrooveJoint *>constraint).grv_b))
        c = cpTransformPoint(t, cpTransformPoint(body_b.transform, (<cpGrooveJoint *>constraint).anchorB))
        options.draw_dot(5.0, vec2d_from_cpv(c), color)
        _draw_segment(options, a, b, color)
    elif cpConstraintIsDampedSpring(constraint):
        a = cpTransformPoint(t, cpTransformPoint(body_a.transform, (<cpDampedSpring *>constraint).anchorA))
        b = cpTransformPoint(t, cpTransformPoint(body_b.transform, (<cpDampedSpring *>constraint).anchorB))
        options.draw_dot(5.0, vec2d_from_cpv(a), color)
        options.draw_dot(5.0, vec2d_from_cpv(b), color)
        # Map the unit zig-zag onto the segment a-b.
        delta = cpvsub(b, a)
        cos_ = delta.x
        sin_ = delta.y
        s = 1.0 / cpvlength(delta)
        r1 = cpv(cos_, -sin_ * s)
        r2 = cpv(sin_, cos_ * s)
        for i in range(_spring_count):
            v = _spring_verts[i]
            verts[i] = cpv(cpvdot(v, r1) + a.x, cpvdot(v, r2) + a.y)
        for i in range(_spring_count - 1):
            _draw_segment(options, verts[i], verts[i + 1], color)
    return 0


# -- Python callbacks from C ---------------------------------------------------------------------------------------
cdef void _write_unraisable(object exc, object where) noexcept:
    cdef object tp = type(exc)
    cdef object tb = exc.__traceback__
    Py_INCREF(tp)
    Py_INCREF(exc)
    if tb is not None:
        Py_INCREF(tb)
    PyErr_Restore(<PyObject *>tp, <PyObject *>exc, <PyObject *>tb if tb is not None else NULL)
    PyErr_WriteUnraisable(where)


cdef void _report_callback_error(cpSpace *space, object exc, object where) noexcept:
    # The Python Space keeps the first error and re-raises it from step().
    if space != NULL and space.userData != NULL:
        try:
            (<object>space.userData)._store_callback_error(exc)
            return
        except BaseException:
            pass
    _write_unraisable(exc, where)


cdef void _call_solve_func(cpConstraint *c, cpSpace *space, bint pre) noexcept:
    if c.userData == NULL:
        return
    cdef Constraint obj = <Constraint>c.userData
    func = obj._pre_solve_func if pre else obj._post_solve_func
    if func is None:
        return
    py_space = <object>space.userData if space != NULL and space.userData != NULL else None
    try:
        func(obj, py_space)
    except BaseException as exc:
        _report_callback_error(space, exc, func)


cdef void _pre_solve_trampoline(cpConstraint *c, cpSpace *space) noexcept nogil:
    with gil:
        _call_solve_func(c, space, 1)


cdef void _post_solve_trampoline(cpConstraint *c, cpSpace *space) noexcept nogil:
    with gil:
        _call_solve_func(c, space, 0)


cdef cpFloat _call_spring_func(cpConstraint *c, cpFloat x, bint rotary) noexcept:
    cdef double result
    if c.userData == NULL:
        return _defaultSpringTorque(c, x) if rotary else _defaultSpringForce(c, x)
    obj = <object>c.userData
    func = (<DampedRotarySpring>obj)._torque_func if rotary else (<DampedSpring>obj)._force_func
    if func is None:
        return _defaultSpringTorque(c, x) if rotary else _defaultSpringForce(c, x)
    try:
        result = func(obj, x)
        if not isfinite(result):
            raise ValueError(f"{'torque_func' if rotary else 'force_func'} returned "
                             f"{result!r}; a spring needs a finite value")
        return result
    except BaseException as exc:
        _report_callback_error(c.space, exc, func)
        return 0.0


cdef cpFloat _spring_force_trampoline(cpConstraint *c, cpFloat dist) noexcept nogil:
    cdef cpFloat f
    with gil:
        f = _call_spring_func(c, dist, 0)
    return f


cdef cpFloat _spring_torque_trampoline(cpConstraint *c, cpFloat relativeAngle) noexcept nogil:
    cdef cpFloat f
    with gil:
        f = _call_spring_func(c, relativeAngle, 1)
    return f


# == Python level ===================================================================================================

# -- parameter checks ----------------------------------------------------------------------------
# A joint parameter is refused when it is set (constructor or setter) if the
# solver cannot use it: the joints square lengths, multiply them by
# stiffnesses and rates and divide by ratios, so a value near the double
# range makes the first steps non-finite whatever the bodies are. What is
# refused, and why, is listed in docs/stability.md ("Joint parameters").

PARAMETER_LIMIT = 1e100
cdef double _LIMIT = 1e100     # PARAMETER_LIMIT, for C


cdef inline double _float_arg(object value, str what) except? -1.0:
    cdef double x
    try:
        x = value
        return x
    except TypeError:
        raise TypeError(f"{what} must be a number, not {type(value).__name__}") from None


cdef double _bounded_arg(object value, str what) except? -1.0:
    # A finite number of magnitude at most PARAMETER_LIMIT.
    cdef double x = _float_arg(value, what)
    if not (cpfabs(x) <= _LIMIT):
        if not isfinite(x):
            raise IllegalConstraint(f"{what} must be a finite number, got {x!r}")
        raise IllegalConstraint(
            f"{what} = {x!r} is too large: joint parameters must be within "
            f"+-{_LIMIT:g} (the solver squares and multiplies them)")
    return x


cdef double _non_negative_arg(object value, str what) except? -1.0:
    cdef double x = _bounded_arg(value, what)
    if not (x >= 0.0):
        raise IllegalConstraint(f"{what} must be >= 0, got {x!r}")
    return x


cdef double _lower_limit_arg(object value, str what) except? -1.0:
    # A lower limit: anything up to PARAMETER_LIMIT, -inf for "none". A
    # larger one can never be met and pushes the bodies apart without end.
    cdef double x = _float_arg(value, what)
    if isnan(x):
        raise IllegalConstraint(f"{what} must not be NaN")
    if x > _LIMIT:
        raise IllegalConstraint(
            f"{what} = {x!r} is a lower limit that can never be met: it must be at "
            f"most {_LIMIT:g} (-inf for no lower limit)")
    return x


cdef double _upper_limit_arg(object value, str what) except? -1.0:
    # An upper limit: anything from -PARAMETER_LIMIT, inf for "none".
    cdef double x = _float_arg(value, what)
    if isnan(x):
        raise IllegalConstraint(f"{what} must not be NaN")
    if x < -_LIMIT:
        raise IllegalConstraint(
            f"{what} = {x!r} is an upper limit that can never be met: it must be at "
            f"least {-_LIMIT:g} (inf for no upper limit)")
    return x


cdef double _divisor_arg(object value, str what) except? -1.0:
    # A ratio or notch distance the solver divides by: 0 is refused in a step
    # (pymunk's tests build joints with it), any other value needs a finite
    # inverse within the limit.
    cdef double x = _bounded_arg(value, what)
    if x != 0.0 and not (cpfabs(x) >= 1.0 / _LIMIT):
        raise IllegalConstraint(
            f"{what} = {x!r} is too small: its inverse must be within +-{_LIMIT:g}")
    return x


cdef double _max_arg(object value, str what) except? -1.0:
    # max_force, max_bias: >= 0, inf (the default) for no limit.
    cdef double x = _float_arg(value, what)
    if not (x >= 0.0):
        raise IllegalConstraint(f"{what} must be >= 0, got {x!r}")
    return x


cdef int _check_point(cpVect v, str what) except -1:
    if not (cpfabs(v.x) <= _LIMIT and cpfabs(v.y) <= _LIMIT):
        raise IllegalConstraint(
            f"{what} = ({v.x!r}, {v.y!r}) is too far out: joint coordinates must be "
            f"within +-{_LIMIT:g} (the solver squares them)")
    return 0


cdef inline cpVect _point_arg(object value, str what) except *:
    cdef cpVect v = cpv_from_object_finite(value, what)
    _check_point(v, what)
    return v


# -- shared setter bodies ------------------------------------------------------------------------
# Every parameter setter wakes the bodies and stores the checked value, as
# Munk2D's cpXxxSetYyy do.

cdef inline int _set_float(Constraint self, cpFloat *field, double value) except -1:
    tamias_wait_constraint(self._constraint)
    cpConstraintActivateBodies(self._constraint)
    field[0] = value
    return 0


cdef inline int _set_point(Constraint self, cpVect *field, object value, str what) except -1:
    cdef cpVect v = _point_arg(value, what)
    tamias_wait_constraint(self._constraint)
    cpConstraintActivateBodies(self._constraint)
    field[0] = v
    return 0


cdef Body _body_arg(object body, str which):
    if not isinstance(body, Body):
        raise TypeError(f"body {which} of a constraint must be a Body, not {type(body).__name__}")
    return <Body>body


cdef object _constraints_of(Body body):
    # The weak set behind Body.constraints, made on first use.
    d = getattr(body, "__dict__")
    s = d.get("_constraints")
    if s is None:
        s = d["_constraints"] = weakref.WeakKeyDictionary()
    return s


cdef inline int _check_callable(object func, str what) except -1:
    if func is not None and not callable(func):
        raise TypeError(f"{what} must be callable or None, not {type(func).__name__}")
    return 0


cdef int _start_init(Constraint self, object a, object b) except -1:
    # Checks shared by every joint's __init__, before anything changes.
    cdef Body ba = _body_arg(a, "a")
    cdef Body bb = _body_arg(b, "b")
    if ba is bb:
        raise IllegalBody("A constraint needs two different bodies.")
    if (cpBodyGetType(&ba._body) != CP_BODY_TYPE_DYNAMIC
            and cpBodyGetType(&bb._body) != CP_BODY_TYPE_DYNAMIC):
        raise IllegalBody("At least one of the two bodies attached to a constraint "
                          "must be DYNAMIC.")
    if self._constraint.space != NULL:
        raise IllegalBody("Cannot re-initialise a constraint that is in a space.")
    return 0


cdef inline void _install_solve_funcs(Constraint self) noexcept:
    if self._pre_solve_func is not None:
        self._constraint.preSolve = _pre_solve_trampoline
    else:
        self._constraint.preSolve = NULL
    if self._post_solve_func is not None:
        self._constraint.postSolve = _post_solve_trampoline
    else:
        self._constraint.postSolve = NULL


cdef int _finish_init(Constraint self, Body a, Body b) except -1:
    # After the C init: user data, callbacks, and the bodies' weak sets.
    if self._a is not None and self._a is not a:
        _constraints_of(self._a).pop(self, None)
    if self._b is not None and self._b is not b:
        _constraints_of(self._b).pop(self, None)
    self._constraint.userData = <void *>self
    _install_solve_funcs(self)
    self._a = a
    self._b = b
    _constraints_of(a)[self] = None
    _constraints_of(b)[self] = None
    return 0


@cython.no_gc_clear
cdef class Constraint:
    """Base class of the joints; not created directly.

    A constraint ties two bodies ``a`` and ``b`` (at least one of them
    dynamic). Every joint has ``max_force`` (the largest force it may use,
    default infinite), ``error_bias`` (the fraction of error left after a
    second, default ``pow(1 - 0.1, 60)``), ``max_bias`` (the fastest it may
    correct error), ``collide_bodies`` (whether its two bodies collide,
    default True), the last ``impulse`` it applied, and optional
    ``pre_solve`` / ``post_solve`` callbacks ``f(constraint, space)``.
    Constraints can be copied and pickled (with their bodies).

    >>> import tamias2d
    >>> j = tamias2d.PivotJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0))
    >>> isinstance(j, tamias2d.Constraint), j.max_force, j.collide_bodies
    (True, inf, True)
    """

    _pickle_attrs_init = ["a", "b"]
    _pickle_attrs_general = ["max_force", "error_bias", "max_bias", "collide_bodies"]
    _pickle_attrs_skip = ["pre_solve", "post_solve"]

    def __cinit__(self, *args, **kwargs):
        if not isinstance(self, _JOINT_TYPES):
            raise TypeError("Constraint is abstract: create one of the joints "
                            "(PinJoint, PivotJoint, DampedSpring, ...)")
        self._constraint = NULL
        self._a = None
        self._b = None
        self._pre_solve_func = None
        self._post_solve_func = None

    def __dealloc__(self):
        # Still in a space (its dict was cleared by the garbage collector):
        # unlink it so that the space and the bodies hold no dangling pointer.
        # The bodies are alive: no_gc_clear keeps _a and _b until here.
        if self._constraint != NULL:
            tamias_constraint_detach(self._constraint)
            self._constraint.userData = NULL

    def __repr__(self):
        return f"<{type(self).__module__}.{type(self).__qualname__} object at {id(self):#x}>"

    @property
    def a(self):
        """The first of the two bodies.

        >>> import tamias2d
        >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
        >>> tamias2d.PivotJoint(a, b, (0, 0)).a is a
        True
        """
        return self._a

    @property
    def b(self):
        """The second of the two bodies.

        >>> import tamias2d
        >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
        >>> tamias2d.PivotJoint(a, b, (0, 0)).b is b
        True
        """
        return self._b

    @property
    def max_force(self):
        """The largest force the constraint may apply (default infinite).

        >>> import tamias2d
        >>> j = tamias2d.PivotJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0))
        >>> j.max_force = 1000
        >>> j.max_force
        1000.0
        """
        return self._constraint.maxForce

    @max_force.setter
    def max_force(self, max_force):
        _set_float(self, &self._constraint.maxForce, _max_arg(max_force, "max_force"))

    @property
    def error_bias(self):
        """Fraction of the joint's error left uncorrected after one second.

        The default, ``pow(1 - 0.1, 60)`` (in C floats), corrects 10% of the
        error every 1/60 s.

        >>> import tamias2d
        >>> j = tamias2d.PivotJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0))
        >>> j.error_bias
        0.0017970074436457143
        """
        return self._constraint.errorBias

    @error_bias.setter
    def error_bias(self, error_bias):
        _set_float(self, &self._constraint.errorBias, _non_negative_arg(error_bias, "error_bias"))

    @property
    def max_bias(self):
        """The fastest speed at which the joint corrects its error (default
        infinite).

        >>> import tamias2d
        >>> j = tamias2d.PivotJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0))
        >>> j.max_bias = 10
        >>> j.max_bias
        10.0
        """
        return self._constraint.maxBias

    @max_bias.setter
    def max_bias(self, max_bias):
        _set_float(self, &self._constraint.maxBias, _max_arg(max_bias, "max_bias"))

    @property
    def collide_bodies(self):
        """Whether the two bodies still collide with each other (default
        True). False on any joint between two bodies stops their collisions.

        >>> import tamias2d
        >>> j = tamias2d.PivotJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0))
        >>> j.collide_bodies = False
        >>> j.collide_bodies
        False
        """
        return <bint>self._constraint.collideBodies

    @collide_bodies.setter
    def collide_bodies(self, collide_bodies):
        cdef bint v = bool(collide_bodies)
        tamias_wait_constraint(self._constraint)
        cpConstraintActivateBodies(self._constraint)
        self._constraint.collideBodies = v

    @property
    def impulse(self):
        """The impulse the constraint applied in the last step (divide by the
        step's dt for a force: handy for breakable joints).

        >>> import tamias2d
        >>> j = tamias2d.PivotJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0))
        >>> j.impulse
        0.0
        """
        return cpConstraintGetImpulse(self._constraint)

    def activate_bodies(self):
        """Wake both bodies (and their sleeping groups).

        >>> import tamias2d
        >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
        >>> tamias2d.PivotJoint(a, b, (0, 0)).activate_bodies()
        """
        tamias_wait_constraint(self._constraint)
        cpConstraintActivateBodies(self._constraint)

    @property
    def pre_solve(self):
        """Called as ``f(constraint, space)`` in every step before the solver
        runs; None (the default) for no callback. An exception it raises is
        re-raised by ``Space.step``.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> b = tamias2d.Body(1, 2)
        >>> j = tamias2d.PivotJoint(s.static_body, b, (0, 0))
        >>> s.add(b, j)
        >>> j.pre_solve = lambda constraint, space: print("before")
        >>> s.step(0.1)
        before
        >>> j.pre_solve = None
        """
        return self._pre_solve_func

    @pre_solve.setter
    def pre_solve(self, func):
        _check_callable(func, "pre_solve")
        tamias_wait_constraint(self._constraint)
        self._pre_solve_func = func
        _install_solve_funcs(self)

    @property
    def post_solve(self):
        """Called as ``f(constraint, space)`` in every step after the solver
        ran; None (the default) for no callback.

        >>> import tamias2d
        >>> s = tamias2d.Space()
        >>> b = tamias2d.Body(1, 2)
        >>> j = tamias2d.PivotJoint(s.static_body, b, (0, 0))
        >>> s.add(b, j)
        >>> j.post_solve = lambda constraint, space: print(round(constraint.impulse, 6))
        >>> s.step(0.1)
        0.0
        """
        return self._post_solve_func

    @post_solve.setter
    def post_solve(self, func):
        _check_callable(func, "post_solve")
        tamias_wait_constraint(self._constraint)
        self._post_solve_func = func
        _install_solve_funcs(self)

    # -- copy and pickle (pymunk's layout, shared in tamias2d._pickle) -----------------------------
    def __getstate__(self):
        """The constraint's state as pymunk lays it out (used by copy and
        pickle): constructor arguments, common properties, user attributes
        and the callbacks.

        >>> import tamias2d
        >>> j = tamias2d.SimpleMotor(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 2)
        >>> [k for k, v in j.__getstate__()["init"]]
        ['a', 'b', 'rate']
        """
        cdef dict d = pymunk_getstate(self)
        d["special"] += [("_pre_solve_func", self._pre_solve_func),
                         ("_post_solve_func", self._post_solve_func)]
        return d

    def __setstate__(self, state):
        """Restore a state made by :meth:`__getstate__` (used by unpickling).

        >>> import tamias2d
        >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
        >>> j = tamias2d.SimpleMotor(a, b, 2)
        >>> j.__setstate__(tamias2d.SimpleMotor(a, b, 5).__getstate__())
        >>> j.rate
        5.0
        """
        pymunk_setstate(self, state)
        for k, v in state["special"]:
            if k == "_pre_solve_func" and v is not None:
                self.pre_solve = v
            elif k == "_post_solve_func" and v is not None:
                self.post_solve = v

    def __reduce__(self):
        return pymunk_reduce(self)

    def copy(self):
        """A deep copy of the constraint (its bodies are copied too).

        >>> import tamias2d
        >>> j = tamias2d.SimpleMotor(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 2)
        >>> j2 = j.copy()
        >>> j2.rate, j2.a is j.a
        (2.0, False)
        """
        return deep_copy(self)


cdef class PinJoint(Constraint):
    """Keeps two anchor points at a fixed distance, like a rigid rod.

    ``PinJoint(a, b, anchor_a=(0, 0), anchor_b=(0, 0))``; anchors are in body
    coordinates. The distance is measured when the joint is created; set
    ``distance`` to change it.

    >>> import tamias2d
    >>> a, b = tamias2d.Body(1, 1), tamias2d.Body(1, 1)
    >>> b.position = 3, 0
    >>> j = tamias2d.PinJoint(a, b, (0, 4), (0, 0))
    >>> j.distance
    5.0
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["anchor_a", "anchor_b"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpPinJoint))
        cpPinJointInit(&self._joint, NULL, NULL, cpvzero(), cpvzero())
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self

    def __init__(self, a, b, anchor_a=(0, 0), anchor_b=(0, 0)):
        _start_init(self, a, b)
        cdef cpVect aa = _point_arg(anchor_a, "anchor_a")
        cdef cpVect ab = _point_arg(anchor_b, "anchor_b")
        cpPinJointInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, aa, ab)
        _finish_init(self, a, b)

    @property
    def anchor_a(self):
        """The anchor point on body a, in body a's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.PinJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (1, 2))
        >>> j.anchor_a
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(self._joint.anchorA)

    @anchor_a.setter
    def anchor_a(self, anchor):
        _set_point(self, &self._joint.anchorA, anchor, "anchor_a")

    @property
    def anchor_b(self):
        """The anchor point on body b, in body b's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.PinJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (3, 4))
        >>> j.anchor_b
        Vec2d(3.0, 4.0)
        """
        return vec2d_from_cpv(self._joint.anchorB)

    @anchor_b.setter
    def anchor_b(self, anchor):
        _set_point(self, &self._joint.anchorB, anchor, "anchor_b")

    @property
    def distance(self):
        """The distance the joint keeps between the anchors.

        >>> import tamias2d
        >>> j = tamias2d.PinJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (10, 0))
        >>> j.distance = 20
        >>> j.distance
        20.0
        """
        return self._joint.dist

    @distance.setter
    def distance(self, distance):
        _set_float(self, &self._joint.dist, _bounded_arg(distance, "distance"))


cdef class SlideJoint(Constraint):
    """Keeps the distance between two anchor points between ``min`` and
    ``max``, like a chain or a telescopic rod.

    ``SlideJoint(a, b, anchor_a, anchor_b, min, max)``; anchors are in body
    coordinates.

    >>> import tamias2d
    >>> j = tamias2d.SlideJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 2, 5)
    >>> j.min, j.max
    (2.0, 5.0)
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["anchor_a", "anchor_b", "min", "max"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpSlideJoint))
        cpSlideJointInit(&self._joint, NULL, NULL, cpvzero(), cpvzero(), 0.0, 0.0)
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self

    def __init__(self, a, b, anchor_a, anchor_b, min, max):
        _start_init(self, a, b)
        cdef cpVect aa = _point_arg(anchor_a, "anchor_a")
        cdef cpVect ab = _point_arg(anchor_b, "anchor_b")
        cdef double mn = _lower_limit_arg(min, "min")
        cdef double mx = _upper_limit_arg(max, "max")
        cpSlideJointInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, aa, ab, mn, mx)
        _finish_init(self, a, b)

    @property
    def anchor_a(self):
        """The anchor point on body a, in body a's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.SlideJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (1, 2), (0, 0), 0, 1)
        >>> j.anchor_a
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(self._joint.anchorA)

    @anchor_a.setter
    def anchor_a(self, anchor):
        _set_point(self, &self._joint.anchorA, anchor, "anchor_a")

    @property
    def anchor_b(self):
        """The anchor point on body b, in body b's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.SlideJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (3, 4), 0, 1)
        >>> j.anchor_b
        Vec2d(3.0, 4.0)
        """
        return vec2d_from_cpv(self._joint.anchorB)

    @anchor_b.setter
    def anchor_b(self, anchor):
        _set_point(self, &self._joint.anchorB, anchor, "anchor_b")

    @property
    def min(self):
        """The shortest allowed distance between the anchors.

        >>> import tamias2d
        >>> j = tamias2d.SlideJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 1, 3)
        >>> j.min = 2
        >>> j.min
        2.0
        """
        return self._joint.min

    @min.setter
    def min(self, min):
        _set_float(self, &self._joint.min, _lower_limit_arg(min, "min"))

    @property
    def max(self):
        """The longest allowed distance between the anchors.

        >>> import tamias2d
        >>> j = tamias2d.SlideJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 1, 3)
        >>> j.max = 4
        >>> j.max
        4.0
        """
        return self._joint.max

    @max.setter
    def max(self, max):
        _set_float(self, &self._joint.max, _upper_limit_arg(max, "max"))


cdef class PivotJoint(Constraint):
    """Lets two bodies turn about a shared point, like a hinge.

    ``PivotJoint(a, b, pivot)`` with the pivot in world coordinates (the
    bodies must already be in place), or ``PivotJoint(a, b, anchor_a,
    anchor_b)`` with one anchor on each body in body coordinates.

    >>> import tamias2d
    >>> a, b = tamias2d.Body(10, 10), tamias2d.Body(20, 20)
    >>> a.position = 5, 7
    >>> j = tamias2d.PivotJoint(a, b, (1, 2))
    >>> j.anchor_a, j.anchor_b
    (Vec2d(-4.0, -5.0), Vec2d(1.0, 2.0))
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["anchor_a", "anchor_b"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpPivotJoint))
        cpPivotJointInit(&self._joint, NULL, NULL, cpvzero(), cpvzero())
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self

    def __init__(self, a, b, *args):
        _start_init(self, a, b)
        cdef cpVect aa, ab, pivot
        if len(args) == 1:
            pivot = _point_arg(args[0], "pivot")
            # cpPivotJointNew: the pivot seen from each body.
            aa = cpBodyWorldToLocal(&(<Body>a)._body, pivot)
            ab = cpBodyWorldToLocal(&(<Body>b)._body, pivot)
            _check_point(aa, "the pivot seen from body a")
            _check_point(ab, "the pivot seen from body b")
        elif len(args) == 2:
            aa = _point_arg(args[0], "anchor_a")
            ab = _point_arg(args[1], "anchor_b")
        else:
            raise TypeError("PivotJoint takes either one pivot point or two anchor points "
                            f"after the bodies ({len(args)} given)")
        cpPivotJointInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, aa, ab)
        _finish_init(self, a, b)

    @property
    def anchor_a(self):
        """The anchor point on body a, in body a's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.PivotJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (1, 2), (3, 4))
        >>> j.anchor_a
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(self._joint.anchorA)

    @anchor_a.setter
    def anchor_a(self, anchor):
        _set_point(self, &self._joint.anchorA, anchor, "anchor_a")

    @property
    def anchor_b(self):
        """The anchor point on body b, in body b's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.PivotJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (1, 2), (3, 4))
        >>> j.anchor_b
        Vec2d(3.0, 4.0)
        """
        return vec2d_from_cpv(self._joint.anchorB)

    @anchor_b.setter
    def anchor_b(self, anchor):
        _set_point(self, &self._joint.anchorB, anchor, "anchor_b")


cdef class GrooveJoint(Constraint):
    """A pivot that slides along a groove: the groove runs from ``groove_a``
    to ``groove_b`` on body a, the pivot is ``anchor_b`` on body b (all in
    body coordinates).

    >>> import tamias2d
    >>> j = tamias2d.GrooveJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (10, 0), (0, 0))
    >>> j.groove_b
    Vec2d(10.0, 0.0)
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["groove_a", "groove_b", "anchor_b"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpGrooveJoint))
        cpGrooveJointInit(&self._joint, NULL, NULL, cpvzero(), cpvzero(), cpvzero())
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self

    def __init__(self, a, b, groove_a, groove_b, anchor_b):
        _start_init(self, a, b)
        cdef cpVect ga = _point_arg(groove_a, "groove_a")
        cdef cpVect gb = _point_arg(groove_b, "groove_b")
        cdef cpVect ab = _point_arg(anchor_b, "anchor_b")
        cpGrooveJointInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, ga, gb, ab)
        _finish_init(self, a, b)

    @property
    def anchor_b(self):
        """The pivot on body b, in body b's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.GrooveJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (1, 0), (1, 2))
        >>> j.anchor_b
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(self._joint.anchorB)

    @anchor_b.setter
    def anchor_b(self, anchor):
        _set_point(self, &self._joint.anchorB, anchor, "anchor_b")

    @property
    def groove_a(self):
        """The start of the groove on body a, in body a's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.GrooveJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (1, 2), (3, 4), (0, 0))
        >>> j.groove_a
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(self._joint.grv_a)

    @groove_a.setter
    def groove_a(self, groove):
        cdef cpVect v = _point_arg(groove, "groove_a")
        tamias_wait_constraint(self._constraint)
        cpConstraintActivateBodies(self._constraint)
        self._joint.grv_a = v
        self._joint.grv_n = cpvperp(cpvnormalize(cpvsub(self._joint.grv_b, v)))

    @property
    def groove_b(self):
        """The end of the groove on body a, in body a's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.GrooveJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (1, 2), (3, 4), (0, 0))
        >>> j.groove_b
        Vec2d(3.0, 4.0)
        """
        return vec2d_from_cpv(self._joint.grv_b)

    @groove_b.setter
    def groove_b(self, groove):
        cdef cpVect v = _point_arg(groove, "groove_b")
        tamias_wait_constraint(self._constraint)
        cpConstraintActivateBodies(self._constraint)
        self._joint.grv_b = v
        self._joint.grv_n = cpvperp(cpvnormalize(cpvsub(v, self._joint.grv_a)))


cdef class DampedSpring(Constraint):
    """A spring with damping between two anchor points.

    ``DampedSpring(a, b, anchor_a, anchor_b, rest_length, stiffness,
    damping)``; anchors in body coordinates. The spring force (without the
    damping) comes from ``force_func``, by default
    :meth:`DampedSpring.spring_force`: ``(rest_length - distance) *
    stiffness``. It is clamped by ``max_force``.

    >>> import tamias2d
    >>> j = tamias2d.DampedSpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 5, 10, 1)
    >>> j.rest_length, j.stiffness, j.damping
    (5.0, 10.0, 1.0)
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + [
        "anchor_a", "anchor_b", "rest_length", "stiffness", "damping"]
    _pickle_attrs_skip = Constraint._pickle_attrs_skip + ["_force_func"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpDampedSpring))
        cpDampedSpringInit(&self._joint, NULL, NULL, cpvzero(), cpvzero(), 0.0, 0.0, 0.0)
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self
        self._force_func = None

    def __init__(self, a, b, anchor_a, anchor_b, rest_length, stiffness, damping):
        _start_init(self, a, b)
        cdef cpVect aa = _point_arg(anchor_a, "anchor_a")
        cdef cpVect ab = _point_arg(anchor_b, "anchor_b")
        cdef double r = _bounded_arg(rest_length, "rest_length")
        cdef double k = _bounded_arg(stiffness, "stiffness")
        cdef double d = _non_negative_arg(damping, "damping")
        cpDampedSpringInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, aa, ab, r, k, d)
        if self._force_func is not None:
            self._joint.springForceFunc = _spring_force_trampoline
        _finish_init(self, a, b)

    @property
    def anchor_a(self):
        """The anchor point on body a, in body a's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.DampedSpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (1, 2), (0, 0), 0, 0, 0)
        >>> j.anchor_a
        Vec2d(1.0, 2.0)
        """
        return vec2d_from_cpv(self._joint.anchorA)

    @anchor_a.setter
    def anchor_a(self, anchor):
        _set_point(self, &self._joint.anchorA, anchor, "anchor_a")

    @property
    def anchor_b(self):
        """The anchor point on body b, in body b's coordinates.

        >>> import tamias2d
        >>> j = tamias2d.DampedSpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (3, 4), 0, 0, 0)
        >>> j.anchor_b
        Vec2d(3.0, 4.0)
        """
        return vec2d_from_cpv(self._joint.anchorB)

    @anchor_b.setter
    def anchor_b(self, anchor):
        _set_point(self, &self._joint.anchorB, anchor, "anchor_b")

    @property
    def rest_length(self):
        """The length the spring wants to have.

        >>> import tamias2d
        >>> j = tamias2d.DampedSpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 1, 0, 0)
        >>> j.rest_length = 2
        >>> j.rest_length
        2.0
        """
        return self._joint.restLength

    @rest_length.setter
    def rest_length(self, rest_length):
        _set_float(self, &self._joint.restLength, _bounded_arg(rest_length, "rest_length"))

    @property
    def stiffness(self):
        """The spring constant (force per unit of stretch).

        >>> import tamias2d
        >>> j = tamias2d.DampedSpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 0, 1, 0)
        >>> j.stiffness = 2
        >>> j.stiffness
        2.0
        """
        return self._joint.stiffness

    @stiffness.setter
    def stiffness(self, stiffness):
        _set_float(self, &self._joint.stiffness, _bounded_arg(stiffness, "stiffness"))

    @property
    def damping(self):
        """How strongly the spring damps the relative speed of its ends.

        >>> import tamias2d
        >>> j = tamias2d.DampedSpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 0, 0, 1)
        >>> j.damping = 2
        >>> j.damping
        2.0
        """
        return self._joint.damping

    @damping.setter
    def damping(self, damping):
        _set_float(self, &self._joint.damping, _non_negative_arg(damping, "damping"))

    @staticmethod
    def spring_force(spring, dist):
        """The default spring force: ``(rest_length - dist) * stiffness``.

        >>> import tamias2d
        >>> j = tamias2d.DampedSpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 5, 2, 0)
        >>> tamias2d.DampedSpring.spring_force(j, 3)
        4.0
        """
        if not isinstance(spring, DampedSpring):
            raise TypeError(f"spring_force needs a DampedSpring, not {type(spring).__name__}")
        cdef double d = dist
        return _defaultSpringForce((<DampedSpring>spring)._constraint, d)

    @property
    def force_func(self):
        """The spring force function ``f(spring, dist) -> force``, called
        every step (the damping is added on top). Defaults to
        :meth:`DampedSpring.spring_force`. An exception it raises is
        re-raised by ``Space.step``; it must return a finite number.

        >>> import tamias2d
        >>> j = tamias2d.DampedSpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), (0, 0), (0, 0), 0, 1, 0)
        >>> j.force_func == tamias2d.DampedSpring.spring_force
        True
        >>> j.force_func = lambda spring, dist: 10.0
        >>> j.force_func(j, 3)
        10.0
        """
        if self._force_func is None:
            return _default_spring_force
        return self._force_func

    @force_func.setter
    def force_func(self, func):
        if func is None or func == _default_spring_force:
            self._force_func = None
            self._joint.springForceFunc = _defaultSpringForce
        elif callable(func):
            self._force_func = func
            self._joint.springForceFunc = _spring_force_trampoline
        else:
            raise TypeError(f"force_func must be callable, not {type(func).__name__}")
        tamias_wait_constraint(self._constraint)
        cpConstraintActivateBodies(self._constraint)


cdef class DampedRotarySpring(Constraint):
    """An angular spring with damping between two bodies.

    ``DampedRotarySpring(a, b, rest_angle, stiffness, damping)``. The spring
    torque (without the damping) comes from ``torque_func``, by default
    :meth:`DampedRotarySpring.spring_torque`: ``(relative_angle -
    rest_angle) * stiffness`` with ``relative_angle = a.angle - b.angle``.

    >>> import tamias2d
    >>> j = tamias2d.DampedRotarySpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0.5, 10, 1)
    >>> j.rest_angle, j.stiffness, j.damping
    (0.5, 10.0, 1.0)
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["rest_angle", "stiffness", "damping"]
    _pickle_attrs_skip = Constraint._pickle_attrs_skip + ["_torque_func"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpDampedRotarySpring))
        cpDampedRotarySpringInit(&self._joint, NULL, NULL, 0.0, 0.0, 0.0)
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self
        self._torque_func = None

    def __init__(self, a, b, rest_angle, stiffness, damping):
        _start_init(self, a, b)
        cdef double r = _bounded_arg(rest_angle, "rest_angle")
        cdef double k = _bounded_arg(stiffness, "stiffness")
        cdef double d = _non_negative_arg(damping, "damping")
        cpDampedRotarySpringInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, r, k, d)
        if self._torque_func is not None:
            self._joint.springTorqueFunc = _spring_torque_trampoline
        _finish_init(self, a, b)

    @property
    def rest_angle(self):
        """The relative angle (radians) the spring wants.

        >>> import tamias2d
        >>> j = tamias2d.DampedRotarySpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 1, 0, 0)
        >>> j.rest_angle = 2
        >>> j.rest_angle
        2.0
        """
        return self._joint.restAngle

    @rest_angle.setter
    def rest_angle(self, rest_angle):
        _set_float(self, &self._joint.restAngle, _bounded_arg(rest_angle, "rest_angle"))

    @property
    def stiffness(self):
        """The spring constant (torque per radian).

        >>> import tamias2d
        >>> j = tamias2d.DampedRotarySpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 1, 0)
        >>> j.stiffness = 2
        >>> j.stiffness
        2.0
        """
        return self._joint.stiffness

    @stiffness.setter
    def stiffness(self, stiffness):
        _set_float(self, &self._joint.stiffness, _bounded_arg(stiffness, "stiffness"))

    @property
    def damping(self):
        """How strongly the spring damps the relative angular speed.

        >>> import tamias2d
        >>> j = tamias2d.DampedRotarySpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 0, 1)
        >>> j.damping = 2
        >>> j.damping
        2.0
        """
        return self._joint.damping

    @damping.setter
    def damping(self, damping):
        _set_float(self, &self._joint.damping, _non_negative_arg(damping, "damping"))

    @staticmethod
    def spring_torque(spring, relative_angle):
        """The default spring torque: ``(relative_angle - rest_angle) *
        stiffness``.

        >>> import tamias2d
        >>> j = tamias2d.DampedRotarySpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 1, 10, 0)
        >>> tamias2d.DampedRotarySpring.spring_torque(j, 3)
        20.0
        """
        if not isinstance(spring, DampedRotarySpring):
            raise TypeError(f"spring_torque needs a DampedRotarySpring, not {type(spring).__name__}")
        cdef double r = relative_angle
        return _defaultSpringTorque((<DampedRotarySpring>spring)._constraint, r)

    @property
    def torque_func(self):
        """The spring torque function ``f(spring, relative_angle) ->
        torque``, called every step (the damping is added on top). Defaults
        to :meth:`DampedRotarySpring.spring_torque`.

        >>> import tamias2d
        >>> j = tamias2d.DampedRotarySpring(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 1, 0)
        >>> j.torque_func == tamias2d.DampedRotarySpring.spring_torque
        True
        """
        if self._torque_func is None:
            return _default_spring_torque
        return self._torque_func

    @torque_func.setter
    def torque_func(self, func):
        if func is None or func == _default_spring_torque:
            self._torque_func = None
            self._joint.springTorqueFunc = _defaultSpringTorque
        elif callable(func):
            self._torque_func = func
            self._joint.springTorqueFunc = _spring_torque_trampoline
        else:
            raise TypeError(f"torque_func must be callable, not {type(func).__name__}")
        tamias_wait_constraint(self._constraint)
        cpConstraintActivateBodies(self._constraint)


cdef class RotaryLimitJoint(Constraint):
    """Keeps the relative angle ``b.angle - a.angle`` between ``min`` and
    ``max`` (radians; the range may exceed a full turn).

    >>> import tamias2d
    >>> j = tamias2d.RotaryLimitJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), -1, 1)
    >>> j.min, j.max
    (-1.0, 1.0)
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["min", "max"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpRotaryLimitJoint))
        cpRotaryLimitJointInit(&self._joint, NULL, NULL, 0.0, 0.0)
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self

    def __init__(self, a, b, min, max):
        _start_init(self, a, b)
        cdef double mn = _lower_limit_arg(min, "min")
        cdef double mx = _upper_limit_arg(max, "max")
        cpRotaryLimitJointInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, mn, mx)
        _finish_init(self, a, b)

    @property
    def min(self):
        """The smallest allowed relative angle.

        >>> import tamias2d
        >>> j = tamias2d.RotaryLimitJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 1, 0)
        >>> j.min = 2
        >>> j.min
        2.0
        """
        return self._joint.min

    @min.setter
    def min(self, min):
        _set_float(self, &self._joint.min, _lower_limit_arg(min, "min"))

    @property
    def max(self):
        """The largest allowed relative angle.

        >>> import tamias2d
        >>> j = tamias2d.RotaryLimitJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 1)
        >>> j.max = 2
        >>> j.max
        2.0
        """
        return self._joint.max

    @max.setter
    def max(self, max):
        _set_float(self, &self._joint.max, _upper_limit_arg(max, "max"))


cdef class RatchetJoint(Constraint):
    """A rotary ratchet, like a socket wrench: the relative angle may grow
    in the direction of ``ratchet`` freely and goes back at most to the last
    notch. ``ratchet`` is the distance between notches (radians, not 0 in a
    step), ``phase`` their offset.

    >>> import tamias2d
    >>> j = tamias2d.RatchetJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 0.5)
    >>> j.phase, j.ratchet, j.angle
    (0.0, 0.5, 0.0)
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["phase", "ratchet"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpRatchetJoint))
        cpRatchetJointInit(&self._joint, NULL, NULL, 0.0, 0.0)
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self

    def __init__(self, a, b, phase, ratchet):
        _start_init(self, a, b)
        cdef double p = _bounded_arg(phase, "phase")
        cdef double r = _divisor_arg(ratchet, "ratchet")
        cpRatchetJointInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, p, r)
        _finish_init(self, a, b)

    @property
    def angle(self):
        """The relative angle of the current notch.

        >>> import tamias2d
        >>> j = tamias2d.RatchetJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 0)
        >>> j.angle = 1
        >>> j.angle
        1.0
        """
        return self._joint.angle

    @angle.setter
    def angle(self, angle):
        _set_float(self, &self._joint.angle, _bounded_arg(angle, "angle"))

    @property
    def phase(self):
        """The offset of the notches (radians).

        >>> import tamias2d
        >>> j = tamias2d.RatchetJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 1, 0)
        >>> j.phase = 2
        >>> j.phase
        2.0
        """
        return self._joint.phase

    @phase.setter
    def phase(self, phase):
        _set_float(self, &self._joint.phase, _bounded_arg(phase, "phase"))

    @property
    def ratchet(self):
        """The distance between notches (radians); its sign gives the free
        direction.

        >>> import tamias2d
        >>> j = tamias2d.RatchetJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 1)
        >>> j.ratchet = 2
        >>> j.ratchet
        2.0
        """
        return self._joint.ratchet

    @ratchet.setter
    def ratchet(self, ratchet):
        _set_float(self, &self._joint.ratchet, _divisor_arg(ratchet, "ratchet"))


cdef class GearJoint(Constraint):
    """Keeps the angular velocities of two bodies in a fixed ratio:
    ``b.angle * ratio - a.angle`` stays at ``phase``. ``ratio`` must not be 0
    in a step.

    >>> import tamias2d
    >>> j = tamias2d.GearJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 2)
    >>> j.phase, j.ratio
    (0.0, 2.0)
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["phase", "ratio"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpGearJoint))
        cpGearJointInit(&self._joint, NULL, NULL, 0.0, 1.0)
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self

    def __init__(self, a, b, phase, ratio):
        _start_init(self, a, b)
        cdef double p = _bounded_arg(phase, "phase")
        cdef double r = _divisor_arg(ratio, "ratio")
        cpGearJointInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, p, r)
        _finish_init(self, a, b)

    @property
    def phase(self):
        """The angular offset of the two bodies (radians).

        >>> import tamias2d
        >>> j = tamias2d.GearJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 1, 1)
        >>> j.phase = 2
        >>> j.phase
        2.0
        """
        return self._joint.phase

    @phase.setter
    def phase(self, phase):
        _set_float(self, &self._joint.phase, _bounded_arg(phase, "phase"))

    @property
    def ratio(self):
        """The gear ratio.

        >>> import tamias2d
        >>> j = tamias2d.GearJoint(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0, 1)
        >>> j.ratio = 2
        >>> j.ratio
        2.0
        """
        return self._joint.ratio

    @ratio.setter
    def ratio(self, ratio):
        cdef double v = _divisor_arg(ratio, "ratio")
        tamias_wait_constraint(self._constraint)
        cpConstraintActivateBodies(self._constraint)
        self._joint.ratio = v
        self._joint.ratio_inv = 1.0 / v


cdef class SimpleMotor(Constraint):
    """Keeps the relative angular velocity of two bodies at ``rate``.

    Without a ``max_force`` a motor may use any torque to keep its rate.

    >>> import tamias2d
    >>> j = tamias2d.SimpleMotor(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0.3)
    >>> j.rate
    0.3
    """

    _pickle_attrs_init = Constraint._pickle_attrs_init + ["rate"]

    def __cinit__(self, *args, **kwargs):
        memset(&self._joint, 0, sizeof(cpSimpleMotor))
        cpSimpleMotorInit(&self._joint, NULL, NULL, 0.0)
        self._constraint = &self._joint.constraint
        self._constraint.userData = <void *>self

    def __init__(self, a, b, rate):
        _start_init(self, a, b)
        cdef double r = _bounded_arg(rate, "rate")
        cpSimpleMotorInit(&self._joint, &(<Body>a)._body, &(<Body>b)._body, r)
        _finish_init(self, a, b)

    @property
    def rate(self):
        """The relative angular velocity the motor keeps (radians/second).

        >>> import tamias2d
        >>> j = tamias2d.SimpleMotor(tamias2d.Body(1, 1), tamias2d.Body(1, 1), 0.3)
        >>> j.rate = 0.4
        >>> j.rate
        0.4
        """
        return self._joint.rate

    @rate.setter
    def rate(self, rate):
        _set_float(self, &self._joint.rate, _bounded_arg(rate, "rate"))


cdef tuple _JOINT_TYPES = (PinJoint, SlideJoint, PivotJoint, GrooveJoint, DampedSpring,
                           DampedRotarySpring, RotaryLimitJoint, RatchetJoint, GearJoint,
                           SimpleMotor)

# The defaults behind force_func / torque_func, for the setters' "restore the
# default" test.
cdef object _default_spring_force = DampedSpring.spring_force
cdef object _default_spring_torque = DampedRotarySpring.spring_torque
