"""gen.EKF and gen.UKF: Kalman filters over a model's own discrete step,
run in C (gen_rt_kalman.c) from Python, in a closed loop inside the engine,
in a standalone program and on a microcontroller.

    ekf = gen.EKF(model, {"x_m": x, "th_m": theta}, 0.01, Q, R, x0, P0)
    ekf.step(z, r)              # predict with r over the period, update with z
    ekf.x, ekf.P                # the estimate (the filter state) and its covariance
    ekf.innovations, ekf.status # the last update's, one per measurement
    res = ekf.filter(t, Z, R_inputs)      # a recording in one C call
    loop = ekf.feedback(gen.LinearFeedback(K), seed=1)
    sim.simulate(x0, 20.0, 1e-3, controller=loop)   # measure, filter, control: in C

The filter state is the model's independent state [q_ind, u_ind] (the
state of ``sim.linearize``), then the estimated constants: ``state_names``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ... import pipeline
from ...codegen.backends.estimator import LAYOUT
from ...core.errors import BuildError, InputError, SolverError
from ...core.resources import csrc_file
from ...core.status import exception_for, status_message, status_name
from ...toolchain.host import host_module, host_object
from .model import filter_model

__all__ = ["EKF", "UKF", "FilterResult", "KALMAN_CONSTANTS", "ACCEPTED", "GATED", "MISSING",
           "DEGENERATE"]


def _read_constants():
    """The #define GEN_RT_KALMAN_* integers of gen_rt_kalman.h (the one
    source of the kinds and statuses)."""
    text = csrc_file("gen_rt_kalman.h").read_text()
    return {m.group(1): int(m.group(2))
            for m in re.finditer(r"#define GEN_RT_KALMAN_(\w+) (-?\d+)\b", text)}


KALMAN_CONSTANTS = _read_constants()
ACCEPTED, GATED, MISSING, DEGENERATE = (KALMAN_CONSTANTS[k] for k in
                                        ("ACCEPTED", "GATED", "MISSING", "DEGENERATE"))


@dataclass
class FilterResult:
    """A recording filtered (:meth:`EKF.filter`): per row, the estimate
    ``x`` (N, ns + ne) and its covariance ``P`` (N, n, n), the model's full
    state ``x_full`` (N, nx), the innovations (N, nz) and the statuses
    (N, nz; ``gen.design.estimator.ACCEPTED``, ``GATED``, ``MISSING``,
    ``DEGENERATE``)."""
    t: np.ndarray
    x: np.ndarray
    P: np.ndarray
    x_full: np.ndarray
    innovations: np.ndarray
    status: np.ndarray

    @property
    def sd(self):
        """The standard deviations of the estimate, (N, n)."""
        return np.sqrt(np.maximum(np.diagonal(self.P, axis1=1, axis2=2), 0.0))


class _Workspace:
    """A filter's workspace (the library's <name>_workspace) in a numpy
    buffer, with views of its fields at the offsets the library reports."""

    def __init__(self, ffi, lib, name):
        self.ffi, self.lib, self.name = ffi, lib, name
        out = ffi.new("long[]", len(LAYOUT) + 1)
        st = getattr(lib, f"{name}_layout")(out, len(LAYOUT) + 1)
        if st:
            raise RuntimeError(f"{name}_layout: status {st}")
        off = dict(zip(LAYOUT, list(out)))
        self.buf = np.zeros((off["size"] + 15) // 8, dtype=np.float64)
        self.ptr = ffi.cast("void *", self.buf.ctypes.data)
        st = getattr(lib, f"{name}_init")(self.ptr)
        if st:
            raise RuntimeError(f"{name}_init: status {st}")
        self.off = off
        self.bytes = self.buf.view(np.uint8)

    def view(self, field, n, dtype=np.float64):
        o = self.off[field]
        return self.bytes[o:o + n * np.dtype(dtype).itemsize].view(dtype)

    def fn(self, verb):
        return getattr(self.lib, f"{self.name}_{verb}")


def _declined(*args):
    """The fast path where the host module has none: always the general path."""
    return None


def _fast_call(ffi, fn, owner, bufs):
    """The host module's CPython fast path of a workspace call fn(ws, a[, b])
    of the filter's library (csrc/host/gen_host_fast.c): f(a[, b]) copies
    each argument into its buffer (bufs: (array, size) pairs, in the call's
    order) when it is an exact C-contiguous float64 array of the size and
    returns fn's status, else None; it keeps owner (the workspace, which
    holds the buffers) alive. :func:`_declined` where the host has none."""
    try:
        host = host_module("double")
    except BuildError:
        return _declined
    make = getattr(host.lib, "eomgen_fast_call_new", None)
    if make is None:
        return _declined
    hffi = host.ffi
    args = []
    for buf, n in list(bufs) + [(None, 0)] * (2 - len(bufs)):
        args += [hffi.NULL if buf is None else hffi.cast("double *", buf.ctypes.data), n]
    ptr = make(int(ffi.cast("uintptr_t", fn)), hffi.cast("void *", id(owner)),
               hffi.cast("void *", owner.buf.ctypes.data), len(bufs), *args)
    f = host_object(host, ptr)
    return _declined if f is None else f


def _matrix(what, a, n, diag_only=False):
    """A covariance from an (n, n) matrix or the (n,) vector of its
    diagonal: finite, symmetric, positive semidefinite (diag_only: diagonal
    too); InputError naming it."""
    a = np.asarray(a, dtype=float)
    if a.ndim == 1 or a.ndim == 0:
        a = np.diag(np.broadcast_to(a, (n,)).astype(float))
    if a.shape != (n, n):
        raise InputError(f"{what} must be ({n}, {n}) or its diagonal ({n},), got shape "
                         f"{np.shape(a)}", what)
    if not np.all(np.isfinite(a)):
        raise InputError(f"{what} holds NaN or infinity", what)
    if diag_only and np.any(a - np.diag(np.diag(a))):
        raise InputError(f"{what} must be diagonal (the measurements are fused one at a time "
                         "as scalars, each with its own variance)", what)
    if np.max(np.abs(a - a.T), initial=0.0) > 1e-12 * max(1.0, np.max(np.abs(a))):
        raise InputError(f"{what} is not symmetric", what)
    w = np.linalg.eigvalsh(0.5 * (a + a.T)) if n else np.zeros(0)
    if n and w[0] < -1e-12 * max(1.0, np.max(np.abs(w))):
        raise InputError(f"{what} is not positive semidefinite (its smallest eigenvalue is "
                         f"{w[0]:.3g})", what, None, float(w[0]))
    return 0.5 * (a + a.T)


class EKF:
    """The extended Kalman filter of a model, in C.

    Prediction through the model's own RK4 step and its exact sensitivity
    (``F = dx1_ind/dx_ind``, the generated Jacobian kernels through the
    step's variational equations), ``P = F P F^T + Q`` kept symmetric;
    update with the measurements one at a time as scalars (no matrix
    inverse), in the Joseph form, each behind a chi-squared innovation gate.
    Constrained models: the filter runs on the independent state and the
    estimate stays on the constraint manifold.

    Parameters
    ----------
    model : gen.Model
        The model.
    measurements : dict or list
        ``{name: sympy expression}`` in the model's states, inputs,
        constants and time, or names of the model's outputs (a value that
        is a string, or a list of names). ``z`` vectors follow this order.
    period : float
        The time of one prediction (> 0).
    Q : array_like, shape (n, n) or (n,)
        The process noise covariance added at each prediction, on the
        filter state (n = ns + the number of estimated constants):
        symmetric positive semidefinite, or its diagonal.
    R : array_like, shape (nz,) or (nz, nz)
        The measurement variances, a vector or a diagonal matrix (>= 0).
    x0 : array_like, shape (nx + ne,)
        The initial estimate: the model's full state x = [q, u] (on its
        constraints; for an unconstrained model nx = ns), then the initial
        values of the estimated constants.
    P0 : array_like, shape (n, n) or (n,)
        The initial covariance of the filter state.
    estimate : list, optional
        Constants to estimate (sympy symbols or names) as random-walk
        states appended to the filter state (their variance per step is
        their entry of Q).
    method : {"rk4"}, optional
        The step (its exact sensitivity is RK4's).
    substeps : int, optional
        RK4 steps per period (F is their product).
    gate : float or None, optional
        The innovation gate in standard deviations: a measurement with
        ``y^2 > gate^2 S`` is not fused (status GATED; a chi-squared test
        with one degree of freedom, 25: p = 5.7e-7). None: no gate.
    p : dict or array_like, optional
        The other constants (None: the model's values).
    t0 : float, optional
        The time of x0.
    name : str, optional
        The library's C prefix (default ``<model>_kf``).

    Attributes
    ----------
    x, P : numpy.ndarray
        The estimate (n,) and its covariance (n, n).
    innovations, innovation_variances, status : numpy.ndarray
        The last update's, one per measurement (status: ACCEPTED 0, GATED 1,
        MISSING 2, DEGENERATE 3).
    state_names, measurement_names : list of str
        The names of the filter's states and of the measurements. The full
        state ``x_full``, the estimated ``params``, the time ``t`` and the
        ``rejected`` counts are properties, documented below.

    Raises
    ------
    gen.InputError
        On bad input, named in the model's terms before anything is built: Q,
        R or P0 not symmetric positive semidefinite (R not diagonal), a
        measurement naming a symbol the model does not know or an output it
        does not have, ``estimate`` naming a state, an input or an unknown
        name, x0 of the wrong length or not finite, a period, substeps, gate
        or method out of range.
    gen.BuildError
        When the filter's library does not compile.
    """
    kind = "EKF"

    def __init__(self, model, measurements, period, Q, R, x0, P0, estimate=None, method="rk4",
                 substeps=1, *, gate=5.0, p=None, t0=0.0, name=None):
        self._settings(period, method, substeps, gate)
        fm = filter_model(model, measurements, estimate=estimate, name=name)
        self._fm = fm
        self.model = model
        self.name = fm.plan_name
        self.state_names = list(fm.state_names)
        self.measurement_names = list(fm.z_names)
        self.n, self.nz, self.ne = fm.ns, fm.nz, fm.ne
        self.nx, self.nr = model.nx, model.nr
        # every argument checked before the library is built
        Q, R = _matrix("Q", Q, self.n), _matrix("R", R, self.nz, diag_only=True)
        P0, x0 = _matrix("P0", P0, self.n), self._full_state(x0)
        self._p = self._constants(p)
        self._check_kind()
        if not np.isfinite(t0):
            raise InputError(f"t0 must be finite, got {t0!r}", "t0", None, t0)
        self.built, self._ffi, self._lib = pipeline.product(fm.plan, "estimator")
        self._ws = self._new_workspace()
        self._bind_calls()
        self._ws.Q[:], self._ws.R[:] = Q.ravel(), np.diag(R)
        self._ws.x[:], self._ws.P[:] = x0, P0.ravel()
        self.reset(t0=t0)

    # ----------------------------------------------------------- settings
    def _check_kind(self):
        """The kind's own checks, once the filter's sizes are known (before
        the build)."""

    def _settings(self, period, method, substeps, gate):
        if method != "rk4":
            raise InputError(f"method must be 'rk4' (the filter's prediction is RK4's step and "
                             f"its exact sensitivity), got {method!r}", "method", None, method)
        if not (isinstance(period, (int, float, np.floating, np.integer))
                and np.isfinite(period) and period > 0):
            raise InputError(f"period must be a number > 0, got {period!r}", "period", None,
                             period)
        if not (isinstance(substeps, (int, np.integer)) and substeps >= 1):
            raise InputError(f"substeps must be an integer >= 1, got {substeps!r}", "substeps",
                             None, substeps)
        if gate is not None and not (np.isfinite(gate) and gate > 0):
            raise InputError(f"gate must be a number of standard deviations > 0 or None, got "
                             f"{gate!r}", "gate", None, gate)
        self.period, self.substeps, self.gate = float(period), int(substeps), gate

    def _new_workspace(self):
        ws = _Workspace(self._ffi, self._lib, self.name)
        n, nz, nxf = self.n, self.nz, self._fm.model.nx
        ws.x, ws.xf = ws.view("x", nxf), ws.view("xf", n)
        ws.P, ws.Q, ws.R = ws.view("P", n * n), ws.view("Q", n * n), ws.view("R", nz)
        ws.p, ws.r = ws.view("params", self._fm.model.np), ws.view("inputs", self.nr)
        ws.y, ws.S = ws.view("y", nz), ws.view("S", nz)
        ws.status, ws.rejected = ws.view("status", nz, np.intc), ws.view("rejected", nz, np.int_)
        ws.scalars = {k: ws.view(k, 1) for k in ("t", "period", "gate", "alpha", "beta",
                                                 "kappa")}
        ws.ints = {k: ws.view(k, 1, np.intc) for k in ("kind", "substeps")}
        ws.theta, ws.noise_sd = ws.view("theta", self.ne), ws.view("noise_sd", nz)
        ws.count = ws.view("count", 1, np.int_)
        ws.counts = {k: ws.view(k, 1, np.int_) for k in ("n_predict", "n_update")}
        ws.rbuf = np.zeros(max(1, self.nr))
        ws.zbuf = np.zeros(max(1, nz))
        c = self._ffi.cast
        ws.rptr = c("double *", ws.rbuf.ctypes.data)
        ws.zptr = c("double *", ws.zbuf.ctypes.data)
        ws.f_predict, ws.f_update, ws.f_step = ws.fn("predict"), ws.fn("update"), ws.fn("step")
        return ws

    def _bind_calls(self):
        """predict, update and step's fast paths, bound to the filter's
        workspace: the host module's CPython functions (_fast_call), which
        take an exact float64 array of the size, copy it into the
        workspace's buffer and call the library's function; None for any
        other argument (the general path then, as without them)."""
        ws, ffi = self._ws, self._ffi
        self._fast_predict = _fast_call(ffi, ws.f_predict, ws, [(ws.rbuf, self.nr)])
        self._fast_update = _fast_call(ffi, ws.f_update, ws, [(ws.zbuf, self.nz)])
        self._fast_step = _fast_call(ffi, ws.f_step, ws, [(ws.zbuf, self.nz),
                                                          (ws.rbuf, self.nr)])

    def _write_settings(self, ws):
        ws.scalars["period"][0] = self.period
        ws.scalars["gate"][0] = 0.0 if self.gate is None else float(self.gate)
        ws.ints["kind"][0] = KALMAN_CONSTANTS[self.kind]
        ws.ints["substeps"][0] = self.substeps
        for k in ("alpha", "beta", "kappa"):
            ws.scalars[k][0] = getattr(self, k, ws.scalars[k][0])

    def _constants(self, p):
        """The filter model's constants: the user's (p or the model's values)
        without the estimated ones."""
        m = self.model
        vals = np.array(m.p_values, dtype=float)
        if isinstance(p, dict):
            for k, v in p.items():
                key = str(k)
                if key not in m.constant_names and key not in m.constant_labels:
                    raise InputError(f"p: {k} is not a constant of the model '{m.name}'", "p",
                                     None, key)
                i = (m.constant_names.index(key) if key in m.constant_names
                     else m.constant_labels.index(key))
                vals[i] = float(v)
        elif p is not None:
            vals = np.asarray(p, dtype=float).ravel()
            if vals.shape != (m.np,):
                raise InputError(f"p must hold the model's {m.np} constants "
                                 f"({', '.join(m.constant_labels)}), got shape {np.shape(p)}",
                                 "p")
        if not np.all(np.isfinite(vals)):
            raise InputError("p holds NaN or infinity", "p")
        keep = [i for i in range(m.np) if i not in self._fm.estimate_index]
        self._theta_nominal = vals[self._fm.estimate_index]
        return vals[keep]

    @property
    def Q(self):
        """The process noise covariance per period (n, n)."""
        return self._ws.Q.reshape(self.n, self.n).copy()

    @Q.setter
    def Q(self, Q):
        self._ws.Q[:] = _matrix("Q", Q, self.n).ravel()

    @property
    def R(self):
        """The measurement variances (nz,)."""
        return self._ws.R.copy()

    @R.setter
    def R(self, R):
        self._ws.R[:] = np.diag(_matrix("R", R, self.nz, diag_only=True))

    def reset(self, x0=None, P0=None, t0=None):
        """Restart the filter; the statuses and counts cleared.

        Parameters
        ----------
        x0 : array_like, shape (nx + ne,), optional
            The estimate (as the constructor's; None: as it is).
        P0 : array_like, shape (n, n) or (n,), optional
            Its covariance (None: as it is).
        t0 : float, optional
            Its time (None: as it is).

        Raises
        ------
        gen.InputError
            On a wrong shape or value (named).
        gen.SolverError
            When the dependent entries of x0 cannot be completed.
        """
        ws = self._ws
        x = None if x0 is None else self._full_state(x0)
        P = None if P0 is None else _matrix("P0", P0, self.n).ravel()
        if t0 is not None and not np.isfinite(t0):
            raise InputError(f"t0 must be finite, got {t0!r}", "t0", None, t0)
        if x is not None:
            ws.x[:] = x
        if P is not None:
            ws.P[:] = P
        if t0 is not None:
            ws.scalars["t"][0] = float(t0)
        ws.p[:] = self._p
        self._write_settings(ws)
        self._check(ws.fn("start")(ws.ptr), "start")

    def _full_state(self, x0):
        """The filter model's full state [q, constants, u] of x0 = [q, u,
        constants] (the user's layout)."""
        m, ne = self.model, self.ne
        x0 = np.asarray(x0, dtype=float).ravel()
        if x0.shape != (m.nx + ne,):
            what = f"the state [{', '.join(m.state_labels)}]" + (
                f" then the estimated constants [{', '.join(self._fm.estimate)}]" if ne else "")
            raise InputError(f"x0 must be {what}: {m.nx + ne} values, got shape "
                             f"{np.shape(x0)}", "x0")
        bad = np.nonzero(~np.isfinite(x0))[0]
        if len(bad):
            i = int(bad[0])
            raise InputError(f"x0[{i}] = {x0[i]!r}: every entry must be finite", "x0", i,
                             float(x0[i]))
        return np.concatenate([x0[:m.nq], x0[m.nx:], x0[m.nq:m.nx]])

    # --------------------------------------------------------------- calls
    def _check(self, st, what):
        if st:
            name = status_name(st)
            exc = exception_for(name)
            msg = f"{self.kind}.{what} at t = {self.t!r}: {status_message(st)} ({name})"
            if issubclass(exc, SolverError):
                raise exc(msg, status=st, status_name=name, time=self.t, state=self.x)
            raise exc(msg)

    def _inputs(self, r):
        ws = self._ws
        if type(r) is np.ndarray and r.shape == ws.rbuf.shape and self.nr:
            ws.rbuf[:] = r          # the common case, fast (NaN: the C call's InputError)
            return
        if self.nr == 0:
            if r is not None and np.size(r):
                raise InputError(f"the model '{self.model.name}' has no inputs; r must be None",
                                 "r")
            return
        if r is None:
            raise InputError(f"r: give the inputs [{', '.join(self.model.input_labels)}] "
                             "held over the period", "r")
        a = np.asarray(r, dtype=float).ravel()
        if a.shape != (self.nr,):
            raise InputError(f"r must hold {self.nr} input(s) "
                             f"[{', '.join(self.model.input_labels)}], got shape {np.shape(r)}",
                             "r")
        self._ws.rbuf[:] = a

    def _measurements(self, z):
        ws = self._ws
        if type(z) is np.ndarray and z.shape == ws.zbuf.shape:
            ws.zbuf[:] = z
            return
        a = np.asarray(z, dtype=float).ravel()
        if a.shape != (self.nz,):
            raise InputError(f"z must hold the {self.nz} measurement(s) "
                             f"[{', '.join(self.measurement_names)}], got shape {np.shape(z)}",
                             "z")
        self._ws.zbuf[:] = a

    def predict(self, r=None):
        """One prediction over the period with the inputs r held.

        Parameters
        ----------
        r : array_like, shape (nr,)
            The inputs (None when the model has none).

        Raises
        ------
        gen.InputError
            On a wrong shape, or a NaN or infinite input.
        gen.SolverError
            When the model's step fails (a singular configuration, a
            diverged state): the estimate is left as it was.
        """
        st = self._fast_predict(r)
        if st is None:              # r is not an exact float64 (nr,) array
            self._inputs(r)
            ws = self._ws
            st = ws.f_predict(ws.ptr, ws.rptr)
        if st:
            self._predict_failed(st)

    def _predict_failed(self, st):
        ws = self._ws
        if not np.all(np.isfinite(ws.rbuf)):
            raise InputError(f"r = {ws.rbuf[:self.nr].tolist()} "
                             f"[{', '.join(self.model.input_labels)}]: every entry must be "
                             "finite", "r")
        self._check(st, "predict")

    def update(self, z):
        """One update with the measurements z (a NaN entry: missing, not
        fused; the estimate unchanged when none is fused).

        Parameters
        ----------
        z : array_like, shape (nz,)
            In the order of ``measurement_names``.

        Raises
        ------
        gen.InputError
            On a wrong shape.
        gen.SolverError
            When the measurement kernels or the constraints fail there.
        """
        st = self._fast_update(z)
        if st is None:              # z is not an exact float64 (nz,) array
            self._measurements(z)
            ws = self._ws
            st = ws.f_update(ws.ptr, ws.zptr)
        if st:
            self._check(st, "update")

    def step(self, z, r=None):
        """``predict(r)`` then ``update(z)``: one period of the filter, in one
        C call.

        Parameters
        ----------
        z : array_like, shape (nz,)
            The measurements at the end of the period.
        r : array_like, shape (nr,)
            The inputs held over it.
        """
        st = self._fast_step(z, r)
        if st is None:
            self._inputs(r)
            self._measurements(z)
            ws = self._ws
            st = ws.f_step(ws.ptr, ws.zptr, ws.rptr)
        if st:
            self._check(st, "step")

    def filter(self, t, Z, R_inputs=None):
        """Filter a recording in one C call: row 0 updates at the current
        time with Z[0]; row k > 0 predicts with R_inputs[k - 1] and updates
        with Z[k].

        Parameters
        ----------
        t : array_like, shape (N,)
            The rows' times: ``self.t + k period``.
        Z : array_like, shape (N, nz)
            The measurements (NaN: missing).
        R_inputs : array_like, shape (N, nr) or (N - 1, nr), optional
            The inputs applied from each row's time to the next (None when
            the model has none).

        Returns
        -------
        FilterResult

        Raises
        ------
        gen.InputError
            On times that are not the filter's samples, or wrong shapes.
        gen.SolverError
            When a row fails (the filter stops there; the message names the row).
        """
        t, Z, Rin = self._recording(t, Z, R_inputs)
        N, n, nz, ffi = len(t), self.n, self.nz, self._ffi
        X = np.zeros((N, n))
        Xf = np.zeros((N, self._fm.model.nx))
        P = np.zeros((N, n, n))
        Y = np.zeros((N, max(1, nz)))
        S = np.zeros((N, max(1, nz)), dtype=np.intc)
        done = ffi.new("int *")
        ptr = lambda a, ty="double *": ffi.cast(ty, a.ctypes.data)  # noqa: E731
        st = self._ws.fn("run")(self._ws.ptr, N, ptr(Z), ptr(Rin), ptr(X), ptr(Xf), ptr(P),
                                ptr(Y), ptr(S, "int *"), done)
        self._check(st, f"filter (row {done[0]})")
        return FilterResult(t, X, P, self._user_full(Xf), Y[:, :nz], S[:, :nz].astype(int))

    def _recording(self, t, Z, R_inputs):
        t = np.asarray(t, dtype=float).ravel()
        N = len(t)
        if N < 1 or not np.all(np.isfinite(t)):
            raise InputError("t must be the rows' times, finite, at least one", "t")
        want = self.t + self.period * np.arange(N)
        tol = 1e-9 * max(1.0, float(np.max(np.abs(want))))
        bad = np.nonzero(np.abs(t - want) > tol)[0]
        if len(bad):
            k = int(bad[0])
            raise InputError(f"t[{k}] = {float(t[k])!r}: the rows must be the filter's samples "
                             f"t = {self.t!r} + k * {self.period!r} (row 0 at the estimate's "
                             "time)", "t", k, float(t[k]))
        Z = np.ascontiguousarray(np.asarray(Z, dtype=float).reshape(N, -1)
                                 if np.size(Z) == N * self.nz else np.asarray(Z, dtype=float))
        if Z.shape != (N, self.nz):
            raise InputError(f"Z must be (N, nz) = ({N}, {self.nz}) "
                             f"[{', '.join(self.measurement_names)}], got {np.shape(Z)}", "Z")
        nr = self.nr
        if nr == 0:
            Rin = np.zeros((max(N, 1), 1))
        else:
            if R_inputs is None:
                raise InputError("R_inputs: give the inputs of each row", "R_inputs")
            Rin = np.asarray(R_inputs, dtype=float)
            if Rin.ndim == 1 and nr == 1:
                Rin = Rin[:, None]
            if Rin.ndim != 2 or Rin.shape[1] != nr or Rin.shape[0] not in (N, N - 1):
                raise InputError(f"R_inputs must be (N, nr) or (N - 1, nr) with nr = {nr}, "
                                 f"got {np.shape(R_inputs)}", "R_inputs")
            if not np.all(np.isfinite(Rin)):
                raise InputError("R_inputs holds NaN or infinity", "R_inputs")
            Rin = np.ascontiguousarray(Rin)
            if len(Rin) == 0:
                Rin = np.zeros((1, nr))
        return t, Z, Rin

    def _user_full(self, Xf):
        """Full states of the filter's model -> the user's layout [q, u]."""
        m, ne = self.model, self.ne
        return np.concatenate([Xf[..., :m.nq], Xf[..., m.nq + ne:]], axis=-1)

    # ------------------------------------------------------------ reading
    @property
    def x(self):
        """The estimate: the filter state (n,)."""
        return self._ws.xf.copy()

    @property
    def P(self):
        """Its covariance (n, n)."""
        return self._ws.P.reshape(self.n, self.n).copy()

    @property
    def x_full(self):
        """The model's full state (nx,) at the estimate."""
        return self._user_full(self._ws.x)

    @property
    def params(self):
        """The estimated constants' values, by name."""
        m = self._fm.model
        return {nm: float(self._ws.x[m.nq - self.ne + i])
                for i, nm in enumerate(self._fm.estimate)}

    @property
    def t(self):
        """The estimate's time."""
        return float(self._ws.scalars["t"][0])

    @property
    def innovations(self):
        """The last update's innovations (NaN: a missing measurement)."""
        return self._ws.y.copy()

    @property
    def innovation_variances(self):
        """Their variances S."""
        return self._ws.S.copy()

    @property
    def status(self):
        """The last update's status of each measurement (ACCEPTED 0, GATED
        1, MISSING 2, DEGENERATE 3)."""
        return self._ws.status.astype(int)

    @property
    def rejected(self):
        """Measurements not fused so far (gated, missing, degenerate), per
        measurement."""
        return self._ws.rejected.astype(int)

    def __repr__(self):
        return (f"<gen.{self.kind} of '{self.model.name}': state [{', '.join(self.state_names)}]"
                f", measurements [{', '.join(self.measurement_names)}], period {self.period}, "
                f"t = {self.t}>")

    # ------------------------------------------------- the loop, firmware
    def feedback(self, law, *, seed=0, noise=None, theta=None, log=10000):
        """The filter feeding a controller, closed in C by ``sim.simulate``
        (:class:`gen.design.estimator.loop.EstimatorFeedback`): at every
        sample the simulation's true state measured through the filter's
        kernels plus seeded noise, predict, update, the law on the estimate.

        Parameters
        ----------
        law : gen.LinearFeedback or object with ``c_controller(sim)``
            The controller fed with the estimate.
        seed : int, optional
            The measurement noise's seed (the same seed, the same run).
        noise : array_like, shape (nz,), optional
            The noise's standard deviations (None: sqrt(R)).
        theta : array_like, shape (ne,), optional
            The estimated constants' true values (None: the model's).
        log : int, optional
            The samples whose estimates are kept.

        Returns
        -------
        gen.design.estimator.loop.EstimatorFeedback
            Pass it as ``controller=`` to ``sim.simulate``.
        """
        from .loop import EstimatorFeedback
        return EstimatorFeedback(self, law, seed=seed, noise=noise, theta=theta, log=log)

    def to_c(self, path, real="double"):
        """Write the filter as a firmware module and a standalone program,
        with its values now (estimate, covariance, time, noise, settings) as
        ``<name>_defaults`` (:func:`gen.design.estimator.firmware.to_c`; the
        C prefix is the filter's ``name``).

        Parameters
        ----------
        path : str or Path
            A folder (created, written atomically).
        real : {"double", "float"}, optional
            The scalar type.

        Returns
        -------
        list of Path
            The files written.
        """
        from .firmware import to_c
        return to_c(self, path, real=real)

    def footprint(self, real="float", target="cortex-m4f", build_dir=None):
        """The firmware module cross-built for a Cortex-M4F and measured
        (:func:`gen.design.estimator.firmware.footprint`; arm-none-eabi-gcc).

        Parameters
        ----------
        real : {"float", "double"}, optional
            The scalar type.
        target : {"cortex-m4f"}, optional
            The target.
        build_dir : str or Path, optional
            Where to build (None: a temporary folder).

        Returns
        -------
        dict
            ``flash``, ``ram``, ``workspace`` (bytes), ``stack`` (worst case
            per function), ``heap`` (none), ``libc``, ``table``.
        """
        from .firmware import footprint
        return footprint(self, real=real, target=target, build_dir=build_dir)


class UKF(EKF):
    """The unscented Kalman filter of a model, in C: van der Merwe's scaled
    sigma points (alpha, beta, kappa as filterpy names them), propagated
    through the model's RK4 step, each measurement gated on its own variance
    and the accepted ones fused together (Cholesky, no inverse).

    Parameters
    ----------
    model, measurements, period, Q, R, x0, P0, estimate, method, substeps
        As :class:`EKF`.
    alpha, beta, kappa : float, optional
        The sigma points' spread (> 0), the prior's kurtosis (2: Gaussian)
        and the secondary scaling (ns + kappa > 0).
    gate, p, t0, name
        As :class:`EKF`.

    Raises
    ------
    gen.InputError
        As :class:`EKF`, and alpha not > 0, kappa with ns + kappa <= 0.
    """
    kind = "UKF"

    def __init__(self, model, measurements, period, Q, R, x0, P0, estimate=None, method="rk4",
                 substeps=1, alpha=1e-3, beta=2.0, kappa=0.0, *, gate=5.0, p=None, t0=0.0,
                 name=None):
        for k, v in (("alpha", alpha), ("beta", beta), ("kappa", kappa)):
            if not np.isfinite(v):
                raise InputError(f"{k} must be finite, got {v!r}", k, None, v)
        if not alpha > 0:
            raise InputError(f"alpha must be > 0, got {alpha!r}", "alpha", None, alpha)
        self.alpha, self.beta, self.kappa = float(alpha), float(beta), float(kappa)
        super().__init__(model, measurements, period, Q, R, x0, P0, estimate, method, substeps,
                         gate=gate, p=p, t0=t0, name=name)

    def _check_kind(self):
        if not self.n + self.kappa > 0:
            raise InputError(f"kappa must make ns + kappa > 0 (ns = {self.n}), got "
                             f"{self.kappa!r}", "kappa", None, self.kappa)
