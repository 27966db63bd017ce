"""The matrix exponential and the zero-order-hold discretization of the
runtime, csrc/gen_rt_expm.c (the Eigen backend's too: its face calls it).

* tests/c/test_expm.c (closed forms, statuses, work-array guards) built with
  the strict C99 flags in double, in float (-DGEN_RT_REAL_FLOAT, as the CMake
  option EOMGEN_REAL_FLOAT does) and under ASan + UBSan (slow);
* gen_rt_expm and gen_rt_c2d_zoh through cffi against scipy.linalg.expm
  (random matrices of sizes 1..12 and 1-norms 1e-3..1e3; the augmented
  matrix [[A, B], [0, 0]] dt for the discretization), in double and float.

The fast builds start together (a thread per build) when the module's first
test asks for one of them.
"""
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from conftest import require_tool

ROOT = Path(__file__).resolve().parents[3]
CSRC = ROOT / "csrc" / "runtime"
C_TEST = ROOT / "tests" / "c" / "test_expm.c"
RT_SOURCES = [CSRC / "gen_rt_expm.c", CSRC / "gen_rt_linalg.c", CSRC / "gen_rt_status.c"]
C_FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
SAN_FLAGS = ["-fsanitize=address,undefined", "-fno-omit-frame-pointer",
             "-fno-sanitize-recover=all"]
FLOAT = ["-DGEN_RT_REAL_FLOAT"]  # what CMake's EOMGEN_REAL_FLOAT defines

# status codes (gen_rt_status.h)
OK, ERR_DIVERGED = 0, -11
FLT_MAX = float(np.finfo(np.float32).max)

# the sizes the work arrays get from the header's macros, evaluated by C
SIZES_C = r"""
#include "gen_rt_expm.h"
int expm_work(int n) { return GEN_RT_EXPM_WORK(n); }
int expm_iwork(int n) { return GEN_RT_EXPM_IWORK(n); }
int c2d_work(int ns, int nr) { return GEN_RT_C2D_WORK(ns, nr); }
int c2d_iwork(int ns, int nr) { return GEN_RT_C2D_IWORK(ns, nr); }
"""

CDEF = """
int gen_rt_expm(int n, const {t} *A, {t} *work, int *iwork, {t} *E);
int gen_rt_c2d_zoh(int ns, int nr, const {t} *A, const {t} *B, {t} dt, {t} *work,
                   int *iwork, {t} *Ad, {t} *Bd);
int expm_work(int n);
int expm_iwork(int n);
int c2d_work(int ns, int nr);
int c2d_iwork(int ns, int nr);
"""

def _run(cmd, **kw):
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)


def _check(r, what):
    assert r.returncode == 0, f"{what} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}"
    return r


@pytest.fixture(scope="module")
def builds(tmp_path_factory):
    """Start the fast builds at once; each test waits for the one it needs."""
    gcc = require_tool("gcc")
    out = tmp_path_factory.mktemp("expm")
    (out / "sizes.c").write_text(SIZES_C)
    jobs = {}
    pool = ThreadPoolExecutor(max_workers=max(2, os.cpu_count() or 2))

    def c_test(name, extra):
        exe = out / name
        r = _run([gcc, *C_FLAGS, *extra, "-I", CSRC, "-I", C_TEST.parent, C_TEST,
                  *RT_SOURCES, "-o", exe, "-lm"])
        return r, exe

    def shared(name, extra):
        lib = out / f"lib{name}.so"
        r = _run([gcc, *C_FLAGS, *extra, "-O2", "-shared", "-fPIC", "-I", CSRC,
                  out / "sizes.c", *RT_SOURCES, "-o", lib, "-lm"])
        return r, lib

    jobs["c_double"] = pool.submit(c_test, "test_expm_double", [])
    jobs["c_float"] = pool.submit(c_test, "test_expm_float", FLOAT)
    jobs["lib_double"] = pool.submit(shared, "expm_double", [])
    jobs["lib_float"] = pool.submit(shared, "expm_float", FLOAT)
    yield {"dir": out, "jobs": jobs}
    pool.shutdown(wait=True)


def _get(builds, key):
    r, path = builds["jobs"][key].result()
    _check(r, f"build of {key}")
    return path


# ----------------------------------------------------------- tests/c/test_expm.c
@pytest.mark.parametrize("key", ["c_double", "c_float"])
def test_c_program(builds, key):
    exe = _get(builds, key)
    r = _check(_run([exe]), exe.name)
    assert "0 failed" in r.stdout


@pytest.mark.slow
@pytest.mark.fuzz
def test_c_program_sanitized(tmp_path):
    gcc = require_tool("gcc")
    for name, extra in (("double", []), ("float", FLOAT)):
        exe = tmp_path / f"test_expm_san_{name}"
        _check(_run([gcc, *C_FLAGS, *SAN_FLAGS, *extra, "-g", "-I", CSRC, "-I", C_TEST.parent,
                     C_TEST, *RT_SOURCES, "-o", exe, "-lm"]), f"sanitized build ({name})")
        r = _check(_run([exe]), f"sanitized run ({name})")
        assert "0 failed" in r.stdout
        assert "runtime error" not in r.stderr


