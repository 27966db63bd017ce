"""Equations of motion of a sympy ``System``'s joint tree by recursive
algorithms (issue 37), without ``KanesMethod.kanes_equations`` or
``System.form_eoms``.

``Model.from_system(system, formulation="recursive")`` lands here. The tree is
read from the System's joints: each joint gives its child body a parent body,
and the body whose frame is the System's frame is the root. Per joint, from
sympy's own joint kinematics, a few small expressions:

- ``E``: the direction cosines from the parent's axes to the child's
  (``child.frame.dcm(parent.frame)``); the joint vector from the parent's mass
  centre to the child's, as a part in the parent's axes (to the child point)
  plus a constant part in the child's axes;
- the joint's relative motion ``[w_rel; v_rel] = S u_j`` in the child's axes
  (the child frame's angular velocity in the parent's, and the derivative in
  the parent frame of the joint vector), ``S`` its Jacobian in the joint's
  speeds, and the velocity-product part ``dS/dt u_j``.

CRBA and RNEA run in the inertial frame's axes at each body's mass centre:
each body's orientation is kept as ``A Rot(k, theta) B``, and a joint turning
about its parent's axis adds its angle to ``theta``. A chain of parallel pins
thus holds ``cos(q1 + ... + qk)``, not a product of k rotation matrices, and
each body's rotation is a few kept nodes. The mass matrix comes from the composite rigid body algorithm
(each subtree's mass, first moment and inertia about its root's mass centre,
shifted by joint vectors; a joint's column ``Ic s`` carried up the tree), the
forcing from recursive Newton-Euler with ``u' = 0`` (velocities and
velocity-product accelerations outward, each body's ``m a - F_ext`` and
``I alpha + w x I w - T_ext`` inward, projected on ``S``). ``M u' = f`` are
then Kane's equations of the tree; the kinematics are the System's own
``kdes``, and the result goes to :meth:`gen.Model.from_matrices` as any model
does, so rhs, linearization, derivative kernels and every backend follow.

For an open tree (no constraints, no ``hybrid``) ``Model.from_system`` takes
instead ``u'`` by the articulated body algorithm
(:func:`gen.intake.aba.accelerations_of_tree`, in each body's own axes at its
joint, on the tree, joint kinematics and loads' places read here) and hands the pipeline ``M = I``, ``f = u'``: measured on the n-link pendulum,
CRBA's n(n+1)/2 entries of M made the n = 50 rhs kernel 3629 temporaries and
its C compile 19 CPU-s (rhs 31 us), ABA's u' is a few dozen temporaries per
body (n = 50: build 6 s, rhs 2.2 us). The identity costs nothing at run time
(its unrolled LDL^T over a diagonal of ones is constant-folded), linearization
and derivative kernels differentiate the same graph. ``sim.mass_matrix`` of
such a model is the identity; the physical M and f are
:func:`equations_of_tree`'s. With constraints (the multiplier solve needs the
true M) or ``hybrid`` impacts (solved with M), CRBA + RNEA as above.

Nothing is expanded or simplified: each body's quantities are kept as shared
opaque nodes (a graph linear in the bodies, equal nodes one object), every walk
of the pipeline visits a shared node once, and gen.plan.ir writes each node as one
temporary, in order (``_kept_program``). The nodes are one build's: an
:class:`gen.sym.intern.Interner` made for the build (``Model.from_system``
makes one per call) and passed down its functions; nothing is kept between
builds or shared with a build in another thread, and sympy's own cache is
left alone (nodes of different builds never compare equal, so an earlier
build's nodes left in it are never walked).

Taken: trees of ``PinJoint``, ``PrismaticJoint``, ``CylindricalJoint``,
``PlanarJoint``, ``SphericalJoint`` and ``WeldJoint`` between rigid bodies
(and of any joint with a ``motion_subspace()`` method returning its ``S`` and
velocity-product part in the child's axes: the quaternion ``FreeJoint`` and
``BallJoint`` of :mod:`gen.intake.robots.joints`),
with forces on points and torques on frames the tree knows (gravity from
``apply_uniform_gravity``, loads, actuators), and the System's holonomic and
nonholonomic constraints (loop closures) with their dependent coordinates
and speeds, handed to the runtime's constraint machinery as a Kane model's
(:func:`constraints_of_tree`). Refused with a :class:`gen.ModelError`
naming what: auxiliary speeds, particles, other joint classes, explicitly
time-dependent joints, bodies not joined to the System's frame, a body that
is the child of two joints, loads on unknown points or frames.
"""
from __future__ import annotations

