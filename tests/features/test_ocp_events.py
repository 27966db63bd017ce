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
        (dict(events=["heelstrike", "heelstrike"]),
         "events=['heelstrike', 'heelstrike']: one event (one phase) is supported so far; a "
         "sequence of phases is not"),
        (dict(events=["heelstrike"], method="midpoint"),
         "events: the guard's crossing is checked through the last node's slopes, which "
         "method='midpoint' has not; use 'hermite-simpson', 'trapezoidal' or "
         "'backward-euler'"),
        (dict(periodic="yes"), "periodic must be True or False, got 'yes'"),
    ]
    for kw, msg in cases:
        with pytest.raises(gen.InputError) as e:
            gen.OptimalControl(model, 11, (2, 6), terminal_cost=t, **kw)
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
def test_event_rows_derivatives_against_finite_differences(walker):
    """The guard, its rate and the periodicity across the heel strike's map
    (generated kernels scattered by the C loop): Jacobian and the exact
    Hessian of the Lagrangian against central differences of the C's own
    values, at a random point."""
    sw, model = walker
    o = gen.OptimalControl(model, 4, (2.0, 6.0), terminal_cost=sm.Symbol("t"),
                           method="trapezoidal", events=["heelstrike"], periodic=True)
    o._assemble()
    o._p = o._pvec()
    rows = {name: b for name, b in o._rows0.items()}
    assert {"guard", "guard_rate", "periodic"} <= set(rows)
    rng = np.random.default_rng(3)
    n, m = o._lay.n, o._m_rows
    z = rng.uniform(-0.8, 0.8, n)
    z[o._lay.T] = 3.0

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
    ev = [r for name in ("guard", "guard_rate", "periodic") for r0 in rows[name]
          for r in range(r0, r0 + {"guard": 1, "guard_rate": 1, "periodic": 4}[name])]
    assert np.abs(Jfd[ev]).max() > 0.1          # rows that are there
