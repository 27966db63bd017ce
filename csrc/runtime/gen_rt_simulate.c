/* gen_rt_simulate.c - integration of a model: the inputs during a run
 * (tables, feedback, controllers, sampling), one RK4 step, advance, and the
 * simulation engine behind simulate, simulate_input and simulate_events:
 * RK4 on the output grid, DOPRI5 and RODAS4 stepping by their error control
 * alone with dense output (the DOPRI5 continuous extension, cubic Hermite
 * for RK4 and RODAS4), projection after every step and on interpolated
 * rows, and events located on the dense output.
 *
 * As in gen_rt_model.c: inputs are assumed checked by the caller, work
 * arrays are the caller's, sized by the GEN_RT_MODEL_*_WORK macros. */
#include "gen_rt_private.h"

/* the methods and holds of gen/codegen/abi.py (gen_rt_abi.h) are those this file
 * implements (method_ok, input_check): one added there fails the build here */
#if GEN_RT_METHOD_COUNT != 3 || GEN_RT_HOLD_COUNT != 2
#error "gen/codegen/abi.py lists a method or table hold that gen_rt_simulate.c does not implement"
#endif

/* ------------------------------------------------------------------ */
/* Integration                                                        */
/* ------------------------------------------------------------------ */

/* what the integrators' callbacks see */
typedef struct {
    const gen_rt_model *m;
    const gen_rt_real *r, *p;
    gen_rt_real proj_tol;
    int proj_max_iter;
    gen_rt_real *work;  /* GEN_RT_MODEL_CB_WORK_ reals, shared by rhs and projection */
    int *iwork;
    /* inputs from a description (NULL: r is constant) */
    const gen_rt_input *in;
    gen_rt_real *r_buf;   /* nr: r at the current evaluation (continuous) */
    gen_rt_real *r_held;  /* nr: r held since the last sample (period > 0) */
    gen_rt_real t_seg;    /* start of the current sub-interval: a ZOH table's row */
    gen_rt_real t0;       /* start of the simulation: samples at t0 + k period */
    gen_rt_real t_sampled; /* time of the held sample (each sample is taken once) */
    int sampled;          /* 1 once a sample is held */
    /* hybrid={...}: the contacts held as constraints (gen_rt_hybrid.c) */
    int n_active;         /* 0: the model's own right-hand side */
    const int *active;    /* nh flags */
    gen_rt_real *hw;      /* GEN_RT_HYBRID_WORK */
    int *hiw;             /* GEN_RT_HYBRID_IWORK */
} model_ctx;

