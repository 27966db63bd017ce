/*
 * gen_rt_mpc.c - real-time iterations over a model's step (gen_rt_mpc.h).
 *
 * The iterate is the full states X (N + 1 rows of nx) and the inputs U (N
 * rows of nr); the QP is in the steps of the independent states dX (ns per
 * node) and of the inputs dU, about the iterate:
 *   dX_{k+1} = A_k dX_k + B_k dU_k + b_k,  A_k, B_k the sensitivities of
 *   the interval's steps, b_k = F(X_k, U_k)_ind - X_{k+1,ind} (the gap),
 *   dX_0 = x_ind - X_{0,ind} (the new state against the prepared one).
 * Its Hessian is the cost's Gauss-Newton one (2 period Q, ...; 2 P at the
 * end), its gradient the cost's at the iterate; the bounds and the path
 * constraints are shifted (lbu - U_k, ...) and linearized about it.
 */
#include "gen_rt_mpc.h"

/* real: once, when gen_rt_qp.c and gen_rt_mpc.c are one unit (a
 * standalone program's <name>_loop.c) */
#ifndef GEN_RT_MPC_REAL_TYPEDEF_
#define GEN_RT_MPC_REAL_TYPEDEF_
typedef gen_rt_real real;
#endif

/* ---- the work array ----------------------------------------------------- */

typedef struct {
    real *X, *U;                        /* the iterate */
    real *A, *B, *b, *Q, *S, *R, *q, *r;  /* the QP */
    real *lbx, *ubx, *lbu, *ubu, *C, *D, *lg, *ug;
    real *dX, *dU, *dx0;                /* its solution, its initial step */
    real *qpw;                          /* its solver's work */
    real *xs, *xe, *Fx, *Fr, *Gx, *Gr, *Hs, *ev, *xr, *ur, *uf;   /* temporaries */
} mpc_ws;

static real *mpc_take(real **w, int n)
{
    real *r = *w;
    *w += n;
    return r;
}

/* the pieces of work; returns the reals used */
static int mpc_layout(const gen_rt_mpc_problem *pb, real *w, mpc_ws *ws)
{
    int N = pb->N, S = N + 1, nx = pb->nx, ns = pb->ns, nr = pb->nr, nh = pb->nh;
    int ne = (nh > pb->ny ? nh : pb->ny) * (1 + ns + nr);
    real *w0 = w;
    ws->X = mpc_take(&w, S * nx); ws->U = mpc_take(&w, S * nr);
    ws->A = mpc_take(&w, S * ns * ns); ws->B = mpc_take(&w, S * ns * nr); ws->b = mpc_take(&w, S * ns);
    ws->Q = mpc_take(&w, S * ns * ns); ws->S = mpc_take(&w, S * nr * ns); ws->R = mpc_take(&w, S * nr * nr);
    ws->q = mpc_take(&w, S * ns); ws->r = mpc_take(&w, S * nr);
    ws->lbx = mpc_take(&w, S * pb->nbx); ws->ubx = mpc_take(&w, S * pb->nbx);
    ws->lbu = mpc_take(&w, S * pb->nbu); ws->ubu = mpc_take(&w, S * pb->nbu);
    ws->C = mpc_take(&w, S * nh * ns); ws->D = mpc_take(&w, S * nh * nr);
    ws->lg = mpc_take(&w, S * nh); ws->ug = mpc_take(&w, S * nh);
    ws->dX = mpc_take(&w, S * ns); ws->dU = mpc_take(&w, S * nr);
    ws->xs = mpc_take(&w, nx); ws->xe = mpc_take(&w, nx); ws->dx0 = mpc_take(&w, nx);
    ws->Fx = mpc_take(&w, ns * ns); ws->Fr = mpc_take(&w, ns * nr);
    ws->Gx = mpc_take(&w, ns * ns); ws->Gr = mpc_take(&w, ns * nr); ws->Hs = mpc_take(&w, ns * (ns + nr));
    ws->ev = mpc_take(&w, ne > 0 ? ne : 1);
    ws->xr = mpc_take(&w, ns); ws->ur = mpc_take(&w, nr); ws->uf = mpc_take(&w, nr);
    ws->qpw = mpc_take(&w, GEN_RT_QP_WORK(N, ns, nr, pb->nbx, pb->nbu, nh));
    return (int)(w - w0);
}

