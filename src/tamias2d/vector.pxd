# Vector module (MIS section 9): the C-level vector, bounding box and affine
# transform of Munk2D (cpVect.h, cpBB.h, cpTransform.h, chipmunk_types.h) as
# inline kernels. Every expression keeps the association of the C headers so
# that results are bitwise equal to pymunk's.
from libc.math cimport sqrt, cos, sin, atan2, acos, fmod, INFINITY
from libc.float cimport DBL_MIN
from libc.limits cimport INT_MAX, INT_MIN
from tamias2d._config cimport cpFloat, cpBool

ctypedef struct cpVect:
    cpFloat x
    cpFloat y

ctypedef struct cpBB:
    cpFloat l
    cpFloat b
    cpFloat r
    cpFloat t

ctypedef struct cpTransform:
    cpFloat a
    cpFloat b
    cpFloat c
    cpFloat d
    cpFloat tx
    cpFloat ty

ctypedef struct cpMat2x2:
    cpFloat a
    cpFloat b
    cpFloat c
    cpFloat d

# -- scalars (chipmunk_types.h) ----------------------------------------------
cdef inline cpFloat cpfmax(cpFloat a, cpFloat b) noexcept nogil:
    return a if a > b else b

cdef inline cpFloat cpfmin(cpFloat a, cpFloat b) noexcept nogil:
    return a if a < b else b

cdef inline cpFloat cpfabs(cpFloat f) noexcept nogil:
    return -f if f < 0 else f

cdef inline cpFloat cpfclamp(cpFloat f, cpFloat lo, cpFloat hi) noexcept nogil:
    return cpfmin(cpfmax(f, lo), hi)

cdef inline cpFloat cpfclamp01(cpFloat f) noexcept nogil:
    return cpfmax(0.0, cpfmin(f, 1.0))

cdef inline cpFloat cpflerp(cpFloat f1, cpFloat f2, cpFloat t) noexcept nogil:
    return f1 * (1.0 - t) + f2 * t

cdef inline cpFloat cpflerpconst(cpFloat f1, cpFloat f2, cpFloat d) noexcept nogil:
    return f1 + cpfclamp(f2 - f1, -d, d)

# -- vectors (cpVect.h); MIS names in comments --------------------------------
cdef inline cpVect cpv(cpFloat x, cpFloat y) noexcept nogil:  # vect
    cdef cpVect v
    v.x = x
    v.y = y
    return v

cdef inline cpBool cpveql(cpVect v1, cpVect v2) noexcept nogil:  # vectEqual
    return v1.x == v2.x and v1.y == v2.y

cdef inline cpVect cpvadd(cpVect v1, cpVect v2) noexcept nogil:  # vectAdd
    return cpv(v1.x + v2.x, v1.y + v2.y)

cdef inline cpVect cpvsub(cpVect v1, cpVect v2) noexcept nogil:  # vectSub
    return cpv(v1.x - v2.x, v1.y - v2.y)

cdef inline cpVect cpvneg(cpVect v) noexcept nogil:  # vectNeg
    return cpv(-v.x, -v.y)

cdef inline cpVect cpvmult(cpVect v, cpFloat s) noexcept nogil:  # vectMult
    return cpv(v.x * s, v.y * s)

cdef inline cpFloat cpvdot(cpVect v1, cpVect v2) noexcept nogil:  # vectDot
    return v1.x * v2.x + v1.y * v2.y

cdef inline cpFloat cpvcross(cpVect v1, cpVect v2) noexcept nogil:  # vectCross
    return v1.x * v2.y - v1.y * v2.x

cdef inline cpVect cpvperp(cpVect v) noexcept nogil:  # vectPerp
    return cpv(-v.y, v.x)

cdef inline cpVect cpvrperp(cpVect v) noexcept nogil:  # vectRPerp
    return cpv(v.y, -v.x)

