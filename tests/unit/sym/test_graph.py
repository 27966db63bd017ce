"""Non-smooth functions (issue 14): sign, Abs, Heaviside, floor, ceiling,
Min, Max, Piecewise and relations print exactly (C99 double and float, C++),
are differentiated almost everywhere for the linearization (gen.sym.graph.partial),
and anything the generator cannot print is refused when the model is created,
named in the user's symbols.

Physics (examples/nonsmooth.py), against closed forms:
- quadratic drag m v' = m g - c |v| v from rest: v = v_t tanh(g t / v_t),
  x = v_t^2/g ln cosh(g t / v_t), v_t = sqrt(m g / c);
- Coulomb friction m v' = -mu m g sign(v): v = v0 - mu g t, x = v0 t - mu g t^2/2
  until the block stops;
- sympy's CoulombKineticFriction docstring example (spring, kinetic and viscous
  friction): while v < 0, an underdamped oscillator about d = mu_k m g / k.
Linearization: central differences of sim.rhs at smooth points; at a kink the
documented convention (mean of the one-sided derivatives for Abs/Min/Max, 0 for
sign/Heaviside/floor/ceiling, the selected branch for Piecewise).
"""
import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen
import nonsmooth as ns
from gen.sym.graph import differentiate_graph, partial
from gen.sym.printers import ModelCPrinter, ModelCxxPrinter, check_printable, unprintable


# ----------------------------------------------------------------- models
@pytest.fixture(scope="module")
def drag():
    model = ns.drag_model()
    return model, gen.compile(model)


@pytest.fixture(scope="module")
def block():
    model = ns.friction_model()
    return model, gen.compile(model)


@pytest.fixture(scope="module")
def actuator():
    model = ns.actuator_model()
    return model, gen.compile(model)


def _kinks_model():
    """Three independent unit masses with one kink each:
    x1'' = -c |v1|            (a V-shaped damper: kink at v1 = 0)
    x2'' = -k Max(x2, 0)      (a one-sided spring, contact: kink at x2 = 0)
    x3'' = Piecewise((-k x3, x3 > 0), (-k x3/4, True))  (kink at x3 = 0)
    x4'' = -k floor(x4) - Heaviside(v4) - Min(v4, 1)    (jumps, and Min)"""
    q = me.dynamicsymbols("x1:5")
    u = me.dynamicsymbols("v1:5")
    c, k = sm.symbols("c k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    bodies, loads = [], []
    forces = [-c * sm.Abs(u[0]), -k * sm.Max(q[1], 0),
              sm.Piecewise((-k * q[2], q[2] > 0), (-k * q[2] / 4, True)),
              -k * sm.floor(q[3]) - sm.Heaviside(u[3]) - sm.Min(u[3], 1)]
    for i in range(4):
        P = O.locatenew(f"P{i}", q[i] * N.x)
        P.set_vel(N, u[i] * N.x)
        bodies.append(me.Particle(f"m{i}", P, 1))
        loads.append((P, forces[i] * N.x))
    KM = me.KanesMethod(N, q_ind=list(q), u_ind=list(u),
                        kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u)])
    KM.kanes_equations(bodies, loads)
    return gen.Model.from_kanes(KM, constants={c: 0.7, k: 3.0}, name="kinks")


@pytest.fixture(scope="module")
def kinks():
    model = _kinks_model()
    return model, gen.compile(model)


def central_differences(sim, x, h=1e-6):
    n = len(x)
    J = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        J[:, j] = (sim.rhs(0.0, x + e) - sim.rhs(0.0, x - e)) / (2 * h)
    return J


# ------------------------------------------------------------- the bug
def test_nonsmooth_models_compile(drag, block, actuator, kinks):
    # before issue 14: PrintMethodNotImplementedError (im, Derivative, DiracDelta)
    # from the derivatives of Abs and sign in the linearization kernel
    for model, sim in (drag, block, actuator, kinks):
        assert sim.nx == model.nx


