"""Hybrid models (issue 35): impacts with the impulse solved in C, persistent
contact and the Zeno rule, resets, and bad input.

References are independent of the code under test: the bouncing ball's
impact times from the analytic geometric series, the falling rod's velocities
after impact from the impulse equations solved here with numpy, and the
constrained pendulum's constraints and normal speed evaluated here.
"""
import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me

import gen

G = 9.81


# ------------------------------------------------------------------ models
def _ball(e=0.8, name="hyb_ball"):
    y, v = me.dynamicsymbols("y v")
    m, g = sm.symbols("m g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", y * N.y)
    P.set_vel(N, v * N.y)
    km = me.KanesMethod(N, [y], [v], kd_eqs=[y.diff() - v])
    km.kanes_equations([me.Particle("b", P, m)], [(P, -m * g * N.y)])
    return gen.Model.from_kanes(km, constants={m: 1.0, g: G}, name=name,
                                hybrid={"ground": gen.Impact(y, restitution=e)})


def _rod(e, name):
    """A planar rod (x, y, theta) of length L falling onto the ground y = 0:
    the gap of its lower end."""
    x, y, th, vx, vy, w = me.dynamicsymbols("x y theta vx vy omega")
    m, g, L = sm.symbols("m g L")
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    B.set_ang_vel(N, w * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)
    C.set_vel(N, vx * N.x + vy * N.y)
    I = me.inertia(B, 0, 0, m * L**2 / 12)
    rod = me.RigidBody("rod", C, B, m, (I, C))
    km = me.KanesMethod(N, [x, y, th], [vx, vy, w],
                        kd_eqs=[x.diff() - vx, y.diff() - vy, th.diff() - w])
    km.kanes_equations([rod], [(C, -m * g * N.y)])
    gap = y - L / 2 * sm.sin(th)
    return gen.Model.from_kanes(km, constants={m: 2.0, g: G, L: 1.5}, name=name,
                                hybrid={"end": gen.Impact(gap, restitution=e)})


def _pendulum(e, name):
    """The seed nonminimal pendulum (x, y with x^2 + y^2 = L^2, Kane with a
    dependent coordinate and speed) and a slanted wall q2 + 0.3 q1 + 0.4 L >= 0."""
    q1, q2, u1, u2 = me.dynamicsymbols("q1:3 u1:3")
    L, m, g = sm.symbols("L m g")
    N = me.ReferenceFrame("N")
    pN = me.Point("N*")
    pN.set_vel(N, 0)
    theta1 = sm.atan(q2 / q1)
    A = N.orientnew("A", "axis", [theta1, N.z])
    P = pN.locatenew("P1", q1 * N.x + q2 * N.y)
    pP = me.Particle("pP", P, m)
    kd = sm.Matrix([q1.diff() - u1, q2.diff() - u2])
    P.set_vel(N, P.pos_from(pN).dt(N))
    f_c = sm.Matrix([P.pos_from(pN).magnitude() - L])
    f_v = sm.Matrix([P.vel(N).express(A).dot(A.x)])
    f_v.simplify()
    km = me.KanesMethod(N, q_ind=[q1], u_ind=[u1], kd_eqs=kd, q_dependent=[q2],
                        configuration_constraints=f_c, u_dependent=[u2],
                        velocity_constraints=f_v)
    km.kanes_equations([pP], [(P, m * g * N.x)])
    gap = q2 + sm.Rational(3, 10) * q1 + sm.Rational(2, 5) * L
    return gen.Model.from_kanes(km, constants={L: 1.0, m: 1.0, g: G}, name=name,
                                hybrid={"wall": gen.Impact(gap, restitution=e)})


# ----------------------------------------------------------- bouncing ball
@pytest.fixture(scope="module")
def ball():
    return gen.compile(_ball())