int gen_rt_mpc_work_len(const gen_rt_mpc_problem *pb)
{
    return GEN_RT_MPC_WORK(pb->nx, pb->ns, pb->nr, pb->N, pb->nbx, pb->nbu, pb->nh, pb->ny);
}

void gen_rt_mpc_init(gen_rt_mpc_state *st)
{
    gen_rt_qp_options qo;
    gen_rt_qp_options_default(&qo);
    st->sqp = 0;
    st->max_iter = 1;
#ifdef GEN_RT_REAL_FLOAT
    st->tol = GEN_RT_C(1e-4);
#else
    st->tol = GEN_RT_C(1e-8);
#endif
    st->time_limit = 0;
    st->qp_max_iter = qo.max_iter;
    st->qp_tol = qo.tol;
    st->clock = 0;
    st->clock_ctx = 0;
    st->has_iterate = 0;
    st->shift = 0;
    st->prepared = 0;
    st->t_prepared = 0;
    st->status = GEN_RT_OK;
    st->qp_status = GEN_RT_OK;
    st->iterations = 0;
    st->qp_iterations = 0;
    st->t_prepare = 0;
    st->t_feedback = 0;
    st->objective = 0;
}

/* ---- helpers ------------------------------------------------------------ */

static int finite(int n, const real *v)
{
    int i;
    for (i = 0; i < n; ++i)
        if (!(v[i] - v[i] == 0)) return 0;
    return 1;
}

static void copy(int n, const real *a, real *b)
{
    int i;
    for (i = 0; i < n; ++i) b[i] = a[i];
}

static void zero(int n, real *a)
{
    int i;
    for (i = 0; i < n; ++i) a[i] = 0;
}

static double now(const gen_rt_mpc_state *st)
{
    return st->clock ? st->clock(st->clock_ctx) : 0.0;
}

/* the reference at time tau: xr (ns), ur (nr); linear between rows */
static void reference(const gen_rt_mpc_problem *pb, real tau, real *xr, real *ur)
{
    int ns = pb->ns, nr = pb->nr, i0 = 0, j;
    real f = 0;
    if (pb->n_ref > 1) {
        real s = (tau - pb->t_ref) / pb->dt_ref;
        if (s >= (real)(pb->n_ref - 1)) {
            i0 = pb->n_ref - 1;
        } else if (s > 0) {
            i0 = (int)s;
            f = s - (real)i0;
        }
    }
    for (j = 0; j < ns; ++j) {
        const real *row = pb->x_ref + i0 * ns;
        xr[j] = f > 0 ? (1 - f) * row[j] + f * row[ns + j] : row[j];
    }
    for (j = 0; j < nr; ++j) {
        const real *row = pb->u_ref + i0 * nr;
        ur[j] = f > 0 ? (1 - f) * row[j] + f * row[nr + j] : row[j];
    }
}

/* u clipped to the input bounds */
static void clip(const gen_rt_mpc_problem *pb, real *u)
{
    int i;
    for (i = 0; i < pb->nbu; ++i) {
        real *v = u + pb->idxbu[i];
        if (*v < pb->lbu[i]) *v = pb->lbu[i];
        if (*v > pb->ubu[i]) *v = pb->ubu[i];
    }
}

/* the interval k's steps from X_k with U_k: xe (the state at its end), Gx,
 * Gr (its sensitivities, composed over the substeps) */
