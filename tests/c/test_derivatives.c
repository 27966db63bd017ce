/*
 * test_derivatives.c - csrc/derivatives (gen_rt_deriv_extern.c, gen_rt_casadi_extern.c)
 * and gen_rt_lu_solve_t, on a hand-written model with analytic kernels:
 *
 *   z = (q1, q2, u1, u2, r1, p1, p2, t), w = (q1', q2', u1', u2'[, lam])
 *   R1 = (1 + q2^2) q1' + 0.3 q2' - u1
 *   R2 = (2 + sin q1) q2' - u2
 *   R3 = (2 + cos q2) u1' + 0.5 u2' - f1 - q1 lam
 *   R4 = 0.5 u1' + (1 + p2) u2' - f2 - q2 lam
 *   R5 = q1 u1' + q2 u2' + q1' u1 + q2' u2           (MV = 1 only)
 *   f1 = -p1 sin q1 - 0.3 u1 + 2 sin 5t + r1,  f2 = -4 q2 - 0.3 u2 + u1^2 sin q2
 *   outputs y = (q1 u2 + sin t, p1 r1 q2); constraint (MV = 1) c = q1 u1 + q2 u2
 *
 * (implicit kinematics, a q- and p-dependent mass matrix, a velocity
 * constraint with its multiplier, t, r and p in f: every block of the
 * derivatives is nonzero). Checked against central differences (all in
 * the model's own arithmetic):
 *   (a) the kernels: Rz, H and W against differences of R and Rz;
 *   (b) gen_rt_lu_solve_t: a^T x = b for random a (pivoting), 1 and 3 rhs;
 *   (c) gen_rt_deriv_solve: R(z, w) = 0, dw/dz; gen_rt_deriv_hessian:
 *       symmetric, against differences of lam^T dw/dz and second
 *       differences of lam^T w;
 *   (d) gen_rt_deriv_rk4: x+ bit for bit gen_rt_rk4_step's, J against
 *       differences of x+ over v = (z, h), T against differences of J, Hl
 *       (adjoint sweep) against sum lam_i T_i;
 *   (e) gen_rt_deriv_rodas4: J against differences of gen_rt_rodas4_trial
 *       (Jf and df/dt from dw/dz) over v;
 *   (f) gen_rt_cs_eval: every mode of every function (values through the
 *       API stand-ins; JAC against differences of the value over every
 *       input, FWD/ADJ against J, JAC_JAC/JAC_FWD/JAC_ADJ against
 *       differences of JAC/FWD/ADJ), NULL inputs as zeros, NULL outputs;
 *   (g) the statuses: BAD_ARG without second-derivative kernels or h = 0.
 * Every case for the model without (MV = 0) and with the constraint.
 */
#include "test_derivatives_model.h"

/* ------------------------------------------------------------ (a), (b) */
static void test_kernels(int mv)
{
    const gen_rt_deriv_model *m = &MODELS[mv];
    const int nw = m->nw;
    real w[NWMAX] = {GEN_RT_C(0.3), GEN_RT_C(-1.1), GEN_RT_C(0.7), GEN_RT_C(0.2), GEN_RT_C(-0.5)};
    real mu[NWMAX] = {GEN_RT_C(0.9), GEN_RT_C(-0.4), GEN_RT_C(1.3), GEN_RT_C(0.6), GEN_RT_C(-0.8)};
    real Rz[NWMAX * NZ], H[NZ * NZ], W[NWMAX * NZ], Rw[NWMAX * NWMAX], R0[NWMAX];
    real zp[NZ], zm[NZ], Rp[NWMAX * NZ], Rm[NWMAX * NZ], Wp[NWMAX * NWMAX], Wm[NWMAX * NWMAX];
    int i, j, k;
    m->rz(Z0, w, Rz);
    m->rh(Z0, w, mu, H, W);
    for (j = 0; j < NZ; ++j) {
        for (k = 0; k < NZ; ++k) zp[k] = zm[k] = Z0[k];
        zp[j] += EPS; zm[j] -= EPS;
        /* R(z, w) = Rw w + R0 */
        m->r0(zp, Wp, Rp); m->r0(zm, Wm, Rm);
        for (i = 0; i < nw; ++i) {
            double dp = Rp[i], dm = Rm[i];
            for (k = 0; k < nw; ++k) { dp += Wp[i * nw + k] * w[k]; dm += Wm[i * nw + k] * w[k]; }
            CHECK_FD(Rz[i * NZ + j], (dp - dm) / (2 * EPS));
            /* W = d(Rw^T mu)/dz */
            for (k = 0, dp = dm = 0; k < nw; ++k) {
                dp += Wp[k * nw + i] * mu[k];
                dm += Wm[k * nw + i] * mu[k];
            }
            CHECK_FD(W[i * NZ + j], (dp - dm) / (2 * EPS));
        }
        /* H = d(mu^T Rz)/dz */
        m->rz(zp, w, Rp); m->rz(zm, w, Rm);
        for (i = 0; i < NZ; ++i) {
            double d = 0;
            for (k = 0; k < nw; ++k) d += mu[k] * (Rp[k * NZ + i] - Rm[k * NZ + i]);
            CHECK_FD(H[i * NZ + j], d / (2 * EPS));
        }
    }
    m->r0(Z0, Rw, R0);
    CHECK(Rw[0] != 0);
}

