/* gen_rt_hybrid.c - impacts, resets and persistent contact of a hybrid
 * model (hybrid={...}, gen/intake/hybrid.py): the dynamics with contacts held as
 * constraints, their forces, the impulse solve at an impact and the reset
 * map. The simulation engine (gen_rt_events.c) locates the events and
 * calls these; no model knowledge here beyond the kernels of gen_rt_hybrid.
 *
 * Model form with the active contacts k (g_k held at zero):
 *   M u' = f + A^T lam + W_k^T Lam_k,  A u' + a = 0,  W_k u' + h_k = 0,
 * and at an impact of the closing set S (with the active contacts C):
 *   M u+ = M u- + A^T mu + W^T Lambda,  A u+ + b = 0,
 *   W_k u+ + w_k = -e_k (W_k u- + w_k)   (k in S; e = 0 for k in C),
 * both solved as one KKT system (gen_rt_accel_kkt). Work: the caller's,
 * GEN_RT_HYBRID_WORK / GEN_RT_HYBRID_IWORK (gen_rt.h). */
#include "gen_rt_private.h"

/* the layout of the hybrid work */
typedef struct {
    gen_rt_real *M, *f, *A, *a, *Kqd, *qd, *W, *w, *h, *lam, *ud, *kkt;
    int *kpiv, *iw;
} hwork_;

static void layout_(const gen_rt_model *m, gen_rt_real *work, int *iwork, hwork_ *L)
{
    int nq = m->nq, nu = m->nu, mv = m->mv, nh = m->hybrid->n;
    L->M = work;
    L->f = L->M + nu * nu;
    L->A = L->f + nu;
    L->a = L->A + (mv + nh) * nu;
    L->Kqd = L->a + mv + nh;
    L->qd = L->Kqd + nq * nq;
    L->W = L->qd + nq;
    L->w = L->W + nh * nu;
    L->h = L->w + nh;
    L->lam = L->h + nh;
    L->ud = L->lam + mv + nh;
    L->kkt = L->ud + nu;
    L->kpiv = iwork;
    L->iw = iwork + nq;
}

/* [M, A^T; A, 0] [ud; -lam] = [f; -a] with the first nc rows of A, a; a
 * non-finite entry of the model's M, f, A or a stops before the solve */
static int kkt_(int nu, int nc, const hwork_ *L)
{
    if (!gen_rt_all_finite(nu * nu, L->M) || !gen_rt_all_finite(nu, L->f) ||
        !gen_rt_all_finite(nc * nu, L->A) || !gen_rt_all_finite(nc, L->a))
        return GEN_RT_ERR_NONFINITE_MODEL;
    return gen_rt_accel_kkt(nu, nc, L->M, L->f, L->A, L->a, L->kkt, L->iw, L->ud, L->lam);
}

int gen_rt_hybrid_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                      const gen_rt_real *r, const gen_rt_real *p, const int *active,
                      gen_rt_real *work, int *iwork, gen_rt_real *dxdt, gen_rt_real *lam_c)
{
    const gen_rt_hybrid *hy = m->hybrid;
    int nq = m->nq, nu = m->nu, mv = m->mv, nh = hy->n, na = 0, k, j, st;
    const gen_rt_real *q = x, *u = x + nq;
    hwork_ L;
    layout_(m, work, iwork, &L);
    m->rhs_terms(q, u, r, p, t, m->explicit_kinematics ? NULL : L.Kqd, L.qd, L.M, L.f,
                 mv ? L.A : NULL, mv ? L.a : NULL);
    if (!m->explicit_kinematics) {
        if (gen_rt_lu_factor(nq, L.Kqd, L.kpiv, 0) || gen_rt_lu_solve(nq, L.Kqd, L.kpiv, 1, L.qd))
            return GEN_RT_ERR_SINGULAR_KINEMATICS;
    }
    if (!gen_rt_all_finite(nq, L.qd)) return GEN_RT_ERR_SINGULAR_KINEMATICS;
    if (mv && m->accel_terms) m->accel_terms(q, u, L.qd, p, t, L.a);
    hy->jacobian(q, p, t, L.W, L.w);
    hy->bias(q, u, p, t, L.h);
    for (k = 0; k < nh; ++k) {
        if (!active[k]) continue;
        for (j = 0; j < nu; ++j) L.A[(mv + na) * nu + j] = L.W[k * nu + j];
        L.a[mv + na] = L.h[k];
        ++na;
    }
    st = kkt_(nu, mv + na, &L);
    if (st) return st;
    rt_copy(nq, L.qd, dxdt);
    rt_copy(nu, L.ud, dxdt + nq);
    if (lam_c) {
        na = 0;
        for (k = 0; k < nh; ++k) lam_c[k] = active[k] ? L.lam[mv + na++] : 0;
    }
    return GEN_RT_OK;
}

