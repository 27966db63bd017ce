"""gen.plan.small (issue 47): the straight-line accelerations traced from the
runtime's KKT and partitioned solves are the runtime's, bit for bit, or fail
before writing; wired into a small constrained model's fused right-hand
side, eval_rhs gives the general path's bits.

Reference: the runtime itself. A harness compiled with csrc/runtime calls
gen_rt_accel_kkt / gen_rt_accel_partitioned and the traced program on the
same inputs (random, with exact zeros, -0, tiny pivots, NaN and inf); where
the program returns GEN_RT_OK the runtime does too with the same bits (%a),
and where the runtime succeeds on a finite input so does the program."""
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from gen.plan.small import accel_program, c_lines

ROOT = Path(__file__).resolve().parents[3]
RT = ROOT / "csrc" / "runtime"

# the seed's shapes: n = 2 speeds, m = 1 constraint, M diagonal, f[0] and a
# structurally zero (the Kane model), and the same with every entry a value
CASES = {
    "kkt-seed": ("kkt", 2, 1, ["M0", 0, 0, "M3"], ["f0", "f1"], ["A0", "A1"], ["a0"], (), ()),
    "kkt-full": ("kkt", 2, 1, ["M0", "M1", "M1", "M3"], ["f0", "f1"], ["A0", "A1"], ["a0"],
                 (), ()),
    "part-seed": ("partitioned", 2, 1, ["M0", 0, 0, "M3"], [0, "f1"], ["A0", "A1"], [0],
                  (0,), (1,)),
    "part-3": ("partitioned", 3, 1, ["M0", "M1", 0, "M1", "M4", 0, 0, 0, "M8"],
               ["f0", "f1", "f2"], ["A0", "A1", "A2"], ["a0"], (0, 2), (1,)),
    # structural ones in A (a cart's x - ...: the KKT's -A^T gets a literal -1)
    "kkt-one": ("kkt", 2, 1, ["M0", "M1", "M1", "M3"], ["f0", "f1"], [1, "A1"], ["a0"], (), ()),
    "part-one": ("partitioned", 2, 1, ["M0", 0, 0, "M3"], ["f0", "f1"], ["A0", 1], ["a0"],
                 (0,), (1,)),
}
NAMES = ["M0", "M1", "M3", "M4", "M8", "f0", "f1", "f2", "A0", "A1", "A2", "a0"]


