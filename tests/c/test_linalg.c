/* test_linalg.c - LU, Cholesky, matmul, status messages, finiteness. */
#include <limits.h>
#include <float.h>

#include "test_common.h"

#define NMAX 8
#define NRHS 3

/* max-norm residual ||A x - b|| / (||A|| ||x||), all in double */
static double rel_residual(int n, int nrhs, const double *A, const gen_rt_real *x,
                           const double *b)
{
    double rmax = 0, anorm = 0, xmax = 0;
    int i, j, k;
    for (i = 0; i < n; ++i) {
        double rowsum = 0;
        for (k = 0; k < n; ++k) rowsum += fabs(A[i * n + k]);
        if (rowsum > anorm) anorm = rowsum;
        for (j = 0; j < nrhs; ++j) {
            double s = -b[i * nrhs + j];
            for (k = 0; k < n; ++k) s += A[i * n + k] * (double)x[k * nrhs + j];
            if (!(fabs(s) <= rmax)) rmax = fabs(s);
            if (fabs((double)x[i * nrhs + j]) > xmax) xmax = fabs((double)x[i * nrhs + j]);
        }
    }
    return rmax / (anorm * xmax);
}

static void test_lu_random(void)
{
    test_lcg g = {12345UL};
    int n, trial, i, j;
    for (n = 1; n <= NMAX; ++n) {
        for (trial = 0; trial < 5; ++trial) {
            double Ad[NMAX * NMAX], bd[NMAX * NRHS];
            gen_rt_real a[NMAX * NMAX], x[NMAX * NRHS];
            int piv[NMAX];
            /* random entries in [-1, 1] plus n on the diagonal: strictly
             * diagonally dominant, condition number O(1) */
            for (i = 0; i < n; ++i)
                for (j = 0; j < n; ++j) {
                    gen_rt_real v = (gen_rt_real)(test_lcg_uniform(&g) + (i == j ? n : 0));
                    a[i * n + j] = v;
                    Ad[i * n + j] = (double)v; /* the exact matrix factored */
                }
            /* scramble the row order so that pivoting matters */
            if (n > 1) {
                for (j = 0; j < n; ++j) {
                    gen_rt_real t = a[j];
                    double td = Ad[j];
                    a[j] = a[(n - 1) * n + j]; a[(n - 1) * n + j] = t;
                    Ad[j] = Ad[(n - 1) * n + j]; Ad[(n - 1) * n + j] = td;
                }
            }
            for (i = 0; i < n * NRHS; ++i) {
                x[i] = (gen_rt_real)(10.0 * test_lcg_uniform(&g));
                bd[i] = (double)x[i];
            }
            CHECK_INT(gen_rt_lu_factor(n, a, piv, 0), GEN_RT_OK);
            for (i = 0; i < n; ++i) CHECK(piv[i] >= i && piv[i] < n);
            CHECK_INT(gen_rt_lu_solve(n, a, piv, NRHS, x), GEN_RT_OK);
            CHECK_LT(rel_residual(n, NRHS, Ad, x, bd), TOL(1e-12, 1e-5));
        }
    }
}

static void test_lu_known(void)
{
    /* 2x + y + z = 5, 4x - 6y = -2, -2x + 7y + 2z = 9  ->  x = 1, y = 1, z = 2
     * (partial pivoting swaps rows 0 and 1 here) */
    gen_rt_real a[9] = {2, 1, 1, 4, -6, 0, -2, 7, 2};
    /* two right-hand sides (columns): for x = (1, 1, 2) and x = (0.5, 1.5, 1) */
    gen_rt_real b[6] = {5, 3.5, -2, -7, 9, 11.5};
    int piv[3];
    CHECK_INT(gen_rt_lu_factor(3, a, piv, 0), GEN_RT_OK);
    CHECK_INT(piv[0], 1); /* |4| is the largest in the first column */
    CHECK_INT(gen_rt_lu_solve(3, a, piv, 2, b), GEN_RT_OK);
    CHECK_NEAR(b[0], 1.0, TOL(4e-15, 4e-6));
    CHECK_NEAR(b[2], 1.0, TOL(4e-15, 4e-6));
    CHECK_NEAR(b[4], 2.0, TOL(4e-15, 4e-6));
    CHECK_NEAR(b[1], 0.5, TOL(4e-15, 4e-6));
    CHECK_NEAR(b[3], 1.5, TOL(4e-15, 4e-6));
    CHECK_NEAR(b[5], 1.0, TOL(4e-15, 4e-6));

    {
        /* 1x1 and a 2x2 needing a pivot swap: [0 1; 1 0] x = [3; 7] */
        gen_rt_real c[4] = {0, 1, 1, 0}, r[2] = {3, 7}, s[1] = {-4}, e[1] = {2};
        int p2[2], p1[1];
        CHECK_INT(gen_rt_lu_factor(2, c, p2, 0), GEN_RT_OK);
        CHECK_INT(gen_rt_lu_solve(2, c, p2, 1, r), GEN_RT_OK);
        CHECK_NEAR(r[0], 7.0, 0.0);
        CHECK_NEAR(r[1], 3.0, 0.0);
        CHECK_INT(gen_rt_lu_factor(1, e, p1, 0), GEN_RT_OK);
        CHECK_INT(gen_rt_lu_solve(1, e, p1, 1, s), GEN_RT_OK);
        CHECK_NEAR(s[0], -2.0, 0.0);
    }
}

