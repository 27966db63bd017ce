/*
 * gen_rt_qp.c - the stage-wise QP's interior point method (gen_rt_qp.h).
 *
 * Notation, for one constraint side (two per row: the lower bound, sigma =
 * +1, and the upper, sigma = -1) with row a (a unit vector for a bound) and
 * bound d: its value c = sigma (a'z - d) (+ s, its slack variable, when
 * soft) must be >= 0; t >= 0 is c's slack (c - t = rd, the residual), lam
 * its multiplier, and for a soft side ls the multiplier of s >= 0, with
 * rs = Z s + zpen - lam - ls. Linearizing t lam = mu and s ls = mu and
 * eliminating dt, dlam, ds, dls leaves, per side, a weight
 *     what = w1 (Z + w2) / G   (hard: w1),   w1 = lam/t, w2 = ls/s,
 *     G = Z + w1 + w2,
 * on a a' in the Hessian, and the step's LQ problem (its gradient the
 * stationarity residual rz, its dynamics' affine term their residual)
 * gets -a sigma kappa in its gradient,
 *     beta  = (-rs + rc1/t - w1 rd + rc2/s) / G,
 *     kappa = rc1/t - w1 (beta + rd)   (hard: rc1/t - w1 rd),
 * rc1, rc2 the complementarity targets (predictor: -t lam, -s ls;
 * corrector: sigma_c mu - t lam - dt_a dlam_a, likewise). From dz:
 *     ds = beta - (w1/G) sigma a'dz, dt = sigma a'dz + ds + rd,
 *     dlam = kappa - what sigma a'dz, dls = (rc2 - ls ds) / s.
 */
#include <math.h>

#include "gen_rt_qp.h"

/* real: once, when gen_rt_qp.c and gen_rt_mpc.c are one unit (a
 * standalone program's <name>_loop.c) */
#ifndef GEN_RT_MPC_REAL_TYPEDEF_
#define GEN_RT_MPC_REAL_TYPEDEF_
typedef gen_rt_real real;
#endif

/* the scalar type's square root (float: sqrtf, no double on a single-
 * precision FPU) */
#ifdef GEN_RT_REAL_FLOAT
#define QP_SQRT sqrtf
#else
#define QP_SQRT sqrt
#endif

/* ---- small dense helpers (row-major) ------------------------------------ */

static void vcopy(int n, const real *a, real *b)
{
    int i;
    for (i = 0; i < n; ++i) b[i] = a[i];
}

static void vzero(int n, real *a)
{
    int i;
    for (i = 0; i < n; ++i) a[i] = 0;
}

static int vfinite(int n, const real *a)
{
    int i;
    for (i = 0; i < n; ++i)
        if (!(a[i] - a[i] == 0)) return 0;
    return 1;
}

static real vmaxabs(int n, const real *a)
{
    int i;
    real m = 0;
    for (i = 0; i < n; ++i) {
        real v = a[i] < 0 ? -a[i] : a[i];
        if (v > m) m = v;
    }
    return m;
}

static real rabs(real a) { return a < 0 ? -a : a; }

/* y = A x (A: n x m), or y += A x when acc */
static void mv(int n, int m, const real *A, const real *x, real *y, int acc)
{
    int i, j;
    for (i = 0; i < n; ++i) {
        real s = acc ? y[i] : 0;
        const real *a = A + i * m;
        for (j = 0; j < m; ++j) s += a[j] * x[j];
        y[i] = s;
    }
}

/* y += A' x (A: n x m, y: m) */
static void mtv(int n, int m, const real *A, const real *x, real *y)
{
    int i, j;
    for (i = 0; i < n; ++i) {
        const real *a = A + i * m;
        real xi = x[i];
        if (xi == 0) continue;
        for (j = 0; j < m; ++j) y[j] += a[j] * xi;
    }
}

/* X = L^-1 X (L: n x n lower, X: n x m) */
static void trsm_l(int n, int m, const real *L, real *X)
{
    int i, j, k;
    for (i = 0; i < n; ++i) {
        real d = L[i * n + i];
        for (k = 0; k < i; ++k) {
            real l = L[i * n + k];
            if (l == 0) continue;
            for (j = 0; j < m; ++j) X[i * m + j] -= l * X[k * m + j];
        }
        for (j = 0; j < m; ++j) X[i * m + j] /= d;
    }
}

/* x = L'^-1 x (L: n x n lower) */
static void trsv_lt(int n, const real *L, real *x)
{
    int i, k;
    for (i = n - 1; i >= 0; --i) {
        real s = x[i];
        for (k = i + 1; k < n; ++k) s -= L[k * n + i] * x[k];
        x[i] = s / L[i * n + i];
    }
}

/* ---- the layout of the work array ---------------------------------------- */

typedef struct {
    const gen_rt_qp *qp;
    int N, nx, nu, nbx, nbu, ng, ms, M;
    /* per stage (N + 1 blocks) */
    real *x, *u, *xp, *up, *pi, *pip, *P, *p, *L, *K, *kt, *gx, *gu, *gv, *rzx, *rzu, *nrb;
    real *rgx, *rgu, *cx, *cu, *cpi;
    /* per side (M = (N + 1) ms) */
    real *t, *lam, *s, *ls, *dt, *dlam, *ds, *dls, *what, *beta, *cs, *kap, *bd, *on, *rd, *rs;
    /* temporaries */
    real *Hxx, *Hux, *Huu, *W, *BA, *Pb, *tx, *tx2, *tu, *tu2;
} qp_ws;

static real *take(real **w, int n)
{
    real *r = *w;
    *w += n;
    return r;
}

