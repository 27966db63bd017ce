/*
 * gen_rt_mpc.h - nonlinear model predictive control by real-time iterations
 * (Diehl, Bock and Schloeder 2005; acados's SQP_RTI) over a model's own
 * discrete step: multiple shooting with N intervals of one period, each
 * `substeps` classic RK4 steps of the model with its exact sensitivities
 * (the model's <p>_step_sensitivity, through gen_rt_mpc_problem.step), a
 * Gauss-Newton Hessian, and the stage-wise QP of gen_rt_qp.h.
 *
 *   min  sum_{k<N} period (|x_k - xr_k|^2_Q + |u_k - ur_k|^2_R + sum_i W_i y_i(x_k, u_k)^2)
 *        + |x_N - xr_N|^2_P + the soft constraints' L1 penalties
 *   s.t. x_0 = the measured state, x_{k+1} = F(x_k, u_k) (the model's step),
 *        lbu <= u_k[idxbu] <= ubu (hard),
 *        lbx <= x_k[idxbx] <= ubx (soft, zx > 0; k >= 1),
 *        lh <= h(x_k, u_k) <= uh (soft where zh > 0, else hard; k < N)
 *
 * on the independent state x_ind (ns entries of the full state x: the
 * model's [q_ind; u_ind]; a constrained model's dependent entries follow
 * through gen_rt_mpc_problem.complete). xr, ur: the reference, a table of
 * n_ref rows from t_ref every dt_ref, linear between rows, held beyond.
 *
 * A call is a preparation phase (gen_rt_mpc_prepare: the previous solution
 * shifted by one interval, the last repeated; the model's steps and
 * sensitivities along it; the QP's data: everything that does not need the
 * new state) and a feedback phase (gen_rt_mpc_feedback: the new state in,
 * the QP solved, the control out). gen_rt_mpc_step does both (RTI: once;
 * SQP: until the step is below tol or max_iter), within a time budget.
 * The control returned is never NaN: on a failure it is the previous
 * solution's, shifted, clipped to the input bounds.
 *
 * Everything is the caller's: the problem (const, usually generated), the
 * state (the options and the outcome of the last call) and the work array
 * (GEN_RT_MPC_WORK(...) reals: the iterate, the QP and its solver's work).
 * No heap, no globals, no stdio; reentrant.
 */
#ifndef GEN_RT_MPC_H
#define GEN_RT_MPC_H

#include "gen_rt_qp.h"

