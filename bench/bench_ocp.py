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

Then opty's parameter-identification example problem (its examples-gallery
``plot_vyasarayani.py``, from Vyasarayani et al. 2011, section 3.1): the
pendulum y1' = y2, y2' = -p sin(y1), p = 10, y(0) = (pi/6, 0), 50 s sampled
at 5000 nodes (odeint), noise N(0, 0.05) on y1 and N(0, 0.1) on y2;
minimise the misfit of y1 over every node, midpoint, initial state free,
p free, the guess the noisy measurements and a random p in [0, 100) (seeded
here, the same for both). opty: its Problem with the objective and gradient
written as in the example; eomgen: gen.OptimalControl(..., method="midpoint",
parameters=[p], fit={y1: (t, y1_meas)}) on the same pendulum from
KanesMethod (unit mass and length, gravity p). The objectives differ by the
example's constant factor (the interval), so the minimisers are the same;
printed: build, solve, iterations, the recovered p of each, their
difference against the standard error of p (Gauss-Newton on the simulated
misfit, p and the initial state free), and the ratios.

    python bench/bench_ocp.py --problems ident [--ident-nodes 5000] [--seed 0]

Issue 47's brachistochrone (a particle under gravity steered by Fn (-vy,
vx), from rest at the origin to (2, -1) in minimum time, trapezoidal,
N = 201, |Fn| <= 10) from its two guesses (positions moving with zero
speeds in T = 1; the default guess), eomgen against the same trapezoidal
transcription in CasADi's Opti (explicit f; with --lifted also eomgen's
form, the slopes as unknowns, unscaled: it stalls as eomgen did): the
iterations, process (CPU) and wall times, the optimum and IPOPT's
infeasibilities at iteration 0.

    python bench/bench_ocp.py --problems brach [--repeat 5] [--lifted]

The large problem: a pendulum swing-up (Hermite-Simpson) at 1,001 and
--big-nodes nodes (100,001: minutes, about 2.5 GB): status, iterations,
times, peak memory, the objective against the coarse grid's.

    python bench/bench_ocp.py --problems big [--big-nodes 100001]
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


# ---------------------------------------- opty's parameter identification
IDENT = {"duration": 50.0, "p": 10.0, "y0": (np.pi / 6.0, 0.0), "noise": (0.05, 0.1)}


def ident_data(N, seed):
    """The example's data: odeint of the pendulum at N nodes, with its noise;
    and the p guess, 100 * uniform [0, 1), all from one seeded generator."""
    from scipy.integrate import odeint
    rng = np.random.default_rng(seed)
    time_ = np.linspace(0.0, IDENT["duration"], N)
    y = odeint(lambda y, t, p: [y[1], -p * np.sin(y[0])], IDENT["y0"], time_, args=(IDENT["p"],))
    y1 = y[:, 0] + rng.normal(scale=IDENT["noise"][0], size=N)
    y2 = y[:, 1] + rng.normal(scale=IDENT["noise"][1], size=N)
    return time_, y1, y2, 100.0 * rng.random()


def ident_standard_error(time_, p):
    """sigma / sqrt of the Gauss-Newton information of the y1 misfit, with p
    and the initial state free (odeint sensitivities by central differences)."""
    from scipy.integrate import odeint

    def y1(th):
        return odeint(lambda y, t, q: [y[1], -q * np.sin(y[0])], th[1:], time_, args=(th[0],),
                      rtol=1e-11, atol=1e-11)[:, 0]
    th0 = np.array([p, *IDENT["y0"]])
    J = np.empty((len(time_), 3))
    for i in range(3):
        d = np.zeros(3)
        d[i] = 1e-6
        J[:, i] = (y1(th0 + d) - y1(th0 - d)) / 2e-6
    cov = IDENT["noise"][0] ** 2 * np.linalg.inv(J.T @ J)
    return float(np.sqrt(cov[0, 0]))