static void test_lu_solve_t(void)
{
    test_lcg g = {777UL};
    int n, nrhs, i, j, k;
    for (n = 1; n <= 6; ++n)
        for (nrhs = 1; nrhs <= 3; nrhs += 2) {
            real a[36], lu[36], b[18], x[18];
            int piv[6];
            for (i = 0; i < n * n; ++i) a[i] = lu[i] = (real)test_lcg_uniform(&g);
            for (i = 0; i < n * nrhs; ++i) b[i] = x[i] = (real)test_lcg_uniform(&g);
            if (gen_rt_lu_factor(n, lu, piv, 0)) continue;   /* a rare singular draw */
            CHECK_INT(gen_rt_lu_solve_t(n, lu, piv, nrhs, x), 0);
            for (i = 0; i < n; ++i)
                for (j = 0; j < nrhs; ++j) {
                    double s = 0;
                    for (k = 0; k < n; ++k) s += (double)a[k * n + i] * x[k * nrhs + j];
                    CHECK_NEAR(s, b[i * nrhs + j], TOL(1e-10, 1e-3));
                }
        }
    CHECK_INT(gen_rt_lu_solve_t(-1, 0, 0, 1, 0), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_lu_solve_t(2, 0, 0, 1, 0), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_lu_solve_t(0, 0, 0, 1, 0), GEN_RT_OK);
}

/* ------------------------------------------------------------------ (c) */
static void test_solve_hessian(int mv)
{
    const gen_rt_deriv_model *m = &MODELS[mv];
    const int nw = m->nw;
    const real lam[NWMAX] = {GEN_RT_C(0.7), GEN_RT_C(-1.2), GEN_RT_C(0.4), GEN_RT_C(1.5),
                             GEN_RT_C(-0.6)};
    real w[NWMAX], lu[NWMAX * NWMAX], Jw[NWMAX * NZ], sw[NWMAX], Rw[NWMAX * NWMAX], R0[NWMAX];
    real H[NZ * NZ], hw[GEN_RT_DERIV_HESSIAN_WORK(NZ, NWMAX)];
    real zp[NZ], zm[NZ], wp[NWMAX], wm[NWMAX], Jp[NWMAX * NZ], Jm[NWMAX * NZ];
    int piv[NWMAX], i, j, k;
    CHECK_INT(gen_rt_deriv_solve(m, Z0, sw, w, lu, piv, Jw), 0);
    m->r0(Z0, Rw, R0);
    for (i = 0; i < nw; ++i) {              /* R(z, w) = 0 */
        double s = R0[i];
        for (k = 0; k < nw; ++k) s += Rw[i * nw + k] * w[k];
        CHECK_NEAR(s, 0, TOL(1e-13, 1e-5));
    }
    CHECK_INT(gen_rt_deriv_hessian(m, Z0, w, lu, piv, Jw, lam, hw, H), 0);
    for (j = 0; j < NZ; ++j) {
        double wpp = 0, wmm = 0, w00 = 0;
        for (k = 0; k < NZ; ++k) zp[k] = zm[k] = Z0[k];
        zp[j] += EPS; zm[j] -= EPS;
        solve_at(m, zp, wp, Jp);
        solve_at(m, zm, wm, Jm);
        for (i = 0; i < nw; ++i) CHECK_FD(Jw[i * NZ + j], (wp[i] - wm[i]) / (2 * EPS));
        for (i = 0; i < NZ; ++i) {
            double d = 0;
            for (k = 0; k < nw; ++k) d += lam[k] * (Jp[k * NZ + i] - Jm[k * NZ + i]);
            CHECK_FD(H[i * NZ + j], d / (2 * EPS));
            CHECK(H[i * NZ + j] == H[j * NZ + i]);
        }
        /* the diagonal against second differences of lam^T w (values only) */
        {
            const real e2 = TOL(1e-4, 1e-1);
            real z2[NZ];
            for (k = 0; k < NZ; ++k) z2[k] = Z0[k];
            z2[j] += e2; solve_at(m, z2, wp, 0);
            z2[j] = Z0[j] - e2; solve_at(m, z2, wm, 0);
            for (k = 0; k < nw; ++k) { wpp += lam[k] * wp[k]; wmm += lam[k] * wm[k]; w00 += lam[k] * w[k]; }
            CHECK_NEAR(H[j * NZ + j], (wpp - 2 * w00 + wmm) / (e2 * e2),
                       TOL(1e-4, 0.3) * scale_of(H[j * NZ + j]));
        }
    }
}

