"""
Model predictive control: a cart-pole under a disturbance, a quadrotor's figure-eight
=====================================================================================

:class:`gen.MPC` re-plans the next second at every sample from the measured
state. It takes one real-time iteration of a Gauss-Newton SQP along the
model's own RK4 steps, and solves the step's quadratic program by a Riccati
interior point in the generated C. We

1. hold the cart-pole of ``examples/cart_pole.py`` upright with the force
   limited to 20 N, and kick the pole halfway: the controller uses the full
   force without exceeding it, and the pole comes back;
2. fly the quadrotor of ``examples/quadrotor.py`` (12 states, 4 inputs)
   along a figure-eight. MPC sees the reference ahead, so it tracks it more
   closely than the time-varying LQR tracker (:class:`gen.TrajectoryTracker`)
   with the same weights and limits;
3. report the controller's size on a Cortex-M4F.

The controls were checked against acados on the same problems
(``bench/bench_mpc.py``): they agree at every step of a 200-step closed loop
to 3e-12 (cart-pole) and 3e-11 (quadrotor) relative to the largest control.
"""
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))                # the checkout
sys.path.insert(0, str(HERE.parents[1] / "examples"))   # cart_pole, quadrotor

import matplotlib.pyplot as plt
import numpy as np

import gen
import cart_pole
import quadrotor

# %%
# The cart-pole, kicked
# ---------------------
# The controller: N = 20 intervals of 50 ms (a one-second horizon), the cost
# on ``[x, theta, v, omega]`` and the force, ``|F| <= 20`` N. It starts
# upright. At t = 2 s the pole is kicked: its angular speed jumps by 3 rad/s.
# The loop is closed in C by ``sim.simulate(..., controller=mpc)``; the kick
# is a second run from the first one's end state.
model = cart_pole.model()
Q = np.diag([10.0, 10.0, 0.1, 0.1])
mpc = gen.MPC(model, horizon=20, period=0.05, Q=Q, R=[0.05], P=5 * Q,
              bounds={"F": (-20.0, 20.0)})
sim = gen.compile(model, derivatives=True)
first = sim.simulate([0.0, 0.05, 0.0, 0.0], 2.0, 1e-3, controller=mpc)
kicked = first.x[-1] + np.array([0.0, 0.0, 0.0, 3.0])
second = sim.simulate(kicked, 4.0, 1e-3, controller=mpc)
t = np.r_[first.t, 2.0 + second.t]
x = np.vstack([first.x, second.x])
F = np.r_[first.r[:, 0], second.r[:, 0]]
print(f"largest |F| = {np.max(np.abs(F)):.3f} N; pole angle at 6 s: {x[-1, 1]:.2e} rad")
assert np.max(np.abs(F)) <= 20.0 + 1e-9 and np.max(np.abs(F)) > 19.9   # the limit, reached
assert np.max(np.abs(x[-1])) < 1e-3                                    # upright again

fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
ax[0].plot(t, x[:, 1], label="theta (rad)")
ax[0].plot(t, x[:, 0], label="x (m)")
ax[0].axvline(2.0, color="0.6", ls=":")
ax[0].legend()
ax[1].plot(t, F, color="C3")
ax[1].axhline(20, color="0.6", ls="--")
ax[1].axhline(-20, color="0.6", ls="--")
ax[1].set_ylabel("F (N)")
ax[1].set_xlabel("t (s)")
fig.suptitle("cart-pole held upright by MPC, kicked at t = 2 s")

# %%
# The quadrotor's figure-eight
# ----------------------------
# The reference is a figure-eight at 1 m height in 8 s, with the hover thrust
# as its input, given as a table. The thrust and the torques are bounded. The
# tracker gets the same Q, R, period and limits.
qmodel = quadrotor.model(kinematics="euler")
hover = quadrotor.hover_input()
period, T = 0.05, 8.0
w = 2 * np.pi / T
ts = period * np.arange(int(T / period) + 21)
X = np.zeros((len(ts), 12))
X[:, 3], X[:, 4], X[:, 5] = np.sin(w * ts), 0.5 * np.sin(2 * w * ts), 1.0
X[:, 9], X[:, 10] = w * np.cos(w * ts), w * np.cos(2 * w * ts)
U = np.tile(hover, (len(ts), 1))
Qq = np.diag([1, 1, 1, 20, 20, 20, 0.1, 0.1, 0.1, 1, 1, 1.0])
Rq = np.diag([0.1, 10, 10, 10.0])
lo = np.array([0.0, -0.5, -0.5, -0.2])
hi = np.array([2.5 * hover[0], 0.5, 0.5, 0.2])
qmpc = gen.MPC(qmodel, 20, period, Qq, Rq, P=5 * Qq, reference=(ts, X, U),
               bounds={n: (a, b) for n, a, b in zip(qmodel.input_names, lo, hi)})
qsim = gen.compile(qmodel, derivatives=True)
tracker = gen.TrajectoryTracker(qsim, ts, X, U, Qq, Rq, period, r_min=lo, r_max=hi)
x0 = np.r_[0, 0, 0, 0, 0, 1.0, np.zeros(6)]
runs = {name: qsim.simulate(x0, T, 5e-3, controller=c)
        for name, c in (("MPC", qmpc), ("LQR tracker", tracker))}
err = {}
for name, sol in runs.items():
    ref = np.array([np.interp(sol.t, ts, X[:, j]) for j in (3, 4, 5)]).T
    err[name] = np.sqrt(np.mean(np.sum((sol.x[:, 3:6] - ref) ** 2, axis=1)))
print("RMS position error: " + ", ".join(f"{k} {v:.3f} m" for k, v in err.items()))
assert err["MPC"] < err["LQR tracker"]
assert np.all(runs["MPC"].r >= lo - 1e-12) and np.all(runs["MPC"].r <= hi + 1e-12)

fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(X[:, 3], X[:, 4], "k--", label="reference")
for name, sol in runs.items():
    ax.plot(sol.x[:, 3], sol.x[:, 4], label=f"{name} (RMS {err[name]:.3f} m)")
ax.set_aspect("equal")
ax.set_xlabel("x (m)")
ax.set_ylabel("y (m)")
ax.legend()
ax.set_title("quadrotor along a figure-eight")

# %%
# On a Cortex-M4F
# ---------------
# ``mpc.to_c(folder, real="float")`` writes the controller next to the
# model's generated sources (``gen.generate(model, folder, real="float")``).
# Its memory is one static instance sized at generation, and there is no
# heap. ``tests/features/test_mpc_embedded.py`` builds it for the Cortex-M4F
# with newlib-nano. For the cart-pole (N = 20) it measures a flash of 35.8 kB,
# a RAM of 14.8 kB (the memory) and a stack of about 1.5 kB. Under qemu-arm,
# its float controls agree with the double build's to 8e-5 relative over a
# 100-step closed loop.
files = mpc.sources(real="float")
print(sorted(files))
