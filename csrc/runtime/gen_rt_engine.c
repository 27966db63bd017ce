/* gen_rt_engine.c - the simulation engine's steps: the integrators'
 * callback (the model's right-hand side with the inputs of the run, or the
 * hybrid one with contacts held), one RK4 step (step_rk4), and one accepted
 * step of the engine behind advance and simulate: RK4 on the output grid,
 * DOPRI5 and RODAS4 stepping by their error control with dense output (the
 * DOPRI5 continuous extension, cubic Hermite for RK4 and RODAS4) and
 * projection after every step. The stages themselves are gen_rt_integrate.c's.
 *
 * As in gen_rt_model.c: inputs are assumed checked by the caller, work
 * arrays are the caller's, sized by the GEN_RT_MODEL_*_WORK macros. */
#include "gen_rt_private.h"

static int rhs_cb(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *dxdt)
{
    const gen_rt_sim_ctx *c = (const gen_rt_sim_ctx *)ctx;
    const gen_rt_real *r = c->r;
    if (c->in && !(c->in->period > 0)) {
        int st = gen_rt_input_at(c->m, c->in, t, c->t_seg, x, c->r_buf);
        if (st) return st;
        r = c->r_buf;
    }
    if (c->n_active > 0)
        return gen_rt_hybrid_rhs(c->m, t, x, r, c->p, c->active, c->hw, c->hiw, dxdt, NULL);
    return gen_rt_model_rhs(c->m, t, x, r, c->p, c->work, c->iwork, dxdt, NULL);
}

/* a context with constant inputs r from t0 (no inputs description, no
 * contacts held, no work yet) */
void gen_rt_sim_ctx_init(gen_rt_sim_ctx *c, const gen_rt_model *m, const gen_rt_real *r,
                         const gen_rt_real *p, gen_rt_real proj_tol, int proj_max_iter,
                         gen_rt_real t0)
{
    c->m = m; c->r = r; c->p = p;
    c->proj_tol = proj_tol; c->proj_max_iter = proj_max_iter;
    c->work = NULL; c->iwork = NULL;
    c->in = NULL; c->r_buf = c->r_held = NULL; c->t_seg = t0; c->t0 = t0;
    c->t_sampled = t0; c->sampled = 0;
    c->n_active = 0; c->active = NULL; c->hw = NULL; c->hiw = NULL;
}