# ------------------------------------------------------------ cffi against scipy
class Runtime:
    """gen_rt_expm / gen_rt_c2d_zoh of one shared object (double or float),
    with work arrays of exactly the macro sizes followed by guard values."""
    GUARD = 16
    SENTINEL = 12345.0

    def __init__(self, lib_path, single):
        import cffi
        self.ffi = cffi.FFI()
        self.t = "float" if single else "double"
        self.dtype = np.float32 if single else np.float64
        self.ffi.cdef(CDEF.format(t=self.t))
        self.lib = self.ffi.dlopen(str(lib_path))

    def _p(self, a, t=None):
        return self.ffi.from_buffer(f"{t or self.t}[]", a) if a is not None else self.ffi.NULL

    def _work(self, nw, ni):
        w = np.full(nw + self.GUARD, self.SENTINEL, dtype=self.dtype)
        iw = np.full(ni + self.GUARD, 12345, dtype=np.intc)
        return w, iw

    def _guards_intact(self, w, iw, nw, ni):
        assert np.all(w[nw:] == self.SENTINEL), "work written beyond its macro size"
        assert np.all(iw[ni:] == 12345), "iwork written beyond its macro size"

    def expm(self, A):
        n = A.shape[0]
        a = np.ascontiguousarray(A, dtype=self.dtype)
        E = np.zeros((n, n), dtype=self.dtype)
        nw, ni = self.lib.expm_work(n), self.lib.expm_iwork(n)
        w, iw = self._work(nw, ni)
        st = self.lib.gen_rt_expm(n, self._p(a), self._p(w), self._p(iw, "int"), self._p(E))
        self._guards_intact(w, iw, nw, ni)
        return st, E

    def c2d(self, A, B, dt):
        ns, nr = A.shape[0], B.shape[1]
        a = np.ascontiguousarray(A, dtype=self.dtype)
        b = np.ascontiguousarray(B, dtype=self.dtype) if nr else None
        Ad = np.zeros((ns, ns), dtype=self.dtype)
        Bd = np.zeros((ns, nr), dtype=self.dtype) if nr else None
        nw, ni = self.lib.c2d_work(ns, nr), self.lib.c2d_iwork(ns, nr)
        w, iw = self._work(nw, ni)
        st = self.lib.gen_rt_c2d_zoh(ns, nr, self._p(a), self._p(b), dt, self._p(w),
                                     self._p(iw, "int"), self._p(Ad), self._p(Bd))
        self._guards_intact(w, iw, nw, ni)
        return st, Ad, (Bd if nr else np.zeros((ns, 0)))


def norm1(a):
    return float(np.abs(a).sum(axis=0).max()) if a.size else 0.0


def rel_err(got, ref):
    """||got - ref||_1 / ||ref||_1 (the absolute error when ref is 0)"""
    r = norm1(ref)
    e = norm1(np.asarray(got, dtype=np.float64) - ref)
    return e / r if r > 0 else e


def random_matrices(count=50, seed=20261123):
    """count matrices of sizes 1..12 (in turn), 1-norms log-uniform in 1e-3..1e3"""
    rng = np.random.default_rng(seed)
    for k in range(count):
        n = 1 + k % 12
        A = rng.standard_normal((n, n))
        yield A * (10.0 ** rng.uniform(-3, 3) / norm1(A))


def float_tol(nrm):
    """exp's relative condition number is at least ||A||: in float the error
    grows like ||A|| u (u = 6e-8), beyond 1e-5 from ||A||_1 ~ 100 on"""
    return 1e-5 * max(1.0, nrm / 100.0)


@pytest.fixture(scope="module")
def rt_double(builds):
    return Runtime(_get(builds, "lib_double"), single=False)


@pytest.fixture(scope="module")
def rt_float(builds):
    return Runtime(_get(builds, "lib_float"), single=True)


def expm_mp(A, dps=40):
    """exp(A) in 40-digit arithmetic (mpmath, sympy's dependency), rounded"""
    import mpmath
    with mpmath.workdps(dps):
        E = mpmath.expm(mpmath.matrix(A.tolist()))
        return np.array([[float(E[i, j]) for j in range(E.cols)] for i in range(E.rows)])


