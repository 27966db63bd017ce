"""
The seed pendulum, with Kane's and Lagrange's method
=====================================================

A point mass on a massless rod of length ``L``, described with two
*nonminimal* coordinates: ``q1`` (down) and ``q2`` (sideways), tied by the
configuration constraint ``q1² + q2² = L²``. It is the seed document's model,
derived exactly as the document does, once with ``KanesMethod`` (a dependent
coordinate ``q1`` and a dependent speed ``u1``) and once with
``LagrangesMethod`` (a holonomic constraint and its multiplier).

We compile both to C, release the pendulum from rest at several amplitudes,
and measure its period with the integrator's event location. The exact
period of a pendulum released at ``θ0`` is

.. math:: T = 4 \\sqrt{L/g}\\, K\\!\\left(\\sin^2(\\theta_0/2)\\right)

with ``K`` the complete elliptic integral of the first kind
(``scipy.special.ellipk``, which takes the parameter ``m = k²``): a number
that owes nothing to sympy or to eomgen.
"""
# %%
# Derive and compile
# ------------------
# ``examples/seed_pendulum.py`` holds the two derivations; ``kane_model()``
# and ``lagrange_model()`` wrap them into :class:`gen.Model` objects with
# the constants ``L = 1 m``, ``m = 1 kg``, ``g = 9.81 m/s²``.
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))   # the checkout: examples/ as a package
import numpy as np
from scipy.special import ellipk

import gen
import examples.seed_pendulum as sp

L, g = sp.DEFAULTS["L"], sp.DEFAULTS["g"]
kane = gen.compile(sp.kane_model())
lagrange = gen.compile(sp.lagrange_model())
print("Kane state    ", kane.state_names, " independent:", kane.independent_state_names)
print("Lagrange state", lagrange.state_names, " independent:", lagrange.independent_state_names)

# %%
# The two models order their states differently (``[q_ind, q_dep, u_ind,
# u_dep]`` for Kane, ``[q, q']`` for Lagrange); a small helper puts the bob
# at an angle ``θ`` from the downward vertical, at rest.


def at_rest(sim, theta):
    state = {"q1": L * np.cos(theta), "q2": L * np.sin(theta)}
    return np.array([state.get(n, 0.0) for n in sim.state_names])


# %%
# The period from the events
# --------------------------
# Released at ``θ0 > 0``, the bob crosses ``q2 = 0`` downwards at ``T/4``
# and again at ``5T/4``: the difference is one period. DOPRI5 locates the
# crossings on its dense output.
#
# The amplitudes stay below 90°: both models take ``q2`` as the independent
# coordinate, and at the horizontal position (``q1 = 0``) ``q2`` no longer
# determines ``q1``. The simulation refuses to go there with
# :class:`gen.SingularError` rather than return a wrong number
# (:doc:`/guides/partitions`).


def period(sim, theta0):
    T_guess = 2 * np.pi * np.sqrt(L / g) * 1.5
    sol = sim.simulate(at_rest(sim, theta0), 1.4 * T_guess, 0.01, method="dopri5",
                       rtol=1e-12, atol=1e-12, events={"q2": -1})
    down = [ev.t for ev in sol.events if ev.name == "q2"]     # gen.Event records
    return down[1] - down[0]


amplitudes = np.radians([5, 15, 30, 45, 60, 75, 85])
exact = 4 * np.sqrt(L / g) * ellipk(np.sin(amplitudes / 2) ** 2)
periods = {"Kane": [period(kane, a) for a in amplitudes],
           "Lagrange": [period(lagrange, a) for a in amplitudes]}

print(f"{'theta0':>7} {'exact T [s]':>16} {'Kane - exact':>13} {'Lagrange - exact':>17}")
for a, Te, Tk, Tl in zip(amplitudes, exact, periods["Kane"], periods["Lagrange"]):
    print(f"{np.degrees(a):6.0f}° {Te:16.12f} {Tk - Te:13.2e} {Tl - Te:17.2e}")

# %%
# The check: both methods give the elliptic-integral period to 1e-10
# relative, from 5° to 85° (where the small-angle period ``2π sqrt(L/g)``
# is 14 % too short).
for method, T in periods.items():
    err = np.max(np.abs(np.array(T) / exact - 1))
    print(f"{method}: max relative error of the period {err:.1e}")
    assert err < 1e-10, (method, err)

# %%
# The tension in the rod, from the multipliers
# --------------------------------------------
# The multiplier ``lam`` is the constraint force along the rows of the
# velocity-constraint matrix (:doc:`/guides/multipliers`): for Kane's model
# the row is the unit radial direction, so the tension is ``-lam``; for
# Lagrange's the row is the gradient ``[2 q1, 2 q2]`` of the constraint, of
# length ``2 L``, so the tension is ``-2 L lam``. Energy conservation gives
# the tension in closed form, ``m g (3 cos θ - 2 cos θ0)``.
theta0 = np.radians(60)
tension = {}
for method, sim, scale in (("Kane", kane, 1.0), ("Lagrange", lagrange, 2 * L)):
    sol = sim.simulate(at_rest(sim, theta0), 2.0, 0.01, method="dopri5", rtol=1e-11,
                       atol=1e-11)
    t, X, lam = sol.t, sol.x, sol.lam          # the multipliers come with the run
    names = list(sim.state_names)
    theta = np.arctan2(X[:, names.index("q2")], X[:, names.index("q1")])
    closed_form = sp.DEFAULTS["m"] * g * (3 * np.cos(theta) - 2 * np.cos(theta0))
    tension[method] = (t, -scale * lam[:, 0], closed_form)
    err = np.max(np.abs(-scale * lam[:, 0] - closed_form))
    print(f"{method}: max |tension - m g (3 cos θ - 2 cos θ0)| = {err:.1e} N")
    assert err < 1e-8, (method, err)

# %%
# The figure: the period against the amplitude, and the tension along a
# swing from 60°.
import matplotlib.pyplot as plt

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
fine = np.linspace(0.01, np.radians(88), 300)
ax1.plot(np.degrees(fine), 4 * np.sqrt(L / g) * ellipk(np.sin(fine / 2) ** 2), "k-",
         lw=1, label="4 sqrt(L/g) K(sin²(θ0/2))")
ax1.axhline(2 * np.pi * np.sqrt(L / g), color="0.6", ls="--", lw=1, label="small angle")
ax1.plot(np.degrees(amplitudes), periods["Kane"], "o", mfc="none", ms=9, label="Kane, C")
ax1.plot(np.degrees(amplitudes), periods["Lagrange"], "x", ms=7, label="Lagrange, C")
ax1.set_xlabel("amplitude θ0 [deg]")
ax1.set_ylabel("period T [s]")
ax1.legend()
for method, style in (("Kane", "-"), ("Lagrange", "--")):
    t, T_rod, closed = tension[method]
    ax2.plot(t, T_rod, style, label=f"{method}: from lam")
ax2.plot(t, closed, "k:", label="m g (3 cos θ - 2 cos θ0)")
ax2.set_xlabel("t [s]")
ax2.set_ylabel("rod tension [N]")
ax2.legend()
fig.suptitle("the seed pendulum, compiled to C with both methods")
fig.tight_layout()
