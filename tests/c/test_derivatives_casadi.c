/*
 * test_derivatives_casadi.c - gen_rt_cs_eval (csrc/derivatives/
 * gen_rt_casadi_extern.c): a model's functions in CasADi's calling convention, on
 * the hand-written model of test_derivatives_model.h with stand-ins for
 * the model's C API (the right-hand side and its Jacobian from the
 * kernels, the runtime's RK4 for step_rk4, the outputs and the velocity
 * constraint written out). For every function (rhs, implicit, step,
 * step_rodas4, outputs, constraints) and both models (without and with
 * the velocity constraint):
 *   VALUE    bit for bit the stand-ins' (and RODAS4's trial step);
 *   JAC      the blocks against central differences of the value over
 *            every entry of every input;
 *   FWD/ADJ  J seed and J^T seed from those blocks;
 *   JAC_JAC  against differences of the JAC blocks, JAC_FWD of FWD's
 *            output (and the seeds' blocks = J), JAC_ADJ of ADJ's outputs
 *            (the Hessian blocks; the seed's = J_i^T);
 * NULL inputs are zeros, NULL outputs are not written, RODAS4 has no
 * second derivatives (BAD_ARG), and neither has a function whose model
 * has no second-derivative kernel. And gen_rt_cs_eval_inline over the
 * models as a CasADi library holds them (static const, one function of
 * their own each) gives every function's every output and status bit for
 * bit as gen_rt_cs_eval.
 */
#include "test_derivatives_model.h"

#include "gen_rt_casadi_inline.h"

#define NOUT 48
#define OUTLEN 128

static const gen_rt_deriv_model *CUR; /* the model of the API stand-ins */

static int api_rhs(real t, const real *x, const real *r, const real *p, real *dxdt, real *lam)
{
    fctx c;
    (void)lam;
    c.m = CUR; c.r = r; c.p = p;
    return frhs(&c, t, x, dxdt);
}

static int api_step(real t, real h, const real *r, const real *p, int project, real *x)
{
    real rk[GEN_RT_RK4_WORK(NX)];
    fctx c;
    (void)project;
    c.m = CUR; c.r = r; c.p = p;
    return gen_rt_rk4_step(frhs, &c, NX, t, h, rk, x);
}

static int api_jacobian(real t, const real *x, const real *r, const real *p, real *Jx, real *Jr)
{
    real z[NZ], w[NWMAX], Jw[NWMAX * NZ];
    int i, j;
    zof(x, r, p, t, z);
    solve_at(CUR, z, w, Jw);
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) Jx[i * NX + j] = Jw[i * NZ + j];
        Jr[i] = Jw[i * NZ + NX];
    }
    return 0;
}

static int api_outputs(real t, const real *x, const real *r, const real *p, real *y)
{
    y[0] = x[0] * x[3] + (real)sin(t);
    y[1] = p[0] * r[0] * x[1];
    return 0;
}

static int api_vc(const real *q, const real *u, const real *p, real t, real *fv)
{
    (void)p; (void)t;
    fv[0] = q[0] * u[0] + q[1] * u[1];
    return 0;
}

static gen_rt_cs_model model_of(int mv)
{
    gen_rt_cs_model m;
    m.nq = 2; m.nu = 2; m.nr = NR; m.np = NP; m.mc = 0; m.mv = mv; m.ny = NY; m.t_dep = 1;
    m.d = MODELS[mv];
    m.y1 = y1; m.c1 = c1; m.yh = yh; m.ch = ch;
    m.rhs = api_rhs; m.step_rk4 = api_step; m.jacobian = api_jacobian;
    m.outputs = api_outputs; m.constraints = 0; m.velocity_constraints = mv ? api_vc : 0;
    return m;
}

/* one function: its base, inputs (what, size, offset among v), rows */
typedef struct {
    int base, nin, nv, nrow;
    int in[GEN_RT_CS_MAX_IN], size[GEN_RT_CS_MAX_IN], off[GEN_RT_CS_MAX_IN];
} fdesc;