int gen_rt_hybrid_values(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                         const gen_rt_real *r, const gen_rt_real *p, const int *active,
                         gen_rt_real *work, int *iwork, gen_rt_real *v)
{
    const gen_rt_hybrid *hy = m->hybrid;
    int nh = hy->n, nx = m->nq + m->nu, k, any = 0, st;
    gen_rt_real *g = work + GEN_RT_HYBRID_CORE_WORK(m->nq, m->nu, m->mv, nh);
    gen_rt_real *dx = g + nh;
    hy->values(x, x + m->nq, p, t, g);
    if (!gen_rt_all_finite(nh, g)) return GEN_RT_ERR_NONFINITE_MODEL;
    for (k = 0; k < nh; ++k) {
        v[k] = g[k];
        any |= active[k];
    }
    if (any) {
        gen_rt_real *lc = dx + nx;
        if ((st = gen_rt_hybrid_rhs(m, t, x, r, p, active, work, iwork, dx, lc))) return st;
        for (k = 0; k < nh; ++k)
            if (active[k]) v[k] = lc[k];
    }
    return GEN_RT_OK;
}

int gen_rt_hybrid_rates(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                        const gen_rt_real *p, gen_rt_real *work, int *iwork,
                        gen_rt_real *gd)
{
    const gen_rt_hybrid *hy = m->hybrid;
    int nu = m->nu, nh = hy->n, k, j;
    hwork_ L;
    layout_(m, work, iwork, &L);
    hy->jacobian(x, p, t, L.W, L.w);
    for (k = 0; k < nh; ++k) {
        gen_rt_real s = L.w[k];
        for (j = 0; j < nu; ++j) s += L.W[k * nu + j] * x[m->nq + j];
        gd[k] = s;
    }
    return gen_rt_all_finite(nh, gd) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_hybrid_impulse(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *p,
                          const int *rows, const gen_rt_real *e, gen_rt_real *work,
                          int *iwork, gen_rt_real *x, gen_rt_real *impulse)
{
    const gen_rt_hybrid *hy = m->hybrid;
    int nq = m->nq, nu = m->nu, mv = m->mv, nh = hy->n, na = 0, k, j, st;
    const gen_rt_real *q = x;
    gen_rt_real *u = x + nq;
    hwork_ L;
    layout_(m, work, iwork, &L);
    m->mass_matrix(q, p, t, L.M);
    if (mv) m->velocity_constraint_matrix(q, p, t, L.A, L.a);
    hy->jacobian(q, p, t, L.W, L.w);
    /* M u+ - A^T mu - W^T Lambda = M u-, A u+ + b = 0, W u+ + w + e (W u- + w) = 0 */
    gen_rt_matmul(nu, nu, 1, L.M, u, L.f);
    for (k = 0; k < nh; ++k) {
        gen_rt_real vn = L.w[k];
        if (!rows[k]) continue;
        for (j = 0; j < nu; ++j) {
            L.A[(mv + na) * nu + j] = L.W[k * nu + j];
            vn += L.W[k * nu + j] * u[j];
        }
        L.a[mv + na] = L.w[k] + e[k] * vn;
        ++na;
    }
    st = kkt_(nu, mv + na, &L);
    if (st == GEN_RT_ERR_NONFINITE_MODEL)
        for (j = 0; j < nu; ++j) u[j] = (gen_rt_real)NAN; /* no impulse: not finite */
    if (st) return st;
    if (!gen_rt_all_finite(nu, L.ud)) {
        rt_copy(nu, L.ud, u);
        return GEN_RT_ERR_NONFINITE_MODEL;
    }
    rt_copy(nu, L.ud, u);
    if (impulse) {
        na = 0;
        for (k = 0; k < nh; ++k) impulse[k] = rows[k] ? L.lam[mv + na++] : 0;
    }
    return GEN_RT_OK;
}

int gen_rt_hybrid_reset(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *p, int k,
                        gen_rt_real proj_tol, int proj_max_iter, gen_rt_real *pwork,
                        gen_rt_real *work, gen_rt_real *x)
{
    const gen_rt_hybrid *hy = m->hybrid;
    int nq = m->nq, nu = m->nu, nx = nq + nu, mc = m->mc, mv = m->mv, nres = 0, i, st;
    gen_rt_real *xr, scale = 1, res = 0;
    if (!hy->reset || hy->reset_index[k] < 0) return GEN_RT_ERR_BAD_ARG;
    for (i = 0; i < hy->n; ++i) nres += hy->reset_index[i] >= 0;
    xr = work;  /* nres x nx */
    hy->reset(x, x + nq, p, t, xr);
    xr += (long)hy->reset_index[k] * nx;
    if (!gen_rt_all_finite(nx, xr)) {
        rt_copy(nx, xr, x);   /* the map as it came out: the caller names its entry */
        return GEN_RT_ERR_NONFINITE_MODEL;
    }
    /* the map must land on the constraints (to a tolerance loose enough for
     * a map written by hand): |f_c| and |A u + b| relative to the state */
    for (i = 0; i < nx; ++i) scale = rt_max(scale, rt_abs(xr[i]));
    if (mc) {
        gen_rt_real *fc = xr + nx;
        (void)nres;
        m->constraints(xr, p, t, fc);
        for (i = 0; i < mc; ++i) res = rt_max(res, rt_abs(fc[i]));
    }
    if (mv) {
        gen_rt_real *fv = xr + nx + mc;
        m->velocity_constraints(xr, xr + nq, p, t, fv);
        for (i = 0; i < mv; ++i) res = rt_max(res, rt_abs(fv[i]));
    }
    rt_copy(nx, xr, x);   /* on failure too: the caller shows the map's state */
    if (!(res <= GEN_RT_HYBRID_RESET_TOL * scale)) return GEN_RT_ERR_INCONSISTENT_RESET;
    if ((mc || mv) && pwork) {
        st = gen_rt_model_project(m, t, p, proj_tol, proj_max_iter, pwork, x);
        if (st) return GEN_RT_ERR_INCONSISTENT_RESET;
    }
    return GEN_RT_OK;
}

int gen_rt_hybrid_jump(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *r,
                       const gen_rt_real *p, int k, gen_rt_real proj_tol, int proj_max_iter,
                       gen_rt_real *pwork, int *active, int *rows, gen_rt_real *scratch,
                       gen_rt_real *work, int *iwork, gen_rt_real *x, int *what)
{
    const gen_rt_hybrid *hy = m->hybrid;
    int nh = hy->n, nq = m->nq, j, st, any = 0;
    gen_rt_real *g = scratch, *gd = scratch + nh, *er = scratch + 2 * nh, gscale = 1;
    *what = 0;
    if (active[k]) {
        /* lift-off: the contact force would pull */
        active[k] = 0;
        *what = GEN_RT_HYBRID_LIFTOFF;
        return GEN_RT_OK;
    }
    if (hy->kind[k] == GEN_RT_HYBRID_RESET) {
        st = gen_rt_hybrid_reset(m, t, p, k, proj_tol, proj_max_iter, pwork, work, x);
        if (st) return st;
        *what = GEN_RT_HYBRID_RESET + 1;
        return GEN_RT_OK;
    }
    /* an impact: with every gap closing at the same time (within 1024 eps
     * of zero) and every contact held */
    hy->values(x, x + nq, p, t, g);
    if ((st = gen_rt_hybrid_rates(m, t, x, p, work, iwork, gd))) return st;
    for (j = 0; j < nq; ++j) gscale = rt_max(gscale, rt_abs(x[j]));
    for (j = 0; j < nh; ++j) {
        int dir = hy->direction[j];
        gen_rt_real v = gd[j];
        int closing = (dir < 0 && v < 0) || (dir > 0 && v > 0) || (dir == 0 && v != 0);
        rows[j] = 0;
        er[j] = 0;
        if (hy->kind[j] != GEN_RT_HYBRID_IMPACT) continue;
        if (active[j]) { rows[j] = 1; continue; }
        /* a gap at zero that barely opens (slower than rest_speed) is a
         * contact coming to rest as well (an importer's root finding can
         * stop there on the rounding of the gap) */
        if (!closing && !(j == k && rt_abs(v) <= hy->rest_speed[j])) continue;
        if (j == k || rt_abs(g[j]) <= 1024 * GEN_RT_EPS * gscale) {
            rows[j] = 1;
            /* the Zeno rule: e = 0, or an impact slower than rest_speed,
             * holds the contact (while its force pushes) */
            if (hy->restitution[j] > 0 && rt_abs(v) > hy->rest_speed[j])
                er[j] = hy->restitution[j];
            else
                er[j] = -1;
        }
    }
    if (!rows[k]) return GEN_RT_OK; /* grazing: not closing */
    for (j = 0; j < nh; ++j) {
        if (er[j] < 0) {
            active[j] = 2; /* tentative */
            er[j] = 0;
        }
    }
    st = gen_rt_hybrid_impulse(m, t, p, rows, er, work, iwork, x, NULL);
    if (st) return st;
    /* the new contacts are held while their force pushes */
    for (j = 0; j < nh; ++j) {
        if (active[j] == 2) active[j] = 1;
        any |= active[j];
    }
    if (any) {
        if ((st = gen_rt_hybrid_values(m, t, x, r, p, active, work, iwork, g))) return st;
        for (j = 0; j < nh; ++j)
            if (active[j] && !(g[j] > 0)) active[j] = 0;
    }
    *what = GEN_RT_HYBRID_IMPACT + 1;
    return GEN_RT_OK;
}

int gen_rt_model_eval_hybrid(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                             const gen_rt_real *p, gen_rt_real *g)
{
    const gen_rt_hybrid *hy = m->hybrid;
    if (!hy || hy->n <= 0) return GEN_RT_OK;
    hy->values(x, x + m->nq, p, t, g);
    return gen_rt_all_finite(hy->n, g) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

/* the distance from zero within which a gap or guard counts as at zero:
 * 1024 eps of the state's size (the engine's simultaneous impacts' rule) */
static gen_rt_real zero_tol_(int nx, const gen_rt_real *x)
{
    gen_rt_real s = 1;
    int i;
    for (i = 0; i < nx; ++i) s = rt_max(s, rt_abs(x[i]));
    return 1024 * GEN_RT_EPS * s;
}

/* 1 when a value v is past zero in direction dir (by more than tol): the
 * side a crossing in dir leads into */
static int past_(int dir, gen_rt_real v, gen_rt_real tol)
{
    return (dir < 0 && v < -tol) || (dir > 0 && v > tol);
}

int gen_rt_hybrid_penetrated(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                             const gen_rt_real *p, gen_rt_real *g, int *which)
{
    const gen_rt_hybrid *hy = m->hybrid;
    gen_rt_real tol;
    int k, st;
    *which = -1;
    if (!hy || hy->n <= 0) return GEN_RT_OK;
    if ((st = gen_rt_model_eval_hybrid(m, t, x, p, g))) return st;
    tol = zero_tol_(m->nq + m->nu, x);
    for (k = 0; k < hy->n; ++k)
        if (past_(hy->direction[k], g[k], tol)) {
            *which = k;
            return GEN_RT_ERR_PENETRATED;
        }
    return GEN_RT_OK;
}

int gen_rt_hybrid_crossed(const gen_rt_model *m, gen_rt_real t0, const gen_rt_real *x0,
                          gen_rt_real t1, const gen_rt_real *x1, const gen_rt_real *p,
                          gen_rt_real *g, int *which)
{
    const gen_rt_hybrid *hy = m->hybrid;
    int nh, k, st;
    *which = -1;
    if (!hy || hy->n <= 0) return GEN_RT_OK;
    nh = hy->n;
    if ((st = gen_rt_model_eval_hybrid(m, t0, x0, p, g))) return st;
    if ((st = gen_rt_model_eval_hybrid(m, t1, x1, p, g + nh))) return st;
    for (k = 0; k < nh; ++k) {
        int d = hy->direction[k];
        gen_rt_real a = g[k], b = g[nh + k];
        /* from strictly before to strictly past: a step that ends on the
         * guard (a phase's last) or starts on or past it is no crossing */
        if ((d <= 0 && a > 0 && b < 0) || (d >= 0 && a < 0 && b > 0)) {
            *which = k;
            return GEN_RT_ERR_GUARD_CROSSED;
        }
    }
    return GEN_RT_OK;
}
