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
        self._jump_xdot = None

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

        A hybrid model's run (``hybrid={...}``) is interpolated piece by
        piece: never across an impact, a reset or a lift-off. Each piece
        runs from the state after a jump (its ``x_after``, with x' there)
        to the state before the next (its ``x``), through the rows between
        them. At a jump's time it gives the state after it (the state before
        is the event's ``x`` in :attr:`events`). While a contact is held
        (between ``"<name>.hold"`` and ``"<name>.liftoff"``) the slopes are
        the rows' finite differences (O(dt^2); exact at rest), since the
        model's x' is the free motion's.

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
        jumps = [e for e in self.events if isinstance(e, JumpEvent)]
        if len(T) == 1 and not jumps:
            out = np.repeat(X[:1], len(ts), axis=0)
            return out[0] if scalar else out
        F = self._row_slopes()
        if not jumps:
            out = _hermite(T, X, F, ts)
            return out[0] if scalar else out
        te = np.array([e.t for e in jumps])
        seg = np.searchsorted(te, ts, side="right")   # the jumps at or before each t
        out = np.empty((len(ts), X.shape[1]))
        for s in np.unique(seg):
            Tk, Xk, Fk = self._piece(int(s), jumps, te, T, X, F)
            sel = seg == s
            out[sel] = _hermite(Tk, Xk, Fk, np.clip(ts[sel], Tk[0], Tk[-1]))
        return out[0] if scalar else out

    def _row_slopes(self):
        """x' at every row (one batch call in C, cached)."""
        if self._xdot is None:
            sim = self._sim
            self._xdot = np.asarray(sim.rhs_batch(self.t, self.x,
                                                  r=self.r if sim.nr else None, p=self._p),
                                    dtype=float)
        return self._xdot

    def _jump_slopes(self, jumps):
        """x' before and after every jump ((m, nx) each, cached), with the
        inputs of the row before it."""
        if self._jump_xdot is None:
            sim, T = self._sim, np.asarray(self.t, dtype=float)
            te = np.array([e.t for e in jumps])
            xb = np.array([e.x for e in jumps], dtype=float)
            xa = np.array([e.x_after for e in jumps], dtype=float)
            r = None
            if sim.nr:
                k = np.clip(np.searchsorted(T, te, side="right") - 1, 0, len(T) - 1)
                r = np.asarray(self.r, dtype=float)[k]
            fb = sim.rhs_batch(te, xb, r=r, p=self._p)
            fa = sim.rhs_batch(te, xa, r=r, p=self._p)
            self._jump_xdot = (np.asarray(fb, dtype=float), np.asarray(fa, dtype=float))
        return self._jump_xdot

    def _piece(self, s, jumps, te, T, X, F):
        """The knots (times, states, slopes) of piece s: from the state
        after jump s-1 (or the first row) to the state before jump s (or
        the last row), through the rows strictly between."""
        fb, fa = self._jump_slopes(jumps)
        m = len(jumps)
        a = T[0] if s == 0 else te[s - 1]
        b = T[-1] if s == m else te[s]
        eps = 64 * np.finfo(float).eps
        inside = (T > a + eps * max(1.0, abs(a))) & (T < b - eps * max(1.0, abs(b)))
        Tk = [T[0] if s == 0 else a, *T[inside], T[-1] if s == m else b]
        Xk = [X[0] if s == 0 else jumps[s - 1].x_after, *X[inside],
              X[-1] if s == m else jumps[s].x]
        Fk = [F[0] if s == 0 else fa[s - 1], *F[inside], F[-1] if s == m else fb[s]]
        Tk, Xk, Fk = np.array(Tk), np.array(Xk, dtype=float), np.array(Fk, dtype=float)
        if _held(jumps, s):
            Fk = _fd_slopes(Tk, Xk)
        return Tk, Xk, Fk

    def __repr__(self):
        return (f"<gen.Solution {self.method}: {len(self.t)} rows, t = [{self.t[0]:.6g}, "
                f"{self.t[-1]:.6g}], status {self.status}: {self.message}>")


def _hermite(T, X, F, ts):
    """The cubic Hermite interpolant through (T, X) with slopes F at ts."""
    if len(T) == 1:
        return np.repeat(X[:1], len(ts), axis=0)
    k = np.clip(np.searchsorted(T, ts, side="right") - 1, 0, len(T) - 2)
    h = T[k + 1] - T[k]
    s = np.where(h > 0, (ts - T[k]) / np.where(h > 0, h, 1.0), 0.0)[:, None]
    h = h[:, None]
    h00 = (1 + 2 * s) * (1 - s) ** 2
    h10 = s * (1 - s) ** 2
    h01 = s * s * (3 - 2 * s)
    h11 = s * s * (s - 1)
    return h00 * X[k] + h10 * h * F[k] + h01 * X[k + 1] + h11 * h * F[k + 1]


def _held(jumps, s):
    """Whether a contact is held during piece s (after jumps 0..s-1): from
    its "<name>.hold" to its "<name>.liftoff"."""
    held = set()
    for e in jumps[:s]:
        base, _, what = e.name.rpartition(".")
        if what == "hold":
            held.add(base)
        elif what == "liftoff":
            held.discard(base)
    return bool(held)


def _fd_slopes(T, X):
    """The slopes of a piece from its knots: three-point differences inside
    (unequal steps), one-sided at the ends; zero for a piece of one knot or
    of no length."""
    n = len(T)
    F = np.zeros_like(X)
    if n < 2 or T[-1] <= T[0]:
        return F
    d = np.diff(T)
    safe = np.where(d > 0, d, 1.0)[:, None]
    D = np.where(d[:, None] > 0, np.diff(X, axis=0) / safe, 0.0)
    F[0], F[-1] = D[0], D[-1]
    if n > 2:
        h0, h1 = d[:-1, None], d[1:, None]
        w = np.where(h0 + h1 > 0, h0 + h1, 1.0)
        F[1:-1] = (h1 * D[:-1] + h0 * D[1:]) / w
    return F