import random

import sympy as sm
import sympy.physics.mechanics as me
from sympy.core.function import AppliedUndef

from ..core.errors import ModelError
from ..sym.intern import Interner
from .sympy_compat import time_symbol

__all__ = ["equations_of_tree", "constraints_of_tree", "Tree", "Places", "joint_kinematics",
           "same_for_all",
           "check_joints_move", "massless_joint_error",
           "SUPPORTED_JOINTS"]

SUPPORTED_JOINTS = ("PinJoint", "PrismaticJoint", "CylindricalJoint", "PlanarJoint",
                    "SphericalJoint", "WeldJoint")

_T = time_symbol()


def name_of(obj):
    return getattr(obj, "name", None) or str(obj)


def cross(a, b):
    return sm.Matrix([a[1] * b[2] - a[2] * b[1],
                      a[2] * b[0] - a[0] * b[2],
                      a[0] * b[1] - a[1] * b[0]])


def col(xs):
    xs = list(xs)
    return sm.Matrix(xs) if xs else sm.zeros(0, 1)


def skew(a):
    return sm.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def _is_zero(e):
    e = sm.expand(e)
    if e == 0:
        return True
    return sm.simplify(e) == 0


class _Body:
    __slots__ = ("body", "joint", "parent", "children", "E", "r", "S", "rel_bias",
                 "speed_idx", "w", "al", "a", "F", "N", "Ic", "depth", "Ftot", "Ntot",
                 "rep", "R", "Sw", "rw", "Iw", "r_pp", "r_cc", "mt", "h", "J", "cw", "cv",
                 "IA", "pA", "U", "D", "Dinv", "uu", "p", "So", "cJ", "v", "c", "fw", "fv", "Rn")

    def __init__(self, body, joint, parent):
        self.body, self.joint, self.parent = body, joint, parent
        self.children = []


