/* mpc_fw.c - a tiny Cortex-M firmware image of a model predictive
 * controller (gen.MPC.to_c) and its model, linked against newlib-nano so
 * that every reference is resolved by a real link: the controller's memory
 * a static instance (the caller's RAM), one controller call per loop on a
 * state the plant's model advances. No heap, no stdio.
 *
 * Built by tests/features/test_mpc_embedded.py with -DFW_MODEL=<name>
 * -DFW_MODEL_UPPER=<NAME> -DFW_HEADER='"<name>.h"' -DMPC=<controller>
 * -DMPC_UPPER=<CONTROLLER> -DMPC_HEADER='"<controller>.h"', startup.c and
 * cortex_m4.ld.
 */
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

static FW_CAT(MPC, _memory) mem;
static real x[NX];
static real u[NR];
volatile int fw_status;
volatile real fw_sink;

int main(void)
{
    int i, k;
    real period = FW_CAT(MPC_UPPER, _PERIOD);
    for (i = 0; i < NX; ++i) x[i] = (real)(i + 1) / (real)(8 * NX);
    fw_status = MPC_FN(_init)(&mem);
    for (k = 0;; ++k) {
        fw_status = MPC_FN(_step)(&mem, (real)k * period, x, u);
        fw_status |= FW_FN(_step_rk4)((real)k * period, period, u, 0, 1, x);
        fw_sink = u[0];
    }
}
