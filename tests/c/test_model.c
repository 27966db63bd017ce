/*
 * test_model.c - the model layer of the runtime (gen_rt_model.c) on models
 * written here by hand, no generator involved:
 *
 *   pend: a particle of mass m at (x, y) held at distance L from the origin,
 *         gravity g along +x (the seed document's pendulum), in the
 *         coordinates q = [x, y], speeds u = [x', y'], with the
 *         configuration constraint x^2 + y^2 - L^2 = 0 and the velocity
 *         constraint x x' + y y' = 0; solved by the KKT system (Lagrange
 *         form) or by the Kane partition (dependent x, x');
 *   osc:  an unconstrained oscillator m x'' = -k x, solved by an LDL^T
 *         "mass_solve" or by the runtime's LU.
 *
 * References are closed forms: the tangential acceleration g sin(theta),
 * the small-oscillation matrix [[0, 1], [-g/L, 0]], cos(w t) for the
 * oscillator, energy conservation. Every work array is the size its
 * GEN_RT_MODEL_*_WORK macro gives plus guard values that must survive.
 */
#include "test_common.h"
#include "test_models.h"

#define PM 1.5   /* mass */
#define PG 9.81  /* gravity */
#define PL 1.2   /* length */
#define PK 4.0   /* spring */
#define GUARD 16

/* ---------------------------------------------------------------- pend */

static void p_constraints(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                          gen_rt_real *fc)
{
    (void)t;
    fc[0] = q[0] * q[0] + q[1] * q[1] - p[2] * p[2];
}

static void p_jac(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t, gen_rt_real *fc,
                  gen_rt_real *Jc)
{
    p_constraints(q, p, t, fc);
    Jc[0] = 2 * q[0]; Jc[1] = 2 * q[1];
}

static void p_energy(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                     gen_rt_real t, gen_rt_real *E)
{
    (void)t;
    E[0] = GEN_RT_C(0.5) * p[0] * (u[0] * u[0] + u[1] * u[1]) - p[0] * p[1] * q[0];
}

static const int p_q_ind[1] = {1}, p_q_dep[1] = {0}, p_u_ind[1] = {1}, p_u_dep[1] = {0};

static gen_rt_model pend_model(int accel)
{
    gen_rt_model m;
    m.nq = 2; m.nu = 2; m.nr = 0; m.np = 3; m.mc = 1; m.mv = 1;
    m.explicit_kinematics = 1; m.accel = accel;
    m.q_ind = p_q_ind; m.q_dep = p_q_dep; m.u_ind = p_u_ind; m.u_dep = p_u_dep;
    m.mass_matrix = p_mass; m.forcing = p_forcing; m.kinematics = p_kin;
    m.rhs_terms = p_rhs_terms; m.constraints = p_constraints; m.constraint_jacobian = p_jac;
    m.velocity_constraints = p_vc; m.velocity_constraint_matrix = p_vcm;
    m.energy = p_energy; m.lin_terms = p_lin; m.mass_solve = NULL;
    m.na = 0; m.auxiliary = NULL; m.accel_terms = NULL; m.rhs_solve = NULL;
    m.reaction_solve = NULL;
    m.ny = 0; m.outputs = NULL; m.output_jacobian = NULL; m.hybrid = NULL;
    return m;
}

/* ----------------------------------------------------------------- osc */

static int o_solve(const gen_rt_real *M, const gen_rt_real *f, gen_rt_real *x)
{
    if (!(M[0] > 0)) return GEN_RT_ERR_SINGULAR;
    x[0] = f[0] / M[0];
    return GEN_RT_OK;
}

/* the fused right-hand side (rhs_solve) of a generated LDL^T model: M and f
 * written where given (the runtime passes NULL when it needs neither) */
static int o_rhs_solve(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                       const gen_rt_real *p, gen_rt_real t, gen_rt_real *qd, gen_rt_real *M,
                       gen_rt_real *f, gen_rt_real *ud)
{
    gen_rt_real M_[1], f_[1];
    o_rhs_terms(q, u, r, p, t, NULL, qd, M ? M : M_, f ? f : f_, NULL, NULL);
    return o_solve(M ? M : M_, f ? f : f_, ud);
}

