/* gen_rt_sens.c - the full-state Jacobian of a model's right-hand side and
 * the exact derivatives of one classic RK4 step (gen_rt_sens.h).
 *
 * The Jacobian differentiates the equations the right-hand side solves,
 *   Kqd q' + k(q, u) = 0,   M u' - f - A^T lam = 0 (R),   A u' + a = 0 (S),
 * with the blocks of the model's lin_terms kernel at the solved q', u', lam
 * (the method of gen_rt_linearize.c without the elimination of the
 * dependent coordinates and speeds). The step propagates it through the
 * four stages of RK4; the outputs are reduced to the independent state as
 * the linearization is. */
#include <stddef.h>

#include "gen_rt_private.h"
#include "gen_rt_sens.h"

/* the blocks of lin_terms that the elimination of the step's output
 * convention needs after the Jacobian (they live in the core work) */
typedef struct {
    const gen_rt_real *A, *Vq, *Jc;
} sens_constraint_blocks;

/* df/dx and df/dr at (t, x), given q' = dx[0..nq), u' = dx[nq..nx) and the
 * multipliers lam (mv) that gen_rt_model_rhs solved there. Jx row i is at
 * Jx + i * ldx, Jr row i at Jr + i * ldr (Jr may be NULL when nr == 0).
 * work: GEN_RT_SENS_CORE_WORK_ reals, iwork: max(nq, nu + mv) ints. The
 * outputs are written only on success; cb (may be NULL) receives pointers
 * to A, Vq and Jc in work. */
static int jacobian_at(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                       const gen_rt_real *r, const gen_rt_real *p, const gen_rt_real *dx,
                       const gen_rt_real *lam, gen_rt_real *work, int *iwork,
                       gen_rt_real *Jx, int ldx, gen_rt_real *Jr, int ldr,
                       sens_constraint_blocks *cb)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nr = m->nr;
    int nx = nq + nu, N = nu + mv, nc = nx + nr, i, j, k, st;
    const gen_rt_real *q = x, *u = x + nq, *qd = dx, *ud = dx + nq;
    gen_rt_real *w = work;
    gen_rt_real *Kqd = rt_take(&w, nq * nq), *Kq = rt_take(&w, nq * nq),
                *Kf = rt_take(&w, nq * nq), *Ku = rt_take(&w, nq * nu),
                *Rq = rt_take(&w, nu * nq), *M = rt_take(&w, nu * nu),
                *Ru = rt_take(&w, nu * nu), *Rr = rt_take(&w, nu * nr + 1),
                *A = rt_take(&w, mv * nu + 1), *Su = rt_take(&w, mv * nu + 1),
                *Sq = rt_take(&w, mv * nq + 1), *Vq = rt_take(&w, mv * nq + 1),
                *Sqd = rt_take(&w, mv * nq + 1), *Jc = rt_take(&w, mc * nq + 1),
                *Dq = rt_take(&w, nq * nx), *K = rt_take(&w, N * N), *G = rt_take(&w, N * nc);
    const int use_sqd = mv > 0 && m->accel_terms != NULL;
    gen_rt_lin_out o;

    o.Kqd = Kqd; o.Ku = Ku; o.M = M; o.A = A; o.Kq = Kq; o.Rq = Rq; o.Ru = Ru; o.Rr = Rr;
    o.Sq = Sq; o.Su = Su; o.Vq = Vq; o.Jc = Jc; o.Sqd = Sqd;
    m->lin_terms(q, u, qd, ud, lam, r, p, t, &o);
    if (!rt_finite(nq * nq, Kqd) || !rt_finite(nq * nq, Kq) || !rt_finite(nq * nu, Ku) ||
        !rt_finite(nu * nu, M) || !rt_finite(nu * nq, Rq) || !rt_finite(nu * nu, Ru) ||
        !rt_finite(nu * nr, Rr) || !rt_finite(mv * nu, A) || !rt_finite(mv * nq, Sq) ||
        !rt_finite(mv * nu, Su) || !rt_finite(mv * nq, Vq) || !rt_finite(mc * nq, Jc) ||
        (use_sqd && !rt_finite(mv * nq, Sqd)))
        return GEN_RT_ERR_NONFINITE_MODEL;

    /* q' rows: Kqd dq' = -[Kq | Ku] [dq; du] */
    for (i = 0; i < nq; ++i) {
        for (j = 0; j < nq; ++j) Dq[i * nx + j] = -Kq[i * nq + j];
        for (j = 0; j < nu; ++j) Dq[i * nx + nq + j] = -Ku[i * nu + j];
    }
    rt_copy(nq * nq, Kqd, Kf);
    if (gen_rt_lu_factor(nq, Kf, iwork, 0) || gen_rt_lu_solve(nq, Kf, iwork, nx, Dq))
        return GEN_RT_ERR_SINGULAR_KINEMATICS;

    /* u' rows: the KKT matrix and the right-hand sides, columns [dq, du, dr] */
    gen_rt_kkt_matrix(nu, mv, M, A, K);
    for (i = 0; i < nu; ++i) {
        gen_rt_real *g = G + i * nc;
        for (j = 0; j < nq; ++j) g[j] = -Rq[i * nq + j];
        for (j = 0; j < nu; ++j) g[nq + j] = -Ru[i * nu + j];
        for (j = 0; j < nr; ++j) g[nx + j] = -Rr[i * nr + j];
    }
    for (i = 0; i < mv; ++i) {
        gen_rt_real *g = G + (nu + i) * nc;
        for (j = 0; j < nq; ++j) g[j] = -Sq[i * nq + j];
        for (j = 0; j < nu; ++j) g[nq + j] = -Su[i * nu + j];
        for (j = 0; j < nr; ++j) g[nx + j] = 0;
        /* the acceleration-constraint term holds q' (implicit kinematics):
         * its share through dq' = Dq [dq; du] */
        if (use_sqd)
            for (j = 0; j < nx; ++j) {
                gen_rt_real s = 0;
                for (k = 0; k < nq; ++k) s += Sqd[i * nq + k] * Dq[k * nx + j];
                g[j] -= s;
            }
    }
    if ((st = gen_rt_lu_factor(N, K, iwork, 0))) return st;
    if ((st = gen_rt_lu_solve(N, K, iwork, nc, G))) return st;
    if (!rt_finite(nq * nx, Dq) || !rt_finite(nu * nc, G)) return GEN_RT_ERR_SINGULAR;

    for (i = 0; i < nq; ++i) {
        rt_copy(nx, Dq + i * nx, Jx + i * ldx);
        if (Jr)
            for (j = 0; j < nr; ++j) Jr[i * ldr + j] = 0; /* the kinematics hold no inputs */
    }
    for (i = 0; i < nu; ++i) {
        rt_copy(nx, G + i * nc, Jx + (nq + i) * ldx);
        if (Jr) rt_copy(nr, G + i * nc + nx, Jr + (nq + i) * ldr);
    }
    if (cb) {
        cb->A = A; cb->Vq = Vq; cb->Jc = Jc;
    }
    return GEN_RT_OK;
}

