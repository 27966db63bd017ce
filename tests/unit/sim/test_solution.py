"""The Python face of issue 32: sim.simulate returns a gen.Solution (every
attribute, on every method and both backends), one argument convention,
sim.jac for solve_ivp, gen.InputError naming the argument, runs refused
before anything is allocated, and the modules off Simulator's private names."""
import ast
import re
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import cart_pole as cp
import gen
import seed_pendulum as sp
from helpers import pendulum_state

ROOT = Path(__file__).resolve().parents[3]
METHODS = ["rk4", "dopri5", "rodas4"]


@pytest.fixture(scope="module")
def cart():
    return gen.compile(cp.model())


def _check_solution(sim, x0, method, r):
    tol = dict(rtol=1e-10, atol=1e-12) if method != "rk4" else {}
    sol = sim.simulate(x0, 1.0, 0.01, method=method, r=r, **tol)
    assert isinstance(sol, gen.Solution)
    rows = len(sol.t)
    assert rows == 101 and sol.t[0] == 0.0 and sol.t[-1] == 1.0
    # unpacks as t, x (python-control's responses), and indexes so
    t, x = sol
    assert t is sol.t and x is sol.x and sol[1] is sol.x and len(sol) == 2
    assert sol.x.shape == (rows, sim.nx) and np.array_equal(sol.x[0], x0)
    # the inputs applied
    assert sol.r.shape == (rows, sim.nr)
    if sim.nr:
        assert np.all(sol.r == r)
    # the multipliers: sim.multipliers at each row (an independent C call)
    assert sol.lam.shape == (rows, sim.mv)
    for k in (0, 50, rows - 1):
        np.testing.assert_allclose(sol.lam[k], sim.multipliers(sol.t[k], sol.x[k], r=r),
                                   rtol=1e-9, atol=1e-12)
    # the outputs: computed in C in one batch call, equal to sim.outputs row by row
    assert list(sol.outputs) == sim.output_names
    for k in range(rows):
        want = sim.outputs(sol.t[k], sol.x[k], r=r)
        assert np.array_equal([sol.outputs[n][k] for n in sim.output_names], want)
    # status, message, stats
    assert sol.status == 0 and sol.message == "the run reached t_end" and sol.success
    st = sol.stats
    assert st["n_steps"] == st["n_accepted"] > 0 and st["n_out"] == rows
    assert st["n_rhs"] >= 4 * st["n_steps"] and st["n_rejected"] >= 0
    assert (st["n_jac"] == st["n_steps"] + st["n_rejected"] or st["n_jac"] == st["n_steps"]) \
        if method == "rodas4" else st["n_jac"] == 0
    assert sol.events == []
    # the interpolant: exact at the rows, and between them close to a finer run's rows
    assert np.array_equal(sol.sol(sol.t[37]), sol.x[37])
    fine = sim.simulate(x0, 1.0, 0.0025, method=method, r=r, **tol)
    mid = sol.sol(fine.t)
    err = np.max(np.abs(mid - fine.x))
    assert err < 1e-6, err
    with pytest.raises(gen.InputError, match="outside the run"):
        sol.sol(1.5)
    return sol


@pytest.mark.parametrize("method", METHODS)
def test_solution_has_every_attribute_c(cart, kane_sim, method):
    _check_solution(cart, np.array([0.0, 0.3, 0.0, 0.0]), method, np.array([0.2]))
    sol = _check_solution(kane_sim, pendulum_state(0.5, 0.0, 1.0, "kane"), method, None)
    assert sim_has_multipliers(sol)


def sim_has_multipliers(sol):
    """The Kane seed's multiplier is the string tension (nonzero while it swings)."""
    return sol.lam.shape[1] == 1 and np.all(np.abs(sol.lam) > 1.0)


@pytest.mark.slow
@pytest.mark.eigen
@pytest.mark.parametrize("method", METHODS)
def test_solution_has_every_attribute_eigen(method):
    from conftest import require_eigen
    require_eigen()
    cart_e = gen.compile(cp.model(), backend="eigen")
    kane_e = gen.compile(sp.kane_model(), backend="eigen")
    cart_c = gen.compile(cp.model())
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    se = _check_solution(cart_e, x0, method, np.array([0.2]))
    sc = cart_c.simulate(x0, 1.0, 0.01, method=method, r=[0.2],
                         **(dict(rtol=1e-10, atol=1e-12) if method != "rk4" else {}))
    assert np.max(np.abs(se.x - sc.x)) < 1e-12
    for n in cart_c.output_names:
        assert np.max(np.abs(se.outputs[n] - sc.outputs[n])) < 1e-12
    _check_solution(kane_e, pendulum_state(0.5, 0.0, 1.0, "kane"), method, None)


