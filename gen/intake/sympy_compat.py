"""Every read of a private attribute of a ``sympy.physics.mechanics`` object,
one function each.

eomgen reads what sympy's mechanics objects hold but do not publish: the
kinematic equations as the user wrote them (never sympy's symbolic solve for
q'), the velocity constraints before sympy eliminates the dependent speeds,
a LagrangesMethod's dynamic equations without the multipliers. Those are
private attributes, which a sympy release may rename or drop. They are read
here and nowhere else, so that a new sympy version is checked (and, if need
be, followed) in this one module; ``tests/unit/intake/test_sympy_compat.py``
calls every function on formed methods of the installed sympy.

Checked on sympy 1.14.0 (the version the project pins and tests). The
``*_implicit`` kinematic attributes appeared in sympy 1.12 (sympy PR 23580,
``explicit_kinematics``); with an older sympy the explicit ones are read, as
before. The public names of the same objects (``km.q``, ``km.u``,
``km.bodies``, ``km.loads``, ``km.mass_matrix``, ``lm.coneqs``, ...) are used
directly where they are needed.
"""
from __future__ import annotations

import sympy as sm
from sympy.physics import mechanics as me

__all__ = ["time_symbol", "kane_is_formed", "kane_auxiliary_speeds", "kane_dependent_counts",
           "kane_kinematics", "kane_configuration_constraints", "kane_velocity_constraints",
           "kane_frame", "kane_qdot_map", "lagrange_dynamics", "lagrange_holonomic",
           "orient_explicit_without_rates"]


def time_symbol():
    """The time symbol t of ``dynamicsymbols`` (``dynamicsymbols._t``, the
    t of every q(t) sympy makes; sympy 1.14)."""
    return me.dynamicsymbols._t


# ------------------------------------------------------------- KanesMethod
def kane_is_formed(km):
    """Whether ``km.kanes_equations`` was called (``km._fr`` is set by it;
    None before; sympy 1.14)."""
    return getattr(km, "_fr", None) is not None


def kane_auxiliary_speeds(km):
    """The auxiliary speeds ``u_auxiliary`` as a list (``km._uaux``; an empty
    Matrix when none; sympy 1.14)."""
    uaux = getattr(km, "_uaux", None)
    return list(uaux) if uaux is not None else []


def kane_dependent_counts(km):
    """(number of dependent coordinates, number of dependent speeds): the
    lengths of ``km._qdep`` and ``km._udep`` (sympy 1.14; None counts as 0)."""
    return (len(km._qdep) if km._qdep is not None else 0,
            len(km._udep) if km._udep is not None else 0)


def kane_kinematics(km):
    """(Kqd, Ku, kf) with the kinematic equations Kqd q' + Ku u + kf = 0 as
    the user gave them (``_k_kqdot_implicit``, ``_k_ku_implicit``,
    ``_f_k_implicit``, sympy >= 1.12), never sympy's symbolic solve for q'
    (``explicit_kinematics=True``, whose entries can be 0/0 at regular
    configurations); the explicit ``_k_kqdot``, ``_k_ku``, ``_f_k`` when the
    implicit ones do not exist (sympy < 1.12). Checked on sympy 1.14."""
    def read(implicit, explicit):
        return sm.Matrix(getattr(km, implicit) if hasattr(km, implicit) else getattr(km, explicit))

    return (read("_k_kqdot_implicit", "_k_kqdot"), read("_k_ku_implicit", "_k_ku"),
            read("_f_k_implicit", "_f_k"))


def kane_configuration_constraints(km):
    """The configuration constraints f_c(q, t) = 0 as a column (``km._f_h``;
    an empty column when there are none; sympy 1.14)."""
    fh = km._f_h
    return sm.Matrix(fh) if fh is not None and len(fh) else sm.zeros(0, 1)


def kane_velocity_constraints(km):
    """(A, b) with the velocity constraints A u + b = 0 before sympy
    eliminates the dependent speeds (``km._k_nh``, ``km._f_nh``; sympy
    1.14). Only meaningful when the method has dependent speeds."""
    return sm.Matrix(km._k_nh), sm.Matrix(km._f_nh)


def kane_frame(km):
    """The inertial frame the method was made with (``km._inertial``;
    sympy 1.14)."""
    return km._inertial


def kane_qdot_map(km):
    """{q': expression in q, u} from sympy's solve of the kinematic
    equations (``km._qdot_u_map``, a dict or None; sympy 1.14): used only to
    replace q' left in M and f, whose own forms already hold it."""
    m = getattr(km, "_qdot_u_map", None)
    return dict(m) if m else {}


# --------------------------------------------------------- LagrangesMethod
def lagrange_dynamics(lm):
    """(M, f): the dynamic equations M q'' = f without the multiplier terms
    (``lm._m_d``, ``lm._f_d``, set by ``form_lagranges_equations``; sympy
    1.14)."""
    return sm.Matrix(lm._m_d), sm.Matrix(lm._f_d)


def lagrange_holonomic(lm):
    """The holonomic constraints f_c(q, t) = 0 as a column (``lm._hol_coneqs``;
    an empty column when there are none or the attribute is absent; sympy
    1.14)."""
    hol = getattr(lm, "_hol_coneqs", None)
    return sm.Matrix(hol) if hol is not None and len(hol) else sm.zeros(0, 1)


# ------------------------------------------------------- ReferenceFrame
def orient_explicit_without_rates(frame, parent, dcm):
    """``frame.orient_explicit(parent, dcm)`` (``dcm``: parent components of
    frame's axes) without sympy's angular velocity from the derivative of
    ``dcm`` (``orient_dcm`` differentiates, expands and trigsimps its nine
    entries: seconds for a quaternion's): the orientation alone, through
    ``ReferenceFrame._dcm`` and a reset ``_var_dict``, as ``orient_dcm`` does
    before its rates (sympy 1.14). The caller sets the angular velocity
    (``frame.set_ang_vel``)."""
    frame._dcm(parent, dcm)
    frame._var_dict = {}
