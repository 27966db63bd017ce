"""Reactions inside the motion, solved together with u' in the C runtime.

A reaction R of an auxiliary speed that enters the dynamic equations with
coefficients that depend on the configuration or the speeds (friction
-mu N on a curved track, a normal force measured along a direction that
turns) is solved with the accelerations as one linear system
[M, -G; C, H] [u'; R] = [f; -g0] per evaluation (gen_rt_accel_reactions).

The references are independent of eomgen and of Kane's method: Newton's
second law for the particle written by hand, solved by sympy as a linear
system in (u', N) and evaluated separately (lambdify); SciPy's solve_ivp on
that right-hand side; central differences of sim.rhs.
"""
import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen
from helpers import rel_err

t = me.dynamicsymbols._t
CONSTS = {"m": 0.7, "g": 9.81, "R_c": 0.5, "mu": 0.4}
EPS = 0.05          # the friction's regularization: -mu N tanh(v / EPS)


def bead_kane(along="vertical"):
    """A bead of mass m on a circular track of radius R_c (angle theta from
    the lowest point, the centre above), pushed along the track by an input
    force F, gravity -m g N.y, the track's normal force N (towards the
    centre, B.y) and the regularized Coulomb friction -mu N tanh(v / EPS)
    against the sliding speed v = R_c omega. along="vertical": the auxiliary
    speed ua is vertical (N.y), so N's coefficient in its equation is
    cos(theta) - mu tanh(...) sin(theta) and N depends on omega': the coupled
    solve. along="normal": ua along the normal B.y, N = m (g cos(theta) +
    R_c omega^2), eliminated symbolically (a constant coefficient)."""
    th, w, ua, Nf, F = me.dynamicsymbols('theta omega ua N F')
    m, g, Rc, mu = sm.symbols('m g R_c mu')
    N = me.ReferenceFrame('N')
    B = N.orientnew('B', 'Axis', [th, N.z])
    B.set_ang_vel(N, w * N.z)
    O = me.Point('O')
    P = O.locatenew('P', -Rc * B.y)
    P.set_vel(N, Rc * w * B.x + ua * (N.y if along == "vertical" else B.y))
    fric = mu * Nf * sm.tanh(Rc * w / EPS)
    km = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w], u_auxiliary=[ua])
    km.kanes_equations([me.Particle('bead', P, m)],
                       [(P, Nf * B.y + (F - fric) * B.x - m * g * N.y)])
    consts = {m: CONSTS["m"], g: CONSTS["g"], Rc: CONSTS["R_c"], mu: CONSTS["mu"]}
    return km, consts, F, Nf


def bead_system():
    """The same bead (vertical auxiliary speed) as a sympy System."""
    th, w, ua, Nf, F = me.dynamicsymbols('theta omega ua N F')
    m, g, Rc, mu = sm.symbols('m g R_c mu')
    system = me.System()
    B = system.frame.orientnew('B', 'Axis', [th, system.z])
    B.set_ang_vel(system.frame, w * system.z)
    P = me.Particle('bead', mass=m)
    system.add_bodies(P)
    P.masscenter.set_pos(system.fixed_point, -Rc * B.y)
    P.masscenter.set_vel(system.frame, Rc * w * B.x + ua * system.y)
    system.q_ind, system.u_ind, system.u_aux = [th], [w], [ua]
    system.kdes = [th.diff(t) - w]
    system.apply_uniform_gravity(-g * system.y)
    fric = mu * Nf * sm.tanh(Rc * w / EPS)
    system.add_loads(me.Force(P, Nf * B.y + (F - fric) * B.x))
    system.validate_system()
    system.form_eoms()
    consts = {m: CONSTS["m"], g: CONSTS["g"], Rc: CONSTS["R_c"], mu: CONSTS["mu"]}
    return system, consts, F


