/*
 * test_qp.c - gen_rt_qp_solve (csrc/products/mpc/gen_rt_qp.c), the
 * stage-wise QP's Riccati interior point, against an independent dense
 * reference: on random QPs (time-varying dynamics, a cross term S, input
 * bounds, soft state bounds with L1 and L2 weights, hard and soft general
 * rows), the active set read off the solver's solution defines an
 * equality-constrained QP whose dense KKT system (every stage's variables
 * at once, LU with partial pivoting in double) is solved here: its
 * solution must be the solver's, its multipliers of the right signs (and
 * below the L1 weight of a soft side), the inactive sides satisfied, and
 * the objective the solver's. Then the statuses: the call errors, NaN
 * data, an indefinite input block, the iteration cap, the deadline.
 */
#include <stdlib.h>

#include "test_common.h"
#include "gen_rt_qp.h"

#define NMAX 20
#define XMAX 8
#define UMAX 3
#define GMAX 2
#define NV ((NMAX + 1) * XMAX + NMAX * UMAX)
#define NC ((NMAX + 1) * XMAX + 2 * (NMAX + 1) * (1 + UMAX + GMAX))
#define NK (NV + NC)

typedef struct {
    int N, nx, nu, nbx, nbu, ng, soft_g;
    int idxbx[1], idxbu[UMAX];
    gen_rt_real A[NMAX * XMAX * XMAX], B[NMAX * XMAX * UMAX], b[NMAX * XMAX];
    gen_rt_real Q[(NMAX + 1) * XMAX * XMAX], S[NMAX * UMAX * XMAX], R[NMAX * UMAX * UMAX];
    gen_rt_real q[(NMAX + 1) * XMAX], r[NMAX * UMAX];
    gen_rt_real lbx[NMAX + 1], ubx[NMAX + 1], lbu[NMAX * UMAX], ubu[NMAX * UMAX];
    gen_rt_real C[NMAX * GMAX * XMAX], D[NMAX * GMAX * UMAX], lg[NMAX * GMAX], ug[NMAX * GMAX];
    gen_rt_real zx[1], Zx[1], zg[GMAX], Zg[GMAX], x0[XMAX];
    gen_rt_qp qp;
} problem;

static double K[NK * NK], rhs[NK];
static int piv[NK];

static double uni(test_lcg *g) { return test_lcg_uniform(g); }

/* a random stage Hessian [Q S'; S R], positive definite in u */
static void stage_weights(test_lcg *g, int nx, int nu, gen_rt_real *Q, gen_rt_real *S,
                          gen_rt_real *R)
{
    double L[(XMAX + UMAX) * (XMAX + UMAX)], H;
    int n = nx + nu, i, j, l;
    for (i = 0; i < n * n; ++i) L[i] = 0.6 * uni(g);
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) {
            H = i == j ? (i < nx ? 0.05 : 0.3) : 0.0;
            for (l = 0; l < n; ++l) H += L[i * n + l] * L[j * n + l];
            if (i < nx && j < nx) Q[i * nx + j] = (gen_rt_real)H;
            else if (i >= nx && j < nx && S) S[(i - nx) * nx + j] = (gen_rt_real)H;
            else if (i >= nx && j >= nx) R[(i - nx) * nu + j - nx] = (gen_rt_real)H;
        }
}

