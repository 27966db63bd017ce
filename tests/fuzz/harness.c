/* Hostile-input harness for a generated model's C API (issue 8).
 *
 * Build with the generated sources and
 *   -DMODEL_H='"<name>.h"' -DP(x)=<name>_##x -DPU(x)=<NAME>_##x
 * Without FUZZ: main() runs a fixed, seeded sweep of extreme values (0, +-1,
 * 1e-300, 1e300, NaN, +-inf, ...) and the NULL-pointer checks, and exits 0
 * when every rule held. With FUZZ (clang -fsanitize=fuzzer): libFuzzer maps
 * its bytes onto the same call sequence.
 *
 * The rules, for every public function:
 *  - the status is 0 or one of the documented negative codes;
 *  - status 0 means every output is finite;
 *  - a failed project / consistent_state / step_rk4 leaves x exactly as it was;
 *  - a NULL required pointer returns the NULL status.
 * A violation prints what and where, and aborts (the sanitizers report memory
 * and undefined-behaviour errors on their own). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include MODEL_H

typedef P(real) real;
#define NQ PU(NQ)
#define NU PU(NU)
#define NX PU(NX)
#define NR PU(NR)
#define NP PU(NP)
#define MC PU(MC)
#define MV PU(MV)
#define NS PU(NS)
#define NA PU(NA)
#define NY PU(NY)
#define ROWS 4
#define STATUS_MIN PU(STATUS_MIN)

static void fail(const char *what, const char *why, int st)
{
    fprintf(stderr, "harness: %s: %s (status %d)\n", what, why, st);
    abort();
}

static int finite_all(const real *v, int n)
{
    int i;
    for (i = 0; i < n; ++i)
        if (!(v[i] - v[i] == 0)) return 0;
    return 1;
}

static int check(const char *what, int st, const real *out, int n)
{
    if (st != 0 && !(st <= -1 && st >= STATUS_MIN)) fail(what, "unknown status", st);
    if (st == 0 && out && n > 0 && !finite_all(out, n)) fail(what, "status 0 with a non-finite output", st);
    return st;
}

static void unchanged(const char *what, int st, const real *before, const real *after)
{
    if (st != 0 && memcmp(before, after, sizeof(real) * NX) != 0)
        fail(what, "failed but changed x", st);
}

static void exercise(const real *x, const real *r, const real *p, real t, real h, int sim)
{
    real dx[NX], lam[MV + 1], M[NU * NU], f[NU], qd[NQ], xc[NX], E[1];
    real A[NS * NS + 1], B[NS * NR + 1];
    real fc[MC + 1], Jc[MC * NQ + 1], fv[MV + 1], Av[MV * NU + 1], bv[MV + 1];
    real Fa[NA + 1], y[NY + 1], Cm[NY * NS + 1], Dm[NY * NR + 1], Jx[NX * NX], Jr[NX * NR + 1];
    real Fx[NS * NS + 1], Fr[NS * NR + 1], K[NR * NS + 1], rout[ROWS * (NR + 1)];
    P(input) in;
    real tout[ROWS], xout[ROWS * NX], lout[ROWS * (MV + 1)];
    P(sim_options) o;
    P(sim_stats) s;
    int st, rows;

    check("eval_rhs", P(eval_rhs)(t, x, r, p, dx, lam), dx, NX);
    if (P(eval_rhs)(t, x, r, p, dx, lam) == 0 && !finite_all(lam, MV)) fail("eval_rhs", "lam not finite", 0);
    check("eval_mass_matrix", P(eval_mass_matrix)(x, p, t, M), M, NU * NU);
    check("eval_forcing", P(eval_forcing)(x, x + NQ, r, p, t, f), f, NU);
    check("eval_kinematics", P(eval_kinematics)(x, x + NQ, p, t, qd), qd, NQ);
#if MC > 0
    check("eval_constraints", P(eval_constraints)(x, p, t, fc), fc, MC);
    check("eval_constraint_jacobian", P(eval_constraint_jacobian)(x, p, t, Jc), Jc, MC * NQ);
#endif
#if MV > 0
    check("eval_velocity_constraints", P(eval_velocity_constraints)(x, x + NQ, p, t, fv), fv, MV);
    st = P(eval_velocity_constraint_matrix)(x, p, t, Av, bv);
    check("eval_velocity_constraint_matrix", st, Av, MV * NU);
    check("eval_velocity_constraint_matrix (b)", st, bv, MV);
#endif
    check("eval_auxiliary_forces", P(eval_auxiliary_forces)(t, x, r, p, Fa), Fa, NA);
    check("eval_outputs", P(eval_outputs)(t, x, r, p, y), y, NY);
    st = P(linearize_outputs)(x, r, p, t, A, B, Cm, Dm);
    check("linearize_outputs (A)", st, A, NS * NS);
    check("linearize_outputs (C)", st, Cm, NY * NS);
    check("linearize_outputs (D)", st, Dm, NY * NR);
    st = P(linearize_discrete)(x, r, p, t, (real)fabs(h), A, B);
    check("linearize_discrete (Ad)", st, A, NS * NS);
    check("linearize_discrete (Bd)", st, B, NS * NR);
    st = P(jacobian)(t, x, r, p, Jx, Jr);
    check("jacobian (Jx)", st, Jx, NX * NX);
    check("jacobian (Jr)", st, Jr, NX * NR);
    memcpy(xc, x, sizeof xc);
    st = P(step_sensitivity)(t, h, r, p, xc, Fx, Fr);
    check("step_sensitivity (x)", st, xc, NX);
    check("step_sensitivity (Fx)", st, Fx, NS * NS);
    check("step_sensitivity (Fr)", st, Fr, NS * NR);
    unchanged("step_sensitivity", st, x, xc);
#if PU(HAS_ENERGY)
    check("eval_energy", P(eval_energy)(x, x + NQ, p, t, E), E, 1);
#endif
    memcpy(xc, x, sizeof xc);
    st = check("project", P(project)(t, p, 0, 0, xc), xc, NX);
    unchanged("project", st, x, xc);
    memcpy(xc, x, sizeof xc);
    st = check("consistent_state", P(consistent_state)(t, p, 0, 0, xc), xc, NX);
    unchanged("consistent_state", st, x, xc);
    memcpy(xc, x, sizeof xc);
    st = check("step_rk4", P(step_rk4)(t, h, r, p, 1, xc), xc, NX);
    unchanged("step_rk4", st, x, xc);
    st = P(linearize)(x, r, p, t, A, B);
    check("linearize (A)", st, A, NS * NS);
    check("linearize (B)", st, B, NS * NR);

    if (!sim) return;
    P(sim_options_default)(&o);
    o.max_steps = 20;
    o.method = (h < 0) ? PU(METHOD_DOPRI5) : PU(METHOD_RK4);
    rows = P(simulate_rows)(t, t + 2 * fabs(h), fabs(h));
    if (rows < STATUS_MIN) fail("simulate_rows", "unknown status", rows);
    if (rows > 0 && rows <= ROWS) {
        memset(&s, 0, sizeof s);
        st = P(simulate)(x, t, t + 2 * fabs(h), fabs(h), r, p, &o, ROWS, tout, xout, lout, &s);
        check("simulate", st, NULL, 0);
        if (s.n_out < 0 || s.n_out > ROWS) fail("simulate", "n_out out of range", s.n_out);
        if (!finite_all(xout, s.n_out * NX) || !finite_all(tout, s.n_out))
            fail("simulate", "non-finite rows reported as written", st);
        /* the same with a feedback on every independent state (sampled at |h|
         * when h < 0) */
        {
            int i;
            memset(&in, 0, sizeof in);
            for (i = 0; i < NR * NS; ++i) K[i] = (real)(i % 3) - 1;
            in.r = r; in.K = K; in.x_op = x;
            in.period = (h < 0) ? (real)fabs(h) : 0;
            memset(&s, 0, sizeof s);
            st = P(simulate_input)(x, t, t + 2 * fabs(h), fabs(h), &in, p, &o, ROWS, tout, xout,
                                   lout, rout, &s);
            check("simulate_input", st, NULL, 0);
            if (s.n_out < 0 || s.n_out > ROWS) fail("simulate_input", "n_out out of range", s.n_out);
            if (!finite_all(xout, s.n_out * NX) || !finite_all(rout, s.n_out * NR))
                fail("simulate_input", "non-finite rows reported as written", st);
        }
    }
}

