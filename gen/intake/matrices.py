"""The matrices adapter: ``M u' = f`` and kinematic equations given as
matrices (PyDy's forms through gen.pydy; a System's joint tree through
gen.intake.recursive) -> :class:`gen.intake.canonical.Equations`."""
from __future__ import annotations

import sympy as sm

from ..core.errors import ModelError
from .canonical import Equations, split_last
from .checks import sym_name
from .sympy_compat import time_symbol

__all__ = ["matrices_equations", "as_column", "row_jacobian"]


def as_column(x, what):
    """x as a column Matrix (a row is transposed; None is empty), or a
    ModelError naming what."""
    if x is None:
        return sm.zeros(0, 1)
    m = sm.Matrix(x)
    if m.shape[1] != 1 and m.shape[0] == 1:
        m = m.T
    if m.shape[1] != 1 and m.shape[0] != 0:
        raise ModelError(f"{what} must be a column of expressions, got shape {m.shape}")
    return m


def row_jacobian(col, syms):
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


def matrices_equations(mass_matrix, forcing, coordinates, speeds, kinematics,
                       constraints=None):
    """The Equations of ``mass_matrix * speeds' = forcing`` with the kinematic
    equations ``kinematics = 0`` (linear in q' and u, one row per
    coordinate); constraints: None, or a System's ``(fc, A, b, nq_dep,
    nu_dep)`` with the dependent coordinates and speeds last
    (gen.intake.recursive)."""
    t = time_symbol()
    q, u = list(coordinates), list(speeds)
    nq, nu = len(q), len(u)
    M = sm.Matrix(mass_matrix)
    f = as_column(forcing, "forcing")
    kd = as_column(kinematics, "kinematics")
    if M.shape != (nu, nu):
        raise ModelError(f"mass_matrix has shape {M.shape}, expected ({nu}, {nu}) "
                         f"for {nu} speed(s)")
    if f.shape != (nu, 1):
        raise ModelError(f"forcing has shape {f.shape}, expected ({nu}, 1)")
    if kd.shape != (nq, 1):
        raise ModelError(f"kinematics has shape {kd.shape}, expected ({nq}, 1) "
                         f"for {nq} coordinate(s)")
    qdots = [qi.diff(t) for qi in q]
    Kqd, Ku, kf = _kinematic_coefficients(kd, qdots, u)
    # explicit kinematics (Kqd diagonal): q' in M and f becomes its value
    qdot_map = {}
    if all(Kqd[i, j] == 0 for i in range(nq) for j in range(nq) if i != j) \
            and all(Kqd[i, i] != 0 for i in range(nq)):
        qdot_map = {qd_: -(Ku[i, :].dot(sm.Matrix(u)) + kf[i]) / Kqd[i, i]
                    for i, qd_ in enumerate(qdots)}
    fc, A, b, nqd, nud = constraints or (sm.zeros(0, 1), sm.zeros(0, nu), sm.zeros(0, 1), 0, 0)
    q_ind, q_dep = split_last(nq, nqd)
    u_ind, u_dep = split_last(nu, nud)
    return Equations(
        method="kane", t=t, q=q, u=u, qdots=qdots, udots=[ui.diff(t) for ui in u],
        q_ind=q_ind, q_dep=q_dep, u_ind=u_ind, u_dep=u_dep, Kqd=Kqd, Ku=Ku, kf=kf, M=M, f=f,
        A=A, b=b, fc=fc, qdot_subs=qdot_map, speed_names=[sym_name(x) for x in u])


def _kinematic_coefficients(kd, qdots, u):
    """(Kqd, Ku, kf) of kd = Kqd q' + Ku u + kf, and the check that no row
    holds q' or u beyond them (the linearization relies on the split)."""
    nq, nu = len(qdots), len(u)
    Qd = [sm.Dummy(f"qd{i}") for i in range(nq)]
    Ud = [sm.Dummy(f"u{i}") for i in range(nu)]
    kd_ = kd.xreplace(dict(zip(qdots, Qd))).xreplace(dict(zip(u, Ud)))
    Kqd = row_jacobian(kd_, Qd)
    Ku = row_jacobian(kd_, Ud)
    kf = kd_.xreplace({s: 0 for s in Qd + Ud})
    for i in range(nq):
        if any(e.has(*Qd, *Ud) for e in list(Kqd[i, :]) + list(Ku[i, :])):
            raise ModelError(
                f"kinematics row {i} ({kd[i]}) is not linear in the coordinate "
                "derivatives and the speeds")
    back = dict(zip(Ud, u))
    return Kqd.xreplace(back), Ku.xreplace(back), kf.xreplace(back)
