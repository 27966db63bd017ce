"""Issue 34, tracking: gen.TrajectoryTracker, a time-varying LQR along a
reference trajectory, in C (sim.simulate), in the standalone binary and in
the float build under qemu-arm, on the cart-pole of examples/cart_pole.py.

References: python-control's dlqr and scipy's solve_discrete_are on the
discretization by scipy's expm of sim.linearize's continuous (A, B); a numpy
Riccati recursion over sim.linearize(dt=period) on the reference evaluated
by scipy's CubicHermiteSpline; the law evaluated in Python and sampled with
a zero-order hold (a callable r(t, x)); the reference's own end and upright.
"""
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline
from scipy.linalg import expm, solve_discrete_are

import cart_pole as cp
import cart_pole_tracking as cpt
import gen
from conftest import require_tool
from helpers import cortex_m4_tables

HERE = Path(__file__).resolve().parents[1]
EMB = HERE / "embedded"
Q = np.diag([10.0, 10.0, 1.0, 1.0])
R = np.array([[0.1]])
PERIOD = 0.01


@pytest.fixture(scope="module")
def sim():
    return gen.compile(cp.model())


@pytest.fixture(scope="module")
def swing(sim):
    """The swing-up reference (hanging to upright in 8 s, inputs held every
    10 ms) and its tracker."""
    t, x, r = cpt.swing_up_reference(sim)
    return t, x, r, gen.TrajectoryTracker(sim, t, x, r, Q, R, PERIOD)


def riccati(Ad, Bd, Pf):
    """The backward recursion, written out: gains K_0 .. K_{M-1}."""
    P, out = Pf, []
    for A, B in zip(Ad[::-1], Bd[::-1]):
        K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
        P = Q + A.T @ P @ A - A.T @ P @ B @ K
        out.append(K)
    return np.array(out[::-1])


# ------------------------------------------------------------- the gains
def upright_dlqr(sim):
    """Ad, Bd by scipy's expm of sim.linearize's continuous (A, B) at upright,
    and scipy's discrete LQR gain and cost."""
    A, B = sim.linearize(np.zeros(4))
    E = expm(np.block([[A, B], [np.zeros((1, 5))]]) * PERIOD)
    Ad, Bd = E[:4, :4], E[:4, 4:]
    P = solve_discrete_are(Ad, Bd, Q, R)
    return Ad, Bd, np.linalg.solve(R + Bd.T @ P @ Bd, Bd.T @ P @ Ad), P


def upright_tracker(sim):
    t = np.linspace(0.0, 6.0, 7)
    return gen.TrajectoryTracker(sim, t, np.zeros((7, 4)), np.zeros((7, 1)), Q, R, PERIOD)


def test_constant_reference_converges_to_dlqr(sim):
    """(a) At upright, held: the recursion's gains are the discrete LQR's
    (scipy's solve_discrete_are on an expm discretization) to 1e-8."""
    Ad, Bd, K, P = upright_dlqr(sim)
    tr = upright_tracker(sim)
    assert tr.K.shape == (601, 1, 4) and tr.terminal == "dare"
    for k in (0, 100, 600):
        assert np.max(np.abs(tr.K[k] - K)) < 1e-8 * np.max(np.abs(K)), k
    assert np.max(np.abs(tr.P[-1] - P)) < 1e-8 * np.max(np.abs(P))
    assert np.max(np.abs(tr.Ad[0] - Ad)) < 1e-12 and np.max(np.abs(tr.Bd[0] - Bd)) < 1e-12


@pytest.mark.slow
def test_constant_reference_converges_to_python_control_dlqr(sim):
    """(a) The same against python-control's dlqr (its import alone takes
    seconds: the slow tier)."""
    import control
    Ad, Bd, K, _ = upright_dlqr(sim)
    K_ctrl, _, _ = control.dlqr(Ad, Bd, Q, R)
    assert np.max(np.abs(K_ctrl - K)) < 1e-9 * np.max(np.abs(K))
    tr = upright_tracker(sim)
    for k in (0, 100, 600):
        assert np.max(np.abs(tr.K[k] - K_ctrl)) < 1e-8 * np.max(np.abs(K_ctrl)), k


