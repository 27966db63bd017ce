"""A Kalman filter as C for a firmware and as a standalone program
(gen.EKF.to_c), and its footprint on a microcontroller (gen.EKF.footprint).

    ekf.to_c("out/cp_kf", real="float")   # the model, the runtime, the filter, a program
    rep = ekf.footprint()                  # Cortex-M4F, float: flash, RAM, stack
    print(rep["table"])

The files: the filter model's C (<name>_model*.c, its kernels and
derivative kernels), the runtime (gen_rt_*.c), the filters
(gen_rt_kalman.c), <name>.c and <name>.h (the measurement kernels, the
workspace struct, <name>_defaults: the filter's values now, as const
tables), <name>_main.c with gen_rt_kalman_main.c (the program: a sensor CSV
in, the estimates out) and a CMakeLists.txt (<name>_lib, <name>_filter).
No heap and no global written in the library: the workspace is the
caller's (static in a firmware).
"""
from __future__ import annotations

import subprocess
import tempfile
from pathlib import Path

from ...codegen.render import render, write_atomic
from ...codegen.templating import fmt_real, template_env
from ...core.errors import BuildError, InputError
from ...core.resources import csrc_file
from ...toolchain.stack import (analyze, display_name, find_tool, image_stack, parse_callgraph,
                                parse_su, section_sizes)
from ..._version import __version__

__all__ = ["sources", "to_c", "footprint", "CORTEX_M4F"]

#: the Cortex-M4F's flags (hard float, single precision)
CORTEX_M4F = ["-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"]
_STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wvla"]
_PROGRAM = ("gen_rt_kalman_main.c", "gen_rt_kalman_main.h")


def _defaults(kf, real):
    ws = kf._ws
    f = lambda v: fmt_real(v, real)  # noqa: E731
    return {"kind": "GEN_RT_KALMAN_" + kf.kind, "substeps": kf.substeps, "period": f(kf.period),
            "gate": f(0.0 if kf.gate is None else kf.gate),
            "alpha": f(ws.scalars["alpha"][0]), "beta": f(ws.scalars["beta"][0]),
            "kappa": f(ws.scalars["kappa"][0]), "t": f(kf.t),
            "x": [f(v) for v in ws.x], "P": [f(v) for v in ws.P], "Q": [f(v) for v in ws.Q],
            "R": [f(v) for v in ws.R], "p": [f(v) for v in ws.p] or [f(0.0)]}


def sources(kf, real="double"):
    """The files of :func:`to_c`, as text: {file name: text}."""
    if real not in ("double", "float"):
        raise InputError(f"real must be 'double' or 'float', got {real!r}", "real", None, real)
    fm = kf._fm
    plan = fm.product_plan(real, data={"defaults": _defaults(kf, real)})
    files = render(plan, real=real, backend="estimator").files
    name = kf.name
    ctx = {**plan.data, "name": name, "version": __version__, "input_names": kf.model.input_names,
           "sz": {"nr": max(1, kf.nr)}}
    env = template_env()
    lib = sorted(f for f in files if f.endswith(".c"))
    files[f"{name}_main.c"] = env.get_template("estimator/main.c.j2").render(**ctx)
    files["CMakeLists.txt"] = env.get_template("estimator/CMakeLists.txt.j2").render(
        **ctx, lib_sources=lib)
    for f in _PROGRAM:
        files[f] = csrc_file(f).read_text()
    return files


def to_c(kf, path, real="double"):
    """Write the filter's C (see the module): a firmware module and a
    standalone program, with the filter's values now (its estimate,
    covariance, time, noise and settings) as <name>_defaults.

    Parameters
    ----------
    path : str or Path
        A folder; created (written atomically).
    real : {"double", "float"}, optional
        The scalar type.

    Returns
    -------
    list of Path
    """
    return write_atomic(sources(kf, real), Path(path))


def library_sources(files, name):
    """The C files of the filter's library (the program's left out)."""
    return sorted(f for f in files if f.endswith(".c") and f not in (
        f"{name}_main.c", f"{name}_probe.c", _PROGRAM[0]))


def _run(cmd, what, cwd=None):
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, cwd=cwd)
    if r.returncode != 0:
        raise BuildError(f"{what} failed", "$ " + " ".join(map(str, cmd)) + "\n" + r.stdout
                         + r.stderr)
    return r


