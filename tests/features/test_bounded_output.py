"""Issue 16 (bounded output): simulate(every=k) keeps every k-th output row
and the last, final_only=True only the row at t_end, max_rows refuses a
run that would return more. The rows are dropped in C (the integration is
unchanged), so they are exactly the corresponding rows of the full output:
checked bit for bit against the full run, with and without inputs, RK4 and
DOPRI5, C and Eigen, and the binary's --every / --final-only."""
import numpy as np
import pytest

import cart_pole as cp
import gen
import seed_pendulum as sp


@pytest.fixture(scope="module")
def sims():
    return {"cart_pole": gen.compile(cp.model()), "seed_kane": gen.compile(sp.kane_model())}


def _x0(sim):
    if sim.mc:
        return sim.consistent_state(np.array([0.5, 0.8, 0.0, 0.0]))
    return np.array([0.0, 0.3, 0.0, 0.0])


def _arrays(sol):
    """Every per-row array of a gen.Solution: t, x, lam, r and the outputs."""
    return [sol.t, sol.x, sol.lam, sol.r] + [sol.outputs[k] for k in sorted(sol.outputs)]


def _check(sim, method, every):
    kw = dict(method=method)
    if sim.nr:
        kw["r"] = lambda t, x: [np.sin(3 * t)]
    full = _arrays(sim.simulate(_x0(sim), 1.0, 0.03, **kw))
    n = len(full[0])
    part = _arrays(sim.simulate(_x0(sim), 1.0, 0.03, every=every, **kw))
    idx = sorted(set(range(0, n, every)) | {n - 1})
    assert len(part[0]) == len(idx) and len(part) == len(full) == 4 + sim.ny
    for a, b in zip(full, part):
        assert np.array_equal(a[idx], b)
    last = _arrays(sim.simulate(_x0(sim), 1.0, 0.03, final_only=True, **kw))
    assert len(last[0]) == 1 and last[0][0] == 1.0
    for a, b in zip(full, last):
        assert np.array_equal(a[[n - 1]], b)


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
@pytest.mark.parametrize("key", ["cart_pole", "seed_kane"])
def test_rows_are_those_of_the_full_output(sims, key, method):
    _check(sims[key], method, 4)
    _check(sims[key], method, 7)      # 35 rows: the last is not a multiple


def test_max_rows_and_bad_every(sims):
    sim = sims["cart_pole"]
    with pytest.raises(ValueError, match=r"would keep 1,001 rows .* more than max_rows=100"):
        sim.simulate(np.zeros(4), 1.0, 1e-3, max_rows=100)
    t, X = sim.simulate(np.zeros(4), 1.0, 1e-3, every=100, max_rows=11)
    assert len(t) == 11 and t[-1] == 1.0
    with pytest.raises(ValueError, match="every must be an integer >= 1"):
        sim.simulate(np.zeros(4), 1.0, 1e-3, every=0)


def test_batch_final_only(sims):
    sim = sims["cart_pole"]
    X0 = np.array([[0.0, 0.1, 0, 0], [0.0, -0.2, 0, 0], [0.1, 0.0, 0, 0]])
    res = sim.ensemble(X0, 1.0, 1e-3, final_only=True, r=[0.5])
    assert res.final.shape == (3, 4)
    for i in range(3):
        _, Xf = sim.simulate(X0[i], 1.0, 1e-3, r=[0.5])
        assert np.array_equal(res.final[i], Xf[-1])


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend(sims):
    from conftest import require_eigen
    require_eigen()
    e = gen.compile(cp.model(), backend="eigen")
    for method in ("rk4", "dopri5"):
        _check(e, method, 4)
        a = sims["cart_pole"].simulate(np.array([0, 0.3, 0, 0.]), 1.0, 0.03, method=method,
                                       every=4)
        b = e.simulate(np.array([0, 0.3, 0, 0.]), 1.0, 0.03, method=method, every=4)
        assert np.max(np.abs(a[1] - b[1])) < 1e-12


@pytest.mark.slow
def test_binary_every_and_final_only(sims, tmp_path):
    import subprocess
    from test_closed_loop import _build_binary, _csv
    sim = sims["cart_pole"]
    exe = _build_binary(cp.model(), tmp_path)
    base = [str(exe), "--t-end", "1", "--dt", "0.01", "--x0", "theta=0.3"]
    _, full = _csv(subprocess.run(base, capture_output=True, text=True, check=True).stdout)
    _, ev = _csv(subprocess.run(base + ["--every", "7"], capture_output=True, text=True,
                                check=True).stdout)
    _, fo = _csv(subprocess.run(base + ["--final-only"], capture_output=True, text=True,
                                check=True).stdout)
    n = len(full)
    idx = sorted(set(range(0, n, 7)) | {n - 1})
    assert np.array_equal(ev, full[idx]) and np.array_equal(fo, full[[n - 1]])
    t, X = sim.simulate(np.array([0, 0.3, 0, 0.]), 1.0, 0.01, every=7)
    assert np.max(np.abs(ev[:, 1:5] - X)) < 1e-12
    bad = subprocess.run(base + ["--every", "0"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--every needs a positive integer" in bad.stderr
