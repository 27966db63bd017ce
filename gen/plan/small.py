"""Straight-line accelerations of a small constrained model, as data.

The runtime solves a constrained model's accelerations in loops sized at
run time (csrc/runtime/gen_rt_dynamics.c): Kane's partitioned solve (the
dependent speeds' block Ad, then the reduced system T^T M T) and Lagrange's
KKT system, each through the pivoted LU of gen_rt_linalg.c. For a small
model those loops, their work arrays and the calls between them cost several
times the model's own arithmetic. ``accel_program`` traces the same
algorithms, operation by operation and in the same order, over the model's
matrices as the fused right-hand-side kernel holds them (locals, with the
structural zeros and ones known), and returns them as straight-line C: each
pivot search becomes comparisons, each possible pivot a branch in which the
row exchange is a renaming, and an operation is left out only where IEEE
arithmetic makes it exact to do so:

- ``1 * x`` is x; ``x - (+0)`` is x; ``+0 + x`` is x unless x may be -0
  (``+0 + -0`` is +0: the sum is kept then);
- a product with a structural zero is +-0 when its other factor is finite
  (which the program then checks before it writes anything), and
  ``s + (+-0)``, ``s - (+-0)`` are s unless s may be -0;
- the runtime's own value tests (``if (l != 0)`` in the LU, ``if (a != 0)``
  in its products) skip what a structural zero makes zero; where only the
  run time knows the value, the update is a select, unless skipping it
  leaves the value unchanged anyway (the other factor finite, the value not
  -0).

A value may be -0 unless it is a literal other than -0, or a sum started
from +0 (``+0 + x`` never is, nor a sum of such). So every result the
program writes is the runtime's, bit for bit, and every failure (a pivot
under its tolerance, a non-finite value, a partition past
GEN_RT_PARTITION_CMAX) returns a nonzero status before anything is written:
the caller then takes the runtime's general path, which names the failure.

    prog = accel_program("kkt", n, m, M, f, A, a)     # None: too large
    lines = c_lines(prog, real="double")

A model uses it through kernel_program: a constrained model with explicit
kinematics whose system is small enough gets a fused right-hand side
(gen.codegen.render, templates/c/model_kern.c.j2): its rhs_terms kernel
binds M, f, A and a to locals (BIND), runs the program over them and returns
its status; the model's eval_rhs calls it first when no multipliers are
asked, and the runtime's rhs_ through gen_rt_model.rhs_solve, each falling
back to the general path on a nonzero status. The partition's bound
GEN_RT_PARTITION_CMAX is in gen_rt.h. tests/unit/plan/test_small_solve.py
checks the programs against the runtime, bit for bit, and the seed's models
with and without the general path.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

__all__ = ["SMALL_MAX_SIZE", "SMALL_MAX_PATHS", "BIND", "accel_program", "kernel_program",
           "c_lines", "Program"]

# the straight-line solve is for systems of at most this size (Kane: the
# speeds; Lagrange: speeds plus multipliers); larger ones keep the
# runtime's loops, whose cost is then the model's rather than the calls'
SMALL_MAX_SIZE = 8
# and at most this many pivot paths (each a copy of the rest of the solve)
SMALL_MAX_PATHS = 16
FAIL = "return GEN_RT_ERR_SINGULAR;"
# the fused right-hand side's locals of M, f, A and a (kernel_program)
BIND = {"M": "m_", "f": "f_", "A": "ca_", "a": "cb_"}


class _TooLarge(Exception):
    pass


@dataclass(frozen=True)
class _V:
    """A value of the traced program: C text (a local's name, a literal, or
    for a structural zero the product that made it), its exact value when it
    is a literal (lit), whether it may be -0 (mnz), and zero: +-0 for sure
    (a structural zero times a factor the program checks finite)."""
    t: str
    lit: float | None = None
    mnz: bool = True
    zero: bool = False

    @property
    def is_zero(self):
        return self.zero or self.lit == 0.0


def _lit(v):
    """A literal 0, -0, 1 or -1 (-1: the negation of a structural 1; the
    only ones folded: any other number stays in its local, so a float build
    computes with the float value)."""
    neg = math.copysign(1.0, v) < 0
    if v == 0.0:
        return _V("(-(gen_rt_real)0)" if neg else "0", -0.0 if neg else 0.0, mnz=neg)
    if v == 1.0:
        return _V("1", 1.0, mnz=False)
    if v == -1.0:
        return _V("(-1)", -1.0, mnz=False)
    raise ValueError(f"not a literal the solve folds: {v!r}")


@dataclass
class Program:
    """The traced solve: items (C statements, and ("if", cond, then, else)
    blocks; every path ends in a return), its number of pivot paths, and
    per path at most: arithmetic operations (+ - * and negations, flops)
    and divisions (divs)."""
    items: list
    paths: int
    flops: int
    divs: int


class _Tracer:
    """Emits the statements of one path; fork() gives each pivot its own."""

    def __init__(self, counter, guard, finite, ops, ends):
        self.items = []
        self.counter = counter      # [int]: unique names across every path
        self.guard = list(guard)    # names to check finite before writing
        self.finite = set(finite)   # names known (or checked) finite here
        self.ops = dict(ops)        # {"flops", "divs"} on this path so far
        self.ends = ends            # the ops of every finished path
        self.neg_of = {}            # {-x's name: x's name}, shared by the forks

    def fork(self):
        t = _Tracer(self.counter, self.guard, self.finite, self.ops, self.ends)
        t.neg_of = self.neg_of
        return t

    def name(self, stem="s"):
        self.counter[0] += 1
        return f"{stem}{self.counter[0]}"

    def let(self, expr, mnz=True, flops=None, divs=0):
        """A local of expr; flops None: its + - * and negations, counted in
        the text (a structural zero's product, "(x * 0)", is executed too)."""
        n = self.name()
        self.items.append(f"const gen_rt_real {n} = {expr};")
        if flops is None:
            flops = (sum(expr.count(f" {o} ") for o in "*+-") + expr.startswith("-")
                     + expr.count("(-") - expr.count("(-1)") - expr.count("(-(gen_rt_real)0)"))
        self.ops["flops"] += flops
        self.ops["divs"] += divs
        return _V(n, mnz=mnz)

    def promise_finite(self, *vals):
        """Folding relied on these being finite: checked before writing."""
        for v in vals:
            if v.lit is None and not v.zero and v.t not in self.finite:
                self.guard.append(v.t)
                self.finite.add(v.t)

    def zero(self, text, *factors):
        self.promise_finite(*factors)
        return _V(f"({text})", zero=True)

    # ------------------------------------------------------ arithmetic
    def mul(self, x, y):
        if x.lit == 1.0:
            return y
        if y.lit == 1.0:
            return x
        if x.is_zero or y.is_zero:
            if x.lit is not None and y.lit is not None:
                return _lit(x.lit * y.lit)
            return self.zero(f"{x.t} * {y.t}", x, y)
        return self.let(f"{x.t} * {y.t}")

    def div(self, x, y):
        if x.is_zero:
            # y is a pivot: nonzero, not NaN (|y| passed its tolerance)
            return self.zero(f"{x.t} / {y.t}", x)
        return self.let(f"{x.t} / {y.t}", flops=0, divs=1)

    def neg(self, x):
        if x.lit is not None:
            return _lit(-x.lit)
        if x.zero:
            return _V(f"(-{x.t})", zero=True)
        v = self.let(f"-{x.t}")
        if x.t in self.finite:            # -x is finite where x is: no test of its own
            self.finite.add(v.t)
        self.neg_of[v.t] = x.t            # |-x| is |x| (max_abs)
        return v

    def add(self, x, y):
        if y.is_zero and not x.mnz:
            return x                                  # x + (+-0), x not -0
        if x.is_zero and not y.mnz:
            return y
        if x.lit == 0.0 and y.lit == 0.0:             # two zeros: -0 only if both are
            return _lit(-0.0) if x.mnz and y.mnz else _lit(0.0)
        plus0 = x.lit == 0.0 and not x.mnz            # +0 + y is never -0
        return self.let(f"{x.t} + {y.t}", mnz=not plus0 and x.mnz and y.mnz)

    def sub(self, x, y):
        if y.lit == 0.0 and not y.mnz:
            return x                                  # x - (+0) is x, -0 included
        if y.is_zero and not x.mnz:
            return x
        # x - y is -0 only when x is -0 and y is +0
        return self.let(f"{x.t} - {y.t}", mnz=x.mnz and not (y.lit not in (None, 0.0)))

    def select(self, test, new, old):
        """The runtime's `if (test != 0) value = new` where test is only
        known at run time."""
        if new is old:
            return old
        return self.let(f"{test.t} != 0 ? {new.t} : {old.t}", mnz=old.mnz or new.mnz, flops=0)

    def guarded(self, coef, old, b, new):
        """new = old +- coef * b under `if (coef != 0)`: new where coef is
        nonzero for sure, old where it is zero, new as well where coef = +-0
        leaves it old (b finite, old not -0), else a select."""
        if coef.lit is not None or new is old:
            return new
        if not old.mnz:
            self.promise_finite(b)
            return new
        return self.select(coef, new, old)

    def sub_update(self, coef, old, b):
        """`if (coef != 0) old -= coef * b` (the LU's updates)."""
        if coef.is_zero:
            return old
        return self.guarded(coef, old, b, self.sub(old, self.mul(coef, b)))

    def add_update(self, coef, acc, b):
        """`if (coef != 0) acc += coef * b` (gen_rt_matmul)."""
        if coef.is_zero:
            return acc
        return self.guarded(coef, acc, b, self.add(acc, self.mul(coef, b)))

    def abs_(self, x):
        """|x| (the runtime's x < 0 ? -x : x, which keeps -0 where fabs
        gives +0): only compared, where -0 and +0 are equal, so fabs, one
        instruction where the select is four (c_lines: fabsf in float)."""
        if x.lit is not None:
            return _lit(abs(x.lit))
        return self.let(f"fabs({x.t})", mnz=False, flops=0)

    def check_finite(self, vals):
        """The runtime's all-finite tests (of M, f, A and a before its solve:
        NONFINITE_MODEL; of a solution: SINGULAR), deferred to the path's one
        test before it writes (end): the status is nonzero either way and
        nothing is written before it, while a branch in the middle waits for
        the slowest value it tests (the kernel's longest chain: a third of
        the seed's Kane model's time with clang)."""
        self.promise_finite(*vals)

    def max_abs(self, vals):
        """gen_rt_max_abs: from 0, the largest |v| (a zero never is)."""
        m = _lit(0.0)
        seen = set()
        for v in vals:
            if v.is_zero:
                continue
            base = self.neg_of.get(v.t, v.t)   # x and -x (K's A and -A^T): once
            if v.lit is None and base in seen:
                continue
            seen.add(base)
            if v.lit is not None:                     # a literal 1 or -1: |v| = 1
                m = (_lit(1.0) if m.lit == 0.0
                     else self.let(f"1 > {m.t} ? 1 : {m.t}", mnz=False, flops=0))
                continue
            a = self.abs_(v)
            m = a if m.lit == 0.0 else self.let(f"{a.t} > {m.t} ? {a.t} : {m.t}", mnz=False,
                                                  flops=0)
        return m

    def end(self, ud, out):
        """A path's end: the promised finite values checked, u' written."""
        self.promise_finite(*ud)
        if self.guard:
            self.items.append(_finite_test(self.guard))
        for i, v in enumerate(ud):
            self.items.append(f"{out}[{i}] = {v.t};")
        self.items.append("return GEN_RT_OK;")
        self.ends.append(dict(self.ops))


def _finite_test(names):
    """x * 0 is 0 for finite x and NaN otherwise (no libm), and a sum is
    finite only where its terms are: one product for all of them. A finite
    sum that overflows fails too, and the runtime's general path then gives
    its own result (values near the type's largest; nothing else changes)."""
    return f"if (!(({' + '.join(names)}) * 0 == 0)) {FAIL}"


# ---------------------------------------------------------------- LU
def _lu(tr, n, a, scale, cont, paths):
    """gen_rt_lu_factor(n, a, piv, scale), traced: a is n rows of values;
    scale None is the runtime's scale 0 (max |a_ij|). cont(tracer, lu,
    piv) continues each pivot path."""
    if n == 0:
        return cont(tr, a, [])
    if scale is None:
        scale = tr.max_abs([v for row in a for v in row])
    if scale.lit is not None and not scale.lit > 0:
        tr.items.append(FAIL)
        return
    if scale.lit is None:
        tr.items.append(f"if (!({scale.t} > 0)) {FAIL}")
    tol = tr.let(f"GEN_RT_PIVOT_RTOL * {scale.t}", mnz=False)
    _lu_step(tr, n, [list(r) for r in a], [], 0, tol, cont, paths)


def _lu_step(tr, n, a, piv, k, tol, cont, paths):
    if k == n:
        return cont(tr, a, piv)
    cands = [i for i in range(k + 1, n) if not a[i][k].is_zero]
    choices = ([] if a[k][k].is_zero else [k]) + cands
    if not choices:
        tr.items.append(FAIL)                       # a zero column: singular
        return
    if len(choices) == 1:
        c = a[choices[0]][k]
        b = _V("1", 1.0, mnz=False) if c.lit is not None else tr.abs_(c)
        tr.items.append(f"if (!({b.t} > {tol.t})) {FAIL}")
        return _lu_pivot(tr, n, a, piv, k, choices[0], tol, cont, paths)
    # the runtime's search: |a_kk|, then each later row with a larger |a_ik|
    best, p = tr.name("sb"), tr.name("sp")
    init = "0" if a[k][k].is_zero else tr.abs_(a[k][k]).t
    tr.items += [f"gen_rt_real {best} = {init};", f"int {p} = {k};"]
    for i in cands:
        v = tr.abs_(a[i][k])
        tr.items.append(f"if ({v.t} > {best}) {{ {best} = {v.t}; {p} = {i}; }}")
    tr.items.append(f"if (!({best} > {tol.t})) {FAIL}")
    paths[0] += len(choices) - 1
    if paths[0] > SMALL_MAX_PATHS:
        raise _TooLarge
    blocks = []
    for choice in choices:
        sub = tr.fork()
        _lu_pivot(sub, n, a, piv, k, choice, tol, cont, paths)
        blocks.append((choice, sub.items))
    node = blocks[-1][1]
    for choice, items in reversed(blocks[:-1]):
        node = [("if", f"{p} == {choice}", items, node)]
    tr.items += node


def _lu_pivot(tr, n, a, piv, k, p, tol, cont, paths):
    a = [list(r) for r in a]
    a[k], a[p] = a[p], a[k]
    for i in range(k + 1, n):
        lik = tr.div(a[i][k], a[k][k])
        a[i][k] = lik
        for j in range(k + 1, n):
            a[i][j] = tr.sub_update(lik, a[i][j], a[k][j])
    _lu_step(tr, n, a, piv + [p], k + 1, tol, cont, paths)


def _lu_solve(tr, n, lu, piv, b):
    """gen_rt_lu_solve(n, lu, piv, nrhs, b), traced (b: n rows)."""
    b = [list(r) for r in b]
    for k in range(n):
        b[k], b[piv[k]] = b[piv[k]], b[k]
    for i in range(n):
        for k in range(i):
            for j in range(len(b[i])):
                b[i][j] = tr.sub_update(lu[i][k], b[i][j], b[k][j])
    for i in reversed(range(n)):
        for k in range(i + 1, n):
            for j in range(len(b[i])):
                b[i][j] = tr.sub_update(lu[i][k], b[i][j], b[k][j])
        for j in range(len(b[i])):
            b[i][j] = tr.div(b[i][j], lu[i][i])
    return b


# ----------------------------------------------------------- the solves
def _kkt(tr, n, m, M, f, A, a, out, paths):
    """gen_rt_accel_kkt: K = [M, -A^T; A, 0], z = [f; -a], K z' = z."""
    N = n + m
    K = [[M[i * n + j] if i < n and j < n else tr.neg(A[(j - n) * n + i]) if i < n
          else A[(i - n) * n + j] if j < n else _lit(0.0) for j in range(N)] for i in range(N)]
    z = [[f[i]] for i in range(n)] + [[tr.neg(a[i])] for i in range(m)]

    def solved(t, lu, piv):
        x = [row[0] for row in _lu_solve(t, N, lu, piv, z)]
        t.check_finite(x)
        t.end(x[:n], out)

    _lu(tr, N, K, None, solved, paths)


def _partitioned(tr, n, m, ind, dep, M, f, A, a, out, paths):
    """gen_rt_accel_partitioned: C = -Ad^-1 [A_i | a] (the dependent
    speeds' solve), T and cf, (T^T M T) ui' = T^T (f - M cf), u' = T ui' + cf."""
    ni = n - m
    Ad = [[A[i * n + dep[j]] for j in range(m)] for i in range(m)]
    C = [[tr.neg(A[i * n + ind[k]]) for k in range(ni)] + [tr.neg(a[i])] for i in range(m)]
    zero, one = _lit(0.0), _lit(1.0)

    def reduced(t, lu, piv):
        c = _lu_solve(t, m, lu, piv, C)
        t.check_finite([v for row in c for v in row])
        for row in c:
            for v in row[:ni]:
                if v.lit is None and not v.zero:
                    t.items.append(f"if ({v.t} > GEN_RT_PARTITION_CMAX || "
                                   f"{v.t} < -GEN_RT_PARTITION_CMAX) {FAIL}")
        T = [[zero] * ni for _ in range(n)]
        cf = [zero] * n
        for k in range(ni):
            T[ind[k]][k] = one
        for j in range(m):
            T[dep[j]] = list(c[j][:ni])
            cf[dep[j]] = c[j][ni]
        MT = [[zero] * ni for _ in range(n)]
        for i in range(n):
            for q in range(n):
                for j in range(ni):
                    MT[i][j] = t.add_update(M[i * n + q], MT[i][j], T[q][j])
        Mr = [[zero] * ni for _ in range(ni)]
        for i in range(ni):
            for j in range(ni):
                for k in range(n):
                    Mr[i][j] = t.add(Mr[i][j], t.mul(T[k][i], MT[k][j]))
        tmp = [zero] * n
        for i in range(n):
            for q in range(n):
                tmp[i] = t.add_update(M[i * n + q], tmp[i], cf[q])
        tmp = [t.sub(f[k], tmp[k]) for k in range(n)]
        fr = [[zero] for _ in range(ni)]
        for i in range(ni):
            for k in range(n):
                fr[i][0] = t.add(fr[i][0], t.mul(T[k][i], tmp[k]))

        def solved(t2, lu2, piv2):
            x = [row[0] for row in _lu_solve(t2, ni, lu2, piv2, fr)]
            ud = []
            for k in range(n):
                acc = zero
                for q in range(ni):
                    acc = t2.add_update(T[k][q], acc, x[q])
                ud.append(t2.add(acc, cf[k]))
            t2.check_finite(ud)
            t2.end(ud, out)

        _lu(t, ni, Mr, None, solved, paths)

    _lu(tr, m, Ad, tr.max_abs(A), reduced, paths)


def accel_program(method, n, m, M, f, A, a, ind=(), dep=(), out="out_ud", inputs=()):
    """The straight-line solve of u' by the runtime's method ("partitioned"
    or "kkt"), or None when the model is too large (SMALL_MAX_SIZE,
    SMALL_MAX_PATHS). M (n * n, row-major), f (n), A (m * n), a (m): each
    entry the C name of the local holding it, or the number 0 or 1 when the
    model's entry is that literal. The program first checks the entries
    finite (the runtime's NONFINITE_MODEL test before its solve), writes u'
    to out[0..n-1] and returns GEN_RT_OK, or returns a failure before
    writing anything. inputs: C names of the caller's inputs, tested finite
    with the values before anything is written (the caller may then test
    its inputs only when the program fails)."""
    if method not in ("partitioned", "kkt"):
        raise ValueError(f"method must be 'partitioned' or 'kkt', got {method!r}")
    if m < 1 or (n + m if method == "kkt" else n) > SMALL_MAX_SIZE:
        return None
    vals = [_lit(v) if isinstance(v, (int, float)) else _V(v) for v in [*M, *f, *A, *a]]
    Mv, fv = vals[:n * n], vals[n * n:n * n + n]
    Av, av = vals[n * n + n:n * n + n + m * n], vals[n * n + n + m * n:]
    ends = []
    # (the inputs first in every path's test: known first, off its critical path)
    tr = _Tracer([0], list(inputs), [], {"flops": 0, "divs": 0}, ends)
    # the runtime's test of M, f, A and a before its solve; in the KKT system
    # f and -a are the right-hand side, each of which its own unknown's
    # substitutions only update (never drop), so a value that is not finite
    # there reaches the solution, which is tested: they need no test of their own
    tr.check_finite([*Mv, *Av] if method == "kkt" else vals)
    paths = [1]
    try:
        if method == "kkt":
            _kkt(tr, n, m, Mv, fv, Av, av, out, paths)
        else:
            _partitioned(tr, n, m, list(ind), list(dep), Mv, fv, Av, av, out, paths)
    except _TooLarge:
        return None
    return Program(_drop_unused(tr.items), paths[0], max((e["flops"] for e in ends), default=0),
                   max((e["divs"] for e in ends), default=0))


_DECL = re.compile(r"^const gen_rt_real (\w+) = ")
_WORD = re.compile(r"\b[A-Za-z_]\w*\b")


def _drop_unused(items):
    """Without the locals nothing reads (a product folded away after it was
    formed): unused, they would trip -Wunused-variable."""
    while True:
        uses = {}

        def count(its):
            for it in its:
                if isinstance(it, str):
                    m = _DECL.match(it)
                    for w in _WORD.findall(it[m.end():] if m else it):
                        uses[w] = uses.get(w, 0) + 1
                else:
                    for w in _WORD.findall(it[1]):
                        uses[w] = uses.get(w, 0) + 1
                    count(it[2])
                    count(it[3])

        count(items)

        def keep(its):
            out, dropped = [], 0
            for it in its:
                if isinstance(it, str):
                    m = _DECL.match(it)
                    if m and not uses.get(m.group(1)):
                        dropped += 1
                        continue
                    out.append(it)
                else:
                    a, da = keep(it[2])
                    b, db = keep(it[3])
                    out.append((it[0], it[1], a, b))
                    dropped += da + db
            return out, dropped

        items, dropped = keep(items)
        if not dropped:
            return items


def c_lines(prog, indent="    ", real="gen_rt_real"):
    """The program as lines of C, its blocks nested in braces; real: the
    scalar type's name."""
    out = []

    def walk(items, ind):
        for it in items:
            if isinstance(it, str):
                it = it.replace("gen_rt_real", real)
                out.append(ind + (it.replace("fabs(", "fabsf(") if real == "float" else it))
                continue
            _, cond, then, other = it
            out.append(f"{ind}if ({cond}) {{")
            walk(then, ind + "    ")
            out.append(f"{ind}}} else {{")
            walk(other, ind + "    ")
            out.append(f"{ind}}}")

    walk(prog.items, indent)
    return out


def kernel_program(kernel, method, n, m, ind=(), dep=(), inputs=()):
    """accel_program over a right-hand-side kernel's outputs M, f, A and a
    as the fused kernel binds them (the locals BIND[name]<k>; an entry
    whose expression is the number 0 or 1 as that literal), or None when
    the model is too large for it or its kernel lacks one of them."""
    outs = {o.name: o.exprs for o in kernel.outputs}
    if any(k not in outs for k in BIND):
        return None

    def entries(name):
        return [0 if e == 0 else 1 if e == 1 else f"{BIND[name]}{k}"
                for k, e in enumerate(outs[name])]

    return accel_program(method, n, m, entries("M"), entries("f"), entries("A"),
                         entries("a"), ind=ind, dep=dep, inputs=inputs)
