"""gen.OptimalControl next to opty 1.5 on the same problems, in one run
(issue 34): the cart-pole swing-up (hanging to upright in 2 s, minimum
integral of F^2, |F| <= 20, |x| <= 1.5) by backward Euler and midpoint, as
opty transcribes them, N = 201 and 401.

    python bench/bench_ocp.py [--nodes 201 401] [--repeat 3] [--json out.json]

Per problem: build (eomgen: from the model to the loaded library, an empty
cache (EOMGEN_CACHE) each time; opty: Problem(...), which generates and
compiles its Cython), solve (IPOPT, tol 1e-8 both), iterations, the whole
wall time and the objectives (they must agree). eomgen with the exact
Hessian (its default) and with limited-memory (opty's only mode).
Medians of --repeat runs; ratios are eomgen / opty. Nothing is asserted.
"""
import argparse
import importlib.util
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import sympy as sm

ROOT = Path(__file__).resolve().parents[1]
PAR = {"mc": 1.0, "mp": 0.1, "l": 0.5, "g": 9.81}


def derive():
    spec = importlib.util.spec_from_file_location("cart_pole", ROOT / "examples" / "cart_pole.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.derive()


def ours(N, method, hessian):
    import gen
    km, s = derive()
    x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
    with tempfile.TemporaryDirectory() as d:
        os.environ["EOMGEN_CACHE"] = d
        try:
            t0 = time.perf_counter()
            model = gen.Model.from_kanes(km, constants={s[k]: val for k, val in PAR.items()},
                                         inputs=[F], name="cart_pole")
            ocp = gen.OptimalControl(model, N, 2.0, objective=F**2, method=method,
                                     bounds={F: (-20, 20), x: (-1.5, 1.5)},
                                     initial={x: 0, th: sm.pi, v: 0, om: 0},
                                     final={x: 0, th: 0, v: 0, om: 0})
            t1 = time.perf_counter()
            sol = ocp.solve(hessian=hessian, tol=1e-8)
            t2 = time.perf_counter()
        finally:
            del os.environ["EOMGEN_CACHE"]
    return dict(build=t1 - t0, solve=t2 - t1, total=t2 - t0, iterations=sol.iterations,
                objective=sol.objective, status=sol.status)


def opty(N, method):
    from opty.direct_collocation import Problem
    km, s = derive()
    x, th, v, om, F = (s[k] for k in ("x", "theta", "v", "omega", "F"))
    states = (x, th, v, om)
    T = 2.0
    h = T / (N - 1)
    meth = method.replace("-", " ")

    def obj(f):
        Fv = f[4 * N:5 * N]
        if meth == "backward euler":
            return h * np.sum(Fv[1:] ** 2)
        return h * np.sum(((Fv[:-1] + Fv[1:]) / 2) ** 2)

    def grad(f):
        g = np.zeros_like(f)
        Fv = f[4 * N:5 * N]
        if meth == "backward euler":
            g[4 * N + 1:5 * N] = 2 * h * Fv[1:]
        else:
            a = (Fv[:-1] + Fv[1:]) / 2
            g[4 * N:5 * N - 1] += h * a
            g[4 * N + 1:5 * N] += h * a
        return g
    inst = (x.func(0.0), th.func(0.0) - np.pi, v.func(0.0), om.func(0.0),
            x.func(T), th.func(T), v.func(T), om.func(T))
    t0 = time.perf_counter()
    eom = km.mass_matrix_full * sm.Matrix([q.diff() for q in states]) - km.forcing_full
    with tempfile.TemporaryDirectory() as d:
        prob = Problem(obj, grad, eom, states, N, h,
                       known_parameter_map={s[k]: val for k, val in PAR.items()},
                       instance_constraints=inst, bounds={F: (-20.0, 20.0), x: (-1.5, 1.5)},
                       integration_method=meth, tmp_dir=d)
        t1 = time.perf_counter()
        prob.add_option("print_level", 0)
        prob.add_option("tol", 1e-8)
        iters = [0]
        g0 = np.zeros(5 * N)
        g0[N:2 * N] = np.linspace(np.pi, 0, N)
        _, info = prob.solve(g0)
        t2 = time.perf_counter()
    return dict(build=t1 - t0, solve=t2 - t1, total=t2 - t0, iterations=iters[0] or None,
                objective=info["obj_val"], status=info["status"])


def median(runs):
    out = {}
    for k in runs[0]:
        vals = [r[k] for r in runs]
        out[k] = statistics.median(vals) if isinstance(vals[0], float) else vals[-1]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, nargs="+", default=[201, 401])
    ap.add_argument("--methods", nargs="+", default=["backward-euler", "midpoint"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--opty-repeat", type=int, default=1)
    ap.add_argument("--json")
    a = ap.parse_args(argv)
    rows = []
    for N in a.nodes:
        for method in a.methods:
            o = median([opty(N, method) for _ in range(a.opty_repeat)])
            e = median([ours(N, method, "exact") for _ in range(a.repeat)])
            lm = median([ours(N, method, "limited-memory") for _ in range(a.repeat)])
            rows.append(dict(N=N, method=method, opty=o, exact=e, lbfgs=lm))
            print(f"N={N} {method}: opty build {o['build']:.2f}s solve {o['solve']:.2f}s "
                  f"obj {o['objective']:.10g} | eomgen exact build {e['build']:.2f}s solve "
                  f"{e['solve']:.2f}s it {e['iterations']} obj {e['objective']:.10g} | "
                  f"limited-memory solve {lm['solve']:.2f}s it {lm['iterations']}", flush=True)
    print()
    print("| N | method | opty build | opty solve | opty total | eomgen build | solve exact (it) "
          "| solve L-BFGS (it) | total exact | build ratio | total ratio | objective rel. diff |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        o, e, lm = r["opty"], r["exact"], r["lbfgs"]
        print(f"| {r['N']} | {r['method']} | {o['build']:.2f} s | {o['solve']:.2f} s | "
              f"{o['total']:.2f} s | {e['build']:.2f} s | {e['solve']:.2f} s ({e['iterations']}) | "
              f"{lm['solve']:.2f} s ({lm['iterations']}) | {e['total']:.2f} s | "
              f"{e['build'] / o['build']:.3f}x | {e['total'] / o['total']:.3f}x | "
              f"{abs(e['objective'] - o['objective']) / abs(o['objective']):.1e} |")
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
