"""Issue 44 on the target: the cart-pole EKF as C (gen.EKF.to_c) - its
standalone program on the host against the filter in Python, its float
Cortex-M4F build (flash, RAM, stack, no heap: gen.EKF.footprint), its float
and double builds for ARM under qemu-arm against the host's double, and the
floating-point operations of one predict and one update counted on qemu's
execution trace.

References: ekf.filter in the host's double (the library gen.EKF loads);
the image's symbols (arm-none-eabi-nm); qemu-arm's translated blocks and
their executions (-d in_asm,exec,nochain).
"""
import re
import shutil
import subprocess
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

import cart_pole as cp
import gen
from conftest import require_tool

HERE = Path(__file__).resolve().parents[1]
EMB = HERE / "embedded"
DT = 0.01
STEPS = 1000
X0, P0 = [0.05, 0.3, 0.0, 0.0], np.diag([1e-2, 1e-2, 1e-1, 1e-1])
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wvla"]


@pytest.fixture(scope="module")
def setup():
    """The cart-pole EKF (position and angle measured) and a recording of
    the cart-pole pushed by a known force (sim.simulate, 1000 samples,
    measurement noise; one sample of the angle missing)."""
    km, s = cp.derive()
    model = cp.model()
    sim = gen.compile(model)
    ekf = gen.EKF(model, {"x_m": s["x"], "th_m": s["theta"]}, DT,
                  np.diag([1e-8, 1e-8, 1e-6, 1e-6]), [1e-4, 1e-4], X0, P0)
    t = DT * np.arange(STEPS)
    Rin = 0.5 * np.sin(0.5 * t)[:, None]
    sol = sim.simulate([0.0, 0.35, 0.0, 0.0], t[-1], DT, r=(t, Rin), input_hold="zoh")
    rng = np.random.default_rng(2)
    Z = sol.x[:, :2] + 0.01 * rng.normal(size=(STEPS, 2))
    Z[400, 1] = np.nan
    return ekf, t, Z, Rin


def _csv(path, t, Z, Rin):
    with open(path, "w") as fh:
        fh.write("F,t,x_m,th_m\n")
        for k in range(len(t)):
            z = ["" if np.isnan(v) else repr(float(v)) for v in Z[k]]
            fh.write(f"{float(Rin[k, 0])!r},{float(t[k])!r},{z[0]},{z[1]}\n")


def _read(text):
    lines = text.strip().splitlines()
    head = lines[0].split(",")
    return head, np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])


def _build(cc, src, out, name, extra, mains):
    """The library's objects once, then one executable per main file."""
    from gen.design.estimator.firmware import library_sources
    files = {p.name: None for p in src.iterdir()}
    objs = []
    procs = []
    for f in library_sources(files, name):
        o = out / (Path(f).stem + ".o")
        procs.append(subprocess.Popen([cc, *extra, *STRICT, "-I", str(src), "-c", str(src / f),
                                       "-o", str(o)], stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, text=True))
        objs.append(o)
        if len(procs) >= 2:
            _wait(procs.pop(0))
    for p in procs:
        _wait(p)
    exes = {}
    for key, (main, defs) in mains.items():
        exe = out / key
        r = subprocess.run([cc, *extra, *STRICT, *defs, "-I", str(src), *[str(m) for m in main],
                            *map(str, objs), "-lm", "-o", str(exe)], capture_output=True,
                           text=True)
        assert r.returncode == 0, r.stdout + r.stderr
        exes[key] = exe
    return exes


def _wait(p):
    log, _ = p.communicate()
    assert p.returncode == 0, " ".join(p.args) + "\n" + log


