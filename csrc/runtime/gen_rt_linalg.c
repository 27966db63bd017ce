/* gen_rt_linalg.c - small dense LU (partial pivoting) and Cholesky. */
#include "gen_rt_private.h"

gen_rt_real gen_rt_max_abs(int n, const gen_rt_real *v)
{
    gen_rt_real m = 0;
    int i;
    for (i = 0; i < n; ++i) {
        gen_rt_real a = rt_abs(v[i]);
        if (a > m) m = a;
    }
    return m;
}

int gen_rt_lu_factor(int n, gen_rt_real *a, int *piv, gen_rt_real scale)
{
    int i, j, k;
    gen_rt_real tol;
    if (n < 0) return GEN_RT_ERR_BAD_ARG;
    if (n == 0) return GEN_RT_OK;
    if (!a || !piv) return GEN_RT_ERR_NULL;
    if (!(scale > 0)) scale = gen_rt_max_abs(n * n, a);
    if (!(scale > 0)) return GEN_RT_ERR_SINGULAR;
    tol = GEN_RT_PIVOT_RTOL * scale;
    for (k = 0; k < n; ++k) {
        int p = k;
        gen_rt_real best = rt_abs(a[k * n + k]);
        for (i = k + 1; i < n; ++i) {
            gen_rt_real v = rt_abs(a[i * n + k]);
            if (v > best) { best = v; p = i; }
        }
        piv[k] = p;
        if (!(best > tol)) return GEN_RT_ERR_SINGULAR; /* also catches NaN */
        if (p != k) {
            for (j = 0; j < n; ++j) {
                gen_rt_real tmp = a[k * n + j];
                a[k * n + j] = a[p * n + j];
                a[p * n + j] = tmp;
            }
        }
        for (i = k + 1; i < n; ++i) {
            gen_rt_real l = a[i * n + k] / a[k * n + k];
            a[i * n + k] = l;
            if (l != 0) {
                for (j = k + 1; j < n; ++j) a[i * n + j] -= l * a[k * n + j];
            }
        }
    }
    return GEN_RT_OK;
}

int gen_rt_lu_solve(int n, const gen_rt_real *lu, const int *piv, int nrhs,
                    gen_rt_real *b)
{
    int i, j, k;
    if (n < 0 || nrhs < 0) return GEN_RT_ERR_BAD_ARG;
    if (n == 0 || nrhs == 0) return GEN_RT_OK;
    if (!lu || !piv || !b) return GEN_RT_ERR_NULL;
    for (k = 0; k < n; ++k) {
        int p = piv[k];
        if (p != k) {
            for (j = 0; j < nrhs; ++j) {
                gen_rt_real tmp = b[k * nrhs + j];
                b[k * nrhs + j] = b[p * nrhs + j];
                b[p * nrhs + j] = tmp;
            }
        }
    }
    for (i = 0; i < n; ++i) {           /* forward: unit lower */
        for (k = 0; k < i; ++k) {
            gen_rt_real l = lu[i * n + k];
            if (l != 0) {
                for (j = 0; j < nrhs; ++j) b[i * nrhs + j] -= l * b[k * nrhs + j];
            }
        }
    }
    for (i = n - 1; i >= 0; --i) {      /* backward: upper */
        for (k = i + 1; k < n; ++k) {
            gen_rt_real uik = lu[i * n + k];
            if (uik != 0) {
                for (j = 0; j < nrhs; ++j) b[i * nrhs + j] -= uik * b[k * nrhs + j];
            }
        }
        for (j = 0; j < nrhs; ++j) b[i * nrhs + j] /= lu[i * n + i];
    }
    return GEN_RT_OK;
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

/* a^T x = b from P a = L U: U^T y = b, L^T c = y (unit diagonal), x = P^T c */
int gen_rt_lu_solve_t(int n, const gen_rt_real *lu, const int *piv, int nrhs,
                      gen_rt_real *b)
{
    int i, j, k;
    if (n < 0 || nrhs < 0) return GEN_RT_ERR_BAD_ARG;
    if (n == 0 || nrhs == 0) return GEN_RT_OK;
    if (!lu || !piv || !b) return GEN_RT_ERR_NULL;
    for (j = 0; j < nrhs; ++j) {
        for (i = 0; i < n; ++i) {
            gen_rt_real s = b[i * nrhs + j];
            for (k = 0; k < i; ++k) s -= lu[k * n + i] * b[k * nrhs + j];
            b[i * nrhs + j] = s / lu[i * n + i];
        }
        for (i = n - 1; i >= 0; --i) {
            gen_rt_real s = b[i * nrhs + j];
            for (k = i + 1; k < n; ++k) s -= lu[k * n + i] * b[k * nrhs + j];
            b[i * nrhs + j] = s;
        }
        for (k = n - 1; k >= 0; --k)
            if (piv[k] != k) {
                gen_rt_real tmp = b[k * nrhs + j];
                b[k * nrhs + j] = b[piv[k] * nrhs + j];
                b[piv[k] * nrhs + j] = tmp;
            }
    }
    return GEN_RT_OK;
}
