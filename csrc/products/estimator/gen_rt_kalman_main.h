/*
 * gen_rt_kalman_main.h - the standalone program of a Kalman filter
 * (gen.EKF.to_c): it reads a sensor CSV and writes the estimates.
 *
 *     <name>_filter [input.csv] [-o output.csv]      (stdin and stdout by default)
 *
 * The input: a header naming its columns (any order, others ignored): t,
 * every measurement and every input; then one row per sample, the times
 * t0 + k period. An empty field or nan is a missing measurement. Row 0
 * updates the filter (its settings and start from <name>_defaults) at t0;
 * row k > 0 predicts with the inputs of row k - 1, then updates. The
 * output: t, the filter state, its standard deviations (sd_<state>) and
 * each measurement's status (GEN_RT_KALMAN_*), one row per input row.
 *
 * Hand-written and model-agnostic: the generated <name>_main.c describes
 * the filter in a gen_rt_kalman_program and calls gen_rt_kalman_main().
 * Not part of the filter's library: it uses stdio (no heap).
 */
#ifndef GEN_RT_KALMAN_MAIN_H
#define GEN_RT_KALMAN_MAIN_H

#include "gen_rt_kalman.h"

#ifdef __cplusplus
extern "C" {
#endif

/* the longest input line */
#define GEN_RT_KALMAN_MAIN_LINE 8192
/* the most columns of an input row */
#define GEN_RT_KALMAN_MAIN_COLS 256

typedef struct {
    const char *name;                  /* the program's name, for messages */
    int ns, nz, nr;
    const char *const *state_names;    /* ns */
    const char *const *z_names;        /* nz */
    const char *const *r_names;        /* nr */
    gen_rt_kalman *k;                  /* the filter, with its values (not started) */
    gen_rt_real *z, *r;                /* nz, nr (>= 1): the row's values */
} gen_rt_kalman_program;

/* Run the program; its exit code (0, 1 on a filter failure, 2 on bad usage
 * or input). */
int gen_rt_kalman_main(int argc, char **argv, const gen_rt_kalman_program *prog);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_KALMAN_MAIN_H */
