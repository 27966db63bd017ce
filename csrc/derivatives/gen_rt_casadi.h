/*
 * gen_rt_casadi.h - a model's functions in CasADi's calling convention for
 * external functions (res = f(arg), CasADi's dense column-major blocks),
 * over the model's C API and its derivative kernels (gen_rt_deriv.h).
 *
 * A library (templates/casadi) describes each of its functions as data, a
 * gen_rt_cs_fn: the base function (rhs, implicit, step, step_rodas4,
 * outputs, constraints), its inputs in order (x, xdot, r, p, t, h) and
 * what the function computes of it (mode):
 *   VALUE    the base function: res[0] = f(x, ...)
 *   JAC      jac_<f>: inputs f's then its output, outputs the blocks
 *            jac_<out>_<in> (rows x columns of input in)
 *   FWD      fwd1_<f>: inputs f's, its output, a forward seed per input;
 *            res[0] = J seed
 *   ADJ      adj1_<f>: inputs f's, its output, the adjoint seed of the
 *            output; res[i] = J_i^T seed
 *   JAC_JAC  jac_jac_<f>: the Jacobians of the JAC blocks w.r.t. f's
 *            inputs and output (the output's blocks are structural zeros)
 *   JAC_FWD  jac_fwd1_<f>: the Jacobians of FWD's output w.r.t. its inputs
 *   JAC_ADJ  jac_adj1_<f>: the Jacobians of ADJ's outputs w.r.t. its
 *            inputs (the Hessian blocks of seed^T f, and J_i^T)
 * (the functions CasADi finds by name for its derivatives). A NULL arg[i]
 * is an input of zeros, a NULL res[i] an output not wanted. The step
 * functions' inputs are (x, r, p, t, h): v = (z, h) of gen_rt_deriv_rk4.
 *
 * gen_rt_cs_eval_inline (gen_rt_casadi_inline.h) is the same function,
 * static inline, for a library that compiles it with its model as a
 * constant (templates/casadi: the same bits, faster).
 *
 * No heap, no globals, no stdio. work: GEN_RT_CS_WORK reals, iwork:
 * GEN_RT_CS_IWORK ints, one size for every function of a model. Returns 0
 * or the status of the model's function or of the derivative algorithm
 * (GEN_RT_ERR_BAD_ARG for h = 0 in RODAS4 or a second derivative the
 * library has no kernels for; GEN_RT_ERR_NONFINITE_MODEL for a derivative
 * that is NaN/inf).
 */
#ifndef GEN_RT_CASADI_H
#define GEN_RT_CASADI_H

#include "gen_rt.h"
#include "gen_rt_deriv.h"

