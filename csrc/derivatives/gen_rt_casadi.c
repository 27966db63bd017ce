/* gen_rt_casadi.c - a model's functions in CasADi's calling convention
 * (gen_rt_casadi.h): the inputs read, the base function or its derivatives
 * (gen_rt_deriv.c, the explicit kernels) computed over the function's
 * differentiable inputs v (its inputs side by side), the outputs laid out
 * as CasADi's dense column-major blocks. */
#include "gen_rt.h"
#include "gen_rt_casadi.h"

/* one call: the inputs as arrays, where each input's columns start among v
 * (off, -1: not an input), the map of z's columns into v (cm) */
typedef struct {
    int nx, nz, nv, nrow, nin;
    int size[GEN_RT_CS_MAX_IN], off[GEN_RT_CS_H + 1];
    gen_rt_real *x, *xd, *r, *p, *z, t, h;
    const int *cm;
} cs_call;

static void cs_in(const gen_rt_real *a, int n, gen_rt_real *d)
{
    int i;
    for (i = 0; i < n; ++i) d[i] = a ? a[i] : 0;
}

static int cs_rows(const gen_rt_cs_model *m, int base)
{
    const int nx = m->nq + m->nu;
    switch (base) {
    case GEN_RT_CS_IMPLICIT: return nx + m->mc + m->mv;
    case GEN_RT_CS_OUTPUTS: return m->ny;
    case GEN_RT_CS_CONSTRAINTS: return m->mc + m->mv;
    default: return nx;
    }
}

/* the inputs of arg into c (work: x, xd, r, p, z), their columns, cm */
static gen_rt_real *cs_read(const gen_rt_cs_model *m, const gen_rt_cs_fn *f,
                            const gen_rt_real **arg, gen_rt_real *work, int *cm, cs_call *c)
{
    const int nx = m->nq + m->nu, nr = m->nr, np = m->np;
    int k, j;
    c->nx = nx;
    c->nz = nx + nr + np + 1;
    c->nin = f->nin;
    c->nrow = cs_rows(m, f->base);
    c->x = work; c->xd = c->x + nx; c->r = c->xd + nx; c->p = c->r + nr; c->z = c->p + np;
    cs_in(0, nr, c->r);   /* a function without r (constraints, guard_, map_): zero */
    c->t = c->h = 0;
    for (k = 0; k <= GEN_RT_CS_H; ++k) c->off[k] = -1;
    c->nv = 0;
    for (k = 0; k < f->nin; ++k) {
        const int what = f->in[k];
        const int n = what == GEN_RT_CS_X || what == GEN_RT_CS_XDOT ? nx
                      : what == GEN_RT_CS_R ? nr : what == GEN_RT_CS_P ? np : 1;
        c->size[k] = n;
        c->off[what] = c->nv;
        c->nv += n;
        if (what == GEN_RT_CS_X) cs_in(arg[k], nx, c->x);
        else if (what == GEN_RT_CS_XDOT) cs_in(arg[k], nx, c->xd);
        else if (what == GEN_RT_CS_R) cs_in(arg[k], nr, c->r);
        else if (what == GEN_RT_CS_P) cs_in(arg[k], np, c->p);
        else if (what == GEN_RT_CS_T) c->t = arg[k] ? arg[k][0] : 0;
        else c->h = arg[k] ? arg[k][0] : 0;
    }
    /* z = (x, r, p, t) and, for a derivative, where its columns go among v */
    for (j = 0; j < nx; ++j) c->z[j] = c->x[j];
    for (j = 0; j < nr; ++j) c->z[nx + j] = c->r[j];
    for (j = 0; j < np; ++j) c->z[nx + nr + j] = c->p[j];
    c->z[c->nz - 1] = c->t;
    c->cm = cm;
    for (j = 0; f->mode != GEN_RT_CS_VALUE && j < c->nz; ++j) {
        const int what = j < nx ? GEN_RT_CS_X : j < nx + nr ? GEN_RT_CS_R
                         : j < nx + nr + np ? GEN_RT_CS_P : GEN_RT_CS_T;
        const int first = what == GEN_RT_CS_X ? 0 : what == GEN_RT_CS_R ? nx
                          : what == GEN_RT_CS_P ? nx + nr : c->nz - 1;
        cm[j] = c->off[what] < 0 ? -1 : c->off[what] + j - first;
    }
    return c->z + c->nz;
}

/* ------------------------------------------------------------ values */

typedef struct {
    const gen_rt_cs_model *m;
    const gen_rt_real *r, *p;
} cs_fctx;

