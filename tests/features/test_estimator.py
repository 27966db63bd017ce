"""Issue 44, state estimation: gen.EKF and gen.UKF over the model's own step,
in C.

References: filterpy 2.0's ExtendedKalmanFilter and UnscentedKalmanFilter
given an independent model (sympy's mass_matrix_full and forcing_full of
the KanesMethod lambdified, RK4 in numpy, the step's Jacobian by
complex-step differentiation); the chi-squared distribution of the
normalized estimation error squared over seeded Monte-Carlo runs whose
truth is the model's RK4 step (sim.step) plus the process noise the filter
assumes; the true damping of a pendulum; the upright cart-pole under an LQR
designed on sim.linearize (examples/cart_pole.py).
"""
import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import cart_pole as cp
import gen
import seed_pendulum as sp
from gen.design.estimator import ACCEPTED, GATED, MISSING

DT = 0.01
N_STEPS = 1000


@pytest.fixture(scope="module")
def cart():
    km, s = cp.derive()
    return km, s, cp.model()


def cart_ekf(cart, kind=gen.EKF, **kw):
    km, s, model = cart
    args = dict(Q=np.diag([1e-8, 1e-8, 1e-6, 1e-6]), R=[1e-4, 1e-4],
                x0=[0.05, 0.0, 0.0, 0.0], P0=np.diag([1e-2, 1e-2, 1e-1, 1e-1]))
    args.update(kw)
    return kind(model, {"x_m": s["x"], "th_m": s["theta"]}, DT, args.pop("Q"), args.pop("R"),
                args.pop("x0"), args.pop("P0"), **args)


# ------------------------------------------------------------ bad input
def test_bad_input_is_named_in_the_users_terms(cart):
    """Q or R not positive semidefinite, an unknown symbol, estimate naming
    a state, a wrong x0: each an InputError naming it, before any build."""
    km, s, model = cart
    z = {"x_m": s["x"], "th_m": s["theta"]}
    good = dict(Q=np.eye(4) * 1e-6, R=[1e-4, 1e-4], x0=np.zeros(4), P0=np.eye(4))

    def make(**kw):
        a = {**good, **kw}
        meas = a.pop("meas", z)
        return gen.EKF(model, meas, DT, a.pop("Q"), a.pop("R"), a.pop("x0"), a.pop("P0"), **a)

    with pytest.raises(gen.InputError, match="Q is not positive semidefinite"):
        make(Q=np.diag([1e-6, -1e-3, 1e-6, 1e-6]))
    with pytest.raises(gen.InputError, match="R is not positive semidefinite"):
        make(R=[1e-4, -1.0])
    with pytest.raises(gen.InputError, match="R must be diagonal"):
        make(R=[[1e-4, 1e-5], [1e-5, 1e-4]])
    with pytest.raises(gen.InputError, match="Q is not symmetric"):
        make(Q=np.triu(np.ones((4, 4))))
    k = sm.symbols("k_unknown")
    with pytest.raises(gen.InputError, match="measurement 'bad' names k_unknown, unknown"):
        make(meas={"bad": k * s["x"]})
    with pytest.raises(gen.InputError, match="'tip_z' is not an output"):
        make(meas=["tip_x", "tip_z"])
    with pytest.raises(gen.InputError, match=r"estimate: theta\(t\) is a state, not a constant"):
        make(estimate=[s["theta"]])
    with pytest.raises(gen.InputError, match="estimate: F is an input"):
        make(estimate=["F"])
    with pytest.raises(gen.InputError, match=r"x0 must be the state \[x, theta, v, omega\]"):
        make(x0=np.zeros(3))
    with pytest.raises(gen.InputError, match="method must be 'rk4'"):
        make(method="dopri5")
    # the UKF's parameters, before its build too
    with pytest.raises(gen.InputError, match=r"kappa must make ns \+ kappa > 0 \(ns = 4\)"):
        gen.UKF(model, z, DT, good["Q"], good["R"], good["x0"], good["P0"], kappa=-4.0)
    with pytest.raises(gen.InputError, match="alpha must be > 0"):
        gen.UKF(model, z, DT, good["Q"], good["R"], good["x0"], good["P0"], alpha=0.0)


