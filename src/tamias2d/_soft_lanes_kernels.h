/* The contact kernels of the soft solver over SoftLanes, written once over
 * the lane type V (mask type M). Included by _soft_lanes.h, which
 * defines V, M, SOFT_KERNEL, LOOP_LANES, the soft_v_* accessors (undefined
 * again at the end of this file) and the V_* comparisons and selects; no
 * include guard on purpose. Included three times (see there).
 *
 * Same arithmetic as SoftSolve in _soft_step.pyx (the scalar solver of the
 * contacts that are not packed into lanes); see there for the why. */

#define L(field) soft_v_load((field), k)
#define S(field, value) soft_v_store((field), k, (value))
#define G(idx, member) soft_v_gather(st, (idx), k, offsetof(SoftState, member))
#define P(idx, w, member, value) soft_v_scatter(st, (idx), (w), k, offsetof(SoftState, member), (value))
/* The arms' cross products with the normal and the tangent, worked out from
 * the anchors as the contacts' preparation does (the same expressions, so
 * the same bits) rather than stored: a quarter fewer bytes per lane. */
#define RN(rx, ry) ((rx) * ny - (ry) * nx)
#define RT(rx, ry) ((rx) * nx + (ry) * ny)
/* A two-point lane's 2x2 normal mass matrix is worked out from the arms as
 * SoftPrepareBlock does (the same expressions, so the same bits) rather
 * than stored: KJJ(j) is its diagonal entry j (k12 is written out where it
 * is used). */
#define KJJ(j) ((mA + mB) + iA * rnA[j] * rnA[j] + iB * rnB[j] * rnB[j])

static SOFT_ALWAYS_INLINE void SOFT_KERNEL(soft_warm_start)(SoftLanes *c, SoftState *st) {
    int k, j;
    LOOP_LANES(k) {
        V iA = L(c->iA), iB = L(c->iB);
        V nx = L(c->nx), ny = L(c->ny);
        V sA[8], sB[8];
        soft_v_gather_state(st, c->ia, k, 0, sA);
        soft_v_gather_state(st, c->ib, k, 0, sB);
        V mA = sA[3], mB = sB[3];
        V vax = sA[0], vay = sA[1], wa = sA[2];
        V vbx = sB[0], vby = sB[1], wb = sB[2];
        for (j = 0; j < c->points; j++) {
            /* P = normalImpulse n + tangentImpulse perp(n) */
            V xn = L(c->normalImpulse[j]), xt = L(c->tangentImpulse[j]);
            V px = xn * nx - xt * ny;
            V py = xn * ny + xt * nx;
            vax = vax - mA * px;
            vay = vay - mA * py;
            V rAx = L(c->rAx[j]), rAy = L(c->rAy[j]), rBx = L(c->rBx[j]), rBy = L(c->rBy[j]);
            wa = wa - iA * (xn * RN(rAx, rAy) + xt * RT(rAx, rAy));
            vbx = vbx + mB * px;
            vby = vby + mB * py;
            wb = wb + iB * (xn * RN(rBx, rBy) + xt * RT(rBx, rBy));
        }
        soft_v_scatter_velocity(st, c->ia, c->wa, k, vax, vay, wa, mA);
        soft_v_scatter_velocity(st, c->ib, c->wb, k, vbx, vby, wb, mB);
    }
}

/* trackMax: keep each point's largest normal impulse of the step (only
 * restitution reads it, so a step without elastic contacts skips it). */
