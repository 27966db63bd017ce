"""The embedded profile: the library subset of a generated project cross-built
for a Cortex-M4F with its own toolchain file (float and double), linked into
a tiny firmware image against newlib-nano, measured (flash, worst-case
stack), and the seed models run under qemu-arm against the host.

Cross builds use the generated CMake project with arm-none-eabi.cmake and
-Wall -Wextra -Werror -pedantic -Wdouble-promotion -Wvla -Wstack-usage=BOUND
(BOUND 4096 bytes per function frame; for cart4, 8192 in float and 12288
in double: its linearize frame alone is 5.4 KB in double, and
step_sensitivity, which keeps the stage Jacobians of the variational
equations, 4.2 KB in float and 8.4 KB in double).
"""
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import gen.toolchain.footprint as fp
from gen.codegen.render import model_sources
from conftest import require_tool
from helpers import pendulum_state

HERE = Path(__file__).resolve().parents[1]
EMB = HERE / "embedded"
CPU = ["-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"]
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wdouble-promotion", "-Wvla"]
MODELS = ["kane", "lagrange", "cart4"]
REALS = ["float", "double"]
# heap, stdio and their helpers must not be in a linked image
FORBIDDEN = re.compile(r"^_*(malloc|calloc|realloc|free|sbrk|_sbrk|_?[a-z]*printf|puts|putchar|"
                       r"fopen|fwrite|fputs|_malloc_r|_free_r|_realloc_r|_calloc_r|_sbrk_r)$")
# the C library functions the model library may call
LIBC_OK = {"sinf", "cosf", "tanf", "sqrtf", "powf", "atan2f", "expf", "logf", "fabsf",
           "sin", "cos", "tan", "sqrt", "pow", "atan2", "exp", "log", "fabs",
           "memset", "memcpy"}


def bound(key, real):
    if key == "cart4":
        return 12288 if real == "double" else 8192
    return 4096


@pytest.fixture(scope="module")
def models(kane_model, lagrange_model):
    import n_link_cart
    return {"kane": kane_model, "lagrange": lagrange_model, "cart4": n_link_cart.model(4)}


@pytest.fixture(scope="module")
def cross(models, tmp_path_factory):
    """(model key, real) -> footprint report of the Cortex-M4F build; the six
    CMake cross builds run two at a time."""
    require_tool("cmake")
    require_tool("arm-none-eabi-gcc")
    keys = [(k, r) for k in MODELS for r in REALS]
    reps = fp.report_many([(models[k], r, bound(k, r)) for k, r in keys], target="cortex-m4f",
                          root=tmp_path_factory.mktemp("cross"), workers=2)
    out = dict(zip(keys, reps))
    yield out
    print("\n" + fp.format_table(reps))


@pytest.mark.slow
@pytest.mark.embedded
@pytest.mark.parametrize("real", REALS)
@pytest.mark.parametrize("key", MODELS)
def test_cross_build_and_footprint(cross, models, key, real):
    rep = cross[key, real]
    p = models[key].name
    for flag in [*CPU, "-Os", "-Wdouble-promotion", "-Wvla", "-pedantic", "-Werror",
                 f"-Wstack-usage={bound(key, real)}", "-fstack-usage", "-fcallgraph-info=su"]:
        assert flag in rep["flags"].split(), (flag, rep["flags"])
    lib = Path(rep["library"])
    assert lib.is_file()
    assert rep["flash"]["flash"] > 1000 and rep["flash"]["data"] == 0 and rep["flash"]["bss"] == 0
    fns = rep["functions"]
    for name in ["eval_rhs", "step_rk4", "project", "linearize", "eval_mass_matrix"]:
        v = fns[f"{p}_{name}"]
        assert 0 < v["frame"] <= v["stack"] <= rep["max_stack"]
        assert v["code"] > 0
        # the C library, and the EABI's software double helpers in double
        assert {f for f in v["libc"] if not f.startswith("__aeabi_")} <= LIBC_OK, v["libc"]
    # the integrator's indirect call is resolved to the runtime's callbacks, and
    # the runtime's calls through the gen_rt_model to the kernels it can reach
    path = fns[f"{p}_step_rk4"]["path"]
    assert "rhs_cb" in path and f"{p}_lin_terms" not in path, path
    assert fns[f"{p}_linearize"]["stack"] >= fns[f"{p}_linearize"]["frame"]
    assert rep["max_stack"] < bound(key, real) + 2048
    if key == "cart4":   # sinf/sin: newlib's argument reduction keeps arrays on the stack
        trig = "sinf" if real == "float" else "sin"
        assert rep["libc_stack"][trig] > 100
        assert fns[f"{p}_eval_rhs"]["stack"] >= rep["libc_stack"][trig]
    if real == "float":
        # no double libm call, no software double arithmetic (__aeabi_dadd, ...)
        assert not any(n.startswith("__aeabi_") or n in LIBC_OK and not n.endswith("f")
                       and n not in ("memset", "memcpy") for n in rep["libc"]), rep["libc"]
    else:
        assert "__aeabi_dmul" in rep["libc"]
    assert p in rep["table"] and "worst case" in rep["table"]


