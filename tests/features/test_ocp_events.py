"""gen.OptimalControl ending on an event, periodic (issue 46): Garcia's
simplest walker's passive gait found by optimisation.

References: the published fixed point (Garcia, Chatterjee, Ruina and
Coleman 1998: theta = 0.2003, theta' = -0.1998 at gamma = 0.009, a step of
3.8825), the fixed point of the stride map found by Newton's method on the
simulator (examples/simplest_walker.py), and the simulator replaying the
gait through its own heel-strike event."""
import os
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sm

import gen

try:
    import cyipopt  # noqa: F401
except ImportError:  # pragma: no cover - the CI installs it (the test extra)
    cyipopt = None

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def walker():
    sys.path.insert(0, str(EXAMPLES))
    try:
        import simplest_walker as sw
    finally:
        sys.path.remove(str(EXAMPLES))
    return sw, sw.model(name="walker_ocp")


def test_events_are_checked_before_building(walker, monkeypatch):
    sw, model = walker

    def refuse(*a, **k):
        raise AssertionError("built despite the error")
    monkeypatch.setattr(gen.pipeline, "product", refuse)
    t = sm.Symbol("t")
    cases = [
        (dict(events=["toe"]), "events: 'toe' is not a hybrid declaration of model "
                               "'walker_ocp' (its declarations: heelstrike)"),
        (dict(events="heelstrike"), "events must be a list of model 'walker_ocp''s hybrid "
                                    "names, got 'heelstrike'"),
        (dict(events=["heelstrike", "heelstrike"], duration=3.0),
         "events=['heelstrike', 'heelstrike']: each phase's duration is free; give duration "
         "as (lo, hi), the bounds of every phase's, not 3.0"),
        (dict(events=["heelstrike"], method="midpoint"),
         "events: the guard's crossing is checked through the last node's slopes, which "
         "method='midpoint' has not; use 'hermite-simpson', 'trapezoidal' or "
         "'backward-euler'"),
        (dict(periodic="yes"), "periodic must be True or False, got 'yes'"),
    ]
    for kw, msg in cases:
        kw = {"duration": (2, 6), **kw}
        with pytest.raises(gen.InputError) as e:
            gen.OptimalControl(model, 11, terminal_cost=t, **kw)
        assert str(e.value) == msg
    # without events=, the declarations are named: not solved through silently
    with pytest.warns(UserWarning) as w, pytest.raises(AssertionError, match="built despite"):
        gen.OptimalControl(model, 11, (2, 6), terminal_cost=t)
    assert str(w[0].message) == (
        "model 'walker_ocp' has hybrid declarations (heelstrike) that events= does not name: "
        "the trajectory is optimised as if they were not there, and may cross their guards "
        "without their jumps")


@pytest.mark.slow
@pytest.mark.skipif(cyipopt is None and os.environ.get("CI") != "true",
                    reason="cyipopt not installed (pip install eomgen[ocp])")
