"""The Kane adapter: a formed ``KanesMethod`` -> :class:`gen.intake.canonical.Equations`.

The kinematic equations are taken as the user wrote them (Kqd q' + Ku u + kf
= 0), never sympy's symbolic solve for q'. With constraints, the
unconstrained equations for all speeds are formed again (cheap), so that the
dependent speeds are eliminated numerically at run time, never symbolically
(sympy's elimination can divide by zero at regular configurations,
../shared/NOTES-sympy.md 1). Auxiliary speeds and their reactions:
:mod:`gen.intake.reactions`.
"""
from __future__ import annotations

import sympy as sm
from sympy.physics import mechanics as me

from ..core.errors import ModelError
from .canonical import Equations, split_last
from .checks import sym_name
from .reactions import auxiliary_zero, kane_auxiliary
from .reactions import eliminate_reactions as eliminate
from .sympy_compat import (kane_auxiliary_speeds, kane_configuration_constraints,
                           kane_dependent_counts, kane_frame, kane_is_formed, kane_kinematics,
                           kane_qdot_map, kane_velocity_constraints, time_symbol)

__all__ = ["kane_equations"]


def kane_equations(km, inputs=None, reactions=None, eliminate_reactions=True):
    """The Equations of a KanesMethod after ``kanes_equations`` (inputs: the
    declared inputs, which are not reactions; reactions, eliminate_reactions:
    as for :meth:`gen.Model.from_kanes`)."""
    if not kane_is_formed(km):
        raise ModelError("call km.kanes_equations(bodies, loads) before Model.from_kanes")
    uaux = kane_auxiliary_speeds(km)
    if reactions is not None and not uaux:
        raise ModelError("reactions given but the KanesMethod has no auxiliary speeds "
                         "(u_auxiliary)")
    t = time_symbol()
    q, u = list(km.q), list(km.u)
    nq, nu = len(q), len(u)
    nqd, nud = kane_dependent_counts(km)
    qdots = [qi.diff(t) for qi in q]
    # the kinematic equations as the user wrote them (Kqd q' + Ku u + kf = 0),
    # never sympy's symbolic solve for q' (explicit_kinematics=True), whose
    # expressions can be 0/0 at regular configurations (ZYX Euler angles at
    # hover): q' is solved numerically at run time when Kqd is not diagonal
    Kqd, Ku, kf = kane_kinematics(km)
    fc = kane_configuration_constraints(km)
    A, b = kane_velocity_constraints(km) if nud else (sm.zeros(0, nu), sm.zeros(0, 1))
    if fc.shape[0] != nqd:
        raise ModelError(
            f"KanesMethod has {nqd} dependent coordinates but {fc.shape[0]} "
            "configuration constraints; they must match")
    M, f = _dynamics(km, q, u, qdots, Kqd, Ku, kf, constrained=bool(nud or nqd))
    aux = None
    if uaux:
        # the auxiliary speeds and their derivatives are zero in every
        # equation of the real speeds (sympy zeroes them in its own M, f;
        # the unconstrained M, f above are formed again, so do it here)
        zero = auxiliary_zero(uaux, t)
        M, f = M.xreplace(zero[0]).xreplace(zero[1]), f.xreplace(zero[0]).xreplace(zero[1])
        # velocity constraints written with the auxiliary speeds (a contact
        # point's velocity, sympy's test_aux_dep): sympy keeps them in
        # _k_nh/_f_nh; they are zero in the real motion too
        A, b = A.xreplace(zero[0]).xreplace(zero[1]), b.xreplace(zero[0]).xreplace(zero[1])
        aux = kane_auxiliary(km, q, u, uaux, inputs, reactions, t, zero)
        if any(M.has(r_) or f.has(r_) for r_ in aux[1]):
            M, f, aux = eliminate(M, f, aux, [ui.diff(t) for ui in u], q,
                                  constrained=bool(nud), eliminate=eliminate_reactions)
    q_ind, q_dep = split_last(nq, nqd)
    u_ind, u_dep = split_last(nu, nud)
    return Equations(
        method="kane", t=t, q=q, u=u, qdots=qdots, udots=[ui.diff(t) for ui in u],
        q_ind=q_ind, q_dep=q_dep, u_ind=u_ind, u_dep=u_dep, Kqd=Kqd, Ku=Ku, kf=kf, M=M, f=f,
        A=A, b=b, fc=fc, qdot_subs=kane_qdot_map(km), speed_names=[sym_name(x) for x in u],
        aux=aux)


def _dynamics(km, q, u, qdots, Kqd, Ku, kf, constrained):
    """(M, f): the method's own without constraints; with them, the
    unconstrained equations for all speeds, formed again from the method's
    frame, bodies and loads (cheap), so that the dependent speeds are
    eliminated numerically at run time."""
    if not constrained:
        return sm.Matrix(km.mass_matrix), sm.Matrix(km.forcing)
    kdes = Kqd * sm.Matrix(qdots) + Ku * sm.Matrix(u) + kf
    km_free = me.KanesMethod(kane_frame(km), q_ind=q, u_ind=u, kd_eqs=kdes)
    km_free.kanes_equations(km.bodies, km.loads)
    return sm.Matrix(km_free.mass_matrix), sm.Matrix(km_free.forcing)
