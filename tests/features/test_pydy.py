"""Issue 33, the PyDy drop-in: gen.pydy.ODEFunctionGenerator as the
``generator=`` of PyDy's generate_ode_function and System.generate_ode_function.

The reference is PyDy's own ``cython`` generator, built in the same process
from the same symbolic objects (and called with the same arguments): every
example PyDy ships (n_link_pendulum_on_cart for n = 1..5 with the cart force
and joint torques, multi_mass_spring_damper), in each of PyDy's three forms
(x' = F; the full mass matrix; the minimal mass matrix with q' = G), with
each argument type PyDy documents for p and r, agrees to 1e-12 (relative to
the largest component). Without Cython, PyDy's lambdify generator is the
reference (the test says so).
"""
import subprocess
import sys

import numpy as np
import pytest
import sympy as sm

pytest.importorskip("pydy")
from pydy.codegen.ode_function_generators import generate_ode_function  # noqa: E402
from pydy.models import multi_mass_spring_damper, n_link_pendulum_on_cart  # noqa: E402

import gen  # noqa: E402
import gen.pydy  # noqa: E402
from helpers import rel_err  # noqa: E402

try:
    import Cython  # noqa: F401
    REFERENCE = "cython"
except ImportError:                                   # pragma: no cover
    REFERENCE = "lambdify"

TOL = 1e-12
OURS = gen.pydy.ODEFunctionGenerator


def pendulum(n):
    return n_link_pendulum_on_cart(n, cart_force=True, joint_torques=True)


MODELS = {
    **{f"pendulum{n}": (lambda n=n: pendulum(n)) for n in range(1, 6)},
    "msd1": lambda: multi_mass_spring_damper(),                       # no specifieds
    "msd3": lambda: multi_mass_spring_damper(3, apply_gravity=True, apply_external_forces=True),
}
# the others in the slow tier; pendulum2 is the model (and the Cython reference build,
# about 3 s) the other fast tests use anyway
FAST = ("pendulum2",)


def _param(names):
    return [k if k in FAST else pytest.param(k, marks=pytest.mark.slow) for k in names]


_systems, _refs = {}, {}


def system(which):
    if which not in _systems:
        _systems[which] = MODELS[which]()
    return _systems[which]


def reference(which, tmp_path_factory):
    """PyDy's own generator over the System's arguments (the minimal form),
    no argument types fixed (it parses every kind), built once per model."""
    if which not in _refs:
        sysm = system(which)
        kw = {"tmp_dir": str(tmp_path_factory.mktemp(f"cython_{which}"))} \
            if REFERENCE == "cython" else {}
        args = sysm._args_for_gen_ode_func()
        kwargs = sysm._kwargs_for_gen_ode_func()
        _refs[which] = generate_ode_function(*args, generator=REFERENCE, **kwargs, **kw)
    return _refs[which]


def samples(sysm, k=4, seed=0):
    """k random (x, t, r, p) in the System's orders (p positive)."""
    rng = np.random.default_rng(seed)
    nx = len(sysm.coordinates) + len(sysm.speeds)
    nr = len(sysm.specifieds_symbols)
    nc = len(sysm.constants_symbols)
    return [(rng.uniform(-1, 1, nx), float(rng.uniform(0, 2)), rng.uniform(-2, 2, nr),
             rng.uniform(0.5, 1.5, nc)) for _ in range(k)]


def call(f, sysm, x, t, r, p):
    return f(x, t, r, p) if sysm.specifieds_symbols else f(x, t, p)


# --------------------------------------------------- every model PyDy ships
@pytest.mark.parametrize("which", _param(MODELS))
def test_system_generate_ode_function_agrees_with_pydy(which, tmp_path_factory):
    """pydy System.generate_ode_function(generator=ODEFunctionGenerator)."""
    sysm = system(which)
    ref = reference(which, tmp_path_factory)
    ours = sysm.generate_ode_function(generator=OURS)
    assert sysm.evaluate_ode_function is ours
    assert ours.simulator.nx == len(sysm.states)
    for x, t, r, p in samples(sysm):
        a = call(ours, sysm, x, t, r, p)
        b = call(ref, sysm, x, t, r, p).copy()
        assert a.shape == b.shape == (len(sysm.states),)
        assert rel_err(a, b) < TOL, (which, a, b)
        assert np.max(np.abs(b)) > 1e-3                # not a trivially zero comparison