#ifdef __cplusplus
extern "C" {
#endif

/* one step of the model: x (NX) advanced by h with inputs r held, Fx = d
 * x1_ind / d x_ind (ns x ns), Fr = d x1_ind / d r (ns x nr) */
typedef int (*gen_rt_mpc_step_fn)(const void *ctx, gen_rt_real t, gen_rt_real h,
                                  const gen_rt_real *r, gen_rt_real *x, gen_rt_real *Fx,
                                  gen_rt_real *Fr);
/* the dependent entries of x from its independent ones */
typedef int (*gen_rt_mpc_complete_fn)(const void *ctx, gen_rt_real t, gen_rt_real *x);
/* m functions of (t, x, r) and their derivatives: out, m rows of
 * [value, d/dx_ind (ns), d/dr (nr)] */
typedef int (*gen_rt_mpc_eval_fn)(const void *ctx, gen_rt_real t, const gen_rt_real *x,
                                  const gen_rt_real *r, gen_rt_real *out);

typedef struct {
    int nx, ns, nr;                 /* full state, independent state, inputs */
    int N, substeps;                /* intervals, RK4 steps per interval */
    gen_rt_real period;             /* an interval's length */
    const int *ind;                 /* ns: the independent entries of x */
    const gen_rt_real *Q, *R, *P;   /* ns x ns, nr x nr, ns x ns */
    int ny;                         /* nonlinear least-squares residuals */
    const gen_rt_real *W;           /* ny: their weights */
    gen_rt_mpc_eval_fn residuals;   /* their values and derivatives */
    int nbx;                        /* bounded independent states (soft) */
    const int *idxbx;               /* nbx: indices into x_ind */
    const gen_rt_real *lbx, *ubx, *zx;
    int nbu;                        /* bounded inputs (hard) */
    const int *idxbu;
    const gen_rt_real *lbu, *ubu;
    int nh;                         /* path constraints */
    const gen_rt_real *lh, *uh, *zh;  /* zh[i] > 0: soft, its L1 weight */
    gen_rt_mpc_eval_fn path;
    int n_ref;                      /* reference rows (>= 1) */
    gen_rt_real t_ref, dt_ref;      /* the time of row 0, between rows (> 0) */
    const gen_rt_real *x_ref;       /* n_ref x ns */
    const gen_rt_real *u_ref;       /* n_ref x nr */
    gen_rt_mpc_step_fn step;
    gen_rt_mpc_complete_fn complete;  /* NULL: an unconstrained model */
    const void *ctx;                /* passed to the functions above */
} gen_rt_mpc_problem;

/* the options, and the state kept between calls */
typedef struct {
    /* options (gen_rt_mpc_init sets the defaults) */
    int sqp;                /* 0: one SQP iteration per call (RTI); 1: to convergence */
    int max_iter;           /* SQP iterations per call (sqp) */
    gen_rt_real tol;        /* sqp: converged when the step's largest entry <= tol (1 + |x|) */
    double time_limit;      /* seconds per call (<= 0: none); needs a clock */
    int qp_max_iter;
    gen_rt_real qp_tol;
    gen_rt_mpc_clock_fn clock;   /* NULL: no times, no time limit */
    void *clock_ctx;
    /* state */
    int has_iterate;        /* 0: the next call starts from the guess (zero) */
    int shift;              /* the iterate is the last call's solution, to be shifted */
    int prepared;           /* the QP's data are at the iterate for t_prepared */
    gen_rt_real t_prepared;
    /* the last call's outcome */
    int status, qp_status, iterations, qp_iterations;
    double t_prepare, t_feedback;   /* seconds in each phase (clock) */
    gen_rt_real objective;          /* the last QP's objective, penalties included */
} gen_rt_mpc_state;

/* reals of work */
#define GEN_RT_MPC_MAX_(a, b) ((a) > (b) ? (a) : (b))
#define GEN_RT_MPC_WORK(nx, ns, nr, N, nbx, nbu, nh, ny)                        \
    (((N) + 1) * ((nx) + 3 * (nr) + 3 * (ns) + 2 * (ns) * (ns) + 2 * (nr) * (ns) + \
                  (nr) * (nr) + 2 * (nbx) + 2 * (nbu) + (nh) * ((ns) + (nr) + 2)) +  \
     GEN_RT_QP_WORK(N, ns, nr, nbx, nbu, nh) + 3 * (nx) + 3 * (ns) * ((ns) + (nr)) + \
     GEN_RT_MPC_MAX_(nh, ny) * (1 + (ns) + (nr)) + 4 * (nr) + (ns) + 8)

/* GEN_RT_MPC_WORK of a problem */
int gen_rt_mpc_work_len(const gen_rt_mpc_problem *pb);

/* the state's defaults: RTI, max_iter 1, tol 1e-8 (float: 1e-4), no time
 * limit, the QP's defaults, no clock, no iterate */
void gen_rt_mpc_init(gen_rt_mpc_state *st);

/* the next call starts from x ((N + 1) x nx full states) and u (N x nr
 * inputs) as they are (no shift); either may be NULL: zero */
int gen_rt_mpc_set_guess(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st,
                         gen_rt_real *work, const gen_rt_real *x, const gen_rt_real *u);

/* the preparation phase for the call at time t */
int gen_rt_mpc_prepare(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st, gen_rt_real t,
                       gen_rt_real *work);

/* the feedback phase: the measured state x (nx) in, the control u (nr) out
 * (prepares first when the QP is not prepared) */
int gen_rt_mpc_feedback(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st,
                        const gen_rt_real *x, gen_rt_real *work, gen_rt_real *u);

/* one controller call at time t: prepare (unless done for t) and feedback,
 * then (sqp) more iterations until converged, max_iter or the time limit.
 * Returns GEN_RT_OK, GEN_RT_MPC_MAX_ITER, GEN_RT_MPC_TIME_LIMIT (a control
 * in every case), or a negative status (the QP's, the model's, or
 * GEN_RT_ERR_NONFINITE_INPUT for a NaN state) with the fallback control. */
int gen_rt_mpc_step(const gen_rt_mpc_problem *pb, gen_rt_mpc_state *st, gen_rt_real t,
                    const gen_rt_real *x, gen_rt_real *work, gen_rt_real *u);

/* the predicted states ((N + 1) x nx; a constrained model's dependent
 * entries completed from the independent ones) and inputs (N x nr) of the
 * last call; either may be NULL */
int gen_rt_mpc_solution(const gen_rt_mpc_problem *pb, const gen_rt_mpc_state *st,
                        const gen_rt_real *work, gen_rt_real *x, gen_rt_real *u);

/* the message of a status of the runtime's or the MPC's table */
const char *gen_rt_mpc_status_message(int status);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_MPC_H */
