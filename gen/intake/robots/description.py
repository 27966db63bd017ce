"""A robot as its file describes it, whatever the format: links with their
inertia, joints between them (:class:`RobotDescription`), the checks every
format shares, and the bodies of the dynamics (:func:`bodies_of`).

The formats' adapters (:mod:`.urdf`, :mod:`.mjcf`) fill a description with
numbers their parsers give; everything after is common:

- one tree: every link the child of at most one joint (a link with two
  parents closes a kinematic loop), one root, no cycle, joints between
  links that exist, joint types known;
- the bodies: each moving joint's child link with every link welded to it by
  fixed joints merged into it (their inertias added, placed in the body's
  frame), in the order of Pinocchio's ``buildModelFromUrdf``: depth first from
  the root, a link's child joints in the order of their names (urdfdom keeps
  them in a ``std::map``), a fixed joint's subtree visited where it stands;
- a moving joint whose subtree has no mass and no inertia (its acceleration
  undefined: Pinocchio's ABA divides by zero there) is refused, naming the
  link and the joint.

Each message names the file, the link or joint and its line where the
parser gives one.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...core.errors import ModelError

__all__ = ["Inertial", "Link", "JointSpec", "RobotDescription", "Body", "bodies_of",
           "KINDS", "DOF", "merge_inertials", "exact_rotation"]

# the joint kinds a description holds, and their speeds
DOF = {"revolute": 1, "continuous": 1, "prismatic": 1, "fixed": 0, "floating": 6, "ball": 3}
KINDS = tuple(DOF)


def exact_rotation(R, tol=1e-15):
    """R (a rotation matrix of floats) with the entries that are 0 or +-1
    up to the rounding of double arithmetic made exact: |entry| below tol
    is 0, and an entry alone in its row and column after that is its sign.
    A file's right angles (``rpy="1.5707963267948966 0 0"``) come as
    cos(pi/2) = 6.1e-17 beside exact ones; exact, the generated code folds
    them (no products with 6.1e-17 or 3.7e-33, a joint axis along a frame
    axis stays one) and the result differs from the unrounded one by those
    roundings (1e-16). An angle the file rounds (``3.14159265359``: sine
    2e-13) is kept as it is, as Pinocchio reads it."""
    R = np.array(R, dtype=float)
    R[np.abs(R) < tol] = 0.0
    for i in range(3):
        nz = np.flatnonzero(R[i])
        if len(nz) == 1 and np.count_nonzero(R[:, nz[0]]) == 1 \
                and abs(abs(R[i, nz[0]]) - 1.0) < tol:
            R[i, nz[0]] = np.sign(R[i, nz[0]])
    return R


@dataclass
class Inertial:
    """A link's mass, centre of mass (link axes) and inertia about it (link
    axes, 3 x 3)."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass
class Link:
    name: str
    inertial: Inertial | None = None
    line: int | None = None


@dataclass
class JointSpec:
    """A joint: its child link's frame is the joint frame moved by the
    joint; the joint frame is placed in the parent link's frame by
    ``rotation`` (parent axes <- joint axes) and ``translation`` (parent
    axes) at zero displacement; ``axis`` (unit, joint axes) is the axis of
    a revolute, continuous or prismatic joint."""

    name: str
    kind: str
    parent: str
    child: str
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axis: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0]))
    limits: tuple | None = None          # (lower, upper)
    mimic: tuple | None = None           # (joint, multiplier, offset)
    line: int | None = None


@dataclass
class RobotDescription:
    """A robot's links and joints, as a file gives them (see the module
    docstring). ``source`` names the file in messages."""

    name: str
    links: dict
    joints: list
    source: str = "<string>"
    gravity: tuple = (0.0, 0.0, -9.81)
    keep_order: bool = False        # a link's child joints in the file's order (MJCF)

    def where(self, obj):
        """' (line N of source)' for a link or joint with a line, else ' (source)'."""
        line = getattr(obj, "line", None)
        return f" (line {line} of {self.source})" if line else f" ({self.source})"

    def link_label(self, name):
        link = self.links.get(name)
        return f"link {name!r}" + (self.where(link) if link is not None else "")

    def joint_label(self, joint):
        return f"joint {joint.name!r}" + self.where(joint)

    def check(self):
        """The root link, after the checks of the module docstring (a
        ModelError naming the link or joint otherwise)."""
        if not self.links:
            raise ModelError(f"{self.source}: the robot has no links (not a robot description: "
                             "a xacro file must be expanded by xacro first)")
        parent_of = {}
        names = set()
        for j in self.joints:
            if j.name in names:
                raise ModelError(f"{self.joint_label(j)}: a second joint of that name")
            names.add(j.name)
            if j.kind not in DOF:
                raise ModelError(f"{self.joint_label(j)} has the unknown type {j.kind!r} "
                                 f"(taken: {', '.join(KINDS)})")
            for end in (j.parent, j.child):
                if end not in self.links:
                    raise ModelError(f"{self.joint_label(j)} joins link {end!r}, which the "
                                     "file does not define")
            if j.parent == j.child:
                raise ModelError(f"kinematic loop: {self.joint_label(j)} joins link "
                                 f"{j.child!r} to itself")
            if j.child in parent_of:
                other = parent_of[j.child]
                raise ModelError(
                    f"kinematic loop: {self.link_label(j.child)} is the child of "
                    f"{self.joint_label(other)} and of {self.joint_label(j)}; a robot file "
                    "describes a tree (close a loop with constraints on the System of "
                    "gen.load_urdf(...).system instead)")
            parent_of[j.child] = j
            if j.kind in ("revolute", "continuous", "prismatic"):
                nrm = float(np.linalg.norm(j.axis))
                if not np.isfinite(nrm) or nrm == 0.0:
                    raise ModelError(f"{self.joint_label(j)} has the axis {list(j.axis)}")
                j.axis = np.asarray(j.axis, float) / nrm
                # components at rounding level (a URDF's 6.12323e-17 for cos(pi/2)) are
                # zero: the axis is the aligned one, as Pinocchio's parser reads it
                j.axis[np.abs(j.axis) < 1e-12] = 0.0
                j.axis /= np.linalg.norm(j.axis)
        roots = [n for n in self.links if n not in parent_of]
        if not roots:
            j = self.joints[0]
            raise ModelError(f"kinematic loop: every link is some joint's child (the joints "
                             f"close a cycle through {self.joint_label(j)}): no root link")
        if len(roots) > 1:
            raise ModelError(f"{self.source}: links {roots[:4]} are no joint's child: a robot "
                             "file describes one tree, with one root link")
        # every link reached from the root (a cycle apart from the root is
        # a loop: its links are children but unreachable)
        seen, stack = {roots[0]}, [roots[0]]
        children = _children(self.joints, self.keep_order)
        while stack:
            for j in children.get(stack.pop(), ()):
                seen.add(j.child)
                stack.append(j.child)
        lost = [j for j in self.joints if j.child not in seen]
        if lost:
            raise ModelError(f"kinematic loop: {self.joint_label(lost[0])} is on a cycle of "
                             "joints not connected to the root link "
                             f"{self.link_label(roots[0])}")
        return roots[0]