def footprint(kf, real="float", target="cortex-m4f", build_dir=None):
    """Cross-build the filter for a Cortex-M4F (arm-none-eabi-gcc, -Os,
    hard float) and measure it: the library's objects with their stack
    usage and call graph, and a firmware image that links them against
    newlib-nano with a static workspace, runs init, defaults, start and
    step, and keeps only what those reach (--gc-sections).

    Returns
    -------
    dict
        ``flash`` (the image's .text + .rodata + .data, bytes), ``ram``
        (.data + .bss: the workspace and the C library's), ``workspace``
        (sizeof the workspace), ``stack`` ({function: worst-case bytes} of
        <name>_init, _start, _predict, _update, _step, with the C library's
        estimated from its disassembly), ``heap`` (heap or stdio symbols
        in the image: none), ``libc`` (the C library functions called),
        ``table`` (text).
    """
    if target != "cortex-m4f":
        raise InputError(f"target must be 'cortex-m4f', got {target!r}", "target", None, target)
    gcc = find_tool("arm-none-eabi-", "gcc")
    root = Path(build_dir) if build_dir else Path(tempfile.mkdtemp(prefix="eomgen-kf-"))
    src, obj = root / "src", root / "obj"
    files = sources(kf, real)
    name = kf.name
    files[f"{name}_probe.c"] = template_env().get_template("estimator/probe.c.j2").render(
        name=name, nz=kf.nz, nr=kf.nr, version=__version__)
    write_atomic(files, src)
    obj.mkdir(parents=True, exist_ok=True)
    flags = [*CORTEX_M4F, "-Os", *_STRICT, "-ffunction-sections", "-fdata-sections",
             "-ffp-contract=off", "-fno-math-errno", "-fstack-usage", "-fcallgraph-info=su"]
    objs = []
    for f in library_sources(files, name) + [f"{name}_probe.c"]:
        o = obj / (Path(f).stem + ".o")
        _run([gcc, *flags, "-I", src, "-c", src / f, "-o", o], f"compiling {f}", cwd=obj)
        objs.append(o)
    elf = root / f"{name}_probe.elf"
    _run([gcc, *CORTEX_M4F, "-nostartfiles", "--specs=nano.specs", "--specs=nosys.specs",
          "-Wl,--gc-sections", "-Wl,-e,main", *objs, "-lm", "-o", elf], "linking the image")
    sec = section_sizes(elf, "arm-none-eabi-")
    nm = _run([find_tool("arm-none-eabi-", "nm"), "-S", elf], "nm").stdout
    syms = {}
    for line in nm.splitlines():
        parts = line.split()
        if len(parts) == 4:
            syms[parts[3]] = int(parts[1], 16)
    frames, edges = parse_callgraph(p.read_text() for p in sorted(obj.glob("*.ci")))
    roots = [f"{name}_{v}" for v in ("init", "start", "predict", "update", "step")]
    su = parse_su(p.read_text() for p in sorted(obj.glob("*.su")))
    assert su
    # the C library's stack, estimated from the image's disassembly
    called = {display_name(c) for cs in edges.values() for c in cs
              if c not in frames and c != "__indirect_call"}
    libst = image_stack(elf, "arm-none-eabi-")
    external = {n: libst[n]["stack"] for n in called if n in libst}
    fns = analyze(frames, edges, roots, indirect_targets=_indirect(frames, kf), external=external)
    forbidden = sorted(s for s in syms if s.lstrip("_") in
                       ("malloc", "free", "calloc", "realloc", "sbrk", "printf", "fopen"))
    rep = {"real": real, "target": target, "flash": sec["text"] + sec["rodata"] + sec["data"],
           "ram": sec["data"] + sec["bss"], "workspace": syms.get(f"{name}_probe_ws", 0),
           "stack": {k: v["stack"] for k, v in fns.items()}, "functions": fns,
           "heap": forbidden, "libc": sorted(set().union(*(v["libc"] for v in fns.values()))),
           "sections": sec, "image": str(elf)}
    rep["table"] = _table(kf, rep)
    return rep


def _indirect(frames, kf):
    """The indirect calls' targets: the integrators call the runtime's
    right-hand side callback; every other call through a pointer reaches a
    kernel (of the model, through its gen_rt_model, or a measurement
    kernel: <name>_h, <name>_hjac)."""
    m, name = kf._fm.model.name, kf.name
    members = {f"{m}_{k}" for k in ("mass_matrix", "forcing", "kinematics", "rhs_terms",
                                     "lin_terms", "mass_solve", "output_jacobian",
                                     "reaction_solve")} | {f"{name}_h", f"{name}_hjac"}
    kernels = sorted({display_name(t) for t in frames
                      if display_name(t) in members or display_name(t).startswith(f"{m}_k_")})
    out = {None: kernels}
    for integrator in ("gen_rt_rk4_step", "gen_rt_dopri5_trial", "gen_rt_rodas4_trial"):
        out[integrator] = ["rhs_cb"]
    out["gen_rt_input_at"] = []          # the user's controller: not the filter's
    out["gen_rt_kalman_control"] = []    # the loop's inner controller: the user's
    return out


def _table(kf, rep):
    lines = [f"{kf.name} ({kf.kind}, {rep['real']}, Cortex-M4F, -Os): flash {rep['flash']} B, "
             f"RAM {rep['ram']} B (workspace {rep['workspace']} B), no heap"]
    for k, v in rep["stack"].items():
        lines.append(f"  {k:<24} stack {v:>6} B")
    return "\n".join(lines)