static SOFT_ALWAYS_INLINE void SOFT_KERNEL(soft_solve)(SoftLanes *c, SoftLaneLinks *x,
                                                       SoftState *st,
                                                       const SoftLaneBiasRates *rates,
                                                       double inv_h_s,
                                                       double pushOut_s, int useBias, int accumulate,
                                                       int trackMax) {
    int k, j;
    V zero = soft_v_splat(0.0), one = soft_v_splat(1.0);
    V inv_h = soft_v_splat(inv_h_s), negPush = soft_v_splat(-pushOut_s);
    LOOP_LANES(k) {
        V iA = L(c->iA), iB = L(c->iB);
        V nx = L(c->nx), ny = L(c->ny);
        V sA[8], sB[8];
        soft_v_gather_state(st, c->ia, k, 1, sA);
        soft_v_gather_state(st, c->ib, k, 1, sB);
        V mA = sA[3], mB = sB[3];
        V vax = sA[0], vay = sA[1], wa = sA[2];
        V vbx = sB[0], vby = sB[1], wb = sB[2];
        V qcA = sA[6], qsA = sA[7], qcB = sB[6], qsB = sB[7];
        V ddx = sB[4] - sA[4], ddy = sB[5] - sA[5];
        V bias[2], gamma[2], held[2];
        V arm[2][4];                        /* rAx, rAy, rBx, rBy of each point */
        V rnA[2], rnB[2];
        V lin, x01, x02, k11, k12, k22, a11, a22, q1, q2, det, x1, x2, y1, z2, n1, n2, d1, d2, imp;
        M ok1, ok2, ok3, ok4;
        int points = c->points;
        V biasRate = zero;
        if (useBias)
            biasRate = L(rates->rate[soft_lane_rate_index(c)]);
        for (j = 0; j < 2; j++) {
            if (j == 1 && points == 1)
                break;
            /* The current separation from the bodies' motion in this step. */
            V rAx = L(c->rAx[j]), rAy = L(c->rAy[j]), rBx = L(c->rBx[j]), rBy = L(c->rBy[j]);
            V prAx = qcA * rAx - qsA * rAy, prAy = qsA * rAx + qcA * rAy;
            arm[j][0] = rAx; arm[j][1] = rAy; arm[j][2] = rBx; arm[j][3] = rBy;
            rnA[j] = RN(rAx, rAy);
            rnB[j] = RN(rBx, rBy);
            V prBx = qcB * rBx - qsB * rBy, prBy = qsB * rBx + qcB * rBy;
            V s = (ddx + (prBx - prAx)) * nx + (ddy + (prBy - prAy)) * ny + L(c->base[j]);
            M spec = V_GT(s, zero);
            if (useBias) {
                /* The part of the warm start the preload holds at no depth;
                 * the push-out cap applies beyond what holds the rest. */
                V x0 = L(c->normalImpulse[j]), pre = L(c->preload[j]);
                V g = L(c->compliance[j]);
                V b = biasRate * s;
                V lim;
                held[j] = V_SEL(V_LT(x0, pre), x0, pre);
                lim = negPush - (points == 2 ? KJJ(j) : L(c->k11)) * g * (x0 - held[j]);
                b = V_SEL(V_LT(b, lim), lim, b);
                bias[j] = V_SEL(spec, s * inv_h, b);
                gamma[j] = V_SEL(spec, zero, g);
            } else {
                bias[j] = V_SEL(spec, s * inv_h, zero);
                gamma[j] = zero;
                held[j] = zero;
            }
        }
        lin = (vbx - vax) * nx + (vby - vay) * ny;
        if (points == 1) {
            /* One row: (k + k gamma) dx = -(vn + bias) - k gamma (x0 - held), x >= 0. */
            V m1;
            x01 = L(c->normalImpulse[0]);
            k11 = L(c->k11);
            q1 = lin + wb * rnB[0] - wa * rnA[0] + bias[0];
            n1 = x01 - (q1 + k11 * gamma[0] * (x01 - held[0])) / (k11 * (one + gamma[0]));
            n1 = V_SEL(V_LT(n1, zero), zero, n1);
            S(c->normalImpulse[0], n1);
            if (trackMax) {
                m1 = L(x->maxNormalImpulse[0]);
                S(x->maxNormalImpulse[0], V_SEL(V_GT(n1, m1), n1, m1));
            }
            d1 = n1 - x01;
            vax = vax - mA * (d1 * nx);
            vay = vay - mA * (d1 * ny);
            wa = wa - iA * (rnA[0] * d1);
            vbx = vbx + mB * (d1 * nx);
            vby = vby + mB * (d1 * ny);
            wb = wb + iB * (rnB[0] * d1);
            goto friction;
        }
        /* Both normal rows at once (the 2x2 LCP, Box2D 2.x's cases). */
        x01 = L(c->normalImpulse[0]);
        x02 = L(c->normalImpulse[1]);
        k11 = KJJ(0);
        k22 = KJJ(1);
        k12 = (mA + mB) + iA * rnA[0] * rnA[1] + iB * rnB[0] * rnB[1];
        a11 = k11 * (one + gamma[0]);
        a22 = k22 * (one + gamma[1]);
        q1 = lin + wb * rnB[0] - wa * rnA[0] + bias[0] - (k11 * x01 + k12 * x02) - k11 * gamma[0] * held[0];
        q2 = lin + wb * rnB[1] - wa * rnA[1] + bias[1] - (k12 * x01 + k22 * x02) - k22 * gamma[1] * held[1];
        det = a11 * a22 - k12 * k12;
        x1 = (k12 * q2 - a22 * q1) / det;
        x2 = (k12 * q1 - a11 * q2) / det;
        ok1 = V_AND(V_GE(x1, zero), V_GE(x2, zero));
        y1 = -(q1 / a11);                                   /* only the first pushes */
        ok2 = V_AND(V_GE(y1, zero), V_GE(k12 * y1 + q2, zero));
        z2 = -(q2 / a22);                                   /* only the second */
        ok3 = V_AND(V_GE(z2, zero), V_GE(k12 * z2 + q1, zero));
        ok4 = V_AND(V_GE(q1, zero), V_GE(q2, zero));        /* neither */
        /* The first case that holds; with none (round-off) the impulses stay. */
        ok2 = V_ANDNOT(ok1, ok2);
        ok3 = V_ANDNOT(V_OR(ok1, ok2), ok3);
        ok4 = V_NOT(V_OR(V_OR(ok1, ok2), V_OR(ok3, ok4)));
        n1 = V_PICK3(ok1, x1, ok2, y1, ok4, x01);
        n2 = V_PICK3(ok1, x2, ok3, z2, ok4, x02);
        d1 = n1 - x01;
        d2 = n2 - x02;
        S(c->normalImpulse[0], n1);
        S(c->normalImpulse[1], n2);
        if (trackMax) {
            V m1 = L(x->maxNormalImpulse[0]), m2 = L(x->maxNormalImpulse[1]);
            S(x->maxNormalImpulse[0], V_SEL(V_GT(n1, m1), n1, m1));
            S(x->maxNormalImpulse[1], V_SEL(V_GT(n2, m2), n2, m2));
        }
        imp = d1 + d2;
        vax = vax - mA * (imp * nx);
        vay = vay - mA * (imp * ny);
        wa = wa - iA * (rnA[0] * d1 + rnA[1] * d2);
        vbx = vbx + mB * (imp * nx);
        vby = vby + mB * (imp * ny);
        wb = wb + iB * (rnB[0] * d1 + rnB[1] * d2);
    friction:
        if (!useBias) {
            /* Friction in the relax pass only; tangent t = perp(n). */
            V mu = L(c->friction), surfaceT = L(c->surfaceT);
            for (j = 0; j < 2; j++) {
                V rtA, rtB;
                if (j == 1 && points == 1)
                    break;
                rtA = RT(arm[j][0], arm[j][1]);
                rtB = RT(arm[j][2], arm[j][3]);
                V vt = ((vby - vay) * nx - (vbx - vax) * ny) + wb * rtB - wa * rtA + surfaceT;
                V old = L(c->tangentImpulse[j]);
                V maxF = mu * L(c->normalImpulse[j]);
                V negMaxF = -maxF;
                /* The tangent mass as SoftPrepareContact works it out (the
                 * same expression, so the same bits; 0 for an empty lane). */
                V kT = (mA + mB) + iA * rtA * rtA + iB * rtB * rtB;
                V tangentMass = V_SEL(V_GT(kT, zero), one / kT, zero);
                V tImp = old - tangentMass * vt;
                tImp = V_SEL(V_LT(tImp, negMaxF), negMaxF, V_SEL(V_GT(tImp, maxF), maxF, tImp));
                S(c->tangentImpulse[j], tImp);
                imp = tImp - old;
                vax = vax + mA * (imp * ny);
                vay = vay - mA * (imp * nx);
                wa = wa - iA * (imp * rtA);
                vbx = vbx - mB * (imp * ny);
                vby = vby + mB * (imp * nx);
                wb = wb + iB * (imp * rtB);
            }
            if (accumulate) {
                for (j = 0; j < points; j++) {
                    S(c->totalNormal[j], L(c->totalNormal[j]) + L(c->normalImpulse[j]));
                    S(c->totalTangent[j], L(c->totalTangent[j]) + L(c->tangentImpulse[j]));
                }
            }
        }
        soft_v_scatter_velocity(st, c->ia, c->wa, k, vax, vay, wa, mA);
        soft_v_scatter_velocity(st, c->ib, c->wb, k, vbx, vby, wb, mB);
    }
}

