/*
 * gen_rt_expm.h - the matrix exponential and the zero-order-hold
 * discretization of a continuous linear system (gen_rt_expm.c).
 *
 * Scaling and squaring with a diagonal Pade approximant (N. J. Higham, "The
 * scaling and squaring method for the matrix exponential revisited", SIAM J.
 * Matrix Anal. Appl. 26(4), 2005): the degree m is the lowest of
 * 3, 5, 7, 9, 13 whose theta_m bounds the 1-norm of A; beyond theta_13 the
 * matrix is scaled by 2^-s to that bound and the approximant squared s
 * times. With gen_rt_real = float the degrees stop at 7 (the single
 * precision thetas of the same paper).
 *
 * Row-major n x n arrays as everywhere in the runtime; no heap, no globals,
 * no stdio: the work arrays belong to the caller, sized by the macros below
 * (constant expressions). Every function returns GEN_RT_OK (0) or a
 * negative GEN_RT_ERR_* code, and writes its outputs only on success.
 */
#ifndef GEN_RT_EXPM_H
#define GEN_RT_EXPM_H

#include "gen_rt.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Work lengths of gen_rt_expm (reals and ints) for an n x n matrix. */
#define GEN_RT_EXPM_WORK(n) (6 * (n) * (n) + 1)
#define GEN_RT_EXPM_IWORK(n) ((n) + 1)

/* E = exp(A), A and E n x n. E may be the same array as A.
 * GEN_RT_ERR_NULL: A, work, iwork or E is NULL; GEN_RT_ERR_BAD_ARG: n <= 0;
 * GEN_RT_ERR_NONFINITE_INPUT: an entry of A is NaN or infinite;
 * GEN_RT_ERR_SINGULAR: the Pade denominator could not be factored (does not
 * happen for finite A: its condition number is bounded by the choice of the
 * degree); GEN_RT_ERR_DIVERGED: exp(A) overflows the scalar type. */
int gen_rt_expm(int n, const gen_rt_real *A, gen_rt_real *work, int *iwork,
                gen_rt_real *E);

/* Work lengths of gen_rt_c2d_zoh (reals and ints), ns states, nr inputs. */
#define GEN_RT_C2D_WORK(ns, nr)                                               \
    (((ns) + (nr)) * ((ns) + (nr)) + GEN_RT_EXPM_WORK((ns) + (nr)))
#define GEN_RT_C2D_IWORK(ns, nr) GEN_RT_EXPM_IWORK((ns) + (nr))

/* Zero-order-hold discretization of x' = A x + B r with the input held over
 * a step dt:  exp([A, B; 0, 0] dt) = [Ad, Bd; 0, I], A ns x ns, B ns x nr,
 * Ad ns x ns, Bd ns x nr (Ad = exp(A dt), Bd = int_0^dt exp(A s) ds B).
 * B may be NULL when nr == 0 (Bd is then not touched and may be NULL).
 * B is scaled by a power of two to the magnitude of A before the
 * exponential (and Bd back): the input units do not change the number of
 * squarings, and the result is the same up to rounding.
 * GEN_RT_ERR_NULL: a required pointer is NULL; GEN_RT_ERR_BAD_ARG: ns <= 0,
 * nr < 0, or dt not finite and > 0; GEN_RT_ERR_NONFINITE_INPUT: A or B holds
 * NaN or inf; GEN_RT_ERR_SINGULAR and GEN_RT_ERR_DIVERGED as gen_rt_expm
 * (DIVERGED also when A dt or B dt overflows). */
int gen_rt_c2d_zoh(int ns, int nr, const gen_rt_real *A, const gen_rt_real *B,
                   gen_rt_real dt, gen_rt_real *work, int *iwork, gen_rt_real *Ad,
                   gen_rt_real *Bd);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_EXPM_H */
