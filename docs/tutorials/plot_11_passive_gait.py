"""
A passive gait found by optimal control
=======================================

Garcia's simplest walker (Garcia, Chatterjee, Ruina and Coleman 1998) walks
down a slope ``γ = 0.009`` with no motor: its gait is a limit cycle across
the heel strike. Here :class:`gen.OptimalControl` finds it as a feasibility
problem: one phase ending on the heel strike (``events=["heelstrike"]``), the
state after the strike's map equal to the start (``periodic=True``), no input.

The references owe nothing to the optimizer: the published fixed point
(``θ = 0.2003``, ``θ' = -0.1998``, a step of ``3.8825``), the fixed point of
the stride map found by Newton's method on the simulator, and the simulator
started from the optimized gait, which makes its own heel strikes.
"""
# %%
# The walker and a first guess
# ----------------------------
# ``examples/simplest_walker.py`` builds the walker with ``LagrangesMethod``:
# ``θ`` the stance leg's angle from the slope normal, ``φ`` the angle between
# the legs, and the heel strike a :class:`gen.Reset` (when ``φ - 2θ`` crosses
# zero upwards the legs swap and the speeds jump). The guess is one step of
# the simulator from ``(θ, θ') = (0.2, -0.2)``, off the gait.
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))   # the checkout: examples/ as a package
import matplotlib.pyplot as plt
import numpy as np
import sympy as sm

import gen
import examples.simplest_walker as sw

walker = sw.model(name="walker_gait")
sim = gen.compile(walker)
run = sim.simulate(sw.start([0.2, -0.2]), 4.5, 0.01, method="dopri5", rtol=1e-10,
                   atol=1e-12)
T0 = [e for e in run.events if e.name == "heelstrike"][0].t
N = 101
Xg = run.sol(np.linspace(0, T0 * (1 - 1e-9), N))     # just before the strike
guess = {n: Xg[:, i] for i, n in enumerate(walker.state_names)}
guess["duration"] = T0
print(f"guess: one step of {T0:.4f} from (0.2, -0.2)")

# %%
# The periodic gait by optimization
# ---------------------------------
# Hermite-Simpson at 101 nodes; the step's duration is free within (2, 6) and
# minimized (the gait is isolated, so this only picks it out). The last node
# lies on the heel strike's guard, crossing upwards, and the strike's map
# carries it back to the first node.
ocp = gen.OptimalControl(walker, N, (2.0, 6.0), terminal_cost=sm.Symbol("t"),
                         method="hermite-simpson", events=["heelstrike"], periodic=True)
gait = ocp.solve(guess, tol=1e-12, print_level=0)
assert gait.status == 0, gait.message
theta, thetad, T = gait.x[0, 0], gait.x[0, 2], gait.t[-1]
print(f"optimized: theta = {theta:.7f}, theta' = {thetad:.7f}, step {T:.6f}")
assert round(theta, 4) == 0.2003 and round(thetad, 4) == -0.1998 and round(T, 4) == 3.8825

# the stride map's fixed point, by Newton's method on the simulator
z, J = sw.fixed_point(sw.stride_map(sim))
print(f"stride map's fixed point: theta = {z[0]:.7f}, theta' = {z[1]:.7f}; "
      f"differences {theta - z[0]:.1e}, {thetad - z[1]:.1e}")
assert abs(theta - z[0]) < 1e-5 and abs(thetad - z[1]) < 1e-5

# %%
# The simulated limit cycle
# -------------------------
# The simulator, started from the optimized first node, strikes at the end of
# the optimized step and comes back to where it started; the stride map's
# eigenvalues (inside the unit circle) make the cycle attract.
rep = sim.simulate(gait.x[0], 3 * T + 0.5, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
strikes = [e for e in rep.events if e.name == "heelstrike"]
err_t = abs(strikes[0].t - T)
err_x = np.abs(strikes[0].x_after - gait.x[0]).max()
print(f"simulated: strike at {strikes[0].t:.6f} ({err_t:.1e} from the optimized step), "
      f"state after it {err_x:.1e} from the start; {len(strikes)} strikes in "
      f"{rep.t[-1]:.2f}; eigenvalues {np.round(np.linalg.eigvals(J), 4)}")
assert err_t < 1e-6 and err_x < 1e-6
assert np.max(np.abs(np.linalg.eigvals(J))) < 1

(ph,) = gait.phases
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
for k, (name, ls) in enumerate([("θ", "-"), ("φ", "--")]):
    ax1.plot(rep.t, rep.x[:, k], "C%d" % k, ls=ls, lw=1, label=f"{name}, simulated")
    ax1.plot(ph.t, ph.x[:, k], "C%d" % k, ls="", marker=".", ms=3,
             label=f"{name}, optimized")
for ev in strikes:
    ax1.axvline(ev.t, color="k", lw=0.5, ls=":")
ax1.set(xlabel="t (√(l/g))", ylabel="angle (rad)", title="three steps and the optimized one")
ax1.set_ylim(-0.5, 0.7)
ax1.legend(loc="upper center", ncol=2, fontsize=7)
ax2.plot(rep.x[:, 0], rep.x[:, 2], lw=1, label="simulated")
ax2.plot(ph.x[:, 0], ph.x[:, 2], ".", ms=3, label="optimized nodes")
ax2.plot([ph.x[-1, 0], ph.x_after[0]], [ph.x[-1, 2], ph.x_after[2]], "k:", lw=0.8,
         label="heel strike")
ax2.set(xlabel="θ", ylabel="θ'", title="the limit cycle")
ax2.legend(loc="center", fontsize=7)
fig.tight_layout()
