"""The right-hand-side kernel of a large model is built twice, for the
baseline and for AVX, and picked by the CPU at load time (GEN_RT_CLONES in
csrc/gen_rt.h, gen.codegen.render.CLONE_MIN_STATEMENTS; issue 17; gen.compile
builds the two as two units in parallel, GEN_RT_CLONE_UNIT): the clones give
bit for bit the baseline's numbers (the same IEEE operations, no FMA), the
code compiles clean under the strict flags and the sanitizers, the threshold
keeps small models as they were, and the kernels are not exported."""
import platform
import subprocess
import sys

import numpy as np
import pytest

import gen
import gen.codegen.render
import n_link_cart
import seed_pendulum
from gen.codegen.backends import C_FLAGS, STRICT_FLAGS, c_compiler

DRIVER = r"""
#include <stdio.h>
#include "{p}.h"
int main(void) {{
    static const double X[{n}][{nx}] = {{ {states} }};
    double dxdt[{nx}];
    int k, i;
#if defined(__x86_64__) && defined(__GNUC__)
    __builtin_cpu_init();
    printf("avx %d\n", __builtin_cpu_supports("avx") ? 1 : 0);
#endif
    for (k = 0; k < {n}; ++k) {{
        int st = {p}_eval_rhs(0.25, X[k], NULL, NULL, dxdt, NULL);
        printf("%d", st);
        for (i = 0; i < {nx}; ++i) printf(" %a", dxdt[i]);
        printf("\n");
    }}
    return 0;
}}
"""

X86_LINUX = sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64")


def _sources(model, out, monkeypatch, threshold=0):
    monkeypatch.setattr(gen.codegen.render, "CLONE_MIN_STATEMENTS", threshold)
    gen.generate(model, out)
    return out


