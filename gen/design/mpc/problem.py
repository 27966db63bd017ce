"""The user's side of a model predictive controller: its arguments read into
plain arrays on the model's independent state, each bad one named in an
InputError in the user's own names (their sympy symbols, their states)
before anything is built.

    pb = read_problem(model, horizon, period, Q, R, P, bounds, path, reference,
                      substeps, method, max_iter, time_limit, ...)
    pb.Q, pb.lbu, pb.x_ref, pb.path_exprs, ...
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import sympy as sm

from ...core.errors import InputError
from ..ocp.names import Names

__all__ = ["Problem", "read_problem", "METHODS"]

#: method -> one SQP iteration per call (RTI) or iterations to convergence
METHODS = ("rti", "sqp")


@dataclass
class Problem:
    """An MPC's problem as numbers (the independent state's order: the
    model's independent_state_names) and expressions (internal symbols)."""
    N: int
    period: float
    substeps: int
    method: str
    max_iter: int
    time_limit: float
    ind: list                      # ns indices of x_ind in x
    Q: np.ndarray
    R: np.ndarray
    P: np.ndarray | None           # None: the DARE's (controller.py)
    idxbx: list = field(default_factory=list)   # into x_ind
    lbx: list = field(default_factory=list)
    ubx: list = field(default_factory=list)
    idxbu: list = field(default_factory=list)
    lbu: list = field(default_factory=list)
    ubu: list = field(default_factory=list)
    path_exprs: list = field(default_factory=list)
    lh: list = field(default_factory=list)
    uh: list = field(default_factory=list)
    path_soft: list = field(default_factory=list)
    res_exprs: list = field(default_factory=list)
    W: list = field(default_factory=list)
    t_ref: float = 0.0
    x_ref: np.ndarray | None = None      # (n_ref, ns)
    u_ref: np.ndarray | None = None      # (n_ref, nr)
    p: np.ndarray | None = None


def _err(msg, name=None, value=None):
    return InputError(f"gen.MPC: {msg}", name, None, value)


def _names(names):
    return ", ".join(names)


def _weight(W, n, name, labels, definite):
    """A symmetric weight (n x n or n diagonal values), semidefinite or
    definite."""
    W = np.asarray(W, dtype=float)
    if W.ndim <= 1 and W.size == n:
        W = np.diag(W.reshape(-1))
    if W.shape != (n, n):
        raise _err(f"{name} must have shape ({n}, {n}) (a weight on {_names(labels)}), or {n} "
                   f"diagonal values, got shape {W.shape}", name)
    if not np.all(np.isfinite(W)):
        i, j = (int(v) for v in np.argwhere(~np.isfinite(W))[0])
        raise _err(f"{name}[{i}, {j}] = {float(W[i, j])!r}: every entry must be finite", name,
                   float(W[i, j]))
    asym = np.abs(W - W.T)
    if np.max(asym) > 1e-12 * max(1.0, np.max(np.abs(W))):
        i, j = np.unravel_index(np.argmax(asym), W.shape)
        raise _err(f"{name} must be symmetric, but {name}[{i}, {j}] = {float(W[i, j])!r} "
                   f"({labels[i]}, {labels[j]}) != {name}[{j}, {i}] = {float(W[j, i])!r}", name)
    ev = np.linalg.eigvalsh(0.5 * (W + W.T))
    top = max(1.0, float(np.max(np.abs(ev))))
    if definite and not ev[0] > 1e-12 * top:
        raise _err(f"{name} must be positive definite (a weight on every one of "
                   f"{_names(labels)}); its smallest eigenvalue is {float(ev[0])!r}", name,
                   float(ev[0]))
    if not definite and ev[0] < -1e-12 * top:
        raise _err(f"{name} must be positive semidefinite; its smallest eigenvalue is "
                   f"{float(ev[0])!r}", name, float(ev[0]))
    return 0.5 * (W + W.T)


def _positive_int(v, name, least=1):
    if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < least:
        raise _err(f"{name} must be an integer >= {least}, got {v!r}", name, v)
    return int(v)