static void random_qp(problem *p, test_lcg *g, int N, int nx, int nu, int ng, int soft_g)
{
    int k, i, j;
    gen_rt_real Sdummy[UMAX * XMAX];
    memset(p, 0, sizeof *p);
    p->N = N; p->nx = nx; p->nu = nu; p->nbx = 1; p->nbu = nu; p->ng = ng;
    p->soft_g = soft_g;
    p->idxbx[0] = (int)((uni(g) + 1) * 0.5 * nx) % nx;
    for (i = 0; i < nu; ++i) p->idxbu[i] = i;
    for (k = 0; k < N; ++k) {
        for (i = 0; i < nx; ++i)
            for (j = 0; j < nx; ++j)
                p->A[(k * nx + i) * nx + j] = (gen_rt_real)((i == j) + 0.25 * uni(g));
        for (i = 0; i < nx * nu; ++i) p->B[k * nx * nu + i] = (gen_rt_real)(0.5 * uni(g));
        for (i = 0; i < nx; ++i) p->b[k * nx + i] = (gen_rt_real)(0.05 * uni(g));
        stage_weights(g, nx, nu, p->Q + k * nx * nx, p->S + k * nu * nx, p->R + k * nu * nu);
        for (i = 0; i < nu; ++i) {
            p->r[k * nu + i] = (gen_rt_real)(0.1 * uni(g));
            p->lbu[k * nu + i] = (gen_rt_real)(-0.4 - 0.2 * (uni(g) + 1));
            p->ubu[k * nu + i] = (gen_rt_real)(0.4 + 0.2 * (uni(g) + 1));
        }
        for (j = 0; j < ng; ++j) {
            for (i = 0; i < nx; ++i)
                p->C[(k * ng + j) * nx + i] = soft_g ? (gen_rt_real)(0.5 * uni(g)) : 0;
            for (i = 0; i < nu; ++i) p->D[(k * ng + j) * nu + i] = (gen_rt_real)uni(g);
            p->lg[k * ng + j] = (gen_rt_real)(-0.3 - 0.2 * (uni(g) + 1));
            p->ug[k * ng + j] = (gen_rt_real)(0.3 + 0.2 * (uni(g) + 1));
        }
    }
    stage_weights(g, nx, nu, p->Q + N * nx * nx, NULL, Sdummy);
    for (k = 0; k <= N; ++k) {
        for (i = 0; i < nx; ++i) p->q[k * nx + i] = (gen_rt_real)(0.1 * uni(g));
        p->lbx[k] = (gen_rt_real)(-0.5 - 0.3 * (uni(g) + 1));
        p->ubx[k] = (gen_rt_real)(0.5 + 0.3 * (uni(g) + 1));
    }
    for (i = 0; i < nx; ++i) p->x0[i] = (gen_rt_real)(2.0 * uni(g));
    p->x0[p->idxbx[0]] = (gen_rt_real)2.0;         /* outside its soft bound */
    p->zx[0] = 5; p->Zx[0] = 0.5;
    for (j = 0; j < ng; ++j) { p->zg[j] = soft_g ? 3 : 0; p->Zg[j] = soft_g ? 0.2 : 0; }
    p->qp.N = N; p->qp.nx = nx; p->qp.nu = nu;
    p->qp.nbx = 1; p->qp.nbu = nu; p->qp.ng = ng;
    p->qp.idxbx = p->idxbx; p->qp.idxbu = p->idxbu;
    p->qp.A = p->A; p->qp.B = p->B; p->qp.b = p->b;
    p->qp.Q = p->Q; p->qp.S = p->S; p->qp.R = p->R; p->qp.q = p->q; p->qp.r = p->r;
    p->qp.lbx = p->lbx; p->qp.ubx = p->ubx; p->qp.lbu = p->lbu; p->qp.ubu = p->ubu;
    p->qp.C = p->C; p->qp.D = p->D; p->qp.lg = p->lg; p->qp.ug = p->ug;
    p->qp.zx = p->zx; p->qp.Zx = p->Zx; p->qp.zg = p->zg; p->qp.Zg = p->Zg;
    p->qp.x0 = p->x0;
}

/* LU with partial pivoting of the n x n K, then the solve of rhs; 0: ok */
static int dense_solve(int n)
{
    int i, j, l, m;
    for (j = 0; j < n; ++j) {
        double best = 0;
        m = j;
        for (i = j; i < n; ++i)
            if (fabs(K[i * n + j]) > best) { best = fabs(K[i * n + j]); m = i; }
        if (best == 0) return 1;
        piv[j] = m;
        if (m != j) {
            double t;
            for (l = 0; l < n; ++l) { t = K[j * n + l]; K[j * n + l] = K[m * n + l]; K[m * n + l] = t; }
            t = rhs[j]; rhs[j] = rhs[m]; rhs[m] = t;
        }
        for (i = j + 1; i < n; ++i) {
            double f = K[i * n + j] / K[j * n + j];
            if (f == 0) continue;
            for (l = j; l < n; ++l) K[i * n + l] -= f * K[j * n + l];
            rhs[i] -= f * rhs[j];
        }
    }
    for (i = n - 1; i >= 0; --i) {
        double s = rhs[i];
        for (l = i + 1; l < n; ++l) s -= K[i * n + l] * rhs[l];
        rhs[i] = s / K[i * n + i];
    }
    return 0;
}

