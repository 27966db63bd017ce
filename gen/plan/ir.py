"""Kernels: named straight-line functions with typed array inputs and
outputs, and one CSE'd list of assignments each.

Jacobians are formed by forward-mode differentiation of the CSE'd
assignment list (an expression graph), never by expanding full symbolic
matrices, so they stay the size of the graph as models grow.

The graph differentiation itself (non-smooth functions almost everywhere)
is gen.sym.graph's.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sm

from ..sym.graph import (Namer, NoFloat, differentiate_graph, float_values, free_symbols,
                         jvp_graph)

__all__ = ["Arg", "Output", "Kernel", "Plan", "plan", "with_derivatives", "lin_mode",
           "make_kernel", "make_jvp_kernel", "make_jacobian_kernel", "JVP_MIN_VARIABLES",
           "DERIVATIVE_KERNELS", "build_kernels", "mass_structure", "core_kernels",
           "derivative_kernels", "kernel_inputs", "KernelInputs", "prune"]


@dataclass(frozen=True)
class Arg:
    """A kernel input: a C array (length n) or scalar (n == 0) of reals."""
    name: str
    symbols: tuple          # the internal symbols it carries, in order
    scalar: bool = False

    @property
    def n(self):
        return len(self.symbols)


@dataclass
class Output:
    """A kernel output matrix, row-major, named in C as ``out_<name>``."""
    name: str
    rows: int
    cols: int
    exprs: list             # flattened row-major, after CSE

    @property
    def size(self):
        return self.rows * self.cols


@dataclass
class Kernel:
    name: str
    args: list
    outputs: list
    assignments: list = field(default_factory=list)   # [(Symbol, Expr)]

    @property
    def op_count(self):
        return sum(sm.count_ops(e) for _, e in self.assignments) + sum(
            sm.count_ops(e) for o in self.outputs for e in o.exprs)


def _flatten(mat):
    mat = sm.Matrix(mat)
    return [mat[i, j] for i in range(mat.shape[0]) for j in range(mat.shape[1])], mat.shape


def make_kernel(name, args, outputs, cse=True, jvps=()):
    """outputs: list of (name, Matrix). One joint CSE over all of them.

    jvps: [(name, column Matrix F, seeds {symbol: expression})]: outputs that
    are the directional derivatives of F along the seeds (dF = sum_s dF/ds
    seed_s), differentiated on the CSE'd graph (jvp_graph) that F and the
    seed expressions share with the plain outputs, then CSE'd again: a graph
    a few times the size of F's, where a symbolic Jacobian of F swells (the
    acceleration-constraint term d(A u + b)/dq q' + d(A u + b)/dt)."""
    flat, shapes = [], []
    for oname, mat in outputs:
        f, shp = _flatten(mat)
        flat.extend(f)
        shapes.append((oname, shp))
    spans = []
    for oname, F, seeds in jvps:
        f, _ = _flatten(F)
        keys = list(seeds)
        spans.append((oname, len(flat), len(f), len(flat) + len(f), keys))
        flat.extend(f)
        flat.extend(sm.sympify(seeds[k]) for k in keys)
    if (cse or jvps) and flat:
        assignments, reduced = _cse(flat, Namer("w"))
    else:
        assignments, reduced = [], _unkept(flat)
    outs, k = [], 0
    for oname, (rows, cols) in shapes:
        outs.append(Output(oname, rows, cols, list(reduced[k:k + rows * cols])))
        k += rows * cols
    extra = []
    for i, (oname, start, n, seed_at, keys) in enumerate(spans):
        fr = reduced[start:start + n]
        seeds = dict(zip(keys, reduced[seed_at:seed_at + len(keys)]))
        # only the temporaries F needs are differentiated
        need = _closure(assignments, fr)
        new, tang = jvp_graph([a for a in assignments if a[0] in need], fr, seeds,
                              prefix=f"j{i}_")
        if new or tang:
            tsyms = [t for t, _ in new]
            a2, r2 = sm.cse([e for _, e in new] + list(tang), symbols=Namer(f"v{i}_"),
                            order="none")
            extra += _toposort(list(a2) + list(zip(tsyms, r2[:len(tsyms)])),
                               set(a for a, _ in assignments) | set(t for t, _ in extra))
            tang = r2[len(tsyms):]
        outs.append(Output(oname, n, 1, list(tang)))
    return prune(Kernel(name, list(args), outs, list(assignments) + extra))


