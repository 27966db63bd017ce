/* fw_main.c - a tiny Cortex-M firmware image linking the embedded subset of a
 * generated model (lib<name>_model.a) against newlib-nano, so that every
 * reference is resolved by a real link. main() evaluates the right-hand side,
 * takes RK4 steps and linearizes on a static state.
 *
 * Build (tests/features/test_embedded.py):
 *   arm-none-eabi-gcc <cpu flags> -Os -DFW_MODEL=<name> -DFW_MODEL_UPPER=<NAME>
 *     -DFW_HEADER='"<name>.h"' -I<generated dir> fw_main.c startup.c
 *     -T cortex_m4.ld -nostartfiles --specs=nano.specs --specs=nosys.specs
 *     -Wl,--gc-sections lib<name>_model.a -lm -o fw.elf
 */
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

static real x[NX];
static real dxdt[NX];
static real lam[ONE1(MV)];
static real A[NS * NS];
static real B[ONE1(NS * NR)];
volatile int fw_status;
volatile real fw_sink;

int main(void)
{
    int i, st;
    /* a consistent small-angle state for the seed pendulums is made by
     * consistent_state from the independent coordinate; other models start
     * from a small offset of every coordinate */
    for (i = 0; i < NX; ++i) x[i] = (real)(i + 1) / (real)(4 * NX);
    st = FW_FN(_consistent_state)(0, 0, 0, 0, x);
    st |= FW_FN(_eval_rhs)(0, x, 0, 0, dxdt, lam);
    for (i = 0; i < 100; ++i) st |= FW_FN(_step_rk4)((real)i / 100, (real)1 / 100, 0, 0, 1, x);
    st |= FW_FN(_linearize)(x, 0, 0, 0, A, B);
    fw_status = st;
    fw_sink = dxdt[0] + A[0] + B[0] + lam[0];
    for (;;) {
    }
}