@pytest.mark.slow
def test_wrong_length_and_nan_measurements(cart):
    """A wrong-length z is an InputError naming the measurements; a NaN one
    is rejected (MISSING) with the estimate unchanged; an outlier is gated
    and reported; the batch filter gives the same numbers as step."""
    ekf = cart_ekf(cart)
    with pytest.raises(gen.InputError, match=r"z must hold the 2 measurement\(s\) \[x_m, th_m\]"):
        ekf.update([0.0, 0.1, 0.2])
    with pytest.raises(gen.InputError, match=r"r must hold 1 input\(s\) \[F\]"):
        ekf.predict([0.0, 1.0])
    ekf.update([0.0, 0.0])
    x, P = ekf.x, ekf.P
    ekf.update([np.nan, np.nan])
    assert list(ekf.status) == [MISSING, MISSING]
    assert np.array_equal(ekf.x, x) and np.array_equal(ekf.P, P)
    assert list(ekf.rejected) == [1, 1]
    ekf.update([np.nan, 0.01])
    assert list(ekf.status) == [MISSING, ACCEPTED] and not np.array_equal(ekf.x, x)
    sd = np.sqrt(ekf.P[0, 0] + 1e-4)
    ekf.update([ekf.x[0] + 50 * sd, ekf.x[1]])
    assert list(ekf.status) == [GATED, ACCEPTED]
    assert ekf.innovations[0] ** 2 > 25 * ekf.innovation_variances[0]
    assert list(ekf.rejected) == [3, 1]
    # filter() runs the same arithmetic as step
    a, b = cart_ekf(cart), cart_ekf(cart)
    rng = np.random.default_rng(5)
    Z = 0.01 * rng.normal(size=(50, 2))
    Z[7, 1] = np.nan
    Rin = 0.3 * rng.normal(size=(50, 1))
    res = a.filter(DT * np.arange(50), Z, Rin)
    b.update(Z[0])
    for k in range(1, 50):
        b.step(Z[k], Rin[k - 1])
    assert np.array_equal(res.x[-1], b.x) and np.array_equal(res.P[-1], b.P)
    assert res.status[7, 1] == MISSING and res.status[7, 0] == ACCEPTED
    with pytest.raises(gen.InputError, match="the rows must be the filter's samples"):
        a.filter([0.0, 0.01], Z[:2], Rin[:2])


@pytest.mark.slow
def test_python_calls_take_the_host_fast_path_and_equal_the_general_path(cart):
    """predict, update and step from Python: an exact C-contiguous float64
    array of the size goes through the host module's CPython function
    (csrc/host/gen_host_fast.c), which declines (None, nothing done)
    anything else: a list, another dtype, a subclass, a strided view, a
    wrong size. A filter given lists (the general path) follows the fast
    one bit for bit; a NaN input through the fast path is the general
    path's InputError, the estimate unchanged."""
    fast, slow = cart_ekf(cart), cart_ekf(cart)
    z = np.array([0.01, 0.5, 0.02])
    for bad in (np.array([0.3, 0.1]), np.array([1]), np.array([0.3], dtype=np.float32),
                np.array([0.3]).view(np.recarray), [0.3], 0.3, None):
        assert fast._fast_predict(bad) is None
    for bad in (z[::2], z[:2].astype(np.float32), z, [0.01, 0.02]):
        assert fast._fast_update(bad) is None
        assert fast._fast_step(bad, np.array([0.3])) is None
    assert fast._fast_step(z[:2].copy(), [0.3]) is None
    assert np.array_equal(fast.x, slow.x) and fast.t == slow.t == 0.0
    rng = np.random.default_rng(9)
    for k in range(60):
        r, z = 0.3 * rng.normal(size=1), 0.01 * rng.normal(size=2)
        if k % 2:
            fast.predict(r)
            fast.update(z)
            slow.predict(r.tolist())
            slow.update(z.tolist())
        else:
            fast.step(z, r)
            slow.step(z.tolist(), r.tolist())
        for a, b in ((fast.x, slow.x), (fast.P, slow.P), (fast.innovations, slow.innovations),
                     (fast.status, slow.status)):
            assert np.array_equal(a, b)
    x, P, t = fast.x, fast.P, fast.t
    with pytest.raises(gen.InputError, match=r"r = \[nan\] \[F\]: every entry must be finite"):
        fast.predict(np.array([np.nan]))
    assert np.array_equal(fast.x, x) and np.array_equal(fast.P, P) and fast.t == t
    assert fast._fast_predict(np.array([0.3])) == 0 and fast.t == t + DT