static void test_lu_singular(void)
{
    int piv[NMAX], n, i, j, k;
    test_lcg g = {777UL};
    {
        gen_rt_real a[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9}; /* rank 2 */
        CHECK_INT(gen_rt_lu_factor(3, a, piv, 0), GEN_RT_ERR_SINGULAR);
    }
    {
        gen_rt_real a[9] = {1, 2, 3, 2, 4, 6, -1, 5, 0}; /* row 1 = 2 * row 0 */
        CHECK_INT(gen_rt_lu_factor(3, a, piv, 0), GEN_RT_ERR_SINGULAR);
    }
    {
        gen_rt_real z[16];
        for (i = 0; i < 16; ++i) z[i] = 0;
        CHECK_INT(gen_rt_lu_factor(4, z, piv, 0), GEN_RT_ERR_SINGULAR);
        for (i = 0; i < 16; ++i) z[i] = 0;
        CHECK_INT(gen_rt_lu_factor(4, z, piv, 1), GEN_RT_ERR_SINGULAR);
        z[0] = 0;
        CHECK_INT(gen_rt_lu_factor(1, z, piv, 0), GEN_RT_ERR_SINGULAR);
    }
    {
        /* a pivot 1e-14 relative to the largest entry */
        gen_rt_real a[4] = {1, 0, 0, GEN_RT_C(1e-14)};
        gen_rt_real c[9] = {2, 1, 0, 1, 3, 1, 0, 1, 0};
        gen_rt_real ok[4] = {1, 0, 0, TOL(1e-10, 1e-4)};
        CHECK_INT(gen_rt_lu_factor(2, a, piv, 0), GEN_RT_ERR_SINGULAR);
        /* [2 1 0; 1 3 1; 0 1 0] with the (2,2) entry set so that the last
         * pivot, 0 - 2/5, becomes tiny: 2/5 + 3e-14 -> pivot ~3e-14 */
        c[8] = (gen_rt_real)(0.4 + 3e-14);
        CHECK_INT(gen_rt_lu_factor(3, c, piv, 0), GEN_RT_ERR_SINGULAR);
        /* a pivot well above the threshold is accepted */
        CHECK_INT(gen_rt_lu_factor(2, ok, piv, 0), GEN_RT_OK);
        /* an explicit scale is what pivots are judged against */
        ok[0] = 1; ok[1] = 0; ok[2] = 0; ok[3] = 1;
        CHECK_INT(gen_rt_lu_factor(2, ok, piv, TOL(1e13, 1e7)), GEN_RT_ERR_SINGULAR);
    }
    if (!TEST_IS_FLOAT) {
        /* random rank-deficient products B (n x r) C (r x n), r < n */
        for (n = 2; n <= NMAX; ++n) {
            double B[NMAX * NMAX], C[NMAX * NMAX];
            gen_rt_real a[NMAX * NMAX];
            int r = n - 1 - (n > 4);
            for (i = 0; i < n * r; ++i) { B[i] = test_lcg_uniform(&g); C[i] = test_lcg_uniform(&g); }
            for (i = 0; i < n; ++i)
                for (j = 0; j < n; ++j) {
                    double s = 0;
                    for (k = 0; k < r; ++k) s += B[i * r + k] * C[k * n + j];
                    a[i * n + j] = (gen_rt_real)s;
                }
            CHECK_INT(gen_rt_lu_factor(n, a, piv, 0), GEN_RT_ERR_SINGULAR);
        }
    }
}