def ident_ours(data, hessian="exact"):
    import gen
    from sympy.physics import mechanics as me
    time_, y1m, y2m, p0 = data
    N = len(time_)
    with tempfile.TemporaryDirectory() as d:
        os.environ["EOMGEN_CACHE"] = d
        try:
            t0 = time.perf_counter()
            y1, y2 = me.dynamicsymbols("y1 y2")
            p = sm.Symbol("p")
            A_ = me.ReferenceFrame("N")
            B_ = A_.orientnew("B", "axis", [y1, A_.z])
            B_.set_ang_vel(A_, y2 * A_.z)
            O = me.Point("O")
            O.set_vel(A_, 0)
            P = O.locatenew("P", B_.x)
            P.v2pt_theory(O, A_, B_)
            km = me.KanesMethod(A_, [y1], [y2], kd_eqs=[y1.diff() - y2])
            km.kanes_equations([me.Particle("m", P, 1)], [(P, p * A_.x)])
            model = gen.Model.from_kanes(km, constants={p: IDENT["p"]}, name="vyasarayani")
            ocp = gen.OptimalControl(model, N, IDENT["duration"], method="midpoint",
                                     parameters=[p], fit={y1: (time_, y1m)})
            t1 = time.perf_counter()
            sol = ocp.solve({y1: y1m, y2: y2m, p: p0}, hessian=hessian, tol=1e-8)
            t2 = time.perf_counter()
        finally:
            del os.environ["EOMGEN_CACHE"]
    return dict(build=t1 - t0, solve=t2 - t1, total=t2 - t0, iterations=sol.iterations,
                objective=sol.objective, status=sol.status, p=float(sol.p[0]))


def ident_opty(data):
    from opty.direct_collocation import Problem
    time_, y1m, y2m, p0 = data
    N = len(time_)
    interval = IDENT["duration"] / (N - 1)
    p, t = sm.symbols("p, t")
    y1, y2 = [f(t) for f in sm.symbols("y1, y2", cls=sm.Function)]
    eom = sm.Matrix([y1, y2]).diff(t) - sm.Matrix([y2, -p * sm.sin(y1)])

    def obj(free):
        return interval * np.sum((y1m - free[:N]) ** 2)

    def obj_grad(free):
        grad = np.zeros_like(free)
        grad[:N] = 2.0 * interval * (free[:N] - y1m)
        return grad
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as d:
        prob = Problem(obj, obj_grad, eom, (y1, y2), N, interval, time_symbol=t,
                       integration_method="midpoint", tmp_dir=d)
        t1 = time.perf_counter()
        prob.add_option("print_level", 0)
        prob.add_option("tol", 1e-8)
        solution, info = prob.solve(np.hstack((y1m, y2m, p0)))
        t2 = time.perf_counter()
    return dict(build=t1 - t0, solve=t2 - t1, total=t2 - t0, iterations=None,
                objective=info["obj_val"] / interval, status=info["status"],
                p=float(solution[-1]))


def run_ident(a):
    data = ident_data(a.ident_nodes, a.seed)
    se = ident_standard_error(data[0], IDENT["p"])
    o = median([ident_opty(data) for _ in range(a.opty_repeat)])
    e = median([ident_ours(data, "exact") for _ in range(a.repeat)])
    lm = median([ident_ours(data, "limited-memory") for _ in range(a.repeat)])
    print(f"\nopty's parameter identification (Vyasarayani 2011), N = {a.ident_nodes}, midpoint, "
          f"seed {a.seed}: true p = {IDENT['p']}, guess p = {data[3]:.4f}, standard error of p "
          f"{se:.2e}")
    print("| | build | solve (it) | total | recovered p | p - 10 | objective (sum of squares) "
          "| status |")
    print("|---|---|---|---|---|---|---|---|")
    for name, r in (("opty 1.5", o), ("eomgen, exact Hessian", e), ("eomgen, limited-memory", lm)):
        it = "" if r["iterations"] is None else f" ({r['iterations']})"
        print(f"| {name} | {r['build']:.2f} s | {r['solve']:.2f} s{it} | {r['total']:.2f} s | "
              f"{r['p']:.8f} | {r['p'] - IDENT['p']:+.2e} | {r['objective']:.8g} | "
              f"{r['status']} |")
    print(f"ratios eomgen (exact) / opty: build {e['build'] / o['build']:.3f}x, solve "
          f"{e['solve'] / o['solve']:.3f}x, total {e['total'] / o['total']:.3f}x; "
          f"|p_eomgen - p_opty| = {abs(e['p'] - o['p']):.1e} "
          f"({abs(e['p'] - o['p']) / se:.1e} standard errors); objectives' rel. diff "
          f"{abs(e['objective'] - o['objective']) / abs(o['objective']):.1e}")
    return dict(N=a.ident_nodes, seed=a.seed, se=se, p_guess=data[3], opty=o, exact=e,
                lbfgs=lm)


