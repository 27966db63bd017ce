/*
 * test_derivatives_model.h - the hand-written model of test_derivatives.c
 * and test_derivatives_casadi.c (the equations: test_derivatives.c's
 * comment), its analytic kernels for the runtime's gen_rt_deriv_model
 * (MODELS[mv], mv = 0: without the velocity constraint, 1: with it), the
 * outputs and the constraint, and the helpers both tests share.
 */
#ifndef TEST_DERIVATIVES_MODEL_H
#define TEST_DERIVATIVES_MODEL_H

#include "test_common.h"

#include "gen_rt_casadi.h"
#include "gen_rt_deriv.h"

#define NX 4
#define NR 1
#define NP 2
#define NZ (NX + NR + NP + 1)
#define NV (NZ + 1)
#define NWMAX (NX + 1)
#define NY 2
#define EPS TOL(1e-6, 1e-2)        /* central differences */
#define FTOL TOL(1e-6, 3e-2)       /* their agreement, relative to max(1, |ref|) */

typedef gen_rt_real real;

/* ---------------------------------------------------------------- model */
static inline void r0_impl(int mv, const real *z, real *Rw, real *R0)
{
    const real q1 = z[0], q2 = z[1], u1 = z[2], u2 = z[3], r1 = z[4], p1 = z[5], p2 = z[6],
               t = z[7];
    const int nw = NX + mv;
    int i;
    for (i = 0; i < nw * nw; ++i) Rw[i] = 0;
    Rw[0 * nw + 0] = 1 + q2 * q2; Rw[0 * nw + 1] = GEN_RT_C(0.3);
    Rw[1 * nw + 1] = 2 + (real)sin(q1);
    Rw[2 * nw + 2] = 2 + (real)cos(q2); Rw[2 * nw + 3] = GEN_RT_C(0.5);
    Rw[3 * nw + 2] = GEN_RT_C(0.5); Rw[3 * nw + 3] = 1 + p2;
    if (mv) {
        Rw[2 * nw + 4] = -q1; Rw[3 * nw + 4] = -q2;
        Rw[4 * nw + 0] = u1; Rw[4 * nw + 1] = u2; Rw[4 * nw + 2] = q1; Rw[4 * nw + 3] = q2;
        R0[4] = 0;
    }
    R0[0] = -u1;
    R0[1] = -u2;
    R0[2] = -(-p1 * (real)sin(q1) - GEN_RT_C(0.3) * u1 + 2 * (real)sin(5 * t) + r1);
    R0[3] = -(-4 * q2 - GEN_RT_C(0.3) * u2 + u1 * u1 * (real)sin(q2));
}

static inline void rz_impl(int mv, const real *z, const real *w, real *Rz)
{
    const real q1 = z[0], q2 = z[1], u1 = z[2], p1 = z[5], t = z[7];
    const real a1 = w[0], a2 = w[1], b1 = w[2], b2 = w[3], lam = mv ? w[4] : 0;
    int i;
    for (i = 0; i < (NX + mv) * NZ; ++i) Rz[i] = 0;
    Rz[0 * NZ + 1] = 2 * q2 * a1; Rz[0 * NZ + 2] = -1;
    Rz[1 * NZ + 0] = (real)cos(q1) * a2; Rz[1 * NZ + 3] = -1;
    Rz[2 * NZ + 1] = -(real)sin(q2) * b1; Rz[2 * NZ + 0] = p1 * (real)cos(q1) - lam;
    Rz[2 * NZ + 2] = GEN_RT_C(0.3); Rz[2 * NZ + 4] = -1; Rz[2 * NZ + 5] = (real)sin(q1);
    Rz[2 * NZ + 7] = -10 * (real)cos(5 * t);
    Rz[3 * NZ + 6] = b2; Rz[3 * NZ + 1] = 4 - u1 * u1 * (real)cos(q2) - lam;
    Rz[3 * NZ + 3] = GEN_RT_C(0.3); Rz[3 * NZ + 2] = -2 * u1 * (real)sin(q2);
    if (mv) {
        Rz[4 * NZ + 0] = b1; Rz[4 * NZ + 1] = b2; Rz[4 * NZ + 2] = a1; Rz[4 * NZ + 3] = a2;
    }
}

