"""Model-specific straight-line solvers, emitted as C.

``ldlt_solve_c`` writes an unrolled LDL^T factorization and solve of a
symmetric positive definite n x n matrix (the mass matrix of an
unconstrained model) for one right-hand side. The structural zeros of the
matrix (known at generation time) are skipped, and so is the fill-in they
spare, so a banded or block-diagonal mass matrix costs what its pattern
costs. Sizes are literals: no loops, no work arrays, nothing for the
compiler to guess.
"""
from __future__ import annotations

__all__ = ["ldlt_pattern", "ldlt_solve_c"]


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


def ldlt_solve_c(prefix, n, nonzero, real, rtol_macro="GEN_RT_PIVOT_RTOL"):
    """C99 source of

        static int <prefix>_mass_solve(const real *M, const real *f, real *x)

    solving M x = f for a symmetric positive definite M (row-major; only the
    lower triangle and the diagonal are read). Returns GEN_RT_ERR_SINGULAR
    when a pivot is not positive relative to the largest diagonal entry
    (also for NaN); x is written only on success."""
    L = ldlt_pattern(nonzero)
    R = real
    out = [f"static int {prefix}_mass_solve(const {R} *M, const {R} *f, {R} *x)", "{"]
    # tolerance relative to the largest diagonal entry (all positive for SPD)
    out.append(f"    {R} dmax = M[0];")
    for i in range(1, n):
        out.append(f"    if (M[{i * n + i}] > dmax) dmax = M[{i * n + i}];")
    out.append(f"    const {R} tol = {rtol_macro} * dmax;")
    out.append("    if (!(dmax > 0)) return GEN_RT_ERR_SINGULAR;")
    # factorization: d_j, l_i_j (unit lower), v_k = l_j_k * d_k reused
    for j in range(n):
        terms = [f"l{j}_{k} * v{j}_{k}" for k in range(j) if L[j][k]]
        for k in range(j):
            if L[j][k]:
                out.append(f"    const {R} v{j}_{k} = l{j}_{k} * d{k};")
        expr = f"M[{j * n + j}]" + "".join(f" - {t}" for t in terms)
        out.append(f"    const {R} d{j} = {expr};")
        out.append(f"    if (!(d{j} > tol)) return GEN_RT_ERR_SINGULAR;")
        out.append(f"    const {R} id{j} = 1 / d{j};")
        for i in range(j + 1, n):
            if not L[i][j]:
                continue
            acc = [f"l{i}_{k} * v{j}_{k}" for k in range(j) if L[i][k] and L[j][k]]
            base = f"M[{i * n + j}]" if nonzero[i][j] or nonzero[j][i] else "0"
            expr = base + "".join(f" - {t}" for t in acc)
            out.append(f"    const {R} l{i}_{j} = ({expr}) * id{j};")
    # forward: L y = f
    for i in range(n):
        expr = f"f[{i}]" + "".join(f" - l{i}_{k} * y{k}" for k in range(i) if L[i][k])
        out.append(f"    const {R} y{i} = {expr};")
    # diagonal and backward: L^T x = D^-1 y
    for i in reversed(range(n)):
        expr = f"y{i} * id{i}" + "".join(f" - l{k}_{i} * z{k}" for k in range(i + 1, n)
                                          if L[k][i])
        out.append(f"    const {R} z{i} = {expr};")
    for i in range(n):
        out.append(f"    x[{i}] = z{i};")
    out.append("    return GEN_RT_OK;")
    out.append("}")
    return "\n".join(out) + "\n"
