"""FMU export (issue 19) checked by FMPy, an FMI importer nobody here wrote:
fmpy.validate_fmu reports no problem for every FMU (FMI 2.0 and 3.0,
Co-Simulation and Model Exchange, the seed pendulum with Kane and with
Lagrange, the cart-pole with an input, the rolling disc), and
fmpy.simulate_fmu reproduces sim.simulate (a tight DOPRI5 run): to 1e-8 in
Co-Simulation, to 1e-7 in Model Exchange with FMPy's own CVODE. An input
signal given to FMPy reaches the model; a singular start state is an error
status and a logged message, not a crash; the source FMU compiles with
FMPy's build step alone; the FMI glue runs clean under ASan/UBSan.

Without FMPy these tests skip (pip install eomgen[fmu]); under CI=true a
missing FMPy fails them.
"""
import functools
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import gen
import gen.core.cache
from gen.plan.dependencies import dependencies

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "examples"))
import cart_pole  # noqa: E402
import rolling_disc  # noqa: E402
import seed_pendulum  # noqa: E402

T_END, DT = 2.0, 0.01
CS_TOL, ME_TOL = 1e-8, 1e-7          # the acceptance figures

# name: (model factory, start state, units)
CASES = {
    "kane": (seed_pendulum.kane_model, {"q2": 0.6, "q1": 0.8, "u2": 0.5}, {"q1": "m", "q2": "m"}),
    "lagrange": (seed_pendulum.lagrange_model, {"q1": 0.8, "q2": 0.6, "q2_d": 0.5}, {}),
    "cart_pole": (cart_pole.model, {"theta": 0.3},
                  {"x": "m", "theta": "rad", "v": "m/s", "omega": "rad/s", "F": "N",
                   "m_c": "kg", "m_p": "kg", "l": "m", "g": "m/s2", "tip_x": "m",
                   "tip_y": "m"}),
    "disc": (rolling_disc.model, {"q2": 0.1, "u3": 8.0, "u1": 0.3}, {}),
}


def _fmpy():
    try:
        import fmpy
        import fmpy.validation  # noqa: F401
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("FMPy is required under CI=true (pip install eomgen[fmu]) but is not "
                        "installed")
        pytest.skip("FMPy is not installed (pip install eomgen[fmu])")
    return fmpy


@functools.lru_cache(maxsize=None)
def _model(name):
    return CASES[name][0]()


@functools.lru_cache(maxsize=None)
def _sim(name):
    return gen.compile(_model(name))


@functools.lru_cache(maxsize=None)
def _fmu(name, version, kind, folder):
    """An FMU of a case, exported once per session."""
    _, start, units = CASES[name]
    path = Path(folder) / f"{name}_{version[0]}_{kind}.fmu"
    return gen.export_fmu(_model(name), path, fmi_version=version, kind=kind, start=start,
                          units=units)


@pytest.fixture(scope="module")
def fmu_dir(tmp_path_factory):
    _fmpy()
    return str(tmp_path_factory.mktemp("fmus"))


def _x0(name):
    sim = _sim(name)
    x = np.zeros(sim.nx)
    for k, v in CASES[name][1].items():
        x[sim.state_names.index(k)] = v
    return sim.consistent_state(x)


@functools.lru_cache(maxsize=None)
def _reference(name, forced=False):
    """sim.simulate at a tolerance far below the comparisons' (forced: with
    the force signal of _signal as a table held between its knots)."""
    sim = _sim(name)
    kw = {}
    if forced:
        tk, Fk, _ = _signal()
        kw = dict(r=(tk, Fk[:, None]), input_hold="zoh")
    return sim.simulate(_x0(name), T_END, DT, method="dopri5", rtol=1e-12, atol=1e-12, **kw)


