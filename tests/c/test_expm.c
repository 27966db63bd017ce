/* test_expm.c - the matrix exponential and the zero-order-hold
 * discretization (gen_rt_expm.c) against closed forms: rotations,
 * nilpotent and diagonal matrices, L D L^-1 with a known eigensystem,
 * exp(A) exp(-A) = I, the double integrator and the damped mass-spring;
 * the status codes; and guard values after the work arrays sized by
 * GEN_RT_EXPM_WORK / GEN_RT_C2D_WORK. References are computed in double
 * from the matrices as stored in gen_rt_real. */
#include <stdlib.h>

#include "test_common.h"
#include "gen_rt_expm.h"

#define NMAX 12
#define GUARD 16
#define WBIG (GEN_RT_C2D_WORK(NMAX, NMAX))
#define IBIG (GEN_RT_C2D_IWORK(NMAX, NMAX))
#define SENTINEL GEN_RT_C(12345.0)

static gen_rt_real work[WBIG + GUARD];
static int iwork[IBIG + GUARD];

/* fill the work arrays: guards must survive right after n reals, ni ints */
static void guard(int n, int ni)
{
    int i;
    CHECK(n <= WBIG && ni <= IBIG);
    for (i = 0; i < WBIG + GUARD; ++i) work[i] = SENTINEL;
    for (i = 0; i < IBIG + GUARD; ++i) iwork[i] = 12345;
}

static void guards_intact(int n, int ni)
{
    int i, ok = 1;
    for (i = n; i < n + GUARD; ++i) ok = ok && work[i] == SENTINEL;
    for (i = ni; i < ni + GUARD; ++i) ok = ok && iwork[i] == 12345;
    CHECK(ok);
}

/* gen_rt_expm with guards after exactly GEN_RT_EXPM_WORK(n) / _IWORK(n) */
static int expm_guarded(int n, const gen_rt_real *A, gen_rt_real *E)
{
    int st;
    guard(GEN_RT_EXPM_WORK(n), GEN_RT_EXPM_IWORK(n));
    st = gen_rt_expm(n, A, work, iwork, E);
    guards_intact(GEN_RT_EXPM_WORK(n), GEN_RT_EXPM_IWORK(n));
    return st;
}

static int c2d_guarded(int ns, int nr, const gen_rt_real *A, const gen_rt_real *B,
                       gen_rt_real dt, gen_rt_real *Ad, gen_rt_real *Bd)
{
    int st;
    guard(GEN_RT_C2D_WORK(ns, nr), GEN_RT_C2D_IWORK(ns, nr));
    st = gen_rt_c2d_zoh(ns, nr, A, B, dt, work, iwork, Ad, Bd);
    guards_intact(GEN_RT_C2D_WORK(ns, nr), GEN_RT_C2D_IWORK(ns, nr));
    return st;
}

/* max |got - ref| / max |ref| over len entries (double) */
static double rel_err(int len, const gen_rt_real *got, const double *ref)
{
    double emax = 0, rmax = 0;
    int i;
    for (i = 0; i < len; ++i) {
        double e = fabs((double)got[i] - ref[i]);
        if (!(e <= emax)) emax = e; /* NaN propagates */
        if (fabs(ref[i]) > rmax) rmax = fabs(ref[i]);
    }
    return rmax > 0 ? emax / rmax : emax;
}

static void dmatmul(int n, const double *a, const double *b, double *c)
{
    int i, j, k;
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) {
            double s = 0;
            for (k = 0; k < n; ++k) s += a[i * n + k] * b[k * n + j];
            c[i * n + j] = s;
        }
}

static double dnorm1(int n, const double *a)
{
    double m = 0;
    int i, j;
    for (j = 0; j < n; ++j) {
        double s = 0;
        for (i = 0; i < n; ++i) s += fabs(a[i * n + j]);
        if (s > m) m = s;
    }
    return m;
}