def _link_firmware(rep, model, out):
    src = Path(rep["build_dir"]).parent / "src"
    elf = out / f"fw_{model.name}.elf"
    cmd = ["arm-none-eabi-gcc", *CPU, "-Os", *STRICT, "-ffunction-sections", "-fdata-sections",
           f"-DFW_MODEL={model.name}", f"-DFW_MODEL_UPPER={model.name.upper()}",
           f'-DFW_HEADER="{model.name}.h"', "-I", str(src),
           str(EMB / "fw_main.c"), str(EMB / "startup.c"), "-T", str(EMB / "cortex_m4.ld"),
           "-nostartfiles", "--specs=nano.specs", "--specs=nosys.specs", "-Wl,--gc-sections",
           f"-Wl,-Map={out / 'fw.map'}", rep["library"], "-lm", "-o", str(elf)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, " ".join(cmd) + "\n" + r.stdout + r.stderr
    return elf


@pytest.mark.slow
@pytest.mark.embedded
@pytest.mark.parametrize("real", REALS)
@pytest.mark.parametrize("key", MODELS)
def test_firmware_links_without_heap_or_stdio(cross, models, key, real, tmp_path):
    require_tool("arm-none-eabi-nm")
    rep = cross[key, real]
    elf = _link_firmware(rep, models[key], tmp_path)
    nm = subprocess.run(["arm-none-eabi-nm", str(elf)], capture_output=True, text=True,
                        check=True).stdout
    syms = {ln.split()[-1] for ln in nm.splitlines() if ln.strip()}
    undefined = [ln for ln in nm.splitlines() if ln.split()[0] == "U"]
    assert not undefined, undefined
    p = models[key].name
    for f in ["eval_rhs", "step_rk4", "linearize", "consistent_state"]:
        assert f"{p}_{f}" in syms
    bad = sorted(s for s in syms if FORBIDDEN.match(s))
    assert not bad, f"heap/stdio symbols in the firmware image: {bad}"
    doubles = sorted(s for s in syms if s.startswith(("__aeabi_d", "__aeabi_f2d", "__aeabi_i2d")))
    if real == "float":
        # no double arithmetic anywhere: the M4F's FPU is single precision
        assert not doubles, f"software double arithmetic in a float image: {doubles}"
    else:
        assert doubles   # double on the M4F is emulated: the helpers are linked
    img = fp.section_sizes(elf, "arm-none-eabi-")
    stack = fp.image_stack(elf)
    assert img["flash"] > 1000
    assert stack["Reset_Handler"]["stack"] >= stack["main"]["stack"] > 0
    libm = {f: stack[f]["stack"] for f in ("sinf", "cosf", "sqrtf", "sin", "cos", "sqrt")
            if f in stack}
    print(f"{p} [{real}] firmware: flash {img['flash']} B (.text {img['text']}, .rodata "
          f"{img['rodata']}), .data {img['data']} B, .bss {img['bss']} B; stack of main "
          f"(disassembly estimate, without the integrator's indirect call) "
          f"{stack['main']['stack']} B; C library: {libm}")


# ---------------------------------------------------------------------------
# qemu-arm: the seed models' driver, float and double, against the host
# ---------------------------------------------------------------------------

def _norm_rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300))


def _build_drivers(model, out):
    """The driver for float and double, compiled at the same time."""
    import gen
    procs = {}
    for real in REALS:
        src = out / f"src_{real}"
        gen.generate(model, src, real=real)
        exe = out / f"driver_{model.name}_{real}"
        sources = [str(src / f) for f in model_sources(model.name)] + sorted(
            str(s) for s in src.glob("gen_rt_*.c"))
        cmd = ["arm-linux-gnueabihf-gcc", "-static", "-O2", *STRICT,
               f"-DFW_MODEL={model.name}", f"-DFW_MODEL_UPPER={model.name.upper()}",
               f'-DFW_HEADER="{model.name}.h"', "-I", str(src), str(EMB / "driver.c"),
               *sources, "-lm", "-o", str(exe)]
        procs[real] = (exe, cmd, subprocess.Popen(cmd, stdout=subprocess.PIPE,
                                                  stderr=subprocess.STDOUT, text=True))
    exes = {}
    for real, (exe, cmd, proc) in procs.items():
        log, _ = proc.communicate()
        assert proc.returncode == 0, " ".join(cmd) + "\n" + log
        exes[real] = exe
    return exes


