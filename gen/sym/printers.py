"""C99 and C++ printers for kernel bodies, and the check that a model's
expressions can be printed at all.

Every model symbol is printed as an array element (``q[0]``) or a
temporary, never under its sympy name (../shared/NOTES-sympy.md 5), so
hostile names cannot reach the C code. ``strict=True``: an expression the
printer cannot print is an error, never a comment that compiles.

Non-smooth functions print exactly, with sympy's values everywhere
(double / float / C++ over the template ``Scalar``):

    Abs(x)          fabs(x)  fabsf(x)  std::fabs(x)
    sign(x)         ((x) > 0 ? 1.0 : ((x) < 0 ? -1.0 : 0.0))     sign(0) = 0
    Heaviside(x)    ((x) > 0 ? 1.0 : ((x) < 0 ? 0.0 : H0))       H0 = 1/2 unless given
    floor, ceiling  floor/floorf/std::floor, ceil/ceilf/std::ceil
    Min, Max        fmin/fminf/std::fmin, fmax/fmaxf/std::fmax (nested when n > 2)
    Mod(a, b)       ((a) - (b)*floor((a)/(b)))                    sympy's sign convention
    Piecewise       ((c1) ? (e1) : ((c2) ? (e2) : (e3)))          needs a (e, True) default
    relations       (a > b), (a == b), ...; And/Or/Not as &&, ||, !

(no ``copysign``: it would give sign(0) = +-1). The linearization
differentiates them almost everywhere (``gen.sym.graph.partial``): d|x| = sign(x),
d sign = d Heaviside = d floor = d ceiling = 0, d Min/Max = the active
argument's derivative, d Piecewise = the Piecewise of the branch
derivatives. At a kink the linearization returns the mean of the two
one-sided derivatives for Abs, Min and Max (d|x|/dx = sign(0) = 0 at
x = 0: what a symmetric central difference gives), 0 for sign, Heaviside,
floor and ceiling at their jumps (the derivative away from the jump; the
Dirac part is dropped), and for Piecewise the derivative of the branch
whose condition holds at the point (the branch that gives the value).

:func:`unprintable` finds what the generator cannot print or
differentiate; :func:`check_printable` turns it into a ``ModelError``
naming the user's expression, when the model is created.
"""
from __future__ import annotations

import functools

import sympy as sm
from sympy.codegen.ast import float32, float64, real
from sympy.core.function import AppliedUndef
from sympy.logic.boolalg import BooleanAtom
from sympy.printing.c import C99CodePrinter

from ..core.errors import ModelError

__all__ = ["ModelCPrinter", "ModelCxxPrinter", "print_kernel_body", "unprintable",
           "check_printable"]


