"""A planar four-bar linkage hanging under gravity: a closed kinematic loop.

Ground pivots O = (0, 0) and D = (d, 0); crank OA (length a, angle q1),
coupler AB (length b, angle q2), rocker DB (length c, angle q3), all angles
absolute from N.x. Each link is a uniform bar (mass m_i, centroidal inertia
m_i L_i^2 / 12). Gravity acts along -N.y.

Loop closure (two configuration constraints):
    a cos q1 + b cos q2 - c cos q3 - d = 0
    a sin q1 + b sin q2 - c sin q3     = 0
q = [q1 | q2, q3], u = [u1 | u2, u3] (u = q'): one degree of freedom,
two dependent coordinates and two dependent speeds.
"""
import sympy as sm
from sympy.physics import mechanics as me

import gen

DEFAULTS = {"a": 1.0, "b": 1.2, "c": 0.9, "d": 1.5,
            "m_a": 1.0, "m_b": 1.5, "m_c": 0.8, "g": 9.81}
# a configuration on the hanging branch (links below the ground line),
# close to the stable equilibrium for DEFAULTS
HANGING = {"q1": -1.2, "q2": -0.15, "q3": -1.45}


def derive():
    q1, q2, q3 = me.dynamicsymbols("q1:4")
    u1, u2, u3 = me.dynamicsymbols("u1:4")
    a, b, c, d, ma, mb, mc, g = sm.symbols("a b c d m_a m_b m_c g")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = N.orientnew("B", "Axis", [q2, N.z])
    C = N.orientnew("C", "Axis", [q3, N.z])
    A.set_ang_vel(N, u1 * N.z)
    B.set_ang_vel(N, u2 * N.z)
    C.set_ang_vel(N, u3 * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    D = O.locatenew("D", d * N.x)
    D.set_vel(N, 0)
    PA = O.locatenew("PA", a * A.x)             # crank tip
    PA.v2pt_theory(O, N, A)
    PB = PA.locatenew("PB", b * B.x)            # coupler tip (== rocker tip)
    PB.v2pt_theory(PA, N, B)
    GA = O.locatenew("GA", a / 2 * A.x)
    GA.v2pt_theory(O, N, A)
    GB = PA.locatenew("GB", b / 2 * B.x)
    GB.v2pt_theory(PA, N, B)
    GC = D.locatenew("GC", c / 2 * C.x)
    GC.v2pt_theory(D, N, C)
    bodies = [
        me.RigidBody("crank", GA, A, ma, (me.inertia(A, 0, 0, ma * a**2 / 12), GA)),
        me.RigidBody("coupler", GB, B, mb, (me.inertia(B, 0, 0, mb * b**2 / 12), GB)),
        me.RigidBody("rocker", GC, C, mc, (me.inertia(C, 0, 0, mc * c**2 / 12), GC)),
    ]
    loads = [(GA, -ma * g * N.y), (GB, -mb * g * N.y), (GC, -mc * g * N.y)]
    loop = PB.pos_from(O) - (D.pos_from(O) + c * C.x)
    f_c = sm.Matrix([loop.dot(N.x), loop.dot(N.y)])
    qd = {q1.diff(): u1, q2.diff(): u2, q3.diff(): u3}
    f_v = f_c.diff(me.dynamicsymbols._t).subs(qd)
    kde = [q1.diff() - u1, q2.diff() - u2, q3.diff() - u3]
    KM = me.KanesMethod(N, q_ind=[q1], u_ind=[u1], q_dependent=[q2, q3],
                        u_dependent=[u2, u3], kd_eqs=kde,
                        configuration_constraints=f_c, velocity_constraints=f_v)
    KM.kanes_equations(bodies, loads)
    energy = sum(bd.kinetic_energy(N) for bd in bodies).subs(qd)
    energy += g * (ma * GA.pos_from(O).dot(N.y) + mb * GB.pos_from(O).dot(N.y)
                   + mc * GC.pos_from(O).dot(N.y))
    syms = dict(q=(q1, q2, q3), u=(u1, u2, u3), a=a, b=b, c=c, d=d, m_a=ma, m_b=mb,
                m_c=mc, g=g, f_c=f_c, energy=energy)
    return KM, syms


def model(name="four_bar", **over):
    KM, s = derive()
    vals = dict(DEFAULTS, **over)
    return gen.Model.from_kanes(KM, constants={s[k]: v for k, v in vals.items()}, name=name,
                                energy=s["energy"])