/* exp([0, th; -th, 0]) = [cos th, sin th; -sin th, cos th] */
static void test_rotation(void)
{
    static const double thetas[] = {1e-3, 0.3, 1.0, 2.5, 10.0, 100.0};
    int k;
    for (k = 0; k < (int)(sizeof thetas / sizeof thetas[0]); ++k) {
        gen_rt_real A[4], E[4];
        double th, ref[4];
        A[0] = 0; A[1] = (gen_rt_real)thetas[k]; A[2] = -A[1]; A[3] = 0;
        th = (double)A[1];
        ref[0] = cos(th); ref[1] = sin(th); ref[2] = -sin(th); ref[3] = cos(th);
        CHECK_INT(expm_guarded(2, A, E), GEN_RT_OK);
        /* exp is conditioned like |theta| here: the error grows with it */
        CHECK_LT(rel_err(4, E, ref), TOL(1e-13, 1e-5) * (th > 1 ? th : 1));
    }
}

/* strictly upper triangular N: exp(N) = I + N + N^2/2 + N^3/6 exactly */
static void test_nilpotent(void)
{
    static const double scales[] = {0.01, 0.5, 3.0, 25.0};
    test_lcg g = {777UL};
    int k, i, j;
    for (k = 0; k < (int)(sizeof scales / sizeof scales[0]); ++k) {
        gen_rt_real A[16], E[16];
        double N[16], N2[16], N3[16], ref[16];
        for (i = 0; i < 4; ++i)
            for (j = 0; j < 4; ++j) {
                A[i * 4 + j] = j > i ? (gen_rt_real)(scales[k] * test_lcg_uniform(&g)) : 0;
                N[i * 4 + j] = (double)A[i * 4 + j];
            }
        dmatmul(4, N, N, N2);
        dmatmul(4, N2, N, N3);
        for (i = 0; i < 16; ++i) ref[i] = N[i] + N2[i] / 2 + N3[i] / 6;
        for (i = 0; i < 4; ++i) ref[i * 4 + i] += 1;
        CHECK_INT(expm_guarded(4, A, E), GEN_RT_OK);
        CHECK_LT(rel_err(16, E, ref), TOL(1e-13, 1e-5));
        for (i = 0; i < 4; ++i) /* the lower triangle stays exactly 0 */
            for (j = 0; j < i; ++j) CHECK(E[i * 4 + j] == 0);
    }
}

/* a diagonal matrix: exp of each entry, off-diagonal exactly 0 */
static void test_diagonal(void)
{
    static const double d[6] = {-20.0, -3.0, 0.0, 0.5, 2.0, 7.0};
    gen_rt_real A[36], E[36];
    int i, j;
    for (i = 0; i < 36; ++i) A[i] = 0;
    for (i = 0; i < 6; ++i) A[i * 6 + i] = (gen_rt_real)d[i];
    CHECK_INT(expm_guarded(6, A, E), GEN_RT_OK);
    for (i = 0; i < 6; ++i) {
        double want = exp(d[i]);
        /* relative per entry; the scaling by 2^-2 and the squarings cost
         * about |d| ulps on the negative end */
        CHECK_NEAR((double)E[i * 6 + i] / want, 1.0, TOL(1e-13, 1e-5));
        for (j = 0; j < 6; ++j)
            if (j != i) CHECK(E[i * 6 + j] == 0);
    }
}

/* A = L D L^-1, L unit lower triangular: exp(A) = L exp(D) L^-1, scaled to
 * 1-norms that select every Pade degree and the scaling (float: 3, 5, 7) */
