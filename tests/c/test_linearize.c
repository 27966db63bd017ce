/* test_linearize.c - gen_rt_linearize on a 1-dof pendulum and on the
 * Cartesian (x, y) pendulum with a configuration constraint. */
#include "test_common.h"

#define PM 1.3   /* mass */
#define PL 0.7   /* length */
#define PG 9.81  /* gravity, along +x for the constrained model */
#define PC 0.37  /* viscous damping: force -c u */

static void check_mat(const gen_rt_real *got, const double *want, int n, double tol,
                      const char *what)
{
    int i, before = test_failures;
    for (i = 0; i < n; ++i) CHECK_NEAR(got[i], want[i], tol);
    if (test_failures != before) fprintf(stderr, "  (in %s)\n", what);
}

/* (a) theta'' = (-m g L sin q - c u + r) / (m L^2), nq = nu = 1, no
 * constraints; run without (c = 0, as specified) and with damping */
static void test_simple_pendulum(void)
{
    const double qs[4] = {0.0, M_PI, 0.8, 0.8};
    int k;
    for (k = 0; k < 4; ++k) {
        double q = qs[k], c = (k == 3) ? PC : 0.0;
        const gen_rt_real Kqd[1] = {1}, Kq[1] = {0}, Ku[1] = {-1}, Rr[1] = {-1};
        gen_rt_real M[1], Rq[1], Ru[1], A[4], B[2];
        gen_rt_real work[GEN_RT_LIN_WORK(1, 1, 0, 0, 1)];
        int iwork[GEN_RT_LIN_IWORK(1, 1, 0, 0)];
        const int ind[1] = {0};
        gen_rt_lin_dims d;
        gen_rt_lin_blocks b;
        double Aw[4], Bw[2];
        memset(&b, 0, sizeof b);
        d.nq = 1; d.nu = 1; d.mc = 0; d.mv = 0; d.nr = 1;
        d.q_ind = ind; d.u_ind = ind; d.q_dep = NULL; d.u_dep = NULL;
        M[0] = (gen_rt_real)(PM * PL * PL);
        Rq[0] = (gen_rt_real)(PM * PG * PL * cos(q));
        Ru[0] = (gen_rt_real)c;
        b.Kqd = Kqd; b.Kq = Kq; b.Ku = Ku; b.M = M; b.Rq = Rq; b.Ru = Ru; b.Rr = Rr;
        CHECK_INT(gen_rt_linearize(&d, &b, work, iwork, A, B), GEN_RT_OK);
        Aw[0] = 0; Aw[1] = 1; Aw[2] = -(PG / PL) * cos(q); Aw[3] = -c / (PM * PL * PL);
        Bw[0] = 0; Bw[1] = 1 / (PM * PL * PL);
        if (k == 0) CHECK_NEAR(Aw[2], -PG / PL, 0.0);
        if (k == 1) CHECK_NEAR(Aw[2], PG / PL, 1e-15);
        check_mat(A, Aw, 4, TOL(1e-13, 1e-5) * PG / PL, "simple pendulum A");
        check_mat(B, Bw, 2, TOL(1e-13, 1e-5), "simple pendulum B");
        /* without inputs B may be NULL */
        d.nr = 0; b.Rr = NULL;
        CHECK_INT(gen_rt_linearize(&d, &b, work, iwork, A, NULL), GEN_RT_OK);
        check_mat(A, Aw, 4, TOL(1e-13, 1e-5) * PG / PL, "simple pendulum A, nr = 0");
    }
}

/* The blocks of the constrained pendulum (q = u = [x, y], y independent)
 * at a state, its accelerations and the runtime-model multiplier lam. */
typedef struct {
    gen_rt_real Kqd[4], Kq[4], Ku[4], M[4], Rq[4], Ru[4], Rr[2];
    gen_rt_real A[2], Sq[2], Su[2], Vq[2], Jc[2];
} cpend_blocks;

