/* gen_rt_kalman.c - the extended and unscented Kalman filters over a
 * generated model, and the closed loop that measures, filters and controls
 * (gen_rt_kalman.h). */
#include <math.h>
#include <stddef.h>

#include "gen_rt_kalman.h"
#include "gen_rt_private.h"

/* the full-state index of the model's independent entry j */
static int full_index(const gen_rt_model *m, int j)
{
    int niq = m->nq - m->mc;
    return j < niq ? m->q_ind[j] : m->nq + m->u_ind[j - niq];
}

static int ns_of(const gen_rt_model *m)
{
    return m->nq - m->mc + m->nu - m->mv;
}

/* the model's scratch: what its largest call needs */
static int model_work_len(const gen_rt_model *m)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nr = m->nr;
    int ek = m->explicit_kinematics, acc = m->accel;
    (void)ek; (void)acc;
    return GEN_RT_MAX_(GEN_RT_MAX_(GEN_RT_MODEL_STEP_SENS_WORK(nq, nu, mc, mv, nr, ek, acc),
                                   GEN_RT_MODEL_STEP_WORK(nq, nu, mc, mv, nr, ek, acc)),
                       GEN_RT_MAX_(GEN_RT_MODEL_CONSISTENT_WORK(nq, nu, mc, mv, nr, ek, acc),
                                   GEN_RT_MODEL_STATE_MAP_WORK(nq, nu, mc, mv, nr, ek, acc)));
}

int gen_rt_kalman_work_len(const gen_rt_model *m, int nz)
{
    return GEN_RT_KALMAN_OWN_(RT_NX(m), ns_of(m), nz) + model_work_len(m);
}

int gen_rt_kalman_iwork_len(const gen_rt_model *m, int nz)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nr = m->nr;
    int ek = m->explicit_kinematics, acc = m->accel;
    (void)nr; (void)ek; (void)acc;
    return GEN_RT_KALMAN_IWORK(nq, nu, mc, mv, nr, ek, acc, nz);
}

/* the model's scratch sits at the end of work, after the filter's own */
static gen_rt_real *model_work(const gen_rt_kalman *k)
{
    return k->work + GEN_RT_KALMAN_OWN_(RT_NX(k->m), ns_of(k->m), k->nz);
}

/* the filter state of a full state: its independent entries in perm's order */
static void independent(const gen_rt_kalman *k, const gen_rt_real *x, gen_rt_real *xf)
{
    int i, n = ns_of(k->m);
    for (i = 0; i < n; ++i) xf[i] = x[full_index(k->m, k->perm[i])];
}

/* xs = k->x with the independent entries of xf, the dependent ones completed */
static int full_state(const gen_rt_kalman *k, const gen_rt_real *xf, gen_rt_real t,
                      gen_rt_real *xs)
{
    const gen_rt_model *m = k->m;
    int i, n = ns_of(m);
    rt_copy(RT_NX(m), k->x, xs);
    for (i = 0; i < n; ++i) xs[full_index(m, k->perm[i])] = xf[i];
    if (!m->mc && !m->mv) return GEN_RT_OK;
    return gen_rt_model_consistent_state(m, t, k->p, 0, 0, model_work(k), k->iwork, xs);
}

/* P = (P + P^T) / 2 */
static void symmetrize(int n, gen_rt_real *P)
{
    int i, j;
    for (i = 0; i < n; ++i)
        for (j = 0; j < i; ++j) {
            gen_rt_real a = GEN_RT_C(0.5) * (P[i * n + j] + P[j * n + i]);
            P[i * n + j] = a;
            P[j * n + i] = a;
        }
}

/* c (n x n) = a b^T (a, b n x n) */
static void mul_abt(int n, const gen_rt_real *a, const gen_rt_real *b, gen_rt_real *c)
{
    int i, j, l;
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) {
            gen_rt_real s = 0;
            for (l = 0; l < n; ++l) s += a[i * n + l] * b[j * n + l];
            c[i * n + j] = s;
        }
}

/* commit a new estimate: xs (full, complete), P */
static void commit(gen_rt_kalman *k, const gen_rt_real *xs, const gen_rt_real *Pn)
{
    int n = ns_of(k->m);
    rt_copy(RT_NX(k->m), xs, k->x);
    independent(k, k->x, k->xf);
    rt_copy(n * n, Pn, k->P);
}

