"""Walks and rewrites of expression graphs whose subexpressions are shared.

sympy's own walks (``xreplace``, ``has``, ``free_symbols``, ``srepr``) treat
an expression as a tree: a subexpression that appears many times is visited
every time. Kane's mass matrix and forcing repeat theirs many times, and the
recursive formulation's graphs (:mod:`gen.sym.intern`) are built to be
shared, so that unfolded as trees they grow far faster than as graphs. Each
function here visits each distinct subexpression once.
"""
from __future__ import annotations

from functools import cmp_to_key

import sympy as sm

__all__ = ["xreplace_shared", "scan", "graph_srepr", "memo_any", "has_kind", "has_any",
           "from_args"]

# sympy's canonical order of the arguments of a sum or product (what
# sympy.core.basic._args_sortkey is)
_ARGS_SORTKEY = cmp_to_key(sm.Basic.compare)
_ID_MEMO, _CONS_MEMO = object(), object()


def from_args(cls, args, commutative):
    """The sum or product cls (``Add``, ``Mul``) of args taken as they are,
    in this order, without sympy's flatten (sympy's private constructor
    ``cls._from_args``: the one read of a sympy private name in gen.sym,
    checked on sympy 1.14). For arguments already in canonical form and
    order, the object sympy's own constructor would build."""
    return cls._from_args(args, commutative)


def xreplace_shared(mat, rule, memo):
    """mat.xreplace(rule), each distinct subexpression rebuilt once (memo,
    shared between calls): sympy's xreplace rebuilds a subexpression every
    time it appears, and Kane's M and f repeat theirs many times.

    When rule maps atoms and functions of time one to one onto new symbols
    (atomic), a sum or product cannot combine terms that were apart (distinct
    terms stay distinct), so it is rebuilt from its new arguments in sympy's
    canonical order (numbers first, then sorted as Add and Mul sort them)
    without re-running their flatten: the same objects, most of the cost
    gone (tests/unit/sym/test_dag.py)."""
    if not rule or not mat.shape[0] * mat.shape[1]:
        return mat
    atomic = (len(set(rule.values())) == len(rule)
              and all(v.is_Symbol for v in rule.values()))

    def rebuild(e, args):
        if atomic and (e.is_Add or e.is_Mul) and e.is_commutative:
            nums = [a for a in args if a.is_Number]
            rest = [a for a in args if not a.is_Number]
            rest.sort(key=_ARGS_SORTKEY)
            return from_args(e.func, nums + rest, True)
        return e.func(*args)

    # memo and the rebuilt nodes keyed by object identity: two equal but
    # distinct deep subexpressions (the recursive formulation's graphs once
    # sympy's LRU cache has dropped the one that made them identical) are never compared
    # with sympy's ==, which walks shared nodes as a tree (exponential); equal
    # rebuilt nodes are made one object (hash-consed by their arguments' ids)
    ids = memo.setdefault(_ID_MEMO, {})
    cons = memo.setdefault(_CONS_MEMO, {})

    def walk(e):
        hit = ids.get(id(e))
        if hit is not None:
            return hit[1]
        if not e.args:
            out = rule.get(e, e)
        elif e in rule:
            out = rule[e]
        else:
            args = [walk(a) if isinstance(a, sm.Basic) else a for a in e.args]
            if any(a is not b for a, b in zip(args, e.args)):
                key = (e.func, tuple(a if not isinstance(a, sm.Basic) or not a.args else id(a)
                                     for a in args))
                out = cons.get(key)
                if out is None:
                    out = rebuild(e, args)
                    cons[key] = out
            else:
                out = e
        ids[id(e)] = (e, out)
        return out

    return sm.Matrix(mat.shape[0], mat.shape[1], [walk(e) for e in mat])


def scan(exprs):
    """(free symbols, derivatives, undefined functions) of expressions (a
    matrix's entries), each distinct subexpression visited once."""
    free, derivs, undef = set(), set(), set()
    seen = set()
    stack = list(exprs)
    while stack:
        e = stack.pop()
        if e in seen:
            continue
        seen.add(e)
        if e.is_Symbol:
            free.add(e)
            continue
        if isinstance(e, sm.Derivative):
            derivs.add(e)
        elif isinstance(e, sm.core.function.AppliedUndef):
            undef.add(e)
        stack.extend(a for a in e.args if isinstance(a, sm.Basic))
    return free, derivs, undef


def graph_srepr(mat, sub):
    """sm.srepr(mat.xreplace(sub)); for matrices holding shared opaque nodes
    (UnevaluatedExpr, :mod:`gen.sym.intern`), whose trees unfolded grow far
    faster than their graphs, the graph instead: one line per distinct
    subexpression, its arguments by number."""
    if not any(has_kind(list(mat), sm.UnevaluatedExpr)):
        return sm.srepr(mat.xreplace(sub))
    ids, lines = {}, []
    for root in mat:
        stack = [(root, False)]
        while stack:
            e, done = stack.pop()
            if e in ids:
                continue
            if done or not e.args:
                ids[e] = len(ids)
                lines.append(sm.srepr(sub.get(e, e)) if not e.args else
                             f"{type(e).__name__}({','.join(str(ids[a]) for a in e.args)})")
                continue
            stack.append((e, True))
            stack.extend((a, False) for a in reversed(e.args) if a not in ids)
        lines.append(f"={ids[root]}")
    return f"{mat.shape}" + ";".join(lines)


def memo_any(exprs, leaf):
    """[whether e holds a node for which leaf(node) is True, for e in exprs]:
    leaf returns True or False to decide a node, None to look inside it;
    each distinct subexpression visited once (sympy's has walks a shared
    subexpression every time it appears)."""
    memo, out = {}, []
    for root in exprs:
        stack = [(root, False)]
        while stack:
            e, done = stack.pop()
            if done:
                memo[e] = any(memo[a] for a in e.args)
                continue
            if e in memo:
                continue
            hit = leaf(e)
            if hit is not None:
                memo[e] = hit
                continue
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if a not in memo)
        out.append(memo[root])
    return out


def has_kind(exprs, kind):
    """[whether e holds a node of class kind for e in exprs]."""
    return memo_any(exprs, lambda e: True if isinstance(e, kind) else
                    (False if not e.args else None))


def has_any(exprs, targets):
    """[e.has(*targets) for e in exprs] for atomic targets (symbols)."""
    targets = set(targets)
    if not targets:
        return [False for _ in exprs]
    return memo_any(exprs, lambda e: None if e.args else e in targets)
