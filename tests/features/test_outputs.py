"""Issue 15: model outputs. Model.from_kanes(..., outputs={name: expr})
compiles measured quantities with the model: sim.outputs, simulate(...,
sol.outputs), C and D of linearize_outputs, a python-control
StateSpace.

References: sympy's own expressions lambdified (the user's symbols, not the
generator's), central differences of sim.outputs on the independent state
(the dependent entries completed by consistent_state), python-control's
own evaluation of the system it receives."""
import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import cart_pole as cp
import gen
from gen.core.errors import ModelError

t = me.dynamicsymbols._t


@pytest.fixture(scope="module")
def cart():
    return gen.compile(cp.model())


def test_cart_pole_outputs_against_sympy(cart):
    km, s = cp.derive()
    consts = {s[k]: v for k, v in cp.DEFAULTS.items()}
    exprs = cp.tip_outputs(s)
    states = [s["x"], s["theta"], s["v"], s["omega"]]
    f = sm.lambdify([states, s["F"]], [e.xreplace(consts) for e in exprs.values()], "numpy")
    assert cart.output_names == ["tip_x", "tip_y"] and cart.ny == 2
    rng = np.random.default_rng(3)
    for _ in range(20):
        x = rng.uniform(-3, 3, 4)
        r = rng.uniform(-5, 5, 1)
        want = np.array(f(x, r[0]), dtype=float)
        got = cart.outputs(0.0, x, r=r)
        assert np.max(np.abs(got - want)) <= 1e-13 * max(1.0, np.max(np.abs(want)))


def test_simulate_returns_the_outputs_at_the_rows(cart):
    x0 = np.array([0.1, 0.3, 0.0, 0.2])
    sol = cart.simulate(x0, 1.0, 0.01, r=lambda tt, x: [np.sin(3 * tt)])
    t_, X, R = sol.t, sol.x, sol.r
    assert list(sol.outputs) == cart.output_names == ["tip_x", "tip_y"]
    Y = np.column_stack([sol.outputs["tip_x"], sol.outputs["tip_y"]])
    assert Y.shape == (len(t_), 2)
    # computed in C in one batch call, equal to sim.outputs row by row
    np.testing.assert_array_equal(Y, [cart.outputs(tk, xk, r=rk) for tk, xk, rk in zip(t_, X, R)])
    for k in (0, 37, len(t_) - 1):
        assert np.array_equal(Y[k], cart.outputs(t_[k], X[k], r=R[k]))
    # tip_x = x - 2 l sin(theta)
    assert np.max(np.abs(Y[:, 0] - (X[:, 0] - 2 * cp.DEFAULTS["l"] * np.sin(X[:, 1])))) < 1e-14


def _fd_CD(sim, x, r, h=1e-6):
    """C, D by central differences of sim.outputs on the independent state."""
    ind = list(sim.q_ind) + [sim.nq + i for i in sim.u_ind]
    C = np.zeros((sim.ny, sim.ns))
    for j, idx in enumerate(ind):
        xp, xm = x.copy(), x.copy()
        xp[idx] += h
        xm[idx] -= h
        if sim.mc or sim.mv:
            xp, xm = sim.consistent_state(xp), sim.consistent_state(xm)
        C[:, j] = (sim.outputs(0.0, xp, r=r) - sim.outputs(0.0, xm, r=r)) / (2 * h)
    D = np.zeros((sim.ny, sim.nr))
    for j in range(sim.nr):
        rp, rm = r.copy(), r.copy()
        rp[j] += h
        rm[j] -= h
        D[:, j] = (sim.outputs(0.0, x, r=rp) - sim.outputs(0.0, x, r=rm)) / (2 * h)
    return C, D


def measured_pendulum():
    """The seed pendulum in x, y (a configuration and a velocity
    constraint) with a force F along N.x, measured: the angle, the kinetic
    energy, and the power of F."""
    q1, q2, u1, u2, F = me.dynamicsymbols("q1 q2 u1 u2 F")
    L, m, g = sm.symbols("L m g")
    N = me.ReferenceFrame("N")
    pN = me.Point("N*")
    pN.set_vel(N, 0)
    P = pN.locatenew("P", q1 * N.x + q2 * N.y)
    P.set_vel(N, u1 * N.x + u2 * N.y)
    pP = me.Particle("pP", P, m)
    km = me.KanesMethod(N, q_ind=[q2], u_ind=[u2], q_dependent=[q1], u_dependent=[u1],
                        configuration_constraints=[q1**2 + q2**2 - L**2],
                        velocity_constraints=[q1 * u1 + q2 * u2],
                        kd_eqs=[q1.diff(t) - u1, q2.diff(t) - u2])
    km.kanes_equations([pP], [(P, m * g * N.x + F * N.y)])
    outputs = {"angle": sm.atan2(q2, q1), "kinetic": m * (u1**2 + u2**2) / 2, "power": F * u2}
    return gen.Model.from_kanes(km, constants={L: 1.0, m: 1.0, g: 9.81}, inputs=[F],
                                name="measured", outputs=outputs)


