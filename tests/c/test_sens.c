/*
 * test_sens.c - gen_rt_sens.c: the full-state Jacobian of the right-hand
 * side and the exact derivatives of one RK4 step, on hand-written models
 * (copied from test_model.c, plus an implicit-kinematics variant):
 *
 *   osc:   m x'' = -k x + r (LDL^T or LU), the linear system
 *          A = [[0, 1], [-k/m, 0]], B = [0, 1/m];
 *   pend:  the particle at (x, y) on a circle of radius L, gravity along +x,
 *          configuration constraint x^2 + y^2 = L^2, velocity constraint
 *          x x' + y y' = 0, dependent x, x' (Kane partition or KKT);
 *   pendi: the same constraints with implicit kinematics
 *          Kqd(q) q' = u, Kqd = [[2 + y^2, x], [0, 1 + x^2]], damping -c u,
 *          so the acceleration-constraint term a = u . q' holds q'
 *          (accel_terms, Sqd).
 *
 * Checked: (a) the Jacobian against central differences (Richardson) of
 * gen_rt_model_rhs, on and off the constraint manifold; (b) the step:
 * x1 bit-identical to gen_rt_model_step_rk4 without projection, Fx and Fr
 * against central differences of the step on the independent state (the
 * dependent entries completed by gen_rt_model_consistent_state); (c) for
 * the oscillator the closed form of RK4 on a linear system; h -> 0 gives
 * I + h A_lin (the linearization); (d) guard values after the work arrays;
 * failures leave x untouched.
 */
#include "test_common.h"
#include "test_models.h"

#include "gen_rt_sens.h"

#define PM 1.5   /* mass */
#define PG 9.81  /* gravity */
#define PL 1.2   /* length */
#define PK 4.0   /* spring */
#define PC 0.3   /* damping (pendi) */
#define GUARD 16

/* ---------------------------------------------------------------- pend */

static void p_constraints(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                          gen_rt_real *fc)
{
    (void)t;
    fc[0] = q[0] * q[0] + q[1] * q[1] - p[2] * p[2];
}

static void p_jac(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t, gen_rt_real *fc,
                  gen_rt_real *Jc)
{
    p_constraints(q, p, t, fc);
    Jc[0] = 2 * q[0]; Jc[1] = 2 * q[1];
}

static const int p_q_ind[1] = {1}, p_q_dep[1] = {0}, p_u_ind[1] = {1}, p_u_dep[1] = {0};

static gen_rt_model pend_model(int accel)
{
    gen_rt_model m;
    m.nq = 2; m.nu = 2; m.nr = 0; m.np = 3; m.mc = 1; m.mv = 1;
    m.explicit_kinematics = 1; m.accel = accel;
    m.q_ind = p_q_ind; m.q_dep = p_q_dep; m.u_ind = p_u_ind; m.u_dep = p_u_dep;
    m.mass_matrix = p_mass; m.forcing = p_forcing; m.kinematics = p_kin;
    m.rhs_terms = p_rhs_terms; m.constraints = p_constraints; m.constraint_jacobian = p_jac;
    m.velocity_constraints = p_vc; m.velocity_constraint_matrix = p_vcm;
    m.energy = NULL; m.lin_terms = p_lin; m.mass_solve = NULL;
    m.na = 0; m.auxiliary = NULL; m.accel_terms = NULL; m.rhs_solve = NULL; m.hybrid = NULL;
    m.reaction_solve = NULL;
    return m;
}

/* --------------------------------------------------------------- pendi */
static void pi_forcing(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                       const gen_rt_real *p, gen_rt_real t, gen_rt_real *f)
{
    (void)q; (void)r; (void)t;
    f[0] = p[0] * p[1] - p[3] * u[0];
    f[1] = -p[3] * u[1];
}

