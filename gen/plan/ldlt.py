"""Model-specific straight-line solvers: what to emit, as data.

``ldlt_program`` plans an unrolled LDL^T factorization and solve of a
symmetric positive definite n x n matrix (the mass matrix of an
unconstrained model) for one right-hand side. The structural zeros of the
matrix (known at generation time) are skipped, and so is the fill-in they
spare, so a banded or block-diagonal mass matrix costs what its pattern
costs. ``ldlt_statements`` spells the plan out as straight-line
assignments (name, expression), and the template
``templates/c/mass_solve.j2`` declares them and writes the pivot test:
sizes are literals, no loops, no work arrays.

The statements are written for a short dependency chain, which is what
bounds the solve at small n (the divisions of the pivots follow each
other): column j keeps the unscaled entries c_ij = M_ij - sum_k c_ik l_jk
(= l_ij d_j) and scales them once, l_ij = c_ij / d_j, so no product
l_ik d_k is formed; the pivot d_j = M_jj - sum_k c_jk^2 / d_k waits for
the last reciprocal through one product and one difference; every sum
ends with its latest term (the nearest column; the nearest row of the
back substitution). The pivots are tested once, after the solve: a failed
pivot leaves inf or NaN in locals, which are then not written out.
"""
from __future__ import annotations

import re

__all__ = ["ldlt_pattern", "ldlt_program", "ldlt_statements", "demand_order", "LDLT_LOOP_MIN",
           "ldlt_work_index"]

# a dense mass matrix of at least this many speeds is solved by the
# runtime's LDL^T in loops (csrc/gen_rt_ldlt.h: the same operations in the
# same order, so the same bits), not unrolled: the unrolled solve is n^3/3
# statements, and from about here on the loops, vectorized four rows at a
# time, are faster with both compilers and compile faster (cart, eval_rhs,
# AVX clone, loops / unrolled: clang nu = 17: 1.00, 21: 0.86, 25: 0.69,
# 33: 0.56; gcc nu = 21: 1.13, 25: 1.00, 33: 0.82; the 32-link cart's
# kernels compile in 5.0 s instead of 8.1 with clang)
LDLT_LOOP_MIN = 24


def ldlt_work_index(n, i, j=None):
    """Where the looped solve (csrc/gen_rt_ldlt.h) reads M_ij (i >= j) in
    its work array (GEN_RT_LDLT_M, GEN_RT_LDLT_D), or f_i when j is None
    (GEN_RT_LDLT_F)."""
    ld = (n + 3) // 4 * 4
    if j is None:
        return ld * ld + 2 * n + i
    if i == j:
        return ld * ld + j
    if i < j:
        raise ValueError(f"M_{i}{j}: the solve reads the lower triangle")
    return j * ld + i


def ldlt_pattern(nonzero):
    """Structural pattern of L (strictly lower) for a symmetric matrix with
    the given pattern (nonzero[i][j] for i > j), fill-in included."""
    n = len(nonzero)
    L = [[False] * n for _ in range(n)]
    for j in range(n):
        for i in range(j + 1, n):
            nz = bool(nonzero[i][j]) or bool(nonzero[j][i])
            if not nz:
                nz = any(L[i][k] and L[j][k] for k in range(j))
            L[i][j] = nz
    return L


