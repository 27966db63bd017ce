"""The model inside CasADi: external functions with exact first and second derivatives.

    F = gen.casadi.functions(model)          # {"rhs": casadi.Function, ...}
    xdot = F["rhs"](x, r, p, t)
    J = casadi.jacobian(F["step"](X, r, p, t, h), X)   # jac_<f>, exact

One shared library, generated from templates/casadi/casadi_ext.c.j2 over
the model's C API (the "casadi" backend of gen/codegen/backends/: the C model,
its derivative kernels, the C runtime, and the CasADi wrappers), built
into the content-keyed cache by gen.build and loaded with
``casadi.external(name, path)``. The functions (CasADi names prefixed with
the model's, ``<model>_rhs``; the dict's keys are the short names):

    rhs(x, r, p, t) -> xdot                      <p>_eval_rhs
    implicit(x, xdot, r, p, t) -> residual       xdot - rhs, then f_c(q), f_v(q, u)
    step(x, r, p, t, h) -> x_next                <p>_step_rk4 with projection, or with
                                                 step="rodas4" one RODAS4 step of the
                                                 runtime (gen_rt_rodas4_trial; CasADi
                                                 name <p>_step_rodas4, first derivatives)
    outputs(x, r, p, t) -> y                     <p>_eval_outputs (models with outputs)
    constraints(x, p, t) -> c                    [f_c(q); f_v(q, u)] (constrained models)
    guard_<name>(x, p, t) -> g                   a hybrid model's (hybrid={...}) gap or
                                                 guard of declaration <name>, as the
                                                 simulator's events see it
    map_<name>(x, p, t) -> x_after               its jump: a Reset's map, or an Impact's
                                                 impulse (the runtime's impulse solve with
                                                 this gap alone, its restitution)

step of a hybrid model integrates one phase and never jumps: a step that
starts strictly before a guard and ends strictly past it, in the
declaration's direction, is refused (ERR_GUARD_CROSSED: gen.SolverError
naming the declaration and its values at x and x_next); one that ends on
the guard, a phase's last, is computed. A multi-phase problem ends each
phase on guard_<name>(x_N) = 0 and starts the next from map_<name>(x_N).

The derivatives, found by CasADi by name in the same library: jac_<f>,
fwd1_<f>, adj1_<f> (every input: x, xdot, r, p, t, h) and their Jacobians
jac_jac_<f>, jac_fwd1_<f>, jac_adj1_<f> (the second derivatives CasADi
forms exact Hessians from), computed by the runtime
(csrc/derivatives/gen_rt_deriv_inline.h: the second-order adjoint of the
equations x' solves; the runtime's RK4 differentiated stage by stage for
step, its RODAS4 step for step_rodas4; compiled into the library with the
model's sizes as constants) over kernels generated from the model's
expressions (gen/codegen/casadi_kernels.py derivative_kernels).
step of a constrained model has no derivatives (its projection has none).
The externals are loaded with enable_forward=False: forward products
through jac_<f> (one Jacobian, not one per seed column). functions(model,
hessians=False) loads a library without the second derivatives (and
without generating their kernels, the costly part of a large model's
build): for limited-memory Hessians, Gauss-Newton, simulation.

A missing r, p or h (a call by keyword without it) is NaN, so the call
fails instead of computing with zeros: pass ``p=model.p_values`` for the
model's own constants. The values are GenFunction (a casadi.Function): a
numeric call that fails raises gen.InputError (the missing or non-finite
input) or the library's status as gen.SolverError/SingularError, where
CasADi says only "Evaluation failed".
"""
from __future__ import annotations

import threading

from ..codegen.backends import get_backend
from ..codegen.casadi_kernels import NAMES, STEP_METHODS, cdef, function_specs, hybrid_bases
from ..core.errors import MissingDependencyError, ModelError
from ..core.optional import require
from ..intake.hybrid import KIND_RESET
from ..intake.model import require_model
from ..pipeline import build_product

__all__ = ["functions", "library", "function_specs", "NAMES", "GenFunction"]


def _casadi():
    return require("casadi", "gen.casadi")