def test_events_are_records(kane_sim):
    x0 = pendulum_state(0.5, 0.0, 1.0, "kane")
    sol = kane_sim.simulate(x0, 3.0, 0.01, method="dopri5", rtol=1e-10, atol=1e-10,
                            events={"q2": -1}, terminal=True)
    (ev,) = sol.events
    assert isinstance(ev, gen.Event) and ev.name == "q2"
    assert ev.t == sol.t[-1] and np.array_equal(ev.x, sol.x[-1]) and abs(ev.x[0]) < 1e-12
    name, t, x = ev                       # and unpacks as before
    assert sol.status == 1 and "'q2'" in sol.message and sol.stats["terminal"] == "q2"


def test_jac_for_solve_ivp_agrees_with_rodas4(cart):
    """solve_ivp(sim.rhs, ..., method="Radau", jac=sim.jac) runs, and agrees
    with sim.simulate(method="rodas4") to the tolerance; sim.jac is df/dx,
    checked against central differences of sim.rhs."""
    from scipy.integrate import solve_ivp
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    calls = []

    def jac(t, x):
        calls.append(t)
        return cart.jac(t, x)

    # 3 s: a full swing of the pole (SciPy's Radau in Python is the cost)
    ref = solve_ivp(cart.rhs, (0, 3), x0, method="Radau", jac=jac, rtol=1e-10, atol=1e-12)
    assert ref.success and calls
    sol = cart.simulate(x0, 3.0, 0.5, method="rodas4", rtol=1e-10, atol=1e-12)
    err = np.max(np.abs(ref.y[:, -1] - sol.x[-1]))
    assert err < 1e-6 * max(1.0, np.max(np.abs(sol.x))), err
    x = np.array([0.1, 0.4, -0.3, 0.2])
    J = cart.jac(0.0, x, r=[0.5])
    assert J.shape == (4, 4)
    h = 1e-6
    Jn = np.column_stack([(cart.rhs(0.0, x + h * e, r=[0.5]) - cart.rhs(0.0, x - h * e, r=[0.5]))
                          / (2 * h) for e in np.eye(4)])
    np.testing.assert_allclose(J, Jn, rtol=1e-6, atol=1e-7)


# ------------------------------------------------------------------ errors
def test_input_error_names_the_argument_entry_and_value(kane_sim, cart):
    assert issubclass(gen.InputError, ValueError) and issubclass(gen.InputError, gen.EomgenError)
    x0 = pendulum_state(0.5, 0.0, 1.0, "kane")
    bad = x0.copy()
    bad[2] = np.nan
    with pytest.raises(gen.InputError) as e:
        kane_sim.simulate(bad, 1.0, 0.01)
    msg = str(e.value)
    assert msg.startswith("x0[2] = nan (u2)") and e.value.argument == "x0"
    assert e.value.index == 2 and np.isnan(e.value.value)
    assert "an input value" not in msg and "state:" not in msg      # no zeros for a state
    with pytest.raises(gen.InputError, match=r"^p\[1\] = inf \(m\)") as e:
        kane_sim.simulate(x0, 1.0, 0.01, p=[1.0, np.inf, 9.81])
    assert e.value.argument == "p"
    with pytest.raises(gen.InputError, match=r"^r\[0\] = nan \(F\)"):
        cart.simulate(np.zeros(4), 1.0, 0.01, r=[np.nan])
    with pytest.raises(gen.InputError, match=r"^t_end must be a number >= t0 = 0.0, got "
                                             r"t_end = nan"):
        cart.simulate(np.zeros(4), np.nan, 0.01)
    # the evaluations name it too (the C check, then the culprit found)
    with pytest.raises(gen.InputError, match=r"eval_rhs: x\[1\] = nan \(theta\)"):
        cart.rhs(0.0, np.array([0.0, np.nan, 0.0, 0.0]))
    with pytest.raises(gen.InputError, match=r"eval_rhs: r\[0\] = inf \(F\)"):
        cart.rhs(0.0, np.zeros(4), r=np.array([np.inf]))


def test_huge_run_is_refused_before_anything_is_allocated(kane_sim, monkeypatch):
    """The newcomer's sim.simulate(x0, 1e5, 1e-4): 10^9 + 1 rows, refused
    with the count and the ways out, nothing allocated (the machine's
    available memory set to 16 GiB, so that the test does not depend on
    this machine's)."""
    import gen.sim.options
    monkeypatch.setattr(gen.sim.options, "memory_available", lambda: 16 * 2**30)
    x0 = pendulum_state(0.5, 0.0, 1.0, "kane")
    tracemalloc.start()
    try:
        with pytest.raises(gen.InputError) as e:
            kane_sim.simulate(x0, 1e5, 1e-4)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    msg = str(e.value)
    assert "1,000,000,001 rows" in msg and "52.2 GiB" in msg, msg
    assert "every=" in msg and "final_only=True" in msg and "max_rows=" in msg
    assert peak < 2**20, peak


