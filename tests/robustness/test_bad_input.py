"""Issue 8: the catalogue of bad input. Each case names the input and the
error it must produce; for the generator cases the output directory must
hold exactly what it held before."""
import hashlib
import os

import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen
import seed_pendulum as sp
from gen.codegen import render


def _snapshot(folder):
    out = {}
    for root, _, files in os.walk(folder):
        for f in files:
            p = os.path.join(root, f)
            out[os.path.relpath(p, folder)] = hashlib.sha256(open(p, "rb").read()).hexdigest()
    return out


def _particle(loads_extra=0, kde_extra=0, name="cat"):
    """A 1-dof particle on a line: x'' = (F + loads_extra) / m."""
    x, u, F = me.dynamicsymbols("x u F")
    m, k = sm.symbols("m k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x)
    P.set_vel(N, u * N.x)
    KM = me.KanesMethod(N, q_ind=[x], u_ind=[u], kd_eqs=[x.diff() - u + kde_extra])
    KM.kanes_equations([me.Particle("pa", P, m)], [(P, (F - k * x + loads_extra) * N.x)])
    return KM, dict(x=x, u=u, F=F, m=m, k=k)


def _kane(**kw):
    KM, s = sp.derive_kane()
    args = dict(constants={s["L"]: 1.0, s["m"]: 1.0, s["g"]: 9.81}, name="cat")
    args.update(kw)
    return gen.Model.from_kanes(KM, **args), s


# ------------------------------------------------------------- the model
CASES = [
    # (case, builder, error class, message pattern)
    ("undeclared constant", lambda: _kane(constants={sp.derive_kane()[1]["L"]: 1.0,
                                                     sp.derive_kane()[1]["m"]: 1.0}),
     gen.ModelError, r"symbol\(s\) g .*constants="),
    ("time function not declared as input",
     lambda: gen.Model.from_kanes(_particle()[0], constants={_particle()[1]["m"]: 1.0,
                                                             _particle()[1]["k"]: 1.0}),
     gen.ModelError, r"forcing contain F\(t\), a function of time .* inputs="),
    ("input given twice",
     lambda: (lambda KM, s: gen.Model.from_kanes(KM, constants={s["m"]: 1, s["k"]: 1},
                                                 inputs=[s["F"], s["F"]]))(*_particle()),
     gen.ModelError, r"input F\(t\) is given twice"),
    ("constant also an input",
     lambda: (lambda KM, s: gen.Model.from_kanes(KM, constants={s["m"]: 1, s["k"]: 1},
                                                 inputs=[s["F"], s["k"]]))(*_particle()),
     gen.ModelError, r"k is declared both as an input and as a constant"),
    ("constant without a numeric value",
     lambda: (lambda KM, s: gen.Model.from_kanes(KM, constants={s["m"]: "heavy", s["k"]: 1},
                                                 inputs=[s["F"]]))(*_particle()),
     gen.ModelError, r"constant m has a value 'heavy' that is not a number"),
    ("a coordinate used as a constant",
     lambda: (lambda KM, s: gen.Model.from_kanes(KM, constants={s["m"]: 1, s["k"]: 1,
                                                                s["x"]: 2.0},
                                                 inputs=[s["F"]]))(*_particle()),
     gen.ModelError, r"must be a sympy Symbol|is a coordinate or speed"),
    ("unprintable function",
     lambda: (lambda KM, s: gen.Model.from_kanes(KM, constants={s["m"]: 1, s["k"]: 1},
                                                 inputs=[s["F"]]))(
         *_particle(loads_extra=sm.besselj(0, me.dynamicsymbols("x")))),
     gen.ModelError, r"besselj.*cannot print"),
    ("leftover derivative",
     lambda: (lambda KM, s: gen.Model.from_kanes(KM, constants={s["m"]: 1, s["k"]: 1},
                                                 inputs=[s["F"]]))(
         *_particle(loads_extra=me.dynamicsymbols("F").diff())),
     gen.ModelError, r"derivative term|function of time"),
    ("partition the constraints do not determine",
     lambda: _lagrange_bad_partition(),
     gen.ModelError, r"more than|do not determine|must together list|must match"),
    ("model name that is a C keyword", lambda: _kane(name="double"),
     gen.ModelError, r"C keyword or C library name"),
    ("model name with a dash", lambda: _kane(name="pend-1"),
     gen.ModelError, r"not a valid C prefix"),
    ("not a KanesMethod", lambda: gen.Model.from_kanes("pendulum"),
     gen.ModelError, r"needs a KanesMethod, got str"),
    ("KanesMethod without equations",
     lambda: gen.Model.from_kanes(me.KanesMethod(me.ReferenceFrame("N"),
                                                 q_ind=[me.dynamicsymbols("a")],
                                                 u_ind=[me.dynamicsymbols("b")],
                                                 kd_eqs=[me.dynamicsymbols("a").diff()
                                                         - me.dynamicsymbols("b")])),
     gen.ModelError, r"call km.kanes_equations"),
]


def _lagrange_bad_partition():
    LM, s = sp.derive_lagrange()
    # q1 listed both as independent and dependent
    return gen.Model.from_lagrange(LM, q_ind=[s["q1"]], qd_ind=[s["q2d"]], q_dep=[s["q1"]],
                                   qd_dep=[s["q1d"]], constants={s["L"]: 1, s["m"]: 1,
                                                                 s["g"]: 9.81})


@pytest.mark.parametrize("case,build,err,pattern", CASES, ids=[c[0] for c in CASES])
def test_bad_model(case, build, err, pattern):
    with pytest.raises(err, match=pattern):
        build()


def test_rank_deficient_partition_named():
    """A dependent coordinate the configuration constraint does not involve:
    the Jacobian block is singular everywhere, and the error names it."""
    q1, q2, q3 = me.dynamicsymbols("q1 q2 q3")
    q1d, q2d, q3d = me.dynamicsymbols("q1 q2 q3", level=1)
    L, m = sm.symbols("L m")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q1 * N.x + q2 * N.y + q3 * N.z)
    P.set_vel(N, P.pos_from(O).dt(N))
    pa = me.Particle("pa", P, m)
    LM = me.LagrangesMethod(me.Lagrangian(N, pa), [q1, q2, q3],
                            hol_coneqs=[q1**2 + q2**2 - L**2], frame=N)
    LM.form_lagranges_equations()
    with pytest.raises(gen.ModelError, match=r"do not determine the dependent coordinates "
                                             r"\['q3'\]"):
        gen.Model.from_lagrange(LM, q_ind=[q1, q2], qd_ind=[q1d, q2d, q3d][:2], q_dep=[q3],
                                qd_dep=[q3d], constants={L: 1.0, m: 1.0}, name="rank")