/* the right-hand side at fixed r, p: the runtime's gen_rt_rhs_fn */
static int cs_f(void *ctx, gen_rt_real t, const gen_rt_real *x, gen_rt_real *dxdt)
{
    const cs_fctx *c = (const cs_fctx *)ctx;
    return c->m->rhs(t, x, c->r, c->p, dxdt, 0);
}

/* one RODAS4 trial step of the runtime (gen_rt_rodas4_trial) with Jf_x =
 * the model's jacobian (the adaptive RODAS4's) and df/dt exact: from dw/dz
 * (the runtime's forward difference is exact where f holds no t: zero) */
static int cs_rodas4_value(const gen_rt_cs_model *m, const cs_call *c, gen_rt_real *out,
                           gen_rt_real *wk, int *iwk)
{
    const int nx = c->nx, nz = c->nz, nw = m->d.nw;
    gen_rt_real *f0 = wk, *Jx = f0 + nx, *Jr = Jx + nx * nx, *dfdt = Jr + nx * m->nr + 1,
                *rw = dfdt + nx, *w = rw + GEN_RT_RODAS4_WORK(nx), *lu = w + nw,
                *Jw = lu + nw * nw, *sw = Jw + nw * nz;
    gen_rt_real err = 0, h = c->h;
    int *rpiv = iwk, *piv = iwk + nx;
    int i, st;
    cs_fctx ctx;
    ctx.m = m;
    ctx.r = c->r;
    ctx.p = c->p;
    if (h != h || h - h != 0) return GEN_RT_ERR_NONFINITE_INPUT;
    if (h == 0) return GEN_RT_ERR_BAD_ARG;
    if ((st = m->rhs(c->t, c->x, c->r, c->p, f0, 0))) return st;
    if ((st = m->jacobian(c->t, c->x, c->r, c->p, Jx, Jr))) return st;
    if (m->t_dep) {
        if ((st = gen_rt_deriv_solve(&m->d, c->z, sw, w, lu, piv, Jw))) return st;
        for (i = 0; i < nx; ++i) dfdt[i] = Jw[i * nz + nz - 1];
    } else {
        for (i = 0; i < nx; ++i) dfdt[i] = 0;
    }
    return gen_rt_rodas4_trial(cs_f, &ctx, nx, c->t, h, c->x, f0, Jx, dfdt, 1, 1, rw, rpiv,
                               out, &err);
}

/* the constraint residuals [f_c(q); f_v(q, u)] */
static int cs_residuals(const gen_rt_cs_model *m, const cs_call *c, gen_rt_real *out)
{
    int st;
    if (m->mc && (st = m->constraints(c->x, c->p, c->t, out))) return st;
    if (m->mv) return m->velocity_constraints(c->x, c->x + m->nq, c->p, c->t, out + m->mc);
    return GEN_RT_OK;
}

static int cs_value(const gen_rt_cs_model *m, const gen_rt_cs_fn *f, const cs_call *c,
                    gen_rt_real *out, gen_rt_real *wk, int *iwk)
{
    const int nx = c->nx;
    int i, st;
    switch (f->base) {
    case GEN_RT_CS_RHS:
        return m->rhs(c->t, c->x, c->r, c->p, out, 0);
    case GEN_RT_CS_IMPLICIT:
        if ((st = m->rhs(c->t, c->x, c->r, c->p, out, 0))) return st;
        for (i = 0; i < nx; ++i) out[i] = c->xd[i] - out[i];
        return cs_residuals(m, c, out + nx);
    case GEN_RT_CS_CONSTRAINTS:
        return cs_residuals(m, c, out);
    case GEN_RT_CS_STEP:
        for (i = 0; i < nx; ++i) out[i] = c->x[i];
        return m->step_rk4(c->t, c->h, c->r, c->p, 1, out);
    case GEN_RT_CS_STEP_RODAS4:
        return cs_rodas4_value(m, c, out, wk, iwk);
    case GEN_RT_CS_OUTPUTS:
        return m->outputs(c->t, c->x, c->r, c->p, out);
    default:
        return GEN_RT_ERR_BAD_ARG;
    }
}

/* ------------------------------------------------------- derivatives */

/* out (nv) += s row (nz) through cm */
static void cs_addrow(const cs_call *c, gen_rt_real s, const gen_rt_real *row, gen_rt_real *out)
{
    int b;
    for (b = 0; b < c->nz; ++b)
        if (c->cm[b] >= 0) out[c->cm[b]] += s * row[b];
}