static inline void hset(real *H, int a, int b, real v)
{
    H[a * NZ + b] += v;
    if (a != b) H[b * NZ + a] += v;
}

static inline void rh_impl(int mv, const real *z, const real *w, const real *mu, real *H, real *W)
{
    const real q1 = z[0], q2 = z[1], u1 = z[2], p1 = z[5], t = z[7];
    const real a1 = w[0], a2 = w[1], b1 = w[2];
    const real m5 = mv ? mu[4] : 0;
    int i;
    for (i = 0; i < NZ * NZ; ++i) H[i] = 0;
    for (i = 0; i < (NX + mv) * NZ; ++i) W[i] = 0;
    hset(H, 1, 1, 2 * a1 * mu[0]);
    hset(H, 0, 0, -(real)sin(q1) * a2 * mu[1]);
    hset(H, 1, 1, -(real)cos(q2) * b1 * mu[2]);
    hset(H, 0, 0, -p1 * (real)sin(q1) * mu[2]);
    hset(H, 0, 5, (real)cos(q1) * mu[2]);
    hset(H, 7, 7, 50 * (real)sin(5 * t) * mu[2]);
    hset(H, 1, 1, u1 * u1 * (real)sin(q2) * mu[3]);
    hset(H, 2, 2, -2 * (real)sin(q2) * mu[3]);
    hset(H, 2, 1, -2 * u1 * (real)cos(q2) * mu[3]);
    W[0 * NZ + 1] = 2 * q2 * mu[0]; W[0 * NZ + 2] = m5;
    W[1 * NZ + 0] = (real)cos(q1) * mu[1]; W[1 * NZ + 3] = m5;
    W[2 * NZ + 1] = -(real)sin(q2) * mu[2]; W[2 * NZ + 0] = m5;
    W[3 * NZ + 6] = mu[3]; W[3 * NZ + 1] = m5;
    if (mv) { W[4 * NZ + 0] = -mu[2]; W[4 * NZ + 1] = -mu[3]; }
}

static inline void r0_a(const real *z, real *Rw, real *R0) { r0_impl(0, z, Rw, R0); }
static inline void r0_b(const real *z, real *Rw, real *R0) { r0_impl(1, z, Rw, R0); }
static inline void rz_a(const real *z, const real *w, real *Rz) { rz_impl(0, z, w, Rz); }
static inline void rz_b(const real *z, const real *w, real *Rz) { rz_impl(1, z, w, Rz); }
static inline void rh_a(const real *z, const real *w, const real *mu, real *H, real *W)
{
    rh_impl(0, z, w, mu, H, W);
}
static inline void rh_b(const real *z, const real *w, const real *mu, real *H, real *W)
{
    rh_impl(1, z, w, mu, H, W);
}

static const gen_rt_deriv_model MODELS[2] = {{NX, NZ, NX, r0_a, rz_a, rh_a},
                                             {NX, NZ, NX + 1, r0_b, rz_b, rh_b}};

/* the outputs and the constraint, explicit in z */
static inline void y1(const real *z, real *J)
{
    int i;
    for (i = 0; i < NY * NZ; ++i) J[i] = 0;
    J[0] = z[3]; J[3] = z[0]; J[7] = (real)cos(z[7]);
    J[NZ + 5] = z[4] * z[1]; J[NZ + 4] = z[5] * z[1]; J[NZ + 1] = z[5] * z[4];
}
static inline void yh(const real *z, const real *mu, real *H)
{
    int i;
    for (i = 0; i < NZ * NZ; ++i) H[i] = 0;
    hset(H, 0, 3, mu[0]); hset(H, 7, 7, -(real)sin(z[7]) * mu[0]);
    hset(H, 5, 4, z[1] * mu[1]); hset(H, 5, 1, z[4] * mu[1]); hset(H, 4, 1, z[5] * mu[1]);
}
static inline void c1(const real *z, real *J)
{
    int i;
    for (i = 0; i < NZ; ++i) J[i] = 0;
    J[0] = z[2]; J[1] = z[3]; J[2] = z[0]; J[3] = z[1];
}
static inline void ch(const real *z, const real *mu, real *H)
{
    int i;
    (void)z;
    for (i = 0; i < NZ * NZ; ++i) H[i] = 0;
    hset(H, 0, 2, mu[0]); hset(H, 1, 3, mu[0]);
}