# --------------------------------------------------- generation is atomic
def test_failed_render_leaves_output_untouched(tmp_path, monkeypatch, kane_model):
    out = tmp_path / "out"
    gen.generate(kane_model, out)
    (out / "notes.txt").write_text("mine")
    before = _snapshot(out)

    def broken(*a, **k):
        raise RuntimeError("disk on fire")
    monkeypatch.setattr(render, "template_env", broken)
    with pytest.raises(RuntimeError, match="disk on fire"):
        gen.generate(kane_model, out)
    assert _snapshot(out) == before


def test_failed_write_leaves_output_untouched(tmp_path, kane_model):
    out = tmp_path / "out"
    gen.generate(kane_model, out)
    before = _snapshot(out)
    files = render.render_files(kane_model)
    files["zz/../../escape.c"] = "int x;"          # cannot be written inside the temp dir
    with pytest.raises(OSError):
        render.write_atomic(files, out)
    assert _snapshot(out) == before
    assert not any(p.name.startswith(".out.tmp") for p in tmp_path.iterdir())


def test_output_path_is_a_file(tmp_path, kane_model):
    target = tmp_path / "file.txt"
    target.write_text("keep")
    with pytest.raises(gen.ModelError, match="not a directory"):
        gen.generate(kane_model, target)
    assert target.read_text() == "keep"


def test_unknown_backend_and_real(tmp_path, kane_model):
    with pytest.raises(gen.ModelError, match="backend"):
        gen.generate(kane_model, tmp_path / "x", backend="fortran")
    with pytest.raises(gen.ModelError, match="real must be"):
        gen.generate(kane_model, tmp_path / "y", real="half")
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


