"""Unit tests of the IR (gen/plan/ir.py), no compiler.

- Jacobians by forward differentiation of the CSE'd assignment list
  (differentiate_graph, make_jacobian_kernel) against sympy's
  Matrix.jacobian of the same expressions: exactly (the difference
  simplifies to zero) on small expressions with shared subexpressions,
  trig, powers and square roots, and at random points (30 digits) on the
  kernels of real models (the seed Kane pendulum's lin_terms blocks against
  the jacobians of its M, f, A, a, b, f_c; the same on a pendulum on a cart
  with an input);
- make_kernel with CSE on and off gives the same values;
- prune removes dead temporaries (and only those);
- collect_constants preserves values and groups constant coefficients.
"""
import random

import pytest
import sympy as sm

import n_link_cart
import seed_pendulum
from gen.plan import ir
from gen.plan.ir import Arg, Kernel, Output, collect_constants, make_jacobian_kernel, \
    make_kernel, prune
from gen.sym.graph import differentiate_graph

DIGITS = 30
TOL = sm.Float("1e-22", DIGITS)

x, y, z = sm.symbols("x y z")
r2 = x**2 + y**2
# expressions with shared subexpressions (x*y, x**2 + y**2, sin(x*y)),
# trig, integer and rational powers, square roots, a quotient
EXPRS = [
    sm.sin(x * y) + sm.sqrt(r2),
    sm.cos(x * y) * r2**3 - sm.sin(x * y)**2,
    sm.exp(sm.sin(x * y)) / z + y**-2,
    sm.atan2(y, x) * sm.sqrt(r2) + z**sm.Rational(3, 2),
    x * y * z + 7,
    sm.Integer(3),                       # constant: a zero row
    r2 / sm.sqrt(r2 + z**2),
]
WRT = [x, y, z]
POINT = {x: sm.Rational(3, 7), y: sm.Rational(-5, 4), z: sm.Rational(9, 5)}


# ------------------------------------------------------------------ helpers
def kernels_of(model):
    """{name: Kernel} of a model, whatever gen.plan.ir now calls the function
    (build_kernels, or a plan object with .kernels)."""
    for fname in ("plan", "build_plan", "make_plan", "build_kernels"):
        fn = getattr(ir, fname, None)
        if fn is not None:
            out = fn(model)
            out = getattr(out, "kernels", out)
            if isinstance(out, (list, tuple)):
                out = {k.name: k for k in out}
            return out
    pytest.fail("gen.plan.ir offers no build_kernels (or plan) function")


def inline(assignments, exprs):
    """exprs with every temporary of the (ordered) assignments substituted
    back: plain sympy expressions over the inputs."""
    env = {}
    for s, e in assignments:
        env[s] = e.xreplace(env)
    return [e.xreplace(env) for e in exprs]


def evaluate_kernel(kernel, values):
    """{output name: Matrix of Floats}: the kernel run straight-line, as C
    would, at DIGITS digits. values: {symbol: number} for every input."""
    env = {s: sm.Float(v, DIGITS) for s, v in values.items()}
    for s, e in kernel.assignments:
        env[s] = e.xreplace(env).evalf(DIGITS)
    out = {}
    for o in kernel.outputs:
        vals = [e.xreplace(env).evalf(DIGITS) for e in o.exprs]
        out[o.name] = sm.Matrix(o.rows, o.cols, vals)
    return out


def evaluate(mat, values):
    env = {s: sm.Float(v, DIGITS) for s, v in values.items()}
    return sm.Matrix(mat).xreplace(env).evalf(DIGITS)


def assert_close(a, b, what=""):
    a, b = sm.Matrix(a), sm.Matrix(b)
    assert a.shape == b.shape, (what, a.shape, b.shape)
    scale = max([abs(v) for v in b] + [sm.Float(1)])
    for i, (u, v) in enumerate(zip(a, b)):
        assert u.is_number and v.is_number, (what, i, u, v)
        assert abs(u - v) <= TOL * scale, (what, i, u, v)


def input_symbols(kernel):
    return [s for a in kernel.args for s in a.symbols]


def random_values(symbols, rng, lo=0.3, hi=1.3):
    """Exact rationals (three decimals) in [lo, hi]."""
    return {s: sm.Rational(rng.randint(round(lo * 1000), round(hi * 1000)), 1000)
            for s in symbols}


