"""Issue 2 acceptance: the seed pendulum (Kane and Lagrange) generated as
C99, compiled with cffi, checked against sympy's own evaluation; and the
fast tier's one compile of the Eigen backend, checked against the C one."""
import os
import subprocess

import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen
import seed_pendulum
from helpers import crossing_times, pendulum_state, rel_err

TOL = 1e-12
N_SAMPLES = 50


def _params(rng):
    return {"L": rng.uniform(0.5, 3.0), "m": rng.uniform(0.2, 5.0), "g": rng.uniform(1.0, 20.0)}


# ----------------------------------------------------------------- Kane
@pytest.fixture(scope="module")
def kane_reference():
    """sympy-side functions, built independently of the generator: the
    unconstrained Kane equations from the same bodies and loads, the
    seed's f_c and f_v, and sympy's own constrained mass_matrix_full /
    forcing_full."""
    KM, s = seed_pendulum.derive_kane()
    q = [s["q2"], s["q1"]]
    u = [s["u2"], s["u1"]]
    qd = [qi.diff(s["t"]) for qi in q]
    pars = [s["L"], s["m"], s["g"]]
    kde = sm.Matrix([qd[0] - u[0], qd[1] - u[1]])
    free = me.KanesMethod(s["frame"], q_ind=q, u_ind=u, kd_eqs=kde)
    free.kanes_equations([s["particle"]], [(s["point"], s["m"] * s["g"] * s["frame"].x)])
    args = q + u + pars
    lam = lambda e: sm.lambdify(args, e, "numpy")  # noqa: E731
    return {
        "M": lam(free.mass_matrix), "f": lam(free.forcing),
        "fc": lam(s["f_c"]), "Jc": lam(s["f_c"].jacobian(q)),
        "fv": lam(s["f_v"]), "MMf": lam(KM.mass_matrix_full), "Ff": lam(KM.forcing_full),
    }


def test_kane_matrices_against_sympy(kane_sim, kane_reference):
    rng = np.random.default_rng(2)
    worst = {}
    for _ in range(N_SAMPLES):
        pr = _params(rng)
        p = np.array([pr["L"], pr["m"], pr["g"]])
        th = rng.uniform(-1.3, 1.3)          # away from the Kane singularity at q1 = 0
        x = pendulum_state(th, rng.uniform(-3, 3), pr["L"], "kane")
        args = list(x) + list(p)
        # residual functions at a random point off the manifold (nonzero values)
        xr = np.concatenate([rng.uniform(0.2, 2.0, 2) * rng.choice([-1, 1], 2), rng.uniform(-3, 3, 2)])
        qr, ur = xr[:2], xr[2:]
        argr = list(xr) + list(p)
        ref = kane_reference
        checks = {
            "mass_matrix": (kane_sim.mass_matrix(qr, p=p), np.array(ref["M"](*argr), float)),
            "forcing": (kane_sim.forcing(qr, ur, p=p), np.array(ref["f"](*argr), float).ravel()),
            "constraints": (kane_sim.constraints(qr, p=p), np.array(ref["fc"](*argr), float).ravel()),
            "constraint_jacobian": (kane_sim.constraint_jacobian(qr, p=p),
                                    np.array(ref["Jc"](*argr), float)),
            "velocity_constraints": (kane_sim.velocity_constraints(qr, ur, p=p),
                                     np.array(ref["fv"](*argr), float).ravel()),
            "rhs": (kane_sim.rhs(0.0, x, p=p),
                    np.linalg.solve(np.array(ref["MMf"](*args), float),
                                    np.array(ref["Ff"](*args), float).ravel())),
        }
        for k, (c, s_) in checks.items():
            worst[k] = max(worst.get(k, 0.0), rel_err(c, s_))
    print("kane max relative errors:", worst)
    for k, e in worst.items():
        assert e < TOL, (k, e)


# ------------------------------------------------------------- Lagrange
@pytest.fixture(scope="module")
def lagrange_reference():
    LM, s = seed_pendulum.derive_lagrange()
    q = [s["q1"], s["q2"]]
    qd = [s["q1d"], s["q2d"]]
    pars = [s["L"], s["m"], s["g"]]
    args = q + qd + pars
    lam = lambda e: sm.lambdify(args, e, "numpy")  # noqa: E731
    fv = s["f_c"].diff(s["t"])
    return {
        "M": lam(LM._m_d), "f": lam(LM.forcing), "fc": lam(s["f_c"]), "Jc": lam(s["f_c"].jacobian(q)),
        "fv": lam(fv), "MMf": lam(LM.mass_matrix_full), "Ff": lam(LM.forcing_full),
    }


