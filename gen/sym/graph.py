"""Differentiation and evaluation of sympy expression graphs: each distinct
subexpression visited once, so the work stays the size of the graph as
models grow.

Non-smooth functions are differentiated almost everywhere (``partial``),
never into sympy's ``DiracDelta``, ``Derivative(sign(x), x)`` or
``re``/``im`` terms, which no printer can print:

    d Abs(a)       = sign(a) da                      (0 at a = 0)
    d sign(a)      = d Heaviside(a) = d floor(a) = d ceiling(a) = 0
    d Max(a, b)    = a > b ? da : (a < b ? db : (da + db)/2)   (Min: a < b ? ...)
    d Mod(a, b)    = da - floor(a/b) db
    d Piecewise((e1, c1), ..., (en, True)) = Piecewise((de1, c1), ..., (den, True))

At a kink the value is the mean of the one-sided derivatives for Abs, Min
and Max, zero at the jumps of sign, Heaviside, floor and ceiling, and the
derivative of the selected branch for Piecewise. Expressions without these
functions are differentiated by sympy's ``diff``, unchanged.

    partial(e, x)                      # d e / d x
    gradient(e, symbols)               # {x: d e / d x}, one reverse sweep
    differentiate_graph(assign, exprs, wrt)   # forward mode over a CSE'd list
    jvp_graph(assign, exprs, seeds)           # directional derivatives
    float_values(exprs, {x: 1.0})      # double-precision values (NoFloat: unknown node)
"""
from __future__ import annotations

import sympy as sm

__all__ = ["Namer", "NONSMOOTH", "partial", "gradient", "differentiate_graph", "jvp_graph",
           "float_values", "free_symbols", "NoFloat"]


class Namer:
    def __init__(self, prefix):
        self.prefix = prefix
        self.i = 0

    def __iter__(self):
        return self

    def __next__(self):
        s = sm.Symbol(f"{self.prefix}{self.i}")
        self.i += 1
        return s



NONSMOOTH = (sm.Abs, sm.sign, sm.Heaviside, sm.floor, sm.ceiling, sm.Min, sm.Max,
              sm.Piecewise, sm.Mod)



_ZERO_DERIVATIVE = (sm.sign, sm.Heaviside, sm.floor, sm.ceiling)



def partial(expr, s):
    """d expr / d s, almost everywhere (the rules in the module docstring).
    Subexpressions free of non-smooth functions go to sympy's diff."""
    memo = {}

    def d(e):
        if e == s:
            return sm.S.One
        if e.is_Atom or not e.has(s):
            return sm.S.Zero
        if not e.has(*NONSMOOTH):
            return e.diff(s)
        hit = memo.get(e)
        if hit is not None:
            return hit
        memo[e] = out = rule(e)
        return out

    def rule(e):
        if e.is_Add:
            return sm.Add(*[d(a) for a in e.args])
        if e.is_Mul:
            terms = []
            for i, a in enumerate(e.args):
                da = d(a)
                if da != 0:
                    terms.append(sm.Mul(*(e.args[:i] + (da,) + e.args[i + 1:])))
            return sm.Add(*terms)
        if e.is_Pow:
            b, x = e.args
            db, dx = d(b), d(x)
            out = sm.S.Zero
            if db != 0:
                out += x * b**(x - 1) * db
            if dx != 0:
                out += e * sm.log(b) * dx
            return out
        if isinstance(e, sm.Abs):
            return sm.sign(e.args[0]) * d(e.args[0])
        if isinstance(e, _ZERO_DERIVATIVE):
            return sm.S.Zero
        if isinstance(e, (sm.Min, sm.Max)):
            a = e.args[0]
            rest = e.args[1] if len(e.args) == 2 else e.func(*e.args[1:])
            da, dr = d(a), d(rest)
            if da == dr:
                return da
            first, second = (a > rest, a < rest) if isinstance(e, sm.Max) else (a < rest, a > rest)
            return sm.Piecewise((da, first), (dr, second), ((da + dr) / 2, True))
        if isinstance(e, sm.Piecewise):
            return sm.Piecewise(*[(d(x), c) for x, c in e.args])
        if isinstance(e, sm.Mod):
            a, b = e.args
            return d(a) - sm.floor(a / b) * d(b)
        if isinstance(e, sm.Function):
            # chain rule through a smooth function of non-smooth arguments
            out = sm.S.Zero
            for i, a in enumerate(e.args):
                da = d(a)
                if da != 0:
                    out += e.fdiff(i + 1) * da
            return out
        return e.diff(s)

    return d(expr)