def cse_graph(exprs):
    k = make_kernel("g", [Arg("x", tuple(WRT))], [("e", sm.Matrix(exprs))])
    return k.assignments, k.outputs[0].exprs


# ------------------------------------------ differentiate_graph, exactly
def test_graph_jacobian_equals_sympy_jacobian_exactly():
    assignments, reduced = cse_graph(EXPRS)
    assert assignments, "CSE should find the shared subexpressions"
    new, jac = differentiate_graph(assignments, reduced, WRT)
    assert len(jac) == len(EXPRS) and all(len(row) == len(WRT) for row in jac)
    # derivative temporaries are fresh, named apart from the primal ones
    primal = {s for s, _ in assignments}
    assert all(s not in primal and s.name.startswith("d") for s, _ in new)
    J = sm.Matrix(inline(assignments + new, [e for row in jac for e in row]))
    J = J.reshape(len(EXPRS), len(WRT))
    ref = sm.Matrix(EXPRS).jacobian(WRT)
    for i in range(ref.rows):
        for j in range(ref.cols):
            diff = J[i, j] - ref[i, j]
            assert sm.simplify(diff) == 0, (i, j, J[i, j], ref[i, j])


def test_graph_jacobian_at_random_points():
    assignments, reduced = cse_graph(EXPRS)
    new, jac = differentiate_graph(assignments, reduced, WRT)
    k = Kernel("j", [Arg("x", tuple(WRT))],
               [Output("J", len(EXPRS), len(WRT), [e for row in jac for e in row])],
               list(assignments) + list(new))
    ref = sm.Matrix(EXPRS).jacobian(WRT)
    rng = random.Random(1)
    for _ in range(5):
        vals = random_values(WRT, rng)
        assert_close(evaluate_kernel(k, vals)["J"], evaluate(ref, vals))


def test_graph_jacobian_reuses_primal_temporaries():
    """d sqrt(w) is written over the temporary that holds sqrt(w)."""
    assignments, reduced = cse_graph([sm.sqrt(r2) * x, sm.sqrt(r2) * y])
    roots = [s for s, e in assignments if e == sm.sqrt(r2)]
    assert roots, assignments
    new, jac = differentiate_graph(assignments, reduced, [x, y])
    derivative_text = [e for _, e in new] + [e for row in jac for e in row]
    assert any(roots[0] in e.free_symbols for e in derivative_text)
    assert not any(e.has(sm.sqrt(r2)) for e in derivative_text)


def test_graph_jacobian_of_inputs_and_constants():
    new, jac = differentiate_graph([], [x, 2 * y, sm.Integer(5), x * y], [x, y])
    assert new == []
    assert jac == [[1, 0], [0, 2], [0, 0], [y, x]]


def test_graph_jacobian_subset_and_order_of_variables():
    assignments, reduced = cse_graph(EXPRS)
    new, jac = differentiate_graph(assignments, reduced, [z, x])
    J = sm.Matrix(inline(assignments + new, [e for row in jac for e in row]))
    J = J.reshape(len(EXPRS), 2)
    ref = sm.Matrix(EXPRS).jacobian([z, x])
    assert_close(J.xreplace(POINT).evalf(DIGITS), ref.xreplace(POINT).evalf(DIGITS))


# ------------------------------------------ make_jacobian_kernel
@pytest.mark.parametrize("cse_derivatives", [True, False], ids=["cse", "no-cse"])
def test_jacobian_kernel_against_sympy(cse_derivatives):
    F = sm.Matrix(EXPRS[:4])
    G = sm.Matrix([EXPRS[4], EXPRS[6]])
    k = make_jacobian_kernel("jk", [Arg("x", tuple(WRT))],
                             plain=[("F", F)],
                             jacobians=[("Fx", F, [x, y]), ("Gz", G, [z, x, y])],
                             cse_derivatives=cse_derivatives)
    assert [(o.name, o.rows, o.cols) for o in k.outputs] == [
        ("F", 4, 1), ("Fx", 4, 2), ("Gz", 2, 3)]
    # every temporary defined before use, every input an input
    defined = set(WRT)
    for s, e in k.assignments:
        assert e.free_symbols <= defined, (s, e)
        defined.add(s)
    for o in k.outputs:
        for e in o.exprs:
            assert e.free_symbols <= defined
    rng = random.Random(2)
    for _ in range(4):
        vals = random_values(WRT, rng)
        got = evaluate_kernel(k, vals)
        assert_close(got["F"], evaluate(F, vals), "F")
        assert_close(got["Fx"], evaluate(F.jacobian([x, y]), vals), "Fx")
        assert_close(got["Gz"], evaluate(G.jacobian([z, x, y]), vals), "Gz")