static void layout(qp_ws *ws, int N, int nx, int nu, int nbx, int nbu, int ng, real *w)
{
    int S = N + 1, M;
    ws->N = N; ws->nx = nx; ws->nu = nu; ws->nbx = nbx; ws->nbu = nbu; ws->ng = ng;
    ws->ms = GEN_RT_QP_SIDES_(nbx, nbu, ng);
    ws->M = M = S * ws->ms;
    ws->x = take(&w, S * nx); ws->xp = take(&w, S * nx); ws->pi = take(&w, S * nx);
    ws->pip = take(&w, S * nx); ws->p = take(&w, S * nx); ws->gx = take(&w, S * nx);
    ws->rzx = take(&w, S * nx); ws->nrb = take(&w, S * nx); ws->rzu = take(&w, S * nu);
    ws->rgx = take(&w, S * nx); ws->cx = take(&w, S * nx); ws->cpi = take(&w, S * nx);
    ws->rgu = take(&w, S * nu); ws->cu = take(&w, S * nu);
    ws->P = take(&w, S * nx * nx);
    ws->u = take(&w, S * nu); ws->up = take(&w, S * nu); ws->kt = take(&w, S * nu);
    ws->gu = take(&w, S * nu);
    ws->L = take(&w, S * nu * nu); ws->K = take(&w, S * nu * nx); ws->gv = take(&w, S * ng);
    ws->t = take(&w, M); ws->lam = take(&w, M); ws->s = take(&w, M); ws->ls = take(&w, M);
    ws->dt = take(&w, M); ws->dlam = take(&w, M); ws->ds = take(&w, M); ws->dls = take(&w, M);
    ws->what = take(&w, M); ws->beta = take(&w, M); ws->cs = take(&w, M);
    ws->kap = take(&w, M); ws->bd = take(&w, M); ws->on = take(&w, M);
    ws->rd = take(&w, M); ws->rs = take(&w, M);
    ws->Hxx = take(&w, nx * nx); ws->Hux = take(&w, nu * nx); ws->Huu = take(&w, nu * nu);
    ws->W = take(&w, (nu + nx) * (nu + nx)); ws->BA = take(&w, nx * (nu + nx));
    ws->Pb = take(&w, nx); ws->tx = take(&w, nx); ws->tx2 = take(&w, nx);
    ws->tu = take(&w, nu); ws->tu2 = take(&w, nu);
}

int gen_rt_qp_work_len(int N, int nx, int nu, int nbx, int nbu, int ng)
{
    return GEN_RT_QP_WORK(N, nx, nu, nbx, nbu, ng);
}

void gen_rt_qp_options_default(gen_rt_qp_options *opt)
{
    opt->max_iter = 100;
#ifdef GEN_RT_REAL_FLOAT
    opt->tol = GEN_RT_C(1e-5);
#else
    opt->tol = GEN_RT_C(1e-10);
#endif
    opt->clock = 0;
    opt->clock_ctx = 0;
    opt->deadline = 0;
}

/* ---- the constraint sides ------------------------------------------------- */

/* kinds of the sides of a stage, in order: 2 nbu input bounds, 2 nbx state
 * bounds, 2 ng general rows; side j of a kind is row j/2, lower when even */
enum { SIDE_U, SIDE_X, SIDE_G };

static int side_kind(const qp_ws *ws, int j, int *row)
{
    if (j < 2 * ws->nbu) {
        *row = j / 2;
        return SIDE_U;
    }
    j -= 2 * ws->nbu;
    if (j < 2 * ws->nbx) {
        *row = j / 2;
        return SIDE_X;
    }
    *row = (j - 2 * ws->nbx) / 2;
    return SIDE_G;
}

/* the soft weights of a side (zpen 0: hard) */
static void side_weights(const qp_ws *ws, int kind, int row, real *zpen, real *Zpen)
{
    const gen_rt_qp *qp = ws->qp;
    *zpen = 0;
    *Zpen = 0;
    if (kind == SIDE_X && qp->zx) {
        *zpen = qp->zx[row];
        *Zpen = qp->Zx ? qp->Zx[row] : 0;
    } else if (kind == SIDE_G && qp->zg) {
        *zpen = qp->zg[row];
        *Zpen = qp->Zg ? qp->Zg[row] : 0;
    }
}

/* the soft weights of side i (of any stage) */
static void side_soft(const qp_ws *ws, int i, real *zpen, real *Zpen)
{
    int row, kind = side_kind(ws, i % ws->ms, &row);
    side_weights(ws, kind, row, zpen, Zpen);
}

/* the general rows' values C x + D u of stage k into ws->gv */
static void general_values(const qp_ws *ws, int k, const real *x, const real *u, real *gv)
{
    const gen_rt_qp *qp = ws->qp;
    int ng = ws->ng, nx = ws->nx, nu = ws->nu;
    if (ng == 0 || k >= ws->N) return;
    mv(ng, nx, qp->C + k * ng * nx, x, gv, 0);
    mv(ng, nu, qp->D + k * ng * nu, u, gv, 1);
}

/* the value a'z of side j of stage k (gv: the stage's general values) */
static real side_value(const qp_ws *ws, int kind, int row, const real *x, const real *u,
                       const real *gv)
{
    if (kind == SIDE_U) return u[ws->qp->idxbu[row]];
    if (kind == SIDE_X) return x[ws->qp->idxbx[row]];
    return gv[row];
}

/* the bounds and on flags of every side; GEN_RT_ERR_BAD_ARG on lb > ub,
 * GEN_RT_MPC_ERR_QP_NONFINITE on a NaN bound */
static int sides_setup(qp_ws *ws)
{
    const gen_rt_qp *qp = ws->qp;
    int k, j, row, kind;
    for (k = 0; k <= ws->N; ++k) {
        for (j = 0; j < ws->ms; j += 2) {
            real lo, hi;
            int i = k * ws->ms + j, valid;
            kind = side_kind(ws, j, &row);
            if (kind == SIDE_U) {
                valid = k < ws->N;
                lo = valid ? qp->lbu[k * ws->nbu + row] : 0;
                hi = valid ? qp->ubu[k * ws->nbu + row] : 0;
            } else if (kind == SIDE_X) {
                valid = k > 0;
                lo = valid ? qp->lbx[k * ws->nbx + row] : 0;
                hi = valid ? qp->ubx[k * ws->nbx + row] : 0;
            } else {
                valid = k < ws->N;
                lo = valid ? qp->lg[k * ws->ng + row] : 0;
                hi = valid ? qp->ug[k * ws->ng + row] : 0;
            }
            if (lo != lo || hi != hi) return GEN_RT_MPC_ERR_QP_NONFINITE;
            if (valid && lo > hi) return GEN_RT_ERR_BAD_ARG;
            ws->bd[i] = lo;
            ws->bd[i + 1] = hi;
            ws->on[i] = (real)(valid && lo > -GEN_RT_QP_INF);
            ws->on[i + 1] = (real)(valid && hi < GEN_RT_QP_INF);
        }
    }
    return GEN_RT_OK;
}

/* ---- residuals ------------------------------------------------------------- */

typedef struct {
    real stat, ineq, soft, mu;
    int m;                      /* complementarity pairs: on sides + their slacks */
} qp_res;