@pytest.fixture(scope="module")
def measured():
    return gen.compile(measured_pendulum())


def test_C_and_D_against_central_differences(cart, measured):
    rng = np.random.default_rng(5)
    for sim in (cart, measured):
        for _ in range(4):
            x = rng.uniform(-1, 1, sim.nx)
            if sim.mc:
                x[sim.q_ind] = rng.uniform(0.2, 0.8, len(sim.q_ind))
                x = sim.consistent_state(x)
            r = rng.uniform(-2, 2, sim.nr)
            A, B, C, D = sim.linearize_outputs(x, r=r)
            A0, B0 = sim.linearize(x, r=r)
            assert np.array_equal(A, A0) and np.array_equal(B, B0)
            Cn, Dn = _fd_CD(sim, x, r)
            assert C.shape == (sim.ny, sim.ns) and D.shape == (sim.ny, sim.nr)
            assert np.max(np.abs(C - Cn)) < 1e-7 * max(1, np.max(np.abs(C))), sim.name
            assert np.max(np.abs(D - Dn)) < 1e-7 * max(1, np.max(np.abs(D))), sim.name


def test_discrete_with_outputs(cart):
    Ad, Bd, C, D = cart.linearize_outputs(np.zeros(4), dt=0.01)
    Ad0, Bd0 = cart.linearize(np.zeros(4), dt=0.01)
    assert np.array_equal(Ad, Ad0) and np.array_equal(Bd, Bd0) and C.shape == (2, 4)


def test_to_statespace(cart, measured):
    control = pytest.importorskip("control", reason="python-control not installed "
                                                    "(pip install 'eomgen[control]')")
    sys = cart.to_statespace(np.zeros(4))
    A, B, C, D = cart.linearize_outputs(np.zeros(4))
    assert np.array_equal(sys.A, A) and np.array_equal(sys.C, C)
    assert sys.input_labels == ["F"] and sys.output_labels == ["tip_x", "tip_y"]
    assert sys.state_labels == ["x", "theta", "v", "omega"]
    # python-control's own poles are A's eigenvalues: one unstable (upright)
    assert np.max(np.real(control.poles(sys))) > 0
    # the LQR of python-control from our system equals scipy's from A, B
    K, _, _ = control.lqr(sys, cp.Q_LQR, cp.R_LQR)
    assert np.allclose(K, cp.lqr(A, B, cp.Q_LQR, cp.R_LQR), rtol=1e-8)
    sysd = cart.to_statespace(np.zeros(4), dt=0.01)
    assert sysd.dt == 0.01
    Ad, Bd = cart.linearize(np.zeros(4), dt=0.01)
    assert np.array_equal(sysd.A, Ad)
    # a model without outputs: the independent state is the output
    import seed_pendulum as sp
    seed = gen.compile(sp.kane_model())
    x = seed.consistent_state(np.array([0.6, 0.8, 0.0, 0.0]))
    s3 = seed.to_statespace(x)
    assert np.array_equal(s3.C, np.eye(seed.ns)) and s3.output_labels == s3.state_labels


def test_output_errors_name_the_problem():
    q, u = me.dynamicsymbols("q u")
    k = sm.symbols("k")
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, u * N.x)
    km = me.KanesMethod(N, q_ind=[q], u_ind=[u], kd_eqs=[q.diff(t) - u])
    km.kanes_equations([me.Particle("p", P, 1)], [(P, -k * q * N.x)])
    with pytest.raises(ModelError, match="output name '2x' must be an identifier"):
        gen.Model.from_kanes(km, constants={k: 1}, outputs={"2x": q})
    with pytest.raises(ModelError, match="output 'v' is a vector"):
        gen.Model.from_kanes(km, constants={k: 1}, outputs={"v": q * N.x})
    c = sm.Symbol("c")
    with pytest.raises(ModelError, match=r"outputs contain symbol\(s\) c"):
        gen.Model.from_kanes(km, constants={k: 1}, outputs={"y": c * q})
    with pytest.raises(ModelError, match=r"names used twice.*'q'"):
        gen.Model.from_kanes(km, constants={k: 1}, outputs={"q": q})


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_outputs(cart, measured):
    from conftest import require_eigen
    require_eigen()
    rng = np.random.default_rng(9)
    for sim, make in ((cart, cp.model), (measured, measured_pendulum)):
        e = gen.compile(make(), backend="eigen")
        for _ in range(3):
            x = rng.uniform(-1, 1, sim.nx)
            if sim.mc:
                x[sim.q_ind] = rng.uniform(0.2, 0.8, len(sim.q_ind))
                x = sim.consistent_state(x)
            r = rng.uniform(-2, 2, sim.nr)
            assert np.max(np.abs(sim.outputs(0.3, x, r=r) - e.outputs(0.3, x, r=r))) < 1e-14
            for a, b in zip(sim.linearize_outputs(x, r=r), e.linearize_outputs(x, r=r)):
                assert a.shape == b.shape and np.all(np.abs(a - b) < 1e-12)
