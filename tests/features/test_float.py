"""real="float": float arithmetic throughout (sinf, 1.0F, no promotion to
double) in the model, the runtime and the binary, and numbers that agree
with the double build to float accuracy.

Error measures: for rhs and linearize, the norm-based relative error
||c_float - c_double||_2 / ||c_double||_2 at the same (float-representable)
state; for a simulation, max over the output times of |x_float - x_double|
divided by max |x_double| over the trajectory.
"""
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import sympy as sm

import gen
from gen.codegen.render import model_sources
from conftest import require_tool
from gen.sym.printers import ModelCPrinter
from helpers import pendulum_state

ROOT = Path(__file__).resolve().parents[2]
FLOAT_FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wdouble-promotion",
               "-Wfloat-conversion", "-Wvla"]
DOUBLE_CALL = re.compile(r"\b(sin|cos|tan|asin|acos|atan|atan2|sinh|cosh|tanh|exp|log|sqrt|"
                         r"cbrt|pow|fabs|floor|ceil|fmod|fmin|fmax)\(")


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def test_printer_float_literals_and_functions():
    x, y = sm.symbols("x y")
    pr = ModelCPrinter({x: "q[0]", y: "q[1]"}, "float")
    assert pr.doprint(sm.sin(x) * sm.cos(y)) == "sinf(q[0])*cosf(q[1])"
    assert pr.doprint(sm.sqrt(x)) == "sqrtf(q[0])"
    assert pr.doprint(sm.Float("9.81") * x) == "9.81F*q[0]"
    assert pr.doprint(x / 3) == "(1.0F/3.0F)*q[0]"
    assert pr.doprint(x ** -2) == "(1.0F/(q[0]*q[0]))"
    assert pr.doprint(sm.atan2(y, x)) == "atan2f(q[1], q[0])"
    assert pr.doprint(sm.Abs(x)) == "fabsf(q[0])"
    assert pr.doprint(sm.pi * x) == "3.14159265F*q[0]"
    # no M_LN2 / M_SQRT2: not C99, and double constants
    assert pr.doprint(sm.log(2) * x) == "q[0]*logf(2)"
    assert "M_" not in pr.doprint(sm.log(x, 2) + sm.log(10) * x)
    pd = ModelCPrinter({x: "q[0]"}, "double")
    assert re.fullmatch(r"sin\(q\[0\]\) \+ 9\.81\d*", pd.doprint(sm.sin(x) + sm.Float("9.81")))


@pytest.fixture(scope="module")
def cart4():
    import n_link_cart
    return n_link_cart.model(4)


@pytest.mark.parametrize("key", ["kane", "lagrange", "cart4"])
def test_float_sources_compile_clean(key, kane_model, lagrange_model, cart4, tmp_path):
    """Every generated C file (model, runtime and main.c) compiles clean as
    float with -Wdouble-promotion -Wfloat-conversion (GCC also
    -Wunsuffixed-float-constants, clang -Wimplicit-float-conversion), and
    only the float libm functions are called."""
    model = {"kane": kane_model, "lagrange": lagrange_model, "cart4": cart4}[key]
    out = tmp_path / "src"
    gen.generate(model, out, real="float")
    p = model.name
    assert f"typedef float {p}_real;" in (out / f"{p}.h").read_text()
    assert "#define GEN_RT_REAL_FLOAT" in (out / "gen_rt_config.h").read_text()
    model_c = (out / f"{p}_kernels.c").read_text()
    if key == "cart4":
        assert "sinf(" in model_c and "cosf(" in model_c
    for f in [*model_sources(p), *sorted(x.name for x in out.glob("gen_rt_*.c"))]:
        text = re.sub(r"/\*.*?\*/", "", (out / f).read_text(), flags=re.S)
        assert not DOUBLE_CALL.search(text), (f, DOUBLE_CALL.search(text).group(0))
    sources = [str(s) for s in sorted(out.glob("*.c"))]
    compilers = [("gcc", ["-Wunsuffixed-float-constants"])]
    if shutil.which("clang"):
        compilers.append(("clang", ["-Wimplicit-float-conversion"]))
    for cc, extra in compilers:
        require_tool(cc)
        for s in sources:
            cmd = [cc, *FLOAT_FLAGS, *extra, "-fsyntax-only", "-I", str(out), s]
            r = subprocess.run(cmd, capture_output=True, text=True)
            assert r.returncode == 0 and not r.stderr.strip(), " ".join(cmd) + "\n" + r.stderr


