"""Model-specific straight-line solvers: what to emit, as data.

``ldlt_program`` plans an unrolled LDL^T factorization and solve of a
symmetric positive definite n x n matrix (the mass matrix of an
unconstrained model) for one right-hand side. The structural zeros of the
matrix (known at generation time) are skipped, and so is the fill-in they
spare, so a banded or block-diagonal mass matrix costs what its pattern
costs. The C is written by the template ``templates/c/mass_solve.j2`` from
this plan: sizes are literals, no loops, no work arrays.
"""
from __future__ import annotations

__all__ = ["ldlt_pattern", "ldlt_program", "ldlt_solve_c"]


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
    diag: row-major indices of M's diagonal after the first (the pivot scale);
    cols: per column j, the k with l_jk != 0 (ks), the index of M_jj (d), and
          its rows i > j with l_ij != 0: the index of M_ij or None (base) and
          the k with l_ik l_jk != 0 (ks);
    forward: per row i, the k < i with l_ik != 0 (L y = f);
    backward: per row i, last to first, the k > i with l_ki != 0 (L^T x = D^-1 y),
          nearest last (the latest value ends the sum: a shorter chain)."""
    L = ldlt_pattern(nonzero)
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
        "diag": [i * n + i for i in range(1, n)],
        "cols": cols,
        "forward": [{"i": i, "ks": [k for k in range(i) if L[i][k]]} for i in range(n)],
        "backward": [{"i": i, "ks": [k for k in reversed(range(i + 1, n)) if L[k][i]]}
                     for i in reversed(range(n))],
    }


def ldlt_solve_c(prefix, n, nonzero, real, rtol_macro="GEN_RT_PIVOT_RTOL"):
    """C99 source of

        static int <prefix>_mass_solve(const real *M, const real *f, real *x)

    solving M x = f for a symmetric positive definite M (row-major; only the
    lower triangle and the diagonal are read). Returns GEN_RT_ERR_SINGULAR
    when a pivot is not positive relative to the largest diagonal entry
    (also for NaN); x is written only on success. Rendered from the
    template the generated models use."""
    from .render import template_env
    macro = template_env().get_template("c/mass_solve.j2").module.mass_solve
    return str(macro(prefix, real, ldlt_program(n, nonzero), rtol_macro))
