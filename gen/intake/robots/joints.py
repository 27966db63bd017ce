"""Joints a robot file has and sympy's mechanics does not: a free (six-dof)
joint and a ball joint, both with a quaternion for the orientation.

Both are ``sympy.physics.mechanics.Joint`` subclasses (sympy 1.14's joint
protocol: ``_generate_coordinates``, ``_generate_speeds``, ``_generate_kdes``,
``_orient_frames``, ``_set_angular_velocity``, ``_set_linear_velocity``), so a
``System`` takes them as any joint and ``form_eoms`` (Kane) works on them; the
recursive formulation (:mod:`gen.intake.recursive`) reads their motion
subspace from :meth:`motion_subspace` instead of differentiating sympy's
kinematics (which would leave ``R^T R``, the identity, unsimplified).

The coordinates follow Pinocchio's free flyer and spherical joint:

- ``FreeJoint``: ``q = [x, y, z, qx, qy, qz, qw]``: the child point's position
  from the parent point in the parent interframe's axes, and the child
  interframe's orientation as a quaternion, scalar last; ``u = [vx, vy, vz,
  wx, wy, wz]``: the child point's velocity and the child's angular velocity
  in the parent, both in the child interframe's axes (body axes: Pinocchio's
  ``v`` of a free flyer).
- ``BallJoint``: ``q = [qx, qy, qz, qw]``, ``u = [wx, wy, wz]`` (child axes).

The rotation is that of the normalized quaternion, ``R(q / |q|)``: the model
is the same for any non-zero scale of the four numbers, so the drift of the
norm in a long integration changes nothing (the kinematics keep the norm in
exact arithmetic: ``d|q|^2/dt = 0``). The kinematic equations, with
``R`` the child-to-parent rotation and ``omega = [wx, wy, wz]``::

    [x, y, z]'       = R [vx, vy, vz]
    [qx, qy, qz, qw]' = 1/2 [ qw wx - qz wy + qy wz,
                              qz wx + qw wy - qx wz,
                             -qy wx + qx wy + qw wz,
                             -qx wx - qy wy - qz wz]
"""
from __future__ import annotations

import sympy as sm
from sympy.physics.mechanics.joint import Joint

from ..sympy_compat import orient_explicit_without_rates, time_symbol

__all__ = ["FreeJoint", "BallJoint", "quaternion_matrix", "quaternion_rates"]


def quaternion_matrix(qx, qy, qz, qw):
    """The rotation of the normalized quaternion (scalar last) as a sympy
    Matrix: child components to parent components."""
    s = qx**2 + qy**2 + qz**2 + qw**2
    return sm.Matrix([
        [1 - 2 * (qy**2 + qz**2) / s, 2 * (qx * qy - qz * qw) / s, 2 * (qx * qz + qy * qw) / s],
        [2 * (qx * qy + qz * qw) / s, 1 - 2 * (qx**2 + qz**2) / s, 2 * (qy * qz - qx * qw) / s],
        [2 * (qx * qz - qy * qw) / s, 2 * (qy * qz + qx * qw) / s, 1 - 2 * (qx**2 + qy**2) / s]])


def quaternion_rates(qx, qy, qz, qw, wx, wy, wz):
    """[qx, qy, qz, qw]' for the angular velocity (wx, wy, wz) in the
    child's axes."""
    h = sm.Rational(1, 2)
    return [h * (qw * wx - qz * wy + qy * wz),
            h * (qz * wx + qw * wy - qx * wz),
            h * (-qy * wx + qx * wy + qw * wz),
            h * (-qx * wx - qy * wy - qz * wz)]


def _skew(a):
    return sm.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


