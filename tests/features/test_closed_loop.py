"""Issue 15: closed loops. Inputs that vary (tables held or interpolated in C,
Python callables sampled with a zero-order hold), gen.LinearFeedback computed
inside the generated C (continuous or sampled), on the cart-pole of
examples/cart_pole.py.

References: solve_ivp (DOP853, rtol 1e-12) over an independent closed-loop
right-hand side (sympy's own mass_matrix_full / forcing_full, lambdified,
with F = -K x); a Python loop of RK4 steps with the input held by hand; the
analytic response of a double integrator to a ramp and to a staircase."""
from pathlib import Path

import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import cart_pole as cp
import gen

T_END = 5.0


@pytest.fixture(scope="module")
def cart():
    sim = gen.compile(cp.model())
    A, B = sim.linearize(np.zeros(4))
    K = cp.lqr(A, B, cp.Q_LQR, cp.R_LQR)
    return sim, K


def sympy_closed_loop_rhs(K):
    """x' of the cart-pole with F = -K x, from sympy's own full form."""
    km, s = cp.derive()
    consts = {s[k]: v for k, v in cp.DEFAULTS.items()}
    states = [s["x"], s["theta"], s["v"], s["omega"]]
    Mf = sm.lambdify([states, s["F"]], km.mass_matrix_full.xreplace(consts), "numpy")
    Ff = sm.lambdify([states, s["F"]], km.forcing_full.xreplace(consts), "numpy")

    def rhs(t, x):
        F = float(-(K @ x)[0])
        return np.linalg.solve(np.array(Mf(x, F), dtype=float),
                               np.array(Ff(x, F), dtype=float).ravel())
    return rhs


def test_lqr_closed_loop_in_c_matches_solve_ivp(cart):
    from scipy.integrate import solve_ivp
    sim, K = cart
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    ref = solve_ivp(sympy_closed_loop_rhs(K), (0, T_END), x0, method="DOP853", rtol=1e-12,
                    atol=1e-12)
    x_ref = ref.y[:, -1]
    for method, dt in (("rk4", 1e-3), ("dopri5", 0.05)):
        t, X = sim.simulate(x0, T_END, dt, method=method, rtol=1e-12, atol=1e-13,
                            controller=gen.LinearFeedback(K))
        assert t[-1] == T_END
        err = np.max(np.abs(X[-1] - x_ref))
        assert err < 1e-8, (method, err)
    assert np.max(np.abs(x_ref)) < 1e-3          # the LQR brought it home


def test_feedback_about_an_operating_point(cart):
    # r = r_op - K (x - x_op): regulate the cart to x = 0.5 with a bias force
    # r_op (which the loop must cancel, leaving the steady state offset
    # x_ss = x_op - r_op / K_x ... here r_op = 0 at the equilibrium x_op)
    sim, K = cart
    x_op = np.array([0.5, 0.0, 0.0, 0.0])
    sol = sim.simulate(np.zeros(4), 8.0, 1e-3, controller=gen.LinearFeedback(K, x_op))
    t, X, R = sol.t, sol.x, sol.r
    assert abs(X[-1, 0] - 0.5) < 1e-4 and np.max(np.abs(X[-1, 1:])) < 1e-4
    # the inputs reported are the law at the rows
    law = gen.LinearFeedback(K, x_op)
    for k in (0, 10, 2000):
        assert abs(R[k, 0] - law(sim, t[k], X[k])[0]) < 1e-12 * (1 + abs(R[k, 0]))


@pytest.mark.parametrize("period,dt,method", [(1e-3, 1e-3, "rk4"), (4e-3, 1e-3, "rk4"),
                                               (2.5e-3, 1e-2, "rk4"), (1e-2, 1e-2, "dopri5")])
def test_sampled_paths_agree(cart, period, dt, method):
    """LinearFeedback(period=Ts) in C and a Python callable sampled every Ts
    give the same run (the same samples, the same arithmetic)."""
    sim, K = cart
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    calls = []

    def law(t, x):
        calls.append(t)
        return -K @ x

    sol = sim.simulate(x0, 2.0, dt, method=method,
                       controller=gen.LinearFeedback(K, period=period))
    _, Xc, Rc = sol.t, sol.x, sol.r
    sol = sim.simulate(x0, 2.0, dt, method=method, r=law,
                       input_period=period)
    _, Xp, Rp = sol.t, sol.x, sol.r
    assert np.max(np.abs(Xc - Xp)) <= 1e-12 and np.max(np.abs(Rc - Rp)) <= 1e-11
    # each sample is taken once, at t = k Ts
    n = int(round(2.0 / period))
    assert len(calls) in (n, n + 1)
    assert np.allclose(calls[:n], np.arange(n) * period, rtol=0, atol=1e-12)


