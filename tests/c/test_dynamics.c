/* test_dynamics.c - gen_rt_accel_kkt and gen_rt_accel_partitioned on a
 * planar pendulum in Cartesian coordinates, checked against the exact
 * solution in polar coordinates; a free particle with a full mass matrix;
 * gen_rt_accel_reactions and gen_rt_reactions_columns on a system solved by
 * hand; the KKT matrix every KKT solve assembles (gen_rt_kkt_matrix). */
#include "test_common.h"
#include "gen_rt_private.h"

#define PM 1.3   /* mass */
#define PL 0.7   /* length */
#define PG 9.81  /* gravity, along +x */

#define WORK_N 4
#define WORK_M 2

typedef struct {
    gen_rt_real M[4], f[2], A[2], a[1];
} pend_model;

/* exact pendulum motion at angle th, rate thd (x = L cos th, y = L sin th) */
typedef struct {
    double x, y, u1, u2, xdd, ydd, lam;
} pend_exact;

static pend_exact pend_reference(double th, double thd, int x_exactly_zero)
{
    pend_exact e;
    double c = cos(th), s = sin(th);
    double thdd = -(PG / PL) * s;
    if (x_exactly_zero) c = 0.0; /* theta = 90 degrees */
    e.x = PL * c;
    e.y = PL * s;
    e.u1 = -PL * s * thd;
    e.u2 = PL * c * thd;
    e.xdd = -PL * s * thdd - PL * c * thd * thd;
    e.ydd = PL * c * thdd - PL * s * thd * thd;
    /* radial balance: m (-L thd^2) = m g cos th + L lam  (A^T lam = lam [x, y]) */
    e.lam = -PM * (PL * thd * thd + PG * c) / PL;
    return e;
}

static void pend_build(const pend_exact *e, pend_model *p)
{
    p->M[0] = (gen_rt_real)PM; p->M[1] = 0; p->M[2] = 0; p->M[3] = (gen_rt_real)PM;
    p->f[0] = (gen_rt_real)(PM * PG); p->f[1] = 0;
    p->A[0] = (gen_rt_real)e->x; p->A[1] = (gen_rt_real)e->y;
    p->a[0] = (gen_rt_real)(e->u1 * e->u1 + e->u2 * e->u2);
}

static void check_pendulum_at(double th, double thd)
{
    pend_exact e = pend_reference(th, thd, 0);
    pend_model p;
    gen_rt_real work[GEN_RT_ACCEL_WORK(WORK_N, WORK_M)];
    int iwork[GEN_RT_ACCEL_IWORK(WORK_N, WORK_M)];
    gen_rt_real ud_k[2] = {-1, -1}, ud_p[2] = {-1, -1}, ud_p2[2] = {-1, -1};
    gen_rt_real lam_k[1] = {0}, lam_p[1] = {0}, lam_p2[1] = {0};
    const int dep0[1] = {0}, ind0[1] = {1}, dep1[1] = {1}, ind1[1] = {0};
    double scale = fabs(e.xdd) > fabs(e.ydd) ? fabs(e.xdd) : fabs(e.ydd);
    double tol = TOL(1e-12, 2e-5) * scale;
    double ltol = TOL(1e-12, 2e-5) * fabs(e.lam);

    /* the reference itself: on the circle, velocity and acceleration
     * constraints hold, and the x equation gives the same multiplier */
    CHECK_NEAR(e.x * e.u1 + e.y * e.u2, 0.0, 1e-14);
    CHECK_NEAR(e.x * e.xdd + e.y * e.ydd + e.u1 * e.u1 + e.u2 * e.u2, 0.0, 1e-13);
    CHECK_NEAR((PM * e.xdd - PM * PG) / e.x, e.lam, 1e-12 * fabs(e.lam));
    if (e.y != 0.0) CHECK_NEAR(PM * e.ydd / e.y, e.lam, 1e-12 * fabs(e.lam));

    pend_build(&e, &p);
    CHECK_INT(gen_rt_accel_kkt(2, 1, p.M, p.f, p.A, p.a, work, iwork, ud_k, lam_k),
              GEN_RT_OK);
    CHECK_NEAR(ud_k[0], e.xdd, tol);
    CHECK_NEAR(ud_k[1], e.ydd, tol);
    CHECK_NEAR(lam_k[0], e.lam, ltol);

    CHECK_INT(gen_rt_accel_partitioned(2, 1, ind0, dep0, p.M, p.f, p.A, p.a, work,
                                       iwork, ud_p, lam_p),
              GEN_RT_OK);
    CHECK_NEAR(ud_p[0], e.xdd, tol);
    CHECK_NEAR(ud_p[1], e.ydd, tol);
    CHECK_NEAR(lam_p[0], e.lam, ltol);
    CHECK_NEAR(lam_p[0], lam_k[0], ltol);

    if (p.A[1] == 0) {
        /* y = 0 exactly: y cannot be the dependent speed */
        CHECK_INT(gen_rt_accel_partitioned(2, 1, ind1, dep1, p.M, p.f, p.A, p.a, work,
                                           iwork, ud_p2, lam_p2),
                  GEN_RT_ERR_SINGULAR);
    } else {
        CHECK_INT(gen_rt_accel_partitioned(2, 1, ind1, dep1, p.M, p.f, p.A, p.a, work,
                                           iwork, ud_p2, lam_p2),
                  GEN_RT_OK);
        CHECK_NEAR(ud_p2[0], e.xdd, tol);
        CHECK_NEAR(ud_p2[1], e.ydd, tol);
        CHECK_NEAR(lam_p2[0], e.lam, ltol);
    }

    /* lam == NULL is allowed and does not change ud */
    CHECK_INT(gen_rt_accel_kkt(2, 1, p.M, p.f, p.A, p.a, work, iwork, ud_k, NULL),
              GEN_RT_OK);
    CHECK_NEAR(ud_k[0], e.xdd, tol);
    CHECK_INT(gen_rt_accel_partitioned(2, 1, ind0, dep0, p.M, p.f, p.A, p.a, work,
                                       iwork, ud_p, NULL),
              GEN_RT_OK);
    CHECK_NEAR(ud_p[1], e.ydd, tol);
}