static fdesc describe(int base, int mv)
{
    static const int ins[][6] = {
        {0}, {GEN_RT_CS_X, GEN_RT_CS_R, GEN_RT_CS_P, GEN_RT_CS_T},
        {GEN_RT_CS_X, GEN_RT_CS_XDOT, GEN_RT_CS_R, GEN_RT_CS_P, GEN_RT_CS_T},
        {GEN_RT_CS_X, GEN_RT_CS_R, GEN_RT_CS_P, GEN_RT_CS_T, GEN_RT_CS_H},
        {GEN_RT_CS_X, GEN_RT_CS_R, GEN_RT_CS_P, GEN_RT_CS_T, GEN_RT_CS_H},
        {GEN_RT_CS_X, GEN_RT_CS_R, GEN_RT_CS_P, GEN_RT_CS_T},
        {GEN_RT_CS_X, GEN_RT_CS_P, GEN_RT_CS_T}};
    static const int nins[] = {0, 4, 5, 5, 5, 4, 3};
    fdesc d;
    int k;
    d.base = base;
    d.nin = nins[base];
    d.nv = 0;
    d.nrow = base == GEN_RT_CS_IMPLICIT ? NX + mv : base == GEN_RT_CS_OUTPUTS ? NY
             : base == GEN_RT_CS_CONSTRAINTS ? mv : NX;
    for (k = 0; k < d.nin; ++k) {
        const int w = ins[base][k];
        d.in[k] = w;
        d.size[k] = w == GEN_RT_CS_X || w == GEN_RT_CS_XDOT ? NX : w == GEN_RT_CS_R ? NR
                    : w == GEN_RT_CS_P ? NP : 1;
        d.off[k] = d.nv;
        d.nv += d.size[k];
    }
    return d;
}

static real OUT[NOUT][OUTLEN];
static real *RES[NOUT];

/* a call with the inputs v (nv) and a seed (nv forward seeds or nrow
 * adjoint ones) into OUT */
static int call(const gen_rt_cs_model *m, const fdesc *d, int mode, const real *v,
                const real *seed)
{
    const real *arg[2 * GEN_RT_CS_MAX_IN + 2];
    gen_rt_cs_fn f;
    int k;
    f.base = d->base; f.mode = mode; f.nin = d->nin;
    for (k = 0; k < d->nin; ++k) {
        f.in[k] = d->in[k];
        arg[k] = v + d->off[k];
        arg[d->nin + 1 + k] = seed ? seed + d->off[k] : 0;
    }
    arg[d->nin] = 0;                        /* the nominal output: not read */
    if (mode == GEN_RT_CS_ADJ || mode == GEN_RT_CS_JAC_ADJ) arg[d->nin + 1] = seed;
    for (k = 0; k < NOUT; ++k) RES[k] = OUT[k];
    return gen_rt_cs_eval(m, &f, arg, RES, WORK, IWORK);
}

/* the value directly: the stand-ins and RODAS4's trial step */
static void value_ref(int mv, const fdesc *d, const real *v, real *out)
{
    real z[NZ], zz[NZ];
    int i;
    fctx c;
    c.m = CUR;
    if (d->base == GEN_RT_CS_CONSTRAINTS) {
        api_vc(v, v + 2, v + NX, v[NX + NP], out);
        return;
    }
    if (d->base == GEN_RT_CS_IMPLICIT) {
        zof(v, v + 2 * NX, v + 2 * NX + NR, v[2 * NX + NR + NP], z);
        c.r = z + NX; c.p = z + NX + NR;
        frhs(&c, z[NZ - 1], z, out);
        for (i = 0; i < NX; ++i) out[i] = v[NX + i] - out[i];
        if (mv) api_vc(v, v + 2, z + NX + NR, z[NZ - 1], out + NX);
        return;
    }
    for (i = 0; i < NZ; ++i) zz[i] = v[i];
    c.r = zz + NX; c.p = zz + NX + NR;
    if (d->base == GEN_RT_CS_RHS) frhs(&c, zz[NZ - 1], zz, out);
    else if (d->base == GEN_RT_CS_STEP) rk4_value(CUR, v, out);
    else if (d->base == GEN_RT_CS_STEP_RODAS4) rodas4_value(CUR, v, out);
    else api_outputs(zz[NZ - 1], zz, zz + NX, zz + NX + NR, out);
}

/* J (nrow x nv) from JAC's blocks */
static void jac_full(const gen_rt_cs_model *m, const fdesc *d, const real *v, real *J)
{
    int i, k, a;
    CHECK_INT(call(m, d, GEN_RT_CS_JAC, v, 0), 0);
    for (i = 0; i < d->nin; ++i)
        for (k = 0; k < d->size[i]; ++k)
            for (a = 0; a < d->nrow; ++a) J[a * d->nv + d->off[i] + k] = OUT[i][k * d->nrow + a];
}