def test_jacobian_kernel_without_plain_outputs_or_variables():
    k = make_jacobian_kernel("jk", [Arg("x", (x, y))], [], [("J", sm.Matrix([x * y, y]), [x])])
    assert_close(evaluate_kernel(k, {x: 2, y: 3})["J"], sm.Matrix([3, 0]))


# ------------------------------------------ real models
def _lin_blocks(m, lin):
    """The sympy reference for every lin_terms output of model m, over the
    kernel's own qd, ud, lam symbols."""
    names = {a.name: a.symbols for a in lin.args}
    Qd, Ud, Lam = (sm.Matrix(names[n]) for n in ("qd", "ud", "lam"))
    U = sm.Matrix(m.u)
    kin_res = m.Kqd * Qd + m.Ku * U + m.kf
    R = m.M * Ud - m.f
    if m.mv:
        R = R - m.A.T * Lam
    ref = {"Kqd": m.Kqd, "Ku": m.Ku, "M": m.M,
           "Kq": kin_res.jacobian(m.q), "Rq": R.jacobian(m.q), "Ru": R.jacobian(m.u)}
    if m.nr:
        ref["Rr"] = R.jacobian(m.r)
    if m.mv:
        # a holds q' as m.qd with implicit kinematics (the kernel's qd here)
        S = m.A * Ud + m.a.xreplace(dict(zip(m.qd, Qd)))
        ref.update({"A": m.A, "Sq": S.jacobian(m.q), "Su": S.jacobian(m.u),
                    "Vq": (m.A * U + m.b).jacobian(m.q)})
        if m.qd:
            ref["Sqd"] = S.jacobian(Qd)
    if m.mc:
        ref["Jc"] = m.fc.jacobian(m.q)
    return ref


def _model_values(m, kernel, rng):
    vals = random_values(input_symbols(kernel), rng, -1.3, 1.3)
    vals.update(random_values(m.p, rng, 0.5, 2.0))      # lengths, masses, g: positive
    if m.mc:                                            # seed: keep away from q1 = 0
        vals[m.q[1]] = abs(vals[m.q[1]]) + sm.Rational(1, 2)
    return vals


@pytest.fixture(scope="module")
def seed_kane():
    m = seed_pendulum.kane_model()
    return m, kernels_of(m)


@pytest.fixture(scope="module")
def cart2():
    m = n_link_cart.model(2)
    return m, kernels_of(m)


@pytest.mark.parametrize("which", ["seed_kane", "cart2"])
def test_lin_terms_blocks_against_sympy_jacobians(which, request):
    m, ks = request.getfixturevalue(which)
    lin = ks["lin_terms"]
    ref = _lin_blocks(m, lin)
    assert {o.name for o in lin.outputs} == set(ref)
    rng = random.Random(3)
    for _ in range(3):
        vals = _model_values(m, lin, rng)
        got = evaluate_kernel(lin, vals)
        for name, mat in ref.items():
            assert_close(got[name], evaluate(mat, vals), f"{which} {name}")


@pytest.mark.parametrize("which", ["seed_kane", "cart2"])
def test_model_kernels_against_model_matrices(which, request):
    m, ks = request.getfixturevalue(which)
    U = sm.Matrix(m.u)
    ref = {"M": m.M, "f": m.f, "fc": m.fc, "Jc": m.fc.jacobian(m.q), "A": m.A, "b": m.b,
           "a": m.a, "fv": m.A * U + m.b, "qdot": m.qdot,
           "E": sm.Matrix([m.energy]) if m.energy is not None else None}
    rng = random.Random(4)
    checked = set()
    for k in ks.values():
        if k.name == "lin_terms":
            continue
        vals = _model_values(m, k, rng)
        for name, got in evaluate_kernel(k, vals).items():
            want = ref.get(name)
            if name == "a" and k.name == "rhs_terms":
                # implicit kinematics: rhs_terms writes a at q' = 0, accel_terms at q'
                want = m.a.xreplace({s: 0 for s in m.qd})
            if want is not None:
                assert_close(got, evaluate(want, vals), f"{which} {k.name}.{name}")
                checked.add(name)
    assert {"M", "f"} <= checked
    if m.mc:
        assert {"fc", "Jc", "A", "b", "fv"} <= checked


