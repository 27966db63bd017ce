"""Footprint of the embedded subset of a generated model: flash and the
worst-case stack of every public function, for a target.

The model is generated, then its library target ``<name>_model`` (model
kernels and runtime, no stdio, no heap) is built with the generated CMake
project: for ``target="cortex-m4f"`` through the project's own toolchain
file ``arm-none-eabi.cmake`` (``-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16
-mfloat-abi=hard -Os``), for ``target="host"`` with the host compiler.
The build uses GCC's ``-fstack-usage`` (one frame size per function, .su)
and ``-fcallgraph-info=su`` (the static call graph with frame sizes, .ci;
GCC >= 10).

Worst-case stack of a function = its frame plus the largest worst case of
anything it calls, along the deepest path of the call graph. The generated
code has no recursion and no dynamic stack: a cycle or a function with a
``dynamic`` (unbounded) frame is an error (FootprintError), never a number;
``dynamic,bounded`` (stack realignment on x86-64) counts with GCC's bound. The only
indirect calls are the integrators calling the runtime's right-hand side
callback (``rhs_cb`` in gen_rt_engine.c), the user's controller, and the
runtime calling the model's kernels through its ``gen_rt_model`` (the
``<name>_k_*`` kernels, their adapters and the unrolled mass solve, the
only other functions whose address is taken); an indirect call counts as
the deepest of its possible targets. Calls into the C library (sinf, cosf, sqrtf,
powf, memset, the EABI's software double helpers) are listed per function
as ``libc``; the C library is not compiled with -fstack-usage, so for a
microcontroller target their stack is estimated from the disassembly of an
image linking them (``image_stack``: push/vpush/sub sp in each function
and its direct calls) and added; on the host they are not counted.

Flash is ``.text`` + ``.rodata`` of the library's objects, before the
linker's ``--gc-sections`` drops the functions a firmware does not call;
``section_sizes`` gives the same numbers for a linked image.

This module generates, builds and reports; the analysis of the compiler's
output (.su, .ci, disassembly, section sizes) is gen.stack.

    rep = gen.toolchain.footprint.report(model, real="float", target="cortex-m4f")
    print(rep["table"])
"""
from __future__ import annotations

import json
import shutil
import subprocess
import tempfile
from pathlib import Path

from ..core.errors import BuildError
from ..codegen.abi import FUNCTIONS, STACK_LIMIT
from ..codegen.render import generate
from .stack import (FootprintError, analyze, display_name, find_tool, image_stack,
                    parse_callgraph, parse_su, section_sizes)

__all__ = ["report", "report_many", "build_library", "analyze", "parse_callgraph", "section_sizes",
           "image_stack", "format_table", "FootprintError", "TARGETS", "DEFAULT_STACK_LIMIT"]

DEFAULT_STACK_LIMIT = STACK_LIMIT     # gen/codegen/abi.py: the embedded profile's bound

# target -> (toolchain file in the generated project or None, tool prefix)
TARGETS = {
    "cortex-m4f": ("arm-none-eabi.cmake", "arm-none-eabi-"),
    "host": (None, ""),
}
# flags to link the C library of a target (the stack of sinf, ... is measured
# on that image)
LIBC_LINK = {
    "cortex-m4f": ["-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard",
                   "--specs=nano.specs", "--specs=nosys.specs", "-nostartfiles"],
}


# --------------------------------------------------------------------------
# build and report
# --------------------------------------------------------------------------

def _run(cmd, what):
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if r.returncode != 0:
        raise BuildError(f"{what} failed", "$ " + " ".join(map(str, cmd)) + "\n"
                         + r.stdout + r.stderr)
    return r


