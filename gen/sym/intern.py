"""Per-build interning of opaque expression nodes.

A recursive build (:mod:`gen.intake.recursive`) keeps each body's quantities
as opaque nodes (sympy ``UnevaluatedExpr``): sums and products built on them
keep them as one argument instead of flattening their terms into theirs, so
the expression graph stays a few nodes per body where flattened trees grow
with the depth. Such graphs are cheap only under two rules, which an
:class:`Interner` keeps:

- within a build, equal nodes are one object (its table): sympy's ``==``
  (dict lookups, its cache, CSE) then compares two nodes through identical
  arguments, never down two equal copies of the graph below them (a walk
  that grows exponentially with the depth);
- nodes of different builds are never equal: each Interner makes its nodes
  of a class of its own (named ``UnevaluatedExpr``, so that sympy prints,
  orders and hashes them as before), and sympy's ``==`` is False at once
  between different classes. A node of an earlier build left in sympy's
  process-wide cache, or one of a build running in another thread, is thus
  never compared down its graph with a new one (which is why the recursive
  builds used to clear sympy's cache, and why two of them in threads
  interfered).

An Interner lives for one build: the caller makes one, passes it to the
functions of that build, and drops it with the build; nothing outlives it but
the nodes, which carry their build's class through every rewrite
(``node.func(*args)`` is the same class). ``gen.plan.ir`` unwraps them after
its CSE (any ``UnevaluatedExpr``); :class:`Kept` is the base of their classes.
"""
from __future__ import annotations

import itertools

import sympy as sm

from .dag import from_args

__all__ = ["Interner", "Kept"]

_BUILDS = itertools.count(1)     # numbers the builds (next() is atomic)


class Kept(sm.UnevaluatedExpr):
    """The base class of every Interner's node class (an ``UnevaluatedExpr``
    of one build)."""

    _build = 0          # the build's number, in the hash
    # a scalar: products of nodes are commutative ones (sympy takes an
    # UnevaluatedExpr of unknown commutativity as a matrix-like factor, and
    # a non-commutative Mul is flattened and rebuilt the slow way: Talos's
    # build 4.3 -> 3.7 s of CPU, its kernels the same)
    is_commutative = True

    def __hash__(self):
        # equal nodes of different builds (never ==) hash apart: the entries
        # an earlier build left in sympy's cache do not share their slots
        h = self._mhash
        if h is None:
            h = self._mhash = hash((type(self).__name__, self._build) + self._hashable_content())
        return h

    def __reduce_ex__(self, protocol):
        # the build's class is made at run time: pickled, a node is a plain
        # UnevaluatedExpr (equal values, no build)
        return (sm.UnevaluatedExpr, self.args)


class Interner:
    """The opaque nodes of one build, equal nodes one object.

    Attributes
    ----------
    node : type
        This build's node class (a :class:`Kept` subclass named
        ``UnevaluatedExpr``).
    """

    def __init__(self):
        self.node = type("UnevaluatedExpr", (Kept,), {"__module__": __name__,
                                                     "__qualname__": "Kept.UnevaluatedExpr",
                                                     "_build": next(_BUILDS)})
        self._table = {}

    def __len__(self):
        return len(self._table)

    def keep(self, e):
        """e as one opaque node of this build: sums and products built on it
        keep it as one argument (a graph linear in the bodies). Atoms, nodes
        already kept and a number times an atom stay as they are."""
        if e.is_Atom or isinstance(e, sm.UnevaluatedExpr) or (
                e.is_Mul and len(e.args) == 2 and e.args[0].is_Number and e.args[1].is_Atom):
            return e
        node = self.node(self.intern(e))
        return self._table.setdefault(node, node)

    def intern(self, e):
        """e with every subexpression (down to the opaque nodes) one object
        per value: equal products built apart (the two sides of a symmetric
        matrix, a cross product's terms) would make sympy's == and its cache
        compare down two equal copies of the graph below them."""
        if e.is_Atom or isinstance(e, sm.UnevaluatedExpr):
            return e
        args = tuple(self.intern(a) for a in e.args)
        if any(a is not b for a, b in zip(args, e.args)):
            # equal arguments: the same canonical form, not re-flattened (a
            # sum's flatten would make its products anew)
            e = rebuild_canonical(e, args)
        return self._table.setdefault(e, e)

    def kept(self, mat):
        """Every entry of mat kept (:meth:`keep`)."""
        return mat.applyfunc(self.keep)

    def sym_kept(self, mat):
        """A symmetric matrix kept from its lower triangle (one node per
        pair)."""
        n = mat.shape[0]
        low = {(i, j): self.keep(mat[i, j]) for i in range(n) for j in range(i + 1)}
        return sm.Matrix(n, n, lambda i, j: low[max(i, j), min(i, j)])


def rebuild_canonical(e, args):
    """e's node over new arguments equal to its own: a sum or product kept
    in the order it has, not flattened again (:func:`gen.sym.dag.from_args`);
    any other node through its class."""
    if e.is_Add or e.is_Mul:
        return from_args(e.func, args, e.is_commutative)
    return e.func(*args)
