#include "pendulum_kane.h"

int pendulum_kane_rhs_batch(int n, const pendulum_kane_real *t, int t_stride, const pendulum_kane_real *x, const pendulum_kane_real *r, int r_stride, const pendulum_kane_real *p, int p_stride, pendulum_kane_real *dxdt, int *status)
{
    int i, st;
    *status = 0;
    for (i = 0; i < n; ++i) {
        st = pendulum_kane_eval_rhs(t ? t[(long)i * t_stride] : 0, x + (long)i * 4,
                          r ? r + (long)i * r_stride : 0, p ? p + (long)i * p_stride : 0,
                          dxdt + (long)i * 4, 0);
        if (st) { *status = st; return i; }
    }
    return -1;
}

int pendulum_kane_mass_matrix_batch(int n, const pendulum_kane_real *q, int q_stride, const pendulum_kane_real *p, int p_stride, pendulum_kane_real *M, int *status)
{
    int i, st;
    *status = 0;
    for (i = 0; i < n; ++i) {
        st = pendulum_kane_eval_mass_matrix(q + (long)i * q_stride, p ? p + (long)i * p_stride : 0, 0,
                                  M + (long)i * 4);
        if (st) { *status = st; return i; }
    }
    return -1;
}

int pendulum_kane_linearize_batch(int n, const pendulum_kane_real *x, const pendulum_kane_real *r, int r_stride, const pendulum_kane_real *p, int p_stride, pendulum_kane_real t, pendulum_kane_real *A, pendulum_kane_real *B, int *status)
{
    int i, st;
    pendulum_kane_real Bdummy[1];
    *status = 0;
    for (i = 0; i < n; ++i) {
        st = pendulum_kane_linearize(x + (long)i * 4, r ? r + (long)i * r_stride : 0,
                           p ? p + (long)i * p_stride : 0, t, A + (long)i * 4,
Bdummy);
        if (st) { *status = st; return i; }
    }
    (void)Bdummy;
    return -1;
}
