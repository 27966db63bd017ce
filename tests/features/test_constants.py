"""Issue 14 (constants): values that are not finite real numbers are refused
with a ModelError naming the constant as the user spelt it and the value,
before anything is generated; a constant that no expression of the model
uses gives an UnusedConstantWarning naming it."""
import math
import warnings

import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen
import gen.toolchain.build
import gen.pipeline
import gen.plan.ir
import gen.codegen.render
from gen.core.errors import UnusedConstantWarning

FINITE = "; constants must be finite real numbers"


def _oscillator():
    """A mass on a spring and damper driven by F (Kane), and the symbols.
    The stiffness is spelt 'k_θ'' to check the message keeps the spelling."""
    q, u, F = me.dynamicsymbols("q u F")
    m, k, c = sm.symbols("m k_θ' c")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, u * N.x)
    km = me.KanesMethod(N, q_ind=[q], u_ind=[u], kd_eqs=[q.diff() - u])
    km.kanes_equations([me.Particle("p", P, m)], [(P, (F - k * q - c * u) * N.x)])
    return km, dict(q=q, u=u, F=F, m=m, k=k, c=c)


def _good(s):
    return {s["m"]: 1.0, s["k"]: 4.0, s["c"]: 0.1}


def _lagrange():
    q = me.dynamicsymbols("q")
    m, k = sm.symbols("m k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, q.diff() * N.x)
    pa = me.Particle("p", P, m)
    pa.potential_energy = k * q ** 2 / 2
    lm = me.LagrangesMethod(me.Lagrangian(N, pa), [q], frame=N)
    lm.form_lagranges_equations()
    return lm, dict(q=q, m=m, k=k)


a_sym = sm.Symbol("a")

# (id, value, the exact message for the stiffness k_θ')
BAD = [
    ("float nan", float("nan"), f"constant k_θ' has a value nan that is NaN{FINITE}"),
    ("numpy nan", np.float64("nan"), f"constant k_θ' has a value nan that is NaN{FINITE}"),
    ("numpy nan 0-d array", np.array(np.nan), f"constant k_θ' has a value nan that is NaN{FINITE}"),
    ("sympy nan", sm.nan, f"constant k_θ' has a value nan that is NaN{FINITE}"),
    ("float inf", float("inf"), f"constant k_θ' has a value inf that is infinite{FINITE}"),
    ("float -inf", -math.inf, f"constant k_θ' has a value -inf that is infinite{FINITE}"),
    ("numpy inf", np.inf, f"constant k_θ' has a value inf that is infinite{FINITE}"),
    ("float overflow", 1e308 * 10, f"constant k_θ' has a value inf that is infinite{FINITE}"),
    ("sympy oo", sm.oo, f"constant k_θ' has a value oo that is infinite{FINITE}"),
    ("sympy -oo", -sm.oo, f"constant k_θ' has a value -oo that is infinite{FINITE}"),
    ("sympy zoo", sm.S(1) / 0, f"constant k_θ' has a value zoo that is infinite{FINITE}"),
    ("complex", 4 + 1j, f"constant k_θ' has a value (4+1j) that is complex{FINITE}"),
    ("complex, zero imaginary part", complex(4, 0),
     f"constant k_θ' has a value (4+0j) that is complex{FINITE}"),
    ("numpy complex", np.complex128(4 + 2j),
     f"constant k_θ' has a value (4+2j) that is complex{FINITE}"),
    ("sympy I", 4 * sm.I, f"constant k_θ' has a value 4*I that is complex{FINITE}"),
    ("sympy complex expression", sm.sqrt(-2) + 1,
     f"constant k_θ' has a value 1 + sqrt(2)*I that is complex{FINITE}"),
    ("sympy symbol", a_sym,
     "constant k_θ' has a value a that is a sympy expression in a, not a number; give its "
     "numeric value"),
    ("sympy expression", 2 * a_sym + sm.Symbol("b"),
     "constant k_θ' has a value 2*a + b that is a sympy expression in a, b, not a number; "
     "give its numeric value"),
    ("string", "4.0", "constant k_θ' has a value '4.0' that is not a number"),
    ("None", None, "constant k_θ' has a value None that is not a number"),
    ("list", [4.0, 5.0], "constant k_θ' has a value [4.0, 5.0] that is not a number"),
    ("sympy matrix", sm.Matrix([4]), "constant k_θ' has a value Matrix([[4]]) that is not a "
                                      "number"),
]


@pytest.mark.parametrize("value,message", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_refused_with_exact_message(value, message):
    km, s = _oscillator()
    with pytest.raises(gen.ModelError) as e:
        gen.Model.from_kanes(km, constants={s["m"]: 1.0, s["k"]: value, s["c"]: 0.1},
                             inputs=[s["F"]], name="osc")
    assert str(e.value) == message


@pytest.mark.parametrize("value", [4, 4.0, np.float32(4.0), np.int64(4), sm.Integer(4),
                                   sm.Rational(8, 2), sm.Float("4.0"), np.array(4.0),
                                   sm.sqrt(16), 4 + 0 * sm.I, sm.exp(sm.log(4))])
def test_real_values_of_every_kind_accepted(value):
    km, s = _oscillator()
    m = gen.Model.from_kanes(km, constants={s["m"]: 1.0, s["k"]: value, s["c"]: 0.1},
                             inputs=[s["F"]], name="osc")
    assert m.p_values[1] == 4.0 and type(m.p_values[1]) is float


def test_lagrange_refuses_too():
    lm, s = _lagrange()
    with pytest.raises(gen.ModelError) as e:
        gen.Model.from_lagrange(lm, constants={s["m"]: float("nan"), s["k"]: 1.0})
    assert str(e.value) == f"constant m has a value nan that is NaN{FINITE}"


def test_first_bad_constant_in_the_users_order_is_named():
    km, s = _oscillator()
    with pytest.raises(gen.ModelError, match=r"^constant c has a value inf"):
        gen.Model.from_kanes(km, constants={s["c"]: math.inf, s["m"]: math.nan, s["k"]: 1},
                             inputs=[s["F"]])


def test_nan_constant_never_reaches_the_compiler(monkeypatch, tmp_path, capsys):
    """No plan, no rendering, no compiler process for a model with a NaN
    constant: neither through the Python API nor through the command line."""
    def forbidden(*a, **k):
        raise AssertionError("the generator or compiler was reached")
    monkeypatch.setattr(gen.toolchain.build.subprocess, "run", forbidden)
    monkeypatch.setattr(gen.pipeline, "build", forbidden)
    monkeypatch.setattr(gen.pipeline, "make_plan", forbidden)
    monkeypatch.setattr(gen.codegen.render, "make_plan", forbidden)
    monkeypatch.setattr(gen.plan.ir, "plan", forbidden)
    km, s = _oscillator()
    with pytest.raises(gen.ModelError, match=r"constant m has a value nan that is NaN"):
        sim = gen.compile(gen.Model.from_kanes(
            km, constants={s["m"]: float("nan"), s["k"]: 4.0, s["c"]: 0.1},
            inputs=[s["F"]], name="osc_nan"))
        del sim
    # the command line: exit code 1, the message, no compiler
    f = tmp_path / "nan_model.py"
    f.write_text(
        "import sympy as sm\n"
        "from sympy.physics import mechanics as me\n"
        "import gen\n"
        "def model():\n"
        "    q, u = me.dynamicsymbols('q u')\n"
        "    m, k = sm.symbols('m k')\n"
        "    N = me.ReferenceFrame('N'); O = me.Point('O'); O.set_vel(N, 0)\n"
        "    P = O.locatenew('P', q * N.x); P.set_vel(N, u * N.x)\n"
        "    km = me.KanesMethod(N, q_ind=[q], u_ind=[u], kd_eqs=[q.diff() - u])\n"
        "    km.kanes_equations([me.Particle('p', P, m)], [(P, -k * q * N.x)])\n"
        "    return gen.Model.from_kanes(km, constants={m: float('nan'), k: 1.0},\n"
        "                                name='nan_cli')\n")
    from gen.cli import main
    rc = main(["build", str(f), "-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 1, err
    assert f"constant m has a value nan that is NaN{FINITE}" in err
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------ unused constants
def test_unused_constant_warns_with_its_name():
    km, s = _oscillator()
    extra = sm.Symbol("L_arm")
    with pytest.warns(UnusedConstantWarning) as rec:
        m = gen.Model.from_kanes(km, constants={**_good(s), extra: 2.0}, inputs=[s["F"]],
                                 name="osc")
    msgs = [str(w.message) for w in rec if issubclass(w.category, UnusedConstantWarning)]
    assert msgs == [
        "model 'osc': constant L_arm appears in no expression of the model (mass matrix, "
        "forcing, kinematic equations, constraints, energy); kept as parameter(s) without "
        "effect"]
    # kept: the parameter vector still has it, in the user's order
    assert m.constant_labels == ["m", "k_θ'", "c", "L_arm"] and m.p_values[-1] == 2.0
    assert issubclass(UnusedConstantWarning, UserWarning)
    # the warning points at the caller's line, not into eomgen
    assert rec[0].filename == __file__


def test_several_unused_constants_in_one_warning():
    lm, s = _lagrange()
    a, b = sm.symbols("a b")
    with pytest.warns(UnusedConstantWarning) as rec:
        gen.Model.from_lagrange(lm, constants={s["m"]: 1.0, a: 1.0, s["k"]: 2.0, b: 3.0})
    assert [str(w.message) for w in rec] == [
        "model 'model': constants a, b appear in no expression of the model (mass matrix, "
        "forcing, kinematic equations, constraints, energy); kept as parameter(s) without "
        "effect"]


def test_constant_used_only_in_energy_or_constraints_is_used():
    km, s = _oscillator()
    E0 = sm.Symbol("E0")
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnusedConstantWarning)
        gen.Model.from_kanes(km, constants={**_good(s), E0: 1.0}, inputs=[s["F"]],
                             energy=s["m"] * s["u"] ** 2 / 2 + s["k"] * s["q"] ** 2 / 2 + E0)


def test_no_warning_when_every_constant_is_used():
    km, s = _oscillator()
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnusedConstantWarning)
        gen.Model.from_kanes(km, constants=_good(s), inputs=[s["F"]], name="osc")
