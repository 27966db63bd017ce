"""Structural dependencies of a model's unknowns on its knowns, from the
canonical model's expressions (no numbers): what an FMU's ModelStructure
declares, and what a sparse Jacobian of the independent-state ODE may use.

The knowns are the independent state [q_ind, u_ind] (the continuous states
of a Model Exchange FMU), the inputs r and the constants p. Everything else
is an implicit function of them, and its dependencies are followed through:

    q_dep     f_c(q_ind, q_dep, t) = 0            (Newton at run time)
    u_dep     A(q) u + b(q, t) = 0                (linear solve)
    q'        Kqd(q) q' + Ku(q) u + kf(q, t) = 0  (explicit or LU)
    u', lam   M(q) u' = f(q, u, r, t) + A^T lam,  A u' + a(q, u, q', t) = 0

A solve couples what its matrix couples: the unknowns of a linear or
nonlinear system depend on everything in the rows of the connected block
(of the matrix's structural pattern) they belong to, so a block-diagonal
mass matrix gives separate blocks, and a constrained system couples the
speeds each constraint row touches. The result is a superset of the true
dependencies (a structural nonzero may cancel numerically), never less.

    deps = dependencies(model)
    deps.derivative[k]    # frozenset of knowns of d/dt of independent state k
    deps.output[k]        # of the model's output y[k]
    deps.multiplier[k], deps.constraint[k], deps.velocity_constraint[k]

A known is ("x", i) (i: index into the full state x = [q, u] of an
independent entry), ("r", k) or ("p", j).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sm

__all__ = ["Dependencies", "dependencies"]


@dataclass(frozen=True)
class Dependencies:
    independent: tuple          # full-state index of each independent state entry
    derivative: tuple           # per independent entry: frozenset of knowns
    output: tuple               # per model output y
    multiplier: tuple           # per velocity constraint (lam)
    constraint: tuple           # per configuration constraint residual f_c
    velocity_constraint: tuple  # per velocity constraint residual A u + b


def _blocks(rows, cols, entries):
    """Connected blocks of a structural pattern: rows and cols are lists of
    ids, entries the (row, col) nonzeros. Returns {id: block number}."""
    parent = {}

    def find(a):
        parent.setdefault(a, a)
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a in list(rows) + list(cols):
        find(a)
    for r, c in entries:
        ra, rb = find(r), find(c)
        if ra != rb:
            parent[ra] = rb
    return {a: find(a) for a in list(rows) + list(cols)}


def dependencies(model) -> Dependencies:
    """The structural dependencies of a gen.Model (see the module docstring)."""
    m = model
    nq, nu = m.nq, m.nu
    known = _Knowns(m)
    _dependent_coordinates(m, known)
    _dependent_speeds(m, known)
    qd_known = _rates(m, known)
    for j, s in enumerate(m.qd):           # q' symbols in the acceleration term
        known[s] = qd_known[j]
    ud_known, lam_known = _accelerations(m, known)
    of = known.of
    independent = tuple(list(m.q_ind) + [nq + j for j in m.u_ind])
    derivative = tuple(qd_known[i] if i < nq else ud_known[i - nq] for i in independent)
    output = tuple(of([m.y[k]]) for k in range(m.ny))
    constraint = tuple(of([m.fc[i]]) for i in range(m.mc))
    velocity = tuple(of([m.b[i]] + [m.A[i, j] * m.u[j] for j in range(nu)])
                     for i in range(m.mv))
    return Dependencies(independent, derivative, output, lam_known, constraint, velocity)


class _Knowns(dict):
    """symbol -> frozenset of the knowns it depends on, starting with the
    knowns themselves (the independent state, inputs, constants; t depends
    on nothing)."""

    def __init__(self, m):
        super().__init__()
        for i in m.q_ind:
            self[m.q[i]] = frozenset({("x", i)})
        for j in m.u_ind:
            self[m.u[j]] = frozenset({("x", m.nq + j)})
        for k, s in enumerate(m.r):
            self[s] = frozenset({("r", k)})
        for k, s in enumerate(m.p):
            self[s] = frozenset({("p", k)})
        self[m.t] = frozenset()

    def of(self, exprs):
        """Knowns of expressions whose symbols are resolved so far."""
        out = set()
        for e in exprs:
            for s in sm.sympify(e).free_symbols:
                if s not in self:
                    raise AssertionError(f"dependency of {s} not resolved yet")
                out |= self[s]
        return frozenset(out)


def _nonzero(e):
    return sm.sympify(e) != 0


def _dependent_coordinates(m, known):
    """q_dep: f_c(q_ind, q_dep) = 0, block by block over the rows and the
    dependent coordinates they hold."""
    if not m.q_dep:
        return
    dep_syms = [m.q[i] for i in m.q_dep]
    resolved_q = {m.q[i] for i in m.q_ind} | set(m.r) | set(m.p) | {m.t}
    ids_rows = [("row", i) for i in range(m.mc)]
    entries = [(("row", i), s) for i in range(m.mc) for s in dep_syms if m.fc[i].has(s)]
    block = _blocks(ids_rows, dep_syms, entries)
    for s in dep_syms:
        rows = [m.fc[i] for i in range(m.mc) if block[("row", i)] == block[s]]
        syms = set().union(*(sm.sympify(e).free_symbols for e in rows)) if rows else set()
        known[s] = known.of([x for x in syms if x in resolved_q])


def _dependent_speeds(m, known):
    """u_dep: A u + b = 0 solved for the dependent speeds, block by block."""
    if not m.u_dep:
        return
    dep_syms = [m.u[j] for j in m.u_dep]
    ids_rows = [("row", i) for i in range(m.mv)]
    entries = [(("row", i), m.u[j]) for i in range(m.mv) for j in m.u_dep
               if _nonzero(m.A[i, j])]
    block = _blocks(ids_rows, dep_syms, entries)
    for s in dep_syms:
        rows = [i for i in range(m.mv) if block[("row", i)] == block[s]]
        exprs = [m.b[i] for i in rows] + [m.A[i, j] for i in rows for j in range(m.nu)]
        exprs += [m.u[j] for i in rows for j in m.u_ind if _nonzero(m.A[i, j])]
        known[s] = known.of(exprs)


def _rates(m, known):
    """The knowns of each q': explicit, or Kqd q' = -(Ku u + kf) block by
    block."""
    nq, nu = m.nq, m.nu
    if m.qdot is not None:
        return [known.of([m.qdot[i]]) for i in range(nq)]
    qd_known = [None] * nq
    ids_rows = [("row", i) for i in range(nq)]
    cols = [("qd", j) for j in range(nq)]
    entries = [(("row", i), ("qd", j)) for i in range(nq) for j in range(nq)
               if _nonzero(m.Kqd[i, j])]
    block = _blocks(ids_rows, cols, entries)
    for j in range(nq):
        rows = [i for i in range(nq) if block[("row", i)] == block[("qd", j)]]
        exprs = [m.Kqd[i, k] for i in rows for k in range(nq)]
        exprs += [m.Ku[i, k] for i in rows for k in range(nu)]
        exprs += [m.kf[i] for i in rows]
        exprs += [m.u[k] for i in rows for k in range(nu) if _nonzero(m.Ku[i, k])]
        qd_known[j] = known.of(exprs)
    return qd_known


def _accelerations(m, known):
    """(knowns of each u', of each multiplier): the KKT system, block by
    block over the speeds (coupled by M's pattern) and the constraint rows
    (coupling the speeds they touch)."""
    nu = m.nu
    speeds = [("u", j) for j in range(nu)]
    rows = [("con", i) for i in range(m.mv)]
    entries = [(("u", i), ("u", j)) for i in range(nu) for j in range(nu)
               if i != j and (_nonzero(m.M[i, j]) or _nonzero(m.M[j, i]))]
    entries += [(("con", i), ("u", j)) for i in range(m.mv) for j in range(nu)
                if _nonzero(m.A[i, j])]
    block = _blocks(rows, speeds, entries)
    block_known = {}
    for b in set(block.values()):
        us = [j for j in range(nu) if block[("u", j)] == b]
        cs = [i for i in range(m.mv) if block[("con", i)] == b]
        exprs = [m.M[i, j] for i in us for j in range(nu)] + [m.f[i] for i in us]
        exprs += [m.A[i, j] for i in cs for j in range(nu)] + [m.a[i] for i in cs]
        block_known[b] = known.of(exprs)
    ud_known = [block_known[block[("u", j)]] for j in range(nu)]
    lam_known = tuple(block_known[block[("con", i)]] for i in range(m.mv))
    return ud_known, lam_known
