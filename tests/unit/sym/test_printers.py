"""Unit tests of the printers (gen/sym/printers.py) on exact strings, no compiler.

ModelCPrinter(symbol_map, real_type) prints C99 for "double" or "float"
(float: the f-suffixed libm functions and F-suffixed literals);
ModelCxxPrinter(symbol_map, scalar) prints C++17 for the Eigen backend
(std::-qualified functions, every literal a Scalar(...)). Both print every
symbol through the map and are strict: a node they cannot print is an
error, never a comment that compiles.
"""
import pytest
import sympy as sm
from sympy.printing.codeprinter import PrintMethodNotImplementedError

from gen.core.errors import ModelError
from gen.plan.ir import Arg, Kernel, Output
from gen.sym.printers import ModelCPrinter, ModelCxxPrinter, print_kernel_body

q0, q1, u0, p0, t = sm.symbols("q0 q1 u0 p0 t")
SYMBOLS = {q0: "q[0]", q1: "q[1]", u0: "u[0]", p0: "p[0]", t: "t"}

# (expression, C double, C float, C++ Scalar)
CASES = [
    (sm.sin(q0), "sin(q[0])", "sinf(q[0])", "std::sin(q[0])"),
    (u0 * sm.cos(q0), "u[0]*cos(q[0])", "u[0]*cosf(q[0])", "u[0]*std::cos(q[0])"),
    (sm.tan(q0), "tan(q[0])", "tanf(q[0])", "std::tan(q[0])"),
    (sm.exp(q0), "exp(q[0])", "expf(q[0])", "std::exp(q[0])"),
    (sm.atan2(q1, q0), "atan2(q[1], q[0])", "atan2f(q[1], q[0])", "std::atan2(q[1], q[0])"),
    (sm.Abs(q0), "fabs(q[0])", "fabsf(q[0])", "std::fabs(q[0])"),
    # small integer powers: repeated multiplication, parenthesized
    (q0**2, "(q[0]*q[0])", "(q[0]*q[0])", "(q[0]*q[0])"),
    (q0**3, "(q[0]*q[0]*q[0])", "(q[0]*q[0]*q[0])", "(q[0]*q[0]*q[0])"),
    ((q0 + q1)**2, "((q[0] + q[1])*(q[0] + q[1]))", "((q[0] + q[1])*(q[0] + q[1]))",
     "((q[0] + q[1])*(q[0] + q[1]))"),
    (q0**-2, "(1.0/(q[0]*q[0]))", "(1.0F/(q[0]*q[0]))", "(Scalar(1.0)/(q[0]*q[0]))"),
    # beyond |n| = 8: pow
    (q0**9, "pow(q[0], 9)", "powf(q[0], 9)", "std::pow(q[0], 9)"),
    (q0**p0, "pow(q[0], p[0])", "powf(q[0], p[0])", "std::pow(q[0], p[0])"),
    # square roots
    (sm.sqrt(q0), "sqrt(q[0])", "sqrtf(q[0])", "std::sqrt(q[0])"),
    (1 / sm.sqrt(q0), "(1.0/sqrt(q[0]))", "(1.0F/sqrtf(q[0]))", "(Scalar(1.0)/std::sqrt(q[0]))"),
    (q0**0.5, "sqrt(q[0])", "sqrtf(q[0])", "std::sqrt(q[0])"),
    (q0**sm.Rational(3, 2), "pow(q[0], 3.0/2.0)", "powf(q[0], 3.0F/2.0F)",
     "std::pow(q[0], Scalar(3)/Scalar(2))"),
    # rationals and floats
    (sm.Rational(1, 3), "1.0/3.0", "1.0F/3.0F", "Scalar(1)/Scalar(3)"),
    (q0 / 2, "(1.0/2.0)*q[0]", "(1.0F/2.0F)*q[0]", "(Scalar(1)/Scalar(2))*q[0]"),
    (sm.Float(1.5) * q0, "1.5*q[0]", "1.5F*q[0]", "Scalar(1.5)*q[0]"),
    (sm.Float("0.1"), "0.10000000000000001", "0.1F", "Scalar(0.10000000000000001)"),
    # integers stay integers
    (2 * q0, "2*q[0]", "2*q[0]", "2*q[0]"),
    (-q0, "-q[0]", "-q[0]", "-q[0]"),
    (q0 / q1, "q[0]/q[1]", "q[0]/q[1]", "q[0]/q[1]"),
    # number symbols as values (M_PI, M_E are not C99), float to float precision
    (sm.pi * q0, "3.1415926535897932*q[0]", "3.14159265F*q[0]",
     "Scalar(3.1415926535897932)*q[0]"),
    (sm.E, "2.7182818284590452", "2.71828183F", "Scalar(2.7182818284590452)"),
    # no math macros (M_LN2 is not C99 and is a double)
    (sm.log(2), "log(2)", "logf(2)", "std::log(2)"),
    # sign and Heaviside as conditionals with typed literals
    (sm.sign(q0), "((q[0]) > 0 ? 1.0 : ((q[0]) < 0 ? -1.0 : 0.0))",
     "((q[0]) > 0 ? 1.0F : ((q[0]) < 0 ? -1.0F : 0.0F))",
     "((q[0]) > 0 ? Scalar(1.0) : ((q[0]) < 0 ? -Scalar(1.0) : Scalar(0.0)))"),
    (sm.Heaviside(q0), "((q[0]) > 0 ? 1.0 : ((q[0]) < 0 ? 0.0 : 0.5))",
     "((q[0]) > 0 ? 1.0F : ((q[0]) < 0 ? 0.0F : 0.5F))",
     "((q[0]) > 0 ? Scalar(1.0) : ((q[0]) < 0 ? Scalar(0.0) : Scalar(0.5)))"),
    # time is a scalar argument
    (sm.sin(t) * p0, "p[0]*sin(t)", "p[0]*sinf(t)", "p[0]*std::sin(t)"),
]
IDS = [str(c[0]) for c in CASES]