static void cpend_build(double x, double y, double u1, double u2, double ud1, double ud2,
                        double lam, double c, cpend_blocks *p)
{
    int i;
    for (i = 0; i < 4; ++i) {
        int diag = (i == 0 || i == 3);
        p->Kqd[i] = diag ? 1 : 0;
        p->Kq[i] = 0;
        p->Ku[i] = diag ? -1 : 0;
        p->M[i] = diag ? (gen_rt_real)PM : 0;
        p->Rq[i] = diag ? (gen_rt_real)(-2 * lam) : 0;
        p->Ru[i] = diag ? (gen_rt_real)c : 0;
    }
    p->Rr[0] = 0; p->Rr[1] = -1;      /* an input force along y */
    p->Jc[0] = (gen_rt_real)(2 * x); p->Jc[1] = (gen_rt_real)(2 * y);
    p->A[0] = (gen_rt_real)(2 * x); p->A[1] = (gen_rt_real)(2 * y);
    p->Vq[0] = (gen_rt_real)(2 * u1); p->Vq[1] = (gen_rt_real)(2 * u2);
    p->Sq[0] = (gen_rt_real)(2 * ud1); p->Sq[1] = (gen_rt_real)(2 * ud2);
    p->Su[0] = (gen_rt_real)(4 * u1); p->Su[1] = (gen_rt_real)(4 * u2);
}

static int cpend_linearize(const cpend_blocks *p, gen_rt_real *A, gen_rt_real *B)
{
    static const int q_ind[1] = {1}, q_dep[1] = {0};
    gen_rt_real work[GEN_RT_LIN_WORK(2, 2, 1, 1, 1)];
    int iwork[GEN_RT_LIN_IWORK(2, 2, 1, 1)];
    gen_rt_lin_dims d;
    gen_rt_lin_blocks b;
    d.nq = 2; d.nu = 2; d.mc = 1; d.mv = 1; d.nr = 1;
    d.q_ind = q_ind; d.q_dep = q_dep; d.u_ind = q_ind; d.u_dep = q_dep;
    b.Kqd = p->Kqd; b.Kq = p->Kq; b.Ku = p->Ku; b.M = p->M; b.Rq = p->Rq; b.Ru = p->Ru;
    b.Rr = p->Rr; b.A = p->A; b.Sq = p->Sq; b.Su = p->Su; b.Vq = p->Vq; b.Jc = p->Jc;
    b.Sqd = NULL;
    b.ny = 0; b.Yq = b.Yu = b.Yr = NULL; b.C_lin = b.D_lin = NULL;
    return gen_rt_linearize(&d, &b, work, iwork, A, B);
}

/* the reduced dynamics in (y, v = y') on the branch sign(x) = sx, with the
 * input force r along y: exact.
 * m xdd = m g - c u1 + x Lam,  m ydd = r - c v + y Lam,
 * x xdd + y ydd + u1^2 + v^2 = 0,  u1 = -y v / x  -> solve for Lam */
static double reduced_ydd(double y, double v, double r, double sx, double c)
{
    double x = sx * sqrt(PL * PL - y * y);
    double u1 = -y * v / x;
    double Lam = -(PM * (u1 * u1 + v * v) + x * (PM * PG - c * u1) + y * (r - c * v)) /
                 (PL * PL);
    return (r - c * v + y * Lam) / PM;
}

static void test_constrained_rest(double sx, double c)
{
    /* hanging (sx = +1) or inverted (sx = -1) rest: x = sx L, y = 0 */
    cpend_blocks p;
    gen_rt_real A[4], B[2];
    double x = sx * PL, lam = -PM * PG / (2 * x); /* m*0 - m g - 2 x lam = 0 */
    double Aw[4], Bw[2];
    cpend_build(x, 0.0, 0.0, 0.0, 0.0, 0.0, lam, c, &p);
    CHECK_INT(cpend_linearize(&p, A, B), GEN_RT_OK);
    Aw[0] = 0; Aw[1] = 1; Aw[2] = -sx * PG / PL; Aw[3] = -c / PM;
    Bw[0] = 0; Bw[1] = 1 / PM;
    check_mat(A, Aw, 4, TOL(1e-12, 1e-5) * PG / PL, "constrained pendulum at rest, A");
    check_mat(B, Bw, 2, TOL(1e-12, 1e-5), "constrained pendulum at rest, B");
}