def _forms(sysm):
    """PyDy's three forms of the same system: (args, kwargs) each."""
    km = sysm.eom_method
    q, u = sysm.coordinates, sysm.speeds
    consts = sysm.constants_symbols
    spec = list(sysm.specifieds_symbols) or None
    args = sysm._args_for_gen_ode_func()
    kw = sysm._kwargs_for_gen_ode_func()
    forms = {"minimal": (args, kw),
             "full mass matrix": ((km.forcing_full, q, u, consts),
                                  {"mass_matrix": km.mass_matrix_full, "specifieds": spec})}
    if len(u) <= 2:
        # x' = F: the minimal form solved symbolically (small models only)
        udot = km.mass_matrix.LUsolve(km.forcing)
        F = sm.Matrix.vstack(kw["coordinate_derivatives"], udot)
        forms["full rhs"] = ((F, q, u, consts), {"specifieds": spec})
    return forms


@pytest.mark.parametrize("which", _param(MODELS))
def test_every_form_agrees_with_pydy(which, tmp_path_factory):
    """generate_ode_function(..., generator=ODEFunctionGenerator) in the
    full-rhs, full-mass-matrix and minimal forms, against PyDy's own
    generator (the minimal form)."""
    sysm = system(which)
    ref = reference(which, tmp_path_factory)
    forms = _forms(sysm)
    assert len(forms) == (3 if len(sysm.speeds) <= 2 else 2)
    for form, (args, kw) in forms.items():
        ours = generate_ode_function(*args, generator=OURS, **kw)
        for x, t, r, p in samples(sysm, seed=1):
            a = call(ours, sysm, x, t, r, p)
            b = call(ref, sysm, x, t, r, p).copy()
            assert rel_err(a, b) < TOL, (which, form, a, b)


@pytest.mark.slow
def test_full_forms_against_pydy_in_the_same_form(tmp_path):
    """The full mass matrix and the full rhs, PyDy's generator built in that
    form too (n = 1)."""
    sysm = system("pendulum1")
    for form, (args, kw) in _forms(sysm).items():
        extra = {"tmp_dir": str(tmp_path / form.replace(" ", "_"))} \
            if REFERENCE == "cython" else {}
        ref = generate_ode_function(*args, generator=REFERENCE, **kw, **extra)
        ours = generate_ode_function(*args, generator=OURS, **kw)
        for x, t, r, p in samples(sysm, seed=2):
            assert rel_err(ours(x, t, r, p), ref(x, t, r, p)) < TOL, form


# ------------------------------------------------------ argument types
ARG_TYPES = [(pt, rt) for pt in (None, "array", "dictionary")
             for rt in (None, "array", "function", "dictionary")]


def _as(kind, sysm, x, t, r, p, time_first=False):
    """r and p as PyDy documents them for the argument type kind."""
    consts = list(sysm.constants_symbols)          # the order PyDy's tuple() gives
    spec = list(sysm.specifieds_symbols)
    pt, rt = kind
    p_ = dict(zip(consts, p)) if pt == "dictionary" else p
    if rt == "function":
        r_ = (lambda t_, x_: r) if time_first else (lambda x_, t_: r)
    elif rt == "dictionary":
        # a single key with a number, a tuple key with an array, a function of (x, t)
        r_ = {spec[0]: r[0]}
        if len(spec) > 2:
            r_[tuple(spec[1:-1])] = r[1:-1]
        if len(spec) > 1:
            r_[spec[-1]] = ((lambda t_, x_: r[-1]) if time_first else (lambda x_, t_: r[-1]))
    else:
        r_ = r
    return r_, p_


@pytest.mark.parametrize("kind", ARG_TYPES, ids=[f"p-{a}-r-{b}" for a, b in ARG_TYPES])
def test_argument_types_agree_with_pydy(kind, tmp_path_factory):
    """constants_arg_type x specifieds_arg_type: p an array or a dict, r an
    array, a function r(x, t) or a dict (single and tuple keys, numbers,
    arrays and functions), each against PyDy's generator given the same."""
    sysm = system("pendulum2")
    ref = reference("pendulum2", tmp_path_factory)
    args = sysm._args_for_gen_ode_func()
    kw = sysm._kwargs_for_gen_ode_func()
    ours = generate_ode_function(*args, generator=OURS, constants_arg_type=kind[0],
                                 specifieds_arg_type=kind[1], **kw)
    for x, t, r, p in samples(sysm, seed=3):
        r_, p_ = _as(kind, sysm, x, t, r, p)
        a = ours(x, t, r_, p_)
        b = ref(x, t, r_, p_).copy()
        assert rel_err(a, b) < TOL, (kind, a, b)


