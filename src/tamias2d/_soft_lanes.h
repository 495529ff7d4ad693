/* The soft solver's contact kernels, several contacts at a time.
 *
 * Contacts of one graph colour share no movable body, so they can be solved
 * together: SoftLanes holds SOFT_LANES of them in structure-of-arrays form
 * (each field one double per lane) and each kernel below works on all lanes
 * at once. It is Box2D v3's contact_solver.c idea (b2ContactConstraintSIMD),
 * in double precision and with this solver's two-point block solve.
 *
 * Each kernel is written once over a type `V` and instantiated twice:
 *   - with GCC / Clang vector extensions (`V` is two doubles: SSE2 on
 *     x86-64, NEON on arm64, both part of the base architecture, so no
 *     -march flag is needed), as soft_*_simd;
 *   - with `V` a plain double, looping over the lanes, as soft_*_scalar (the
 *     path on compilers without vector extensions, and a check of the other).
 * Both do the same IEEE operations in the same order (no fused multiply-add:
 * the build passes -ffp-contract=off; branches become selects in both), so
 * they give the same bits, which tests/test_soft_solver.py checks.
 */
#ifndef TAMIAS_SOFT_LANES_H
#define TAMIAS_SOFT_LANES_H

#include <stddef.h>
#include <string.h>

#define SOFT_LANES 2

/* The solver state of one body (Box2D's b2BodyState): velocity and the
 * motion since the step began. Slot 0 is the immovable body (all zero,
 * qc = 1). */
typedef struct {
    double vx, vy, w;
    double dpx, dpy;      /* centre displacement since the step began */
    double qc, qs;        /* rotation since the step began (cos, sin) */
    double pad;
} SoftState;

/* SOFT_LANES contact constraints of one colour, all with `points` points
 * (one-point manifolds, most of a pile of circles, get a one-row solve).
 * Point j of lane k is field[j][k]. An empty lane is filled so that it takes
 * no impulse (SoftLanesClear). */
typedef struct {
    int points;                           /* 1 or 2: every lane's manifold has that many */
    int ia[SOFT_LANES], ib[SOFT_LANES];   /* SoftState slots */
    int wa[SOFT_LANES], wb[SOFT_LANES];   /* write the body back (movable, not slot 0) */
    int src[SOFT_LANES];                  /* SoftContact index, -1: empty lane */
    double mA[SOFT_LANES], iA[SOFT_LANES], mB[SOFT_LANES], iB[SOFT_LANES];
    double nx[SOFT_LANES], ny[SOFT_LANES];
    double friction[SOFT_LANES], surfaceT[SOFT_LANES];
    double k11[SOFT_LANES], k12[SOFT_LANES], k22[SOFT_LANES];
    double rAx[2][SOFT_LANES], rAy[2][SOFT_LANES], rBx[2][SOFT_LANES], rBy[2][SOFT_LANES];
    double rnA[2][SOFT_LANES], rnB[2][SOFT_LANES], rtA[2][SOFT_LANES], rtB[2][SOFT_LANES];
    double base[2][SOFT_LANES];           /* adjusted separation */
    double biasRate[2][SOFT_LANES], compliance[2][SOFT_LANES];
    double tangentMass[2][SOFT_LANES];
    double normalImpulse[2][SOFT_LANES], tangentImpulse[2][SOFT_LANES];
    double maxNormalImpulse[2][SOFT_LANES];
    double totalNormal[2][SOFT_LANES], totalTangent[2][SOFT_LANES];
} SoftLanes;

/* Far apart: a row with this separation is speculative and its bias keeps
 * its impulse at zero. */
#define SOFT_LANE_FAR 1e30

static inline void SoftLanesClear(SoftLanes *c, int k) {
    /* Lane k (of a colour's last, part-filled lane) takes no impulse: it
     * joins the immovable slot 0 to itself, its rows far apart. */
    int p;
    c->ia[k] = c->ib[k] = 0;
    c->wa[k] = c->wb[k] = 0;
    c->src[k] = -1;
    c->mA[k] = c->iA[k] = c->mB[k] = c->iB[k] = 0.0;
    c->nx[k] = 0.0; c->ny[k] = 1.0;
    c->friction[k] = c->surfaceT[k] = 0.0;
    c->k11[k] = 1.0; c->k12[k] = 0.0; c->k22[k] = 1.0;
    for (p = 0; p < 2; p++) {
        c->rAx[p][k] = c->rAy[p][k] = c->rBx[p][k] = c->rBy[p][k] = 0.0;
        c->rnA[p][k] = c->rnB[p][k] = c->rtA[p][k] = c->rtB[p][k] = 0.0;
        c->base[p][k] = SOFT_LANE_FAR;
        c->biasRate[p][k] = c->compliance[p][k] = 0.0;
        c->tangentMass[p][k] = 0.0;
        c->normalImpulse[p][k] = c->tangentImpulse[p][k] = 0.0;
        c->maxNormalImpulse[p][k] = 0.0;
        c->totalNormal[p][k] = c->totalTangent[p][k] = 0.0;
    }
}

