/*
 * gen_rt_casadi_inline.h - gen_rt_cs_eval (gen_rt_casadi.h) as a static
 * inline function, gen_rt_cs_eval_inline (the same arguments, the same
 * bits), over gen_rt_deriv_inline.h.
 *
 * gen_rt_casadi_extern.c defines the library function over it. A CasADi library
 * (<name>_casadi.c) includes this header and calls it with its model, a
 * static const gen_rt_cs_model, from one function of its own: the
 * compiler specializes the whole call tree for the model's sizes and
 * kernels (gen_rt_deriv_inline.h).
 *
 * The inputs read, the base function or its derivatives computed over the
 * function's differentiable inputs v (its inputs side by side), the
 * outputs laid out as CasADi's dense column-major blocks.
 */
#ifndef GEN_RT_CASADI_INLINE_H
#define GEN_RT_CASADI_INLINE_H

#include "gen_rt.h"
#include "gen_rt_casadi.h"
#include "gen_rt_deriv_inline.h"

/* one call: the function's sizes (the model's are m's), each input's
 * entries (size), where each input's columns start among v (off, -1: not
 * an input), whether z's columns are v's first, and the inputs: x, r, p
 * inside z = (x, r, p, t) */
typedef struct {
    int nv, nrow, nin;
    int size[GEN_RT_CS_MAX_IN], off[GEN_RT_CS_H + 1];
    int zfirst;                /* z's columns are v's first nz, in order */
    gen_rt_real *x, *xd, *r, *p, *z, t, h;
} rt_cs_call;

GEN_RT_DERIV_ALWAYS void rt_cs_in(const gen_rt_real *a, int n, gen_rt_real *d)
{
    int i;
    for (i = 0; i < n; ++i) d[i] = a ? a[i] : 0;
}

GEN_RT_DERIV_ALWAYS int rt_cs_rows(const gen_rt_cs_model *m, int base)
{
    const int nx = m->nq + m->nu;
    switch (base) {
    case GEN_RT_CS_IMPLICIT: return nx + m->mc + m->mv;
    case GEN_RT_CS_OUTPUTS: return m->ny;
    case GEN_RT_CS_CONSTRAINTS: return m->mc + m->mv;
    default: return nx;
    }
}

/* the entries of an input */
GEN_RT_DERIV_ALWAYS int rt_cs_size(const gen_rt_cs_model *m, int what)
{
    const int nx = m->nq + m->nu;
    return what == GEN_RT_CS_X || what == GEN_RT_CS_XDOT ? nx
           : what == GEN_RT_CS_R ? m->nr : what == GEN_RT_CS_P ? m->np : 1;
}

/* the inputs of arg into c (work: z = (x, r, p, t), then xd; an input the
 * function does not have is zero, as a NULL one), their columns; returns
 * the rest of work */
GEN_RT_DERIV_ALWAYS gen_rt_real *rt_cs_read(const gen_rt_cs_model *m, const gen_rt_cs_fn *f,
                                            const gen_rt_real **arg, gen_rt_real *work,
                                            rt_cs_call *c)
{
    const int nx = m->nq + m->nu, nr = m->nr, np = m->np;
    const gen_rt_real *in[GEN_RT_CS_H + 1] = {0, 0, 0, 0, 0, 0, 0};
    int k;
    c->nin = f->nin;
    c->nrow = rt_cs_rows(m, f->base);
    c->z = work; c->x = c->z; c->r = c->x + nx; c->p = c->r + nr; c->xd = c->z + nx + nr + np + 1;
    for (k = 0; k <= GEN_RT_CS_H; ++k) c->off[k] = -1;
    c->nv = 0;
    for (k = 0; k < f->nin; ++k) {
        c->size[k] = rt_cs_size(m, f->in[k]);
        c->off[f->in[k]] = c->nv;
        c->nv += c->size[k];
        in[f->in[k]] = arg[k];
    }
    rt_cs_in(in[GEN_RT_CS_X], nx, c->x);
    rt_cs_in(in[GEN_RT_CS_XDOT], c->off[GEN_RT_CS_XDOT] < 0 ? 0 : nx, c->xd);
    rt_cs_in(in[GEN_RT_CS_R], nr, c->r);
    rt_cs_in(in[GEN_RT_CS_P], np, c->p);
    rt_cs_in(in[GEN_RT_CS_T], 1, &c->t);
    rt_cs_in(in[GEN_RT_CS_H], 1, &c->h);
    c->z[nx + nr + np] = c->t;
    c->zfirst = c->off[GEN_RT_CS_X] == 0 && c->off[GEN_RT_CS_R] == nx &&
                c->off[GEN_RT_CS_P] == nx + nr && c->off[GEN_RT_CS_T] == nx + nr + np;
    return c->xd + nx;
}

