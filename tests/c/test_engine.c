/* test_engine.c - the pieces of the simulation engine on problems with
 * exact solutions: the order of DOPRI5's continuous extension and of the
 * cubic Hermite interpolant, the orders of RODAS4 and of its embedded
 * error estimate (also with df/dt), RODAS4's stability on a stiff problem
 * where DOPRI5's step is rejected, and the RMS error norm. */
#include "test_common.h"

/* y1' = y1^2 (y1 = 1 / (1 - t) from 1), y2' = -2 t y2 (y2 = exp(-t^2)):
 * nonlinear, and non-autonomous (df/dt != 0) */
static int nl_rhs(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *dx)
{
    (void)ctx;
    dx[0] = x[0] * x[0];
    dx[1] = -2 * t * x[1];
    return GEN_RT_OK;
}

static void nl_exact(double t, double *x)
{
    x[0] = 1.0 / (1.0 - t);
    x[1] = exp(-t * t);
}

static double max_err(const gen_rt_real *x, const double *ref)
{
    double e0 = fabs((double)x[0] - ref[0]), e1 = fabs((double)x[1] - ref[1]);
    return e0 > e1 ? e0 : e1;
}

/* one DOPRI5 step of size h from the exact state at t0: the errors of the
 * dense output at theta and (for the checks at the ends) the states */
static double dopri5_dense_err(double h, double theta)
{
    const double t0 = 0.1;
    double ref[2];
    gen_rt_real x[2], k[14], y[2], ynew[2], out[2], err = 0;
    nl_exact(t0, ref);
    x[0] = (gen_rt_real)ref[0];
    x[1] = (gen_rt_real)ref[1];
    nl_rhs(NULL, (gen_rt_real)t0, x, k);
    CHECK_INT(gen_rt_dopri5_trial(nl_rhs, NULL, 2, (gen_rt_real)t0, (gen_rt_real)h, x,
                                  GEN_RT_C(1e-6), GEN_RT_C(1e-6), k, y, ynew, &err), GEN_RT_OK);
    gen_rt_dopri5_dense(2, (gen_rt_real)h, (gen_rt_real)theta, x, ynew, k, out);
    nl_exact(t0 + theta * h, ref);
    /* exact at both ends of the step */
    gen_rt_dopri5_dense(2, (gen_rt_real)h, 0, x, ynew, k, y);
    CHECK(y[0] == x[0] && y[1] == x[1]);
    gen_rt_dopri5_dense(2, (gen_rt_real)h, 1, x, ynew, k, y);
    CHECK_NEAR(y[0], ynew[0], TOL(1e-15, 1e-6) * fabs((double)ynew[0]));
    return max_err(out, ref);
}

static double hermite_err(double h, double theta)
{
    const double t0 = 0.1;
    double r0[2], r1[2], ref[2];
    gen_rt_real x0[2], x1[2], f0[2], f1[2], out[2];
    nl_exact(t0, r0);
    nl_exact(t0 + h, r1);
    x0[0] = (gen_rt_real)r0[0]; x0[1] = (gen_rt_real)r0[1];
    x1[0] = (gen_rt_real)r1[0]; x1[1] = (gen_rt_real)r1[1];
    nl_rhs(NULL, (gen_rt_real)t0, x0, f0);
    nl_rhs(NULL, (gen_rt_real)(t0 + h), x1, f1);
    gen_rt_hermite(2, (gen_rt_real)h, (gen_rt_real)theta, x0, f0, x1, f1, out);
    nl_exact(t0 + theta * h, ref);
    return max_err(out, ref);
}

/* one RODAS4 step from the exact state at t0 with the exact J and df/dt:
 * the error of y1 and the size of the embedded estimate */
static void rodas4_errs(double h, double *e_sol, double *e_est)
{
    const double t0 = 0.1;
    double ref[2];
    gen_rt_real x[2], f0[2], J[4], dfdt[2], ynew[2], err = 0;
    gen_rt_real work[GEN_RT_RODAS4_WORK(2)];
    int piv[2];
    const gen_rt_real tol = GEN_RT_C(1e-3);
    nl_exact(t0, ref);
    x[0] = (gen_rt_real)ref[0];
    x[1] = (gen_rt_real)ref[1];
    nl_rhs(NULL, (gen_rt_real)t0, x, f0);
    J[0] = 2 * x[0]; J[1] = 0;
    J[2] = 0;        J[3] = (gen_rt_real)(-2 * t0);
    dfdt[0] = 0;
    dfdt[1] = -2 * x[1];
    CHECK_INT(gen_rt_rodas4_trial(nl_rhs, NULL, 2, (gen_rt_real)t0, (gen_rt_real)h, x, f0, J,
                                  dfdt, tol, tol, work, piv, ynew, &err), GEN_RT_OK);
    nl_exact(t0 + h, ref);
    *e_sol = max_err(ynew, ref);
    /* err is the RMS of K6 / (atol + rtol max|y|): back to an absolute size */
    *e_est = (double)err * (double)tol;
}

