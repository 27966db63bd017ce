/*
 * gen_rt_sens.h - exact derivatives of a model's right-hand side and of one
 * classic RK4 step ("step sensitivities"), for an extended Kalman filter or
 * a shooting MPC: the variational equations of the step, evaluated with
 * the model's generated Jacobian kernels (lin_terms), no finite differences.
 *
 * Row-major arrays, no heap, no globals, no stdio, as in gen_rt.h; the work
 * arrays are the caller's, sized by the macros below (constant expressions
 * taking the same arguments as the GEN_RT_MODEL_*_WORK macros of gen_rt.h:
 * (nq, nu, mc, mv, nr, explicit_kinematics, accel)). Inputs are assumed
 * checked (non-NULL where the sizes call for it, finite), as for the other
 * gen_rt_model_* functions. Outputs are written only on success.
 *
 * Statuses: those of gen_rt_model_rhs (the right-hand side at the point or
 * at a stage), GEN_RT_ERR_NONFINITE_MODEL when a Jacobian block of the
 * model is NaN/inf, GEN_RT_ERR_SINGULAR_KINEMATICS when Kqd cannot be
 * factored, GEN_RT_ERR_SINGULAR when the KKT matrix [M, -A^T; A, 0] or a
 * dependent block of the constraint Jacobians (Jc, A) is singular, and
 * GEN_RT_ERR_DIVERGED when the step or its derivative overflows.
 */
#ifndef GEN_RT_SENS_H
#define GEN_RT_SENS_H

