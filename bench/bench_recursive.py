"""Issue 37: the n-link pendulum of PinJoints, from a sympy System to
compiled C, three ways in one run, and the right-hand side against
Pinocchio's ABA:

- sympy's ``System.form_eoms()`` alone (Kane), then this project's Kane path
  on it (``Model.from_system`` + ``gen.compile``);
- ``Model.from_system(system, formulation="recursive")`` (CRBA + RNEA over
  the joint tree) and ``gen.compile`` (generation + C compile);
- the C right-hand side ``<name>_eval_rhs`` timed in C (bench/_cdriver.py's
  driver, gcc -O2, median of interleaved repeats) against Pinocchio's
  ``pin.aba`` on the same tree (built here from the same parameters),
  timed in a Python loop minus the measured time of a cheap binding call
  with like arguments and result (``pin.integrate(model, q, v)``: the model,
  two vectors in, a new vector out, O(n) work): the Python-call overhead
  subtracted (slightly over-subtracted, in Pinocchio's favour). Not in a C++
  driver: the ``pin`` wheel's headers lack ``pinocchio/multibody/model.hpp``.

Builds go to a fresh cache (EOMGEN_CACHE in a temporary folder) whose
runtime objects are compiled first, by a one-link model: every build timed
compiles its model's own sources, not the shared runtime.

Build times are CPU seconds (this process and the compilers it ran; the
wall time is printed beside them): the machine may be shared. Prints the
times, the ratios and the growth exponents between the last two n.

    python bench/bench_recursive.py [--n 7 20 50] [--form-eoms-max 20] [--no-rhs]
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
    args = ap.parse_args(argv)
    os.environ["EOMGEN_CACHE"] = tempfile.mkdtemp(prefix="bench_recursive_")
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import gen
    warnings.simplefilter("ignore")
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
            from _cdriver import time_rhs_in_c
            rng = np.random.default_rng(n)
            x = rng.uniform(-1, 1, 2 * n)
            folder = tempfile.mkdtemp(prefix=f"bench_recursive_{n}_")
            gen.generate(model, folder)
            c = time_rhs_in_c(folder, model.name, x, model.p_values, reps=11, runs=2)
            row["rhs_c"] = c["eomgen"]
            pin, pmodel = pinocchio_pendulum(n)
            row["aba"], row["aba_raw"], row["noop"] = time_pinocchio(pin, pmodel, x)
            want = pin.aba(pmodel, pmodel.createData(), x[:n], x[n:], np.zeros(n))
            row["maxdiff"] = float(np.max(np.abs(sim.rhs(0.0, x)[n:] - want)))
        rows.append(row)
        msg = (f"n={n:3d}  recursive: model {row['rec_model']:6.2f} s + compile "
               f"{row['rec_compile']:6.2f} s = {row['rec_build']:6.2f} s CPU "
               f"({row['rec_build_wall']:.2f} s wall)")
        if "form_eoms" in row:
            msg += (f" | form_eoms {row['form_eoms']:7.2f} s CPU ({row['form_eoms_wall']:.2f} s "
                    f"wall; recursive build / form_eoms {row['rec_build'] / row['form_eoms']:.3f}"
                    f"), Kane path build after it {row['kane_build']:6.2f} s CPU")
        if "rhs_c" in row:
            msg += (f" | rhs in C {row['rhs_c'] * 1e6:7.2f} us, Pinocchio ABA "
                    f"{row['aba'] * 1e6:6.2f} us ({row['aba_raw'] * 1e6:.2f} us from Python "
                    f"- {row['noop'] * 1e6:.2f} us binding call), C / ABA "
                    f"{row['rhs_c'] / row['aba']:.2f}, |C - ABA| {row['maxdiff']:.1e}")
        print(msg, flush=True)
    for key in ("form_eoms", "kane_build", "rec_model", "rec_compile", "rec_build",
                "rhs_c", "aba"):
        pts = [(r["n"], r[key]) for r in rows if key in r]
        if len(pts) >= 2:
            (n0, t0_), (n1, t1) = pts[-2], pts[-1]
            print(f"growth exponent {key} n={n0}->{n1}: "
                  f"{math.log(t1 / t0_) / math.log(n1 / n0):.2f}")


if __name__ == "__main__":
    main()
