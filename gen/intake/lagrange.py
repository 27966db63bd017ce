"""The Lagrange adapter: a formed ``LagrangesMethod`` -> :class:`gen.intake.canonical.Equations`.

The speeds are the coordinate derivatives (u := q', the state x = [q, q'] in
the method's coordinate order); the velocity constraints are the Jacobian of
the method's ``coneqs`` (holonomic constraints differentiated, and the
nonholonomic ones) in q'. The multipliers are solved for numerically at run
time. Sign: M u' = f + A^T lam with A = d(coneqs)/dq', so lam is the
multiplier part of the solution of sympy's ``mass_matrix_full`` system, the
negative of ``LM.solve_multipliers`` (sympy issue 30215).
"""
from __future__ import annotations

import sympy as sm

from ..core.errors import ModelError
from .canonical import Equations
from .checks import sym_name
from .sympy_compat import lagrange_dynamics, lagrange_holonomic, time_symbol

__all__ = ["lagrange_equations", "lagrange_partition"]


def lagrange_equations(lm, q_ind=None, qd_ind=None, q_dep=None, qd_dep=None):
    """The Equations of a LagrangesMethod after
    ``form_lagranges_equations``, with the partition given (as for
    :meth:`gen.Model.from_lagrange`: all coordinates independent by
    default)."""
    if getattr(lm, "eom", None) is None:
        raise ModelError("call lm.form_lagranges_equations() before Model.from_lagrange")
    t = time_symbol()
    q = list(lm.q)
    n = len(q)
    qdots = [qi.diff(t) for qi in q]
    qdds = [qi.diff(t, 2) for qi in q]
    qi, qdp, ui, udp = _partition(q, qdots, q_ind, qd_ind, q_dep, qd_dep)
    M, f = lagrange_dynamics(lm)
    fc = lagrange_holonomic(lm)
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
    # the speeds are the coordinate derivatives: u_i := q_i' (the canonical
    # passes map the q' objects to the speed symbols)
    return Equations(
        method="lagrange", t=t, q=q, u=qdots, qdots=qdots, udots=qdds,
        q_ind=qi, q_dep=qdp, u_ind=ui, u_dep=udp, Kqd=sm.eye(n), Ku=-sm.eye(n),
        kf=sm.zeros(n, 1), M=M, f=f, A=A, b=b, fc=fc, qdot_subs={},
        speed_names=[sym_name(x) + "_d" for x in q])


def _partition(q, qdots, q_ind, qd_ind, q_dep, qd_dep):
    """(q_ind, q_dep, qd_ind, qd_dep) as indices into q: every coordinate
    independent when no partition is given; each list checked against the
    model's coordinates (or their derivatives), both halves together listing
    each exactly once."""
    n = len(q)
    q_ind, q_dep = list(q_ind or []), list(q_dep or [])
    qd_ind, qd_dep = list(qd_ind or []), list(qd_dep or [])
    if not q_ind and not q_dep:
        q_ind = list(q)
    if not qd_ind and not qd_dep:
        qd_ind = list(qdots)

    def index_of(items, pool, what):
        out = []
        for it in items:
            hits = [i for i, s in enumerate(pool) if s == it]
            if not hits:
                kind = what[:-4] if what.endswith('_ind') or what.endswith('_dep') else what
                raise ModelError(f"{what} entry {it} is not one of the model's {kind}: "
                                 f"{list(pool)}")
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
    return qi, qdp, ui, udp


def lagrange_partition(system, lm, partition):
    """q_ind/q_dep/qd_ind/qd_dep for a LagrangesMethod from a sympy System:
    the user's where given, else the System's coordinates and, for the
    derivatives, its speeds when they are the coordinate derivatives and
    split as the velocity constraints need (a Lagrange System built with q'
    as the joints' speeds), else q_ind' and q_dep'."""
    out = dict(partition)
    t = time_symbol()
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
