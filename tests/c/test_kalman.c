/*
 * test_kalman.c - gen_rt_kalman.c (the extended and unscented Kalman
 * filters, the closed loop) and gen_rt_model_state_map (gen_rt_sens.c), on
 * hand-written models:
 *
 *   osc:   m q'' = -k q + r, measured z = [q, q + u]: a linear system, so
 *          the EKF is the textbook Kalman filter on RK4's transition
 *          x1 = F x + G r (F = I + hA + (hA)^2/2 + (hA)^3/6 + (hA)^4/24),
 *          with the batch update (2 x 2 inverse, Joseph form) computed here
 *          in double, and the UKF too (the unscented transform is exact for
 *          linear maps);
 *   pend:  the particle on a circle (gen_rt_sens's test model), x dependent:
 *          E keeps the constraints, an update keeps the estimate on them.
 *
 * Checked: the filters against the reference; a NaN measurement rejected
 * with MISSING and the estimate unchanged, an outlier GATED, the counts;
 * E; the generator's moments and reproducibility; one closed-loop sample
 * (noise-free: r = -K x_est); the work macros against the functions.
 */
#include <stdlib.h>

#include "gen_rt_kalman.h"
#include "test_common.h"
#include "test_models.h"

#define PM 1.5
#define PK 4.0
#define H_STEP 0.05

/* ----------------------------------------------------------------- osc */

static const int o_ind[1] = {0}, o_none[1] = {0};

static gen_rt_model osc_model(void)
{
    gen_rt_model m;
    memset(&m, 0, sizeof m);
    m.nq = 1; m.nu = 1; m.nr = 1; m.np = 2;
    m.explicit_kinematics = 1; m.accel = GEN_RT_ACCEL_LU;
    m.q_ind = o_ind; m.q_dep = o_none; m.u_ind = o_ind; m.u_dep = o_none;
    m.mass_matrix = o_mass; m.forcing = o_forcing; m.kinematics = o_kin;
    m.rhs_terms = o_rhs_terms; m.lin_terms = o_lin;
    return m;
}

/* z = [q, q + u] */
static void o_h(const gen_rt_real *x, const gen_rt_real *r, const gen_rt_real *p,
                const gen_rt_real *t, gen_rt_real *h)
{
    (void)r; (void)p; (void)t;
    h[0] = x[0];
    h[1] = x[0] + x[1];
}

static void o_hjac(const gen_rt_real *x, const gen_rt_real *r, const gen_rt_real *p,
                   const gen_rt_real *t, gen_rt_real *h, gen_rt_real *H)
{
    o_h(x, r, p, t, h);
    H[0] = 1; H[1] = 0; H[2] = 1; H[3] = 1;
}

/* ---------------------------------------------------------------- pend */

static void p_jac(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t, gen_rt_real *fc,
                  gen_rt_real *Jc)
{
    (void)t;
    fc[0] = q[0] * q[0] + q[1] * q[1] - p[2] * p[2];
    Jc[0] = 2 * q[0]; Jc[1] = 2 * q[1];
}

static void p_constraints(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                          gen_rt_real *fc)
{
    gen_rt_real J[2];
    p_jac(q, p, t, fc, J);
}

static const int p_q_ind[1] = {1}, p_q_dep[1] = {0}, p_u_ind[1] = {1}, p_u_dep[1] = {0};

static gen_rt_model pend_model(void)
{
    gen_rt_model m;
    memset(&m, 0, sizeof m);
    m.nq = 2; m.nu = 2; m.np = 3; m.mc = 1; m.mv = 1;
    m.explicit_kinematics = 1; m.accel = GEN_RT_ACCEL_PARTITIONED;
    m.q_ind = p_q_ind; m.q_dep = p_q_dep; m.u_ind = p_u_ind; m.u_dep = p_u_dep;
    m.mass_matrix = p_mass; m.forcing = p_forcing; m.kinematics = p_kin;
    m.rhs_terms = p_rhs_terms; m.constraints = p_constraints; m.constraint_jacobian = p_jac;
    m.velocity_constraints = p_vc; m.velocity_constraint_matrix = p_vcm; m.lin_terms = p_lin;
    return m;
}

