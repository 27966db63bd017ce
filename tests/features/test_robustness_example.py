"""examples/cart_pole_robustness.py (issue 18's example), against sampled-data
linear theory: a run of the Monte Carlo recovers exactly when the nominal
LQR, sampled and held at PERIOD, stabilizes that run's plant, that is when
the zero-order-hold closed loop Ad - Bd K of the plant linearized at rest
(its own masses and length) has a spectral radius below 1. The initial
angles (<= 0.2 rad) are small enough that the nonlinear outcome follows the
linear one, except within a sliver of the boundary."""
import numpy as np
import pytest
from scipy.linalg import expm

import cart_pole_robustness as ex


def test_monte_carlo_success_is_the_sampled_data_stability_region():
    sim, draws, res, ok = ex.run(n=400, seed=3, progress=False)
    A, B = sim.linearize(np.zeros(sim.nx))
    import cart_pole
    K = cart_pole.lqr(A, B, cart_pole.Q_LQR, cart_pole.R_LQR)
    ns, nr = sim.ns, sim.nr
    rho = []
    for i in range(len(ok)):
        p = {k: draws[k][i] for k in ("m_c", "m_p", "l")}
        Ai, Bi = sim.linearize(np.zeros(sim.nx), p=p)
        # ZOH over one period, by the exponential of the augmented matrix (SciPy)
        Mi = np.zeros((ns + nr, ns + nr))
        Mi[:ns, :ns], Mi[:ns, ns:] = Ai, Bi
        E = expm(Mi * ex.PERIOD)
        Ad, Bd = E[:ns, :ns], E[:ns, ns:]
        rho.append(max(abs(np.linalg.eigvals(Ad - Bd @ K))))
    rho = np.array(rho)
    stable = rho < 1
    # away from the boundary the outcome is the theory's: a spectral radius
    # below 0.95 has the pole back within 5 s (42 samples), above 1.05 it
    # never does; between, 5 s and the nonlinear terms decide
    clear = (rho < 0.95) | (rho > 1.05)
    assert clear.sum() > 380
    # both outcomes occur at this sample time, so the comparison can fail
    assert 0.5 < ok.mean() < 0.995 and (~stable[clear]).sum() >= 3
    assert np.array_equal(ok[clear], stable[clear]), np.flatnonzero(ok[clear] != stable[clear])
    # every failure away from the boundary is a run the simulator stopped or left off-target
    assert set(np.flatnonzero(~res.ok)) <= set(np.flatnonzero(~ok))
