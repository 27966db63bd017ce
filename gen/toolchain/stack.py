"""Worst-case stack from GCC's own output, for any C code: frame sizes from
``-fstack-usage`` (.su), the static call graph from ``-fcallgraph-info=su``
(.ci, GCC >= 10), the worst case of each root along the deepest path, and
an estimate from the disassembly for code built without them (the C
library). Also the section sizes of an object, archive or linked image.

Recursion, an unbounded (``dynamic``) frame or an unresolvable indirect
call is an error (FootprintError), never a number. gen.footprint builds a
generated model and calls these.
"""
from __future__ import annotations

import re
import shutil
import subprocess

from ..core.errors import EomgenError

__all__ = ["analyze", "parse_callgraph", "parse_su", "display_name", "section_sizes",
           "image_stack", "find_tool", "FootprintError"]


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
    graph. indirect_targets: the functions an indirect call may reach, as a
    list (any caller) or as {caller: [targets]} with the key None for every
    other caller; an indirect call counts as the deepest of its targets.
    external: {C library function: worst-case stack} for callees outside
    the graph (else they count 0). Returns {root: {"frame", "stack",
    "path", "libc"}}; raises FootprintError on recursion, a dynamic frame
    or an unresolvable indirect call."""
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
    if not isinstance(indirect_targets, dict):
        indirect_targets = {None: list(indirect_targets)}
    ind_by = {k: [t for n in v for t in by_name.get(n, [])] for k, v in indirect_targets.items()}
    memo = {}
    state = {}

    def callees(t):
        for c in sorted(edges.get(t, ())):
            if c == "__indirect_call":
                ind = ind_by.get(display_name(t), ind_by.get(None, []))
                if not ind and display_name(t) in ind_by:
                    continue            # its possible targets are not in this build
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

def find_tool(prefix, name):
    """The path of the tool prefix + name (a binutils/GCC program); FootprintError
    when it is not on PATH."""
    exe = shutil.which(prefix + name)
    if exe is None:
        raise FootprintError(f"{prefix + name} not found on PATH")
    return exe


def section_sizes(path, prefix=""):
    """Section sizes of an object, archive or linked image (``size -A``):
    {"text", "rodata", "data", "bss", "flash", "functions": {name: code bytes}}.
    flash = text (with .isr_vector) + rodata; a linked image also keeps the
    initial values of .data in flash."""
    r = subprocess.run([find_tool(prefix, "size"), "-A", str(path)], capture_output=True,
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
    r = subprocess.run([find_tool(prefix, "objdump"), "-d", "--no-show-raw-insn", str(elf)],
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
