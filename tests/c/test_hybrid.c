/* test_hybrid.c - the hybrid runtime (gen_rt_hybrid.c) on a point mass in
 * the plane (x, y; mass PM, gravity -PG along y) with two gaps, the floor
 * y >= 0 and the wall x >= 0: the impulse of one gap and of two closing
 * together against the reflection computed by hand, the contact held as a
 * constraint (its force m g), the Zeno rule and a lift-off in
 * gen_rt_hybrid_jump, a reset map and the argument checks of the work
 * macros' layout; the engine's start (a refused start inside a gap, a
 * contact held from t0), a step across a guard and a map that is not
 * finite. */
#include "test_common.h"

#define PM 1.5
#define TS (TEST_IS_FLOAT ? 1e9 : 1.0)   /* tolerances scaled for float */
#define PG 9.81

static void p_mass(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t, gen_rt_real *M)
{
    (void)q; (void)p; (void)t;
    M[0] = PM; M[1] = 0; M[2] = 0; M[3] = PM;
}

static void p_forcing(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                      const gen_rt_real *p, gen_rt_real t, gen_rt_real *f)
{
    (void)q; (void)u; (void)r; (void)p; (void)t;
    f[0] = 0; f[1] = -PM * PG;
}

static void p_kin(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                  gen_rt_real t, gen_rt_real *Kqd, gen_rt_real *qd)
{
    (void)q; (void)p; (void)t; (void)Kqd;
    qd[0] = u[0]; qd[1] = u[1];
}

static void p_rhs_terms(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                        const gen_rt_real *p, gen_rt_real t, gen_rt_real *Kqd, gen_rt_real *qd,
                        gen_rt_real *M, gen_rt_real *f, gen_rt_real *A, gen_rt_real *a)
{
    (void)A; (void)a;
    p_kin(q, u, p, t, Kqd, qd);
    p_mass(q, p, t, M);
    p_forcing(q, u, r, p, t, f);
}

/* declarations: 0 the floor y, 1 the wall x (impacts), 2 a reset when x
 * crosses 5 upwards: x -> x - 10 */
static void h_values(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                     gen_rt_real t, gen_rt_real *g)
{
    (void)u; (void)p; (void)t;
    g[0] = q[1]; g[1] = q[0]; g[2] = q[0] - 5;
}

static void h_jacobian(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                       gen_rt_real *W, gen_rt_real *w)
{
    int i;
    (void)q; (void)p; (void)t;
    for (i = 0; i < 6; ++i) W[i] = 0;
    W[0 * 2 + 1] = 1; W[1 * 2 + 0] = 1;
    w[0] = w[1] = w[2] = 0;
}

static void h_bias(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                   gen_rt_real t, gen_rt_real *h)
{
    (void)q; (void)u; (void)p; (void)t;
    h[0] = h[1] = h[2] = 0;
}

static void h_reset(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                    gen_rt_real t, gen_rt_real *xr)
{
    (void)p; (void)t;
    xr[0] = q[0] - 10; xr[1] = q[1]; xr[2] = u[0]; xr[3] = u[1];
}

static const int h_kind[3] = { GEN_RT_HYBRID_IMPACT, GEN_RT_HYBRID_IMPACT, GEN_RT_HYBRID_RESET };
static const int h_dir[3] = { -1, -1, 1 };
static const int h_ridx[3] = { -1, -1, 0 };
static const gen_rt_real h_e[3] = { GEN_RT_C(0.5), GEN_RT_C(0.75), 0 };
static const gen_rt_real h_rest[3] = { GEN_RT_C(1e-3), GEN_RT_C(1e-3), 0 };
static const int ind2[2] = { 0, 1 };

static gen_rt_model point_model(const gen_rt_hybrid *hy)
{
    gen_rt_model m;
    memset(&m, 0, sizeof m);   /* every kernel the point has not: NULL */
    m.nq = 2; m.nu = 2; m.nr = 0; m.np = 0; m.mc = 0; m.mv = 0;
    m.explicit_kinematics = 1; m.accel = GEN_RT_ACCEL_LU;
    m.q_ind = ind2; m.q_dep = ind2; m.u_ind = ind2; m.u_dep = ind2;
    m.mass_matrix = p_mass; m.forcing = p_forcing; m.kinematics = p_kin;
    m.rhs_terms = p_rhs_terms; m.constraints = NULL; m.constraint_jacobian = NULL;
    m.velocity_constraints = NULL; m.velocity_constraint_matrix = NULL;
    m.energy = NULL; m.lin_terms = NULL; m.mass_solve = NULL;
    m.na = 0; m.auxiliary = NULL; m.accel_terms = NULL; m.rhs_solve = NULL;
    m.ny = 0; m.outputs = NULL; m.output_jacobian = NULL;
    m.hybrid = hy;
    return m;
}

