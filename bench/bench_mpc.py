"""gen.MPC next to acados on the same problems, in one run (issue 43).

    python bench/bench_mpc.py [--problems cartpole quadrotor] [--steps 200] [--json out.json]

acados lives in a virtual environment of its own (comma-deps-acados
0.2.2.post92, then casadi 3.7.2 over it: the wheel's own casadi is built for
Python 3.12), found at $EOMGEN_ACADOS_VENV (default /work/venvs/acados):

    python3 -m venv /work/venvs/acados
    /work/venvs/acados/bin/pip install comma-deps-acados==0.2.2.post92
    /work/venvs/acados/bin/pip install casadi==3.7.2

This script runs itself there as a worker (``--acados-worker``), with the
source tree acados_template expects made of links (lib, include, bin and
interfaces/acados_template/acados_template) in a temporary folder,
ACADOS_SOURCE_DIR and LD_LIBRARY_PATH set, and acados.TEMPLATE_DIR's parent
on sys.path. The model reaches acados as CasADi expressions printed from
the same sympy model (its explicit right-hand side, the constants
substituted).

Each problem: the same cost (acados's LINEAR_LS with W = 2 diag(Q, R),
scaled by the interval as acados does, W_e = 2 P: the same J), horizon,
integrator (ERK, 4 stages: classic RK4, `substeps` steps per interval),
bounds, Gauss-Newton Hessian, SQP_RTI with PARTIAL_CONDENSING_HPIPM (QP
tolerances 1e-10); acados given the same shifted warm start (the previous
solution shifted by one interval, the last repeated; zeros at the start).
A closed loop of --steps periods from the same start against the same
plant (RK4, 10 steps per period, the model's C for eomgen, the same CasADi
expression for acados): the applied controls compared at every step
(largest difference relative to the largest control), the time per RTI
(medians: eomgen's phases measured in its C, acados's time_tot of its
rti_phase 1 and 2), the feedback phase alone, and the ratios.

Problems: the cart-pole (examples/cart_pole.py; N = 20, Tf = 1 s, |F| <= 20,
from 0.4 rad off upright), and the quadrotor (examples/quadrotor.py with the
Euler-rate kinematics; 12 states, 4 inputs, N = 20, period 0.05 s, thrust and
torques bounded, along a figure-eight).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ACADOS_VENV = Path(os.environ.get("EOMGEN_ACADOS_VENV", "/work/venvs/acados"))


# --------------------------------------------------------------- problems
def _example(name):
    import importlib.util
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def explicit_rhs(model):
    """The model's x' = f(x, u) as strings of x0.., u0.. (its constants
    substituted), for CasADi: q' from the kinematics, u' = M^-1 f."""
    import sympy as sm
    m = model
    sub = dict(zip(m.p, m.p_values))
    q, u = sm.Matrix(m.q), sm.Matrix(m.u)
    if m.qdot is not None:
        qd = sm.Matrix(m.qdot)
    else:
        qd = m.Kqd.LUsolve(-(m.Ku * u + m.kf))
    ud = m.M.LUsolve(m.f)
    xs = sm.symbols(f"x0:{m.nx}")
    us = sm.symbols(f"u0:{m.nr}")
    ren = {**dict(zip(list(m.q) + list(m.u), xs)), **dict(zip(m.r, us)), m.t: 0}
    return [str(sm.sympify(e).xreplace(sub).xreplace(ren)) for e in list(qd) + list(ud)]


def cartpole_problem(steps):
    import sympy as sm  # noqa: F401
    cp = _example("cart_pole")
    model = cp.model()
    N, period = 20, 0.05
    Q = np.diag([10.0, 10.0, 0.1, 0.1])
    R = np.diag([0.05])
    return {"name": "cartpole", "model": model, "N": N, "period": period, "substeps": 1,
            "Q": Q, "R": R, "P": 5 * Q, "bounds": {"F": (-20.0, 20.0)},
            "x0": [0.0, 0.4, 0.0, 0.0], "steps": steps,
            "ref": lambda t: (np.zeros(4), np.zeros(1))}


def figure_eight(t, period_s=8.0, a=1.0, hover=None):
    """A figure-eight in the horizontal plane at 1 m: x = a sin(w t),
    y = a/2 sin(2 w t); velocities the derivatives; attitude level."""
    w = 2 * np.pi / period_s
    x = np.zeros(12)
    x[3], x[4], x[5] = a * np.sin(w * t), 0.5 * a * np.sin(2 * w * t), 1.0
    x[9], x[10] = a * w * np.cos(w * t), a * w * np.cos(2 * w * t)
    return x, np.array(hover)


def quadrotor_problem(steps):
    qr = _example("quadrotor")
    model = qr.model(kinematics="euler")
    hover = qr.hover_input()
    N, period = 20, 0.05
    Q = np.diag([1, 1, 1, 20, 20, 20, 0.1, 0.1, 0.1, 1, 1, 1.0])
    R = np.diag([0.1, 10, 10, 10.0])
    bounds = {"T": (0.0, 2.5 * hover[0]), "tau1": (-0.5, 0.5), "tau2": (-0.5, 0.5),
              "tau3": (-0.2, 0.2)}
    return {"name": "quadrotor", "model": model, "N": N, "period": period, "substeps": 1,
            "Q": Q, "R": R, "P": 5 * Q, "bounds": bounds, "steps": steps,
            "x0": np.r_[0, 0, 0, 0, 0, 1.0, np.zeros(6)],
            "ref": lambda t: figure_eight(t, hover=hover)}


# ----------------------------------------------------------------- eomgen
def run_ours(pb):
    """gen.MPC's closed loop against the RK4 plant: controls, phase times."""
    import gen
    model = pb["model"]
    N, period, steps = pb["N"], pb["period"], pb["steps"]
    ts = period * np.arange(steps + N + 1)
    X = np.array([pb["ref"](t)[0] for t in ts])
    U = np.array([pb["ref"](t)[1] for t in ts])
    t0 = time.perf_counter()
    mpc = gen.MPC(model, N, period, pb["Q"], pb["R"], P=pb["P"], bounds=pb["bounds"],
                  reference=(ts, X, U), substeps=pb["substeps"])
    build = time.perf_counter() - t0
    sim = gen.compile(model, derivatives=True)
    x = np.array(pb["x0"], dtype=float)
    us, prep, fb, xs = [], [], [], [x.copy()]
    h = period / 10
    for k in range(steps):
        u = mpc(x, t=k * period)
        us.append(u)
        prep.append(mpc.times.prepare)
        fb.append(mpc.times.feedback)
        for j in range(10):
            x = sim.step(k * period + j * h, x, h, r=u)
        xs.append(x.copy())
    # the same loop closed in C (sim.simulate, the engine calling the controller)
    sol = sim.simulate(np.array(pb["x0"], float), steps * period, h, controller=mpc)
    return {"u": np.array(us), "x": np.array(xs), "prepare": prep, "feedback": fb,
            "build": build, "u_c": sol.r[::10][:steps], "x_c": sol.x[::10]}