cdef inline cpVect cpvproject(cpVect v1, cpVect v2) noexcept nogil:  # vectProject
    return cpvmult(v2, cpvdot(v1, v2) / cpvdot(v2, v2))

cdef inline cpVect cpvforangle(cpFloat a) noexcept nogil:  # vectForAngle
    return cpv(cos(a), sin(a))

cdef inline cpFloat cpvtoangle(cpVect v) noexcept nogil:  # vectToAngle
    return atan2(v.y, v.x)

cdef inline cpVect cpvrotate(cpVect v1, cpVect v2) noexcept nogil:  # vectRotate
    return cpv(v1.x * v2.x - v1.y * v2.y, v1.x * v2.y + v1.y * v2.x)

cdef inline cpVect cpvunrotate(cpVect v1, cpVect v2) noexcept nogil:  # vectUnrotate
    return cpv(v1.x * v2.x + v1.y * v2.y, v1.y * v2.x - v1.x * v2.y)

cdef inline cpFloat cpvlengthsq(cpVect v) noexcept nogil:  # vectLengthSq
    return cpvdot(v, v)

cdef inline cpFloat cpvlength(cpVect v) noexcept nogil:  # vectLength
    return sqrt(cpvdot(v, v))

cdef inline cpVect cpvlerp(cpVect v1, cpVect v2, cpFloat t) noexcept nogil:  # vectLerp
    return cpvadd(cpvmult(v1, 1.0 - t), cpvmult(v2, t))

cdef inline cpVect cpvnormalize(cpVect v) noexcept nogil:  # vectNormalize
    # Adds DBL_MIN so a zero vector gives (0, 0) rather than NaN.
    return cpvmult(v, 1.0 / (cpvlength(v) + DBL_MIN))

cdef inline cpVect cpvslerp(cpVect v1, cpVect v2, cpFloat t) noexcept nogil:
    cdef cpFloat dot = cpvdot(cpvnormalize(v1), cpvnormalize(v2))
    cdef cpFloat omega = acos(cpfclamp(dot, -1.0, 1.0))
    cdef cpFloat denom
    if omega < 1e-3:
        return cpvlerp(v1, v2, t)
    denom = 1.0 / sin(omega)
    return cpvadd(cpvmult(v1, sin((1.0 - t) * omega) * denom), cpvmult(v2, sin(t * omega) * denom))

cdef inline cpVect cpvslerpconst(cpVect v1, cpVect v2, cpFloat a) noexcept nogil:
    cdef cpFloat dot = cpvdot(cpvnormalize(v1), cpvnormalize(v2))
    cdef cpFloat omega = acos(cpfclamp(dot, -1.0, 1.0))
    return cpvslerp(v1, v2, cpfmin(a, omega) / omega)

cdef inline cpVect cpvclamp(cpVect v, cpFloat len) noexcept nogil:  # vectClamp
    return cpvmult(cpvnormalize(v), len) if cpvdot(v, v) > len * len else v

cdef inline cpVect cpvlerpconst(cpVect v1, cpVect v2, cpFloat d) noexcept nogil:
    return cpvadd(v1, cpvclamp(cpvsub(v2, v1), d))

cdef inline cpFloat cpvdist(cpVect v1, cpVect v2) noexcept nogil:  # vectDist
    return cpvlength(cpvsub(v1, v2))

cdef inline cpFloat cpvdistsq(cpVect v1, cpVect v2) noexcept nogil:  # vectDistSq
    return cpvlengthsq(cpvsub(v1, v2))

cdef inline cpBool cpvnear(cpVect v1, cpVect v2, cpFloat dist) noexcept nogil:  # vectNear
    return cpvdistsq(v1, v2) < dist * dist

# MIS 9.3.1 exported constants. zeroVect is Munk2D's cpvzero and PI its CP_PI;
# VECT_ERR ({INT_MAX, INT_MIN}) has no use in Munk2D and exists for the MIS.
# (Cython has no struct constants, hence the inline functions.)
cdef const cpFloat CP_PI = 3.14159265358979323846264338327950288

