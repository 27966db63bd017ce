"""
The Whipple bicycle against Meijaard's benchmark
================================================

The benchmark bicycle of Meijaard, Papadopoulos, Ruina and Schwab (2007,
*Linearized dynamics equations for the balance and steer of a bicycle: a
benchmark and review*, Proc. R. Soc. A 463, 1955-1982): four rigid bodies
(rear frame with rider, rear wheel, front frame, front wheel), knife-edge
wheels rolling without slip. ``examples/bicycle.py`` derives it with
``KanesMethod`` in Moore's formulation: eight coordinates, one holonomic
constraint (the front wheel touches the ground, the pitch is dependent),
five nonholonomic ones (no slip), three independent speeds.

We compile the full nonlinear model to C, linearize it about upright rolling
at speeds from 0 to 10 m/s (in C, at every speed), and find the speed range
where the bicycle balances itself. The benchmark published these numbers to
14 decimals: the weave speed (an oscillatory lean/steer mode becomes
stable) and the capsize speed (a slow lean mode becomes unstable).
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

import gen
import examples.bicycle as bicycle

# %%
# Derive and compile
# ------------------
# The derivation and ``Model.from_kanes`` take a few seconds of sympy; the
# compile, about half a minute from an empty cache (then it is cached by
# content and takes nothing).
tick = time.perf_counter()
model = bicycle.model()
sim = gen.compile(model)
print(f"derived and compiled in {time.perf_counter() - tick:.1f} s")
print("coordinates", sim.state_names[:sim.nq])
print("independent state of the linearization", sim.independent_state_names)

# %%
# Upright rolling at speed ``v`` is a consistent state: the pitch and the
# dependent speeds come from ``sim.consistent_state``. The linearization's
# rows and columns of lean ``q4``, steer ``q7`` and their rates are
# Meijaard's lean/steer model; the other six eigenvalues are zero
# (ignorable coordinates and the constant wheel rate).
speeds = np.linspace(0.0, 10.0, 101)
ev = np.array([bicycle.eigenvalues(sim, v) for v in speeds])
for v in (0.0, 2.0, 4.0, 5.0, 6.0, 8.0):
    e = bicycle.eigenvalues(sim, v)
    print(f"v = {v:4.1f} m/s: " + "  ".join(f"{z.real:+9.5f}{z.imag:+9.5f}j" for z in e))

# %%
# Weave and capsize speeds
# ------------------------
# ``bicycle.critical_speeds`` finds, with ``scipy.optimize.brentq``, where
# the largest real part of the four eigenvalues crosses zero: upwards of it
# the weave pair is stable, and beyond the capsize speed the capsize
# eigenvalue is unstable again. The reference values are Table 2 of the
# paper.
vw, vc = bicycle.critical_speeds(sim)
print(f"weave speed   {vw:.14f} m/s   Meijaard et al.: {bicycle.MEIJAARD_WEAVE_SPEED:.14f}")
print(f"capsize speed {vc:.14f} m/s   Meijaard et al.: {bicycle.MEIJAARD_CAPSIZE_SPEED:.14f}")
assert abs(vw / bicycle.MEIJAARD_WEAVE_SPEED - 1) < 1e-12
assert abs(vc / bicycle.MEIJAARD_CAPSIZE_SPEED - 1) < 1e-12

# %%
# Self-stable exactly between them: every real part is negative inside
# (weave, capsize) and one is positive outside.
for v, stable in ((4.0, False), (4.5, True), (5.5, True), (6.5, False)):
    assert (np.max(bicycle.eigenvalues(sim, v).real) < 0) == stable, v

# %%
# Meijaard's matrices
# -------------------
# The linearized equations of the benchmark are
# ``M q'' + v C1 q' + (g K0 + v² K2) q = f`` on ``q = (lean, steer)``; they
# follow from two of eomgen's linearizations (at 0 and 5 m/s). The paper
# prints ``M[0, 0] = 80.81722`` and ``K0[0, 0] = -80.95``.
M, C1, K0, K2 = bicycle.meijaard_matrices(sim)
print("M  =", M.round(8).tolist())
print("C1 =", C1.round(8).tolist())
print("K0 =", K0.round(8).tolist())
print("K2 =", K2.round(8).tolist())
assert abs(M[0, 0] - 80.81722) < 1e-10 and abs(K0[0, 0] + 80.95) < 1e-10

# %%
# The figure: the real and imaginary parts of the four eigenvalues against
# speed, the self-stable range shaded.
import matplotlib.pyplot as plt

fig, ax = plt.subplots(figsize=(8, 5))
ax.axvspan(vw, vc, color="tab:green", alpha=0.12, label="self-stable")
ax.plot(speeds, ev.real, "k.", ms=3)
ax.plot(speeds, np.abs(ev.imag), ".", color="tab:blue", ms=3)
ax.plot([], [], "k.", label="real parts")
ax.plot([], [], ".", color="tab:blue", label="|imaginary parts|")
for v, name in ((vw, "weave"), (vc, "capsize")):
    ax.axvline(v, color="tab:green", lw=0.8)
    ax.annotate(f"{name}\n{v:.4f} m/s", (v, 8), ha="center", fontsize=8)
ax.axhline(0, color="0.5", lw=0.8)
ax.set_ylim(-10, 10)
ax.set_xlabel("forward speed v [m/s]")
ax.set_ylabel("eigenvalue [1/s]")
ax.set_title("benchmark bicycle: lean/steer eigenvalues from eomgen's C linearization")
ax.legend(loc="lower left")
fig.tight_layout()
