/*
 * gen_rt_abi.h - the runtime's part of the interface description: the
 * integration methods, the table holds, the embedded stack bound and the
 * structs of the public API as the runtime sees them (gen_rt_<name>; a
 * model's <p>_<name> has the same fields in the same order, rendered from
 * the same list, and its wrappers copy them field by field from that list).
 *
 * Rendered from gen/codegen/abi.py (templates/c/gen_rt_abi.h.j2); every generated
 * model carries its own copy. Do not edit: change gen/codegen/abi.py, then
 * EOMGEN_UPDATE_GOLDEN=1 python -m pytest tests/unit/codegen/test_abi.py rewrites this
 * file (the test fails while it differs from gen/codegen/abi.py).
 * Included by gen_rt.h once gen_rt_real is defined.
 */
#ifndef GEN_RT_ABI_H
#define GEN_RT_ABI_H

/* integration methods (gen_rt_sim_options.method) */
#define GEN_RT_METHOD_RK4 0
#define GEN_RT_METHOD_DOPRI5 1
#define GEN_RT_METHOD_RODAS4 2
#define GEN_RT_METHOD_COUNT 3
/* every spelling of a method a user may give, aliases included: X(name, code) */
#define GEN_RT_METHOD_NAMES(X) X("rk4", 0) X("dopri5", 1) X("rodas4", 2) X("rodas", 2)
/* table holds (gen_rt_input.hold) */
#define GEN_RT_HOLD_ZOH 0
#define GEN_RT_HOLD_LINEAR 1
#define GEN_RT_HOLD_COUNT 2
#define GEN_RT_HOLD_NAMES(X) X("zoh", 0) X("linear", 1)
/* the embedded profile's bound on a function's stack frame, in bytes */
#define GEN_RT_STACK_LIMIT 8192

/* a controller of gen_rt_input: r holds the inputs so far and may be
 * overwritten; nonzero return: GEN_RT_ERR_CONTROLLER */
typedef int (*gen_rt_controller_fn)(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *r);

/* Integration options (fill with <p>_sim_options_default). */
typedef struct {
    int method; /* GEN_RT_METHOD_RK4 (on the output grid), GEN_RT_METHOD_DOPRI5 or GEN_RT_METHOD_RODAS4 (adaptive, dense output) */
    int project; /* 1: project onto the constraints after each step */
    gen_rt_real rtol; /* adaptive: relative tolerance */
    gen_rt_real atol; /* adaptive: absolute tolerance */
    gen_rt_real h_init; /* adaptive: first step, <= 0: automatic */
    gen_rt_real h_min; /* adaptive: minimum step, <= 0: automatic */
    gen_rt_real h_max; /* adaptive: maximum step, <= 0: unbounded */
    long max_steps; /* adaptive: step budget between two output rows */
    gen_rt_real proj_tol; /* projection: relative tolerance on the correction */
    int proj_max_iter; /* projection: Newton iterations */
    int every; /* simulate: keep every k-th output row and the last (<= 1: all) */
    int final_only; /* simulate: 1 keeps only the row at t_end */
    const volatile int *cancel; /* flag owned by the caller, read before every step: nonzero stops the run with GEN_RT_ERR_CANCELLED (NULL: never cancelled) */
} gen_rt_sim_options;

/* Inputs during a simulation (simulate_input): a constant or a table, a linear feedback on the independent state, a controller callback; continuous or sampled. Zero-fill it (memset) and set what you use. */
typedef struct {
    const gen_rt_real *r; /* NR constant inputs (NULL: zero); the base of the feedback */
    int n_table; /* > 0: the base from a table of n_table rows instead */
    const gen_rt_real *t_table; /* n_table strictly increasing times */
    const gen_rt_real *r_table; /* n_table x NR inputs, row-major */
    int hold; /* table: GEN_RT_HOLD_ZOH (the last knot's row) or GEN_RT_HOLD_LINEAR */
    const gen_rt_real *K; /* NR x NS gain on the independent state (NULL: none): r = base - K (x_ind - x_op_ind) */
    const gen_rt_real *x_op; /* NX operating state of the gain (NULL: zero) */
    gen_rt_controller_fn controller; /* called last with r holding the above; may overwrite r; nonzero return: ERR_CONTROLLER (NULL: none) */
    void *ctx; /* passed to the controller */
    gen_rt_real period; /* 0: r evaluated at every stage; > 0: sampled at t0 + k period and held */
    int n_gain; /* > 0: a gain schedule of n_gain rows: K is n_gain x NR x NS, x_op n_gain x NX and r (when not NULL) n_gain x NR, row k used from t_gain + k dt_gain on (row 0 before, the last row after) */
    gen_rt_real t_gain; /* schedule: the time of row 0 */
    gen_rt_real dt_gain; /* schedule: the time between rows (> 0) */
    const gen_rt_real *r_min; /* NR lower bounds the inputs are clipped to after the feedback (NULL: none; -inf: unbounded) */
    const gen_rt_real *r_max; /* NR upper bounds, likewise (NULL: none; inf: unbounded) */
} gen_rt_input;

/* Events of simulate_events: crossings of a level by a state or an output, located on the dense output; the log of those found. Zero-fill it and set what you use. */
typedef struct {
    int n; /* number of event functions */
    const int *which; /* n: 0..NX-1 the state x[which], NX..NX+NY-1 the output y[which - NX] */
    const int *direction; /* n: +1 crossing upwards, -1 downwards, 0 both */
    const int *terminal; /* n (NULL: none): nonzero ends the run at the event */
    const gen_rt_real *level; /* n (NULL: zero): the level crossed */
    int capacity; /* events the log holds */
    int *log_which; /* capacity: the event's index i */
    gen_rt_real *log_t; /* capacity: its time */
    gen_rt_real *log_x; /* capacity x NX: its state (the dense output, projected) */
    gen_rt_real *log_x_after; /* capacity x NX (NULL: not kept): the state after a hybrid event's jump (impact, reset), else as log_x */
    gen_rt_real *hybrid_work; /* GEN_RT_HYBRID_WORK(NQ, NU, MV, NH) reals: the engine's hybrid scratch (a model with hybrid={...} needs it) */
    int *hybrid_iwork; /* GEN_RT_HYBRID_IWORK(NQ, NU, MV, NH) ints */
} gen_rt_events;

/* Integration statistics (advance accumulates them). A counted field is the caller's array here. */
typedef struct {
    long n_accepted; /* accepted steps */
    long n_rejected; /* rejected steps (dopri5) */
    long n_rhs; /* right-hand-side evaluations */
    long n_jac; /* Jacobian evaluations (rodas4) */
    int n_out; /* output rows written */
    int n_events; /* events found (simulate_events; the log holds the first capacity) */
    int terminal; /* the terminal event that ended the run, -1: none */
    gen_rt_real t_last; /* time of the last good state */
    gen_rt_real h_next; /* adaptive: step size to continue with */
    gen_rt_real *x_last; /* NX: last good state (on failure: where it failed) */
} gen_rt_sim_stats;

#endif /* GEN_RT_ABI_H */
