"""Issue 45: robots from URDF files (gen.Model.from_urdf, gen.load_urdf).

Reference: Pinocchio's own model of the same file (``buildModelFromUrdf``,
with a ``JointModelFreeFlyer`` root for a floating base): its ``aba``,
``crba``, ``rnea`` and ``computeABADerivatives`` at random states and
torques, on the robots of the ``example-robot-data`` wheel (the UR5, fixed;
Solo12, floating). The mimic joints' reference is Pinocchio's model without
them, reduced by hand (``G^T M G``). The bad files are refused before any
build (fast tier); every build is in the slow tier. The sweep over all 69
files is ``python bench/bench_robots.py sweep``.
"""
import os
from pathlib import Path

import numpy as np
import pytest

import gen

pin = pytest.importorskip("pinocchio", reason="Pinocchio (pip install pin) is the reference")
pytest.importorskip("yourdfpy", reason="yourdfpy reads URDF (pip install eomgen[robots])")

pytestmark = [pytest.mark.filterwarnings("ignore::gen.UnusedConstantWarning"),
              pytest.mark.filterwarnings("ignore::gen.UnusedInputWarning"),
              pytest.mark.filterwarnings("ignore:\\s*Velocity of:UserWarning")]
TOL = 1e-10


def robot_file(rel):
    """A URDF of the example-robot-data wheel (robots/ folder)."""
    from importlib import metadata
    try:
        files = metadata.files("example-robot-data") or ()
    except metadata.PackageNotFoundError:
        files = ()
    for f in files:
        if str(f).endswith("/robots/" + rel):
            return Path(f.locate())
    why = "example-robot-data 6.0.0 (pip install example-robot-data) holds the URDFs"
    if os.environ.get("CI") == "true":
        pytest.fail(f"{why}: required under CI=true")
    pytest.skip(why)


def rel_err(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / (1 + np.max(np.abs(b))))


def pin_q(pm, q):
    """Pinocchio's configuration of ours: a continuous joint's angle as (cos, sin)."""
    out, i = [], 0
    for j in range(1, pm.njoints):
        if pm.joints[j].nq == 2 and pm.joints[j].nv == 1:
            out += [np.cos(q[i]), np.sin(q[i])]
            i += 1
        else:
            out += list(q[i:i + pm.joints[j].nq])
            i += pm.joints[j].nq
    return np.array(out)


def unit_quaternions(x, names):
    for i, n in enumerate(names):
        if n.endswith("_qw"):
            x[i - 3:i + 1] /= np.linalg.norm(x[i - 3:i + 1])
    return x


