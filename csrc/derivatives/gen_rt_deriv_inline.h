/*
 * gen_rt_deriv_inline.h - the algorithms of gen_rt_deriv.h as static inline
 * functions: gen_rt_deriv_<f>_inline is gen_rt_deriv_<f> (the same
 * arguments, the same IEEE operations in the same order: the same bits).
 *
 * gen_rt_deriv_extern.c defines the library functions over them. A model's
 * translation unit (the CasADi library's <name>_casadi.c, through
 * gen_rt_casadi_inline.h) includes this header and calls them with its own
 * model, a static const gen_rt_deriv_model, the same one at every call:
 * the compiler then sees the model's sizes as constants (loops over them
 * unrolled and vectorized, offsets folded; the LU of gen_rt_private.h
 * with them) and its kernels as direct calls, as in code generated for
 * the model, while the algorithm is written once, here. The steps
 * (GEN_RT_DERIV_APART) stay functions of their own, which the compiler
 * specializes all the same (every call passes the one model) and which
 * keep its loop passes over each function short.
 *
 * The products are written for that: an entry's sum in a register (the
 * dot form, each entry's terms in a fixed order), restrict operands, and
 * only the nx dense rows of a stage's dzeta/dv multiplied.
 */
#ifndef GEN_RT_DERIV_INLINE_H
#define GEN_RT_DERIV_INLINE_H

#include "gen_rt.h"
#include "gen_rt_deriv.h"
#include "gen_rt_private.h"
#include "gen_rt_rodas4.h"

#define GEN_RT_DERIV_INLINE static inline
/* compiled into each caller: where the caller's constants decide the
 * function's own (its sizes, its branches) */
#if defined(__GNUC__)
#define GEN_RT_DERIV_ALWAYS static inline __attribute__((always_inline))
#else
#define GEN_RT_DERIV_ALWAYS static inline
#endif
/* compiled once, apart (a step's algorithm, large: the callers' own code
 * stays small enough for the compiler's loop passes) */
#if defined(__GNUC__)
#define GEN_RT_DERIV_APART static __attribute__((noinline, unused))
#else
#define GEN_RT_DERIV_APART static
#endif
#if defined(__cplusplus)
#define RT_DV_RESTRICT __restrict
#else
#define RT_DV_RESTRICT restrict
#endif

/* RODAS4 coefficients (the tableau of gen_rt_rodas4.h) */
#define RT_DV_COEF_(name, value) static const gen_rt_real RT_DV_##name = GEN_RT_C(value);
GEN_RT_RODAS4_TABLEAU(RT_DV_COEF_)
#undef RT_DV_COEF_

GEN_RT_DERIV_INLINE int gen_rt_deriv_solve_inline(const gen_rt_deriv_model *m, const gen_rt_real *z,
                                                  gen_rt_real *work, gen_rt_real *w,
                                                  gen_rt_real *lu, int *piv, gen_rt_real *Jw)
{
    const int nw = m->nw, nz = m->nz;
    gen_rt_real *r0 = work;
    int i, st;
    m->r0(z, lu, r0);
    if (!rt_finite(nw * nw, lu) || !rt_finite(nw, r0))
        return GEN_RT_ERR_NONFINITE_MODEL;
    if ((st = rt_lu_factor(nw, lu, piv, 0))) return st;
    for (i = 0; i < nw; ++i) w[i] = -r0[i];
    rt_lu_solve(nw, lu, piv, 1, w);
    if (Jw) {
        m->rz(z, w, Jw);
        for (i = 0; i < nw * nz; ++i) Jw[i] = -Jw[i];
        rt_lu_solve(nw, lu, piv, nz, Jw);
    }
    return GEN_RT_OK;
}

/* H = -(sym(Hz) + Wz^T Jw + Jw^T Wz) (nz x nz; Wz, Jw: nw x nz): each
 * entry of the upper triangle summed in the order of k, then mirrored */