cdef inline cpVect cpvzero() noexcept nogil:  # zeroVect
    return cpv(0.0, 0.0)

cdef inline cpVect VECT_ERR() noexcept nogil:  # VECT_ERR
    return cpv(<cpFloat>INT_MAX, <cpFloat>INT_MIN)

cdef inline cpMat2x2 cpMat2x2New(cpFloat a, cpFloat b, cpFloat c, cpFloat d) noexcept nogil:
    cdef cpMat2x2 m
    m.a = a
    m.b = b
    m.c = c
    m.d = d
    return m

cdef inline cpVect cpMat2x2Transform(cpMat2x2 m, cpVect v) noexcept nogil:
    return cpv(v.x * m.a + v.y * m.b, v.x * m.c + v.y * m.d)

# chipmunk.h: closest point on segment a-b to p (parameter measured from b; a
# zero-length segment gives NaN, which the clamp turns into 1, i.e. a).
cdef inline cpVect cpClosetPointOnSegment(cpVect p, cpVect a, cpVect b) noexcept nogil:
    cdef cpVect delta = cpvsub(a, b)
    cdef cpFloat t = cpfclamp01(cpvdot(delta, cpvsub(p, b)) / cpvlengthsq(delta))
    return cpvadd(b, cpvmult(delta, t))

# -- bounding boxes (cpBB.h) --------------------------------------------------
cdef inline cpBB cpBBNew(cpFloat l, cpFloat b, cpFloat r, cpFloat t) noexcept nogil:
    cdef cpBB bb
    bb.l = l
    bb.b = b
    bb.r = r
    bb.t = t
    return bb

cdef inline cpBB cpBBNewForExtents(cpVect c, cpFloat hw, cpFloat hh) noexcept nogil:
    return cpBBNew(c.x - hw, c.y - hh, c.x + hw, c.y + hh)

cdef inline cpBB cpBBNewForCircle(cpVect p, cpFloat r) noexcept nogil:
    return cpBBNewForExtents(p, r, r)

cdef inline cpBool cpBBIntersects(cpBB a, cpBB b) noexcept nogil:
    return a.l <= b.r and b.l <= a.r and a.b <= b.t and b.b <= a.t

cdef inline cpBool cpBBContainsBB(cpBB bb, cpBB other) noexcept nogil:
    return bb.l <= other.l and bb.r >= other.r and bb.b <= other.b and bb.t >= other.t

cdef inline cpBool cpBBContainsVect(cpBB bb, cpVect v) noexcept nogil:
    return bb.l <= v.x and bb.r >= v.x and bb.b <= v.y and bb.t >= v.y

cdef inline cpBB cpBBMerge(cpBB a, cpBB b) noexcept nogil:
    return cpBBNew(cpfmin(a.l, b.l), cpfmin(a.b, b.b), cpfmax(a.r, b.r), cpfmax(a.t, b.t))

cdef inline cpBB cpBBExpand(cpBB bb, cpVect v) noexcept nogil:
    return cpBBNew(cpfmin(bb.l, v.x), cpfmin(bb.b, v.y), cpfmax(bb.r, v.x), cpfmax(bb.t, v.y))

cdef inline cpVect cpBBCenter(cpBB bb) noexcept nogil:
    return cpvlerp(cpv(bb.l, bb.b), cpv(bb.r, bb.t), 0.5)

cdef inline cpFloat cpBBArea(cpBB bb) noexcept nogil:
    return (bb.r - bb.l) * (bb.t - bb.b)

cdef inline cpFloat cpBBMergedArea(cpBB a, cpBB b) noexcept nogil:
    return (cpfmax(a.r, b.r) - cpfmin(a.l, b.l)) * (cpfmax(a.t, b.t) - cpfmin(a.b, b.b))

