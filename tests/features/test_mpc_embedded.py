"""gen.MPC on the target (issue 43): the cart-pole MPC (N = 20) written by
mpc.to_c with the model's generated sources, (a) cross-built for ARM Linux
and run under qemu-arm in float and double over a closed loop, the float
controls against the double ones, and the double ones against the host's
gen.MPC; (b) linked into a Cortex-M4F firmware image (newlib-nano, no
heap, no stdio), the controller's module with no mutable global, its
flash, RAM and stack reported."""
import subprocess
from pathlib import Path

import numpy as np
import pytest

import cart_pole as cp
import gen
import gen.toolchain.footprint as fp
from conftest import require_tool

EMB = Path(__file__).resolve().parents[1] / "embedded"
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wvla", "-Wshadow"]
CPU = ["-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"]
Q = np.diag([10.0, 10.0, 0.1, 0.1])
X0 = [0.0, 0.3, 0.0, 0.0]
STEPS = 100
DEFS = ["-DFW_MODEL=cart_pole", "-DFW_MODEL_UPPER=CART_POLE", '-DFW_HEADER="cart_pole.h"',
        "-DMPC=cp_mpc", "-DMPC_UPPER=CP_MPC", '-DMPC_HEADER="cp_mpc.h"']


@pytest.fixture(scope="module")
def mpc():
    return gen.MPC(cp.model(), 20, 0.05, Q, [0.05], P=5 * Q, bounds={"F": (-20.0, 20.0)})


def _sources(mpc, out, real):
    from gen.codegen.render import model_sources
    src = out / f"src_{real}"
    gen.generate(mpc.model, src, real=real)
    mpc.to_c(src, name="cp_mpc", real=real)
    files = [src / f for f in model_sources(mpc.model.name)]
    files += sorted(s for s in src.glob("gen_rt_*.c") if s.name != "gen_rt_main.c")
    return src, [*files, src / "cp_mpc.c"]