#include "gen_rt.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- the full-state Jacobian of the right-hand side ------------------
 * gen_rt_model_rhs computes x' = f(t, x, r), x = [q; u] (nx = nq + nu).
 * gen_rt_model_jacobian gives Jx = df/dx (nx x nx) and Jr = df/dr
 * (nx x nr; may be NULL when nr == 0), every entry of x free (dependent
 * coordinates and speeds too, and x need not satisfy the constraints):
 *   q' rows:  Kqd dq' = -(Kq dq + Ku du)
 *   u' rows:  [M, -A^T; A, 0] [du'; dlam] = -[Rq dq + Ru du + Rr dr;
 *                                              Sq dq + Su du + Sqd dq']
 * with the blocks of the model's lin_terms kernel evaluated at x and at the
 * q', u' and multipliers lam that gen_rt_model_rhs itself solves there
 * (Sqd only for a model whose acceleration-constraint term holds q', i.e.
 * with accel_terms). The kinematics hold no inputs: the q' rows of Jr are
 * zero. A Kane model's partitioned accelerations solve the same equations
 * as the KKT system (also off the constraint manifold), so this is their
 * derivative too. A failure of the right-hand side at x is returned as is. */

/* reals: the blocks of lin_terms, q' rows and the KKT solve, given the
 * point (internal) */
#define GEN_RT_SENS_CORE_WORK_(nq, nu, mc, mv, nr)                              \
    (3 * (nq) * (nq) + 2 * (nq) * (nu) + 2 * (nu) * (nu) + (nu) * (nr) +         \
     2 * (mv) * (nu) + 3 * (mv) * (nq) + (mc) * (nq) +                          \
     (nq) * GEN_RT_NX_(nq, nu) + ((nu) + (mv)) * ((nu) + (mv)) +                 \
     ((nu) + (mv)) * (GEN_RT_NX_(nq, nu) + (nr)) + 16)
/* reals: the constraint elimination of the step's output convention */
#define GEN_RT_SENS_ELIM_WORK_(nq, nu, mc, mv)                                  \
    ((mc) * (mc) + (mc) * (nq) + (mv) * (mv) + (mv) * ((nq) + (nu)) + 4)

#define GEN_RT_MODEL_JACOBIAN_WORK(nq, nu, mc, mv, nr, ek, acc)                 \
    (GEN_RT_NX_(nq, nu) + (mv) + 1 +                                            \
     GEN_RT_MAX_(GEN_RT_MODEL_RHS_WORK(nq, nu, mc, mv, nr, ek, acc),            \
                 GEN_RT_SENS_CORE_WORK_(nq, nu, mc, mv, nr)))
#define GEN_RT_MODEL_JACOBIAN_IWORK(nq, nu, mc, mv, nr, ek, acc)                \
    GEN_RT_MODEL_RHS_IWORK(nq, nu, mc, mv, nr, ek, acc)

int gen_rt_model_jacobian(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                          const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                          int *iwork, gen_rt_real *Jx, gen_rt_real *Jr);

/* ---- one RK4 step and its exact derivatives --------------------------
 * gen_rt_model_step_sensitivity takes one classic RK4 step of size h from
 * (t, x) with the inputs r held constant: the same stages and arithmetic as
 * gen_rt_model_step_rk4 with project = 0 (x1 is bit-identical to it), x
 * updated in place (unchanged on failure). Through the stages it propagates
 * the variational equations, with Jx_i, Jr_i the Jacobians of f at stage i
 * (gen_rt_model_jacobian) and dk_i = d k_i / d[x, r] (nx x (nx + nr)):
 *   dk_i = Jx_i Y_i + [0, Jr_i],   Y_1 = [I, 0],  Y_2 = [I, 0] + h/2 dk_1,
 *   Y_3 = [I, 0] + h/2 dk_2,       Y_4 = [I, 0] + h dk_3,
 *   [Fx_full, Fr_full] = [I, 0] + h/6 (dk_1 + 2 dk_2 + 2 dk_3 + dk_4),
 * exact derivatives of the computed x1 (up to rounding), not of the flow.
 *
 * Output convention (that of gen_rt_model_linearize): on the independent
 * state x_ind = [q_ind; u_ind] (ns = nq - mc + nu - mv, in the order of
 * m->q_ind then m->u_ind):
 *   Fx (ns x ns) = P_ind Fx_full E,    Fr (ns x nr) = P_ind Fr_full,
 * P_ind picking the rows q_ind and nq + u_ind of x, and E (nx x ns) the
 * map from an independent perturbation to the full perturbation that keeps
 * the constraint residuals f_c(q) and A(q) u + b at their values at x to
 * first order (x is normally on the constraint manifold):
 *   E = [Q, 0; Uq, Uu],   Jc Q = 0 with Q's q_ind rows = I,
 *   A [Uq, Uu] + [Vq Q, 0] = 0 with [Uq, Uu]'s u_ind rows = [0, I],
 * Jc = df_c/dq, A, Vq = d(A u + b)/dq at x. So Fx is what a user gets by
 * perturbing x_ind, completing the dependent entries
 * (gen_rt_model_consistent_state), stepping without projection and reading
 * x1_ind. Without constraints ns = nx and Fx is the full dx1/dx.
 * Fr may be NULL when nr == 0. Cost: the four right-hand sides of the step,
 * four lin_terms evaluations and O(nx^2 (nx + nr)) per stage. */
#define GEN_RT_MODEL_STEP_SENS_WORK(nq, nu, mc, mv, nr, ek, acc)                \
    (5 * GEN_RT_NX_(nq, nu) + (mv) + 1 +                                        \
     4 * GEN_RT_NX_(nq, nu) * (GEN_RT_NX_(nq, nu) + (nr)) +                     \
     GEN_RT_NX_(nq, nu) * GEN_RT_NS_(nq, nu, mc, mv) +                          \
     GEN_RT_NS_(nq, nu, mc, mv) * (GEN_RT_NS_(nq, nu, mc, mv) + (nr)) +         \
     GEN_RT_MAX_(GEN_RT_MODEL_RHS_WORK(nq, nu, mc, mv, nr, ek, acc),            \
                 GEN_RT_SENS_CORE_WORK_(nq, nu, mc, mv, nr) +                   \
                     GEN_RT_SENS_ELIM_WORK_(nq, nu, mc, mv)))
#define GEN_RT_MODEL_STEP_SENS_IWORK(nq, nu, mc, mv, nr, ek, acc)               \
    GEN_RT_MODEL_RHS_IWORK(nq, nu, mc, mv, nr, ek, acc)

int gen_rt_model_step_sensitivity(const gen_rt_model *m, gen_rt_real t, gen_rt_real h,
                                  const gen_rt_real *r, const gen_rt_real *p,
                                  gen_rt_real *work, int *iwork, gen_rt_real *x,
                                  gen_rt_real *Fx, gen_rt_real *Fr);

/* ---- the map from the independent state to the full state ------------
 * gen_rt_model_state_map gives E (nx x ns) at x: an independent
 * perturbation [dq_ind; du_ind] to the full perturbation that keeps the
 * constraint residuals f_c(q) and A(q) u + b at their values at x to first
 * order (the E of the step's output convention above). A function g(x) of
 * the full state has g_x E as its derivative on the independent state (a
 * Kalman filter's measurement Jacobian, gen.EKF). Without constraints E
 * only picks the independent entries (the identity on x). r: the inputs
 * (NULL when nr == 0). Statuses: GEN_RT_ERR_NONFINITE_MODEL when a
 * constraint Jacobian is NaN/inf, GEN_RT_ERR_SINGULAR when a dependent
 * block is singular; E is written only on success. */
#define GEN_RT_MODEL_STATE_MAP_WORK(nq, nu, mc, mv, nr, ek, acc)                \
    (2 * GEN_RT_NX_(nq, nu) + (nr) + (mv) + 4 + GEN_RT_SENS_CORE_WORK_(nq, nu, mc, mv, nr) + \
     GEN_RT_SENS_ELIM_WORK_(nq, nu, mc, mv) + GEN_RT_NX_(nq, nu) * GEN_RT_NS_(nq, nu, mc, mv))
#define GEN_RT_MODEL_STATE_MAP_IWORK(nq, nu, mc, mv, nr, ek, acc) ((mc) + (mv) + 1)

int gen_rt_model_state_map(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                           const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                           int *iwork, gen_rt_real *E);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_SENS_H */
