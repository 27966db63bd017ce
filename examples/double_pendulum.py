"""A planar double pendulum: two point masses on massless rods, minimal
coordinates (absolute angles from the downward vertical), q' = u.

Small oscillations about hanging rest, for equal masses and lengths, have
the normal-mode frequencies omega^2 = (g / l) (2 -+ sqrt(2)).
"""
import sympy as sm
from sympy.physics import mechanics as me

import gen

DEFAULTS = {"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 1.0, "g": 9.81}


def derive():
    q1, q2 = me.dynamicsymbols("q1 q2")
    u1, u2 = me.dynamicsymbols("u1 u2")
    m1, m2, l1, l2, g = sm.symbols("m1 m2 l1 l2 g")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = N.orientnew("B", "Axis", [q2, N.z])
    A.set_ang_vel(N, u1 * N.z)
    B.set_ang_vel(N, u2 * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P1 = O.locatenew("P1", -l1 * A.y)
    P1.v2pt_theory(O, N, A)
    P2 = P1.locatenew("P2", -l2 * B.y)
    P2.v2pt_theory(P1, N, B)
    parts = [me.Particle("p1", P1, m1), me.Particle("p2", P2, m2)]
    loads = [(P1, -m1 * g * N.y), (P2, -m2 * g * N.y)]
    KM = me.KanesMethod(N, q_ind=[q1, q2], u_ind=[u1, u2],
                        kd_eqs=[q1.diff() - u1, q2.diff() - u2])
    KM.kanes_equations(parts, loads)
    energy = (sum(p.kinetic_energy(N) for p in parts)
              + g * (m1 * P1.pos_from(O).dot(N.y) + m2 * P2.pos_from(O).dot(N.y)))
    energy = energy.subs({q1.diff(): u1, q2.diff(): u2})
    return KM, dict(q1=q1, q2=q2, u1=u1, u2=u2, m1=m1, m2=m2, l1=l1, l2=l2, g=g,
                    energy=energy)


def model(name="double_pendulum", **over):
    KM, s = derive()
    vals = dict(DEFAULTS, **over)
    return gen.Model.from_kanes(KM, constants={s[k]: v for k, v in vals.items()}, name=name,
                                energy=s["energy"])
