"""Two lanes: a kernel's twin statements computed side by side.

A robot's mirrored limbs (Talos's two legs and two arms, a quadruped's
legs) give a right-hand-side kernel that holds the same arithmetic twice,
once per limb, on different temporaries and often different constants.
:func:`lanes_body` pairs those statements and writes each pair as one
statement on a two-lane vector of doubles (GCC's and clang's
``vector_size`` extension: SSE2 or AVX on x86-64, NEON on AArch64), where
the compiler emits one packed instruction for two scalar ones. The
straight-line kernel of a large robot is bound by its code size (Talos's is
larger than the instruction cache), so half the instructions for the limbs
is most of its time (bench/README.md, "Robots").

Each lane computes exactly what its scalar statement computes, bit for bit:

- the same operations on the same operands in the same association (a sum
  ``((a + b) + c)`` stays a left fold);
- operands of ``+`` and ``*`` may be swapped between the lanes (IEEE
  addition and multiplication are commutative);
- a sign may differ between the lanes (the mirror's ``-0.085`` where the
  other limb has ``0.085``, ``a - x`` where the other has ``a + x``): the
  lane's operand is multiplied by ``-1.0``, which negates exactly, and
  ``a + (-x)`` is ``a - x`` (IEEE 754 defines subtraction so);
- a function call (``sin``, ``cos``, ``sqrt``) stays a scalar call per
  lane, the two results packed.

The generated file keeps the scalar body beside the vector one
(``#if GEN_RT_LANES``, gen_rt.h): a compiler without the extension, a
32-bit ARM, a float build or ``-DGEN_RT_NO_LANES`` computes the same
numbers with scalars.

Which statements are twins: the kernel's outputs for twin speeds (the model
gives them: :func:`gen.intake.recursive.twin_speeds`, sibling subtrees with
the same joints) seed the pairing; it follows the operands of each pair
down (a statement and its twin must have the same local structure:
operations and kinds of operands, signs and constants aside), then the
users of each pair up. Statements that are not twins stay scalar; a lane
that a scalar statement reads is taken out of its vector (an extract), a
vector operand whose lanes are not one pair is packed from scalars.
"""
from __future__ import annotations

import ast
import heapq
import re

__all__ = ["lanes_body", "VECTOR", "MIN_PAIRS"]

VECTOR = "gen_rt_v2d"     # gen_rt.h: typedef double gen_rt_v2d, two lanes
# fewer pairs than this: the scalar body alone (the vector one would add
# source for nothing measurable)
MIN_PAIRS = 8

_STMT = re.compile(r"^(\s*)const (\w+) (\w+) = (.*);$")
_STORE = re.compile(r"^(\s*)(out_\w+\[\d+\]) = (.*);$")
_IDENT = re.compile(r"\b[A-Za-z_]\w*\b")


class _Opaque(Exception):
    """An expression or a pair the two-lane form does not take."""


# ---------------------------------------------------------------- the form
# A statement's expression as a tree of tuples, signs pulled out of products
# (exact: (-a) * b is -(a * b) in IEEE arithmetic) and kept on the terms of
# sums: ("lit", text), ("in", text) (an argument's entry, a name not written
# here), ("t", name) (a statement's result), ("add", (sign, node), (sign,
# node)), ("mul", a, b), ("div", a, b), ("call", fname, arg, ...).
def _canon(t):
    """(sign, node) of a Python AST of a C expression (module comment)."""
    if isinstance(t, ast.Constant) and isinstance(t.value, (int, float)) \
            and not isinstance(t.value, bool):
        return 1, ("lit", repr(t.value))
    if isinstance(t, ast.UnaryOp) and isinstance(t.op, ast.USub):
        s, n = _canon(t.operand)
        return -s, n
    if isinstance(t, ast.Name):
        return 1, ("t", t.id)
    if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name) \
            and isinstance(t.slice, ast.Constant) and isinstance(t.slice.value, int):
        return 1, ("in", f"{t.value.id}[{t.slice.value}]")
    if isinstance(t, ast.BinOp):
        sl, nl = _canon(t.left)
        sr, nr = _canon(t.right)
        if isinstance(t.op, ast.Mult):
            return sl * sr, ("mul", nl, nr)
        if isinstance(t.op, ast.Div):
            if nl[0] == "lit" and nr[0] == "lit" and "." not in nl[1] + nr[1]:
                raise _Opaque("an integer division")     # C's 1/2 is 0
            return sl * sr, ("div", nl, nr)
        if isinstance(t.op, ast.Add):
            return 1, ("add", (sl, nl), (sr, nr))
        if isinstance(t.op, ast.Sub):
            return 1, ("add", (sl, nl), (-sr, nr))
    if isinstance(t, ast.Call) and isinstance(t.func, ast.Name) and not t.keywords:
        args = []
        for a in t.args:
            s, n = _canon(a)
            if s != 1:
                raise _Opaque("a negated argument")
            args.append(n)
        return 1, ("call", t.func.id) + tuple(args)
    raise _Opaque(type(t).__name__)