def test_seed_kernels_hold_no_dead_temporaries(seed_kane):
    _, ks = seed_kane
    for k in ks.values():
        assert len(prune(Kernel(k.name, k.args, k.outputs, list(k.assignments))).assignments) \
            == len(k.assignments), k.name


# ------------------------------------------ CSE on and off
def test_make_kernel_cse_on_and_off_agree():
    outputs = [("a", sm.Matrix(EXPRS[:3])), ("b", sm.Matrix(2, 2, EXPRS[3:7]))]
    on = make_kernel("k", [Arg("x", tuple(WRT))], outputs, cse=True)
    off = make_kernel("k", [Arg("x", tuple(WRT))], outputs, cse=False)
    assert on.assignments and not off.assignments
    assert on.op_count < off.op_count
    assert [(o.name, o.rows, o.cols) for o in on.outputs] == [("a", 3, 1), ("b", 2, 2)]
    rng = random.Random(5)
    for _ in range(4):
        vals = random_values(WRT, rng)
        a, b = evaluate_kernel(on, vals), evaluate_kernel(off, vals)
        for name in ("a", "b"):
            assert_close(a[name], b[name], name)
    # CSE is a rewrite, not an approximation: inlined, it is the input exactly
    for o in on.outputs:
        flat = inline(on.assignments, o.exprs)
        src = dict(outputs)[o.name]
        assert all(sm.simplify(u - v) == 0 for u, v in zip(flat, src))


def test_make_kernel_empty_output():
    k = make_kernel("k", [Arg("x", (x,))], [("e", sm.zeros(0, 1))])
    assert k.assignments == [] and k.outputs[0].exprs == []


# ------------------------------------------ prune
def test_prune_removes_dead_temporaries_only():
    w = sm.symbols("w0:7")
    assignments = [
        (w[0], sm.sin(x)),             # used by w2
        (w[1], sm.cos(x)),             # dead
        (w[2], w[0] * y),              # used by the output
        (w[3], w[1] + 1),              # dead (uses a dead one)
        (w[4], x * y),                 # used by the output
        (w[5], w[4] ** 2),             # dead
        (w[6], w[2] + w[4]),           # used by the output
    ]
    k = prune(Kernel("k", [Arg("x", (x, y))], [Output("o", 1, 2, [w[6], w[2] * z])],
                     list(assignments)))
    assert [s for s, _ in k.assignments] == [w[0], w[2], w[4], w[6]]
    assert k.assignments == [a for a in assignments if a[0] in (w[0], w[2], w[4], w[6])]


def test_prune_drops_everything_when_outputs_are_plain():
    w0 = sm.Symbol("w0")
    k = prune(Kernel("k", [], [Output("o", 1, 1, [x + 1])], [(w0, sm.sin(x))]))
    assert k.assignments == []


def test_jacobian_kernel_is_pruned():
    """Derivative temporaries only some outputs need vanish with them."""
    k = make_jacobian_kernel("jk", [Arg("x", (x, y))], [],
                             [("J", sm.Matrix([sm.sin(x * y) * sm.cos(x * y)]), [y])])
    needed = set()
    for o in k.outputs:
        for e in o.exprs:
            needed |= e.free_symbols
    for s, e in reversed(k.assignments):
        assert s in needed, s
        needed |= e.free_symbols


# ------------------------------------------ collect_constants
def test_collect_constants_groups_and_preserves_value():
    m1, m2, m3, g, L = sm.symbols("m1 m2 m3 g L")
    q, u = sm.symbols("q u")
    e = (m1 * g * sm.sin(q) + m2 * g * sm.sin(q) + 3 * sm.sin(q)
         + m1 * u**2 + m3 * L * u**2 + m2 * sm.cos(q) * u)
    M = sm.Matrix([[e, m1 * q + m2 * q], [sm.Integer(0), m1 + m2]])
    out = collect_constants(M, [q, u])
    assert out.shape == M.shape
    assert sm.expand(out[0, 0] - e) == 0
    assert out[0, 1] == (m1 + m2) * q
    assert out[1, 0] == 0 and out[1, 1] == m1 + m2          # no variable: untouched
    # sin(q) and u**2 each appear once after collection
    assert out[0, 0].count(sm.sin(q)) == 1
    assert sum(1 for a in sm.Add.make_args(out[0, 0]) if a.has(u**2)) == 1
    assert sm.count_ops(out[0, 0]) < sm.count_ops(e)
    rng = random.Random(6)
    for _ in range(3):
        vals = random_values([m1, m2, m3, g, L, q, u], rng)
        assert_close(evaluate(out, vals), evaluate(M, vals))