/* rd and rs of every side, the stationarity residual (inf-norm) and mu */
static void residuals(qp_ws *ws, qp_res *res)
{
    const gen_rt_qp *qp = ws->qp;
    int N = ws->N, nx = ws->nx, nu = ws->nu, ng = ws->ng, k, j, row, kind;
    real stat = 0, ineq = 0, soft = 0, comp = 0;
    int m = 0;
    for (k = 0; k <= N; ++k) {
        const real *x = ws->x + k * nx, *u = ws->u + k * nu;
        real *gv = ws->gv + k * ng, *ru = ws->rzu + k * nu, *rx = ws->rzx + k * nx;
        general_values(ws, k, x, u, gv);
        /* the dynamics' residual, negated: -(x_{k+1} - A x_k - B u_k - b_k) */
        if (k < N) {
            real *nrb = ws->nrb + k * nx;
            vcopy(nx, qp->b + k * nx, nrb);
            mv(nx, nx, qp->A + k * nx * nx, x, nrb, 1);
            mv(nx, nu, qp->B + k * nx * nu, u, nrb, 1);
            for (j = 0; j < nx; ++j) nrb[j] -= x[nx + j];
        }
        /* the cost's and the dynamics' part */
        if (k < N) {
            mv(nu, nu, qp->R + k * nu * nu, u, ru, 0);
            if (qp->S) mv(nu, nx, qp->S + k * nu * nx, x, ru, 1);
            for (j = 0; j < nu; ++j) ru[j] += qp->r[k * nu + j];
            mtv(nx, nu, qp->B + k * nx * nu, ws->pi + k * nx, ru);
        }
        mv(nx, nx, qp->Q + k * nx * nx, x, rx, 0);
        for (j = 0; j < nx; ++j) rx[j] += qp->q[k * nx + j];
        if (k < N) {
            if (qp->S) mtv(nu, nx, qp->S + k * nu * nx, u, rx);
            mtv(nx, nx, qp->A + k * nx * nx, ws->pi + k * nx, rx);
        }
        if (k > 0)
            for (j = 0; j < nx; ++j) rx[j] -= ws->pi[(k - 1) * nx + j];
        /* the sides */
        for (j = 0; j < ws->ms; ++j) {
            int i = k * ws->ms + j;
            real sg = (j & 1) ? GEN_RT_C(-1.0) : GEN_RT_C(1.0), v, c, zp, Zp, sl;
            if (ws->on[i] == 0) continue;
            kind = side_kind(ws, j, &row);
            side_weights(ws, kind, row, &zp, &Zp);
            v = side_value(ws, kind, row, x, u, gv);
            c = sg * (v - ws->bd[i]);
            sl = sg * ws->lam[i];
            if (kind == SIDE_U) ru[qp->idxbu[row]] -= sl;
            else if (kind == SIDE_X) rx[qp->idxbx[row]] -= sl;
            else {
                int l;
                const real *Ci = qp->C + (k * ng + row) * nx, *Di = qp->D + (k * ng + row) * nu;
                for (l = 0; l < nx; ++l) rx[l] -= sl * Ci[l];
                for (l = 0; l < nu; ++l) ru[l] -= sl * Di[l];
            }
            if (zp > 0) {
                c += ws->s[i];
                ws->rs[i] = Zp * ws->s[i] + zp - ws->lam[i] - ws->ls[i];
                if (rabs(ws->rs[i]) > soft) soft = rabs(ws->rs[i]);
                comp += ws->s[i] * ws->ls[i];
                ++m;
            }
            ws->rd[i] = c - ws->t[i];
            if (rabs(ws->rd[i]) > ineq) ineq = rabs(ws->rd[i]);
            comp += ws->t[i] * ws->lam[i];
            ++m;
        }
        if (k < N && vmaxabs(nu, ru) > stat) stat = vmaxabs(nu, ru);
        if (k > 0 && vmaxabs(nx, rx) > stat) stat = vmaxabs(nx, rx);
    }
    res->stat = stat;
    res->ineq = ineq;
    res->soft = soft;
    res->m = m;
    res->mu = m ? comp / (real)m : 0;
}

/* ---- the Newton system ------------------------------------------------------ */

/* the eliminations' weights of every side */
static void side_elimination(qp_ws *ws)
{
    int i;
    for (i = 0; i < ws->M; ++i) {
        real w1, zp, Zp;
        if (ws->on[i] == 0) continue;
        side_soft(ws, i, &zp, &Zp);
        w1 = ws->lam[i] / ws->t[i];
        if (zp > 0) {
            real w2 = ws->ls[i] / ws->s[i], G = Zp + w1 + w2;
            ws->what[i] = w1 * (Zp + w2) / G;
            ws->cs[i] = w1 / G;
        } else {
            ws->what[i] = w1;
            ws->cs[i] = 0;
        }
    }
}

/* the stage's Hessian blocks with the sides' weights: Hxx, Hux, Huu */
static void stage_hessian(qp_ws *ws, int k)
{
    const gen_rt_qp *qp = ws->qp;
    int nx = ws->nx, nu = ws->nu, ng = ws->ng, j, row, kind, a, b;
    vcopy(nx * nx, qp->Q + k * nx * nx, ws->Hxx);
    if (k < ws->N) {
        vcopy(nu * nu, qp->R + k * nu * nu, ws->Huu);
        if (qp->S) vcopy(nu * nx, qp->S + k * nu * nx, ws->Hux);
        else vzero(nu * nx, ws->Hux);
    }
    for (j = 0; j < ws->ms; ++j) {
        int i = k * ws->ms + j;
        real w = ws->what[i];
        if (ws->on[i] == 0) continue;
        kind = side_kind(ws, j, &row);
        if (kind == SIDE_U) {
            int c = qp->idxbu[row];
            ws->Huu[c * nu + c] += w;
        } else if (kind == SIDE_X) {
            int c = qp->idxbx[row];
            ws->Hxx[c * nx + c] += w;
        } else {
            const real *Ci = qp->C + (k * ng + row) * nx, *Di = qp->D + (k * ng + row) * nu;
            for (a = 0; a < nx; ++a) {
                real wa = w * Ci[a];
                if (wa == 0) continue;
                for (b = 0; b < nx; ++b) ws->Hxx[a * nx + b] += wa * Ci[b];
            }
            for (a = 0; a < nu; ++a) {
                real wa = w * Di[a];
                if (wa == 0) continue;
                for (b = 0; b < nu; ++b) ws->Huu[a * nu + b] += wa * Di[b];
                for (b = 0; b < nx; ++b) ws->Hux[a * nx + b] += wa * Ci[b];
            }
        }
    }
}

/* the Cholesky factor of the first ncol columns of W (n x n, its lower
 * triangle, in place): a pivot of the first nstrict columns that is not
 * positive is an error (-1); a later one at most eps times its diagonal
 * (a direction the cost-to-go has lost to rounding) gives a zero column */
