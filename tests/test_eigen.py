"""Issue 5: the C++17/Eigen backend.

- every Simulator method of every example model, C backend against the Eigen
  backend (through its extern "C" layer, the same cffi wrapper and the same
  Simulator) at random states, to 1e-13 relative (max|a-b| / max|b|);
- the seed models' rhs and linearization on the Eigen backend against sympy;
- the generated C++ with -std=c++17 -Wall -Wextra -Werror -pedantic against
  Eigen 3.4: the generated CMake project (find_package(Eigen3 3.4)), its
  standalone binary against the C backend's, and tests/cpp/test_typed.cpp,
  which uses the typed C++ API for double and float with heap allocation
  forbidden (EIGEN_RUNTIME_NO_MALLOC) and compares with the C backend.

The C++ compiles are slow (Eigen's templates: ~10 s of CPU per model), so
every build runs up front in a pool of two processes; the compiled modules
land in gen.compile's content-keyed cache, where the tests find them.
"""
import multiprocessing
import os
import shutil
import subprocess
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
import zlib

import numpy as np
import pytest
import sympy as sm

import chaplygin_sleigh as cs
import double_pendulum as dp
import four_bar as fb
import gen
import n_link_cart as nl
import rolling_disc as rd
import seed_pendulum as sp
from gen.backends import RUNTIME_SOURCES
from gen.render import model_sources
from conftest import require_eigen
from helpers import pendulum_state, rel_err

ROOT = Path(__file__).resolve().parent.parent
TOL = 1e-13
N_STATES = 10
TINY = 1e-300

MODELS = {
    "kane": sp.kane_model,
    "lagrange": sp.lagrange_model,
    "sleigh": cs.model,
    "cart": nl.model,
    "four_bar": fb.model,
    "rolling_disc": rd.model,
    "double_pendulum": dp.model,
}


