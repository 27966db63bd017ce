"""Issue 15: the discrete-time linearization. Ad, Bd = sim.linearize(x_op,
r_op, dt=Ts) is the zero-order-hold discretization, computed in C by
scaling and squaring (csrc/gen_rt_expm.c, tests/unit/runtime/test_expm.py for the
exponential itself). Reference: scipy.linalg.expm of the augmented matrix
[[A, B], [0, 0]] Ts built from sim.linearize's own A, B; and the simulated
response of the held input, which the discretization must reproduce."""
import numpy as np
import pytest
from scipy.linalg import expm

import cart_pole as cp
import gen
import seed_pendulum as sp

MODELS = {"seed_kane": sp.kane_model, "cart_pole": cp.model}


@pytest.fixture(scope="module", params=[(k, real) for k in MODELS for real in ("double", "float")],
                ids=lambda kr: f"{kr[0]}-{kr[1]}")
def sim(request):
    key, real = request.param
    return gen.compile(MODELS[key](), real=real), real


def _points(s):
    rng = np.random.default_rng(7)
    pts = [np.zeros(s.nx)] if not s.mc else []
    for _ in range(3):
        x = rng.uniform(-0.8, 0.8, s.nx)
        if s.mc:
            x[s.q_ind] = rng.uniform(0.3, 1.2, len(s.q_ind))
        pts.append(s.consistent_state(x) if (s.mc or s.mv) else x)
    return pts


def test_against_scipy_expm_of_the_augmented_matrix(sim):
    s, real = sim
    tol = 1e-12 if real == "double" else 1e-5
    for x in _points(s):
        r = np.full(s.nr, 0.4)
        A, B = s.linearize(x, r=r)
        for Ts in (1e-3, 0.05, 0.7):
            Ad, Bd = s.linearize(x, r=r, dt=Ts)
            ns, nr = s.ns, s.nr
            M = np.zeros((ns + nr, ns + nr))
            M[:ns, :ns], M[:ns, ns:] = A, B
            E = expm(M.astype(float) * Ts)
            scale = max(1.0, np.max(np.abs(E)))
            assert np.max(np.abs(Ad - E[:ns, :ns])) <= tol * scale, (Ts, x)
            if nr:
                assert np.max(np.abs(Bd - E[:ns, ns:])) <= tol * scale, (Ts, x)
            else:
                assert Bd.shape == (ns, 0)


def test_discrete_model_predicts_the_held_input_response():
    """At the upright equilibrium of the cart-pole, a small force held over
    one step moves the state as Ad x + Bd u predicts (to second order in
    the perturbation)."""
    s = gen.compile(cp.model())
    Ts, eps = 0.02, 1e-6
    Ad, Bd = s.linearize(np.zeros(4), dt=Ts)
    dx0 = eps * np.array([0.3, -0.5, 0.2, 0.7])
    du = np.array([eps * 2.0])
    _, X = s.simulate(dx0, Ts, Ts / 200, r=du)
    pred = Ad @ dx0 + Bd @ du
    assert np.max(np.abs(X[-1] - pred)) < 1e-4 * eps


def test_bad_dt_is_refused():
    s = gen.compile(sp.kane_model())
    x = s.consistent_state(np.array([0.3, 0.9, 0, 0]))
    for dt in (0.0, -1.0, np.nan):
        with pytest.raises(ValueError, match="dt must be a positive number"):
            s.linearize(x, dt=dt)


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_matches_c():
    from conftest import require_eigen
    require_eigen()
    for key in MODELS:
        c = gen.compile(MODELS[key]())
        e = gen.compile(MODELS[key](), backend="eigen")
        for x in _points(c):
            Ad, Bd = c.linearize(x, dt=0.05)
            Ae, Be = e.linearize(x, dt=0.05)
            assert np.max(np.abs(Ad - Ae)) < 1e-13, key
            assert Bd.shape == Be.shape and np.all(np.abs(Bd - Be) < 1e-13), key