def _prepare(model, real, target, build_dir, stack_limit, jobs):
    """Generate the sources; the CMake commands that build the library."""
    if target not in TARGETS:
        raise FootprintError(f"unknown target {target!r}; known: {', '.join(TARGETS)}")
    toolchain, prefix = TARGETS[target]
    stack_limit = DEFAULT_STACK_LIMIT if stack_limit is None else stack_limit
    if int(stack_limit) != stack_limit or stack_limit < 0:
        raise FootprintError(f"stack_limit must be a number of bytes >= 0 (0: no bound), "
                             f"got {stack_limit!r}")
    if shutil.which("cmake") is None:
        raise FootprintError("cmake not found on PATH")
    if target != "host":
        find_tool(prefix, "gcc")
    root = Path(build_dir) if build_dir else Path(tempfile.mkdtemp(prefix="eomgen-footprint-"))
    src, bld = root / "src", root / "build"
    generate(model, src, real=real)
    P = model.name.upper()
    # MinSizeRel (-Os) for a microcontroller, Release (-O3) on the host
    btype = "Release" if target == "host" else "MinSizeRel"
    cfg = ["cmake", "-S", src, "-B", bld, f"-DCMAKE_BUILD_TYPE={btype}",
           f"-D{P}_STACK_USAGE=ON", f"-D{P}_STACK_LIMIT={int(stack_limit)}",
           f"-D{P}_BUILD_SIM=OFF", "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON"]
    if toolchain:
        cfg.append(f"-DCMAKE_TOOLCHAIN_FILE={src / toolchain}")
    what = f"{model.name} ({real}, {target})"
    commands = [(cfg, f"configuring {what}"),
                (["cmake", "--build", bld, "--target", f"{model.name}_model", f"-j{jobs}"],
                 f"building {model.name}_model for {what}")]
    return {"model": model, "real": real, "target": target, "stack_limit": int(stack_limit),
            "src": src, "build": bld, "prefix": prefix, "commands": commands,
            "library": bld / f"lib{model.name}_model.a"}


def _execute(job):
    for cmd, what in job["commands"]:
        _run(cmd, what)
    flags = ""
    cc_json = job["build"] / "compile_commands.json"
    if cc_json.is_file():
        for entry in json.loads(cc_json.read_text()):
            if entry["file"].endswith(f"{job['model'].name}.c"):
                cmd = entry["command"].split()
                flags = " ".join(c for c in cmd[1:] if c.startswith(("-m", "-O", "-W", "-f",
                                                                      "-std", "-pedantic")))
    job["flags"] = flags
    return job


def build_library(model, real="float", target="cortex-m4f", build_dir=None,
                  stack_limit=DEFAULT_STACK_LIMIT, jobs=2):
    """Generate the model into build_dir/src and build its library target
    with stack-usage output. Returns {"src", "build", "library", "flags",
    "prefix", ...}."""
    return _execute(_prepare(model, real, target, build_dir, stack_limit, jobs))


def _measure(job):
    model = job["model"]
    objdir = job["build"] / "CMakeFiles" / f"{model.name}_model.dir"
    ci = sorted(objdir.glob("*.ci"))
    su = sorted(objdir.glob("*.su"))
    if not su:
        raise FootprintError(f"no .su files in {objdir}: the compiler does not support "
                             "-fstack-usage (GCC needed)")
    if not ci:
        raise FootprintError(f"no .ci files in {objdir}: -fcallgraph-info=su needs GCC >= 10")
    frames, edges = parse_callgraph(p.read_text() for p in ci)
    su_frames = parse_su(p.read_text() for p in su)
    for t, (n, q) in frames.items():   # the two outputs must agree
        s = su_frames.get(display_name(t))
        if s is not None and s[1] != q:
            raise FootprintError(f"{display_name(t)}: .su says {s}, .ci says {(n, q)}")
    p = model.name
    public = [f"{p}_{f.verb}" for f in FUNCTIONS]
    called = {display_name(c) for cs in edges.values() for c in cs
              if c not in frames and c != "__indirect_call"}
    libc_stack = _libc_stacks(sorted(called), job["target"], job["prefix"], job["build"])
    fns = analyze(frames, edges, public, indirect_targets=_indirect_targets(p),
                  external=libc_stack)
    sizes = section_sizes(job["library"], job["prefix"])
    for name, v in fns.items():
        v["code"] = sizes["functions"].get(name, 0)
    flash = {k: sizes[k] for k in ("text", "rodata", "data", "bss", "flash")}
    rep = {
        "model": p, "real": job["real"], "target": job["target"], "flags": job["flags"],
        "stack_limit": job["stack_limit"], "library": str(job["library"]),
        "build_dir": str(job["build"]), "flash": flash, "functions": fns,
        "max_stack": max(v["stack"] for v in fns.values()),
        "libc": sorted(set().union(*(v["libc"] for v in fns.values()))),
        "libc_stack": libc_stack,
    }
    rep["table"] = format_table([rep])
    return rep


def _libc_stacks(names, target, prefix, workdir):
    """{C library function: worst-case stack}, estimated by image_stack on
    an image that links just these functions from the target's C library
    (newlib-nano, libm, libgcc); {} for the host (not counted)."""
    if target not in LIBC_LINK or not names:
        return {}
    elf = Path(workdir) / "libc_probe.elf"
    und = ",".join(f"--undefined={n}" for n in names)
    _run([find_tool(prefix, "gcc"), *LIBC_LINK[target], f"-Wl,-e,{names[0]}", f"-Wl,{und}",
          "-o", elf, "-lm", "-lc", "-lgcc"], f"linking the C library functions {names}")
    st = image_stack(elf, prefix)
    return {n: st[n]["stack"] for n in names if n in st}