/* Kqd q' = kr: Kqd = [[2 + y^2, x], [0, 1 + x^2]], kr = u */
static void pi_kin(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                   gen_rt_real t, gen_rt_real *Kqd, gen_rt_real *qd)
{
    (void)p; (void)t;
    Kqd[0] = 2 + q[1] * q[1]; Kqd[1] = q[0];
    Kqd[2] = 0;               Kqd[3] = 1 + q[0] * q[0];
    qd[0] = u[0];
    qd[1] = u[1];
}

static void pi_rhs_terms(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                         const gen_rt_real *p, gen_rt_real t, gen_rt_real *Kqd,
                         gen_rt_real *qd, gen_rt_real *M, gen_rt_real *f, gen_rt_real *A,
                         gen_rt_real *a)
{
    pi_kin(q, u, p, t, Kqd, qd);
    p_mass(q, p, t, M);
    pi_forcing(q, u, r, p, t, f);
    A[0] = q[0]; A[1] = q[1];
    a[0] = 0; /* d(A u)/dq q' at q' = 0 */
}

/* a = d(A u + b)/dq q' = u . q' */
static void pi_accel_terms(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *qd,
                           const gen_rt_real *p, gen_rt_real t, gen_rt_real *a)
{
    (void)q; (void)p; (void)t;
    a[0] = u[0] * qd[0] + u[1] * qd[1];
}

/* kin = Kqd(q) q' - u,  R = M u' - f - A^T lam,  S = A u' + u . q' */
static void pi_lin(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *qd,
                   const gen_rt_real *ud, const gen_rt_real *lam, const gen_rt_real *r,
                   const gen_rt_real *p, gen_rt_real t, const gen_rt_lin_out *o)
{
    int i;
    (void)r; (void)t;
    o->Kqd[0] = 2 + q[1] * q[1]; o->Kqd[1] = q[0];
    o->Kqd[2] = 0;               o->Kqd[3] = 1 + q[0] * q[0];
    o->Kq[0] = qd[1];            o->Kq[1] = 2 * q[1] * qd[0];
    o->Kq[2] = 2 * q[0] * qd[1]; o->Kq[3] = 0;
    for (i = 0; i < 4; ++i) {
        o->Ku[i] = (i == 0 || i == 3) ? -1 : 0;
        o->M[i] = (i == 0 || i == 3) ? p[0] : 0;
        o->Rq[i] = (i == 0 || i == 3) ? -lam[0] : 0;
        o->Ru[i] = (i == 0 || i == 3) ? p[3] : 0;
    }
    o->A[0] = q[0]; o->A[1] = q[1];
    o->Sq[0] = ud[0]; o->Sq[1] = ud[1];
    o->Su[0] = qd[0]; o->Su[1] = qd[1];
    o->Sqd[0] = u[0]; o->Sqd[1] = u[1];
    o->Vq[0] = u[0]; o->Vq[1] = u[1];
    o->Jc[0] = 2 * q[0]; o->Jc[1] = 2 * q[1];
}

static gen_rt_model pendi_model(int accel)
{
    gen_rt_model m = pend_model(accel);
    m.np = 4;
    m.explicit_kinematics = 0;
    m.forcing = pi_forcing; m.kinematics = pi_kin; m.rhs_terms = pi_rhs_terms;
    m.lin_terms = pi_lin; m.accel_terms = pi_accel_terms;
    return m;
}

/* ----------------------------------------------------------------- osc */

/* the same blocks, NaN beyond x = 100 (a kernel singular there) */
static void o_lin_bad(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *qd,
                      const gen_rt_real *ud, const gen_rt_real *lam, const gen_rt_real *r,
                      const gen_rt_real *p, gen_rt_real t, const gen_rt_lin_out *o)
{
    o_lin(q, u, qd, ud, lam, r, p, t, o);
    if (q[0] > 100) o->Rq[0] = (gen_rt_real)NAN;
}

static int o_solve(const gen_rt_real *M, const gen_rt_real *f, gen_rt_real *x)
{
    if (!(M[0] > 0)) return GEN_RT_ERR_SINGULAR;
    x[0] = f[0] / M[0];
    return GEN_RT_OK;
}

static const int o_ind[1] = {0}, o_none[1] = {0};

