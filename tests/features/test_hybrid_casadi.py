"""A hybrid model inside CasADi (issue 46): gen.casadi.functions gives each
declaration's guard_<name> and map_<name> (an Impact's impulse map) with
their derivatives, and step integrates one phase: a step across a guard is
refused (ERR_GUARD_CROSSED), never silently continued.

References: the simulator's own events (the guard at each located event, the
state after each jump: to 1e-14), sympy's expressions of the guard and the
map evaluated separately, the impulse's analytic rebound (-e v), CasADi's own
central finite differences (enable_fd) for every derivative, and the rimless
wheel's analytic steady state (McGeer; Coleman): the speed after each heel
strike cot(2 alpha) sqrt(4 (g/l) sin(alpha) sin(gamma)), reproduced by a
two-phase casadi.Opti problem built from step, guard_strike and map_strike.
"""
import os

import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me

import gen
from helpers import load_test_file

try:
    import casadi as ca
except ImportError:  # pragma: no cover - the CI installs it (the test extra)
    ca = None

if ca is None:
    if os.environ.get("CI") == "true":
        pytest.fail("casadi is required under CI=true (pip install eomgen[casadi])",
                    pytrace=False)
    pytestmark = pytest.mark.skip(reason="casadi not installed (pip install eomgen[casadi])")

import gen.export.casadi as gc  # noqa: E402  (importable without casadi)

hybrid = load_test_file("features/test_hybrid.py")
G, L, ALPHA, GAMMA = 9.81, 1.0, np.pi / 6, 0.3


def rimless_wheel(name="rimless_wheel"):
    """The rimless wheel (McGeer 1990): a hub mass on massless spokes of
    length l, 2 alpha apart, rolling down a slope gamma. theta is the stance
    spoke's angle from the vertical (theta'' = (g/l) sin theta); when it
    reaches gamma + alpha the next spoke strikes: theta -> theta - 2 alpha,
    theta' -> cos(2 alpha) theta' (angular momentum about the new foot)."""
    th = me.dynamicsymbols("theta")
    m, g, l, a, gam = sm.symbols("m g l alpha gamma")
    lm = me.LagrangesMethod(m * l**2 * th.diff()**2 / 2 - m * g * l * sm.cos(th), [th])
    lm.form_lagranges_equations()
    strike = gen.Reset(th - (gam + a), {th: th - 2 * a, th.diff(): sm.cos(2 * a) * th.diff()},
                       direction=1)
    return gen.Model.from_lagrange(lm, constants={m: 1.0, g: G, l: L, a: ALPHA, gam: GAMMA},
                                   name=name, hybrid={"strike": strike})


def steady_speed():
    """The speed just after each strike on the limit cycle (and before)."""
    after = np.sqrt(4 * G / L * np.sin(ALPHA) * np.sin(GAMMA)) / np.tan(2 * ALPHA)
    return after, after / np.cos(2 * ALPHA)


@pytest.fixture(scope="module")
def wheel():
    model = rimless_wheel()
    return model, gc.functions(model), gen.compile(model)


@pytest.fixture(scope="module")
def pendulum():
    """The seed nonminimal pendulum against a slanted wall: an impact whose
    impulse keeps the model's velocity constraint (mv = 1)."""
    model = hybrid._pendulum(0.5, "hyb_cs_pend")
    return model, gc.functions(model), gen.compile(model)


@pytest.fixture(scope="module")
def ball():
    model = hybrid._ball(name="hyb_cs_ball")
    return model, gc.functions(model), gen.compile(model)


def _v(a):
    return np.asarray(ca.DM(a).full(), float).ravel()


