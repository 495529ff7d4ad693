/* The soft solver's contact kernels, several contacts at a time.
 *
 * Contacts of one graph colour share no movable body, so they can be solved
 * together: SoftLanes holds SOFT_LANES of them in structure-of-arrays form
 * (each field one double per lane) and each kernel below works on all lanes
 * at once. It is Box2D v3's contact_solver.c idea (b2ContactConstraintSIMD),
 * in double precision and with this solver's two-point block solve.
 *
 * Each kernel is written once over a type `V` and instantiated three times:
 *   - with GCC / Clang vector extensions, `V` two doubles (SSE2 on x86-64,
 *     NEON on arm64, both part of the base architecture, so no -march flag
 *     is needed), two passes over a SoftLanes, as soft_*_simd;
 *   - with GCC on x86-64, `V` four doubles compiled for AVX2 (a function
 *     target, chosen at run time where the CPU has it), as soft_*_avx2;
 *   - with `V` a plain double, looping over the lanes, as soft_*_scalar (the
 *     path on compilers without vector extensions, and a check of the others).
 * All do the same IEEE operations in the same order (no fused multiply-add:
 * the build passes -ffp-contract=off and the AVX2 target does not include
 * FMA; branches become selects), so they give the same bits, which
 * tests/test_soft_solver.py checks.
 */
#ifndef TAMIAS_SOFT_LANES_H
#define TAMIAS_SOFT_LANES_H

#include <stddef.h>
#include <string.h>

#define SOFT_LANES 4

/* The kernels' bodies are inlined into their range loops whatever the
 * optimiser would choose, so that the flags become constants there. */
#if defined(__GNUC__) || defined(__clang__)
#define SOFT_ALWAYS_INLINE inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define SOFT_ALWAYS_INLINE __forceinline
#else
#define SOFT_ALWAYS_INLINE inline
#endif

/* The solver state of one body (Box2D's b2BodyState): velocity and the
 * motion since the step began, and the inverse mass, which fills the first
 * row's last place (the warm start gathers that row alone; in the lanes
 * each contact's would take a cache line of every pass). Two rows of four
 * doubles, one cache line. Slot 0 is the immovable body (all zero,
 * qc = 1). */
typedef struct {
    double vx, vy, w;
    double m_inv;
    double dpx, dpy;      /* centre displacement since the step began */
    double qc, qs;        /* rotation since the step began (cos, sin) */
} SoftState;

/* The state at byte offset `off` from st. The lanes hold their bodies'
 * slots as byte offsets (slot * sizeof(SoftState)), so that reaching a row
 * takes no multiplication: the kernels reach a row of each side of each
 * lane in every pass. */
#define SOFT_AT(st, off) (*(SoftState *)((const char *)(st) + (off)))

/* SOFT_LANES contact constraints of one colour, all with `points` points
 * (one-point manifolds, most of a pile of circles, get a one-row solve).
 * Point j of lane k is field[j][k]. An empty lane is filled so that it takes
 * no impulse (SoftLanesClear).
 *
 * Laid out by cache lines (64 bytes; the lanes array starts on one and a
 * lane is a whole number of them), in the order the passes read them: the
 * warm start reads lines 0-8; the biased pass 0-7 and 9-11; the relax
 * passes 0-9 and 12, and the last of a substep's also 14-15 (the step's
 * totals); a one-point lane's passes also 13. The passes are bound by the
 * bytes they stream (a large pile's lanes do not fit in a core's L2
 * cache), so the lines a pass touches decide its speed: a lane 256 bytes
 * longer made them 11-17% slower; this layout against the fields in their
 * first order (7% fewer bytes): warm start -22%, biased pass -10%, relax -5%
 * on the large pyramid. For the same reason a lane holds no bias rate (a
 * step has two, SoftLaneBiasRates) and no tangent mass (the relax passes
 * work it out from the arms, as the 2x2 normal matrix). */