# ------------------------------------------------------------- fixed base
@pytest.mark.slow
def test_ur5_against_pinocchio():
    path = robot_file("ur_description/urdf/ur5_robot.urdf")
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    names = [pm.names[j] for j in range(1, pm.njoints)]
    model = gen.Model.from_urdf(path, name="ur5")
    sim = gen.compile(model)
    csim = gen.compile(gen.Model.from_urdf(str(path), name="ur5_crba", formulation="crba"))
    assert model.state_names == [f"q_{n}" for n in names] + [f"u_{n}" for n in names]
    assert model.input_names == [f"tau_{n}" for n in names]
    rng = np.random.default_rng(1)
    for _ in range(5):
        q, v, tau = rng.uniform(-2, 2, (3, 6))
        x = np.concatenate([q, v])
        assert rel_err(sim.rhs(0.0, x, r=tau)[6:], pin.aba(pm, pd, q, v, tau)) < TOL
        M = pin.crba(pm, pd, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert rel_err(csim.mass_matrix(q), M) < TOL
        assert rel_err(-csim.forcing(q, v, r=np.zeros(6)), pin.rnea(pm, pd, q, v, 0 * v)) < TOL
    # the linearization at the last state: A = [[0, I], [da/dq, da/dv]], B = [0; M^-1]
    A, B = sim.linearize(x, r=tau)
    pin.computeABADerivatives(pm, pd, q, v, tau)
    assert rel_err(A[6:, :6], pd.ddq_dq) < 1e-8
    assert rel_err(A[6:, 6:], pd.ddq_dv) < 1e-8
    assert rel_err(B[6:], pd.Minv) < 1e-8
    assert rel_err(A[:6], np.hstack([np.zeros((6, 6)), np.eye(6)])) < 1e-14


@pytest.mark.slow
def test_ur5_symbolic_inertias_change_at_run_time():
    """constants="symbolic": the forearm's mass, changed in p, changes the
    accelerations as the same change in Pinocchio's model does."""
    path = robot_file("ur_description/urdf/ur5_robot.urdf")
    model = gen.Model.from_urdf(path, constants="symbolic", name="ur5_sym")
    sim = gen.compile(model)
    assert {"m_forearm_link", "c_forearm_link_z", "I_forearm_link_xy"} <= set(
        sim.constant_names)
    pm = pin.buildModelFromUrdf(str(path))
    j = pm.getJointId("elbow_joint")            # forearm_link's joint
    rng = np.random.default_rng(2)
    q, v, tau = rng.uniform(-2, 2, (3, 6))
    x = np.concatenate([q, v])
    assert rel_err(sim.rhs(0.0, x, r=tau)[6:], pin.aba(pm, pm.createData(), q, v, tau)) < TOL
    Y = pm.inertias[j]
    mass = Y.mass * 1.7                         # (Y is a view of pm.inertias[j])
    pm.inertias[j] = pin.Inertia(mass, Y.lever.copy(), Y.inertia.copy())
    p = {"m_forearm_link": mass}
    want = pin.aba(pm, pm.createData(), q, v, tau)
    got = sim.rhs(0.0, x, r=tau, p=p)[6:]
    assert rel_err(got, want) < TOL
    assert rel_err(sim.rhs(0.0, x, r=tau)[6:], want) > 1e-3      # the change matters


# ----------------------------------------------------------- floating base
@pytest.mark.slow
def test_solo12_floating_against_pinocchio():
    path = robot_file("solo_description/robots/solo12.urdf")
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    pd = pm.createData()
    model = gen.Model.from_urdf(path, base="floating", name="solo12")
    sim = gen.compile(model)
    nq, nv = pm.nq, pm.nv
    assert (len(model.q), len(model.u), len(model.r)) == (nq, nv, nv - 6)
    assert model.state_names[:7] == ["base_x", "base_y", "base_z", "base_qx", "base_qy",
                                     "base_qz", "base_qw"]
    assert model.state_names[nq:nq + 6] == ["base_vx", "base_vy", "base_vz", "base_wx",
                                            "base_wy", "base_wz"]
    assert model.state_names[7:nq] == [f"q_{pm.names[j]}" for j in range(2, pm.njoints)]
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = unit_quaternions(rng.uniform(-1, 1, nq + nv), model.state_names)
        tau = rng.uniform(-1, 1, nv - 6)
        q, v = x[:nq], x[nq:]
        a = pin.aba(pm, pd, q, v, np.concatenate([np.zeros(6), tau]))
        assert rel_err(sim.rhs(0.0, x, r=tau)[nq:], a) < TOL
    # derivatives: Pinocchio's d/dq is along the tangent (q + N(q) dq), N the
    # kinematics' d q'/du (the top right block of our Jacobian)
    Jx, _ = sim.jacobian(0.0, x, r=tau)
    pin.computeABADerivatives(pm, pd, q, v, np.concatenate([np.zeros(6), tau]))
    N = Jx[:nq, nq:]
    assert rel_err(Jx[nq:, :nq] @ N, pd.ddq_dq) < 1e-8
    assert rel_err(Jx[nq:, nq:], pd.ddq_dv) < 1e-8


# ------------------------------------------------------------------ mimic
ARM = """<robot name="arm">
  <link name="base"><inertial><mass value="2"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="a"><inertial><origin xyz="0.2 0.05 0" rpy="0.1 0 0.2"/><mass value="1.5"/><inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0.001" ixz="0.002" iyz="0.003"/></inertial></link>
  <link name="b"><inertial><origin xyz="0.1 0 0.02"/><mass value="0.7"/><inertia ixx="0.01" iyy="0.012" izz="0.013" ixy="0" ixz="0.001" iyz="0"/></inertial>
    <visual><geometry><mesh filename="package://nowhere/b.stl"/></geometry></visual></link>
  <link name="c"><inertial><mass value="0.3"/><inertia ixx="0.002" iyy="0.003" izz="0.004" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"><visual><geometry><mesh filename="package://nowhere/tip.stl"/></geometry></visual></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0 0 0.3" rpy="0.3 0 0"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="a"/><child link="b"/><origin xyz="0.4 0 0" rpy="0 0.2 0"/><axis xyz="0 1 0"/></joint>
  <joint name="j3" type="prismatic"><parent link="b"/><child link="c"/><origin xyz="0.3 0 0"/><axis xyz="1 0 1"/><limit lower="-0.1" upper="0.2" effort="1" velocity="1"/><mimic joint="j2" multiplier="0.5" offset="0.1"/></joint>
  <joint name="tool" type="fixed"><parent link="c"/><child link="tip"/><origin xyz="0.05 0 0"/></joint>
</robot>"""


@pytest.mark.slow
def test_mimic_joint_as_a_constraint_and_ignored():
    """mimic="constraints": q_j3 = 0.5 q_j2 + 0.1, dependent; the reference
    is Pinocchio's model without the mimic, reduced by G (v = G v_ind).
    mimic="ignore": three independent joints, Pinocchio's aba itself. The
    Kane formulation of the same System agrees (a small robot)."""
    pm = pin.buildModelFromXML(ARM)
    pd = pm.createData()
    rng = np.random.default_rng(4)
    free = gen.compile(gen.Model.from_urdf(ARM, mimic="ignore", name="arm_free"))
    kane = gen.compile(gen.Model.from_urdf(ARM, mimic="ignore", formulation="kane",
                                           name="arm_kane"))
    q, v, tau = rng.uniform(-1, 1, (3, 3))
    x = np.concatenate([q, v])
    want = pin.aba(pm, pd, pin_q(pm, q), v, tau)
    assert rel_err(free.rhs(0.0, x, r=tau)[3:], want) < TOL
    assert rel_err(kane.rhs(0.0, x, r=tau)[3:], want) < TOL

    model = gen.Model.from_urdf(ARM, name="arm_mimic")
    sim = gen.compile(model)
    assert model.state_names == ["q_j1", "q_j2", "q_j3", "u_j1", "u_j2", "u_j3"]
    assert model.input_names == ["tau_j1", "tau_j2"]
    G = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.5]])
    for _ in range(3):
        q1, q2, v1, v2, t1, t2 = rng.uniform(-1, 1, 6)
        q = np.array([q1, q2, 0.5 * q2 + 0.1])
        v = G @ [v1, v2]
        M = pin.crba(pm, pd, pin_q(pm, q))
        M = np.triu(M) + np.triu(M, 1).T
        b = pin.rnea(pm, pd, pin_q(pm, q), v, np.zeros(3))
        a_ind = np.linalg.solve(G.T @ M @ G, G.T @ (np.array([t1, t2, 0.0]) - b))
        xd = sim.rhs(0.0, np.concatenate([q, v]), r=[t1, t2])
        assert rel_err(xd[3:], G @ a_ind) < TOL


