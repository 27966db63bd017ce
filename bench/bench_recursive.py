"""Issue 37: the n-link pendulum of PinJoints, from a sympy System to
compiled C, three ways in one run, and the right-hand side against
Pinocchio's ABA:

- sympy's ``System.form_eoms()`` alone (Kane), then this project's Kane path
  on it (``Model.from_system`` + ``gen.compile``);
- ``Model.from_system(system, formulation="recursive")`` (CRBA + RNEA over
  the joint tree) and ``gen.compile`` (generation + C compile);
- the C right-hand side ``<name>_eval_rhs`` timed in C (bench/_cdriver.py's
  driver, gcc -O2, median of repeats) against Pinocchio's ABA on the same
  tree (``pinocchio_pendulum``: built here from the same parameters) timed
  in C++ (bench/_pinocchio_aba.cpp, built by bench/_pinocchio_cpp.py against
  the ``pin`` wheel's headers, its Boost and an Eigen 3.4; the model is
  passed to it from the Python ``pin`` model, every parameter to the bit):
  ``pinocchio::aba(model, data, q, v, tau)`` in a loop of the same form as
  the C driver's, median of repeats. Two builds of the driver:
  ``header`` (header-only, ``g++ -std=c++17 -O2 -DNDEBUG``: the C driver's
  -O2; ``--pin-flags`` changes them) and ``shipped`` (the aba instance in the
  wheel's libpinocchio_default.so, which the Python binding calls, linked
  with PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION). The C driver and the C++
  drivers run in turns (``--rounds`` rounds; each a separate process): the
  times are medians over the rounds and the ratio C / ABA the median of the
  rounds' ratios; with both builds, also C / the faster of the two in each
  round (the figure in Pinocchio's favour).
  Each driver's ABA result must equal ``pin.aba`` from Python to 1e-12
  (|d| / (1 + |ddq|), printed; else that driver is not timed); the C rhs's difference from ABA is printed beside it. A driver
  built once is cached (``~/.cache/eomgen-bench``; a build takes 1-3
  CPU-minutes). If the C++ build fails here (no compiler, no Eigen, a wheel
  without headers), the bench prints why and falls back, visibly, to the
  Python timing below for the ratio.
- secondary, as before: ``pin.aba`` timed in a Python loop minus the
  measured time of a cheap binding call with like arguments and result
  (``pin.integrate(model, q, v)``: the model, two vectors in, a new vector
  out, O(n) work): the Python-call overhead subtracted, but not all of
  it (this reads 5-60% above the C++ ``shipped`` time: bench/README.md).

Builds go to a fresh cache (EOMGEN_CACHE in a temporary folder) whose
runtime objects are compiled first, by a one-link model: every build timed
compiles its model's own sources, not the shared runtime.

Build times are CPU seconds (this process and the compilers it ran; the
wall time is printed beside them): the machine may be shared. Prints the
times, the ratios and the growth exponents between the last two n.

    python bench/bench_recursive.py [--n 7 20 50] [--form-eoms-max 20] [--no-rhs]
        [--rounds 3] [--pin-variants header shipped] [--pin-flags "-O2 -DNDEBUG"]
"""
from __future__ import annotations

import argparse
import math
import os
import resource
import statistics
import sys
import tempfile
import time
import warnings

import numpy as np
import sympy as sm
import sympy.physics.mechanics as me


def pendulum(n):
    """n rigid links hanging from PinJoints about N.z, gravity along -N.y."""
    ground = me.RigidBody("G")
    N = ground.frame
    system = me.System.from_newtonian(ground)
    g = sm.Symbol("g")
    consts = {g: 9.81}
    parent = ground
    for i in range(n):
        m, l, I = sm.symbols(f"m{i} l{i} I{i}")
        B = me.ReferenceFrame(f"B{i}")
        mc = me.Point(f"mc{i}")
        body = me.RigidBody(f"b{i}", mc, B, m, (me.inertia(B, I / 10, I, I), mc))
        q, u = me.dynamicsymbols(f"q{i} u{i}")
        ppt = parent.masscenter if i == 0 else parent.masscenter.locatenew(
            f"P{i}", sm.Symbol(f"l{i-1}") / 2 * parent.frame.x)
        cpt = mc.locatenew(f"C{i}", -l / 2 * B.x)
        system.add_joints(me.PinJoint(f"J{i}", parent, body, q, u, ppt, cpt,
                                      joint_axis=parent.frame.z))
        consts.update({m: 1.0, l: 1.0, I: 1.0 / 12})
        parent = body
    system.apply_uniform_gravity(-g * N.y)
    return system, consts


