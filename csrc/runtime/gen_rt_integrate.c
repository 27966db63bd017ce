/* gen_rt_integrate.c - the steps of the integrators, over a callback: one
 * classic RK4 step, one Dormand-Prince 5(4) trial step with its continuous
 * extension, the cubic Hermite interpolant, one RODAS4 trial step, and the
 * scaled error norm. The simulation engine (gen_rt_engine.c) drives them. */
#include "gen_rt_private.h"
#include "gen_rt_dopri5.h"
#include "gen_rt_rodas4.h"

int gen_rt_rk4_step(gen_rt_rhs_fn f, void *ctx, int nx, gen_rt_real t,
                    gen_rt_real h, gen_rt_real *work, gen_rt_real *x)
{
    gen_rt_real *k1 = work, *k2 = k1 + nx, *k3 = k2 + nx, *k4 = k3 + nx,
                *y = k4 + nx;
    gen_rt_real h2 = GEN_RT_C(0.5) * h;
    int i, st;
    if (!f || !work || !x) return GEN_RT_ERR_NULL;
    if (nx <= 0) return GEN_RT_ERR_BAD_ARG;
    if ((st = f(ctx, t, x, k1))) return st;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h2 * k1[i];
    if ((st = f(ctx, t + h2, y, k2))) return st;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h2 * k2[i];
    if ((st = f(ctx, t + h2, y, k3))) return st;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h * k3[i];
    if ((st = f(ctx, t + h, y, k4))) return st;
    for (i = 0; i < nx; ++i)
        y[i] = x[i] + (h / GEN_RT_C(6.0)) *
                          (k1[i] + GEN_RT_C(2.0) * (k2[i] + k3[i]) + k4[i]);
    if (!gen_rt_all_finite(nx, y)) return GEN_RT_ERR_DIVERGED; /* finite stages, overflow */
    for (i = 0; i < nx; ++i) x[i] = y[i];
    return GEN_RT_OK;
}

/* Dormand-Prince coefficients (the tableau of gen_rt_dopri5.h) */
#define GEN_RT_DP_COEF_(name, num, den) static const gen_rt_real name = GEN_RT_C(num) / GEN_RT_C(den);
GEN_RT_DOPRI5_TABLEAU(GEN_RT_DP_COEF_)
#undef GEN_RT_DP_COEF_


/* the scaled RMS norm of an error estimate d: sqrt(mean((d_i / sc_i)^2)),
 * sc_i = atol + rtol max(|x_i|, |xnew_i|) (Hairer's dopri5 and rodas,
 * SciPy's solve_ivp); NaN propagates */
gen_rt_real gen_rt_err_norm(int nx, const gen_rt_real *x, const gen_rt_real *xnew,
                            const gen_rt_real *d, gen_rt_real rtol, gen_rt_real atol)
{
    gen_rt_real s = 0;
    int i;
    for (i = 0; i < nx; ++i) {
        gen_rt_real sc = atol + rtol * rt_max(RT_FABS(x[i]), RT_FABS(xnew[i]));
        gen_rt_real r = d[i] / sc;
        s += r * r;
    }
    return RT_SQRT(s / (gen_rt_real)nx);
}

