"""Benchmark (issue 47): the small constrained models per state, against the
1-link cart (4 states, unconstrained) in the same run.

    python bench/bench_small.py [--reps 21] [--n 1000] [--json PATH]

Each model is compiled (cached by content); ``sim.rhs_batch`` over N = 1000
random states into a preallocated ``out=`` is timed in interleaved repeats
(the machine is shared), and the median per state is printed with its ratio
to the 1-link cart's median. The models: the seed's Kane model (4 states,
one holonomic and one velocity constraint, a dependent coordinate and
speed: the partitioned solve), its Lagrange model (the KKT solve with one
multiplier), the 1-link and 2-link carts (examples/n_link_cart.py). Nothing
is asserted; tests/golden checks the seed's numbers.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))


def models():
    import gen
    import n_link_cart
    import seed_pendulum
    return {"cart n=1": gen.compile(n_link_cart.model(1)),
            "cart n=2": gen.compile(n_link_cart.model(2)),
            "seed Kane": gen.compile(seed_pendulum.kane_model()),
            "seed Lagrange": gen.compile(seed_pendulum.lagrange_model())}


def states(sim, n, seed=0):
    """n consistent states: the seed's from its angle (helpers.pendulum_state),
    the carts' at random."""
    import numpy as np
    from helpers import pendulum_state
    rng = np.random.default_rng(seed)
    if "q1" in sim.state_names and sim.nx == 4 and "u2" in sim.state_names:
        kind = "lagrange" if "lagrange" in sim.name else "kane"
        return np.array([pendulum_state(a, w, 1.0, kind)
                         for a, w in zip(rng.uniform(-1, 1, n), rng.uniform(-1, 1, n))])
    return rng.uniform(-1, 1, (n, sim.nx))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=21)
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    import numpy as np
    sims = models()
    data = {k: (s, states(s, args.n), np.empty((args.n, s.nx))) for k, s in sims.items()}
    for s, X, out in data.values():
        s.rhs_batch(0.0, X, out=out)                 # warm
    times = {k: [] for k in data}
    for _ in range(args.reps):
        for k, (s, X, out) in data.items():
            t0 = time.perf_counter()
            s.rhs_batch(0.0, X, out=out)
            times[k].append((time.perf_counter() - t0) / args.n)
    ref = statistics.median(times["cart n=1"])
    res = {}
    print(f"rhs_batch per state, N = {args.n}, median of {args.reps} interleaved repeats")
    print("| model | states | ns per state | / cart n=1 |")
    print("|---|---|---|---|")
    for k, ts in times.items():
        med = statistics.median(ts)
        res[k] = {"ns": med * 1e9, "ratio_cart1": med / ref}
        print(f"| {k} | {sims[k].nx} | {med * 1e9:.1f} | {med / ref:.2f} |")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
