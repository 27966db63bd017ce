/* gen_rt_ocp.h - the node loop of a direct-collocation problem (gen.OptimalControl).
 *
 * A problem is a list of blocks. A block is one kernel family (generated:
 * the point equations, the defects, the running cost, ...) instantiated at
 * ninst places of the trajectory. Each instance gathers its nv local
 * variables from the decision vector z as linear combinations
 *     v[a] = sum_k gcoef[k] * (gidx[k] >= 0 ? z[gidx[k]] : 1),
 *            k in [gstart[i*nv + a], gstart[i*nv + a + 1])
 * calls the family's kernels and scatters their values into the caller's
 * output: constraint rows row0[i] + j (row0[i] < 0: the objective), the
 * nonzeros of the sparse constraint Jacobian (or the dense objective
 * gradient) and of the lower triangle of the Hessian of the Lagrangian,
 * through precomputed (local nonzero, slot, coefficient) triplets.
 * Everything is caller-owned; no heap, no globals, reentrant. */
#ifndef GEN_RT_OCP_H
#define GEN_RT_OCP_H

#include "gen_rt_status.h"
/* gen_rt_ocp_block and the GEN_RT_OCP_* codes: the library's interface,
 * described once (gen/codegen/backends.py OcpBackend.interface) and
 * rendered into gen_rt_ocp_abi.h beside this file in every build, as into
 * the cffi cdef that loads the library */
#include "gen_rt_ocp_abi.h"

/* the runtime's status codes (as gen_rt.h declares them; this header
 * stands alone: an optimal-control library links no simulator) */
#ifndef GEN_RT_H
#define GEN_RT_STATUS_ENUM_(name, value, text) GEN_RT_##name = (value),
enum gen_rt_status { GEN_RT_STATUS_TABLE(GEN_RT_STATUS_ENUM_) GEN_RT_STATUS_END_ = 1 };
#undef GEN_RT_STATUS_ENUM_
#endif

/* one kernel: v (nv locals), p (known constants), d (nd instance data),
 * lam (nrow multipliers; the Hessian kernel only), out */
typedef int (*gen_rt_ocp_kernel)(const double *v, const double *p, const double *d,
                                 const double *lam, double *out);

typedef struct {
    int nv, nrow, nd, njac, nhess;
    gen_rt_ocp_kernel val, jac, hess;
} gen_rt_ocp_family;

/* the size of work gen_rt_ocp_eval needs for these families */
int gen_rt_ocp_work_len(const gen_rt_ocp_family *fams, int nfam);

/* what: one of GEN_RT_OCP_*; out (nout) is zeroed, then filled. lam: the
 * constraint multipliers and sigma the objective's factor (Hessian only).
 * Returns 0, GEN_RT_ERR_NULL, or a kernel's negative status. */
int gen_rt_ocp_eval(const gen_rt_ocp_family *fams, const gen_rt_ocp_block *blocks,
                    int nblocks, const double *z, const double *p, int what,
                    const double *lam, double sigma, double *work, int nout, double *out);

#endif /* GEN_RT_OCP_H */
