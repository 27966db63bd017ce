"""The articulated body algorithm of a sympy ``System``'s open joint tree, in
each body's own axes at its joint (issue 45).

``Model.from_system(system, formulation="recursive")`` of an open tree (no
constraints, no ``hybrid``) takes ``u'`` from :func:`accelerations_of_tree`
and hands the pipeline ``M = I``, ``f = u'`` (:mod:`gen.intake.recursive`
explains why, and forms M and f by CRBA and RNEA where the true M is needed).

The recursions are Featherstone's, as Pinocchio runs them: spatial vectors
(angular part first) in each body's axes (its frame) at its origin, the
point its joint holds it by (the joint's ``child_point``). There,

- the body's spatial inertia and its joint's motion subspace ``S`` are
  constants, and ``S`` is sparse: a pin about a body axis is one unit entry,
  so ``U = I^A S`` is a column of ``I^A`` and ``D = S^T U`` one of its entries;
- the transform from the parent's axes is the joint's own rotation ``E``
  (``child.frame.dcm(parent.frame)``: a pin turns about one axis, so ``E`` is
  the constant rotation of the joint's placement times four sines and
  cosines) and the joint vector ``p`` from the parent's origin, a constant
  for a pin: no body's orientation in the world is formed, where the
  inertial axes (CRBA and RNEA) need each body's full rotation, its inertia
  turned by it (``R I R^T``) and its ``S`` turned.

Gravity, when it is uniform (every body's weight ``m g`` at its mass
centre, ``g`` one constant vector in the inertial axes, as
``System.apply_uniform_gravity`` and :func:`gen.load_urdf` give it), is the
base's acceleration ``-g`` (Featherstone's fictitious base acceleration);
any other load in the inertial axes is turned into the body's axes through
the chain of the bodies' rotations, formed only for the bodies that need it.

Per body, outward: the velocity ``v = X v_parent + S u_j`` and the
velocity-product acceleration ``c = c_J + v x S u_j``; the bias force
``p = v x* I v - f_ext``. Inward: ``I^A``, ``p^A``, ``U``, ``D^-1``,
``uu = -S^T p^A``, and the articulated inertia and bias seen through the
joint, carried to the parent by ``X^T (.) X`` (rotated by ``E^T``, then
shifted by ``p``). Outward: ``a' = X a_parent + c``,
``u'_j = D^-1 (uu - U^T a')``, ``a = a' + S u'_j``. Every body's quantities
are shared opaque nodes (:class:`gen.sym.intern.Interner`): the graph, and
so the straight-line C, is linear in the bodies.
"""
from __future__ import annotations

import sys

import sympy as sm
import sympy.physics.mechanics as me

from ..core.errors import ModelError
from ..sym.intern import Interner
from .recursive import (Places, Tree, col, cross, inertia_matrix, joint_kinematics,
                        massless_joint_error, same_for_all, skew)
from .sympy_compat import time_symbol

__all__ = ["accelerations_of_tree", "twin_speeds"]

_T = time_symbol()


def accelerations_of_tree(system, interner=None):
    """u' of a System's open joint tree by the articulated body algorithm in
    the bodies' own axes (module docstring).

    Parameters
    ----------
    system : sympy System
        A tree of rigid bodies and joints without constraints.
    interner : gen.sym.intern.Interner, optional
        The build's interner (its opaque nodes); a new one when None.

    Returns
    -------
    (ud, q, u, kdes, twins) : sympy Matrix (nu, 1), list, list, Matrix (nq, 1), list
        The accelerations in the System's speed order, the System's
        kinematic equations (``kdes = 0``) and the twin speeds
        (:func:`twin_speeds`).
    """
    ik = Interner() if interner is None else interner
    tree = Tree(system)
    tree.ik = ik
    joint_kinematics(tree)
    # the graph is a few nodes deep per body, inward and outward: the
    # pipeline's recursive walks (model conversion, CSE) go that deep
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 2000 + 200 * len(tree.order)))
    for n in tree.order:
        _at_origin(n, tree)
    a0 = _loads(tree, system)
    for n in tree.order:
        _velocity(n, ik)
    for n in reversed(tree.order):
        _inward(n, ik)
    ud = sm.zeros(len(tree.u), 1)
    for n in tree.order:
        _outward(n, a0, ud, ik)
    return ud, tree.q, tree.u, tree.kdes, twin_speeds(tree)