def test_lagrange_matrices_against_sympy(lagrange_sim, lagrange_reference):
    rng = np.random.default_rng(3)
    worst = {}
    for _ in range(N_SAMPLES):
        pr = _params(rng)
        p = np.array([pr["L"], pr["m"], pr["g"]])
        th = rng.uniform(-np.pi, np.pi)      # anywhere, through the horizontal too
        x = pendulum_state(th, rng.uniform(-3, 3), pr["L"], "lagrange")
        args = list(x) + list(p)
        xr = np.concatenate([rng.uniform(-2, 2, 2), rng.uniform(-3, 3, 2)])
        q, u = xr[:2], xr[2:]
        argr = list(xr) + list(p)
        ref = lagrange_reference
        sol = np.linalg.solve(np.array(ref["MMf"](*args), float),
                              np.array(ref["Ff"](*args), float).ravel())
        checks = {
            "mass_matrix": (lagrange_sim.mass_matrix(q, p=p), np.array(ref["M"](*argr), float)),
            "forcing": (lagrange_sim.forcing(q, u, p=p), np.array(ref["f"](*argr), float).ravel()),
            "constraints": (lagrange_sim.constraints(q, p=p), np.array(ref["fc"](*argr), float).ravel()),
            "constraint_jacobian": (lagrange_sim.constraint_jacobian(q, p=p),
                                    np.array(ref["Jc"](*argr), float)),
            "velocity_constraints": (lagrange_sim.velocity_constraints(q, u, p=p),
                                     np.array(ref["fv"](*argr), float).ravel()),
            # sympy's full form solves [q', q'', lam]: compare the state part
            # and the multipliers (the mass_matrix_full solve's: -solve_multipliers)
            "rhs": (lagrange_sim.rhs(0.0, x, p=p), sol[:4]),
            "multipliers": (lagrange_sim.multipliers(0.0, x, p=p), sol[4:]),
        }
        for k, (c, s_) in checks.items():
            worst[k] = max(worst.get(k, 0.0), rel_err(c, s_))
    print("lagrange max relative errors:", worst)
    for k, e in worst.items():
        assert e < TOL, (k, e)


# -------------------------------------------------------- linearization
@pytest.fixture(scope="module")
def sympy_kane_AB():
    KM, s = seed_pendulum.derive_kane()
    q_op = {s["q1"]: s["L"], s["q2"]: 0}
    u_op = {s["u1"]: 0, s["u2"]: 0}
    ud_op = {s["u1"].diff(s["t"]): 0, s["u2"].diff(s["t"]): 0}
    A, B, inp = KM.linearize(op_point=[q_op, u_op, ud_op], A_and_B=True, new_method=True,
                             simplify=True)
    return A, B, s


@pytest.fixture(scope="module")
def sympy_lagrange_AB():
    LM, s = seed_pendulum.derive_lagrange()
    t = s["t"]
    op = {s["q1"]: s["L"], s["q2"]: 0, s["q1d"]: 0, s["q2d"]: 0,
          s["q1d"].diff(t): 0, s["q2d"].diff(t): 0}
    op.update(LM.solve_multipliers(op_point=op))
    A, B, inp = LM.linearize([s["q2"]], [s["q2d"]], [s["q1"]], [s["q1d"]], op_point=op,
                             A_and_B=True)
    return A, B, s


@pytest.mark.parametrize("g,L", [(9.81, 1.0), (1.62, 0.35), (24.8, 4.0), (3.7, 2.5)])
def test_kane_linearize_seed_point(kane_sim, sympy_kane_AB, g, L):
    A_s, B_s, s = sympy_kane_AB
    A_ref = np.array(A_s.subs({s["g"]: g, s["L"]: L}).evalf(), dtype=float)
    A, B = kane_sim.linearize([0.0, L, 0.0, 0.0], p=[L, 1.3, g])
    assert A.shape == (2, 2) and B.shape == (2, 0) and B_s.shape == (0, 0)
    assert rel_err(A, A_ref) < 1e-12
    assert rel_err(A, [[0, 1], [-g / L, 0]]) < 1e-12


@pytest.mark.parametrize("g,L", [(9.81, 1.0), (1.62, 0.35), (24.8, 4.0), (3.7, 2.5)])
def test_lagrange_linearize_seed_point(lagrange_sim, sympy_lagrange_AB, g, L):
    A_s, B_s, s = sympy_lagrange_AB
    A_ref = np.array(A_s.subs({s["g"]: g, s["L"]: L, s["m"]: 0.7}).evalf(), dtype=float)
    A, B = lagrange_sim.linearize([L, 0.0, 0.0, 0.0], p=[L, 0.7, g])
    assert A.shape == (2, 2) and B.shape == (2, 0)
    assert rel_err(A, A_ref) < 1e-12
    assert rel_err(A, [[0, 1], [-g / L, 0]]) < 1e-12


# ------------------------------------------------------ the binary (CMake)
# kane_binary: conftest.py (one build per session, shared with the other
# modules' binary tests)


