"""Closed loops: where a simulation's inputs come from.

``sim.simulate(x0, t_end, dt, r=..., controller=...)`` takes, for r:

- None or an array of NR values: constant inputs;
- a table ``(t_grid, R)`` with R of shape (len(t_grid), NR), held
  (``input_hold="zoh"``) or interpolated (``"linear"``) inside C;
- a Python callable ``r(t, x) -> array``, sampled with a zero-order hold
  once per ``input_period`` (default: the RK4 step dt, or DOPRI5's output
  interval), called from C through a cffi callback;

and for controller a :class:`LinearFeedback`, evaluated inside the
generated C at every stage (period None) or sampled (period Ts), with one
gain or a schedule of gains (a time-varying LQR such as
:class:`gen.TrajectoryTracker`'s), or a controller written in C by a
product's library (a model predictive controller, an estimator feeding a
law): any object with a ``c_controller(sim)`` method that returns a
:class:`CController`, called from the engine with no Python in the loop.

All of them become one ``<p>_input`` description for the C function
``<p>_simulate_input`` (README, "Closed loops").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..codegen.abi import hold_code
from ..core.errors import InputError

__all__ = ["LinearFeedback", "CController", "InputPlan", "plan_inputs"]


@dataclass
class LinearFeedback:
    """A linear state feedback ``r = r_op - K (x_ind - x_op_ind)``, computed in
    the generated C.

    Parameters
    ----------
    K : array_like, shape (nr, ns)
        The gain on the independent state [q_ind, u_ind] (the state of
        ``sim.linearize``).
    x_op : array_like, shape (nx,) or (ns,), optional
        The operating state, full or independent (default zero).
    r_op : array_like, shape (nr,), optional
        The inputs at the operating point (default zero).
    period : float, optional
        None evaluates the law at every stage (a continuous controller);
        Ts > 0 samples it at t0 + k Ts and holds it (a digital one).
    t_gain, dt_gain : float, optional
        A gain schedule: K of shape (n, nr, ns), with x_op (n, nx) or
        (n, ns) and r_op (n, nr) (or one row for all), row k used from
        ``t_gain + k dt_gain`` on (row 0 before, the last row after the
        end); dt_gain defaults to the period. With one gain they are unused.
    r_min, r_max : array_like, shape (nr,), optional
        Bounds the law's inputs are clipped to (None: none; -inf / inf
        entries: unbounded), in C after the feedback.
    """
    K: object
    x_op: object = None
    r_op: object = None
    period: float | None = None
    t_gain: float = 0.0
    dt_gain: float | None = None
    r_min: object = None
    r_max: object = None

    @property
    def n_gain(self):
        """The rows of the gain schedule (0: one gain)."""
        return int(np.shape(self.K)[0]) if np.ndim(self.K) == 3 else 0

    def arrays(self, sim):
        """The gain and operating point as float arrays, checked against a model.

        Parameters
        ----------
        sim : gen.sim.simulator.Simulator
            The model the feedback closes.

        Returns
        -------
        K : numpy.ndarray, shape (nr, ns)
        x_op : numpy.ndarray, shape (nx,)
        r_op : numpy.ndarray, shape (nr,)

        Raises
        ------
        ValueError
            On a wrong shape, NaN or infinity, or a period that is not None or
            positive.
        """
        K = np.asarray(self.K, dtype=float)
        if K.ndim == 1 and sim.nr == 1:
            K = K[None, :]
        n = K.shape[0] if K.ndim == 3 else 0       # a schedule of n gains
        lead = (n,) if n else ()
        if K.shape[-2:] != (sim.nr, sim.ns) or K.ndim not in (2, 3) or (K.ndim == 3 and n < 1):
            raise InputError(f"LinearFeedback: K must have shape (nr, ns) = ({sim.nr}, {sim.ns}) "
                             f"(inputs {sim.input_names} by the independent state "
                             f"{sim.independent_state_names}), or (n, nr, ns) for a schedule "
                             f"of n gains, got {K.shape}")
        if self.x_op is None:
            x_op = np.zeros(lead + (sim.nx,))
        else:
            x = np.asarray(self.x_op, dtype=float)
            x = x.reshape(-1) if not n else (x if x.ndim == 2 else np.broadcast_to(x, (n, x.size)))
            if x.shape == lead + (sim.nx,):
                x_op = np.array(x)
            elif x.shape == lead + (sim.ns,):
                x_op = np.zeros(lead + (sim.nx,))
                idx = list(sim.q_ind) + [sim.nq + i for i in sim.u_ind]
                x_op[..., idx] = x
            else:
                raise InputError(f"LinearFeedback: x_op must have nx = {sim.nx} (the state "
                                 f"{sim.state_names}) or ns = {sim.ns} values"
                                 + (f" in each of the schedule's {n} rows" if n else "")
                                 + f", got {x.shape}")
        if self.r_op is None:
            r_op = np.zeros(lead + (sim.nr,))
        else:
            r_op = np.asarray(self.r_op, dtype=float)
            if not n:
                r_op = r_op.reshape(-1)
            elif r_op.ndim <= 1 and r_op.size == sim.nr:      # one row for all
                r_op = np.tile(r_op.reshape(1, -1), (n, 1))
            elif r_op.ndim == 1 and sim.nr == 1:               # n values of one input
                r_op = r_op[:, None]
        if r_op.shape != lead + (sim.nr,):
            raise InputError(f"LinearFeedback: r_op must have nr = {sim.nr} values "
                             f"({sim.input_names})"
                             + (f" in each of the schedule's {n} rows" if n else "")
                             + f", got {r_op.shape}")
        for name, a in (("K", K), ("x_op", x_op), ("r_op", r_op)):
            if not np.all(np.isfinite(a)):
                raise InputError(f"LinearFeedback: {name} holds NaN or infinity")
        if self.period is not None and not (np.isfinite(self.period) and self.period > 0):
            raise InputError(f"LinearFeedback: period must be None (continuous) or a positive "
                             f"number, got {self.period!r}")
        if n:
            step = self.dt_gain if self.dt_gain is not None else self.period
            if step is None or not (np.isfinite(step) and step > 0):
                raise InputError(f"LinearFeedback: a schedule of {n} gains needs dt_gain > 0 "
                                 f"(or a period), got dt_gain = {self.dt_gain!r}")
            if not np.isfinite(self.t_gain):
                raise InputError(f"LinearFeedback: t_gain must be finite, got {self.t_gain!r}")
        return K, x_op, r_op

    def bounds(self, sim):
        """The input bounds as float arrays, checked against a model.

        Parameters
        ----------
        sim : gen.sim.simulator.Simulator
            The model the feedback closes.

        Returns
        -------
        r_min, r_max : numpy.ndarray or None
            Shape (nr,) each; None where not given.

        Raises
        ------
        gen.InputError
            On a wrong shape, a NaN, or r_min > r_max.
        """
        out = []
        for name, v in (("r_min", self.r_min), ("r_max", self.r_max)):
            if v is None:
                out.append(None)
                continue
            a = np.asarray(v, dtype=float).reshape(-1)
            if a.shape != (sim.nr,):
                raise InputError(f"LinearFeedback: {name} must have nr = {sim.nr} values "
                                 f"({sim.input_names}), got shape {np.shape(v)}", name,
                                 None, None)
            if np.any(np.isnan(a)):
                i = int(np.argmax(np.isnan(a)))
                raise InputError(f"LinearFeedback: {name}[{i}] = nan ({sim.input_names[i]})",
                                 name, i, float(a[i]))
            out.append(a)
        lo, hi = out
        if lo is not None and hi is not None and np.any(lo > hi):
            i = int(np.argmax(lo > hi))
            raise InputError(f"LinearFeedback: r_min[{i}] = {float(lo[i])!r} > r_max[{i}] = "
                             f"{float(hi[i])!r} ({sim.input_names[i]})", "r_min", i,
                             float(lo[i]))
        return lo, hi

    def row(self, t):
        """The schedule's row in effect at a time.

        Parameters
        ----------
        t : float
            The time.

        Returns
        -------
        int
            The last k with ``t_gain + k dt_gain <= t``, within rounding (the
            C runtime's rule); 0 before t_gain and for one gain, the last
            row after the schedule's end.
        """
        n = self.n_gain
        if n <= 1:
            return 0
        step = self.dt_gain if self.dt_gain is not None else self.period
        s = (t - self.t_gain) / step
        if not s > 0:
            return 0
        if s >= n - 1:
            return n - 1
        k = int(s)
        if self.t_gain + (k + 1) * step <= t + 64 * np.finfo(float).eps * max(abs(t), 1.0):
            k += 1
        return min(k, n - 1)

    def __call__(self, sim, t, x):
        """The law in numpy (for checks): r at time t and the full state x."""
        K, x_op, r_op = self.arrays(sim)
        if K.ndim == 3:
            k = self.row(t)
            K, x_op, r_op = K[k], x_op[k], r_op[k]
        idx = list(sim.q_ind) + [sim.nq + i for i in sim.u_ind]
        x = np.asarray(x, dtype=float)
        r = r_op - K @ (x[idx] - x_op[idx])
        lo, hi = self.bounds(sim)
        if lo is not None:
            r = np.maximum(r, lo)
        if hi is not None:
            r = np.minimum(r, hi)
        return r


@dataclass(frozen=True)
class CController:
    """A controller in C, from a product's library: the address of its
    function, of the runtime's type ``gen_rt_controller_fn``
    (``int f(void *ctx, real t, const real *x, real *r)``, r holding the
    inputs of the rest of the description, a nonzero return stops the run
    with ERR_CONTROLLER), the address of the context it is called with, the
    object that keeps both alive for the run, and its sampling period (0:
    every stage; Ts > 0: at t0 + k Ts, held between).

    A product's face (``gen.MPC``, an estimator) returns one from its
    ``c_controller(sim)`` method; ``sim.simulate(..., controller=obj)``
    then closes the loop in C. The function's scalar type must be the
    simulator's (``sim.dtype``)."""
    function: int
    context: int
    owner: object
    period: float = 0.0


class InputPlan:
    """The input struct (<p>_input) and everything it points to, kept alive for the
    duration of one C call. ``error`` holds an exception raised by a Python
    callable (re-raised after the call)."""

    def __init__(self, sim):
        self.sim = sim
        self.keep = []
        self.error = None
        self.struct = sim.library.new("input")

    def array(self, a):
        a = np.ascontiguousarray(a, dtype=self.sim.dtype)
        self.keep.append(a)
        return self.sim.library.array(a)

    def callback(self, fn):
        sim, ffi = self.sim, self.sim.library.ffi
        nx, nr, dtype = sim.nx, sim.nr, sim.dtype
        size = np.dtype(dtype).itemsize

        def cb(ctx, t, x, r):
            try:
                xs = np.frombuffer(ffi.buffer(x, nx * size), dtype=dtype).astype(float)
                val = np.asarray(fn(float(t), xs), dtype=float).ravel()
                if val.shape != (nr,):
                    raise InputError(f"the input function r(t, x) must return nr = {nr} values "
                                     f"({sim.input_names}), got shape {val.shape}")
                if not np.all(np.isfinite(val)):
                    raise InputError(f"the input function r(t, x) returned NaN or infinity at "
                                     f"t = {float(t)}: {val}")
                for i in range(nr):
                    r[i] = val[i]
                return 0
            except BaseException as e:  # re-raised after the C call
                if self.error is None:
                    self.error = e
                return 1

        handle = ffi.callback("eomgen_controller", cb)
        self.keep.append(handle)
        return handle


def plan_inputs(sim, r, controller, dt, method, input_period, input_hold):
    """The InputPlan of simulate's r / controller arguments, or None when
    the inputs are constant (the plain simulate path)."""
    table = isinstance(r, tuple) and len(r) == 2
    if controller is None and not callable(r) and not table:
        if input_period is not None:
            raise InputError("input_period applies to a callable r(t, x); r is constant")
        return None
    try:
        hold = hold_code(input_hold)
    except ValueError as e:
        raise InputError(str(e)) from None
    plan = InputPlan(sim)
    s = plan.struct
    s.hold = hold
    if controller is not None and hasattr(controller, "c_controller"):
        return _c_controller(plan, controller, r, input_period)
    if controller is not None:
        if not isinstance(controller, LinearFeedback):
            raise TypeError(f"controller must be a gen.LinearFeedback or a controller in C "
                            f"(an object with c_controller(sim)), got "
                            f"{type(controller).__name__} (for a Python function, pass it as "
                            "r=lambda t, x: ...)")
        if r is not None:
            raise InputError("give the inputs at the operating point as LinearFeedback(r_op=...), "
                             "not also as r")
        K, x_op, r_op = controller.arrays(sim)
        s.K = plan.array(K)
        s.x_op = plan.array(x_op)
        s.r = plan.array(r_op)
        s.period = 0.0 if controller.period is None else float(controller.period)
        lo, hi = controller.bounds(sim)
        if lo is not None:
            s.r_min = plan.array(lo)
        if hi is not None:
            s.r_max = plan.array(hi)
        if K.ndim == 3:
            s.n_gain = K.shape[0]
            s.t_gain = float(controller.t_gain)
            s.dt_gain = float(controller.dt_gain if controller.dt_gain is not None
                              else controller.period)
        if input_period is not None:
            raise InputError("the LinearFeedback has its own period; input_period is for a "
                             "callable r(t, x)")
        return plan
    if table:
        tg = np.asarray(r[0], dtype=float).ravel()
        R = np.asarray(r[1], dtype=float)
        if R.ndim == 1 and sim.nr == 1:
            R = R[:, None]
        if tg.ndim != 1 or len(tg) < 1 or R.shape != (len(tg), sim.nr):
            raise InputError(f"an input table is (t_grid, R) with R of shape (len(t_grid), nr) = "
                             f"({len(tg)}, {sim.nr}) (inputs {sim.input_names}), got {R.shape}")
        if not (np.all(np.isfinite(tg)) and np.all(np.isfinite(R))):
            raise InputError("the input table holds NaN or infinity")
        if np.any(np.diff(tg) <= 0):
            raise InputError("the input table's times must be strictly increasing")
        s.n_table = len(tg)
        s.t_table = plan.array(tg)
        s.r_table = plan.array(R)
        if input_period is not None:
            raise InputError("input_period applies to a callable r(t, x); a table is "
                             "evaluated inside C")
        return plan
    # a Python callable, sampled
    period = dt if input_period is None else float(input_period)
    if not (np.isfinite(period) and period >= 0):
        raise InputError(f"input_period must be a number >= 0 (0: every stage), got "
                         f"{input_period!r}")
    s.controller = plan.callback(r)
    s.period = period
    return plan


def _c_controller(plan, controller, r, input_period):
    """The input description of a controller in C (CController): its
    function and context in the struct, the base inputs r (constant, or
    none) before it, its period."""
    c = controller.c_controller(plan.sim)
    if not isinstance(c, CController):
        raise TypeError(f"{type(controller).__name__}.c_controller must return a "
                        f"gen.sim.inputs.CController, got {type(c).__name__}")
    if input_period is not None:
        raise InputError(f"the {type(controller).__name__} has its own period; input_period is "
                         "for a callable r(t, x)")
    if not (np.isfinite(c.period) and c.period >= 0):
        raise InputError(f"a controller's period must be a number >= 0, got {c.period!r}")
    if r is not None:
        plan.struct.r = plan.array(np.broadcast_to(np.asarray(r, dtype=float), (plan.sim.nr,)))
    ffi = plan.sim.library.ffi
    plan.struct.controller = ffi.cast("eomgen_controller", c.function)
    plan.struct.ctx = ffi.cast("void *", c.context)
    plan.struct.period = float(c.period)
    plan.keep.append(c.owner)
    return plan