/* two made-up reactions R of the oscillator: F R + g = 0 with g = [m x'', x]
 * and the constant F = [[2, 1], [1, 3]] (the singular [[1, 2], [2, 4]] when
 * x > 100) */
static void o_aux(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *ud,
                  const gen_rt_real *r, const gen_rt_real *p, gen_rt_real t, gen_rt_real *F,
                  gen_rt_real *g)
{
    (void)u; (void)r; (void)t;
    if (q[0] > 100) {
        F[0] = 1; F[1] = 2; F[2] = 2; F[3] = 4;
    } else {
        F[0] = 2; F[1] = 1; F[2] = 1; F[3] = 3;
    }
    g[0] = p[0] * ud[0];
    g[1] = q[0];
}

static const int o_ind[1] = {0}, o_none[1] = {0};

static gen_rt_model osc_model(int accel)
{
    gen_rt_model m;
    m.nq = 1; m.nu = 1; m.nr = 1; m.np = 2; m.mc = 0; m.mv = 0;
    m.explicit_kinematics = 1; m.accel = accel;
    m.q_ind = o_ind; m.q_dep = o_none; m.u_ind = o_ind; m.u_dep = o_none;
    m.mass_matrix = o_mass; m.forcing = o_forcing; m.kinematics = o_kin;
    m.rhs_terms = o_rhs_terms; m.constraints = NULL; m.constraint_jacobian = NULL;
    m.velocity_constraints = NULL; m.velocity_constraint_matrix = NULL;
    m.energy = NULL; m.lin_terms = o_lin;
    m.mass_solve = accel == GEN_RT_ACCEL_LDLT ? o_solve : NULL;
    m.na = 0; m.auxiliary = NULL; m.accel_terms = NULL;
    m.rhs_solve = accel == GEN_RT_ACCEL_LDLT ? o_rhs_solve : NULL;
    m.reaction_solve = NULL;
    m.ny = 0; m.outputs = NULL; m.output_jacobian = NULL; m.hybrid = NULL;
    return m;
}

/* ------------------------------------------------------------- helpers */
#define DIMS_P(acc) 2, 2, 1, 1, 0, 1, acc
#define DIMS_O(acc) 1, 1, 0, 0, 1, 1, acc
#define W(f, ...) f(__VA_ARGS__) /* expands DIMS_* into the macro arguments */
#define BIG 4096

static gen_rt_real work[BIG + GUARD];
static int iwork[256 + GUARD];

/* fill the work arrays, put guards right after n (reals) and ni (ints) */
static void guard(int n, int ni)
{
    int i;
    for (i = 0; i < BIG + GUARD; ++i) work[i] = GEN_RT_C(12345.0);
    for (i = 0; i < 256 + GUARD; ++i) iwork[i] = 12345;
    CHECK(n < BIG && ni < 256);
}

static void guards_intact(int n, int ni)
{
    int i, ok = 1;
    for (i = n; i < n + GUARD; ++i) ok = ok && work[i] == GEN_RT_C(12345.0);
    for (i = ni; i < ni + GUARD; ++i) ok = ok && iwork[i] == 12345;
    CHECK(ok);
}