def _children(n):
    if n[0] == "add":
        return [n[1][1], n[2][1]]
    if n[0] == "call":
        return list(n[2:])
    return [n[1], n[2]]


class _Statement:
    __slots__ = ("name", "text", "ctype", "indent", "item", "form", "reads", "store")

    def __init__(self, item):
        self.item = item
        self.store = False
        if isinstance(item, str):
            m = _STMT.match(item)
            if m:
                self.indent, self.ctype, self.name, self.text = m.groups()
            else:
                m = _STORE.match(item)
                if not m:
                    raise _Opaque(f"a line that is not a statement: {item.strip()[:60]}")
                self.indent, self.name, self.text = m.groups()
                self.ctype, self.store = None, True
        else:
            self.name, self.text = item[0], item[1]
            self.ctype = self.indent = None
        self.reads = set(_IDENT.findall(self.text))
        self.form = None
        if isinstance(item, str) and not self.store:
            try:
                form = _canon(ast.parse(self.text, mode="eval").body)
            except (SyntaxError, _Opaque, RecursionError):
                form = None
            # a copy of a name or a literal computes nothing
            if form is not None and not (form[1][0] == "lit" or form[1] == ("t", form[1][1])
                                         and form[0] == 1):
                self.form = form


# --------------------------------------------------------------- pairing
class _Pairs:
    """The twin statements of a body (module docstring)."""

    DEPTH = 3       # how deep through temporaries a tie between alignments is decided

    def __init__(self, stmts):
        self.st = stmts
        self.idx = {s.name: i for i, s in enumerate(stmts) if not s.store}
        self.alias = {s.name: s.text.strip() for s in stmts
                      if s.form is None and not s.store and re.fullmatch(r"\w+", s.text.strip())}
        self.ids, self.memo = {}, {}
        self.partner = {}

    def _id(self, key):
        return self.ids.setdefault(key, len(self.ids))

    def skel(self, n, d):
        """The structure of a node to depth d through temporaries: kinds
        and operations; signs, literal values, the order of + and * and the
        names aside."""
        k = n[0]
        if k == "lit":
            return self._id(("lit",))
        if k == "in":
            return self._id(("in", n[1].split("[")[0]))
        if k == "t":
            j = self.idx.get(n[1])
            if j is None:
                return self._id(("in", n[1]))
            if d <= 0 or self.st[j].form is None:
                return self._id(("t",))
            key = (j, d)
            if key not in self.memo:
                self.memo[key] = self._id(("t", self.skel(self.st[j].form[1], d - 1)))
            return self.memo[key]
        if k in ("add", "mul"):
            a, b = _children(n)
            return self._id((k,) + tuple(sorted((self.skel(a, d), self.skel(b, d)))))
        if k == "div":
            return self._id(("div", self.skel(n[1], d), self.skel(n[2], d)))
        return self._id(("call", n[1]) + tuple(self.skel(a, d) for a in n[2:]))

    def twins_of(self, na, nb, out):
        """The (a, b) statement pairs two nodes of the same structure read
        at the same places (children of + and * aligned by structure)."""
        k = na[0]
        if k == "t":
            ja, jb = self.idx.get(na[1]), self.idx.get(nb[1])
            if ja is not None and jb is not None and ja != jb:
                out.append((ja, jb))
            return
        if k in ("lit", "in"):
            return
        ca, cb = _children(na), _children(nb)
        if len(ca) != len(cb):
            return
        if k in ("add", "mul"):
            straight = [self.skel(x, 0) == self.skel(y, 0) for x, y in zip(ca, cb)]
            crossed = [self.skel(x, 0) == self.skel(y, 0) for x, y in zip(ca, cb[::-1])]
            if all(crossed) and not all(straight):
                cb = cb[::-1]
            elif all(crossed):
                for d in range(1, self.DEPTH + 1):
                    s1 = sum(self.skel(x, d) == self.skel(y, d) for x, y in zip(ca, cb))
                    s2 = sum(self.skel(x, d) == self.skel(y, d) for x, y in zip(ca, cb[::-1]))
                    if s1 != s2:
                        cb = cb[::-1] if s2 > s1 else cb
                        break
        for x, y in zip(ca, cb):
            if x[0] == y[0] and self.skel(x, 0) == self.skel(y, 0):
                self.twins_of(x, y, out)

    def pair(self, i, j):
        """Pair statements i (lane 0) and j (lane 1), then their operands'
        statements, down."""
        stack = [(i, j)]
        while stack:
            a, b = stack.pop()
            if a == b or a in self.partner or b in self.partner:
                continue
            fa, fb = self.st[a].form, self.st[b].form
            if fa is None or fb is None or fa[1][0] != fb[1][0] \
                    or self.skel(fa[1], 0) != self.skel(fb[1], 0):
                continue
            self.partner[a] = self.partner[b] = (a, b)
            out = []
            self.twins_of(fa[1], fb[1], out)
            stack.extend(reversed(out))

    def resolve(self, name):
        seen = set()
        while name in self.alias and name not in seen:
            seen.add(name)
            name = self.alias[name]
        return name

    def run(self, seeds):
        for x, y in seeds:
            i, j = self.idx.get(self.resolve(x)), self.idx.get(self.resolve(y))
            if i is not None and j is not None:
                self.pair(i, j)
        self.upward()
        return self.partner

    def upward(self):
        """Pair the readers of paired statements: a statement that reads
        lane 0 of a pair with one that reads lane 1 at the same place."""
        users = {}
        for i, s in enumerate(self.st):
            if s.form is None:
                continue
            for x in s.reads:
                j = self.idx.get(x)
                if j is not None:
                    users.setdefault(j, []).append(i)
        changed = True
        while changed:
            changed = False
            for x in sorted(self.partner):
                a0, b0 = self.partner[x]
                if x != a0:
                    continue
                for a in users.get(a0, ()):
                    if a in self.partner:
                        continue
                    sa = self.skel(self.st[a].form[1], 0)
                    for b in users.get(b0, ()):
                        if b in self.partner or b == a or self.st[b].form is None \
                                or self.skel(self.st[b].form[1], 0) != sa:
                            continue
                        out = []
                        self.twins_of(self.st[a].form[1], self.st[b].form[1], out)
                        if (a0, b0) in out:
                            self.pair(a, b)
                            changed = True
                            break


