/* gen_rt_expm.c - the matrix exponential (scaling and squaring with a
 * diagonal Pade approximant, Higham 2005) and the zero-order-hold
 * discretization built on it. No libm: the scaling is by exact powers of
 * two, found by doubling. */
#include "gen_rt_private.h"

/* Coefficients b_0..b_m of p_m(x) = sum b_k x^k, r_m(x) = p_m(x) / p_m(-x)
 * the [m/m] Pade approximant of exp (b_k = (2m-k)! m! / ((2m)! k! (m-k)!),
 * scaled to b_m = 1: all are integers, exact in double). */
static const gen_rt_real expm_b3[4] = {GEN_RT_C(120.0), GEN_RT_C(60.0), GEN_RT_C(12.0),
                                       GEN_RT_C(1.0)};
static const gen_rt_real expm_b5[6] = {GEN_RT_C(30240.0), GEN_RT_C(15120.0),
                                       GEN_RT_C(3360.0),  GEN_RT_C(420.0),
                                       GEN_RT_C(30.0),    GEN_RT_C(1.0)};
static const gen_rt_real expm_b7[8] = {GEN_RT_C(17297280.0), GEN_RT_C(8648640.0),
                                       GEN_RT_C(1995840.0),  GEN_RT_C(277200.0),
                                       GEN_RT_C(25200.0),    GEN_RT_C(1512.0),
                                       GEN_RT_C(56.0),       GEN_RT_C(1.0)};
#ifndef GEN_RT_REAL_FLOAT
static const gen_rt_real expm_b9[10] = {
    17643225600.0, 8821612800.0, 2075673600.0, 302702400.0, 30270240.0,
    2162160.0,     110880.0,     3960.0,       90.0,        1.0};
static const gen_rt_real expm_b13[14] = {
    64764752532480000.0, 32382376266240000.0, 7771770303897600.0,
    1187353796428800.0,  129060195264000.0,   10559470521600.0,
    670442572800.0,      33522128640.0,       1323241920.0,
    40840800.0,          960960.0,            16380.0,
    182.0,               1.0};
#endif

/* The degrees in increasing order with theta_m: the largest 1-norm for
 * which r_m(A) has a backward error below the unit roundoff (Higham 2005,
 * Table 2.3). The last one is also the target of the scaling. */
typedef struct {
    int m;
    gen_rt_real theta;
    const gen_rt_real *b;
} expm_degree;

#ifdef GEN_RT_REAL_FLOAT
/* u = 2^-24: degrees 3, 5, 7 */
static const expm_degree expm_degrees[] = {
    {3, 4.258730016922831e-1F, expm_b3},
    {5, 1.880152677804762F, expm_b5},
    {7, 3.925724783138660F, expm_b7},
};
#else
/* u = 2^-53: degrees 3, 5, 7, 9, 13 */
static const expm_degree expm_degrees[] = {
    {3, 1.495585217958292e-2, expm_b3},
    {5, 2.539398330063230e-1, expm_b5},
    {7, 9.504178996162932e-1, expm_b7},
    {9, 2.097847961257068, expm_b9},
    {13, 5.371920351148152, expm_b13},
};
#endif
#define EXPM_NDEG ((int)(sizeof expm_degrees / sizeof expm_degrees[0]))

/* max over the columns c0..c1-1 of the sum of |a_ij| over the rows
 * 0..rows-1 of a row-major array with ld columns (the 1-norm of that
 * block); inf when a sum overflows */
static gen_rt_real expm_col_norm(int rows, int ld, int c0, int c1, const gen_rt_real *a)
{
    gen_rt_real nrm = 0;
    int i, j;
    for (j = c0; j < c1; ++j) {
        gen_rt_real s = 0;
        for (i = 0; i < rows; ++i) s += rt_abs(a[i * ld + j]);
        if (s > nrm) nrm = s;
    }
    return nrm;
}

/* y = c x + y (nn entries) */
static void expm_axpy(int nn, gen_rt_real c, const gen_rt_real *x, gen_rt_real *y)
{
    int i;
    for (i = 0; i < nn; ++i) y[i] += c * x[i];
}

/* y += c I (n x n) */
static void expm_add_identity(int n, gen_rt_real c, gen_rt_real *y)
{
    int i;
    for (i = 0; i < n; ++i) y[i * n + i] += c;
}

/* y = c I (n x n) */
static void expm_set_identity(int n, gen_rt_real c, gen_rt_real *y)
{
    int i;
    for (i = 0; i < n * n; ++i) y[i] = 0;
    expm_add_identity(n, c, y);
}