def _cse(exprs, symbols):
    """sympy's cse, with the recursive formulation's opaque nodes
    (UnevaluatedExpr, shared subexpressions kept whole: gen.sym.intern)
    unwrapped in what it returns: the
    repeated ones are temporaries by then. Models without them come back
    unchanged (the same objects)."""
    if _has_kept(exprs):
        return _kept_program(exprs, symbols)
    assignments, reduced = sm.cse(exprs, symbols=symbols, order="none")
    memo = {}
    return ([(s, _unkept([e], memo)[0]) for s, e in assignments], _unkept(reduced, memo))


def _has_kept(exprs):
    seen, stack = set(), list(exprs)
    while stack:
        e = stack.pop()
        if isinstance(e, sm.UnevaluatedExpr):
            return True
        if id(e) in seen or not e.args:
            continue
        seen.add(id(e))
        stack.extend(a for a in e.args if isinstance(a, sm.Basic))
    return False


def _kept_program(exprs, symbols):
    """The recursive formulation's graphs: each opaque node (UnevaluatedExpr,
    a body's quantity, shared) is one temporary over the temporaries of the nodes it
    holds, in an order where each is written before it is read: the
    graph is already the straight-line program, its size linear in the
    bodies (sympy's cse over it sorts nested sums, superlinear in the
    depth). Iterative: the graphs are thousands of nodes deep."""
    memo, assignments = {}, []
    stack = [(e, False) for e in reversed(list(exprs))]
    while stack:
        e, ready = stack.pop()
        if e in memo:
            continue
        if not e.args or not isinstance(e, sm.Basic):
            memo[e] = e
            continue
        if not ready:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if a not in memo)
            continue
        args = [memo[a] for a in e.args]
        if isinstance(e, sm.UnevaluatedExpr):
            sym = next(symbols)
            assignments.append((sym, args[0]))
            memo[e] = sym
        else:
            memo[e] = e.func(*args) if any(a is not b for a, b in zip(args, e.args)) else e
    return assignments, [memo[e] for e in exprs]


def _unkept(exprs, memo=None):
    """exprs with every UnevaluatedExpr replaced by its argument (each
    distinct subexpression rebuilt once)."""
    memo = {} if memo is None else memo

    def walk(e):
        hit = memo.get(e)
        if hit is not None:
            return hit
        if isinstance(e, sm.UnevaluatedExpr):
            out = walk(e.args[0])
        elif not e.args:
            out = e
        else:
            args = [walk(a) for a in e.args]
            out = e.func(*args) if any(a is not b for a, b in zip(args, e.args)) else e
        memo[e] = out
        return out

    return [walk(e) for e in exprs]


def _closure(assignments, exprs):
    """The temporaries of assignments that exprs need, directly or through
    other temporaries."""
    defs = dict(assignments)
    need, stack = set(), [s for e in exprs for s in e.free_symbols if s in defs]
    while stack:
        s = stack.pop()
        if s in need:
            continue
        need.add(s)
        stack.extend(x for x in defs[s].free_symbols if x in defs and x not in need)
    return need


def make_jvp_kernel(name, args, funcs, seeds):
    """A kernel of directional derivatives: outputs[k] = d funcs[k] along
    the seeds {variable: tangent symbol} (the tangents are among args), all
    from one joint CSE of the primal and one of the tangents.

    funcs: [(out_name, column Matrix)]"""
    flat, shapes = [], []
    for oname, mat in funcs:
        f, shp = _flatten(mat)
        shapes.append((oname, len(f)))
        flat.extend(f)
    assignments, reduced = _cse(flat, Namer("w")) if flat else ([], [])
    new, outs_flat = jvp_graph(assignments, reduced, seeds)
    if new or outs_flat:
        tsyms = [s for s, _ in new]
        texprs = [e for _, e in new]
        a2, r2 = sm.cse(texprs + list(outs_flat), symbols=Namer("v"), order="none")
        new_assign = list(a2) + list(zip(tsyms, r2[:len(tsyms)]))
        outs_flat = r2[len(tsyms):]
        new = _toposort(new_assign, set(s for s, _ in assignments))
    outs, k = [], 0
    for oname, n in shapes:
        outs.append(Output(oname, n, 1, list(outs_flat[k:k + n])))
        k += n
    return prune(Kernel(name, list(args), outs, list(assignments) + list(new)))


