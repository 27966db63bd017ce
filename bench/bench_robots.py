"""Issue 45: robots from their files, against Pinocchio (and MuJoCo).

Three parts, each a command:

``speed`` (the acceptance's "Fast"): for the UR5, Panda, Solo12 and Talos
(``--robots``), in one run,

- the wall time from ``import gen`` to a compiled model, in a fresh Python
  process (``gen.Model.from_urdf`` + ``gen.compile``), with the cache's
  runtime objects compiled beforehand (a one-link model) and the robot's own
  build not cached (a fresh cache folder per robot, the runtime copied in);
  the CPU time beside it (the machine is shared: CPU is the measure that does
  not count waiting);
- the C right-hand side ``<name>_eval_rhs`` timed in C (bench/_cdriver.py,
  gcc -O2) against Pinocchio's ABA timed in C++ on the same robot
  (bench/_pinocchio_aba.cpp through bench/_pinocchio_cpp.py: the
  ``header`` build, ``g++ -O2 -DNDEBUG``, and the ``shipped`` one, the
  wheel's libpinocchio_default), in turns (``--rounds``), medians, the
  ratio C / ABA per round and its median; each driver's ABA must equal
  ``pin.aba`` to 1e-12 and the C rhs is printed beside (|C - ABA|);
- the arithmetic operations of the generated right-hand-side kernel
  (``rhs kernel N flops``: bench/_cdriver.py's count of the printed C).

``sweep`` (the acceptance's "The robots people use"): every URDF of the
``example-robot-data`` wheel, with a floating base where the robot has one
(legged, humanoid and flying robots: ``FLOATING``), mimic joints ignored
(Pinocchio's default): Pinocchio's ``buildModelFromUrdf`` model against
``gen.Model.from_urdf`` at 5 random states and torques: the accelerations
(the default, recursive model) against ``aba``, the mass matrix and the bias
forces (a ``formulation="crba"`` model: ``sim.mass_matrix``, ``-sim.forcing``
at zero torque) against ``crba`` and ``rnea(q, v, 0)``, relative to
``1 + max|reference|``. A file Pinocchio refuses is listed with
Pinocchio's reason and ours. ``--no-crba`` leaves the CRBA builds out.

MJCF against MuJoCo's ``mj_forward`` is tests/features/test_mjcf.py (the
mujoco wheel holds one model; ``mujoco-menagerie`` is not installable here).

    python bench/bench_robots.py speed [--robots ur5 panda solo12 talos] [--rounds 3]
    python bench/bench_robots.py sweep [--only NAME ...] [--no-crba]
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

# the robots with a floating base (legged, humanoid, flying); the rest are
# fixed to the world (arms, hands, pendulums, the mobile manipulators'
# example-robot-data loaders fix them too)
FLOATING = {"a1", "alex_nub_hands", "alex_psyonic_hands", "alex_sake_hands",
            "alexander_v1.lowerBodyOnly", "anymal", "anymal-kinova", "b1", "b1-z1", "bolt",
            "borinot_flying_arm_2", "centauro", "g1_29dof_rev_1_0",
            "g1_29dof_with_hand_rev_1_0", "go1", "go2", "quadrotor_base",
            "hextilt_flying_arm_5", "human", "hyq_no_sensors", "icub", "icub_reduced", "iris",
            "iris_simple", "laikago", "quadruped", "romeo", "romeo_laas_small", "romeo_small",
            "simple_humanoid", "simple_humanoid_classical", "solo", "solo12", "talos_full_v2",
            "talos_full_v2_box", "talos_reduced", "talos_reduced_box",
            "talos_reduced_corrected"}

SPEED = {"ur5": "ur_description/urdf/ur5_robot.urdf",
         "panda": "panda_description/urdf/panda.urdf",
         "solo12": "solo_description/robots/solo12.urdf",
         "talos": "talos_data/robots/talos_reduced.urdf"}


def robots_folder():
    """The example-robot-data wheel's robots/ folder."""
    from importlib import metadata
    for f in metadata.files("example-robot-data") or ():
        s = str(f)
        if s.endswith(".urdf") and "/robots/" in s:
            p = Path(f.locate()).resolve()
            return Path(str(p)[:str(p).index("/robots/") + len("/robots")])
    raise SystemExit("example-robot-data is not installed (pip install example-robot-data)")


