/* gen_rt_events.c - events and hybrid jumps in a step of the engine
 * (gen_rt.h, "events during a simulation"; gen_rt_hybrid.c): the crossings
 * of the user's events and of the hybrid declarations' gaps, guards and
 * contact forces found between the ends of the step just taken, located on
 * its dense output (Illinois), logged in time order; a terminal event ends
 * the run, a hybrid jump (impact, reset, lift-off) restarts it.
 *
 * As in gen_rt_model.c: inputs are assumed checked by the caller. */
#include "gen_rt_private.h"

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

int gen_rt_events_check(const gen_rt_model *m, const gen_rt_events *ev)
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

/* the outputs at (t, x) with the inputs of the current step */
static int outputs_(gen_rt_engine *e, gen_rt_real t, const gen_rt_real *x, gen_rt_real *y)
{
    const gen_rt_sim_ctx *c = e->c;
    const gen_rt_real *r;
    int st;
    if (!e->need_y) return GEN_RT_OK;
    if ((st = gen_rt_input_now(e->c, t, x, &r))) return st;
    c->m->outputs(x, x + c->m->nq, r, c->p, t, y);
    return rt_finite(c->m->ny, y) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

/* the hybrid event values (nh) at (t, x): gaps and guards, the forces of
 * the contacts held */
static int hyb_values_(gen_rt_engine *e, gen_rt_real t, const gen_rt_real *x, gen_rt_real *v)
{
    gen_rt_sim_ctx *c = e->c;
    const gen_rt_real *r;
    int st;
    if ((st = gen_rt_input_now(c, t, x, &r))) return st;
    return gen_rt_hybrid_values(c->m, t, x, r, c->p, e->active, e->hw, e->hiw, v);
}

/* event i's value: a user event (i < nev) from x and y, a hybrid one from
 * hv (its values at the same state) */
static gen_rt_real event_g(const gen_rt_engine *e, int i, const gen_rt_real *x,
                           const gen_rt_real *y, const gen_rt_real *hv)
{
    const gen_rt_events *ev = e->ev;
    int w;
    if (i >= e->nev) return hv[i - e->nev];
    w = ev->which[i];
    return (w < e->nx ? x[w] : y[w - e->nx]) - (ev->level ? ev->level[i] : 0);
}

/* the direction of event i: a contact held is released when its force
 * falls through zero */
static int event_dir(const gen_rt_engine *e, int i)
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
static int event_root(gen_rt_engine *e, int i, gen_rt_real lo, gen_rt_real hi, gen_rt_real glo,
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
        gen_rt_engine_dense(e, mid, e->xi);
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
static void log_event_(gen_rt_engine *e, int which, gen_rt_real t, const gen_rt_real *xb,
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

static int count_active_(const gen_rt_engine *e)
{
    int k, n = 0;
    for (k = 0; k < e->nh; ++k) n += e->active[k] != 0;
    return n;
}

/* the log's entries of a jump of declaration k at t (what: gen_rt_hybrid_jump's)
 * from e->xb to e->xe: the jump (or the lift-off), then each contact held
 * from now on that was not before (held0) */
static void log_jump_(gen_rt_engine *e, int k, gen_rt_real t, int what, const int *held0)
{
    int j;
    log_event_(e, e->nev + (what == GEN_RT_HYBRID_LIFTOFF ? e->nh : 0) + k, t, e->xb, e->xe);
    for (j = 0; j < e->nh; ++j)
        if (e->active[j] && !held0[j])
            log_event_(e, e->nev + GEN_RT_HYBRID_LOG_HOLD * e->nh + j, t, e->xe, e->xe);
}

/* the jump of hybrid declaration k at (t, e->xe) (gen_rt_hybrid_jump);
 * *jumped = 0 when nothing happens (a gap that is not closing). Logged
 * with logged = 1; with logged = 0 the caller logs (log_jump_). A jump
 * that fails is logged with the map's state (NaN where it is not finite),
 * for the caller's message. held0: nh ints, the last of the hybrid iwork
 * (GEN_RT_HYBRID_IWORK), the contacts held before. */
static int hybrid_jump_(gen_rt_engine *e, int k, gen_rt_real t, int logged, int *jumped)
{
    gen_rt_sim_ctx *c = e->c;
    const gen_rt_real *r;
    int *held0 = e->rows + e->nh;
    int st, what = 0, j;
    *jumped = 0;
    rt_copy(e->nx, e->xe, e->xb);
    for (j = 0; j < e->nh; ++j) held0[j] = e->active[j];
    if ((st = gen_rt_input_now(c, t, e->xe, &r))) return st;
    st = gen_rt_hybrid_jump(c->m, t, r, c->p, k, c->proj_tol, c->proj_max_iter, c->work,
                            e->active, e->rows, e->hvi, e->hw, e->hiw, e->xe, &what);
    if (st) {
        log_event_(e, e->nev + k, t, e->xb, e->xe);
        return st;
    }
    if (!what) return GEN_RT_OK;
    c->n_active = count_active_(e);
    if (logged) log_jump_(e, k, t, what, held0);
    *jumped = 1;
    return GEN_RT_OK;
}

int gen_rt_events_start(gen_rt_engine *e, gen_rt_real t0, gen_rt_real *x)
{
    gen_rt_sim_ctx *c = e->c;
    gen_rt_real tol = 1;
    int k, j, st, which, jumped = 0, changed = 0;
    const int *held0;
    if (e->nh <= 0) return GEN_RT_OK;
    held0 = e->rows + e->nh;
    st = gen_rt_hybrid_penetrated(c->m, t0, x, c->p, e->hva, &which);
    if (st == GEN_RT_ERR_PENETRATED) log_event_(e, e->nev + which, t0, x, x);
    if (st) return st;
    if ((st = gen_rt_hybrid_rates(c->m, t0, x, c->p, e->hw, e->hiw, e->gd))) return st;
    for (j = 0; j < e->nx; ++j) tol = rt_max(tol, rt_abs(x[j]));
    tol *= 1024 * GEN_RT_EPS;
    for (k = 0; k < e->nh; ++k) {
        int d = e->hy->direction[k];
        /* a gap at zero that closes, or rests there: the impact (and the
         * contact held while it pushes) at t0 */
        if (e->hy->kind[k] != GEN_RT_HYBRID_IMPACT || d == 0 || !(rt_abs(e->hva[k]) <= tol) ||
            !((gen_rt_real)d * e->gd[k] >= 0))
            continue;
        rt_copy(e->nx, x, e->xe);
        if ((st = hybrid_jump_(e, k, t0, 0, &jumped))) return st;
        if (!jumped) break;
        for (j = 0; j < e->nx; ++j) changed |= e->xe[j] != x[j];
        for (j = 0; j < e->nh; ++j) changed |= e->active[j] && !held0[j];
        if (changed) {     /* else a contact at rest whose force would pull: nothing */
            log_jump_(e, k, t0, GEN_RT_HYBRID_IMPACT + 1, held0);
            rt_copy(e->nx, e->xe, x);
        }
        break;
    }
    return GEN_RT_OK;
}

/* the events in the step just taken, in time order: logged, and *stop set
 * (with *te, e->xe) at the first terminal one; *jump set (with *te and the
 * state after in e->xe) at the first hybrid jump */
int gen_rt_events_step(gen_rt_engine *e, int *stop, int *jump, gen_rt_real *te)
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
        gen_rt_engine_dense(e, th_best, e->xe);
        if (th_best < 1 && (st = gen_rt_engine_project(e, t_ev, e->xe))) return st;
        if (best >= e->nev) {
            int jumped = 0;
            if ((st = hybrid_jump_(e, best - e->nev, t_ev, 1, &jumped))) return st;
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
        gen_rt_engine_dense(e, a, e->xa);
        if (a < 1 && (st = outputs_(e, t_ev, e->xa, e->ya))) return st;
        if (a < 1 && e->nh > 0 && (st = hyb_values_(e, t_ev, e->xa, e->hva))) return st;
    }
    return GEN_RT_OK;
}
