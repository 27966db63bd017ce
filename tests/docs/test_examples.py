"""Issue 7: every example model, against exact physics and sympy.

- double pendulum: normal-mode frequencies (g/l)(2 -+ sqrt(2));
- rolling disc (two nonholonomic constraints, an input): the classical
  upright-rolling stability limit Omega^2 = g / (3 r) and the lean mode
  lambda^2 = (4/5)(g/r - 3 Omega^2) of the thin disc; energy conservation
  and no-slip residuals along a simulation;
- n-link pendulum on a cart, n = 1, 2, 4, 8: mass matrix and right-hand
  side against sympy's own mass_matrix_full / forcing_full, energy;
- every example's generated C compiles under the strict flags.
"""
import os
import subprocess

import numpy as np
import pytest
import sympy as sm

import chaplygin_sleigh
import double_pendulum
import four_bar
import gen
import n_link_cart
import rolling_disc
import seed_pendulum
from helpers import rel_err


# ---------------------------------------------------------- double pendulum
def test_double_pendulum_normal_modes():
    sim = gen.compile(double_pendulum.model())
    g, l = 9.81, 1.0
    A, B = sim.linearize(np.zeros(4))
    w2 = np.sort(np.real(-np.linalg.eigvals(A) ** 2))
    expected = np.sort(np.repeat([g / l * (2 - np.sqrt(2)), g / l * (2 + np.sqrt(2))], 2))
    assert rel_err(w2, expected) < 1e-12, (w2, expected)


def test_double_pendulum_energy():
    sim = gen.compile(double_pendulum.model())
    x0 = np.array([2.0, -1.0, 0.5, 3.0])         # large, chaotic swing
    t, X = sim.simulate(x0, 10.0, 0.01, method="dopri5", rtol=1e-11, atol=1e-12)
    E = np.array([sim.energy(x) for x in X])
    assert np.max(np.abs(E - E[0])) < 1e-7 * np.max(np.abs(E))


# -------------------------------------------------------------- rolling disc
@pytest.fixture(scope="module")
def disc():
    return gen.compile(rolling_disc.model())


def _upright(sim, omega):
    x = np.zeros(sim.nx)
    x[sim.state_names.index("u3")] = omega
    return sim.consistent_state(x)


@pytest.mark.parametrize("factor", [0.5, 0.9, 1.1, 2.0])
def test_rolling_disc_stability_limit(disc, factor):
    g, r = rolling_disc.DEFAULTS["g"], rolling_disc.DEFAULTS["r"]
    omega_c = np.sqrt(g / (3 * r))
    omega = factor * omega_c
    x = _upright(disc, omega)
    # the contact point rolls forward at r * Omega along the heading
    assert abs(x[disc.state_names.index("u4")] - r * omega) < 1e-12
    A, B = disc.linearize(x, r=[0.0])
    assert A.shape == (8, 8) and B.shape == (8, 1)
    ev = np.linalg.eigvals(A)
    lam2 = 0.8 * (g / r - 3 * omega**2)
    if factor < 1:
        assert abs(np.max(ev.real) - np.sqrt(lam2)) < 1e-9 * np.sqrt(lam2)
    else:
        assert np.max(np.abs(ev.real)) < 1e-9
        assert abs(np.max(ev.imag) - np.sqrt(-lam2)) < 1e-9 * np.sqrt(-lam2)
    # the torque about the axle spins the disc up: d(u3')/dT = 1 / (3/2 m r^2)
    m = rolling_disc.DEFAULTS["m"]
    assert abs(B[disc.independent_state_names.index("u3"), 0] - 1 / (1.5 * m * r**2)) < 1e-9


def test_rolling_disc_energy_and_no_slip(disc):
    x0 = _upright(disc, 6.0)
    x0[1] = 0.2                                  # lean
    x0[5] = 0.5                                  # yaw rate
    x0 = disc.consistent_state(x0)
    t, X = disc.simulate(x0, 5.0, 0.01, method="dopri5", rtol=1e-11, atol=1e-12, r=[0.0])
    E = np.array([disc.energy(x) for x in X])
    assert np.max(np.abs(E - E[0])) < 1e-8 * abs(E[0])
    fv = np.array([disc.velocity_constraints(x[:5], x[5:]) for x in X])
    assert np.max(np.abs(fv)) < 1e-10
    assert np.ptp(X[:, 3]) > 1.0                  # it rolled somewhere


