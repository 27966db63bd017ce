"""The filter's model and measurements: the user's model with the constants
to estimate promoted to coordinates (random walks: q' = 0, so the model's
own step and its exact sensitivity carry them), the measurements read in
the user's symbols (or the model's outputs by name) and made kernels, and
the estimator backend's ProductPlan.

    fm = filter_model(model, {"x_m": x, "th_m": theta}, estimate=[c], name="pend_kf")
    fm.model          # the filter's gen.Model: q = [q, c], independent; constants without c
    fm.plan           # ProductPlan(name, kernels=[h, hjac], files=<the model's C>, data)
"""
from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass, replace

import sympy as sm
from sympy.physics import mechanics as me

from ...codegen.product_abi import ProductPlan
from ...codegen.render import render
from ...codegen.templating import fmt_real
from ...core.errors import InputError
from ...core.names import validate_name
from ...plan.ir import Arg, make_jacobian_kernel, make_kernel, plan as make_plan
from ...sym.printers import check_printable

__all__ = ["FilterModel", "filter_model", "promote_constants", "measurement_exprs"]


@dataclass
class FilterModel:
    """What a filter is built from: the filter's model (the user's with the
    estimated constants as its last coordinates), the measurements' names
    and internal expressions, the estimated constants (names, indices into
    the user's constants, values), the filter state's names and the
    permutation from the filter state to the model's independent state, and
    the ProductPlan of its library."""
    source: object          # the user's gen.Model
    model: object           # the filter's gen.Model
    z_names: list
    z_exprs: list
    estimate: list          # names of the estimated constants
    estimate_index: list    # their indices into the user's constants
    state_names: list       # the filter state: the independent state, then the constants
    perm: list
    plan: ProductPlan

    def product_plan(self, real="double", data=None):
        """The estimator backend's ProductPlan for a scalar type: the
        filter model's C sources (its plugin table left out) rendered in
        real, the kernels, the data (updated with data)."""
        rendered = render(self.mplan, real=real, backend="c", project=False)
        m = self.model.name
        files = {f: txt for f, txt in rendered.files.items()
                 if f not in (f"{m}_api.c", f"{m}_lin_stub.c")}
        d = {**self.data, "work_dims": rendered.interface.work_dims(),
             "p0": [fmt_real(v, real) for v in self.data["p_values"]] or ["0"],
             "theta0": [fmt_real(v, real) for v in self.data["theta_values"]], **(data or {})}
        return ProductPlan(self.plan_name, kernels=self.kernels, data=d, files=files)

    @property
    def plan_name(self):
        return self.model.name[:-len("_model")]

    @property
    def ns(self):
        return self.model.ns

    @property
    def nz(self):
        return len(self.z_names)

    @property
    def ne(self):
        return len(self.estimate)


# ---------------------------------------------------------------- constants
def estimate_indices(model, estimate):
    """The indices into model's constants of estimate (symbols or names);
    InputError naming an entry that is not a constant (a state, an input,
    an unknown name)."""
    if estimate is None:
        return []
    if isinstance(estimate, (str, sm.Basic)):
        estimate = [estimate]
    out = []
    for e in estimate:
        i = None
        for j, (c, nm, lab) in enumerate(zip(model.p_orig, model.constant_names,
                                              model.constant_labels)):
            if (isinstance(e, str) and e in (nm, lab)) or (not isinstance(e, str) and e == c):
                i = j
        if i is None:
            what = _what_is(model, e)
            raise InputError(f"estimate: {e} is {what}, not a constant of the model "
                             f"'{model.name}': estimate takes constants (its constants: "
                             f"{', '.join(model.constant_labels) or 'none'})", "estimate",
                             None, str(e))
        if i in out:
            raise InputError(f"estimate: the constant {e} is given twice", "estimate", None,
                             str(e))
        out.append(i)
    return out


def _what_is(model, e):
    s = str(e)
    if s in model.state_labels or s in model.state_names or e in model.q_orig + model.u_orig:
        return "a state"
    if s in model.input_labels or s in model.input_names or e in model.r_orig:
        return "an input"
    return "unknown to the model"