def gradient(e, symbols):
    """{s: d e / d s} for the symbols s of ``symbols`` that e holds, by one
    reverse sweep over e's expression graph (each distinct subexpression
    once): linear in e's size, where a derivative per symbol walks all of e
    again (a CSE'd assignment can be a long sum). Holds the rules of
    ``partial``: an expression with a non-smooth function goes to it, symbol
    by symbol."""
    symbols = set(symbols)
    if e.has(*NONSMOOTH):
        return {x: partial(e, x) for x in symbols if e.has(x)}
    dep, order, stack = {}, [], [(e, False)]
    while stack:                          # post-order: children before parents
        x, done = stack.pop()
        if done:
            dep[x] = x in symbols or any(dep.get(c, False) for c in x.args)
            order.append(x)
            continue
        if x in dep:
            continue
        dep[x] = False                    # visiting
        stack.append((x, True))
        if not x.is_Atom:
            stack.extend((c, False) for c in x.args if c not in dep)
    if not dep.get(e):
        return {}
    adj = {e: [sm.S.One]}
    out = {}
    for x in reversed(order):             # parents before children
        terms = adj.pop(x, None)
        if not terms or not dep[x]:
            continue
        a = sm.Add(*terms)
        if x in symbols:
            out[x] = a
            continue
        args = x.args
        if x.is_Add:
            for c in args:
                if dep[c]:
                    adj.setdefault(c, []).append(a)
        elif x.is_Mul:
            for i, c in enumerate(args):
                if dep[c]:
                    adj.setdefault(c, []).append(a * sm.Mul(*(args[:i] + args[i + 1:])))
        elif x.is_Pow:
            b, k = args
            if dep[b]:
                adj.setdefault(b, []).append(a * k * b ** (k - 1))
            if dep[k]:
                adj.setdefault(k, []).append(a * x * sm.log(b))
        elif isinstance(x, sm.Function):
            for i, c in enumerate(args):
                if dep[c]:
                    adj.setdefault(c, []).append(a * x.fdiff(i + 1))
        else:                             # anything else: sympy's rules
            return {s_: partial(e, s_) for s_ in symbols if e.has(s_)}
    return out



def differentiate_graph(assignments, exprs, wrt, prefix="d"):
    """Forward-mode derivatives of ``exprs`` (written over the temporaries
    of ``assignments``) with respect to the symbols ``wrt``.

    Returns (new_assignments, jac) where new_assignments extend the primal
    list with derivative temporaries, and jac[i][j] = d exprs[i] / d wrt[j].
    Primal subexpressions that reappear in a derivative are replaced by
    their temporaries (so d sqrt(w3) reuses w4 = sqrt(w3))."""
    namer = Namer(prefix)
    widx = {v: j for j, v in enumerate(wrt)}
    reverse = {}
    for s, e in assignments:
        if not e.is_Atom:
            reverse.setdefault(e, s)
    deriv = {}                  # temp -> {j: symbol or expr}
    new = []

    def dexpr(e):
        """{j: d e / d wrt[j]} for an expression over wrt and temps."""
        syms = sorted((x for x in e.free_symbols if x in widx or deriv.get(x)),
                      key=sm.default_sort_key)
        if not syms:
            return {}
        grad = gradient(e, syms)
        terms = {}
        for x in syms:
            pd = grad.get(x, sm.S.Zero)
            if pd == 0:
                continue
            if x in widx:
                terms.setdefault(widx[x], []).append(pd)
            else:
                for j, dx in deriv[x].items():
                    terms.setdefault(j, []).append(pd * dx)
        res = {}
        for j in sorted(terms):
            v = sm.Add(*terms[j])
            if v != 0:
                res[j] = v.xreplace(reverse) if reverse else v
        return res

    for s, e in assignments:
        d = dexpr(e)
        entry = {}
        for j, v in d.items():
            if v.is_Atom:
                entry[j] = v
            else:
                ds = next(namer)
                new.append((ds, v))
                entry[j] = ds
        deriv[s] = entry
    jac = []
    for e in exprs:
        d = dexpr(e)
        jac.append([d.get(j, sm.S.Zero) for j in range(len(wrt))])
    return new, jac