/* the dense variables: w = [x_0 .. x_N, u_0 .. u_{N-1}] */
#define XI(k, i) ((k) * nx + (i))
#define UI(k, i) ((N + 1) * nx + (k) * nu + (i))

typedef struct { double a[NV]; double c; double z; int soft; } row;   /* a'w <= c */
static row rows[NC];

/* the constraint sides as rows a'w <= c (soft: z > 0, the L1 weight) */
static int sides(const problem *p, double Zw[NC])
{
    int N = p->N, nx = p->nx, nu = p->nu, ng = p->ng, n = 0, k, j, i, sg;
    for (k = 0; k <= N; ++k) {
        if (k > 0)
            for (sg = -1; sg <= 1; sg += 2) {          /* the soft state bound */
                memset(&rows[n], 0, sizeof rows[n]);
                rows[n].a[XI(k, p->idxbx[0])] = sg;
                rows[n].c = sg > 0 ? p->ubx[k] : -p->lbx[k];
                rows[n].z = p->zx[0]; Zw[n] = p->Zx[0]; rows[n].soft = 1;
                ++n;
            }
        if (k == N) break;
        for (j = 0; j < nu; ++j)
            for (sg = -1; sg <= 1; sg += 2) {
                memset(&rows[n], 0, sizeof rows[n]);
                rows[n].a[UI(k, j)] = sg;
                rows[n].c = sg > 0 ? p->ubu[k * nu + j] : -p->lbu[k * nu + j];
                Zw[n] = 0;
                ++n;
            }
        for (j = 0; j < ng; ++j)
            for (sg = -1; sg <= 1; sg += 2) {
                memset(&rows[n], 0, sizeof rows[n]);
                for (i = 0; i < nx; ++i) rows[n].a[XI(k, i)] = sg * p->C[(k * ng + j) * nx + i];
                for (i = 0; i < nu; ++i) rows[n].a[UI(k, i)] = sg * p->D[(k * ng + j) * nu + i];
                rows[n].c = sg > 0 ? p->ug[k * ng + j] : -p->lg[k * ng + j];
                rows[n].z = p->zg[j]; Zw[n] = p->Zg[j]; rows[n].soft = p->soft_g;
                ++n;
            }
    }
    return n;
}

/* the dense KKT system of the QP with the active sides as equalities and
 * the violated soft sides as their smooth penalties; returns the largest
 * difference to the solver's (x, u) relative to 1 + |w|, and checks the
 * multipliers and the inactive sides */