GEN_RT_DERIV_INLINE void rt_dv_hsym(int nz, int nw, const gen_rt_real *RT_DV_RESTRICT Hz,
                                    const gen_rt_real *RT_DV_RESTRICT Wz,
                                    const gen_rt_real *RT_DV_RESTRICT Jw,
                                    gen_rt_real *RT_DV_RESTRICT H)
{
    int a, b, k;
    for (a = 0; a < nz; ++a)
        for (b = a; b < nz; ++b) {
            gen_rt_real s = GEN_RT_C(0.5) * (Hz[a * nz + b] + Hz[b * nz + a]);
            for (k = 0; k < nw; ++k)
                s += Wz[k * nz + a] * Jw[k * nz + b] + Jw[k * nz + a] * Wz[k * nz + b];
            H[a * nz + b] = H[b * nz + a] = -s;
        }
}

GEN_RT_DERIV_INLINE int gen_rt_deriv_hessian_inline(const gen_rt_deriv_model *m,
                                                    const gen_rt_real *z, const gen_rt_real *w,
                                                    const gen_rt_real *lu, const int *piv,
                                                    const gen_rt_real *Jw, const gen_rt_real *lam,
                                                    gen_rt_real *work, gen_rt_real *H)
{
    const int nw = m->nw, nz = m->nz;
    gen_rt_real *mu = work, *Hz = mu + nw, *Wz = Hz + nz * nz;
    int k, st;
    if (!m->rh) return GEN_RT_ERR_BAD_ARG;
    for (k = 0; k < nw; ++k) mu[k] = lam[k];
    if ((st = rt_lu_solve_t(nw, lu, piv, 1, mu))) return st;
    m->rh(z, w, mu, Hz, Wz);
    rt_dv_hsym(nz, nw, Hz, Wz, Jw, H);
    return GEN_RT_OK;
}

/* out (n x nv, nv = nz + 1) = A Z for A (n x nz) and a stage's Z =
 * dzeta/dv = E_c + [X; 0] (E_c: the identity on z and c at (t, h); X:
 * nx x nv): each entry A E_c's, then the terms of X in the order of al */
GEN_RT_DERIV_INLINE void rt_dv_mulz(int n, int nx, int nz, const gen_rt_real *RT_DV_RESTRICT A,
                                    const gen_rt_real *RT_DV_RESTRICT X, gen_rt_real c,
                                    gen_rt_real *RT_DV_RESTRICT out)
{
    const int nv = nz + 1;
    int i, a, al;
    for (i = 0; i < n; ++i) {
        const gen_rt_real *Ai = A + i * nz;
        for (a = 0; a < nv; ++a) {
            gen_rt_real s = a < nz ? Ai[a] : c * Ai[nz - 1];
            for (al = 0; al < nx; ++al) s += Ai[al] * X[al * nv + a];
            out[i * nv + a] = s;
        }
    }
}

/* out (nv x nv, nv = nz + 1) += Z^T Hz Z for a symmetric Hz (nz x nz) and
 * a stage's Z = dzeta/dv = E_c + [X; 0] (E_c: the identity on z and c at
 * (t, h); X: nx x nv): B = Hz Z (nz x nv), then the upper triangle of
 * Z^T B, mirrored. nx of the nz rows of Z are dense, so this costs
 * nx (nz nv + nv^2 / 2) instead of nz nv (nz + nv) */
GEN_RT_DERIV_INLINE void rt_dv_zhz(int nx, int nz, const gen_rt_real *RT_DV_RESTRICT Hz,
                                   const gen_rt_real *RT_DV_RESTRICT X, gen_rt_real c,
                                   gen_rt_real *RT_DV_RESTRICT out, gen_rt_real *RT_DV_RESTRICT B)
{
    const int nv = nz + 1;
    int a, b, al;
    rt_dv_mulz(nz, nx, nz, Hz, X, c, B);
    /* the upper triangle of Z^T B (each entry summed in the order of al),
     * added to out, mirrored */
    for (a = 0; a < nv; ++a)
        for (b = a; b < nv; ++b) {
            gen_rt_real s = a < nz ? B[a * nv + b] : c * B[(nz - 1) * nv + b];
            for (al = 0; al < nx; ++al) s += X[al * nv + a] * B[al * nv + b];
            out[a * nv + b] += s;
            if (b != a) out[b * nv + a] += s;
        }
}