def pinocchio_pendulum(n):
    """The same chain in Pinocchio: joint i at the previous link's end (the
    ground's origin for the first), a revolute about z, the link's mass
    centre l/2 along its x axis, its central inertia diag(I/10, I, I)."""
    import pinocchio as pin
    model = pin.Model()
    parent = 0
    for i in range(n):
        place = pin.SE3(np.eye(3), np.array([0.0, 0, 0]) if i == 0 else np.array([1.0, 0, 0]))
        parent = model.addJoint(parent, pin.JointModelRZ(), place, f"J{i}")
        model.appendBodyToJoint(parent, pin.Inertia(1.0, np.array([0.5, 0, 0]),
                                                    np.diag([1 / 120, 1 / 12, 1 / 12])),
                                pin.SE3.Identity())
    model.gravity.linear = np.array([0.0, -9.81, 0.0])
    return pin, model


def time_pinocchio(pin, model, x, k=20000, reps=7):
    """Seconds per pin.aba call (median of reps loops of k), minus the
    median per-call time of pin.integrate(model, q, v) (the Python binding's
    call, argument conversion and returned array); both raw times are
    returned too."""
    data = model.createData()
    n = model.nq
    q, v, tau = x[:n].copy(), x[n:].copy(), np.zeros(n)
    aba, noop = [], []
    for _ in range(reps):
        t0 = time.perf_counter()
        for _ in range(k):
            pin.aba(model, data, q, v, tau)
        t1 = time.perf_counter()
        for _ in range(k):
            pin.integrate(model, q, v)
        t2 = time.perf_counter()
        aba.append((t1 - t0) / k)
        noop.append((t2 - t1) / k)
    a, o = statistics.median(aba), statistics.median(noop)
    return a - o, a, o


def pinocchio_drivers(variants, flags):
    """{variant: (exe, info)} of the C++ ABA drivers that build here; a
    variant that does not build is reported (why) and left out."""
    import _pinocchio_cpp as pc
    out = {}
    for v in variants:
        try:
            exe, info = pc.build_driver(v, flags=flags if v == "header" else pc.DEFAULT_FLAGS)
        except (pc.DriverError, ImportError, OSError) as e:
            print(f"Pinocchio C++ ABA driver '{v}' NOT BUILT, so not timed: {e}", flush=True)
            continue
        print(f"Pinocchio C++ ABA driver '{v}': Eigen {info['eigen']}; {info['cmd']}", flush=True)
        out[v] = (exe, info)
    if not out:
        print("FALLBACK: no C++ build of Pinocchio's ABA here; C / ABA below is against "
              "pin.aba timed from Python (minus the binding call)", flush=True)
    return out


def rhs_section(row, n, gen, model, sim, drivers, rounds):
    """Time the C rhs and Pinocchio's ABA (C++ drivers in turns with the C
    driver; and from Python), check the results, fill row."""
    import _pinocchio_cpp as pc
    from _cdriver import time_rhs_in_c
    rng = np.random.default_rng(n)
    x = rng.uniform(-1, 1, 2 * n)
    folder = tempfile.mkdtemp(prefix=f"bench_recursive_{n}_")
    gen.generate(model, folder)
    pin, pmodel = pinocchio_pendulum(n)
    q, v, tau = x[:n].copy(), x[n:].copy(), np.zeros(n)
    want = pin.aba(pmodel, pmodel.createData(), q, v, tau)
    row["maxdiff"] = float(np.max(np.abs(sim.rhs(0.0, x)[n:] - want)))
    cs, per = [], {k: [] for k in drivers}
    for _ in range(rounds):
        c = time_rhs_in_c(folder, model.name, x, model.p_values, reps=7, runs=1)
        cs.append(c["eomgen"])
        for k, (exe, _info) in drivers.items():
            r = pc.run_driver(exe, pmodel, q, v, tau, reps=7)
            dd = float(np.max(np.abs(r["ddq"] - want) / (1 + np.abs(want))))
            row[f"check_{k}"] = max(row.get(f"check_{k}", 0.0), dd)
            per[k].append(r["aba"])
    row["rhs_c"] = statistics.median(cs)
    for k, ts in per.items():
        if row[f"check_{k}"] > 1e-12:       # not the same computation: no timing
            continue
        row[f"aba_{k}"] = statistics.median(ts)
        row[f"ratio_{k}"] = statistics.median(a / b for a, b in zip(cs, ts))
    timed = [per[k] for k in per if f"aba_{k}" in row]
    if len(timed) > 1:         # against the faster build in each round
        row["ratio_best"] = statistics.median(a / min(b) for a, b in zip(cs, zip(*timed)))
    row["aba"], row["aba_raw"], row["noop"] = time_pinocchio(pin, pmodel, x)