static void test_known_eigensystem(void)
{
    static const double targets[] = {0.01, 0.2, 0.9, 2.0, 5.0, 40.0};
    test_lcg g = {4242UL};
    const int n = 5;
    int k, i, j, m;
    for (k = 0; k < (int)(sizeof targets / sizeof targets[0]); ++k) {
        double L[25], Li[25], D[25], T[25], A0[25], ref[25], c;
        gen_rt_real A[25], E[25], E2[25];
        for (i = 0; i < 25; ++i) { L[i] = 0; D[i] = 0; Li[i] = 0; }
        for (i = 0; i < n; ++i) {
            L[i * n + i] = 1;
            for (j = 0; j < i; ++j) L[i * n + j] = 0.5 * test_lcg_uniform(&g);
            D[i * n + i] = (double)(i - 2) / 2 + 0.2 * test_lcg_uniform(&g);
        }
        /* L^-1 column by column (forward substitution) */
        for (j = 0; j < n; ++j)
            for (i = 0; i < n; ++i) {
                double s = i == j ? 1.0 : 0.0;
                for (m = 0; m < i; ++m) s -= L[i * n + m] * Li[m * n + j];
                Li[i * n + j] = s;
            }
        dmatmul(n, L, D, T);
        dmatmul(n, T, Li, A0);
        c = targets[k] / dnorm1(n, A0);
        for (i = 0; i < n; ++i) D[i * n + i] = exp(c * D[i * n + i]);
        dmatmul(n, L, D, T);
        dmatmul(n, T, Li, ref);
        for (i = 0; i < 25; ++i) A[i] = (gen_rt_real)(c * A0[i]);
        CHECK_INT(expm_guarded(n, A, E), GEN_RT_OK);
        /* float: the rounding of A alone moves exp(A) by ~||A|| u */
        CHECK_LT(rel_err(25, E, ref),
                 TOL(1e-13, 1e-5) * (targets[k] > 10 ? targets[k] / 10 : 1));
        /* in place (E = A) gives the same numbers */
        for (i = 0; i < 25; ++i) E2[i] = A[i];
        CHECK_INT(expm_guarded(n, E2, E2), GEN_RT_OK);
        for (i = 0; i < 25; ++i) CHECK(E2[i] == E[i]);
    }
}

/* a random skew-symmetric 6x6 of 1-norm 50 (scaled and squared):
 * exp(A) exp(-A) = I, and exp(A) is orthogonal with exp(-A) = exp(A)^T */
static void test_inverse(void)
{
    test_lcg g = {99UL};
    const int n = 6;
    double S[36], P[36], Q[36], EA[36], EB[36], c, err = 0, err2 = 0, err3 = 0;
    gen_rt_real A[36], Am[36], E[36], Em[36];
    int i, j;
    for (i = 0; i < n; ++i) {
        S[i * n + i] = 0;
        for (j = 0; j < i; ++j) {
            S[i * n + j] = test_lcg_uniform(&g);
            S[j * n + i] = -S[i * n + j];
        }
    }
    c = 50.0 / dnorm1(n, S);
    for (i = 0; i < 36; ++i) {
        A[i] = (gen_rt_real)(c * S[i]);
        Am[i] = -A[i];
    }
    CHECK_INT(expm_guarded(n, A, E), GEN_RT_OK);
    CHECK_INT(expm_guarded(n, Am, Em), GEN_RT_OK);
    for (i = 0; i < 36; ++i) { EA[i] = (double)E[i]; EB[i] = (double)Em[i]; }
    dmatmul(n, EA, EB, P);
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) {
            double QtQ = 0;
            int k;
            for (k = 0; k < n; ++k) QtQ += EA[k * n + i] * EA[k * n + j];
            Q[i * n + j] = QtQ;
            if (fabs(P[i * n + j] - (i == j)) > err) err = fabs(P[i * n + j] - (i == j));
            if (fabs(Q[i * n + j] - (i == j)) > err2) err2 = fabs(Q[i * n + j] - (i == j));
            if (fabs(EB[i * n + j] - EA[j * n + i]) > err3) err3 = fabs(EB[i * n + j] - EA[j * n + i]);
        }
    /* ||A|| = 50: the relative condition of exp is ~50 */
    CHECK_LT(err, TOL(1e-13, 1e-5) * 50);
    CHECK_LT(err2, TOL(1e-13, 1e-5) * 50);
    CHECK_LT(err3, TOL(1e-13, 1e-5) * 50);
}

