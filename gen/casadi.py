"""The model inside CasADi: external functions with their Jacobians.

    F = gen.casadi.functions(model)          # {"rhs": casadi.Function, ...}
    xdot = F["rhs"](x, r, p, t)
    J = casadi.jacobian(F["step"](X, r, p, t, h), X)   # jac_<f>, exact

One shared library, generated from templates/casadi/casadi_ext.c.j2 over
the model's C API (the "casadi" backend of gen/backends.py: the C model,
its derivative kernels, the C runtime, and the CasADi wrappers), built
into the content-keyed cache by gen.build and loaded with
``casadi.external(name, path)``. The functions (CasADi names prefixed with
the model's, ``<model>_rhs``; the dict's keys are the short names):

    rhs(x, r, p, t) -> xdot                      <p>_eval_rhs
    implicit(x, xdot, r, p, t) -> residual       xdot - rhs, then f_c(q), f_v(q, u)
    step(x, r, p, t, h) -> x_next                <p>_step_rk4 with projection
    outputs(x, r, p, t) -> y                     <p>_eval_outputs (models with outputs)
    constraints(x, p, t) -> c                    [f_c(q); f_v(q, u)] (constrained models)

The Jacobians, found by CasADi by name (``jac_<model>_<f>``), come from the
generated derivative kernels (``<p>_jacobian``, ``<p>_linearize_outputs``)
and the runtime's step sensitivities (``<p>_step_sensitivity``): blocks for
x (and xdot) and r. The model library has no derivative with respect to the
constants p, the time t or the step h: a Jacobian block for one of them
fails when requested (CasADi raises), it is never a silent zero. For a
constrained model only rhs has a Jacobian (the others' would need
d f_v/dq and the projection's derivative, which the library lacks).

A missing r, p or h (a call by keyword without it) is NaN, so the call
fails instead of computing with zeros: pass ``p=model.p_values`` for the
model's own constants.
"""
from __future__ import annotations

import importlib

from .backends import get_backend
from .build import build
from .errors import MissingDependencyError, ModelError
from .ir import plan as make_plan
from .model import require_model
from .render import render

__all__ = ["functions", "library", "function_specs", "block_specs", "NAMES"]

#: the functions, in the order of the dict functions() returns
NAMES = ("rhs", "implicit", "step", "outputs", "constraints")


def _casadi():
    try:
        return importlib.import_module("casadi")
    except ImportError:
        raise MissingDependencyError(
            "gen.casadi needs CasADi, which is not installed: pip install eomgen[casadi] "
            "(or pip install casadi)") from None


def _dense(m, n):
    """CasADi's compressed column storage of a dense m x n matrix."""
    return [m, n, *[j * m for j in range(n + 1)], *[i for _ in range(n) for i in range(m)]]


def block_specs(model):
    """The functions whose Jacobian blocks the library computes."""
    return [{"name": n} for n in _with_jac(model)]


def _with_jac(model):
    m = model
    if m.mc or m.mv:
        return ["rhs"]
    return ["rhs", "implicit", "step"] + (["outputs"] if m.output_names else [])