def newton_reference():
    """Newton's law for the bead by hand, m a = N B.y + (F - mu N T) B.x -
    m g N.y with a = R_c omega' B.x + R_c omega^2 B.y, in its tangential and
    vertical components, solved by sympy for (omega', N): a function
    (theta, omega, F) -> (omega', N)."""
    th, w, wd, Nf, F = sm.symbols('theta omega omegad N F')
    m, g, Rc, mu = (sm.Float(CONSTS[k]) for k in ("m", "g", "R_c", "mu"))
    T = sm.tanh(Rc * w / EPS)
    # B.x = (cos, sin), B.y = (-sin, cos) in N
    tangential = m * Rc * wd - (F - mu * Nf * T - m * g * sm.sin(th))
    vertical = (m * (Rc * wd * sm.sin(th) + Rc * w**2 * sm.cos(th))
                - (Nf * sm.cos(th) + (F - mu * Nf * T) * sm.sin(th) - m * g))
    sol = sm.solve([tangential, vertical], [wd, Nf], dict=True)[0]
    return sm.lambdify([th, w, F], [sol[wd], sol[Nf]], "numpy"), (th, w, F, sol[wd], sol[Nf])


@pytest.fixture(scope="module")
def ref():
    return newton_reference()


@pytest.fixture(scope="module")
def bead():
    km, consts, F, _ = bead_kane("vertical")
    model = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bead")
    return model, gen.compile(model)


def states(n, seed):
    rng = np.random.default_rng(seed)
    X = np.column_stack([rng.uniform(-1.2, 1.2, n), rng.uniform(-3, 3, n)])
    return X, rng.uniform(-2, 2, n)


def test_bead_on_a_curved_track_solves_motion_and_normal_force_together(bead, ref):
    model, sim = bead
    assert model.aux_G is not None            # the coupled path (not eliminated)
    assert sim.auxiliary_names == ["N"]
    f, _ = ref
    X, Fs = states(25, 1)
    for x, F in zip(X, Fs):
        wd, n_val = f(x[0], x[1], F)
        got = sim.rhs(0.0, x, r=[F])
        assert abs(got[0] - x[1]) == 0
        assert abs(got[1] - wd) <= 1e-12 * max(1.0, abs(wd)), (x, got[1], wd)
        aux = sim.auxiliary_forces(0.0, x, r=[F])
        assert abs(aux[0] - n_val) <= 1e-12 * max(1.0, abs(n_val)), (x, aux[0], n_val)


def test_bead_trajectory_matches_scipy_on_the_reference_rhs(bead, ref):
    from scipy.integrate import solve_ivp
    _, sim = bead
    f, _ = ref
    F = 0.6

    def rhs(_t, x):
        wd, _ = f(x[0], x[1], F)
        return [x[1], wd]

    x0, t_end, dt = [0.9, 0.0], 2.0, 0.05
    ts = np.arange(41) * dt
    sol = solve_ivp(rhs, (0.0, t_end), x0, method="DOP853", t_eval=ts, rtol=1e-12, atol=1e-12)
    for method, dt_, opts, tol in (("dopri5", dt, dict(rtol=1e-11, atol=1e-11), 1e-8),
                                   ("rk4", 1e-3, {}, 1e-8),
                                   ("rodas4", dt, dict(rtol=1e-9, atol=1e-9), 2e-6)):
        t_, X = sim.simulate(x0, t_end, dt_, r=[F], method=method, **opts)
        keep = np.isin(np.round(t_ / dt, 6), np.round(ts / dt, 6))
        assert keep.sum() == len(ts), method
        assert rel_err(X[keep], sol.y.T) < tol, method
    # the normal force along the trajectory, as the reference solves it
    _, X = sim.simulate(x0, t_end, dt, r=[F], method="dopri5", rtol=1e-11, atol=1e-11)
    N_ref = np.array([f(x[0], x[1], F)[1] for x in X])
    N_got = np.array([sim.auxiliary_forces(0.0, x, r=[F])[0] for x in X])
    assert rel_err(N_got, N_ref) < 1e-12