static void null_checks(void)
{
    real x[NX], dx[NX], M[NU * NU], A[NS * NS + 1], B[NS * NR + 1], r[NR + 1];
    memset(x, 0, sizeof x);
    memset(r, 0, sizeof r);
    x[0] = (real)0.3;
    if (P(eval_rhs)(0, NULL, r, NULL, dx, NULL) != -1) fail("eval_rhs", "NULL x accepted", 0);
    if (P(eval_rhs)(0, x, r, NULL, NULL, NULL) != -1) fail("eval_rhs", "NULL dxdt accepted", 0);
    if (P(eval_mass_matrix)(x, NULL, 0, NULL) != -1) fail("eval_mass_matrix", "NULL M accepted", 0);
    if (P(eval_mass_matrix)(NULL, NULL, 0, M) != -1) fail("eval_mass_matrix", "NULL q accepted", 0);
    if (P(linearize)(NULL, r, NULL, 0, A, B) != -1) fail("linearize", "NULL x accepted", 0);
    if (P(linearize)(x, r, NULL, 0, NULL, B) != -1) fail("linearize", "NULL A accepted", 0);
    if (P(project)(0, NULL, 0, 0, NULL) != -1) fail("project", "NULL x accepted", 0);
    if (P(step_rk4)(0, (real)0.01, r, NULL, 1, NULL) != -1) fail("step_rk4", "NULL x accepted", 0);
    if (P(simulate)(x, 0, 1, (real)0.1, r, NULL, NULL, 4, NULL, NULL, NULL, NULL) != -1)
        fail("simulate", "NULL outputs accepted", 0);
    if (P(eval_auxiliary_forces)(0, NULL, r, NULL, dx) != -1)
        fail("eval_auxiliary_forces", "NULL x accepted", 0);
    if (NA > 0 && P(eval_auxiliary_forces)(0, x, r, NULL, NULL) != -1)
        fail("eval_auxiliary_forces", "NULL F accepted", 0);
    if (P(simulate_input)(x, 0, 1, (real)0.1, NULL, NULL, NULL, 4, dx, dx, NULL, NULL, NULL) != -1)
        fail("simulate_input", "NULL input accepted", 0);
    if (P(status_message)(-3) == NULL || P(status_message)(12345) == NULL)
        fail("status_message", "NULL message", 0);
}