@pytest.mark.slow
def test_time_first_and_no_specifieds(tmp_path_factory):
    """time_first=True: rhs(t, x, r, p), and r's functions called (t, x), as
    PyDy; a model without specifieds: rhs(x, t, p)."""
    sysm = system("pendulum2")
    ref = reference("pendulum2", tmp_path_factory)
    args, kw = sysm._args_for_gen_ode_func(), sysm._kwargs_for_gen_ode_func()
    ours = generate_ode_function(*args, generator=OURS, time_first=True, **kw)
    for x, t, r, p in samples(sysm, seed=4):
        r_, p_ = _as(("dictionary", "dictionary"), sysm, x, t, r, p, time_first=True)
        assert rel_err(ours(t, x, r_, p_), ref(x, t, r, p)) < TOL
    msd = system("msd1")
    ref1 = reference("msd1", tmp_path_factory)
    ours1 = msd.generate_ode_function(generator=OURS)
    x, t, _, p = samples(msd)[0]
    assert rel_err(ours1(x, t, p), ref1(x, t, p)) < TOL
    with pytest.raises(TypeError, match=r"rhs takes \(x, t, p\), 4 argument"):
        ours1(x, t, np.zeros(0), p)


def test_linear_sys_solver(tmp_path_factory):
    """'numpy' and 'scipy' solve in C; a function is called with the speeds'
    mass matrix and forcing, as PyDy calls it."""
    sysm = system("pendulum2")
    ref = reference("pendulum2", tmp_path_factory)
    args, kw = sysm._args_for_gen_ode_func(), sysm._kwargs_for_gen_ode_func()
    seen = []

    def solve(A, b):
        seen.append(A.shape)
        return np.linalg.solve(A, b)

    x, t, r, p = samples(sysm, seed=5)[0]
    for solver in ("numpy", "scipy", solve):
        ours = generate_ode_function(*args, generator=OURS, linear_sys_solver=solver, **kw)
        assert rel_err(ours(x, t, r, p), ref(x, t, r, p)) < TOL, solver
    assert seen == [(3, 3)]
    # the symbolic solve is PyDy's Cython-only option (generate_ode_function
    # refuses it for other generators); the class itself takes it (solved in C)
    g = OURS(*args, linear_sys_solver="sympy:LU", **kw)
    assert rel_err(g.generate()(x, t, r, p), ref(x, t, r, p)) < TOL


# ------------------------------------------- a fresh array per call
def test_fresh_array_and_solve_ivp(tmp_path_factory):
    """PyDy's Cython rhs returns the same array on every call; scipy's
    solve_ivp keeps the derivative it was given (FSAL stage, rejected steps,
    the first step's estimate), so the bare function silently gives another
    trajectory. The rhs here returns a fresh array and integrates as PyDy's
    rhs wrapped in .copy() does."""
    from scipy.integrate import solve_ivp
    sysm = system("pendulum2")
    ref = reference("pendulum2", tmp_path_factory)
    args, kw = sysm._args_for_gen_ode_func(), sysm._kwargs_for_gen_ode_func()
    ours = generate_ode_function(*args, generator=OURS, **kw)
    x, t, r, p = samples(sysm, seed=6)[0]
    a1 = ours(x, t, r, p)
    a1_before = a1.copy()
    a2 = ours(x + 0.1, t, r, p)
    assert a1 is not a2 and np.array_equal(a1, a1_before)
    if REFERENCE == "cython":
        assert ref(x, t, r, p) is ref(x + 0.1, t, r, p)    # PyDy's shared buffer
    x0 = np.array([0.0, 2.0, 2.5, 0.0, 0.0, 0.0])            # a large swing
    r0 = np.zeros(3)

    def run(f):
        return solve_ivp(lambda tt, y: f(y, tt, r0, p), (0.0, 3.0), x0, method="RK45",
                         rtol=1e-8, atol=1e-10)

    good, mine = run(lambda *a: ref(*a).copy()), run(ours)
    assert good.status == mine.status == 0
    assert rel_err(mine.y[:, -1], good.y[:, -1]) < 1e-6
    if REFERENCE == "cython":
        bare = run(ref)
        # the shared buffer changes the run: another number of evaluations
        # and another final state
        assert bare.nfev != good.nfev
        assert rel_err(bare.y[:, -1], good.y[:, -1]) > 100 * rel_err(mine.y[:, -1],
                                                                      good.y[:, -1])