def twin_speeds(tree):
    """Pairs (i, j) of speed indices whose equations are alike: the speeds
    of twin subtrees, siblings (children of one body, or joined to the
    ground) with the same joints (kind, number of speeds, children alike,
    recursively), matched two by two in the tree's order and then joint by
    joint (a robot's two legs; a quadruped's four legs, as two pairs).

    They are a hint for the generator (gen.codegen.lanes computes twin
    statements side by side), checked there statement by statement: the
    limbs' constants and placements may differ."""
    memo = {}

    def sig(n):
        k = memo.get(id(n))
        if k is None:
            k = memo[id(n)] = (type(n.joint).__name__, len(n.joint.speeds),
                               tuple(sorted(sig(c) for c in n.children)))
        return k

    out = []

    def match(a, b):
        out.extend(zip(a.speed_idx, b.speed_idx))
        for x, y in zip(sorted(a.children, key=sig), sorted(b.children, key=sig)):
            match(x, y)

    def visit(nodes):
        groups = {}
        for n in nodes:
            groups.setdefault(sig(n), []).append(n)
        for group in groups.values():
            for x, y in zip(group[0::2], group[1::2]):
                match(x, y)
            if len(group) % 2:
                visit(group[-1].children)

    visit([n for n in tree.order if n.parent is None])
    return out


# ------------------------------------------------------------ the joints
def _at_origin(n, tree):
    """n's joint at the body's origin, in its axes: E (child <- parent, its
    sines and cosines kept), p (the origin from the parent's, parent axes),
    So and the velocity-product part cJ (from the mass-centre ones of
    joint_kinematics)."""
    ik = tree.ik
    qj = list(n.joint.coordinates)
    E = n.E
    trig = {}
    for f in E.atoms(sm.sin, sm.cos):
        trig[f] = ik.keep(f)
    n.E = (E.xreplace(trig) if trig else E).applyfunc(lambda e: _keep_entry(e, ik))
    rc = n.r_cc
    S = n.S
    if S.shape[1]:
        Sw = S[:3, :]
        Sv = (S[3:, :] + skew(rc) * Sw).applyfunc(sm.expand)
        So = sm.Matrix.vstack(Sw, Sv)
        bias = n.rel_bias
        if qj and So.has(*qj):
            # an axis sympy wrote through the joint's own rotation (a pin
            # about a tilted axis): constant in the body's axes
            S0 = So.xreplace({x: 0 for x in qj})
            if same_for_all(So, S0, qj):
                So, bias = S0, None
        n.So = ik.kept(So)
        if bias is not None:
            bw = bias[:3, :]
            bias = sm.Matrix.vstack(bw, bias[3:, :] + skew(rc) * bw)
            n.cJ = ik.kept(bias)
        else:
            n.cJ = None
    else:
        n.So, n.cJ = sm.zeros(6, 0), None
    if n.parent is not None:
        n.p = ik.kept((n.r_pp + n.parent.r_cc).applyfunc(sm.expand))
    else:
        n.p = None
    n.Rn = None


def _keep_entry(e, ik):
    """e kept, unless a number or a number times a kept node."""
    if e.is_Number or isinstance(e, sm.UnevaluatedExpr) or (
            e.is_Mul and len(e.args) == 2 and e.args[0].is_Number
            and isinstance(e.args[1], sm.UnevaluatedExpr)):
        return e
    return ik.keep(e)


# ------------------------------------------------------------ the loads
def _loads(tree, system):
    """Each body's external spatial force (fw, fv: the moment about its
    origin and the force, its axes), and the base's acceleration: -g when
    gravity is uniform (module docstring), else zero."""
    places = Places(tree, system)
    for n in tree.order:
        n.fw, n.fv = sm.zeros(3, 1), sm.zeros(3, 1)
    loads = list(system.loads)
    for act in system.actuators:
        loads.extend(act.to_loads())
    g, weights = _uniform_gravity(tree, places, loads)
    for ld in loads:
        if isinstance(ld, me.Force):
            if id(ld) in weights:
                continue
            b = places.body_of_point(ld.point, f"force {ld}")
            if b is None:
                continue
            n = tree.nodes[b]
            F = _in_body(n, ld.vector, places, tree)
            n.fv += F
            r = ld.point.pos_from(n.joint.child_point).to_matrix(b.frame)
            if any(x != 0 for x in r):
                n.fw += cross(r, F)
        elif isinstance(ld, me.Torque):
            b = places.body_of_frame(ld.frame, f"torque {ld}")
            if b is None:
                continue
            n = tree.nodes[b]
            n.fw += _in_body(n, ld.vector, places, tree)
        else:      # pragma: no cover - sympy's loads are Force or Torque
            raise ModelError(f"load {ld!r} is neither a Force nor a Torque")
    return None if g is None else -g


