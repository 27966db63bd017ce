"""The model's conversion of a method's matrices to internal symbols
(gen.sym.dag.xreplace_shared) builds exactly the objects sympy's xreplace builds: the
same arguments in the same canonical order (== compares them in order), on
models whose expressions hold functions of time, derivatives, non-smooth
functions and numbers, and the same when the rule maps onto expressions
(the path that re-evaluates)."""
import pytest
import sympy as sm
import sympy.physics.mechanics as me

from gen.sym.dag import xreplace_shared

import cart_pole
import n_link_cart
import nonsmooth
import rolling_disc
import seed_pendulum

T = me.dynamicsymbols._t


def _rule(exprs):
    """Functions of time and their derivatives -> fresh Dummies, t -> a
    Dummy (what gen.intake.canonical.convert does), in a fixed order."""
    fns = set()
    for e in exprs:
        fns |= e.atoms(sm.Derivative) | e.atoms(sm.core.function.AppliedUndef)
    rule = {f: sm.Dummy(f"s{i}") for i, f in enumerate(sorted(fns, key=sm.default_sort_key))}
    rule[T] = sm.Dummy("t")
    return rule


def _full(derived):
    return [derived[0].mass_matrix_full, derived[0].forcing_full]


def _reduced(derived):
    return [derived[0].mass_matrix, derived[0].forcing]


# formed when a test runs, not at collection (every pytest-xdist worker collects)
METHODS = {
    "kane": lambda: _full(seed_pendulum.derive_kane()),
    "lagrange": lambda: _full(seed_pendulum.derive_lagrange()),
    "cart5": lambda: _reduced(n_link_cart.derive(5)),
    "rolling_disc": lambda: _full(rolling_disc.derive()),
    "cart_pole": lambda: _reduced(cart_pole.derive()),
    **{d.__name__: (lambda d=d: _reduced(d())) for d in (
        nonsmooth.derive_drag, nonsmooth.derive_friction, nonsmooth.derive_actuator)},
}


@pytest.mark.parametrize("name", list(METHODS))
def test_conversion_builds_sympys_objects(name):
    mats = METHODS[name]()
    rule = _rule([e for m in mats for e in m])
    memo = {}
    for mat in mats:
        fast = xreplace_shared(sm.Matrix(mat), rule, memo)
        slow = sm.Matrix(mat).xreplace(rule)
        for a, b in zip(fast, slow):
            assert a == b and hash(a) == hash(b), (name, a, b)


def test_non_atomic_rule_re_evaluates():
    x, y = sm.symbols("x y")
    f = me.dynamicsymbols("f")
    mat = sm.Matrix([f * x + f**2 - x * f, sm.sin(f) * f])
    rule = {f: x + y}
    fast = xreplace_shared(mat, rule, {})
    assert fast == mat.xreplace(rule)
    assert fast[0] == (x + y)**2          # f*x - x*f cancelled by evaluation
