"""MJCF in: a file or an XML string compiled by MuJoCo's own compiler
(``mujoco``, the ``robots`` extra: it alone resolves MJCF's defaults,
classes, includes and ``inertiafromgeom``), and the compiled ``mjModel``'s
bodies and joints read into a
:class:`~gen.intake.robots.description.RobotDescription`.

MuJoCo's tree is bodies, each with zero or more joints about (along) an
anchor ``jnt_pos`` in the body's frame, applied in turn; a body without a
joint is welded to its parent. In the description:

- a body with joints ``j1 .. jn`` becomes a chain of links: the links
  ``<joint>_link`` of ``j1 .. j(n-1)``, massless, then the body's own link,
  whose frame is the body's frame moved to the anchor of ``jn`` (its inertia
  and its children placed from there), so each joint's child frame is its
  joint frame moved, as the description wants;
- ``hinge``: revolute; ``slide``: prismatic; ``ball``: ball (quaternion);
  ``free``: floating, placed at the world's origin (MuJoCo's free joint holds
  the body's pose in the world);
- the children keep the file's order (MuJoCo's joint order: the state
  follows ``qpos``/``qvel``, a quaternion scalar last: see
  docs/guides/robots.md), the joints' ranges where ``jnt_limited``, the
  gravity of ``<option gravity>``.

Only the rigid-body tree is read: geoms (their inertia already in the
bodies'), contacts, tendons, actuators, equality constraints, joint damping,
armature, springs and friction loss are left out.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ...core.errors import ModelError
from ...core.optional import require
from .description import Inertial, JointSpec, Link, RobotDescription, exact_rotation

__all__ = ["read_mjcf", "compile_mjcf"]

# mjtJoint: free, ball, slide, hinge
_KINDS = {0: "floating", 1: "ball", 2: "prismatic", 3: "revolute"}


def compile_mjcf(source):
    """(mujoco.MjModel, label) of an MJCF path or XML string; MuJoCo's
    compiler errors (with their line) as a ModelError."""
    mujoco = require("mujoco", "gen.Model.from_mjcf")
    if isinstance(source, bytes):
        source = source.decode()
    try:
        if isinstance(source, str) and source.lstrip().startswith("<"):
            return mujoco.MjModel.from_xml_string(source), "<string>"
        if isinstance(source, (str, os.PathLike)):
            path = Path(source)
            if not path.is_file():
                raise ModelError(f"gen.Model.from_mjcf: no file {str(path)!r}")
            return mujoco.MjModel.from_xml_path(str(path)), str(path)
    except ValueError as e:
        label = "<string>" if str(source).lstrip().startswith("<") else str(source)
        msg = " ".join(str(e).split())
        raise ModelError(f"{label}: MuJoCo's compiler refuses it: {msg}") from None
    raise ModelError(f"gen.Model.from_mjcf takes a file path or an XML string, got "
                     f"{type(source).__name__}")


def _quat(wxyz):
    """The rotation matrix of MuJoCo's quaternion (scalar first)."""
    w, x, y, z = np.asarray(wxyz, float) / np.linalg.norm(wxyz)
    return exact_rotation(np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]))


def _bases(m, base, bodies, jnames, label):
    """{body: the name of its added free joint} for base="floating": every
    body of the world without a joint gets one (``base``, or
    ``<body>_base`` when several do); a body of the world on other joints
    than a free one is refused. base="fixed" (free joints welded) and None
    add none."""
    if base not in (None, "fixed", "floating"):
        raise ModelError(f"base={base!r}: accepted are None (the file's joints), 'fixed' and "
                         "'floating'")
    if base != "floating":
        return {}
    top = [b for b in range(1, m.nbody) if int(m.body_parentid[b]) == 0]
    bare = []
    for b in top:
        adr, n = int(m.body_jntadr[b]), int(m.body_jntnum[b])
        kinds = [_KINDS[int(m.jnt_type[j])] for j in range(adr, adr + max(n, 0))]
        if not kinds:
            bare.append(b)
        elif kinds != ["floating"]:
            raise ModelError(
                f"{label}: base='floating': body {bodies[b]!r} of the world moves on the "
                f"joint(s) {[jnames[j] for j in range(adr, adr + n)]}, not a free joint: a "
                "free base is added only to a body welded to the world (base=None keeps "
                "the file's joints)")
    names = set(jnames)
    one = "base" if "base" not in names else "root_joint"
    return {b: one if len(bare) == 1 else f"{bodies[b]}_base" for b in bare}


