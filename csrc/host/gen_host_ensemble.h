/*
 * gen_host_ensemble.h - many simulations of one model in one call, reduced
 * as they finish (gen/sim/ensemble.py). Hand-written; part of eomgen's Python
 * host module (gen/toolchain/host.py), which declares eomgen_real, the structs and
 * the plugin table eomgen_api before this header. Also the module's cffi
 * declarations: plain C, no preprocessor beyond integer constants.
 */

/* what a reducer keeps of each run (over its output rows) */
#define EOMGEN_REDUCE_FINAL 0   /* the state of the last row: nx values */
#define EOMGEN_REDUCE_AT 1      /* n_rows rows x n_sel quantities */
#define EOMGEN_REDUCE_MIN 2     /* n_sel values: the smallest over the rows */
#define EOMGEN_REDUCE_MAX 3     /* n_sel values: the largest */
#define EOMGEN_REDUCE_MEAN 4    /* n_sel values: the mean over the rows */
#define EOMGEN_REDUCE_ROWS 5    /* every row: rows x nx (a Python reducer's input) */

/* a quantity of a reducer: 0..nx-1 the state x[k], nx..nx+ny-1 the output
 * y[k - nx] (the model's outputs, evaluated at each row with its inputs) */
typedef struct {
    int kind;                 /* EOMGEN_REDUCE_* */
    int n_sel;                /* quantities (AT, MIN, MAX, MEAN) */
    const int *sel;
    int n_rows;               /* AT: the output rows taken */
    const int *rows;
    eomgen_real *out;         /* n runs x the kind's width, row-major; NaN for a failed run */
} eomgen_reducer;

typedef struct {
    int n;                    /* runs of this call */
    const eomgen_real *x0;    /* initial states, run i at x0 + i * x0_stride (0: one for all) */
    int x0_stride;
    const eomgen_real *p;     /* constants, run i at p + i * p_stride; NULL: the defaults */
    int p_stride;
    const eomgen_real *r;     /* constant inputs (the base of in), run i at r + i * r_stride; NULL: zero or in's */
    int r_stride;
    const eomgen_input *input; /* NULL: constant inputs (simulate); else simulate_input with it, its r replaced by run i's */
    /* a hybrid model (hybrid={...}): its events struct (no user events, no
     * log needed: capacity 0) with the engine's hybrid work; every run is
     * then simulate_events with the inputs (input, or a zero-filled one with
     * run i's r), as sim.simulate makes it: the same impacts, resets and
     * contacts, the same bits. NULL for a model without declarations */
    const eomgen_events *events;
    const eomgen_sim_options *opts;
    eomgen_real t0, t_end, dt;
    int rows;                 /* output rows of a full run (simulate_rows) */
    int final_only;           /* 1: every reducer is FINAL: one row a run */
    int consistent;           /* 1: the dependent states solved first (consistent_state) */
    int n_reducers;
    const eomgen_reducer *reducers;
    /* work of one run: rows, rows x nx, rows x nr (NULL without input), nx, ny,
     * and a sim_stats of the table's sizeof_sim_stats bytes */
    eomgen_real *t_buf, *x_buf, *r_buf, *x_start, *y_buf;
    void *stats;
    /* results of every run */
    int *status;              /* n: 0 or the failing status */
    eomgen_real *t_last;      /* n: the time of the last good state */
    eomgen_real *x_last;      /* n x nx: the last good state (where a failed run stopped) */
} eomgen_ensemble;

/* The n runs of e in order; returns the number of failed runs (their
 * status, time and last state in e->status, e->t_last, e->x_last; their
 * reducer rows NaN). The runs are independent: any split of an ensemble
 * into calls gives the same numbers. When opts->cancel is set, the run in
 * progress stops and the rest are not made (status ERR_CANCELLED). */
int eomgen_ensemble_run(const eomgen_api *api, const eomgen_ensemble *e);