int gen_rt_model_step_rk4(const gen_rt_model *m, gen_rt_real t, gen_rt_real h,
                          const gen_rt_real *r, const gen_rt_real *p, int project,
                          gen_rt_real *work, int *iwork, gen_rt_real *x)
{
    int nx = RT_NX(m), st;
    gen_rt_real *rk = work, *xn = rk + GEN_RT_RK4_WORK(nx);
    gen_rt_sim_ctx c;
    gen_rt_sim_ctx_init(&c, m, r, p, 16 * GEN_RT_EPS, 10, t);
    c.work = xn + nx; c.iwork = iwork;
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

/* err^(-1/q): the step-size factor's power, q = 5 (DOPRI5) or 4 (RODAS4) */
static gen_rt_real inv_root(gen_rt_real err, int q)
{
    return RT_POW(err, -GEN_RT_C(1.0) / (gen_rt_real)q);
}

/* x projected onto the constraints when the options ask for it */
int gen_rt_engine_project(gen_rt_engine *e, gen_rt_real t, gen_rt_real *x)
{
    const gen_rt_sim_ctx *c = e->c;
    if (!e->o->project) return GEN_RT_OK;
    return gen_rt_model_project(c->m, t, c->p, c->proj_tol, c->proj_max_iter, c->work, x);
}

/* the state at t + theta h inside the step just taken (not projected) */
void gen_rt_engine_dense(const gen_rt_engine *e, gen_rt_real theta, gen_rt_real *out)
{
    if (theta >= 1) { rt_copy(e->nx, e->xn, out); return; }
    if (e->dense_kind == GEN_RT_DENSE_DOPRI5)
        gen_rt_dopri5_dense(e->nx, e->h, theta, e->x, e->d_x1, e->d_k, out);
    else
        gen_rt_hermite(e->nx, e->h, theta, e->x, e->d_f0, e->xn, e->d_f1, out);
}

/* the RMS norm of v scaled by atol + rtol |x| */
static gen_rt_real scaled_rms(const gen_rt_engine *e, const gen_rt_real *x,
                              const gen_rt_real *v)
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
static int first_step(gen_rt_engine *e, gen_rt_real t, const gen_rt_real *x,
                      const gen_rt_real *f0, int q, gen_rt_real *y1, gen_rt_real *f1)
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
static int control_(gen_rt_engine *e, int st, gen_rt_real err, gen_rt_real hh, int last,
                    int q)
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
static int trial_size_(gen_rt_engine *e, gen_rt_real t, gen_rt_real t_stop,
                       gen_rt_real hmin, gen_rt_real *hh, int *last)
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

/* RK4 from t to t_stop in one step (the output grid's), and f at the end
 * for the Hermite interpolant when there are events */
static int step_rk4_(gen_rt_engine *e, gen_rt_real t, gen_rt_real t_stop)
{
    gen_rt_sim_ctx *c = e->c;
    int nx = e->nx, st;
    gen_rt_real *rk = e->iw, *f1 = rk + GEN_RT_RK4_WORK(nx);
    gen_rt_real h = t_stop - t;
    rt_copy(nx, e->x, e->xn);
    st = gen_rt_rk4_step(rhs_cb, c, nx, t, h, rk, e->xn);
    e->s->n_rhs += 4;
    if (!st) st = gen_rt_engine_project(e, t_stop, e->xn);
    if (st) return st;
    e->s->n_accepted += 1;
    e->t1 = t_stop;
    e->h = h;
    e->dense_kind = GEN_RT_DENSE_NONE;
    if (e->nev + e->nh > 0) {
        /* the Hermite interpolant for events: f at the end as well */
        if ((st = rhs_cb(c, t_stop, e->xn, f1))) return st;
        e->s->n_rhs += 1;
        e->dense_kind = GEN_RT_DENSE_HERMITE;
        e->d_f0 = rk;
        e->d_f1 = f1;
    }
    return GEN_RT_OK;
}

/* DOPRI5 trials from t towards t_stop until one is accepted */
static int step_dopri5_(gen_rt_engine *e, gen_rt_real t, gen_rt_real t_stop, gen_rt_real hmin)
{
    gen_rt_sim_ctx *c = e->c;
    const gen_rt_sim_options *o = e->o;
    int nx = e->nx, i, st;
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
    if ((st = gen_rt_engine_project(e, e->t1, e->xn))) return st;
    /* k7 = f(t1, ynew) starts the next step unless projection moved it */
    for (i = 0; i < nx; ++i)
        if (e->xn[i] != ynew[i]) { e->f0_valid = 0; break; }
    e->dense_kind = GEN_RT_DENSE_DOPRI5;
    e->d_x1 = ynew;
    e->d_k = k;
    return GEN_RT_OK;
}

/* RODAS4's J = df/dx of the closed loop at (t, e->x): the model's, and a
 * continuous linear feedback's through df/dr (a controller callback's is
 * not known); Jr (nx x nr) and jw the Jacobian's scratch */
static int rodas4_jacobian_(gen_rt_engine *e, gen_rt_real t, gen_rt_real *J, gen_rt_real *Jr,
                            gen_rt_real *jw)
{
    gen_rt_sim_ctx *c = e->c;
    const gen_rt_model *m = c->m;
    int nx = e->nx, nr = m->nr, st;
    const gen_rt_real *r;
    if ((st = gen_rt_input_now(c, t, e->x, &r))) return st;
    st = gen_rt_model_jacobian(m, t, e->x, r, c->p, jw, c->iwork, J, nr ? Jr : NULL);
    if (st) return st;
    e->s->n_jac += 1;
    if (c->in && !(c->in->period > 0) && c->in->K && nr) {
        int niq = m->nq - m->mc, ns = niq + m->nu - m->mv, a, b, j;
        const gen_rt_real *K = c->in->K
            + (c->in->n_gain > 0 ? (long)gen_rt_input_gain_row(c->in, c->t_seg) * nr * ns : 0);
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
    return GEN_RT_OK;
}

/* RODAS4 trials from t towards t_stop until one is accepted: the Jacobian
 * and df/dt once, f at the accepted state (the next f0) */
static int step_rodas4_(gen_rt_engine *e, gen_rt_real t, gen_rt_real t_stop, gen_rt_real hmin)
{
    gen_rt_sim_ctx *c = e->c;
    const gen_rt_sim_options *o = e->o;
    int nx = e->nx, nr = c->m->nr, i, st;
    gen_rt_real *f0 = e->iw, *f1 = f0 + nx, *dfdt = f1 + nx, *ynew = dfdt + nx,
                *J = ynew + nx, *Jr = J + nx * nx, *rw = Jr + nx * nr + 1,
                *jw = rw + GEN_RT_RODAS4_WORK(nx), *ft = jw;
    gen_rt_real dt;
    if (e->f0_valid) {
        rt_copy(nx, f1, f0);
    } else {
        if ((st = rhs_cb(c, t, e->x, f0))) return st;
        e->s->n_rhs += 1;
    }
    if ((st = rodas4_jacobian_(e, t, J, Jr, jw))) return st;
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
            st = gen_rt_engine_project(e, t1, e->xn);
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
    e->dense_kind = GEN_RT_DENSE_HERMITE;
    e->d_f0 = f0;
    e->d_f1 = f1;
    return GEN_RT_OK;
}

/* one accepted step from (t, e->x) towards t_stop: e->t1, e->xn (projected)
 * and what gen_rt_engine_dense needs. A failure leaves e->x untouched. */
int gen_rt_engine_step(gen_rt_engine *e, gen_rt_real t, gen_rt_real t_stop)
{
    const gen_rt_sim_options *o = e->o;
    gen_rt_real hmin = o->h_min > 0 ? o->h_min
                                    : 64 * GEN_RT_EPS * rt_max(GEN_RT_C(1.0), rt_abs(t_stop));
    e->t = t;
    if (cancelled_(o)) return GEN_RT_ERR_CANCELLED;
    if (o->method == GEN_RT_METHOD_RK4) return step_rk4_(e, t, t_stop);
    if (o->method == GEN_RT_METHOD_DOPRI5) return step_dopri5_(e, t, t_stop, hmin);
    if (o->method == GEN_RT_METHOD_RODAS4) return step_rodas4_(e, t, t_stop, hmin);
    return GEN_RT_ERR_BAD_ARG;
}

/* the engine over the caller's work: layout shared by advance and simulate */
void gen_rt_engine_init(gen_rt_engine *e, gen_rt_sim_ctx *c, const gen_rt_sim_options *o,
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
    e->ya = ybuf;
    e->yb = ybuf ? ybuf + m->ny + 1 : NULL;
    e->yi = ybuf ? e->yb + m->ny + 1 : NULL;
    e->dense_kind = GEN_RT_DENSE_NONE;
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

/* 1 when o names a method the engine has, with usable tolerances */
int gen_rt_engine_method_ok(const gen_rt_sim_options *o)
{
    if (o->method != GEN_RT_METHOD_RK4 && o->method != GEN_RT_METHOD_DOPRI5 &&
        o->method != GEN_RT_METHOD_RODAS4)
        return 0;
    if (o->method != GEN_RT_METHOD_RK4 &&
        (!(o->rtol >= 0) || !(o->atol >= 0) || !(o->rtol > 0 || o->atol > 0)))
        return 0;
    return 1;
}