#ifdef __cplusplus
extern "C" {
#endif

/* an input of a function */
enum { GEN_RT_CS_X = 1, GEN_RT_CS_XDOT, GEN_RT_CS_R, GEN_RT_CS_P, GEN_RT_CS_T, GEN_RT_CS_H };
/* the base functions */
enum {
    GEN_RT_CS_RHS = 1, GEN_RT_CS_IMPLICIT, GEN_RT_CS_STEP, GEN_RT_CS_STEP_RODAS4,
    GEN_RT_CS_OUTPUTS, GEN_RT_CS_CONSTRAINTS
};
/* what a function computes of its base */
enum {
    GEN_RT_CS_VALUE = 0, GEN_RT_CS_JAC, GEN_RT_CS_FWD, GEN_RT_CS_ADJ, GEN_RT_CS_JAC_JAC,
    GEN_RT_CS_JAC_FWD, GEN_RT_CS_JAC_ADJ
};
#define GEN_RT_CS_MAX_IN 6

typedef struct {
    int base, mode;
    int nin;                   /* the base function's inputs */
    int in[GEN_RT_CS_MAX_IN];  /* what each is: GEN_RT_CS_X, ... */
} gen_rt_cs_fn;

/* J = dk/dz (n x nz) of an explicit function k(z) (outputs, constraints) */
typedef void (*gen_rt_cs_jac_fn)(const gen_rt_real *z, gen_rt_real *J);
/* H = d2(mu^T k)/dz2 (nz x nz) */
typedef void (*gen_rt_cs_hess_fn)(const gen_rt_real *z, const gen_rt_real *mu, gen_rt_real *H);

typedef struct {
    int nq, nu, nr, np, mc, mv, ny;
    int t_dep;                 /* f holds t (RODAS4's value needs df/dt) */
    gen_rt_deriv_model d;      /* R(z, w) = 0: x' and the multipliers */
    gen_rt_cs_jac_fn y1, c1;   /* the outputs y(z), the constraints [f_c; A u + b] */
    gen_rt_cs_hess_fn yh, ch;  /* NULL: first derivatives only */
    /* the model's C API (<name>.h) */
    int (*rhs)(gen_rt_real t, const gen_rt_real *x, const gen_rt_real *r, const gen_rt_real *p,
               gen_rt_real *dxdt, gen_rt_real *lam);
    int (*step_rk4)(gen_rt_real t, gen_rt_real h, const gen_rt_real *r, const gen_rt_real *p,
                    int project, gen_rt_real *x);
    int (*jacobian)(gen_rt_real t, const gen_rt_real *x, const gen_rt_real *r,
                    const gen_rt_real *p, gen_rt_real *Jx, gen_rt_real *Jr);
    int (*outputs)(gen_rt_real t, const gen_rt_real *x, const gen_rt_real *r,
                   const gen_rt_real *p, gen_rt_real *y);
    int (*constraints)(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                       gen_rt_real *fc);
    int (*velocity_constraints)(const gen_rt_real *q, const gen_rt_real *u,
                                const gen_rt_real *p, gen_rt_real t, gen_rt_real *fv);
} gen_rt_cs_model;

/* sizes: z, the most differentiable inputs (implicit's), the most rows */
#define GEN_RT_CS_NZ_(nx, nr, np) ((nx) + (nr) + (np) + 1)
#define GEN_RT_CS_NV_(nx, nr, np) (GEN_RT_CS_NZ_(nx, nr, np) + (nx))
#define GEN_RT_CS_MR_(nx, mc, mv, ny) GEN_RT_MAX_(GEN_RT_MAX_(1, (nx) + (mc) + (mv)), (ny))
#define GEN_RT_CS_CALL_WORK_(nx, nr, np, mc, mv, ny)                              \
    (2 * (nx) + (nr) + (np) + GEN_RT_CS_NZ_(nx, nr, np) + GEN_RT_CS_MR_(nx, mc, mv, ny) + \
     GEN_RT_CS_MR_(nx, mc, mv, ny) * GEN_RT_CS_NV_(nx, nr, np) *                   \
         (1 + GEN_RT_CS_NV_(nx, nr, np)) +                                       \
     GEN_RT_CS_NV_(nx, nr, np) * (GEN_RT_CS_NV_(nx, nr, np) + 1))
#define GEN_RT_CS_EXPLICIT_WORK_(nz, mr) ((mr) * (nz) + (mr) + (nz) * (nz))
#define GEN_RT_CS_RODAS4_VALUE_WORK_(nx, nr, nz, nw)                              \
    (2 * (nx) + (nx) * (nx) + (nx) * (nr) + 1 + GEN_RT_RODAS4_WORK(nx) +          \
     GEN_RT_DERIV_POINT_(nz, nw) + GEN_RT_DERIV_SOLVE_WORK(nw))
#define GEN_RT_CS_WORK(nx, nr, np, mc, mv, ny)                                    \
    (GEN_RT_CS_CALL_WORK_(nx, nr, np, mc, mv, ny) +                               \
     GEN_RT_MAX_(GEN_RT_MAX_(GEN_RT_DERIV_RK4_WORK(nx, GEN_RT_CS_NZ_(nx, nr, np), (nx) + (mv)), \
                             GEN_RT_DERIV_RODAS4_WORK(nx, GEN_RT_CS_NZ_(nx, nr, np), (nx) + (mv))), \
                 GEN_RT_MAX_(GEN_RT_CS_EXPLICIT_WORK_(GEN_RT_CS_NZ_(nx, nr, np),    \
                                                      GEN_RT_CS_MR_(nx, mc, mv, ny)), \
                             GEN_RT_CS_RODAS4_VALUE_WORK_(nx, nr, GEN_RT_CS_NZ_(nx, nr, np), \
                                                          (nx) + (mv)))))
#define GEN_RT_CS_IWORK(nx, nr, np, mv)                                           \
    (GEN_RT_CS_NZ_(nx, nr, np) + 5 * ((nx) + (mv)) + (nx))

int gen_rt_cs_eval(const gen_rt_cs_model *m, const gen_rt_cs_fn *f, const gen_rt_real **arg,
                   gen_rt_real **res, gen_rt_real *work, int *iwork);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_CASADI_H */