def test_expm_vs_scipy_double(rt_double):
    """Against scipy.linalg.expm, and where the two differ by 1e-13 or more,
    against exp in 40 digits: scipy's own error reaches ~4e-12 on some of
    these (1-norms of several hundred), so there the distance to scipy is
    held to 1e-12 plus scipy's distance to the 40-digit value, and the
    distance to that value to 1e-12."""
    worst = worst_mp = worst_scipy_own = 0.0
    for A in random_matrices():
        ref = sla.expm(A)
        st, E = rt_double.expm(A)
        if not np.all(np.isfinite(ref)):
            assert st == ERR_DIVERGED
            continue
        assert st == OK
        err = rel_err(E, ref)
        worst = max(worst, err)
        if err < 1e-13:  # two algorithms agree: both are right
            continue
        ref_mp = expm_mp(A)
        err_mp, scipy_own = rel_err(E, ref_mp), rel_err(ref, ref_mp)
        assert err_mp < 1e-12, (A.shape, norm1(A), err_mp)
        assert err < 1e-12 + scipy_own, (A.shape, norm1(A), err, scipy_own)
        worst_mp = max(worst_mp, err_mp)
        worst_scipy_own = max(worst_scipy_own, scipy_own)
    print(f"gen_rt_expm double: max relative error vs scipy {worst:.3g}; where that is "
          f">= 1e-13: vs 40 digits {worst_mp:.3g} (scipy's {worst_scipy_own:.3g})")


def test_expm_vs_scipy_float(rt_float):
    worst, ok = 0.0, 0
    for A in random_matrices():
        a32 = A.astype(np.float32)
        ref = sla.expm(a32.astype(np.float64))  # exp of the matrix float holds
        big = np.abs(ref).max() if np.all(np.isfinite(ref)) else np.inf
        st, E = rt_float.expm(a32)
        if big > FLT_MAX:
            assert st == ERR_DIVERGED, (A.shape, norm1(A))
            continue
        if big > FLT_MAX / 1e3:  # close to overflow: a squaring may overflow
            assert st in (OK, ERR_DIVERGED)
            continue
        assert st == OK
        if norm1(ref) < 1e-30:  # below float's range: 0 (or subnormal) is right
            assert np.abs(E).max() < 1e-30
            continue
        err = rel_err(E, ref)
        assert err < float_tol(norm1(A)), (A.shape, norm1(A), err)
        worst, ok = max(worst, err), ok + 1
    assert ok >= 35  # most of the 50 are compared, not skipped as overflow
    print(f"gen_rt_expm float: max relative error vs scipy {worst:.3g}")


def c2d_cases(count=30, seed=7):
    """(A, B, dt): ns 1..8, nr 0..3, ||A||_1 1e-2..1e2, B in units 1e-3..1e3"""
    rng = np.random.default_rng(seed)
    for k in range(count):
        ns, nr = 1 + k % 8, k % 4
        A = rng.standard_normal((ns, ns))
        A *= 10.0 ** rng.uniform(-2, 2) / norm1(A)
        B = rng.standard_normal((ns, nr)) * 10.0 ** rng.uniform(-3, 3)
        yield A, B, float(10.0 ** rng.uniform(-3, 0.5))


def c2d_reference(A, B, dt):
    ns, nr = B.shape
    M = np.zeros((ns + nr, ns + nr))
    M[:ns, :ns] = A * dt
    M[:ns, ns:] = B * dt
    E = sla.expm(M)
    # the structure of the exact result: [[Ad, Bd], [0, I]]
    assert np.allclose(E[ns:, :ns], 0) and np.allclose(E[ns:, ns:], np.eye(nr))
    return E[:ns, :ns], E[:ns, ns:]


@pytest.mark.parametrize("single", [False, True], ids=["double", "float"])
def test_c2d_vs_scipy(rt_double, rt_float, single):
    rt = rt_float if single else rt_double
    worst = 0.0
    for A, B, dt in c2d_cases():
        if single:  # the numbers float holds
            A, B = (A.astype(np.float32).astype(np.float64),
                    B.astype(np.float32).astype(np.float64))
            dt = float(np.float32(dt))
        refA, refB = c2d_reference(A, B, dt)
        st, Ad, Bd = rt.c2d(A, B, dt)
        assert st == OK
        tol = float_tol(norm1(A) * dt) if single else 1e-12
        errs = [rel_err(Ad, refA)] + ([rel_err(Bd, refB)] if B.shape[1] else [])
        assert max(errs) < tol, (A.shape, B.shape, dt, errs)
        worst = max(worst, *errs)
    print(f"gen_rt_c2d_zoh {'float' if single else 'double'}: max relative error {worst:.3g}")


def test_c2d_known_units(rt_double):
    """B in units 1e9 times those of A (the power-of-two balancing): Bd stays
    relative-accurate, Ad is exp(A dt) regardless of B"""
    A = np.array([[0.0, 1.0], [-4.0, -0.4]])
    B = np.array([[0.0], [1e9]])
    dt = 0.05
    refA, refB = c2d_reference(A, B, dt)
    st, Ad, Bd = rt_double.c2d(A, B, dt)
    assert st == OK
    assert rel_err(Ad, sla.expm(A * dt)) < 1e-14
    assert rel_err(Ad, refA) < 1e-13
    assert rel_err(Bd, refB) < 1e-13
