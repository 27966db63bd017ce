/* gen_rt_linalg.c - small dense LU (partial pivoting: the algorithms in
 * gen_rt_private.h) and Cholesky. */
#include "gen_rt_private.h"

gen_rt_real gen_rt_max_abs(int n, const gen_rt_real *v)
{
    return rt_max_abs(n, v);
}

int gen_rt_lu_factor(int n, gen_rt_real *a, int *piv, gen_rt_real scale)
{
    return rt_lu_factor(n, a, piv, scale);
}

int gen_rt_lu_solve(int n, const gen_rt_real *lu, const int *piv, int nrhs,
                    gen_rt_real *b)
{
    return rt_lu_solve(n, lu, piv, nrhs, b);
}

static gen_rt_real rt_sqrt(gen_rt_real x)
{
    /* Newton iteration: keeps the runtime free of libm for this one use.
     * The iteration starts at max(x, 1) and at worst halves per step, so x is
     * first brought into [2^-64, 2^64] by exact powers of 4 (sqrt scaled back
     * by the matching power of 2): within the 100-step cap for any x. */
    const gen_rt_real big = GEN_RT_C(18446744073709551616.0); /* 2^64 */
    const gen_rt_real half_big = GEN_RT_C(4294967296.0);      /* 2^32 */
    gen_rt_real y, s = 1;
    int it;
    if (!(x > 0)) return 0;
    if (x - x != 0) return x; /* inf */
    while (x > big) { x /= big; s *= half_big; }
    while (x < 1 / big) { x *= big; s /= half_big; }
    y = x > 1 ? x : GEN_RT_C(1.0);
    for (it = 0; it < 100; ++it) {
        gen_rt_real ny = GEN_RT_C(0.5) * (y + x / y);
        if (!(ny < y)) break;
        y = ny;
    }
    return y * s;
}

int gen_rt_chol_factor(int n, gen_rt_real *a)
{
    int i, j, k;
    gen_rt_real dmax = 0, tol;
    if (n < 0) return GEN_RT_ERR_BAD_ARG;
    if (n == 0) return GEN_RT_OK;
    if (!a) return GEN_RT_ERR_NULL;
    for (i = 0; i < n; ++i)
        if (rt_abs(a[i * n + i]) > dmax) dmax = rt_abs(a[i * n + i]);
    tol = GEN_RT_PIVOT_RTOL * dmax;
    for (j = 0; j < n; ++j) {
        gen_rt_real d = a[j * n + j];
        for (k = 0; k < j; ++k) d -= a[j * n + k] * a[j * n + k];
        if (!(d > tol)) return GEN_RT_ERR_SINGULAR;
        d = rt_sqrt(d);
        a[j * n + j] = d;
        for (i = j + 1; i < n; ++i) {
            gen_rt_real s = a[i * n + j];
            for (k = 0; k < j; ++k) s -= a[i * n + k] * a[j * n + k];
            a[i * n + j] = s / d;
        }
    }
    return GEN_RT_OK;
}

int gen_rt_chol_solve(int n, const gen_rt_real *l, int nrhs, gen_rt_real *b)
{
    int i, j, k;
    if (n < 0 || nrhs < 0) return GEN_RT_ERR_BAD_ARG;
    if (n == 0 || nrhs == 0) return GEN_RT_OK;
    if (!l || !b) return GEN_RT_ERR_NULL;
    for (i = 0; i < n; ++i) {
        for (k = 0; k < i; ++k)
            for (j = 0; j < nrhs; ++j) b[i * nrhs + j] -= l[i * n + k] * b[k * nrhs + j];
        for (j = 0; j < nrhs; ++j) b[i * nrhs + j] /= l[i * n + i];
    }
    for (i = n - 1; i >= 0; --i) {
        for (k = i + 1; k < n; ++k)
            for (j = 0; j < nrhs; ++j) b[i * nrhs + j] -= l[k * n + i] * b[k * nrhs + j];
        for (j = 0; j < nrhs; ++j) b[i * nrhs + j] /= l[i * n + i];
    }
    return GEN_RT_OK;
}

void gen_rt_matmul(int m, int k, int n, const gen_rt_real *a,
                   const gen_rt_real *b, gen_rt_real *c)
{
    int i, j, p;
    for (i = 0; i < m; ++i) {
        for (j = 0; j < n; ++j) c[i * n + j] = 0;
        for (p = 0; p < k; ++p) {
            gen_rt_real aip = a[i * k + p];
            if (aip != 0)
                for (j = 0; j < n; ++j) c[i * n + j] += aip * b[p * n + j];
        }
    }
}

/* a^T x = b from P a = L U (rt_lu_solve_t, gen_rt_private.h) */
int gen_rt_lu_solve_t(int n, const gen_rt_real *lu, const int *piv, int nrhs,
                      gen_rt_real *b)
{
    return rt_lu_solve_t(n, lu, piv, nrhs, b);
}
