"""Issue 45: robots from MJCF files (gen.Model.from_mjcf, gen.load_mjcf),
compiled by MuJoCo's own compiler.

Reference: MuJoCo's ``mj_forward`` on the same file, with contacts, joint
limits, equality constraints, springs, damping, armature (the joints', the
actuators' and the tendons'), friction loss, actuation, gravity
compensation and fluid forces switched off: its ``qacc`` at random states
and joint forces (``qfrc_applied``). MuJoCo holds a quaternion scalar first
and a free joint's linear velocity in world axes; ours are scalar last and
body axes (Pinocchio's free flyer), converted here. Models: a multi-joint
arm written here (joints with anchors, several joints in one body, a slide)
and the model of the mujoco wheel's own tests (``mujoco/testdata/model.xml``:
free bodies, a ball joint, tendons, actuators, classes and defaults)."""
from pathlib import Path

import numpy as np
import pytest

import gen

mujoco = pytest.importorskip("mujoco", reason="MuJoCo (pip install mujoco) compiles MJCF")

pytestmark = [pytest.mark.filterwarnings("ignore::gen.UnusedConstantWarning"),
              pytest.mark.filterwarnings("ignore::gen.UnusedInputWarning"),
              pytest.mark.filterwarnings("ignore:\\s*Velocity of:UserWarning")]
TOL = 1e-9

ARM = """<mujoco model="arm">
  <default><joint damping="3" armature="0.2"/></default>
  <worldbody>
    <body name="upper" pos="0 0 1" euler="10 20 30">
      <joint name="shoulder_z" axis="0 0 1" pos="0 0 0.1"/>
      <joint name="shoulder_y" axis="0 1 0" pos="0.05 0 0"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05"/>
      <body name="lower" pos="0.5 0 0">
        <joint name="elbow" axis="0 1 1" range="-60 60" limited="true"/>
        <geom type="box" size="0.2 0.05 0.03" pos="0.2 0 0" euler="0 30 0"/>
        <body name="hand" pos="0.4 0 0" euler="0 0 45">
          <geom type="sphere" size="0.05"/>
          <body name="slider" pos="0.1 0 0">
            <joint name="slide" type="slide" axis="1 0 0" range="-0.1 0.1"/>
            <geom type="sphere" size="0.05" pos="0 0.02 0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>"""


def rigid_only(m):
    """m with everything but the rigid-body dynamics switched off."""
    bit = mujoco.mjtDisableBit
    for name in ("mjDSBL_CONTACT", "mjDSBL_LIMIT", "mjDSBL_EQUALITY", "mjDSBL_SPRING",
                 "mjDSBL_DAMPER", "mjDSBL_ACTUATION", "mjDSBL_FRICTIONLOSS",
                 "mjDSBL_CONSTRAINT"):
        m.opt.disableflags |= int(getattr(bit, name))
    m.dof_M0[:] -= m.dof_armature          # the simple bodies' diagonal, armature included
    m.dof_armature[:] = 0
    m.dof_damping[:] = 0
    for name in ("actuator_armature", "tendon_armature", "body_gravcomp"):
        if hasattr(m, name):
            getattr(m, name)[:] = 0
    m.opt.density = m.opt.viscosity = 0.0
    m.opt.wind[:] = 0
    return m


def _rot(w, x, y, z):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def mujoco_accel(m, x, forces):
    """Our u' from MuJoCo's qacc at our state x (module docstring)."""
    qpos, qvel = np.zeros(m.nq), np.zeros(m.nv)
    i = k = 0
    nq = sum({0: 7, 1: 4}.get(int(t), 1) for t in m.jnt_type)
    q, u = x[:nq], x[nq:]
    frees = []
    for j in range(m.njnt):
        typ, qa, da = int(m.jnt_type[j]), int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
        if typ == 0:
            qx, qy, qz, qw = q[i + 3:i + 7]
            R = _rot(qw, qx, qy, qz)
            qpos[qa:qa + 7] = [*q[i:i + 3], qw, qx, qy, qz]
            qvel[da:da + 3], qvel[da + 3:da + 6] = R @ u[k:k + 3], u[k + 3:k + 6]
            frees.append((da, R, u[k:k + 3], u[k + 3:k + 6]))
            i, k = i + 7, k + 6
        elif typ == 1:
            qx, qy, qz, qw = q[i:i + 4]
            qpos[qa:qa + 4] = [qw, qx, qy, qz]
            qvel[da:da + 3] = u[k:k + 3]
            i, k = i + 4, k + 3
        else:
            qpos[qa], qvel[da] = q[i], u[k]
            i, k = i + 1, k + 1
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:], d.qfrc_applied[:] = qpos, qvel, forces
    mujoco.mj_forward(m, d)
    a = d.qacc.copy()
    for da, R, v, w in frees:          # d/dt (R v) = R (v' + w x v)
        a[da:da + 3] = R.T @ a[da:da + 3] - np.cross(w, v)
    return a


