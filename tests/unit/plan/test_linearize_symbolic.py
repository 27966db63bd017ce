"""gen.linearize_symbolic: the seed document's closed forms exactly, and
agreement with the compiled linearization at moving points."""
import numpy as np
import pytest
import sympy as sm

import chaplygin_sleigh as cs
import four_bar
import gen
import n_link_cart
import seed_pendulum as sp
from helpers import pendulum_state, rel_err


def _is_zero(M):
    return all(sm.simplify(e) == 0 for e in M)


@pytest.mark.parametrize("method", ["kane", "lagrange"])
def test_seed_closed_forms(method):
    if method == "kane":
        model = sp.kane_model()
        _, s = sp.derive_kane()
        hang = {s["q1"]: s["L"], s["q2"]: 0, s["u1"]: 0, s["u2"]: 0}
        up = {s["q1"]: -s["L"], s["q2"]: 0, s["u1"]: 0, s["u2"]: 0}
    else:
        model = sp.lagrange_model()
        _, s = sp.derive_lagrange()
        hang = {s["q1"]: s["L"], s["q2"]: 0, s["q1d"]: 0, s["q2d"]: 0}
        up = {"q1": -s["L"], "q2": 0, "q1_d": 0, "q2_d": 0}      # names work too
    L, g = s["L"], s["g"]
    A, B = gen.linearize_symbolic(model, hang)
    assert A.shape == (2, 2) and B.shape == (2, 0)
    assert _is_zero(A - sm.Matrix([[0, 1], [-g / L, 0]])), A
    A, _ = gen.linearize_symbolic(model, up)
    assert _is_zero(A - sm.Matrix([[0, 1], [g / L, 0]])), A
    A, _ = gen.linearize_symbolic(model, hang, constants="values")
    assert A == sm.Matrix([[0, 1], [-sm.Float(9.81), 0]])


def _compare(model, sim, points, r=None):
    worst = 0.0
    names = model.state_names
    for x in points:
        op = dict(zip(names, x))
        rr = dict(zip(model.input_names, r)) if r is not None else None
        A_s, B_s = gen.linearize_symbolic(model, op, r_op=rr, constants="values",
                                          simplify=False)
        A, B = sim.linearize(x, r=r)
        worst = max(worst, rel_err(A, np.array(A_s.evalf(), dtype=float)))
        if model.nr:
            worst = max(worst, rel_err(B, np.array(B_s.evalf(), dtype=float)))
    return worst


def test_moving_points_agree_with_compiled(kane_sim, lagrange_sim):
    rng = np.random.default_rng(5)
    pts_k = [pendulum_state(rng.uniform(-1.2, 1.2), rng.uniform(-3, 3), 1.0, "kane")
             for _ in range(4)]
    pts_l = [pendulum_state(rng.uniform(-1.2, 1.2), rng.uniform(-3, 3), 1.0, "lagrange")
             for _ in range(4)]
    assert _compare(sp.kane_model(), kane_sim, pts_k) < 1e-12
    assert _compare(sp.lagrange_model(), lagrange_sim, pts_l) < 1e-12


def test_nonholonomic_inputs_and_closed_loop():
    rng = np.random.default_rng(6)
    sl = cs.model()
    sim = gen.compile(sl)
    pts = []
    for _ in range(3):
        x = rng.uniform(-1, 1, sl.nx)
        pts.append(sim.consistent_state(x))
    err = _compare(sl, sim, pts, r=[0.7, -0.2])
    fb = four_bar.model()
    fsim = gen.compile(fb)
    fpts = [fsim.consistent_state(np.array([-1.1 + 0.2 * k, -0.1, -1.4, 1.0 - k, 0, 0]))
            for k in range(3)]
    err = max(err, _compare(fb, fsim, fpts))
    cart = n_link_cart.model(2)
    csim = gen.compile(cart)
    err = max(err, _compare(cart, csim, [rng.uniform(-1, 1, cart.nx) for _ in range(3)],
                            r=[1.5]))
    print(f"linearize_symbolic vs compiled: max rel err {err:.2e}")
    assert err < 1e-12


def test_errors_name_the_problem():
    model = sp.kane_model()
    _, s = sp.derive_kane()
    with pytest.raises(gen.ModelError, match="theta"):
        gen.linearize_symbolic(model, {"theta": 0})
    with pytest.raises(gen.ModelError, match="constant"):
        gen.linearize_symbolic(model, {s["q1"]: 1}, constants={"Lx": 1})
    # where q1 = 0 the seed's velocity constraint (built on atan(q2/q1))
    # vanishes identically: the constrained dynamics are singular there
    with pytest.raises(gen.SingularError, match="singular"):
        gen.linearize_symbolic(model, {s["q1"]: 0, s["q2"]: s["L"], s["u1"]: 0, s["u2"]: 0})