def rhs_line(row, drivers):
    n = row["n"]
    msg = f"n={n:3d}  rhs in C {row['rhs_c'] * 1e6:7.2f} us"
    for k in drivers:
        if f"aba_{k}" in row:
            msg += (f" | Pinocchio ABA C++ {k} {row[f'aba_{k}'] * 1e6:6.2f} us, C / ABA "
                    f"{row[f'ratio_{k}']:.2f} (|ABA - pin.aba| {row[f'check_{k}']:.0e})")
        else:
            msg += (f" | Pinocchio ABA C++ {k}: RESULT DIFFERS from pin.aba by "
                    f"{row[f'check_{k}']:.1e} (relative): not timed")
    msg += (f" | from Python {row['aba'] * 1e6:6.2f} us ({row['aba_raw'] * 1e6:.2f} us "
            f"- {row['noop'] * 1e6:.2f} us binding call)")
    if "ratio_best" in row:
        msg += f" | C / the faster C++ ABA {row['ratio_best']:.2f}"
    if not any(f"aba_{k}" in row for k in drivers):
        msg += f", C / ABA(Python, FALLBACK) {row['rhs_c'] / row['aba']:.2f}"
    msg += f" | |C - ABA| {row['maxdiff']:.1e}"
    return msg


class Clock:
    """Wall time and CPU time (this process and its finished children: the
    compilers) of a block: on a machine shared with other jobs the CPU time
    is the measure that does not count the waiting."""

    def __enter__(self):
        self.w0, self.c0 = time.perf_counter(), _cpu()
        return self

    def __exit__(self, *exc):
        self.wall = time.perf_counter() - self.w0
        self.cpu = _cpu() - self.c0


def _cpu():
    me_, ch = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me_.ru_utime + me_.ru_stime + ch.ru_utime + ch.ru_stime


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[7, 20, 50])
    ap.add_argument("--form-eoms-max", type=int, default=20,
                    help="largest n for sympy's form_eoms and the Kane path (minutes above)")
    ap.add_argument("--no-rhs", action="store_true", help="build times only")
    ap.add_argument("--rounds", type=int, default=3,
                    help="turns of the C driver and the C++ ABA drivers (medians over them)")
    ap.add_argument("--pin-variants", nargs="*", default=["header", "shipped"],
                    choices=["header", "shipped"],
                    help="C++ builds of Pinocchio's ABA to time (none: the Python timing only)")
    ap.add_argument("--pin-flags", default="-O2 -DNDEBUG",
                    help="g++ flags of the header-only ABA driver")
    args = ap.parse_args(argv)
    os.environ["EOMGEN_CACHE"] = tempfile.mkdtemp(prefix="bench_recursive_")
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import gen
    warnings.simplefilter("ignore")
    drivers = {} if args.no_rhs else pinocchio_drivers(args.pin_variants, args.pin_flags.split())
    system, consts = pendulum(1)      # the runtime's objects, compiled once
    gen.compile(gen.Model.from_system(system, constants=consts, name="warm",
                                      formulation="recursive"))
    rows = []
    for n in args.n:
        row = {"n": n}
        if n <= args.form_eoms_max:
            system, consts = pendulum(n)
            with Clock() as c:
                system.form_eoms()
            row["form_eoms"], row["form_eoms_wall"] = c.cpu, c.wall
            with Clock() as c:
                kmodel = gen.Model.from_system(system, constants=consts, name=f"kane{n}")
                gen.compile(kmodel)
            row["kane_build"], row["kane_build_wall"] = c.cpu, c.wall
        system, consts = pendulum(n)
        with Clock() as c:
            model = gen.Model.from_system(system, constants=consts, name=f"rec{n}",
                                          formulation="recursive")
        row["rec_model"], row["rec_model_wall"] = c.cpu, c.wall
        with Clock() as c:
            sim = gen.compile(model)
        row["rec_compile"], row["rec_compile_wall"] = c.cpu, c.wall
        row["rec_build"] = row["rec_model"] + row["rec_compile"]
        row["rec_build_wall"] = row["rec_model_wall"] + row["rec_compile_wall"]
        if not args.no_rhs:
            rhs_section(row, n, gen, model, sim, drivers, args.rounds)
        rows.append(row)
        msg = (f"n={n:3d}  recursive: model {row['rec_model']:6.2f} s + compile "
               f"{row['rec_compile']:6.2f} s = {row['rec_build']:6.2f} s CPU "
               f"({row['rec_build_wall']:.2f} s wall)")
        if "form_eoms" in row:
            msg += (f" | form_eoms {row['form_eoms']:7.2f} s CPU ({row['form_eoms_wall']:.2f} s "
                    f"wall; recursive build / form_eoms {row['rec_build'] / row['form_eoms']:.3f}"
                    f"), Kane path build after it {row['kane_build']:6.2f} s CPU")
        print(msg, flush=True)
        if "rhs_c" in row:
            print(rhs_line(row, drivers), flush=True)
    for key in ("form_eoms", "kane_build", "rec_model", "rec_compile", "rec_build",
                "rhs_c", "aba_header", "aba_shipped", "aba"):
        pts = [(r["n"], r[key]) for r in rows if key in r]
        if len(pts) >= 2:
            (n0, t0_), (n1, t1) = pts[-2], pts[-1]
            print(f"growth exponent {key} n={n0}->{n1}: "
                  f"{math.log(t1 / t0_) / math.log(n1 / n0):.2f}")


if __name__ == "__main__":
    main()
