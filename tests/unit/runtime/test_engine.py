"""The simulation engine (issue 16): dense output, events, the stiff
method RODAS4 and bounded output, checked against exact physics (the
pendulum's elliptic-integral times), SciPy (DOP853, Radau) and the
engine's own full output.

The C pieces (orders of the continuous extension, the Hermite
interpolant, RODAS4 and its estimate) are tested in tests/c/test_engine.c.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk, ellipkinc

import cart_pole
import gen
import stiff_double_pendulum
from helpers import pendulum_state

L, G = 1.0, 9.81
TH0 = np.pi / 3


def quarter_period(theta0=TH0):
    return np.sqrt(L / G) * ellipk(np.sin(theta0 / 2) ** 2)


def time_to(theta1, theta0=TH0):
    """Time from rest at theta0 down to theta1 (0 <= theta1 < theta0): with
    sin(theta/2) = k sin(phi), t = sqrt(L/g) (K(k) - F(phi1, k))."""
    k = np.sin(theta0 / 2)
    phi1 = np.arcsin(np.sin(theta1 / 2) / k)
    return np.sqrt(L / G) * (ellipk(k ** 2) - ellipkinc(phi1, k ** 2))


@pytest.fixture(scope="module", params=["kane", "lagrange"])
def seed(request, kane_sim, lagrange_sim):
    sim = kane_sim if request.param == "kane" else lagrange_sim
    return sim, pendulum_state(TH0, 0.0, L, request.param)


SETTINGS = {"dopri5": dict(dt=0.01, rtol=1e-12, atol=1e-12),
            "rodas4": dict(dt=0.01, rtol=1e-12, atol=1e-12),
            "rk4": dict(dt=1e-3)}


def _run(sim, x0, method, t_end=2.0, **kw):
    s = dict(SETTINGS[method])
    dt = s.pop("dt")
    return sim.simulate(x0, t_end, dt, method=method, **s, **kw)


# ------------------------------------------------------------------ events
@pytest.mark.parametrize("method", ["dopri5", "rodas4", "rk4"])
def test_first_crossing_is_the_exact_quarter_period(seed, method):
    """The independent coordinate (y = L sin theta) crosses zero first at T/4
    and then every T/2: to 1e-9 relative (the acceptance), both directions."""
    sim, x0 = seed
    name = sim.independent_state_names[0]
    sol = _run(sim, x0, method, events={name: 0})
    t, X, ev, st = sol.t, sol.x, sol.events, sol.stats
    T4 = quarter_period()
    times = np.array([e[1] for e in ev])
    assert len(ev) == st["n_events"] == 2 and st["terminal"] is None
    assert abs(times[0] - T4) / T4 < 1e-9, (times[0], T4)
    assert abs(times[1] - 3 * T4) / T4 < 1e-9
    for name_e, te, xe in ev:
        assert name_e == name
        assert abs(xe[sim.state_names.index(name)]) < 1e-8
        # the logged state is on the constraint (projected dense output)
        q = xe[:2]
        assert abs(q @ q - L ** 2) < 1e-12
    # directions: the first crossing goes down (theta decreasing), the second up
    down = _run(sim, x0, method, events={name: -1}).events
    up = _run(sim, x0, method, events={name: +1}).events
    assert [e[1] for e in down] == [times[0]] and [e[1] for e in up] == [times[1]]


@pytest.mark.parametrize("method", ["dopri5", "rodas4", "rk4"])
def test_terminal_event_ends_the_run_at_the_event(seed, method):
    sim, x0 = seed
    name = sim.independent_state_names[0]
    t_full, X_full = _run(sim, x0, method)
    sol = _run(sim, x0, method, events={name: 0}, terminal=True)
    t, X, ev = sol.t, sol.x, sol.events
    te, xe = ev[0][1], ev[0][2]
    assert len(ev) == 1 and abs(te - quarter_period()) / quarter_period() < 1e-9
    # the last row is the event state; the rows before are the full run's
    assert t[-1] == te and np.array_equal(X[-1], xe)
    n = len(t) - 1
    assert np.all(t_full[:n] < te) and t_full[n] >= te
    np.testing.assert_array_equal(t[:n], t_full[:n])
    np.testing.assert_array_equal(X[:n], X_full[:n])
    # per-event terminal dict; final_only keeps only the event row
    t2, X2 = _run(sim, x0, method, events={name: 0, sim.state_names[0]: 0},
                  terminal={name: True}, final_only=True)
    assert len(t2) == 1 and t2[0] == te and np.array_equal(X2[0], xe)


@pytest.mark.parametrize("method", ["dopri5", "rodas4"])
def test_level_crossing_against_the_elliptic_integral(seed, method):
    """y = L sin(theta) crossing L/2 on the way down: theta = pi/6, at
    sqrt(L/g) (K(k) - F(phi1, k))."""
    sim, x0 = seed
    name = sim.independent_state_names[0]
    ev = _run(sim, x0, method, t_end=1.0, events={name: (-1, 0.5 * L)}).events
    want = time_to(np.pi / 6)
    assert abs(ev[0][1] - want) / want < 1e-9
    assert abs(ev[0][2][sim.state_names.index(name)] - 0.5 * L) < 1e-9


@pytest.mark.parametrize("method", ["dopri5", "rodas4", "rk4"])
def test_each_crossing_is_logged_once(seed, method):
    """Crossings of levels off zero, where projecting the event state can
    move the value back across the level: y = L sin(theta) = L/2 (theta =
    30 degrees) twice in 2 s, and x = L cos(theta) = 0.9 L four times, at
    the times of the elliptic integral."""
    sim, x0 = seed
    iq = sim.independent_state_names[0]                        # y
    dq = next(n for n in sim.state_names[:2] if n != iq)       # x
    ev = _run(sim, x0, method, events={iq: (0, 0.5 * L), dq: (0, 0.9 * L)}).events
    T = 4 * quarter_period()
    ta, tb = time_to(np.pi / 6), time_to(np.arccos(0.9))
    want = sorted([(ta, iq), (T - ta, iq), (tb, dq), (T / 2 - tb, dq), (T / 2 + tb, dq),
                   (T - tb, dq)])
    assert [e[0] for e in ev] == [n for _, n in want]
    np.testing.assert_allclose([e[1] for e in ev], [t for t, _ in want], rtol=1e-9)


def test_output_event_agrees_with_the_state_event():
    """An output (the cart-pole's tip height, 2 l cos(theta)) crossing zero
    is the pole passing horizontal: the same time as theta crossing pi/2,
    located through the outputs kernel instead of the state."""
    sim = gen.compile(cart_pole.model())
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    ev_y = sim.simulate(x0, 3.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12,
                        events={"tip_y": -1}, terminal=True).events
    ev_q = sim.simulate(x0, 3.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12,
                        events={"theta": (+1, np.pi / 2)}, terminal=True).events
    assert len(ev_y) == len(ev_q) == 1
    assert abs(ev_y[0][1] - ev_q[0][1]) < 1e-10
    assert abs(ev_y[0][2][1] - np.pi / 2) < 1e-9


def test_many_events_are_all_returned(kane_sim):
    """More crossings than the first log holds (256): the run is repeated
    with room for all; they come every T/2."""
    x0 = pendulum_state(TH0, 0.0, L, "kane")
    sol = kane_sim.simulate(x0, 300.0, 1.0, method="dopri5", rtol=1e-10, atol=1e-10,
                            events={"q2": 0})
    t, X, ev, st = sol.t, sol.x, sol.events, sol.stats
    T4 = quarter_period()
    times = np.array([e[1] for e in ev])
    assert len(ev) == st["n_events"] > 256
    np.testing.assert_allclose(times, T4 * (1 + 2 * np.arange(len(ev))), rtol=0, atol=1e-6)


def test_bad_event_arguments_name_the_states(kane_sim):
    x0 = pendulum_state(TH0, 0.0, L, "kane")
    with pytest.raises(ValueError, match=r"neither a state nor an output.*q2"):
        kane_sim.simulate(x0, 1.0, 0.1, events={"theta": 0})
    with pytest.raises(ValueError, match="direction"):
        kane_sim.simulate(x0, 1.0, 0.1, events={"q2": 2})
    with pytest.raises(ValueError, match="not in events"):
        kane_sim.simulate(x0, 1.0, 0.1, events={"q2": 0}, terminal={"q1": True})
    with pytest.raises(gen.InputError, match="terminal= needs events") as e:
        kane_sim.simulate(x0, 1.0, 0.1, terminal=True)
    assert e.value.argument == "terminal"


# ------------------------------------------------------------ dense output
def test_dopri5_steps_do_not_depend_on_the_output_grid(kane_sim):
    """DOPRI5 steps by its error control alone: the same steps (and rhs
    count) for output every 0.1, 0.01 and 0.001 s, and rows at common times
    agree; the interpolated rows are as accurate as the steps (against
    SciPy's DOP853 at tight tolerance)."""
    x0 = pendulum_state(TH0, 0.0, L, "kane")
    runs = {dt: kane_sim.simulate(x0, 3.0, dt, method="dopri5", rtol=1e-8, atol=1e-10)
            for dt in (0.1, 0.01, 0.001)}
    counts = {dt: r.stats["n_rhs"] for dt, r in runs.items()}
    assert len(set(counts.values())) == 1, counts
    np.testing.assert_allclose(runs[0.01][1], runs[0.001][1][::10], rtol=0, atol=1e-13)
    ref = solve_ivp(lambda t, x: kane_sim.rhs(t, x), (0, 3.0), x0, method="DOP853",
                    rtol=1e-13, atol=1e-14, t_eval=runs[0.001][0])
    err = np.max(np.abs(runs[0.001][1] - ref.y.T))
    assert err < 1e-6, err


@pytest.mark.slow
def test_dopri5_no_more_evaluations_than_scipy_rk45_for_no_larger_error():
    """The issue's case (bench/bench_peers.py): the n = 4 pendulum on a cart,
    10 s, rtol 1e-8, atol 1e-10, output every 0.01 s. SciPy's RK45 uses the
    same Dormand-Prince pair and RMS norm; eomgen's DOPRI5 (dense output,
    Hairer's PI step control) makes no more rhs evaluations for an error
    (against DOP853 at 1e-13, over all rows and at t = 10) no larger."""
    import math
    import n_link_cart
    n = 4
    sim = gen.compile(n_link_cart.model(n))
    x0 = np.array([0.0] + [math.pi + (0.3 if i % 2 == 0 else -0.2) for i in range(n)]
                  + [0.0] * (n + 1))
    sol = sim.simulate(x0, 10.0, 0.01, method="dopri5", rtol=1e-8, atol=1e-10)
    t, X, st = sol.t, sol.x, sol.stats
    fun = lambda t, x: sim.rhs(t, x)  # noqa: E731
    rk = solve_ivp(fun, (0, 10.0), x0, method="RK45", rtol=1e-8, atol=1e-10, t_eval=t)
    ref = solve_ivp(fun, (0, 10.0), x0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t)
    e_ours, e_rk45 = np.max(np.abs(X - ref.y.T)), np.max(np.abs(rk.y.T - ref.y.T))
    f_ours, f_rk45 = np.max(np.abs(X[-1] - ref.y[:, -1])), np.max(np.abs(rk.y[:, -1] - ref.y[:, -1]))
    print(f"eomgen {st['n_rhs']} rhs, errors {e_ours:.2e} / {f_ours:.2e}; "
          f"RK45 {rk.nfev} rhs, errors {e_rk45:.2e} / {f_rk45:.2e}")
    assert st["n_rhs"] <= rk.nfev
    assert e_ours <= e_rk45 and f_ours <= f_rk45


@pytest.mark.parametrize("method", ["dopri5", "rodas4"])
def test_every_and_final_only_are_rows_of_the_full_output(kane_sim, method):
    x0 = pendulum_state(TH0, 0.3, L, "kane")
    kw = dict(method=method, rtol=1e-9, atol=1e-9)
    t, X = kane_sim.simulate(x0, 1.0, 0.01, **kw)
    t3, X3 = kane_sim.simulate(x0, 1.0, 0.01, every=7, **kw)
    tf, Xf = kane_sim.simulate(x0, 1.0, 0.01, final_only=True, **kw)
    keep = sorted(set(range(0, len(t), 7)) | {len(t) - 1})
    np.testing.assert_array_equal(t3, t[keep])
    np.testing.assert_array_equal(X3, X[keep])
    np.testing.assert_array_equal(Xf[0], X[-1])


# -------------------------------------------------------------- RODAS4
@pytest.fixture(scope="module")
def stiff():
    return gen.compile(stiff_double_pendulum.model())


def test_rodas4_on_a_stiff_model(stiff):
    """The double pendulum with a critically damped elbow spring 1e4 times
    faster than its swing: RODAS4 at rtol 1e-6 reaches DOPRI5's final state
    at tight tolerance to 1e-6 with at least 20x fewer evaluations (rhs +
    Jacobians) than DOPRI5 needs at rtol 1e-6; SciPy's Radau (with the
    generated Jacobian) at the same tolerance agrees."""
    x0 = np.array([1.0, 0.0, 0.0, 0.0])
    big = dict(max_steps=10 ** 8)
    ref = stiff.simulate(x0, 2.0, 0.01, method="dopri5", rtol=1e-10, atol=1e-10, **big)
    d = stiff.simulate(x0, 2.0, 0.01, method="dopri5", rtol=1e-6, atol=1e-6, **big)
    r = stiff.simulate(x0, 2.0, 0.01, method="rodas", rtol=1e-6, atol=1e-6, **big)
    (Xref, sref), (Xd, sd), (Xr, sr) = ((s.x, s.stats) for s in (ref, d, r))
    ours = sr["n_rhs"] + sr["n_jac"]
    print(f"dopri5 1e-6: {sd['n_rhs']} rhs; rodas4 1e-6: {sr['n_rhs']} rhs + {sr['n_jac']} "
          f"Jacobians; |rodas4 - ref| = {np.max(np.abs(Xr[-1] - Xref[-1])):.2e}")
    assert np.max(np.abs(Xr[-1] - Xref[-1])) < 1e-6
    assert sd["n_rhs"] >= 20 * ours
    radau = solve_ivp(lambda t, x: stiff.rhs(t, x), (0, 2.0), x0, method="Radau", rtol=1e-6,
                      atol=1e-6, jac=lambda t, x: stiff.jacobian(t, x)[0])
    assert radau.success
    assert np.max(np.abs(radau.y[:, -1] - Xref[-1])) < 1e-5
    assert np.max(np.abs(Xr[-1] - radau.y[:, -1])) < 1e-5


def test_rodas4_matches_dopri5_on_non_stiff_models(seed):
    sim, x0 = seed
    _, Xd = sim.simulate(x0, 2.0, 0.01, method="dopri5", rtol=1e-11, atol=1e-11)
    sol = sim.simulate(x0, 2.0, 0.01, method="rodas4", rtol=1e-9, atol=1e-9)
    _, Xr, st = sol.t, sol.x, sol.stats
    assert np.max(np.abs(Xr - Xd)) < 1e-7
    assert st["n_jac"] == st["n_accepted"]   # one Jacobian per step (no rejections here)
    q = Xr[:, :2]
    np.testing.assert_allclose(np.sum(q * q, axis=1), L ** 2, atol=1e-12)  # projected


def test_rodas4_closed_loop_with_linear_feedback():
    """A continuous LinearFeedback enters RODAS4's Jacobian (-df/dr K): the
    closed loop agrees with DOPRI5's."""
    sim = gen.compile(cart_pole.model())
    A, B = sim.linearize(np.zeros(4))
    K = cart_pole.lqr(A, B, cart_pole.Q_LQR, cart_pole.R_LQR)
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    ctl = gen.LinearFeedback(K)
    _, Xd = sim.simulate(x0, 5.0, 0.01, method="dopri5", rtol=1e-11, atol=1e-11, controller=ctl)
    sol = sim.simulate(x0, 5.0, 0.01, method="rodas4", rtol=1e-8, atol=1e-10,
                       controller=ctl)
    _, Xr, st = sol.t, sol.x, sol.stats
    assert np.max(np.abs(Xr - Xd)) < 1e-6
    assert np.max(np.abs(Xr[-1])) < 1e-3


def test_rodas4_failure_keeps_the_last_good_state():
    """A run that cannot continue reports where (a blow-up in finite time:
    x'' = 2 x^3 from rest at x = 1), never a singular configuration."""
    import sympy as sm
    from sympy.physics import mechanics as me
    x, u = me.dynamicsymbols("x u")
    c, m = sm.symbols("c m")
    N = me.ReferenceFrame("N")
    P = me.Point("O").locatenew("P", x * N.x)
    P.set_vel(N, u * N.x)
    km = me.KanesMethod(N, q_ind=[x], u_ind=[u], kd_eqs=[x.diff() - u])
    km.kanes_equations([me.Particle("p", P, m)], [(P, c * x ** 3 * N.x)])
    sim = gen.compile(gen.Model.from_kanes(km, constants={c: 2.0, m: 1.0}, name="blowup_r"))
    with pytest.raises(gen.ConvergenceError) as e:
        sim.simulate([1.0, 0.0], 3.0, 0.01, method="rodas4", rtol=1e-8, atol=1e-8)
    assert not isinstance(e.value, gen.SingularError)
    assert 1.2 < e.value.time < 1.4 and np.all(np.isfinite(e.value.state))