# -------------------------------------------------------------- physics
def test_drag_terminal_velocity(drag):
    model, sim = drag
    m, g, c = ns.DRAG["m"], ns.DRAG["g"], ns.DRAG["c"]
    vt = np.sqrt(m * g / c)
    t, X = sim.simulate([0.0, 0.0], 3.0, 0.25, method="dopri5", rtol=1e-12, atol=1e-13)
    v_exact = vt * np.tanh(g * t / vt)
    x_exact = vt**2 / g * np.log(np.cosh(g * t / vt))
    assert len(t) == 13
    err_v = np.max(np.abs(X[:, 1] - v_exact))
    err_x = np.max(np.abs(X[:, 0] - x_exact))
    assert err_v < 1e-8 and err_x < 1e-8, (err_v, err_x)
    # and at terminal speed the drag balances gravity
    assert abs(sim.rhs(0.0, [0.0, vt])[1]) < 1e-12


def test_drag_rk4_small_step(drag):
    model, sim = drag
    m, g, c = ns.DRAG["m"], ns.DRAG["g"], ns.DRAG["c"]
    vt = np.sqrt(m * g / c)
    t, X = sim.simulate([0.0, 0.0], 2.0, 1e-3, method="rk4")
    idx = [250, 500, 1000, 1500, 2000]
    err = np.max(np.abs(X[idx, 1] - vt * np.tanh(g * t[idx] / vt)))
    assert err < 1e-8, err


def test_coulomb_block_decelerates_at_mu_g(block):
    model, sim = block
    g, mu = ns.FRICTION["g"], ns.FRICTION["mu"]
    v0 = 2.0
    t_stop = v0 / (mu * g)                       # 0.6796 s
    for method, dt in (("rk4", 1e-3), ("dopri5", 0.05)):
        t, X = sim.simulate([0.0, v0], 0.65, dt, method=method, rtol=1e-12, atol=1e-13)
        assert t[-1] < t_stop
        err_v = np.max(np.abs(X[:, 1] - (v0 - mu * g * t)))
        err_x = np.max(np.abs(X[:, 0] - (v0 * t - mu * g * t**2 / 2)))
        assert err_v < 1e-8 and err_x < 1e-8, (method, err_v, err_x)
    # sign(0) = 0: a block at rest stays at rest
    assert np.all(sim.rhs(0.0, [0.3, 0.0]) == 0.0)


def test_sympy_coulomb_kinetic_friction_actuator(actuator):
    """sympy's docstring example: from x0 > 0 at rest the block moves left
    (v < 0) as m x'' + sigma x' + k (x - d) = 0, d = mu_k m g / k, until
    it stops after about half a damped period."""
    model, sim = actuator
    m, g, k = ns.ACTUATOR["m"], ns.ACTUATOR["g"], ns.ACTUATOR["k"]
    mu, sigma = ns.ACTUATOR["mu_k"], ns.ACTUATOR["sigma"]
    assert model.f[0].has(sm.sign) and model.f[0].has(sm.Abs)
    d = mu * m * g / k
    w0 = np.sqrt(k / m)
    zeta = sigma / (2 * np.sqrt(k * m))
    wd = w0 * np.sqrt(1 - zeta**2)
    x0 = 0.5
    # at rest sign(v) = 0: start moving (v slightly negative), as the block would
    t, X = sim.simulate([x0, 0.0], 0.45, 0.05, method="dopri5", rtol=1e-12, atol=1e-13)
    # the first instant has v = 0 (no friction) for one step of measure zero; compare
    # with the solution that has friction from t = 0+
    A = x0 - d
    e = np.exp(-zeta * w0 * t)
    x_exact = d + A * e * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))
    v_exact = -A * e * (w0**2 / wd) * np.sin(wd * t)
    assert np.pi / wd > 0.45 and np.all(v_exact[1:] < 0)
    err = max(np.max(np.abs(X[:, 0] - x_exact)), np.max(np.abs(X[:, 1] - v_exact)))
    assert err < 1e-8, err
    # and it runs on through the stops (x passes 0 away from the grid of
    # the 0/0 at x = 0 exactly; sympy's expression is x/|x|)
    t, X = sim.simulate([x0, 0.0], 5.0, 0.01, method="rk4")
    assert np.all(np.isfinite(X)) and abs(X[-1, 0]) < x0