# -------------------------------------------------------------- emission
def _v(a, b):
    return f"(({VECTOR}){{{a}, {b}}})"


def _signed(x, s):
    """x (a vector) with the lanes' signs s applied, exactly."""
    if s == (1, 1):
        return x
    if s == (-1, -1):
        return f"(-{x})"
    return f"({x} * {_v(float(s[0]), float(s[1]))})"


class _Writer:
    """The vector expression of a pair of nodes: (aligned operands, text,
    the scalar names it reads)."""

    def __init__(self, pairs, vname):
        self.p = pairs
        self.vname = vname
        self.memo = {}

    def vec(self, na, nb):
        key = (id(na), id(nb))
        hit = self.memo.get(key)
        if hit is None:
            hit = self.memo[key] = self._vec(na, nb)
        if isinstance(hit, _Opaque):
            raise hit
        return hit

    def _vec(self, na, nb):
        k = na[0]
        if k != nb[0]:
            return _Opaque("kinds")
        if k in ("lit", "in"):
            return 0, _v(na[1], nb[1]), frozenset()
        if k == "t":
            ja, jb = self.p.idx.get(na[1]), self.p.idx.get(nb[1])
            if ja is not None and ja != jb and self.p.partner.get(ja) == (ja, jb):
                return 1, self.vname[ja], frozenset()
            return 0, _v(na[1], nb[1]), frozenset((na[1], nb[1]))
        if k == "call":
            return _Opaque("a call inside an expression")
        try:
            if k == "div":
                s1, left, r1 = self.vec(na[1], nb[1])
                s2, right, r2 = self.vec(na[2], nb[2])
                return s1 + s2, f"({left} / {right})", r1 | r2
            best = None
            ca = (na[1], na[2])
            for cb in ((nb[1], nb[2]), (nb[2], nb[1])):
                xa = [c[1] if k == "add" else c for c in ca]
                xb = [c[1] if k == "add" else c for c in cb]
                if any(x[0] != y[0] or self.p.skel(x, 0) != self.p.skel(y, 0)
                       for x, y in zip(xa, xb)):
                    continue
                try:
                    s1, left, r1 = self.vec(xa[0], xb[0])
                    s2, right, r2 = self.vec(xa[1], xb[1])
                except _Opaque:
                    continue
                if best is not None and s1 + s2 <= best[0]:
                    continue
                if k == "mul":
                    text = f"({left} * {right})"
                else:
                    text = _add_text(left, (ca[0][0], cb[0][0]), right, (ca[1][0], cb[1][0]))
                best = (s1 + s2, text, r1 | r2)
            if best is None:
                return _Opaque("no alignment")
            return best
        except _Opaque as e:
            return e


def _add_text(left, sl, right, sr):
    """left * sl + right * sr per lane, as the scalar code computes it."""
    if sl == (1, 1) and sr == (-1, -1):
        return f"({left} - {right})"
    if sl == (-1, -1) and sr == (1, 1):
        return f"({right} - {left})"
    return f"({_signed(left, sl)} + {_signed(right, sr)})"