def _children(joints, keep_order=False):
    """{link: its child joints, by name} (urdfdom's order), or in the
    file's order (``keep_order``: MuJoCo's)."""
    out = {}
    for j in (joints if keep_order else sorted(joints, key=lambda j: j.name)):
        out.setdefault(j.parent, []).append(j)
    return out


@dataclass
class Body:
    """A rigid body of the dynamics: the link whose frame it has, the joint
    that moves it (None for a fixed root), its parent body (an index into
    the list, None for the ground), the joint's placement in the parent
    body's frame, and the links merged in it, each ``(link, R, p)``: its
    frame's axes (body <- link) and origin in the body's frame."""

    name: str
    joint: JointSpec | None
    parent: int | None
    rotation: np.ndarray
    translation: np.ndarray
    links: list


def bodies_of(desc, floating):
    """(bodies, root) of a checked description: the bodies (module
    docstring), parents first; ``floating``: the root link moves on a free
    joint named ``root_joint`` (its first body), else it and the links
    welded to it are the ground. Refuses a moving joint over a massless
    subtree."""
    root = desc.check()
    children = _children(desc.joints, desc.keep_order)
    out = []
    eye, zero = np.eye(3), np.zeros(3)
    if floating:
        free = JointSpec("root_joint", "floating", "world", root)
        out.append(Body(root, free, None, eye, zero, [(desc.links[root], eye, zero)]))
        start = (0, root, eye, zero)
    else:
        start = (None, root, eye, zero)

    def visit(body, link, R, p):
        # link: placed at (R, p) in body's frame (body None: the ground)
        for j in children.get(link, ()):
            Rj, pj = exact_rotation(R @ j.rotation), R @ j.translation + p
            if j.kind == "fixed":
                if body is not None:
                    out[body].links.append((desc.links[j.child], Rj, pj))
                visit(body, j.child, Rj, pj)
            else:
                out.append(Body(j.child, j, body, Rj, pj, [(desc.links[j.child], eye, zero)]))
                visit(len(out) - 1, j.child, eye, zero)

    visit(*start)
    _check_mass(desc, out)
    return out, root


def _check_mass(desc, bodies):
    """A moving joint over a subtree without mass or inertia is refused."""
    carried = [0.0] * len(bodies)
    for i in reversed(range(len(bodies))):
        b = bodies[i]
        own = sum(lk.inertial.mass + float(np.abs(lk.inertial.inertia).sum())
                  for lk, _, _ in b.links if lk.inertial is not None)
        carried[i] += own
        if b.joint is not None and carried[i] <= 0.0:
            raise ModelError(
                f"{desc.link_label(b.name)} has no inertia and carries "
                f"{desc.joint_label(b.joint)}: nothing it moves has mass or inertia, so the "
                "joint's acceleration is undefined (give the link an <inertial>, or make the "
                "joint fixed)")
        if b.parent is not None:
            carried[b.parent] += carried[i]


def merge_inertials(placed):
    """(mass, com, inertia about com) in a body's frame of the links
    ``[(link, R, p)]`` placed in it (numbers; a link without inertial adds
    nothing)."""
    mass, first = 0.0, np.zeros(3)
    parts = []
    for link, R, p in placed:
        ine = link.inertial
        if ine is None:
            continue
        c = R @ ine.com + p
        parts.append((ine.mass, c, R @ ine.inertia @ R.T))
        mass += ine.mass
        first += ine.mass * c
    com = first / mass if mass > 0 else np.zeros(3)
    inertia = np.zeros((3, 3))
    for m, c, Ic in parts:
        d = c - com
        inertia += Ic + m * (d @ d * np.eye(3) - np.outer(d, d))
    return mass, com, inertia