class Tree:
    """The System's joint tree, checked, in an order parents first."""

    def __init__(self, system):
        if not isinstance(system, me.System):
            raise ModelError(
                f"formulation='recursive' needs a sympy System, got {type(system).__name__}")
        self.system = system
        self.N = system.frame
        if len(system.u_aux):
            raise ModelError(
                f"formulation='recursive' does not take auxiliary speeds (the System has "
                f"{list(system.u_aux)}): use formulation='kane'")
        nh, nn = len(system.holonomic_constraints), len(system.nonholonomic_constraints)
        if len(system.q_dep) != nh:
            raise ModelError(
                f"the System has {nh} holonomic constraint(s) and {len(system.q_dep)} "
                "dependent coordinate(s) (q_dep): formulation='recursive' needs one "
                "dependent coordinate per holonomic constraint")
        if len(system.u_dep) != nh + nn:
            raise ModelError(
                f"the System has {nh} holonomic and {nn} nonholonomic constraint(s) and "
                f"{len(system.u_dep)} dependent speed(s) (u_dep): formulation='recursive' "
                "needs one dependent speed per constraint")
        self.q = list(system.q)
        self.u = list(system.u)
        child_of = {}
        for j in system.joints:
            kind = type(j).__name__
            if kind not in SUPPORTED_JOINTS and not callable(getattr(j, "motion_subspace", None)):
                raise ModelError(
                    f"joint {name_of(j)!r} is a {kind}: formulation='recursive' takes "
                    f"{', '.join(SUPPORTED_JOINTS)}")
            for b in (j.parent, j.child):
                if not isinstance(b, me.RigidBody):
                    raise ModelError(
                        f"body {name_of(b)!r} of joint {name_of(j)!r} is a {type(b).__name__}: "
                        "formulation='recursive' takes rigid bodies")
            if j.child in child_of:
                raise ModelError(
                    f"body {name_of(j.child)!r} is the child of joints {name_of(child_of[j.child])!r} "
                    f"and {name_of(j)!r}: formulation='recursive' takes the joints of a tree; "
                    "close a loop with holonomic constraints on the tree instead "
                    "(System.add_holonomic_constraints, with the dependent coordinates "
                    "and speeds in q_dep and u_dep)")
            child_of[j.child] = j
        # the root: the body (or bodies) whose frame is the System's frame
        self.ground = set()
        for j in system.joints:
            if j.parent not in child_of:
                if j.parent.frame != self.N:
                    raise ModelError(
                        f"body {name_of(j.parent)!r} (parent of joint {name_of(j)!r}) is not "
                        f"connected to the tree: it is no joint's child and its frame "
                        f"{j.parent.frame.name!r} is not the System's frame {self.N.name!r}")
                self.ground.add(j.parent)
        for b in system.bodies:
            if b not in child_of and b not in self.ground and not (
                    isinstance(b, me.RigidBody) and b.frame == self.N):
                raise ModelError(
                    f"body {name_of(b)!r} is not connected to the tree: no joint has it as "
                    "its child (formulation='recursive' needs every body joined, through "
                    "joints, to the System's frame)")
        # parents first
        nodes, order = {}, []
        pending = list(child_of.items())
        while pending:
            rest = []
            for child, j in pending:
                if j.parent in self.ground:
                    parent = None
                elif j.parent in nodes:
                    parent = nodes[j.parent]
                else:
                    rest.append((child, j))
                    continue
                n = _Body(child, j, parent)
                n.depth = 0 if parent is None else parent.depth + 1
                if parent is not None:
                    parent.children.append(n)
                nodes[child] = n
                order.append(n)
            if len(rest) == len(pending):     # pragma: no cover - cycles are refused above
                raise ModelError(f"joints {[name_of(j) for _, j in rest]} do not form a tree")
            pending = rest
        self.nodes, self.order = nodes, order
        # joint speeds -> positions in system.u
        uidx = {s: i for i, s in enumerate(self.u)}
        for n in order:
            try:
                n.speed_idx = [uidx[s] for s in n.joint.speeds]
            except KeyError as e:
                raise ModelError(f"speed {e.args[0]} of joint {name_of(n.joint)!r} is not one "
                                 "of the System's speeds") from None
        self._qdot_map()

    def _qdot_map(self):
        """q' in q and u, from the System's kinematic equations (solved per
        block of rows that share coordinates)."""
        kd = sm.Matrix(self.system.kdes)
        qd = [qi.diff(_T) for qi in self.q]
        if kd.shape[0] != len(qd):
            raise ModelError(f"the System has {kd.shape[0]} kinematic equation(s) for "
                             f"{len(qd)} coordinate(s)")
        self.kdes = kd
        # the coefficients of q' by row, over plain symbols and only for the
        # q' a row holds (a Jacobian in every q' of every row is quadratic
        # in n, each entry a derivative by a Derivative)
        D = [sm.Dummy(f"qd{i}") for i in range(len(qd))]
        kdD = kd.xreplace(dict(zip(qd, D)))
        K = sm.zeros(len(qd), len(qd))
        where = {d: k for k, d in enumerate(D)}
        for i in range(len(qd)):
            for d in kdD[i].free_symbols & set(D):
                K[i, where[d]] = kdD[i].diff(d)
        rest = kd.xreplace({x: 0 for x in qd})
        if any(K[i, k] != 0 for i in range(len(qd)) for k in range(len(qd)) if i != k):
            sol = K.LUsolve(-rest)
        else:
            if any(K[i, i] == 0 for i in range(len(qd))):
                raise ModelError("the System's kinematic equations do not determine every q'")
            sol = [-rest[i] / K[i, i] for i in range(len(qd))]
        self.qdot = dict(zip(qd, sol))