def make_jacobian_kernel(name, args, plain, jacobians, cse_derivatives=True):
    """A kernel whose outputs are plain matrices and Jacobians of
    matrices, all from one joint CSE.

    plain: [(out_name, Matrix)]
    jacobians: [(out_name, Matrix F (column), wrt symbols)] -> dF/dwrt
    """
    flat, spans = [], []
    for oname, mat in plain:
        f, shp = _flatten(mat)
        spans.append(("plain", oname, len(flat), shp, None))
        flat.extend(f)
    for oname, mat, wrt in jacobians:
        f, shp = _flatten(mat)
        spans.append(("jac", oname, len(flat), (len(f), len(wrt)), list(wrt)))
        flat.extend(f)
    if flat:
        assignments, reduced = _cse(flat, Namer("w"))
    else:
        assignments, reduced = [], []
    # one forward sweep for the union of all differentiation variables
    allwrt = []
    for kind, _, _, _, wrt in spans:
        if kind == "jac":
            for v in wrt:
                if v not in allwrt:
                    allwrt.append(v)
    jac_rows_exprs = []
    for kind, _, start, shp, wrt in spans:
        if kind == "jac":
            jac_rows_exprs.extend(reduced[start:start + shp[0]])
    new, jac_all = differentiate_graph(assignments, jac_rows_exprs, allwrt)
    outs_flat = []
    shapes = []
    k = 0
    for kind, oname, start, shp, wrt in spans:
        if kind == "plain":
            outs_flat.extend(reduced[start:start + shp[0] * shp[1]])
            shapes.append((oname, shp))
        else:
            cols = [allwrt.index(v) for v in wrt]
            for i in range(shp[0]):
                row = jac_all[k + i]
                outs_flat.extend(row[c] for c in cols)
            k += shp[0]
            shapes.append((oname, shp))
    # second CSE over the derivative temporaries and the outputs
    if cse_derivatives and (new or outs_flat):
        dsyms = [s for s, _ in new]
        dexprs = [e for _, e in new]
        a2, r2 = sm.cse(dexprs + outs_flat, symbols=Namer("v"), order="none")
        new_assign = list(a2)
        # keep d-temporaries as named assignments so outputs can refer to them
        for s, e in zip(dsyms, r2[:len(dsyms)]):
            new_assign.append((s, e))
        outs_flat = r2[len(dsyms):]
        # a2 may refer to d-temps defined later; order topologically
        new = _toposort(new_assign, set(s for s, _ in assignments))
    outs, k = [], 0
    for oname, (rows, cols) in shapes:
        outs.append(Output(oname, rows, cols, list(outs_flat[k:k + rows * cols])))
        k += rows * cols
    return prune(Kernel(name, list(args), outs, list(assignments) + list(new)))


def _toposort(assign, known):
    """Order assignments so every temporary is defined before use."""
    defined = set(known)
    pending = list(assign)
    ordered = []
    names = {s for s, _ in assign}
    while pending:
        progress = False
        rest = []
        for s, e in pending:
            need = {x for x in e.free_symbols if x in names}
            if need <= defined:
                ordered.append((s, e))
                defined.add(s)
                progress = True
            else:
                rest.append((s, e))
        if not progress:
            raise RuntimeError("cyclic temporaries in derivative kernel")
        pending = rest
    return ordered