static int interval(const gen_rt_mpc_problem *pb, mpc_ws *ws, real t, int k)
{
    int nx = pb->nx, ns = pb->ns, nr = pb->nr, j, a, b, l, st;
    real h = pb->period / (real)pb->substeps;
    const real *u = ws->U + k * nr;
    copy(nx, ws->X + k * nx, ws->xe);
    for (j = 0; j < pb->substeps; ++j) {
        real *Fx = j ? ws->Fx : ws->Gx, *Fr = j ? ws->Fr : ws->Gr;
        st = pb->step(pb->ctx, t + (real)j * h, h, u, ws->xe, Fx, Fr);
        if (st) return st;
        if (j == 0) continue;
        /* G = F G: [Gx, Gr] <- Fx [Gx, Gr] + [0, Fr], through Hs */
        for (a = 0; a < ns; ++a)
            for (b = 0; b < ns + nr; ++b) {
                real sum = b < ns ? 0 : Fr[a * nr + b - ns];
                for (l = 0; l < ns; ++l)
                    sum += Fx[a * ns + l] * (b < ns ? ws->Gx[l * ns + b] : ws->Gr[l * nr + b - ns]);
                ws->Hs[a * (ns + nr) + b] = sum;
            }
        for (a = 0; a < ns; ++a) {
            copy(ns, ws->Hs + a * (ns + nr), ws->Gx + a * ns);
            copy(nr, ws->Hs + a * (ns + nr) + ns, ws->Gr + a * nr);
        }
    }
    return GEN_RT_OK;
}

/* ---- the preparation phase ------------------------------------------------ */

/* the cost's Gauss-Newton blocks and gradient of stage k (k < N) at the
 * iterate, with the reference at tau */
static int stage_cost(const gen_rt_mpc_problem *pb, mpc_ws *ws, real tau, int k)
{
    int ns = pb->ns, nr = pb->nr, a, b, i, st;
    const real *x = ws->X + k * pb->nx, *u = ws->U + k * nr;
    real c = 2 * pb->period;
    real *Q = ws->Q + k * ns * ns, *R = ws->R + k * nr * nr, *S = ws->S + k * nr * ns;
    real *q = ws->q + k * ns, *r = ws->r + k * nr;
    reference(pb, tau, ws->xr, ws->ur);
    for (a = 0; a < ns; ++a) ws->xs[a] = x[pb->ind[a]] - ws->xr[a];
    for (a = 0; a < ns; ++a) {
        real g = 0;
        for (b = 0; b < ns; ++b) {
            Q[a * ns + b] = c * pb->Q[a * ns + b];
            g += pb->Q[a * ns + b] * ws->xs[b];
        }
        q[a] = c * g;
    }
    for (a = 0; a < nr; ++a) {
        real g = 0;
        for (b = 0; b < nr; ++b) {
            R[a * nr + b] = c * pb->R[a * nr + b];
            g += pb->R[a * nr + b] * (u[b] - ws->ur[b]);
        }
        r[a] = c * g;
    }
    zero(nr * ns, S);
    if (pb->ny == 0) return GEN_RT_OK;
    if ((st = pb->residuals(pb->ctx, tau, x, u, ws->ev))) return st;
    if (!finite(pb->ny * (1 + ns + nr), ws->ev)) return GEN_RT_ERR_NONFINITE_MODEL;
    for (i = 0; i < pb->ny; ++i) {
        const real *row = ws->ev + i * (1 + ns + nr), *Yx = row + 1, *Yr = row + 1 + ns;
        real w = c * pb->W[i];
        for (a = 0; a < ns; ++a) {
            for (b = 0; b < ns; ++b) Q[a * ns + b] += w * Yx[a] * Yx[b];
            q[a] += w * row[0] * Yx[a];
        }
        for (a = 0; a < nr; ++a) {
            for (b = 0; b < nr; ++b) R[a * nr + b] += w * Yr[a] * Yr[b];
            for (b = 0; b < ns; ++b) S[a * ns + b] += w * Yr[a] * Yx[b];
            r[a] += w * row[0] * Yr[a];
        }
    }
    return GEN_RT_OK;
}

/* the terminal cost's blocks at the iterate, the reference at tau */
static void terminal_cost(const gen_rt_mpc_problem *pb, mpc_ws *ws, real tau)
{
    int ns = pb->ns, N = pb->N, a, b;
    const real *x = ws->X + N * pb->nx;
    real *Q = ws->Q + N * ns * ns, *q = ws->q + N * ns;
    reference(pb, tau, ws->xr, ws->ur);
    for (a = 0; a < ns; ++a) ws->xs[a] = x[pb->ind[a]] - ws->xr[a];
    for (a = 0; a < ns; ++a) {
        real g = 0;
        for (b = 0; b < ns; ++b) {
            Q[a * ns + b] = 2 * pb->P[a * ns + b];
            g += pb->P[a * ns + b] * ws->xs[b];
        }
        q[a] = 2 * g;
    }
}

