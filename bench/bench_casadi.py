"""IPOPT time per iteration: gen.casadi's step (the model's library, exact
Hessian through jac_adj1_/jac_jac_) against the same problem in pure CasADi
SX, in the same run (issue 36).

The problem: move the n-link cart (examples/n_link_cart.py; n = 1 is a
cart-pole) from hanging down to upright in N h seconds with minimum effort,
multiple shooting in casadi.Opti, one RK4 step per interval, IPOPT with
hessian_approximation="exact". The pure-SX peer is the same model's M and f
lambdified onto SX (sympy's cse, sin/cos -> casadi), x' = [u; solve(M, f)]
(CasADi's symbolic solve), and the same RK4 by hand. Two ways to write the
shooting constraints, each on both sides: "map" (step.map(N) over the
intervals, one call node) and "calls" (one step call per interval). Prints
the median milliseconds per IPOPT iteration over the repeats (gen and SX
solved by turns), the ratio gen / SX (of the medians, and "paired": the
median of each repeat's ratio), and IPOPT's Hessian and constraint
Jacobian time per iteration (t_wall_nlp_hess_l, t_wall_nlp_jac_g).

    python bench/bench_casadi.py [--n 1 4] [--repeats 5] [--form map calls]
"""
import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "examples")]

import casadi as ca  # noqa: E402
import sympy as sm  # noqa: E402

import gen.casadi as gc  # noqa: E402
import n_link_cart  # noqa: E402


def sx_rhs(model):
    """x' of the model in SX: M and f lambdified (the model's own
    expressions), q' = u (the n-link cart's kinematics)."""
    ns = {"sin": ca.sin, "cos": ca.cos}
    args = [list(model.q) + list(model.u), list(model.r), list(model.p)]
    fM = sm.lambdify(args, list(model.M), modules=[ns], cse=True)
    ff = sm.lambdify(args, list(model.f), modules=[ns], cse=True)
    X, R, P = ca.SX.sym("x", model.nx), ca.SX.sym("r", model.nr), ca.SX.sym("p", model.np)
    a = [[X[i] for i in range(model.nx)], [R[i] for i in range(model.nr)],
         [P[i] for i in range(model.np)]]
    M = ca.reshape(ca.vertcat(*fM(*a)), model.nu, model.nu).T
    f = ca.vertcat(*ff(*a))
    return ca.Function("f", [X, R, P], [ca.vertcat(X[model.nq:], ca.solve(M, f))])


