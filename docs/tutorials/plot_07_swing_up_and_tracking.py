"""
A cart-pole swing-up by optimal control, tracked in C and sized for a Cortex-M
==============================================================================

The cart-pole of ``examples/cart_pole.py`` (``theta`` from the upward
vertical) hangs at ``theta = pi``. We

1. ask :class:`gen.OptimalControl` for the swing-up: hanging to upright in
   2 s, minimum :math:`\\int F^2 dt`, :math:`|F| \\le 20` N and
   :math:`|x| \\le 1.5` m, by Hermite-Simpson collocation on 101 nodes
   (generated C for the defects, their Jacobian and the Hessian; IPOPT
   through cyipopt, the ``eomgen[ocp]`` extra);
2. replay the optimal force open loop from a start 0.05 rad off: the
   swing-up is unstable, and the pole misses upright;
3. close the loop with ``sol.tracker(Q, R, period)``, a time-varying LQR
   along the optimum (the discrete Riccati recursion on
   ``sim.linearize(dt=period)``), run inside the generated C, from the same
   start: it ends upright;
4. write the tracker as ``static const`` tables (``tracker.to_c``) and size
   them for a Cortex-M4F in single precision.
"""
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))                # the checkout
sys.path.insert(0, str(HERE.parents[1] / "examples"))   # cart_pole, cart_pole_swing_up

import numpy as np
import sympy as sm

import gen
import cart_pole

# %%
# The optimal control problem
# ---------------------------
# The model is ``gen.Model.from_kanes`` on the cart-pole's ``KanesMethod``
# (``m_c`` = 1 kg, ``m_p`` = 0.1 kg, half-length ``l`` = 0.5 m), with the
# force ``F`` as its input. The running cost, bounds and boundary states are
# written in the model's own symbols (this is
# ``examples/cart_pole_swing_up.py``'s ``problem()``).
km, s = cart_pole.derive()
x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
model = gen.Model.from_kanes(km, constants={s[k]: val for k, val in cart_pole.DEFAULTS.items()},
                             inputs=[F], name="cart_pole")
ocp = gen.OptimalControl(model, 101, 2.0, objective=F**2, method="hermite-simpson",
                         bounds={F: (-20, 20), x: (-1.5, 1.5)},
                         initial={x: 0, th: sm.pi, v: 0, om: 0},
                         final={x: 0, th: 0, v: 0, om: 0})
sol = ocp.solve()
print(sol)
print(f"{sol.message}: objective {sol.objective:.6g} N^2 s in {sol.iterations} iterations "
      f"(build {sol.build_seconds:.2f} s, solve {sol.solve_seconds:.2f} s)")
assert sol.status == 0
assert np.max(np.abs(sol.x[0] - [0, np.pi, 0, 0])) < 1e-8
assert np.max(np.abs(sol.x[-1])) < 1e-8
assert np.max(np.abs(sol.r)) <= 20 + 1e-6 and np.max(np.abs(sol.x[:, 0])) <= 1.5 + 1e-6

# %%
# Why a tracker: the optimal force replayed open loop through ``sim.simulate``
# misses upright, from 0.05 rad off and even from the exact hanging start,
# where the transcription's small error (101 nodes) grows through the
# unstable motion.
sim = ocp.simulator
x0 = sol.x[0] + np.array([0.0, 0.05, 0.0, 0.0])          # 0.05 rad off
replay = sim.simulate(sol.x[0], 2.0, 1e-3, r=(sol.t, sol.r[:, 0]))
open_loop = sim.simulate(x0, 2.0, 1e-3, r=(sol.t, sol.r[:, 0]))
print(f"open loop, exact start:   ends {np.max(np.abs(replay.x[-1])):.2f} from upright at rest")
print(f"open loop, 0.05 rad off:  ends {np.max(np.abs(open_loop.x[-1])):.2f} from upright at rest")
assert np.max(np.abs(open_loop.x[-1])) > 0.3

# %%
# The tracker
# -----------
# ``sol.tracker(Q, R, period)`` samples the optimum every 10 ms (the
# collocation's cubic interpolant between the nodes), linearizes the model
# there in C (zero-order hold), and runs the Riccati recursion backwards from
# the upright LQR's cost at the end. Its law, ``F = F_ref(t_k) - K_k (x -
# x_ref(t_k))`` held for a period, is evaluated by the C runtime: passed as
# ``controller=``, the whole closed loop runs in the generated C.
Q = np.diag([100.0, 100.0, 10.0, 10.0])      # x, theta, v, omega
R = np.array([[0.1]])
tracker = sol.tracker(Q, R, 0.01)
print(tracker)
runs = {}
for d in (0.05, -0.05):
    runs[d] = sim.simulate(sol.x[0] + np.array([0.0, d, 0.0, 0.0]), 2.0, 1e-3,
                           controller=tracker)
    end = runs[d].x[-1]
    print(f"tracked from {d:+.2f} rad off: ends {np.max(np.abs(end)):.1e} from upright at rest "
          f"(theta {end[1]:+.1e} rad), max |F| {np.max(np.abs(runs[d].r)):.1f} N")
    assert np.max(np.abs(end)) < 1e-2