int gen_rt_model_jacobian(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                          const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                          int *iwork, gen_rt_real *Jx, gen_rt_real *Jr)
{
    int nx = m->nq + m->nu, nr = m->nr, st;
    gen_rt_real *dx = work, *lam = dx + nx, *w = lam + m->mv + 1;
    /* q', u' and lam at x: the right-hand side itself (its failure is the
     * Jacobian's: f has no derivative where it is not defined) */
    lam[0] = 0;
    st = gen_rt_model_rhs(m, t, x, r, p, w, iwork, dx, lam);
    if (st) return st;
    return jacobian_at(m, t, x, r, p, dx, lam, w, iwork, Jx, nx, nr ? Jr : NULL, nr, NULL);
}

/* E (nx x ns, row-major): an independent perturbation [dq_ind; du_ind] to the
 * full one keeping f_c and A u + b to first order (steps 1-2 of
 * gen_rt_linearize). work: GEN_RT_SENS_ELIM_WORK_ reals. */
static int elimination(const gen_rt_model *m, const sens_constraint_blocks *cb,
                       gen_rt_real *work, int *iwork, gen_rt_real *E)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nx = nq + nu;
    int niq = nq - mc, niu = nu - mv, ns = niq + niu, i, j, k, st;
    gen_rt_real *w = work;
    gen_rt_real *Jd = rt_take(&w, mc * mc), *X = rt_take(&w, mc * niq),
                *Ad = rt_take(&w, mv * mv), *Y = rt_take(&w, mv * ns);
    rt_zero(nx * ns, E);
    for (k = 0; k < niq; ++k) E[m->q_ind[k] * ns + k] = 1;
    for (k = 0; k < niu; ++k) E[(nq + m->u_ind[k]) * ns + niq + k] = 1;
    /* coordinates: Jc_dep dq_dep = -Jc_ind dq_ind */
    if (mc > 0) {
        for (i = 0; i < mc; ++i) {
            for (j = 0; j < mc; ++j) Jd[i * mc + j] = cb->Jc[i * nq + m->q_dep[j]];
            for (k = 0; k < niq; ++k) X[i * niq + k] = cb->Jc[i * nq + m->q_ind[k]];
        }
        if ((st = gen_rt_lu_factor(mc, Jd, iwork, gen_rt_max_abs(mc * nq, cb->Jc)))) return st;
        if ((st = gen_rt_lu_solve(mc, Jd, iwork, niq, X))) return st;
        for (j = 0; j < mc; ++j)
            for (k = 0; k < niq; ++k) E[m->q_dep[j] * ns + k] = -X[j * niq + k];
    }
    /* speeds: A_dep du_dep = -(A_ind du_ind + Vq dq) */
    if (mv > 0) {
        for (i = 0; i < mv; ++i) {
            for (j = 0; j < mv; ++j) Ad[i * mv + j] = cb->A[i * nu + m->u_dep[j]];
            for (k = 0; k < niq; ++k) {
                gen_rt_real s = 0;
                for (j = 0; j < nq; ++j) s += cb->Vq[i * nq + j] * E[j * ns + k];
                Y[i * ns + k] = s;
            }
            for (k = 0; k < niu; ++k) Y[i * ns + niq + k] = cb->A[i * nu + m->u_ind[k]];
        }
        if ((st = gen_rt_lu_factor(mv, Ad, iwork, gen_rt_max_abs(mv * nu, cb->A)))) return st;
        if ((st = gen_rt_lu_solve(mv, Ad, iwork, ns, Y))) return st;
        for (j = 0; j < mv; ++j)
            for (k = 0; k < ns; ++k) E[(nq + m->u_dep[j]) * ns + k] = -Y[j * ns + k];
    }
    return rt_finite(nx * ns, E) ? GEN_RT_OK : GEN_RT_ERR_SINGULAR;
}

