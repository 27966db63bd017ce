"""Optimal control by direct collocation on the model's implicit equations
(issue 34): trajectories, free final times and parameter identification,
solved by IPOPT (cyipopt) with the exact Hessian of the Lagrangian.

    ocp = gen.OptimalControl(model, 101, 2.0, objective=F**2,
                             bounds={F: (-20, 20), x: (-1.5, 1.5)},
                             initial={x: 0, theta: sm.pi, v: 0, omega: 0},
                             final={x: 0, theta: 0, v: 0, omega: 0})
    sol = ocp.solve()                  # a gen.OptimalSolution
    sol.objective, sol.t, sol.x, sol.r, sol(0.5)

The transcription. Every collocation point (the nodes, the midpoints, or
both: the method decides) carries the slopes s = [q', u'] of the state as
unknowns, and the model's implicit equations hold there:

    kinematics   Kqd(q) q' + Ku(q) u + kf(q, t) = 0
    dynamics     M(q) u' - f(q, u, r, p, t) - A(q)^T lam = 0

with lam the velocity constraints' multipliers (unknowns at every point;
for Kane's method M and f are the unconstrained equations of all the
speeds, so A^T lam is the constraint force). Constrained models
(method "hermite-simpson" only, OpenSim Moco's form) keep the
configuration, velocity and acceleration constraints f_c(q) = 0,
A u + b = 0 and A u' + a = 0 at every node, and a velocity correction
Jc(q)^T mu of the midpoint's coordinate slopes in Simpson's rule (mu zero
for the DAE): the model stays a DAE and nothing is inverted symbolically.
At an end node whose initial or final values give all of q (and u), the
configuration (and velocity) rows are checked on those values and left
out: kept, they would repeat the fixed values and IPOPT's equality
constraints would be linearly dependent. The
defects tie the states to the slopes, linearly (h = T/(N-1)):

    backward-euler   x[k+1] - x[k] - h s[k+1]                   (points: nodes 1..N-1)
    midpoint         x[k+1] - x[k] - h s[k+1/2], at the point ((x[k] + x[k+1])/2,
                     (r[k] + r[k+1])/2)                          (points: midpoints)
    trapezoidal      x[k+1] - x[k] - h/2 (s[k] + s[k+1])         (points: nodes)
    hermite-simpson  separated form: the midpoint state x[k+1/2] and input
                     r[k+1/2] are unknowns with
                     x[k+1/2] - (x[k] + x[k+1])/2 - h/8 (s[k] - s[k+1]) = 0,
                     x[k+1] - x[k] - h/6 (s[k] + 4 s[k+1/2] + s[k+1]) = 0
                                                                 (points: nodes and midpoints)

Backward Euler and midpoint are opty's transcriptions (the slopes,
eliminated, give its defects). The running cost is integrated by the
method's rule (h sum over nodes 1..N-1; h sum over midpoints; trapezoid;
Simpson) and the final time T is always a variable, fixed by its bounds
when ``duration`` is a number.

The C. Each piece (the point equations, the manifold, the defects, the
running and terminal costs, the path and instance constraints, the fits)
is a family of three generated kernels over its local variables: values,
the sparse Jacobian, and the lower triangle of the Hessian of
sum_i lam_i g_i, from one CSE'd graph each (gen.ir). The runtime
(csrc/gen_rt_ocp.c) loops over the instances of every family in C, once
per IPOPT callback: it gathers each instance's locals from the decision
vector, calls the kernels and scatters into IPOPT's arrays through index
tables this module computes. Bounds, initial and final values, known
constants, path bounds, the duration and the fit data are arguments of
those calls, never compiled in; the library is cached by content
(gen.cache, gen.build).
"""
from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import dataclass, field

import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

from .._version import __version__
from ..core.errors import InputError, MissingDependencyError, ModelError
from ..intake.model import require_model

__all__ = ["OptimalControl", "OptimalSolution", "METHODS"]

METHODS = ("backward-euler", "midpoint", "trapezoidal", "hermite-simpson")

_NONSMOOTH = (sm.Abs, sm.sign, sm.Heaviside, sm.floor, sm.ceiling, sm.Min, sm.Max,
              sm.Piecewise, sm.Mod)

# IPOPT's return statuses in plain words (IpReturnCodes.h)
IPOPT_MESSAGES = {
    0: "solved: an optimum was found to the requested tolerance",
    1: "solved to the acceptable tolerance only (not the requested one)",
    2: "the problem is infeasible: IPOPT converged to a point that violates the "
       "constraints least, not to a feasible one; check the bounds, the initial and final "
       "values, the path constraints and the duration",
    3: "stopped: the search direction became too small (the problem may be badly scaled)",
    4: "the iterates diverged: a variable grew without bound (add bounds)",
    5: "stopped at the user's request",
    6: "a feasible point was found (the objective was not minimised further)",
    -1: "not solved: the maximum number of iterations was reached "
        "(raise max_iter, or give a better guess)",
    -2: "not solved: the restoration phase failed to find a feasible point "
        "(the problem is likely infeasible)",
    -3: "not solved: an error in the step computation (the problem may be singular)",
    -4: "not solved: the maximum CPU time was reached",
    -5: "not solved: the maximum wall time was reached",
    -10: "not solved: not enough degrees of freedom (more equality constraints than "
         "variables: the initial, final and instance constraints over-determine the problem)",
    -11: "not solved: invalid problem definition",
    -12: "not solved: an invalid IPOPT option",
    -13: "not solved: a NaN or infinite value was computed (the model is undefined at "
         "some iterate; add bounds)",
}


def _cyipopt():
    try:
        import cyipopt
    except ImportError:
        raise MissingDependencyError(
            "gen.OptimalControl solves with IPOPT through cyipopt, which is not installed: "
            "pip install eomgen[ocp] (or pip install cyipopt-wheels)") from None
    return cyipopt


