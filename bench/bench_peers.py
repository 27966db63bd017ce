"""Benchmark (issue 7): eomgen side by side with PyDy (Cython) and CasADi on
the n-link pendulum on a cart (examples/n_link_cart.py; the physics of
pydy.models.n_link_pendulum_on_cart(n, cart_force=True)).

  1. generation + compile, cold, per tool (sympy's kanes_equations, common
     to all three, reported apart);
  2. C time per right-hand-side call: eomgen's <prefix>_eval_rhs against
     CasADi's generated function (unrolled symbolic LDL^T), one C driver,
     interleaved repeats, and an operation-count floor;
  3. Python call cost of one rhs: eomgen's Simulator.rhs against PyDy's
     Cython rhs(x, t, r, p);
  4. 10 s of the n = 4 model: eomgen's generated DOPRI5 against
     scipy's solve_ivp(RK45) over PyDy's rhs, same tolerances;
  5. eomgen's batch rhs, if the Simulator has one.

    python bench/bench_peers.py [--quick] [--max-seconds S] [--json PATH]
    bash bench/run.sh [--quick] ...          (fresh venv, then this script)

Every (tool, n) generation runs in its own child process with a time limit
(--max-seconds, per model and tool); a peer that fails or times out is
reported as such and the run goes on. Times are reported and compared as
ratios; nothing is asserted.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import signal
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
sys.path.insert(0, str(HERE))

TOOLS = ("eomgen", "pydy", "casadi")
RTOL, ATOL = 1e-8, 1e-10


# ---------------------------------------------------------------- shared
def derive(n):
    """(KanesMethod, symbols, constants list, values list), timed by the caller."""
    import n_link_cart
    KM, s = n_link_cart.derive(n)
    consts = [s["g"], *s["m"], *s["l"]]
    d = n_link_cart.defaults(n)
    vals = [d[str(c)] for c in consts]
    return KM, s, consts, vals


def test_state(n):
    """A generic state (no symmetry, moving) for cross-checks and timing."""
    import math
    q = [0.1] + [math.pi - 0.3 + 0.17 * i for i in range(n)]
    u = [0.05] + [0.2 - 0.07 * i for i in range(n)]
    return q + u


def sim_state(n):
    """x0 of the simulation: hanging, displaced, at rest."""
    import math
    q = [0.0] + [math.pi + (0.3 if i % 2 == 0 else -0.2) for i in range(n)]
    return q + [0.0] * (n + 1)


def median_call(fn, reps, calls):
    out = []
    for _ in range(reps):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        out.append((time.perf_counter() - t0) / calls)
    return statistics.median(out)


def write_result(path, res):
    Path(path).write_text(json.dumps(res))


# ---------------------------------------------------------------- workers
def worker_eomgen(n, work, opts):
    import numpy as np
    import gen
    res = {}
    t0 = time.perf_counter()
    KM, s, consts, vals = derive(n)
    res["derive"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = gen.Model.from_kanes(KM, constants=dict(zip(consts, vals)), inputs=[s["F"]],
                                 name=f"cart{n}")
    t1 = time.perf_counter()
    tm = {}
    sim = gen.compile(model, timings=tm)             # with the time of each stage
    t2 = time.perf_counter()
    res.update(extract=t1 - t0, build=t2 - t1, total=t2 - t0,
               stages={k: v for k, v in tm.items() if k != "cached"}, cached=tm.get("cached"))
    res["stages"]["extract"] = t1 - t0
    # the derivative kernels are generated and compiled on first use (the
    # first linearize); PyDy and CasADi build none (their right-hand side only)
    x = np.array(test_state(n))
    t0 = time.perf_counter()
    sim.linearize(x, r=np.zeros(1))
    res["derivatives"] = time.perf_counter() - t0
    res["derivative_stages"] = {k: sim.build_info.get(k) for k in
                                ("kernels_derivatives", "printing_derivatives",
                                 "compile_derivatives")}
    res["linearize_call"] = median_call(lambda: sim.linearize(x, r=np.zeros(1)), 5, 20)
    # the sources for the C driver and the op count (not timed)
    out = Path(work) / "eomgen_src"
    gen.generate(model, out)
    res["src_dir"] = str(out)
    from _cdriver import count_flops, function_body
    ctext = (out / f"cart{n}.c").read_text()
    try:   # an unrolled mass-matrix solve, when eomgen emits one
        sbody = function_body(ctext, f"cart{n}_mass_solve")
        # a large dense M: the runtime's LDL^T in loops (csrc/gen_rt_ldlt.h),
        # not in the generated text; the floor counts its flops as nu^3/3
        res["solve_kind"] = "loops" if "gen_rt_ldlt_dense" in sbody else "unrolled"
        res["solve_ops"] = count_flops(sbody) if res["solve_kind"] == "unrolled" else None
    except ValueError:
        res["solve_ops"] = None
    try:
        # the right-hand-side kernel (<name>_kernels.c); fused with the
        # unrolled LDL^T for an unconstrained model, whose statements are
        # mass_solve's (one plan), interleaved: its kernel part is the rest
        # (a large model's kernel is <name>_k_rhs_terms_isa, built for the
        # baseline and for AVX, behind a wrapper of the plain name)
        ktext = (out / f"cart{n}_kernels.c").read_text()
        kname = f"cart{n}_k_rhs_terms"
        body = function_body(ktext, kname + "_isa" if kname + "_isa(" in ktext else kname)
        ops = count_flops(body.split("if (!out_ud)")[0])
        if "if (!out_ud)" in body and res["solve_ops"]:
            ops = {k: max(0, v - res["solve_ops"][k]) for k, v in ops.items()}
        res["ops"] = ops
    except ValueError as e:
        res["ops_error"] = str(e)
    x = np.array(test_state(n))
    r = np.zeros(1)
    res["rhs_test"] = sim.rhs(0.0, x, r=r).tolist()
    if opts["py"]:
        res["py_call"] = median_call(lambda: sim.rhs(0.0, x, r=r), opts["reps"], opts["calls"])
    batch, errors = None, []
    X = np.tile(x, (1000, 1))
    X[:, 1] += np.linspace(0.0, 0.1, len(X))
    for name in ("rhs_batch", "rhs"):
        fn = getattr(sim, name, None)
        if fn is None:
            continue
        try:
            Y = np.asarray(fn(0.0, X, r))
        except Exception as e:  # noqa: BLE001 - the batch path is optional
            errors.append(f"{name}: {type(e).__name__}: {e}")
            continue
        if Y.shape == X.shape:
            per = median_call(lambda: fn(0.0, X, r), opts["reps"], 5) / len(X)
            one = np.array([sim.rhs(0.0, xi, r=r) for xi in X[:50]])
            batch = {"method": name, "per_state": per, "N": len(X),
                     "maxdiff_vs_rhs": float(np.max(np.abs(Y[:50] - one)))}
            break
    if batch and batch["method"] == "rhs_batch":
        # against the C loop over the same code: the library's compiler and
        # flags, the same constants, and the two timed by turns (this VM's
        # speed changes between phases), the median of the pairs' ratios;
        # rhs_batch into a preallocated out= (as a loop calling it would)
        from _cdriver import time_rhs_in_c
        from gen.codegen.backends import C_FLAGS, c_compiler as _compiler
        cc, pv, pairs = _compiler(), np.array(vals, dtype=float), []
        Yb = np.empty_like(X)
        for _ in range(7):
            per = median_call(lambda: fn(0.0, X, r, pv, out=Yb), 3, 5) / len(X)
            one = time_rhs_in_c(out, f"cart{n}", test_state(n), vals, reps=5, runs=1, cc=cc,
                                cflags=C_FLAGS)["eomgen"]
            pairs.append((per, one, per / one))
        batch["same_cc"] = {"cc": cc, "per_state": statistics.median(v[0] for v in pairs),
                            "eval_rhs": statistics.median(v[1] for v in pairs),
                            "ratio": statistics.median(v[2] for v in pairs)}
    res["batch"] = batch or {"note": "no batch rhs in this Simulator (no rhs_batch; rhs takes "
                                     "(nx,) only)", "errors": errors}
    if opts["sim"]:
        x0 = np.array(sim_state(n))
        times, final, stats = [], None, None
        for _ in range(opts["sim_reps"]):
            t0 = time.perf_counter()
            sol = sim.simulate(x0, 10.0, 0.01, method="dopri5", rtol=RTOL, atol=ATOL)
            T, X, st = sol.t, sol.x, sol.stats
            times.append(time.perf_counter() - t0)
            final, stats = X[-1].tolist(), st
        # a tight-tolerance reference, to see how far each integrator is from it
        _, Xr = sim.simulate(x0, 10.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-14,
                             max_steps=10 ** 7)
        res["sim"] = {"time": statistics.median(times), "final": final, "t_final": float(T[-1]),
                      "stats": stats, "reference_final": Xr[-1].tolist(),
                      "reference": "eomgen dopri5, rtol 1e-12, atol 1e-14"}
    return res


def worker_pydy(n, work, opts):
    import numpy as np
    import sympy as sm
    from pydy.codegen.ode_function_generators import generate_ode_function
    res = {}
    t0 = time.perf_counter()
    KM, s, consts, vals = derive(n)
    res["derive"] = time.perf_counter() - t0
    kd = KM.kindiffdict()
    q, u = s["q"], s["u"]
    G = sm.Matrix([kd[qi.diff()] for qi in q])
    build = Path(work) / "pydy_build"
    build.mkdir(parents=True, exist_ok=True)
    cwd = os.getcwd()
    os.chdir(build)                                   # cold: a fresh directory
    try:
        t0 = time.perf_counter()
        rhs = generate_ode_function(KM.forcing, q, u, consts, mass_matrix=KM.mass_matrix,
                                    coordinate_derivatives=G, specifieds=[s["F"]],
                                    generator="cython", constants_arg_type="array",
                                    specifieds_arg_type="array", tmp_dir=str(build))
        res["total"] = time.perf_counter() - t0
    finally:
        os.chdir(cwd)
    p = np.array(vals)
    r = np.zeros(1)
    x = np.array(test_state(n))
    res["rhs_test"] = np.asarray(rhs(x, 0.0, r, p)).tolist()
    a = rhs(x, 0.0, r, p)
    res["returns_shared_buffer"] = bool(np.shares_memory(a, rhs(x + 0.1, 0.0, r, p)))
    if opts["py"]:
        res["py_call"] = median_call(lambda: rhs(x, 0.0, r, p), opts["reps"], opts["calls"])
    if opts["sim"]:
        from scipy.integrate import solve_ivp
        x0 = np.array(sim_state(n))
        t_eval = np.linspace(0.0, 10.0, 1001)
        times, sol = [], None
        for _ in range(max(1, opts["sim_reps"] // 2)):
            t0 = time.perf_counter()
            # .copy(): PyDy's Cython rhs returns the same buffer on every call,
            # which corrupts solve_ivp's stored stages (see bench/README.md)
            sol = solve_ivp(lambda t, y: rhs(y, t, r, p).copy(), (0.0, 10.0), x0, method="RK45",
                            rtol=RTOL, atol=ATOL, t_eval=t_eval)
            times.append(time.perf_counter() - t0)
        res["sim"] = {"time": statistics.median(times), "final": sol.y[:, -1].tolist(),
                      "t_final": float(sol.t[-1]), "nfev": int(sol.nfev), "status": int(sol.status)}
    return res


def worker_casadi(n, work, opts):
    import casadi as ca
    import numpy as np
    import sympy as sm
    res = {}
    t0 = time.perf_counter()
    KM, s, consts, vals = derive(n)
    res["derive"] = time.perf_counter() - t0
    nu = n + 1
    t0 = time.perf_counter()
    # sympy -> CasADi SX: plain symbols, lambdify (with sympy's cse) on SX
    qs = sm.symbols(f"qq0:{nu}")
    us = sm.symbols(f"uu0:{nu}")
    Fs = sm.Symbol("FF")
    sub = dict(zip(s["q"], qs))
    sub.update(zip(s["u"], us))
    sub[s["F"]] = Fs
    M = KM.mass_matrix.xreplace(sub)
    f = KM.forcing.xreplace(sub)
    exprs = list(M) + list(f)
    fn = sm.lambdify([qs, us, [Fs], consts], exprs,
                     modules=[{"sin": ca.sin, "cos": ca.cos, "sqrt": ca.sqrt}], cse=True)
    x = ca.SX.sym("x", 2 * nu)
    rr = ca.SX.sym("r", 1)
    pp = ca.SX.sym("p", len(consts))
    el = fn([x[i] for i in range(nu)], [x[nu + i] for i in range(nu)], [rr[0]],
            [pp[i] for i in range(len(consts))])
    Mx = ca.SX(nu, nu)
    for i in range(nu):
        for j in range(nu):
            Mx[i, j] = el[i * nu + j]
    fx = ca.vertcat(*el[nu * nu:])
    t1 = time.perf_counter()
    # unrolled symbolic LDL^T (no pivoting: M is symmetric positive definite)
    D, LT, perm = ca.ldl(Mx, False)
    ud = ca.ldl_solve(fx, D, LT, perm)
    # kinematics: q' = u (the KanesMethod's kdes of this model)
    xdot = ca.vertcat(x[nu:], ud)
    F = ca.Function(f"cas_cart{n}", [x, rr, pp], [xdot])
    t2 = time.perf_counter()
    src = Path(work) / "casadi_src"
    src.mkdir(parents=True, exist_ok=True)
    cwd = os.getcwd()
    os.chdir(src)
    try:
        cfile = F.generate(f"cas_cart{n}.c", {"with_header": True})
    finally:
        os.chdir(cwd)
    cfile = src / cfile
    t3 = time.perf_counter()
    so = src / f"cas_cart{n}.so"
    cmd = ["gcc", "-O2", "-fPIC", "-shared", str(cfile), "-o", str(so), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError("gcc failed on CasADi's code: " + proc.stderr[-2000:])
    t4 = time.perf_counter()
    res.update(sx_build=t1 - t0, ldl_function=t2 - t1, codegen=t3 - t2, compile=t4 - t3,
               total=t4 - t0, c_file=str(cfile), fname=f"cas_cart{n}")
    from _cdriver import count_flops, function_body
    res["ops"] = count_flops(function_body(cfile.read_text(), "casadi_f0"))
    res["rhs_test"] = np.asarray(F(test_state(n), [0.0], vals)).ravel().tolist()
    return res


def worker_install(n, work, opts):
    """What the first model of a fresh installation pays on top (the host
    module, the runtime's objects, the compiled templates; EOMGEN_CACHE
    empty), against the same model with those in place, and the seed
    pendulum's Python call path (sim.rhs(t, x), the acceptance's call)."""
    import numpy as np
    import gen
    import n_link_cart
    import seed_pendulum
    res = {}
    t0 = time.perf_counter()
    tm = {}
    gen.compile(n_link_cart.model(1, name="install_probe"), timings=tm)
    res["first"] = time.perf_counter() - t0
    res["first_stages"] = {k: v for k, v in tm.items() if k != "cached"}
    sim = gen.compile(seed_pendulum.kane_model())
    x = np.array([0.3, 0.9539392014169456, 0.1, -0.03144854510165755])
    res["seed_rhs"] = median_call(lambda: sim.rhs(0.0, x), opts.get("reps", 15),
                                  opts.get("calls", 5000))
    return res


WORKERS = {"eomgen": worker_eomgen, "pydy": worker_pydy, "casadi": worker_casadi,
           "install": worker_install}


def run_worker(tool, n, work, opts, timeout):
    """Run one worker in a child process (own process group, killed on
    timeout); returns (status, result dict or message)."""
    work = Path(work)
    work.mkdir(parents=True, exist_ok=True)
    out = work / f"{tool}.json"
    env = dict(os.environ)
    cache = work / "eomgen_cache"
    env["EOMGEN_CACHE"] = str(cache)          # no model in it: a cold build
    if tool == "eomgen" and opts.get("installation"):
        # what is built once per installation (the host module, the runtime's
        # objects, the compiled templates), as a user has it after the first
        # model; section 0 reports its cost
        import shutil
        for d in Path(opts["installation"]).iterdir():
            if d.is_dir() and not (cache / d.name).exists():
                shutil.copytree(d, cache / d.name)
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", tool, str(n), str(work),
           json.dumps(opts)]
    log = open(work / f"{tool}.log", "w")
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env,
                            start_new_session=True)
    try:
        rc = proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()
        log.close()
        return "timeout", f"> {timeout:.0f} s"
    finally:
        log.close()
    wall = time.perf_counter() - t0
    if rc != 0 or not out.exists():
        tail = (work / f"{tool}.log").read_text()[-1500:]
        return "failed", f"exit {rc}: {tail.strip().splitlines()[-1] if tail.strip() else ''}"
    res = json.loads(out.read_text())
    res["wall"] = wall
    return "ok", res


# ---------------------------------------------------------------- report
def fmt_t(v, unit="s"):
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    if unit == "us":
        return f"{v * 1e6:.3g}"
    return f"{v:.3g}" if v < 100 else f"{v:.0f}"


def ratio(a, b):
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and b > 0:
        return f"{a / b:.3g}"
    return "-"


def md_table(headers, rows):
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def floor_flops(ops, nu):
    """Arithmetic flops of the rhs kernel + a Cholesky-class factor/solve
    (nu^3/3 + 2 nu^2)."""
    return ops["arith"] + nu ** 3 / 3 + 2 * nu ** 2


def floor_cycles(ops, nu):
    """Cycles: floor_flops at 4 flops/cycle, + 20 cycles per sin/cos."""
    if not ops:
        return None
    return floor_flops(ops, nu) / 4 + 20 * (ops["sin"] + ops["cos"])


def measured_floor(ops, nu, repeats):
    """The floor from measurements of the same repeats: floor_flops at the
    peak scalar rate the driver measured, plus the platform's libm on the
    model's sin/cos arguments; the median over the repeats of floor (s) and
    of eomgen / floor."""
    if not ops or not repeats:
        return None
    flops = floor_flops(ops, nu)
    fl = [flops / r["peak"] + r["libm"] for r in repeats]
    return {"floor_measured": statistics.median(fl),
            "floor_measured_ratio": statistics.median(r["eomgen"] / f
                                                      for r, f in zip(repeats, fl)),
            "peak_flops": statistics.median(r["peak"] for r in repeats),
            "libm": statistics.median(r["libm"] for r in repeats)}


def floor_estimate(ops, nu, mhz):
    """Seconds: floor_cycles at mhz, the clock the C driver measured between
    its repeats (the core's speed at that moment, turbo or a VM's slow phase
    included), or the nominal /proc/cpuinfo clock where there is no
    measurement."""
    cycles = floor_cycles(ops, nu)
    if not cycles or not mhz:
        return None
    return cycles / (mhz * 1e6)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="n = 1, 2, 4 only, fewer repeats (about 2 minutes)")
    ap.add_argument("--n", type=int, nargs="*",
                    help="sizes (default 1 2 4 8 10 + 12 16 20 32 50 in budget)")
    ap.add_argument("--max-seconds", type=float, default=300.0,
                    help="time limit of one tool's generation + compile for one model (default 300)")
    ap.add_argument("--derive-seconds", type=float,
                    help="the derivation's expected time at the first n (the time limit's "
                         "allowance for sympy; later sizes scale the last measured one)")
    ap.add_argument("--tools", nargs="*", default=list(TOOLS), choices=TOOLS)
    ap.add_argument("--json", default=str(HERE / "results.json"), help="where to write all numbers")
    ap.add_argument("--keep", help="keep the generated sources in this directory")
    ap.add_argument("--worker", nargs=4, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        tool, n, work, opts = args.worker
        res = WORKERS[tool](int(n), work, json.loads(opts))
        write_result(Path(work) / f"{tool}.json", res)
        return

    from _cdriver import cpu_info, time_rhs_in_c
    cpu, mhz, cores = cpu_info()
    quick = args.quick
    base = [1, 2, 4] if quick else [1, 2, 4, 8, 10]
    extra = [] if quick else [12, 16, 20, 32, 50]
    if args.n:
        base, extra = [v for v in args.n if v <= 10], [v for v in args.n if v > 10]
    py_ns = {1, 2, 4} if quick else {1, 2, 4, 8, 10}
    sim_n = 4
    import casadi
    import pydy
    import scipy
    import sympy
    import numpy
    import gen
    meta = {"date": datetime.datetime.now().isoformat(timespec="seconds"), "cpu": cpu,
            "cpu_mhz": mhz, "cores": cores, "python": platform.python_version(),
            "versions": {"eomgen": gen.__version__, "pydy": pydy.__version__,
                         "casadi": casadi.__version__, "sympy": sympy.__version__,
                         "scipy": scipy.__version__, "numpy": numpy.__version__},
            "quick": quick, "max_seconds": args.max_seconds, "rtol": RTOL, "atol": ATOL,
            "floor_model": "arith flops of the rhs kernel (counted in the printed C) + "
                           "nu^3/3 + 2 nu^2 (Cholesky-class solve), at 4 flops/cycle, "
                           "+ 20 cycles per sin/cos, at the clock the C driver measures "
                           "between its repeats (floor_nominal: at the /proc/cpuinfo 'cpu MHz'); "
                           "floor_measured: the same flops at the peak scalar rate the driver "
                           "measures, + the libm's sin/cos at the model's angles, both timed "
                           "in the same repeat as eomgen"}
    try:
        meta["git_head"] = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                                          capture_output=True, text=True).stdout.strip()
        meta["git_dirty"] = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain",
                                            "--", "gen", "templates", "csrc"],
                                           capture_output=True, text=True).stdout.split("\n")
        meta["git_dirty"] = [v.strip() for v in meta["git_dirty"] if v.strip()]
    except OSError:
        pass
    print(f"# {cpu} ({cores} logical cores, {mhz} MHz), {meta['date']}", flush=True)
    results = {"meta": meta, "models": {}}
    gave_up = {}                      # tool -> n where it timed out/failed (extra sizes)
    last_derive = None                # (n, seconds) of the last derivation measured
    tmp_root = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="eomgen_bench_"))
    tmp_root.mkdir(parents=True, exist_ok=True)
    try:
        # 0. the installation: built once, then shared by every model
        install = tmp_root / "install"
        st, res = run_worker("install", 1, install, {"reps": 7 if quick else 15,
                                                     "calls": 2000 if quick else 5000},
                             args.max_seconds)
        results["installation"] = res if st == "ok" else {"status": st, "why": res}
        if st == "ok":
            print(f"installation: first model {res['first']:.2f} s "
                  f"({', '.join(f'{k} {v:.2f}' for k, v in res['first_stages'].items())}); "
                  f"seed pendulum sim.rhs(t, x) {res['seed_rhs'] * 1e6:.2f} us", flush=True)
        for n in base + extra:
            is_extra = n in extra
            opts = {"py": n in py_ns and not is_extra, "sim": n == sim_n,
                    "reps": 7 if quick else 15, "calls": 2000 if quick else 5000,
                    "sim_reps": 3 if quick else 5,
                    "installation": str(install / "eomgen_cache") if st == "ok" else None}
            entry = results["models"][n] = {"n": n, "nx": 2 * (n + 1)}
            work = tmp_root / f"n{n}"
            derive_t = None
            # the first tool's derivation at this n, guessed from the last n's
            # (sympy's Kane derivation grows about as n^4 here): the budget is
            # for generation + compile, not for sympy
            guess = (last_derive[1] * (n / last_derive[0]) ** 4 if last_derive
                     else args.derive_seconds or args.max_seconds)
            for tool in args.tools:
                if tool in gave_up:
                    entry[tool] = {"status": "skipped",
                                   "why": f"{gave_up[tool][1]} at n = {gave_up[tool][0]}"}
                    continue
                # the budget is for generation + compile; the derivation and the
                # measurements come on top
                timeout = args.max_seconds + 3 * (derive_t or guess) + 60
                st, res = run_worker(tool, n, work, opts, timeout)
                if st == "ok":
                    derive_t = derive_t or res.get("derive")
                    if derive_t:
                        last_derive = (n, derive_t)
                    if res.get("total", 0) > args.max_seconds:
                        st = "over budget"
                    entry[tool] = {"status": st, **res}
                else:
                    entry[tool] = {"status": st, "why": res}
                if st != "ok" and is_extra:
                    gave_up[tool] = (n, st)
                line = f"n={n:2d} {tool:7s} {st:8s}"
                if st in ("ok", "over budget"):
                    line += f" derive {res['derive']:.2f} s, gen+compile {res['total']:.2f} s"
                    if "stages" in res:
                        line += " (" + ", ".join(f"{k} {v:.2f}" for k, v in res["stages"].items()) + ")"
                else:
                    line += f" {res}"
                print(line, flush=True)
            # the C driver
            e, c = entry.get("eomgen", {}), entry.get("casadi", {})
            if e.get("status") in ("ok", "over budget"):
                try:
                    cas_ok = c.get("status") in ("ok", "over budget")
                    ct = time_rhs_in_c(
                        e["src_dir"], f"cart{n}", test_state(n),
                        derive_values(n),
                        cas_c=c.get("c_file") if cas_ok else None,
                        cas_fname=c.get("fname") if cas_ok else None,
                        reps=11 if quick else 21, trig=range(1, n + 1))
                    entry["c_call"] = ct
                    clock = ct.get("clock", 0) / 1e6 or None
                    fl = floor_estimate(e.get("ops"), n + 1, clock or mhz)
                    entry["floor"] = fl
                    entry["floor_nominal"] = floor_estimate(e.get("ops"), n + 1, mhz)
                    # eomgen / floor per repeat: cycles per call at the clock
                    # of the same repeat against the floor's cycles
                    fc = floor_cycles(e.get("ops"), n + 1)
                    if fc and ct.get("eomgen_cycles"):
                        entry["floor_ratio"] = ct["eomgen_cycles"] / fc
                    # the measured floor: the flops at this machine's peak
                    # rate of scalar arithmetic and the model's sin and cos
                    # at what its libm takes, both timed in the same repeat
                    # as eomgen (no clock needed: on a VM whose neighbours
                    # slow an integer chain, cycles read wrong)
                    mf = measured_floor(e.get("ops"), n + 1, ct.get("repeats"))
                    if mf:
                        entry.update(mf)
                    print(f"n={n:2d} C rhs: eomgen {ct['eomgen'] * 1e6:.3f} us"
                          + (f", casadi {ct['casadi'] * 1e6:.3f} us (max rel diff "
                             f"{ct.get('maxreldiff', float('nan')):.2g})" if "casadi" in ct else "")
                          + (f", floor {fl * 1e6:.3f} us at {clock or mhz:.0f} MHz"
                             + (" measured" if clock else " nominal") if fl else ""), flush=True)
                except Exception as ex:  # noqa: BLE001 - report and go on
                    entry["c_call"] = {"error": str(ex)[-1500:]}
                    print(f"n={n:2d} C driver failed: {str(ex)[-300:]}", flush=True)
            # cross-check of the three right-hand sides
            import numpy as np
            ref = e.get("rhs_test")
            if ref is not None:
                entry["rhs_maxdiff"] = {
                    t: float(np.max(np.abs(np.array(entry[t]["rhs_test"]) - np.array(ref))))
                    for t in ("pydy", "casadi") if entry.get(t, {}).get("rhs_test")}
            Path(args.json).write_text(json.dumps(results, indent=1, default=str))
    finally:
        if not args.keep:
            import shutil
            shutil.rmtree(tmp_root, ignore_errors=True)
    report(results)
    Path(args.json).write_text(json.dumps(results, indent=1, default=str))
    print(f"\nall numbers: {args.json}")


def derive_values(n):
    import n_link_cart
    d = n_link_cart.defaults(n)
    return [d["g"]] + [d[f"m{i}"] for i in range(n + 1)] + [d[f"l{i}"] for i in range(n)]


def _get(entry, tool, key):
    d = entry.get(tool, {})
    if d.get("status") in ("ok", "over budget"):
        return d.get(key)
    return d.get("status") if d else None


def report(results):
    models = results["models"]
    ns = sorted(models)
    out = []
    # 0. the installation
    inst = results.get("installation") or {}
    if "first" in inst:
        out.append("### 0. Once per installation\n")
        out.append(f"The first model built with an empty cache also builds the host module, "
                   f"the runtime's objects and the compiled templates: {fmt_t(inst['first'])} s "
                   f"for the 1-link cart ("
                   + ", ".join(f"{k} {fmt_t(v)}" for k, v in inst["first_stages"].items())
                   + "). The rows below start from a cache holding those (a user's second "
                   f"model on), with no model in it. Seed pendulum `sim.rhs(t, x)`: "
                   f"{fmt_t(inst['seed_rhs'], 'us')} us per call.\n")
    # 1. generation
    rows = []
    for n in ns:
        m = models[n]
        e = m.get("eomgen", {})
        st = e.get("stages", {}) if e.get("status") in ("ok", "over budget") else {}
        te, tp, tc = _get(m, "eomgen", "total"), _get(m, "pydy", "total"), _get(m, "casadi", "total")
        der = _get(m, "eomgen", "derive") or _get(m, "pydy", "derive") or _get(m, "casadi", "derive")
        rows.append([n, m["nx"], fmt_t(der), fmt_t(te),
                     " / ".join(fmt_t(st.get(k)) for k in ("extract", "kernels", "printing",
                                                           "templates", "compile"))
                     if st else "-",
                     fmt_t(_get(m, "eomgen", "derivatives")),
                     fmt_t(tp), fmt_t(tc), ratio(te, tp), ratio(te, tc)])
    out.append("### 1. Generation + compile (cold model), seconds\n")
    out.append(md_table(["n", "nx", "sympy derive", "eomgen",
                         "eomgen extract / kernels / printing / templates / cc",
                         "eomgen derivatives (first linearize)", "PyDy cython", "CasADi",
                         "eomgen / PyDy", "eomgen / CasADi"], rows))
    # 1b. growth with n
    rows = []
    prev = None
    for n in ns:
        if prev is not None:
            m0, m1 = models[prev], models[n]
            row = [f"{prev} -> {n}"]
            for tool in ("eomgen", "pydy", "casadi"):
                a, b = _get(m0, tool, "total"), _get(m1, tool, "total")
                if isinstance(a, (int, float)) and isinstance(b, (int, float)) and a > 0:
                    import math
                    row.append(f"{b / a:.2f} (n^{math.log(b / a) / math.log(n / prev):.2f})")
                else:
                    row.append(b if isinstance(b, str) else "-")
            rows.append(row)
        prev = n
    out.append("\n### 1b. Growth of generation + compile with n (time ratio and local "
               "exponent)\n")
    out.append(md_table(["n", "eomgen", "PyDy cython", "CasADi"], rows))
    # 2. C call
    rows = []
    for n in ns:
        m = models[n]
        ct = m.get("c_call", {})
        e = m.get("eomgen", {})
        ops = e.get("ops") if isinstance(e, dict) else None
        cops = (m.get("casadi") or {}).get("ops")
        ce, cc, fl = ct.get("eomgen"), ct.get("casadi"), m.get("floor")
        pr, frr = ct.get("pair_ratio"), m.get("floor_ratio")
        sops = e.get("solve_ops") if isinstance(e, dict) else None
        cstat = (m.get("casadi") or {}).get("status", "-")
        rmin = ratio(ct.get("eomgen_min"), ct.get("casadi_min"))
        b = (e.get("batch") or {}) if isinstance(e, dict) else {}
        rows.append([n, m["nx"], fmt_t(ce, "us"), fmt_t(cc, "us") if cc else cstat,
                     (f"{pr:.3g}" if pr else ratio(ce, cc)) + (f" ({rmin})" if rmin != "-" else ""),
                     (f"{b['same_cc']['ratio']:.3g} ({Path(b['same_cc']['cc']).name})"
                      if "same_cc" in b else ratio(b.get("per_state"), ce)),
                     (f"{ops['arith']} + {ops['sin']}s/{ops['cos']}c" if ops else "-")
                     + (f" + solve {sops['arith']}" if sops else "")
                     + (" + solve in loops" if isinstance(e, dict)
                        and e.get("solve_kind") == "loops" else ""),
                     f"{cops['arith']} + {cops['sin']}s/{cops['cos']}c" if cops else "-",
                     fmt_t(fl, "us") + (f" at {ct['clock'] / 1e9:.2f} GHz" if ct.get("clock") else ""),
                     f"{frr:.3g}" if frr else ratio(ce, fl),
                     (f"{m['floor_measured_ratio']:.3g} (floor {m['floor_measured'] * 1e6:.3g} us: "
                      f"{m['peak_flops'] / 1e9:.3g} Gflop/s, libm {m['libm'] * 1e6:.3g} us)"
                      if m.get("floor_measured_ratio") else "-"),
                     f"{ct['maxreldiff']:.1g}" if "maxreldiff" in ct else "-"])
    out.append("\n### 2. C time per rhs call (median), microseconds\n")
    out.append(md_table(["n", "nx", "eomgen eval_rhs", "CasADi",
                         "eomgen / CasADi (median of the repeats' ratios; of minima)",
                         "rhs_batch (N = 1000, out=) per state / eval_rhs (the library's compiler, by turns)",
                         "eomgen ops (arith + sin/cos [+ unrolled solve])", "CasADi ops (incl. LDL)", "floor (at the measured clock)", "eomgen / floor (per repeat, at its clock)",
                         "eomgen / measured floor (the flops at the measured peak scalar rate + the libm's sin/cos at the model's angles, per repeat)",
                         "max rel diff"], rows))
    # 3. Python call
    rows = []
    for n in ns:
        m = models[n]
        pe, pp = _get(m, "eomgen", "py_call"), _get(m, "pydy", "py_call")
        if pe is None and pp is None:
            continue
        b = (m.get("eomgen") or {}).get("batch") or {}
        rows.append([n, m["nx"], fmt_t(pe, "us"), fmt_t(pp, "us"), ratio(pp, pe),
                     (fmt_t(b.get("per_state"), "us") + f" (`{b['method']}`)") if "per_state" in b
                     else ("n/a: no batch rhs" if "note" in b else "-"),
                     fmt_t(m.get("rhs_maxdiff", {}).get("pydy"))])
    out.append("\n### 3. Python call cost per rhs (median), microseconds\n")
    out.append(md_table(["n", "nx", "eomgen Simulator.rhs", "PyDy cython rhs", "PyDy / eomgen",
                         "eomgen batch rhs per state (N = 1000)", "max abs rhs diff vs PyDy"], rows))
    # 4. simulation
    rows = []
    for n in ns:
        m = models[n]
        se, sp = _get(m, "eomgen", "sim"), _get(m, "pydy", "sim")
        if not isinstance(se, dict) and not isinstance(sp, dict):
            continue
        import numpy as np
        te = se["time"] if isinstance(se, dict) else se
        tp = sp["time"] if isinstance(sp, dict) else sp
        diff = (float(np.max(np.abs(np.array(se["final"]) - np.array(sp["final"]))))
                if isinstance(se, dict) and isinstance(sp, dict) else None)
        ref = np.array(se["reference_final"]) if isinstance(se, dict) else None
        err = [f"{float(np.max(np.abs(np.array(d['final']) - ref))):.2g}"
               if isinstance(d, dict) and ref is not None else "-" for d in (se, sp)]
        rows.append([n, fmt_t(te), fmt_t(tp), ratio(tp, te),
                     se["stats"]["n_rhs"] if isinstance(se, dict) else "-",
                     sp["nfev"] if isinstance(sp, dict) else "-",
                     f"{diff:.2g}" if diff is not None else "-", err[0], err[1]])
    out.append("\n### 4. Simulation of 10 s (rtol 1e-8, atol 1e-10, output every 0.01 s), seconds\n")
    out.append(md_table(["n", "eomgen dopri5 (C)", "solve_ivp RK45 + PyDy rhs", "scipy / eomgen",
                         "eomgen rhs evals", "scipy rhs evals", "max abs x(10) diff",
                         "eomgen error vs ref", "scipy error vs ref"], rows))
    text = "\n".join(out)
    print()
    print(text)
    results["table_markdown"] = text


if __name__ == "__main__":
    main()
