/* test_integrate.c - RK4 order, Dormand-Prince accuracy, step control,
 * callbacks and error paths, on the harmonic oscillator x'' = -x. */
#include "test_common.h"

typedef struct {
    long n_post;          /* post callback calls */
    gen_rt_real t_post;   /* time of the last post call */
    int t_post_monotone;  /* post times strictly increasing */
    int fail_below;       /* rhs returns SINGULAR when x[0] < 0.5 */
    long n_rhs;
} osc_ctx;

static int osc_rhs(void *vctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *dxdt)
{
    osc_ctx *c = (osc_ctx *)vctx;
    (void)t;
    if (c) {
        c->n_rhs += 1;
        if (c->fail_below && x[0] < GEN_RT_C(0.5)) return GEN_RT_ERR_SINGULAR;
    }
    dxdt[0] = x[1];
    dxdt[1] = -x[0];
    return GEN_RT_OK;
}

static int osc_post(void *vctx, gen_rt_real t, gen_rt_real *x)
{
    osc_ctx *c = (osc_ctx *)vctx;
    (void)x;
    if (c->n_post > 0 && !(t > c->t_post)) c->t_post_monotone = 0;
    c->n_post += 1;
    c->t_post = t;
    return GEN_RT_OK;
}

/* max error against the exact solution x = cos t, x' = -sin t (t in double) */
static double osc_error(const gen_rt_real *x, double t)
{
    double e0 = fabs((double)x[0] - cos(t)), e1 = fabs((double)x[1] + sin(t));
    return e0 > e1 ? e0 : e1;
}

static double rk4_error(int nsteps)
{
    gen_rt_real x[2] = {1, 0}, work[GEN_RT_RK4_WORK(2)];
    double h = 2 * M_PI / nsteps;
    int i, st = GEN_RT_OK;
    for (i = 0; i < nsteps && st == GEN_RT_OK; ++i)
        st = gen_rt_rk4_step(osc_rhs, NULL, 2, (gen_rt_real)(i * h), (gen_rt_real)h, work, x);
    CHECK_INT(st, GEN_RT_OK);
    return osc_error(x, nsteps * h);
}

static void test_rk4_order(void)
{
    /* in float the step must stay large enough for the truncation error to
     * dominate the rounding error */
    const int n = TOL(50, 20);
    double e1 = rk4_error(n), e2 = rk4_error(2 * n);
    double order = log(e1 / e2) / log(2.0);
    CHECK_NEAR(order, 4.0, 0.2);
    CHECK_LT(e2, e1);
    /* leading term: global phase error 2 pi h^4 / 120 */
    CHECK_NEAR(e1 / (2 * M_PI * pow(2 * M_PI / n, 4) / 120), 1.0, 0.1);
    {
        gen_rt_real x[2] = {1, 0}, work[GEN_RT_RK4_WORK(2)];
        CHECK_INT(gen_rt_rk4_step(NULL, NULL, 2, 0, GEN_RT_C(0.1), work, x), GEN_RT_ERR_NULL);
        CHECK_INT(gen_rt_rk4_step(osc_rhs, NULL, 0, 0, GEN_RT_C(0.1), work, x), GEN_RT_ERR_BAD_ARG);
    }
}

static gen_rt_dopri5_opts make_opts(double rtol, double atol)
{
    gen_rt_dopri5_opts o;
    o.rtol = (gen_rt_real)rtol;
    o.atol = (gen_rt_real)atol;
    o.h_init = 0;
    o.h_min = 0;
    o.h_max = 0;
    o.max_steps = 0;
    return o;
}

/* integrate [0, t1] with rtol = atol = tol; return the error at t1 */
static double dopri5_error(double tol, gen_rt_real t1, osc_ctx *ctx,
                           gen_rt_dopri5_stats *stats)
{
    gen_rt_real x[2] = {1, 0}, work[GEN_RT_DOPRI5_WORK(2)], t_reached = -1;
    gen_rt_dopri5_opts o = make_opts(tol, tol);
    int st;
    memset(stats, 0, sizeof *stats);
    st = gen_rt_dopri5_integrate(osc_rhs, osc_post, ctx, 2, 0, t1, &o, work, stats,
                                 &t_reached, x);
    CHECK_INT(st, GEN_RT_OK);
    CHECK(t_reached == t1); /* exactly */
    return osc_error(x, (double)t1);
}