def equations_of_tree(system, interner=None):
    """M, f, q, u, kinematics of a System's joint tree by CRBA and RNEA (see
    the module docstring).

    Parameters
    ----------
    system : sympy System
    interner : gen.sym.intern.Interner, optional
        The build's interner (its opaque nodes); a new one when None.

    Returns
    -------
    (M, f, q, u, kdes) : sympy Matrix (nu, nu), Matrix (nu, 1), list, list, Matrix (nq, 1)
        ``M u' = f`` in the System's speed order, and the System's kinematic
        equations (``kdes = 0``). With constraints, M and f are the tree's
        equations for all its speeds (independent, then dependent: the
        System's order), without the constraint forces, as a Kane model's
        are; see :func:`constraints_of_tree`.
    """
    ik = Interner() if interner is None else interner
    tree = _walk(system, ik)
    nu = len(tree.u)
    zero = sm.zeros(3, 1)
    for n in tree.order:
        al_p, a_p = (zero, zero) if n.parent is None else (n.parent.al, n.parent.a)
        n.al, n.a = ik.kept(al_p + n.cw), ik.kept(a_p + cross(al_p, n.rw) + n.cv)
    # forces in: each body's F - m a and T - I al - w x I w, plus its
    # children's (formed with their signs: negating a large sum would make
    # sympy distribute the -1 over every term)
    f = sm.zeros(nu, 1)
    for n in reversed(tree.order):
        b = n.body
        Fi = n.F - b.mass * n.a
        Ni = n.N + (-n.Iw) * n.al + cross(n.Iw * n.w, n.w)
        for c in n.children:
            Fi += c.Ftot
            Ni += c.Ntot + cross(c.rw, c.Ftot)
        n.Ftot, n.Ntot = Fi, Ni = ik.kept(Fi), ik.kept(Ni)
        tau = n.Sw.T * sm.Matrix.vstack(Ni, Fi)
        for k, idx in enumerate(n.speed_idx):
            f[idx] = tau[k]

    # ---- CRBA: each subtree's mass, first moment h and inertia J about the
    # mass centre of its root body (inertial axes; shifted by the joint
    # vectors, never by absolute positions); a joint's column F = Ic s goes up
    # the tree as the force of the backward pass does
    M = sm.zeros(nu, nu)
    for n in reversed(tree.order):
        mt, h, J = n.body.mass, sm.zeros(3, 1), n.Iw
        for c in n.children:
            d = c.rw
            dt_, ht, ndt = skew(d), skew(c.h), skew(-d)
            mt += c.mt
            h += c.h + c.mt * d
            J += c.J + (ht * ndt + ndt * ht) + c.mt * (dt_ * ndt)
        n.mt, n.h, n.J = ik.keep(mt), ik.kept(h), ik.kept(J)
    for n in tree.order:
        nj = n.Sw.shape[1]
        if not nj:
            continue
        ht = skew(n.h)
        sw, sv = n.Sw[:3, :], n.Sw[3:, :]
        L = ik.kept(n.J * sw + ht * sv)
        P = ik.kept(n.mt * sv + sm.Matrix.hstack(*[cross(sw[:, k], n.h) for k in range(nj)]))
        m = n
        while m is not None:
            if m is not n:
                L = ik.kept(L + sm.Matrix.hstack(*[cross(prev.rw, P[:, k]) for k in range(nj)]))
            blk = m.Sw.T * sm.Matrix.vstack(L, P)    # rows: m's speeds, columns: n's
            for a_, ia in enumerate(m.speed_idx):
                for b_, ib in enumerate(n.speed_idx):
                    M[ia, ib] = blk[a_, b_]
                    M[ib, ia] = blk[a_, b_]
            prev, m = m, m.parent
    return M, f, tree.q, tree.u, tree.kdes


def check_joints_move(system, M, speeds):
    """For CRBA's M of an open tree: a ModelError naming the body when the
    rows of M of one of its joint's speeds are all zero (the same refusal
    as the articulated body algorithm's)."""
    idx = {s: i for i, s in enumerate(speeds)}
    n = len(speeds)
    for j in system.joints:
        zero = [s for s in j.speeds if s in idx
                and all(M[idx[s], k] == 0 for k in range(n))]
        if zero:
            raise massless_joint_error(j, zero)


def massless_joint_error(joint, speeds):
    """The ModelError of a joint that moves no mass or inertia: its child
    body named, and the speeds whose accelerations are undetermined."""
    return ModelError(
        f"body {name_of(joint.child)!r} has no mass or inertia that its joint "
        f"{name_of(joint)!r} moves (nor has any body beyond it), so the equations do "
        f"not determine the acceleration of {', '.join(str(s.func) for s in speeds)}: "
        "give it a mass or inertia, or weld it to its parent (WeldJoint)")


