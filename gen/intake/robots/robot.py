"""A robot description as a sympy ``System`` of bodies and joints
(:class:`Robot`), ready for ``Model.from_system``.

Per body (a moving link with the links welded to it, :func:`bodies_of`): a
``RigidBody`` named after its link, its frame the link's frame, its mass
centre and central inertia merged from its links' inertials; per moving
joint a sympy joint from the parent body to the child body:

- ``revolute`` and ``continuous``: ``PinJoint`` about the joint's axis;
  coordinate ``q_<joint>`` (an angle, also for a continuous joint, which
  Pinocchio holds as (cos, sin)), speed ``u_<joint>``;
- ``prismatic``: ``PrismaticJoint`` along the axis;
- ``floating``: :class:`~gen.intake.robots.joints.FreeJoint`, coordinates
  ``<joint>_x, _y, _z, _qx, _qy, _qz, _qw``, speeds ``<joint>_vx, _vy, _vz,
  _wx, _wy, _wz`` (body axes: Pinocchio's free flyer); a floating base is
  the joint ``base`` (``root_joint`` if the file has a joint named base);
- ``ball`` (MJCF): :class:`~gen.intake.robots.joints.BallJoint`.

The joint frame sits in the parent body's frame where the file puts it
(composed through fixed joints); its child is the child link's frame, as in
URDF and Pinocchio. Inputs: a torque ``tau_<joint>`` (a force for a
prismatic joint) between the two bodies about (along) the axis of each
actuated one-dof joint. Gravity: ``m g`` at every body's mass centre.

Mimic joints (``mimic="constraints"``): the holonomic constraint
``q_j = multiplier q_source + offset`` (a chain of mimics resolved to its
source), the mimic joints' coordinates and speeds dependent (last in the
state, in joint order), without a torque; ``mimic="ignore"``: independent
joints, as Pinocchio's parser gives them by default.

``constants="symbolic"``: each link with an inertial keeps its mass
``m_<link>``, centre of mass ``c_<link>_x/y/z`` (link axes) and inertia about
it ``I_<link>_xx/xy/xz/yy/yz/zz`` (link axes) as named constants, valued
from the file (a merged body's mass, centre and inertia are their sums,
weighted mean and parallel-axis sums); ``"numeric"``: the numbers
themselves, folded into the C.
"""
from __future__ import annotations

import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

from ...core.errors import ModelError
from ..sympy_compat import time_symbol
from .description import DOF, bodies_of, merge_inertials
from .joints import BallJoint, FreeJoint

__all__ = ["Robot", "build_robot", "MIMIC", "CONSTANTS", "BASES"]

MIMIC = ("constraints", "ignore")
CONSTANTS = ("numeric", "symbolic")
BASES = ("fixed", "floating")
_T = time_symbol()


def _num(x):
    """A float as a sympy number: exact zero and small integers as Integers
    (sparser expressions), else a Float of the same binary value."""
    x = float(x)
    if x == int(x) and abs(x) < 1e6:
        return sm.Integer(int(x))
    return sm.Float(x)


def _vec(frame, v):
    return _num(v[0]) * frame.x + _num(v[1]) * frame.y + _num(v[2]) * frame.z \
        if not isinstance(v[0], sm.Basic) else v[0] * frame.x + v[1] * frame.y + v[2] * frame.z


def _dyadic(frame, Ic):
    """The inertia dyadic of a 3 x 3 matrix in frame's axes, built at once
    (me.inertia adds nine outer products, each addition comparing printed
    vectors)."""
    axes = (frame.x, frame.y, frame.z)
    return me.Dyadic([(Ic[i, j], axes[i], axes[j]) for i in range(3) for j in range(3)
                      if Ic[i, j] != 0])


def _fn(name):
    return sm.Function(name)(_T)