# ---------------------------------------------------------- linearization
def test_linearize_drag_smooth_point_matches_central_differences(drag):
    model, sim = drag
    m, c = ns.DRAG["m"], ns.DRAG["c"]
    for v in (3.0, -1.5):
        x = np.array([0.4, v])
        A, _ = sim.linearize(x)
        J = central_differences(sim, x)
        assert np.max(np.abs(A - J)) < 1e-7, (A, J)
        assert abs(A[1, 1] - (-2 * c * abs(v) / m)) < 1e-12


def test_linearize_at_kinks(drag, block, kinks):
    # drag: |v| v is C1, its derivative at 0 is 0 (sign(0) = 0 gives it)
    A, _ = drag[1].linearize([0.0, 0.0])
    assert np.array_equal(A, [[0.0, 1.0], [0.0, 0.0]])
    # Coulomb friction: d sign = 0, at v = 0 too (the Dirac part is dropped)
    for v in (0.0, 1.0, -1.0):
        A, _ = block[1].linearize([0.0, v])
        assert np.array_equal(A, [[0.0, 1.0], [0.0, 0.0]])
    # the V-damper, the one-sided spring and the Piecewise spring at their kinks
    model, sim = kinks
    c, k = 0.7, 3.0
    A, _ = sim.linearize(np.zeros(8))
    B = A[4:, :4]            # d accelerations / d positions
    C = A[4:, 4:]            # d accelerations / d speeds
    assert C[0, 0] == 0.0                 # d(-c|v|)/dv at 0: mean of -c and +c
    assert B[1, 1] == -k / 2              # d(-k Max(x, 0))/dx at 0: mean of -k and 0
    assert B[2, 2] == -k / 4              # Piecewise: the branch selected at x = 0
    assert B[3, 3] == 0.0                 # d floor = 0 (also at the jump x = 0)
    assert C[3, 3] == -1.0                # d Heaviside = 0 at its jump; d Min(v, 1) = 1 at v = 0
    A, _ = sim.linearize(np.array([0, 0, 0, 1.0, 0, 0, 0, 1.0]))
    assert A[7, 7] == -0.5                # Min(v, 1) at the tie v = 1: mean of 1 and 0
    # one-sided values at smooth points, against central differences
    x = np.array([0.3, 0.2, -0.4, 0.5, -0.6, 0.1, 0.2, 0.4])
    A, _ = sim.linearize(x)
    assert np.max(np.abs(A - central_differences(sim, x))) < 1e-7
    x = -x
    A, _ = sim.linearize(x)
    assert np.max(np.abs(A - central_differences(sim, x))) < 1e-7


def test_verify_nonsmooth_models(drag, block, actuator):
    for model, sim in (drag, block, actuator):
        report = gen.verify(model, samples=8, sim=sim)
        assert report.ok, report.table()
        assert dict((r[0], r[1]) for r in report.rows)["linearize"] < 1e-9


def test_float_build_of_drag(drag):
    model, _ = drag
    sim = gen.compile(model, real="float")
    vt = np.sqrt(ns.DRAG["m"] * ns.DRAG["g"] / ns.DRAG["c"])
    t, X = sim.simulate([0.0, 0.0], 2.0, 1e-2, method="rk4")
    assert np.max(np.abs(X[:, 1] - vt * np.tanh(ns.DRAG["g"] * t / vt))) < 1e-4


# ----------------------------------------------------- differentiation
x, y, z = sm.symbols("x y z")


