"""A cart-pole swing-up, tracked in C by a time-varying LQR
(gen.TrajectoryTracker) from a perturbed start.

    python examples/cart_pole_tracking.py
    python examples/cart_pole_tracking.py --c-out out/cart_pole --plot docs/tracking.png
    python examples/cart_pole_tracking.py --reference simulated

The reference is the optimal swing-up of examples/cart_pole_swing_up.py
(gen.OptimalControl: hanging to upright in 2 s, minimum integral of F^2,
|F| <= 20 N, |x| <= 1.5 m, Hermite-Simpson on 101 nodes, IPOPT through
cyipopt), and the tracker is ``sol.tracker(Q, R, period)``. It linearizes
the model along the optimum (``sim.linearize(dt=period)``), runs the
discrete Riccati recursion backwards from the upright LQR's cost, and closes
the loop inside the generated C from 0.05 rad off the optimal start; the
optimal inputs replayed open loop from the same start miss upright.

Without cyipopt (``pip install eomgen[ocp]``), or with ``--reference
simulated``, the reference is simulated instead: an energy-pumping swing-up
(Astrom and Furuta 2000) from hanging, handed to an LQR near upright,
sampled at 100 Hz with a zero-order hold (8 s), tracked by
``gen.TrajectoryTracker(sim, t, x, r, Q, R, period)``.

``--c-out`` writes the model's sources with the tracker as const tables
(``swingup.c``, ``swingup.h``): the standalone binary closed by it is

    cd out/cart_pole && cc -O2 -DCART_POLE_TRACKER=swingup *.c -lm -o cart_pole_sim
    ./cart_pole_sim --t-end 2 --dt 1e-3 --x0 theta=3.19159

and on a microcontroller, every 10 ms: ``swingup_step(t, x, F)``.
"""
import argparse

import numpy as np

import cart_pole as cp
import gen

PERIOD = 0.01
T_END = 8.0
Q_TRACK = np.diag([10.0, 10.0, 1.0, 1.0])
R_TRACK = np.array([[0.1]])
# the optimum's tracker: a 2 s manoeuvre, tighter weights
OCP_T_END = 2.0
OCP_Q = np.diag([100.0, 100.0, 10.0, 10.0])
OCP_R = np.array([[0.1]])


def wrap(a):
    """An angle in [-pi, pi)."""
    return (a + np.pi) % (2 * np.pi) - np.pi


def swing_up_law(sim, k=30.0, f_max=20.0):
    """r(t, x): pump the pole's energy towards upright's (a cart acceleration
    k E omega cos(theta), E the pole's energy above upright), keep the cart
    near the middle, and hand over to an LQR within 0.35 rad of upright."""
    mp, l, g, mc = (cp.DEFAULTS[n] for n in ("mp", "l", "g", "mc"))
    J = 4.0 / 3.0 * mp * l**2                      # the pole about its hinge
    A, B = sim.linearize(np.zeros(4))
    K = cp.lqr(A, B, np.diag([10.0, 50.0, 1.0, 1.0]), np.array([[1.0]]))

    def law(t, x):
        th, w = wrap(x[1]), x[3]
        E = 0.5 * J * w**2 + mp * g * l * (np.cos(th) - 1)
        if abs(th) < 0.35 and abs(E) < 0.1:
            return np.clip(-K @ np.array([x[0], th, x[2], w]), -f_max, f_max)
        a = -k * E * w * np.cos(th) - 2.0 * x[0] - 2.0 * x[2]
        return np.array([np.clip((mc + mp) * a, -f_max, f_max)])
    return law


def swing_up_reference(sim, t_end=T_END, period=PERIOD, theta0=np.pi - 0.01):
    """A swing-up of the model from hanging (theta0) to upright (theta = 2 pi),
    its inputs sampled every period and held: (t, x, r) at the samples."""
    x0 = np.array([0.0, theta0, 0.0, 0.0])
    sol = sim.simulate(x0, t_end, period, r=swing_up_law(sim), input_period=period)
    return sol.t, sol.x, sol.r


def optimal_reference(nodes=101):
    """The optimal swing-up (examples/cart_pole_swing_up.py), solved: the
    OptimalSolution and its simulator; None without cyipopt."""
    try:
        import cyipopt  # noqa: F401
    except ImportError:
        return None
    import cart_pole_swing_up as cps
    ocp, _ = cps.problem(nodes, "hermite-simpson")
    sol = ocp.solve()
    if sol.status != 0:
        raise RuntimeError(f"the swing-up optimum was not found: {sol.message}")
    return sol, ocp.simulator


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", choices=("optimal", "simulated"), default="optimal",
                    help="the optimal swing-up (needs cyipopt) or a simulated one")
    ap.add_argument("--c-out", help="write the model's C sources and the tracker's here")
    ap.add_argument("--plot", help="save a plot of the reference and the tracked run")
    a = ap.parse_args(argv)
    opt = optimal_reference() if a.reference == "optimal" else None
    if a.reference == "optimal" and opt is None:
        print("cyipopt is not installed (pip install eomgen[ocp]): tracking the simulated "
              "swing-up instead of the optimal one")
    if opt is not None:
        ocp_sol, sim = opt
        t, x, r, t_end = ocp_sol.t, ocp_sol.x, ocp_sol.r, OCP_T_END
        print(f"optimal swing-up: {ocp_sol.iterations} IPOPT iterations, objective "
              f"{ocp_sol.objective:.6g} N^2 s")
        tracker = ocp_sol.tracker(OCP_Q, OCP_R, PERIOD)
    else:
        sim = gen.compile(cp.model())
        t, x, r = swing_up_reference(sim)
        t_end = T_END
        tracker = gen.TrajectoryTracker(sim, t, x, r, Q_TRACK, R_TRACK, PERIOD)
    print(tracker)
    x0 = x[0] + np.array([0.0, 0.05, 0.0, 0.0])
    sol = sim.simulate(x0, t_end, 1e-3, controller=tracker)
    end = sol.x[-1]
    print(f"from {x0[1] - x[0, 1]:+.2f} rad off the reference's start: at t = {sol.t[-1]} s "
          f"max |x - x_ref(end)| = {np.max(np.abs(end - x[-1])):.2e}, "
          f"off upright {abs(wrap(end[1])):.2e} rad, cart at {end[0]:+.4f} m")
    if opt is not None:
        ol = sim.simulate(x0, t_end, 1e-3, r=(t, r[:, 0]))
        print(f"the optimal inputs open loop from the same start: max |x - x_ref(end)| = "
              f"{np.max(np.abs(ol.x[-1] - x[-1])):.2e}, off upright "
              f"{abs(wrap(ol.x[-1, 1])):.2e} rad")
    fp = tracker.footprint("float")
    print(f"tables ({fp['rows']} rows): {fp['flash']} bytes of flash in float, "
          f"{tracker.footprint('double')['flash']} in double, no RAM")
    if a.c_out:
        gen.generate(cp.model(), a.c_out)   # the same model and constants as the OCP's
        for f in tracker.to_c(a.c_out, name="swingup"):
            print("wrote", f)
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
        ax[0].plot(t, x[:, 1], "k--", label="reference")
        ax[0].plot(sol.t, sol.x[:, 1], label="tracked, 0.05 rad off")
        ax[0].set_ylabel("theta [rad]")
        ax[0].legend()
        ax[1].plot(sol.t, sol.r[:, 0])
        ax[1].set_ylabel("F [N]")
        ax[1].set_xlabel("t [s]")
        fig.savefig(a.plot, dpi=100)
    return sol


if __name__ == "__main__":
    main()