static void test_pendulum(void)
{
    check_pendulum_at(0.9, 1.7);
    check_pendulum_at(-2.3, -0.4);
    check_pendulum_at(0.0, 2.0);      /* hanging, y = 0 exactly */
    check_pendulum_at(3.0, 0.0);      /* near the top, at rest */
}

static void test_pendulum_horizontal(void)
{
    /* theta = 90 degrees with x = 0.0 exactly: x cannot be the dependent speed */
    const double thd = 1.1;
    pend_exact e = pend_reference(M_PI / 2, thd, 1);
    pend_model p;
    gen_rt_real work[GEN_RT_ACCEL_WORK(WORK_N, WORK_M)];
    int iwork[GEN_RT_ACCEL_IWORK(WORK_N, WORK_M)];
    gen_rt_real ud[2], lam[1], udk[2], lamk[1];
    const int dep0[1] = {0}, ind0[1] = {1}, dep1[1] = {1}, ind1[1] = {0};
    CHECK(e.x == 0.0);
    /* exact: thdd = -g/L, xdd = g, ydd = -L thd^2, lam = -m thd^2 */
    CHECK_NEAR(e.xdd, PG, 1e-13);
    CHECK_NEAR(e.ydd, -PL * thd * thd, 1e-13);
    CHECK_NEAR(e.lam, -PM * thd * thd, 1e-13);
    pend_build(&e, &p);
    CHECK(p.A[0] == 0);
    CHECK_INT(gen_rt_accel_partitioned(2, 1, ind0, dep0, p.M, p.f, p.A, p.a, work,
                                       iwork, ud, lam),
              GEN_RT_ERR_SINGULAR);
    /* nearly horizontal: x = 1e-14 L is as bad as x = 0 for this partition */
    p.A[0] = (gen_rt_real)(1e-14 * PL);
    CHECK_INT(gen_rt_accel_partitioned(2, 1, ind0, dep0, p.M, p.f, p.A, p.a, work,
                                       iwork, ud, lam),
              GEN_RT_ERR_SINGULAR);
    p.A[0] = 0;
    CHECK_INT(gen_rt_accel_partitioned(2, 1, ind1, dep1, p.M, p.f, p.A, p.a, work,
                                       iwork, ud, lam),
              GEN_RT_OK);
    CHECK_NEAR(ud[0], PG, TOL(1e-12, 2e-5) * PG);
    CHECK_NEAR(ud[1], -PL * thd * thd, TOL(1e-12, 2e-5) * PG);
    CHECK_NEAR(lam[0], -PM * thd * thd, TOL(1e-12, 2e-5) * PM * thd * thd);
    /* the multiplier form does not care about the partition */
    CHECK_INT(gen_rt_accel_kkt(2, 1, p.M, p.f, p.A, p.a, work, iwork, udk, lamk),
              GEN_RT_OK);
    CHECK_NEAR(udk[0], ud[0], TOL(1e-12, 2e-5) * PG);
    CHECK_NEAR(udk[1], ud[1], TOL(1e-12, 2e-5) * PG);
    CHECK_NEAR(lamk[0], lam[0], TOL(1e-12, 2e-5) * PM * thd * thd);
}

