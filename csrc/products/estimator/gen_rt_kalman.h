/*
 * gen_rt_kalman.h - Kalman filters over a generated model (gen.EKF,
 * gen.UKF): the extended filter on the model's own discrete step and its
 * exact sensitivity, the unscented filter on van der Merwe's scaled sigma
 * points propagated through the same step, scalar sequential updates in the
 * Joseph form with a chi-squared innovation gate, and a closed loop that
 * measures a simulation's true state, filters and feeds a controller.
 *
 * The filter's state is the model's independent state [q_ind, u_ind]
 * (ns = nq - mc + nu - mv, the state of gen_rt_model_linearize and of the
 * step sensitivity) in the order perm gives; constants to estimate are the
 * model's coordinates already (the face promotes them to coordinates with
 * q' = 0: random walks, whose step sensitivity is the model's). The full
 * state x is kept on the constraint manifold: the dependent coordinates and
 * speeds are completed (gen_rt_model_consistent_state) after every predict
 * and update.
 *
 * Measurements z = h(x, r, p, t) (nz) come from the generated kernels hz
 * (h) and hjac (h and dh/dx, nz x nx, on the full state); the filter's
 * Jacobian is dh/dx E (gen_rt_model_state_map).
 *
 * Predict (EKF): substeps RK4 steps of period / substeps with r held,
 * F = the product of their sensitivities, P = F P F^T + Q. Update (EKF):
 * h and H at the prior, then each measurement as a scalar in turn (no
 * matrix inverse), with the innovation of the linearized measurement
 * y_i = z_i - h_i - H_i (x - x_prior), S_i = H_i P H_i^T + R_i, fused when
 * y_i^2 <= gate^2 S_i (gate <= 0: no gate), P in the Joseph form
 * (I - K H_i) P (I - K H_i)^T + R_i K K^T, kept symmetric. A NaN or
 * infinite z_i is skipped with GEN_RT_KALMAN_MISSING, a gated one with
 * GEN_RT_KALMAN_GATED; both counted in rejected[i]. The result is the
 * batch EKF update's (the order does not matter).
 *
 * UKF: 2 ns + 1 sigma points x, x +- columns of chol((ns + lambda) P),
 * lambda = alpha^2 (ns + kappa) - ns, weights Wm_0 = lambda / (ns + lambda),
 * Wc_0 = Wm_0 + 1 - alpha^2 + beta, Wm_i = Wc_i = 1 / (2 (ns + lambda));
 * predict propagates them through the same steps (P gets Q); update draws
 * them from the prior, gates each measurement on its own variance and fuses
 * the accepted ones together (K = Pxz Pzz^-1 by Cholesky, P -= K Pzz K^T).
 *
 * Everything belongs to the caller: no heap, no globals, no stdio. A call
 * that fails (a model status) leaves the filter as it was.
 */
#ifndef GEN_RT_KALMAN_H
#define GEN_RT_KALMAN_H

#include <stdint.h>

#include "gen_rt.h"

