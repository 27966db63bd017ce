"""Benchmark (issue 17, "scale beyond the chart"): the Whipple bicycle
(examples/bicycle.py) and the 3D chain of rigid rods on spherical joints
(examples/chain3d.py), each derived with sympy, generated, compiled and
checked against sympy, with the time of every step.

    python bench/bench_scale.py [--chain 12] [--json PATH]

For each model, in a fresh process with a cache that holds the installation
(host module, runtime objects, templates; built first, reported apart) and
no model:

- sympy: the KanesMethod and kanes_equations (the user's derivation);
- eomgen: Model.from_kanes, gen.compile (generation + compile: what a user
  waits for before the first simulation), the first linearize (the
  derivative kernels, generated and compiled on first use), then the cost
  of a call from Python (sim.rhs, sim.linearize; medians of repeats);
- the check: the compiled right-hand side against sympy's own equations
  (the KanesMethod's mass matrix and forcing lambdified, numpy's solve; the
  constrained bicycle through sympy's elimination), max relative error over
  random consistent states; and for the bicycle the weave and capsize speeds
  against Meijaard et al. 2007.

Nothing is asserted (tests/physics/test_bicycle.py and tests/physics/test_chain3d.py do
that); the numbers are printed and written to --json.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT))


def median_call(fn, reps=7, calls=200):
    out = []
    for _ in range(reps):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        out.append((time.perf_counter() - t0) / calls)
    return statistics.median(out)


def _rel(a, b):
    import numpy as np
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def run_bicycle():
    import numpy as np
    import sympy as sm
    import bicycle
    import gen
    res = {}
    tm = {}
    model = bicycle.model(timings=tm)
    res["sympy_derive"] = tm.get("KanesMethod.__init__", 0) + tm.get("kanes_equations", 0) \
        + tm.get("kinematics", 0)
    res["from_kanes"] = tm["Model.from_kanes"]
    t1 = time.perf_counter()
    st = {}
    sim = gen.compile(model, timings=st)
    res["compile"] = time.perf_counter() - t1
    res["stages"] = {k: v for k, v in st.items() if k != "cached"}
    res["generate_and_compile"] = res["from_kanes"] + res["compile"]
    x = bicycle.upright_state(sim, 5.0)
    t2 = time.perf_counter()
    sim.linearize(x)
    res["first_linearize"] = time.perf_counter() - t2
    res["linearize_call"] = median_call(lambda: sim.linearize(x), calls=500)
    res["rhs_call"] = median_call(lambda: sim.rhs(0.0, x), calls=5000)
    # sympy's own constrained equations (its symbolic elimination of the
    # dependent speeds): u' from KM.mass_matrix, KM.forcing, lambdified
    import math
    KM, s = bicycle.derive()
    q, u, T = list(KM.q), list(KM.u), list(s["T"])
    P = [s[k] for k in bicycle.MOORE_NAMES]
    vals = bicycle.benchmark_to_moore()
    fun = sm.lambdify([q, u, T, P], [KM.mass_matrix, KM.forcing], cse=True)
    names = list(sim.state_names)
    qi = [names.index(str(a.func)) for a in q]
    ui = [names.index(str(a.func)) for a in u]
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(5):
        xr = np.zeros(sim.nx)
        for nm in ("q1", "q2", "q3", "q4", "q6", "q7", "q8", "u4", "u7"):
            xr[names.index(nm)] = rng.uniform(-0.6, 0.6)
        xr[names.index("q5")] = math.pi / 10
        xr[names.index("u6")] = -rng.uniform(5, 25)
        xr = sim.consistent_state(xr)
        r = rng.uniform(-2, 2, 3)
        M, f = (np.asarray(m_, dtype=float) for m_ in
                fun(xr[qi], xr[ui], r, [vals[k] for k in bicycle.MOORE_NAMES]))
        worst = max(worst, _rel(sim.rhs(0.0, xr, r=r)[ui], np.linalg.solve(M, f.ravel())))
    res["rhs_vs_sympy"] = worst
    vw, vc = bicycle.critical_speeds(sim)
    res["weave"], res["capsize"] = vw, vc
    res["weave_rel_err"] = abs(vw - 4.29238253634111) / 4.29238253634111
    res["capsize_rel_err"] = abs(vc - 6.02426201538837) / 6.02426201538837
    return res


def run_chain(n):
    import numpy as np
    import sympy as sm
    import chain3d
    import gen
    res = {"n": n}
    t0 = time.perf_counter()
    KM, s = chain3d.derive(n)
    res["sympy_derive"] = time.perf_counter() - t0
    vals = chain3d.defaults(n)
    consts = [s["g"], *s["m"], *s["l"], *s["Ixx"], *s["Iyy"], *s["Izz"]]
    t1 = time.perf_counter()
    model = gen.Model.from_kanes(KM, constants={c: vals[str(c)] for c in consts},
                                 name=f"chain3d_{n}", energy=s["energy"])
    res["from_kanes"] = time.perf_counter() - t1
    t2 = time.perf_counter()
    st = {}
    sim = gen.compile(model, timings=st)
    res["compile"] = time.perf_counter() - t2
    res["stages"] = {k: v for k, v in st.items() if k != "cached"}
    res["generate_and_compile"] = res["from_kanes"] + res["compile"]
    x = np.zeros(sim.nx)
    t3 = time.perf_counter()
    sim.linearize(x)
    res["first_linearize"] = time.perf_counter() - t3
    res["linearize_call"] = median_call(lambda: sim.linearize(x), calls=50)
    res["rhs_call"] = median_call(lambda: sim.rhs(0.0, x), calls=2000)
    sub = {c: vals[str(c)] for c in consts}
    q, u = s["q"], s["u"]
    M = sm.lambdify([q], KM.mass_matrix.xreplace(sub), "numpy", cse=True)
    f = sm.lambdify([q, u], KM.forcing.xreplace(sub), "numpy", cse=True)
    kd = KM.kindiffdict()
    qdot = sm.lambdify([q, u], sm.Matrix([kd[v.diff()] for v in q]), "numpy", cse=True)
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(3):
        xr = np.concatenate([rng.uniform(-0.6, 0.6, 3 * n), rng.uniform(-1, 1, 3 * n)])
        qv, uv = xr[:3 * n], xr[3 * n:]
        ref = np.concatenate([np.asarray(qdot(qv, uv), float).ravel(),
                              np.linalg.solve(np.asarray(M(qv), float),
                                              np.asarray(f(qv, uv), float).ravel())])
        worst = max(worst, _rel(sim.rhs(0.0, xr), ref))
    res["rhs_vs_sympy"] = worst
    return res


def run_install():
    import gen
    import n_link_cart
    t0 = time.perf_counter()
    gen.compile(n_link_cart.model(1, name="install_probe"))
    return {"first": time.perf_counter() - t0}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chain", type=int, default=12, help="rods of the 3D chain (default 12)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--worker", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        what, out = args.worker
        res = (run_bicycle() if what == "bicycle" else run_install() if what == "install"
               else run_chain(int(what[len("chain"):])))
        Path(out).write_text(json.dumps(res))
        return
    tmp = Path(tempfile.mkdtemp(prefix="eomgen_scale_"))
    results = {}
    try:
        install = tmp / "install"

        def worker(what, cache):
            out = tmp / f"{what}.json"
            env = dict(os.environ, EOMGEN_CACHE=str(cache))
            subprocess.run([sys.executable, __file__, "--worker", what, str(out)], env=env,
                           check=True)
            return json.loads(out.read_text())

        results["installation"] = worker("install", install)
        print(f"installation (once): {results['installation']['first']:.2f} s", flush=True)
        for what in ("bicycle", f"chain{args.chain}"):
            cache = tmp / what
            shutil.copytree(install, cache)
            for d in cache.glob("_eomgen_*"):
                shutil.rmtree(d)
            r = results[what] = worker(what, cache)
            print(f"{what}: sympy {r['sympy_derive']:.2f} s; eomgen from_kanes "
                  f"{r['from_kanes']:.2f} s + compile {r['compile']:.2f} s = "
                  f"{r['generate_and_compile']:.2f} s ("
                  + ", ".join(f"{k} {v:.2f}" for k, v in r["stages"].items())
                  + f"); first linearize {r['first_linearize']:.2f} s; linearize "
                  f"{r['linearize_call'] * 1e6:.1f} us, rhs {r['rhs_call'] * 1e6:.2f} us a call; "
                  f"rhs vs sympy {r['rhs_vs_sympy']:.1e}"
                  + (f"; weave {r['weave']:.12f} ({r['weave_rel_err']:.1e}), capsize "
                     f"{r['capsize']:.12f} ({r['capsize_rel_err']:.1e})" if "weave" in r else ""),
                  flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