def _walk(system, ik):
    """The checked tree with, per body, its joint's kinematics, external
    loads, orientation R, and (inertial axes, at the mass centres) S, the
    joint vector, velocities, velocity-product accelerations (absolute: al,
    a; the joint's own share: cw, cv) and central inertia: what CRBA/RNEA
    (equations_of_tree) start from. ik: the build's Interner (tree.ik)."""
    tree = Tree(system)
    tree.ik = ik
    joint_kinematics(tree)
    _common_axes(tree)
    places = Places(tree, system)
    # each body's axes in the inertial frame's: R = A Rot(k, theta) B, the
    # angles of consecutive joints about one axis summed (a chain of parallel
    # pins keeps cos(q1 + ... + qn), not a product of n rotations)
    for n in tree.order:
        _orientation(n, tree)
    _external_loads(tree, system, places)
    _velocities(tree)
    return tree


def _common_axes(tree):
    """The axes the recursions run in: the inertial frame's, or, for a tree
    whose one root body moves on a free joint (a joint with its own
    six-column ``motion_subspace``, from the System's frame), that body's
    own axes. Every equation of the recursions is a vector equation, true
    in any axes; in the root's axes the limbs' orientations are those of a
    fixed-base robot (constant rotations and joint angles) instead of
    products with the root's quaternion, and only the loads given in the
    inertial axes (gravity) are turned, by ``tree.Rt`` (inertial -> root
    axes, kept nodes). ``tree.Rt`` is None for the inertial axes."""
    tree.Rt, tree.float_root = None, None
    roots = [n for n in tree.order if n.parent is None]
    if len(roots) == 1:
        n = roots[0]
        if callable(getattr(n.joint, "motion_subspace", None)) and n.S.shape[1] == 6 \
                and n.joint.parent.frame == tree.N:
            tree.float_root = n
            tree.Rt = tree.ik.kept(n.E)       # child <- parent = root <- inertial


def joint_kinematics(tree):
    """Per joint: E, the joint vector's parts r_pp and r_cc, S and the
    velocity-product part of d/dt [w_rel; v_rel] (rel_bias), in the child's
    axes."""
    qset = set(tree.q)
    udots = [s.diff(_T) for s in tree.u]
    for n in tree.order:
        j, child, parent = n.joint, n.body, n.joint.parent
        try:
            n.E = sm.Matrix(child.frame.dcm(parent.frame))
            # C_child - C_parent = r_pp (parent's axes) + r_cc (child's axes)
            n.r_pp = j.child_point.pos_from(parent.masscenter).to_matrix(parent.frame)
            n.r_cc = child.masscenter.pos_from(j.child_point).to_matrix(child.frame)
            w_rel = child.frame.ang_vel_in(parent.frame).to_matrix(child.frame)
        except ValueError as e:
            raise ModelError(f"joint {name_of(j)!r}: sympy cannot relate body "
                             f"{name_of(child)!r} to body {name_of(parent)!r} ({e})") from None
        if any(e.has(_T) for e in n.r_cc):
            raise ModelError(f"joint {name_of(j)!r}: its child point moves in body "
                             f"{name_of(child)!r}")
        if callable(getattr(j, "motion_subspace", None)):
            # a joint that gives its own S and velocity-product part (the
            # quaternion joints of gen.intake.robots.joints)
            n.S, n.rel_bias = j.motion_subspace()
            continue
        # d/dt in the parent frame of C_child - C_parent, in the child's axes
        v_rel = n.E * n.r_pp.diff(_T) + cross(w_rel, n.r_cc)
        rel = sm.Matrix.vstack(w_rel, v_rel).xreplace(tree.qdot)
        S = rel.jacobian(list(j.speeds)) if len(j.speeds) else sm.zeros(6, 0)
        resid = rel - S * col(j.speeds)
        if not all(_is_zero(e) for e in resid):
            raise ModelError(
                f"joint {name_of(j)!r}: the child's motion relative to the parent is not "
                "linear and homogeneous in the joint's speeds (an explicitly time-"
                "dependent joint): formulation='recursive' does not take it")
        if any(e.has(*udots) for e in S):
            raise ModelError(f"joint {name_of(j)!r}: the joint's motion holds speed derivatives")
        qs = sorted((S.atoms(sm.Function) & qset), key=sm.default_sort_key)
        if qs:
            dq = sm.Matrix([tree.qdot[x.diff(_T)] for x in qs])
            # (dS/dt) u_j: the part of d/dt [w_rel; v_rel] (child's axes) without u'
            n.rel_bias = (S * col(j.speeds)).jacobian(qs) * dq
        else:
            n.rel_bias = None
        n.S = S