@pytest.mark.slow
def test_ball_impact_times_and_rest(ball):
    h0, e = 1.0, 0.8
    sol = ball.simulate([h0, 0.0], 6.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
    t1 = np.sqrt(2 * h0 / G)
    v1 = np.sqrt(2 * G * h0)
    k = np.arange(50)
    # t_1, then flights of 2 v1 e^k / g
    t_exact = t1 + np.concatenate([[0.0], np.cumsum(2 * v1 * e ** (k[1:]) / G)])
    t_found = np.array([ev.t for ev in sol.events if ev.name == "ground"][:50])
    assert len(t_found) == 50
    assert np.max(np.abs(t_found - t_exact)) < 1e-10
    # each impact: the speed after is -e times the speed before
    for ev in sol.events[:50]:
        assert ev.x_after[1] == pytest.approx(-e * ev.x[1], rel=1e-12, abs=1e-15)
        assert ev.x_after[0] == ev.x[0]
    # at rest after the Zeno time t_Z = t1 + 2 v1 e / (g (1 - e))
    t_zeno = t1 + 2 * v1 * e / (G * (1 - e))
    last = [ev.t for ev in sol.events if ev.name == "ground"][-1]
    assert last <= t_zeno + 1e-9
    after = sol.t > t_zeno + 1e-6
    assert np.all(np.abs(sol.x[after, 0]) < 1e-12)
    assert np.all(sol.x[after, 1] == 0)


@pytest.mark.slow
def test_ball_rest_bounded_steps(ball):
    """Resting on the ground, the steps grow: a 100x longer rest takes a
    bounded number of further steps (no stalled step)."""
    runs = {}
    for t_end in (10.0, 1000.0):
        sol = ball.simulate([1.0, 0.0], t_end, t_end, method="dopri5", rtol=1e-10, atol=1e-12)
        runs[t_end] = sol.stats["n_accepted"]
        assert abs(sol.x[-1, 0]) < 1e-10 and sol.x[-1, 1] == 0
    assert runs[1000.0] - runs[10.0] <= 30


@pytest.mark.slow
def test_ball_rk4_and_rodas4(ball):
    """The fixed-step RK4 finishes its step from the event time; RODAS4
    restarts too: both find the first bounce where it is."""
    t1 = np.sqrt(2 / G)
    for method, tol in (("rk4", 1e-9), ("rodas4", 1e-9)):
        sol = ball.simulate([1.0, 0.0], 1.0, 1e-3, method=method, rtol=1e-12, atol=1e-12)
        assert sol.events[0].name == "ground"
        assert abs(sol.events[0].t - t1) < tol, method
        assert sol.events[0].x_after[1] == pytest.approx(0.8 * np.sqrt(2 * G), rel=1e-7)


# -------------------------------------------------------------- falling rod
def _rod_reference(xb, e, m=2.0, L=1.5):
    """The velocities after the impact, solved here: M du = J^T P,
    J u+ = -e J u- with J = d(gap)/dq = [0, 1, -L/2 cos theta]."""
    th = xb[2]
    u = xb[3:]
    M = np.diag([m, m, m * L**2 / 12])
    J = np.array([0.0, 1.0, -L / 2 * np.cos(th)])
    Minv = np.linalg.inv(M)
    P = -(1 + e) * (J @ u) / (J @ Minv @ J)
    return u + Minv @ J * P


@pytest.mark.slow
@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_rod_impact(e):
    sim = gen.compile(_rod(e, f"hyb_rod_{int(e * 10)}"))
    x0 = [0.0, 1.0, 0.5, 0.3, 0.0, 1.2]
    sol = sim.simulate(x0, 0.6, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
    ev = [v for v in sol.events if v.name == "end"][0]
    xb, xa = ev.x, ev.x_after
    assert abs(xb[1] - 0.75 * np.sin(xb[2])) < 1e-12            # at the gap
    ref = _rod_reference(xb, e)
    assert np.max(np.abs(xa[3:] - ref)) < 1e-12
    assert np.all(xa[:3] == xb[:3])
    m, L = 2.0, 1.5
    ke = lambda x: 0.5 * m * (x[3]**2 + x[4]**2) + 0.5 * m * L**2 / 12 * x[5]**2  # noqa: E731
    if e == 1.0:
        assert abs(ke(xa) - ke(xb)) < 1e-12 * max(1.0, ke(xb))
    else:
        assert ke(xa) < ke(xb)
    # the end's normal speed after: -e times before
    vn = lambda x: x[4] - L / 2 * np.cos(x[2]) * x[5]  # noqa: E731
    assert abs(vn(xa) + e * vn(xb)) < 1e-12


# ------------------------------------------------- constrained pendulum
@pytest.mark.slow
@pytest.mark.parametrize("e", [0.0, 0.7])
def test_pendulum_wall_keeps_constraints(e):
    sim = gen.compile(_pendulum(e, f"hyb_pend_{int(e * 10)}"))
    L = 1.0
    phi = 0.8
    x0 = [L * np.cos(phi), L * np.sin(phi), 0.0, 0.0]
    sol = sim.simulate(x0, 1.5, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
    ev = [v for v in sol.events if v.name == "wall"][0]
    xb, xa = ev.x, ev.x_after
    gap = lambda x: x[1] + 0.3 * x[0] + 0.4 * L  # noqa: E731
    vn = lambda x: x[3] + 0.3 * x[2]             # noqa: E731
    assert abs(gap(xb)) < 1e-12
    assert vn(xb) < -0.1
    # the model's constraints after the impact
    assert abs(xa[0]**2 + xa[1]**2 - L**2) < 1e-12
    assert abs(xa[0] * xa[2] + xa[1] * xa[3]) < 1e-12
    # the normal speed after is -e times before
    assert abs(vn(xa) + e * vn(xb)) < 1e-12
    # and the motion goes on from there on the circle
    assert np.max(np.abs(sol.x[:, 0]**2 + sol.x[:, 1]**2 - L**2)) < 1e-9


# ---------------------------------------------------------------- bad input
def test_bad_input_names_symbols():
    y, v, z = me.dynamicsymbols("y v z")
    m, g, k = sm.symbols("m g k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", y * N.y)
    P.set_vel(N, v * N.y)
    km = me.KanesMethod(N, [y], [v], kd_eqs=[y.diff() - v])
    km.kanes_equations([me.Particle("b", P, m)], [(P, -m * g * N.y)])
    c = {m: 1.0, g: G}
    with pytest.raises(gen.ModelError, match=r"gap of impact 'floor'.*speed\(s\) v"):
        gen.Model.from_kanes(km, constants=c, hybrid={"floor": gen.Impact(y + 0.1 * v)})
    with pytest.raises(gen.ModelError, match=r"unknown symbol\(s\) k"):
        gen.Model.from_kanes(km, constants=c, hybrid={"floor": gen.Impact(y - k)})
    with pytest.raises(gen.ModelError, match=r"unknown symbol\(s\) z"):
        gen.Model.from_kanes(km, constants=c, hybrid={"floor": gen.Impact(y - z)})
    with pytest.raises(gen.ModelError, match=r"restitution must be in \[0, 1\], got 1.5"):
        gen.Impact(y, restitution=1.5)
    with pytest.raises(gen.ModelError, match=r"restitution must be in \[0, 1\], got -0.1"):
        gen.Impact(y, restitution=-0.1)
    with pytest.raises(gen.ModelError, match="direction must be"):
        gen.Impact(y, direction=2)
    with pytest.raises(gen.ModelError, match="direction must be"):
        gen.Reset(y, {v: -v}, direction=0.5)
    with pytest.raises(gen.ModelError, match=r"sets z, which is not a state.*y, v"):
        gen.Model.from_kanes(km, constants=c, hybrid={"jump": gen.Reset(y, {z: 0})})
    with pytest.raises(gen.ModelError, match=r"must be gen.Impact or gen.Reset"):
        gen.Model.from_kanes(km, constants=c, hybrid={"floor": y})
    # a good declaration is kept in the internal symbols
    mod = gen.Model.from_kanes(km, constants=c, hybrid={"floor": gen.Impact(y, 0.5)})
    assert [d.name for d in mod.hybrid] == ["floor"]
    assert mod.hybrid[0].expr == mod.q[0]