static void pendulum_tests(int accel)
{
    const gen_rt_model m = pend_model(accel);
    const gen_rt_real p[3] = {PM, PG, PL};
    const double th = 0.4;
    gen_rt_real x[4], dx[4], lam[1], E0, E1;
    int st, n, ni, k;

    /* consistent state: x from y (Newton), x' from y' (linear) */
    x[0] = GEN_RT_C(1.0); x[1] = (gen_rt_real)(PL * sin(th)); x[2] = 0; x[3] = GEN_RT_C(0.3);
    n = W(GEN_RT_MODEL_CONSISTENT_WORK, DIMS_P(0)); ni = W(GEN_RT_MODEL_CONSISTENT_IWORK, DIMS_P(0));
    guard(n, ni);
    st = gen_rt_model_consistent_state(&m, 0, p, 0, 0, work, iwork, x);
    CHECK_INT(st, GEN_RT_OK);
    guards_intact(n, ni);
    CHECK_NEAR(x[0], PL * cos(th), TOL(1e-13, 1e-5));
    CHECK_NEAR(x[0] * x[2] + x[1] * x[3], 0, TOL(1e-13, 1e-5));

    /* at rest at angle th: u' = g sin(th) along the tangent (-sin, cos) */
    x[2] = 0; x[3] = 0;
    n = W(GEN_RT_MODEL_EVAL_RHS_WORK, DIMS_P(accel)); ni = W(GEN_RT_MODEL_EVAL_RHS_IWORK, DIMS_P(accel));
    guard(n, ni);
    st = gen_rt_model_eval_rhs(&m, 0, x, NULL, p, work, iwork, dx, lam);
    CHECK_INT(st, GEN_RT_OK);
    guards_intact(n, ni);
    CHECK_NEAR(dx[2], -PG * sin(th) * -sin(th), TOL(1e-12, 1e-4));
    CHECK_NEAR(dx[3], -PG * sin(th) * cos(th), TOL(1e-12, 1e-4));
    /* the tension: m u' = f + A^T lam with A = [x, y]: lam = -m g cos(th) / L */
    CHECK_NEAR(lam[0], -PM * PG * cos(th) / PL, TOL(1e-12, 1e-4));

    /* linearization at the hanging state: [[0, 1], [-g/L, 0]] on [y, y'] */
    {
        gen_rt_real xop[4] = {PL, 0, 0, 0}, Al[4], Bl[1];
        n = W(GEN_RT_MODEL_LINEARIZE_WORK, DIMS_P(accel));
        ni = W(GEN_RT_MODEL_LINEARIZE_IWORK, DIMS_P(accel));
        guard(n, ni);
        st = gen_rt_model_linearize(&m, xop, NULL, p, 0, work, iwork, Al, Bl);
        CHECK_INT(st, GEN_RT_OK);
        guards_intact(n, ni);
        CHECK_NEAR(Al[0], 0, TOL(1e-13, 1e-5));
        CHECK_NEAR(Al[1], 1, TOL(1e-13, 1e-5));
        CHECK_NEAR(Al[2], -PG / PL, TOL(1e-12, 1e-4));
        CHECK_NEAR(Al[3], 0, TOL(1e-13, 1e-5));
    }

    /* projection: onto the circle and the tangent, and idempotent */
    {
        gen_rt_real y[4] = {PL * 0.9, PL * 0.5, 0.2, 0.1}, z[4];
        n = W(GEN_RT_MODEL_PROJECT_WORK, DIMS_P(accel));
        guard(n, 0);
        st = gen_rt_model_project(&m, 0, p, 0, 0, work, y);
        CHECK_INT(st, GEN_RT_OK);
        guards_intact(n, 0);
        CHECK_NEAR(y[0] * y[0] + y[1] * y[1], PL * PL, TOL(1e-13, 1e-5));
        CHECK_NEAR(y[0] * y[2] + y[1] * y[3], 0, TOL(1e-13, 1e-5));
        for (k = 0; k < 4; ++k) z[k] = y[k];
        st = gen_rt_model_project(&m, 0, p, 0, 0, work, z);
        CHECK_INT(st, GEN_RT_OK);
        for (k = 0; k < 4; ++k) CHECK_NEAR(z[k], y[k], TOL(1e-14, 1e-6));
    }

    /* simulate 2 s, RK4 + projection: energy and the constraint hold */
    {
        static gen_rt_real t_out[201], x_out[201 * 4], lam_out[201];
        gen_rt_real last[4];
        gen_rt_sim_options o;
        gen_rt_sim_stats s;
        o.method = GEN_RT_METHOD_RK4; o.project = 1; o.rtol = GEN_RT_C(1e-8);
        o.atol = GEN_RT_C(1e-10); o.h_init = 0; o.h_min = 0; o.h_max = 0;
        o.max_steps = 100000L; o.proj_tol = 0; o.proj_max_iter = 10;
        o.every = 1; o.final_only = 0; o.cancel = NULL;
        s.x_last = last;
        x[0] = (gen_rt_real)(PL * cos(1.0)); x[1] = (gen_rt_real)(PL * sin(1.0));
        x[2] = 0; x[3] = 0;
        p_energy(x, x + 2, p, 0, &E0);
        n = W(GEN_RT_MODEL_SIMULATE_WORK, DIMS_P(accel));
        ni = W(GEN_RT_MODEL_SIMULATE_IWORK, DIMS_P(accel));
        guard(n, ni);
        st = gen_rt_model_simulate(&m, x, 0, 2, GEN_RT_C(0.01), NULL, p, &o, 201, work, iwork,
                                   t_out, x_out, lam_out, &s);
        CHECK_INT(st, GEN_RT_OK);
        guards_intact(n, ni);
        CHECK_INT(s.n_out, 201);
        CHECK_NEAR(t_out[200], 2, 0);
        p_energy(x_out + 800, x_out + 802, p, 0, &E1);
        CHECK_NEAR(E1, E0, TOL(1e-7, 1e-3) * fabs(E0));
        CHECK_NEAR(x_out[800] * x_out[800] + x_out[801] * x_out[801], PL * PL, TOL(1e-13, 1e-5));
        /* the rows are the state: row 0 is x0 */
        CHECK_NEAR(x_out[0], x[0], 0);
        /* too small a buffer */
        st = gen_rt_model_simulate(&m, x, 0, 2, GEN_RT_C(0.01), NULL, p, &o, 200, work, iwork,
                                   t_out, x_out, NULL, &s);
        CHECK_INT(st, GEN_RT_ERR_OUTPUT_FULL);
        /* the caller's cancellation flag: set, the run stops before its first
         * step (RK4 and DOPRI5) with ERR_CANCELLED, row 0 written and x0 as
         * the last good state; clear, the run is the one above bit for bit */
        {
            static gen_rt_real t_c[201], x_c[201 * 4];
            volatile int stop = 1;
            int meth;
            o.cancel = &stop;
            for (meth = 0; meth < 2; ++meth) {
                o.method = meth == 0 ? GEN_RT_METHOD_RK4 : GEN_RT_METHOD_DOPRI5;
                st = gen_rt_model_simulate(&m, x, 0, 2, GEN_RT_C(0.01), NULL, p, &o, 201, work,
                                           iwork, t_c, x_c, NULL, &s);
                CHECK_INT(st, GEN_RT_ERR_CANCELLED);
                CHECK_INT(s.n_out, 1);
                CHECK_NEAR(s.t_last, 0, 0);
                CHECK_NEAR(s.x_last[0], x[0], 0);
                CHECK_NEAR(s.x_last[1], x[1], 0);
                for (k = 0; k < 4; ++k) last[k] = x[k];
                st = gen_rt_model_advance(&m, 0, 1, NULL, p, &o, work, iwork, &s, last);
                CHECK_INT(st, GEN_RT_ERR_CANCELLED);
                CHECK_NEAR(last[0], x[0], 0);
            }
            stop = 0;
            o.method = GEN_RT_METHOD_RK4;
            st = gen_rt_model_simulate(&m, x, 0, 2, GEN_RT_C(0.01), NULL, p, &o, 201, work,
                                       iwork, t_c, x_c, NULL, &s);
            CHECK_INT(st, GEN_RT_OK);
            for (k = 0; k < 4; ++k) CHECK_NEAR(x_c[800 + k], x_out[800 + k], 0);
            o.cancel = NULL;
        }
        /* DOPRI5 to the same end: agrees with RK4 at h = 0.01 to its error */
        o.method = GEN_RT_METHOD_DOPRI5; o.rtol = (gen_rt_real)TOL(1e-10, 1e-5);
        o.atol = (gen_rt_real)TOL(1e-12, 1e-6);
        st = gen_rt_model_simulate(&m, x, 0, 2, GEN_RT_C(0.5), NULL, p, &o, 201, work, iwork,
                                   t_out, x_out + 4 * 4, NULL, &s);
        CHECK_INT(st, GEN_RT_OK);
        CHECK_NEAR(x_out[4 * 4 + 4 * 4 + 1], x_out[801], TOL(1e-7, 1e-3));
    }

    /* a singular partition: x = 0 makes A_dep = [x] zero (Kane form only) */
    if (accel == GEN_RT_ACCEL_PARTITIONED) {
        gen_rt_real xs[4] = {0, PL, 0, 0};
        st = gen_rt_model_eval_rhs(&m, 0, xs, NULL, p, work, iwork, dx, NULL);
        CHECK_INT(st, GEN_RT_ERR_SINGULAR);
    }
}

