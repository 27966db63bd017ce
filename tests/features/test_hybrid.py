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


# ------------------------------------------------------------ simplest walker
GAMMA, BETA = 0.009, 1e-6


def _walker_lagrangian():
    """Garcia, Chatterjee, Ruina and Coleman (1998): a hip mass M and a foot
    mass m = BETA M on massless legs of length l, on a slope GAMMA (g = l = 1);
    theta the stance leg's angle from the slope normal, phi the angle between
    the legs."""
    th, ph = me.dynamicsymbols("theta phi")
    Mh, mf, g, l, gam = sm.symbols("M_h m_f g l gamma")
    t = me.dynamicsymbols._t
    hip = sm.Matrix([-l * sm.sin(th), l * sm.cos(th)])
    foot = hip + sm.Matrix([l * sm.sin(th - ph), -l * sm.cos(th - ph)])
    ag = sm.Matrix([g * sm.sin(gam), -g * sm.cos(gam)])
    vh, vf = hip.diff(t), foot.diff(t)
    T = (Mh * vh.dot(vh) + mf * vf.dot(vf)) / 2
    V = -(Mh * ag.dot(hip) + mf * ag.dot(foot))
    consts = {Mh: 1.0, mf: BETA, g: 1.0, l: 1.0, gam: GAMMA}
    return T - V, th, ph, consts


def _walker_model():
    Lag, th, ph, consts = _walker_lagrangian()
    thd, phd = th.diff(), ph.diff()
    lm = me.LagrangesMethod(Lag, [th, ph])
    lm.form_lagranges_equations()
    c2 = sm.cos(2 * th)
    # heel strike: the swing foot reaches the slope (phi = 2 theta, moving
    # up through it: the mid-stance scuffing crosses downwards), Garcia's map
    # in the limit of a small foot mass
    strike = gen.Reset(ph - 2 * th, {th: -th, ph: -2 * th, thd: c2 * thd,
                                     phd: c2 * (1 - c2) * thd}, direction=1)
    return gen.Model.from_lagrange(lm, constants=consts, name="hyb_walker",
                                   hybrid={"heelstrike": strike})


def _newton(stride, z0, h=1e-7, iters=8):
    z = np.array(z0, dtype=float)
    for _ in range(iters):
        S = stride(z)
        J = np.column_stack([(stride(z + dz) - stride(z - dz)) / (2 * h)
                             for dz in np.eye(2) * h])
        step = np.linalg.solve(J - np.eye(2), S - z)
        z = z - step
        if np.max(np.abs(step)) < 1e-13:
            break
    J = np.column_stack([(stride(z + dz) - stride(z - dz)) / (2 * h) for dz in np.eye(2) * h])
    return z, J


def _start(z):
    a, ad = z
    return np.array([a, 2 * a, ad, (1 - np.cos(2 * a)) * ad])


def _scipy_stride_map():
    """The same model integrated by SciPy: M and f of the Euler-Lagrange
    equations lambdified here, DOP853 with an event at the heel strike."""
    from scipy.integrate import solve_ivp
    Lag, th, ph, consts = _walker_lagrangian()
    t = me.dynamicsymbols._t
    q = [th, ph]
    qd = [s.diff(t) for s in q]
    qdd = [s.diff(t) for s in qd]
    eqs = sm.Matrix([Lag.diff(v).diff(t) - Lag.diff(s) for s, v in zip(q, qd)]).xreplace(consts)
    Mm = eqs.jacobian(qdd)
    F = -eqs.xreplace({a: 0 for a in qdd})
    X = sm.symbols("x0:4")
    sub = dict(zip(q + qd, X))
    Mf = sm.lambdify([X], Mm.xreplace(sub), "numpy")
    Ff = sm.lambdify([X], F.xreplace(sub), "numpy")

    def rhs(_t, x):
        acc = np.linalg.solve(np.array(Mf(x), dtype=float), np.array(Ff(x), dtype=float).ravel())
        return np.concatenate([x[2:], acc])

    def strike(_t, x):
        return x[1] - 2 * x[0]
    strike.direction = 1
    strike.terminal = True

    def stride(z):
        # the first half second apart: SciPy would take phi - 2 theta = 0
        # at the start for a crossing
        s0 = solve_ivp(rhs, (0, 0.5), _start(z), method="DOP853", rtol=1e-13, atol=1e-13)
        s = solve_ivp(rhs, (0.5, 4.5), s0.y[:, -1], method="DOP853", rtol=1e-13, atol=1e-13,
                      events=strike)
        x = s.y_events[0][0]
        c2 = np.cos(2 * x[0])
        return np.array([-x[0], c2 * x[2]])
    return stride


