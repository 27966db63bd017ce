"""A Kalman filter feeding a controller, closed in C by the simulation
engine (gen.sim.inputs.CController): at every sample of the filter's period
the engine calls the filter library's <name>_control, which measures the
simulation's true state through the filter's own measurement kernels plus
seeded Gaussian noise (a splitmix64 generator of the runtime: the same seed,
the same run), predicts with the inputs it applied since the last sample,
updates, and sets the inputs from the estimate: a gen.LinearFeedback (an
LQR, a gain schedule such as a TrajectoryTracker's, with its bounds)
evaluated by the runtime on the estimate, or another controller in C
(anything with ``c_controller(sim)``: an MPC) called on it.

    loop = ekf.feedback(gen.LinearFeedback(K), seed=7)
    sol = sim.simulate(x0, 20.0, 1e-3, controller=loop)
    loop.t, loop.x, loop.sd      # the estimates at the samples

No Python runs in the loop. Each simulate restarts the loop from the
filter's state when the loop was made (x, P, t) and the seed.
"""
from __future__ import annotations

import numpy as np

from ...core.errors import InputError
from ...sim.inputs import CController, LinearFeedback

__all__ = ["EstimatorFeedback"]


class EstimatorFeedback:
    """The filter ``kf`` (gen.EKF or gen.UKF) feeding ``law``, for
    ``sim.simulate(..., controller=loop)``.

    Parameters
    ----------
    kf : gen.EKF or gen.UKF
        The filter; its state now is the loop's start (its time the
        simulation's first sample).
    law : gen.LinearFeedback or object with ``c_controller(sim)``
        The controller fed with the estimate: a linear feedback on the
        model's independent state (its own period is not used: the loop
        samples at the filter's period), or a controller in C called with
        the estimate as its state.
    seed : int, optional
        The measurement noise's seed.
    noise : array_like, shape (nz,), optional
        The measurement noise's standard deviations (None: sqrt(R), the
        filter's own model of its sensors).
    theta : array_like, shape (ne,), optional
        The true values of the estimated constants, which the plant's
        measurements use (None: the model's values, or p's).
    log : int, optional
        The samples whose estimates are kept (t, x, sd).

    Attributes
    ----------
    t, x, sd : numpy.ndarray
        After a run: the sample times, the estimates (filter state) and
        their standard deviations, for the first ``log`` samples;
        ``n_samples`` (a property, below) counts the last run's samples.
    """

    def __init__(self, kf, law, *, seed=0, noise=None, theta=None, log=10000):
        self.kf = kf
        if not (isinstance(law, LinearFeedback) or hasattr(law, "c_controller")):
            raise TypeError(f"law must be a gen.LinearFeedback or a controller in C (an object "
                            f"with c_controller(sim)), got {type(law).__name__}")
        self.law = law
        if not (isinstance(seed, (int, np.integer)) and 0 <= seed < 2 ** 64):
            raise InputError(f"seed must be an integer in [0, 2**64), got {seed!r}", "seed",
                             None, seed)
        self.seed = int(seed)
        nz, ne = kf.nz, kf.ne
        sd = np.sqrt(kf.R) if noise is None else np.asarray(noise, dtype=float).ravel()
        if sd.shape != (nz,) or not np.all(np.isfinite(sd)) or np.any(sd < 0):
            raise InputError(f"noise must be {nz} standard deviations >= 0 "
                             f"[{', '.join(kf.measurement_names)}], got {noise!r}", "noise")
        th = kf._theta_nominal if theta is None else np.asarray(theta, dtype=float).ravel()
        if th.shape != (ne,) or not np.all(np.isfinite(th)):
            raise InputError(f"theta must be the true values of the {ne} estimated constant(s) "
                             f"{kf._fm.estimate}, got {theta!r}", "theta")
        self.noise, self.theta = sd, th
        if not (isinstance(log, (int, np.integer)) and log >= 0):
            raise InputError(f"log must be a number of samples >= 0, got {log!r}", "log")
        self.capacity = int(log)
        ws = kf._ws
        # the filter's state now: where every run starts
        self._start = {k: getattr(ws, k).copy() for k in ("x", "P", "Q", "R", "p")}
        self._start["t"] = kf.t
        self._ws = kf._new_workspace()
        self._log = [np.zeros(max(1, self.capacity)), np.zeros((max(1, self.capacity), kf.n)),
                     np.zeros((max(1, self.capacity), kf.n))]
        self._keep = []

    def __repr__(self):
        return (f"<EstimatorFeedback: gen.{self.kf.kind} of '{self.kf.model.name}' feeding "
                f"{type(self.law).__name__}, seed {self.seed}>")

    def _law_arrays(self, sim):
        """The LinearFeedback as arrays on the filter's model: K with zero
        columns for the estimated constants, x_op with their values."""
        kf, fm = self.kf, self.kf._fm
        K, x_op, r_op = self.law.arrays(sim)
        lo, hi = self.law.bounds(sim)
        niq, ne, nq = sim.nq - sim.mc, kf.ne, sim.nq
        K = np.concatenate([K[..., :niq], np.zeros(K.shape[:-1] + (ne,)), K[..., niq:]], axis=-1)
        th = np.broadcast_to(self.theta, x_op.shape[:-1] + (ne,))
        x_op = np.concatenate([x_op[..., :nq], th, x_op[..., nq:]], axis=-1)
        assert K.shape[-1] == fm.model.ns
        n_gain = K.shape[0] if K.ndim == 3 else 0
        step = self.law.dt_gain if self.law.dt_gain is not None else self.law.period
        return (K, x_op, r_op, lo, hi, n_gain, float(self.law.t_gain),
                float(step) if n_gain else 0.0)

    def c_controller(self, sim):
        """The loop for the engine (gen.sim.inputs.CController): the
        filter restarted from the loop's start, the generator seeded."""
        kf = self.kf
        m = kf.model
        if (sim.nx, sim.nr, list(sim.state_names)) != (m.nx, m.nr, list(m.state_names)):
            raise InputError(f"the simulator '{sim.name}' is not the filter's model "
                             f"'{m.name}' (states {sim.state_names} vs {m.state_names})", "sim")
        if np.dtype(sim.dtype) != np.float64:
            raise InputError("the filter's loop runs in double: compile the model with "
                             "real='double'", "sim")
        ws, ffi = self._ws, kf._ffi
        for k in ("x", "P", "Q", "R", "p"):
            getattr(ws, k)[:] = self._start[k]
        ws.scalars["t"][0] = self._start["t"]
        kf._write_settings(ws)
        ws.theta[:] = self.theta
        ws.noise_sd[:] = self.noise
        kf._check(ws.fn("start")(ws.ptr), "start (the loop)")
        ptr = lambda a: ffi.cast("double *", a.ctypes.data) if a is not None else ffi.NULL  # noqa
        self._keep = []
        if isinstance(self.law, LinearFeedback):
            K, x_op, r_op, lo, hi, n_gain, t_gain, dt_gain = self._law_arrays(sim)
            arrays = [np.ascontiguousarray(a, dtype=float) if a is not None else None
                      for a in (K, x_op, r_op, lo, hi)]
            self._keep += arrays
            st = ws.fn("law")(ws.ptr, *[ptr(a) for a in arrays], n_gain, t_gain, dt_gain)
        else:
            inner = self.law.c_controller(sim)
            if not isinstance(inner, CController):
                raise TypeError(f"{type(self.law).__name__}.c_controller must return a "
                                "gen.sim.inputs.CController")
            self._keep.append(inner)
            st = ws.fn("inner")(ws.ptr, inner.function, ffi.cast("void *", inner.context))
        kf._check(st, "feedback")
        st = ws.fn("loop")(ws.ptr, self.seed, self.capacity, *[ptr(a) for a in self._log])
        kf._check(st, "feedback")
        fn = int(ffi.cast("uintptr_t", ffi.addressof(kf._lib, f"{kf.name}_control")))
        return CController(fn, int(ffi.cast("uintptr_t", ws.ptr)), self, kf.period)

    def _rows(self):
        return min(int(self._ws.count[0]), self.capacity)

    @property
    def n_samples(self):
        """The samples of the last run."""
        return int(self._ws.count[0])

    @property
    def t(self):
        """The logged samples' times."""
        return self._log[0][:self._rows()].copy()

    @property
    def x(self):
        """The estimates (the filter state) at the logged samples."""
        return self._log[1][:self._rows()].copy()

    @property
    def sd(self):
        """Their standard deviations."""
        return self._log[2][:self._rows()].copy()

    @property
    def estimate(self):
        """The loop's filter state now (after a run: at the last sample)."""
        return self._ws.xf.copy()

    @property
    def covariance(self):
        """The loop's covariance now (after a run: at the last sample)."""
        return self._ws.P.reshape(self.kf.n, self.kf.n).copy()