/* the last knot index k with T[k] <= t (0 before the first) */
static int table_row(int n, const gen_rt_real *T, gen_rt_real t)
{
    int lo = 0, hi = n - 1;
    if (t < T[0]) return 0;
    if (t >= T[n - 1]) return n - 1;
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (T[mid] <= t) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* a time within a relative rounding of a sample or knot counts as it */
static gen_rt_real time_tol(gen_rt_real t)
{
    gen_rt_real a = t < 0 ? -t : t;
    return 64 * GEN_RT_EPS * (a > 1 ? a : 1);
}

/* the gain schedule's row at t: the last k with t_gain + k dt_gain <= t
 * (within rounding), 0 before t_gain, n_gain - 1 after the end */
static int gain_row(const gen_rt_input *in, gen_rt_real t)
{
    gen_rt_real s = (t - in->t_gain) / in->dt_gain;
    long k;
    if (in->n_gain <= 1 || !(s > 0)) return 0;
    if (s >= (gen_rt_real)(in->n_gain - 1)) return in->n_gain - 1;
    k = (long)s;
    if (in->t_gain + (gen_rt_real)(k + 1) * in->dt_gain <= t + time_tol(t)) ++k;
    return (int)(k < in->n_gain - 1 ? k : in->n_gain - 1);
}

/* base, feedback and controller at t (a ZOH table and the gain schedule's
 * row at t_zoh) */
static int input_at(const gen_rt_model *m, const gen_rt_input *in, gen_rt_real t,
                    gen_rt_real t_zoh, const gen_rt_real *x, gen_rt_real *r)
{
    int nr = m->nr, nq = m->nq, niq = m->nq - m->mc, niu = m->nu - m->mv, ns = niq + niu;
    int i, j, k, g = in->n_gain > 0 ? gain_row(in, t_zoh) : 0;
    const gen_rt_real *K = in->K ? in->K + (long)g * nr * ns : NULL;
    const gen_rt_real *x_op = in->x_op ? in->x_op + (long)g * (nq + m->nu) : NULL;
    if (in->n_table > 0) {
        const gen_rt_real *T = in->t_table, *R = in->r_table;
        int n = in->n_table;
        if (in->hold == GEN_RT_HOLD_LINEAR && n > 1 && t > T[0] && t < T[n - 1]) {
            gen_rt_real w;
            k = table_row(n, T, t);
            w = (t - T[k]) / (T[k + 1] - T[k]);
            for (i = 0; i < nr; ++i)
                r[i] = R[(long)k * nr + i] + w * (R[(long)(k + 1) * nr + i] - R[(long)k * nr + i]);
        } else {
            k = table_row(n, T, in->hold == GEN_RT_HOLD_LINEAR ? t : t_zoh);
            for (i = 0; i < nr; ++i) r[i] = R[(long)k * nr + i];
        }
    } else {
        const gen_rt_real *r0 = in->r ? in->r + (long)g * nr : NULL;
        for (i = 0; i < nr; ++i) r[i] = r0 ? r0[i] : 0;
    }
    if (K) {
        for (i = 0; i < nr; ++i) {
            gen_rt_real s = 0;
            for (j = 0; j < ns; ++j) {
                int idx = j < niq ? m->q_ind[j] : nq + m->u_ind[j - niq];
                s += K[(long)i * ns + j] * (x[idx] - (x_op ? x_op[idx] : 0));
            }
            r[i] -= s;
        }
    }
    for (i = 0; i < nr; ++i) {
        if (in->r_min && r[i] < in->r_min[i]) r[i] = in->r_min[i];
        if (in->r_max && r[i] > in->r_max[i]) r[i] = in->r_max[i];
    }
    if (in->controller && in->controller(in->ctx, t, x, r)) return GEN_RT_ERR_CONTROLLER;
    if (!rt_finite(nr, r)) return GEN_RT_ERR_NONFINITE_INPUT;
    return GEN_RT_OK;
}

static int input_check(const gen_rt_model *m, const gen_rt_input *in)
{
    int i, nr = m->nr, ns = m->nq - m->mc + m->nu - m->mv, rows;
    if (!in) return GEN_RT_ERR_NULL;
    if (in->n_table < 0 || (in->hold != GEN_RT_HOLD_ZOH && in->hold != GEN_RT_HOLD_LINEAR))
        return GEN_RT_ERR_BAD_ARG;
    rows = in->n_gain > 0 ? in->n_gain : 1;    /* a schedule's rows */
    if (!rt_finite(1, &in->period) || in->period < 0) return GEN_RT_ERR_BAD_ARG;
    if (in->n_gain < 0 || (in->n_gain > 0 && !(rt_finite(1, &in->t_gain)
                                               && rt_finite(1, &in->dt_gain) && in->dt_gain > 0)))
        return GEN_RT_ERR_BAD_ARG;
    if (in->n_table > 0) {
        if (!in->t_table || (nr > 0 && !in->r_table)) return GEN_RT_ERR_NULL;
        if (!rt_finite(in->n_table, in->t_table) || !rt_finite(in->n_table * nr, in->r_table))
            return GEN_RT_ERR_NONFINITE_INPUT;
        for (i = 1; i < in->n_table; ++i)
            if (!(in->t_table[i] > in->t_table[i - 1])) return GEN_RT_ERR_BAD_ARG;
    } else if (in->r && !rt_finite(rows * nr, in->r)) {
        return GEN_RT_ERR_NONFINITE_INPUT;
    }
    for (i = 0; i < nr; ++i) {     /* bounds: infinite allowed, NaN or lo > hi not */
        gen_rt_real lo = in->r_min ? in->r_min[i] : 0, hi = in->r_max ? in->r_max[i] : 0;
        if (lo != lo || hi != hi) return GEN_RT_ERR_NONFINITE_INPUT;
        if (in->r_min && in->r_max && lo > hi) return GEN_RT_ERR_BAD_ARG;
    }
    if (in->K && !rt_finite(rows * nr * ns, in->K)) return GEN_RT_ERR_NONFINITE_INPUT;
    if (in->x_op && !rt_finite(rows * RT_NX(m), in->x_op)) return GEN_RT_ERR_NONFINITE_INPUT;
    return GEN_RT_OK;
}

int gen_rt_model_eval_input(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                            const gen_rt_input *in, gen_rt_real *r)
{
    int st = input_check(m, in);
    if (st) return st;
    return input_at(m, in, t, t, x, r);
}

static int rhs_cb(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *dxdt)
{
    const model_ctx *c = (const model_ctx *)ctx;
    const gen_rt_real *r = c->r;
    if (c->in && !(c->in->period > 0)) {
        int st = input_at(c->m, c->in, t, c->t_seg, x, c->r_buf);
        if (st) return st;
        r = c->r_buf;
    }
    if (c->n_active > 0)
        return gen_rt_hybrid_rhs(c->m, t, x, r, c->p, c->active, c->hw, c->hiw, dxdt, NULL);
    return gen_rt_model_rhs(c->m, t, x, r, c->p, c->work, c->iwork, dxdt, NULL);
}

int gen_rt_model_step_rk4(const gen_rt_model *m, gen_rt_real t, gen_rt_real h,
                          const gen_rt_real *r, const gen_rt_real *p, int project,
                          gen_rt_real *work, int *iwork, gen_rt_real *x)
{
    int nx = RT_NX(m), st;
    gen_rt_real *rk = work, *xn = rk + GEN_RT_RK4_WORK(nx);
    model_ctx c;
    c.m = m; c.r = r; c.p = p;
    c.proj_tol = 16 * GEN_RT_EPS; c.proj_max_iter = 10;
    c.work = xn + nx; c.iwork = iwork;
    c.in = NULL; c.r_buf = c.r_held = NULL; c.t_seg = t; c.t0 = t;
    c.t_sampled = t; c.sampled = 0;
    c.n_active = 0; c.active = NULL; c.hw = NULL; c.hiw = NULL;
    rt_copy(nx, x, xn);
    st = gen_rt_rk4_step(rhs_cb, &c, nx, t, h, rk, xn);
    if (st) return st;
    if (project) {
        st = gen_rt_model_project(m, t + h, p, c.proj_tol, c.proj_max_iter, c.work, xn);
        if (st) return st;
    }
    rt_copy(nx, xn, x);
    return GEN_RT_OK;
}

/* is t a sample time t0 + k period? */
static int is_sample(const model_ctx *c, gen_rt_real t)
{
    gen_rt_real per = c->in->period, k;
    if (!(per > 0)) return 0;
    k = (gen_rt_real)(long)((t - c->t0) / per + GEN_RT_C(0.5));
    return (t - (c->t0 + k * per)) <= time_tol(t) && (c->t0 + k * per - t) <= time_tol(t);
}

/* the end of the sub-interval from t towards t1: the next sample or knot */
static gen_rt_real next_break(const model_ctx *c, gen_rt_real t, gen_rt_real t1)
{
    const gen_rt_input *in = c->in;
    gen_rt_real tb = t1, tol = time_tol(t);
    if (in->period > 0) {
        long k = (long)((t - c->t0) / in->period) + 1;
        gen_rt_real ts = c->t0 + (gen_rt_real)k * in->period;
        if (ts <= t + tol) ts = c->t0 + (gen_rt_real)(k + 1) * in->period;
        if (ts < tb - time_tol(tb)) tb = ts;
    }
    if (in->n_gain > 1) {
        int k = gain_row(in, t + tol) + 1;
        gen_rt_real tk = in->t_gain + (gen_rt_real)k * in->dt_gain;
        if (k < in->n_gain && tk > t + tol && tk < tb - time_tol(tb)) tb = tk;
    }
    if (in->n_table > 0) {
        int k = table_row(in->n_table, in->t_table, t + tol);
        gen_rt_real tk;
        if (in->t_table[k] <= t + tol) ++k;
        if (k < in->n_table) {
            tk = in->t_table[k];
            if (tk > t + tol && tk < tb - time_tol(tb)) tb = tk;
        }
    }
    return tb;
}

/* ------------------------------------------------------------------ */
/* The engine                                                          */
/* ------------------------------------------------------------------ */

/* how a step can be evaluated inside: the DOPRI5 continuous extension,
 * a cubic Hermite interpolant (RK4, RODAS4), or not at all */
enum { DENSE_NONE, DENSE_DOPRI5, DENSE_HERMITE };

typedef struct {
    model_ctx *c;
    const gen_rt_sim_options *o;
    const gen_rt_events *ev;
    gen_rt_sim_stats *s;
    int nx, ny, need_y, dense_kind;
    gen_rt_real t_span;   /* t_end - t0: the scale of the first step */
    gen_rt_real *x;       /* the current state */
    gen_rt_real *xn;      /* the state after the step (projected) */
    gen_rt_real *xa, *xi, *xe; /* states inside the step */
    gen_rt_real *ya, *yb, *yi; /* outputs (ny) for output events */
    gen_rt_real *iw;      /* the method's scratch: GEN_RT_ENGINE_WORK_ reals */
    int *piv;             /* nx: RODAS4's pivots */
    /* the step just taken: from (t, x) to (t1, xn), h = t1 - t */
    gen_rt_real t, t1, h;
    const gen_rt_real *d_x1, *d_k, *d_f0, *d_f1;
    /* adaptive state */
    gen_rt_real h_next;   /* next trial step (<= 0: choose) */
    int rejected_last, f0_valid;
    gen_rt_real err_old;  /* DOPRI5's PI control: the last accepted error */
    long attempts;        /* since the last output row */
    /* hybrid={...}: nh declarations, event functions nev.. after the nev
     * user events (gen_rt_hybrid.c) */
    const gen_rt_hybrid *hy;
    int nev, nh;
    int *active, *rows;   /* nh: contacts held; the impulse's gaps */
    gen_rt_real *hw, *hva, *hvb, *hvi, *gd, *er, *xb; /* nh x 5, nx */
    int *hiw;
} engine;

/* err^(-1/q): the step-size factor's power, q = 5 (DOPRI5) or 4 (RODAS4) */
static gen_rt_real inv_root(gen_rt_real err, int q)
{
    return RT_POW(err, -GEN_RT_C(1.0) / (gen_rt_real)q);
}

/* the input in effect at (t, x) during the current step */
static int inputs_now(model_ctx *c, gen_rt_real t, const gen_rt_real *x, const gen_rt_real **r)
{
    int st;
    if (!c->in) { *r = c->r; return GEN_RT_OK; }
    if (c->in->period > 0) { *r = c->r_held; return GEN_RT_OK; }
    st = input_at(c->m, c->in, t, c->t_seg, x, c->r_buf);
    *r = c->r_buf;
    return st;
}

/* a sample of the inputs at t from x (each sample time once) */
static int sample_(engine *e, gen_rt_real t, const gen_rt_real *x)
{
    model_ctx *c = e->c;
    if (!c->in || !(c->in->period > 0) || !is_sample(c, t) || (c->sampled && c->t_sampled == t))
        return GEN_RT_OK;
    c->sampled = 1;
    c->t_sampled = t;
    e->f0_valid = 0;
    return input_at(c->m, c->in, t, t, x, c->r_held);
}

static int project_(engine *e, gen_rt_real t, gen_rt_real *x)
{
    const model_ctx *c = e->c;
    if (!e->o->project) return GEN_RT_OK;
    return gen_rt_model_project(c->m, t, c->p, c->proj_tol, c->proj_max_iter, c->work, x);
}

/* the state at t + theta h inside the step just taken (not projected) */
static void dense_at(const engine *e, gen_rt_real theta, gen_rt_real *out)
{
    if (theta >= 1) { rt_copy(e->nx, e->xn, out); return; }
    if (e->dense_kind == DENSE_DOPRI5)
        gen_rt_dopri5_dense(e->nx, e->h, theta, e->x, e->d_x1, e->d_k, out);
    else
        gen_rt_hermite(e->nx, e->h, theta, e->x, e->d_f0, e->xn, e->d_f1, out);
}

/* the RMS norm of v scaled by atol + rtol |x| */
static gen_rt_real scaled_rms(const engine *e, const gen_rt_real *x, const gen_rt_real *v)
{
    gen_rt_real s = 0;
    int i;
    for (i = 0; i < e->nx; ++i) {
        gen_rt_real r = v[i] / (e->o->atol + e->o->rtol * rt_abs(x[i]));
        s += r * r;
    }
    return RT_SQRT(s / (gen_rt_real)e->nx);
}

/* The starting step of Hairer's hinit (and SciPy's select_initial_step):
 * h0 from |x| / |f|, one Euler step to estimate the second derivative,
 * then h = min(100 h0, (0.01 / max(|f|, |f'|))^(1/q)), bounded by the span
 * and h_max. One evaluation of f (y1, f1: nx scratch each). */
static int first_step(engine *e, gen_rt_real t, const gen_rt_real *x, const gen_rt_real *f0,
                      int q, gen_rt_real *y1, gen_rt_real *f1)
{
    const gen_rt_sim_options *o = e->o;
    gen_rt_real d0, d1, d2, h0, h1, h;
    int i, st;
    if (o->h_init > 0) { e->h_next = o->h_init; return GEN_RT_OK; }
    d0 = scaled_rms(e, x, x);
    d1 = scaled_rms(e, x, f0);
    h0 = (d0 < GEN_RT_C(1e-5) || d1 < GEN_RT_C(1e-5)) ? GEN_RT_C(1e-6) : GEN_RT_C(0.01) * d0 / d1;
    if (e->t_span > 0) h0 = rt_min(h0, e->t_span);
    for (i = 0; i < e->nx; ++i) y1[i] = x[i] + h0 * f0[i];
    if ((st = rhs_cb(e->c, t + h0, y1, f1))) return st;
    e->s->n_rhs += 1;
    for (i = 0; i < e->nx; ++i) f1[i] -= f0[i];
    d2 = scaled_rms(e, x, f1) / h0;
    if (d1 <= GEN_RT_C(1e-15) && d2 <= GEN_RT_C(1e-15))
        h1 = rt_max(GEN_RT_C(1e-6), h0 * GEN_RT_C(1e-3));
    else
        h1 = RT_POW(GEN_RT_C(0.01) / rt_max(d1, d2), GEN_RT_C(1.0) / (gen_rt_real)q);
    h = rt_min(100 * h0, h1);
    if (e->t_span > 0) h = rt_min(h, e->t_span);
    e->h_next = h;
    return GEN_RT_OK;
}

/* after a trial: the next step size; returns 1 when the step is accepted.
 * q = 5, DOPRI5: Hairer's dopri5 control, a PI controller (beta = 0.04,
 * exponent 1/5 - 0.75 beta) with safety 0.9, the step changed by a factor
 * in [0.2, 10]. q = 4, RODAS4: the elementary controller err^(-1/4), safety
 * 0.9, factor in [0.2, 6] (Hairer's rodas). No increase right after a
 * rejection; a failed evaluation shrinks the step by 4. */
static int control_(engine *e, int st, gen_rt_real err, gen_rt_real hh, int last, int q)
{
    const gen_rt_sim_options *o = e->o;
    gen_rt_real fac, h_nat = e->h_next;
    const gen_rt_real fac_max = q == 5 ? GEN_RT_C(10.0) : GEN_RT_C(6.0);
    if (st || !(err <= GEN_RT_C(1.0))) {
        e->s->n_rejected += 1;
        if (st == 0 && err == err)
            fac = rt_max(GEN_RT_C(0.2), GEN_RT_C(0.9) * inv_root(err, q));
        else
            fac = GEN_RT_C(0.25); /* a failed evaluation: shrink towards it */
        e->h_next = hh * fac;
        e->rejected_last = 1;
        return 0;
    }
    if (q == 5) {
        gen_rt_real e0 = rt_max(err, GEN_RT_C(1e-10));
        fac = GEN_RT_C(0.9) * RT_POW(e0, -GEN_RT_C(0.17)) * RT_POW(e->err_old, GEN_RT_C(0.04));
        e->err_old = rt_max(err, GEN_RT_C(1e-4));
    } else {
        fac = err > 0 ? GEN_RT_C(0.9) * inv_root(err, q) : fac_max;
    }
    fac = rt_min(e->rejected_last ? GEN_RT_C(1.0) : fac_max, rt_max(GEN_RT_C(0.2), fac));
    /* a clipped step says little about the natural step */
    e->h_next = (last && fac >= GEN_RT_C(1.0)) ? rt_max(hh * fac, h_nat) : hh * fac;
    if (o->h_max > 0) e->h_next = rt_min(e->h_next, o->h_max);
    e->rejected_last = 0;
    e->s->n_accepted += 1;
    return 1;
}

/* the caller's cancellation flag is set (NULL: never) */
static int cancelled_(const gen_rt_sim_options *o)
{
    return o->cancel != NULL && *o->cancel != 0;
}

/* the next trial step from t towards t_stop: *hh, and *last when it is
 * clipped to reach t_stop (a step within 0.01% of it stretches to it) */
static int trial_size_(engine *e, gen_rt_real t, gen_rt_real t_stop, gen_rt_real hmin,
                       gen_rt_real *hh, int *last)
{
    long max_steps = e->o->max_steps > 0 ? e->o->max_steps : 100000L;
    if (cancelled_(e->o)) return GEN_RT_ERR_CANCELLED;
    if (e->attempts >= max_steps) return GEN_RT_ERR_MAX_STEPS;
    if (e->h_next < hmin) return GEN_RT_ERR_STEP_UNDERFLOW;
    e->attempts += 1;
    *hh = e->h_next;
    *last = 0;
    if (t + *hh >= t_stop || t + GEN_RT_C(1.0001) * *hh >= t_stop) {
        *hh = t_stop - t;
        *last = 1;
    }
    return GEN_RT_OK;
}

/* one accepted step from (t, e->x) towards t_stop: e->t1, e->xn (projected)
 * and what dense_at needs. A failure leaves e->x untouched. */
static int step_(engine *e, gen_rt_real t, gen_rt_real t_stop)
{
    model_ctx *c = e->c;
    const gen_rt_sim_options *o = e->o;
    const gen_rt_model *m = c->m;
    int nx = e->nx, i, st;
    gen_rt_real hmin = o->h_min > 0 ? o->h_min
                                    : 64 * GEN_RT_EPS * rt_max(GEN_RT_C(1.0), rt_abs(t_stop));
    e->t = t;
    if (cancelled_(o)) return GEN_RT_ERR_CANCELLED;
    if (o->method == GEN_RT_METHOD_RK4) {
        gen_rt_real *rk = e->iw, *f1 = rk + GEN_RT_RK4_WORK(nx);
        gen_rt_real h = t_stop - t;
        rt_copy(nx, e->x, e->xn);
        st = gen_rt_rk4_step(rhs_cb, c, nx, t, h, rk, e->xn);
        e->s->n_rhs += 4;
        if (!st) st = project_(e, t_stop, e->xn);
        if (st) return st;
        e->s->n_accepted += 1;
        e->t1 = t_stop;
        e->h = h;
        e->dense_kind = DENSE_NONE;
        if (e->nev + e->nh > 0) {
            /* the Hermite interpolant for events: f at the end as well */
            if ((st = rhs_cb(c, t_stop, e->xn, f1))) return st;
            e->s->n_rhs += 1;
            e->dense_kind = DENSE_HERMITE;
            e->d_f0 = rk;
            e->d_f1 = f1;
        }
        return GEN_RT_OK;
    }
    if (o->method == GEN_RT_METHOD_DOPRI5) {
        gen_rt_real *k = e->iw, *y = k + 7 * nx, *ynew = y + nx;
        if (e->f0_valid) {
            for (i = 0; i < nx; ++i) k[i] = k[6 * nx + i]; /* first same as last */
        } else {
            if ((st = rhs_cb(c, t, e->x, k))) return st;
            e->s->n_rhs += 1;
            e->f0_valid = 1;
        }
        if (e->h_next <= 0 && (st = first_step(e, t, e->x, k, 5, y, ynew))) return st;
        if (o->h_max > 0) e->h_next = rt_min(e->h_next, o->h_max);
        for (;;) {
            gen_rt_real hh, err = 0;
            int last = 0;
            if ((st = trial_size_(e, t, t_stop, hmin, &hh, &last))) return st;
            st = gen_rt_dopri5_trial(rhs_cb, c, nx, t, hh, e->x, o->rtol, o->atol, k, y, ynew,
                                     &err);
            e->s->n_rhs += 6;
            if (!control_(e, st, err, hh, last, 5)) {
                if (e->h_next < hmin) return st ? st : GEN_RT_ERR_STEP_UNDERFLOW;
                continue;
            }
            e->t1 = last ? t_stop : t + hh;
            e->h = hh;
            break;
        }
        rt_copy(nx, ynew, e->xn);
        if ((st = project_(e, e->t1, e->xn))) return st;
        /* k7 = f(t1, ynew) starts the next step unless projection moved it */
        for (i = 0; i < nx; ++i)
            if (e->xn[i] != ynew[i]) { e->f0_valid = 0; break; }
        e->dense_kind = DENSE_DOPRI5;
        e->d_x1 = ynew;
        e->d_k = k;
        return GEN_RT_OK;
    }
    if (o->method == GEN_RT_METHOD_RODAS4) {
        int nr = m->nr;
        gen_rt_real *f0 = e->iw, *f1 = f0 + nx, *dfdt = f1 + nx, *ynew = dfdt + nx,
                    *J = ynew + nx, *Jr = J + nx * nx, *rw = Jr + nx * nr + 1,
                    *jw = rw + GEN_RT_RODAS4_WORK(nx), *ft = jw;
        const gen_rt_real *r;
        gen_rt_real dt;
        if (e->f0_valid) {
            rt_copy(nx, f1, f0);
        } else {
            if ((st = rhs_cb(c, t, e->x, f0))) return st;
            e->s->n_rhs += 1;
        }
        /* J = df/dx of the closed loop: the model's, and a continuous linear
         * feedback's through df/dr (a controller callback's is not known) */
        if ((st = inputs_now(c, t, e->x, &r))) return st;
        st = gen_rt_model_jacobian(m, t, e->x, r, c->p, jw, c->iwork, J, nr ? Jr : NULL);
        if (st) return st;
        e->s->n_jac += 1;
        if (c->in && !(c->in->period > 0) && c->in->K && nr) {
            int niq = m->nq - m->mc, ns = niq + m->nu - m->mv, a, b, j;
            const gen_rt_real *K = c->in->K
                + (c->in->n_gain > 0 ? (long)gain_row(c->in, c->t_seg) * nr * ns : 0);
            for (j = 0; j < ns; ++j) {
                int col = j < niq ? m->q_ind[j] : m->nq + m->u_ind[j - niq];
                for (a = 0; a < nx; ++a) {
                    gen_rt_real sum = 0;
                    for (b = 0; b < nr; ++b) {
                        /* an input held at a bound does not follow the state */
                        if ((c->in->r_min && r[b] <= c->in->r_min[b])
                            || (c->in->r_max && r[b] >= c->in->r_max[b]))
                            continue;
                        sum += Jr[a * nr + b] * K[(long)b * ns + j];
                    }
                    J[a * nx + col] -= sum;
                }
            }
        }
        /* df/dt by a forward difference (the inputs' time dependence too),
         * with Hairer's increment sqrt(eps max(1e-5, |t|)) */
        dt = RT_SQRT(GEN_RT_EPS * rt_max(GEN_RT_C(1e-5), rt_abs(t)));
        if ((st = rhs_cb(c, t + dt, e->x, ft))) return st;
        e->s->n_rhs += 1;
        for (i = 0; i < nx; ++i) dfdt[i] = (ft[i] - f0[i]) / dt;
        if (e->h_next <= 0 && (st = first_step(e, t, e->x, f0, 4, ynew, ft))) return st;
        if (o->h_max > 0) e->h_next = rt_min(e->h_next, o->h_max);
        for (;;) {
            gen_rt_real hh, err = 0;
            int last = 0;
            if ((st = trial_size_(e, t, t_stop, hmin, &hh, &last))) return st;
            st = gen_rt_rodas4_trial(rhs_cb, c, nx, t, hh, e->x, f0, J, dfdt, o->rtol, o->atol,
                                     rw, e->piv, ynew, &err);
            e->s->n_rhs += 5;
            if (st == GEN_RT_ERR_SINGULAR && err < 0) {
                /* I/(h gamma) - J singular: a property of this step size,
                 * not of the model; rejected like a large error */
                st = GEN_RT_OK;
                err = GEN_RT_C(1e30);
            }
            if (!st && err <= GEN_RT_C(1.0)) {
                /* f at the new state: the interpolant's end and the next f0
                 * (a failure there rejects the step) */
                gen_rt_real t1 = last ? t_stop : t + hh;
                rt_copy(nx, ynew, e->xn);
                st = project_(e, t1, e->xn);
                if (!st) {
                    st = rhs_cb(c, t1, e->xn, f1);
                    e->s->n_rhs += 1;
                }
            }
            if (!control_(e, st, err, hh, last, 4)) {
                if (e->h_next < hmin) return st ? st : GEN_RT_ERR_STEP_UNDERFLOW;
                continue;
            }
            e->t1 = last ? t_stop : t + hh;
            e->h = hh;
            break;
        }
        e->f0_valid = 1;
        e->dense_kind = DENSE_HERMITE;
        e->d_f0 = f0;
        e->d_f1 = f1;
        return GEN_RT_OK;
    }
    return GEN_RT_ERR_BAD_ARG;
}

/* ---- events ---------------------------------------------------------- */

static int hybrid_check(const gen_rt_model *m, const gen_rt_events *ev);

static int events_check(const gen_rt_model *m, const gen_rt_events *ev)
{
    int i, nx = RT_NX(m), st;
    if (!ev || ev->n == 0) return hybrid_check(m, ev);
    if (ev->n < 0 || ev->capacity < 0) return GEN_RT_ERR_BAD_ARG;
    if ((st = hybrid_check(m, ev))) return st;
    if (!ev->which || !ev->direction) return GEN_RT_ERR_NULL;
    if (ev->capacity > 0 && (!ev->log_which || !ev->log_t || !ev->log_x)) return GEN_RT_ERR_NULL;
    if (ev->level && !rt_finite(ev->n, ev->level)) return GEN_RT_ERR_NONFINITE_INPUT;
    for (i = 0; i < ev->n; ++i) {
        if (ev->which[i] < 0 || ev->which[i] >= nx + m->ny) return GEN_RT_ERR_BAD_ARG;
        if (ev->direction[i] < -1 || ev->direction[i] > 1) return GEN_RT_ERR_BAD_ARG;
    }
    return GEN_RT_OK;
}

/* a hybrid model runs with its events struct's hybrid work */
static int hybrid_check(const gen_rt_model *m, const gen_rt_events *ev)
{
    if (!m->hybrid || m->hybrid->n <= 0) return GEN_RT_OK;
    if (!ev || ev->n < 0) return GEN_RT_ERR_BAD_ARG;
    if (!ev->hybrid_work || !ev->hybrid_iwork) return GEN_RT_ERR_NULL;
    if (ev->n > 0 && (!ev->which || !ev->direction)) return GEN_RT_ERR_NULL;
    if (ev->capacity < 0) return GEN_RT_ERR_BAD_ARG;
    if (ev->capacity > 0 && (!ev->log_which || !ev->log_t || !ev->log_x)) return GEN_RT_ERR_NULL;
    return GEN_RT_OK;
}

/* the outputs at (t, x) with the inputs of the current step */
static int outputs_(engine *e, gen_rt_real t, const gen_rt_real *x, gen_rt_real *y)
{
    const model_ctx *c = e->c;
    const gen_rt_real *r;
    int st;
    if (!e->need_y) return GEN_RT_OK;
    if ((st = inputs_now(e->c, t, x, &r))) return st;
    c->m->outputs(x, x + c->m->nq, r, c->p, t, y);
    return rt_finite(c->m->ny, y) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

/* the hybrid event values (nh) at (t, x): gaps and guards, the forces of
 * the contacts held */
static int hyb_values_(engine *e, gen_rt_real t, const gen_rt_real *x, gen_rt_real *v)
{
    model_ctx *c = e->c;
    const gen_rt_real *r;
    int st;
    if ((st = inputs_now(c, t, x, &r))) return st;
    return gen_rt_hybrid_values(c->m, t, x, r, c->p, e->active, e->hw, e->hiw, v);
}

/* event i's value: a user event (i < nev) from x and y, a hybrid one from
 * hv (its values at the same state) */
static gen_rt_real event_g(const engine *e, int i, const gen_rt_real *x, const gen_rt_real *y,
                           const gen_rt_real *hv)
{
    const gen_rt_events *ev = e->ev;
    int w;
    if (i >= e->nev) return hv[i - e->nev];
    w = ev->which[i];
    return (w < e->nx ? x[w] : y[w - e->nx]) - (ev->level ? ev->level[i] : 0);
}

/* the direction of event i: a contact held is released when its force
 * falls through zero */
static int event_dir(const engine *e, int i)
{
    int k = i - e->nev;
    if (i < e->nev) return e->ev->direction[i];
    return e->active[k] ? -1 : e->hy->direction[k];
}

static int crosses(int dir, gen_rt_real ga, gen_rt_real gb)
{
    return (dir >= 0 && ga < 0 && gb >= 0) || (dir <= 0 && ga > 0 && gb <= 0);
}

/* the crossing of event i in (lo, hi] on the dense output (Illinois, with a
 * bisection every third iteration): the end of the final bracket on the
 * side of gb, to a few units of rounding in t */
static int event_root(engine *e, int i, gen_rt_real lo, gen_rt_real hi, gen_rt_real glo,
                      gen_rt_real ghi, gen_rt_real *theta)
{
    gen_rt_real tol = 4 * GEN_RT_EPS * rt_max(GEN_RT_C(1.0), rt_max(rt_abs(e->t), rt_abs(e->t1)));
    int it, side = 0, st;
    for (it = 0; it < 300 && ghi != 0; ++it) {
        gen_rt_real mid, gm, tm;
        if ((hi - lo) * rt_abs(e->h) <= tol) break;
        mid = hi - ghi * (hi - lo) / (ghi - glo);
        if (it % 3 == 2 || !(mid > lo && mid < hi)) mid = GEN_RT_C(0.5) * (lo + hi);
        if (!(mid > lo && mid < hi)) break;
        dense_at(e, mid, e->xi);
        tm = e->t + mid * e->h;
        if (i >= e->nev) {
            if ((st = hyb_values_(e, tm, e->xi, e->hvi))) return st;
        } else if ((st = outputs_(e, tm, e->xi, e->yi))) {
            return st;
        }
        gm = event_g(e, i, e->xi, e->yi, e->hvi);
        if (gm == 0) { hi = mid; break; }
        if ((gm > 0) == (ghi > 0)) {
            hi = mid; ghi = gm;
            if (side == 1) glo *= GEN_RT_C(0.5);
            side = 1;
        } else {
            lo = mid; glo = gm;
            if (side == -1) ghi *= GEN_RT_C(0.5);
            side = -1;
        }
    }
    *theta = hi;
    return GEN_RT_OK;
}

/* a log row: event index, time, the state before and after */
static void log_event_(engine *e, int which, gen_rt_real t, const gen_rt_real *xb,
                       const gen_rt_real *xa)
{
    const gen_rt_events *ev = e->ev;
    gen_rt_sim_stats *s = e->s;
    if (s->n_events < ev->capacity) {
        ev->log_which[s->n_events] = which;
        ev->log_t[s->n_events] = t;
        rt_copy(e->nx, xb, ev->log_x + (long)s->n_events * e->nx);
        if (ev->log_x_after) rt_copy(e->nx, xa, ev->log_x_after + (long)s->n_events * e->nx);
    }
    s->n_events += 1;
}

static int count_active_(const engine *e)
{
    int k, n = 0;
    for (k = 0; k < e->nh; ++k) n += e->active[k] != 0;
    return n;
}

/* the jump of hybrid declaration k at (t, e->xe) (gen_rt_hybrid_jump),
 * logged; *jumped = 0 when nothing happens (a gap that is not closing) */
static int hybrid_jump_(engine *e, int k, gen_rt_real t, int *jumped)
{
    model_ctx *c = e->c;
    const gen_rt_real *r;
    int st, what = 0;
    *jumped = 0;
    rt_copy(e->nx, e->xe, e->xb);
    if ((st = inputs_now(c, t, e->xe, &r))) return st;
    st = gen_rt_hybrid_jump(c->m, t, r, c->p, k, c->proj_tol, c->proj_max_iter, c->work,
                            e->active, e->rows, e->hvi, e->hw, e->hiw, e->xe, &what);
    if (st) return st;
    if (!what) return GEN_RT_OK;
    c->n_active = count_active_(e);
    log_event_(e, e->nev + (what == GEN_RT_HYBRID_LIFTOFF ? e->nh : 0) + k, t, e->xb, e->xe);
    *jumped = 1;
    return GEN_RT_OK;
}

/* the events in the step just taken, in time order: logged, and *stop set
 * (with *te, e->xe) at the first terminal one; *jump set (with *te and the
 * state after in e->xe) at the first hybrid jump */
static int events_(engine *e, int *stop, int *jump, gen_rt_real *te)
{
    const gen_rt_events *ev = e->ev;
    gen_rt_sim_stats *s = e->s;
    gen_rt_real a = 0;
    int st, i, n = e->nev + e->nh;
    *stop = 0;
    *jump = 0;
    if (n <= 0) return GEN_RT_OK;
    if ((st = outputs_(e, e->t, e->x, e->ya))) return st;
    if ((st = outputs_(e, e->t1, e->xn, e->yb))) return st;
    if (e->nh > 0) {
        if ((st = hyb_values_(e, e->t, e->x, e->hva))) return st;
        if ((st = hyb_values_(e, e->t1, e->xn, e->hvb))) return st;
        /* a gap at zero that opens (just after an impact, or a contact
         * released) counts as open: its next closing is found */
        if ((st = gen_rt_hybrid_rates(e->c->m, e->t, e->x, e->c->p, e->hw, e->hiw, e->gd)))
            return st;
        for (i = 0; i < e->nh; ++i) {
            int d = e->hy->direction[i];
            if (e->active[i] || e->hy->kind[i] != GEN_RT_HYBRID_IMPACT) continue;
            if (d < 0 && e->hva[i] <= 0 && e->gd[i] > 0) e->hva[i] = GEN_RT_EPS * GEN_RT_EPS;
            if (d > 0 && e->hva[i] >= 0 && e->gd[i] < 0) e->hva[i] = -GEN_RT_EPS * GEN_RT_EPS;
        }
    }
    rt_copy(e->nx, e->x, e->xa);
    while (a < 1) {
        int best = -1;
        gen_rt_real th_best = 2, t_ev;
        for (i = 0; i < n; ++i) {
            gen_rt_real ga = event_g(e, i, e->xa, e->ya, e->hva);
            gen_rt_real gb = event_g(e, i, e->xn, e->yb, e->hvb), th;
            if (!crosses(event_dir(e, i), ga, gb)) continue;
            if ((st = event_root(e, i, a, 1, ga, gb, &th))) return st;
            if (th < th_best) { th_best = th; best = i; }
        }
        if (best < 0) break;
        t_ev = th_best >= 1 ? e->t1 : e->t + th_best * e->h;
        dense_at(e, th_best, e->xe);
        if (th_best < 1 && (st = project_(e, t_ev, e->xe))) return st;
        if (best >= e->nev) {
            int jumped = 0;
            if ((st = hybrid_jump_(e, best - e->nev, t_ev, &jumped))) return st;
            if (jumped) {
                *jump = 1;
                *te = t_ev;
                return GEN_RT_OK;
            }
        } else {
            log_event_(e, best, t_ev, e->xe, e->xe);
            if (ev->terminal && ev->terminal[best]) {
                *stop = 1;
                *te = t_ev;
                s->terminal = best;
                return GEN_RT_OK;
            }
        }
        /* search on from the dense output at the event (not the projected
         * state logged: projection may move the value back across the
         * level, and the same crossing would be found again) */
        a = th_best;
        dense_at(e, a, e->xa);
        if (a < 1 && (st = outputs_(e, t_ev, e->xa, e->ya))) return st;
        if (a < 1 && e->nh > 0 && (st = hyb_values_(e, t_ev, e->xa, e->hva))) return st;
    }
    return GEN_RT_OK;
}

/* ---- the drivers ----------------------------------------------------- */

/* the engine over the caller's work: layout shared by advance and simulate */
static void engine_init(engine *e, model_ctx *c, const gen_rt_sim_options *o,
                        const gen_rt_events *ev, gen_rt_sim_stats *s, gen_rt_real *x,
                        gen_rt_real *w, int *iwork, gen_rt_real *ybuf)
{
    const gen_rt_model *m = c->m;
    int nx = RT_NX(m), i;
    e->c = c; e->o = o; e->ev = ev; e->s = s;
    e->nx = nx; e->ny = m->ny; e->need_y = 0;
    if (ev && ev->n > 0 && m->ny > 0 && m->outputs)
        for (i = 0; i < ev->n; ++i) e->need_y |= ev->which[i] >= nx;
    e->x = x;
    e->xn = w; e->xa = w + nx; e->xi = w + 2 * nx; e->xe = w + 3 * nx;
    e->iw = w + 4 * nx;
    c->work = e->iw + GEN_RT_ENGINE_WORK_(m->nq, m->nu, m->mc, m->mv, m->nr,
                                          m->explicit_kinematics, m->accel);
    c->iwork = iwork;
    e->piv = iwork + GEN_RT_MODEL_RHS_IWORK(m->nq, m->nu, m->mc, m->mv, m->nr,
                                            m->explicit_kinematics, m->accel);
    e->ya = ybuf; e->yb = ybuf ? ybuf + m->ny + 1 : NULL; e->yi = ybuf ? e->yb + m->ny + 1 : NULL;
    e->dense_kind = DENSE_NONE;
    e->h_next = s->h_next; e->rejected_last = 0; e->f0_valid = 0; e->attempts = 0;
    e->err_old = GEN_RT_C(1e-4);
    e->t = e->t1 = e->h = 0;
    e->d_x1 = e->d_k = e->d_f0 = e->d_f1 = NULL;
    e->nev = (ev && ev->n > 0) ? ev->n : 0;
    e->hy = NULL; e->nh = 0; e->active = e->rows = e->hiw = NULL;
    e->hw = e->hva = e->hvb = e->hvi = e->gd = e->er = e->xb = NULL;
    if (m->hybrid && m->hybrid->n > 0 && ev && ev->hybrid_work && ev->hybrid_iwork) {
        int nh = m->hybrid->n;
        gen_rt_real *hx = ev->hybrid_work + GEN_RT_HYBRID_FN_WORK(m->nq, m->nu, m->mv, nh);
        e->hy = m->hybrid; e->nh = nh;
        e->hw = ev->hybrid_work; e->hiw = ev->hybrid_iwork;
        e->hva = hx; e->hvb = hx + nh; e->hvi = hx + 2 * nh; e->gd = hx + 3 * nh;
        e->er = hx + 4 * nh; e->xb = hx + 5 * nh;
        e->active = ev->hybrid_iwork + GEN_RT_HYBRID_FN_IWORK(m->nq, m->nu, m->mv, nh);
        e->rows = e->active + nh;
        for (i = 0; i < nh; ++i) e->active[i] = 0;
        c->active = e->active; c->n_active = 0;
        c->hw = e->hw; c->hiw = e->hiw;
    }
}

static int method_ok(const gen_rt_sim_options *o)
{
    if (o->method != GEN_RT_METHOD_RK4 && o->method != GEN_RT_METHOD_DOPRI5 &&
        o->method != GEN_RT_METHOD_RODAS4)
        return 0;
    if (o->method != GEN_RT_METHOD_RK4 &&
        (!(o->rtol >= 0) || !(o->atol >= 0) || !(o->rtol > 0 || o->atol > 0)))
        return 0;
    return 1;
}

int gen_rt_model_advance(const gen_rt_model *m, gen_rt_real t0, gen_rt_real t1,
                         const gen_rt_real *r, const gen_rt_real *p,
                         const gen_rt_sim_options *o, gen_rt_real *work, int *iwork,
                         gen_rt_sim_stats *s, gen_rt_real *x)
{
    int nx = RT_NX(m), st;
    gen_rt_real t = t0;
    model_ctx c;
    engine e;
    if (!(t1 >= t0) || !method_ok(o)) return GEN_RT_ERR_BAD_ARG;
    c.m = m; c.r = r; c.p = p;
    c.proj_tol = o->proj_tol; c.proj_max_iter = o->proj_max_iter;
    c.in = NULL; c.r_buf = c.r_held = NULL; c.t_seg = t0; c.t0 = t0;
    c.t_sampled = t0; c.sampled = 0;
    c.n_active = 0; c.active = NULL; c.hw = NULL; c.hiw = NULL;
    engine_init(&e, &c, o, NULL, s, x, work, iwork, NULL);
    e.t_span = t1 - t0;
    while (t < t1) {
        st = step_(&e, t, t1);
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
static int emit_row(engine *e, const row_sink *o, int k, int last, gen_rt_real tk,
                    const gen_rt_real *xr)
{
    model_ctx *c = e->c;
    const gen_rt_model *m = c->m;
    const gen_rt_sim_options *op = e->o;
    const gen_rt_real *rk = c->r;
    int nx = e->nx, nr = m->nr, mv = m->mv, ldl = mv > 0 ? mv : 1, i, st;
    gen_rt_sim_stats *s = e->s;
    if (c->in) {
        if (c->in->period > 0) {
            rk = c->r_held;
        } else {
            if ((st = input_at(m, c->in, tk, tk, xr, c->r_buf))) return st;
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
    model_ctx c;
    engine e;
    row_sink out;
    gen_rt_real t = t0;
    stats_reset(m, x0, t0, s);
    rt_copy(nx, x0, x);
    rows = gen_rt_simulate_rows(t0, t_end, dt);
    if (rows < 0) return rows;
    if (o->every < 0 || o->final_only < 0 || !method_ok(o)) return GEN_RT_ERR_BAD_ARG;
    if (capacity < gen_rt_simulate_rows_kept(rows, o->every, o->final_only))
        return GEN_RT_ERR_OUTPUT_FULL;
    if ((st = events_check(m, ev))) return st;
    c.m = m; c.p = p;
    c.proj_tol = o->proj_tol; c.proj_max_iter = o->proj_max_iter;
    c.in = in; c.t_seg = t0; c.t0 = t0; c.t_sampled = t0; c.sampled = 0;
    c.n_active = 0; c.active = NULL; c.hw = NULL; c.hiw = NULL;
    c.r_buf = in ? rb : NULL;
    c.r_held = in ? rb + nr + 1 : NULL;
    c.r = in ? (in->period > 0 ? c.r_held : c.r_buf) : r;
    engine_init(&e, &c, o, ev, s, x, w, iwork, (ev && ev->n > 0) ? yb : NULL);
    e.t_span = t_end - t0;
    out.rows = rows; out.capacity = capacity; out.t0 = t0; out.t_end = t_end; out.dt = dt;
    out.t_out = t_out; out.x_out = x_out; out.lam_out = lam_out; out.r_out = r_out;
    out.dx = dx; out.lam = lam;
#define FAIL_AT_(tf, xf) do { s->t_last = (tf); rt_copy(nx, (xf), s->x_last); return st; } while (0)
    if ((st = project_(&e, t0, x))) return st;
    if (in && in->period > 0 && (st = sample_(&e, t0, x))) FAIL_AT_(t0, x);
    if ((st = emit_row(&e, &out, 0, rows == 1, t0, x))) FAIL_AT_(t0, x);
    k = 1;
    while (k < rows) {
        gen_rt_real t_stop = o->method == GEN_RT_METHOD_RK4 ? row_time(&out, k) : t_end;
        int stop = 0, jump = 0;
        gen_rt_real te = 0;
        if (in) t_stop = next_break(&c, t, t_stop);
        if ((st = sample_(&e, t, x))) FAIL_AT_(t, x);
        c.t_seg = t;
        if ((st = step_(&e, t, t_stop))) FAIL_AT_(t, x);
        if ((st = events_(&e, &stop, &jump, &te))) FAIL_AT_(t, x);
        /* a sample at t1 comes first: the rows at t1 show the new input */
        if (!stop && !jump && (st = sample_(&e, e.t1, e.xn))) FAIL_AT_(t, x);
        while (k < rows) {
            gen_rt_real tk = row_time(&out, k), tol1 = time_tol(e.t1);
            const gen_rt_real *xr = e.xn;
            if ((stop || jump) ? !(tk < te - time_tol(te)) : !(tk <= e.t1 + tol1)) break;
            if (tk < e.t1 - tol1) {
                /* inside the step: the dense output, projected */
                dense_at(&e, (tk - t) / e.h, e.xi);
                if (!gen_rt_all_finite(nx, e.xi)) { st = GEN_RT_ERR_DIVERGED; FAIL_AT_(t, x); }
                if ((st = project_(&e, tk, e.xi))) FAIL_AT_(t, x);
                xr = e.xi;
            }
            if ((st = emit_row(&e, &out, k, k == rows - 1, tk, xr))) FAIL_AT_(t, x);
            ++k;
        }
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
    int st = input_check(m, in);
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
    int st = input_check(m, in);
    stats_reset(m, x0, t0, s);
    if (st) return st;
    return simulate_(m, x0, t0, t_end, dt, NULL, in, ev, p, o, capacity, work, iwork, t_out,
                     x_out, lam_out, r_out, s);
}