def all_urdfs():
    root = robots_folder()
    return sorted(root.rglob("*.urdf"), key=lambda p: (p.parent.parent.name, p.name))


def stem(path):
    return Path(path).name[:-len(".urdf")]


def _cpu():
    a = resource.getrusage(resource.RUSAGE_SELF)
    b = resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime


# ------------------------------------------------------------- Pinocchio
def pin_model(path, floating, mimic=False):
    import pinocchio as pin
    if floating:
        return pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer(), mimic)
    return pin.buildModelFromUrdf(str(path), mimic)


def pin_configuration(pmodel, q):
    """Pinocchio's q of ours: a continuous joint's angle as (cos, sin), the
    rest as it is (the free flyer's [x, y, z, qx, qy, qz, qw] is ours)."""
    out, i = [], 0
    for j in range(1, pmodel.njoints):
        jm = pmodel.joints[j]
        if jm.nq == 2 and jm.nv == 1:
            out += [np.cos(q[i]), np.sin(q[i])]
            i += 1
        else:
            out += list(q[i:i + jm.nq])
            i += jm.nq
    return np.array(out)


def random_state(rng, model, floating):
    nq, nu = len(model.q), len(model.u)
    x = np.concatenate([rng.uniform(-1, 1, nq), rng.uniform(-1, 1, nu)])
    if floating:
        x[3:7] /= np.linalg.norm(x[3:7])
    return x


# ------------------------------------------------------------------ speed
SPEED_SCRIPT = r"""
import resource, sys, time, warnings
def cpu():
    a = resource.getrusage(resource.RUSAGE_SELF); b = resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime
w0, c0 = time.perf_counter(), cpu()
import gen
warnings.simplefilter("ignore")
model = gen.Model.from_urdf(sys.argv[1], base=sys.argv[2], name=sys.argv[3], mimic="ignore")
w1, c1 = time.perf_counter(), cpu()
sim = gen.compile(model)
w2, c2 = time.perf_counter(), cpu()
print(w2 - w0, c2 - c0, w1 - w0, c1 - c0, sim.build_info.get("cached"))
"""