# ------------------------------------------------------ n-link on a cart
@pytest.mark.parametrize("n", [1, 2, *(pytest.param(n, marks=pytest.mark.slow) for n in (4, 8))])
def test_n_link_cart_against_sympy(n):
    KM, s = n_link_cart.derive(n)
    model = n_link_cart.model(n)
    sim = gen.compile(model)
    consts = {str(c): c for c in (s["g"], *s["m"], *s["l"])}
    rng = np.random.default_rng(100 + n)
    vals = {consts[k]: v * rng.uniform(0.5, 1.5) for k, v in n_link_cart.defaults(n).items()}
    p = np.array([vals[c] for c in model.p_orig])
    states = list(s["q"]) + list(s["u"])
    fM = sm.lambdify(states + [s["F"]], KM.mass_matrix_full.xreplace(vals), "numpy")
    fF = sm.lambdify(states + [s["F"]], KM.forcing_full.xreplace(vals), "numpy")
    worst = 0.0
    for _ in range(5):
        x = rng.uniform(-2, 2, model.nx)
        F = rng.uniform(-3, 3)
        ref = np.linalg.solve(np.array(fM(*x, F), dtype=float),
                              np.array(fF(*x, F), dtype=float).ravel())
        worst = max(worst, rel_err(sim.rhs(0.0, x, r=[F], p=p), ref))
        Mfull = np.array(fM(*x, F), dtype=float)
        worst = max(worst, rel_err(sim.mass_matrix(x[:n + 1], p=p), Mfull[n + 1:, n + 1:]))
    print(f"cart{n}: max rel err vs sympy {worst:.2e}")
    assert worst < 1e-12
    # energy is conserved without the force
    x0 = rng.uniform(-0.5, 0.5, model.nx)
    t, X = sim.simulate(x0, 2.0, 0.01, method="dopri5", rtol=1e-11, atol=1e-12, p=p)
    E = np.array([sim.energy(x, p=p) for x in X])
    assert np.max(np.abs(E - E[0])) < 1e-8 * np.max(np.abs(E))


# -------------------------------------------------------------- strict C
EXAMPLES = {
    "seed_kane": seed_pendulum.kane_model,
    "seed_lagrange": seed_pendulum.lagrange_model,
    "double_pendulum": double_pendulum.model,
    "four_bar": four_bar.model,
    "rolling_disc": rolling_disc.model,
    "sleigh": chaplygin_sleigh.model,
    "cart4": lambda: n_link_cart.model(4),
}


# fast tier: cart4 (unconstrained, the unrolled LDL^T); the seeds are also
# compiled strict by test_seed_pendulum.py
@pytest.mark.parametrize("which", [w if w == "cart4" else pytest.param(w, marks=pytest.mark.slow)
                                   for w in sorted(EXAMPLES)])
def test_every_example_compiles_strict(tmp_path, which):
    model = EXAMPLES[which]()
    paths = gen.generate(model, tmp_path)
    for path in paths:
        if path.suffix == ".c":
            proc = subprocess.run(["gcc", "-std=c99", "-O1", "-Wall", "-Wextra", "-Werror",
                                   "-pedantic", "-Wshadow", "-Wvla", "-c", str(path), "-o",
                                   os.devnull, "-I", str(tmp_path)],
                                  capture_output=True, text=True)
            assert proc.returncode == 0, f"{path.name}:\n{proc.stderr}"


# ------------------------------------------------ a PyDy script, switched
def test_pydy_switch_example():
    """examples/pydy_switch.py (issue 33): PyDy's System.integrate over
    generator=gen.pydy.ODEFunctionGenerator follows PyDy's own lambdify
    generator within odeint's tolerance (rtol 1e-10), and the script runs."""
    pytest.importorskip("pydy")
    import pydy_switch
    t, X, _ = pydy_switch.simulate(gen.pydy.ODEFunctionGenerator)
    _, Y, _ = pydy_switch.simulate("lambdify")
    assert X.shape == Y.shape == (len(t), 6)
    assert np.max(np.abs(X[-1] - X[0])) > 0.5          # it moved
    assert rel_err(X, Y) < 1e-7
    diff = pydy_switch.main([])
    assert diff < 1e-7