typedef struct {
    int points;                           /* 1 or 2: every lane's manifold has that many */
    int ia[SOFT_LANES], ib[SOFT_LANES];   /* SoftState slots, as byte offsets (SOFT_AT) */
    unsigned char wa[SOFT_LANES], wb[SOFT_LANES];   /* write the body back (movable, not slot 0) */
    unsigned char inner[SOFT_LANES];      /* the contact is inside a web (SoftInnerContact; an
                                           * empty slot counts as inside): soft_lane_inner */
    char pad0[64 - 4 - 2 * 4 * SOFT_LANES - 3 * SOFT_LANES];
    double iA[SOFT_LANES], iB[SOFT_LANES];    /* (the masses are the bodies' SoftState's) */
    double nx[SOFT_LANES], ny[SOFT_LANES];
    double rAx[2][SOFT_LANES], rAy[2][SOFT_LANES], rBx[2][SOFT_LANES], rBy[2][SOFT_LANES];
    double normalImpulse[2][SOFT_LANES];
    double tangentImpulse[2][SOFT_LANES];
    double base[2][SOFT_LANES];           /* adjusted separation */
    double compliance[2][SOFT_LANES], preload[2][SOFT_LANES];
    double friction[SOFT_LANES], surfaceT[SOFT_LANES];
    double k11[SOFT_LANES];               /* one-point lanes: the row's effective mass (two-point
                                           * lanes work their 2x2 matrix out from the arms) */
    double pad13[SOFT_LANES];
    double totalNormal[2][SOFT_LANES], totalTangent[2][SOFT_LANES];
} SoftLanes;

/* The bodies' states a lane reads (each one cache line), fetched
 * SOFT_FETCH_AHEAD lanes before the kernel reaches it: the lanes stream in
 * order, which the hardware prefetches, but the states are scattered, and
 * in a pile larger than a core's L2 cache each one is a miss. */
#define SOFT_FETCH_AHEAD 4
#if defined(__GNUC__) || defined(__clang__)
#define SOFT_FETCH(p) __builtin_prefetch((p), 1)
#define SOFT_FETCH_READ(p) __builtin_prefetch((p), 0)
#else
#define SOFT_FETCH(p) ((void)(p))
#define SOFT_FETCH_READ(p) ((void)(p))
#endif

/* A whole number of cache lines (C89 has no static assertion). */
typedef char soft_lanes_fill_lines[sizeof(SoftLanes) % 64 == 0 ? 1 : -1];

/* What the passes over a lane do not read, beside it in an array of the
 * same index, so that it takes no room in the lines they stream:
 * maxNormalImpulse is read and written only in steps with an elastic
 * contact (restitution reads it), the rest when packing and storing. */
typedef struct {
    int src[SOFT_LANES];                  /* SoftContact index, -1: empty lane */
    void *dst[SOFT_LANES];                /* its arbiter's cpContacts (the step's impulses go there) */
    double maxNormalImpulse[2][SOFT_LANES];
} SoftLaneLinks;

/* Far apart: a row with this separation is speculative and its bias keeps
 * its impulse at zero. */
#define SOFT_LANE_FAR 1e30

/* A contact's bias rate is its softness's: the static one where a side is
 * immovable, else the contact one (SoftPrepareContact), so a step has two.
 * The kernels take a lane's four from a table of the 16 patterns, indexed
 * by which sides are both movable (wa and wb, already in the lane's first
 * line): SOFT_LANES doubles of every lane fewer to stream. The index
 * gathers the low bit of each of the four bytes (wa & wb) into four bits,
 * by one multiplication; the table is filled through the same function, so
 * the bit order (the bytes' order in a word) is whatever this machine's
 * is. */
#if SOFT_LANES != 4
#error "soft_lane_rate_index packs four lanes"
#endif
static inline unsigned int soft_lane_rate_index(const SoftLanes *c) {
    unsigned int a, b;
    memcpy(&a, c->wa, sizeof(a));
    memcpy(&b, c->wb, sizeof(b));
    return (((a & b) * 0x08040201u) >> 24) & 15u;
}