def library(model, verbose=False, hessians=True, step="rk4"):
    """The path of the model's CasADi shared library (built into the cache
    on first use): the file ``casadi.external(name, path)`` loads.

    With ``hessians=True`` (the default) one library holds every function,
    both steps and the second derivatives. With ``hessians=False`` it holds
    first derivatives only, and the RODAS4 step only when ``step="rodas4"``
    (its first derivatives need the rhs Hessian kernel, which RK4's do not):
    no second-derivative kernels to generate. A second call in the same
    process returns the path without generating again
    (gen.pipeline.build_product)."""
    require_model(model, "gen.casadi")
    hessians = bool(hessians)
    rodas4 = hessians or step == "rodas4"
    b = get_backend("casadi").variant(hessians=hessians, rodas4=rodas4)
    return build_product(model, b, key=(hessians, rodas4), verbose=verbose)


# the class of functions()' values, made once casadi is imported
_lock = threading.Lock()
_classes = {}


def _checked_class(ca):
    """casadi.Function with a clear error for a failing numeric call."""
    with _lock:
        cls = _classes.get("GenFunction")
        if cls is None:
            cls = _classes["GenFunction"] = _make_class(ca)
        return cls


def _make_class(ca):
    class GenFunction(ca.Function):
        """A casadi.Function of the model's library: everything CasADi's
        has; a numeric call that fails (CasADi says only "Evaluation
        failed") raises a gen error that names the input or the status."""

        def __init__(self, f, path, model, spec):
            ca.Function.__init__(self, f)
            self._gen = (path, model, spec)

        def __call__(self, *args, **kwargs):
            try:
                return ca.Function.__call__(self, *args, **kwargs)
            except RuntimeError as e:
                if "Evaluation failed" not in str(e):
                    raise
                _explain(self, args, kwargs, e)
                raise

        def call(self, *args, **kwargs):
            try:
                return ca.Function.call(self, *args, **kwargs)
            except RuntimeError as e:
                if "Evaluation failed" not in str(e):
                    raise
                a = args[0] if args else kwargs.get("arg", ())
                if isinstance(a, dict):
                    _explain(self, (), a, e)
                else:
                    _explain(self, tuple(a), {}, e)
                raise

    GenFunction.__module__, GenFunction.__qualname__ = __name__, "GenFunction"
    return GenFunction


def __getattr__(name):
    # gen.casadi.GenFunction: the class of functions()' values (made once
    # casadi is imported)
    if name == "GenFunction":
        return _checked_class(_casadi())
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

# forward products through jac_<f>: CasADi would otherwise call fwd1_<f> (the
# whole Jacobian each time) once per seed column; reverse products and the
# Hessians keep adj1_<f> and jac_adj1_<f> (one adjoint sweep)
_OPTIONS = {"enable_forward": False}


def _arrays(F, args, kwargs):
    """[(name, nonzeros, values or None)] of a call's inputs by name; None
    for symbolic or odd arguments."""
    import numpy as np
    names = F.name_in()
    try:
        vals = dict(zip(names, args))
        vals.update(kwargs)
        return [(n, F.nnz_in(i), np.asarray(np.asarray(vals[n], dtype=float).ravel(order="F"),
                                            dtype=float) if n in vals else None)
                for i, n in enumerate(names)]
    except (TypeError, ValueError):
        return None


def _input_error(F, model, arrays, err):
    """Raise InputError for a missing r, p or h, a NaN or infinite input
    entry, or h = 0 in a RODAS4 step."""
    import numpy as np

    from ..core.errors import InputError
    fname = F.name()
    sig = f"{fname}({', '.join(F.name_in())})"
    for n, k, v in arrays:
        if v is None and k and n in ("r", "p", "h"):
            what = {"r": f"the model's inputs {list(model.input_names)}",
                    "p": "the constants (p=model.p_values for the model's own)",
                    "h": "the step size"}[n]
            raise InputError(f"{sig}: {n} is missing ({what}): it defaults to NaN so "
                             f"that the call fails instead of computing with zeros") from err
        if v is not None and v.size == k and not np.all(np.isfinite(v)):
            i = int(np.flatnonzero(~np.isfinite(v))[0])
            raise InputError(f"{sig}: {n}[{i}] = {v[i]}: the inputs must be finite") from err
        if n == "h" and fname.endswith("_step_rodas4") and v is not None and v.size == 1 \
                and v[0] == 0:
            raise InputError(f"{sig}: h = 0: a RODAS4 step needs a nonzero step size "
                             f"(its stages divide by h)") from err