class ModelCPrinter(C99CodePrinter):
    """C99 printer with a symbol map and a chosen scalar type."""

    def __init__(self, symbol_map, real_type="double"):
        if real_type not in ("double", "float"):
            raise ModelError(f"real type must be 'double' or 'float', got {real_type!r}")
        # math_macros off: M_LN2, M_SQRT2, ... are not C99 and are double
        # constants (a silent promotion in float code); log(2) prints as log(2)
        settings = {"strict": True, "math_macros": {},
                    "type_aliases": {real: float32 if real_type == "float" else float64}}
        super().__init__(settings)
        self.symbol_map = symbol_map
        self.real_type = real_type

    def _lit(self, text):
        return text + ("F" if self.real_type == "float" else "")

    def _print_Symbol(self, expr):
        try:
            return self.symbol_map[expr]
        except KeyError:
            raise ModelError(f"internal: symbol {expr!r} has no C name") from None

    _print_Dummy = _print_Symbol

    def _print_Pow(self, expr):
        base, e = expr.as_base_exp()
        if e.is_Integer:
            n = int(e)
            if n == 0:
                return self._lit("1.0")
            if 0 < n <= 8:
                b = self.parenthesize(base, 100)   # atoms bare, others parenthesized
                return "(" + "*".join([b] * n) + ")"
            if -8 <= n < 0:
                b = self.parenthesize(base, 100)
                return "(" + self._lit("1.0") + "/(" + "*".join([b] * (-n)) + "))"
        if e == sm.S.Half:
            return f"{self._ns}sqrt{self._suffix()}({self._print(base)})"
        if e == -sm.S.Half:
            return f"({self._lit('1.0')}/{self._ns}sqrt{self._suffix()}({self._print(base)}))"
        return super()._print_Pow(expr)

    def _suffix(self):
        return "f" if self.real_type == "float" else ""

    def _print_NumberSymbol(self, expr):
        # M_PI / M_E are not C99: print the value
        return self._print(sm.Float(expr.evalf(20), 17))

    _print_Pi = _print_NumberSymbol
    _print_Exp1 = _print_NumberSymbol
    _print_EulerGamma = _print_NumberSymbol
    _print_GoldenRatio = _print_NumberSymbol

    def _print_Float(self, expr):
        s = super()._print_Float(expr)
        return s

    def _print_sign(self, expr):
        a = self._print(expr.args[0])
        return f"(({a}) > 0 ? {self._lit('1.0')} : (({a}) < 0 ? -{self._lit('1.0')} : {self._lit('0.0')}))"

    def _print_Heaviside(self, expr):
        a = self._print(expr.args[0])
        h0 = expr.args[1] if len(expr.args) > 1 else sm.S.Half
        if h0.is_Number:
            h = self._lit(repr(float(h0)))
        else:
            h = f"({self._print(h0)})"
        return f"(({a}) > 0 ? {self._lit('1.0')} : (({a}) < 0 ? {self._lit('0.0')} : {h}))"

    def _print_Mod(self, expr):
        # sympy's Mod takes the sign of the divisor (fmod: of the dividend)
        a, b = (self._print(x) for x in expr.args)
        return f"(({a}) - ({b})*{self._ns}floor{self._suffix()}(({a})/({b})))"

    def _print_Piecewise(self, expr):
        if expr.args[-1].cond != sm.true:
            raise ModelError(f"internal: Piecewise without a default (expr, True) branch: {expr}")
        # conditions print parenthesized (relations, &&, ||, !) or as 1/0;
        # integer branches as real literals, so both arms have the real type
        def arm(e):
            return self._lit(f"{int(e)}.0") if e.is_Integer else self._print(e)
        out = f"({arm(expr.args[-1].expr)})"
        for e, c in reversed(expr.args[:-1]):
            out = f"({self._print(c)} ? ({arm(e)}) : {out})"
        return out

    def _print_Relational(self, expr):
        lhs, rhs = self._print(expr.lhs), self._print(expr.rhs)
        return f"({lhs} {expr.rel_op} {rhs})"

    def _print_And(self, expr):
        return "(" + " && ".join(self._print(a) for a in expr.args) + ")"

    def _print_Or(self, expr):
        return "(" + " || ".join(self._print(a) for a in expr.args) + ")"

    def _print_Not(self, expr):
        return f"(!{self._print(expr.args[0])})"

    def _print_BooleanTrue(self, expr):
        return "1"

    def _print_BooleanFalse(self, expr):
        return "0"


def kernel_statements(kernel, printer, bind=None, reads=True):
    """A kernel as printed C: ([(name, line, reads)] of its temporaries and
    of its bound outputs' locals, in order, reads the names of the symbols
    each expression reads; [lines] of its other outputs' stores). Each
    expression goes to the printer's _print directly: what doprint adds
    (assignment targets, a walk for UnevaluatedExpr, code formatting,
    collecting unsupported nodes) does nothing for a kernel's single-line
    expressions, and strict printers raise on an unsupported node in _print
    itself. bind: {output: prefix}: those outputs as locals prefix<k>, not
    stored (the caller stores them). reads=False: empty reads (the
    free-symbol walk costs time at scale and only an ordering needs it)."""
    rt = printer.real_type
    printer._not_supported = set()
    printer._number_symbols = set()
    pr = printer._print
    temps, stores = [], []
    names = (lambda e: {x.name for x in e.free_symbols}) if reads else (lambda e: set())
    for sym, e in kernel.assignments:
        temps.append((sym.name, f"const {rt} {sym.name} = {pr(e)};", names(e)))
    bind = bind or {}
    for o in kernel.outputs:
        for k, e in enumerate(o.exprs):
            if o.name in bind:
                v = f"{bind[o.name]}{k}"
                temps.append((v, f"const {rt} {v} = {pr(e)};", names(e)))
            else:
                stores.append(f"out_{o.name}[{k}] = {pr(e)};")
    return temps, stores