/* the RK4 step's scratch (gen_rt_deriv_rk4), carved from its work */
typedef struct {
    gen_rt_real *w, *lu, *Jw, *sw, *lw, *Hz, *hw, *K, *S, *ak, *g, *zk;
    gen_rt_real *Dp, *Dk, *DA, *DM, *X, *G, *ZH, *V, *Ep, *Ek, *EA, *EM, *St;
} rt_dv_rk4_work;

GEN_RT_DERIV_INLINE rt_dv_rk4_work rt_dv_rk4_carve(int nx, int nz, int nw, gen_rt_real *work)
{
    const int nv = nz + 1, npt = GEN_RT_DERIV_POINT_(nz, nw);
    rt_dv_rk4_work r;
    gen_rt_real *w = work;
    r.w = rt_take(&w, nw); r.lu = rt_take(&w, nw * nw); r.Jw = rt_take(&w, nw * nz);
    r.sw = rt_take(&w, GEN_RT_DERIV_SOLVE_WORK(nw)); r.lw = rt_take(&w, nw);
    r.Hz = rt_take(&w, nz * nz); r.hw = rt_take(&w, GEN_RT_DERIV_HESSIAN_WORK(nz, nw));
    r.K = rt_take(&w, 5 * nx); r.S = rt_take(&w, nx); r.ak = rt_take(&w, nx); r.g = rt_take(&w, nx);
    r.zk = rt_take(&w, nz);
    r.Dp = rt_take(&w, nx * nv); r.Dk = rt_take(&w, nx * nv); r.DA = rt_take(&w, nx * nv);
    r.DM = rt_take(&w, nx * nv); r.X = rt_take(&w, nx * nv); r.G = rt_take(&w, nx * nv);
    r.ZH = rt_take(&w, nz * nv); r.V = rt_take(&w, nv * nv);
    r.Ep = rt_take(&w, nx * nv * nv); r.Ek = rt_take(&w, nx * nv * nv);
    r.EA = rt_take(&w, nx * nv * nv); r.EM = rt_take(&w, nx * nv * nv);
    r.St = rt_take(&w, 4 * (nz + npt + 2 * nx * nv));
    return r;
}

/* acc = the runtime's RK4 sum k1 + 2 (k2 + k3) + k4 of stage s's value v
 * (n entries), accumulated in acc (k1, then the sum) and mid (k2 + k3) */
GEN_RT_DERIV_INLINE void rt_dv_rk4_sum(int s, int n, const gen_rt_real *v, gen_rt_real *acc,
                                       gen_rt_real *mid)
{
    int i;
    if (s == 0) for (i = 0; i < n; ++i) acc[i] = v[i];
    else if (s == 1) for (i = 0; i < n; ++i) mid[i] = v[i];
    else if (s == 2) for (i = 0; i < n; ++i) mid[i] += v[i];
    else for (i = 0; i < n; ++i) acc[i] = acc[i] + GEN_RT_C(2.0) * mid[i] + v[i];
}

/* E_k[i] = Z^T Hf_i Z + c (e_h G_i^T + G_i e_h^T + h sum_al Jf[i][al] E_{k-1}[al]),
 * G = Jf_x D_{k-1}: the stage's second derivatives (forward over forward) */