/* double integrator x'' = r: Ad = [1, dt; 0, 1], Bd = [dt^2/2; dt]; also
 * with B in large units (1e6), which the power-of-two balancing absorbs */
static void test_c2d_double_integrator(void)
{
    static const double dts[] = {1e-3, 0.1, 1.0, 10.0};
    static const double bs[] = {1.0, 1e6, 1e-6};
    int k, l;
    for (k = 0; k < (int)(sizeof dts / sizeof dts[0]); ++k)
        for (l = 0; l < (int)(sizeof bs / sizeof bs[0]); ++l) {
            gen_rt_real A[4] = {0, 1, 0, 0}, B[2], Ad[4], Bd[2];
            gen_rt_real dt = (gen_rt_real)dts[k];
            double h = (double)dt, b, refA[4], refB[2];
            B[0] = 0;
            B[1] = (gen_rt_real)bs[l];
            b = (double)B[1];
            refA[0] = 1; refA[1] = h; refA[2] = 0; refA[3] = 1;
            refB[0] = b * h * h / 2; refB[1] = b * h;
            CHECK_INT(c2d_guarded(2, 1, A, B, dt, Ad, Bd), GEN_RT_OK);
            CHECK_LT(rel_err(4, Ad, refA), TOL(1e-14, 1e-6));
            CHECK_LT(rel_err(2, Bd, refB), TOL(1e-14, 1e-6));
        }
}

/* mass-spring-damper m x'' + c x' + k x = r, state [x, x']:
 * with w0 = sqrt(k/m), s = c/(2m), wd = sqrt(w0^2 - s^2) (underdamped)
 *   Ad = e^{-s dt} [cos + s/wd sin, sin/wd; -w0^2 sin/wd, cos - s/wd sin]
 *   Bd = [(1 - Ad00)/k; Ad01/m]        (sin, cos of wd dt) */
static void test_c2d_mass_spring(void)
{
    static const double cs[] = {0.0, 1.5, 6.0};
    static const double dts[] = {0.01, 0.1, 1.0, 3.0};
    const double mass = 2.0, kk = 50.0;
    int a, b;
    for (a = 0; a < (int)(sizeof cs / sizeof cs[0]); ++a)
        for (b = 0; b < (int)(sizeof dts / sizeof dts[0]); ++b) {
            gen_rt_real A[4], B[2], Ad[4], Bd[2];
            gen_rt_real dt = (gen_rt_real)dts[b];
            double w0, s, wd, h = (double)dt, e, co, si, refA[4], refB[2], km, cm, im;
            A[0] = 0; A[1] = 1;
            A[2] = (gen_rt_real)(-kk / mass);
            A[3] = (gen_rt_real)(-cs[a] / mass);
            B[0] = 0;
            B[1] = (gen_rt_real)(1.0 / mass);
            /* the system as stored: k/m, c/m and 1/m from A and B */
            km = -(double)A[2]; cm = -(double)A[3]; im = (double)B[1];
            w0 = sqrt(km); s = cm / 2; wd = sqrt(w0 * w0 - s * s);
            e = exp(-s * h); co = cos(wd * h); si = sin(wd * h);
            refA[0] = e * (co + s / wd * si);
            refA[1] = e * si / wd;
            refA[2] = -e * w0 * w0 * si / wd;
            refA[3] = e * (co - s / wd * si);
            refB[0] = (1 - refA[0]) / km * im;
            refB[1] = refA[1] * im;
            CHECK_INT(c2d_guarded(2, 1, A, B, dt, Ad, Bd), GEN_RT_OK);
            CHECK_LT(rel_err(4, Ad, refA), TOL(1e-13, 1e-5) * (h > 1 ? h : 1));
            CHECK_LT(rel_err(2, Bd, refB), TOL(1e-13, 1e-5) * (h > 1 ? h : 1));
        }
}

