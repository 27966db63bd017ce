"""Time per right-hand-side call and per linearize call, C backend against
the C++/Eigen backend, for the seed Kane pendulum and the n-link pendulum on
a cart (n = 2, 4, 8 by default).

Timed in compiled code, not through Python: for each model both backends
are generated (prefixes <model>_c and <model>_e), and a small C++ driver
calls the C backend's <p>_eval_rhs / <p>_linearize and the Eigen backend's
typed eval_rhs / linearize in a loop over 64 precomputed states. The Eigen
backend is a typed face over the C runtime (gen/codegen/backends/eigen.py): the driver links
its C model (<model>_e.c, ...) and one copy of the runtime, which both
models share (the same sources and flags). Batches of
each are interleaved and repeated; the table shows the median ns/call and
the ratio Eigen/C (< 1: Eigen faster). Both sides are compiled with the same
optimization (-O2 -DNDEBUG, no -march), both check their inputs for NaN/inf.

    python bench/bench_eigen.py                  # seed, cart n = 2, 4, 8
    python bench/bench_eigen.py --n 2 4 --repeats 31 --keep out/bench_eigen
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "examples"))

import gen  # noqa: E402
from gen.codegen.backends import eigen_include_dir  # noqa: E402
from gen.codegen.backends import RUNTIME_SOURCES  # noqa: E402
from gen.codegen.render import model_sources  # noqa: E402

DRIVER = r"""
// bench driver for {P}: C backend ({pc}_*) against the typed Eigen API ({pe}::)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "{pc}.h"
#include "{pe}.hpp"

namespace pe = {pe};
using Clock = std::chrono::steady_clock;
static volatile double sink;
constexpr int NSTATES = 64;

struct States {{
    pe::State<double> x[NSTATES];
    pe::Inputs<double> r[NSTATES];
}};

template <typename F>
static double time_batch(F &&f, long n)
{{
    const auto t0 = Clock::now();
    for (long i = 0; i < n; ++i) f(static_cast<int>(i % NSTATES));
    const auto t1 = Clock::now();
    return std::chrono::duration<double, std::nano>(t1 - t0).count() / static_cast<double>(n);
}}

static double median(std::vector<double> v)
{{
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}}