def test_passive_walker_gait_found_by_optimisation(walker):
    """One phase ending on the heel strike, periodic, no input (a
    feasibility problem; the duration minimised within (2, 6)), Hermite-
    Simpson at 101 nodes, from one simulated step off the gait: the fixed
    point of the stride map to 1e-5 and the published one to its digits;
    replayed through the simulator, the step returns to itself within 1e-6."""
    sw, model = walker
    sim = gen.compile(model)
    z_ref, _ = sw.fixed_point(sw.stride_map(sim))
    ref = sim.simulate(sw.start(z_ref), 4.5, 4.5, method="dopri5", rtol=1e-12, atol=1e-12)
    T_ref = [e for e in ref.events if e.name == "heelstrike"][0].t
    # the guess: one step of the simulator from (0.2, -0.2)
    run = sim.simulate(sw.start([0.2, -0.2]), 4.5, 0.01, method="dopri5", rtol=1e-10,
                       atol=1e-12)
    T0 = [e for e in run.events if e.name == "heelstrike"][0].t
    N = 101
    Xg = run.sol(np.linspace(0, T0 * (1 - 1e-9), N))
    guess = {n: Xg[:, i] for i, n in enumerate(model.state_names)}
    guess["duration"] = T0
    ocp = gen.OptimalControl(model, N, (2.0, 6.0), terminal_cost=sm.Symbol("t"),
                             method="hermite-simpson", events=["heelstrike"], periodic=True)
    sol = ocp.solve(guess, tol=1e-12)
    assert sol.status == 0, sol.message
    theta, thetad, T = sol.x[0, 0], sol.x[0, 2], sol.t[-1]
    assert abs(theta - z_ref[0]) < 1e-5 and abs(thetad - z_ref[1]) < 1e-5, (sol.x[0], z_ref)
    assert abs(T - T_ref) < 1e-5, (T, T_ref)
    assert round(theta, 4) == 0.2003 and round(thetad, 4) == -0.1998 and round(T, 4) == 3.8825
    (ph,) = sol.phases
    assert ph.event == "heelstrike" and ph.t[-1] == T
    np.testing.assert_allclose(ph.x_after, sol.x[0], atol=1e-10)     # periodic
    rep = sim.simulate(sol.x[0], 1.05 * T, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
    strike = [e for e in rep.events if e.name == "heelstrike"][0]
    assert abs(strike.t - T) < 1e-6
    assert np.abs(strike.x_after - sol.x[0]).max() < 1e-6


@pytest.mark.slow
@pytest.mark.parametrize("phases", [1, 2])
def test_event_rows_derivatives_against_finite_differences(walker, phases):
    """The guard, its rate and the periodicity across the heel strike's map
    (generated kernels scattered by the C loop), one phase or two (the map
    joining them, each phase's own duration in its time and steps): Jacobian
    and the exact Hessian of the Lagrangian against central differences of
    the C's own values, at a random point."""
    sw, model = walker
    o = gen.OptimalControl(model, 4, (2.0, 6.0), terminal_cost=sm.Symbol("t"),
                           method="trapezoidal", events=["heelstrike"] * phases, periodic=True)
    _check_derivatives(o, phases, {"guard0": 1, "rate0": 1, "jump0": 4})


@pytest.mark.slow
def test_impulse_rows_derivatives_against_finite_differences():
    """An impact's impulse equations (q+ = q, M (u+ - u) = W^T imp,
    W u+ + w = -e (W u + w)) on a point mass in polar coordinates (its mass
    matrix and the gap's W depend on r and theta) striking the ground
    y = r sin(theta): derivatives against central differences."""
    import sympy.physics.mechanics as me
    r, th = me.dynamicsymbols("r theta")
    m, g = sm.symbols("m g")
    lm = me.LagrangesMethod(m * (r.diff()**2 + r**2 * th.diff()**2) / 2 - m * g * r * sm.sin(th),
                            [r, th])
    lm.form_lagranges_equations()
    model = gen.Model.from_lagrange(lm, constants={m: 1.3, g: 9.81}, name="polar_ocp",
                                    hybrid={"ground": gen.Impact(r * sm.sin(th), restitution=0.5)})
    o = gen.OptimalControl(model, 3, (0.5, 2.0), terminal_cost=sm.Symbol("t"),
                           method="trapezoidal", events=["ground", "ground"])
    _check_derivatives(o, 2, {"guard0": 1, "rate0": 1, "jump0": 5}, jumps=1)


def _check_derivatives(o, phases, nrows, jumps=None):
    """The problem's Jacobian and exact Hessian of the Lagrangian (random
    multipliers) against central differences of the C's values, at a random
    point; the event rows are there and not zero."""
    o._assemble()
    o._p = o._pvec()
    rows = {name: b for name, b in o._rows0.items()}
    assert set(nrows) <= set(rows)
    rng = np.random.default_rng(3)
    n, m = o._lay.n, o._m_rows
    z = rng.uniform(-0.8, 0.8, n)
    z[o._lay.Ts] = np.linspace(3.0, 2.5, phases)
    assert len(rows["jump0"]) == (phases if jumps is None else jumps)
    assert len(rows["guard0"]) == phases

    def dense(vals, r, c, shape):
        out = np.zeros(shape)
        np.add.at(out, (r, c), vals)
        return out
    J = dense(o.evaluate(z, "jacobian"), o._jrows, o._jcols, (m, n))
    lam = rng.normal(size=m)
    H = dense(o._call(o._what["hessian"], z, len(o._hrows), lam, 0.0), o._hrows, o._hcols,
              (n, n))
    H = H + np.tril(H, -1).T
    eps = 1e-6

    def lagrangian_gradient(zz):
        return dense(o.evaluate(zz, "jacobian"), o._jrows, o._jcols, (m, n)).T @ lam
    Jfd, Hfd = np.zeros((m, n)), np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = eps
        Jfd[:, j] = (o.evaluate(z + e, "constraints") - o.evaluate(z - e, "constraints")) / (2 * eps)
        Hfd[:, j] = (lagrangian_gradient(z + e) - lagrangian_gradient(z - e)) / (2 * eps)
    assert np.abs(J - Jfd).max() < 1e-7 * max(1, np.abs(Jfd).max())
    assert np.abs(H - Hfd).max() < 1e-6 * max(1, np.abs(Hfd).max())
    ev = [r for name in nrows for r0 in rows[name] for r in range(r0, r0 + nrows[name])]
    assert np.abs(Jfd[ev]).max() > 0.1          # rows that are there


G, ALPHA, GAMMA = 9.81, np.pi / 6, 0.3


def rimless_wheel(name):
    """The rimless wheel (McGeer 1990): spokes of length 1, 2 alpha apart,
    down a slope gamma; theta'' = g sin(theta) from the vertical, and when
    theta reaches gamma + alpha the next spoke strikes: theta -> theta -
    2 alpha, theta' -> cos(2 alpha) theta' (angular momentum about the new
    foot)."""
    import sympy.physics.mechanics as me
    th = me.dynamicsymbols("theta")
    m, g, a, gam = sm.symbols("m g alpha gamma")
    lm = me.LagrangesMethod(m * th.diff()**2 / 2 - m * g * sm.cos(th), [th])
    lm.form_lagranges_equations()
    strike = gen.Reset(th - (gam + a), {th: th - 2 * a, th.diff(): sm.cos(2 * a) * th.diff()},
                       direction=1)
    return gen.Model.from_lagrange(lm, constants={m: 1.0, g: G, a: ALPHA, gam: GAMMA},
                                   name=name, hybrid={"strike": strike})


@pytest.mark.slow
@pytest.mark.skipif(cyipopt is None and os.environ.get("CI") != "true",
                    reason="cyipopt not installed (pip install eomgen[ocp])")
def test_rimless_wheel_two_phases_against_the_analytic_steady_state():
    """Two phases (two steps), each ending on the strike with its own free
    duration, the strike's map carrying the first into the second and the
    second back to the start (periodic). The speed after each strike is the
    analytic cot(2 alpha) sqrt(4 g sin(alpha) sin(gamma)) (energy over a
    step: w-^2 = w+^2 + 4 g sin(alpha) sin(gamma); the strike: w+ = cos(2
    alpha) w-) to 1e-6; each phase's duration is the simulator's strike
    time from the analytic state to 1e-6; sol.replay() makes the simulator's
    own two strikes at the phases' ends."""
    model = rimless_wheel("rimless_ocp")
    sim = gen.compile(model)
    after = np.sqrt(4 * G * np.sin(ALPHA) * np.sin(GAMMA)) / np.tan(2 * ALPHA)
    before = after / np.cos(2 * ALPHA)
    ref = sim.simulate([GAMMA - ALPHA, after], 1.0, 1.0, method="dopri5", rtol=1e-12,
                       atol=1e-12)
    T_ref = ref.events[0].t
    # the guess: the first step from a speed off the cycle, for both phases
    run = sim.simulate([GAMMA - ALPHA, 1.5], 3.0, 0.01, method="dopri5", rtol=1e-10,
                       atol=1e-12)
    T0 = run.events[0].t
    N = 21
    Xg = run.sol(np.linspace(0, T0 * (1 - 1e-9), N))
    guess = {n: np.concatenate([Xg[:, i]] * 2) for i, n in enumerate(model.state_names)}
    guess["duration"] = [T0, T0]
    ocp = gen.OptimalControl(model, N, (0.05, 5.0), terminal_cost=sm.Symbol("t"),
                             events=["strike", "strike"], periodic=True)
    sol = ocp.solve(guess, tol=1e-12)
    assert sol.status == 0, sol.message
    p1, p2 = sol.phases
    assert (p1.event, p2.event) == ("strike", "strike") and len(p1.t) == len(p2.t) == N
    for ph in (p1, p2):
        assert abs(ph.x[0, 0] - (GAMMA - ALPHA)) < 1e-9 and abs(ph.x[-1, 0] - (GAMMA + ALPHA)) < 1e-9
        assert abs(ph.x[0, 1] - after) < 1e-6 and abs(ph.x[-1, 1] - before) < 1e-6, ph.x
        assert abs((ph.t[-1] - ph.t[0]) - T_ref) < 1e-6, (ph.t, T_ref)
    np.testing.assert_allclose(p1.x_after, p2.x[0], atol=1e-10)       # the map joins them
    np.testing.assert_allclose(p2.x_after, p1.x[0], atol=1e-10)       # periodic
    assert p2.t[0] == p1.t[-1] and sol.t[-1] == p2.t[-1]
    # the interpolant stays within its phase: at the first strike, the state after it
    np.testing.assert_allclose(sol(p1.t[-1]), p2.x[0], atol=1e-12)
    rep = sol.replay(rtol=1e-12, atol=1e-12)
    strikes = [e for e in rep.events if e.name == "strike"]
    assert len(strikes) == 2
    assert abs(strikes[0].t - p1.t[-1]) < 1e-6 and abs(strikes[1].t - p2.t[-1]) < 1e-6
    assert np.abs(strikes[1].x_after - sol.x[0]).max() < 1e-6


@pytest.mark.slow
@pytest.mark.skipif(cyipopt is None and os.environ.get("CI") != "true",
                    reason="cyipopt not installed (pip install eomgen[ocp])")
def test_ball_two_phases_across_its_impact_against_the_analytic_bounce():
    """A gen.Impact ending a phase: the ball dropped from rest at y = 1, two
    phases each ending on the ground (the impact's impulse, an unknown of
    the problem, carrying the first into the second). Against the analytic
    fall (t1 = sqrt(2 y0 / g), v- = -sqrt(2 g y0), v+ = -e v-, the bounce
    2 v+ / g) to 1e-9, and against the simulator's own two impacts (times
    and the states after them) on replay."""
    import sympy.physics.mechanics as me
    y = me.dynamicsymbols("y")
    m, g = sm.symbols("m g")
    lm = me.LagrangesMethod(m * y.diff()**2 / 2 - m * g * y, [y])
    lm.form_lagranges_equations()
    e, g0 = 0.8, 9.81
    ball = gen.Model.from_lagrange(lm, constants={m: 1.0, g: g0}, name="ball_ocp",
                                   hybrid={"ground": gen.Impact(y, restitution=e)})
    t1 = np.sqrt(2 / g0)
    v_before = -np.sqrt(2 * g0)
    v_after = -e * v_before
    t2 = 2 * v_after / g0
    N = 11
    tau = np.linspace(0, 1, N)
    yg = np.concatenate([1 - tau, 0.5 * np.sin(np.pi * tau)])
    ocp = gen.OptimalControl(ball, N, (0.05, 5.0), terminal_cost=sm.Symbol("t"),
                             events=["ground", "ground"], initial={"y": 1.0, "y_d": 0.0})
    sol = ocp.solve({"y": yg, "duration": [0.5, 1.0]}, tol=1e-12)
    assert sol.status == 0, sol.message
    p1, p2 = sol.phases
    assert abs(p1.t[-1] - t1) < 1e-9 and abs(p2.t[-1] - p2.t[0] - t2) < 1e-9, (p1.t, p2.t)
    assert abs(p1.x[-1, 1] - v_before) < 1e-9 and abs(p2.x[0, 1] - v_after) < 1e-9
    np.testing.assert_allclose(p1.x_after, p2.x[0], atol=1e-9)
    assert abs(p2.x_after[1] - e * e * -v_before) < 1e-9      # the second bounce's speed
    rep = sol.replay(rtol=1e-12, atol=1e-12)      # to the last phase's end: one impact inside
    assert [ev.name for ev in rep.events] == ["ground"]
    assert abs(rep.events[0].t - p1.t[-1]) < 1e-8
    run = ocp.simulator.simulate(sol.x[0], 1.05 * sol.t[-1], 0.01, method="dopri5",
                                 rtol=1e-12, atol=1e-12)
    hits = [ev for ev in run.events if ev.name == "ground"]
    assert len(hits) == 2
    assert abs(hits[0].t - p1.t[-1]) < 1e-8 and abs(hits[1].t - p2.t[-1]) < 1e-8
    np.testing.assert_allclose(hits[0].x_after, p2.x[0], atol=1e-8)
    np.testing.assert_allclose(hits[1].x_after, p2.x_after, atol=1e-8)
    with pytest.raises(gen.InputError) as err:
        sol.tracker(np.eye(2), np.eye(0), 0.01)
    assert str(err.value) == ("tracker: this solution has 2 phases (events ['ground', "
                              "'ground']); a tracker follows one phase, not a trajectory "
                              "across events")


def _impulse_strike(x, Mh, m, b, l=1.0):
    """The heel strike of examples/compass_gait.py by the impulse method, in
    numpy (Westervelt, Grizzle et al. 2007, 3.4): the walker floating (hip
    x, y and each leg's absolute angle), D (p+' - p-') = J^T Lambda with the
    new stance foot's velocity J p+' = 0; then the legs swap."""
    th, ph, om, mu, tau = x
    thd = om
    phd = mu + 2 * om
    psi, psid = th - ph, thd - phd                      # the swing leg's angle, rate
    pd = np.array([-l * np.cos(th) * thd, -l * np.sin(th) * thd, thd, psid])

    def point(a, s, k):       # hip + s (sin a, -cos a): its Jacobian in (x, y, th, psi)
        J = np.zeros((2, 4))
        J[:, :2] = np.eye(2)
        J[:, k] = [s * np.cos(a), s * np.sin(a)]
        return J
    Jh = np.zeros((2, 4))
    Jh[:, :2] = np.eye(2)
    D = Mh * Jh.T @ Jh + sum(m * J.T @ J for J in (point(th, b, 2), point(psi, b, 3)))
    Jf = point(psi, l, 3)
    K = np.block([[D, -Jf.T], [Jf, np.zeros((2, 2))]])
    after = np.linalg.solve(K, np.concatenate([D @ pd, [0, 0]]))[:4]
    th1, thd1, phd1 = psi, after[3], after[3] - after[2]
    return np.array([th1, -ph, thd1, phd1 - 2 * thd1, -tau])


@pytest.mark.slow
@pytest.mark.skipif(cyipopt is None and os.environ.get("CI") != "true",
                    reason="cyipopt not installed (pip install eomgen[ocp])")
def test_powered_compass_gait_replays_through_its_heel_strikes():
    """The powered compass gait on flat ground (examples/compass_gait.py: hip
    mass 1, leg masses 0.5 at 0.5 from the hip, a hip torque tau with rate
    sigma), least effort for a step of 0.5 in 2.0: its heel strike (from
    angular momentum, derived in sympy) against the impulse method in
    numpy, and Garcia's map in the limit of massless legs; the optimum
    replayed through the simulator, which makes its own strike, to the
    transcription's accuracy as the nodes double; the motor's torque
    continuous and smooth across the strike (tau(0) = -tau(T) by the
    periodic map, and its rate too, which nothing imposes)."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        import compass_gait as cg
    finally:
        sys.path.remove(str(EXAMPLES))
    # Garcia's heel strike in the limit of massless legs with feet at their ends
    garcia = gen.compile(cg.model(m=1e-9, b=1.0, name="compass_garcia"))
    run = garcia.simulate([-0.2, -0.4 - 1e-4, -0.2, 0.1, 0.0], 0.01, 0.01, method="dopri5",
                          rtol=1e-12, atol=1e-12)      # just before the guard phi = 2 theta
    (ev,) = run.events
    assert ev.name == "heelstrike"
    th, ph, om, _, _ = ev.x
    c2 = np.cos(ph)
    assert abs(ph - 2 * th) < 1e-12
    assert abs(ev.x_after[2] - c2 * om) < 1e-7
    assert abs(ev.x_after[3] + 2 * ev.x_after[2] - c2 * (1 - c2) * om) < 1e-7
    model = cg.model(name="compass_ocp")
    errs, sols = [], []
    for N in (41, 81):
        ocp, sol = cg.powered_gait(model, nodes=N, tol=1e-12)
        assert sol.status == 0, sol.message
        T = sol.t[-1]
        (phase,) = sol.phases
        assert abs(2 * np.sin(-phase.x[-1, 0]) - 0.5) < 1e-12 and abs(phase.x[-1, 3] - 0.2) < 1e-12
        # the strike's map at the optimum: the impulse method's
        np.testing.assert_allclose(phase.x_after, _impulse_strike(phase.x[-1], 1.0, 0.5, 0.5),
                                   rtol=0, atol=1e-12)
        run = ocp.simulator.simulate(sol.x[0], 1.05 * T, 0.01,       # sigma held after T
                                     r=lambda t, x, s=sol, T=T: s.input(min(t, T)),
                                     method="dopri5", input_period=0, rtol=1e-13, atol=1e-13)
        (strike,) = [e for e in run.events if e.name == "heelstrike"]
        np.testing.assert_allclose(strike.x_after, _impulse_strike(strike.x, 1.0, 0.5, 0.5),
                                   rtol=0, atol=1e-12)
        errs.append(max(abs(strike.t - T), np.abs(strike.x - phase.x[-1]).max(),
                        np.abs(strike.x_after - sol.x[0]).max()))
        sols.append(sol)
    assert errs[1] < 1e-5 and errs[0] / errs[1] > 8, errs      # fourth order or near it
    sol = sols[1]
    tau, sigma = sol.x[:, 4], sol.r[:, 0]
    assert abs(tau[0] + tau[-1]) < 1e-10                       # the motor's torque
    assert abs(sigma[0] + sigma[-1]) < 1e-3 * np.abs(sigma).max()    # and its rate