/* nr = 0: B and Bd may be NULL, Ad = exp(A dt) (diagonal: closed form) */
static void test_c2d_no_inputs(void)
{
    static const double d[3] = {-4.0, 0.25, 1.5};
    gen_rt_real A[9], Ad[9];
    const gen_rt_real dt = GEN_RT_C(0.5);
    int i, j;
    for (i = 0; i < 9; ++i) A[i] = 0;
    for (i = 0; i < 3; ++i) A[i * 3 + i] = (gen_rt_real)d[i];
    CHECK_INT(c2d_guarded(3, 0, A, NULL, dt, Ad, NULL), GEN_RT_OK);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double want = i == j ? exp(d[i] * 0.5) : 0.0;
            CHECK_NEAR(Ad[i * 3 + j], want, TOL(1e-14, 1e-6) * (want > 1 ? want : 1));
        }
}

/* a work array of exactly GEN_RT_*_WORK: the sanitizer build sees any
 * access beyond it (the guards above see only writes) */
static void test_exact_work(void)
{
    gen_rt_real w[GEN_RT_EXPM_WORK(3)], wc[GEN_RT_C2D_WORK(2, 1)];
    int iw[GEN_RT_EXPM_IWORK(3)], iwc[GEN_RT_C2D_IWORK(2, 1)];
    gen_rt_real A[9] = {0, 7, 0, -7, 0, 0, 0, 0, -1}, E[9];
    gen_rt_real A2[4] = {0, 1, 0, 0}, B2[2] = {0, 1}, Ad[4], Bd[2];
    CHECK_INT(gen_rt_expm(3, A, w, iw, E), GEN_RT_OK);
    CHECK_NEAR(E[0], cos(7.0), TOL(1e-13, 1e-5));
    CHECK_NEAR(E[1], sin(7.0), TOL(1e-13, 1e-5));
    CHECK_NEAR(E[8], exp(-1.0), TOL(1e-14, 1e-6));
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A2, B2, GEN_RT_C(0.5), wc, iwc, Ad, Bd), GEN_RT_OK);
    CHECK_NEAR(Bd[0], 0.125, TOL(1e-15, 1e-7));
    CHECK_NEAR(Bd[1], 0.5, TOL(1e-15, 1e-7));
}