static gen_rt_model osc_model(int accel)
{
    gen_rt_model m;
    m.nq = 1; m.nu = 1; m.nr = 1; m.np = 2; m.mc = 0; m.mv = 0;
    m.explicit_kinematics = 1; m.accel = accel;
    m.q_ind = o_ind; m.q_dep = o_none; m.u_ind = o_ind; m.u_dep = o_none;
    m.mass_matrix = o_mass; m.forcing = o_forcing; m.kinematics = o_kin;
    m.rhs_terms = o_rhs_terms; m.constraints = NULL; m.constraint_jacobian = NULL;
    m.velocity_constraints = NULL; m.velocity_constraint_matrix = NULL;
    m.energy = NULL; m.lin_terms = o_lin;
    m.mass_solve = accel == GEN_RT_ACCEL_LDLT ? o_solve : NULL;
    m.na = 0; m.auxiliary = NULL; m.accel_terms = NULL; m.rhs_solve = NULL; m.hybrid = NULL;
    m.reaction_solve = NULL;
    return m;
}

/* ------------------------------------------------------------- helpers */
#define DIMS_P(ek, acc) 2, 2, 1, 1, 0, ek, acc
#define DIMS_O(acc) 1, 1, 0, 0, 1, 1, acc
#define W(f, ...) f(__VA_ARGS__) /* expands DIMS_* into the macro arguments */
#define BIG 4096

static gen_rt_real work[BIG + GUARD];
static int iwork[256 + GUARD];
/* the finite differences' own work (not guarded) */
static gen_rt_real fdwork[BIG];
static int fdiwork[256];

/* the largest errors seen, printed at the end for the record */
static double worst_jac = 0, worst_step = 0, worst_closed = 0, worst_lin = 0;

static void guard(int n, int ni)
{
    int i;
    for (i = 0; i < BIG + GUARD; ++i) work[i] = GEN_RT_C(12345.0);
    for (i = 0; i < 256 + GUARD; ++i) iwork[i] = 12345;
    CHECK(n < BIG && ni < 256);
}

static void guards_intact(int n, int ni)
{
    int i, ok = 1;
    for (i = n; i < n + GUARD; ++i) ok = ok && work[i] == GEN_RT_C(12345.0);
    for (i = ni; i < ni + GUARD; ++i) ok = ok && iwork[i] == 12345;
    CHECK(ok);
}

/* max |a - b| / max(1, max |b|) */
static double rel_err(int n, const gen_rt_real *a, const double *b)
{
    double e = 0, s = 1;
    int i;
    for (i = 0; i < n; ++i) {
        double d = fabs((double)a[i] - b[i]);
        if (!(d <= e)) e = d;
        if (fabs(b[i]) > s) s = fabs(b[i]);
    }
    return e / s;
}

/* central differences with one Richardson extrapolation (error O(d^4)) */
#define FD_STEP TOL(1e-4, 1e-2)
static double richardson(double fp1, double fm1, double fp2, double fm2, double d)
{
    double D1 = (fp1 - fm1) / (2 * d), D2 = (fp2 - fm2) / d; /* steps d and d/2 */
    return (4 * D2 - D1) / 3;
}

/* the columns of d rhs / d[x, r] by differences: ref (nx x (nx + nr)) */
static int fd_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                  const gen_rt_real *r, const gen_rt_real *p, double *ref)
{
    int nx = m->nq + m->nu, nr = m->nr, nc = nx + nr, j, i, k, st;
    gen_rt_real xs[8], rs[4], f[4][8];
    for (j = 0; j < nc; ++j) {
        gen_rt_real base = j < nx ? x[j] : r[j - nx];
        double d = FD_STEP * (1 + fabs((double)base));
        const double sg[4] = {1, -1, 0.5, -0.5};
        for (k = 0; k < 4; ++k) {
            for (i = 0; i < nx; ++i) xs[i] = x[i];
            for (i = 0; i < nr; ++i) rs[i] = r[i];
            if (j < nx) xs[j] = (gen_rt_real)(base + sg[k] * d);
            else rs[j - nx] = (gen_rt_real)(base + sg[k] * d);
            st = gen_rt_model_eval_rhs(m, t, xs, nr ? rs : NULL, p, fdwork, fdiwork, f[k], NULL);
            if (st) return st;
        }
        for (i = 0; i < nx; ++i)
            ref[i * nc + j] = richardson(f[0][i], f[1][i], f[2][i], f[3][i], d);
    }
    return GEN_RT_OK;
}