/* ------------------------------------------------------------------ (d) */
static void rk4_deriv(const gen_rt_deriv_model *m, const real *v, const real *lam, real *xn,
                      real *J, real *Hl, real *T)
{
    CHECK_INT(gen_rt_deriv_rk4(m, v, v[NZ], lam, WORK, IWORK, xn, J, Hl, T), 0);
}

static void test_rk4(int mv)
{
    const gen_rt_deriv_model *m = &MODELS[mv];
    const real lam[NX] = {GEN_RT_C(0.8), GEN_RT_C(-0.5), GEN_RT_C(1.1), GEN_RT_C(0.3)};
    static real J[NX * NV], T[NX * NV * NV], Hl[NV * NV], Ht[NV * NV], Jp[NX * NV], Jm[NX * NV];
    real v[NV], vp[NV], vm[NV], xn[NX], xr[NX], xp[NX], xm[NX];
    int i, j, a, k;
    for (i = 0; i < NZ; ++i) v[i] = Z0[i];
    v[NZ] = GEN_RT_C(0.05);
    rk4_deriv(m, v, lam, xn, J, 0, T);
    rk4_value(m, v, xr);
    for (i = 0; i < NX; ++i) CHECK(xn[i] == xr[i]);     /* gen_rt_rk4_step's bits */
    for (j = 0; j < NV; ++j) {
        for (k = 0; k < NV; ++k) vp[k] = vm[k] = v[k];
        vp[j] += EPS; vm[j] -= EPS;
        rk4_value(m, vp, xp);
        rk4_value(m, vm, xm);
        rk4_deriv(m, vp, 0, 0, Jp, 0, 0);
        rk4_deriv(m, vm, 0, 0, Jm, 0, 0);
        for (i = 0; i < NX; ++i) {
            CHECK_FD(J[i * NV + j], (xp[i] - xm[i]) / (2 * EPS));
            for (a = 0; a < NV; ++a)
                CHECK_FD(T[(i * NV + a) * NV + j], (Jp[i * NV + a] - Jm[i * NV + a]) / (2 * EPS));
        }
    }
    /* Hl by the adjoint sweep = sum lam_i T_i = Hl from T */
    rk4_deriv(m, v, lam, 0, 0, Hl, 0);
    rk4_deriv(m, v, lam, 0, 0, Ht, T);
    for (a = 0; a < NV * NV; ++a) {
        double s = 0;
        for (i = 0; i < NX; ++i) s += lam[i] * T[i * NV * NV + a];
        CHECK_NEAR(Hl[a], s, TOL(1e-12, 1e-4) * scale_of(s));
        CHECK_NEAR(Ht[a], s, TOL(1e-12, 1e-4) * scale_of(s));
    }
    CHECK(fabs(Hl[(NV - 1) * NV + 2]) > 1e-3);          /* a real cross term with h */
}

/* ------------------------------------------------------------------ (e) */
static void test_rodas4(int mv)
{
    const gen_rt_deriv_model *m = &MODELS[mv];
    gen_rt_deriv_model no_rh = *m;
    real J[NX * NV], v[NV], vp[NV], vm[NV], xp[NX], xm[NX];
    int i, j, k;
    for (i = 0; i < NZ; ++i) v[i] = Z0[i];
    v[NZ] = GEN_RT_C(0.2);
    CHECK_INT(gen_rt_deriv_rodas4(m, v, v[NZ], WORK, IWORK, J), 0);
    for (j = 0; j < NV; ++j) {
        for (k = 0; k < NV; ++k) vp[k] = vm[k] = v[k];
        vp[j] += EPS; vm[j] -= EPS;
        rodas4_value(m, vp, xp);
        rodas4_value(m, vm, xm);
        for (i = 0; i < NX; ++i) CHECK_FD(J[i * NV + j], (xp[i] - xm[i]) / (2 * EPS));
    }
    /* (g) the statuses */
    CHECK_INT(gen_rt_deriv_rodas4(m, v, 0, WORK, IWORK, J), GEN_RT_ERR_BAD_ARG);
    no_rh.rh = 0;
    CHECK_INT(gen_rt_deriv_rodas4(&no_rh, v, v[NZ], WORK, IWORK, J), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_deriv_rk4(&no_rh, v, v[NZ], 0, WORK, IWORK, 0, J, 0, WORK), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_deriv_rk4(&no_rh, v, v[NZ], 0, WORK, IWORK, 0, J, 0, 0), 0);
}

int main(void)
{
    int mv;
    test_lu_solve_t();
    for (mv = 0; mv <= 1; ++mv) {
        test_kernels(mv);
        test_solve_hessian(mv);
        test_rk4(mv);
        test_rodas4(mv);
    }
    TEST_END();
}