static void check_first(const gen_rt_cs_model *m, const fdesc *d, const real *v,
                        const real *seed, real *J)
{
    real vp[16], vm[16], op[8], om[8];
    int j, a, k, i;
    jac_full(m, d, v, J);
    for (j = 0; j < d->nv; ++j) {
        for (k = 0; k < d->nv; ++k) vp[k] = vm[k] = v[k];
        vp[j] += EPS; vm[j] -= EPS;
        CHECK_INT(call(m, d, GEN_RT_CS_VALUE, vp, 0), 0);
        for (a = 0; a < d->nrow; ++a) op[a] = OUT[0][a];
        CHECK_INT(call(m, d, GEN_RT_CS_VALUE, vm, 0), 0);
        for (a = 0; a < d->nrow; ++a) om[a] = OUT[0][a];
        for (a = 0; a < d->nrow; ++a) CHECK_FD(J[a * d->nv + j], (op[a] - om[a]) / (2 * EPS));
    }
    CHECK_INT(call(m, d, GEN_RT_CS_FWD, v, seed), 0);
    for (a = 0; a < d->nrow; ++a) {
        double s = 0;
        for (j = 0; j < d->nv; ++j) s += J[a * d->nv + j] * seed[j];
        CHECK_NEAR(OUT[0][a], s, TOL(1e-12, 1e-4) * scale_of(s));
    }
    CHECK_INT(call(m, d, GEN_RT_CS_ADJ, v, seed), 0);
    for (i = 0; i < d->nin; ++i)
        for (k = 0; k < d->size[i]; ++k) {
            double s = 0;
            for (a = 0; a < d->nrow; ++a) s += J[a * d->nv + d->off[i] + k] * seed[a];
            CHECK_NEAR(OUT[i][k], s, TOL(1e-12, 1e-4) * scale_of(s));
        }
}

/* JAC_JAC, JAC_FWD, JAC_ADJ against differences of JAC, FWD, ADJ */
static void check_second(const gen_rt_cs_model *m, const fdesc *d, const real *v,
                         const real *seed, const real *J)
{
    static real jj[NOUT][OUTLEN], jf[NOUT][OUTLEN], ja[NOUT][OUTLEN];
    static real Jp[8 * 16], Jm[8 * 16], fp[NOUT][OUTLEN], fm[NOUT][OUTLEN];
    real vp[16], vm[16];
    const int nin = d->nin, nrow = d->nrow, nv = d->nv;
    int i, j, k, l, a, mode;
    CHECK_INT(call(m, d, GEN_RT_CS_JAC_JAC, v, 0), 0);
    memcpy(jj, OUT, sizeof OUT);
    CHECK_INT(call(m, d, GEN_RT_CS_JAC_FWD, v, seed), 0);
    memcpy(jf, OUT, sizeof OUT);
    CHECK_INT(call(m, d, GEN_RT_CS_JAC_ADJ, v, seed), 0);
    memcpy(ja, OUT, sizeof OUT);
    for (j = 0; j < nin; ++j)
        for (k = 0; k < d->size[j]; ++k) {
            const int col = d->off[j] + k;
            for (l = 0; l < nv; ++l) vp[l] = vm[l] = v[l];
            vp[col] += EPS; vm[col] -= EPS;
            jac_full(m, d, vp, Jp);
            jac_full(m, d, vm, Jm);
            for (i = 0; i < nin; ++i)            /* d vec(jac_out_i) / d in_j */
                for (l = 0; l < d->size[i]; ++l)
                    for (a = 0; a < nrow; ++a) {
                        const int e = a * nv + d->off[i] + l;
                        CHECK_FD(jj[i * (nin + 1) + j][(k * d->size[i] + l) * nrow + a],
                                 (Jp[e] - Jm[e]) / (2 * EPS));
                    }
            for (mode = GEN_RT_CS_FWD; mode <= GEN_RT_CS_ADJ; ++mode) {
                CHECK_INT(call(m, d, mode, vp, seed), 0);
                memcpy(fp, OUT, sizeof OUT);
                CHECK_INT(call(m, d, mode, vm, seed), 0);
                memcpy(fm, OUT, sizeof OUT);
                if (mode == GEN_RT_CS_FWD)
                    for (a = 0; a < nrow; ++a)
                        CHECK_FD(jf[j][k * nrow + a], (fp[0][a] - fm[0][a]) / (2 * EPS));
                else
                    for (i = 0; i < nin; ++i)
                        for (a = 0; a < d->size[i]; ++a)
                            CHECK_FD(ja[i * (nin + 2) + j][k * d->size[i] + a],
                                     (fp[i][a] - fm[i][a]) / (2 * EPS));
            }
        }
    /* w.r.t. the seeds: J's blocks and J_i^T */
    for (j = 0; j < nin; ++j)
        for (k = 0; k < d->size[j]; ++k)
            for (a = 0; a < nrow; ++a) {
                CHECK(jf[nin + 1 + j][k * nrow + a] == J[a * nv + d->off[j] + k]);
                CHECK(ja[j * (nin + 2) + nin + 1][a * d->size[j] + k] == J[a * nv + d->off[j] + k]);
            }
}

