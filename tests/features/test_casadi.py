"""gen.casadi: the model as CasADi external functions (issue 36).

Every function's value equals the Simulator's (the same C, called through
CasADi's calling convention) to 1e-14; casadi.jacobian of each (jac_<f>),
its forward and reverse derivatives (fwd1_/adj1_) equal this project's
Jacobians (sim.jac, sim.jacobian, sim.step_sensitivity,
sim.linearize_outputs) to 1e-12 and CasADi's own central finite
differences to 1e-6; map over threads gives the same bits; bad use fails.
"""
import os

import numpy as np
import pytest

import gen

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


@pytest.fixture(scope="module")
def cart_model():
    import cart_pole
    return cart_pole.model()


@pytest.fixture(scope="module")
def cart_sim(cart_model):
    return gen.compile(cart_model)


@pytest.fixture(scope="module")
def bicycle_model():
    import bicycle
    return bicycle.model()


@pytest.fixture(scope="module")
def bicycle_sim(bicycle_model):
    return gen.compile(bicycle_model)


def _case(request, which):
    """(model, sim, F, x, r, p) of one model at a state away from zero."""
    model = request.getfixturevalue(f"{which}_model")
    sim = request.getfixturevalue(f"{which}_sim")
    # the bicycle's tests need no second derivatives: its library without them
    # skips generating the Hessian kernels (60 s of sympy; hessians=False)
    F = gc.functions(model, hessians=which != "bicycle")
    rng = np.random.default_rng(36)
    p = np.array(model.p_values, float) * 1.1      # not the defaults
    x = rng.uniform(-0.6, 0.6, model.nx)
    if which == "bicycle":
        import bicycle
        x = bicycle.upright_state(sim, 4.0, p=p)
        names = list(sim.state_names)
        x[names.index("q4")] += 0.1                   # leaning, steering, turning
        x[names.index("u4")] += 0.3
        x[names.index("u7")] -= 0.2
        x = sim.consistent_state(x, p=p)
    elif model.mc or model.mv:
        x = sim.consistent_state(np.array([0.5, 0.8, 0.1, 0.1]), p=p)
    r = rng.uniform(-1, 1, model.nr)
    return model, sim, F, x, r, p


MODELS = ["kane", "lagrange", "cart",
          pytest.param("bicycle", marks=pytest.mark.slow)]     # 20 s of compiles


def _v(a):
    return np.asarray(ca.DM(a).full(), float).ravel()


@pytest.mark.parametrize("which", MODELS)
def test_values_equal_the_simulator(request, which):
    model, sim, F, x, r, p = _case(request, which)
    t, h = 0.3, 0.01
    names = ["rhs", "implicit", "step"] + (["outputs"] if model.output_names else []) \
        + (["constraints"] if model.mc + model.mv else [])
    assert sorted(F) == sorted(names)
    xdot = sim.rhs(t, x, r=r, p=p)
    np.testing.assert_allclose(_v(F["rhs"](x, r, p, t)), xdot, rtol=0, atol=1e-14)
    # implicit: xdot - rhs, then the constraint residuals
    xd = np.linspace(-1, 1, model.nx)
    res = xd - xdot
    if model.mc:
        res = np.r_[res, sim.constraints(x[:model.nq], p=p, t=t)]
    if model.mv:
        res = np.r_[res, sim.velocity_constraints(x[:model.nq], x[model.nq:], p=p, t=t)]
    np.testing.assert_allclose(_v(F["implicit"](x, xd, r, p, t)), res, rtol=0, atol=1e-14)
    np.testing.assert_allclose(_v(F["step"](x, r, p, t, h)), sim.step(t, x, h, r=r, p=p),
                               rtol=0, atol=1e-14)
    if model.output_names:
        np.testing.assert_allclose(_v(F["outputs"](x, r, p, t)), sim.outputs(t, x, r=r, p=p),
                                   rtol=0, atol=1e-14)
    if model.mc + model.mv:
        np.testing.assert_allclose(_v(F["constraints"](x, p, t)), res[model.nx:],
                                   rtol=0, atol=1e-14)
        assert np.abs(res[model.nx:]).max() < 1e-10       # a consistent state


def _jacobians(F, name, x, r, p, t, extra):
    """casadi.jacobian of F[name] w.r.t. x and r (and their forward and
    reverse products) as numpy arrays."""
    X = ca.MX.sym("X", x.size)
    R = ca.MX.sym("R", r.size)
    args = {"x": X, "r": R, "p": p, "t": t, **extra}
    (out,) = F[name].call(args).values()
    n = out.size1()
    v, w = np.linspace(0.5, 1.5, x.size), np.linspace(-1, 1, n)
    G = ca.Function("G", [X, R], [ca.jacobian(out, X), ca.jacobian(out, R),
                                  ca.jtimes(out, X, v), ca.jtimes(out, X, w, True)])
    return [np.array(a.full()) for a in G(x, r)], v, w


