"""The numpy-facing simulator over a compiled model. C status codes become
exceptions from gen.core.errors; wrong shapes raise gen.InputError (a ValueError) naming the
expected shape. Every call returns fresh arrays (safe with solve_ivp).

A Simulator is made from the host module (gen/toolchain/host.py), the model
library's plugin table and the model's interface description
(gen.codegen.abi.Interface). It needs no sympy object, except through
``derivatives``: a function that builds the derivative kernels on their
first use (gen.compile's lazy build).

The evaluation methods (``mass_matrix``, ``forcing``, ..., ``jacobian``) are
generated from the interface description (gen/sim/methods.py); every
docstring is assembled from the shared text of gen/sim/docstrings.py and, for
the run options, gen/sim/options.py."""
from __future__ import annotations

import functools
import threading

import numpy as np

from ..codegen.abi import DERIVATIVE_VERBS, JACOBIAN_METHODS
from ..core.errors import InputError, SolverError
from ..core.optional import require
from ..core.status import EXCEPTIONS, status_name
from .docstrings import documented
from .ensemble import run_ensemble
from .interrupt import call
from .library import ModelLibrary, fast_rhs
from .methods import EVALUATIONS, method
from .options import (OPTION_NAMES, fill_sim_options, finite_or_raise, option_params,
                      options_signature, plan_rows, run_options)
from .solution import Solution

__all__ = ["Simulator", "ModelLibrary", "EXCEPTIONS"]

# the options an ensemble accepts as simulate's but keeps its own way (its reducers)
_KEPT_BY_REDUCERS = ("every", "final_only", "events", "terminal")