#endif /* TAMIAS_SOFT_LANES_H */

/* -- the kernels, instantiated twice ------------------------------------------- */

#if defined(__GNUC__) || defined(__clang__)
#define SOFT_HAVE_SIMD 1
typedef double SoftV2 __attribute__((vector_size(16)));
typedef long long SoftM2 __attribute__((vector_size(16)));

#define V SoftV2
#define M SoftM2
#define SOFT_KERNEL(name) name##_simd
#define LOOP_LANES(k) for (k = 0; k < 1; k++)
static inline V soft_v_load(const double *p, int k) { V v; (void)k; memcpy(&v, p, sizeof(v)); return v; }
static inline void soft_v_store(double *p, int k, V v) { (void)k; memcpy(p, &v, sizeof(v)); }
static inline V soft_v_splat(double s) { V v = {s, s}; return v; }
static inline V soft_v_gather(const SoftState *st, const int *idx, int k, size_t off) {
    V v; (void)k;
    v[0] = *(const double *)((const char *)&st[idx[0]] + off);
    v[1] = *(const double *)((const char *)&st[idx[1]] + off);
    return v;
}
static inline void soft_v_scatter(SoftState *st, const int *idx, const int *w, int k, size_t off, V v) {
    (void)k;
    if (w[0]) *(double *)((char *)&st[idx[0]] + off) = v[0];
    if (w[1]) *(double *)((char *)&st[idx[1]] + off) = v[1];
}
#define V_SEL(m, a, b) ((V)(((M)(a) & (m)) | ((M)(b) & ~(m))))
#define V_GT(a, b) ((M)((a) > (b)))
#define V_GE(a, b) ((M)((a) >= (b)))
#define V_LT(a, b) ((M)((a) < (b)))
#define V_AND(m, n) ((m) & (n))
#define V_OR(m, n) ((m) | (n))
#define V_ANDNOT(m, n) (~(m) & (n))
#define V_NOT(m) (~(m))
/* Of three exclusive masks, the value of the one that is set, else +0.0. */
#define V_PICK3(m1, a, m2, b, m3, c) ((V)(((M)(a) & (m1)) | ((M)(b) & (m2)) | ((M)(c) & (m3))))
#include "_soft_lanes_kernels.h"
#else
#define SOFT_HAVE_SIMD 0
#endif

#define V double
#define M int
#define SOFT_KERNEL(name) name##_scalar
#define LOOP_LANES(k) for (k = 0; k < SOFT_LANES; k++)
static inline double soft_s_load(const double *p, int k) { return p[k]; }
static inline void soft_s_store(double *p, int k, double v) { p[k] = v; }
static inline double soft_s_splat(double s) { return s; }
static inline double soft_s_gather(const SoftState *st, const int *idx, int k, size_t off) {
    return *(const double *)((const char *)&st[idx[k]] + off);
}
static inline void soft_s_scatter(SoftState *st, const int *idx, const int *w, int k, size_t off, double v) {
    if (w[k]) *(double *)((char *)&st[idx[k]] + off) = v;
}
#define soft_v_load soft_s_load
#define soft_v_store soft_s_store
#define soft_v_splat soft_s_splat
#define soft_v_gather soft_s_gather
#define soft_v_scatter soft_s_scatter
#define V_SEL(m, a, b) ((m) ? (a) : (b))
#define V_GT(a, b) ((a) > (b))
#define V_GE(a, b) ((a) >= (b))
#define V_LT(a, b) ((a) < (b))
#define V_AND(m, n) ((m) && (n))
#define V_OR(m, n) ((m) || (n))
#define V_ANDNOT(m, n) (!(m) && (n))
#define V_NOT(m) (!(m))
#define V_PICK3(m1, a, m2, b, m3, c) ((m1) ? (a) : (m2) ? (b) : (m3) ? (c) : 0.0)
#include "_soft_lanes_kernels.h"

/* The path the solver takes: the vector kernels where the compiler has
 * them, unless soft_lanes_use_scalar is set (a test switch). */
static int soft_lanes_use_scalar = 0;

static inline void SoftLanesWarmStart(SoftLanes *c, SoftState *st) {
#if SOFT_HAVE_SIMD
    if (!soft_lanes_use_scalar) { soft_warm_start_simd(c, st); return; }
#endif
    soft_warm_start_scalar(c, st);
}

static inline void SoftLanesSolve(SoftLanes *c, SoftState *st, double inv_h, double pushOut, int useBias) {
#if SOFT_HAVE_SIMD
    if (!soft_lanes_use_scalar) { soft_solve_simd(c, st, inv_h, pushOut, useBias); return; }
#endif
    soft_solve_scalar(c, st, inv_h, pushOut, useBias);
}

static inline int SoftLanesHaveSimd(void) { return SOFT_HAVE_SIMD; }
static inline void SoftLanesSetScalar(int on) { soft_lanes_use_scalar = on; }
static inline int SoftLanesScalar(void) { return soft_lanes_use_scalar || !SOFT_HAVE_SIMD; }
