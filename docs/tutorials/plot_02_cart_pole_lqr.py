"""
A cart-pole from sympy to an LQR in C, and on to a Cortex-M
===========================================================

The cart-pole (``examples/cart_pole.py``): a cart of mass ``m_c`` on a
track, pushed by a force ``F``, carrying a uniform pole of mass ``m_p`` and
half-length ``l`` hinged at the cart; ``theta`` is measured from the upward
vertical, so upright is an unstable equilibrium. We

1. derive it with ``KanesMethod`` and compile it to C;
2. linearize it at upright, in C, and design an LQR with SciPy's Riccati
   solver;
3. close the loop inside the generated C (:class:`gen.LinearFeedback`),
   continuous and sampled at 1 kHz, and check that the pole comes back;
4. compile the same model in single precision, the scalar type of the
   embedded profile, and build its library for a Cortex-M4F with
   ``arm-none-eabi-gcc`` (flash and worst-case stack of every function).
"""
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))   # the checkout: examples/ as a package

import numpy as np
from scipy.linalg import expm

import gen
import examples.cart_pole as cart_pole

# %%
# The model and its linearization at upright
# ------------------------------------------
# ``cart_pole.model()`` is ``gen.Model.from_kanes`` on the derivation, with
# the force ``F`` as input and the pole tip's position as two outputs.
model = cart_pole.model()
sim = gen.compile(model)
print("state", sim.state_names, " input", sim.input_names, " outputs", sim.output_names)
A, B = sim.linearize(np.zeros(4))
print("A =\n", A.round(4), "\nB =\n", B.round(4))

# %%
# The linearization is checked against the textbook cart-pole (uniform pole,
# Florian 2007): at upright, with ``M = m_c + m_p`` and the pole's inertia
# about its centre ``m_p l²/3``,
#
# .. math:: \ddot\theta = \frac{g \sin\theta - \cos\theta\, (F + m_p l \dot\theta^2 \sin\theta)/M}
#                              {l\,(4/3 - m_p \cos^2\theta / M)}
#
# so ``d theta''/d theta = g / (l (4/3 - m_p/M))`` there (the sign: this
# model's ``theta`` is positive to the left, the textbook's to the right, so
# ``d theta''/dF`` changes sign and ``d theta''/d theta`` does not).
p = cart_pole.DEFAULTS
M_tot = p["mc"] + p["mp"]
denom = p["l"] * (4 / 3 - p["mp"] / M_tot)
i_th, i_om = sim.state_names.index("theta"), sim.state_names.index("omega")
assert abs(A[i_om, i_th] - p["g"] / denom) < 1e-12 * p["g"] / denom
assert abs(abs(B[i_om, 0]) - 1 / (M_tot * denom)) < 1e-12 / (M_tot * denom)
print("open-loop eigenvalues", np.linalg.eigvals(A).round(4))

# %%
# The LQR
# -------
# ``Q`` weighs the cart position and the angle; the gain comes from SciPy's
# continuous algebraic Riccati equation, on eomgen's ``A`` and ``B``.
K = cart_pole.lqr(A, B, cart_pole.Q_LQR, cart_pole.R_LQR)
closed = np.linalg.eigvals(A - B @ K)
print("K =", K.round(3))
print("closed-loop eigenvalues", closed.round(4))
assert np.all(closed.real < -0.1)

# %%
# The closed loop, in C
# ---------------------
# :class:`gen.LinearFeedback` evaluates ``F = -K x`` inside the generated C:
# at every stage of the integrator (a continuous controller), or sampled at
# 1 kHz and held (a digital one). From 0.3 rad off upright:
x0 = np.array([0.0, 0.3, 0.0, 0.0])
runs = {}
for label, ctrl in (("continuous", gen.LinearFeedback(K)),
                    ("sampled, 1 kHz", gen.LinearFeedback(K, period=1e-3))):
    sol = sim.simulate(x0, 6.0, 1e-3, controller=ctrl)   # a gen.Solution
    t, X, R = sol.t, sol.x, sol.r              # times, states, the force applied
    Y = np.column_stack([sol.outputs[k] for k in sim.output_names])   # tip_x, tip_y
    runs[label] = (t, X, R, Y)
    print(f"{label:15s}: |x(6 s)| = {np.max(np.abs(X[-1])):.1e}, max |F| = "
          f"{np.max(np.abs(R)):.2f} N")
    assert np.max(np.abs(X[-1])) < 1e-3             # back to upright, cart back home