@pytest.mark.parametrize("period", [PERIOD, 0.025])
def test_gains_equal_a_numpy_riccati_recursion(sim, swing, period):
    """(b) Every gain is the numpy recursion's over sim.linearize(dt=period)
    at the reference (scipy's CubicHermiteSpline with sim.rhs slopes between
    the nodes, the inputs linear), from the terminal DARE."""
    t, x, r, _ = swing
    tr = gen.TrajectoryTracker(sim, t, x, r, Q, R, period)
    M = int(np.ceil((t[-1] - t[0]) / period - 1e-9))
    ts = t[0] + np.arange(M) * period
    assert np.allclose(tr.t_samples, ts, rtol=0, atol=1e-14)
    dx = np.array([sim.rhs(ti, xi, r=ri) for ti, xi, ri in zip(t, x, r)])
    xs = CubicHermiteSpline(t, x, dx)(ts)
    rs = np.interp(ts, t, r[:, 0])[:, None]
    assert np.max(np.abs(tr.x_op[:M] - xs)) < 1e-12 and np.max(np.abs(tr.r_op[:M] - rs)) < 1e-12
    AB = [sim.linearize(xk, r=rk, dt=period) for xk, rk in zip(xs, rs)]
    Af, Bf = sim.linearize(x[-1], r=r[-1], dt=period)
    Pf = solve_discrete_are(Af, Bf, Q, R)
    K = riccati(np.array([a for a, _ in AB]), np.array([b for _, b in AB]), Pf)
    scale = np.max(np.abs(K))
    assert np.max(np.abs(tr.K[:M] - K)) < 1e-10 * scale
    assert np.max(np.abs(tr.K[M] - np.linalg.solve(R + Bf.T @ Pf @ Bf, Bf.T @ Pf @ Af))) \
        < 1e-10 * scale
    assert np.all(tr.x_op[M] == x[-1]) and np.all(tr.r_op[M] == r[-1])


# ------------------------------------------------------- the loop in C
def python_law(tr):
    """The tracker's law written in numpy from its tables."""
    def law(t, x):
        k = min(int(round((t - tr.t_gain) / tr.period)), len(tr.K) - 1)
        return tr.r_op[k] - tr.K[k] @ (x - tr.x_op[k])
    return law


@pytest.mark.parametrize("dt,method", [(PERIOD, "rk4"), (PERIOD / 4, "rk4"), (0.05, "dopri5")])
def test_closed_loop_in_c_equals_the_law_in_python(sim, swing, dt, method):
    """(c) The tracker in C and the same law as a Python callable sampled
    every period with a zero-order hold: the same run."""
    t, x, r, tr = swing
    x0 = x[0] + np.array([0.0, 0.05, 0.0, 0.0])
    a = sim.simulate(x0, 8.0, dt, method=method, controller=tr)
    b = sim.simulate(x0, 8.0, dt, method=method, r=python_law(tr), input_period=PERIOD)
    assert np.max(np.abs(a.x - b.x)) < 1e-10 and np.max(np.abs(a.r - b.r)) < 1e-10
    # the inputs reported are the law at the samples
    for k in (0, 37, 400):
        i = int(round(k * PERIOD / dt)) if dt <= PERIOD else None
        if i is not None:
            assert abs(a.r[i, 0] - tr(sim, a.t[i], a.x[i])[0]) < 1e-12 * (1 + abs(a.r[i, 0]))