/* the observed orders: in float the step must stay large for the truncation
 * error to dominate rounding, short of the asymptotic range (wider bounds) */
static void test_orders(void)
{
    const double h = TOL(0.04, 0.2), th = 0.37;
    double e1, e2, o;
    /* DOPRI5's continuous extension: local error O(h^5) */
    e1 = dopri5_dense_err(h, th);
    e2 = dopri5_dense_err(h / 2, th);
    o = log(e1 / e2) / log(2.0);
    printf("dopri5 dense: errors %.3e %.3e, local order %.2f\n", e1, e2, o);
    CHECK(o > 4.5 && o < TOL(5.6, 6.3));
    /* the cubic Hermite interpolant: O(h^4) */
    e1 = hermite_err(h, th);
    e2 = hermite_err(h / 2, th);
    o = log(e1 / e2) / log(2.0);
    printf("hermite: errors %.3e %.3e, order %.2f\n", e1, e2, o);
    CHECK(o > 3.6 && o < TOL(4.4, 4.8));
    /* RODAS4: y1 of order 4 (local O(h^5)), the estimate of order 3 (O(h^4)) */
    {
        double s1, s2, k1, k2;
        rodas4_errs(h, &s1, &k1);
        rodas4_errs(h / 2, &s2, &k2);
        o = log(s1 / s2) / log(2.0);
        printf("rodas4: errors %.3e %.3e, local order %.2f\n", s1, s2, o);
        CHECK(o > 4.5 && o < TOL(5.6, 6.3));
        o = log(k1 / k2) / log(2.0);
        printf("rodas4 estimate: %.3e %.3e, order %.2f\n", k1, k2, o);
        CHECK(o > 3.5 && o < TOL(4.6, 4.9));
        /* the estimate bounds the error of the order-4 solution */
        CHECK(s1 < k1);
    }
}

/* y' = -lam (y - cos t) - sin t, y = cos t from 1: stiff for lam = 1e6 */
static int stiff_rhs(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *dx)
{
    (void)ctx;
    dx[0] = -GEN_RT_C(1e6) * (x[0] - (gen_rt_real)cos((double)t)) - (gen_rt_real)sin((double)t);
    return GEN_RT_OK;
}

static void test_stiff(void)
{
    const gen_rt_real h = GEN_RT_C(0.1), t0 = GEN_RT_C(0.3), tol = GEN_RT_C(1e-4);
    gen_rt_real x[1], f0[1], J[1], dfdt[1], ynew[1], err = 0, k[7], y[1];
    gen_rt_real work[GEN_RT_RODAS4_WORK(1)];
    int piv[1];
    x[0] = (gen_rt_real)cos((double)t0) + GEN_RT_C(1e-3); /* off the slow manifold */
    stiff_rhs(NULL, t0, x, f0);
    J[0] = -GEN_RT_C(1e6);
    dfdt[0] = GEN_RT_C(1e6) * -(gen_rt_real)sin((double)t0) - (gen_rt_real)cos((double)t0);
    CHECK_INT(gen_rt_rodas4_trial(stiff_rhs, NULL, 1, t0, h, x, f0, J, dfdt, tol, tol, work, piv,
                                  ynew, &err), GEN_RT_OK);
    /* L-stable: the transient is gone after one step 1e5 times its time scale */
    printf("rodas4 stiff step: y1 - cos(t1) = %.3e, err %.3e\n",
           (double)ynew[0] - cos((double)(t0 + h)), (double)err);
    CHECK_NEAR(ynew[0], cos((double)(t0 + h)), TOL(1e-5, 1e-4));
    CHECK(err <= 1);
    /* DOPRI5 at that step is unstable: its estimate rejects the step */
    k[0] = f0[0];
    CHECK_INT(gen_rt_dopri5_trial(stiff_rhs, NULL, 1, t0, h, x, tol, tol, k, y, ynew, &err),
              GEN_RT_OK);
    CHECK(!(err <= 1));
}

static void test_err_norm(void)
{
    gen_rt_real x[2] = {1, -3}, xn[2] = {2, 1}, d[2] = {GEN_RT_C(0.3), GEN_RT_C(0.2)};
    /* sc = atol + rtol max(|x|, |xn|) = 0.1 + 0.1 * (2, 3) = (0.3, 0.4) */
    double want = sqrt((1.0 + 0.25) / 2);
    CHECK_NEAR(gen_rt_err_norm(2, x, xn, d, GEN_RT_C(0.1), GEN_RT_C(0.1)), want, TOL(1e-15, 1e-6));
}

int main(void)
{
    test_orders();
    test_stiff();
    test_err_norm();
    TEST_END();
}
