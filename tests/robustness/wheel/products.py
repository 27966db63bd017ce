"""Every product once, run from an installed wheel in a fresh virtual
environment (tests/robustness/test_wheel.py): simulate, the Eigen backend,
an FMU (checked by FMPy), CasADi functions, optimal control with its
tracker, a hybrid model, the recursive formulation, model predictive
control, an extended Kalman filter, a robot from URDF. Each prints one line
`ok <product> <number>`; the numbers are checked here against independent
references (exact physics, the model's own equations)."""
import math
import sys
from pathlib import Path

import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen

assert "site-packages" in gen.__file__, gen.__file__      # the installed wheel, not a checkout


def pendulum(name):
    theta, omega, T = me.dynamicsymbols("theta omega T")
    m, l, g = sm.symbols("m l g")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [theta, N.z])
    A.set_ang_vel(N, omega * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    km = me.KanesMethod(N, q_ind=[theta], u_ind=[omega], kd_eqs=[theta.diff() - omega])
    km.kanes_equations([me.Particle("bob", P, m)], [(P, m * g * N.x), (A, T * N.z)])
    model = gen.Model.from_kanes(km, constants={m: 1.0, l: 0.5, g: 9.81}, inputs=[T], name=name)
    return model, (theta, omega, T)


def check_simulate():
    model, syms = pendulum("wheel_pend")
    sim = gen.compile(model)
    A, _ = sim.linearize([0.0, 0.0])
    assert np.allclose(A, [[0, 1], [-9.81 / 0.5, 0]], rtol=0, atol=1e-12), A
    sol = sim.simulate([0.01, 0.0], 2 * math.pi * math.sqrt(0.5 / 9.81), 1e-3)
    assert abs(sol.x[-1, 0] - 0.01) < 1e-6, sol.x[-1]      # one small-angle period
    print("ok simulate", A[1, 0])
    return model, syms


def check_eigen(model):
    sim = gen.compile(model, backend="eigen")
    ref = gen.compile(model)
    x = np.array([0.3, -0.2])
    assert np.array_equal(sim.rhs(0.0, x, r=[0.1]), ref.rhs(0.0, x, r=[0.1]))   # the C bits
    print("ok eigen", sim.rhs(0.0, x, r=[0.1])[1])


def check_fmu(model, tmp):
    from fmpy import simulate_fmu
    path = gen.export_fmu(model, tmp / "pend.fmu", fmi_version="2.0", kind="me",
                          start={"theta": 0.2})
    res = simulate_fmu(str(path), stop_time=1.0, output_interval=0.01, output=["theta"])
    ref = gen.compile(model).simulate([0.2, 0.0], 1.0, 0.01, method="dopri5", rtol=1e-10,
                                      atol=1e-12)
    err = abs(res["theta"][-1] - ref.x[-1, 0])
    assert err < 1e-4, err
    print("ok fmu", err)


def check_casadi(model):
    import casadi as ca
    F = gen.casadi.functions(model)
    sim = gen.compile(model)
    x, r, p = np.array([0.3, -0.2]), np.array([0.1]), np.array(model.p_values)
    got = F["rhs"](x, r, p, 0.0).full().ravel()
    assert np.allclose(got, sim.rhs(0.0, x, r=r, p=p), rtol=0, atol=1e-14)
    X = ca.MX.sym("x", 2)
    J = ca.Function("J", [X], [ca.jacobian(F["rhs"](X, r, p, 0.0), X)])(x).full()
    assert abs(J[1, 0] - (-9.81 / 0.5 * math.cos(0.3))) < 1e-12, J
    print("ok casadi", J[1, 0])


def check_ocp_and_tracker(model, syms):
    theta, omega, T = syms
    ocp = gen.OptimalControl(model, 41, 2.0, objective=T**2, bounds={T: (-20, 20)},
                             initial={theta: 0.0, omega: 0.0}, final={theta: 1.0, omega: 0.0},
                             method="hermite-simpson")
    sol = ocp.solve()
    assert sol.status == 0, sol.message
    rep = sol.replay(rtol=1e-10, atol=1e-10)
    assert abs(rep.x[-1, 0] - 1.0) < 1e-3, rep.x[-1]
    tracker = sol.tracker(np.diag([100.0, 10.0]), np.array([[0.01]]), 0.01)
    run = ocp.simulator.simulate([0.05, 0.0], 2.0, 1e-3, controller=tracker)
    assert abs(run.x[-1, 0] - 1.0) < 0.02, run.x[-1]
    print("ok ocp+tracker", sol.objective)


def check_hybrid():
    y, v = me.dynamicsymbols("y v")
    m, g = sm.symbols("m g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", y * N.y)
    P.set_vel(N, v * N.y)
    km = me.KanesMethod(N, [y], [v], kd_eqs=[y.diff() - v])
    km.kanes_equations([me.Particle("ball", P, m)], [(P, -m * g * N.y)])
    model = gen.Model.from_kanes(km, constants={m: 1.0, g: 9.81}, name="wheel_ball",
                                 hybrid={"ground": gen.Impact(y, restitution=0.8)})
    sol = gen.compile(model).simulate([1.0, 0.0], 1.0, 1e-3, method="dopri5", rtol=1e-12,
                                      atol=1e-12)
    hit = [e for e in sol.events if e.name == "ground"][0]
    t1 = math.sqrt(2 * 1.0 / 9.81)                         # free fall from 1 m
    assert abs(hit.t - t1) < 1e-9, (hit.t, t1)
    print("ok hybrid", hit.t)


def arm():
    """A two-link arm on PinJoints, a sympy System (the Python API guide's)."""
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    g = sm.symbols("g")
    ground, links = me.RigidBody("ground"), []
    for name, length in (("link1", 0.5), ("link2", 0.4)):
        link = me.RigidBody(name, mass=1.0)
        link.central_inertia = me.inertia(link.frame, 0, 0, length**2 / 12)
        links.append(link)
    system = me.System.from_newtonian(ground)
    system.add_joints(
        me.PinJoint("shoulder", ground, links[0], q1, u1, joint_axis=ground.z,
                    child_point=-0.25 * links[0].frame.x),
        me.PinJoint("elbow", links[0], links[1], q2, u2, joint_axis=links[0].z,
                    parent_point=0.25 * links[0].frame.x, child_point=-0.2 * links[1].frame.x))
    system.add_loads(*[me.Force(b.masscenter, -b.mass * g * ground.y) for b in links])
    return system, g


def check_recursive():
    system, g = arm()
    rec = gen.compile(gen.Model.from_system(system, constants={g: 9.81}, name="wheel_rec",
                                            formulation="recursive"))
    system, g = arm()
    system.form_eoms()
    kane = gen.compile(gen.Model.from_system(system, constants={g: 9.81}, name="wheel_kane"))
    x = np.array([0.3, -0.4, 0.5, 0.2])
    assert np.allclose(rec.rhs(0.0, x), kane.rhs(0.0, x), rtol=1e-12, atol=1e-12)
    print("ok recursive", rec.rhs(0.0, x)[2])


def check_mpc(model, syms):
    """gen.MPC brings the pendulum from 0.5 rad to hanging at rest, |T| <= 1, loop in C."""
    mpc = gen.MPC(model, 20, 0.05, Q=[10.0, 1.0], R=[0.1], bounds={syms[2]: (-1.0, 1.0)})
    u0 = mpc([0.5, 0.0], t=0.0)
    sim = gen.compile(model, derivatives=True)
    sol = sim.simulate([0.5, 0.0], 4.0, 1e-3, controller=mpc)
    assert mpc.status == 0 and abs(u0[0]) <= 1.0, (mpc.status, u0)
    assert np.max(np.abs(sol.r)) <= 1.0 and abs(sol.r[0, 0] - u0[0]) < 1e-12
    assert np.max(np.abs(sol.x[-1])) < 1e-3, sol.x[-1]
    print("ok mpc", sol.x[-1, 0])


def check_estimator():
    """gen.EKF's first predict and update on the pendulum hanging at rest,
    against the linear pendulum's exact transition and the scalar Kalman gain."""
    model, (theta, omega, T) = pendulum("wheel_kf")
    P0 = np.diag([1e-4, 1e-3])
    ekf = gen.EKF(model, {"angle": theta}, 0.01, np.zeros((2, 2)), [1e-4], [0.0, 0.0], P0)
    ekf.predict([0.0])
    w = math.sqrt(9.81 / 0.5)
    c, s = math.cos(w * 0.01), math.sin(w * 0.01)
    F = np.array([[c, s / w], [-w * s, c]])  # exp(A dt) of theta'' = -w^2 theta
    Pp = F @ P0 @ F.T
    assert np.allclose(ekf.P, Pp, rtol=1e-6, atol=0), ekf.P   # RK4 against exp: (w dt)^5/120
    ekf.update([0.01])                       # K = P H^T / (H P H^T + R)
    K = Pp[:, 0] / (Pp[0, 0] + 1e-4)
    assert np.allclose(ekf.x, K * 0.01, rtol=1e-6, atol=0), ekf.x
    print("ok estimator", ekf.x[0])


URDF = """<robot name="pend">
  <link name="base"/>
  <link name="arm">
    <inertial><origin xyz="0 0 -0.5"/><mass value="1.0"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="10"/></joint>
</robot>"""


def check_robots():
    """A URDF pendulum (yourdfpy) against its small-oscillation rate
    m g l / (I + m l^2) about the hinge."""
    model = gen.Model.from_urdf(URDF, name="wheel_urdf")
    A, _ = gen.compile(model).linearize([0.0, 0.0])
    w2 = 1.0 * 9.81 * 0.5 / (0.01 + 1.0 * 0.5 ** 2)
    assert np.allclose(A, [[0, 1], [-w2, 0]], rtol=0, atol=1e-12), A
    print("ok robots", A[1, 0])


def main():
    tmp = Path(sys.argv[1])
    model, syms = check_simulate()
    check_eigen(model)
    check_fmu(model, tmp)
    check_casadi(model)
    check_ocp_and_tracker(model, syms)
    check_hybrid()
    check_recursive()
    check_mpc(model, syms)
    check_estimator()
    check_robots()


if __name__ == "__main__":
    main()