/* the step's derivatives on the independent state by differences:
 * perturb x_ind (or r), complete the dependent entries, step without
 * projection, read x1_ind. ref: ns x (ns + nr). */
static int fd_step(const gen_rt_model *m, gen_rt_real t, gen_rt_real h, const gen_rt_real *x,
                   const gen_rt_real *r, const gen_rt_real *p, double *ref)
{
    int nq = m->nq, nx = m->nq + m->nu, nr = m->nr, niq = m->nq - m->mc;
    int ns = niq + m->nu - m->mv, nc = ns + nr, j, i, k, st;
    gen_rt_real xs[8], rs[4], x1[4][8];
    for (j = 0; j < nc; ++j) {
        int idx = j < niq ? m->q_ind[j] : (j < ns ? nq + m->u_ind[j - niq] : -1);
        gen_rt_real base = idx >= 0 ? x[idx] : r[j - ns];
        double d = FD_STEP * (1 + fabs((double)base));
        const double sg[4] = {1, -1, 0.5, -0.5};
        for (k = 0; k < 4; ++k) {
            for (i = 0; i < nx; ++i) xs[i] = x[i];
            for (i = 0; i < nr; ++i) rs[i] = r[i];
            if (idx >= 0) xs[idx] = (gen_rt_real)(base + sg[k] * d);
            else rs[j - ns] = (gen_rt_real)(base + sg[k] * d);
            st = gen_rt_model_consistent_state(m, t, p, 0, 0, fdwork, fdiwork, xs);
            if (st) return st;
            st = gen_rt_model_step_rk4(m, t, h, nr ? rs : NULL, p, 0, fdwork, fdiwork, xs);
            if (st) return st;
            for (i = 0; i < nx; ++i) x1[k][i] = xs[i];
        }
        for (i = 0; i < ns; ++i) {
            int row = i < niq ? m->q_ind[i] : nq + m->u_ind[i - niq];
            ref[i * nc + j] = richardson(x1[0][row], x1[1][row], x1[2][row], x1[3][row], d);
        }
    }
    return GEN_RT_OK;
}

/* (a) the Jacobian at x against differences of the right-hand side */
static void check_jacobian(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                           const gen_rt_real *r, const gen_rt_real *p, const char *what)
{
    int nx = m->nq + m->nu, nr = m->nr, nc = nx + nr, n, ni, i, j, st;
    gen_rt_real Jx[64], Jr[16], J[80];
    double ref[80], e;
    n = W(GEN_RT_MODEL_JACOBIAN_WORK, m->nq, m->nu, m->mc, m->mv, nr, m->explicit_kinematics,
          m->accel);
    ni = W(GEN_RT_MODEL_JACOBIAN_IWORK, m->nq, m->nu, m->mc, m->mv, nr,
           m->explicit_kinematics, m->accel);
    guard(n, ni);
    st = gen_rt_model_jacobian(m, t, x, r, p, work, iwork, Jx, nr ? Jr : NULL);
    CHECK_INT(st, GEN_RT_OK);
    guards_intact(n, ni);
    for (i = 0; i < nx; ++i)
        for (j = 0; j < nc; ++j) J[i * nc + j] = j < nx ? Jx[i * nx + j] : Jr[i * nr + j - nx];
    CHECK_INT(fd_rhs(m, t, x, r, p, ref), GEN_RT_OK);
    e = rel_err(nx * nc, J, ref);
    if (e > worst_jac) worst_jac = e;
    CHECK_LT(e, TOL(1e-7, 2e-3));
    if (!(e < TOL(1e-7, 2e-3))) fprintf(stderr, "  (jacobian: %s)\n", what);
}