@pytest.mark.parametrize("expr,c_double,c_float,cxx", CASES, ids=IDS)
def test_c_double(expr, c_double, c_float, cxx):
    assert ModelCPrinter(SYMBOLS, "double").doprint(expr) == c_double


@pytest.mark.parametrize("expr,c_double,c_float,cxx", CASES, ids=IDS)
def test_c_float(expr, c_double, c_float, cxx):
    assert ModelCPrinter(SYMBOLS, "float").doprint(expr) == c_float


@pytest.mark.parametrize("expr,c_double,c_float,cxx", CASES, ids=IDS)
def test_cxx_scalar(expr, c_double, c_float, cxx):
    assert ModelCxxPrinter(SYMBOLS).doprint(expr) == cxx


def test_cxx_scalar_name_is_the_parameter():
    p = ModelCxxPrinter(SYMBOLS, "T")
    assert p.real_type == "T"
    assert p.doprint(sm.Float(1.5) * q0 + q0**-1) == "T(1.5)*q[0] + (T(1.0)/(q[0]))"
    assert p.doprint(sm.oo) == "std::numeric_limits<T>::infinity()"
    assert p.doprint(-sm.oo) == "(-std::numeric_limits<T>::infinity())"
    assert p.doprint(sm.nan) == "std::numeric_limits<T>::quiet_NaN()"


def test_float_output_has_no_double_function_or_literal():
    """Everything a float kernel can contain prints without a bare double."""
    p = ModelCPrinter(SYMBOLS, "float")
    for expr, _, c_float, _ in CASES:
        text = p.doprint(expr)
        for fn in ("sin(", "cos(", "tan(", "exp(", "sqrt(", "pow(", "fabs(", "atan2(", "log("):
            assert fn not in text.replace(fn[:-1] + "f(", ""), text
        assert "M_" not in text


def test_symbols_come_from_the_map_only():
    """A symbol whose sympy name is a C keyword or libm name still prints
    as its array element; a symbol outside the map is refused."""
    weird = sm.Symbol("int")
    sin_sym = sm.Symbol("sin")
    d = sm.Dummy("lam0")
    p = ModelCPrinter({weird: "q[0]", sin_sym: "p[1]", d: "lam[0]"}, "double")
    # sympy orders the factors by name (int, sin), not by their C spelling
    assert p.doprint(weird * sin_sym + d) == "lam[0] + q[0]*p[1]"
    with pytest.raises(ModelError, match="no C name"):
        p.doprint(weird + sm.Symbol("z"))


@pytest.mark.parametrize("printer", [ModelCPrinter(SYMBOLS, "double"),
                                     ModelCPrinter(SYMBOLS, "float"),
                                     ModelCxxPrinter(SYMBOLS)], ids=["double", "float", "cxx"])
@pytest.mark.parametrize("expr", [sm.Function("f")(q0), sm.besselj(0, q0),
                                  sm.Derivative(sm.Function("f")(q0), q0), sm.zoo],
                         ids=["undefined-function", "besselj", "derivative", "zoo"])
def test_strict_refuses_unsupported_nodes(printer, expr):
    with pytest.raises(PrintMethodNotImplementedError):
        printer.doprint(expr)


def test_real_type_is_checked():
    with pytest.raises(ModelError, match="double' or 'float"):
        ModelCPrinter(SYMBOLS, "long double")


def test_print_kernel_body_lines():
    w0, w1 = sm.symbols("w0 w1")
    k = Kernel("k", [Arg("q", (q0, q1))],
               [Output("y", 1, 2, [w1 * w0, w1 + 1])],
               [(w0, sm.sin(q0)), (w1, q1**2 * w0)])
    smap = {**SYMBOLS, w0: "w0", w1: "w1"}
    assert print_kernel_body(k, ModelCPrinter(smap, "double")) == [
        "    const double w0 = sin(q[0]);",
        "    const double w1 = (q[1]*q[1])*w0;",
        "    out_y[0] = w0*w1;",
        "    out_y[1] = w1 + 1;",
    ]
    assert print_kernel_body(k, ModelCPrinter(smap, "float"), indent="") == [
        "const float w0 = sinf(q[0]);",
        "const float w1 = (q[1]*q[1])*w0;",
        "out_y[0] = w0*w1;",
        "out_y[1] = w1 + 1;",
    ]
    assert print_kernel_body(k, ModelCxxPrinter(smap), indent="  ")[:2] == [
        "  const Scalar w0 = std::sin(q[0]);",
        "  const Scalar w1 = (q[1]*q[1])*w0;",
    ]
