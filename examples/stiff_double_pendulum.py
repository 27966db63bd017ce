"""A stiff model: a double pendulum of two uniform rods whose elbow joint
carries a stiff torsional spring-damper, so that the pair swings almost as
one rigid body (slow: the pendulum's own frequency) while the elbow rings
about 1e4 times faster, critically damped. An explicit method must resolve
that fast, decaying mode for stability over the whole run; a stiff method
(method="rodas4") steps at the pace of the slow motion.

    python examples/stiff_double_pendulum.py     # DOPRI5 vs RODAS4 vs SciPy Radau

States: q1 (shoulder angle from the downward vertical), q2 (elbow angle,
relative), u1 = q1', u2 = q2'. Constants: m, l (each rod), g, k, c (the
elbow's stiffness and damping).
"""
import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen


def derive():
    """(KanesMethod, symbols) of the double pendulum with an elastic elbow."""
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    m, l, g, k, c = sm.symbols("m l g k c", positive=True)
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = A.orientnew("B", "Axis", [q2, A.z])
    A.set_ang_vel(N, u1 * N.z)
    B.set_ang_vel(A, u2 * A.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    Ao = O.locatenew("Ao", -l / 2 * A.y)       # rod centres, hanging along -y
    E = O.locatenew("E", -l * A.y)             # the elbow
    Bo = E.locatenew("Bo", -l / 2 * B.y)
    for P, F in ((Ao, A), (E, A), (Bo, B)):
        P.v2pt_theory(O if P is not Bo else E, N, F)
    I = m * l ** 2 / 12
    rodA = me.RigidBody("rodA", Ao, A, m, (me.inertia(A, 0, 0, I), Ao))
    rodB = me.RigidBody("rodB", Bo, B, m, (me.inertia(B, 0, 0, I), Bo))
    tau = -k * q2 - c * u2                     # the elbow's spring-damper, on B, reacting on A
    loads = [(Ao, -m * g * N.y), (Bo, -m * g * N.y), (B, tau * N.z), (A, -tau * N.z)]
    km = me.KanesMethod(N, q_ind=[q1, q2], u_ind=[u1, u2], kd_eqs=[q1.diff() - u1, q2.diff() - u2])
    km.kanes_equations([rodA, rodB], loads)
    return km, dict(q1=q1, q2=q2, u1=u1, u2=u2, m=m, l=l, g=g, k=k, c=c)


def constants(ratio=1e4, m=1.0, l=1.0, g=9.81):
    """The constants for an elbow ringing `ratio` times faster than the pair
    swings as one rigid rod of length 2 l (omega_slow = sqrt(3 g / (2 (2 l)))),
    critically damped about the outer rod's inertia about the elbow
    (J = m l^2 / 3): k = J omega_fast^2, c = 2 J omega_fast."""
    w_slow = np.sqrt(3 * g / (2 * 2 * l))
    w_fast = ratio * w_slow
    J = m * l ** 2 / 3
    return {"m": m, "l": l, "g": g, "k": J * w_fast ** 2, "c": 2 * J * w_fast}


def model(name="stiff_double_pendulum", ratio=1e4):
    km, s = derive()
    vals = constants(ratio)
    return gen.Model.from_kanes(km, constants={s[k]: v for k, v in vals.items()}, name=name)


def main():
    import time
    sim = gen.compile(model())
    x0 = np.array([1.0, 0.0, 0.0, 0.0])
    for method, rtol in (("dopri5", 1e-6), ("rodas4", 1e-6)):
        t0 = time.perf_counter()
        sol = sim.simulate(x0, 2.0, 0.01, method=method, rtol=rtol, atol=rtol, max_steps=10 ** 7)
        t, X, st = sol.t, sol.x, sol.stats
        print(f"{method:7s} rtol {rtol:g}: x(2) = {X[-1]}, {st['n_rhs']} rhs, {st['n_jac']} "
              f"Jacobians, {time.perf_counter() - t0:.3f} s")


if __name__ == "__main__":
    main()