/* H (nv x nv) += s Hz (nz x nz) through cm */
static void cs_addh(const cs_call *c, gen_rt_real s, const gen_rt_real *Hz, gen_rt_real *H)
{
    const int *cm = c->cm;
    int a, b;
    for (a = 0; a < c->nz; ++a)
        for (b = 0; b < c->nz; ++b)
            if (cm[a] >= 0 && cm[b] >= 0) H[cm[a] * c->nv + cm[b]] += s * Hz[a * c->nz + b];
}

/* rows 0..nx of rhs (s = 1) or implicit (s = -1): s dw/dz, the Hessian of
 * lam^T w and its rows' (T), from the implicit function */
static int cs_implicit(const gen_rt_cs_model *m, const cs_call *c, gen_rt_real s,
                       const gen_rt_real *lam, gen_rt_real *J, gen_rt_real *Hl, gen_rt_real *T,
                       gen_rt_real *wk, int *piv)
{
    const int nx = c->nx, nz = c->nz, nw = m->d.nw, nv = c->nv;
    gen_rt_real *w = wk, *lu = w + nw, *Jw = lu + nw * nw, *sw = Jw + nw * nz, *lw = sw + nw,
                *Hz = lw + nw, *hw = Hz + nz * nz;
    int i, k, st;
    if ((st = gen_rt_deriv_solve(&m->d, c->z, sw, w, lu, piv, Jw))) return st;
    if (J)
        for (i = 0; i < nx; ++i) cs_addrow(c, s, Jw + i * nz, J + i * nv);
    for (k = 0; k < nw; ++k) lw[k] = 0;
    if (Hl) {
        for (k = 0; k < nx; ++k) lw[k] = lam ? lam[k] : 0;
        if ((st = gen_rt_deriv_hessian(&m->d, c->z, w, lu, piv, Jw, lw, hw, Hz))) return st;
        cs_addh(c, s, Hz, Hl);
    }
    if (T)
        for (i = 0; i < nx; ++i) {
            for (k = 0; k < nw; ++k) lw[k] = k == i;
            if ((st = gen_rt_deriv_hessian(&m->d, c->z, w, lu, piv, Jw, lw, hw, Hz))) return st;
            cs_addh(c, s, Hz, T + i * nv * nv);
        }
    return GEN_RT_OK;
}

/* rows r0..r0+nk of an explicit function k(z): its Jacobian, the Hessian
 * of lam^T k and its rows' */
static int cs_explicit(const cs_call *c, gen_rt_cs_jac_fn k1, gen_rt_cs_hess_fn kh, int nk,
                       int r0, const gen_rt_real *lam, gen_rt_real *J, gen_rt_real *Hl,
                       gen_rt_real *T, gen_rt_real *wk)
{
    const int nz = c->nz, nv = c->nv;
    gen_rt_real *Jk = wk, *lk = Jk + nk * nz, *Hz = lk + nk;
    int i, k;
    if ((Hl || T) && !kh) return GEN_RT_ERR_BAD_ARG;
    k1(c->z, Jk);
    if (J)
        for (i = 0; i < nk; ++i) cs_addrow(c, 1, Jk + i * nz, J + (r0 + i) * nv);
    if (Hl) {
        for (k = 0; k < nk; ++k) lk[k] = lam ? lam[r0 + k] : 0;
        kh(c->z, lk, Hz);
        cs_addh(c, 1, Hz, Hl);
    }
    if (T)
        for (i = 0; i < nk; ++i) {
            for (k = 0; k < nk; ++k) lk[k] = k == i;
            kh(c->z, lk, Hz);
            cs_addh(c, 1, Hz, T + (r0 + i) * nv * nv);
        }
    return GEN_RT_OK;
}

/* the base function's derivatives over v: J (rows x nv), the Hessian Hl of
 * lam^T out (nv x nv) and the tensor T (rows x nv x nv), each when not NULL */
