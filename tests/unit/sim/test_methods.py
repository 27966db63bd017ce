"""The evaluation methods generated from the interface description
(gen/sim/methods.py, issue 42): the public signatures they had when written
by hand, a docstring each, outputs of the C function's sizes (empty ones
included), fresh arrays, errors that name the argument, and numbers against
independent references (finite differences, the exact pendulum)."""
import inspect

import numpy as np
import pytest

import cart_pole
import gen
from gen.sim.methods import EVALUATIONS
from helpers import pendulum_state

# the signatures of the hand-written methods before issue 42 (the public API)
SIGNATURES = {
    "mass_matrix": "(self, q, *, p=None, t=0.0)",
    "forcing": "(self, q, u, *, r=None, p=None, t=0.0)",
    "kinematics": "(self, q, u, *, p=None, t=0.0)",
    "constraints": "(self, q, *, p=None, t=0.0)",
    "constraint_jacobian": "(self, q, *, p=None, t=0.0)",
    "velocity_constraints": "(self, q, u, *, p=None, t=0.0)",
    "velocity_constraint_matrix": "(self, q, *, p=None, t=0.0)",
    "energy": "(self, x, *, p=None, t=0.0)",
    "multipliers": "(self, t, x, *, r=None, p=None)",
    "auxiliary_forces": "(self, t, x, *, r=None, p=None)",
    "outputs": "(self, t, x, *, r=None, p=None)",
    "hybrid_values": "(self, t, x, *, p=None)",             # issue 46
    "project": "(self, x, *, p=None, t=0.0, tol=0.0, max_iter=0)",
    "consistent_state": "(self, x, *, p=None, t=0.0, tol=0.0, max_iter=0)",
    "jacobian": "(self, t, x, *, r=None, p=None)",
}


@pytest.fixture(scope="module")
def cart():
    return gen.compile(cart_pole.model())


def test_signatures_and_docstrings_are_those_of_the_api():
    assert set(EVALUATIONS) == set(SIGNATURES)
    for name, sig in SIGNATURES.items():
        fn = getattr(gen.Simulator, name)
        assert str(inspect.signature(fn)) == sig, name
        assert fn.__qualname__ == f"Simulator.{name}"
        doc = inspect.getdoc(fn)
        assert doc.splitlines()[0] == inspect.cleandoc(EVALUATIONS[name].summary).splitlines()[0]
        for section in ("Parameters", "Returns", "Raises"):
            assert f"\n{section}\n" in doc, (name, section)
    assert "A : numpy.ndarray, shape (mv, nu)\nb : numpy.ndarray, shape (mv,)" in \
        gen.Simulator.velocity_constraint_matrix.__doc__
    assert "numpy.ndarray, shape (nu, nu)" in gen.Simulator.mass_matrix.__doc__
    assert "t : float, optional" in gen.Simulator.mass_matrix.__doc__
    assert "t : float\n    Time." in gen.Simulator.multipliers.__doc__


def test_shapes_of_the_interface_and_fresh_arrays(kane_sim, cart):
    x = pendulum_state(0.4, 0.2, 1.0, "kane")
    q, u = x[:2], x[2:]
    s = kane_sim
    assert s.mass_matrix(q).shape == (2, 2) and s.forcing(q, u).shape == (2,)
    assert s.constraint_jacobian(q).shape == (1, 2)
    A, b = s.velocity_constraint_matrix(q)
    assert A.shape == (1, 2) and b.shape == (1,)
    Jx, Jr = s.jacobian(0.0, x)
    assert Jx.shape == (4, 4) and Jr.shape == (4, 0)
    assert s.auxiliary_forces(0.0, x).shape == (0,) and s.outputs(0.0, x).shape == (0,)
    assert isinstance(s.energy(x), float)
    # an unconstrained model: empty residuals and multipliers, of their true shapes
    xc = np.array([0.1, 0.2, 0.3, 0.4])
    assert cart.constraints(xc[:2]).shape == (0,)
    assert cart.constraint_jacobian(xc[:2]).shape == (0, 2)
    A, b = cart.velocity_constraint_matrix(xc[:2])
    assert A.shape == (0, 2) and b.shape == (0,)
    assert cart.multipliers(0.0, xc).shape == (0,) and cart.outputs(0.0, xc).shape == (2,)
    a, b2 = s.mass_matrix(q), s.mass_matrix(q)
    assert not np.shares_memory(a, b2)
    x_in = x.copy()
    s.project(x_in + 0.01)
    assert np.array_equal(x_in, x)                   # project writes a copy