def _uniform_gravity(tree, places, loads):
    """(g, ids of the weight loads) when every body of the tree has one
    force at its mass centre equal to its mass times one constant g in the
    inertial axes (and no body a second such force); (None, ()) otherwise."""
    centre = {n.body.masscenter: n for n in tree.order}
    N = tree.N
    found = {}
    for ld in loads:
        if not isinstance(ld, me.Force) or ld.point not in centre:
            continue
        if any(fr not in places.ground_frames for _, fr in ld.vector.args):
            continue
        F = ld.vector.to_matrix(N)
        if F.has(_T) or centre[ld.point] in found:
            continue
        found[centre[ld.point]] = (ld, F)
    massive = [n for n in tree.order if n.body.mass != 0]
    if not massive or any(n not in found for n in massive) or not found:
        return None, ()
    n0 = massive[0]
    g = (found[n0][1] / n0.body.mass).applyfunc(sm.cancel)
    for n, (_ld, F) in found.items():
        if any(sm.expand(F[i] - n.body.mass * g[i]) != 0 for i in range(3)):
            return None, ()
    if all(x == 0 for x in g):
        return None, {id(ld) for ld, _F in found.values()}
    return g, {id(ld) for ld, _F in found.values()}


def _in_body(n, vec, places, tree):
    """A sympy Vector's components in n's body axes."""
    out = sm.zeros(3, 1)
    body = n.body
    for comp, frame in vec.args:
        comp = sm.Matrix(comp)
        owner = None if frame in places.ground_frames else \
            places.body_of_frame(frame, f"a load's vector in frame {frame.name!r}")
        if owner is body:
            out += (comp if frame == body.frame else sm.Matrix(body.frame.dcm(frame)) * comp)
        elif n.parent is not None and owner is n.parent.body:
            v = n.E * (sm.Matrix(owner.frame.dcm(frame)) * comp)
            qj = list(n.joint.coordinates)
            # (doit: the kept sines and cosines at 0 are numbers again)
            v0 = v.xreplace({x: 0 for x in qj}).doit()
            # a vector along the joint's own axis (its torque) has the same
            # components in both bodies: no rotation at run time
            out += v0 if same_for_all(v, v0, qj) else v
        else:
            Rn = _world_rotation(n, tree)
            if owner is None:
                w = sm.Matrix(tree.N.dcm(frame)) * comp
            else:
                o = tree.nodes[owner]
                w = _world_rotation(o, tree).T * (sm.Matrix(owner.frame.dcm(frame)) * comp)
            out += Rn * w
    return out


def _world_rotation(n, tree):
    """n's body axes <- the inertial axes (kept nodes), formed on demand."""
    if n.Rn is None:
        R = n.E if n.parent is None else n.E * _world_rotation(n.parent, tree)
        n.Rn = tree.ik.kept(R)
    return n.Rn


# ------------------------------------------------------------ the passes
def _velocity(n, ik):
    """n.v = (w, v) and n.c, outward; the body's bias force into (fw, fv)."""
    nj = n.So.shape[1]
    vJ = ik.kept(n.So * col(n.joint.speeds)) if nj else sm.zeros(6, 1)
    if n.parent is None:
        w, v = vJ[:3, :], vJ[3:, :]
        c = (sm.zeros(3, 1), sm.zeros(3, 1))
    else:
        wp, vp = n.parent.v
        E = n.E
        w = ik.kept(E * wp)
        v = ik.kept(E * (vp + cross(wp, n.p)))
        c = (cross(w, vJ[:3, :]), cross(w, vJ[3:, :]) + cross(v, vJ[:3, :]))
        w, v = ik.kept(w + vJ[:3, :]), ik.kept(v + vJ[3:, :])
    if n.cJ is not None:
        c = (c[0] + n.cJ[:3, :], c[1] + n.cJ[3:, :])
    n.v = (w, v)
    n.c = (ik.kept(c[0]), ik.kept(c[1]))
    # the body's bias force v x* I v - f_ext: at the mass centre (velocity
    # vc) [w x Ic w; m w x vc], moved to the origin
    b, rc = n.body, n.r_cc
    Ic = inertia_matrix(b)
    vc = ik.kept(v + cross(w, rc))
    fv = ik.kept(b.mass * cross(w, vc))
    n.fw = cross(w, ik.kept(Ic * w)) + cross(rc, fv) - n.fw
    n.fv = fv - n.fv
    # the body's spatial inertia at its origin
    m, rx = b.mass, skew(rc)
    n.IA = (Ic - m * rx * rx, m * rx, m * sm.eye(3))