def _harness(tmp, key):
    method, n, m, M, f, A, a, ind, dep = CASES[key]
    prog = accel_program(method, n, m, M, f, A, a, ind=ind, dep=dep)
    assert prog is not None
    body = "\n".join(c_lines(prog, real="double"))
    def entry(v):
        return f"in[{NAMES.index(v)}]" if isinstance(v, str) else repr(float(v))
    decl = "\n".join(f"    const double {v} = in[{i}]; (void){v};" for i, v in enumerate(NAMES))
    call = (f"gen_rt_accel_kkt({n}, {m}, Mv, fv, Av, av, w, iw, ud, 0)" if method == "kkt" else
            f"gen_rt_accel_partitioned({n}, {m}, ind, dep, Mv, fv, Av, av, w, iw, ud, 0)")
    src = f"""#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "gen_rt_private.h"
static int small(const double *in, double *out_ud)
{{
{decl}
{body}
}}
int main(void)
{{
    double in[{len(NAMES)}], ud[{n}], mine[{n}], w[256];
    int iw[16], i;
    const int ind[] = {{{", ".join(map(str, ind)) or "0"}}}, dep[] = {{{", ".join(map(str, dep)) or "0"}}};
    (void)ind; (void)dep;
    char buf[64];
    for (;;) {{
        for (i = 0; i < {len(NAMES)}; ++i) {{
            if (scanf("%63s", buf) != 1) return 0;
            in[i] = strtod(buf, 0);
        }}
        const double Mv[] = {{{", ".join(entry(v) for v in M)}}};
        const double fv[] = {{{", ".join(entry(v) for v in f)}}};
        const double Av[] = {{{", ".join(entry(v) for v in A)}}};
        const double av[] = {{{", ".join(entry(v) for v in a)}}};
        int st = {call};
        int s2 = small(in, mine);
        printf("%d %d", st, s2);
        for (i = 0; i < {n}; ++i) printf(" %a %a", st ? 0.0 : ud[i], s2 ? 0.0 : mine[i]);
        printf("\\n");
    }}
}}
"""
    c = tmp / f"{key}.c"
    c.write_text(src)
    exe = tmp / key
    sources = [str(RT / s) for s in ("gen_rt_dynamics.c", "gen_rt_linalg.c", "gen_rt_status.c")]
    r = subprocess.run(["cc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic",
                        "-Wno-unused-variable", "-I", str(RT), str(c), *sources, "-lm",
                        "-o", str(exe)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[:3000]
    return exe


def _inputs(rng, k):
    rows = rng.uniform(-2, 2, (k, len(NAMES)))
    rows[:, [0, 2, 3, 4]] = rng.uniform(0.5, 2, (k, 4))       # positive masses
    special = [0.0, -0.0, 1e-300, -1e-17, np.nan, np.inf, 1.0]
    for row in rows[k // 2:]:                                 # half with special entries
        for j in rng.choice(len(NAMES), 2, replace=False):
            row[j] = special[rng.integers(len(special))]
    return rows


@pytest.mark.parametrize("key", [k if "seed" in k else pytest.param(k, marks=pytest.mark.slow)
                                 for k in sorted(CASES)])
def test_straight_line_solve_is_the_runtime_bit_for_bit(key, tmp_path):
    if shutil.which("cc") is None:
        pytest.skip("no C compiler (cc)")
    exe = _harness(tmp_path, key)
    rows = _inputs(np.random.default_rng(sorted(CASES).index(key)), 4000)
    text = "\n".join(" ".join(float(v).hex() if np.isfinite(v) else str(v) for v in r)
                     for r in rows) + "\n"
    out = subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True)
    ok = 0
    for r, line in zip(rows, out.stdout.splitlines()):
        st, s2, *vals = line.split()
        if s2 == "0":
            ok += 1
            assert st == "0", (r, line)
            assert vals[0::2] == vals[1::2], (r, line)
        elif st == "0" and np.all(np.isfinite(r)):
            pytest.fail(f"the runtime solved {r.tolist()} and the program did not: {line}")
    assert ok > 2000


@pytest.mark.parametrize("which", ["kane", "lagrange"])
def test_models_fused_solve_is_the_general_path(which, request):
    """The seed's models: eval_rhs without multipliers (the fused kernel's
    straight-line solve) gives the same status and bits as with them (the
    runtime's general path, gen_rt_accel_partitioned / gen_rt_accel_kkt),
    at consistent states, states off the constraints, and at q1 = 0, where
    the Kane model's velocity constraint divides by zero (the fused solve
    fails there and the general path names the failure)."""
    from helpers import pendulum_state
    sim = request.getfixturevalue(f"{which}_sim")
    fn = sim.library.function("eval_rhs")
    ffi = sim.library.ffi
    rng = np.random.default_rng(3)
    states = [pendulum_state(a, w, 1.0, which) for a, w in rng.uniform(-3, 3, (100, 2))]
    states += list(rng.uniform(-2, 2, (100, 4)))
    q1 = sim.state_names.index("q1")
    for x in states[:10]:
        y = np.array(x, dtype=float)
        y[q1] = 0.0
        states.append(y)
    fails = 0
    for x in states:
        x = np.ascontiguousarray(x, dtype=float)
        fast, slow, lam = (ffi.new("eomgen_real[]", 4), ffi.new("eomgen_real[]", 4),
                           ffi.new("eomgen_real[]", 1))
        xp = ffi.cast("eomgen_real *", ffi.from_buffer(x))
        st1 = fn(0.0, xp, ffi.NULL, ffi.NULL, fast, ffi.NULL)
        st2 = fn(0.0, xp, ffi.NULL, ffi.NULL, slow, lam)
        assert st1 == st2, (x, st1, st2)
        if st1 == 0:
            assert [float(v).hex() for v in fast] == [float(v).hex() for v in slow], x
        fails += st1 != 0
    assert fails < len(states) // 4



@pytest.mark.parametrize("which", ["kane", "lagrange"])
def test_models_fused_solve_tests_every_input(which, request):
    """eval_rhs of a small constrained model tests its inputs only where the
    fused solve failed; the solve's own finite test holds every input (the
    state, t and the constants), so a NaN or an infinity in any one of them
    is still GEN_RT_ERR_NONFINITE_INPUT (gen_rt_status.h), with or without
    multipliers, and a NULL state or output GEN_RT_ERR_NULL."""
    from gen.core.status import status_value
    from helpers import pendulum_state
    sim = request.getfixturevalue(f"{which}_sim")
    fn = sim.library.function("eval_rhs")
    ffi = sim.library.ffi
    x0 = np.array(pendulum_state(0.4, 0.2, 1.0, which), dtype=float)
    p0 = np.array(sim.constants, dtype=float)
    out, lam = ffi.new("eomgen_real[]", 4), ffi.new("eomgen_real[]", 1)

    def ptr(v):
        return ffi.cast("eomgen_real *", ffi.from_buffer(v))

    def call(x, t=0.0, p=None, with_lam=False):
        x = np.ascontiguousarray(x, dtype=float)
        return fn(t, ptr(x), ffi.NULL, ffi.NULL if p is None else ptr(p), out,
                  lam if with_lam else ffi.NULL)

    assert call(x0) == 0 and call(x0, p=p0) == 0
    codes = []
    for bad in (np.nan, np.inf, -np.inf):
        for with_lam in (False, True):
            for i in range(4):
                x = x0.copy()
                x[i] = bad
                codes.append(call(x, with_lam=with_lam))
            codes.append(call(x0, t=bad, with_lam=with_lam))
            for i in range(len(p0)):
                p = p0.copy()
                p[i] = bad
                codes.append(call(x0, p=p, with_lam=with_lam))
    assert set(codes) == {status_value("ERR_NONFINITE_INPUT")}, codes
    null = status_value("ERR_NULL")
    assert fn(0.0, ffi.NULL, ffi.NULL, ffi.NULL, out, ffi.NULL) == null
    assert fn(0.0, ptr(x0), ffi.NULL, ffi.NULL, ffi.NULL, ffi.NULL) == null