/* the bounds and path constraints of stage k about the iterate */
static int stage_constraints(const gen_rt_mpc_problem *pb, mpc_ws *ws, real tau, int k)
{
    int ns = pb->ns, nr = pb->nr, nh = pb->nh, i, st;
    const real *x = ws->X + k * pb->nx, *u = ws->U + k * nr;
    for (i = 0; i < pb->nbx; ++i) {
        real v = x[pb->ind[pb->idxbx[i]]];
        ws->lbx[k * pb->nbx + i] = pb->lbx[i] - v;
        ws->ubx[k * pb->nbx + i] = pb->ubx[i] - v;
    }
    if (k == pb->N) return GEN_RT_OK;
    for (i = 0; i < pb->nbu; ++i) {
        real v = u[pb->idxbu[i]];
        ws->lbu[k * pb->nbu + i] = pb->lbu[i] - v;
        ws->ubu[k * pb->nbu + i] = pb->ubu[i] - v;
    }
    if (nh == 0) return GEN_RT_OK;
    if ((st = pb->path(pb->ctx, tau, x, u, ws->ev))) return st;
    if (!finite(nh * (1 + ns + nr), ws->ev)) return GEN_RT_ERR_NONFINITE_MODEL;
    for (i = 0; i < nh; ++i) {
        const real *row = ws->ev + i * (1 + ns + nr);
        copy(ns, row + 1, ws->C + (k * nh + i) * ns);
        copy(nr, row + 1 + ns, ws->D + (k * nh + i) * nr);
        ws->lg[k * nh + i] = pb->lh[i] - row[0];
        ws->ug[k * nh + i] = pb->uh[i] - row[0];
    }
    return GEN_RT_OK;
}

/* the iterate shifted by one interval, the last repeated */
static void shift(const gen_rt_mpc_problem *pb, mpc_ws *ws)
{
    int N = pb->N, nx = pb->nx, nr = pb->nr, k;
    for (k = 0; k < N; ++k) copy(nx, ws->X + (k + 1) * nx, ws->X + k * nx);
    for (k = 0; k + 1 < N; ++k) copy(nr, ws->U + (k + 1) * nr, ws->U + k * nr);
}

static int prepare_(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st, real t, mpc_ws *ws)
{
    int N = pb->N, nx = pb->nx, ns = pb->ns, k, i, s;
    double t0 = now(st);
    if (!st->has_iterate) {
        zero((N + 1) * nx, ws->X);
        zero(N * pb->nr, ws->U);
        st->has_iterate = 1;
    } else if (st->shift) {
        shift(pb, ws);
    }
    st->shift = 0;
    st->prepared = 0;
    for (k = 0; k <= N && pb->complete; ++k)
        if ((s = pb->complete(pb->ctx, t + (real)k * pb->period, ws->X + k * nx))) return s;
    for (k = 0; k < N; ++k) {
        real tk = t + (real)k * pb->period;
        if ((s = interval(pb, ws, tk, k))) return s;
        copy(ns * ns, ws->Gx, ws->A + k * ns * ns);
        copy(ns * pb->nr, ws->Gr, ws->B + k * ns * pb->nr);
        for (i = 0; i < ns; ++i)
            ws->b[k * ns + i] = ws->xe[pb->ind[i]] - ws->X[(k + 1) * nx + pb->ind[i]];
        if ((s = stage_cost(pb, ws, tk, k))) return s;
        if ((s = stage_constraints(pb, ws, tk, k))) return s;
    }
    terminal_cost(pb, ws, t + (real)N * pb->period);
    stage_constraints(pb, ws, t + (real)N * pb->period, N);
    st->prepared = 1;
    st->t_prepared = t;
    st->t_prepare += now(st) - t0;
    return GEN_RT_OK;
}

