"""Benchmark (issue 4): sympy's linearize against eomgen's generated C.

For each model it measures, in the same run:
  sympy      to_linearizer + linearize(A_and_B=True, linear_solver='CRAMER')
             at one numeric operating point (the result for one point);
  eomgen     Model.from_* + generate + compile (cffi, cold cache): paid once;
  C call     one <prefix>_linearize call, timed in C (a small driver loop,
             median of repeats), and through Python (Simulator.linearize).
The last column is how many C linearizations fit in one sympy linearize.

    python bench/bench_linearize.py [--quick] [--timeout S] [--n 1 2 4 8]

Each sympy measurement runs in a child process with a time limit; a model
that exceeds it is reported as '> S s'.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT))


# ---------------------------------------------------------------- models
def derive(case):
    """(formed sympy object, builder of gen.Model, sympy op point) for a case."""
    import sympy as sm
    if case in ("seed_kane", "seed_lagrange"):
        import seed_pendulum as sp
        vals = sp.DEFAULTS
        if case == "seed_kane":
            KM, s = sp.derive_kane()
            op = {s["q1"]: vals["L"], s["q2"]: 0, s["u1"]: 0, s["u2"]: 0,
                  s["u1"].diff(s["t"]): 0, s["u2"].diff(s["t"]): 0}
            build = sp.kane_model
        else:
            KM, s = sp.derive_lagrange()
            op = {s["q1"]: vals["L"], s["q2"]: 0, s["q1d"]: 0, s["q2d"]: 0,
                  s["q1"].diff(s["t"], 2): 0, s["q2"].diff(s["t"], 2): 0,
                  # sympy's Linearizer takes the multiplier with LM.eom's sign
                  KM.lam_vec[0]: vals["m"] * vals["g"] / (2 * vals["L"])}
            build = sp.lagrange_model
            KM.linearizer_args = dict(q_ind=[s["q2"]], qd_ind=[s["q2d"]], q_dep=[s["q1"]],
                                      qd_dep=[s["q1d"]])
        op.update({s[k]: v for k, v in vals.items()})
        return KM, build, op
    n = int(case.removeprefix("cart"))
    import n_link_cart
    KM, s = n_link_cart.derive(n)
    from sympy.physics.mechanics import dynamicsymbols
    t = dynamicsymbols._t
    op = {qi: 0 for qi in s["q"]}
    op.update({ui: 0 for ui in s["u"]})
    op.update({ui.diff(t): 0 for ui in s["u"]})
    op[s["F"]] = 0
    consts = {str(c): c for c in (s["g"], *s["m"], *s["l"])}
    op.update({consts[k]: v for k, v in n_link_cart.defaults(n).items()})
    return KM, (lambda: n_link_cart.model(n)), op


def sympy_worker(case):
    """Child process: print the seconds sympy's linearize takes."""
    obj, _, op = derive(case)
    t0 = time.perf_counter()
    lin = obj.to_linearizer(linear_solver="CRAMER", **getattr(obj, "linearizer_args", {}))
    A, B = lin.linearize(op_point=op, A_and_B=True)
    dt = time.perf_counter() - t0
    print(f"{dt:.6f}")


def time_sympy(case, timeout):
    cmd = [sys.executable, __file__, "--sympy-worker", case]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=True)
        return float(out.stdout.strip().splitlines()[-1])
    except subprocess.TimeoutExpired:
        return None


# ------------------------------------------------------------ C driver
DRIVER = textwrap.dedent("""\
    #include <stdio.h>
    #include <time.h>
    #include "{p}.h"
    static double now(void) {{
        struct timespec ts; clock_gettime(CLOCK_MONOTONIC, &ts);
        return ts.tv_sec + 1e-9 * ts.tv_nsec;
    }}
    int main(void) {{
        {p}_real x[{P}_NX] = {{0}}, r[{P}_NR + 1] = {{0}};
        {p}_real A[{P}_NS * {P}_NS], B[{P}_NS * {P}_NR + 1];
        volatile double sink = 0;
        int i, rep, n = {iters};
        for (i = 0; i < {P}_NX; ++i) x[i] = {x0};
        if ({p}_consistent_state(0, NULL, 0, 0, x) != 0) return 2;
        for (rep = 0; rep < {reps}; ++rep) {{
            double t0 = now();
            for (i = 0; i < n; ++i) {{
                x[0] += 1e-12;
                if ({p}_linearize(x, r, NULL, 0, A, B) != 0) return 1;
                sink += A[0];
            }}
            printf("%.9g\\n", (now() - t0) / n);
        }}
        return sink == 12345.0;
    }}
""")


