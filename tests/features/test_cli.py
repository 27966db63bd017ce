"""Issue 9: the command line, driven as a subprocess on the seed models;
and the command-line tour of the docs (docs/guides/cli.md), run exactly as written."""
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gen
from conftest import require_tool

ROOT = Path(__file__).resolve().parents[2]
SEED = str(ROOT / "examples" / "seed_pendulum.py")


def eomgen(*args, cwd=None, check_rc=None):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run([sys.executable, "-m", "gen", *args], capture_output=True, text=True,
                          cwd=cwd, env=env)
    if check_rc is not None:
        assert proc.returncode == check_rc, (args, proc.returncode, proc.stdout, proc.stderr)
    return proc


def _matrix(text, label):
    """Rows of a labelled matrix printed by `eomgen linearize`."""
    lines = text.splitlines()
    i = lines.index(label)
    rows = []
    for ln in lines[i + 2:]:
        parts = ln.split()
        if len(parts) < 2 or not re.match(r"^-?[\d.]", parts[1]):
            break
        rows.append([float(v) for v in parts[1:]])
    return np.array(rows)


def test_generate_writes_the_project(tmp_path):
    out = tmp_path / "pend"
    p = eomgen("generate", SEED, "-o", str(out), check_rc=0)
    assert "wrote" in p.stdout
    names = {f.name for f in out.iterdir()}
    assert {"pendulum_kane.h", "pendulum_kane.c", "main.c", "CMakeLists.txt",
            "gen_rt.h"} <= names
    p = eomgen("generate", SEED + ":lagrange_model", "-o", str(tmp_path / "pf"), "--real",
               "float", "--name", "pl", check_rc=0)
    assert "typedef float pl_real;" in (tmp_path / "pf" / "pl.h").read_text()


@pytest.mark.slow
def test_build_prints_a_working_binary(tmp_path):
    require_tool("cmake")
    p = eomgen("build", SEED, "-o", str(tmp_path / "pend"), check_rc=0)
    exe = Path(p.stdout.strip().splitlines()[-1])
    assert exe.is_file()
    r = subprocess.run([str(exe), "--t-end", "0.1", "--x0", "q2=0.5", "--x0", "q1=0.8"],
                       capture_output=True, text=True, check=True)
    assert r.stdout.splitlines()[0].startswith("t,q2,q1,u2,u1")


def test_linearize_prints_labelled_A_and_eigenvalues():
    p = eomgen("linearize", SEED, "--at", "q1=1", check_rc=0)
    A = _matrix(p.stdout, "A =")
    assert np.allclose(A, [[0, 1], [-9.81, 0]], atol=1e-12)
    assert "q2" in p.stdout.splitlines()[2] and "u2" in p.stdout.splitlines()[2]
    assert re.search(r"eigenvalues of A: .*-3\.13209195j", p.stdout)
    p = eomgen("linearize", SEED + ":lagrange_model", "--at", "q1=-1", "--param", "g=4",
               check_rc=0)
    assert np.allclose(_matrix(p.stdout, "A ="), [[0, 1], [4, 0]], atol=1e-12)
    assert "B = (no inputs)" in p.stdout


@pytest.mark.slow
def test_simulate_csv_and_plot(tmp_path):
    csv = tmp_path / "run.csv"
    png = tmp_path / "plots" / "run.png"
    eomgen("simulate", SEED, "--t-end", "2", "--dt", "0.01", "--x0", "q2=0.5", "--x0",
           "q1=0.8", "--method", "dopri5", "--csv", str(csv), "--plot", str(png), check_rc=0)
    header = csv.read_text().splitlines()[0].split(",")
    assert header == ["t", "q2", "q1", "u2", "u1", "lam0", "fc0", "fv0", "energy"]
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert data.shape == (201, 9)
    assert np.allclose(data[:, 1] ** 2 + data[:, 2] ** 2, 1.0, atol=1e-9)   # on the circle
    E = data[:, -1]
    assert np.max(np.abs(E - E[0])) < 1e-6 * abs(E[0])
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10000


