"""
Exporting an FMU and running it in FMPy
=======================================

Systems engineers exchange models as Functional Mock-up Units (FMI 2.0 and
3.0) between Simulink, Dymola, OpenModelica and co-simulation masters.
:func:`gen.export_fmu` writes a model as one: ``modelDescription.xml``, the
generated C and its runtime as sources, and a binary for this machine.

We export the seed pendulum (Kane's model: a dependent coordinate and a
dependent speed) with both interfaces, Co-Simulation and Model Exchange,
check it with FMPy's validator, run it with FMPy, an importer nobody here
wrote, and compare the trajectories with eomgen's own simulation.
"""
import sys
from pathlib import Path
try:                      # python docs/tutorials/<this file>, from anywhere
    HERE = Path(__file__).resolve().parent
except NameError:         # sphinx-gallery runs each script in its own folder
    HERE = Path.cwd()
sys.path.insert(0, str(HERE.parents[1]))   # the checkout: examples/ as a package

import tempfile
import zipfile

import numpy as np
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

import gen
import examples.seed_pendulum as sp

# %%
# Export
# ------
# ``start`` gives the start state by name: the independent ``q2`` and
# ``u2`` are exact, the dependent ``q1`` is the guess that picks the branch
# (hanging, ``q1 > 0``). ``units`` uses Modelica's unit syntax; the
# derivatives get ``/s``.
model = sp.kane_model()
start = {"q2": 0.6, "q1": 0.8, "u2": 0.5}
folder = Path(tempfile.mkdtemp(prefix="eomgen-fmu-"))
path = gen.export_fmu(model, folder / "pendulum.fmu", fmi_version="3.0", kind="both",
                      start=start, units={"q1": "m", "q2": "m", "u1": "m/s", "u2": "m/s"})
print(path.name, f"{path.stat().st_size} bytes")
for name in sorted(zipfile.ZipFile(path).namelist())[:12]:
    print("  ", name)

# %%
# FMPy's validator finds no problem in the model description:
problems = validate_fmu(str(path))
print("validate_fmu:", problems)
assert problems == []
md = read_model_description(str(path))
print("FMI", md.fmiVersion, "| states:", [v.name for v in md.modelVariables
                                         if v.name in ("q1", "q2", "u1", "u2")])

# %%
# Run it in FMPy
# --------------
# Co-Simulation integrates the full state with eomgen's DOPRI5 inside the
# FMU (projected onto the constraints after every step), at FMPy's
# tolerance. Model Exchange hands the independent state ``[q2, u2]`` to
# FMPy's CVODE; the FMU solves the dependent ``q1, u1`` whenever CVODE sets
# the state. The reference is ``sim.simulate`` at a tolerance far below
# both.
T_END, DT = 2.0, 0.01
sim = gen.compile(model)
x0 = np.zeros(sim.nx)
for k, v in start.items():
    x0[sim.state_names.index(k)] = v
x0 = sim.consistent_state(x0)
t_ref, X_ref = sim.simulate(x0, T_END, DT, method="dopri5", rtol=1e-12, atol=1e-12)

results = {}
for kind, tol in (("CoSimulation", 1e-10), ("ModelExchange", 1e-12)):
    r = simulate_fmu(str(path), fmi_type=kind, stop_time=T_END, output_interval=DT,
                     relative_tolerance=tol, output=list(sim.state_names))
    keep = np.r_[np.diff(r["time"]) > 0, True]       # rows FMPy repeats at events
    t = r["time"][keep]
    X = np.column_stack([r[n] for n in sim.state_names])[keep]
    assert np.allclose(t, t_ref, rtol=0, atol=1e-12)
    err = np.max(np.abs(X - X_ref))
    results[kind] = (t, X, err)
    print(f"{kind:14s}: max |FMPy - sim.simulate| over the state = {err:.1e}")

# %%
# The check: FMPy's runs agree with eomgen's to 1e-8 (Co-Simulation) and
# 1e-7 (Model Exchange, CVODE's own error control), and stay on the
# constraint ``q1² + q2² = L²``.
assert results["CoSimulation"][2] < 1e-8
assert results["ModelExchange"][2] < 1e-7
for kind, (t, X, _) in results.items():
    q1, q2 = X[:, sim.state_names.index("q1")], X[:, sim.state_names.index("q2")]
    residual = np.max(np.abs(np.hypot(q1, q2) - sp.DEFAULTS["L"]))
    print(f"{kind:14s}: max constraint residual {residual:.1e} m")
    assert residual < 1e-9

# %%
# The figure: the motion from FMPy on top of eomgen's, and the difference.
import matplotlib.pyplot as plt

fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
i2 = sim.state_names.index("q2")
ax1.plot(t_ref, X_ref[:, i2], "k-", lw=3, alpha=0.3, label="sim.simulate (eomgen)")
for kind, (t, X, _) in results.items():
    ax1.plot(t, X[:, i2], "--", label=f"FMPy, {kind}")
    ax2.semilogy(t, np.max(np.abs(X - X_ref), axis=1) + 1e-17, label=kind)
ax1.set_ylabel("q2 [m]")
ax1.legend()
ax2.set_ylabel("max |FMPy - eomgen|")
ax2.set_xlabel("t [s]")
ax2.legend()
fig.suptitle("the seed pendulum as an FMI 3.0 FMU, run by FMPy")
fig.tight_layout()