def report(model, real="float", target="cortex-m4f", build_dir=None,
           stack_limit=DEFAULT_STACK_LIMIT):
    """Build the embedded subset for a target and measure it; the build fails
    (BuildError, -Wstack-usage) on a function frame above stack_limit bytes
    (None: DEFAULT_STACK_LIMIT, 0: no bound). Returns a dict:
    model, real, target, flags, flash {text, rodata, data, bss, flash},
    functions {public name: {frame, stack, path, libc, code}}, max_stack,
    libc (library functions called, not counted), and table (text)."""
    return _measure(build_library(model, real=real, target=target, build_dir=build_dir,
                                  stack_limit=stack_limit))


# Which members of a gen_rt_model each runtime function calls through its
# pointers (csrc/gen_rt_model.c), and what the integrators call back: the
# indirect calls of the call graph, resolved per caller.
_RUNTIME_INDIRECT = {
    "gen_rt_model_eval_mass_matrix": ["mass_matrix"],
    "gen_rt_model_eval_forcing": ["forcing"],
    "gen_rt_model_eval_kinematics": ["kinematics"],
    "gen_rt_model_eval_constraints": ["constraints"],
    "gen_rt_model_eval_constraint_jacobian": ["constraint_jacobian"],
    "gen_rt_model_eval_velocity_constraints": ["velocity_constraints"],
    "gen_rt_model_eval_velocity_constraint_matrix": ["velocity_constraint_matrix"],
    "gen_rt_model_eval_energy": ["energy"],
    "gen_rt_model_eval_auxiliary_forces": ["auxiliary", "rhs_terms", "reaction_solve"],
    # static helpers of gen_rt_model.c, when the compiler does not inline them
    "constraint_jacobian_at": ["constraint_jacobian"],
    "velocity_matrix_at": ["velocity_constraint_matrix"],
    "gen_rt_model_rhs": ["rhs_terms", "accel_terms", "mass_solve", "rhs_solve", "reaction_solve"],
    "rhs_": ["rhs_terms", "accel_terms", "mass_solve", "rhs_solve", "reaction_solve"],
    "gen_rt_model_eval_rhs": ["rhs_terms", "accel_terms", "mass_solve", "rhs_solve",
                              "reaction_solve"],
    "gen_rt_model_project": ["constraint_jacobian", "velocity_constraint_matrix"],
    "gen_rt_model_consistent_state": ["constraint_jacobian", "velocity_constraint_matrix"],
    "gen_rt_model_linearize": ["rhs_terms", "accel_terms", "lin_terms", "mass_solve",
                               "reaction_solve"],
    # the user's controller callback (simulate_input, gen_rt_input.c): its
    # stack is the user's own and not part of the model's report
    "gen_rt_input_at": [],
    "gen_rt_model_jacobian": ["rhs_terms", "accel_terms", "mass_solve", "rhs_solve", "lin_terms",
                              "reaction_solve"],
    "jacobian_at": ["lin_terms"],
    "gen_rt_model_step_sensitivity": ["rhs_terms", "accel_terms", "mass_solve", "rhs_solve",
                                      "lin_terms", "reaction_solve"],
    "gen_rt_model_linearize_discrete": ["rhs_terms", "accel_terms", "lin_terms", "mass_solve",
                                        "reaction_solve"],
    "linearize_": ["rhs_terms", "accel_terms", "lin_terms", "mass_solve", "output_jacobian",
                   "reaction_solve"],
    "gen_rt_model_linearize_outputs": ["rhs_terms", "accel_terms", "lin_terms", "mass_solve",
                                       "output_jacobian", "reaction_solve"],
    "gen_rt_model_eval_outputs": ["outputs"],
    # the simulation engine (gen_rt_events.c): output events
    "outputs_": ["outputs"],
    # hybrid={...} (gen_rt_hybrid.c, and the engine's jumps)
    "gen_rt_hybrid_rhs": ["rhs_terms", "accel_terms", "hybrid_jacobian", "hybrid_bias"],
    "gen_rt_hybrid_values": ["hybrid_values", "rhs_terms", "accel_terms", "hybrid_jacobian",
                             "hybrid_bias"],
    "gen_rt_hybrid_rates": ["hybrid_jacobian"],
    "gen_rt_hybrid_impulse": ["mass_matrix", "velocity_constraint_matrix", "hybrid_jacobian"],
    "gen_rt_hybrid_reset": ["hybrid_reset", "constraints", "velocity_constraints",
                            "constraint_jacobian", "velocity_constraint_matrix"],
    "gen_rt_hybrid_jump": ["hybrid_values", "hybrid_jacobian", "mass_matrix",
                     "velocity_constraint_matrix", "hybrid_reset", "constraints",
                     "velocity_constraints", "constraint_jacobian", "rhs_terms", "accel_terms",
                     "hybrid_bias"],
}
# what the integrators call back (gen_rt_engine.c)
_CALLBACKS = ["rhs_cb"]