int gen_rt_expm(int n, const gen_rt_real *A, gen_rt_real *work, int *iwork,
                gen_rt_real *E)
{
    gen_rt_real *w[6], *u, *v, *r, *o;
    const gen_rt_real *a = A, *b;
    gen_rt_real nrm;
    int nn, i, j, k, m, s = 0, st;

    if (!A || !work || !iwork || !E) return GEN_RT_ERR_NULL;
    if (n <= 0) return GEN_RT_ERR_BAD_ARG;
    nn = n * n;
    if (!gen_rt_all_finite(nn, A)) return GEN_RT_ERR_NONFINITE_INPUT;
    for (k = 0; k < 6; ++k) w[k] = work + k * nn;

    /* the lowest degree whose theta bounds ||A||_1; beyond the last one,
     * A / 2^s with the least s that brings the norm to theta_max */
    nrm = expm_col_norm(n, n, 0, n, A);
    for (k = 0; k < EXPM_NDEG - 1 && !(nrm <= expm_degrees[k].theta); ++k) {}
    m = expm_degrees[k].m;
    b = expm_degrees[k].b;
    if (k == EXPM_NDEG - 1) {
        /* ends: an overflowed norm (inf) stops the doubling at inf */
        gen_rt_real t = expm_degrees[k].theta, f = 1;
        while (nrm > t) {
            t *= 2;
            ++s;
        }
        if (s > 0) {
            for (i = 0; i < s; ++i) f *= GEN_RT_C(0.5);
            for (i = 0; i < nn; ++i) w[5][i] = A[i] * f; /* exact: a power of 2 */
            a = w[5];
        }
    }

    /* r_m = (V - U)^-1 (V + U), U the odd and V the even part of p_m(A) */
#ifndef GEN_RT_REAL_FLOAT
    if (m == 13) {
        /* m = 13 (Higham 2005, (2.11)): A^2, A^4, A^6 in w0, w1, w2;
         * U = A [A^6 (b13 A^6 + b11 A^4 + b9 A^2) + b7 A^6 + b5 A^4 + b3 A^2 + b1 I]
         * V = A^6 (b12 A^6 + b10 A^4 + b8 A^2) + b6 A^6 + b4 A^4 + b2 A^2 + b0 I */
        gen_rt_matmul(n, n, n, a, a, w[0]);
        gen_rt_matmul(n, n, n, w[0], w[0], w[1]);
        gen_rt_matmul(n, n, n, w[1], w[0], w[2]);
        for (i = 0; i < nn; ++i)
            w[3][i] = b[13] * w[2][i] + b[11] * w[1][i] + b[9] * w[0][i];
        gen_rt_matmul(n, n, n, w[2], w[3], w[4]);
        for (i = 0; i < nn; ++i)
            w[4][i] += b[7] * w[2][i] + b[5] * w[1][i] + b[3] * w[0][i];
        expm_add_identity(n, b[1], w[4]);
        gen_rt_matmul(n, n, n, a, w[4], w[3]); /* U; a (maybe w5) used up */
        for (i = 0; i < nn; ++i)
            w[4][i] = b[12] * w[2][i] + b[10] * w[1][i] + b[8] * w[0][i];
        gen_rt_matmul(n, n, n, w[2], w[4], w[5]);
        for (i = 0; i < nn; ++i)
            w[5][i] += b[6] * w[2][i] + b[4] * w[1][i] + b[2] * w[0][i];
        expm_add_identity(n, b[0], w[5]);
        u = w[3];
        v = w[5];
    } else
#endif
    {
        /* the even powers A^2, A^4, A^6, A^8 in w0, w1, w2, w5 (A^8 only
         * for m = 9, never scaled: w5 is free then) */
        gen_rt_real *pw[5];
        pw[0] = 0;
        pw[1] = w[0];
        pw[2] = w[1];
        pw[3] = w[2];
        pw[4] = w[5];
        gen_rt_matmul(n, n, n, a, a, w[0]);
        if (m >= 5) gen_rt_matmul(n, n, n, w[0], w[0], w[1]);
        if (m >= 7) gen_rt_matmul(n, n, n, w[1], w[0], w[2]);
        if (m >= 9) gen_rt_matmul(n, n, n, w[1], w[1], w[5]);
        /* w3 = sum b_{2j+1} A^{2j}, w4 = V = sum b_{2j} A^{2j} */
        expm_set_identity(n, b[1], w[3]);
        expm_set_identity(n, b[0], w[4]);
        for (j = 1; 2 * j < m; ++j) {
            expm_axpy(nn, b[2 * j + 1], pw[j], w[3]);
            expm_axpy(nn, b[2 * j], pw[j], w[4]);
        }
        gen_rt_matmul(n, n, n, a, w[3], w[0]); /* U = A w3 (A^2 used up) */
        u = w[0];
        v = w[4];
    }
    for (i = 0; i < nn; ++i) {
        gen_rt_real ui = u[i], vi = v[i];
        u[i] = vi + ui; /* numerator p_m(A) */
        v[i] = vi - ui; /* denominator p_m(-A) */
    }
    st = gen_rt_lu_factor(n, v, iwork, 0);
    if (st != GEN_RT_OK) return st;
    st = gen_rt_lu_solve(n, v, iwork, n, u);
    if (st != GEN_RT_OK) return st;

    /* undo the scaling: r = r^2, s times (v is free now) */
    r = u;
    o = v;
    for (i = 0; i < s; ++i) {
        gen_rt_real *t;
        gen_rt_matmul(n, n, n, r, r, o);
        t = r;
        r = o;
        o = t;
    }
    if (!gen_rt_all_finite(nn, r)) return GEN_RT_ERR_DIVERGED;
    for (i = 0; i < nn; ++i) E[i] = r[i];
    return GEN_RT_OK;
}

