/* gen_rt_model.c - everything the public API does with a model: evaluation,
 * the right-hand side, projection and consistent states, integration and
 * linearization, over the kernels of a gen_rt_model.
 *
 * Inputs are assumed checked by the caller (the generated wrappers): the
 * pointers the sizes call for are non-NULL and every input is finite. Work
 * arrays are the caller's, sized by the GEN_RT_MODEL_*_WORK macros of
 * gen_rt.h. The arithmetic is laid out so that a generated model gives the
 * same numbers, bit for bit, as the code the generator used to inline. */
#include <stddef.h>

#include "gen_rt.h"

static int finite_n(int n, const gen_rt_real *v)
{
    return n <= 0 || gen_rt_all_finite(n, v);
}

static void copy_n(int n, const gen_rt_real *src, gen_rt_real *dst)
{
    int i;
    for (i = 0; i < n; ++i) dst[i] = src[i];
}

#define NX_(m) ((m)->nq + (m)->nu)

/* ------------------------------------------------------------------ */
/* Evaluation                                                         */
/* ------------------------------------------------------------------ */

int gen_rt_model_eval_mass_matrix(const gen_rt_model *m, const gen_rt_real *q,
                                  const gen_rt_real *p, gen_rt_real t, gen_rt_real *M)
{
    m->mass_matrix(q, p, t, M);
    return finite_n(m->nu * m->nu, M) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_forcing(const gen_rt_model *m, const gen_rt_real *q,
                              const gen_rt_real *u, const gen_rt_real *r,
                              const gen_rt_real *p, gen_rt_real t, gen_rt_real *f)
{
    m->forcing(q, u, r, p, t, f);
    return finite_n(m->nu, f) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

/* q' from the kinematic equations' outputs: explicit, qd holds q' (checked);
 * implicit, Kqd q' = qd is solved in place (Kqd overwritten). Any failure
 * is the kinematics' own status. */
static int solve_kinematics(const gen_rt_model *m, gen_rt_real *Kqd, int *piv, gen_rt_real *qd)
{
    int nq = m->nq;
    if (m->explicit_kinematics)
        return finite_n(nq, qd) ? GEN_RT_OK : GEN_RT_ERR_SINGULAR_KINEMATICS;
    if (!finite_n(nq * nq, Kqd) || !finite_n(nq, qd)) return GEN_RT_ERR_SINGULAR_KINEMATICS;
    if (gen_rt_lu_factor(nq, Kqd, piv, 0) || gen_rt_lu_solve(nq, Kqd, piv, 1, qd))
        return GEN_RT_ERR_SINGULAR_KINEMATICS;
    return GEN_RT_OK;
}

int gen_rt_model_eval_kinematics(const gen_rt_model *m, const gen_rt_real *q,
                                 const gen_rt_real *u, const gen_rt_real *p, gen_rt_real t,
                                 gen_rt_real *work, int *iwork, gen_rt_real *qdot)
{
    m->kinematics(q, u, p, t, m->explicit_kinematics ? NULL : work, qdot);
    return solve_kinematics(m, work, iwork, qdot);
}

int gen_rt_model_eval_constraints(const gen_rt_model *m, const gen_rt_real *q,
                                  const gen_rt_real *p, gen_rt_real t, gen_rt_real *fc)
{
    if (!m->mc) return GEN_RT_OK;
    m->constraints(q, p, t, fc);
    return finite_n(m->mc, fc) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_constraint_jacobian(const gen_rt_model *m, const gen_rt_real *q,
                                          const gen_rt_real *p, gen_rt_real t,
                                          gen_rt_real *work, gen_rt_real *Jc)
{
    if (!m->mc) return GEN_RT_OK;
    m->constraint_jacobian(q, p, t, work, Jc);
    return finite_n(m->mc * m->nq, Jc) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_velocity_constraints(const gen_rt_model *m, const gen_rt_real *q,
                                           const gen_rt_real *u, const gen_rt_real *p,
                                           gen_rt_real t, gen_rt_real *fv)
{
    if (!m->mv) return GEN_RT_OK;
    m->velocity_constraints(q, u, p, t, fv);
    return finite_n(m->mv, fv) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_velocity_constraint_matrix(const gen_rt_model *m,
                                                 const gen_rt_real *q,
                                                 const gen_rt_real *p, gen_rt_real t,
                                                 gen_rt_real *A, gen_rt_real *b)
{
    if (!m->mv) return GEN_RT_OK;
    m->velocity_constraint_matrix(q, p, t, A, b);
    return (finite_n(m->mv * m->nu, A) && finite_n(m->mv, b)) ? GEN_RT_OK
                                                             : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_energy(const gen_rt_model *m, const gen_rt_real *q,
                             const gen_rt_real *u, const gen_rt_real *p, gen_rt_real t,
                             gen_rt_real *E)
{
    if (!m->energy) {
        E[0] = 0;
        return GEN_RT_ERR_BAD_ARG; /* the model was generated without an energy expression */
    }
    m->energy(q, u, p, t, E);
    return finite_n(1, E) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

/* ------------------------------------------------------------------ */
/* The right-hand side                                                */
/* ------------------------------------------------------------------ */

static int rhs_(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work, int *iwork,
                gen_rt_real *dxdt, gen_rt_real *lam);

int gen_rt_model_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                     const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                     int *iwork, gen_rt_real *dxdt, gen_rt_real *lam)
{
    int st = rhs_(m, t, x, r, p, work, iwork, dxdt, lam);
    /* a failure at a state that has run away (beyond GEN_RT_DIVERGED_ABS, or
     * an integrator stage that overflowed) is divergence, not a singular
     * configuration of the model */
    if (st && (!gen_rt_all_finite(NX_(m), x) || gen_rt_max_abs(NX_(m), x) > GEN_RT_DIVERGED_ABS))
        return GEN_RT_ERR_DIVERGED;
    return st;
}

static int rhs_(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work, int *iwork,
                gen_rt_real *dxdt, gen_rt_real *lam)
{
    int nq = m->nq, nu = m->nu, mv = m->mv, st;
    const gen_rt_real *q = x, *u = x + nq;
    gen_rt_real *M = work, *f = M + nu * nu, *A = f + nu, *a = A + mv * nu,
                *Kqd = a + mv;
    gen_rt_real *w = Kqd + (m->explicit_kinematics ? 0 : nq * nq);
    int *kpiv = iwork, *iw = iwork + nq;
    m->rhs_terms(q, u, r, p, t, m->explicit_kinematics ? NULL : Kqd, dxdt, M, f,
                 mv ? A : NULL, mv ? a : NULL);
    if ((st = solve_kinematics(m, Kqd, kpiv, dxdt))) return st;
    if (mv && m->accel_terms) m->accel_terms(q, u, dxdt, p, t, a);
    if (!finite_n(nu * nu, M) || !finite_n(nu, f)) return GEN_RT_ERR_NONFINITE_MODEL;
    if (mv) {
        if (!finite_n(mv * nu, A) || !finite_n(mv, a)) return GEN_RT_ERR_NONFINITE_MODEL;
        if (m->accel == GEN_RT_ACCEL_PARTITIONED)
            /* Kane: eliminate the dependent speeds through the partition */
            return gen_rt_accel_partitioned(nu, mv, m->u_ind, m->u_dep, M, f, A, a, w, iw,
                                            dxdt + nq, lam);
        /* Lagrange: accelerations and multipliers from the KKT system */
        return gen_rt_accel_kkt(nu, mv, M, f, A, a, w, iw, dxdt + nq, lam);
    }
    if (m->accel == GEN_RT_ACCEL_LDLT) {
        /* the unrolled LDL^T checks its pivots; an overflowing solution
         * (a tiny mass under a large force) is singular too, as with LU */
        if ((st = m->mass_solve(M, f, dxdt + nq))) return st;
        return finite_n(nu, dxdt + nq) ? GEN_RT_OK : GEN_RT_ERR_SINGULAR;
    }
    return gen_rt_accel_kkt(nu, 0, M, f, NULL, NULL, w, iw, dxdt + nq, NULL);
}

int gen_rt_model_eval_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                          const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                          int *iwork, gen_rt_real *dxdt, gen_rt_real *lam)
{
    int st = gen_rt_model_rhs(m, t, x, r, p, work + NX_(m), iwork, work, lam);
    if (st) return st;
    copy_n(NX_(m), work, dxdt);
    return GEN_RT_OK;
}

int gen_rt_model_eval_auxiliary_forces(const gen_rt_model *m, gen_rt_real t,
                                       const gen_rt_real *x, const gen_rt_real *r,
                                       const gen_rt_real *p, gen_rt_real *work, int *iwork,
                                       gen_rt_real *F)
{
    int na = m->na, i, st;
    gen_rt_real *dx = work, *Fm = dx + NX_(m), *g = Fm + na * na, *w = g + na;
    if (na <= 0 || !m->auxiliary) return GEN_RT_OK;
    /* u' of the real speeds, then the auxiliary equations at them */
    st = gen_rt_model_rhs(m, t, x, r, p, w, iwork, dx, NULL);
    if (st) return st;
    m->auxiliary(x, x + m->nq, dx + m->nq, r, p, t, Fm, g);
    if (!finite_n(na * na, Fm) || !finite_n(na, g)) return GEN_RT_ERR_NONFINITE_MODEL;
    for (i = 0; i < na; ++i) g[i] = -g[i];
    if ((st = gen_rt_lu_factor(na, Fm, iwork, 0))) return st;
    if ((st = gen_rt_lu_solve(na, Fm, iwork, 1, g))) return st;
    if (!finite_n(na, g)) return GEN_RT_ERR_NONFINITE_MODEL;
    copy_n(na, g, F);
    return GEN_RT_OK;
}

/* ------------------------------------------------------------------ */
/* Constraint manifold: projection and consistent states              */
/* ------------------------------------------------------------------ */

/* f_c and its Jacobian at q; NONFINITE_MODEL when they are not finite */
static int constraint_jacobian_at(const gen_rt_model *m, const gen_rt_real *q,
                                  const gen_rt_real *p, gen_rt_real t, gen_rt_real *fc,
                                  gen_rt_real *Jc)
{
    m->constraint_jacobian(q, p, t, fc, Jc);
    return (finite_n(m->mc, fc) && finite_n(m->mc * m->nq, Jc)) ? GEN_RT_OK
                                                                : GEN_RT_ERR_NONFINITE_MODEL;
}

/* A and b of the velocity constraints at q, checked the same way */
static int velocity_matrix_at(const gen_rt_model *m, const gen_rt_real *q, const gen_rt_real *p,
                              gen_rt_real t, gen_rt_real *A, gen_rt_real *b)
{
    m->velocity_constraint_matrix(q, p, t, A, b);
    return (finite_n(m->mv * m->nu, A) && finite_n(m->mv, b)) ? GEN_RT_OK
                                                             : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_project(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *p,
                         gen_rt_real tol, int max_iter, gen_rt_real *work, gen_rt_real *x)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nx = NX_(m), i, j, st;
    int nw = (mc * mc + mc > mv * mv + mv ? mc * mc + mc : mv * mv + mv) + 1;
    gen_rt_real *xc = work, *w = xc + nx, *fc = w + nw, *Jc = fc + mc, *q0 = Jc + mc * nq,
                *A = q0 + nq, *b = A + mv * nu, *res = b + mv;
    if (!mc && !mv) return GEN_RT_OK;
    copy_n(nx, x, xc);
    if (mc) {
        int it, converged = 0;
        if (max_iter <= 0) max_iter = 10;
        if (!(tol > 0)) tol = 16 * GEN_RT_EPS;
        for (it = 0; it < max_iter; ++it) {
            gen_rt_real dmax = 0;
            if ((st = constraint_jacobian_at(m, xc, p, t, fc, Jc))) return st;
            copy_n(nq, xc, q0);
            st = gen_rt_min_norm_correct(mc, nq, Jc, fc, w, xc);
            if (st) return st;
            for (i = 0; i < nq; ++i) {
                gen_rt_real d = xc[i] - q0[i];
                if (d < 0) d = -d;
                if (d > dmax) dmax = d;
            }
            if (!(dmax == dmax)) return GEN_RT_ERR_NONFINITE_MODEL;
            if (dmax <= tol * (1 + gen_rt_max_abs(nq, xc))) { converged = 1; break; }
        }
        if (!converged) return GEN_RT_ERR_NO_CONVERGENCE;
    }
    if (mv) {
        if ((st = velocity_matrix_at(m, xc, p, t, A, b))) return st;
        for (i = 0; i < mv; ++i) {
            gen_rt_real s = b[i];
            for (j = 0; j < nu; ++j) s += A[i * nu + j] * xc[nq + j];
            res[i] = s;
        }
        st = gen_rt_min_norm_correct(mv, nu, A, res, w, xc + nq);
        if (st) return st;
    }
    if (!finite_n(nx, xc)) return GEN_RT_ERR_NONFINITE_MODEL;
    copy_n(nx, xc, x);
    return GEN_RT_OK;
}

int gen_rt_model_consistent_state(const gen_rt_model *m, gen_rt_real t,
                                  const gen_rt_real *p, gen_rt_real tol, int max_iter,
                                  gen_rt_real *work, int *iwork, gen_rt_real *x)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nx = NX_(m), i, j, st;
    gen_rt_real *xc = work, *fc = xc + nx, *Jc = fc + mc, *Jd = Jc + mc * nq,
                *A = Jd + mc * mc, *b = A + mv * nu, *Ad = b + mv, *rhs = Ad + mv * mv;
    int *piv = iwork, *piv2 = iwork + mc;
    if (!mc && !mv) return GEN_RT_OK;
    copy_n(nx, x, xc);
    if (mc) {
        int it, converged = 0;
        if (max_iter <= 0) max_iter = 50;
        if (!(tol > 0)) tol = 16 * GEN_RT_EPS;
        for (it = 0; it < max_iter; ++it) {
            gen_rt_real dmax = 0;
            if ((st = constraint_jacobian_at(m, xc, p, t, fc, Jc))) return st;
            for (i = 0; i < mc; ++i)
                for (j = 0; j < mc; ++j) Jd[i * mc + j] = Jc[i * nq + m->q_dep[j]];
            st = gen_rt_lu_factor(mc, Jd, piv, gen_rt_max_abs(mc * nq, Jc));
            if (st) return st;
            st = gen_rt_lu_solve(mc, Jd, piv, 1, fc);
            if (st) return st;
            for (j = 0; j < mc; ++j) {
                gen_rt_real d = fc[j] < 0 ? -fc[j] : fc[j];
                xc[m->q_dep[j]] -= fc[j];
                if (d > dmax) dmax = d;
            }
            if (!(dmax == dmax)) return GEN_RT_ERR_NONFINITE_MODEL;
            if (dmax <= tol * (1 + gen_rt_max_abs(nq, xc))) { converged = 1; break; }
        }
        if (!converged) return GEN_RT_ERR_NO_CONVERGENCE;
    }
    if (mv) {
        if ((st = velocity_matrix_at(m, xc, p, t, A, b))) return st;
        for (i = 0; i < mv; ++i) {
            gen_rt_real s = -b[i];
            for (j = 0; j < nu - mv; ++j)
                s -= A[i * nu + m->u_ind[j]] * xc[nq + m->u_ind[j]];
            rhs[i] = s;
            for (j = 0; j < mv; ++j) Ad[i * mv + j] = A[i * nu + m->u_dep[j]];
        }
        st = gen_rt_lu_factor(mv, Ad, piv2, gen_rt_max_abs(mv * nu, A));
        if (st) return st;
        st = gen_rt_lu_solve(mv, Ad, piv2, 1, rhs);
        if (st) return st;
        for (j = 0; j < mv; ++j) xc[nq + m->u_dep[j]] = rhs[j];
    }
    if (!finite_n(nx, xc)) return GEN_RT_ERR_NONFINITE_MODEL;
    copy_n(nx, xc, x);
    return GEN_RT_OK;
}

/* ------------------------------------------------------------------ */
/* Integration                                                        */
/* ------------------------------------------------------------------ */

/* what the integrators' callbacks see */
typedef struct {
    const gen_rt_model *m;
    const gen_rt_real *r, *p;
    gen_rt_real proj_tol;
    int proj_max_iter;
    gen_rt_real *work;  /* GEN_RT_MODEL_CB_WORK_ reals, shared by rhs and projection */
    int *iwork;
    /* inputs from a description (NULL: r is constant) */
    const gen_rt_input *in;
    gen_rt_real *r_buf;   /* nr: r at the current evaluation (continuous) */
    gen_rt_real *r_held;  /* nr: r held since the last sample (period > 0) */
    gen_rt_real t_seg;    /* start of the current sub-interval: a ZOH table's row */
    gen_rt_real t0;       /* start of the simulation: samples at t0 + k period */
    gen_rt_real t_sampled; /* time of the held sample (each sample is taken once) */
    int sampled;          /* 1 once a sample is held */
} model_ctx;

/* the last knot index k with T[k] <= t (0 before the first) */
static int table_row(int n, const gen_rt_real *T, gen_rt_real t)
{
    int lo = 0, hi = n - 1;
    if (t < T[0]) return 0;
    if (t >= T[n - 1]) return n - 1;
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (T[mid] <= t) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* base, feedback and controller at t (a ZOH table at t_zoh) */
static int input_at(const gen_rt_model *m, const gen_rt_input *in, gen_rt_real t,
                    gen_rt_real t_zoh, const gen_rt_real *x, gen_rt_real *r)
{
    int nr = m->nr, nq = m->nq, niq = m->nq - m->mc, niu = m->nu - m->mv, ns = niq + niu;
    int i, j, k;
    if (in->n_table > 0) {
        const gen_rt_real *T = in->t_table, *R = in->r_table;
        int n = in->n_table;
        if (in->hold == GEN_RT_HOLD_LINEAR && n > 1 && t > T[0] && t < T[n - 1]) {
            gen_rt_real w;
            k = table_row(n, T, t);
            w = (t - T[k]) / (T[k + 1] - T[k]);
            for (i = 0; i < nr; ++i)
                r[i] = R[(long)k * nr + i] + w * (R[(long)(k + 1) * nr + i] - R[(long)k * nr + i]);
        } else {
            k = table_row(n, T, in->hold == GEN_RT_HOLD_LINEAR ? t : t_zoh);
            for (i = 0; i < nr; ++i) r[i] = R[(long)k * nr + i];
        }
    } else {
        for (i = 0; i < nr; ++i) r[i] = in->r ? in->r[i] : 0;
    }
    if (in->K) {
        for (i = 0; i < nr; ++i) {
            gen_rt_real s = 0;
            for (j = 0; j < ns; ++j) {
                int idx = j < niq ? m->q_ind[j] : nq + m->u_ind[j - niq];
                s += in->K[(long)i * ns + j] * (x[idx] - (in->x_op ? in->x_op[idx] : 0));
            }
            r[i] -= s;
        }
    }
    if (in->controller && in->controller(in->ctx, t, x, r)) return GEN_RT_ERR_CONTROLLER;
    if (!finite_n(nr, r)) return GEN_RT_ERR_NONFINITE_INPUT;
    return GEN_RT_OK;
}

static int input_check(const gen_rt_model *m, const gen_rt_input *in)
{
    int i, nr = m->nr, ns = m->nq - m->mc + m->nu - m->mv;
    if (!in) return GEN_RT_ERR_NULL;
    if (in->n_table < 0 || (in->hold != GEN_RT_HOLD_ZOH && in->hold != GEN_RT_HOLD_LINEAR))
        return GEN_RT_ERR_BAD_ARG;
    if (!finite_n(1, &in->period) || in->period < 0) return GEN_RT_ERR_BAD_ARG;
    if (in->n_table > 0) {
        if (!in->t_table || (nr > 0 && !in->r_table)) return GEN_RT_ERR_NULL;
        if (!finite_n(in->n_table, in->t_table) || !finite_n(in->n_table * nr, in->r_table))
            return GEN_RT_ERR_NONFINITE_INPUT;
        for (i = 1; i < in->n_table; ++i)
            if (!(in->t_table[i] > in->t_table[i - 1])) return GEN_RT_ERR_BAD_ARG;
    } else if (in->r && !finite_n(nr, in->r)) {
        return GEN_RT_ERR_NONFINITE_INPUT;
    }
    if (in->K && !finite_n(nr * ns, in->K)) return GEN_RT_ERR_NONFINITE_INPUT;
    if (in->x_op && !finite_n(NX_(m), in->x_op)) return GEN_RT_ERR_NONFINITE_INPUT;
    return GEN_RT_OK;
}

int gen_rt_model_eval_input(const gen_rt_model *m, const gen_rt_input *in, gen_rt_real t,
                            const gen_rt_real *x, gen_rt_real *r)
{
    int st = input_check(m, in);
    if (st) return st;
    return input_at(m, in, t, t, x, r);
}

static int rhs_cb(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *dxdt)
{
    const model_ctx *c = (const model_ctx *)ctx;
    const gen_rt_real *r = c->r;
    if (c->in && !(c->in->period > 0)) {
        int st = input_at(c->m, c->in, t, c->t_seg, x, c->r_buf);
        if (st) return st;
        r = c->r_buf;
    }
    return gen_rt_model_rhs(c->m, t, x, r, c->p, c->work, c->iwork, dxdt, NULL);
}

static int post_cb(void *ctx, gen_rt_real t, gen_rt_real *x)
{
    const model_ctx *c = (const model_ctx *)ctx;
    return gen_rt_model_project(c->m, t, c->p, c->proj_tol, c->proj_max_iter, c->work, x);
}

int gen_rt_model_step_rk4(const gen_rt_model *m, gen_rt_real t, gen_rt_real h,
                          const gen_rt_real *r, const gen_rt_real *p, int project,
                          gen_rt_real *work, int *iwork, gen_rt_real *x)
{
    int nx = NX_(m), st;
    gen_rt_real *rk = work, *xn = rk + GEN_RT_RK4_WORK(nx);
    model_ctx c;
    c.m = m; c.r = r; c.p = p;
    c.proj_tol = 16 * GEN_RT_EPS; c.proj_max_iter = 10;
    c.work = xn + nx; c.iwork = iwork;
    c.in = NULL; c.r_buf = c.r_held = NULL; c.t_seg = t; c.t0 = t;
    c.t_sampled = t; c.sampled = 0;
    copy_n(nx, x, xn);
    st = gen_rt_rk4_step(rhs_cb, &c, nx, t, h, rk, xn);
    if (st) return st;
    if (project) {
        st = gen_rt_model_project(m, t + h, p, c.proj_tol, c.proj_max_iter, c.work, xn);
        if (st) return st;
    }
    copy_n(nx, xn, x);
    return GEN_RT_OK;
}

/* one integration from t0 to t1 (one RK4 step, or DOPRI5 steps) */
static int integrate_(model_ctx *c, gen_rt_real t0, gen_rt_real t1,
                      const gen_rt_sim_options *o, gen_rt_real *work, gen_rt_sim_stats *s,
                      gen_rt_real *x)
{
    const gen_rt_model *m = c->m;
    int nx = NX_(m), st;
    if (o->method == GEN_RT_METHOD_RK4) {
        gen_rt_real *rk = work, *xn = rk + GEN_RT_RK4_WORK(nx);
        copy_n(nx, x, xn);
        st = gen_rt_rk4_step(rhs_cb, c, nx, t0, t1 - t0, rk, xn);
        s->n_rhs += 4;
        if (!st && o->project)
            st = gen_rt_model_project(m, t1, c->p, c->proj_tol, c->proj_max_iter, c->work, xn);
        if (st) {
            s->t_last = t0;
            copy_n(nx, x, s->x_last);
            return st;
        }
        copy_n(nx, xn, x);
        s->n_accepted += 1;
    } else if (o->method == GEN_RT_METHOD_DOPRI5) {
        gen_rt_dopri5_opts d;
        gen_rt_dopri5_stats ds;
        gen_rt_real t_reached = t0;
        d.rtol = o->rtol; d.atol = o->atol; d.h_init = o->h_init;
        d.h_min = o->h_min; d.h_max = o->h_max; d.max_steps = o->max_steps;
        ds.n_accepted = 0; ds.n_rejected = 0; ds.n_rhs = 0; ds.h_last = s->h_next;
        st = gen_rt_dopri5_integrate(rhs_cb, o->project ? post_cb : NULL, c, nx, t0, t1, &d,
                                     work, &ds, &t_reached, x);
        s->n_accepted += ds.n_accepted;
        s->n_rejected += ds.n_rejected;
        s->n_rhs += ds.n_rhs;
        s->h_next = ds.h_last;
        if (st) {
            s->t_last = t_reached;
            copy_n(nx, x, s->x_last);
            return st;
        }
    } else {
        return GEN_RT_ERR_BAD_ARG;
    }
    s->t_last = t1;
    copy_n(nx, x, s->x_last);
    return GEN_RT_OK;
}

/* a time within a relative rounding of a sample or knot counts as it */
static gen_rt_real time_tol(gen_rt_real t)
{
    gen_rt_real a = t < 0 ? -t : t;
    return 64 * GEN_RT_EPS * (a > 1 ? a : 1);
}

/* is t a sample time t0 + k period? */
static int is_sample(const model_ctx *c, gen_rt_real t)
{
    gen_rt_real per = c->in->period, k;
    if (!(per > 0)) return 0;
    k = (gen_rt_real)(long)((t - c->t0) / per + GEN_RT_C(0.5));
    return (t - (c->t0 + k * per)) <= time_tol(t) && (c->t0 + k * per - t) <= time_tol(t);
}

/* the end of the sub-interval from t towards t1: the next sample or knot */
static gen_rt_real next_break(const model_ctx *c, gen_rt_real t, gen_rt_real t1)
{
    const gen_rt_input *in = c->in;
    gen_rt_real tb = t1, tol = time_tol(t);
    if (in->period > 0) {
        long k = (long)((t - c->t0) / in->period) + 1;
        gen_rt_real ts = c->t0 + (gen_rt_real)k * in->period;
        if (ts <= t + tol) ts = c->t0 + (gen_rt_real)(k + 1) * in->period;
        if (ts < tb - time_tol(tb)) tb = ts;
    }
    if (in->n_table > 0) {
        int k = table_row(in->n_table, in->t_table, t + tol);
        gen_rt_real tk;
        if (in->t_table[k] <= t + tol) ++k;
        if (k < in->n_table) {
            tk = in->t_table[k];
            if (tk > t + tol && tk < tb - time_tol(tb)) tb = tk;
        }
    }
    return tb;
}

/* integrate t0 -> t1 with inputs from c->in: sub-intervals end at samples
 * and knots; at a sample the held r is refreshed from the state there */
static int advance_input_(model_ctx *c, gen_rt_real t0, gen_rt_real t1,
                          const gen_rt_sim_options *o, gen_rt_real *work, gen_rt_sim_stats *s,
                          gen_rt_real *x)
{
    gen_rt_real t = t0;
    int st;
    if (!c->in) return integrate_(c, t0, t1, o, work, s, x);
    while (t < t1) {
        gen_rt_real tb = next_break(c, t, t1);
        if (is_sample(c, t) && !(c->sampled && c->t_sampled == t)) {
            c->sampled = 1;
            c->t_sampled = t;
            st = input_at(c->m, c->in, t, t, x, c->r_held);
            if (st) {
                s->t_last = t;
                copy_n(NX_(c->m), x, s->x_last);
                return st;
            }
        }
        c->t_seg = t;
        st = integrate_(c, t, tb, o, work, s, x);
        if (st) return st;
        t = tb;
    }
    return GEN_RT_OK;
}

int gen_rt_model_advance(const gen_rt_model *m, gen_rt_real t0, gen_rt_real t1,
                         const gen_rt_real *r, const gen_rt_real *p,
                         const gen_rt_sim_options *o, gen_rt_real *work, int *iwork,
                         gen_rt_sim_stats *s, gen_rt_real *x)
{
    int nx = NX_(m);
    int nint = GEN_RT_RK4_WORK(nx) + nx > GEN_RT_DOPRI5_WORK(nx) ? GEN_RT_RK4_WORK(nx) + nx
                                                                 : GEN_RT_DOPRI5_WORK(nx);
    model_ctx c;
    if (!(t1 >= t0)) return GEN_RT_ERR_BAD_ARG;
    c.m = m; c.r = r; c.p = p;
    c.proj_tol = o->proj_tol; c.proj_max_iter = o->proj_max_iter;
    c.work = work + nint; c.iwork = iwork;
    c.in = NULL; c.r_buf = c.r_held = NULL; c.t_seg = t0; c.t0 = t0;
    c.t_sampled = t0; c.sampled = 0;
    return integrate_(&c, t0, t1, o, work, s, x);
}

int gen_rt_simulate_rows(gen_rt_real t0, gen_rt_real t_end, gen_rt_real dt)
{
    long n;
    if (!(dt > 0) || !(t_end >= t0) || !finite_n(1, &t0) || !finite_n(1, &t_end))
        return GEN_RT_ERR_BAD_ARG;
    if ((t_end - t0) / dt > GEN_RT_C(1e9)) return GEN_RT_ERR_BAD_ARG;
    n = (long)((t_end - t0) / dt);
    if (t0 + (gen_rt_real)n * dt < t_end - GEN_RT_C(1e-9) * dt) n += 1;
    return (int)(n + 1);
}

int gen_rt_simulate_rows_kept(int rows, int every, int final_only)
{
    if (rows <= 0) return rows;
    if (final_only) return 1;
    if (every <= 1) return rows;
    return (rows - 1) / every + 1 + ((rows - 1) % every != 0);
}

/* simulate and simulate_input: in == NULL for a constant r */
static int simulate_(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                     gen_rt_real t_end, gen_rt_real dt, const gen_rt_real *r,
                     const gen_rt_input *in, const gen_rt_real *p,
                     const gen_rt_sim_options *o, int capacity, gen_rt_real *work, int *iwork,
                     gen_rt_real *t_out, gen_rt_real *x_out, gen_rt_real *lam_out,
                     gen_rt_real *r_out, gen_rt_sim_stats *s)
{
    int nx = NX_(m), nr = m->nr, mv = m->mv, ldl = mv > 0 ? mv : 1, rows, k, i, st;
    int nint = GEN_RT_RK4_WORK(nx) + nx > GEN_RT_DOPRI5_WORK(nx) ? GEN_RT_RK4_WORK(nx) + nx
                                                                 : GEN_RT_DOPRI5_WORK(nx);
    gen_rt_real *x = work, *dx = x + nx, *lam = dx + nx, *w = lam + mv + 1;
    gen_rt_real *rb = w + GEN_RT_MODEL_ADVANCE_WORK(m->nq, m->nu, m->mc, mv, nr,
                                                    m->explicit_kinematics, m->accel);
    model_ctx c;
    gen_rt_real t_prev = t0;
    s->n_accepted = 0; s->n_rejected = 0; s->n_rhs = 0;
    s->n_out = 0; s->t_last = t0; s->h_next = 0;
    copy_n(nx, x0, x);
    copy_n(nx, x0, s->x_last);
    rows = gen_rt_simulate_rows(t0, t_end, dt);
    if (rows < 0) return rows;
    if (o->every < 0 || o->final_only < 0) return GEN_RT_ERR_BAD_ARG;
    if (capacity < gen_rt_simulate_rows_kept(rows, o->every, o->final_only))
        return GEN_RT_ERR_OUTPUT_FULL;
    c.m = m; c.p = p;
    c.proj_tol = o->proj_tol; c.proj_max_iter = o->proj_max_iter;
    c.work = w + nint; c.iwork = iwork;
    c.in = in; c.t_seg = t0; c.t0 = t0; c.t_sampled = t0; c.sampled = 0;
    c.r_buf = in ? rb : NULL;
    c.r_held = in ? rb + nr + 1 : NULL;
    c.r = in ? (in->period > 0 ? c.r_held : c.r_buf) : r;
    if (o->project) {
        st = gen_rt_model_project(m, t0, p, o->proj_tol, o->proj_max_iter, w, x);
        if (st) return st;
    }
    for (k = 0; k < rows; ++k) {
        gen_rt_real tk = (k == rows - 1) ? t_end : t0 + (gen_rt_real)k * dt;
        const gen_rt_real *rk = r;
        if (k > 0) {
            st = advance_input_(&c, t_prev, tk, o, w, s, x);
            if (st) return st;
        }
        if (in) {
            /* the inputs in effect from tk on: a new sample at a sample time,
             * else the held one; continuous: evaluated here */
            if (in->period > 0 && (k == 0 || is_sample(&c, tk))) {
                c.sampled = 1;
                c.t_sampled = tk;
                st = input_at(m, in, tk, tk, x, c.r_held);
            } else if (!(in->period > 0)) {
                st = input_at(m, in, tk, tk, x, c.r_buf);
            } else {
                st = GEN_RT_OK;
            }
            if (st) {
                s->t_last = tk;
                copy_n(nx, x, s->x_last);
                return st;
            }
            rk = c.r;
        }
        st = gen_rt_model_rhs(m, tk, x, rk, p, w, iwork, dx, lam);
        if (st) {
            s->t_last = tk;
            copy_n(nx, x, s->x_last);
            return st;
        }
        if (o->final_only ? k == rows - 1
                          : (o->every <= 1 || k % o->every == 0 || k == rows - 1)) {
            long j = s->n_out;
            t_out[j] = tk;
            copy_n(nx, x, x_out + j * nx);
            if (lam_out)
                for (i = 0; i < mv; ++i) lam_out[j * ldl + i] = lam[i];
            if (r_out)
                for (i = 0; i < nr; ++i) r_out[j * nr + i] = rk ? rk[i] : 0;
            s->n_out = (int)j + 1;
        }
        t_prev = tk;
    }
    return GEN_RT_OK;
}

int gen_rt_model_simulate(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                          gen_rt_real t_end, gen_rt_real dt, const gen_rt_real *r,
                          const gen_rt_real *p, const gen_rt_sim_options *o, int capacity,
                          gen_rt_real *work, int *iwork, gen_rt_real *t_out,
                          gen_rt_real *x_out, gen_rt_real *lam_out, gen_rt_sim_stats *s)
{
    return simulate_(m, x0, t0, t_end, dt, r, NULL, p, o, capacity, work, iwork, t_out, x_out,
                     lam_out, NULL, s);
}

int gen_rt_model_simulate_input(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                                gen_rt_real t_end, gen_rt_real dt, const gen_rt_input *in,
                                const gen_rt_real *p, const gen_rt_sim_options *o,
                                int capacity, gen_rt_real *work, int *iwork,
                                gen_rt_real *t_out, gen_rt_real *x_out, gen_rt_real *lam_out,
                                gen_rt_real *r_out, gen_rt_sim_stats *s)
{
    int st = input_check(m, in);
    s->n_accepted = 0; s->n_rejected = 0; s->n_rhs = 0;
    s->n_out = 0; s->t_last = t0; s->h_next = 0;
    copy_n(NX_(m), x0, s->x_last);
    if (st) return st;
    return simulate_(m, x0, t0, t_end, dt, NULL, in, p, o, capacity, work, iwork, t_out, x_out,
                     lam_out, r_out, s);
}

/* ------------------------------------------------------------------ */
/* Linearization about any operating point                             */
/* ------------------------------------------------------------------ */

static int linearize_(const gen_rt_model *m, const gen_rt_real *x_op,
                      const gen_rt_real *r_op, const gen_rt_real *p, gen_rt_real t,
                      gen_rt_real *work, int *iwork, gen_rt_real *A_lin, gen_rt_real *B_lin,
                      gen_rt_real *Y, gen_rt_real *C_lin, gen_rt_real *D_lin);

int gen_rt_model_linearize(const gen_rt_model *m, const gen_rt_real *x_op,
                           const gen_rt_real *r_op, const gen_rt_real *p, gen_rt_real t,
                           gen_rt_real *work, int *iwork, gen_rt_real *A_lin,
                           gen_rt_real *B_lin)
{
    return linearize_(m, x_op, r_op, p, t, work, iwork, A_lin, B_lin, NULL, NULL, NULL);
}

int gen_rt_model_linearize_outputs(const gen_rt_model *m, const gen_rt_real *x_op,
                                   const gen_rt_real *r_op, const gen_rt_real *p,
                                   gen_rt_real t, gen_rt_real *work, int *iwork,
                                   gen_rt_real *A_lin, gen_rt_real *B_lin, gen_rt_real *C_lin,
                                   gen_rt_real *D_lin)
{
    int ny = m->ny, nq = m->nq, nu = m->nu, nr = m->nr;
    gen_rt_real *Y = work, *w = work + ny * (nq + nu + nr) + 1;
    if (ny <= 0 || !m->output_jacobian)
        return linearize_(m, x_op, r_op, p, t, work, iwork, A_lin, B_lin, NULL, NULL, NULL);
    return linearize_(m, x_op, r_op, p, t, w, iwork, A_lin, B_lin, Y, C_lin, D_lin);
}

int gen_rt_model_eval_outputs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                              const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *y)
{
    if (m->ny <= 0 || !m->outputs) return GEN_RT_OK;
    m->outputs(x, x + m->nq, r, p, t, y);
    return finite_n(m->ny, y) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

/* Y: ny (nq + nu + nr) reals for the output Jacobians, or NULL */
static int linearize_(const gen_rt_model *m, const gen_rt_real *x_op,
                      const gen_rt_real *r_op, const gen_rt_real *p, gen_rt_real t,
                      gen_rt_real *work, int *iwork, gen_rt_real *A_lin, gen_rt_real *B_lin,
                      gen_rt_real *Y, gen_rt_real *C_lin, gen_rt_real *D_lin)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nr = m->nr, st;
    const gen_rt_real *q = x_op, *u = x_op + nq;
    gen_rt_real *qd = work, *ud = qd + nq, *lam = ud + nu, *M = lam + mv + 1, *f = M + nu * nu,
                *A = f + nu, *a = A + mv * nu, *Kqd = a + mv, *Kq = Kqd + nq * nq,
                *Ku = Kq + nq * nq, *Rq = Ku + nq * nu, *Ru = Rq + nu * nq, *Rr = Ru + nu * nu,
                *Sq = Rr + nu * nr, *Su = Sq + mv * nq, *Vq = Su + mv * nu, *Jc = Vq + mv * nq,
                *Sqd = Jc + mc * nq, *scratch = Sqd + mv * nq;
    int sw = GEN_RT_ACCEL_WORK(nu, mv);
    gen_rt_real Bdummy[1];
    gen_rt_lin_out o;
    gen_rt_lin_dims d;
    gen_rt_lin_blocks b;
    if (sw < GEN_RT_MODEL_KIN_WORK(nq, nu, mc, mv, nr, m->explicit_kinematics, m->accel))
        sw = GEN_RT_MODEL_KIN_WORK(nq, nu, mc, mv, nr, m->explicit_kinematics, m->accel);
    if (sw < nq + nu * nu + nu + nq * nq) sw = nq + nu * nu + nu + nq * nq;
    /* accelerations and multipliers at the operating point */
    st = gen_rt_model_eval_kinematics(m, q, u, p, t, scratch, iwork, qd);
    if (st) return st;
    m->mass_matrix(q, p, t, M);
    m->forcing(q, u, r_op, p, t, f);
    if (!finite_n(nu * nu, M) || !finite_n(nu, f)) return GEN_RT_ERR_NONFINITE_MODEL;
    if (mv) {
        /* A and a from the joint right-hand-side kernel (its other outputs
         * are not needed here) */
        gen_rt_real *qdt = scratch, *Mt = qdt + nq, *ft = Mt + nu * nu, *Kt = ft + nu;
        m->rhs_terms(q, u, r_op, p, t, m->explicit_kinematics ? NULL : Kt, qdt, Mt, ft, A, a);
        if (m->accel_terms) m->accel_terms(q, u, qd, p, t, a);
        if (!finite_n(mv * nu, A) || !finite_n(mv, a)) return GEN_RT_ERR_NONFINITE_MODEL;
        st = gen_rt_accel_kkt(nu, mv, M, f, A, a, scratch, iwork, ud, lam);
        if (st) return st;
    } else if (m->accel == GEN_RT_ACCEL_LDLT) {
        if ((st = m->mass_solve(M, f, ud))) return st;
        if (!finite_n(nu, ud)) return GEN_RT_ERR_SINGULAR;
        lam[0] = 0;
    } else {
        st = gen_rt_accel_kkt(nu, 0, M, f, NULL, NULL, scratch, iwork, ud, NULL);
        if (st) return st;
        lam[0] = 0;
    }
    o.Kqd = Kqd; o.Ku = Ku; o.M = M; o.A = A; o.Kq = Kq; o.Rq = Rq; o.Ru = Ru; o.Rr = Rr;
    o.Sq = Sq; o.Su = Su; o.Vq = Vq; o.Jc = Jc; o.Sqd = Sqd;
    m->lin_terms(q, u, qd, ud, lam, r_op, p, t, &o);
    d.nq = nq; d.nu = nu; d.mc = mc; d.mv = mv; d.nr = nr;
    d.q_ind = m->q_ind; d.q_dep = m->q_dep; d.u_ind = m->u_ind; d.u_dep = m->u_dep;
    b.Kqd = Kqd; b.Kq = Kq; b.Ku = Ku; b.M = M; b.Rq = Rq; b.Ru = Ru;
    b.Rr = nr ? Rr : NULL; b.A = mv ? A : NULL;
    b.Sq = mv ? Sq : NULL; b.Su = mv ? Su : NULL;
    b.Vq = mv ? Vq : NULL; b.Jc = mc ? Jc : NULL;
    b.Sqd = (mv && m->accel_terms) ? Sqd : NULL;
    b.ny = 0; b.Yq = b.Yu = b.Yr = NULL; b.C_lin = b.D_lin = NULL;
    if (Y && C_lin) {
        int ny = m->ny;
        gen_rt_real *Yq = Y, *Yu = Yq + ny * nq, *Yr = Yu + ny * nu;
        m->output_jacobian(q, u, r_op, p, t, Yq, Yu, Yr);
        b.ny = ny; b.Yq = Yq; b.Yu = Yu; b.Yr = nr ? Yr : NULL;
        b.C_lin = C_lin; b.D_lin = nr ? D_lin : NULL;
    }
    if (!finite_n(nq * nq, Kq) || !finite_n(nu * nq, Rq) || !finite_n(nu * nu, Ru) ||
        !finite_n(mv * nq, Sq) || !finite_n(mv * nu, Su) || !finite_n(mc * nq, Jc) ||
        !finite_n(mv * nq, Vq) || !finite_n(nu * nr, Rr) ||
        (b.Sqd && !finite_n(mv * nq, Sqd)))
        return GEN_RT_ERR_NONFINITE_MODEL;
    return gen_rt_linearize(&d, &b, scratch + sw, iwork, A_lin, nr ? B_lin : Bdummy);
}

int gen_rt_model_linearize_discrete(const gen_rt_model *m, const gen_rt_real *x_op,
                                    const gen_rt_real *r_op, const gen_rt_real *p,
                                    gen_rt_real t, gen_rt_real dt, gen_rt_real *work,
                                    int *iwork, gen_rt_real *Ad, gen_rt_real *Bd)
{
    int ns = m->nq - m->mc + m->nu - m->mv, nr = m->nr, st;
    gen_rt_real *A = work, *B = A + ns * ns, *w = B + ns * nr + 1;
    if (!(dt > 0) || !finite_n(1, &dt)) return GEN_RT_ERR_BAD_ARG;
    st = gen_rt_model_linearize(m, x_op, r_op, p, t, w, iwork, A, B);
    if (st) return st;
    return gen_rt_c2d_zoh(ns, nr, A, nr ? B : NULL, dt, w, iwork, Ad, Bd);
}
