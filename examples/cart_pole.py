"""The cart-pole (Barto, Sutton and Anderson 1983; Florian 2007): a cart of
mass mc on a track, pushed by a force F, carrying a uniform pole of mass mp
and half-length l hinged at the cart, theta measured from the upward
vertical. Upright (x = 0, theta = 0) is an unstable equilibrium.

    python examples/cart_pole.py            # LQR at upright, closed loops in C
    python examples/cart_pole.py --plot docs/cart_pole.png --gain-csv K.csv

The same loop in the standalone binary, without Python:

    eomgen build examples/cart_pole.py -o out/cart_pole     # prints the binary's path
    <binary> --t-end 5 --dt 1e-3 --x0 theta=0.3 --gain K.csv --period 1e-3

The script linearizes the model at upright, designs an LQR with
scipy.linalg.solve_continuous_are from eomgen's A, B, and closes the loop
from 0.3 rad off upright three ways: gen.LinearFeedback evaluated inside
the generated C at every stage, the same law sampled at 1 kHz
(period=1e-3), and a Python callable r(t, x) sampled at 1 kHz.
"""
import argparse

import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen

DEFAULTS = {"mc": 1.0, "mp": 0.1, "l": 0.5, "g": 9.81}


def derive():
    """(KanesMethod, symbols) of the cart-pole."""
    x, theta, v, omega, F = me.dynamicsymbols("x theta v omega F")
    mc, mp, l, g = sm.symbols("m_c m_p l g")
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [theta, N.z])   # the pole, B.y along it
    B.set_ang_vel(N, omega * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x)
    C.set_vel(N, v * N.x)
    # the pole's centre; B.y = -sin(theta) N.x + cos(theta) N.y (theta from the
    # upward vertical, positive to the left)
    P = C.locatenew("P", l * B.y)
    P.v2pt_theory(C, N, B)
    cart = me.Particle("cart", C, mc)
    pole = me.RigidBody("pole", P, B, mp, (me.inertia(B, 0, 0, mp * (2 * l) ** 2 / 12), P))
    loads = [(C, F * N.x - mc * g * N.y), (P, -mp * g * N.y)]
    km = me.KanesMethod(N, q_ind=[x, theta], u_ind=[v, omega],
                        kd_eqs=[x.diff() - v, theta.diff() - omega])
    km.kanes_equations([cart, pole], loads)
    tip = C.locatenew("T", 2 * l * B.y)
    syms = dict(x=x, theta=theta, v=v, omega=omega, F=F, mc=mc, mp=mp, l=l, g=g, N=N,
                tip=tip, O=O)
    return km, syms


def tip_outputs(s):
    """The pole tip's position: what a camera over the track measures."""
    tip = s["tip"].pos_from(s["O"])
    return {"tip_x": tip.dot(s["N"].x), "tip_y": tip.dot(s["N"].y)}


def model(name="cart_pole", **values):
    km, s = derive()
    vals = {**DEFAULTS, **values}
    return gen.Model.from_kanes(km, constants={s[k]: v for k, v in vals.items()},
                                inputs=[s["F"]], name=name, outputs=tip_outputs(s))


def lqr(A, B, Q, R):
    """K of the continuous LQR (scipy's Riccati solver)."""
    from scipy.linalg import solve_continuous_are
    P = solve_continuous_are(A, B, Q, R)
    return np.linalg.solve(R, B.T @ P)


Q_LQR = np.diag([100.0, 10.0, 1.0, 1.0])
R_LQR = np.array([[1.0]])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plot", help="write a figure of the closed loops (needs matplotlib)")
    ap.add_argument("--gain-csv", help="write K for the binary's --gain")
    a = ap.parse_args(argv)
    sim = gen.compile(model())
    A, B = sim.linearize(np.zeros(4))
    K = lqr(A, B, Q_LQR, R_LQR)
    print("states", sim.state_names, "input", sim.input_names)
    print("A =\n", A, "\nB =\n", B)
    print("LQR gain K =", K)
    if a.gain_csv:
        with open(a.gain_csv, "w") as fh:
            fh.write("# LQR gain: F by [x, theta, v, omega]\n")
            fh.write(",".join(f"{v:.17g}" for v in K[0]) + "\n")
        print("wrote", a.gain_csv)
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    runs = {
        "LinearFeedback, continuous": dict(controller=gen.LinearFeedback(K)),
        "LinearFeedback, 1 kHz": dict(controller=gen.LinearFeedback(K, period=1e-3)),
        "Python r(t, x), 1 kHz": dict(r=lambda t, x: -K @ x, input_period=1e-3),
    }
    out = {}
    for label, kw in runs.items():
        sol = sim.simulate(x0, 5.0, 1e-3, **kw)           # a gen.Solution
        t, X, R = sol.t, sol.x, sol.r                     # times, states, the force applied
        Y = np.column_stack([sol.outputs[k] for k in sim.output_names])   # tip_x, tip_y
        out[label] = (t, X, R, Y)
        print(f"{label:28s} |x(5)| = {np.max(np.abs(X[-1])):.2e}, "
              f"max |F| = {np.max(np.abs(R)):.2f} N")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(4, 1, figsize=(7, 8.5), sharex=True)
        for label, (t, X, R, Y) in out.items():
            ax[0].plot(t, X[:, 0], label=label)
            ax[1].plot(t, X[:, 1])
            ax[2].plot(t, Y[:, 0])
            ax[3].plot(t, R[:, 0])
        ax[0].set_ylabel("x [m]")
        ax[1].set_ylabel("theta [rad]")
        ax[2].set_ylabel("tip_x [m]")
        ax[3].set_ylabel("F [N]")
        ax[3].set_xlabel("t [s]")
        ax[0].legend(fontsize=8)
        fig.suptitle("cart-pole, LQR from 0.3 rad (eomgen, closed loop in C)")
        fig.tight_layout()
        fig.savefig(a.plot, dpi=110)
        print("wrote", a.plot)


if __name__ == "__main__":
    main()
