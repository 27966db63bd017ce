"""URDF in: a file or an XML string read by ``yourdfpy`` (the ``robots``
extra) into a :class:`~gen.intake.robots.description.RobotDescription`.

The XML is first parsed strictly with lxml (yourdfpy's own parse recovers
from broken XML silently): malformed XML is a ModelError with the parser's
line and message, and every link and joint keeps its line for later
messages. yourdfpy then reads the values (origins from ``xyz``/``rpy``, axes,
inertials, limits, mimic tags); meshes are never loaded (dynamics need none:
a link with only visual or collision geometry is a link without inertia).

Taken joint types: ``revolute``, ``continuous``, ``prismatic``, ``fixed``
and ``floating``; ``planar`` and any other type are refused, naming the
joint and its line.
"""
from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from ...core.errors import ModelError
from ...core.optional import require
from .description import Inertial, JointSpec, Link, RobotDescription, exact_rotation

__all__ = ["read_urdf", "read_xml"]

_URDF_KINDS = ("revolute", "continuous", "prismatic", "fixed", "floating")


def read_xml(source, what):
    """(lxml root element, text bytes, label) of ``source``: a path (str or
    Path) or an XML string (its first non-blank character ``<``); a
    ModelError with the line for malformed XML, or for a missing file."""
    from lxml import etree
    if isinstance(source, bytes):
        data, label = source, "<string>"
    elif isinstance(source, str) and source.lstrip().startswith("<"):
        data, label = source.encode(), "<string>"
    elif isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if not path.is_file():
            raise ModelError(f"{what}: no file {str(path)!r}")
        data, label = path.read_bytes(), str(path)
    else:
        raise ModelError(f"{what} takes a file path or an XML string, got "
                         f"{type(source).__name__}")
    try:
        root = etree.fromstring(data, parser=etree.XMLParser(remove_comments=False))
    except etree.XMLSyntaxError as e:
        line = getattr(e, "lineno", None) or (e.position[0] if e.position else None)
        raise ModelError(f"{label}: malformed XML at line {line}: {e.msg}") from None
    return root, data, label


def _lines(root, tag):
    return {el.get("name"): el.sourceline for el in root.findall(tag)}


def read_urdf(source):
    """The RobotDescription of a URDF file or string (module docstring)."""
    yourdfpy = require("yourdfpy", "gen.Model.from_urdf")
    root, data, label = read_xml(source, "gen.Model.from_urdf")
    if root.tag != "robot":
        raise ModelError(f"{label}: the root element is <{root.tag}>, not <robot>: not a URDF "
                         "file")
    for tag in ("link", "joint"):
        for el in root.findall(tag):
            if not el.get("name"):
                raise ModelError(f"{label}: a <{tag}> without a name at line {el.sourceline}")
    if not root.findall("link"):
        raise ModelError(f"{label}: the robot has no links (not a robot description: a xacro "
                         "file must be expanded by xacro first)")
    link_lines, joint_lines = _lines(root, "link"), _lines(root, "joint")
    for el in root.findall("joint"):
        kind = el.get("type")
        if kind not in _URDF_KINDS:
            what = ("is planar, which gen.Model.from_urdf does not take"
                    if kind == "planar" else f"has the unknown type {kind!r}")
            raise ModelError(f"joint {el.get('name')!r} (line {el.sourceline} of {label}) "
                             f"{what} (taken: {', '.join(_URDF_KINDS)})")
        for end in ("parent", "child"):
            sub = el.find(end)
            if sub is None or not sub.get("link"):
                raise ModelError(f"joint {el.get('name')!r} (line {el.sourceline} of {label}) "
                                 f"has no <{end} link=...>")
    if not root.get("name"):
        root.set("name", "robot")          # urdfdom refuses it; the name is not dynamics
    try:
        from lxml import etree
        robot = yourdfpy.URDF.load(io.BytesIO(etree.tostring(root)), build_scene_graph=False,
                                   load_meshes=False, build_collision_scene_graph=False,
                                   load_collision_meshes=False).robot
    except Exception as e:          # yourdfpy's errors are plain ones: name the file
        raise ModelError(f"{label}: yourdfpy could not read it: {type(e).__name__}: "
                         f"{e}") from None
    links = {}
    for lk in robot.links:
        links[lk.name] = Link(lk.name, _inertial(lk, label, link_lines), link_lines.get(lk.name))
    joints = []
    for j in robot.joints:
        joints.append(_joint(j, label, joint_lines.get(j.name)))
    return RobotDescription(root.get("name"), links, joints, label)


def _floats(value, n, what):
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{what}: {value!r} is not {n} number(s)") from None
    if out.size != n or not np.all(np.isfinite(out)):
        raise ModelError(f"{what}: {list(np.ravel(value))} is not {n} finite number(s)")
    return out.reshape(-1) if n == 1 else out


def _inertial(lk, label, lines):
    ine = lk.inertial
    if ine is None:
        return None
    what = f"link {lk.name!r} (line {lines.get(lk.name)} of {label})"
    mass = 0.0 if ine.mass is None else float(_floats(ine.mass, 1, f"{what}: mass")[0])
    if mass < 0:
        raise ModelError(f"{what} has the negative mass {mass}")
    inertia = np.zeros((3, 3)) if ine.inertia is None else \
        _floats(ine.inertia, 9, f"{what}: inertia").reshape(3, 3)
    T = np.eye(4) if ine.origin is None else np.asarray(ine.origin, float)
    R = exact_rotation(T[:3, :3])
    return Inertial(mass, T[:3, 3].copy(), R @ inertia @ R.T)


def _joint(j, label, line):
    what = f"joint {j.name!r} (line {line} of {label})"
    T = np.eye(4) if j.origin is None else _floats(j.origin, 16, f"{what}: origin").reshape(4, 4)
    axis = np.array([1.0, 0.0, 0.0]) if j.axis is None else _floats(j.axis, 3, f"{what}: axis")
    limits = None
    if j.limit is not None and j.type in ("revolute", "prismatic") \
            and j.limit.lower is not None and j.limit.upper is not None:
        limits = (float(j.limit.lower), float(j.limit.upper))
        if not limits[0] <= limits[1]:
            raise ModelError(f"{what}: its lower limit {limits[0]} is above its upper limit "
                             f"{limits[1]}")
    mimic = None
    if j.mimic is not None:
        if not j.mimic.joint:
            raise ModelError(f"{what}: <mimic> names no joint")
        mimic = (j.mimic.joint, float(j.mimic.multiplier), float(j.mimic.offset))
    return JointSpec(j.name, j.type, j.parent, j.child, exact_rotation(T[:3, :3]), T[:3, 3].copy(),
                     axis, limits, mimic, line)
