# Constraints (joints): the ten joint kinds of Munk2D (cpConstraint.c and one
# file per joint: cpPinJoint.c, cpSlideJoint.c, cpPivotJoint.c, cpGrooveJoint.c,
# cpDampedSpring.c, cpDampedRotarySpring.c, cpRotaryLimitJoint.c,
# cpRatchetJoint.c, cpGearJoint.c, cpSimpleMotor.c) and the Python classes of
# pymunk.constraints. They are not part of the MIS.
#
# The base struct cpConstraint and its class table cpConstraintClass are in
# _structs.pxd (bodies and the space point at them). The space module calls the
# class table from its step and cimports this module for the Python classes;
# this module never cimports the space (a constraint reaches its Python Space
# through cpSpace.userData).
from tamias2d._config cimport cpFloat, cpBool
from tamias2d._structs cimport (cpBody, cpSpace, cpConstraint, cpConstraintClass,
    cpConstraintPreSolveFunc, cpConstraintPostSolveFunc)
from tamias2d.vector cimport (cpVect, cpMat2x2, cpTransform, cpMat2x2New)
from tamias2d.body cimport Body, cpBodyActivate
from libc.math cimport pow

# -- joint structs (chipmunk_structs.h; field names as Munk2D) ------------------------
ctypedef cpFloat (*cpDampedSpringForceFunc)(cpConstraint *spring, cpFloat dist) noexcept nogil
ctypedef cpFloat (*cpDampedRotarySpringTorqueFunc)(cpConstraint *spring, cpFloat relativeAngle) noexcept nogil

cdef struct cpPinJoint:
    cpConstraint constraint
    cpVect anchorA
    cpVect anchorB
    cpFloat dist
    cpVect r1
    cpVect r2
    cpVect n
    cpFloat nMass
    cpFloat jnAcc
    cpFloat bias

cdef struct cpSlideJoint:
    cpConstraint constraint
    cpVect anchorA
    cpVect anchorB
    cpFloat min
    cpFloat max
    cpVect r1
    cpVect r2
    cpVect n
    cpFloat nMass
    cpFloat jnAcc
    cpFloat bias

cdef struct cpPivotJoint:
    cpConstraint constraint
    cpVect anchorA
    cpVect anchorB
    cpVect r1
    cpVect r2
    cpMat2x2 k
    cpVect jAcc
    cpVect bias

cdef struct cpGrooveJoint:
    cpConstraint constraint
    cpVect grv_n
    cpVect grv_a
    cpVect grv_b
    cpVect anchorB
    cpVect grv_tn
    cpFloat clamp
    cpVect r1
    cpVect r2
    cpMat2x2 k
    cpVect jAcc
    cpVect bias

cdef struct cpDampedSpring:
    cpConstraint constraint
    cpVect anchorA
    cpVect anchorB
    cpFloat restLength
    cpFloat stiffness
    cpFloat damping
    cpDampedSpringForceFunc springForceFunc
    cpFloat target_vrn
    cpFloat v_coef
    cpVect r1
    cpVect r2
    cpFloat nMass
    cpVect n
    cpFloat jAcc

cdef struct cpDampedRotarySpring:
    cpConstraint constraint
    cpFloat restAngle
    cpFloat stiffness
    cpFloat damping
    cpDampedRotarySpringTorqueFunc springTorqueFunc
    cpFloat target_wrn
    cpFloat w_coef
    cpFloat iSum
    cpFloat jAcc

cdef struct cpRotaryLimitJoint:
    cpConstraint constraint
    cpFloat min
    cpFloat max
    cpFloat iSum
    cpFloat bias
    cpFloat jAcc
    cpFloat softSide  # the soft solver's nearer limit: +1 lower, -1 upper

cdef struct cpRatchetJoint:
    cpConstraint constraint
    cpFloat angle
    cpFloat phase
    cpFloat ratchet
    cpFloat iSum
    cpFloat bias
    cpFloat jAcc

cdef struct cpGearJoint:
    cpConstraint constraint
    cpFloat phase
    cpFloat ratio
    cpFloat ratio_inv
    cpFloat iSum
    cpFloat bias
    cpFloat jAcc

cdef struct cpSimpleMotor:
    cpConstraint constraint
    cpFloat rate
    cpFloat iSum
    cpFloat jAcc

