"""The multiplier sign contract for LagrangesMethod models: sim.multipliers
is the multiplier part of the solution of sympy's mass_matrix_full /
forcing_full system, and the negative of LM.solve_multipliers (sympy issue
30215). Checked on a holonomic model (the seed pendulum: x^2 + y^2 = L^2)
and on a nonholonomic one (a knife-edge sleigh: no sideways slip), at
random moving states, against both of sympy's values."""
import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen
import seed_pendulum as sp


def _sympy_values(LM, op, nlam):
    """(solve_multipliers, the multiplier part of the full solve) at op."""
    sm_vals = LM.solve_multipliers(op_point=op)
    lam_sm = np.array([float(sm_vals[lv]) for lv in LM.lam_vec])
    MM = np.array(LM.mass_matrix_full.xreplace(op).evalf(), dtype=float)
    FF = np.array(LM.forcing_full.xreplace(op).evalf(), dtype=float).ravel()
    sol = np.linalg.solve(MM, FF)
    return lam_sm, sol[-nlam:]


def test_holonomic_seed_pendulum():
    LM, s = sp.derive_lagrange()
    sim = gen.compile(sp.lagrange_model())
    rng = np.random.default_rng(3)
    for _ in range(5):
        th, w = rng.uniform(-1.2, 1.2), rng.uniform(-2, 2)
        x = np.array([np.cos(th), np.sin(th), -w * np.sin(th), w * np.cos(th)])   # L = 1
        op = {s["q1"]: x[0], s["q2"]: x[1], s["q1d"]: x[2], s["q2d"]: x[3],
              s["L"]: 1.0, s["m"]: 1.0, s["g"]: 9.81}
        lam_sm, lam_full = _sympy_values(LM, op, 1)
        lam = sim.multipliers(0.0, x)
        assert np.allclose(lam, lam_full, rtol=1e-12, atol=1e-12)
        assert np.allclose(lam, -lam_sm, rtol=1e-12, atol=1e-12)
        # the physical reading: the rod's tension T = -2 L lam = m (g cos th + w^2 L)
        assert -2.0 * lam[0] == pytest.approx(9.81 * np.cos(th) + w ** 2, rel=1e-12)


def _sleigh():
    t = me.dynamicsymbols._t
    x, y, th = me.dynamicsymbols("x y theta")
    xd, yd, thd = me.dynamicsymbols("x y theta", 1)
    m, I, F, c = sm.symbols("m I F c")
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, xd * N.x + yd * N.y)
    L = m * (xd ** 2 + yd ** 2) / 2 + I * thd ** 2 / 2
    # no sideways slip: the velocity of P across the blade vanishes
    nonhol = [-sm.sin(th) * xd + sm.cos(th) * yd]
    A = N.orientnew("A", "Axis", [th, N.z])
    A.set_ang_vel(N, thd * N.z)
    loads = [(P, F * A.x), (A, -c * thd * N.z)]
    LM = me.LagrangesMethod(L, [x, y, th], nonhol_coneqs=nonhol, forcelist=loads, frame=N)
    LM.form_lagranges_equations()
    vals = {m: 2.0, I: 0.3, F: 1.5, c: 0.2}
    model = gen.Model.from_lagrange(LM, q_ind=[x, y, th], qd_ind=[xd, thd], q_dep=[],
                                    qd_dep=[yd], constants=vals, name="sleigh_lagrange")
    return LM, model, (x, y, th, xd, yd, thd), vals


def test_nonholonomic_sleigh():
    LM, model, (x, y, th, xd, yd, thd), vals = _sleigh()
    sim = gen.compile(model)
    rng = np.random.default_rng(4)
    for _ in range(5):
        s0 = rng.uniform(-1, 1, 6)
        st = sim.consistent_state(s0)              # y' from the blade constraint
        op = {x: st[0], y: st[1], th: st[2], xd: st[3], yd: st[4], thd: st[5], **vals}
        lam_sm, lam_full = _sympy_values(LM, op, 1)
        lam = sim.multipliers(0.0, st)
        assert abs(lam[0]) > 1e-3                   # a real sideways force here
        assert np.allclose(lam, lam_full, rtol=1e-12, atol=1e-12)
        assert np.allclose(lam, -lam_sm, rtol=1e-12, atol=1e-12)