def test_binary_period_and_constraint(kane_binary, tmp_path):
    from scipy.special import ellipk
    L, g = 1.7, 9.81
    th0 = np.radians(30.0)
    csv = tmp_path / "run.csv"
    x0 = pendulum_state(th0, 0.0, L, "kane")
    cmd = [str(kane_binary), "--t-end", "10", "--dt", "0.001", "--param", f"L={L}",
           "--param", f"g={g}", "--x0", ",".join(repr(float(v)) for v in x0),
           "--output", str(csv)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    with open(csv) as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert header[:5] == ["t", "q2", "q1", "u2", "u1"]
    t, y, x = data[:, 0], data[:, 1], data[:, 2]
    assert abs(t[-1] - 10.0) < 1e-12 and len(t) == 10001
    T_exact = 4 * np.sqrt(L / g) * ellipk(np.sin(th0 / 2) ** 2)
    # y = L sin(theta) falls through zero once per period
    cr = crossing_times(t, y, direction=-1)
    assert len(cr) >= 3
    T = (cr[-1] - cr[0]) / (len(cr) - 1)
    print(f"period {T:.12f} exact {T_exact:.12f} rel err {abs(T - T_exact) / T_exact:.2e}")
    assert abs(T - T_exact) / T_exact < 1e-5
    assert np.max(np.abs(x ** 2 + y ** 2 - L ** 2)) < 1e-6


def test_binary_linearize_prints_A(kane_binary):
    proc = subprocess.run([str(kane_binary), "--linearize", "--x0", "q1=2.0", "--param", "L=2.0"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    rows = [ln.split() for ln in proc.stdout.splitlines() if ln.startswith("  ")]
    A = np.array([[float(v) for v in r[1:]] for r in rows[:2]])
    assert rel_err(A, [[0, 1], [-9.81 / 2.0, 0]]) < 1e-11


def test_binary_bad_arguments(kane_binary):
    for args, code in ((["--x0", "nosuch=1"], 2), (["--param", "L=abc"], 2),
                       (["--method", "euler"], 2), (["--frobnicate"], 2),
                       (["--x0", "q1=0", "--x0", "q2=1"], 1)):
        proc = subprocess.run([str(kane_binary), *args], capture_output=True, text=True)
        assert proc.returncode == code, (args, proc.returncode, proc.stderr)
        assert proc.stderr.strip(), args


# ------------------------------------------------------------ strict C
@pytest.mark.parametrize("which", ["kane", "lagrange"])
def test_generated_c_compiles_strict(tmp_path, which, kane_model, lagrange_model):
    model = kane_model if which == "kane" else lagrange_model
    paths = gen.generate(model, tmp_path / "src")
    names = sorted(p.name for p in paths)
    for need in (f"{model.name}.h", f"{model.name}.c", "main.c", "CMakeLists.txt", "gen_rt.h"):
        assert need in names
    for p in paths:
        if p.suffix == ".c":
            proc = subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic",
                                   "-c", str(p), "-o", os.devnull, "-I", str(tmp_path / "src")],
                                  capture_output=True, text=True)
            assert proc.returncode == 0, proc.stderr


def test_generation_is_reproducible(tmp_path, kane_model):
    a = gen.generate(kane_model, tmp_path / "a")
    b = gen.generate(seed_pendulum.kane_model(), tmp_path / "b")
    for pa, pb in zip(sorted(a), sorted(b)):
        assert pa.read_text() == pb.read_text(), pa.name


# ------------------------------------------------------- Eigen backend
@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_agrees_with_c(kane_model, kane_sim):
    """The fast tier's compile of the C++/Eigen backend (tests/features/test_eigen.py,
    marked slow, checks every model and method): the seed Kane pendulum's
    mass matrix, rhs, multipliers and linearization agree with the C backend."""
    from conftest import require_eigen
    require_eigen()
    sim = gen.compile(kane_model, backend="eigen")
    assert sim.build_info["backend"] == "eigen"
    rng = np.random.default_rng(11)
    for _ in range(5):
        x = pendulum_state(rng.uniform(-1.3, 1.3), rng.uniform(-3, 3), 1.0, "kane")
        q = x[:kane_sim.nq]
        assert rel_err(sim.mass_matrix(q), kane_sim.mass_matrix(q)) < 1e-13
        assert rel_err(sim.rhs(0.2, x), kane_sim.rhs(0.2, x)) < 1e-13
        assert rel_err(sim.multipliers(0.2, x), kane_sim.multipliers(0.2, x)) < 1e-13
        for a, c in zip(sim.linearize(x), kane_sim.linearize(x)):
            assert rel_err(a, c) < 1e-13


# ----------------------------------------------------------- bad input
def test_unknown_symbol_refused_before_writing(tmp_path):
    KM, s = seed_pendulum.derive_kane()
    out = tmp_path / "never"
    with pytest.raises(gen.ModelError, match=r"\bg\b"):
        m = gen.Model.from_kanes(KM, constants={s["L"]: 1.0, s["m"]: 1.0}, name="pend")
        gen.generate(m, out)
    assert not out.exists()


@pytest.mark.parametrize("name", ["1pend", "Pend", "pend-x", "int", "double", "sin", "", "a__b",
                                  "x" * 50, "pend_"])
def test_bad_model_names(name):
    KM, s = seed_pendulum.derive_kane()
    with pytest.raises(gen.ModelError, match="name"):
        gen.Model.from_kanes(KM, constants={s["L"]: 1.0, s["m"]: 1.0, s["g"]: 9.81}, name=name)