static int chol_cols(int n, int ncol, int nstrict, real *W)
{
    int i, j, k;
    for (j = 0; j < ncol; ++j) {
        real d0 = W[j * n + j], d = d0;
        for (k = 0; k < j; ++k) d -= W[j * n + k] * W[j * n + k];
        if (j < nstrict ? !(d > 0) : !(d > GEN_RT_EPS * (d0 > 0 ? d0 : 0))) {
            if (j < nstrict) return -1;
            for (i = j; i < n; ++i) W[i * n + j] = 0;
            continue;
        }
        d = QP_SQRT(d);
        W[j * n + j] = d;
        for (i = j + 1; i < n; ++i) {
            real sum = W[i * n + j];
            for (k = 0; k < j; ++k) sum -= W[i * n + k] * W[j * n + k];
            W[i * n + j] = sum / d;
        }
    }
    return 0;
}

/* the backward Riccati factorization in its square-root form (HPIPM's):
 * with P_{k+1} = Lp Lp' and M = Lp' [B A], the stage matrix
 *     [Ruu Sux; Sux' Qxx] = [Huu Hux; Hux' Hxx] + M'M = L L'
 * gives L_k (its inputs' block), K_k = L_k^-1 Sux (the transpose of its
 * lower-left block) and Lp_k (its states' block): P_k = Lp_k Lp_k' stays
 * positive semidefinite however large the sides' weights grow */
static int factorize(qp_ws *ws)
{
    const gen_rt_qp *qp = ws->qp;
    int N = ws->N, nx = ws->nx, nu = ws->nu, nz = nx + nu, k, a, b, l, i;
    real *W = ws->W, *M = ws->BA;
    stage_hessian(ws, N);
    vcopy(nx * nx, ws->Hxx, W);
    if (chol_cols(nx, nx, 0, W)) return GEN_RT_MPC_ERR_QP_SINGULAR;
    vcopy(nx * nx, W, ws->P + N * nx * nx);
    for (k = N - 1; k >= 0; --k) {
        const real *A = qp->A + k * nx * nx, *B = qp->B + k * nx * nu;
        const real *Lp = ws->P + (k + 1) * nx * nx;
        real *L = ws->L + k * nu * nu, *K = ws->K + k * nu * nx;
        stage_hessian(ws, k);
        /* M = Lp' [B A] (Lp lower: Lp'[a][l] = Lp[l][a], l >= a), row by
         * row of [B A]: the inner loops run along contiguous rows */
        for (i = 0; i < nx * nz; ++i) M[i] = 0;
        for (l = 0; l < nx; ++l) {
            const real *Bl = B + l * nu, *Al = A + l * nx;
            for (a = 0; a <= l; ++a) {
                real c = Lp[l * nx + a], *Ma = M + a * nz;
                for (b = 0; b < nu; ++b) Ma[b] += c * Bl[b];
                for (b = 0; b < nx; ++b) Ma[nu + b] += c * Al[b];
            }
        }
        /* W = [Huu Hux; Hux' Hxx] + M'M, the lower triangle, accumulated
         * over M's rows */
        for (a = 0; a < nz; ++a)
            for (b = 0; b <= a; ++b)
                W[a * nz + b] = a < nu ? ws->Huu[a * nu + b]
                                : b < nu ? ws->Hux[b * nx + a - nu]
                                : ws->Hxx[(a - nu) * nx + b - nu];
        for (l = 0; l < nx; ++l) {
            const real *Ml = M + l * nz;
            for (a = 0; a < nz; ++a) {
                real c = Ml[a], *Wa = W + a * nz;
                for (b = 0; b <= a; ++b) Wa[b] += c * Ml[b];
            }
        }
        if (chol_cols(nz, k > 0 ? nz : nu, nu, W)) return GEN_RT_MPC_ERR_QP_SINGULAR;
        for (a = 0; a < nu; ++a)
            for (b = 0; b < nu; ++b) L[a * nu + b] = b <= a ? W[a * nz + b] : 0;
        for (a = 0; a < nu; ++a)
            for (b = 0; b < nx; ++b) K[a * nx + b] = W[(nu + b) * nz + a];
        if (k > 0) {
            real *Lpk = ws->P + k * nx * nx;
            for (a = 0; a < nx; ++a)
                for (b = 0; b < nx; ++b) Lpk[a * nx + b] = b <= a ? W[(nu + a) * nz + nu + b] : 0;
        }
    }
    return vfinite((N + 1) * nx * nx, ws->P) && vfinite(N * nu * nx, ws->K)
               ? GEN_RT_OK : GEN_RT_MPC_ERR_QP_NONFINITE;
}

/* y = P v + y0 with P = Lp Lp' (Lp: nx x nx lower), tmp: nx reals */
static void pmul(int nx, const real *Lp, const real *v, const real *y0, real *tmp, real *y)
{
    int a, l;
    /* tmp = Lp' v, along Lp's rows */
    for (a = 0; a < nx; ++a) tmp[a] = 0;
    for (l = 0; l < nx; ++l) {
        const real *row = Lp + l * nx;
        real vl = v[l];
        for (a = 0; a <= l; ++a) tmp[a] += row[a] * vl;
    }
    for (a = 0; a < nx; ++a) {
        real sum = y0[a];
        for (l = 0; l <= a; ++l) sum += Lp[a * nx + l] * tmp[l];
        y[a] = sum;
    }
}

/* the complementarity targets of side i: mode 0 (predictor) or 1 (corrector
 * with the affine steps in dt, dlam, ds, dls and the target smu) */
static void targets(const qp_ws *ws, int i, int mode, real smu, real *rc1, real *rc2)
{
    *rc1 = -ws->t[i] * ws->lam[i];
    *rc2 = -ws->s[i] * ws->ls[i];
    if (mode) {
        *rc1 += smu - ws->dt[i] * ws->dlam[i];
        *rc2 += smu - ws->ds[i] * ws->dls[i];
    }
}

/* beta and kappa of every side, and the gradients gx, gu of the step's LQ
 * problem: rz - sum of a sigma kappa */
