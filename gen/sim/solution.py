"""What ``sim.simulate`` returns: a :class:`Solution`, like SciPy's
``OdeResult``, that also unpacks as ``t, x = sim.simulate(...)`` (like
python-control's responses)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Solution", "Event"]


class Event(NamedTuple):
    """An event found during a run: its name, time and state (also unpacks
    as ``name, t, x = event``)."""
    name: str
    t: float
    x: np.ndarray


class JumpEvent(Event):
    """A hybrid event (an impact, a reset or a contact's lift-off,
    ``hybrid={...}``): also ``x_after``, the state after the jump. Unpacks
    as ``name, t, x = event`` like every Event."""

    def __new__(cls, name, t, x, x_after):
        self = super().__new__(cls, name, t, x)
        self.x_after = x_after
        return self


class Solution:
    """The result of :meth:`gen.sim.simulator.Simulator.simulate`.

    Unpacks as ``t, x = sol`` (``sol[0]``, ``sol[1]``), so
    ``t, X = sim.simulate(x0, t_end, dt)`` reads as before.

    Attributes
    ----------
    t : numpy.ndarray, shape (rows,)
        The output times.
    x : numpy.ndarray, shape (rows, nx)
        The states (layout: ``sim.state_names``).
    r : numpy.ndarray, shape (rows, nr)
        The inputs in effect from each output time on (constant inputs, a
        table's, a callable's or a controller's).
    lam : numpy.ndarray, shape (rows, mv)
        The multipliers of the velocity constraints (no columns for a model
        without velocity constraints).
    events : list of gen.Event
        The crossings found (``events=``), each with ``name``, ``t``, ``x``;
        with ``hybrid={...}`` also every impact, reset and lift-off
        (``"<name>.liftoff"``), as a ``JumpEvent`` that also has ``x_after``,
        the state after the jump.
    status : int
        0: the run reached t_end; 1: a terminal event ended it (as
        ``solve_ivp``'s). A failed run raises instead.
    message : str
        The status in words.
    success : bool
        Always True (a failed run raises a :class:`gen.SolverError`).
    stats : dict
        The integrator's counts: ``n_steps`` (accepted steps), ``n_rejected``,
        ``n_rhs`` (right-hand-side evaluations), ``n_jac`` (Jacobians),
        ``n_out`` (rows written), and with events ``n_events`` and
        ``terminal`` (the name of the event that ended the run, or None).
        ``n_accepted`` is ``n_steps``.
    method : str
        The integrator.
    """

    def __init__(self, sim, t, x, r, lam, p, events, status, message, stats, method):
        self._sim = sim
        self._p = p
        self.t = t
        self.x = x
        self.r = r
        self.lam = lam
        self.events = events
        self.status = status
        self.message = message
        self.success = True
        self.stats = stats
        self.method = method
        self._outputs = None
        self._xdot = None

    # ------------------------------------------------ unpacking: t, x
    def __iter__(self):
        return iter((self.t, self.x))

    def __len__(self):
        return 2

    def __getitem__(self, k):
        return (self.t, self.x)[k]

    # ------------------------------------------------------ outputs
    @property
    def outputs(self):
        """The model's outputs at every row: a dict ``{output name: array of
        shape (rows,)}`` in the order of ``sim.output_names``, evaluated in C
        in one batch call (``outputs_batch``) on first access, with each
        row's inputs; empty for a model without outputs."""
        if self._outputs is None:
            sim = self._sim
            if sim.ny == 0:
                self._outputs = {}
            else:
                Y = sim.outputs_batch(self.t, self.x, r=self.r if sim.nr else None, p=self._p)
                self._outputs = {name: Y[:, k] for k, name in enumerate(sim.output_names)}
        return self._outputs

    # ---------------------------------------------------- the interpolant
    def sol(self, t):
        """The state at time(s) t inside the run: a cubic Hermite interpolant
        over the output rows with the model's x' at each row (evaluated in C
        in one batch call, with the row's inputs), exact at the rows and
        O(dt^4) between them for a smooth solution. With ``every=`` or
        ``final_only=True`` it interpolates the rows kept.

        Parameters
        ----------
        t : float or array_like
            Times in [t[0], t[-1]].

        Returns
        -------
        numpy.ndarray, shape (nx,) or (len(t), nx)

        Raises
        ------
        gen.InputError
            For a time outside the run.
        """
        from ..core.errors import InputError
        ts = np.asarray(t, dtype=float)
        scalar = ts.ndim == 0
        ts = np.atleast_1d(ts)
        T, X = np.asarray(self.t, dtype=float), np.asarray(self.x, dtype=float)
        lo, hi = T[0], T[-1]
        tol = 1e-12 * max(1.0, abs(lo), abs(hi))
        bad = (ts < lo - tol) | (ts > hi + tol) | ~np.isfinite(ts)
        if np.any(bad):
            v = float(ts[np.flatnonzero(bad)[0]])
            raise InputError(f"sol(t): t = {v!r} is outside the run [{lo}, {hi}]", "t", None, v)
        if len(T) == 1:
            out = np.repeat(X[:1], len(ts), axis=0)
            return out[0] if scalar else out
        if self._xdot is None:
            sim = self._sim
            self._xdot = np.asarray(sim.rhs_batch(self.t, self.x,
                                                  r=self.r if sim.nr else None, p=self._p),
                                    dtype=float)
        F = self._xdot
        k = np.clip(np.searchsorted(T, ts, side="right") - 1, 0, len(T) - 2)
        h = T[k + 1] - T[k]
        s = np.where(h > 0, (ts - T[k]) / np.where(h > 0, h, 1.0), 0.0)[:, None]
        h = h[:, None]
        h00 = (1 + 2 * s) * (1 - s) ** 2
        h10 = s * (1 - s) ** 2
        h01 = s * s * (3 - 2 * s)
        h11 = s * s * (s - 1)
        out = h00 * X[k] + h10 * h * F[k] + h01 * X[k + 1] + h11 * h * F[k + 1]
        return out[0] if scalar else out

    def __repr__(self):
        return (f"<gen.Solution {self.method}: {len(self.t)} rows, t = [{self.t[0]:.6g}, "
                f"{self.t[-1]:.6g}], status {self.status}: {self.message}>")