def test_sampled_feedback_is_a_zero_order_hold(cart):
    """At period = dt the sampled loop is RK4 steps with the input computed
    at the start of each step and held: a Python loop of sim.step(method="rk4")."""
    sim, K = cart
    dt = 1e-3
    x = np.array([0.0, 0.3, 0.0, 0.0])
    _, Xc = sim.simulate(x, 0.5, dt, controller=gen.LinearFeedback(K, period=dt))
    rows = [x]
    for k in range(500):
        x = sim.step(k * dt, x, dt, r=-K @ x, method="rk4")
        rows.append(x)
    assert np.max(np.abs(Xc - np.array(rows))) < 1e-13


def test_continuous_differs_from_sampled_by_the_hold(cart):
    # a slow sampling visibly changes the loop (the hold is real)
    sim, K = cart
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    _, Xc = sim.simulate(x0, 2.0, 1e-3, controller=gen.LinearFeedback(K))
    _, Xs = sim.simulate(x0, 2.0, 1e-3, controller=gen.LinearFeedback(K, period=2e-2))
    assert np.max(np.abs(Xc - Xs)) > 1e-3


@pytest.fixture(scope="module")
def double_integrator():
    """x'' = F / m (m = 2)."""
    x, v, F = me.dynamicsymbols("x v F")
    m = sm.symbols("m")
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, v * N.x)
    km = me.KanesMethod(N, q_ind=[x], u_ind=[v], kd_eqs=[x.diff() - v])
    km.kanes_equations([me.Particle("p", P, m)], [(P, F * N.x)])
    return gen.compile(gen.Model.from_kanes(km, constants={m: 2.0}, inputs=[F], name="dint"))


def staircase(tk, rk, t, m=2.0):
    """x(t), v(t) of x'' = r(t)/m from rest, r held at rk[i] on [tk[i], tk[i+1])."""
    x = v = 0.0
    edges = list(tk[1:]) + [np.inf]
    t_prev = 0.0
    for i, (a, b) in enumerate(zip(tk, edges)):
        a = max(a, t_prev)
        if t <= a:
            break
        h = min(b, t) - a
        acc = rk[i] / m
        x += v * h + 0.5 * acc * h * h
        v += acc * h
        t_prev = a + h
    return x, v


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
def test_input_table_zoh_and_linear_against_analytic(double_integrator, method):
    sim = double_integrator
    kw = dict(method=method, rtol=1e-12, atol=1e-14)
    # linear hold of a ramp r = 3 t: x = t^3 / 4 (m = 2)
    tg = np.array([0.0, 0.7, 1.3, 2.0])
    sol = sim.simulate([0.0, 0.0], 2.0, 0.01, r=(tg, 3 * tg), input_hold="linear", **kw)
    t, X, R = sol.t, sol.x, sol.r
    assert np.max(np.abs(X[:, 0] - t**3 / 4)) < 1e-9
    assert np.max(np.abs(X[:, 1] - 3 * t**2 / 4)) < 1e-9
    assert np.max(np.abs(R[:, 0] - 3 * t)) < 1e-12
    # zero-order hold of a staircase with knots between output times
    tk = np.array([0.0, 0.333, 1.1, 1.55])
    rk = np.array([1.0, -2.0, 0.5, 3.0])
    sol = sim.simulate([0.0, 0.0], 2.0, 0.01, r=(tk, rk), **kw)
    t, X, R = sol.t, sol.x, sol.r
    want = np.array([staircase(tk, rk, ti) for ti in t])
    assert np.max(np.abs(X - want)) < 1e-9
    held = rk[np.searchsorted(tk, t, side="right") - 1]
    assert np.array_equal(R[:, 0], held)


