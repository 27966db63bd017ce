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
For a LagrangesMethod this lam equals the multiplier part of the solution of
sympy's ``mass_matrix_full`` / ``forcing_full`` system (and of ``LM.rhs()``),
the negative of what ``LM.solve_multipliers`` returns (sympy issue 30215).

The C naming rules (validate_name, c_name, c_names) live in gen.names and
are re-exported here.
"""
from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field

import sympy as sm
from sympy.core.basic import _args_sortkey
from sympy.physics import mechanics as me

from ..core.errors import ModelError
from .hybrid import attach_hybrid
from ..sym.printers import check_printable
from ..core.names import C_KEYWORDS, C_LIBRARY_NAMES, c_name, c_names, validate_name  # noqa: F401

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


# ---------------------------------------------------------------- containers
# Model.from_kanes / from_lagrange / from_system accept the formed method or
# an object holding one: a sympy System (``eom_method``), a JointsMethod
# (``method``) or a PyDy System (``eom_method``, ``constants``,
# ``specifieds``). They never call ``form_eoms`` themselves: that call picks
# the backend (Kane or Lagrange) and its options, which is the user's choice.

_ACCEPTED = {
    "kane": ("Model.from_kanes", "KanesMethod",
             "use Model.from_lagrange or Model.from_system"),
    "lagrange": ("Model.from_lagrange", "LagrangesMethod",
                 "use Model.from_kanes or Model.from_system"),
}


def _is_pydy_system(obj):
    try:
        from pydy.system import System as PydySystem
    except Exception:                          # pydy missing or broken
        PydySystem = None
    if PydySystem is not None and isinstance(obj, PydySystem):
        return True
    # duck type (a stand-in, or another pydy version): the three attributes
    # PyDy documents, and not sympy's System (which has no specifieds)
    return (not isinstance(obj, me.System) and hasattr(type(obj), "eom_method")
            and hasattr(obj, "constants") and hasattr(obj, "specifieds"))


def _unwrap(obj):
    """(formed method or None, description of obj, container kind, what the
    user must call to form it). kind: None (a method itself), "system",
    "joints" or "pydy"."""
    if isinstance(obj, (me.KanesMethod, me.LagrangesMethod)):
        return obj, type(obj).__name__, None, None
    if isinstance(obj, me.System):
        m = obj.eom_method
        kind, label, call = "system", "System", "system.form_eoms()"
    elif isinstance(obj, me.JointsMethod):
        m = obj.method
        kind, label, call = "joints", "JointsMethod", "method.form_eoms()"
    elif _is_pydy_system(obj):
        m = obj.eom_method
        kind, label, call = "pydy", "pydy System", "km.kanes_equations(bodies, loads)"
    else:
        return None, type(obj).__name__, None, None
    if m is None:
        return None, f"{label} without equations of motion", kind, call
    return m, f"{label} with a {type(m).__name__}", kind, call


def _method_of(obj, want):
    """The formed KanesMethod (want="kane") or LagrangesMethod ("lagrange")
    held by obj, and obj's container kind; a ModelError naming what was given
    and what is accepted otherwise."""
    caller, cls_name, other = _ACCEPTED[want]
    m, desc, kind, call = _unwrap(obj)
    accepted = (f"(accepted: a {cls_name}, or a sympy System, JointsMethod or pydy "
                "System holding one)")
    if m is None and kind is not None:
        raise ModelError(
            f"{caller} needs a {cls_name}, got {desc}: call {call} first (eomgen does not "
            f"form the equations itself: the backend is your choice) {accepted}")
    want_cls = me.KanesMethod if want == "kane" else me.LagrangesMethod
    if not isinstance(m, want_cls):
        hint = f": {other}" if isinstance(m, (me.KanesMethod, me.LagrangesMethod)) else ""
        raise ModelError(f"{caller} needs a {cls_name}, got {desc}{hint} {accepted}")
    return m, kind


def _pydy_defaults(obj):
    """(constants, inputs) of a PyDy System: its constants dict as given, and
    its specified quantities (the keys of its specifieds, then any other
    specified symbol it knows, by name)."""
    constants = dict(obj.constants or {})
    spec = obj.specifieds or {}
    inputs = []
    if "symbols" in spec and "values" in spec:
        inputs = list(spec["symbols"])
    else:
        for k in spec:
            inputs.extend(k if isinstance(k, tuple) else [k])
    rest = getattr(obj, "specifieds_symbols", None) or ()
    inputs += sorted((s for s in rest if s not in inputs), key=str)
    return constants, inputs


def _lagrange_partition(system, lm, partition):
    """q_ind/q_dep/qd_ind/qd_dep for a LagrangesMethod from a sympy System:
    the user's where given, else the System's coordinates and, for the
    derivatives, its speeds when they are the coordinate derivatives and
    split as the velocity constraints need (a Lagrange System built with q'
    as the joints' speeds), else q_ind' and q_dep'."""
    out = dict(partition)
    t = me.dynamicsymbols._t
    if not out.get("q_ind") and not out.get("q_dep"):
        out["q_ind"], out["q_dep"] = list(system.q_ind), list(system.q_dep)
    if not out.get("qd_ind") and not out.get("qd_dep"):
        qdots = {qi.diff(t) for qi in lm.q}
        u_ind, u_dep = list(system.u_ind), list(system.u_dep)
        n_vc = len(lm.coneqs) if lm.coneqs is not None else 0
        if (u_ind or u_dep) and all(s in qdots for s in u_ind + u_dep) \
                and len(u_ind) + len(u_dep) == len(lm.q) and len(u_dep) == n_vc:
            out["qd_ind"], out["qd_dep"] = u_ind, u_dep
        else:
            out["qd_ind"] = [s.diff(t) for s in (out.get("q_ind") or [])]
            out["qd_dep"] = [s.diff(t) for s in (out.get("q_dep") or [])]
    return out


def user_stacklevel():
    """warnings.warn's stacklevel, from the function calling this, of the
    first frame outside the gen package (the user's call)."""
    import os
    import sys
    here = os.path.dirname(os.path.abspath(__file__))
    f, level = sys._getframe(1), 1
    while f is not None and os.path.dirname(os.path.abspath(f.f_code.co_filename)) == here:
        f, level = f.f_back, level + 1
    return level


def _warn_unused(cls, model_name, kind, names, what):
    """Warn (cls) that the model's constants or inputs `names` appear in no
    expression; `what` lists where they were looked for and what follows."""
    if not names:
        return
    import warnings
    many = len(names) > 1
    warnings.warn(cls(f"model '{model_name}': {kind}{'s' if many else ''} {', '.join(names)} "
                      f"appear{'' if many else 's'} in no expression of the model {what}"),
                  stacklevel=user_stacklevel())


_user_stacklevel = user_stacklevel


# what turns a sympy object into a gen.Model: the constructor to call first
_CONSTRUCTORS = (("KanesMethod", "gen.Model.from_kanes(km, constants={...}, inputs=[...])"),
                 ("LagrangesMethod", "gen.Model.from_lagrange(lm, constants={...}, "
                  "inputs=[...])"),
                 ("JointsMethod", "gen.Model.from_system(method, constants={...}, "
                  "inputs=[...])"),
                 ("System", "gen.Model.from_system(system, constants={...}, inputs=[...])"))


def require_model(obj, caller):
    """obj itself when it is a gen.Model; otherwise a ModelError that says
    what was given and, for a sympy mechanics object, the constructor to
    call first (gen.compile(km) used to fail with "AttributeError: ... has
    no attribute 'M'")."""
    if isinstance(obj, Model):
        return obj
    kind = type(obj).__name__
    for name, ctor in _CONSTRUCTORS:
        cls = getattr(me, name, None)
        if (cls is not None and isinstance(obj, cls)) or (name == "System"
                                                          and _is_pydy_system(obj)):
            raise ModelError(
                f"{caller} takes a gen.Model, got a sympy {kind}: make the model first with "
                f"{ctor}, then {caller}(model, ...)")
    raise ModelError(f"{caller} takes a gen.Model (from gen.Model.from_kanes, from_lagrange "
                     f"or from_system), got {kind}")


def _constant_value(c, v):
    """The float value of constant c, or a ModelError naming c (as the user
    spelt it) and the value: NaN, infinite, complex, symbolic or not a
    number at all."""
    import math

    import numpy as np

    shown = repr(v) if isinstance(v, (str, bytes)) else str(v)

    def refuse(what):
        raise ModelError(f"constant {c} has a value {shown} that is {what}")

    finite_real = "; constants must be finite real numbers"
    if isinstance(v, (str, bytes)):
        refuse("not a number")
    if isinstance(v, (complex, np.complexfloating)) or (
            isinstance(v, np.ndarray) and v.dtype.kind == "c"):
        refuse("complex" + finite_real)
    if isinstance(v, sm.Basic):
        if not isinstance(v, sm.Expr):
            refuse("not a number")
        free = sorted(str(s) for s in v.free_symbols)
        if free:
            refuse(f"a sympy expression in {', '.join(free)}, not a number; give its "
                   "numeric value")
        if v.has(sm.nan):
            refuse("NaN" + finite_real)
        if v.has(sm.zoo, sm.oo, -sm.oo):
            refuse("infinite" + finite_real)
        re_, im_ = sm.N(v, 20).as_real_imag()
        if im_ != 0:
            refuse("complex" + finite_real)
        v = re_
    try:
        fv = float(v)
    except (TypeError, ValueError):
        refuse("not a number")
    if math.isnan(fv):
        refuse("NaN" + finite_real)
    if math.isinf(fv):
        refuse("infinite" + finite_real)
    return fv


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
    # auxiliary speeds (Kane's u_auxiliary): the reaction forces along them
    # solve aux_F reactions + aux_g = 0 (NA rows, aux_F square), with aux_F
    # and aux_g in q, u, ud (the internal symbols of u'), r, p, t
    aux_F: sm.Matrix | None = None
    aux_g: sm.Matrix | None = None
    # reactions inside the dynamics, solved with u' at run time (one linear
    # system in [u', reactions] per evaluation): f holds them at zero and
    # M u' = f + aux_G reactions (NU x NA, in q, u, r, p, t); None when the
    # reactions do not enter the motion or were eliminated symbolically
    aux_G: sm.Matrix | None = None
    ud: list = field(default_factory=list)
    reaction_orig: list = field(default_factory=list)
    auxiliary_names: list = field(default_factory=list)   # C-safe, unique
    auxiliary_labels: list = field(default_factory=list)  # as sympy prints them
    # internal symbols of q' in the acceleration-constraint term a, when the
    # kinematics are implicit (qdot is None) and there are velocity
    # constraints; empty otherwise (a is then a function of q, u, t)
    qd: list = field(default_factory=list)
    # outputs y(q, u, r, p, t) (from_kanes(..., outputs={name: expr})): NY rows
    y: sm.Matrix = field(default_factory=lambda: sm.zeros(0, 1))
    output_names: list = field(default_factory=list)    # C-safe, unique
    output_labels: list = field(default_factory=list)   # as the user named them
    # hybrid={name: gen.Impact | gen.Reset} (gen/intake/hybrid.py): HybridDecl in order
    hybrid: list = field(default_factory=list)

    # ------------------------------------------------------------------ sizes
    @property
    def a(self):
        """The acceleration-constraint term a = d(A u + b)/dq q' + d(A u +
        b)/dt (A u' + a = 0), in q' = qdot(q, u) with explicit kinematics, else
        in the symbols qd. Formed on first use (the derivative kernels, the
        symbolic references); the right-hand side's code computes it as a
        directional derivative on its own graph (gen.plan.ir.core_kernels)."""
        a = self.__dict__.get("_a")
        if a is None:
            from ..sym.graph import gradient
            if not self.mv:
                a = sm.zeros(0, 1)
            else:
                fv = self.A * sm.Matrix(self.u) + self.b
                qdot = list(self.qdot) if self.qdot is not None else list(self.qd)
                rows = []
                for e in fv:
                    # one reverse sweep per row (a symbolic Jacobian of A u + b
                    # walks each row once per coordinate)
                    g = gradient(e, set(self.q) | {self.t})
                    rows.append(sm.Add(*[g[x] * v for x, v in zip(self.q, qdot) if x in g])
                                + g.get(self.t, sm.S.Zero))
                a = sm.Matrix(rows)
            self.__dict__["_a"] = a
        return a

    @property
    def nq(self):
        """Number of generalized coordinates q."""
        return len(self.q)

    @property
    def nu(self):
        """Number of generalized speeds u."""
        return len(self.u)

    @property
    def nx(self):
        """Size of the state x = [q, u]."""
        return self.nq + self.nu

    @property
    def ny(self):
        """Number of outputs."""
        return self.y.shape[0]

    @property
    def na(self):
        """Number of auxiliary speeds (= reaction forces)."""
        return 0 if self.aux_F is None else self.aux_F.shape[0]

    @property
    def nr(self):
        """Number of inputs r."""
        return len(self.r)

    @property
    def np(self):
        """Number of constants p."""
        return len(self.p)

    @property
    def mc(self):
        """Number of configuration constraints f_c(q) = 0 (dependent coordinates)."""
        return self.fc.shape[0]

    @property
    def mv(self):
        """Number of velocity constraints A u + b = 0 (multipliers)."""
        return self.A.shape[0]

    @property
    def ns(self):
        """Size of the independent state [q_ind, u_ind] (linearization)."""
        return self.nq - self.mc + self.nu - self.mv

    @property
    def independent_state_names(self):
        """The names of the independent state [q_ind, u_ind], the state of ``linearize``."""
        return ([self.state_names[i] for i in self.q_ind]
                + [self.state_names[self.nq + i] for i in self.u_ind])

    def fingerprint(self) -> str:
        """A hash of everything generation depends on.

        Returns
        -------
        str
            Hex digest; equal models give equal fingerprints.
        """
        h = hashlib.sha256()
        parts = [self.name, self.method, repr(self.q_ind), repr(self.q_dep),
                 repr(self.u_ind), repr(self.u_dep), repr(self.state_names),
                 repr(self.input_names), repr(self.constant_names)]
        sub = {s: sm.Symbol(f"_q{i}") for i, s in enumerate(self.q)}
        sub.update({s: sm.Symbol(f"_u{i}") for i, s in enumerate(self.u)})
        sub.update({s: sm.Symbol(f"_r{i}") for i, s in enumerate(self.r)})
        sub.update({s: sm.Symbol(f"_p{i}") for i, s in enumerate(self.p)})
        sub[self.t] = sm.Symbol("_t")
        sub.update({s: sm.Symbol(f"_qd{i}") for i, s in enumerate(self.qd)})
        # (a follows from A, b and the kinematics)
        for mat in (self.Kqd, self.Ku, self.kf, self.M, self.f, self.A, self.b, self.fc):
            parts.append(_srepr(mat, sub))
        if self.energy is not None:
            parts.append(sm.srepr(self.energy.xreplace(sub)))
        if self.ny:
            parts += [repr(self.output_names), sm.srepr(self.y.xreplace(sub))]
        if self.na:
            sub.update({s: sm.Symbol(f"_ud{i}") for i, s in enumerate(self.ud)})
            parts += [repr(self.auxiliary_names), sm.srepr(self.aux_F.xreplace(sub)),
                      sm.srepr(self.aux_g.xreplace(sub))]
            if self.aux_G is not None:
                parts += ["coupled", sm.srepr(self.aux_G.xreplace(sub))]
        for d in self.hybrid:
            xm = None if d.xmap is None else [sm.srepr(e.xreplace(sub)) for e in d.xmap]
            parts.append(repr((d.name, d.kind, sm.srepr(d.expr.xreplace(sub)), d.restitution,
                               d.direction, d.rest_speed, xm)))
        for part in parts:
            h.update(part.encode())
            h.update(b"\0")
        return h.hexdigest()

    # ------------------------------------------------------------ builders
    @classmethod
    def from_kanes(cls, km, constants=None, inputs=None, name="model",
                   energy=None, reactions=None, outputs=None, hybrid=None):
        """Build from a ``KanesMethod`` after ``kanes_equations``.

        Parameters
        ----------
        km : KanesMethod, sympy System, JointsMethod or PyDy System
            The formed equations of motion. A sympy ``System`` or
            ``JointsMethod`` after ``form_eoms()`` with the Kane backend, or a
            PyDy ``System`` (whose ``constants`` and ``specifieds`` give
            constants and inputs when these are None), go in too; see
            :meth:`from_system`.
        constants : dict, optional
            ``{symbol: value}`` for every parameter, finite real numbers (a
            constant that appears in no expression gives a
            :class:`gen.UnusedConstantWarning`).
        inputs : list, optional
            Symbols or functions of time that are the inputs r, in this order.
        name : str, optional
            The model's name: the prefix of every C symbol (``[a-z][a-z0-9_]*``,
            not a C keyword or a C library name).
        energy : sympy expression, optional
            The total energy, for diagnostics (``sim.energy``, the CSV).
        reactions : list, optional
            With ``u_auxiliary``: the unknown reaction forces (functions of time),
            in the order wanted; by default found in ``km.auxiliary_eqs`` and
            ordered by name. When the auxiliary equations hold no unknown force
            (every force along the auxiliary directions is a declared input or
            constant), the model is built all the same and
            ``sim.auxiliary_forces`` gives, for each auxiliary speed (named
            after it), the generalized force that direction still needs to
            keep its speed zero, minus the value of its auxiliary equation
            (Kane's Fr + Fr*) at the declared inputs: zero when they are the
            forces the auxiliary direction carries, and with the declared
            force along it at zero, the reaction itself (the number the model
            with that force left unknown gives). Reactions that enter the
            motion (friction ``-mu*N``) are eliminated exactly when their
            auxiliary coefficients are constant, else solved with u' at run
            time, one linear system per evaluation (:doc:`/guides/model`).
        outputs : dict, optional
            ``{name: expression}`` of quantities to measure (sensor readings,
            point positions) in the coordinates, speeds, inputs, constants and t
            (``sim.outputs``; ``linearize_outputs`` gives C and D).
        hybrid : dict, optional
            ``{name: gen.Impact(gap, ...) or gen.Reset(guard, map, ...)}``:
            impacts and resets, run in C with the rest of the model; every jump
            is logged in ``sol.events`` (``docs/guides/hybrid.md``).

        Returns
        -------
        Model
            The canonical model, validated.

        Raises
        ------
        gen.ModelError
            When the model cannot be generated correctly as given: a free symbol
            that is neither a coordinate, a speed, an input nor a constant, a
            non-finite constant, a bad name or partition, an expression the
            generator cannot print (the message names the culprit).
        """
        validate_name(name)
        container = km
        km, kind = _method_of(km, "kane")
        if kind == "pydy":
            pd_constants, pd_inputs = _pydy_defaults(container)
            constants = pd_constants if constants is None else constants
            inputs = pd_inputs if inputs is None else inputs
        if getattr(km, "_fr", None) is None:
            raise ModelError("call km.kanes_equations(bodies, loads) before Model.from_kanes")
        uaux = list(km._uaux) if getattr(km, "_uaux", None) is not None else []
        if reactions is not None and not uaux:
            raise ModelError("reactions given but the KanesMethod has no auxiliary speeds "
                             "(u_auxiliary)")
        t = me.dynamicsymbols._t
        q = list(km.q)
        u = list(km.u)
        nq, nu = len(q), len(u)
        nqd = len(km._qdep) if km._qdep is not None else 0
        nud = len(km._udep) if km._udep is not None else 0
        qdots = [qi.diff(t) for qi in q]

        # the kinematic equations as the user wrote them (Kqd q' + Ku u + kf = 0),
        # never sympy's symbolic solve for q' (explicit_kinematics=True), whose
        # expressions can be 0/0 at regular configurations (ZYX Euler angles at
        # hover): q' is solved numerically at run time when Kqd is not diagonal
        Kqd = sm.Matrix(getattr(km, "_k_kqdot_implicit", km._k_kqdot))
        Ku = sm.Matrix(getattr(km, "_k_ku_implicit", km._k_ku))
        kf = sm.Matrix(getattr(km, "_f_k_implicit", km._f_k))
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

        aux = None
        if uaux:
            # the auxiliary speeds and their derivatives are zero in every
            # equation of the real speeds (sympy zeroes them in its own M, f;
            # the unconstrained M, f above are formed again, so do it here)
            zero = _aux_zero(uaux, t)
            M, f = M.xreplace(zero[0]).xreplace(zero[1]), f.xreplace(zero[0]).xreplace(zero[1])
            # velocity constraints written with the auxiliary speeds (a contact
            # point's velocity, sympy's test_aux_dep): sympy keeps them in
            # _k_nh/_f_nh; they are zero in the real motion too
            A, b = A.xreplace(zero[0]).xreplace(zero[1]), b.xreplace(zero[0]).xreplace(zero[1])
            aux = _kane_auxiliary(km, q, u, uaux, inputs, reactions, t, zero)
            if any(M.has(r_) or f.has(r_) for r_ in aux[1]):
                M, f, aux = _eliminate_reactions(M, f, aux, [ui.diff(t) for ui in u], q,
                                                 constrained=bool(nud))
        qdot_map = dict(km._qdot_u_map) if km._qdot_u_map else {}
        return attach_hybrid(cls._finish(
            name=name, method="kane", t=t, q=q, u=u, qdots=qdots, udots=[ui.diff(t) for ui in u],
            q_ind=list(range(nq - nqd)), q_dep=list(range(nq - nqd, nq)),
            u_ind=list(range(nu - nud)), u_dep=list(range(nu - nud, nu)),
            Kqd=Kqd, Ku=Ku, kf=kf, M=M, f=f, A=A, b=b, fc=fc,
            qdot_subs=qdot_map, constants=constants, inputs=inputs, energy=energy,
            speed_names=[_sym_name(x) for x in u], aux=aux, outputs=outputs), hybrid)

    @classmethod
    def from_lagrange(cls, lm, q_ind=None, qd_ind=None, q_dep=None, qd_dep=None,
                      constants=None, inputs=None, name="model", energy=None, outputs=None,
                      hybrid=None):
        """Build from a ``LagrangesMethod`` after ``form_lagranges_equations``.

        The state is x = [q, q'] in the method's coordinate order.

        Parameters
        ----------
        lm : LagrangesMethod, sympy System or JointsMethod
            The formed equations of motion (a ``System`` or ``JointsMethod``
            after ``form_eoms(LagrangesMethod)`` goes in too).
        q_ind, q_dep : list, optional
            The partition of the coordinates, as for sympy's
            ``LagrangesMethod.linearize`` (:doc:`/guides/partitions`); with a
            System and no partition, the System's own.
        qd_ind, qd_dep : list, optional
            Their derivatives (with a System: its u_ind/u_dep when they are the
            coordinate derivatives, else q_ind'/q_dep').
        constants : dict, optional
            ``{symbol: value}`` for every parameter, finite real numbers (a
            constant that appears in no expression gives a
            :class:`gen.UnusedConstantWarning`).
        inputs : list, optional
            Symbols or functions of time that are the inputs r, in this order.
        name : str, optional
            The model's name: the prefix of every C symbol (``[a-z][a-z0-9_]*``,
            not a C keyword or a C library name).
        energy : sympy expression, optional
            The total energy, for diagnostics (``sim.energy``, the CSV).
        outputs : dict, optional
            ``{name: expression}`` of quantities to measure (sensor readings,
            point positions) in the coordinates, speeds, inputs, constants and t
            (``sim.outputs``; ``linearize_outputs`` gives C and D).
        hybrid : dict, optional
            ``{name: gen.Impact(gap, ...) or gen.Reset(guard, map, ...)}``:
            impacts and resets, run in C with the rest of the model; every jump
            is logged in ``sol.events`` (``docs/guides/hybrid.md``).

        Returns
        -------
        Model
            The canonical model, validated.

        Raises
        ------
        gen.ModelError
            When the model cannot be generated correctly as given: a free symbol
            that is neither a coordinate, a speed, an input nor a constant, a
            non-finite constant, a bad name or partition, an expression the
            generator cannot print (the message names the culprit).
        """
        validate_name(name)
        container = lm
        lm, kind = _method_of(lm, "lagrange")
        if kind == "system":
            part = _lagrange_partition(container, lm, dict(
                q_ind=q_ind, q_dep=q_dep, qd_ind=qd_ind, qd_dep=qd_dep))
            q_ind, q_dep = part["q_ind"], part["q_dep"]
            qd_ind, qd_dep = part["qd_ind"], part["qd_dep"]
        elif kind == "pydy":
            pd_constants, pd_inputs = _pydy_defaults(container)
            constants = pd_constants if constants is None else constants
            inputs = pd_inputs if inputs is None else inputs
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
        return attach_hybrid(cls._finish(
            name=name, method="lagrange", t=t, q=q, u=qdots, qdots=qdots, udots=qdds,
            q_ind=qi, q_dep=qdp, u_ind=ui, u_dep=udp,
            Kqd=Kqd, Ku=Ku, kf=kf, M=M, f=f, A=A, b=b, fc=fc,
            qdot_subs={}, constants=constants, inputs=inputs, energy=energy,
            speed_names=[_sym_name(x) + "_d" for x in q], outputs=outputs), hybrid)

    @classmethod
    def from_system(cls, obj, constants=None, inputs=None, name="model", energy=None,
                    outputs=None, formulation="kane", hybrid=None, **partition):
        """Build from whatever holds formed equations of motion.

        Dispatches to :meth:`from_kanes` or :meth:`from_lagrange` on the formed
        method; with ``formulation="recursive"``, forms the equations of a sympy
        System's joint tree itself (:mod:`gen.recursive`).

        Parameters
        ----------
        obj : KanesMethod, LagrangesMethod, sympy System, JointsMethod or PyDy System
            After ``kanes_equations`` / ``form_lagranges_equations`` /
            ``form_eoms()`` (either backend).
        constants : dict, optional
            As for :meth:`from_kanes`; for a PyDy System, None takes its
            ``constants`` dict.
        inputs : list, optional
            As for :meth:`from_kanes`; for a PyDy System, None takes its specified
            quantities.
        name : str, optional
            The model's name: the prefix of every C symbol (``[a-z][a-z0-9_]*``,
            not a C keyword or a C library name).
        energy : sympy expression, optional
            The total energy, for diagnostics (``sim.energy``, the CSV).
        outputs : dict, optional
            ``{name: expression}`` of quantities to measure (sensor readings,
            point positions) in the coordinates, speeds, inputs, constants and t
            (``sim.outputs``; ``linearize_outputs`` gives C and D).
        hybrid : dict, optional
            ``{name: gen.Impact(gap, ...) or gen.Reset(guard, map, ...)}``:
            impacts and resets, run in C with the rest of the model; every jump
            is logged in ``sol.events`` (``docs/guides/hybrid.md``).
        formulation : {"kane", "recursive", "crba"}, optional
            ``"kane"``: the equations the method formed (``form_eoms()`` first).
            ``"recursive"``: a sympy System's joint tree, its equations formed
            here (no ``form_eoms()`` needed, none called), the System's kdes as
            the kinematics (:mod:`gen.recursive`; trees of rigid bodies and
            sympy's joints). An open tree (no constraints, no ``hybrid``): u' by
            the articulated body algorithm, the model's mass matrix the identity
            and its forcing u' (``sim.mass_matrix`` is I); with constraints or
            ``hybrid``: the mass matrix by the composite rigid body algorithm,
            the forcing by recursive Newton-Euler. ``"crba"``: the same tree,
            always by CRBA + RNEA, for the physical mass matrix and forcing
            (``sim.mass_matrix`` is M; a slower build and rhs from n ~ 20).
        **partition
            The further keywords of the builder: q_ind, q_dep, qd_ind, qd_dep for
            Lagrange models (a sympy System's own partition is the default), those
            of :meth:`from_kanes` for Kane models.

        Returns
        -------
        Model
            The canonical model, validated.

        Raises
        ------
        gen.ModelError
            As :meth:`from_kanes`; also for a System whose ``form_eoms()`` was not
            called (or whose equations were reset by a later change): eomgen never
            forms the equations itself.
        """
        if formulation in ("recursive", "crba"):
            if partition:
                raise ModelError(
                    f"unknown argument(s) {', '.join(sorted(partition))} for "
                    f"Model.from_system with formulation={formulation!r}: accepted are none")
            from .recursive import accelerations_of_tree, constraints_of_tree, equations_of_tree
            cons = constraints_of_tree(obj)
            if cons is None and not hybrid and formulation == "recursive":
                # an open tree: u' by the articulated body algorithm, the
                # model's M the identity (gen.recursive's docstring)
                ud, q, u, kdes = accelerations_of_tree(obj)
                M, f = sm.eye(len(u)), ud
            else:
                M, f, q, u, kdes = equations_of_tree(obj)
            return cls.from_matrices(M, f, q, u, kdes, constants=constants, inputs=inputs,
                                     name=name, energy=energy, outputs=outputs, hybrid=hybrid,
                                     _constraints=cons)
        if formulation != "kane":
            raise ModelError(f"formulation={formulation!r} for Model.from_system: "
                             "accepted are 'kane', 'recursive' and 'crba'")
        m, desc, kind, call = _unwrap(obj)
        needs = "Model.from_system needs a KanesMethod or LagrangesMethod"
        accepted = ("(accepted: a KanesMethod or LagrangesMethod, or a sympy System, "
                    "JointsMethod or pydy System holding one)")
        if m is None and kind is not None:
            raise ModelError(f"{needs}, got {desc}: call {call} first {accepted}")
        import inspect
        lagrange_part = {"q_ind", "q_dep", "qd_ind", "qd_dep"}
        if isinstance(m, me.KanesMethod):
            builder = cls.from_kanes
            given = sorted(set(partition) & lagrange_part)
            if given:
                raise ModelError(
                    f"{', '.join(given)} given for a Kane model ({desc}): the "
                    "partition of a KanesMethod is its own (q_ind/q_dependent, "
                    "u_ind/u_dependent)")
        elif isinstance(m, me.LagrangesMethod):
            builder = cls.from_lagrange
        else:
            raise ModelError(f"{needs}, got {desc} {accepted}")
        # the builder's own further keywords (partition, reactions, ...)
        extra = [k for k in inspect.signature(builder).parameters
                 if k not in ("km", "lm", "constants", "inputs", "name", "energy", "outputs",
                              "hybrid")]
        bad = sorted(set(partition) - set(extra))
        if bad:
            raise ModelError(
                f"unknown argument(s) {', '.join(bad)} for Model.from_system with {desc}: "
                f"accepted are {', '.join(extra) or 'none'}")
        return builder(obj, constants=constants, inputs=inputs, name=name, energy=energy,
                       outputs=outputs, hybrid=hybrid, **partition)

    # ---- from matrices (gen.pydy: PyDy's forms; any M, f and kinematics) ----
    @classmethod
    def from_matrices(cls, mass_matrix, forcing, coordinates, speeds, kinematics,
                      constants=None, inputs=None, name="model", energy=None, outputs=None,
                      hybrid=None, _constraints=None):
        """Build from the equations themselves, without a formed method.

        ``mass_matrix * speeds' = forcing``, with the kinematic equations
        ``kinematics = 0`` (as ``KanesMethod``'s ``kd_eqs``: linear in the
        coordinate derivatives and in the speeds, one row per coordinate).
        No constraints: the speeds are all independent.

        Parameters
        ----------
        mass_matrix : sympy Matrix, shape (nu, nu)
            M(q, t); it must not depend on the speeds or the inputs.
        forcing : sympy Matrix, shape (nu, 1)
            f(q, u, r, t).
        coordinates, speeds : list
            The coordinates q and speeds u (functions of time), in the order of
            the kinematic rows and of the mass matrix's rows and columns.
        kinematics : sympy Matrix, shape (nq, 1)
            Expressions that vanish, ``q' - G(q, u)`` for explicit kinematics.
        constants, inputs, name, energy, outputs, hybrid
            As for :meth:`from_kanes`.
        _constraints : tuple, optional
            Internal (``gen.recursive``): a System's constraints as
            ``(fc, A, b, nq_dep, nu_dep)``, the dependent coordinates and speeds
            last; not for users.

        Returns
        -------
        Model
            The canonical model, validated.

        Raises
        ------
        gen.ModelError
            As :meth:`from_kanes`; also when a shape does not match or the
            kinematics are not linear in q' and u (the row is named).
        """
        validate_name(name)
        t = me.dynamicsymbols._t
        q, u = list(coordinates), list(speeds)
        nq, nu = len(q), len(u)
        M = sm.Matrix(mass_matrix)
        f = _as_matrix(forcing, "forcing")
        kd = _as_matrix(kinematics, "kinematics")
        if M.shape != (nu, nu):
            raise ModelError(f"mass_matrix has shape {M.shape}, expected ({nu}, {nu}) "
                             f"for {nu} speed(s)")
        if f.shape != (nu, 1):
            raise ModelError(f"forcing has shape {f.shape}, expected ({nu}, 1)")
        if kd.shape != (nq, 1):
            raise ModelError(f"kinematics has shape {kd.shape}, expected ({nq}, 1) "
                             f"for {nq} coordinate(s)")
        qdots = [qi.diff(t) for qi in q]
        # Kqd q' + Ku u + kf = 0: the coefficients, and the check that no row
        # holds q' or u beyond them (the linearization relies on the split)
        Qd = [sm.Dummy(f"qd{i}") for i in range(nq)]
        Ud = [sm.Dummy(f"u{i}") for i in range(nu)]
        kd_ = kd.xreplace(dict(zip(qdots, Qd))).xreplace(dict(zip(u, Ud)))
        Kqd = _row_jacobian(kd_, Qd)
        Ku = _row_jacobian(kd_, Ud)
        kf = kd_.xreplace({s: 0 for s in Qd + Ud})
        for i in range(nq):
            if any(e.has(*Qd, *Ud) for e in list(Kqd[i, :]) + list(Ku[i, :])):
                raise ModelError(
                    f"kinematics row {i} ({kd[i]}) is not linear in the coordinate "
                    "derivatives and the speeds")
        back = dict(zip(Ud, u))
        Kqd, Ku = Kqd.xreplace(back), Ku.xreplace(back)
        kf = kf.xreplace(back)
        # explicit kinematics (Kqd diagonal): q' in M and f becomes its value
        qdot_map = {}
        if all(Kqd[i, j] == 0 for i in range(nq) for j in range(nq) if i != j) \
                and all(Kqd[i, i] != 0 for i in range(nq)):
            qdot_map = {qd_: -(Ku[i, :].dot(sm.Matrix(u)) + kf[i]) / Kqd[i, i]
                        for i, qd_ in enumerate(qdots)}
        # (gen.recursive: a System's constraints as a Kane model's, the
        # dependent coordinates and speeds last)
        fc, A, b, nqd, nud = _constraints or (sm.zeros(0, 1), sm.zeros(0, nu), sm.zeros(0, 1),
                                              0, 0)
        return attach_hybrid(cls._finish(
            name=name, method="kane", t=t, q=q, u=u, qdots=qdots,
            udots=[ui.diff(t) for ui in u], q_ind=list(range(nq - nqd)),
            q_dep=list(range(nq - nqd, nq)), u_ind=list(range(nu - nud)),
            u_dep=list(range(nu - nud, nu)), Kqd=Kqd, Ku=Ku, kf=kf, M=M, f=f,
            A=A, b=b, fc=fc, qdot_subs=qdot_map,
            constants=constants, inputs=inputs, energy=energy,
            speed_names=[_sym_name(x) for x in u], outputs=outputs), hybrid)

    # ------------------------------------------------------------ internals
    @classmethod
    def _finish(cls, *, name, method, t, q, u, qdots, udots, q_ind, q_dep, u_ind,
                u_dep, Kqd, Ku, kf, M, f, A, b, fc, qdot_subs, constants, inputs,
                energy, speed_names, aux=None, outputs=None):
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
        # finite real numbers only (NaN, inf, complex, symbolic: ModelError
        # naming the constant and its value), before anything is generated
        values = [_constant_value(c, v) for c, v in constants.items()]
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
        # one memo for every matrix: M and f (and the rest) share most of
        # their subexpressions, each converted once
        memo_qd, memo = {}, {}

        def conv(mat, what):
            mat = sm.Matrix(mat)
            if qd_subs:
                mat = _xreplace_shared(mat, qd_subs, memo_qd)
            out = _xreplace_shared(mat, sub, memo)
            check_printable(out, what, {v: k for k, v in sub.items()}, T)
            _check_expressions(out, what, set(Q) | set(U) | set(R) | set(P) | {T}, inputs)
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
        out_labels, Y_ = [], sm.zeros(0, 1)
        if outputs is not None:
            out_labels, exprs = _outputs_of(outputs)
            Y_ = conv(sm.Matrix(exprs), "outputs") if exprs else sm.zeros(0, 1)
        # auxiliary equations F reactions + g = 0: u' becomes the symbols UD
        UD, aux_F_, aux_g_, aux_G_, reactions, aux_of = [], None, None, None, [], []
        if aux is not None:
            UD = [sm.Dummy(f"ud{i}") for i in range(nu)]
            usub = dict(zip(udots, UD))
            back = {v: k for k, v in sub.items()}
            back.update({v: k for k, v in usub.items()})
            allowed = set(Q) | set(U) | set(UD) | set(R) | set(P) | {T}

            def conv_aux(mat, what):
                mat = sm.Matrix(mat)
                if qd_subs:
                    mat = mat.xreplace(qd_subs)
                mat = mat.xreplace(usub).xreplace(sub)     # u' before u
                check_printable(mat, what, back, T)
                _check_expressions(mat, what, allowed, inputs)
                return mat

            aux_F_ = conv_aux(aux[0], "auxiliary equations (reaction coefficients)")
            aux_g_ = conv_aux(aux[2], "auxiliary equations")
            if len(aux) > 4:
                # the reactions' coefficients in the dynamics (coupled solve)
                aux_G_ = conv_aux(aux[4], "forcing (reaction coefficients)")
            # the reactions solved for, and what names the auxiliary forces:
            # the reactions, or the auxiliary speeds when none is unknown
            reactions, aux_of = list(aux[1]), list(aux[3] if len(aux) > 3 else aux[1])

        # ---- constants that no expression uses: a warning naming them ----
        # (one walk over every distinct subexpression: the recursive
        # formulation's matrices share theirs, gen.recursive)
        used = _scan([e for mat in (Kqd_, Ku_, kf_, M_, f_, A_, b_, fc_, Y_) + (
            (aux_F_, aux_g_) if aux_F_ is not None else ()) + (
            (aux_G_,) if aux_G_ is not None else ()) for e in mat]
            + ([E_] if E_ is not None else []))[0]
        from ..core.errors import UnusedConstantWarning, UnusedInputWarning
        _warn_unused(UnusedConstantWarning, name, "constant",
                     [str(c) for c, d in zip(constants, P) if d not in used],
                     "(mass matrix, forcing, kinematic equations, constraints, energy); kept as "
                     "parameter(s) without effect")
        # ---- inputs that no equation uses: a warning naming them ---------
        _warn_unused(UnusedInputWarning, name, "input",
                     [str(r_) for r_, d in zip(inputs, R) if d not in used],
                     "(forcing, outputs, ...): kept as input(s) without effect (a misspelt or "
                     "stale entry of inputs=[...]?)")

        # ---- structure checks -------------------------------------------
        if M_.shape != (nu, nu):
            raise ModelError(f"mass matrix has shape {M_.shape}, expected ({nu}, {nu})")
        if f_.shape != (nu, 1):
            raise ModelError(f"forcing has shape {f_.shape}, expected ({nu}, 1)")
        if any(_has_any(M_, U)):
            raise ModelError("the mass matrix depends on the speeds; such models are not supported")
        # a speed whose row of M is identically zero (and that no velocity
        # constraint involves) has no acceleration equation: M (or the
        # constrained system) is singular at every state
        zero = [i for i in range(nu) if all(M_[i, j] == 0 for j in range(nu))
                and all(A_[k, i] == 0 for k in range(A_.shape[0]))]
        if zero:
            names = [str(speed_names[i]) for i in zero]
            if len(zero) == nu:       # nothing to simulate: refused
                raise ModelError(
                    f"model '{name}': the mass matrix is identically zero (speeds "
                    f"{', '.join(names)}): the equations of motion do not determine the "
                    "accelerations at any state (every simulation would fail as singular). "
                    "Give the bodies their masses and inertias (particles, rigid bodies) in "
                    "the equations you formed")
            # a massless part: its M and f (and sympy's own tests of them) are
            # meaningful, a simulation is not
            import warnings
            from ..core.errors import MasslessSpeedWarning
            warnings.warn(MasslessSpeedWarning(
                f"model '{name}': the mass matrix is zero in the row(s) of speed(s) "
                f"{', '.join(names)}: the equations of motion do not determine those "
                "accelerations (a massless particle or body?), so a simulation will stop "
                "as singular; M, f and their Jacobians are generated as given"),
                stacklevel=_user_stacklevel())
        for mat, what in ((Kqd_, "kinematic q' coefficients"), (Ku_, "kinematic u coefficients"),
                          (A_, "velocity-constraint matrix")):
            if any(_has_any(mat, U)) or any(_has_any(mat, R)):
                raise ModelError(f"the {what} depend on speeds or inputs; the kinematic "
                                 "equations and velocity constraints must be linear in the speeds")
        if any(_has_any(fc_, U + R)):
            raise ModelError("the configuration constraints depend on speeds or inputs")
        if any(_has_any(list(kf_) + list(b_), R)):
            raise ModelError("the kinematic equations or velocity constraints depend on inputs; not supported")

        # explicit q' when Kqd is diagonal (the usual q' = u)
        qdot = None
        if all(Kqd_[i, j] == 0 for i in range(nq) for j in range(nq) if i != j):
            diag = [Kqd_[i, i] for i in range(nq)]
            if all(d != 0 for d in diag):
                qdot = sm.Matrix([-(Ku_[i, :].dot(sm.Matrix(U)) + kf_[i]) / diag[i]
                                  for i in range(nq)])
        # a = d/dt(A u + b) - A u' = d(A u + b)/dq q' + d(A u + b)/dt. With
        # explicit kinematics q' is an expression of (q, u); otherwise it
        # stays the symbols QD, which the runtime fills with the q' it solved
        # from Kqd q' = kr (never sympy's symbolic solve of the kinematics,
        # 0/0 at regular configurations such as ZYX Euler angles at hover)
        # (Model.a, formed on first use: the kernels take it as a directional
        # derivative of the CSE'd graph of A u + b instead, gen.ir)
        QD = []
        mv = A_.shape[0]
        if mv and qdot is None:
            QD = [sm.Dummy(f"qd{i}") for i in range(nq)]

        state_labels = [_sym_name(s) for s in q] + list(speed_names)
        input_labels = [_sym_name(s) for s in inputs]
        constant_labels = [str(s) for s in constants]
        aux_labels = [_sym_name(s) for s in aux_of]
        all_labels = state_labels + input_labels + constant_labels + aux_labels + out_labels
        dup = sorted({n_ for n_ in all_labels if all_labels.count(n_) > 1})
        if dup:
            raise ModelError(f"names used twice among states, inputs, constants and outputs: "
                             f"{dup}; give each coordinate, speed, input, constant and output "
                             "its own name")
        # the names generated files use (CSV columns, --x0 NAME=..., C string
        # literals and comments): plain identifiers, unique after sanitizing
        safe = c_names(all_labels)
        ns_, nr_ = len(state_labels), len(input_labels)
        state_names, input_names = safe[:ns_], safe[ns_:ns_ + nr_]
        n_out = len(out_labels)
        constant_names = safe[ns_ + nr_:len(safe) - len(aux_labels) - n_out]
        aux_names = safe[len(safe) - len(aux_labels) - n_out:len(safe) - n_out]
        out_names = safe[len(safe) - n_out:]

        model = cls(
            name=name, method=method, q_orig=list(q), u_orig=list(u), r_orig=inputs,
            p_orig=list(constants), p_values=values, q=Q, u=U, r=R, p=P, t=T,
            q_ind=list(q_ind), q_dep=list(q_dep), u_ind=list(u_ind), u_dep=list(u_dep),
            Kqd=Kqd_, Ku=Ku_, kf=kf_, M=M_, f=f_, A=A_, b=b_, fc=fc_, qdot=qdot,
            energy=E_, state_names=state_names, input_names=input_names,
            constant_names=constant_names, state_labels=state_labels,
            input_labels=input_labels, constant_labels=constant_labels,
            aux_F=aux_F_, aux_g=aux_g_, aux_G=aux_G_, ud=UD, reaction_orig=reactions,
            auxiliary_names=aux_names, auxiliary_labels=aux_labels, qd=QD,
            y=Y_, output_names=out_names, output_labels=list(out_labels))
        model._check_partition()
        return model

    def _check_constraints_kept_by_kinematics(self, rng):
        """With fewer velocity constraints than configuration constraints
        (a unit quaternion whose norm's derivative is one of the kinematic
        equations), the time derivative of f_c must vanish by the kinematic
        equations alone: d f_c/dt = Jc q'(q, u) + df_c/dt = 0 at any q and u.
        Checked numerically at random points; the run time keeps f_c = 0 by
        projection, and the linearization is on [q_ind, u_ind]."""
        import numpy as np
        U = sm.Matrix(self.u)
        Jc = self.fc.jacobian(self.q)
        ft = self.fc.diff(self.t)
        worst, scale = 0.0, 1.0
        for _attempt in range(4):
            vals = {s: rng.uniform(0.3, 1.7) for s in self.q + self.u + self.p + self.r + [self.t]}
            try:
                K = np.array(self.Kqd.xreplace(vals).evalf().tolist(), dtype=float)
                rhs = -np.array((self.Ku * U + self.kf).xreplace(vals).evalf().tolist(),
                                dtype=float).ravel()
                qd = np.linalg.solve(K, rhs)
                J = np.array(Jc.xreplace(vals).evalf().tolist(), dtype=float)
                d = J @ qd + np.array(ft.xreplace(vals).evalf().tolist(), dtype=float).ravel()
            except (TypeError, ValueError, np.linalg.LinAlgError):
                continue
            worst = max(worst, float(np.max(np.abs(d))))
            scale = max(scale, float(np.max(np.abs(J))) * float(np.max(np.abs(qd))))
        if not worst <= 1e-9 * scale:
            raise ModelError(
                f"{self.mc} configuration constraints but only {self.mv} velocity constraints, "
                "and the time derivative of the configuration constraints does not follow from "
                "the kinematic equations (|d f_c/dt| = "
                f"{worst:.3g} at a sample point): give each configuration constraint its time "
                "derivative among the velocity constraints (with a dependent speed), or among "
                "the kinematic equations")

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
            self._check_constraints_kept_by_kinematics(rng)
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


def _aux_zero(uaux, t):
    """({uaux': 0}, {uaux: 0}): replace the derivatives first."""
    return ({s.diff(t): 0 for s in uaux}, {s: 0 for s in uaux})


def _kane_auxiliary(km, q, u, uaux, inputs, reactions, t, zero):
    """(F, reactions, g, named) with km.auxiliary_eqs = F reactions + g (in
    the user's functions of time; u' appear in g). The reactions are the
    user's (reactions=[...]) or the functions of time in the auxiliary
    equations that are neither coordinates, speeds, their derivatives nor
    declared inputs, ordered by name; named are the symbols that name the
    auxiliary forces (the reactions).

    When none is found (every force along the auxiliary directions is a
    declared input or constant), there is nothing to solve for: F = I,
    reactions = [], g = the auxiliary equations, named = the auxiliary
    speeds, so that the auxiliary forces are minus the values of the
    auxiliary equations (Kane's Fr + Fr*) at the declared inputs: the
    generalized force each auxiliary direction still needs to keep its
    speed zero (the reaction an unknown force along it would take)."""
    eqs = sm.Matrix(km.auxiliary_eqs).xreplace(zero[0]).xreplace(zero[1])
    na = len(uaux)
    if eqs.shape[0] != na:
        raise ModelError(f"the KanesMethod has {len(uaux)} auxiliary speeds but "
                         f"{eqs.shape[0]} auxiliary equations")
    known = set(q) | set(u) | set(uaux) | set(inputs or [])
    if reactions is None:
        found = set()
        for e in eqs:
            for fn in e.atoms(sm.core.function.AppliedUndef):
                if fn.args == (t,) and fn not in known:
                    found.add(fn)
        reactions = sorted(found, key=sm.default_sort_key)
        where = "found in the auxiliary equations"
    else:
        reactions = list(reactions)
        where = "given in reactions=[...]"
        bad = [r_ for r_ in reactions if r_ in known
               or not (isinstance(r_, sm.Symbol)
                       or (isinstance(r_, sm.core.function.AppliedUndef) and r_.args == (t,)))]
        if bad or len(set(reactions)) != len(reactions):
            raise ModelError(
                f"reactions must be distinct symbols or functions of time that are not "
                f"coordinates, speeds or inputs; got {[_sym_name(r_) for r_ in reactions]}")
    names = [_sym_name(r_) for r_ in reactions]
    if not reactions and where.startswith("found"):
        # no unknown force: every force along the auxiliary directions is a
        # declared input (or constant). The model is well posed; what the
        # auxiliary equations give is the generalized force w each auxiliary
        # direction still needs, Fr + Fr* + w = 0 at the declared inputs (0
        # when they are the reactions; the reaction itself when an unknown
        # force along it is left out): F = I makes the runtime's solve of
        # F w + g = 0 return w = -g exactly
        return sm.eye(na), [], eqs, list(uaux)
    if len(reactions) != na:
        raise ModelError(
            f"{na} auxiliary speed(s) {[_sym_name(s) for s in uaux]} but {len(reactions)} "
            f"reaction force(s) {where}: {names}; apply one unknown force (a "
            "dynamicsymbol) along each auxiliary direction, declare other functions of "
            "time in inputs=[...], or name the reactions with reactions=[...]")
    F = eqs.jacobian(reactions)
    nonlin = sorted({_sym_name(r_) for r_ in reactions for e in F if e.has(r_)}
                    | {_sym_name(r_) for r_ in reactions for e in eqs
                       if e.has(sm.Derivative(r_, t))})
    if nonlin:
        raise ModelError(f"the auxiliary equations are not linear in the reaction force(s) "
                         f"{', '.join(nonlin)}")
    g = eqs.xreplace({r_: 0 for r_ in reactions})
    return F, reactions, g, reactions



def _outputs_of(outputs):
    """(names, expressions) of outputs={name: expr} (or [(name, expr), ...])."""
    items = list(outputs.items()) if isinstance(outputs, dict) else list(outputs)
    names, exprs = [], []
    for item in items:
        try:
            name, expr = item
        except (TypeError, ValueError):
            raise ModelError("outputs must be a dict {name: expression} or a list of (name, "
                             f"expression) pairs, got {item!r}") from None
        if not isinstance(name, str) or not re.match(r"^[A-Za-z_][A-Za-z0-9_]*$", name):
            raise ModelError(f"output name {name!r} must be an identifier (letters, digits, "
                             "'_', not starting with a digit)")
        if isinstance(expr, me.Vector):
            raise ModelError(f"output {name!r} is a vector: give one scalar expression per "
                             "output (for example P.pos_from(O).dot(N.x))")
        try:
            e = sm.sympify(expr)
        except (sm.SympifyError, TypeError) as err:
            raise ModelError(f"output {name!r} is not a sympy expression: {err}") from None
        if not isinstance(e, sm.Expr):
            raise ModelError(f"output {name!r} must be a scalar sympy expression, got "
                             f"{type(e).__name__}")
        names.append(name)
        exprs.append(e)
    return names, exprs


def _eliminate_reactions(M, f, aux, udots, coords, constrained=False):
    """Reactions in the real speeds' equations (friction -mu*N on the normal
    reaction N of an auxiliary speed): M u' = f0 + G N and the auxiliary
    equations aux_F N + aux_g(u') = 0 form one linear system in (u', N).
    Returns (M, f, aux).

    When aux_F is constant and regular and N's share of the motion leaves
    the matrix multiplying u' free of the speeds (a reaction applied along
    its auxiliary direction on flat ground, the usual case), N =
    -aux_F^-1 aux_g(u') is put into f exactly, its u' terms move into M
    (which may then be unsymmetric; the runtime solves it by LU) and aux is
    returned as given. Otherwise (coefficients that depend on the
    configuration, the speeds or the time; a reaction that its own
    auxiliary direction does not determine) the reactions stay unknowns: f
    is returned at N = 0 and aux gains G = df/dN, and the runtime solves
    [M, -G; C, aux_F] [u'; N] = [f0; -g0] (C = d aux_g/du', g0 = aux_g at
    u' = 0) by pivoted LU at every evaluation (gen_rt_accel_reactions)."""
    F, reactions, g = aux[:3]
    names = [_sym_name(r_) for r_ in reactions]
    inM = [n for r_, n in zip(reactions, names) if M.has(r_)]
    if inM:
        raise ModelError(f"the reaction force(s) {', '.join(inM)} appear in the mass matrix of "
                         "the real speeds; not supported")
    G = f.jacobian(reactions)
    nonlin = [n for r_, n in zip(reactions, names) if any(e.has(r_) for e in G)]
    if nonlin:
        raise ModelError(f"the forcing is not linear in the reaction force(s) "
                         f"{', '.join(nonlin)} (for example Abs(N) or a product of "
                         "reactions): eomgen solves the motion and the reactions together "
                         "and needs them to enter linearly")
    C = g.jacobian(udots)
    if any(e.has(*udots) for e in C):
        raise ModelError(f"the auxiliary equations of the reaction force(s) {', '.join(names)} "
                         "are not linear in the accelerations; not supported")
    if any(e.has(ud) for e in G for ud in udots):
        raise ModelError(f"the coefficients of the reaction force(s) {', '.join(names)} in the "
                         "forcing depend on the accelerations; not supported")
    varying = any(fn.args == (me.dynamicsymbols._t,) for e in F
                  for fn in e.atoms(sm.core.function.AppliedUndef)) \
        or any(e.has(me.dynamicsymbols._t) for e in F)
    if _ELIMINATE_CONSTANT and not varying and sm.simplify(F.det()) != 0:
        sol = -F.LUsolve(g)
        f_sub = f.xreplace(dict(zip(reactions, sol)))
        J = f_sub.jacobian(udots)
        speeds = [fn for e in J for fn in e.atoms(sm.core.function.AppliedUndef)
                  if fn not in coords]
        if not any(e.has(ud) for e in J for ud in udots) and not speeds:
            zero = {ud: 0 for ud in udots}
            return M - J, f_sub.xreplace(zero), aux
    if constrained:
        raise ModelError(
            f"the reaction force(s) {', '.join(names)} appear in the equations of motion and "
            "must be solved together with the accelerations, which eomgen does for models "
            "without velocity constraints (dependent speeds); not supported here")
    f0 = f.xreplace({r_: 0 for r_ in reactions})
    _check_coupled_regular(M, G, C, F, names)
    return M, f0, tuple(aux[:4]) + (G,)


def _check_coupled_regular(M, G, C, H, names):
    """Refuse reactions that the coupled system [M, -G; C, H] leaves
    undetermined at every state (singular at three random points: a
    reaction that neither its auxiliary equations nor the accelerations
    fix), naming them; a system singular only at some configurations is the
    run time's GEN_RT_ERR_SINGULAR_REACTIONS."""
    import numpy as np
    K = sm.Matrix(sm.BlockMatrix([[M, -G], [C, H]]))
    atoms = set()
    for e in K:
        atoms |= {a for a in e.atoms(sm.core.function.AppliedUndef, sm.Symbol)}
    rng = np.random.default_rng(0)
    n = K.shape[0]
    for _ in range(3):
        vals = {a: sm.Float(rng.uniform(0.3, 1.3)) for a in atoms}
        try:
            Kn = np.array(K.xreplace(vals).evalf(), dtype=float)
        except (TypeError, ValueError):
            return                    # not a number at this point: left to the run time
        if np.all(np.isfinite(Kn)) and np.linalg.matrix_rank(Kn) == n:
            return
    raise ModelError(
        f"the reaction force(s) {', '.join(names)} enter the equations of motion but the "
        "auxiliary equations together with the motion do not determine them (the coupled "
        "system in the accelerations and the reactions is singular at random states): apply "
        "each reaction along its auxiliary direction")


# the reactions of a constant, regular auxiliary matrix whose share of the
# motion leaves M free of the speeds are eliminated symbolically (exact, and
# M stays a matrix of q alone); False sends every reaction inside the motion
# through the coupled solve (bench/bench_reactions.py compares the two)
_ELIMINATE_CONSTANT = True


_ID_MEMO, _CONS_MEMO = object(), object()


def _xreplace_shared(mat, rule, memo):
    """mat.xreplace(rule), each distinct subexpression rebuilt once (memo,
    shared between calls): sympy's xreplace rebuilds a subexpression every
    time it appears, and Kane's M and f repeat theirs many times.

    When rule maps atoms and functions of time one to one onto new symbols
    (atomic), a sum or product cannot combine terms that were apart (distinct
    terms stay distinct), so it is rebuilt from its new arguments in sympy's
    canonical order (numbers first, then sorted as Add and Mul sort them)
    without re-running their flatten: the same objects, most of the cost
    gone (tests/unit/intake/test_model.py)."""
    if not rule or not mat.shape[0] * mat.shape[1]:
        return mat
    atomic = (len(set(rule.values())) == len(rule)
              and all(v.is_Symbol for v in rule.values()))

    def rebuild(e, args):
        if atomic and (e.is_Add or e.is_Mul) and e.is_commutative:
            nums = [a for a in args if a.is_Number]
            rest = [a for a in args if not a.is_Number]
            rest.sort(key=_args_sortkey)
            return e.func._from_args(nums + rest, True)
        return e.func(*args)

    # memo and the rebuilt nodes keyed by object identity: two equal but
    # distinct deep subexpressions (gen.recursive's graphs once sympy's LRU
    # cache has dropped the one that made them identical) are never compared
    # with sympy's ==, which walks shared nodes as a tree (exponential); equal
    # rebuilt nodes are made one object (hash-consed by their arguments' ids)
    ids = memo.setdefault(_ID_MEMO, {})
    cons = memo.setdefault(_CONS_MEMO, {})

    def walk(e):
        hit = ids.get(id(e))
        if hit is not None:
            return hit[1]
        if not e.args:
            out = rule.get(e, e)
        elif e in rule:
            out = rule[e]
        else:
            args = [walk(a) if isinstance(a, sm.Basic) else a for a in e.args]
            if any(a is not b for a, b in zip(args, e.args)):
                key = (e.func, tuple(a if not isinstance(a, sm.Basic) or not a.args else id(a)
                                     for a in args))
                out = cons.get(key)
                if out is None:
                    out = rebuild(e, args)
                    cons[key] = out
            else:
                out = e
        ids[id(e)] = (e, out)
        return out

    return sm.Matrix(mat.shape[0], mat.shape[1], [walk(e) for e in mat])


def _scan(mat):
    """(free symbols, derivatives, undefined functions) of a matrix's
    entries, each distinct subexpression visited once."""
    free, derivs, undef = set(), set(), set()
    seen = set()
    stack = list(mat)
    while stack:
        e = stack.pop()
        if e in seen:
            continue
        seen.add(e)
        if e.is_Symbol:
            free.add(e)
            continue
        if isinstance(e, sm.Derivative):
            derivs.add(e)
        elif isinstance(e, sm.core.function.AppliedUndef):
            undef.add(e)
        stack.extend(a for a in e.args if isinstance(a, sm.Basic))
    return free, derivs, undef


def _row_jacobian(col, syms):
    """col.jacobian(syms) for a column over plain symbols, each row
    differentiated only by the symbols it holds (the same matrix; the
    kinematics of n coordinates, one q' per row, in O(n) derivatives
    instead of n^2)."""
    where = {s: k for k, s in enumerate(syms)}
    out = sm.zeros(col.shape[0], len(syms))
    for i in range(col.shape[0]):
        for s in col[i].free_symbols:
            if s in where:
                out[i, where[s]] = col[i].diff(s)
    return out


def _srepr(mat, sub):
    """sm.srepr(mat.xreplace(sub)); for matrices holding gen.recursive's
    shared opaque nodes (UnevaluatedExpr), whose trees unfolded grow far
    faster than their graphs, the graph instead: one line per distinct
    subexpression, its arguments by number."""
    if not any(_has_kind(list(mat), sm.UnevaluatedExpr)):
        return sm.srepr(mat.xreplace(sub))
    ids, lines = {}, []
    for root in mat:
        stack = [(root, False)]
        while stack:
            e, done = stack.pop()
            if e in ids:
                continue
            if done or not e.args:
                ids[e] = len(ids)
                lines.append(sm.srepr(sub.get(e, e)) if not e.args else
                             f"{type(e).__name__}({','.join(str(ids[a]) for a in e.args)})")
                continue
            stack.append((e, True))
            stack.extend((a, False) for a in reversed(e.args) if a not in ids)
        lines.append(f"={ids[root]}")
    return f"{mat.shape}" + ";".join(lines)


def _memo_any(exprs, leaf):
    """[whether e holds a node for which leaf(node) is True, for e in exprs]:
    leaf returns True or False to decide a node, None to look inside it;
    each distinct subexpression visited once (sympy's has walks a shared
    subexpression every time it appears)."""
    memo, out = {}, []
    for root in exprs:
        stack = [(root, False)]
        while stack:
            e, done = stack.pop()
            if done:
                memo[e] = any(memo[a] for a in e.args)
                continue
            if e in memo:
                continue
            hit = leaf(e)
            if hit is not None:
                memo[e] = hit
                continue
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if a not in memo)
        out.append(memo[root])
    return out


