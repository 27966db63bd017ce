"""gen.MPC (issue 43) against independent references: the QP of a linear
model against Clarabel on the same QP written densely in numpy (the RK4
step of a linear ODE written as its matrix series), the converged SQP
against CasADi + IPOPT on the same NLP, the closed loop of the cart-pole
(in Python and closed in C by sim.simulate), and bad input.

The acados comparison (the same controller, 200-step closed loops, times)
is bench/bench_mpc.py: acados lives in a venv of its own."""
import importlib
import os

import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import cart_pole as cp
import gen

PERIOD, N_CP = 0.05, 20


def need(name, why):
    """An independent tool from PyPI (pyproject's test extra): skipped with
    the reason on a machine without it, a failure under CI."""
    if os.environ.get("CI") == "true":
        return importlib.import_module(name)
    return pytest.importorskip(name, reason=why)


Q_CP = np.diag([10.0, 10.0, 0.1, 0.1])
R_CP = np.array([[0.05]])
P_CP = 5 * Q_CP
X0_CP = np.array([0.0, 0.4, 0.0, 0.0])


@pytest.fixture(scope="module")
def cart():
    return cp.model()


@pytest.fixture(scope="module")
def rti(cart):
    return gen.MPC(cart, N_CP, PERIOD, Q_CP, R_CP, P=P_CP, bounds={"F": (-20.0, 20.0)})


