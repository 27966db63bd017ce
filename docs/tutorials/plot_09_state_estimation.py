"""
Estimating the cart-pole's rates, then balancing it on the estimate, in C
=========================================================================

The cart-pole of ``examples/cart_pole.py`` (``theta`` from the upward
vertical) measures its cart position and its pole angle, with noise, and
nothing else. We

1. build an extended Kalman filter from the model, :class:`gen.EKF`: its
   prediction is the model's own RK4 step over the 10 ms period and that
   step's exact sensitivity, its update fuses the two measurements one at a
   time as scalars;
2. check it against the same filter written in numpy from scratch: sympy's
   equations lambdified, RK4 in numpy, the Jacobian by complex-step
   differentiation, the textbook update with its matrix inverse;
3. put it in a closed loop with an LQR, inside the generated C: the
   simulation measures its true state with seeded noise, the filter
   estimates, the LQR acts on the estimate. From 0.1 rad and a wrong first
   estimate, the pole stays up;
4. plot the estimates, their 3-sigma bands and the truth.
"""
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))                # the checkout
sys.path.insert(0, str(HERE.parents[1] / "examples"))   # cart_pole

import numpy as np
import sympy as sm

import gen
import cart_pole

# %%
# The filter
# ----------
# The measurements are sympy expressions in the model's symbols (here two of
# its states); ``Q`` is the process noise added per period on the state
# ``[x, theta, v, omega]``, ``R`` the measurement variances (1 cm, 0.01 rad).
km, s = cart_pole.derive()
model = cart_pole.model()
sim = gen.compile(model)

DT = 0.01
Q = np.diag([1e-8, 1e-8, 1e-6, 1e-6])
R = np.array([1e-4, 1e-4])
X0_EST = np.array([0.05, 0.0, 0.0, 0.0])        # a wrong guess: 5 cm off, pole upright
P0 = np.diag([1e-2, 1e-2, 1e-1, 1e-1])
ekf = gen.EKF(model, {"x_m": s["x"], "th_m": s["theta"]}, DT, Q, R, X0_EST, P0)
print(ekf)

# %%
# A recording: the cart-pole pushed by a known force for 5 s, simulated by
# the compiled model, its position and angle measured with noise.
rng = np.random.default_rng(9)
N = 500
t = DT * np.arange(N)
F = 0.5 * np.sin(0.5 * t)[:, None]
truth, Z = np.zeros((N, 4)), np.zeros((N, 2))
x = np.array([0.0, 0.15, 0.0, 0.0])
for k in range(N):
    truth[k] = x
    Z[k] = x[:2] + rng.normal(size=2) * np.sqrt(R)
    x = sim.step(t[k], x, DT, r=F[k])
res = ekf.filter(t, Z, F)          # 500 predicts and updates in one C call

# %%
# The same filter in numpy, from scratch
# --------------------------------------
# No eomgen here: sympy's full mass matrix and forcing lambdified, RK4 in
# numpy, the step's Jacobian by complex-step differentiation (exact to
# rounding), and the textbook update ``K = P Hᵀ (H P Hᵀ + R)⁻¹`` in the
# Joseph form.
vals = {s[k]: v for k, v in cart_pole.DEFAULTS.items()}
Xs, Fs = sm.symbols("X0:4"), sm.Symbol("F_in")
sub = {**dict(zip([s["x"], s["theta"], s["v"], s["omega"]], Xs)), s["F"]: Fs}
M_f = sm.lambdify([Xs, Fs], km.mass_matrix_full.subs(vals).xreplace(sub), "numpy")
f_f = sm.lambdify([Xs, Fs], km.forcing_full.subs(vals).xreplace(sub), "numpy")


def rhs(x, r):
    dt = complex if np.iscomplexobj(x) else float
    return np.linalg.solve(np.array(M_f(x, r), dtype=dt), np.array(f_f(x, r), dtype=dt).ravel())


def rk4(x, r, h=DT):
    k1 = rhs(x, r)
    k2 = rhs(x + h / 2 * k1, r)
    k3 = rhs(x + h / 2 * k2, r)
    return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + rhs(x + h * k3, r))


def jacobian(x, r, eps=1e-30):
    J = np.zeros((4, 4))
    for j in range(4):
        xc = x.astype(complex)
        xc[j] += 1j * eps
        J[:, j] = rk4(xc, r).imag / eps
    return J


