"""Helpers of bench/bench_peers.py: the C timing driver (eomgen's
<prefix>_eval_rhs against CasADi's generated function, in one executable,
interleaved repeats) and a floating-point operation count of printed,
straight-line C."""
from __future__ import annotations

import re
import statistics
import subprocess
import textwrap
from pathlib import Path

# ------------------------------------------------------------ op counting
_FLOAT = re.compile(r"(?<![\w\]])(\d+\.\d*|\.\d+|\d+)([eE][+-]?\d+)?")
_BINARY_MINUS = re.compile(r"(?<=[\w\)\]])\s*-(?!=|-|>)")


def function_body(c_text, name):
    """The text between the braces of the C function `name` (first definition)."""
    m = re.search(r"\b" + re.escape(name) + r"\s*\([^;{]*\)\s*\{", c_text)
    if m is None:
        raise ValueError(f"function {name} not found")
    i, depth = m.end(), 1
    while depth:
        ch = c_text[i]
        depth += ch == "{"
        depth -= ch == "}"
        i += 1
    return c_text[m.end():i - 1]


def count_flops(body):
    """Floating-point operations of straight-line C: binary + - * /, with
    sin/cos/tan/exp/log/sqrt/pow and CasADi's casadi_sq counted apart.
    Index arithmetic inside [...] and pointer offsets are ignored."""
    text = re.sub(r"/\*.*?\*/", " ", body, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    text = re.sub(r"\[[^\[\]]*\]", "[]", text)           # a[i*n+j] -> a[]
    text = _FLOAT.sub("1", text)                          # 1.5e-3 -> 1 (no '-' inside)
    # only the right-hand sides of assignments (casadi's `if (res[0]!=0) ...`)
    rhs = []
    for stmt in text.split(";"):
        if "=" in stmt:
            lhs, _, r = stmt.partition("=")
            if r.startswith("="):  # '==' comparison, not an assignment
                continue
            rhs.append(r.replace("!=", " ").replace("?", " ").replace(":", " "))
    t = "\n".join(rhs)
    funcs = {f: len(re.findall(r"\b" + f + r"\s*\(", t))
             for f in ("sin", "cos", "tan", "exp", "log", "sqrt", "pow", "casadi_sq", "fabs")}
    adds = t.count("+") - 2 * t.count("++")
    subs = len(_BINARY_MINUS.findall(t))
    muls = t.count("*")
    divs = t.count("/")
    return {"add": adds, "sub": subs, "mul": muls + funcs["casadi_sq"], "div": divs,
            "sin": funcs["sin"], "cos": funcs["cos"],
            "other_fn": funcs["tan"] + funcs["exp"] + funcs["log"] + funcs["sqrt"] + funcs["pow"],
            "arith": adds + subs + muls + funcs["casadi_sq"] + divs}


def cpu_info():
    """(model name, MHz, logical cores) from /proc/cpuinfo (None where unknown)."""
    name, mhz, cores = None, None, 0
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            k, _, v = line.partition(":")
            k, v = k.strip(), v.strip()
            if k == "model name" and name is None:
                name = v
            elif k == "cpu MHz" and mhz is None:
                mhz = float(v)
            elif k == "processor":
                cores += 1
    except OSError:
        pass
    return name, mhz, cores or None


# ------------------------------------------------------------ the driver
DRIVER = textwrap.dedent("""\
    #define _POSIX_C_SOURCE 199309L
    #include <stdio.h>
    #include <stdlib.h>
    #include <math.h>
    #include <time.h>
    #include "{p}.h"
    {cas_include}
    static double now(void) {{
        struct timespec ts; clock_gettime(CLOCK_MONOTONIC, &ts);
        return ts.tv_sec + 1e-9 * ts.tv_nsec;
    }}
    /* the clock the core runs at now: a chain of n (add, xor) pairs, one
     * cycle each on every x86-64 and ARMv8 core, which no compiler shortens */
    static unsigned long long chain(long n, unsigned long long a) {{
        long i;
        for (i = 0; i < n; ++i) a = (a + a) ^ (unsigned long long)i;
        return a;
    }}
    /* the machine's peak rate of scalar arithmetic, measured: twelve
     * independent chains of a product and a sum or a difference (operations
     * no compiler packs into vectors; enough chains to fill every pipe),
     * n iterations of 24 flops */
    static double peak(long n, double m, double a) {{
        double s0 = 1, s1 = 1.1, s2 = 1.2, s3 = 1.3, s4 = 1.4, s5 = 1.5;
        double s6 = 1.6, s7 = 1.7, s8 = 1.8, s9 = 1.9, s10 = 2.0, s11 = 2.1;
        long i;
        for (i = 0; i < n; ++i) {{
            s0 = s0 * m + a; s1 = s1 * m - a; s2 = a + s2 * m; s3 = s3 * m - a;
            s4 = s4 * m + a; s5 = s5 * m - a; s6 = a + s6 * m; s7 = s7 * m - a;
            s8 = s8 * m + a; s9 = s9 * m - a; s10 = a + s10 * m; s11 = s11 * m - a;
        }}
        return s0 + s1 + s2 + s3 + s4 + s5 + s6 + s7 + s8 + s9 + s10 + s11;
    }}
    int main(void) {{
        static const double x0[{P}_NX] = {{ {x0} }};
        static const double p[{np}] = {{ {pvals} }};
        double x[{P}_NX], r[{P}_NR + 1], d_eom[{P}_NX], d_cas[{P}_NX];
        volatile double sink = 0;
        volatile unsigned long long spin = 1;
        int i, rep, n = {iters};
        {cas_setup}
        for (i = 0; i < {P}_NX; ++i) x[i] = x0[i];
        for (i = 0; i <= {P}_NR; ++i) r[i] = 0.0;     /* the inputs at zero */
        if ({p}_eval_rhs(0.0, x, r, p, d_eom, NULL) != 0) return 2;
        {cas_check}
        for (rep = 0; rep < {reps}; ++rep) {{
            double t0, t1;
            for (i = 0; i < {P}_NX; ++i) x[i] = x0[i];
            t0 = now();
            for (i = 0; i < n; ++i) {{
                x[1] += 1e-12;
                if ({p}_eval_rhs(0.0, x, r, p, d_eom, NULL) != 0) return 1;
                sink += d_eom[{P}_NX - 1];
            }}
            t1 = now();
            printf("eomgen %.9g\\n", (t1 - t0) / n);
            {cas_loop}
            {{
                /* the fastest of 15 short chains: a chain that the VM's
                 * scheduler interrupts reads slow, one that runs through
                 * reads the core's clock */
                double best = 0;
                int c;
                for (c = 0; c < 15; ++c) {{
                    t0 = now();
                    spin = chain(20000L, spin);
                    t1 = now();
                    if (2 * 20000.0 / (t1 - t0) > best) best = 2 * 20000.0 / (t1 - t0);
                }}
                printf("clock %.9g\\n", best);
            }}
            {{
                volatile double pm = 0.999999, pa = 1e-7;
                double best = 0;
                int c;
                for (c = 0; c < 5; ++c) {{
                    t0 = now();
                    sink += peak(20000L, pm, pa);
                    t1 = now();
                    if (24 * 20000.0 / (t1 - t0) > best) best = 24 * 20000.0 / (t1 - t0);
                }}
                printf("peak %.9g\\n", best);
            }}
            {libm_loop}
        }}
        return sink == 12345.0;
    }}
""")

# the platform's sin and cos at the arguments the model's kernel takes
# (x[k] for k in the trig indices), per call of the loop: what the floor's
# trigonometric part costs on this machine with this libm
LIBM_LOOP = """
            for (i = 0; i < {P}_NX; ++i) x[i] = x0[i];
            t0 = now();
            for (i = 0; i < n; ++i) {{
                double acc = 0, d = 1e-12 * i;   /* every argument moves */
{calls}
                sink += acc;
            }}
            t1 = now();
            printf("libm %.9g\\n", (t1 - t0) / n);
"""

CAS_SETUP = """
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    const casadi_real **arg; casadi_real **res; casadi_int *iw; casadi_real *w;
    double maxdiff = 0;
    {f}_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
    arg = malloc(sizeof(*arg) * (sz_arg > 3 ? sz_arg : 3));
    res = malloc(sizeof(*res) * (sz_res > 1 ? sz_res : 1));
    iw = malloc(sizeof(*iw) * (sz_iw > 0 ? sz_iw : 1));
    w = malloc(sizeof(*w) * (sz_w > 0 ? sz_w : 1));
    arg[0] = x; arg[1] = r; arg[2] = p; res[0] = d_cas;
"""
CAS_CHECK = """
    if ({f}(arg, res, iw, w, 0) != 0) return 3;
    for (i = 0; i < {P}_NX; ++i) {{
        double dd = fabs(d_cas[i] - d_eom[i]) / (1.0 + fabs(d_eom[i]));
        if (dd > maxdiff) maxdiff = dd;
    }}
    printf("maxreldiff %.3g\\n", maxdiff);
"""
CAS_LOOP = """
            for (i = 0; i < {P}_NX; ++i) x[i] = x0[i];
            t0 = now();
            for (i = 0; i < n; ++i) {{
                x[1] += 1e-12;
                if ({f}(arg, res, iw, w, 0) != 0) return 1;
                sink += d_cas[{P}_NX - 1];
            }}
            t1 = now();
            printf("casadi %.9g\\n", (t1 - t0) / n);
"""


def time_rhs_in_c(eom_dir, prefix, x0, pvals, cas_c=None, cas_fname=None, reps=21,
                  iters=None, cc="gcc", runs=3, cflags=("-std=c99", "-O2"), trig=()):
    """Build one driver from eomgen's generated sources (and CasADi's
    generated .c if given) with cc and cflags, and return {'eomgen': s,
    'casadi': s, 'maxreldiff': d, 'clock': Hz} (median seconds per call, and
    the median clock the core ran at, measured between the repeats by the
    fastest of short chains of one-cycle integer operations; interleaved
    repeats). trig: the indices k of x whose sin and cos the kernel takes:
    the driver also times those calls of the platform's libm ('libm', s
    per call of the model). Each repeat also measures the peak rate of
    scalar arithmetic ('peak', flops/s; with trig, per repeat with eomgen's
    and the libm's times in 'repeats'). The driver
    is built once per (sources, compiler, flags, sizes): a second call runs
    it again."""
    eom_dir = Path(eom_dir)
    nx = len(x0)
    if iters is None:
        iters = max(500, int(2e6 / nx ** 2))
    P = prefix.upper()
    fmt = dict(p=prefix, P=P, f=cas_fname)
    src = DRIVER.format(
        p=prefix, P=P, np=len(pvals), iters=iters, reps=reps,
        x0=", ".join(repr(float(v)) for v in x0),
        pvals=", ".join(repr(float(v)) for v in pvals),
        cas_include=f'#include "{Path(cas_c).with_suffix(".h").name}"' if cas_c else "",
        cas_setup=CAS_SETUP.format(**fmt) if cas_c else "",
        cas_check=CAS_CHECK.format(**fmt) if cas_c else "",
        cas_loop=CAS_LOOP.format(**fmt) if cas_c else "",
        libm_loop=LIBM_LOOP.format(P=P, calls="\n".join(
            f"                acc += sin(x[{k}] + d) + cos(x[{k}] + d);" for k in trig)) if trig else "")
    tag = re.sub(r"\W", "_", Path(cc).name)
    drv = eom_dir / f"bench_driver_{tag}.c"
    exe = eom_dir / f"bench_driver_{tag}"
    from gen.codegen.render import model_sources
    srcs = [str(drv)] + [str(eom_dir / f) for f in model_sources(prefix)] + sorted(
        str(f) for f in eom_dir.glob("gen_rt_*.c"))
    incs = ["-I", str(eom_dir)]
    if cas_c:
        srcs.append(str(cas_c))
        incs += ["-I", str(Path(cas_c).parent)]
    cmd = [cc, *cflags, *incs, *srcs, "-o", str(exe), "-lm"]
    stamp = exe.with_suffix(".cmd")
    if not (exe.exists() and drv.exists() and drv.read_text() == src
            and stamp.exists() and stamp.read_text() == " ".join(cmd)):
        drv.write_text(src)
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError("driver build failed:\n$ " + " ".join(cmd) + "\n"
                               + proc.stderr[-4000:])
        stamp.write_text(" ".join(cmd))
    text = ""
    for _ in range(runs):          # separate runs, samples pooled (noisy machines)
        res = subprocess.run([str(exe)], capture_output=True, text=True)
        if res.returncode != 0:
            raise RuntimeError(f"driver exited with {res.returncode}: {res.stdout[-2000:]}")
        text += res.stdout
    vals = {"eomgen": [], "casadi": [], "clock": [], "libm": [], "peak": []}
    out = {"iters": iters, "reps": reps, "runs": runs, "cc": cc}
    for line in text.split("\n"):
        if not line.strip():
            continue
        k, v = line.split()
        if k == "maxreldiff":
            out["maxreldiff"] = float(v)
        else:
            vals[k].append(float(v))
    for k, v in vals.items():
        if v:
            out[k] = statistics.median(v)
            if k != "clock":
                out[k + "_min"] = min(v)
    # per repeat (the lines come in repeat order: eomgen, casadi, clock), so
    # that a change of the machine's speed between repeats cancels: the
    # median of the repeats' eomgen / CasADi ratios, and eomgen's cycles per
    # call at the clock measured in the same repeat
    e, c, hz = vals["eomgen"], vals["casadi"], vals["clock"]
    if c and len(c) == len(e):
        out["pair_ratio"] = statistics.median(a / b for a, b in zip(e, c))
    if hz and len(hz) == len(e):
        out["eomgen_cycles"] = statistics.median(a * f for a, f in zip(e, hz))
    if e and len(vals["peak"]) == len(e) == len(vals["libm"]):
        # per repeat, for the measured floor: eomgen's time, the libm's time
        # and the peak rate of the same repeat
        out["repeats"] = [{"eomgen": a, "libm": lm, "peak": pk}
                          for a, lm, pk in zip(e, vals["libm"], vals["peak"])]
    return out
