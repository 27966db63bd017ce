/* gen_rt_simulate.c - the row drivers of the simulation engine: advance
 * (t0 to t1, no rows), and simulate, simulate_input and simulate_events,
 * which step the engine (gen_rt_engine.c) between the output times, take a
 * digital controller's samples (gen_rt_input.c), handle the events and
 * hybrid jumps found in each step (gen_rt_events.c), and write the rows:
 * at the step ends, or inside a step from its dense output, projected.
 *
 * As in gen_rt_model.c: inputs are assumed checked by the caller, work
 * arrays are the caller's, sized by the GEN_RT_MODEL_*_WORK macros. */
#include "gen_rt_private.h"

/* a sample of the inputs at t from x (each sample time once); a new input
 * starts the next step with f evaluated afresh */
static int sample_(gen_rt_engine *e, gen_rt_real t, const gen_rt_real *x)
{
    int taken, st = gen_rt_input_sample(e->c, t, x, &taken);
    if (taken) e->f0_valid = 0;
    return st;
}

int gen_rt_model_advance(const gen_rt_model *m, gen_rt_real t0, gen_rt_real t1,
                         const gen_rt_real *r, const gen_rt_real *p,
                         const gen_rt_sim_options *o, gen_rt_real *work, int *iwork,
                         gen_rt_sim_stats *s, gen_rt_real *x)
{
    int nx = RT_NX(m), st;
    gen_rt_real t = t0;
    gen_rt_sim_ctx c;
    gen_rt_engine e;
    if (!(t1 >= t0) || !gen_rt_engine_method_ok(o)) return GEN_RT_ERR_BAD_ARG;
    gen_rt_sim_ctx_init(&c, m, r, p, o->proj_tol, o->proj_max_iter, t0);
    gen_rt_engine_init(&e, &c, o, NULL, s, x, work, iwork, NULL);
    e.t_span = t1 - t0;
    while (t < t1) {
        st = gen_rt_engine_step(&e, t, t1);
        if (st) {
            s->t_last = t;
            rt_copy(nx, x, s->x_last);
            s->h_next = e.h_next;
            return st;
        }
        rt_copy(nx, e.xn, x);
        t = e.t1;
    }
    s->t_last = t1;
    s->h_next = e.h_next;
    rt_copy(nx, x, s->x_last);
    return GEN_RT_OK;
}

int gen_rt_simulate_rows(gen_rt_real t0, gen_rt_real t_end, gen_rt_real dt)
{
    long n;
    if (!(dt > 0) || !(t_end >= t0) || !rt_finite(1, &t0) || !rt_finite(1, &t_end))
        return GEN_RT_ERR_BAD_ARG;
    if ((t_end - t0) / dt > GEN_RT_C(1e9)) return GEN_RT_ERR_BAD_ARG;
    n = (long)((t_end - t0) / dt);
    if (t0 + (gen_rt_real)n * dt < t_end - GEN_RT_C(1e-9) * dt) n += 1;
    return (int)(n + 1);
}

int gen_rt_simulate_rows_kept(int rows, int every, int final_only)
{
    if (rows <= 0) return rows;
    if (final_only) return 1;
    if (every <= 1) return rows;
    return (rows - 1) / every + 1 + ((rows - 1) % every != 0);
}

/* what simulate writes: the rows and where they go */
typedef struct {
    int rows, capacity;
    gen_rt_real t0, t_end, dt;
    gen_rt_real *t_out, *x_out, *lam_out, *r_out;
    gen_rt_real *dx, *lam;
} row_sink;

static gen_rt_real row_time(const row_sink *o, int k)
{
    return (k == o->rows - 1) ? o->t_end : o->t0 + (gen_rt_real)k * o->dt;
}

/* row k at tk with state xr: the inputs in effect from tk on, the
 * multipliers when asked for, stored if kept */
static int emit_row(gen_rt_engine *e, const row_sink *o, int k, int last, gen_rt_real tk,
                    const gen_rt_real *xr)
{
    gen_rt_sim_ctx *c = e->c;
    const gen_rt_model *m = c->m;
    const gen_rt_sim_options *op = e->o;
    const gen_rt_real *rk = c->r;
    int nx = e->nx, nr = m->nr, mv = m->mv, ldl = mv > 0 ? mv : 1, i, st;
    gen_rt_sim_stats *s = e->s;
    if (c->in) {
        if (c->in->period > 0) {
            rk = c->r_held;
        } else {
            if ((st = gen_rt_input_at(m, c->in, tk, tk, xr, c->r_buf))) return st;
            rk = c->r_buf;
        }
    }
    st = gen_rt_model_rhs(m, tk, xr, rk, c->p, c->work, c->iwork, o->dx, o->lam);
    if (st) return st;
    e->attempts = 0;
    if (op->final_only ? last : (op->every <= 1 || k % op->every == 0 || last)) {
        long j = s->n_out;
        if (j >= o->capacity) return GEN_RT_ERR_OUTPUT_FULL;
        o->t_out[j] = tk;
        rt_copy(nx, xr, o->x_out + j * nx);
        if (o->lam_out)
            for (i = 0; i < mv; ++i) o->lam_out[j * ldl + i] = o->lam[i];
        if (o->r_out)
            for (i = 0; i < nr; ++i) o->r_out[j * nr + i] = rk ? rk[i] : 0;
        s->n_out = (int)j + 1;
    }
    return GEN_RT_OK;
}

