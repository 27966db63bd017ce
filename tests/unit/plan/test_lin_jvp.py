"""Issue 17: the linearization's Jacobian blocks generated as a kernel of
directional derivatives called once per variable (gen/plan/ir.py, lin="jvp",
the C backend's choice from JVP_MIN_VARIABLES variables) give the same
numbers as the unrolled kernel (lin="unrolled"): linearize, jacobian and
step sensitivities of constrained, nonholonomic and implicit-kinematics
models, at random states."""
import numpy as np
import pytest

import cart_pole
import four_bar
import gen
import gen.plan.ir as ir
import rolling_disc
import seed_pendulum
from helpers import load_test_file
from gen.sim.simulator import Simulator
from gen.toolchain.build import build
from gen.toolchain.host import load
from gen.codegen.render import render

MODELS = {
    "kane": seed_pendulum.kane_model,
    "lagrange": seed_pendulum.lagrange_model,
    "cart_pole": cart_pole.model,
    "rolling_disc": rolling_disc.model,
    "four_bar": four_bar.model,
}


def _sim(model, lin):
    b = build(render(ir.plan(model, lin=lin), project=False))
    return Simulator(*load(b), b.interface)


def _skate():
    skate = load_test_file("physics/test_implicit_kinematics_constrained.py").skate
    return skate(explicit_kinematics=False, name="skate_jvp")


SLOW = {"lagrange", "cart_pole", "rolling_disc", "four_bar"}


@pytest.mark.parametrize("key", [pytest.param(k, marks=pytest.mark.slow) if k in SLOW else k
                                 for k in list(MODELS) + ["skate"]])
def test_jvp_blocks_equal_the_unrolled_ones(key):
    model = _skate() if key == "skate" else MODELS[key]()
    su, sj = _sim(model, "unrolled"), _sim(model, "jvp")
    rng = np.random.default_rng(7)
    for _ in range(3):
        x = rng.normal(size=su.nx) * 0.4
        if su.mc or su.mv:
            x = su.consistent_state(x)
        r = rng.normal(size=su.nr) if su.nr else None
        A1, B1 = su.linearize(x, r=r)
        A2, B2 = sj.linearize(x, r=r)
        scale = 1 + np.max(np.abs(A1))
        assert np.max(np.abs(A1 - A2)) <= 1e-12 * scale
        if su.nr:
            assert np.max(np.abs(B1 - B2)) <= 1e-12 * (1 + np.max(np.abs(B1)))
        Jx1, _ = su.jacobian(0.0, x, r=r)
        Jx2, _ = sj.jacobian(0.0, x, r=r)
        assert np.max(np.abs(Jx1 - Jx2)) <= 1e-12 * (1 + np.max(np.abs(Jx1)))
    # the independent reference: central differences of the rhs
    x = su.consistent_state(rng.normal(size=su.nx) * 0.4) if (su.mc or su.mv) else \
        rng.normal(size=su.nx) * 0.4
    r = rng.normal(size=su.nr) if su.nr else None
    Jx, _ = sj.jacobian(0.0, x, r=r)
    h = 1e-6
    fd = np.column_stack([(sj.rhs(0.0, x + h * e, r=r) - sj.rhs(0.0, x - h * e, r=r)) / (2 * h)
                          for e in np.eye(sj.nx)])
    assert np.max(np.abs(Jx - fd)) <= 1e-6 * (1 + np.max(np.abs(fd)))


@pytest.mark.slow
def test_large_models_choose_jvp():
    import n_link_cart
    assert ir.JVP_MIN_VARIABLES > 4 + 4 + 1      # the seed models stay unrolled
    m = n_link_cart.model(14)                    # nq + nu + nr = 31
    p = ir.plan(m)
    assert "lin_jvp" in p.kernels and "lin_terms" not in p.kernels
    assert "lin_terms" in ir.plan(seed_pendulum.kane_model()).kernels