/* the angle atan2(y, x) */
static void p_h(const gen_rt_real *x, const gen_rt_real *r, const gen_rt_real *p,
                const gen_rt_real *t, gen_rt_real *h)
{
    (void)r; (void)p; (void)t;
    h[0] = (gen_rt_real)atan2((double)x[1], (double)x[0]);
}

static void p_hjac(const gen_rt_real *x, const gen_rt_real *r, const gen_rt_real *p,
                   const gen_rt_real *t, gen_rt_real *h, gen_rt_real *H)
{
    gen_rt_real d = x[0] * x[0] + x[1] * x[1];
    p_h(x, r, p, t, h);
    H[0] = -x[1] / d; H[1] = x[0] / d; H[2] = 0; H[3] = 0;
}

/* ------------------------------------------------------------ a filter */
#define WORK 8192
#define IWORK 256

typedef struct {
    gen_rt_kalman k;
    gen_rt_real x[4], xf[4], P[16], Q[16], R[2], p[3], r[1], y[2], S[2];
    int status[2];
    long rejected[2];
    gen_rt_real work[WORK];
    int iwork[IWORK];
} filter;

static const int perm_id[4] = {0, 1, 2, 3};

static void filter_init(filter *f, const gen_rt_model *m, int nz, gen_rt_kalman_h_fn h,
                        gen_rt_kalman_hjac_fn hj, int kind)
{
    memset(f, 0, sizeof *f);
    f->k.m = m; f->k.nz = nz; f->k.h = h; f->k.hjac = hj; f->k.perm = perm_id;
    f->k.kind = kind; f->k.substeps = 1; f->k.period = (gen_rt_real)H_STEP;
    f->k.alpha = 1; f->k.beta = 2; f->k.kappa = 0;
    f->k.x = f->x; f->k.xf = f->xf; f->k.P = f->P; f->k.Q = f->Q; f->k.R = f->R; f->k.p = f->p;
    f->k.r = f->r; f->k.y = f->y; f->k.S = f->S; f->k.status = f->status;
    f->k.rejected = f->rejected; f->k.work = f->work; f->k.iwork = f->iwork;
    CHECK(gen_rt_kalman_work_len(m, nz) <= WORK);
    CHECK(gen_rt_kalman_iwork_len(m, nz) <= IWORK);
}

/* the reference: the linear Kalman filter of osc in double */
static void ref_predict(double *x, double *P, double r, const double *Q)
{
    /* F = sum_{k<=4} (hA)^k / k!, G = h sum_{k<=3} (hA)^k / (k+1)! B */
    double h = H_STEP, hA[4] = {0, h, -h * PK / PM, 0}, Mk[4] = {1, 0, 0, 1};
    double F[4] = {1, 0, 0, 1}, S[4] = {1, 0, 0, 1}, T[4], fact = 1, G[2], x0, x1;
    int i, j, l, k;
    for (k = 1; k <= 4; ++k) {
        double Mn[4] = {0, 0, 0, 0};
        for (i = 0; i < 2; ++i)
            for (j = 0; j < 2; ++j)
                for (l = 0; l < 2; ++l) Mn[i * 2 + j] += Mk[i * 2 + l] * hA[l * 2 + j];
        memcpy(Mk, Mn, sizeof Mk);
        fact *= k;
        for (i = 0; i < 4; ++i) {
            F[i] += Mk[i] / fact;
            if (k < 4) S[i] += Mk[i] / (fact * (k + 1));
        }
    }
    G[0] = h * S[1] / PM;
    G[1] = h * S[3] / PM;
    x0 = F[0] * x[0] + F[1] * x[1] + G[0] * r;
    x1 = F[2] * x[0] + F[3] * x[1] + G[1] * r;
    x[0] = x0;
    x[1] = x1;
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j) T[i * 2 + j] = F[i * 2] * P[j] + F[i * 2 + 1] * P[2 + j];
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j)
            P[i * 2 + j] = T[i * 2] * F[j * 2] + T[i * 2 + 1] * F[j * 2 + 1] + Q[i * 2 + j];
}

