"""The C++/Eigen backend: a typed face over the one C runtime (issue 31).

Its library is the C backend's model and runtime (for the build's scalar
type, the C API; again for the other type under the prefix <name>_s/_d, the
runtime's names renamed by csrc/eigen/gen_rt_names.h), so:
- every Simulator method of every example model gives the C backend's
  numbers bit for bit (rhs, multipliers, linearize, RK4, DOPRI5 and RODAS4
  runs, ...), and the seed models do in float too;
- the plan's solver choice holds: a model whose mass matrix is not symmetric
  (the plan picks "lu") against sympy, on both backends;
- the seed models' rhs and linearization against sympy (independent);
- the generated C++ with -std=c++17 -Wall -Wextra -Werror -pedantic against
  Eigen 3.4: the generated CMake project (find_package(Eigen3 3.4)), its
  standalone binary against the C backend's (the same CSV text), and
  tests/cpp/test_typed.cpp, which uses the typed face for double and float in
  one program with heap allocation forbidden, checks the double face against
  the C API bit for bit and prints both types' numbers, checked here bit for
  bit against the C backend built for each type.

The builds run up front in a pool of two processes; the compiled modules
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
from gen.codegen.backends import RUNTIME_SOURCES
import gen.plan.ir
from gen.codegen.render import model_sources
from conftest import require_eigen
from helpers import pendulum_state, rel_err

ROOT = Path(__file__).resolve().parents[2]
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
# built for float too (both backends)
FLOAT_MODELS = ("kane", "lagrange")


# ------------------------------------------ a non-symmetric mass matrix
def derive_nonsymmetric():
    """Two carts on springs along N.x; cart 1's actuator is fed forward from
    cart 2's acceleration and damped by a speed- and position-dependent
    force (F1 = -c x2'' - d x1' sin x2): LagrangesMethod's mass matrix is
    [[m1, c], [0, m2]], not symmetric, and the plan solves it by LU."""
    import sympy.physics.mechanics as me
    x1, x2 = me.dynamicsymbols("x1 x2")
    m1, m2, k1, k2, c, d = sm.symbols("m1 m2 k1 k2 c d")
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P1 = O.locatenew("P1", x1 * N.x)
    P1.set_vel(N, x1.diff(t) * N.x)
    P2 = O.locatenew("P2", x2 * N.x)
    P2.set_vel(N, x2.diff(t) * N.x)
    L = (me.Lagrangian(N, me.Particle("b1", P1, m1), me.Particle("b2", P2, m2))
         - k1 * x1**2 / 2 - k2 * (x2 - x1)**2 / 2)
    forces = [(P1, -c * x2.diff(t, 2) * N.x - d * x1.diff(t) * sm.sin(x2) * N.x)]
    LM = me.LagrangesMethod(L, [x1, x2], forcelist=forces, frame=N)
    LM.form_lagranges_equations()
    return LM, (x1, x2, m1, m2, k1, k2, c, d)


NONSYM_P = (1.5, 0.7, 3.0, 2.0, 0.4, 0.3)      # m1, m2, k1, k2, c, d


def nonsymmetric_model(name="nonsym"):
    LM, s = derive_nonsymmetric()
    return gen.Model.from_lagrange(LM, constants=dict(zip(s[2:], NONSYM_P)), name=name)


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
        model, backend, real = arg
        gen.compile(model, backend=backend, real=real, derivatives=True)  # into the cache
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
    c_sources = ";".join(model_sources("pend_c"))
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
    models["nonsym"] = nonsymmetric_model()
    jobs = []
    for k, m in models.items():
        for real in ("double", "float") if k in FLOAT_MODELS else ("double",):
            jobs.append(("cffi", (m, "eigen", real)))
            jobs.append(("cffi", (m, "c", real)))
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
        out[k] = (gen.compile(m, derivatives=True), gen.compile(m, backend="eigen"))
        assert out[k][1].build_info["cached"] and out[k][1].build_info["backend"] == "eigen"
        if k in FLOAT_MODELS:
            out[k, "float"] = (gen.compile(m, real="float", derivatives=True),
                               gen.compile(m, backend="eigen", real="float"))
    return out


def same_bits(a, b):
    """The same shape and the same bytes (-0.0 is not 0.0, NaN is NaN)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


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
        elif key in ("cart", "double_pendulum", "nonsym"):
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
    for method in ("dopri5", "rodas4"):
        sol = sim.simulate(x, 1.0, 0.1, method=method, r=R, rtol=1e-9, atol=1e-11)
        t, X, lam = sol.t, sol.x, sol.lam
        out["simulate_" + method] = np.concatenate([t, X.ravel(), lam.ravel()])
    return out


@pytest.mark.parametrize("key", list(MODELS) + ["nonsym"])
def test_c_and_eigen_same_bits(sims, key):
    """Every Simulator method, and RK4, DOPRI5 and RODAS4 runs: the same
    bits on both backends (the Eigen backend's library is the C one)."""
    sim_c, sim_e = sims[key]
    rng = np.random.default_rng(zlib.crc32(key.encode()))
    differ = set()
    n = 0
    for i, (x, r) in enumerate(_states(key, sim_c, rng)):
        pert = rng.normal(0, 1e-3, sim_c.nx)
        a = _calls(sim_e, x, r, pert)
        b = _calls(sim_c, x, r, pert)
        if i < 3:           # the trajectories: three initial states per model
            a.update(_simulations(sim_e, x, r))
            b.update(_simulations(sim_c, x, r))
        assert a.keys() == b.keys()
        differ |= {name for name in b if not same_bits(a[name], b[name])}
        n += len(b)
    print(f"\n{key}: {n} results, bit-identical but {sorted(differ)}")
    assert not differ


@pytest.mark.parametrize("key", FLOAT_MODELS)
def test_c_and_eigen_same_bits_float(sims, key):
    """The seed models built for float: rhs, multipliers, linearize and the
    DOPRI5 and RODAS4 runs, the same bits on both backends."""
    sim_c, sim_e = sims[key, "float"]
    rng = np.random.default_rng(5)
    for k in range(N_STATES):
        x = pendulum_state(rng.uniform(-1.3, 1.3), rng.uniform(-3, 3), 1.0, key)
        got = {}
        for tag, sim in (("c", sim_c), ("e", sim_e)):
            out = {"rhs": sim.rhs(0.3, x), "multipliers": sim.multipliers(0.3, x),
                   "linearize": np.concatenate([a.ravel() for a in sim.linearize(x)])}
            if k < 2:
                for method in ("dopri5", "rodas4"):
                    out[method] = sim.simulate(x, 1.0, 0.1, method=method, rtol=1e-5,
                                               atol=1e-7)[1]
            got[tag] = out
        for name in got["c"]:
            assert got["c"][name].dtype == np.float32, name
            assert same_bits(got["e"][name], got["c"][name]), (key, k, name)


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
    """sympy's Linearizer at moving points (as tests/physics/test_linearize.py does
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


def test_nonsymmetric_mass_matrix_lu(sims):
    """M = [[m1, c], [0, m2]]: the plan picks the LU solve, and both backends
    follow it: rhs and linearization against sympy (M^-1 f and its Jacobian,
    lambdified from LagrangesMethod's own matrices). An LDL^T over M's lower
    triangle (what the old C++ runtime did) is off by far more than the
    tolerance here."""
    model = nonsymmetric_model()
    assert gen.plan.ir.plan(model).accel == "lu"
    LM, s = derive_nonsymmetric()
    x1, x2 = s[:2]
    v1, v2 = sm.symbols("v1 v2")
    qd = {x1.diff(): v1, x2.diff(): v2}
    sub = lambda e: e.subs(qd).subs({x1: sm.Symbol("y1"), x2: sm.Symbol("y2")})  # noqa: E731
    y = sm.symbols("y1 y2")
    M, f = sub(LM.mass_matrix), sub(LM.forcing)
    rhs = sm.Matrix([v1, v2]).col_join(M.LUsolve(f))
    X = sm.Matrix([*y, v1, v2])
    args = [*X, *s[2:]]
    rhs_f = sm.lambdify(args, rhs, "numpy")
    jac_f = sm.lambdify(args, rhs.jacobian(X), "numpy")
    M_lower = sm.Matrix(2, 2, lambda i, j: M[max(i, j), min(i, j)])   # what an LDL^T reads
    lower_f = sm.lambdify(args, sm.Matrix([v1, v2]).col_join(M_lower.LUsolve(f)), "numpy")
    rng = np.random.default_rng(31)
    worst = {"c": 0.0, "eigen": 0.0}
    gap = np.inf
    for _ in range(10):
        x = rng.uniform(-1, 1, 4)
        p = np.array(NONSYM_P) * rng.uniform(0.8, 1.25, 6)
        want = np.array(rhs_f(*x, *p), float).ravel()
        want_A = np.array(jac_f(*x, *p), float)
        gap = min(gap, rel(np.array(lower_f(*x, *p), float).ravel(), want))
        for tag, sim in zip(("c", "eigen"), sims["nonsym"]):
            A, B = sim.linearize(x, p=p)
            worst[tag] = max(worst[tag], rel(sim.rhs(0.0, x, p=p), want), rel(A, want_A))
    print(f"\nnon-symmetric M vs sympy: {worst}; a symmetric solve is off by {gap:.2f}")
    assert gap > 1e-2
    assert all(v < 1e-12 for v in worst.values()), worst


# --------------------------------------------- the C++ project and binary
@pytest.fixture(scope="module")
def cmake_build(builds):
    if builds["cmake"] is None:
        from conftest import require_tool
        require_tool("cmake")
    rc, log, bld = builds["cmake"].result()
    assert rc == 0, log
    return Path(bld)


def test_typed_cpp_program(cmake_build, sims):
    """tests/cpp/test_typed.cpp: the typed face (double and float in one
    program, no heap) against the C API bit for bit, built with the strict
    flags; exits non-zero on a mismatch. Its printed numbers (hex) for both
    types are the C backend's for that type, bit for bit."""
    r = subprocess.run([str(cmake_build / "test_typed")], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.splitlines()[-1].startswith("ok")
    got = {}
    for line in r.stdout.splitlines()[:-1]:
        real, what, *vals = line.split()
        got[real, what] = np.array([float.fromhex(v) for v in vals])
    assert len(got) == 12, sorted(got)
    for real, key in (("double", "kane"), ("float", ("kane", "float"))):
        sim = sims[key][0]                                  # the C backend
        dtype = np.float64 if real == "double" else np.float32
        x = got[real, "x"].astype(dtype)
        want = {"rhs": sim.rhs(0.0, x), "lam": sim.multipliers(0.0, x),
                "A": sim.linearize(x)[0]}
        for method in ("dopri5", "rodas4"):
            want[method] = sim.simulate(x, 1.0, 0.1, method=method, rtol=1e-6, atol=1e-8)[1]
        for what, w in want.items():
            w = np.asarray(w).ravel()
            assert same_bits(got[real, what].astype(w.dtype), w), (real, what)
            assert np.array_equal(got[real, what], w.astype(float)), (real, what)


def test_library_names(cmake_build):
    """The Eigen library defines each name once: the second copy's runtime
    names carry gen_rt_s_ (gen_rt_names.h is complete)."""
    from conftest import require_tool
    require_tool("nm")
    lib = cmake_build / "eigen_model" / "libpend_e.a"
    r = subprocess.run(["nm", "-g", "--defined-only", str(lib)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    names = [ln.split()[-1] for ln in r.stdout.splitlines() if len(ln.split()) == 3
             and ln.split()[1] in "TDRB"]
    dup = {n for n in names if names.count(n) > 1}
    assert not dup, sorted(dup)
    assert {n for n in names if n.startswith("gen_rt_s_")} == {
        "gen_rt_s_" + n[len("gen_rt_"):] for n in names
        if n.startswith("gen_rt_") and not n.startswith("gen_rt_s_")}
    assert all(n.startswith(("pend_e_", "gen_rt_", "_Z")) for n in names), names


def test_binary_matches_c_binary(cmake_build, tmp_path):
    """The Eigen project's standalone simulator (main.c on the C API) writes
    the C backend's simulator's CSV and linearization, character for
    character."""
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
        assert len(e) == 202 and e == c                      # header + 201 rows, the same text
    assert out["e", "lin"] == out["c", "lin"]
    r = subprocess.run([str(exe_e), "--method", "euler"], capture_output=True, text=True)
    assert r.returncode == 2