def test_input_bounds_clip_the_law_in_c(sim, swing, tmp_path):
    """r_min / r_max: the law clipped in C equals np.clip of the law in
    Python; the bounds are reached; the C source keeps them (an infinite
    one as HUGE_VAL) and compiles strict."""
    t, x, r, _ = swing
    tr = gen.TrajectoryTracker(sim, t, x, r, Q, R, PERIOD, r_min=[-12.0], r_max=[15.0])
    x0 = x[0] + np.array([0.0, 0.05, 0.0, 0.0])
    a = sim.simulate(x0, 8.0, PERIOD / 2, controller=tr)
    law = python_law(tr)
    b = sim.simulate(x0, 8.0, PERIOD / 2, r=lambda t, x: np.clip(law(t, x), -12.0, 15.0),
                     input_period=PERIOD)
    assert np.max(np.abs(a.x - b.x)) < 1e-10 and np.max(np.abs(a.r - b.r)) < 1e-10
    assert a.r.min() == -12.0 and a.r.max() == 15.0
    # a continuous law with bounds under RODAS4 (the Jacobian leaves out a
    # saturated input) and DOPRI5 agree
    A, B = sim.linearize(np.zeros(4))
    fb = gen.LinearFeedback(cp.lqr(A, B, cp.Q_LQR, cp.R_LQR), r_min=[-2.0], r_max=[2.0])
    xs = np.array([0.0, 0.3, 0.0, 0.0])
    d = sim.simulate(xs, 3.0, 0.1, method="dopri5", rtol=1e-11, atol=1e-12, controller=fb)
    ro = sim.simulate(xs, 3.0, 0.1, method="rodas4", rtol=1e-9, atol=1e-11, controller=fb)
    assert d.r.min() == -2.0 and np.max(np.abs(d.x - ro.x)) < 1e-6
    # the C source
    tr2 = gen.TrajectoryTracker(sim, t[:101], x[:101], r[:101], Q, R, PERIOD,
                                r_min=[-np.inf], r_max=[15.0])
    src = tr2.sources("bounded")
    assert "bounded_r_min[CART_POLE_NR] = { -HUGE_VAL };" in src["bounded.c"]
    assert "bounded_r_max[CART_POLE_NR] = { 15.0 };" in src["bounded.c"]
    assert tr2.footprint("double")["bounds"] == 16
    gen.generate(cp.model(), tmp_path)
    tr2.to_c(tmp_path, name="bounded", real="double")
    p = subprocess.run([_cc(), *STRICT, "-c", "-I", str(tmp_path), str(tmp_path / "bounded.c"),
                        "-o", str(tmp_path / "bounded.o")], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr


def test_started_on_the_reference_it_reproduces_it(sim, swing):
    """A reference that is a sampled run of the model, tracked at its own
    samples from its own start: the feedback is zero and the run is the
    reference's."""
    t, x, r, tr = swing
    sol = sim.simulate(x[0], 8.0, PERIOD, controller=tr)
    assert np.max(np.abs(sol.x - x)) < 1e-12


def test_tracks_the_swing_up_from_a_perturbed_start(sim, swing):
    """(d) From 0.05 rad off the reference's start, the tracker brings the
    nonlinear cart-pole to the reference's end and upright, in C."""
    t, x, r, tr = swing
    assert abs(cpt.wrap(x[-1, 1])) < 1e-3 and abs(x[-1, 1] - 2 * np.pi) < 1e-3
    ends = []
    for d in (0.05, -0.05):
        x0 = x[0] + np.array([0.0, d, 0.0, 0.0])
        sol = sim.simulate(x0, 8.0, 1e-3, controller=tr)
        end = sol.x[-1]
        ends.append(end)
        assert np.max(np.abs(end - x[-1])) < 1e-2, (d, end, x[-1])
        assert np.max(np.abs(end - np.array([0.0, 2 * np.pi, 0.0, 0.0]))) < 1e-2
        # the pole went over the top (a real swing-up, not a hold near hanging)
        assert np.max(sol.x[:, 1]) > 5.5
    # without the tracker, the same start and the reference's inputs miss
    open_loop = sim.simulate(x[0] + np.array([0.0, 0.05, 0.0, 0.0]), 8.0, PERIOD,
                             r=(t, r[:, 0]))
    assert np.max(np.abs(open_loop.x[-1] - x[-1])) > 0.1


def test_ensemble_runs_the_tracker_and_it_pickles_as_its_law(sim, swing):
    import pickle
    t, x, r, tr = swing
    X0 = np.array([x[0] + [0.0, d, 0.0, 0.0] for d in (-0.05, 0.02, 0.05)])
    res = sim.ensemble(X0, 8.0, 1e-3, controller=tr, reduce="final")
    for i, x0 in enumerate(X0):
        one = sim.simulate(x0, 8.0, 1e-3, controller=tr)
        assert np.max(np.abs(res.values["final"][i] - one.x[-1])) < 1e-13
    law = pickle.loads(pickle.dumps(tr))
    assert type(law) is gen.LinearFeedback and law.n_gain == tr.n_gain == 801
    a = sim.simulate(X0[0], 2.0, 1e-3, controller=law)
    b = sim.simulate(X0[0], 2.0, 1e-3, controller=tr)
    assert np.array_equal(a.x, b.x)


def test_constrained_model_the_sleigh():
    """A nonholonomic model (examples/chaplygin_sleigh.py: u_y dependent):
    the reference between the nodes satisfies the constraint, and the
    tracker brings a heading 0.05 rad off back onto the reference."""
    import chaplygin_sleigh as cs
    sim = gen.compile(cs.model())
    ref = sim.simulate(np.array([0.0, 0.0, 0.0, 0.5, 0.0, 0.0]), 4.0, 0.05,
                       r=lambda t, x: np.array([1.0 + 0.5 * np.sin(t), 0.2 * np.cos(t)]),
                       input_period=0.05)
    tr = gen.TrajectoryTracker(sim, ref.t, ref.x, ref.r, np.diag([10, 10, 10, 1, 1.0]),
                               0.1 * np.eye(2), 0.02)
    assert tr.K.shape == (201, 2, 5)
    nq = sim.nq
    worst = max(np.max(np.abs(sim.velocity_constraints(xk[:nq], xk[nq:]))) for xk in tr.x_op)
    assert worst < 1e-12
    x0 = ref.x[0].copy()
    x0[2] += 0.05
    x0 = sim.consistent_state(x0)
    sol = sim.simulate(x0, 4.0, 1e-3, controller=tr)
    assert np.max(np.abs(sol.x[-1] - ref.x[-1])) < 1e-2
    open_loop = sim.simulate(x0, 4.0, 0.05, r=(ref.t, ref.r))
    assert np.max(np.abs(open_loop.x[-1] - ref.x[-1])) > 0.1


def test_schedule_rows_change_at_their_times(sim):
    """A LinearFeedback schedule evaluated continuously (period None): row k
    from t_gain + k dt_gain on, the rows' changes are step boundaries; the
    C runtime's <p>_eval_input and LinearFeedback's numpy law agree."""
    K = np.array([[[1.0, 2.0, 3.0, 4.0]], [[-1.0, 0.5, 0.0, 2.0]], [[0.0, 0.0, 0.0, 1.0]]])
    xo = np.array([[0.1, 0.0, 0.0, 0.0], [0.0, 0.2, 0.0, 0.0], [0.0, 0.0, 0.3, 0.0]])
    fb = gen.LinearFeedback(K, xo, np.array([1.0, 2.0, 3.0]), t_gain=0.5, dt_gain=0.25)
    lib = sim.library
    from gen.sim.inputs import plan_inputs
    plan = plan_inputs(sim, None, fb, 1e-3, "rk4", None, "zoh")
    fn = lib.function("eval_input")
    x = np.array([0.3, -0.2, 0.1, 0.4])
    out = np.zeros(1)
    for t, row in ((0.0, 0), (0.5, 0), (0.7499, 0), (0.75, 1), (0.9, 1), (1.0, 2), (5.0, 2),
                   (0.75 - 1e-17, 1)):
        assert fn(t, lib.array(x), plan.struct, lib.array(out)) == 0
        want = [1.0, 2.0, 3.0][row] - K[row] @ (x - xo[row])
        assert abs(out[0] - want) < 1e-14, (t, out, want)
        assert abs(fb(sim, t, x)[0] - want) < 1e-14
    # a continuous run: the breaks at 0.75 and 1.0 are steps' ends
    sol = sim.simulate(x, 1.2, 0.1, method="dopri5", controller=fb, rtol=1e-12, atol=1e-12)
    from scipy.integrate import solve_ivp

    def rhs(t, y):
        return sim.rhs(t, y, r=fb(sim, t, y))
    ref = solve_ivp(rhs, (0, 1.2), x, method="DOP853", rtol=1e-12, atol=1e-12,
                    t_eval=sol.t)
    assert np.max(np.abs(ref.y.T - sol.x)) < 1e-8


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_runs_the_tracker_too(sim, swing):
    """The C++/Eigen face over the same runtime: the same tracked run."""
    from conftest import require_eigen
    require_eigen()
    t, x, r, tr = swing
    sim_e = gen.compile(cp.model(), backend="eigen")
    x0 = x[0] + np.array([0.0, 0.05, 0.0, 0.0])
    for method, dt in (("rk4", 1e-3), ("dopri5", 0.05)):
        a = sim.simulate(x0, 8.0, dt, method=method, controller=tr)
        b = sim_e.simulate(x0, 8.0, dt, method=method, controller=tr)
        assert np.max(np.abs(a.x - b.x)) < 1e-10 and np.max(np.abs(a.r - b.r)) < 1e-9, method


@pytest.mark.slow
def test_example_runs_and_writes_the_c_sources(tmp_path, capsys):
    sol = cpt.main(["--reference", "simulated", "--c-out", str(tmp_path / "cart_pole")])
    out = capsys.readouterr().out
    assert "800 samples every 0.01" in out and "28836 bytes of flash in float" in out
    assert abs(sol.x[-1, 1] - 2 * np.pi) < 1e-2
    assert (tmp_path / "cart_pole" / "swingup.c").is_file()
    assert (tmp_path / "cart_pole" / "cart_pole.h").is_file()


# ------------------------------------------------------------ bad input
def test_bad_input_is_named(sim):
    t = np.linspace(0, 1, 11)
    x, r = np.zeros((11, 4)), np.zeros((11, 1))

    def bad(match, **kw):
        args = dict(t=t, x=x, r=r, Q=Q, R=R, period=0.1)
        args.update(kw)
        with pytest.raises(gen.InputError, match=match):
            gen.TrajectoryTracker(sim, args["t"], args["x"], args["r"], args["Q"], args["R"],
                                  args["period"])

    bad(r"x must have shape \(len\(t\), nx\) = \(11, 4\) \(the state x, theta, v, omega",
        x=np.zeros((11, 3)))
    bad(r"r must have shape \(len\(t\), nr\) = \(11, 1\) \(the inputs F", r=np.zeros((10, 1)))
    bad(r"t must be the reference's node times", t=np.array([0.0]))
    bad(r"t must be strictly increasing, but t\[3\] = 0.2 <= t\[2\] = 0.2",
        t=np.array([0, .1, .2, .2, .4, .5, .6, .7, .8, .9, 1.]))
    bad(r"Q must have shape \(ns, ns\) = \(4, 4\) \(a weight on the independent state x, "
        r"theta, v, omega\)", Q=np.eye(3))
    bad(r"R must have shape \(nr, nr\) = \(1, 1\) \(a weight on the inputs F\)", R=np.eye(2))
    bad(r"period must be a positive number, got period = 0.0", period=0.0)
    bad(r"period must be a positive number, got period = -0.1", period=-0.1)
    bad(r"period = 2.0 is longer than the trajectory \(t\[-1\] - t\[0\] = 1.0\)", period=2.0)
    Qa = np.eye(4)
    Qa[0, 1] = 0.5
    bad(r"Q must be symmetric, but Q\[0, 1\] = 0.5 \(x, theta\) != Q\[1, 0\] = 0.0", Q=Qa)
    bad(r"Q must be positive semidefinite; its smallest eigenvalue is -1.0",
        Q=np.diag([1.0, -1.0, 1.0, 1.0]))
    bad(r"R must be positive definite .*smallest eigenvalue is 0.0", R=np.zeros((1, 1)))
    bad(r"x\[3, 1\] = nan \(node 3, theta\)",
        x=np.where(np.arange(44).reshape(11, 4) == 13, np.nan, 0))
    with pytest.raises(ValueError):             # an InputError is a ValueError
        gen.TrajectoryTracker(sim, t, x, r, Q, R, float("nan"))
    with pytest.raises(gen.InputError, match=r"r_min\[0\] = 2.0 > r_max\[0\] = 1.0 \(F\)"):
        gen.TrajectoryTracker(sim, t, x, r, Q, R, 0.1, r_min=[2.0], r_max=[1.0])
    with pytest.raises(gen.InputError, match=r"r_max must have nr = 1 values"):
        gen.TrajectoryTracker(sim, t, x, r, Q, R, 0.1, r_max=[1.0, 2.0])
    tr = gen.TrajectoryTracker(sim, t, x, r, Q, R, 0.1)
    with pytest.raises(gen.InputError, match="tracker name 'int'"):
        tr.sources(name="int")
    with pytest.raises(gen.InputError, match="is the model's"):
        tr.sources(name="cart_pole")


# --------------------------------------------------- C: binary, target
def _cc():
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        require_tool("gcc")
    return cc


STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wdouble-promotion", "-Wvla",
          "-Wshadow"]