def _has_kind(exprs, kind):
    """[whether e holds a node of class kind for e in exprs]."""
    return _memo_any(exprs, lambda e: True if isinstance(e, kind) else
                     (False if not e.args else None))


def _has_any(exprs, targets):
    """[e.has(*targets) for e in exprs] for atomic targets (symbols)."""
    targets = set(targets)
    if not targets:
        return [False for _ in exprs]
    return _memo_any(exprs, lambda e: None if e.args else e in targets)


def _check_expressions(mat, what, allowed, inputs=()):
    """Refuse free symbols, leftover derivatives and unknown functions,
    naming the culprit (and, when inputs holds the same name as a plain
    Symbol where the model has a function of time, or the other way round,
    the mix-up)."""
    free, derivs, undef = _scan(mat)
    extra = free - allowed
    functions = {str(r_.func): r_ for r_ in inputs if isinstance(r_, sm.core.function.AppliedUndef)}
    for s_ in sorted(extra, key=str):
        if str(s_) in functions:    # the other mix-up: T(t) declared, the plain T used
            raise ModelError(
                f"the {what} contain {s_}, a plain Symbol, but inputs=[...] gives "
                f"{functions[str(s_)]}, a function of time (a dynamicsymbol): declare the "
                "input as the model writes it (the same object), or use "
                f"dynamicsymbols('{s_}') in the model")
    if extra:
        names = sorted(str(s) for s in extra)
        raise ModelError(
            f"the {what} contain symbol(s) {', '.join(names)} that are neither coordinates, "
            "speeds, inputs nor constants: give them a value in constants={...} or list "
            "them in inputs=[...]")
    if derivs:
        raise ModelError(
            f"the {what} contain derivative term(s) {sorted(map(str, derivs))[:3]}: "
            "express them through the speeds (kinematic equations) or declare them")
    plain = {str(r_): r_ for r_ in inputs if isinstance(r_, sm.Symbol)}
    for fn in sorted(undef, key=str):
        name = str(fn.func)
        if name in plain:
            raise ModelError(
                f"the {what} contain {name}(t), a function of time (a dynamicsymbol), but "
                f"inputs=[...] gives {name}, a plain Symbol: the model uses {name}(t); list "
                f"dynamicsymbols('{name}') in inputs=[...] (sympy.physics.mechanics) "
                f"instead of Symbol('{name}')")
        raise ModelError(
            f"the {what} contain {fn.func}(t), a function of time that is not a "
            "coordinate, "
            "speed or declared input: list it in inputs=[...]")
    # printability (in the user's spelling) is checked before this by
    # gen.sym.printers.check_printable, which knows every function it prints