int gen_rt_model_step_sensitivity(const gen_rt_model *m, gen_rt_real t, gen_rt_real h,
                                  const gen_rt_real *r, const gen_rt_real *p,
                                  gen_rt_real *work, int *iwork, gen_rt_real *x,
                                  gen_rt_real *Fx, gen_rt_real *Fr)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nr = m->nr;
    int nx = nq + nu, nc = nx + nr, niq = nq - mc, ns = nq - mc + nu - mv;
    int i, j, k, s, st;
    gen_rt_real *w = work;
    gen_rt_real *k1 = rt_take(&w, nx), *k2 = rt_take(&w, nx), *k3 = rt_take(&w, nx),
                *k4 = rt_take(&w, nx), *y = rt_take(&w, nx), *lam = rt_take(&w, mv + 1),
                *J = rt_take(&w, nx * nc), *Y = rt_take(&w, nx * nc),
                *D = rt_take(&w, nx * nc), *S = rt_take(&w, nx * nc),
                *E = rt_take(&w, nx * ns), *out = rt_take(&w, ns * (ns + nr));
    gen_rt_real *sw = w; /* rhs, or the Jacobian's core work then the elimination's */
    gen_rt_real *kst[4];
    gen_rt_real h2 = GEN_RT_C(0.5) * h;
    sens_constraint_blocks cb;

    kst[0] = k1; kst[1] = k2; kst[2] = k3; kst[3] = k4;
    lam[0] = 0;
    for (s = 0; s < 4; ++s) {
        /* the stage's state: the arithmetic of gen_rt_rk4_step */
        gen_rt_real ts = s == 0 ? t : (s == 3 ? t + h : t + h2);
        const gen_rt_real *xs = x;
        gen_rt_real c = s == 3 ? h : h2; /* Y_s = [I, 0] + c dk_{s-1} */
        if (s > 0) {
            const gen_rt_real *kp = kst[s - 1];
            for (i = 0; i < nx; ++i) y[i] = x[i] + c * kp[i];
            xs = y;
        }
        if ((st = gen_rt_model_rhs(m, ts, xs, r, p, sw, iwork, kst[s], lam))) return st;
        st = jacobian_at(m, ts, xs, r, p, kst[s], lam, sw, iwork, J, nc, J + nx, nc,
                         s == 0 ? &cb : NULL);
        if (st) return st;
        if (s == 0) {
            /* E from Jc, A, Vq at x (still in the core work) */
            if ((st = elimination(m, &cb, sw + GEN_RT_SENS_CORE_WORK_(nq, nu, mc, mv, nr),
                                  iwork, E)))
                return st;
            /* dk_1 = [Jx, Jr] */
            rt_copy(nx * nc, J, D);
            rt_copy(nx * nc, D, S);
        } else {
            /* Y = [I, 0] + c dk_{s-1} (D), then dk_s = Jx Y + [0, Jr] */
            for (i = 0; i < nx; ++i)
                for (j = 0; j < nc; ++j)
                    Y[i * nc + j] = (i == j ? GEN_RT_C(1.0) : GEN_RT_C(0.0)) + c * D[i * nc + j];
            for (i = 0; i < nx; ++i) {
                gen_rt_real *d = D + i * nc;
                for (j = 0; j < nc; ++j) d[j] = j < nx ? 0 : J[i * nc + j];
                for (k = 0; k < nx; ++k) {
                    gen_rt_real a = J[i * nc + k];
                    if (a != 0)
                        for (j = 0; j < nc; ++j) d[j] += a * Y[k * nc + j];
                }
            }
            for (i = 0; i < nx * nc; ++i)
                S[i] += (s == 3 ? GEN_RT_C(1.0) : GEN_RT_C(2.0)) * D[i];
        }
    }
    /* x1 exactly as gen_rt_rk4_step */
    for (i = 0; i < nx; ++i)
        y[i] = x[i] + (h / GEN_RT_C(6.0)) *
                          (k1[i] + GEN_RT_C(2.0) * (k2[i] + k3[i]) + k4[i]);
    if (!gen_rt_all_finite(nx, y)) return GEN_RT_ERR_DIVERGED;
    /* [Fx_full, Fr_full] = [I, 0] + h/6 S, reduced: out = P_ind [F_x E, F_r] */
    for (i = 0; i < nx; ++i)
        for (j = 0; j < nc; ++j)
            S[i * nc + j] = (i == j ? GEN_RT_C(1.0) : GEN_RT_C(0.0)) +
                            (h / GEN_RT_C(6.0)) * S[i * nc + j];
    for (k = 0; k < ns; ++k) {
        int row = k < niq ? m->q_ind[k] : nq + m->u_ind[k - niq];
        const gen_rt_real *f = S + row * nc;
        for (j = 0; j < ns; ++j) {
            gen_rt_real a = 0;
            for (i = 0; i < nx; ++i) a += f[i] * E[i * ns + j];
            out[k * (ns + nr) + j] = a;
        }
        for (j = 0; j < nr; ++j) out[k * (ns + nr) + ns + j] = f[nx + j];
    }
    if (!rt_finite(ns * (ns + nr), out)) return GEN_RT_ERR_DIVERGED;
    rt_copy(nx, y, x);
    for (k = 0; k < ns; ++k) {
        rt_copy(ns, out + k * (ns + nr), Fx + k * ns);
        if (nr && Fr) rt_copy(nr, out + k * (ns + nr) + ns, Fr + k * nr);
    }
    return GEN_RT_OK;
}

