/* gen_rt_dynamics.c - accelerations (and multipliers) of a constrained model:
 *   M u' = f + A^T lam,   A u' + a = 0.                                     */
#include "gen_rt_private.h"

void gen_rt_kkt_matrix(int n, int m, const gen_rt_real *M, const gen_rt_real *A,
                       gen_rt_real *K)
{
    int N = n + m, i, j;
    for (i = 0; i < N; ++i)
        for (j = 0; j < N; ++j) {
            gen_rt_real v = 0;
            if (i < n && j < n) v = M[i * n + j];
            else if (i < n) v = -A[(j - n) * n + i];
            else if (j < n) v = A[(i - n) * n + j];
            K[i * N + j] = v;
        }
}

int gen_rt_accel_kkt(int n, int m, const gen_rt_real *M, const gen_rt_real *f,
                     const gen_rt_real *A, const gen_rt_real *a,
                     gen_rt_real *work, int *iwork, gen_rt_real *ud,
                     gen_rt_real *lam)
{
    int N = n + m, i, st;
    gen_rt_real *K = work, *z = work + N * N;
    if (n <= 0 || m < 0) return GEN_RT_ERR_BAD_ARG;
    if (!M || !f || !work || !iwork || !ud || (m > 0 && (!A || !a)))
        return GEN_RT_ERR_NULL;
    gen_rt_kkt_matrix(n, m, M, A, K);
    for (i = 0; i < n; ++i) z[i] = f[i];
    for (i = 0; i < m; ++i) z[n + i] = -a[i];
    st = gen_rt_lu_factor(N, K, iwork, 0);
    if (st) return st;
    st = gen_rt_lu_solve(N, K, iwork, 1, z);
    if (st) return st;
    if (!gen_rt_all_finite(N, z)) return GEN_RT_ERR_SINGULAR;
    for (i = 0; i < n; ++i) ud[i] = z[i];
    if (lam) for (i = 0; i < m; ++i) lam[i] = z[n + i];
    return GEN_RT_OK;
}

