"""From an adapter's equations to the canonical Model: named passes, each
taking and returning values.

Every adapter (:mod:`gen.intake.kane`, :mod:`~gen.intake.lagrange`,
:mod:`~gen.intake.matrices`; :mod:`~gen.intake.system` dispatches to them)
hands over an :class:`Equations`: the kinematics, dynamics and constraints in
the user's own symbols (functions of time), and the partition. :func:`finish`
runs the passes on it, in this order:

1. :func:`declare`: the inputs and constants, declared once, with finite
   real values;
2. :func:`internal_symbols`: a plain symbol for every coordinate, speed,
   input, constant and t;
3. :func:`convert`: every matrix (and the energy, the outputs) in those
   symbols, checked (printable; no unknown symbol, derivative or function of
   time, each named);
4. :func:`convert_auxiliary`: the auxiliary equations of the reactions, u' as
   symbols too;
5. :func:`warn_unused`: a warning naming the constants and inputs no
   expression uses;
6. :func:`check_structure`: shapes, and what may depend on what (M not on
   the speeds, the kinematics and velocity constraints linear in them, ...);
7. :func:`explicit_kinematics`: q' as expressions when Kqd is diagonal, else
   symbols the run time fills;
8. :func:`name_all`: the names as sympy prints them and as identifiers;
9. :func:`assemble`, then :func:`gen.intake.checks.check_partition` (the
   dependent coordinates and speeds determined by the constraints) and
   :func:`gen.intake.hybrid.attach_hybrid` (impacts and resets).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sm

from ..core.errors import ModelError
from ..core.names import c_names
from ..sym.dag import has_any, scan, xreplace_shared
from ..sym.printers import check_printable
from .checks import (check_expressions, check_partition, constant_value, outputs_of, sym_name,
                     user_stacklevel)
from .checks import warn_unused as warn_names
from .hybrid import attach_hybrid, hybrid_symbols

__all__ = ["Equations", "finish", "split_last", "declare", "internal_symbols", "convert",
           "convert_auxiliary", "warn_unused", "check_structure", "explicit_kinematics",
           "name_all", "assemble"]


@dataclass
class Equations:
    """What an adapter hands over, in the user's symbols (functions of time):

        Kqd q' + Ku u + kf = 0,  M u' = f (+ A^T lam),  A u + b = 0,  fc = 0

    q_ind .. u_dep index q and u; qdot_subs maps q' left in M and f to its
    value; speed_names name the speeds (q1_d for a Lagrange model's q1');
    aux, with auxiliary speeds: (F, reactions, g[, named[, G]]), the
    auxiliary equations F reactions + g = 0 (g in u'), the symbols that name
    the auxiliary forces, and G, the reactions' coefficients in f when they
    are solved with u' at run time (:mod:`gen.intake.reactions`)."""
    method: str                      # "kane" | "lagrange"
    t: sm.Symbol
    q: list
    u: list
    qdots: list
    udots: list
    q_ind: list
    q_dep: list
    u_ind: list
    u_dep: list
    Kqd: sm.Matrix
    Ku: sm.Matrix
    kf: sm.Matrix
    M: sm.Matrix
    f: sm.Matrix
    A: sm.Matrix
    b: sm.Matrix
    fc: sm.Matrix
    qdot_subs: dict
    speed_names: list
    aux: tuple | None = None


def split_last(n, ndep):
    """(independent, dependent) indices of n entries whose last ndep are the
    dependent ones (a KanesMethod's order)."""
    return list(range(n - ndep)), list(range(n - ndep, n))


def finish(cls, eqs, *, name, constants=None, inputs=None, energy=None, outputs=None,
           hybrid=None):
    """The canonical model (an instance of cls) of an adapter's equations,
    through the passes of the module docstring, in order."""
    decl = declare(eqs, constants, inputs)
    syms = internal_symbols(eqs, decl)
    conv = convert(eqs, decl, syms, energy, outputs)
    aux = convert_auxiliary(eqs, decl, syms)
    warn_unused(name, decl, syms, conv, aux, hybrid_symbols(hybrid))
    check_structure(name, eqs, syms, conv)
    qdot, qd = explicit_kinematics(conv, syms)
    names = name_all(eqs, decl, aux, conv)
    model = assemble(cls, name, eqs, decl, syms, conv, aux, (qdot, qd), names)
    check_partition(model)
    return attach_hybrid(model, hybrid)


# ------------------------------------------------------------ 1. declare
@dataclass
class Declared:
    constants: dict                  # {symbol: value as given}, the user's order
    inputs: list
    values: list                     # the constants' float values


def declare(eqs, constants, inputs):
    """The inputs and constants, each declared once: an input twice, a
    constant that is not a Symbol, a name both input and constant, a
    coordinate or speed among them, or a constant whose value is not a finite
    real number (NaN, inf, complex, symbolic) is a ModelError naming it,
    before anything is generated."""
    constants = dict(constants or {})
    inputs = list(inputs or [])
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
    values = [constant_value(c, v) for c, v in constants.items()]
    for s in list(eqs.q) + list(eqs.u):
        if s in seen or s in constants:
            raise ModelError(f"{s} is a coordinate or speed and cannot be an input or constant")
    return Declared(constants, inputs, values)


# ----------------------------------------------------- 2. internal symbols
@dataclass
class Internal:
    Q: list
    U: list
    R: list
    P: list
    T: sm.Symbol
    sub: dict                        # the user's symbols -> these


def internal_symbols(eqs, decl):
    """A plain symbol (Dummy) for every coordinate, speed, input, constant
    and t, and the map from the user's symbols to them (for a Lagrange model
    the speeds are the q', mapped first: u' must not appear, q' may)."""
    nq, nu = len(eqs.q), len(eqs.u)
    Q = [sm.Dummy(f"q{i}") for i in range(nq)]
    U = [sm.Dummy(f"u{i}") for i in range(nu)]
    R = [sm.Dummy(f"r{i}") for i in range(len(decl.inputs))]
    P = [sm.Dummy(f"p{i}") for i in range(len(decl.constants))]
    T = sm.Dummy("t")
    sub = {}
    if eqs.method == "lagrange":
        sub.update(zip(eqs.qdots, U))
    sub.update(zip(eqs.q, Q))
    if eqs.method == "kane":
        sub.update(zip(eqs.u, U))
    sub.update(zip(decl.inputs, R))
    sub.update(zip(decl.constants, P))
    sub[eqs.t] = T
    return Internal(Q, U, R, P, T, sub)


# ------------------------------------------------------------- 3. convert
@dataclass
class Converted:
    Kqd: sm.Matrix
    Ku: sm.Matrix
    kf: sm.Matrix
    M: sm.Matrix
    f: sm.Matrix
    A: sm.Matrix
    b: sm.Matrix
    fc: sm.Matrix
    energy: sm.Expr | None
    y: sm.Matrix
    output_labels: list

    def matrices(self):
        return (self.Kqd, self.Ku, self.kf, self.M, self.f, self.A, self.b, self.fc, self.y)


def convert(eqs, decl, syms, energy, outputs):
    """Every matrix, the energy and the outputs in the internal symbols,
    each checked: printable by the generator, and holding no symbol,
    derivative or function of time the model does not know (a ModelError
    naming the culprit in the user's spelling)."""
    qd_subs = dict(eqs.qdot_subs)
    # one memo for every matrix: M and f (and the rest) share most of
    # their subexpressions, each converted once
    memo_qd, memo = {}, {}
    back = {v: k for k, v in syms.sub.items()}
    allowed = set(syms.Q) | set(syms.U) | set(syms.R) | set(syms.P) | {syms.T}

    def conv(mat, what):
        mat = sm.Matrix(mat)
        if qd_subs:
            mat = xreplace_shared(mat, qd_subs, memo_qd)
        out = xreplace_shared(mat, syms.sub, memo)
        check_printable(out, what, back, syms.T)
        check_expressions(out, what, allowed, decl.inputs)
        return out

    Kqd = conv(eqs.Kqd, "kinematic equations (q' coefficients)")
    Ku = conv(eqs.Ku, "kinematic equations (u coefficients)")
    kf = conv(eqs.kf, "kinematic equations")
    M = conv(eqs.M, "mass matrix")
    f = conv(eqs.f, "forcing")
    A = conv(eqs.A, "velocity constraints")
    b = conv(eqs.b, "velocity constraints")
    fc = conv(eqs.fc, "configuration constraints")
    E = conv(sm.Matrix([energy]), "energy")[0] if energy is not None else None
    labels, Y = [], sm.zeros(0, 1)
    if outputs is not None:
        labels, exprs = outputs_of(outputs)
        Y = conv(sm.Matrix(exprs), "outputs") if exprs else sm.zeros(0, 1)
    return Converted(Kqd, Ku, kf, M, f, A, b, fc, E, Y, labels)


# --------------------------------------------------- 4. convert auxiliary
@dataclass
class Auxiliary:
    ud: list = ()                    # the internal symbols of u'
    F: sm.Matrix | None = None
    g: sm.Matrix | None = None
    G: sm.Matrix | None = None
    reactions: list = ()             # the reactions solved for (the user's symbols)
    named: list = ()                 # what names the auxiliary forces

    def matrices(self):
        return tuple(m for m in (self.F, self.g, self.G) if m is not None)


def convert_auxiliary(eqs, decl, syms):
    """The auxiliary equations F reactions + g = 0 (and the reactions'
    coefficients G in the forcing) in the internal symbols, u' as symbols of
    their own, checked as :func:`convert` checks; an empty Auxiliary without
    auxiliary speeds."""
    if eqs.aux is None:
        return Auxiliary()
    aux = eqs.aux
    UD = [sm.Dummy(f"ud{i}") for i in range(len(eqs.u))]
    usub = dict(zip(eqs.udots, UD))
    back = {v: k for k, v in syms.sub.items()}
    back.update({v: k for k, v in usub.items()})
    allowed = set(syms.Q) | set(syms.U) | set(UD) | set(syms.R) | set(syms.P) | {syms.T}

    def conv(mat, what):
        mat = sm.Matrix(mat)
        if eqs.qdot_subs:
            mat = mat.xreplace(dict(eqs.qdot_subs))
        mat = mat.xreplace(usub).xreplace(syms.sub)     # u' before u
        check_printable(mat, what, back, syms.T)
        check_expressions(mat, what, allowed, decl.inputs)
        return mat

    F = conv(aux[0], "auxiliary equations (reaction coefficients)")
    g = conv(aux[2], "auxiliary equations")
    # the reactions' coefficients in the dynamics (coupled solve)
    G = conv(aux[4], "forcing (reaction coefficients)") if len(aux) > 4 else None
    # the reactions solved for, and what names the auxiliary forces: the
    # reactions, or the auxiliary speeds when none is unknown
    return Auxiliary(UD, F, g, G, list(aux[1]), list(aux[3] if len(aux) > 3 else aux[1]))


# ---------------------------------------------------------- 5. warn unused
def warn_unused(name, decl, syms, conv, aux, hybrid_used=frozenset()):
    """A warning naming the constants, and one naming the inputs, that no
    expression of the model uses (kept, without effect): one walk over every
    distinct subexpression (the recursive formulation's matrices share
    theirs). hybrid_used: the user's symbols of the hybrid declarations (a
    constant that moves only a guard is used)."""
    from ..core.errors import UnusedConstantWarning, UnusedInputWarning
    used = scan([e for mat in conv.matrices() + aux.matrices() for e in mat]
                + ([conv.energy] if conv.energy is not None else []))[0]
    warn_names(UnusedConstantWarning, name, "constant",
               [str(c) for c, d in zip(decl.constants, syms.P)
                if d not in used and c not in hybrid_used],
               "(mass matrix, forcing, kinematic equations, constraints, energy); kept as "
               "parameter(s) without effect")
    warn_names(UnusedInputWarning, name, "input",
               [str(r_) for r_, d in zip(decl.inputs, syms.R)
                if d not in used and r_ not in hybrid_used],
               "(forcing, outputs, ...): kept as input(s) without effect (a misspelt or "
               "stale entry of inputs=[...]?)")


# ------------------------------------------------------- 6. check structure
def check_structure(name, eqs, syms, conv):
    """Shapes, and what may depend on what: M not on the speeds (and not
    identically zero: refused, or a warning naming the massless speeds), the
    kinematic coefficients and the velocity-constraint matrix not on the
    speeds or inputs, f_c not on them, kf and b not on the inputs."""
    nu, U, R = len(eqs.u), syms.U, syms.R
    M, A = conv.M, conv.A
    if nu == 0:
        raise ModelError(f"model '{name}' has no speeds, so no state: nothing to simulate "
                         "(an empty System or method?)")
    if M.shape != (nu, nu):
        raise ModelError(f"mass matrix has shape {M.shape}, expected ({nu}, {nu})")
    if conv.f.shape != (nu, 1):
        raise ModelError(f"forcing has shape {conv.f.shape}, expected ({nu}, 1)")
    if any(has_any(M, U)):
        raise ModelError("the mass matrix depends on the speeds; such models are not supported")
    # a speed whose row of M is identically zero (and that no velocity
    # constraint involves) has no acceleration equation: M (or the
    # constrained system) is singular at every state
    zero = [i for i in range(nu) if all(M[i, j] == 0 for j in range(nu))
            and all(A[k, i] == 0 for k in range(A.shape[0]))]
    if zero:
        _massless(name, [str(eqs.speed_names[i]) for i in zero], everything=len(zero) == nu)
    for mat, what in ((conv.Kqd, "kinematic q' coefficients"),
                      (conv.Ku, "kinematic u coefficients"), (A, "velocity-constraint matrix")):
        if any(has_any(mat, U)) or any(has_any(mat, R)):
            raise ModelError(f"the {what} depend on speeds or inputs; the kinematic "
                             "equations and velocity constraints must be linear in the speeds")
    if any(has_any(conv.fc, U + R)):
        raise ModelError("the configuration constraints depend on speeds or inputs")
    if any(has_any(list(conv.kf) + list(conv.b), R)):
        raise ModelError("the kinematic equations or velocity constraints depend on inputs; "
                         "not supported")


def _massless(name, names, everything):
    """The speeds `names` have a zero row in M: refused when that is every
    speed (nothing to simulate), else a MasslessSpeedWarning (a massless
    part: its M and f, and sympy's own tests of them, are meaningful; a
    simulation is not)."""
    if everything:
        raise ModelError(
            f"model '{name}': the mass matrix is identically zero (speeds "
            f"{', '.join(names)}): the equations of motion do not determine the "
            "accelerations at any state (every simulation would fail as singular). "
            "Give the bodies their masses and inertias (particles, rigid bodies) in "
            "the equations you formed")
    import warnings

    from ..core.errors import MasslessSpeedWarning
    warnings.warn(MasslessSpeedWarning(
        f"model '{name}': the mass matrix is zero in the row(s) of speed(s) "
        f"{', '.join(names)}: the equations of motion do not determine those "
        "accelerations (a massless particle or body?), so a simulation will stop "
        "as singular; M, f and their Jacobians are generated as given"),
        stacklevel=user_stacklevel())


# -------------------------------------------------- 7. explicit kinematics
def explicit_kinematics(conv, syms):
    """(qdot, qd): q' as expressions of (q, u) when Kqd is diagonal (the
    usual q' = u) or a diagonal with its rows permuted, else None; and, when q' stays implicit and there are
    velocity constraints, the symbols qd of q' in the acceleration-constraint
    term a (the run time fills them with the q' it solved from Kqd q' = kr;
    never sympy's symbolic solve of the kinematics, 0/0 at regular
    configurations such as ZYX Euler angles at hover), else []."""
    Kqd, nq = conv.Kqd, len(syms.Q)
    qdot = None
    # row i of Kqd q' = -(Ku u + kf) holds the one q'_j with Kqd[i, j] != 0
    # (a diagonal, or a permutation of one: kd_eqs listed in another order
    # than q, as the seed pendulum's [q1' - u1, q2' - u2] for q = [q2, q1])
    cols = [[j for j in range(nq) if Kqd[i, j] != 0] for i in range(nq)]
    if all(len(c) == 1 for c in cols) and sorted(c[0] for c in cols) == list(range(nq)):
        row_of = {c[0]: i for i, c in enumerate(cols)}
        U = sm.Matrix(syms.U)
        qdot = sm.Matrix([-(conv.Ku[i, :].dot(U) + conv.kf[i]) / Kqd[i, j]
                          for j, i in sorted(row_of.items())])
    # (Model.a, d(A u + b)/dq q' + d(A u + b)/dt, is formed on first use:
    # the kernels take it as a directional derivative of the CSE'd graph of
    # A u + b instead, gen.plan.ir)
    qd = []
    if conv.A.shape[0] and qdot is None:
        qd = [sm.Dummy(f"qd{i}") for i in range(nq)]
    return qdot, qd


# ------------------------------------------------------------- 8. name all
@dataclass
class Names:
    state_labels: list
    input_labels: list
    constant_labels: list
    auxiliary_labels: list
    output_labels: list
    state_names: list
    input_names: list
    constant_names: list
    auxiliary_names: list
    output_names: list


def name_all(eqs, decl, aux, conv):
    """The names as sympy prints them (labels) and as the identifiers that
    generated files use (CSV columns, --x0 NAME=..., C string literals and
    comments): plain identifiers, unique after sanitizing. A name used twice
    among states, inputs, constants, auxiliary forces and outputs is a
    ModelError."""
    state = [sym_name(s) for s in eqs.q] + list(eqs.speed_names)
    inputs = [sym_name(s) for s in decl.inputs]
    constants = [str(s) for s in decl.constants]
    auxiliary = [sym_name(s) for s in aux.named]
    outputs = list(conv.output_labels)
    labels = state + inputs + constants + auxiliary + outputs
    dup = sorted({n_ for n_ in labels if labels.count(n_) > 1})
    if dup:
        raise ModelError(f"names used twice among states, inputs, constants and outputs: "
                         f"{dup}; give each coordinate, speed, input, constant and output "
                         "its own name")
    safe, parts = c_names(labels), []
    for group in (state, inputs, constants, auxiliary, outputs):
        parts.append(safe[:len(group)])
        safe = safe[len(group):]
    return Names(state, inputs, constants, auxiliary, outputs, *parts)


# -------------------------------------------------------------- 9. assemble
def assemble(cls, name, eqs, decl, syms, conv, aux, kinematics, names):
    """The Model (cls) of the passes' values."""
    qdot, qd = kinematics
    return cls(
        name=name, method=eqs.method, q_orig=list(eqs.q), u_orig=list(eqs.u),
        r_orig=decl.inputs, p_orig=list(decl.constants), p_values=decl.values,
        q=syms.Q, u=syms.U, r=syms.R, p=syms.P, t=syms.T,
        q_ind=list(eqs.q_ind), q_dep=list(eqs.q_dep), u_ind=list(eqs.u_ind),
        u_dep=list(eqs.u_dep), Kqd=conv.Kqd, Ku=conv.Ku, kf=conv.kf, M=conv.M, f=conv.f,
        A=conv.A, b=conv.b, fc=conv.fc, qdot=qdot, energy=conv.energy,
        state_names=names.state_names, input_names=names.input_names,
        constant_names=names.constant_names, state_labels=names.state_labels,
        input_labels=names.input_labels, constant_labels=names.constant_labels,
        aux_F=aux.F, aux_g=aux.g, aux_G=aux.G, ud=list(aux.ud),
        reaction_orig=list(aux.reactions), auxiliary_names=names.auxiliary_names,
        auxiliary_labels=names.auxiliary_labels, qd=qd, y=conv.y,
        output_names=names.output_names, output_labels=names.output_labels)