# ----------------------------------------------------------------- acados
def acados_python():
    """The acados venv's python, or None when it is not installed."""
    py = ACADOS_VENV / "bin" / "python"
    if not py.is_file():
        return None
    r = subprocess.run([str(py), "-c", "import acados, casadi"], capture_output=True)
    return py if r.returncode == 0 else None


def run_acados(pb):
    """The same closed loop by acados (in its venv, a subprocess)."""
    py = acados_python()
    if py is None:
        raise RuntimeError(f"acados is not installed in {ACADOS_VENV} (see this file's "
                           "docstring)")
    model, N, period, steps = pb["model"], pb["N"], pb["period"], pb["steps"]
    ts = period * np.arange(steps + N + 1)
    job = {"rhs": explicit_rhs(model), "nx": model.nx, "nu": model.nr, "N": N,
           "period": period, "substeps": pb["substeps"], "Q": np.asarray(pb["Q"]).tolist(),
           "R": np.asarray(pb["R"]).tolist(), "P": np.asarray(pb["P"]).tolist(),
           "idxbu": [model.input_names.index(k) for k in pb["bounds"]],
           "lbu": [v[0] for v in pb["bounds"].values()],
           "ubu": [v[1] for v in pb["bounds"].values()],
           "x0": list(map(float, pb["x0"])), "steps": steps,
           "x_ref": [pb["ref"](t)[0].tolist() for t in ts],
           "u_ref": [pb["ref"](t)[1].tolist() for t in ts], "name": pb["name"]}
    with tempfile.TemporaryDirectory(prefix="eomgen-acados-") as d:
        d = Path(d)
        (d / "job.json").write_text(json.dumps(job))
        env = acados_env(py, d)
        r = subprocess.run([str(py), __file__, "--acados-worker", str(d)], capture_output=True,
                           text=True, timeout=1800, env=env)
        if r.returncode != 0:
            raise RuntimeError("the acados worker failed:\n" + r.stdout[-3000:] + r.stderr[-3000:])
        out = json.loads((d / "out.json").read_text())
    return {k: np.array(v) if isinstance(v, list) else v for k, v in out.items()}


