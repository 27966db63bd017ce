/*
 * test_models.h - the models of the runtime's C tests (test_model.c,
 * test_sens.c, test_kalman.c): the oscillator (M = p[0], f = -p[1] q + r,
 * q' = u, with its linearization blocks) and the pendulum's kernels in
 * nonminimal coordinates (M = m I, f = (m g, 0), the constraint x^2 + y^2).
 */
#ifndef TEST_MODELS_H
#define TEST_MODELS_H

#include "gen_rt.h"

static void o_mass(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t, gen_rt_real *M)
{
    (void)q; (void)t;
    M[0] = p[0];
}

static void o_forcing(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                      const gen_rt_real *p, gen_rt_real t, gen_rt_real *f)
{
    (void)u; (void)t;
    f[0] = -p[1] * q[0] + r[0];
}

static void o_kin(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                  gen_rt_real t, gen_rt_real *Kqd, gen_rt_real *qd)
{
    (void)q; (void)p; (void)t; (void)Kqd;
    qd[0] = u[0];
}

static void o_rhs_terms(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                        const gen_rt_real *p, gen_rt_real t, gen_rt_real *Kqd,
                        gen_rt_real *qd, gen_rt_real *M, gen_rt_real *f, gen_rt_real *A,
                        gen_rt_real *a)
{
    (void)Kqd; (void)A; (void)a;
    qd[0] = u[0];
    o_mass(q, p, t, M);
    o_forcing(q, u, r, p, t, f);
}

static void o_lin(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *qd,
                  const gen_rt_real *ud, const gen_rt_real *lam, const gen_rt_real *r,
                  const gen_rt_real *p, gen_rt_real t, const gen_rt_lin_out *o)
{
    (void)q; (void)u; (void)qd; (void)ud; (void)lam; (void)r; (void)t;
    o->Kqd[0] = 1; o->Ku[0] = -1; o->Kq[0] = 0;
    o->M[0] = p[0]; o->Rq[0] = p[1]; o->Ru[0] = 0; o->Rr[0] = -1;
}

/* ---------------------------------------------------------------- pend */
static void p_mass(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t, gen_rt_real *M)
{
    (void)q; (void)t;
    M[0] = p[0]; M[1] = 0; M[2] = 0; M[3] = p[0];
}

static void p_forcing(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                      const gen_rt_real *p, gen_rt_real t, gen_rt_real *f)
{
    (void)q; (void)u; (void)r; (void)t;
    f[0] = p[0] * p[1];
    f[1] = 0;
}

static void p_kin(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                  gen_rt_real t, gen_rt_real *Kqd, gen_rt_real *qd)
{
    (void)q; (void)p; (void)t; (void)Kqd;
    qd[0] = u[0];
    qd[1] = u[1];
}

static void p_rhs_terms(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                        const gen_rt_real *p, gen_rt_real t, gen_rt_real *Kqd,
                        gen_rt_real *qd, gen_rt_real *M, gen_rt_real *f, gen_rt_real *A,
                        gen_rt_real *a)
{
    p_kin(q, u, p, t, Kqd, qd);
    p_mass(q, p, t, M);
    p_forcing(q, u, r, p, t, f);
    A[0] = q[0]; A[1] = q[1];
    a[0] = u[0] * u[0] + u[1] * u[1];
}

static void p_vcm(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t, gen_rt_real *A,
                  gen_rt_real *b)
{
    (void)p; (void)t;
    A[0] = q[0]; A[1] = q[1];
    b[0] = 0;
}

static void p_vc(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                 gen_rt_real t, gen_rt_real *fv)
{
    (void)p; (void)t;
    fv[0] = q[0] * u[0] + q[1] * u[1];
}

/* the linearization blocks of  q' - u = 0,  M u' - f - A^T lam = 0,
 * A u' + a = 0,  f_c = 0,  A u + b = 0 */
static void p_lin(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *qd,
                  const gen_rt_real *ud, const gen_rt_real *lam, const gen_rt_real *r,
                  const gen_rt_real *p, gen_rt_real t, const gen_rt_lin_out *o)
{
    int i;
    (void)qd; (void)r; (void)t;
    for (i = 0; i < 4; ++i) {
        o->Kqd[i] = (i == 0 || i == 3) ? 1 : 0;
        o->Ku[i] = (i == 0 || i == 3) ? -1 : 0;
        o->Kq[i] = 0;
        o->M[i] = (i == 0 || i == 3) ? p[0] : 0;
        o->Rq[i] = (i == 0 || i == 3) ? -lam[0] : 0;
        o->Ru[i] = 0;
    }
    o->A[0] = q[0]; o->A[1] = q[1];
    o->Sq[0] = ud[0]; o->Sq[1] = ud[1];
    o->Su[0] = 2 * u[0]; o->Su[1] = 2 * u[1];
    o->Vq[0] = u[0]; o->Vq[1] = u[1];
    o->Jc[0] = 2 * q[0]; o->Jc[1] = 2 * q[1];
}

#endif
