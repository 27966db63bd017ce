"""Ensembles (gen/sim/ensemble.py, csrc/host/gen_host_ensemble.c): many runs in
C, reduced as they finish.

Every number is checked against an independent computation: each run
against sim.simulate of the same x0, p, r (bit for bit: the same C path),
each reducer against numpy over that run's full trajectory, failures
against the status a single simulate gives, and a Dask LocalCluster (two
worker processes, an empty cache of their own) against the local run.
"""
import os
import subprocess
import sys

import numpy as np
import pytest

import gen
from helpers import pendulum_state

import cart_pole


@pytest.fixture(scope="module")
def cart_sim():
    return gen.compile(cart_pole.model())


def _thetas(n, seed=0):
    return np.random.default_rng(seed).uniform(-1.2, 1.2, n)


def test_runs_equal_simulate_bit_for_bit(kane_sim):
    rng = np.random.default_rng(1)
    th = _thetas(300)
    X0 = np.array([pendulum_state(a, rng.uniform(-1, 1), 1.0, "kane") for a in th])
    P = np.tile(kane_sim.constants, (300, 1))
    P[:, 0] = rng.uniform(0.8, 1.2, 300)                     # L per run
    X0[:, :2] *= P[:, :1]                                     # consistent with L
    X0[:, 2:] *= P[:, :1]
    res = kane_sim.ensemble(X0, 2.0, 1e-3, p=P, chunk=37)
    assert res.final.shape == (300, 4) and not res.failures
    for i in rng.choice(300, 6, replace=False):
        _, X = kane_sim.simulate(X0[i], 2.0, 1e-3, p=P[i])
        assert np.array_equal(res.final[i], X[-1]), i
    # adaptive method, DOPRI5
    res = kane_sim.ensemble(X0[:40], 2.0, 0.01, p=P[:40], method="dopri5", rtol=1e-10,
                            atol=1e-12)
    for i in (0, 13, 39):
        _, X = kane_sim.simulate(X0[i], 2.0, 0.01, p=P[i], method="dopri5", rtol=1e-10,
                                 atol=1e-12)
        assert np.array_equal(res.final[i], X[-1])


def test_chunks_and_threads_do_not_change_a_number(kane_sim):
    X0 = np.array([pendulum_state(a, 0.0, 1.0, "kane") for a in _thetas(64, 2)])
    a = kane_sim.ensemble(X0, 1.0, 1e-3, workers=1, chunk=64)
    b = kane_sim.ensemble(X0, 1.0, 1e-3, workers=2, chunk=5)
    assert np.array_equal(a.final, b.final) and a.chunks == 1 and b.chunks == 13


def test_reducers_against_numpy_on_the_full_run(cart_sim):
    rng = np.random.default_rng(3)
    X0 = np.zeros((20, 4))
    X0[:, 1] = rng.uniform(-0.3, 0.3, 20)
    R = rng.uniform(-1, 1, (20, 1))
    reduce = {"final": "final",
              "at": gen.At([0.5, 1.0, 2.0], ["theta", "tip_y"]),
              "peak": gen.Max(["x", "tip_x"]), "low": gen.Min("tip_y"),
              "mean": gen.Mean(["theta"]),
              "user": lambda t, X: np.abs(X[:, :, 0]).max(axis=1)}
    res = cart_sim.ensemble(X0, 2.0, 0.01, r=R, reduce=reduce, chunk=6)
    names = cart_sim.state_names
    assert names[:2] == ["x", "theta"] and cart_sim.output_names == ["tip_x", "tip_y"]
    for i in (0, 7, 19):
        sol = cart_sim.simulate(X0[i], 2.0, 0.01, r=R[i])
        t, X = sol
        Y = np.column_stack([sol.outputs[k] for k in cart_sim.output_names])
        assert np.array_equal(res["final"][i], X[-1])
        rows = [50, 100, 200]
        np.testing.assert_array_equal(res["at"][i], np.column_stack([X[rows, 1], Y[rows, 1]]))
        np.testing.assert_array_equal(res["peak"][i], [X[:, 0].max(), Y[:, 0].max()])
        np.testing.assert_array_equal(res["low"][i], [Y[:, 1].min()])
        assert abs(res["mean"][i][0] - X[:, 1].mean()) <= 1e-14 * max(1, abs(X[:, 1]).max())
        assert res["user"][i] == np.abs(X[:, 0]).max()
    np.testing.assert_array_equal(res.t, t)