def promote_constants(model, idx, name):
    """The model named name with the constants idx (indices into p) as
    coordinates appended to q, independent, with q' = 0 (random walks):
    their internal symbols are the same, so every expression holds them as
    it did. The model's outputs are left out (a filter measures through its
    own kernels)."""
    ne, nq, nu = len(idx), model.nq, model.nu
    keep = [i for i in range(model.np) if i not in idx]
    pick = lambda seq, ids: [seq[i] for i in ids]  # noqa: E731
    changes = dict(name=name, y=sm.zeros(0, 1), output_names=[], output_labels=[])
    if ne:
        theta = pick(model.p, idx)
        changes.update(
            q_orig=list(model.q_orig) + pick(model.p_orig, idx), q=list(model.q) + theta,
            p_orig=pick(model.p_orig, keep), p=pick(model.p, keep),
            p_values=pick(model.p_values, keep),
            constant_names=pick(model.constant_names, keep),
            constant_labels=pick(model.constant_labels, keep),
            q_ind=list(model.q_ind) + list(range(nq, nq + ne)),
            state_names=(list(model.state_names[:nq]) + pick(model.constant_names, idx)
                         + list(model.state_names[nq:])),
            state_labels=(list(model.state_labels[:nq]) + pick(model.constant_labels, idx)
                          + list(model.state_labels[nq:])),
            Kqd=sm.diag(model.Kqd, sm.eye(ne)) if nq else sm.eye(ne),
            Ku=model.Ku.col_join(sm.zeros(ne, nu)), kf=model.kf.col_join(sm.zeros(ne, 1)),
            qdot=None if model.qdot is None else model.qdot.col_join(sm.zeros(ne, 1)),
            qd=(list(model.qd) + [sm.Dummy(f"qd{nq + j}") for j in range(ne)]
                if model.qd else []))
    return replace(model, **changes)


# ------------------------------------------------------------- measurements
def measurement_exprs(model, measurements):
    """(names, expressions in the model's internal symbols) of
    measurements: {name: sympy expression or output name} or a list of
    output names. InputError naming a measurement that holds a symbol the
    model does not know, or an output it does not have."""
    if isinstance(measurements, dict):
        items = list(measurements.items())
    elif isinstance(measurements, (list, tuple)) and all(isinstance(m, str)
                                                        for m in measurements):
        items = [(m, m) for m in measurements]
    else:
        raise InputError("measurements must be a dict {name: sympy expression or output name} "
                         f"or a list of the model's output names, got {measurements!r}",
                         "measurements")
    if not items:
        raise InputError("measurements: give at least one", "measurements")
    t = me.dynamicsymbols._t
    sub = dict(zip(model.q_orig, model.q))
    sub.update(zip(model.u_orig, model.u))
    sub.update(zip(model.r_orig, model.r))
    sub.update(zip(model.p_orig, model.p))
    sub[t] = model.t
    qd = {}
    if model.method == "kane" and model.qdot is not None:
        qd = {qi.diff(t): e for qi, e in zip(model.q_orig, model.qdot)}
    outputs = dict(zip(model.output_names, model.y)) | dict(zip(model.output_labels, model.y))
    allowed = set(model.q) | set(model.u) | set(model.r) | set(model.p) | {model.t}
    back = {v: k for k, v in sub.items()}
    names, exprs = [], []
    for name, e in items:
        if not isinstance(name, str) or not name.isidentifier():
            raise InputError(f"measurement name {name!r} must be an identifier",
                             "measurements", None, name)
        if name in names:
            raise InputError(f"measurement {name!r} is given twice", "measurements", None, name)
        if isinstance(e, str):
            if e not in outputs:
                raise InputError(f"measurement {name!r}: {e!r} is not an output of the model "
                                 f"'{model.name}' (its outputs: "
                                 f"{', '.join(model.output_labels) or 'none'})",
                                 "measurements", None, e)
            expr = outputs[e]
        else:
            try:
                expr = sm.sympify(e)
            except (sm.SympifyError, TypeError) as err:
                raise InputError(f"measurement {name!r} is not a sympy expression: {err}",
                                 "measurements", None, name) from None
            if not isinstance(expr, sm.Expr):
                raise InputError(f"measurement {name!r} must be a scalar sympy expression, "
                                 f"got {type(expr).__name__}", "measurements", None, name)
            expr = expr.xreplace(qd).xreplace(sub)
        _check_known(model, name, expr, allowed, back)
        check_printable([expr], f"measurement {name!r}", back, model.t)
        names.append(name)
        exprs.append(expr)
    return names, exprs