class Simulator:
    """A compiled model: numpy arrays in, numpy arrays out, every call in the
    generated C.

    Returned by :func:`gen.compile` (not constructed directly).

    Attributes
    ----------
    nq, nu, nx, nr, np, mc, mv, ns, na, ny : int
        The sizes: coordinates, speeds, state, inputs, constants,
        configuration and velocity constraints, independent state, reaction
        forces, outputs.
    state_names, input_names, constant_names, independent_state_names : list of str
        C-safe names (``theta'`` -> ``theta_p``); the sympy spelling is
        accepted wherever a name is.
    output_names, auxiliary_names : list of str
        The outputs and the reaction forces.
    constants : numpy.ndarray
        The default constants.
    has_energy : bool
        Whether the model was given an energy.
    interface : gen.codegen.abi.Interface
        The description of the C interface the model was built with.
    """

    def __init__(self, host, api, interface, derivatives=None):
        iface = interface
        self.interface = iface
        self._mod = host
        self._ffi = host.ffi
        self._lib = host.lib
        self._api = api
        # builds the derivative kernels: () -> (table, Built, timings); None
        # once the library has them
        self._derive = derivatives
        self._derive_lock = threading.Lock()
        self.build_info = {}
        self._p = iface.name
        self.real = iface.real
        self.dtype = np.float64 if iface.real == "double" else np.float32
        self._ctype = "eomgen_real"
        self.name = iface.name
        self.method = iface.method
        self.nq, self.nu, self.nx = iface.nq, iface.nu, iface.nx
        self.nr, self.np, self.mc, self.mv = iface.nr, iface.np, iface.mc, iface.mv
        self.ns = iface.ns
        # reaction forces of the auxiliary speeds (Kane's u_auxiliary)
        self.na = iface.sizes.get("NA", 0)
        self.auxiliary_names = list(getattr(iface, "auxiliary_names", []))
        self.auxiliary_labels = list(getattr(iface, "auxiliary_labels", []))
        # outputs y(q, u, r, t) (Model(..., outputs={...}))
        self.ny = iface.sizes.get("NY", 0)
        self.output_names = list(getattr(iface, "output_names", []))
        self.output_labels = list(getattr(iface, "output_labels", []))
        # hybrid={...}: impacts and resets (gen/intake/hybrid.py)
        self.hybrid_names = list(getattr(iface, "hybrid_names", []))
        self.hybrid_kinds = list(getattr(iface, "hybrid_kinds", []))
        self.nh = len(self.hybrid_names)
        self.has_energy = iface.has_energy
        self.state_names = list(iface.state_names)
        self.input_names = list(iface.input_names)
        self.constant_names = list(iface.constant_names)
        self.independent_state_names = list(iface.independent_state_names)
        self._labels = {"state": list(iface.state_labels), "inputs": list(iface.input_labels),
                        "constants": list(iface.constant_labels)}
        self.constants = np.array(iface.constants, dtype=float)
        self.q_ind, self.q_dep = list(iface.q_ind), list(iface.q_dep)
        self.u_ind, self.u_dep = list(iface.u_ind), list(iface.u_dep)
        # per-call overhead: typed buffers without casts, functions looked up
        # once, the default constants converted once
        self._arr_t = f"{self._ctype}[]"
        self._dt = np.dtype(self.dtype)
        self._fns = {}
        self._outs = {}
        self._xshape = (self.nx,)
        self._rshape = (self.nr,)
        self._fb = self._ffi.from_buffer
        self._null = self._ffi.NULL
        self._rhs_c = self._lib.eomgen_eval_rhs    # the fast path passes the table itself
        self._rhs_fast = fast_rhs(host, api)
        self._rhs_batch_fast = fast_rhs(host, api, "rhs_batch")
        for k, n in (("nq", self.nq), ("nu", self.nu), ("nr", self.nr), ("np", self.np),
                     ("mc", self.mc), ("mv", self.mv), ("ns", self.ns), ("ny", self.ny),
                     ("na", self.na)):
            if getattr(api, k) != n:
                raise ValueError(f"the library of '{self.name}' has {k} = {getattr(api, k)}, "
                                 f"its interface {n}: a library of another model")

    @property
    def library(self):
        """The compiled library under this Simulator (:class:`ModelLibrary`),
        for code that fills the C structs itself."""
        lib = self.__dict__.get("_library")
        if lib is None:
            lib = self._library = ModelLibrary(self)
        return lib

    @property
    def state_labels(self):
        """The states as the user spelled them in sympy, in the order of ``state_names``."""
        return list(self._labels["state"])

    @property
    def input_labels(self):
        """The inputs as the user spelled them in sympy, in the order of ``input_names``."""
        return list(self._labels["inputs"])

    @property
    def constant_labels(self):
        """The constants as the user spelled them in sympy, in the order of ``constant_names``."""
        return list(self._labels["constants"])

    # ------------------------------------------------------------ helpers
    def _fn(self, name):
        """The C function <p>_<name> (through the host module, its table
        bound): a function taking the C function's own arguments."""
        f = self._fns.get(name)
        if f is None:
            if name in DERIVATIVE_VERBS:
                self._need_derivatives()
            f = self._fns[name] = functools.partial(getattr(self._lib, f"eomgen_{name}"),
                                                    self._api)
        return f

    @property
    def has_derivatives(self):
        """Whether the derivative kernels (linearize, jacobian,
        step_sensitivity, RODAS4) are compiled in; they are built on first
        use otherwise."""
        return self._derive is None

    def _need_derivatives(self):
        """Build (or load from the cache) the derivative kernels and switch
        to the complete library: once, thread-safe."""
        if self._derive is None:
            return
        with self._derive_lock:
            if self._derive is None:
                return
            api, built, timings = self._derive()
            self._api = api
            self._rhs_fast = fast_rhs(self._mod, api)
            self._rhs_batch_fast = fast_rhs(self._mod, api, "rhs_batch")
            self._fns.clear()
            self.build_info.update(timings, module=str(built.path), derivatives=True)
            self._derive = None

    def _new(self, struct):
        """A zeroed C struct of the interface ("sim_options", "input",
        "events", "sim_stats"), as the host module declares it."""
        if struct == "sim_stats":
            return self._ffi.new("eomgen_sim_stats *", {"x_last": max(1, self.nx)})
        return self._ffi.new(f"eomgen_{struct} *")

    def _out_sizes(self, verb):
        """The true sizes of a function's array outputs (interface description)."""
        sizes = self._outs.get(verb)
        if sizes is None:
            fn = self.interface.function(verb)
            sizes = self._outs[verb] = [self.interface.size(a.size) for a in fn.params
                                        if a.role in ("out", "out?")]
        return sizes

    def _call(self, verb, *args, t=None, state=None, named=None):
        """Call <p>_<verb> with the inputs (arrays become pointers, None
        NULL, numbers pass as they are) followed by fresh arrays for its
        outputs (sizes from the interface description); raise on a failure
        status (named: {argument: array} of the inputs, for the message of a
        NaN); return the outputs, each of its true length."""
        sizes = self._out_sizes(verb)
        outs = [np.zeros(max(1, n), dtype=self.dtype) for n in sizes]
        conv = [self._ptr(a) if a is None or isinstance(a, np.ndarray) else a for a in args]
        st = self._fn(verb)(*conv, *[self._ptr(o) for o in outs])
        if st:
            self._check(st, verb, t, state, args=named)
        return [o if n == o.size else o[:n].copy() for o, n in zip(outs, sizes)]

    def _vec(self, v, n, what, default=None):
        if (type(v) is np.ndarray and v.dtype is self._dt and v.shape == (n,)
                and v.flags.c_contiguous):
            return v                                   # fast path: no copy
        if v is None:
            if default is None:
                v = np.zeros(n)
            else:
                v = default
        if isinstance(v, dict):
            v = self._from_dict(v, what)
        a = np.ascontiguousarray(v, dtype=self.dtype)
        if a.ndim == 0 and n == 1:
            a = a.reshape(1)
        if a.shape != (n,):
            raise InputError(f"{what} must have shape ({n},), got {np.shape(v)}",
                             what.split()[-1])
        return a

    def _from_dict(self, d, what):
        kind = what.split()[0]
        names = {"state": self.state_names, "inputs": self.input_names,
                 "constants": self.constant_names}.get(kind)
        if names is None:
            raise InputError(f"{what} cannot be given as a dict", what.split()[-1])
        labels = self._labels[kind]
        base = {"state": np.zeros(self.nx), "inputs": np.zeros(self.nr),
                "constants": self.constants.copy()}[kind]
        for k, v in d.items():
            k = str(k)
            if k in names:
                base[names.index(k)] = float(v)
            elif k in labels:                  # the sympy spelling works too
                base[labels.index(k)] = float(v)
            else:
                raise InputError(f"unknown name {k!r} in {what}; known: {names}",
                                 what.split()[-1], None, k)
        return base

    def _ptr(self, a):
        if a is None:
            return self._ffi.NULL
        return self._ffi.from_buffer(self._arr_t, a)

    def _check(self, status, where, t=None, state=None, args=None):
        """Raise the exception of a failure status: the function, the status,
        the time and the state. args: {argument name: array} of the call, so
        that a NaN or infinite input names its argument and entry."""
        if status == 0:
            return
        name = status_name(status)
        if name == "ERR_NONFINITE_INPUT" and args:
            labels = {"x": self.state_names, "x0": self.state_names, "r": self.input_names,
                      "p": self.constant_names}
            for arg, a in args.items():
                if a is not None:
                    try:
                        finite_or_raise(arg, a, labels.get(arg))
                    except InputError as e:
                        raise InputError(f"{self._p}_{where}: {e}", e.argument, e.index,
                                         e.value) from None
        msg = self._ffi.string(self._fn("status_message")(status)).decode()
        if name == "ERR_SINGULAR_REACTIONS" and self.auxiliary_names:
            msg += f" (the reactions {', '.join(self.auxiliary_names)})"
        if name == "ERR_INCONSISTENT_RESET":
            resets = [n for n, k in zip(self.hybrid_names, self.hybrid_kinds) if k == 1]
            msg += f" (reset(s) {', '.join(resets)} of model '{self.name}')"
        text = f"{self._p}_{where}: {msg} [{name}]"
        if t is not None:
            text += f" at t = {float(t):.17g}"
        if state is not None:
            pairs = ", ".join(f"{n}={float(v):.12g}" for n, v in zip(self.state_names, state))
            text += f", state: {pairs}"
        cls = EXCEPTIONS.get(name, SolverError)
        if cls is InputError:
            raise InputError(text)
        if cls in (ValueError, KeyboardInterrupt):
            raise cls(text)
        raise cls(text, status=status, status_name=name, time=t,
                  state=None if state is None else np.array(state, dtype=float))

    def _params(self, p):
        """None (NULL: the C function takes its default constants, unchecked:
        they are finite by construction) or the constants as an array."""
        if p is None:
            return None
        return self._vec(p, self.np, "constants p", default=self.constants)

    def _inputs(self, r):
        return None if r is None else self._vec(r, self.nr, "inputs r")

    # ------------------------------------------- evaluation (generated)
    mass_matrix = method(EVALUATIONS["mass_matrix"], __name__)
    forcing = method(EVALUATIONS["forcing"], __name__)
    kinematics = method(EVALUATIONS["kinematics"], __name__)
    constraints = method(EVALUATIONS["constraints"], __name__)
    constraint_jacobian = method(EVALUATIONS["constraint_jacobian"], __name__)
    velocity_constraints = method(EVALUATIONS["velocity_constraints"], __name__)
    velocity_constraint_matrix = method(EVALUATIONS["velocity_constraint_matrix"], __name__)
    energy = method(EVALUATIONS["energy"], __name__)
    multipliers = method(EVALUATIONS["multipliers"], __name__)
    auxiliary_forces = method(EVALUATIONS["auxiliary_forces"], __name__)
    outputs = method(EVALUATIONS["outputs"], __name__)
    hybrid_values = method(EVALUATIONS["hybrid_values"], __name__)
    project = method(EVALUATIONS["project"], __name__)
    consistent_state = method(EVALUATIONS["consistent_state"], __name__)
    jacobian = method(EVALUATIONS["jacobian"], __name__)

    @documented("The state derivative x', usable as ``solve_ivp``'s ``fun``.",
                ["t", ("x", "array_like, shape (nx,) or (N, nx)", "The state, or N states "
                       "evaluated in one C call (:meth:`rhs_batch`)."), "r", "p",
                 ("out", "numpy.ndarray, optional", "A preallocated C-contiguous result "
                  "array.")],
                [("", "numpy.ndarray, shape (nx,) or (N, nx)", "A fresh array per call (or "
                  "``out``).")])
    def rhs(self, t, x, *, r=None, p=None, out=None):
        if p is None and out is None and self._rhs_fast is not None:
            # the host's CPython function (csrc/host/gen_host_fast.c): x' for
            # an exact array of the right type and size, None otherwise or
            # on a nonzero status (the paths below convert, check, raise)
            res = self._rhs_fast(t, x, r)
            if res is not None:
                return res
        if (p is None and out is None and type(x) is np.ndarray and x.dtype is self._dt
                and x.shape == self._xshape and (r is None or (
                    type(r) is np.ndarray and r.dtype is self._dt and r.shape == self._rshape))):
            # the common calls (solve_ivp, a controller's r): no conversions,
            # no lookups; from_buffer refuses a non-contiguous array (ValueError),
            # which takes the general path below. The C function checks the
            # values (finite) itself.
            fb, at, null = self._fb, self._arr_t, self._null
            try:
                xb = fb(at, x)
                rb = null if r is None else fb(at, r)
            except ValueError:
                pass
            else:
                res = np.empty(self.nx, dtype=self._dt)
                st = self._rhs_c(self._api, t, xb, rb, null, fb(at, res), null)
                if st:
                    self._check(st, "eval_rhs", t, x, args={"x": x, "r": r})
                return res
        if np.ndim(x) == 2:
            return self.rhs_batch(t, x, r=r, p=p, out=out)
        x = self._vec(x, self.nx, "state x")
        if out is None:
            out = np.empty(self.nx, dtype=self.dtype)
        elif (type(out) is not np.ndarray or out.dtype is not self._dt
                or out.shape != (self.nx,) or not out.flags.c_contiguous):
            raise InputError(f"out must be a C-contiguous {self.dtype.__name__} array of "
                             f"shape ({self.nx},)")
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        st = self._fn("eval_rhs")(t, self._ptr(x), self._ptr(r), self._ptr(self._params(p)),
                                  self._ptr(out), self._ffi.NULL)
        self._check(st, "eval_rhs", t, x, args={"x": x, "r": r, "p": self._params(p)})
        return out


    @documented("""The Jacobian d x'/dx of the right-hand side (every entry of x free),
                usable as ``solve_ivp``'s ``jac``: ``solve_ivp(sim.rhs, (0, 10), x0,
                method="Radau", jac=sim.jac)``.""", ["t", "x", "r", "p"],
                [("", "numpy.ndarray, shape (nx, nx)", "")])
    def jac(self, t, x, *, r=None, p=None):
        return self.jacobian(t, x, r=r, p=p)[0]

    # ------------------------------------------------------- simulation
    @documented("""Simulate from x0 to t_end, in C, with one row per output time.

                ``t, x = sim.simulate(x0, t_end, dt)`` unpacks the result; every
                other quantity is an attribute of it (:class:`gen.Solution`). The
                options of the run are keywords, or ``options=gen.RunOptions(...)``
                (a keyword given explicitly wins over options).""",
                ["x0", "t_end", "dt@run",
                 ("r", "None, array_like, tuple or callable, optional", "None or nr "
                  "constant inputs; a table ``(t_grid, R)`` held or interpolated in C "
                  "(``input_hold``); or a callable ``r(t, x)`` sampled every "
                  "``input_period``."),
                 ("p", "array_like, shape (np,), or dict, optional", "The constants (None: "
                  "the defaults given at model creation)."),
                 ("controller", "gen.LinearFeedback, optional", "A feedback computed "
                  "inside C, continuous or sampled."),
                 *option_params(OPTION_NAMES), "options"],
                [("", "gen.Solution", "``t``, ``x``, ``r``, ``lam``, ``outputs``, "
                  "``events``, ``status``, ``message``, ``stats`` and ``sol(t)``; unpacks "
                  "as ``t, x``.")], ["run", "step", "keyword"])
    def simulate(self, x0, t_end, dt, *, r=None, p=None, controller=None, options=None,
                 **keywords):
        from .inputs import plan_inputs
        o = run_options(t_end, dt, options, keywords, "Simulator.simulate")
        x0 = self._vec(x0, self.nx, "state x0")
        finite_or_raise("x0", x0, self.state_names)
        pp = self._params(p)
        if pp is not None:
            finite_or_raise("p", pp, self.constant_names)
        plan = plan_inputs(self, r, controller, o.dt, o.method, o.input_period, o.input_hold)
        if plan is None and r is not None:
            r = self._vec(r, self.nr, "inputs r")
            finite_or_raise("r", r, self.input_names)
        # the rows kept, checked before anything is allocated
        full = self._fn("simulate_rows")(o.t0, o.t_end, o.dt)
        row_bytes = self._dt.itemsize * (1 + self.nx + max(1, self.mv) + max(1, self.nr))
        rows, full = plan_rows(o, full if full >= 0 else None, row_bytes,
                               self.library.function("simulate_rows_kept"))
        if o.method in JACOBIAN_METHODS:
            self._need_derivatives()       # its Jacobian
        if o.consistent:
            x0 = self.consistent_state(x0, p=pp, t=o.t0)
        return self._run(o, x0, r, pp, plan, rows)

    simulate.__signature__ = options_signature(simulate)

    def _run(self, o, x0, r, pp, plan, rows):
        """simulate's C call (simulate, simulate_input with a plan of inputs,
        simulate_events with events or hybrid jumps) and its Solution."""
        from .events import hybrid_error, plan_events
        from .inputs import InputPlan
        opts = self._new("sim_options")
        self._fn("sim_options_default")(opts)
        fill_sim_options(opts, o)
        evplan = None
        if o.events is not None or self.nh:   # hybrid={...}: its jumps are events
            evplan = plan_events(self, o.events, o.terminal)
            if plan is None:
                plan = InputPlan(self)
                if r is not None:
                    plan.struct.r = plan.array(r)
        stats = self._new("sim_stats")
        t = np.empty(rows, dtype=self.dtype)
        X = np.empty((rows, self.nx), dtype=self.dtype)
        lam = np.empty((rows, max(1, self.mv)), dtype=self.dtype)
        R = np.empty((rows, max(1, self.nr)), dtype=self.dtype)
        P, ptr = self._ptr(pp), self._ptr
        if evplan is not None:
            verb, args = "simulate_events", (ptr(x0), o.t0, o.t_end, o.dt, plan.struct,
                                             evplan.struct, P, opts, rows, ptr(t), ptr(X),
                                             ptr(lam), ptr(R), stats)
        elif plan is None:
            verb, args = "simulate", (ptr(x0), o.t0, o.t_end, o.dt, ptr(r), P, opts, rows,
                                      ptr(t), ptr(X), ptr(lam), stats)
            R[:, :self.nr] = 0 if r is None else r
        else:
            verb, args = "simulate_input", (ptr(x0), o.t0, o.t_end, o.dt, plan.struct, P, opts,
                                            rows, ptr(t), ptr(X), ptr(lam), ptr(R), stats)
        while True:
            st = call(self, opts, self._fn(verb), *args)   # the C call of simulate (Ctrl-C: gen/sim/interrupt.py)
            if plan is not None and plan.error is not None:
                raise plan.error
            if evplan is None or stats.n_events <= evplan.capacity:
                break
            evplan.resize(stats.n_events)   # the same run again, with room for all
        if st != 0:
            if evplan is not None and self.nh:   # a jump or the start, in the user's names
                err = hybrid_error(self, evplan, st, stats.n_events, pp, verb)
                if err is not None:
                    raise err
            if stats.n_out > 0:
                self._check(st, verb, stats.t_last,
                            np.array([stats.x_last[i] for i in range(self.nx)]))
            self._check(st, verb, o.t0, x0, args={"x0": x0, "p": pp, "r": r})
        if stats.n_out < rows:   # a terminal event ended the run
            rows = stats.n_out
            t, X, lam, R = t[:rows], X[:rows], lam[:rows], R[:rows]
        return self._solution(o, stats, evplan, t, X, lam, R, pp)

    def _solution(self, o, stats, evplan, t, X, lam, R, pp):
        """The Solution of a run: its rows, statistics, events and status."""
        status, message = 0, "the run reached t_end"
        info = {"n_steps": stats.n_accepted, "n_accepted": stats.n_accepted,
                "n_rejected": stats.n_rejected, "n_rhs": stats.n_rhs, "n_jac": stats.n_jac,
                "n_out": stats.n_out}
        found = []
        if evplan is not None:
            found = evplan.found(stats.n_events)
            info["n_events"] = stats.n_events
            info["terminal"] = evplan.names[stats.terminal] if stats.terminal >= 0 else None
            if info["terminal"] is not None:
                status = 1
                message = f"the terminal event {info['terminal']!r} ended the run at " \
                          f"t = {float(t[-1]):.17g}"
        return Solution(self, t, X, R[:, :self.nr], lam[:, :self.mv],
                        pp, found, status, message, info, o.method)

    @documented("One integrator step of size h from (t, x).",
                ["t", "x", "h", "r", "p",
                 ("method", '{"rk4"}, optional', "The integrator: the classic RK4 step (the "
                  "C ``<p>_step_rk4``)."),
                 ("project", "bool, optional", "Project the new state onto the constraints "
                  "(default True).")],
                [("", "numpy.ndarray, shape (nx,)", "The state after the step.")],
                [("gen.InputError", "On a wrong shape (the message names the expected one), "
                  "a NaN or infinite input, or a method other than rk4."), "solver"])
    def step(self, t, x, h, *, r=None, p=None, method="rk4", project=True):
        if method != "rk4":
            raise InputError(f"step supports method='rk4' (a fixed step); got {method!r}",
                             "method", None, method)
        x1 = self._vec(x, self.nx, "state x").copy()
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        pp = self._params(p)
        st = self._fn("step_rk4")(t, h, self._ptr(r), self._ptr(pp), 1 if project else 0,
                                  self._ptr(x1))
        self._check(st, "step_rk4", t, x, args={"x": x1, "r": r, "p": pp})
        return x1

    @documented("""One integrator step of size h from (t, x) and its exact derivatives
                by the step's variational equations (the generated Jacobian kernels, not
                finite differences); the step is not projected.

                For a constrained model the dependent entries of x follow the
                constraints to first order (perturb ``x_ind``, complete with
                ``consistent_state``). For an unconstrained model Fx is the full
                dx1/dx; as h -> 0, Fx -> I + h A.""",
                ["t", "x", "h", "r", "p", ("method", '{"rk4"}, optional', "The integrator "
                                            "(the sensitivities are those of RK4).")],
                [("x1", "numpy.ndarray, shape (nx,)", "The state after the (unprojected) "
                  "step."),
                 ("Fx", "numpy.ndarray, shape (ns, ns)", "``dx1_ind/dx_ind`` on the "
                  "independent state."),
                 ("Fr", "numpy.ndarray, shape (ns, nr)", "``dx1_ind/dr``.")],
                [("gen.InputError", "On a wrong shape, a NaN or infinite input, or a method "
                  "other than rk4."), "solver"])
    def step_sensitivity(self, t, x, h, *, r=None, p=None, method="rk4"):
        if method != "rk4":
            raise InputError(f"step_sensitivity supports method='rk4' (a fixed step); got "
                             f"{method!r}", "method", None, method)
        x1 = self._vec(x, self.nx, "state x").copy()
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        pp = self._params(p)
        Fx = np.empty(self.ns * self.ns, dtype=self.dtype)
        Fr = np.zeros(max(1, self.ns * self.nr), dtype=self.dtype)
        st = self._fn("step_sensitivity")(t, h, self._ptr(r), self._ptr(pp),
                                          self._ptr(x1), self._ptr(Fx), self._ptr(Fr))
        self._check(st, "step_sensitivity", t, x1, args={"x": x1, "r": r, "p": pp})
        return (x1, Fx.reshape(self.ns, self.ns),
                Fr[:self.ns * self.nr].reshape(self.ns, self.nr).copy())

    # ---------------------------------------------------- linearization
    @documented("""Linearize about any operating point (it need not be an equilibrium),
                in C, on the independent state ``[q_ind, u_ind]`` (sympy's
                ``A_and_B=True`` partition).""", ["x@op", "r@op", "p", "t=", "dt@zoh"],
                [("A", "numpy.ndarray, shape (ns, ns)", "(or Ad with dt)"),
                 ("B", "numpy.ndarray, shape (ns, nr)", "(or Bd with dt)")])
    def linearize(self, x, *, r=None, p=None, t=0.0, dt=None):
        return self._linearize(x, r, p, t, dt, False)

    @documented(""":meth:`linearize` and the outputs' ``C = dy/dx_ind`` (ny, ns) and ``D =
                dy/dr`` (ny, nr), in one C call (the dependent entries follow the
                constraints, as for A).""",
                ["x@op", "r@op", "p", "t=", ("dt", "float, optional", "A and B as the "
                                              "zero-order-hold discretization over dt (C "
                                              "and D are the same).")],
                [("A, B", "numpy.ndarray, shapes (ns, ns), (ns, nr)", "As :meth:`linearize`."),
                 ("C, D", "numpy.ndarray, shapes (ny, ns), (ny, nr)", "")])
    def linearize_outputs(self, x, *, r=None, p=None, t=0.0, dt=None):
        return self._linearize(x, r, p, t, dt, True)

    def _linearize(self, x, r, p, t, dt, outputs):
        x = self._vec(x, self.nx, "state x")
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        A = np.empty(self.ns * self.ns, dtype=self.dtype)
        B = np.zeros(max(1, self.ns * self.nr), dtype=self.dtype)
        if dt is not None:
            if not (np.isfinite(dt) and dt > 0):
                raise InputError(f"dt must be a positive number, got {dt!r}")
            st = self._fn("linearize_discrete")(self._ptr(x), self._ptr(r),
                                                self._ptr(self._params(p)), t, dt,
                                                self._ptr(A), self._ptr(B))
            self._check(st, "linearize_discrete", t, x)
        elif not outputs:
            st = self._fn("linearize")(self._ptr(x), self._ptr(r), self._ptr(self._params(p)),
                                       t, self._ptr(A), self._ptr(B))
            self._check(st, "linearize", t, x)
        if outputs:
            # one C call gives A, B, C, D; with dt its continuous A, B are
            # dropped (Ad, Bd came from linearize_discrete)
            Ac = A if dt is None else np.empty_like(A)
            Bc = B if dt is None else np.zeros_like(B)
            C = np.zeros(max(1, self.ny * self.ns), dtype=self.dtype)
            D = np.zeros(max(1, self.ny * self.nr), dtype=self.dtype)
            st = self._fn("linearize_outputs")(self._ptr(x), self._ptr(r),
                                               self._ptr(self._params(p)), t, self._ptr(Ac),
                                               self._ptr(Bc), self._ptr(C), self._ptr(D))
            self._check(st, "linearize_outputs", t, x)
            return (A.reshape(self.ns, self.ns),
                    B[:self.ns * self.nr].reshape(self.ns, self.nr).copy(),
                    C[:self.ny * self.ns].reshape(self.ny, self.ns).copy(),
                    D[:self.ny * self.nr].reshape(self.ny, self.nr).copy())
        return (A.reshape(self.ns, self.ns),
                B[:self.ns * self.nr].reshape(self.ns, self.nr).copy())

    @documented("""The linearization as a python-control ``StateSpace``, with its states,
                inputs and outputs named (``pip install eomgen[control]``).""",
                ["x@op", "r@op", "p", "t=", ("dt", "float, optional", "A discrete-time "
                                              "system with this sampling time (zero-order "
                                              "hold).")],
                [("", "control.StateSpace", "Outputs are the model's (C, D of "
                  ":meth:`linearize_outputs`), or the independent state (C = I, D = 0) for a "
                  "model without outputs.")],
                [("gen.MissingDependencyError", "When python-control is not installed (an "
                  "ImportError; ``pip install eomgen[control]``)."), "input", "solver"])
    def to_statespace(self, x, *, r=None, p=None, t=0.0, dt=None):
        control = require("control", "Simulator.to_statespace")
        names = list(self.independent_state_names)
        if self.ny:
            A, B, C, D = self.linearize_outputs(x, r=r, p=p, t=t, dt=dt)
            out_names = list(self.output_names)
        else:
            A, B = self.linearize(x, r=r, p=p, t=t, dt=dt)
            C, D = np.eye(self.ns), np.zeros((self.ns, self.nr))
            out_names = names
        kw = dict(states=names, inputs=list(self.input_names), outputs=out_names,
                  name=self.name)
        if dt is None:
            return control.ss(A, B, C, D, **kw)
        return control.ss(A, B, C, D, dt, **kw)

    # ------------------------------------------------------------ batches
    def _rows(self, a, n, width, what, allow_none=True):
        """None, one vector (stride 0) or an (n, width) array -> (array, stride)."""
        if a is None:
            if allow_none:
                return None, 0
            a = np.zeros(width)
        a = np.ascontiguousarray(a, dtype=self.dtype)
        if a.ndim == 1 and a.shape == (width,):
            return a, 0
        if a.shape == (n, width):
            return a, width
        raise InputError(f"{what} must have shape ({width},) or ({n}, {width}), got {a.shape}",
                         what.split()[-1])

    def _batch_fn(self, name):
        return functools.partial(call, self, None, self._fn(name))   # Ctrl-C: gen/sim/interrupt.py

    def _batch_check(self, idx, status, where, X, t=None):
        if idx >= 0:
            try:
                self._check(status, where, t, X[idx])
            except (ValueError, SolverError) as e:
                raise InputError(f"state {idx} of {len(X)}: {e}") if isinstance(e, ValueError) \
                    else type(e)(f"state {idx} of {len(X)}: {e}", status=e.status,
                                 status_name=e.status_name, time=e.time, state=e.state) from None

    @documented("x' for N states in one C call, the GIL released.",
                ["t@N", "X@N", "r@N", "p@N", ("out", "numpy.ndarray, shape (N, nx), optional",
                                              "A preallocated C-contiguous result.")],
                [("", "numpy.ndarray, shape (N, nx)", "")])
    def rhs_batch(self, t, X, *, r=None, p=None, out=None):
        if self._rhs_batch_fast is not None:
            # the host's CPython function (csrc/host/gen_host_fast.c): for a
            # number t and exact arrays of the right types and shapes; None
            # otherwise or when a state fails (the path below converts,
            # checks and names the state)
            res = self._rhs_batch_fast(t, X, r, p, out)
            if res is not None:
                return res
        X = np.ascontiguousarray(X, dtype=self.dtype)
        if X.ndim != 2 or X.shape[1] != self.nx:
            raise InputError(f"states must have shape (N, {self.nx}), got {X.shape}")
        n = X.shape[0]
        # (a Python number first: np.ndim costs a microsecond, a fifth of
        # the call's fixed cost)
        if isinstance(t, (float, int)) or np.ndim(t) == 0:
            T, ts = np.array([t], dtype=self.dtype), 0
        else:
            T, ts = np.ascontiguousarray(t, dtype=self.dtype), 1
            if T.shape != (n,):
                raise InputError(f"t must be a number or have shape ({n},), got {T.shape}")
        R, rs = self._rows(r, n, self.nr, "inputs r")
        P, ps = self._rows(p, n, self.np, "constants p")
        if out is None:
            out = np.empty((n, self.nx), dtype=self.dtype)
        elif out.shape != (n, self.nx) or out.dtype is not self._dt or not out.flags.c_contiguous:
            raise InputError(f"out must be a C-contiguous array of shape ({n}, {self.nx})")
        st = self._ffi.new("int *")
        idx = self._batch_fn("rhs_batch")(n, self._ptr(T), ts, self._ptr(X), self._ptr(R), rs,
                                           self._ptr(P), ps, self._ptr(out), st)
        self._batch_check(idx, st[0], "eval_rhs", X)
        return out

    @documented("M(q) for N configurations in one C call.",
                [("Q", "array_like, shape (N, nq) or (N, nx)", "Configurations (or states)."),
                 ("p", "array_like, shape (np,) or (N, np), optional", "The constants.")],
                [("", "numpy.ndarray, shape (N, nu, nu)", "")])
    def mass_matrix_batch(self, Q, *, p=None):
        Q = np.ascontiguousarray(Q, dtype=self.dtype)
        if Q.ndim != 2 or Q.shape[1] not in (self.nq, self.nx):
            raise InputError(f"coordinates must have shape (N, {self.nq}) or (N, {self.nx}), "
                             f"got {Q.shape}")
        n = Q.shape[0]
        P, ps = self._rows(p, n, self.np, "constants p")
        out = np.empty((n, self.nu, self.nu), dtype=self.dtype)
        st = self._ffi.new("int *")
        idx = self._batch_fn("mass_matrix_batch")(n, self._ptr(Q), Q.shape[1], self._ptr(P), ps,
                                                   self._ptr(out), st)
        self._batch_check(idx, st[0], "eval_mass_matrix", Q)
        return out

    @documented("(A, B) at N operating points in one C call.",
                [("X", "array_like, shape (N, nx)", "The operating states."),
                 ("r", "array_like, shape (nr,) or (N, nr), optional", "The operating inputs."),
                 ("p", "array_like, shape (np,) or (N, np), optional", "The constants."), "t="],
                [("A", "numpy.ndarray, shape (N, ns, ns)", ""),
                 ("B", "numpy.ndarray, shape (N, ns, nr)", "")])
    def linearize_batch(self, X, *, r=None, p=None, t=0.0):
        X = np.ascontiguousarray(X, dtype=self.dtype)
        if X.ndim != 2 or X.shape[1] != self.nx:
            raise InputError(f"operating points must have shape (N, {self.nx}), got {X.shape}")
        n = X.shape[0]
        R, rs = self._rows(r, n, self.nr, "inputs r")
        P, ps = self._rows(p, n, self.np, "constants p")
        A = np.empty((n, self.ns, self.ns), dtype=self.dtype)
        B = np.empty((n, self.ns, self.nr), dtype=self.dtype)
        st = self._ffi.new("int *")
        idx = self._batch_fn("linearize_batch")(n, self._ptr(X), self._ptr(R), rs, self._ptr(P),
                                                 ps, t, self._ptr(A),
                                                 self._ptr(B) if self.nr else self._ffi.NULL, st)
        self._batch_check(idx, st[0], "linearize", X, t)
        return A, B

    @documented("The outputs y for N states in one C call.", ["t@N", "X@N", "r@N", "p@N"],
                [("", "numpy.ndarray, shape (N, ny)", "Named by ``output_names``.")])
    def outputs_batch(self, t, X, *, r=None, p=None):
        X = np.ascontiguousarray(X, dtype=self.dtype)
        if X.ndim != 2 or X.shape[1] != self.nx:
            raise InputError(f"states X must have shape (N, {self.nx}), got {X.shape}", "X")
        n = X.shape[0]
        if np.ndim(t) == 0:
            T, ts = np.array([t], dtype=self.dtype), 0
        else:
            T, ts = np.ascontiguousarray(t, dtype=self.dtype), 1
            if T.shape != (n,):
                raise InputError(f"t must be a number or have shape ({n},), got {T.shape}", "t")
        R, rs = self._rows(r, n, self.nr, "inputs r")
        P, ps = self._rows(p, n, self.np, "constants p")
        out = np.empty((n, max(1, self.ny)), dtype=self.dtype)
        if self.ny == 0 or n == 0:
            return out[:, :0] if self.ny == 0 else out
        st = self._ffi.new("int *")
        idx = self._batch_fn("outputs_batch")(n, self._ptr(T), ts, self._ptr(X), self._ptr(R),
                                              rs, self._ptr(P), ps, self._ptr(out), st)
        self._batch_check(idx, st[0], "eval_outputs", X)
        return out

    # --------------------------------------------------------- ensembles
    @documented("""N simulations in C, reduced as they finish (or every row kept): in
                chunks on every core (threads, the GIL released) or on a Dask cluster
                (:doc:`/guides/ensembles`).

                Each run is exactly ``sim.simulate`` of its own x0, p, r (the same C
                path), so the results do not depend on chunk, workers or client. The
                options of the runs are simulate's: keywords, or
                ``options=gen.RunOptions(...)`` (a keyword given explicitly wins).""",
                [("x0", "array_like or dict", "One state for every run, an (N, nx) array, "
                  "or a dict ``{name: number or (N,) array}`` (other states 0); "
                  ":class:`gen.Sampler` draws such dicts."),
                 ("t_end", "float", "The final time."), "dt@run",
                 ("r", "optional", "Constant inputs (one row, (N, nr) or a dict), or a table "
                  "``(t_grid, R)`` shared by every run; a Python function is refused (it "
                  "would hold the GIL at every step)."),
                 ("p", "array_like or dict, optional", "One constant vector, (N, np), or a "
                  "dict (other constants their defaults)."),
                 ("controller", "gen.LinearFeedback, optional", "A feedback computed in C, "
                  "shared by every run."),
                 ("reduce", "str, reducer, callable or dict, optional", '``"final"`` (the '
                  'state at t_end, (N, nx)), ``"rows"`` (every row, (N, rows, nx), with '
                  "``res.t``), :class:`gen.At`, :class:`gen.Min`, :class:`gen.Max`, "
                  ":class:`gen.Mean`, a function ``f(t, X)`` called per chunk on its full "
                  "trajectories, or a dict ``{key: reducer}``."),
                 ("client", "dask.distributed.Client, optional", "Run the chunks on the "
                  "cluster's workers (each builds the model from its sources into its own "
                  "cache, by content)."),
                 ("chunk", "int, optional", "Runs per C call (default: a few chunks per "
                  "worker)."),
                 ("workers", "int, optional", "Threads (default: every core)."),
                 ("progress", "bool, optional", "A tqdm progress bar (None: on a terminal; "
                  "``pip install eomgen[ensemble]``)."),
                 (", ".join(n for n in OPTION_NAMES if n not in _KEPT_BY_REDUCERS), "",
                  "As for :meth:`simulate` (checked by the same code)."),
                 (", ".join(_KEPT_BY_REDUCERS), "", "Accepted as :meth:`simulate`'s; an "
                  "ensemble keeps what its reducers ask for, so ``every`` must be 1, "
                  '``final_only=True`` means ``reduce="final"``, and events are refused '
                  "(simulate the runs that need them)."), "options"],
                [("", "gen.EnsembleResult", "``res[key]`` per reducer, ``res.status``, "
                  "``res.failures`` (failed runs: NaN rows, their status and last state), "
                  "``res.runs_per_second``.")], ["run", "keyword"])
    def ensemble(self, x0, t_end, dt, *, r=None, p=None, controller=None, reduce="final",
                 client=None, chunk=None, workers=None, progress=None, options=None,
                 **keywords):
        opts = run_options(t_end, dt, options, keywords, "Simulator.ensemble")
        return run_ensemble(self, x0, opts, r=r, p=p, controller=controller, reduce=reduce,
                            client=client, chunk=chunk, workers=workers, progress=progress)

    ensemble.__signature__ = options_signature(ensemble)

    def __repr__(self):
        return (f"<eomgen Simulator '{self.name}' ({self.method}, {self.real}): "
                f"nq={self.nq} nu={self.nu} nr={self.nr} np={self.np} mc={self.mc} mv={self.mv}>")
