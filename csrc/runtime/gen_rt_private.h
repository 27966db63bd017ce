/*
 * gen_rt_private.h - the runtime's own: the small helpers its files share
 * (static inline, written once here) and the KKT assembly.
 *
 * Not part of the API: a generated model includes gen_rt.h, never this.
 * Every function declared here is GEN_RT_INTERNAL (hidden in a shared
 * library) and, having external linkage, is renamed for the second scalar
 * type by csrc/eigen/gen_rt_names.h like the public ones.
 */
#ifndef GEN_RT_PRIVATE_H
#define GEN_RT_PRIVATE_H

#include <math.h>
#include <stddef.h>

#include "gen_rt.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- small helpers ----------------------------------------------------
 * (the largest magnitude is gen_rt_max_abs, gen_rt_linalg.c) */

/* 1 if the n values are finite (n <= 0: 1): gen_rt_finite_n of gen_rt.h,
 * inline and branch-free (gen_rt_all_finite is the same test out of line) */
static inline int rt_finite(int n, const gen_rt_real *v)
{
    return gen_rt_finite_n(n, v);
}

/* dst[0..n) = src[0..n) */
static inline void rt_copy(int n, const gen_rt_real *src, gen_rt_real *dst)
{
    int i;
    for (i = 0; i < n; ++i) dst[i] = src[i];
}

/* dst[0..n) = 0 */
static inline void rt_zero(int n, gen_rt_real *dst)
{
    int i;
    for (i = 0; i < n; ++i) dst[i] = 0;
}

/* the next n reals of a work array *w (a bump allocator over the caller's
 * work: the pieces follow one another in the order taken) */
static inline gen_rt_real *rt_take(gen_rt_real **w, int n)
{
    gen_rt_real *r = *w;
    *w += n;
    return r;
}

/* |a|, max and min without libm (NaN: as the comparisons fall) */
static inline gen_rt_real rt_abs(gen_rt_real a) { return a < 0 ? -a : a; }
static inline gen_rt_real rt_max(gen_rt_real a, gen_rt_real b) { return a > b ? a : b; }
static inline gen_rt_real rt_min(gen_rt_real a, gen_rt_real b) { return a < b ? a : b; }

/* the libm calls of the scalar type */
#ifdef GEN_RT_REAL_FLOAT
#define RT_POW powf
#define RT_FABS fabsf
#define RT_SQRT sqrtf
#else
#define RT_POW pow
#define RT_FABS fabs
#define RT_SQRT sqrt
#endif

/* a model's state length nx = nq + nu */
#define RT_NX(m) ((m)->nq + (m)->nu)

/* ---- the KKT matrix (gen_rt_dynamics.c) -------------------------------
 * K ((n + m) x (n + m), row-major) = [M, -A^T; A, 0], M n x n, A m x n:
 * the matrix of M u' - A^T lam = f, A u' = -a (gen_rt_accel_kkt), and of
 * its derivatives (gen_rt_linearize, gen_rt_model_jacobian). A may be NULL
 * when m == 0. */
GEN_RT_INTERNAL void gen_rt_kkt_matrix(int n, int m, const gen_rt_real *M,
                                       const gen_rt_real *A, gen_rt_real *K);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_PRIVATE_H */