# ---------------------------------------------- the independent reference
class Reference:
    """The cart-pole without eomgen: sympy's full mass matrix and forcing of
    the KanesMethod lambdified, RK4 in numpy, the step's Jacobian by
    complex-step differentiation."""

    def __init__(self, km, s):
        vals = {s[k]: v for k, v in cp.DEFAULTS.items()}
        X, F = sm.symbols("X0:4"), sm.Symbol("F_in")
        sub = dict(zip([s["x"], s["theta"], s["v"], s["omega"]], X))
        sub[s["F"]] = F
        self.M = sm.lambdify([X, F], km.mass_matrix_full.subs(vals).xreplace(sub), "numpy")
        self.f = sm.lambdify([X, F], km.forcing_full.subs(vals).xreplace(sub), "numpy")

    def rhs(self, x, r):
        dt = complex if np.iscomplexobj(x) else float
        M = np.array(self.M(x, r), dtype=dt)
        return np.linalg.solve(M, np.array(self.f(x, r), dtype=dt).ravel())

    def step(self, x, r, h=DT):
        k1 = self.rhs(x, r)
        k2 = self.rhs(x + h / 2 * k1, r)
        k3 = self.rhs(x + h / 2 * k2, r)
        k4 = self.rhs(x + h * k3, r)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def jacobian(self, x, r, eps=1e-30):
        J = np.zeros((4, 4))
        for j in range(4):
            xc = x.astype(complex)
            xc[j] += 1j * eps
            J[:, j] = self.step(xc, r).imag / eps
        return J


@pytest.fixture(scope="module")
def recording(cart):
    """1000 samples of the cart-pole pushed by a known force, its position and
    angle measured with noise (the reference's own RK4 plus process noise)."""
    km, s, _ = cart
    ref = Reference(km, s)
    rng = np.random.default_rng(1)
    Q = np.diag([1e-8, 1e-8, 1e-6, 1e-6])
    R = np.array([1e-4, 1e-4])
    x = np.array([0.0, 0.15, 0.0, 0.0])
    Z, Rin = np.zeros((N_STEPS, 2)), np.zeros((N_STEPS, 1))
    for k in range(N_STEPS):
        Rin[k] = 0.5 * np.sin(0.5 * k * DT)
        Z[k] = x[:2] + rng.normal(size=2) * np.sqrt(R)
        x = ref.step(x, Rin[k, 0]) + rng.normal(size=4) * np.sqrt(np.diag(Q))
    return ref, Q, R, Z, Rin


@pytest.mark.slow
def test_ekf_equals_filterpy_with_an_independent_model(cart, recording):
    """1000 predicts and updates of the cart-pole, position-only measurements:
    the states and covariances of filterpy's ExtendedKalmanFilter (F by
    complex-step differentiation of a numpy RK4 on sympy's lambdified
    equations; the batch Joseph update with its matrix inverse) agree to
    1e-10 with gen.EKF's (the model's step sensitivity; scalar updates)."""
    filterpy = pytest.importorskip("filterpy.kalman", reason="filterpy (the test extra)")
    ref, Q, R, Z, Rin = recording
    x0, P0 = np.array([0.05, 0.1, 0.0, 0.0]), np.diag([1e-2, 1e-2, 1e-1, 1e-1])
    H = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])

    class EKFRef(filterpy.ExtendedKalmanFilter):
        def predict_x(self, u=0):
            self.x = ref.step(self.x, u)

    fp = EKFRef(4, 2)
    fp.x, fp.P, fp.Q, fp.R = x0.copy(), P0.copy(), Q, np.diag(R)
    ekf = cart_ekf(cart, Q=Q, R=R, x0=x0, P0=P0, gate=None)
    dx = dP = 0.0
    for k in range(N_STEPS):
        if k:
            fp.F = ref.jacobian(fp.x, Rin[k - 1, 0])
            fp.predict(u=Rin[k - 1, 0])
            ekf.predict(Rin[k - 1])
        fp.update(Z[k], HJacobian=lambda x: H, Hx=lambda x: H @ x)
        ekf.update(Z[k])
        dx, dP = max(dx, np.max(np.abs(fp.x - ekf.x))), max(dP, np.max(np.abs(fp.P - ekf.P)))
    assert dx < 1e-10 and dP < 1e-10, (dx, dP)
    assert np.max(np.abs(ekf.x)) > 1.0          # the run went somewhere
    print(f"\nEKF vs filterpy, 1000 steps: max |dx| = {dx:.1e}, max |dP| = {dP:.1e}")