def _bounds(model, nm, bounds, ind, penalty):
    """(idxbx, lbx, ubx, idxbu, lbu, ubu) of bounds {state or input: (lo, hi)}."""
    out = ([], [], [], [], [], [])
    if bounds is None:
        return out
    if not isinstance(bounds, dict):
        raise _err(f"bounds must be a dict {{state or input: (lo, hi)}}, got "
                   f"{type(bounds).__name__}", "bounds")
    for k, v in bounds.items():
        kind, i = nm.key(k, "gen.MPC: bounds")
        label = (model.state_names[i] if kind == "x" else
                 model.input_names[i] if kind == "r" else str(k))
        try:
            lo, hi = (float(b) for b in v)
        except (TypeError, ValueError):
            raise _err(f"bounds[{label}] must be (lo, hi), got {v!r}", "bounds") from None
        if math.isnan(lo) or math.isnan(hi):
            raise _err(f"bounds[{label}] = ({lo}, {hi}): a bound is NaN", "bounds")
        if lo > hi:
            raise _err(f"bounds[{label}] = ({lo}, {hi}): lo > hi", "bounds", (lo, hi))
        if kind == "x":
            if i not in ind:
                raise _err(f"bounds[{label}]: {label} is a dependent coordinate or speed of "
                           f"model {model.name!r}; bound an independent one "
                           f"({_names(model.independent_state_names)})", "bounds")
            out[0].append(ind.index(i)); out[1].append(lo); out[2].append(hi)
        elif kind == "r":
            out[3].append(i); out[4].append(lo); out[5].append(hi)
        else:
            raise _err(f"bounds: {label} is a constant of model {model.name!r}, not a state or "
                       "an input", "bounds")
    if out[0] and not (penalty > 0 and math.isfinite(penalty)):
        raise _err(f"penalty must be a positive number (the L1 weight of the soft state "
                   f"bounds), got {penalty!r}", "penalty", penalty)
    return out


def _expression(model, nm, e, what, ind):
    """A path constraint's or residual's expression in internal symbols; on a
    constrained model, of the independent states and the inputs only."""
    out = nm.expr(e, what)
    if model.mc or model.mv:
        x = list(model.q) + list(model.u)
        dep = [model.state_names[i] for i, s in enumerate(x)
               if i not in ind and s in out.free_symbols]
        if dep:
            raise _err(f"{what} = {e} holds {_names(dep)}, a dependent coordinate or speed of "
                       f"the constrained model {model.name!r}: write it in the independent "
                       f"state ({_names(model.independent_state_names)}) and the inputs", what)
    return out


def _path(model, nm, path, ind, penalty):
    exprs, lo, hi, soft = [], [], [], []
    for j, item in enumerate(path or []):
        try:
            e, a, b = item
        except (TypeError, ValueError):
            raise _err(f"path[{j}] must be (expr, lo, hi), got {item!r}", "path") from None
        ex = _expression(model, nm, e, f"path[{j}]", ind)
        a, b = float(a), float(b)
        if math.isnan(a) or math.isnan(b) or a > b:
            raise _err(f"path[{j}] = ({e}, {a}, {b}): need lo <= hi", "path", (a, b))
        x = set(model.q) | set(model.u)
        exprs.append(ex)
        lo.append(a)
        hi.append(b)
        # soft where it holds a state (a measured state may violate it)
        soft.append(penalty if ex.free_symbols & x else 0.0)
    return exprs, lo, hi, soft


def _residuals(model, nm, residuals, ind):
    if residuals is None:
        return [], []
    items = residuals.items() if isinstance(residuals, dict) else residuals
    exprs, W = [], []
    for j, item in enumerate(items):
        try:
            e, w = item
            w = float(w)
        except (TypeError, ValueError):
            raise _err(f"residuals[{j}] must be (expr, weight), got {item!r}",
                       "residuals") from None
        if not (w >= 0 and math.isfinite(w)):
            raise _err(f"residuals[{j}]: the weight of {e} must be >= 0, got {w!r}",
                       "residuals", w)
        exprs.append(_expression(model, nm, e, f"residuals[{j}]", ind))
        W.append(w)
    return exprs, W