GEN_RT_DERIV_INLINE int rt_dv_rk4_stage_second(const gen_rt_deriv_model *m, const rt_dv_rk4_work *r,
                                               const int *piv, gen_rt_real c, gen_rt_real h)
{
    const int nx = m->nx, nz = m->nz, nw = m->nw, nv = nz + 1;
    int i, a, al, k, st;
    for (i = 0; i < nx; ++i) {
        gen_rt_real *Gi = r->G + i * nv;
        for (a = 0; a < nv; ++a) Gi[a] = 0;
        for (al = 0; al < nx; ++al) {
            const gen_rt_real j_ = r->Jw[i * nz + al], *Da = r->Dp + al * nv;
            for (a = 0; a < nv; ++a) Gi[a] += j_ * Da[a];
        }
    }
    for (i = 0; i < nx; ++i) {
        gen_rt_real *E = r->Ek + i * nv * nv;
        for (k = 0; k < nw; ++k) r->lw[k] = k == i;
        st = gen_rt_deriv_hessian_inline(m, r->zk, r->w, r->lu, piv, r->Jw, r->lw, r->hw, r->Hz);
        if (st) return st;
        for (a = 0; a < nv * nv; ++a) E[a] = 0;
        rt_dv_zhz(nx, nz, r->Hz, r->X, c, E, r->ZH);
        for (al = 0; al < nx; ++al) {
            const gen_rt_real j_ = c * h * r->Jw[i * nz + al], *Ea = r->Ep + al * nv * nv;
            for (a = 0; a < nv * nv; ++a) E[a] += j_ * Ea[a];
        }
        for (a = 0; a < nv; ++a) {
            E[(nv - 1) * nv + a] += c * r->G[i * nv + a];
            E[a * nv + nv - 1] += c * r->G[i * nv + a];
        }
    }
    return GEN_RT_OK;
}

/* Hl = (h/6) d2Phi + (e_h dPhi^T + dPhi e_h^T) / 6, Phi = lam^T (K1 + 2 K2 +
 * 2 K3 + K4): with a_k the adjoint of K_k (a_4 = lam, a_k = w_k lam +
 * c_{k+1} h Jf_{k+1,x}^T a_{k+1}), d2Phi = sum_k Z_k^T d2(a_k^T f)(zeta_k)
 * Z_k + c_k (e_h g_k^T D_{k-1} + ...), g_k = Jf_{k,x}^T a_k (the adjoint of
 * the stage state); the stages' data stored in r->St (nsb reals each) */
GEN_RT_DERIV_INLINE int rt_dv_rk4_adjoint(const gen_rt_deriv_model *m, const rt_dv_rk4_work *r,
                                          const int *spiv, const gen_rt_real *cs, gen_rt_real h,
                                          const gen_rt_real *lam, gen_rt_real *Hl)
{
    const int nx = m->nx, nz = m->nz, nw = m->nw, nv = nz + 1;
    const int nsb = nz + GEN_RT_DERIV_POINT_(nz, nw) + 2 * nx * nv;
    const gen_rt_real hs = h / GEN_RT_C(6.0);
    int s, i, k, a, st;
    for (i = 0; i < nx; ++i) r->g[i] = 0;
    for (s = 3; s >= 0; --s) {
        const gen_rt_real *zs = r->St + s * nsb, *ws = zs + nz, *lus = ws + nw,
                          *Jws = lus + nw * nw, *Xs = Jws + nw * nz, *Ds = Xs + nx * nv;
        const gen_rt_real cn = s < 3 ? cs[s + 1] * h : 0;
        const gen_rt_real wt = (s == 0 || s == 3) ? GEN_RT_C(1.0) : GEN_RT_C(2.0);
        for (i = 0; i < nw; ++i) r->lw[i] = i < nx ? wt * lam[i] + cn * r->g[i] : 0;
        st = gen_rt_deriv_hessian_inline(m, zs, ws, lus, spiv + s * nw, Jws, r->lw, r->hw, r->Hz);
        if (st) return st;
        rt_dv_zhz(nx, nz, r->Hz, Xs, cs[s], Hl, r->ZH);
        for (i = 0; i < nx; ++i) {
            gen_rt_real v = 0;
            for (k = 0; k < nx; ++k) v += Jws[k * nz + i] * r->lw[k];
            r->ak[i] = v;
        }
        for (a = 0; a < nv; ++a) {
            gen_rt_real v = 0;
            for (i = 0; i < nx; ++i) v += r->ak[i] * Ds[i * nv + a];
            Hl[(nv - 1) * nv + a] += cs[s] * v;
            Hl[a * nv + nv - 1] += cs[s] * v;
        }
        for (i = 0; i < nx; ++i) r->g[i] = r->ak[i];
    }
    for (i = 0; i < nv * nv; ++i) Hl[i] *= hs;
    for (a = 0; a < nv; ++a) {
        gen_rt_real v = 0;
        for (i = 0; i < nx; ++i) v += r->DA[i * nv + a] * lam[i];
        v = v / GEN_RT_C(6.0);
        Hl[(nv - 1) * nv + a] += v;
        Hl[a * nv + nv - 1] += v;
    }
    return GEN_RT_OK;
}