def _signal():
    """A force on the cart that steps every 0.25 s: the knots (t_k, F_k) and
    the same staircase as FMPy's input table, each step a repeated time
    point. FMPy's Model Exchange driver sets a continuous input only at
    communication points and input events (its right-hand side does not
    interpolate it), and stops, sets and restarts CVODE at the events: a
    staircase is what both of its drivers apply exactly."""
    tk = np.round(np.arange(0, T_END, 0.25), 12)
    Fk = 2.0 * np.sin(3.0 * tk) + 0.5
    rows = []
    for i, (t, F) in enumerate(zip(tk, Fk)):
        if i:
            rows.append((t, Fk[i - 1]))
        rows.append((t, F))
    rows.append((T_END, Fk[-1]))
    return tk, Fk, np.array(rows, dtype=[("time", np.float64), ("F", np.float64)])


def _simulate(path, kind, names, **kw):
    """FMPy's run on the output grid (the rows it adds at events dropped:
    the state is continuous there)."""
    from fmpy import simulate_fmu
    tol = 1e-10 if kind == "CoSimulation" else 1e-12
    kw.setdefault("relative_tolerance", tol)
    r = simulate_fmu(str(path), fmi_type=kind, stop_time=T_END, output_interval=DT,
                     output=list(names), **kw)
    keep = np.r_[np.diff(r["time"]) > 0, True]
    return r["time"][keep], np.column_stack([r[n] for n in names])[keep]


def _check_matches(name, path, kind, forced=False, **kw):
    """The FMU's states against sim.simulate; returns the error."""
    sim = _sim(name)
    t_ref, X_ref = _reference(name, forced)
    t, X = _simulate(path, kind, sim.state_names, **kw)
    assert t.shape == t_ref.shape and np.allclose(t, t_ref, rtol=0, atol=1e-12)
    err = float(np.max(np.abs(X - X_ref)))
    assert err < (CS_TOL if kind == "CoSimulation" else ME_TOL), (name, kind, err)
    return err


def _check_outputs(name, path, kind):
    """Outputs: the model's (y), else the multipliers and residuals, against
    the Simulator at the FMU's own states."""
    sim = _sim(name)
    names = (list(sim.output_names) if sim.ny else
             [f"lam{i}" for i in range(sim.mv)] + [f"fc{i}" for i in range(sim.mc)]
             + [f"fv{i}" for i in range(sim.mv)])
    t, V = _simulate(path, kind, sim.state_names + names)
    X, Y = V[:, :sim.nx], V[:, sim.nx:]
    for ti, xi, yi in zip(t[::20], X[::20], Y[::20]):
        if sim.ny:
            want = sim.outputs(ti, xi)
        else:
            want = np.concatenate([sim.multipliers(ti, xi), sim.constraints(xi[:sim.nq]),
                                   sim.velocity_constraints(xi[:sim.nq], xi[sim.nq:])])
        np.testing.assert_allclose(yi, want, rtol=1e-9, atol=1e-11)
    if not sim.ny:
        assert np.max(np.abs(Y[:, sim.mv:])) < 1e-10      # on the constraints


# ------------------------------------------------------------- fast tier
def test_seed_pendulum_fmi2_validates_and_matches(fmu_dir):
    """The Kane pendulum, FMI 2.0, one FMU with both interfaces."""
    from fmpy.validation import validate_fmu
    path = _fmu("kane", "2.0", "both", fmu_dir)
    assert validate_fmu(str(path)) == []
    cs = _check_matches("kane", path, "CoSimulation")
    me = _check_matches("kane", path, "ModelExchange")
    print(f"kane FMI 2.0: CS {cs:.2e}, ME {me:.2e}")
    _check_outputs("kane", path, "CoSimulation")
    # doStep honours the importer's tolerance: over long communication steps
    # (0.5 s) a loose one is less accurate, and each meets its tolerance
    from fmpy import simulate_fmu
    sim = _sim("kane")
    _, X_ref = sim.simulate(_x0("kane"), T_END, 0.5, method="dopri5", rtol=1e-12, atol=1e-12)
    err = {}
    for tol in (1e-5, 1e-10):
        r = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=T_END,
                         output_interval=0.5, relative_tolerance=tol, output=sim.state_names)
        err[tol] = np.max(np.abs(np.column_stack([r[n] for n in sim.state_names]) - X_ref))
    assert err[1e-10] < 1e-8 and 1e3 * err[1e-10] < err[1e-5] < 1e-3, err