def mass_structure(model):
    """(symmetric, nonzero): whether the mass matrix is symmetric (checked
    numerically at two random points: exact symmetry of the expressions is
    not needed, only of the values, to 1e-9 of the matrix's largest entry)
    and its structural nonzero pattern."""
    import random
    M = model.M
    n = M.shape[0]
    nonzero = [[M[i, j] != 0 for j in range(n)] for i in range(n)]
    symmetric = all(nonzero[i][j] == nonzero[j][i] for i in range(n) for j in range(i))
    rnd = random.Random(12345)
    syms = sorted(free_symbols(M), key=str)
    pairs = [(i, j) for i in range(n) for j in range(i) if nonzero[i][j]]
    for _ in range(2 if symmetric and pairs else 0):
        vals = {s: rnd.uniform(0.3, 1.3) for s in syms}
        try:
            flat = float_values([M[i, j] for i in range(n) for j in range(n)], vals)
        except NoFloat:
            flat = None
        if flat is not None:
            scale = max(abs(v) for v in flat)
            if any(abs(flat[i * n + j] - flat[j * n + i]) > 1e-300 + 1e-9 * scale
                   for i, j in pairs):
                symmetric = False
            continue
        # what the float walk cannot evaluate: sympy at 30 digits
        Mv = M.xreplace({s: sm.Float(v, 30) for s, v in vals.items()})
        for i, j in pairs:
            try:
                a, b = complex(Mv[i, j].evalf(30)), complex(Mv[j, i].evalf(30))
            except (TypeError, ValueError):
                symmetric = False
                break
            if abs(a - b) > 1e-20 + 1e-12 * max(abs(a), abs(b)):
                symmetric = False
                break
        if not symmetric:
            break
    return symmetric, nonzero


def _mass_for_kernels(model, symmetric):
    """M with its upper triangle taken from the lower one when M is
    symmetric, so each pair is computed once (CSE merges the copies)."""
    if not symmetric:
        return model.M
    n = model.M.shape[0]
    return sm.Matrix(n, n, lambda i, j: model.M[max(i, j), min(i, j)])


def _common_factor(terms):
    """The sum of constant terms with their common monomial factor taken
    out: m2 l1 l2 + m3 l1 l2 -> l1 l2 (m2 + m3). Kane's mass matrix of a
    chain holds sum_k m_k l_i l_j in every entry: factored, the sums of the
    masses are shared by CSE and the parameters' work is linear in the
    links, not cubic (the n = 16 cart's right-hand side: 3884 -> 1962
    operations). Integer powers only; a plain product walk (sympy's
    gcd_terms took five times as long)."""
    total = sm.Add(*terms)
    if len(terms) < 2 or not total.is_Add:
        return total
    parts = []
    common = None
    for a in total.args:
        coeff, rest = a.as_coeff_Mul()
        powers = rest.as_powers_dict()
        parts.append((coeff, powers))
        if common is None:
            common = {b: e for b, e in powers.items() if e.is_Integer and e > 0}
        else:
            common = {b: min(e, powers[b]) for b, e in common.items()
                      if b in powers and powers[b].is_Integer and powers[b] > 0}
        if not common:
            return total
    factor = sm.Mul(*[b ** e for b, e in common.items()])
    rest = sm.Add(*[coeff * sm.Mul(*[b ** (e - common.get(b, 0)) for b, e in powers.items()])
                    for coeff, powers in parts])
    return factor * rest


def collect_constants(mat, variables, cache=None):
    """Rewrite every sum c1*d + c2*d + ... as (c1 + c2 + ...)*d, where the
    c's hold no variable (constants and numbers only): Kane's forcing and
    mass matrix are full of sums of masses times one state term, which CSE
    cannot see as shared. Linear in the size of the expression graph."""
    from collections import defaultdict
    variables = frozenset(variables)
    cache = {} if cache is None else cache
    deps = {}

    def dep(e):
        """Whether e holds a variable (memoized: free_symbols is not)."""
        hit = deps.get(e)
        if hit is None:
            hit = deps[e] = (e in variables) if e.is_Atom else any(dep(a) for a in e.args)
        return hit

    def split(term):
        """term.as_independent(*variables, as_Add=False), by the memo."""
        if term.is_Mul:
            c = [a for a in term.args if not dep(a)]
            if len(c) == len(term.args):
                return term, sm.S.One
            if not c:
                return sm.S.One, term
            return sm.Mul(*c), sm.Mul(*[a for a in term.args if dep(a)])
        return (sm.S.One, term) if dep(term) else (term, sm.S.One)

    def walk(e):
        if e.is_Atom:
            return e
        hit = cache.get(e)
        if hit is not None:
            return hit
        args = [walk(a) for a in e.args]
        if e.is_Add:
            groups = defaultdict(list)
            order = []
            for term in args:
                c, d = split(term)
                if d not in groups:
                    order.append(d)
                groups[d].append(c)
            out = (sm.Add(*[_common_factor(groups[d]) * d for d in order])
                   if len(order) < len(args) else e.func(*args))
        elif args != list(e.args):
            out = e.func(*args)
        else:
            out = e
        cache[e] = out
        return out

    return sm.Matrix(mat.shape[0], mat.shape[1], [walk(x) for x in mat])