def _names(m, obj, n, prefix):
    import mujoco
    out = []
    for i in range(n):
        name = mujoco.mj_id2name(m, obj, i)
        out.append(name if name else f"{prefix}{i}")
    return out


def read_mjcf(source, base=None):
    """The RobotDescription of an MJCF file or string (module docstring);
    base: None (the file's joints), "fixed" or "floating" (:func:`_bases`)."""
    m, label = compile_mjcf(source)           # MissingDependencyError without mujoco
    import mujoco
    bodies = _names(m, mujoco.mjtObj.mjOBJ_BODY, m.nbody, "body")
    jnames = _names(m, mujoco.mjtObj.mjOBJ_JOINT, m.njnt, "joint")
    free = _bases(m, base, bodies, jnames, label)
    links, joints = {bodies[0]: Link(bodies[0])}, []
    anchor = [np.zeros(3)] * m.nbody          # each body's link origin in its frame
    for b in range(1, m.nbody):
        adr, n = int(m.body_jntadr[b]), int(m.body_jntnum[b])
        ids = list(range(adr, adr + n)) if n > 0 else []
        kinds = [_KINDS[int(m.jnt_type[j])] for j in ids]
        pos = [np.zeros(3) if k == "floating" else np.array(m.jnt_pos[j], float)
               for j, k in zip(ids, kinds)]
        anchor[b] = pos[-1] if ids else np.zeros(3)
        R = _quat(m.body_quat[b])
        parent = int(m.body_parentid[b])
        t = np.array(m.body_pos[b], float) - anchor[parent]
        Ri = _quat(m.body_iquat[b])
        inertia = Ri @ np.diag(np.array(m.body_inertia[b], float)) @ Ri.T
        links[bodies[b]] = Link(bodies[b], Inertial(float(m.body_mass[b]),
                                                    np.array(m.body_ipos[b], float) - anchor[b],
                                                    inertia))
        if b in free:                 # base="floating": a free joint added
            joints.append(JointSpec(free[b], "floating", bodies[parent], bodies[b],
                                    np.eye(3), np.zeros(3)))
            continue
        if not ids or (base == "fixed" and kinds == ["floating"]):
            # welded (base="fixed": where the file puts the free body)
            joints.append(JointSpec(f"{bodies[b]}_weld", "fixed", bodies[parent], bodies[b], R, t))
            continue
        prev, prev_pos = bodies[parent], None
        for k, (j, kind, p) in enumerate(zip(ids, kinds, pos)):
            last = k == n - 1
            child = bodies[b] if last else f"{jnames[j]}_link"
            if not last:
                links[child] = Link(child)
            if prev_pos is None:
                Rj, tj = R, t + R @ p
            else:
                Rj, tj = np.eye(3), p - prev_pos
            if kind == "floating":
                if prev_pos is not None or parent != 0:
                    raise ModelError(f"{label}: the free joint {jnames[j]!r} of body "
                                     f"{bodies[b]!r} is not its body's only joint under the "
                                     "world: taken only there")
                Rj, tj = np.eye(3), np.zeros(3)
            limits = None
            if kind in ("revolute", "prismatic") and m.jnt_limited[j]:
                limits = (float(m.jnt_range[j][0]), float(m.jnt_range[j][1]))
            joints.append(JointSpec(jnames[j], kind, prev, child, Rj, tj,
                                    np.array(m.jnt_axis[j], float), limits))
            prev, prev_pos = child, p
    name = bytes(m.names).split(b"\0")[0].decode() or "robot"
    return RobotDescription(name, links, joints, label, tuple(float(g) for g in m.opt.gravity),
                            keep_order=True)