def _inward(n, ik):
    """I^A, p^A, U, D^-1, uu of n (its children already added), and its
    articulated inertia and bias added to its parent's."""
    A, B, C = n.IA
    A, B, C = ik.sym_kept(A), ik.kept(B), ik.sym_kept(C)
    pw, pv = ik.kept(n.fw), ik.kept(n.fv)
    nj = n.So.shape[1]
    cw, cv = n.c
    if nj:
        sw, sv = n.So[:3, :], n.So[3:, :]
        Uw, Uv = ik.kept(A * sw + B * sv), ik.kept(B.T * sw + C * sv)
        D = ik.sym_kept(sw.T * Uw + sv.T * Uv)
        _check_moved(n, D)
        n.uu = uu = ik.kept(-(sw.T * pw + sv.T * pv))
        n.U = (Uw, Uv)
        if n.parent is None and nj > 1:
            # a free root: D^-1 only in u' = D^-1 (uu - U^T a'), a solve
            n.Dinv, n.D = None, D
            return
        n.Dinv = Dinv = _inv_small(D, ik)
        if n.parent is None:
            return              # the forward pass's U, D^-1, uu only
        UDw, UDv = ik.kept(Uw * Dinv), ik.kept(Uv * Dinv)
        Aa, Ba, Ca = (sm.Matrix(x) for x in (A - UDw * Uw.T, B - UDw * Uv.T, C - UDv * Uv.T))
        gw, gv = UDw * uu, UDv * uu
    else:
        if n.parent is None:
            return
        Aa, Ba, Ca = sm.Matrix(A), sm.Matrix(B), sm.Matrix(C)
        gw, gv = sm.zeros(3, 1), sm.zeros(3, 1)
    # I^a S = 0 and S^T p^a = 0: along a joint axis that is a body axis (S a
    # unit column) the articulated inertia's row and column and the bias's
    # entry are zero; written as zeros, not as x - x
    axes = _unit_axes(n.So)
    for k in axes:
        if k < 3:
            Aa[k, :], Aa[:, k], Ba[k, :] = sm.zeros(1, 3), sm.zeros(3, 1), sm.zeros(1, 3)
        else:
            Ca[k - 3, :], Ca[:, k - 3], Ba[:, k - 3] = sm.zeros(1, 3), sm.zeros(3, 1), sm.zeros(3, 1)
    Aa, Ba, Ca = ik.sym_kept(Aa), ik.kept(Ba), ik.sym_kept(Ca)
    pw, pv = sm.Matrix(pw + Aa * cw + Ba * cv + gw), sm.Matrix(pv + Ba.T * cw + Ca * cv + gv)
    for k in axes:
        if k < 3:
            pw[k] = 0
        else:
            pv[k - 3] = 0
    pw, pv = ik.kept(pw), ik.kept(pv)
    # X^T (.) X: into the parent's axes (E^T . E), then shifted by p
    E, ET = n.E, n.E.T
    Ap = ik.sym_kept(ET * ik.kept(Aa * E))
    Bp = ik.kept(ET * ik.kept(Ba * E))
    Cp = ik.sym_kept(ET * ik.kept(Ca * E))
    pwp, pvp = ik.kept(ET * pw), ik.kept(ET * pv)
    rx = skew(n.p)
    P, RC = ik.kept(Bp * rx), ik.kept(rx * Cp)
    a, b, c = n.parent.IA
    n.parent.IA = (a + Ap - P - P.T - RC * rx, b + Bp + RC, c + Cp)
    n.parent.fw = n.parent.fw + pwp + cross(n.p, pvp)
    n.parent.fv = n.parent.fv + pvp


def _check_moved(n, D):
    """A ModelError naming the body when its joint moves no mass or
    inertia (D = S^T IA S has a zero on its diagonal: a massless body, and
    nothing beyond it that the joint's motion moves), whose accelerations
    the equations then do not determine (1 / 0 in the recursion)."""
    zero = [n.joint.speeds[k] for k in range(D.shape[0]) if D[k, k] == 0]
    if zero:
        raise massless_joint_error(n.joint, zero)