static void test_dopri5_accuracy(void)
{
    const gen_rt_real t1 = (gen_rt_real)(2 * M_PI);
    gen_rt_dopri5_stats st_tight, st_loose;
    osc_ctx c_tight, c_loose, c3;
    double tight = TOL(1e-10, 1e-6), loose = TOL(1e-6, 1e-3), mid = TOL(1e-9, 1e-5);
    double e_tight, e_loose, e_mid;
    memset(&c_tight, 0, sizeof c_tight);
    memset(&c_loose, 0, sizeof c_loose);
    memset(&c3, 0, sizeof c3);
    c_tight.t_post_monotone = c_loose.t_post_monotone = c3.t_post_monotone = 1;

    e_tight = dopri5_error(tight, t1, &c_tight, &st_tight);
    CHECK_LT(e_tight, TOL(1e-8, 2e-5));
    e_loose = dopri5_error(loose, t1, &c_loose, &st_loose);
    CHECK_LT(e_tight, e_loose);
    {
        gen_rt_dopri5_stats s3;
        e_mid = dopri5_error(mid, t1, &c3, &s3);
    }
    /* error scales with the tolerance: three decades of tolerance give more
     * than two decades of error */
    CHECK_LT(100.0 * e_mid, e_loose);
    CHECK_LT(st_loose.n_accepted, st_tight.n_accepted);

    /* the post callback: once per accepted step, last at t1 exactly */
    CHECK_INT(c_tight.n_post, st_tight.n_accepted);
    CHECK_INT(c_loose.n_post, st_loose.n_accepted);
    CHECK(c_tight.t_post == t1);
    CHECK(c_tight.t_post_monotone);
    CHECK(c_loose.t_post_monotone);
    CHECK_LT(0, st_tight.h_last);
    /* rhs count: the runtime's statistic matches the calls the model saw */
    CHECK_INT(st_tight.n_rhs, c_tight.n_rhs);

    /* integrating to an end that is not a multiple of any natural step */
    {
        const gen_rt_real t_end = GEN_RT_C(1.2345);
        osc_ctx c;
        gen_rt_dopri5_stats s;
        double e;
        memset(&c, 0, sizeof c);
        c.t_post_monotone = 1;
        e = dopri5_error(tight, t_end, &c, &s);
        CHECK_LT(e, TOL(1e-8, 2e-5));
        CHECK(c.t_post == t_end);
    }
    /* two calls [0, pi] + [pi, 2 pi] continue with stats->h_last */
    {
        gen_rt_real x[2] = {1, 0}, work[GEN_RT_DOPRI5_WORK(2)], tr = 0;
        gen_rt_real tm = (gen_rt_real)M_PI;
        gen_rt_dopri5_opts o = make_opts(tight, tight);
        gen_rt_dopri5_stats s;
        memset(&s, 0, sizeof s);
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, 0, tm, &o, work, &s, &tr, x),
                  GEN_RT_OK);
        CHECK(tr == tm);
        CHECK_LT(osc_error(x, (double)tm), TOL(1e-8, 2e-5));
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, tm, t1, &o, work, &s, &tr, x),
                  GEN_RT_OK);
        CHECK(tr == t1);
        CHECK_LT(osc_error(x, (double)t1), TOL(1e-8, 2e-5));
        /* zero-length interval: nothing happens */
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, t1, t1, &o, work, &s, &tr, x),
                  GEN_RT_OK);
        CHECK(tr == t1);
    }
}