static int check_settings(const gen_rt_kalman *k)
{
    int n = ns_of(k->m), i;
    if (!(k->period > 0) || k->substeps < 1 || k->nz < 0) return GEN_RT_ERR_BAD_ARG;
    if (k->kind != GEN_RT_KALMAN_EKF && k->kind != GEN_RT_KALMAN_UKF) return GEN_RT_ERR_BAD_ARG;
    if (k->kind == GEN_RT_KALMAN_UKF &&
        (!(k->alpha > 0) || !(n + k->kappa > 0) || !rt_finite(1, &k->beta)))
        return GEN_RT_ERR_BAD_ARG;
    if (!rt_finite(RT_NX(k->m), k->x) || !rt_finite(n * n, k->P) || !rt_finite(n * n, k->Q) ||
        !rt_finite(k->nz, k->R) || !rt_finite(k->m->np, k->p) || !rt_finite(1, &k->t) ||
        !rt_finite(k->m->nr, k->r))
        return GEN_RT_ERR_NONFINITE_INPUT;
    for (i = 0; i < n; ++i)
        if (k->P[i * n + i] < 0 || k->Q[i * n + i] < 0) return GEN_RT_ERR_BAD_ARG;
    for (i = 0; i < k->nz; ++i)
        if (k->R[i] < 0) return GEN_RT_ERR_BAD_ARG;
    return GEN_RT_OK;
}

int gen_rt_kalman_start(gen_rt_kalman *k)
{
    int st, i, nx;
    gen_rt_real *xs;
    if (!k || !k->m || !k->x || !k->xf || !k->P || !k->Q || !k->R || !k->y || !k->S ||
        !k->status || !k->rejected || !k->work || !k->iwork || !k->perm ||
        (k->m->np && !k->p) || (k->m->nr && !k->r) || (k->nz && (!k->h || !k->hjac)))
        return GEN_RT_ERR_NULL;
    if ((st = check_settings(k))) return st;
    nx = RT_NX(k->m);
    xs = k->work;
    rt_copy(nx, k->x, xs);
    if (k->m->mc || k->m->mv) {
        st = gen_rt_model_consistent_state(k->m, k->t, k->p, 0, 0, model_work(k), k->iwork, xs);
        if (st) return st;
    }
    rt_copy(nx, xs, k->x);
    independent(k, k->x, k->xf);
    symmetrize(ns_of(k->m), k->P);
    for (i = 0; i < k->nz; ++i) {
        k->status[i] = GEN_RT_KALMAN_ACCEPTED;
        k->rejected[i] = 0;
        k->y[i] = 0;
        k->S[i] = 0;
    }
    k->n_predict = 0;
    k->n_update = 0;
    return GEN_RT_OK;
}

/* ------------------------------------------------------------------ EKF */

static int ekf_predict(gen_rt_kalman *k, const gen_rt_real *r)
{
    const gen_rt_model *m = k->m;
    int nx = RT_NX(m), n = ns_of(m), i, j, s, st;
    gen_rt_real *w = k->work;
    gen_rt_real *xs = rt_take(&w, nx), *Fx = rt_take(&w, n * n), *F = rt_take(&w, n * n),
                *T = rt_take(&w, n * n), *Pn = rt_take(&w, n * n);
    gen_rt_real h = k->period / (gen_rt_real)k->substeps;
    rt_copy(nx, k->x, xs);
    for (s = 0; s < k->substeps; ++s) {
        gen_rt_real ts = k->t + (gen_rt_real)s * h;
        st = gen_rt_model_step_sensitivity(m, ts, h, r, k->p, model_work(k), k->iwork, xs, Fx,
                                           NULL);
        if (st) return st;
        if (m->mc || m->mv) {
            st = gen_rt_model_consistent_state(m, ts + h, k->p, 0, 0, model_work(k), k->iwork,
                                               xs);
            if (st) return st;
        }
        /* F <- Fx (in the filter's order) F */
        for (i = 0; i < n; ++i)
            for (j = 0; j < n; ++j) T[i * n + j] = Fx[k->perm[i] * n + k->perm[j]];
        if (s == 0) {
            rt_copy(n * n, T, F);
        } else {
            gen_rt_matmul(n, n, n, T, F, Pn);
            rt_copy(n * n, Pn, F);
        }
    }
    /* P = F P F^T + Q */
    gen_rt_matmul(n, n, n, F, k->P, T);
    mul_abt(n, T, F, Pn);
    for (i = 0; i < n * n; ++i) Pn[i] += k->Q[i];
    symmetrize(n, Pn);
    if (!rt_finite(n * n, Pn)) return GEN_RT_ERR_DIVERGED;
    commit(k, xs, Pn);
    return GEN_RT_OK;
}

