"""The optimal control problem (gen.OptimalControl): the user's problem
checked and transcribed (gen/design/ocp/transcription.py), its library
rendered, built, cached and opened through the pipeline as the OCP
backend's (gen.pipeline.product), assembled at every solve from its
current data (gen/design/ocp/layout.py) and solved by IPOPT
(gen/design/ocp/ipopt.py)."""
from __future__ import annotations

import math
import time

import numpy as np
import sympy as sm

from ... import pipeline
from ...core.errors import InputError, ModelError
from ...intake.model import require_model
from .ipopt import cyipopt, run_ipopt, status_message
from .events import read_events, solution_phases
from .guess import start_point
from .layout import assemble, index_tables
from .names import Names, read_instance
from .solution import OptimalSolution
from .transcription import METHODS, ocp_plan

__all__ = ["OptimalControl"]

# measured on the cart-pole (Hermite-Simpson, 2,001 and 8,001 nodes): peak
# bytes per unknown of a solve, and Jacobian nonzeros per unknown (about 4)
BYTES_PER_UNKNOWN = 4096
JAC_PER_UNKNOWN = 8


class OptimalControl:
    """A trajectory optimisation (or identification) problem on a model,
    transcribed by direct collocation and solved by IPOPT.

    Parameters
    ----------
    model : gen.Model
    nodes : int
        Number of nodes N (N - 1 intervals of equal length).
    duration : float or (lo, hi)
        The final time T (the initial time is 0); a pair: a free final time.
    objective : sympy expression, optional
        The running cost L(x, r, p, t), integrated by the method's rule.
    terminal_cost : sympy expression, optional
        A cost of the final state and time (t is the final time).
    method : str
        "backward-euler", "midpoint", "trapezoidal" or "hermite-simpson".
    bounds : dict, optional
        {state, input or free parameter: (lo, hi)}, applied at every node.
    initial, final : dict, optional
        {state: value}.
    constraints : list, optional
        Instance constraints in opty's form: expressions equal to zero in
        states at given times, e.g. ``theta.func(0) - theta.func(2.0)``.
    path : list, optional
        [(expr, lo, hi)]: lo <= expr(x, r, p, t) <= hi at every node.
    parameters : list, optional
        Constants to identify (unknowns of the problem).
    fit : dict, optional
        {state or output: (t_data, values)}: adds sum (y(t_i) - values_i)^2
        to the objective, y linearly interpolated between nodes.
    events : list of str, optional
        The model's hybrid declarations (``gen.Reset``, or ``gen.Impact``:
        its impulse an unknown of the problem), in order: one
        phase each, of ``nodes`` nodes and its own duration (free within
        ``duration``'s (lo, hi), which bounds every phase's). A phase's last
        node lies on its event's guard, crossing in its direction, and the
        event's map carries it into the next phase's first node
        (gen/design/ocp/events.py). ``initial`` is the first phase's first
        node, ``final`` and ``terminal_cost`` the last phase's last node (t:
        the total duration); a dict guess gives arrays over all the phases'
        nodes in order and ``"duration"`` a number or one per phase.
    periodic : bool, optional
        The state after the last event's map (without an event: the final
        state) equals the initial state: a limit cycle. ``sol.phases``
        gives each phase's times, states and the state after its event.

    ``bounds``, ``initial``, ``final``, ``constants``, ``duration`` (within
    fixed or free), ``path_bounds`` and ``fit`` are attributes that can be
    changed between solves without rebuilding the C.

    Raises
    ------
    gen.InputError
        A non-differentiable objective, a symbol that is not the model's, a
        key of bounds that is not a state, input or parameter to identify, a
        bad duration or method, a constrained model with a method other than
        "hermite-simpson", initial or final values that violate the model's
        constraints (before anything is built).
    gen.ModelError
        When ``model`` is not a gen.Model, or has auxiliary speeds (not
        supported yet).
    gen.BuildError
        When the compiler fails.
    """

    def __init__(self, model, nodes, duration, objective=None, terminal_cost=None,
                 method="hermite-simpson", bounds=None, initial=None, final=None,
                 constraints=None, path=None, parameters=None, fit=None, events=None,
                 periodic=False):
        require_model(model, "gen.OptimalControl")
        t0 = time.perf_counter()
        m = self.model = model
        if m.na:
            raise ModelError(f"model {m.name!r} has auxiliary speeds (reaction outputs): "
                             "gen.OptimalControl does not support them yet")
        if method not in METHODS:
            raise InputError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
        self.method = method
        if (m.mc or m.mv) and method != "hermite-simpson":
            # position, velocity and acceleration constraints at the nodes with
            # a velocity correction at the midpoints: Hermite-Simpson's form
            # (OpenSim Moco); the other rules would over-determine the DAE
            raise InputError(
                f"model {m.name!r} has {m.mc} configuration and {m.mv} velocity constraints: "
                "gen.OptimalControl transcribes constrained models with "
                f"method='hermite-simpson' only (got {method!r}); or use minimal coordinates")
        if m.mc and any(m.t in e.free_symbols for e in m.fc):
            raise InputError(f"model {m.name!r}: time-dependent configuration constraints are "
                             "not supported by gen.OptimalControl yet")
        if not isinstance(nodes, (int, np.integer)) or nodes < 2:
            raise InputError(f"nodes must be an integer >= 2, got {nodes!r}")
        self.nodes = int(nodes)
        self._events, self.periodic = read_events(self, events, periodic)
        self.events = list(events or [])
        self.phases = max(1, len(self.events))
        self._names = nm = Names(m)
        self.duration = duration
        self._check_duration(duration)
        self.free_time = not np.isscalar(duration)
        if self.phases > 1 and not self.free_time:
            raise InputError(f"events={self.events!r}: each phase's duration is free; give "
                             f"duration as (lo, hi), the bounds of every phase's, not {duration!r}")
        # parameters to identify
        self.parameters = list(parameters or [])
        self._pf = []
        for k in self.parameters:
            kind, i = nm.key(k, "parameters")
            if kind != "p":
                raise InputError(f"parameters: {k} is not a constant of model {m.name!r}")
            self._pf.append(i)
        self._check_size()
        # user expressions, in internal symbols
        self._L = nm.expr(objective, "objective", allow_y=True) if objective is not None else None
        self._phi = (nm.expr(terminal_cost, "terminal_cost", allow_y=True)
                     if terminal_cost is not None else None)
        self._path = []
        for j, item in enumerate(path or []):
            try:
                e, lo, hi = item
            except (TypeError, ValueError):
                raise InputError(f"path[{j}] must be (expr, lo, hi), got {item!r}") from None
            self._path.append(nm.expr(e, f"path[{j}]", allow_y=True))
        self.path_bounds = [(float(lo), float(hi)) for _, lo, hi in (path or [])]
        self._instance, self._inst_refs = read_instance(nm, m, constraints or [])
        self._fit_keys = []
        for k in (fit or {}):
            kind, i = nm.key(k, "fit")
            if kind not in ("x", "y"):
                raise InputError(f"fit: {k} is not a state or an output of model {m.name!r}")
            self._fit_keys.append((kind, i))
        self.fit = fit
        if self._L is None and self._phi is None and not self._fit_keys:
            raise InputError("nothing to minimise: give an objective, a terminal_cost or fit data")
        if self.free_time and self._fit_keys:
            raise InputError("fit data need a fixed duration (a number), not a free final time")
        # runtime data (changeable)
        self.bounds = bounds or {}
        self.initial = initial or {}
        self.final = final or {}
        self.constants = {}
        self._check_runtime()
        self._fixed_manifold_nodes()     # inconsistent initial/final values: refused now
        self._build()
        self.build_seconds = time.perf_counter() - t0
        self._sim = None

    # --------------------------------------------------------- checks
    def _unknowns(self):
        """The number of unknowns of the transcription at self.nodes (the
        Layout's count, without building it)."""
        m, N = self.model, self.nodes
        nx, nr, mv, mc = m.nq + m.nu, m.nr, m.mv, m.mc
        node = nx + nr + (0 if self.method == "midpoint" else nx + mv)
        mid = {"hermite-simpson": 2 * nx + nr + mv + mc, "midpoint": nx + mv}.get(self.method, 0)
        P = max(1, len(self.events))
        return P * (N * node + (N - 1) * mid + 1) + len(self._pf)

    def _check_size(self):
        """Refuses, before anything is allocated, a problem past the memory
        available (measured: about BYTES_PER_UNKNOWN per unknown, from the
        assembly's tables to IPOPT's factors) or past the C index tables'
        32-bit range, naming the nodes and the unknowns."""
        from ...sim.options import memory_available
        n = self._unknowns()
        need = n * BYTES_PER_UNKNOWN
        avail = memory_available()
        if n * JAC_PER_UNKNOWN >= 2**31 or (avail is not None and need > avail):
            where = ("more than the 2**31 nonzeros the C index tables can address"
                     if n * JAC_PER_UNKNOWN >= 2**31 else
                     f"more than the {avail / 2**30:.1f} GiB of memory available")
            raise InputError(f"nodes={self.nodes}: the transcription ({self.method}) would have "
                             f"{n:,} unknowns and need about {need / 2**30:.1f} GiB, {where}; "
                             "use fewer nodes (a solution on a coarse grid is a good guess "
                             "for a finer one)")

    def _check_duration(self, d):
        if np.isscalar(d):
            if not (isinstance(d, (int, float, np.number)) and math.isfinite(d) and d > 0):
                raise InputError(f"duration must be a positive number or (lo, hi), got {d!r}")
        else:
            try:
                lo, hi = (float(v) for v in d)
            except (TypeError, ValueError):
                raise InputError(f"duration must be a positive number or (lo, hi), got {d!r}") \
                    from None
            if not (0 < lo <= hi) or not math.isfinite(hi):
                raise InputError(f"duration = ({lo}, {hi}): need 0 < lo <= hi < inf")

    def _check_runtime(self):
        """Names every unknown key of bounds, initial, final and constants."""
        nm = self._names
        for what, d in (("bounds", self.bounds), ("initial", self.initial),
                        ("final", self.final)):
            if not isinstance(d, dict):
                raise InputError(f"{what} must be a dict, got {type(d).__name__}")
            for k, v in d.items():
                kind, i = nm.key(k, what)
                if what == "bounds":
                    if kind == "p" and i not in self._pf:
                        raise InputError(f"bounds: {k} is a known constant, not one of the "
                                         "parameters to identify")
                    self._bound(k, v)
                else:
                    if kind != "x":
                        raise InputError(f"{what}: {k} is not a state of model {self.model.name!r}")
                    nm.number(v, f"{what}[{k}]")
        for k, v in self.constants.items():
            kind, i = nm.key(k, "constants")
            if kind != "p":
                raise InputError(f"constants: {k} is not a constant of model {self.model.name!r}")
            nm.number(v, f"constants[{k}]")
        if len(self.path_bounds) != len(self._path):
            raise InputError("path_bounds must have one (lo, hi) per path constraint")

    def _bound(self, k, v):
        """(lo, hi) of bounds[k]: numbers (strings read in the model's
        symbols), -inf/inf for none; NaN and lo > hi refused naming k."""
        nm = self._names
        try:
            lo, hi = v
        except (TypeError, ValueError):
            raise InputError(f"bounds[{k}] must be (lo, hi), got {v!r}") from None
        out = []
        for side, b in (("lo", lo), ("hi", hi)):
            e = nm.parse(b, f"bounds[{k}]") if isinstance(b, str) else b
            try:
                f = float(e)
            except (TypeError, ValueError):
                raise InputError(f"bounds[{k}] = {v!r}: {side} = {b!r} is not a number") from None
            if math.isnan(f):
                raise InputError(f"bounds[{k}] = ({lo}, {hi}): {side} is NaN, not a number; "
                                 "give a number, or -inf/inf for no bound")
            out.append(f)
        if out[0] > out[1]:
            raise InputError(f"bounds[{k}] = ({lo}, {hi}): lo must be <= hi")
        return tuple(out)

    def _values(self, what):
        """{(kind, index): float} of initial or final, strings read in the
        model's symbols."""
        nm = self._names
        return {nm.key(k, what): nm.number(v, f"{what}[{k}]")
                for k, v in getattr(self, what).items()}

    # --------------------------------------------------------- build
    def _build(self):
        """Transcribe, render, build (or find in the cache) and open the
        library: the OCP backend through the pipeline (gen.pipeline.product,
        gen/codegen/backends/ OcpBackend)."""
        plan, self._meta = ocp_plan(self)
        built, self._ffi, self._lib = pipeline.product(plan, "ocp")
        iface = built.interface
        self._prefix = iface.name
        self._lib_path = built.path
        # the codes of <prefix>_eval, from the interface description
        self._what = {w: iface.value(f"GEN_RT_OCP_{w.upper()}")
                      for w in ("objective", "gradient", "constraints", "jacobian", "hessian")}
        self._eval = getattr(self._lib, f"{self._prefix}_eval")
        self._work = np.zeros(getattr(self._lib, f"{self._prefix}_work_len")())

    # --------------------------------------------------------- assembly
    def _assemble(self):
        """The layout, the gathers and scatters, bounds: everything a solve
        needs that is not compiled (gen/design/ocp/layout.py)."""
        self._check_runtime()
        key = self._assembly_key()
        if key == getattr(self, "_asm_key", None):
            return                  # the same structure, rows and data: kept
        a = assemble(self, self._meta)
        self._lay = a.lay
        self._m_rows = a.rows
        self._rows0 = {name: b.row0 for name, b in a.blocks.items()}
        self._cl, self._cu = np.array(a.row_lo, float), np.array(a.row_hi, float)
        blocks = list(a.blocks.values())
        self._arrays, (self._jrows, self._jcols), (self._hrows, self._hcols) = \
            index_tables(blocks)
        self._cblocks = self._c_blocks(blocks, self._arrays)
        self._nblocks = len(blocks)
        self._n = a.lay.n
        self._asm_key = key

    def _assembly_key(self):
        """What the assembly depends on besides the compiled families: the
        nodes and method, a fixed duration (the instance constraints' and
        fit data's nodes), the path bounds, the fit data and the end nodes
        whose manifold rows the boundary values fix. The bounds, boundary
        values and constants are arguments of every solve, not in it."""
        fit = tuple((np.asarray(td, float).tobytes(), np.asarray(v, float).tobytes())
                    for td, v in (self.fit or {}).values())
        skip = tuple(sorted((k, tuple(sorted(v))) for k, v in self._fixed_manifold_nodes().items()))
        return (self.method, self.nodes, self.phases,
                None if self.free_time else float(self.duration),
                tuple(tuple(map(float, b)) for b in self.path_bounds), fit, skip)

    def _c_blocks(self, blocks, arrays):
        """The blocks as the library's gen_rt_ocp_block array over the
        index tables (kept alive in self._arrays)."""
        ffi = self._ffi
        cblocks = ffi.new("gen_rt_ocp_block[]", len(blocks))
        for cb, b, arrs in zip(cblocks, blocks, arrays):
            cb.family = b.fi
            cb.ninst = len(b.gathers)
            for k, a in arrs.items():
                if a is None:
                    setattr(cb, k, ffi.NULL)
                else:
                    ctype = "int *" if a.dtype == np.int32 else "double *"
                    setattr(cb, k, ffi.cast(ctype, a.ctypes.data))
        return cblocks

    def _fixed_manifold_nodes(self):
        """The end nodes whose initial or final values fix the constraints'
        arguments: there the position (all q given) or velocity (all q and u
        given) constraint rows would repeat the fixed values and make the
        equality constraints linearly dependent (IPOPT needs them independent),
        so they are left out after checking that the given values satisfy
        them. {"holonomic": {k}, "velocity": {k}}."""
        m, N, nm = self.model, self.nodes, self._names
        skip = {"holonomic": set(), "velocity": set()}
        if not (m.mc or m.mv):
            return skip
        pv = self._pvec()
        for what, k0 in (("initial", 0), ("final", N - 1)):
            given = {i: v for (_, i), v in self._values(what).items()}
            q_all = all(i in given for i in range(m.nq))
            x_all = q_all and all(m.nq + i in given for i in range(m.nu))
            if not q_all:
                continue
            sub = {m.t: 0.0 if k0 == 0 else float(np.mean(np.atleast_1d(self.duration)))}
            sub.update({s_: pv[i] for i, s_ in enumerate(m.p)})
            sub.update({m.q[i]: given[i] for i in range(m.nq)})
            checks = [("holonomic", m.fc, "configuration")]
            if x_all:
                sub.update({m.u[i]: given[m.nq + i] for i in range(m.nu)})
                checks.append(("velocity", m.A * sm.Matrix(m.u) + m.b, "velocity"))
            for name, expr, label in checks:
                if not expr.shape[0]:
                    continue
                res = [float(e.xreplace(sub).evalf()) for e in expr]
                if max(abs(r) for r in res) > 1e-9:
                    vals = ", ".join(f"{k}={v}" for k, v in getattr(self, what).items())
                    raise InputError(
                        f"{what} values ({vals}) violate model {m.name!r}'s {label} "
                        f"constraints (residuals {res}): give a consistent state")
                skip[name].add(k0)
        return skip

    def _fit_data(self, j):
        keys = list(self.fit)
        td, vals = self.fit[keys[j]]
        td = np.asarray(td, float).ravel()
        vals = np.asarray(vals, float).ravel()
        if td.shape != vals.shape:
            raise InputError(f"fit[{keys[j]}]: t_data and values differ in length "
                             f"({td.size} and {vals.size})")
        T = float(self.duration)
        if np.any(~np.isfinite(td)) or np.any(~np.isfinite(vals)):
            raise InputError(f"fit[{keys[j]}]: t_data and values must be finite")
        if td.size and (td.min() < 0 or td.max() > T * (1 + 1e-12)):
            raise InputError(f"fit[{keys[j]}]: the data times must lie in [0, {T}]")
        return td, vals

    # --------------------------------------------------------- evaluation
    def _call(self, what, z, nout, lam=None, sigma=0.0):
        out = np.zeros(nout)
        z = np.ascontiguousarray(z, float)
        ffi = self._ffi
        lp = ffi.NULL
        if lam is not None:
            lam = np.ascontiguousarray(lam, float)
            lp = ffi.cast("double *", lam.ctypes.data)
        st = self._eval(self._cblocks, self._nblocks, ffi.cast("double *", z.ctypes.data),
                        ffi.cast("double *", self._p.ctypes.data), what, lp, sigma,
                        ffi.cast("double *", self._work.ctypes.data), nout,
                        ffi.cast("double *", out.ctypes.data))
        if st:
            raise ModelError(f"the optimal-control kernels returned status {st}")
        return out

    def _pvec(self):
        m = self.model
        p = np.array(m.p_values, float)
        nm = self._names
        for k, v in self.constants.items():
            _, i = nm.key(k, "constants")
            if i in self._pf:
                raise InputError(f"constants: {k} is a parameter to identify; give its guess "
                                 "or bounds instead")
            p[i] = nm.number(v, f"constants[{k}]")
        return p

    def _var_bounds(self):
        m, lay, N = self.model, self._lay, self.nodes
        BIG = 1e20
        lb = np.full(lay.n, -BIG)
        ub = np.full(lay.n, BIG)
        nm = self._names
        for k, v in self.bounds.items():
            kind, i = nm.key(k, "bounds")
            lo, hi = self._bound(k, v)
            lo, hi = max(lo, -BIG), min(hi, BIG)
            if kind == "x":
                idx = [X[i] for X in lay.X + lay.XM]
            elif kind == "r":
                idx = [R[i] for R in lay.R + lay.RM]
            else:
                idx = [lay.P[self._pf.index(i)]]
            lb[idx], ub[idx] = lo, hi
        for what, k0 in (("initial", 0), ("final", lay.NN - 1)):
            for k, v in getattr(self, what).items():
                _, i = nm.key(k, what)
                v = nm.number(v, f"{what}[{k}]")
                j = lay.X[k0][i]
                if not lb[j] <= v <= ub[j]:
                    raise InputError(f"{what}[{k}] = {v} is outside its bounds "
                                     f"({lb[j]}, {ub[j]})")
                lb[j] = ub[j] = v
        if self.free_time:
            lb[lay.Ts], ub[lay.Ts] = (float(v) for v in self.duration)
        else:
            lb[lay.T] = ub[lay.T] = float(self.duration)
        return lb, ub

    def _layout_key(self):
        return (self.method, self.nodes, self.model.mv, self.model.mc, len(self._pf),
                self.phases)

    # --------------------------------------------------------- solve
    def solve(self, guess=None, *, hessian="exact", **ipopt_options):
        """Solve with IPOPT.

        Parameters
        ----------
        guess : None, dict, gen.OptimalSolution or array, optional
            None: states linear from the initial to the final values, inputs
            zero. A dict {state or input: value or array over the nodes,
            parameter: value, "duration": T}. A previous solution (a warm
            start). Or the whole vector of unknowns.
        hessian : {"exact", "limited-memory"}
            The exact Hessian of the Lagrangian (generated), or IPOPT's
            L-BFGS approximation.
        **ipopt_options
            IPOPT options (``tol=1e-10``, ``max_iter=500``, ``print_level=5``, ...).

        Returns
        -------
        gen.OptimalSolution
            IPOPT's outcome is ``status``/``message``; a failed solve is
            returned, not raised.

        Raises
        ------
        gen.MissingDependencyError
            When cyipopt is not installed (``pip install eomgen[ocp]``).
        gen.InputError
            A bad option, guess, bound, boundary value or fit data.
        """
        cyipopt()
        if hessian not in ("exact", "limited-memory"):
            raise InputError(f"hessian must be 'exact' or 'limited-memory', got {hessian!r}")
        self._check_duration(self.duration)
        if self.free_time == np.isscalar(self.duration):
            raise InputError("duration: a fixed duration cannot become free (or the reverse) "
                             "without a new OptimalControl")
        t0 = time.perf_counter()
        self._assemble()
        self._p = self._pvec()
        lb, ub = self._var_bounds()
        z0 = start_point(self, guess, lb, ub)
        z, info, iterations = run_ipopt(self, z0, lb, ub, hessian, ipopt_options)
        solve_seconds = time.perf_counter() - t0
        status, msg = status_message(info)
        sol = OptimalSolution._make(self, np.asarray(z, float), float(info["obj_val"]), status,
                                    msg, iterations, solve_seconds)
        sol.first_iterate = info["first_iterate"]
        sol.phases = solution_phases(self, sol)
        return sol

    # --------------------------------------------------------- helpers
    @property
    def simulator(self):
        """A compiled gen.Simulator of the same model (gen.compile), built
        on first use: replays and tracking."""
        if self._sim is None:
            self._sim = pipeline.compile(self.model)
        return self._sim

    def evaluate(self, z, what):
        """The problem's functions, in C, at the unknowns z (after a solve
        or its assembly): for checks.

        Parameters
        ----------
        z : ndarray
            The vector of unknowns.
        what : str
            "objective", "gradient", "constraints", "jacobian" (the nonzeros)
            or "hessian" (the lower triangle's nonzeros, multipliers 1, objective factor 1).

        Returns
        -------
        ndarray
        """
        sizes = {"objective": 1, "gradient": self._lay.n, "constraints": self._m_rows,
                 "jacobian": len(self._jrows)}
        if what == "hessian":
            return self._call(self._what["hessian"], z, len(self._hrows),
                              np.ones(self._m_rows), 1.0)
        return self._call(self._what[what], z, sizes[what])
