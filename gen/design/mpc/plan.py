"""An MPC as the MPC backend's ProductPlan (gen/codegen/backends/mpc.py):
its path constraints' and residuals' kernels (rows of [value, d/dx_ind,
d/dr], from one CSE'd graph each, gen.plan.ir), the problem's numbers for
the templates, and, for the library gen.MPC loads, the model's own C
sources rendered by the C backend (ProductPlan.files)."""
from __future__ import annotations

import numpy as np

from ...codegen.product_abi import ProductPlan
from ...codegen.render import render
from ...plan.ir import Arg, make_kernel, plan as make_plan
from .problem import sympy_jacobian_rows

__all__ = ["mpc_plan", "model_files", "KERNEL_DOCS"]

KERNEL_DOCS = {"path": "the path constraints h(x, u)",
               "residuals": "the least-squares residuals y(x, u)"}


def model_files(model, real):
    """The model's C sources (the C backend's, with the derivative kernels,
    without its plugin table): what the MPC's library compiles with its
    own."""
    files = render(make_plan(model, derivatives=True), real=real, backend="c",
                   project=False).files
    drop = {f"{model.name}_api.c", f"{model.name}_lin_stub.c"}
    return {k: v for k, v in files.items() if k not in drop}


def _kernels(model, pb):
    x = list(model.q) + list(model.u)
    x_ind = [x[i] for i in pb.ind]
    args = [Arg("x", tuple(x)), Arg("r", tuple(model.r)), Arg("p", tuple(model.p)),
            Arg("t", (model.t,))]
    out = []
    for kname, exprs in (("path", pb.path_exprs), ("residuals", pb.res_exprs)):
        if exprs:
            out.append(make_kernel(kname, args, [("out", sympy_jacobian_rows(
                exprs, x_ind, list(model.r)))]))
    return out


def mpc_plan(model, pb, ref, P, name, real, options, with_model=True):
    """The ProductPlan of an MPC (pb: problem.Problem, ref: reference.Reference,
    P: the terminal weight, options: tol, qp_tol, qp_max_iter, penalty)."""
    ind = pb.ind
    data = {
        "model": model.name, "N": pb.N, "nx": model.nx, "ns": len(ind), "nr": model.nr,
        "np_": max(1, model.np), "period": pb.period, "substeps": pb.substeps,
        "method": pb.method, "method_doc": ("one SQP iteration per call (RTI)"
                                            if pb.method == "rti" else
                                            f"SQP to convergence, at most {pb.max_iter} "
                                            "iterations per call"),
        "sqp": int(pb.method == "sqp"), "max_iter": pb.max_iter,
        "time_limit": pb.time_limit, "time_limit_lit": repr(float(pb.time_limit)),
        "tol": options["tol"], "qp_tol": options["qp_tol"],
        "qp_max_iter": options["qp_max_iter"],
        "constrained": bool(model.mc or model.mv),
        "ind_names": list(model.independent_state_names),
        "input_names": list(model.input_names),
        "ind": ind, "Q": pb.Q.ravel(), "R": pb.R.ravel(), "P": np.asarray(P).ravel(),
        "ny_": len(pb.res_exprs), "W": np.asarray(pb.W, dtype=float),
        "nbx": len(pb.idxbx), "idxbx": pb.idxbx, "lbx": pb.lbx, "ubx": pb.ubx,
        "zx": [options["penalty"]] * len(pb.idxbx),
        "nbu": len(pb.idxbu), "idxbu": pb.idxbu, "lbu": pb.lbu, "ubu": pb.ubu,
        "nh": len(pb.path_exprs), "lh": pb.lh, "uh": pb.uh, "zh": pb.path_soft,
        "n_ref": len(ref.x), "t_ref": ref.t0, "dt_ref": ref.dt,
        "t_ref_text": repr(float(ref.t0)), "dt_ref_text": repr(float(ref.dt)),
        "x_ref": ref.x[:, ind].ravel(), "u_ref": ref.u.ravel(),
        "p": pb.p if model.np else np.zeros(1),
        "kernel_docs": KERNEL_DOCS,
    }
    files = model_files(model, real) if with_model else {}
    return ProductPlan(name, names={"p": model.name}, kernels=_kernels(model, pb), data=data,
                       files=files)