static int ekf_update(gen_rt_kalman *k, const gen_rt_real *z)
{
    const gen_rt_model *m = k->m;
    int nx = RT_NX(m), n = ns_of(m), nz = k->nz, i, j, l, st, fused = 0;
    gen_rt_real *w = k->work;
    gen_rt_real *hz = rt_take(&w, nz + 1), *Hf = rt_take(&w, nz * nx + 1),
                *E = rt_take(&w, nx * n), *H = rt_take(&w, nz * n + 1), *x0 = rt_take(&w, n),
                *xn = rt_take(&w, n), *Pn = rt_take(&w, n * n), *M = rt_take(&w, n * n),
                *PHt = rt_take(&w, n), *K = rt_take(&w, n), *row = rt_take(&w, n),
                *xs = rt_take(&w, nx);
    k->hjac(k->x, k->r, k->p, &k->t, hz, Hf);
    if (!rt_finite(nz, hz) || !rt_finite(nz * nx, Hf)) return GEN_RT_ERR_NONFINITE_MODEL;
    st = gen_rt_model_state_map(m, k->t, k->x, k->r, k->p, model_work(k), k->iwork, E);
    if (st) return st;
    /* H = dh/dx E, the columns in the filter's order */
    for (i = 0; i < nz; ++i)
        for (j = 0; j < n; ++j) {
            gen_rt_real a = 0;
            for (l = 0; l < nx; ++l) a += Hf[i * nx + l] * E[l * n + k->perm[j]];
            H[i * n + j] = a;
        }
    rt_copy(n, k->xf, x0);
    rt_copy(n, k->xf, xn);
    rt_copy(n * n, k->P, Pn);
    for (i = 0; i < nz; ++i) {
        const gen_rt_real *Hi = H + i * n;
        gen_rt_real yi, Si, Ri = k->R[i];
        if (!rt_finite(1, z + i)) {
            k->status[i] = GEN_RT_KALMAN_MISSING;
            k->y[i] = k->S[i] = (gen_rt_real)NAN;
            k->rejected[i]++;
            continue;
        }
        /* the innovation of the measurement linearized at the prior */
        yi = z[i] - hz[i];
        for (j = 0; j < n; ++j) yi -= Hi[j] * (xn[j] - x0[j]);
        for (j = 0; j < n; ++j) {
            gen_rt_real a = 0;
            for (l = 0; l < n; ++l) a += Pn[j * n + l] * Hi[l];
            PHt[j] = a;
        }
        Si = Ri;
        for (j = 0; j < n; ++j) Si += Hi[j] * PHt[j];
        k->y[i] = yi;
        k->S[i] = Si;
        if (!(Si > 0) || !rt_finite(1, &Si) || !rt_finite(1, &yi)) {
            k->status[i] = GEN_RT_KALMAN_DEGENERATE;
            k->rejected[i]++;
            continue;
        }
        if (k->gate > 0 && yi * yi > k->gate * k->gate * Si) {
            k->status[i] = GEN_RT_KALMAN_GATED;
            k->rejected[i]++;
            continue;
        }
        k->status[i] = GEN_RT_KALMAN_ACCEPTED;
        for (j = 0; j < n; ++j) K[j] = PHt[j] / Si;
        for (j = 0; j < n; ++j) xn[j] += K[j] * yi;
        /* Joseph: M = P (I - K H_i)^T = P - PHt K^T, then
         * P = (I - K H_i) M + R_i K K^T = M - K (H_i M) + R_i K K^T */
        for (j = 0; j < n; ++j)
            for (l = 0; l < n; ++l) M[j * n + l] = Pn[j * n + l] - PHt[j] * K[l];
        for (l = 0; l < n; ++l) {
            gen_rt_real a = 0;
            for (j = 0; j < n; ++j) a += Hi[j] * M[j * n + l];
            row[l] = a;
        }
        for (j = 0; j < n; ++j)
            for (l = 0; l < n; ++l)
                Pn[j * n + l] = M[j * n + l] - K[j] * row[l] + Ri * K[j] * K[l];
        symmetrize(n, Pn);
        fused++;
    }
    if (!fused) return GEN_RT_OK;
    if (!rt_finite(n, xn) || !rt_finite(n * n, Pn)) return GEN_RT_ERR_DIVERGED;
    if ((st = full_state(k, xn, k->t, xs))) return st;
    commit(k, xs, Pn);
    return GEN_RT_OK;
}

