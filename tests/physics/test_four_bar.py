"""Issue 4: a closed kinematic loop (planar four-bar, two dependent
coordinates and speeds). A at the stable equilibrium against the
small-oscillation frequency derived independently in the one minimal
coordinate (the crank angle) from T = J(q1) q1'^2 / 2 and V(q1), with the
loop closed in closed form (intersection of two circles) and evaluated at
50 digits with mpmath. No Kane, no constraint Jacobian, no multiplier on
that side."""
import mpmath as mp
import numpy as np
import pytest
import sympy as sm

import four_bar
import gen
from helpers import rel_err

P = four_bar.DEFAULTS


def _one_coordinate(vals):
    """V(q1), J(q1) of the four-bar in the crank angle alone."""
    q1 = sm.Symbol("q1")
    a, b, c, d, ma, mb, mc, g = (sm.Float(vals[k], 50) for k in
                                 ("a", "b", "c", "d", "m_a", "m_b", "m_c", "g"))
    Ax, Ay = a * sm.cos(q1), a * sm.sin(q1)
    ex, ey = d - Ax, -Ay                         # from crank tip A to ground pivot D
    s2 = ex**2 + ey**2
    s = sm.sqrt(s2)
    h0 = (b**2 - c**2 + s2) / (2 * s)            # along A->D
    k = sm.sqrt(b**2 - h0**2)                    # across; the hanging branch is -perp
    Bx = Ax + (h0 * ex + k * ey) / s
    By = Ay + (h0 * ey - k * ex) / s
    # potential: centres of the crank, coupler (midpoint AB), rocker (midpoint DB)
    V = g * (ma * Ay / 2 + mb * (Ay + By) / 2 + mc * By / 2)
    # kinetic energy per unit q1'^2: link rates from |B-A| = b, |B-D| = c
    dAx, dAy, dBx, dBy = (e.diff(q1) for e in (Ax, Ay, Bx, By))
    w2 = ((Bx - Ax) * (dBy - dAy) - (By - Ay) * (dBx - dAx)) / b**2
    w3 = ((Bx - d) * dBy - By * dBx) / c**2
    J = (ma * a**2 / 3
         + mb * (((dAx + dBx) / 2)**2 + ((dAy + dBy) / 2)**2) + mb * b**2 / 12 * w2**2
         + mc * c**2 / 3 * w3**2)
    q2 = sm.atan2(By - Ay, Bx - Ax)
    q3 = sm.atan2(By, Bx - d)
    f = {name: sm.lambdify(q1, e, "mpmath")
         for name, e in (("dV", V.diff(q1)), ("d2V", V.diff(q1, 2)), ("J", J),
                         ("q2", q2), ("q3", q3), ("w2", w2), ("w3", w3))}
    return f


@pytest.fixture(scope="module")
def fb_sim():
    return gen.compile(four_bar.model())


@pytest.fixture(scope="module")
def equilibrium():
    mp.mp.dps = 50
    f = _one_coordinate(P)
    q1s = mp.findroot(f["dV"], mp.mpf(four_bar.HANGING["q1"]))
    omega2 = f["d2V"](q1s) / f["J"](q1s)
    return {"q1": float(q1s), "q2": float(f["q2"](q1s)), "q3": float(f["q3"](q1s)),
            "omega2": float(omega2), "f": f, "q1_mp": q1s}


def test_independent_equilibrium_is_stable_and_hanging(equilibrium):
    assert equilibrium["omega2"] > 0
    assert -np.pi < equilibrium["q1"] < 0 and equilibrium["q3"] < 0


def test_four_bar_A_at_stable_equilibrium(fb_sim, equilibrium):
    e = equilibrium
    x = np.array([e["q1"], 0.2, -1.0, 0, 0, 0])        # rough dependent guess
    x = fb_sim.consistent_state(x, tol=1e-14)
    # the generated loop closure finds the same configuration
    assert abs(x[1] - e["q2"]) < 1e-12 and abs(x[2] - e["q3"]) < 1e-12
    # it is an equilibrium of the compiled dynamics
    assert np.max(np.abs(fb_sim.rhs(0.0, x))) < 1e-12
    A, B = fb_sim.linearize(x)
    assert A.shape == (2, 2) and B.shape == (2, 0)
    expected = np.array([[0.0, 1.0], [-e["omega2"], 0.0]])
    err = rel_err(A, expected)
    print(f"four-bar: omega^2 = {e['omega2']:.15g}, A[1,0] = {A[1, 0]:.15g}, rel err {err:.2e}")
    assert err < 1e-9
    lam = np.linalg.eigvals(A)
    assert np.allclose(sorted(lam.imag), [-np.sqrt(e["omega2"]), np.sqrt(e["omega2"])],
                       rtol=1e-9, atol=0)


def test_four_bar_dependent_speeds_match_loop_rates(fb_sim, equilibrium):
    """The generated velocity constraints give the link rates of the
    closed-form loop, away from the equilibrium and moving."""
    f = equilibrium["f"]
    for q1, u1 in ((-1.0, 0.7), (-1.4, -1.3), (-0.8, 2.0)):
        x = fb_sim.consistent_state(np.array([q1, -0.1, -1.4, u1, 0, 0]), tol=1e-14)
        assert abs(x[1] - float(f["q2"](q1))) < 1e-11
        assert abs(x[2] - float(f["q3"](q1))) < 1e-11
        assert abs(x[4] - u1 * float(f["w2"](q1))) < 1e-10 * max(1, abs(u1))
        assert abs(x[5] - u1 * float(f["w3"](q1))) < 1e-10 * max(1, abs(u1))


def test_four_bar_small_oscillation_period(fb_sim, equilibrium):
    """Simulated period at small amplitude tends to 2 pi / omega."""
    e = equilibrium
    amp = 1e-3
    x0 = fb_sim.consistent_state(np.array([e["q1"] + amp, e["q2"], e["q3"], 0, 0, 0]),
                                 tol=1e-14)
    T0 = 2 * np.pi / np.sqrt(e["omega2"])
    t, X = fb_sim.simulate(x0, 3.2 * T0, T0 / 400, method="dopri5", rtol=1e-12, atol=1e-14)
    from helpers import crossing_times
    tc = crossing_times(t, X[:, 3], -1)
    period = np.mean(np.diff(tc))
    assert abs(period - T0) / T0 < 1e-5          # amplitude correction is O(amp^2)


def test_four_bar_energy_and_loop_closure(fb_sim):
    x0 = fb_sim.consistent_state(np.array([-0.6, 0.0, -1.2, 1.5, 0, 0]), tol=1e-14)
    t, X = fb_sim.simulate(x0, 5.0, 0.01, method="dopri5", rtol=1e-10, atol=1e-12)
    E = np.array([fb_sim.energy(x) for x in X])
    assert np.max(np.abs(E - E[0])) / abs(E[0]) < 1e-7
    res = np.array([fb_sim.constraints(x[:3]) for x in X])
    assert np.max(np.abs(res)) < 1e-10
    assert np.ptp(X[:, 0]) > 0.5                 # it really moved
