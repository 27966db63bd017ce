"""A bouncing ball: an impact with restitution e, simulated in C.

    python examples/bouncing_ball.py

``gen.Impact(y, restitution=e)`` declares the ground: when the gap y reaches
zero moving down, the speed jumps to -e times its value (the impulse solved in
the C runtime); the impacts are in ``sol.events`` with the states before and
after. The bounces pile up towards the Zeno time t_Z = t_1 + 2 e v_1 /
(g (1 - e)); once an impact is slower than ``rest_speed`` the contact is held
(the ball rests on the ground, its force ``m g`` pushing) and the steps grow:
no stalled step.

The compliant alternative, a Hunt-Crossley contact force written with
``Piecewise`` and integrated by RODAS4, is ``compliant_model()``.
"""
import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen

G = 9.81


def _ball(contact_force=None):
    y, v = me.dynamicsymbols("y v")
    m, g = sm.symbols("m g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", y * N.y)
    P.set_vel(N, v * N.y)
    km = me.KanesMethod(N, [y], [v], kd_eqs=[y.diff() - v])
    force = -m * g + (contact_force(y, v) if contact_force else 0)
    km.kanes_equations([me.Particle("ball", P, m)], [(P, force * N.y)])
    return km, y, v, m, g


def model(e=0.8):
    """The ball with the ground as an impact of restitution e."""
    km, y, v, m, g = _ball()
    return gen.Model.from_kanes(km, constants={m: 1.0, g: G}, name="bouncing_ball",
                                hybrid={"ground": gen.Impact(y, restitution=e)})


def compliant_model(k=1e5, alpha=1.5):
    """The ground as a Hunt-Crossley force k p^(3/2) (1 + alpha p') on the
    penetration p = -y (zero in the air, and never pulling: Max), stiff:
    integrate it with method="rodas4"."""
    kk, al = sm.symbols("k alpha")

    def force(y, v):
        p = -y
        f = kk * p**sm.Rational(3, 2) * (1 - al * v)
        return sm.Piecewise((sm.Max(f, 0), p > 0), (0, True))
    km, y, v, m, g = _ball(force)
    return gen.Model.from_kanes(km, constants={m: 1.0, g: G, kk: k, al: alpha},
                                name="bouncing_ball_hc")


def main():
    e, h0 = 0.8, 1.0
    sim = gen.compile(model(e))
    sol = sim.simulate([h0, 0.0], 6.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
    t1, v1 = np.sqrt(2 * h0 / G), np.sqrt(2 * G * h0)
    t_zeno = t1 + 2 * e * v1 / (G * (1 - e))
    print(f"{len(sol.events)} impacts; the first five:")
    for ev in sol.events[:5]:
        print(f"  {ev.name} t = {ev.t:.15f}  v before {ev.x[1]:+.6f}  after {ev.x_after[1]:+.6f}")
    print(f"last impact t = {sol.events[-1].t:.12f}, Zeno time t_Z = {t_zeno:.12f}")
    print(f"at t = {sol.t[-1]}: y = {sol.x[-1, 0]:.3g}, v = {sol.x[-1, 1]:.3g}, "
          f"{sol.stats['n_steps']} steps")
    hc = gen.compile(compliant_model())
    sol = hc.simulate([h0, 0.0], 6.0, 0.01, method="rodas4", rtol=1e-6, atol=1e-9)
    print(f"compliant (Hunt-Crossley, RODAS4): y(6) = {sol.x[-1, 0]:.6g} (static "
          f"{-(G / 1e5) ** (2 / 3):.6g}), {sol.stats['n_steps']} steps")
    sol = hc.simulate([h0, 0.0], 1000.0, 1000.0, method="rodas4", rtol=1e-6, atol=1e-9)
    print(f"  to t = 1000: {sol.stats['n_steps']} steps (at rest, the steps grow)")


if __name__ == "__main__":
    main()
