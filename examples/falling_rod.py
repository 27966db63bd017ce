"""A rod falling onto the ground on one end: a planar rigid body (x, y,
theta) with an impact on its lower end.

    python examples/falling_rod.py

The gap is the height of the end, y - (L/2) sin(theta). At the impact the C
runtime solves the impulse with the mass matrix and the gap's gradient: the
end's normal speed becomes -e times its value, and the centre of mass and the
rotation change together (tests/features/test_hybrid.py checks them against the
impulse equations solved by hand). With e = 1 the kinetic energy is kept.
"""
import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen

MASS, LENGTH, G = 2.0, 1.5, 9.81


def model(e=0.5, name="falling_rod"):
    x, y, th, vx, vy, w = me.dynamicsymbols("x y theta vx vy omega")
    m, g, L = sm.symbols("m g L")
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    B.set_ang_vel(N, w * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)
    C.set_vel(N, vx * N.x + vy * N.y)
    rod = me.RigidBody("rod", C, B, m, (me.inertia(B, 0, 0, m * L**2 / 12), C))
    km = me.KanesMethod(N, [x, y, th], [vx, vy, w],
                        kd_eqs=[x.diff() - vx, y.diff() - vy, th.diff() - w])
    km.kanes_equations([rod], [(C, -m * g * N.y)])
    return gen.Model.from_kanes(km, constants={m: MASS, g: G, L: LENGTH}, name=name,
                                hybrid={"end": gen.Impact(y - L / 2 * sm.sin(th),
                                                          restitution=e)})


def main():
    x0 = [0.0, 1.0, 0.5, 0.3, 0.0, 1.2]
    ke = lambda s: 0.5 * MASS * (s[3]**2 + s[4]**2) + MASS * LENGTH**2 / 24 * s[5]**2  # noqa: E731
    for e in (0.0, 0.5, 1.0):
        sim = gen.compile(model(e, name=f"falling_rod_{int(10 * e)}"))
        sol = sim.simulate(x0, 0.6, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
        ev = sol.events[0]
        print(f"e = {e}: impact at t = {ev.t:.12f}, theta = {ev.x[2]:.6f}")
        print(f"   (vx, vy, omega) before {np.round(ev.x[3:], 6)} after {np.round(ev.x_after[3:], 6)}")
        print(f"   kinetic energy {ke(ev.x):.12f} -> {ke(ev.x_after):.12f}")


if __name__ == "__main__":
    main()