@pytest.mark.slow
def test_verify_passes_then_catches_tampering(tmp_path):
    p = eomgen("verify", SEED, "--samples", "5", check_rc=0)
    assert "all functions agree" in p.stdout and "eval_rhs" in p.stdout
    out = tmp_path / "pend"
    eomgen("generate", SEED, "-o", str(out), check_rc=0)
    src = out / "pendulum_kane_kernels.c"
    src.write_text(src.read_text().replace("sqrt(", "fabs(", 1))
    p = eomgen("verify", SEED, "--samples", "5", "--sources", str(out), check_rc=1)
    assert "MISMATCH" in p.stdout and "FAIL" in p.stdout


def _slow(*case):
    return pytest.param(*case, marks=pytest.mark.slow)


# fast tier: a missing file and an unknown name; every other refusal takes the same
# one-line exit-2 path (parse errors as 'half' and 'soon') and runs in the slow tier
@pytest.mark.parametrize("args,needle", [
    (["simulate", "missing.py", "--t-end", "1"], "model file not found"),
    _slow(["simulate", "NOMODEL", "--t-end", "1"], "defines no function model()"),
    (["simulate", SEED, "--t-end", "1", "--x0", "theta=1"], "unknown state name 'theta'"),
    _slow(["simulate", SEED, "--t-end", "1", "--param", "mass=2"], "unknown constant name 'mass'"),
    _slow(["simulate", SEED, "--t-end", "1", "--x0", "q2=half"], "'half' is not a number"),
    _slow(["simulate", SEED, "--t-end", "soon"], "invalid float value"),
    _slow(["generate", SEED, "-o", "x", "--backend", "fortran"], "invalid choice: 'fortran'"),
    _slow(["linearize", SEED, "--at", "q2"], "must be NAME=VALUE"),
    _slow(["frobnicate"], "invalid choice"),
    _slow(["simulate", SEED, "--t-end", "1", "--x0", "q2=0.5", "--x0", "q1=0.8", "--rtol", "-1"],
          "--rtol: rtol must be a positive number, got rtol = -1.0"),
    _slow(["ensemble", SEED, "--samples", "2", "--t-end", "1", "-o", "r.npz", "--max-steps",
           "0"], "--max-steps: max_steps must be an integer >= 1"),
])
def test_bad_arguments_one_line_exit_2(tmp_path, args, needle):
    nomodel = tmp_path / "nomodel.py"
    nomodel.write_text("x = 1\n")
    args = [str(nomodel) if a == "NOMODEL" else a for a in args]
    p = eomgen(*args, cwd=tmp_path, check_rc=2)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1, p.stderr
    assert needle in lines[0] and lines[0].startswith("eomgen")
    assert "Traceback" not in p.stderr