# ------------------------------------------------- the brachistochrone
BRACH = dict(N=201, g=9.81, fmax=10.0, T=(0.1, 5.0), end=(2.0, -1.0))


def brach_model():
    """A particle under gravity steered by Fn (-vy, vx) (no work): Kane's
    equations, unit mass."""
    import gen
    from sympy.physics import mechanics as me
    x, y, vx, vy, Fn = me.dynamicsymbols("x y v_x v_y F_n")
    g, m = sm.symbols("g m")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, vx * N.x + vy * N.y)
    km = me.KanesMethod(N, [x, y], [vx, vy], kd_eqs=[x.diff() - vx, y.diff() - vy])
    km.kanes_equations([me.Particle("p", P, m)],
                       [(P, -m * g * N.y + Fn * (-vy * N.x + vx * N.y))])
    model = gen.Model.from_kanes(km, constants={g: BRACH["g"], m: 1.0}, inputs=[Fn],
                                 name="brachistochrone")
    return model, (x, y, vx, vy, Fn)


def brach_guess(which, N):
    """The issue's two guesses as (positions, speeds, T): "positions" moves
    the positions linearly with zero speeds in T = 1; "default" is
    OptimalControl's (states linear between the boundary values, zero
    speeds, T the middle of its bounds)."""
    T = 1.0 if which == "positions" else 0.5 * sum(BRACH["T"])
    return np.linspace(0, BRACH["end"][0], N), np.linspace(0, BRACH["end"][1], N), T


def brach_ours(which, repeat):
    import gen
    model, (x, y, vx, vy, Fn) = brach_model()
    N = BRACH["N"]
    ocp = gen.OptimalControl(model, N, BRACH["T"], terminal_cost=sm.Symbol("t"),
                             method="trapezoidal", bounds={Fn: (-BRACH["fmax"], BRACH["fmax"])},
                             initial={x: 0, y: 0, vx: 0, vy: 0},
                             final={x: BRACH["end"][0], y: BRACH["end"][1]})
    X, Y, T = brach_guess(which, N)
    guess = {x: X, y: Y, "duration": T} if which == "positions" else None
    runs = []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        sol = ocp.solve(guess, tol=1e-8)
        runs.append(dict(wall=time.perf_counter() - t0, cpu=time.process_time() - c0,
                         iterations=sol.iterations, objective=sol.objective, status=sol.status,
                         inf_pr0=sol.first_iterate[0], inf_du0=sol.first_iterate[1]))
    return median(runs)


