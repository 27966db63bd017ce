"""The result of an optimal control problem's solve: the nodes' states and
inputs, IPOPT's outcome, the transcription's interpolant, a replay through
the model's simulator and a tracker along it."""
from __future__ import annotations

import numpy as np

from ...core.errors import InputError

__all__ = ["OptimalSolution"]


class OptimalSolution:
    """The result of :meth:`OptimalControl.solve`.

    Attributes
    ----------
    t : ndarray (N,)       node times (every phase's nodes in order: across events,
                           a phase's last time repeats as the next's first)
    x : ndarray (N, nx)    states at the nodes
    r : ndarray (N, nr)    inputs at the nodes
    p : ndarray            the identified parameters (in ``parameters``' order)
    constants : ndarray    every constant of the model as solved (the model's order):
                           :meth:`replay` and :meth:`tracker` use these, whatever
                           ``ocp.constants`` holds later
    objective : float
    status : int           IPOPT's status (0 solved, 1 acceptable, 2 infeasible, < 0 failed)
    message : str          the status in words
    iterations : int
    first_iterate : (float, float)
                           IPOPT's primal and dual infeasibility at iteration 0
    build_seconds, solve_seconds : float
    success : bool         status 0 or 1
    phases : list          each phase's times ``t``, states ``x``, inputs ``r``, the
                           ``event`` that ends it and ``x_after``, the state after its map

    ``sol(t)`` is the state of the transcription's interpolant at t (linear
    for backward Euler and midpoint, quadratic for trapezoidal, cubic for
    Hermite-Simpson); ``sol.input(t)`` the inputs (linear; quadratic for
    Hermite-Simpson). ``t, x = sol`` unpacks.
    """

    @classmethod
    def _make(cls, ocp, z, obj, status, message, iterations, solve_seconds):
        s = cls()
        lay = ocp._lay
        s._ocp = ocp
        s._z = z
        s._layout_key = ocp._layout_key()
        s.method = ocp.method
        n1, Ts = lay.N, z[lay.Ts]
        N = lay.NN
        # every phase's nodes, in order (a phase's last time is the next's first)
        s._t0 = np.concatenate([[0.0], np.cumsum(Ts)])
        s.t = np.concatenate([s._t0[j] + np.linspace(0.0, Ts[j], n1) for j in range(len(Ts))])
        s._n1 = n1
        T = float(s._t0[-1])
        s.x = np.array([z[X] for X in lay.X])
        s.r = np.array([z[R] for R in lay.R]).reshape(N, ocp.model.nr)
        s.p = z[lay.P].copy()
        # every constant as solved (the known ones then, the identified
        # ones found): replay and tracker use these, not the problem's
        # constants of a later moment
        s.constants = np.array(ocp._p, float)
        s.constants[list(ocp._pf)] = s.p
        s.objective = obj
        s.status = status
        s.message = message
        s.iterations = iterations
        s.first_iterate = (float("nan"), float("nan"))
        s.phases = []
        s.build_seconds = ocp.build_seconds
        s.solve_seconds = solve_seconds
        s.success = status in (0, 1)
        s.duration = T
        nx = ocp.model.nx
        S = np.full((N, nx), np.nan)
        for k, (si, _, _) in lay.node_point.items():
            S[k] = z[si]
        s._S = S
        # the midpoints' slopes, states, inputs by their interval's first node
        s._SM = s._XM = s._RM = None
        if lay.mid_point:
            s._SM = np.full((N - 1, nx), np.nan)
            for k, (si, _, _) in lay.mid_point.items():
                s._SM[k] = z[si]
        if lay.XM:
            s._XM, s._RM = np.full((N - 1, nx), np.nan), np.full((N - 1, ocp.model.nr), np.nan)
            for k, i in lay.mid_index.items():
                s._XM[k], s._RM[k] = z[lay.XM[i]], z[lay.RM[i]]
        return s

    def __iter__(self):
        return iter((self.t, self.x))

    def __repr__(self):
        return (f"OptimalSolution(status={self.status}, objective={self.objective:.10g}, "
                f"iterations={self.iterations}, nodes={len(self.t)}, method={self.method!r})")

    def _locate(self, t):
        """(t, the first node k of t's interval, t - t_k, the interval's
        length h as an array like t): within t's phase (at an event's time,
        the next phase's first interval)."""
        t = np.asarray(t, float)
        n1, t0 = self._n1, self._t0
        ph = np.clip(np.searchsorted(t0, t, side="right") - 1, 0, len(t0) - 2)
        h = (t0[ph + 1] - t0[ph]) / (n1 - 1)
        kl = np.clip(np.floor((t - t0[ph]) / h).astype(int), 0, n1 - 2)
        k = ph * n1 + kl
        tau = t - (t0[ph] + kl * h)
        return t, k, tau, h

    def __call__(self, t):
        """The states at times t (the transcription's interpolant)."""
        t, k, tau, h = self._locate(t)
        X = self.x
        if self.method in ("backward-euler", "midpoint"):
            a = (tau / h)[..., None]
            return X[k] * (1 - a) + X[k + 1] * a
        hh = h[..., None]
        if self.method == "trapezoidal":
            s0, s1 = self._S[k], self._S[k + 1]
            tt = tau[..., None]
            return X[k] + s0 * tt + (s1 - s0) * tt ** 2 / (2 * hh)
        # Hermite-Simpson: the slope is quadratic through s_k, s_m, s_k+1;
        # integrate from x_k
        s0, sm_, s1 = self._S[k], self._SM[k], self._S[k + 1]
        u = (tau / h)[..., None]
        # s(u) = s0 (1-u)(1-2u) + 4 sm u (1-u) + s1 u (2u-1)
        i0 = u - 3 * u ** 2 / 2 + 2 * u ** 3 / 3
        im = 2 * u ** 2 - 4 * u ** 3 / 3
        i1 = -u ** 2 / 2 + 2 * u ** 3 / 3
        return X[k] + hh * (s0 * i0 + sm_ * im + s1 * i1)

    def input(self, t):
        """The inputs at times t: linear between nodes; quadratic through
        the node and midpoint inputs for Hermite-Simpson.

        Parameters
        ----------
        t : float or array_like

        Returns
        -------
        ndarray, shape (..., nr)
        """
        t, k, tau, h = self._locate(t)
        u = (tau / h)[..., None]
        R = self.r
        if self.method == "hermite-simpson":
            rm = self._RM[k]
            return R[k] * (1 - u) * (1 - 2 * u) + 4 * rm * u * (1 - u) + R[k + 1] * u * (2 * u - 1)
        return R[k] * (1 - u) + R[k + 1] * u

    def replay(self, dt=None, method="dopri5", **options):
        """The optimal inputs replayed through the model's simulator
        (``sim.simulate``, the inputs from :meth:`input` at every stage),
        from ``x[0]`` for the whole duration: across several phases the
        simulator makes the model's events itself (compare its ``events``
        with ``phases``).

        Parameters
        ----------
        dt : float, optional
            The output interval (default: the node spacing).
        method : str, optional
            The simulator's method (default "dopri5").
        **options
            More ``simulate`` keywords (``rtol``, ``atol``).

        Returns
        -------
        gen.Solution
            Its final state against ``x[-1]`` measures the transcription's error.
        """
        sim = self._ocp.simulator
        dt = dt or float(self.t[1] - self.t[0])
        return sim.simulate(self.x[0], float(self.t[-1]), dt, r=lambda t, x: self.input(t),
                            p=self.constants.copy(), method=method, input_period=0, **options)

    def tracker(self, Q, R, period):
        """A time-varying LQR along this trajectory (gen.tracking).

        Parameters
        ----------
        Q, R : array_like
            State and input weights.
        period : float
            The sampling period of the discrete Riccati recursion.

        Returns
        -------
        gen.design.tracking.TrajectoryTracker

        Raises
        ------
        gen.InputError
            For a solution of several phases: a tracker follows one phase.
        """
        from ..tracking import TrajectoryTracker
        if len(self.phases) > 1:
            raise InputError(f"tracker: this solution has {len(self.phases)} phases (events "
                             f"{[ph.event for ph in self.phases]}); a tracker follows one "
                             "phase, not a trajectory across events")
        return TrajectoryTracker(self._ocp.simulator, self.t, self.x, self.r, Q, R, period,
                                 p=self.constants.copy())