/* The kernels over a range of lanes, each case of the flags its own loop
 * (the flags are constants inside, so the compiler drops what a pass does
 * not do; the arithmetic that stays is the same, so are the bits). */
static void SOFT_KERNEL(soft_warm_start_range)(SoftLanes *c, int n, SoftState *st, int fetch) {
    int i;
    for (i = 0; i < n; i++) {
        if (fetch && i + SOFT_FETCH_AHEAD < n) {
            soft_fetch_states(&c[i + SOFT_FETCH_AHEAD], st);
            soft_fetch_lane_for_warm_start(&c[i + 2]);
        }
        SOFT_KERNEL(soft_warm_start)(&c[i], st);
    }
}

#define SOFT_SOLVE_LOOP(bias, acc, track) do { \
        for (i = 0; i < n; i++) { \
            if (fetch && i + SOFT_FETCH_AHEAD < n \
                    && !(skipInner && soft_lane_inner(&c[i + SOFT_FETCH_AHEAD]) == SOFT_LANES)) \
                soft_fetch_states(&c[i + SOFT_FETCH_AHEAD], st); \
            inner = skipInner ? soft_lane_inner(&c[i]) : 0; \
            if (inner == SOFT_LANES) \
                continue; \
            if (inner) \
                soft_lane_hold_inner(&c[i], &x[i], &held); \
            SOFT_KERNEL(soft_solve)(&c[i], &x[i], st, rates, inv_h, pushOut, (bias), (acc), (track)); \
            if (inner) \
                soft_lane_release_inner(&c[i], &x[i], &held); \
        } \
    } while (0)

