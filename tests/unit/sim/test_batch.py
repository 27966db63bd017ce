"""Issue 7: batch entry points (N states in one C call) and the threaded
batch simulation agree exactly with the one-state calls."""
import numpy as np
import pytest

import gen
import n_link_cart
from helpers import pendulum_state


@pytest.fixture(scope="module")
def cart():
    return gen.compile(n_link_cart.model(3))


def test_rhs_batch_equals_single_calls(cart):
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (50, cart.nx))
    F = rng.uniform(-1, 1, (50, 1))
    t = rng.uniform(0, 1, 50)
    ref = np.array([cart.rhs(ti, x, r=f) for ti, x, f in zip(t, X, F)])
    assert np.array_equal(cart.rhs_batch(t, X, r=F), ref)
    assert np.array_equal(cart.rhs(t, X, r=F), ref)              # (N, nx) through rhs
    out = np.empty_like(ref)
    assert cart.rhs_batch(t, X, r=F, out=out) is out
    # one input vector and one parameter vector shared by every state
    p = cart.constants * 1.1
    ref2 = np.array([cart.rhs(0.0, x, r=[0.3], p=p) for x in X])
    assert np.array_equal(cart.rhs_batch(0.0, X, r=[0.3], p=p), ref2)
    # per-state parameters
    P = np.tile(cart.constants, (50, 1)) * rng.uniform(0.8, 1.2, (50, 1))
    ref3 = np.array([cart.rhs(0.0, x, r=None, p=pi) for x, pi in zip(X, P)])
    assert np.array_equal(cart.rhs_batch(0.0, X, r=None, p=P), ref3)


def test_rhs_out_preallocated(cart):
    x = np.full(cart.nx, 0.2)
    out = np.empty(cart.nx)
    assert cart.rhs(0.0, x, out=out) is out
    assert np.array_equal(out, cart.rhs(0.0, x))
    with pytest.raises(ValueError, match="out must be"):
        cart.rhs(0.0, x, out=np.empty(3))


def test_mass_matrix_and_linearize_batch(cart):
    rng = np.random.default_rng(1)
    X = rng.uniform(-1, 1, (20, cart.nx))
    M = cart.mass_matrix_batch(X[:, :cart.nq])
    assert np.array_equal(M, np.array([cart.mass_matrix(x[:cart.nq]) for x in X]))
    assert np.array_equal(cart.mass_matrix_batch(X), M)         # states work too
    A, B = cart.linearize_batch(X, r=[0.5])
    for k, x in enumerate(X):
        a, b = cart.linearize(x, r=[0.5])
        assert np.array_equal(A[k], a) and np.array_equal(B[k], b)


def test_batch_errors_name_the_state(kane_sim):
    X = np.array([pendulum_state(0.3, 0.0, 1.0, "kane"), [1.0, 0.0, 0.0, 0.0]])
    with pytest.raises(gen.SingularError, match="state 1 of 2"):
        kane_sim.rhs_batch(0.0, X)
    X[0, 2] = np.nan
    with pytest.raises(ValueError, match="state 0 of 2.*NaN"):
        kane_sim.rhs_batch(0.0, X)
    with pytest.raises(ValueError, match=r"shape \(N, 4\)"):
        kane_sim.rhs_batch(0.0, np.zeros((3, 5)))
    with pytest.raises(ValueError, match=r"inputs r must have shape"):
        kane_sim.rhs_batch(0.0, np.zeros((3, 4)), r=np.zeros((2, 1)))


def test_ensemble_rows_match_serial(cart):
    """ensemble(reduce="rows") keeps every row of every run (what
    simulate_batch did), each run exactly its simulate."""
    rng = np.random.default_rng(2)
    X0 = rng.uniform(-0.5, 0.5, (6, cart.nx))
    P = np.tile(cart.constants, (6, 1)) * rng.uniform(0.9, 1.1, (6, 1))
    res = cart.ensemble(X0, 1.0, 0.01, p=P, method="dopri5", workers=2, reduce="rows")
    t, X = res.t, res["rows"]
    assert X.shape == (6, len(t), cart.nx)
    for i in range(6):
        ti, Xi = cart.simulate(X0[i], 1.0, 0.01, p=P[i], method="dopri5")
        assert np.array_equal(ti, t) and np.array_equal(Xi, X[i])
    # one initial state, many parameter sets
    X = cart.ensemble(X0[0], 0.5, 0.01, p=P, reduce="rows").rows
    assert X.shape[0] == 6 and not np.array_equal(X[0], X[1])