/* x+ = x + (h/6) S, S = K1 + 2 (K2 + K3) + K4: J = [I 0] + (h/6) DA +
 * S e_h^T / 6; T = (h/6) EA + (e_h DA^T + DA e_h^T) / 6 */
GEN_RT_DERIV_INLINE void rt_dv_rk4_outputs(int nx, int nz, const rt_dv_rk4_work *r, gen_rt_real h,
                                           const gen_rt_real *z, gen_rt_real *xn, gen_rt_real *J,
                                           gen_rt_real *T)
{
    const int nv = nz + 1;
    const gen_rt_real hs = h / GEN_RT_C(6.0);
    const gen_rt_real *k1 = r->K + nx, *k2 = k1 + nx, *k3 = k2 + nx, *k4 = k3 + nx;
    int i, a;
    for (i = 0; i < nx; ++i) r->S[i] = k1[i] + GEN_RT_C(2.0) * (k2[i] + k3[i]) + k4[i];
    if (xn)     /* the arithmetic of gen_rt_rk4_step */
        for (i = 0; i < nx; ++i)
            xn[i] = z[i] + (h / GEN_RT_C(6.0)) * (k1[i] + GEN_RT_C(2.0) * (k2[i] + k3[i]) + k4[i]);
    if (J)
        for (i = 0; i < nx; ++i) {
            for (a = 0; a < nv; ++a) J[i * nv + a] = hs * r->DA[i * nv + a];
            J[i * nv + i] += 1;
            J[i * nv + nv - 1] += r->S[i] / GEN_RT_C(6.0);
        }
    if (T) {
        for (i = 0; i < nx * nv * nv; ++i) T[i] = hs * r->EA[i];
        for (i = 0; i < nx; ++i)
            for (a = 0; a < nv; ++a) {
                const gen_rt_real d = r->DA[i * nv + a] / GEN_RT_C(6.0);
                T[(i * nv + nv - 1) * nv + a] += d;
                T[(i * nv + a) * nv + nv - 1] += d;
            }
    }
}

/* the stage's state zeta = (x + c h K_{k-1}, r, p, t + c h), X = dzeta_x/dv
 * = c h D_{k-1} + c K_{k-1} e_h^T, and after the solve D_k = Jf dzeta/dv */
GEN_RT_DERIV_INLINE void rt_dv_rk4_stage_first(int nx, int nz, const rt_dv_rk4_work *r,
                                               const gen_rt_real *z, const gen_rt_real *Kp,
                                               gen_rt_real c, gen_rt_real h, int solved)
{
    const int nv = nz + 1;
    int i, a;
    if (!solved) {
        for (i = 0; i < nz; ++i) r->zk[i] = z[i];
        for (i = 0; i < nx; ++i) r->zk[i] += c * h * Kp[i];
        r->zk[nz - 1] += c * h;
        for (i = 0; i < nx; ++i) {
            for (a = 0; a < nv; ++a) r->X[i * nv + a] = c * h * r->Dp[i * nv + a];
            r->X[i * nv + nv - 1] += c * Kp[i];
        }
        return;
    }
    rt_dv_mulz(nx, nx, nz, r->Jw, r->X, c, r->Dk);
}

