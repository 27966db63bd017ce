"""A quadrotor: one rigid body with ZYX Euler angles (yaw psi, pitch theta,
roll phi) as coordinates, body rates (p, q, r) and inertial velocities as
speeds, thrust T along the body z axis and body torques tau1..3 as inputs.

kinematics="sympy" writes the kinematic equations the way sympy users do,
w_B . B_i - u_i = 0 with w_B taken from the orientation, and leaves the
Euler-rate matrix to the generator (KanesMethod's own explicit solve of
those equations is 0/0 at hover for this coordinate order; eomgen solves
them numerically at run time). kinematics="euler" writes the textbook
Euler-rate equations phi' = p + sin(phi) tan(theta) q + ... by hand.

    model()                                  # sympy's kinematics (explicit solve)
    model(explicit_kinematics=False)         # the same, KanesMethod told not to solve
    model(kinematics="euler")                # hand-written Euler rates
Hover: x = 0, r = [m g, 0, 0, 0].
"""
import sympy as sm
from sympy.physics import mechanics as me

import gen

DEFAULTS = {"m": 1.2, "g": 9.81, "Ixx": 0.02, "Iyy": 0.025, "Izz": 0.04}


def derive(kinematics="sympy", explicit_kinematics=True):
    t = me.dynamicsymbols._t
    psi, theta, phi, x, y, z = me.dynamicsymbols("psi theta phi x y z")
    p, q, r, vx, vy, vz = me.dynamicsymbols("p q r vx vy vz")
    T, tau1, tau2, tau3 = me.dynamicsymbols("T tau1 tau2 tau3")
    m, g, Ixx, Iyy, Izz = sm.symbols("m g Ixx Iyy Izz")
    N = me.ReferenceFrame("N")
    B = me.ReferenceFrame("B")
    B.orient_body_fixed(N, (psi, theta, phi), "zyx")
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y + z * N.z)
    if kinematics == "sympy":
        w = B.ang_vel_in(N)
        kd = [w.dot(B.x) - p, w.dot(B.y) - q, w.dot(B.z) - r]
    elif kinematics == "euler":
        kd = [phi.diff(t) - (p + sm.sin(phi) * sm.tan(theta) * q + sm.cos(phi) * sm.tan(theta) * r),
              theta.diff(t) - (sm.cos(phi) * q - sm.sin(phi) * r),
              psi.diff(t) - (sm.sin(phi) / sm.cos(theta) * q + sm.cos(phi) / sm.cos(theta) * r)]
    else:
        raise ValueError(f"kinematics must be 'sympy' or 'euler', got {kinematics!r}")
    kd += [x.diff(t) - vx, y.diff(t) - vy, z.diff(t) - vz]
    B.set_ang_vel(N, p * B.x + q * B.y + r * B.z)
    C.set_vel(N, vx * N.x + vy * N.y + vz * N.z)
    body = me.RigidBody("body", C, B, m, (me.inertia(B, Ixx, Iyy, Izz), C))
    loads = [(C, -m * g * N.z + T * B.z), (B, tau1 * B.x + tau2 * B.y + tau3 * B.z)]
    km = me.KanesMethod(N, q_ind=[psi, theta, phi, x, y, z], u_ind=[p, q, r, vx, vy, vz],
                        kd_eqs=kd, explicit_kinematics=explicit_kinematics)
    km.kanes_equations([body], loads)
    syms = dict(m=m, g=g, Ixx=Ixx, Iyy=Iyy, Izz=Izz)
    return km, syms, [T, tau1, tau2, tau3]


def model(kinematics="sympy", explicit_kinematics=True, name="quadrotor", **values):
    km, s, inputs = derive(kinematics, explicit_kinematics)
    vals = {**DEFAULTS, **values}
    return gen.Model.from_kanes(km, constants={s[k]: v for k, v in vals.items()},
                                inputs=inputs, name=name)


def hover_input(values=None):
    vals = {**DEFAULTS, **(values or {})}
    return [vals["m"] * vals["g"], 0.0, 0.0, 0.0]
