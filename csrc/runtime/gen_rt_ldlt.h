/*
 * gen_rt_ldlt.h - M x = f for a dense symmetric positive definite M by an
 * LDL^T in loops: the mass-matrix solve of a large model.
 *
 * A small model's solve is unrolled by the generator over M's structural
 * nonzeros (gen/plan/ldlt.py). From about two dozen speeds on, with M dense, the
 * unrolled code (n^3/3 statements) is slower than loops the compiler
 * vectorizes, and slower to compile (gen.plan.ldlt.LDLT_LOOP_MIN). This is
 * the same factorization in loops: the same IEEE operations in the same
 * order on every entry, so the solution is the unrolled solve's bit for bit
 * (tests/unit/plan/test_ldlt_loop.py):
 *
 *   c_ij = M_ij - sum_{k<j} c_ik l_jk      (k ascending; c_ij = l_ij d_j)
 *   d_j  = M_jj - sum_{k<j} c_jk c_jk id_k,   id_j = 1 / d_j,  l_ij = c_ij id_j
 *   y_i  = f_i - sum_{k<i} l_ik y_k         (k ascending)
 *   x_i  = y_i id_i - sum_{k>i} l_ki x_k    (k descending)
 *
 * Right-looking (a factored column updates every later column), so every
 * inner loop runs over independent rows: nothing is reassociated. Blocked
 * by four columns, so an entry is loaded and stored once per four terms.
 * Columns are padded to a multiple of four rows and every inner loop runs
 * over whole groups of four from the group holding the column's first row:
 * no remainder loops. The rows above a column's own are scratch (zeroed,
 * then holding finite garbage nothing reads as data).
 *
 * The caller's work array holds GEN_RT_LDLT_WORK(n) reals: M_ij (i > j) at
 * GEN_RT_LDLT_M(n, i, j), M_jj at GEN_RT_LDLT_D(n, j), f_i at
 * GEN_RT_LDLT_F(n, i) (gen_rt_ldlt_pack puts them there; a fused kernel
 * stores them there itself). The functions are static inline, always
 * inlined where the compiler allows: compiled in the caller's translation
 * unit for the caller's target (each GEN_RT_CLONES version), with the
 * caller's literal n.
 */
#ifndef GEN_RT_LDLT_H
#define GEN_RT_LDLT_H

#include "gen_rt.h"