@pytest.mark.slow
def test_standalone_program_reads_a_sensor_csv(setup, tmp_path):
    """The program of to_c (host compiler, and its CMake project): the sensor
    CSV's estimates, standard deviations and statuses are ekf.filter's to
    1e-12; a NaN field is a missing measurement."""
    ekf, t, Z, Rin = setup
    ekf.reset(X0, P0, t0=0.0)
    src = tmp_path / "src"
    files = ekf.to_c(src)
    name = ekf.name
    assert {f"{name}.c", f"{name}.h", f"{name}_main.c", "CMakeLists.txt"} <= {f.name for f in files}
    text = (src / f"{name}.c").read_text()
    assert "malloc" not in text and "printf" not in text
    _csv(tmp_path / "in.csv", t, Z, Rin)
    cc = shutil.which("cc") or shutil.which("gcc")
    out = tmp_path / "obj"
    out.mkdir()
    exe = _build(cc, src, out, name, ["-O2", "-ffp-contract=off"],
                 {"prog": ([src / f"{name}_main.c", src / "gen_rt_kalman_main.c"], [])})["prog"]
    res = subprocess.run([str(exe), str(tmp_path / "in.csv")], capture_output=True, text=True,
                         check=True)
    head, data = _read(res.stdout)
    assert head == ["t", "x", "theta", "v", "omega", "sd_x", "sd_theta", "sd_v", "sd_omega",
                    "status_x_m", "status_th_m"]
    ref = ekf.filter(t, Z, Rin)
    assert np.max(np.abs(data[:, 1:5] - ref.x)) < 1e-12
    assert np.max(np.abs(data[:, 5:9] - ref.sd)) < 1e-12
    assert np.array_equal(data[:, 9:].astype(int), ref.status)
    assert data[400, 10] == 2                  # GEN_RT_KALMAN_MISSING
    # the CMake project builds the same program
    if shutil.which("cmake"):
        b = tmp_path / "build"
        for cmd in (["cmake", "-S", str(src), "-B", str(b)],
                    ["cmake", "--build", str(b), "--target", f"{name}_filter", "-j2"]):
            p = subprocess.run(cmd, capture_output=True, text=True)
            assert p.returncode == 0, p.stdout + p.stderr
        res2 = subprocess.run([str(b / f"{name}_filter"), str(tmp_path / "in.csv")],
                              capture_output=True, text=True, check=True)
        assert np.max(np.abs(_read(res2.stdout)[1][:, 1:5] - ref.x)) < 1e-10


@pytest.mark.slow
@pytest.mark.embedded
def test_float_cortex_m4f_build_footprint(setup, tmp_path):
    """The float Cortex-M4F image (arm-none-eabi-gcc -Os, hard float) of the
    filter with a static workspace: no heap and no stdio, no software
    double arithmetic; its flash, RAM and worst-case stack, reported."""
    require_tool("arm-none-eabi-gcc")
    ekf = setup[0]
    ekf.reset(X0, P0, t0=0.0)
    rep = ekf.footprint(real="float", build_dir=tmp_path)
    nm = subprocess.run(["arm-none-eabi-nm", rep["image"]], capture_output=True, text=True,
                        check=True).stdout
    syms = {ln.split()[-1] for ln in nm.splitlines() if ln.strip()}
    assert not rep["heap"]
    assert not [s for s in syms if re.match(r"^_*(malloc|free|sbrk|_?printf|fopen)$", s)]
    assert not [s for s in syms if s.startswith(("__aeabi_d", "__aeabi_f2d"))], "double in float"
    assert rep["workspace"] > 0 and rep["ram"] >= rep["workspace"]
    assert rep["flash"] < 64 * 1024 and rep["ram"] < 8 * 1024
    assert max(rep["stack"].values()) < 4096
    assert rep["stack"][f"{ekf.name}_step"] >= rep["stack"][f"{ekf.name}_predict"]
    print("\n" + rep["table"] + f"\n  C library: {', '.join(rep['libc'])}")


def _count_fp(exe, mark):
    """The instructions executed between consecutive calls of the function at
    address mark, from qemu-arm's trace: [Counter of mnemonics] per span."""
    log = Path(str(exe) + ".trace")
    subprocess.run(["qemu-arm", "-d", "in_asm,exec,nochain", "-D", str(log), str(exe)],
                   check=True, timeout=300)
    blocks, cur, order = {}, None, []
    insn = re.compile(r"^0x([0-9a-f]+):\s+(?:[0-9a-f]{4,8}\s+)+\s*([a-z][\w.]*)")
    for line in log.read_text().splitlines():
        if line.startswith("IN:"):
            cur = None
            continue
        m = insn.match(line)
        if m:
            if cur is None:
                cur = int(m.group(1), 16)
                blocks[cur] = []
            blocks[cur].append(m.group(2))
            continue
        if line.startswith("Trace"):
            cur = None
            order.append(int(line.split("[")[1].split("/")[1], 16))
    spans, count = [], None
    for pc in order:
        if pc == mark:
            if count is not None:
                spans.append(count)
            count = Counter()
        elif count is not None:
            count.update(blocks.get(pc, []))
    log.unlink()
    return spans


