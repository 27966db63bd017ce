/* gen_rt_linearize.c - linearization of a constrained model about any
 * operating point (Peterson, Gede & Hubbard's elimination, done numerically).
 *
 * Perturbations of the dependent coordinates and speeds follow from the
 * constraint Jacobians:   Jc dq = 0,   A du + Vq dq = 0,
 * the coordinate rates from the kinematic equations
 *                         Kqd dq' + Kq dq + Ku du = 0,
 * and the accelerations and multipliers from the differentiated dynamics
 *   [M  -A^T] [du' ]     [Rq dq + Ru du + Rr dr]
 *   [A    0 ] [dlam] = - [Sq dq + Su du        ].                          */
#include "gen_rt_private.h"

int gen_rt_linearize(const gen_rt_lin_dims *d, const gen_rt_lin_blocks *b,
                     gen_rt_real *work, int *iwork, gen_rt_real *A_lin,
                     gen_rt_real *B_lin)
{
    int nq, nu, mc, mv, nr, niq, niu, ns, N, i, j, k, st;
    gen_rt_real *w = work;
    gen_rt_real *Q, *Jd, *X, *Uu, *Uq, *Ad, *Y, *Dq, *T1, *K, *G, *T2, *T3, *VqQ, *Kf;
    if (!d || !b || !work || !iwork || !A_lin) return GEN_RT_ERR_NULL;
    nq = d->nq; nu = d->nu; mc = d->mc; mv = d->mv; nr = d->nr;
    niq = nq - mc; niu = nu - mv; ns = niq + niu; N = nu + mv;
    if (nq <= 0 || nu <= 0 || mc < 0 || mv < 0 || nr < 0 || niq < 0 || niu < 0)
        return GEN_RT_ERR_BAD_ARG;
    if (!b->Kqd || !b->Kq || !b->Ku || !b->M || !b->Rq || !b->Ru) return GEN_RT_ERR_NULL;
    if (nr > 0 && (!b->Rr || !B_lin)) return GEN_RT_ERR_NULL;
    if (mv > 0 && (!b->A || !b->Sq || !b->Su || !b->Vq || !d->u_dep)) return GEN_RT_ERR_NULL;
    if (mc > 0 && (!b->Jc || !d->q_dep)) return GEN_RT_ERR_NULL;
    if ((niq > 0 && !d->q_ind) || (niu > 0 && !d->u_ind)) return GEN_RT_ERR_NULL;

    Q = rt_take(&w, nq * niq);
    Jd = rt_take(&w, mc * mc);
    X = rt_take(&w, mc * niq);
    Uu = rt_take(&w, nu * niu);
    Uq = rt_take(&w, nu * niq);
    Ad = rt_take(&w, mv * mv);
    Y = rt_take(&w, mv * ns);
    Dq = rt_take(&w, nq * ns);
    T1 = rt_take(&w, nq * ns);
    K = rt_take(&w, N * N);
    G = rt_take(&w, N * (ns + nr));
    T2 = rt_take(&w, nu * ns);
    T3 = rt_take(&w, nu * niq);
    VqQ = rt_take(&w, mv * niq);
    Kf = rt_take(&w, nq * nq);

    /* 1. coordinates: dq = Q dq_ind */
    for (i = 0; i < nq * niq; ++i) Q[i] = 0;
    for (k = 0; k < niq; ++k) Q[d->q_ind[k] * niq + k] = 1;
    if (mc > 0) {
        for (i = 0; i < mc; ++i) {
            for (j = 0; j < mc; ++j) Jd[i * mc + j] = b->Jc[i * nq + d->q_dep[j]];
            for (k = 0; k < niq; ++k) X[i * niq + k] = b->Jc[i * nq + d->q_ind[k]];
        }
        st = gen_rt_lu_factor(mc, Jd, iwork, gen_rt_max_abs(mc * nq, b->Jc));
        if (st) return st;
        if ((st = gen_rt_lu_solve(mc, Jd, iwork, niq, X))) return st;
        for (j = 0; j < mc; ++j)
            for (k = 0; k < niq; ++k) Q[d->q_dep[j] * niq + k] = -X[j * niq + k];
    }
    /* 2. speeds: du = Uq dq_ind + Uu du_ind */
    for (i = 0; i < nu * niu; ++i) Uu[i] = 0;
    for (i = 0; i < nu * niq; ++i) Uq[i] = 0;
    for (k = 0; k < niu; ++k) Uu[d->u_ind[k] * niu + k] = 1;
    if (mv > 0) {
        gen_rt_matmul(mv, nq, niq, b->Vq, Q, VqQ);
        for (i = 0; i < mv; ++i) {
            for (j = 0; j < mv; ++j) Ad[i * mv + j] = b->A[i * nu + d->u_dep[j]];
            for (k = 0; k < niu; ++k) Y[i * ns + k] = b->A[i * nu + d->u_ind[k]];
            for (k = 0; k < niq; ++k) Y[i * ns + niu + k] = VqQ[i * niq + k];
        }
        st = gen_rt_lu_factor(mv, Ad, iwork, gen_rt_max_abs(mv * nu, b->A));
        if (st) return st;
        if ((st = gen_rt_lu_solve(mv, Ad, iwork, ns, Y))) return st;
        for (j = 0; j < mv; ++j) {
            for (k = 0; k < niu; ++k) Uu[d->u_dep[j] * niu + k] = -Y[j * ns + k];
            for (k = 0; k < niq; ++k) Uq[d->u_dep[j] * niq + k] = -Y[j * ns + niu + k];
        }
    }
    /* 3. kinematics: dq' = Dq [dq_ind; du_ind],  Dq = -Kqd^-1 [Kq Q + Ku Uq | Ku Uu] */
    gen_rt_matmul(nq, nq, niq, b->Kq, Q, T1);
    for (i = 0; i < nq; ++i) {
        for (k = 0; k < niq; ++k) {
            gen_rt_real s = T1[i * niq + k];
            for (j = 0; j < nu; ++j) s += b->Ku[i * nu + j] * Uq[j * niq + k];
            Dq[i * ns + k] = -s;
        }
        for (k = 0; k < niu; ++k) {
            gen_rt_real s = 0;
            for (j = 0; j < nu; ++j) s += b->Ku[i * nu + j] * Uu[j * niu + k];
            Dq[i * ns + niq + k] = -s;
        }
    }
    for (i = 0; i < nq * nq; ++i) Kf[i] = b->Kqd[i];
    if ((st = gen_rt_lu_factor(nq, Kf, iwork, 0))) return st;
    if ((st = gen_rt_lu_solve(nq, Kf, iwork, ns, Dq))) return st;

    /* 4. dynamics: KKT matrix and the right-hand sides */
    gen_rt_kkt_matrix(nu, mv, b->M, b->A, K);
    /* rows of R: Rq Q + Ru Uq | Ru Uu | Rr */
    gen_rt_matmul(nu, nq, niq, b->Rq, Q, T3);
    gen_rt_matmul(nu, nu, niq, b->Ru, Uq, T2);
    for (i = 0; i < nu; ++i) {
        for (k = 0; k < niq; ++k)
            G[i * (ns + nr) + k] = -(T3[i * niq + k] + T2[i * niq + k]);
    }
    gen_rt_matmul(nu, nu, niu, b->Ru, Uu, T2);
    for (i = 0; i < nu; ++i) {
        for (k = 0; k < niu; ++k) G[i * (ns + nr) + niq + k] = -T2[i * niu + k];
        for (k = 0; k < nr; ++k) G[i * (ns + nr) + ns + k] = -b->Rr[i * nr + k];
    }
    if (mv > 0) {
        gen_rt_matmul(mv, nq, niq, b->Sq, Q, T3);
        gen_rt_matmul(mv, nu, niq, b->Su, Uq, T2);
        for (i = 0; i < mv; ++i)
            for (k = 0; k < niq; ++k)
                G[(nu + i) * (ns + nr) + k] = -(T3[i * niq + k] + T2[i * niq + k]);
        gen_rt_matmul(mv, nu, niu, b->Su, Uu, T2);
        for (i = 0; i < mv; ++i) {
            for (k = 0; k < niu; ++k) G[(nu + i) * (ns + nr) + niq + k] = -T2[i * niu + k];
            for (k = 0; k < nr; ++k) G[(nu + i) * (ns + nr) + ns + k] = 0;
        }
        /* S holds q' (implicit kinematics): its share through dq' = Dq */
        if (b->Sqd)
            for (i = 0; i < mv; ++i)
                for (k = 0; k < ns; ++k) {
                    gen_rt_real s = 0;
                    for (j = 0; j < nq; ++j) s += b->Sqd[i * nq + j] * Dq[j * ns + k];
                    G[(nu + i) * (ns + nr) + k] -= s;
                }
    }
    if ((st = gen_rt_lu_factor(N, K, iwork, 0))) return st;
    if ((st = gen_rt_lu_solve(N, K, iwork, ns + nr, G))) return st;

    /* 5. gather the independent rows */
    for (k = 0; k < niq; ++k) {
        for (j = 0; j < ns; ++j) A_lin[k * ns + j] = Dq[d->q_ind[k] * ns + j];
        for (j = 0; j < nr; ++j) B_lin[k * nr + j] = 0;
    }
    for (k = 0; k < niu; ++k) {
        const gen_rt_real *row = G + d->u_ind[k] * (ns + nr);
        for (j = 0; j < ns; ++j) A_lin[(niq + k) * ns + j] = row[j];
        for (j = 0; j < nr; ++j) B_lin[(niq + k) * nr + j] = row[ns + j];
    }
    if (!gen_rt_all_finite(ns * ns, A_lin) || (nr > 0 && !gen_rt_all_finite(ns * nr, B_lin)))
        return GEN_RT_ERR_SINGULAR;
    /* 6. outputs: dy = Yq dq + Yu du + Yr dr = [Yq Q + Yu Uq | Yu Uu] dx_ind + Yr dr */
    if (b->ny > 0 && b->C_lin) {
        int ny = b->ny;
        if (!b->Yq || !b->Yu || (nr > 0 && (!b->Yr || !b->D_lin))) return GEN_RT_ERR_NULL;
        for (i = 0; i < ny; ++i) {
            for (k = 0; k < niq; ++k) {
                gen_rt_real s = 0;
                for (j = 0; j < nq; ++j) s += b->Yq[i * nq + j] * Q[j * niq + k];
                for (j = 0; j < nu; ++j) s += b->Yu[i * nu + j] * Uq[j * niq + k];
                b->C_lin[i * ns + k] = s;
            }
            for (k = 0; k < niu; ++k) {
                gen_rt_real s = 0;
                for (j = 0; j < nu; ++j) s += b->Yu[i * nu + j] * Uu[j * niu + k];
                b->C_lin[i * ns + niq + k] = s;
            }
            for (k = 0; k < nr; ++k) b->D_lin[i * nr + k] = b->Yr[i * nr + k];
        }
        if (!gen_rt_all_finite(ny * ns, b->C_lin) ||
            (nr > 0 && !gen_rt_all_finite(ny * nr, b->D_lin)))
            return GEN_RT_ERR_NONFINITE_MODEL;
    }
    return GEN_RT_OK;
}
