/*
 * gen_rt_main.h - the standalone simulator of a generated model: its
 * command line, its input tables (CSV), the run loop and the CSV it writes.
 *
 * Hand-written and model-agnostic: a generated main.c describes its model
 * in a gen_rt_main_model (sizes, names, default constants and a few
 * functions that call the model's public API) and calls gen_rt_main().
 * Arrays of the model's scalar type are passed as void pointers; real_size
 * (4: float, 8: double) says which. Every number read from the command
 * line or a file is parsed in double and rounded to the model's type, so a
 * value this file keeps in a double is exactly the model's.
 *
 * Not part of the model library: this file uses stdio and the heap, and is
 * compiled into the <name>_sim program only.
 */
#ifndef GEN_RT_MAIN_H
#define GEN_RT_MAIN_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define GEN_RT_MAIN_MAX_EVENTS 256   /* --event options */
#define GEN_RT_MAIN_EVENT_LOG 1024   /* events logged before a rerun with a larger log */
#define GEN_RT_MAIN_CONTINUE (-1)    /* gen_rt_main_parse: run (else: exit with the code) */

/* the options of the model's sim_options that the command line sets */
typedef struct {
    int method, project, every, final_only;
    double rtol, atol;
} gen_rt_main_options;

/* one run as the command line asked for it: what the model's simulate_input
 * or simulate_events needs (arrays of the model's scalar type) */
typedef struct {
    double t_end, dt;
    int rows;                       /* the output arrays' rows (simulate_rows) */
    const void *p;                  /* NP constants */
    gen_rt_main_options opts;
    const void *r;                  /* NR constant inputs; the base of the feedback */
    int hold;                       /* the model's HOLD_ZOH or HOLD_LINEAR */
    double period;                  /* 0: continuous feedback */
    int n_table;                    /* > 0: the inputs from a table */
    const void *t_table, *r_table;  /* n_table times, n_table x NR inputs */
    const void *K, *x_op;           /* NR x NS gain (NULL: none), NX operating state */
    int n_events;                   /* 0: simulate_input; else simulate_events */
    const int *ev_which, *ev_direction, *ev_terminal;
    const void *ev_level;
    int capacity;                   /* the event log: capacity entries */
    int *log_which;
    void *log_t, *log_x;
    void *log_x_after;              /* capacity x NX: the state after a hybrid jump */
} gen_rt_main_run;

/* what the run loop reads of the model's sim_stats */
typedef struct {
    int n_out, n_events;
    double t_last;
    void *x_last;                   /* NX: the caller's array, filled by simulate */
} gen_rt_main_stats;

/* The model, as a generated main.c describes it. The functions return the
 * model's status (0 ok, negative on failure); a NULL eval_energy,
 * eval_auxiliary or eval_outputs means the model has none. */
typedef struct {
    const char *name;               /* the model's name: the program is <name>_sim */
    int real_size;                  /* sizeof(the model's scalar type): 4 or 8 */
    int nq, nx, nr, np, mc, mv, ns, na, ny;
    const char *const *state_names;     /* nx */
    const char *const *input_names;     /* nr (NULL when nr == 0) */
    const char *const *param_names;     /* np (NULL when np == 0) */
    const char *const *output_names;    /* ny (NULL when ny == 0) */
    const char *const *aux_names;       /* na: the reaction forces' columns */
    const char *const *ind_names;       /* ns: the independent state */
    const void *p_default;              /* np default constants */
    void (*options_default)(gen_rt_main_options *opts);
    int (*consistent_state)(const void *p, void *x);
    int (*linearize)(const void *x, const void *r, const void *p, void *A, void *B);
    int (*simulate_rows)(double t_end, double dt);
    int (*simulate)(const gen_rt_main_run *run, const void *x0, void *t_out, void *x_out,
                    void *lam_out, void *r_out, gen_rt_main_stats *stats);
    int (*eval_constraints)(double t, const void *x, const void *p, void *fc);
    int (*eval_energy)(double t, const void *x, const void *p, void *E);
    int (*eval_auxiliary)(double t, const void *x, const void *r, const void *p, void *fa);
    int (*eval_outputs)(double t, const void *x, const void *r, const void *p, void *y);
    const char *(*status_message)(int status);
    int tracker;                        /* 1: built with a trajectory tracker (its
                                           inputs vary: their columns are written) */
    /* hybrid={...}: the declarations' names (nh; 0 and NULL: none). Their
     * jumps are events: the run always logs them */
    int nh;
    const char *const *hybrid_names;
    const int *hybrid_kinds;            /* nh: GEN_RT_HYBRID_IMPACT or _RESET */
    /* the gaps and guards at (t, x) (nh values; NULL when nh == 0): a refused
     * start names its declaration's value */
    int (*eval_hybrid)(double t, const void *x, const void *p, void *g);
} gen_rt_main_model;

/* The command line, parsed. The arrays hold the model's scalar type and
 * are allocated by gen_rt_main_parse (free them with gen_rt_main_free). */
typedef struct {
    double t_end, dt, period;
    gen_rt_main_options opts;
    int consistent, linearize, hold;
    const char *output, *input_csv, *gain_file, *events_csv;
    void *x, *x_op, *p, *r;         /* NX, NX, NP, NR */
    int n_ev;
    int ev_which[GEN_RT_MAIN_MAX_EVENTS], ev_dir[GEN_RT_MAIN_MAX_EVENTS];
    int ev_term[GEN_RT_MAIN_MAX_EVENTS];
    void *ev_level;                 /* GEN_RT_MAIN_MAX_EVENTS */
} gen_rt_main_args;

/* The whole program: parse argv, read the tables, run, write the CSV.
 * Returns the exit code: 0 done, 1 a failure (a message on stderr), 2 a
 * usage error. */
int gen_rt_main(const gen_rt_main_model *m, int argc, char **argv);

/* argv into a (allocated even on failure: free it with gen_rt_main_free).
 * GEN_RT_MAIN_CONTINUE, or the exit code (0 after --help). */
int gen_rt_main_parse(const gen_rt_main_model *m, int argc, char **argv, gen_rt_main_args *a);
void gen_rt_main_free(gen_rt_main_args *a);

/* The numbers of a CSV file row by row (separators ',', ' ' or tab; blank
 * lines and lines starting with '#' skipped). A first line that is not
 * numeric is copied into header when header is not NULL (else it is an
 * error). *data is malloc'ed (rows x cols of the model's scalar type).
 * 0, or the exit code with a message on stderr: 1 the file cannot be read,
 * 2 a malformed table. */
int gen_rt_main_read_csv(const gen_rt_main_model *m, const char *path, void **data, int *rows,
                         int *cols, char *header, size_t header_size);

/* The input table of --input-csv (a header 't,<input names>' in any
 * order, then rows) into *t_table (n) and *r_table (n x NR), malloc'ed.
 * 0 or the exit code (a message printed). */
int gen_rt_main_read_inputs(const gen_rt_main_model *m, const char *path, void **t_table,
                            void **r_table, int *n);

/* The real number s, rounded to the model's scalar type: 0, or -1 when s
 * is not a number, not finite or out of the type's range. */
int gen_rt_main_parse_real(const gen_rt_main_model *m, const char *s, double *out);

/* element i of an array of the model's scalar type */
double gen_rt_main_get(const gen_rt_main_model *m, const void *a, long i);
void gen_rt_main_set(const gen_rt_main_model *m, void *a, long i, double v);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_MAIN_H */
