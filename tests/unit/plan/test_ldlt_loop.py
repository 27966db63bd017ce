"""The mass-matrix solve of a large dense model: the runtime's LDL^T in
loops (csrc/gen_rt_ldlt.h, gen.plan.ldlt.LDLT_LOOP_MIN; issue 17). It does
the unrolled solve's operations in the same order, so it must give the
unrolled solve's bits, refuse what it refuses, agree with numpy, and leave
small models and sparse mass matrices unrolled."""
import subprocess
from pathlib import Path

import numpy as np
import pytest

import gen
import gen.plan.ldlt
import n_link_cart
from gen.codegen.backends import C_FLAGS, STRICT_FLAGS, c_compiler
from gen.plan.ldlt import ldlt_program
from helpers import ldlt_solve_c

CSRC = Path(__file__).resolve().parents[3] / "csrc" / "runtime"


def _solve_both(tmp_path, monkeypatch, Ms, fs, real="double", flags=()):
    """Each (M, f) solved by the unrolled solve and by the looped one, in one
    C program: [(status unrolled, status loop, x unrolled, x loop)], x read
    back from %a (exact)."""
    n = len(fs[0])
    dense = [[True] * n for _ in range(n)]
    monkeypatch.setattr(gen.plan.ldlt, "LDLT_LOOP_MIN", 10 ** 6)
    unrolled = ldlt_solve_c("u", n, dense, real)
    monkeypatch.setattr(gen.plan.ldlt, "LDLT_LOOP_MIN", 1)
    loop = ldlt_solve_c("l", n, dense, real)
    assert "gen_rt_ldlt_dense" in loop and "gen_rt_ldlt_dense" not in unrolled
    lit = lambda v: "NAN" if np.isnan(v) else repr(float(v))  # noqa: E731
    rows = lambda A: ", ".join("{" + ", ".join(lit(v) for v in np.ravel(a)) + "}" for a in A)  # noqa: E731
    src = (('#define GEN_RT_REAL_FLOAT\n' if real == "float" else "")
           + '#include <math.h>\n#include <stdio.h>\n#include "gen_rt_ldlt.h"\n' + unrolled + "\n" + loop + f"""
int main(void) {{
    static const {real} M[{len(Ms)}][{n * n}] = {{ {rows(Ms)} }};
    static const {real} f[{len(Ms)}][{n}] = {{ {rows(fs)} }};
    {real} xu[{n}], xl[{n}];
    int k, i;
    for (k = 0; k < {len(Ms)}; ++k) {{
        int su = u_mass_solve(M[k], f[k], xu), sl = l_mass_solve(M[k], f[k], xl);
        printf("%d %d", su, sl);
        for (i = 0; i < {n}; ++i) printf(" %a %a", su ? 0.0 : (double)xu[i], sl ? 0.0 : (double)xl[i]);
        printf("\\n");
    }}
    return 0;
}}
""")
    (tmp_path / "t.c").write_text(src)
    cmd = [c_compiler(), *C_FLAGS, *STRICT_FLAGS, *flags, "-I", str(CSRC), str(tmp_path / "t.c"),
           "-o", str(tmp_path / "t"), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr
    run = subprocess.run([str(tmp_path / "t")], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    out = []
    for line in run.stdout.splitlines():
        w = line.split()
        vals = np.array([float.fromhex(v) for v in w[2:]]).reshape(n, 2)
        out.append((int(w[0]), int(w[1]), vals[:, 0], vals[:, 1]))
    return out


def _spd(rng, n, cond_scale=1.0):
    B = rng.normal(size=(n, n))
    return B @ B.T + cond_scale * n * np.eye(n)


@pytest.mark.parametrize("n", [1, 2, 5, 24, pytest.param(33, marks=pytest.mark.slow),
                               pytest.param(40, marks=pytest.mark.slow)])
def test_loop_gives_the_unrolled_bits_and_numpy(tmp_path, monkeypatch, n):
    rng = np.random.default_rng(n)
    Ms = [_spd(rng, n) for _ in range(4)]
    fs = [rng.normal(size=n) for _ in range(4)]
    for M, f, (su, sl, xu, xl) in zip(Ms, fs, _solve_both(tmp_path, monkeypatch, Ms, fs)):
        assert su == sl == 0
        assert np.array_equal(xu.view(np.int64), xl.view(np.int64)), np.max(np.abs(xu - xl))
        ref = np.linalg.solve(M, f)
        assert np.max(np.abs(xl - ref)) <= 1e-12 * np.linalg.cond(M) * np.max(np.abs(ref))


def test_loop_float(tmp_path, monkeypatch):
    rng = np.random.default_rng(7)
    n = 26
    Ms = [_spd(rng, n) for _ in range(2)]
    fs = [rng.normal(size=n) for _ in range(2)]
    for M, f, (su, sl, xu, xl) in zip(Ms, fs, _solve_both(tmp_path, monkeypatch, Ms, fs, "float")):
        assert su == sl == 0
        assert np.array_equal(xu, xl)
        ref = np.linalg.solve(M, f)
        assert np.max(np.abs(xl - ref)) <= 1e-5 * np.linalg.cond(M) * np.max(np.abs(ref))


def test_loop_refuses_what_the_unrolled_refuses(tmp_path, monkeypatch):
    """Indefinite, singular, a NaN on the diagonal and off it, a zero
    matrix: GEN_RT_ERR_SINGULAR (-3) from both, and x not written."""
    n = 25
    rng = np.random.default_rng(11)
    good = _spd(rng, n)
    indefinite = good.copy()
    indefinite[7, 7] = -indefinite[7, 7]
    B = rng.normal(size=(n, n - 1))
    singular = B @ B.T                       # rank n - 1
    nan_diag = good.copy()
    nan_diag[3, 3] = np.nan
    nan_off = good.copy()
    nan_off[20, 4] = nan_off[4, 20] = np.nan
    cases = [indefinite, singular, nan_diag, nan_off, np.zeros((n, n))]
    fs = [np.ones(n)] * len(cases)
    res = _solve_both(tmp_path, monkeypatch, cases, fs)
    assert [(su, sl) for su, sl, _, _ in res] == [(-3, -3)] * len(cases)


@pytest.mark.slow
def test_loop_under_sanitizers(tmp_path, monkeypatch):
    rng = np.random.default_rng(5)
    n = 30
    Ms = [_spd(rng, n)]
    fs = [rng.normal(size=n)]
    flags = ("-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g")
    (su, sl, xu, xl), = _solve_both(tmp_path, monkeypatch, Ms, fs, flags=flags)
    assert su == sl == 0 and np.array_equal(xu, xl)


def test_threshold_keeps_small_and_sparse_models_unrolled(monkeypatch):
    lo = gen.plan.ldlt.LDLT_LOOP_MIN
    dense = lambda n: [[True] * n for _ in range(n)]  # noqa: E731
    assert not ldlt_program(lo - 1, dense(lo - 1))["loop"]
    assert ldlt_program(lo, dense(lo))["loop"]
    band = [[abs(i - j) <= 1 for j in range(40)] for i in range(40)]
    assert not ldlt_program(40, band)["loop"]        # structure beats loops


def test_model_with_the_loop_gives_the_unrolled_model_bit_for_bit(tmp_path, monkeypatch):
    """The 4-link cart with the threshold at 1 (its fused right-hand side
    and its mass_solve call the loops: a block of four columns and a
    panel of one) against the same model unrolled:
    rhs and linearize (which calls mass_solve) agree bit for bit, and rhs
    solves M u' = f for the model's own M and f."""
    m = n_link_cart.model(4, name="cart4loop")
    rng = np.random.default_rng(3)
    X = rng.uniform(-2.0, 2.0, size=(12, m.nx))
    out = {}
    for mode, thr in (("unrolled", 10 ** 6), ("loop", 1)):
        monkeypatch.setattr(gen.plan.ldlt, "LDLT_LOOP_MIN", thr)
        gen.generate(m, tmp_path / mode)
        for f in ("cart4loop_kernels.c", "cart4loop.c"):
            assert ("gen_rt_ldlt_dense" in (tmp_path / mode / f).read_text()) == (mode == "loop")
        sim = gen.compile(m)
        out[mode] = (np.array([sim.rhs(0.0, x) for x in X]),
                     np.array([sim.linearize(x)[0] for x in X[:3]]))
        nq = m.nq
        for x, dx in zip(X, out[mode][0]):
            M, f = sim.mass_matrix(x[:nq]), sim.forcing(x[:nq], x[nq:])
            np.testing.assert_allclose(dx[nq:], np.linalg.solve(M, f), rtol=1e-11, atol=1e-12)
    assert np.array_equal(out["loop"][0], out["unrolled"][0])
    assert np.array_equal(out["loop"][1], out["unrolled"][1])


def test_work_index_is_the_headers(tmp_path):
    """gen.plan.ldlt.ldlt_work_index (where a fused kernel stores M and f) and
    the header's GEN_RT_LDLT_M/D/F/WORK macros (where the solve reads them)
    are one layout."""
    from gen.plan.ldlt import ldlt_work_index
    ns = [1, 3, 4, 5, 24, 33]
    body = "".join(
        f'    for (i = 0; i < {n}; ++i) {{ printf("F %d %d %d\\n", {n}, i, GEN_RT_LDLT_F({n}, i));\n'
        f'        for (j = 0; j <= i; ++j) printf("M %d %d %d %d\\n", {n}, i, j, i == j ? '
        f'GEN_RT_LDLT_D({n}, j) : GEN_RT_LDLT_M({n}, i, j)); }}\n'
        f'    printf("W %d %d\\n", {n}, GEN_RT_LDLT_WORK({n}));\n' for n in ns)
    (tmp_path / "w.c").write_text('#include <stdio.h>\n#include "gen_rt_ldlt.h"\n'
                                  "int main(void) {\n    int i, j;\n" + body + "    return 0;\n}\n")
    subprocess.run([c_compiler(), *STRICT_FLAGS, "-I", str(CSRC), str(tmp_path / "w.c"), "-o",
                    str(tmp_path / "w")], check=True)
    out = subprocess.run([str(tmp_path / "w")], capture_output=True, text=True).stdout
    seen = {n: set() for n in ns}
    work = {}
    for line in out.splitlines():
        kind, *v = line.split()
        v = list(map(int, v))
        if kind == "F":
            assert v[2] == ldlt_work_index(v[0], v[1])
            seen[v[0]].add(v[2])
        elif kind == "M":
            assert v[3] == ldlt_work_index(v[0], v[1], v[2])
            seen[v[0]].add(v[3])
        else:
            work[v[0]] = v[1]
    for n in ns:    # distinct places, all inside the work array
        assert len(seen[n]) == n * (n + 1) // 2 + n and max(seen[n]) < work[n]
