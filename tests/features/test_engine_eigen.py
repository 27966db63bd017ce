"""The simulation engine of the Eigen backend against the C backend's,
through the same cffi wrapper and the same Simulator.

There is one engine (csrc/runtime/gen_rt_engine.c and the rest of the C runtime):
the Eigen backend's library is the C backend's model and runtime plus the
typed C++ face (gen/codegen/backends/eigen.py). So every run here is the same on both
backends bit for bit: the output times, the states, the inputs, the event
times and states, the step, rejection, right-hand-side and Jacobian counts
and h_next, for DOPRI5, RODAS4 and RK4, with tables, feedback, callbacks,
events and bounded output. (The old C++ runtime agreed to ~1e-12 and, with
RODAS4 on a time-dependent right-hand side, only to ~1e-10.) The physics of
these runs is checked against independent references in tests/unit/runtime/test_engine.py.
"""
import os
from concurrent.futures import ProcessPoolExecutor
import multiprocessing

import numpy as np
import pytest

import cart_pole as cp
import gen
import seed_pendulum as sp
import stiff_double_pendulum as sdp
from conftest import require_eigen
from helpers import pendulum_state

pytestmark = [pytest.mark.eigen, pytest.mark.slow]

MODELS = {
    "kane": sp.kane_model,
    "lagrange": sp.lagrange_model,
    "cart_pole": cp.model,
    "stiff": sdp.model,
}



def _build(job):
    model, backend = job
    gen.compile(model, backend=backend, derivatives=True)   # into the cache the fixture reads


@pytest.fixture(scope="module")
def sims():
    """{key: (C simulator, Eigen simulator)}: every build up front, two at a
    time, into gen.compile's cache."""
    require_eigen()
    models = {k: f() for k, f in MODELS.items()}
    jobs = [(m, b) for m in models.values() for b in ("eigen", "c")]
    ctx = multiprocessing.get_context("fork" if os.name == "posix" else "spawn")
    with ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
        for f in [pool.submit(_build, j) for j in jobs]:
            f.result()
    out = {}
    for k, m in models.items():
        # the derivative kernels now: _advance calls RODAS4 through the raw C API
        out[k] = (gen.compile(m, derivatives=True), gen.compile(m, backend="eigen"))
        assert out[k][1].build_info["backend"] == "eigen"
    return out


def _both(sims, key, *args, **kw):
    """The same simulate call on both backends: (C result, Eigen result)."""
    sim_c, sim_e = sims[key]
    return sim_c.simulate(*args, **kw), sim_e.simulate(*args, **kw)


def _parts(sols, *names):
    """(attribute, ...) of each gen.Solution, in the order of names."""
    return [tuple(getattr(sol, n) for n in names) for sol in sols]