/* the rows from *k on in the step just taken from t (up to its end, or
 * before te when it ended at a terminal event or a hybrid jump: cut): at
 * the end, or inside from the dense output, projected; *k the next row */
static int step_rows_(gen_rt_engine *e, const row_sink *out, int *k, gen_rt_real t, int cut,
                      gen_rt_real te)
{
    int st;
    while (*k < out->rows) {
        gen_rt_real tk = row_time(out, *k), tol1 = rt_time_tol(e->t1);
        const gen_rt_real *xr = e->xn;
        if (cut ? !(tk < te - rt_time_tol(te)) : !(tk <= e->t1 + tol1)) break;
        if (tk < e->t1 - tol1) {
            /* inside the step: the dense output, projected */
            gen_rt_engine_dense(e, (tk - t) / e->h, e->xi);
            if (!gen_rt_all_finite(e->nx, e->xi)) return GEN_RT_ERR_DIVERGED;
            if ((st = gen_rt_engine_project(e, tk, e->xi))) return st;
            xr = e->xi;
        }
        if ((st = emit_row(e, out, *k, *k == out->rows - 1, tk, xr))) return st;
        ++*k;
    }
    return GEN_RT_OK;
}

static void stats_reset(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                        gen_rt_sim_stats *s)
{
    s->n_accepted = 0; s->n_rejected = 0; s->n_rhs = 0; s->n_jac = 0;
    s->n_out = 0; s->n_events = 0; s->terminal = -1; s->t_last = t0; s->h_next = 0;
    rt_copy(RT_NX(m), x0, s->x_last);
}

/* simulate, simulate_input and simulate_events: in == NULL for a constant
 * r, ev == NULL for no events */