#define NH 3
static gen_rt_real work[GEN_RT_HYBRID_WORK(2, 2, 0, NH)];
static int iwork[GEN_RT_HYBRID_IWORK(2, 2, 0, NH)];

/* a run of the engine (simulate_events, no user events) from x0 to t_end
 * with RK4 on a grid of dt: its status, the log (which, t, x, x after) */
#define SW GEN_RT_MODEL_SIMULATE_EVENTS_WORK(2, 2, 0, 0, 0, 1, GEN_RT_ACCEL_LU, 0)
#define SIW GEN_RT_MODEL_SIMULATE_EVENTS_IWORK(2, 2, 0, 0, 0, 1, GEN_RT_ACCEL_LU, 0)
#define CAP 8
static gen_rt_real s_work[SW], s_t[64], s_x[64 * 4], s_lt[CAP], s_lx[CAP * 4], s_la[CAP * 4];
static int s_iwork[SIW], s_lw[CAP];
static gen_rt_real s_last[4];

static int run(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t_end,
               gen_rt_real dt, gen_rt_sim_stats *s)
{
    gen_rt_input in;
    gen_rt_events ev;
    gen_rt_sim_options o;
    memset(&in, 0, sizeof in);
    memset(&ev, 0, sizeof ev);
    memset(&o, 0, sizeof o);
    o.method = GEN_RT_METHOD_RK4;
    o.project = 1;
    o.rtol = GEN_RT_C(1e-8);
    o.atol = GEN_RT_C(1e-10);
    o.max_steps = 1000;
    o.proj_tol = 16 * GEN_RT_EPS;
    o.proj_max_iter = 10;
    ev.capacity = CAP;
    ev.log_which = s_lw; ev.log_t = s_lt; ev.log_x = s_lx; ev.log_x_after = s_la;
    ev.hybrid_work = work;
    ev.hybrid_iwork = iwork;
    s->x_last = s_last;
    return gen_rt_model_simulate_events(m, x0, 0, t_end, dt, &in, &ev, NULL, &o, 64, s_work,
                                        s_iwork, s_t, s_x, NULL, NULL, s);
}

/* a reset whose map is NaN where x > 7 (the reset of x crossing 5 upwards) */
static void h_reset_nan(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                        gen_rt_real t, gen_rt_real *xr)
{
    h_reset(q, u, p, t, xr);
    xr[2] = (gen_rt_real)sqrt(-1.0 - (double)u[0] * 0);
}

/* the start of a run: a gap below zero (or a guard inside its region) is
 * refused with its declaration logged; a gap at zero and at rest is held
 * from t0 (the point rests on the floor), at zero and closing an impact at
 * t0; a step across a guard (gen_rt_hybrid_crossed); a map that is not
 * finite, logged with the map's values */