class Robot:
    """A robot file as a sympy ``System`` (module docstring), and what a model
    of it needs.

    Attributes
    ----------
    system : sympy.physics.mechanics.System
        Its bodies, joints, gravity and joint torques; add loads, actuators or
        constraints before building a model from it.
    constants : dict
        ``{Symbol: value}`` of the symbolic inertial parameters (empty for
        ``constants="numeric"``).
    inputs : list
        The joint torques (functions of time), in joint order.
    joints : list of str
        The moving joints, in the state's order (Pinocchio's).
    limits : dict
        ``{joint: (lower, upper)}`` of the limited revolute and prismatic joints.
    name : str
        A model name made from the file's robot name.

    Parameters
    ----------
    system, constants, inputs, joints, limits, name
        The attributes above (made by ``gen.load_urdf`` and ``gen.load_mjcf``).
    coordinates : dict
        ``{joint: its coordinate}`` of the one-dof joints.
    """

    def __init__(self, system, constants, inputs, joints, limits, name, coordinates):
        self.system = system
        self.constants = constants
        self.inputs = inputs
        self.joints = joints
        self.limits = limits
        self.name = name
        self._coordinate = coordinates        # {joint: its coordinate}

    def __repr__(self):
        return (f"<gen.Robot {self.name!r}: {len(self.system.bodies) - 1} bodies, "
                f"{len(self.system.q)} coordinates, {len(self.system.u)} speeds, "
                f"{len(self.inputs)} inputs>")

    def limit_impacts(self, restitution=0.0):
        """``{"<joint>_lower": gen.Impact(q - lower), "<joint>_upper":
        gen.Impact(upper - q)}`` for every limited joint: each limit a
        unilateral contact, ``restitution`` its coefficient (0: the joint
        stays at its stop while pushed into it).

        Parameters
        ----------
        restitution : float, optional
            The impacts' coefficient of restitution.

        Returns
        -------
        dict
            ``{name: gen.Impact}``, empty for a robot without limits.
        """
        from ..hybrid import Impact
        out = {}
        for j, (lo, hi) in self.limits.items():
            q = self._coordinate[j]
            out[f"{j}_lower"] = Impact(q - _num(lo), restitution)
            out[f"{j}_upper"] = Impact(_num(hi) - q, restitution)
        return out

    def model_options(self, formulation="recursive", name=None, hybrid=None):
        """The keywords of ``gen.Model.from_system(robot.system, **options)``
        that build this robot's model (what ``gen.Model.from_urdf`` and
        ``from_mjcf`` do): its constants, inputs, name, formulation and
        impacts.

        Parameters
        ----------
        formulation : {"recursive", "crba", "kane"}
            As for ``Model.from_system``; ``"kane"`` forms the System's
            equations with ``form_eoms()`` first (small robots only).
        name : str, optional
            The model's C prefix; the robot's name by default.
        hybrid : None, "limits" or dict
            ``"limits"``: :meth:`limit_impacts`; a dict of ``gen.Impact`` /
            ``gen.Reset`` as for any model.

        Returns
        -------
        dict
            ``constants``, ``inputs``, ``name``, ``formulation``, ``hybrid``.

        Raises
        ------
        gen.ModelError
            On an unknown ``hybrid`` string, or ``"limits"`` without limits.
        """
        if isinstance(hybrid, str):
            if hybrid != "limits":
                raise ModelError(f"hybrid={hybrid!r}: accepted are None, 'limits' or a dict "
                                 "of gen.Impact / gen.Reset")
            hybrid = self.limit_impacts()
            if not hybrid:
                raise ModelError("hybrid='limits': the robot has no limited joint")
        if formulation == "kane" and self.system.eom_method is None:
            self.system.form_eoms()
        return {"constants": dict(self.constants), "inputs": list(self.inputs),
                "name": name or self.name, "formulation": formulation, "hybrid": hybrid}


def _model_name(name):
    import re
    s = re.sub(r"[^a-z0-9_]", "_", (name or "robot").lower()).strip("_") or "robot"
    return s if s[0].isalpha() else "r_" + s


def _check_options(base, constants, mimic, inputs, gravity):
    if base not in BASES:
        raise ModelError(f"base={base!r}: accepted are 'fixed' and 'floating'")
    if constants not in CONSTANTS:
        raise ModelError(f"constants={constants!r}: accepted are 'numeric' and 'symbolic'")
    if mimic not in MIMIC:
        raise ModelError(f"mimic={mimic!r}: accepted are 'constraints' and 'ignore'")
    if not (inputs is None or inputs == "torques" or isinstance(inputs, (list, tuple))):
        raise ModelError(f"inputs={inputs!r}: accepted are 'torques', None or a list of joint "
                         "names")
    g = np.asarray(gravity, dtype=float) if gravity is not None else None
    if g is not None and (g.shape != (3,) or not np.all(np.isfinite(g))):
        raise ModelError(f"gravity={gravity!r}: three finite numbers (world axes)")
    return g