/* ------------------------------------------------------------ values */

typedef struct {
    const gen_rt_cs_model *m;
    const gen_rt_real *r, *p;
} rt_cs_fctx;

/* the right-hand side at fixed r, p: the runtime's gen_rt_rhs_fn */
GEN_RT_DERIV_INLINE int rt_cs_f(void *ctx, gen_rt_real t, const gen_rt_real *x,
                                gen_rt_real *dxdt)
{
    const rt_cs_fctx *c = (const rt_cs_fctx *)ctx;
    return c->m->rhs(t, x, c->r, c->p, dxdt, 0);
}

/* one RODAS4 trial step of the runtime (gen_rt_rodas4_trial) with Jf_x =
 * the model's jacobian (the adaptive RODAS4's) and df/dt exact: from dw/dz
 * (the runtime's forward difference is exact where f holds no t: zero) */
GEN_RT_DERIV_APART int rt_cs_rodas4_value(const gen_rt_cs_model *m, const rt_cs_call *c,
                                          gen_rt_real *out, gen_rt_real *wk, int *iwk)
{
    const int nx = m->nq + m->nu, nz = m->d.nz, nw = m->d.nw;
    gen_rt_real *f0 = wk, *Jx = f0 + nx, *Jr = Jx + nx * nx, *dfdt = Jr + nx * m->nr + 1,
                *rw = dfdt + nx, *w = rw + GEN_RT_RODAS4_WORK(nx), *lu = w + nw,
                *Jw = lu + nw * nw, *sw = Jw + nw * nz;
    gen_rt_real err = 0, h = c->h;
    int *rpiv = iwk, *piv = iwk + nx;
    int i, st;
    rt_cs_fctx ctx;
    ctx.m = m;
    ctx.r = c->r;
    ctx.p = c->p;
    if (h != h || h - h != 0) return GEN_RT_ERR_NONFINITE_INPUT;
    if (h == 0) return GEN_RT_ERR_BAD_ARG;
    if ((st = m->rhs(c->t, c->x, c->r, c->p, f0, 0))) return st;
    if ((st = m->jacobian(c->t, c->x, c->r, c->p, Jx, Jr))) return st;
    if (m->t_dep) {
        if ((st = gen_rt_deriv_solve_inline(&m->d, c->z, sw, w, lu, piv, Jw))) return st;
        for (i = 0; i < nx; ++i) dfdt[i] = Jw[i * nz + nz - 1];
    } else {
        for (i = 0; i < nx; ++i) dfdt[i] = 0;
    }
    return gen_rt_rodas4_trial(rt_cs_f, &ctx, nx, c->t, h, c->x, f0, Jx, dfdt, 1, 1, rw, rpiv,
                               out, &err);
}

/* the constraint residuals [f_c(q); f_v(q, u)] */
GEN_RT_DERIV_ALWAYS int rt_cs_residuals(const gen_rt_cs_model *m, const rt_cs_call *c,
                                        gen_rt_real *out)
{
    int st;
    if (m->mc && (st = m->constraints(c->x, c->p, c->t, out))) return st;
    if (m->mv) return m->velocity_constraints(c->x, c->x + m->nq, c->p, c->t, out + m->mc);
    return GEN_RT_OK;
}

GEN_RT_DERIV_ALWAYS int rt_cs_value(const gen_rt_cs_model *m, const gen_rt_cs_fn *f,
                                    const rt_cs_call *c, gen_rt_real *out, gen_rt_real *wk,
                                    int *iwk)
{
    const int nx = m->nq + m->nu;
    int i, st;
    switch (f->base) {
    case GEN_RT_CS_RHS:
        return m->rhs(c->t, c->x, c->r, c->p, out, 0);
    case GEN_RT_CS_IMPLICIT:
        if ((st = m->rhs(c->t, c->x, c->r, c->p, out, 0))) return st;
        for (i = 0; i < nx; ++i) out[i] = c->xd[i] - out[i];
        return rt_cs_residuals(m, c, out + nx);
    case GEN_RT_CS_CONSTRAINTS:
        return rt_cs_residuals(m, c, out);
    case GEN_RT_CS_STEP:
        for (i = 0; i < nx; ++i) out[i] = c->x[i];
        return m->step_rk4(c->t, c->h, c->r, c->p, 1, out);
    case GEN_RT_CS_STEP_RODAS4:
        return rt_cs_rodas4_value(m, c, out, wk, iwk);
    case GEN_RT_CS_OUTPUTS:
        return m->outputs(c->t, c->x, c->r, c->p, out);
    default:
        return GEN_RT_ERR_BAD_ARG;
    }
}

