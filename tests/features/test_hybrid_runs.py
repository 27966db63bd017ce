"""Every run of a hybrid model is hybrid (issue 46): ensembles apply the
same impacts as simulate, bit for bit; the interpolant sol.sol(t) is
piecewise between the jumps; a run that starts inside a contact or a
reset's guard region is refused, naming the declaration and its value.

References: each run's own sim.simulate (the ensemble), the bouncing ball's
analytic velocities after its impacts (the geometric series of the
restitution), and the gap's value computed here from the start state.
"""
import numpy as np
import pytest

import gen
from helpers import load_test_file

G = 9.81
hybrid = load_test_file("features/test_hybrid.py")


@pytest.fixture(scope="module")
def ball():
    return gen.compile(hybrid._ball())


def _dask_client():
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        import os
        if os.environ.get("CI") == "true":
            pytest.fail("dask.distributed is required under CI=true (pip install eomgen[dask])")
        pytest.skip("dask.distributed is not installed (pip install eomgen[dask])")
    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    return cluster, Client(cluster)


@pytest.mark.slow
def test_ensemble_of_the_ball_is_each_runs_simulate_bit_for_bit(ball):
    """8 heights, every row of every run (a "rows" reducer) and the final
    state: each the run's own sim.simulate, on threads (2 workers, chunks of
    3) and on a Dask worker process."""
    heights = np.linspace(0.3, 2.0, 8)
    X0 = np.c_[heights, np.zeros(8)]
    kw = dict(method="dopri5", rtol=1e-10, atol=1e-12)
    res = ball.ensemble(X0, 3.0, 0.01, reduce={"final": "final", "rows": "rows"}, chunk=3,
                        workers=2, **kw)
    assert np.all(res.status == 0)
    for i, x0 in enumerate(X0):
        sol = ball.simulate(x0, 3.0, 0.01, **kw)
        assert len(sol.events) >= 3                     # it bounced
        assert res["rows"][i].tobytes() == sol.x.tobytes()
        assert res["final"][i].tobytes() == sol.x[-1].tobytes()
    # RK4 on the grid, through the same C loop: the same bits as simulate's
    rk = ball.ensemble(X0, 1.5, 0.005)
    for i, x0 in enumerate(X0):
        assert rk.final[i].tobytes() == ball.simulate(x0, 1.5, 0.005).x[-1].tobytes()
    cluster, client = _dask_client()
    with cluster, client:
        remote = ball.ensemble(X0, 3.0, 0.01, chunk=4, client=client, **kw)
    assert remote.final.tobytes() == res["final"].tobytes()



@pytest.mark.slow
def test_interpolant_is_piecewise_between_the_impacts(ball):
    """sol.sol(t) never interpolates across a jump: just after each of the
    first 10 impacts it gives the analytic rebound e^k sqrt(2 g h0) - g dt
    (before: v = -3.17 where the exact value is +3.53), just before it the
    analytic fall, at the impact's time the state after it; at rest (held)
    the ball stays on the floor between the rows."""
    h0, e = 1.0, 0.8
    sol = ball.simulate([h0, 0.0], 8.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12)
    impacts = [ev for ev in sol.events if ev.name == "ground"]
    v1 = np.sqrt(2 * G * h0)
    t_k = np.sqrt(2 * h0 / G) + np.concatenate([[0.0], np.cumsum(2 * v1 * e ** np.arange(1, 10)
                                                                  / G)])
    for k, ev in enumerate(impacts[:10]):
        v_before, v_after = v1 * e ** k, v1 * e ** (k + 1)
        assert abs(ev.t - t_k[k]) < 1e-11
        for dt in (1e-6, 1e-3, 4e-3):
            x = sol.sol(ev.t + dt)
            assert abs(x[1] - (v_after - G * dt)) < 1e-9, (k, dt, x)
            assert abs(x[0] - (v_after * dt - G * dt * dt / 2)) < 1e-9
            assert abs(sol.sol(ev.t - dt)[1] - (-v_before + G * dt)) < 1e-9
        np.testing.assert_array_equal(sol.sol(ev.t), ev.x_after)
    names = [ev.name for ev in sol.events]
    assert names[-1] == "ground.hold" and names.count("ground") == len(names) - 1
    rest = sol.events[-1].t
    ts = np.linspace(rest + 0.001, 8.0, 777)
    assert np.abs(sol.sol(ts)).max() < 1e-12        # held on the floor, not falling


