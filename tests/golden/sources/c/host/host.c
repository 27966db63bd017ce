#include <stddef.h>

typedef double eomgen_real;
typedef int (*eomgen_controller)(void *ctx, eomgen_real t, const eomgen_real *x, eomgen_real *r);
typedef struct {
    int method;
    int project;
    eomgen_real rtol;
    eomgen_real atol;
    eomgen_real h_init;
    eomgen_real h_min;
    eomgen_real h_max;
    long max_steps;
    eomgen_real proj_tol;
    int proj_max_iter;
    int every;
    int final_only;
    const volatile int *cancel;
} eomgen_sim_options;
typedef struct {
    const eomgen_real *r;
    int n_table;
    const eomgen_real *t_table;
    const eomgen_real *r_table;
    int hold;
    const eomgen_real *K;
    const eomgen_real *x_op;
    eomgen_controller controller;
    void *ctx;
    eomgen_real period;
    int n_gain;
    eomgen_real t_gain;
    eomgen_real dt_gain;
    const eomgen_real *r_min;
    const eomgen_real *r_max;
} eomgen_input;
typedef struct {
    int n;
    const int *which;
    const int *direction;
    const int *terminal;
    const eomgen_real *level;
    int capacity;
    int *log_which;
    eomgen_real *log_t;
    eomgen_real *log_x;
    eomgen_real *log_x_after;
    eomgen_real *hybrid_work;
    int *hybrid_iwork;
} eomgen_events;
typedef struct {
    long n_accepted;
    long n_rejected;
    long n_rhs;
    long n_jac;
    int n_out;
    int n_events;
    int terminal;
    eomgen_real t_last;
    eomgen_real h_next;
    eomgen_real x_last[];
} eomgen_sim_stats;
typedef struct {
    const char *abi;                 /* gen/codegen/abi.py ABI_TAG: the layout of this table */
    const char *name;                /* the model's name */
    int real_size;                   /* sizeof(eomgen_real) */
    int nq, nu, nx, nr, np, mc, mv, ns, na, ny;
    size_t sizeof_sim_options, sizeof_input, sizeof_events, sizeof_sim_stats;
    const char * (*status_message)(int status);
    int (*eval_mass_matrix)(const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *M);
    int (*eval_forcing)(const eomgen_real *q, const eomgen_real *u, const eomgen_real *r, const eomgen_real *p, eomgen_real t, eomgen_real *f);
    int (*eval_kinematics)(const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *qdot);
    int (*eval_constraints)(const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *fc);
    int (*eval_constraint_jacobian)(const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *Jc);
    int (*eval_velocity_constraints)(const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *fv);
    int (*eval_velocity_constraint_matrix)(const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *b);
    int (*eval_energy)(const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *E);
    int (*eval_rhs)(eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *dxdt, eomgen_real *lam);
    int (*eval_auxiliary_forces)(eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *F);
    int (*project)(eomgen_real t, const eomgen_real *p, eomgen_real tol, int max_iter, eomgen_real *x);
    int (*consistent_state)(eomgen_real t, const eomgen_real *p, eomgen_real tol, int max_iter, eomgen_real *x);
    void (*sim_options_default)(void *opts);
    int (*step_rk4)(eomgen_real t, eomgen_real h, const eomgen_real *r, const eomgen_real *p, int project, eomgen_real *x);
    int (*advance)(eomgen_real t0, eomgen_real t1, const eomgen_real *r, const eomgen_real *p, const void *opts, void *stats, eomgen_real *x);
    int (*simulate_rows)(eomgen_real t0, eomgen_real t_end, eomgen_real dt);
    int (*simulate_rows_kept)(int rows, int every, int final_only);
    int (*simulate)(const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const eomgen_real *r, const eomgen_real *p, const void *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, void *stats);
    int (*simulate_input)(const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const void *in, const eomgen_real *p, const void *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, eomgen_real *r_out, void *stats);
    int (*simulate_events)(const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const void *in, const void *ev, const eomgen_real *p, const void *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, eomgen_real *r_out, void *stats);
    int (*linearize)(const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *B);
    int (*jacobian)(eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *Jx, eomgen_real *Jr);
    int (*step_sensitivity)(eomgen_real t, eomgen_real h, const eomgen_real *r, const eomgen_real *p, eomgen_real *x, eomgen_real *Fx, eomgen_real *Fr);
    int (*eval_input)(eomgen_real t, const eomgen_real *x, const void *in, eomgen_real *r);
    int (*eval_outputs)(eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *y);
    int (*eval_hybrid)(eomgen_real t, const eomgen_real *x, const eomgen_real *p, eomgen_real *g);
    int (*linearize_outputs)(const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *B, eomgen_real *C, eomgen_real *D);
    int (*linearize_discrete)(const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real dt, eomgen_real *Ad, eomgen_real *Bd);
} eomgen_api;
const char * eomgen_status_message(const eomgen_api *api, int status);
int eomgen_eval_mass_matrix(const eomgen_api *api, const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *M);
int eomgen_eval_forcing(const eomgen_api *api, const eomgen_real *q, const eomgen_real *u, const eomgen_real *r, const eomgen_real *p, eomgen_real t, eomgen_real *f);
int eomgen_eval_kinematics(const eomgen_api *api, const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *qdot);
int eomgen_eval_constraints(const eomgen_api *api, const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *fc);
int eomgen_eval_constraint_jacobian(const eomgen_api *api, const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *Jc);
int eomgen_eval_velocity_constraints(const eomgen_api *api, const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *fv);
int eomgen_eval_velocity_constraint_matrix(const eomgen_api *api, const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *b);
int eomgen_eval_energy(const eomgen_api *api, const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *E);
int eomgen_eval_rhs(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *dxdt, eomgen_real *lam);
int eomgen_eval_auxiliary_forces(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *F);
int eomgen_project(const eomgen_api *api, eomgen_real t, const eomgen_real *p, eomgen_real tol, int max_iter, eomgen_real *x);
int eomgen_consistent_state(const eomgen_api *api, eomgen_real t, const eomgen_real *p, eomgen_real tol, int max_iter, eomgen_real *x);
void eomgen_sim_options_default(const eomgen_api *api, eomgen_sim_options *opts);
int eomgen_step_rk4(const eomgen_api *api, eomgen_real t, eomgen_real h, const eomgen_real *r, const eomgen_real *p, int project, eomgen_real *x);
int eomgen_advance(const eomgen_api *api, eomgen_real t0, eomgen_real t1, const eomgen_real *r, const eomgen_real *p, const eomgen_sim_options *opts, eomgen_sim_stats *stats, eomgen_real *x);
int eomgen_simulate_rows(const eomgen_api *api, eomgen_real t0, eomgen_real t_end, eomgen_real dt);
int eomgen_simulate_rows_kept(const eomgen_api *api, int rows, int every, int final_only);
int eomgen_simulate(const eomgen_api *api, const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const eomgen_real *r, const eomgen_real *p, const eomgen_sim_options *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, eomgen_sim_stats *stats);
int eomgen_simulate_input(const eomgen_api *api, const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const eomgen_input *in, const eomgen_real *p, const eomgen_sim_options *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, eomgen_real *r_out, eomgen_sim_stats *stats);
int eomgen_simulate_events(const eomgen_api *api, const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const eomgen_input *in, const eomgen_events *ev, const eomgen_real *p, const eomgen_sim_options *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, eomgen_real *r_out, eomgen_sim_stats *stats);
int eomgen_linearize(const eomgen_api *api, const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *B);
int eomgen_jacobian(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *Jx, eomgen_real *Jr);
int eomgen_step_sensitivity(const eomgen_api *api, eomgen_real t, eomgen_real h, const eomgen_real *r, const eomgen_real *p, eomgen_real *x, eomgen_real *Fx, eomgen_real *Fr);
int eomgen_eval_input(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_input *in, eomgen_real *r);
int eomgen_eval_outputs(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *y);
int eomgen_eval_hybrid(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *p, eomgen_real *g);
int eomgen_linearize_outputs(const eomgen_api *api, const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *B, eomgen_real *C, eomgen_real *D);
int eomgen_linearize_discrete(const eomgen_api *api, const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real dt, eomgen_real *Ad, eomgen_real *Bd);
int eomgen_rhs_batch(const eomgen_api *api, int n, const eomgen_real *t, int t_stride, const eomgen_real *x, const eomgen_real *r, int r_stride, const eomgen_real *p, int p_stride, eomgen_real *dxdt, int *status);
int eomgen_outputs_batch(const eomgen_api *api, int n, const eomgen_real *t, int t_stride, const eomgen_real *x, const eomgen_real *r, int r_stride, const eomgen_real *p, int p_stride, eomgen_real *y, int *status);
int eomgen_mass_matrix_batch(const eomgen_api *api, int n, const eomgen_real *q, int q_stride, const eomgen_real *p, int p_stride, eomgen_real *M, int *status);
int eomgen_linearize_batch(const eomgen_api *api, int n, const eomgen_real *x, const eomgen_real *r, int r_stride, const eomgen_real *p, int p_stride, eomgen_real t, eomgen_real *A, eomgen_real *B, int *status);



