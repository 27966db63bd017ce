/*
 * gen_host_ensemble.c - many simulations of one model in one call, each
 * through the model's plugin table exactly as one sim.simulate call makes
 * it (simulate, or simulate_input with a table, a feedback, or for a hybrid
 * model simulate_events with its hybrid work), then reduced
 * into the caller's arrays (gen_host_ensemble.h). The options' cancel flag
 * (Ctrl-C, gen/sim/interrupt.py) is read before each run and, inside a run, by
 * the runtime before each step. Hand-written; compiled
 * into eomgen's Python host module after its declarations.
 */

#include <string.h>

/* the status of a run not made because the caller cancelled the call
 * (sim_options.cancel set): the runtime's GEN_RT_ERR_CANCELLED */
#define EOMGEN_ERR_CANCELLED_ (-13)

/* the sim_stats fields before x_last, as the host declares them */
#define EOMGEN_STATS_(s) ((eomgen_sim_stats *)(s))

static eomgen_real eomgen_nan_(void)
{
    volatile eomgen_real z = 0;
    return z / z;
}

/* the width of a reducer's row of one run */
static long eomgen_reducer_width_(const eomgen_api *api, const eomgen_reducer *rd,
                                  int rows)
{
    switch (rd->kind) {
    case EOMGEN_REDUCE_FINAL: return api->nx;
    case EOMGEN_REDUCE_AT: return (long)rd->n_rows * rd->n_sel;
    case EOMGEN_REDUCE_ROWS: return (long)rows * api->nx;
    default: return rd->n_sel;
    }
}

/* quantity k of row j: a state, or an output evaluated at the row */
static int eomgen_quantity_(const eomgen_api *api, const eomgen_ensemble *e,
                            const eomgen_real *p, const eomgen_real *r_const, int j, int k,
                            eomgen_real *v)
{
    const eomgen_real *x = e->x_buf + (long)j * api->nx;
    const eomgen_real *r;
    int st;
    if (k < api->nx) {
        *v = x[k];
        return 0;
    }
    r = e->input ? e->r_buf + (long)j * api->nr : r_const;
    st = api->eval_outputs(e->t_buf[j], x, r, p, e->y_buf);
    *v = e->y_buf[k - api->nx];
    return st;
}

static int eomgen_reduce_(const eomgen_api *api, const eomgen_ensemble *e,
                          const eomgen_reducer *rd, long i, int n_out, const eomgen_real *p,
                          const eomgen_real *r_const)
{
    long w = eomgen_reducer_width_(api, rd, e->rows);
    eomgen_real *out = rd->out + i * w;
    int j, k, st;
    eomgen_real v;
    switch (rd->kind) {
    case EOMGEN_REDUCE_FINAL:
        for (k = 0; k < api->nx; ++k) out[k] = e->x_buf[(long)(n_out - 1) * api->nx + k];
        return 0;
    case EOMGEN_REDUCE_ROWS:
        for (j = 0; j < (long)e->rows * api->nx; ++j)
            out[j] = j < (long)n_out * api->nx ? e->x_buf[j] : eomgen_nan_();
        return 0;
    case EOMGEN_REDUCE_AT:
        for (j = 0; j < rd->n_rows; ++j)
            for (k = 0; k < rd->n_sel; ++k) {
                if (rd->rows[j] >= n_out) {
                    out[(long)j * rd->n_sel + k] = eomgen_nan_();
                    continue;
                }
                if ((st = eomgen_quantity_(api, e, p, r_const, rd->rows[j], rd->sel[k], &v)))
                    return st;
                out[(long)j * rd->n_sel + k] = v;
            }
        return 0;
    default:
        for (k = 0; k < rd->n_sel; ++k) {
            eomgen_real acc = 0;
            for (j = 0; j < n_out; ++j) {
                if ((st = eomgen_quantity_(api, e, p, r_const, j, rd->sel[k], &v))) return st;
                if (rd->kind == EOMGEN_REDUCE_MEAN) acc += v;
                else if (j == 0 || (rd->kind == EOMGEN_REDUCE_MIN ? v < acc : v > acc)) acc = v;
            }
            out[k] = rd->kind == EOMGEN_REDUCE_MEAN ? acc / n_out : acc;
        }
        return 0;
    }
}