typedef struct {
    double rate[16][SOFT_LANES];
} SoftLaneBiasRates;

static inline void SoftLaneBiasRatesFill(SoftLaneBiasRates *t, double contactRate,
                                         double staticRate) {
    SoftLanes probe;
    int pattern, k;
    for (pattern = 0; pattern < 16; pattern++) {
        for (k = 0; k < SOFT_LANES; k++) {
            probe.wa[k] = (unsigned char)((pattern >> k) & 1);
            probe.wb[k] = 1;
        }
        for (k = 0; k < SOFT_LANES; k++)
            t->rate[soft_lane_rate_index(&probe)][k] = probe.wa[k] ? contactRate : staticRate;
    }
}

static inline void soft_fetch_states(const SoftLanes *c, const SoftState *st) {
    int k;
    for (k = 0; k < SOFT_LANES; k++) {
        SOFT_FETCH(&SOFT_AT(st, c->ia[k]));
        SOFT_FETCH(&SOFT_AT(st, c->ib[k]));
    }
}

/* The lines of a lane that the warm start reads (those before `base`),
 * fetched two lanes ahead. The lanes stream in order, but the warm start
 * does so little with each that on an AMD EPYC (Zen 3) the hardware's
 * fetching fell behind: its pass took 19-34% longer without this. The
 * solve's passes, with more arithmetic a lane, did not gain from it. */
static inline void soft_fetch_lane_for_warm_start(const SoftLanes *c) {
    const char *p = (const char *)c;
    int k;
    for (k = 0; k < (int)offsetof(SoftLanes, base); k += 64)
        SOFT_FETCH_READ(p + k);
}

/* How many of the lane's slots are inside a web (one byte a slot, each
 * written by whichever thread packs that contact). On one thread, and in
 * contact groups, the colouring gives the inner two-point contacts lanes of
 * their own (SoftLaneClass), and a relax pass that leaves them out
 * (skipInner) passes over whole lanes. */
static inline int soft_lane_inner(const SoftLanes *c) {
    int k, count = 0;
    for (k = 0; k < SOFT_LANES; k++)
        count += c->inner[k] != 0;
    return count;
}

/* On the pool the lanes keep arbiter order, which keeps a region's bodies
 * on one thread from pass to pass (the classes' lanes apart made both
 * threads' warm start and biased pass 15-20% slower); there such a pass
 * meets lanes of both kinds. It solves them with the inner slots' sides
 * not written back, then puts back what it wrote of their impulses: each
 * contact is solved, or not, as in a lane of its own kind (the contacts of
 * a lane share no body), so the layout changes no bits. */
typedef struct {
    unsigned char wa[SOFT_LANES], wb[SOFT_LANES];
    double normal[2][SOFT_LANES], tangent[2][SOFT_LANES], maxNormal[2][SOFT_LANES];
} SoftInnerHeld;

static inline void soft_lane_hold_inner(SoftLanes *c, const SoftLaneLinks *x, SoftInnerHeld *h) {
    int k;
    memcpy(h->wa, c->wa, sizeof(h->wa));
    memcpy(h->wb, c->wb, sizeof(h->wb));
    memcpy(h->normal, c->normalImpulse, sizeof(h->normal));
    memcpy(h->tangent, c->tangentImpulse, sizeof(h->tangent));
    memcpy(h->maxNormal, x->maxNormalImpulse, sizeof(h->maxNormal));
    for (k = 0; k < SOFT_LANES; k++)
        if (c->inner[k])
            c->wa[k] = c->wb[k] = 0;
}