/* ------------------------------------------------------------------ UKF */

typedef struct {
    gen_rt_real wm0, wc0, wi;
} ukf_weights;

static ukf_weights weights(const gen_rt_kalman *k)
{
    int n = ns_of(k->m);
    gen_rt_real a2 = k->alpha * k->alpha, c = a2 * ((gen_rt_real)n + k->kappa);
    gen_rt_real lambda = c - (gen_rt_real)n;
    ukf_weights wt;
    wt.wm0 = lambda / c;
    wt.wc0 = wt.wm0 + (1 - a2 + k->beta);
    wt.wi = GEN_RT_C(0.5) / c;
    return wt;
}

/* the 2n + 1 sigma points of (k->xf, k->P) (rows of sig); L: n x n scratch */
static int sigma_points(const gen_rt_kalman *k, gen_rt_real *L, gen_rt_real *sig)
{
    int n = ns_of(k->m), i, j, st;
    gen_rt_real c = k->alpha * k->alpha * ((gen_rt_real)n + k->kappa);
    for (i = 0; i < n * n; ++i) L[i] = c * k->P[i];
    if ((st = gen_rt_chol_factor(n, L))) return st;
    rt_copy(n, k->xf, sig);
    for (j = 0; j < n; ++j) {
        gen_rt_real *plus = sig + (1 + j) * n, *minus = sig + (1 + n + j) * n;
        for (i = 0; i < n; ++i) {
            gen_rt_real d = i >= j ? L[i * n + j] : 0;
            plus[i] = k->xf[i] + d;
            minus[i] = k->xf[i] - d;
        }
    }
    return GEN_RT_OK;
}

static int ukf_predict(gen_rt_kalman *k, const gen_rt_real *r)
{
    const gen_rt_model *m = k->m;
    int nx = RT_NX(m), n = ns_of(m), ns2 = 2 * n + 1, i, j, l, s, st;
    gen_rt_real *w = k->work;
    gen_rt_real *L = rt_take(&w, n * n), *sig = rt_take(&w, ns2 * n),
                *sigf = rt_take(&w, ns2 * n), *Pn = rt_take(&w, n * n), *mean = rt_take(&w, n),
                *xs = rt_take(&w, nx), *xc = rt_take(&w, nx), *d = rt_take(&w, n);
    gen_rt_real h = k->period / (gen_rt_real)k->substeps;
    ukf_weights wt = weights(k);
    if ((st = sigma_points(k, L, sig))) return st;
    for (i = 0; i < ns2; ++i) {
        if ((st = full_state(k, sig + i * n, k->t, xs))) return st;
        for (s = 0; s < k->substeps; ++s) {
            gen_rt_real ts = k->t + (gen_rt_real)s * h;
            st = gen_rt_model_step_rk4(m, ts, h, r, k->p, 0, model_work(k), k->iwork, xs);
            if (st) return st;
            if (m->mc || m->mv) {
                st = gen_rt_model_consistent_state(m, ts + h, k->p, 0, 0, model_work(k),
                                                   k->iwork, xs);
                if (st) return st;
            }
        }
        independent(k, xs, sigf + i * n);
        if (i == 0) rt_copy(nx, xs, xc);
    }
    /* the mean as the central point plus the weighted differences (the
     * weights sum to 1): with a small alpha the weights are large (Wm_0 =
     * 1 - 1 / alpha^2) and the plain weighted sum loses their magnitude's
     * digits */
    for (j = 0; j < n; ++j) {
        gen_rt_real a = 0;
        for (i = 1; i < ns2; ++i) a += wt.wi * (sigf[i * n + j] - sigf[j]);
        mean[j] = sigf[j] + a;
    }
    rt_copy(n * n, k->Q, Pn);
    for (i = 0; i < ns2; ++i) {
        gen_rt_real wc = i ? wt.wi : wt.wc0;
        for (j = 0; j < n; ++j) d[j] = sigf[i * n + j] - mean[j];
        for (j = 0; j < n; ++j)
            for (l = 0; l < n; ++l) Pn[j * n + l] += wc * d[j] * d[l];
    }
    symmetrize(n, Pn);
    if (!rt_finite(n, mean) || !rt_finite(n * n, Pn)) return GEN_RT_ERR_DIVERGED;
    /* the mean's full state, from the central point's */
    rt_copy(nx, xc, xs);
    for (j = 0; j < n; ++j) xs[full_index(m, k->perm[j])] = mean[j];
    if (m->mc || m->mv) {
        st = gen_rt_model_consistent_state(m, k->t + k->period, k->p, 0, 0, model_work(k),
                                           k->iwork, xs);
        if (st) return st;
    }
    commit(k, xs, Pn);
    return GEN_RT_OK;
}