/* at most 2^-C2D_MAX_HALVINGS on B (a normal number in float too) */
#define C2D_MAX_HALVINGS 100

int gen_rt_c2d_zoh(int ns, int nr, const gen_rt_real *A, const gen_rt_real *B,
                   gen_rt_real dt, gen_rt_real *work, int *iwork, gen_rt_real *Ad,
                   gen_rt_real *Bd)
{
    gen_rt_real *M;
    gen_rt_real back = 1;
    int n, i, j, st;

    if (!A || !work || !iwork || !Ad) return GEN_RT_ERR_NULL;
    if (nr > 0 && (!B || !Bd)) return GEN_RT_ERR_NULL;
    if (ns <= 0 || nr < 0) return GEN_RT_ERR_BAD_ARG;
    if (!(dt > 0) || dt - dt != 0) return GEN_RT_ERR_BAD_ARG; /* NaN, <= 0, inf */
    if (!gen_rt_all_finite(ns * ns, A)) return GEN_RT_ERR_NONFINITE_INPUT;
    if (nr > 0 && !gen_rt_all_finite(ns * nr, B)) return GEN_RT_ERR_NONFINITE_INPUT;

    /* M = [A dt, B dt; 0, 0], n x n, then M = exp(M) in place */
    n = ns + nr;
    M = work;
    for (i = 0; i < ns; ++i) {
        for (j = 0; j < ns; ++j) M[i * n + j] = A[i * ns + j] * dt;
        for (j = 0; j < nr; ++j) M[i * n + ns + j] = B[i * nr + j] * dt;
    }
    for (i = ns * n; i < n * n; ++i) M[i] = 0;
    if (!gen_rt_all_finite(n * n, M)) return GEN_RT_ERR_DIVERGED;
    if (nr > 0) {
        /* Bd is linear in B: bring ||B dt||_1 down to ||A dt||_1 (or 1) by a
         * power of two, so that B does not decide the degree and the
         * scaling, and scale Bd back by the same power (exact). */
        gen_rt_real an = expm_col_norm(ns, n, 0, ns, M);
        gen_rt_real bn = expm_col_norm(ns, n, ns, n, M);
        gen_rt_real target = an > 0 ? an : GEN_RT_C(1.0), f = 1;
        int h = 0;
        while (bn > target && h < C2D_MAX_HALVINGS) {
            bn *= GEN_RT_C(0.5);
            f *= GEN_RT_C(0.5);
            back *= 2;
            ++h;
        }
        if (h > 0)
            for (i = 0; i < ns; ++i)
                for (j = 0; j < nr; ++j) M[i * n + ns + j] *= f;
    }
    st = gen_rt_expm(n, M, work + n * n, iwork, M);
    if (st != GEN_RT_OK) return st;
    if (back != 1) {
        for (i = 0; i < ns; ++i)
            for (j = 0; j < nr; ++j) M[i * n + ns + j] *= back;
        if (!gen_rt_all_finite(n * n, M)) return GEN_RT_ERR_DIVERGED;
    }
    for (i = 0; i < ns; ++i) {
        for (j = 0; j < ns; ++j) Ad[i * ns + j] = M[i * n + j];
        for (j = 0; j < nr; ++j) Bd[i * nr + j] = M[i * n + ns + j];
    }
    return GEN_RT_OK;
}
