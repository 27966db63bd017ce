"""The transcription of an optimal control problem into kernel families
(the point equations, the manifold, the defects, the costs, the path and
instance constraints, the fits), each a family of three generated kernels
over its local variables: values, the sparse Jacobian and the lower
triangle of the Hessian of sum_i lam_i g_i, from one CSE'd graph each
(gen.plan.ir). ocp_plan hands them to the render stage as the OCP
backend's ProductPlan (gen/codegen/backends/ OcpBackend)."""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import sympy as sm

from ...codegen.product_abi import ProductPlan
from ...core.names import c_name
from ...plan.ir import Arg, make_jacobian_kernel, make_kernel, prune
from ...sym.graph import gradient
from .events import event_families

__all__ = ["METHODS", "Family", "families", "family_kernels", "describe_local", "ocp_plan"]

METHODS = ("backward-euler", "midpoint", "trapezoidal", "hermite-simpson")


@dataclass
class Family:
    """A piece of the problem: exprs over the locals (internal symbols or
    dummies), nd instance data symbols, objective or constraint rows."""
    name: str
    locals: list
    exprs: list
    data: list = field(default_factory=list)
    objective: bool = False
    # filled by family_kernels
    jac: list = field(default_factory=list)      # [(row, local)]
    hess: list = field(default_factory=list)     # [(a, b)] a >= b


def _point_families(m, pf, method):
    """The point equations and the manifold (constrained models)."""
    nq, nu, mv, mc = m.nq, m.nu, m.mv, m.mc
    q, u, r, t = list(m.q), list(m.u), list(m.r), m.t
    qd = [sm.Dummy(f"qd{i}") for i in range(nq)]
    ud = [sm.Dummy(f"ud{i}") for i in range(nu)]
    lam = [sm.Dummy(f"lam{i}") for i in range(mv)]
    kin = m.Kqd * sm.Matrix(qd) + m.Ku * sm.Matrix(u) + m.kf
    dyn = m.M * sm.Matrix(ud) - m.f
    if mv:
        dyn = dyn - m.A.T * sm.Matrix(lam)
    fams = [Family("point", q + u + qd + ud + lam + r + pf + [t], list(kin) + list(dyn))]
    if mv:
        fams.append(Family("velocity", q + u + pf + [t], list(m.A * sm.Matrix(u) + m.b)))
    if mc:
        fams.append(Family("holonomic", q + pf + [t], list(m.fc)))
    if mv and method == "hermite-simpson":
        # the acceleration constraints at the nodes (the node multipliers'
        # equations; the midpoints' follow from the defects), OpenSim
        # Moco's form of Hermite-Simpson with kinematic constraints
        acc = m.A * sm.Matrix(ud) + m.a.xreplace(dict(zip(list(m.qd), qd)))
        fams.append(Family("acceleration", q + u + qd + ud + pf + [t], list(acc)))
    return fams


def _defect_family(m, method, N, T):
    """The defects tying the states to the slopes (the method's rule)."""
    nx, nq, mc = m.nq + m.nu, m.nq, m.mc
    mu = [sm.Dummy(f"mu{i}") for i in range(mc)]
    xa = [sm.Dummy(f"xa{i}") for i in range(nx)]
    xb = [sm.Dummy(f"xb{i}") for i in range(nx)]
    sa = [sm.Dummy(f"sa{i}") for i in range(nx)]
    sb = [sm.Dummy(f"sb{i}") for i in range(nx)]
    xm = [sm.Dummy(f"xm{i}") for i in range(nx)]
    sm_ = [sm.Dummy(f"sm{i}") for i in range(nx)]
    h = T / (N - 1)
    if method == "backward-euler":
        dl = xa + xb + sb + [T]
        de = [xb[i] - xa[i] - h * sb[i] for i in range(nx)]
    elif method == "midpoint":
        dl = xa + xb + sm_ + [T]
        de = [xb[i] - xa[i] - h * sm_[i] for i in range(nx)]
    elif method == "trapezoidal":
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
            q = list(m.q)
            Jm = m.fc.jacobian(q).xreplace(dict(zip(q, xm[:nq])))
            corr = Jm.T * sm.Matrix(mu)
            for i in range(nq):
                de[nx + i] -= h * sm.Rational(4, 6) * corr[i]
            dl = dl + mu
    return Family("defect", dl, de)