# the linearization kernels: above this many variables (nq + nu + nr) the
# Jacobian blocks come from a directional-derivative kernel called once per
# column ("jvp") instead of one unrolled kernel ("unrolled"): code (and
# compile time) that grows like the right-hand side, not n times it
JVP_MIN_VARIABLES = 30


@dataclass
class KernelInputs:
    """What every kernel of a model is written over: the argument arrays
    and M and f with their constant sums collected (computed once, shared by
    the core and the derivative kernels)."""
    model: object
    q: Arg
    u: Arg
    r: Arg
    p: Arg
    t: Arg
    M: sm.Matrix           # symmetric M with its upper triangle from the lower one
    f: sm.Matrix


def kernel_inputs(model, symmetric):
    m = model
    variables = set(m.q) | set(m.u) | set(m.r) | {m.t}
    cache = {}
    return KernelInputs(
        m, Arg("q", tuple(m.q)), Arg("u", tuple(m.u)), Arg("r", tuple(m.r)),
        Arg("p", tuple(m.p)), Arg("t", (m.t,), scalar=True),
        collect_constants(_mass_for_kernels(m, symmetric), variables, cache),
        collect_constants(m.f, variables, cache))


def build_kernels(model, mass=None, lin="auto", derivatives=True, inputs=None):
    """Every kernel a model's C code needs, as plain data. mass: the
    (symmetric, nonzero) structure of M, computed when not given. lin:
    "unrolled", "jvp" or "auto" (by JVP_MIN_VARIABLES): how the
    linearization's Jacobian blocks are generated. derivatives=False leaves
    out the derivative kernels (derivative_kernels): the largest kernels,
    needed only by linearize, jacobian, step_sensitivity and RODAS4.

    M and f have no kernels of their own: the runtime gets them from
    rhs_terms (one CSE for everything the right-hand side needs; separate
    kernels repeated most of its code)."""
    if inputs is None:
        symmetric, _ = mass if mass is not None else mass_structure(model)
        inputs = kernel_inputs(model, symmetric)
    kernels = core_kernels(inputs)
    if derivatives:
        kernels.update(derivative_kernels(inputs, lin))
    return kernels