static void test_dopri5_failures(void)
{
    gen_rt_real work[GEN_RT_DOPRI5_WORK(2)];
    gen_rt_dopri5_stats s;
    /* rhs fails below x = 0.5: x = cos t crosses 0.5 at t = pi/3 */
    {
        gen_rt_real x[2] = {1, 0}, tr = -1;
        gen_rt_dopri5_opts o = make_opts(TOL(1e-10, 1e-6), TOL(1e-10, 1e-6));
        osc_ctx c;
        const double t_cross = M_PI / 3;
        int st;
        memset(&c, 0, sizeof c);
        memset(&s, 0, sizeof s);
        c.fail_below = 1;
        st = gen_rt_dopri5_integrate(osc_rhs, NULL, &c, 2, 0, 2, &o, work, &s, &tr, x);
        CHECK_INT(st, GEN_RT_ERR_SINGULAR);
        CHECK(gen_rt_all_finite(2, x));
        /* stopped just before the crossing, at the last good state */
        CHECK_LT(tr, t_cross + TOL(1e-8, 1e-4));
        CHECK_LT(t_cross - 1e-2, tr);
        CHECK(x[0] >= GEN_RT_C(0.5));
        CHECK_LT(osc_error(x, (double)tr), TOL(1e-8, 2e-5));
    }
    /* step budget */
    {
        gen_rt_real x[2] = {1, 0}, tr = -1;
        gen_rt_dopri5_opts o = make_opts(TOL(1e-10, 1e-6), TOL(1e-10, 1e-6));
        memset(&s, 0, sizeof s);
        o.max_steps = 3;
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, 0, (gen_rt_real)(2 * M_PI),
                                          &o, work, &s, &tr, x),
                  GEN_RT_ERR_MAX_STEPS);
        CHECK_INT(s.n_accepted + s.n_rejected, 3);
        CHECK_LT(0, tr);
        CHECK_LT(tr, 2 * M_PI);
        CHECK_LT(osc_error(x, (double)tr), TOL(1e-8, 2e-5));
    }
    /* a too small minimum step: the tolerance cannot be met */
    {
        gen_rt_real x[2] = {1, 0}, tr = -1;
        gen_rt_dopri5_opts o = make_opts(TOL(1e-10, 1e-6), TOL(1e-10, 1e-6));
        memset(&s, 0, sizeof s);
        o.h_min = GEN_RT_C(0.5);
        o.h_init = GEN_RT_C(0.6);
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, 0, 1, &o, work, &s, &tr, x),
                  GEN_RT_ERR_STEP_UNDERFLOW);
        CHECK(tr == 0);
        CHECK(x[0] == 1 && x[1] == 0);
    }
    /* bad arguments */
    {
        gen_rt_real x[2] = {1, 0}, tr = -1;
        gen_rt_dopri5_opts o = make_opts(1e-6, 1e-6);
        memset(&s, 0, sizeof s);
        o.rtol = -1;
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, 0, 1, &o, work, &s, &tr, x),
                  GEN_RT_ERR_BAD_ARG);
        o.rtol = GEN_RT_C(1e-6);
        o.atol = -1;
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, 0, 1, &o, work, &s, &tr, x),
                  GEN_RT_ERR_BAD_ARG);
        o.rtol = 0; o.atol = 0;
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, 0, 1, &o, work, &s, &tr, x),
                  GEN_RT_ERR_BAD_ARG);
        o.rtol = GEN_RT_C(1e-6); o.atol = GEN_RT_C(1e-6);
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, 1, 0, &o, work, &s, &tr, x),
                  GEN_RT_ERR_BAD_ARG);
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 0, 0, 1, &o, work, &s, &tr, x),
                  GEN_RT_ERR_BAD_ARG);
        CHECK_INT(gen_rt_dopri5_integrate(NULL, NULL, NULL, 2, 0, 1, &o, work, &s, &tr, x),
                  GEN_RT_ERR_NULL);
        CHECK_INT(gen_rt_dopri5_integrate(osc_rhs, NULL, NULL, 2, 0, 1, NULL, work, &s, &tr, x),
                  GEN_RT_ERR_NULL);
        CHECK(x[0] == 1 && x[1] == 0); /* untouched */
        CHECK_INT(s.n_accepted + s.n_rejected, 0);
    }
}

int main(void)
{
    test_rk4_order();
    test_dopri5_accuracy();
    test_dopri5_failures();
    TEST_END();
}