def test_row_count_honours_every_and_final_only_before_the_size_check(kane_sim):
    """Past the C limit (10^9 output intervals) the message says so, naming
    dt, even with final_only=True; max_rows is checked on the rows kept."""
    x0 = pendulum_state(0.5, 0.0, 1.0, "kane")
    for kw in (dict(final_only=True), dict(final_only=True, max_rows=1000)):
        with pytest.raises(gen.InputError, match=r"more than the 1e\+09 output intervals") as e:
            kane_sim.simulate(x0, 1e6, 1e-4, **kw)
        assert "ERR_BAD_ARG" not in str(e.value) and e.value.argument == "dt"
    with pytest.raises(gen.InputError, match=r"would keep 10,000,000,001 rows .* max_rows=1000"):
        kane_sim.simulate(x0, 1e6, 1e-4, max_rows=1000)
    # within the limit, final_only keeps one row, so max_rows=1 passes
    t, x = kane_sim.simulate(x0, 1.0, 1e-3, final_only=True, max_rows=1)
    assert t.tolist() == [1.0]
    t, x = kane_sim.simulate(x0, 1.0, 1e-3, every=100, max_rows=11)
    assert len(t) == 11


# ------------------------------------------------------------- convention
def test_one_convention_keyword_only_and_one_option_check(cart):
    x = np.zeros(4)
    for call in (lambda: cart.rhs(0.0, x, [0.5]), lambda: cart.jac(0.0, x, [0.5]),
                 lambda: cart.linearize(x, [0.5]), lambda: cart.mass_matrix(x[:2], None),
                 lambda: cart.simulate(x, 1.0, 0.01, "dopri5"),
                 lambda: cart.ensemble(x, 1.0, 0.01, None)):
        with pytest.raises(TypeError):
            call()
    assert not hasattr(cart, "step_rk4") and not hasattr(cart, "simulate_batch")
    # simulate and ensemble take the same options, checked by the same code
    for kw, arg in ((dict(every=0), "every"), (dict(method="euler"), "method"),
                    (dict(rtol=-1.0), "rtol"), (dict(max_rows=0), "max_rows"),
                    (dict(input_hold="cubic"), "input_hold")):
        msgs = []
        for fn in (cart.simulate, cart.ensemble):
            with pytest.raises(gen.InputError) as e:
                fn(x, 1.0, 0.01, **kw)
            assert e.value.argument == arg
            msgs.append(str(e.value))
        assert msgs[0] == msgs[1]


def test_exports():
    for name in ("Solution", "Simulator", "MissingDependencyError", "InputError", "Event"):
        assert name in gen.__all__ and getattr(gen, name) is not None
    from gen.sim.simulator import Simulator
    assert gen.Simulator is Simulator


def test_modules_use_no_private_simulator_names_and_no_import_circle():
    """gen/sim/ensemble.py, inputs.py and events.py reach the C library through
    sim.library, never sim._name; gen.sim.ensemble imports nothing of
    gen.sim.simulator (the simulator imports it: one direction)."""
    for name in ("ensemble", "inputs", "events"):
        src = (ROOT / "gen" / "sim" / f"{name}.py").read_text()
        tree = ast.parse(src)
        private = [n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)
                   and n.attr.startswith("_") and not n.attr.startswith("__")
                   and not (isinstance(n.value, ast.Name) and n.value.id in ("self", "np"))]
        assert not private, (name, private)
        imports = [n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
        assert "simulator" not in imports, name
    assert re.search(r"^from \.ensemble import",
                     (ROOT / "gen" / "sim" / "simulator.py").read_text(), re.M)


def test_a_failure_at_the_start_names_x0_not_zeros(kane_sim):
    """The seed's Kane partition is singular at q1 = 0: the run fails at t0,
    before any row, and the message and .state are the x0 passed (the C
    runtime's last-state buffer holds nothing yet)."""
    x0 = np.array([1.0, 0.0, 0.0, 0.3])
    with pytest.raises(gen.SingularError) as e:
        kane_sim.simulate(x0, 1.0, 0.01)
    assert "at t = 0, state: q2=1, q1=0, u2=0, u1=0.3" in str(e.value)
    assert np.array_equal(e.value.state, x0) and e.value.time == 0.0