def core_kernels(inputs):
    """The kernels of evaluation and simulation: kinematics, rhs_terms (q'
    or its system, M, f and the velocity-constraint terms, jointly CSE'd),
    constraints, energy, reactions, outputs."""
    m, Aq, Au, Ar, Ap, At = inputs.model, inputs.q, inputs.u, inputs.r, inputs.p, inputs.t
    U = sm.Matrix(m.u)
    kernels = {}
    if m.qdot is not None:
        kin_out = [("qdot", m.qdot)]
    else:
        kin_out = [("Kqd", m.Kqd), ("kr", -(m.Ku * U + m.kf))]
    kernels["kinematics"] = make_kernel("kinematics", [Aq, Au, Ap, At], kin_out)
    # everything the right-hand side needs, jointly CSE'd
    rhs_out = list(kin_out) + [("M", inputs.M), ("f", inputs.f)]
    qd_model = list(getattr(m, "qd", []) or [])
    jvps = []
    if m.mv:
        # a = d(A u + b)/dq q' + d(A u + b)/dt: the directional derivative of
        # A u + b along (q', 1) on the kernel's graph. With implicit
        # kinematics q' is the run time's (m.qd): rhs_terms writes a at
        # q' = 0, and accel_terms at the q' the runtime solved for
        fv = m.A * U + m.b
        if m.qdot is not None:
            seeds = dict(zip(m.q, m.qdot))
        else:
            seeds = {}
            kernels["accel_terms"] = make_kernel(
                "accel_terms", [Aq, Au, Arg("qd", tuple(qd_model)), Ap, At], [],
                jvps=[("a", fv, {**dict(zip(m.q, qd_model)), m.t: 1})])
        seeds[m.t] = 1
        rhs_out += [("A", m.A)]
        jvps.append(("a", fv, seeds))
    kernels["rhs_terms"] = make_kernel("rhs_terms", [Aq, Au, Ar, Ap, At], rhs_out, jvps=jvps)
    if m.mc:
        kernels["constraints"] = make_kernel("constraints", [Aq, Ap, At], [("fc", m.fc)])
        kernels["constraint_jacobian"] = make_jacobian_kernel(
            "constraint_jacobian", [Aq, Ap, At], [("fc", m.fc)], [("Jc", m.fc, m.q)])
    if m.mv:
        kernels["velocity_constraint_matrix"] = make_kernel(
            "velocity_constraint_matrix", [Aq, Ap, At], [("A", m.A), ("b", m.b)])
        kernels["velocity_constraints"] = make_kernel(
            "velocity_constraints", [Aq, Au, Ap, At], [("fv", m.A * U + m.b)])
    if m.energy is not None:
        kernels["energy"] = make_kernel("energy", [Aq, Au, Ap, At], [("E", sm.Matrix([m.energy]))])
    if getattr(m, "na", 0):
        # reaction forces along the auxiliary speeds: F reactions + g = 0,
        # g in the accelerations ud (the runtime computes them first)
        kernels["auxiliary"] = make_kernel(
            "auxiliary", [Aq, Au, Arg("ud", tuple(m.ud)), Ar, Ap, At],
            [("F", m.aux_F), ("g", m.aux_g)])
        if getattr(m, "aux_G", None) is not None:
            # reactions inside the motion: the blocks of the coupled system
            # [M, -G; C, H] [u'; reactions] = [f; -g0] (gen_rt_accel_reactions)
            kernels["reaction_terms"] = make_kernel(
                "reaction_terms", [Aq, Au, Ar, Ap, At], reaction_blocks(m))
    if getattr(m, "ny", 0):
        # outputs y(q, u, r, p, t) (their Jacobians are derivative kernels)
        kernels["outputs"] = make_kernel("outputs", [Aq, Au, Ar, Ap, At], [("y", m.y)])
    # hybrid={...} (gen/intake/hybrid.py): gaps and guards, the gaps' rates and
    # biases, the reset maps
    from ..intake.hybrid import hybrid_kernels
    hargs = {"q": Aq, "u": Au, "p": Ap, "t": At}
    for kname, args, outs in hybrid_kernels(m):
        kernels[kname] = make_kernel(kname, [hargs[c] for c in args], outs)
    return kernels


def reaction_blocks(m):
    """The blocks of the coupled solve of a model whose reactions enter the
    motion (m.aux_G): G (nu x na, f = f0 + G reactions), C (na x nu, the
    accelerations' coefficients in the auxiliary equations), H (na x na,
    the reactions' = aux_F) and g0 (na, the auxiliary equations at u' = 0
    and zero reactions), as [(name, Matrix)]."""
    zero = {s: 0 for s in m.ud}
    return [("G", m.aux_G), ("C", m.aux_g.jacobian(list(m.ud))), ("H", m.aux_F),
            ("g0", m.aux_g.xreplace(zero))]