/* ------------------------------------------------------- derivatives */

/* z's segment g (0: x, 1: r, 2: p, 3: t): where it starts in z (*z0), its
 * length (*n); returns where it starts among v (-1: not an input). The
 * sizes are the model's (m: constants where m is one) */
GEN_RT_DERIV_ALWAYS int rt_cs_seg(const gen_rt_cs_model *m, const rt_cs_call *c, int g, int *z0,
                                  int *n)
{
    static const int what[4] = {GEN_RT_CS_X, GEN_RT_CS_R, GEN_RT_CS_P, GEN_RT_CS_T};
    const int nx = m->nq + m->nu;
    *z0 = g == 0 ? 0 : g == 1 ? nx : g == 2 ? nx + m->nr : nx + m->nr + m->np;
    *n = g == 0 ? nx : g == 1 ? m->nr : g == 2 ? m->np : 1;
    return c->off[what[g]];
}

/* out (nv) += s row (nz): each of z's segments onto its input's columns
 * (one run of nz, the model's, when z's columns are v's first) */
GEN_RT_DERIV_ALWAYS void rt_cs_addrow(const gen_rt_cs_model *m, const rt_cs_call *c,
                                      gen_rt_real s, const gen_rt_real *row, gen_rt_real *out)
{
    int g, j, z0, n;
    if (c->zfirst) {
        const int nz = m->d.nz;
        for (j = 0; j < nz; ++j) out[j] += s * row[j];
        return;
    }
    for (g = 0; g < 4; ++g) {
        const int v0 = rt_cs_seg(m, c, g, &z0, &n);
        if (v0 >= 0)
            for (j = 0; j < n; ++j) out[v0 + j] += s * row[z0 + j];
    }
}

/* H (nv x nv) += s Hz (nz x nz): the rows of each of z's segments onto its
 * input's rows */
GEN_RT_DERIV_ALWAYS void rt_cs_addh(const gen_rt_cs_model *m, const rt_cs_call *c, gen_rt_real s,
                                    const gen_rt_real *Hz, gen_rt_real *H)
{
    const int nz = m->d.nz, nv = c->nv;
    int g, a, z0, n;
    if (c->zfirst) {
        for (a = 0; a < nz; ++a) rt_cs_addrow(m, c, s, Hz + a * nz, H + a * nv);
        return;
    }
    for (g = 0; g < 4; ++g) {
        const int v0 = rt_cs_seg(m, c, g, &z0, &n);
        if (v0 >= 0)
            for (a = 0; a < n; ++a) rt_cs_addrow(m, c, s, Hz + (z0 + a) * nz, H + (v0 + a) * nv);
    }
}

/* rows 0..nx of rhs (s = 1) or implicit (s = -1): s dw/dz, the Hessian of
 * lam^T w and its rows' (T), from the implicit function */
GEN_RT_DERIV_APART int rt_cs_implicit(const gen_rt_cs_model *m, const rt_cs_call *c,
                                      gen_rt_real s, const gen_rt_real *lam, gen_rt_real *J,
                                      gen_rt_real *Hl, gen_rt_real *T, gen_rt_real *wk, int *piv)
{
    const int nx = m->nq + m->nu, nz = m->d.nz, nw = m->d.nw, nv = c->nv;
    gen_rt_real *w = wk, *lu = w + nw, *Jw = lu + nw * nw, *sw = Jw + nw * nz, *lw = sw + nw,
                *Hz = lw + nw, *hw = Hz + nz * nz;
    int i, k, st;
    if ((st = gen_rt_deriv_solve_inline(&m->d, c->z, sw, w, lu, piv, Jw))) return st;
    if (J)
        for (i = 0; i < nx; ++i) rt_cs_addrow(m, c, s, Jw + i * nz, J + i * nv);
    for (k = 0; k < nw; ++k) lw[k] = 0;
    if (Hl) {
        for (k = 0; k < nx; ++k) lw[k] = lam ? lam[k] : 0;
        if ((st = gen_rt_deriv_hessian_inline(&m->d, c->z, w, lu, piv, Jw, lw, hw, Hz))) return st;
        rt_cs_addh(m, c, s, Hz, Hl);
    }
    if (T)
        for (i = 0; i < nx; ++i) {
            for (k = 0; k < nw; ++k) lw[k] = k == i;
            st = gen_rt_deriv_hessian_inline(&m->d, c->z, w, lu, piv, Jw, lw, hw, Hz);
            if (st) return st;
            rt_cs_addh(m, c, s, Hz, T + i * nv * nv);
        }
    return GEN_RT_OK;
}