def read_problem(model, horizon, period, Q, R, P, bounds, path, substeps, method, max_iter,
                 time_limit, residuals=None, penalty=1e3):
    """The arguments of gen.MPC as a Problem (the reference aside:
    reference.py); InputError naming the first bad one."""
    if model.nr == 0:
        raise _err(f"model {model.name!r} has no inputs to control", "model")
    N = _positive_int(horizon, "horizon")
    try:
        period = float(period)
    except (TypeError, ValueError):
        raise _err(f"period must be a number, got {period!r}", "period", period) from None
    if not (math.isfinite(period) and period > 0):
        raise _err(f"period must be a positive number, got {period!r}", "period", period)
    substeps = _positive_int(substeps, "substeps")
    if method not in METHODS:
        raise _err(f"method must be one of {', '.join(map(repr, METHODS))}, got {method!r}",
                   "method", method)
    max_iter = _positive_int(max_iter, "max_iter")
    if method == "rti" and max_iter != 1:
        raise _err(f"max_iter = {max_iter} applies to method='sqp' (method='rti' does one "
                   "iteration per call)", "max_iter", max_iter)
    if time_limit is None:
        time_limit = 0.0
    else:
        try:
            time_limit = float(time_limit)
        except (TypeError, ValueError):
            raise _err(f"time_limit must be seconds or None, got {time_limit!r}",
                       "time_limit") from None
        if not (math.isfinite(time_limit) and time_limit > 0):
            raise _err(f"time_limit must be a positive number of seconds, got {time_limit!r}",
                       "time_limit", time_limit)
    try:
        penalty = float(penalty)
    except (TypeError, ValueError):
        raise _err(f"penalty must be a number, got {penalty!r}", "penalty") from None
    ind = list(model.q_ind) + [model.nq + j for j in model.u_ind]
    ns, labels = len(ind), list(model.independent_state_names)
    Qm = _weight(Q, ns, "Q", labels, definite=False)
    Rm = _weight(R, model.nr, "R", list(model.input_names), definite=True)
    Pm = None if P is None else _weight(P, ns, "P", labels, definite=False)
    nm = Names(model)
    idxbx, lbx, ubx, idxbu, lbu, ubu = _bounds(model, nm, bounds, ind, penalty)
    pe, lh, uh, soft = _path(model, nm, path, ind, penalty)
    re, W = _residuals(model, nm, residuals, ind)
    if any(soft) and not (penalty > 0 and math.isfinite(penalty)):
        raise _err(f"penalty must be a positive number (the L1 weight of the soft path "
                   f"constraints), got {penalty!r}", "penalty", penalty)
    return Problem(N, period, substeps, method, max_iter, time_limit, ind, Qm, Rm, Pm,
                   idxbx, lbx, ubx, idxbu, lbu, ubu, pe, lh, uh, soft, re, W)


def constants(model, p):
    """The model's constants: its defaults, or p (an array of np values or a
    dict {constant: value})."""
    vals = np.array(model.p_values, dtype=float)
    if p is None:
        return vals
    if isinstance(p, dict):
        nm = Names(model)
        for k, v in p.items():
            kind, i = nm.key(k, "gen.MPC: p")
            if kind != "p":
                raise _err(f"p: {k} is not a constant of model {model.name!r}", "p")
            vals[i] = float(v)
    else:
        a = np.asarray(p, dtype=float).reshape(-1)
        if a.shape != vals.shape:
            raise _err(f"p must have {len(vals)} values ({_names(model.constant_names)}), got "
                       f"shape {np.shape(p)}", "p")
        vals = a
    if not np.all(np.isfinite(vals)):
        i = int(np.argwhere(~np.isfinite(vals))[0][0])
        raise _err(f"p[{i}] = {vals[i]!r} ({model.constant_names[i]}): not finite", "p")
    return vals


def sympy_jacobian_rows(exprs, x_ind, r):
    """rows [e, de/dx_ind, de/dr] of expressions, as one sympy Matrix"""
    rows = [[e] + [sm.diff(e, s) for s in x_ind] + [sm.diff(e, s) for s in r] for e in exprs]
    return sm.Matrix(rows)