def function_specs(model):
    """The functions of a model's CasADi library, as the template's data:
    [{"sym", "kind", "ins": [(name, sparsity, default)], "outs": [(name,
    sparsity)], "sz_w", "sz_out", ...}], with jac_, fwd1_ and adj1_ of
    each function that has derivatives (their "base", "mode", "blocks"
    and "nodiff": what the template's code needs)."""
    m = model
    p = m.name
    nx, nr, np_, mc, mv, ny = m.nx, m.nr, m.np, m.mc, m.mv, len(m.output_names)
    nan = "NAN"
    # defaults: r, p, h are NaN when missing (the call fails), t is 0
    x_, r_, p_, t_ = ("x", nx, 0), ("r", nr, nan if nr else 0), ("p", np_, nan if np_ else 0), \
        ("t", 1, 0)
    base = {
        "rhs": ([x_, r_, p_, t_], [("xdot", nx)]),
        "implicit": ([x_, ("xdot", nx, 0), r_, p_, t_], [("residual", nx + mc + mv)]),
        "step": ([x_, r_, p_, t_, ("h", 1, nan)], [("x_next", nx)]),
        "outputs": ([x_, r_, p_, t_], [("y", ny)]),
        "constraints": ([x_, p_, t_], [("c", mc + mv)]),
    }
    have = [n for n in NAMES if (n != "outputs" or ny) and (n != "constraints" or mc + mv)]
    with_jac = set(_with_jac(m))
    sz_out = max(1, nx + mc + mv, ny)
    specs = []
    for n in have:
        ins, outs = base[n]
        specs.append({"sym": f"{p}_{n}", "kind": n, "name": n,
                      "ins": [(a, _dense(k, 1), d) for a, k, d in ins],
                      "outs": [(a, _dense(k, 1)) for a, k in outs],
                      "sz_w": 0, "sz_out": sz_out, "nodiff": []})
        if n not in with_jac:
            continue
        nrow = outs[0][1]
        # the row-major blocks <p>_<n>_blocks writes: (input index, offset, columns)
        offs, blocks, nodiff_in = 0, [], []
        for i, (a, k, _) in enumerate(ins):
            if a in ("p", "t", "h"):
                nodiff_in.append((i, k))
            else:
                blocks.append((i, offs, k))
                offs += nrow * k
        sz_w = 2 * nx * nx + nx * nr + ny * nx + ny * nr + 1
        common = {"base": n, "nrow": nrow, "sz_out": sz_out, "sz_w": sz_w}
        nin, nout = len(ins), len(outs)
        nom = [(a, _dense(k, 1), 0) for a, k, _ in ins] + [(f"out_{a}", _dense(k, 1), 0)
                                                           for a, k in outs]
        # jac_<f>: the blocks jac_<out>_<in> (one output: block i is input i)
        specs.append({**common, "sym": f"jac_{p}_{n}", "kind": f"jac_{n}", "name": f"jac_{n}",
                      "mode": "jac", "ins": nom,
                      "outs": [(f"jac_{outs[0][0]}_{a}", _dense(nrow, k)) for a, k, _ in ins],
                      "nodiff": [i for i, _ in nodiff_in], "blocks": blocks})
        # fwd1_<f>: J times the forward seeds of the inputs
        specs.append({**common, "sym": f"fwd1_{p}_{n}", "kind": f"fwd1_{n}", "name": f"fwd1_{n}",
                      "mode": "fwd",
                      "ins": nom + [(f"fwd_{a}", _dense(k, 1), 0) for a, k, _ in ins],
                      "outs": [(f"fwd_{outs[0][0]}", _dense(nrow, 1))],
                      "nodiff": [(nin + nout + i, k) for i, k in nodiff_in],
                      "blocks": [(nin + nout + i, off, k) for i, off, k in blocks]})
        # adj1_<f>: J^T times the adjoint seed of the output
        specs.append({**common, "sym": f"adj1_{p}_{n}", "kind": f"adj1_{n}", "name": f"adj1_{n}",
                      "mode": "adj",
                      "ins": nom + [(f"adj_{outs[0][0]}", _dense(nrow, 1), 0)],
                      "outs": [(f"adj_{a}", _dense(k, 1)) for a, k, _ in ins],
                      "nodiff": nodiff_in, "blocks": blocks, "seed": nin + nout})
    return specs


def library(model, verbose=False):
    """The path of the model's CasADi shared library (built into the cache
    on first use): the file ``casadi.external(name, path)`` loads."""
    require_model(model, "gen.casadi")
    b = get_backend("casadi")
    plan = make_plan(model, lin=b.lin, derivatives=True)
    rendered = render(plan, real="double", backend=b, project=False)
    return build(rendered, verbose=verbose).path


def functions(model, verbose=False):
    """The model as CasADi functions, loaded with ``casadi.external`` from
    one generated shared library (:func:`library`).

    Parameters
    ----------
    model : gen.Model
        The model.
    verbose : bool, optional
        Print the compiler's commands.

    Returns
    -------
    dict of str to casadi.Function
        ``rhs``, ``implicit``, ``step`` and, when the model has them,
        ``outputs`` and ``constraints`` (the module's docstring lists their
        inputs and outputs; ``F.name_in()`` too).

    Raises
    ------
    gen.MissingDependencyError
        When CasADi is not installed (``pip install eomgen[casadi]``).
    gen.ModelError
        When ``model`` is not a gen.Model.
    gen.BuildError
        When the compiler fails.
    """
    ca = _casadi()
    if ca.__dict__.get("external") is None:
        raise MissingDependencyError("the installed casadi has no casadi.external: "
                                     "pip install --upgrade eomgen[casadi]")
    require_model(model, "gen.casadi.functions")
    path = str(library(model, verbose=verbose))
    out = {}
    for s in function_specs(model):
        if s["kind"] not in NAMES:
            continue
        out[s["name"]] = ca.external(s["sym"], path)
    if not out:
        raise ModelError(f"model {model.name!r} gave no CasADi functions")
    return out