def _run(exe):
    r = subprocess.run(["qemu-arm", str(exe), str(STEPS), *map(repr, X0)], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    rows = {"u": [], "x": [], "st": []}
    for line in r.stdout.splitlines():
        tag, k, st, *vals = line.split()
        rows[tag].append([float(v) for v in vals])
        if tag == "u":
            rows["st"].append(int(st))
    return np.array(rows["u"]), np.array(rows["x"]), rows["st"]


@pytest.mark.slow
@pytest.mark.embedded
def test_float_controls_agree_with_double_under_qemu(mpc, tmp_path):
    cc = require_tool("arm-linux-gnueabihf-gcc")
    require_tool("qemu-arm")
    res = {}
    for real in ("double", "float"):
        src, files = _sources(mpc, tmp_path, real)
        exe = tmp_path / f"mpc_{real}"
        cmd = [cc, "-static", "-O2", *STRICT, *DEFS, "-I", str(src),
               str(EMB / "mpc_driver.c"), *map(str, files), "-lm", "-o", str(exe)]
        r = subprocess.run(cmd, capture_output=True, text=True)
        assert r.returncode == 0, " ".join(cmd) + "\n" + r.stdout + r.stderr
        res[real] = _run(exe)
    (ud, xd, std), (uf, xf, stf) = res["double"], res["float"]
    assert set(std) == {0} and all(s >= 0 for s in stf), (std, stf)
    scale = np.max(np.abs(ud))
    assert scale == pytest.approx(20.0)                   # the bound, active
    d_float = np.max(np.abs(uf - ud)) / scale
    # the double build under qemu against the host's gen.MPC on the same states
    mpc.reset()
    uh = np.array([mpc(x, t=k * 0.05) for k, x in enumerate(xd[:-1])])
    d_host = np.max(np.abs(uh - ud)) / scale
    print(f"\ncart-pole MPC (N = 20) under qemu-arm, {STEPS} steps: max |u_float - u_double| "
          f"/ max |u| = {d_float:.1e}; double vs the host: {d_host:.1e}")
    assert d_host < 1e-7
    assert d_float < 1e-4
    assert np.max(np.abs(xf[-1])) < 1e-2                   # upright in float too


@pytest.mark.slow
@pytest.mark.embedded
def test_cortex_m4f_firmware_footprint(mpc, tmp_path):
    """The float controller and its model linked for the Cortex-M4F: every
    reference resolved, no heap or stdio symbol, the MPC's own objects with
    nothing in .data or .bss; flash, RAM (the static memory) and stack."""
    require_tool("arm-none-eabi-gcc")
    require_tool("arm-none-eabi-nm")
    src, files = _sources(mpc, tmp_path, "float")
    for f in ("cp_mpc.c", "gen_rt_mpc.c", "gen_rt_qp.c"):
        obj = tmp_path / f"{f}.o"
        subprocess.run(["arm-none-eabi-gcc", *CPU, "-Os", *STRICT, "-c", "-I", str(src),
                        str(src / f), "-o", str(obj)], check=True)
        sec = fp.section_sizes(obj, "arm-none-eabi-")
        assert sec["data"] == 0 and sec["bss"] == 0, (f, sec)
    elf = tmp_path / "fw_mpc.elf"
    cmd = ["arm-none-eabi-gcc", *CPU, "-Os", *STRICT, "-ffunction-sections", "-fdata-sections",
           *DEFS, "-I", str(src), str(EMB / "mpc_fw.c"), str(EMB / "startup.c"),
           *map(str, files), "-T", str(EMB / "cortex_m4.ld"), "-nostartfiles",
           "--specs=nano.specs", "--specs=nosys.specs", "-Wl,--gc-sections", "-lm", "-o",
           str(elf)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, " ".join(cmd) + "\n" + r.stdout + r.stderr
    nm = subprocess.run(["arm-none-eabi-nm", str(elf)], capture_output=True, text=True,
                        check=True).stdout
    syms = {ln.split()[-1] for ln in nm.splitlines() if ln.strip()}
    assert not [ln for ln in nm.splitlines() if ln.split()[0] == "U"]
    assert {"cp_mpc_step", "cp_mpc_init", "gen_rt_qp_solve"} <= syms
    bad = sorted(s for s in syms if s in {"malloc", "free", "calloc", "realloc", "_malloc_r",
                                          "printf", "fprintf", "puts", "fwrite", "_sbrk"})
    assert not bad, bad
    img = fp.section_sizes(elf, "arm-none-eabi-")
    stack = fp.image_stack(elf)
    ram = img["data"] + img["bss"]
    mem_bytes = mpc._fn["memory_size"]() // 2      # the host's double memory, in float
    assert ram >= mem_bytes * 0.9
    print(f"\ncart-pole MPC (N = 20), float, Cortex-M4F image: flash {img['flash']} B "
          f"(.text {img['text']}, .rodata {img['rodata']}), RAM {ram} B (.data {img['data']}, "
          f".bss {img['bss']}: the controller's static memory), stack of main "
          f"{stack['main']['stack']} B (disassembly estimate, indirect calls aside)")


@pytest.mark.slow
def test_standalone_binary_closed_by_the_mpc(mpc, tmp_path):
    """The model's generated project built with -DCART_POLE_TRACKER=cp_mpc_loop:
    its simulator is closed by the controller of mpc.to_c, the same run as
    sim.simulate(..., controller=mpc)."""
    require_tool("cmake")
    src, _ = _sources(mpc, tmp_path, "double")
    b = tmp_path / "build"
    for cmd in (["cmake", "-S", str(src), "-B", str(b), "-DCART_POLE_TRACKER=cp_mpc_loop"],
                ["cmake", "--build", str(b), "--target", "cart_pole_sim"]):
        p = subprocess.run(cmd, capture_output=True, text=True)
        assert p.returncode == 0, p.stdout + p.stderr
    out = subprocess.run([str(b / "cart_pole_sim"), "--t-end", "3", "--dt", "5e-3",
                          "--x0", "theta=0.3"], capture_output=True, text=True,
                         check=True).stdout.strip().splitlines()
    head = out[0].split(",")
    data = np.array([[float(v) for v in ln.split(",")] for ln in out[1:]])
    sim = gen.compile(mpc.model, derivatives=True)
    sol = sim.simulate(X0, 3.0, 5e-3, controller=mpc)
    assert data.shape[0] == len(sol.t)
    assert np.max(np.abs(data[:, 1:5] - sol.x)) < 1e-10
    assert np.max(np.abs(data[:, head.index("F")] - sol.r[:, 0])) < 1e-9
    assert np.max(np.abs(sol.r)) == pytest.approx(20.0)