H = np.eye(4)[:2]
xe, Pe = X0_EST.copy(), P0.copy()
dx = dP = 0.0
for k in range(N):
    if k:
        Fk = jacobian(xe, F[k - 1, 0])
        xe, Pe = rk4(xe, F[k - 1, 0]), Fk @ Pe @ Fk.T + Q
    S = H @ Pe @ H.T + np.diag(R)
    K = Pe @ H.T @ np.linalg.inv(S)
    xe = xe + K @ (Z[k] - H @ xe)
    IKH = np.eye(4) - K @ H
    Pe = IKH @ Pe @ IKH.T + K @ np.diag(R) @ K.T
    dx, dP = max(dx, np.max(np.abs(xe - res.x[k]))), max(dP, np.max(np.abs(Pe - res.P[k])))
print(f"gen.EKF against numpy over {N} steps: max |dx| = {dx:.1e}, max |dP| = {dP:.1e}")
assert dx < 1e-10 and dP < 1e-10

# %%
# The filter only sees ``x`` and ``theta``; it infers the rates, and the
# truth stays inside its 3-sigma band.
inside = np.mean(np.abs(res.x[100:] - truth[100:]) < 3 * res.sd[100:], axis=0)
print("fraction of the samples after 1 s inside 3 sigma, per state:", np.round(inside, 3))
assert np.all(inside > 0.97)

# %%
# Estimate and control, in C
# --------------------------
# An LQR designed on ``sim.linearize`` at upright, fed with the estimate.
# ``ekf.feedback`` makes one controller of the two for ``sim.simulate``: at
# every 10 ms sample, inside the generated C, the true state is measured
# through the filter's measurement kernels plus seeded noise, the filter
# predicts and updates, and the LQR acts on the estimate.
A, B = sim.linearize(np.zeros(4))
K_lqr = cart_pole.lqr(A, B, cart_pole.Q_LQR, cart_pole.R_LQR)
ekf.reset(x0=X0_EST, P0=P0, t0=0.0)
loop = ekf.feedback(gen.LinearFeedback(K_lqr), seed=7)
sol = sim.simulate([0.0, 0.1, 0.0, 0.0], 20.0, 1e-3, controller=loop)
print(f"|theta| over the last 5 s <= {np.max(np.abs(sol.x[-5000:, 1])):.4f} rad, "
      f"|x| <= {np.max(np.abs(sol.x[-5000:, 0])):.4f} m")
assert np.max(np.abs(sol.x[-5000:, 1])) < 0.03

# %%
# The estimates logged at each sample, their 3-sigma bands and the truth
# (the simulation's state at the same instants).
import matplotlib.pyplot as plt

true_at = sol.x[::10]
fig, ax = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
for i, (label, unit) in enumerate([("x", "m"), ("theta", "rad"), ("v", "m/s"),
                                   ("omega", "rad/s")]):
    est, sd = loop.x[:, i], loop.sd[:, i]
    ax[i].fill_between(loop.t, est - 3 * sd, est + 3 * sd, color="C0", alpha=0.25,
                       label="estimate ± 3 sd")
    ax[i].plot(loop.t, est, "C0", lw=1, label="estimate")
    ax[i].plot(loop.t, true_at[:, i], "k--", lw=1, label="truth")
    ax[i].set_ylabel(f"{label} [{unit}]")
    ax[i].set_xlim(0, 5)
ax[0].legend(loc="upper right", fontsize=8)
ax[-1].set_xlabel("t [s]  (the first 5 s of 20)")
fig.suptitle("cart-pole: EKF on noisy x and theta, LQR on the estimate, one loop in C")
fig.tight_layout()
inside = np.mean(np.abs(loop.x[100:] - true_at[100:]) < 3 * loop.sd[100:])
print(f"closed loop: {100 * inside:.1f}% of the estimates after 1 s within 3 sd of the truth")
assert inside > 0.97

# %%
# On the target
# -------------
# ``ekf.to_c(folder, real="float")`` writes the filter as a firmware module
# (a static workspace, no heap) and a standalone program that reads a sensor
# CSV; ``ekf.footprint()`` cross-builds it for a Cortex-M4F. See the guide,
# :doc:`/guides/estimation`.
