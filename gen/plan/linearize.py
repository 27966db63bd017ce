"""Symbolic linearization of a canonical model at a given operating point.

``linearize_symbolic`` returns A and B as sympy matrices for the
independent state [q_ind, u_ind] (sympy's ``A_and_B=True`` partition),
following the same elimination (Peterson, Gede & Hubbard) as the C
runtime's ``gen_rt_linearize``. The operating point is substituted
*before* anything is solved, so the linear solves act on small matrices
of numbers and parameters, never on the full symbolic system (the source
of sympy's NaN at regular points, ../shared/NOTES-sympy.md point 2).

For small models, to reproduce closed forms such as the seed document's
A = [[0, 1], [-g/L, 0]]; for numbers at many points use the compiled
``Simulator.linearize``.
"""
from __future__ import annotations

import sympy as sm

from ..core.status import status_value
from ..core.errors import ModelError, SingularError
from ..intake.model import Model

__all__ = ["linearize_symbolic"]


def _key_index(model, key):
    """Map a user's key (symbol, q'(t), or state/input name) to ('x', i) or
    ('r', i)."""
    names = model.state_names
    if isinstance(key, str):
        for pool, where in ((names, "x"), (model.state_labels, "x"),
                            (model.input_names, "r"), (model.input_labels, "r")):
            if key in pool:
                return where, pool.index(key)
        raise ModelError(f"operating point names {key!r}, which is not a state or input of "
                         f"'{model.name}'; states: {names}, inputs: {model.input_names}")
    pool = list(model.q_orig) + list(model.u_orig)
    for i, s in enumerate(pool):
        if s == key:
            return "x", i
    for i, s in enumerate(model.r_orig):
        if s == key:
            return "r", i
    raise ModelError(f"operating point key {key} is not a coordinate, speed or input of "
                     f"'{model.name}'; states: {pool}, inputs: {list(model.r_orig)}")


def _solve(Mat, rhs, what):
    Mat = Mat.applyfunc(sm.simplify)
    try:
        return Mat.LUsolve(rhs).applyfunc(sm.simplify)
    except (ValueError, ZeroDivisionError) as e:
        raise SingularError(f"{what} is singular at this operating point ({e})",
                            status=status_value("ERR_SINGULAR"), status_name="ERR_SINGULAR") from None


def linearize_symbolic(model: Model, op_point=None, r_op=None, constants=None, t=0,
                       simplify=True):
    """The linearization A, B as sympy matrices, about an operating point.

    The operating point need not be an equilibrium: the accelerations and
    multipliers there are solved from the model.

    Parameters
    ----------
    model : gen.Model
        The model (small ones: the algebra is symbolic).
    op_point : dict, optional
        ``{coordinate or speed: value}`` (the user's sympy objects, or state
        names as strings); values may be numbers or expressions in the
        model's constants. States left out stay symbolic.
    r_op : dict, optional
        ``{input: value}`` (may also be given inside op_point); unset inputs
        are 0.
    constants : None, "values" or dict, optional
        None keeps the constants as symbols; ``"values"`` substitutes the
        model's values; a dict ``{symbol or name: value}`` those given.
    t : optional
        The time.
    simplify : bool, optional
        Simplify the result.

    Returns
    -------
    A : sympy.Matrix, shape (ns, ns)
    B : sympy.Matrix, shape (ns, nr)

    Raises
    ------
    gen.SingularError
        When the dependent partition or the dynamics are singular at the
        point.
    gen.ModelError
        On an unknown name in op_point, r_op or constants.
    """
    if not isinstance(model, Model):
        raise ModelError(f"linearize_symbolic needs a gen.Model, got {type(model).__name__}")
    m = model
    csub = _constants_map(m, constants)
    pt = _Point(m, _operating_point(m, op_point, r_op, csub, t))
    Q, U = sm.Matrix(m.q), sm.Matrix(m.u)
    niq, niu = m.nq - m.mc, m.nu - m.mv
    # the Linearizer's f_0..f_4, f_c, f_v, f_a at the point
    Kq = pt.jac(m.Kqd * pt.Qd + m.Ku * U + m.kf, Q)
    R = m.M * pt.Ud - m.f - (m.A.T * pt.Lam if m.mv else sm.zeros(m.nu, 1))
    if pt.coupled:
        R = R - m.aux_G * pt.Lam
    Rq, Ru = pt.jac(R, Q), pt.jac(R, U)
    Rr = pt.jac(R, sm.Matrix(m.r)) if m.nr else sm.zeros(m.nu, 0)
    Qm = _coordinate_map(m, pt)                                 # 1. dq = Qm dq_ind
    Uq, Uu = _speed_map(m, pt, Qm)                              # 2. du = Uq dq_ind + Uu du_ind
    # 3. kinematics: Kqd dq' = -[Kq Qm + Ku Uq | Ku Uu]
    Dq = _solve(pt.Kqd0, -(Kq * Qm + pt.Ku0 * Uq).row_join(pt.Ku0 * Uu),
                "the kinematic matrix Kqd")
    # 4. dynamics
    G = -(Rq * Qm + Ru * Uq).row_join(Ru * Uu).row_join(Rr)
    G = _constraint_rows(m, pt, G, Qm, Uq, Uu, Dq)
    Z = _solve(pt.K, G, "the constrained dynamics [M, -A^T; A, 0]")
    # 5. independent rows
    ns = niq + niu
    A_lin, B_lin = sm.zeros(ns, ns), sm.zeros(ns, m.nr)
    for k, i in enumerate(m.q_ind):
        A_lin[k, :] = Dq[i, :]
    for k, i in enumerate(m.u_ind):
        A_lin[niq + k, :] = Z[i, :ns]
        B_lin[niq + k, :] = Z[i, ns:]
    if simplify:
        A_lin = A_lin.applyfunc(sm.simplify)
        B_lin = B_lin.applyfunc(sm.simplify)
    if any(e.has(sm.nan, sm.zoo, sm.oo, -sm.oo) for e in list(A_lin) + list(B_lin)):
        raise SingularError("the linearization is not finite at this operating point",
                            status=status_value("ERR_SINGULAR"), status_name="ERR_SINGULAR")
    return A_lin, B_lin


