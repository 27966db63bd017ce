"""The simplest walking model (Garcia, Chatterjee, Ruina and Coleman 1998):
its period-one gait by Newton's method on the stride map, and its stability.

    python examples/simplest_walker.py

A hip mass M and a small foot mass m = beta M on massless legs of length l,
walking down a slope gamma (g = l = 1). theta is the stance leg's angle from
the slope normal, phi the angle between the legs. The heel strike is a
``gen.Reset``: when phi - 2 theta crosses zero upwards (the swing foot reaches
the slope; the scuffing at mid-stance crosses downwards), the legs swap and
the speeds jump by Garcia's map. The stride map takes the state after one
heel strike to the state after the next; its fixed point is the gait
(published: theta = 0.2003, theta' = -0.1998 at gamma = 0.009) and the
eigenvalues of its Jacobian, inside the unit circle, make it stable.
"""
import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen


def model(gamma=0.009, beta=1e-6, name="simplest_walker"):
    th, ph = me.dynamicsymbols("theta phi")
    thd, phd = th.diff(), ph.diff()
    Mh, mf, g, l, gam = sm.symbols("M_h m_f g l gamma")
    t = me.dynamicsymbols._t
    hip = sm.Matrix([-l * sm.sin(th), l * sm.cos(th)])
    foot = hip + sm.Matrix([l * sm.sin(th - ph), -l * sm.cos(th - ph)])
    ag = sm.Matrix([g * sm.sin(gam), -g * sm.cos(gam)])     # gravity in the slope's frame
    vh, vf = hip.diff(t), foot.diff(t)
    T = (Mh * vh.dot(vh) + mf * vf.dot(vf)) / 2
    V = -(Mh * ag.dot(hip) + mf * ag.dot(foot))
    lm = me.LagrangesMethod(T - V, [th, ph])
    lm.form_lagranges_equations()
    c2 = sm.cos(2 * th)
    strike = gen.Reset(ph - 2 * th, {th: -th, ph: -2 * th, thd: c2 * thd,
                                     phd: c2 * (1 - c2) * thd}, direction=1)
    return gen.Model.from_lagrange(
        lm, constants={Mh: 1.0, mf: beta, g: 1.0, l: 1.0, gam: gamma}, name=name,
        hybrid={"heelstrike": strike})


def start(z):
    """The state just after a heel strike from (theta, theta')."""
    a, ad = z
    return np.array([a, 2 * a, ad, (1 - np.cos(2 * a)) * ad])


def stride_map(sim):
    def stride(z):
        sol = sim.simulate(start(z), 4.5, 4.5, method="dopri5", rtol=1e-12, atol=1e-12)
        ev = [e for e in sol.events if e.name == "heelstrike"][0]
        return np.array([ev.x_after[0], ev.x_after[2]])
    return stride


def fixed_point(stride, z0=(0.2, -0.2), h=1e-7):
    z = np.array(z0, dtype=float)
    for _ in range(10):
        J = np.column_stack([(stride(z + d) - stride(z - d)) / (2 * h) for d in np.eye(2) * h])
        step = np.linalg.solve(J - np.eye(2), stride(z) - z)
        z -= step
        if np.max(np.abs(step)) < 1e-13:
            break
    J = np.column_stack([(stride(z + d) - stride(z - d)) / (2 * h) for d in np.eye(2) * h])
    return z, J


def main():
    sim = gen.compile(model())
    z, J = fixed_point(stride_map(sim))
    print(f"fixed point: theta = {z[0]:.6f}, theta' = {z[1]:.6f} (published 0.2003, -0.1998)")
    lam = np.linalg.eigvals(J)
    print(f"stride map eigenvalues {np.round(lam, 6)}, |lambda| = {np.abs(lam).round(6)}: "
          + ("stable" if np.max(np.abs(lam)) < 1 else "unstable"))
    sol = sim.simulate(start(z), 40.0, 0.05, method="dopri5", rtol=1e-10, atol=1e-12)
    print(f"{len(sol.events)} steps in 40 time units: " +
          ", ".join(f"{e.t:.4f}" for e in sol.events[:4]) + ", ...")


if __name__ == "__main__":
    main()