def test_failed_runs_are_listed_and_the_others_exact(kane_sim):
    """1% of the runs start at the Kane partition's singular configuration
    (q1 = 0: the pendulum horizontal, where q1 cannot follow from q2)."""
    n = 400
    X0 = np.array([pendulum_state(a, 0.0, 1.0, "kane") for a in _thetas(n, 4)])
    bad = np.arange(0, n, 100) + 7
    X0[bad] = [1.0, 0.0, 0.0, 0.0]                  # q2 = L, q1 = 0
    res = kane_sim.ensemble(X0, 1.0, 1e-3, chunk=50)
    fails = res.failures
    assert [f[0] for f in fails] == list(bad)
    for i, name, t, x in fails:
        with pytest.raises(gen.SolverError) as e:
            kane_sim.simulate(X0[i], 1.0, 1e-3)
        assert name == e.value.status_name and np.isnan(res.final[i]).all()
        assert t == 0.0 and np.array_equal(x, X0[i])
    ok = np.setdiff1d(np.arange(n), bad)
    assert res.ok.sum() == n - len(bad) and np.isfinite(res.final[ok]).all()
    for i in ok[::97]:
        _, X = kane_sim.simulate(X0[i], 1.0, 1e-3)
        assert np.array_equal(res.final[i], X[-1])


def test_named_values_sampler_and_consistent_states(kane_sim):
    s = gen.Sampler(seed=5)
    d = s.draw(50, q2=("normal", 0.0, 0.3), L=("uniform", 0.8, 1.2))
    assert gen.Sampler(seed=5).draw(50, q2=("normal", 0.0, 0.3), L=("uniform", 0.8, 1.2))["L"] \
        .tolist() == d["L"].tolist()
    res = kane_sim.ensemble({"q2": d["q2"], "q1": 1.0}, 1.0, 1e-3, p={"L": d["L"]},
                            consistent=True)
    for i in (0, 49):
        p = kane_sim.constants.copy()
        p[0] = d["L"][i]
        x = kane_sim.consistent_state([d["q2"][i], 1.0, 0, 0], p=p)
        _, X = kane_sim.simulate(x, 1.0, 1e-3, p=p)
        assert np.array_equal(res.final[i], X[-1])
    g = gen.Sampler.grid(a=[1, 2, 3], b=[10, 20])
    assert g["a"].tolist() == [1, 1, 2, 2, 3, 3] and g["b"].tolist() == [10, 20] * 3
    assert gen.Sampler.parse("uniform:0.8:1.2") == ("uniform", 0.8, 1.2)
    assert gen.Sampler.parse("0.25") == 0.25
    with pytest.raises(ValueError, match="normal:MEAN:STD"):
        gen.Sampler.parse("gauss:0:1")


def test_a_linear_feedback_ensemble_is_its_closed_loop(cart_sim):
    A, B = cart_sim.linearize(np.zeros(4))
    K = cart_pole.lqr(A, B, np.diag([10, 100, 1, 1]), np.eye(1))
    ctl = gen.LinearFeedback(K)
    X0 = np.zeros((12, 4))
    X0[:, 1] = np.linspace(-0.3, 0.3, 12)
    res = cart_sim.ensemble(X0, 3.0, 1e-3, controller=ctl,
                            reduce={"final": "final", "peak": gen.Max(["theta"])})
    for i in (0, 5, 11):
        _, X = cart_sim.simulate(X0[i], 3.0, 1e-3, controller=ctl)
        assert np.array_equal(res["final"][i], X[-1])
        assert res["peak"][i][0] == X[:, 1].max()
    assert np.max(np.abs(res["final"][:, 1])) < 0.05          # the loop stabilizes