def solve(model, step_all, N, h, max_iter=300, form="map"):
    """One Opti problem, solved twice: (objective, iterations, seconds of the
    second solve, status, seconds of the first, {t_wall_nlp_*: seconds}).
    form "map": step_all(X[:, :-1], U) maps over the intervals (one call
    node); "calls": step_all(X[:, k], U[:, k], k) once per interval."""
    opti = ca.Opti()
    nx = model.nx
    X = opti.variable(nx, N + 1)
    U = opti.variable(1, N)
    opti.minimize(h * ca.sumsqr(U))
    if form == "map":
        opti.subject_to(X[:, 1:] == step_all(X[:, :-1], U))
    else:
        for k in range(N):
            opti.subject_to(X[:, k + 1] == step_all(X[:, k], U[:, k], k))
    x0 = np.zeros(nx)
    x0[1:model.nq] = np.pi
    opti.subject_to(X[:, 0] == x0)
    opti.subject_to(X[:, N] == np.zeros(nx))
    opti.subject_to(opti.bounded(-40, U, 40))
    for i in range(1, model.nq):
        opti.set_initial(X[i, :], np.linspace(np.pi, 0, N + 1))
    opti.solver("ipopt", {"print_time": False, "record_time": True},
                {"print_level": 0, "sb": "yes", "tol": 1e-8, "max_iter": max_iter,
                 "hessian_approximation": "exact"})
    t0 = time.perf_counter()
    sol = opti.solve_limited()          # builds the solver (CasADi's setup) and solves
    dt0 = time.perf_counter() - t0
    t0 = time.perf_counter()
    sol = opti.solve_limited()          # the same solve again, the solver built
    dt = time.perf_counter() - t0
    st = sol.stats()
    parts = {k[len("t_wall_"):]: v for k, v in st.items() if k.startswith("t_wall_nlp_")}
    return sol.value(opti.f), st["iter_count"], dt, st["return_status"], dt0, parts


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, nargs="+", default=[1, 4])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--N", type=int, default=100)
    ap.add_argument("--form", nargs="+", default=["map", "calls"], choices=["map", "calls"],
                    help="step mapped over the intervals (one call node), or one call per "
                         "interval; both by default")
    ap.add_argument("--max-iter", type=int, default=50,
                    help="IPOPT's iteration limit (the n-link swing-ups need hundreds; the "
                         "time per iteration is the measure)")
    a = ap.parse_args()
    h = 2.0 / a.N
    print("| n | form | gen ms/iteration | pure SX ms/iteration | gen / SX | paired | "
          "with setup: gen / SX | hess_l ms/it (gen, SX) | jac_g ms/it (gen, SX) | "
          "iterations (gen, SX) | objective (gen, SX) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for n in a.n:
        model = n_link_cart.model(n)
        p = np.array(model.p_values, float)
        step1 = gc.functions(model)["step"]
        step = step1.map(a.N)
        f = sx_rhs(model)
        Xs, Us, Hs = ca.SX.sym("x", model.nx), ca.SX.sym("u"), ca.SX.sym("h")
        k1 = f(Xs, Us, p)
        k2 = f(Xs + Hs / 2 * k1, Us, p)
        k3 = f(Xs + Hs / 2 * k2, Us, p)
        k4 = f(Xs + Hs * k3, Us, p)
        step_sx1 = ca.Function("step_sx", [Xs, Us, Hs], [Xs + Hs / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
        step_sx = step_sx1.map(a.N)
        tk = (np.arange(a.N) * h).reshape(1, -1)
        peers = {"map": (lambda X, U: step(X, U, p, tk, h), lambda X, U: step_sx(X, U, h)),
                 "calls": (lambda X, U, k: step1(X, U, p, k * h, h),
                           lambda X, U, k: step_sx1(X, U, h))}
        runs = {(form, who): [] for form in a.form for who in (0, 1)}
        for _ in range(a.repeats):
            for form in a.form:             # gen and SX by turns, in the same run
                for who in (0, 1):
                    runs[form, who].append(solve(model, peers[form][who], a.N, h, a.max_iter,
                                                 form))
        for form in a.form:
            ours, ref = runs[form, 0], runs[form, 1]

            def per_it(rs, key=None):
                if key is None:
                    return statistics.median(1e3 * r[2] / max(1, r[1]) for r in rs)
                return statistics.median(1e3 * r[5].get(key, 0) / max(1, r[1]) for r in rs)
            g, s_ = per_it(ours), per_it(ref)
            # the median of each repeat's ratio (gen and SX solved back to back)
            pr = statistics.median((a[2] / max(1, a[1])) / (b[2] / max(1, b[1]))
                                   for a, b in zip(ours, ref))
            g0 = statistics.median(r[4] for r in ours)
            s0 = statistics.median(r[4] for r in ref)
            print(f"| {n} | {form} | {g:.2f} | {s_:.2f} | {g / s_:.2f} | {pr:.2f} | {g0 / s0:.2f} | "
                  f"{per_it(ours, 'nlp_hess_l'):.2f}, {per_it(ref, 'nlp_hess_l'):.2f} | "
                  f"{per_it(ours, 'nlp_jac_g'):.2f}, {per_it(ref, 'nlp_jac_g'):.2f} | "
                  f"{ours[0][1]}, {ref[0][1]} | {ours[0][0]:.8g}, {ref[0][0]:.8g} "
                  f"({ours[0][3]}, {ref[0][3]}) |", flush=True)


if __name__ == "__main__":
    main()