def _constants_map(m, constants):
    """{constant: value} for linearize_symbolic's constants argument: None
    keeps them symbols, "values" the model's values, a dict those given (by
    symbol or name)."""
    csub = {}
    if constants is None:
        pass
    elif isinstance(constants, str) and constants == "values":
        csub = dict(zip(m.p_orig, [sm.nsimplify(v) if float(v).is_integer() else sm.Float(v)
                                   for v in m.p_values]))
    elif isinstance(constants, dict):
        for k, v in constants.items():
            hit = [s for s in m.p_orig if s == k or str(s) == str(k)]
            if not hit:
                raise ModelError(f"constant {k} is not one of '{m.name}''s constants "
                                 f"{[str(s) for s in m.p_orig]}")
            csub[hit[0]] = sm.sympify(v)
    else:
        raise ModelError("constants must be None, 'values' or a dict {symbol: value}")
    return csub


def _operating_point(m, op_point, r_op, csub, t):
    """{internal symbol: value} of the operating point: the states and
    inputs given (unset states stay symbolic, unset inputs are 0), the
    constants (csub, else symbols) and t."""
    nq = m.nq
    xv = list(m.q_orig) + list(m.u_orig)
    rv = [sm.S.Zero] * m.nr
    items = list((op_point or {}).items()) + list((r_op or {}).items())
    for k, v in items:
        where, i = _key_index(m, k)
        val = sm.sympify(v).xreplace(csub) if csub else sm.sympify(v)
        if where == "x":
            xv[i] = val
        else:
            rv[i] = val
    sub = dict(zip(m.q, xv[:nq]))
    sub.update(zip(m.u, xv[nq:]))
    sub.update(zip(m.r, rv))
    sub.update({P: csub.get(po, po) for P, po in zip(m.p, m.p_orig)})
    sub[m.t] = sm.sympify(t)
    return sub