def test_cart_pole_fmi3_input_reaches_the_model(fmu_dir):
    """FMI 3.0, the cart-pole with a force signal given to FMPy, against
    sim.simulate with the same force as a table."""
    from fmpy.validation import validate_fmu
    path = _fmu("cart_pole", "3.0", "both", fmu_dir)
    assert validate_fmu(str(path)) == []
    signal = _signal()[2]
    cs = _check_matches("cart_pole", path, "CoSimulation", forced=True, input=signal)
    me = _check_matches("cart_pole", path, "ModelExchange", forced=True, input=signal)
    print(f"cart_pole FMI 3.0 with input: CS {cs:.2e}, ME {me:.2e}")
    # and without the signal the motion is another one: the input did reach it
    _, X_free = _reference("cart_pole")
    _, X_forced = _reference("cart_pole", True)
    assert np.max(np.abs(X_free[:, 0] - X_forced[:, 0])) > 0.1
    _check_outputs("cart_pole", path, "ModelExchange")


def test_model_description(fmu_dir):
    """Variables, units and descriptions as FMPy reads them."""
    from fmpy import read_model_description
    md = read_model_description(str(_fmu("cart_pole", "3.0", "both", fmu_dir)))
    var = {v.name: v for v in md.modelVariables}
    assert var["x"].unit == "m" and var["der(x)"].unit == "m/s"
    assert var["v"].unit == "m/s" and var["der(v)"].unit == "m/s2"
    assert var["F"].causality == "input" and var["F"].unit == "N"
    assert var["m_c"].causality == "parameter" and var["m_c"].variability == "tunable"
    assert float(var["g"].start) == 9.81 and var["g"].unit == "m/s2"
    # the units' SI decomposition
    base = {u.name: u.baseUnit for u in md.unitDefinitions}
    assert (base["N"].kg, base["N"].m, base["N"].s) == (1, 1, -2)
    assert (base["rad/s2"].rad, base["rad/s2"].s, base["rad/s2"].m) == (1, -2, 0)
    assert [o.variable.name for o in md.outputs] == ["tip_x", "tip_y"]
    assert "theta" in var["theta"].description
    # continuous states in the order of the independent state
    assert [d.variable.derivative.name for d in md.derivatives] == ["x", "theta", "v", "omega"]
    # dependencies from the structure: x' = v, theta' = omega, the accelerations
    # on theta, omega and F; tip_y on theta alone
    deps = {d.variable.name: sorted(v.name for v in d.dependencies) for d in md.derivatives}
    assert deps == {"der(x)": ["v"], "der(theta)": ["omega"],
                    "der(v)": ["F", "omega", "theta"], "der(omega)": ["F", "omega", "theta"]}
    out = {o.variable.name: sorted(v.name for v in o.dependencies) for o in md.outputs}
    assert out == {"tip_x": ["theta", "x"], "tip_y": ["theta"]}
    # the constrained pendulum: L holds the constraint (fixed), m and g do not
    md = read_model_description(str(_fmu("kane", "2.0", "both", fmu_dir)))
    var = {v.name: v for v in md.modelVariables}
    assert var["L"].variability == "fixed" and var["g"].variability == "tunable"
    assert var["q2"].initial == "exact" and var["q1"].initial == "approx"
    assert md.numberOfContinuousStates == 2
    assert [o.variable.name for o in md.outputs] == ["lam0", "fc0", "fv0"]


