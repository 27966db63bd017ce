/* gen_rt_ocp.c - the node loop of a direct-collocation problem: gather,
 * call the generated kernels, scatter (gen_rt_ocp.h). */
#include "gen_rt_ocp.h"

#include <stddef.h>

int gen_rt_ocp_work_len(const gen_rt_ocp_family *fams, int nfam)
{
    int f, n = 0;
    for (f = 0; f < nfam; ++f) {
        const gen_rt_ocp_family *F = &fams[f];
        int m = F->nv + 2 * F->nrow + F->njac + F->nhess + 1;
        if (m > n) n = m;
    }
    return n;
}

int gen_rt_ocp_eval(const gen_rt_ocp_family *fams, const gen_rt_ocp_block *blocks,
                    int nblocks, const double *z, const double *p, int what,
                    const double *lam, double sigma, double *work, int nout, double *out)
{
    int b, i, a, k, j, st;
    if (!fams || !blocks || !z || !work || !out) return GEN_RT_ERR_NULL;
    if (what == GEN_RT_OCP_HESSIAN && !lam) return GEN_RT_ERR_NULL;
    for (k = 0; k < nout; ++k) out[k] = 0.0;
    for (b = 0; b < nblocks; ++b) {
        const gen_rt_ocp_block *B = &blocks[b];
        const gen_rt_ocp_family *F = &fams[B->family];
        int nv = F->nv, nrow = F->nrow, nd = F->nd;
        double *v = work, *ml = work + nv, *val = work + nv + nrow;
        for (i = 0; i < B->ninst; ++i) {
            const double *d = B->data ? B->data + (size_t)i * (size_t)nd : NULL;
            int r0 = B->row0[i];
            for (a = 0; a < nv; ++a) {
                double s = 0.0;
                for (k = B->gstart[i * nv + a]; k < B->gstart[i * nv + a + 1]; ++k)
                    s += B->gidx[k] >= 0 ? B->gcoef[k] * z[B->gidx[k]] : B->gcoef[k];
                v[a] = s;
            }
            switch (what) {
            case GEN_RT_OCP_OBJECTIVE:
            case GEN_RT_OCP_CONSTRAINTS:
                if ((what == GEN_RT_OCP_OBJECTIVE) != (r0 < 0)) break;
                st = F->val(v, p, d, NULL, val);
                if (st) return st;
                if (r0 < 0) {
                    for (j = 0; j < nrow; ++j) out[0] += val[j];
                } else {
                    for (j = 0; j < nrow; ++j) out[r0 + j] = val[j];
                }
                break;
            case GEN_RT_OCP_GRADIENT:
            case GEN_RT_OCP_JACOBIAN:
                if ((what == GEN_RT_OCP_GRADIENT) != (r0 < 0)) break;
                st = F->jac(v, p, d, NULL, val);
                if (st) return st;
                for (k = B->jstart[i]; k < B->jstart[i + 1]; ++k)
                    out[B->jslot[k]] += B->jcoef[k] * val[B->jloc[k]];
                break;
            case GEN_RT_OCP_HESSIAN:
                if (F->nhess == 0) break;
                for (j = 0; j < nrow; ++j) ml[j] = r0 < 0 ? sigma : lam[r0 + j];
                st = F->hess(v, p, d, ml, val);
                if (st) return st;
                for (k = B->hstart[i]; k < B->hstart[i + 1]; ++k)
                    out[B->hslot[k]] += B->hcoef[k] * val[B->hloc[k]];
                break;
            default:
                return GEN_RT_ERR_NULL;
            }
        }
    }
    return GEN_RT_OK;
}