@pytest.mark.slow
def test_guards_and_maps_equal_the_simulator(wheel, ball, pendulum):
    """At every jump the simulator made: guard_<name>(x before) is the
    simulator's gap there bit for bit (zero to the event's location),
    map_<name>(x before) is the state after to 1e-14 (the same kernels and
    the same impulse solve; the pendulum's keeps its velocity constraint);
    and both equal sympy's expressions and the analytic rebound at other
    states."""
    for model, F, sim, x0, t_end in [(*wheel, [GAMMA - ALPHA, 1.6], 3.0),
                                     (*ball, [1.0, 0.0], 2.0),
                                     (*pendulum, [np.cos(0.8), np.sin(0.8), 0.0, 0.0], 1.5)]:
        name = model.hybrid[0].name
        assert list(F)[-2:] == [f"guard_{name}", f"map_{name}"]
        assert F[f"guard_{name}"].name_in() == ["x", "p", "t"]
        p = np.array(model.p_values)
        sol = sim.simulate(x0, t_end, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
        jumps = [e for e in sol.events if e.name == name]
        assert len(jumps) >= (1 if model is pendulum[0] else 3)
        for e in jumps:
            assert abs(_v(F[f"guard_{name}"](e.x, p, e.t))[0]) < 1e-12   # located
            assert np.abs(_v(F[f"map_{name}"](e.x, p, e.t)) - e.x_after).max() < 1e-14
            g = sim.hybrid_values(e.t, e.x)
            assert _v(F[f"guard_{name}"](e.x, p, e.t))[0] == g[0]
    # independent references: the wheel's guard and map from sympy, the
    # ball's impulse -e v
    model, F, _ = wheel
    p = np.array(model.p_values)
    for x in ([0.2, 1.1], [-0.4, 2.3]):
        assert _v(F["guard_strike"](x, p, 0))[0] == pytest.approx(x[0] - GAMMA - ALPHA,
                                                                   abs=1e-15)
        np.testing.assert_allclose(_v(F["map_strike"](x, p, 0)),
                                   [x[0] - 2 * ALPHA, np.cos(2 * ALPHA) * x[1]], atol=1e-15)
    model, F, _ = ball
    p = np.array(model.p_values)
    np.testing.assert_allclose(_v(F["map_ground"]([0.0, -3.0], p, 0)), [0.0, 2.4],
                               atol=1e-15)
    assert _v(F["guard_ground"]([0.7, -3.0], p, 0))[0] == 0.7
    # the pendulum's impulse at a state on the wall, off the motion: the
    # normal speed -e times before, the velocity constraint kept
    model, F, _ = pendulum
    p = np.array(model.p_values)
    phi = np.arcsin(-0.4 / np.hypot(1.0, 0.3)) - np.arctan2(0.3, 1.0)   # sin + 0.3 cos = -0.4
    q = np.array([np.cos(phi), np.sin(phi)])
    assert abs(q[1] + 0.3 * q[0] + 0.4) < 1e-12                      # on the wall
    u = 1.7 * np.array([-q[1], q[0]])                                 # along the circle
    u = u if u[1] + 0.3 * u[0] < 0 else -u                           # into the wall
    xa = _v(F["map_wall"](np.r_[q, u], p, 0))
    vn = lambda w: w[1] + 0.3 * w[0]  # noqa: E731
    assert vn(u) < -0.1
    np.testing.assert_allclose(xa[:2], q, atol=0)
    assert abs(vn(xa[2:]) + 0.5 * vn(u)) < 1e-13
    assert abs(q @ xa[2:]) < 1e-13


@pytest.mark.slow
@pytest.mark.parametrize("which,name", [("wheel", "guard_strike"), ("wheel", "map_strike"),
                                        ("ball", "guard_ground"), ("ball", "map_ground"),
                                        ("pendulum", "map_wall")])
def test_derivatives_against_casadi_finite_differences(request, which, name):
    """jac_<f> (every input: x, p, t), fwd1_/adj1_ and the exact Hessian of a
    weighted sum against CasADi's own central differences of the value (the
    same external with enable_fd and its derivatives off); the impact's map is
    the implicit function of the impulse's equations."""
    model, _, _ = request.getfixturevalue(which)
    path = str(gc.library(model))
    sym = f"{model.name}_{name}"
    exact = ca.external(sym, path)
    fd = ca.external(sym, path, {"enable_fd": True, "enable_jacobian": False,
                                 "enable_forward": False, "enable_reverse": False,
                                 "fd_method": "central"})
    x = {"ball": np.array([0.37, -1.9]), "wheel": np.array([0.11, 1.3]),
         "pendulum": np.array([0.62, -0.61, 1.3, 0.9])}[which]
    nx = x.size
    p, t = np.array(model.p_values) * 1.05, 0.2
    X, P, T = ca.MX.sym("X", nx), ca.MX.sym("P", p.size), ca.MX.sym("T")
    n = exact.nnz_out(0)
    w = np.linspace(0.7, 1.3, n)
    out = exact(X, P, T)
    z = ca.vertcat(X, P, T)
    d = ca.Function("d", [X, P, T], [ca.jacobian(out, z), ca.gradient(ca.dot(w, out), z),
                                     ca.jtimes(out, z, np.linspace(0.5, 1.5, z.numel()))])
    J, gr, fwd = [np.array(a.full()) for a in d(x, p, t)]
    # CasADi's central differences: one forward seed per column of x, p, t
    f1 = fd.forward(1)
    args = {"x": x, "p": p, "t": t}
    base = {**args, **{f"out_{k}": v for k, v in fd.call(args).items()},
            **{f"fwd_{k}": 0 * ca.DM(v) for k, v in args.items()}}
    cols = [np.array(f1.call({**base, f"fwd_{a}": e}).popitem()[1].full()).ravel()
            for a in ("x", "p", "t") for e in np.eye(np.size(args[a]))]
    Jfd = np.column_stack(cols)
    np.testing.assert_allclose(J, Jfd, rtol=1e-7, atol=1e-8)
    np.testing.assert_allclose(gr.ravel(), Jfd.T @ w, rtol=1e-7, atol=1e-8)
    np.testing.assert_allclose(fwd.ravel(), Jfd @ np.linspace(0.5, 1.5, z.numel()), rtol=1e-7,
                               atol=1e-8)
    assert np.abs(J[:, :nx]).max() > 0.5                  # not a trivial Jacobian
    # the Hessian of w^T f (jac_adj1_: exact) against central differences of
    # the exact gradient
    z = ca.vertcat(X, P, T)
    H = ca.Function("H", [X, P, T], [ca.hessian(ca.dot(w, exact(X, P, T)), z)[0]])
    g = ca.Function("g", [X, P, T], [ca.gradient(ca.dot(w, exact(X, P, T)), z)])
    v0 = np.r_[x, p, t]
    eps = 1e-6
    cols = []
    for k in range(v0.size):
        d = np.zeros(v0.size)
        d[k] = eps
        a, b = v0 + d, v0 - d
        cols.append((np.array(g(a[:nx], a[nx:-1], a[-1]).full()) -
                     np.array(g(b[:nx], b[nx:-1], b[-1]).full())).ravel() / (2 * eps))
    np.testing.assert_allclose(np.array(H(x, p, t).full()), np.column_stack(cols),
                               rtol=1e-6, atol=1e-6)


@pytest.mark.slow
def test_step_refuses_to_cross_a_guard(ball, wheel):
    """step is one phase: a step across the ground (falling through it) or
    across the wheel's strike is refused, naming the declaration; a step
    that ends on the guard (a phase's last), or moves away, is computed."""
    model, F, sim = ball
    p = np.array(model.p_values)
    with pytest.raises(gen.SolverError, match=r"hyb_cs_ball_step\(x, r, p, t, h\) failed with "
                       r"ERR_GUARD_CROSSED: .* impact 'ground' goes from 0\.01 at x to "
                       r"-0\.13905 at x_next"):
        F["step"]([0.01, -1.0], [], p, 0.0, 0.1)
    np.testing.assert_array_equal(_v(F["step"]([0.5, -1.0], [], p, 0.0, 0.1)),
                                  sim.step(0.0, [0.5, -1.0], 0.1))
    # an RK4 step of a free fall is exact: from y = g h^2 / 2 with v = 0 it
    # ends on the ground, g h down; that is no crossing
    h = 0.1
    end = _v(F["step"]([G * h * h / 2, 0.0], [], p, 0.0, h))
    assert end[0] == 0.0 and end[1] == pytest.approx(-G * h, abs=1e-15)
    model, F, sim = wheel
    p = np.array(model.p_values)
    with pytest.raises(gen.SolverError, match=r"reset 'strike' goes from -0\.0236 at x to "):
        F["step"]([GAMMA + ALPHA - 0.0236, 2.0], [], p, 0.0, 0.05)


def _guide_block():
    """docs/guides/casadi.md's two-phase Opti problem (its section "A hybrid
    model"), the block as the guide shows it."""
    from pathlib import Path
    text = (Path(__file__).resolve().parents[2] / "docs" / "guides" / "casadi.md").read_text()
    section = text[text.index("## A hybrid model"):]
    return section[section.index("```python\n") + 10:section.index("\n```\n")]


@pytest.mark.slow
def test_two_phase_opti_gives_the_rimless_wheels_steady_state(wheel):
    """The acceptance: a two-phase Opti problem over the rimless wheel built
    from step, guard_strike and map_strike (the casadi guide's block, run
    here) gives its analytic steady-state speeds to 1e-6 (after and before
    each strike); replayed through sim.simulate, the gait returns to itself."""
    _, _, sim = wheel
    ns = {}
    exec(compile(_guide_block(), "docs/guides/casadi.md", "exec"), ns)  # noqa: S102
    X, T = ns["X"], ns["T"]
    after, before = steady_speed()
    for i in range(2):
        assert abs(X[i][1, 0] - after) < 1e-6, (X[i][1, 0], after)
        assert abs(X[i][1, -1] - before) < 1e-6, (X[i][1, -1], before)
        assert X[i][0, 0] == pytest.approx(GAMMA - ALPHA, abs=1e-12)
    assert abs(T[0] - T[1]) < 1e-9
    sol = sim.simulate(X[0][:, 0], 2 * T[0] + 0.01, 0.01, method="dopri5", rtol=1e-12,
                       atol=1e-12)
    strikes = [e for e in sol.events if e.name == "strike"]
    assert len(strikes) == 2
    assert abs(strikes[1].x_after[1] - after) < 1e-6
    assert abs(strikes[0].t - T[0]) < 1e-6