def test_singular_start_is_an_error_with_a_message(fmu_dir):
    """q2 = L with q1 = 0: the dependent coordinate cannot be solved; FMPy
    gets fmi2Error and the logger the reason, for both interfaces."""
    from fmpy import simulate_fmu
    path = _fmu("kane", "2.0", "both", fmu_dir)
    for kind in ("CoSimulation", "ModelExchange"):
        messages = []

        def logger(*args):
            messages.append(args[-1].decode())

        with pytest.raises(Exception, match="fmi2ExitInitializationMode"):
            simulate_fmu(str(path), fmi_type=kind, stop_time=1.0, logger=logger,
                         start_values={"q2": 1.0, "q1": 0.0})
        assert any("the dependent coordinates and speeds (q1, u1) cannot be solved" in m
                   for m in messages), messages
    # the same FMU still runs from a regular state afterwards (nothing global)
    r = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=0.1,
                     start_values={"q2": -0.6}, output=["q1"])
    assert abs(r["q1"][0] - 0.8) < 1e-15


def test_fmu_state_rollback_with_fmpy(fmu_dir):
    """A co-simulation master's rollback: FMPy saves the FMU state, steps,
    restores it (also through its serialized bytes) and steps again to the
    same numbers."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    path = str(_fmu("kane", "2.0", "both", fmu_dir))
    md = read_model_description(path)
    vr = [v.valueReference for v in md.modelVariables if v.name in ("q2", "q1", "u2", "u1")]
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path), instanceName="rollback",
                    modelIdentifier=md.coSimulation.modelIdentifier)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    state = fmu.getFMUstate()
    fmu.doStep(0.0, 0.1)
    a = fmu.getReal(vr)
    blob = fmu.serializeFMUstate(state)
    fmu.setFMUstate(state)
    fmu.doStep(0.0, 0.1)
    assert fmu.getReal(vr) == a
    state2 = fmu.deSerializeFMUstate(blob)
    fmu.setFMUstate(state2)
    fmu.doStep(0.0, 0.1)
    assert fmu.getReal(vr) == a
    fmu.freeFMUstate(state)
    fmu.freeFMUstate(state2)
    fmu.terminate()
    fmu.freeInstance()


def test_export_refuses_a_start_state_that_cannot_be_solved(tmp_path):
    _fmpy()
    old = tmp_path / "p.fmu"
    old.write_bytes(b"an older file")
    with pytest.raises(gen.ModelError, match=r"does not initialize at its start values.*q1, "
                                             r"u1\) cannot be solved.*start=\{\.\.\.\}"):
        gen.export_fmu(_model("kane"), old, start={"q2": 1.0, "q1": 0.0})
    assert old.read_bytes() == b"an older file"          # left as it was
    assert [p.name for p in tmp_path.iterdir()] == ["p.fmu"]


def test_bad_arguments(tmp_path, monkeypatch):
    m = _model("cart_pole")
    for kw, msg in [(dict(fmi_version="1.0"), "fmi_version must be one of 2.0, 3.0"),
                    (dict(kind="hybrid"), "kind must be one of cs, me, both"),
                    (dict(real="half"), "real must be"),
                    (dict(cs_method="euler"), "cs_method must be one of"),
                    (dict(start={"phi": 1}), "start: unknown state 'phi'; the states are x, "
                                             "theta, v, omega"),
                    (dict(start={"x": float("nan")}), "must be finite"),
                    (dict(units={"speed": "m/s"}), "units: unknown name 'speed'"),
                    (dict(units={"x": " m"}), "the unit of x")]:
        with pytest.raises(gen.ModelError, match=msg):
            gen.export_fmu(m, tmp_path / "c.fmu", **kw)
    with pytest.raises(gen.ModelError, match="must end in .fmu"):
        gen.export_fmu(m, tmp_path / "c.zip")
    # no FMPy (an import of it fails): the error says how to install it
    monkeypatch.setitem(sys.modules, "fmpy", None)
    with pytest.raises(gen.core.errors.MissingDependencyError,
                       match=r"gen.export_fmu .*needs fmpy.*pip install eomgen\[fmu\]"):
        gen.export_fmu(m, tmp_path / "c.fmu")
    assert not (tmp_path / "c.fmu").exists()


@pytest.mark.slow
def test_reproducible(tmp_path, monkeypatch):
    """The same model gives the same bytes (no timestamps, sorted entries,
    fixed zip dates, no build path in the binary), also when the binary is
    built afresh in another build cache (the binary is cached by content,
    as every library gen.toolchain.build makes)."""
    _fmpy()
    m, (_, start, units) = _model("kane"), CASES["kane"]
    a = gen.export_fmu(m, tmp_path / "a.fmu", start=start, units=units)
    monkeypatch.setenv("EOMGEN_CACHE", str(tmp_path / "other-cache"))
    b = gen.export_fmu(m, tmp_path / "b.fmu", start=start, units=units)
    assert gen.core.cache.cache_info()["modules"] == 1      # b's binary: built there
    assert a.read_bytes() == b.read_bytes()
    names = zipfile.ZipFile(a).namelist()
    assert "binaries/linux64/pendulum_kane.so" in names or sys.platform != "linux"
    assert not any(n.startswith("sources/fmi") for n in names)    # the importer's headers
    assert {"sources/pendulum_kane_lin.c", "sources/gen_fmu_fmi2.c",
            "sources/gen_fmu_model.h", "sources/gen_rt_simulate.c"} <= set(names)


def test_cli(tmp_path, capsys):
    _fmpy()
    from fmpy.validation import validate_fmu

    from gen.cli import main
    out = tmp_path / "pend.fmu"
    model = str(ROOT / "examples" / "seed_pendulum.py")
    rc = main(["fmu", model, "-o", str(out), "--fmi", "3.0", "--kind", "cs", "--start",
               "q2=0.6", "--start", "q1=0.8", "--unit", "q1=m", "--no-binary", "-q"])
    assert rc == 0
    assert "wrote" in capsys.readouterr().out
    assert validate_fmu(str(out)) == []
    names = zipfile.ZipFile(out).namelist()
    assert "sources/buildDescription.xml" in names
    assert not any(n.startswith("binaries/") for n in names)
    assert "<CoSimulation" in zipfile.ZipFile(out).read("modelDescription.xml").decode()
    assert "<ModelExchange" not in zipfile.ZipFile(out).read("modelDescription.xml").decode()
    assert main(["fmu", model, "-o", str(out), "--start", "zz=1", "-q"]) == 2
    assert "unknown state name 'zz'" in capsys.readouterr().err
    assert main(["fmu", model, "-o", str(out), "--unit", "speed=m", "-q"]) == 2
    with pytest.raises(SystemExit) as e:
        main(["fmu", model, "-o", str(out), "--fmi", "1.0", "-q"])
    assert e.value.code == 2


def _check_dependencies(name):
    """The declared dependencies hold every nonzero of the linearization
    (A, B, C, D on the independent state, the dependent entries following
    the constraints) at random states, and of the multipliers' finite
    differences."""
    rng = np.random.default_rng(3)
    m, sim = _model(name), _sim(name)
    deps = dependencies(m)
    ind = list(deps.independent)
    col = {("x", i): k for k, i in enumerate(ind)}
    col.update({("r", k): len(ind) + k for k in range(m.nr)})

    def mask(known):
        out = np.zeros(m.ns + m.nr, bool)
        for k in known:
            if k[0] != "p":
                out[col[k]] = True
        return out

    for _ in range(5):
        x = sim.consistent_state(_x0(name) + 0.1 * rng.standard_normal(m.nx))
        r = rng.standard_normal(m.nr)
        if m.ny:
            A, B, C, D = sim.linearize_outputs(x, r=r)
        else:
            A, B = sim.linearize(x, r=r)
        for k, d in enumerate(deps.derivative):
            row = np.hstack([A[k], B[k]])
            assert not np.any((np.abs(row) > 1e-12) & ~mask(d)), (name, k, row, d)
        for k, d in enumerate(deps.output):
            row = np.hstack([C[k], D[k]])
            assert not np.any((np.abs(row) > 1e-12) & ~mask(d)), (name, k, row, d)
        if m.mv:   # the multipliers, by central differences on the manifold
            for i in ind:
                h = 1e-6
                xp, xm = x.copy(), x.copy()
                xp[i] += h
                xm[i] -= h
                dl = (sim.multipliers(0, sim.consistent_state(xp), r=r)
                      - sim.multipliers(0, sim.consistent_state(xm), r=r)) / (2 * h)
                for k in range(m.mv):
                    if abs(dl[k]) > 1e-6:
                        assert ("x", i) in deps.multiplier[k], (name, k, i, dl)


def test_dependencies_cover_the_numeric_jacobians():
    for name in ("kane", "cart_pole"):
        _check_dependencies(name)
    # where the model is sparse, so are they: the pendulum's q2' = u2 alone
    assert dependencies(_model("kane")).derivative[0] == frozenset({("x", 2)})


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lagrange", "disc"])
def test_dependencies_cover_the_numeric_jacobians_more(name):
    _check_dependencies(name)


def test_dependencies_follow_blocks():
    """Two uncoupled oscillators: a diagonal mass matrix gives two blocks, so
    each acceleration depends on its own coordinate, speed and constants."""
    import sympy as sm
    from sympy.physics import mechanics as me
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    k1, k2, m1, m2 = sm.symbols("k1 k2 m1 m2")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P1, P2 = O.locatenew("P1", q1 * N.x), O.locatenew("P2", q2 * N.y)
    P1.set_vel(N, u1 * N.x)
    P2.set_vel(N, u2 * N.y)
    km = me.KanesMethod(N, q_ind=[q1, q2], u_ind=[u1, u2], kd_eqs=[q1.diff() - u1,
                                                                     q2.diff() - u2])
    km.kanes_equations([me.Particle("a", P1, m1), me.Particle("b", P2, m2)],
                       [(P1, -k1 * q1 * N.x), (P2, -k2 * q2 * N.y)])
    model = gen.Model.from_kanes(km, constants={k1: 1.0, k2: 2.0, m1: 1.0, m2: 3.0},
                                 name="two_springs")
    d = dependencies(model)
    assert d.derivative[2] == {("x", 0), ("p", 0), ("p", 2)}      # u1' = -k1 q1 / m1
    assert d.derivative[3] == {("x", 1), ("p", 1), ("p", 3)}


def test_units():
    """Derivative units and SI decompositions in Modelica's unit syntax."""
    from gen.export.fmu import _base_unit, _per_second
    assert [_per_second(u) for u in ("m", "m/s", "rad/s2", "N.m/rad", "1", "m/(rad.s)")] == \
        ["m/s", "m/s2", "rad/s3", "N.m/(rad.s)", "1/s", "m/(rad.s.s)"]
    assert _base_unit("N.m/rad") == [("kg", "1"), ("m", "2"), ("s", "-2"), ("rad", "-1")]
    assert _base_unit("kg.m2") == [("kg", "1"), ("m", "2")]
    assert _base_unit("km/h") == [("m", "1"), ("s", "-1"), ("factor", repr(1000 / 3600))]
    assert _base_unit("1/s") == [("s", "-1")] and _base_unit("1") == []
    assert _base_unit("degC") is None and _base_unit("m/s/s") is None