# %%
# Two checks that do not come from the simulation itself:
#
# - close to upright the nonlinear loop is the linear one: from 0.01 rad, the
#   C simulation follows ``expm((A - B K) t) x0`` to 1e-3 of the motion (the
#   neglected terms are of second order in the 0.01 rad);
# - the loop sampled at 1 kHz stays within 3 % (of the initial angle, over
#   every state) of the continuous one: 1 ms is short against the
#   closed-loop time constants (0.2 s and more).
small = x0 / 30
t, X = sim.simulate(small, 3.0, 1e-3, controller=gen.LinearFeedback(K))
Acl = A - B @ K
X_lin = np.array([expm(Acl * tk) @ small for tk in t])
dev = np.max(np.abs(X - X_lin)) / np.max(np.abs(X_lin))
print(f"nonlinear vs linear closed loop from 0.01 rad: {dev:.1e} of the motion")
assert dev < 1e-3
gap = np.max(np.abs(runs["continuous"][1] - runs["sampled, 1 kHz"][1])) / 0.3
print(f"sampled vs continuous: {gap:.1e} of the initial angle")
assert gap < 0.03

# %%
# The embedded build
# ------------------
# The embedded profile is the same model in single precision (``float``
# arrays, ``sinf``/``cosf``, no heap, no globals, no stdio). First on this
# machine: the float library follows the double closed loop to float's
# accuracy.
sim32 = gen.compile(model, real="float")
t32, X32 = sim32.simulate(x0, 6.0, 1e-3, controller=gen.LinearFeedback(K))
err32 = np.max(np.abs(X32 - runs["continuous"][1]))
print(f"float vs double closed loop: max |difference| {err32:.1e}")
assert err32 < 1e-4

# %%
# Then for a Cortex-M4F (``-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16
# -mfloat-abi=hard``, newlib-nano, ``-Os``): ``gen.toolchain.footprint.report``
# generates the CMake project with its toolchain file, builds the static
# library with ``arm-none-eabi-gcc`` and reads its flash and, from GCC's
# stack usage and call graph, the worst-case stack of every public
# function. Without the cross compiler this step says so and is skipped.
import shutil

from gen.toolchain import footprint

if shutil.which("arm-none-eabi-gcc"):
    rep = footprint.report(model, real="float", target="cortex-m4f")
    print(rep["table"])
    flash = rep["flash"]["flash"]
    print(f"flash (.text + .rodata): {flash} B, worst-case stack {rep['max_stack']} B")
    assert 0 < flash < 64 * 1024 and 0 < rep["max_stack"] < 8192
else:
    print("arm-none-eabi-gcc is not installed: the Cortex-M4F build is skipped "
          "(apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi)")

# %%
# The figure: the two closed loops from 0.3 rad, and the float run on top.
import matplotlib.pyplot as plt

fig, ax = plt.subplots(4, 1, figsize=(8, 8), sharex=True)
for label, (t, X, R, Y) in runs.items():
    ax[0].plot(t, X[:, 0], label=f"LinearFeedback, {label}")
    ax[1].plot(t, X[:, 1])
    ax[2].plot(t, Y[:, 0])
    ax[3].plot(t, R[:, 0])
ax[1].plot(t32, X32[:, 1], "k:", label="float build")
ax[0].set_ylabel("x [m]")
ax[1].set_ylabel("theta [rad]")
ax[2].set_ylabel("tip_x [m]")
ax[3].set_ylabel("F [N]")
ax[3].set_xlabel("t [s]")
ax[0].legend(fontsize=8)
ax[1].legend(fontsize=8)
fig.suptitle("cart-pole, LQR from 0.3 rad, the loop closed in the generated C")
fig.tight_layout()