/* --------------------------------------------------------------- helpers */
static real WORK[GEN_RT_CS_WORK(NX, NR, NP, 0, 1, NY) + 16];
static int IWORK[GEN_RT_CS_IWORK(NX, NR, NP, 1) + 4];

static inline void zof(const real *x, const real *r, const real *p, real t, real *z)
{
    int i;
    for (i = 0; i < NX; ++i) z[i] = x[i];
    z[NX] = r[0]; z[NX + 1] = p[0]; z[NX + 2] = p[1]; z[NZ - 1] = t;
}

static const real Z0[NZ] = {GEN_RT_C(0.4), GEN_RT_C(-0.7), GEN_RT_C(0.9), GEN_RT_C(-0.3),
                            GEN_RT_C(0.6), GEN_RT_C(3.0), GEN_RT_C(0.8), GEN_RT_C(0.35)};

static inline double scale_of(double ref) { return fabs(ref) > 1 ? fabs(ref) : 1; }

#define CHECK_FD(got, ref) CHECK_NEAR(got, ref, FTOL * scale_of(ref))

/* the right-hand side as the runtime's callback: x' = w[0..nx) at (x, r, p, t) */
typedef struct { const gen_rt_deriv_model *m; const real *r, *p; } fctx;
static inline int frhs(void *ctx, real t, const real *x, real *dxdt)
{
    const fctx *c = (const fctx *)ctx;
    real z[NZ], w[NWMAX], lu[NWMAX * NWMAX], sw[NWMAX];
    int piv[NWMAX], i, st;
    zof(x, c->r, c->p, t, z);
    if ((st = gen_rt_deriv_solve(c->m, z, sw, w, lu, piv, 0))) return st;
    for (i = 0; i < NX; ++i) dxdt[i] = w[i];
    return 0;
}

static inline void solve_at(const gen_rt_deriv_model *m, const real *z, real *w, real *Jw)
{
    real lu[NWMAX * NWMAX], sw[NWMAX];
    int piv[NWMAX];
    CHECK_INT(gen_rt_deriv_solve(m, z, sw, w, lu, piv, Jw), 0);
}

/* x+ of the runtime's RK4 at v = (z, h) */
static inline void rk4_value(const gen_rt_deriv_model *m, const real *v, real *xn)
{
    real rk[GEN_RT_RK4_WORK(NX)];
    fctx c;
    int i;
    c.m = m; c.r = v + NX; c.p = v + NX + NR;
    for (i = 0; i < NX; ++i) xn[i] = v[i];
    CHECK_INT(gen_rt_rk4_step(frhs, &c, NX, v[NZ - 1], v[NZ], rk, xn), 0);
}

static inline void rodas4_value(const gen_rt_deriv_model *m, const real *v, real *xn)
{
    real w[NWMAX], Jw[NWMAX * NZ], Jx[NX * NX], dfdt[NX], rw[GEN_RT_RODAS4_WORK(NX)], err;
    int rpiv[NX], i, j;
    fctx c;
    c.m = m; c.r = v + NX; c.p = v + NX + NR;
    solve_at(m, v, w, Jw);
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) Jx[i * NX + j] = Jw[i * NZ + j];
        dfdt[i] = Jw[i * NZ + NZ - 1];
    }
    CHECK_INT(gen_rt_rodas4_trial(frhs, &c, NX, v[NZ - 1], v[NZ], v, w, Jx, dfdt, 1, 1, rw, rpiv,
                                  xn, &err), 0);
}

#endif /* TEST_DERIVATIVES_MODEL_H */
