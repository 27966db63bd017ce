"""Canonical model: what a simulator needs, extracted from a formed
``sympy.physics.mechanics`` object and validated.

Every model, Kane or Lagrange, is held in one form (all expressions in
plain sympy symbols, no functions of time):

    kinematics    Kqd(q) q' + Ku(q) u + kf(q, t) = 0           (nq rows)
    dynamics      M(q) u' = f(q, u, r, t) + A(q)^T lam          (nu rows)
    velocity      A(q) u + b(q, t) = 0                          (mv rows)
    acceleration  A(q) u' + a(q, u, t) = 0                      (mv rows)
    configuration f_c(q, t) = 0                                 (mc rows)

M and f are the *unconstrained* equations for all speeds: the dependent
speeds are eliminated (Kane) or the multipliers solved for (Lagrange)
numerically at run time, never symbolically (sympy's symbolic elimination
can divide by zero at regular configurations, ../shared/NOTES-sympy.md 1).

State layout: x = [q, u]. For Kane models q = [q_ind, q_dep] and
u = [u_ind, u_dep] in the KanesMethod's order; for Lagrange models
q is the LagrangesMethod's coordinate order and u = q'.

Multiplier sign: M u' = f + A^T lam with A = d(velocity constraints)/du.
For a LagrangesMethod this lam equals the values sympy's
``solve_multipliers`` returns (sympy's own ``eom`` uses the opposite sign,
sympy issue 30215).

The C naming rules (validate_name, c_name, c_names) live in gen.names and
are re-exported here.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import sympy as sm
from sympy.physics import mechanics as me

from .errors import ModelError
from .names import C_KEYWORDS, C_LIBRARY_NAMES, c_name, c_names, validate_name  # noqa: F401

__all__ = ["Model", "validate_name", "c_name", "c_names"]


def _as_matrix(x, what):
    if x is None:
        return sm.zeros(0, 1)
    m = sm.Matrix(x)
    if m.shape[1] != 1 and m.shape[0] == 1:
        m = m.T
    if m.shape[1] != 1 and m.shape[0] != 0:
        raise ModelError(f"{what} must be a column of expressions, got shape {m.shape}")
    return m


def _sym_name(s) -> str:
    """A readable name for a symbol or function of time: 'q1' for q1(t)."""
    if isinstance(s, sm.Function) or (isinstance(s, sm.Expr) and s.is_Function):
        return type(s).__name__ if not hasattr(s, "func") else str(s.func)
    return str(s)


@dataclass
class Model:
    """A validated, canonical model (see the module docstring for the form).

    Build one with :meth:`from_kanes` or :meth:`from_lagrange`."""

    name: str
    method: str                      # "kane" | "lagrange"
    # sympy objects as the user knows them (functions of time / symbols)
    q_orig: list
    u_orig: list
    r_orig: list
    p_orig: list
    p_values: list
    # internal plain symbols, same order as the originals
    q: list
    u: list
    r: list
    p: list
    t: sm.Symbol
    q_ind: list                      # indices into q
    q_dep: list
    u_ind: list                      # indices into u
    u_dep: list
    # expressions in the internal symbols
    Kqd: sm.Matrix
    Ku: sm.Matrix
    kf: sm.Matrix
    M: sm.Matrix
    f: sm.Matrix
    A: sm.Matrix
    b: sm.Matrix
    a: sm.Matrix
    fc: sm.Matrix
    qdot: sm.Matrix | None           # explicit q' (when Kqd is diagonal), else None
    energy: sm.Expr | None = None    # total energy, if known
    # names as identifiers ([A-Za-z_][A-Za-z0-9_]*, unique): what generated
    # files, the CLI and the Python API use
    state_names: list = field(default_factory=list)
    input_names: list = field(default_factory=list)
    constant_names: list = field(default_factory=list)
    # the names as sympy prints them (may hold any character)
    state_labels: list = field(default_factory=list)
    input_labels: list = field(default_factory=list)
    constant_labels: list = field(default_factory=list)

    # ------------------------------------------------------------------ sizes
    @property
    def nq(self):
        return len(self.q)

    @property
    def nu(self):
        return len(self.u)

    @property
    def nx(self):
        return self.nq + self.nu

    @property
    def nr(self):
        return len(self.r)

    @property
    def np(self):
        return len(self.p)

    @property
    def mc(self):
        return self.fc.shape[0]

    @property
    def mv(self):
        return self.A.shape[0]

    @property
    def ns(self):
        """Size of the independent state [q_ind, u_ind] (linearization)."""
        return self.nq - self.mc + self.nu - self.mv

    @property
    def independent_state_names(self):
        return ([self.state_names[i] for i in self.q_ind]
                + [self.state_names[self.nq + i] for i in self.u_ind])

    def fingerprint(self) -> str:
        """A hash of everything generation depends on."""
        h = hashlib.sha256()
        parts = [self.name, self.method, repr(self.q_ind), repr(self.q_dep),
                 repr(self.u_ind), repr(self.u_dep), repr(self.state_names),
                 repr(self.input_names), repr(self.constant_names)]
        sub = {s: sm.Symbol(f"_q{i}") for i, s in enumerate(self.q)}
        sub.update({s: sm.Symbol(f"_u{i}") for i, s in enumerate(self.u)})
        sub.update({s: sm.Symbol(f"_r{i}") for i, s in enumerate(self.r)})
        sub.update({s: sm.Symbol(f"_p{i}") for i, s in enumerate(self.p)})
        sub[self.t] = sm.Symbol("_t")
        for mat in (self.Kqd, self.Ku, self.kf, self.M, self.f, self.A, self.b,
                    self.a, self.fc):
            parts.append(sm.srepr(mat.xreplace(sub)))
        if self.energy is not None:
            parts.append(sm.srepr(self.energy.xreplace(sub)))
        for part in parts:
            h.update(part.encode())
            h.update(b"\0")
        return h.hexdigest()

    # ------------------------------------------------------------ builders
    @classmethod
    def from_kanes(cls, km, constants=None, inputs=None, name="model",
                   energy=None):
        """Build from a ``KanesMethod`` after ``kanes_equations``.

        constants: {symbol: value} for every parameter; inputs: symbols or
        functions of time that are inputs r (in this order); energy: an
        optional expression of the total energy (for diagnostics).
        """
        validate_name(name)
        if not isinstance(km, me.KanesMethod):
            raise ModelError(f"from_kanes needs a KanesMethod, got {type(km).__name__}")
        if getattr(km, "_fr", None) is None:
            raise ModelError("call km.kanes_equations(bodies, loads) before Model.from_kanes")
        if getattr(km, "_uaux", None) is not None and len(km._uaux) > 0:
            raise ModelError("auxiliary speeds (u_auxiliary) are not supported")
        t = me.dynamicsymbols._t
        q = list(km.q)
        u = list(km.u)
        nq, nu = len(q), len(u)
        nqd = len(km._qdep) if km._qdep is not None else 0
        nud = len(km._udep) if km._udep is not None else 0
        qdots = [qi.diff(t) for qi in q]

        Kqd = sm.Matrix(km._k_kqdot)
        Ku = sm.Matrix(km._k_ku)
        kf = sm.Matrix(km._f_k)
        fc = sm.Matrix(km._f_h) if km._f_h is not None and len(km._f_h) else sm.zeros(0, 1)
        if nud:
            A = sm.Matrix(km._k_nh)
            b = sm.Matrix(km._f_nh)
        else:
            A = sm.zeros(0, nu)
            b = sm.zeros(0, 1)
        if fc.shape[0] != nqd:
            raise ModelError(
                f"KanesMethod has {nqd} dependent coordinates but {fc.shape[0]} "
                "configuration constraints; they must match")

        if nud == 0 and nqd == 0:
            M, f = sm.Matrix(km.mass_matrix), sm.Matrix(km.forcing)
        else:
            # Form the unconstrained equations for all speeds (cheap), so that
            # the dependent speeds are eliminated numerically at run time.
            kdes = Kqd * sm.Matrix(qdots) + Ku * sm.Matrix(u) + kf
            km_free = me.KanesMethod(km._inertial, q_ind=q, u_ind=u, kd_eqs=kdes)
            km_free.kanes_equations(km.bodies, km.loads)
            M, f = sm.Matrix(km_free.mass_matrix), sm.Matrix(km_free.forcing)

        qdot_map = dict(km._qdot_u_map) if km._qdot_u_map else {}
        return cls._finish(
            name=name, method="kane", t=t, q=q, u=u, qdots=qdots, udots=[ui.diff(t) for ui in u],
            q_ind=list(range(nq - nqd)), q_dep=list(range(nq - nqd, nq)),
            u_ind=list(range(nu - nud)), u_dep=list(range(nu - nud, nu)),
            Kqd=Kqd, Ku=Ku, kf=kf, M=M, f=f, A=A, b=b, fc=fc,
            qdot_subs=qdot_map, constants=constants, inputs=inputs, energy=energy,
            speed_names=[_sym_name(x) for x in u])

    @classmethod
    def from_lagrange(cls, lm, q_ind=None, qd_ind=None, q_dep=None, qd_dep=None,
                      constants=None, inputs=None, name="model", energy=None):
        """Build from a ``LagrangesMethod`` after ``form_lagranges_equations``.

        q_ind/q_dep partition the coordinates, qd_ind/qd_dep their
        derivatives, as for sympy's ``LagrangesMethod.linearize``. The state
        is x = [q, q'] in the method's coordinate order."""
        validate_name(name)
        if not isinstance(lm, me.LagrangesMethod):
            raise ModelError(f"from_lagrange needs a LagrangesMethod, got {type(lm).__name__}")
        if getattr(lm, "eom", None) is None:
            raise ModelError("call lm.form_lagranges_equations() before Model.from_lagrange")
        t = me.dynamicsymbols._t
        q = list(lm.q)
        n = len(q)
        qdots = [qi.diff(t) for qi in q]
        qdds = [qi.diff(t, 2) for qi in q]
        q_ind = list(q_ind or [])
        q_dep = list(q_dep or [])
        qd_ind = list(qd_ind or [])
        qd_dep = list(qd_dep or [])
        if not q_ind and not q_dep:
            q_ind = list(q)
        if not qd_ind and not qd_dep:
            qd_ind = list(qdots)

        def index_of(items, pool, what):
            out = []
            for it in items:
                hits = [i for i, s in enumerate(pool) if s == it]
                if not hits:
                    raise ModelError(f"{what} entry {it} is not one of the model's {what[:-4] if what.endswith('_ind') or what.endswith('_dep') else what}: {list(pool)}")
                out.append(hits[0])
            return out

        qi = index_of(q_ind, q, "q_ind")
        qdp = index_of(q_dep, q, "q_dep")
        ui = index_of(qd_ind, qdots, "qd_ind")
        udp = index_of(qd_dep, qdots, "qd_dep")
        if sorted(qi + qdp) != list(range(n)):
            raise ModelError(
                f"q_ind {q_ind} and q_dep {q_dep} must together list every coordinate "
                f"{q} exactly once")
        if sorted(ui + udp) != list(range(n)):
            raise ModelError(
                f"qd_ind {qd_ind} and qd_dep {qd_dep} must together list every "
                f"coordinate derivative {qdots} exactly once")

        M = sm.Matrix(lm._m_d)
        f = sm.Matrix(lm._f_d)
        hol = getattr(lm, "_hol_coneqs", None)
        fc = sm.Matrix(hol) if hol is not None and len(hol) else sm.zeros(0, 1)
        coneqs = sm.Matrix(lm.coneqs) if lm.coneqs is not None and len(lm.coneqs) else sm.zeros(0, 1)
        if coneqs.shape[0]:
            A = coneqs.jacobian(qdots)
            b = (coneqs - A * sm.Matrix(qdots)).applyfunc(sm.expand)
        else:
            A = sm.zeros(0, n)
            b = sm.zeros(0, 1)
        if fc.shape[0] != len(qdp):
            raise ModelError(
                f"the LagrangesMethod has {fc.shape[0]} holonomic constraints but "
                f"q_dep lists {len(qdp)} dependent coordinates; they must match")
        if A.shape[0] != len(udp):
            raise ModelError(
                f"the LagrangesMethod has {A.shape[0]} velocity-level constraints "
                f"(holonomic derivatives and nonholonomic) but qd_dep lists {len(udp)} "
                "dependent speeds; they must match")
        # the speeds are the coordinate derivatives: u_i := q_i'
        Kqd = sm.eye(n)
        Ku = -sm.eye(n)
        kf = sm.zeros(n, 1)
        # Symbols for u: reuse the q' objects; _finish maps them.
        return cls._finish(
            name=name, method="lagrange", t=t, q=q, u=qdots, qdots=qdots, udots=qdds,
            q_ind=qi, q_dep=qdp, u_ind=ui, u_dep=udp,
            Kqd=Kqd, Ku=Ku, kf=kf, M=M, f=f, A=A, b=b, fc=fc,
            qdot_subs={}, constants=constants, inputs=inputs, energy=energy,
            speed_names=[_sym_name(x) + "_d" for x in q])

    # ------------------------------------------------------------ internals
    @classmethod
    def _finish(cls, *, name, method, t, q, u, qdots, udots, q_ind, q_dep, u_ind,
                u_dep, Kqd, Ku, kf, M, f, A, b, fc, qdot_subs, constants, inputs,
                energy, speed_names):
        constants = dict(constants or {})
        inputs = list(inputs or [])
        nq, nu = len(q), len(u)

        # ---- inputs and constants: declared once, with values -----------
        seen = set()
        for r_ in inputs:
            if r_ in seen:
                raise ModelError(f"input {r_} is given twice in inputs")
            seen.add(r_)
        for c in constants:
            if not isinstance(c, sm.Symbol):
                raise ModelError(f"constant {c} must be a sympy Symbol, got {type(c).__name__}")
            if c in seen:
                raise ModelError(f"{c} is declared both as an input and as a constant")
        values = []
        for c, v in constants.items():
            try:
                fv = float(v)
            except (TypeError, ValueError):
                raise ModelError(f"constant {c} has a value {v!r} that is not a number") from None
            values.append(fv)
        for i, s in enumerate(list(q) + list(u)):
            if s in seen or s in constants:
                raise ModelError(f"{s} is a coordinate or speed and cannot be an input or constant")

        # ---- internal symbols -------------------------------------------
        Q = [sm.Dummy(f"q{i}") for i in range(nq)]
        U = [sm.Dummy(f"u{i}") for i in range(nu)]
        R = [sm.Dummy(f"r{i}") for i in range(len(inputs))]
        P = [sm.Dummy(f"p{i}") for i in range(len(constants))]
        T = sm.Dummy("t")
        sub = {}
        # derivatives first (u' must not appear; q' may appear for Lagrange)
        for qd_, ui_ in zip(qdots, U if method == "lagrange" else [None] * nq):
            if ui_ is not None:
                sub[qd_] = ui_
        for s, d in zip(q, Q):
            sub[s] = d
        if method == "kane":
            for s, d in zip(u, U):
                sub[s] = d
        for s, d in zip(inputs, R):
            sub[s] = d
        for s, d in zip(constants, P):
            sub[s] = d
        sub[t] = T

        qd_subs = {k: v for k, v in qdot_subs.items()}

        def conv(mat, what):
            mat = sm.Matrix(mat)
            if qd_subs:
                mat = mat.xreplace(qd_subs) if mat.shape[0] * mat.shape[1] else mat
            out = mat.xreplace(sub) if mat.shape[0] * mat.shape[1] else mat
            _check_expressions(out, what, set(Q) | set(U) | set(R) | set(P) | {T})
            return out

        Kqd_, Ku_, kf_ = conv(Kqd, "kinematic equations (q' coefficients)"), conv(Ku, "kinematic equations (u coefficients)"), conv(kf, "kinematic equations")
        M_ = conv(M, "mass matrix")
        f_ = conv(f, "forcing")
        A_ = conv(A, "velocity constraints")
        b_ = conv(b, "velocity constraints")
        fc_ = conv(fc, "configuration constraints")
        E_ = None
        if energy is not None:
            E_ = conv(sm.Matrix([energy]), "energy")[0]

        # ---- structure checks -------------------------------------------
        if M_.shape != (nu, nu):
            raise ModelError(f"mass matrix has shape {M_.shape}, expected ({nu}, {nu})")
        if f_.shape != (nu, 1):
            raise ModelError(f"forcing has shape {f_.shape}, expected ({nu}, 1)")
        if any(e.has(*U) for e in M_):
            raise ModelError("the mass matrix depends on the speeds; such models are not supported")
        for mat, what in ((Kqd_, "kinematic q' coefficients"), (Ku_, "kinematic u coefficients"),
                          (A_, "velocity-constraint matrix")):
            if any(e.has(*U) for e in mat) or any(e.has(*R) for e in mat):
                raise ModelError(f"the {what} depend on speeds or inputs; the kinematic "
                                 "equations and velocity constraints must be linear in the speeds")
        if any(e.has(*U) or e.has(*R) for e in fc_):
            raise ModelError("the configuration constraints depend on speeds or inputs")
        if any(e.has(*R) for e in list(kf_) + list(b_)):
            raise ModelError("the kinematic equations or velocity constraints depend on inputs; not supported")

        # explicit q' when Kqd is diagonal (the usual q' = u)
        qdot = None
        if all(Kqd_[i, j] == 0 for i in range(nq) for j in range(nq) if i != j):
            diag = [Kqd_[i, i] for i in range(nq)]
            if all(d != 0 for d in diag):
                qdot = sm.Matrix([-(Ku_[i, :].dot(sm.Matrix(U)) + kf_[i]) / diag[i]
                                  for i in range(nq)])
        # q' as a function of (q, u) for the acceleration constraint
        if qdot is not None:
            qdot_expr = qdot
        elif method == "kane" and qd_subs:
            qdot_expr = sm.Matrix([qd_subs[qd].xreplace(sub) if qd in qd_subs else None
                                   for qd in qdots])
        else:
            qdot_expr = Kqd_.LUsolve(-(Ku_ * sm.Matrix(U) + kf_))
        # a = d/dt(A u + b) - A u'  (q' from the kinematic equations)
        mv = A_.shape[0]
        if mv:
            fv = A_ * sm.Matrix(U) + b_
            a_ = fv.jacobian(Q) * qdot_expr + fv.diff(T)
        else:
            a_ = sm.zeros(0, 1)

        state_labels = [_sym_name(s) for s in q] + list(speed_names)
        input_labels = [_sym_name(s) for s in inputs]
        constant_labels = [str(s) for s in constants]
        all_labels = state_labels + input_labels + constant_labels
        dup = sorted({n_ for n_ in all_labels if all_labels.count(n_) > 1})
        if dup:
            raise ModelError(f"names used twice among states, inputs and constants: {dup}; "
                             "give each coordinate, speed, input and constant its own name")
        # the names generated files use (CSV columns, --x0 NAME=..., C string
        # literals and comments): plain identifiers, unique after sanitizing
        safe = c_names(all_labels)
        ns_, nr_ = len(state_labels), len(input_labels)
        state_names, input_names = safe[:ns_], safe[ns_:ns_ + nr_]
        constant_names = safe[ns_ + nr_:]

        model = cls(
            name=name, method=method, q_orig=list(q), u_orig=list(u), r_orig=inputs,
            p_orig=list(constants), p_values=values, q=Q, u=U, r=R, p=P, t=T,
            q_ind=list(q_ind), q_dep=list(q_dep), u_ind=list(u_ind), u_dep=list(u_dep),
            Kqd=Kqd_, Ku=Ku_, kf=kf_, M=M_, f=f_, A=A_, b=b_, a=a_, fc=fc_, qdot=qdot,
            energy=E_, state_names=state_names, input_names=input_names,
            constant_names=constant_names, state_labels=state_labels,
            input_labels=input_labels, constant_labels=constant_labels)
        model._check_partition()
        return model

    def _check_partition(self):
        """The dependent coordinates/speeds must be determined by the
        constraints: square blocks, of full rank at a sample point."""
        import random
        rng = random.Random(1234)
        if self.mc != len(self.q_dep):
            raise ModelError(f"{self.mc} configuration constraints but {len(self.q_dep)} dependent coordinates")
        if self.mv != len(self.u_dep):
            raise ModelError(f"{self.mv} velocity constraints but {len(self.u_dep)} dependent speeds")
        if self.mv < self.mc:
            raise ModelError(
                f"{self.mc} configuration constraints but only {self.mv} velocity constraints: "
                "every configuration constraint needs its time derivative among the velocity constraints")
        syms = self.q + self.p + [self.t]
        checks = []
        if self.mc:
            J = self.fc.jacobian(self.q)
            checks.append((J[:, self.q_dep], "configuration constraints", "dependent coordinates",
                           [self.state_names[i] for i in self.q_dep]))
        if self.mv:
            checks.append((self.A[:, self.u_dep], "velocity constraints", "dependent speeds",
                           [self.state_names[self.nq + i] for i in self.u_dep]))
        for block, cname, dname, names in checks:
            ok = False
            for _attempt in range(5):
                vals = {s: rng.uniform(0.3, 1.7) for s in syms}
                try:
                    num = sm.Matrix(block.xreplace(vals)).evalf()
                    import numpy as np
                    arr = np.array(num.tolist(), dtype=float)
                except (TypeError, ValueError):
                    continue
                if not np.all(np.isfinite(arr)):
                    continue
                if np.linalg.matrix_rank(arr) == arr.shape[0]:
                    ok = True
                    break
            if not ok:
                raise ModelError(
                    f"the {cname} do not determine the {dname} {names}: their Jacobian "
                    f"with respect to them is rank-deficient at random sample points; "
                    "choose another partition")


_PRINTABLE_FUNCS = (sm.sin, sm.cos, sm.tan, sm.asin, sm.acos, sm.atan, sm.atan2, sm.sinh,
                    sm.cosh, sm.tanh, sm.asinh, sm.acosh, sm.atanh, sm.exp, sm.log,
                    sm.Abs, sm.sign, sm.floor, sm.ceiling, sm.Min, sm.Max, sm.erf,
                    sm.gamma, sm.loggamma, sm.Piecewise, sm.Heaviside)


def _check_expressions(mat, what, allowed):
    """Refuse free symbols, leftover derivatives and unknown functions,
    naming the culprit."""
    free = set()
    for e in mat:
        free |= e.free_symbols
    extra = free - allowed
    if extra:
        names = sorted(str(s) for s in extra)
        raise ModelError(
            f"the {what} contain symbol(s) {', '.join(names)} that are neither coordinates, "
            "speeds, inputs nor constants: give them a value in constants={...} or list "
            "them in inputs=[...]")
    for e in mat:
        d = e.atoms(sm.Derivative)
        if d:
            raise ModelError(
                f"the {what} contain derivative term(s) {sorted(map(str, d))[:3]}: "
                "express them through the speeds (kinematic equations) or declare them")
        for fn in e.atoms(sm.Function):
            if isinstance(fn, sm.core.function.AppliedUndef):
                raise ModelError(
                    f"the {what} contain {fn.func}(t), a function of time that is not a "
                    "coordinate, "
                    "speed or declared input: list it in inputs=[...]")
            if not isinstance(fn, _PRINTABLE_FUNCS):
                raise ModelError(
                    f"the {what} contain the function {type(fn).__name__} ({fn}), "
                    "which the C printer cannot print")