class _QuaternionJoint(Joint):
    """The shared parts: the quaternion's rotation and rates, the angular
    velocity in the child interframe's axes, the motion subspace."""

    n_position = 0          # 3 for the free joint

    def __init__(self, name, parent, child, coordinates=None, speeds=None, parent_point=None,
                 child_point=None, parent_interframe=None, child_interframe=None):
        super().__init__(name, parent, child, coordinates, speeds, parent_point, child_point,
                         parent_interframe, child_interframe)

    def __str__(self):
        return f"{type(self).__name__}: {self.name}  parent: {self.parent}  child: {self.child}"

    def _generate_coordinates(self, coordinates):
        return self._fill_coordinate_list(coordinates, self.n_position + 4, "q")

    def _generate_speeds(self, speeds):
        return self._fill_coordinate_list(speeds, self.n_position + 3, "u")

    def _quaternion(self):
        return list(self.coordinates[self.n_position:])

    def _omega(self):
        return list(self.speeds[self.n_position:])

    def rotation(self):
        """The child interframe's axes in the parent interframe's (3 x 3)."""
        return quaternion_matrix(*self._quaternion())

    def _generate_kdes(self):
        t = time_symbol()
        q, u, n = self.coordinates, self.speeds, self.n_position
        rows = []
        if n:
            pdot = self.rotation() * sm.Matrix(u[:3])
            rows += [q[i].diff(t) - pdot[i] for i in range(3)]
        rates = quaternion_rates(*self._quaternion(), *self._omega())
        rows += [q[n + i].diff(t) - rates[i] for i in range(4)]
        return sm.Matrix(rows)

    def _orient_frames(self):
        # the angular velocity is the speeds' (_set_angular_velocity): sympy's
        # own, from the rotation's derivative, would take seconds
        orient_explicit_without_rates(self.child_interframe, self.parent_interframe,
                                      self.rotation())

    def _set_angular_velocity(self):
        C = self.child_interframe
        wx, wy, wz = self._omega()
        C.set_ang_vel(self.parent_interframe, wx * C.x + wy * C.y + wz * C.z)

    def motion_subspace(self):
        """(S, None): the child's angular velocity and the velocity of its
        mass centre relative to the parent (derivative in the parent frame),
        both in the child body's axes, as ``S u`` (6 x nu, angular rows
        first); S is constant in the body's axes, so its velocity-product
        part is None. The protocol of :mod:`gen.intake.recursive`."""
        body = self.child.frame
        Cm = sm.Matrix(body.dcm(self.child_interframe))      # body <- interframe, constant
        rcc = self.child.masscenter.pos_from(self.child_point).to_matrix(body)
        n = self.n_position
        S = sm.zeros(6, n + 3)
        S[:3, n:] = Cm
        S[3:, n:] = -_skew(rcc) * Cm
        if n:
            S[3:, :3] = Cm
        return S, None


class FreeJoint(_QuaternionJoint):
    """A free (six-dof) joint: the child moves freely in the parent.

    Parameters
    ----------
    name : str
    parent, child : RigidBody
    coordinates : list of 7 dynamicsymbols, optional
        ``[x, y, z, qx, qy, qz, qw]`` (module docstring); made when None.
    speeds : list of 6 dynamicsymbols, optional
        ``[vx, vy, vz, wx, wy, wz]`` in the child interframe's axes.
    parent_point, child_point, parent_interframe, child_interframe
        As for sympy's joints (the child's interframe must be fixed in it).
    """

    n_position = 3

    def _set_linear_velocity(self):
        P, C = self.parent_interframe, self.child_interframe
        x, y, z = self.coordinates[:3]
        vx, vy, vz = self.speeds[:3]
        self.child_point.set_pos(self.parent_point, x * P.x + y * P.y + z * P.z)
        self.parent_point.set_vel(self._parent_frame, 0)
        self.child_point.set_vel(self._parent_frame, vx * C.x + vy * C.y + vz * C.z)
        self.child.masscenter.v2pt_theory(self.child_point, self._parent_frame,
                                          self._child_frame)


class BallJoint(_QuaternionJoint):
    """A ball (three-dof rotation) joint about the coincident joint points.

    Parameters
    ----------
    name : str
    parent, child : RigidBody
    coordinates : list of 4 dynamicsymbols, optional
        ``[qx, qy, qz, qw]``; made when None.
    speeds : list of 3 dynamicsymbols, optional
        ``[wx, wy, wz]`` in the child interframe's axes.
    parent_point, child_point, parent_interframe, child_interframe
        As for sympy's joints.
    """

    def _set_linear_velocity(self):
        self.child_point.set_pos(self.parent_point, 0)
        self.parent_point.set_vel(self._parent_frame, 0)
        self.child_point.set_vel(self._child_frame, 0)
        self.child.masscenter.v2pt_theory(self.parent_point, self._parent_frame,
                                          self._child_frame)