static void ref_update(double *x, double *P, const double *z, const double *R)
{
    double H[4] = {1, 0, 1, 1}, PH[4], S[4], Si[4], K[4], IK[4], T[4], det, y[2];
    int i, j, l;
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j) PH[i * 2 + j] = P[i * 2] * H[j * 2] + P[i * 2 + 1] * H[j * 2 + 1];
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j)
            S[i * 2 + j] = H[i * 2] * PH[j] + H[i * 2 + 1] * PH[2 + j] + (i == j ? R[i] : 0);
    det = S[0] * S[3] - S[1] * S[2];
    Si[0] = S[3] / det; Si[1] = -S[1] / det; Si[2] = -S[2] / det; Si[3] = S[0] / det;
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j) K[i * 2 + j] = PH[i * 2] * Si[j] + PH[i * 2 + 1] * Si[2 + j];
    y[0] = z[0] - x[0];
    y[1] = z[1] - x[0] - x[1];
    x[0] += K[0] * y[0] + K[1] * y[1];
    x[1] += K[2] * y[0] + K[3] * y[1];
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j)
            IK[i * 2 + j] = (i == j) - (K[i * 2] * H[j] + K[i * 2 + 1] * H[2 + j]);
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j) T[i * 2 + j] = IK[i * 2] * P[j] + IK[i * 2 + 1] * P[2 + j];
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j) {
            double s = T[i * 2] * IK[j * 2] + T[i * 2 + 1] * IK[j * 2 + 1];
            for (l = 0; l < 2; ++l) s += K[i * 2 + l] * R[l] * K[j * 2 + l];
            P[i * 2 + j] = s;
        }
}

static void linear_filter(int kind, double tol)
{
    gen_rt_model m = osc_model();
    static filter f;
    double x[2] = {0.3, -0.2}, P[4] = {0.5, 0.1, 0.1, 0.8};
    double Q[4] = {1e-3, 2e-4, 2e-4, 4e-3}, R[2] = {0.01, 0.04};
    gen_rt_real z[2], r[1];
    int i, k;
    filter_init(&f, &m, 2, o_h, o_hjac, kind);
    for (i = 0; i < 2; ++i) f.x[i] = (gen_rt_real)x[i];
    for (i = 0; i < 4; ++i) { f.P[i] = (gen_rt_real)P[i]; f.Q[i] = (gen_rt_real)Q[i]; }
    f.R[0] = (gen_rt_real)R[0]; f.R[1] = (gen_rt_real)R[1];
    f.p[0] = (gen_rt_real)PM; f.p[1] = (gen_rt_real)PK;
    CHECK_INT(gen_rt_kalman_start(&f.k), GEN_RT_OK);
    for (k = 0; k < 40; ++k) {
        double zd[2];
        zd[0] = 0.5 * sin(0.3 * k);
        zd[1] = zd[0] + 0.2 * cos(0.7 * k);
        z[0] = (gen_rt_real)zd[0];
        z[1] = (gen_rt_real)zd[1];
        r[0] = (gen_rt_real)(0.1 * k);
        CHECK_INT(gen_rt_kalman_predict(&f.k, r), GEN_RT_OK);
        ref_predict(x, P, (double)r[0], Q);
        CHECK_INT(gen_rt_kalman_update(&f.k, z), GEN_RT_OK);
        ref_update(x, P, zd, R);
        CHECK_INT(f.status[0], GEN_RT_KALMAN_ACCEPTED);
        CHECK_INT(f.status[1], GEN_RT_KALMAN_ACCEPTED);
    }
    for (i = 0; i < 2; ++i) CHECK_NEAR(f.xf[i], x[i], tol);
    for (i = 0; i < 4; ++i) CHECK_NEAR(f.P[i], P[i], tol);
    CHECK_NEAR(f.k.t, 40 * H_STEP, TOL(1e-12, 1e-5));
    CHECK_INT(f.k.n_predict, 40);

    /* a NaN measurement: rejected, MISSING, the estimate unchanged */
    {
        gen_rt_real xs[2], Ps[4];
        memcpy(xs, f.xf, sizeof xs);
        memcpy(Ps, f.P, sizeof Ps);
        z[0] = (gen_rt_real)NAN;
        z[1] = (gen_rt_real)NAN;
        CHECK_INT(gen_rt_kalman_update(&f.k, z), GEN_RT_OK);
        CHECK_INT(f.status[0], GEN_RT_KALMAN_MISSING);
        CHECK_INT(f.status[1], GEN_RT_KALMAN_MISSING);
        CHECK(memcmp(xs, f.xf, sizeof xs) == 0 && memcmp(Ps, f.P, sizeof Ps) == 0);
        CHECK_INT(f.rejected[0], 1);
        /* an outlier 100 sigma away: GATED at 5 sigma, the other fused */
        f.k.gate = 5;
        z[0] = f.xf[0] + 100 * (gen_rt_real)sqrt((double)(f.P[0] + f.R[0]));
        z[1] = f.xf[0] + f.xf[1];
        CHECK_INT(gen_rt_kalman_update(&f.k, z), GEN_RT_OK);
        CHECK_INT(f.status[0], GEN_RT_KALMAN_GATED);
        CHECK_INT(f.status[1], GEN_RT_KALMAN_ACCEPTED);
        CHECK_INT(f.rejected[0], 2);
        CHECK_INT(f.rejected[1], 1);
        CHECK(f.y[0] * f.y[0] > 25 * f.S[0]);
    }
    /* a bad setting */
    f.k.period = 0;
    CHECK_INT(gen_rt_kalman_start(&f.k), GEN_RT_ERR_BAD_ARG);
}