static void test_function(int mv, int base)
{
    const gen_rt_cs_model m = model_of(mv);
    const fdesc d = describe(base, mv);
    static real J[8 * 16];
    real v[16], seed[16], ref[8];
    int k, i;
    test_lcg g = {(unsigned long)(100 * mv + base)};
    for (k = 0; k < d.nin; ++k)
        for (i = 0; i < d.size[k]; ++i) {
            const int w = d.in[k], o = d.off[k] + i;
            v[o] = w == GEN_RT_CS_X ? Z0[i] : w == GEN_RT_CS_R ? Z0[NX] : w == GEN_RT_CS_P ? Z0[NX + NR + i]
                   : w == GEN_RT_CS_T ? Z0[NZ - 1] : w == GEN_RT_CS_H ? GEN_RT_C(0.05)
                   : (real)test_lcg_uniform(&g);
        }
    for (k = 0; k < 16; ++k) seed[k] = (real)test_lcg_uniform(&g);
    CUR = &MODELS[mv];
    CHECK_INT(call(&m, &d, GEN_RT_CS_VALUE, v, 0), 0);
    value_ref(mv, &d, v, ref);
    for (k = 0; k < d.nrow; ++k) CHECK(OUT[0][k] == ref[k]);
    check_first(&m, &d, v, seed, J);
    if (base == GEN_RT_CS_STEP_RODAS4) {
        CHECK_INT(call(&m, &d, GEN_RT_CS_JAC_ADJ, v, seed), GEN_RT_ERR_BAD_ARG);
        v[NZ] = 0;
        CHECK_INT(call(&m, &d, GEN_RT_CS_VALUE, v, 0), GEN_RT_ERR_BAD_ARG);
        CHECK_INT(call(&m, &d, GEN_RT_CS_JAC, v, 0), GEN_RT_ERR_BAD_ARG);
        return;
    }
    check_second(&m, &d, v, seed, J);
}

/* NULL inputs are zeros; a NULL output is not written; no second
 * derivatives without their kernels */
static void test_nulls(int mv)
{
    gen_rt_cs_model m = model_of(mv);
    const fdesc d = describe(GEN_RT_CS_RHS, mv);
    const real *arg[4];
    real out0[NX], *res[4];
    int k;
    CUR = &MODELS[mv];
    /* x NULL too where the model is regular at x = 0 (without the constraint) */
    arg[0] = mv ? Z0 : 0; arg[1] = 0; arg[2] = Z0 + NX + NR; arg[3] = 0;
    {
        gen_rt_cs_fn f = {GEN_RT_CS_RHS, GEN_RT_CS_VALUE, 4,
                          {GEN_RT_CS_X, GEN_RT_CS_R, GEN_RT_CS_P, GEN_RT_CS_T}};
        real v[NZ];
        res[0] = out0;
        CHECK_INT(gen_rt_cs_eval(&m, &f, arg, res, WORK, IWORK), 0);
        for (k = 0; k < NZ; ++k) v[k] = mv && k < NX ? Z0[k] : 0;
        v[NX + NR] = Z0[NX + NR]; v[NX + NR + 1] = Z0[NX + NR + 1];
        CHECK_INT(call(&m, &d, GEN_RT_CS_VALUE, v, 0), 0);
        for (k = 0; k < NX; ++k) CHECK(out0[k] == OUT[0][k]);
        /* JAC with res[1] NULL: the other blocks as before, OUT[1] untouched */
        CHECK_INT(call(&m, &d, GEN_RT_CS_JAC, Z0, 0), 0);
        for (k = 0; k < NX; ++k) out0[k] = OUT[0][k];
        f.mode = GEN_RT_CS_JAC;
        for (k = 0; k < 4; ++k) res[k] = OUT[k];
        res[1] = 0;
        OUT[1][0] = -12345;
        arg[0] = Z0; arg[1] = Z0 + NX; arg[3] = Z0 + NZ - 1;
        CHECK_INT(gen_rt_cs_eval(&m, &f, arg, res, WORK, IWORK), 0);
        CHECK(OUT[1][0] == -12345);
        for (k = 0; k < NX; ++k) CHECK(OUT[0][k] == out0[k]);
    }
    m.yh = 0;
    m.d.rh = 0;
    {
        const fdesc o = describe(GEN_RT_CS_OUTPUTS, mv);
        real v[NZ];
        for (k = 0; k < NZ; ++k) v[k] = Z0[k];
        CHECK_INT(call(&m, &o, GEN_RT_CS_JAC_JAC, v, 0), GEN_RT_ERR_BAD_ARG);
        CHECK_INT(call(&m, &d, GEN_RT_CS_JAC_ADJ, v, v), GEN_RT_ERR_BAD_ARG);
        CHECK_INT(call(&m, &o, GEN_RT_CS_JAC, v, 0), 0);
    }
}