def _indirect_targets(p):
    """{caller: [functions its indirect calls may reach]} for model prefix p."""
    member = {"kinematics": f"{p}_kinematics", "rhs_terms": f"{p}_rhs_terms",
              "lin_terms": f"{p}_lin_terms", "mass_solve": f"{p}_mass_solve",
              "output_jacobian": f"{p}_output_jacobian", "mass_matrix": f"{p}_mass_matrix",
              "forcing": f"{p}_forcing", "rhs_solve": f"{p}_k_rhs_terms",
              "reaction_solve": f"{p}_reaction_solve"}
    # a small constrained model's rhs_solve is a wrapper of its fused kernel
    extra = {"rhs_solve": [f"{p}_rhs_solve"]}
    out = {caller: [n for k in ks for n in [member.get(k, f"{p}_k_{k}")] + extra.get(k, [])]
           for caller, ks in _RUNTIME_INDIRECT.items()}
    for integrator in ("gen_rt_rk4_step", "gen_rt_dopri5_trial", "gen_rt_rodas4_trial"):
        out[integrator] = list(_CALLBACKS)
    # any other caller is runtime code the compiler inlined somewhere else (at
    # -O3 gen_rt_model_rhs into rhs_cb, say): it may reach any kernel. The
    # kernels call nothing indirectly, so this bound is safe (and may be loose)
    members = {k for ks in _RUNTIME_INDIRECT.values() for k in ks}
    out[None] = sorted(n for k in members for n in [member.get(k, f"{p}_k_{k}")] + extra.get(k, []))
    return out


def report_many(items, target="cortex-m4f", root=None, stack_limit=DEFAULT_STACK_LIMIT,
                workers=2):
    """report() for several (model, real) or (model, real, stack_limit)
    items: generated one after the other, built by `workers` CMake builds at
    once, measured. Returns the reports in the order of items."""
    from concurrent.futures import ThreadPoolExecutor
    root = Path(root) if root else Path(tempfile.mkdtemp(prefix="eomgen-footprint-"))
    jobs = []
    for it in items:
        model, real = it[0], it[1]
        lim = it[2] if len(it) > 2 else stack_limit
        jobs.append(_prepare(model, real, target, root / f"{model.name}_{real}", lim, 1))
    with ThreadPoolExecutor(max_workers=max(1, int(workers))) as ex:
        done = list(ex.map(_execute, jobs))
    return [_measure(j) for j in done]


def format_table(reports):
    """A text table of one or more reports (flash, then the stack of every
    public function)."""
    lines = []
    for rep in reports:
        f = rep["flash"]
        lines.append(f"{rep['model']} [{rep['real']}, {rep['target']}]  flash {f['flash']} B "
                     f"(.text {f['text']} + .rodata {f['rodata']}), .data {f['data']} B, "
                     f".bss {f['bss']} B")
        lines.append(f"  flags: {rep['flags']}")
        w = max(len(n) for n in rep["functions"])
        how = ("C library stack estimated from its disassembly" if rep.get("libc_stack")
               else "+ C library calls, not counted")
        lines.append(f"  {'function':<{w}}  {'code B':>7}  {'frame B':>7}  {'stack B':>7}  "
                     f"deepest path ({how})")
        for n, v in rep["functions"].items():
            path = " > ".join(v["path"][1:]) or "-"
            names = [n for n in v["libc"] if not n.startswith("__aeabi_")]
            if len(names) < len(v["libc"]):
                names.append("__aeabi_* (software double)")
            lib = f"  [calls {', '.join(names)}]" if names else ""
            code = v["code"] or "-"   # per-function code needs -ffunction-sections
            lines.append(f"  {n:<{w}}  {code:>7}  {v['frame']:>7}  {v['stack']:>7}  "
                         f"{path}{lib}")
        lines.append(f"  worst case: {rep['max_stack']} B")
        lines.append("")
    return "\n".join(lines)