@pytest.mark.slow
def test_failures_exit_1_without_traceback(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import seed_pendulum as sp\n"
                   "def model():\n"
                   "    KM, s = sp.derive_kane()\n"
                   "    import gen\n"
                   "    return gen.Model.from_kanes(KM, constants={s['L']: 1.0}, name='bad')\n")
    env_path = str(ROOT / "examples")
    p = subprocess.run([sys.executable, "-m", "gen", "generate", str(bad), "-o",
                        str(tmp_path / "o")], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{env_path}"})
    assert p.returncode == 1
    assert "neither coordinates" in p.stderr and "Traceback" not in p.stderr
    assert not (tmp_path / "o").exists()
    p = subprocess.run([sys.executable, "-m", "gen", "--debug", "generate", str(bad), "-o",
                        str(tmp_path / "o")], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{env_path}"})
    assert p.returncode != 0 and "Traceback" in p.stderr


@pytest.mark.slow
def test_help_has_examples():
    p = eomgen("--help", check_rc=0)
    assert "examples:" in p.stdout and "eomgen verify" in p.stdout
    for cmd in ("generate", "build", "simulate", "linearize", "verify", "report"):
        p = eomgen(cmd, "--help", check_rc=0)
        assert "example:" in p.stdout and f"eomgen {cmd}" in p.stdout


@pytest.mark.slow
def test_progress_quiet_off_a_terminal_and_verbose_timings():
    p = eomgen("linearize", SEED, "--at", "q1=1", check_rc=0)
    assert p.stderr == ""                          # not a terminal: no progress
    p = eomgen("linearize", SEED, "--at", "q1=1", "--verbose", check_rc=0)
    for stage in ("derive the model", "kernels, printing, templates", "compile", "total"):
        assert stage in p.stderr


# ------------------------------------------------ the command-line tour (docs)
def _tour_commands():
    text = (ROOT / "docs" / "guides" / "cli.md").read_text()
    block = text.split("<!-- tour:begin -->", 1)[1].split("<!-- tour:end -->", 1)[0]
    cmds = [ln.strip() for ln in block.splitlines() if ln.strip().startswith("eomgen ")]
    assert len(cmds) >= 6
    return cmds


@pytest.mark.slow
def test_readme_tour_runs_as_written(tmp_path):
    require_tool("cmake")
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    for cmd in _tour_commands():
        args = cmd.split()[1:]
        expect = 1 if "# fails" in cmd else 0
        args = args[:args.index("#")] if "#" in args else args
        p = eomgen(*args, cwd=tmp_path, check_rc=expect)
        if args[0] == "linearize" and "--at" in args and "q1=1" in args:
            assert np.allclose(_matrix(p.stdout, "A ="), [[0, 1], [-9.81, 0]], atol=1e-12)
    pngs = list(tmp_path.rglob("*.png"))
    assert pngs, "the tour writes a plot"
    committed = ROOT / "docs" / pngs[0].name
    assert committed.is_file(), f"the tour's plot {committed} is committed"


PIN_MODEL = '''
import sympy as sm
from sympy.physics import mechanics as me
import gen


def model():
    t = me.dynamicsymbols._t
    th, w, ua1, ua2, R1, R2 = me.dynamicsymbols('theta omega ua1 ua2 R1 R2')
    m, g, L = sm.symbols('m g L')
    N = me.ReferenceFrame('N')
    A = N.orientnew('A', 'Axis', [th, N.z])
    A.set_ang_vel(N, w * N.z)
    O = me.Point('O')
    O.set_vel(N, ua1 * A.x + ua2 * A.y)
    P = O.locatenew('P', L * A.x)
    P.v2pt_theory(O, N, A)
    km = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w],
                        u_auxiliary=[ua1, ua2])
    km.kanes_equations([me.Particle('bob', P, m)], [(P, m * g * N.x), (O, R1 * A.x + R2 * A.y)])
    return gen.Model.from_kanes(km, constants={m: 1.3, g: 9.81, L: 0.8}, name="pin")
'''


@pytest.mark.slow
def test_simulate_csv_has_the_reaction_forces(tmp_path):
    # the pin force of a pendulum, by hand: R1 = -m (g cos(theta) + L theta'^2), R2 = 0
    f = tmp_path / "pin_model.py"
    f.write_text(PIN_MODEL)
    out = tmp_path / "run.csv"
    eomgen("simulate", str(f), "--t-end", "0.5", "--dt", "0.01", "--x0", "theta=0.5",
           "--x0", "omega=1.5", "--csv", str(out), check_rc=0)
    lines = out.read_text().splitlines()
    assert lines[0].split(",") == ["t", "theta", "omega", "R1", "R2"]
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    radial = -1.3 * (9.81 * np.cos(data[:, 1]) + 0.8 * data[:, 2] ** 2)
    assert np.max(np.abs(data[:, 3] - radial)) < 1e-12 * np.max(np.abs(radial))
    assert np.max(np.abs(data[:, 4])) < 1e-12 * np.max(np.abs(radial))
    # on stdout too
    p = eomgen("simulate", str(f), "--t-end", "0.02", "--dt", "0.01", "--x0", "theta=0.5",
               check_rc=0)
    assert p.stdout.splitlines()[0] == "t,theta,omega,R1,R2"


# ------------------------------------------------ the run flags (issue 42)
def _help_entries(text):
    """{flag: its help text, wrapped lines joined} of an argparse --help."""
    out, flag = {}, None
    for line in text.splitlines():
        m = re.match(r"^  (--[a-z0-9-]+)(.*)$", line)
        if m:
            flag = m.group(1)
            out[flag] = m.group(2)
        elif flag and line.startswith("      "):
            out[flag] += " " + line.strip()
        else:
            flag = None
    return {k: " ".join(v.split()) for k, v in out.items()}


def _described_defaults():
    """{flag: default as --help should show it}, read from the interface
    description itself (gen/codegen/abi.py), not from gen.RunOptions."""
    from gen.codegen import abi
    f = {fl.name: fl for s in abi.STRUCTS if s.name == "sim_options" for fl in s.fields}
    hold = next(fl for s in abi.STRUCTS if s.name == "input" for fl in s.fields
                if fl.name == "hold")
    method = next(k for k, v in abi.METHODS.items() if v == f["method"].default)
    both = {"--method": method, "--rtol": f["rtol"].default, "--atol": f["atol"].default,
            "--h-init": f["h_init"].default, "--h-min": f["h_min"].default,
            "--h-max": f["h_max"].default, "--max-steps": f["max_steps"].default,
            "--no-project": "on" if f["project"].default else "off",
            # "eps16": 0, which the engine reads as 16 machine epsilons
            "--proj-tol": 0.0 if f["proj_tol"].default == "eps16" else f["proj_tol"].default,
            "--proj-max-iter": f["proj_max_iter"].default}
    only = {"--hold": next(k for k, v in abi.HOLDS.items() if v == hold.default),
            "--every": f["every"].default,
            "--final-only": "on" if f["final_only"].default else "off", "--max-rows": "none"}
    return {"simulate": {**both, **only}, "ensemble": both}


@pytest.mark.parametrize("cmd", ["simulate", "ensemble"])
def test_help_lists_every_run_option_with_the_described_default(cmd):
    from gen.sim.options import OPTIONS
    text = eomgen(cmd, "--help", check_rc=0).stdout
    entries = _help_entries(text)
    expected = _described_defaults()[cmd]
    group = text.split("\nrun options (those of gen.RunOptions):\n", 1)[1].split("\n\n")[0]
    assert set(_help_entries(group)) == set(expected)
    for flag, want in expected.items():
        m = re.search(r"\(default ([^;)]+)", entries[flag])
        assert m, (flag, entries[flag])
        got = m.group(1)
        if isinstance(want, str):
            assert got == want, (flag, got, want)
        else:
            assert float(got) == want, (flag, got, want)
    # the help text is the option's own (gen.sim.options.OPTIONS)
    doc = next(o.doc for o in OPTIONS if o.name == "max_steps").rstrip(".")
    assert doc in entries["--max-steps"]
    assert "{rk4,dopri5,rodas4,rodas}" in entries["--method"]


@pytest.mark.slow
def test_run_flags_give_the_numbers_of_run_options(kane_sim):
    """eomgen simulate with run flags writes the rows gen.RunOptions gives in
    Python, digit for digit (17 significant digits round-trip a double)."""
    args = ["--method", "dopri5", "--rtol", "1e-10", "--atol", "1e-12", "--h-max", "0.05",
            "--every", "7"]
    p = eomgen("simulate", SEED, "--t-end", "2", "--dt", "0.01", "--x0", "q2=0.5", "--x0",
               "q1=0.8", *args, check_rc=0)
    rows = np.array([[float(v) for v in ln.split(",")] for ln in p.stdout.splitlines()[1:]])
    x0 = kane_sim.consistent_state(np.array([0.5, 0.8, 0.0, 0.0]))
    sol = kane_sim.simulate(x0, 2.0, 0.01, options=gen.RunOptions(
        method="dopri5", rtol=1e-10, atol=1e-12, h_max=0.05, every=7))
    assert rows.shape == (len(sol.t), 5) and len(sol.t) == 30
    np.testing.assert_array_equal(rows[:, 0], sol.t)
    np.testing.assert_array_equal(rows[:, 1:], sol.x)
    p = eomgen("simulate", SEED, "--t-end", "2", "--x0", "q2=0.5", "--x0", "q1=0.8",
               "--final-only", "--no-project", check_rc=0)
    rows = np.array([[float(v) for v in ln.split(",")] for ln in p.stdout.splitlines()[1:]])
    sol = kane_sim.simulate(x0, 2.0, 0.01, final_only=True, project=False)
    np.testing.assert_array_equal(rows, np.column_stack([sol.t, sol.x]))