def rel(a, b):
    """Norm-based relative error max|a-b| / max(max|b|, tiny)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    assert a.shape == b.shape, (a.shape, b.shape)
    if a.size == 0:
        return 0.0
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), TINY))


# ------------------------------------------------------------- the builds
def _build(job):
    kind, arg = job
    if kind == "cffi":
        model, backend = arg
        gen.compile(model, backend=backend)          # into the cache the fixture reads
        return None
    return _cmake_project(*arg)


def _cmake_project(work):
    """Generate the seed Kane pendulum with both backends (prefixes pend_e and
    pend_c), build tests/cpp against them (the generated Eigen project by
    add_subdirectory, strict flags) and return (returncode, log, build dir)."""
    work = Path(work)
    model_e = sp.kane_model(name="pend_e")
    model_c = sp.kane_model(name="pend_c")
    gen.generate(model_e, work / "pend_e", backend="eigen")
    gen.generate(model_c, work / "pend_c")
    bld = work / "build"
    c_sources = ";".join(model_sources("pend_c") + RUNTIME_SOURCES)
    log = []
    for cmd in (["cmake", "-S", str(ROOT / "tests" / "cpp"), "-B", str(bld),
                 "-DCMAKE_BUILD_TYPE=Release", f"-DEIGEN_PROJECT={work / 'pend_e'}",
                 f"-DC_PROJECT={work / 'pend_c'}", f"-DC_SOURCES={c_sources}"],
                ["cmake", "--build", str(bld), "-j", "2"]):
        r = subprocess.run(cmd, capture_output=True, text=True)
        log.append("$ " + " ".join(cmd) + "\n" + r.stdout + r.stderr)
        if r.returncode:
            return r.returncode, "\n".join(log), str(bld)
    return 0, "\n".join(log), str(bld)


@pytest.fixture(scope="module")
def builds(tmp_path_factory):
    """Start every build at once (two worker processes): the cffi modules of
    all models for both backends, and the CMake project of tests/cpp."""
    require_eigen()
    models = {k: f() for k, f in MODELS.items()}
    jobs = []
    for k, m in models.items():
        jobs.append(("cffi", (m, "eigen")))
        jobs.append(("cffi", (m, "c")))
    cmake_job = None
    if shutil.which("cmake") is not None:
        cmake_job = ("cmake", (str(tmp_path_factory.mktemp("eigen_cmake")),))
    ctx = multiprocessing.get_context("fork" if os.name == "posix" else "spawn")
    pool = ProcessPoolExecutor(max_workers=2, mp_context=ctx)
    try:
        cmake_future = pool.submit(_build, cmake_job) if cmake_job else None
        futures = [pool.submit(_build, j) for j in jobs]
        for f in futures:
            f.result()
        yield {"models": models, "cmake": cmake_future}
    finally:
        pool.shutdown(wait=True)


@pytest.fixture(scope="module")
def sims(builds):
    """{model key: (C simulator, Eigen simulator)}, from the cache."""
    out = {}
    for k, m in builds["models"].items():
        out[k] = (gen.compile(m), gen.compile(m, backend="eigen"))
        assert out[k][1].build_info["cached"] and out[k][1].build_info["backend"] == "eigen"
    return out


# ---------------------------------------------------------- the states
def _states(key, sim, rng):
    """N_STATES states (x, r) per model, consistent with the constraints."""
    out = []
    for k in range(N_STATES):
        r = rng.uniform(-1, 1, sim.nr)
        if key in ("kane", "lagrange"):
            th = rng.uniform(-1.3, 1.3)        # away from the Kane partition's singularity
            x = pendulum_state(th, 0.0 if k < 2 else rng.uniform(-3, 3), 1.0, key)
        elif key == "sleigh":
            x = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1.2, 1.2),
                          rng.uniform(-2, 2), rng.uniform(-2, 2), 0.0])
            x = sim.consistent_state(x)
        elif key in ("cart", "double_pendulum"):
            x = np.concatenate([rng.uniform(-1, 1, sim.nq), rng.uniform(-2, 2, sim.nu)])
        elif key == "rolling_disc":
            x = np.concatenate([rng.uniform(-0.5, 0.5, sim.nq), rng.uniform(-2, 2, 3),
                                np.zeros(2)])
            x[7] += 6.0                        # rolling, not toppled
            x = sim.consistent_state(x)
        else:
            h = fb.HANGING
            x = np.array([h["q1"] + rng.uniform(-0.3, 0.3), h["q2"], h["q3"],
                          rng.uniform(-2, 2), 0.0, 0.0])
            x = sim.consistent_state(x)
        out.append((x, r))
    return out


def _calls(sim, x, r, rng_pert):
    """Every Simulator method at (x, r): {name: array}."""
    q, u = x[:sim.nq], x[sim.nq:]
    xp = x + rng_pert          # off the manifold, for project / consistent_state
    R = r if sim.nr else None
    out = {
        "mass_matrix": sim.mass_matrix(q),
        "forcing": sim.forcing(q, u, r=R),
        "kinematics": sim.kinematics(q, u),
        "constraints": sim.constraints(q + rng_pert[:sim.nq]),
        "constraint_jacobian": sim.constraint_jacobian(q),
        "velocity_constraints": sim.velocity_constraints(q, u + rng_pert[sim.nq:]),
        "velocity_constraint_matrix": np.concatenate(
            [a.ravel() for a in sim.velocity_constraint_matrix(q)]),
        "rhs": sim.rhs(0.3, x, r=R),
        "multipliers": sim.multipliers(0.3, x, r=R),
        "project": sim.project(xp),
        "consistent_state": sim.consistent_state(xp),
        "step_rk4": sim.step(0.0, x, 0.01, r=R, method="rk4"),
        "linearize": np.concatenate([a.ravel() for a in sim.linearize(x, r=R)]),
    }
    if sim.has_energy:
        out["energy"] = np.array([sim.energy(x)])
    return out


def _simulations(sim, x, r):
    R = r if sim.nr else None
    out = {}
    t, X = sim.simulate(x, 0.5, 0.01, method="rk4", r=R)
    out["simulate_rk4"] = np.concatenate([t, X.ravel()])
    sol = sim.simulate(x, 1.0, 0.1, method="dopri5", r=R, rtol=1e-9, atol=1e-11)
    t, X, lam = sol.t, sol.x, sol.lam
    out["simulate_dopri5"] = np.concatenate([t, X.ravel(), lam.ravel()])
    return out


@pytest.mark.parametrize("key", list(MODELS))
def test_c_and_eigen_agree(sims, key):
    sim_c, sim_e = sims[key]
    rng = np.random.default_rng(zlib.crc32(key.encode()))
    worst = {}
    for i, (x, r) in enumerate(_states(key, sim_c, rng)):
        pert = rng.normal(0, 1e-3, sim_c.nx)
        a = _calls(sim_e, x, r, pert)
        b = _calls(sim_c, x, r, pert)
        if i < 3:           # the trajectories: three initial states per model
            a.update(_simulations(sim_e, x, r))
            b.update(_simulations(sim_c, x, r))
        assert a.keys() == b.keys()
        for name in b:
            worst[name] = max(worst.get(name, 0.0), rel(a[name], b[name]))
    print(f"\n{key}: max relative error Eigen vs C: "
          + ", ".join(f"{k} {v:.1e}" for k, v in sorted(worst.items())))
    bad = {k: v for k, v in worst.items() if not v < TOL}
    assert not bad, bad


def test_eigen_errors_match_c(sims):
    """The same statuses become the same exceptions."""
    sim_c, sim_e = sims["kane"]
    x = np.array([1.0, 0.0, 0.0, 1.0])     # q1 = 0: the Kane partition (u1 dependent) is singular
    for sim in (sim_c, sim_e):
        with pytest.raises(gen.SingularError):
            sim.rhs(0.0, x)
        with pytest.raises(ValueError):
            sim.rhs(0.0, [np.nan, 1.0, 0.0, 0.0])
    sim_c, sim_e = sims["sleigh"]
    x = np.array([0, 0, np.pi / 2, 1.0, 0.0, 0.0])
    for sim in (sim_c, sim_e):
        with pytest.raises(gen.SingularError):
            sim.linearize(x, r=[0, 0])


# ------------------------------------------------------ against sympy
def _num(M):
    return np.array(sm.Matrix(M).evalf(), dtype=float)


def test_seed_rhs_against_sympy(sims):
    KM, s = sp.derive_kane()
    LM, s2 = sp.derive_lagrange()
    rng = np.random.default_rng(21)
    worst = {}
    for which, meth, sym in (("kane", KM, s), ("lagrange", LM, s2)):
        sim = sims[which][1]
        names = (["q2", "q1", "u2", "u1"] if which == "kane" else ["q1", "q2", "q1d", "q2d"])
        args = [sym[n] for n in names] + [sym["L"], sym["m"], sym["g"]]
        MM = sm.lambdify(args, meth.mass_matrix_full, "numpy")
        FF = sm.lambdify(args, meth.forcing_full, "numpy")
        for _ in range(20):
            L, m, g = rng.uniform(0.5, 3), rng.uniform(0.2, 5), rng.uniform(1, 20)
            x = pendulum_state(rng.uniform(-1.3, 1.3), rng.uniform(-3, 3), L, which)
            sol = np.linalg.solve(np.array(MM(*x, L, m, g), float),
                                  np.array(FF(*x, L, m, g), float).ravel())
            e = rel(sim.rhs(0.0, x, p=[L, m, g]), sol[:4])
            worst[which] = max(worst.get(which, 0.0), e)
            if which == "lagrange":
                e = rel(sim.multipliers(0.0, x, p=[L, m, g]), sol[4:])
                worst["lagrange multipliers"] = max(worst.get("lagrange multipliers", 0.0), e)
    print("\nEigen rhs vs sympy:", {k: f"{v:.1e}" for k, v in worst.items()})
    assert all(v < 1e-12 for v in worst.values()), worst


def test_seed_linearize_against_sympy(sims):
    """sympy's Linearizer at moving points (as tests/test_linearize.py does
    for the C backend), and the exact hanging/inverted results."""
    KM, s = sp.derive_kane()
    lin = KM.to_linearizer(linear_solver="CRAMER")
    t = s["t"]
    sim = sims["kane"][1]
    rng = np.random.default_rng(22)
    worst = 0.0
    for k in range(5):
        L, m, g = rng.uniform(0.5, 2), rng.uniform(0.5, 2), rng.uniform(2, 15)
        x = pendulum_state(rng.uniform(-1.3, 1.3), 0.0 if k == 0 else rng.uniform(-3, 3), L,
                           "kane")
        pv = {s["L"]: L, s["m"]: m, s["g"]: g}
        st = {s["q2"]: x[0], s["q1"]: x[1], s["u2"]: x[2], s["u1"]: x[3]}
        ud = np.linalg.solve(_num(KM.mass_matrix_full.xreplace(pv).xreplace(st)),
                             _num(KM.forcing_full.xreplace(pv).xreplace(st)).ravel())[2:]
        op = dict(st)
        op.update({s["u2"].diff(t): ud[0], s["u1"].diff(t): ud[1]})
        op.update(pv)
        A_s, _ = lin.linearize(op_point=op, A_and_B=True)
        A, B = sim.linearize(x, p=[L, m, g])
        worst = max(worst, rel_err(A, _num(A_s)))
    print(f"\nEigen kane linearize vs sympy Linearizer: {worst:.1e}")
    assert worst < 1e-9
    for which in ("kane", "lagrange"):
        sim = sims[which][1]
        for L, g in ((1.0, 9.81), (2.5, 3.7)):
            for th, sign in ((0.0, -1), (np.pi, +1)):
                A, _ = sim.linearize(pendulum_state(th, 0.0, L, which), p=[L, 1.0, g])
                assert rel_err(A, [[0, 1], [sign * g / L, 0]]) < 1e-12, (which, th, A)


# --------------------------------------------- the C++ project and binary
@pytest.fixture(scope="module")
def cmake_build(builds):
    if builds["cmake"] is None:
        from conftest import require_tool
        require_tool("cmake")
    rc, log, bld = builds["cmake"].result()
    assert rc == 0, log
    return Path(bld)


def test_typed_cpp_program(cmake_build):
    """tests/cpp/test_typed.cpp: the typed API (double and float, no heap)
    against the C backend, built with the strict flags; exits non-zero on a
    mismatch."""
    r = subprocess.run([str(cmake_build / "test_typed")], capture_output=True, text=True)
    print(r.stdout)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "ok" in r.stdout


def test_binary_matches_c_binary(cmake_build, tmp_path):
    """The Eigen project's standalone simulator (main.c on the extern "C"
    layer) writes the CSV of the C backend's simulator."""
    exe_e = cmake_build / "eigen_model" / "pend_e_sim"
    exe_c = cmake_build / "pend_c_sim"
    args = ["--t-end", "2", "--dt", "0.01", "--x0", "q2=0.5", "--x0", "q1=0.8"]
    out = {}
    for tag, exe in (("e", exe_e), ("c", exe_c)):
        for method in ("rk4", "dopri5"):
            csv = tmp_path / f"{tag}_{method}.csv"
            r = subprocess.run([str(exe), *args, "--method", method, "--output", str(csv)],
                               capture_output=True, text=True)
            assert r.returncode == 0, r.stderr
            out[tag, method] = csv.read_text().splitlines()
        r = subprocess.run([str(exe), "--linearize", "--x0", "q1=1", "--param", "L=1"],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        out[tag, "lin"] = r.stdout
    for method in ("rk4", "dopri5"):
        e, c = out["e", method], out["c", method]
        assert e[0] == c[0] and len(e) == len(c) == 202     # header + 201 rows
        a = np.array([[float(v) for v in line.split(",")] for line in e[1:]])
        b = np.array([[float(v) for v in line.split(",")] for line in c[1:]])
        assert rel(a, b) < 1e-12, (method, rel(a, b))
    # the same text up to the sign of zeros and the last digit of %.12g
    tok_e, tok_c = out["e", "lin"].split(), out["c", "lin"].split()
    assert len(tok_e) == len(tok_c)
    for a, b in zip(tok_e, tok_c):
        try:
            fa, fb_ = float(a), float(b)
        except ValueError:
            assert a == b
        else:
            assert abs(fa - fb_) <= 1e-11 * max(1.0, abs(fb_)), (a, b)
    r = subprocess.run([str(exe_e), "--method", "euler"], capture_output=True, text=True)
    assert r.returncode == 2