class Places:
    """Which body a load's point or frame belongs to (None: the ground), and
    a vector in the inertial axes."""

    def __init__(self, tree, system):
        self.tree = tree
        self.points, self.frames = {}, {}
        for n in tree.order:
            self.points[n.body.masscenter] = n.body
            self.frames[n.body.frame] = n.body
        self.ground_frames = {tree.N} | {g.frame for g in tree.ground}
        self.ground_points = {g.masscenter for g in tree.ground} | {system.fixed_point}
        for j in system.joints:
            for pt, fr, b in ((j.child_point, j.child_interframe, j.child),
                              (j.parent_point, j.parent_interframe, j.parent)):
                if b in tree.ground:
                    self.ground_points.add(pt)
                    self.ground_frames.add(fr)
                else:
                    self.points.setdefault(pt, b)
                    self.frames.setdefault(fr, b)

    def body_of_point(self, pt, what):
        if pt in self.points:
            return self.points[pt]
        if pt in self.ground_points:
            return None
        for n in self.tree.order:
            try:
                rb = pt.pos_from(n.body.masscenter).to_matrix(n.body.frame)
            except ValueError:
                continue
            if not any(e.has(_T) for e in rb):
                self.points[pt] = n.body
                return n.body
        raise ModelError(
            f"{what} acts on point {name_of(pt)!r}, which the joint tree does not know: "
            "not a body's mass centre, a joint's point, or a point fixed in a body")

    def body_of_frame(self, fr, what):
        if fr in self.frames:
            return self.frames[fr]
        if fr in self.ground_frames:
            return None
        for n in self.tree.order:
            try:
                d = fr.dcm(n.body.frame)
            except ValueError:
                continue
            if not any(e.has(_T) for e in d):
                self.frames[fr] = n.body
                return n.body
        raise ModelError(
            f"{what} acts on frame {name_of(fr)!r}, which the joint tree does not know: "
            "not a body's frame, a joint's frame, or a frame fixed in a body")

    def in_world(self, vec):
        """vec's components in the inertial axes (through the bodies' R)."""
        N, out, inertial = self.tree.N, sm.zeros(3, 1), sm.zeros(3, 1)
        for comp, frame in vec.args:
            comp = sm.Matrix(comp)
            if frame == N:
                inertial += comp
            elif frame in self.frames and frame not in self.ground_frames:
                b = self.tree.nodes[self.frames[frame]]
                if frame != b.body.frame:
                    comp = me.Vector([(comp, frame)]).to_matrix(b.body.frame)
                out += b.R * comp
            else:
                inertial += me.Vector([(comp, frame)]).to_matrix(N)
        # the recursions' axes (_common_axes)
        return out + (inertial if self.tree.Rt is None else self.tree.Rt * inertial)


def _external_loads(tree, system, places):
    """Per body, the external force F and torque N (about its mass centre),
    in the inertial axes: the System's loads and its actuators' loads."""
    for n in tree.order:
        n.F, n.N = sm.zeros(3, 1), sm.zeros(3, 1)
    loads = list(system.loads)
    for act in system.actuators:
        loads.extend(act.to_loads())
    for ld in loads:
        if isinstance(ld, me.Force):
            b = places.body_of_point(ld.point, f"force {ld}")
            if b is None:
                continue
            n = tree.nodes[b]
            Fw = places.in_world(ld.vector)
            n.F += Fw
            if ld.point != b.masscenter:
                rb = ld.point.pos_from(b.masscenter).to_matrix(b.frame)
                n.N += cross(n.R * rb, Fw)
        elif isinstance(ld, me.Torque):
            b = places.body_of_frame(ld.frame, f"torque {ld}")
            if b is None:
                continue
            n = tree.nodes[b]
            n.N += places.in_world(ld.vector)
        else:      # pragma: no cover - sympy's loads are Force or Torque
            raise ModelError(f"load {ld!r} is neither a Force nor a Torque")


