/* gen_rt_input.c - the inputs during a run (gen_rt.h, "inputs during a
 * simulation"): a table held or interpolated, a linear feedback on the
 * independent state with one gain or a schedule of gains, bounds, the
 * user's controller, and a digital controller's samples and the step
 * boundaries they and the knots make. The engine (gen_rt_engine.c) calls
 * these at every evaluation of the right-hand side; the row drivers
 * (gen_rt_simulate.c) at the output rows and the sub-intervals' ends.
 *
 * As in gen_rt_model.c: inputs are assumed checked by the caller. */
#include "gen_rt_private.h"

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

/* the gain schedule's row at t: the last k with t_gain + k dt_gain <= t
 * (within rounding), 0 before t_gain, n_gain - 1 after the end */
int gen_rt_input_gain_row(const gen_rt_input *in, gen_rt_real t)
{
    gen_rt_real s = (t - in->t_gain) / in->dt_gain;
    long k;
    if (in->n_gain <= 1 || !(s > 0)) return 0;
    if (s >= (gen_rt_real)(in->n_gain - 1)) return in->n_gain - 1;
    k = (long)s;
    if (in->t_gain + (gen_rt_real)(k + 1) * in->dt_gain <= t + rt_time_tol(t)) ++k;
    return (int)(k < in->n_gain - 1 ? k : in->n_gain - 1);
}

/* base, feedback and controller at t (a ZOH table and the gain schedule's
 * row at t_zoh) */
int gen_rt_input_at(const gen_rt_model *m, const gen_rt_input *in, gen_rt_real t,
                    gen_rt_real t_zoh, const gen_rt_real *x, gen_rt_real *r)
{
    int nr = m->nr, nq = m->nq, niq = m->nq - m->mc, niu = m->nu - m->mv, ns = niq + niu;
    int i, j, k, g = in->n_gain > 0 ? gen_rt_input_gain_row(in, t_zoh) : 0;
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

int gen_rt_input_check(const gen_rt_model *m, const gen_rt_input *in)
{
    int i, nr = m->nr, ns = m->nq - m->mc + m->nu - m->mv, rows;
    if (!in) return GEN_RT_ERR_NULL;
    if (in->n_table < 0 || (in->hold != GEN_RT_HOLD_ZOH && in->hold != GEN_RT_HOLD_LINEAR))
        return GEN_RT_ERR_BAD_ARG;
    rows = in->n_gain > 0 ? in->n_gain : 1;    /* a schedule's rows */
    if (!rt_finite(1, &in->period) || in->period < 0) return GEN_RT_ERR_BAD_ARG;
    if (in->n_gain < 0 || (in->n_gain > 0 && !(rt_finite(1, &in->t_gain) &&
                                               rt_finite(1, &in->dt_gain) &&
                                               in->dt_gain > 0)))
        return GEN_RT_ERR_BAD_ARG;
    if (in->n_table > 0) {
        if (!in->t_table || (nr > 0 && !in->r_table)) return GEN_RT_ERR_NULL;
        if (!rt_finite(in->n_table, in->t_table) ||
            !rt_finite(in->n_table * nr, in->r_table))
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
    if (in->x_op && !rt_finite(rows * RT_NX(m), in->x_op))
        return GEN_RT_ERR_NONFINITE_INPUT;
    return GEN_RT_OK;
}

int gen_rt_model_eval_input(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                            const gen_rt_input *in, gen_rt_real *r)
{
    int st = gen_rt_input_check(m, in);
    if (st) return st;
    return gen_rt_input_at(m, in, t, t, x, r);
}

/* the input in effect at (t, x) during the current step */
int gen_rt_input_now(gen_rt_sim_ctx *c, gen_rt_real t, const gen_rt_real *x,
                     const gen_rt_real **r)
{
    int st;
    if (!c->in) { *r = c->r; return GEN_RT_OK; }
    if (c->in->period > 0) { *r = c->r_held; return GEN_RT_OK; }
    st = gen_rt_input_at(c->m, c->in, t, c->t_seg, x, c->r_buf);
    *r = c->r_buf;
    return st;
}

/* is t a sample time t0 + k period? */
static int is_sample(const gen_rt_sim_ctx *c, gen_rt_real t)
{
    gen_rt_real per = c->in->period, k;
    if (!(per > 0)) return 0;
    k = (gen_rt_real)(long)((t - c->t0) / per + GEN_RT_C(0.5));
    return (t - (c->t0 + k * per)) <= rt_time_tol(t) && (c->t0 + k * per - t) <= rt_time_tol(t);
}

/* a sample of the inputs at t from x (each sample time once) */
int gen_rt_input_sample(gen_rt_sim_ctx *c, gen_rt_real t, const gen_rt_real *x, int *taken)
{
    *taken = 0;
    if (!c->in || !(c->in->period > 0) || !is_sample(c, t) || (c->sampled && c->t_sampled == t))
        return GEN_RT_OK;
    c->sampled = 1;
    c->t_sampled = t;
    *taken = 1;
    return gen_rt_input_at(c->m, c->in, t, t, x, c->r_held);
}

/* the end of the sub-interval from t towards t1: the next sample or knot */
gen_rt_real gen_rt_input_next_break(const gen_rt_sim_ctx *c, gen_rt_real t, gen_rt_real t1)
{
    const gen_rt_input *in = c->in;
    gen_rt_real tb = t1, tol = rt_time_tol(t);
    if (in->period > 0) {
        long k = (long)((t - c->t0) / in->period) + 1;
        gen_rt_real ts = c->t0 + (gen_rt_real)k * in->period;
        if (ts <= t + tol) ts = c->t0 + (gen_rt_real)(k + 1) * in->period;
        if (ts < tb - rt_time_tol(tb)) tb = ts;
    }
    if (in->n_gain > 1) {
        int k = gen_rt_input_gain_row(in, t + tol) + 1;
        gen_rt_real tk = in->t_gain + (gen_rt_real)k * in->dt_gain;
        if (k < in->n_gain && tk > t + tol && tk < tb - rt_time_tol(tb)) tb = tk;
    }
    if (in->n_table > 0) {
        int k = table_row(in->n_table, in->t_table, t + tol);
        gen_rt_real tk;
        if (in->t_table[k] <= t + tol) ++k;
        if (k < in->n_table) {
            tk = in->t_table[k];
            if (tk > t + tol && tk < tb - rt_time_tol(tb)) tb = tk;
        }
    }
    return tb;
}