static void constrained(void)
{
    gen_rt_model m = pend_model();
    static filter f;
    gen_rt_real E[8], z[1], th = GEN_RT_C(0.4), L = GEN_RT_C(1.2);
    gen_rt_real x[4];
    static gen_rt_real mw[WORK];
    int iw[16], i;
    static const int perm[2] = {0, 1};
    x[0] = L * (gen_rt_real)cos((double)th); x[1] = L * (gen_rt_real)sin((double)th);
    x[2] = -GEN_RT_C(0.7) * x[1]; x[3] = GEN_RT_C(0.7) * x[0];
    /* E: the independent rows the identity, the constraints kept */
    CHECK_INT(gen_rt_model_state_map(&m, 0, x, NULL, (gen_rt_real[]){1, 9.81, 1.2}, mw, iw, E),
              GEN_RT_OK);
    CHECK_NEAR(E[1 * 2 + 0], 1, 0);
    CHECK_NEAR(E[1 * 2 + 1], 0, 0);
    CHECK_NEAR(E[3 * 2 + 1], 1, 0);
    for (i = 0; i < 2; ++i) {
        /* Jc E_q = 0, A E_u + Vq E_q = 0 */
        CHECK_NEAR(2 * x[0] * E[0 * 2 + i] + 2 * x[1] * E[1 * 2 + i], 0, TOL(1e-14, 1e-6));
        CHECK_NEAR(x[0] * E[2 * 2 + i] + x[1] * E[3 * 2 + i] + x[2] * E[0 * 2 + i] +
                   x[3] * E[1 * 2 + i], 0, TOL(1e-14, 1e-6));
    }
    /* an update on the angle keeps the estimate on the constraints */
    filter_init(&f, &m, 1, p_h, p_hjac, GEN_RT_KALMAN_EKF);
    f.k.perm = perm;
    memcpy(f.x, x, sizeof x);
    f.P[0] = GEN_RT_C(0.01); f.P[3] = GEN_RT_C(0.04); f.R[0] = GEN_RT_C(1e-4);
    f.p[0] = 1; f.p[1] = GEN_RT_C(9.81); f.p[2] = L;
    CHECK_INT(gen_rt_kalman_start(&f.k), GEN_RT_OK);
    CHECK_INT(gen_rt_kalman_predict(&f.k, NULL), GEN_RT_OK);
    z[0] = th + GEN_RT_C(0.05);
    CHECK_INT(gen_rt_kalman_update(&f.k, z), GEN_RT_OK);
    CHECK_INT(f.status[0], GEN_RT_KALMAN_ACCEPTED);
    CHECK_NEAR(f.x[0] * f.x[0] + f.x[1] * f.x[1], L * L, TOL(1e-12, 1e-5));
    CHECK_NEAR(f.x[0] * f.x[2] + f.x[1] * f.x[3], 0, TOL(1e-12, 1e-5));
    CHECK_NEAR(f.xf[0], f.x[1], 0);
    /* the estimate moved toward the measured angle */
    CHECK_LT(atan2((double)f.x[1], (double)f.x[0]), (double)z[0]);
    CHECK_LT((double)th, atan2((double)f.x[1], (double)f.x[0]));
}

