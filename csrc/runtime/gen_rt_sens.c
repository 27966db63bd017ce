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

#include "gen_rt_sens.h"

static int finite_n(int n, const gen_rt_real *v)
{
    return n <= 0 || gen_rt_all_finite(n, v);
}

static void copy_n(int n, const gen_rt_real *src, gen_rt_real *dst)
{
    int i;
    for (i = 0; i < n; ++i) dst[i] = src[i];
}

static gen_rt_real *take(gen_rt_real **w, int n)
{
    gen_rt_real *r = *w;
    *w += n;
    return r;
}

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
    gen_rt_real *Kqd = take(&w, nq * nq), *Kq = take(&w, nq * nq), *Kf = take(&w, nq * nq),
                *Ku = take(&w, nq * nu), *Rq = take(&w, nu * nq), *M = take(&w, nu * nu),
                *Ru = take(&w, nu * nu), *Rr = take(&w, nu * nr + 1), *A = take(&w, mv * nu + 1),
                *Su = take(&w, mv * nu + 1), *Sq = take(&w, mv * nq + 1),
                *Vq = take(&w, mv * nq + 1), *Sqd = take(&w, mv * nq + 1),
                *Jc = take(&w, mc * nq + 1), *Dq = take(&w, nq * nx), *K = take(&w, N * N),
                *G = take(&w, N * nc);
    const int use_sqd = mv > 0 && m->accel_terms != NULL;
    gen_rt_lin_out o;

    o.Kqd = Kqd; o.Ku = Ku; o.M = M; o.A = A; o.Kq = Kq; o.Rq = Rq; o.Ru = Ru; o.Rr = Rr;
    o.Sq = Sq; o.Su = Su; o.Vq = Vq; o.Jc = Jc; o.Sqd = Sqd;
    m->lin_terms(q, u, qd, ud, lam, r, p, t, &o);
    if (!finite_n(nq * nq, Kqd) || !finite_n(nq * nq, Kq) || !finite_n(nq * nu, Ku) ||
        !finite_n(nu * nu, M) || !finite_n(nu * nq, Rq) || !finite_n(nu * nu, Ru) ||
        !finite_n(nu * nr, Rr) || !finite_n(mv * nu, A) || !finite_n(mv * nq, Sq) ||
        !finite_n(mv * nu, Su) || !finite_n(mv * nq, Vq) || !finite_n(mc * nq, Jc) ||
        (use_sqd && !finite_n(mv * nq, Sqd)))
        return GEN_RT_ERR_NONFINITE_MODEL;

    /* q' rows: Kqd dq' = -[Kq | Ku] [dq; du] */
    for (i = 0; i < nq; ++i) {
        for (j = 0; j < nq; ++j) Dq[i * nx + j] = -Kq[i * nq + j];
        for (j = 0; j < nu; ++j) Dq[i * nx + nq + j] = -Ku[i * nu + j];
    }
    copy_n(nq * nq, Kqd, Kf);
    if (gen_rt_lu_factor(nq, Kf, iwork, 0) || gen_rt_lu_solve(nq, Kf, iwork, nx, Dq))
        return GEN_RT_ERR_SINGULAR_KINEMATICS;

    /* u' rows: the KKT matrix and the right-hand sides, columns [dq, du, dr] */
    for (i = 0; i < N; ++i)
        for (j = 0; j < N; ++j) {
            gen_rt_real v = 0;
            if (i < nu && j < nu) v = M[i * nu + j];
            else if (i < nu) v = -A[(j - nu) * nu + i];
            else if (j < nu) v = A[(i - nu) * nu + j];
            K[i * N + j] = v;
        }
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
    if (!finite_n(nq * nx, Dq) || !finite_n(nu * nc, G)) return GEN_RT_ERR_SINGULAR;

    for (i = 0; i < nq; ++i) {
        copy_n(nx, Dq + i * nx, Jx + i * ldx);
        if (Jr)
            for (j = 0; j < nr; ++j) Jr[i * ldr + j] = 0; /* the kinematics hold no inputs */
    }
    for (i = 0; i < nu; ++i) {
        copy_n(nx, G + i * nc, Jx + (nq + i) * ldx);
        if (Jr) copy_n(nr, G + i * nc + nx, Jr + (nq + i) * ldr);
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
    gen_rt_real *Jd = take(&w, mc * mc), *X = take(&w, mc * niq), *Ad = take(&w, mv * mv),
                *Y = take(&w, mv * ns);
    for (i = 0; i < nx * ns; ++i) E[i] = 0;
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
    return finite_n(nx * ns, E) ? GEN_RT_OK : GEN_RT_ERR_SINGULAR;
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
    gen_rt_real *k1 = take(&w, nx), *k2 = take(&w, nx), *k3 = take(&w, nx),
                *k4 = take(&w, nx), *y = take(&w, nx), *lam = take(&w, mv + 1),
                *J = take(&w, nx * nc), *Y = take(&w, nx * nc), *D = take(&w, nx * nc),
                *S = take(&w, nx * nc), *E = take(&w, nx * ns), *out = take(&w, ns * (ns + nr));
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
            copy_n(nx * nc, J, D);
            for (i = 0; i < nx * nc; ++i) S[i] = D[i];
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
    if (!finite_n(ns * (ns + nr), out)) return GEN_RT_ERR_DIVERGED;
    copy_n(nx, y, x);
    for (k = 0; k < ns; ++k) {
        copy_n(ns, out + k * (ns + nr), Fx + k * ns);
        if (nr && Fr) copy_n(nr, out + k * (ns + nr) + ns, Fr + k * nr);
    }
    return GEN_RT_OK;
}