int gen_rt_mpc_prepare(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st, gen_rt_real t,
                       gen_rt_real *work)
{
    mpc_ws ws;
    int s;
    if (!pb || !st || !work) return GEN_RT_ERR_NULL;
    if (!(t - t == 0)) return GEN_RT_ERR_NONFINITE_INPUT;
    mpc_layout(pb, work, &ws);
    st->t_prepare = 0;
    s = prepare_(pb, st, t, &ws);
    if (s) st->has_iterate = 0;    /* a failed preparation leaves no iterate to build on */
    return s;
}

/* ---- the feedback phase ----------------------------------------------------- */

/* the fallback control: the iterate's first input (the previous solution,
 * shifted: its second when the shift is pending), else the reference's,
 * clipped */
static void fallback(const gen_rt_mpc_problem *pb, const gen_rt_mpc_state *st, mpc_ws *ws,
                     real t, real *u)
{
    const real *u0 = ws->U + (st->shift && pb->N > 1 ? pb->nr : 0);
    if (st->has_iterate && finite(pb->nr, u0)) {
        copy(pb->nr, u0, u);
    } else {
        reference(pb, t, ws->xr, ws->ur);
        copy(pb->nr, ws->ur, u);
    }
    clip(pb, u);
    if (!finite(pb->nr, u)) zero(pb->nr, u);
}

/* the QP at the prepared iterate with the initial step dx0, solved; the
 * iterate updated (partial: a time-limited QP's last iterate may be taken) */
static int feedback_(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st, const real *x,
                     mpc_ws *ws, double deadline, int partial, real *u)
{
    int N = pb->N, nx = pb->nx, ns = pb->ns, nr = pb->nr, k, i, s;
    gen_rt_qp qp;
    gen_rt_qp_options qo;
    gen_rt_qp_stats qs;
    double t0 = now(st);
    /* a call error of the QP leaves its stats unwritten */
    qs.iterations = 0;
    qs.res_stat = qs.res_ineq = qs.mu = qs.objective = 0;
    for (i = 0; i < ns; ++i) ws->dx0[i] = x[pb->ind[i]] - ws->X[pb->ind[i]];
    qp.N = N; qp.nx = ns; qp.nu = nr;
    qp.nbx = pb->nbx; qp.nbu = pb->nbu; qp.ng = pb->nh;
    qp.idxbx = pb->idxbx; qp.idxbu = pb->idxbu;
    qp.A = ws->A; qp.B = ws->B; qp.b = ws->b;
    qp.Q = ws->Q; qp.S = pb->ny ? ws->S : 0; qp.R = ws->R; qp.q = ws->q; qp.r = ws->r;
    qp.lbx = ws->lbx; qp.ubx = ws->ubx; qp.lbu = ws->lbu; qp.ubu = ws->ubu;
    qp.C = ws->C; qp.D = ws->D; qp.lg = ws->lg; qp.ug = ws->ug;
    qp.zx = pb->zx; qp.Zx = 0; qp.zg = pb->zh; qp.Zg = 0;
    qp.x0 = ws->dx0;
    qo.max_iter = st->qp_max_iter;
    qo.tol = st->qp_tol;
    qo.clock = deadline > 0 ? st->clock : 0;
    qo.clock_ctx = st->clock_ctx;
    qo.deadline = deadline;
    s = gen_rt_qp_solve(&qp, &qo, ws->qpw, ws->dX, ws->dU, &qs);
    st->qp_status = s;
    st->qp_iterations += qs.iterations;
    st->objective = qs.objective;
    if (s == GEN_RT_OK || (s == GEN_RT_MPC_TIME_LIMIT && partial)) {
        copy(nx, x, ws->X);
        for (k = 1; k <= N; ++k)
            for (i = 0; i < ns; ++i) ws->X[k * nx + pb->ind[i]] += ws->dX[k * ns + i];
        for (k = 0; k < N * nr; ++k) ws->U[k] += ws->dU[k];
        copy(nr, ws->U, u);
        clip(pb, u);
    }
    st->t_feedback += now(st) - t0;
    return s;
}