static inline void soft_lane_release_inner(SoftLanes *c, SoftLaneLinks *x, const SoftInnerHeld *h) {
    int j, k;
    for (k = 0; k < SOFT_LANES; k++) {
        if (!c->inner[k])
            continue;
        for (j = 0; j < 2; j++) {
            c->normalImpulse[j][k] = h->normal[j][k];
            c->tangentImpulse[j][k] = h->tangent[j][k];
            x->maxNormalImpulse[j][k] = h->maxNormal[j][k];
        }
    }
    memcpy(c->wa, h->wa, sizeof(h->wa));
    memcpy(c->wb, h->wb, sizeof(h->wb));
}

static inline void SoftLanesClear(SoftLanes *c, SoftLaneLinks *x, int k) {
    /* Lane k (of a colour's last, part-filled lane) takes no impulse: it
     * joins the immovable slot 0 to itself, its rows far apart, and writes
     * nothing back (wa, wb). Its sides are given unit moments of inertia
     * and arms only so that the 2x2 matrix the kernels work out from them
     * is regular (k11 = k22 = 2, k12 = 0; slot 0's mass is 0). */
    int p;
    c->ia[k] = c->ib[k] = 0;
    c->wa[k] = c->wb[k] = 0;
    c->inner[k] = 1;
    x->src[k] = -1;
    x->dst[k] = 0;
    c->iA[k] = c->iB[k] = 1.0;
    c->nx[k] = 0.0; c->ny[k] = 1.0;
    c->friction[k] = c->surfaceT[k] = 0.0;
    c->k11[k] = 1.0;
    for (p = 0; p < 2; p++) {
        c->rAx[p][k] = 1.0;
        c->rBx[p][k] = p == 0 ? 1.0 : -1.0;
        c->rAy[p][k] = c->rBy[p][k] = 0.0;
        c->base[p][k] = SOFT_LANE_FAR;
        c->compliance[p][k] = c->preload[p][k] = 0.0;
        c->normalImpulse[p][k] = c->tangentImpulse[p][k] = 0.0;
        x->maxNormalImpulse[p][k] = 0.0;
        c->totalNormal[p][k] = c->totalTangent[p][k] = 0.0;
    }
}

#endif /* TAMIAS_SOFT_LANES_H */

/* -- the kernels, instantiated three times ------------------------------------ */

#if defined(__GNUC__) || defined(__clang__)
#define SOFT_HAVE_SIMD 1
/* Vector comparisons, selects and masks, for either vector width. */
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

/* Two doubles: SSE2 on x86-64, NEON on arm64 (the base instruction sets). */
typedef double SoftV2 __attribute__((vector_size(16)));
typedef long long SoftM2 __attribute__((vector_size(16)));
#define V SoftV2
#define M SoftM2
#define SOFT_KERNEL(name) name##_simd
#define LOOP_LANES(k) for (k = 0; k < SOFT_LANES; k += 2)
static inline SoftV2 soft_v2_load(const double *p, int k) { SoftV2 v; memcpy(&v, p + k, sizeof(v)); return v; }
static inline void soft_v2_store(double *p, int k, SoftV2 v) { memcpy(p + k, &v, sizeof(v)); }
static inline SoftV2 soft_v2_splat(double s) { SoftV2 v = {s, s}; return v; }
static inline SoftV2 soft_v2_gather(const SoftState *st, const int *idx, int k, size_t off) {
    SoftV2 v;
    v[0] = *(const double *)((const char *)&SOFT_AT(st, idx[k]) + off);
    v[1] = *(const double *)((const char *)&SOFT_AT(st, idx[k + 1]) + off);
    return v;
}
static inline void soft_v2_scatter(SoftState *st, const int *idx, const unsigned char *w, int k,
                                   size_t off, SoftV2 v) {
    if (w[k]) *(double *)((char *)&SOFT_AT(st, idx[k]) + off) = v[0];
    if (w[k + 1]) *(double *)((char *)&SOFT_AT(st, idx[k + 1]) + off) = v[1];
}
/* A body's state into the lanes and its velocity back as whole rows, moved
 * between rows and lanes by shuffles (a 2x2 transpose) rather than one
 * double at a time. Only data moves: the same bits as the above. */