def _library_status(F, keep):
    """The status of the library's function at the inputs keep (arrays),
    called again through gen.toolchain.host.open_library with the cdef of
    its declarations (rendered from its spec, as its header is)."""
    import numpy as np

    from ..toolchain.host import open_library
    path, _, spec = F._gen
    ffi, lib = open_library(path, cdef([spec]))
    sz = ffi.new("long long[4]")
    getattr(lib, spec["sym"] + "_work")(sz, sz + 1, sz + 2, sz + 3)
    outs = [np.zeros(max(1, F.nnz_out(i))) for i in range(F.n_out())]
    arg = ffi.new("double *[]", max(1, sz[0]))
    res = ffi.new("double *[]", max(1, sz[1]))
    for i, a in enumerate(keep):
        arg[i] = ffi.cast("double *", a.ctypes.data)
    for i, o in enumerate(outs):
        res[i] = ffi.cast("double *", o.ctypes.data)
    w = ffi.new("double[]", max(1, sz[3]))
    iw = ffi.new("long long[]", max(1, sz[2]))
    return getattr(lib, spec["sym"])(arg, res, iw, w, 0), outs


def _explain(F, args, kwargs, err):
    """Raise the gen error of a failed numeric call of F: a missing r, p or
    h; a NaN or infinite input entry; or the library's status (its name and
    message, from the same C function called again)."""
    import numpy as np

    from ..core.errors import SolverError
    from ..core.status import EXCEPTIONS, status_message, status_name
    path, model, _ = F._gen
    arrays = _arrays(F, args, kwargs)
    if arrays is None:
        return                      # symbolic or odd arguments: CasADi's error stands
    _input_error(F, model, arrays, err)
    keep = [np.ascontiguousarray(v if v is not None else np.zeros(k)) for _, k, v in arrays]
    st, outs = _library_status(F, keep)
    if st == 0:
        return
    name = status_name(st)
    names = F.name_in()
    at = ", ".join(f"{n} = {np.array2string(v, precision=6, separator=', ')}" if v.size > 1
                   else f"{n} = {float(v[0]):g}" for n, v in zip(names, keep)
                   if n in ("x", "t", "h"))
    cls = EXCEPTIONS.get(name, SolverError)
    msg = f"{F.name()}({', '.join(names)}) failed with {name}: {status_message(st)} (at {at})"
    if name == "ERR_GUARD_CROSSED":
        msg += _crossed(F, dict(zip(names, keep)), outs[0])
    try:
        exc = cls(msg, status=st, status_name=name)
    except TypeError:           # an error class without a status (InputError)
        exc = cls(msg)
    raise exc from err


def _crossed(F, args, x_next):
    """Which guards a refused step crossed: each declaration's value at x
    and at x_next (the step's own guard_<name> functions), in the user's
    names."""
    import numpy as np
    ca = _casadi()
    path, model, _ = F._gen
    t, h = float(args["t"][0]), float(args["h"][0])
    parts = []
    for d in getattr(model, "hybrid", None) or []:
        g = ca.external(f"{model.name}_guard_{d.name}", path)
        a = float(np.asarray(g(args["x"], args["p"], t)).ravel()[0])
        b = float(np.asarray(g(x_next, args["p"], t + h)).ravel()[0])
        if (d.direction <= 0 and a > 0 > b) or (d.direction >= 0 and a < 0 < b):
            kind = "reset" if d.kind == KIND_RESET else "impact"
            parts.append(f"{kind} {d.name!r} goes from {a:.6g} at x to {b:.6g} at x_next")
    return ("; " + "; ".join(parts) + " (a phase ends on its guard: guard_<name>(x_N) = 0, "
            "then map_<name>)") if parts else ""


