"""gen.MPC: the controller's Python face over its library (the MPC backend
through gen.pipeline.product), its closed loop in C (c_controller) and
its firmware module (to_c)."""
from __future__ import annotations

import math
import re
import time
from collections import namedtuple
from pathlib import Path

import numpy as np

from ... import pipeline
from ...core.errors import InputError
from ...core.names import validate_name
from ...core.optional import require
from ...core.resources import csrc_file
from ...intake.model import require_model
from ...sim.inputs import CController
from .plan import mpc_plan
from .problem import constants, read_problem
from .reference import read_reference

__all__ = ["MPC", "MPCTimes", "STATUSES", "status_name"]

#: the phase times of the last call, in seconds (the C's clock)
MPCTimes = namedtuple("MPCTimes", ["prepare", "feedback"])


def _read_statuses():
    """{code: (NAME, message)} of csrc/products/mpc/gen_rt_mpc_status.h."""
    text = csrc_file("gen_rt_mpc_status.h").read_text()
    body = text[text.index("#define GEN_RT_MPC_STATUS_TABLE(X)"):].split("\n\n")[0]
    body = body.replace("\\\n", " ")
    out = {0: ("OK", "ok")}
    for m in re.finditer(r'X\((\w+),\s*(-?\d+),\s*((?:"(?:[^"\\]|\\.)*"\s*)+)\)', body):
        out[int(m.group(2))] = (m.group(1), "".join(re.findall(r'"((?:[^"\\]|\\.)*)"',
                                                                m.group(3))))
    return out


#: the MPC's own statuses: {code: (name, message)}; negative runtime codes
#: are the model's (gen.core.status)
STATUSES = _read_statuses()


def status_name(code):
    """'TIME_LIMIT' for 2, 'ERR_QP_MAX_ITER' for -101, the runtime's names
    for its codes."""
    if code in STATUSES:
        return STATUSES[code][0]
    from ...core.status import status_name as rt_name
    return rt_name(code)


def _terminal_weight(model, pb, ref, p):
    """P of the discrete LQR at the reference's end: the DARE of the MPC's
    own discrete model (its RK4 steps' sensitivities) with the stage
    weights period Q, period R; period Q where the end is not stabilizable."""
    linalg = require("scipy.linalg", "gen.MPC's terminal cost (P=None)")
    from ...pipeline import compile as gen_compile
    sim = gen_compile(model, derivatives=True)
    x, u = ref.x[-1], ref.u[-1]
    t_end = ref.t0 + ref.dt * (len(ref.x) - 1)
    h = pb.period / pb.substeps
    A, B = np.eye(sim.ns), np.zeros((sim.ns, sim.nr))
    for j in range(pb.substeps):
        x, Fx, Fr = sim.step_sensitivity(t_end + j * h, x, h, r=u, p=p)
        A, B = Fx @ A, Fx @ B + Fr
    Qd, Rd = pb.period * pb.Q, pb.period * pb.R
    try:
        with np.errstate(all="ignore"):
            X = linalg.solve_discrete_are(A, B, Qd, Rd)
        if np.all(np.isfinite(X)):
            K = np.linalg.solve(Rd + B.T @ X @ B, B.T @ X @ A)
            if np.max(np.abs(np.linalg.eigvals(A - B @ K))) < 1:
                return 0.5 * (X + X.T), "dare"
    except (ValueError, np.linalg.LinAlgError):
        pass
    return Qd, "period Q"