GEN_RT_DERIV_APART int gen_rt_deriv_rk4_inline(const gen_rt_deriv_model *m, const gen_rt_real *z,
                                               gen_rt_real h, const gen_rt_real *lam,
                                               gen_rt_real *work, int *iwork, gen_rt_real *xn,
                                               gen_rt_real *J, gen_rt_real *Hl, gen_rt_real *T)
{
    /* the runtime's RK4 (gen_rt_rk4_step): c h = 0, h/2, h/2, h */
    const gen_rt_real cs[4] = {0, GEN_RT_C(0.5), GEN_RT_C(0.5), GEN_RT_C(1.0)};
    const int nx = m->nx, nz = m->nz, nw = m->nw, nv = nz + 1;
    const int npt = GEN_RT_DERIV_POINT_(nz, nw), nsb = nz + npt + 2 * nx * nv;
    const int second = T != 0, adj = Hl != 0 && T == 0 && lam != 0;
    rt_dv_rk4_work r = rt_dv_rk4_carve(nx, nz, nw, work);
    int *piv = iwork, *spiv = iwork + nw;
    int s, i, st;
    if ((Hl || T) && !m->rh) return GEN_RT_ERR_BAD_ARG;
    for (i = 0; i < nx; ++i) r.K[i] = 0;            /* K_0 = 0, D_0 = 0, E_0 = 0 */
    for (i = 0; i < nx * nv; ++i) r.Dp[i] = 0;
    if (second) for (i = 0; i < nx * nv * nv; ++i) r.Ep[i] = 0;
    for (s = 0; s < 4; ++s) {
        const gen_rt_real c = cs[s];
        gen_rt_real *tmp;
        rt_dv_rk4_stage_first(nx, nz, &r, z, r.K + s * nx, c, h, 0);
        if ((st = gen_rt_deriv_solve_inline(m, r.zk, r.sw, r.w, r.lu, piv, r.Jw))) return st;
        rt_dv_rk4_stage_first(nx, nz, &r, z, r.K + s * nx, c, h, 1);
        if (adj) {
            /* the stage's data for the adjoint sweep: zeta, w, Rw's LU, dw/dz, X, D_{k-1} */
            gen_rt_real *sb = r.St + s * nsb;
            rt_copy(nz, r.zk, sb);
            rt_copy(npt, r.w, sb + nz);    /* w, lu, Jw: contiguous */
            rt_copy(nx * nv, r.X, sb + nz + npt);
            rt_copy(nx * nv, r.Dp, sb + nz + npt + nx * nv);
            for (i = 0; i < nw; ++i) spiv[s * nw + i] = piv[i];
        }
        if (second && (st = rt_dv_rk4_stage_second(m, &r, piv, c, h))) return st;
        rt_copy(nx, r.w, r.K + (s + 1) * nx);
        rt_dv_rk4_sum(s, nx * nv, r.Dk, r.DA, r.DM);
        tmp = r.Dp; r.Dp = r.Dk; r.Dk = tmp;
        if (second) {
            rt_dv_rk4_sum(s, nx * nv * nv, r.Ek, r.EA, r.EM);
            tmp = r.Ep; r.Ep = r.Ek; r.Ek = tmp;
        }
    }
    rt_dv_rk4_outputs(nx, nz, &r, h, z, xn, J, T);
    if (Hl) {
        for (i = 0; i < nv * nv; ++i) Hl[i] = 0;
        if (adj && (st = rt_dv_rk4_adjoint(m, &r, spiv, cs, h, lam, Hl))) return st;
        if (second && lam)
            for (s = 0; s < nx; ++s)
                if (lam[s] != 0)
                    for (i = 0; i < nv * nv; ++i) Hl[i] += lam[s] * T[s * nv * nv + i];
    }
    if ((xn && !rt_finite(nx, xn)) || (J && !rt_finite(nx * nv, J)) ||
        (T && !rt_finite(nx * nv * nv, T)) || (Hl && !rt_finite(nv * nv, Hl)))
        return GEN_RT_ERR_NONFINITE_MODEL;
    return GEN_RT_OK;
}

