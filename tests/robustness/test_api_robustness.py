"""Issue 8: property-based tests (hypothesis) of the compiled Python API,
and two processes building the same model into one cache at once."""
import multiprocessing
import os
import tempfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gen
import rolling_disc
import seed_pendulum as sp

FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64)
MODERATE = st.floats(min_value=-3, max_value=3, allow_nan=False)
OK_ERRORS = (ValueError, gen.SolverError)
SETTINGS = settings(max_examples=300, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module")
def disc():
    return gen.compile(rolling_disc.model())


@SETTINGS
@given(x=st.lists(FLOATS, min_size=4, max_size=4), t=FLOATS)
def test_rhs_finite_or_raises(kane_sim, x, t):
    """Any input: a finite result or a named error, never NaN silently."""
    x = np.array(x)
    try:
        dx = kane_sim.rhs(t, x)
    except OK_ERRORS:
        return
    assert np.all(np.isfinite(dx))
    assert np.all(np.isfinite(x)) and np.isfinite(t)   # non-finite input never "succeeds"


@SETTINGS
@given(x=st.lists(MODERATE, min_size=10, max_size=10), T=MODERATE)
def test_disc_linearize_and_projection_properties(disc, x, T):
    x = np.array(x)
    try:
        xc = disc.project(x)
    except OK_ERRORS:
        return
    # on the manifold after projection, and projecting again changes nothing
    assert np.max(np.abs(disc.velocity_constraints(xc[:5], xc[5:]))) < 1e-10 * (
        1 + np.max(np.abs(xc)))
    assert np.allclose(disc.project(xc), xc, rtol=0, atol=1e-12 * (1 + np.max(np.abs(xc))))
    try:
        A, B = disc.linearize(xc, r=[T])
    except OK_ERRORS:
        return
    assert np.all(np.isfinite(A)) and np.all(np.isfinite(B))
    # the kinematic rows of A: q' = u exactly
    assert np.array_equal(A[:3, 5:8], np.eye(3))


@SETTINGS
@given(x=st.lists(MODERATE, min_size=4, max_size=4), h=st.floats(-1, 1, allow_nan=False))
def test_step_unchanged_on_failure_and_on_manifold(kane_sim, x, h):
    x = np.array(x)
    before = x.copy()
    try:
        y = kane_sim.step(0.0, x, h, method="rk4")
    except OK_ERRORS:
        assert np.array_equal(x, before)
        return
    assert np.array_equal(x, before)                 # the input is never written
    assert abs(np.hypot(y[0], y[1]) - 1.0) < 1e-9    # projected onto the circle


def _build_in(cache, q):
    os.environ["EOMGEN_CACHE"] = cache
    try:
        sim = gen.compile(sp.kane_model(name="race"))
        x = np.array([0.3, np.sqrt(1 - 0.09), 0.0, 0.0])
        q.put(("ok", sim.build_info["module"], float(sim.rhs(0.0, x)[2])))
    except Exception as e:  # report, do not hang the parent
        q.put(("error", repr(e), 0.0))


@pytest.mark.slow
def test_two_processes_build_the_same_model_at_once():
    cache = tempfile.mkdtemp(prefix="eomgen-race-")
    ctx = multiprocessing.get_context("spawn")
    q = ctx.Queue()
    procs = [ctx.Process(target=_build_in, args=(cache, q)) for _ in range(2)]
    for p in procs:
        p.start()
    res = [q.get(timeout=300) for _ in procs]
    for p in procs:
        p.join(timeout=60)
    assert all(r[0] == "ok" for r in res), res
    assert res[0][1] == res[1][1]                    # the same module file
    assert res[0][2] == res[1][2]
    entries = [e for e in os.listdir(cache) if e.startswith("_eomgen_race_")]
    assert len(entries) == 1, entries                # one finished build, no debris
    assert not [e for e in os.listdir(cache) if e.startswith(".")]
