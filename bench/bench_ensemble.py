"""Benchmark (issue 18): an ensemble of the seed pendulum, 10^5 runs of 5 s
at RK4 h = 1 ms (5000 steps each), final state only, on this machine.

    python bench/bench_ensemble.py [--n 100000] [--model kane|lagrange] [--json PATH]

Printed, all measured in this run (the peers on subsamples, scaled to runs/s):

1. runs/s of sim.ensemble on every core, and on one (the scaling 1 -> 2 cores);
2. runs/s of a Python loop over sim.simulate(..., final_only=True);
3. runs/s of sim.ensemble(reduce="rows") (every row kept: the
   pre-ensemble path) and its memory per run;
4. runs/s of SciPy's solve_ivp (RK45, rtol 1e-8, atol 1e-10) over sim.rhs;
5. peak RSS of ensembles of growing N in fresh processes (reduce="final"):
   the growth is the result (N x nx floats), not N x rows;
6. the same ensemble on a Dask LocalCluster with 2 worker processes (a
   subsample), runs/s and the check that its numbers equal the local run's.

The initial angles are uniform in [-1, 1] rad, the string lengths uniform in
[0.8, 1.2] m (per-run constants), from gen.Sampler(seed=0). Nothing is
asserted (tests/features/test_ensemble.py checks the numbers).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))

T_END, DT = 5.0, 1e-3


def setup(model, n, seed=0):
    import numpy as np
    import gen
    import seed_pendulum
    from helpers import pendulum_state
    m = seed_pendulum.kane_model() if model == "kane" else seed_pendulum.lagrange_model()
    sim = gen.compile(m)
    d = gen.Sampler(seed).draw(n, theta=("uniform", -1.0, 1.0), L=("uniform", 0.8, 1.2))
    X0 = np.array([pendulum_state(a, 0.0, 1.0, model) for a in d["theta"]]) * d["L"][:, None]
    P = np.tile(sim.constants, (n, 1))
    P[:, sim.constant_names.index("L")] = d["L"]
    return sim, X0, P


def rss_worker(model, n, save=None):
    """One fresh process: compile (cached), draw, run N on every core with
    reduce="final"; its peak RSS (kB) before and after, its runs/s; the
    final states saved to save (.npy) if given."""
    import numpy as np
    sim, X0, P = setup(model, n)
    base = peak_rss_kb()
    res = sim.ensemble(X0, T_END, DT, p=P, progress=False)
    peak = peak_rss_kb()
    if save:
        np.save(save, res.final)
    return {"n": n, "base_kb": base, "peak_kb": peak, "failed": len(res.failures),
            "seconds": res.seconds, "runs_per_s": res.runs_per_second, "chunks": res.chunks}


def peak_rss_kb():
    """This process's peak resident set (kB): VmHWM, the high-water mark of
    its own memory. (getrusage's ru_maxrss is not: on Linux it keeps the
    parent's resident size at the fork, so a child of a large parent
    reports the parent's.)"""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def kept_worker(model, what, n, rows):
    """Issue 47, memory by what is kept: one fresh process, warmed with a
    short run, then one simulate(final_only=True) of `rows` rows (what =
    "simulate") or one ensemble(reduce="final") of n such runs on every
    core ("ensemble"); its peak RSS growth (VmHWM) and the peak of its
    Python allocations (tracemalloc: numpy's arrays included)."""
    import tracemalloc
    import numpy as np
    import gen
    sim, X0, P = setup(model, n)
    t_end = (rows - 1) * DT
    final = gen.RunOptions(final_only=True)
    if what == "simulate":
        def run():
            return sim.simulate(X0[0], t_end, DT, p=P[0], options=final)
    else:
        def run():
            return sim.ensemble(X0, t_end, DT, p=P, reduce="final", progress=False)
    sim.simulate(X0[0], 10 * DT, DT, p=P[0], options=final)
    sim.ensemble(X0[:2], 10 * DT, DT, p=P[:2], reduce="final", progress=False)
    base = peak_rss_kb()
    tracemalloc.start()
    t0 = time.perf_counter()
    run()
    seconds = time.perf_counter() - t0
    traced = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return {"what": what, "n": n, "rows": rows, "rss_growth_kb": peak_rss_kb() - base,
            "peak_rss_kb": peak_rss_kb(),
            "traced_peak_bytes": traced, "seconds": seconds}


def kept(model, n, rows):
    """kept_worker's two cases in fresh processes, printed as a table row."""
    res = {}
    for what in ("simulate", "ensemble"):
        cmd = [sys.executable, __file__, "--kept-worker", model, what, str(n), str(rows)]
        p = subprocess.run(cmd, capture_output=True, text=True, check=True)
        res[what] = json.loads(p.stdout.strip().splitlines()[-1])
    s, e = res["simulate"], res["ensemble"]
    print(f"memory by what is kept, {rows} rows a run: simulate(final_only=True) 1 run: "
          f"+{s['rss_growth_kb']} kB RSS, {s['traced_peak_bytes']} B traced; "
          f"ensemble(reduce='final') {n} runs on {os.cpu_count()} cores: "
          f"+{e['rss_growth_kb']} kB RSS, {e['traced_peak_bytes']} B traced "
          f"({e['traced_peak_bytes'] / s['traced_peak_bytes'] / os.cpu_count():.2f}x per "
          f"worker), {e['seconds']:.0f} s", flush=True)
    return res


def fresh(model, n, save=None):
    """rss_worker in a fresh process."""
    cmd = [sys.executable, __file__, "--rss-worker", model, str(n)] + ([save] if save else [])
    p = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100000, help="runs of the ensemble (default 1e5)")
    ap.add_argument("--model", default="kane", choices=["kane", "lagrange"])
    ap.add_argument("--json", default=None)
    ap.add_argument("--rss-worker", nargs="+", help=argparse.SUPPRESS)
    ap.add_argument("--kept", nargs=2, type=int, metavar=("N", "ROWS"),
                    help="only the memory of ensemble(reduce='final') of N runs of ROWS rows "
                    "against one simulate(final_only=True) (issue 47: 1000 100000)")
    ap.add_argument("--kept-worker", nargs=4, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.kept_worker:
        w = args.kept_worker
        print(json.dumps(kept_worker(w[0], w[1], int(w[2]), int(w[3]))))
        return
    if args.kept:
        res = kept(args.model, *args.kept)
        if args.json:
            Path(args.json).write_text(json.dumps(res, indent=1))
        return
    if args.rss_worker:
        w = args.rss_worker
        print(json.dumps(rss_worker(w[0], int(w[1]), w[2] if len(w) > 2 else None)))
        return
    import numpy as np
    out = {"n": args.n, "model": args.model, "cores": os.cpu_count()}
    sim, X0, P = setup(args.model, args.n)
    print(f"# seed pendulum ({args.model}), {args.n} runs of {T_END} s at RK4 h = {DT} s, "
          f"final state; {os.cpu_count()} cores", flush=True)

    # 1. the ensemble, every core (in a fresh process: its peak RSS is
    # part 5's largest N), and one
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        big = fresh(args.model, args.n, save=os.path.join(tmp, "final.npy"))
        final = np.load(os.path.join(tmp, "final.npy"))
    out["ensemble"] = big
    print(f"ensemble, {os.cpu_count()} threads: {big['seconds']:.1f} s, "
          f"{big['runs_per_s']:.0f} runs/s ({big['failed']} failed)", flush=True)

    class res:                  # the big run's numbers, as the parts below read them
        runs_per_second = big["runs_per_s"]
    res.final = final
    k1 = min(args.n, 5000)
    one = sim.ensemble(X0[:k1], T_END, DT, p=P[:k1], workers=1, progress=False)
    out["ensemble_1"] = {"n": k1, "runs_per_s": one.runs_per_second}
    assert np.array_equal(one.final, res.final[:k1])
    print(f"ensemble, 1 thread ({k1} runs): {one.runs_per_second:.0f} runs/s; scaling 1 -> "
          f"{os.cpu_count()} cores: {res.runs_per_second / one.runs_per_second:.2f}x", flush=True)

    # 2. a Python loop over sim.simulate
    k = 300
    t0 = time.perf_counter()
    for i in range(k):
        _, X = sim.simulate(X0[i], T_END, DT, p=P[i], final_only=True)
    loop = k / (time.perf_counter() - t0)
    out["python_loop"] = {"n": k, "runs_per_s": loop}
    print(f"Python loop over sim.simulate(final_only=True) ({k} runs): {loop:.0f} runs/s", flush=True)

    # 3. every row kept: ensemble(reduce="rows") (what simulate_batch was)
    k = 1000
    t0 = time.perf_counter()
    Xs = sim.ensemble(X0[:k], T_END, DT, p=P[:k], reduce="rows").rows
    batch = k / (time.perf_counter() - t0)
    out["rows"] = {"n": k, "runs_per_s": batch, "bytes_per_run": Xs[0].nbytes,
                   "matches": bool(np.array_equal(Xs[:, -1], res.final[:k]))}
    print(f"ensemble(reduce='rows') ({k} runs, every row): {batch:.0f} runs/s, "
          f"{Xs[0].nbytes / 1e3:.0f} kB "
          f"a run ({Xs.nbytes / 1e6:.0f} MB for {k}; {Xs[0].nbytes * args.n / 1e9:.1f} GB for "
          f"{args.n})", flush=True)
    del Xs

    # 4. SciPy over sim.rhs
    from scipy.integrate import solve_ivp
    k = 10
    t0 = time.perf_counter()
    err = 0.0
    for i in range(k):
        sol = solve_ivp(lambda t, x, p=P[i]: sim.rhs(t, x, p=p), (0, T_END), X0[i],
                        method="RK45", rtol=1e-8, atol=1e-10)
        err = max(err, float(np.max(np.abs(sol.y[:, -1] - res.final[i]))))
    scipy_rate = k / (time.perf_counter() - t0)
    out["scipy"] = {"n": k, "runs_per_s": scipy_rate, "max_abs_diff_final": err}
    print(f"solve_ivp RK45 rtol 1e-8 over sim.rhs ({k} runs): {scipy_rate:.1f} runs/s "
          f"(final states differ from the ensemble's by {err:.1e}: the constraint drifts "
          "without projection)", flush=True)
    print(f"ensemble / Python loop {res.runs_per_second / loop:.1f}x, / every row kept "
          f"{res.runs_per_second / batch:.1f}x, / solve_ivp {res.runs_per_second / scipy_rate:.0f}x",
          flush=True)

    # 5. memory in fresh processes (the largest N: part 1's run)
    rows = []
    for n in sorted({min(args.n, v) for v in (1000, 10000)} | {args.n}):
        r = big if n == args.n else fresh(args.model, n)
        rows.append(r)
        print(f"peak RSS, N = {n}: {r['peak_kb'] / 1e3:.0f} MB (before the ensemble "
              f"{r['base_kb'] / 1e3:.0f} MB: +{(r['peak_kb'] - r['base_kb']) / 1e3:.1f} MB; "
              f"the result is {n * sim.nx * 8 / 1e6:.1f} MB)", flush=True)
    out["rss"] = rows

    # 6. Dask
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        print("Dask: not installed (pip install 'eomgen[dask]')")
    else:
        k = min(args.n, 20000)
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            warm = sim.ensemble(X0[:50], T_END, DT, p=P[:50], client=client)   # workers build
            d = sim.ensemble(X0[:k], T_END, DT, p=P[:k], client=client, progress=False)
        same = bool(np.array_equal(d.final, res.final[:k])) and bool(
            np.array_equal(warm.final, res.final[:50]))
        out["dask"] = {"n": k, "runs_per_s": d.runs_per_second, "bit_identical": same}
        print(f"Dask LocalCluster, 2 workers ({k} runs): {d.runs_per_second:.0f} runs/s, "
              f"bit-identical to the local run: {same}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
