"""The seed document's nonminimal-coordinates pendulum, derived exactly as
the document does, with Kane's and with Lagrange's method.

Model-file convention: `model()` returns a gen.Model (Kane's);
`kane_model()` and `lagrange_model()` return either one. The raw sympy
objects come from `derive_kane()` / `derive_lagrange()`.
"""
from sympy import Matrix, atan, solve, symbols
from sympy.physics.mechanics import (KanesMethod, LagrangesMethod, Lagrangian, Particle,
                                     Point, ReferenceFrame, dynamicsymbols)

import gen

DEFAULTS = {"L": 1.0, "m": 1.0, "g": 9.81}


def derive_kane():
    """Kane's method: q = [q2 (ind), q1 (dep)], u = [u2 (ind), u1 (dep)]."""
    q1, q2 = dynamicsymbols('q1:3')
    q1d, q2d = dynamicsymbols('q1:3', level=1)
    u1, u2 = dynamicsymbols('u1:3')
    L, m, g, t = symbols('L, m, g, t')
    N = ReferenceFrame('N')
    pN = Point('N*')
    pN.set_vel(N, 0)
    theta1 = atan(q2/q1)
    A = N.orientnew('A', 'axis', [theta1, N.z])
    P = pN.locatenew('P1', q1*N.x + q2*N.y)
    pP = Particle('pP', P, m)
    kde = Matrix([q1d - u1, q2d - u2])
    dq_dict = solve(kde, [q1d, q2d])
    P.set_vel(N, P.pos_from(pN).dt(N).subs(dq_dict))
    f_c = Matrix([P.pos_from(pN).magnitude() - L])
    f_v = Matrix([P.vel(N).express(A).dot(A.x)])
    f_v.simplify()
    R = m*g*N.x
    KM = KanesMethod(N, q_ind=[q2], u_ind=[u2], q_dependent=[q1], u_dependent=[u1],
                     configuration_constraints=f_c, velocity_constraints=f_v, kd_eqs=kde)
    KM.kanes_equations([pP], [(P, R)])
    syms = dict(q1=q1, q2=q2, u1=u1, u2=u2, q1d=q1d, q2d=q2d, L=L, m=m, g=g, t=t,
                f_c=f_c, f_v=f_v, frame=N, point=P, particle=pP)
    return KM, syms


def derive_lagrange():
    """Lagrange's method: q = [q1, q2], holonomic constraint q1^2+q2^2-L^2."""
    q1, q2 = dynamicsymbols('q1:3')
    q1d, q2d = dynamicsymbols('q1:3', level=1)
    L, m, g, t = symbols('L, m, g, t')
    N = ReferenceFrame('N')
    pN = Point('N*')
    pN.set_vel(N, 0)
    theta1 = atan(q2/q1)
    N.orientnew('A', 'axis', [theta1, N.z])
    P = pN.locatenew('P1', q1*N.x + q2*N.y)
    P.set_vel(N, P.pos_from(pN).dt(N))
    pP = Particle('pP', P, m)
    f_c = Matrix([q1**2 + q2**2 - L**2])
    R = m*g*N.x
    Lag = Lagrangian(N, pP)
    LM = LagrangesMethod(Lag, [q1, q2], hol_coneqs=f_c, forcelist=[(P, R)], frame=N)
    LM.form_lagranges_equations()
    syms = dict(q1=q1, q2=q2, q1d=q1d, q2d=q2d, L=L, m=m, g=g, t=t, f_c=f_c,
                frame=N, point=P, particle=pP)
    return LM, syms




def kane_model(L=DEFAULTS["L"], m=DEFAULTS["m"], g=DEFAULTS["g"], name="pendulum_kane"):
    KM, s = derive_kane()
    energy = (s["m"] * (s["u1"]**2 + s["u2"]**2) / 2 - s["m"] * s["g"] * s["q1"])
    return gen.Model.from_kanes(KM, constants={s["L"]: L, s["m"]: m, s["g"]: g}, name=name,
                                energy=energy)


def lagrange_model(L=DEFAULTS["L"], m=DEFAULTS["m"], g=DEFAULTS["g"], name="pendulum_lagrange"):
    LM, s = derive_lagrange()
    energy = (s["m"] * (s["q1d"]**2 + s["q2d"]**2) / 2 - s["m"] * s["g"] * s["q1"])
    return gen.Model.from_lagrange(LM, q_ind=[s["q2"]], qd_ind=[s["q2d"]], q_dep=[s["q1"]],
                                   qd_dep=[s["q1d"]], constants={s["L"]: L, s["m"]: m, s["g"]: g},
                                   name=name, energy=energy)


def model():
    return kane_model()
