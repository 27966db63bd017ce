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

from .casadi_specs import NAMES, block_specs, function_specs  # noqa: E402,F401

def _casadi():
    try:
        return importlib.import_module("casadi")
    except ImportError:
        raise MissingDependencyError(
            "gen.casadi needs CasADi, which is not installed: pip install eomgen[casadi] "
            "(or pip install casadi)") from None


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