static void test_chol(void)
{
    test_lcg g = {4242UL};
    int n, trial, i, j, k, si;
    for (n = 1; n <= NMAX; ++n) {
        for (trial = 0; trial < 5; ++trial) {
            double B[NMAX * NMAX], Ad[NMAX * NMAX], bd[NMAX * NRHS];
            gen_rt_real a[NMAX * NMAX], x[NMAX * NRHS];
            for (i = 0; i < n * n; ++i) B[i] = test_lcg_uniform(&g);
            for (i = 0; i < n; ++i)
                for (j = 0; j < n; ++j) {
                    double s = (i == j) ? n : 0;
                    for (k = 0; k < n; ++k) s += B[i * n + k] * B[j * n + k];
                    a[i * n + j] = (gen_rt_real)s;
                }
            for (i = 0; i < n; ++i)          /* symmetric exactly */
                for (j = 0; j < i; ++j) a[j * n + i] = a[i * n + j];
            for (i = 0; i < n * n; ++i) Ad[i] = (double)a[i];
            for (i = 0; i < n * NRHS; ++i) {
                x[i] = (gen_rt_real)test_lcg_uniform(&g);
                bd[i] = (double)x[i];
            }
            CHECK_INT(gen_rt_chol_factor(n, a), GEN_RT_OK);
            /* L L^T reproduces A */
            for (i = 0; i < n; ++i)
                for (j = 0; j <= i; ++j) {
                    double s = 0;
                    for (k = 0; k <= j; ++k) s += (double)a[i * n + k] * (double)a[j * n + k];
                    CHECK_NEAR(s, Ad[i * n + j], TOL(1e-13, 1e-5) * 2.0 * n);
                }
            CHECK_INT(gen_rt_chol_solve(n, a, NRHS, x), GEN_RT_OK);
            CHECK_LT(rel_residual(n, NRHS, Ad, x, bd), TOL(1e-12, 1e-5));
        }
    }
    /* scale invariance: the factor of s*A is sqrt(s) times the factor of A */
    for (si = 0; si < 4; ++si) {
        const double scales[4] = {TOL(1e-120, 1e-30), TOL(1e-40, 1e-10),
                                  TOL(1e40, 1e10), TOL(1e120, 1e30)};
        double s = scales[si], rs = sqrt(s);
        gen_rt_real a[4];
        a[0] = (gen_rt_real)(4 * s); a[1] = (gen_rt_real)(2 * s);
        a[2] = (gen_rt_real)(2 * s); a[3] = (gen_rt_real)(10 * s);
        /* [4 2; 2 10] = L L^T with L = [2 0; 1 3] */
        CHECK_INT(gen_rt_chol_factor(2, a), GEN_RT_OK);
        CHECK_NEAR(a[0] / rs, 2.0, TOL(1e-14, 1e-5));
        CHECK_NEAR(a[2] / rs, 1.0, TOL(1e-14, 1e-5));
        CHECK_NEAR(a[3] / rs, 3.0, TOL(1e-14, 1e-5));
    }
    {
        gen_rt_real indef[4] = {1, 2, 2, 1};      /* eigenvalues 3, -1 */
        gen_rt_real negd[4] = {-1, 0, 0, -2};
        gen_rt_real semi[9] = {1, 1, 0, 1, 1, 0, 0, 0, 1}; /* singular PSD */
        gen_rt_real zero[1] = {0};
        /* SPD in exact arithmetic, but the second pivot is 1e-14 relative */
        gen_rt_real near[4] = {1, 1, 1, (gen_rt_real)(1 + 1e-14)};
        gen_rt_real fine[4] = {1, 1, 1, (gen_rt_real)(1 + TOL(1e-9, 1e-3))};
        CHECK_INT(gen_rt_chol_factor(2, near), GEN_RT_ERR_SINGULAR);
        CHECK_INT(gen_rt_chol_factor(2, fine), GEN_RT_OK);
        CHECK_INT(gen_rt_chol_factor(2, indef), GEN_RT_ERR_SINGULAR);
        CHECK_INT(gen_rt_chol_factor(2, negd), GEN_RT_ERR_SINGULAR);
        CHECK_INT(gen_rt_chol_factor(3, semi), GEN_RT_ERR_SINGULAR);
        CHECK_INT(gen_rt_chol_factor(1, zero), GEN_RT_ERR_SINGULAR);
    }
}