static void oscillator_tests(int accel)
{
    const gen_rt_model m = osc_model(accel);
    const gen_rt_real p[2] = {PM, PK}, r[1] = {0};
    const double w = sqrt(PK / PM);
    gen_rt_real x[2], E[1], Al[4], Bl[2];
    double err1, err2;
    int st, k, n, ni;

    /* RK4 order: error at t = 1 with h and h/2 */
    n = W(GEN_RT_MODEL_STEP_WORK, DIMS_O(accel)); ni = W(GEN_RT_MODEL_STEP_IWORK, DIMS_O(accel));
    guard(n, ni);
    x[0] = 1; x[1] = 0;
    for (k = 0; k < 20; ++k) {
        st = gen_rt_model_step_rk4(&m, GEN_RT_C(0.05) * k, GEN_RT_C(0.05), r, p, 1, work, iwork, x);
        CHECK_INT(st, GEN_RT_OK);
    }
    guards_intact(n, ni);
    err1 = fabs(x[0] - cos(w));
    x[0] = 1; x[1] = 0;
    for (k = 0; k < 40; ++k)
        gen_rt_model_step_rk4(&m, GEN_RT_C(0.025) * k, GEN_RT_C(0.025), r, p, 1, work, iwork, x);
    err2 = fabs(x[0] - cos(w));
    if (!TEST_IS_FLOAT) CHECK_NEAR(err1 / err2, 16, 2);

    /* DOPRI5 through advance: cos(w t) to its tolerance, stats add up */
    {
        gen_rt_real last[2];
        gen_rt_sim_options o;
        gen_rt_sim_stats s;
        o.method = GEN_RT_METHOD_DOPRI5; o.project = 1; o.rtol = GEN_RT_C(1e-10);
        o.atol = GEN_RT_C(1e-12); o.h_init = 0; o.h_min = 0; o.h_max = 0;
        o.max_steps = 100000L; o.proj_tol = 0; o.proj_max_iter = 10;
        o.every = 1; o.final_only = 0; o.cancel = NULL;
        s.n_accepted = 0; s.n_rejected = 0; s.n_rhs = 0; s.n_out = 0; s.t_last = 0;
        s.h_next = 0; s.x_last = last;
        x[0] = 1; x[1] = 0;
        n = W(GEN_RT_MODEL_ADVANCE_WORK, DIMS_O(accel));
        ni = W(GEN_RT_MODEL_ADVANCE_IWORK, DIMS_O(accel));
        guard(n, ni);
        st = gen_rt_model_advance(&m, 0, 3, r, p, &o, work, iwork, &s, x);
        CHECK_INT(st, GEN_RT_OK);
        guards_intact(n, ni);
        CHECK_NEAR(x[0], cos(3 * w), TOL(1e-8, 1e-3));
        CHECK_NEAR(x[1], -w * sin(3 * w), TOL(1e-8, 1e-3));
        CHECK(s.n_rhs >= 6 * s.n_accepted);
        CHECK_NEAR(s.t_last, 3, 0);
        CHECK_NEAR(last[0], x[0], 0);
        /* backwards time is a bad argument */
        CHECK_INT(gen_rt_model_advance(&m, 3, 2, r, p, &o, work, iwork, &s, x), GEN_RT_ERR_BAD_ARG);
        o.method = 7;
        CHECK_INT(gen_rt_model_advance(&m, 0, 1, r, p, &o, work, iwork, &s, x), GEN_RT_ERR_BAD_ARG);
    }

    /* linearization: [[0, 1], [-k/m, 0]], B = [0, 1/m] */
    x[0] = GEN_RT_C(0.3); x[1] = GEN_RT_C(-0.2);
    n = W(GEN_RT_MODEL_LINEARIZE_WORK, DIMS_O(accel));
    ni = W(GEN_RT_MODEL_LINEARIZE_IWORK, DIMS_O(accel));
    guard(n, ni);
    st = gen_rt_model_linearize(&m, x, r, p, 0, work, iwork, Al, Bl);
    CHECK_INT(st, GEN_RT_OK);
    guards_intact(n, ni);
    CHECK_NEAR(Al[2], -PK / PM, TOL(1e-13, 1e-5));
    CHECK_NEAR(Bl[1], 1 / PM, TOL(1e-13, 1e-5));

    /* what the model does not have */
    CHECK_INT(gen_rt_model_eval_energy(&m, x, x + 1, p, 0, E), GEN_RT_ERR_BAD_ARG);
    CHECK_NEAR(E[0], 0, 0);
    CHECK_INT(gen_rt_model_eval_constraints(&m, x, p, 0, E), GEN_RT_OK);
    CHECK_INT(gen_rt_model_project(&m, 0, p, 0, 0, work, x), GEN_RT_OK);
    /* a zero mass: singular, whichever solver */
    {
        const gen_rt_real p0[2] = {0, PK};
        gen_rt_real dx[2];
        st = gen_rt_model_eval_rhs(&m, 0, x, r, p0, work, iwork, dx, NULL);
        CHECK_INT(st, GEN_RT_ERR_SINGULAR);
    }
}