static void lq_gradient(qp_ws *ws, int mode, real smu)
{
    const gen_rt_qp *qp = ws->qp;
    int N = ws->N, nx = ws->nx, nu = ws->nu, ng = ws->ng, k, j, row, kind, l;
    for (k = 0; k <= N; ++k) {
        real *gx = ws->gx + k * nx, *gu = ws->gu + k * nu;
        vcopy(nx, ws->rzx + k * nx, gx);
        if (k < N) vcopy(nu, ws->rzu + k * nu, gu);
        for (j = 0; j < ws->ms; ++j) {
            int i = k * ws->ms + j;
            real sg = (j & 1) ? GEN_RT_C(-1.0) : GEN_RT_C(1.0), rc1, rc2, zp, Zp, w1, cf;
            if (ws->on[i] == 0) continue;
            kind = side_kind(ws, j, &row);
            side_weights(ws, kind, row, &zp, &Zp);
            targets(ws, i, mode, smu, &rc1, &rc2);
            w1 = ws->lam[i] / ws->t[i];
            if (zp > 0) {
                real G = Zp + w1 + ws->ls[i] / ws->s[i];
                ws->beta[i] = (-ws->rs[i] + rc1 / ws->t[i] - w1 * ws->rd[i] +
                               rc2 / ws->s[i]) / G;
                ws->kap[i] = rc1 / ws->t[i] - w1 * (ws->beta[i] + ws->rd[i]);
            } else {
                ws->beta[i] = 0;
                ws->kap[i] = rc1 / ws->t[i] - w1 * ws->rd[i];
            }
            /* the step's LQ gradient: rz - a sigma kappa */
            cf = -sg * ws->kap[i];
            if (kind == SIDE_U) gu[qp->idxbu[row]] += cf;
            else if (kind == SIDE_X) gx[qp->idxbx[row]] += cf;
            else {
                const real *Ci = qp->C + (k * ng + row) * nx, *Di = qp->D + (k * ng + row) * nu;
                for (l = 0; l < nx; ++l) gx[l] += cf * Ci[l];
                for (l = 0; l < nu; ++l) gu[l] += cf * Di[l];
            }
        }
    }
}

/* the step's LQ problem solved from the factorization and gradients gxv,
 * guv (dynamics' affine term nrb, NULL: zero):
 * the backward vector pass, then the forward sweep from dx_0 = 0 into
 * dx, du and the dynamics' multipliers' step dpi (the affine term of
 * the step's dynamics: their residual, negated) */
static void lq_pass(qp_ws *ws, const real *gxv, const real *guv, const real *nrb, real *dx,
                    real *du, real *dpi)
{
    const gen_rt_qp *qp = ws->qp;
    int N = ws->N, nx = ws->nx, nu = ws->nu, k, j;
    vcopy(nx, gxv + N * nx, ws->p + N * nx);
    for (k = N - 1; k >= 0; --k) {
        const real *A = qp->A + k * nx * nx, *B = qp->B + k * nx * nu;
        const real *Lp1 = ws->P + (k + 1) * nx * nx, *p1 = ws->p + (k + 1) * nx;
        const real *L = ws->L + k * nu * nu, *K = ws->K + k * nu * nx;
        real *kt = ws->kt + k * nu;
        if (nrb) pmul(nx, Lp1, nrb + k * nx, p1, ws->tx2, ws->Pb);   /* P b + p */
        else vcopy(nx, p1, ws->Pb);
        vcopy(nu, guv + k * nu, kt);
        mtv(nx, nu, B, ws->Pb, kt);                       /* ru = gu + B'(P b + p) */
        trsm_l(nu, 1, L, kt);                             /* kt = L^-1 ru */
        if (k > 0) {
            real *p = ws->p + k * nx;
            vcopy(nx, gxv + k * nx, p);
            mtv(nx, nx, A, ws->Pb, p);                    /* qx = gx + A'(P b + p) */
            for (j = 0; j < nu; ++j) {
                int l;
                for (l = 0; l < nx; ++l) p[l] -= K[j * nx + l] * kt[j];
            }
        }
    }
    vzero(nx, dx);                                        /* dx_0 = 0 */
    for (k = 0; k < N; ++k) {
        const real *A = qp->A + k * nx * nx, *B = qp->B + k * nx * nu;
        const real *xk = dx + k * nx;
        real *uk = du + k * nu, *x1 = dx + (k + 1) * nx;
        /* u = -L'^-1 (K x + kt) */
        vcopy(nu, ws->kt + k * nu, uk);
        mv(nu, nx, ws->K + k * nu * nx, xk, uk, 1);
        for (j = 0; j < nu; ++j) uk[j] = -uk[j];
        trsv_lt(nu, ws->L + k * nu * nu, uk);
        if (nrb) vcopy(nx, nrb + k * nx, x1);
        else vzero(nx, x1);
        mv(nx, nx, A, xk, x1, 1);
        mv(nx, nu, B, uk, x1, 1);
        /* pi_k = P_{k+1} x_{k+1} + p_{k+1} */
        pmul(nx, ws->P + (k + 1) * nx * nx, x1, ws->p + (k + 1) * nx, ws->tx2, dpi + k * nx);
    }
}

/* the residual of the LQ problem's stationarity at (dx, du, dpi): into
 * rgx, rgu; returns its inf-norm relative to the gradient's */
static real lq_residual(qp_ws *ws, real *rgx, real *rgu)
{
    const gen_rt_qp *qp = ws->qp;
    int N = ws->N, nx = ws->nx, nu = ws->nu, k, j;
    real rmax = 0, gmax = 0;
    for (k = 0; k <= N; ++k) {
        const real *dx = ws->xp + k * nx, *du = ws->up + k * nu;
        real *rx = rgx + k * nx, *ru = rgu + k * nu;
        stage_hessian(ws, k);
        vcopy(nx, ws->gx + k * nx, rx);
        mv(nx, nx, ws->Hxx, dx, rx, 1);
        if (k < N) {
            vcopy(nu, ws->gu + k * nu, ru);
            mv(nu, nu, ws->Huu, du, ru, 1);
            mv(nu, nx, ws->Hux, dx, ru, 1);
            mtv(nu, nx, ws->Hux, du, rx);
            mtv(nx, nu, qp->B + k * nx * nu, ws->pip + k * nx, ru);
            mtv(nx, nx, qp->A + k * nx * nx, ws->pip + k * nx, rx);
            if (vmaxabs(nu, ru) > rmax) rmax = vmaxabs(nu, ru);
            if (vmaxabs(nu, ws->gu + k * nu) > gmax) gmax = vmaxabs(nu, ws->gu + k * nu);
        }
        if (k > 0) {
            for (j = 0; j < nx; ++j) rx[j] -= ws->pip[(k - 1) * nx + j];
            if (vmaxabs(nx, rx) > rmax) rmax = vmaxabs(nx, rx);
            if (vmaxabs(nx, ws->gx + k * nx) > gmax) gmax = vmaxabs(nx, ws->gx + k * nx);
        }
    }
    return rmax / (gmax > 0 ? gmax : 1);
}

/* the step's LQ problem solved (lq_pass), then refined: when a side's
 * weight is large (an active side near the solution, GEN_RT_QP_REFINE
 * times the Hessian's scale), the factorization's rounding (a general
 * row's rank-one weight cancels in the Cholesky pivots) leaves a residual,
 * solved again with the same factors, at most twice */
