/* test_project.c - gen_rt_min_norm_correct as a Gauss-Newton projection onto
 * the unit circle and as a linear velocity projection. */
#include "test_common.h"

static void project_circle(double r0, double ang)
{
    gen_rt_real x[2], J[2], res[1], work[GEN_RT_MIN_NORM_WORK(1, 2)];
    double r = r0, ang_after;
    int it;
    x[0] = (gen_rt_real)(r0 * cos(ang));
    x[1] = (gen_rt_real)(r0 * sin(ang));
    ang = atan2((double)x[1], (double)x[0]); /* the angle of the stored point */
    for (it = 0; it < 4; ++it) {
        double rn;
        res[0] = x[0] * x[0] + x[1] * x[1] - 1;
        J[0] = 2 * x[0];
        J[1] = 2 * x[1];
        CHECK_INT(gen_rt_min_norm_correct(1, 2, J, res, work, x), GEN_RT_OK);
        /* Newton on the radius: r <- r - (r^2 - 1) / (2 r) = (r^2 + 1) / (2 r) */
        r = (r * r + 1) / (2 * r);
        rn = sqrt((double)x[0] * x[0] + (double)x[1] * x[1]);
        CHECK_NEAR(rn, r, TOL(4e-16, 2e-7) * 4);
        /* the correction is along the normal: the angle does not move */
        ang_after = atan2((double)x[1], (double)x[0]);
        CHECK_NEAR(ang_after, ang, TOL(1e-14, 1e-6));
    }
    CHECK_NEAR(sqrt((double)x[0] * x[0] + (double)x[1] * x[1]), 1.0, TOL(1e-15, 3e-7));
    CHECK_NEAR((double)x[0] * x[0] + (double)x[1] * x[1] - 1.0, 0.0, TOL(1e-15, 6e-7));
    CHECK_NEAR(x[0], cos(ang), TOL(1e-15, 3e-7));
    CHECK_NEAR(x[1], sin(ang), TOL(1e-15, 3e-7));
}

static void test_circle(void)
{
    project_circle(1.1, 0.7);
    project_circle(0.93, -2.5);
    project_circle(1.05, M_PI / 2);
}

static void test_velocity(void)
{
    /* A u = 0 with A 2 x 3: one call is exact (the constraint is linear) */
    const double Ad[6] = {1.0, 2.0, -1.0, 0.5, -1.0, 3.0};
    const double ud[3] = {0.3, -0.7, 1.1};
    gen_rt_real A[6], u[3], res[2], work[GEN_RT_MIN_NORM_WORK(2, 3)];
    double G[4], Gi[4], det, y[2], uref[3], nvec[3], du[3], dot = 0, ncross = 0;
    int i, j, k;
    for (i = 0; i < 6; ++i) A[i] = (gen_rt_real)Ad[i];
    for (i = 0; i < 3; ++i) u[i] = (gen_rt_real)ud[i];
    for (i = 0; i < 2; ++i) {
        res[i] = 0;
        for (k = 0; k < 3; ++k) res[i] += A[i * 3 + k] * u[k];
    }
    CHECK_INT(gen_rt_min_norm_correct(2, 3, A, res, work, u), GEN_RT_OK);
    for (i = 0; i < 2; ++i) {
        double s = 0;
        for (k = 0; k < 3; ++k) s += Ad[i * 3 + k] * (double)u[k];
        CHECK_NEAR(s, 0.0, TOL(1e-15, 1e-6));
    }
    /* independent reference: u - A^T (A A^T)^-1 A u with an explicit inverse */
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 2; ++j) {
            G[i * 2 + j] = 0;
            for (k = 0; k < 3; ++k) G[i * 2 + j] += Ad[i * 3 + k] * Ad[j * 3 + k];
        }
    det = G[0] * G[3] - G[1] * G[2];
    Gi[0] = G[3] / det; Gi[1] = -G[1] / det; Gi[2] = -G[2] / det; Gi[3] = G[0] / det;
    for (i = 0; i < 2; ++i) {
        double r = 0;
        for (k = 0; k < 3; ++k) r += Ad[i * 3 + k] * ud[k];
        y[i] = r;
    }
    {
        double z0 = Gi[0] * y[0] + Gi[1] * y[1], z1 = Gi[2] * y[0] + Gi[3] * y[1];
        for (k = 0; k < 3; ++k) uref[k] = ud[k] - (Ad[k] * z0 + Ad[3 + k] * z1);
    }
    for (k = 0; k < 3; ++k) CHECK_NEAR(u[k], uref[k], TOL(1e-15, 1e-6));
    /* minimum norm: the correction is orthogonal to the null space of A */
    nvec[0] = Ad[1] * Ad[5] - Ad[2] * Ad[4];
    nvec[1] = Ad[2] * Ad[3] - Ad[0] * Ad[5];
    nvec[2] = Ad[0] * Ad[4] - Ad[1] * Ad[3];
    for (k = 0; k < 3; ++k) {
        du[k] = (double)u[k] - ud[k];
        dot += du[k] * nvec[k];
        ncross += nvec[k] * nvec[k];
    }
    CHECK_NEAR(dot / sqrt(ncross), 0.0, TOL(1e-15, 1e-6));
    /* a second call changes nothing (already on the constraint) */
    {
        gen_rt_real u2[3];
        for (k = 0; k < 3; ++k) u2[k] = u[k];
        for (i = 0; i < 2; ++i) {
            res[i] = 0;
            for (k = 0; k < 3; ++k) res[i] += A[i * 3 + k] * u2[k];
        }
        CHECK_INT(gen_rt_min_norm_correct(2, 3, A, res, work, u2), GEN_RT_OK);
        for (k = 0; k < 3; ++k) CHECK_NEAR(u2[k], u[k], TOL(1e-15, 1e-6));
    }
}

static void test_degenerate(void)
{
    gen_rt_real J[6] = {1, 2, 3, 2, 4, 6}; /* rank 1 */
    gen_rt_real res[2] = {1, 1}, x[3] = {1, 1, 1}, work[GEN_RT_MIN_NORM_WORK(2, 3)];
    gen_rt_real z[3] = {0, 0, 0};
    CHECK_INT(gen_rt_min_norm_correct(2, 3, J, res, work, x), GEN_RT_ERR_SINGULAR);
    CHECK_INT(gen_rt_min_norm_correct(1, 3, z, res, work, x), GEN_RT_ERR_SINGULAR);
    CHECK(x[0] == 1 && x[1] == 1 && x[2] == 1); /* untouched on failure */
    CHECK_INT(gen_rt_min_norm_correct(0, 3, NULL, NULL, NULL, x), GEN_RT_OK);
    CHECK_INT(gen_rt_min_norm_correct(1, 3, NULL, res, work, x), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_min_norm_correct(1, 3, J, res, work, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_min_norm_correct(-1, 3, J, res, work, x), GEN_RT_ERR_BAD_ARG);
}

int main(void)
{
    test_circle();
    test_velocity();
    test_degenerate();
    TEST_END();
}
