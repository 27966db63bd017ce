"""A Chaplygin sleigh on an incline: a rigid body on a knife edge (no
lateral slip at the blade: one nonholonomic constraint) with a force F
along the blade and a steering torque tau as inputs.

q = [x, y, theta] (blade contact point, heading), u = [u_x, u_theta | u_y]:
the lateral constraint -sin(theta) u_x + cos(theta) u_y = 0 makes u_y
dependent (singular partition where cos(theta) = 0).
"""
from sympy import symbols
from sympy.physics.mechanics import (KanesMethod, Point, ReferenceFrame, RigidBody,
                                     dynamicsymbols, inertia)

import gen

DEFAULTS = {"m": 2.0, "I": 0.3, "d": 0.4, "g": 9.81, "alpha": 0.2}


def derive():
    x, y, th = dynamicsymbols("x y theta")
    ux, uy, uth = dynamicsymbols("u_x u_y u_theta")
    F, tau = dynamicsymbols("F tau")
    m, I, d, g, alpha = symbols("m I d g alpha")
    N = ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    B.set_ang_vel(N, uth * N.z)
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, ux * N.x + uy * N.y)
    Gc = P.locatenew("G", d * B.x)
    Gc.v2pt_theory(P, N, B)
    body = RigidBody("body", Gc, B, m, (inertia(B, 0, 0, I), Gc))
    kde = [x.diff() - ux, y.diff() - uy, th.diff() - uth]
    f_v = [P.vel(N).dot(B.y)]
    KM = KanesMethod(N, q_ind=[x, y, th], u_ind=[ux, uth], u_dependent=[uy], kd_eqs=kde,
                     velocity_constraints=f_v)
    loads = [(Gc, m * g * alpha * N.x), (P, F * B.x), (B, tau * N.z)]
    KM.kanes_equations([body], loads)
    syms = dict(x=x, y=y, th=th, ux=ux, uy=uy, uth=uth, F=F, tau=tau, m=m, I=I, d=d, g=g,
                alpha=alpha)
    return KM, syms


def model(name="sleigh", **over):
    KM, s = derive()
    vals = dict(DEFAULTS, **over)
    return gen.Model.from_kanes(KM, constants={s[k]: v for k, v in vals.items()},
                                inputs=[s["F"], s["tau"]], name=name)