static void lq_solve(qp_ws *ws, real wbig)
{
    int n = (ws->N + 1), it, k;
    real wmax = 0;
    lq_pass(ws, ws->gx, ws->gu, ws->nrb, ws->xp, ws->up, ws->pip);
    for (k = 0; k < ws->M; ++k)
        if (ws->on[k] != 0 && ws->what[k] > wmax) wmax = ws->what[k];
    if (!(wmax > wbig)) return;
    for (it = 0; it < 2; ++it) {
        if (!(lq_residual(ws, ws->rgx, ws->rgu) > GEN_RT_EPS)) return;
        lq_pass(ws, ws->rgx, ws->rgu, 0, ws->cx, ws->cu, ws->cpi);
        for (k = 0; k < n * ws->nx; ++k) {
            ws->xp[k] += ws->cx[k];
            ws->pip[k] += ws->cpi[k];
        }
        for (k = 0; k < n * ws->nu; ++k) ws->up[k] += ws->cu[k];
    }
}

/* the steps of the sides from dz (mode and smu as for lq_gradient);
 * returns the largest step in (0, 1] keeping t, lam, s, ls >= 0 */
static real side_steps(qp_ws *ws, int mode, real smu)
{
    const gen_rt_qp *qp = ws->qp;
    int N = ws->N, nx = ws->nx, nu = ws->nu, ng = ws->ng, k, j, row, kind;
    real amax = 1;
    for (k = 0; k <= N; ++k) {
        const real *xp = ws->xp + k * nx, *up = ws->up + k * nu;
        for (j = 0; j < ws->ms; ++j) {
            int i = k * ws->ms + j;
            real sg = (j & 1) ? GEN_RT_C(-1.0) : GEN_RT_C(1.0), dv, zp, Zp, rc1, rc2;
            if (ws->on[i] == 0) continue;
            kind = side_kind(ws, j, &row);
            side_weights(ws, kind, row, &zp, &Zp);
            if (kind == SIDE_U) dv = up[qp->idxbu[row]];
            else if (kind == SIDE_X) dv = xp[qp->idxbx[row]];
            else {
                const real *Ci = qp->C + (k * ng + row) * nx, *Di = qp->D + (k * ng + row) * nu;
                int l;
                dv = 0;
                for (l = 0; l < nx; ++l) dv += Ci[l] * xp[l];
                for (l = 0; l < nu; ++l) dv += Di[l] * up[l];
            }
            dv *= sg;
            targets(ws, i, mode, smu, &rc1, &rc2);
            (void)rc1;
            if (zp > 0) {
                ws->ds[i] = ws->beta[i] - ws->cs[i] * dv;
                ws->dls[i] = (rc2 - ws->ls[i] * ws->ds[i]) / ws->s[i];
                ws->dt[i] = dv + ws->ds[i] + ws->rd[i];
                if (ws->ds[i] < 0 && -ws->s[i] / ws->ds[i] < amax) amax = -ws->s[i] / ws->ds[i];
                if (ws->dls[i] < 0 && -ws->ls[i] / ws->dls[i] < amax)
                    amax = -ws->ls[i] / ws->dls[i];
            } else {
                ws->dt[i] = dv + ws->rd[i];
            }
            ws->dlam[i] = ws->kap[i] - ws->what[i] * dv;
            if (ws->dt[i] < 0 && -ws->t[i] / ws->dt[i] < amax) amax = -ws->t[i] / ws->dt[i];
            if (ws->dlam[i] < 0 && -ws->lam[i] / ws->dlam[i] < amax)
                amax = -ws->lam[i] / ws->dlam[i];
        }
    }
    return amax;
}

/* the mean complementarity after a step alpha along the steps */
static real mu_after(const qp_ws *ws, real alpha, int m)
{
    int i;
    real comp = 0, zp, Zp;
    if (m == 0) return 0;
    for (i = 0; i < ws->M; ++i) {
        if (ws->on[i] == 0) continue;
        comp += (ws->t[i] + alpha * ws->dt[i]) * (ws->lam[i] + alpha * ws->dlam[i]);
        side_soft(ws, i, &zp, &Zp);
        if (zp > 0) comp += (ws->s[i] + alpha * ws->ds[i]) * (ws->ls[i] + alpha * ws->dls[i]);
    }
    return comp / (real)m;
}

/* ---- the iteration ----------------------------------------------------------- */

/* the starting point: u inside its hard bounds, x from the dynamics, the
 * sides' slacks at least thr, lam = mu0 / t */
static void start(qp_ws *ws)
{
    const gen_rt_qp *qp = ws->qp;
    int N = ws->N, nx = ws->nx, nu = ws->nu, ng = ws->ng, k, j, row, kind;
    const real thr = GEN_RT_C(0.1), mu0 = GEN_RT_C(1.0);
    vzero((N + 1) * nu, ws->u);
    vzero((N + 1) * nx, ws->pi);
    vcopy(nx, qp->x0, ws->x);
    for (k = 0; k < N; ++k) {
        real *u = ws->u + k * nu, *x1 = ws->x + (k + 1) * nx;
        for (j = 0; j < ws->nbu; ++j) {
            int i = k * ws->ms + 2 * j, c = qp->idxbu[j];
            real lo = ws->bd[i], hi = ws->bd[i + 1], v = 0;
            int onl = ws->on[i] != 0, onh = ws->on[i + 1] != 0;
            if (onl && onh && hi - lo < 4 * thr) v = GEN_RT_C(0.5) * (lo + hi);
            else if (onl && v < lo + thr) v = lo + thr;
            else if (onh && v > hi - thr) v = hi - thr;
            u[c] = v;
        }
        vcopy(nx, qp->b + k * nx, x1);
        mv(nx, nx, qp->A + k * nx * nx, ws->x + k * nx, x1, 1);
        mv(nx, nu, qp->B + k * nx * nu, u, x1, 1);
    }
    for (k = 0; k <= N; ++k) {
        const real *x = ws->x + k * nx, *u = ws->u + k * nu;
        real *gv = ws->gv + k * ng;
        general_values(ws, k, x, u, gv);
        for (j = 0; j < ws->ms; ++j) {
            int i = k * ws->ms + j;
            real sg = (j & 1) ? GEN_RT_C(-1.0) : GEN_RT_C(1.0), c, zp, Zp;
            ws->t[i] = ws->lam[i] = ws->s[i] = ws->ls[i] = 0;
            ws->dt[i] = ws->dlam[i] = ws->ds[i] = ws->dls[i] = 0;
            if (ws->on[i] == 0) continue;
            kind = side_kind(ws, j, &row);
            side_weights(ws, kind, row, &zp, &Zp);
            c = sg * (side_value(ws, kind, row, x, u, gv) - ws->bd[i]);
            if (zp > 0) {
                ws->s[i] = c < 0 ? thr - c : thr;
                ws->ls[i] = mu0 / ws->s[i];
                c += ws->s[i];
            }
            ws->t[i] = c > thr ? c : thr;
            ws->lam[i] = mu0 / ws->t[i];
        }
    }
}