def acados_env(py, root):
    """The worker's environment: acados_template's expected source tree made
    of links in root (lib, include, bin, interfaces/acados_template/
    acados_template), ACADOS_SOURCE_DIR and LD_LIBRARY_PATH (read by the
    loader when the worker starts)."""
    r = subprocess.run([str(py), "-c", "import acados, json; "
                        "print(json.dumps([acados.DIR, acados.TEMPLATE_DIR]))"],
                       capture_output=True, text=True, check=True)
    adir, tdir = json.loads(r.stdout)
    tree = Path(root) / "acados_src"
    (tree / "interfaces" / "acados_template").mkdir(parents=True)
    for sub in ("lib", "include", "bin"):
        os.symlink(os.path.join(adir, sub), tree / sub)
    os.symlink(tdir, tree / "interfaces" / "acados_template" / "acados_template")
    env = dict(os.environ)
    env["ACADOS_SOURCE_DIR"] = str(tree)
    env["LD_LIBRARY_PATH"] = str(tree / "lib") + (
        ":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
    env["PYTHONPATH"] = str(Path(tdir).parent)
    return env


def acados_worker(folder):
    """Runs in the acados venv: the job's closed loop by acados."""
    folder = Path(folder)
    job = json.loads((folder / "job.json").read_text())
    import acados
    sys.path.insert(0, str(Path(acados.TEMPLATE_DIR).parent))
    import casadi as cs
    from acados_template import AcadosModel, AcadosOcp, AcadosOcpSolver
    nx, nu, N = job["nx"], job["nu"], job["N"]
    x, u = cs.SX.sym("x", nx), cs.SX.sym("u", nu)
    env = {"sin": cs.sin, "cos": cs.cos, "tan": cs.tan, "sqrt": cs.sqrt, "pi": np.pi,
           **{f"x{i}": x[i] for i in range(nx)}, **{f"u{i}": u[i] for i in range(nu)}}
    rhs = cs.vertcat(*[eval(s, env) for s in job["rhs"]])  # noqa: S307 (our own printout)
    model = AcadosModel()
    model.name = "eomgen_" + job["name"]
    model.x, model.u = x, u
    model.xdot = cs.SX.sym("xdot", nx)
    model.f_expl_expr = rhs
    model.f_impl_expr = model.xdot - rhs
    ocp = AcadosOcp()
    ocp.model = model
    ocp.dims.N = N
    Q, R, P = (np.array(job[k]) for k in ("Q", "R", "P"))
    ny = nx + nu
    ocp.cost.cost_type = ocp.cost.cost_type_e = "LINEAR_LS"
    W = np.zeros((ny, ny))
    W[:nx, :nx], W[nx:, nx:] = 2 * Q, 2 * R
    ocp.cost.W, ocp.cost.W_e = W, 2 * P
    ocp.cost.Vx = np.vstack([np.eye(nx), np.zeros((nu, nx))])
    ocp.cost.Vu = np.vstack([np.zeros((nx, nu)), np.eye(nu)])
    ocp.cost.Vx_e = np.eye(nx)
    ocp.cost.yref, ocp.cost.yref_e = np.zeros(ny), np.zeros(nx)
    ocp.constraints.idxbu = np.array(job["idxbu"])
    ocp.constraints.lbu, ocp.constraints.ubu = np.array(job["lbu"]), np.array(job["ubu"])
    ocp.constraints.x0 = np.array(job["x0"])
    so = ocp.solver_options
    so.tf = N * job["period"]
    so.integrator_type = "ERK"
    so.sim_method_num_stages = 4
    so.sim_method_num_steps = job["substeps"]
    so.nlp_solver_type = "SQP_RTI"
    so.qp_solver = "PARTIAL_CONDENSING_HPIPM"
    so.hessian_approx = "GAUSS_NEWTON"
    so.qp_solver_iter_max = 100
    so.qp_tol = 1e-10
    so.print_level = 0
    ocp.code_export_directory = str(folder / "c_generated_code")
    t0 = time.perf_counter()
    solver = AcadosOcpSolver(ocp, json_file=str(folder / "ocp.json"), verbose=False)
    build = time.perf_counter() - t0
    f = cs.Function("f", [x, u], [rhs])
    xr, ur = np.array(job["x_ref"]), np.array(job["u_ref"])
    xk = np.array(job["x0"], dtype=float)
    for k in range(N + 1):
        solver.set(k, "x", np.zeros(nx))
        if k < N:
            solver.set(k, "u", np.zeros(nu))
    us, prep, fb, xs, st = [], [], [], [xk.copy()], []
    h = job["period"] / 10
    for step in range(job["steps"]):
        for k in range(N):
            solver.set(k, "yref", np.r_[xr[step + k], ur[step + k]])
        solver.set(N, "yref", xr[step + N])
        solver.options_set("rti_phase", 1)
        solver.solve()
        prep.append(float(np.ravel(solver.get_stats("time_tot"))[0]))
        solver.set(0, "lbx", xk)
        solver.set(0, "ubx", xk)
        solver.options_set("rti_phase", 2)
        st.append(int(solver.solve()))
        fb.append(float(np.ravel(solver.get_stats("time_tot"))[0]))
        uk = solver.get(0, "u")
        us.append(uk.tolist())
        # the plant: RK4, 10 steps per period, the same expression
        for j in range(10):
            k1 = np.array(f(xk, uk)).ravel()
            k2 = np.array(f(xk + h / 2 * k1, uk)).ravel()
            k3 = np.array(f(xk + h / 2 * k2, uk)).ravel()
            k4 = np.array(f(xk + h * k3, uk)).ravel()
            xk = xk + h / 6 * (k1 + 2 * (k2 + k3) + k4)
        xs.append(xk.tolist())
        # the same shifted warm start as eomgen's
        X = [solver.get(k, "x") for k in range(N + 1)]
        U = [solver.get(k, "u") for k in range(N)]
        for k in range(N):
            solver.set(k, "x", X[k + 1])
            if k < N - 1:
                solver.set(k, "u", U[k + 1])
    out = {"u": us, "x": [list(map(float, v)) for v in xs], "prepare": prep, "feedback": fb,
           "status": st, "build": build}
    (folder / "out.json").write_text(json.dumps(out))


# ------------------------------------------------------------------ report
def compare(pb, ours, theirs):
    umax = np.max(np.abs(theirs["u"]))
    du = np.max(np.abs(ours["u"] - theirs["u"])) / umax
    du_c = np.max(np.abs(ours["u_c"] - theirs["u"])) / umax
    med = statistics.median
    t_ours = med(np.add(ours["prepare"], ours["feedback"]))
    t_acados = med(np.add(theirs["prepare"], theirs["feedback"]))
    return {"problem": pb["name"], "steps": pb["steps"], "du_rel": du, "du_rel_closed_in_c": du_c,
            "dx_max": float(np.max(np.abs(ours["x"] - theirs["x"]))),
            "rti_us_eomgen": 1e6 * t_ours, "rti_us_acados": 1e6 * t_acados,
            "ratio_rti": t_ours / t_acados,
            "prepare_us_eomgen": 1e6 * med(ours["prepare"]),
            "prepare_us_acados": 1e6 * med(theirs["prepare"]),
            "feedback_us_eomgen": 1e6 * med(ours["feedback"]),
            "feedback_us_acados": 1e6 * med(theirs["feedback"]),
            "ratio_feedback": med(ours["feedback"]) / med(theirs["feedback"]),
            "build_s_eomgen": ours["build"], "build_s_acados": theirs["build"],
            "acados_status_nonzero": int(np.count_nonzero(theirs["status"]))}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--problems", nargs="+", default=["cartpole", "quadrotor"])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--json")
    ap.add_argument("--acados-worker", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.acados_worker:
        return acados_worker(a.acados_worker)
    makers = {"cartpole": cartpole_problem, "quadrotor": quadrotor_problem}
    rows = []
    for name in a.problems:
        pb = makers[name](a.steps)
        ours = run_ours(pb)
        theirs = run_acados(pb)
        row = compare(pb, ours, theirs)
        rows.append(row)
        print(f"{name}: {a.steps} RTIs; controls vs acados: max |du| / max |u| = "
              f"{row['du_rel']:.1e} (the loop closed in C: {row['du_rel_closed_in_c']:.1e}); "
              f"median per RTI eomgen {row['rti_us_eomgen']:.1f} us, acados "
              f"{row['rti_us_acados']:.1f} us (ratio {row['ratio_rti']:.2f}); feedback phase "
              f"{row['feedback_us_eomgen']:.1f} vs {row['feedback_us_acados']:.1f} us (ratio "
              f"{row['ratio_feedback']:.2f}); preparation {row['prepare_us_eomgen']:.1f} vs "
              f"{row['prepare_us_acados']:.1f} us; build {row['build_s_eomgen']:.1f} vs "
              f"{row['build_s_acados']:.1f} s", flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))
    return rows


if __name__ == "__main__":
    main()