int gen_rt_accel_partitioned(int n, int m, const int *ind, const int *dep,
                             const gen_rt_real *M, const gen_rt_real *f,
                             const gen_rt_real *A, const gen_rt_real *a,
                             gen_rt_real *work, int *iwork, gen_rt_real *ud,
                             gen_rt_real *lam)
{
    int ni = n - m, i, j, k, st;
    gen_rt_real *Ad, *C, *T, *cf, *MT, *Mr, *fr, *tmp;
    if (n <= 0 || m < 0 || ni < 0) return GEN_RT_ERR_BAD_ARG;
    if (!M || !f || !work || !iwork || !ud) return GEN_RT_ERR_NULL;
    if (m > 0 && (!A || !a || !dep)) return GEN_RT_ERR_NULL;
    if (ni > 0 && !ind) return GEN_RT_ERR_NULL;
    Ad = work;                 /* m x m */
    C = Ad + m * m;            /* m x (ni + 1): [-Ad^-1 A_i | -Ad^-1 a] */
    T = C + m * (ni + 1);      /* n x ni */
    cf = T + n * ni;           /* n */
    MT = cf + n;               /* n x ni */
    Mr = MT + n * ni;          /* ni x ni */
    fr = Mr + ni * ni;         /* ni */
    tmp = fr + ni;             /* n */
    if (m > 0) {
        for (i = 0; i < m; ++i) {
            for (j = 0; j < m; ++j) Ad[i * m + j] = A[i * n + dep[j]];
            for (k = 0; k < ni; ++k) C[i * (ni + 1) + k] = -A[i * n + ind[k]];
            C[i * (ni + 1) + ni] = -a[i];
        }
        st = gen_rt_lu_factor(m, Ad, iwork, gen_rt_max_abs(m * n, A));
        if (st) return st;
        st = gen_rt_lu_solve(m, Ad, iwork, ni + 1, C);
        if (st) return st;
        if (!gen_rt_all_finite(m * (ni + 1), C)) return GEN_RT_ERR_SINGULAR;
        for (i = 0; i < m * (ni + 1); ++i) {
            if ((i % (ni + 1)) != ni &&
                (C[i] > GEN_RT_PARTITION_CMAX || C[i] < -GEN_RT_PARTITION_CMAX))
                return GEN_RT_ERR_SINGULAR;
        }
    }
    for (i = 0; i < n * ni; ++i) T[i] = 0;
    for (i = 0; i < n; ++i) cf[i] = 0;
    for (k = 0; k < ni; ++k) T[ind[k] * ni + k] = 1;
    for (j = 0; j < m; ++j) {
        for (k = 0; k < ni; ++k) T[dep[j] * ni + k] = C[j * (ni + 1) + k];
        cf[dep[j]] = C[j * (ni + 1) + ni];
    }
    /* reduced system (T^T M T) ui' = T^T (f - M cf) */
    gen_rt_matmul(n, n, ni, M, T, MT);
    for (i = 0; i < ni; ++i)
        for (j = 0; j < ni; ++j) {
            gen_rt_real s = 0;
            for (k = 0; k < n; ++k) s += T[k * ni + i] * MT[k * ni + j];
            Mr[i * ni + j] = s;
        }
    gen_rt_matmul(n, n, 1, M, cf, tmp);
    for (k = 0; k < n; ++k) tmp[k] = f[k] - tmp[k];
    for (i = 0; i < ni; ++i) {
        gen_rt_real s = 0;
        for (k = 0; k < n; ++k) s += T[k * ni + i] * tmp[k];
        fr[i] = s;
    }
    if (ni > 0) {
        st = gen_rt_lu_factor(ni, Mr, iwork, 0);
        if (st) return st;
        st = gen_rt_lu_solve(ni, Mr, iwork, 1, fr);
        if (st) return st;
    }
    gen_rt_matmul(n, ni, 1, T, fr, ud);
    for (k = 0; k < n; ++k) ud[k] += cf[k];
    if (!gen_rt_all_finite(n, ud)) return GEN_RT_ERR_SINGULAR;
    if (lam && m > 0) {
        /* A A^T lam = A (M ud - f); reuse the work space from Ad on */
        gen_rt_real *AAt = work, *y = work + m * m, *r = y + m;
        gen_rt_matmul(n, n, 1, M, ud, r);
        for (k = 0; k < n; ++k) r[k] -= f[k];
        for (i = 0; i < m; ++i) {
            gen_rt_real s = 0;
            for (j = 0; j < m; ++j) {
                gen_rt_real t2 = 0;
                for (k = 0; k < n; ++k) t2 += A[i * n + k] * A[j * n + k];
                AAt[i * m + j] = t2;
            }
            for (k = 0; k < n; ++k) s += A[i * n + k] * r[k];
            y[i] = s;
        }
        st = gen_rt_lu_factor(m, AAt, iwork, 0);
        if (st) return st;
        st = gen_rt_lu_solve(m, AAt, iwork, 1, y);
        if (st) return st;
        /* accelerations can be finite while M ud - f overflows (found by the fuzzer) */
        if (!gen_rt_all_finite(m, y)) return GEN_RT_ERR_SINGULAR;
        for (i = 0; i < m; ++i) lam[i] = y[i];
    }
    return GEN_RT_OK;
}

/* K = [M, -G; C, H] ((n + na) square) into K */
static void reactions_matrix(int n, int na, const gen_rt_real *M, const gen_rt_real *G,
                             const gen_rt_real *C, const gen_rt_real *H, gen_rt_real *K)
{
    int N = n + na, i, j;
    for (i = 0; i < N; ++i)
        for (j = 0; j < N; ++j) {
            gen_rt_real v;
            if (i < n && j < n) v = M[i * n + j];
            else if (i < n) v = -G[i * na + (j - n)];
            else if (j < n) v = C[(i - n) * n + j];
            else v = H[(i - n) * na + (j - n)];
            K[i * N + j] = v;
        }
}

int gen_rt_accel_reactions(int n, int na, const gen_rt_real *M, const gen_rt_real *f,
                           const gen_rt_real *G, const gen_rt_real *C, const gen_rt_real *H,
                           const gen_rt_real *g0, gen_rt_real *work, int *iwork,
                           gen_rt_real *ud, gen_rt_real *R)
{
    int N = n + na, i;
    gen_rt_real *K = work, *z = work + N * N;
    if (n <= 0 || na <= 0) return GEN_RT_ERR_BAD_ARG;
    if (!M || !f || !G || !C || !H || !g0 || !work || !iwork || !ud) return GEN_RT_ERR_NULL;
    reactions_matrix(n, na, M, G, C, H, K);
    for (i = 0; i < n; ++i) z[i] = f[i];
    for (i = 0; i < na; ++i) z[n + i] = -g0[i];
    if (!gen_rt_all_finite(N * N, K) || !gen_rt_all_finite(N, z))
        return GEN_RT_ERR_NONFINITE_MODEL;
    if (gen_rt_lu_factor(N, K, iwork, 0) || gen_rt_lu_solve(N, K, iwork, 1, z) ||
        !gen_rt_all_finite(N, z))
        return GEN_RT_ERR_SINGULAR_REACTIONS;
    for (i = 0; i < n; ++i) ud[i] = z[i];
    if (R) for (i = 0; i < na; ++i) R[i] = z[n + i];
    return GEN_RT_OK;
}