int gen_rt_dopri5_trial(gen_rt_rhs_fn f, void *ctx, int nx, gen_rt_real t, gen_rt_real h,
                        const gen_rt_real *x, gen_rt_real rtol, gen_rt_real atol,
                        gen_rt_real *k, gen_rt_real *y, gen_rt_real *ynew, gen_rt_real *err)
{
    gen_rt_real *k1 = k, *k2 = k + nx, *k3 = k2 + nx, *k4 = k3 + nx,
                *k5 = k4 + nx, *k6 = k5 + nx, *k7 = k6 + nx;
    int i, st;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h * A21 * k1[i];
    if ((st = f(ctx, t + C2 * h, y, k2))) return st;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h * (A31 * k1[i] + A32 * k2[i]);
    if ((st = f(ctx, t + C3 * h, y, k3))) return st;
    for (i = 0; i < nx; ++i)
        y[i] = x[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
    if ((st = f(ctx, t + C4 * h, y, k4))) return st;
    for (i = 0; i < nx; ++i)
        y[i] = x[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
    if ((st = f(ctx, t + C5 * h, y, k5))) return st;
    for (i = 0; i < nx; ++i)
        y[i] = x[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] +
                           A64 * k4[i] + A65 * k5[i]);
    if ((st = f(ctx, t + h, y, k6))) return st;
    for (i = 0; i < nx; ++i)
        ynew[i] = x[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] +
                              B5 * k5[i] + B6 * k6[i]);
    if (!gen_rt_all_finite(nx, ynew)) return GEN_RT_ERR_DIVERGED; /* finite stages, overflow */
    if ((st = f(ctx, t + h, ynew, k7))) return st;
    for (i = 0; i < nx; ++i)
        y[i] = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] +
                    E7 * k7[i]);
    *err = gen_rt_err_norm(nx, x, ynew, y, rtol, atol);
    return GEN_RT_OK;
}

void gen_rt_dopri5_dense(int nx, gen_rt_real h, gen_rt_real theta, const gen_rt_real *x,
                         const gen_rt_real *ynew, const gen_rt_real *k, gen_rt_real *out)
{
    const gen_rt_real *k1 = k, *k3 = k + 2 * nx, *k4 = k3 + nx, *k5 = k4 + nx,
                      *k6 = k5 + nx, *k7 = k6 + nx;
    gen_rt_real th1 = GEN_RT_C(1.0) - theta;
    int i;
    for (i = 0; i < nx; ++i) {
        gen_rt_real ydiff = ynew[i] - x[i], bspl = h * k1[i] - ydiff;
        gen_rt_real c4 = ydiff - h * k7[i] - bspl;
        gen_rt_real c5 = h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] +
                              D6 * k6[i] + D7 * k7[i]);
        out[i] = x[i] + theta * (ydiff + th1 * (bspl + theta * (c4 + th1 * c5)));
    }
}

void gen_rt_hermite(int nx, gen_rt_real h, gen_rt_real theta, const gen_rt_real *x0,
                    const gen_rt_real *f0, const gen_rt_real *x1, const gen_rt_real *f1,
                    gen_rt_real *out)
{
    /* the cubic with x(0) = x0, x'(0) = f0, x(h) = x1, x'(h) = f1, in the
     * form of the DOPRI5 extension (exact at theta = 0 and 1) */
    gen_rt_real th1 = GEN_RT_C(1.0) - theta;
    int i;
    for (i = 0; i < nx; ++i) {
        gen_rt_real ydiff = x1[i] - x0[i], bspl = h * f0[i] - ydiff;
        gen_rt_real c4 = ydiff - h * f1[i] - bspl;
        out[i] = x0[i] + theta * (ydiff + th1 * (bspl + theta * c4));
    }
}

/* RODAS4 coefficients (the tableau of gen_rt_rodas4.h) */
#define GEN_RT_RD_COEF_(name, value) static const gen_rt_real RD_##name = GEN_RT_C(value);
GEN_RT_RODAS4_TABLEAU(GEN_RT_RD_COEF_)
#undef GEN_RT_RD_COEF_

