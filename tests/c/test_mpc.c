/*
 * test_mpc.c - the real-time iterations of gen_rt_mpc.c on a model whose
 * step is linear (a double integrator, x+ = A x + B u exactly): one
 * iteration solves the MPC exactly, so the controller's solution must be
 * the linear MPC's, found here independently by projected gradient
 * descent on the condensed problem (the inputs only, |u| <= 1) in double.
 * Then: the shifted warm start gives the same solution as a cold start at
 * the next state, prepare + feedback equal a step, SQP converges in two
 * iterations, and the statuses reach the caller with a finite control
 * (a NaN state, a failing model step, a time budget with a clock that
 * runs out, a budget without a clock).
 */
#include "test_common.h"
#include "gen_rt_mpc.h"

#define NH 10
#define HP 0.1
#define NXS 2

static int fail_step = 0;

/* the double integrator's exact step: p += h v + h^2/2 u, v += h u */
static int step(const void *ctx, gen_rt_real t, gen_rt_real h, const gen_rt_real *r,
                gen_rt_real *x, gen_rt_real *Fx, gen_rt_real *Fr)
{
    (void)ctx;
    (void)t;
    if (fail_step) return GEN_RT_ERR_NONFINITE_MODEL;
    x[0] += h * x[1] + h * h / 2 * r[0];
    x[1] += h * r[0];
    Fx[0] = 1; Fx[1] = h; Fx[2] = 0; Fx[3] = 1;
    Fr[0] = h * h / 2; Fr[1] = h;
    return GEN_RT_OK;
}

static const int ind[NXS] = {0, 1};
static const gen_rt_real Qw[4] = {1, 0, 0, (gen_rt_real)0.1};
static const gen_rt_real Rw[1] = {(gen_rt_real)0.01};
static const gen_rt_real Pw[4] = {10, 0, 0, 10};
static const int idxbu[1] = {0};
static const gen_rt_real lbu[1] = {-1}, ubu[1] = {1};
static const gen_rt_real xref[NXS] = {0, 0}, uref[1] = {0};

static gen_rt_mpc_problem problem(void)
{
    gen_rt_mpc_problem pb;
    memset(&pb, 0, sizeof pb);
    pb.nx = NXS; pb.ns = NXS; pb.nr = 1; pb.N = NH; pb.substeps = 1; pb.period = (gen_rt_real)HP;
    pb.ind = ind; pb.Q = Qw; pb.R = Rw; pb.P = Pw;
    pb.nbu = 1; pb.idxbu = idxbu; pb.lbu = lbu; pb.ubu = ubu;
    pb.n_ref = 1; pb.t_ref = 0; pb.dt_ref = (gen_rt_real)HP; pb.x_ref = xref; pb.u_ref = uref;
    pb.step = step;
    return pb;
}

/* the condensed linear MPC from x0 by projected gradient descent (the
 * cost J(U) = sum period (x'Qx + u'Ru) + x_N'P x_N, |u| <= 1): U (NH) */
static void reference_mpc(const double *x0, double *U)
{
    double Hm[NH][NH], g[NH], G[NH + 1][2][NH], f[NH + 1][2], L = 0;
    double A[2][2] = {{1, HP}, {0, 1}}, B[2] = {HP * HP / 2, HP};
    int k, i, j, it, a;
    memset(G, 0, sizeof G);
    f[0][0] = x0[0]; f[0][1] = x0[1];
    for (k = 0; k < NH; ++k) {          /* x_{k+1} = f + G U */
        for (a = 0; a < 2; ++a) {
            f[k + 1][a] = A[a][0] * f[k][0] + A[a][1] * f[k][1];
            for (j = 0; j < NH; ++j)
                G[k + 1][a][j] = A[a][0] * G[k][0][j] + A[a][1] * G[k][1][j] + (j == k ? B[a] : 0);
        }
    }
    /* J = sum_k w_k (x_k' W_k x_k) + period R |U|^2: HP = 2 (sum G'WG + period R I), g = 2 sum G'W f */
    for (i = 0; i < NH; ++i) {
        g[i] = 0;
        for (j = 0; j < NH; ++j) Hm[i][j] = i == j ? 2 * HP * 0.01 : 0;
    }
    for (k = 1; k <= NH; ++k) {
        double W[2] = {k < NH ? HP * 1.0 : 10.0, k < NH ? HP * 0.1 : 10.0};
        for (a = 0; a < 2; ++a)
            for (i = 0; i < NH; ++i) {
                g[i] += 2 * W[a] * G[k][a][i] * f[k][a];
                for (j = 0; j < NH; ++j) Hm[i][j] += 2 * W[a] * G[k][a][i] * G[k][a][j];
            }
    }
    for (i = 0; i < NH; ++i) {          /* a bound on the largest eigenvalue */
        double s = 0;
        for (j = 0; j < NH; ++j) s += fabs(Hm[i][j]);
        L = s > L ? s : L;
    }
    for (i = 0; i < NH; ++i) U[i] = 0;
    for (it = 0; it < 200000; ++it) {
        double dmax = 0;
        for (i = 0; i < NH; ++i) {
            double gi = g[i], v;
            for (j = 0; j < NH; ++j) gi += Hm[i][j] * U[j];
            v = U[i] - gi / L;
            v = v < -1 ? -1 : v > 1 ? 1 : v;
            dmax = fabs(v - U[i]) > dmax ? fabs(v - U[i]) : dmax;
            U[i] = v;
        }
        if (dmax < 1e-15) break;
    }
}

static double ticks = 0;

static double fake_clock(void *ctx)
{
    (void)ctx;
    ticks += 1.0;             /* a second per reading: any budget runs out */
    return ticks;
}