cdef inline cpFloat cpBBSegmentQuery(cpBB bb, cpVect a, cpVect b) noexcept nogil:
    cdef cpVect delta = cpvsub(b, a)
    cdef cpFloat tmin = -INFINITY
    cdef cpFloat tmax = INFINITY
    cdef cpFloat t1, t2
    if delta.x == 0.0:
        if a.x < bb.l or bb.r < a.x:
            return INFINITY
    else:
        t1 = (bb.l - a.x) / delta.x
        t2 = (bb.r - a.x) / delta.x
        tmin = cpfmax(tmin, cpfmin(t1, t2))
        tmax = cpfmin(tmax, cpfmax(t1, t2))
    if delta.y == 0.0:
        if a.y < bb.b or bb.t < a.y:
            return INFINITY
    else:
        t1 = (bb.b - a.y) / delta.y
        t2 = (bb.t - a.y) / delta.y
        tmin = cpfmax(tmin, cpfmin(t1, t2))
        tmax = cpfmin(tmax, cpfmax(t1, t2))
    if tmin <= tmax and 0.0 <= tmax and tmin <= 1.0:
        return cpfmax(tmin, 0.0)
    return INFINITY

cdef inline cpBool cpBBIntersectsSegment(cpBB bb, cpVect a, cpVect b) noexcept nogil:
    return cpBBSegmentQuery(bb, a, b) != INFINITY

cdef inline cpVect cpBBClampVect(cpBB bb, cpVect v) noexcept nogil:
    return cpv(cpfclamp(v.x, bb.l, bb.r), cpfclamp(v.y, bb.b, bb.t))

cdef inline cpVect cpBBWrapVect(cpBB bb, cpVect v) noexcept nogil:
    cdef cpFloat dx = cpfabs(bb.r - bb.l)
    cdef cpFloat modx = fmod(v.x - bb.l, dx)
    cdef cpFloat x = modx if modx > 0.0 else modx + dx
    cdef cpFloat dy = cpfabs(bb.t - bb.b)
    cdef cpFloat mody = fmod(v.y - bb.b, dy)
    cdef cpFloat y = mody if mody > 0.0 else mody + dy
    return cpv(x + bb.l, y + bb.b)

cdef inline cpBB cpBBOffset(cpBB bb, cpVect v) noexcept nogil:
    return cpBBNew(bb.l + v.x, bb.b + v.y, bb.r + v.x, bb.t + v.y)

# -- affine transforms (cpTransform.h) -----------------------------------------
cdef inline cpTransform cpTransformNew(cpFloat a, cpFloat b, cpFloat c, cpFloat d,
                                       cpFloat tx, cpFloat ty) noexcept nogil:
    cdef cpTransform t
    t.a = a
    t.b = b
    t.c = c
    t.d = d
    t.tx = tx
    t.ty = ty
    return t

cdef inline cpTransform cpTransformNewTranspose(cpFloat a, cpFloat c, cpFloat tx,
                                                cpFloat b, cpFloat d, cpFloat ty) noexcept nogil:
    return cpTransformNew(a, b, c, d, tx, ty)

cdef inline cpTransform cpTransformIdentity() noexcept nogil:
    return cpTransformNew(1.0, 0.0, 0.0, 1.0, 0.0, 0.0)

cdef inline cpTransform cpTransformInverse(cpTransform t) noexcept nogil:
    cdef cpFloat inv_det = 1.0 / (t.a * t.d - t.c * t.b)
    return cpTransformNewTranspose(
        t.d * inv_det, -t.c * inv_det, (t.c * t.ty - t.tx * t.d) * inv_det,
        -t.b * inv_det, t.a * inv_det, (t.tx * t.b - t.a * t.ty) * inv_det)