static void starts(gen_rt_model *m)
{
    gen_rt_hybrid hy = *m->hybrid;
    gen_rt_real x[4], x1[4], g[2 * NH];
    gen_rt_sim_stats s;
    int which = 7, k;
    x[0] = 2; x[1] = -0.5; x[2] = 0; x[3] = 0;
    CHECK_INT(gen_rt_model_eval_hybrid(m, 0, x, NULL, g), GEN_RT_OK);
    CHECK_NEAR(g[0], -0.5, 0);
    CHECK_NEAR(g[1], 2, 0);
    CHECK_NEAR(g[2], -3, 0);
    CHECK_INT(gen_rt_hybrid_penetrated(m, 0, x, NULL, g, &which), GEN_RT_ERR_PENETRATED);
    CHECK_INT(which, 0);
    CHECK_INT(run(m, x, GEN_RT_C(0.5), GEN_RT_C(0.1), &s), GEN_RT_ERR_PENETRATED);
    CHECK_INT(s.n_events, 1);
    CHECK_INT(s_lw[0], 0);
    CHECK_NEAR(s_lx[1], -0.5, 0);
    CHECK_INT(s.n_out, 0);
    /* the reset's guard x - 5 inside its region (above zero, direction +1) */
    x[0] = 6; x[1] = 1;
    CHECK_INT(gen_rt_hybrid_penetrated(m, 0, x, NULL, g, &which), GEN_RT_ERR_PENETRATED);
    CHECK_INT(which, 2);
    CHECK_NEAR(g[2], 1, 0);
    /* on the floor and the wall's open side, below the guard: a start */
    x[0] = 2; x[1] = 0;
    CHECK_INT(gen_rt_hybrid_penetrated(m, 0, x, NULL, g, &which), GEN_RT_OK);
    CHECK_INT(which, -1);
    /* at rest on the floor: held from t0, the rows stay on it */
    CHECK_INT(run(m, x, GEN_RT_C(0.5), GEN_RT_C(0.1), &s), GEN_RT_OK);
    CHECK_INT(s.n_out, 6);
    CHECK_INT(s.n_events, 2);
    CHECK_INT(s_lw[0], 0);            /* the impact at t0 */
    CHECK_INT(s_lw[1], 2 * NH + 0);   /* the floor held from then on */
    CHECK_NEAR(s_lt[1], 0, 0);
    for (k = 0; k < 6; ++k) {
        CHECK_NEAR(s_x[4 * k + 1], 0, 1e-14 * TS);
        CHECK_NEAR(s_x[4 * k + 3], 0, 1e-14 * TS);
    }
    /* at zero and closing: the impact at t0 (e = 0.5) */
    x[3] = -2;
    CHECK_INT(run(m, x, GEN_RT_C(0.1), GEN_RT_C(0.1), &s), GEN_RT_OK);
    CHECK_INT(s_lw[0], 0);
    CHECK_NEAR(s_la[3], 1, 1e-14 * TS);
    CHECK_NEAR(s_x[3], 1, 1e-14 * TS);  /* row 0: the state after it */
    /* steps across a declaration, from strictly before to strictly past */
    x[0] = 4; x[1] = 1; x[2] = x[3] = 0;
    x1[0] = 6; x1[1] = 1; x1[2] = x1[3] = 0;
    CHECK_INT(gen_rt_hybrid_crossed(m, 0, x, 1, x1, NULL, g, &which), GEN_RT_ERR_GUARD_CROSSED);
    CHECK_INT(which, 2);
    CHECK_NEAR(g[NH + 2], 1, 0);
    x1[0] = 5;                         /* ends on the guard: the phase's last step */
    CHECK_INT(gen_rt_hybrid_crossed(m, 0, x, 1, x1, NULL, g, &which), GEN_RT_OK);
    CHECK_INT(which, -1);
    x1[0] = 3;                         /* back, against its direction */
    CHECK_INT(gen_rt_hybrid_crossed(m, 0, x, 1, x1, NULL, g, &which), GEN_RT_OK);
    x1[0] = 4; x1[1] = -1;             /* through the floor */
    CHECK_INT(gen_rt_hybrid_crossed(m, 0, x, 1, x1, NULL, g, &which), GEN_RT_ERR_GUARD_CROSSED);
    CHECK_INT(which, 0);
    /* a map that is not finite: the run stops, the map's values logged */
    hy.reset = h_reset_nan;
    m->hybrid = &hy;
    x[0] = 4.9; x[1] = 100; x[2] = 2; x[3] = 0;
    CHECK_INT(run(m, x, GEN_RT_C(0.5), GEN_RT_C(0.1), &s), GEN_RT_ERR_NONFINITE_MODEL);
    CHECK_INT(s.n_events, 1);
    CHECK_INT(s_lw[0], 2);
    CHECK(s_la[2] != s_la[2]);         /* the map's u_x: NaN */
    CHECK_NEAR(s_la[0], s_lx[0] - 10, 1e-12 * TS);
    CHECK_NEAR(s_lx[0], 5, 1e-9 * TS);
}