def brach_casadi(which, repeat, lifted=False):
    """The same trapezoidal transcription in CasADi's Opti: the explicit
    right-hand side f(x, u) in the defects, or (lifted) the slopes as
    unknowns with the equations of motion as constraints at every node, as
    eomgen transcribes them; the same guess, IPOPT's defaults, tol 1e-8."""
    import casadi as ca
    N, g = BRACH["N"], BRACH["g"]
    opti = ca.Opti()
    X, U, T = opti.variable(4, N), opti.variable(1, N), opti.variable()
    h = T / (N - 1)

    def f(x, u):
        return ca.vertcat(x[2], x[3], -u * x[3], -g + u * x[2])
    if lifted:
        S = opti.variable(4, N)
        for k in range(N):
            opti.subject_to(S[:, k] - f(X[:, k], U[k]) == 0)
        slope = [S[:, k] for k in range(N)]
        opti.set_initial(S[3, :], -g)
    else:
        slope = [f(X[:, k], U[k]) for k in range(N)]
    for k in range(N - 1):
        opti.subject_to(X[:, k + 1] - X[:, k] - h / 2 * (slope[k] + slope[k + 1]) == 0)
    opti.subject_to(X[:, 0] == 0)
    opti.subject_to(X[0, -1] == BRACH["end"][0])
    opti.subject_to(X[1, -1] == BRACH["end"][1])
    opti.subject_to(opti.bounded(-BRACH["fmax"], U, BRACH["fmax"]))
    opti.subject_to(opti.bounded(BRACH["T"][0], T, BRACH["T"][1]))
    opti.minimize(T)
    Xg, Yg, Tg = brach_guess(which, N)
    opti.set_initial(T, Tg)
    opti.set_initial(X[0, :], Xg)
    opti.set_initial(X[1, :], Yg)
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": 1e-8,
                                                 "max_iter": 3000})
    runs = []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        sol = opti.solve_limited()
        st = sol.stats()
        runs.append(dict(wall=time.perf_counter() - t0, cpu=time.process_time() - c0,
                         iterations=st["iter_count"], objective=float(sol.value(T)),
                         status=st["return_status"],
                         inf_pr0=st["iterations"]["inf_pr"][0],
                         inf_du0=st["iterations"]["inf_du"][0]))
    return median(runs)


def run_brach(a):
    """eomgen and CasADi on the issue 47 brachistochrone, both guesses."""
    print(f"\nbrachistochrone (trapezoidal, N = {BRACH['N']}, |Fn| <= {BRACH['fmax']}, min T; "
          f"medians of {a.repeat}; CPU = process time, the peers single-threaded)")
    print("| guess | solver | iterations | CPU | wall | T* | inf_pr, inf_du at iteration 0 |")
    print("|---|---|---|---|---|---|---|")
    out = {}
    for which in ("positions", "default"):
        rows = {"eomgen": brach_ours(which, a.repeat),
                "CasADi (explicit f)": brach_casadi(which, a.repeat)}
        if a.lifted:
            rows["CasADi (lifted, eomgen's form, unscaled)"] = brach_casadi(which, 1, True)
        for name, r in rows.items():
            print(f"| {which} | {name} | {r['iterations']} | {r['cpu']:.3f} s | {r['wall']:.3f} s "
                  f"| {r['objective']:.12f} | {r['inf_pr0']:.3g}, {r['inf_du0']:.3g} |", flush=True)
        e, c = rows["eomgen"], rows["CasADi (explicit f)"]
        print(f"| {which} | ratio eomgen / CasADi | {e['iterations'] / c['iterations']:.2f}x | "
              f"{e['cpu'] / c['cpu']:.2f}x | {e['wall'] / c['wall']:.2f}x | "
              f"{abs(e['objective'] - c['objective']):.1e} | "
              f"{e['inf_pr0'] / c['inf_pr0']:.2f}x |")
        out[which] = rows
    return out


