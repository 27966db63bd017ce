/* gen_rt_casadi_extern.c - a model's functions in CasADi's calling convention
 * (gen_rt_casadi.h): the library function over gen_rt_casadi_inline.h. */
#include "gen_rt.h"
#include "gen_rt_casadi.h"
#include "gen_rt_casadi_inline.h"

int gen_rt_cs_eval(const gen_rt_cs_model *m, const gen_rt_cs_fn *f, const gen_rt_real **arg,
                   gen_rt_real **res, gen_rt_real *work, int *iwork)
{
    return gen_rt_cs_eval_inline(m, f, arg, res, work, iwork);
}