# %%
# The gains are the recursion's, written out in numpy over the tracker's own
# discretizations (``tracker.Ad``, ``tracker.Bd``; ``tests/features/test_ocp_tracking.py``
# checks them against an independent reference too):
P = tracker.P[-1]
for k in range(len(tracker.t_samples) - 1, -1, -1):
    A, B = tracker.Ad[k], tracker.Bd[k]
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    P = Q + A.T @ P @ (A - B @ K)
assert np.max(np.abs(K - tracker.K[0])) < 1e-9 * np.max(np.abs(tracker.K))
print("K at t = 0:", tracker.K[0].round(2), " at the end:", tracker.K[-1].round(2))

# %%
# On a Cortex-M4F
# ---------------
# ``tracker.to_c(folder, name)`` writes ``<name>.c`` and ``<name>.h``: the
# reference and the gains as ``static const`` tables and
# ``<name>_step(t, x, r)``, the law at a sample time (no heap, nothing
# written but the caller's ``r``). In the float build the tables are 201 rows
# of ``K`` (4 values), ``x_ref`` (4) and ``r_ref`` (1), 4 bytes each. With
# ``arm-none-eabi-gcc`` installed, the tracker's object is compiled for the
# Cortex-M4F (``-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard
# -Os``) and its sections measured, as ``tests/features/test_tracking.py`` does; the
# model's own library is sized in the LQR tutorial. Without it, the sizes
# are computed from the tables ``to_c`` wrote.
import shutil
import subprocess
import tempfile

fp = tracker.footprint("float")
print(f"tables in float: K {fp['K']} B, x_ref {fp['x_ref']} B, r_ref {fp['r_ref']} B, "
      f"{fp['flash']} B of flash in all, RAM {fp['ram']} B "
      f"(double: {tracker.footprint('double')['flash']} B)")
assert fp["flash"] == 201 * (4 + 4 + 1) * 4
with tempfile.TemporaryDirectory() as tmp:
    src = Path(tmp) / "cart_pole"
    gen.generate(model, src, real="float")
    tracker.to_c(src, name="swingup", real="float")
    text = (src / "swingup.c").read_text()
    assert "static const cart_pole_real swingup_K[201 * CART_POLE_NR * CART_POLE_NS]" in text
    if shutil.which("arm-none-eabi-gcc"):
        from gen.toolchain.footprint import section_sizes
        obj = Path(tmp) / "swingup.o"
        subprocess.run(["arm-none-eabi-gcc", "-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16",
                        "-mfloat-abi=hard", "-Os", "-std=c99", "-Wall", "-Wextra", "-Werror",
                        "-c", "-I", str(src), str(src / "swingup.c"), "-o", str(obj)],
                       check=True)
        sec = section_sizes(obj, "arm-none-eabi-")
        print(f"Cortex-M4F object of the tracker: .text {sec['text']} B, .rodata "
              f"{sec['rodata']} B, .data {sec['data']} B, .bss {sec['bss']} B")
        assert sec["data"] == 0 and sec["bss"] == 0 and sec["rodata"] >= fp["flash"]
    else:
        print("arm-none-eabi-gcc is not installed: the sizes above are the tables' "
              "(apt-get install gcc-arm-none-eabi to measure the object)")

# %%
# The figure: the optimum, the open-loop replay and the tracked runs from
# 0.05 rad off, and the forces.
import matplotlib.pyplot as plt

t = np.linspace(0, 2, 401)
fig, ax = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
ax[0].plot(t, sol(t)[:, 1], "k--", label="optimum")
ax[0].plot(open_loop.t, open_loop.x[:, 1], ":", label="optimal F, open loop, +0.05 rad")
for d, run in runs.items():
    ax[0].plot(run.t, run.x[:, 1], label=f"tracked, {d:+.2f} rad")
    ax[1].plot(run.t, run.x[:, 0])
    ax[2].plot(run.t, run.r[:, 0])
ax[1].plot(t, sol(t)[:, 0], "k--")
ax[2].plot(t, sol.input(t)[:, 0], "k--")
ax[0].set_ylabel("theta [rad]")
ax[1].set_ylabel("x [m]")
ax[2].set_ylabel("F [N]")
ax[2].set_xlabel("t [s]")
ax[0].legend(fontsize=8)
fig.suptitle("cart-pole swing-up: gen.OptimalControl, tracked in C by sol.tracker")
fig.tight_layout()