int gen_rt_reactions_columns(int n, int na, const gen_rt_real *M, const gen_rt_real *G,
                             const gen_rt_real *C, const gen_rt_real *H, int nc,
                             gen_rt_real *work, int *iwork, gen_rt_real *B)
{
    int N = n + na;
    gen_rt_real *K = work;
    if (n <= 0 || na <= 0 || nc < 0) return GEN_RT_ERR_BAD_ARG;
    if (!M || !G || !C || !H || !work || !iwork || (nc > 0 && !B)) return GEN_RT_ERR_NULL;
    reactions_matrix(n, na, M, G, C, H, K);
    if (!gen_rt_all_finite(N * N, K)) return GEN_RT_ERR_NONFINITE_MODEL;
    if (gen_rt_lu_factor(N, K, iwork, 0) || (nc > 0 && gen_rt_lu_solve(N, K, iwork, nc, B)) ||
        !gen_rt_all_finite(N * nc, B))
        return GEN_RT_ERR_SINGULAR_REACTIONS;
    return GEN_RT_OK;
}

int gen_rt_reactions_lin(int nq, int nu, int nr, int na, const gen_rt_real *M,
                         const gen_rt_real *G, const gen_rt_real *C, const gen_rt_real *H,
                         const gen_rt_real *Xq, const gen_rt_real *Xu, const gen_rt_real *Xr,
                         const gen_rt_real *Pq, const gen_rt_real *Pu, const gen_rt_real *Pr,
                         gen_rt_real *work, int *iwork, gen_rt_real *Rq, gen_rt_real *Ru,
                         gen_rt_real *Rr, gen_rt_real *Mout)
{
    int nc = nq + nu + nr, i, j, st;
    gen_rt_real *B = work, *w = work + (nu + na) * nc;
    if (nq < 0 || nu <= 0 || nr < 0 || na <= 0) return GEN_RT_ERR_BAD_ARG;
    if (!M || !G || !C || !H || !Xq || !Xu || !Pq || !Pu || !work || !iwork || !Rq || !Ru ||
        !Mout || (nr > 0 && (!Xr || !Pr || !Rr)))
        return GEN_RT_ERR_NULL;
    /* B = [Rq + Xq, Ru + Xu, Rr + Xr; Pq, Pu, Pr] */
    for (i = 0; i < nu; ++i) {
        gen_rt_real *b = B + i * nc;
        for (j = 0; j < nq; ++j) b[j] = Rq[i * nq + j] + Xq[i * nq + j];
        for (j = 0; j < nu; ++j) b[nq + j] = Ru[i * nu + j] + Xu[i * nu + j];
        for (j = 0; j < nr; ++j) b[nq + nu + j] = Rr[i * nr + j] + Xr[i * nr + j];
    }
    for (i = 0; i < na; ++i) {
        gen_rt_real *b = B + (nu + i) * nc;
        for (j = 0; j < nq; ++j) b[j] = Pq[i * nq + j];
        for (j = 0; j < nu; ++j) b[nq + j] = Pu[i * nu + j];
        for (j = 0; j < nr; ++j) b[nq + nu + j] = Pr[i * nr + j];
    }
    if ((st = gen_rt_reactions_columns(nu, na, M, G, C, H, nc, w, iwork, B))) return st;
    /* the first nu rows of K^-1 B, with the identity for M */
    for (i = 0; i < nu; ++i) {
        const gen_rt_real *b = B + i * nc;
        for (j = 0; j < nq; ++j) Rq[i * nq + j] = b[j];
        for (j = 0; j < nu; ++j) {
            Ru[i * nu + j] = b[nq + j];
            Mout[i * nu + j] = i == j ? 1 : 0;
        }
        for (j = 0; j < nr; ++j) Rr[i * nr + j] = b[nq + nu + j];
    }
    return GEN_RT_OK;
}