/* gen_rt_model_eval_auxiliary_forces: u' from the right-hand side, then
 * F R = -g; closed form R = -F^-1 g with F^-1 = [[3, -1], [-1, 2]] / 5 */
static void auxiliary_tests(int accel)
{
    gen_rt_model m = osc_model(accel);
    const gen_rt_real p[2] = {PM, PK}, r[1] = {GEN_RT_C(0.7)};
    const double xq = 0.3, g0 = -PK * xq + 0.7, g1 = xq;
    gen_rt_real x[2], R[2];
    int st, n, ni;
    x[0] = (gen_rt_real)xq; x[1] = GEN_RT_C(-0.2);
    /* a model without auxiliary speeds: OK, nothing written */
    R[0] = 7; R[1] = 7;
    st = gen_rt_model_eval_auxiliary_forces(&m, 0, x, r, p, work, iwork, R);
    CHECK_INT(st, GEN_RT_OK);
    CHECK(R[0] == 7 && R[1] == 7);
    CHECK_INT(W(GEN_RT_MODEL_AUX_WORK, DIMS_O(accel), 0), 1);
    m.na = 2; m.auxiliary = o_aux;
    n = W(GEN_RT_MODEL_AUX_WORK, DIMS_O(accel), 2);
    ni = W(GEN_RT_MODEL_AUX_IWORK, DIMS_O(accel), 2);
    guard(n, ni);
    st = gen_rt_model_eval_auxiliary_forces(&m, 0, x, r, p, work, iwork, R);
    CHECK_INT(st, GEN_RT_OK);
    guards_intact(n, ni);
    CHECK_NEAR(R[0], -(3 * g0 - g1) / 5, TOL(1e-14, 1e-6));
    CHECK_NEAR(R[1], -(-g0 + 2 * g1) / 5, TOL(1e-14, 1e-6));
    /* singular F: the reactions cannot be solved for (ERR_SINGULAR_REACTIONS) */
    x[0] = 200;
    R[0] = 7;
    st = gen_rt_model_eval_auxiliary_forces(&m, 0, x, r, p, work, iwork, R);
    CHECK_INT(st, GEN_RT_ERR_SINGULAR_REACTIONS);
    CHECK(R[0] == 7);
}