def test_packaging_ships_the_fmu_files():
    """pyproject.toml puts templates/ and csrc/ into the wheel whole (the
    FMU's templates and its glue among them); test_wheel.py checks the
    wheel itself."""
    tomllib = pytest.importorskip("tomllib", reason="tomllib needs Python 3.11")
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())
    include = cfg["tool"]["hatch"]["build"]["targets"]["wheel"]["force-include"]
    assert include == {"templates": "gen/templates", "csrc": "gen/csrc"}
    for folder, pattern in (("templates/fmu", "*.j2"), ("templates/fmu/fmi2", "*.j2"),
                            ("templates/fmu/fmi3", "*.j2"), ("csrc/products/fmu", "*.c")):
        assert any((ROOT / folder).glob(pattern)), folder
    assert any("fmpy" in d for d in cfg["project"]["optional-dependencies"]["test"])


# ------------------------------------------------------------ slow tier
MATRIX = [(name, version, kind) for name in CASES for version in ("2.0", "3.0")
          for kind in ("cs", "me")]


@pytest.mark.slow
@pytest.mark.parametrize("name,version,kind", MATRIX,
                         ids=[f"{n}-fmi{v[0]}-{k}" for n, v, k in MATRIX])
def test_matrix(fmu_dir, name, version, kind):
    """Every model, FMI version and interface: FMPy validates the FMU and
    reproduces sim.simulate (with the cart-pole's force signal as input);
    the interface the FMU was exported without is refused."""
    from fmpy import simulate_fmu
    from fmpy.validation import validate_fmu
    path = _fmu(name, version, kind, fmu_dir)
    assert validate_fmu(str(path)) == []
    fmi_type = "CoSimulation" if kind == "cs" else "ModelExchange"
    kw = dict(input=_signal()[2], forced=True) if name == "cart_pole" else {}
    err = _check_matches(name, path, fmi_type, **kw)
    print(f"{name} FMI {version} {fmi_type}: max error {err:.2e}")
    _check_outputs(name, path, fmi_type)
    other = "ModelExchange" if kind == "cs" else "CoSimulation"
    with pytest.raises(Exception):
        simulate_fmu(str(path), fmi_type=other, stop_time=0.1)