def _check_known(model, name, expr, allowed, back):
    extra = sorted((str(s) for s in expr.free_symbols - allowed))
    funcs = sorted(str(f) for f in expr.atoms(sm.Function)
                   if isinstance(f, sm.core.function.AppliedUndef))
    derivs = sorted(str(d.xreplace(back)) for d in expr.atoms(sm.Derivative))
    bad = extra + funcs + derivs
    if bad:
        raise InputError(
            f"measurement {name!r} names {', '.join(bad)}, unknown to the model "
            f"'{model.name}': a measurement is an expression in its states "
            f"({', '.join(model.state_labels)}), inputs ({', '.join(model.input_labels) or 'none'}"
            f"), constants ({', '.join(model.constant_labels) or 'none'}) and time",
            "measurements", None, bad[0])


# ----------------------------------------------------------------- the plan
_MEMO_SIZE = 16
_memo = OrderedDict()
_memo_lock = threading.Lock()


def filter_model(model, measurements, estimate=None, name=None):
    """The FilterModel of a model, its measurements and the constants to
    estimate; its plan (the filter model's C, the measurement kernels) kept
    for the process (at most 16, by the model's fingerprint, the
    measurements, the estimate and the name)."""
    if getattr(model, "hybrid", None):
        raise InputError(f"gen.EKF: the model '{model.name}' is hybrid (impacts or resets): "
                         "a filter over its smooth step would not see its jumps",
                         "model")
    name = name or f"{model.name}_kf"
    try:
        validate_name(name)
        validate_name(f"{name}_model")
    except Exception as e:
        raise InputError(f"name {name!r}: {e}", "name", None, name) from None
    if name == model.name:
        raise InputError(f"the filter's name {name!r} is the model's", "name", None, name)
    idx = estimate_indices(model, estimate)
    z_names, z_exprs = measurement_exprs(model, measurements)
    key = (model.fingerprint(), tuple(idx), tuple(z_names),
           tuple(sm.srepr(e) for e in z_exprs), name)
    with _memo_lock:
        hit = _memo.get(key)
        if hit is not None:
            _memo.move_to_end(key)
            return hit
    fm = _build(model, idx, z_names, z_exprs, name)
    with _memo_lock:
        _memo[key] = fm
        while len(_memo) > _MEMO_SIZE:
            _memo.popitem(last=False)
    return fm


def _build(model, idx, z_names, z_exprs, name):
    fmod = promote_constants(model, idx, f"{name}_model")
    ne, nq0 = len(idx), model.nq
    # the filter state: the user's independent state, then the constants;
    # the model's independent state is [q_ind, constants, u_ind]
    niq = model.nq - model.mc
    perm = (list(range(niq)) + list(range(niq + ne, fmod.ns)) + list(range(niq, niq + ne)))
    names = [fmod.independent_state_names[j] for j in perm]
    kernels = _kernels(fmod, z_exprs)
    data = {
        "model": fmod.name, "source_model": model.name, "nx": fmod.nx, "ns": fmod.ns,
        "nz": len(z_names), "nr": fmod.nr, "np": fmod.np, "ne": ne, "nq_plant": nq0,
        "perm": perm, "p_values": list(fmod.p_values),
        "theta_values": [model.p_values[i] for i in idx],
        "z_names": list(z_names), "state_names": names,
        "estimate_names": [model.constant_names[i] for i in idx],
    }
    fm = FilterModel(model, fmod, list(z_names), list(z_exprs),
                     [model.constant_names[i] for i in idx], list(idx), names, perm, None)
    fm.mplan = make_plan(fmod, derivatives=True)
    fm.kernels, fm.data = kernels, data
    fm.plan = fm.product_plan("double")
    return fm


def _kernels(fmod, z_exprs):
    """h and (h, dh/dx) over x = [q, u] of the filter's model, r, p, t."""
    xs = list(fmod.q) + list(fmod.u)
    args = [Arg("x", tuple(xs)), Arg("r", tuple(fmod.r)), Arg("p", tuple(fmod.p)),
            Arg("t", (fmod.t,))]
    Z = sm.Matrix(z_exprs)
    return [make_kernel("h", args, [("h", Z)]),
            make_jacobian_kernel("hjac", args, [("h", Z)], [("H", Z, xs)])]
