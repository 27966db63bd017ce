/* gen_rt_integrate.c - classic RK4 and Dormand-Prince 5(4). */
#include <math.h>
#include "gen_rt.h"
#include "gen_rt_dopri5.h"

#ifdef GEN_RT_REAL_FLOAT
#define RT_POW powf
#define RT_FABS fabsf
#else
#define RT_POW pow
#define RT_FABS fabs
#endif

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

static gen_rt_real rt_max(gen_rt_real a, gen_rt_real b) { return a > b ? a : b; }
static gen_rt_real rt_min(gen_rt_real a, gen_rt_real b) { return a < b ? a : b; }

/* One trial step: stages into k[0..6], proposal into ynew, returns the
 * scaled max-norm error estimate in *err (or a status). */
static int dopri5_trial(gen_rt_rhs_fn f, void *ctx, int nx, gen_rt_real t,
                        gen_rt_real h, const gen_rt_real *x, gen_rt_real *k,
                        gen_rt_real *y, gen_rt_real *ynew,
                        const gen_rt_dopri5_opts *o, gen_rt_real *err)
{
    gen_rt_real *k1 = k, *k2 = k + nx, *k3 = k2 + nx, *k4 = k3 + nx,
                *k5 = k4 + nx, *k6 = k5 + nx, *k7 = k6 + nx;
    gen_rt_real e = 0;
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
    if ((st = f(ctx, t + h, ynew, k7))) return st;
    for (i = 0; i < nx; ++i) {
        gen_rt_real d = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] +
                             E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        gen_rt_real sc = o->atol + o->rtol * rt_max(RT_FABS(x[i]), RT_FABS(ynew[i]));
        gen_rt_real r = RT_FABS(d) / sc;
        if (!(r <= e)) e = r; /* NaN propagates into e */
    }
    *err = e;
    return GEN_RT_OK;
}

int gen_rt_dopri5_integrate(gen_rt_rhs_fn f, gen_rt_post_fn post, void *ctx,
                            int nx, gen_rt_real t0, gen_rt_real t1,
                            const gen_rt_dopri5_opts *opts, gen_rt_real *work,
                            gen_rt_dopri5_stats *stats, gen_rt_real *t_reached,
                            gen_rt_real *x)
{
    gen_rt_real *k = work, *y = work + 7 * nx, *ynew = y + nx;
    gen_rt_real t = t0, h, span = t1 - t0, hmin;
    long max_steps, attempts = 0;
    int i, st, rejected_last = 0;
    if (!f || !opts || !work || !stats || !x) return GEN_RT_ERR_NULL;
    if (t_reached) *t_reached = t0;
    if (nx <= 0 || !(opts->rtol >= 0) || !(opts->atol >= 0) ||
        !(opts->rtol > 0 || opts->atol > 0) || !(span >= 0))
        return GEN_RT_ERR_BAD_ARG;
    if (span == 0) return GEN_RT_OK;
    max_steps = opts->max_steps > 0 ? opts->max_steps : 100000L;
    hmin = opts->h_min > 0 ? opts->h_min
                           : GEN_RT_C(64.0) * GEN_RT_EPS * rt_max(GEN_RT_C(1.0), RT_FABS(t1));
    if ((st = f(ctx, t, x, k))) return st;
    stats->n_rhs += 1;
    if (opts->h_init > 0) h = opts->h_init;
    else if (stats->h_last > 0) h = stats->h_last;
    else {
        /* Hairer's starting-step heuristic, max norms */
        gen_rt_real d0 = 0, d1 = 0;
        for (i = 0; i < nx; ++i) {
            gen_rt_real sc = opts->atol + opts->rtol * RT_FABS(x[i]);
            d0 = rt_max(d0, RT_FABS(x[i]) / sc);
            d1 = rt_max(d1, RT_FABS(k[i]) / sc);
        }
        h = (d0 < GEN_RT_C(1e-5) || d1 < GEN_RT_C(1e-5)) ? GEN_RT_C(1e-6)
                                                        : GEN_RT_C(0.01) * d0 / d1;
        h = rt_min(h, span);
    }
    if (opts->h_max > 0) h = rt_min(h, opts->h_max);
    while (t < t1) {
        gen_rt_real err = 0, hs, h_nat = h;
        int last = 0;
        if (attempts >= max_steps) { if (t_reached) *t_reached = t; return GEN_RT_ERR_MAX_STEPS; }
        ++attempts;
        if (t + h >= t1 || t + GEN_RT_C(1.0001) * h >= t1) { h = t1 - t; last = 1; }
        st = dopri5_trial(f, ctx, nx, t, h, x, k, y, ynew, opts, &err);
        stats->n_rhs += 6;
        if (st || !(err <= GEN_RT_C(1.0))) {
            /* rejected: a failed evaluation (singular / non-finite) counts as
             * an infinite error, so the step shrinks towards it */
            stats->n_rejected += 1;
            if (st == 0 && err == err)
                hs = h * rt_max(GEN_RT_C(0.2), GEN_RT_C(0.9) * RT_POW(err, -GEN_RT_C(0.2)));
            else
                hs = h * GEN_RT_C(0.25);
            if (hs < hmin) {
                if (t_reached) *t_reached = t;
                return st ? st : GEN_RT_ERR_STEP_UNDERFLOW;
            }
            h = hs;
            rejected_last = 1;
            continue;
        }
        /* accepted */
        t = last ? t1 : t + h;
        for (i = 0; i < nx; ++i) x[i] = ynew[i];
        stats->n_accepted += 1;
        if (post) {
            if ((st = post(ctx, t, x))) { if (t_reached) *t_reached = t; return st; }
        }
        {
            gen_rt_real fac = err > 0 ? GEN_RT_C(0.9) * RT_POW(err, -GEN_RT_C(0.2))
                                      : GEN_RT_C(5.0);
            fac = rt_min(rejected_last ? GEN_RT_C(1.0) : GEN_RT_C(5.0), rt_max(GEN_RT_C(0.2), fac));
            h = h * fac;
            /* a clipped final step says little about the natural step */
            stats->h_last = (last && fac >= GEN_RT_C(1.0)) ? rt_max(h, h_nat) : h;
        }
        if (opts->h_max > 0) h = rt_min(h, opts->h_max);
        rejected_last = 0;
        if (t < t1) {
            if ((st = f(ctx, t, x, k))) { if (t_reached) *t_reached = t; return st; }
            stats->n_rhs += 1;
        }
    }
    if (t_reached) *t_reached = t1;
    return GEN_RT_OK;
}