static int ukf_update(gen_rt_kalman *k, const gen_rt_real *z)
{
    const gen_rt_model *m = k->m;
    int nx = RT_NX(m), n = ns_of(m), nz = k->nz, ns2 = 2 * n + 1, i, j, l, a, st, na = 0;
    gen_rt_real *w = k->work;
    gen_rt_real *L = rt_take(&w, n * n), *sig = rt_take(&w, ns2 * n),
                *Zs = rt_take(&w, ns2 * nz + 1), *zp = rt_take(&w, nz + 1),
                *Pzz = rt_take(&w, nz * nz + 1), *Pxz = rt_take(&w, n * nz + 1),
                *Kt = rt_take(&w, n * nz + 1), *Pn = rt_take(&w, n * n),
                *xn = rt_take(&w, n), *xs = rt_take(&w, nx), *Lz = rt_take(&w, nz * nz + 1);
    int *acc = k->iwork + gen_rt_kalman_iwork_len(m, nz) - nz - 1;
    ukf_weights wt = weights(k);
    if ((st = sigma_points(k, L, sig))) return st;
    for (i = 0; i < ns2; ++i) {
        if ((st = full_state(k, sig + i * n, k->t, xs))) return st;
        k->h(xs, k->r, k->p, &k->t, Zs + i * nz);
    }
    if (!rt_finite(ns2 * nz, Zs)) return GEN_RT_ERR_NONFINITE_MODEL;
    for (j = 0; j < nz; ++j) {
        gen_rt_real s = 0;
        for (i = 1; i < ns2; ++i) s += wt.wi * (Zs[i * nz + j] - Zs[j]);
        zp[j] = Zs[j] + s;
    }
    rt_zero(nz * nz, Pzz);
    rt_zero(n * nz, Pxz);
    for (i = 0; i < ns2; ++i) {
        gen_rt_real wc = i ? wt.wi : wt.wc0;
        const gen_rt_real *zi = Zs + i * nz, *si = sig + i * n;
        for (j = 0; j < nz; ++j)
            for (l = 0; l < nz; ++l) Pzz[j * nz + l] += wc * (zi[j] - zp[j]) * (zi[l] - zp[l]);
        for (j = 0; j < n; ++j)
            for (l = 0; l < nz; ++l)
                Pxz[j * nz + l] += wc * (si[j] - k->xf[j]) * (zi[l] - zp[l]);
    }
    for (j = 0; j < nz; ++j) Pzz[j * nz + j] += k->R[j];
    /* each measurement gated on its own variance */
    for (j = 0; j < nz; ++j) {
        gen_rt_real yj = z[j] - zp[j], Sj = Pzz[j * nz + j];
        if (!rt_finite(1, z + j)) {
            k->status[j] = GEN_RT_KALMAN_MISSING;
            k->y[j] = k->S[j] = (gen_rt_real)NAN;
            k->rejected[j]++;
            continue;
        }
        k->y[j] = yj;
        k->S[j] = Sj;
        if (!(Sj > 0) || !rt_finite(1, &Sj)) {
            k->status[j] = GEN_RT_KALMAN_DEGENERATE;
            k->rejected[j]++;
        } else if (k->gate > 0 && yj * yj > k->gate * k->gate * Sj) {
            k->status[j] = GEN_RT_KALMAN_GATED;
            k->rejected[j]++;
        } else {
            k->status[j] = GEN_RT_KALMAN_ACCEPTED;
            acc[na++] = j;
        }
    }
    if (!na) return GEN_RT_OK;
    /* the accepted block Sa (na x na), compacted in place (each entry
     * moves to a place at or before its own, in increasing order) */
    for (a = 0; a < na; ++a)
        for (l = 0; l < na; ++l) Pzz[a * na + l] = Pzz[acc[a] * nz + acc[l]];
    for (a = 0; a < na; ++a) {
        for (j = 0; j < n; ++j) Kt[a * n + j] = Pxz[j * nz + acc[a]];
        zp[a] = k->y[acc[a]];
    }
    /* K^T = Sa^-1 Pxz_a^T by Cholesky */
    rt_copy(na * na, Pzz, Lz);
    if ((st = gen_rt_chol_factor(na, Lz)) || (st = gen_rt_chol_solve(na, Lz, n, Kt))) {
        for (a = 0; a < na; ++a) {
            k->status[acc[a]] = GEN_RT_KALMAN_DEGENERATE;
            k->rejected[acc[a]]++;
        }
        return GEN_RT_OK;
    }
    /* x += K y, P -= K Sa K^T (K Sa = Pxz_a) */
    for (j = 0; j < n; ++j) {
        gen_rt_real s = 0;
        for (a = 0; a < na; ++a) s += Kt[a * n + j] * zp[a];
        xn[j] = k->xf[j] + s;
    }
    for (j = 0; j < n; ++j)
        for (l = 0; l < n; ++l) {
            gen_rt_real s = 0;
            for (a = 0; a < na; ++a) {
                gen_rt_real ks = 0;
                for (i = 0; i < na; ++i) ks += Kt[i * n + j] * Pzz[i * na + a];
                s += ks * Kt[a * n + l];
            }
            Pn[j * n + l] = k->P[j * n + l] - s;
        }
    symmetrize(n, Pn);
    if (!rt_finite(n, xn) || !rt_finite(n * n, Pn)) return GEN_RT_ERR_DIVERGED;
    if ((st = full_state(k, xn, k->t, xs))) return st;
    commit(k, xs, Pn);
    return GEN_RT_OK;
}

