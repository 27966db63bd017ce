/* test_integrate.c - the RK4 step's order, its leading error term and its
 * error paths, on the harmonic oscillator x'' = -x. (The DOPRI5 and RODAS4
 * trial steps, their dense output and the error norm: test_engine.c.) */
#include "test_common.h"

static int osc_rhs(void *vctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *dxdt)
{
    (void)vctx;
    (void)t;
    dxdt[0] = x[1];
    dxdt[1] = -x[0];
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

int main(void)
{
    test_rk4_order();
    TEST_END();
}