@pytest.mark.parametrize("expr,wrt,expected", [
    (sm.Abs(x), x, sm.sign(x)),
    (sm.Abs(x) * x, x, x * sm.sign(x) + sm.Abs(x)),
    (sm.sign(x) * y, x, 0),
    (sm.Heaviside(x) * x, x, sm.Heaviside(x)),
    (sm.floor(x) + sm.ceiling(x), x, 0),
    (sm.Max(x, y), x, sm.Piecewise((1, x > y), (0, x < y), (sm.S.Half, True))),
    (sm.Min(x, y), y, sm.Piecewise((0, x < y), (1, x > y), (sm.S.Half, True))),
    (sm.Piecewise((x**2, x > 0), (sm.sin(x), True)), x,
     sm.Piecewise((2 * x, x > 0), (sm.cos(x), True))),
    (sm.sin(sm.Abs(x)), x, sm.cos(sm.Abs(x)) * sm.sign(x)),
    (sm.exp(x * y), x, y * sm.exp(x * y)),           # smooth: sympy's diff
])
def test_partial_rules(expr, wrt, expected):
    assert sm.simplify(partial(expr, wrt) - expected) == 0


def test_differentiate_graph_has_no_dirac_or_derivative():
    w0, w1 = sm.symbols("w0 w1")
    assignments = [(w0, sm.Abs(x) * x), (w1, sm.sign(w0) * sm.Heaviside(y))]
    new, jac = differentiate_graph(assignments, [w0 + w1 * sm.Max(x, y)], [x, y])
    everything = [e for _, e in new] + jac[0]
    for e in everything:
        assert not e.has(sm.Derivative, sm.DiracDelta, sm.re, sm.im), e


# --------------------------------------------------------------- printers
P0, P1 = sm.symbols("P0 P1")
SYMBOLS = {x: "q[0]", y: "u[0]", z: "p[0]"}

# (expression, C double, C float, C++ Scalar)
CASES = [
    (sm.Abs(x), "fabs(q[0])", "fabsf(q[0])", "std::fabs(q[0])"),
    (sm.sign(x), "((q[0]) > 0 ? 1.0 : ((q[0]) < 0 ? -1.0 : 0.0))",
     "((q[0]) > 0 ? 1.0F : ((q[0]) < 0 ? -1.0F : 0.0F))",
     "((q[0]) > 0 ? Scalar(1.0) : ((q[0]) < 0 ? -Scalar(1.0) : Scalar(0.0)))"),
    (sm.Heaviside(x), "((q[0]) > 0 ? 1.0 : ((q[0]) < 0 ? 0.0 : 0.5))",
     "((q[0]) > 0 ? 1.0F : ((q[0]) < 0 ? 0.0F : 0.5F))",
     "((q[0]) > 0 ? Scalar(1.0) : ((q[0]) < 0 ? Scalar(0.0) : Scalar(0.5)))"),
    (sm.Heaviside(x, 1), "((q[0]) > 0 ? 1.0 : ((q[0]) < 0 ? 0.0 : 1.0))",
     "((q[0]) > 0 ? 1.0F : ((q[0]) < 0 ? 0.0F : 1.0F))",
     "((q[0]) > 0 ? Scalar(1.0) : ((q[0]) < 0 ? Scalar(0.0) : Scalar(1.0)))"),
    (sm.floor(x), "floor(q[0])", "floorf(q[0])", "std::floor(q[0])"),
    (sm.ceiling(x), "ceil(q[0])", "ceilf(q[0])", "std::ceil(q[0])"),
    (sm.Min(x, y), "fmin(q[0], u[0])", "fminf(q[0], u[0])", "std::fmin(q[0], u[0])"),
    (sm.Max(x, y, z), "fmax(q[0], fmax(u[0], p[0]))", "fmaxf(q[0], fmaxf(u[0], p[0]))",
     "std::fmax(q[0], std::fmax(u[0], p[0]))"),
    (sm.Piecewise((x, x > y), (y, True)), "((q[0] > u[0]) ? (q[0]) : (u[0]))",
     "((q[0] > u[0]) ? (q[0]) : (u[0]))", "((q[0] > u[0]) ? (q[0]) : (u[0]))"),
    (sm.Piecewise((x, (x >= 0) & (y < 1.5)), (x**2, sm.Eq(y, 2) | sm.Ne(x, z)),
                  (-x, ~(x <= z)), (0, True)),
     "(((u[0] < 1.5) && (q[0] >= 0)) ? (q[0]) : (((u[0] == 2) || (q[0] != p[0])) ? "
     "((q[0]*q[0])) : ((q[0] > p[0]) ? (-q[0]) : (0.0))))",
     "(((u[0] < 1.5F) && (q[0] >= 0)) ? (q[0]) : (((u[0] == 2) || (q[0] != p[0])) ? "
     "((q[0]*q[0])) : ((q[0] > p[0]) ? (-q[0]) : (0.0F))))",
     "(((u[0] < Scalar(1.5)) && (q[0] >= 0)) ? (q[0]) : (((u[0] == 2) || (q[0] != p[0])) ? "
     "((q[0]*q[0])) : ((q[0] > p[0]) ? (-q[0]) : (Scalar(0.0)))))"),
    # integer arms print as real literals (both arms of a ternary have the real type)
    (sm.Piecewise((1, x > 0), (-2, True)), "((q[0] > 0) ? (1.0) : (-2.0))",
     "((q[0] > 0) ? (1.0F) : (-2.0F))", "((q[0] > 0) ? (Scalar(1.0)) : (Scalar(-2.0)))"),
    (sm.Mod(x, z), "((q[0]) - (p[0])*floor((q[0])/(p[0])))",
     "((q[0]) - (p[0])*floorf((q[0])/(p[0])))",
     "((q[0]) - (p[0])*std::floor((q[0])/(p[0])))"),
    (sm.atan2(y, x), "atan2(u[0], q[0])", "atan2f(u[0], q[0])", "std::atan2(u[0], q[0])"),
    (sm.exp(-x), "exp(-q[0])", "expf(-q[0])", "std::exp(-q[0])"),
    (sm.log(x), "log(q[0])", "logf(q[0])", "std::log(q[0])"),
    (sm.tanh(x / z), "tanh(q[0]/p[0])", "tanhf(q[0]/p[0])", "std::tanh(q[0]/p[0])"),
    (sm.sqrt(x), "sqrt(q[0])", "sqrtf(q[0])", "std::sqrt(q[0])"),
    (x**3, "(q[0]*q[0]*q[0])", "(q[0]*q[0]*q[0])", "(q[0]*q[0]*q[0])"),
    (x**z, "pow(q[0], p[0])", "powf(q[0], p[0])", "std::pow(q[0], p[0])"),
    (sm.Abs(y) * y, "u[0]*fabs(u[0])", "u[0]*fabsf(u[0])", "u[0]*std::fabs(u[0])"),
]
IDS = [str(c[0]) for c in CASES]


