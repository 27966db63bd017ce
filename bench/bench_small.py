"""Benchmark (issue 47): the small constrained models per state, against the
1-link cart (4 states, unconstrained) and against each model's floor, in the
same run.

    python bench/bench_small.py [--reps 21] [--n 1000] [--json PATH]

Each model is compiled (cached by content); ``sim.rhs_batch`` over N = 1000
random states into a preallocated ``out=`` is timed in interleaved repeats
(the machine is shared; each timed call follows an untimed one of the same
model), and the median per state is printed with its ratio to the 1-link
cart's median. The models: the seed's Kane model (4 states,
one holonomic and one velocity constraint, a dependent coordinate and
speed: the partitioned solve), its Lagrange model (the KKT solve with one
multiplier), the 1-link and 2-link carts (examples/n_link_cart.py), and
the other small constrained examples: the four-bar linkage (Kane, 3 speeds,
2 constraints), the Chaplygin sleigh (Kane, 3 speeds, 1 nonholonomic) and
the rolling disc (Kane, 5 speeds, 2 nonholonomic), at random states in
[-0.5, 0.5].

The floor of a model: the operations of its right-hand side, each class at
the rate this machine reaches for it, measured in the same repeat by a probe
built with the models' own C flags (gen.codegen.backends.base.C_FLAGS):
sums, differences, products and negations at the peak scalar rate (twelve
independent chains of a product and a sum, as bench/_cdriver.py's measured
floor), divisions and square roots at their own peak rates (twelve
independent chains each), and each sin/cos pair at the platform's libm time
on angles in [-1, 1]. The operations are the kernel's (counted in the
printed C of the fused right-hand side, <name>_k_rhs_terms; a quotient of
two literals is the compiler's) plus the solve's: for an unconstrained model
its unrolled LDL^T (in the same function, counted with it), for a
constrained one the straight-line partitioned or KKT solve on its longest
pivot path (gen.plan.small's Program: flops and divisions; the argument
checks, |x| and the pivot search are not counted). It ignores loads and
stores, latency chains, the call and the checks of the state, so a ratio
near 1 is not reachable: it is a lower bound. The ratio to the floor is the
median over the repeats of the model's time over the floor of the same
repeat. Nothing is asserted; tests/golden checks the seed's numbers.
"""
from __future__ import annotations

import argparse
import json
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

PROBE = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <time.h>
static double now(void) {
    struct timespec ts; clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
#define CHAINS(OP) do { \
    s0 = OP(s0); s1 = OP(s1); s2 = OP(s2); s3 = OP(s3); s4 = OP(s4); s5 = OP(s5); \
    s6 = OP(s6); s7 = OP(s7); s8 = OP(s8); s9 = OP(s9); s10 = OP(s10); s11 = OP(s11); \
} while (0)
static volatile double vm = 0.999999, va = 1e-7, vd = 1.3, vs = 0.5;
static volatile double sink;
/* kind 0: a product and a sum per chain (2 flops); 1: a division; 2: sqrt */
static double run(int kind, long n) {
    double s0 = 1, s1 = 1.1, s2 = 1.2, s3 = 1.3, s4 = 1.4, s5 = 1.5;
    double s6 = 1.6, s7 = 1.7, s8 = 1.8, s9 = 1.9, s10 = 2.0, s11 = 2.1;
    const double m = vm, a = va, d = vd, h = vs;
    long i;
    double t0 = now();
#define FMA_(x) ((x) * m + a)
#define DIV_(x) (d / (x))
#define SQRT_(x) sqrt((x) + h)
    if (kind == 0) for (i = 0; i < n; ++i) CHAINS(FMA_);
    else if (kind == 1) for (i = 0; i < n; ++i) CHAINS(DIV_);
    else for (i = 0; i < n; ++i) CHAINS(SQRT_);
    sink = s0 + s1 + s2 + s3 + s4 + s5 + s6 + s7 + s8 + s9 + s10 + s11;
    return (now() - t0) / (12.0 * n);
}
static double trig(long n) {
    double acc = 0, t0 = now();
    long i;
    for (i = 0; i < n; ++i) {
        double x = -1.0 + 2.0 * (double)(i % 1000) / 1000.0 + 1e-12 * (double)i;
        acc += sin(x) + cos(x);
    }
    sink = acc;
    return (now() - t0) / n;
}
int main(void) {
    double best[4] = {1, 1, 1, 1};
    int c, k;
    for (c = 0; c < 5; ++c) {
        for (k = 0; k < 3; ++k) {
            double t = run(k, 20000L);
            if (t < best[k]) best[k] = t;
        }
        { double t = trig(20000L); if (t < best[3]) best[3] = t; }
    }
    /* seconds per flop (a product-sum chain step is 2), per division, per
     * square root (less its sum, at the flop rate), per sin/cos pair */
    printf("%.6e %.6e %.6e %.6e\n", best[0] / 2, best[1], best[2] - best[0] / 2, best[3]);
    return 0;
}
"""


def build_probe(work):
    """The probe executable, built with the models' C flags."""
    from gen.codegen.backends.base import C_FLAGS
    src = Path(work) / "probe.c"
    exe = Path(work) / "probe"
    src.write_text(PROBE)
    subprocess.run(["gcc", *C_FLAGS, str(src), "-o", str(exe), "-lm"], check=True)
    return exe