/* map bytes onto the inputs: 8 bytes per value, a tag byte picks specials */
static real value(const uint8_t *d, size_t n, size_t *pos)
{
    static const double special[] = {0.0, 1.0, -1.0, 0.5, 1e-300, 1e300, -1e300, 3.14159,
                                     -2.5, 1e-5, 1e5};
    double v = 0;
    uint8_t tag;
    if (*pos >= n) return 0;
    tag = d[(*pos)++];
    if (tag < 64) return (real)special[tag % (sizeof special / sizeof special[0])];
    if (tag == 64) return (real)NAN;
    if (tag == 65) return (real)INFINITY;
    if (tag == 66) return (real)-INFINITY;
    if (*pos + sizeof v <= n) {
        memcpy(&v, d + *pos, sizeof v);
        *pos += sizeof v;
    }
    if (tag < 160 && v == v) v = fmod(v, 10.0);     /* mostly moderate values */
    return (real)v;
}

static void run_bytes(const uint8_t *d, size_t n)
{
    real x[NX], r[NR + 1], p[NP + 1], t, h;
    const real *pp = NULL;
    size_t pos = 0;
    int i, sim = n > 0 && (d[0] & 7) == 0;   /* simulate() on one input in eight */
    for (i = 0; i < NX; ++i) x[i] = value(d, n, &pos);
    for (i = 0; i < NR; ++i) r[i] = value(d, n, &pos);
    if (pos < n && (d[pos++] & 1)) {
        for (i = 0; i < NP; ++i) p[i] = value(d, n, &pos);
        pp = p;
    }
    t = value(d, n, &pos);
    h = value(d, n, &pos);
    exercise(x, r, pp, t, h, sim);
}

#ifdef FUZZ
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int once = 0;
    if (!once) { null_checks(); once = 1; }
    run_bytes(data, size);
    return 0;
}
#else
int main(int argc, char **argv)
{
    uint8_t buf[512];
    uint32_t s = 12345u;
    long k, iters = argc > 1 ? atol(argv[1]) : 3000;
    size_t i;
    null_checks();
    for (k = 0; k < iters; ++k) {
        for (i = 0; i < sizeof buf; ++i) {
            s = s * 1664525u + 1013904223u;
            buf[i] = (uint8_t)(s >> 24);
        }
        /* every third case: all moderate values (exercise the success paths) */
        if (k % 3 == 0)
            for (i = 0; i < sizeof buf; i += 9) buf[i] = (uint8_t)(70 + buf[i] % 90);
        run_bytes(buf, sizeof buf);
    }
    printf("harness: %ld cases, all rules held\n", iters);
    return 0;
}
#endif