#if defined(__clang__)
#define SOFT_SHUFFLE2(a, b, i, j) __builtin_shufflevector((a), (b), i, j)
#else
#define SOFT_SHUFFLE2(a, b, i, j) __builtin_shuffle((a), (b), (SoftM2){i, j})
#endif
static inline void soft_v2_gather_state(const SoftState *st, const int *idx, int k, int full,
                                        SoftV2 out[8]) {
    const double *a = &SOFT_AT(st, idx[k]).vx, *b = &SOFT_AT(st, idx[k + 1]).vx;
    SoftV2 a0, a1, b0, b1;
    memcpy(&a0, a, 16); memcpy(&a1, a + 2, 16);
    memcpy(&b0, b, 16); memcpy(&b1, b + 2, 16);
    out[0] = SOFT_SHUFFLE2(a0, b0, 0, 2);   /* vx */
    out[1] = SOFT_SHUFFLE2(a0, b0, 1, 3);   /* vy */
    out[2] = SOFT_SHUFFLE2(a1, b1, 0, 2);   /* w */
    out[3] = SOFT_SHUFFLE2(a1, b1, 1, 3);   /* m_inv */
    if (full) {
        memcpy(&a0, a + 4, 16); memcpy(&a1, a + 6, 16);
        memcpy(&b0, b + 4, 16); memcpy(&b1, b + 6, 16);
        out[4] = SOFT_SHUFFLE2(a0, b0, 0, 2);   /* dpx */
        out[5] = SOFT_SHUFFLE2(a0, b0, 1, 3);   /* dpy */
        out[6] = SOFT_SHUFFLE2(a1, b1, 0, 2);   /* qc */
        out[7] = SOFT_SHUFFLE2(a1, b1, 1, 3);   /* qs */
    }
}
static inline void soft_v2_scatter_velocity(SoftState *st, const int *idx, const unsigned char *w,
                                            int k, SoftV2 vx, SoftV2 vy, SoftV2 ww, SoftV2 m) {
    SoftV2 row;
    (void)m;    /* (the AVX2 path writes it back with the row) */
    if (w[k]) {
        row = SOFT_SHUFFLE2(vx, vy, 0, 2);
        memcpy(&SOFT_AT(st, idx[k]).vx, &row, 16);
        SOFT_AT(st, idx[k]).w = ww[0];
    }
    if (w[k + 1]) {
        row = SOFT_SHUFFLE2(vx, vy, 1, 3);
        memcpy(&SOFT_AT(st, idx[k + 1]).vx, &row, 16);
        SOFT_AT(st, idx[k + 1]).w = ww[1];
    }
}
#define soft_v_load soft_v2_load
#define soft_v_store soft_v2_store
#define soft_v_splat soft_v2_splat
#define soft_v_gather soft_v2_gather
#define soft_v_scatter soft_v2_scatter
#define soft_v_gather_state soft_v2_gather_state
#define soft_v_scatter_velocity soft_v2_scatter_velocity
#include "_soft_lanes_kernels.h"