int gen_rt_mpc_feedback(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st,
                        const gen_rt_real *x, gen_rt_real *work, gen_rt_real *u)
{
    mpc_ws ws;
    int s;
    double deadline = 0;
    if (!pb || !st || !x || !work || !u) return GEN_RT_ERR_NULL;
    mpc_layout(pb, work, &ws);
    fallback(pb, st, &ws, st->t_prepared, ws.uf);
    copy(pb->nr, ws.uf, u);
    st->t_feedback = 0;
    st->qp_iterations = 0;
    if (!finite(pb->nx, x)) return st->status = GEN_RT_ERR_NONFINITE_INPUT;
    if (!st->prepared) return st->status = GEN_RT_ERR_BAD_ARG;
    if (st->time_limit > 0) {
        if (!st->clock) return st->status = GEN_RT_MPC_ERR_NO_CLOCK;
        deadline = now(st) + st->time_limit;
    }
    s = feedback_(pb, st, x, &ws, deadline, 1, u);
    st->prepared = 0;
    st->shift = 1;
    st->iterations = 1;
    if (s < 0 || !finite(pb->nr, u)) copy(pb->nr, ws.uf, u);
    return st->status = s;
}

/* the step's largest entry against the iterate's (sqp's convergence test) */
static int converged(const gen_rt_mpc_problem *pb, const gen_rt_mpc_state *st, mpc_ws *ws)
{
    int N = pb->N, k;
    real dmax = 0, xmax = 0;
    for (k = 0; k < (N + 1) * pb->ns; ++k)
        if ((ws->dX[k] < 0 ? -ws->dX[k] : ws->dX[k]) > dmax) dmax = ws->dX[k] < 0 ? -ws->dX[k] : ws->dX[k];
    for (k = 0; k < N * pb->nr; ++k)
        if ((ws->dU[k] < 0 ? -ws->dU[k] : ws->dU[k]) > dmax) dmax = ws->dU[k] < 0 ? -ws->dU[k] : ws->dU[k];
    for (k = 0; k < (N + 1) * pb->nx; ++k)
        if ((ws->X[k] < 0 ? -ws->X[k] : ws->X[k]) > xmax) xmax = ws->X[k] < 0 ? -ws->X[k] : ws->X[k];
    for (k = 0; k < N * pb->nr; ++k)
        if ((ws->U[k] < 0 ? -ws->U[k] : ws->U[k]) > xmax) xmax = ws->U[k] < 0 ? -ws->U[k] : ws->U[k];
    return dmax <= st->tol * (1 + xmax);
}

/* a first iterate for a constrained model (zero is not one of its
 * states): the measured state at every node, the reference's inputs */
static void start_at(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st, mpc_ws *ws, real t,
                     const real *x)
{
    int k;
    for (k = 0; k <= pb->N; ++k) copy(pb->nx, x, ws->X + k * pb->nx);
    for (k = 0; k < pb->N; ++k) {
        reference(pb, t + (real)k * pb->period, ws->xr, ws->ur);
        copy(pb->nr, ws->ur, ws->U + k * pb->nr);
    }
    st->has_iterate = 1;
    st->shift = 0;
}