# ------------------------------------------- the 100,000-node swing-up
def pendulum_swing_up(nodes):
    """A pendulum (unit mass and length) swung up from hanging to upright
    in 4 s by a torque |tau| <= 6, minimum integral tau^2, Hermite-Simpson:
    (its OptimalControl, build seconds)."""
    import gen
    from sympy.physics import mechanics as me
    th, om, tau = me.dynamicsymbols("theta omega tau")
    m, l, g = sm.symbols("m l g")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    A.set_ang_vel(N, om * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", -l * A.y)
    P.v2pt_theory(O, N, A)
    km = me.KanesMethod(N, [th], [om], kd_eqs=[th.diff() - om])
    km.kanes_equations([me.Particle("p", P, m)], [(P, -m * g * N.y), (A, tau * N.z)])
    model = gen.Model.from_kanes(km, constants={m: 1.0, l: 1.0, g: 9.81}, inputs=[tau],
                                 name="pendulum_swing_up")
    t0 = time.perf_counter()
    ocp = gen.OptimalControl(model, nodes, 4.0, objective=tau**2, method="hermite-simpson",
                             bounds={tau: (-6, 6)}, initial={th: 0, om: 0},
                             final={th: sm.pi, om: 0})
    return ocp, time.perf_counter() - t0


def run_big(a):
    """The pendulum swing-up at 1,001 nodes and at --big-nodes (100,001):
    status, iterations, times, peak memory, the objective against the
    coarse one (Hermite-Simpson converges to the same optimum)."""
    import resource
    print(f"\npendulum swing-up (Hermite-Simpson, 4 s, |tau| <= 6, min int tau^2)")
    print("| nodes | unknowns | status | iterations | build | solve (CPU) | peak RSS | objective |")
    print("|---|---|---|---|---|---|---|---|")
    out = []
    for nodes in (1001, a.big_nodes):
        ocp, build = pendulum_swing_up(nodes)
        t0, c0 = time.perf_counter(), time.process_time()
        sol = ocp.solve()
        r = dict(nodes=nodes, unknowns=ocp._lay.n, status=sol.status, message=sol.message,
                 iterations=sol.iterations, build=build, solve=time.perf_counter() - t0,
                 cpu=time.process_time() - c0, objective=sol.objective,
                 rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
        print(f"| {nodes:,} | {r['unknowns']:,} | {r['status']} | {r['iterations']} | "
              f"{build:.2f} s | {r['solve']:.1f} s ({r['cpu']:.1f} s) | {r['rss_mb']:.0f} MB | "
              f"{r['objective']:.10f} |", flush=True)
        out.append(r)
    return out


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
    ap.add_argument("--problems", nargs="+", default=["swing-up", "ident", "brach"],
                    choices=["swing-up", "ident", "brach", "big"])
    ap.add_argument("--big-nodes", type=int, default=100001,
                    help="big: the nodes of the large pendulum swing-up (minutes)")
    ap.add_argument("--lifted", action="store_true",
                    help="brach: also CasADi on eomgen's lifted form (stalls: minutes)")
    ap.add_argument("--ident-nodes", type=int, default=5000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json")
    a = ap.parse_args(argv)
    rows = []
    for N in (a.nodes if "swing-up" in a.problems else []):
        for method in a.methods:
            o = median([opty(N, method) for _ in range(a.opty_repeat)])
            e = median([ours(N, method, "exact") for _ in range(a.repeat)])
            lm = median([ours(N, method, "limited-memory") for _ in range(a.repeat)])
            rows.append(dict(N=N, method=method, opty=o, exact=e, lbfgs=lm))
            print(f"N={N} {method}: opty build {o['build']:.2f}s solve {o['solve']:.2f}s "
                  f"obj {o['objective']:.10g} | eomgen exact build {e['build']:.2f}s solve "
                  f"{e['solve']:.2f}s it {e['iterations']} obj {e['objective']:.10g} | "
                  f"limited-memory solve {lm['solve']:.2f}s it {lm['iterations']}", flush=True)
    if rows:
        table(rows)
    ident = run_ident(a) if "ident" in a.problems else None
    brach = run_brach(a) if "brach" in a.problems else None
    big = run_big(a) if "big" in a.problems else None
    if a.json:
        Path(a.json).write_text(json.dumps({"swing_up": rows, "ident": ident, "brach": brach,
                                            "big": big}, indent=1))


def table(rows):
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


if __name__ == "__main__":
    main()
