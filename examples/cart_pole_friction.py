"""A cart-pole whose cart slides with Coulomb friction on its normal force
(Florian, 'Correct equations for the dynamics of the cart-pole system',
2007): the swinging pole presses the cart onto the track and lifts it, so
the normal force N, and with it the friction -mu N sign(v), changes with
the pole's acceleration, while the cart's acceleration depends on the
friction. eomgen solves u' and N together, as one linear system per
evaluation of the right-hand side, in the generated C:

    [M, -G; C, H] [u'; N] = [f; -g0]

(the cart's vertical speed ua is an auxiliary speed that carries N; G is
N's coefficient in the motion, -mu sign(v) for the cart; C and H its
auxiliary equation). The sign is smoothed, sign(v) ~ tanh(v / v_eps), so
that the right-hand side stays smooth where the cart stops.

    python examples/cart_pole_friction.py           # simulate, print N
    eomgen simulate examples/cart_pole_friction.py --t-end 2 --x0 theta=2.5 \\
        --csv cart.csv                               # the N column
"""
import argparse

import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen

DEFAULTS = {"m_c": 1.4, "m_p": 0.6, "l": 0.7, "g": 9.81, "mu": 0.25, "v_eps": 0.01}


def derive():
    """(KanesMethod, F, N, constants) of the cart (mass m_c, position x,
    speed v) and the pendulum (a point mass m_p on a rod of length l, angle
    theta from the downward vertical)."""
    t = me.dynamicsymbols._t
    x, th, v, w, ua, N, F = me.dynamicsymbols("x theta v omega ua N F")
    mc, mp, l, g, mu, v_eps = sm.symbols("m_c m_p l g mu v_eps")
    frame = me.ReferenceFrame("frame")
    A = frame.orientnew("A", "Axis", [th, frame.z])
    A.set_ang_vel(frame, w * frame.z)
    O = me.Point("O")
    C = O.locatenew("C", x * frame.x)
    C.set_vel(frame, v * frame.x + ua * frame.y)       # ua: auxiliary, carries N
    P = C.locatenew("P", -l * A.y)
    P.v2pt_theory(C, frame, A)
    friction = mu * N * sm.tanh(v / v_eps)
    loads = [(C, -mc * g * frame.y + N * frame.y + (F - friction) * frame.x),
             (P, -mp * g * frame.y)]
    km = me.KanesMethod(frame, q_ind=[x, th], u_ind=[v, w],
                        kd_eqs=[x.diff(t) - v, th.diff(t) - w], u_auxiliary=[ua])
    km.kanes_equations([me.Particle("cart", C, mc), me.Particle("bob", P, mp)], loads)
    consts = {mc: DEFAULTS["m_c"], mp: DEFAULTS["m_p"], l: DEFAULTS["l"], g: DEFAULTS["g"],
              mu: DEFAULTS["mu"], v_eps: DEFAULTS["v_eps"]}
    return km, F, N, consts


def model():
    """The gen.Model: state [x, theta, v, omega], input F, the reaction N
    (sim.auxiliary_forces, the CSV's N column)."""
    km, F, _, consts = derive()
    return gen.Model.from_kanes(km, constants=consts, inputs=[F], name="cart_pole_friction")


def newton_euler(state, F):
    """By hand (Newton-Euler on the cart and the bob, rod tension T):
    [x'', theta'', T, N] from four linear equations."""
    mc, mp, l, g, mu, v_eps = (DEFAULTS[k] for k in ("m_c", "m_p", "l", "g", "mu", "v_eps"))
    _, th, v, w = state
    s, c, sg = np.sin(th), np.cos(th), np.tanh(v / v_eps)
    K = np.array([[mp, mp * l * c, s, 0.0],          # bob x: mp ax = -T sin
                  [0.0, mp * l * s, -c, 0.0],        # bob y: mp ay = T cos - mp g
                  [mc, 0.0, -s, mu * sg],            # cart x: mc x'' = F - mu N sg + T sin
                  [0.0, 0.0, c, -1.0]])              # cart y: 0 = N - mc g - T cos
    rhs = np.array([mp * l * w**2 * s, -mp * l * w**2 * c - mp * g, F, -mc * g])
    return np.linalg.solve(K, rhs)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--theta0", type=float, default=2.5, help="the pendulum's start angle [rad]")
    ap.add_argument("--v0", type=float, default=0.8, help="the cart's start speed [m/s]")
    ap.add_argument("--t-end", type=float, default=2.0)
    a = ap.parse_args(argv)
    sim = gen.compile(model())
    t, X = sim.simulate([0.0, a.theta0, a.v0, 0.0], a.t_end, 0.01, method="dopri5",
                        rtol=1e-10, atol=1e-10)
    N = np.array([sim.auxiliary_forces(ti, xi)[0] for ti, xi in zip(t, X)])
    # the same numbers by hand, at every output row
    ref = np.array([newton_euler(x, 0.0) for x in X])
    acc = np.array([sim.rhs(ti, xi)[2:] for ti, xi in zip(t, X)])
    err = max(np.max(np.abs(acc - ref[:, :2])) / np.max(np.abs(ref[:, :2])),
              np.max(np.abs(N - ref[:, 3])) / np.max(np.abs(ref[:, 3])))
    weight = (DEFAULTS["m_c"] + DEFAULTS["m_p"]) * DEFAULTS["g"]
    print(f"N from {N.min():.4f} to {N.max():.4f} (the weight is {weight:.4f})")
    print(f"the cart's speed from {a.v0} to {X[-1, 2]:.4f}")
    print(f"largest difference from Newton-Euler by hand: {err:.2e}")
    return N, err


if __name__ == "__main__":
    main()
