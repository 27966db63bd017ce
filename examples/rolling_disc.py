"""A thin uniform disc rolling without slipping on a horizontal plane:
two nonholonomic constraints (the contact point of the disc has no
horizontal velocity), a drive torque T about the disc's axle as input.

q = [yaw q1, lean q2, spin q3, contact x, y]; u = q' with
u = [u1, u2, u3 | u4, u5]: the contact point's rates u4, u5 are the
dependent speeds. Upright rolling at spin rate Omega is stable for
Omega^2 > g / (3 r) (thin disc, I_axis = m r^2 / 2, I_diam = m r^2 / 4).
"""
import sympy as sm
from sympy.physics import mechanics as me

import gen

DEFAULTS = {"m": 1.0, "r": 0.3, "g": 9.81}


def derive():
    q1, q2, q3, x, y = me.dynamicsymbols("q1 q2 q3 x y")
    u1, u2, u3, u4, u5 = me.dynamicsymbols("u1:6")
    T = me.dynamicsymbols("T")
    m, r, g = sm.symbols("m r g")
    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])      # heading
    L = Y.orientnew("L", "Axis", [q2, Y.x])      # lean
    R = L.orientnew("R", "Axis", [q3, L.y])      # spin about the axle L.y
    qd = {q1.diff(): u1, q2.diff(): u2, q3.diff(): u3, x.diff(): u4, y.diff(): u5}
    R.set_ang_vel(N, R.ang_vel_in(N).subs(qd))
    L.set_ang_vel(N, L.ang_vel_in(N).subs(qd))
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)      # contact point (a point of the plane path)
    Dmc = C.locatenew("Dmc", r * L.z)            # disc centre
    Dmc.set_vel(N, Dmc.pos_from(O).dt(N).subs(qd))
    # material point of the disc at the contact: no slip in the plane
    v_contact = Dmc.vel(N) + R.ang_vel_in(N).cross(C.pos_from(Dmc))
    f_v = sm.Matrix([v_contact.dot(Y.x), v_contact.dot(Y.y)]).applyfunc(sm.expand)
    I_disc = me.inertia(L, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4)
    disc = me.RigidBody("disc", Dmc, R, m, (I_disc, Dmc))
    kde = [q1.diff() - u1, q2.diff() - u2, q3.diff() - u3, x.diff() - u4, y.diff() - u5]
    KM = me.KanesMethod(N, q_ind=[q1, q2, q3, x, y], u_ind=[u1, u2, u3],
                        u_dependent=[u4, u5], kd_eqs=kde, velocity_constraints=f_v)
    loads = [(Dmc, -m * g * N.z), (R, T * L.y), (L, -T * L.y)]
    KM.kanes_equations([disc], loads)
    energy = disc.kinetic_energy(N).subs(qd) + m * g * r * sm.cos(q2)
    return KM, dict(q=(q1, q2, q3, x, y), u=(u1, u2, u3, u4, u5), T=T, m=m, r=r, g=g,
                    energy=energy, f_v=f_v)


def model(name="rolling_disc", **over):
    KM, s = derive()
    vals = dict(DEFAULTS, **over)
    return gen.Model.from_kanes(KM, constants={s[k]: v for k, v in vals.items()},
                                inputs=[s["T"]], name=name, energy=s["energy"])