/* ------------------------------------------------------------ the calls */

int gen_rt_kalman_predict(gen_rt_kalman *k, const gen_rt_real *r)
{
    int st, nr;
    if (!k || !k->m) return GEN_RT_ERR_NULL;
    nr = k->m->nr;
    if (nr && !r) return GEN_RT_ERR_NULL;
    if (!rt_finite(nr, r)) return GEN_RT_ERR_NONFINITE_INPUT;
    st = k->kind == GEN_RT_KALMAN_UKF ? ukf_predict(k, r) : ekf_predict(k, r);
    if (st) return st;
    if (nr) rt_copy(nr, r, k->r);
    k->t += k->period;
    k->n_predict++;
    return GEN_RT_OK;
}

int gen_rt_kalman_update(gen_rt_kalman *k, const gen_rt_real *z)
{
    int st;
    if (!k || !k->m) return GEN_RT_ERR_NULL;
    if (k->nz && !z) return GEN_RT_ERR_NULL;
    if (!k->nz) return GEN_RT_OK;
    st = k->kind == GEN_RT_KALMAN_UKF ? ukf_update(k, z) : ekf_update(k, z);
    if (st) return st;
    k->n_update++;
    return GEN_RT_OK;
}

int gen_rt_kalman_run(gen_rt_kalman *k, int rows, const gen_rt_real *Z, const gen_rt_real *Rin,
                      gen_rt_real *X, gen_rt_real *Xfull, gen_rt_real *Pout, gen_rt_real *Y,
                      int *St, int *done)
{
    int i, st, n, nx, nz, nr;
    if (done) *done = 0;
    if (!k || !k->m) return GEN_RT_ERR_NULL;
    if (rows < 0) return GEN_RT_ERR_BAD_ARG;
    n = ns_of(k->m); nx = RT_NX(k->m); nz = k->nz; nr = k->m->nr;
    if ((rows && nz && !Z) || (rows > 1 && nr && !Rin)) return GEN_RT_ERR_NULL;
    for (i = 0; i < rows; ++i) {
        if (i > 0 && (st = gen_rt_kalman_predict(k, nr ? Rin + (long)(i - 1) * nr : NULL)))
            return st;
        if ((st = gen_rt_kalman_update(k, nz ? Z + (long)i * nz : NULL))) return st;
        if (X) rt_copy(n, k->xf, X + (long)i * n);
        if (Xfull) rt_copy(nx, k->x, Xfull + (long)i * nx);
        if (Pout) rt_copy(n * n, k->P, Pout + (long)i * n * n);
        if (Y) rt_copy(nz, k->y, Y + (long)i * nz);
        if (St) {
            int j;
            for (j = 0; j < nz; ++j) St[(long)i * nz + j] = k->status[j];
        }
        if (done) *done = i + 1;
    }
    return GEN_RT_OK;
}