@pytest.mark.slow
@pytest.mark.parametrize("alpha,tol", [(0.1, 1e-10), (1.0, 1e-10), (1e-3, 1e-6)])
def test_ukf_equals_filterpy_with_an_independent_model(cart, recording, alpha, tol):
    """The same run with filterpy's UnscentedKalmanFilter and
    MerweScaledSigmaPoints (its sigma points through the numpy RK4): states
    and covariances to 1e-10. With alpha = 1e-3 (filterpy's example) the
    sigma points are 1e-3 standard deviations from the mean and the weights
    W0 = 1 - 1/alpha^2 = -999999 and 125000 amplify the rounding of every
    propagated point: the problem itself is ill-conditioned there, and three
    implementations (filterpy's weighted sums, a numpy one summing the
    differences from the central point as gen.UKF does, and gen.UKF) differ
    pairwise by ~1e-8 in the states, so the test asks 1e-6 there."""
    filterpy = pytest.importorskip("filterpy.kalman", reason="filterpy (the test extra)")
    ref, Q, R, Z, Rin = recording
    x0, P0 = np.array([0.05, 0.1, 0.0, 0.0]), np.diag([1e-2, 1e-2, 1e-1, 1e-1])
    pts = filterpy.MerweScaledSigmaPoints(4, alpha=alpha, beta=2.0, kappa=0.0)
    fp = filterpy.UnscentedKalmanFilter(4, 2, DT, hx=lambda x: x[:2],
                                        fx=lambda x, dt, u: ref.step(x, u), points=pts)
    fp.x, fp.P, fp.Q, fp.R = x0.copy(), P0.copy(), Q, np.diag(R)
    ukf = cart_ekf(cart, gen.UKF, Q=Q, R=R, x0=x0, P0=P0, gate=None, alpha=alpha)
    ours, theirs = [], []
    for k in range(N_STEPS):
        # (filterpy's update uses the sigma points its predict drew: predict first)
        fp.predict(u=Rin[k, 0])
        ukf.predict(Rin[k])
        fp.update(Z[k])
        ukf.update(Z[k])
        ours.append((ukf.x, ukf.P))
        theirs.append((fp.x.copy(), fp.P.copy()))
    dx, dP = max_diff(ours, theirs)
    assert dx < tol and dP < tol, (dx, dP)
    print(f"\nUKF (alpha {alpha}) vs filterpy: max |dx| = {dx:.1e}, max |dP| = {dP:.1e}")
    if alpha < 0.01:
        mine = merwe_ukf_numpy(ref, Q, R, Z, Rin, x0, P0, alpha)
        (ax, aP), (bx, bP) = max_diff(mine, ours), max_diff(mine, theirs)
        print(f"numpy UKF (means by differences) vs gen.UKF: {ax:.1e}, {aP:.1e}; "
              f"vs filterpy: {bx:.1e}, {bP:.1e}")
        assert ax < tol and aP < tol and bx < tol and bP < tol


def max_diff(a, b):
    """The largest |dx| and |dP| between two runs' [(x, P)]."""
    return (max(np.max(np.abs(x - y)) for (x, _), (y, _) in zip(a, b)),
            max(np.max(np.abs(P - S)) for (_, P), (_, S) in zip(a, b)))


def merwe_ukf_numpy(ref, Q, R, Z, Rin, x, P, alpha, beta=2.0, kappa=0.0):
    """van der Merwe's scaled UKF in numpy on the reference's RK4 (the
    sigma points redrawn after the predict, as filterpy does), each mean the
    central point plus weighted differences: [(x, P)] after each update."""
    n = len(x)
    c = alpha ** 2 * (n + kappa)
    wm0, wi = (c - n) / c, 0.5 / c
    wc0 = wm0 + 1 - alpha ** 2 + beta

    def points(x, P):
        L = np.linalg.cholesky(c * P)
        return np.vstack([x, x + L.T, x - L.T])

    def mean(S):
        return S[0] + wi * np.sum(S[1:] - S[0], axis=0)

    def cov(A, a, B, b):
        da, db = A - a, B - b
        return wc0 * np.outer(da[0], db[0]) + wi * da[1:].T @ db[1:]

    out = []
    for k in range(len(Z)):
        S = np.array([ref.step(s, Rin[k, 0]) for s in points(x, P)])
        x = mean(S)
        P = cov(S, x, S, x) + Q
        S = points(x, P)
        Hs = S[:, :2]
        zp = mean(Hs)
        Pzz = cov(Hs, zp, Hs, zp) + np.diag(R)
        K = np.linalg.solve(Pzz, cov(S, x, Hs, zp).T).T
        x, P = x + K @ (Z[k] - zp), P - K @ Pzz @ K.T
        out.append((x, P))
    return out