# ----------------------------------------------------------- the rest
def test_errors_name_the_argument_and_are_not_type_errors():
    """PyDy's generate_ode_function takes a TypeError from the class for "not
    a generator" (NotImplementedError: ... is not a valid generator): every
    refusal here is a gen.ModelError (a ValueError) naming the argument."""
    sysm = system("pendulum1")
    args, kw = sysm._args_for_gen_ode_func(), sysm._kwargs_for_gen_ode_func()
    with pytest.raises(gen.ModelError, match="unknown argument.*bogus"):
        generate_ode_function(*args, generator=OURS, bogus=1, **kw)
    with pytest.raises(gen.ModelError, match="constants_arg_type = 'list'"):
        generate_ode_function(*args, generator=OURS, constants_arg_type="list", **kw)
    with pytest.raises(gen.ModelError, match="linear_sys_solver = 'lu'"):
        generate_ode_function(*args, generator=OURS, linear_sys_solver="lu", **kw)
    with pytest.raises(gen.ModelError, match=r"mass_matrix has shape \(2, 2\), expected \(4, 4\)"):
        generate_ode_function(sysm.eom_method.forcing_full, *args[1:], generator=OURS,
                              mass_matrix=sysm.eom_method.mass_matrix,
                              specifieds=kw["specifieds"])
    # PyDy's own cython options are accepted (a switched script runs as it was)
    OURS(*args, cse=False, prefix="x", tmp_dir="/nonexistent", force_c_contiguous=True, **kw)
    # a full mass matrix that couples the kinematic rows with u'
    km = sysm.eom_method
    Mf = km.mass_matrix_full.copy()
    Mf[0, 2] = 1
    with pytest.raises(gen.ModelError, match=r"mass_matrix\[:nq, nq:\].*not zero"):
        OURS(km.forcing_full, *args[1:], mass_matrix=Mf,
             specifieds=kw["specifieds"]).generate()
    ours = generate_ode_function(*args, generator=OURS, **kw)
    x, t, r, p = samples(sysm)[0]
    consts = list(sysm.constants_symbols)
    with pytest.raises(ValueError, match=f"no value for the constant {consts[0]}"):
        ours(x, t, r, {c: 1.0 for c in consts[1:]})
    spec = list(sysm.specifieds_symbols)
    with pytest.raises(ValueError, match="gives no value"):
        ours(x, t, {spec[0]: 1.0}, p)
    with pytest.raises(ValueError, match=r"x must have shape \(4,\), got \(3,\)"):
        ours(x[:3], t, r, p)
    with pytest.raises(ValueError, match=rf"p must have shape \({len(p)},\)"):
        ours(x, t, r, p[:-1])
    # lists work as arrays do
    assert rel_err(ours(list(x), t, list(r), list(p)), ours(x, t, r, p)) == 0


def test_nonlinear_kinematics_refused_by_from_matrices():
    q, u = sm.Function("q")(sm.Symbol("t")), sm.Function("u")(sm.Symbol("t"))
    k = sm.Symbol("k")
    with pytest.raises(gen.ModelError, match="kinematics row 0 .* not linear"):
        gen.Model.from_matrices(sm.Matrix([[1]]), sm.Matrix([-k * q]), [q], [u],
                                sm.Matrix([q.diff() - u**2]), constants={k: 1.0})


def test_from_matrices_matches_from_kanes():
    """Model.from_matrices of a KanesMethod's M, f and kd_eqs gives the same
    compiled rhs as Model.from_kanes (bit for bit or to rounding)."""
    sysm = system("pendulum2")
    km = sysm.eom_method
    consts = {c: v for c, v in zip(sorted(sysm.constants_symbols, key=str),
                                   [9.81, 1.0, 0.7, 1.1, 0.4, 0.9])}
    inputs = sorted(sysm.specifieds_symbols, key=str)
    t = sm.Symbol("t")
    kd = sm.Matrix([qi.diff(t) - ui for qi, ui in zip(km.q, km.u)])
    a = gen.compile(gen.Model.from_matrices(km.mass_matrix, km.forcing, km.q, km.u, kd,
                                            constants=consts, inputs=inputs, name="fm"))
    b = gen.compile(gen.Model.from_kanes(km, constants=consts, inputs=inputs, name="fk"))
    x, _, r, _ = samples(sysm, seed=7)[0]
    assert rel_err(a.rhs(0.0, x, r=r), b.rhs(0.0, x, r=r)) < 1e-14