def _order(stmts, units, unit_of, idx):
    """The units in an order every read respects, near the body's own."""
    deps = [set() for _ in units]
    for k, u in enumerate(units):
        for i in u:
            for x in stmts[i].reads:
                j = idx.get(x)
                if j is not None and unit_of[j] != k:
                    deps[k].add(unit_of[j])
    users = [[] for _ in units]
    for k, d in enumerate(deps):
        for j in d:
            users[j].append(k)
    indeg = [len(d) for d in deps]
    heap = [(max(u), k) for k, u in enumerate(units) if not indeg[k]]
    heapq.heapify(heap)
    out = []
    while heap:
        _, k = heapq.heappop(heap)
        out.append(k)
        for w in users[k]:
            indeg[w] -= 1
            if not indeg[w]:
                heapq.heappush(heap, (max(units[w]), w))
    if len(out) != len(units):
        raise _Opaque("a cycle among the pairs")
    return out


def lanes_body(items, seeds, after=()):
    """The two-lane form of a kernel body, or None.

    Parameters
    ----------
    items : list
        The body in order: lines ``const <type> <name> = <expr>;`` or
        ``out_<x>[<k>] = <expr>;``, or ``(name, expr)`` statements (the
        template declares them).
    seeds : list of (str, str)
        Names of twin results (lane 0, lane 1): the kernel's outputs for
        twin speeds, or names the body copies them to.
    after : iterable of str
        What the kernel reads after the body (its stores' lines, the names
        of its bound outputs): the names in it stay defined.

    Returns
    -------
    list or None
        The body's items with the pairs as vector statements (module
        docstring); None when the body has a line of another kind or fewer
        than MIN_PAIRS pairs.
    """
    try:
        stmts = [_Statement(it) for it in items]
    except _Opaque:
        return None
    p = _Pairs(stmts)
    partner = p.run(seeds)
    n = len(stmts)
    units, unit_of = [], {}
    for i in range(n):
        if i not in unit_of:
            u = partner.get(i, (i,))
            for x in u:
                unit_of[x] = len(units)
            units.append(u)
    vname = {}
    for u in units:
        if len(u) == 2:
            vname[u[0]] = vname[u[1]] = "v_" + stmts[u[0]].name
    w = _Writer(p, vname)
    try:
        order = _order(stmts, units, unit_of, p.idx)
    except _Opaque:
        return None
    plan, npairs = [], 0
    need = {x for text in after for x in _IDENT.findall(text)}
    for k in order:
        u = units[k]
        if len(u) == 2:
            a, b = u
            (sa, na), (sb, nb) = stmts[a].form, stmts[b].form
            if na[0] != "call":
                try:
                    _s, text, reads = w.vec(na, nb)
                except _Opaque:
                    text = None
                if text is not None:
                    plan.append(("v", a, b, _signed(text, (sa, sb))))
                    need |= reads
                    npairs += 1
                    continue
                # no vector form after all: two scalars
                del partner[a], partner[b]
                plan += [("s", a), ("s", b)]
            else:
                plan += [("s", a), ("s", b), ("pack", a, b)]
            need |= stmts[a].reads | stmts[b].reads
        else:
            plan.append(("s", u[0]))
            need |= stmts[u[0]].reads
    if npairs < MIN_PAIRS:
        return None
    out = []
    for step in plan:
        if step[0] == "s":
            out.append(stmts[step[1]].item)
        elif step[0] == "pack":
            _, a, b = step
            out.append(f"{stmts[a].indent}const {VECTOR} {vname[a]} = "
                       f"{_v(stmts[a].name, stmts[b].name)};")
        else:
            _, a, b, text = step
            s = stmts[a]
            out.append(f"{s.indent}const {VECTOR} {vname[a]} = {text};")
            for lane, i in enumerate((a, b)):
                if stmts[i].name in need:
                    out.append(f"{s.indent}const {stmts[i].ctype} {stmts[i].name} = "
                               f"{vname[a]}[{lane}];")
    return _without_unread(out)


def _without_unread(lines):
    """lines without the vector statements nothing reads (a strict build
    refuses an unused variable), to a fixed point."""
    decl = re.compile(rf"^\s*const {VECTOR} (\w+) = ")
    while True:
        reads = {}
        for line in lines:
            text = line if isinstance(line, str) else line[1]
            m = decl.match(text) if isinstance(line, str) else None
            rhs = text[m.end():] if m else text.split("=", 1)[-1]
            for x in _IDENT.findall(rhs):
                reads[x] = reads.get(x, 0) + 1
        keep = [ln for ln in lines if not (isinstance(ln, str) and decl.match(ln)
                                           and not reads.get(decl.match(ln).group(1)))]
        if len(keep) == len(lines):
            return lines
        lines = keep