static void SOFT_KERNEL(soft_solve_range)(SoftLanes *c, SoftLaneLinks *x, int n, SoftState *st,
                                          const SoftLaneBiasRates *rates, double inv_h,
                                          double pushOut, int useBias, int accumulate,
                                          int trackMax, int fetch, int skipInner) {
    int i, inner;
    SoftInnerHeld held;
    if (useBias) {
        if (trackMax) SOFT_SOLVE_LOOP(1, 0, 1); else SOFT_SOLVE_LOOP(1, 0, 0);
    } else if (accumulate) {
        if (trackMax) SOFT_SOLVE_LOOP(0, 1, 1); else SOFT_SOLVE_LOOP(0, 1, 0);
    } else {
        if (trackMax) SOFT_SOLVE_LOOP(0, 0, 1); else SOFT_SOLVE_LOOP(0, 0, 0);
    }
}
#undef SOFT_SOLVE_LOOP

#undef L
#undef S
#undef G
#undef P
#undef RN
#undef RT
#undef KJJ

/* The instantiation's type and accessor macros, for the next one (the V_*
 * operations are _soft_lanes.h's to undefine). */
#undef V
#undef M
#undef SOFT_KERNEL
#undef LOOP_LANES
#undef soft_v_load
#undef soft_v_store
#undef soft_v_splat
#undef soft_v_gather
#undef soft_v_scatter
#undef soft_v_gather_state
#undef soft_v_scatter_velocity