int main(int argc, char **argv)
{{
    const int repeats = argc > 1 ? std::atoi(argv[1]) : 15;
    const double target_ns = argc > 2 ? std::atof(argv[2]) : 2e7;   // per batch
    States s;
    unsigned long long seed = 12345;
    auto uni = [&seed]() {{
        seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
        return static_cast<double>(seed >> 11) / 9007199254740992.0 * 2.0 - 1.0;
    }};
    const pe::Params<double> p = pe::default_params<double>();
    for (int k = 0; k < NSTATES; ++k) {{
        {fill}
        for (int i = 0; i < pe::NR; ++i) s.r[k][i] = uni();
    }}
    // the kernels under test
    auto rhs_c = [&](int k) {{
        double dx[pe::NX];
        {pc}_eval_rhs(0.0, s.x[k].data(), s.r[k].data(), p.data(), dx, nullptr);
        sink = dx[pe::NX - 1];
    }};
    auto rhs_e = [&](int k) {{
        pe::State<double> dx;
        pe::eval_rhs(0.0, s.x[k], s.r[k], p, dx);
        sink = dx[pe::NX - 1];
    }};
    auto lin_c = [&](int k) {{
        double A[pe::NS * pe::NS], B[pe::NS * (pe::NR > 0 ? pe::NR : 1)];
        {pc}_linearize(s.x[k].data(), s.r[k].data(), p.data(), 0.0, A, B);
        sink = A[pe::NS * pe::NS - 1];
    }};
    auto lin_e = [&](int k) {{
        pe::StateMatrix<double> A;
        pe::InputMatrix<double> B;
        pe::linearize(s.x[k], s.r[k], p, 0.0, A, B);
        sink = A(pe::NS - 1, pe::NS - 1);
    }};
    // agreement at every state (the benchmark times the same computation)
    double worst = 0;
    for (int k = 0; k < NSTATES; ++k) {{
        double dxc[pe::NX], Ac[pe::NS * pe::NS], Bc[pe::NS * (pe::NR > 0 ? pe::NR : 1)];
        pe::State<double> dxe;
        pe::StateMatrix<double> Ae;
        pe::InputMatrix<double> Be;
        int st = {pc}_eval_rhs(0.0, s.x[k].data(), s.r[k].data(), p.data(), dxc, nullptr);
        st |= {pc}_linearize(s.x[k].data(), s.r[k].data(), p.data(), 0.0, Ac, Bc);
        st |= pe::eval_rhs(0.0, s.x[k], s.r[k], p, dxe);
        st |= pe::linearize(s.x[k], s.r[k], p, 0.0, Ae, Be);
        if (st) {{ std::fprintf(stderr, "status %d at state %d\n", st, k); return 1; }}
        const double e1 = (dxe - Eigen::Map<const pe::State<double>>(dxc)).cwiseAbs().maxCoeff()
                          / dxe.cwiseAbs().maxCoeff();
        const double e2 = (Ae - Eigen::Map<const pe::StateMatrix<double>>(Ac)).cwiseAbs().maxCoeff()
                          / Ae.cwiseAbs().maxCoeff();
        worst = std::max(worst, std::max(e1, e2));
    }}
    // calibrate the batch sizes on a first run of each
    auto calib = [&](auto &f) {{
        long n = 16;
        while (time_batch(f, n) * static_cast<double>(n) < target_ns / 4 && n < (1L << 30)) n *= 2;
        return std::max(16L, static_cast<long>(target_ns / time_batch(f, n)));
    }};
    const long n_rc = calib(rhs_c), n_re = calib(rhs_e), n_lc = calib(lin_c), n_le = calib(lin_e);
    std::vector<double> rc, re, lc, le;
    for (int i = 0; i < repeats; ++i) {{       // interleaved: the same noise for both
        rc.push_back(time_batch(rhs_c, n_rc));
        re.push_back(time_batch(rhs_e, n_re));
        lc.push_back(time_batch(lin_c, n_lc));
        le.push_back(time_batch(lin_e, n_le));
    }}
    std::printf("%.3f %.3f %.3f %.3f %.3e\n", median(rc), median(re), median(lc), median(le), worst);
    return 0;
}}
"""

FILL_PENDULUM = """const double th = 1.2 * uni(), thd = 3.0 * uni(), L = p[0];
        s.x[k] << L * std::sin(th), L * std::cos(th), L * std::cos(th) * thd,
                  -L * std::sin(th) * thd;"""
FILL_FREE = """for (int i = 0; i < pe::NX; ++i) s.x[k][i] = uni();"""

CXX = os.environ.get("CXX", "g++")
CC = os.environ.get("CC", "gcc")
FLAGS = ["-O2", "-DNDEBUG"]


def models(ns):
    import n_link_cart as nl
    import seed_pendulum as sp
    out = [("seed (Kane)", lambda name: sp.kane_model(name=name), "seed", FILL_PENDULUM)]
    for n in ns:
        out.append((f"cart n={n}", lambda name, n=n: nl.model(n, name=name), f"cart{n}",
                    FILL_FREE))
    return out


def build(work: Path, label, make, stem, fill, eigen):
    t0 = time.perf_counter()
    pc, pe = f"{stem}_c", f"{stem}_e"
    mc, me = make(pc), make(pe)
    d = work / stem
    gen.generate(mc, d / "c")
    gen.generate(me, d / "e", backend="eigen")
    (d / "driver.cpp").write_text(DRIVER.format(P=label, pc=pc, pe=pe, fill=fill))
    objs = []
    for folder, src in ([("c", s) for s in model_sources(pc) + RUNTIME_SOURCES]
                        + [("e", s) for s in model_sources(pe)]):
        o = d / (src + ".o")
        subprocess.run([CC, "-std=c99", *FLAGS, "-c", str(d / folder / src), "-o", str(o),
                        "-I", str(d / folder)], check=True)
        objs.append(str(o))
    exe = d / "bench"
    r = subprocess.run([CXX, "-std=c++17", *FLAGS, "-I", str(d / "c"), "-I", str(d / "e"),
                        "-isystem", str(eigen), str(d / "driver.cpp"), *objs, "-lm", "-o",
                        str(exe)], capture_output=True, text=True)
    if r.returncode:
        raise SystemExit(f"compiling the driver for {label} failed:\n{r.stderr}")
    return label, exe, me, time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="*", default=[2, 4, 8], help="cart link counts")
    ap.add_argument("--repeats", type=int, default=15, help="interleaved batches (median)")
    ap.add_argument("--batch-ms", type=float, default=20.0, help="target time per batch")
    ap.add_argument("--keep", help="build in this directory and keep it")
    args = ap.parse_args(argv)
    eigen = eigen_include_dir()
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench_eigen-"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        print(f"building {len(args.n) + 1} drivers (Eigen {eigen}) ...", flush=True)
        with ThreadPoolExecutor(max_workers=2) as pool:
            built = list(pool.map(lambda m: build(work, *m, eigen), models(args.n)))
        rows = []
        for label, exe, model, secs in built:
            r = subprocess.run([str(exe), str(args.repeats), str(args.batch_ms * 1e6)],
                               capture_output=True, text=True)
            if r.returncode:
                raise SystemExit(f"{label}: {r.stderr}")
            rc, re_, lc, le, worst = map(float, r.stdout.split())
            rows.append((label, model.nx, model.ns, rc, re_, lc, le, worst))
        print()
        print(f"{'model':<12} {'nx':>3} {'ns':>3} | {'rhs C':>9} {'rhs Eigen':>9} {'E/C':>5} | "
              f"{'lin C':>9} {'lin Eigen':>9} {'E/C':>5} | {'max rel diff':>12}")
        print(f"{'':<12} {'':>3} {'':>3} | {'ns/call':>9} {'ns/call':>9} {'':>5} | "
              f"{'ns/call':>9} {'ns/call':>9} {'':>5} |")
        print("-" * 92)
        for label, nx, ns, rc, re_, lc, le, worst in rows:
            print(f"{label:<12} {nx:>3} {ns:>3} | {rc:>9.1f} {re_:>9.1f} {re_ / rc:>5.2f} | "
                  f"{lc:>9.1f} {le:>9.1f} {le / lc:>5.2f} | {worst:>12.1e}")
        print(f"\nmedian of {args.repeats} interleaved batches of ~{args.batch_ms:g} ms; "
              f"{CXX}/{CC} {' '.join(FLAGS)}; Eigen side: the typed C++ API")
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