def print_kernel_body(kernel, printer, indent="    "):
    """Lines of C for a kernel: temporaries then output stores
    (kernel_statements)."""
    temps, stores = kernel_statements(kernel, printer, reads=False)
    return [indent + line for _, line, _ in temps] + [indent + line for line in stores]


class ModelCxxPrinter(ModelCPrinter):
    """C++17 printer for the Eigen backend: the same symbol map and the same
    strictness as ModelCPrinter, but every function is ``std::``-qualified
    (overloaded on the argument type) and every literal is a ``Scalar(...)``
    so one kernel body serves any scalar type given as a template
    parameter (double, float)."""

    _ns = "std::"

    def __init__(self, symbol_map, scalar="Scalar"):
        super().__init__(symbol_map, "double")
        # the declared type of temporaries (print_kernel_body reads it)
        self.real_type = scalar

    def _lit(self, text):
        return f"{self.real_type}({text})"

    def _suffix(self):
        return ""

    def _print_Float(self, expr):
        return self._lit(super()._print_Float(expr))

    def _print_Rational(self, expr):
        return f"{self._lit(str(int(expr.p)))}/{self._lit(str(int(expr.q)))}"

    def _print_Infinity(self, expr):
        return f"std::numeric_limits<{self.real_type}>::infinity()"

    def _print_NegativeInfinity(self, expr):
        return f"(-std::numeric_limits<{self.real_type}>::infinity())"

    def _print_NaN(self, expr):
        return f"std::numeric_limits<{self.real_type}>::quiet_NaN()"


# ------------------------------------------------------------------ check
# nodes printed by the printers' own structure (operators, ternaries)
_STRUCTURAL = (sm.Add, sm.Mul, sm.Pow, sm.Piecewise, sm.core.relational.Relational,
               sm.And, sm.Or, sm.Not, BooleanAtom, sm.Symbol, sm.NumberSymbol,
               sm.UnevaluatedExpr)     # opaque nodes (gen.sym.intern), unwrapped after CSE


def _printers():
    return (ModelCPrinter, {"real_type": "double"}), (ModelCPrinter, {"real_type": "float"}), \
        (ModelCxxPrinter, {})


def _prints(expr, syms):
    """Whether all three printers print expr (over the symbols syms)."""
    smap = {x: f"a[{i}]" for i, x in enumerate(syms)}
    for cls, kw in _printers():
        try:
            cls(smap, **kw).doprint(expr)
        except Exception:       # noqa: BLE001 - any failure means: cannot print
            return False
    return True


def _function_problem(e):
    """Why the function node e cannot be printed or differentiated for the
    linearization, or None. Checked once per function and number of
    arguments, on fresh symbols (then shown with e's arguments)."""
    hit = _shell_problem(e.func, len(e.args))
    if hit is None:
        return None
    kind, detail, syms = hit
    if kind == "cannot differentiate":
        detail = detail.xreplace(dict(zip(syms, e.args)))
    return kind, detail