def probe(exe):
    """{flop, div, sqrt, trig}: seconds per operation now (the best of five)."""
    vals = [float(v) for v in subprocess.run([str(exe)], capture_output=True, text=True,
                                             check=True).stdout.split()]
    return dict(zip(("flop", "div", "sqrt", "trig"), vals))


_LITERAL_RATIO = re.compile(r"(?<![\w\]\)])(\d+\.?\d*)\s*/\s*(\d+\.?\d*)")


def count_ops(c_text):
    """{arith, div, sqrt, trig} of straight-line C (bench/_cdriver.py's
    count_flops, a quotient of two literals being the compiler's)."""
    from _cdriver import count_flops
    text = _LITERAL_RATIO.sub("1", c_text)
    ops = count_flops(text)
    return {"arith": ops["add"] + ops["sub"] + ops["mul"], "div": ops["div"],
            "sqrt": len(re.findall(r"\bsqrt\s*\(", text)),
            "trig": max(ops["sin"], ops["cos"])}


def model_ops(model, work):
    """The floor's operations of a model's right-hand side: its fused
    kernel's, plus for a constrained model the straight-line solve's
    (gen.plan.small), or None when it has no fused kernel."""
    import gen
    from _cdriver import function_body
    from gen.plan.ir import plan
    from gen.plan.small import kernel_program
    out = Path(work) / model.name
    gen.generate(model, out)
    # (without the preprocessor lines of a large kernel's two versions)
    text = "\n".join(ln for ln in (out / f"{model.name}_kernels.c").read_text().splitlines()
                     if not ln.startswith("#"))
    name = f"{model.name}_k_rhs_terms"
    body = function_body(text, name + "_isa" if name + "_isa(" in text else name)
    if model.mv == 0:
        return count_ops(body)
    ops = count_ops(body.split("if (!out_ud)")[0])
    pl = plan(model, derivatives=False)
    prog = kernel_program(pl.kernels["rhs_terms"], pl.accel, model.nu, model.mv,
                          ind=model.u_ind, dep=model.u_dep)
    ops["arith"] += prog.flops
    ops["div"] += prog.divs
    ops["solve"] = {"flops": prog.flops, "divs": prog.divs, "paths": prog.paths}
    return ops


def floor_seconds(ops, rates):
    return (ops["arith"] * rates["flop"] + ops["div"] * rates["div"]
            + ops["sqrt"] * rates["sqrt"] + ops["trig"] * rates["trig"])


