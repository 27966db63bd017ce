"""The Python call path of Simulator.rhs (issue 17): the fast path (an
ndarray state of the model's dtype and shape, inputs as such an array or
None) gives exactly the general path's numbers (out=, lists, strided views,
other dtypes), and bad values still raise with the model's names."""
import numpy as np
import pytest

import cart_pole
import gen
from helpers import pendulum_state


@pytest.fixture(scope="module")
def cart():
    return gen.compile(cart_pole.model())


def test_fast_path_equals_general_path(kane_sim, cart):
    x = pendulum_state(0.3, 0.1, 1.0, "kane")
    ref = np.empty(4)
    kane_sim.rhs(0.0, x, out=ref)                       # the general path
    assert np.array_equal(kane_sim.rhs(0.0, x), ref)
    assert np.array_equal(kane_sim.rhs(0.0, list(x)), ref)
    v = np.zeros(8)
    v[::2] = x
    assert np.array_equal(kane_sim.rhs(0.0, v[::2]), ref)   # strided: general path
    assert np.array_equal(kane_sim.rhs(0.0, x.astype(np.float32).astype(float)),
                          kane_sim.rhs(0.0, x.astype(np.float32)))
    xc, r = np.array([0.1, 0.2, 0.3, 0.4]), np.array([0.5])
    refc = np.empty(4)
    cart.rhs(0.0, xc, r=r, out=refc)
    assert np.array_equal(cart.rhs(0.0, xc, r=r), refc)
    assert np.array_equal(cart.rhs(0.0, xc, r=[0.5]), refc)
    assert np.array_equal(cart.rhs(0.0, xc, r=0.5), refc)
    # the independent reference: M u' = f at this state, from the model's own M and f
    M = cart.mass_matrix(xc[:2])
    f = cart.forcing(xc[:2], xc[2:], r=r)
    np.testing.assert_allclose(refc[2:], np.linalg.solve(M, f), rtol=1e-13)
    np.testing.assert_array_equal(refc[:2], xc[2:])
    # a fresh array every call (solve_ivp keeps them)
    a, b = cart.rhs(0.0, xc, r=r), cart.rhs(0.0, xc + 0.1, r=r)
    assert not np.shares_memory(a, b)


def test_fast_path_still_refuses_bad_values(cart):
    xc = np.array([0.1, 0.2, 0.3, 0.4])
    with pytest.raises(ValueError, match="NaN or infinite"):
        cart.rhs(0.0, xc, r=np.array([np.nan]))
    with pytest.raises(ValueError, match="NaN or infinite"):
        cart.rhs(0.0, np.array([0.1, np.inf, 0.3, 0.4]), r=np.array([0.5]))
    with pytest.raises(ValueError, match="inputs r"):
        cart.rhs(0.0, xc, r=np.array([0.5, 0.5]))


def test_fused_rhs_failure_names_the_cause_and_writes_nothing(cart):
    """eval_rhs calls the fused kernel without M and f and checks only u'
    (q' is the checked u): a u' that overflows and a singular mass matrix
    are still found, named, and the output buffer keeps its contents."""
    out = np.full(4, 7.0)
    # omega^2 overflows in the forcing: u' is not finite while x is
    with pytest.raises(gen.DivergenceError) as e:
        cart.rhs(0.0, np.array([0.1, 0.2, 0.3, 1e200]), r=np.array([0.5]), out=out)
    assert e.value.status_name == "ERR_DIVERGED" and "omega=1e+200" in str(e.value)
    assert np.array_equal(out, np.full(4, 7.0))
    # a massless pole: M = [[m_c, 0], [0, 0]] has a zero pivot
    with pytest.raises(gen.SingularError) as e:
        cart.rhs(0.0, np.array([0.1, 0.2, 0.3, 0.4]), r=np.array([0.5]),
                 p=[1.0, 0.0, 0.5, 9.81], out=out)
    assert e.value.status_name == "ERR_SINGULAR"
    assert np.array_equal(out, np.full(4, 7.0))
    # and next to the failures, a regular call: M u' = f from the model's M and f
    x = np.array([0.1, 0.2, 0.3, 0.4])
    ud = cart.rhs(0.0, x, r=np.array([0.5]), out=out)[2:]
    np.testing.assert_allclose(ud, np.linalg.solve(cart.mass_matrix(x[:2]),
                                                   cart.forcing(x[:2], x[2:], r=[0.5])), rtol=1e-13)


