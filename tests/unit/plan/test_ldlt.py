"""The generated straight-line LDL^T solve and the constant-collection
pass (issue 7: generated code near the floor), against numpy and sympy."""
import subprocess
from types import SimpleNamespace

import numpy as np
import pytest
import sympy as sm

import gen
import n_link_cart
from gen.plan.ir import collect_constants, mass_structure
from gen.plan.ldlt import ldlt_pattern
from helpers import ldlt_solve_c, rel_err

HEAD = ("#include <math.h>\n#include <stdio.h>\n#define GEN_RT_OK 0\n"
        "#define GEN_RT_ERR_SINGULAR (-3)\n")
RTOL = {"double": "#define GEN_RT_PIVOT_RTOL 1e-12\n",
        "float": "#define GEN_RT_PIVOT_RTOL 1e-6F\n"}


def _run(tmp_path, M, f, real="double"):
    n = len(f)
    nz = [[M[i][j] != 0 for j in range(n)] for i in range(n)]
    body = ldlt_solve_c("t", n, nz, real)
    vals = lambda a: ",".join("NAN" if np.isnan(v) else repr(float(v))  # noqa: E731
                              for v in np.ravel(a))
    src = HEAD + RTOL[real] + body + (
        f"int main(void) {{ {real} M[{n * n}] = {{{vals(M)}}}; {real} f[{n}] = {{{vals(f)}}};\n"
        f"  {real} x[{n}]; int i, st = t_mass_solve(M, f, x); printf(\"%d\\n\", st);\n"
        f"  if (!st) for (i = 0; i < {n}; ++i) printf(\"%.17g\\n\", (double)x[i]);\n"
        "  return 0; }\n")
    (tmp_path / "t.c").write_text(src)
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic",
                    "-Wdouble-promotion", "-O2", str(tmp_path / "t.c"), "-o",
                    str(tmp_path / "t")], check=True)
    out = subprocess.run([str(tmp_path / "t")], capture_output=True, text=True).stdout.split()
    return int(out[0]), np.array(out[1:], dtype=float)


@pytest.mark.parametrize("shape", ["dense1", "dense6", "dense12", "tridiagonal", "blocks"])
def test_ldlt_against_numpy(tmp_path, shape):
    rng = np.random.default_rng(len(shape))
    n = {"dense1": 1, "dense6": 6, "dense12": 12}.get(shape, 9)
    B = rng.normal(size=(n, n))
    M = B @ B.T + 0.1 * np.eye(n)
    if shape == "tridiagonal":
        M[np.abs(np.subtract.outer(range(n), range(n))) > 1] = 0
        M += 3 * np.eye(n)
    if shape == "blocks":
        mask = np.kron(np.eye(3), np.ones((3, 3))) > 0
        M = np.where(mask, M, 0) + 3 * np.eye(n)
    f = rng.normal(size=n)
    st, x = _run(tmp_path, M, f)
    assert st == 0
    assert rel_err(x, np.linalg.solve(M, f)) < 1e-12 * np.linalg.cond(M)


def test_ldlt_skips_structural_zeros():
    n = 8
    tri = [[abs(i - j) <= 1 for j in range(n)] for i in range(n)]
    L = ldlt_pattern(tri)
    assert sum(map(sum, L)) == n - 1            # no fill-in for a band
    arrow = [[i == j or i == n - 1 or j == n - 1 for j in range(n)] for i in range(n)]
    assert sum(map(sum, ldlt_pattern(arrow))) == n - 1
    text = ldlt_solve_c("t", n, tri, "double")
    assert text.count("const double l") == n - 1


def test_ldlt_refuses_indefinite_singular_and_nan(tmp_path):
    M = np.array([[1.0, 2.0], [2.0, 1.0]])      # indefinite
    assert _run(tmp_path, M, [1.0, 1.0])[0] == -3
    M = np.array([[1.0, 1.0], [1.0, 1.0]])      # singular
    assert _run(tmp_path, M, [1.0, 1.0])[0] == -3
    M = np.array([[float("nan"), 0.0], [0.0, 1.0]])
    assert _run(tmp_path, M, [1.0, 1.0])[0] == -3


def test_ldlt_float(tmp_path):
    rng = np.random.default_rng(3)
    B = rng.normal(size=(5, 5))
    M = B @ B.T + np.eye(5)
    f = rng.normal(size=5)
    st, x = _run(tmp_path, M, f, real="float")
    assert st == 0 and rel_err(x, np.linalg.solve(M, f)) < 1e-4


def test_collect_constants_keeps_values_and_saves_operations():
    model = n_link_cart.model(4)
    variables = set(model.q) | set(model.u) | set(model.r) | {model.t}
    F = collect_constants(model.f, variables)
    rng = np.random.default_rng(1)
    vals = {s: sm.Float(rng.uniform(-1, 1), 30) for s in model.f.free_symbols}
    a = np.array(model.f.xreplace(vals).evalf(30), dtype=float)
    b = np.array(F.xreplace(vals).evalf(30), dtype=float)
    assert rel_err(b, a) < 1e-14
    ops = lambda mat: sum(sm.count_ops(e) for e in mat)  # noqa: E731
    assert ops(F) < 0.8 * ops(model.f)


def test_mass_structure():
    model = n_link_cart.model(2)
    sym, nz = mass_structure(model)
    assert sym and all(all(r) for r in nz)      # dense and symmetric
    x, y = sm.symbols("x y")
    fake = SimpleNamespace(M=sm.Matrix([[1 + x**2, x], [y, 2]]))
    assert mass_structure(fake)[0] is False
    fake = SimpleNamespace(M=sm.Matrix([[1, sm.sin(x)**2 + sm.cos(x)**2], [1, 2]]))
    assert mass_structure(fake)[0] is True      # equal values, different expressions


def test_generated_singular_mass_matrix_raises():
    vals = {f"m{i}": 0.0 for i in range(3)}
    sim = gen.compile(n_link_cart.model(2, name="cart2_massless", **vals))
    with pytest.raises(gen.SingularError, match="singular"):
        sim.rhs(0.0, np.full(sim.nx, 0.1))


def test_demand_order_defines_before_use():
    """The fused kernel's order (gen.plan.ldlt.demand_order): each temporary
    right before the first spine line that reads it, its own reads first,
    the unread ones after the spine in their order; a chain of 5000 (the
    size of a large kernel) without recursion."""
    from gen.plan.ldlt import demand_order
    temps = [("a", "A", set()), ("b", "B", {"a", "q"}), ("c", "C", {"b"}),
             ("d", "D", set()), ("e", "E", {"a", "d"})]
    out = demand_order(["S1 = c;", "S2 = a + e;"], temps)
    assert out == ["A", "B", "C", "S1 = c;", "D", "E", "S2 = a + e;"]
    out = demand_order(["S = a;"], temps)
    assert out == ["A", "S = a;", "B", "C", "D", "E"]
    n = 5000
    chain = [(f"w{i}", f"w{i}", {f"w{i - 1}"} if i else set()) for i in range(n)]
    out = demand_order([f"x = w{n - 1};"], chain)
    assert out == [f"w{i}" for i in range(n)] + [f"x = w{n - 1};"]