def test_errors_name_the_problem(cart, double_integrator):
    sim, K = cart
    x0 = np.zeros(4)
    with pytest.raises(ValueError, match=r"K must have shape \(nr, ns\) = \(1, 4\).*F.*x"):
        sim.simulate(x0, 1.0, 1e-2, controller=gen.LinearFeedback(np.ones((2, 4))))
    with pytest.raises(ValueError, match="must return nr = 1 values"):
        sim.simulate(x0, 1.0, 1e-2, r=lambda t, x: [1.0, 2.0])

    class Boom(Exception):
        pass

    def bad(t, x):
        if t > 0.5:
            raise Boom("controller failed")
        return [0.0]
    with pytest.raises(Boom):
        sim.simulate(x0, 1.0, 1e-2, r=bad)
    with pytest.raises(ValueError, match="strictly increasing"):
        double_integrator.simulate([0, 0], 1.0, 0.1, r=([0.0, 1.0, 1.0], [0.0, 1.0, 2.0]))
    with pytest.raises(ValueError, match="input_hold"):
        double_integrator.simulate([0, 0], 1.0, 0.1, r=([0.0, 1.0], [0.0, 1.0]),
                                   input_hold="cubic")
    with pytest.raises(ValueError, match="r_op"):
        sim.simulate(x0, 1.0, 1e-2, r=[1.0], controller=gen.LinearFeedback(K))


def test_ensemble_rows_take_a_controller_and_refuse_a_callable(cart):
    sim, K = cart
    X0 = np.array([[0.0, 0.1, 0, 0], [0.0, -0.2, 0, 0]])
    res = sim.ensemble(X0, 1.0, 1e-3, controller=gen.LinearFeedback(K, period=1e-3),
                       reduce="rows")
    for i in range(2):
        t, X = sim.simulate(X0[i], 1.0, 1e-3, controller=gen.LinearFeedback(K, period=1e-3))
        assert np.array_equal(res.rows[i], X) and np.array_equal(res.t, t)
    # a Python r(t, x) would hold the GIL at every step: refused, naming r
    with pytest.raises(gen.InputError, match="not a Python function") as e:
        sim.ensemble(X0, 1.0, 1e-3, r=lambda t, x: -K @ x, reduce="rows")
    assert e.value.argument == "r"


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_closes_the_loop_too(cart):
    from conftest import require_eigen
    require_eigen()
    sim, K = cart
    sim_e = gen.compile(cp.model(), backend="eigen")
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    tk = np.array([0.0, 0.333, 1.1])
    for kw in (dict(controller=gen.LinearFeedback(K)),
               dict(controller=gen.LinearFeedback(K, period=2.5e-3)),
               dict(r=lambda t, x: -K @ x, input_period=2e-3),
               dict(r=(tk, np.array([1.0, -2.0, 0.5])), input_hold="linear"),
               dict(r=(tk, np.array([1.0, -2.0, 0.5])))):
        for method in ("rk4", "dopri5"):
            sol = sim.simulate(x0, 2.0, 1e-2, method=method, **kw)
            _, X, R = sol.t, sol.x, sol.r
            sol = sim_e.simulate(x0, 2.0, 1e-2, method=method, **kw)
            _, Xe, Re = sol.t, sol.x, sol.r
            assert np.max(np.abs(X - Xe)) < 1e-10 and np.max(np.abs(R - Re)) < 1e-9, kw


def _build_binary(model, tmp_path):
    import shutil
    import subprocess
    from gen.codegen.render import generate
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    generate(model, tmp_path / "src")
    src = sorted(str(p) for p in (tmp_path / "src").glob("*.c"))
    exe = tmp_path / f"{model.name}_sim"
    subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2",
                    "-I", str(tmp_path / "src"), *src, "-lm", "-o", str(exe)], check=True)
    return exe


def _csv(text):
    lines = text.strip().splitlines()
    return lines[0].split(","), np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])


