"""Robots as their users describe them: URDF and MJCF files in, a sympy
``System`` of bodies and joints out (:class:`Robot`), and from it a
``gen.Model`` (``gen.Model.from_urdf``, ``gen.Model.from_mjcf``).

    robot = gen.load_urdf("ur5.urdf")                 # a gen.Robot: robot.system, ...
    model = gen.Model.from_system(robot.system, **robot.model_options())
                                                      # = gen.Model.from_urdf("ur5.urdf")

Modules: :mod:`.description` (the format-free description, its checks and
bodies), :mod:`.urdf` (yourdfpy), :mod:`.mjcf` (MuJoCo's compiler),
:mod:`.joints` (the free and ball joints, quaternions), :mod:`.robot` (the
System). See docs/guides/robots.md.
"""
from __future__ import annotations

from .joints import BallJoint, FreeJoint
from .robot import Robot, build_robot

__all__ = ["load_urdf", "load_mjcf", "Robot", "FreeJoint", "BallJoint"]


def load_urdf(source, base="fixed", constants="numeric", mimic="constraints", gravity=None,
              inputs="torques"):
    """A URDF file (or XML string) as a :class:`Robot`: its sympy System
    and what a model of it needs (docs/guides/robots.md).

    Parameters
    ----------
    source : str or path
        A file path, or the XML itself.
    base : {"fixed", "floating"}
        ``"floating"``: the root link on a free joint (quaternion; see
        :class:`FreeJoint`).
    constants : {"numeric", "symbolic"}
        ``"symbolic"``: each link's mass, centre of mass and inertia as named
        constants (``robot.constants``).
    mimic : {"constraints", "ignore"}
        Mimic joints as holonomic constraints, or as independent joints.
    gravity : 3 numbers, optional
        In the world's axes; ``(0, 0, -9.81)`` by default.
    inputs : "torques", None or list of joint names
        The joints that get a torque input ``tau_<joint>``.

    Returns
    -------
    Robot

    Raises
    ------
    gen.ModelError
        Malformed XML (with its line), a kinematic loop, an unknown joint
        type, a moving joint over a massless subtree (naming the link and the
        joint, with their lines).
    gen.MissingDependencyError
        Without yourdfpy (``pip install eomgen[robots]``).
    """
    from .urdf import read_urdf
    return build_robot(read_urdf(source), base, constants, mimic, gravity, inputs)


def load_mjcf(source, base=None, constants="numeric", gravity=None, inputs="torques"):
    """An MJCF file (or XML string) compiled by MuJoCo, as a :class:`Robot`
    (docs/guides/robots.md): the file's own joints (its free joints as
    :class:`FreeJoint`, its ball joints as :class:`BallJoint`), the file's
    gravity unless ``gravity`` is given.

    Parameters
    ----------
    source : str or path
        A file path, or the XML itself.
    base : {None, "fixed", "floating"}
        ``None``: the file's joints. ``"fixed"``: every free joint welded,
        its body where the file places it (``pos``, ``quat``), as if its
        ``<freejoint/>`` were removed. ``"floating"``: every body of the
        world that has no joint gets a free joint (named ``base``, or
        ``<body>_base`` when several do), as if it had a ``<freejoint/>``;
        a free body stays free, and a body of the world on another joint is
        refused.
    constants : {"numeric", "symbolic"}
        As for :func:`load_urdf`.
    gravity : 3 numbers, optional
        In the world's axes; the file's ``<option gravity>`` by default.
    inputs : "torques", None or list of joint names
        The joints that get a torque input ``tau_<joint>``.

    Returns
    -------
    Robot

    Raises
    ------
    gen.ModelError
        What MuJoCo's compiler refuses (its message, with the line), or what
        the dynamics cannot take (naming the body or joint).
    gen.MissingDependencyError
        Without mujoco (``pip install eomgen[robots]``).
    """
    from .mjcf import read_mjcf
    return build_robot(read_mjcf(source, base), "fixed", constants, "ignore", gravity, inputs)