/* Four doubles with AVX2, chosen at run time where the CPU has it (a wheel
 * cannot assume it). GCC only; other compilers keep the two-double path. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define SOFT_HAVE_AVX2 1
#pragma GCC push_options
#pragma GCC target("avx2")
typedef double SoftV4 __attribute__((vector_size(32)));
typedef long long SoftM4 __attribute__((vector_size(32)));
#define V SoftV4
#define M SoftM4
#define SOFT_KERNEL(name) name##_avx2
#define LOOP_LANES(k) for (k = 0; k < 1; k++)
static inline SoftV4 soft_v4_load(const double *p, int k) { SoftV4 v; (void)k; memcpy(&v, p, sizeof(v)); return v; }
static inline void soft_v4_store(double *p, int k, SoftV4 v) { (void)k; memcpy(p, &v, sizeof(v)); }
static inline SoftV4 soft_v4_splat(double s) { SoftV4 v = {s, s, s, s}; return v; }
static inline SoftV4 soft_v4_gather(const SoftState *st, const int *idx, int k, size_t off) {
    SoftV4 v;
    int j;
    (void)k;
    for (j = 0; j < 4; j++)
        v[j] = *(const double *)((const char *)&SOFT_AT(st, idx[j]) + off);
    return v;
}
static inline void soft_v4_scatter(SoftState *st, const int *idx, const unsigned char *w, int k,
                                   size_t off, SoftV4 v) {
    int j;
    (void)k;
    for (j = 0; j < 4; j++)
        if (w[j]) *(double *)((char *)&SOFT_AT(st, idx[j]) + off) = v[j];
}
/* As soft_v2_gather_state, four rows at a time (4x4 transposes). */
#define SOFT_SHUFFLE4(a, b, i, j, l, m) __builtin_shuffle((a), (b), (SoftM4){i, j, l, m})
#define SOFT_TRANSPOSE4(r0, r1, r2, r3, o0, o1, o2, o3) do { \
        SoftV4 t0_ = SOFT_SHUFFLE4(r0, r1, 0, 4, 2, 6), t1_ = SOFT_SHUFFLE4(r0, r1, 1, 5, 3, 7); \
        SoftV4 t2_ = SOFT_SHUFFLE4(r2, r3, 0, 4, 2, 6), t3_ = SOFT_SHUFFLE4(r2, r3, 1, 5, 3, 7); \
        o0 = SOFT_SHUFFLE4(t0_, t2_, 0, 1, 4, 5); o1 = SOFT_SHUFFLE4(t1_, t3_, 0, 1, 4, 5); \
        o2 = SOFT_SHUFFLE4(t0_, t2_, 2, 3, 6, 7); o3 = SOFT_SHUFFLE4(t1_, t3_, 2, 3, 6, 7); \
    } while (0)
static inline SoftV4 soft_v4_row(const SoftState *st, int i, int half) {    /* i: a byte offset */
    SoftV4 r;
    memcpy(&r, &SOFT_AT(st, i).vx + 4 * half, sizeof(r));
    return r;
}
static inline void soft_v4_gather_state(const SoftState *st, const int *idx, int k, int full,
                                        SoftV4 out[8]) {
    SoftV4 r0 = soft_v4_row(st, idx[0], 0), r1 = soft_v4_row(st, idx[1], 0);
    SoftV4 r2 = soft_v4_row(st, idx[2], 0), r3 = soft_v4_row(st, idx[3], 0);
    (void)k;
    SOFT_TRANSPOSE4(r0, r1, r2, r3, out[0], out[1], out[2], out[3]);   /* vx, vy, w, m_inv */
    if (full) {
        r0 = soft_v4_row(st, idx[0], 1); r1 = soft_v4_row(st, idx[1], 1);
        r2 = soft_v4_row(st, idx[2], 1); r3 = soft_v4_row(st, idx[3], 1);
        SOFT_TRANSPOSE4(r0, r1, r2, r3, out[4], out[5], out[6], out[7]);  /* dpx, dpy, qc, qs */
    }
}
/* The velocities back as whole rows (vx, vy, w and the m_inv gathered
 * with them, so the row's last place keeps its bits), one unconditional
 * aligned 32-byte store each (the states start on a cache line): a side
 * that is not written back (immovable, or an empty lane) stores into a
 * local row instead of being branched around. (With the branches the
 * compiler kept the four rows on the stack and reloaded each: ten
 * instructions a row.) */