@functools.lru_cache(maxsize=1024)
def _shell_problem(func, nargs):
    """_function_problem's answer for func over nargs fresh symbols: a
    bounded cache (lru_cache: thread-safe, least recently used dropped
    first) shared by every build, since a function class prints (or not)
    the same way in all of them."""
    from .graph import partial
    name = getattr(func, "__name__", str(func))
    syms = [sm.Dummy(f"a{i}") for i in range(nargs)]
    try:
        shell = func(*syms)
    except Exception:           # noqa: BLE001
        shell = None
    if shell is None or not _prints(shell, syms):
        return ("cannot print", f"{name} is not a function the generator can write in C99 "
                "or C++ (see the README, Non-smooth models, for the supported ones)", syms)
    for x in syms:
        try:
            dx = partial(shell, x)
        except Exception:       # noqa: BLE001
            dx = sm.Derivative(shell, x)
        if dx.has(sm.Derivative, sm.Subs) or not _prints(dx, syms):
            return ("cannot differentiate", dx, syms)
    return None


def _node_problem(e):
    """(kind, detail) when the node e itself (its arguments assumed fine)
    cannot be printed, else None."""
    if isinstance(e, sm.Derivative):
        return ("derivative", None)
    if isinstance(e, AppliedUndef):
        return ("undefined", None)
    if e.is_Number:
        if e in (sm.nan, sm.zoo) or e.is_extended_real is False:
            return ("cannot print", f"{e} is not a real number")
        return None
    if e is sm.I or (e.is_Atom and e.is_real is False):
        return ("cannot print", f"{e} is not a real number")
    if isinstance(e, sm.Piecewise):
        if e.args[-1].cond != sm.true:
            return ("cannot print", "a Piecewise needs a default branch (expr, True), "
                    "used where no condition holds")
        return None
    if isinstance(e, _STRUCTURAL) or isinstance(e, sm.core.containers.Tuple) or e.is_Atom \
            or type(e).__name__ == "ExprCondPair":
        return None
    return _function_problem(e)


def unprintable(expr):
    """The innermost subexpression of expr that the generator cannot print
    in C99 (double and float) and C++, or whose derivative (by the rules of
    ``gen.sym.graph.partial``, for the linearization) it cannot print; None when
    everything prints. Undefined functions (``friction(v)``, ``F(t)``) and
    leftover ``Derivative`` terms count as unprintable."""
    return _first_problem(expr)[0]


def _first_problem(expr, seen=None):
    """(node, (kind, detail)) of the first problem in a post-order walk
    (each distinct subexpression once), or (None, None)."""
    seen = set() if seen is None else seen
    stack = [(sm.sympify(expr), False)]
    while stack:
        e, done = stack.pop()
        if done:
            p = _node_problem(e)
            if p is not None:
                return e, p
            continue
        if e in seen:
            continue
        seen.add(e)
        stack.append((e, True))
        if not isinstance(e, (sm.Derivative, AppliedUndef)):
            stack.extend((a, False) for a in reversed(e.args))
    return None, None


def check_printable(exprs, what, names, time=None):
    """Raise ModelError when an expression of ``exprs`` holds something the
    generator cannot print (``unprintable``), naming it in the user's
    symbols: ``names`` maps the model's internal symbols to the user's.
    Undefined functions of ``time`` alone and leftover derivatives are left
    to the caller (they are undeclared inputs, with their own message)."""
    seen = set()            # subexpressions shared between entries are checked once
    for expr in exprs:
        node, problem = _first_problem(expr, seen)
        if node is None:
            continue
        kind, detail = problem
        shown = node.xreplace(names)
        if kind == "derivative":
            continue
        if kind == "undefined":
            if time is not None and all(a == time for a in node.args):
                continue
            raise ModelError(
                f"the {what} contain {shown}, a call of the undefined function {node.func}, "
                "which the generator cannot print: write it out with the functions it prints "
                "(sign, Abs, Heaviside, Min, Max, Piecewise, exp, tanh, ...)")
        if kind == "cannot differentiate":
            raise ModelError(
                f"the {what} contain {shown}, which the generator cannot differentiate for "
                f"the linearization: its derivative {detail.xreplace(names)} cannot be printed")
        raise ModelError(f"the {what} contain {shown}, which the generator cannot print: "
                         f"{detail}")