int gen_rt_mpc_step(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st, gen_rt_real t,
                    const gen_rt_real *x, gen_rt_real *work, gen_rt_real *u)
{
    mpc_ws ws;
    int s = GEN_RT_OK, it, iters;
    double deadline = 0;
    if (!pb || !st || !x || !work || !u) return GEN_RT_ERR_NULL;
    mpc_layout(pb, work, &ws);
    st->iterations = 0;
    st->qp_iterations = 0;
    st->t_feedback = 0;
    fallback(pb, st, &ws, t, ws.uf);
    copy(pb->nr, ws.uf, u);
    if (!(t - t == 0) || !finite(pb->nx, x)) return st->status = GEN_RT_ERR_NONFINITE_INPUT;
    if (st->time_limit > 0) {
        if (!st->clock) return st->status = GEN_RT_MPC_ERR_NO_CLOCK;
        deadline = now(st) + st->time_limit;
    }
    if (!st->has_iterate && pb->complete) start_at(pb, st, &ws, t, x);
    if (!(st->prepared && st->t_prepared == t)) {
        st->t_prepare = 0;
        if ((s = prepare_(pb, st, t, &ws))) {
            st->has_iterate = 0;
            return st->status = s;
        }
    }
    iters = st->sqp ? (st->max_iter > 0 ? st->max_iter : 1) : 1;
    for (it = 0; it < iters; ++it) {
        if (it > 0) {
            if (deadline > 0 && now(st) >= deadline) {
                s = GEN_RT_MPC_TIME_LIMIT;
                break;
            }
            st->shift = 0;
            if ((s = prepare_(pb, st, t, &ws))) break;
        }
        s = feedback_(pb, st, x, &ws, deadline, it == 0, u);
        st->prepared = 0;
        if (s == GEN_RT_OK) ++st->iterations;
        if (s != GEN_RT_OK) break;
        /* sqp: converged on a small step; else its last iteration's control */
        if (st->sqp && converged(pb, st, &ws)) break;
        if (st->sqp && it == iters - 1) s = GEN_RT_MPC_MAX_ITER;
    }
    if (s == GEN_RT_MPC_TIME_LIMIT && st->iterations == 0) st->iterations = 1;
    st->shift = 1;
    if (s < 0) {
        /* the last good control: the first iteration's fallback, or the
         * previous iteration's solution */
        if (st->iterations == 0) copy(pb->nr, ws.uf, u);
        else {
            copy(pb->nr, ws.U, u);
            clip(pb, u);
        }
        if (!finite(pb->nr, ws.U) || !finite(pb->nx, ws.X)) st->has_iterate = 0;
    }
    if (!finite(pb->nr, u)) copy(pb->nr, ws.uf, u);
    return st->status = s;
}

int gen_rt_mpc_set_guess(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st,
                         gen_rt_real *work, const gen_rt_real *x, const gen_rt_real *u)
{
    mpc_ws ws;
    if (!pb || !st || !work) return GEN_RT_ERR_NULL;
    mpc_layout(pb, work, &ws);
    if ((x && !finite((pb->N + 1) * pb->nx, x)) || (u && !finite(pb->N * pb->nr, u)))
        return GEN_RT_ERR_NONFINITE_INPUT;
    if (x) copy((pb->N + 1) * pb->nx, x, ws.X);
    else zero((pb->N + 1) * pb->nx, ws.X);
    if (u) copy(pb->N * pb->nr, u, ws.U);
    else zero(pb->N * pb->nr, ws.U);
    st->has_iterate = 1;
    st->shift = 0;
    st->prepared = 0;
    return GEN_RT_OK;
}

int gen_rt_mpc_solution(const gen_rt_mpc_problem *pb, const gen_rt_mpc_state *st,
                        const gen_rt_real *work, gen_rt_real *x, gen_rt_real *u)
{
    int k, s;
    if (!pb || !st || !work) return GEN_RT_ERR_NULL;
    /* X and U lead the work array (layout) */
    if (u) copy(pb->N * pb->nr, work + (pb->N + 1) * pb->nx, u);
    if (!x) return GEN_RT_OK;
    copy((pb->N + 1) * pb->nx, work, x);
    /* a constrained model: the QP moved the independent entries only, the
     * dependent ones follow (the next preparation does the same) */
    for (k = 1; k <= pb->N && pb->complete && st->has_iterate; ++k)
        if ((s = pb->complete(pb->ctx, st->t_prepared + (real)k * pb->period, x + k * pb->nx)))
            return s;
    return GEN_RT_OK;
}

const char *gen_rt_mpc_status_message(int status)
{
    switch (status) {
#define GEN_RT_MPC_STATUS_CASE_(name, value, text) case GEN_RT_MPC_##name: return text;
    GEN_RT_MPC_STATUS_TABLE(GEN_RT_MPC_STATUS_CASE_)
#undef GEN_RT_MPC_STATUS_CASE_
    default: return gen_rt_status_message(status);
    }
}
