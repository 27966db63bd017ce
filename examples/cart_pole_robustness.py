"""Robustness of the cart-pole's LQR, by Monte Carlo (issue 18's example).

The LQR of examples/cart_pole.py is designed for the nominal cart-pole (cart
1 kg, pole 0.1 kg, half-length 0.5 m) and runs as a digital controller at
PERIOD (sampled and held, gen.LinearFeedback(K, period=PERIOD)). The plant
is not the nominal one: each run draws the cart mass, the pole mass and the
pole length within +-20 % and the initial angle within +-0.2 rad, and
simulates 5 s in C (sim.ensemble, every core). A run succeeds when the loop
brings the pole back: |theta| < 0.01 rad and |x| < 0.05 m at t = 5 s, and
|theta| never beyond 0.5 rad on the way.

    python examples/cart_pole_robustness.py                    # 10^5 runs
    python examples/cart_pole_robustness.py --n 20000 --plot docs/cart_pole_robustness.png

Prints the success rate and where the failures are; the plot shows the
success fraction over (pole length, initial angle) and over (cart mass,
pole length): at this sample time the design loses the short poles on light
carts (faster plants), whatever the initial angle, and the pole mass hardly
matters. Those runs diverge: the simulator stops them (ERR_DIVERGED) and the
others complete.
"""
import argparse
import time
from collections import Counter

import numpy as np

import gen

import cart_pole

PERIOD = 0.12            # s: the digital controller's sample time (8.3 Hz: slow
                         # enough that the +-20 % plants do not all recover)
SPREAD = 0.2             # +-20 % on the masses and the length
THETA0 = 0.2             # rad: the initial angles


def run(n=100_000, seed=0, workers=None, client=None, progress=None):
    """(sim, draws, result, success mask) of the Monte Carlo."""
    sim = gen.compile(cart_pole.model())
    A, B = sim.linearize(np.zeros(sim.nx))
    K = cart_pole.lqr(A, B, cart_pole.Q_LQR, cart_pole.R_LQR)
    nominal = dict(zip(sim.constant_names, sim.constants))
    s = gen.Sampler(seed)
    p = s.draw(n, **{k: ("uniform", (1 - SPREAD) * nominal[k], (1 + SPREAD) * nominal[k])
                     for k in ("m_c", "m_p", "l")})
    x0 = s.draw(n, theta=("uniform", -THETA0, THETA0))
    res = sim.ensemble(x0, 5.0, 1e-3, p=p, controller=gen.LinearFeedback(K, period=PERIOD),
                       reduce={"final": "final", "top": gen.Max(["theta"]),
                               "bottom": gen.Min(["theta"])},
                       workers=workers, client=client, progress=progress)
    i_x, i_th = sim.state_names.index("x"), sim.state_names.index("theta")
    fin = res["final"]
    swing = np.maximum(res["top"][:, 0], -res["bottom"][:, 0])
    with np.errstate(invalid="ignore"):
        ok = (res.ok & (np.abs(fin[:, i_th]) < 0.01) & (np.abs(fin[:, i_x]) < 0.05)
              & (swing < 0.5))
    return sim, {**p, **x0}, res, ok


def plot(draws, ok, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(10, 4.2), layout="constrained")
    for a, (kx, ky, lx, ly) in zip(ax, [("l", "theta", "pole half-length l [m]",
                                          "initial angle [rad]"),
                                         ("m_c", "l", "cart mass m_c [kg]",
                                          "pole half-length l [m]")]):
        h_ok, xe, ye = np.histogram2d(draws[kx], draws[ky], bins=30, weights=ok.astype(float))
        h_all, _, _ = np.histogram2d(draws[kx], draws[ky], bins=[xe, ye])
        with np.errstate(invalid="ignore"):
            frac = h_ok / h_all
        im = a.pcolormesh(xe, ye, frac.T, vmin=0, vmax=1, cmap="RdYlGn", shading="flat")
        a.set_xlabel(lx)
        a.set_ylabel(ly)
    fig.colorbar(im, ax=ax, label="success fraction")
    fig.suptitle(f"cart-pole LQR at {1 / PERIOD:.1f} Hz, +-20 % masses and length: "
                 f"{ok.mean():.1%} of {len(ok)} runs recover")
    fig.savefig(path, dpi=110)
    print("wrote", path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=100_000, help="runs (default 10^5)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--plot", help="write the map of the stable region (PNG)")
    ap.add_argument("--scheduler", help="a Dask scheduler's address (default: this machine)")
    a = ap.parse_args(argv)
    client = None
    if a.scheduler:
        from distributed import Client
        client = Client(a.scheduler)
    t0 = time.perf_counter()
    sim, draws, res, ok = run(a.n, a.seed, client=client)
    stops = Counter(status for _, status, _, _ in res.failures)
    print(f"{a.n} runs in {time.perf_counter() - t0:.1f} s ({res.runs_per_second:.0f} runs/s in "
          f"C); {len(res.failures)} stopped on an error "
          f"({', '.join(f'{k}: {v}' for k, v in stops.most_common()) or 'none'})")
    print(f"success rate {ok.mean():.2%}")
    bad = ~ok
    if bad.any():
        for k in ("l", "theta", "m_p", "m_c"):
            print(f"  failures: {k} in [{draws[k][bad].min():.3f}, {draws[k][bad].max():.3f}] "
                  f"(all runs: [{draws[k].min():.3f}, {draws[k].max():.3f}])")
    if a.plot:
        plot(draws, ok, a.plot)


if __name__ == "__main__":
    main()