@pytest.mark.parametrize("expr,c_double,c_float,cxx", CASES, ids=IDS)
def test_print_c_double(expr, c_double, c_float, cxx):
    assert ModelCPrinter(SYMBOLS, "double").doprint(expr) == c_double


@pytest.mark.parametrize("expr,c_double,c_float,cxx", CASES, ids=IDS)
def test_print_c_float(expr, c_double, c_float, cxx):
    assert ModelCPrinter(SYMBOLS, "float").doprint(expr) == c_float


@pytest.mark.parametrize("expr,c_double,c_float,cxx", CASES, ids=IDS)
def test_print_cxx(expr, c_double, c_float, cxx):
    assert ModelCxxPrinter(SYMBOLS).doprint(expr) == cxx


def test_printed_values_match_sympy():
    """The printed forms have sympy's values, at the kinks too: evaluate the
    C-syntax strings as Python (ternaries rewritten) on a grid including 0."""
    import math

    env = {"fabs": abs, "floor": math.floor, "ceil": math.ceil, "fmin": min, "fmax": max}
    for expr in (sm.sign(x), sm.Heaviside(x), sm.Heaviside(x, 0), sm.floor(x), sm.ceiling(x),
                 sm.Min(x, 0.5), sm.Max(x, -0.5), sm.Abs(x)):
        code = ModelCPrinter({x: "X"}, "double").doprint(expr)
        code = code.replace("((X) > 0 ? ", "(").replace(" : ((X) < 0 ? ", " if X > 0 else (")
        code = code.replace(" : ", " if X < 0 else ")
        for xv in (-1.5, -0.5, 0.0, 0.25, 0.5, 2.0):
            got = eval(code, dict(env, X=xv))          # noqa: S307 - our own printed code
            want = float(expr.subs(x, xv))
            assert got == want, (expr, xv, code, got, want)