def reaction_lin_kernel(m, Aq, Au, Ar, Ap, At):
    """The derivative kernel of the coupled solve: at the accelerations ud
    and the reactions rx it solved, the Jacobians with respect to q, u and r
    of the reactions' share of the dynamic residual, -G rx (Xq, Xu, Xr), and
    of the auxiliary residual, aux_F rx + aux_g(ud) (Pq, Pu, Pr)."""
    Rx = [sm.Dummy(f"rx{i}") for i in range(m.na)]
    rx = sm.Matrix(Rx)
    X = -(m.aux_G * rx)
    P = m.aux_F * rx + m.aux_g
    jacs = [("Xq", X, m.q), ("Xu", X, m.u)]
    if m.nr:
        jacs.append(("Xr", X, m.r))
    jacs += [("Pq", P, m.q), ("Pu", P, m.u)]
    if m.nr:
        jacs.append(("Pr", P, m.r))
    return make_jacobian_kernel(
        "reaction_lin", [Aq, Au, Arg("ud", tuple(m.ud)), Arg("rx", tuple(Rx)), Ar, Ap, At],
        [], jacs)


def derivative_kernels(inputs, lin="auto"):
    """The derivative kernels: the Jacobian blocks of the linearization
    (lin_terms, or lin_plain and lin_jvp) and the outputs' Jacobians
    (output_jacobian)."""
    m, Aq, Au, Ar, Ap, At = inputs.model, inputs.q, inputs.u, inputs.r, inputs.p, inputs.t
    Msym, F = inputs.M, inputs.f
    U = sm.Matrix(m.u)
    Qd = [sm.Dummy(f"qd{i}") for i in range(m.nq)]
    Ud = [sm.Dummy(f"ud{i}") for i in range(m.nu)]
    Lam = [sm.Dummy(f"lam{i}") for i in range(m.mv)]
    Aqd = Arg("qd", tuple(Qd))
    Aud = Arg("ud", tuple(Ud))
    Alam = Arg("lam", tuple(Lam))
    qd_model = list(getattr(m, "qd", []) or [])
    kernels = {}
    if getattr(m, "ny", 0):
        yj = [("Yq", m.y, m.q), ("Yu", m.y, m.u)] + ([("Yr", m.y, m.r)] if m.nr else [])
        kernels["output_jacobian"] = make_jacobian_kernel(
            "output_jacobian", [Aq, Au, Ar, Ap, At], [], yj)

    # linearization pieces (sympy's Linearizer f_0..f_4, f_c, f_v, f_a)
    kin_res = m.Kqd * sm.Matrix(Qd) + m.Ku * U + m.kf
    R = Msym * sm.Matrix(Ud) - F
    if m.mv:
        R = R - m.A.T * sm.Matrix(Lam)
    plain = [("Kqd", m.Kqd), ("Ku", m.Ku), ("M", Msym)]
    jacs = [("Kq", kin_res, m.q), ("Rq", R, m.q), ("Ru", R, m.u)]
    if m.nr:
        jacs.append(("Rr", R, m.r))
    if m.mv:
        S = m.A * sm.Matrix(Ud) + m.a.xreplace(dict(zip(qd_model, Qd)))
        plain.append(("A", m.A))
        jacs += [("Sq", S, m.q), ("Su", S, m.u), ("Vq", m.A * U + m.b, m.q)]
    if m.mc:
        jacs.append(("Jc", m.fc, m.q))
    if m.mv and qd_model:
        jacs.append(("Sqd", S, Qd))
    lin_args = [Aq, Au, Aqd, Aud, Alam, Ar, Ap, At]
    if getattr(m, "aux_G", None) is not None:
        kernels["reaction_lin"] = reaction_lin_kernel(m, Aq, Au, Ar, Ap, At)
    lin = lin_mode(m, lin)
    if lin == "unrolled":
        kernels["lin_terms"] = make_jacobian_kernel("lin_terms", lin_args, plain, jacs)
        return kernels
    # the Jacobian blocks column by column: one kernel of directional
    # derivatives along (dq, du, dr, dqd), called once per variable by the
    # generated lin_terms (a unit seed in one block gives that variable's
    # column of every block), and the plain blocks apart
    seeds = {}
    seed_args = []
    for aname, syms in (("dq", m.q), ("du", m.u), ("dr", m.r),
                        ("dqd", Qd if (m.mv and qd_model) else [])):
        tang = tuple(sm.Dummy(f"{aname}{i}") for i in range(len(syms)))
        seeds.update(zip(syms, tang))
        seed_args.append(Arg(aname, tang))
    funcs = [("jkin", kin_res), ("jR", R)]
    if m.mv:
        funcs += [("jS", S), ("jV", m.A * U + m.b)]
    if m.mc:
        funcs.append(("jJc", m.fc))
    kernels["lin_plain"] = make_kernel("lin_plain", lin_args, plain)
    kernels["lin_jvp"] = make_jvp_kernel("lin_jvp", lin_args + seed_args, funcs, seeds)
    return kernels