def test_constants_as_a_set_give_one_cached_build():
    """A set's iteration order changes between processes: the model keeps
    the constants and specifieds of a set by name (and each call permutes p
    and r into that order), so the compile cache finds one build whatever
    the order; a list keeps the user's order."""
    sysm = system("pendulum1")
    args, kw = sysm._args_for_gen_ode_func(), sysm._kwargs_for_gen_ode_func()
    consts = list(args[3])
    spec = list(kw["specifieds"])
    kw = {**kw, "specifieds": set(spec)}
    a = OURS(*args[:3], set(consts), **kw).generate()
    by_name = sorted(consts, key=str)
    assert a.model.p_orig == by_name
    assert a.model.r_orig == sorted(spec, key=str)
    b = OURS(*args[:3], by_name, **{**kw, "specifieds": sorted(spec, key=str)}).generate()
    assert a.simulator.build_info["module"] == b.simulator.build_info["module"]
    c = OURS(*args[:3], by_name[::-1], **{**kw, "specifieds": spec}).generate()
    assert c.model.p_orig == by_name[::-1]
    x, t, r, p = samples(sysm, seed=8)[0]
    # samples' p and r are in the order of sysm's sets (== consts, spec)
    pd, rd = dict(zip(consts, p)), dict(zip(spec, r))
    ref = a(x, t, [rd[s] for s in a.specifieds], [pd[c] for c in a.constants])
    got = c(x, t, rd, pd)
    assert rel_err(got, ref) < 1e-15


def test_import_gen_does_not_import_pydy():
    code = ("import sys, gen; assert 'gen.pydy' not in sys.modules and 'pydy' not in "
            "sys.modules; assert gen.pydy.ODEFunctionGenerator.__name__ == "
            "'ODEFunctionGenerator'; assert 'pydy' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_derivative_specifieds_and_time():
    """A specified's derivative as a specified (PyDy allows Derivative
    specifieds), against PyDy's lambdify generator and the hand-written
    value; an explicit t in the forcing (PyDy's generators cannot take it)
    against the hand-written value."""
    x, v, y = sm.Function("x")(sm.Symbol("t")), sm.Function("v")(sm.Symbol("t")), \
        sm.Function("y")(sm.Symbol("t"))
    k, c, m, t = sm.symbols("k c m t")
    M, G = sm.Matrix([[m]]), sm.Matrix([v])
    F = sm.Matrix([-k * (x - y) - c * (v - y.diff(t))])
    X, r, p = np.array([0.3, -0.2]), np.array([0.1, 0.5]), np.array([2.0, 0.3, 1.5])
    expected = np.array([-0.2, (-2.0 * (0.3 - 0.1) - 0.3 * (-0.2 - 0.5)) / 1.5])
    kw = dict(mass_matrix=M, coordinate_derivatives=G, specifieds=[y, y.diff(t)])
    ours = generate_ode_function(F, [x], [v], [k, c, m], generator=OURS, **kw)
    ref = generate_ode_function(F, [x], [v], [k, c, m], generator="lambdify", **kw)
    assert rel_err(ours(X, 0.7, r, p), expected) < 1e-15
    assert rel_err(ours(X, 0.7, r, p), ref(X, 0.7, r, p)) < 1e-15
    timed = generate_ode_function(F + sm.Matrix([sm.sin(t)]), [x], [v], [k, c, m],
                                  generator=OURS, **kw)
    assert rel_err(timed(X, 0.7, r, p), expected + [0, np.sin(0.7) / 1.5]) < 1e-15


def test_non_finite_values_are_named_by_their_kind_and_symbol():
    """A NaN constant was reported as "an input value is NaN" (issue 47): the
    C call refuses it, and the drop-in names it in the caller's terms, a
    constant of p, a specified of r or a state of x, by its symbol."""
    sysm = system("pendulum1")
    args, kw = sysm._args_for_gen_ode_func(), sysm._kwargs_for_gen_ode_func()
    ours = generate_ode_function(*args, generator=OURS, **kw)
    x, t, r, p = samples(sysm)[0]
    consts, spec = list(sysm.constants_symbols), list(sysm.specifieds_symbols)
    states = [str(s.func) for s in list(sysm.coordinates) + list(sysm.speeds)]
    bad = p.copy()
    bad[1] = np.nan
    with pytest.raises(gen.InputError) as e:
        ours(x, t, r, bad)
    assert str(e.value) == f"the constant {consts[1]} of p is nan: every constant must be finite"
    assert (e.value.argument, e.value.index) == ("p", 1)
    with pytest.raises(gen.InputError, match=rf"^the constant {consts[0]} of p is inf: "):
        ours(x, t, r, {c: (np.inf if c == consts[0] else 1.0) for c in consts})
    rb = r.copy()
    rb[-1] = -np.inf
    with pytest.raises(gen.InputError, match=rf"^the specified {spec[-1].func} of r is -inf: "
                       "every specified must be finite$"):
        ours(x, t, rb, p)
    xb = x.copy()
    xb[2] = np.nan
    with pytest.raises(gen.InputError, match=rf"^the state {states[2]} of x is nan: every "
                       "state must be finite$"):
        ours(xb, t, r, p)