int gen_rt_rodas4_trial(gen_rt_rhs_fn f, void *ctx, int nx, gen_rt_real t, gen_rt_real h,
                        const gen_rt_real *x, const gen_rt_real *f0, const gen_rt_real *J,
                        const gen_rt_real *dfdt, gen_rt_real rtol, gen_rt_real atol,
                        gen_rt_real *work, int *iwork, gen_rt_real *ynew, gen_rt_real *err)
{
    gen_rt_real *K1 = work, *K2 = K1 + nx, *K3 = K2 + nx, *K4 = K3 + nx, *K5 = K4 + nx,
                *K6 = K5 + nx, *y = K6 + nx, *G = y + nx;
    gen_rt_real hg = GEN_RT_C(1.0) / (h * RD_GAMMA), ih = GEN_RT_C(1.0) / h;
    int i, j, st;
    /* G = I / (h gamma) - J, factored once for the six stages */
    for (i = 0; i < nx; ++i)
        for (j = 0; j < nx; ++j) G[i * nx + j] = (i == j ? hg : 0) - J[i * nx + j];
    *err = -1; /* marks a failure of G's factorization */
    if ((st = gen_rt_lu_factor(nx, G, iwork, 0))) return st;
    *err = 0;
#define RD_DT_(gam) (dfdt ? h * (gam) * dfdt[i] : 0)
    for (i = 0; i < nx; ++i) K1[i] = f0[i] + RD_DT_(RD_GAMMA);
    if ((st = gen_rt_lu_solve(nx, G, iwork, 1, K1))) return st;
    for (i = 0; i < nx; ++i) y[i] = x[i] + RD_A21 * K1[i];
    if ((st = f(ctx, t + RD_ALPHA2 * h, y, K2))) return st;
    for (i = 0; i < nx; ++i) K2[i] += ih * (RD_C21 * K1[i]) + RD_DT_(RD_GAMMA2);
    if ((st = gen_rt_lu_solve(nx, G, iwork, 1, K2))) return st;
    for (i = 0; i < nx; ++i) y[i] = x[i] + RD_A31 * K1[i] + RD_A32 * K2[i];
    if ((st = f(ctx, t + RD_ALPHA3 * h, y, K3))) return st;
    for (i = 0; i < nx; ++i)
        K3[i] += ih * (RD_C31 * K1[i] + RD_C32 * K2[i]) + RD_DT_(RD_GAMMA3);
    if ((st = gen_rt_lu_solve(nx, G, iwork, 1, K3))) return st;
    for (i = 0; i < nx; ++i) y[i] = x[i] + RD_A41 * K1[i] + RD_A42 * K2[i] + RD_A43 * K3[i];
    if ((st = f(ctx, t + RD_ALPHA4 * h, y, K4))) return st;
    for (i = 0; i < nx; ++i)
        K4[i] += ih * (RD_C41 * K1[i] + RD_C42 * K2[i] + RD_C43 * K3[i]) + RD_DT_(RD_GAMMA4);
    if ((st = gen_rt_lu_solve(nx, G, iwork, 1, K4))) return st;
    for (i = 0; i < nx; ++i)
        y[i] = x[i] + RD_A51 * K1[i] + RD_A52 * K2[i] + RD_A53 * K3[i] + RD_A54 * K4[i];
    if ((st = f(ctx, t + h, y, K5))) return st;
    for (i = 0; i < nx; ++i)
        K5[i] += ih * (RD_C51 * K1[i] + RD_C52 * K2[i] + RD_C53 * K3[i] + RD_C54 * K4[i]);
    if ((st = gen_rt_lu_solve(nx, G, iwork, 1, K5))) return st;
    for (i = 0; i < nx; ++i) y[i] += K5[i]; /* Y_6 = Y_5 + K_5 */
    if ((st = f(ctx, t + h, y, K6))) return st;
    for (i = 0; i < nx; ++i)
        K6[i] += ih * (RD_C61 * K1[i] + RD_C62 * K2[i] + RD_C63 * K3[i] + RD_C64 * K4[i] +
                       RD_C65 * K5[i]);
    if ((st = gen_rt_lu_solve(nx, G, iwork, 1, K6))) return st;
#undef RD_DT_
    for (i = 0; i < nx; ++i) ynew[i] = y[i] + K6[i];
    if (!gen_rt_all_finite(nx, ynew)) return GEN_RT_ERR_DIVERGED;
    *err = gen_rt_err_norm(nx, x, ynew, K6, rtol, atol);
    return GEN_RT_OK;
}