static void generator(void)
{
    uint64_t s1 = 42, s2 = 42;
    double sum = 0, sum2 = 0;
    int i, n = 20000;
    for (i = 0; i < n; ++i) {
        double v = (double)gen_rt_kalman_normal(&s1);
        sum += v;
        sum2 += v * v;
    }
    CHECK_LT(fabs(sum / n), 4 / sqrt((double)n));
    CHECK_LT(fabs(sum2 / n - 1), 4 * sqrt(2.0 / n));
    s1 = 42;
    CHECK((double)gen_rt_kalman_normal(&s1) == (double)gen_rt_kalman_normal(&s2));
}

static void loop_sample(void)
{
    gen_rt_model m = osc_model();
    static filter f;
    gen_rt_kalman_loop L;
    gen_rt_input law;
    gen_rt_real K[2] = {3, 2}, xa[2], xo[2], z[2], rprev[1], sd[2] = {0, 0};
    gen_rt_real lt[4], lx[8], ls[8], xt[2] = {GEN_RT_C(0.2), GEN_RT_C(-0.1)}, r[1] = {0}, r1;
    filter_init(&f, &m, 2, o_h, o_hjac, GEN_RT_KALMAN_EKF);
    f.P[0] = 1; f.P[3] = 1; f.R[0] = GEN_RT_C(1e-6); f.R[1] = GEN_RT_C(1e-6);
    f.p[0] = (gen_rt_real)PM; f.p[1] = (gen_rt_real)PK;
    CHECK_INT(gen_rt_kalman_start(&f.k), GEN_RT_OK);
    memset(&L, 0, sizeof L);
    memset(&law, 0, sizeof law);
    law.K = K;
    L.k = &f.k; L.law = &law; L.nq = 1; L.noise_sd = sd; L.rng = 1;
    L.xa = xa; L.xo = xo; L.z = z; L.rprev = rprev;
    L.capacity = 4; L.log_t = lt; L.log_x = lx; L.log_sd = ls;
    CHECK_INT(gen_rt_kalman_control(&L, 0, xt, r), GEN_RT_OK);
    r1 = r[0];
    /* noise-free, nearly exact measurements of both entries: the estimate
     * is the truth to the R / P ratio, and r = -K x_est */
    CHECK_NEAR(f.xf[0], xt[0], TOL(1e-5, 1e-4));
    CHECK_NEAR(f.xf[1], xt[1], TOL(1e-5, 1e-4));
    CHECK_NEAR(r[0], -(K[0] * f.xf[0] + K[1] * f.xf[1]), TOL(1e-14, 1e-5));
    CHECK_INT(L.count, 1);
    CHECK_NEAR(lx[1], f.xf[1], 0);
    CHECK_NEAR(ls[0], sqrt((double)f.P[0]), TOL(1e-15, 1e-6));
    /* the second sample predicts with the first's r */
    CHECK_INT(gen_rt_kalman_control(&L, (gen_rt_real)H_STEP, xt, r), GEN_RT_OK);
    CHECK_INT(f.k.n_predict, 1);
    CHECK_NEAR(f.r[0], r1, 0);
    CHECK_NEAR(lt[1], H_STEP, TOL(1e-15, 1e-7));
}

int main(void)
{
    linear_filter(GEN_RT_KALMAN_EKF, TOL(1e-12, 2e-4));
    linear_filter(GEN_RT_KALMAN_UKF, TOL(1e-10, 2e-3));
    constrained();
    generator();
    loop_sample();
    {
        gen_rt_model m = osc_model(), pm = pend_model();
        CHECK_INT(gen_rt_kalman_work_len(&m, 2),
                  GEN_RT_KALMAN_WORK(1, 1, 0, 0, 1, 1, GEN_RT_ACCEL_LU, 2));
        CHECK_INT(gen_rt_kalman_work_len(&pm, 1),
                  GEN_RT_KALMAN_WORK(2, 2, 1, 1, 0, 1, GEN_RT_ACCEL_PARTITIONED, 1));
    }
    TEST_END();
}