# ---------------------------------------------------------- consistency
def chi2_bounds(n, runs, p=0.95):
    from scipy.stats import chi2
    return (chi2.ppf((1 - p) / 2, n * runs) / runs, chi2.ppf((1 + p) / 2, n * runs) / runs)


def anees(kf, sim, truth0, P0, Q, R, h, steps, runs, rng, r_of=None):
    """The average NEES at each step over seeded runs: the truth the model's
    RK4 step (sim.step, unprojected) plus process noise on the independent
    state (the dependent entries completed), the measurements h(truth) plus
    noise; the filter restarted each run and run over the recording in one
    C call."""
    ind = list(sim.q_ind) + [sim.nq + i for i in sim.u_ind]
    L0, LQ = np.linalg.cholesky(P0), np.linalg.cholesky(Q)
    nees = np.zeros(steps)
    for _ in range(runs):
        xt = truth0.copy()
        xt[ind] += L0 @ rng.normal(size=len(ind))
        if sim.mc or sim.mv:
            xt = sim.consistent_state(xt)
        X, Z = np.zeros((steps, len(ind))), np.zeros((steps, len(R)))
        Rin = np.array([r_of(k) for k in range(steps)]) if r_of else None
        for k in range(steps):
            X[k] = xt[ind]
            Z[k] = h(xt) + rng.normal(size=len(R)) * np.sqrt(R)
            xt = sim.step(k * DT, xt, DT, r=None if Rin is None else Rin[k], project=False)
            xt[ind] += LQ @ rng.normal(size=len(ind))
            if sim.mc or sim.mv:
                xt = sim.consistent_state(xt)
        kf.reset(x0=truth0, P0=P0, t0=0.0)
        res = kf.filter(DT * np.arange(steps), Z, Rin)
        e = X - res.x
        nees += np.einsum("ki,kij,kj->k", e, np.linalg.inv(res.P), e)
    return nees / runs


@pytest.mark.slow
def test_nees_within_the_95_percent_chi_squared_bounds(cart, kane_model):
    """100 seeded Monte-Carlo runs of 1000 steps: the cart-pole (position and
    angle measured) and the seed's nonminimal pendulum (its angle
    atan2(q2, q1) measured; the filter on [q2, u2], the estimate on the
    circle): the run-averaged NEES at each step lies within the 95%
    chi-squared bounds for 95% of the steps (nominally), and its mean over
    the steps within them."""
    km, s, model = cart
    runs, rng = 100, np.random.default_rng(44)
    Q, R, P0 = np.diag([1e-8, 1e-8, 1e-6, 1e-6]), np.array([1e-4, 1e-4]), np.diag(
        [1e-4, 1e-4, 1e-3, 1e-3])
    sim = gen.compile(model)
    x0 = np.array([0.0, 0.2, 0.0, 0.0])
    ekf = cart_ekf(cart, Q=Q, R=R, x0=x0, P0=P0, gate=None)
    a = anees(ekf, sim, x0, P0, Q, R, lambda x: x[:2], N_STEPS, runs, rng,
              r_of=lambda k: [0.5 * np.sin(0.5 * k * DT)])
    lo, hi = chi2_bounds(4, runs)
    inside = np.mean((a >= lo) & (a <= hi))
    print(f"\ncart-pole ANEES: mean {a.mean():.3f}, bounds [{lo:.3f}, {hi:.3f}], "
          f"{100 * inside:.1f}% of the steps inside")
    assert lo <= a.mean() <= hi and inside >= 0.9, (a.mean(), inside)

    KM, ps = sp.derive_kane()
    psim = gen.compile(kane_model)
    th = 0.5
    x0 = np.array([np.sin(th), np.cos(th), 0.0, 0.0])       # [q2, q1, u2, u1]
    Qp, Rp, P0p = np.diag([1e-8, 1e-6]), np.array([1e-4]), np.diag([1e-3, 1e-3])
    pekf = gen.EKF(kane_model, {"angle": sm.atan2(ps["q2"], ps["q1"])}, DT, Qp, Rp, x0, P0p,
                   gate=None)
    a = anees(pekf, psim, x0, P0p, Qp, Rp, lambda x: [np.arctan2(x[0], x[1])], N_STEPS, runs,
              rng)
    lo, hi = chi2_bounds(2, runs)
    inside = np.mean((a >= lo) & (a <= hi))
    print(f"nonminimal pendulum ANEES: mean {a.mean():.3f}, bounds [{lo:.3f}, {hi:.3f}], "
          f"{100 * inside:.1f}% of the steps inside")
    assert lo <= a.mean() <= hi and inside >= 0.9, (a.mean(), inside)
    fc = pekf.x_full[0] ** 2 + pekf.x_full[1] ** 2 - 1.0
    assert abs(fc) < 1e-12