def functions(model, verbose=False, step="rk4", hessians=True):
    """The model as CasADi functions, loaded with ``casadi.external`` from
    one generated shared library (:func:`library`).

    Parameters
    ----------
    model : gen.Model
        The model.
    verbose : bool, optional
        Print the compiler's commands.
    step : {"rk4", "rodas4"}, optional
        The method of ``step``: one classic RK4 step with the projection
        (``<model>_step_rk4``; exact first and second derivatives), or one
        RODAS4 step of the runtime (``gen_rt_rodas4_trial``, the adaptive
        RODAS4's trial step: linearly implicit, L-stable, for stiff models
        and large h; unconstrained models; exact first derivatives, no
        second derivatives). The dict's key is ``step`` either way; the
        CasADi name is ``<model>_step`` or ``<model>_step_rodas4``.
    hessians : bool, optional
        With the second derivatives (``jac_jac_``, ``jac_fwd1_``,
        ``jac_adj1_``: exact Hessians through the functions, IPOPT's
        ``hessian_approximation="exact"``; the default). ``False`` builds a
        library with first derivatives only, which skips generating the
        second-derivative kernels (the costly part of the build: for the
        Whipple bicycle most of it). For limited-memory Hessians
        (``hessian_approximation="limited-memory"``), Gauss-Newton or
        simulation. A Hessian through such a function fails in CasADi
        ("Derivatives cannot be calculated for ...").

    Returns
    -------
    dict of str to casadi.Function
        ``rhs``, ``implicit``, ``step`` and, when the model has them,
        ``outputs`` and ``constraints``, then for a hybrid model
        ``guard_<name>`` and ``map_<name>`` of each declaration in order
        (the module's docstring lists their inputs and outputs;
        ``F.name_in()`` too). ``step`` of a hybrid model integrates one
        phase: a step across a guard in its direction raises
        ``gen.SolverError`` (``ERR_GUARD_CROSSED``) instead of jumping.

    Raises
    ------
    gen.MissingDependencyError
        When CasADi is not installed (``pip install eomgen[casadi]``).
    gen.ModelError
        When ``model`` is not a gen.Model, or ``step="rodas4"`` for a
        constrained model.
    ValueError
        When ``step`` is not one of "rk4", "rodas4", or ``hessians`` is not a bool.
    gen.BuildError
        When the compiler fails.
    """
    ca = _casadi()
    if ca.__dict__.get("external") is None:
        raise MissingDependencyError("the installed casadi has no casadi.external: "
                                     "pip install --upgrade eomgen[casadi]")
    require_model(model, "gen.casadi.functions")
    if not isinstance(step, str) or step not in STEP_METHODS:
        raise ValueError(f"gen.casadi.functions(step={step!r}): step must be one of "
                         f"{', '.join(repr(k) for k in STEP_METHODS)}")
    if not isinstance(hessians, bool):
        raise ValueError(f"gen.casadi.functions(hessians={hessians!r}): hessians must be True "
                         f"(exact second derivatives) or False (first derivatives only)")
    if step == "rodas4" and (model.mc or model.mv):
        raise ModelError(
            f"gen.casadi.functions(step='rodas4'): model {model.name!r} has constraints "
            f"({model.mc} holonomic, {model.mv} nonholonomic) and the RODAS4 step has no "
            f"projection and no derivatives of one; use step='rk4' (with its projection)")
    path = str(library(model, verbose=verbose, hessians=hessians, step=step))
    out = {}
    want = STEP_METHODS[step]
    hybrid = [b[0] for b in hybrid_bases(model)]
    for s in function_specs(model, hessians, hessians or step == "rodas4"):
        if s["kind"] not in NAMES and s["kind"] != want and s["kind"] not in hybrid:
            continue
        if s["kind"] == "step" and want != "step":
            continue
        key = "step" if s["kind"] == want else s["name"]
        out[key] = _checked_class(ca)(ca.external(s["sym"], path, _OPTIONS), path, model, s)
    out = {k: out[k] for k in (*NAMES, *hybrid) if k in out}
    if not out:
        raise ModelError(f"model {model.name!r} gave no CasADi functions")
    return out