# ------------------------------------------------------------ the Python API
def test_python_api_bad_arrays(kane_sim):
    with pytest.raises(ValueError, match=r"state x must have shape \(4,\)"):
        kane_sim.rhs(0.0, np.zeros(3))
    with pytest.raises(ValueError, match=r"states must have shape \(N, 4\), got \(2, 2\)"):
        kane_sim.rhs(0.0, np.zeros((2, 2)))
    with pytest.raises(ValueError, match=r"constants p must have shape \(3,\)"):
        kane_sim.rhs(0.0, np.zeros(4), p=[1.0])
    with pytest.raises(ValueError, match="unknown name 'q9'"):
        kane_sim.consistent_state({"q9": 1.0})
    with pytest.raises(ValueError, match="NaN or infinite"):
        kane_sim.rhs(0.0, np.array([0.0, 1.0, np.nan, 0.0]))
    with pytest.raises(ValueError, match="NaN or infinite"):
        kane_sim.linearize(np.array([0.0, np.inf, 0.0, 0.0]))
    with pytest.raises(ValueError, match="method must be one of"):
        kane_sim.simulate(np.array([0.0, 1.0, 0.0, 0.0]), 1.0, 0.1, method="euler")
    with pytest.raises(ValueError, match="dt must be a positive number"):
        kane_sim.simulate(np.array([0.0, 1.0, 0.0, 0.0]), 1.0, -0.1)
    with pytest.raises(ValueError, match="could not convert|must have shape"):
        kane_sim.rhs(0.0, ["a", "b", "c", "d"])


def test_solver_error_carries_status_time_state(kane_sim):
    # the seed's Kane model (atan(q2/q1)) has no finite value where q1 = 0
    with pytest.raises(gen.SingularError) as e:
        kane_sim.rhs(0.5, np.array([1.0, 0.0, 0.0, 0.0]))
    err = e.value
    assert err.status == -8 and err.status_name == "ERR_NONFINITE_MODEL" and err.time == 0.5
    assert list(err.state) == [1.0, 0.0, 0.0, 0.0]
    assert "q2=1" in str(err) and "t = 0.5" in str(err)


# ------------------------------------------------------------ the binary
@pytest.fixture(scope="module")
def binary(kane_binary):
    """The seed Kane pendulum's standalone simulator (conftest.py)."""
    return kane_binary


BINARY_CASES = [
    (["--x0", "q2=nan"], 2, "not a finite number: q2=nan"),
    (["--x0", "q2=1e400"], 2, "not a finite number"),
    (["--x0", "theta=1"], 2, "unknown"),
    (["--param", "mass=1"], 2, "unknown constant name"),
    (["--dt", "-1"], 2, "--dt needs a positive number"),
    (["--t-end", "soon"], 2, "--t-end needs a number"),
    (["--method", "euler"], 2, "--method must be rk4, dopri5 or rodas4"),
    (["--frobnicate"], 2, "frobnicate"),
]


@pytest.mark.slow
@pytest.mark.parametrize("args,code,needle", BINARY_CASES, ids=[c[2] for c in BINARY_CASES])
def test_binary_bad_arguments(binary, args, code, needle):
    import subprocess
    r = subprocess.run([str(binary), *args], capture_output=True, text=True)
    assert r.returncode == code and needle in r.stderr, (r.returncode, r.stderr)
    assert r.stdout == ""                          # no CSV at all


def test_binary_failed_step_says_the_csv_is_truncated(binary, tmp_path):
    import subprocess
    out = tmp_path / "run.csv"
    r = subprocess.run([str(binary), "--t-end", "2", "--x0", "q2=0.5", "--x0", "q1=0.8",
                        "--method", "dopri5", "--rtol", "1e-30", "--atol", "1e-30",
                        "--output", str(out)], capture_output=True, text=True)
    assert r.returncode == 1
    assert "step failed at t=" in r.stderr and "CSV truncated after 1 rows" in r.stderr
    assert "last good state: q2=0.5" in r.stderr
    assert len(out.read_text().splitlines()) == 2   # header + the one good row


def test_compile_failure_raises_build_error_with_the_log(kane_model):
    from gen.toolchain.build import build
    from gen.plan.ir import plan
    rendered = render.render(plan(kane_model))
    name = f"{kane_model.name}.c"
    files = rendered.files
    files[name] = files[name].replace("return gen_rt_model_", "return +gen_rt_model_ +", 1)
    with pytest.raises(gen.BuildError) as e:
        build(rendered)
    assert "compiling the model 'pendulum_kane' failed" in str(e.value)
    assert "error" in e.value.log and name in e.value.log
    assert f"$ {gen.codegen.backends.c_compiler()} " in e.value.log       # the compiler's command line