/* rows r0..r0+nk of an explicit function k(z): its Jacobian, the Hessian
 * of lam^T k and its rows' */
GEN_RT_DERIV_APART int rt_cs_explicit(const gen_rt_cs_model *m, const rt_cs_call *c,
                                      gen_rt_cs_jac_fn k1, gen_rt_cs_hess_fn kh, int nk, int r0,
                                      const gen_rt_real *lam, gen_rt_real *J, gen_rt_real *Hl,
                                      gen_rt_real *T, gen_rt_real *wk)
{
    const int nz = m->d.nz, nv = c->nv;
    gen_rt_real *Jk = wk, *lk = Jk + nk * nz, *Hz = lk + nk;
    int i, k;
    if ((Hl || T) && !kh) return GEN_RT_ERR_BAD_ARG;
    k1(c->z, Jk);
    if (J)
        for (i = 0; i < nk; ++i) rt_cs_addrow(m, c, 1, Jk + i * nz, J + (r0 + i) * nv);
    if (Hl) {
        for (k = 0; k < nk; ++k) lk[k] = lam ? lam[r0 + k] : 0;
        kh(c->z, lk, Hz);
        rt_cs_addh(m, c, 1, Hz, Hl);
    }
    if (T)
        for (i = 0; i < nk; ++i) {
            for (k = 0; k < nk; ++k) lk[k] = k == i;
            kh(c->z, lk, Hz);
            rt_cs_addh(m, c, 1, Hz, T + (r0 + i) * nv * nv);
        }
    return GEN_RT_OK;
}

/* the base function's derivatives over v: J (rows x nv), the Hessian Hl of
 * lam^T out (nv x nv) and the tensor T (rows x nv x nv), each when not NULL */
GEN_RT_DERIV_ALWAYS int rt_cs_deriv(const gen_rt_cs_model *m, const gen_rt_cs_fn *f,
                                    const rt_cs_call *c, const gen_rt_real *lam, gen_rt_real *J,
                                    gen_rt_real *Hl, gen_rt_real *T, gen_rt_real *wk, int *iwk)
{
    const int nx = m->nq + m->nu, nv = c->nv, nrow = c->nrow, mk = m->mc + m->mv;
    int i, st = GEN_RT_OK;
    if (f->base != GEN_RT_CS_STEP && f->base != GEN_RT_CS_STEP_RODAS4) {
        /* the rest add into them (the steps write every entry) */
        if (J) rt_zero(nrow * nv, J);
        if (Hl) rt_zero(nv * nv, Hl);
        if (T) rt_zero(nrow * nv * nv, T);
    }
    switch (f->base) {
    case GEN_RT_CS_RHS:
    case GEN_RT_CS_IMPLICIT:
        st = rt_cs_implicit(m, c, f->base == GEN_RT_CS_RHS ? 1 : -1, lam, J, Hl, T, wk, iwk);
        if (st || f->base == GEN_RT_CS_RHS) break;
        if (J) for (i = 0; i < nx; ++i) J[i * nv + c->off[GEN_RT_CS_XDOT] + i] = 1;
        if (mk) st = rt_cs_explicit(m, c, m->c1, m->ch, mk, nx, lam, J, Hl, T, wk);
        break;
    case GEN_RT_CS_OUTPUTS:
        st = rt_cs_explicit(m, c, m->y1, m->yh, m->ny, 0, lam, J, Hl, T, wk);
        break;
    case GEN_RT_CS_CONSTRAINTS:
        st = rt_cs_explicit(m, c, m->c1, m->ch, mk, 0, lam, J, Hl, T, wk);
        break;
    case GEN_RT_CS_STEP:
        st = gen_rt_deriv_rk4_inline(&m->d, c->z, c->h, lam, wk, iwk, 0, J, Hl, T);
        break;
    case GEN_RT_CS_STEP_RODAS4:
        st = (Hl || T || !J) ? GEN_RT_ERR_BAD_ARG
                             : gen_rt_deriv_rodas4_inline(&m->d, c->z, c->h, wk, iwk, J);
        break;
    default:
        st = GEN_RT_ERR_BAD_ARG;
    }
    if (st) return st;
    if ((J && !rt_finite(nrow * nv, J)) || (Hl && !rt_finite(nv * nv, Hl)) ||
        (T && !rt_finite(nrow * nv * nv, T)))
        return GEN_RT_ERR_NONFINITE_MODEL;
    return GEN_RT_OK;
}

