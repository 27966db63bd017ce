"""
A Monte Carlo robustness map on a Dask cluster
==============================================

The LQR of the previous tutorial is designed for the nominal cart-pole
(cart 1 kg, pole 0.1 kg, half-length 0.5 m). Here it runs as a slow digital
controller (sampled every 120 ms and held) on plants that are not the
nominal one: each run draws the cart mass, the pole mass and the pole
length within ±30 % and the initial angle within ±0.3 rad, and simulates
5 s in C. A run succeeds when the pole is back: ``|theta| < 0.01`` rad and
``|x| < 0.05`` m at 5 s, and ``|theta|`` never beyond 0.5 rad on the way.

The runs go to a :class:`dask.distributed.LocalCluster` of two worker
processes: ``sim.ensemble(..., client=client)`` sends each worker the model
library's sources once, the worker builds them into its cache (by content)
and runs its chunks in C. The same call without ``client`` runs on this
process's threads, and gives the same numbers, bit for bit. (A study of
10⁵ runs at 60 ms and ±20 % is ``examples/cart_pole_robustness.py``; this
page runs 2000, at a slower rate and a wider spread where the map shows
its edge, so that the site builds in minutes.)
"""
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))   # the checkout: examples/ as a package

import time

import numpy as np
from distributed import Client, LocalCluster

import gen
import examples.cart_pole as cart_pole

N_RUNS = 2000
PERIOD = 0.12            # s: the digital controller's sample time
SPREAD = 0.3             # +-30 % on the masses and the length
THETA0 = 0.3             # rad: the initial angles

# %%
# The model, the gain and the draws
# ---------------------------------
# :class:`gen.Sampler` draws each constant and initial state by name (its
# seed makes the draws reproducible); names that are not drawn keep their
# nominal values (constants) or zero (states).
sim = gen.compile(cart_pole.model())
A, B = sim.linearize(np.zeros(sim.nx))
K = cart_pole.lqr(A, B, cart_pole.Q_LQR, cart_pole.R_LQR)
nominal = dict(zip(sim.constant_names, sim.constants))
s = gen.Sampler(seed=0)
p = s.draw(N_RUNS, **{k: ("uniform", (1 - SPREAD) * nominal[k], (1 + SPREAD) * nominal[k])
                      for k in ("m_c", "m_p", "l")})
x0 = s.draw(N_RUNS, theta=("uniform", -THETA0, THETA0))
controller = gen.LinearFeedback(K, period=PERIOD)
reduce = {"final": "final", "top": gen.Max(["theta"]), "bottom": gen.Min(["theta"])}

# %%
# On the cluster
# --------------
# The workers are forked from this process (Dask's default, spawn, would
# start each worker by running this script again, which a script without an
# ``if __name__ == "__main__":`` guard cannot stand).
import dask

dask.config.set({"distributed.worker.multiprocessing-method": "fork"})
tick = time.perf_counter()
with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                  dashboard_address=None) as cluster, Client(cluster) as client:
    res = sim.ensemble(x0, 5.0, 1e-3, p=p, controller=controller, reduce=reduce,
                       client=client, progress=False)
print(f"{N_RUNS} runs on 2 Dask workers in {time.perf_counter() - tick:.1f} s "
      f"(cluster start and the workers' builds included)")

# %%
# The same runs on this process's threads, and three of them one by one
# with ``sim.simulate``: the cluster's numbers are these, bit for bit.
local = sim.ensemble(x0, 5.0, 1e-3, p=p, controller=controller, reduce=reduce,
                     progress=False)
for key in reduce:
    assert np.array_equal(res[key], local[key], equal_nan=True), key
names = list(sim.constant_names)
for i in (0, 1, N_RUNS - 1):
    pi = np.array([p[n][i] if n in p else nominal[n] for n in names])
    xi = np.zeros(sim.nx)
    xi[sim.state_names.index("theta")] = x0["theta"][i]
    t, X = sim.simulate(xi, 5.0, 1e-3, p=pi, controller=controller)
    assert np.array_equal(X[-1], res["final"][i])
print("cluster == threads == simulate, bit for bit")

# %%
# Success
# -------
i_x, i_th = sim.state_names.index("x"), sim.state_names.index("theta")
fin = res["final"]
swing = np.maximum(res["top"][:, 0], -res["bottom"][:, 0])
with np.errstate(invalid="ignore"):
    ok = (res.ok & (np.abs(fin[:, i_th]) < 0.01) & (np.abs(fin[:, i_x]) < 0.05)
          & (swing < 0.5))
print(f"success rate {ok.mean():.1%}; {len(res.failures)} runs stopped on a solver error")
for index, status, t_fail, _ in res.failures[:3]:
    print(f"  run {index}: {status} at t = {t_fail:.3f} s")
for k in ("l", "m_p", "m_c"):
    print(f"  {k:4s}: succeeded in [{p[k][ok].min():.3f}, {p[k][ok].max():.3f}], "
          f"failed in [{p[k][~ok].min():.3f}, {p[k][~ok].max():.3f}]" if (~ok).any()
          else f"  {k}: no failure")

# %%
# A check against the physics: the nominal plant is the one the gain was
# designed for, and the linear loop sampled with a zero-order hold predicts
# whether it recovers. The discrete closed loop ``Ad - Bd K`` (``Ad, Bd``:
# eomgen's zero-order-hold discretization over 120 ms, computed in C) must
# have its eigenvalues inside the unit circle, and the runs within 10 % of
# the nominal plant and 0.1 rad of upright must all succeed.
Ad, Bd = sim.linearize(np.zeros(sim.nx), dt=PERIOD)
rho = np.max(np.abs(np.linalg.eigvals(Ad - Bd @ K)))
print(f"spectral radius of the sampled nominal loop: {rho:.3f}")
assert rho < 1
near = np.ones(N_RUNS, bool)
for k in ("m_c", "m_p", "l"):
    near &= np.abs(p[k] / nominal[k] - 1) < 0.1
near &= np.abs(x0["theta"]) < 0.1
print(f"{near.sum()} runs within 10 % of nominal and 0.1 rad: {ok[near].mean():.0%} succeed")
assert near.sum() > 0 and ok[near].all()

# %%
# The map: the success fraction over (pole length, initial angle) and over
# (pole mass, cart mass).
import matplotlib.pyplot as plt

draws = {**p, **x0}
fig, ax = plt.subplots(1, 2, figsize=(10, 4.2))
for a, (kx, ky, lx, ly) in zip(ax, [("l", "theta", "pole half-length l [m]",
                                      "initial angle [rad]"),
                                     ("m_p", "m_c", "pole mass [kg]", "cart mass [kg]")]):
    h_ok, xe, ye = np.histogram2d(draws[kx], draws[ky], bins=12, weights=ok.astype(float))
    h_all, _, _ = np.histogram2d(draws[kx], draws[ky], bins=[xe, ye])
    with np.errstate(invalid="ignore"):
        frac = h_ok / h_all
    im = a.pcolormesh(xe, ye, frac.T, vmin=0, vmax=1, cmap="RdYlGn", shading="flat")
    a.set_xlabel(lx)
    a.set_ylabel(ly)
fig.colorbar(im, ax=ax, label="success fraction")
fig.suptitle(f"cart-pole LQR at {1 / PERIOD:.0f} Hz, ±30 % masses and length: "
             f"{ok.mean():.1%} of {N_RUNS} runs recover (Dask, 2 workers)")
