"""Cart-pole swing-up by direct collocation (gen.OptimalControl, issue 34):
from hanging (theta = pi) to upright (theta = 0) in 2 s, minimising the
integral of F^2 with |F| <= 20 N and |x| <= 1.5 m, on the model of
examples/cart_pole.py. Then the optimal inputs replayed through the
simulator (the transcription's accuracy), and the same problem with a
free final time and a time penalty.

    python examples/cart_pole_swing_up.py [--nodes 101] [--method hermite-simpson] [--plot out.png]
"""
import argparse
import sys
from pathlib import Path

import numpy as np
import sympy as sm

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cart_pole  # noqa: E402

import gen  # noqa: E402


def problem(nodes=101, method="hermite-simpson", duration=2.0):
    km, s = cart_pole.derive()
    x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
    model = gen.Model.from_kanes(km, constants={s[k]: val for k, val in
                                                {"mc": 1.0, "mp": 0.1, "l": 0.5, "g": 9.81}.items()},
                                 inputs=[F], name="cart_pole")
    ocp = gen.OptimalControl(model, nodes, duration, objective=F**2, method=method,
                             bounds={F: (-20, 20), x: (-1.5, 1.5)},
                             initial={x: 0, th: sm.pi, v: 0, om: 0},
                             final={x: 0, th: 0, v: 0, om: 0})
    return ocp, s


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, default=101)
    ap.add_argument("--method", default="hermite-simpson", choices=gen.design.ocp.METHODS)
    ap.add_argument("--plot")
    a = ap.parse_args(argv)
    ocp, s = problem(a.nodes, a.method)
    sol = ocp.solve()
    print(sol)
    print(f"  {sol.message}")
    print(f"  objective {sol.objective:.8g} N^2 s, {sol.iterations} iterations, "
          f"build {sol.build_seconds:.2f} s, solve {sol.solve_seconds:.2f} s")
    rep = sol.replay(rtol=1e-10, atol=1e-10)
    print(f"  replayed through the simulator: final-state error "
          f"{np.abs(rep.x[-1] - sol.x[-1]).max():.2e}")
    # the same problem, limited-memory Hessian (opty's mode): more iterations
    lm = ocp.solve(hessian="limited-memory")
    print(f"  limited-memory: objective {lm.objective:.8g}, {lm.iterations} iterations")
    # bounds change without a rebuild
    ocp.bounds = {s["F"]: (-10, 10), s["x"]: (-1.5, 1.5)}
    tight = ocp.solve(sol)
    print(f"  |F| <= 10: objective {tight.objective:.8g} ({tight.message})")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        t = np.linspace(0, sol.t[-1], 400)
        fig, ax = plt.subplots(3, 1, sharex=True, figsize=(6, 6))
        ax[0].plot(t, sol(t)[:, 0])
        ax[0].set_ylabel("x [m]")
        ax[1].plot(t, sol(t)[:, 1])
        ax[1].set_ylabel("theta [rad]")
        ax[2].plot(t, sol.input(t)[:, 0])
        ax[2].set_ylabel("F [N]")
        ax[2].set_xlabel("t [s]")
        fig.tight_layout()
        fig.savefig(a.plot)
    return sol


if __name__ == "__main__":
    main()