/* ------------------------------------------------------------ layout */

/* sv (nv) = the seeds arg[first + i] of the inputs, side by side */
GEN_RT_DERIV_ALWAYS void rt_cs_seeds(const rt_cs_call *c, const gen_rt_real **arg, int first,
                                     gen_rt_real *sv)
{
    const int nin = c->nin;
    int i, k, o = 0;
    rt_zero(c->nv, sv);
    for (i = 0; i < nin; ++i) {
        const int ni = c->size[i];
        const gen_rt_real *a = arg[first + i];
        if (a)
            for (k = 0; k < ni; ++k) sv[o + k] = a[k];
        o += ni;
    }
}

/* res = the block of columns o..o+n of J (nrow x nv), column-major */
GEN_RT_DERIV_ALWAYS void rt_cs_block(int nrow, int nv, const gen_rt_real *J, int o, int n,
                                     gen_rt_real *res)
{
    int a, k;
    if (res)
        for (k = 0; k < n; ++k)
            for (a = 0; a < nrow; ++a) res[k * nrow + a] = J[a * nv + o + k];
}

/* the first derivatives' outputs: JAC, FWD, ADJ */
GEN_RT_DERIV_ALWAYS void rt_cs_first(const rt_cs_call *c, int mode, const gen_rt_real **arg,
                                     const gen_rt_real *J, gen_rt_real *sv, gen_rt_real **res)
{
    const int nin = c->nin, nrow = c->nrow, nv = c->nv;
    const gen_rt_real *seed = mode == GEN_RT_CS_ADJ ? arg[nin + 1] : 0;
    int i, k, a, o = 0;
    if (mode == GEN_RT_CS_FWD) {
        gen_rt_real *r = res[0];
        rt_cs_seeds(c, arg, nin + 1, sv);
        if (r)
            for (a = 0; a < nrow; ++a) {
                gen_rt_real s = 0;
                for (k = 0; k < nv; ++k) s += J[a * nv + k] * sv[k];
                r[a] = s;
            }
        return;
    }
    for (i = 0; i < nin; ++i) {
        const int ni = c->size[i];
        gen_rt_real *r = res[i];
        if (mode == GEN_RT_CS_JAC) rt_cs_block(nrow, nv, J, o, ni, r);
        else if (r)
            for (k = 0; k < ni; ++k) {
                gen_rt_real s = 0;
                if (seed) for (a = 0; a < nrow; ++a) s += J[a * nv + o + k] * seed[a];
                r[k] = s;
            }
        o += ni;
    }
}

/* JAC_JAC: block (i, j) = d vec(jac_out_i) / d in_j (vec column-major; the
 * output's own blocks j = nin are structural zeros) */
GEN_RT_DERIV_ALWAYS void rt_cs_jac_jac(const rt_cs_call *c, const gen_rt_real *T, gen_rt_real **res)
{
    const int nin = c->nin, nrow = c->nrow, nv = c->nv;
    int i, j, oi = 0, oj, a, k, l;
    for (i = 0; i < nin; ++i) {
        const int ni = c->size[i];
        for (j = 0, oj = 0; j < nin; ++j) {
            const int nj = c->size[j];
            gen_rt_real *r = res[i * (nin + 1) + j];
            if (r)
                for (k = 0; k < nj; ++k)
                    for (l = 0; l < ni; ++l)
                        for (a = 0; a < nrow; ++a)
                            r[(k * ni + l) * nrow + a] = T[(a * nv + oi + l) * nv + oj + k];
            oj += nj;
        }
        oi += ni;
    }
}