def _fp_ops(c):
    """Floating-point arithmetic among a Counter of mnemonics: the
    instructions by kind, and flops (a multiply-accumulate, VMLA/VMLS: the
    product rounded, then the sum, counts two)."""
    kinds = {"add": ("vadd",), "sub": ("vsub",), "mul": ("vmul", "vnmul"), "div": ("vdiv",),
             "sqrt": ("vsqrt",), "neg/abs": ("vneg", "vabs"),
             "mac": ("vmla", "vmls", "vnmla", "vnmls", "vfma", "vfms")}
    out = {k: sum(n for mn, n in c.items() if mn.startswith(ps) and ".f" in mn)
           for k, ps in kinds.items()}
    out["compare"] = sum(n for mn, n in c.items() if mn.startswith("vcmp"))
    out["flops"] = sum(out[k] for k in kinds) + out["mac"]
    out["instructions"] = sum(c.values())
    return out


@pytest.mark.slow
@pytest.mark.embedded
def test_float_agrees_with_double_under_qemu_and_operation_count(setup, tmp_path):
    """The program built for ARM (arm-linux-gnueabihf-gcc -static, hard
    float) in float and in double, run under qemu-arm on the sensor CSV:
    double equals the host's ekf.filter (to its printed digits), float
    agrees with it to 1e-4 relative over the 1000 steps. Then one predict
    and one update of the float build counted on qemu's execution trace:
    the floating-point instructions executed (the model's kernels, the
    runtime's algebra and the C library's sinf/cosf)."""
    require_tool("arm-linux-gnueabihf-gcc")
    require_tool("qemu-arm")
    ekf, t, Z, Rin = setup
    _csv(tmp_path / "in.csv", t, Z, Rin)
    name, out = ekf.name, {}
    for real in ("double", "float"):
        src = tmp_path / f"src_{real}"
        ekf.reset(X0, P0, t0=0.0)
        ekf.to_c(src, real=real)
        obj = tmp_path / f"obj_{real}"
        obj.mkdir()
        mains = {"prog": ([src / f"{name}_main.c", src / "gen_rt_kalman_main.c"], [])}
        if real == "float":
            mains["opcount"] = ([EMB / "estimator_opcount.c"],
                                [f"-DKF={name}", f'-DKF_HEADER="{name}.h"'])
        exes = _build("arm-linux-gnueabihf-gcc", src, obj, name,
                      ["-static", "-Os", "-mthumb", "-ffp-contract=off"], mains)
        res = subprocess.run(["qemu-arm", str(exes["prog"]), str(tmp_path / "in.csv")],
                             capture_output=True, text=True, timeout=300)
        assert res.returncode == 0, res.stderr
        out[real] = _read(res.stdout)[1]
        if real == "float":
            op_exe = exes["opcount"]
    ref = ekf.filter(t, Z, Rin)
    scale = np.max(np.abs(ref.x), axis=0)
    errs = {real: np.max(np.abs(out[real][:, 1:5] - ref.x) / scale) for real in out}
    sd_err = np.max(np.abs(out["float"][:, 5:9] - ref.sd) / np.max(ref.sd, axis=0))
    print(f"\nunder qemu-arm vs the host's double, max |dx| / max |x| per state over "
          f"{STEPS} steps: double {errs['double']:.1e}, float {errs['float']:.1e} "
          f"(standard deviations: {sd_err:.1e})")
    assert errs["double"] < 1e-12 and errs["float"] < 1e-4 and sd_err < 1e-3
    nm = subprocess.run(["arm-linux-gnueabihf-nm", str(op_exe)], capture_output=True,
                        text=True, check=True).stdout
    mark = next(int(ln.split()[0], 16) for ln in nm.splitlines() if ln.endswith(" kf_mark"))
    spans = _count_fp(op_exe, mark & ~1)
    # the marks: 0, predict, 1, update, 2, three times: the third pair measured
    assert len(spans) == 8
    pred, upd = _fp_ops(spans[6]), _fp_ops(spans[7])
    assert pred["flops"] > 1000 and upd["flops"] > 50 and pred["div"] >= 4
    print(f"one predict: {pred['flops']} flops ({pred}); one update: {upd['flops']} flops "
          f"({upd})")