def _velocities(tree):
    """RNEA with u' = 0, in the inertial frame's axes, at the mass centres:
    per body, S in those axes (Sw), the joint vector (rw), the angular
    velocity (w), the joint's share of the velocity-product accelerations
    (cw, cv) and the central inertia (Iw), outwards."""
    ik = tree.ik
    zero = sm.zeros(3, 1)
    for n in tree.order:
        R = n.R
        n.Sw = ik.kept(sm.Matrix.vstack(R * n.S[:3, :], R * n.S[3:, :])) if n.S.shape[1] \
            else sm.zeros(6, 0)
        rel = ik.kept(n.Sw * col(n.joint.speeds))
        w_rel, v_rel = rel[:3, :], rel[3:, :]
        if n.parent is None:
            w_p, Rp = zero, (sm.eye(3) if tree.Rt is None else tree.Rt)
        else:
            w_p, Rp = n.parent.w, n.parent.R
        r = ik.kept(Rp * n.r_pp + R * n.r_cc)
        n.rw = r
        n.w = ik.kept(w_p + w_rel)
        # the joint's share of the velocity-product accelerations: the
        # body's (al, a) = the parent's carried to it + (cw, cv) at u' = 0
        cw = cross(w_p, w_rel)
        cv = cross(w_p, cross(w_p, r)) + cross(2 * w_p, v_rel) + cross(w_rel, v_rel)
        if n.rel_bias is not None:
            cw += R * n.rel_bias[:3, :]
            cv += R * n.rel_bias[3:, :]
        n.cw, n.cv = ik.kept(cw), ik.kept(cv)
        b = n.body
        # R I first, one node per entry: R (I R^T) as one product would
        # repeat each column of R I in three entries
        n.Iw = ik.sym_kept(ik.kept(R * inertia_matrix(b)) * R.T)


def inertia_matrix(body):
    """The body's central inertia in its own axes: read off the dyadic's
    terms when they are all in those axes (sympy's to_matrix expresses
    each of the nine components through dot products, the slowest step of
    the build); to_matrix otherwise."""
    frame, out = body.frame, sm.zeros(3, 3)
    for coef, v1, v2 in body.central_inertia.args:
        idx = []
        for v in (v1, v2):
            if len(v.args) != 1 or v.args[0][1] != frame:
                return body.central_inertia.to_matrix(frame)
            comps = list(v.args[0][0])
            nz = [i for i, c in enumerate(comps) if c != 0]
            if len(nz) != 1 or comps[nz[0]] != 1:
                return body.central_inertia.to_matrix(frame)
            idx.append(nz[0])
        out[idx[0], idx[1]] += coef
    return out


def constraints_of_tree(system):
    """The System's loop closures and other constraints, for the runtime's
    constraint machinery (dependent coordinates and speeds, the constrained
    solve, projection), as a Kane model carries them.

    Returns
    -------
    None, or (fc, A, b, nq_dep, nu_dep)
        ``fc(q) = 0`` (the holonomic constraints), ``A u + b = 0`` (the
        velocity constraints: the holonomic ones differentiated and the
        nonholonomic ones, q' replaced by the kinematic equations' solution),
        and the numbers of dependent coordinates and speeds (last in the
        System's q and u).
    """
    if not isinstance(system, me.System):
        Tree(system)           # the error naming what it got
    nh, nn = len(system.holonomic_constraints), len(system.nonholonomic_constraints)
    if not nh and not nn:
        return None
    tree = Tree(system)        # the same checks and q' map as equations_of_tree
    vc = sm.Matrix(system.velocity_constraints).xreplace(tree.qdot)
    A = vc.jacobian(tree.u)
    b = vc.xreplace({s: 0 for s in tree.u})
    fc = sm.Matrix(system.holonomic_constraints) if nh else sm.zeros(0, 1)
    if any(e.has(*[s.diff(_T) for s in tree.u]) for e in list(A) + list(b)):
        raise ModelError("the System's velocity constraints hold speed derivatives")
    return fc, A, b, len(system.q_dep), len(system.u_dep)