@pytest.mark.slow
def test_the_damping_of_a_pendulum_estimated_online():
    """A damped pendulum's angle measured with noise: the damping c, a
    random-walk state started at a sixth of its value, converges to the true
    value within three of its own standard deviations, which shrink."""
    theta, omega = me.dynamicsymbols("theta omega")
    m, l, g, c = sm.symbols("m l g c")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [theta, N.z])
    A.set_ang_vel(N, omega * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    km = me.KanesMethod(N, q_ind=[theta], u_ind=[omega], kd_eqs=[theta.diff() - omega])
    km.kanes_equations([me.Particle("bob", P, m)], [(P, m * g * N.x), (A, -c * omega * N.z)])
    c_true = 0.3
    model = gen.Model.from_kanes(km, constants={m: 1.0, l: 0.5, g: 9.81, c: c_true},
                                 name="damped_pend")
    sim = gen.compile(model)
    rng = np.random.default_rng(3)
    x, Z = np.array([1.0, 0.0]), np.zeros((1500, 1))
    for k in range(1500):
        Z[k] = x[0] + 0.01 * rng.normal()
        x = sim.step(k * DT, x, DT)
    ekf = gen.EKF(model, {"angle": theta}, DT, np.diag([0.0, 1e-8, 0.0]), [1e-4],
                  [1.0, 0.0, 0.05], np.diag([1e-2, 1e-2, 0.1]), estimate=[c])
    assert ekf.state_names == ["theta", "omega", "c"] and ekf.params == {"c": 0.05}
    res = ekf.filter(DT * np.arange(1500), Z)
    est, sd = ekf.params["c"], np.sqrt(ekf.P[2, 2])
    print(f"\ndamping: {est:.5f} +- {sd:.5f} (true {c_true})")
    assert abs(est - c_true) < 3 * sd and sd < 0.01
    assert res.sd[-1, 2] < res.sd[100, 2] < res.sd[0, 2]


# ------------------------------------------------------------ closed loop
@pytest.mark.slow
def test_ekf_and_lqr_hold_the_cart_pole_upright_in_c(cart):
    """An EKF on noisy cart position and angle feeding an LQR, one loop in C
    (sim.simulate, no Python): from 0.1 rad with a wrong initial estimate
    (the cart 5 cm off, the pole upright) the pole stays up for 20 s; the
    same seed gives the same run, another seed another; the logged
    estimates follow the truth within their standard deviations."""
    km, s, model = cart
    sim = gen.compile(model)
    A, B = sim.linearize(np.zeros(4))
    K = cp.lqr(A, B, cp.Q_LQR, cp.R_LQR)
    ekf = cart_ekf(cart)
    loop = ekf.feedback(gen.LinearFeedback(K), seed=7)
    sol = sim.simulate([0.0, 0.1, 0.0, 0.0], 20.0, 1e-3, controller=loop)
    assert np.max(np.abs(sol.x[:, 1])) <= 0.1 + 1e-9
    assert np.max(np.abs(sol.x[-5000:, 1])) < 0.03 and np.max(np.abs(sol.x[-5000:, 0])) < 0.1
    assert loop.n_samples == 2001 and np.allclose(loop.t, DT * np.arange(2001))
    truth = sol.x[::10]
    err = np.abs(loop.x - truth) / loop.sd
    assert np.mean(err[200:] < 3) > 0.97
    again = sim.simulate([0.0, 0.1, 0.0, 0.0], 20.0, 1e-3, controller=loop)
    assert np.array_equal(again.x, sol.x)
    other = sim.simulate([0.0, 0.1, 0.0, 0.0], 20.0, 1e-3,
                         controller=ekf.feedback(gen.LinearFeedback(K), seed=8))
    assert np.max(np.abs(other.x - sol.x)) > 1e-4
    # the UKF closes the same loop
    ukf = cart_ekf(cart, gen.UKF, alpha=0.5)
    sol_u = sim.simulate([0.0, 0.1, 0.0, 0.0], 20.0, 1e-3,
                         controller=ukf.feedback(gen.LinearFeedback(K), seed=7))
    assert np.max(np.abs(sol_u.x[-5000:, 1])) < 0.03
