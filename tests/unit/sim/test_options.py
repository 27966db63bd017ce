"""The run options (gen/sim/options.py, issue 42): gen.RunOptions is the one
list of them; its defaults are the C engine's own (``<p>_sim_options_default``,
rendered from gen/codegen/abi.py); ``options=`` gives the same numbers as the
keywords, bit for bit, and a keyword given explicitly wins; a wrong name or
value names the argument; the options that have no keyword reach the engine."""
import dataclasses
import inspect

import numpy as np
import pytest

import cart_pole
import gen
from gen.codegen import abi
from gen.sim.options import OPTION_NAMES, OPTIONS
from helpers import pendulum_state

# the keywords of simulate and ensemble before options= existed (the public API)
SIMULATE = ["x0", "t_end", "dt", "r", "p", "controller", "method", "rtol", "atol", "project",
            "t0", "max_steps", "input_period", "input_hold", "every", "final_only", "max_rows",
            "events", "terminal", "consistent"]
ENSEMBLE = SIMULATE[:6] + ["reduce", "client", "chunk", "workers", "progress"] + SIMULATE[6:]


@pytest.fixture(scope="module")
def cart():
    return gen.compile(cart_pole.model())


def _x0(sim):
    return pendulum_state(0.9, 0.3, 1.0, "kane")


def test_defaults_are_the_engines(kane_sim):
    """Every option the C struct has starts at the value the C library's own
    sim_options_default writes (proj_tol: 0 stands for its 16 epsilons)."""
    lib = kane_sim.library
    c = lib.new("sim_options")
    lib.function("sim_options_default")(c)
    d = gen.RunOptions()
    assert abi.METHODS[d.method] == c.method == 0 and d.method == "rk4"
    for name in ("rtol", "atol", "h_init", "h_min", "h_max", "max_steps", "proj_max_iter",
                 "every"):
        assert getattr(d, name) == getattr(c, name), name
    assert (d.project, d.final_only) == (bool(c.project), bool(c.final_only)) == (True, False)
    assert d.proj_tol == 0.0 and c.proj_tol == 16 * np.finfo(float).eps
    assert d.input_hold == "zoh" and abi.HOLDS["zoh"] == lib.new("input").hold
    assert (d.rtol, d.atol, d.max_steps) == (1e-8, 1e-10, 100000)


def test_signatures_keep_their_keywords_and_show_the_defaults():
    sim_sig = inspect.signature(gen.Simulator.simulate)
    ens_sig = inspect.signature(gen.Simulator.ensemble)
    assert list(sim_sig.parameters)[1:] == SIMULATE + ["options"]
    assert list(ens_sig.parameters)[1:] == ENSEMBLE + ["options"]
    d = gen.RunOptions()
    for sig in (sim_sig, ens_sig):
        for name in OPTION_NAMES:
            par = sig.parameters[name]
            assert par.kind is par.KEYWORD_ONLY and par.default == getattr(d, name), name
    assert sim_sig.parameters["method"].default == "rk4"
    assert [o.name for o in OPTIONS] == [f.name for f in dataclasses.fields(gen.RunOptions)]
    for name in ("Parameters", "options : gen.RunOptions", "rtol : float, optional"):
        assert name in gen.Simulator.simulate.__doc__
    assert "options : gen.RunOptions" in gen.Simulator.ensemble.__doc__


@pytest.mark.parametrize("opts", [dict(method="dopri5", rtol=1e-10, atol=1e-12),
                                  dict(method="rodas4", rtol=1e-9, atol=1e-11, max_steps=5000),
                                  dict(method="rk4", project=False, every=7),
                                  dict(method="dopri5", final_only=True, t0=0.5)])
def test_options_equal_the_keywords_bit_for_bit(kane_sim, opts):
    x0 = _x0(kane_sim)
    ref = kane_sim.simulate(x0, 2.0, 0.01, **opts)
    sol = kane_sim.simulate(x0, 2.0, 0.01, options=gen.RunOptions(**opts))
    assert np.array_equal(sol.t, ref.t) and np.array_equal(sol.x, ref.x)
    assert np.array_equal(sol.lam, ref.lam) and sol.stats == ref.stats
    if not opts.get("final_only"):
        assert len(ref.t) > 10


def test_a_keyword_given_explicitly_wins(kane_sim):
    x0 = _x0(kane_sim)
    opts = gen.RunOptions(method="rk4", rtol=1e-4, every=3)
    dopri = kane_sim.simulate(x0, 2.0, 0.01, method="dopri5", rtol=1e-10)
    rk4 = kane_sim.simulate(x0, 2.0, 0.01)
    got = kane_sim.simulate(x0, 2.0, 0.01, options=opts, method="dopri5", rtol=1e-10, every=1)
    assert np.array_equal(got.x, dopri.x) and not np.array_equal(got.x, rk4.x)
    # the defaults of a keyword never override options: only what is given does
    got = kane_sim.simulate(x0, 2.0, 0.01, options=gen.RunOptions(method="dopri5", rtol=1e-10))
    assert np.array_equal(got.x, dopri.x)
    # keywords over options= in an ensemble too, each run as its simulate
    X0 = np.array([pendulum_state(a, 0.0, 1.0, "kane") for a in (0.3, 0.8, 1.2)])
    res = kane_sim.ensemble(X0, 1.0, 0.01, options=opts, method="dopri5", rtol=1e-10,
                            every=1)
    ref = kane_sim.ensemble(X0, 1.0, 0.01, method="dopri5", rtol=1e-10)
    assert np.array_equal(res.final, ref.final)
    assert np.array_equal(res.final[1], kane_sim.simulate(X0[1], 1.0, 0.01, method="dopri5",
                                                          rtol=1e-10).x[-1])