def test_bad_arguments_name_the_problem(kane_sim):
    x0 = pendulum_state(0.3, 0, 1.0, "kane")
    with pytest.raises(ValueError, match="not a Python function"):
        kane_sim.ensemble(x0, 1.0, 1e-3, r=lambda t, x: [0.0])
    with pytest.raises(ValueError, match="different numbers of runs"):
        kane_sim.ensemble(np.tile(x0, (3, 1)), 1.0, 1e-3, p=np.tile(kane_sim.constants, (4, 1)))
    with pytest.raises(ValueError, match="unknown name 'Lx'"):
        kane_sim.ensemble(x0, 1.0, 1e-3, p={"Lx": [1.0]})
    with pytest.raises(ValueError, match="unknown quantity 'zz'"):
        kane_sim.ensemble(x0, 1.0, 1e-3, reduce=gen.Max(["zz"]))
    with pytest.raises(gen.InputError, match=r"x0\[1, 0\] = nan \(run 1, q2\)"):
        kane_sim.ensemble(np.array([x0, x0 * np.nan]), 1.0, 1e-3)


def test_host_hand_written_sources_compile_strict(tmp_path):
    """The hand-written host parts, with the host's declarations, under the
    project's strict flags (the host module itself is compiled by cffi):
    the plain-C ensemble loop with -pedantic; the fast path of
    Simulator.rhs with Python's and numpy's headers, whose own macros are
    not -pedantic clean, with the rest."""
    import sysconfig
    cdef, source = gen.toolchain.host.host_sources("double", python=False)
    assert "eomgen_fast_rhs" not in source
    src = tmp_path / "host.c"
    src.write_text(source)
    strict = ["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror"]
    r = subprocess.run(strict + ["-pedantic", "-c", str(src), "-o", os.devnull],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    cdef, source = gen.toolchain.host.host_sources("double")
    assert "eomgen_fast_rhs_new" in cdef
    src.write_text("#define _CFFI_NO_LIMITED_API\n#include <Python.h>\n" + source)
    r = subprocess.run(strict + ["-I" + np.get_include(), "-I" + sysconfig.get_paths()["include"],
                                 "-c", str(src), "-o", os.devnull], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def _dask():
    try:
        import distributed  # noqa: F401
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("dask.distributed is required under CI=true (pip install eomgen[dask])")
        pytest.skip("dask.distributed is not installed (pip install eomgen[dask])")


@pytest.mark.slow
def test_dask_local_cluster_bit_identical_and_builds_by_content(kane_sim, lagrange_sim, tmp_path):
    """Two worker processes whose eomgen cache starts empty: they build the
    model from the shipped sources, and give the local run's numbers; again
    on the same client, for the same model and for another one (each
    model's sources reach the workers under a key of their own)."""
    _dask()
    from distributed import Client, LocalCluster
    X0 = np.array([pendulum_state(a, 0.1, 1.0, "kane") for a in _thetas(200, 6)])
    P = np.tile(kane_sim.constants, (200, 1))
    P[:, 0] = np.linspace(0.8, 1.2, 200)
    X0[:, :2] *= P[:, :1]
    X0[:, 2:] *= P[:, :1]
    reduce = {"final": "final", "peak": gen.Max(["u2"])}
    local = kane_sim.ensemble(X0, 1.0, 1e-3, p=P, reduce=reduce, chunk=25)
    worker_cache = tmp_path / "worker-cache"
    env = {"EOMGEN_CACHE": str(worker_cache)}
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      env=env) as cluster, Client(cluster) as client:
        remote = kane_sim.ensemble(X0, 1.0, 1e-3, p=P, reduce=reduce, chunk=25, client=client)
        again = kane_sim.ensemble(X0[:50], 1.0, 1e-3, p=P[:50], chunk=10, client=client)
        XL = np.array([pendulum_state(a, 0.1, 1.0, "lagrange") for a in _thetas(40, 7)])
        other = lagrange_sim.ensemble(XL, 1.0, 1e-3, chunk=10, client=client)
        info = client.run(lambda: os.environ.get("EOMGEN_CACHE"))
    assert np.array_equal(again.final, local["final"][:50])
    assert np.array_equal(other.final, lagrange_sim.ensemble(XL, 1.0, 1e-3, chunk=10).final)
    assert set(info.values()) == {str(worker_cache)}
    assert np.array_equal(remote["final"], local["final"])
    assert np.array_equal(remote["peak"], local["peak"])
    built = [d.name for d in worker_cache.iterdir() if d.name.startswith("_eomgen_pendulum_kane")]
    assert built, list(worker_cache.iterdir())                 # built there, by content


@pytest.mark.slow
def test_command_line_ensemble_npz_and_parquet(kane_sim, tmp_path):
    """eomgen ensemble: the samples it draws (Sampler, seed, in the order of
    the options), the runs it makes from them (dependent states solved), the
    results it writes, against the Python API."""
    from test_cli import SEED, eomgen
    out = tmp_path / "res.npz"
    p = eomgen("ensemble", SEED, "--samples", "60", "--param", "L=uniform:0.8:1.2",
               "--x0", "q2=normal:0:0.2", "--x0", "q1=1.0", "--t-end", "0.5", "--dt", "1e-3",
               "--reduce", "final", "--reduce", "max:u2", "--seed", "3", "-o", str(out),
               "--quiet", check_rc=0)
    assert "60 runs, 0 failed" in p.stdout
    d = np.load(out)
    s = gen.Sampler(3)
    x0 = s.draw(60, q2=("normal", 0.0, 0.2), q1=1.0)
    pl = s.draw(60, L=("uniform", 0.8, 1.2))
    np.testing.assert_array_equal(d["x0.q2"], x0["q2"])
    np.testing.assert_array_equal(d["param.L"], pl["L"])
    ref = kane_sim.ensemble(x0, 0.5, 1e-3, p=pl, consistent=True,
                            reduce={"final": "final", "max": gen.Max(["u2"])})
    np.testing.assert_array_equal(d["final"], ref["final"])
    np.testing.assert_array_equal(d["max"], ref["max"])
    assert not d["status"].any()
    pq = tmp_path / "res.parquet"
    eomgen("ensemble", SEED, "--samples", "10", "--param", "L=uniform:0.8:1.2", "--t-end", "0.1",
           "--x0", "q2=0.3", "--x0", "q1=0.9", "-o", str(pq), "--quiet", check_rc=0)
    import pandas as pd
    df = pd.read_parquet(pq)
    assert len(df) == 10 and {"param.L", "status", "final.0", "final.3"} <= set(df.columns)
    bad = eomgen("ensemble", SEED, "--samples", "5", "--param", "L=gauss:1:2", "--t-end", "1",
                 "-o", str(tmp_path / "x.npz"), check_rc=2)
    assert "normal:MEAN:STD" in bad.stderr


def test_reduce_final_holds_no_rows(kane_sim):
    """Issue 47: ensemble(reduce="final") allocated every output time of a
    run (1.6 GB at 10^8 rows) although it keeps only the final state. Its
    Python allocations (tracemalloc, numpy's included) are now at most
    2x those of one simulate(final_only=True) per worker, whatever the
    rows; the output times are made only when res.t is read."""
    import tracemalloc
    x0 = pendulum_state(0.3, 0.0, 1.0, "kane")
    X0 = np.tile(x0, (2, 1))
    dt, rows = 1e-3, 20001
    t_end = (rows - 1) * dt
    final = gen.RunOptions(final_only=True)

    def peak(f):
        f()                                       # first calls' imports and caches
        tracemalloc.start()
        try:
            out = f()
            return tracemalloc.get_traced_memory()[1], out
        finally:
            tracemalloc.stop()

    one, sol = peak(lambda: kane_sim.simulate(x0, t_end, dt, options=final))
    ens, res = peak(lambda: kane_sim.ensemble(X0, t_end, dt, reduce="final", workers=2))
    assert ens <= 2 * 2 * one < 8 * rows         # 2 workers; the times alone are 8 * rows
    np.testing.assert_array_equal(res.final[1], sol.x[-1])
    t = res.t
    assert t.shape == (rows,) and t[-1] == t_end and t[1] == dt
