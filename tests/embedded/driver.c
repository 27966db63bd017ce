/* driver.c - test driver for a generated model, built with a cross compiler
 * (arm-linux-gnueabihf-gcc -static) and run under qemu-arm by
 * tests/features/test_embedded.py, or natively. Only the model library and stdio.
 *
 *   driver X0 X1 ... X(NX-1)
 *
 * prints, with %.9g, at the given state x: "rhs" x' (NX values), "A" and "B"
 * of the linearization (NS*NS and NS*NR values), then "sim" rows
 * "t x0 .. x(NX-1)" of a 10 s RK4 simulation with dt = 0.01 and projection
 * onto the constraints after every step, every 1 s (the initial state is
 * projected first, as <name>_simulate does).
 *
 * Built with -DFW_MODEL=<name> -DFW_MODEL_UPPER=<NAME> -DFW_HEADER='"<name>.h"'.
 */
#include <stdio.h>
#include <stdlib.h>
#include FW_HEADER

#define FW_CAT2(a, b) a##b
#define FW_CAT(a, b) FW_CAT2(a, b)
#define FW_FN(suffix) FW_CAT(FW_MODEL, suffix)
#define FW_DIM(suffix) FW_CAT(FW_MODEL_UPPER, suffix)
#define NX FW_DIM(_NX)
#define NS FW_DIM(_NS)
#define NR FW_DIM(_NR)
#define MV FW_DIM(_MV)
#define ONE1(n) ((n) > 0 ? (n) : 1)

typedef FW_FN(_real) real;

static void row(const char *label, const real *v, int n)
{
    int i;
    printf("%s", label);
    for (i = 0; i < n; ++i) printf(" %.9g", (double)v[i]);
    printf("\n");
}

int main(int argc, char **argv)
{
    real x[NX], dxdt[NX], lam[ONE1(MV)], A[NS * NS], B[ONE1(NS * NR)];
    const real dt = (real)1 / (real)100;
    int i, k, st;
    if (argc != NX + 1) {
        fprintf(stderr, "usage: driver X0 .. X%d\n", NX - 1);
        return 2;
    }
    for (i = 0; i < NX; ++i) x[i] = (real)strtod(argv[i + 1], NULL);
    if ((st = FW_FN(_eval_rhs)(0, x, NULL, NULL, dxdt, lam))) goto fail;
    row("rhs", dxdt, NX);
    if ((st = FW_FN(_linearize)(x, NULL, NULL, 0, A, B))) goto fail;
    row("A", A, NS * NS);
    row("B", B, NS * NR);
    if ((st = FW_FN(_project)(0, NULL, 0, 0, x))) goto fail;
    printf("sim 0");
    row("", x, NX);
    for (k = 1; k <= 1000; ++k) {
        real t = (real)(k - 1) * dt;
        if ((st = FW_FN(_step_rk4)(t, dt, NULL, NULL, 1, x))) goto fail;
        if (k % 100 == 0) {
            printf("sim %d", k / 100);
            row("", x, NX);
        }
    }
    return 0;
fail:
    fprintf(stderr, "driver: %s\n", FW_FN(_status_message)(st));
    return 1;
}