def test_bead_linearization_is_the_jacobian_of_the_coupled_solve(bead, ref):
    _, sim = bead
    _, (th, w, F, wd, _) = ref
    # the sympy Jacobian of the eliminated right-hand side [omega, omega'(theta, omega, F)]
    J = sm.lambdify([th, w, F], sm.Matrix([wd]).jacobian([th, w, F]), "numpy")
    for x, Fv in zip(*states(6, 3)):
        A, B = sim.linearize(x, r=[Fv])
        Js = np.array(J(x[0], x[1], Fv), dtype=float)
        np.testing.assert_allclose(A, [[0.0, 1.0], list(Js[0, :2])], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(B, [[0.0], [Js[0, 2]]], rtol=1e-10, atol=1e-10)
        # the full-state Jacobian (RODAS4's) is the same derivative
        Jx, Jr = sim.jacobian(0.0, x, r=[Fv])
        np.testing.assert_allclose(Jx, A, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(Jr, B, rtol=1e-12, atol=1e-12)


def test_singular_coupled_system_names_the_reaction(bead):
    # at theta = pi/2 the track is vertical: the vertical auxiliary
    # direction does not see the (horizontal) normal force; the system in
    # (omega', N) has determinant -m R_c^2 cos(theta)
    _, sim = bead
    x = [np.pi / 2, 1.0]
    with pytest.raises(gen.SingularError, match=r"\(the reactions N\) \[ERR_SINGULAR_REACTIONS\]") as e:
        sim.rhs(0.0, x, r=[0.0])
    assert e.value.status_name == "ERR_SINGULAR_REACTIONS"
    with pytest.raises(gen.SingularError, match=r"the reactions N"):
        sim.auxiliary_forces(0.0, x, r=[0.0])
    with pytest.raises(gen.SingularError, match=r"the reactions N"):
        sim.linearize(x, r=[0.0])
    # a simulation from there stops at once with the same status
    with pytest.raises(gen.SingularError, match="ERR_SINGULAR_REACTIONS"):
        sim.simulate(x, 0.1, 0.01, r=[0.0], method="rk4")


def test_system_model_matches_the_kane_model(bead, ref):
    system, consts, F = bead_system()
    model = gen.Model.from_system(system, constants=consts, inputs=[F], name="bead_sys")
    assert model.aux_G is not None
    sim = gen.compile(model)
    f, _ = ref
    for x, Fv in zip(*states(10, 7)):
        wd, n_val = f(x[0], x[1], Fv)
        assert abs(sim.rhs(0.0, x, r=[Fv])[1] - wd) <= 1e-12 * max(1.0, abs(wd))
        assert abs(sim.auxiliary_forces(0.0, x, r=[Fv])[0] - n_val) <= 1e-12 * max(1.0, abs(n_val))


def test_normal_auxiliary_direction_is_eliminated_and_equals_the_coupled_solve(ref):
    # ua along the normal: N = m (g cos(theta) + R_c omega^2) exactly (its
    # coefficient is 1, no omega' in it), eliminated symbolically; the
    # coupled solve (forced: eliminate_reactions=False) gives the same numbers
    km, consts, F, _ = bead_kane("normal")
    m, g, Rc, mu = (CONSTS[k] for k in ("m", "g", "R_c", "mu"))
    elim = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bead_n")
    assert elim.aux_G is None
    coupled = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bead_nc",
                                   eliminate_reactions=False)
    assert coupled.aux_G is not None
    # the same keyword through Model.from_system (a Kane builder's own)
    assert gen.Model.from_system(km, constants=consts, inputs=[F], name="bead_nc",
                                 eliminate_reactions=False).fingerprint() == coupled.fingerprint()
    s1, s2 = gen.compile(elim), gen.compile(coupled)
    for x, Fv in zip(*states(15, 9)):
        n_val = m * (g * np.cos(x[0]) + Rc * x[1]**2)
        wd = (Fv - mu * n_val * np.tanh(Rc * x[1] / EPS) - m * g * np.sin(x[0])) / (m * Rc)
        for s in (s1, s2):
            assert abs(s.rhs(0.0, x, r=[Fv])[1] - wd) <= 1e-12 * max(1.0, abs(wd))
            assert abs(s.auxiliary_forces(0.0, x, r=[Fv])[0] - n_val) <= 1e-12 * abs(n_val)
        A1, B1 = s1.linearize(x, r=[Fv])
        A2, B2 = s2.linearize(x, r=[Fv])
        np.testing.assert_allclose(A2, A1, rtol=1e-11, atol=1e-11)
        np.testing.assert_allclose(B2, B1, rtol=1e-11, atol=1e-11)


@pytest.mark.slow
def test_float_build_agrees_with_double(bead):
    model, sim = bead
    simf = gen.compile(model, real="float")
    for x, Fv in zip(*states(8, 13)):
        x = np.float32(x).astype(float)
        Fv = float(np.float32(Fv))
        d, fl = sim.rhs(0.0, x, r=[Fv]), simf.rhs(0.0, x, r=[Fv])
        assert np.linalg.norm(fl - d) <= 1e-5 * np.linalg.norm(d)
        nd, nf = sim.auxiliary_forces(0.0, x, r=[Fv]), simf.auxiliary_forces(0.0, x, r=[Fv])
        assert abs(nf[0] - nd[0]) <= 1e-5 * abs(nd[0])


def test_nonlinear_reaction_in_the_auxiliary_accelerations_is_refused():
    # a reaction squared in the motion: named in the error
    th, w, ua, Nf = me.dynamicsymbols('theta omega ua N')
    N = me.ReferenceFrame('N')
    B = N.orientnew('B', 'Axis', [th, N.z])
    P = me.Point('P')
    P.set_vel(N, w * N.x + ua * N.y)
    km = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w], u_auxiliary=[ua])
    km.kanes_equations([me.Particle('p', P, 1)], [(P, Nf * B.y - Nf**2 * N.x)])
    with pytest.raises(gen.ModelError, match=r"not linear in the reaction force\(s\) N"):
        gen.Model.from_kanes(km, name="nonlin")


