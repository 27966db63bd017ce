"""gen.OptimalControl's edges (issue 47): the size checked before anything
is allocated, scalar objectives, strings read in the model's own symbols,
non-finite bounds and values named, and a solution that keeps the
constants it was solved with.

References: the exact messages; sympy's own value of pi; the same problem
written with sympy objects; the model's simulator run separately with
the solved constants."""
import importlib.util
import os
import tracemalloc
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
PAR = {"mc": 1.0, "mp": 0.1, "l": 0.5, "g": 9.81}
needs_ipopt = pytest.mark.skipif(cyipopt is None and os.environ.get("CI") != "true",
                                 reason="cyipopt not installed (pip install eomgen[ocp])")


@pytest.fixture(scope="module")
def cart():
    spec = importlib.util.spec_from_file_location("cart_pole_for_ocp_edges",
                                                  EXAMPLES / "cart_pole.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    km, s = mod.derive()
    model = gen.Model.from_kanes(km, constants={s[k]: v for k, v in PAR.items()},
                                 inputs=[s["F"]], name="cart_pole_ocp")
    return s, model


def _swing_up(model, s, nodes=21, method="trapezoidal", **kw):
    x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
    args = dict(objective=F**2, method=method, bounds={F: (-20, 20), x: (-1.5, 1.5)},
                initial={x: 0, th: sm.pi, v: 0, om: 0}, final={x: 0, th: 0, v: 0, om: 0})
    args.update(kw)
    return gen.OptimalControl(model, nodes, 2.0, **args)


@pytest.fixture
def no_build(monkeypatch):
    def refuse(*a, **k):
        raise AssertionError("built despite the error")
    monkeypatch.setattr(gen.pipeline, "product", refuse)


def test_a_billion_nodes_are_refused_before_allocating(cart, no_build):
    s, model = cart
    tracemalloc.start()
    try:
        with pytest.raises(gen.InputError) as e:
            _swing_up(model, s, nodes=10**9, method="hermite-simpson")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    msg = str(e.value)
    # the unknowns: per node 4 states + 1 input + 4 slopes, per interval a
    # midpoint's 4 states + 1 input + 4 slopes, and the duration
    n = 10**9 * 9 + (10**9 - 1) * 9 + 1
    assert msg.startswith(f"nodes=1000000000: the transcription (hermite-simpson) would have "
                          f"{n:,} unknowns and need about "), msg
    assert msg.endswith("use fewer nodes (a solution on a coarse grid is a good guess for a "
                        "finer one)"), msg
    assert peak < 50 * 2**20, peak


def test_an_objective_must_be_a_scalar(cart, no_build):
    s, model = cart
    F, x = s["F"], s["x"]
    with pytest.raises(gen.InputError) as e:
        _swing_up(model, s, objective=sm.Matrix([F**2, x**2]))
    assert str(e.value) == ("objective must be a scalar expression, got MutableDenseMatrix "
                            "of shape (2, 1)")
    with pytest.raises(gen.InputError) as e:
        _swing_up(model, s, terminal_cost=[x**2])
    assert str(e.value) == "terminal_cost must be a scalar expression, got list of shape (1,)"


def test_strings_are_read_in_the_models_symbols(cart, no_build):
    s, model = cart
    th = s["theta"]
    with pytest.raises(gen.InputError) as e:
        _swing_up(model, s, objective="c_d*F**2")
    assert str(e.value) == ("objective = c_d*F(t)**2 holds c_d, not a state, input or "
                            "constant of model 'cart_pole_ocp' (nor t)")
    with pytest.raises(gen.InputError) as e:
        _swing_up(model, s, objective="F**")
    assert str(e.value) == ("objective = 'F**' cannot be read as an expression in model "
                            "'cart_pole_ocp''s symbols (SympifyError)")
    with pytest.raises(gen.InputError) as e:
        _swing_up(model, s, initial={th: "pie"})
    assert str(e.value) == "initial[theta(t)] = 'pie' is not a number"


def test_non_finite_bounds_and_values_name_the_argument(cart, no_build):
    s, model = cart
    th = s["theta"]
    with pytest.raises(gen.InputError) as e:
        _swing_up(model, s, bounds={th: (float("nan"), 5)})
    assert str(e.value) == ("bounds[theta(t)] = (nan, 5): lo is NaN, not a number; give a "
                            "number, or -inf/inf for no bound")
    with pytest.raises(gen.InputError) as e:
        _swing_up(model, s, bounds={th: (-1, "x")})
    assert str(e.value) == "bounds[theta(t)] = (-1, 'x'): hi = 'x' is not a number"
    with pytest.raises(gen.InputError) as e:
        _swing_up(model, s, final={th: float("inf")})
    assert str(e.value) == "final[theta(t)] = inf: not a finite number"


@needs_ipopt
def test_string_objective_and_values_solve_as_sympy_ones(cart):
    """objective="F**2" and initial={theta: "pi"} give the same problem as
    F**2 and sympy.pi: the same optimum, bit for bit, theta(0) = pi."""
    s, model = cart
    x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
    a = _swing_up(model, s).solve(tol=1e-9)
    b = _swing_up(model, s, objective="F**2",
                  initial={x: 0, "theta": "pi", v: 0, om: 0},
                  bounds={"F": ("-20", 20), x: (-1.5, "3/2")}).solve(tol=1e-9)
    assert a.status == 0 and b.status == 0, (a.message, b.message)
    assert b.x[0, 1] == float(sm.pi)
    assert b.objective == a.objective
    np.testing.assert_array_equal(a.x, b.x)


@needs_ipopt
def test_replay_uses_the_constants_it_was_solved_with(cart):
    """After ocp.constants changes, sol.replay() still replays the solved
    problem: its final state is the transcription's to the method's
    accuracy, as before the change, and equals the simulator run apart
    with the solve's constants."""
    s, model = cart
    ocp = _swing_up(model, s, nodes=41, method="hermite-simpson")
    sol = ocp.solve(tol=1e-10)
    assert sol.status == 0, sol.message
    before = sol.replay(rtol=1e-10, atol=1e-10)
    ocp.constants = {s["g"]: 4.81}
    after = sol.replay(rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(before.x, after.x)
    assert np.abs(after.x[-1] - sol.x[-1]).max() < 1e-3
    np.testing.assert_array_equal(sol.constants, [1.0, 0.1, 0.5, 9.81])
    # the same inputs under the new constants end elsewhere (what the old
    # replay returned)
    moved = ocp.simulator.simulate(sol.x[0], 2.0, sol.t[1], r=lambda t, x: sol.input(t),
                                   p=[1.0, 0.1, 0.5, 4.81], input_period=0,
                                   rtol=1e-10, atol=1e-10)
    assert np.abs(moved.x[-1] - sol.x[-1]).max() > 0.5
    # a non-finite constant is named as a constant
    ocp.constants = {s["g"]: float("nan")}
    with pytest.raises(gen.InputError) as e:
        ocp.solve()
    assert str(e.value) == "constants[g] = nan: not a finite number"


# ----------------------------------------------------- the brachistochrone
def _brachistochrone_casadi(N, T0, X0, Y0):
    """The same trapezoidal transcription in CasADi's Opti (explicit
    right-hand side), from the same guess: (T*, iterations, inf_pr at
    iteration 0)."""
    ca = pytest.importorskip("casadi", reason="CasADi is the brachistochrone's peer "
                                              "(pip install eomgen[casadi])")
    g = 9.81
    opti = ca.Opti()
    X, U, T = opti.variable(4, N), opti.variable(1, N), opti.variable()
    f = [ca.vertcat(X[2, k], X[3, k], -U[k] * X[3, k], -g + U[k] * X[2, k]) for k in range(N)]
    for k in range(N - 1):
        opti.subject_to(X[:, k + 1] - X[:, k] - T / (N - 1) / 2 * (f[k] + f[k + 1]) == 0)
    opti.subject_to(X[:, 0] == 0)
    opti.subject_to(X[0, -1] == 2)
    opti.subject_to(X[1, -1] == -1)
    opti.subject_to(opti.bounded(-10, U, 10))
    opti.subject_to(opti.bounded(0.1, T, 5.0))
    opti.minimize(T)
    opti.set_initial(T, T0)
    opti.set_initial(X[0, :], X0)
    opti.set_initial(X[1, :], Y0)
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": 1e-10})
    sol = opti.solve()
    st = sol.stats()
    return float(sol.value(T)), st["iter_count"], st["iterations"]["inf_pr"][0]


@pytest.mark.slow
@needs_ipopt
def test_brachistochrone_does_not_stall():
    """Issue 47's brachistochrone (a particle under gravity steered by
    Fn (-vy, vx), rest at the origin to (2, -1) in minimum time,
    trapezoidal, N = 201, |Fn| <= 10), from a guess whose positions move
    while its speeds are zero and from the default guess: the minimum time
    of CasADi's transcription to 1e-9, in at most twice CasADi's iterations
    (it stalled for 123 iterations), the first iterate's infeasibility
    within 10x of CasADi's and its dual infeasibility not 1e11."""
    from sympy.physics import mechanics as me
    x, y, vx, vy, Fn = me.dynamicsymbols("x y v_x v_y F_n")
    g, m = sm.symbols("g m")
    N_ = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N_, 0)
    P = O.locatenew("P", x * N_.x + y * N_.y)
    P.set_vel(N_, vx * N_.x + vy * N_.y)
    km = me.KanesMethod(N_, [x, y], [vx, vy], kd_eqs=[x.diff() - vx, y.diff() - vy])
    km.kanes_equations([me.Particle("p", P, m)], [(P, -m * g * N_.y + Fn * (-vy * N_.x + vx * N_.y))])
    model = gen.Model.from_kanes(km, constants={g: 9.81, m: 1.0}, inputs=[Fn], name="brach_ocp")
    N = 201
    ocp = gen.OptimalControl(model, N, (0.1, 5.0), terminal_cost=sm.Symbol("t"),
                             method="trapezoidal", bounds={Fn: (-10, 10)},
                             initial={x: 0, y: 0, vx: 0, vy: 0}, final={x: 2, y: -1})
    X0, Y0 = np.linspace(0, 2, N), np.linspace(0, -1, N)
    for guess, T0 in (({x: X0, y: Y0, "duration": 1.0}, 1.0), (None, 2.55)):
        sol = ocp.solve(guess, tol=1e-10)
        T_ref, it_ref, pr_ref = _brachistochrone_casadi(N, T0, X0, Y0)
        assert sol.status == 0, sol.message
        assert sol.objective == pytest.approx(T_ref, rel=1e-9), (sol.objective, T_ref)
        assert sol.iterations <= 2 * it_ref, (sol.iterations, it_ref)
        pr, du = sol.first_iterate
        assert pr <= 10 * pr_ref and du < 1e3, (pr, pr_ref, du)