def ldlt_program(n, nonzero):
    """The unrolled solve as plain data for the template:
    loop: M is dense (no structural zero in L) and n >= LDLT_LOOP_MIN: the
          template calls the runtime's solve in loops instead (the same
          operations, in the same order, as the statements of this plan);
    dense: L has no structural zero (the loops would be exact at any n);
    diag: row-major indices of M's diagonal after the first (the pivot scale);
    cols: per column j, the k with l_jk != 0 (ks), the index of M_jj (d), and
          its rows i > j with l_ij != 0: the index of M_ij or None (base) and
          the k with l_ik l_jk != 0 (ks);
    forward: per row i, the k < i with l_ik != 0 (L y = f);
    backward: per row i, last to first, the k > i with l_ki != 0 (L^T x = D^-1 y),
          nearest last (the latest value ends the sum: a shorter chain)."""
    L = ldlt_pattern(nonzero)
    dense = all(L[i][j] for i in range(n) for j in range(i))
    cols = []
    for j in range(n):
        rows = []
        for i in range(j + 1, n):
            if not L[i][j]:
                continue
            base = i * n + j if nonzero[i][j] or nonzero[j][i] else None
            rows.append({"i": i, "base": base,
                         "ks": [k for k in range(j) if L[i][k] and L[j][k]]})
        cols.append({"j": j, "d": j * n + j, "ks": [k for k in range(j) if L[j][k]],
                     "rows": rows})
    return {
        "n": n,
        # solved in loops by the runtime (gen_rt_ldlt_dense), not unrolled
        "loop": dense and n >= LDLT_LOOP_MIN,
        # L has no structural zero (the loops then do the same operations)
        "dense": dense,
        "diag": [i * n + i for i in range(1, n)],
        "cols": cols,
        "forward": [{"i": i, "ks": [k for k in range(i) if L[i][k]]} for i in range(n)],
        "backward": [{"i": i, "ks": [k for k in reversed(range(i + 1, n)) if L[k][i]]}
                     for i in reversed(range(n))],
    }


def ldlt_statements(s, M=lambda i: f"M[{i}]", f=lambda i: f"f[{i}]"):
    """The solve of plan s (ldlt_program) as straight-line assignments
    [(name, expression)], in the plan's order: per column the pivot d<j>,
    its reciprocal id<j> and the entries c<i>_<j>, l<i>_<j>; then y<i>
    (L y = f) and z<i> (the solution). M(i) and f(i) give the text that
    reads M's row-major entry i and f's entry i. The templates declare them
    (templates/c/mass_solve.j2: ldlt_decl)."""
    out = []
    for c in s["cols"]:
        j = c["j"]
        out.append((f"d{j}", M(c["d"]) + "".join(f" - c{j}_{k} * c{j}_{k} * id{k}"
                                                  for k in c["ks"])))
        out.append((f"id{j}", f"1 / d{j}"))
        for r in c["rows"]:
            i = r["i"]
            terms = [f"c{i}_{k} * l{j}_{k}" for k in r["ks"]]
            base = M(r["base"]) if r["base"] is not None else None
            if base is None:
                expr = "-" + " - ".join(terms)          # fill-in: no entry of M
            else:
                expr = base + "".join(f" - {t}" for t in terms)
            out.append((f"c{i}_{j}", expr))
            out.append((f"l{i}_{j}", f"c{i}_{j} * id{j}"))
    for r in s["forward"]:
        i = r["i"]
        out.append((f"y{i}", f(i) + "".join(f" - l{i}_{k} * y{k}" for k in r["ks"])))
    for r in s["backward"]:
        i = r["i"]
        out.append((f"z{i}", f"y{i} * id{i}" + "".join(f" - l{k}_{i} * z{k}" for k in r["ks"])))
    return out


_NAME = re.compile(r"[A-Za-z_]\w*")


def demand_order(spine, temps):
    """Straight-line statements in one order: the items of spine, in their
    order (lines, or (name, expression) statements such as ldlt_statements
    gives), each preceded by the temporaries it reads that are not yet
    written (and theirs); then the temporaries nothing in the spine read,
    in their own order. temps: [(name, line, reads)] in a valid order
    (reads: the names the temporary's expression reads). So the fused
    right-hand side computes M's entries, and the trigonometric calls
    behind them, where the solve first needs them, in its columns' order,
    and the processor overlaps the solve's chain of divisions with them.
    Returns the temporaries' lines and the spine's items. Iterative
    (kernels have chains of thousands)."""
    info = {n: (i, t, rd) for i, (n, t, rd) in enumerate(temps)}
    done, out = set(), []

    def need(names):
        stack = [(n, False) for n in sorted((n for n in names if n in info and n not in done),
                                            key=lambda n: -info[n][0])]
        while stack:
            n, ready = stack.pop()
            if n in done:
                continue
            if ready:
                done.add(n)
                out.append(info[n][1])
                continue
            stack.append((n, True))
            stack.extend((d, False) for d in sorted(
                (d for d in info[n][2] if d in info and d not in done),
                key=lambda d: -info[d][0]))

    for item in spine:
        need(_NAME.findall(item if isinstance(item, str) else " ".join(item)))
        out.append(item)
    need([n for n, _, _ in temps])
    return out
