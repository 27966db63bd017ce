/*
 * gen_rt_deriv.h - exact first and second derivatives of a model's
 * right-hand side and of one step of the runtime's integrators, over any
 * model given as kernels (a struct of function pointers, as gen_rt_model).
 *
 * The model is the equations its right-hand side solves, linear in w:
 *     R(z, w) = 0,   z = (x, r, p, t) (nz = nx + nr + np + 1, t = z[nz-1]),
 *     w = (x', multipliers) (nw >= nx, x' = w[0..nx)),
 * given by three kernels: Rw = dR/dw and R(z, 0) (r0), dR/dz at a w (rz),
 * and the second derivatives d2(mu^T R)/dz2 and d(Rw^T mu)/dz (rh; only the
 * functions that give second derivatives or the RODAS4 step's first ones
 * call it). With them, exactly (no finite differences):
 *     dw/dz = -Rw^-1 dR/dz,
 *     d2(lam^T w)/dz2 = -(d2(mu^T R)/dz2 + W^T dw/dz + (dw/dz)^T W),
 *     Rw^T mu = lam,  W = d(Rw^T mu)/dz
 * (the second-order adjoint of the implicit function). On that:
 *   gen_rt_deriv_solve     w and dw/dz at z (and Rw's LU, for the next),
 *   gen_rt_deriv_hessian   d2(lam^T w)/dz2,
 *   gen_rt_deriv_rk4       one step of the runtime's RK4 (gen_rt_rk4_step's
 *                          stages and arithmetic: x+ bit for bit) and its
 *                          first and second derivatives over v = (z, h),
 *   gen_rt_deriv_rodas4    the first derivatives over v = (z, h) of one
 *                          RODAS4 trial step (gen_rt_rodas4_trial, the
 *                          tableau of gen_rt_rodas4.h) with Jf and df/dt
 *                          from dw/dz.
 *
 * gen_rt_deriv_inline.h has each as a static inline function,
 * gen_rt_deriv_<f>_inline (the same bits), for a translation unit that
 * calls them with its model as a constant (the CasADi library).
 *
 * Matrices are row-major; derivatives over v have nv = nz + 1 columns (h
 * last). No heap, no globals, no stdio; work arrays are the caller's, sized
 * by the macros below. Statuses: those of the factorizations
 * (GEN_RT_ERR_SINGULAR), GEN_RT_ERR_NONFINITE_MODEL when a kernel or a
 * result is NaN/inf, GEN_RT_ERR_BAD_ARG when a second derivative is asked
 * of a model without rh, or h = 0 for RODAS4.
 */
#ifndef GEN_RT_DERIV_H
#define GEN_RT_DERIV_H

#include "gen_rt.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Rw = dR/dw (nw x nw), R0 = R(z, 0) (nw) */
typedef void (*gen_rt_deriv_r0_fn)(const gen_rt_real *z, gen_rt_real *Rw, gen_rt_real *R0);
/* Rz = dR/dz at w (nw x nz) */
typedef void (*gen_rt_deriv_rz_fn)(const gen_rt_real *z, const gen_rt_real *w, gen_rt_real *Rz);
/* H = d2(mu^T R)/dz2 (nz x nz) and W = d(Rw^T mu)/dz (nw x nz) at w */
typedef void (*gen_rt_deriv_rh_fn)(const gen_rt_real *z, const gen_rt_real *w,
                                   const gen_rt_real *mu, gen_rt_real *H, gen_rt_real *W);

typedef struct {
    int nx, nz, nw;
    gen_rt_deriv_r0_fn r0;
    gen_rt_deriv_rz_fn rz;
    gen_rt_deriv_rh_fn rh; /* NULL: first derivatives only */
} gen_rt_deriv_model;

/* ---- the implicit function w(z) --------------------------------------
 * w solves R(z, w) = 0; lu (nw x nw) and piv (nw) hold Rw's LU factors;
 * Jw = dw/dz (nw x nz; NULL: not wanted). work: GEN_RT_DERIV_SOLVE_WORK. */
#define GEN_RT_DERIV_SOLVE_WORK(nw) (nw)
int gen_rt_deriv_solve(const gen_rt_deriv_model *m, const gen_rt_real *z, gen_rt_real *work,
                       gen_rt_real *w, gen_rt_real *lu, int *piv, gen_rt_real *Jw);

/* H = d2(lam^T w)/dz2 (nz x nz, symmetric) at a solution of
 * gen_rt_deriv_solve (w, lu, piv, Jw); lam has nw entries. */