/* (b) the step against gen_rt_model_step_rk4 and differences */
static void check_step(const gen_rt_model *m, gen_rt_real t, gen_rt_real h, const gen_rt_real *x0,
                       const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *Fx,
                       gen_rt_real *Fr, const char *what)
{
    int nx = m->nq + m->nu, nr = m->nr, ns = m->nq - m->mc + m->nu - m->mv, nc = ns + nr;
    int n, ni, i, j, st, same = 1;
    gen_rt_real x[8], xr[8], F[80];
    double ref[80], e;
    for (i = 0; i < nx; ++i) x[i] = xr[i] = x0[i];
    n = W(GEN_RT_MODEL_STEP_SENS_WORK, m->nq, m->nu, m->mc, m->mv, nr, m->explicit_kinematics,
          m->accel);
    ni = W(GEN_RT_MODEL_STEP_SENS_IWORK, m->nq, m->nu, m->mc, m->mv, nr,
           m->explicit_kinematics, m->accel);
    guard(n, ni);
    st = gen_rt_model_step_sensitivity(m, t, h, r, p, work, iwork, x, Fx, nr ? Fr : NULL);
    CHECK_INT(st, GEN_RT_OK);
    guards_intact(n, ni);
    st = gen_rt_model_step_rk4(m, t, h, r, p, 0, fdwork, fdiwork, xr);
    CHECK_INT(st, GEN_RT_OK);
    for (i = 0; i < nx; ++i) same = same && x[i] == xr[i];
    CHECK(same);
    for (i = 0; i < ns; ++i)
        for (j = 0; j < nc; ++j) F[i * nc + j] = j < ns ? Fx[i * ns + j] : Fr[i * nr + j - ns];
    CHECK_INT(fd_step(m, t, h, x0, r, p, ref), GEN_RT_OK);
    e = rel_err(ns * nc, F, ref);
    if (e > worst_step) worst_step = e;
    CHECK_LT(e, TOL(1e-7, 2e-3));
    if (!(e < TOL(1e-7, 2e-3)) || !same) fprintf(stderr, "  (step: %s)\n", what);
}

/* h -> 0: (Fx - I) / h -> A_lin and Fr / h -> B_lin (gen_rt_model_linearize) */
static void check_small_step(const gen_rt_model *m, const gen_rt_real *x0, const gen_rt_real *r,
                             const gen_rt_real *p)
{
    int nx = m->nq + m->nu, nr = m->nr, ns = m->nq - m->mc + m->nu - m->mv, i, j, st;
    const gen_rt_real h = (gen_rt_real)TOL(1e-5, 1e-2);
    gen_rt_real x[8], Fx[64], Fr[16], Al[64], Bl[16], D[80];
    double ref[80], e;
    for (i = 0; i < nx; ++i) x[i] = x0[i];
    st = gen_rt_model_linearize(m, x0, r, p, 0, fdwork, fdiwork, Al, Bl);
    CHECK_INT(st, GEN_RT_OK);
    st = gen_rt_model_step_sensitivity(m, 0, h, r, p, fdwork, fdiwork, x, Fx, Fr);
    CHECK_INT(st, GEN_RT_OK);
    for (i = 0; i < ns; ++i)
        for (j = 0; j < ns + nr; ++j) {
            int c = i * (ns + nr) + j;
            if (j < ns) {
                D[c] = (Fx[i * ns + j] - (i == j ? 1 : 0)) / h;
                ref[c] = Al[i * ns + j];
            } else {
                D[c] = Fr[i * nr + j - ns] / h;
                ref[c] = Bl[i * nr + j - ns];
            }
        }
    e = rel_err(ns * (ns + nr), D, ref);
    if (e > worst_lin) worst_lin = e;
    /* O(h |A|) plus the rounding of Fx - I */
    CHECK_LT(e, TOL(1e-3, 1e-1));
}