def test_collect_constants_nested_and_cached():
    a, b, q = sm.symbols("a b q")
    inner = a * sm.cos(q) + b * sm.cos(q)
    e = sm.sin(inner) * (a * q + b * q) + sm.sqrt(a * q**2 + b * q**2)
    cache = {}
    out = collect_constants(sm.Matrix([e, inner]), [q], cache)
    assert out[1] == (a + b) * sm.cos(q)
    assert out[0].has((a + b) * sm.cos(q))
    assert sm.simplify(out[0] - e) == 0
    assert cache                                             # memoized over the graph
    assert collect_constants(sm.Matrix([e]), [q], cache)[0] == out[0]


def test_collect_constants_on_a_model_preserves_value(cart2):
    m, _ = cart2
    variables = set(m.q) | set(m.u) | set(m.r) | {m.t}
    F = collect_constants(m.f, variables)
    Mc = collect_constants(m.M, variables)
    rng = random.Random(7)
    syms = sorted(variables | set(m.p), key=str)
    for _ in range(2):
        vals = random_values(syms, rng)
        assert_close(evaluate(F, vals), evaluate(m.f, vals), "f")
        assert_close(evaluate(Mc, vals), evaluate(m.M, vals), "M")


def test_collect_constants_takes_out_common_factors():
    """A chain's mass-matrix entry, as Kane's method expands it:
    sum_k m_k l1 l2 cos(q) becomes l1 l2 (m_1 + ... + m_6) cos(q): one sum
    of the masses and two products instead of six triple products."""
    ms = sm.symbols("m1:7")
    l1, l2, q = sm.symbols("l1 l2 q")
    e = sm.Add(*[mk * l1 * l2 * sm.cos(q) for mk in ms]) + l1 * ms[0] * sm.sin(q)
    out = collect_constants(sm.Matrix([e]), [q])[0]
    assert out.has(l1 * l2 * sm.Add(*ms) * sm.cos(q)), out
    assert sm.count_ops(out) <= len(ms) + 7 < sm.count_ops(e)       # 13 against 33
    assert sm.expand(out - e) == 0


def test_common_factors_make_the_parameter_work_linear():
    """On the 6-link cart the parameters' own work (temporaries of p alone)
    in the right-hand-side kernel: the suffix sums of the masses, shared by
    the entries, and a few products per link, instead of a triple product per
    mass and entry; the whole kernel is smaller, and its values are the
    model's (sympy's M and f at random points)."""
    import n_link_cart
    from gen.plan import ir as gir
    m = n_link_cart.model(6)

    def param_work(kernel):
        p = set(m.p)
        only = set()
        for s, e in kernel.assignments:
            if e.free_symbols <= p | only:
                only.add(s)
        return len(only), sum(sm.count_ops(e) for s, e in kernel.assignments)

    sym, _ = gir.mass_structure(m)
    k = gir.core_kernels(gir.kernel_inputs(m, sym))["rhs_terms"]
    n_par, ops = param_work(k)
    plain = gir._common_factor
    try:
        gir._common_factor = lambda terms: sm.Add(*terms)
        k0 = gir.core_kernels(gir.kernel_inputs(m, sym))["rhs_terms"]
    finally:
        gir._common_factor = plain
    n_par0, ops0 = param_work(k0)
    assert n_par <= 4 * 7 < n_par0, (n_par, n_par0)
    assert ops < 0.8 * ops0, (ops, ops0)
    inputs = gir.kernel_inputs(m, sym)
    variables = set(m.q) | set(m.u) | set(m.r) | {m.t}
    syms = sorted(variables | set(m.p), key=str)
    rng = random.Random(8)
    for _ in range(2):
        vals = random_values(syms, rng)
        assert_close(evaluate(inputs.M, vals), evaluate(m.M, vals), "M")
        assert_close(evaluate(inputs.f, vals), evaluate(m.f, vals), "f")