@pytest.mark.slow
@pytest.mark.eigen
def test_cpp_typed_face_eval_auxiliary_forces(tmp_path, ref):
    """tests/cpp/test_reactions.cpp: the C++/Eigen face's eval_rhs,
    eval_auxiliary_forces and linearize for double and float (the library's
    two copies) against Newton's law, and the singular status."""
    import subprocess
    from pathlib import Path
    from conftest import require_eigen, require_tool
    from gen.codegen.backends.eigen import ALT_DEFINE, sources
    from gen.codegen.render import C_TEMPLATES, RUNTIME_SOURCES
    inc = require_eigen()
    cc, cxx = require_tool("gcc"), require_tool("g++")
    km, consts, F, _ = bead_kane("vertical")
    model = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bead_e")
    out = tmp_path
    gen.generate(model, out, backend="eigen")
    main, alt, cxx_src = sources("bead_e", "double", True, C_TEMPLATES)
    prog = Path(__file__).resolve().parents[1] / "cpp" / "test_reactions.cpp"
    strict = ["-Wall", "-Wextra", "-Werror", "-pedantic", "-O1"]
    units = [(out / f, cc, ["-std=c99"]) for f in main + RUNTIME_SOURCES]
    units += [(out / f, cc, ["-std=c99", f"-D{ALT_DEFINE}"]) for f in alt + RUNTIME_SOURCES]
    units += [(out / f, cxx, ["-std=c++17"]) for f in cxx_src] + [(prog, cxx, ["-std=c++17"])]
    objs = []
    for i, (src, comp, flags) in enumerate(units):
        obj = out / f"u{i}_{Path(src).stem}.o"
        r = subprocess.run([comp, *flags, *strict, "-I", str(out), "-isystem", str(inc),
                            "-c", str(src), "-o", str(obj)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        objs.append(str(obj))
    exe = out / "test_reactions"
    r = subprocess.run([cxx, *objs, "-o", str(exe), "-lm"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    X, Fs = states(5, 21)
    stdin = "".join(f"{float(x[0])!r} {float(x[1])!r} {float(Fv)!r}\n" for x, Fv in zip(X, Fs))
    r = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert r.stdout.rstrip().endswith("ok")
    got = {}
    for line in r.stdout.splitlines()[:-1]:
        typ, what, k, *vals = line.split()
        got[typ, what, int(k)] = np.array([float.fromhex(v) for v in vals])
    assert len(got) == 2 * 4 * len(X)
    f, (th, w, Fsym, wd, _) = ref
    J = sm.lambdify([th, w, Fsym], sm.Matrix([wd]).jacobian([th, w, Fsym]), "numpy")
    for k, (x, Fv) in enumerate(zip(X, Fs)):
        for typ, tol in (("double", 1e-12), ("float", 2e-5)):
            xs = x if typ == "double" else np.float32(x).astype(float)
            Fk = Fv if typ == "double" else float(np.float32(Fv))
            wd_ref, n_ref = f(xs[0], xs[1], Fk)
            Js = np.array(J(xs[0], xs[1], Fk), dtype=float)[0]
            assert rel_err(got[typ, "rhs", k], [xs[1], wd_ref]) < tol, (typ, k)
            assert abs(got[typ, "N", k][0] - n_ref) <= tol * max(1.0, abs(n_ref)), (typ, k)
            assert rel_err(got[typ, "A", k], [0.0, 1.0, Js[0], Js[1]]) < 100 * tol, (typ, k)
            assert rel_err(got[typ, "B", k], [0.0, Js[2]]) < 100 * tol, (typ, k)


def test_verify_and_symbolic_linearization_know_the_coupled_solve(bead, ref):
    # gen.verify's references (numpy's solve of the coupled system, sympy's
    # linearization by the implicit function theorem) agree with the
    # compiled model, and linearize_symbolic with the Newton reference
    model, sim = bead
    report = gen.verify(model, samples=6, linearize_samples=2, sim=sim)
    assert report.ok, report
    assert {"eval_rhs", "eval_auxiliary_forces", "linearize"} <= {r[0] for r in report.rows}
    _, (th, w, F, wd, _) = ref
    J = [float(v) for v in sm.Matrix([wd]).jacobian([th, w, F]).subs({th: 0.4, w: -0.7, F: 0.3})]
    A, B = gen.linearize_symbolic(model, {"theta": 0.4, "omega": -0.7}, r_op={"F": 0.3},
                                  constants="values", simplify=False)
    np.testing.assert_allclose(np.array(A.evalf(), dtype=float), [[0, 1], [J[0], J[1]]],
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.array(B.evalf(), dtype=float), [[0], [J[2]]],
                               rtol=1e-12, atol=1e-12)


@pytest.mark.slow
def test_standalone_binary_writes_the_coupled_reaction(tmp_path, ref):
    # the generated main.c: its CSV ends with the N column, from the coupled solve
    import shutil
    import subprocess
    from gen.codegen.render import generate
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    km, consts, F, _ = bead_kane("vertical")
    model = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bead_bin")
    generate(model, tmp_path / "src")
    src = sorted(str(p) for p in (tmp_path / "src").glob("*.c"))
    exe = tmp_path / "bead_sim"
    subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1",
                    "-I", str(tmp_path / "src"), *src, "-lm", "-o", str(exe)], check=True)
    out = subprocess.run([str(exe), "--t-end", "0.3", "--dt", "0.01", "--x0", "theta=0.4",
                          "--x0", "omega=1.5", "--input", "F=0.5"],
                         capture_output=True, text=True, check=True).stdout
    lines = out.splitlines()
    assert lines[0].split(",") == ["t", "theta", "omega", "N"]
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    assert data.shape == (31, 4)
    f, _ = ref
    n_ref = np.array([f(row[1], row[2], 0.5)[1] for row in data])
    assert rel_err(data[:, 3], n_ref) < 1e-12


def test_reaction_the_auxiliary_equations_never_determine_is_refused():
    # R pushes along N.x (the motion); along the auxiliary direction N.y its
    # coefficient is (sin^2 + cos^2 - 1) R, zero though not structurally,
    # and no acceleration is: undetermined at every state
    th, w, ua, R = me.dynamicsymbols('theta omega ua R')
    g = sm.Symbol('g')
    N = me.ReferenceFrame('N')
    P = me.Point('P')
    P.set_vel(N, w * N.x + ua * N.y)
    km = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w], u_auxiliary=[ua])
    km.kanes_equations([me.Particle('p', P, 1)],
                       [(P, R * N.x + R * (sm.sin(th)**2 + sm.cos(th)**2 - 1) * N.y - g * N.y)])
    with pytest.raises(gen.ModelError, match=r"reaction force\(s\) R enter the equations of "
                                             r"motion but .* do not determine them"):
        gen.Model.from_kanes(km, constants={g: 9.81}, name="undet")


def test_impact_on_a_coupled_reaction_model_is_refused_naming_the_reaction():
    """gen.Impact's impulse and held contact solve with M and f alone; on a
    model whose reaction N enters the motion they would drop N's coupling, so
    the declaration is refused with N named (a Reset, a pure state map, is
    taken)."""
    km, consts, F, _ = bead_kane("vertical")
    th = km.q[0]
    with pytest.raises(gen.ModelError, match=r"reactions \(N\).*gen.Impact|gen.Impact.*\(N\)"):
        gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bead_hit",
                             hybrid={"stop": gen.Impact(1 - th, restitution=0.5)})
    model = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bead_reset",
                                 hybrid={"wrap": gen.Reset(th - 3, {th: th - 6})})
    assert [d.name for d in model.hybrid] == ["wrap"]