# ------------------------------------------------------------- symbols
class _Names:
    """The model's symbols as the user writes them -> internal symbols."""

    def __init__(self, m):
        self.m = m
        self.sub = {}
        self.label = {}
        t_user = me.dynamicsymbols._t
        for orig, s, name in zip(list(m.q_orig) + list(m.u_orig), list(m.q) + list(m.u),
                                 m.state_names):
            self.sub[orig] = s
            self.label[s] = name
        for orig, s, name in zip(m.r_orig, m.r, m.input_names):
            self.sub[orig] = s
            self.label[s] = name
        for orig, s, name in zip(m.p_orig, m.p, m.constant_names):
            self.sub[orig] = s
            self.label[s] = name
        self.sub[t_user] = m.t
        self.label[m.t] = "t"
        self.states = list(m.q) + list(m.u)
        self.by_name = {}
        for i, n in enumerate(m.state_names):
            self.by_name[n] = ("x", i)
        for i, n in enumerate(m.input_names):
            self.by_name[n] = ("r", i)
        for i, n in enumerate(m.constant_names):
            self.by_name[n] = ("p", i)
        for i, n in enumerate(m.output_names):
            self.by_name.setdefault(n, ("y", i))
        self.state_funcs = {}       # theta (the function class) -> state index
        for i, orig in enumerate(list(m.q_orig) + list(m.u_orig)):
            if isinstance(orig, sm.core.function.AppliedUndef):
                self.state_funcs[orig.func] = i

    def key(self, k, what):
        """('x'|'r'|'p'|'y', index) of a user key: a sympy object or a name."""
        if isinstance(k, str):
            if k in self.by_name:
                return self.by_name[k]
            raise InputError(f"{what}: {k!r} is not a state, input or constant of model "
                             f"{self.m.name!r}")
        s = self.sub.get(sm.sympify(k))
        if s is not None:
            if s in self.m.q or s in self.m.u:
                return ("x", self.states.index(s))
            if s in self.m.r:
                return ("r", self.m.r.index(s))
            if s in self.m.p:
                return ("p", self.m.p.index(s))
        raise InputError(f"{what}: {k} is not a state, input or constant of model "
                         f"{self.m.name!r}")

    def expr(self, e, what, allow_y=False):
        """A user expression in internal symbols; unknown symbols are named."""
        try:
            e = sm.sympify(e)
        except (sm.SympifyError, TypeError) as err:
            raise InputError(f"{what}: cannot read {e!r} as a sympy expression ({err})") from None
        bad = [a for a in e.atoms(*_NONSMOOTH)] if e.has(*_NONSMOOTH) else []
        if bad:
            raise InputError(
                f"{what} = {e} is not differentiable: it holds {bad[0].func.__name__} "
                f"({bad[0]}); IPOPT needs twice-differentiable functions. Write a smooth "
                "form instead (e.g. sqrt(x**2 + eps**2) for Abs(x), or a slack variable with "
                "a path constraint)")
        out = e.xreplace(self.sub)
        if allow_y and self.m.ny:
            out = out.xreplace({sm.Symbol(n): y for n, y in zip(self.m.output_names, self.m.y)})
        known = set(self.m.q) | set(self.m.u) | set(self.m.r) | set(self.m.p) | {self.m.t}
        unknown = sorted({str(s) for s in out.free_symbols if s not in known})
        undef = sorted({str(f) for f in out.atoms(sm.core.function.AppliedUndef)})
        if unknown or undef:
            raise InputError(f"{what} = {e} holds {', '.join(unknown + undef)}, not a state, "
                             f"input or constant of model {self.m.name!r} (nor t)")
        return out


# ------------------------------------------------------------- families
@dataclass
class _Family:
    """A piece of the problem: exprs over the locals (internal symbols or
    dummies), nd instance data symbols, objective or constraint rows."""
    name: str
    locals: list
    exprs: list
    data: list = field(default_factory=list)
    objective: bool = False
    # filled by _kernels
    jac: list = field(default_factory=list)      # [(row, local)]
    hess: list = field(default_factory=list)     # [(a, b)] a >= b