def _inertia_params(link, symbolic, params):
    """(mass, com, inertia) of a link in its own axes: numbers, or named
    constants (recorded in params)."""
    ine = link.inertial
    if not symbolic:
        return ine.mass, ine.com, ine.inertia
    m = sm.Symbol(f"m_{link.name}")
    c = [sm.Symbol(f"c_{link.name}_{a}") for a in "xyz"]
    keys = ("xx", "xy", "xz", "yy", "yz", "zz")
    idx = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
    Isym = {k: sm.Symbol(f"I_{link.name}_{k}") for k in keys}
    params[m] = float(ine.mass)
    for s, v in zip(c, ine.com):
        params[s] = float(v)
    for k, (i, j) in zip(keys, idx):
        params[Isym[k]] = float(ine.inertia[i, j])
    Im = sm.Matrix(3, 3, lambda i, j: Isym[keys[idx.index((min(i, j), max(i, j)))]])
    return m, sm.Matrix(c), Im


def _body_inertia(body, symbolic, params):
    """(mass, com (3,), inertia about com (3x3)) of a body in its frame."""
    if not symbolic:
        m, c, Ic = merge_inertials(body.links)
        return _num(m), [_num(x) for x in c], sm.Matrix(3, 3, lambda i, j: _num(Ic[i, j]))
    parts = []
    for link, R, p in body.links:
        if link.inertial is None:
            continue
        m, c, Ic = _inertia_params(link, True, params)
        Rm = sm.Matrix(3, 3, lambda i, j: _num(R[i, j]))
        parts.append((m, Rm * c + sm.Matrix([_num(x) for x in p]), Rm * Ic * Rm.T))
    if not parts:
        return sm.S.Zero, [sm.S.Zero] * 3, sm.zeros(3, 3)
    if len(parts) == 1:
        m, c, Ic = parts[0]
        return m, list(c), Ic
    M = sm.Add(*[m for m, _, _ in parts])
    com = sm.Matrix(3, 1, lambda i, _: sm.Add(*[m * c[i] for m, c, _ in parts]) / M)
    Ic = sm.zeros(3, 3)
    for m, c, I_ in parts:
        d = c - com
        Ic += I_ + m * ((d.T * d)[0] * sm.eye(3) - d * d.T)
    return M, list(com), Ic


def build_robot(desc, base="fixed", constants="numeric", mimic="constraints", gravity=None,
                inputs="torques"):
    """The :class:`Robot` of a RobotDescription (module docstring)."""
    g = _check_options(base, constants, mimic, inputs, gravity)
    g = np.asarray(desc.gravity, float) if g is None else g
    bodies, root = bodies_of(desc, base == "floating")
    names = {j.name for j in desc.joints}
    if bodies and bodies[0].joint is not None and bodies[0].joint.name == "root_joint" \
            and base == "floating":
        bodies[0].joint.name = "root_joint" if "base" in names else "base"
    symbolic = constants == "symbolic"
    params = {}
    ground = me.RigidBody("universe")
    system = me.System.from_newtonian(ground)
    N = ground.frame
    rb, joints, coord, loads, com_of = [], [], {}, [], {ground: [0, 0, 0]}
    actuated = _actuated(desc, bodies, inputs, mimic)
    taus = []
    for b in bodies:
        m, c, Ic = _body_inertia(b, symbolic, params)
        frame = me.ReferenceFrame(b.name)
        mc = me.Point(f"{b.name}_com")
        body = me.RigidBody(b.name, mc, frame, m, (_dyadic(frame, Ic), mc))
        com_of[body] = c                 # the mass centre from the link origin (frame axes)
        rb.append(body)
        parent = ground if b.parent is None else rb[b.parent]
        joint = _joint(b, parent, body, com_of, coord)
        joints.append(joint)
        loads.append(me.Force(mc, m * (_num(g[0]) * N.x + _num(g[1]) * N.y
                                       + _num(g[2]) * N.z)))
        if b.joint.name in actuated:
            tau = _fn(f"tau_{b.joint.name}")
            taus.append(tau)
            loads.extend(_torque_loads(b.joint, joint, tau))
    system.add_joints(*joints)
    system.add_loads(*loads)
    if mimic == "constraints":
        _mimic_constraints(desc, system, bodies, coord)
    limits = {b.joint.name: b.joint.limits for b in bodies
              if b.joint.limits is not None and b.joint.kind in ("revolute", "prismatic")}
    return Robot(system, params, taus, [b.joint.name for b in bodies], limits,
                 _model_name(desc.name), coord)


def _actuated(desc, bodies, inputs, mimic):
    """The names of the joints that get a torque input."""
    one = [b.joint.name for b in bodies if DOF[b.joint.kind] == 1
           and not (mimic == "constraints" and b.joint.mimic is not None)]
    if inputs is None:
        return set()
    if inputs == "torques":
        return set(one)
    bad = [j for j in inputs if j not in one]
    if bad:
        raise ModelError(f"inputs={list(inputs)!r}: {bad} are not actuated one-dof joints of "
                         f"{desc.source} (those are {one})")
    return set(inputs)