# the derivative kernels (build_kernels(..., derivatives=True) adds them):
# the C backend compiles them apart, in <name>_lin.c
DERIVATIVE_KERNELS = ("lin_terms", "lin_plain", "lin_jvp", "output_jacobian", "reaction_lin")


@dataclass
class Plan:
    """What the generator will write for a model: its kernels, the
    structure of its mass matrix and the solver its accelerations use
    (decided here, carried out by the runtime). derivatives: whether the
    derivative kernels are among the kernels; lin: how they are (or would
    be) generated, "unrolled" or "jvp"."""
    model: object
    kernels: dict
    mass_symmetric: bool
    mass_nonzero: list
    accel: str          # "partitioned", "kkt", "ldlt" (unrolled for this M) or "lu"
    derivatives: bool = True
    lin: str = "unrolled"
    inputs: KernelInputs | None = None     # kept for with_derivatives


def accel_method(model, mass_symmetric):
    """Kane with velocity constraints: the partitioned solve (dependent
    speeds eliminated); Lagrange with constraints: the KKT system; no
    constraints: an LDL^T unrolled over M's pattern when M is symmetric,
    else pivoted LU; reactions inside the motion (model.aux_G): "lu", the
    plan's name for the runtime's general path, where the model's
    reaction_solve takes u' and the reactions from one LU solve."""
    if model.mv:
        return "partitioned" if model.method == "kane" else "kkt"
    if getattr(model, "aux_G", None) is not None:
        # reactions inside the motion: u' and the reactions from one LU
        # solve (the model's reaction_solve; gen_rt_accel_reactions)
        return "lu"
    return "ldlt" if mass_symmetric else "lu"


def lin_mode(model, lin="auto"):
    """"unrolled" or "jvp": how a model's Jacobian blocks are generated
    (lin="auto" chooses by JVP_MIN_VARIABLES)."""
    if lin == "auto":
        return "jvp" if model.nq + model.nu + model.nr >= JVP_MIN_VARIABLES else "unrolled"
    if lin not in ("unrolled", "jvp"):
        raise ValueError(f"lin must be 'auto', 'unrolled' or 'jvp', got {lin!r}")
    return lin


def plan(model, lin="auto", derivatives=True):
    """The Plan of a canonical model (nothing is stored on the model).
    lin: how the Jacobian blocks are generated (build_kernels);
    derivatives=False: without the derivative kernels (with_derivatives adds
    them later)."""
    symmetric, nonzero = mass_structure(model)
    mode = lin_mode(model, lin)
    inputs = kernel_inputs(model, symmetric)
    kernels = build_kernels(model, lin=mode, derivatives=derivatives, inputs=inputs)
    return Plan(model, kernels, symmetric, nonzero, accel_method(model, symmetric),
                derivatives=derivatives, lin=mode, inputs=inputs)


def with_derivatives(p):
    """The Plan p with its derivative kernels (p itself when it has them):
    the same kernels otherwise, so the sources it renders differ from p's
    only by the derivative kernels."""
    if p.derivatives:
        return p
    inputs = p.inputs or kernel_inputs(p.model, p.mass_symmetric)
    kernels = dict(p.kernels)
    kernels.update(derivative_kernels(inputs, p.lin))
    return Plan(p.model, kernels, p.mass_symmetric, p.mass_nonzero, p.accel,
                derivatives=True, lin=p.lin, inputs=inputs)


def prune(kernel):
    """Drop temporaries that no output needs (dead code would trip
    -Wunused-variable)."""
    needed = set()
    for o in kernel.outputs:
        for e in o.exprs:
            needed |= e.free_symbols
    keep = []
    for s, e in reversed(kernel.assignments):
        if s in needed:
            keep.append((s, e))
            needed |= e.free_symbols
    kernel.assignments = list(reversed(keep))
    return kernel