/* ------------------------------------------------------------- tests */
static void oscillator_tests(int accel)
{
    gen_rt_model m = osc_model(accel);
    const gen_rt_real p[2] = {PM, PK}, r[1] = {GEN_RT_C(0.7)};
    const gen_rt_real states[3][2] = {{GEN_RT_C(0.3), GEN_RT_C(-0.2)}, {0, 0}, {-2, 5}};
    const double a = -PK / PM;
    gen_rt_real Fx[4], Fr[2], x[2];
    int s, k, n, ni, st;

    for (s = 0; s < 3; ++s) {
        check_jacobian(&m, GEN_RT_C(0.1) * s, states[s], r, p, "osc");
        check_step(&m, GEN_RT_C(0.1) * s, GEN_RT_C(0.1), states[s], r, p, Fx, Fr, "osc");
    }

    /* (c) RK4 on x' = A x + B r: Fx = I + hA + (hA)^2/2 + (hA)^3/6 + (hA)^4/24,
     * Fr = h (I + hA/2 + (hA)^2/6 + (hA)^3/24) B; A^2 = a I */
    {
        const double hs[3] = {0.1, 0.37, 1e-3};
        for (k = 0; k < 3; ++k) {
            double h = hs[k], h2 = h * h, e = 0;
            double c0 = 1 + a * h2 / 2 + a * a * h2 * h2 / 24; /* even powers */
            double c1 = h + a * h2 * h / 6;                     /* odd powers / A */
            double Fw[4], Bw[2];
            double d0 = h + a * h2 * h / 6, d1 = h2 / 2 + a * h2 * h2 / 24;
            Fw[0] = c0; Fw[1] = c1; Fw[2] = a * c1; Fw[3] = c0;
            /* h S(hA) B with B = [0, 1/m]: S = d0/h I + d1/h A */
            Bw[0] = d1 / PM; Bw[1] = d0 / PM;
            x[0] = GEN_RT_C(0.3); x[1] = GEN_RT_C(-0.2);
            n = W(GEN_RT_MODEL_STEP_SENS_WORK, DIMS_O(accel));
            ni = W(GEN_RT_MODEL_STEP_SENS_IWORK, DIMS_O(accel));
            guard(n, ni);
            st = gen_rt_model_step_sensitivity(&m, 0, (gen_rt_real)h, r, p, work, iwork, x, Fx,
                                               Fr);
            CHECK_INT(st, GEN_RT_OK);
            guards_intact(n, ni);
            e = rel_err(4, Fx, Fw);
            if (rel_err(2, Fr, Bw) > e) e = rel_err(2, Fr, Bw);
            if (e > worst_closed) worst_closed = e;
            CHECK_LT(e, TOL(1e-14, 1e-6));
            /* the system is linear: x1 = Fx x0 + Fr r */
            CHECK_NEAR(x[0], Fw[0] * 0.3 + Fw[1] * -0.2 + Bw[0] * 0.7, TOL(1e-14, 1e-6));
            CHECK_NEAR(x[1], Fw[2] * 0.3 + Fw[3] * -0.2 + Bw[1] * 0.7, TOL(1e-14, 1e-6));
            /* h -> 0: Fx = I + h A + O(h^2) */
            if (k == 2) {
                CHECK_NEAR(Fx[0], 1, h2 * fabs(a));
                CHECK_NEAR(Fx[1], h, h2 * fabs(a));
                CHECK_NEAR(Fx[2], h * a, h2 * fabs(a));
                CHECK_NEAR(Fx[3], 1, h2 * fabs(a));
            }
        }
    }
    check_small_step(&m, states[0], r, p);

    /* the Jacobian: [[0, 1], [-k/m, 0]], [0, 1/m] exactly */
    {
        gen_rt_real Jx[4], Jr[2];
        n = W(GEN_RT_MODEL_JACOBIAN_WORK, DIMS_O(accel));
        ni = W(GEN_RT_MODEL_JACOBIAN_IWORK, DIMS_O(accel));
        guard(n, ni);
        CHECK_INT(gen_rt_model_jacobian(&m, 0, states[0], r, p, work, iwork, Jx, Jr), GEN_RT_OK);
        guards_intact(n, ni);
        CHECK_NEAR(Jx[0], 0, 0);
        CHECK_NEAR(Jx[1], 1, 0);
        CHECK_NEAR(Jx[2], a, TOL(1e-15, 1e-6));
        CHECK_NEAR(Jx[3], 0, 0);
        CHECK_NEAR(Jr[0], 0, 0);
        CHECK_NEAR(Jr[1], 1 / PM, TOL(1e-15, 1e-6));
    }

    /* failures: x untouched, outputs untouched */
    {
        const gen_rt_real p0[2] = {0, PK};
        gen_rt_real Jx[4] = {7, 7, 7, 7}, Jr[2] = {7, 7};
        x[0] = GEN_RT_C(0.3); x[1] = GEN_RT_C(-0.2);
        Fx[0] = 7;
        /* a zero mass: singular */
        st = gen_rt_model_step_sensitivity(&m, 0, GEN_RT_C(0.1), r, p0, work, iwork, x, Fx, Fr);
        CHECK_INT(st, GEN_RT_ERR_SINGULAR);
        CHECK(x[0] == GEN_RT_C(0.3) && x[1] == GEN_RT_C(-0.2) && Fx[0] == 7);
        st = gen_rt_model_jacobian(&m, 0, x, r, p0, work, iwork, Jx, Jr);
        CHECK_INT(st, GEN_RT_ERR_SINGULAR);
        CHECK(Jx[0] == 7 && Jr[1] == 7);
        /* a Jacobian kernel giving NaN */
        m.lin_terms = o_lin_bad;
        x[0] = 200;
        st = gen_rt_model_jacobian(&m, 0, x, r, p, work, iwork, Jx, Jr);
        CHECK_INT(st, GEN_RT_ERR_NONFINITE_MODEL);
        CHECK(Jx[0] == 7 && Jr[1] == 7);
        st = gen_rt_model_step_sensitivity(&m, 0, GEN_RT_C(0.1), r, p, work, iwork, x, Fx, Fr);
        CHECK_INT(st, GEN_RT_ERR_NONFINITE_MODEL);
        CHECK(x[0] == 200 && Fx[0] == 7);
        /* fine below */
        x[0] = GEN_RT_C(0.3);
        st = gen_rt_model_step_sensitivity(&m, 0, GEN_RT_C(0.1), r, p, work, iwork, x, Fx, Fr);
        CHECK_INT(st, GEN_RT_OK);
    }
}

