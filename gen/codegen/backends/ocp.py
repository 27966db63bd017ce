"""The optimal-control product's backend: a direct-collocation problem's
kernels over the node loop of csrc/products/ocp (gen.OptimalControl)."""
from __future__ import annotations

from .base import ProductBackend
from ..product_abi import CConst, CEnum, CField, CFunction, CStruct, ProductInterface

class OcpBackend(ProductBackend):
    """A direct-collocation problem's library (gen.OptimalControl,
    gen/design/ocp): the generated kernels of every family of the problem
    (values, sparse Jacobian, Hessian of the Lagrangian) in <name>.c, over
    the hand-written node loop (csrc/products/ocp/gen_rt_ocp.c), which
    gathers each instance's locals and scatters into IPOPT's arrays through
    the caller's index tables (gen_rt_ocp_block)."""
    name = "ocp"
    tag = ""
    templates = (("{name}.c", "ocp/ocp.c.j2", "product"),)
    runtime_files = ("gen_rt_ocp.c", "gen_rt_ocp.h", "gen_rt_status.h")
    interface = ProductInterface(
        product="ocp",
        doc="the optimal-control kernels of the model '{model}' over the node loop",
        types_header="gen_rt_ocp_abi.h",
        enums=(CEnum("what gen_rt_ocp_eval (a library's <prefix>_eval) computes", (
            CConst("GEN_RT_OCP_OBJECTIVE", 0, "the objective, out[0]"),
            CConst("GEN_RT_OCP_GRADIENT", 1, "its gradient, one per unknown"),
            CConst("GEN_RT_OCP_CONSTRAINTS", 2, "the constraints, one per row"),
            CConst("GEN_RT_OCP_JACOBIAN", 3, "the nonzeros of their Jacobian"),
            CConst("GEN_RT_OCP_HESSIAN", 4, "the nonzeros of the lower triangle of the "
                   "Hessian of the Lagrangian"))),),
        structs=(CStruct(
            "gen_rt_ocp_block", "One family's instances: where each gathers its locals "
            "from z, its rows, and where its Jacobian and Hessian nonzeros go.", (
                CField("family", "int", "index into the families"),
                CField("ninst", "int", "instances"),
                CField("gstart", "const int *", "ninst*nv + 1"),
                CField("gidx", "const int *", "z index, or -1 for the constant 1"),
                CField("gcoef", "const double *"),
                CField("data", "const double *", "ninst*nd"),
                CField("row0", "const int *", "ninst: first constraint row, < 0: objective"),
                CField("jstart", "const int *", "ninst + 1"),
                CField("jloc", "const int *", "local Jacobian nonzero"),
                CField("jslot", "const int *", "global Jacobian nonzero (or gradient entry)"),
                CField("jcoef", "const double *"),
                CField("hstart", "const int *", "ninst + 1"),
                CField("hloc", "const int *"),
                CField("hslot", "const int *"),
                CField("hcoef", "const double *"))),),
        functions=(
            CFunction("{name}_eval", "int", (
                ("const gen_rt_ocp_block *", "blocks"), ("int", "nblocks"),
                ("const double *", "z"), ("const double *", "p"), ("int", "what"),
                ("const double *", "lam"), ("double", "sigma"), ("double *", "work"),
                ("int", "nout"), ("double *", "out")),
                "The problem's what (GEN_RT_OCP_*) at the unknowns z, p the known constants: "
                "out (nout) zeroed, then filled by the blocks' instances. lam: the "
                "constraint multipliers and sigma the objective's factor (Hessian only); "
                "work: {name}_work_len() doubles. Returns 0, GEN_RT_ERR_NULL, or a "
                "kernel's negative status."),
            CFunction("{name}_work_len", "int", (),
                      "The doubles of work {name}_eval needs.")))

    def names(self, plan, real):
        return {**super().names(plan, real), "model": plan.data["model"]}