def test_numbers_against_independent_references(kane_sim, cart):
    x = pendulum_state(0.7, -0.4, 1.0, "kane")
    s = kane_sim
    # the seed pendulum's energy is conserved along its exact motion: along a fine
    # RK4 run, to 1e-9
    t, X = s.simulate(x, 1.0, 1e-3)
    E = np.array([s.energy(xi) for xi in X])
    assert np.ptp(E) < 1e-9 * max(1.0, abs(E[0]))
    # the Jacobian against central differences of rhs (every entry of x free)
    Jx, _ = s.jacobian(0.3, x)
    h = 1e-6
    fd = np.column_stack([(s.rhs(0.3, x + h * e) - s.rhs(0.3, x - h * e)) / (2 * h)
                          for e in np.eye(4)])
    np.testing.assert_allclose(Jx, fd, rtol=1e-6, atol=1e-6)
    # the cart-pole: u' = M^-1 f, what rhs integrates; q' = u (kinematics)
    xc, r = np.array([0.1, 0.2, 0.3, -0.4]), np.array([0.7])
    M, f = cart.mass_matrix(xc[:2]), cart.forcing(xc[:2], xc[2:], r=r)
    np.testing.assert_allclose(cart.rhs(0.0, xc, r=r)[2:], np.linalg.solve(M, f), rtol=1e-13)
    np.testing.assert_array_equal(cart.kinematics(xc[:2], xc[2:]), xc[2:])
    # a consistent state from a dict: on the circle of radius L, the branch of the guess
    xs = s.consistent_state({"q2": 0.6, "q1": 0.5})
    assert abs(xs[0] ** 2 + xs[1] ** 2 - 1.0) < 1e-14 and xs[1] > 0
    assert abs(s.velocity_constraints(xs[:2], xs[2:])[0]) < 1e-14


def test_errors_name_the_argument(kane_sim, cart):
    s = kane_sim
    with pytest.raises(gen.InputError, match=r"coordinates q must have shape \(2,\), got \(3,\)"):
        s.mass_matrix([0.1, 0.2, 0.3])
    with pytest.raises(gen.InputError, match=r"speeds u must have shape \(2,\)"):
        s.forcing([0.6, 0.8], [0.0])
    with pytest.raises(gen.InputError, match=r"eval_mass_matrix: q\[1\] = nan"):
        s.mass_matrix([0.6, np.nan])
    with pytest.raises(gen.InputError, match=r"eval_energy: x\[2\] = inf \(u2\)") as e:
        s.energy([0.6, 0.8, np.inf, 0.0])
    assert e.value.argument == "x" and e.value.index == 2
    with pytest.raises(gen.InputError, match=r"constants p must have shape \(3,\)"):
        s.constraints([0.6, 0.8], p=[1.0])
    with pytest.raises(gen.InputError, match="unknown name 'q9'"):
        s.project({"q9": 1.0})
    with pytest.raises(gen.InputError, match="model 'cart_pole' was built without energy="):
        cart.energy(np.zeros(4))
    with pytest.raises(gen.SingularError) as e:        # atan(q2/q1) at q1 = 0
        s.multipliers(0.5, np.array([1.0, 0.0, 0.0, 0.0]))
    assert e.value.time == 0.5 and list(e.value.state) == [1.0, 0.0, 0.0, 0.0]