static inline SoftV4 *soft_v4_row_out(SoftState *st, const int *idx, const unsigned char *w,
                                      int j, SoftV4 *sink) {
    return w[j] ? (SoftV4 *)__builtin_assume_aligned(&SOFT_AT(st, idx[j]).vx, 32) : sink;
}
static inline void soft_v4_scatter_velocity(SoftState *st, const int *idx, const unsigned char *w,
                                            int k, SoftV4 vx, SoftV4 vy, SoftV4 ww, SoftV4 m) {
    SoftV4 r0, r1, r2, r3, sink;
    unsigned int every;
    (void)k;
    SOFT_TRANSPOSE4(vx, vy, ww, m, r0, r1, r2, r3);   /* row j: vx, vy, w, m_inv */
    memcpy(&every, w, sizeof(every));
    if (every == 0x01010101u) {
        /* All four sides written back, most lanes of a pile: no selects. */
        *(SoftV4 *)__builtin_assume_aligned(&SOFT_AT(st, idx[0]).vx, 32) = r0;
        *(SoftV4 *)__builtin_assume_aligned(&SOFT_AT(st, idx[1]).vx, 32) = r1;
        *(SoftV4 *)__builtin_assume_aligned(&SOFT_AT(st, idx[2]).vx, 32) = r2;
        *(SoftV4 *)__builtin_assume_aligned(&SOFT_AT(st, idx[3]).vx, 32) = r3;
        return;
    }
    *soft_v4_row_out(st, idx, w, 0, &sink) = r0;
    *soft_v4_row_out(st, idx, w, 1, &sink) = r1;
    *soft_v4_row_out(st, idx, w, 2, &sink) = r2;
    *soft_v4_row_out(st, idx, w, 3, &sink) = r3;
}
#define soft_v_load soft_v4_load
#define soft_v_store soft_v4_store
#define soft_v_splat soft_v4_splat
#define soft_v_gather soft_v4_gather
#define soft_v_scatter soft_v4_scatter
#define soft_v_gather_state soft_v4_gather_state
#define soft_v_scatter_velocity soft_v4_scatter_velocity
#include "_soft_lanes_kernels.h"
#pragma GCC pop_options
#else
#define SOFT_HAVE_AVX2 0
#endif

#undef V_SEL
#undef V_GT
#undef V_GE
#undef V_LT
#undef V_AND
#undef V_OR
#undef V_ANDNOT
#undef V_NOT
#undef V_PICK3
#else
#define SOFT_HAVE_SIMD 0
#define SOFT_HAVE_AVX2 0
#endif

/* One double, lane by lane: what a compiler without vector extensions
 * builds, and the check of the others. */
#define V double
#define M int
#define SOFT_KERNEL(name) name##_scalar
#define LOOP_LANES(k) for (k = 0; k < SOFT_LANES; k++)
static inline double soft_s_load(const double *p, int k) { return p[k]; }
static inline void soft_s_store(double *p, int k, double v) { p[k] = v; }
static inline double soft_s_splat(double s) { return s; }
static inline double soft_s_gather(const SoftState *st, const int *idx, int k, size_t off) {
    return *(const double *)((const char *)&SOFT_AT(st, idx[k]) + off);
}
static inline void soft_s_scatter(SoftState *st, const int *idx, const unsigned char *w, int k,
                                  size_t off, double v) {
    if (w[k]) *(double *)((char *)&SOFT_AT(st, idx[k]) + off) = v;
}
static inline void soft_s_gather_state(const SoftState *st, const int *idx, int k, int full,
                                       double out[8]) {
    const SoftState *b = &SOFT_AT(st, idx[k]);
    out[0] = b->vx; out[1] = b->vy; out[2] = b->w; out[3] = b->m_inv;
    if (full) {
        out[4] = b->dpx; out[5] = b->dpy; out[6] = b->qc; out[7] = b->qs;
    }
}
static inline void soft_s_scatter_velocity(SoftState *st, const int *idx, const unsigned char *w,
                                           int k, double vx, double vy, double ww, double m) {
    (void)m;
    if (w[k]) {
        SOFT_AT(st, idx[k]).vx = vx; SOFT_AT(st, idx[k]).vy = vy; SOFT_AT(st, idx[k]).w = ww;
    }
}
#define soft_v_load soft_s_load
#define soft_v_store soft_s_store
#define soft_v_splat soft_s_splat
#define soft_v_gather soft_s_gather
#define soft_v_scatter soft_s_scatter
#define soft_v_gather_state soft_s_gather_state
#define soft_v_scatter_velocity soft_s_scatter_velocity
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
#undef V_SEL
#undef V_GT
#undef V_GE
#undef V_LT
#undef V_AND
#undef V_OR
#undef V_ANDNOT
#undef V_NOT
#undef V_PICK3

