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
