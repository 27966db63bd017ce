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
indirect calls are the integrators calling the model's right-hand side and
projection callbacks (``<name>_rhs_cb``, ``<name>_post_cb``, the only
functions whose address the generated code takes); an indirect call counts
as the deeper of the two. Calls into the C library (sinf, cosf, sqrtf,
powf, memset, the EABI's software double helpers) are listed per function
as ``libc``; the C library is not compiled with -fstack-usage, so for a
microcontroller target their stack is estimated from the disassembly of an
image linking them (``image_stack``: push/vpush/sub sp in each function
and its direct calls) and added; on the host they are not counted.

Flash is ``.text`` + ``.rodata`` of the library's objects, before the
linker's ``--gc-sections`` drops the functions a firmware does not call;
``section_sizes`` gives the same numbers for a linked image.

    rep = gen.footprint.report(model, real="float", target="cortex-m4f")
    print(rep["table"])
"""
from __future__ import annotations

import json
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

from .errors import BuildError, EomgenError
from .render import api_functions, generate

__all__ = ["report", "report_many", "build_library", "analyze", "parse_callgraph", "section_sizes",
           "image_stack", "format_table", "FootprintError", "TARGETS", "DEFAULT_STACK_LIMIT"]

DEFAULT_STACK_LIMIT = 8192

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


class FootprintError(EomgenError):
    """The stack bound cannot be computed: recursion, a dynamic frame, a
    missing tool or missing stack-usage output."""


# --------------------------------------------------------------------------
# call graph (.ci) and frames (.su)
# --------------------------------------------------------------------------

_NODE = re.compile(r'node:\s*\{\s*title:\s*"([^"]*)"\s*label:\s*"([^"]*)"')
_EDGE = re.compile(r'edge:\s*\{\s*sourcename:\s*"([^"]*)"\s*targetname:\s*"([^"]*)"')
_BYTES = re.compile(r"(\d+) bytes \(([a-z,]+)\)")


def display_name(title):
    """'dir/file.c:foo.constprop.0.isra.0' -> 'foo'."""
    name = title.rsplit(":", 1)[-1]
    return name.split(".", 1)[0]


def parse_callgraph(ci_texts):
    """Merge GCC .ci files: ({title: (frame bytes, qualifier)}, {title: set of
    callee titles}). Nodes without a frame are declarations of functions
    defined elsewhere (another file, or the C library)."""
    frames, edges = {}, {}
    for text in ci_texts:
        for title, label in _NODE.findall(text):
            m = _BYTES.search(label.replace("\\n", "\n"))
            if m:
                frames[title] = (int(m.group(1)), m.group(2))
        for src, dst in _EDGE.findall(text):
            edges.setdefault(src, set()).add(dst)
    return frames, edges


def parse_su(su_texts):
    """GCC .su lines 'file:line:col:name<TAB>bytes<TAB>qualifier' ->
    {name: (bytes, qualifier)} (the largest frame when a name repeats)."""
    out = {}
    for text in su_texts:
        for line in text.splitlines():
            parts = line.split("\t")
            if len(parts) != 3:
                continue
            name = display_name(parts[0])
            b, q = int(parts[1]), parts[2].strip()
            if name not in out or b > out[name][0]:
                out[name] = (b, q)
    return out


def analyze(frames, edges, roots, indirect_targets=(), external=None):
    """Worst-case stack of each root along the deepest path of the call
    graph. external: {C library function: worst-case stack} for callees
    outside the graph (else they count 0). Returns {root: {"frame",
    "stack", "path", "libc"}}; raises FootprintError on recursion, a
    dynamic frame or an unresolvable indirect call."""
    external = external or {}
    # 'dynamic,bounded' (stack realignment) prints an upper bound: accepted
    dynamic = sorted(display_name(t) for t, (_, q) in frames.items()
                     if q not in ("static", "dynamic,bounded"))
    if dynamic:
        raise FootprintError("functions with an unbounded dynamic stack frame (VLA or "
                             "alloca): " + ", ".join(dynamic))
    by_name = {}
    for t in frames:
        by_name.setdefault(display_name(t), []).append(t)
    ind = [t for n in indirect_targets for t in by_name.get(n, [])]
    memo = {}
    state = {}

    def callees(t):
        for c in sorted(edges.get(t, ())):
            if c == "__indirect_call":
                if not ind:
                    raise FootprintError(f"{display_name(t)} makes an indirect call and no "
                                         "indirect call target is known")
                yield from ind
            else:
                yield c

    def visit(t, chain):
        if t in memo:
            return memo[t]
        if state.get(t) == "open":
            cyc = chain[chain.index(t):] + [t]
            raise FootprintError("recursion in the call graph: "
                                 + " -> ".join(display_name(c) for c in cyc))
        state[t] = "open"
        frame = frames[t][0]
        best, best_path, libc = 0, [], set()
        for c in callees(t):
            if c in frames:
                s, p, lc = visit(c, chain + [t])
                libc |= lc
                if s > best:
                    best, best_path = s, p
            else:
                libc.add(display_name(c))
                s = external.get(display_name(c), 0)
                if s > best:
                    best, best_path = s, [display_name(c) + " (libc)"]
        state[t] = "done"
        memo[t] = (frame + best, [display_name(t)] + best_path, libc)
        return memo[t]

    out = {}
    for r in roots:
        ts = by_name.get(r)
        if not ts:
            raise FootprintError(f"no stack-usage entry for the public function {r} "
                                 "(was the library built with -fcallgraph-info=su?)")
        res = [(visit(t, []), t) for t in ts]
        (s, p, lc), t = max(res, key=lambda v: v[0][0])
        out[r] = {"frame": frames[t][0], "stack": s, "path": p, "libc": sorted(lc)}
    return out


# --------------------------------------------------------------------------
# sizes
# --------------------------------------------------------------------------

def _tool(prefix, name):
    exe = shutil.which(prefix + name)
    if exe is None:
        raise FootprintError(f"{prefix + name} not found on PATH")
    return exe


def section_sizes(path, prefix=""):
    """Section sizes of an object, archive or linked image (``size -A``):
    {"text", "rodata", "data", "bss", "flash", "functions": {name: code bytes}}.
    flash = text (with .isr_vector) + rodata; a linked image also keeps the
    initial values of .data in flash."""
    r = subprocess.run([_tool(prefix, "size"), "-A", str(path)], capture_output=True,
                       text=True)
    if r.returncode != 0:
        raise FootprintError(f"size -A {path} failed: {r.stderr}")
    tot = {"text": 0, "rodata": 0, "data": 0, "bss": 0}
    funcs = {}
    for line in r.stdout.splitlines():
        parts = line.split()
        if len(parts) < 2 or not parts[1].isdigit() or not parts[0].startswith("."):
            continue
        sec, n = parts[0], int(parts[1])
        if sec.startswith(".text") or sec == ".isr_vector":
            tot["text"] += n
            if sec.startswith(".text."):
                fn = sec[len(".text."):]
                funcs[fn] = funcs.get(fn, 0) + n
        elif sec.startswith(".rodata"):
            tot["rodata"] += n
        elif sec.startswith(".data"):
            tot["data"] += n
        elif sec.startswith(".bss"):
            tot["bss"] += n
    tot["flash"] = tot["text"] + tot["rodata"]
    tot["functions"] = funcs
    return tot


_FUNC = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
_PUSH = re.compile(r"\b(push|stmdb|vpush)(?:\.w)?\s+(?:sp!,\s*)?\{([^}]*)\}")
_SUB = re.compile(r"\bsub(?:w|\.w)?\s+sp,\s*(?:sp,\s*)?#(\d+)")
_CALL = re.compile(r"\b(bl|b\.w|b)\s+[0-9a-f]+ <([^>+]+)>")


def _reg_count(regs):
    n = 0
    for part in regs.split(","):
        part = part.strip()
        if "-" in part:
            a, b = part.split("-")
            n += int(b[1:]) - int(a[1:]) + 1
        elif part:
            n += 1
    return n, regs.strip().startswith("d")


def image_stack(elf, prefix="arm-none-eabi-"):
    """Estimated worst-case stack of every function of a linked Thumb image,
    from its disassembly: frame = push/vpush + 'sub sp, #n' in the body,
    callees from 'bl' and tail branches to another symbol. For the C library
    functions (sinf, ...) that are not built with -fstack-usage. Recursive
    library functions keep their own frame once (the estimate says so)."""
    r = subprocess.run([_tool(prefix, "objdump"), "-d", "--no-show-raw-insn", str(elf)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise FootprintError(f"objdump -d {elf} failed: {r.stderr}")
    frames, edges, cur = {}, {}, None
    for line in r.stdout.splitlines():
        m = _FUNC.match(line.strip())
        if m:
            cur = m.group(2)
            frames[cur] = 0
            edges[cur] = set()
            continue
        if cur is None or ":" not in line:
            continue
        ins = line.split(":", 1)[1]
        m = _PUSH.search(ins)
        if m:
            n, dregs = _reg_count(m.group(2))
            frames[cur] += n * (8 if dregs else 4)
        m = _SUB.search(ins)
        if m:
            frames[cur] += int(m.group(1))
        m = _CALL.search(ins)
        if m and m.group(2) != cur:
            edges[cur].add(m.group(2))
    memo = {}

    def visit(f, seen):
        if f in memo:
            return memo[f]
        if f in seen:
            return 0
        best = max((visit(c, seen | {f}) for c in edges.get(f, ()) if c in frames), default=0)
        memo[f] = frames.get(f, 0) + best
        return memo[f]

    return {f: {"frame": frames[f], "stack": visit(f, frozenset())} for f in frames}


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
    if shutil.which("cmake") is None:
        raise FootprintError("cmake not found on PATH")
    if target != "host":
        _tool(prefix, "gcc")
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
    public = [f[0] for f in api_functions(p)]
    called = {display_name(c) for cs in edges.values() for c in cs
              if c not in frames and c != "__indirect_call"}
    libc_stack = _libc_stacks(sorted(called), job["target"], job["prefix"], job["build"])
    fns = analyze(frames, edges, public, indirect_targets=[f"{p}_rhs_cb", f"{p}_post_cb"],
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
    _run([_tool(prefix, "gcc"), *LIBC_LINK[target], f"-Wl,-e,{names[0]}", f"-Wl,{und}",
          "-o", elf, "-lm", "-lc", "-lgcc"], f"linking the C library functions {names}")
    st = image_stack(elf, prefix)
    return {n: st[n]["stack"] for n in names if n in st}


def report(model, real="float", target="cortex-m4f", build_dir=None,
           stack_limit=DEFAULT_STACK_LIMIT):
    """Build the embedded subset for a target and measure it. Returns a dict:
    model, real, target, flags, flash {text, rodata, data, bss, flash},
    functions {public name: {frame, stack, path, libc, code}}, max_stack,
    libc (library functions called, not counted), and table (text)."""
    return _measure(build_library(model, real=real, target=target, build_dir=build_dir,
                                  stack_limit=stack_limit))


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
