"""An MPC's reference: constant, a table over time, or a trajectory such as
a gen.OptimalSolution, as the uniform table the C reads (rows every period
from t_ref, linear between rows, the ends held).

    reference=None                     zero states and inputs
    reference=(x, u)                   a constant full state (nx) and inputs (nr)
    reference=(t, X, U)                a table: times (M,), full states (M, nx),
                                       inputs (M, nr), linear between its rows
    reference=sol                      a trajectory with .t, sol(t) and sol.input(t)
                                       (gen.OptimalSolution), sampled every period
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.errors import InputError

__all__ = ["Reference", "read_reference"]


@dataclass
class Reference:
    """The table: full states x (n, nx) and inputs u (n, nr) at t0 + k dt."""
    t0: float
    dt: float
    x: np.ndarray
    u: np.ndarray

    def at(self, t):
        """(x, u) at time t, as the C reads the table."""
        n = len(self.x)
        s = (t - self.t0) / self.dt
        if n == 1 or s <= 0:
            return self.x[0], self.u[0]
        if s >= n - 1:
            return self.x[-1], self.u[-1]
        i = int(s)
        f = s - i
        return ((1 - f) * self.x[i] + f * self.x[i + 1], (1 - f) * self.u[i] + f * self.u[i + 1])


def _err(msg):
    return InputError(f"gen.MPC: {msg}", "reference", None, None)


def _finite(a, what, labels):
    if not np.all(np.isfinite(a)):
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        raise _err(f"{what}[{', '.join(map(str, idx))}] = {float(a[idx])!r} "
                   f"({labels[idx[-1]]}): the reference must be finite")


def _states(model, x, rows):
    nx = model.nx
    x = np.asarray(x, dtype=float)
    want = (nx,) if rows is None else (rows, nx)
    if x.shape != want:
        shape = "(nx,)" if rows is None else "(len(t), nx)"
        raise _err(f"the reference states must have shape {shape} = {want} (the full state "
                   f"{', '.join(model.state_names)}), got {x.shape}")
    _finite(x, "reference x", model.state_names)
    return x


def _inputs(model, u, rows):
    nr = model.nr
    u = np.asarray(u, dtype=float)
    if rows is None and u.ndim == 0 and nr == 1:
        u = u.reshape(1)
    if rows is not None and u.ndim == 1 and nr == 1:
        u = u[:, None]
    want = (nr,) if rows is None else (rows, nr)
    if u.shape != want:
        shape = "(nr,)" if rows is None else "(len(t), nr)"
        raise _err(f"the reference inputs must have shape {shape} = {want} (the inputs "
                   f"{', '.join(model.input_names)}), got {u.shape}")
    _finite(u, "reference u", model.input_names)
    return u


def _grid(t0, t1, period):
    k = max(0, int(math.ceil((t1 - t0) / period * (1 - 1e-12))))
    return t0 + period * np.arange(k + 1)


def read_reference(model, reference, period):
    """The Reference of gen.MPC's reference argument; InputError naming a
    wrong shape or value."""
    if reference is None:
        return Reference(0.0, period, np.zeros((1, model.nx)), np.zeros((1, model.nr)))
    if hasattr(reference, "input") and callable(reference) and hasattr(reference, "t"):
        t = np.asarray(reference.t, dtype=float)
        ts = _grid(float(t[0]), float(t[-1]), period)
        ts = np.minimum(ts, t[-1])
        x = np.array([np.asarray(reference(float(s)), dtype=float) for s in ts])
        u = np.array([np.asarray(reference.input(float(s)), dtype=float).reshape(-1) for s in ts])
        return Reference(float(t[0]), period, _states(model, x, len(ts)),
                         _inputs(model, u, len(ts)))
    if not isinstance(reference, (tuple, list)) or len(reference) not in (2, 3):
        raise _err(f"reference must be None, (x, u), (t, x, u) or a trajectory such as a "
                   f"gen.OptimalSolution, got {type(reference).__name__}")
    if len(reference) == 2:
        x, u = reference
        return Reference(0.0, period, _states(model, x, None)[None, :],
                         _inputs(model, u, None)[None, :])
    t, x, u = reference
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or len(t) < 1:
        raise _err(f"the reference times must be a 1-D array of at least one value, got shape "
                   f"{t.shape}")
    if not np.all(np.isfinite(t)):
        raise _err("the reference times must be finite")
    bad = np.nonzero(np.diff(t) <= 0)[0]
    if len(bad):
        i = int(bad[0])
        raise _err(f"the reference times must increase, but t[{i + 1}] = {float(t[i + 1])!r} <= "
                   f"t[{i}] = {float(t[i])!r}")
    x = _states(model, x, len(t))
    u = _inputs(model, u, len(t))
    if len(t) == 1:
        return Reference(float(t[0]), period, x, u)
    ts = _grid(float(t[0]), float(t[-1]), period)
    xs = np.column_stack([np.interp(ts, t, x[:, j]) for j in range(model.nx)])
    us = np.column_stack([np.interp(ts, t, u[:, j]) for j in range(model.nr)])
    return Reference(float(t[0]), period, xs, us)