def families(ocp):
    """The families of an OptimalControl's problem, in assembly order."""
    m = ocp.model
    pf = [m.p[i] for i in ocp._pf]
    T = sm.Dummy("T")
    r, t = list(m.r), m.t
    N = ocp.nodes
    fams = _point_families(m, pf, ocp.method)
    fams.append(_defect_family(m, ocp.method, N, T))
    for name, loc, exprs in event_families(m, pf, ocp._events, ocp.periodic):
        fams.append(Family(name, loc, exprs))
    x = list(m.q) + list(m.u)
    if ocp._L is not None:
        w = sm.Dummy("w")
        fams.append(Family("cost", x + r + pf + [t, T], [w * T / (N - 1) * ocp._L],
                           data=[w], objective=True))
    if ocp._phi is not None:
        fams.append(Family("terminal", x + r + pf + [T], [ocp._phi.xreplace({t: T})],
                           objective=True))
    if ocp._path:
        fams.append(Family("path", x + r + pf + [t], list(ocp._path)))
    if ocp._instance:
        fams.append(Family("instance", [d for _, d in ocp._inst_refs] + pf,
                           list(ocp._instance)))
    for j, (kind, i) in enumerate(ocp._fit_keys):
        y = x[i] if kind == "x" else m.y[i]
        val = sm.Dummy("val")
        fams.append(Family(f"fit{j}", x + r + pf + [t], [(y - val) ** 2], data=[val],
                           objective=True))
    return fams


def family_kernels(fam, psyms):
    """The three kernels of a family (gen.plan.ir Kernel objects: values,
    the Jacobian's nonzeros, the Hessian's lower-triangle nonzeros), with
    fam's Jacobian and Hessian patterns filled in."""
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
    return [kval, kjac, khess]


def describe_local(s, m, pf, inst_refs):
    """A local variable as data: (role, index), what assembly gathers (pf:
    the indices of the parameters to identify; inst_refs: the instance
    constraints' ((state, time), dummy))."""
    name = s.name if isinstance(s, sm.Dummy) else None
    if s in m.q:
        return ("x", m.q.index(s))
    if s in m.u:
        return ("x", m.nq + m.u.index(s))
    if s in m.r:
        return ("r", m.r.index(s))
    if s in m.p:
        return ("pf", pf.index(m.p.index(s)))
    if s == m.t:
        return ("t", 0)
    mt = re.fullmatch(r"([a-z_]+?)(\d+)", name or "")
    if name == "T":
        return ("T", 0)
    if name == "w" or name == "val":
        raise AssertionError("data symbol among locals")
    if "_at_" in (name or ""):
        return ("inst", [d for _, d in inst_refs].index(s))
    if mt:
        role, i = mt.group(1), int(mt.group(2))
        if role == "qd":
            return ("s", i)
        if role == "ud":
            return ("s", m.nq + i)
        return (role, i)
    raise AssertionError(f"internal: unknown local {s}")


def ocp_plan(ocp):
    """(the OCP backend's ProductPlan, the families as data): the kernels
    of every family and, for assembly, each family's sizes, patterns and
    locals (describe_local)."""
    m = ocp.model
    kernels, meta = [], []
    for fam in families(ocp):
        kernels += family_kernels(fam, list(m.p))
        meta.append({"name": fam.name, "nv": len(fam.locals), "nrow": len(fam.exprs),
                     "nd": len(fam.data), "objective": fam.objective,
                     "jac": fam.jac, "hess": fam.hess,
                     "locals": [describe_local(s, m, ocp._pf, ocp._inst_refs)
                                for s in fam.locals]})
    rows = [{"nv": f["nv"], "nrow": f["nrow"], "nd": f["nd"], "njac": len(f["jac"]),
             "nhess": len(f["hess"]), "name": f["name"]} for f in meta]
    plan = ProductPlan(c_name(f"{m.name}_ocp"), kernels=kernels,
                       data={"model": m.name, "families": rows})
    return plan, meta