def _kernels(fam, psyms):
    """(C function sources, fam with its Jacobian and Hessian patterns)."""
    from ..plan.ir import Arg, make_jacobian_kernel, make_kernel, prune
    from ..sym.graph import gradient
    loc = list(fam.locals)
    # a constant among the locals (a parameter to identify) is read from v, not p
    psyms = [sm.Dummy(f"unused{i}") if s in loc else s for i, s in enumerate(psyms)]
    lams = [sm.Dummy(f"lam{i}") for i in range(len(fam.exprs))]
    args = [Arg("v", tuple(loc)), Arg("p", tuple(psyms)), Arg("d", tuple(fam.data)),
            Arg("lam", tuple(lams))]
    F = sm.Matrix(fam.exprs)
    kval = make_kernel(f"{fam.name}_val", args, [("g", F)])
    kjac = make_jacobian_kernel(f"{fam.name}_jac", args, [], [("J", F, loc)])
    J = kjac.outputs[0]
    fam.jac = [(i // J.cols, i % J.cols) for i, e in enumerate(J.exprs) if e != 0]
    J.exprs = [e for e in J.exprs if e != 0]
    J.rows, J.cols = len(J.exprs), 1
    prune(kjac)
    phi = sm.Add(*[lam * e for lam, e in zip(lams, fam.exprs)])
    g = gradient(phi, loc)
    G = sm.Matrix([g.get(s, sm.S.Zero) for s in loc])
    khess = make_jacobian_kernel(f"{fam.name}_hess", args, [], [("H", G, loc)])
    H = khess.outputs[0]
    n = len(loc)
    keep = [(i // n, i % n) for i, e in enumerate(H.exprs) if e != 0 and i // n >= i % n]
    H.exprs = [H.exprs[a * n + b] for a, b in keep]
    H.rows, H.cols = len(H.exprs), 1
    fam.hess = keep
    prune(khess)
    return [_c_function(k, args) for k in (kval, kjac, khess)]


def _c_function(kernel, args):
    from ..sym.printers import ModelCPrinter, kernel_statements
    smap = {}
    for a in args:
        for i, s in enumerate(a.symbols):
            smap[s] = f"{a.name}[{i}]"
    for s, _ in kernel.assignments:
        smap[s] = s.name
    pr = ModelCPrinter(smap, "double")
    temps, stores = kernel_statements(kernel, pr, reads=False)
    out = kernel.outputs[0].name
    return {"name": kernel.name, "out": f"out_{out}",
            "lines": [line for _, line, _ in temps] + stores}


# ------------------------------------------------------------- layout
class _Layout:
    """Where every unknown lives in the decision vector z, and the
    collocation points."""

    def __init__(self, method, N, nq, nu, nr, mv, mc, npf):
        nx = nq + nu
        self.N, self.nx, self.nr = N, nx, nr
        n = 0

        def take(k):
            nonlocal n
            a = list(range(n, n + k))      # plain ints: assembly indexes them often
            n += k
            return a
        node_pt = {"backward-euler": lambda k: k > 0, "midpoint": lambda k: False,
                   "trapezoidal": lambda k: True, "hermite-simpson": lambda k: True}[method]
        mid_pt = method in ("midpoint", "hermite-simpson")
        self.X, self.R, self.XM, self.RM = [], [], [], []
        self.points = []        # (x terms, r terms, s, lam, mu, time fraction, own state)
        self.node_point, self.mid_point = {}, {}
        for k in range(N):
            self.X.append(take(nx))
            self.R.append(take(nr))
            if node_pt(k):
                self.node_point[k] = (take(nx), take(mv), take(0))
            if k < N - 1 and mid_pt:
                if method == "hermite-simpson":
                    self.XM.append(take(nx))
                    self.RM.append(take(nr))
                # (slopes, multipliers, the midpoint's velocity correction)
                self.mid_point[k] = (take(nx), take(mv),
                                     take(mc if method == "hermite-simpson" else 0))
        self.P = take(npf)
        self.T = int(take(1)[0])
        self.n = n
        for k in range(N):
            if k in self.node_point:
                s, lam, mu = self.node_point[k]
                self.points.append(([(self.X[k], 1.0)], [(self.R[k], 1.0)], s, lam, mu,
                                    k / (N - 1), ("node", k)))
            if k in self.mid_point:
                s, lam, mu = self.mid_point[k]
                if method == "hermite-simpson":
                    xs, rs = [(self.XM[k], 1.0)], [(self.RM[k], 1.0)]
                else:
                    xs = [(self.X[k], 0.5), (self.X[k + 1], 0.5)]
                    rs = [(self.R[k], 0.5), (self.R[k + 1], 0.5)]
                self.points.append((xs, rs, s, lam, mu, (k + 0.5) / (N - 1), ("mid", k)))


def _terms(parts, i):
    """The gather terms of element i of a sum of (index array, coef)."""
    return [(int(idx[i]), c) for idx, c in parts]


class _Block:
    """One family's instances: gathers, data, rows (assembled to arrays)."""

    def __init__(self, fi, fam):
        self.fi, self.fam = fi, fam
        self.gathers, self.data, self.row0 = [], [], []

    def add(self, gather, data=(), row0=-1):
        assert len(gather) == len(self.fam["locals"]), (self.fam["name"], len(gather))
        self.gathers.append(gather)
        self.data.append(list(data))
        self.row0.append(row0)


# ------------------------------------------------------------- the problem
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
                 constraints=None, path=None, parameters=None, fit=None):
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
        self._names = nm = _Names(m)
        self.duration = duration
        self._check_duration(duration)
        self.free_time = not np.isscalar(duration)
        # parameters to identify
        self.parameters = list(parameters or [])
        self._pf = []
        for k in self.parameters:
            kind, i = nm.key(k, "parameters")
            if kind != "p":
                raise InputError(f"parameters: {k} is not a constant of model {m.name!r}")
            self._pf.append(i)
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
        self._instance, self._inst_refs = self._read_instance(constraints or [])
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
        self._lib = None
        self._build()
        self.build_seconds = time.perf_counter() - t0
        self._sim = None

    # --------------------------------------------------------- checks
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
                    try:
                        lo, hi = (float(x) for x in v)
                    except (TypeError, ValueError):
                        raise InputError(f"bounds[{k}] must be (lo, hi), got {v!r}") from None
                    if lo > hi or math.isnan(lo) or math.isnan(hi):
                        raise InputError(f"bounds[{k}] = ({lo}, {hi}): lo must be <= hi")
                else:
                    if kind != "x":
                        raise InputError(f"{what}: {k} is not a state of model {self.model.name!r}")
                    if not math.isfinite(float(v)):
                        raise InputError(f"{what}[{k}] = {v}: not a finite number")
        for k, v in self.constants.items():
            kind, i = nm.key(k, "constants")
            if kind != "p":
                raise InputError(f"constants: {k} is not a constant of model {self.model.name!r}")
        if len(self.path_bounds) != len(self._path):
            raise InputError("path_bounds must have one (lo, hi) per path constraint")

    def _read_instance(self, cons):
        """Instance constraints: their expressions in dummies for the states
        at given times, and the (state, time) of each dummy."""
        nm = self._names
        refs, exprs = {}, []
        for j, c in enumerate(cons):
            c = sm.sympify(c)
            rep = {}
            for f in c.atoms(sm.core.function.AppliedUndef):
                if f.func not in nm.state_funcs:
                    continue
                (arg,) = f.args
                if arg == me.dynamicsymbols._t:
                    raise InputError(f"constraints[{j}] = {c}: {f} is not at a given time; "
                                     "write the state at a time, e.g. theta.func(0)")
                if not arg.is_number:
                    raise InputError(f"constraints[{j}] = {c}: the time of {f} must be a number")
                tv = float(arg)
                key = (nm.state_funcs[f.func], tv)
                if key not in refs:
                    refs[key] = sm.Dummy(f"{f.func.__name__}_at_{len(refs)}")
                rep[f] = refs[key]
            exprs.append(self._instance_expr(c.xreplace(rep), refs, j, c))
        return exprs, list(refs.items())

    def _instance_expr(self, e, refs, j, c):
        nm = self._names
        e = e.xreplace(nm.sub)
        known = set(self.model.p) | set(refs.values())
        unknown = sorted({str(s) for s in e.free_symbols if s not in known})
        if unknown:
            raise InputError(f"constraints[{j}] = {c} holds {', '.join(unknown)}: an instance "
                             "constraint may hold states at given times and constants only")
        if e.has(*_NONSMOOTH):
            raise InputError(f"constraints[{j}] = {c} is not differentiable")
        return e

    # --------------------------------------------------------- build
    def _families(self):
        m = self.model
        nq, nu, nr, mv, mc = m.nq, m.nu, m.nr, m.mv, m.mc
        pf = [m.p[i] for i in self._pf]
        T = sm.Dummy("T")
        q, u, r, t = list(m.q), list(m.u), list(m.r), m.t
        qd = [sm.Dummy(f"qd{i}") for i in range(nq)]
        ud = [sm.Dummy(f"ud{i}") for i in range(nu)]
        lam = [sm.Dummy(f"lam{i}") for i in range(mv)]
        mu = [sm.Dummy(f"mu{i}") for i in range(mc)]
        N = self.nodes
        fams = []
        # the point equations
        kin = m.Kqd * sm.Matrix(qd) + m.Ku * sm.Matrix(u) + m.kf
        dyn = m.M * sm.Matrix(ud) - m.f
        if mv:
            dyn = dyn - m.A.T * sm.Matrix(lam)
        fams.append(_Family("point", q + u + qd + ud + lam + r + pf + [t],
                            list(kin) + list(dyn)))
        if mv:
            fams.append(_Family("velocity", q + u + pf + [t], list(m.A * sm.Matrix(u) + m.b)))
        if mc:
            fams.append(_Family("holonomic", q + pf + [t], list(m.fc)))
        if mv and self.method == "hermite-simpson":
            # the acceleration constraints at the nodes (the node multipliers'
            # equations; the midpoints' follow from the defects), OpenSim
            # Moco's form of Hermite-Simpson with kinematic constraints
            acc = m.A * sm.Matrix(ud) + m.a.xreplace(dict(zip(list(m.qd), qd)))
            fams.append(_Family("acceleration", q + u + qd + ud + pf + [t], list(acc)))
        nx = nq + nu
        xa = [sm.Dummy(f"xa{i}") for i in range(nx)]
        xb = [sm.Dummy(f"xb{i}") for i in range(nx)]
        sa = [sm.Dummy(f"sa{i}") for i in range(nx)]
        sb = [sm.Dummy(f"sb{i}") for i in range(nx)]
        xm = [sm.Dummy(f"xm{i}") for i in range(nx)]
        sm_ = [sm.Dummy(f"sm{i}") for i in range(nx)]
        h = T / (N - 1)
        if self.method == "backward-euler":
            dl = xa + xb + sb + [T]
            de = [xb[i] - xa[i] - h * sb[i] for i in range(nx)]
        elif self.method == "midpoint":
            dl = xa + xb + sm_ + [T]
            de = [xb[i] - xa[i] - h * sm_[i] for i in range(nx)]
        elif self.method == "trapezoidal":
            dl = xa + xb + sa + sb + [T]
            de = [xb[i] - xa[i] - h / 2 * (sa[i] + sb[i]) for i in range(nx)]
        else:
            dl = xa + xb + sa + sb + xm + sm_ + [T]
            de = ([xm[i] - (xa[i] + xb[i]) / 2 - h / 8 * (sa[i] - sb[i]) for i in range(nx)]
                  + [xb[i] - xa[i] - h / 6 * (sa[i] + 4 * sm_[i] + sb[i]) for i in range(nx)])
            if mc:
                # the velocity correction of the midpoint's coordinate slopes
                # in Simpson's rule (Posa, Kuindersma and Tedrake 2016; OpenSim
                # Moco): q' = u + Jc(q)^T mu at the midpoint, mu zero for the
                # DAE. It enters times h: a correction of the interpolated
                # midpoint coordinates instead would free them (by O(1)) off
                # the manifold, where the forces differ (a spurious optimum)
                Jm = m.fc.jacobian(q).xreplace(dict(zip(q, xm[:nq])))
                corr = Jm.T * sm.Matrix(mu)
                for i in range(nq):
                    de[nx + i] -= h * sm.Rational(4, 6) * corr[i]
                dl = dl + mu
        fams.append(_Family("defect", dl, de))
        x = q + u
        if self._L is not None:
            w = sm.Dummy("w")
            fams.append(_Family("cost", x + r + pf + [t, T], [w * T / (N - 1) * self._L],
                                data=[w], objective=True))
        if self._phi is not None:
            fams.append(_Family("terminal", x + r + pf + [T], [self._phi.xreplace({t: T})],
                                objective=True))
        if self._path:
            fams.append(_Family("path", x + r + pf + [t], list(self._path)))
        if self._instance:
            fams.append(_Family("instance", [d for _, d in self._inst_refs] + pf,
                                list(self._instance)))
        for j, (kind, i) in enumerate(self._fit_keys):
            y = x[i] if kind == "x" else m.y[i]
            val = sm.Dummy("val")
            fams.append(_Family(f"fit{j}", x + r + pf + [t], [(y - val) ** 2], data=[val],
                                objective=True))
        return fams

    def _key(self):
        from ..core.resources import csrc_file, templates_dir
        m = self.model
        h = hashlib.sha256()
        parts = [__version__, m.fingerprint(), self.method, str(self.nodes), repr(self._pf),
                 repr(self._fit_keys), csrc_file("gen_rt_ocp.c").read_text(),
                 csrc_file("gen_rt_ocp.h").read_text(),
                 (templates_dir() / "ocp" / "ocp.c.j2").read_text(),
                 # the transcription itself (the families are defined here)
                 open(__file__, encoding="utf-8").read()]
        sub = {s: sm.Symbol(f"_s{i}") for i, s in
               enumerate(list(m.q) + list(m.u) + list(m.r) + list(m.p) + [m.t])}
        for e in [self._L, self._phi, *self._path, *self._instance]:
            parts.append(sm.srepr(e.xreplace(sub)) if e is not None else "-")
        parts.append(repr([(i, tv) for (i, tv), _ in self._inst_refs]))
        for p in parts:
            h.update(p.encode())
            h.update(b"\0")
        return h.hexdigest()[:16]

    def _build(self):
        """Generate, compile (or find in the cache) and load the library."""
        from ..toolchain.build import build_plain
        from ..core.names import c_name
        m = self.model
        key = self._key()
        prefix = c_name(f"{m.name}_ocp")
        modname = f"_eomgen_ocp_{m.name}_{key}"

        def render():
            from ..codegen.render import template_env
            from ..core.resources import csrc_file
            fams = self._families()
            funcs = []
            meta = []
            for fam in fams:
                kv, kj, kh = _kernels(fam, list(m.p))
                funcs += [kv, kj, kh]
                meta.append({"name": fam.name, "nv": len(fam.locals), "nrow": len(fam.exprs),
                             "nd": len(fam.data), "objective": fam.objective,
                             "jac": fam.jac, "hess": fam.hess,
                             "locals": [self._describe(s) for s in fam.locals]})
            fam_rows = [{"nv": f["nv"], "nrow": f["nrow"], "nd": f["nd"],
                         "njac": len(f["jac"]), "nhess": len(f["hess"]),
                         "name": f["name"]} for f in meta]
            src = template_env().get_template("ocp/ocp.c.j2").render(
                prefix=prefix, funcs=funcs, families=fam_rows, version=__version__,
                model=m.name)
            files = {f"{prefix}.c": src,
                     "gen_rt_ocp.c": csrc_file("gen_rt_ocp.c").read_text(),
                     "gen_rt_ocp.h": csrc_file("gen_rt_ocp.h").read_text(),
                     "gen_rt_status.h": csrc_file("gen_rt_status.h").read_text(),
                     "meta.json": json.dumps(meta)}
            return files, [f"{prefix}.c", "gen_rt_ocp.c"]

        folder, lib = build_plain(modname, render)
        self._meta = json.loads((folder / "src" / "meta.json").read_text())
        self._prefix = prefix
        self._lib_path = lib
        self._load()

    def _describe(self, s):
        """A local variable as data: (role, index) (what assembly gathers)."""
        m = self.model
        name = s.name if isinstance(s, sm.Dummy) else None
        if s in m.q:
            return ["x", m.q.index(s)]
        if s in m.u:
            return ["x", m.nq + m.u.index(s)]
        if s in m.r:
            return ["r", m.r.index(s)]
        if s in m.p:
            return ["pf", self._pf.index(m.p.index(s))]
        if s == m.t:
            return ["t", 0]
        import re
        mt = re.fullmatch(r"([a-z_]+?)(\d+)", name or "")
        if name == "T":
            return ["T", 0]
        if name == "w" or name == "val":
            raise AssertionError("data symbol among locals")
        if "_at_" in (name or ""):
            return ["inst", [d for _, d in self._inst_refs].index(s)]
        if mt:
            role, i = mt.group(1), int(mt.group(2))
            if role == "qd":
                return ["s", i]
            if role == "ud":
                return ["s", m.nq + i]
            return [role, i]
        raise AssertionError(f"internal: unknown local {s}")

    def _load(self):
        import cffi
        ffi = cffi.FFI()
        ffi.cdef("""
        typedef struct {
            int family; int ninst;
            const int *gstart; const int *gidx; const double *gcoef;
            const double *data; const int *row0;
            const int *jstart; const int *jloc; const int *jslot; const double *jcoef;
            const int *hstart; const int *hloc; const int *hslot; const double *hcoef;
        } gen_rt_ocp_block;
        """ + f"""
        int {self._prefix}_eval(const gen_rt_ocp_block *blocks, int nblocks, const double *z,
                                const double *p, int what, const double *lam, double sigma,
                                double *work, int nout, double *out);
        int {self._prefix}_work_len(void);
        """)
        self._ffi = ffi
        self._lib = ffi.dlopen(str(self._lib_path))
        self._eval = getattr(self._lib, f"{self._prefix}_eval")
        self._work = np.zeros(getattr(self._lib, f"{self._prefix}_work_len")())

    # --------------------------------------------------------- assembly
    def _assemble(self):
        """The layout, the gathers and scatters, bounds: everything a solve
        needs that is not compiled."""
        m = self.model
        N, nx, nr = self.nodes, m.nx, m.nr
        self._check_runtime()
        lay = _Layout(self.method, N, m.nq, m.nu, nr, m.mv, m.mc, len(self._pf))
        fams = {f["name"]: (fi, f) for fi, f in enumerate(self._meta)}
        blocks = {}
        rows = [0]
        row_lo, row_hi = [], []

        def block(name):
            fi, f = fams[name]
            if name not in blocks:
                blocks[name] = _Block(fi, f)
            return blocks[name]

        def con_rows(f, lo=None, hi=None):
            r0 = rows[0]
            rows[0] += f["nrow"]
            row_lo.extend(lo if lo is not None else [0.0] * f["nrow"])
            row_hi.extend(hi if hi is not None else [0.0] * f["nrow"])
            return r0

        Tt = [(lay.T, 1.0)]

        def gather(f, xs, rs, c, s=None, lam=None, mu=None, extra=None):
            g = []
            for role, i in f["locals"]:
                if role == "x":
                    g.append([(int(idx[i]), cf) for idx, cf in xs])
                elif role == "r":
                    g.append([(int(idx[i]), cf) for idx, cf in rs])
                elif role == "s":
                    g.append([(int(s[i]), 1.0)])
                elif role == "lam":
                    g.append([(int(lam[i]), 1.0)])
                elif role == "pf":
                    g.append([(int(lay.P[i]), 1.0)])
                elif role == "t":
                    g.append([(lay.T, c)])
                elif role == "T":
                    g.append(Tt)
                else:
                    g.append(extra[(role, i)])
            return g

        # point equations and manifold
        pt = fams["point"][1]
        for xs, rs, s, lam, mu, c, own in lay.points:
            b = block("point")
            b.add(gather(pt, xs, rs, c, s, lam, mu), row0=con_rows(pt))
        skip = self._fixed_manifold_nodes()
        for name, own in (("velocity", []), ("holonomic", [])):
            if name not in fams:
                continue
            mf = fams[name][1]
            for k in range(N):
                if k in skip[name]:
                    continue
                block(name).add(gather(mf, [(lay.X[k], 1.0)], [], k / (N - 1)),
                                row0=con_rows(mf))
            for k in range(len(own)):
                block(name).add(gather(mf, [(own[k], 1.0)], [], (k + .5) / (N - 1)),
                                row0=con_rows(mf))
        if "acceleration" in fams:
            af = fams["acceleration"][1]
            for k in range(N):
                block("acceleration").add(
                    gather(af, [(lay.X[k], 1.0)], [], k / (N - 1), lay.node_point[k][0]),
                    row0=con_rows(af))
        # defects
        df = fams["defect"][1]
        for k in range(N - 1):
            ex = {}
            for i in range(nx):
                ex[("xa", i)] = [(int(lay.X[k][i]), 1.0)]
                ex[("xb", i)] = [(int(lay.X[k + 1][i]), 1.0)]
                if k in lay.node_point:
                    ex[("sa", i)] = [(int(lay.node_point[k][0][i]), 1.0)]
                if k + 1 in lay.node_point:
                    ex[("sb", i)] = [(int(lay.node_point[k + 1][0][i]), 1.0)]
                if k in lay.mid_point:
                    ex[("sm", i)] = [(int(lay.mid_point[k][0][i]), 1.0)]
                if lay.XM:
                    ex[("xm", i)] = [(int(lay.XM[k][i]), 1.0)]
            if k in lay.mid_point:
                for i, g in enumerate(lay.mid_point[k][2]):
                    ex[("mu", i)] = [(int(g), 1.0)]
            block("defect").add(gather(df, [], [], 0.0, extra=ex), row0=con_rows(df))
        # running cost: the method's quadrature weights (times h, in the kernel)
        if "cost" in fams:
            cf = fams["cost"][1]
            for xs, rs, s, lam, mu, c, own in self._cost_points(lay):
                block("cost").add(gather(cf, xs, rs, c), data=[s])
        if "terminal" in fams:
            tf = fams["terminal"][1]
            block("terminal").add(gather(tf, [(lay.X[N - 1], 1.0)], [(lay.R[N - 1], 1.0)], 1.0))
        if "path" in fams:
            pf_ = fams["path"][1]
            lo = [a for a, _ in self.path_bounds]
            hi = [b for _, b in self.path_bounds]
            for k in range(N):
                block("path").add(gather(pf_, [(lay.X[k], 1.0)], [(lay.R[k], 1.0)], k / (N - 1)),
                                  row0=con_rows(pf_, lo, hi))
        if "instance" in fams:
            inf = fams["instance"][1]
            ex = {}
            T_fixed = None if self.free_time else float(self.duration)
            for j, ((i, tv), _) in enumerate(self._inst_refs):
                if T_fixed is None:
                    if tv != 0:
                        raise InputError("with a free final time, instance constraints may "
                                         "refer to t = 0 only (use final= for the end)")
                    k = 0
                else:
                    kf = tv / T_fixed * (N - 1)
                    k = int(round(kf))
                    if abs(kf - k) > 1e-9 * max(1, N) or not 0 <= k < N:
                        raise InputError(f"constraints: the time {tv} is not a node time "
                                         f"(nodes at multiples of {T_fixed / (N - 1)!r} in "
                                         f"[0, {T_fixed}])")
                ex[("inst", j)] = [(int(lay.X[k][i]), 1.0)]
            block("instance").add(gather(inf, [], [], 0.0, extra=ex), row0=con_rows(inf))
        for j, key in enumerate(self._fit_keys):
            name = f"fit{j}"
            ff = fams[name][1]
            td, vals = self._fit_data(j)
            Tf = float(self.duration)
            for tk, vk in zip(td, vals):
                a = tk / Tf * (N - 1)
                k = min(int(math.floor(a)), N - 2)
                al = a - k
                xs = [(lay.X[k], 1 - al), (lay.X[k + 1], al)]
                rs = [(lay.R[k], 1 - al), (lay.R[k + 1], al)]
                block(name).add(gather(ff, xs, rs, tk / Tf), data=[vk])
        self._lay = lay
        self._m_rows = rows[0]
        self._cl, self._cu = np.array(row_lo, float), np.array(row_hi, float)
        self._finish_blocks(list(blocks.values()), lay.n)

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
            given = {}
            for k, v in getattr(self, what).items():
                given[nm.key(k, what)[1]] = float(v)
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

    def _cost_points(self, lay):
        """(x terms, r terms, weight, -, -, time fraction, -) of the
        running cost's quadrature (weights in units of h)."""
        N = self.nodes
        out = []
        if self.method == "backward-euler":
            for k in range(1, N):
                out.append(([(lay.X[k], 1.0)], [(lay.R[k], 1.0)], 1.0, 0, 0, k / (N - 1), 0))
        elif self.method == "midpoint":
            for k in range(N - 1):
                out.append(([(lay.X[k], .5), (lay.X[k + 1], .5)],
                            [(lay.R[k], .5), (lay.R[k + 1], .5)], 1.0, 0, 0,
                            (k + .5) / (N - 1), 0))
        else:
            node_w = 0.5 if self.method == "trapezoidal" else 1 / 6
            for k in range(N):
                w = node_w * (1 if k in (0, N - 1) else 2)
                out.append(([(lay.X[k], 1.0)], [(lay.R[k], 1.0)], w, 0, 0, k / (N - 1), 0))
            if self.method == "hermite-simpson":
                for k in range(N - 1):
                    out.append(([(lay.XM[k], 1.0)], [(lay.RM[k], 1.0)], 4 / 6, 0, 0,
                                (k + .5) / (N - 1), 0))
        return out

    def _finish_blocks(self, blocks, n):
        """Index tables: gathers flattened, Jacobian and Hessian slots."""
        jac_slots, hess_slots = {}, {}
        self._arrays = []          # keep the buffers alive
        cblocks = self._ffi.new("gen_rt_ocp_block[]", len(blocks))
        for bi, b in enumerate(blocks):
            f = b.fam
            nv = f["nv"]
            gstart, gidx, gcoef = [0], [], []
            jstart, jloc, jslot, jcoef = [0], [], [], []
            hstart, hloc, hslot, hcoef = [0], [], [], []
            hfull = {}
            for e, (a, c) in enumerate(f["hess"]):
                hfull.setdefault(a, []).append((c, e))
                if a != c:
                    hfull.setdefault(c, []).append((a, e))
            for g, r0 in zip(b.gathers, b.row0):
                for terms in g:
                    for idx, cf in terms:
                        gidx.append(idx)
                        gcoef.append(cf)
                    gstart.append(len(gidx))
                for e, (row, a) in enumerate(f["jac"]):
                    for idx, cf in g[a]:
                        if idx < 0 or cf == 0:
                            continue
                        if r0 < 0:
                            slot = idx
                        else:
                            key = (r0 + row, idx)
                            slot = jac_slots.setdefault(key, len(jac_slots))
                        jloc.append(e)
                        jslot.append(slot)
                        jcoef.append(cf)
                jstart.append(len(jloc))
                for a, lst in hfull.items():
                    for c, e in lst:
                        for ia, ca in g[a]:
                            if ia < 0 or ca == 0:
                                continue
                            for ic, cc in g[c]:
                                if ic < 0 or cc == 0 or ia < ic:
                                    continue
                                slot = hess_slots.setdefault((ia, ic), len(hess_slots))
                                hloc.append(e)
                                hslot.append(slot)
                                hcoef.append(ca * cc)
                hstart.append(len(hloc))
            arrs = dict(
                gstart=np.array(gstart, np.int32), gidx=np.array(gidx, np.int32),
                gcoef=np.array(gcoef, float),
                data=np.array(b.data, float).ravel() if f["nd"] else None,
                row0=np.array(b.row0, np.int32),
                jstart=np.array(jstart, np.int32), jloc=np.array(jloc, np.int32),
                jslot=np.array(jslot, np.int32), jcoef=np.array(jcoef, float),
                hstart=np.array(hstart, np.int32), hloc=np.array(hloc, np.int32),
                hslot=np.array(hslot, np.int32), hcoef=np.array(hcoef, float))
            self._arrays.append(arrs)
            cb = cblocks[bi]
            cb.family = b.fi
            cb.ninst = len(b.gathers)
            for k, a in arrs.items():
                if a is None:
                    setattr(cb, k, self._ffi.NULL)
                else:
                    ctype = "int *" if a.dtype == np.int32 else "double *"
                    setattr(cb, k, self._ffi.cast(ctype, a.ctypes.data))
        self._cblocks = cblocks
        self._nblocks = len(blocks)
        jk = sorted(jac_slots, key=jac_slots.get)
        self._jrows = np.array([r for r, _ in jk], np.int32)
        self._jcols = np.array([c for _, c in jk], np.int32)
        hk = sorted(hess_slots, key=hess_slots.get)
        self._hrows = np.array([r for r, _ in hk], np.int32)
        self._hcols = np.array([c for _, c in hk], np.int32)
        self._n = n

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
            p[i] = float(v)
        return p

    def _var_bounds(self):
        m, lay, N = self.model, self._lay, self.nodes
        BIG = 1e20
        lb = np.full(lay.n, -BIG)
        ub = np.full(lay.n, BIG)
        nm = self._names
        for k, (lo, hi) in self.bounds.items():
            kind, i = nm.key(k, "bounds")
            lo, hi = max(float(lo), -BIG), min(float(hi), BIG)
            if kind == "x":
                idx = [X[i] for X in lay.X + lay.XM]
            elif kind == "r":
                idx = [R[i] for R in lay.R + lay.RM]
            else:
                idx = [lay.P[self._pf.index(i)]]
            lb[idx], ub[idx] = lo, hi
        for what, k0 in (("initial", 0), ("final", N - 1)):
            for k, v in getattr(self, what).items():
                _, i = nm.key(k, what)
                v = float(v)
                j = lay.X[k0][i]
                if not lb[j] <= v <= ub[j]:
                    raise InputError(f"{what}[{k}] = {v} is outside its bounds "
                                     f"({lb[j]}, {ub[j]})")
                lb[j] = ub[j] = v
        if self.free_time:
            lb[lay.T], ub[lay.T] = (float(v) for v in self.duration)
        else:
            lb[lay.T] = ub[lay.T] = float(self.duration)
        return lb, ub

    def _guess(self, guess, lb, ub):
        m, lay, N = self.model, self._lay, self.nodes
        z = np.zeros(lay.n)
        T = 0.5 * (lb[lay.T] + ub[lay.T])
        z[lay.T] = T
        nm = self._names
        x0 = np.zeros(m.nx)
        x1 = np.zeros(m.nx)
        for k, v in self.initial.items():
            x0[nm.key(k, "initial")[1]] = float(v)
            x1[nm.key(k, "initial")[1]] = float(v)
        for k, v in self.final.items():
            x1[nm.key(k, "final")[1]] = float(v)
        p = self._pvec()
        for j, i in enumerate(self._pf):
            z[lay.P[j]] = p[i]
        if isinstance(guess, OptimalSolution) and guess._z is not None \
                and guess._z.size == lay.n and guess._layout_key == self._layout_key():
            z = guess._z.copy()
        elif guess is None or isinstance(guess, dict) or isinstance(guess, OptimalSolution):
            tau = np.linspace(0, 1, N)
            X = x0[None, :] + tau[:, None] * (x1 - x0)[None, :]
            R = np.zeros((N, m.nr))
            if isinstance(guess, OptimalSolution):
                ts = tau * T
                X, R = guess(ts), guess.input(ts)
                if self.free_time:
                    z[lay.T] = guess.t[-1]
            for k, v in (guess or {}).items() if isinstance(guess, dict) else []:
                if isinstance(k, str) and k == "duration":
                    z[lay.T] = float(v)
                    continue
                kind, i = nm.key(k, "guess")
                v = np.broadcast_to(np.asarray(v, float), (N,))
                if kind == "x":
                    X[:, i] = v
                elif kind == "r":
                    R[:, i] = v
                elif kind == "p":
                    z[lay.P[self._pf.index(i)]] = float(v[0])
            T = z[lay.T]
            slope = np.gradient(X, T * tau, axis=0) if N > 2 else (X[1:] - X[:1]) / T
            for k in range(N):
                z[lay.X[k]] = X[k]
                z[lay.R[k]] = R[k]
                if k in lay.node_point:
                    z[lay.node_point[k][0]] = slope[k]
                if k in lay.mid_point:
                    z[lay.mid_point[k][0]] = 0.5 * (slope[k] + slope[k + 1])
            for k in range(len(lay.XM)):
                z[lay.XM[k]] = 0.5 * (X[k] + X[k + 1])
                z[lay.RM[k]] = 0.5 * (R[k] + R[k + 1])
        else:
            g = np.asarray(guess, float).ravel()
            if g.size != lay.n:
                raise InputError(f"guess: an array must have the problem's {lay.n} unknowns, "
                                 f"got {g.size}")
            z = g.copy()
        return np.clip(z, lb, ub)

    def _layout_key(self):
        return (self.method, self.nodes, self.model.mv, self.model.mc, len(self._pf))

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
        cyipopt = _cyipopt()
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
        z0 = self._guess(guess, lb, ub)
        n, mrows = self._lay.n, self._m_rows
        ocp = self
        nj, nh = len(self._jrows), len(self._hrows)
        iters = [0]

        class _NLP:
            def objective(self, z):
                return float(ocp._call(0, z, 1)[0])

            def gradient(self, z):
                return ocp._call(1, z, n)

            def constraints(self, z):
                return ocp._call(2, z, mrows)

            def jacobian(self, z):
                return ocp._call(3, z, nj)

            def jacobianstructure(self):
                return ocp._jrows, ocp._jcols

            def intermediate(self, alg_mod, iter_count, *args):
                iters[0] = iter_count
                return True

        if hessian == "exact":
            def hess(self, z, lagrange, obj_factor):
                return ocp._call(4, z, nh, np.asarray(lagrange, float), float(obj_factor))

            def hstruct(self):
                return ocp._hrows, ocp._hcols
            _NLP.hessian = hess
            _NLP.hessianstructure = hstruct
        nlp = cyipopt.Problem(n=n, m=mrows, problem_obj=_NLP(), lb=lb, ub=ub,
                              cl=self._cl, cu=self._cu)
        opts = {"print_level": 0, "sb": "yes"}
        if hessian == "limited-memory":
            opts["hessian_approximation"] = "limited-memory"
        opts.update(ipopt_options)
        for k, v in opts.items():
            try:
                nlp.add_option(k, v)
            except (TypeError, ValueError) as e:
                raise InputError(f"IPOPT option {k}={v!r}: {e}") from None
        z, info = nlp.solve(z0)
        solve_seconds = time.perf_counter() - t0
        status = int(info["status"])
        msg = IPOPT_MESSAGES.get(status)
        raw = info.get("status_msg", b"")
        raw = raw.decode() if isinstance(raw, bytes) else str(raw)
        if msg is None:
            msg = f"IPOPT failed (status {status}): {raw}"
        return OptimalSolution._make(self, np.asarray(z, float), float(info["obj_val"]), status,
                                     msg, iters[0], solve_seconds)

    # --------------------------------------------------------- helpers
    @property
    def simulator(self):
        """A compiled gen.Simulator of the same model (gen.compile), built
        on first use: replays and tracking."""
        if self._sim is None:
            from ..pipeline import compile as _compile
            self._sim = _compile(self.model)
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
        codes = {"objective": (0, 1), "gradient": (1, self._lay.n),
                 "constraints": (2, self._m_rows), "jacobian": (3, len(self._jrows))}
        if what == "hessian":
            return self._call(4, z, len(self._hrows), np.ones(self._m_rows), 1.0)
        c, n = codes[what]
        return self._call(c, z, n)


class OptimalSolution:
    """The result of :meth:`OptimalControl.solve`.

    Attributes
    ----------
    t : ndarray (N,)       node times
    x : ndarray (N, nx)    states at the nodes
    r : ndarray (N, nr)    inputs at the nodes
    p : ndarray            the identified parameters (in ``parameters``' order)
    objective : float
    status : int           IPOPT's status (0 solved, 1 acceptable, 2 infeasible, < 0 failed)
    message : str          the status in words
    iterations : int
    build_seconds, solve_seconds : float
    success : bool         status 0 or 1

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
        T = z[lay.T]
        N = ocp.nodes
        s.t = np.linspace(0.0, T, N)
        s.x = np.array([z[X] for X in lay.X])
        s.r = np.array([z[R] for R in lay.R]).reshape(N, ocp.model.nr)
        s.p = z[lay.P].copy()
        s.objective = obj
        s.status = status
        s.message = message
        s.iterations = iterations
        s.build_seconds = ocp.build_seconds
        s.solve_seconds = solve_seconds
        s.success = status in (0, 1)
        s.duration = T
        nx = ocp.model.nx
        S = np.full((N, nx), np.nan)
        for k, (si, _, _) in lay.node_point.items():
            S[k] = z[si]
        s._S = S
        s._SM = np.array([z[lay.mid_point[k][0]] for k in range(N - 1)]) if lay.mid_point else None
        s._XM = np.array([z[X] for X in lay.XM]) if lay.XM else None
        s._RM = (np.array([z[R] for R in lay.RM]).reshape(len(lay.RM), ocp.model.nr)
                  if lay.RM else None)
        return s

    def __iter__(self):
        return iter((self.t, self.x))

    def __repr__(self):
        return (f"OptimalSolution(status={self.status}, objective={self.objective:.10g}, "
                f"iterations={self.iterations}, nodes={len(self.t)}, method={self.method!r})")

    def _locate(self, t):
        t = np.asarray(t, float)
        h = self.t[1] - self.t[0]
        k = np.clip(np.floor(t / h).astype(int), 0, len(self.t) - 2)
        tau = t - k * h
        return t, k, tau, h

    def __call__(self, t):
        """The states at times t (the transcription's interpolant)."""
        t, k, tau, h = self._locate(t)
        X = self.x
        if self.method in ("backward-euler", "midpoint"):
            a = (tau / h)[..., None]
            return X[k] * (1 - a) + X[k + 1] * a
        if self.method == "trapezoidal":
            s0, s1 = self._S[k], self._S[k + 1]
            tt = tau[..., None]
            return X[k] + s0 * tt + (s1 - s0) * tt ** 2 / (2 * h)
        # Hermite-Simpson: the slope is quadratic through s_k, s_m, s_k+1;
        # integrate from x_k
        s0, sm_, s1 = self._S[k], self._SM[k], self._S[k + 1]
        u = (tau / h)[..., None]
        # s(u) = s0 (1-u)(1-2u) + 4 sm u (1-u) + s1 u (2u-1)
        i0 = u - 3 * u ** 2 / 2 + 2 * u ** 3 / 3
        im = 2 * u ** 2 - 4 * u ** 3 / 3
        i1 = -u ** 2 / 2 + 2 * u ** 3 / 3
        return X[k] + h * (s0 * i0 + sm_ * im + s1 * i1)

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
        (``sim.simulate``, the inputs from :meth:`input` at every stage).

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
        x0 = self.x[0]
        p = self._ocp._pvec()
        for j, i in enumerate(self._ocp._pf):
            p[i] = self.p[j]
        dt = dt or (self.t[1] - self.t[0])
        return sim.simulate(x0, float(self.t[-1]), dt, r=lambda t, x: self.input(t),
                            p=p, method=method, input_period=0, **options)

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
        """
        from .tracking import TrajectoryTracker
        return TrajectoryTracker(self._ocp.simulator, self.t, self.x, self.r, Q, R, period,
                                 p=self._ocp._pvec())