int main(void)
{
    static gen_rt_real work[GEN_RT_MPC_WORK(NXS, NXS, 1, NH, 0, 1, 0, 0)];
    static gen_rt_real X[(NH + 1) * NXS], U[NH], X2[(NH + 1) * NXS], U2[NH];
    gen_rt_mpc_problem pb = problem();
    gen_rt_mpc_state st;
    gen_rt_real x[NXS] = {1, 0}, u[1], u2[1], xn[NXS];
    double x0d[NXS] = {1, 0}, Uref[NH], worst = 0;
    int k, st1;

    CHECK_INT(gen_rt_mpc_work_len(&pb), GEN_RT_MPC_WORK(NXS, NXS, 1, NH, 0, 1, 0, 0));
    gen_rt_mpc_init(&st);
    /* one RTI from the zero guess solves the linear MPC */
    CHECK_INT(gen_rt_mpc_step(&pb, &st, 0, x, work, u), GEN_RT_OK);
    CHECK_INT(st.iterations, 1);
    CHECK_INT(gen_rt_mpc_solution(&pb, &st, work, X, U), GEN_RT_OK);
    reference_mpc(x0d, Uref);
    for (k = 0; k < NH; ++k) worst = fabs(U[k] - Uref[k]) > worst ? fabs(U[k] - Uref[k]) : worst;
    CHECK_NEAR(worst, 0, TOL(1e-7, 2e-3));
    CHECK_NEAR(u[0], Uref[0], TOL(1e-7, 2e-3));
    CHECK_NEAR(Uref[0], -1, 1e-12);                   /* the bound, active */
    for (k = 0; k < NH; ++k) {                         /* the predictions follow the model */
        CHECK_NEAR(X[(k + 1) * 2], X[k * 2] + HP * X[k * 2 + 1] + HP * HP / 2 * U[k], TOL(1e-12, 1e-5));
        CHECK_NEAR(X[(k + 1) * 2 + 1], X[k * 2 + 1] + HP * U[k], TOL(1e-12, 1e-5));
    }
    /* the next state; the shifted warm start against a cold start there */
    xn[0] = X[2]; xn[1] = X[3];
    CHECK_INT(gen_rt_mpc_step(&pb, &st, (gen_rt_real)HP, xn, work, u), GEN_RT_OK);
    CHECK_INT(gen_rt_mpc_solution(&pb, &st, work, X, U), GEN_RT_OK);
    gen_rt_mpc_init(&st);
    CHECK_INT(gen_rt_mpc_prepare(&pb, &st, (gen_rt_real)HP, work), GEN_RT_OK);
    CHECK_INT(gen_rt_mpc_feedback(&pb, &st, xn, work, u2), GEN_RT_OK);
    CHECK_INT(gen_rt_mpc_solution(&pb, &st, work, X2, U2), GEN_RT_OK);
    CHECK_NEAR(u[0], u2[0], TOL(1e-9, 1e-3));
    for (k = 0; k < NH; ++k) CHECK_NEAR(U[k], U2[k], TOL(1e-9, 1e-3));
    /* SQP on a linear model: the second step is zero */
    gen_rt_mpc_init(&st);
    st.sqp = 1;
    st.max_iter = 10;
    CHECK_INT(gen_rt_mpc_step(&pb, &st, 0, x, work, u), GEN_RT_OK);
    CHECK_INT(st.iterations, 2);
    CHECK_NEAR(u[0], Uref[0], TOL(1e-7, 2e-3));
    /* a NaN state: the status, the previous solution's next control */
    gen_rt_mpc_init(&st);
    CHECK_INT(gen_rt_mpc_step(&pb, &st, 0, x, work, u), GEN_RT_OK);
    CHECK_INT(gen_rt_mpc_solution(&pb, &st, work, X, U), GEN_RT_OK);
    xn[0] = (gen_rt_real)NAN;
    CHECK_INT(gen_rt_mpc_step(&pb, &st, (gen_rt_real)HP, xn, work, u), GEN_RT_ERR_NONFINITE_INPUT);
    CHECK_NEAR(u[0], U[1], 0);
    /* the model's step fails: its status, a finite control in the bounds */
    fail_step = 1;
    x[0] = (gen_rt_real)0.5;
    st1 = gen_rt_mpc_step(&pb, &st, (gen_rt_real)HP, x, work, u);
    CHECK_INT(st1, GEN_RT_ERR_NONFINITE_MODEL);
    CHECK(u[0] - u[0] == 0 && u[0] >= -1 && u[0] <= 1);
    fail_step = 0;
    /* a budget: no clock, then a clock that runs out */
    gen_rt_mpc_init(&st);
    st.time_limit = 1e-3;
    CHECK_INT(gen_rt_mpc_step(&pb, &st, 0, x, work, u), GEN_RT_MPC_ERR_NO_CLOCK);
    CHECK(u[0] - u[0] == 0);
    st.clock = fake_clock;
    st1 = gen_rt_mpc_step(&pb, &st, 0, x, work, u);
    CHECK_INT(st1, GEN_RT_MPC_TIME_LIMIT);
    CHECK(u[0] - u[0] == 0 && u[0] >= -1 && u[0] <= 1);
    CHECK(st.t_prepare >= 0 && st.t_feedback > 0);
    /* the status table */
    CHECK(strstr(gen_rt_mpc_status_message(GEN_RT_MPC_TIME_LIMIT), "time budget") != NULL);
    CHECK(strstr(gen_rt_mpc_status_message(GEN_RT_MPC_ERR_QP_MAX_ITER), "iteration cap") != NULL);
    printf("linear MPC: largest |U - U_ref| = %.2e\n", worst);
    TEST_END();
}
