"""gen.model's conversion of a method's matrices to internal symbols
(_xreplace_shared) builds exactly the objects sympy's xreplace builds: the
same arguments in the same canonical order (== compares them in order), on
models whose expressions hold functions of time, derivatives, non-smooth
functions and numbers, and the same when the rule maps onto expressions
(the path that re-evaluates)."""
import pytest
import sympy as sm
import sympy.physics.mechanics as me

from gen.model import _xreplace_shared

import cart_pole
import n_link_cart
import nonsmooth
import rolling_disc
import seed_pendulum

T = me.dynamicsymbols._t


def _rule(exprs):
    """Functions of time and their derivatives -> fresh Dummies, t -> a
    Dummy (what Model._finish does), in a fixed order."""
    fns = set()
    for e in exprs:
        fns |= e.atoms(sm.Derivative) | e.atoms(sm.core.function.AppliedUndef)
    rule = {f: sm.Dummy(f"s{i}") for i, f in enumerate(sorted(fns, key=sm.default_sort_key))}
    rule[T] = sm.Dummy("t")
    return rule


def _methods():
    KM, _ = seed_pendulum.derive_kane()
    yield "kane", [KM.mass_matrix_full, KM.forcing_full]
    LM, _ = seed_pendulum.derive_lagrange()
    yield "lagrange", [LM.mass_matrix_full, LM.forcing_full]
    KM, _ = n_link_cart.derive(5)
    yield "cart5", [KM.mass_matrix, KM.forcing]
    KM, _ = rolling_disc.derive()
    yield "rolling_disc", [KM.mass_matrix_full, KM.forcing_full]
    KM, _ = cart_pole.derive()
    yield "cart_pole", [KM.mass_matrix, KM.forcing]
    for derive in (nonsmooth.derive_drag, nonsmooth.derive_friction, nonsmooth.derive_actuator):
        KM, _ = derive()
        yield derive.__name__, [KM.mass_matrix, KM.forcing]


@pytest.mark.parametrize("name,mats", list(_methods()))
def test_conversion_builds_sympys_objects(name, mats):
    rule = _rule([e for m in mats for e in m])
    memo = {}
    for mat in mats:
        fast = _xreplace_shared(sm.Matrix(mat), rule, memo)
        slow = sm.Matrix(mat).xreplace(rule)
        for a, b in zip(fast, slow):
            assert a == b and hash(a) == hash(b), (name, a, b)


def test_non_atomic_rule_re_evaluates():
    x, y = sm.symbols("x y")
    f = me.dynamicsymbols("f")
    mat = sm.Matrix([f * x + f**2 - x * f, sm.sin(f) * f])
    rule = {f: x + y}
    fast = _xreplace_shared(mat, rule, {})
    assert fast == mat.xreplace(rule)
    assert fast[0] == (x + y)**2          # f*x - x*f cancelled by evaluation