# -------------------------------------------------------------- bad input
def test_bad_files_are_refused_naming_the_link_or_joint():
    loop = ARM.replace('<joint name="tool"', '<joint name="back" type="fixed"><parent '
                       'link="c"/><child link="a"/></joint>\n  <joint name="tool"')
    with pytest.raises(gen.ModelError, match=r"kinematic loop.*link 'a'.*line 3.*joint 'j1'"):
        gen.load_urdf(loop)
    massless = ARM.replace('<link name="c"><inertial><mass value="0.3"/><inertia ixx="0.002" '
                           'iyy="0.003" izz="0.004" ixy="0" ixz="0" iyz="0"/></inertial></link>',
                           '<link name="c"/>')
    with pytest.raises(gen.ModelError, match=r"link 'c' \(line 6 .*no inertia.*joint 'j3'"):
        gen.load_urdf(massless, mimic="ignore")
    with pytest.raises(gen.ModelError, match=r"joint 'j2' \(line 9 .*unknown type 'spherical'"):
        gen.load_urdf(ARM.replace('type="continuous"', 'type="spherical"'))
    with pytest.raises(gen.ModelError, match=r"malformed XML at line 3"):
        gen.load_urdf(ARM.replace('<link name="a">', '<link name="a>'))
    with pytest.raises(gen.ModelError, match=r"no file"):
        gen.load_urdf("/nonexistent/robot.urdf")
    # meshes are never read: links with mesh-only geometry (missing files)
    robot = gen.load_urdf(ARM)
    assert robot.joints == ["j1", "j2", "j3"]
    assert robot.limits == {"j1": (-1.0, 1.0), "j3": (-0.1, 0.2)}
    with pytest.raises(gen.ModelError, match=r"base='wobbly'"):
        gen.load_urdf(ARM, base="wobbly")