# -- chipmunk_private.h helpers for joints --------------------------------------------
cdef inline void cpConstraintActivateBodies(cpConstraint *constraint) noexcept nogil:
    cpBodyActivate(constraint.a)
    cpBodyActivate(constraint.b)

# The inverse of the 2x2 effective-mass matrix of a point constraint (pivot and
# groove joints). A zero determinant is not checked, as in pymunk's build.
cdef inline cpMat2x2 k_tensor(cpBody *a, cpBody *b, cpVect r1, cpVect r2) noexcept nogil:
    cdef cpFloat m_sum = a.m_inv + b.m_inv
    cdef cpFloat k11 = m_sum, k12 = 0.0
    cdef cpFloat k21 = 0.0, k22 = m_sum
    cdef cpFloat a_i_inv = a.i_inv
    cdef cpFloat r1xsq = r1.x * r1.x * a_i_inv
    cdef cpFloat r1ysq = r1.y * r1.y * a_i_inv
    cdef cpFloat r1nxy = -r1.x * r1.y * a_i_inv
    k11 += r1ysq
    k12 += r1nxy
    k21 += r1nxy
    k22 += r1xsq
    cdef cpFloat b_i_inv = b.i_inv
    cdef cpFloat r2xsq = r2.x * r2.x * b_i_inv
    cdef cpFloat r2ysq = r2.y * r2.y * b_i_inv
    cdef cpFloat r2nxy = -r2.x * r2.y * b_i_inv
    k11 += r2ysq
    k12 += r2nxy
    k21 += r2nxy
    k22 += r2xsq
    cdef cpFloat det = k11 * k22 - k12 * k21
    cdef cpFloat det_inv = 1.0 / det
    return cpMat2x2New(k22 * det_inv, -k12 * det_inv, -k21 * det_inv, k11 * det_inv)

# Fraction of a joint's error corrected in a step of length dt.
cdef inline cpFloat bias_coef(cpFloat errorBias, cpFloat dt) noexcept nogil:
    return 1.0 - pow(errorBias, dt)

# -- cpConstraint.c ----------------------------------------------------------------------
cdef void cpConstraintInit(cpConstraint *constraint, const cpConstraintClass *klass,
                           cpBody *a, cpBody *b) noexcept nogil
cdef cpFloat cpConstraintGetImpulse(cpConstraint *constraint) noexcept nogil

