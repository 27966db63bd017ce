"""
Impacts and resets: a bouncing ball and the simplest walker
============================================================

Two hybrid models, declared with ``hybrid={...}`` and simulated in C: a ball
bouncing with restitution ``e = 0.8`` (a :class:`gen.Impact`) until it rests,
and the simplest walking model of Garcia, Chatterjee, Ruina and Coleman
(1998), whose heel strike is a :class:`gen.Reset`. Its period-one gait comes
from Newton's method on the stride map, and the map's eigenvalues tell that
the gait is stable.

The references owe nothing to eomgen: the ball's impact times form a
geometric series, ``t_{k+1} = t_k + 2 v_1 e^k / g``, and the walker's fixed
point at slope ``0.009`` is published (``θ = 0.2003``, ``θ' = -0.1998``).
"""
# %%
# The bouncing ball
# -----------------
# ``examples/bouncing_ball.py`` declares the ground as
# ``gen.Impact(y, restitution=0.8)``. Each impact is in ``sol.events`` with
# the state before and after (``x_after``).
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))   # the checkout: examples/ as a package
import matplotlib.pyplot as plt
import numpy as np

import gen
import examples.bouncing_ball as bb
import examples.simplest_walker as sw

G, e = 9.81, 0.8
ball = gen.compile(bb.model(e))
sol = ball.simulate([1.0, 0.0], 6.0, 0.002, method="dopri5", rtol=1e-12, atol=1e-12)
t1, v1 = np.sqrt(2 / G), np.sqrt(2 * G)
k = np.arange(50)
t_exact = t1 + np.concatenate([[0.0], np.cumsum(2 * v1 * e ** k[1:] / G)])
t_found = np.array([ev.t for ev in sol.events[:50]])
print(f"{len(sol.events)} impacts; the first 50 within "
      f"{np.max(np.abs(t_found - t_exact)):.1e} s of the geometric series")
assert np.max(np.abs(t_found - t_exact)) < 1e-10
t_zeno = t1 + 2 * e * v1 / (G * (1 - e))
print(f"Zeno time {t_zeno:.9f} s; at rest from then on: y(6) = {sol.x[-1, 0]:.1e}, "
      f"{sol.stats['n_steps']} steps in all")
assert sol.x[-1, 1] == 0

fig, ax = plt.subplots(figsize=(7, 3))
ax.plot(sol.t, sol.x[:, 0])
ax.axvline(t_zeno, color="k", lw=0.5, ls="--")
ax.set(xlabel="t (s)", ylabel="y (m)", title="bouncing ball, e = 0.8")
fig.tight_layout()

# %%
# The simplest walker
# -------------------
# ``examples/simplest_walker.py`` builds the walker with ``LagrangesMethod``
# (hip mass 1, foot mass ``1e-6``) and the heel strike as a reset: when
# ``φ - 2θ`` crosses zero upwards, the legs swap and the speeds jump by
# Garcia's map. The stride map takes ``(θ, θ')`` just after a heel strike to
# the same just after the next one; Newton's method finds its fixed point.
walker = gen.compile(sw.model())
z, J = sw.fixed_point(sw.stride_map(walker))
lam = np.linalg.eigvals(J)
print(f"gait: theta = {z[0]:.6f}, theta' = {z[1]:.6f}; eigenvalues {np.round(lam, 4)}")
assert abs(z[0] - 0.2003) < 1e-4 and abs(z[1] + 0.1998) < 1e-4
assert np.max(np.abs(lam)) < 1          # a stable gait

sol = walker.simulate(sw.start(z), 20.0, 0.01, method="dopri5", rtol=1e-10, atol=1e-12)
fig, ax = plt.subplots(figsize=(7, 3))
ax.plot(sol.t, sol.x[:, 0], label="θ (stance)")
ax.plot(sol.t, sol.x[:, 1], label="φ (between the legs)")
for ev in sol.events:
    ax.axvline(ev.t, color="k", lw=0.5, ls=":")
ax.set(xlabel="t (√(l/g))", ylabel="angle (rad)", title="the period-one gait")
ax.legend(loc="upper right")
fig.tight_layout()