/* a batch loop stops at a SIGINT (Ctrl-C: gen/sim/interrupt.py, the relay of
   csrc/host/gen_host_interrupt.c) with the runtime's ERR_CANCELLED */
#define EOMGEN_CANCELLED_ (-13)

const char * eomgen_status_message(const eomgen_api *api, int status)
{
    return api->status_message(status);
}

int eomgen_eval_mass_matrix(const eomgen_api *api, const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *M)
{
    return api->eval_mass_matrix(q, p, t, M);
}

int eomgen_eval_forcing(const eomgen_api *api, const eomgen_real *q, const eomgen_real *u, const eomgen_real *r, const eomgen_real *p, eomgen_real t, eomgen_real *f)
{
    return api->eval_forcing(q, u, r, p, t, f);
}

int eomgen_eval_kinematics(const eomgen_api *api, const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *qdot)
{
    return api->eval_kinematics(q, u, p, t, qdot);
}

int eomgen_eval_constraints(const eomgen_api *api, const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *fc)
{
    return api->eval_constraints(q, p, t, fc);
}

int eomgen_eval_constraint_jacobian(const eomgen_api *api, const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *Jc)
{
    return api->eval_constraint_jacobian(q, p, t, Jc);
}

int eomgen_eval_velocity_constraints(const eomgen_api *api, const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *fv)
{
    return api->eval_velocity_constraints(q, u, p, t, fv);
}