def _build_with_fmpy(unzipped, out):
    """FMPy's compile step (CMake over the FMU's build description), in a
    process that cannot import eomgen."""
    script = r"""
import sys
sys.modules["gen"] = None        # eomgen is not there
try:
    from fmpy.build import build_platform_binary as build
except ImportError:              # older FMPy
    from fmpy.util import compile_platform_binary as build
build(sys.argv[1])
"""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return subprocess.run([sys.executable, "-c", script, str(unzipped)], cwd=out, env=env,
                          capture_output=True, text=True)


@pytest.mark.slow
@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_source_fmu_builds_without_eomgen(fmu_dir, tmp_path, version):
    """Unzip, delete the binary, build it again from sources/ with FMPy's
    step (CMake): the rebuilt FMU validates and gives the same trajectory."""
    from conftest import require_tool
    require_tool("cmake")
    src = _fmu("disc", version, "cs", fmu_dir)
    unzipped = tmp_path / "fmu"
    zipfile.ZipFile(src).extractall(unzipped)
    for p in sorted((unzipped / "binaries").rglob("*"), reverse=True):
        p.unlink() if p.is_file() else p.rmdir()
    (unzipped / "binaries").rmdir()
    r = _build_with_fmpy(unzipped, tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    built = list((unzipped / "binaries").rglob("*.so"))
    assert len(built) == 1, built
    rebuilt = tmp_path / "rebuilt.fmu"
    with zipfile.ZipFile(rebuilt, "w") as zf:
        for p in sorted(unzipped.rglob("*")):
            if p.is_file():
                zf.write(p, p.relative_to(unzipped).as_posix())
    from fmpy.validation import validate_fmu
    assert validate_fmu(str(rebuilt)) == []
    names = _sim("disc").state_names
    _, X0 = _simulate(src, "CoSimulation", names)
    _, X1 = _simulate(rebuilt, "CoSimulation", names)
    assert np.max(np.abs(X1 - X0)) < 1e-9


@pytest.mark.slow
@pytest.mark.fuzz
@pytest.mark.parametrize("version", ["2", "3"])
def test_glue_under_sanitizers(tmp_path, version):
    """tests/fmu/test_fmi{2,3}_glue.c against the seed pendulum's FMU
    sources: strict flags, AddressSanitizer and UBSan."""
    from conftest import require_tool
    cc = require_tool("gcc")
    _fmpy()
    from gen.export.fmu import fmi_headers
    src = gen.export_fmu(_model("kane"), tmp_path / "k.fmu", fmi_version=f"{version}.0",
                         start={"q2": 0.6, "q1": 0.8}, binary=False)
    zipfile.ZipFile(src).extractall(tmp_path / "fmu")
    sources = sorted(str(p) for p in (tmp_path / "fmu" / "sources").glob("*.c"))
    exe = tmp_path / "glue"
    cmd = [cc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-g",
           "-fsanitize=address,undefined", "-fno-sanitize-recover=all",
           "-fno-omit-frame-pointer", "-I", str(tmp_path / "fmu" / "sources"), "-isystem",
           str(fmi_headers(f"{version}.0")), str(ROOT / "tests" / "fmu" /
                                                  f"test_fmi{version}_glue.c"),
           *sources, "-lm", "-o", str(exe)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run([str(exe)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "all checks passed" in r.stdout


@pytest.mark.slow
def test_float_and_rodas4(tmp_path):
    """real='float' (the variables stay doubles) and the RODAS4 integrator
    in Co-Simulation."""
    _fmpy()
    from fmpy.validation import validate_fmu
    m = _model("cart_pole")
    t_ref, X_ref = _reference("cart_pole")
    names = _sim("cart_pole").state_names
    f = gen.export_fmu(m, tmp_path / "f.fmu", real="float", start={"theta": 0.3})
    assert validate_fmu(str(f)) == []
    _, X = _simulate(f, "CoSimulation", names, relative_tolerance=1e-5)
    assert np.max(np.abs(X - X_ref)) < 1e-3
    r4 = gen.export_fmu(m, tmp_path / "r.fmu", cs_method="rodas4", start={"theta": 0.3},
                        kind="cs")
    _, X = _simulate(r4, "CoSimulation", names, relative_tolerance=1e-9)
    assert np.max(np.abs(X - X_ref)) < 1e-6


@pytest.mark.slow
# FMPy's CVODE callback reports the FMU's fmi3Error as an exception it cannot raise
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_partition_limit_in_model_exchange(tmp_path):
    """The four-bar with the crank angle q1 independent: at its limit
    position (q1 turns back near t = 0.93 s) no q2, q3 exist beyond it, so
    CVODE's trial step past it is refused with a message naming the state,
    as README's "what an importer must know" says, and nothing crashes;
    Co-Simulation (the full state, projected) passes through it."""
    _fmpy()
    import four_bar
    from fmpy import simulate_fmu
    m = four_bar.model()
    sim = gen.compile(m)
    x0 = sim.consistent_state(0.3 * np.random.default_rng(1).standard_normal(sim.nx))
    path = gen.export_fmu(m, tmp_path / "fb.fmu", start=dict(zip(sim.state_names, x0)))
    messages = []
    with pytest.raises(Exception):
        simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=1.0, output_interval=DT,
                     relative_tolerance=1e-12, logger=lambda *a: messages.append(a[-1].decode()))
    assert any("GetDerivatives: the dependent coordinates and speeds (q2, q3, u2, u3) cannot "
               "be solved" in s and "q1 = " in s for s in messages), messages
    t_ref, X_ref = sim.simulate(x0, 1.0, DT, method="dopri5", rtol=1e-12, atol=1e-12)
    r = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=1.0, output_interval=DT,
                     relative_tolerance=1e-10, output=sim.state_names)
    X = np.column_stack([r[n] for n in sim.state_names])
    assert np.max(np.abs(X - X_ref)) < CS_TOL
