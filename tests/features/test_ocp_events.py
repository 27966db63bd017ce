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
    o._assemble()
    o._p = o._pvec()
    rows = {name: b for name, b in o._rows0.items()}
    assert {"guard0", "rate0", "jump0"} <= set(rows)
    rng = np.random.default_rng(3)
    n, m = o._lay.n, o._m_rows
    z = rng.uniform(-0.8, 0.8, n)
    z[o._lay.Ts] = np.linspace(3.0, 2.5, phases)
    assert len(rows["jump0"]) == phases and len(rows["guard0"]) == phases

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
    ev = [r for name in ("guard0", "rate0", "jump0") for r0 in rows[name]
          for r in range(r0, r0 + {"guard0": 1, "rate0": 1, "jump0": 4}[name])]
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