static int cs_deriv(const gen_rt_cs_model *m, const gen_rt_cs_fn *f, const cs_call *c,
                    const gen_rt_real *lam, gen_rt_real *J, gen_rt_real *Hl, gen_rt_real *T,
                    gen_rt_real *wk, int *iwk)
{
    const int nx = c->nx, nv = c->nv, nrow = c->nrow, mk = m->mc + m->mv;
    int i, st = GEN_RT_OK;
    if (J) for (i = 0; i < nrow * nv; ++i) J[i] = 0;
    if (Hl) for (i = 0; i < nv * nv; ++i) Hl[i] = 0;
    if (T) for (i = 0; i < nrow * nv * nv; ++i) T[i] = 0;
    switch (f->base) {
    case GEN_RT_CS_RHS:
    case GEN_RT_CS_IMPLICIT:
        st = cs_implicit(m, c, f->base == GEN_RT_CS_RHS ? 1 : -1, lam, J, Hl, T, wk, iwk);
        if (st || f->base == GEN_RT_CS_RHS) break;
        if (J) for (i = 0; i < nx; ++i) J[i * nv + c->off[GEN_RT_CS_XDOT] + i] = 1;
        if (mk) st = cs_explicit(c, m->c1, m->ch, mk, nx, lam, J, Hl, T, wk);
        break;
    case GEN_RT_CS_OUTPUTS:
        st = cs_explicit(c, m->y1, m->yh, m->ny, 0, lam, J, Hl, T, wk);
        break;
    case GEN_RT_CS_CONSTRAINTS:
        st = cs_explicit(c, m->c1, m->ch, mk, 0, lam, J, Hl, T, wk);
        break;
    case GEN_RT_CS_STEP:
        st = gen_rt_deriv_rk4(&m->d, c->z, c->h, lam, wk, iwk, 0, J, Hl, T);
        break;
    case GEN_RT_CS_STEP_RODAS4:
        st = (Hl || T || !J) ? GEN_RT_ERR_BAD_ARG
                             : gen_rt_deriv_rodas4(&m->d, c->z, c->h, wk, iwk, J);
        break;
    default:
        st = GEN_RT_ERR_BAD_ARG;
    }
    if (st) return st;
    if ((J && !gen_rt_all_finite(nrow * nv, J)) || (Hl && !gen_rt_all_finite(nv * nv, Hl)) ||
        (T && !gen_rt_all_finite(nrow * nv * nv, T)))
        return GEN_RT_ERR_NONFINITE_MODEL;
    return GEN_RT_OK;
}

/* ------------------------------------------------------------ layout */

/* sv (nv) = the seeds arg[first + i] of the inputs, side by side */
static void cs_seeds(const cs_call *c, const gen_rt_real **arg, int first, gen_rt_real *sv)
{
    int i, k, o = 0;
    for (i = 0; i < c->nv; ++i) sv[i] = 0;
    for (i = 0; i < c->nin; o += c->size[i], ++i)
        if (arg[first + i])
            for (k = 0; k < c->size[i]; ++k) sv[o + k] = arg[first + i][k];
}

/* res = the block of columns o..o+n of J (rows x nv), column-major */
static void cs_block(const cs_call *c, const gen_rt_real *J, int o, int n, gen_rt_real *res)
{
    int a, k;
    if (res)
        for (k = 0; k < n; ++k)
            for (a = 0; a < c->nrow; ++a) res[k * c->nrow + a] = J[a * c->nv + o + k];
}

/* the first derivatives' outputs: JAC, FWD, ADJ */
static void cs_first(const cs_call *c, int mode, const gen_rt_real **arg, const gen_rt_real *J,
                     gen_rt_real *sv, gen_rt_real **res)
{
    const int nin = c->nin, nrow = c->nrow, nv = c->nv;
    const gen_rt_real *seed = mode == GEN_RT_CS_ADJ ? arg[nin + 1] : 0;
    int i, k, a, o = 0;
    if (mode == GEN_RT_CS_FWD) {
        cs_seeds(c, arg, nin + 1, sv);
        if (res[0])
            for (a = 0; a < nrow; ++a) {
                gen_rt_real s = 0;
                for (k = 0; k < nv; ++k) s += J[a * nv + k] * sv[k];
                res[0][a] = s;
            }
        return;
    }
    for (i = 0; i < nin; o += c->size[i], ++i) {
        if (mode == GEN_RT_CS_JAC) cs_block(c, J, o, c->size[i], res[i]);
        else if (res[i])
            for (k = 0; k < c->size[i]; ++k) {
                gen_rt_real s = 0;
                if (seed) for (a = 0; a < nrow; ++a) s += J[a * nv + o + k] * seed[a];
                res[i][k] = s;
            }
    }
}

/* JAC_JAC: block (i, j) = d vec(jac_out_i) / d in_j (vec column-major; the
 * output's own blocks j = nin are structural zeros) */
static void cs_jac_jac(const cs_call *c, const gen_rt_real *T, gen_rt_real **res)
{
    const int nin = c->nin, nrow = c->nrow, nv = c->nv;
    int i, j, oi = 0, oj, a, k, l;
    for (i = 0; i < nin; oi += c->size[i], ++i)
        for (j = 0, oj = 0; j < nin; oj += c->size[j], ++j) {
            gen_rt_real *r = res[i * (nin + 1) + j];
            if (r)
                for (k = 0; k < c->size[j]; ++k)
                    for (l = 0; l < c->size[i]; ++l)
                        for (a = 0; a < nrow; ++a)
                            r[(k * c->size[i] + l) * nrow + a] = T[(a * nv + oi + l) * nv + oj + k];
        }
}