/* The path the solver takes (SOFT_PATH_*): the widest this build and this
 * CPU have, chosen once at import (SoftLanesInit); a test switch sets
 * another. All three give the same bits. */
enum { SOFT_PATH_SCALAR = 0, SOFT_PATH_SIMD = 1, SOFT_PATH_AVX2 = 2 };
static int soft_lanes_path = SOFT_PATH_SCALAR;

static inline int SoftLanesPathAvailable(int path) {
    if (path == SOFT_PATH_SCALAR)
        return 1;
    if (path == SOFT_PATH_SIMD)
        return SOFT_HAVE_SIMD;
#if SOFT_HAVE_AVX2
    if (path == SOFT_PATH_AVX2) {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") ? 1 : 0;
    }
#endif
    return 0;
}

static inline void SoftLanesInit(void) {
    soft_lanes_path = SoftLanesPathAvailable(SOFT_PATH_AVX2) ? SOFT_PATH_AVX2
                    : SoftLanesPathAvailable(SOFT_PATH_SIMD) ? SOFT_PATH_SIMD : SOFT_PATH_SCALAR;
}

static inline int SoftLanesGetPath(void) { return soft_lanes_path; }

static inline int SoftLanesSetPath(int path) {
    if (!SoftLanesPathAvailable(path))
        return 0;
    soft_lanes_path = path;
    return 1;
}

/* The kernels over n lanes from c. */
static inline void SoftLanesWarmStart(SoftLanes *c, int n, SoftState *st, int fetch) {
#if SOFT_HAVE_AVX2
    if (soft_lanes_path == SOFT_PATH_AVX2) { soft_warm_start_range_avx2(c, n, st, fetch); return; }
#endif
#if SOFT_HAVE_SIMD
    if (soft_lanes_path == SOFT_PATH_SIMD) { soft_warm_start_range_simd(c, n, st, fetch); return; }
#endif
    soft_warm_start_range_scalar(c, n, st, fetch);
}

/* accumulate (relax passes only): add the lane's impulses to its step
 * totals after solving it, as the substep's last pass does; trackMax: keep
 * the points' largest normal impulses (for restitution); fetch: fetch the
 * bodies' states SOFT_FETCH_AHEAD lanes ahead (a pile too big for the
 * cache); skipInner: leave out the inner contacts (a relax pass that only
 * the others take: whole lanes, or soft_lane_hold_inner). */
static inline void SoftLanesSolve(SoftLanes *c, SoftLaneLinks *x, int n, SoftState *st,
                                  const SoftLaneBiasRates *rates,
                                  double inv_h, double pushOut, int useBias, int accumulate,
                                  int trackMax, int fetch, int skipInner) {
#if SOFT_HAVE_AVX2
    if (soft_lanes_path == SOFT_PATH_AVX2) {
        soft_solve_range_avx2(c, x, n, st, rates, inv_h, pushOut, useBias, accumulate, trackMax, fetch, skipInner);
        return;
    }
#endif
#if SOFT_HAVE_SIMD
    if (soft_lanes_path == SOFT_PATH_SIMD) {
        soft_solve_range_simd(c, x, n, st, rates, inv_h, pushOut, useBias, accumulate, trackMax, fetch, skipInner);
        return;
    }
#endif
    soft_solve_range_scalar(c, x, n, st, rates, inv_h, pushOut, useBias, accumulate, trackMax, fetch, skipInner);
}