@pytest.mark.slow
def test_binary_with_gain_and_input_table_reproduces_the_c_path(cart, tmp_path):
    import subprocess
    sim, K = cart
    exe = _build_binary(cp.model(), tmp_path)
    (tmp_path / "K.csv").write_text("# LQR gain, F by [x, theta, v, omega]\n"
                                    + ",".join(f"{v:.17g}" for v in K[0]) + "\n")
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    for period in (None, 2e-3):
        args = [str(exe), "--t-end", "5", "--dt", "1e-3", "--x0", "theta=0.3", "--gain",
                str(tmp_path / "K.csv")] + (["--period", str(period)] if period else [])
        head, data = _csv(subprocess.run(args, capture_output=True, text=True,
                                         check=True).stdout)
        assert head == ["t", "x", "theta", "v", "omega", "tip_x", "tip_y", "F"]
        sol = sim.simulate(x0, 5.0, 1e-3, controller=gen.LinearFeedback(K, period=period))
        t, X, R = sol.t, sol.x, sol.r
        Y = np.column_stack([sol.outputs[k] for k in sim.output_names])
        assert np.max(np.abs(data[:, 1:5] - X)) < 1e-10
        assert np.max(np.abs(data[:, 5:7] - Y)) < 1e-10
        assert np.max(np.abs(data[:, 7] - R[:, 0])) < 1e-9
    # an input table, held and interpolated
    tg = np.array([0.0, 0.0125, 0.3, 0.75])
    Rt = np.array([1.0, -2.0, 0.5, 3.0])
    (tmp_path / "in.csv").write_text("t,F\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(tg, Rt)))
    for hold in ("zoh", "linear"):
        out = subprocess.run([str(exe), "--t-end", "1", "--dt", "0.01", "--x0", "theta=0.3",
                              "--input-csv", str(tmp_path / "in.csv"), "--hold", hold],
                             capture_output=True, text=True, check=True).stdout
        head, data = _csv(out)
        sol = sim.simulate(x0, 1.0, 0.01, r=(tg, Rt), input_hold=hold)
        t, X, R = sol.t, sol.x, sol.r
        assert np.max(np.abs(data[:, 1:5] - X)) < 1e-12
        assert np.max(np.abs(data[:, 7] - R[:, 0])) < 1e-12
    # a gain of the wrong shape is named
    (tmp_path / "K2.csv").write_text("1,2\n")
    bad = subprocess.run([str(exe), "--gain", str(tmp_path / "K2.csv")], capture_output=True,
                         text=True)
    assert bad.returncode == 2
    assert "K must be 1 row(s) of 4 values" in bad.stderr and "x theta v omega" in bad.stderr


@pytest.mark.slow
def test_cli_input_csv(double_integrator, tmp_path):
    import os
    import subprocess
    import sys
    root = str(Path(__file__).resolve().parents[2])
    (tmp_path / "m.py").write_text(
        "import sympy as sm\nfrom sympy.physics import mechanics as me\nimport gen\n\n"
        "def model():\n"
        "    x, v, F = me.dynamicsymbols('x v F')\n"
        "    m = sm.symbols('m')\n"
        "    N = me.ReferenceFrame('N')\n"
        "    P = me.Point('P')\n"
        "    P.set_vel(N, v * N.x)\n"
        "    km = me.KanesMethod(N, q_ind=[x], u_ind=[v], kd_eqs=[x.diff() - v])\n"
        "    km.kanes_equations([me.Particle('p', P, m)], [(P, F * N.x)])\n"
        "    return gen.Model.from_kanes(km, constants={m: 2.0}, inputs=[F], name='dint')\n")
    (tmp_path / "ramp.csv").write_text("t,F\n0,0\n0.7,2.1\n2,6\n")
    env = dict(os.environ, PYTHONPATH=root)
    out = tmp_path / "run.csv"
    p = subprocess.run([sys.executable, "-m", "gen", "simulate", str(tmp_path / "m.py"),
                        "--t-end", "2", "--dt", "0.05", "--input-csv", str(tmp_path / "ramp.csv"),
                        "--hold", "linear", "--csv", str(out)], capture_output=True, text=True,
                       env=env)
    assert p.returncode == 0, p.stderr
    head, data = _csv(out.read_text())
    assert head == ["t", "x", "v", "F"]
    t = data[:, 0]
    assert np.max(np.abs(data[:, 1] - t**3 / 4)) < 1e-9        # r = 3 t, m = 2
    assert np.max(np.abs(data[:, 3] - 3 * t)) < 1e-12
    (tmp_path / "bad.csv").write_text("t,G\n0,1\n")
    p = subprocess.run([sys.executable, "-m", "gen", "simulate", str(tmp_path / "m.py"),
                        "--t-end", "1", "--input-csv", str(tmp_path / "bad.csv")],
                       capture_output=True, text=True, env=env)
    assert p.returncode != 0 and "unknown input(s) G" in p.stderr and "no column for input(s) F" \
        in p.stderr
