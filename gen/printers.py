"""C99 printer for kernel bodies.

Every model symbol is printed as an array element (``q[0]``) or a
temporary, never under its sympy name (../shared/NOTES-sympy.md 5), so
hostile names cannot reach the C code. ``strict=True``: an expression the
printer cannot print is an error, never a comment that compiles.
"""
from __future__ import annotations

import sympy as sm
from sympy.codegen.ast import float32, float64, real
from sympy.printing.c import C99CodePrinter

from .errors import ModelError

__all__ = ["ModelCPrinter", "ModelCxxPrinter", "print_kernel_body"]


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
        return f"(({a}) > 0 ? {self._lit('1.0')} : (({a}) < 0 ? {self._lit('0.0')} : {self._lit('0.5')}))"


def print_kernel_body(kernel, printer, indent="    "):
    """Lines of C for a kernel: temporaries then output stores."""
    lines = []
    rt = printer.real_type
    for s, e in kernel.assignments:
        lines.append(f"{indent}const {rt} {s.name} = {printer.doprint(e)};")
    for o in kernel.outputs:
        for k, e in enumerate(o.exprs):
            lines.append(f"{indent}out_{o.name}[{k}] = {printer.doprint(e)};")
    return lines


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