/* statuses; the outputs are written only on success */
static void test_status(void)
{
    gen_rt_real A[4] = {1, 2, 3, 4}, B[2] = {1, 0}, E[4], Bd[2];
    const double nan = strtod("nan", NULL), inf = strtod("inf", NULL);
    gen_rt_real bad[4];
    int i, ok;

    /* expm */
    for (i = 0; i < 4; ++i) E[i] = SENTINEL;
    CHECK_INT(gen_rt_expm(2, NULL, work, iwork, E), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_expm(2, A, NULL, iwork, E), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_expm(2, A, work, NULL, E), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_expm(2, A, work, iwork, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_expm(0, A, work, iwork, E), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_expm(-3, A, work, iwork, E), GEN_RT_ERR_BAD_ARG);
    for (i = 0; i < 4; ++i) bad[i] = A[i];
    bad[3] = (gen_rt_real)nan;
    CHECK_INT(gen_rt_expm(2, bad, work, iwork, E), GEN_RT_ERR_NONFINITE_INPUT);
    bad[3] = (gen_rt_real)inf;
    CHECK_INT(gen_rt_expm(2, bad, work, iwork, E), GEN_RT_ERR_NONFINITE_INPUT);
    bad[3] = (gen_rt_real)-inf;
    CHECK_INT(gen_rt_expm(2, bad, work, iwork, E), GEN_RT_ERR_NONFINITE_INPUT);
    /* e^1000 overflows double and float */
    bad[0] = GEN_RT_C(1000.0); bad[1] = 0; bad[2] = 0; bad[3] = GEN_RT_C(1.0);
    CHECK_INT(gen_rt_expm(2, bad, work, iwork, E), GEN_RT_ERR_DIVERGED);
    ok = 1;
    for (i = 0; i < 4; ++i) ok = ok && E[i] == SENTINEL;
    CHECK(ok);
    /* e^-1000 underflows to 0: not an error */
    bad[0] = GEN_RT_C(-1000.0);
    CHECK_INT(gen_rt_expm(2, bad, work, iwork, E), GEN_RT_OK);
    CHECK(E[0] == 0 && E[1] == 0 && E[2] == 0);
    CHECK_NEAR(E[3], exp(1.0), TOL(1e-13, 1e-5) * 10);
    /* the largest finite entries: an overflowing 1-norm still terminates */
    bad[0] = (gen_rt_real)(TEST_IS_FLOAT ? -3e38 : -1.7e308); bad[1] = bad[0];
    bad[2] = bad[0]; bad[3] = bad[0];
    CHECK(gen_rt_expm(2, bad, work, iwork, E) <= 0);

    /* c2d */
    for (i = 0; i < 4; ++i) E[i] = SENTINEL;
    Bd[0] = Bd[1] = SENTINEL;
    CHECK_INT(gen_rt_c2d_zoh(2, 1, NULL, B, GEN_RT_C(0.1), work, iwork, E, Bd), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, NULL, GEN_RT_C(0.1), work, iwork, E, Bd), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, B, GEN_RT_C(0.1), NULL, iwork, E, Bd), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, B, GEN_RT_C(0.1), work, NULL, E, Bd), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, B, GEN_RT_C(0.1), work, iwork, NULL, Bd), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, B, GEN_RT_C(0.1), work, iwork, E, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_c2d_zoh(0, 1, A, B, GEN_RT_C(0.1), work, iwork, E, Bd), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_c2d_zoh(-1, 0, A, B, GEN_RT_C(0.1), work, iwork, E, Bd), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_c2d_zoh(2, -1, A, B, GEN_RT_C(0.1), work, iwork, E, Bd), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, B, 0, work, iwork, E, Bd), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, B, GEN_RT_C(-0.1), work, iwork, E, Bd), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, B, (gen_rt_real)nan, work, iwork, E, Bd), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, B, (gen_rt_real)inf, work, iwork, E, Bd), GEN_RT_ERR_BAD_ARG);
    bad[0] = A[0]; bad[1] = A[1]; bad[2] = (gen_rt_real)nan; bad[3] = A[3];
    CHECK_INT(gen_rt_c2d_zoh(2, 1, bad, B, GEN_RT_C(0.1), work, iwork, E, Bd), GEN_RT_ERR_NONFINITE_INPUT);
    bad[0] = (gen_rt_real)inf; bad[1] = 0;
    CHECK_INT(gen_rt_c2d_zoh(2, 1, A, bad, GEN_RT_C(0.1), work, iwork, E, Bd), GEN_RT_ERR_NONFINITE_INPUT);
    /* A dt overflows */
    bad[0] = (gen_rt_real)(TEST_IS_FLOAT ? 3e38 : 1.7e308); bad[1] = 0; bad[2] = 0; bad[3] = 0;
    CHECK_INT(gen_rt_c2d_zoh(2, 1, bad, B, GEN_RT_C(10.0), work, iwork, E, Bd), GEN_RT_ERR_DIVERGED);
    ok = 1;
    for (i = 0; i < 4; ++i) ok = ok && E[i] == SENTINEL;
    CHECK(ok && Bd[0] == SENTINEL && Bd[1] == SENTINEL);
}

int main(void)
{
    test_rotation();
    test_nilpotent();
    test_diagonal();
    test_known_eigensystem();
    test_inverse();
    test_c2d_double_integrator();
    test_c2d_mass_spring();
    test_c2d_no_inputs();
    test_exact_work();
    test_status();
    TEST_END();
}
