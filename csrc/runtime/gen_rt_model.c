/* gen_rt_model.c - what the public API does with a model at one point:
 * evaluation, the right-hand side, projection and consistent states, and
 * linearization, over the kernels of a gen_rt_model (integration: the
 * engine of gen_rt_engine.c and gen_rt_simulate.c).
 *
 * Inputs are assumed checked by the caller (the generated wrappers): the
 * pointers the sizes call for are non-NULL and every input is finite. Work
 * arrays are the caller's, sized by the GEN_RT_MODEL_*_WORK macros of
 * gen_rt.h. The arithmetic is laid out so that a generated model gives the
 * same numbers, bit for bit, as the code the generator used to inline. */
#include "gen_rt_private.h"

/* ------------------------------------------------------------------ */
/* Evaluation                                                         */
/* ------------------------------------------------------------------ */

int gen_rt_model_eval_mass_matrix(const gen_rt_model *m, const gen_rt_real *q,
                                  const gen_rt_real *p, gen_rt_real t, gen_rt_real *M)
{
    m->mass_matrix(q, p, t, M);
    return rt_finite(m->nu * m->nu, M) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_forcing(const gen_rt_model *m, const gen_rt_real *q,
                              const gen_rt_real *u, const gen_rt_real *r,
                              const gen_rt_real *p, gen_rt_real t, gen_rt_real *f)
{
    m->forcing(q, u, r, p, t, f);
    return rt_finite(m->nu, f) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

/* q' from the kinematic equations' outputs: explicit, qd holds q' (checked);
 * implicit, Kqd q' = qd is solved in place (Kqd overwritten). Any failure
 * is the kinematics' own status. */
static int solve_kinematics(const gen_rt_model *m, gen_rt_real *Kqd, int *piv, gen_rt_real *qd)
{
    int nq = m->nq;
    if (m->explicit_kinematics)
        return rt_finite(nq, qd) ? GEN_RT_OK : GEN_RT_ERR_SINGULAR_KINEMATICS;
    if (!rt_finite(nq * nq, Kqd) || !rt_finite(nq, qd)) return GEN_RT_ERR_SINGULAR_KINEMATICS;
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
    return rt_finite(m->mc, fc) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_constraint_jacobian(const gen_rt_model *m, const gen_rt_real *q,
                                          const gen_rt_real *p, gen_rt_real t,
                                          gen_rt_real *work, gen_rt_real *Jc)
{
    if (!m->mc) return GEN_RT_OK;
    m->constraint_jacobian(q, p, t, work, Jc);
    return rt_finite(m->mc * m->nq, Jc) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_velocity_constraints(const gen_rt_model *m, const gen_rt_real *q,
                                           const gen_rt_real *u, const gen_rt_real *p,
                                           gen_rt_real t, gen_rt_real *fv)
{
    if (!m->mv) return GEN_RT_OK;
    m->velocity_constraints(q, u, p, t, fv);
    return rt_finite(m->mv, fv) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_eval_velocity_constraint_matrix(const gen_rt_model *m,
                                                 const gen_rt_real *q,
                                                 const gen_rt_real *p, gen_rt_real t,
                                                 gen_rt_real *A, gen_rt_real *b)
{
    if (!m->mv) return GEN_RT_OK;
    m->velocity_constraint_matrix(q, p, t, A, b);
    return (rt_finite(m->mv * m->nu, A) && rt_finite(m->mv, b)) ? GEN_RT_OK
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
    return rt_finite(1, E) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

/* ------------------------------------------------------------------ */
/* The right-hand side                                                */
/* ------------------------------------------------------------------ */

static int rhs_(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work, int *iwork,
                gen_rt_real *dxdt, gen_rt_real *lam);

/* a failure at a state that has run away (beyond GEN_RT_DIVERGED_ABS, or
 * an integrator stage that overflowed) is divergence, not a singular
 * configuration of the model */
static int failure_at_(const gen_rt_model *m, const gen_rt_real *x, int st)
{
    if (!gen_rt_all_finite(RT_NX(m), x) || gen_rt_max_abs(RT_NX(m), x) > GEN_RT_DIVERGED_ABS)
        return GEN_RT_ERR_DIVERGED;
    return st;
}

int gen_rt_model_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                     const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                     int *iwork, gen_rt_real *dxdt, gen_rt_real *lam)
{
    int st = rhs_(m, t, x, r, p, work, iwork, dxdt, lam);
    return st ? failure_at_(m, x, st) : GEN_RT_OK;
}

static int rhs_(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work, int *iwork,
                gen_rt_real *dxdt, gen_rt_real *lam)
{
    int nq = m->nq, nu = m->nu, mv = m->mv, st;
    const gen_rt_real *q = x, *u = x + nq;
    gen_rt_real *M = work, *f = M + nu * nu, *A = f + nu, *a = A + mv * nu,
                *Kqd = a + mv;
    if (m->reaction_solve) {
        /* reactions inside the motion: u' and the reactions from one
         * linear system (the model's blocks, gen_rt_accel_reactions) */
        m->rhs_terms(q, u, r, p, t, m->explicit_kinematics ? NULL : Kqd, dxdt, M, f, NULL,
                     NULL);
        if ((st = solve_kinematics(m, Kqd, iwork, dxdt))) return st;
        if (!rt_finite(nu * nu, M) || !rt_finite(nu, f)) return GEN_RT_ERR_NONFINITE_MODEL;
        return m->reaction_solve(q, u, r, p, t, M, f, dxdt + nq, NULL);
    }
    if (m->explicit_kinematics &&
        (m->rhs_solve ? !(mv && lam) : m->accel == GEN_RT_ACCEL_LDLT)) {
        /* the common unconstrained case in one pass (no constraints with
         * LDL^T), and a small constrained model without its multipliers:
         * q' and u' from the model's fused right-hand side (or its kernel
         * and its solve), one check of the whole x'; a failure goes through
         * the general path below, which names it */
        if (m->rhs_solve) {
            st = m->rhs_solve(q, u, r, p, t, dxdt, NULL, NULL, dxdt + nq);
        } else {
            m->rhs_terms(q, u, r, p, t, NULL, dxdt, M, f, NULL, NULL);
            st = m->mass_solve(M, f, dxdt + nq);
        }
        if (!st && gen_rt_finite_n(nq + nu, dxdt)) return GEN_RT_OK;
    }
    gen_rt_real *w = Kqd + (m->explicit_kinematics ? 0 : nq * nq);
    int *kpiv = iwork, *iw = iwork + nq;
    m->rhs_terms(q, u, r, p, t, m->explicit_kinematics ? NULL : Kqd, dxdt, M, f,
                 mv ? A : NULL, mv ? a : NULL);
    if ((st = solve_kinematics(m, Kqd, kpiv, dxdt))) return st;
    if (m->accel == GEN_RT_ACCEL_LDLT && !mv) {
        /* The unrolled LDL^T reads M's lower triangle (the upper holds the
         * same values) and rejects a pivot that is not > its tolerance: NaN
         * or inf in M ends there (an infinite diagonal makes every
         * tolerance infinite) or in a non-finite solution, and so does NaN
         * or inf in f. So a finite solution means finite M and f, and only a
         * failure pays for the checks that name the culprit. */
        st = m->mass_solve(M, f, dxdt + nq);
        if (!st && rt_finite(nu, dxdt + nq)) return GEN_RT_OK;
        if (!rt_finite(nu * nu, M) || !rt_finite(nu, f)) return GEN_RT_ERR_NONFINITE_MODEL;
        /* an overflowing solution (a tiny mass under a large force) is
         * singular, as with LU */
        return st ? st : GEN_RT_ERR_SINGULAR;
    }
    if (mv && m->accel_terms) m->accel_terms(q, u, dxdt, p, t, a);
    if (!rt_finite(nu * nu, M) || !rt_finite(nu, f)) return GEN_RT_ERR_NONFINITE_MODEL;
    if (mv) {
        if (!rt_finite(mv * nu, A) || !rt_finite(mv, a)) return GEN_RT_ERR_NONFINITE_MODEL;
        if (m->accel == GEN_RT_ACCEL_PARTITIONED)
            /* Kane: eliminate the dependent speeds through the partition */
            return gen_rt_accel_partitioned(nu, mv, m->u_ind, m->u_dep, M, f, A, a, w, iw,
                                            dxdt + nq, lam);
        /* Lagrange: accelerations and multipliers from the KKT system */
        return gen_rt_accel_kkt(nu, mv, M, f, A, a, w, iw, dxdt + nq, lam);
    }
    return gen_rt_accel_kkt(nu, 0, M, f, NULL, NULL, w, iw, dxdt + nq, NULL);
}

int gen_rt_model_eval_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                          const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                          int *iwork, gen_rt_real *dxdt, gen_rt_real *lam)
{
    int st;
    if (m->rhs_solve && !(m->mv && lam)) {
        /* the fused right-hand side, straight (rhs_ below names a failure;
         * it also gives a constrained model's multipliers) */
        const int nq = m->nq, nu = m->nu;
        st = m->rhs_solve(x, x + nq, r, p, t, work, NULL, NULL, work + nq);
        if (!st && gen_rt_finite_n(nq + nu, work)) {
            rt_copy(nq + nu, work, dxdt);
            return GEN_RT_OK;
        }
    }
    st = rhs_(m, t, x, r, p, work + RT_NX(m), iwork, work, lam);
    if (st) return failure_at_(m, x, st);
    rt_copy(RT_NX(m), work, dxdt);
    return GEN_RT_OK;
}

int gen_rt_model_eval_auxiliary_forces(const gen_rt_model *m, gen_rt_real t,
                                       const gen_rt_real *x, const gen_rt_real *r,
                                       const gen_rt_real *p, gen_rt_real *work, int *iwork,
                                       gen_rt_real *F)
{
    int na = m->na, i, st;
    gen_rt_real *dx = work, *Fm = dx + RT_NX(m), *g = Fm + na * na, *w = g + na;
    if (na <= 0 || !m->auxiliary) return GEN_RT_OK;
    if (m->reaction_solve) {
        /* the reactions enter the motion: they come with u' from the
         * coupled solve (the auxiliary equations alone may not determine
         * them) */
        int nu = m->nu;
        gen_rt_real *M = w, *f = M + nu * nu, *Kqd = f + nu;
        m->rhs_terms(x, x + m->nq, r, p, t, m->explicit_kinematics ? NULL : Kqd, dx, M, f,
                     NULL, NULL);
        if (!rt_finite(nu * nu, M) || !rt_finite(nu, f))
            return failure_at_(m, x, GEN_RT_ERR_NONFINITE_MODEL);
        st = m->reaction_solve(x, x + m->nq, r, p, t, M, f, dx + m->nq, g);
        if (st) return failure_at_(m, x, st);
        rt_copy(na, g, F);
        return GEN_RT_OK;
    }
    /* u' of the real speeds, then the auxiliary equations at them */
    st = gen_rt_model_rhs(m, t, x, r, p, w, iwork, dx, NULL);
    if (st) return st;
    m->auxiliary(x, x + m->nq, dx + m->nq, r, p, t, Fm, g);
    if (!rt_finite(na * na, Fm) || !rt_finite(na, g)) return GEN_RT_ERR_NONFINITE_MODEL;
    for (i = 0; i < na; ++i) g[i] = -g[i];
    /* a singular F (finite): the reactions are not determined here */
    if (gen_rt_lu_factor(na, Fm, iwork, 0) || gen_rt_lu_solve(na, Fm, iwork, 1, g) ||
        !rt_finite(na, g))
        return GEN_RT_ERR_SINGULAR_REACTIONS;
    rt_copy(na, g, F);
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
    return (rt_finite(m->mc, fc) && rt_finite(m->mc * m->nq, Jc)) ? GEN_RT_OK
                                                                : GEN_RT_ERR_NONFINITE_MODEL;
}

/* A and b of the velocity constraints at q, checked the same way */
static int velocity_matrix_at(const gen_rt_model *m, const gen_rt_real *q, const gen_rt_real *p,
                              gen_rt_real t, gen_rt_real *A, gen_rt_real *b)
{
    m->velocity_constraint_matrix(q, p, t, A, b);
    return (rt_finite(m->mv * m->nu, A) && rt_finite(m->mv, b)) ? GEN_RT_OK
                                                             : GEN_RT_ERR_NONFINITE_MODEL;
}

int gen_rt_model_project(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *p,
                         gen_rt_real tol, int max_iter, gen_rt_real *work, gen_rt_real *x)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nx = RT_NX(m), i, j, st;
    int nw = (mc * mc + mc > mv * mv + mv ? mc * mc + mc : mv * mv + mv) + 1;
    gen_rt_real *xc = work, *w = xc + nx, *fc = w + nw, *Jc = fc + mc, *q0 = Jc + mc * nq,
                *A = q0 + nq, *b = A + mv * nu, *res = b + mv;
    if (!mc && !mv) return GEN_RT_OK;
    rt_copy(nx, x, xc);
    if (mc) {
        int it, converged = 0;
        if (max_iter <= 0) max_iter = 10;
        if (!(tol > 0)) tol = 16 * GEN_RT_EPS;
        for (it = 0; it < max_iter; ++it) {
            gen_rt_real dmax = 0;
            if ((st = constraint_jacobian_at(m, xc, p, t, fc, Jc))) return st;
            rt_copy(nq, xc, q0);
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
    if (!rt_finite(nx, xc)) return GEN_RT_ERR_NONFINITE_MODEL;
    rt_copy(nx, xc, x);
    return GEN_RT_OK;
}

int gen_rt_model_consistent_state(const gen_rt_model *m, gen_rt_real t,
                                  const gen_rt_real *p, gen_rt_real tol, int max_iter,
                                  gen_rt_real *work, int *iwork, gen_rt_real *x)
{
    int nq = m->nq, nu = m->nu, mc = m->mc, mv = m->mv, nx = RT_NX(m), i, j, st;
    gen_rt_real *xc = work, *fc = xc + nx, *Jc = fc + mc, *Jd = Jc + mc * nq,
                *A = Jd + mc * mc, *b = A + mv * nu, *Ad = b + mv, *rhs = Ad + mv * mv;
    int *piv = iwork, *piv2 = iwork + mc;
    if (!mc && !mv) return GEN_RT_OK;
    rt_copy(nx, x, xc);
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
    if (!rt_finite(nx, xc)) return GEN_RT_ERR_NONFINITE_MODEL;
    rt_copy(nx, xc, x);
    return GEN_RT_OK;
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
    return rt_finite(m->ny, y) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
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
    {
        /* M, f (and A, a) from the joint right-hand-side kernel; its
         * kinematics outputs are not needed here */
        gen_rt_real *qdt = scratch, *Kt = qdt + nq;
        m->rhs_terms(q, u, r_op, p, t, m->explicit_kinematics ? NULL : Kt, qdt, M, f, A, a);
    }
    if (!rt_finite(nu * nu, M) || !rt_finite(nu, f)) return GEN_RT_ERR_NONFINITE_MODEL;
    if (m->reaction_solve) {
        /* u' of the coupled solve (lin_terms then writes the blocks of its
         * derivative, by the implicit function theorem) */
        if ((st = m->reaction_solve(q, u, r_op, p, t, M, f, ud, NULL))) return st;
        lam[0] = 0;
    } else if (mv) {
        if (m->accel_terms) m->accel_terms(q, u, qd, p, t, a);
        if (!rt_finite(mv * nu, A) || !rt_finite(mv, a)) return GEN_RT_ERR_NONFINITE_MODEL;
        st = gen_rt_accel_kkt(nu, mv, M, f, A, a, scratch, iwork, ud, lam);
        if (st) return st;
    } else if (m->accel == GEN_RT_ACCEL_LDLT) {
        if ((st = m->mass_solve(M, f, ud))) return st;
        if (!rt_finite(nu, ud)) return GEN_RT_ERR_SINGULAR;
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
    if (!rt_finite(nq * nq, Kq) || !rt_finite(nu * nq, Rq) || !rt_finite(nu * nu, Ru) ||
        !rt_finite(mv * nq, Sq) || !rt_finite(mv * nu, Su) || !rt_finite(mc * nq, Jc) ||
        !rt_finite(mv * nq, Vq) || !rt_finite(nu * nr, Rr) ||
        (b.Sqd && !rt_finite(mv * nq, Sqd)))
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
    if (!(dt > 0) || !rt_finite(1, &dt)) return GEN_RT_ERR_BAD_ARG;
    st = gen_rt_model_linearize(m, x_op, r_op, p, t, w, iwork, A, B);
    if (st) return st;
    return gen_rt_c2d_zoh(ns, nr, A, nr ? B : NULL, dt, w, iwork, Ad, Bd);
}