#ifdef __cplusplus
extern "C" {
#endif

/* the solve is compiled into its caller: in a GEN_RT_CLONES kernel, once
 * per target (a call would reach one baseline copy), with the caller's
 * literal n */
#if defined(__GNUC__)
#define GEN_RT_LDLT_INLINE static inline __attribute__((always_inline))
#else
#define GEN_RT_LDLT_INLINE static inline
#endif

/* the leading dimension: n rounded up to four, so that every inner loop
 * runs over whole groups of four rows (one AVX vector of doubles, two SSE
 * ones) from a group's first row, with no remainder */
#define GEN_RT_LDLT_LD(n) (((n) + 3) / 4 * 4)
/* reals of work: C = L D strictly below the diagonal, by columns (LD x LD),
 * D (then the pivots d_j), the reciprocal pivots, and f (then y, then x) */
#define GEN_RT_LDLT_WORK(n) (GEN_RT_LDLT_LD(n) * GEN_RT_LDLT_LD(n) + 3 * (n))
/* where M_ij (i > j) goes in the work array */
#define GEN_RT_LDLT_M(n, i, j) ((j) * GEN_RT_LDLT_LD(n) + (i))
/* where M_jj goes */
#define GEN_RT_LDLT_D(n, j) (GEN_RT_LDLT_LD(n) * GEN_RT_LDLT_LD(n) + (j))
/* where f_i goes */
#define GEN_RT_LDLT_F(n, i) (GEN_RT_LDLT_LD(n) * GEN_RT_LDLT_LD(n) + 2 * (n) + (i))

#if defined(__cplusplus)
#define GEN_RT_RESTRICT __restrict
#else
#define GEN_RT_RESTRICT restrict
#endif

/* M (row-major n x n; its lower triangle and diagonal are read) and f
 * into the work array */
static inline void gen_rt_ldlt_pack(int n, const gen_rt_real *M, const gen_rt_real *f,
                                    gen_rt_real *work)
{
    int i, j;
    for (j = 0; j < n; ++j) {
        for (i = j + 1; i < n; ++i)
            work[GEN_RT_LDLT_M(n, i, j)] = M[i * n + j];
        work[GEN_RT_LDLT_D(n, j)] = M[j * n + j];
        work[GEN_RT_LDLT_F(n, j)] = f[j];
    }
}

/* c_i -= a_i s for the rows i of groups b0/4 .. b1/4 - 1 (the inner loop
 * of a column's update; the rows above the column's own are scratch) */
GEN_RT_LDLT_INLINE void gen_rt_ldlt_axpy_(int b0, int b1, gen_rt_real *GEN_RT_RESTRICT c,
                                          const gen_rt_real *GEN_RT_RESTRICT a, gen_rt_real s)
{
    int b, v;
    for (b = b0; b < b1; b += 4)
        for (v = b; v < b + 4; ++v)
            c[v] = c[v] - a[v] * s;
}

/* c_i -= a0_i s0, then a1_i s1, a2_i s2, a3_i s3 (four columns' updates in
 * their order, in one pass), rows as gen_rt_ldlt_axpy_ */
GEN_RT_LDLT_INLINE void gen_rt_ldlt_axpy4_(int b0, int b1, gen_rt_real *GEN_RT_RESTRICT c,
                                           const gen_rt_real *GEN_RT_RESTRICT a0,
                                           const gen_rt_real *GEN_RT_RESTRICT a1,
                                           const gen_rt_real *GEN_RT_RESTRICT a2,
                                           const gen_rt_real *GEN_RT_RESTRICT a3,
                                           gen_rt_real s0, gen_rt_real s1, gen_rt_real s2,
                                           gen_rt_real s3)
{
    int b, v;
    for (b = b0; b < b1; b += 4)
        for (v = b; v < b + 4; ++v)
            c[v] = c[v] - a0[v] * s0 - a1[v] * s1 - a2[v] * s2 - a3[v] * s3;
}

/* Factors and solves in place, blocked by four columns: each block's
 * columns are factored one after the other (a panel), then update every
 * later column in one pass (four terms per entry, in k's order). l_ik is
 * c_ik id_k wherever it is needed (the same product, so the same bits), so
 * L is never stored. rtol: a pivot must be above rtol times the largest
 * diagonal entry of M (which must be positive); otherwise, or on a NaN,
 * GEN_RT_ERR_SINGULAR and x is not written. On GEN_RT_OK x holds the
 * solution. The work array is overwritten. */
GEN_RT_LDLT_INLINE int gen_rt_ldlt_dense(int n, gen_rt_real rtol, gen_rt_real *work,
                                         gen_rt_real *x)
{
    const int N = GEN_RT_LDLT_LD(n);
    gen_rt_real *const d = work + N * N;
    gen_rt_real *const id = d + n;
    gen_rt_real *const y = id + n;
    gen_rt_real dmax = d[0], tol;
    int i, j, k, k0, ok;

    /* the scratch rows the groups of four read: from each column's own
     * group to its diagonal, and the padding below row n */
    for (j = 0; j < n; ++j) {
        gen_rt_real *const cj = work + j * N;
        for (i = (j + 1) / 4 * 4; i <= j; ++i)
            cj[i] = 0;
        for (i = n; i < N; ++i)
            cj[i] = 0;
    }
    for (j = 1; j < n; ++j)
        if (d[j] > dmax) dmax = d[j];
    for (k0 = 0; k0 < n; k0 += 4) {
        const int k1 = k0 + 4 < n ? k0 + 4 : n;
        /* the panel: columns k0 .. k1 - 1, and y's entries below each */
        for (k = k0; k < k1; ++k) {
            const gen_rt_real *const ck = work + k * N;
            const gen_rt_real idk = 1 / d[k];
            const gen_rt_real yk = y[k];
            id[k] = idk;
            for (i = k + 1; i < n; ++i)
                y[i] = y[i] - ck[i] * idk * yk;
            for (j = k + 1; j < k1; ++j) {
                d[j] = d[j] - ck[j] * ck[j] * idk;
                gen_rt_ldlt_axpy_((j + 1) / 4 * 4, N, work + j * N, ck, ck[j] * idk);
            }
        }
        /* the later columns, by the panel's four */
        if (k1 - k0 == 4) {
            const gen_rt_real *const a0 = work + k0 * N, *const a1 = a0 + N;
            const gen_rt_real *const a2 = a1 + N, *const a3 = a2 + N;
            const gen_rt_real i0 = id[k0], i1 = id[k0 + 1], i2 = id[k0 + 2], i3 = id[k0 + 3];
            for (j = k1; j < n; ++j) {
                d[j] = d[j] - a0[j] * a0[j] * i0 - a1[j] * a1[j] * i1
                       - a2[j] * a2[j] * i2 - a3[j] * a3[j] * i3;
                gen_rt_ldlt_axpy4_((j + 1) / 4 * 4, N, work + j * N, a0, a1, a2, a3,
                                   a0[j] * i0, a1[j] * i1, a2[j] * i2, a3[j] * i3);
            }
        }
    }
    /* x_i = y_i id_i - l_ki x_k, k from the last down, by blocks of four
     * k: each block's own triangle, then the rows above it, four terms at
     * a time (l_ki = c_ki id_i: row k of C, four neighbours in column i) */
    for (i = 0; i < n; ++i)
        y[i] = y[i] * id[i];
    for (k0 = (n - 1) / 4 * 4; k0 >= 0; k0 -= 4) {
        const int k1 = k0 + 4 < n ? k0 + 4 : n;
        for (k = k1 - 1; k > k0; --k) {
            const gen_rt_real zk = y[k];
            for (i = k0; i < k; ++i)
                y[i] = y[i] - work[i * N + k] * id[i] * zk;
        }
        if (k1 - k0 == 4) {
            const gen_rt_real z0 = y[k0], z1 = y[k0 + 1], z2 = y[k0 + 2], z3 = y[k0 + 3];
            for (i = 0; i < k0; ++i) {
                const gen_rt_real *const ci = work + i * N + k0;
                const gen_rt_real idi = id[i];
                y[i] = y[i] - ci[3] * idi * z3 - ci[2] * idi * z2 - ci[1] * idi * z1
                       - ci[0] * idi * z0;
            }
        } else {
            for (k = k1 - 1; k >= k0; --k) {
                const gen_rt_real zk = y[k];
                for (i = 0; i < k0; ++i)
                    y[i] = y[i] - work[i * N + k] * id[i] * zk;
            }
        }
    }
    tol = rtol * dmax;
    ok = dmax > 0;
    for (j = 0; j < n; ++j)
        ok = ok && d[j] > tol;
    if (!ok)
        return GEN_RT_ERR_SINGULAR;
    for (i = 0; i < n; ++i)
        x[i] = y[i];
    return GEN_RT_OK;
}

#ifdef __cplusplus
}
#endif

#endif /* GEN_RT_LDLT_H */
