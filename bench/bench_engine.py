"""Benchmark of the simulation engine: eomgen's generated DOPRI5, RODAS4 and
RK4 (``sim.simulate``) next to SciPy's ``solve_ivp`` over the same compiled
right-hand side (``sim.rhs``, and ``sim.jacobian`` for the implicit solvers).

  1. dense output, the n = 4 pendulum on a cart (bench_peers.py section 4:
     10 s, rtol 1e-8, atol 1e-10, output every 0.01 s, hanging and displaced
     at rest, F = 0): eomgen DOPRI5 against solve_ivp(RK45, t_eval=the grid);
     rhs evaluations, steps, time, and the error over all output rows and at
     t = 10 against a tight reference (solve_ivp DOP853, rtol 1e-13); then
     the same DOPRI5 run with output every 0.1, 0.01, 0.001 s (the steps do
     not depend on the output grid);
  2. the stiff double pendulum (examples/stiff_double_pendulum.py, 2 s,
     output every 0.01 s, rtol = atol = 1e-6): eomgen DOPRI5, eomgen RODAS4,
     SciPy Radau and BDF with the analytic Jacobian; counts, times and the
     final-state error against a tight reference (eomgen RODAS4 at 1e-10,
     checked against eomgen DOPRI5 at 1e-11);
  3. events on the seed pendulum (Kane and Lagrange), released from rest at
     60 degrees: the first crossing of q2 through zero (a quarter period)
     by eomgen's DOPRI5 (rtol 1e-10) and RK4 (dt 1e-3) against
     solve_ivp(RK45, rtol 1e-10, events=...), all against the exact
     T/4 = sqrt(L/g) K(sin^2(theta0/2)).

    python bench/bench_engine.py [--quick] [--json PATH]

Times are medians of interleaved repeats (the machine may be shared); they
are compared as ratios. Nothing is asserted: the acceptance criteria of the
issue are printed with what came out.
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import platform
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402

CART_N = 4
CART_T, CART_DT, CART_RTOL, CART_ATOL = 10.0, 0.01, 1e-8, 1e-10
STIFF_T, STIFF_DT, STIFF_TOL = 2.0, 0.01, 1e-6
EV_THETA0, EV_RTOL, EV_ATOL, EV_RK4_DT, EV_T_END = math.pi / 3, 1e-10, 1e-12, 1e-3, 1.0
BIG = 10 ** 7


# ---------------------------------------------------------------- helpers

def tsx(sol, events=False):
    """(t, X[, events], stats) of a gen.Solution."""
    return (sol.t, sol.x) + ((sol.events,) if events else ()) + (sol.stats,)

def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def interleaved(fns, reps):
    """Run each of fns (name -> callable) reps times, interleaved; return
    ({name: median time}, {name: min time}, {name: last result})."""
    times = {k: [] for k in fns}
    last = {}
    for _ in range(reps):
        for k, fn in fns.items():
            dt, last[k] = timed(fn)
            times[k].append(dt)
    return ({k: statistics.median(v) for k, v in times.items()},
            {k: min(v) for k, v in times.items()}, last)


def md_table(headers, rows):
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def g3(v):
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    if isinstance(v, int):
        return str(v)
    return f"{v:.3g}"


def e2(v):
    return "-" if v is None else f"{v:.2g}"


def ms(v):
    return "-" if v is None else f"{v * 1e3:.3g}"


def cpu_model():
    name, cores = None, 0
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            k, _, v = line.partition(":")
            if k.strip() == "model name" and name is None:
                name = v.strip()
            elif k.strip() == "processor":
                cores += 1
    except OSError:
        pass
    return name, cores or None


def compile_models():
    """The four simulators (gen.compile; eomgen's build cache applies)."""
    import gen
    import n_link_cart
    import seed_pendulum
    import stiff_double_pendulum
    out, tm = {}, {}
    for key, mk in (("cart", lambda: n_link_cart.model(CART_N)),
                    ("stiff", stiff_double_pendulum.model),
                    ("kane", seed_pendulum.kane_model),
                    ("lagrange", seed_pendulum.lagrange_model)):
        dt, out[key] = timed(lambda: gen.compile(mk()))
        tm[key] = dt
    return out, tm


# ---------------------------------------------------------------- 1. cart
def bench_cart(sim, reps, sweep_factors):
    from scipy.integrate import solve_ivp
    from bench_peers import sim_state
    x0 = np.array(sim_state(CART_N), dtype=float)
    nrows = int(round(CART_T / CART_DT)) + 1
    grid = np.linspace(0.0, CART_T, nrows)

    def eom():
        return tsx(sim.simulate(x0, CART_T, CART_DT, method="dopri5", rtol=CART_RTOL,
                                atol=CART_ATOL))

    def rk45():
        return solve_ivp(sim.rhs, (0.0, CART_T), x0, method="RK45", rtol=CART_RTOL,
                         atol=CART_ATOL, t_eval=grid)

    med, mins, last = interleaved({"eomgen": eom, "scipy": rk45}, reps)
    T, X, st = last["eomgen"]
    sol = last["scipy"]
    assert np.allclose(T, grid, rtol=0, atol=1e-12), "output grids differ"
    assert sol.status == 0 and sol.y.shape == (x0.size, nrows), sol.message
    # step counts of RK45 (untimed): the same run with dense_output keeps its steps
    solc = solve_ivp(sim.rhs, (0.0, CART_T), x0, method="RK45", rtol=CART_RTOL,
                     atol=CART_ATOL, dense_output=True)
    rk45_acc = len(solc.sol.ts) - 1
    rk45_att = (solc.nfev - 2) // 6          # 6 evaluations an attempt (FSAL) + 2 at the start
    # references: scipy DOP853 (independent of eomgen) and eomgen DOPRI5, both tight
    tr, ref = timed(lambda: solve_ivp(sim.rhs, (0.0, CART_T), x0, method="DOP853", rtol=1e-13,
                                      atol=1e-14, t_eval=grid))
    Xref = ref.y.T
    _, Xe = sim.simulate(x0, CART_T, CART_DT, method="dopri5", rtol=1e-13, atol=1e-14,
                         max_steps=BIG)
    Xs = sol.y.T
    err = {"eomgen": (float(np.max(np.abs(X - Xref))), float(np.max(np.abs(X[-1] - Xref[-1])))),
           "scipy": (float(np.max(np.abs(Xs - Xref))), float(np.max(np.abs(Xs[-1] - Xref[-1]))))}
    res = {
        "eomgen": {"time": med["eomgen"], "time_min": mins["eomgen"], **st,
                   "err_all_rows": err["eomgen"][0], "err_final": err["eomgen"][1]},
        "scipy": {"time": med["scipy"], "time_min": mins["scipy"], "nfev": int(sol.nfev),
                  "n_accepted": rk45_acc, "n_rejected": rk45_att - rk45_acc,
                  "err_all_rows": err["scipy"][0], "err_final": err["scipy"][1]},
        "reference": "solve_ivp DOP853 rtol 1e-13 atol 1e-14 over sim.rhs, t_eval = the grid",
        "reference_time": tr, "reference_nfev": int(ref.nfev),
        "reference_vs_eomgen_dopri5_1e-13": float(np.max(np.abs(Xe - Xref))),
        "eomgen_vs_scipy_all_rows": float(np.max(np.abs(X - Xs))),
    }
    # the output grid does not drive the steps any more
    grids = {}
    gfns = {}
    for dt in (0.1, 0.01, 0.001):
        gfns[dt] = (lambda dt=dt: tsx(sim.simulate(x0, CART_T, dt, method="dopri5",
                                                    rtol=CART_RTOL, atol=CART_ATOL)))
    gfns["final_only"] = lambda: tsx(sim.simulate(x0, CART_T, CART_DT, method="dopri5",
                                                  rtol=CART_RTOL, atol=CART_ATOL,
                                                  final_only=True))
    gmed, _, glast = interleaved(gfns, reps)
    for k, (Tg, Xg, stg) in glast.items():
        grids[str(k)] = {"dt": CART_DT if k == "final_only" else k, "rows": len(Tg),
                         "time": gmed[k], **stg,
                         "final_diff_vs_dt0.01": float(np.max(np.abs(Xg[-1] - X[-1])))}
    res["grids"] = grids
    # the step sequence is sensitive to tiny changes (a rejection more or less
    # shifts all later steps): the same comparison over a band of rtol, and
    # RK45 started with eomgen's first step (Hairer's, max norms, no second
    # evaluation: emulated here) instead of its own
    f0 = sim.rhs(0.0, x0)
    sc = CART_ATOL + CART_RTOL * np.abs(x0)
    h0 = 0.01 * np.max(np.abs(x0) / sc) / np.max(np.abs(f0) / sc)
    res["eomgen_first_step"] = float(h0)
    res["rk45_first_step"] = float(solc.sol.ts[1])
    sweep = []
    for f in sweep_factors:
        rt = CART_RTOL * f
        sol = sim.simulate(x0, CART_T, CART_DT, method="dopri5", rtol=rt, atol=CART_ATOL)
        _, Xf, stf = sol.t, sol.x, sol.stats
        sf = solve_ivp(sim.rhs, (0.0, CART_T), x0, method="RK45", rtol=rt, atol=CART_ATOL,
                       t_eval=grid)
        sh = solve_ivp(sim.rhs, (0.0, CART_T), x0, method="RK45", rtol=rt, atol=CART_ATOL,
                       t_eval=grid, first_step=h0)
        sweep.append({"rtol": rt, "eomgen_n_rhs": stf["n_rhs"], "rk45_nfev": int(sf.nfev),
                      "rk45_h0_nfev": int(sh.nfev),
                      "eomgen_err": float(np.max(np.abs(Xf - Xref))),
                      "rk45_err": float(np.max(np.abs(sf.y.T - Xref))),
                      "rk45_h0_err": float(np.max(np.abs(sh.y.T - Xref)))})
    res["sweep"] = sweep
    return res


def report_cart(r):
    e, s = r["eomgen"], r["scipy"]
    rows = [["eomgen DOPRI5 (C)", e["n_rhs"], e["n_accepted"], e["n_rejected"], ms(e["time"]),
             e2(e["err_all_rows"]), e2(e["err_final"])],
            ["solve_ivp RK45 over sim.rhs", s["nfev"], s["n_accepted"], s["n_rejected"],
             ms(s["time"]), e2(s["err_all_rows"]), e2(s["err_final"])]]
    out = [f"### 1. Dense output: n = {CART_N} cart, {CART_T:g} s, rtol {CART_RTOL:g}, "
           f"atol {CART_ATOL:g}, output every {CART_DT:g} s\n",
           md_table(["solver", "rhs evals", "accepted", "rejected", "time (ms, median)",
                     "max abs error, all 1001 rows", "max abs error at t = 10"], rows),
           "",
           f"- rhs evals eomgen / RK45: **{e['n_rhs'] / s['nfev']:.3f}**; error eomgen / RK45: "
           f"all rows **{e['err_all_rows'] / s['err_all_rows']:.3g}**, at t = 10 "
           f"**{e['err_final'] / s['err_final']:.3g}**; time RK45 / eomgen: "
           f"{s['time'] / e['time']:.0f}",
           f"- acceptance (eomgen evals <= RK45's with an error <= RK45's): "
           f"evals {'yes' if e['n_rhs'] <= s['nfev'] else 'NO'}, error (all rows) "
           f"{'yes' if e['err_all_rows'] <= s['err_all_rows'] else 'NO'}, error (t = 10) "
           f"{'yes' if e['err_final'] <= s['err_final'] else 'NO'}",
           f"- reference: {r['reference']} ({r['reference_nfev']} evals); it agrees with eomgen "
           f"DOPRI5 at rtol 1e-13, atol 1e-14 to {e2(r['reference_vs_eomgen_dopri5_1e-13'])} "
           f"over all rows; eomgen and RK45 differ by {e2(r['eomgen_vs_scipy_all_rows'])}",
           "",
           "Output grid (eomgen DOPRI5, same run, C):\n"]
    rows = []
    for k, g in r["grids"].items():
        rows.append([("final_only (dt 0.01)" if k == "final_only" else f"{g['dt']:g}"), g["rows"],
                     g["n_rhs"], g["n_accepted"], g["n_rejected"], ms(g["time"]),
                     e2(g["final_diff_vs_dt0.01"])])
    out.append(md_table(["output every (s)", "rows", "rhs evals", "accepted", "rejected",
                         "time (ms, median)", "x(10) diff vs dt 0.01"], rows))
    sw = r["sweep"]
    out += ["", f"rtol band (atol {CART_ATOL:g}; error = max abs over all rows vs the reference; "
                f"'RK45, eomgen h0' = solve_ivp RK45 with first_step = eomgen's first step "
                f"{r['eomgen_first_step']:.2g} s instead of its own {r['rk45_first_step']:.2g} s):\n"]
    rows = [[f"{v['rtol']:.3g}", v["eomgen_n_rhs"], v["rk45_nfev"], v["rk45_h0_nfev"],
             f"{v['eomgen_n_rhs'] / v['rk45_nfev']:.3f}", e2(v["eomgen_err"]), e2(v["rk45_err"]),
             e2(v["rk45_h0_err"])] for v in sw]
    med = {k: statistics.median(v[k] for v in sw) for k in sw[0]}
    rows.append(["**median**", g3(med["eomgen_n_rhs"]), g3(med["rk45_nfev"]),
                 g3(med["rk45_h0_nfev"]), f"{med['eomgen_n_rhs'] / med['rk45_nfev']:.3f}",
                 e2(med["eomgen_err"]), e2(med["rk45_err"]), e2(med["rk45_h0_err"])])
    out.append(md_table(["rtol", "eomgen DOPRI5 evals", "RK45 evals", "RK45, eomgen h0, evals",
                         "eomgen / RK45 evals", "eomgen error", "RK45 error",
                         "RK45, eomgen h0, error"], rows))
    n_le = sum(v["eomgen_n_rhs"] <= v["rk45_nfev"] for v in sw)
    n_eq = sum(v["eomgen_n_rhs"] == v["rk45_h0_nfev"] for v in sw)
    n_el = sum(v["eomgen_err"] <= v["rk45_err"] for v in sw)
    out.append(f"\n- over the band: eomgen evals <= RK45's at {n_le} of {len(sw)} tolerances, "
               f"error <= RK45's at {n_el} of {len(sw)}; with eomgen's first step RK45 takes "
               f"exactly eomgen's count at {n_eq} of {len(sw)}")
    return "\n".join(out)


# ---------------------------------------------------------------- 2. stiff
def bench_stiff(sim, reps):
    from scipy.integrate import solve_ivp
    x0 = np.array([1.0, 0.0, 0.0, 0.0])
    nrows = int(round(STIFF_T / STIFF_DT)) + 1
    grid = np.linspace(0.0, STIFF_T, nrows)

    def jac(t, x):
        return sim.jacobian(t, x)[0]

    def eom(method):
        return lambda: tsx(sim.simulate(x0, STIFF_T, STIFF_DT, method=method, rtol=STIFF_TOL,
                                        atol=STIFF_TOL, max_steps=BIG))

    def sp(method):
        return lambda: solve_ivp(sim.rhs, (0.0, STIFF_T), x0, method=method, rtol=STIFF_TOL,
                                 atol=STIFF_TOL, jac=jac, t_eval=grid)

    fns = {"dopri5": eom("dopri5"), "rodas4": eom("rodas4"), "radau": sp("Radau"),
           "bdf": sp("BDF")}
    med, mins, last = interleaved(fns, reps)
    # references
    tr1, (Tr, Xr, str1) = timed(lambda: tsx(sim.simulate(x0, STIFF_T, STIFF_DT,
                                                         method="rodas4", rtol=1e-10,
                                                         atol=1e-10, max_steps=BIG)))
    tr2, (_, Xd, str2) = timed(lambda: tsx(sim.simulate(x0, STIFF_T, STIFF_DT, method="dopri5",
                                                        rtol=1e-11, atol=1e-11,
                                                        max_steps=BIG)))
    res = {"reference": "eomgen RODAS4 rtol = atol = 1e-10",
           "reference_stats": str1, "reference_time": tr1,
           "check": "eomgen DOPRI5 rtol = atol = 1e-11", "check_stats": str2, "check_time": tr2,
           "reference_vs_check_final": float(np.max(np.abs(Xr[-1] - Xd[-1]))),
           "reference_vs_check_all_rows": float(np.max(np.abs(Xr - Xd))),
           "x_final_reference": Xr[-1].tolist()}
    for k in ("dopri5", "rodas4"):
        T, X, st = last[k]
        res[k] = {"time": med[k], "time_min": mins[k], **st,
                  "err_final": float(np.max(np.abs(X[-1] - Xr[-1]))),
                  "err_final_q": float(np.max(np.abs(X[-1, :2] - Xr[-1, :2]))),
                  "err_all_rows": float(np.max(np.abs(X - Xr)))}
    for k, meth in (("radau", "Radau"), ("bdf", "BDF")):
        sol = last[k]
        solc = solve_ivp(sim.rhs, (0.0, STIFF_T), x0, method=meth, rtol=STIFF_TOL,
                         atol=STIFF_TOL, jac=jac, dense_output=True)      # for the step count
        Xs = sol.y.T
        res[k] = {"time": med[k], "time_min": mins[k], "status": int(sol.status),
                  "nfev": int(sol.nfev), "njev": int(sol.njev), "nlu": int(sol.nlu),
                  "n_accepted": len(solc.sol.ts) - 1,
                  "err_final": float(np.max(np.abs(Xs[-1] - Xr[-1]))),
                  "err_final_q": float(np.max(np.abs(Xs[-1, :2] - Xr[-1, :2]))),
                  "err_all_rows": float(np.max(np.abs(Xs - Xr)))}
    d, r = res["dopri5"], res["rodas4"]
    res["ratio_evals"] = (d["n_rhs"] + d["n_jac"]) / (r["n_rhs"] + r["n_jac"])
    return res


def report_stiff(r):
    rows = []
    names = {"dopri5": "eomgen DOPRI5 (C)", "rodas4": "eomgen RODAS4 (C)",
             "radau": "solve_ivp Radau + sim.jacobian", "bdf": "solve_ivp BDF + sim.jacobian"}
    for k in ("dopri5", "rodas4", "radau", "bdf"):
        v = r[k]
        if k in ("dopri5", "rodas4"):
            rows.append([names[k], v["n_rhs"], v["n_jac"], "-", v["n_accepted"], v["n_rejected"],
                         ms(v["time"]), e2(v["err_final"]), e2(v["err_final_q"]),
                         e2(v["err_all_rows"])])
        else:
            rows.append([names[k], v["nfev"], v["njev"], v["nlu"], v["n_accepted"], "-",
                         ms(v["time"]), e2(v["err_final"]), e2(v["err_final_q"]),
                         e2(v["err_all_rows"])])
    d, ro = r["dopri5"], r["rodas4"]
    out = [f"### 2. Stiff double pendulum (elbow 1e4 x faster), {STIFF_T:g} s, rtol = atol = "
           f"{STIFF_TOL:g}, output every {STIFF_DT:g} s\n",
           md_table(["solver", "rhs evals", "Jacobians", "LU", "accepted steps", "rejected",
                     "time (ms, median)", "max abs error x(2)", "... of q1, q2 at t = 2",
                     "max abs error, all rows"], rows),
           "",
           f"- (DOPRI5 rhs + Jacobians) / (RODAS4 rhs + Jacobians) = {d['n_rhs'] + d['n_jac']} / "
           f"{ro['n_rhs'] + ro['n_jac']} = **{r['ratio_evals']:.3g}** (acceptance: >= 20: "
           f"{'yes' if r['ratio_evals'] >= 20 else 'NO'}); time DOPRI5 / RODAS4: "
           f"{d['time'] / ro['time']:.3g}; Radau / RODAS4: {r['radau']['time'] / ro['time']:.3g}",
           f"- reference: {r['reference']} ({r['reference_stats']['n_accepted']} steps); "
           f"{r['check']} ({r['check_stats']['n_rhs']} rhs) agrees with it to "
           f"{e2(r['reference_vs_check_final'])} at t = 2 "
           f"({e2(r['reference_vs_check_all_rows'])} over all rows)"]
    return "\n".join(out)


# ---------------------------------------------------------------- 3. events
def bench_events(sims, reps):
    from scipy.integrate import solve_ivp
    from scipy.special import ellipk
    from helpers import pendulum_state
    import seed_pendulum
    L, g = seed_pendulum.DEFAULTS["L"], seed_pendulum.DEFAULTS["g"]
    t_exact = math.sqrt(L / g) * float(ellipk(math.sin(EV_THETA0 / 2) ** 2))    # T / 4
    res = {"t_exact": t_exact, "theta0_deg": math.degrees(EV_THETA0)}
    for key, order in (("kane", "kane"), ("lagrange", "lagrange")):
        sim = sims[key]
        x0 = pendulum_state(EV_THETA0, 0.0, L, order)
        iq2 = list(sim.state_names).index("q2")

        def eom(method, rtol, dt, project=True):
            return lambda: tsx(sim.simulate(x0, EV_T_END, dt, method=method, rtol=rtol,
                                            atol=EV_ATOL, events={"q2": 0}, terminal=True,
                                            max_steps=BIG, project=project), events=True)

        def ev(t, x):
            return x[iq2]
        ev.terminal = True
        ev.direction = 0

        def rk45():
            return solve_ivp(sim.rhs, (0.0, EV_T_END), x0, method="RK45", rtol=EV_RTOL,
                             atol=EV_ATOL, events=ev)

        fns = {"dopri5": eom("dopri5", EV_RTOL, 0.01), "rk4": eom("rk4", EV_RTOL, EV_RK4_DT),
               "scipy": rk45, "dopri5_noproj": eom("dopri5", EV_RTOL, 0.01, project=False)}
        med, mins, last = interleaved(fns, reps)
        out = {}
        for k in ("dopri5", "rk4", "dopri5_noproj"):
            _, _, evs, st = last[k]
            t_ev = evs[0][1]
            out[k] = {"t_event": t_ev, "rel_err": abs(t_ev - t_exact) / t_exact,
                      "n_rhs": st["n_rhs"], "n_accepted": st["n_accepted"],
                      "n_rejected": st["n_rejected"], "time": med[k], "time_min": mins[k],
                      "terminal": st.get("terminal")}
        sol = last["scipy"]
        t_ev = float(sol.t_events[0][0])
        solc = solve_ivp(sim.rhs, (0.0, EV_T_END), x0, method="RK45", rtol=EV_RTOL,
                         atol=EV_ATOL, events=ev, dense_output=True)     # for the step count
        out["scipy"] = {"t_event": t_ev, "rel_err": abs(t_ev - t_exact) / t_exact,
                        "nfev": int(sol.nfev), "time": med["scipy"], "time_min": mins["scipy"],
                        "n_accepted": len(solc.sol.ts) - 1,
                        "n_attempts": (int(solc.nfev) - 2) // 6}
        res[key] = out
    return res


def report_events(r):
    rows = []
    labels = (("dopri5", f"eomgen DOPRI5 rtol {EV_RTOL:g}"),
              ("rk4", f"eomgen RK4 dt {EV_RK4_DT:g}"),
              ("scipy", f"solve_ivp RK45 rtol {EV_RTOL:g} + events"),
              ("dopri5_noproj", f"(eomgen DOPRI5 rtol {EV_RTOL:g}, project=False)"))
    for key in ("kane", "lagrange"):
        for k, label in labels:
            v = r[key][k]
            rej = v["n_attempts"] - v["n_accepted"] if k == "scipy" else v["n_rejected"]
            rows.append([key, label, f"{v['t_event']:.15f}", e2(v["rel_err"]),
                         v["nfev"] if k == "scipy" else v["n_rhs"], v["n_accepted"], rej,
                         ms(v["time"])])
    out = [f"### 3. Events: seed pendulum from rest at {r['theta0_deg']:g} deg, first crossing "
           f"of q2 through 0 (events={{'q2': 0}}, terminal), atol {EV_ATOL:g}\n",
           f"Exact T/4 = sqrt(L/g) K(sin^2(theta0/2)) = {r['t_exact']:.15f} s\n",
           md_table(["model", "solver", "t of the event (s)", "relative error", "rhs evals",
                     "accepted", "rejected", "time (ms, median)"], rows), ""]
    for key in ("kane", "lagrange"):
        v = r[key]
        out.append(f"- {key}: relative error eomgen DOPRI5 / RK45 "
                   f"{v['dopri5']['rel_err'] / max(v['scipy']['rel_err'], 1e-300):.3g}, "
                   f"rhs evals {v['dopri5']['n_rhs'] / v['scipy']['nfev']:.3g} "
                   f"(project=False: {v['dopri5_noproj']['n_rhs'] / v['scipy']['nfev']:.3g}), "
                   f"time RK45 / eomgen DOPRI5 {v['scipy']['time'] / v['dopri5']['time']:.0f}")
    return "\n".join(out)


# ---------------------------------------------------------------- main
def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats (well under a minute)")
    ap.add_argument("--reps", type=int, help="repeats of every timed run (default 21, quick 3)")
    ap.add_argument("--json", help="write all numbers to this file")
    args = ap.parse_args()
    reps = args.reps or (3 if args.quick else 21)
    reps_slow = max(1, reps // 2) if not args.quick else 1   # the stiff runs (~0.1-1 s each)

    import gen
    import scipy
    t_start = time.perf_counter()
    cpu, cores = cpu_model()
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "cpu": cpu, "cores": cores, "python": platform.python_version(),
            "versions": {"eomgen": gen.__version__, "scipy": scipy.__version__,
                         "numpy": np.__version__},
            "quick": args.quick, "reps": reps, "reps_stiff": reps_slow}
    print(f"# {cpu} ({cores} logical cores), {meta['date']}, python {meta['python']}, "
          f"scipy {scipy.__version__}, numpy {np.__version__}, reps {reps} (stiff {reps_slow})",
          flush=True)
    sims, ctimes = compile_models()
    meta["compile_times"] = ctimes
    print("# compiled (eomgen cache applies): "
          + ", ".join(f"{k} {v:.2f} s" for k, v in ctimes.items()), flush=True)
    results = {"meta": meta}
    texts = []
    factors = ([0.9, 1.0, 1.1] if args.quick
               else [float(v) for v in np.round(np.linspace(0.9, 1.1, 11), 3)])
    results["cart"] = bench_cart(sims["cart"], reps, factors)
    texts.append(report_cart(results["cart"]))
    print("\n" + texts[-1], flush=True)
    results["stiff"] = bench_stiff(sims["stiff"], reps_slow)
    texts.append(report_stiff(results["stiff"]))
    print("\n" + texts[-1], flush=True)
    results["events"] = bench_events(sims, reps)
    texts.append(report_events(results["events"]))
    print("\n" + texts[-1], flush=True)
    meta["wall"] = time.perf_counter() - t_start
    print(f"\n# total {meta['wall']:.1f} s")
    results["table_markdown"] = "\n\n".join(texts)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1, default=str))
        print(f"all numbers: {args.json}")


if __name__ == "__main__":
    main()
