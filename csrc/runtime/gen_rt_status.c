/* gen_rt_status.c - status messages (from the table in gen_rt_status.h)
 * and finiteness checks. */
#include "gen_rt.h"

const char *gen_rt_status_message(int status)
{
    switch (status) {
#define GEN_RT_STATUS_CASE_(name, value, text) case GEN_RT_##name: return text;
    GEN_RT_STATUS_TABLE(GEN_RT_STATUS_CASE_)
#undef GEN_RT_STATUS_CASE_
    default: return GEN_RT_STATUS_UNKNOWN;
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
