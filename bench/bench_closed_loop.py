"""What closing the loop costs (issue 15), measured side by side in one run.

    python bench/bench_closed_loop.py [--repeat 7]

The cart-pole of examples/cart_pole.py, 5 s at dt = 1 ms with RK4 (5000
steps, one C call each run), with its inputs from:
  - a constant r (the plain simulate: the reference, ratio 1);
  - gen.LinearFeedback, continuous (the law at every stage, in C);
  - gen.LinearFeedback, sampled at 1 kHz (once per step, in C);
  - a table interpolated in C (input_hold="linear");
  - a Python callable r(t, x) sampled at 1 kHz (a cffi callback per step);
and, for a peer, scipy's solve_ivp (RK45, rtol 1e-8) over sim.rhs with the
same feedback in Python. Medians of --repeat runs; the machine is noisy, so
read the ratios, not the absolute times.
"""
import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "examples")]

import cart_pole as cp  # noqa: E402
import gen  # noqa: E402


def median_time(fn, repeat):
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return statistics.median(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=7)
    a = ap.parse_args(argv)
    sim = gen.compile(cp.model())
    A, B = sim.linearize(np.zeros(4))
    K = cp.lqr(A, B, cp.Q_LQR, cp.R_LQR)
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    tg = np.linspace(0, 5, 501)
    cases = {
        "constant r (reference)": lambda: sim.simulate(x0, 5.0, 1e-3, r=[0.1]),
        "LinearFeedback, every stage": lambda: sim.simulate(
            x0, 5.0, 1e-3, controller=gen.LinearFeedback(K)),
        "LinearFeedback, 1 kHz": lambda: sim.simulate(
            x0, 5.0, 1e-3, controller=gen.LinearFeedback(K, period=1e-3)),
        "table, linear, in C": lambda: sim.simulate(x0, 5.0, 1e-3, r=(tg, np.sin(tg)),
                                                    input_hold="linear"),
        "Python r(t, x), 1 kHz": lambda: sim.simulate(x0, 5.0, 1e-3, r=lambda t, x: -K @ x),
    }
    times = {k: median_time(f, a.repeat) for k, f in cases.items()}
    try:
        from scipy.integrate import solve_ivp

        def scipy_loop():
            solve_ivp(lambda t, x: sim.rhs(t, x, r=-K @ x), (0, 5), x0, rtol=1e-8,
                      atol=1e-10, t_eval=np.linspace(0, 5, 5001))
        times["scipy solve_ivp over sim.rhs"] = median_time(scipy_loop, max(1, a.repeat // 3))
    except ImportError:
        print("(scipy not installed: no solve_ivp row)")
    ref = times["constant r (reference)"]
    print(f"cart-pole, 5 s at 1 ms (RK4, 5000 steps), median of {a.repeat}:")
    for k, v in times.items():
        print(f"  {k:32s} {v * 1e3:9.2f} ms   {v / ref:7.2f} x   {v / 5000 * 1e9:8.0f} ns/step")


if __name__ == "__main__":
    main()