def models():
    import chaplygin_sleigh
    import four_bar
    import n_link_cart
    import rolling_disc
    import seed_pendulum
    return {"cart n=1": n_link_cart.model(1), "cart n=2": n_link_cart.model(2),
            "seed Kane": seed_pendulum.kane_model(),
            "seed Lagrange": seed_pendulum.lagrange_model(),
            "four-bar": four_bar.model(), "Chaplygin sleigh": chaplygin_sleigh.model(),
            "rolling disc": rolling_disc.model()}


def states(sim, n, seed=0):
    """n states: the seed's consistent, from its angle (helpers.pendulum_state),
    the carts' at random in [-1, 1], the other models' in [-0.5, 0.5]."""
    import numpy as np
    from helpers import pendulum_state
    rng = np.random.default_rng(seed)
    if "q1" in sim.state_names and sim.nx == 4 and "u2" in sim.state_names:
        kind = "lagrange" if "lagrange" in sim.name else "kane"
        return np.array([pendulum_state(a, w, 1.0, kind)
                         for a, w in zip(rng.uniform(-1, 1, n), rng.uniform(-1, 1, n))])
    if sim.name.startswith("cart"):
        return rng.uniform(-1, 1, (n, sim.nx))
    return rng.uniform(-0.5, 0.5, (n, sim.nx))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=21)
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    import numpy as np
    import gen
    work = tempfile.mkdtemp(prefix="bench_small_")
    mods = models()
    sims = {k: gen.compile(m) for k, m in mods.items()}
    ops = {k: model_ops(m, work) for k, m in mods.items()}
    exe = build_probe(work)
    data = {k: (s, states(s, args.n), np.empty((args.n, s.nx))) for k, s in sims.items()}
    for s, X, out in data.values():
        s.rhs_batch(0.0, X, out=out)                 # warm
    times = {k: [] for k in data}
    rates = []
    for _ in range(args.reps):
        for k, (s, X, out) in data.items():
            # each timed call after an untimed one of the same model: the
            # steady state an integrator sees, not the caches and branch
            # predictors the previous model (or the probe) left
            s.rhs_batch(0.0, X, out=out)
            t0 = time.perf_counter()
            s.rhs_batch(0.0, X, out=out)
            times[k].append((time.perf_counter() - t0) / args.n)
        rates.append(probe(exe))
    ref = statistics.median(times["cart n=1"])
    res = {"rates": {k: statistics.median(r[k] for r in rates) for k in rates[0]}}
    rt = res["rates"]
    print(f"rhs_batch per state, N = {args.n}, median of {args.reps} interleaved repeats; "
          f"rates: {1e-9 / rt['flop']:.2f} Gflop/s, division {rt['div'] * 1e9:.2f} ns, "
          f"sqrt {rt['sqrt'] * 1e9:.2f} ns, sin+cos {rt['trig'] * 1e9:.2f} ns")
    print("| model | states | ns per state (best) | / cart n=1 | ops (arith, div, sqrt, "
          "sin/cos) | floor ns | / floor (best / floor) |")
    print("|---|---|---|---|---|---|---|")
    best_ref = min(times["cart n=1"])
    for k, ts in times.items():
        med = statistics.median(ts)
        o = ops[k]
        fl = [floor_seconds(o, r) for r in rates]
        ratio = statistics.median(t / f for t, f in zip(ts, fl))
        fmed = statistics.median(fl)
        res[k] = {"ns": med * 1e9, "ns_best": min(ts) * 1e9, "ratio_cart1": med / ref,
                  "ratio_cart1_best": min(ts) / best_ref, "ops": o, "floor_ns": fmed * 1e9,
                  "ratio_floor": ratio, "ratio_floor_best": min(ts) / fmed}
        print(f"| {k} | {sims[k].nx} | {med * 1e9:.1f} ({min(ts) * 1e9:.1f}) | {med / ref:.2f} | "
              f"{o['arith']}, {o['div']}, {o['sqrt']}, {o['trig']} | "
              f"{fmed * 1e9:.1f} | {ratio:.2f} ({min(ts) / fmed:.2f}) |")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