# --------------------------------------------------------- penetrated starts
PENETRATED = ("hyb_ball_simulate_events: the run starts inside the contact of impact 'ground': "
              "its gap is -0.5 at t = 0, below zero, the side its impact closes onto (the "
              "motion would run through it); start with the gap on its open side, or at zero "
              "[ERR_PENETRATED], state: y=-0.5, v=0")


@pytest.mark.slow
def test_penetrated_start_is_refused_in_python_and_an_ensemble(ball):
    """The hybrid guide's ball from y = -0.5 (it used to fall to y = -5.4 with
    status 0): refused, naming the impact and its gap, whatever the method;
    in an ensemble that run fails with ERR_PENETRATED and the others run."""
    for method in ("rk4", "dopri5", "rodas4"):
        with pytest.raises(gen.InputError) as err:
            ball.simulate([-0.5, 0.0], 1.0, 0.01, method=method)
        assert str(err.value) == PENETRATED
        assert err.value.argument == "x0" and err.value.value == -0.5
    np.testing.assert_array_equal(ball.hybrid_values(0.0, [-0.5, 0.0]), [-0.5])
    res = ball.ensemble(np.array([[1.0, 0.0], [-0.5, 0.0]]), 1.0, 0.01)
    assert res.failures[0][:2] == (1, "ERR_PENETRATED") and res.status[0] == 0
    # on the surface: at rest it is held from t0 (it used to fall through),
    # moving down it bounces at t0 with v = +e |v|
    sol = ball.simulate([0.0, 0.0], 1.0, 0.1, method="dopri5")
    assert [e.name for e in sol.events] == ["ground", "ground.hold"]
    assert np.all(sol.x == 0.0)
    sol = ball.simulate([0.0, -2.0], 0.3, 0.1, method="dopri5", rtol=1e-12, atol=1e-12)
    assert sol.events[0].t == 0.0 and sol.x[0, 1] == pytest.approx(1.6, abs=1e-15)
    assert sol.x[1, 0] == pytest.approx(1.6 * 0.1 - G / 2 * 0.01, abs=1e-12)


@pytest.mark.slow
def test_penetrated_start_in_the_binary_and_the_fmu(tmp_path):
    """The same refusal in the standalone binary (exit status 1, the message
    on stderr) and in the FMU (fmi2ExitInitializationMode: fmi2Error, the
    message through the logger)."""
    import subprocess
    from conftest import build_binary
    model = hybrid._ball(name="hyb_ball_pen")
    exe = build_binary(model, tmp_path / "bin")
    r = subprocess.run([str(exe), "--x0", "-0.5,0", "--t-end", "1", "--dt", "0.01"],
                       capture_output=True, text=True)
    assert r.returncode == 1
    assert ("hyb_ball_pen_sim: the run starts inside the contact of impact 'ground': its gap "
            "is -0.5 at t = 0, below zero, the side its impact closes onto (refused: "
            "ERR_PENETRATED)") in r.stderr
    fmpy = pytest.importorskip("fmpy", reason="FMPy (pip install eomgen[fmu])")
    path = tmp_path / "ball.fmu"
    gen.export_fmu(model, str(path), kind="me", fmi_version="2.0")
    logged = []
    with pytest.raises(Exception, match=r"fmi2ExitInitializationMode failed with status 3"):
        fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=1.0,
                          start_values={"y": -0.5}, logger=lambda *a: logged.append(a[-1]))
    assert logged[-1].decode() == (
        "ExitInitializationMode: the start is inside the contact of impact 'ground': its gap "
        "is -0.5 at t = 0, below zero, the side its impact closes onto (ERR_PENETRATED: the "
        "state would run through it)")