int eomgen_eval_velocity_constraint_matrix(const eomgen_api *api, const eomgen_real *q, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *b)
{
    return api->eval_velocity_constraint_matrix(q, p, t, A, b);
}

int eomgen_eval_energy(const eomgen_api *api, const eomgen_real *q, const eomgen_real *u, const eomgen_real *p, eomgen_real t, eomgen_real *E)
{
    return api->eval_energy(q, u, p, t, E);
}

int eomgen_eval_rhs(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *dxdt, eomgen_real *lam)
{
    return api->eval_rhs(t, x, r, p, dxdt, lam);
}

int eomgen_eval_auxiliary_forces(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *F)
{
    return api->eval_auxiliary_forces(t, x, r, p, F);
}

int eomgen_project(const eomgen_api *api, eomgen_real t, const eomgen_real *p, eomgen_real tol, int max_iter, eomgen_real *x)
{
    return api->project(t, p, tol, max_iter, x);
}

int eomgen_consistent_state(const eomgen_api *api, eomgen_real t, const eomgen_real *p, eomgen_real tol, int max_iter, eomgen_real *x)
{
    return api->consistent_state(t, p, tol, max_iter, x);
}

void eomgen_sim_options_default(const eomgen_api *api, eomgen_sim_options *opts)
{
    api->sim_options_default(opts);
}

int eomgen_step_rk4(const eomgen_api *api, eomgen_real t, eomgen_real h, const eomgen_real *r, const eomgen_real *p, int project, eomgen_real *x)
{
    return api->step_rk4(t, h, r, p, project, x);
}

int eomgen_advance(const eomgen_api *api, eomgen_real t0, eomgen_real t1, const eomgen_real *r, const eomgen_real *p, const eomgen_sim_options *opts, eomgen_sim_stats *stats, eomgen_real *x)
{
    return api->advance(t0, t1, r, p, opts, stats, x);
}

int eomgen_simulate_rows(const eomgen_api *api, eomgen_real t0, eomgen_real t_end, eomgen_real dt)
{
    return api->simulate_rows(t0, t_end, dt);
}

int eomgen_simulate_rows_kept(const eomgen_api *api, int rows, int every, int final_only)
{
    return api->simulate_rows_kept(rows, every, final_only);
}

int eomgen_simulate(const eomgen_api *api, const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const eomgen_real *r, const eomgen_real *p, const eomgen_sim_options *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, eomgen_sim_stats *stats)
{
    return api->simulate(x0, t0, t_end, dt, r, p, opts, capacity, t_out, x_out, lam_out, stats);
}

int eomgen_simulate_input(const eomgen_api *api, const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const eomgen_input *in, const eomgen_real *p, const eomgen_sim_options *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, eomgen_real *r_out, eomgen_sim_stats *stats)
{
    return api->simulate_input(x0, t0, t_end, dt, in, p, opts, capacity, t_out, x_out, lam_out, r_out, stats);
}

int eomgen_simulate_events(const eomgen_api *api, const eomgen_real *x0, eomgen_real t0, eomgen_real t_end, eomgen_real dt, const eomgen_input *in, const eomgen_events *ev, const eomgen_real *p, const eomgen_sim_options *opts, int capacity, eomgen_real *t_out, eomgen_real *x_out, eomgen_real *lam_out, eomgen_real *r_out, eomgen_sim_stats *stats)
{
    return api->simulate_events(x0, t0, t_end, dt, in, ev, p, opts, capacity, t_out, x_out, lam_out, r_out, stats);
}

int eomgen_linearize(const eomgen_api *api, const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *B)
{
    return api->linearize(x_op, r_op, p, t, A, B);
}

