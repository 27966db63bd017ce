/* gen_rt_status.c - status messages and finiteness checks. */
#include "gen_rt.h"

const char *gen_rt_status_message(int status)
{
    switch (status) {
    case GEN_RT_OK: return "ok";
    case GEN_RT_ERR_NULL: return "a required pointer argument is NULL";
    case GEN_RT_ERR_NONFINITE_INPUT: return "an input value is NaN or infinite";
    case GEN_RT_ERR_SINGULAR: return "singular system: the matrix to solve is singular or too badly conditioned at this state (for a partitioned model: the dependent coordinates/speeds are not determined here)";
    case GEN_RT_ERR_NO_CONVERGENCE: return "Newton iteration on the configuration constraints did not converge";
    case GEN_RT_ERR_STEP_UNDERFLOW: return "step size underflow: the adaptive integrator could not meet the tolerance";
    case GEN_RT_ERR_MAX_STEPS: return "maximum number of integration steps exceeded";
    case GEN_RT_ERR_BAD_ARG: return "an argument is out of range (size, step or tolerance)";
    case GEN_RT_ERR_NONFINITE_MODEL: return "the model expressions evaluate to NaN or infinity at this state (a singular configuration of the model)";
    case GEN_RT_ERR_OUTPUT_FULL: return "the output buffer is too small";
    default: return "unknown status code";
    }
}

int gen_rt_all_finite(int n, const gen_rt_real *v)
{
    int i;
    for (i = 0; i < n; ++i) {
        /* x - x is NaN for NaN and inf, 0 otherwise; no libm needed */
        gen_rt_real d = v[i] - v[i];
        if (d != d) return 0;
    }
    return 1;
}
