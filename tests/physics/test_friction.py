"""Issue 32, smaller friction: each of the newcomer's reproductions, now a
clear gen error or a warning that names the culprit."""
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me

import gen

ROOT = Path(__file__).resolve().parents[2]


def spring(force=True, mass=True, extra_input=False):
    """A mass on a spring, pushed by the input T(t)."""
    q, u = me.dynamicsymbols("q u")
    T, F = me.dynamicsymbols("T F")
    m, k = sm.symbols("m k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, u * N.x)
    pa = me.Particle("pa", P, m if mass else 0)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u])
    km.kanes_equations([pa], [(P, (-k * q + (T if force else 0)) * N.x)])
    return km, dict(q=q, u=u, T=T, F=F, m=m, k=k)


# ---------------------------------------------------------------- gen.compile(km)
def test_compile_of_a_kanes_method_says_to_make_a_model_first():
    km, s = spring()
    with pytest.raises(gen.ModelError) as e:
        gen.compile(km)
    msg = str(e.value)
    assert "gen.compile takes a gen.Model, got a sympy KanesMethod" in msg
    assert "gen.Model.from_kanes(km" in msg
    assert "attribute" not in msg


def test_the_other_entries_and_methods_say_the_same(tmp_path):
    km, s = spring()
    with pytest.raises(gen.ModelError, match=r"gen.generate takes a gen.Model.*from_kanes"):
        gen.generate(km, tmp_path / "out")
    assert not (tmp_path / "out").exists()
    with pytest.raises(gen.ModelError, match=r"gen.export_fmu takes a gen.Model.*from_kanes"):
        gen.export_fmu(km, tmp_path / "m.fmu", binary=False)
    with pytest.raises(gen.ModelError, match=r"gen.verify takes a gen.Model"):
        gen.verify(km)
    # a LagrangesMethod and a System: their own constructors
    q = me.dynamicsymbols("q")
    m, g = sm.symbols("m g")
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, q.diff() * N.x)
    pa = me.Particle("pa", P, m)
    pa.potential_energy = m * g * q
    lm = me.LagrangesMethod(me.Lagrangian(N, pa), [q])
    lm.form_lagranges_equations()
    with pytest.raises(gen.ModelError, match=r"sympy LagrangesMethod.*gen.Model.from_lagrange"):
        gen.compile(lm)
    system = me.System(N, me.Point("O"))
    with pytest.raises(gen.ModelError, match=r"sympy System.*gen.Model.from_system"):
        gen.compile(system)
    with pytest.raises(gen.ModelError, match=r"takes a gen.Model .*got str"):
        gen.compile("pendulum.py")


# ------------------------------------------------ inputs=[Symbol("T")] for T(t)
def test_a_plain_symbol_for_a_dynamicsymbol_input_is_named():
    km, s = spring()
    with pytest.raises(gen.ModelError) as e:
        gen.Model.from_kanes(km, constants={s["m"]: 1, s["k"]: 2}, inputs=[sm.Symbol("T")])
    msg = str(e.value)
    assert "the model uses T(t)" in msg and "T, a plain Symbol" in msg
    assert "dynamicsymbols('T')" in msg
    # the right declaration works
    gen.Model.from_kanes(km, constants={s["m"]: 1, s["k"]: 2}, inputs=[s["T"]])


def test_a_dynamicsymbol_for_a_plain_symbol_input_is_named():
    """The other way round: the model pushes with the constant-looking T,
    inputs=[...] gives T(t)."""
    q, u = me.dynamicsymbols("q u")
    T, m = sm.symbols("T m")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, u * N.x)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u])
    km.kanes_equations([me.Particle("pa", P, m)], [(P, T * N.x)])
    with pytest.raises(gen.ModelError, match=r"contain T, a plain Symbol, but inputs=\[...\] "
                                             r"gives T\(t\), a function of time"):
        gen.Model.from_kanes(km, constants={m: 1}, inputs=[me.dynamicsymbols("T")])


def test_an_undeclared_function_of_time_keeps_its_message():
    km, s = spring()
    with pytest.raises(gen.ModelError, match=r"contain T\(t\), a function of time that is not"):
        gen.Model.from_kanes(km, constants={s["m"]: 1, s["k"]: 2}, inputs=[sm.Symbol("X")])