#define GEN_RT_DERIV_HESSIAN_WORK(nz, nw) ((nw) + (nz) * (nz) + (nw) * (nz))
int gen_rt_deriv_hessian(const gen_rt_deriv_model *m, const gen_rt_real *z,
                         const gen_rt_real *w, const gen_rt_real *lu, const int *piv,
                         const gen_rt_real *Jw, const gen_rt_real *lam, gen_rt_real *work,
                         gen_rt_real *H);

/* ---- one RK4 step -----------------------------------------------------
 * From z = (x, r, p, t) with step h (r, p held): x+ exactly as
 * gen_rt_rk4_step computes it (xn; NULL: not wanted), and over
 * v = (z, h) (nv = nz + 1):
 *   J  = dx+/dv (nx x nv),
 *   T  = d2x+/dv2 (nx x nv x nv: T[(i nv + a) nv + b]), forward over
 *        forward, stage by stage,
 *   Hl = d2(lam^T x+)/dv2 (nv x nv): from T when T is asked too, else by
 *        one adjoint sweep over the stages (lam NULL: zero),
 * each NULL when not wanted (Hl and T need m->rh). The stages are
 * zeta_k = (x + c_k h K_{k-1}, r, p, t + c_k h) with the runtime's c_k h
 * (0, h/2, h/2, h) and x+ = x + (h/6)(K_1 + 2 (K_2 + K_3) + K_4); with
 * D_k = dK_k/dv, dzeta_k/dv = E_c + [X_k; 0] (X_k = c_k (h D_{k-1} +
 * K_{k-1} e_h^T)), so every product with it costs nx, not nz, per entry. */
#define GEN_RT_DERIV_POINT_(nz, nw) ((nw) + (nw) * (nw) + (nw) * (nz))
#define GEN_RT_DERIV_RK4_WORK(nx, nz, nw)                                        \
    (GEN_RT_DERIV_POINT_(nz, nw) + GEN_RT_DERIV_SOLVE_WORK(nw) + (nw) + (nz) * (nz) + \
     GEN_RT_DERIV_HESSIAN_WORK(nz, nw) + 8 * (nx) + (nz) +                        \
     6 * (nx) * ((nz) + 1) + ((nz) + 1) * (2 * (nz) + 1) +                        \
     4 * (nx) * ((nz) + 1) * ((nz) + 1) +                                         \
     4 * ((nz) + GEN_RT_DERIV_POINT_(nz, nw) + 2 * (nx) * ((nz) + 1)))
#define GEN_RT_DERIV_RK4_IWORK(nw) (5 * (nw))
int gen_rt_deriv_rk4(const gen_rt_deriv_model *m, const gen_rt_real *z, gen_rt_real h,
                     const gen_rt_real *lam, gen_rt_real *work, int *iwork, gen_rt_real *xn,
                     gen_rt_real *J, gen_rt_real *Hl, gen_rt_real *T);

/* ---- one RODAS4 step, first derivatives --------------------------------
 * J = dx+/dv (nx x nv, v = (z, h)) of gen_rt_rodas4_trial from x = z[0..nx)
 * at t = z[nz-1] with f = w[0..nx), its Jacobian Jf_x and df/dt from dw/dz
 * at z. With G = I/(h gamma) - Jf_x, the stages
 *   G K_s = f(zeta_s) + sum_j (C_sj / h) K_j + h gamma_s df/dt,
 *   zeta_s = (x + sum_j A_sj K_j, r, p, t + alpha_s h),
 * x+ = x + A51 K1 + A52 K2 + A53 K3 + A54 K4 + K5 + K6 differentiate to
 *   G dK_s = dF_s - dG K_s,   dG_c = -d(Jf_x)/dv_c - delta_ch I/(h^2 gamma),
 * d(Jf)/dz from the Hessians of f (gen_rt_deriv_hessian; needs m->rh). */
#define GEN_RT_DERIV_RODAS4_WORK(nx, nz, nw)                                     \
    (GEN_RT_DERIV_POINT_(nz, nw) + GEN_RT_DERIV_SOLVE_WORK(nw) + (nw) +            \
     GEN_RT_DERIV_HESSIAN_WORK(nz, nw) + (nx) + (nx) * (nz) + (nx) * (nz) * (nz) + \
     (nx) * (nx) + 6 * (nx) + 6 * (nx) * ((nz) + 1) + (nz) * ((nz) + 1) +          \
     (nx) * ((nz) + 1) + (nz))
#define GEN_RT_DERIV_RODAS4_IWORK(nx, nw) ((nw) + (nx))
int gen_rt_deriv_rodas4(const gen_rt_deriv_model *m, const gen_rt_real *z, gen_rt_real h,
                        gen_rt_real *work, int *iwork, gen_rt_real *J);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_DERIV_H */
