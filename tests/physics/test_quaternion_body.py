"""A configuration constraint without a dependent speed: sympy's
test_implicit_kinematics body (examples/quaternion_body.py), whose unit
quaternion norm is kept by the kinematic equations (lambda . lambda' = 0 is
one of them) and by projection. Checked: the right-hand side against
sympy's own mass_matrix_full / forcing_full solve; 10 s of tumbling flight
on the unit sphere (norm error < 1e-12) with and without projection; the
12-state linearization against central differences along the manifold; a
constraint whose derivative the kinematics do not keep is refused."""
import numpy as np
import pytest
import sympy as sm

import gen
import quaternion_body as qb


@pytest.fixture(scope="module")
def setup():
    km, consts, inputs = qb.derive()
    model = gen.Model.from_kanes(km, constants=consts, inputs=inputs, name="quat_body")
    return km, consts, inputs, model, gen.compile(model)


def _state(sim, rng):
    x = np.zeros(sim.nx)
    lam = rng.normal(size=4)
    lam /= np.linalg.norm(lam)
    for i in range(4):
        x[sim.state_names.index(f"lambda_{i}")] = lam[i]
    x[sim.nq:] = rng.uniform(-1, 1, sim.nu)
    x[3:6] = rng.uniform(-1, 1, 3)
    return x


def test_rhs_matches_sympy_full_solve(setup):
    km, consts, inputs, model, sim = setup
    rng = np.random.default_rng(7)
    qs = list(km.q) + list(km.u)
    f = sm.lambdify([qs, inputs], (km.mass_matrix_full.xreplace(consts),
                                   km.forcing_full.xreplace(consts)), "numpy")
    for _ in range(5):
        x = _state(sim, rng)
        r = rng.uniform(-1, 1, 2)
        MM, FF = f(list(x), list(r))
        ref = np.linalg.solve(np.array(MM, float), np.array(FF, float).ravel())
        got = sim.rhs(0.0, x, r=r)
        assert np.max(np.abs(got - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref)))


@pytest.mark.parametrize("project", [True, False])
def test_flight_stays_on_the_unit_sphere(setup, project):
    sim = setup[-1]
    x = _state(sim, np.random.default_rng(1))
    t, X = sim.simulate(x, 10.0, 1e-3, r=[0.05, -5.0], project=project)
    lam = X[:, [sim.state_names.index(f"lambda_{i}") for i in range(4)]]
    assert np.max(np.abs(np.sum(lam ** 2, axis=1) - 1)) < 1e-12
    assert np.ptp(lam[:, 0]) > 0.1                    # it really tumbles


def test_linearization_on_the_independent_state(setup):
    sim = setup[-1]
    assert sim.ns == 12 and "lambda_0" not in sim.independent_state_names
    x0 = sim.consistent_state(_state(sim, np.random.default_rng(3)))
    r0 = np.array([0.1, -3.0])
    A, B = sim.linearize(x0, r=r0)
    ind = [sim.state_names.index(n) for n in sim.independent_state_names]

    def f(z, r):
        x = x0.copy()
        x[ind] = z
        x = sim.consistent_state(x)             # lambda_0 from the others
        return sim.rhs(0.0, x, r=r)[ind]

    z0, h = x0[ind], 1e-6
    A_fd = np.column_stack([(f(z0 + h * e, r0) - f(z0 - h * e, r0)) / (2 * h)
                            for e in np.eye(len(z0))])
    B_fd = np.column_stack([(f(z0, r0 + h * e) - f(z0, r0 - h * e)) / (2 * h)
                            for e in np.eye(2)])
    assert np.max(np.abs(A - A_fd)) <= 1e-7 * max(1.0, np.max(np.abs(A)))
    assert np.max(np.abs(B - B_fd)) <= 1e-7 * max(1.0, np.max(np.abs(B)))


def test_constraint_not_kept_by_the_kinematics_is_refused():
    """x^2 + y^2 = L^2 with q' = u and no velocity constraint: its derivative
    2 (x u_x + y u_y) is not zero, so a dependent speed is required."""
    from sympy.physics import mechanics as me
    x, y, ux, uy = me.dynamicsymbols("x y ux uy")
    L, m = sm.symbols("L m")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, ux * N.x + uy * N.y)
    km = me.KanesMethod(N, q_ind=[y], u_ind=[ux, uy], q_dependent=[x],
                        configuration_constraints=[x ** 2 + y ** 2 - L ** 2],
                        kd_eqs=[x.diff() - ux, y.diff() - uy])
    km.kanes_equations([me.Particle("p", P, m)], [])
    with pytest.raises(gen.ModelError, match="does not follow from the kinematic equations"):
        gen.Model.from_kanes(km, constants={L: 1.0, m: 1.0}, name="drifting")