# ------------------------------------------------------------- unused inputs
def test_unused_inputs_warn_like_unused_constants():
    assert issubclass(gen.UnusedInputWarning, UserWarning)
    assert "UnusedInputWarning" in gen.__all__
    km, s = spring()
    with pytest.warns(gen.UnusedInputWarning, match=r"input F\(t\) appears in no expression"):
        model = gen.Model.from_kanes(km, constants={s["m"]: 1, s["k"]: 2},
                                     inputs=[s["T"], s["F"]])
    assert model.nr == 2          # kept, without effect
    km, s = spring(force=False)
    with pytest.warns(gen.UnusedInputWarning, match=r"input T\(t\) appears"):
        gen.Model.from_kanes(km, constants={s["m"]: 1, s["k"]: 2}, inputs=[s["T"]])
    # every input used: no warning
    km, s = spring()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gen.Model.from_kanes(km, constants={s["m"]: 1, s["k"]: 2}, inputs=[s["T"]])


def test_an_input_used_only_by_an_output_is_used():
    km, s = spring(force=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", gen.UnusedInputWarning)
        model = gen.Model.from_kanes(km, constants={s["m"]: 1, s["k"]: 2}, inputs=[s["T"]],
                                     outputs={"push": 3 * s["T"]})
    assert model.nr == 1


# --------------------------------------------------------- zero mass matrix
def test_an_identically_zero_mass_matrix_is_refused_at_creation():
    km, s = spring(mass=False)
    with pytest.raises(gen.ModelError) as e:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gen.UnusedConstantWarning)
            gen.Model.from_kanes(km, constants={s["m"]: 1, s["k"]: 2}, inputs=[s["T"]])
    msg = str(e.value)
    assert "mass matrix is identically zero (speeds u)" in msg


def test_a_zero_row_names_its_speed():
    """Two particles, one massless: the massless one's speed row is zero."""
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    m, k = sm.symbols("m k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P1 = O.locatenew("P1", q1 * N.x)
    P1.set_vel(N, u1 * N.x)
    P2 = O.locatenew("P2", q2 * N.y)
    P2.set_vel(N, u2 * N.y)
    km = me.KanesMethod(N, [q1, q2], [u1, u2], kd_eqs=[q1.diff() - u1, q2.diff() - u2])
    km.kanes_equations([me.Particle("a", P1, m), me.Particle("b", P2, 0)],
                       [(P1, -k * q1 * N.x), (P2, -k * q2 * N.y)])
    with pytest.warns(gen.MasslessSpeedWarning, match=r"mass matrix is zero in the row\(s\) "
                                                      r"of speed\(s\) u2:"):
        model = gen.Model.from_kanes(km, constants={m: 1, k: 2})
    # M and f are generated as given (sympy's own tests check such models' M
    # and f); a simulation stops as singular, naming the step
    sim = gen.compile(model)
    np.testing.assert_array_equal(sim.mass_matrix([0.1, 0.2]), [[1.0, 0.0], [0.0, 0.0]])
    with pytest.raises(gen.SingularError):
        sim.simulate([0.1, 0.2, 0.0, 0.0], 0.1, 0.01)


def test_a_regular_model_is_accepted_and_simulates(kane_model):
    assert kane_model.nu == 2      # the seed pendulum: nonzero rows, constrained


# ------------------------------------------------------------------ gen.At
def test_at_warns_when_a_time_is_not_an_output_time(kane_sim):
    sim = kane_sim
    x0 = sim.consistent_state(np.array([0.5, 0.8, 0.0, 0.0]))
    t, X = sim.simulate(x0, 1.0, 0.1)[:2]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = sim.ensemble(x0[None], 1.0, 0.1, reduce=gen.At([0.3, 1.0]))
    assert np.array_equal(np.asarray(res["at"])[0], X[[3, 10]])
    with pytest.warns(UserWarning, match=r"gen.At: not an output time .* t = 0.33 -> 0.3\b"):
        res = sim.ensemble(x0[None], 1.0, 0.1, reduce=gen.At([0.33, 1.0]))
    assert np.array_equal(np.asarray(res["at"])[0], X[[3, 10]])


def test_at_the_clipped_end_is_the_last_row(kane_sim):
    """t_end = 1.05 with dt = 0.1: the last row is at 1.05 (not t0 + k dt)."""
    sim = kane_sim
    x0 = sim.consistent_state(np.array([0.5, 0.8, 0.0, 0.0]))
    t, X = sim.simulate(x0, 1.05, 0.1)[:2]
    assert t[-1] == 1.05
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = sim.ensemble(x0[None], 1.05, 0.1, reduce=gen.At([1.05]))
    assert np.array_equal(np.asarray(res["at"])[0, 0], X[-1])


# ------------------------------------------------------------ docs/guides/fmu.md
def test_fmu_guide_names_the_real_validate_function():
    text = (ROOT / "docs" / "guides" / "fmu.md").read_text()
    assert "fmpy.validate_fmu" not in text
    assert "fmpy.validation.validate_fmu" in text
    fmpy = pytest.importorskip("fmpy")
    from fmpy.validation import validate_fmu
    assert callable(validate_fmu) and not hasattr(fmpy, "validate_fmu")