/* 3x3 determinant, for Cramer's rule */
static double det3(const double *a)
{
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
}

static void test_free_particle(void)
{
    /* m = 0 constraints: u' = M^-1 f, with a full SPD mass matrix */
    const double Md[9] = {2.0, 0.5, 0.0, 0.5, 3.0, 0.25, 0.0, 0.25, 1.5};
    const double fd[3] = {1.0, -2.0, 3.0};
    gen_rt_real M[9], f[3], ud_k[3], ud_p[3], lam_dummy[1] = {42};
    gen_rt_real work[GEN_RT_ACCEL_WORK(3, 0)];
    int iwork[GEN_RT_ACCEL_IWORK(3, 0)];
    const int ind[3] = {0, 1, 2};
    double ref[3], D = det3(Md);
    int i, j;
    for (i = 0; i < 9; ++i) M[i] = (gen_rt_real)Md[i];
    for (i = 0; i < 3; ++i) f[i] = (gen_rt_real)fd[i];
    for (j = 0; j < 3; ++j) {       /* Cramer: replace column j by f */
        double Mj[9];
        for (i = 0; i < 9; ++i) Mj[i] = Md[i];
        for (i = 0; i < 3; ++i) Mj[i * 3 + j] = fd[i];
        ref[j] = det3(Mj) / D;
    }
    CHECK_INT(gen_rt_accel_kkt(3, 0, M, f, NULL, NULL, work, iwork, ud_k, lam_dummy),
              GEN_RT_OK);
    CHECK_INT(gen_rt_accel_partitioned(3, 0, ind, NULL, M, f, NULL, NULL, work, iwork,
                                       ud_p, lam_dummy),
              GEN_RT_OK);
    for (i = 0; i < 3; ++i) {
        CHECK_NEAR(ud_k[i], ref[i], TOL(1e-14, 1e-6));
        CHECK_NEAR(ud_p[i], ref[i], TOL(1e-14, 1e-6));
    }
    CHECK_NEAR(lam_dummy[0], 42.0, 0.0); /* no multipliers: untouched */
}

static void test_all_dependent(void)
{
    /* n = m: a point fully prescribed by two constraints u1' = -a1, u1' + u2' = -a2 */
    const gen_rt_real M[4] = {1, 0, 0, 2}, f[2] = {3, 4};
    const gen_rt_real A[4] = {1, 0, 1, 1}, a[2] = {-1, -5};
    const int dep[2] = {0, 1};
    gen_rt_real work[GEN_RT_ACCEL_WORK(2, 2)], ud[2], lam[2], udk[2], lamk[2];
    int iwork[GEN_RT_ACCEL_IWORK(2, 2)];
    /* u' = (1, 4); M u' - f = (-2, 4) = A^T lam -> lam2 = 4, lam1 = -6 */
    CHECK_INT(gen_rt_accel_partitioned(2, 2, NULL, dep, M, f, A, a, work, iwork, ud, lam),
              GEN_RT_OK);
    CHECK_INT(gen_rt_accel_kkt(2, 2, M, f, A, a, work, iwork, udk, lamk), GEN_RT_OK);
    CHECK_NEAR(ud[0], 1.0, TOL(1e-14, 1e-6));
    CHECK_NEAR(ud[1], 4.0, TOL(1e-14, 1e-6));
    CHECK_NEAR(lam[0], -6.0, TOL(1e-14, 1e-5));
    CHECK_NEAR(lam[1], 4.0, TOL(1e-14, 1e-5));
    CHECK_NEAR(udk[0], 1.0, TOL(1e-14, 1e-6));
    CHECK_NEAR(udk[1], 4.0, TOL(1e-14, 1e-6));
    CHECK_NEAR(lamk[0], -6.0, TOL(1e-14, 1e-5));
    CHECK_NEAR(lamk[1], 4.0, TOL(1e-14, 1e-5));
}