static double check_against_dense(const problem *p, const gen_rt_real *x, const gen_rt_real *u,
                                  double act_tol, double tol)
{
    static double Zw[NC], w[NV], H[NV * NV], gq[NV];
    int N = p->N, nx = p->nx, nu = p->nu, nv = (N + 1) * nx + N * nu;
    int ns, k, i, j, l, ne = 0, n;
    int act[NC], nact = 0;
    double diff = 0, wmax = 1;
    for (k = 0; k <= N; ++k)
        for (i = 0; i < nx; ++i) w[XI(k, i)] = x[k * nx + i];
    for (k = 0; k < N; ++k)
        for (i = 0; i < nu; ++i) w[UI(k, i)] = u[k * nu + i];
    for (i = 0; i < nv; ++i) wmax = fabs(w[i]) > wmax ? fabs(w[i]) : wmax;
    memset(H, 0, sizeof H);
    memset(gq, 0, sizeof gq);
    for (k = 0; k <= N; ++k) {
        for (i = 0; i < nx; ++i) {
            gq[XI(k, i)] = p->q[k * nx + i];
            for (j = 0; j < nx; ++j) H[XI(k, i) * NV + XI(k, j)] = p->Q[(k * nx + i) * nx + j];
        }
        if (k == N) break;
        for (i = 0; i < nu; ++i) {
            gq[UI(k, i)] = p->r[k * nu + i];
            for (j = 0; j < nu; ++j) H[UI(k, i) * NV + UI(k, j)] = p->R[(k * nu + i) * nu + j];
            for (j = 0; j < nx; ++j) {
                H[UI(k, i) * NV + XI(k, j)] = p->S[(k * nu + i) * nx + j];
                H[XI(k, j) * NV + UI(k, i)] = p->S[(k * nu + i) * nx + j];
            }
        }
    }
    ns = sides(p, Zw);
    for (i = 0; i < ns; ++i) {
        double v = -rows[i].c;
        for (l = 0; l < nv; ++l) v += rows[i].a[l] * w[l];
        if (rows[i].soft && v > act_tol) {
            /* violated soft side: z v + Z/2 v^2 */
            for (l = 0; l < nv; ++l) {
                if (rows[i].a[l] == 0) continue;
                gq[l] += (rows[i].z - Zw[i] * rows[i].c) * rows[i].a[l];
                for (j = 0; j < nv; ++j) H[l * NV + j] += Zw[i] * rows[i].a[l] * rows[i].a[j];
            }
        } else if (v > -act_tol) {
            act[nact++] = i;
        } else {
            CHECK(v <= 0);
        }
        CHECK(rows[i].soft || v <= act_tol);
    }
    /* equalities: x_0 = x0, the dynamics, the active sides */
    ne = nx + N * nx + nact;
    n = nv + ne;
    CHECK(n <= NK);
    if (n > NK) return 1e300;
    memset(K, 0, sizeof(double) * (size_t)n * (size_t)n);
    for (i = 0; i < nv; ++i) {
        for (j = 0; j < nv; ++j) K[i * n + j] = H[i * NV + j];
        rhs[i] = -gq[i];
    }
#define EQ(r, col, val) (K[(nv + (r)) * n + (col)] = (val), K[(col) * n + nv + (r)] = (val))
    for (i = 0; i < nx; ++i) { EQ(i, XI(0, i), 1.0); rhs[nv + i] = p->x0[i]; }
    for (k = 0; k < N; ++k)
        for (i = 0; i < nx; ++i) {
            int r = nx + k * nx + i;
            EQ(r, XI(k + 1, i), 1.0);
            for (j = 0; j < nx; ++j) EQ(r, XI(k, j), -p->A[(k * nx + i) * nx + j]);
            for (j = 0; j < nu; ++j) EQ(r, UI(k, j), -p->B[(k * nx + i) * nu + j]);
            rhs[nv + r] = p->b[k * nx + i];
        }
    for (i = 0; i < nact; ++i) {
        int r = nx + N * nx + i;
        for (l = 0; l < nv; ++l)
            if (rows[act[i]].a[l] != 0) EQ(r, l, rows[act[i]].a[l]);
        rhs[nv + r] = rows[act[i]].c;
    }
#undef EQ
    CHECK_INT(dense_solve(n), 0);
    for (i = 0; i < nv; ++i)
        diff = fabs(rhs[i] - w[i]) > diff ? fabs(rhs[i] - w[i]) : diff;
    /* the multipliers of a'w <= c: >= 0, and <= z on a soft side */
    for (i = 0; i < nact; ++i) {
        double lam = rhs[nv + nx + N * nx + i];
        CHECK(lam >= -tol * 100 * wmax);
        if (rows[act[i]].soft) CHECK(lam <= rows[act[i]].z + tol * 100 * wmax);
    }
    return diff / wmax;
}