int gen_rt_model_state_map(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                           const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                           int *iwork, gen_rt_real *E)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nr = m->nr, nx = nq + nu;
    int ns = nq - mc + nu - mv, k, st;
    gen_rt_real *w = work;
    gen_rt_real *zd = rt_take(&w, 2 * nx + nr + mv + 4), *Eo;
    gen_rt_real *Kqd, *Kq, *Ku, *M, *Rq, *Ru, *Rr, *A, *Sq, *Su, *Vq, *Sqd, *Jc;
    sens_constraint_blocks cb;
    gen_rt_lin_out o;
    if (!mc && !mv) {
        rt_zero(nx * ns, E);
        for (k = 0; k < nq; ++k) E[m->q_ind[k] * ns + k] = 1;
        for (k = 0; k < nu; ++k) E[(nq + m->u_ind[k]) * ns + nq + k] = 1;
        return GEN_RT_OK;
    }
    /* the kernel's blocks at q, u with q', u', the multipliers (and the
     * inputs when r is NULL) zero: Jc, A and Vq hold none of them */
    rt_zero(2 * nx + nr + mv + 4, zd);
    Kqd = rt_take(&w, nq * nq); Kq = rt_take(&w, nq * nq); Ku = rt_take(&w, nq * nu);
    M = rt_take(&w, nu * nu); Rq = rt_take(&w, nu * nq); Ru = rt_take(&w, nu * nu);
    Rr = rt_take(&w, nu * nr + 1); A = rt_take(&w, mv * nu + 1); Sq = rt_take(&w, mv * nq + 1);
    Su = rt_take(&w, mv * nu + 1); Vq = rt_take(&w, mv * nq + 1);
    Sqd = rt_take(&w, mv * nq + 1); Jc = rt_take(&w, mc * nq + 1);
    Eo = rt_take(&w, nx * ns);
    o.Kqd = Kqd; o.Ku = Ku; o.M = M; o.A = A; o.Kq = Kq; o.Rq = Rq; o.Ru = Ru; o.Rr = Rr;
    o.Sq = Sq; o.Su = Su; o.Vq = Vq; o.Jc = Jc; o.Sqd = Sqd;
    m->lin_terms(x, x + nq, zd, zd + nq, zd + nx, r ? r : zd + nx + mv + 1, p, t, &o);
    if (!rt_finite(mv * nu, A) || !rt_finite(mv * nq, Vq) || !rt_finite(mc * nq, Jc))
        return GEN_RT_ERR_NONFINITE_MODEL;
    cb.A = A; cb.Vq = Vq; cb.Jc = Jc;
    if ((st = elimination(m, &cb, w, iwork, Eo))) return st;
    rt_copy(nx * ns, Eo, E);
    return GEN_RT_OK;
}