static int check(const gen_rt_qp *qp, const gen_rt_qp_options *opt)
{
    int N, nx, nu, j;
    if (!qp || !opt) return GEN_RT_ERR_NULL;
    N = qp->N; nx = qp->nx; nu = qp->nu;
    if (N < 1 || nx < 1 || nu < 1 || qp->nbx < 0 || qp->nbx > nx || qp->nbu < 0 ||
        qp->nbu > nu || qp->ng < 0 || opt->max_iter < 1 || !(opt->tol > 0))
        return GEN_RT_ERR_BAD_ARG;
    if (!qp->A || !qp->B || !qp->b || !qp->Q || !qp->R || !qp->q || !qp->r || !qp->x0 ||
        (qp->nbx && (!qp->idxbx || !qp->lbx || !qp->ubx)) ||
        (qp->nbu && (!qp->idxbu || !qp->lbu || !qp->ubu)) ||
        (qp->ng && (!qp->C || !qp->D || !qp->lg || !qp->ug)))
        return GEN_RT_ERR_NULL;
    for (j = 0; j < qp->nbx; ++j)
        if (qp->idxbx[j] < 0 || qp->idxbx[j] >= nx) return GEN_RT_ERR_BAD_ARG;
    for (j = 0; j < qp->nbu; ++j)
        if (qp->idxbu[j] < 0 || qp->idxbu[j] >= nu) return GEN_RT_ERR_BAD_ARG;
    for (j = 0; j < qp->nbx; ++j)
        if ((qp->zx && !(qp->zx[j] >= 0)) || (qp->Zx && !(qp->Zx[j] >= 0)))
            return GEN_RT_ERR_BAD_ARG;
    for (j = 0; j < qp->ng; ++j)
        if ((qp->zg && !(qp->zg[j] >= 0)) || (qp->Zg && !(qp->Zg[j] >= 0)))
            return GEN_RT_ERR_BAD_ARG;
    if (!vfinite(N * nx * nx, qp->A) || !vfinite(N * nx * nu, qp->B) ||
        !vfinite(N * nx, qp->b) || !vfinite((N + 1) * nx * nx, qp->Q) ||
        !vfinite(N * nu * nu, qp->R) || !vfinite((N + 1) * nx, qp->q) ||
        !vfinite(N * nu, qp->r) || !vfinite(nx, qp->x0) ||
        (qp->S && !vfinite(N * nu * nx, qp->S)) ||
        (qp->ng && (!vfinite(N * qp->ng * nx, qp->C) || !vfinite(N * qp->ng * nu, qp->D))))
        return GEN_RT_MPC_ERR_QP_NONFINITE;
    return GEN_RT_OK;
}

/* the scales of the convergence test: the gradient's, the bounds', the
 * penalties' */
static void scales(const qp_ws *ws, real *sg, real *sb, real *sz)
{
    const gen_rt_qp *qp = ws->qp;
    int i;
    real zp, Zp;
    *sg = 1;
    *sb = 1;
    *sz = 1;
    if (vmaxabs((ws->N + 1) * ws->nx, qp->q) > *sg) *sg = vmaxabs((ws->N + 1) * ws->nx, qp->q);
    if (vmaxabs(ws->N * ws->nu, qp->r) > *sg) *sg = vmaxabs(ws->N * ws->nu, qp->r);
    for (i = 0; i < ws->M; ++i) {
        if (ws->on[i] == 0) continue;
        if (rabs(ws->bd[i]) > *sb) *sb = rabs(ws->bd[i]);
        side_soft(ws, i, &zp, &Zp);
        if (zp > *sz) *sz = zp;
    }
}

/* the largest diagonal entry of the cost's Hessian (at least 1) */
static real hessian_scale(const qp_ws *ws)
{
    const gen_rt_qp *qp = ws->qp;
    int k, j, nx = ws->nx, nu = ws->nu;
    real h = 1;
    for (k = 0; k <= ws->N; ++k) {
        for (j = 0; j < nx; ++j)
            if (qp->Q[(k * nx + j) * nx + j] > h) h = qp->Q[(k * nx + j) * nx + j];
        for (j = 0; k < ws->N && j < nu; ++j)
            if (qp->R[(k * nu + j) * nu + j] > h) h = qp->R[(k * nu + j) * nu + j];
    }
    return h;
}

/* a side's weight past this times the Hessian's scale: the LQ solves are
 * refined */
#ifdef GEN_RT_REAL_FLOAT
#define GEN_RT_QP_REFINE GEN_RT_C(1e3)
#else
#define GEN_RT_QP_REFINE GEN_RT_C(1e6)
#endif

/* the mean complementarity's tolerance relative to the residuals': a
 * side active with a vanishing multiplier lies sqrt(mu) off its bound */
#ifdef GEN_RT_REAL_FLOAT
#define GEN_RT_QP_COMP GEN_RT_C(1e-2)
#else
#define GEN_RT_QP_COMP GEN_RT_C(1e-4)
#endif
/* the residuals' factor of an acceptable point (IPOPT's acceptable level),
 * and the iterations without a better point that end a solve from an
 * acceptable one */
#define GEN_RT_QP_ACCEPT GEN_RT_C(100.0)
#define GEN_RT_QP_STALL 5

/* one predictor-corrector iteration from the iterate with residuals res */
static int ipm_iteration(qp_ws *ws, const qp_res *res, real wbig)
{
    int st, k;
    real amax, mu_aff, smu, alpha;
    side_elimination(ws);
    if ((st = factorize(ws))) return st;
    /* the predictor (affine) step */
    lq_gradient(ws, 0, 0);
    lq_solve(ws, wbig);
    amax = side_steps(ws, 0, 0);
    mu_aff = mu_after(ws, amax, res->m);
    smu = res->m ? mu_aff * mu_aff * mu_aff / (res->mu * res->mu) : 0;
    /* the corrector */
    lq_gradient(ws, 1, smu);
    lq_solve(ws, wbig);
    amax = side_steps(ws, 1, smu);
    alpha = res->m ? GEN_RT_C(0.995) * amax : 1;
    if (alpha > 1) alpha = 1;
    for (k = 0; k < (ws->N + 1) * ws->nx; ++k) {
        ws->x[k] += alpha * ws->xp[k];
        ws->pi[k] += alpha * ws->pip[k];
    }
    for (k = 0; k < ws->N * ws->nu; ++k) ws->u[k] += alpha * ws->up[k];
    for (k = 0; k < ws->M; ++k) {
        ws->t[k] += alpha * ws->dt[k];
        ws->lam[k] += alpha * ws->dlam[k];
        ws->s[k] += alpha * ws->ds[k];
        ws->ls[k] += alpha * ws->dls[k];
    }
    return GEN_RT_OK;
}