def against_mujoco(sim, m, seed, states=4):
    """The worst relative difference of u' from MuJoCo's at random states
    and joint torques; the torques on MuJoCo's dofs by joint name."""
    rng = np.random.default_rng(seed)
    names = sim.state_names[:sim.nq]
    dof = {}
    for j in range(m.njnt):
        nm = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
        dof[f"tau_{nm}"] = int(m.jnt_dofadr[j])
    worst = 0.0
    for _ in range(states):
        x = rng.uniform(-1, 1, sim.nx)
        for i, n in enumerate(names):
            if n.endswith("_qw"):
                x[i - 3:i + 1] /= np.linalg.norm(x[i - 3:i + 1])
        r = rng.uniform(-1, 1, sim.nr)
        forces = np.zeros(m.nv)
        for name, val in zip(sim.input_names, r):
            forces[dof[name]] = val
        a = mujoco_accel(m, x, forces)
        got = sim.rhs(0.0, x, r=r)[sim.nq:]
        worst = max(worst, float(np.max(np.abs(got - a)) / (1 + np.max(np.abs(a)))))
    return worst


@pytest.mark.slow
def test_arm_against_mujoco():
    robot = gen.load_mjcf(ARM)
    assert robot.joints == ["shoulder_z", "shoulder_y", "elbow", "slide"]
    assert sorted(robot.limits) == ["elbow", "slide"]          # the file's degrees, in rad
    assert np.allclose(robot.limits["elbow"], (-np.pi / 3, np.pi / 3), rtol=1e-15)
    assert np.allclose(robot.limits["slide"], (-0.1, 0.1), rtol=1e-15)
    model = gen.Model.from_mjcf(ARM, name="mj_arm")
    assert model.state_names == ["q_shoulder_z", "q_shoulder_y", "q_elbow", "q_slide",
                                 "u_shoulder_z", "u_shoulder_y", "u_elbow", "u_slide"]
    sim = gen.compile(model)
    assert against_mujoco(sim, rigid_only(mujoco.MjModel.from_xml_string(ARM)), 1) < TOL


@pytest.mark.slow
def test_mujoco_test_model_free_bodies_and_ball_joint():
    path = Path(mujoco.__file__).parent / "testdata" / "model.xml"
    if not path.is_file():
        pytest.skip(f"the mujoco wheel has no {path}")
    m = rigid_only(mujoco.MjModel.from_xml_path(str(path)))
    model = gen.Model.from_mjcf(path, name="mj_testmodel")
    assert (len(model.q), len(model.u)) == (m.nq, m.nv)
    assert model.state_names[:7] == ["joint0_x", "joint0_y", "joint0_z", "joint0_qx",
                                     "joint0_qy", "joint0_qz", "joint0_qw"]
    assert "wheel_0_qw" in model.state_names and "wheel_0_wz" in model.state_names
    sim = gen.compile(model)
    assert against_mujoco(sim, m, 2, states=3) < TOL


def test_mujoco_compiler_errors_name_the_element_and_line():
    with pytest.raises(gen.ModelError, match=r"MuJoCo's compiler refuses it.*'hing'.*line 5"):
        gen.load_mjcf(ARM.replace('name="shoulder_z"', 'name="shoulder_z" type="hing"'))
    with pytest.raises(gen.ModelError, match=r"MuJoCo's compiler refuses it.*[Ll]ine"):
        gen.load_mjcf(ARM.replace("</body>\n  </worldbody>", "</worldbody>"))
    with pytest.raises(gen.ModelError, match=r"no file"):
        gen.load_mjcf("/nonexistent/robot.xml")


WALKER = """<mujoco model="walker">
  <worldbody>
    <body name="torso" pos="0.1 -0.2 1.2" quat="0.9 0.1 -0.3 0.2">
      {joint}
      <geom type="box" size="0.2 0.1 0.3"/>
      <body name="thigh" pos="0 0.1 -0.3" euler="0 0 20">
        <joint name="hip" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.05"/>
        <body name="shin" pos="0 0 -0.4">
          <joint name="knee" axis="1 0 1"/>
          <joint name="ankle" type="slide" axis="0 0 1"/>
          <geom type="capsule" fromto="0 0 0 0.1 0 -0.3" size="0.04"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>"""


@pytest.mark.slow
def test_base_fixed_and_floating_as_the_freejoint_removed_and_added():
    """base="fixed" on a file whose torso has a <freejoint/> equals MuJoCo
    on the file without it (the torso welded where the file puts it);
    base="floating" on the file without it equals MuJoCo on the file with
    it; base=None keeps the file's joints."""
    free, welded = WALKER.format(joint='<freejoint name="root"/>'), WALKER.format(joint="")
    assert gen.load_mjcf(free).joints == ["root", "hip", "knee", "ankle"]
    assert gen.load_mjcf(welded).joints == ["hip", "knee", "ankle"]
    assert gen.load_mjcf(free, base="floating").joints == ["root", "hip", "knee", "ankle"]
    fixed = gen.Model.from_mjcf(free, base="fixed", name="mj_walker_fixed")
    assert fixed.state_names[:3] == ["q_hip", "q_knee", "q_ankle"] and len(fixed.q) == 3
    m_welded = rigid_only(mujoco.MjModel.from_xml_string(welded))
    assert against_mujoco(gen.compile(fixed), m_welded, 3) < TOL
    floating = gen.Model.from_mjcf(welded, "floating", name="mj_walker_floating")
    assert floating.state_names[:7] == ["base_x", "base_y", "base_z", "base_qx", "base_qy",
                                        "base_qz", "base_qw"]
    m_free = rigid_only(mujoco.MjModel.from_xml_string(free))
    assert against_mujoco(gen.compile(floating), m_free, 4) < TOL
    with pytest.raises(gen.ModelError, match=r"base='floating'.*'upper'.*shoulder_z"):
        gen.load_mjcf(ARM, base="floating")
    with pytest.raises(gen.ModelError, match=r"base='welded'"):
        gen.Model.from_mjcf(ARM, base="welded")