@pytest.fixture(scope="module")
def float_sims(kane_model, lagrange_model):
    return {"kane": gen.compile(kane_model, real="float"),
            "lagrange": gen.compile(lagrange_model, real="float")}


@pytest.mark.parametrize("key", ["kane", "lagrange"])
def test_float_agrees_with_double(key, float_sims, kane_sim, lagrange_sim):
    sf = float_sims[key]
    sd = {"kane": kane_sim, "lagrange": lagrange_sim}[key]
    assert sf.real == "float" and sd.real == "double"
    rng = np.random.default_rng(6)
    e_rhs = e_lin = 0.0
    for _ in range(25):
        # |theta| <= 1.2 rad keeps the Kane partition (q1 = L cos theta) regular
        x = pendulum_state(rng.uniform(-1.2, 1.2), rng.uniform(-3, 3), 1.0, key)
        x = x.astype(np.float32).astype(float)    # the same input for both
        fd, ff = sd.rhs(0.0, x), sf.rhs(0.0, x)
        assert ff.dtype == np.float32
        e_rhs = max(e_rhs, rel(ff, fd))
        Ad, _ = sd.linearize(x)
        Af, _ = sf.linearize(x)
        e_lin = max(e_lin, rel(Af, Ad))
    print(f"{key}: float vs double, max norm-relative error over 25 states: "
          f"rhs {e_rhs:.2e}, linearize A {e_lin:.2e}")
    assert e_rhs < 1e-5
    assert e_lin < 1e-5


@pytest.mark.parametrize("key", ["kane", "lagrange"])
def test_float_rk4_10s_tracks_double(key, float_sims, kane_sim, lagrange_sim):
    """0.5 rad amplitude (about 1.6 periods of 2 s in 10 s), dt = 0.01 s,
    projection after every step: the float trajectory stays within 1e-4 of
    the double one, relative to the amplitude of x."""
    sf = float_sims[key]
    sd = {"kane": kane_sim, "lagrange": lagrange_sim}[key]
    x0 = pendulum_state(0.5, 0.0, 1.0, key).astype(np.float32).astype(float)
    td, Xd = sd.simulate(x0, 10.0, 0.01, method="rk4")
    tf, Xf = sf.simulate(x0, 10.0, 0.01, method="rk4")
    assert Xf.dtype == np.float32 and Xf.shape == Xd.shape
    np.testing.assert_allclose(tf, td, rtol=1e-6)
    err = float(np.max(np.abs(Xf - Xd)) / np.max(np.abs(Xd)))
    print(f"{key}: 10 s RK4, float vs double: max |dx| / max |x| = {err:.2e}")
    assert err < 1e-4


@pytest.mark.slow
def test_cli_float_build_and_binary(kane_sim, tmp_path):
    """--real float through the command line: generate, build the binary
    with CMake, and its linearization agrees with the double simulator."""
    require_tool("cmake")
    from gen.cli import main
    model_file = str(ROOT / "examples" / "seed_pendulum.py")
    out = tmp_path / "pf"
    assert main(["build", model_file, "-o", str(out), "--real", "float"]) == 0
    assert "typedef float pendulum_kane_real;" in (out / "pendulum_kane.h").read_text()
    assert (out / "arm-none-eabi.cmake").is_file()
    exe = out / "build" / "pendulum_kane_sim"
    r = subprocess.run([str(exe), "--linearize", "--x0", "q2=0.5", "--x0", "q1=0.8"],
                       capture_output=True, text=True, check=True)
    state = dict(kv.split("=") for kv in r.stdout.splitlines()[0].split()[1:])
    x = np.array([float(state[n]) for n in kane_sim.state_names])
    rows = [ln.split()[1:] for ln in r.stdout.splitlines() if ln.startswith("  ")]
    A = np.array([[float(v) for v in row] for row in rows[:2]])
    Ad, _ = kane_sim.linearize(x)
    assert rel(A, Ad) < 1e-5
    # a value float cannot hold is a usage error, not a silent infinity
    r = subprocess.run([str(exe), "--x0", "q2=1e39"], capture_output=True, text=True)
    assert r.returncode == 2 and "not a finite number" in r.stderr
    r = subprocess.run([str(exe), "--t-end", "1", "--x0", "q2=0.5", "--x0", "q1=0.8"],
                       capture_output=True, text=True, check=True)
    assert len(r.stdout.splitlines()) == 102