@pytest.mark.slow
def test_simplest_walker_fixed_point():
    sim = gen.compile(_walker_model())

    def stride(z):
        sol = sim.simulate(_start(z), 4.5, 4.5, method="dopri5", rtol=1e-12, atol=1e-12)
        ev = [e for e in sol.events if e.name == "heelstrike"][0]
        return np.array([ev.x_after[0], ev.x_after[2]])

    z, J = _newton(stride, [0.2, -0.2])
    # Garcia et al. 1998, gamma = 0.009: theta = 0.2003, theta' = -0.1998
    assert abs(z[0] - 0.2003) < 1e-4 and abs(z[1] + 0.1998) < 1e-4
    # a stable gait: the stride map's eigenvalues inside the unit circle
    assert np.max(np.abs(np.linalg.eigvals(J))) < 1
    # the same model by SciPy
    z_ref, _ = _newton(_scipy_stride_map(), [0.2, -0.2])
    assert np.max(np.abs(z - z_ref)) < 1e-8


@pytest.mark.slow
def test_inconsistent_reset_is_an_error():
    """A reset whose map leaves the pendulum's circle stops the run with
    ERR_INCONSISTENT_RESET, naming the reset."""
    q1, q2 = me.dynamicsymbols("q1:3")
    m = _pendulum(0.5, "hyb_pend_bad")
    from gen.intake.hybrid import attach_hybrid
    attach_hybrid(m, {"kick": gen.Reset(q2 + sm.Rational(1, 5), {q1: 2 * q1})})
    sim = gen.compile(m)
    with pytest.raises(gen.SolverError, match=r"hyb_pend_bad_simulate_events: the map of reset "
                       r"'kick' at t = 0\.6058\d+ gives a state that violates the model's "
                       r"constraints: q1=1\.9595.*\[ERR_INCONSISTENT_RESET\], the state before "
                       r"it: q1=0\.9797"):
        sim.simulate([np.cos(0.8), np.sin(0.8), 0.0, 0.0], 1.5, 0.01, method="dopri5")


# ------------------------------------------------------- standalone binary
def _events_csv(path):
    import csv
    with open(path) as fh:
        rows = list(csv.reader(fh))
    return rows[0], [(r[0], [float(v) for v in r[1:]]) for r in rows[1:]]


@pytest.mark.slow
@pytest.mark.parametrize("which", ["ball", "walker"])
def test_binary_matches_python(which, tmp_path):
    """The standalone binary runs the same engine: its event CSV (with the
    states after each jump) and its rows are Python's, bit for bit."""
    import subprocess
    from conftest import build_binary
    if which == "ball":
        model, x0, t_end = _ball(name="hyb_ball_bin"), [1.0, 0.0], 6.0
    else:
        model, x0, t_end = _walker_model(), list(_start([0.2003, -0.1998])), 8.0
    exe = build_binary(model, tmp_path)
    sim = gen.compile(model)
    sol = sim.simulate(x0, t_end, 0.05, method="dopri5", rtol=1e-10, atol=1e-12)
    evcsv, out = tmp_path / "ev.csv", tmp_path / "x.csv"
    subprocess.run([str(exe), "--method", "dopri5", "--rtol", "1e-10", "--atol", "1e-12",
                    "--t-end", str(t_end), "--dt", "0.05",
                    "--x0", ",".join(repr(float(v)) for v in x0), "--events-csv", str(evcsv),
                    "--output", str(out)], check=True, capture_output=True)
    head, rows = _events_csv(evcsv)
    nx = sim.nx
    assert head[:2] == ["event", "t"] and head[2 + nx:] == [f"{n}_after" for n in sim.state_names]
    assert len(rows) == len(sol.events) > 0
    for (name, vals), ev in zip(rows, sol.events):
        assert name == ev.name
        assert vals[0] == ev.t
        assert vals[1:1 + nx] == list(ev.x)
        assert vals[1 + nx:] == list(ev.x_after)
    X = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    assert np.array_equal(X[:, 0], sol.t)
    assert np.array_equal(X[:, 1:1 + nx], sol.x)