/* gen_rt_model_simulate_input: a C controller closes the loop. On the
 * oscillator m x'' = -k x + r, the damping law r = -c x' (continuous) gives
 * x(t) = e^{-z t} (cos(wd t) + z/wd sin(wd t)), z = c / 2m, wd^2 = k/m - z^2;
 * the same law sampled every 2 dt equals a loop of RK4 steps with r held. */
typedef struct { gen_rt_real c; long calls; } damper;

static int damp_law(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *r)
{
    damper *d = (damper *)ctx;
    (void)t;
    d->calls += 1;
    r[0] = -d->c * x[1];
    return 0;
}

static int failing_law(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *r)
{
    (void)ctx; (void)x; (void)r;
    return t > GEN_RT_C(0.5);
}

static void controller_tests(int accel)
{
    gen_rt_model m = osc_model(accel);
    const gen_rt_real p[2] = {PM, PK};
    const double c = 0.6, z = c / (2 * PM), wd = sqrt(PK / PM - z * z);
    gen_rt_real x0[2], t_out[101], x_out[202], r_out[101], x[2], xs[2];
    gen_rt_sim_options o;
    gen_rt_sim_stats s;
    gen_rt_input in;
    damper d;
    int st, k, n, ni;
    x0[0] = 1; x0[1] = 0;
    o.method = GEN_RT_METHOD_RK4; o.project = 0; o.rtol = GEN_RT_C(1e-8); o.atol = GEN_RT_C(1e-10);
    o.h_init = 0; o.h_min = 0; o.h_max = 0; o.max_steps = 1000; o.proj_tol = 0; o.proj_max_iter = 0;
    o.every = 1; o.final_only = 0; o.cancel = NULL;
    s.x_last = x;
    memset(&in, 0, sizeof in);
    d.c = (gen_rt_real)c; d.calls = 0;
    in.controller = damp_law; in.ctx = &d;
    n = W(GEN_RT_MODEL_SIMULATE_INPUT_WORK, DIMS_O(accel));
    ni = W(GEN_RT_MODEL_SIMULATE_INPUT_IWORK, DIMS_O(accel));
    guard(n, ni);
    st = gen_rt_model_simulate_input(&m, x0, 0, 1, GEN_RT_C(0.01), &in, p, &o, 101, work, iwork,
                                     t_out, x_out, NULL, r_out, &s);
    CHECK_INT(st, GEN_RT_OK);
    guards_intact(n, ni);
    CHECK_INT(s.n_out, 101);
    CHECK_NEAR(x_out[200], exp(-z) * (cos(wd) + z / wd * sin(wd)), TOL(1e-8, 1e-5));
    CHECK_NEAR(r_out[100], -c * x_out[201], TOL(1e-15, 1e-6));
    CHECK(d.calls >= 400);                       /* every stage, and every row */
    /* sampled every 2 dt: RK4 steps with the input computed at the sample */
    in.period = GEN_RT_C(0.02);
    d.calls = 0;
    st = gen_rt_model_simulate_input(&m, x0, 0, 1, GEN_RT_C(0.01), &in, p, &o, 101, work, iwork,
                                     t_out, x_out, NULL, r_out, &s);
    CHECK_INT(st, GEN_RT_OK);
    CHECK_INT((int)d.calls, 51);                 /* once per sample, t = 0, 0.02, ..., 1 */
    xs[0] = x0[0]; xs[1] = x0[1];
    for (k = 0; k < 100; ++k) {
        gen_rt_real r1[1];
        if (k % 2 == 0) r1[0] = (gen_rt_real)(-c) * xs[1];
        else r1[0] = r_out[k - 1];
        CHECK_NEAR(r_out[k], r1[0], TOL(1e-15, 1e-6));
        st = gen_rt_model_step_rk4(&m, (gen_rt_real)k * GEN_RT_C(0.01), GEN_RT_C(0.01), r1, p, 0,
                                   work, iwork, xs);
        CHECK_INT(st, GEN_RT_OK);
        CHECK_NEAR(x_out[2 * (k + 1)], xs[0], TOL(1e-15, 1e-6));
    }
    /* a failing controller stops the run, naming it */
    in.controller = failing_law;
    in.period = 0;
    st = gen_rt_model_simulate_input(&m, x0, 0, 1, GEN_RT_C(0.01), &in, p, &o, 101, work, iwork,
                                     t_out, x_out, NULL, NULL, &s);
    CHECK_INT(st, GEN_RT_ERR_CONTROLLER);
    CHECK(s.n_out >= 50 && s.n_out <= 52 && s.t_last <= GEN_RT_C(0.51));
    /* a table that is not increasing is a bad argument */
    {
        const gen_rt_real tt[3] = {0, 1, 1}, rr[3] = {0, 1, 2};
        memset(&in, 0, sizeof in);
        in.n_table = 3; in.t_table = tt; in.r_table = rr;
        st = gen_rt_model_simulate_input(&m, x0, 0, 1, GEN_RT_C(0.01), &in, p, &o, 101, work,
                                         iwork, t_out, x_out, NULL, NULL, &s);
        CHECK_INT(st, GEN_RT_ERR_BAD_ARG);
    }
    /* a gain schedule: row k (K, x_op, r) from t_gain + k dt_gain on, row 0
     * before, the last after; continuous, the rows' starts are step ends */
    {
        const gen_rt_real K[6] = {1, 2, 3, 4, 5, 6}, xo[6] = {1, 0, 0, 1, 2, 0};
        const gen_rt_real rb[3] = {10, 20, 30};
        const gen_rt_real ts[6] = {-1, 0.25, 0.5, 0.7499, 0.75, 9};
        const int rows[6] = {0, 0, 1, 1, 2, 2};
        gen_rt_real xe[2] = {GEN_RT_C(0.5), GEN_RT_C(-0.25)}, r1[1];
        memset(&in, 0, sizeof in);
        in.K = K; in.x_op = xo; in.r = rb;
        in.n_gain = 3; in.t_gain = GEN_RT_C(0.25); in.dt_gain = GEN_RT_C(0.25);
        for (k = 0; k < 6; ++k) {
            int g = rows[k];
            st = gen_rt_model_eval_input(&m, ts[k], xe, &in, r1);
            CHECK_INT(st, GEN_RT_OK);
            CHECK_NEAR(r1[0], rb[g] - K[2 * g] * (xe[0] - xo[2 * g])
                       - K[2 * g + 1] * (xe[1] - xo[2 * g + 1]), TOL(1e-15, 1e-6));
        }
        st = gen_rt_model_simulate_input(&m, x0, 0, 1, GEN_RT_C(0.01), &in, p, &o, 101, work,
                                         iwork, t_out, x_out, NULL, r_out, &s);
        CHECK_INT(st, GEN_RT_OK);
        for (k = 0; k <= 100; k += 25) {         /* rows at 0, 0.25, 0.5, 0.75, 1 */
            int g = k < 50 ? 0 : (k < 75 ? 1 : 2);
            CHECK_NEAR(r_out[k], rb[g] - K[2 * g] * (x_out[2 * k] - xo[2 * g])
                       - K[2 * g + 1] * (x_out[2 * k + 1] - xo[2 * g + 1]), TOL(1e-13, 1e-5));
        }
        {                                        /* bounds clip the law */
            const gen_rt_real lo[1] = {-1}, hi[1] = {GEN_RT_C(2.5)}, bad[1] = {-2};
            in.r_min = lo; in.r_max = hi;
            CHECK_INT(gen_rt_model_eval_input(&m, GEN_RT_C(0.3), xe, &in, r1), GEN_RT_OK);
            CHECK_NEAR(r1[0], 2.5, 0);           /* 20 - 3 * (0.5 - 0) - 4 * (-0.25 - 1) */
            in.r_max = bad;                      /* r_min > r_max */
            CHECK_INT(gen_rt_model_eval_input(&m, GEN_RT_C(0.3), xe, &in, r1), GEN_RT_ERR_BAD_ARG);
            in.r_min = NULL; in.r_max = NULL;
        }
        in.dt_gain = 0;                          /* a schedule needs dt_gain > 0 */
        CHECK_INT(gen_rt_model_eval_input(&m, 0, xe, &in, r1), GEN_RT_ERR_BAD_ARG);
        in.dt_gain = GEN_RT_C(0.25); in.n_gain = -1;
        CHECK_INT(gen_rt_model_eval_input(&m, 0, xe, &in, r1), GEN_RT_ERR_BAD_ARG);
    }
}

int main(void)
{
    controller_tests(GEN_RT_ACCEL_LDLT);
    controller_tests(GEN_RT_ACCEL_LU);
    auxiliary_tests(GEN_RT_ACCEL_LDLT);
    auxiliary_tests(GEN_RT_ACCEL_LU);
    pendulum_tests(GEN_RT_ACCEL_KKT);
    pendulum_tests(GEN_RT_ACCEL_PARTITIONED);
    oscillator_tests(GEN_RT_ACCEL_LDLT);
    oscillator_tests(GEN_RT_ACCEL_LU);
    CHECK_INT(gen_rt_simulate_rows(0, 1, GEN_RT_C(0.1)), 11);
    CHECK_INT(gen_rt_simulate_rows(0, 1, GEN_RT_C(0.3)), 5);
    CHECK_INT(gen_rt_simulate_rows(0, 1, 0), GEN_RT_ERR_BAD_ARG);
    TEST_END();
}