#ifdef __cplusplus
extern "C" {
#endif

/* the filter kinds */
#define GEN_RT_KALMAN_EKF 0
#define GEN_RT_KALMAN_UKF 1

/* one measurement's status in an update */
#define GEN_RT_KALMAN_ACCEPTED 0   /* fused */
#define GEN_RT_KALMAN_GATED 1      /* innovation beyond the gate: not fused */
#define GEN_RT_KALMAN_MISSING 2    /* NaN or infinite: not fused */
#define GEN_RT_KALMAN_DEGENERATE 3 /* innovation variance not positive: not fused */

/* the measurements h (nz) at the full state x (nx), the inputs r, the
 * constants p and the time t[0]; hjac also writes H = dh/dx (nz x nx) */
typedef void (*gen_rt_kalman_h_fn)(const gen_rt_real *x, const gen_rt_real *r,
                                   const gen_rt_real *p, const gen_rt_real *t, gen_rt_real *h);
typedef void (*gen_rt_kalman_hjac_fn)(const gen_rt_real *x, const gen_rt_real *r,
                                      const gen_rt_real *p, const gen_rt_real *t,
                                      gen_rt_real *h, gen_rt_real *H);

typedef struct {
    /* the model and its measurements (generated) */
    const gen_rt_model *m;
    int nz;
    gen_rt_kalman_h_fn h;
    gen_rt_kalman_hjac_fn hjac;
    const int *perm;        /* ns: the filter state's entry i is the model's independent entry perm[i] */
    /* settings (gen_rt_kalman_start checks them) */
    int kind;               /* GEN_RT_KALMAN_EKF or _UKF */
    int substeps;           /* RK4 steps per period (>= 1) */
    gen_rt_real period;     /* the time of one predict (> 0) */
    gen_rt_real gate;       /* innovation gate in standard deviations (<= 0: none) */
    gen_rt_real alpha, beta, kappa; /* UKF: alpha > 0, ns + kappa > 0 */
    /* the filter */
    gen_rt_real t;          /* the estimate's time */
    gen_rt_real *x;         /* nx: the full state, on the constraints */
    gen_rt_real *xf;        /* ns: the filter state (x's independent entries, in perm's order) */
    gen_rt_real *P;         /* ns x ns covariance */
    gen_rt_real *Q;         /* ns x ns process noise, added at each predict */
    gen_rt_real *R;         /* nz measurement variances (>= 0) */
    gen_rt_real *p;         /* np constants */
    gen_rt_real *r;         /* nr: the inputs of the last predict (the measurements' r) */
    gen_rt_real *y;         /* nz: the last update's innovations (NaN: missing) */
    gen_rt_real *S;         /* nz: their variances */
    int *status;            /* nz: GEN_RT_KALMAN_* of the last update */
    long *rejected;         /* nz: measurements not fused, counted */
    long n_predict, n_update;
    gen_rt_real *work;      /* GEN_RT_KALMAN_WORK reals */
    int *iwork;             /* GEN_RT_KALMAN_IWORK ints */
} gen_rt_kalman;

/* work arrays: the filter's own, and the largest of what its model calls need
 * (the model's sizes as gen_rt.h's macros take them, then nz) */
#define GEN_RT_KALMAN_OWN_(nx, ns, nz)                                          \
    (5 * (ns) * (ns) + (2 * (ns) + 1) * ((ns) + (nz)) + 2 * (nz) * (nz) +          \
     2 * (ns) * (nz) + (nx) * (ns) + (nz) * (nx) + 4 * (nx) + 6 * (ns) + 4 * (nz) + 8)
#define GEN_RT_KALMAN_WORK(nq, nu, mc, mv, nr, ek, acc, nz)                     \
    (GEN_RT_KALMAN_OWN_(GEN_RT_NX_(nq, nu), GEN_RT_NS_(nq, nu, mc, mv), nz) +    \
     GEN_RT_MAX_(GEN_RT_MAX_(GEN_RT_MODEL_STEP_SENS_WORK(nq, nu, mc, mv, nr, ek, acc), \
                             GEN_RT_MODEL_STEP_WORK(nq, nu, mc, mv, nr, ek, acc)),     \
                 GEN_RT_MAX_(GEN_RT_MODEL_CONSISTENT_WORK(nq, nu, mc, mv, nr, ek, acc), \
                             GEN_RT_MODEL_STATE_MAP_WORK(nq, nu, mc, mv, nr, ek, acc))))
#define GEN_RT_KALMAN_IWORK(nq, nu, mc, mv, nr, ek, acc, nz)                    \
    (GEN_RT_MODEL_STEP_SENS_IWORK(nq, nu, mc, mv, nr, ek, acc) + (mc) + (mv) + (nz) + 2)

/* the reals and ints of work a filter over m with nz measurements needs */
int gen_rt_kalman_work_len(const gen_rt_model *m, int nz);
int gen_rt_kalman_iwork_len(const gen_rt_model *m, int nz);

/* Start (or restart) the filter from k->x (its dependent entries
 * completed), k->P and the settings: GEN_RT_ERR_BAD_ARG on a setting out of
 * range (period, substeps, kind, alpha, kappa, a negative R or diagonal of P
 * or Q), GEN_RT_ERR_NONFINITE_INPUT on a NaN or infinite value, a model
 * status when x cannot be completed. Clears the statuses and counters. */
int gen_rt_kalman_start(gen_rt_kalman *k);

/* One prediction over k->period with the inputs r held (NULL when nr == 0). */
int gen_rt_kalman_predict(gen_rt_kalman *k, const gen_rt_real *r);

/* One update with the measurements z (nz; NaN: missing) at k->t. */
int gen_rt_kalman_update(gen_rt_kalman *k, const gen_rt_real *z);

/* A recording of rows samples k->t + i period: row 0 updates with Z[0],
 * row i > 0 predicts with Rin[i - 1] (nr each), then updates with Z[i].
 * Written per row (each may be NULL): X the filter state (ns), Xfull the
 * full state (nx), Pout the covariance (ns x ns), Y the innovations and St
 * the statuses (nz). *done: the rows completed (a failure stops there). */
int gen_rt_kalman_run(gen_rt_kalman *k, int rows, const gen_rt_real *Z, const gen_rt_real *Rin,
                      gen_rt_real *X, gen_rt_real *Xfull, gen_rt_real *Pout, gen_rt_real *Y,
                      int *St, int *done);

/* ---- a closed loop: measure, filter, control --------------------------
 * gen_rt_kalman_control is a gen_rt_controller_fn (the simulation engine's
 * controller, sampled every k->period): at each sample it measures the
 * true state x of the plant through the filter's measurement functions
 * plus Gaussian noise of standard deviations noise_sd (a seeded generator
 * of its own: the same seed, the same run), predicts with the inputs it
 * applied since the last sample (none at the first), updates, and sets r
 * from the estimate: the feedback law (gen_rt_model_eval_input on the
 * filter's model and its full state) or, when inner is not NULL, the inner
 * controller called on the estimate in the plant's layout. The plant's
 * state is the filter model's without its ne estimated constants
 * (coordinates nq .. nq + ne - 1 of the filter's model), which the
 * measurements of the plant take from theta. With capacity > 0 the
 * estimates (t, the filter state, its standard deviations) of the first
 * capacity samples are logged. */
typedef struct {
    gen_rt_kalman *k;
    const gen_rt_input *law;        /* the feedback on the estimate (NULL with inner) */
    gen_rt_controller_fn inner;     /* or a controller on it (NULL: the law) */
    void *inner_ctx;
    int nq;                         /* the plant's coordinates */
    int ne;                         /* the estimated constants */
    const gen_rt_real *theta;       /* ne: their true values */
    const gen_rt_real *noise_sd;    /* nz: the measurement noise */
    uint64_t rng;                   /* the generator's state (the seed) */
    int started;
    gen_rt_real *xa;                /* nx of the filter's model: the plant's true state */
    gen_rt_real *xo;                /* the estimate in the plant's layout */
    gen_rt_real *z;                 /* nz */
    gen_rt_real *rprev;             /* nr: the inputs applied since the last sample */
    int capacity;                   /* log rows (0: no log) */
    long count;                     /* samples taken */
    gen_rt_real *log_t, *log_x, *log_sd; /* capacity, capacity x ns, capacity x ns */
} gen_rt_kalman_loop;

int gen_rt_kalman_control(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *r);

/* a standard normal draw from the loop's generator (splitmix64, Box-Muller) */
gen_rt_real gen_rt_kalman_normal(uint64_t *state);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_KALMAN_H */