@pytest.mark.slow
def test_joint_limits_as_impacts():
    """hybrid="limits": each limit a plastic impact (gen.Impact): the joint
    driven into its stop stays inside its range, where the same robot
    without the impacts goes past it."""
    model = gen.Model.from_urdf(ARM, hybrid="limits", mimic="ignore", name="arm_limits")
    sim = gen.compile(model)
    assert sim.hybrid_names == ["j1_lower", "j1_upper", "j3_lower", "j3_upper"]
    x0 = np.array([0.9, 0.0, 0.0, 2.0, 0.0, 0.0])
    sol = sim.simulate(x0, 1.0, 1e-3)
    assert sol.success
    assert -1 - 1e-9 <= sol.x[:, 0].min() and sol.x[:, 0].max() <= 1 + 1e-9
    assert sol.x[:, 0].max() > 1 - 1e-6                          # it reached the stop
    assert -0.1 - 1e-9 <= sol.x[:, 2].min() and sol.x[:, 2].max() <= 0.2 + 1e-9
    free = gen.compile(gen.Model.from_urdf(ARM, mimic="ignore", name="arm_free"))
    assert free.simulate(x0, 1.0, 1e-3).x[:, 0].max() > 1.05


def test_right_angles_are_exact_and_rounded_angles_kept():
    """A joint origin's rpy right angles (cos(pi/2) = 6.1e-17 in double)
    reach the System as exact 0 and +-1 (the generated code folds them);
    an angle the file rounds (3.14159265359: sine 2e-13) stays as SciPy's
    rotation of it, as Pinocchio reads it."""
    from scipy.spatial.transform import Rotation
    urdf = ARM.replace('xyz="0 0 0.3" rpy="0.3 0 0"',
                       'xyz="0 0 0.3" rpy="1.5707963267948966 0 -1.5707963267948966"'
                       ).replace('xyz="0.4 0 0" rpy="0 0.2 0"', 'xyz="0.4 0 0" rpy="0 3.14159265359 0"')
    assert urdf.count("1.5707963267948966") == 2 and "3.14159265359" in urdf
    robot = gen.load_urdf(urdf, mimic="ignore")
    joint = {j.name: j for j in robot.system.joints}

    def placement(name):
        j = joint[name]
        return j.parent_interframe.dcm(j.parent.frame)

    right = placement("j1")
    want = Rotation.from_euler("xyz", [np.pi / 2, 0, -np.pi / 2]).as_matrix()
    assert 0 < np.abs(want[np.abs(want) < 0.5]).max() < 1e-15      # SciPy's is rounded
    assert all(e in (0, 1, -1) and e.is_Integer for e in right)
    assert any(np.array_equal(np.array(m.tolist(), dtype=float), np.round(want))
               for m in (right, right.T))
    rounded = np.array(placement("j2").tolist(), dtype=float)
    want = Rotation.from_euler("xyz", [0, 3.14159265359, 0]).as_matrix()
    assert min(np.abs(m - want).max() for m in (rounded, rounded.T)) < 1e-16
    assert 1e-13 < np.abs(rounded[np.abs(rounded) < 0.5]).max() < 1e-12