static void test_matmul(void)
{
    const gen_rt_real a[6] = {1, 2, 3, 4, 5, 6};          /* 2 x 3 */
    const gen_rt_real b[6] = {7, 8, 9, 10, 11, 12};       /* 3 x 2 */
    const gen_rt_real want[4] = {58, 64, 139, 154};
    const gen_rt_real v[3] = {1, -1, 2};
    gen_rt_real c[4], cv[2];
    int i;
    for (i = 0; i < 4; ++i) c[i] = -999; /* must be overwritten, not accumulated */
    gen_rt_matmul(2, 3, 2, a, b, c);
    for (i = 0; i < 4; ++i) CHECK_NEAR(c[i], want[i], 0.0);
    gen_rt_matmul(2, 3, 1, a, v, cv);           /* matrix-vector */
    CHECK_NEAR(cv[0], 5.0, 0.0);
    CHECK_NEAR(cv[1], 11.0, 0.0);
    gen_rt_matmul(1, 3, 1, v, v, cv);           /* inner product */
    CHECK_NEAR(cv[0], 6.0, 0.0);
    CHECK_NEAR(gen_rt_max_abs(3, v), 2.0, 0.0);
    CHECK_NEAR(gen_rt_max_abs(0, v), 0.0, 0.0);
}

static void test_null_and_args(void)
{
    gen_rt_real a[4] = {1, 0, 0, 1}, b[2] = {1, 1};
    int piv[2] = {0, 1};
    CHECK_INT(gen_rt_lu_factor(2, NULL, piv, 0), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_lu_factor(2, a, NULL, 0), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_lu_solve(2, NULL, piv, 1, b), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_lu_solve(2, a, NULL, 1, b), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_lu_solve(2, a, piv, 1, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_chol_factor(2, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_chol_solve(2, NULL, 1, b), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_chol_solve(2, a, 1, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_lu_factor(-1, a, piv, 0), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_lu_solve(2, a, piv, -1, b), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_chol_factor(-1, a), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_lu_factor(0, NULL, NULL, 0), GEN_RT_OK); /* empty is fine */
}

static void test_status(void)
{
    const char *msgs[1 - GEN_RT_STATUS_MIN];
    int code, other, nmsg = 0;
    const int unknown[5] = {1, GEN_RT_STATUS_MIN - 1, -100, INT_MAX, INT_MIN};
    for (code = GEN_RT_OK; code >= GEN_RT_STATUS_MIN; --code) {
        const char *m = gen_rt_status_message(code);
        CHECK(m != NULL);
        if (!m) continue;
        CHECK(strlen(m) > 0);
        CHECK(strcmp(m, "unknown status code") != 0);
        for (other = 0; other < nmsg; ++other) CHECK(strcmp(m, msgs[other]) != 0);
        msgs[nmsg++] = m;
    }
    CHECK_INT(nmsg, 1 - GEN_RT_STATUS_MIN);
    for (code = 0; code < 5; ++code) {
        const char *m = gen_rt_status_message(unknown[code]);
        CHECK(m != NULL && strcmp(m, "unknown status code") == 0);
    }
}

static void test_finite(void)
{
    volatile gen_rt_real zero = 0, one = 1;
    gen_rt_real nan_v = zero / zero, inf_v = one / zero, ninf_v = -one / zero;
    gen_rt_real v[4] = {1, -2, 3, 4};
    int i;
    CHECK(nan_v != nan_v); /* the test's own NaN is one */
    CHECK_INT(gen_rt_all_finite(4, v), 1);
    CHECK_INT(gen_rt_all_finite(0, v), 1);
#ifdef GEN_RT_REAL_FLOAT
    v[0] = FLT_MAX;
    v[2] = FLT_MIN / 4; /* subnormal */
#else
    v[0] = DBL_MAX;
    v[2] = DBL_MIN / 4;
#endif
    v[1] = -v[0];
    CHECK_INT(gen_rt_all_finite(4, v), 1);
    for (i = 0; i < 4; ++i) {
        gen_rt_real keep = v[i];
        v[i] = nan_v;
        CHECK_INT(gen_rt_all_finite(4, v), 0);
        v[i] = inf_v;
        CHECK_INT(gen_rt_all_finite(4, v), 0);
        v[i] = ninf_v;
        CHECK_INT(gen_rt_all_finite(4, v), 0);
        /* outside the first n values a NaN is not looked at */
        CHECK_INT(gen_rt_all_finite(i, v), 1);
        v[i] = keep;
    }
}

int main(void)
{
    test_lu_random();
    test_lu_known();
    test_lu_singular();
    test_chol();
    test_matmul();
    test_null_and_args();
    test_status();
    test_finite();
    TEST_END();
}