def time_c_call(model, workdir, reps=7):
    import gen
    out = Path(workdir) / model.name
    gen.generate(model, out)
    p = model.name
    iters = max(200, int(2e5 / max(1, model.nx) ** 2))
    x0 = "0.3" if model.mc or model.mv else "0.1"
    (out / "bench.c").write_text(DRIVER.format(p=p, P=p.upper(), iters=iters, reps=reps, x0=x0))
    exe = out / "bench"
    from gen.codegen.render import model_sources
    srcs = [str(out / "bench.c")] + [str(out / f) for f in model_sources(p)] + sorted(
        str(f) for f in out.glob("gen_rt_*.c"))
    subprocess.run(["gcc", "-std=c99", "-O2", "-D_POSIX_C_SOURCE=199309L", "-I", str(out), *srcs,
                    "-o", str(exe), "-lm"], check=True)
    res = subprocess.run([str(exe)], capture_output=True, text=True, check=True)
    return statistics.median(float(v) for v in res.stdout.split())


def time_py_call(sim, reps=7):
    import numpy as np
    x = sim.consistent_state(np.full(sim.nx, 0.3 if sim.mc or sim.mv else 0.1))
    r = np.zeros(sim.nr)
    n = 2000
    out = []
    for _ in range(reps):
        t0 = time.perf_counter()
        for _ in range(n):
            sim.linearize(x, r=r)
        out.append((time.perf_counter() - t0) / n)
    return statistics.median(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="*", default=[1, 2, 4, 8])
    ap.add_argument("--timeout", type=float, default=600.0,
                    help="seconds allowed for one sympy linearize (default 600)")
    ap.add_argument("--quick", action="store_true", help="seed models and n = 1, 2 only")
    ap.add_argument("--sympy-worker", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.sympy_worker:
        sympy_worker(args.sympy_worker)
        return
    ns = [1, 2] if args.quick else args.n
    cases = ["seed_kane", "seed_lagrange"] + [f"cart{n}" for n in ns]
    import gen
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["EOMGEN_CACHE"] = str(Path(tmp) / "cache")      # cold compile
        for case in cases:
            t_sym = time_sympy(case, args.timeout)
            _, build, _ = derive(case)
            t0 = time.perf_counter()
            model = build()
            t1 = time.perf_counter()
            sim = gen.compile(model)
            t2 = time.perf_counter()
            c_call = time_c_call(model, tmp)
            py_call = time_py_call(sim)
            rows.append((case, model.nx, t_sym, t1 - t0, t2 - t1, c_call, py_call))
            sym = f"{t_sym:9.3f}" if t_sym is not None else f"> {args.timeout:.0f}".rjust(9)
            ratio = f"{t_sym / c_call:12.3g}" if t_sym is not None else f"> {args.timeout / c_call:10.3g}"
            print(f"{case:14s} nx={model.nx:3d}  sympy {sym} s  derive {t1 - t0:7.3f} s  "
                  f"gen+compile {t2 - t1:7.3f} s  C {c_call * 1e6:9.3f} us  "
                  f"py {py_call * 1e6:8.2f} us  sympy/C {ratio}", flush=True)
    print()
    print("| model | nx | sympy linearize (s) | derive + extract (s) | generate + compile (s) "
          "| C linearize (us) | via Python (us) | C calls per sympy call |")
    print("|---|---|---|---|---|---|---|---|")
    for case, nx, ts, tm, tg, tc, tp in rows:
        s = f"{ts:.3f}" if ts is not None else f"> {args.timeout:.0f}"
        r = f"{ts / tc:.3g}" if ts is not None else f"> {args.timeout / tc:.3g}"
        print(f"| {case} | {nx} | {s} | {tm:.3f} | {tg:.3f} | {tc * 1e6:.3f} | {tp * 1e6:.2f} | {r} |")


if __name__ == "__main__":
    main()