int gen_rt_qp_solve(const gen_rt_qp *qp, const gen_rt_qp_options *opt, gen_rt_real *work,
                    gen_rt_real *x, gen_rt_real *u, gen_rt_qp_stats *stats)
{
    qp_ws ws;
    qp_res res, best;
    int st, it, since = 0;
    real sg, sb, sz, wbig, merit, best_merit = GEN_RT_QP_INF;
    if ((st = check(qp, opt))) return st;
    if (!work || !x || !u) return GEN_RT_ERR_NULL;
    best.stat = best.ineq = best.soft = best.mu = 0;
    best.m = 0;
    ws.qp = qp;
    layout(&ws, qp->N, qp->nx, qp->nu, qp->nbx, qp->nbu, qp->ng, work);
    if ((st = sides_setup(&ws))) return st;
    scales(&ws, &sg, &sb, &sz);
    wbig = GEN_RT_QP_REFINE * hessian_scale(&ws);
    start(&ws);
    for (it = 0;; ++it) {
        residuals(&ws, &res);
        if (!(res.stat - res.stat == 0) || !(res.mu - res.mu == 0)) {
            st = GEN_RT_MPC_ERR_QP_NONFINITE;
            break;
        }
        /* the residuals relative to their tolerances: converged at 1; the
         * best iterate is kept (the last ones of a hard end game, past
         * which the active sides' growing weights leave the Newton steps
         * to rounding, can be worse) */
        merit = res.stat / sg;
        if (res.ineq / sb > merit) merit = res.ineq / sb;
        if (res.soft / sz > merit) merit = res.soft / sz;
        merit /= opt->tol;
        if (res.mu / (GEN_RT_QP_COMP * opt->tol * sg) > merit)
            merit = res.mu / (GEN_RT_QP_COMP * opt->tol * sg);
        if (merit < best_merit) {
            best_merit = merit;
            best = res;
            since = 0;
            vcopy((qp->N + 1) * qp->nx, ws.x, x);
            vcopy(qp->N * qp->nu, ws.u, u);
        } else {
            ++since;
        }
        if (merit <= 1) {
            st = GEN_RT_OK;
            break;
        }
        if (it >= opt->max_iter || (since >= GEN_RT_QP_STALL && best_merit <= GEN_RT_QP_ACCEPT)) {
            st = GEN_RT_MPC_ERR_QP_MAX_ITER;
            break;
        }
        if (opt->clock && opt->clock(opt->clock_ctx) >= opt->deadline) {
            st = GEN_RT_MPC_TIME_LIMIT;
            break;
        }
        if ((st = ipm_iteration(&ws, &res, wbig))) break;
    }
    /* the best iterate ends an unfinished solve as converged when it is
     * acceptable: its residuals within GEN_RT_QP_ACCEPT times their
     * tolerances, its complementarity within the residuals' */
    if ((st == GEN_RT_MPC_ERR_QP_MAX_ITER || st == GEN_RT_MPC_ERR_QP_SINGULAR) &&
        best_merit <= GEN_RT_QP_ACCEPT && best.mu <= opt->tol * sg)
        st = GEN_RT_OK;
    if (best_merit < GEN_RT_QP_INF) res = best;
    if (stats) {
        stats->iterations = it;
        stats->res_stat = res.stat;
        stats->res_ineq = res.ineq;
        stats->mu = res.mu;
        stats->objective = gen_rt_qp_objective(qp, x, u);
    }
    return st;
}

gen_rt_real gen_rt_qp_objective(const gen_rt_qp *qp, const gen_rt_real *x, const gen_rt_real *u)
{
    int N = qp->N, nx = qp->nx, nu = qp->nu, ng = qp->ng, k, j, l;
    real obj = 0;
    for (k = 0; k <= N; ++k) {
        const real *xk = x + k * nx, *uk = u + k * nu, *Q = qp->Q + k * nx * nx;
        for (j = 0; j < nx; ++j) {
            real qx = 0;
            for (l = 0; l < nx; ++l) qx += Q[j * nx + l] * xk[l];
            obj += (GEN_RT_C(0.5) * qx + qp->q[k * nx + j]) * xk[j];
        }
        if (k < N) {
            const real *R = qp->R + k * nu * nu;
            for (j = 0; j < nu; ++j) {
                real ru = 0;
                for (l = 0; l < nu; ++l) ru += R[j * nu + l] * uk[l];
                if (qp->S)
                    for (l = 0; l < nx; ++l) ru += qp->S[(k * nu + j) * nx + l] * xk[l];
                obj += (GEN_RT_C(0.5) * ru + qp->r[k * nu + j]) * uk[j];
                if (qp->S) {
                    /* u'S x counted once: the half above and the other half here */
                    real sx = 0;
                    for (l = 0; l < nx; ++l) sx += qp->S[(k * nu + j) * nx + l] * xk[l];
                    obj += GEN_RT_C(0.5) * sx * uk[j];
                }
            }
        }
        /* the soft sides' least slacks */
        if (k > 0 && qp->zx)
            for (j = 0; j < qp->nbx; ++j) {
                real v = xk[qp->idxbx[j]], lo = qp->lbx[k * qp->nbx + j];
                real hi = qp->ubx[k * qp->nbx + j], sl;
                real Z = qp->Zx ? qp->Zx[j] : 0;
                if (!(qp->zx[j] > 0)) continue;
                sl = lo > -GEN_RT_QP_INF && v < lo ? lo - v : 0;
                obj += qp->zx[j] * sl + GEN_RT_C(0.5) * Z * sl * sl;
                sl = hi < GEN_RT_QP_INF && v > hi ? v - hi : 0;
                obj += qp->zx[j] * sl + GEN_RT_C(0.5) * Z * sl * sl;
            }
        if (k < N && qp->zg)
            for (j = 0; j < ng; ++j) {
                real v = 0, lo = qp->lg[k * ng + j], hi = qp->ug[k * ng + j], sl;
                real Z = qp->Zg ? qp->Zg[j] : 0;
                if (!(qp->zg[j] > 0)) continue;
                for (l = 0; l < nx; ++l) v += qp->C[(k * ng + j) * nx + l] * xk[l];
                for (l = 0; l < nu; ++l) v += qp->D[(k * ng + j) * nu + l] * uk[l];
                sl = lo > -GEN_RT_QP_INF && v < lo ? lo - v : 0;
                obj += qp->zg[j] * sl + GEN_RT_C(0.5) * Z * sl * sl;
                sl = hi < GEN_RT_QP_INF && v > hi ? v - hi : 0;
                obj += qp->zg[j] * sl + GEN_RT_C(0.5) * Z * sl * sl;
            }
    }
    return obj;
}
