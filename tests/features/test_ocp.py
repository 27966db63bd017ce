"""gen.OptimalControl (issue 34): direct collocation on the implicit
equations, generated kernels, IPOPT through cyipopt.

References: central finite differences of the C's own values (Jacobian,
gradient, exact Hessian of the Lagrangian), IPOPT's limited-memory
solution, opty 1.5 on the same problem (slow tier), and the model's
simulator replaying the optimal inputs (the order of Hermite-Simpson).
"""
import importlib.util
import os
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import sympy as sm

import gen

try:
    import cyipopt  # noqa: F401
except ImportError:  # pragma: no cover - the CI installs it (the test extra)
    cyipopt = None

if cyipopt is None:
    if os.environ.get("CI") == "true":
        pytest.fail("cyipopt is required under CI=true (pip install eomgen[ocp])", pytrace=False)
    pytestmark = pytest.mark.skip(reason="cyipopt not installed (pip install eomgen[ocp])")

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
PAR = {"mc": 1.0, "mp": 0.1, "l": 0.5, "g": 9.81}


def _cart_pole():
    spec = importlib.util.spec_from_file_location("cart_pole_for_ocp", EXAMPLES / "cart_pole.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    km, s = mod.derive()
    model = gen.Model.from_kanes(km, constants={s[k]: v for k, v in PAR.items()},
                                 inputs=[s["F"]], name="cart_pole_ocp")
    return km, s, model


@pytest.fixture(scope="module")
def cart():
    return _cart_pole()


def swing_up(model, s, nodes, method, duration=2.0, fmax=20.0):
    x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
    return gen.OptimalControl(model, nodes, duration, objective=F**2, method=method,
                              bounds={F: (-fmax, fmax), x: (-1.5, 1.5)},
                              initial={x: 0, th: sm.pi, v: 0, om: 0},
                              final={x: 0, th: 0, v: 0, om: 0})


def _dense(o, z, vals, rows, cols, shape):
    return sp.coo_matrix((vals, (rows, cols)), shape).toarray()


@pytest.mark.parametrize("method", ["backward-euler", "hermite-simpson",
                                    pytest.param("midpoint", marks=pytest.mark.slow),
                                    pytest.param("trapezoidal", marks=pytest.mark.slow)])
def test_derivatives_against_finite_differences(cart, method):
    """Jacobian, gradient and the exact Hessian of the Lagrangian (the
    generated kernels, scattered by the C loop) against central differences
    of the C's values, with a free final time, a parameter to identify, a
    terminal cost, a path constraint and a time-dependent cost."""
    _, s, model = cart
    x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
    t = sm.Symbol("t")
    o = gen.OptimalControl(model, 5, (1.0, 3.0), objective=F**2 * sm.cos(th) + x**2 * t,
                           terminal_cost=v * om + sm.sin(th), method=method,
                           parameters=[s["mp"]], path=[(x * v + F, -5, 5)],
                           constraints=[th.func(0) - sm.pi], initial={x: 0})
    o._assemble()
    o._p = o._pvec()
    rng = np.random.default_rng(1)
    n, m = o._lay.n, o._m_rows
    z = rng.uniform(0.5, 1.5, n)
    J = _dense(o, z, o.evaluate(z, "jacobian"), o._jrows, o._jcols, (m, n))
    g = o.evaluate(z, "gradient")
    lam = rng.normal(size=m)
    H = _dense(o, z, o._call(4, z, len(o._hrows), lam, 0.7), o._hrows, o._hcols, (n, n))
    H = H + np.tril(H, -1).T
    eps = 1e-6
    Jfd, gfd, Hfd = np.zeros((m, n)), np.zeros(n), np.zeros((n, n))

    def lagrangian_gradient(zz):
        Jz = _dense(o, zz, o.evaluate(zz, "jacobian"), o._jrows, o._jcols, (m, n))
        return 0.7 * o.evaluate(zz, "gradient") + Jz.T @ lam
    for j in range(n):
        e = np.zeros(n)
        e[j] = eps
        Jfd[:, j] = (o.evaluate(z + e, "constraints") - o.evaluate(z - e, "constraints")) / (2 * eps)
        gfd[j] = (o.evaluate(z + e, "objective")[0] - o.evaluate(z - e, "objective")[0]) / (2 * eps)
        Hfd[:, j] = (lagrangian_gradient(z + e) - lagrangian_gradient(z - e)) / (2 * eps)
    assert np.abs(J - Jfd).max() < 1e-7 * max(1, np.abs(Jfd).max())
    assert np.abs(g - gfd).max() < 1e-7 * max(1, np.abs(gfd).max())
    assert np.abs(H - Hfd).max() < 1e-6 * max(1, np.abs(Hfd).max())
    assert np.abs(Hfd).max() > 0.1          # a Hessian that is there


def test_swing_up_exact_and_limited_memory_agree(cart):
    """The same optimum from the exact Hessian and from L-BFGS; the
    solution meets its bounds and boundary values; fewer iterations with the
    exact Hessian."""
    _, s, model = cart
    o = swing_up(model, s, 51, "backward-euler")
    a = o.solve(tol=1e-10)
    b = o.solve(hessian="limited-memory", tol=1e-10)
    assert a.status == 0 and b.status == 0, (a.message, b.message)
    assert a.objective == pytest.approx(b.objective, rel=1e-7)
    assert a.iterations < b.iterations
    np.testing.assert_allclose(a.x[0], [0, np.pi, 0, 0], atol=1e-12)
    np.testing.assert_allclose(a.x[-1], [0, 0, 0, 0], atol=1e-12)
    assert np.abs(a.r).max() <= 20 + 1e-6 and np.abs(a.x[:, 0]).max() <= 1.5 + 1e-6
    # backward Euler's own quadrature of the cost, from the returned inputs
    h = a.t[1] - a.t[0]
    assert a.objective == pytest.approx(h * np.sum(a.r[1:, 0] ** 2), rel=1e-12)
    # changing a bound needs no rebuild: a tighter force bound costs more
    lib = o._lib_path
    o.bounds = {s["F"]: (-15, 15), s["x"]: (-1.5, 1.5)}
    c = o.solve(a, tol=1e-10)
    assert o._lib_path == lib and c.status == 0
    assert c.objective > a.objective and np.abs(c.r).max() <= 15 + 1e-6


def _replay_error(sol):
    rep = sol.replay(dt=sol.t[-1] / 200, method="dopri5", rtol=1e-12, atol=1e-12)
    return np.abs(rep.x[-1] - sol.x[-1]).max()


@pytest.mark.slow
def test_hermite_simpson_order(cart):
    """Hermite-Simpson with 101 nodes replays at least as accurately as
    midpoint with 401 (the optimal inputs, interpolated as each method
    does, through the simulator at tight tolerance)."""
    _, s, model = cart
    hs = swing_up(model, s, 101, "hermite-simpson").solve(tol=1e-10)
    mp = swing_up(model, s, 401, "midpoint").solve(tol=1e-10)
    assert hs.status == 0 and mp.status == 0
    e_hs, e_mp = _replay_error(hs), _replay_error(mp)
    assert e_hs <= e_mp, (e_hs, e_mp)
    # and the objectives converge to the same value
    assert hs.objective == pytest.approx(mp.objective, rel=1e-3)


def test_interpolant_matches_nodes(cart):
    _, s, model = cart
    for method in gen.design.ocp.METHODS:
        sol = swing_up(model, s, 21, method).solve(tol=1e-9)
        assert sol.status == 0, (method, sol.message)
        np.testing.assert_allclose(sol(sol.t), sol.x, atol=1e-9, err_msg=method)
        np.testing.assert_allclose(sol.input(sol.t), sol.r, atol=1e-9, err_msg=method)


def _opty(km, s, N, method):
    from opty.direct_collocation import Problem
    x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
    states = (x, th, v, om)
    eom = km.mass_matrix_full * sm.Matrix([q.diff() for q in states]) - km.forcing_full
    T = 2.0
    h = T / (N - 1)

    def obj(f):
        Fv = f[4 * N:5 * N]
        if method == "backward euler":
            return h * np.sum(Fv[1:] ** 2)
        return h * np.sum(((Fv[:-1] + Fv[1:]) / 2) ** 2)

    def grad(f):
        g = np.zeros_like(f)
        Fv = f[4 * N:5 * N]
        if method == "backward euler":
            g[4 * N + 1:5 * N] = 2 * h * Fv[1:]
        else:
            a = (Fv[:-1] + Fv[1:]) / 2
            g[4 * N:5 * N - 1] += h * a
            g[4 * N + 1:5 * N] += h * a
        return g
    inst = (x.func(0.0), th.func(0.0) - np.pi, v.func(0.0), om.func(0.0),
            x.func(T), th.func(T), v.func(T), om.func(T))
    prob = Problem(obj, grad, eom, states, N, h,
                   known_parameter_map={s[k]: val for k, val in PAR.items()},
                   instance_constraints=inst, bounds={F: (-20.0, 20.0), x: (-1.5, 1.5)},
                   integration_method=method)
    prob.add_option("print_level", 0)
    prob.add_option("tol", 1e-10)
    g0 = np.zeros(5 * N)
    g0[N:2 * N] = np.linspace(np.pi, 0, N)
    _, info = prob.solve(g0)
    return info


@pytest.mark.slow
@pytest.mark.parametrize("method", ["backward-euler", "midpoint"])
def test_same_optimum_as_opty(cart, method):
    """Cart-pole swing-up, N = 201: our objective equals opty 1.5's, its
    transcription (backward Euler, midpoint) and quadrature the same."""
    try:
        import opty  # noqa: F401
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("opty is required under CI=true (scripts/env.sh installs it)")
        pytest.skip("opty not installed (pip install --no-deps opty==1.5.0)")
    km, s, model = cart
    ours = swing_up(model, s, 201, method).solve(tol=1e-10)
    info = _opty(km, s, 201, method.replace("-", " "))
    assert ours.status == 0 and info["status"] in (0, 1)
    assert ours.objective == pytest.approx(info["obj_val"], rel=1e-6)


# ----------------------------------------------------------- bad input
def test_bad_input_is_refused_before_building(cart, monkeypatch):
    _, s, model = cart
    x, th, F = s["x"], s["theta"], s["F"]

    def no_build(*a, **k):
        raise AssertionError("built despite the error")
    monkeypatch.setattr(gen.pipeline, "product", no_build)
    for bad in (sm.Abs(F), sm.Max(F, 0), sm.Piecewise((F, x > 0), (0, True))):
        with pytest.raises(gen.InputError, match="not differentiable"):
            gen.OptimalControl(model, 11, 1.0, objective=bad)
    zeta = sm.Symbol("zeta")
    with pytest.raises(gen.InputError, match="zeta"):
        gen.OptimalControl(model, 11, 1.0, objective=F**2, bounds={zeta: (0, 1)})
    with pytest.raises(gen.InputError, match="m_p"):
        gen.OptimalControl(model, 11, 1.0, objective=F**2, bounds={s["mp"]: (0, 1)})
    with pytest.raises(gen.InputError, match="zeta"):
        gen.OptimalControl(model, 11, 1.0, objective=F**2 + zeta)
    with pytest.raises(gen.InputError, match="method"):
        gen.OptimalControl(model, 11, 1.0, objective=F**2, method="rk4")
    with pytest.raises(gen.InputError, match="duration"):
        gen.OptimalControl(model, 11, -1.0, objective=F**2)
    with pytest.raises(gen.InputError, match="nothing to minimise"):
        gen.OptimalControl(model, 11, 1.0)


def test_infeasible_problem_status_in_words(cart):
    """A swing-up that |F| <= 0.5 cannot do in 0.5 s: IPOPT's status and
    its meaning reach the solution."""
    _, s, model = cart
    sol = swing_up(model, s, 21, "trapezoidal", duration=0.5, fmax=0.5).solve(max_iter=300)
    assert not sol.success
    assert sol.status in (2, -2, -1)
    assert ("infeasible" in sol.message) or ("maximum number of iterations" in sol.message)


def test_constrained_models_are_refused_with_a_reason():
    sys.path.insert(0, str(EXAMPLES))
    try:
        import seed_pendulum as sp_
    finally:
        sys.path.remove(str(EXAMPLES))
    m = sp_.kane_model()
    with pytest.raises(gen.InputError, match="hermite-simpson"):
        gen.OptimalControl(m, 11, 1.0, objective=sm.Symbol("m"), method="trapezoidal")


# ----------------------------------------------------------- identification
def test_identification_of_a_damped_pendulum():
    """g and the damping c of a pendulum from 101 noisy samples of theta
    (sigma = 0.01): the estimate is within 4 standard errors (Gauss-Newton
    covariance sigma^2 (J^T J)^-1, J by differences of the simulator) of the
    truth, and equals SciPy's nonlinear least squares on the simulator to a
    small fraction of a standard error."""
    from scipy.optimize import least_squares
    from sympy.physics import mechanics as me
    th, om = me.dynamicsymbols("theta omega")
    c, g, l, m = sm.symbols("c g l m")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "axis", [th, N.z])
    A.set_ang_vel(N, om * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    km = me.KanesMethod(N, [th], [om], kd_eqs=[th.diff() - om])
    km.kanes_equations([me.Particle("p", P, m)], [(P, m * g * N.x), (A, -c * om * N.z)])
    truth = {m: 1.0, l: 1.0, g: 9.81, c: 0.3}
    model = gen.Model.from_kanes(km, constants=dict(truth), name="damped_pendulum_ocp")
    sim = gen.compile(model)
    T, x0, sigma = 5.0, [1.0, 0.0], 0.01
    td = np.linspace(0, T, 101)
    ig, ic = model.p_orig.index(g), model.p_orig.index(c)

    def theta_of(q):
        p = np.array(model.p_values, float)
        p[ig], p[ic] = q
        run = sim.simulate(x0, T, T / 100, p=p, method="dopri5", rtol=1e-12, atol=1e-12)
        return np.interp(td, run.t, run.x[:, 0])
    y = theta_of([9.81, 0.3]) + np.random.default_rng(0).normal(0, sigma, td.size)
    ocp = gen.OptimalControl(model, 201, T, fit={th: (td, y)}, parameters=[g, c],
                             initial={th: x0[0], om: x0[1]}, bounds={g: (5, 15), c: (0, 2)})
    sol = ocp.solve(tol=1e-12)
    assert sol.status == 0, sol.message
    est = sol.p
    J = np.zeros((td.size, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = 1e-6 * max(1, abs(est[j]))
        J[:, j] = (theta_of(est + e) - theta_of(est - e)) / (2 * e[j])
    se = np.sqrt(np.diag(sigma ** 2 * np.linalg.inv(J.T @ J)))
    assert np.all(np.abs(est - [9.81, 0.3]) < 4 * se), (est, se)
    ls = least_squares(lambda q: theta_of(q) - y, [9.0, 0.5], xtol=1e-14, ftol=1e-14)
    assert np.all(np.abs(est - ls.x) < 0.01 * se), (est, ls.x, se)
    # the misfit is the objective: sum of squared residuals at the estimate
    assert sol.objective == pytest.approx(np.sum((theta_of(est) - y) ** 2), rel=1e-4)
    # new data, no rebuild
    lib = ocp._lib_path
    ocp.fit = {th: (td, theta_of([9.81, 0.3]))}
    exact = ocp.solve(tol=1e-12)
    assert ocp._lib_path == lib
    np.testing.assert_allclose(exact.p, [9.81, 0.3], rtol=1e-6)


def test_generated_c_is_strict_clean(cart, tmp_path):
    """The generated kernels and the runtime's node loop compile clean with
    the strict flags (-std=c99 -Wall -Wextra -Werror -pedantic)."""
    import subprocess
    from gen.codegen.backends import STRICT_FLAGS, c_compiler
    _, s, model = cart
    o = swing_up(model, s, 11, "hermite-simpson")
    src = Path(o._lib_path).parent / "src"
    files = sorted(p.name for p in src.glob("*.c"))
    assert "gen_rt_ocp.c" in files and len(files) == 2
    for f in files:
        proc = subprocess.run([c_compiler(), *STRICT_FLAGS, "-c", f, "-o", str(tmp_path / "x.o")],
                              cwd=src, capture_output=True, text=True)
        assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr


def test_library_interface_is_described_once(cart, tmp_path):
    """The OCP library's C interface (gen_rt_ocp_block, the GEN_RT_OCP_*
    codes, <prefix>_eval, <prefix>_work_len) is one description
    (OcpBackend.interface): its headers in the library's sources and the
    cffi cdef that opens it are rendered from it, and they agree with the C
    compiler on the struct's layout and the codes' values."""
    import subprocess
    from gen.codegen.backends import STRICT_FLAGS, c_compiler, get_backend
    from gen.codegen.render import product_cdef
    _, s, model = cart
    o = swing_up(model, s, 11, "trapezoidal")
    src = Path(o._lib_path).parent / "src"
    iface = get_backend("ocp").interface.bind(name=o._prefix, model=model.name)
    header, types = (src / f"{o._prefix}.h").read_text(), (src / "gen_rt_ocp_abi.h").read_text()
    cdef = product_cdef(iface)
    for f in iface.functions:
        assert f"{f.signature};" in " ".join(header.split()).replace("( ", "(")
        assert f"{f.signature};" in cdef
    (struct,) = iface.structs
    fields = [f.name for f in struct.fields]
    assert "typedef struct {" in types and all(f"{n};" in types for n in fields)
    assert "typedef struct {" in cdef and all(f"{n};" in cdef for n in fields)
    # the compiler's layout of the rendered header against cffi's of the cdef
    codes = [c.name for e in iface.enums for c in e.members]
    prog = tmp_path / "layout.c"
    prog.write_text("#include <stdio.h>\n#include <stddef.h>\n"
                    f'#include "{o._prefix}.h"\nint main(void)\n{{\n'
                    '    printf("%d\\n", (int)sizeof(gen_rt_ocp_block));\n'
                    + "".join(f'    printf("%d\\n", (int)offsetof(gen_rt_ocp_block, {n}));\n'
                              for n in fields)
                    + "".join(f'    printf("%d\\n", (int){c});\n' for c in codes)
                    + "    return 0;\n}\n")
    exe = tmp_path / "layout"
    subprocess.run([c_compiler(), *STRICT_FLAGS, "-I", str(src), str(prog), "-o", str(exe)],
                   check=True)
    c_side = [int(v) for v in subprocess.run([str(exe)], capture_output=True, text=True,
                                             check=True).stdout.split()]
    ffi = o._ffi
    assert c_side == ([ffi.sizeof("gen_rt_ocp_block")]
                      + [ffi.offsetof("gen_rt_ocp_block", n) for n in fields]
                      + [iface.value(c) for c in codes])
    assert o._what == {"objective": 0, "gradient": 1, "constraints": 2, "jacobian": 3,
                       "hessian": 4}
    # content-keyed: the same problem is the same library, found in the cache
    assert swing_up(model, s, 11, "trapezoidal")._lib_path == o._lib_path


# ------------------------------------------- constrained models (branch ocpdae)
# The seed's nonminimal pendulum (x, y with |P| = L; gravity along +x, hanging
# at (L, 0), upright at (-L, 0)), a torque tau about the pivot applied as a
# force tau/L^2 (-y, x) perpendicular to the rod. The seed's Kane velocity
# constraint is P's velocity along atan(y/x)'s frame, singular at x = 0, which
# every swing-up crosses: the Kane model here writes the same constraint as
# x u1 + y u2 = 0 (the seed's times |P| x / |x|), otherwise as the seed.
PEND = {"L": 1.0, "m": 1.0, "g": 9.81}
SWING_T, SWING_TAU = 2.0, 15.0


def _pendulum(kind):
    from sympy.physics.mechanics import (KanesMethod, LagrangesMethod, Lagrangian, Particle,
                                         Point, ReferenceFrame, dynamicsymbols)
    L, m, g = sm.symbols("L m g")
    tau = dynamicsymbols("tau")
    consts = {L: PEND["L"], m: PEND["m"], g: PEND["g"]}
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    if kind == "minimal":
        th, om = dynamicsymbols("theta omega")
        A = N.orientnew("A", "Axis", [th, N.z])
        A.set_ang_vel(N, om * N.z)
        P = O.locatenew("P", L * A.x)
        P.v2pt_theory(O, N, A)
        km = KanesMethod(N, q_ind=[th], u_ind=[om], kd_eqs=[th.diff() - om])
        km.kanes_equations([Particle("pP", P, m)], [(P, m * g * N.x), (A, tau * N.z)])
        return gen.Model.from_kanes(km, constants=consts, inputs=[tau], name="pend_min_ocp"), \
            {"theta": th, "omega": om, "tau": tau}
    q1, q2 = dynamicsymbols("q1:3")
    P = O.locatenew("P", q1 * N.x + q2 * N.y)
    load = [(P, m * g * N.x + tau / L**2 * (-q2 * N.x + q1 * N.y))]
    if kind in ("kane", "kane_seed"):
        u1, u2 = dynamicsymbols("u1:3")
        P.set_vel(N, u1 * N.x + u2 * N.y)
        if kind == "kane":
            f_v = q1 * u1 + q2 * u2
        else:       # the seed's own: P's velocity along the rod frame atan(y/x)'s x
            A = N.orientnew("A", "axis", [sm.atan(q2 / q1), N.z])
            f_v = sm.simplify(P.vel(N).express(A).dot(A.x))
        km = KanesMethod(N, q_ind=[q2], u_ind=[u2], q_dependent=[q1], u_dependent=[u1],
                         configuration_constraints=[sm.sqrt(q1**2 + q2**2) - L],
                         velocity_constraints=[f_v],
                         kd_eqs=[q1.diff() - u1, q2.diff() - u2])
        km.kanes_equations([Particle("pP", P, m)], load)
        model = gen.Model.from_kanes(km, constants=consts, inputs=[tau],
                                     name=f"pend_nonmin_{kind}_ocp")
        return model, {"q1": q1, "q2": q2, "u1": u1, "u2": u2, "tau": tau}
    P.set_vel(N, P.pos_from(O).dt(N))
    lm = LagrangesMethod(Lagrangian(N, Particle("pP", P, m)), [q1, q2],
                         hol_coneqs=[q1**2 + q2**2 - L**2], forcelist=load, frame=N)
    lm.form_lagranges_equations()
    model = gen.Model.from_lagrange(lm, q_ind=[q2], qd_ind=[q2.diff()], q_dep=[q1],
                                    qd_dep=[q1.diff()], constants=consts, inputs=[tau],
                                    name="pend_nonmin_lagrange_ocp")
    return model, {"q1": q1, "q2": q2, "u1": q1.diff(), "u2": q2.diff(), "tau": tau}


def _pendulum_swing_up(kind, nodes):
    """Hanging to upright in 2 s, |tau| <= 15, min integral tau^2; the
    guess: the half circle at constant speed."""
    model, s = _pendulum(kind)
    tt = np.linspace(0, SWING_T, nodes)
    a = np.pi * tt / SWING_T
    w = np.pi / SWING_T
    tau = s["tau"]
    if kind == "minimal":
        th, om = s["theta"], s["omega"]
        ocp = gen.OptimalControl(model, nodes, SWING_T, objective=tau**2,
                                 bounds={tau: (-SWING_TAU, SWING_TAU)},
                                 initial={th: 0, om: 0}, final={th: sm.pi, om: 0})
        return ocp, {th: a, om: w}, model, s
    q1, q2, u1, u2 = (s[k] for k in ("q1", "q2", "u1", "u2"))
    ocp = gen.OptimalControl(model, nodes, SWING_T, objective=tau**2,
                             bounds={tau: (-SWING_TAU, SWING_TAU)},
                             initial={q1: PEND["L"], q2: 0, u1: 0, u2: 0},
                             final={q1: -PEND["L"], q2: 0, u1: 0, u2: 0})
    return ocp, {q1: np.cos(a), q2: np.sin(a), u1: -w * np.sin(a), u2: w * np.cos(a)}, model, s


def _manifold_residuals(sol, model):
    """|x^2 + y^2 - L^2| and |x x' + y y'| at every node, from sol.x."""
    X = sol.x
    i1, i2 = model.state_names.index("q1"), model.state_names.index("q2")
    x, y = X[:, i1], X[:, i2]
    xd, yd = X[:, model.nq + i1], X[:, model.nq + i2]
    return np.abs(x**2 + y**2 - PEND["L"]**2).max(), np.abs(x * xd + y * yd).max()


@pytest.mark.parametrize("kind", ["kane", "lagrange"])
def test_constrained_derivatives_against_finite_differences(kind):
    """The constrained transcription's kernels (multipliers at every point,
    position/velocity/acceleration rows at the nodes, the midpoint velocity
    correction): Jacobian and exact Hessian of the Lagrangian against central
    differences of the C's values, at a random point."""
    model, s = _pendulum(kind)
    o = gen.OptimalControl(model, 4, 1.0, objective=s["tau"]**2 * s["q2"] + s["q1"]**2,
                           initial={s["q1"]: 1.0, s["q2"]: 0.0})
    o._assemble()
    o._p = o._pvec()
    rng = np.random.default_rng(3)
    n, m = o._lay.n, o._m_rows
    z = rng.uniform(0.5, 1.5, n)
    J = _dense(o, z, o.evaluate(z, "jacobian"), o._jrows, o._jcols, (m, n))
    lam = rng.normal(size=m)
    H = _dense(o, z, o._call(4, z, len(o._hrows), lam, 0.7), o._hrows, o._hcols, (n, n))
    H = H + np.tril(H, -1).T
    eps = 1e-6

    def lagrangian_gradient(zz):
        Jz = _dense(o, zz, o.evaluate(zz, "jacobian"), o._jrows, o._jcols, (m, n))
        return 0.7 * o.evaluate(zz, "gradient") + Jz.T @ lam
    Jfd, Hfd = np.zeros((m, n)), np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = eps
        Jfd[:, j] = (o.evaluate(z + e, "constraints")
                     - o.evaluate(z - e, "constraints")) / (2 * eps)
        Hfd[:, j] = (lagrangian_gradient(z + e) - lagrangian_gradient(z - e)) / (2 * eps)
    assert np.abs(J - Jfd).max() < 1e-7 * max(1, np.abs(Jfd).max())
    assert np.abs(H - Hfd).max() < 1e-6 * max(1, np.abs(Hfd).max())
    assert np.abs(Hfd).max() > 0.1


def test_constrained_inconsistent_boundary_values_are_refused():
    """Initial values off the constraint manifold: refused naming them,
    before anything is built; the methods without the DAE form refused."""
    model, s = _pendulum("lagrange")
    q1, q2, u1, u2, tau = (s[k] for k in ("q1", "q2", "u1", "u2", "tau"))
    with pytest.raises(gen.InputError, match="configuration constraints"):
        gen.OptimalControl(model, 11, 1.0, objective=tau**2, initial={q1: 0.9, q2: 0})
    with pytest.raises(gen.InputError, match="velocity constraints"):
        gen.OptimalControl(model, 11, 1.0, objective=tau**2,
                           initial={q1: 1.0, q2: 0, u1: 0.3, u2: 0})
    with pytest.raises(gen.InputError, match="hermite-simpson"):
        gen.OptimalControl(model, 11, 1.0, objective=tau**2, method="midpoint")


@pytest.fixture(scope="module")
def minimal_swing_up():
    out = {}
    for nodes in (51, 101):
        ocp, guess, _, _ = _pendulum_swing_up("minimal", nodes)
        sol = ocp.solve(guess=guess, tol=1e-12, print_level=0)
        assert sol.success, sol.message
        out[nodes] = sol.objective
    return out


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["kane", "lagrange"])
def test_constrained_pendulum_swing_up_equals_minimal(kind, minimal_swing_up):
    """Issue 34's acceptance: the nonminimal pendulum (Kane with a dependent
    speed, Lagrange with a multiplier) swung up from hanging has the minimal
    pendulum's optimum to 1e-6 (N = 101; both transcriptions converge to the
    same continuous optimum at fourth order: the gap falls 16-fold from N = 51),
    with the constraints held to 1e-10 at every node; the node multipliers
    are the rod's force, and the inputs replayed through the simulator end
    upright."""
    gaps = {}
    for nodes in (51, 101):
        ocp, guess, model, s = _pendulum_swing_up(kind, nodes)
        sol = ocp.solve(guess=guess, tol=1e-12, print_level=0)
        assert sol.success, sol.message
        gaps[nodes] = sol.objective / minimal_swing_up[nodes] - 1
        hol, vel = _manifold_residuals(sol, model)
        assert hol <= 1e-10 and vel <= 1e-10, (hol, vel)
        i1 = model.state_names.index("q1")
        assert sol.x[:, i1].min() < -0.99 and sol.x[:, i1].max() > 0.99   # it swings over
        # the multipliers are the rod's force: radial m (-L w^2) = m g cos(th) + N_r,
        # the constraint force A^T lam = c lam (x, y) (c: 1 Kane's x u1 + y u2, 2
        # Lagrange's derivative of x^2 + y^2 - L^2)
        lay, z = ocp._lay, sol._z
        lam = np.array([z[lay.node_point[k][1][0]] for k in range(nodes)])
        i2 = model.state_names.index("q2")
        x, y = sol.x[:, i1], sol.x[:, i2]
        w2 = (sol.x[:, model.nq + i1]**2 + sol.x[:, model.nq + i2]**2) / PEND["L"]**2
        c = 1.0 if kind == "kane" else 2.0
        N_r = -PEND["m"] * PEND["L"] * w2 - PEND["m"] * PEND["g"] * x / PEND["L"]
        assert np.abs(c * lam * PEND["L"] - N_r).max() < 1e-8 * np.abs(N_r).max()
    # the optimal inputs, replayed through the model's own simulator (its
    # constraint handling, not the transcription's), swing it up: 2e-5 measured
    run = sol.replay(rtol=1e-10, atol=1e-10)
    assert np.abs(run.x[-1] - sol.x[-1]).max() < 1e-3
    assert abs(gaps[101]) < 1e-6, gaps
    assert 10 < gaps[51] / gaps[101] < 25, gaps     # h^4: the same continuous optimum


@pytest.mark.parametrize("kind", ["kane_seed", "lagrange"])
def test_constrained_pendulum_one_sided_swing_with_the_seeds_constraint(kind):
    """The seed's own Kane velocity constraint (singular at x = 0) on a swing
    that stays on the hanging side: from rest hanging to rest at 60 degrees in
    1 s, min integral tau^2, 41 nodes; the minimal pendulum's optimum to 1e-6
    and the constraints to 1e-10 at every node."""
    th1, T, nodes = np.pi / 3, 1.0, 41
    mmod, ms = _pendulum("minimal")
    tt = np.linspace(0, T, nodes)
    a = th1 * tt / T
    th, om, tau_m = ms["theta"], ms["omega"], ms["tau"]
    ref = gen.OptimalControl(mmod, nodes, T, objective=tau_m**2, initial={th: 0, om: 0},
                             final={th: th1, om: 0}).solve(guess={th: a, om: th1 / T},
                                                           tol=1e-12, print_level=0)
    assert ref.success, ref.message
    model, s = _pendulum(kind)
    q1, q2, u1, u2, tau = (s[k] for k in ("q1", "q2", "u1", "u2", "tau"))
    c1, s1 = np.cos(th1), np.sin(th1)
    ocp = gen.OptimalControl(model, nodes, T, objective=tau**2,
                             initial={q1: 1.0, q2: 0, u1: 0, u2: 0},
                             final={q1: c1, q2: s1, u1: 0, u2: 0})
    w = th1 / T
    sol = ocp.solve(guess={q1: np.cos(a), q2: np.sin(a), u1: -w * np.sin(a), u2: w * np.cos(a)},
                    tol=1e-12, print_level=0)
    assert sol.success, sol.message
    assert abs(sol.objective / ref.objective - 1) < 1e-6, (sol.objective, ref.objective)
    hol, vel = _manifold_residuals(sol, model)
    assert hol <= 1e-10 and vel <= 1e-10, (hol, vel)


def test_nonholonomic_sleigh_manoeuvre_replays():
    """A nonholonomic model (examples/chaplygin_sleigh.py: no lateral slip at
    the blade, u_y dependent) moved from rest to rest 1 forward, 0.5 sideways
    in 2 s, min integral F^2 + tau^2: the no-slip constraint holds to 1e-10 at
    every node, and the optimal inputs replayed through the model's own
    simulator reach the transcribed final state (1.2e-6 measured)."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        import chaplygin_sleigh as cs
    finally:
        sys.path.remove(str(EXAMPLES))
    km, s = cs.derive()
    model = gen.Model.from_kanes(km, constants={s[k]: v for k, v in cs.DEFAULTS.items()},
                                 inputs=[s["F"], s["tau"]], name="sleigh_ocp")
    x, y, th, ux, uy, uth, F, tau = (s[k] for k in "x y th ux uy uth F tau".split())
    rest = {ux: 0, uy: 0, uth: 0}
    ocp = gen.OptimalControl(model, 41, 2.0, objective=F**2 + tau**2,
                             initial={x: 0, y: 0, th: 0, **rest},
                             final={x: 1, y: 0.5, th: 0, **rest})
    sol = ocp.solve(tol=1e-10, print_level=0)
    assert sol.success, sol.message
    names = model.state_names
    th_, ux_, uy_ = (sol.x[:, names.index(k)] for k in ("theta", "u_x", "u_y"))
    assert np.abs(-np.sin(th_) * ux_ + np.cos(th_) * uy_).max() <= 1e-10
    assert np.abs(th_).max() > 0.1          # it has to turn: no sideways slip
    run = sol.replay(rtol=1e-10, atol=1e-10)
    assert np.abs(run.x[-1] - sol.x[-1]).max() < 1e-5