def _build(src, prefix, nx, states, name, flags, split=False):
    """The driver over the model's sources; split: the kernels file compiled
    as its two units (GEN_RT_CLONE_UNIT 1 and 2, as gen.compile does)."""
    drv = src / f"drv_{name}.c"
    rows = ", ".join("{" + ", ".join(repr(float(v)) for v in x) + "}" for x in states)
    drv.write_text(DRIVER.format(p=prefix, n=len(states), nx=nx, states=rows))
    from gen.codegen.render import model_sources
    srcs = [str(drv)] + [str(src / f) for f in model_sources(prefix)] + sorted(
        str(f) for f in src.glob("gen_rt_*.c"))
    if split:
        kern = str(src / f"{prefix}_kernels.c")
        srcs.remove(kern)
        for unit in (1, 2):
            obj = src / f"kernels_{name}_{unit}.o"
            cmd = [c_compiler(), *C_FLAGS, *STRICT_FLAGS, *flags, f"-DGEN_RT_CLONE_UNIT={unit}",
                   "-I", str(src), "-c", kern, "-o", str(obj)]
            proc = subprocess.run(cmd, capture_output=True, text=True)
            assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr
            srcs.append(str(obj))
    exe = src / f"drv_{name}"
    cmd = [c_compiler(), *C_FLAGS, *STRICT_FLAGS, *flags, "-I", str(src), *srcs, "-o", str(exe),
           "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0 and not proc.stderr.strip(), " ".join(cmd) + "\n" + proc.stderr
    return exe


def _run(exe):
    proc = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    lines = proc.stdout.splitlines()
    avx = [ln for ln in lines if ln.startswith("avx")]
    return [ln for ln in lines if not ln.startswith("avx")], avx


@pytest.mark.slow
@pytest.mark.parametrize("which", ["cart", "kane"])
def test_clones_give_the_baseline_bit_for_bit(tmp_path, monkeypatch, which):
    """With the threshold at 0 the seed Kane pendulum (constrained: the
    fused right-hand side with its straight-line partitioned solve,
    gen.plan.small) and the 2-link cart (the fused right-hand side with its
    unrolled LDL^T) get the clones; the library built with them gives, at
    random states, the same bits as the same sources built with
    GEN_RT_NO_CLONES, and the same under ASan and UBSan. The numbers are
    checked against M u' = f from sympy's own matrices elsewhere
    (test_golden_numbers, test_seed_pendulum); here the claim is identity."""
    if which == "cart":
        model, prefix = n_link_cart.model(2), "cart2"
    else:
        model, prefix = seed_pendulum.kane_model(), "pendulum_kane"
    src = _sources(model, tmp_path / "src", monkeypatch)
    kern = (src / f"{prefix}_kernels.c").read_text()
    assert f"GEN_RT_CLONES static int {prefix}_k_rhs_terms_isa(" in kern
    rng = np.random.default_rng(17)
    nx = model.nq + model.nu
    if which == "cart":
        states = rng.uniform(-3, 3, (12, nx))
    else:
        from helpers import pendulum_state
        states = [pendulum_state(th, w, 1.0, "kane")
                  for th, w in rng.uniform(-2.5, 2.5, (12, 2))]
    base, _ = _run(_build(src, prefix, nx, states, "base", ["-DGEN_RT_NO_CLONES"]))
    clones, avx = _run(_build(src, prefix, nx, states, "clones", []))
    split, _ = _run(_build(src, prefix, nx, states, "split", [], split=True))
    assert all(ln.split()[0] == "0" for ln in base), base
    assert clones == base and split == base
    if X86_LINUX:
        exe = src / "drv_clones"
        syms = subprocess.run(["nm", str(exe)], capture_output=True, text=True).stdout
        assert f"{prefix}_k_rhs_terms_isa.avx" in syms, "no AVX clone was built"
        assert avx, "the driver did not report the CPU"
        syms = subprocess.run(["nm", str(src / "drv_split")], capture_output=True,
                              text=True).stdout
        assert f"{prefix}_k_rhs_terms_avx" in syms and f"{prefix}_k_rhs_terms_pick" in syms


@pytest.mark.slow
def test_clones_are_sanitizer_clean(tmp_path, monkeypatch):
    """The fused kernel's clones under ASan and UBSan: the baseline's bits."""
    src = _sources(n_link_cart.model(2), tmp_path / "src", monkeypatch)
    states = np.random.default_rng(5).uniform(-3, 3, (8, 6))
    base, _ = _run(_build(src, "cart2", 6, states, "base", ["-DGEN_RT_NO_CLONES"]))
    san = ["-O1", "-g", "-fno-omit-frame-pointer", "-fsanitize=address,undefined",
           "-fno-sanitize-recover=all"]
    sanitized, _ = _run(_build(src, "cart2", 6, states, "san", san))
    assert sanitized == base
    sanitized, _ = _run(_build(src, "cart2", 6, states, "san_split", san, split=True))
    assert sanitized == base


def test_small_models_keep_one_kernel(tmp_path, monkeypatch):
    """Below the threshold (the default's 300 statements: the 2-link cart
    has about 100) the kernel is built once, as before."""
    src = _sources(n_link_cart.model(2), tmp_path / "src", monkeypatch,
                   threshold=gen.codegen.render.CLONE_MIN_STATEMENTS)
    kern = (src / "cart2_kernels.c").read_text()
    assert "GEN_RT_CLONES" not in kern and "_isa" not in kern
    assert "int cart2_k_rhs_terms(" in kern


@pytest.mark.slow
@pytest.mark.skipif(not X86_LINUX, reason="the clones are built on x86-64 Linux only")
def test_compiled_library_dispatches_and_hides_its_kernels(monkeypatch):
    """gen.compile's library (the cffi path) with the clones, whose two
    versions it compiles as two units in parallel (GEN_RT_CLONE_UNIT): the
    rhs is the baseline library's to the bit, and neither the kernels nor
    their versions are among the library's exported functions
    (GEN_RT_INTERNAL)."""
    monkeypatch.setattr(gen.codegen.render, "CLONE_MIN_STATEMENTS", 0)
    sim = gen.compile(n_link_cart.model(2, name="cart2_clones"))
    monkeypatch.setattr(gen.codegen.render, "CLONE_MIN_STATEMENTS", 10 ** 9)
    ref = gen.compile(n_link_cart.model(2, name="cart2_noclones"))
    so = sim.build_info["module"]
    syms = subprocess.run(["nm", so], capture_output=True, text=True).stdout
    assert "cart2_clones_k_rhs_terms_avx" in syms and "cart2_clones_k_rhs_terms_base" in syms
    assert "cart2_clones_k_rhs_terms_pick" in syms
    dyn = subprocess.run(["nm", "-D", "--defined-only", so], capture_output=True,
                         text=True).stdout
    exported = {ln.split()[-1] for ln in dyn.splitlines() if ln.strip()}
    assert "cart2_clones_eval_rhs" in exported
    # (clang 14 exports the ifunc's resolver of a static function, whatever
    # the visibility: a symbol of the compiler's, not a kernel)
    kernels = [s for s in exported if s.startswith("cart2_clones_k_")
               and not s.endswith((".resolver", "_pick"))]
    assert not kernels, kernels
    rng = np.random.default_rng(3)
    X = rng.uniform(-3, 3, (40, sim.nx))
    assert np.array_equal(sim.rhs_batch(0.0, X), ref.rhs_batch(0.0, X))
    # and the numbers themselves: M u' = f from the model's M and f
    x = X[0]
    M, f = sim.mass_matrix(x[:3]), sim.forcing(x[:3], x[3:])
    np.testing.assert_allclose(sim.rhs(0.0, x)[3:], np.linalg.solve(M, f), rtol=1e-12)