def import_to_compiled(path, floating, name, warm_cache):
    """(wall, cpu, wall to the model, cpu to the model, cached) of a fresh
    process: import gen, from_urdf, compile; the cache holds the runtime
    only (a copy of warm_cache)."""
    cache = tempfile.mkdtemp(prefix=f"bench_robots_{name}_")
    shutil.rmtree(cache)
    shutil.copytree(warm_cache, cache)
    env = dict(os.environ, EOMGEN_CACHE=cache)
    r = subprocess.run([sys.executable, "-c", SPEED_SCRIPT, str(path),
                        "floating" if floating else "fixed", name],
                       capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise RuntimeError(r.stderr[-3000:])
    w, c, wm, cm, cached = r.stdout.split()
    return float(w), float(c), float(wm), float(cm), cached


def rhs_kernel_flops(folder, name):
    """The arithmetic operations of the generated right-hand-side kernel
    ``<name>_k_rhs_terms`` (bench/_cdriver.py's count of the printed C; the
    body of its cloned versions when it has them; its scalar body when it
    also has the two-lane one, which computes the same operations)."""
    import re
    from _cdriver import count_flops, function_body
    text = (Path(folder) / f"{name}_kernels.c").read_text()
    text = re.sub(r"\n#if GEN_RT_LANES\n.*?\n#else(?=\n)", "", text, flags=re.S)
    text = re.sub(r"\n#[^\n]*", "", text)
    for fn in (f"{name}_k_rhs_terms_isa", f"{name}_k_rhs_terms"):
        try:
            return count_flops(function_body(text, fn))["arith"]
        except ValueError:
            continue
    return None


def speed(args):
    import gen
    import _pinocchio_cpp as pc
    from _cdriver import time_rhs_in_c
    from bench_recursive import pendulum, pinocchio_drivers
    warnings.simplefilter("ignore")
    root = robots_folder()
    warm = tempfile.mkdtemp(prefix="bench_robots_warm_")
    os.environ["EOMGEN_CACHE"] = warm
    system, consts = pendulum(1)       # the runtime's objects, compiled once
    gen.compile(gen.Model.from_system(system, constants=consts, name="warm",
                                      formulation="recursive"))
    drivers = pinocchio_drivers(args.pin_variants, pc.DEFAULT_FLAGS)
    rows = []
    for key in args.robots:
        path = root / SPEED[key]
        floating = stem(path) in FLOATING
        w, c, wm, cm, cached = import_to_compiled(path, floating, key, warm)
        row = {"robot": key, "file": SPEED[key], "base": "floating" if floating else "fixed",
               "wall": w, "cpu": c, "wall_model": wm, "cpu_model": cm}
        model = gen.Model.from_urdf(path, base=row["base"], name=key, mimic="ignore")
        sim = gen.compile(model)
        pm = pin_model(path, floating)
        rng = np.random.default_rng(5)
        x = random_state(rng, model, floating)
        nq = len(model.q)
        q, v = pin_configuration(pm, x[:nq]), x[nq:].copy()
        tau = np.zeros(pm.nv)
        import pinocchio as pin
        want = pin.aba(pm, pm.createData(), q, v, tau)
        row["maxdiff"] = float(np.max(np.abs(sim.rhs(0.0, x, r=np.zeros(len(model.r)))[nq:]
                                             - want)) / (1 + np.max(np.abs(want))))
        folder = tempfile.mkdtemp(prefix=f"bench_robots_src_{key}_")
        gen.generate(model, folder)
        row["flops"] = rhs_kernel_flops(folder, key)
        cs, per, check = [], {k: [] for k in drivers}, {}
        for _ in range(args.rounds):
            cs.append(time_rhs_in_c(folder, key, x, model.p_values, reps=7, runs=1)["eomgen"])
            for k, (exe, _info) in drivers.items():
                res = pc.run_driver(exe, pm, q, v, tau, reps=7)
                check[k] = max(check.get(k, 0.0),
                               float(np.max(np.abs(res["ddq"] - want) / (1 + np.abs(want)))))
                per[k].append(res["aba"])
        row["rhs_c"] = statistics.median(cs)
        for k, ts in per.items():
            row[f"check_{k}"] = check[k]
            if check[k] > 1e-12:
                continue
            row[f"aba_{k}"] = statistics.median(ts)
            row[f"ratio_{k}"] = statistics.median(a / b for a, b in zip(cs, ts))
        timed = [per[k] for k in per if f"aba_{k}" in row]
        if len(timed) > 1:
            row["ratio_best"] = statistics.median(a / min(b) for a, b in zip(cs, zip(*timed)))
        rows.append(row)
        msg = (f"{key:7s} {row['base']:8s} nq={nq:2d}: import->compiled {w:5.2f} s wall "
               f"({c:5.2f} s CPU; model {wm:.2f} s wall) | rhs in C {row['rhs_c'] * 1e6:6.2f} us")
        for k in drivers:
            if f"aba_{k}" in row:
                msg += (f" | ABA C++ {k} {row[f'aba_{k}'] * 1e6:6.2f} us, C / ABA "
                        f"{row[f'ratio_{k}']:.3f}")
            else:
                msg += f" | ABA C++ {k}: differs from pin.aba by {check[k]:.1e}: not timed"
        if "ratio_best" in row:
            msg += f" | C / faster ABA {row['ratio_best']:.3f}"
        msg += f" | |C - aba| {row['maxdiff']:.1e} | rhs kernel {row['flops']} flops"
        print(msg, flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


# ------------------------------------------------------------------ sweep
def check_robot(path, floating, crba=True, seed=0, states=5):
    """{'aba': err, 'crba': err, 'rnea': err, ...} of one URDF against
    Pinocchio (module docstring); raises what either side raises."""
    import gen
    import pinocchio as pin
    base = "floating" if floating else "fixed"
    name = "r_" + "".join(ch if ch.isalnum() else "_" for ch in stem(path).lower())
    out = {}
    c0, w0 = _cpu(), time.perf_counter()
    model = gen.Model.from_urdf(path, base=base, name=name, mimic="ignore")
    sim = gen.compile(model)
    out["build_cpu"], out["build_wall"] = _cpu() - c0, time.perf_counter() - w0
    csim = None
    if crba:
        c0 = _cpu()
        csim = gen.compile(gen.Model.from_urdf(path, base=base, name=name + "_crba",
                                               mimic="ignore", formulation="crba"))
        out["crba_build_cpu"] = _cpu() - c0
    pm = pin_model(path, floating)
    pd = pm.createData()
    names = [pm.names[j] for j in range(1, pm.njoints)]
    ours = list(gen.load_urdf(path, base=base, mimic="ignore").joints)
    if floating:
        names, ours = names[1:], ours[1:]
    if names != ours:
        raise AssertionError(f"joint order: Pinocchio {names[:6]}..., ours {ours[:6]}...")
    rng = np.random.default_rng(seed)
    nq, nr = len(model.q), len(model.r)
    errs = {"aba": 0.0, "crba": 0.0, "rnea": 0.0}
    for _ in range(states):
        x = random_state(rng, model, floating)
        tau = rng.uniform(-1, 1, nr)
        q, v = pin_configuration(pm, x[:nq]), x[nq:]
        taup = np.zeros(pm.nv)
        taup[pm.nv - nr:] = tau
        a = pin.aba(pm, pd, q, v, taup)
        ud = sim.rhs(0.0, x, r=tau)[nq:]
        errs["aba"] = max(errs["aba"], float(np.max(np.abs(ud - a)) / (1 + np.max(np.abs(a)))))
        if csim is not None:
            M = pin.crba(pm, pd, q)
            M = np.triu(M) + np.triu(M, 1).T
            b = pin.rnea(pm, pd, q, v, np.zeros(pm.nv))
            Mo = csim.mass_matrix(x[:nq])
            bo = -csim.forcing(x[:nq], x[nq:], r=np.zeros(nr))
            errs["crba"] = max(errs["crba"],
                               float(np.max(np.abs(Mo - M)) / (1 + np.max(np.abs(M)))))
            errs["rnea"] = max(errs["rnea"],
                               float(np.max(np.abs(bo - b)) / (1 + np.max(np.abs(b)))))
    out.update(errs)
    out["nq"], out["nv"] = nq, len(model.u)
    return out


def sweep(args):
    import gen
    warnings.simplefilter("ignore")
    os.environ.setdefault("EOMGEN_CACHE", tempfile.mkdtemp(prefix="bench_robots_sweep_"))
    rows = []
    for path in all_urdfs():
        s = stem(path)
        if args.only and s not in args.only:
            continue
        floating = s in FLOATING
        row = {"file": str(path.relative_to(robots_folder())), "base":
               "floating" if floating else "fixed"}
        try:
            pin_model(path, floating)
        except Exception as e:           # Pinocchio refuses the file
            row["pinocchio"] = str(e).splitlines()[0][:100]
            try:
                gen.load_urdf(path, base=row["base"])
                row["ours"] = "loaded"
            except gen.ModelError as e2:
                row["ours"] = str(e2)[:160]
            rows.append(row)
            print(f"{row['file']:58s} NOT LOADED BY PINOCCHIO: {row['pinocchio']} | ours: "
                  f"{row['ours']}", flush=True)
            continue
        try:
            row.update(check_robot(path, floating, crba=not args.no_crba))
        except Exception as e:
            row["error"] = f"{type(e).__name__}: {str(e)[:200]}"
        tol = 1e-10
        ok = "error" not in row and all(row.get(k, 0.0) <= tol for k in ("aba", "crba", "rnea"))
        row["ok"] = ok
        rows.append(row)
        if "error" in row:
            print(f"{row['file']:58s} FAILED: {row['error']}", flush=True)
        else:
            print(f"{row['file']:58s} {row['base']:8s} nq={row['nq']:3d} aba {row['aba']:.1e} "
                  f"crba {row['crba']:.1e} rnea {row['rnea']:.1e} build {row['build_cpu']:6.2f} "
                  f"s CPU {'ok' if ok else 'OVER 1e-10'}", flush=True)
    n_ok = sum(1 for r in rows if r.get("ok"))
    print(f"{n_ok} of {len(rows)} files agree with Pinocchio to 1e-10")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    sp = sub.add_parser("speed")
    sp.add_argument("--robots", nargs="+", default=list(SPEED), choices=list(SPEED))
    sp.add_argument("--rounds", type=int, default=3)
    sp.add_argument("--pin-variants", nargs="*", default=["header", "shipped"])
    sp.add_argument("--json")
    sw = sub.add_parser("sweep")
    sw.add_argument("--only", nargs="*")
    sw.add_argument("--no-crba", action="store_true")
    sw.add_argument("--json")
    args = ap.parse_args(argv)
    if args.cmd == "speed":
        speed(args)
    else:
        sweep(args)


if __name__ == "__main__":
    main()
