"""Twin statements in two-lane vectors (gen/codegen/lanes.py, GEN_RT_LANES
in csrc/runtime/gen_rt.h): each lane computes what its scalar statement
computes, bit for bit. The reference is the scalar code itself, compiled
from the same file with -DGEN_RT_NO_LANES, at inputs chosen to hit every
sign case (exact cancellations that give +0 or -0, negative operands):
printf's %a shows every bit, the sign of zero included.

Also here: the model side (gen.intake.aba.twin_speeds: sibling limbs with
the same joints), and a tree with two mirrored legs through gen.generate,
whose right-hand side must be the same bits with and without the lanes
and must hold vector statements."""
import platform
import re
import subprocess

import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me

import gen
from gen.codegen.backends import C_FLAGS, STRICT_FLAGS, c_compiler
from gen.codegen.lanes import MIN_PAIRS, VECTOR, lanes_body
from gen.core.resources import csrc_file
from conftest import require_tool

LANES_HOST = platform.machine() in ("x86_64", "AMD64", "aarch64", "arm64")

# statement pairs (lane 0, lane 1) over inputs x[0..7]: the same arithmetic
# with the signs, constants, operand orders and subtractions a mirrored limb
# gives (each line: name, lane-0 expression, lane-1 expression)
TWINS = [
    ("s", "sin(x[0])", "sin(x[1])"),
    ("c", "cos(x[0])", "cos(x[1])"),
    ("a", "0.085*x[2] + x[3]", "x[4] - 0.085*x[5]"),
    ("b", "-a*s + c", "c + s*a"),
    ("d", "a - b", "b - a"),
    ("e", "-d*x[6]", "d*x[7]"),
    ("f", "(a*b + c*d) - e*0.5", "-0.5*e + (b*a + d*c)"),
    ("g", "1.0/(f*f + 1.0)", "1.0/(f*f + 1.0)"),
    ("h", "-(a + b)*g - 2*x[2]", "-2*x[4] + g*(-a - b)"),
    ("k", "h/3.0 - f*f*f", "h/3.0 - f*f*f"),
    ("m", "-k", "-k"),
    ("n", "m - 1.5e-12*s*c", "-1.5e-12*c*s + m"),
    ("o", "x[2] - x[3]", "x[4] - x[5]"),
    ("r", "-o*a + o*a", "o*a - a*o"),
    ("z", "r - o", "-o - r"),
]

DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include "gen_rt.h"
static void kernel(const double *x, double *out_y)
{{
#if GEN_RT_LANES
{lanes}
#else
{scalar}
#endif
}}
int main(void)
{{
    static const double X[][8] = {{ {inputs} }};
    double out[{nout}];
    size_t k;
    int i;
    printf("lanes %d\n", GEN_RT_LANES);
    for (k = 0; k < sizeof X / sizeof X[0]; ++k) {{
        kernel(X[k], out);
        for (i = 0; i < {nout}; ++i) printf(" %a", out[i]);
        printf("\n");
    }}
    return 0;
}}
"""


def _body():
    """The scalar lines (lane 0's statements on names ending in 0, then
    lane 1's ending in 1), the stores, and the seeds (the last statements)."""
    out = []
    for lane in (0, 1):
        for n, e0, e1 in TWINS:
            e = re.sub(r"\b([a-wyz])\b", lambda m: f"{m.group(1)}{lane}", e1 if lane else e0)
            out.append(f"    const double {n}{lane} = {e};")
    stores = [f"    out_y[{2 * i + lane}] = {n}{lane};" for i, (n, _, _) in enumerate(TWINS)
              for lane in (0, 1)]
    return out + stores, [(f"{n}0", f"{n}1") for n, _, _ in TWINS[-4:]]


def _inputs():
    rng = np.random.default_rng(3)
    rows = [rng.uniform(-2, 2, 8) for _ in range(6)]
    # exact cancellations: x[2] = x[3] and x[4] = x[5] make o = 0 (+0 or
    # -0 by the operation), equal lanes, zeros of both signs
    rows.append(np.array([0.5, 0.5, 1.25, 1.25, 1.25, 1.25, 0.0, -0.0]))
    rows.append(np.array([-0.0, 0.0, -1.0, -1.0, 2.0, 2.0, -3.0, 3.0]))
    rows.append(np.array([1.0, -1.0, 0.0, -0.0, -0.0, 0.0, 1e-300, -1e-300]))
    return ", ".join("{" + ", ".join(float(v).hex() for v in r) + "}" for r in rows)


def _compile_run(tmp_path, src, flags, name):
    c = tmp_path / f"{name}.c"
    c.write_text(src)
    exe = tmp_path / name
    rt = csrc_file("gen_rt.h").parent
    cmd = [c_compiler(), *C_FLAGS, *STRICT_FLAGS, *flags, "-I", str(tmp_path), "-I", str(rt),
           str(c), "-o", str(exe), "-lm"]
    (tmp_path / "gen_rt_config.h").write_text("#define GEN_RT_CONFIG_H\n")
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0 and not proc.stderr.strip(), " ".join(cmd) + "\n" + proc.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    return run.stdout.splitlines()


@pytest.mark.skipif(not LANES_HOST, reason="two lanes are built on x86-64 and AArch64 only")
def test_every_lane_is_its_scalar_statement_bit_for_bit(tmp_path, monkeypatch):
    monkeypatch.setattr(gen.codegen.lanes, "MIN_PAIRS", 1)
    lines, seeds = _body()
    lanes = gen.codegen.lanes.lanes_body(lines, seeds)
    assert lanes is not None
    vec = [ln for ln in lanes if f"const {VECTOR} " in ln]
    # every arithmetic pair is one vector statement; sin and cos are packed
    assert len(vec) == len(TWINS), "\n".join(lanes)
    src = DRIVER.format(lanes="\n".join(lanes), scalar="\n".join(lines), inputs=_inputs(),
                        nout=2 * len(TWINS))
    with_lanes = _compile_run(tmp_path, src, [], "with_lanes")
    scalar = _compile_run(tmp_path, src, ["-DGEN_RT_NO_LANES"], "scalar")
    assert with_lanes[0] == "lanes 1" and scalar[0] == "lanes 0"
    assert with_lanes[1:] == scalar[1:]
    # the inputs reach both signs of zero (the check above covers them)
    assert any(" -0x0p+0" in row for row in scalar[1:]) and any(" 0x0p+0" in row
                                                               for row in scalar[1:])


def test_no_lanes_for_other_lines_or_too_few_pairs():
    lines, seeds = _body()
    assert lanes_body(lines + ["    if (x[0] > 0) return;"], seeds) is None
    # one pair is below MIN_PAIRS
    assert MIN_PAIRS > 1
    assert lanes_body(["    const double a0 = 2.0*x[0];", "    const double a1 = 2.0*x[1];"],
                      [("a0", "a1")]) is None
    # an integer division stays scalar (C's 1/2 is 0)
    body = [f"    const double a{i} = 1/2*x[{i}];" for i in range(2 * MIN_PAIRS)]
    assert lanes_body(body, [(f"a{2 * i}", f"a{2 * i + 1}") for i in range(MIN_PAIRS)]) is None


# ---------------------------------------------------------------- the model
def _two_legs(third=False):
    """A trunk on a pin joint with two legs of two pin joints each, the legs'
    hips mirrored in y (different constants, the same joints); third: a
    third leg of one joint (no twin)."""
    ground = me.RigidBody("G")
    N = ground.frame
    system = me.System.from_newtonian(ground)
    bodies = {}

    def body(name, m, I):
        B = me.ReferenceFrame(f"F_{name}")
        mc = me.Point(f"mc_{name}")
        return me.RigidBody(name, masscenter=mc, frame=B, mass=m,
                            inertia=(me.inertia(B, *I), mc))

    def pin(name, parent, child, axis, at):
        q, u = me.dynamicsymbols(f"q_{name} u_{name}")
        P = parent.frame
        ppt = parent.masscenter.locatenew(f"p_{name}", at[0] * P.x + at[1] * P.y + at[2] * P.z)
        cpt = child.masscenter.locatenew(f"c_{name}", -0.1 * child.frame.z)
        j = me.PinJoint(name, parent, child, coordinates=q, speeds=u,
                        parent_point=ppt, child_point=cpt,
                        joint_axis=getattr(P, axis))
        system.add_joints(j)
        system.add_actuators(me.TorqueActuator(me.dynamicsymbols(f"T_{name}"),
                                               getattr(P, axis), child, parent))
        return j

    trunk = body("trunk", 5.0, (0.3, 0.2, 0.4, 0.01, 0.0, 0.02))
    pin("yaw", ground, trunk, "z", (0, 0, 1))
    for side, y in (("l", 0.15), ("r", -0.15)):
        thigh = body(f"thigh_{side}", 2.0, (0.05, 0.04, 0.01, 0.001 * (1 if y > 0 else -1), 0, 0))
        shin = body(f"shin_{side}", 1.0, (0.03, 0.02, 0.005, 0, 0.002, 0))
        pin(f"hip_{side}", trunk, thigh, "x", (0.02, y, -0.1))
        pin(f"knee_{side}", thigh, shin, "y", (0.0, 0.01 if y > 0 else -0.01, -0.4))
    if third:
        tail = body("tail", 0.5, (0.01, 0.01, 0.01, 0, 0, 0))
        pin("tail", trunk, tail, "y", (-0.3, 0, 0))
    system.apply_uniform_gravity(-9.81 * N.z)
    return system, sorted((a.torque for a in system.actuators), key=str)


def test_twin_speeds_pair_the_mirrored_legs():
    system, inputs = _two_legs(third=True)
    m = gen.Model.from_system(system, inputs=inputs, formulation="recursive", name="legs")
    names = [str(s) for s in m.u_orig]
    pairs = {(names[i], names[j]) for i, j in m.twins}
    assert pairs == {("u_hip_l(t)", "u_hip_r(t)"), ("u_knee_l(t)", "u_knee_r(t)")}
    # CRBA's equations (M and f, then the solve) do not use the hint
    system, inputs = _two_legs()
    assert gen.Model.from_system(system, inputs=inputs, formulation="crba",
                                 name="k").twins == []


DRV = r"""
#include <stdio.h>
#include "gen_rt.h"
#include "legs.h"
int main(void)
{{
    static const double X[][{nx}] = {{ {states} }};
    static const double R[{nr}] = {{ 0 }};
    double dx[{nx}];
    size_t k;
    int i;
    printf("lanes %d\n", GEN_RT_LANES);
    for (k = 0; k < sizeof X / sizeof X[0]; ++k) {{
        int st = legs_eval_rhs(0.0, X[k], R, NULL, dx, NULL);
        printf("%d", st);
        for (i = 0; i < {nx}; ++i) printf(" %a", dx[i]);
        printf("\n");
    }}
    return 0;
}}
"""


def _legs_sources(tmp_path):
    """The two-legged model's sources with a driver printing u' (%a) at
    six states; (model, states, source files)."""
    system, inputs = _two_legs()
    model = gen.Model.from_system(system, inputs=inputs, formulation="recursive", name="legs")
    out = tmp_path / "src"
    gen.generate(model, out)
    kern = (out / "legs_kernels.c").read_text()
    assert kern.count(f"const {VECTOR} ") >= MIN_PAIRS
    rng = np.random.default_rng(11)
    states = [rng.uniform(-1.5, 1.5, model.nx) for _ in range(5)] + [np.zeros(model.nx)]
    rows = ", ".join("{" + ", ".join(float(v).hex() for v in x) + "}" for x in states)
    (out / "drv.c").write_text(DRV.format(nx=model.nx, nr=max(1, model.nr), states=rows))
    from gen.codegen.render import model_sources
    srcs = [str(out / "drv.c")] + [str(out / f) for f in model_sources("legs")]
    return model, states, out, srcs


def _legs_runs(tmp_path, cc, run=(), extra=()):
    """The driver's output (its lines of u') built with and without the
    lanes (the runtime, which has none, compiled once); each build must
    have taken its branch."""
    model, states, out, srcs = _legs_sources(tmp_path)
    flags = [*C_FLAGS, *STRICT_FLAGS, *extra, "-I", str(out)]
    rt = tmp_path / "runtime.o"
    proc = subprocess.run([cc, *flags, "-r", "-nostdlib", *sorted(
        str(f) for f in out.glob("gen_rt_*.c")), "-o", str(rt)], capture_output=True, text=True)
    assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr
    runs = []
    for lanes in ([], ["-DGEN_RT_NO_LANES"]):
        exe = tmp_path / f"drv{len(runs)}"
        cmd = [cc, *flags, *lanes, *srcs, str(rt), "-o", str(exe), "-lm"]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr
        lines = subprocess.run([*run, str(exe)], capture_output=True, text=True,
                               timeout=120).stdout.splitlines()
        assert lines[0] == f"lanes {0 if lanes else 1}", lines[:1]
        runs.append("\n".join(lines[1:]) + "\n")
    return model, states, runs


@pytest.mark.skipif(not LANES_HOST, reason="two lanes are built on x86-64 and AArch64 only")
def test_mirrored_legs_same_bits_with_and_without_lanes(tmp_path):
    model, states, runs = _legs_runs(tmp_path, c_compiler())
    assert runs[0] == runs[1] and runs[0].count("\n") == len(states)
    # and they are the physics: sympy's own form_eoms on the same System,
    # built again, lambdified and solved with numpy (zero torques)
    ref, torques = _two_legs()
    ref.form_eoms()
    xs = list(ref.q) + list(ref.u)
    zero = {s: 0 for s in torques}
    Mf = sm.lambdify(xs, ref.mass_matrix_full.xreplace(zero), "numpy")
    Ff = sm.lambdify(xs, ref.forcing_full.xreplace(zero), "numpy")
    order = [xs.index(s) for s in list(model.q_orig) + list(model.u_orig)]
    for x, row in zip(states, runs[0].splitlines()):
        got = np.array([float.fromhex(v) for v in row.split()[1:]])
        xr = np.empty(len(xs))
        xr[order] = x
        want = np.linalg.solve(Mf(*xr), Ff(*xr)).ravel()[order]
        assert np.max(np.abs(got - want)) < 1e-12 * (1 + np.max(np.abs(want)))


@pytest.mark.slow
@pytest.mark.skipif(not LANES_HOST, reason="compared with this host's lanes")
def test_aarch64_lanes_are_the_hosts_bits(tmp_path):
    """AArch64 (NEON's two-lane doubles), cross-built and run under
    qemu-aarch64: the same bits with and without the lanes there, and this
    host's numbers (to the last bits: the two libms' sin and cos may round
    apart)."""
    cc = require_tool("aarch64-linux-gnu-gcc")
    qemu = require_tool("qemu-aarch64")
    _, _, host = _legs_runs(tmp_path / "host", c_compiler())
    _, _, a64 = _legs_runs(tmp_path / "a64", cc, run=[qemu], extra=["-static"])
    assert a64[0] == a64[1] and a64[0].count("\n") == 6
    for ra, rh in zip(a64[0].splitlines(), host[0].splitlines()):
        a = np.array([float.fromhex(v) for v in ra.split()[1:]])
        h = np.array([float.fromhex(v) for v in rh.split()[1:]])
        assert ra.split()[0] == rh.split()[0] == "0"
        assert np.max(np.abs(a - h)) <= 1e-14 * (1 + np.max(np.abs(h)))
