"""Issue 15: step sensitivities. x1, Fx, Fr = sim.step(t, x, h, r,
sim.step_sensitivity) are one RK4 step and its exact derivatives by the
step's variational equations (the generated Jacobian kernels; the C
runtime's own tests in tests/c/test_sens.c check the algebra on hand-written
models). Here, on generated models, against central differences of the
step itself, unconstrained and constrained (the dependent entries completed
by consistent_state, the step not projected: the documented convention)."""
import numpy as np
import pytest

import cart_pole as cp
import gen
import rolling_disc
import seed_pendulum as sp

MODELS = {"cart_pole": cp.model, "seed_kane": sp.kane_model, "seed_lagrange": sp.lagrange_model,
          "rolling_disc": rolling_disc.model}


@pytest.fixture(scope="module")
def sims():
    return {k: gen.compile(f()) for k, f in MODELS.items()}


def _state(sim, rng):
    x = rng.uniform(-0.6, 0.6, sim.nx)
    if sim.mc:
        x[sim.q_ind] = rng.uniform(0.4, 0.9, len(sim.q_ind))
    return sim.consistent_state(x) if (sim.mc or sim.mv) else x


def _fd(sim, t, x, h, r, d=1e-6):
    """Central differences of the unprojected step on the independent state."""
    ind = list(sim.q_ind) + [sim.nq + i for i in sim.u_ind]

    def step(xx, rr):
        return sim.step(t, xx, h, r=rr, project=False, method="rk4")[ind]

    Fx = np.zeros((sim.ns, sim.ns))
    for j, idx in enumerate(ind):
        xp, xm = x.copy(), x.copy()
        xp[idx] += d
        xm[idx] -= d
        if sim.mc or sim.mv:
            xp, xm = sim.consistent_state(xp), sim.consistent_state(xm)
        Fx[:, j] = (step(xp, r) - step(xm, r)) / (2 * d)
    Fr = np.zeros((sim.ns, sim.nr))
    for j in range(sim.nr):
        rp, rm = r.copy(), r.copy()
        rp[j] += d
        rm[j] -= d
        Fr[:, j] = (step(x, rp) - step(x, rm)) / (2 * d)
    return Fx, Fr


@pytest.mark.parametrize("key", list(MODELS))
def test_against_central_differences_of_the_step(sims, key):
    sim = sims[key]
    rng = np.random.default_rng(11)
    for h in (1e-3, 0.05):
        x = _state(sim, rng)
        r = rng.uniform(-1, 1, sim.nr)
        x1, Fx, Fr = sim.step_sensitivity(0.2, x, h, r=r)
        # the step itself is the plain unprojected RK4 step, bit for bit
        assert np.array_equal(x1, sim.step(0.2, x, h, r=r, project=False, method="rk4"))
        Fxn, Frn = _fd(sim, 0.2, x, h, r)
        assert Fx.shape == (sim.ns, sim.ns) and Fr.shape == (sim.ns, sim.nr)
        assert np.max(np.abs(Fx - Fxn)) < 1e-7 * max(1, np.max(np.abs(Fx))), (key, h)
        if sim.nr:
            assert np.max(np.abs(Fr - Frn)) < 1e-7 * max(1, np.max(np.abs(Fr))), (key, h)


@pytest.mark.parametrize("key", ["cart_pole", "seed_kane"])
def test_small_steps_tend_to_I_plus_hA(sims, key):
    sim = sims[key]
    x = _state(sim, np.random.default_rng(2))
    r = np.full(sim.nr, 0.3)
    A, B = sim.linearize(x, r=r)
    errs = []
    for h in (1e-2, 1e-3, 1e-4):
        _, Fx, Fr = sim.step_sensitivity(0.0, x, h, r=r)
        errs.append(np.max(np.abs((Fx - np.eye(sim.ns)) / h - A)))
        if sim.nr:
            assert np.max(np.abs(Fr / h - B)) < 10 * h * max(1, np.max(np.abs(B)))
    # first order in h: each factor of 10 in h divides the error by about 10
    assert errs[1] < errs[0] / 5 and errs[2] < errs[1] / 5, errs


def test_jacobian_against_central_differences_of_the_rhs(sims):
    rng = np.random.default_rng(4)
    for key, sim in sims.items():
        x = _state(sim, rng) + rng.uniform(-1e-2, 1e-2, sim.nx)   # off the manifold too
        r = rng.uniform(-1, 1, sim.nr)
        Jx, Jr = sim.jacobian(0.1, x, r=r)
        d = 1e-6
        Jn = np.column_stack([(sim.rhs(0.1, x + d * e, r=r) - sim.rhs(0.1, x - d * e, r=r))
                              / (2 * d) for e in np.eye(sim.nx)])
        assert np.max(np.abs(Jx - Jn)) < 1e-7 * max(1, np.max(np.abs(Jx))), key


def test_unconstrained_full_state_and_errors(sims):
    sim = sims["cart_pole"]
    with pytest.raises(gen.InputError, match="method='rk4'"):
        sim.step_sensitivity(0.0, np.zeros(4), 0.01, method="dopri5")
    # the differentiated step is the unprojected one: no project= to ask otherwise, and
    # no flag that changes what step returns
    with pytest.raises(TypeError):
        sim.step_sensitivity(0.0, np.zeros(4), 0.01, project=True)
    with pytest.raises(TypeError):
        sim.step(0.0, np.zeros(4), 0.01, sensitivities=True)
    # without sensitivities, step(method="rk4") is the classic RK4 step over sim.rhs
    x, h, r = np.array([0.1, 0.2, 0.3, 0.4]), 0.01, [1.0]
    f = lambda t, y: sim.rhs(t, y, r=r)  # noqa: E731
    k1 = f(0.0, x)
    k2 = f(h / 2, x + h / 2 * k1)
    k3 = f(h / 2, x + h / 2 * k2)
    k4 = f(h, x + h * k3)
    want = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    np.testing.assert_allclose(sim.step(0.0, x, h, r=r, method="rk4"), want, rtol=0, atol=1e-15)
    assert np.array_equal(sim.step(0.0, x, h, r=r), sim.step(0.0, x, h, r=r, method="rk4"))
    with pytest.raises(gen.InputError, match="method='rk4'"):
        sim.step(0.0, x, h, method="dopri5")


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_matches_c(sims):
    from conftest import require_eigen
    require_eigen()
    rng = np.random.default_rng(6)
    for key in ("cart_pole", "seed_kane", "rolling_disc"):
        c = sims[key]
        e = gen.compile(MODELS[key](), backend="eigen")
        x = _state(c, rng)
        r = rng.uniform(-1, 1, c.nr)
        for a, b in zip(c.step_sensitivity(0.0, x, 0.02, r=r),
                        e.step_sensitivity(0.0, x, 0.02, r=r)):
            assert a.shape == b.shape and np.all(np.abs(a - b) <= 1e-12 * max(1, np.max(np.abs(a), initial=0)))
        for a, b in zip(c.jacobian(0.0, x, r=r), e.jacobian(0.0, x, r=r)):
            assert np.all(np.abs(a - b) <= 1e-12 * max(1, np.max(np.abs(a), initial=0)))