/* JAC_FWD: w.r.t. the inputs T sv (blocks), the output none, the seeds J */
GEN_RT_DERIV_ALWAYS void rt_cs_jac_fwd(const rt_cs_call *c, const gen_rt_real **arg,
                                       const gen_rt_real *J, const gen_rt_real *T,
                                       gen_rt_real *sv, gen_rt_real **res)
{
    const int nin = c->nin, nrow = c->nrow, nv = c->nv;
    int j, o = 0, a, k, i;
    rt_cs_seeds(c, arg, nin + 1, sv);
    for (j = 0; j < nin; ++j) {
        const int nj = c->size[j];
        gen_rt_real *r = res[j];
        if (r)
            for (k = 0; k < nj; ++k)
                for (a = 0; a < nrow; ++a) {
                    gen_rt_real s = 0;
                    for (i = 0; i < nv; ++i) s += T[(a * nv + i) * nv + o + k] * sv[i];
                    r[k * nrow + a] = s;
                }
        rt_cs_block(nrow, nv, J, o, nj, res[nin + 1 + j]);
        o += nj;
    }
}

/* JAC_ADJ: block (i, j): the Hessian block (in_i, in_j) of seed^T f, the
 * output's none, the seed's J_i^T */
GEN_RT_DERIV_ALWAYS void rt_cs_jac_adj(const rt_cs_call *c, const gen_rt_real *J,
                                       const gen_rt_real *Hl, gen_rt_real **res)
{
    const int nin = c->nin, nrow = c->nrow, nv = c->nv;
    int i, j, oi = 0, oj, a, k;
    for (i = 0; i < nin; ++i) {
        const int ni = c->size[i];
        gen_rt_real *rt = res[i * (nin + 2) + nin + 1];
        for (j = 0, oj = 0; j < nin; ++j) {
            const int nj = c->size[j];
            gen_rt_real *r = res[i * (nin + 2) + j];
            if (r)
                for (k = 0; k < nj; ++k)
                    for (a = 0; a < ni; ++a) r[k * ni + a] = Hl[(oi + a) * nv + oj + k];
            oj += nj;
        }
        if (rt)
            for (k = 0; k < nrow; ++k)
                for (a = 0; a < ni; ++a) rt[k * ni + a] = J[k * nv + oi + a];
        oi += ni;
    }
}

GEN_RT_DERIV_ALWAYS int gen_rt_cs_eval_inline(const gen_rt_cs_model *m, const gen_rt_cs_fn *f,
                                              const gen_rt_real **arg, gen_rt_real **res,
                                              gen_rt_real *work, int *iwork)
{
    const int nx = m->nq + m->nu, nr = m->nr, np = m->np;
    const int nvmax = GEN_RT_CS_NV_(nx, nr, np), mrow = GEN_RT_CS_MR_(nx, m->mc, m->mv, m->ny);
    rt_cs_call c;
    gen_rt_real *out = rt_cs_read(m, f, arg, work, &c);
    gen_rt_real *J = out + mrow, *Hl = J + mrow * nvmax, *T = Hl + nvmax * nvmax,
                *sv = T + mrow * nvmax * nvmax, *wk = sv + nvmax;
    int *iwk = iwork;
    int st;
    switch (f->mode) {
    case GEN_RT_CS_VALUE:         /* into res[0] (the inputs are read: no alias) */
        return rt_cs_value(m, f, &c, res[0] ? res[0] : out, wk, iwk);
    case GEN_RT_CS_JAC:
    case GEN_RT_CS_FWD:
    case GEN_RT_CS_ADJ:
        if ((st = rt_cs_deriv(m, f, &c, 0, J, 0, 0, wk, iwk))) return st;
        rt_cs_first(&c, f->mode, arg, J, sv, res);
        return GEN_RT_OK;
    case GEN_RT_CS_JAC_JAC:
        if ((st = rt_cs_deriv(m, f, &c, 0, 0, 0, T, wk, iwk))) return st;
        rt_cs_jac_jac(&c, T, res);
        return GEN_RT_OK;
    case GEN_RT_CS_JAC_FWD:
        if ((st = rt_cs_deriv(m, f, &c, 0, J, 0, T, wk, iwk))) return st;
        rt_cs_jac_fwd(&c, arg, J, T, sv, res);
        return GEN_RT_OK;
    case GEN_RT_CS_JAC_ADJ:
        if ((st = rt_cs_deriv(m, f, &c, arg[c.nin + 1], J, Hl, 0, wk, iwk))) return st;
        rt_cs_jac_adj(&c, J, Hl, res);
        return GEN_RT_OK;
    default:
        return GEN_RT_ERR_BAD_ARG;
    }
}

#endif /* GEN_RT_CASADI_INLINE_H */