static void pendulum_tests(gen_rt_model m, const gen_rt_real *p, const char *what)
{
    const double ths[3] = {0.4, 1.1, -0.7};
    gen_rt_real x[4], Fx[4];
    int k, st, n, ni;

    for (k = 0; k < 3; ++k) {
        /* on the manifold: y and y' independent, x and x' completed */
        x[0] = GEN_RT_C(1.0);
        x[1] = (gen_rt_real)(PL * sin(ths[k]));
        x[2] = 0;
        x[3] = (gen_rt_real)(0.3 + 0.4 * k);
        st = gen_rt_model_consistent_state(&m, 0, p, 0, 0, work, iwork, x);
        CHECK_INT(st, GEN_RT_OK);
        check_jacobian(&m, 0, x, NULL, p, what);
        check_step(&m, 0, GEN_RT_C(0.05), x, NULL, p, Fx, NULL, what);
        check_step(&m, GEN_RT_C(0.3), GEN_RT_C(0.2), x, NULL, p, Fx, NULL, what);
        if (k == 0) check_small_step(&m, x, NULL, p);
        /* off the manifold (both constraints violated): the Jacobian of the
         * right-hand side is exact there too */
        x[0] += GEN_RT_C(0.15); x[1] -= GEN_RT_C(0.1); x[2] += GEN_RT_C(0.4);
        check_jacobian(&m, 0, x, NULL, p, what);
    }
    /* at the hanging state, h -> 0: Fx -> I + h [[0, 1], [-g/L, 0]] */
    {
        const gen_rt_real h = (gen_rt_real)TOL(1e-4, 1e-2);
        x[0] = PL; x[1] = 0; x[2] = 0; x[3] = 0;
        n = W(GEN_RT_MODEL_STEP_SENS_WORK, DIMS_P(m.explicit_kinematics, m.accel));
        ni = W(GEN_RT_MODEL_STEP_SENS_IWORK, DIMS_P(m.explicit_kinematics, m.accel));
        guard(n, ni);
        st = gen_rt_model_step_sensitivity(&m, 0, h, NULL, p, work, iwork, x, Fx, NULL);
        CHECK_INT(st, GEN_RT_OK);
        guards_intact(n, ni);
        if (m.explicit_kinematics) {
            CHECK_NEAR(Fx[0], 1, 10 * h * h * PG / PL);
            CHECK_NEAR(Fx[1], h, 10 * h * h * PG / PL);
            CHECK_NEAR(Fx[2], -h * PG / PL, 10 * h * h * PG / PL);
            CHECK_NEAR(Fx[3], 1, 10 * h * h * PG / PL);
        }
    }
    /* a singular partition (x = 0, Kane form): the right-hand side's status */
    if (m.accel == GEN_RT_ACCEL_PARTITIONED) {
        gen_rt_real xs[4] = {0, PL, 0, 0}, J[16];
        J[0] = 7;
        st = gen_rt_model_jacobian(&m, 0, xs, NULL, p, work, iwork, J, NULL);
        CHECK_INT(st, GEN_RT_ERR_SINGULAR);
        CHECK(J[0] == 7);
        st = gen_rt_model_step_sensitivity(&m, 0, GEN_RT_C(0.1), NULL, p, work, iwork, xs, J,
                                           NULL);
        CHECK_INT(st, GEN_RT_ERR_SINGULAR);
        CHECK(xs[0] == 0 && xs[1] == (gen_rt_real)PL && J[0] == 7);
    }
}