def _run_driver(exe, x):
    r = subprocess.run(["qemu-arm", str(exe), *[f"{v:.9g}" for v in x]], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    out = {"sim": []}
    for line in r.stdout.splitlines():
        tag, *vals = line.split()
        nums = [float(v) for v in vals]
        if tag == "sim":
            out["sim"].append(nums[1:])
        else:
            out[tag] = np.array(nums)
    out["sim"] = np.array(out["sim"])
    return out


@pytest.mark.slow
@pytest.mark.embedded
@pytest.mark.parametrize("key", ["kane", "lagrange"])
def test_qemu_arm_matches_host(models, kane_sim, lagrange_sim, key, tmp_path):
    require_tool("arm-linux-gnueabihf-gcc")
    require_tool("qemu-arm")
    model = models[key]
    sim = {"kane": kane_sim, "lagrange": lagrange_sim}[key]
    exes = _build_drivers(model, tmp_path)
    worst = {r: [0.0, 0.0, 0.0] for r in REALS}
    # fixed states (amplitude, rate), moving and at rest, away from the Kane
    # model's singular partition at q1 = 0
    for theta, thetadot in [(0.5, 0.0), (-0.3, 1.2), (0.9, -0.7)]:
        x = pendulum_state(theta, thetadot, 1.0, key).astype(np.float32).astype(float)
        ref_rhs = sim.rhs(0.0, x)
        ref_A, _ = sim.linearize(x)
        _, ref_X = sim.simulate(x, 10.0, 0.01, method="rk4")
        ref_X = ref_X[::100]
        for r in REALS:
            o = _run_driver(exes[r], x)
            e = worst[r]
            e[0] = max(e[0], _norm_rel(o["rhs"], ref_rhs))
            e[1] = max(e[1], _norm_rel(o["A"], ref_A.ravel()))
            assert o["sim"].shape == ref_X.shape
            e[2] = max(e[2], float(np.max(np.abs(o["sim"] - ref_X)) / np.max(np.abs(ref_X))))
    print(f"{key}: qemu-arm vs host double, norm-relative rhs, A; trajectory max-abs / max|x|: "
          + "; ".join(f"{r}: {e[0]:.2e}, {e[1]:.2e}, {e[2]:.2e}" for r, e in worst.items()))
    f, d = worst["float"], worst["double"]
    assert f[0] < 1e-5 and f[1] < 1e-5 and f[2] < 1e-4, f
    # %.9g printing limits the double comparison to ~1e-9
    assert d[0] < 1e-8 and d[1] < 1e-8 and d[2] < 1e-8, d


# ---------------------------------------------------------------------------
# the stack analysis itself, on synthetic call graphs
# ---------------------------------------------------------------------------

def test_analyze_deepest_path_and_indirect_calls():
    frames = {"a": (16, "static"), "f.c:b": (100, "static"), "c": (40, "static"),
              "f.c:m_rhs_cb": (8, "static"), "d": (200, "dynamic,bounded")}
    edges = {"a": {"f.c:b", "c", "sinf"}, "f.c:b": {"c"}, "c": {"__indirect_call"},
             "f.c:m_rhs_cb": {"d"}}
    out = fp.analyze(frames, edges, ["a", "c"], indirect_targets=["m_rhs_cb"])
    assert out["a"]["stack"] == 16 + 100 + 40 + 8 + 200
    assert out["a"]["path"] == ["a", "b", "c", "m_rhs_cb", "d"]
    assert out["a"]["libc"] == ["sinf"]
    assert out["c"]["stack"] == 248
    # a C library callee's stack (estimated from the target's libm) counts
    out = fp.analyze(frames, edges, ["a"], ["m_rhs_cb"], external={"sinf": 1000})
    assert out["a"]["stack"] == 1016 and out["a"]["path"] == ["a", "sinf (libc)"]


def test_analyze_refuses_recursion_and_dynamic_frames():
    frames = {"a": (8, "static"), "b": (8, "static")}
    with pytest.raises(fp.FootprintError, match="recursion.*a -> b -> a"):
        fp.analyze(frames, {"a": {"b"}, "b": {"a"}}, ["a"])
    with pytest.raises(fp.FootprintError, match="dynamic stack frame.*: b"):
        fp.analyze({"a": (8, "static"), "b": (8, "dynamic")}, {"a": {"b"}}, ["a"])
    with pytest.raises(fp.FootprintError, match="indirect call"):
        fp.analyze(frames, {"a": {"__indirect_call"}}, ["a"])


@pytest.mark.slow
@pytest.mark.embedded
def test_report_cli_writes_footprint(tmp_path, monkeypatch):
    require_tool("cmake")
    require_tool("arm-none-eabi-gcc")
    from gen.cli import main
    root = HERE.parent
    out = tmp_path / "footprint.txt"
    rc = main(["report", str(root / "examples" / "seed_pendulum.py:lagrange_model"),
               "--real", "float", "--build-dir", str(tmp_path / "b"), "-o", str(out),
               "--json", str(tmp_path / "fp.json"), "--stack-limit", "4096"])
    assert rc == 0
    text = out.read_text()
    assert "pendulum_lagrange [float, cortex-m4f]" in text
    assert "pendulum_lagrange_linearize" in text and "-Wstack-usage=4096" in text
    import json
    (rep,) = json.loads((tmp_path / "fp.json").read_text())
    assert rep["functions"]["pendulum_lagrange_step_rk4"]["stack"] > 0