static void test_args(void)
{
    gen_rt_real M[4] = {1, 0, 0, 1}, f[2] = {0, 0}, A[2] = {1, 0}, a[1] = {0};
    gen_rt_real work[GEN_RT_ACCEL_WORK(2, 1)], ud[2];
    int iwork[GEN_RT_ACCEL_IWORK(2, 1)];
    const int dep[1] = {0}, ind[1] = {1};
    CHECK_INT(gen_rt_accel_kkt(2, 1, NULL, f, A, a, work, iwork, ud, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_accel_kkt(2, 1, M, f, NULL, a, work, iwork, ud, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_accel_kkt(2, 1, M, f, A, a, NULL, iwork, ud, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_accel_kkt(2, 1, M, f, A, a, work, iwork, NULL, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_accel_kkt(0, 0, M, f, A, a, work, iwork, ud, NULL), GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_accel_partitioned(2, 1, ind, NULL, M, f, A, a, work, iwork, ud, NULL),
              GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_accel_partitioned(2, 1, NULL, dep, M, f, A, a, work, iwork, ud, NULL),
              GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_accel_partitioned(2, 1, ind, dep, M, NULL, A, a, work, iwork, ud, NULL),
              GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_accel_partitioned(1, 2, ind, dep, M, f, A, a, work, iwork, ud, NULL),
              GEN_RT_ERR_BAD_ARG);
    /* a singular mass matrix */
    M[3] = 0;
    CHECK_INT(gen_rt_accel_kkt(2, 0, M, f, NULL, NULL, work, iwork, ud, NULL),
              GEN_RT_ERR_SINGULAR);
}

/* [M, -G; C, H] [u'; R] = [f; -g0] with M = diag(2, 3), f = (1, -2),
 * G = (1/2, 1), C = (1, -1), H = 2, g0 = 1/4: by hand R = -17/23,
 * u' = (29/92, -21/23) */
static void test_reactions(void)
{
    const gen_rt_real M[4] = {2, 0, 0, 3}, f[2] = {1, -2}, G[2] = {0.5, 1};
    const gen_rt_real C[2] = {1, -1}, H[1] = {2}, g0[1] = {0.25}, Hs[1] = {0}, Gs[2] = {0, 0};
    gen_rt_real work[GEN_RT_REACTIONS_WORK(2, 1)], ud[2] = {7, 7}, R[1] = {7};
    gen_rt_real B[6] = {1, 2, -2, 0, -0.25, 0};
    int iwork[3];
    CHECK_INT(gen_rt_accel_reactions(2, 1, M, f, G, C, H, g0, work, iwork, ud, R), GEN_RT_OK);
    CHECK_NEAR(ud[0], 29.0 / 92.0, TOL(1e-15, 1e-6));
    CHECK_NEAR(ud[1], -21.0 / 23.0, TOL(1e-15, 1e-6));
    CHECK_NEAR(R[0], -17.0 / 23.0, TOL(1e-15, 1e-6));
    CHECK_INT(gen_rt_accel_reactions(2, 1, M, f, G, C, H, g0, work, iwork, ud, NULL), GEN_RT_OK);
    CHECK_NEAR(ud[1], -21.0 / 23.0, TOL(1e-15, 1e-6));
    /* the same matrix on two columns: [f; -g0] gives [u'; R], and the unit
     * column e0 scaled by 2 the first column of the inverse times 2 */
    CHECK_INT(gen_rt_reactions_columns(2, 1, M, G, C, H, 2, work, iwork, B), GEN_RT_OK);
    CHECK_NEAR(B[0], 29.0 / 92.0, TOL(1e-15, 1e-6));
    CHECK_NEAR(B[2], -21.0 / 23.0, TOL(1e-15, 1e-6));
    CHECK_NEAR(B[4], -17.0 / 23.0, TOL(1e-15, 1e-6));
    /* the second column z = K^-1 (2, 0, 0): 2 z0 - z2/2 = 2, 3 z1 - z2 = 0, z0 - z1 + 2 z2 = 0 */
    CHECK_NEAR(2 * B[1] - 0.5 * B[5], 2.0, TOL(1e-14, 1e-5));
    CHECK_NEAR(3 * B[3] - B[5], 0.0, TOL(1e-14, 1e-5));
    CHECK_NEAR(B[1] - B[3] + 2 * B[5], 0.0, TOL(1e-14, 1e-5));
    /* the reaction appears nowhere: singular, outputs untouched */
    ud[0] = ud[1] = R[0] = 7;
    CHECK_INT(gen_rt_accel_reactions(2, 1, M, f, Gs, C, Hs, g0, work, iwork, ud, R),
              GEN_RT_ERR_SINGULAR_REACTIONS);
    CHECK(ud[0] == 7 && ud[1] == 7 && R[0] == 7);
    CHECK_INT(gen_rt_reactions_columns(2, 1, M, Gs, C, Hs, 2, work, iwork, B),
              GEN_RT_ERR_SINGULAR_REACTIONS);
    CHECK_INT(gen_rt_accel_reactions(2, 1, NULL, f, G, C, H, g0, work, iwork, ud, R),
              GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_accel_reactions(2, 0, M, f, G, C, H, g0, work, iwork, ud, R),
              GEN_RT_ERR_BAD_ARG);
    CHECK_INT(gen_rt_reactions_columns(2, 1, M, G, C, H, 2, work, iwork, NULL),
              GEN_RT_ERR_NULL);
}

/* gen_rt_reactions_lin, one of each: K = [2, -1/2; 1, 2] (det 9/2),
 * B = [Rq + Xq, Ru + Xu, Rr + Xr; Pq, Pu, Pr] = [4, 0, -1; 4, 1, 0]; the first
 * row of K^-1 B is (2 B0 + B1 / 2) / (9/2) = (20, 1, -4) / 9 */
static void test_reactions_lin(void)
{
    const gen_rt_real M[1] = {2}, G[1] = {0.5}, C[1] = {1}, H[1] = {2};
    const gen_rt_real Xq[1] = {1}, Xu[1] = {0}, Xr[1] = {0}, Pq[1] = {4}, Pu[1] = {1}, Pr[1] = {0};
    gen_rt_real Rq[1] = {3}, Ru[1] = {0}, Rr[1] = {-1}, Mo[1] = {7};
    gen_rt_real work[GEN_RT_REACTIONS_LIN_WORK(1, 1, 1, 1)];
    int iwork[2];
    CHECK_INT(gen_rt_reactions_lin(1, 1, 1, 1, M, G, C, H, Xq, Xu, Xr, Pq, Pu, Pr, work, iwork,
                                   Rq, Ru, Rr, Mo), GEN_RT_OK);
    CHECK_NEAR(Rq[0], 20.0 / 9.0, TOL(1e-15, 1e-6));
    CHECK_NEAR(Ru[0], 1.0 / 9.0, TOL(1e-15, 1e-6));
    CHECK_NEAR(Rr[0], -4.0 / 9.0, TOL(1e-15, 1e-6));
    CHECK_NEAR(Mo[0], 1.0, 0.0);
    CHECK_INT(gen_rt_reactions_lin(1, 1, 1, 1, M, G, C, H, Xq, Xu, NULL, Pq, Pu, Pr, work, iwork,
                                   Rq, Ru, Rr, Mo), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_reactions_lin(1, 1, 0, 1, M, G, C, H, Xq, Xu, NULL, Pq, Pu, NULL, work, iwork,
                                   Rq, Ru, NULL, Mo), GEN_RT_OK);
}

/* gen_rt_kkt_matrix: [M, -A^T; A, 0] entry by entry (n = 3, m = 2, every
 * entry of M and A distinct), and M alone without constraints (A NULL) */
static void test_kkt_matrix(void)
{
    const gen_rt_real M[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    const gen_rt_real A[6] = {11, 12, 13, 14, 15, 16};
    const gen_rt_real want[25] = {1,  2,  3,  -11, -14,
                                  4,  5,  6,  -12, -15,
                                  7,  8,  9,  -13, -16,
                                  11, 12, 13, 0,   0,
                                  14, 15, 16, 0,   0};
    gen_rt_real K[25];
    int i;
    for (i = 0; i < 25; ++i) K[i] = -99;
    gen_rt_kkt_matrix(3, 2, M, A, K);
    for (i = 0; i < 25; ++i) CHECK_NEAR(K[i], want[i], 0.0);
    for (i = 0; i < 25; ++i) K[i] = -99;
    gen_rt_kkt_matrix(3, 0, M, NULL, K);
    for (i = 0; i < 9; ++i) CHECK_NEAR(K[i], M[i], 0.0);
    CHECK_NEAR(K[9], -99.0, 0.0); /* nothing written beyond 3 x 3 */
}

int main(void)
{
    test_kkt_matrix();
    test_reactions();
    test_reactions_lin();
    test_pendulum();
    test_pendulum_horizontal();
    test_free_particle();
    test_all_dependent();
    test_args();
    TEST_END();
}