def test_host_fast_path_is_taken_and_exact(kane_sim, cart):
    """The host module's CPython function (csrc/host/gen_host_fast.c) is
    bound to the model, gives the general path's numbers for the usual
    arguments (a numpy float t, as solve_ivp passes, a read-only x), and
    declines (None) whatever it does not take: a subclass of ndarray, the
    wrong size or dtype, a failing status; Simulator.rhs then answers."""
    fast = kane_sim._rhs_fast
    assert fast is not None
    x = pendulum_state(0.3, 0.1, 1.0, "kane")
    ref = np.empty(4)
    kane_sim.rhs(0.0, x, out=ref)
    assert np.array_equal(fast(0.0, x, None), ref)
    assert np.array_equal(fast(np.float64(0.0), x, None), ref)
    xr = x.copy()
    xr.flags.writeable = False
    assert np.array_equal(fast(0, xr, None), ref)
    assert fast(0.0, x.view(np.recarray), None) is None
    assert fast(0.0, x[:3], None) is None
    assert fast(0.0, x.astype(np.float32), None) is None
    assert fast(0.0, x * np.nan, None) is None
    assert fast("0", x, None) is None
    with pytest.raises(TypeError):
        fast(0.0)
    xc, r = np.array([0.1, 0.2, 0.3, 0.4]), np.array([0.5])
    refc = np.empty(4)
    cart.rhs(0.0, xc, r=r, out=refc)
    assert np.array_equal(cart._rhs_fast(0.0, xc, r), refc)
    assert cart._rhs_fast(0.0, xc, np.array([0.5, 0.5])) is None


def test_host_fast_path_float_model():
    """A float model's fast path takes float32 arrays, and matches its
    general path; a float64 state takes the general path (converted)."""
    sim = gen.compile(cart_pole.model(), real="float")
    xc, r = np.array([0.1, 0.2, 0.3, 0.4], dtype=np.float32), np.array([0.5], np.float32)
    ref = np.empty(4, dtype=np.float32)
    sim.rhs(0.0, xc, r=r, out=ref)
    out = sim._rhs_fast(0.0, xc, r)
    assert out.dtype == np.float32 and np.array_equal(out, ref)
    assert sim._rhs_fast(0.0, xc.astype(float), r) is None
    np.testing.assert_array_equal(sim.rhs(0.0, xc.astype(float), r=r), ref)


def test_host_fast_batch_is_taken_and_exact(cart):
    """rhs_batch's CPython function (csrc/host/gen_host_fast.c): for a
    number t and exact arrays (X (N, nx), r and p vectors or None, out None
    or (N, nx)) it gives each state's rhs, into out when given; whatever it
    does not take (per-state r or p, an array t, a strided or read-only or
    mistyped array, a failing state) it declines, and Simulator.rhs_batch
    then takes the general path, which names the failing state."""
    fast = cart._rhs_batch_fast
    assert fast is not None
    rng = np.random.default_rng(11)
    X = rng.uniform(-1, 1, (25, 4))
    r, p = np.array([0.5]), cart.constants * 1.2
    ref = np.array([cart.rhs(0.0, x, r=r, p=p) for x in X])
    # independent: M u' = f from the model's own M and f, q' = u
    for x, d in zip(X[:3], ref[:3]):
        M, f = cart.mass_matrix(x[:2], p=p), cart.forcing(x[:2], x[2:], r=r, p=p)
        np.testing.assert_allclose(d[2:], np.linalg.solve(M, f), rtol=1e-13)
        assert np.array_equal(d[:2], x[2:])
    got = fast(0.0, X, r, p, None)
    assert got.shape == X.shape and np.array_equal(got, ref)
    out = np.full_like(X, 7.0)
    assert fast(0, X, r, p, out) is out and np.array_equal(out, ref)
    assert np.array_equal(fast(0.0, X, None, None, None),
                          np.array([cart.rhs(0.0, x) for x in X]))
    assert fast(0.0, X[:0], r, p, None).shape == (0, 4)
    # declined
    assert fast(np.zeros(25), X, r, p, None) is None                     # t per state
    assert fast(0.0, X, np.tile(r, (25, 1)), p, None) is None             # r per state
    assert fast(0.0, X, r, np.tile(p, (25, 1)), None) is None             # p per state
    assert fast(0.0, np.asfortranarray(X), r, p, None) is None
    assert fast(0.0, X[:, :3], r, p, None) is None
    assert fast(0.0, X.astype(np.float32), r, p, None) is None
    ro = np.empty_like(X)
    ro.flags.writeable = False
    assert fast(0.0, X, r, p, ro) is None
    assert fast(0.0, X, r, p, np.empty((24, 4))) is None
    bad = X.copy()
    bad[7, 1] = np.nan
    assert fast(0.0, bad, r, p, None) is None
    with pytest.raises(TypeError):
        fast(0.0, X)
    # Simulator.rhs_batch: the same numbers by either path, and the failing state named
    assert np.array_equal(cart.rhs_batch(0.0, X, r=r, p=p), ref)
    assert np.array_equal(cart.rhs_batch(np.zeros(25), X, r=r, p=np.tile(p, (25, 1))), ref)
    with pytest.raises(ValueError, match="state 7 of 25"):
        cart.rhs_batch(0.0, bad, r=r, p=p)