def jvp_graph(assignments, exprs, seeds, prefix="t"):
    """Forward-mode directional derivatives (one tangent per temporary):
    the derivative of ``exprs`` (written over the temporaries of
    ``assignments``) along the direction ``seeds`` {variable: tangent
    symbol}. Returns (new_assignments, tangents of exprs). The tangent graph
    is a few times the size of the primal one, whatever the number of
    variables (differentiate_graph's is that many times larger)."""
    namer = Namer(prefix)
    reverse = {}
    for s, e in assignments:
        if not e.is_Atom:
            reverse.setdefault(e, s)
    tangent = {}                 # temporary -> tangent symbol
    new = []

    def dexpr(e):
        syms = sorted((a for a in e.free_symbols if a in seeds or a in tangent),
                      key=sm.default_sort_key)
        if not syms:
            return sm.S.Zero
        grad = gradient(e, syms)
        terms = []
        for a in syms:
            pd = grad.get(a, sm.S.Zero)
            if pd != 0:
                terms.append(pd * seeds.get(a, tangent.get(a)))
        out = sm.Add(*terms)
        return out.xreplace(reverse) if reverse and out != 0 else out

    for s, e in assignments:
        d = dexpr(e)
        if d == 0:
            continue
        if d.is_Atom:
            tangent[s] = d
        else:
            ts = next(namer)
            new.append((ts, d))
            tangent[s] = ts
    return new, [dexpr(e) for e in exprs]



# --------------------------------------------------------------------------
# sympy functions the fast float evaluator knows (anything else: the slow,
# exact path of mass_structure)
def _float_functions():
    import math

    def sign(v):
        return (v > 0) - (v < 0)
    return {sm.sin: math.sin, sm.cos: math.cos, sm.tan: math.tan, sm.asin: math.asin,
            sm.acos: math.acos, sm.atan: math.atan, sm.atan2: math.atan2, sm.sinh: math.sinh,
            sm.cosh: math.cosh, sm.tanh: math.tanh, sm.exp: math.exp, sm.log: math.log,
            sm.Abs: abs, sm.sign: sign, sm.floor: math.floor, sm.ceiling: math.ceil,
            sm.Min: min, sm.Max: max}



class NoFloat(Exception):
    """An expression the fast float evaluator does not handle."""



def float_values(exprs, values):
    """The float values of sympy expressions at {symbol: float}: a walk of
    the expression graph in double precision (each shared subexpression
    once), far faster than xreplace + evalf on large mass matrices. Raises
    NoFloat for a node it does not know or a value that is not a finite
    real (the caller falls back to sympy)."""
    import math
    funcs = _float_functions()
    memo = {}

    def ev(e):
        hit = memo.get(e)
        if hit is not None:
            return hit
        if e.is_Number:
            v = float(e)
        elif e.is_Symbol:
            try:
                v = values[e]
            except KeyError:
                raise NoFloat(e) from None
        elif e.is_Add:
            v = 0.0
            for a in e.args:
                v += ev(a)
        elif e.is_Mul:
            v = 1.0
            for a in e.args:
                v *= ev(a)
        elif e.is_Pow:
            v = ev(e.args[0]) ** ev(e.args[1])
        elif isinstance(e, sm.UnevaluatedExpr):     # opaque nodes (gen.sym.intern)
            v = ev(e.args[0])
        else:
            fn = funcs.get(type(e))
            if fn is None:
                raise NoFloat(e)
            v = fn(*[ev(a) for a in e.args])
        if not isinstance(v, (int, float)) or not math.isfinite(v):
            raise NoFloat(e)
        memo[e] = v = float(v)
        return v

    try:
        return [ev(e) for e in exprs]
    except (ZeroDivisionError, OverflowError, ValueError, TypeError, RecursionError) as err:
        raise NoFloat(err) from None



def free_symbols(exprs):
    """The free symbols of exprs (no bound variables in a model's
    matrices), each distinct subexpression visited once."""
    seen, out, stack = set(), set(), list(exprs)
    while stack:
        e = stack.pop()
        if e in seen:
            continue
        seen.add(e)
        if e.is_Symbol:
            out.add(e)
        stack.extend(e.args)
    return out