GEN_RT_DERIV_APART int gen_rt_deriv_rodas4_inline(const gen_rt_deriv_model *m, const gen_rt_real *z,
                                                  gen_rt_real h, gen_rt_real *work, int *iwork,
                                                  gen_rt_real *J)
{
    const gen_rt_real al_[6] = {0, RT_DV_ALPHA2, RT_DV_ALPHA3, RT_DV_ALPHA4, 1, 1};
    const gen_rt_real ga_[6] = {RT_DV_GAMMA, RT_DV_GAMMA2, RT_DV_GAMMA3, RT_DV_GAMMA4, 0, 0};
    const gen_rt_real A_[6][5] = {
        {0, 0, 0, 0, 0}, {RT_DV_A21, 0, 0, 0, 0}, {RT_DV_A31, RT_DV_A32, 0, 0, 0},
        {RT_DV_A41, RT_DV_A42, RT_DV_A43, 0, 0}, {RT_DV_A51, RT_DV_A52, RT_DV_A53, RT_DV_A54, 0},
        {RT_DV_A51, RT_DV_A52, RT_DV_A53, RT_DV_A54, 1}};
    const gen_rt_real C_[6][5] = {
        {0, 0, 0, 0, 0}, {RT_DV_C21, 0, 0, 0, 0}, {RT_DV_C31, RT_DV_C32, 0, 0, 0},
        {RT_DV_C41, RT_DV_C42, RT_DV_C43, 0, 0}, {RT_DV_C51, RT_DV_C52, RT_DV_C53, RT_DV_C54, 0},
        {RT_DV_C61, RT_DV_C62, RT_DV_C63, RT_DV_C64, RT_DV_C65}};
    const gen_rt_real b_[6] = {RT_DV_A51, RT_DV_A52, RT_DV_A53, RT_DV_A54, 1, 1};
    const int nx = m->nx, nz = m->nz, nw = m->nw, nv = nz + 1;
    gen_rt_real *wk = work;
    gen_rt_real *w = rt_take(&wk, nw), *lu = rt_take(&wk, nw * nw), *Jw = rt_take(&wk, nw * nz),
                *sw = rt_take(&wk, GEN_RT_DERIV_SOLVE_WORK(nw)), *lw = rt_take(&wk, nw),
                *hw = rt_take(&wk, GEN_RT_DERIV_HESSIAN_WORK(nz, nw)), *f0 = rt_take(&wk, nx),
                *J0 = rt_take(&wk, nx * nz), *Hr = rt_take(&wk, nx * nz * nz),
                *G = rt_take(&wk, nx * nx), *K = rt_take(&wk, 6 * nx),
                *dK = rt_take(&wk, 6 * nx * nv), *Zt = rt_take(&wk, nz * nv),
                *B = rt_take(&wk, nx * nv), *zk = rt_take(&wk, nz);
    int *piv = iwork, *gpiv = iwork + nw;
    gen_rt_real ih, hg;
    int i, j, k, s, a, c, st;
    if (!m->rh || !(h != 0)) return GEN_RT_ERR_BAD_ARG;
    ih = 1 / h;
    hg = 1 / (h * RT_DV_GAMMA);
    /* f, Jf and the Hessians of f's rows at z */
    if ((st = gen_rt_deriv_solve_inline(m, z, sw, w, lu, piv, Jw))) return st;
    rt_copy(nx, w, f0);
    rt_copy(nx * nz, Jw, J0);
    for (i = 0; i < nx; ++i) {
        for (k = 0; k < nw; ++k) lw[k] = k == i;
        if ((st = gen_rt_deriv_hessian_inline(m, z, w, lu, piv, Jw, lw, hw, Hr + i * nz * nz)))
            return st;
    }
    for (i = 0; i < nx; ++i)
        for (j = 0; j < nx; ++j) G[i * nx + j] = (i == j ? hg : 0) - J0[i * nz + j];
    if ((st = rt_lu_factor(nx, G, gpiv, 0))) return st;
    for (s = 0; s < 6; ++s) {
        gen_rt_real *Ks = K + s * nx, *dKs = dK + s * nx * nv;
        const gen_rt_real *fs = f0, *Js = J0;
        /* zeta_s and Zt = dzeta_s/dv */
        for (i = 0; i < nz; ++i) zk[i] = z[i];
        for (i = 0; i < nz * nv; ++i) Zt[i] = 0;
        for (i = 0; i < nz; ++i) Zt[i * nv + i] = 1;
        for (j = 0; j < s; ++j)
            for (i = 0; i < nx; ++i) {
                zk[i] += A_[s][j] * K[j * nx + i];
                for (c = 0; c < nv; ++c) Zt[i * nv + c] += A_[s][j] * dK[(j * nx + i) * nv + c];
            }
        zk[nz - 1] += al_[s] * h;
        Zt[(nz - 1) * nv + nv - 1] += al_[s];
        if (s > 0) {
            if ((st = gen_rt_deriv_solve_inline(m, zk, sw, w, lu, piv, Jw))) return st;
            fs = w;
            Js = Jw;
        }
        /* K_s = G^-1 F_s; B = dF_s + (d(Jf_x)/dv) K_s + e_h K_s / (h^2 gamma) */
        for (i = 0; i < nx; ++i) {
            gen_rt_real F = fs[i] + h * ga_[s] * J0[i * nz + nz - 1];
            for (j = 0; j < s; ++j) F += ih * C_[s][j] * K[j * nx + i];
            Ks[i] = F;
        }
        if ((st = rt_lu_solve(nx, G, gpiv, 1, Ks))) return st;
        for (i = 0; i < nx; ++i) {
            const gen_rt_real *Hi = Hr + i * nz * nz;
            gen_rt_real eh = ga_[s] * J0[i * nz + nz - 1] + Ks[i] * ih * hg;
            gen_rt_real *Bi = B + i * nv;
            /* each entry summed in the order of the terms, row by row */
            for (c = 0; c < nv; ++c) Bi[c] = 0;
            for (a = 0; a < nz; ++a) {
                const gen_rt_real ja = Js[i * nz + a], *Za = Zt + a * nv;
                for (c = 0; c < nv; ++c) Bi[c] += ja * Za[c];
            }
            for (j = 0; j < s; ++j) {
                const gen_rt_real cj = ih * C_[s][j], *dKj = dK + (j * nx + i) * nv;
                for (c = 0; c < nv; ++c) Bi[c] += cj * dKj[c];
            }
            for (c = 0; c < nz; ++c) Bi[c] += h * ga_[s] * Hi[(nz - 1) * nz + c];
            for (a = 0; a < nx; ++a) {
                const gen_rt_real ka = Ks[a], *Ha = Hi + a * nz;
                for (c = 0; c < nz; ++c) Bi[c] += Ha[c] * ka;
            }
            for (j = 0; j < s; ++j) eh -= ih * ih * C_[s][j] * K[j * nx + i];
            B[i * nv + nv - 1] += eh;
        }
        if ((st = rt_lu_solve(nx, G, gpiv, nv, B))) return st;
        rt_copy(nx * nv, B, dKs);
    }
    for (i = 0; i < nx; ++i)
        for (c = 0; c < nv; ++c) {
            gen_rt_real v = c == i;
            for (s = 0; s < 6; ++s) v += b_[s] * dK[(s * nx + i) * nv + c];
            J[i * nv + c] = v;
        }
    return rt_finite(nx * nv, J) ? GEN_RT_OK : GEN_RT_ERR_NONFINITE_MODEL;
}

#endif /* GEN_RT_DERIV_INLINE_H */
