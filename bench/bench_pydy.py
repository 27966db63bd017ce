"""Benchmark (issue 33): PyDy's generate_ode_function with
``generator=gen.pydy.ODEFunctionGenerator`` against PyDy's own ``cython`` and
``lambdify`` generators, measured in the same run.

For pydy.models.n_link_pendulum_on_cart(n, cart_force=True,
joint_torques=True), n as given (default 1..5), the System's arguments (the
minimal form, as ``System.generate_ode_function`` passes them):

  build  the time of generate_ode_function(...) per generator; eomgen cold
         (an empty compile cache; the C runtime's objects compiled once
         before, as after a first model) and cached (the same model again:
         the kernels are formed and printed, the library found by content);
  call   the time of one rhs(x, t, r, p) call, array arguments, with the
         argument types given (constants_arg_type="array",
         specifieds_arg_type="array") and not given (PyDy's default: every
         call works out what p and r are); the median of --reps repeats of
         --calls calls, the generators timed by turns.

Every rhs is checked against PyDy's Cython one first (max relative
difference printed). Times are reported with ratios; nothing is asserted.
PyDy's Cython rhs returns the same array on every call: its call time is of
the bare function (a caller that keeps results pays a .copy() on top).

    python bench/bench_pydy.py [--n 1 2 3 4 5] [--reps 15] [--calls 2000] [--json PATH]
    python bench/bench_pydy.py --report PATH     (the tables of a --json file again)
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import numpy as np  # noqa: E402


def median_calls(fns, reps, calls):
    """{name: median seconds per call}, the functions timed by turns."""
    times = {k: [] for k in fns}
    for _ in range(reps):
        for k, fn in fns.items():
            t0 = time.perf_counter()
            for _ in range(calls):
                fn()
            times[k].append((time.perf_counter() - t0) / calls)
    return {k: statistics.median(v) for k, v in times.items()}


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def run(ns, reps, calls, tmp):
    os.environ["EOMGEN_CACHE"] = str(Path(tmp) / "eomgen-cache")
    import gen
    import gen.pydy
    from pydy.codegen.ode_function_generators import generate_ode_function
    from pydy.models import multi_mass_spring_damper, n_link_pendulum_on_cart

    # the C runtime's objects, compiled once per cache (not a per-model cost)
    warm = multi_mass_spring_damper()
    _, t_runtime = timed(lambda: warm.generate_ode_function(generator=gen.pydy.ODEFunctionGenerator))
    rows = []
    for n in ns:
        sysm, t_derive = timed(lambda: n_link_pendulum_on_cart(n, cart_force=True,
                                                               joint_torques=True))
        args, kw = sysm._args_for_gen_ode_func(), sysm._kwargs_for_gen_ode_func()
        row = {"n": n, "nx": 2 * (n + 1), "derive_s": t_derive}

        def build(generator, **extra):
            return timed(lambda: generate_ode_function(*args, generator=generator, **kw,
                                                       **extra))

        ours, row["build_eomgen_cold_s"] = build(gen.pydy.ODEFunctionGenerator)
        _, row["build_eomgen_cached_s"] = build(gen.pydy.ODEFunctionGenerator)
        cy, row["build_cython_s"] = build("cython", tmp_dir=str(Path(tmp) / f"cython{n}"))
        lam, row["build_lambdify_s"] = build("lambdify")
        typed = {"constants_arg_type": "array", "specifieds_arg_type": "array"}
        ours_t, _ = build(gen.pydy.ODEFunctionGenerator, **typed)
        cy_t, _ = build("cython", tmp_dir=str(Path(tmp) / f"cython{n}t"), **typed)
        lam_t, _ = build("lambdify", **typed)

        rng = np.random.default_rng(n)
        x = rng.uniform(-1, 1, row["nx"])
        r = rng.uniform(-1, 1, len(sysm.specifieds_symbols))
        p = rng.uniform(0.5, 1.5, len(sysm.constants_symbols))
        ref = cy(x, 0.0, r, p).copy()
        scale = np.max(np.abs(ref))
        row["max_rel_diff"] = {k: float(np.max(np.abs(f(x, 0.0, r, p) - ref)) / scale)
                               for k, f in (("eomgen", ours), ("eomgen_typed", ours_t),
                                            ("lambdify", lam), ("cython_typed", cy_t))}
        fns = {"eomgen": lambda: ours(x, 0.0, r, p), "cython": lambda: cy(x, 0.0, r, p),
               "lambdify": lambda: lam(x, 0.0, r, p),
               "eomgen_typed": lambda: ours_t(x, 0.0, r, p),
               "cython_typed": lambda: cy_t(x, 0.0, r, p),
               "lambdify_typed": lambda: lam_t(x, 0.0, r, p)}
        for k, v in median_calls(fns, reps, calls).items():
            row[f"call_{k}_us"] = v * 1e6
        rows.append(row)
        print(f"n = {n} done", file=sys.stderr, flush=True)
    return {"runtime_s": t_runtime, "rows": rows}


def fmt_ratio(a, b):
    r = a / b
    return f"{r:.1f}x" if r >= 1 else f"{r:.2f}x"


def report(res, reps, calls):
    out = [f"PyDy generate_ode_function: generator=gen.pydy.ODEFunctionGenerator against "
           f"'cython' and 'lambdify' (same run; {platform.python_version()}, "
           f"{platform.machine()}, {os.cpu_count()} cores)",
           f"eomgen's C runtime compiled once first: {res['runtime_s']:.2f} s", "",
           "Build (s): generate_ode_function(...) per generator",
           "| n | nx | eomgen cold | eomgen cached | cython | lambdify | cython / eomgen cold "
           "| lambdify / eomgen cold | cython / eomgen cached |",
           "|---|---|---|---|---|---|---|---|---|"]
    for w in res["rows"]:
        c, k = w["build_eomgen_cold_s"], w["build_eomgen_cached_s"]
        out.append(f"| {w['n']} | {w['nx']} | {c:.2f} | {k:.2f} | {w['build_cython_s']:.2f} | "
                   f"{w['build_lambdify_s']:.2f} | {fmt_ratio(w['build_cython_s'], c)} | "
                   f"{fmt_ratio(w['build_lambdify_s'], c)} | "
                   f"{fmt_ratio(w['build_cython_s'], k)} |")
    out += ["", f"Call (us): rhs(x, t, r, p), array arguments, median of {reps} x {calls} "
            "calls; 'typed' = constants_arg_type and specifieds_arg_type 'array'",
            "| n | eomgen | cython | lambdify | cython / eomgen | lambdify / eomgen | "
            "eomgen typed | cython typed | lambdify typed | cython / eomgen (typed) | "
            "lambdify / eomgen (typed) |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for w in res["rows"]:
        e, cy, la = w["call_eomgen_us"], w["call_cython_us"], w["call_lambdify_us"]
        et, cyt, lat = (w["call_eomgen_typed_us"], w["call_cython_typed_us"],
                        w["call_lambdify_typed_us"])
        out.append(f"| {w['n']} | {e:.2f} | {cy:.2f} | {la:.2f} | {fmt_ratio(cy, e)} | "
                   f"{fmt_ratio(la, e)} | {et:.2f} | {cyt:.2f} | {lat:.2f} | "
                   f"{fmt_ratio(cyt, et)} | {fmt_ratio(lat, et)} |")
    out += ["", "Max relative difference from PyDy's Cython rhs (same x, t, r, p):"]
    for w in res["rows"]:
        out.append(f"  n = {w['n']}: " + ", ".join(f"{k} {v:.1e}"
                                                   for k, v in w["max_rel_diff"].items()))
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--reps", type=int, default=15)
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--json", help="write the measurements here")
    ap.add_argument("--report", help="print the report of a --json file (no measuring)")
    a = ap.parse_args(argv)
    if a.report:
        print(report(json.loads(Path(a.report).read_text()), a.reps, a.calls))
        return
    with tempfile.TemporaryDirectory(prefix="bench-pydy-") as tmp:
        res = run(a.n, a.reps, a.calls, tmp)
    print(report(res, a.reps, a.calls))
    if a.json:
        Path(a.json).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
