/* tracker_driver.c - a trajectory tracker (gen.TrajectoryTracker.to_c) run as
 * a digital controller on a generated model, built with a cross compiler
 * (arm-linux-gnueabihf-gcc -static) and run under qemu-arm by
 * tests/features/test_tracking.py, or natively. Only the model library, the
 * tracker's const tables and stdio.
 *
 *   tracker_driver T_END DT X0 X1 ... X(NX-1)
 *
 * Every TRK_PERIOD: r = <trk>_step(t, x) (the law from the tables), then
 * RK4 steps of DT (a divisor of the period) with r held and projection;
 * prints, with %.9g, "r t r0 .." at each sample and "x t x0 .." every
 * sample, the last at T_END.
 *
 * Built with -DFW_MODEL=<name> -DFW_MODEL_UPPER=<NAME> -DFW_HEADER='"<name>.h"'
 * -DTRK=<tracker> -DTRK_UPPER=<TRACKER> -DTRK_HEADER='"<tracker>.h"'.
 */
#include <stdio.h>
#include <stdlib.h>
#include FW_HEADER
#include TRK_HEADER

#define FW_CAT2(a, b) a##b
#define FW_CAT(a, b) FW_CAT2(a, b)
#define FW_FN(suffix) FW_CAT(FW_MODEL, suffix)
#define FW_DIM(suffix) FW_CAT(FW_MODEL_UPPER, suffix)
#define NX FW_DIM(_NX)
#define NR FW_DIM(_NR)

typedef FW_FN(_real) real;

static void row(const char *label, double t, const real *v, int n)
{
    int i;
    printf("%s %.9g", label, t);
    for (i = 0; i < n; ++i) printf(" %.9g", (double)v[i]);
    printf("\n");
}

int main(int argc, char **argv)
{
    real x[NX], r[NR], t, dt, period = FW_CAT(TRK_UPPER, _PERIOD);
    double t_end;
    long k, j, n_samples, n_sub;
    int i, st;
    if (argc != NX + 3) {
        fprintf(stderr, "usage: tracker_driver T_END DT X0 .. X%d\n", NX - 1);
        return 2;
    }
    t_end = strtod(argv[1], NULL);
    dt = (real)strtod(argv[2], NULL);
    for (i = 0; i < NX; ++i) x[i] = (real)strtod(argv[i + 3], NULL);
    n_samples = (long)(t_end / (double)period + 0.5);
    n_sub = (long)((double)period / (double)dt + 0.5);
    row("x", 0, x, NX);
    for (k = 0; k < n_samples; ++k) {
        t = (real)k * period;
        if ((st = FW_CAT(TRK, _step)(t, x, r))) goto fail;
        row("r", (double)t, r, NR);
        for (j = 0; j < n_sub; ++j) {
            if ((st = FW_FN(_step_rk4)(t, dt, r, NULL, 1, x))) goto fail;
            t += dt;
        }
        row("x", (double)(k + 1) * (double)period, x, NX);
    }
    return 0;
fail:
    fprintf(stderr, "tracker_driver: %s\n", FW_FN(_status_message)(st));
    return 1;
}