int main(void)
{
    const gen_rt_real pp[3] = {PM, PG, PL}, ppi[4] = {PM, PG, PL, PC};
    /* the macros are constant expressions: arrays on the stack */
    {
        gen_rt_real w1[W(GEN_RT_MODEL_JACOBIAN_WORK, DIMS_P(0, GEN_RT_ACCEL_KKT))];
        gen_rt_real w2[W(GEN_RT_MODEL_STEP_SENS_WORK, DIMS_O(GEN_RT_ACCEL_LDLT))];
        int i1[W(GEN_RT_MODEL_JACOBIAN_IWORK, DIMS_P(0, GEN_RT_ACCEL_KKT))];
        int i2[W(GEN_RT_MODEL_STEP_SENS_IWORK, DIMS_O(GEN_RT_ACCEL_LDLT))];
        CHECK(sizeof w1 > 0 && sizeof w2 > 0 && sizeof i1 > 0 && sizeof i2 > 0);
    }
    oscillator_tests(GEN_RT_ACCEL_LDLT);
    oscillator_tests(GEN_RT_ACCEL_LU);
    pendulum_tests(pend_model(GEN_RT_ACCEL_KKT), pp, "pend KKT");
    pendulum_tests(pend_model(GEN_RT_ACCEL_PARTITIONED), pp, "pend partitioned");
    pendulum_tests(pendi_model(GEN_RT_ACCEL_KKT), ppi, "pendi KKT");
    pendulum_tests(pendi_model(GEN_RT_ACCEL_PARTITIONED), ppi, "pendi partitioned");
    printf("max relative errors: jacobian vs FD %.3g, step Fx/Fr vs FD %.3g, "
           "Fx/Fr vs closed form %.3g, (Fx - I)/h vs linearize %.3g\n",
           worst_jac, worst_step, worst_closed, worst_lin);
    TEST_END();
}