static void test_constrained_moving(double c)
{
    /* a general state on the circle (x > 0) with velocity: compare with
     * central differences of the exact reduced dynamics */
    const double y = 0.31, v = -0.9, h = 1e-5;
    double x = sqrt(PL * PL - y * y), u1 = -y * v / x, u2 = v;
    /* physical multiplier Lam (force Lam [x, y]); the runtime's model has
     * A = [2x, 2y], so its multiplier is Lam / 2 */
    double Lam = -(PM * (u1 * u1 + u2 * u2) + x * (PM * PG - c * u1) - y * c * u2) /
                 (PL * PL);
    double ud1 = (PM * PG - c * u1 + x * Lam) / PM, ud2 = (-c * u2 + y * Lam) / PM;
    double Aw[4], Bw[2];
    cpend_blocks p;
    gen_rt_real A[4], B[2];
    /* consistency of the reference */
    CHECK_NEAR(x * ud1 + y * ud2 + u1 * u1 + u2 * u2, 0.0, 1e-12);
    CHECK_NEAR(ud2, reduced_ydd(y, v, 0, 1, c), 1e-12);
    cpend_build(x, y, u1, u2, ud1, ud2, Lam / 2, c, &p);
    CHECK_INT(cpend_linearize(&p, A, B), GEN_RT_OK);
    Aw[0] = 0; Aw[1] = 1;
    Aw[2] = (reduced_ydd(y + h, v, 0, 1, c) - reduced_ydd(y - h, v, 0, 1, c)) / (2 * h);
    Aw[3] = (reduced_ydd(y, v + h, 0, 1, c) - reduced_ydd(y, v - h, 0, 1, c)) / (2 * h);
    Bw[0] = 0;
    Bw[1] = (reduced_ydd(y, v, h, 1, c) - reduced_ydd(y, v, -h, 1, c)) / (2 * h);
    check_mat(A, Aw, 4, TOL(1e-8, 1e-4) * PG / PL, "moving constrained pendulum, A");
    check_mat(B, Bw, 2, TOL(1e-8, 1e-4), "moving constrained pendulum, B");
}

static void test_constrained_singular(void)
{
    /* horizontal, x = 0 exactly: x cannot be the dependent coordinate */
    cpend_blocks p;
    gen_rt_real A[4], B[2];
    double thd = 1.1, y = PL, u2 = 0.0, u1 = -PL * thd;
    /* xdd = g, ydd = -L thd^2, m ydd = 2 y lam */
    double lam = PM * (-PL * thd * thd) / (2 * y);
    cpend_build(0.0, y, u1, u2, PG, -PL * thd * thd, lam, 0.0, &p);
    CHECK(p.Jc[0] == 0);
    CHECK_INT(cpend_linearize(&p, A, B), GEN_RT_ERR_SINGULAR);
}

static void test_args(void)
{
    gen_rt_real work[GEN_RT_LIN_WORK(1, 1, 0, 0, 1)], A[4], B[2];
    const gen_rt_real one[1] = {1}, zero[1] = {0};
    int iwork[GEN_RT_LIN_IWORK(1, 1, 0, 0)];
    const int ind[1] = {0};
    gen_rt_lin_dims d;
    gen_rt_lin_blocks b;
    memset(&b, 0, sizeof b);
    d.nq = 1; d.nu = 1; d.mc = 0; d.mv = 0; d.nr = 1;
    d.q_ind = ind; d.u_ind = ind; d.q_dep = NULL; d.u_dep = NULL;
    b.Kqd = one; b.Kq = zero; b.Ku = one; b.M = one; b.Rq = zero; b.Ru = zero;
    CHECK_INT(gen_rt_linearize(&d, &b, work, iwork, A, B), GEN_RT_ERR_NULL); /* Rr */
    b.Rr = one;
    CHECK_INT(gen_rt_linearize(&d, &b, work, iwork, A, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_linearize(NULL, &b, work, iwork, A, B), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_linearize(&d, &b, NULL, iwork, A, B), GEN_RT_ERR_NULL);
    d.mc = 2;
    CHECK_INT(gen_rt_linearize(&d, &b, work, iwork, A, B), GEN_RT_ERR_BAD_ARG);
    d.mc = 0;
    b.Kqd = zero; /* singular kinematic matrix */
    CHECK_INT(gen_rt_linearize(&d, &b, work, iwork, A, B), GEN_RT_ERR_SINGULAR);
    b.Kqd = one; b.M = zero; /* singular mass matrix */
    CHECK_INT(gen_rt_linearize(&d, &b, work, iwork, A, B), GEN_RT_ERR_SINGULAR);
}

int main(void)
{
    test_simple_pendulum();
    test_constrained_rest(1.0, 0.0);  /* hanging: A = [[0, 1], [-g/L, 0]] */
    test_constrained_rest(-1.0, 0.0); /* inverted: A = [[0, 1], [g/L, 0]] */
    test_constrained_rest(1.0, PC);   /* damped: A[1][1] = -c/m */
    test_constrained_moving(0.0);
    test_constrained_moving(PC);
    test_constrained_singular();
    test_args();
    TEST_END();
}
