/*
 * gen_rt_qp.h - a stage-wise quadratic program (the QP of one SQP iteration
 * of a model predictive controller) solved by a primal-dual interior point
 * method whose Newton systems are Riccati recursions (HPIPM's design:
 * Frison and Diehl 2020; the stage-wise KKT system factorized backwards).
 *
 *   min  sum_{k<N} [ 1/2 x_k' Q_k x_k + u_k' S_k x_k + 1/2 u_k' R_k u_k + q_k' x_k + r_k' u_k ]
 *        + 1/2 x_N' Q_N x_N + q_N' x_N + sum of the slacks' penalties
 *   s.t. x_0 = x0 (fixed),  x_{k+1} = A_k x_k + B_k u_k + b_k,        k < N
 *        lbu_k <= u_k[idxbu] <= ubu_k                      (hard), k < N
 *        lbx_k - s <= x_k[idxbx] <= ubx_k + s              (soft), 1 <= k <= N
 *        lg_k - s <= C_k x_k + D_k u_k <= ug_k + s   (soft or hard), k < N
 *
 * A soft constraint (its L1 weight z > 0) has a slack s >= 0 per side,
 * penalized by z s + 1/2 Z s^2 (an exact penalty when z exceeds the
 * constraint's multiplier); a hard one (z = 0) has none. A bound of
 * +-infinity (or beyond +-GEN_RT_QP_INF) is no constraint.
 *
 * Each iteration is Mehrotra's predictor-corrector: the slacks and the
 * multipliers of the inequalities are eliminated stage by stage (a
 * diagonal weight on each constraint row), the remaining equality-
 * constrained LQ problem is solved by the backward Riccati recursion with
 * x_0 fixed (one factorization, two right-hand sides), then the forward
 * sweep.
 *
 * Matrices are row-major and per stage contiguous: A is N blocks of
 * nx x nx, B N blocks of nx x nu, S N blocks of nu x nx (NULL: zero), Q
 * N + 1 blocks, R N blocks; vectors likewise (q: (N + 1) nx, lbx: (N + 1)
 * nbx, stage 0's unused). Everything is caller-owned: the work array holds
 * GEN_RT_QP_WORK(N, nx, nu, nbx, nbu, ng) reals. No heap, no globals, no
 * stdio; reentrant. The scalar is gen_rt_real (double, or float with
 * GEN_RT_REAL_FLOAT).
 */
#ifndef GEN_RT_QP_H
#define GEN_RT_QP_H

#include "gen_rt.h"
#include "gen_rt_mpc_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* a bound at or beyond this magnitude is no constraint */
#define GEN_RT_QP_INF GEN_RT_C(1e30)

/* a monotonic clock in seconds (the caller's: a POSIX clock on a host, a
 * cycle counter on a microcontroller) */
typedef double (*gen_rt_mpc_clock_fn)(void *ctx);

typedef struct {
    int N, nx, nu;          /* intervals (N >= 1), states, inputs (nu >= 1) */
    int nbx, nbu, ng;       /* bounded states, bounded inputs, general rows per stage */
    const int *idxbx;       /* nbx: the bounded entries of x */
    const int *idxbu;       /* nbu: the bounded entries of u */
    const gen_rt_real *A, *B, *b;    /* N x (nx x nx), N x (nx x nu), N x nx */
    const gen_rt_real *Q, *S, *R;    /* (N+1) x (nx x nx), N x (nu x nx) or NULL, N x (nu x nu) */
    const gen_rt_real *q, *r;        /* (N+1) x nx, N x nu */
    const gen_rt_real *lbx, *ubx;    /* (N+1) x nbx (stage 0's unused) */
    const gen_rt_real *lbu, *ubu;    /* N x nbu */
    const gen_rt_real *C, *D;        /* N x (ng x nx), N x (ng x nu) */
    const gen_rt_real *lg, *ug;      /* N x ng */
    const gen_rt_real *zx, *Zx;      /* nbx: the state bounds' L1 and L2 weights (zx NULL or
                                      * zx[i] = 0: hard; Zx NULL: 0) */
    const gen_rt_real *zg, *Zg;      /* ng: the general rows' weights, likewise */
    const gen_rt_real *x0;           /* nx: the initial state */
} gen_rt_qp;

typedef struct {
    int max_iter;                 /* iterations (>= 1) */
    gen_rt_real tol;              /* the scaled residuals and the mean complementarity */
    gen_rt_mpc_clock_fn clock;    /* NULL: no deadline */
    void *clock_ctx;
    double deadline;              /* stop when clock(clock_ctx) >= deadline */
} gen_rt_qp_options;

typedef struct {
    int iterations;
    gen_rt_real res_stat;         /* the stationarity residual, inf-norm */
    gen_rt_real res_ineq;         /* the inequalities' residual, inf-norm */
    gen_rt_real mu;               /* the mean complementarity */
    gen_rt_real objective;        /* with the slacks' penalties */
} gen_rt_qp_stats;

/* the default options: max_iter 100, tol 1e-10 (double) or 1e-5 (float),
 * no clock */
void gen_rt_qp_options_default(gen_rt_qp_options *opt);

/* reals of work: per stage the iterate and the Riccati factors, per
 * constraint side (two per row, each stage) its slack, multiplier, the
 * soft slack and its multiplier, the steps of all four and the
 * eliminations' coefficients */
#define GEN_RT_QP_SIDES_(nbx, nbu, ng) (2 * ((nbx) + (nbu) + (ng)))
#define GEN_RT_QP_WORK(N, nx, nu, nbx, nbu, ng)                                  \
    (((N) + 1) * (11 * (nx) + (nx) * (nx) + 7 * (nu) + (nu) * (nu) + (nu) * (nx) + \
                  (ng) + 16 * GEN_RT_QP_SIDES_(nbx, nbu, ng)) +                  \
     3 * (nx) * (nx) + 4 * (nx) * (nu) + 2 * (nu) * (nu) + 3 * (nx) + 2 * (nu))

/* GEN_RT_QP_WORK as a function (the same number) */
int gen_rt_qp_work_len(int N, int nx, int nu, int nbx, int nbu, int ng);

/* Solve qp: the states x ((N + 1) nx) and inputs u (N nu) of the
 * solution; stats (may be NULL) filled. The iterate is kept on every exit
 * but a call error: on GEN_RT_MPC_TIME_LIMIT and GEN_RT_MPC_ERR_QP_MAX_ITER
 * x and u hold the last iterate (dynamically feasible, inside the hard
 * bounds up to its residual). Returns GEN_RT_OK, GEN_RT_MPC_TIME_LIMIT
 * (the deadline passed), GEN_RT_MPC_ERR_QP_MAX_ITER (no convergence in
 * max_iter), GEN_RT_MPC_ERR_QP_SINGULAR (a stage's Hessian block of the
 * inputs is not positive definite), GEN_RT_MPC_ERR_QP_NONFINITE (NaN or
 * inf in the data or the iterates), GEN_RT_ERR_NULL, GEN_RT_ERR_BAD_ARG
 * (sizes, an index out of range, lb > ub, a negative weight, tol <= 0). */
int gen_rt_qp_solve(const gen_rt_qp *qp, const gen_rt_qp_options *opt, gen_rt_real *work,
                    gen_rt_real *x, gen_rt_real *u, gen_rt_qp_stats *stats);

/* the objective of (x, u) with slacks at their least values: the
 * quadratic cost plus, per soft side, z s + 1/2 Z s^2 at s = its violation */
gen_rt_real gen_rt_qp_objective(const gen_rt_qp *qp, const gen_rt_real *x,
                                const gen_rt_real *u);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_QP_H */
