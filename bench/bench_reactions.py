"""Reactions inside the motion: the symbolic elimination against the
coupled solve, on a model where both apply (issue 33).

The bead on a circular track of tests/physics/test_reactions_coupled.py with its
auxiliary speed along the track's normal: the normal force's coefficient is
1, so Model.from_kanes eliminates it exactly (N = m (g cos + R omega^2) put
into f, today's path); with Model.from_kanes(..., eliminate_reactions=False) the
same model goes through the coupled solve ([M, -G; C, H] [u'; N] = [f; -g0] by
pivoted LU at each evaluation). Also the cart-pole with Coulomb friction
(examples/cart_pole_friction.py), which only the coupled solve handles,
next to the same cart-pole without friction.

Measured: the C time of one RK4 step (simulate in C, final_only, many
steps; median of repeats) and gen.compile's time into an empty cache.
Printed as ratios; nothing asserted.

    python bench/bench_reactions.py [--steps 200000] [--repeats 7]
"""
import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "examples")]

import gen                                      # noqa: E402


def step_time(sim, x0, r, steps, repeats, dt=1e-5):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sim.simulate(x0, steps * dt, dt, r=r, final_only=True, max_rows=None)
        times.append((time.perf_counter() - t0) / steps)
    return statistics.median(times)


def compile_cold(model):
    with tempfile.TemporaryDirectory() as d:
        old = os.environ.get("EOMGEN_CACHE")
        os.environ["EOMGEN_CACHE"] = d
        try:
            t0 = time.perf_counter()
            sim = gen.compile(model)
            return sim, time.perf_counter() - t0
        finally:
            if old is None:
                os.environ.pop("EOMGEN_CACHE")
            else:
                os.environ["EOMGEN_CACHE"] = old


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200000)
    ap.add_argument("--repeats", type=int, default=7)
    a = ap.parse_args(argv)
    from test_reactions_coupled import bead_kane
    import cart_pole_friction as cpf
    km, consts, F, _ = bead_kane("normal")
    elim = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bench_elim")
    coupled = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bench_cpl",
                                   eliminate_reactions=False)
    assert elim.aux_G is None and coupled.aux_G is not None
    s_e, b_e = compile_cold(elim)
    s_c, b_c = compile_cold(coupled)
    x0, r = [0.4, 1.1], [0.3]
    diff = np.max(np.abs(s_e.rhs(0.0, x0, r=r) - s_c.rhs(0.0, x0, r=r)))
    # interleaved, so that the machine's load falls on both alike
    te, tc = [], []
    for _ in range(3):
        te.append(step_time(s_e, x0, r, a.steps, a.repeats))
        tc.append(step_time(s_c, x0, r, a.steps, a.repeats))
    te, tc = statistics.median(te), statistics.median(tc)
    print("bead on a circular track, N along the normal (both paths apply)")
    print(f"  RK4 step in C   eliminated {te * 1e9:8.1f} ns   coupled {tc * 1e9:8.1f} ns   "
          f"coupled / eliminated {tc / te:.2f}")
    print(f"  gen.compile     eliminated {b_e:8.2f} s    coupled {b_c:8.2f} s    "
          f"coupled / eliminated {b_c / b_e:.2f}")
    print(f"  max |x'| difference between the two {diff:.1e}")
    fr = cpf.model()
    s_f, b_f = compile_cold(fr)
    xf = [0.0, 2.5, 0.8, 0.0]
    tf = statistics.median(step_time(s_f, xf, [0.0], a.steps // 2, a.repeats) for _ in range(3))
    print("cart-pole with Coulomb friction on N (coupled only)")
    print(f"  RK4 step in C {tf * 1e9:8.1f} ns, gen.compile {b_f:.2f} s")


if __name__ == "__main__":
    main()