class MPC:
    """A nonlinear model predictive controller by real-time iterations, in C.

    See gen.design.mpc and docs/guides/mpc.md for the problem and the
    algorithm. ``u = mpc(x, t=t)`` returns the control; the predicted
    states and inputs, the status and the phase times are then attributes.
    The same C closes the loop in ``sim.simulate(..., controller=mpc)`` and
    runs on a microcontroller (:meth:`to_c`).

    Parameters
    ----------
    model : gen.Model
        The model; its inputs are the controls.
    horizon : int
        N, the shooting intervals (N + 1 states).
    period : float
        An interval's length and the sample period, seconds.
    Q, R : array_like
        The stage weights on the independent state (ns x ns or ns diagonal
        values, positive semidefinite) and on the inputs (nr x nr or nr
        values, positive definite); the stage cost is weighted by the period.
    P : array_like, optional
        The terminal weight (not weighted by the period); None: the discrete
        Riccati solution at the reference's end (SciPy).
    bounds : dict, optional
        {state or input (symbol or name): (lo, hi)}: inputs hard,
        independent states soft (L1 penalty).
    path : list, optional
        (expr, lo, hi) constraints on sympy expressions of the states and
        inputs, linearized at each iteration (soft where a state appears).
    reference : optional
        None (zero), (x, u) constant, (t, X, U) a table, or a trajectory
        such as a gen.OptimalSolution.
    substeps : int, optional
        RK4 steps per interval.
    method : {"rti", "sqp"}, optional
        One SQP iteration per call, or iterations to convergence.
    max_iter : int, optional
        SQP iterations per call (method="sqp").
    time_limit : float, optional
        Seconds per call; on expiry the best control so far, status
        TIME_LIMIT.
    residuals : list, optional
        (expr, weight) nonlinear least-squares terms (Gauss-Newton).
    penalty : float, optional
        The L1 weight of the soft constraints.
    p : array_like or dict, optional
        The model's constants (default: its own).
    real : {"double", "float"}, optional
        The scalar type of the library.
    name : str, optional
        The C prefix (default ``<model>_mpc``).
    tol, qp_tol : float, optional
        The SQP step's and the QP's tolerances (default by the scalar type).
    qp_max_iter : int, optional
        The QP's interior-point iterations.

    Raises
    ------
    gen.InputError
        On a bad argument (named in the user's own names), before anything
        is built.
    """

    def __init__(self, model, horizon, period, Q, R, P=None, bounds=None, path=None,
                 reference=None, substeps=1, method="rti", max_iter=1, time_limit=None, *,
                 residuals=None, penalty=1e3, p=None, real="double", name=None, tol=None,
                 qp_tol=None, qp_max_iter=100):
        require_model(model, "gen.MPC")
        t0 = time.perf_counter()
        if real not in ("double", "float"):
            raise InputError(f"gen.MPC: real must be 'double' or 'float', got {real!r}", "real",
                             None, real)
        self.model, self.real = model, real
        self.name = self._check_name(name or f"{model.name}_mpc", model)
        pb = read_problem(model, horizon, period, Q, R, P, bounds, path, substeps, method,
                          max_iter, time_limit, residuals=residuals, penalty=penalty)
        pb.p = constants(model, p)
        self.reference = ref = read_reference(model, reference, pb.period)
        self.problem = pb
        if pb.P is None:
            self.P, self.terminal = _terminal_weight(model, pb, ref, pb.p)
        else:
            self.P, self.terminal = pb.P, "given"
        self._tols = (tol, qp_tol, qp_max_iter, penalty)
        self.options = self._options(real)
        for k in ("tol", "qp_tol"):
            if not (self.options[k] > 0 and math.isfinite(self.options[k])):
                raise InputError(f"gen.MPC: {k} must be a positive number, got "
                                 f"{self.options[k]!r}", k, None, self.options[k])
        if self.options["qp_max_iter"] < 1:
            raise InputError(f"gen.MPC: qp_max_iter must be >= 1, got {qp_max_iter!r}",
                             "qp_max_iter", None, qp_max_iter)
        plan = mpc_plan(model, pb, ref, self.P, self.name, real, self.options)
        built, self._ffi, self._lib = pipeline.product(plan, "mpc", real=real)
        self.library = built.path
        self._dtype = np.float64 if real == "double" else np.float32
        self._fn = {f: getattr(self._lib, f"{self.name}_{f}") for f in (
            "init", "step", "prepare", "feedback", "solution", "get_info", "reset", "set_guess",
            "set_options", "status_message", "memory_size")}
        self._mem_buf = self._ffi.new("char[]", self._fn["memory_size"]())
        self._mem = self._ffi.cast(f"{self.name}_memory *", self._mem_buf)
        self._info = self._ffi.new(f"{self.name}_info *")
        self._check(self._fn["init"](self._mem), "init")
        self.build_seconds = time.perf_counter() - t0

    def _options(self, real):
        """The solver's options in a scalar type: the tolerances given, or
        the type's defaults (double 1e-8 and 1e-10, float 1e-4 and 1e-5)."""
        tol, qp_tol, qp_max_iter, penalty = self._tols
        return {"tol": float(tol if tol is not None else (1e-8 if real == "double" else 1e-4)),
                "qp_tol": float(qp_tol if qp_tol is not None else
                                (1e-10 if real == "double" else 1e-5)),
                "qp_max_iter": int(qp_max_iter), "penalty": float(penalty)}

    @staticmethod
    def _check_name(name, model):
        try:
            validate_name(name)
        except Exception as e:
            raise InputError(f"gen.MPC: name {name!r}: {e}", "name", None, name) from None
        taken = {model.name, f"{model.name}_kernels", f"{model.name}_lin"}
        if name in taken or name.startswith("gen_rt_"):
            raise InputError(f"gen.MPC: name {name!r} is one of the model's files' names",
                             "name", None, name)
        return name

    def __repr__(self):
        pb = self.problem
        return (f"<gen.MPC of '{self.model.name}': N = {pb.N} intervals of {pb.period} s, "
                f"method {pb.method!r}, {self.real}>")

    # ------------------------------------------------------------ sizes
    @property
    def horizon(self):
        """N, the shooting intervals."""
        return self.problem.N

    @property
    def period(self):
        """The sample period, seconds."""
        return self.problem.period

    # ------------------------------------------------------------ calls
    def _ptr(self, a):
        return self._ffi.cast(f"{self.real} *", a.ctypes.data)

    def _state(self, x, what="x"):
        m = self.model
        x = np.asarray(x, dtype=float).reshape(-1) if np.ndim(x) else np.asarray([x], float)
        if x.shape != (m.nx,):
            raise InputError(f"gen.MPC: {what} must have shape ({m.nx},) (the state "
                             f"{', '.join(m.state_names)}), got {np.shape(x)}", what, None, None)
        bad = np.nonzero(~np.isfinite(x))[0]
        if len(bad):
            i = int(bad[0])
            raise InputError(f"gen.MPC: {what}[{i}] = {float(x[i])!r} ({m.state_names[i]}): the "
                             "state must be finite", what, i, float(x[i]))
        return np.ascontiguousarray(x, dtype=self._dtype)

    def _time(self, t):
        try:
            t = float(t)
        except (TypeError, ValueError):
            raise InputError(f"gen.MPC: t must be a number, got {t!r}", "t", None, t) from None
        if not math.isfinite(t):
            raise InputError(f"gen.MPC: t = {t!r} must be finite", "t", None, t)
        return t

    def _check(self, st, what):
        if st == -1 or st == -7:    # ERR_NULL, ERR_BAD_ARG: a call error
            raise InputError(f"gen.MPC.{what}: {self.message_of(st)}", what, None, st)
        return st

    def __call__(self, x, t=0.0):
        """The control to apply at time t from the state x (nx): one
        controller call in C (preparation unless :meth:`prepare` was called
        for t, feedback; with method="sqp", iterations to convergence).

        Returns
        -------
        numpy.ndarray, shape (nr,)
            Never NaN: on a failure (a negative :attr:`status`) the previous
            solution's control, shifted, clipped to the bounds.

        Raises
        ------
        gen.InputError
            On a state of the wrong shape or with NaN or infinite entries,
            or a time that is not finite.
        """
        xs = self._state(x)
        u = np.zeros(self.model.nr, dtype=self._dtype)
        self._fn["step"](self._mem, self._time(t), self._ptr(xs), self._ptr(u))
        return u.astype(float)

    def prepare(self, t):
        """The preparation phase for the call at time t (the last solution
        shifted, the model's steps and sensitivities along it, the QP's
        data): what does not need the new state.

        Parameters
        ----------
        t : float
            The time of the next feedback.

        Returns
        -------
        int
            The status (0, or a negative failure of the model's steps).

        Raises
        ------
        gen.InputError
            On a time that is not finite.
        """
        return self._check(self._fn["prepare"](self._mem, self._time(t)), "prepare")

    def feedback(self, x):
        """The feedback phase: the state x in, the control out (the QP
        solved from the prepared data; prepared first when it is not).

        Parameters
        ----------
        x : array_like, shape (nx,)
            The measured state.

        Returns
        -------
        numpy.ndarray, shape (nr,)
            The control, never NaN.

        Raises
        ------
        gen.InputError
            On a state of the wrong shape or not finite.
        """
        xs = self._state(x)
        u = np.zeros(self.model.nr, dtype=self._dtype)
        self._fn["feedback"](self._mem, self._ptr(xs), self._ptr(u))
        return u.astype(float)

    def reset(self, x=None, u=None):
        """Forget the iterate: the next call starts from zero states and
        inputs (a constrained model: the state it gets, repeated), or from
        a guess.

        Parameters
        ----------
        x : array_like, optional
            States, (N + 1, nx) or (nx,) repeated.
        u : array_like, optional
            Inputs, (N, nr) or (nr,) repeated.

        Raises
        ------
        gen.InputError
            On a guess that is not finite.
        """
        if x is None and u is None:
            self._fn["reset"](self._mem)
            return
        N, m = self.problem.N, self.model
        X = np.zeros((N + 1, m.nx)) if x is None else np.broadcast_to(
            np.asarray(x, dtype=float), (N + 1, m.nx))
        U = np.zeros((N, m.nr)) if u is None else np.broadcast_to(
            np.asarray(u, dtype=float), (N, m.nr))
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(U))):
            raise InputError("gen.MPC.reset: the guess must be finite", "x", None, None)
        X = np.ascontiguousarray(X, dtype=self._dtype)
        U = np.ascontiguousarray(U, dtype=self._dtype)
        self._check(self._fn["set_guess"](self._mem, self._ptr(X), self._ptr(U)), "reset")

    # ------------------------------------------------------------ outcome
    def _read_info(self):
        self._fn["get_info"](self._mem, self._info)
        return self._info

    @property
    def x(self):
        """The predicted states of the last call, (N + 1, nx)."""
        N, m = self.problem.N, self.model
        X = np.zeros((N + 1) * m.nx, dtype=self._dtype)
        U = np.zeros(N * m.nr, dtype=self._dtype)
        self._fn["solution"](self._mem, self._ptr(X), self._ptr(U))
        return X.reshape(N + 1, m.nx).astype(float)

    @property
    def u(self):
        """The predicted inputs of the last call, (N, nr)."""
        N, m = self.problem.N, self.model
        X = np.zeros((N + 1) * m.nx, dtype=self._dtype)
        U = np.zeros(N * m.nr, dtype=self._dtype)
        self._fn["solution"](self._mem, self._ptr(X), self._ptr(U))
        return U.reshape(N, m.nr).astype(float)

    @property
    def status(self):
        """The last call's status: 0, a positive outcome with a control
        (1 MAX_ITER, 2 TIME_LIMIT) or a negative failure (the QP's, the
        model's; :func:`status_name`)."""
        return int(self._read_info().status)

    @property
    def status_name(self):
        """The last call's status by name ('OK', 'TIME_LIMIT', ...)."""
        return status_name(self.status)

    @property
    def message(self):
        """The last call's status in words."""
        return self.message_of(self.status)

    def message_of(self, code):
        """The message of a status code.

        Parameters
        ----------
        code : int
            A status.

        Returns
        -------
        str
        """
        return self._ffi.string(self._fn["status_message"](int(code))).decode()

    @property
    def qp_status(self):
        """The last QP's status."""
        return int(self._read_info().qp_status)

    @property
    def iterations(self):
        """SQP iterations of the last call."""
        return int(self._read_info().iterations)

    @property
    def qp_iterations(self):
        """Interior-point iterations of the last call, all its QPs."""
        return int(self._read_info().qp_iterations)

    @property
    def times(self):
        """(prepare, feedback): the last call's seconds in each phase,
        measured in C (the host's monotonic clock)."""
        i = self._read_info()
        return MPCTimes(float(i.t_prepare), float(i.t_feedback))

    @property
    def objective(self):
        """The last QP's objective (the cost's second-order model)."""
        return float(self._read_info().objective)

    # ------------------------------------------------------------ closed loop
    def c_controller(self, sim):
        """The controller in C for ``sim.simulate(..., controller=mpc)``
        (gen.sim.inputs.CController): ``<name>_controller`` on this
        object's memory, sampled every period. The iterate is forgotten
        first: a closed loop starts from the first guess.

        Parameters
        ----------
        sim : gen.Simulator
            The model's simulator, in the controller's scalar type.

        Returns
        -------
        gen.sim.inputs.CController

        Raises
        ------
        gen.InputError
            On another model's simulator or another scalar type.
        """
        m = self.model
        if (sim.name != m.name or sim.nx != m.nx or sim.nr != m.nr):
            raise InputError(f"gen.MPC of model {m.name!r} cannot close a loop on model "
                             f"{sim.name!r}", "controller", None, None)
        if np.dtype(sim.dtype) != np.dtype(self._dtype):
            raise InputError(f"gen.MPC: the controller is built in {self.real} and the "
                             f"simulator in {np.dtype(sim.dtype).name}: build both in one "
                             "scalar type (gen.MPC(..., real=...))", "controller", None, None)
        self._fn["reset"](self._mem)
        ffi = self._ffi
        fn = int(ffi.cast("uintptr_t", ffi.addressof(self._lib, f"{self.name}_controller")))
        return CController(fn, int(ffi.cast("uintptr_t", self._mem)), self, self.period)

    # ------------------------------------------------------------ C source
    def sources(self, name=None, real=None):
        """The controller's C for a firmware or the standalone binary, as
        text: ``<name>.h``, ``<name>.c``, the driver of the standalone
        simulator ``<name>_loop.c``/``.h`` and the MPC runtime
        (gen_rt_mpc.c/.h, gen_rt_qp.c/.h, gen_rt_mpc_status.h).

        Parameters
        ----------
        name : str, optional
            The C prefix (default: this controller's).
        real : {"double", "float"}, optional
            The scalar type (default: this controller's; the tolerances not
            given take the type's defaults).

        Returns
        -------
        dict
            {file name: text}.

        Raises
        ------
        gen.InputError
            On a bad name or scalar type.
        """
        from ..._version import __version__
        from ...codegen.render import render, template_env
        name = self._check_name(name or self.name, self.model)
        real = real or self.real
        if real not in ("double", "float"):
            raise InputError(f"gen.MPC: real must be 'double' or 'float', got {real!r}",
                             "real", None, real)
        plan = mpc_plan(self.model, self.problem, self.reference, self.P, name, real,
                        self._options(real), with_model=False)
        files = dict(render(plan, real=real, backend="mpc").files)
        env = template_env()
        ctx = {"name": name, "p": self.model.name, "P": self.model.name.upper(),
               "N": name.upper(), "version": __version__}
        for ext in ("h", "c"):
            files[f"{name}_loop.{ext}"] = env.get_template(f"mpc/mpc_loop.{ext}.j2").render(**ctx)
        return files

    def to_c(self, path, name=None, real=None):
        """Write the controller as C into a folder (usually the model's
        generated one, gen.generate): a firmware module with its workspace
        sized at generation (``<name>_memory``, the caller's static
        instance), no heap, no stdio and no global that is written; and the
        standalone simulator's driver: ``cmake -D<P>_TRACKER=<name>_loop``
        builds the model's binary closed by the controller.

        Parameters
        ----------
        path : str or Path
            The folder.
        name, real : optional
            As :meth:`sources`.

        Returns
        -------
        list of Path
            The paths written.
        """
        from ...codegen.render import write_atomic
        return write_atomic(self.sources(name, real), Path(path))