int eomgen_jacobian(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *Jx, eomgen_real *Jr)
{
    return api->jacobian(t, x, r, p, Jx, Jr);
}

int eomgen_step_sensitivity(const eomgen_api *api, eomgen_real t, eomgen_real h, const eomgen_real *r, const eomgen_real *p, eomgen_real *x, eomgen_real *Fx, eomgen_real *Fr)
{
    return api->step_sensitivity(t, h, r, p, x, Fx, Fr);
}

int eomgen_eval_input(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_input *in, eomgen_real *r)
{
    return api->eval_input(t, x, in, r);
}

int eomgen_eval_outputs(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *r, const eomgen_real *p, eomgen_real *y)
{
    return api->eval_outputs(t, x, r, p, y);
}

int eomgen_eval_hybrid(const eomgen_api *api, eomgen_real t, const eomgen_real *x, const eomgen_real *p, eomgen_real *g)
{
    return api->eval_hybrid(t, x, p, g);
}

int eomgen_linearize_outputs(const eomgen_api *api, const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real *A, eomgen_real *B, eomgen_real *C, eomgen_real *D)
{
    return api->linearize_outputs(x_op, r_op, p, t, A, B, C, D);
}

int eomgen_linearize_discrete(const eomgen_api *api, const eomgen_real *x_op, const eomgen_real *r_op, const eomgen_real *p, eomgen_real t, eomgen_real dt, eomgen_real *Ad, eomgen_real *Bd)
{
    return api->linearize_discrete(x_op, r_op, p, t, dt, Ad, Bd);
}

int eomgen_rhs_batch(const eomgen_api *api, int n, const eomgen_real *t, int t_stride,
                     const eomgen_real *x, const eomgen_real *r, int r_stride,
                     const eomgen_real *p, int p_stride, eomgen_real *dxdt, int *status)
{
    const long nx = api->nx;
    int i, st;
    const long sigints = eomgen_interrupt_count();
    *status = 0;
    for (i = 0; i < n; ++i) {
        if (eomgen_interrupt_count() != sigints) { *status = EOMGEN_CANCELLED_; return i; }
        st = api->eval_rhs(t ? t[(long)i * t_stride] : 0, x + i * nx,
                           r ? r + (long)i * r_stride : NULL, p ? p + (long)i * p_stride : NULL,
                           dxdt + i * nx, NULL);
        if (st) { *status = st; return i; }
    }
    return -1;
}

int eomgen_outputs_batch(const eomgen_api *api, int n, const eomgen_real *t, int t_stride,
                         const eomgen_real *x, const eomgen_real *r, int r_stride,
                         const eomgen_real *p, int p_stride, eomgen_real *y, int *status)
{
    const long nx = api->nx, ny = api->ny;
    int i, st;
    *status = 0;
    for (i = 0; i < n; ++i) {
        st = api->eval_outputs(t ? t[(long)i * t_stride] : 0, x + i * nx,
                               r ? r + (long)i * r_stride : NULL,
                               p ? p + (long)i * p_stride : NULL, y + i * ny);
        if (st) { *status = st; return i; }
    }
    return -1;
}

int eomgen_mass_matrix_batch(const eomgen_api *api, int n, const eomgen_real *q, int q_stride,
                             const eomgen_real *p, int p_stride, eomgen_real *M, int *status)
{
    const long nm = (long)api->nu * api->nu;
    int i, st;
    const long sigints = eomgen_interrupt_count();
    *status = 0;
    for (i = 0; i < n; ++i) {
        if (eomgen_interrupt_count() != sigints) { *status = EOMGEN_CANCELLED_; return i; }
        st = api->eval_mass_matrix(q + (long)i * q_stride, p ? p + (long)i * p_stride : NULL, 0,
                                   M + i * nm);
        if (st) { *status = st; return i; }
    }
    return -1;
}

int eomgen_linearize_batch(const eomgen_api *api, int n, const eomgen_real *x,
                           const eomgen_real *r, int r_stride, const eomgen_real *p,
                           int p_stride, eomgen_real t, eomgen_real *A, eomgen_real *B,
                           int *status)
{
    const long nx = api->nx, na = (long)api->ns * api->ns, nb = (long)api->ns * api->nr;
    eomgen_real Bdummy[1];
    int i, st;
    const long sigints = eomgen_interrupt_count();
    *status = 0;
    for (i = 0; i < n; ++i) {
        if (eomgen_interrupt_count() != sigints) { *status = EOMGEN_CANCELLED_; return i; }
        st = api->linearize(x + i * nx, r ? r + (long)i * r_stride : NULL,
                            p ? p + (long)i * p_stride : NULL, t, A + i * na,
                            B && nb ? B + i * nb : Bdummy);
        if (st) { *status = st; return i; }
    }
    return -1;
}