def test_hybrid_work_sizes_match_runtime(tmp_path):
    """gen.hybrid's work lengths are the runtime's GEN_RT_HYBRID_WORK and
    GEN_RT_HYBRID_IWORK macros (Python allocates what C uses)."""
    import subprocess
    from pathlib import Path
    from gen.codegen.backends import c_compiler
    from gen.intake.hybrid import hybrid_iwork_len, hybrid_work_len
    csrc = Path(gen.__file__).resolve().parent.parent / "csrc" / "runtime"
    sizes = [(1, 1, 0, 1), (3, 3, 0, 2), (2, 2, 1, 1), (2, 2, 1, 3), (7, 6, 2, 4)]
    body = "".join(f'    printf("%d %d\\n", (int)GEN_RT_HYBRID_WORK({a}, {b}, {c}, {d}), '
                   f'(int)GEN_RT_HYBRID_IWORK({a}, {b}, {c}, {d}));\n' for a, b, c, d in sizes)
    src = tmp_path / "w.c"
    src.write_text('#include <stdio.h>\n#include "gen_rt.h"\nint main(void)\n{\n' + body +
                   "    return 0;\n}\n")
    exe = tmp_path / "w"
    subprocess.run([c_compiler(), "-std=c99", f"-I{csrc}", str(src), "-o", str(exe)], check=True)
    got = [tuple(map(int, line.split())) for line in
           subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout.split("\n")
           if line]
    assert got == [(hybrid_work_len(*s), hybrid_iwork_len(*s)) for s in sizes]


# ------------------------------------------------- compliant contact (RODAS4)
@pytest.mark.slow
def test_compliant_contact_rests_without_stalling():
    """The documented alternative: a Hunt-Crossley force (Piecewise, Max)
    integrated by RODAS4 settles at the static penetration (m g / k)^(2/3),
    and a 100x longer rest takes a bounded number of further steps."""
    import bouncing_ball
    sim = gen.compile(bouncing_ball.compliant_model(k=1e5, alpha=1.5))
    steps = {}
    for t_end in (10.0, 1000.0):
        sol = sim.simulate([1.0, 0.0], t_end, t_end, method="rodas4", rtol=1e-6, atol=1e-9)
        steps[t_end] = sol.stats["n_steps"]
        assert sol.x[-1, 0] == pytest.approx(-(G / 1e5) ** (2 / 3), rel=1e-5)
        assert abs(sol.x[-1, 1]) < 1e-8
    assert steps[1000.0] - steps[10.0] <= 30


# ---------------------------------------------------- float Cortex-M build
@pytest.mark.slow
@pytest.mark.embedded
def test_cortex_m_float_footprint():
    """The ball and the walker cross-built for a Cortex-M4F in float (the
    embedded subset: no heap, no stdio, no globals): simulate_events, the
    hybrid engine included, links and reports its flash and worst-case stack."""
    import bouncing_ball
    import simplest_walker
    import gen.toolchain.footprint as fp
    from conftest import require_tool
    require_tool("cmake")
    require_tool("arm-none-eabi-gcc")
    reps = fp.report_many([(bouncing_ball.model(), "float"), (simplest_walker.model(), "float")],
                          target="cortex-m4f", workers=2)
    print("\n" + fp.format_table(reps))
    for rep in reps:
        assert rep["flash"]["data"] == 0 and rep["flash"]["bss"] == 0
        assert rep["flash"]["flash"] > 1000
        f = rep["functions"][rep["model"] + "_simulate_events"]
        assert 0 < f["frame"] <= f["stack"] <= rep["max_stack"]
        assert not any(n in rep["libc"] for n in ("malloc", "free", "printf", "calloc"))
        # no double arithmetic in a float build
        assert not any(n.startswith("__aeabi_d") for n in rep["libc"]), rep["libc"]
        print(f"{rep['model']} [float, cortex-m4f]: flash {rep['flash']['flash']} B, "
              f"simulate_events stack {f['stack']} B")


