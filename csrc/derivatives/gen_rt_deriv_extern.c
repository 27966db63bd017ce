/* gen_rt_deriv_extern.c - the implicit function's derivatives and the derivatives
 * of one RK4 and one RODAS4 step (gen_rt_deriv.h): the library functions
 * over the algorithms of gen_rt_deriv_inline.h. */
#include "gen_rt.h"
#include "gen_rt_deriv.h"
#include "gen_rt_deriv_inline.h"

int gen_rt_deriv_solve(const gen_rt_deriv_model *m, const gen_rt_real *z, gen_rt_real *work,
                       gen_rt_real *w, gen_rt_real *lu, int *piv, gen_rt_real *Jw)
{
    return gen_rt_deriv_solve_inline(m, z, work, w, lu, piv, Jw);
}

int gen_rt_deriv_hessian(const gen_rt_deriv_model *m, const gen_rt_real *z,
                         const gen_rt_real *w, const gen_rt_real *lu, const int *piv,
                         const gen_rt_real *Jw, const gen_rt_real *lam, gen_rt_real *work,
                         gen_rt_real *H)
{
    return gen_rt_deriv_hessian_inline(m, z, w, lu, piv, Jw, lam, work, H);
}

int gen_rt_deriv_rk4(const gen_rt_deriv_model *m, const gen_rt_real *z, gen_rt_real h,
                     const gen_rt_real *lam, gen_rt_real *work, int *iwork, gen_rt_real *xn,
                     gen_rt_real *J, gen_rt_real *Hl, gen_rt_real *T)
{
    return gen_rt_deriv_rk4_inline(m, z, h, lam, work, iwork, xn, J, Hl, T);
}

int gen_rt_deriv_rodas4(const gen_rt_deriv_model *m, const gen_rt_real *z, gen_rt_real h,
                        gen_rt_real *work, int *iwork, gen_rt_real *J)
{
    return gen_rt_deriv_rodas4_inline(m, z, h, work, iwork, J);
}