def _joint(b, parent, child, com_of, coord):
    """The sympy joint of body b (parent and child RigidBody; com_of: each
    body's mass centre from its link origin, in its axes)."""
    j = b.joint
    Pf = parent.frame
    cp, c_child = com_of[parent], com_of[child]
    ppos = [(_num(b.translation[i]) - cp[i]) for i in range(3)]
    ppoint = parent.masscenter.locatenew(f"{j.name}_parent", _vec(Pf, ppos))
    cpoint = child.masscenter.locatenew(f"{j.name}_child",
                                        _vec(child.frame, [-x for x in c_child]))
    if np.array_equal(b.rotation, np.eye(3)):
        pint = Pf
    else:
        pint = me.ReferenceFrame(f"{j.name}_frame")
        pint.orient_explicit(Pf, sm.Matrix(3, 3, lambda r, s: _num(b.rotation[r, s])))
    kw = dict(parent_point=ppoint, child_point=cpoint, parent_interframe=pint,
              child_interframe=child.frame)
    if j.kind in ("revolute", "continuous", "prismatic"):
        q, u = _fn(f"q_{j.name}"), _fn(f"u_{j.name}")
        coord[j.name] = q
        cls = me.PrismaticJoint if j.kind == "prismatic" else me.PinJoint
        return cls(j.name, parent, child, q, u, joint_axis=_vec(pint, j.axis), **kw)
    if j.kind == "floating":
        q = [_fn(f"{j.name}_{s}") for s in ("x", "y", "z", "qx", "qy", "qz", "qw")]
        u = [_fn(f"{j.name}_{s}") for s in ("vx", "vy", "vz", "wx", "wy", "wz")]
        return FreeJoint(j.name, parent, child, q, u, **kw)
    if j.kind == "ball":
        q = [_fn(f"{j.name}_{s}") for s in ("qx", "qy", "qz", "qw")]
        u = [_fn(f"{j.name}_{s}") for s in ("wx", "wy", "wz")]
        return BallJoint(j.name, parent, child, q, u, **kw)
    raise ModelError(f"joint {j.name!r}: kind {j.kind!r} is not a moving joint")  # pragma: no cover


def _torque_loads(spec, joint, tau):
    """The loads of a joint's actuator: tau about (along) its axis on the
    child, its reaction on the parent."""
    axis = joint.joint_axis
    if spec.kind == "prismatic":
        return [me.Force(joint.child_point, tau * axis), me.Force(joint.parent_point, -tau * axis)]
    return [me.Torque(joint.child.frame, tau * axis), me.Torque(joint.parent.frame, -tau * axis)]


def _mimic_constraints(desc, system, bodies, coord):
    """q_j = multiplier q_source + offset for each mimic joint (module
    docstring): holonomic constraints, the mimic coordinates and speeds
    dependent."""
    spec = {b.joint.name: b.joint for b in bodies}
    by_name = {j.name: j for j in desc.joints}
    dep, cons = [], []
    for b in bodies:
        j = b.joint
        if j.mimic is None or DOF[j.kind] != 1:
            continue
        mult, off, src, seen = 1.0, 0.0, j, {j.name}
        while src.mimic is not None:
            name, k, o = src.mimic
            mult, off = mult * k, off + mult * o
            if name in seen:
                raise ModelError(f"{desc.joint_label(j)}: its mimic tags close a cycle "
                                 f"through joint {name!r}")
            seen.add(name)
            if name not in by_name:
                raise ModelError(f"{desc.joint_label(src)} mimics joint {name!r}, which the "
                                 "file does not define (mimic='ignore' leaves the tag out)")
            src = by_name[name]
        if src.name not in spec or DOF[src.kind] != 1:
            raise ModelError(f"{desc.joint_label(j)} mimics {desc.joint_label(src)}, which "
                             "is not a one-dof moving joint (use mimic='ignore')")
        dep.append(j.name)
        cons.append(coord[j.name] - (_num(mult) * coord[src.name] + _num(off)))
    if not dep:
        return
    qd = [coord[n] for n in dep]
    ud = [sm.Function(f"u_{n}")(_T) for n in dep]
    system.q_ind = [q for q in system.q if q not in qd]
    system.q_dep = qd
    system.u_ind = [u for u in system.u if u not in ud]
    system.u_dep = ud
    system.add_holonomic_constraints(*cons)