def _check(J, ref_x, ref_r, v, w):
    Jx, Jr, fwd, adj = J
    np.testing.assert_allclose(Jx, ref_x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(Jr, ref_r, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fwd.ravel(), ref_x @ v, rtol=0, atol=1e-12)
    np.testing.assert_allclose(adj.ravel(), ref_x.T @ w, rtol=0, atol=1e-12)


@pytest.mark.parametrize("which", MODELS)
def test_rhs_jacobian_equals_sim_jac(request, which):
    model, sim, F, x, r, p = _case(request, which)
    J, v, w = _jacobians(F, "rhs", x, r, p, 0.3, {})
    Jx, Jr = sim.jacobian(0.3, x, r=r, p=p)
    np.testing.assert_array_equal(sim.jac(0.3, x, r=r, p=p), Jx)
    _check(J, Jx, Jr, v, w)


def test_cart_jacobians(cart_model, cart_sim):
    """implicit, step and outputs of the (unconstrained) cart-pole."""
    model, sim = cart_model, cart_sim
    F = gc.functions(model)
    x, r, p, t, h = np.array([0.1, 0.5, 0.2, -0.3]), np.array([0.7]), \
        np.array(model.p_values, float), 0.3, 0.02
    Jx, Jr = sim.jacobian(t, x, r=r, p=p)
    J, v, w = _jacobians(F, "implicit", x, r, p, t, {"xdot": np.ones(4)})
    _check(J, -Jx, -Jr, v, w)
    J, v, w = _jacobians(F, "step", x, r, p, t, {"h": h})
    _, Fx, Fr = sim.step_sensitivity(t, x, h, r=r, p=p)
    _check(J, Fx, Fr, v, w)
    A, B = sim.linearize(x, r=r, p=p, t=t)
    np.testing.assert_allclose(Fx, np.eye(4) + h * A, atol=h * h * 50)    # the same A, to O(h^2)
    J, v, w = _jacobians(F, "outputs", x, r, p, t, {})
    _, _, C, D = sim.linearize_outputs(x, r=r, p=p, t=t)
    _check(J, C, D, v, w)


@pytest.mark.parametrize("name", ["rhs", "implicit", "step", "outputs"])
def test_derivatives_against_casadi_finite_differences(cart_model, name):
    """jac_/fwd1_/adj1_ against the same external function with CasADi's own
    central differences (enable_fd, its derivative functions disabled):
    the FD forward derivative, one seed per column of every input (x, xdot,
    r, p, t, h)."""
    path = str(gc.library(cart_model))
    sym = f"{cart_model.name}_{name}"
    exact = ca.external(sym, path)
    fd = ca.external(sym, path, {"enable_fd": True, "enable_jacobian": False,
                                 "enable_forward": False, "enable_reverse": False,
                                 "fd_method": "central"})
    x, r, p = np.array([0.1, 0.5, 0.2, -0.3]), np.array([0.7]), np.array(cart_model.p_values)
    extra = {"step": {"h": 0.02}, "implicit": {"xdot": np.ones(4)}}.get(name, {})
    (Jx, Jr, fwd, adj), v, w = _jacobians({name: exact}, name, x, r, p, 0.3, extra)
    f1 = fd.forward(1)
    args = {"x": x, "r": r, "p": p, "t": 0.3, **extra}
    nom = fd.call(args)
    base = {**args, **{f"out_{k}": val for k, val in nom.items()},
            **{f"fwd_{k}": 0 * ca.DM(val) for k, val in args.items()}}

    def column(which, seed):
        (d,) = f1.call({**base, f"fwd_{which}": seed}).values()
        return np.array(d.full()).ravel()
    fd_x = np.column_stack([column("x", e) for e in np.eye(4)])
    fd_r = np.column_stack([column("r", [1.0])])
    for a, b in [(Jx, fd_x), (Jr, fd_r), (fwd.ravel(), fd_x @ v), (adj.ravel(), fd_x.T @ w)]:
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-7)
    assert np.abs(Jx).max() > 0.5                   # not a trivial Jacobian
    # every other input (p, t, h, xdot): the Jacobian w.r.t. all inputs stacked
    vals = _inputs({name: exact}, name, cart_model, x, r, p, 0.3, 0.02)
    _, Jall, _ = _derivs(exact, vals, np.ones(exact.nnz_out(0)))
    at = dict(zip(exact.name_in(), vals))
    at.update({f"out_{k}": val for k, val in fd.call(at).items()})
    at.update({f"fwd_{k}": 0 * ca.DM(val) for k, val in zip(exact.name_in(), vals)})
    cols = [np.array(f1.call({**at, f"fwd_{n}": e}).popitem()[1].full()).ravel()
            for i, n in enumerate(exact.name_in()) for e in np.eye(vals[i].size)]
    np.testing.assert_allclose(Jall, np.column_stack(cols), rtol=1e-6, atol=1e-7)


def test_map_threads_same_bits(cart_model):
    F = gc.functions(cart_model)
    rng = np.random.default_rng(1)
    X = rng.uniform(-1, 1, (4, 100))
    R = rng.uniform(-1, 1, (1, 100))
    p = np.array(cart_model.p_values)
    for name, extra in [("rhs", []), ("step", [0.01])]:
        M = F[name].map(100, "thread", 2)
        got = np.array(M(X, R, p, 0.2, *extra).full())
        one = np.column_stack([np.array(F[name](X[:, k], R[:, k], p, 0.2, *extra).full()).ravel()
                               for k in range(100)])
        assert got.tobytes() == one.tobytes()
    # and the Jacobian through the map
    Xs = ca.MX.sym("X", 4, 100)
    Jm = ca.Function("Jm", [Xs], [ca.jacobian(F["rhs"].map(100, "thread", 2)(Xs, R, p, 0.2), Xs)])
    Jd = np.array(ca.densify(Jm(X)).full())
    sim = gen.compile(cart_model)
    for k in (0, 57, 99):
        blk = Jd[4 * k:4 * k + 4, 4 * k:4 * k + 4]
        np.testing.assert_allclose(blk, sim.jac(0.2, X[:, k], r=R[:, k], p=p), rtol=0, atol=1e-12)


def test_bad_use(cart_model, kane_model, monkeypatch):
    F = gc.functions(cart_model)
    x, p = np.array([0.1, 0.5, 0.2, -0.3]), np.array(cart_model.p_values)
    # wrong sizes: CasADi names the input
    with pytest.raises(RuntimeError, match=r"Input 0 \(x\) has mismatching shape"):
        F["rhs"](np.ones(3), 0.7, p, 0)
    with pytest.raises(RuntimeError, match=r"Input 2 \(p\) has mismatching shape"):
        F["rhs"](x, 0.7, p[:2], 0)
    # a failing numeric call names what failed (CasADi itself says "Evaluation failed");
    # the model has an input: a call without r fails (r's default is NaN), never zeros
    with pytest.raises(gen.InputError, match=r"cart_pole_rhs\(x, r, p, t\): r is missing"):
        F["rhs"](x=x, p=p, t=0)
    with pytest.raises(gen.InputError, match=r"cart_pole_step\(x, r, p, t, h\): h is missing"):
        F["step"].call({"x": x, "r": 0.3, "p": p, "t": 0})
    with pytest.raises(gen.InputError, match=r"x\[1\] = nan"):
        F["rhs"](np.array([0.1, np.nan, 0, 0]), 0.7, p, 0)
    with pytest.raises(gen.SingularError, match=r"cart_pole_rhs.*ERR_SINGULAR.*x = \[ ?0.1"):
        F["rhs"](x, 0.7, np.r_[0.0, 0.0, p[2:]], 0)          # massless: singular M
    # constrained model: no derivatives for step (they would need the projection's)
    Fk = gc.functions(kane_model)
    Xk = ca.MX.sym("X", 4)
    with pytest.raises(RuntimeError, match="pendulum_kane_step"):
        ca.Function("J", [Xk], [ca.jacobian(Fk["step"](Xk, [], kane_model.p_values, 0, 0.01),
                                            Xk)])(np.ones(4))
    with pytest.raises(gen.ModelError, match="gen.casadi"):
        gc.functions("not a model")
    # without casadi: MissingDependencyError naming the extra
    import importlib
    real = importlib.import_module

    def no_casadi(name, *a, **k):
        if name == "casadi":
            raise ImportError("No module named 'casadi'")
        return real(name, *a, **k)
    monkeypatch.setattr(importlib, "import_module", no_casadi)
    with pytest.raises(gen.MissingDependencyError, match=r"eomgen\[casadi\]"):
        gc.functions(cart_model)


#: the models whose tests need first derivatives only: their library is
#: functions(model, step="rodas4", hessians=False)'s
_FIRST = {"forced": {"hessians": False, "step": "rodas4"}}


