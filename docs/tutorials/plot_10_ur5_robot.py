"""
A UR5 from its URDF: gravity compensation, linearization, a Cortex-M4F build
============================================================================

The UR5 arm as its users describe it, the URDF of the ``example-robot-data``
wheel, turned into a compiled simulator by one call,
``gen.Model.from_urdf``. We hold it still with gravity-compensation torques,
let it go from a nearby posture, linearize it about the held posture, and
cross-build it for a Cortex-M4F. Pinocchio (``pip install pin``), when it is
installed, is the reference for the accelerations and the linearization.
"""
# %%
# Load and compile
# ----------------
# The bodies are the URDF's links (those welded by fixed joints merged),
# the state ``[q, u]`` follows Pinocchio's joint order, and the inputs are
# one torque per joint, ``tau_<joint>``.
import shutil
import warnings
from importlib import metadata

import matplotlib.pyplot as plt
import numpy as np

import gen

warnings.simplefilter("ignore")
urdf = next(f.locate() for f in metadata.files("example-robot-data")
            if str(f).endswith("robots/ur_description/urdf/ur5_robot.urdf"))
model = gen.Model.from_urdf(urdf, name="ur5")
sim = gen.compile(model)
print(model.state_names[:6])
print(model.input_names)

# %%
# Gravity compensation
# --------------------
# At rest, ``u' = M^-1 (tau - g(q))``; the linearization's input matrix is
# ``M^-1``, so the gravity torques at ``q0`` are ``-M u'(q0, tau=0)``.
q0 = np.array([0.0, -1.0, 1.2, -0.5, 0.3, 0.0])
x0 = np.concatenate([q0, np.zeros(6)])
A, B = sim.linearize(x0, r=np.zeros(6))
tau_g = -np.linalg.solve(B[6:], sim.rhs(0.0, x0, r=np.zeros(6))[6:])
print("gravity torques (N m):", np.round(tau_g, 3))

held = sim.simulate(x0, 2.0, 1e-3, r=tau_g)
x1 = x0.copy()
x1[1] += 0.05                                   # the shoulder 0.05 rad off
moved = sim.simulate(x1, 2.0, 1e-3, r=tau_g)
print("held posture, largest drift after 2 s:", np.max(np.abs(held.x[-1] - x0)))
assert np.max(np.abs(held.x[-1] - x0)) < 1e-9

fig, ax = plt.subplots(figsize=(7, 3.5))
for i, name in enumerate(model.state_names[:6]):
    ax.plot(moved.t, moved.x[:, i] - q0[i], label=name)
ax.set_xlabel("t (s)")
ax.set_ylabel("q - q0 (rad)")
ax.set_title("UR5 under the torques that hold q0, released 0.05 rad off")
ax.legend(fontsize=7, ncol=2)
fig.tight_layout()

# %%
# Linearize about the held posture
# --------------------------------
# ``A = [[0, I], [da/dq, da/du]]``: the held posture of a gravity-loaded arm
# is unstable or neutral in each joint, as the eigenvalues show.
A, B = sim.linearize(x0, r=tau_g)
eig = np.linalg.eigvals(A)
print("largest real part of A's eigenvalues:", np.max(eig.real))
try:
    import pinocchio as pin
    pm = pin.buildModelFromUrdf(str(urdf))
    pd = pm.createData()
    pin.computeABADerivatives(pm, pd, q0, np.zeros(6), tau_g)
    err = np.max(np.abs(A[6:, :6] - pd.ddq_dq)) / (1 + np.max(np.abs(pd.ddq_dq)))
    print(f"da/dq against Pinocchio's computeABADerivatives: {err:.1e}")
    assert err < 1e-8
except ImportError:
    print("Pinocchio is not installed: no reference here")

# %%
# Build for a Cortex-M4F
# ----------------------
# The same model in float, cross-compiled (``arm-none-eabi-gcc``,
# ``-mcpu=cortex-m4 -mfpu=fpv4-sp-d16``, ``-Os``): its flash and the stack
# of the right-hand side and the RK4 step. ``stack_limit=0``: the
# discrete linearization of a 12-state model needs more than the embedded
# profile's default 8 kB bound; a firmware that steps the model does not.
if shutil.which("arm-none-eabi-gcc"):
    from gen.toolchain import footprint
    rep = footprint.report(model, real="float", target="cortex-m4f", stack_limit=0)
    fns = rep["functions"]
    print(f"flash {rep['flash']['flash']} B (.text {rep['flash']['text']} B, .data "
          f"{rep['flash']['data']} B, .bss {rep['flash']['bss']} B); stack: ur5_eval_rhs "
          f"{fns['ur5_eval_rhs']['stack']} B, ur5_step_rk4 {fns['ur5_step_rk4']['stack']} B")
else:
    print("arm-none-eabi-gcc is not installed: no cross-build here")