# Which joint a constraint is (its class table).
cdef cpBool cpConstraintIsPinJoint(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsSlideJoint(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsPivotJoint(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsGrooveJoint(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsDampedSpring(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsDampedRotarySpring(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsRotaryLimitJoint(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsRatchetJoint(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsGearJoint(const cpConstraint *constraint) noexcept nogil
cdef cpBool cpConstraintIsSimpleMotor(const cpConstraint *constraint) noexcept nogil

# -- joint constructors (Init on caller-owned memory; bodies may be NULL) ----------
cdef cpPinJoint *cpPinJointInit(cpPinJoint *joint, cpBody *a, cpBody *b,
                                cpVect anchorA, cpVect anchorB) noexcept nogil
cdef cpSlideJoint *cpSlideJointInit(cpSlideJoint *joint, cpBody *a, cpBody *b, cpVect anchorA,
                                    cpVect anchorB, cpFloat min, cpFloat max) noexcept nogil
cdef cpPivotJoint *cpPivotJointInit(cpPivotJoint *joint, cpBody *a, cpBody *b,
                                    cpVect anchorA, cpVect anchorB) noexcept nogil
cdef cpGrooveJoint *cpGrooveJointInit(cpGrooveJoint *joint, cpBody *a, cpBody *b,
                                      cpVect groove_a, cpVect groove_b, cpVect anchorB) noexcept nogil
cdef cpDampedSpring *cpDampedSpringInit(cpDampedSpring *spring, cpBody *a, cpBody *b,
                                        cpVect anchorA, cpVect anchorB, cpFloat restLength,
                                        cpFloat stiffness, cpFloat damping) noexcept nogil
cdef cpDampedRotarySpring *cpDampedRotarySpringInit(cpDampedRotarySpring *spring, cpBody *a,
        cpBody *b, cpFloat restAngle, cpFloat stiffness, cpFloat damping) noexcept nogil
cdef cpRotaryLimitJoint *cpRotaryLimitJointInit(cpRotaryLimitJoint *joint, cpBody *a, cpBody *b,
                                                cpFloat min, cpFloat max) noexcept nogil
cdef cpRatchetJoint *cpRatchetJointInit(cpRatchetJoint *joint, cpBody *a, cpBody *b,
                                        cpFloat phase, cpFloat ratchet) noexcept nogil
cdef cpGearJoint *cpGearJointInit(cpGearJoint *joint, cpBody *a, cpBody *b,
                                  cpFloat phase, cpFloat ratio) noexcept nogil
cdef cpSimpleMotor *cpSimpleMotorInit(cpSimpleMotor *joint, cpBody *a, cpBody *b,
                                      cpFloat rate) noexcept nogil

# -- helpers for the space module -------------------------------------------------------
# Unlink a constraint from its space without waking anything: swap-remove it
# from space->constraints (a no-op when sleeping took it out), unlink it from
# both bodies' lists, clear constraint->space. For teardown (a constraint or a
# space being freed); Space.remove uses cpSpaceRemoveConstraint.
cdef void tamias_constraint_detach(cpConstraint *constraint) noexcept nogil
# Detach every constraint that still points at `space`: those in its array and
# those of the bodies of its sleeping components. For Space teardown.
cdef void tamias_space_detach_constraints(cpSpace *space) noexcept nogil
cdef void tamias_constraint_clear_impulse(cpConstraint *c) noexcept nogil
# Multiplies the accumulated (warm-start) impulse by factor (the soft solver).
cdef void tamias_constraint_scale_impulse(cpConstraint *c, cpFloat factor) noexcept nogil
# Raise a clear exception (and return -1) if a constraint of the space's array
# would drive the solver into a division by zero or a NaN: a dynamic body with
# a mass or moment the step would reject, a ratchet or gear ratio of 0, or a
# rotary joint between two bodies that cannot rotate; or, with sleeping on, a
# dynamic body of another space. Called before a step.
cdef int tamias_check_constraints(cpSpace *space) except -1
# The same test without the GIL: 1 when tamias_check_constraints would pass.
cdef bint tamias_constraints_ok(cpSpace *space) noexcept nogil
# The joints-across-spaces rule, checked by Space.add: a joint may be in a
# space only if each of its bodies is in that space or in none (a body in no
# space whose shapes were left in another space counts as of that space).
# Raise IllegalConstraint (and return -1) when adding `c` to `space`, or when
# adding `body` to `space` while one of its joints lives in another space.
cdef int tamias_check_joint_space(cpSpace *space, cpConstraint *c) except -1
cdef int tamias_check_body_joints(cpSpace *space, cpBody *body) except -1
# cpSpaceDebugDrawConstraint: draw one constraint with a Python
# SpaceDebugDrawOptions (draw_dot / draw_segment; segments with a NaN end are
# skipped, as pymunk does).
cdef int tamias_constraint_debug_draw(cpConstraint *constraint, cpTransform t, object options,
                                      object color) except -1

# -- Python ----------------------------------------------------------------------------------
cdef class Constraint:
    cdef cpConstraint *_constraint   # points at the subclass's embedded joint struct
    cdef Body _a                     # the two bodies (strong references), None before __init__
    cdef Body _b
    cdef object _pre_solve_func      # Python pre_solve / post_solve, or None
    cdef object _post_solve_func
    cdef dict __dict__               # user attributes (pickled as pymunk does)
    cdef object __weakref__          # Body.constraints holds constraints weakly

cdef class PinJoint(Constraint):
    cdef cpPinJoint _joint

cdef class SlideJoint(Constraint):
    cdef cpSlideJoint _joint

cdef class PivotJoint(Constraint):
    cdef cpPivotJoint _joint

cdef class GrooveJoint(Constraint):
    cdef cpGrooveJoint _joint

cdef class DampedSpring(Constraint):
    cdef cpDampedSpring _joint
    cdef object _force_func          # Python spring force, or None for the C default

cdef class DampedRotarySpring(Constraint):
    cdef cpDampedRotarySpring _joint
    cdef object _torque_func         # Python spring torque, or None for the C default

cdef class RotaryLimitJoint(Constraint):
    cdef cpRotaryLimitJoint _joint

cdef class RatchetJoint(Constraint):
    cdef cpRatchetJoint _joint

cdef class GearJoint(Constraint):
    cdef cpGearJoint _joint

cdef class SimpleMotor(Constraint):
    cdef cpSimpleMotor _joint