@pytest.mark.parametrize("which", ["kane", "cart", "forced"])
def test_wrappers_compile_strict(request, which):
    """The generated <name>_casadi.c is clean under the project's strict
    flags (-std=c99 -Wall -Wextra -Werror -pedantic)."""
    import subprocess
    from gen.codegen.backends import STRICT_FLAGS, c_compiler
    model = request.getfixturevalue(f"{which}_model")
    # forced: the first-derivative library (hessians=False) with the RODAS4 step
    src = gc.library(model, **_FIRST.get(which, {})).parent / "src"
    fname = f"{model.name}_casadi.c"
    assert (src / fname).is_file()
    proc = subprocess.run([c_compiler(), *STRICT_FLAGS, "-I", ".", "-c", fname, "-o", os.devnull],
                          cwd=src, capture_output=True, text=True)
    assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr


def _cart_rhs_sx(x, u, p):
    """The cart-pole's x' written by hand in CasADi symbols (Lagrange's
    equations of examples/cart_pole.py: a uniform pole of half-length l,
    theta from the upward vertical, positive to the left)."""
    mc, mp, l, g = p[0], p[1], p[2], p[3]
    th, v, w = x[1], x[2], x[3]
    inertia = mp * (2 * l) ** 2 / 12
    m11, m12, m22 = mc + mp, -mp * l * ca.cos(th), mp * l ** 2 + inertia
    f1 = u - mp * l * ca.sin(th) * w ** 2
    f2 = mp * g * l * ca.sin(th)
    det = m11 * m22 - m12 * m12
    return ca.vertcat(v, w, (m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det)


def _swing_up(step_all, N, h, hess="exact"):
    """Minimum-effort swing-up of the cart-pole from hanging to upright in
    N h seconds, by multiple shooting in casadi.Opti (IPOPT); step_all maps
    (X[:, :-1], U) to the next states. (objective, U, iterations, seconds)."""
    import time
    opti = ca.Opti()
    X = opti.variable(4, N + 1)
    U = opti.variable(1, N)
    opti.minimize(h * ca.sumsqr(U))
    opti.subject_to(X[:, 1:] == step_all(X[:, :-1], U))
    opti.subject_to(X[:, 0] == [0, np.pi, 0, 0])
    opti.subject_to(X[:, N] == [0, 0, 0, 0])
    opti.subject_to(opti.bounded(-20, U, 20))
    opti.subject_to(opti.bounded(-1.5, X[0, :], 1.5))
    opti.set_initial(X[1, :], np.linspace(np.pi, 0, N + 1))
    # IPOPT's exact Hessian, through CasADi (jac_adj1_/jac_jac_ of step), for both
    opti.solver("ipopt", {"print_time": False},
                {"print_level": 0, "sb": "yes", "tol": 1e-10, "max_iter": 500,
                 "hessian_approximation": hess})
    t0 = time.perf_counter()
    sol = opti.solve()
    dt = time.perf_counter() - t0
    return sol.value(opti.f), np.array(sol.value(U)), sol.stats()["iter_count"], dt


def test_opti_swing_up_equals_pure_sx(cart_model, cart_sim):
    """The swing-up with gen's step (mapped over the 100 intervals) has the
    optimum of the same problem in pure CasADi SX (the same RK4 by hand)."""
    N, h = 100, 0.02
    p = np.array(cart_model.p_values, float)
    # the hand-written reference is the model
    Xs, Us, Hs = ca.SX.sym("x", 4), ca.SX.sym("u"), ca.SX.sym("h")
    f_sx = ca.Function("f", [Xs, Us], [_cart_rhs_sx(Xs, Us, p)])
    for x in ([0.1, 0.5, 0.2, -0.3], [0, np.pi, 1, 2]):
        np.testing.assert_allclose(_v(f_sx(x, 0.7)), cart_sim.rhs(0, np.array(x), r=[0.7]),
                                   rtol=1e-14, atol=1e-14)
    k1 = _cart_rhs_sx(Xs, Us, p)
    k2 = _cart_rhs_sx(Xs + Hs / 2 * k1, Us, p)
    k3 = _cart_rhs_sx(Xs + Hs / 2 * k2, Us, p)
    k4 = _cart_rhs_sx(Xs + Hs * k3, Us, p)
    step_sx = ca.Function("step_sx", [Xs, Us, Hs], [Xs + Hs / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
    step = gc.functions(cart_model)["step"].map(N)
    tk = (np.arange(N) * h).reshape(1, -1)
    ours = _swing_up(lambda X, U: step(X, U, p, tk, h), N, h)
    ref = _swing_up(lambda X, U: step_sx.map(N)(X, U, h), N, h)
    assert ours[0] > 10                                       # a real swing-up, not U = 0
    assert abs(ours[0] - ref[0]) <= 1e-6 * ref[0]
    np.testing.assert_allclose(ours[1], ref[1], rtol=0, atol=1e-6)
    print(f"swing-up: {ours[2]} iterations, {1e3 * ours[3] / ours[2]:.1f} ms/iteration; "
          f"pure SX {ref[2]}, {1e3 * ref[3] / ref[2]:.1f} ms/iteration")


@pytest.mark.slow
@pytest.mark.parametrize("which", ["cart", "kane", "forced"])
def test_sanitizers_every_entry_point(request, which, tmp_path):
    """Every function of the library, called through CasADi's convention
    from C (the work sizes it reports, NULL inputs as zeros, NULL outputs
    not written), is clean under AddressSanitizer and UBSan; the values
    agree with the library CasADi loaded."""
    import shutil
    import subprocess
    from gen.codegen.backends import c_compiler
    cart_model = request.getfixturevalue(f"{which}_model")
    src = gc.library(cart_model).parent / "src"
    specs = gc.function_specs(cart_model)
    p = np.array(cart_model.p_values)
    lines = ["#include <stdio.h>", "#include <stdlib.h>", "#include <string.h>",
             "typedef long long int ci;"]
    calls = []
    for s in specs:
        f = s["sym"]
        lines += [f"int {f}(const double **, double **, ci *, double *, int);",
                  f"int {f}_work(ci *, ci *, ci *, ci *);", f"ci {f}_n_in(void);",
                  f"ci {f}_n_out(void);", f"const ci *{f}_sparsity_out(ci);",
                  f"int {f}_checkout(void);", f"void {f}_release(int);"]
        ins = []
        for name, sp, _ in s["ins"]:
            n = sp[0] * sp[1]
            val = {"p": list(p), "t": [0.3], "h": [0.02], "r": [0.7]}.get(
                name, list(np.linspace(0.1, 0.4, n)))
            ins.append(val[:n] + [0.0] * (n - len(val)))
        calls.append((f, ins, [sp[2 + sp[1]] for _, sp in s["outs"]], s.get("mode")))  # nonzeros
    body = ["int main(void) {", "  int bad = 0;"]
    for f, ins, outs, mode in calls:
        body += ["  {", "    ci na, nr, niw, nw; int mem, st, k;",
                 f"    {f}_work(&na, &nr, &niw, &nw);",
                 f"    if (na != {f}_n_in() || nr != {f}_n_out()) bad = 1;"]
        for i, v in enumerate(ins):
            body.append(f"    static const double in{i}[{max(1, len(v))}] = "
                        f"{{{', '.join(repr(float(a)) for a in v) or '0'}}};")
        arg_list = ", ".join(f"in{i}" for i in range(len(ins)))
        body += [f"    const double *arg[{len(ins)}] = {{{arg_list}}};",
                 f"    double *res[{len(outs)}];",
                 "    double *w = malloc(sizeof(double) * (size_t)(nw > 0 ? nw : 1));"]
        for i, n in enumerate(outs):
            body.append(f"    double *o{i} = malloc(sizeof(double) * {max(1, n)});"
                        f" res[{i}] = o{i};")
        # a derivative with one of its outputs not wanted (NULL)
        if mode is not None and len(outs) > 1:
            body.append("    res[1] = 0;")
        body += [f"    mem = {f}_checkout();", f"    st = {f}(arg, res, 0, w, mem);",
                 f"    {f}_release(mem);",
                 f'    printf("{f} %d", st);',
                 *[f'    for (k = 0; k < {n}; ++k) if (res[{i}]) printf(" %.17g", o{i}[k]);'
                   for i, n in enumerate(outs)],
                 '    printf("\\n");', "    if (st) bad = 1;",
                 # NULL inputs are zeros: no crash (a status is fine)
                 f"    for (k = 0; k < {len(ins)}; ++k) arg[k] = 0;",
                 f"    (void){f}(arg, res, 0, w, 0);",
                 "    free(w);", *[f"    free(o{i});" for i in range(len(outs))], "  }"]
    body += ["  return bad;", "}"]
    (tmp_path / "harness.c").write_text("\n".join(lines + body) + "\n")
    cc = c_compiler()
    if shutil.which(cc) is None:
        pytest.skip(f"{cc} not installed")
    sources = [str(f) for f in sorted(src.glob("*.c")) if not f.name.endswith("_lin_stub.c")]
    exe = tmp_path / "harness"
    flags = ["-std=c99", "-g", "-O1", "-fsanitize=address,undefined", "-fno-sanitize-recover=all",
             "-I", str(src)]
    proc = subprocess.run([cc, *flags, str(tmp_path / "harness.c"), *sources, "-lm",
                           "-o", str(exe)], capture_output=True, text=True)
    if proc.returncode != 0 and "sanitize" in proc.stderr:
        pytest.skip(f"{cc} has no sanitizer runtime: {proc.stderr[:200]}")
    assert proc.returncode == 0, proc.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True,
                         env={**os.environ, "ASAN_OPTIONS": "detect_leaks=1"})
    assert run.returncode == 0, run.stdout + run.stderr
    assert "runtime error" not in run.stderr and "AddressSanitizer" not in run.stderr
    got = {ln.split()[0]: [float(v) for v in ln.split()[2:]] for ln in run.stdout.splitlines()}
    assert len(got) == len(specs)
    # the C harness's numbers are CasADi's
    F = gc.functions(cart_model)
    x = np.linspace(0.1, 0.4, 4)
    r = [0.7] if cart_model.nr else []
    np.testing.assert_array_equal(got[f"{cart_model.name}_rhs"], _v(F["rhs"](x, r, p, 0.3)))
    np.testing.assert_array_equal(got[f"{cart_model.name}_step"],
                                  _v(F["step"](x, r, p, 0.3, 0.02)))
    if f"{cart_model.name}_step_rodas4" in got:      # unconstrained: the RODAS4 step too
        Fr = gc.functions(cart_model, step="rodas4")["step"]
        np.testing.assert_array_equal(got[f"{cart_model.name}_step_rodas4"],
                                      _v(Fr(x, r, p, 0.3, 0.02)))
    # and a second derivative: the Hessian blocks jac_adj1_rhs wrote are CasADi's
    ja = F["rhs"].reverse(1).jacobian()
    vals = ja(x, r, p, 0.3, *[np.linspace(0.1, 0.4, 4)] * 2, *[0] * 4)
    want = [np.array(v.nonzeros(), float) for v in vals]   # column-major nonzeros
    mine = got[f"jac_adj1_{cart_model.name}_rhs"]
    flat = np.concatenate([w for k, w in enumerate(want) if k != 1])   # res[1] was NULL
    np.testing.assert_array_equal(mine, flat)


@pytest.mark.slow
def test_sources_build_standalone(cart_model, tmp_path):
    """The library's src/ folder (the guide's file list: every .c but the
    derivative stand-ins, the headers, <name>_casadi.h declaring the
    functions) compiles on its own with a plain `cc -shared`, and that
    library, loaded by casadi.external, gives the same bits."""
    import subprocess
    from gen.codegen.backends import c_compiler
    src = gc.library(cart_model).parent / "src"
    name = cart_model.name
    header = (src / f"{name}_casadi.h").read_text()
    for s in gc.function_specs(cart_model):
        assert f"int {s['sym']}(const casadi_real **arg" in header
    sources = [str(f) for f in sorted(src.glob("*.c")) if not f.name.endswith("_lin_stub.c")]
    so = tmp_path / f"lib{name}_casadi.so"
    proc = subprocess.run([c_compiler(), "-std=c99", "-O2", "-fPIC", "-shared", "-I", str(src),
                           *sources, "-lm", "-o", str(so)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    F = gc.functions(cart_model)
    x, p = np.array([0.1, 0.5, 0.2, -0.3]), np.array(cart_model.p_values)
    for key in ("rhs", "step"):
        mine = ca.external(f"{name}_{key}", str(so))
        args = (x, 0.7, p, 0.3) + ((0.02,) if key == "step" else ())
        assert _v(mine(*args)).tobytes() == _v(F[key](*args)).tobytes()
    X = ca.MX.sym("X", 4)
    step = ca.external(f"{name}_step", str(so))
    J = ca.Function("J", [X], [ca.jacobian(step(X, 0.7, p, 0.3, 0.02), X)])
    _, Fx, _ = gen.compile(cart_model).step_sensitivity(0.3, x, 0.02, r=[0.7], p=p)
    np.testing.assert_allclose(np.array(J(x).full()), Fx, rtol=0, atol=1e-12)


def test_lazy_import():
    """gen.casadi is loaded on first use, and casadi only when a library is
    loaded: `import gen` stays as it was."""
    import subprocess
    import sys
    code = ("import sys, gen; a = 'gen.export.casadi' in sys.modules; "
            "f = gen.casadi.functions; import gen.casadi as c; "
            "print(a, 'casadi' in sys.modules, f.__module__, c is gen.casadi)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": str(gc.__file__).rsplit("/gen/", 1)[0]})
    assert out.stdout.split() == ["False", "False", "gen.export.casadi", "True"], out.stderr


# ------------------------------------------- every input; second derivatives
def _sx(model, exprs):
    """sympy expressions of (q, u, r, p, t) as a CasADi SX function of
    (x, r, p, t): an independent reference (sympy's lambdify onto SX)."""
    import sympy as sm
    ns = {"sin": ca.sin, "cos": ca.cos, "tan": ca.tan, "sqrt": ca.sqrt, "exp": ca.exp,
          "log": ca.log, "atan2": ca.atan2, "Abs": ca.fabs}
    f = sm.lambdify([list(model.q) + list(model.u), list(model.r), list(model.p), model.t],
                    list(exprs), modules=[ns])
    X, R, P, T = (ca.SX.sym(n, k) for n, k in (("x", model.nx), ("r", model.nr),
                                                   ("p", model.np), ("t", 1)))
    return ca.Function("ref", [X, R, P, T], [ca.vertcat(*f([X[i] for i in range(model.nx)],
                                                            [R[i] for i in range(model.nr)],
                                                            [P[i] for i in range(model.np)],
                                                            T))],
                       ["x", "r", "p", "t"], ["y"])


def _inputs(F, name, model, x, r, p, t, h=0.01):
    vals = {"x": x, "xdot": np.linspace(-1, 1, model.nx), "r": r, "p": p, "t": t, "h": h}
    return [np.atleast_1d(np.asarray(vals[n], float)) for n in F[name].name_in()]


def _funcs(model):
    return [n for n in ("rhs", "implicit", "step", "outputs", "constraints")
            if (n != "outputs" or model.output_names) and (n != "constraints" or model.mc + model.mv)
            and not (n == "step" and model.mc + model.mv)]


def _derivs(f, vals, wt):
    """casadi.jacobian of f w.r.t. all its inputs stacked, and casadi.hessian
    of wt^T f (jac_/fwd1_/adj1_ and jac_jac_/jac_fwd1_/jac_adj1_)."""
    syms = [ca.MX.sym(f.name_in(i), v.size) for i, v in enumerate(vals)]
    V = ca.vertcat(*syms)
    out = f(*syms)
    G = ca.Function("G", syms, [out, ca.jacobian(out, V), ca.hessian(ca.dot(wt, out), V)[0]])
    return [np.array(ca.densify(a).full()) for a in G(*vals)]


@pytest.mark.parametrize("which", ["kane", "lagrange", "cart"])
def test_every_input_derivatives_and_hessians(request, which):
    """Every function's Jacobian w.r.t. every input (x, xdot, r, p, t, h)
    against central differences of its values, and the Hessian of a
    weighted sum of its outputs against central differences of the exact
    gradient (the same library's first derivatives, checked above)."""
    model, sim, F, x, r, p = _case(request, which)
    t = 0.3
    for name in _funcs(model):
        vals = _inputs(F, name, model, x, r, p, t)
        n_out = F[name].nnz_out(0)
        wt = np.linspace(0.5, 1.5, n_out)
        val, J, H = _derivs(F[name], vals, wt)
        flat = np.concatenate(vals)
        cuts = np.cumsum([v.size for v in vals])[:-1]

        def value(z):
            return _v(F[name](*np.split(z, cuts)))

        def grad(z):
            return wt @ _derivs(F[name], np.split(z, cuts), wt)[1]
        eps = 1e-6
        E = np.eye(flat.size)
        Jfd = np.column_stack([(value(flat + eps * e) - value(flat - eps * e)) / (2 * eps) for e in E])
        np.testing.assert_allclose(J, Jfd, rtol=1e-6, atol=1e-6 * max(1, np.abs(J).max()),
                                   err_msg=f"{which} {name}")
        Hfd = np.column_stack([(grad(flat + eps * e) - grad(flat - eps * e)) / (2 * eps) for e in E])
        np.testing.assert_allclose(H, Hfd, rtol=1e-5, atol=1e-5 * max(1, np.abs(H).max()),
                                   err_msg=f"{which} {name}")
        np.testing.assert_allclose(H, H.T, rtol=0, atol=1e-10 * max(1, np.abs(H).max()))
        # the x (and r) blocks are this project's Jacobians
        if name == "rhs":
            Jx, Jr = sim.jacobian(t, x, r=r, p=p)
            np.testing.assert_allclose(J[:, :model.nx], Jx, rtol=0, atol=1e-12)
            np.testing.assert_allclose(J[:, model.nx:model.nx + model.nr], Jr, rtol=0, atol=1e-12)
        if name == "constraints":
            assert np.abs(J).max() > 0.1
        assert np.abs(H).max() > 1e-3                   # a real second derivative


@pytest.mark.parametrize("which", ["kane", "lagrange", "cart"])
def test_hessians_equal_sympy(request, which):
    """casadi.hessian of a weighted sum of the outputs and of the constraints
    equals sympy's expressions lambdified onto SX, to 1e-10."""
    import sympy as sm
    model, sim, F, x, r, p = _case(request, which)
    t = 0.3
    refs = []
    if model.output_names:
        refs.append(("outputs", model.y))
    if model.mc + model.mv:
        c = sm.Matrix(model.fc) if model.mc else sm.zeros(0, 1)
        if model.mv:
            c = c.col_join(model.A * sm.Matrix(model.u) + model.b)
        refs.append(("constraints", c))
    assert refs
    for name, expr in refs:
        ref = _sx(model, expr)
        vals = _inputs(F, name, model, x, r, p, t)
        rvals = _inputs({"r": ref}, "r", model, x, r, p, t)
        wt = np.linspace(0.5, 1.5, F[name].nnz_out(0))
        a = _derivs(F[name], vals, wt)
        b = _derivs(ref, rvals, wt)
        if name == "constraints":           # ref has r among its inputs: drop its columns
            keep = np.r_[0:model.nx, model.nx + model.nr:model.nx + model.nr + model.np + 1]
            b = [b[0], b[1][:, keep], b[2][np.ix_(keep, keep)]]
        for u, v in zip(a, b):
            np.testing.assert_allclose(u, v, rtol=0, atol=1e-10 * max(1, np.abs(v).max()))


def test_cart_hessians_equal_pure_sx(cart_model):
    """rhs, implicit and step of the cart-pole: value, Jacobian w.r.t. every
    input and Hessian against the hand-written SX equations (and RK4)."""
    F = gc.functions(cart_model)
    p0 = np.array(cart_model.p_values, float)
    x0, r0, t0, h0 = np.array([0.1, 0.5, 0.2, -0.3]), np.array([0.7]), 0.3, 0.02
    Xs, Rs, Ps, Ts, Hs, XDs = (ca.SX.sym(n, k) for n, k in
                               (("x", 4), ("r", 1), ("p", 4), ("t", 1), ("h", 1), ("xd", 4)))

    def rk4(x, u, p, h):
        k1 = _cart_rhs_sx(x, u, p)
        k2 = _cart_rhs_sx(x + h / 2 * k1, u, p)
        k3 = _cart_rhs_sx(x + h / 2 * k2, u, p)
        k4 = _cart_rhs_sx(x + h * k3, u, p)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    refs = {"rhs": ([Xs, Rs, Ps, Ts], _cart_rhs_sx(Xs, Rs, Ps)),
            "implicit": ([Xs, XDs, Rs, Ps, Ts], XDs - _cart_rhs_sx(Xs, Rs, Ps)),
            "step": ([Xs, Rs, Ps, Ts, Hs], rk4(Xs, Rs, Ps, Hs))}
    for name, (syms, e) in refs.items():
        vals = _inputs(F, name, cart_model, x0, r0, p0, t0, h0)
        wt = np.linspace(0.5, 1.5, 4)
        a = _derivs(F[name], vals, wt)
        b = _derivs(ca.Function("ref", syms, [e]), vals, wt)
        for u, v in zip(a, b):
            np.testing.assert_allclose(u, v, rtol=0, atol=1e-10 * max(1, np.abs(v).max()),
                                       err_msg=name)


# ---------------------------------------------------------------------------
# step="rodas4": one RODAS4 step of the runtime (gen_rt_rodas4_trial) with
# exact first derivatives (the stage equations differentiated, d(Jf)/dv from
# the rhs Hessian kernels); no second derivatives.

# the tableau of csrc/gen_rt_rodas4.h, written out again for the reference
_RD = dict(
    GAMMA=0.25, ALPHA2=0.386, ALPHA3=0.21, ALPHA4=0.63,
    GAMMA2=-0.1043, GAMMA3=0.1035, GAMMA4=-0.3620000000000023E-01,
    A21=0.1544000000000000E+01, A31=0.9466785280815826, A32=0.2557011698983284,
    A41=0.3314825187068521E+01, A42=0.2896124015972201E+01, A43=0.9986419139977817,
    A51=0.1221224509226641E+01, A52=0.6019134481288629E+01, A53=0.1253708332932087E+02,
    A54=-0.6878860361058950,
    C21=-0.5668800000000000E+01, C31=-0.2430093356833875E+01, C32=-0.2063599157091915,
    C41=-0.1073529058151375, C42=-0.9594562251023355E+01, C43=-0.2047028614809616E+02,
    C51=0.7496443313967647E+01, C52=-0.1024680431464352E+02, C53=-0.3399990352819905E+02,
    C54=0.1170890893206160E+02,
    C61=0.8083246795921522E+01, C62=-0.7981132988064893E+01, C63=-0.3152159432874371E+02,
    C64=0.1631930543123136E+02, C65=-0.6058818238834054E+01)


def _rodas4_numpy(f, Jx, dfdt, t, x, h):
    """One RODAS4 step (Hairer-Wanner VI.4, the form of gen_rt_rodas4.h) in
    numpy: f(t, x), the Jacobian Jx and df/dt at (t, x)."""
    c = _RD
    n = len(x)
    G = np.eye(n) / (h * c["GAMMA"]) - Jx
    A = [[], [c["A21"]], [c["A31"], c["A32"]], [c["A41"], c["A42"], c["A43"]],
         [c["A51"], c["A52"], c["A53"], c["A54"]],
         [c["A51"], c["A52"], c["A53"], c["A54"], 1.0]]
    C = [[], [c["C21"]], [c["C31"], c["C32"]], [c["C41"], c["C42"], c["C43"]],
         [c["C51"], c["C52"], c["C53"], c["C54"]],
         [c["C61"], c["C62"], c["C63"], c["C64"], c["C65"]]]
    al = [0, c["ALPHA2"], c["ALPHA3"], c["ALPHA4"], 1, 1]
    ga = [c["GAMMA"], c["GAMMA2"], c["GAMMA3"], c["GAMMA4"], 0, 0]
    K = []
    for s in range(6):
        y = x + sum(a * k for a, k in zip(A[s], K))
        rhs = f(t + al[s] * h, y) + sum(cc / h * k for cc, k in zip(C[s], K)) + h * ga[s] * dfdt
        K.append(np.linalg.solve(G, rhs))
    return x + sum(a * k for a, k in zip(A[5], K)) + K[5]


@pytest.fixture(scope="module")
def forced_model():
    """A small nonautonomous model with an input (from_matrices): two
    coupled oscillators, a q-dependent mass matrix, a stiff-ish spring and
    a drive a sin(w t) + r, so that df/dt and d(Jf)/dv are not zero."""
    import sympy as sm
    t = sm.Symbol("t")
    q1, q2, u1, u2 = [sm.Function(n)(t) for n in ("q1", "q2", "u1", "u2")]
    k1, k2, c1, a, w = sm.symbols("k1 k2 c1 a w")
    r0 = sm.Function("F")(t)
    M = sm.Matrix([[2 + sm.cos(q2), sm.Rational(1, 2)], [sm.Rational(1, 2), 1]])
    f = sm.Matrix([-k1 * sm.sin(q1) - c1 * u1 + a * sm.sin(w * t) + r0,
                   -k2 * q2 - c1 * u2 + u1 ** 2 * sm.sin(q2)])
    kd = sm.Matrix([q1.diff(t) - u1, q2.diff(t) - u2])
    return gen.Model.from_matrices(M, f, [q1, q2], [u1, u2], kd,
                                   constants={k1: 3.0, k2: 400.0, c1: 0.3, a: 2.0, w: 5.0},
                                   inputs=[r0], name="forced_cs")


def _rodas4_case(request, which):
    model = request.getfixturevalue(f"{which}_model")
    F = gc.functions(model, **{"step": "rodas4", **_FIRST.get(which, {})})
    rng = np.random.default_rng(360)
    x = rng.uniform(-0.6, 0.6, model.nx)
    r = rng.uniform(-1, 1, model.nr)
    p = np.array(model.p_values, float) * 1.1
    return model, F, x, r, p


@pytest.fixture(scope="module")
def stiff_model():
    """examples/stiff_double_pendulum.py with the elbow ringing 1e3 times
    faster than the pair swings (unconstrained, autonomous)."""
    import stiff_double_pendulum as sdp
    return sdp.model(name="stiff_dp_cs", ratio=1e3)


@pytest.mark.parametrize("which", ["cart", "stiff"])
def test_rodas4_step_same_bits_as_the_runtime(request, which):
    """step="rodas4" is the adaptive RODAS4's trial step: a simulation with
    method="rodas4" whose first (and only) step is h (loose tolerances,
    t_end = h) lands on the same bits; and the numpy RODAS4 of the tableau
    agrees to rounding."""
    model, F, x, r, p = _rodas4_case(request, which)
    if which == "stiff":
        x = np.array([0.6, 0.0, 0.0, 0.0])     # at rest: the first step heuristic takes h whole
    sim = gen.compile(model)
    assert F["step"].name() == f"{model.name}_step_rodas4"
    assert list(F) == [k for k in gc.NAMES if k in F]
    rk = gc.functions(model)["step"]
    assert rk.name() == f"{model.name}_step" and rk.name_in() == F["step"].name_in()
    for h in (0.01, 0.03):      # steps the first-step heuristic takes whole (loose tolerances)
        sol = sim.simulate(x, h, h, method="rodas4", rtol=1e3, atol=1e3, p=p, r=r)
        assert sol.stats["n_steps"] == 1 and sol.t[-1] == h
        got = _v(F["step"](x, r, p, 0.0, h))
        assert got.tobytes() == np.asarray(sol.x)[-1].tobytes()
        ref = _rodas4_numpy(lambda tt, y: sim.rhs(tt, y, r=r, p=p), sim.jac(0.0, x, r=r, p=p),
                            np.zeros(model.nx), 0.0, x, h)
        np.testing.assert_allclose(got, ref, rtol=1e-13, atol=1e-14)
        assert np.abs(got - _v(rk(x, r, p, 0.0, h))).max() > 1e-11    # not RK4's value (both order 4)


def _fd_jacobian(F, z, n, nr, np_, rel=1e-6):
    def val(z):
        return _v(F(z[:n], z[n:n + nr], z[n + nr:n + nr + np_], z[-2], z[-1]))
    cols = []
    for c in range(len(z)):
        d = rel * max(1.0, abs(z[c]))
        e = np.zeros(len(z))
        e[c] = d
        cols.append((val(z + e) - val(z - e)) / (2 * d))
    return np.column_stack(cols)


@pytest.mark.parametrize("which", ["cart", "forced"])
def test_rodas4_step_jacobian(request, which):
    """jac_step (every input: x, r, p, t, h) against central differences of
    the value and CasADi's own finite differences; forward and reverse
    products through it; the value against the numpy RODAS4 with the exact
    df/dt (a nonautonomous model)."""
    model, F, x, r, p = _rodas4_case(request, which)
    S = F["step"]
    t, h = 0.3, 0.04
    n, nr, np_ = model.nx, model.nr, model.np
    X, R, P = ca.SX.sym("x", n), ca.SX.sym("r", nr), ca.SX.sym("p", np_)
    T, H = ca.SX.sym("t"), ca.SX.sym("h")
    V = ca.vertcat(X, R, P, T, H)
    y = S(X, R, P, T, H)
    Jf = ca.Function("J", [X, R, P, T, H], [ca.jacobian(y, V)])
    J = np.array(ca.densify(Jf(x, r, p, t, h)).full())
    z = np.concatenate([x, r, p, [t, h]])
    Jn = _fd_jacobian(S, z, n, nr, np_)
    scale = np.abs(J).max()
    assert np.abs(J - Jn).max() <= 1e-7 * scale, np.abs(J - Jn).max(axis=0)
    assert np.abs(J[:, :n] - np.eye(n)).max() > 1e-2           # not a trivial step
    if which == "forced":
        assert np.abs(J[:, n + nr + np_]).max() > 1e-3        # df/dt's derivative is in
    # CasADi's own central differences of the external (its derivatives disabled)
    path = str(gc.library(model, **_FIRST.get(which, {})))
    fd = ca.external(S.name(), path, {"enable_fd": True, "enable_jacobian": False,
                                      "enable_forward": False, "enable_reverse": False,
                                      "fd_method": "central"})
    f1 = fd.forward(1)
    args = {"x": x, "r": r, "p": p, "t": t, "h": h}
    base = {**args, "out_x_next": fd.call(args)["x_next"],
            **{f"fwd_{k}": 0 * ca.DM(val) for k, val in args.items()}}
    Jfd = np.column_stack([_v(f1.call({**base, f"fwd_{k}": e})["fwd_x_next"])
                           for k in args for e in np.eye(np.size(args[k]))])
    np.testing.assert_allclose(J, Jfd, rtol=1e-6, atol=1e-6 * scale)
    # forward and reverse products (jac_ with enable_forward=False, adj1_)
    rng = np.random.default_rng(5)
    sv, sw = rng.standard_normal(len(z)), rng.standard_normal(n)
    fwd = ca.Function("f", [X, R, P, T, H], [ca.jtimes(y, V, ca.DM(sv))])
    adj = ca.Function("a", [X, R, P, T, H], [ca.jtimes(y, V, ca.DM(sw), True)])
    np.testing.assert_allclose(_v(fwd(x, r, p, t, h)), J @ sv, rtol=1e-12, atol=1e-12 * scale)
    np.testing.assert_allclose(_v(adj(x, r, p, t, h)), J.T @ sw, rtol=1e-12, atol=1e-12 * scale)
    if which == "forced":
        # the value: the numpy RODAS4 with the exact df/dt (from jac_rhs)
        sim = gen.compile(model)
        dfdt = np.array(ca.Function("d", [T], [ca.jacobian(F["rhs"](x, r, p, T), T)])(t)).ravel()
        assert np.abs(dfdt).max() > 0.1
        ref = _rodas4_numpy(lambda tt, yy: sim.rhs(tt, yy, r=r, p=p), sim.jac(t, x, r=r, p=p),
                            dfdt, t, x, h)
        np.testing.assert_allclose(_v(S(x, r, p, t, h)), ref, rtol=1e-13, atol=1e-14)


def test_rodas4_step_stiff_model_large_h(stiff_model):
    """The point of step="rodas4": on the stiff double pendulum (its elbow
    rings 1e3 times faster than the pair swings) a step of h = 0.02 stays on
    the solution (compared with the adaptive RODAS4 at tight tolerances)
    while RK4 at the same h blows up."""
    model = stiff_model
    sim = gen.compile(model)
    Fr = gc.functions(model, step="rodas4")
    Fk = gc.functions(model)
    p = np.array(model.p_values, float)
    x0 = np.array([0.6, 0.0, 0.0, 0.0])
    h, N = 0.02, 50
    ref = np.asarray(sim.simulate(x0, N * h, N * h, method="rodas4", rtol=1e-10, atol=1e-12,
                                  p=p).x)[-1]
    xr, xk = x0.copy(), x0.copy()
    blew = False
    for k in range(N):
        xr = _v(Fr["step"](xr, [], p, k * h, h))
        if not blew:
            try:
                xk = _v(Fk["step"](xk, [], p, k * h, h))
                blew = not np.abs(xk).max() < 1e3
            except gen.SolverError:
                blew = True
    assert blew                                     # RK4 is unstable at this h
    assert abs(ref[0]) > 0.3                        # it has swung through
    np.testing.assert_allclose(xr, ref, rtol=0, atol=1e-6)     # measured: 2e-8


def test_rodas4_bad_use(cart_model, kane_model):
    with pytest.raises(ValueError, match=r"step must be one of 'rk4', 'rodas4'"):
        gc.functions(cart_model, step="rk5")
    # a constrained model: no RODAS4 step (it would need the projection)
    with pytest.raises(gen.ModelError, match=r"step='rodas4'.*constraints.*step='rk4'"):
        gc.functions(kane_model, step="rodas4")
    F = gc.functions(cart_model, step="rodas4")
    x, p = np.array([0.1, 0.5, 0.2, -0.3]), np.array(cart_model.p_values)
    with pytest.raises(gen.InputError, match=r"cart_pole_step_rodas4\(x, r, p, t, h\): h is missing"):
        F["step"].call({"x": x, "r": 0.3, "p": p, "t": 0})
    with pytest.raises(gen.InputError, match=r"step_rodas4\(x, r, p, t, h\): h = 0"):
        F["step"](x, 0.3, p, 0, 0.0)
    # no second derivatives: CasADi says it cannot differentiate the adjoint
    X = ca.MX.sym("X", 4)
    y = F["step"](X, 0.3, p, 0, 0.01)
    g = ca.gradient(ca.sumsqr(y), X)
    with pytest.raises(RuntimeError, match="adj1_cart_pole_step_rodas4"):
        ca.Function("H", [X], [ca.jacobian(g, X)])(x)


def test_rodas4_swing_up_limited_memory(cart_model, cart_sim):
    """The swing-up by multiple shooting with step="rodas4" (first
    derivatives only: IPOPT's limited-memory Hessian) has the optimum of the
    RK4 problem to the two methods' difference, and its controls, replayed
    by the adaptive RODAS4 at tight tolerances (a zero-order-hold table),
    bring the cart-pole upright."""
    N, h = 100, 0.02
    p = np.array(cart_model.p_values, float)
    tk = (np.arange(N) * h).reshape(1, -1)
    Sr = gc.functions(cart_model, step="rodas4")["step"].map(N)
    Sk = gc.functions(cart_model)["step"].map(N)
    ours = _swing_up(lambda X, U: Sr(X, U, p, tk, h), N, h, hess="limited-memory")
    ref = _swing_up(lambda X, U: Sk(X, U, p, tk, h), N, h)
    assert ours[0] > 10
    assert abs(ours[0] - ref[0]) <= 1e-5 * ref[0]              # measured 7e-7
    np.testing.assert_allclose(ours[1], ref[1], rtol=0, atol=1e-3)   # measured 2e-5
    sol = cart_sim.simulate([0, np.pi, 0, 0], N * h, h, method="rodas4", rtol=1e-11,
                            atol=1e-12, p=p, r=(np.arange(N) * h, ours[1].reshape(-1, 1)))
    np.testing.assert_allclose(np.asarray(sol.x)[-1], 0, atol=1e-4)  # measured 2e-6


def test_hessians_false_first_derivatives_only(forced_model):
    """functions(model, hessians=False): a library without the second-
    derivative functions and kernels (the costly part of a large model's
    build), the same values and first derivatives as the simulator; a
    Hessian through it fails in CasADi; hessians must be a bool. (The
    library is the one the forced model's RODAS4 tests load.)"""
    import ctypes
    from gen.codegen.casadi_kernels import derivative_kernels, function_specs
    model = forced_model
    F = gc.functions(model, **_FIRST["forced"])
    assert F["step"].name() == "forced_cs_step_rodas4"
    lib = ctypes.CDLL(str(gc.library(model, **_FIRST["forced"])))
    for f in ("rhs", "implicit", "step", "step_rodas4"):
        assert hasattr(lib, f"jac_forced_cs_{f}") and hasattr(lib, f"adj1_forced_cs_{f}")
        for pre in ("jac_jac_", "jac_fwd1_", "jac_adj1_"):
            assert not hasattr(lib, f"{pre}forced_cs_{f}"), pre + f
    # without step="rodas4" not even the rhs Hessian kernel (RODAS4's first
    # derivatives need it, RK4's do not), and no RODAS4 step
    kinds = {s["kind"] for s in function_specs(model, hessians=False, rodas4=False)}
    assert kinds == {f"{pre}{n}" for n in ("rhs", "implicit", "step")
                     for pre in ("", "jac_", "fwd1_", "adj1_")}
    assert sorted(derivative_kernels(model, hessians=False)) == ["cs_w0", "cs_wz"]
    sim = gen.compile(model)
    rng = np.random.default_rng(37)
    x, r, p, t = rng.uniform(-0.6, 0.6, 4), np.array([0.4]), np.array(model.p_values) * 1.1, 0.3
    np.testing.assert_allclose(_v(F["rhs"](x, r, p, t)), sim.rhs(t, x, r=r, p=p), rtol=0, atol=1e-14)
    J, v, w = _jacobians(F, "rhs", x, r, p, t, {})
    _check(J, *sim.jacobian(t, x, r=r, p=p), v, w)
    X = ca.MX.sym("X", 4)
    for name in ("rhs", "step"):
        extra = (0.02,) if name == "step" else ()
        with pytest.raises(RuntimeError, match=r"Derivatives cannot be calculated for adj1_forced_cs"):
            ca.Function("H", [X], [ca.hessian(ca.sumsqr(F[name](X, r, p, t, *extra)), X)[0]])
    for bad in ("no", None, 1):
        with pytest.raises(ValueError, match=r"hessians must be True"):
            gc.functions(model, hessians=bad)


def test_library_path_kept_for_the_process(cart_model, monkeypatch):
    """library(): a second call returns the path without planning or
    rendering again (gen.pipeline.build_product's memo), from threads too;
    the memo holds at most MEMO_SIZE libraries, and a dropped one is
    rendered again to the same path (the cache is keyed by content)."""
    from concurrent.futures import ThreadPoolExecutor

    import gen.pipeline as pl
    first = gc.library(cart_model)
    calls = []
    real = pl.render
    monkeypatch.setattr(pl, "render", lambda *a, **k: calls.append(1) or real(*a, **k))
    with ThreadPoolExecutor(2) as ex:
        assert list(ex.map(lambda _: gc.library(cart_model), range(4))) == [first] * 4
    assert calls == []
    monkeypatch.setattr(pl, "MEMO_SIZE", 1)
    other = gc.library(cart_model, hessians=False)      # another library: drops the oldest
    assert other != first and calls == [1] and len(pl._built) == 1
    assert gc.library(cart_model) == first and calls == [1, 1]
