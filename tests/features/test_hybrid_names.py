"""Hybrid declarations in the user's own names (issue 46): a constant used
only by a guard is used; a guard or gap is one scalar; an input in a guard is
named as the user wrote it; a map that is not finite names the reset, the
state before it and the entry. Each with its exact message."""
import warnings

import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me

import gen

G = 9.81


def _equations():
    """A ball y, v pushed by an input force F, with constants m, g, h, k."""
    y, v, F = me.dynamicsymbols("y v F")
    m, g, h, k = sm.symbols("m g h k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", y * N.y)
    P.set_vel(N, v * N.y)
    km = me.KanesMethod(N, [y], [v], kd_eqs=[y.diff() - v])
    km.kanes_equations([me.Particle("b", P, m)], [(P, (F - m * g) * N.y)])
    return km, (y, v, F), (m, g, h, k)


def test_a_constant_only_in_a_guard_or_map_is_used():
    """h moves only the guard, k only the map: neither is reported unused
    (before: UnusedConstantWarning for both, though p= moves them); a
    constant used nowhere still is."""
    km, (y, v, F), (m, g, h, k) = _equations()
    c = {m: 1.0, g: G, h: 0.2, k: 0.5}
    hyb = {"kick": gen.Reset(y - h, {v: -k * v})}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = gen.Model.from_kanes(km, constants=c, inputs=[F], hybrid=hyb, name="uc")
    assert [str(s) for s in model.p_orig] == ["m", "g", "h", "k"]
    z = sm.Symbol("z")
    with pytest.warns(gen.UnusedConstantWarning) as rec:
        gen.Model.from_kanes(km, constants={**c, z: 3.0}, inputs=[F], hybrid=hyb, name="uc")
    assert str(rec[0].message) == (
        "model 'uc': constant z appears in no expression of the model (mass matrix, forcing, "
        "kinematic equations, constraints, energy); kept as parameter(s) without effect")


def test_a_guard_is_one_scalar():
    """gen.Reset(Matrix([g1, g2]), ...) was accepted and only g1 acted."""
    km, (y, v, F), _ = _equations()
    with pytest.raises(gen.ModelError) as err:
        gen.Reset(sm.Matrix([y, v]), {v: -v})
    assert str(err.value) == (
        "Reset: the guard must be one scalar expression, got a 2 x 1 matrix "
        "(Matrix([[y(t)], [v(t)]])); declare one gen.Reset per guard under names of their "
        "own (hybrid={'a': ..., 'b': ...})")
    with pytest.raises(gen.ModelError) as err:
        gen.Impact([y, y - 1])
    assert str(err.value) == (
        "Impact: the gap must be one scalar expression, got a 2 list ([y(t), y(t) - 1]); "
        "declare one gen.Impact per gap under names of their own (hybrid={'a': ..., 'b': ...})")
    with pytest.raises(gen.ModelError) as err:
        gen.Reset(y, {v: sm.Matrix([-v, v])})
    assert str(err.value) == (
        "Reset(y(t)): the map[v] must be one scalar expression, got a 2 x 1 matrix "
        "(Matrix([[-v(t)], [v(t)]])); declare one gen.Reset per map under names of their own "
        "(hybrid={'a': ..., 'b': ...})")
    with pytest.raises(gen.ModelError) as err:
        gen.Impact(y < 0)
    assert str(err.value) == (
        "Impact: the gap must be one scalar expression, got StrictLessThan (y(t) < 0); a gap or "
        "guard is an expression whose zero crossing is the event (y, not y < 0)")


def test_an_input_in_a_guard_is_named_as_the_user_wrote_it():
    """Before: "holds unknown symbol(s) _r0"."""
    km, (y, v, F), (m, g, h, k) = _equations()
    c = {m: 1.0, g: G}
    with pytest.raises(gen.ModelError) as err:
        gen.Model.from_kanes(km, constants=c, inputs=[F], name="ui",
                             hybrid={"kick": gen.Reset(y - F, {v: -v})})
    assert str(err.value) == (
        "model 'ui': the guard of 'kick' (-F(t) + y(t)) holds the input(s) F; a guard is a "
        "function of the state, the constants and t (the engine evaluates it without the "
        "inputs)")
    with pytest.raises(gen.ModelError) as err:
        gen.Model.from_kanes(km, constants=c, inputs=[F], name="ui",
                             hybrid={"kick": gen.Reset(y, {v: F * v})})
    assert str(err.value) == (
        "model 'ui': the map[v] of 'kick' (F(t)*v(t)) holds the input(s) F; a map is a "
        "function of the state before the jump, the constants and t (the engine evaluates it "
        "without the inputs)")
    with pytest.raises(gen.ModelError) as err:
        gen.Model.from_kanes(km, constants=c, inputs=[F], name="ui",
                             hybrid={"floor": gen.Impact(y - F)})
    assert str(err.value) == (
        "model 'ui': the gap of 'floor' (-F(t) + y(t)) holds the input(s) F; a gap is a "
        "function of the coordinates (the engine evaluates it without the inputs)")
    w = sm.Symbol("w")
    with pytest.raises(gen.ModelError) as err:
        gen.Model.from_kanes(km, constants=c, inputs=[F], name="ui",
                             hybrid={"kick": gen.Reset(y - w, {v: -v})})
    assert str(err.value) == (
        "model 'ui': the guard of 'kick' (-w + y(t)) holds unknown symbol(s) w: neither a "
        "coordinate (y), a speed nor a constant (m, g)")


@pytest.mark.slow
def test_a_map_that_is_not_finite_names_the_reset_the_state_and_the_entry():
    """Before: ERR_NONFINITE_MODEL with no name. The ball falls from 1 and
    its map at y = h = 0.5 takes sqrt(y - 1): the reset, the time and the
    state before it (analytic here), and the entry v = nan."""
    km, (y, v, F), (m, g, h, k) = _equations()
    model = gen.Model.from_kanes(km, constants={m: 1.0, g: G, h: 0.5, k: 0.5}, inputs=[F],
                                 name="hyb_nan_map",
                                 hybrid={"kick": gen.Reset(y - h, {v: -k * sm.sqrt(y - 1)})})
    sim = gen.compile(model)
    with pytest.raises(gen.SingularError) as err:
        sim.simulate([1.0, 0.0], 1.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
    e = err.value
    t1 = np.sqrt(2 * 0.5 / G)
    assert abs(e.time - t1) < 1e-12 and abs(e.state[0] - 0.5) < 1e-12
    assert abs(e.state[1] + G * t1) < 1e-11
    assert str(e) == (
        f"hyb_nan_map_simulate_events: the map of reset 'kick' is not finite at "
        f"t = {e.time:.17g}: v = nan [ERR_NONFINITE_MODEL], the state before it: "
        f"y={e.state[0]:.12g}, v={e.state[1]:.12g}")