# --------------------------------------------------------------- refusals
def _particle(force_of):
    xq, v = me.dynamicsymbols("x v")
    m, c = sm.symbols("m c")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", xq * N.x)
    P.set_vel(N, v * N.x)
    KM = me.KanesMethod(N, q_ind=[xq], u_ind=[v], kd_eqs=[xq.diff() - v])
    KM.kanes_equations([me.Particle("pa", P, m)], [(P, force_of(xq, v, c) * N.x)])
    return lambda: gen.Model.from_kanes(KM, constants={m: 1.0, c: 0.3})


friction = sm.Function("friction")

REFUSALS = [
    ("besselj", lambda xq, v, c: -sm.besselj(0, c * v),
     "the forcing contain besselj(0, c*v(t)), which the generator cannot print: besselj is "
     "not a function the generator can write in C99 or C++ (see the README, Non-smooth "
     "models, for the supported ones)"),
    ("undefined friction(v)", lambda xq, v, c: -c * friction(v),
     "the forcing contain friction(v(t)), a call of the undefined function friction, which "
     "the generator cannot print: write it out with the functions it prints (sign, Abs, "
     "Heaviside, Min, Max, Piecewise, exp, tanh, ...)"),
    ("undefined friction(x, v)", lambda xq, v, c: friction(xq, v),
     "the forcing contain friction(x(t), v(t)), a call of the undefined function friction, "
     "which the generator cannot print: write it out with the functions it prints (sign, "
     "Abs, Heaviside, Min, Max, Piecewise, exp, tanh, ...)"),
    ("gamma: derivative unprintable", lambda xq, v, c: c * sm.gamma(v),
     "the forcing contain gamma(v(t)), which the generator cannot differentiate for the "
     "linearization: its derivative gamma(v(t))*polygamma(0, v(t)) cannot be printed"),
    ("Piecewise without default", lambda xq, v, c: sm.Piecewise((-c * v, v > 0)),
     "the forcing contain Piecewise((-c*v(t), v(t) > 0)), which the generator cannot print: "
     "a Piecewise needs a default branch (expr, True), used where no condition holds"),
    ("complex", lambda xq, v, c: sm.I * c * v,
     "the forcing contain I, which the generator cannot print: I is not a real number"),
    ("re", lambda xq, v, c: -c * sm.re(v),
     "the forcing contain re(v(t)), which the generator cannot print: re is not a function "
     "the generator can write in C99 or C++ (see the README, Non-smooth models, for the "
     "supported ones)"),
]


@pytest.mark.parametrize("force_of,message", [r[1:] for r in REFUSALS],
                         ids=[r[0] for r in REFUSALS])
def test_refused_at_model_creation(force_of, message):
    build = _particle(force_of)
    with pytest.raises(gen.ModelError) as info:
        build()
    assert str(info.value) == message


def test_function_of_time_keeps_its_message():
    F = me.dynamicsymbols("F")
    with pytest.raises(gen.ModelError, match=r"contain F\(t\), a function of time .* inputs="):
        _particle(lambda xq, v, c: F)()


def test_unprintable_returns_the_innermost_culprit():
    assert unprintable(sm.sin(x) * sm.Abs(y) + sm.Piecewise((x, x > 0), (0, True))) is None
    assert unprintable(sm.sin(sm.besselj(0, x)) + 1) == sm.besselj(0, x)
    assert unprintable(sm.exp(friction(x))) == friction(x)
    assert unprintable(sm.sqrt(x) + sm.loggamma(y)) == sm.loggamma(y)
    # names: the internal symbols shown as the user's
    with pytest.raises(gen.ModelError, match=r"contain besselj\(1, P0\*P1\),"):
        check_printable([sm.besselj(1, x * y)], "forcing", {x: P0, y: P1})
