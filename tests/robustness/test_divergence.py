"""A state that runs away is reported as divergence (ERR_DIVERGED,
gen.DivergenceError), never as a singular configuration of the model: a
particle pushed by a force c x^3 reaches infinity in finite time,
t* = integral_1^inf dx / sqrt(c/2 (x^4 - 1)) from rest at x = 1."""
import numpy as np
import pytest
import sympy as sm
from scipy.integrate import quad
from sympy.physics import mechanics as me

import gen


@pytest.fixture(scope="module")
def sim():
    x, u = me.dynamicsymbols("x u")
    c, m = sm.symbols("c m")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    P = O.locatenew("P", x * N.x)
    P.set_vel(N, u * N.x)
    km = me.KanesMethod(N, q_ind=[x], u_ind=[u], kd_eqs=[x.diff() - u])
    km.kanes_equations([me.Particle("p", P, m)], [(P, c * x ** 3 * N.x)])
    return gen.compile(gen.Model.from_kanes(km, constants={c: 2.0, m: 1.0}, name="blowup"))


def _blowup_time(c=2.0):
    val, _ = quad(lambda x: 1.0 / np.sqrt(c / 2 * (x ** 4 - 1)), 1.0, np.inf)
    return val


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
def test_runaway_state_is_divergence(sim, method):
    """RK4 at a fixed step overflows: ERR_DIVERGED. DOPRI5 steps by its
    error control alone and follows the blow-up with ever smaller steps
    until the step size underflows (ERR_STEP_UNDERFLOW) at a huge but
    finite state, unless a trial overflows first: either way a
    ConvergenceError at t*, never a singular configuration."""
    t_star = _blowup_time()
    with pytest.raises(gen.ConvergenceError) as e:
        sim.simulate([1.0, 0.0], 2 * t_star, 1e-4, method=method)
    err = e.value
    if method == "rk4":
        assert isinstance(err, gen.DivergenceError)
        assert err.status_name == "ERR_DIVERGED" and "diverged" in str(err)
    else:
        assert err.status_name in ("ERR_DIVERGED", "ERR_STEP_UNDERFLOW"), err.status_name
    assert not isinstance(err, gen.SingularError)
    # it runs away right at the analytic blow-up time, not before
    assert t_star * 0.99 < err.time < t_star * 1.01
    assert np.max(np.abs(err.state)) > 1e6


def test_regular_state_of_the_same_model_is_fine(sim):
    t, X = sim.simulate([1.0, 0.0], 0.5 * _blowup_time(), 1e-4)
    assert np.all(np.isfinite(X))