def _rot(k, th, ik=None):
    """Rotation by th about the unit axis k (components in the frame's axes);
    with the build's interner ik, its sine and cosine kept nodes (each one
    temporary of the C: a C compiler without -fno-math-errno calls sin and
    cos as often as the code names them)."""
    K = skew(k)
    s, c = sm.sin(th), sm.cos(th)
    if ik is not None:
        s, c = ik.keep(s), ik.keep(c)
    return sm.eye(3) + s * K + (1 - c) * (K * K)


def _orientation(n, tree):
    """n.R (body axes -> inertial axes) as A Rot(k, theta) B, sharing the
    angle with the parent when the joint turns about the parent's axis."""
    ik = tree.ik
    if n is tree.float_root:
        # the recursions' axes are this body's (_common_axes)
        n.rep = (sm.eye(3), None, sm.S.Zero, sm.eye(3))
        n.R = sm.eye(3)
        return
    if n.parent is None:
        A, k, th, B = sm.eye(3), None, sm.S.Zero, sm.eye(3)
        if n.joint.parent.frame != tree.N:     # pragma: no cover - refused in Tree
            A = sm.Matrix(tree.N.dcm(n.joint.parent.frame))
    else:
        A, k, th, B = n.parent.rep
    ET = n.E.T                                  # parent axes <- child axes
    wq = n.S[:3, :]                             # w_rel (child axes) = wq u_j
    qj = [x for x in n.joint.coordinates]
    rep = None
    if not any(e.has(*qj) for e in ET) if qj else True:
        # no rotation in this joint: a constant ET
        if all(e == 0 for e in wq):
            rep = (A, k, th, B * ET)
    elif len(qj) >= 1 and wq.shape[1] >= 1:
        # one rotating coordinate about a constant axis?
        rot = [x for x in qj if any(e.has(x) for e in ET)]
        cols = [c for c in range(wq.shape[1]) if any(e != 0 for e in wq[:, c])]
        if len(rot) == 1 and len(cols) == 1 and not any(e.has(_T) for e in wq[:, cols[0]]):
            q = rot[0]
            E0T = ET.xreplace({q: 0})
            kp = E0T * wq[:, cols[0]]           # the axis in the parent's axes
            if same_for_all(ET, _rot(kp, q) * E0T, [q]):
                if k is not None and _same_vec(B * kp, k):
                    rep = (A, k, th + q, B * E0T)
                else:
                    Rp = A * (_rot(k, th, ik) if k is not None else sm.eye(3)) * B
                    rep = (Rp, kp, q, E0T)
    if rep is None:
        Rp = A * (_rot(k, th, ik) if k is not None else sm.eye(3)) * B
        rep = (Rp * ET, None, sm.S.Zero, sm.eye(3))
    A, k, th, B = rep
    n.rep = rep = (ik.kept(A), k, ik.keep(th), B)
    A, k, th, B = rep
    n.R = ik.kept(ik.kept(A * _rot(k, th, ik)) * B if k is not None else A * B)


def same_for_all(X, Y, qs):
    """X == Y for every value of the coordinates qs (numerically at a few
    points, every other symbol and function of time given random values:
    both are small matrices of constants, sines and cosines)."""
    rnd = random.Random(7)
    free = sorted((X.free_symbols | Y.free_symbols | X.atoms(AppliedUndef)
                   | Y.atoms(AppliedUndef)) - {_T}, key=str)
    for _ in range(3):
        vals = {s: rnd.uniform(0.2, 1.3) for s in free}
        vals.update({x: rnd.uniform(-2, 2) for x in qs})
        d = (X - Y).xreplace(vals)
        try:
            if max((abs(complex(sm.N(e))) for e in d), default=0.0) > 1e-12:
                return False
        except TypeError:
            return False
    return True


def _same_vec(a, b):
    return all(sm.simplify(x - y) == 0 for x, y in zip(a, b))