/* JAC_FWD: w.r.t. the inputs T sv (blocks), the output none, the seeds J */
static void cs_jac_fwd(const cs_call *c, const gen_rt_real **arg, const gen_rt_real *J,
                       const gen_rt_real *T, gen_rt_real *sv, gen_rt_real **res)
{
    const int nin = c->nin, nrow = c->nrow, nv = c->nv;
    int j, o = 0, a, k, i;
    cs_seeds(c, arg, nin + 1, sv);
    for (j = 0; j < nin; o += c->size[j], ++j) {
        gen_rt_real *r = res[j];
        if (r)
            for (k = 0; k < c->size[j]; ++k)
                for (a = 0; a < nrow; ++a) {
                    gen_rt_real s = 0;
                    for (i = 0; i < nv; ++i) s += T[(a * nv + i) * nv + o + k] * sv[i];
                    r[k * nrow + a] = s;
                }
        cs_block(c, J, o, c->size[j], res[nin + 1 + j]);
    }
}

/* JAC_ADJ: block (i, j): the Hessian block (in_i, in_j) of seed^T f, the
 * output's none, the seed's J_i^T */
static void cs_jac_adj(const cs_call *c, const gen_rt_real *J, const gen_rt_real *Hl,
                       gen_rt_real **res)
{
    const int nin = c->nin, nrow = c->nrow, nv = c->nv;
    int i, j, oi = 0, oj, a, k;
    for (i = 0; i < nin; oi += c->size[i], ++i) {
        const int ni = c->size[i];
        gen_rt_real *rt = res[i * (nin + 2) + nin + 1];
        for (j = 0, oj = 0; j < nin; oj += c->size[j], ++j) {
            gen_rt_real *r = res[i * (nin + 2) + j];
            if (r)
                for (k = 0; k < c->size[j]; ++k)
                    for (a = 0; a < ni; ++a) r[k * ni + a] = Hl[(oi + a) * nv + oj + k];
        }
        if (rt)
            for (k = 0; k < nrow; ++k)
                for (a = 0; a < ni; ++a) rt[k * ni + a] = J[k * nv + oi + a];
    }
}

int gen_rt_cs_eval(const gen_rt_cs_model *m, const gen_rt_cs_fn *f, const gen_rt_real **arg,
                   gen_rt_real **res, gen_rt_real *work, int *iwork)
{
    const int nx = m->nq + m->nu, nr = m->nr, np = m->np;
    const int NV = GEN_RT_CS_NV_(nx, nr, np), MR = GEN_RT_CS_MR_(nx, m->mc, m->mv, m->ny);
    cs_call c;
    gen_rt_real *out = cs_read(m, f, arg, work, iwork, &c);
    gen_rt_real *J = out + MR, *Hl = J + MR * NV, *T = Hl + NV * NV, *sv = T + MR * NV * NV,
                *wk = sv + NV;
    int *iwk = iwork + c.nz;
    int i, st;
    switch (f->mode) {
    case GEN_RT_CS_VALUE:
        if ((st = cs_value(m, f, &c, out, wk, iwk))) return st;
        if (res[0]) for (i = 0; i < c.nrow; ++i) res[0][i] = out[i];
        return GEN_RT_OK;
    case GEN_RT_CS_JAC:
    case GEN_RT_CS_FWD:
    case GEN_RT_CS_ADJ:
        if ((st = cs_deriv(m, f, &c, 0, J, 0, 0, wk, iwk))) return st;
        cs_first(&c, f->mode, arg, J, sv, res);
        return GEN_RT_OK;
    case GEN_RT_CS_JAC_JAC:
        if ((st = cs_deriv(m, f, &c, 0, 0, 0, T, wk, iwk))) return st;
        cs_jac_jac(&c, T, res);
        return GEN_RT_OK;
    case GEN_RT_CS_JAC_FWD:
        if ((st = cs_deriv(m, f, &c, 0, J, 0, T, wk, iwk))) return st;
        cs_jac_fwd(&c, arg, J, T, sv, res);
        return GEN_RT_OK;
    case GEN_RT_CS_JAC_ADJ:
        if ((st = cs_deriv(m, f, &c, arg[c.nin + 1], J, Hl, 0, wk, iwk))) return st;
        cs_jac_adj(&c, J, Hl, res);
        return GEN_RT_OK;
    default:
        return GEN_RT_ERR_BAD_ARG;
    }
}