cdef inline cpTransform cpTransformMult(cpTransform t1, cpTransform t2) noexcept nogil:
    return cpTransformNewTranspose(
        t1.a * t2.a + t1.c * t2.b, t1.a * t2.c + t1.c * t2.d, t1.a * t2.tx + t1.c * t2.ty + t1.tx,
        t1.b * t2.a + t1.d * t2.b, t1.b * t2.c + t1.d * t2.d, t1.b * t2.tx + t1.d * t2.ty + t1.ty)

cdef inline cpVect cpTransformPoint(cpTransform t, cpVect p) noexcept nogil:
    return cpv(t.a * p.x + t.c * p.y + t.tx, t.b * p.x + t.d * p.y + t.ty)

cdef inline cpVect cpTransformVect(cpTransform t, cpVect v) noexcept nogil:
    return cpv(t.a * v.x + t.c * v.y, t.b * v.x + t.d * v.y)

cdef inline cpBB cpTransformbBB(cpTransform t, cpBB bb) noexcept nogil:
    cdef cpVect center = cpBBCenter(bb)
    cdef cpFloat hw = (bb.r - bb.l) * 0.5
    cdef cpFloat hh = (bb.t - bb.b) * 0.5
    cdef cpFloat a = t.a * hw
    cdef cpFloat b = t.c * hh
    cdef cpFloat d = t.b * hw
    cdef cpFloat e = t.d * hh
    cdef cpFloat hw_max = cpfmax(cpfabs(a + b), cpfabs(a - b))
    cdef cpFloat hh_max = cpfmax(cpfabs(d + e), cpfabs(d - e))
    return cpBBNewForExtents(cpTransformPoint(t, center), hw_max, hh_max)

cdef inline cpTransform cpTransformTranslate(cpVect translate) noexcept nogil:
    return cpTransformNewTranspose(1.0, 0.0, translate.x, 0.0, 1.0, translate.y)

cdef inline cpTransform cpTransformScale(cpFloat scaleX, cpFloat scaleY) noexcept nogil:
    return cpTransformNewTranspose(scaleX, 0.0, 0.0, 0.0, scaleY, 0.0)

cdef inline cpTransform cpTransformRotate(cpFloat radians) noexcept nogil:
    cdef cpVect rot = cpvforangle(radians)
    return cpTransformNewTranspose(rot.x, -rot.y, 0.0, rot.y, rot.x, 0.0)

cdef inline cpTransform cpTransformRigid(cpVect translate, cpFloat radians) noexcept nogil:
    cdef cpVect rot = cpvforangle(radians)
    return cpTransformNewTranspose(rot.x, -rot.y, translate.x, rot.y, rot.x, translate.y)

cdef inline cpTransform cpTransformRigidInverse(cpTransform t) noexcept nogil:
    return cpTransformNewTranspose(
        t.d, -t.c, (t.c * t.ty - t.tx * t.d),
        -t.b, t.a, (t.tx * t.b - t.a * t.ty))

cdef inline cpTransform cpTransformWrap(cpTransform outer, cpTransform inner) noexcept nogil:
    return cpTransformMult(cpTransformInverse(outer), cpTransformMult(inner, outer))

cdef inline cpTransform cpTransformWrapInverse(cpTransform outer, cpTransform inner) noexcept nogil:
    return cpTransformMult(outer, cpTransformMult(inner, cpTransformInverse(outer)))

# -- Python boundary (defined in vector.pyx) -----------------------------------
# A Vec2d from a C vector, and a C vector from any 2-sequence (Vec2d, tuple,
# list, ...); raises TypeError/ValueError with a clear message otherwise.
cdef object vec2d_from_cpv(cpVect v)
cdef cpVect cpv_from_object(object o) except *
# Same, but rejects NaN and infinite components with ValueError naming `what`.
cdef cpVect cpv_from_object_finite(object o, str what) except *
cdef object bb_from_cpbb(cpBB bb)
cdef cpBB cpbb_from_object(object o) except *
cdef object transform_from_cp(cpTransform t)
cdef cpTransform cptransform_from_object(object o) except *