static int simulate_(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                     gen_rt_real t_end, gen_rt_real dt, const gen_rt_real *r,
                     const gen_rt_input *in, const gen_rt_events *ev, const gen_rt_real *p,
                     const gen_rt_sim_options *o, int capacity, gen_rt_real *work, int *iwork,
                     gen_rt_real *t_out, gen_rt_real *x_out, gen_rt_real *lam_out,
                     gen_rt_real *r_out, gen_rt_sim_stats *s)
{
    int nx = RT_NX(m), nr = m->nr, mv = m->mv, rows, k, st;
    gen_rt_real *x = work, *dx = x + nx, *lam = dx + nx, *w = lam + mv + 1;
    gen_rt_real *rb = w + GEN_RT_MODEL_SIM_CORE_WORK_(m->nq, m->nu, m->mc, mv, nr,
                                                      m->explicit_kinematics, m->accel);
    gen_rt_real *yb = rb + 2 * nr + 2;
    gen_rt_sim_ctx c;
    gen_rt_engine e;
    row_sink out;
    gen_rt_real t = t0;
    stats_reset(m, x0, t0, s);
    rt_copy(nx, x0, x);
    rows = gen_rt_simulate_rows(t0, t_end, dt);
    if (rows < 0) return rows;
    if (o->every < 0 || o->final_only < 0 || !gen_rt_engine_method_ok(o)) return GEN_RT_ERR_BAD_ARG;
    if (capacity < gen_rt_simulate_rows_kept(rows, o->every, o->final_only))
        return GEN_RT_ERR_OUTPUT_FULL;
    if ((st = gen_rt_events_check(m, ev))) return st;
    gen_rt_sim_ctx_init(&c, m, r, p, o->proj_tol, o->proj_max_iter, t0);
    if (in) {
        c.in = in;
        c.r_buf = rb;
        c.r_held = rb + nr + 1;
        c.r = in->period > 0 ? c.r_held : c.r_buf;
    }
    gen_rt_engine_init(&e, &c, o, ev, s, x, w, iwork, (ev && ev->n > 0) ? yb : NULL);
    e.t_span = t_end - t0;
    out.rows = rows; out.capacity = capacity; out.t0 = t0; out.t_end = t_end; out.dt = dt;
    out.t_out = t_out; out.x_out = x_out; out.lam_out = lam_out; out.r_out = r_out;
    out.dx = dx; out.lam = lam;
#define FAIL_AT_(tf, xf) do { s->t_last = (tf); rt_copy(nx, (xf), s->x_last); return st; } while (0)
    if ((st = gen_rt_engine_project(&e, t0, x))) return st;
    if ((st = gen_rt_events_start(&e, t0, x))) FAIL_AT_(t0, x);  /* hybrid={...} */
    if (in && in->period > 0 && (st = sample_(&e, t0, x))) FAIL_AT_(t0, x);
    if ((st = emit_row(&e, &out, 0, rows == 1, t0, x))) FAIL_AT_(t0, x);
    k = 1;
    while (k < rows) {
        gen_rt_real t_stop = o->method == GEN_RT_METHOD_RK4 ? row_time(&out, k) : t_end;
        int stop = 0, jump = 0;
        gen_rt_real te = 0;
        if (in) t_stop = gen_rt_input_next_break(&c, t, t_stop);
        if ((st = sample_(&e, t, x))) FAIL_AT_(t, x);
        c.t_seg = t;
        if ((st = gen_rt_engine_step(&e, t, t_stop))) FAIL_AT_(t, x);
        if ((st = gen_rt_events_step(&e, &stop, &jump, &te))) FAIL_AT_(t, x);
        /* a sample at t1 comes first: the rows at t1 show the new input */
        if (!stop && !jump && (st = sample_(&e, e.t1, e.xn))) FAIL_AT_(t, x);
        if ((st = step_rows_(&e, &out, &k, t, stop || jump, te))) FAIL_AT_(t, x);
        if (stop) {
            /* the run ends at the terminal event: its state is the last row */
            if ((st = emit_row(&e, &out, k, 1, te, e.xe))) FAIL_AT_(t, x);
            s->t_last = te;
            s->h_next = e.h_next;
            rt_copy(nx, e.xe, s->x_last);
            return GEN_RT_OK;
        }
        if (jump) {
            /* a hybrid jump at te: on from the state after it, the step
             * size history reset (the adaptive methods choose a first step
             * again; RK4 finishes its step from te) */
            rt_copy(nx, e.xe, x);
            t = te;
            e.f0_valid = 0;
            e.rejected_last = 0;
            e.err_old = GEN_RT_C(1e-4);
            e.h_next = 0;
            continue;
        }
        /* the inputs may change at a break: f at t1 is evaluated afresh */
        if (in && t_stop < t_end && e.t1 == t_stop) e.f0_valid = 0;
        rt_copy(nx, e.xn, x);
        t = e.t1;
    }
#undef FAIL_AT_
    s->t_last = t_end;
    s->h_next = e.h_next;
    rt_copy(nx, x, s->x_last);
    return GEN_RT_OK;
}

int gen_rt_model_simulate(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                          gen_rt_real t_end, gen_rt_real dt, const gen_rt_real *r,
                          const gen_rt_real *p, const gen_rt_sim_options *o, int capacity,
                          gen_rt_real *work, int *iwork, gen_rt_real *t_out,
                          gen_rt_real *x_out, gen_rt_real *lam_out, gen_rt_sim_stats *s)
{
    return simulate_(m, x0, t0, t_end, dt, r, NULL, NULL, p, o, capacity, work, iwork, t_out,
                     x_out, lam_out, NULL, s);
}

int gen_rt_model_simulate_input(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                                gen_rt_real t_end, gen_rt_real dt, const gen_rt_input *in,
                                const gen_rt_real *p, const gen_rt_sim_options *o,
                                int capacity, gen_rt_real *work, int *iwork,
                                gen_rt_real *t_out, gen_rt_real *x_out, gen_rt_real *lam_out,
                                gen_rt_real *r_out, gen_rt_sim_stats *s)
{
    int st = gen_rt_input_check(m, in);
    stats_reset(m, x0, t0, s);
    if (st) return st;
    return simulate_(m, x0, t0, t_end, dt, NULL, in, NULL, p, o, capacity, work, iwork, t_out,
                     x_out, lam_out, r_out, s);
}

int gen_rt_model_simulate_events(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                                 gen_rt_real t_end, gen_rt_real dt, const gen_rt_input *in,
                                 const gen_rt_events *ev, const gen_rt_real *p,
                                 const gen_rt_sim_options *o, int capacity, gen_rt_real *work,
                                 int *iwork, gen_rt_real *t_out, gen_rt_real *x_out,
                                 gen_rt_real *lam_out, gen_rt_real *r_out, gen_rt_sim_stats *s)
{
    int st = gen_rt_input_check(m, in);
    stats_reset(m, x0, t0, s);
    if (st) return st;
    return simulate_(m, x0, t0, t_end, dt, NULL, in, ev, p, o, capacity, work, iwork, t_out,
                     x_out, lam_out, r_out, s);
}