# ------------------------------------------------------------------ the QP
def chain(m, seed):
    """m masses in a chain (springs, dampers), a force on some of them: a
    linear model x' = Ac x + Bc r with random coefficients; (model, Ac, Bc)."""
    rng = np.random.default_rng(seed)
    q = me.dynamicsymbols(f"q0:{m}")
    u = me.dynamicsymbols(f"u0:{m}")
    nr = max(1, m // 2)
    r = me.dynamicsymbols(f"F0:{nr}")
    k = rng.uniform(0.5, 3.0, m + 1)
    c = rng.uniform(0.0, 0.3, m)
    mass = rng.uniform(0.5, 2.0, m)
    at = rng.choice(m, nr, replace=False)
    K = np.zeros((m, m))
    for i in range(m):
        K[i, i] = k[i] + k[i + 1]
        if i + 1 < m:
            K[i, i + 1] = K[i + 1, i] = -k[i + 1]
    Bf = np.zeros((m, nr))
    Bf[at, np.arange(nr)] = 1.0
    f = (-sm.Matrix(K) * sm.Matrix(q) - sm.Matrix(np.diag(c)) * sm.Matrix(u)
         + sm.Matrix(Bf) * sm.Matrix(r))
    kin = sm.Matrix([q[i].diff() - u[i] for i in range(m)])
    model = gen.Model.from_matrices(sm.diag(*[sm.Float(v) for v in mass]), sm.Matrix(f), q, u, kin, inputs=r,
                                    name=f"chain{m}")
    Minv = np.diag(1 / mass)
    Ac = np.block([[np.zeros((m, m)), np.eye(m)], [-Minv @ K, -Minv @ np.diag(c)]])
    Bc = np.vstack([np.zeros((m, nr)), Minv @ Bf])
    return model, Ac, Bc


def rk4_matrices(Ac, Bc, h):
    """One classic RK4 step of x' = Ac x + Bc r (r held): x+ = Ad x + Bd r."""
    hA = h * Ac
    n = len(Ac)
    Ad = np.eye(n) + hA + hA @ hA / 2 + hA @ hA @ hA / 6 + hA @ hA @ hA @ hA / 24
    Bd = h * (np.eye(n) + hA / 2 + hA @ hA / 6 + hA @ hA @ hA / 24) @ Bc
    return Ad, Bd


def clarabel_mpc(Ad, Bd, N, period, Q, R, P, x0, ubox, xbox, penalty):
    """The linear MPC's QP, dense, solved by Clarabel: z = [x_1..x_N,
    u_0..u_{N-1}, slacks (two per state bound, stages 1..N)]; (X, U, J)."""
    clarabel = need("clarabel", "Clarabel, the independent QP solver")
    import scipy.sparse as sp
    nx, nu = Bd.shape
    nX, nU = N * nx, N * nu
    ib, lbx, ubx = xbox
    nb = len(ib)
    nS = 2 * N * nb
    nz = nX + nU + nS
    H = np.zeros((nz, nz))
    for k in range(N):
        H[nX + k * nu:nX + (k + 1) * nu, nX + k * nu:nX + (k + 1) * nu] = 2 * period * R
        W = 2 * (P if k == N - 1 else period * Q)
        H[k * nx:(k + 1) * nx, k * nx:(k + 1) * nx] = W
    c = np.zeros(nz)
    c[nX + nU:] = penalty
    const = period * x0 @ Q @ x0            # stage 0's state cost
    # dynamics: x_{k+1} - Ad x_k - Bd u_k = 0
    Aeq = np.zeros((nX, nz))
    beq = np.zeros(nX)
    for k in range(N):
        Aeq[k * nx:(k + 1) * nx, k * nx:(k + 1) * nx] = np.eye(nx)
        Aeq[k * nx:(k + 1) * nx, nX + k * nu:nX + (k + 1) * nu] = -Bd
        if k:
            Aeq[k * nx:(k + 1) * nx, (k - 1) * nx:k * nx] = -Ad
        else:
            beq[:nx] = Ad @ x0
    rows, rhs = [], []
    iu, lbu, ubu = ubox
    for k in range(N):
        for j, i in enumerate(iu):
            e = np.zeros(nz)
            e[nX + k * nu + i] = 1
            rows += [e, -e]
            rhs += [ubu[j], -lbu[j]]
        for j, i in enumerate(ib):
            s_lo, s_hi = nX + nU + 2 * (k * nb + j), nX + nU + 2 * (k * nb + j) + 1
            e = np.zeros(nz)
            e[k * nx + i] = 1
            e_hi, e_lo = e.copy(), -e
            e_hi[s_hi] = -1
            e_lo[s_lo] = -1
            rows += [e_hi, e_lo]
            rhs += [ubx[j], -lbx[j]]
    for s in range(nS):
        e = np.zeros(nz)
        e[nX + nU + s] = -1
        rows.append(e)
        rhs.append(0.0)
    A = sp.csc_matrix(np.vstack([Aeq, np.array(rows)]))
    b = np.r_[beq, rhs]
    cones = [clarabel.ZeroConeT(nX), clarabel.NonnegativeConeT(len(rows))]
    st = clarabel.DefaultSettings()
    st.verbose = False
    st.tol_gap_abs = st.tol_gap_rel = st.tol_feas = 1e-12
    st.tol_ktratio = 1e-10
    st.static_regularization_constant = 1e-13
    st.iterative_refinement_max_iter = 50
    st.max_iter = 400
    sol = clarabel.DefaultSolver(sp.csc_matrix(np.triu(H)), c, A, b, cones, st).solve()
    assert str(sol.status) == "Solved", sol.status
    z = polish(H, c, Aeq, beq, np.array(rows), np.array(rhs), np.array(sol.x),
               np.array(sol.z)[nX:])
    X = np.vstack([x0, z[:nX].reshape(N, nx)])
    U = z[nX:nX + nU].reshape(N, nu)
    return X, U, sol.obj_val + const


def polish(H, c, Aeq, beq, G, h, z, y):
    """Clarabel's solution polished as OSQP polishes its own: the
    inequalities with a positive multiplier taken as equalities, the KKT
    system of that equality-constrained QP solved densely; kept when it
    is feasible and its multipliers keep their signs."""
    act = np.nonzero(y > 1e-9 * max(1.0, np.max(y)))[0]
    E = np.vstack([Aeq, G[act]])
    K = np.block([[H, E.T], [E, np.zeros((len(E), len(E)))]])
    sol = np.linalg.solve(K, np.r_[-c, beq, h[act]])
    zp, lam = sol[:len(z)], sol[len(z) + len(Aeq):]
    if np.all(G @ zp - h <= 1e-11) and np.all(lam >= -1e-9):
        return zp
    return z


def objective(X, U, period, Q, R, P, xbox, penalty):
    """J of the issue (and the soft bounds' L1 penalties) at (X, U)."""
    J = sum(period * (x @ Q @ x + u @ R @ u) for x, u in zip(X[:-1], U)) + X[-1] @ P @ X[-1]
    ib, lbx, ubx = xbox
    for x in X[1:]:
        for j, i in enumerate(ib):
            J += penalty * (max(0.0, x[i] - ubx[j]) + max(0.0, lbx[j] - x[i]))
    return J


@pytest.mark.slow
@pytest.mark.parametrize("m, N, count", [(2, 10, 34), (4, 30, 33), (6, 50, 33)],
                         ids=["nx4-N10", "nx8-N30", "nx12-N50"])
def test_qp_against_clarabel(m, N, count):
    """100 random stage-wise QPs over three linear models (states 4 to 12,
    horizons 10 to 50), input bounds active and soft state bounds: one
    RTI from the zero guess solves the linear MPC's QP, whose solution
    and objective equal Clarabel's on the dense QP to 1e-7."""
    model, Ac, Bc = chain(m, seed=m)
    nx, nr = 2 * m, Bc.shape[1]
    rng = np.random.default_rng(100 + m)
    L = rng.normal(size=(nx, nx))
    Q = L @ L.T / nx + 0.1 * np.eye(nx)
    R = np.diag(rng.uniform(1.0, 5.0, nr))
    P = 3 * Q
    umax = 0.3
    bounds = {model.input_names[i]: (-umax, umax) for i in range(nr)}
    bounds[model.state_names[0]] = (-0.6, 0.6)
    penalty = 10.0
    mpc = gen.MPC(model, N, PERIOD, Q, R, P=P, bounds=bounds, penalty=penalty)
    Ad, Bd = rk4_matrices(Ac, Bc, PERIOD)
    ubox = (list(range(nr)), [-umax] * nr, [umax] * nr)
    xbox = ([0], [-0.6], [0.6])
    active = 0
    for _ in range(count):
        x0 = rng.normal(size=nx) * rng.uniform(0.5, 2.0)
        mpc.reset()
        u = mpc(x0, t=0.0)
        assert mpc.status == 0, mpc.message
        X, U, J = clarabel_mpc(Ad, Bd, N, PERIOD, Q, R, P, x0, ubox, xbox, penalty)
        scale = max(1.0, np.max(np.abs(X)), np.max(np.abs(U)))
        assert np.max(np.abs(mpc.u - U)) <= 1e-7 * scale
        assert np.max(np.abs(mpc.x - X)) <= 1e-7 * scale
        np.testing.assert_allclose(u, U[0], rtol=0, atol=1e-7 * scale)
        Jm = objective(mpc.x, mpc.u, PERIOD, Q, R, P, xbox, penalty)
        assert abs(Jm - J) <= 1e-7 * max(1.0, abs(J))
        active += int(np.any(np.abs(np.abs(U) - umax) < 1e-9))
    assert active >= count // 2         # the bounds are active in most


# ------------------------------------------------------------------ SQP vs IPOPT
def casadi_rhs(model, x, u):
    """The model's x' = f(x, u) as CasADi expressions, from its sympy
    equations (q' = u here, u' = M^-1 f), the constants substituted."""
    cs = need("casadi", "CasADi + IPOPT, the independent NLP solver")
    m = model
    sub = dict(zip(m.p, m.p_values))
    ud = m.M.LUsolve(m.f)
    xs = sm.symbols(f"x0:{m.nx}")
    us = sm.symbols(f"u0:{m.nr}")
    ren = {**dict(zip(list(m.q) + list(m.u), xs)), **dict(zip(m.r, us)), m.t: 0}
    env = {"sin": cs.sin, "cos": cs.cos, **{f"x{i}": x[i] for i in range(m.nx)},
           **{f"u{i}": u[i] for i in range(m.nr)}}
    exprs = [str(sm.sympify(e).xreplace(sub).xreplace(ren)) for e in list(m.u) + list(ud)]
    exprs[:m.nq] = [f"x{m.nq + i}" for i in range(m.nq)]      # q' = u (the kinematics)
    return cs.vertcat(*[eval(e, env) for e in exprs])  # noqa: S307 (our own printout)


@pytest.mark.slow
def test_sqp_against_ipopt(cart):
    """method='sqp' with active input bounds: controls and predicted states
    equal CasADi + IPOPT's solution of the same NLP (the same RK4 shooting,
    cost and bounds) to 1e-6."""
    cs = need("casadi", "CasADi + IPOPT, the independent NLP solver")
    mpc = gen.MPC(cart, N_CP, PERIOD, Q_CP, R_CP, P=P_CP, bounds={"F": (-20.0, 20.0)},
                  method="sqp", max_iter=100)
    u0 = mpc(X0_CP, t=0.0)
    assert mpc.status == 0, mpc.message
    assert mpc.iterations > 1
    xs, us = cs.SX.sym("x", 4), cs.SX.sym("u", 1)
    f = cs.Function("f", [xs, us], [casadi_rhs(cart, xs, us)])
    U = cs.SX.sym("U", N_CP)
    x, h, J = cs.DM(X0_CP), PERIOD, 0
    X = [x]
    for k in range(N_CP):
        J += PERIOD * (cs.mtimes([x.T, Q_CP, x]) + R_CP[0, 0] * U[k] ** 2)
        k1 = f(x, U[k])
        k2 = f(x + h / 2 * k1, U[k])
        k3 = f(x + h / 2 * k2, U[k])
        k4 = f(x + h * k3, U[k])
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        X.append(x)
    J += cs.mtimes([x.T, P_CP, x])
    solver = cs.nlpsol("s", "ipopt", {"x": U, "f": J},
                       {"ipopt.print_level": 0, "print_time": 0, "ipopt.tol": 1e-12,
                        "ipopt.sb": "yes", "ipopt.bound_relax_factor": 0.0})
    sol = solver(x0=np.zeros(N_CP), lbx=-20.0, ubx=20.0)
    assert solver.stats()["success"]
    Uref = np.array(sol["x"]).ravel()
    Xref = np.array(cs.Function("X", [U], [cs.horzcat(*X)])(Uref)).T
    assert np.sum(np.abs(np.abs(Uref) - 20) < 1e-8) >= 1      # a bound active
    np.testing.assert_allclose(mpc.u.ravel(), Uref, rtol=0, atol=1e-6)
    np.testing.assert_allclose(mpc.x, Xref, rtol=0, atol=1e-6)
    assert u0[0] == pytest.approx(Uref[0], abs=1e-6)


# ------------------------------------------------------------------ closed loop
@pytest.mark.slow
def test_cart_pole_closed_loop_python_and_c(cart, rti):
    """RTI stabilizes the cart-pole from 0.4 rad with |F| <= 20 (active at
    first); the loop closed in C by sim.simulate applies the same controls
    as the Python loop against the model's own step."""
    sim = gen.compile(cart, derivatives=True)
    x, h, us = X0_CP.copy(), PERIOD / 10, []
    rti.reset()
    for k in range(100):
        u = rti(x, t=k * PERIOD)
        assert rti.status == 0, rti.message
        assert rti.iterations == 1
        assert rti.times.feedback > 0 and rti.times.prepare > 0
        assert rti.x.shape == (N_CP + 1, 4) and rti.u.shape == (N_CP, 1)
        us.append(u)
        for j in range(10):
            x = sim.step(k * PERIOD + j * h, x, h, r=u)
    us = np.array(us)
    assert np.max(np.abs(us)) == pytest.approx(20.0)      # the bound, active
    assert np.all(np.abs(us) <= 20.0 + 1e-9)
    assert np.max(np.abs(x)) < 1e-3                        # upright, at rest
    sol = sim.simulate(X0_CP, 100 * PERIOD, h, controller=rti)
    np.testing.assert_allclose(sol.r[::10][:100], us, rtol=0, atol=1e-8)


# ------------------------------------------------------------------ statuses
@pytest.mark.slow
def test_infeasible_start_and_qp_failure_status(cart):
    """A start outside the soft state bounds gives a control, not a
    failure; a QP stopped by its iteration cap reports ERR_QP_MAX_ITER
    through Python, with a finite control."""
    mpc = gen.MPC(cart, N_CP, PERIOD, Q_CP, R_CP, P=P_CP,
                  bounds={"F": (-20.0, 20.0), "x": (-0.5, 0.5)})
    u = mpc([1.0, 0.1, 0.0, 0.0], t=0.0)
    assert mpc.status == 0 and np.all(np.isfinite(u)) and abs(u[0]) <= 20
    assert mpc.u[0, 0] == u[0]
    bad = gen.MPC(cart, N_CP, PERIOD, Q_CP, R_CP, P=P_CP, bounds={"F": (-20.0, 20.0)},
                  qp_max_iter=1)
    u = bad(X0_CP, t=0.0)
    assert bad.status == -101 and bad.status_name == "ERR_QP_MAX_ITER"
    assert "iteration cap" in bad.message
    assert np.all(np.isfinite(u))


@pytest.mark.slow
def test_nan_state_rejected(rti):
    with pytest.raises(gen.InputError, match=r"x\[1\] = nan \(theta\)"):
        rti([0.0, np.nan, 0.0, 0.0])
    with pytest.raises(gen.InputError, match=r"shape \(4,\)"):
        rti([0.0, 0.1])


@pytest.mark.parametrize("kw, match", [
    ({"bounds": {"F": (1.0, -1.0)}}, r"bounds\[F\] = \(1.0, -1.0\): lo > hi"),
    ({"Q": np.diag([1.0, -1.0, 1.0, 1.0])}, r"Q must be positive semidefinite"),
    ({"R": [0.0]}, r"R must be positive definite"),
    ({"reference": (np.zeros(3), [0.0])}, r"reference states must have shape \(nx,\)"),
    ({"reference": (np.zeros(4), [0.0, 1.0])}, r"reference inputs must have shape"),
    ({"horizon": 0}, r"horizon must be an integer >= 1"),
    ({"method": "ddp"}, r"method must be one of"),
])
def test_bad_input_named_before_build(cart, kw, match):
    args = dict(horizon=N_CP, period=PERIOD, Q=Q_CP, R=R_CP, P=P_CP)
    args.update(kw)
    with pytest.raises(gen.InputError, match=match):
        gen.MPC(cart, **args)


@pytest.mark.slow
def test_phases_separately_and_the_time_limit(cart, rti):
    """prepare(t) then feedback(x) is the call mpc(x, t), bit for bit; a
    time budget too short for the QP ends the call with TIME_LIMIT and the
    best control so far, finite and inside the bounds."""
    rti.reset()
    u1 = rti(X0_CP, t=0.0)
    rti.reset()
    assert rti.prepare(0.0) == 0
    u2 = rti.feedback(X0_CP)
    assert np.array_equal(u1, u2) and rti.status == 0
    fast = gen.MPC(cart, N_CP, PERIOD, Q_CP, R_CP, P=P_CP, bounds={"F": (-20.0, 20.0)},
                   time_limit=1e-7)
    u = fast(X0_CP, t=0.0)
    assert fast.status == 2 and fast.status_name == "TIME_LIMIT", fast.message
    assert np.all(np.isfinite(u)) and abs(u[0]) <= 20.0


# ------------------------------------------------------------------ path, residuals
@pytest.mark.slow
def test_path_constraint_and_residuals_against_ipopt(cart):
    """A path constraint on the cart's position (soft, linearized at each
    iteration) and a nonlinear least-squares residual (the pole tip's
    height below its upright height, Gauss-Newton): the converged SQP
    equals IPOPT's solution of the NLP with the constraint hard (the L1
    penalty is exact) and the residual in the cost, to 1e-6."""
    cs = need("casadi", "CasADi + IPOPT, the independent NLP solver")
    import sympy.physics.mechanics as mech
    xc, th = mech.dynamicsymbols("x theta")
    lo = -0.355
    w = 4.0
    mpc = gen.MPC(cart, N_CP, PERIOD, Q_CP, R_CP, P=P_CP, bounds={"F": (-20.0, 20.0)},
                  path=[(xc, lo, 1.0)], residuals=[(1 - sm.cos(th), w)], method="sqp",
                  max_iter=100, penalty=1e3)
    mpc(X0_CP, t=0.0)
    assert mpc.status == 0, mpc.message
    xs, us = cs.SX.sym("x", 4), cs.SX.sym("u", 1)
    f = cs.Function("f", [xs, us], [casadi_rhs(cart, xs, us)])
    U = cs.SX.sym("U", N_CP)
    x, h, J, g = cs.DM(X0_CP), PERIOD, 0, []
    X = [x]
    for k in range(N_CP):
        J += PERIOD * (cs.mtimes([x.T, Q_CP, x]) + R_CP[0, 0] * U[k] ** 2
                       + w * (1 - cs.cos(x[1])) ** 2)
        k1 = f(x, U[k])
        k2 = f(x + h / 2 * k1, U[k])
        k3 = f(x + h / 2 * k2, U[k])
        k4 = f(x + h * k3, U[k])
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        X.append(x)
        if k < N_CP - 1:
            g.append(x[0])
    J += cs.mtimes([x.T, P_CP, x])
    solver = cs.nlpsol("s", "ipopt", {"x": U, "f": J, "g": cs.vertcat(*g)},
                       {"ipopt.print_level": 0, "print_time": 0, "ipopt.tol": 1e-12,
                        "ipopt.sb": "yes", "ipopt.bound_relax_factor": 0.0})
    sol = solver(x0=np.zeros(N_CP), lbx=-20.0, ubx=20.0, lbg=lo, ubg=1.0)
    assert solver.stats()["success"]
    Uref = np.array(sol["x"]).ravel()
    Xref = np.array(cs.Function("X", [U], [cs.horzcat(*X)])(Uref)).T
    assert np.min(Xref[1:N_CP, 0]) == pytest.approx(lo, abs=1e-9)     # the path, active
    np.testing.assert_allclose(mpc.u.ravel(), Uref, rtol=0, atol=1e-6)
    np.testing.assert_allclose(mpc.x, Xref, rtol=0, atol=1e-6)


# ------------------------------------------------------------------ constrained model
def forced_pendulum():
    """The seed's nonminimal pendulum (q1, q2 Cartesian, |P| = L; gravity
    along N.x) with a force F along N.y on the particle."""
    from sympy import Matrix, atan, solve, symbols
    from sympy.physics.mechanics import (KanesMethod, Particle, Point, ReferenceFrame,
                                         dynamicsymbols)
    q1, q2 = dynamicsymbols("q1:3")
    q1d, q2d = dynamicsymbols("q1:3", level=1)
    u1, u2 = dynamicsymbols("u1:3")
    F = dynamicsymbols("F")
    L, m, g = symbols("L, m, g")
    N = ReferenceFrame("N")
    pN = Point("N*")
    pN.set_vel(N, 0)
    A = N.orientnew("A", "axis", [atan(q2 / q1), N.z])
    P = pN.locatenew("P1", q1 * N.x + q2 * N.y)
    kde = Matrix([q1d - u1, q2d - u2])
    P.set_vel(N, P.pos_from(pN).dt(N).subs(solve(kde, [q1d, q2d])))
    f_c = Matrix([P.pos_from(pN).magnitude() - L])
    f_v = Matrix([P.vel(N).express(A).dot(A.x)])
    f_v.simplify()
    KM = KanesMethod(N, q_ind=[q2], u_ind=[u2], q_dependent=[q1], u_dependent=[u1],
                     configuration_constraints=f_c, velocity_constraints=f_v, kd_eqs=kde)
    KM.kanes_equations([Particle("pP", P, m)], [(P, m * g * N.x + F * N.y)])
    return gen.Model.from_kanes(KM, constants={L: 1.0, m: 1.0, g: 9.81}, inputs=[F],
                                name="pendulum_forced")


@pytest.mark.slow
def test_constrained_pendulum_stabilized_upright():
    """The nonminimal pendulum held upright (q1 = -L) by MPC on its
    independent state (q2, u2), the loop closed in C: it converges, the
    force stays in its bounds, and the configuration and velocity
    constraints hold to 1e-10 along the loop and in the predictions."""
    model = forced_pendulum()
    assert model.independent_state_names == ["q2", "u2"]
    i = {n: k for k, n in enumerate(model.state_names)}
    up = np.zeros(4)
    up[i["q1"]] = -1.0
    mpc = gen.MPC(model, 20, 0.05, [20.0, 1.0], [0.01], P=np.diag([200.0, 10.0]),
                  bounds={"F": (-15.0, 15.0)}, reference=(up, [0.0]))
    x0 = np.zeros(4)
    x0[i["q2"]], x0[i["q1"]] = 0.4, -np.sqrt(1 - 0.16)
    sim = gen.compile(model, derivatives=True)
    sol = sim.simulate(x0, 4.0, 5e-3, controller=mpc)
    q1, q2, u1, u2 = (sol.x[:, i[n]] for n in ("q1", "q2", "u1", "u2"))
    assert np.max(np.abs(np.hypot(q1, q2) - 1.0)) < 1e-10
    assert np.max(np.abs(q1 * u1 + q2 * u2)) < 1e-10
    assert np.max(np.abs(sol.r)) == pytest.approx(15.0) and np.max(np.abs(sol.r)) <= 15.0
    assert abs(q2[-1]) < 1e-3 and q1[-1] == pytest.approx(-1.0, abs=1e-6)
    u = mpc(sol.x[len(sol.t) // 4], t=1.0)
    assert mpc.status == 0 and np.all(np.isfinite(u))
    X = mpc.x
    assert np.max(np.abs(np.hypot(X[:, i["q1"]], X[:, i["q2"]]) - 1.0)) < 1e-10
    assert np.max(np.abs(X[:, i["q1"]] * X[:, i["u1"]] + X[:, i["q2"]] * X[:, i["u2"]])) < 1e-10


# ------------------------------------------------------------------ quadrotor
@pytest.mark.slow
def test_quadrotor_figure_eight_beats_the_lqr_tracker():
    """The quadrotor (12 states, 4 inputs, Euler-rate kinematics) along a
    figure-eight at 1 m, the loops closed in C by sim.simulate: the MPC's
    position error is below the time-varying LQR tracker's
    (gen.TrajectoryTracker, the same Q, R and period, its inputs clipped to
    the same limits), and the thrust and torques stay within their limits."""
    import quadrotor as qr
    model = qr.model(kinematics="euler")
    hover = qr.hover_input()
    period, T_end = 0.05, 8.0
    w = 2 * np.pi / T_end
    ts = period * np.arange(int(T_end / period) + 21)
    X = np.zeros((len(ts), 12))
    X[:, 3], X[:, 4], X[:, 5] = np.sin(w * ts), 0.5 * np.sin(2 * w * ts), 1.0
    X[:, 9], X[:, 10] = w * np.cos(w * ts), w * np.cos(2 * w * ts)
    U = np.tile(hover, (len(ts), 1))
    Q = np.diag([1, 1, 1, 20, 20, 20, 0.1, 0.1, 0.1, 1, 1, 1.0])
    R = np.diag([0.1, 10, 10, 10.0])
    lo = np.array([0.0, -0.5, -0.5, -0.2])
    hi = np.array([2.5 * hover[0], 0.5, 0.5, 0.2])
    names = model.input_names
    mpc = gen.MPC(model, 20, period, Q, R, P=5 * Q, reference=(ts, X, U),
                  bounds={n: (a, b) for n, a, b in zip(names, lo, hi)})
    sim = gen.compile(model, derivatives=True)
    tracker = gen.TrajectoryTracker(sim, ts, X, U, Q, R, period, r_min=lo, r_max=hi)
    x0 = np.r_[0, 0, 0, 0, 0, 1.0, np.zeros(6)]
    err, rmax = {}, {}
    for key, ctl in (("mpc", mpc), ("lqr", tracker)):
        sol = sim.simulate(x0, T_end, 5e-3, controller=ctl)
        ref = np.array([np.interp(sol.t, ts, X[:, j]) for j in (3, 4, 5)]).T
        err[key] = np.sqrt(np.mean(np.sum((sol.x[:, 3:6] - ref) ** 2, axis=1)))
        rmax[key] = (np.min(sol.r - lo), np.min(hi - sol.r))
    print(f"\nquadrotor figure-eight: RMS position error MPC {err['mpc']:.4f} m, "
          f"LQR tracker {err['lqr']:.4f} m")
    assert min(rmax["mpc"]) >= -1e-12
    assert err["mpc"] < err["lqr"]
    assert err["mpc"] < 0.1