/* --------------------------------------------------------- closed loop */

/* splitmix64 (Steele, Lea and Flood 2014): the next 64 random bits */
static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

gen_rt_real gen_rt_kalman_normal(uint64_t *state)
{
    /* Box-Muller on two uniforms in (0, 1], in double */
    double u1 = ((double)(splitmix64(state) >> 11) + 1.0) * (1.0 / 9007199254740992.0);
    double u2 = (double)(splitmix64(state) >> 11) * (1.0 / 9007199254740992.0);
    return (gen_rt_real)(sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2));
}

int gen_rt_kalman_control(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *r)
{
    gen_rt_kalman_loop *L = (gen_rt_kalman_loop *)ctx;
    gen_rt_kalman *k;
    const gen_rt_model *m;
    int nx, nxp, nr, n, i, st;
    if (!L || !L->k || !x || !r) return GEN_RT_ERR_NULL;
    k = L->k;
    m = k->m;
    nx = RT_NX(m);
    nxp = nx - L->ne;
    nr = m->nr;
    n = ns_of(m);
    if (!L->inner && !L->law) return GEN_RT_ERR_NULL;
    /* the plant's true state in the filter model's layout, measured */
    for (i = 0; i < L->nq; ++i) L->xa[i] = x[i];
    for (i = 0; i < L->ne; ++i) L->xa[L->nq + i] = L->theta[i];
    for (i = L->nq; i < nxp; ++i) L->xa[i + L->ne] = x[i];
    if (!L->started) rt_copy(nr, r, L->rprev);
    if (k->nz) {
        k->h(L->xa, L->rprev, k->p, &t, L->z);
        for (i = 0; i < k->nz; ++i) L->z[i] += L->noise_sd[i] * gen_rt_kalman_normal(&L->rng);
    }
    if (L->started && (st = gen_rt_kalman_predict(k, L->rprev))) return st;
    k->t = t;
    if (!L->started && nr) rt_copy(nr, L->rprev, k->r);
    if ((st = gen_rt_kalman_update(k, L->z))) return st;
    /* the law on the estimate */
    if (L->inner) {
        for (i = 0; i < L->nq; ++i) L->xo[i] = k->x[i];
        for (i = L->nq; i < nxp; ++i) L->xo[i] = k->x[i + L->ne];
        if (L->inner(L->inner_ctx, t, L->xo, r)) return GEN_RT_ERR_CONTROLLER;
    } else if ((st = gen_rt_model_eval_input(m, t, k->x, L->law, r))) {
        return st;
    }
    if (L->capacity > 0 && L->count < L->capacity) {
        long c = L->count;
        L->log_t[c] = t;
        for (i = 0; i < n; ++i) {
            L->log_x[c * n + i] = k->xf[i];
            L->log_sd[c * n + i] = RT_SQRT(k->P[i * n + i]);
        }
    }
    L->count++;
    rt_copy(nr, r, L->rprev);
    L->started = 1;
    return GEN_RT_OK;
}