@pytest.mark.slow
def test_standalone_binary_runs_the_tracker_from_const_tables(sim, swing, tmp_path):
    """(e) The standalone binary built with -DCART_POLE_TRACKER=swingup: its
    run equals sim.simulate's with the tracker to 1e-12; the tables are
    const (no writable data in the tracker's object)."""
    t, x, r, tr = swing
    src = tmp_path / "src"
    gen.generate(cp.model(), src)
    files = tr.to_c(src, name="swingup")
    assert sorted(f.name for f in files) == ["swingup.c", "swingup.h"]
    text = (src / "swingup.c").read_text()
    assert "static const cart_pole_real swingup_K[801 * CART_POLE_NR * CART_POLE_NS]" in text
    assert "malloc" not in text and "static cart_pole_real" not in text
    exe = tmp_path / "cart_pole_sim"
    cc = _cc()
    subprocess.run([cc, *STRICT, "-O2", "-DCART_POLE_TRACKER=swingup", "-I", str(src),
                    *sorted(str(p) for p in src.glob("*.c")), "-lm", "-o", str(exe)],
                   check=True)
    # the tracker's object: text and read-only data only
    obj = tmp_path / "swingup.o"
    subprocess.run([cc, *STRICT, "-O2", "-c", "-I", str(src), str(src / "swingup.c"), "-o",
                    str(obj)], check=True)
    if shutil.which("size"):
        from gen.toolchain.footprint import section_sizes
        sec = section_sizes(obj)
        assert sec["data"] == 0 and sec["bss"] == 0, sec
        assert sec["rodata"] >= tr.footprint("double")["flash"], sec
    x0 = x[0] + np.array([0.0, 0.05, 0.0, 0.0])
    out = subprocess.run([str(exe), "--t-end", "8", "--dt", "1e-3", "--x0",
                          f"theta={float(x0[1])!r}"], capture_output=True, text=True,
                         check=True).stdout
    lines = out.strip().splitlines()
    assert lines[0].split(",") == ["t", "x", "theta", "v", "omega", "tip_x", "tip_y", "F"]
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    sol = sim.simulate(x0, 8.0, 1e-3, controller=tr)
    assert data.shape[0] == len(sol.t)
    assert np.max(np.abs(data[:, 1:5] - sol.x)) < 1e-12
    assert np.max(np.abs(data[:, 7] - sol.r[:, 0])) < 1e-12
    # the generated CMake project's option builds the same program
    if shutil.which("cmake"):
        b = tmp_path / "build"
        for cmd in (["cmake", "-S", str(src), "-B", str(b), "-DCART_POLE_TRACKER=swingup"],
                    ["cmake", "--build", str(b), "--target", "cart_pole_sim"]):
            p = subprocess.run(cmd, capture_output=True, text=True)
            assert p.returncode == 0, p.stdout + p.stderr
        out2 = subprocess.run([str(b / "cart_pole_sim"), "--t-end", "8", "--dt", "1e-3",
                               "--x0", f"theta={float(x0[1])!r}"], capture_output=True,
                              text=True, check=True).stdout
        data2 = np.array([[float(v) for v in ln.split(",")]
                          for ln in out2.strip().splitlines()[1:]])
        assert np.max(np.abs(data2[:, 1:5] - sol.x)) < 1e-12


