"""Tracking a trajectory: a time-varying LQR along a reference, run in C.

    tracker = gen.TrajectoryTracker(sim, t, x, r, Q, R, period)
    sol = sim.simulate(x0, t[-1], dt, controller=tracker)     # in C
    tracker.to_c("out/cart_pole", name="swingup")            # const tables, no heap

The reference is a trajectory of the model: node times ``t`` (N), full
states ``x`` (N, nx) and inputs ``r`` (N, nr), such as an optimal control's
solution (``sol.tracker(Q, R, period)``) or a simulated run. The controller
is digital: it samples the state at ``t0 + k period`` and holds

    r = r_ref(t_k) - K_k (x_ind - x_ref_ind(t_k))

until the next sample, on the independent state ``[q_ind, u_ind]`` of
``sim.linearize``. The gains come from the backward discrete Riccati
recursion on the zero-order-hold discretizations
``Ad_k, Bd_k = sim.linearize(x_ref(t_k), r=r_ref(t_k), dt=period)`` (the
engine's, in C):

    P_M = P_f,   K_k = (R + B'P B)^-1 B'P A,   P_k = Q + A'P (A - B K_k)

with ``P_f`` the discrete algebraic Riccati solution at the trajectory's
end (scipy's ``solve_discrete_are``), or Q where the end is not
stabilizable. After the end the tracker holds the end of the reference with
that terminal gain: an LQR about the end state.

The reference between the nodes: the states by the cubic Hermite
interpolant on the nodes with the model's own slopes ``sim.rhs`` (the
interpolant of Hermite-Simpson collocation, third order), the inputs
linearly (the trapezoidal and Hermite-Simpson transcriptions' controls are
continuous and piecewise linear; at a node both give the node's values
exactly, so a reference sampled at its own nodes is used as it is).

The law is a :class:`gen.LinearFeedback` with a gain schedule (K of shape
(M + 1, nr, ns)), evaluated by the C runtime (``<p>_simulate_input``,
``<p>_eval_input``): the same arithmetic in ``sim.simulate``, in the
standalone binary (``cmake -D<P>_TRACKER=<name>``) and on a
microcontroller (:meth:`TrajectoryTracker.to_c`).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..core.errors import InputError
from ..core.optional import require
from ..sim.inputs import LinearFeedback

__all__ = ["TrajectoryTracker"]


def _names(names):
    return ", ".join(names)


class TrajectoryTracker(LinearFeedback):
    """A time-varying LQR along a reference trajectory, sampled every period.

    Parameters
    ----------
    sim : gen.sim.simulator.Simulator
        The model the tracker closes.
    t : array_like, shape (N,)
        The reference's node times, strictly increasing (N >= 2).
    x : array_like, shape (N, nx)
        The full states at the nodes.
    r : array_like, shape (N, nr)
        The inputs at the nodes.
    Q : array_like, shape (ns, ns)
        The state weight on the independent state (symmetric positive
        semidefinite).
    R : array_like, shape (nr, nr)
        The input weight (symmetric positive definite).
    period : float
        The controller's sample period (> 0, at most the trajectory's length).
    p : array_like or dict, optional
        The constants of the linearizations (None: the model's defaults).
    r_min, r_max : array_like, shape (nr,), optional
        Bounds the tracker's inputs are clipped to (an actuator's limits;
        None: none, -inf / inf entries: unbounded). The gains do not know
        them: a reference that rides a bound leaves the tracker no margin.

    Attributes
    ----------
    t_samples : numpy.ndarray, shape (M,)
        The sample times ``t[0] + k period`` of the recursion.
    K : numpy.ndarray, shape (M + 1, nr, ns)
        The gains: row k at t_samples[k], row M the terminal gain (held
        after the end).
    x_op, r_op : numpy.ndarray, shape (M + 1, nx), (M + 1, nr)
        The reference at the samples, then its end.
    Ad, Bd : numpy.ndarray, shape (M + 1, ns, ns), (M + 1, ns, nr)
        The discretizations the gains came from (row M at the end).
    P : numpy.ndarray, shape (M + 1, ns, ns)
        The cost-to-go matrices (P[M] the terminal cost).
    terminal : str
        ``"dare"`` or ``"Q"``: where the terminal cost came from.
    """

    def __init__(self, sim, t, x, r, Q, R, period, p=None, *, r_min=None, r_max=None):
        t, x, r, Q, R, period = _check(sim, t, x, r, Q, R, period)
        LinearFeedback(np.zeros((sim.nr, sim.ns)), r_min=r_min, r_max=r_max).bounds(sim)
        self.sim = sim
        self.p = p
        self.t_ref, self.x_ref, self.r_ref = t, x, r
        self.Q, self.R = Q, R
        span = t[-1] - t[0]
        M = max(1, int(math.ceil(span / period * (1 - 1e-12))))
        ts = t[0] + np.arange(M) * period
        xs, rs = self.reference(ts)
        ns, nr = sim.ns, sim.nr
        Ad = np.empty((M + 1, ns, ns))
        Bd = np.empty((M + 1, ns, nr))
        for k in range(M):
            Ad[k], Bd[k] = sim.linearize(xs[k], r=rs[k], p=p, t=float(ts[k]), dt=period)
        Ad[M], Bd[M] = sim.linearize(x[-1], r=r[-1], p=p, t=float(t[-1]), dt=period)
        Pf, self.terminal = _terminal_cost(Ad[M], Bd[M], Q, R)
        K = np.empty((M + 1, nr, ns))
        P = np.empty((M + 1, ns, ns))
        P[M] = Pf
        K[M] = _gain(Ad[M], Bd[M], Pf, R)
        Pk = Pf
        for k in range(M - 1, -1, -1):
            A, B = Ad[k], Bd[k]
            K[k] = _gain(A, B, Pk, R)
            Pk = Q + A.T @ Pk @ (A - B @ K[k])
            Pk = 0.5 * (Pk + Pk.T)
            P[k] = Pk
        self.t_samples = ts
        self.Ad, self.Bd, self.P = Ad, Bd, P
        LinearFeedback.__init__(self, K=K, x_op=np.vstack([xs, x[-1]]),
                                r_op=np.vstack([rs, r[-1]]), period=period,
                                t_gain=float(t[0]), dt_gain=period, r_min=r_min, r_max=r_max)

    def __repr__(self):
        return (f"<gen.TrajectoryTracker of '{self.sim.name}': {len(self.t_samples)} samples "
                f"every {self.period} from t = {self.t_gain}, terminal cost {self.terminal}>")

    # the LinearFeedback dataclass's eq compares arrays; a tracker is an object
    __eq__ = object.__eq__
    __hash__ = object.__hash__

    def __reduce__(self):
        # pickled (an ensemble's workers) as its law: the LinearFeedback of its
        # tables, without the Simulator it was built from
        return (LinearFeedback, (self.K, self.x_op, self.r_op, self.period, self.t_gain,
                                 self.dt_gain, self.r_min, self.r_max))

    def reference(self, ts):
        """The reference at times ts: states by the cubic Hermite interpolant
        on the nodes with the slopes ``sim.rhs(t_i, x_i, r=r_i)`` (the
        dependent coordinates and speeds then solved from the independent
        ones, on a constrained model), inputs linear; the nodes' own values
        at the nodes, the ends held outside.

        Parameters
        ----------
        ts : array_like
            The times.

        Returns
        -------
        x : numpy.ndarray, shape (len(ts), nx)
        r : numpy.ndarray, shape (len(ts), nr)
        """
        sim, t, x, r = self.sim, self.t_ref, self.x_ref, self.r_ref
        if not hasattr(self, "_slopes"):
            self._slopes = np.array([sim.rhs(float(ti), xi, r=ri, p=self.p)
                                     for ti, xi, ri in zip(t, x, r)])
        f = self._slopes
        ts = np.atleast_1d(np.asarray(ts, dtype=float))
        xs = np.empty((len(ts), sim.nx))
        rs = np.empty((len(ts), sim.nr))
        tol = 1e-12 * max(1.0, abs(t[-1]), abs(t[0]))
        for j, tj in enumerate(ts):
            i = int(np.searchsorted(t, tj + tol, side="right")) - 1
            if i < 0:
                xs[j], rs[j] = x[0], r[0]
            elif i >= len(t) - 1 or abs(tj - t[i]) <= tol:
                i = min(i, len(t) - 1)
                xs[j], rs[j] = x[i], r[i]
            else:
                h = t[i + 1] - t[i]
                s = (tj - t[i]) / h
                h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
                h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
                xs[j] = h00 * x[i] + h10 * h * f[i] + h01 * x[i + 1] + h11 * h * f[i + 1]
                rs[j] = (1 - s) * r[i] + s * r[i + 1]
                if sim.mc or sim.mv:
                    # the dependent entries back on the constraints
                    xs[j] = sim.consistent_state(xs[j], p=self.p, t=float(tj))
        return xs, rs

    # ------------------------------------------------------------ C source
    def footprint(self, real=None):
        """The size of the tracker's const tables.

        Parameters
        ----------
        real : {"double", "float"}, optional
            The scalar type (None: the model's).

        Returns
        -------
        dict
            ``rows``; bytes of ``K``, ``x_ref``, ``r_ref`` and their sum
            ``flash``; ``ram`` 0 (the tables are const; the controller's
            state is the caller's input struct).
        """
        real = real or self.sim.real
        size = 8 if real == "double" else 4
        n = self.n_gain
        k, xr, rr = (n * self.sim.nr * self.sim.ns, n * self.sim.nx, n * self.sim.nr)
        nb = self.sim.nr * ((self.r_min is not None) + (self.r_max is not None))
        return {"rows": n, "K": k * size, "x_ref": xr * size, "r_ref": rr * size,
                "bounds": nb * size, "flash": (k + xr + rr + nb) * size, "ram": 0}

    def sources(self, name="tracker", real=None):
        """The tracker's C source and header, as text (see :meth:`to_c`).

        Parameters
        ----------
        name : str, optional
            The C prefix of the tracker's symbols and files.
        real : {"double", "float"}, optional
            The scalar type (None: the model's).

        Returns
        -------
        dict
            ``{"<name>.h": text, "<name>.c": text}``.

        Raises
        ------
        gen.InputError
            On a name that is not a C identifier, a C keyword, or the model's
            own; on an unknown real.
        """
        from ..codegen.render import render
        from ..core.names import validate_name
        try:
            validate_name(name)
        except Exception as e:
            raise InputError(f"tracker name {name!r}: {e}", "name", None, name) from None
        real = real or self.sim.real
        if real not in ("double", "float"):
            raise InputError(f"real must be 'double' or 'float', got {real!r}", "real", None,
                             real)
        if name == self.sim.name:
            raise InputError(f"the tracker's name {name!r} is the model's: its files would "
                             "replace the model's", "name", None, name)
        return render(self._plan(name, real), real=real, backend="tracker").files

    def _plan(self, name, real):
        """The tracker as the tracker backend's ProductPlan
        (gen/codegen/backends/ TrackerBackend): its tables and what its C
        says of them, rendered through gen.codegen.render.render."""
        from ..codegen.product_abi import ProductPlan
        sim = self.sim
        K, x_op, r_op = self.arrays(sim)
        lo, hi = self.bounds(sim)
        return ProductPlan(name, names={"p": sim.name}, data={
            "model": sim.name, "n_gain": self.n_gain, "t0": float(self.t_gain),
            "period": float(self.period), "terminal": self.terminal,
            "ind_names": list(sim.independent_state_names), "K": K, "x_op": x_op,
            "r_op": r_op, "r_min": lo, "r_max": hi, "ns": sim.ns, "nx": sim.nx, "nr": sim.nr,
            "footprint": self.footprint(real or sim.real)})

    def to_c(self, path, name="tracker", real=None):
        """Write the tracker as C: ``<name>.h`` and ``<name>.c`` with the
        trajectory and the gains as ``static const`` tables and

        - ``void <name>_input(<p>_input *in)``: fills an input description
          with the tracker, for ``<p>_simulate_input``;
        - ``int <name>_step(<p>_real t, const <p>_real *x, <p>_real *r)``:
          the inputs at a sample time t from the state x (the runtime's
          ``<p>_eval_input``): call it every period and hold r.

        No heap, no global that is written. Compile it with the model's
        sources (``gen.generate(model, path)``); the standalone binary runs
        the tracker when built with ``-D<P>_TRACKER=<name>`` (CMake:
        ``cmake -D<P>_TRACKER=<name>``).

        Parameters
        ----------
        path : str or Path
            A folder (usually the model's generated one); created.
        name : str, optional
            The C prefix of the tracker's symbols and files.
        real : {"double", "float"}, optional
            The scalar type (None: the model's); it must be the model build's.

        Returns
        -------
        list of Path
        """
        from ..codegen.render import write_atomic
        return write_atomic(self.sources(name, real), Path(path))


def _gain(A, B, P, R):
    BtP = B.T @ P
    return np.linalg.solve(R + BtP @ B, BtP @ A)


def _terminal_cost(A, B, Q, R):
    """The DARE's solution at the end, or Q where it has none (the end not
    stabilizable, or Q not detectable)."""
    solve_discrete_are = require("scipy.linalg", "gen.TrajectoryTracker").solve_discrete_are
    try:
        with np.errstate(all="ignore"):
            P = solve_discrete_are(A, B, Q, R)
        if np.all(np.isfinite(P)):
            # a stabilizing solution: the closed loop's spectral radius < 1
            K = _gain(A, B, P, R)
            if np.max(np.abs(np.linalg.eigvals(A - B @ K))) < 1:
                return 0.5 * (P + P.T), "dare"
    except (ValueError, np.linalg.LinAlgError):
        pass
    return np.array(Q), "Q"


def finite_or_raise(name, a, labels=None):
    """InputError naming the first NaN or infinite entry: ``x[3, 1] = nan
    (node 3, theta)``."""
    a = np.asarray(a)
    if a.size and not np.all(np.isfinite(a)):
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        where = ", ".join(map(str, idx))
        what = ([f"node {idx[0]}"] if a.ndim == 2 and labels is not None else []) + \
            ([labels[idx[-1]]] if labels is not None else [])
        label = f" ({', '.join(what)})" if what else ""
        raise InputError(f"TrajectoryTracker: {name}[{where}] = {float(a[idx])!r}{label}: every "
                         f"entry of {name} must be finite", name, None, float(a[idx]))


def _check(sim, t, x, r, Q, R, period):
    """The arguments as float arrays; InputError naming the argument, the
    expected shape in the model's names, and the value otherwise."""
    nx, nr, ns = sim.nx, sim.nr, sim.ns
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or len(t) < 2:
        raise InputError(f"TrajectoryTracker: t must be the reference's node times, a 1-D array "
                         f"of at least 2 values, got shape {t.shape}", "t", None, None)
    N = len(t)
    finite_or_raise("t", t)
    bad = np.nonzero(np.diff(t) <= 0)[0]
    if len(bad):
        i = int(bad[0])
        raise InputError(f"TrajectoryTracker: t must be strictly increasing, but t[{i + 1}] = "
                         f"{float(t[i + 1])!r} <= t[{i}] = {float(t[i])!r}", "t", i + 1,
                         float(t[i + 1]))
    x = np.asarray(x, dtype=float)
    if x.ndim == 1 and nx == 1:
        x = x[:, None]
    if x.shape != (N, nx):
        raise InputError(f"TrajectoryTracker: x must have shape (len(t), nx) = ({N}, {nx}) "
                         f"(the state {_names(sim.state_names)} at each node), got {x.shape}",
                         "x", None, None)
    finite_or_raise("x", x, sim.state_names)
    r = np.asarray(r, dtype=float)
    if nr == 0:
        raise InputError(f"TrajectoryTracker: model '{sim.name}' has no inputs to track with",
                         "r", None, None)
    if r.ndim == 1 and nr == 1:
        r = r[:, None]
    if r.shape != (N, nr):
        raise InputError(f"TrajectoryTracker: r must have shape (len(t), nr) = ({N}, {nr}) "
                         f"(the inputs {_names(sim.input_names)} at each node), got {r.shape}",
                         "r", None, None)
    finite_or_raise("r", r, sim.input_names)
    ind = _names(sim.independent_state_names)
    Q = np.asarray(Q, dtype=float)
    if Q.ndim == 1 and Q.shape == (ns,):
        Q = np.diag(Q)
    if Q.shape != (ns, ns):
        raise InputError(f"TrajectoryTracker: Q must have shape (ns, ns) = ({ns}, {ns}) (a "
                         f"weight on the independent state {ind}), or ns diagonal values, "
                         f"got {Q.shape}", "Q", None, None)
    finite_or_raise("Q", Q)
    R = np.asarray(R, dtype=float)
    if R.ndim <= 1 and R.size == nr:
        R = np.diag(R.reshape(-1))
    if R.shape != (nr, nr):
        raise InputError(f"TrajectoryTracker: R must have shape (nr, nr) = ({nr}, {nr}) (a "
                         f"weight on the inputs {_names(sim.input_names)}), or nr diagonal "
                         f"values, got {R.shape}", "R", None, None)
    finite_or_raise("R", R)
    for name, W, labels in (("Q", Q, sim.independent_state_names),
                            ("R", R, sim.input_names)):
        asym = np.max(np.abs(W - W.T))
        if asym > 1e-12 * max(1.0, np.max(np.abs(W))):
            i, j = np.unravel_index(np.argmax(np.abs(W - W.T)), W.shape)
            raise InputError(f"TrajectoryTracker: {name} must be symmetric, but "
                             f"{name}[{i}, {j}] = {float(W[i, j])!r} ({labels[i]}, {labels[j]}) "
                             f"!= {name}[{j}, {i}] = {float(W[j, i])!r}", name, None, None)
    eq = np.linalg.eigvalsh(Q)
    if eq[0] < -1e-12 * max(1.0, eq[-1]):
        raise InputError(f"TrajectoryTracker: Q must be positive semidefinite; its smallest "
                         f"eigenvalue is {float(eq[0])!r}", "Q", None, float(eq[0]))
    er = np.linalg.eigvalsh(R)
    if not er[0] > 1e-12 * max(1.0, er[-1]):
        raise InputError(f"TrajectoryTracker: R must be positive definite (a weight on every "
                         f"input {_names(sim.input_names)}); its smallest eigenvalue is "
                         f"{float(er[0])!r}", "R", None, float(er[0]))
    try:
        period = float(period)
    except (TypeError, ValueError):
        raise InputError(f"TrajectoryTracker: period must be a number, got {period!r}",
                         "period", None, period) from None
    span = t[-1] - t[0]
    if not (math.isfinite(period) and period > 0):
        raise InputError(f"TrajectoryTracker: period must be a positive number, got period = "
                         f"{period!r}", "period", None, period)
    if period > span * (1 + 1e-12):
        raise InputError(f"TrajectoryTracker: period = {period!r} is longer than the "
                         f"trajectory (t[-1] - t[0] = {float(span)!r})", "period", None, period)
    return t, x, r, Q, R, period
