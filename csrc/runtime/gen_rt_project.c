/* gen_rt_project.c - minimum-norm corrections onto linearized constraints. */
#include "gen_rt.h"

int gen_rt_min_norm_correct(int m, int n, const gen_rt_real *J,
                            const gen_rt_real *res, gen_rt_real *work,
                            gen_rt_real *x)
{
    int i, j, k, st;
    gen_rt_real *G = work, *y = work + m * m;
    if (m < 0 || n < 0) return GEN_RT_ERR_BAD_ARG;
    if (m == 0) return GEN_RT_OK;
    if (!J || !res || !work || !x) return GEN_RT_ERR_NULL;
    for (i = 0; i < m; ++i) {
        for (j = 0; j <= i; ++j) {
            gen_rt_real s = 0;
            for (k = 0; k < n; ++k) s += J[i * n + k] * J[j * n + k];
            G[i * m + j] = s;
            G[j * m + i] = s;
        }
        y[i] = res[i];
    }
    st = gen_rt_chol_factor(m, G);
    if (st) return st;
    st = gen_rt_chol_solve(m, G, 1, y);
    if (st) return st;
    for (k = 0; k < n; ++k) {
        gen_rt_real s = 0;
        for (i = 0; i < m; ++i) s += J[i * n + k] * y[i];
        x[k] -= s;
    }
    return GEN_RT_OK;
}