def _inv_small(D, ik):
    """The inverse of a small symmetric matrix of kept entries, by its
    adjugate over placeholder symbols (sympy's inv would test the kept
    entries for zero, a walk down the whole graph)."""
    k = D.shape[0]
    if k == 1:
        return sm.Matrix([[ik.keep(1 / D[0, 0])]])
    if k > 3:
        return _inv_ldlt(D, ik)
    X = sm.Matrix(k, k, lambda i, j: sm.Symbol(f"_D{min(i, j)}_{max(i, j)}"))
    sub = {X[i, j]: D[i, j] for i in range(k) for j in range(k)}
    idet = ik.keep(1 / ik.keep(X.det(method="berkowitz").xreplace(sub)))
    adj = X.adjugate(method="berkowitz").xreplace(sub)
    return ik.sym_kept(adj * idet)


def _inv_ldlt(D, ik):
    """The inverse of a symmetric positive definite matrix of kept entries
    (a free joint's 6 x 6) through its LDL^T factors, each entry one kept
    node: O(k^3) nodes, where the adjugate's cofactors grow factorially."""
    k = D.shape[0]
    L, dinv = _ldl(D, ik)
    # L^-1, unit lower triangular, by forward substitution
    Li = sm.eye(k)
    for i in range(k):
        for j in range(i):
            Li[i, j] = ik.keep(-sm.Add(*[L[i, m] * Li[m, j] for m in range(j, i)]))
    low = {(i, j): ik.keep(sm.Add(*[Li[m, i] * dinv[m] * Li[m, j] for m in range(max(i, j), k)]))
           for i in range(k) for j in range(i + 1)}
    return sm.Matrix(k, k, lambda i, j: low[max(i, j), min(i, j)])


def _ldl(D, ik):
    """(L, [1 / d]) of D = L diag(d) L^T, D symmetric positive definite
    (kept entries), each entry one kept node: O(k^3) nodes, where an
    adjugate's cofactors grow factorially."""
    k = D.shape[0]
    L, d, di = sm.eye(k), [None] * k, [None] * k
    for j in range(k):
        d[j] = ik.keep(D[j, j] - sm.Add(*[L[j, m]**2 * d[m] for m in range(j)]))
        di[j] = ik.keep(1 / d[j])
        for i in range(j + 1, k):
            L[i, j] = ik.keep((D[i, j] - sm.Add(*[L[i, m] * L[j, m] * d[m] for m in range(j)]))
                              * di[j])
    return L, di


def _solve_spd(D, b, ik):
    """x of D x = b, D symmetric positive definite (kept entries), through
    its LDL^T factors, each entry one kept node."""
    k = D.shape[0]
    L, di = _ldl(D, ik)
    y = [None] * k
    for i in range(k):
        y[i] = ik.keep(b[i] - sm.Add(*[L[i, m] * y[m] for m in range(i)]))
    x = [None] * k
    for i in reversed(range(k)):
        x[i] = ik.keep(y[i] * di[i] - sm.Add(*[L[m, i] * x[m] for m in range(i + 1, k)]))
    return sm.Matrix(x)


def _unit_axes(S):
    """The rows k of S's columns that are signed unit vectors e_k (its only
    nonzero entry +-1): the joint's axes that are body axes."""
    out = []
    for j in range(S.shape[1]):
        nz = [k for k in range(6) if S[k, j] != 0]
        if len(nz) == 1 and S[nz[0], j] in (1, -1):
            out.append(nz[0])
    return out


def _outward(n, a0, ud, ik):
    """n's u'_j into ud and its acceleration (n.c becomes a), outward."""
    cw, cv = n.c
    if n.parent is None:
        aw, av = cw, cv
        if a0 is not None:
            av = av + n.E * a0
    else:
        pw, pv = n.parent.c
        aw = n.E * pw + cw
        av = n.E * (pv + cross(pw, n.p)) + cv
    aw, av = ik.kept(aw), ik.kept(av)
    if n.So.shape[1]:
        Uw, Uv = n.U
        rhs = n.uu - (Uw.T * aw + Uv.T * av)
        uj = ik.kept(n.Dinv * rhs if n.Dinv is not None else _solve_spd(n.D, rhs, ik))
        for k, s in enumerate(n.joint.speeds):
            ud[n.speed_idx[k]] = uj[k]
        aw = ik.kept(aw + n.So[:3, :] * uj)
        av = ik.kept(av + n.So[3:, :] * uj)
    n.c = (aw, av)