static void test_random_qps(void)
{
    static problem p;
    static gen_rt_real work[GEN_RT_QP_WORK(NMAX, XMAX, UMAX, 1, UMAX, GMAX)];
    gen_rt_real x[(NMAX + 1) * XMAX], u[NMAX * UMAX];
    gen_rt_qp_options opt;
    gen_rt_qp_stats stats;
    test_lcg g = {12345};
    int t, active_u = 0, singular = 0;
    double worst = 0;
    for (t = 0; t < 24; ++t) {
        int N = 3 + t % 18, nx = 2 + t % 7, nu = 1 + t % 3, ng = t % 3, soft = t % 2, st, k;
        double d, obj;
        random_qp(&p, &g, N, nx, nu, ng, soft);
        CHECK_INT(gen_rt_qp_work_len(N, nx, nu, 1, nu, ng),
                  GEN_RT_QP_WORK(N, nx, nu, 1, nu, ng));
        gen_rt_qp_options_default(&opt);
        st = gen_rt_qp_solve(&p.qp, &opt, work, x, u, &stats);
        if (st != GEN_RT_OK) {
            printf("QP %d (N %d, nx %d, nu %d, ng %d): status %d\n", t, N, nx, nu, ng, st);
            /* float: a Riccati pivot of the inputs lost to rounding under
             * the sides' large weights (the status says so) in at most one */
            CHECK(TEST_IS_FLOAT && st == GEN_RT_MPC_ERR_QP_SINGULAR && ++singular <= 1);
            continue;
        }
        for (k = 0; k < N * nu; ++k)
            active_u += fabs(u[k] - p.ubu[k]) < 1e-6 || fabs(u[k] - p.lbu[k]) < 1e-6;
        d = check_against_dense(&p, x, u, TOL(1e-7, 1e-3), TOL(1e-8, 1e-3));
        worst = d > worst ? d : worst;
        CHECK_NEAR(d, 0.0, TOL(1e-8, 2e-3));
        obj = (double)gen_rt_qp_objective(&p.qp, x, u);
        CHECK_NEAR(stats.objective, obj, 1e-12 * (1 + fabs(obj)) + TOL(0, 1e-3 * fabs(obj)));
        CHECK(stats.iterations >= 1 && stats.iterations <= opt.max_iter);
    }
    CHECK(active_u > 24);             /* the input bounds are active */
    printf("random QPs: largest |w - w_dense| / (1 + |w|) = %.2e\n", worst);
}

static double late_clock(void *ctx)
{
    (void)ctx;
    return 1e9;
}

static void test_statuses(void)
{
    static problem p;
    static gen_rt_real work[GEN_RT_QP_WORK(NMAX, XMAX, UMAX, 1, UMAX, GMAX)];
    gen_rt_real x[(NMAX + 1) * XMAX], u[NMAX * UMAX], keep;
    gen_rt_qp_options opt;
    test_lcg g = {777};
    int i;
    random_qp(&p, &g, 10, 4, 2, 1, 1);
    gen_rt_qp_options_default(&opt);
    CHECK_INT(gen_rt_qp_solve(NULL, &opt, work, x, u, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_qp_solve(&p.qp, NULL, work, x, u, NULL), GEN_RT_ERR_NULL);
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, NULL, x, u, NULL), GEN_RT_ERR_NULL);
    /* sizes, an index out of range, a negative weight */
    p.qp.N = 0;
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, work, x, u, NULL), GEN_RT_ERR_BAD_ARG);
    p.qp.N = 10;
    p.idxbu[1] = 5;
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, work, x, u, NULL), GEN_RT_ERR_BAD_ARG);
    p.idxbu[1] = 1;
    p.zx[0] = -1;
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, work, x, u, NULL), GEN_RT_ERR_BAD_ARG);
    p.zx[0] = 5;
    /* NaN data */
    keep = p.A[3];
    p.A[3] = (gen_rt_real)NAN;
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, work, x, u, NULL), GEN_RT_MPC_ERR_QP_NONFINITE);
    p.A[3] = keep;
    /* an input block that is not positive definite */
    for (i = 0; i < 10 * 4; ++i) p.R[i] = (gen_rt_real)(i % 4 == 0 || i % 4 == 3 ? -100 : 0);
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, work, x, u, NULL), GEN_RT_MPC_ERR_QP_SINGULAR);
    random_qp(&p, &g, 10, 4, 2, 1, 1);
    /* the iteration cap: the iterate is kept, finite */
    opt.max_iter = 1;
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, work, x, u, NULL), GEN_RT_MPC_ERR_QP_MAX_ITER);
    for (i = 0; i < 10 * 2; ++i) CHECK(u[i] - u[i] == 0);
    /* the deadline passed */
    gen_rt_qp_options_default(&opt);
    opt.clock = late_clock;
    opt.deadline = 1.0;
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, work, x, u, NULL), GEN_RT_MPC_TIME_LIMIT);
    for (i = 0; i < 10 * 2; ++i) CHECK(u[i] - u[i] == 0);
    /* solved again without either: converged */
    gen_rt_qp_options_default(&opt);
    CHECK_INT(gen_rt_qp_solve(&p.qp, &opt, work, x, u, NULL), GEN_RT_OK);
}

int main(void)
{
    test_random_qps();
    test_statuses();
    TEST_END();
}