int eomgen_ensemble_run(const eomgen_api *api, const eomgen_ensemble *e)
{
    const int nx = api->nx;
    eomgen_sim_options opts = *e->opts;
    eomgen_input in, in_zero;
    int i, k, q, failed = 0, capacity;
    memset(&in_zero, 0, sizeof in_zero);    /* the inputs' struct zero-filled: r = NULL, zero */
    opts.final_only = e->final_only ? 1 : opts.final_only;
    /* the rows simulate writes (the runtime's count, gen_rt_simulate_rows_kept) */
    capacity = api->simulate_rows_kept(e->rows, opts.every, opts.final_only);
    for (i = 0; i < e->n; ++i) {
        const eomgen_real *x0 = e->x0 + (long)i * e->x0_stride;
        if (opts.cancel && *(const volatile int *)opts.cancel) {
            /* cancelled by the caller: this run and the rest are not made */
            for (; i < e->n; ++i) {
                e->status[i] = EOMGEN_ERR_CANCELLED_;
                e->t_last[i] = e->t0;
                for (k = 0; k < nx; ++k)
                    e->x_last[(long)i * nx + k] = e->x0[(long)i * e->x0_stride + k];
                for (q = 0; q < e->n_reducers; ++q) {
                    const eomgen_reducer *rd = e->reducers + q;
                    long w = eomgen_reducer_width_(api, rd, e->rows), j;
                    for (j = 0; j < w; ++j) rd->out[(long)i * w + j] = eomgen_nan_();
                }
                ++failed;
            }
            break;
        }
        const eomgen_real *p = e->p ? e->p + (long)i * e->p_stride : NULL;
        const eomgen_real *r = e->r ? e->r + (long)i * e->r_stride : NULL;
        eomgen_sim_stats *s = EOMGEN_STATS_(e->stats);
        int st = 0, n_out = 0;
        for (k = 0; k < nx; ++k) e->x_start[k] = x0[k];
        s->t_last = e->t0;
        for (k = 0; k < nx; ++k) s->x_last[k] = x0[k];
        if (e->consistent)
            st = api->consistent_state(e->t0, p, 0, 0, e->x_start);
        if (!st) {
            if (e->events) {
                /* hybrid={...}: the engine's jumps need its events struct
                 * (simulate and simulate_input refuse a hybrid model) */
                if (e->input) in = *e->input;
                else in = in_zero;
                if (r) in.r = r;
                st = api->simulate_events(e->x_start, e->t0, e->t_end, e->dt, &in, e->events,
                                          p, &opts, capacity, e->t_buf, e->x_buf, NULL,
                                          e->r_buf, s);
            } else if (e->input) {
                in = *e->input;
                if (r) in.r = r;
                st = api->simulate_input(e->x_start, e->t0, e->t_end, e->dt, &in, p, &opts,
                                         capacity, e->t_buf, e->x_buf, NULL, e->r_buf, s);
            } else {
                st = api->simulate(e->x_start, e->t0, e->t_end, e->dt, r, p, &opts, capacity,
                                   e->t_buf, e->x_buf, NULL, s);
            }
            n_out = s->n_out;
        }
        for (q = 0; !st && q < e->n_reducers; ++q)
            st = eomgen_reduce_(api, e, e->reducers + q, i, n_out, p, r);
        e->status[i] = st;
        e->t_last[i] = s->t_last;
        for (k = 0; k < nx; ++k)
            e->x_last[(long)i * nx + k] = st ? s->x_last[k] : e->x_buf[(long)(n_out - 1) * nx + k];
        if (st) {
            ++failed;
            for (q = 0; q < e->n_reducers; ++q) {
                const eomgen_reducer *rd = e->reducers + q;
                long w = eomgen_reducer_width_(api, rd, e->rows), j;
                for (j = 0; j < w; ++j) rd->out[(long)i * w + j] = eomgen_nan_();
            }
        }
    }
    return failed;
}