def test_options_without_a_keyword_reach_the_engine(cart):
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    free = cart.simulate(x0, 2.0, 0.5, method="dopri5")
    capped = cart.simulate(x0, 2.0, 0.5, options=gen.RunOptions(method="dopri5", h_max=0.005))
    assert free.stats["n_accepted"] < 400 <= capped.stats["n_accepted"]
    np.testing.assert_allclose(capped.x, free.x, rtol=0, atol=1e-6)
    # a first step: the number of rejected and accepted steps changes, not the answer
    tiny = cart.simulate(x0, 2.0, 0.5, options=gen.RunOptions(method="dopri5", h_init=1e-9))
    assert tiny.stats["n_accepted"] > free.stats["n_accepted"]
    np.testing.assert_allclose(tiny.x, free.x, rtol=0, atol=1e-6)
    # the same through an ensemble, each run as its simulate
    res = cart.ensemble(np.array([x0, x0]), 2.0, 0.5,
                        options=gen.RunOptions(method="dopri5", h_max=0.005))
    assert np.array_equal(res.final[1], capped.x[-1])


def test_the_projection_options_reach_the_engine(kane_sim):
    """One Newton iteration cannot bring an RK4 step of the seed pendulum
    back onto its circle to 16 epsilons: the run stops, as the engine says."""
    x0 = _x0(kane_sim)
    sol = kane_sim.simulate(x0, 1.0, 0.01, options=gen.RunOptions(proj_max_iter=10))
    fc = np.array([kane_sim.constraints(x[:2]) for x in sol.x])
    assert np.max(np.abs(fc)) < 1e-14
    with pytest.raises(gen.ConvergenceError, match="did not converge"):
        kane_sim.simulate(x0, 1.0, 0.01, options=gen.RunOptions(proj_max_iter=1))
    unprojected = kane_sim.simulate(x0, 1.0, 0.01, project=False)
    fc = np.array([kane_sim.constraints(x[:2]) for x in unprojected.x])
    assert np.max(np.abs(fc)) > 1e-12        # the drift projection removes


def test_a_wrong_name_is_named(kane_sim):
    x0 = _x0(kane_sim)
    with pytest.raises(TypeError, match="'rtoll'"):
        gen.RunOptions(rtoll=1e-6)
    with pytest.raises(TypeError, match=r"unexpected keyword argument 'rtoll'; did you mean "
                                        r"'rtol'\?"):
        kane_sim.simulate(x0, 1.0, 0.1, rtoll=1e-6)
    with pytest.raises(TypeError, match=r"'h_max': give it as options=gen\.RunOptions"):
        kane_sim.simulate(x0, 1.0, 0.1, h_max=0.1)
    with pytest.raises(TypeError, match=r"Simulator\.ensemble\(\) got an unexpected keyword "
                                        "argument 'methd'"):
        kane_sim.ensemble(x0, 1.0, 0.1, methd="rk4")


@pytest.mark.parametrize("name, value, text", [
    ("method", "euler", "method must be one of"), ("rtol", -1.0, "rtol must be a positive"),
    ("atol", "tight", "atol must be a number"), ("max_steps", 0, "max_steps must be an "
                                                                "integer >= 1"),
    ("max_steps", "a lot", "max_steps must be an integer"), ("every", 1.5, "every must be"),
    ("h_max", float("nan"), "h_max must be a finite"), ("proj_max_iter", -1, "proj_max_iter"),
    ("input_hold", "cubic", "input_hold must be 'zoh' or 'linear'"),
    ("max_rows", 0, "max_rows must be None or an integer >= 1"),
    ("t0", float("inf"), "t0 must be a finite"), ("terminal", True, "terminal= needs events")])
def test_a_wrong_value_names_the_argument(kane_sim, name, value, text):
    with pytest.raises(gen.InputError, match=text) as e:
        gen.RunOptions(**{name: value})
    assert e.value.argument == name
    if name in OPTION_NAMES:          # the keyword says the same
        with pytest.raises(gen.InputError, match=text) as e:
            kane_sim.simulate(_x0(kane_sim), 1.0, 0.1, **{name: value})
        assert e.value.argument == name


def test_options_must_be_run_options(kane_sim):
    with pytest.raises(gen.InputError, match="options must be a gen.RunOptions, got dict"):
        kane_sim.simulate(_x0(kane_sim), 1.0, 0.1, options={"method": "dopri5"})


def test_run_options_are_frozen_and_normalized():
    o = gen.RunOptions(method="rodas", max_steps=5000.0, project=0)
    assert (o.method, o.max_steps, o.project) == ("rodas4", 5000, False)
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.rtol = 1.0
    assert dataclasses.replace(o, rtol=1e-6).rtol == 1e-6