@pytest.mark.slow
def test_float_build_bounces():
    """The same engine in float: the bounce times within float's tolerance."""
    sim = gen.compile(_ball(name="hyb_ball_f"), real="float")
    sol = sim.simulate([1.0, 0.0], 3.0, 0.01, method="dopri5", rtol=1e-5, atol=1e-6)
    t1, v1 = np.sqrt(2 / G), np.sqrt(2 * G)
    t_exact = t1 + np.concatenate([[0.0], np.cumsum(2 * v1 * 0.8 ** np.arange(1, 4) / G)])
    t_found = np.array([ev.t for ev in sol.events[:4]])
    assert np.max(np.abs(t_found - t_exact)) < 1e-4


# ------------------------------------------------------------ FMU (FMI 2.0 ME)
@pytest.mark.slow
def test_fmu_model_exchange_ball_and_walker(tmp_path):
    """FMI 2.0 Model Exchange with one event indicator per declaration and
    the state update at the event, in FMPy (CVODE's root finding):
    validate_fmu is clean; the bounce times agree with the analytic ones
    (the first 20 to 1e-8: later ones are bounded by the importer's error
    in the gap, which its root finding divides by the falling speed), the
    ball rests at the end; the walker's heel strikes are Python's to 1e-8."""
    fmpy = pytest.importorskip("fmpy")
    from fmpy.validation import validate_fmu
    import simplest_walker
    import bouncing_ball
    # the ball
    path = tmp_path / "ball.fmu"
    gen.export_fmu(bouncing_ball.model(), str(path), kind="me", fmi_version="2.0")
    assert validate_fmu(str(path)) == []
    r = fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=6.0,
                          output_interval=0.01, relative_tolerance=1e-12, output=["y", "v"],
                          start_values={"y": 1.0})
    t, v = r["time"], r["v"]
    # an impact: two rows at one time, falling before and rising after
    ti = t[np.where((np.diff(t) == 0) & (v[:-1] < 0) & (v[1:] > 0))[0]]
    t1, v1 = np.sqrt(2 / G), np.sqrt(2 * G)
    k = np.arange(20)
    t_exact = t1 + np.concatenate([[0.0], np.cumsum(2 * v1 * 0.8 ** k[1:] / G)])
    assert np.max(np.abs(ti[:20] - t_exact)) < 1e-8
    assert abs(r["y"][-1]) < 1e-12 and r["v"][-1] == 0
    # the walker
    path = tmp_path / "walker.fmu"
    model = simplest_walker.model()
    gen.export_fmu(model, str(path), kind="me", fmi_version="2.0")
    assert validate_fmu(str(path)) == []
    names = list(model.state_names)
    x0 = simplest_walker.start([0.2003, -0.1998])
    r = fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=12.0,
                          output_interval=0.01, relative_tolerance=1e-12, output=names,
                          start_values=dict(zip(names, x0)))
    t, th = r["time"], r[names[0]]
    strikes = t[np.where((np.diff(t) == 0) & (np.abs(np.diff(th)) > 0.1))[0]]
    sol = gen.compile(model).simulate(x0, 12.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
    t_py = np.array([e.t for e in sol.events if e.name == "heelstrike"])
    assert len(strikes) == len(t_py) == 3
    assert np.max(np.abs(strikes - t_py)) < 1e-8


def test_fmu_refuses_hybrid_cs_and_fmi3():
    with pytest.raises(gen.ModelError, match=r"hybrid.*kind='me', fmi_version='2.0'"):
        from gen.export.fmu import describe
        describe(_ball(), fmi_version="2.0", kind="both")
    with pytest.raises(gen.ModelError, match=r"FMI 2.0 Model Exchange"):
        describe(_ball(), fmi_version="3.0", kind="me")
