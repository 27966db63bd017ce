"""Issue 37: build time of the n-link pendulum of PinJoints, from a sympy
System, three ways in one run:

- sympy's ``System.form_eoms()`` alone (Kane), the derivation the Kane path
  needs before eomgen starts;
- ``Model.from_system(system, formulation="recursive")`` (CRBA + RNEA over the
  joint tree) alone, and with ``gen.compile`` (generation + C compile, a fresh
  cache so nothing is reused);
  and the time of one ``sim.rhs`` call from Python.

Prints the times, the ratios recursive / form_eoms and the growth exponents
(not yet: the Kane path's own build and Pinocchio's ABA timing, which issue 37
also asks for; tests/test_recursive.py checks Pinocchio's values).

    python bench/bench_recursive.py [--n 5 10 20] [--compile] [--no-form-eoms]
"""
from __future__ import annotations

import argparse
import math
import time

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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[5, 10, 20])
    ap.add_argument("--compile", action="store_true", help="also time gen.compile")
    ap.add_argument("--no-form-eoms", action="store_true",
                    help="skip sympy's form_eoms (large n)")
    args = ap.parse_args(argv)
    import warnings

    import gen
    warnings.simplefilter("ignore")
    rows = []
    if True:     # the shared content cache: the runtime's objects are reused, the model's are new
        for n in args.n:
            row = {"n": n}
            if not args.no_form_eoms:
                system, _ = pendulum(n)
                t0 = time.perf_counter()
                system.form_eoms()
                row["form_eoms"] = time.perf_counter() - t0
            system, consts = pendulum(n)
            t0 = time.perf_counter()
            model = gen.Model.from_system(system, constants=consts, name=f"pend{n}",
                                          formulation="recursive")
            row["recursive"] = time.perf_counter() - t0
            if args.compile:
                t0 = time.perf_counter()
                sim = gen.compile(model)
                row["compile"] = time.perf_counter() - t0
                x = np.full(2 * n, 0.1)
                sim.rhs(0.0, x)
                k = 2000
                t0 = time.perf_counter()
                for _ in range(k):
                    sim.rhs(0.0, x)
                row["rhs_us"] = (time.perf_counter() - t0) / k * 1e6
            rows.append(row)
            msg = f"n={n:3d}  recursive model {row['recursive']:7.2f} s"
            if "form_eoms" in row:
                msg += (f"  form_eoms {row['form_eoms']:7.2f} s  ratio "
                        f"{row['recursive'] / row['form_eoms']:.3f}")
            if "compile" in row:
                msg += (f"  compile {row['compile']:6.2f} s  total "
                        f"{row['recursive'] + row['compile']:6.2f} s  rhs (Python call) "
                        f"{row['rhs_us']:.1f} us")
            print(msg, flush=True)
    for key in ("form_eoms", "recursive", "compile"):
        pts = [(r["n"], r[key]) for r in rows if key in r]
        if len(pts) >= 2:
            (n0, t0_), (n1, t1) = pts[-2], pts[-1]
            print(f"growth exponent {key} n={n0}->{n1}: "
                  f"{math.log(t1 / t0_) / math.log(n1 / n0):.2f}")


if __name__ == "__main__":
    main()