class _Point:
    """The model at the operating point: its rates q', accelerations u' and
    multipliers (or reactions) there, solved from the model, the KKT matrix
    K, and Jacobians evaluated at the point (jac)."""

    def __init__(self, m, sub):
        self.m, self.sub = m, sub
        nu, mv = m.nu, m.mv
        U = sm.Matrix(m.u)
        self.Kqd0, self.Ku0, kf0 = self.at(m.Kqd), self.at(m.Ku), self.at(m.kf)
        qd0 = _solve(self.Kqd0, -(self.Ku0 * self.at(U) + kf0), "the kinematic matrix Kqd")
        M0, f0 = self.at(m.M), self.at(m.f)
        self.A0 = self.at(m.A) if mv else sm.zeros(0, nu)
        K = sm.zeros(nu + mv, nu + mv)
        K[:nu, :nu] = M0
        rhs = sm.zeros(nu + mv, 1)
        rhs[:nu, 0] = f0
        if mv:
            K[:nu, nu:] = -self.A0.T
            K[nu:, :nu] = self.A0
            rhs[nu:, 0] = -self.at(m.a).xreplace(dict(zip(m.qd, qd0)))
        self.coupled = getattr(m, "aux_G", None) is not None
        if self.coupled:
            # reactions inside the motion (mv == 0): [M, -G; C, H] [u'; R] = [f; -g0]
            na = m.na
            zero_ud = {s_: 0 for s_ in m.ud}
            K = sm.zeros(nu + na, nu + na)
            K[:nu, :nu] = M0
            K[:nu, nu:] = -self.at(m.aux_G)
            K[nu:, :nu] = self.at(m.aux_g.jacobian(list(m.ud)))
            K[nu:, nu:] = self.at(m.aux_F)
            rhs = f0.col_join(-self.at(m.aux_g.xreplace(zero_ud)))
        self.K = K
        sol = _solve(K, rhs, "the constrained dynamics [M, -A^T; A, 0]" if not self.coupled
                     else "the coupled dynamics and reactions [M, -G; C, F]")
        ud0, lam0 = sol[:nu, 0], sol[nu:, 0]
        self.Qd = sm.Matrix([sm.Dummy(f"qd{i}") for i in range(m.nq)])
        self.Ud = sm.Matrix([sm.Dummy(f"ud{i}") for i in range(nu)])
        self.Lam = sm.Matrix([sm.Dummy(f"lam{i}")
                              for i in range(mv if not self.coupled else m.na)])
        self.rates = dict(zip(self.Qd, qd0))
        self.rates.update(zip(self.Ud, ud0))
        self.rates.update(zip(self.Lam, lam0))

    def at(self, expr):
        return sm.Matrix(expr).xreplace(self.sub)

    def jac(self, expr, wrt):
        return self.at(expr.jacobian(wrt)).xreplace(self.rates)


def _coordinate_map(m, pt):
    """Qm with dq = Qm dq_ind: the dependent coordinates' share through the
    configuration constraints' Jacobian at the point."""
    Q = sm.Matrix(m.q)
    niq = m.nq - m.mc
    Qm = sm.zeros(m.nq, niq)
    for k, i in enumerate(m.q_ind):
        Qm[i, k] = 1
    if m.mc:
        Jc = pt.jac(m.fc, Q)
        Jd = Jc.extract(list(range(m.mc)), m.q_dep)
        Ji = Jc.extract(list(range(m.mc)), m.q_ind)
        X = _solve(Jd, Ji, "the configuration-constraint Jacobian w.r.t. the dependent coordinates")
        for j, i in enumerate(m.q_dep):
            Qm[i, :] = -X[j, :]
    return Qm


def _speed_map(m, pt, Qm):
    """(Uq, Uu) with du = Uq dq_ind + Uu du_ind: the dependent speeds' share
    through the velocity constraints at the point."""
    niq, niu, mv = m.nq - m.mc, m.nu - m.mv, m.mv
    Uu, Uq = sm.zeros(m.nu, niu), sm.zeros(m.nu, niq)
    for k, i in enumerate(m.u_ind):
        Uu[i, k] = 1
    if mv:
        Vq = pt.jac(m.A * sm.Matrix(m.u) + m.b, sm.Matrix(m.q))
        Ad = pt.A0.extract(list(range(mv)), m.u_dep)
        Ai = pt.A0.extract(list(range(mv)), m.u_ind)
        Y = _solve(Ad, Ai.row_join(Vq * Qm), "the velocity-constraint matrix w.r.t. the "
                   "dependent speeds")
        for j, i in enumerate(m.u_dep):
            Uu[i, :] = -Y[j, :niu]
            Uq[i, :] = -Y[j, niu:]
    return Uq, Uu


def _constraint_rows(m, pt, G, Qm, Uq, Uu, Dq):
    """G with the rows of the acceleration constraints (with velocity
    constraints) or of the auxiliary residual (reactions inside the motion:
    the implicit function theorem on the coupled system) below the
    dynamics' rows."""
    Q, U, nr = sm.Matrix(m.q), sm.Matrix(m.u), m.nr
    if m.mv:
        # a may hold q' (m.qd, implicit kinematics): its share through q'(q, u)
        S = m.A * pt.Ud + m.a.xreplace(dict(zip(m.qd, pt.Qd)))
        Sq, Su = pt.jac(S, Q), pt.jac(S, U)
        GS = (-(Sq * Qm + Su * Uq)).row_join(-Su * Uu)
        if m.qd:
            GS = GS - pt.jac(S, pt.Qd) * Dq
        G = G.col_join(GS.row_join(sm.zeros(m.mv, nr)))
    if pt.coupled:
        S = m.aux_F * pt.Lam + m.aux_g.xreplace(dict(zip(m.ud, pt.Ud)))
        Sq, Su = pt.jac(S, Q), pt.jac(S, U)
        Sr = pt.jac(S, sm.Matrix(m.r)) if nr else sm.zeros(m.na, 0)
        G = G.col_join((-(Sq * Qm + Su * Uq)).row_join(-Su * Uu).row_join(-Sr))
    return G