# ------------------------------------------------ the friction block
def test_friction_block_example_and_its_csv(tmp_path):
    """examples/friction_block.py (issue 33): sympy's box on ground with
    friction -mu N; the block slides at u' = F/m - mu g (analytic) with the
    normal force N = m g, in the script and in `eomgen simulate --csv`'s N
    column (the CLI in its own process, as a user runs it)."""
    import sys
    from pathlib import Path

    import friction_block
    m, g, mu = (friction_block.DEFAULTS[k] for k in ("m", "g", "mu"))
    accel, N = friction_block.main(["--force", "8", "--t-end", "0.5"])
    assert abs(accel - (8.0 / m - mu * g)) < 1e-12 * g
    assert np.max(np.abs(N - m * g)) < 1e-12 * m * g
    sim = gen.compile(friction_block.model())
    assert sim.auxiliary_names == ["N"] and sim.input_names == ["F"]
    for F in (0.0, 3.0, 20.0):
        x = np.array([0.3, 0.7])
        assert abs(sim.rhs(0.0, x, r=[F])[1] - (F / m - mu * g)) < 1e-12 * g
    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ)
    env["PYTHONPATH"] = str(root) + os.pathsep + env.get("PYTHONPATH", "")
    out = tmp_path / "block.csv"
    proc = subprocess.run([sys.executable, "-m", "gen", "simulate",
                           str(root / "examples" / "friction_block.py"), "--t-end", "0.2",
                           "--dt", "0.01", "--x0", "u=0.5", "--input", "F=4", "--csv", str(out)],
                          capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    lines = out.read_text().splitlines()
    header = lines[0].split(",")
    assert header == ["t", "q", "u", "N"]
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    assert data.shape == (21, 4)
    assert np.max(np.abs(data[:, 3] - m * g)) < 1e-12 * m * g
    # u(t) = 0.5 + (F/m - mu g) t
    assert np.max(np.abs(data[:, 2] - (0.5 + (4.0 / m - mu * g) * data[:, 0]))) < 1e-12


# ------------------------------------------ the cart-pole with friction
def test_cart_pole_friction_example_and_its_csv(tmp_path):
    """examples/cart_pole_friction.py (issue 33): Coulomb friction on a
    normal force that the swinging pendulum changes, solved with u' in C;
    the script and `eomgen simulate --csv`'s N column against Newton-Euler
    by hand (the example's own newton_euler, numpy's solve of four equations)."""
    import sys
    from pathlib import Path

    import cart_pole_friction as cpf
    N, err = cpf.main(["--t-end", "1.0"])
    weight = (cpf.DEFAULTS["m_c"] + cpf.DEFAULTS["m_p"]) * cpf.DEFAULTS["g"]
    assert err < 1e-12
    assert N.min() < weight < N.max()          # the pendulum lifts and presses the cart
    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ)
    env["PYTHONPATH"] = str(root) + os.pathsep + env.get("PYTHONPATH", "")
    out = tmp_path / "cart.csv"
    proc = subprocess.run([sys.executable, "-m", "gen", "simulate",
                           str(root / "examples" / "cart_pole_friction.py"), "--t-end", "0.3",
                           "--dt", "0.01", "--x0", "theta=2.5", "--x0", "v=0.8", "--input", "F=1.5",
                           "--csv", str(out)], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    lines = out.read_text().splitlines()
    assert lines[0].split(",") == ["t", "x", "theta", "v", "omega", "N"]
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    assert data.shape == (31, 6)
    n_ref = np.array([cpf.newton_euler(row[1:5], 1.5)[3] for row in data])
    assert np.max(np.abs(data[:, 5] - n_ref)) < 1e-12 * np.max(np.abs(n_ref))