def _build_driver(model, tr, out, real, cc, extra=()):
    src = out / f"src_{real}"
    gen.generate(model, src, real=real)
    tr.to_c(src, name="swingup", real=real)
    exe = out / f"tracker_driver_{real}"
    from gen.codegen.render import model_sources
    sources = [str(src / f) for f in model_sources(model.name)] + sorted(
        str(s) for s in src.glob("gen_rt_*.c") if s.name != "gen_rt_main.c") + [
        str(src / "swingup.c")]
    cmd = [cc, *extra, "-O2", *STRICT, "-DFW_MODEL=cart_pole", "-DFW_MODEL_UPPER=CART_POLE",
           '-DFW_HEADER="cart_pole.h"', "-DTRK=swingup", "-DTRK_UPPER=SWINGUP",
           '-DTRK_HEADER="swingup.h"', "-I", str(src), str(EMB / "tracker_driver.c"),
           *sources, "-lm", "-o", str(exe)]
    return exe, cmd, subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                      text=True)


def _run_driver(cmd, t_end, dt, x0):
    res = subprocess.run([*cmd, str(t_end), repr(dt), *[f"{v:.9g}" for v in x0]],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    rows = {"x": [], "r": []}
    for line in res.stdout.splitlines():
        tag, *vals = line.split()
        rows[tag].append([float(v) for v in vals])
    return np.array(rows["x"]), np.array(rows["r"])


@pytest.mark.slow
@pytest.mark.embedded
def test_float_cortex_build_agrees_with_double_under_qemu(sim, swing, tmp_path):
    """(f) The tracker's step in the float and double builds (ARM Linux
    cross build under qemu-arm, as tests/features/test_embedded.py runs the seed),
    closing the loop every 10 ms over RK4 steps of 1 ms: the same run as the
    host's double sim.simulate, float to 1e-4; the Cortex-M4F object of the
    tables: const data only, its size reported."""
    require_tool("arm-linux-gnueabihf-gcc")
    require_tool("qemu-arm")
    t, x, r, tr = swing
    model = cp.model()
    procs = {real: _build_driver(model, tr, tmp_path, real, "arm-linux-gnueabihf-gcc",
                                 ["-static"]) for real in ("float", "double")}
    for real, (exe, cmd, proc) in procs.items():
        log, _ = proc.communicate()
        assert proc.returncode == 0, " ".join(cmd) + "\n" + log
    x0 = (x[0] + np.array([0.0, 0.05, 0.0, 0.0])).astype(np.float32).astype(float)
    host = sim.simulate(x0, 8.0, 1e-3, controller=tr)
    Xh, Rh = host.x[::10], host.r[::10][:-1]
    res = {}
    for real in ("float", "double"):
        X, Rr = _run_driver(["qemu-arm", str(procs[real][0])], 8.0, 1e-3, x0)
        assert X.shape == (801, 5) and Rr.shape == (800, 2)
        # max-abs over the run / max |value| (tests/features/test_embedded.py's measure),
        # and the end state's largest difference
        res[real] = (np.max(np.abs(X[:, 1:] - Xh)) / np.max(np.abs(Xh)),
                     np.max(np.abs(Rr[:, 1] - Rh[:, 0])) / np.max(np.abs(Rh)),
                     np.max(np.abs(X[-1, 1:] - Xh[-1])))
    # %.9g printing bounds the double comparison
    assert max(res["double"]) < 1e-8, res
    assert max(res["float"]) < 1e-3 and res["float"][0] < 1e-4 and res["float"][1] < 1e-4, res
    # both builds end upright
    assert abs(X[-1, 2] - 2 * np.pi) < 1e-2
    # the float tables on the Cortex-M4F: text and const data, nothing in RAM
    fp_float = tr.footprint("float")
    sec = cortex_m4_tables(tmp_path / "src_float", "swingup.c", tmp_path / "swingup_m4.o",
                           STRICT, fp_float["flash"])
    if sec is not None:
        print(f"\ntracker (801 rows) on the Cortex-M4F, float: tables {fp_float['flash']} B "
              f"(K {fp_float['K']}, x_ref {fp_float['x_ref']}, r_ref {fp_float['r_ref']}), "
              f"object .text {sec['text']} B, .rodata {sec['rodata']} B, RAM 0 B")
    print("qemu-arm vs host double, max-abs / max |value| of the state and of F, and the "
          "end state's max-abs difference: " + "; ".join(
              f"{k}: {v[0]:.1e}, {v[1]:.1e}, {v[2]:.1e}" for k, v in res.items()))