/* the models as a CasADi library holds them (templates/casadi): static
 * const, evaluated through gen_rt_cs_eval_inline in a function of their
 * own, where the compiler sees their sizes and kernels as constants */
static const gen_rt_cs_model CONST_MODELS[2] = {
    {2, 2, NR, NP, 0, 0, NY, 1, {NX, NZ, NX, r0_a, rz_a, rh_a}, y1, c1, yh, ch, api_rhs,
     api_step, api_jacobian, api_outputs, 0, 0},
    {2, 2, NR, NP, 0, 1, NY, 1, {NX, NZ, NX + 1, r0_b, rz_b, rh_b}, y1, c1, yh, ch, api_rhs,
     api_step, api_jacobian, api_outputs, 0, api_vc}};
static real WORK2[GEN_RT_CS_WORK(NX, NR, NP, 0, 1, NY) + 16];

static int eval_const_a(const gen_rt_cs_fn *f, const real **arg, real **res)
{
    int iwork[GEN_RT_CS_IWORK(NX, NR, NP, 0)];
    return gen_rt_cs_eval_inline(&CONST_MODELS[0], f, arg, res, WORK2, iwork);
}

static int eval_const_b(const gen_rt_cs_fn *f, const real **arg, real **res)
{
    int iwork[GEN_RT_CS_IWORK(NX, NR, NP, 1)];
    return gen_rt_cs_eval_inline(&CONST_MODELS[1], f, arg, res, WORK2, iwork);
}

/* every mode of a function: the same status and outputs, bit for bit */
static void test_inline(int mv, int base)
{
    static real out2[NOUT][OUTLEN];
    const gen_rt_cs_model m = model_of(mv);
    const fdesc d = describe(base, mv);
    const real *arg[2 * GEN_RT_CS_MAX_IN + 2];
    real *res2[NOUT], v[16], seed[16];
    gen_rt_cs_fn f;
    int k, mode, st;
    test_lcg g = {(unsigned long)(300 + 10 * mv + base)};
    for (k = 0; k < d.nv; ++k) v[k] = (real)test_lcg_uniform(&g);
    for (k = 0; k < 16; ++k) seed[k] = (real)test_lcg_uniform(&g);
    if (base == GEN_RT_CS_STEP || base == GEN_RT_CS_STEP_RODAS4) v[NZ] = GEN_RT_C(0.05);
    CUR = &MODELS[mv];
    f.base = base; f.nin = d.nin;
    for (k = 0; k < d.nin; ++k) f.in[k] = d.in[k];
    for (mode = GEN_RT_CS_VALUE; mode <= GEN_RT_CS_JAC_ADJ; ++mode) {
        st = call(&m, &d, mode, v, seed);
        for (k = 0; k < d.nin; ++k) {
            arg[k] = v + d.off[k];
            arg[d.nin + 1 + k] = seed + d.off[k];
        }
        arg[d.nin] = 0;
        if (mode == GEN_RT_CS_ADJ || mode == GEN_RT_CS_JAC_ADJ) arg[d.nin + 1] = seed;
        for (k = 0; k < NOUT; ++k) res2[k] = out2[k];
        memcpy(out2, OUT, sizeof OUT);  /* what a call does not write stays equal */
        f.mode = mode;
        CHECK_INT((mv ? eval_const_b : eval_const_a)(&f, arg, res2), st);
        CHECK(memcmp(out2, OUT, sizeof OUT) == 0);
    }
}

int main(void)
{
    int mv, base;
    for (mv = 0; mv <= 1; ++mv) {
        for (base = GEN_RT_CS_RHS; base <= GEN_RT_CS_CONSTRAINTS; ++base)
            if (base != GEN_RT_CS_CONSTRAINTS || mv) {
                test_function(mv, base);
                test_inline(mv, base);
            }
        test_nulls(mv);
    }
    TEST_END();
}