int main(void)
{
    gen_rt_hybrid hy;
    gen_rt_model m;
    gen_rt_real x[4], e[NH], imp[NH], dx[4], lam[NH], v[NH], scratch[3 * NH];
    int rows[NH], active[NH] = { 0, 0, 0 }, what = -1, i;
    hy.n = NH; hy.kind = h_kind; hy.direction = h_dir; hy.reset_index = h_ridx;
    hy.restitution = h_e; hy.rest_speed = h_rest;
    hy.values = h_values; hy.jacobian = h_jacobian; hy.bias = h_bias; hy.reset = h_reset;
    m = point_model(&hy);

    /* the floor alone: u_y -> -e u_y, u_x kept, impulse m (1 + e) |u_y| */
    x[0] = 2; x[1] = 0; x[2] = 0.3; x[3] = -4;
    rows[0] = 1; rows[1] = 0; rows[2] = 0;
    e[0] = h_e[0]; e[1] = e[2] = 0;
    CHECK_INT(gen_rt_hybrid_impulse(&m, 0, NULL, rows, e, work, iwork, x, imp), GEN_RT_OK);
    CHECK_NEAR(x[2], 0.3, 1e-14 * TS);
    CHECK_NEAR(x[3], 2.0, 1e-14 * TS);
    CHECK_NEAR(imp[0], PM * 1.5 * 4, 1e-13 * TS);
    CHECK_NEAR(imp[1], 0, 0);

    /* both gaps closing together: each speed reflected with its own e */
    x[0] = 0; x[1] = 0; x[2] = -2; x[3] = -4;
    rows[0] = rows[1] = 1;
    e[0] = h_e[0]; e[1] = h_e[1];
    CHECK_INT(gen_rt_hybrid_impulse(&m, 0, NULL, rows, e, work, iwork, x, imp), GEN_RT_OK);
    CHECK_NEAR(x[2], 1.5, 1e-14 * TS);
    CHECK_NEAR(x[3], 2.0, 1e-14 * TS);

    /* a contact held: the floor's force is m g and the ball does not move */
    x[0] = 2; x[1] = 0; x[2] = 0; x[3] = 0;
    active[0] = 1;
    CHECK_INT(gen_rt_hybrid_rhs(&m, 0, x, NULL, NULL, active, work, iwork, dx, lam), GEN_RT_OK);
    CHECK_NEAR(dx[3], 0, 1e-13 * TS);
    CHECK_NEAR(lam[0], PM * PG, 1e-12 * TS);
    CHECK_NEAR(lam[1], 0, 0);
    CHECK_INT(gen_rt_hybrid_values(&m, 0, x, NULL, NULL, active, work, iwork, v), GEN_RT_OK);
    CHECK_NEAR(v[0], PM * PG, 1e-12 * TS);   /* the force, not the gap */
    CHECK_NEAR(v[1], 2, 0);

    /* the jump: a held contact is released (lift-off) */
    CHECK_INT(gen_rt_hybrid_jump(&m, 0, NULL, NULL, 0, 0, 0, NULL, active, rows, scratch, work,
                                 iwork, x, &what), GEN_RT_OK);
    CHECK_INT(what, GEN_RT_HYBRID_LIFTOFF);
    CHECK_INT(active[0], 0);

    /* a fast impact bounces; a slow one (below rest_speed) is held */
    x[0] = 2; x[1] = 0; x[2] = 0; x[3] = -3;
    CHECK_INT(gen_rt_hybrid_jump(&m, 0, NULL, NULL, 0, 0, 0, NULL, active, rows, scratch, work,
                                 iwork, x, &what), GEN_RT_OK);
    CHECK_INT(what, GEN_RT_HYBRID_IMPACT + 1);
    CHECK_NEAR(x[3], 1.5, 1e-14 * TS);
    CHECK_INT(active[0], 0);
    x[3] = -1e-4;
    CHECK_INT(gen_rt_hybrid_jump(&m, 0, NULL, NULL, 0, 0, 0, NULL, active, rows, scratch, work,
                                 iwork, x, &what), GEN_RT_OK);
    CHECK_INT(what, GEN_RT_HYBRID_IMPACT + 1);
    CHECK_NEAR(x[3], 0, 1e-15 * TS);
    CHECK_INT(active[0], 1);
    /* a gap opening fast is not an impact (grazing): nothing happens */
    active[0] = 0;
    x[3] = 1;
    CHECK_INT(gen_rt_hybrid_jump(&m, 0, NULL, NULL, 0, 0, 0, NULL, active, rows, scratch, work,
                                 iwork, x, &what), GEN_RT_OK);
    CHECK_INT(what, 0);
    CHECK_NEAR(x[3], 1, 0);

    /* the reset: x -> x - 10 */
    x[0] = 5; x[1] = 1; x[2] = 2; x[3] = 3;
    CHECK_INT(gen_rt_hybrid_jump(&m, 0, NULL, NULL, 2, 0, 0, NULL, active, rows, scratch, work,
                                 iwork, x, &what), GEN_RT_OK);
    CHECK_INT(what, GEN_RT_HYBRID_RESET + 1);
    CHECK_NEAR(x[0], -5, 0);
    for (i = 1; i < 4; ++i) CHECK_NEAR(x[i], (gen_rt_real)i, 0);
    /* an impact's index has no reset map */
    CHECK_INT(gen_rt_hybrid_reset(&m, 0, NULL, 0, 0, 0, NULL, work, x), GEN_RT_ERR_BAD_ARG);

    starts(&m);
    TEST_END();
}