def _dmax(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape, (a.shape, b.shape)
    return float(np.max(np.abs(a - b))) if a.size else 0.0


def _same(a, b):
    """The same shape and bits."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _same_counts(st_c, st_e, keys=("n_accepted", "n_rejected", "n_rhs", "n_jac", "n_out")):
    for k in keys:
        assert st_c[k] == st_e[k], (k, st_c, st_e)


# ------------------------------------------------------------------ DOPRI5
@pytest.mark.parametrize("key", ["kane", "lagrange"])
def test_dopri5_seed_pendulum(sims, key):
    """Adaptive steps, rows from the continuous extension every 0.01 s."""
    x0 = pendulum_state(1.1, 0.7, 1.0, key)
    (t_c, X_c, st_c), (t_e, X_e, st_e) = _parts(_both(
        sims, key, x0, 3.0, 0.01, method="dopri5", rtol=1e-10, atol=1e-10), "t", "x", "stats")
    d = _dmax(X_e, X_c)
    print(f"\n{key} dopri5: max|dX| = {d:.2e}, {st_c}")
    assert len(t_c) == 301 and np.array_equal(t_c, t_e)
    _same_counts(st_c, st_e)
    assert st_c["n_accepted"] < 300 and st_c["n_jac"] == 0   # steps by error control alone
    assert _same(X_e, X_c), d


def _cart_pole_gain(sim):
    A, B = sim.linearize(np.zeros(4))
    return cp.lqr(A, B, cp.Q_LQR, cp.R_LQR)


@pytest.mark.parametrize("method", ["dopri5", "rodas4"])
@pytest.mark.parametrize("period", [None, 0.05])
def test_cart_pole_feedback(sims, method, period):
    """A LinearFeedback inside the engine, continuous (RODAS4: its -Jr K in
    the Jacobian) or sampled (the steps stop at every sample)."""
    sim_c, _ = sims["cart_pole"]
    K = _cart_pole_gain(sim_c)
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    ctl = gen.LinearFeedback(K, period=period)
    (t_c, X_c, R_c, st_c), (t_e, X_e, R_e, st_e) = _parts(_both(
        sims, "cart_pole", x0, 3.0, 0.01, method=method, rtol=1e-10, atol=1e-10,
        controller=ctl), "t", "x", "r", "stats")
    d, dr = _dmax(X_e, X_c), _dmax(R_e, R_c)
    print(f"\ncart_pole {method} period {period}: max|dX| = {d:.2e}, max|dF| = {dr:.2e}, {st_c}")
    assert np.array_equal(t_c, t_e)
    _same_counts(st_c, st_e)
    assert np.max(np.abs(X_c[-1])) < 0.05          # the loop is closed
    assert _same(X_e, X_c) and _same(R_e, R_c), (d, dr)


@pytest.mark.parametrize("method", ["dopri5", "rodas4", "rk4"])
@pytest.mark.parametrize("kind", ["table_zoh", "table_linear", "callable"])
def test_cart_pole_inputs(sims, method, kind):
    """Inputs from a table (knots are step boundaries) and from a Python
    controller sampled every 0.02 s (a callback from inside the engine)."""
    sim_c, _ = sims["cart_pole"]
    K = _cart_pole_gain(sim_c)
    x0 = np.array([0.0, 0.3, 0.0, 0.0])
    if kind == "callable":
        kw = dict(r=lambda t, x: -K @ x, input_period=0.02)
    else:
        tt = np.linspace(0.0, 2.0, 9)
        kw = dict(r=(tt, np.sin(3 * tt)[:, None]), input_hold=kind.split("_")[1])
    (t_c, X_c, R_c, st_c), (t_e, X_e, R_e, st_e) = _parts(_both(
        sims, "cart_pole", x0, 2.0, 0.01, method=method, rtol=1e-10, atol=1e-10, **kw),
        "t", "x", "r", "stats")
    d, dr = _dmax(X_e, X_c), _dmax(R_e, R_c)
    print(f"\ncart_pole {method} {kind}: max|dX| = {d:.2e}, max|dF| = {dr:.2e}, {st_c}")
    assert np.array_equal(t_c, t_e)
    assert st_c == st_e
    assert _same(X_e, X_c) and _same(R_e, R_c), (d, dr)


# ------------------------------------------------------------------ RODAS4
def test_rodas4_stiff(sims):
    x0 = np.array([1.0, 0.0, 0.0, 0.0])
    (t_c, X_c, st_c), (t_e, X_e, st_e) = _parts(_both(
        sims, "stiff", x0, 2.0, 0.01, method="rodas4", rtol=1e-6, atol=1e-6,
        max_steps=10 ** 6), "t", "x", "stats")
    d = _dmax(X_e, X_c)
    print(f"\nstiff rodas4: max|dX| = {d:.2e}, {st_c}")
    assert len(t_c) == 201 and np.array_equal(t_c, t_e)
    _same_counts(st_c, st_e)
    assert st_c["n_jac"] == st_c["n_accepted"]     # one Jacobian per step, kept on rejection
    # fewer steps than DOPRI5 needs on this stiff model
    st_d = sims["stiff"][1].simulate(x0, 2.0, 0.01, method="dopri5", rtol=1e-6,
                                     atol=1e-6, max_steps=10 ** 7).stats
    assert st_c["n_accepted"] < st_d["n_accepted"]
    assert _same(X_e, X_c), d


def _advance(sim, x, t0, t1, method, h_next=0.0, rtol=1e-8, atol=1e-8):
    """The C API's advance (accumulating stats) through cffi."""
    opts = sim._new("sim_options")
    sim._fn("sim_options_default")(opts)
    opts.method = gen.codegen.abi.METHODS[method]
    opts.rtol, opts.atol = rtol, atol
    stats = sim._new("sim_stats")
    stats.h_next = h_next
    x = np.array(x, dtype=float)
    p = sim._params(None)
    st = sim._fn("advance")(t0, t1, sim._ffi.NULL, sim._ptr(p), opts, stats, sim._ptr(x))
    assert st == 0, sim._ffi.string(sim._fn("status_message")(st))
    return x, {k: getattr(stats, k) for k in ("n_accepted", "n_rejected", "n_rhs", "n_jac",
                                              "t_last", "h_next")}


ADVANCE_X0 = {"stiff": np.array([1.0, 0.0, 0.0, 0.0]),
              "kane": pendulum_state(1.0, 0.5, 1.0, "kane"),
              "lagrange": pendulum_state(1.0, 0.5, 1.0, "lagrange")}


@pytest.mark.parametrize("method, key", [("rodas4", "stiff"), ("dopri5", "stiff"),
                                         ("rodas4", "kane"), ("rk4", "lagrange")])
def test_advance(sims, method, key):
    """advance in pieces, h_next carried from one call to the next (RK4: one
    step per call, projected)."""
    n, span = (40, 0.005) if method == "rk4" else (4, 0.05)
    out = {}
    for tag, sim in zip(("c", "e"), sims[key]):
        x, h, total = ADVANCE_X0[key], 0.0, {}
        for k in range(n):
            x, st = _advance(sim, x, span * k, span * (k + 1), method, h_next=h)
            h = st["h_next"]
            for name in ("n_accepted", "n_rejected", "n_rhs", "n_jac"):
                total[name] = total.get(name, 0) + st[name]
        out[tag] = (x, total, h)
    d = _dmax(out["e"][0], out["c"][0])
    print(f"\nadvance {method} {key}: max|dx| = {d:.2e}, {out['c'][1]}")
    assert out["e"][1] == out["c"][1]
    assert (out["c"][1]["n_jac"] > 0) == (method == "rodas4")
    assert out["e"][2] == out["c"][2]              # h_next
    assert _same(out["e"][0], out["c"][0]), d


# ------------------------------------------------------------------ events
def _events_run(sim, terminal, method="dopri5"):
    x0 = pendulum_state(np.pi / 3, 0.0, 1.0, "kane")     # released at 60 degrees
    return sim.simulate(x0, 2.0, 0.01, method=method, rtol=1e-12, atol=1e-12,
                        events={"q2": 0}, terminal=terminal)


@pytest.mark.parametrize("method", ["dopri5", "rodas4", "rk4"])
def test_events(sims, method):
    """Both crossings of q2 = 0 in 2 s, located on the dense output."""
    (t_c, X_c, ev_c, st_c), (t_e, X_e, ev_e, st_e) = _parts(
        [_events_run(s, False, method) for s in sims["kane"]], "t", "x", "events", "stats")
    print(f"\nevents {method}: C {[(n, t) for n, t, _ in ev_c]}, stats {st_c}")
    assert np.array_equal(t_c, t_e) and len(t_c) == 201
    _same_counts(st_c, st_e, ("n_accepted", "n_rejected", "n_rhs", "n_jac", "n_out",
                              "n_events"))
    assert st_c["terminal"] is None and st_e["terminal"] is None
    assert st_c["n_events"] == len(ev_c) == len(ev_e) >= 2
    dt = max(abs(a[1] - b[1]) for a, b in zip(ev_c, ev_e))
    dx = max(_dmax(a[2], b[2]) for a, b in zip(ev_c, ev_e))
    assert [a[0] for a in ev_c] == [b[0] for b in ev_e] == ["q2"] * len(ev_c)
    assert dt == 0 and all(_same(a[2], b[2]) for a, b in zip(ev_c, ev_e)), (dt, dx)
    assert _same(X_e, X_c)
    for _, _, xe in ev_e:
        assert abs(xe[0]) < (1e-12 if method != "rk4" else 1e-4)


def test_events_terminal(sims):
    """terminal=True: the run ends at the first crossing, its state the last row."""
    (t_c, X_c, ev_c, st_c), (t_e, X_e, ev_e, st_e) = _parts(
        [_events_run(s, True) for s in sims["kane"]], "t", "x", "events", "stats")
    print(f"\nterminal: t_event C {ev_c[0][1]!r}, Eigen {ev_e[0][1]!r}; stats {st_c}")
    assert st_c == st_e       # n_rhs, n_jac, n_events, terminal, ...
    assert st_e["terminal"] == "q2" and st_e["n_events"] == 1
    assert len(t_e) == len(t_c) < 201
    assert t_e[-1] == ev_e[0][1] and np.array_equal(X_e[-1], ev_e[0][2])
    assert _same(t_e, t_c) and _same(X_e, X_c)
    assert np.array_equal(t_e[:-1], t_c[:-1]) and t_e[-2] < t_e[-1]
    assert abs(X_e[-1][0]) < 1e-12


# --------------------------------------------------------- bounded output
@pytest.mark.parametrize("method", ["dopri5", "rk4", "rodas4"])
def test_every_and_final_only(sims, method):
    """every=k and final_only keep rows of the same run (the integration is
    the same), equal between the backends."""
    x0 = pendulum_state(0.9, 0.4, 1.0, "lagrange")
    kw = dict(method=method, rtol=1e-9, atol=1e-9)
    full = sims["lagrange"][0].simulate(x0, 1.0, 0.01, **kw)
    full_c = (full.t, full.x, full.stats)
    for extra in (dict(every=7), dict(final_only=True)):
        (t_c, X_c, st_c), (t_e, X_e, st_e) = _parts(_both(sims, "lagrange", x0, 1.0, 0.01,
                                                          **kw, **extra), "t", "x", "stats")
        _same_counts(st_c, st_e)
        assert np.array_equal(t_c, t_e)
        if "every" in extra:
            idx = sorted(set(range(0, 101, 7)) | {100})
        else:
            idx = [100]
        assert np.array_equal(t_c, full_c[0][idx]) and np.array_equal(X_c, full_c[1][idx])
        assert st_c["n_rhs"] == full_c[2]["n_rhs"] and st_c["n_out"] == len(idx)
        assert _same(X_e, X_c)
