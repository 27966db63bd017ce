/* mpc_driver.c - a model predictive controller (gen.MPC.to_c) closing the
 * loop on its generated model, built with a cross compiler
 * (arm-linux-gnueabihf-gcc -static) and run under qemu-arm by
 * tests/features/test_mpc_embedded.py, or natively: the controller's
 * memory a static instance, no heap.
 *
 *   mpc_driver STEPS X0 X1 ... X(NX-1)
 *
 * Every MPC_PERIOD: u = <mpc>_step(t, x), then 10 RK4 steps of the model
 * with u held; prints, with %.9g, "u k status u0 .." and "x k x0 ..".
 *
 * Built with -DFW_MODEL=<name> -DFW_MODEL_UPPER=<NAME> -DFW_HEADER='"<name>.h"'
 * -DMPC=<controller> -DMPC_UPPER=<CONTROLLER> -DMPC_HEADER='"<controller>.h"'.
 */
#include <stdio.h>
#include <stdlib.h>
#include FW_HEADER
#include MPC_HEADER

#define FW_CAT2(a, b) a##b
#define FW_CAT(a, b) FW_CAT2(a, b)
#define FW_FN(suffix) FW_CAT(FW_MODEL, suffix)
#define FW_DIM(suffix) FW_CAT(FW_MODEL_UPPER, suffix)
#define MPC_FN(suffix) FW_CAT(MPC, suffix)
#define NX FW_DIM(_NX)
#define NR FW_DIM(_NR)

typedef FW_FN(_real) real;
typedef FW_CAT(MPC, _memory) memory;

static memory mem;

static void row(const char *label, long k, int st, const real *v, int n)
{
    int i;
    printf("%s %ld %d", label, k, st);
    for (i = 0; i < n; ++i) printf(" %.9g", (double)v[i]);
    printf("\n");
}

int main(int argc, char **argv)
{
    real x[NX], u[NR], t, period = FW_CAT(MPC_UPPER, _PERIOD), h;
    long k, steps;
    int i, j, st;
    if (argc != NX + 2) {
        fprintf(stderr, "usage: mpc_driver STEPS X0 .. X%d\n", NX - 1);
        return 2;
    }
    steps = strtol(argv[1], NULL, 10);
    for (i = 0; i < NX; ++i) x[i] = (real)strtod(argv[i + 2], NULL);
    h = period / 10;
    if ((st = MPC_FN(_init)(&mem))) return 1;
    row("x", 0, 0, x, NX);
    for (k = 0; k < steps; ++k) {
        t = (real)k * period;
        st = MPC_FN(_step)(&mem, t, x, u);
        row("u", k, st, u, NR);
        for (j = 0; j < 10; ++j)
            if ((st = FW_FN(_step_rk4)(t + (real)j * h, h, u, NULL, 1, x))) {
                fprintf(stderr, "mpc_driver: %s\n", FW_FN(_status_message)(st));
                return 1;
            }
        row("x", k + 1, 0, x, NX);
    }
    return 0;
}
