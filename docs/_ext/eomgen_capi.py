"""Sphinx extension: the reference of the generated C interface, rendered
at build time from the one description of it (gen/codegen/abi.py).

``.. eomgen-c-api::`` (option ``:prefix:``, default ``pendulum_kane``)
writes the sizes, the scalar type, the structs with their fields, every
public function with the C prototype of the generated header (the same
Jinja macro, ``templates/common/macros.j2``, renders both), its parameters
with their role and size, and the status codes with their messages and the
Python exception each one raises. Nothing of it is written by hand: a
function added to ``gen.codegen.abi.FUNCTIONS`` appears here on the next build.
"""
from __future__ import annotations

import dataclasses

from docutils import nodes
from docutils.parsers.rst import directives
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

from gen.codegen import abi
from gen.core.status import EXCEPTIONS
from gen.codegen.render import template_env

# what each role of gen.codegen.abi.Param means for the caller (its docstring, in words)
_ROLES = {
    "in": "input array of {size} values; NULL gives ``ERR_NULL``, a NaN or infinite "
          "value ``ERR_NONFINITE_INPUT``",
    "in?": "input array of {size} values, or NULL for {default}; a given array is "
           "checked like an input",
    "scalar": "a real number, checked for NaN and infinity",
    "value": "a plain value, passed through unchecked",
    "inout": "array of {size} values, read and written in place (checked like an input)",
    "out": "output array of {size} values (NULL gives ``ERR_NULL`` when the size is not zero)",
    "out?": "optional output{sized} (NULL: not computed)",
    "rows": "output rows, ``capacity`` of them (NULL gives ``ERR_NULL``)",
    "struct": "the struct, read (NULL gives ``ERR_NULL``)",
    "struct?": "the struct, read; NULL takes the defaults of ``{p}_sim_options_default``",
    "struct_out": "the struct, written (NULL gives ``ERR_NULL``)",
}
_DEFAULTS = {"p": "the model's default constants", "r": "zero inputs"}
_SIZES = (
    ("NQ", "generalized coordinates q"), ("NU", "generalized speeds u"),
    ("NX", "state x = [q, u]"), ("NR", "inputs r"), ("NP", "constants p"),
    ("MC", "configuration constraints f_c(q) = 0"),
    ("MV", "velocity constraints A(q) u + b = 0, and multipliers"),
    ("NS", "independent state [q_ind, u_ind] of the linearization"),
    ("NA", "auxiliary speeds, i.e. reaction forces"), ("NY", "outputs y"),
)


def _ctype(t, p):
    return {"real": f"{p}_real", "creal*": f"const {p}_real *", "real*": f"{p}_real *",
            "cint*": "const int *", "int*": "int *", "controller": f"{p}_controller",
            "void*": "void *"}.get(t, t)


def _size(expr, P):
    """'NU*NU' -> ``PEND_NU*PEND_NU`` for the text."""
    if not expr:
        return ""
    out = expr
    for name, _ in _SIZES:
        out = out.replace(name, f"{P}_{name}")
    return f"``{out}``"


def _param_text(a, p, P):
    text = _ROLES[a.role].format(size=_size(a.size, P), p=p,
                                 default=_DEFAULTS.get(a.default or "", "the default"),
                                 sized=f" of {_size(a.size, P)} values" if a.size else "")
    if a.ctype in abi.STRUCT_NAMES:
        text = text.replace("the struct", f":c:type:`{p}_{a.ctype}`")
    return text


def _escape(text):
    return text.replace("*", r"\*").replace("`", "'")


def c_api_lines(prefix="pendulum_kane", real="double"):
    """The reStructuredText of the C reference for a model prefix."""
    iface = dataclasses.replace(abi.host_interface(real), name=prefix)
    macros = template_env().get_template("common/macros.j2").module
    p, P = prefix, prefix.upper()
    L = []
    add = L.append

    add("Sizes and types")
    add("---------------")
    add("")
    add(f".. c:type:: {real} {p}_real")
    add("")
    add("   The scalar type of every array (``double``, or ``float`` with ``real=\"float\"``).")
    add("")
    for name, doc in _SIZES:
        add(f".. c:macro:: {P}_{name}")
        add("")
        add(f"   Number of {doc}.")
        add("")
    add(f".. c:macro:: {P}_HAS_ENERGY")
    add("")
    add("   1 when the model was given an energy expression (``eval_energy``), else 0.")
    add("")
    for name, value in abi.METHODS.items():
        add(f".. c:macro:: {P}_METHOD_{name.upper()}")
        add("")
        add(f"   ``{value}``: the integration method ``\"{name}\"`` of "
            f":c:member:`{p}_sim_options.method`.")
        add("")
    add(f".. c:type:: int (*{p}_controller)(void *ctx, {p}_real t, const {p}_real *x, "
        f"{p}_real *r)")
    add("")
    add(f"   A controller callback of :c:type:`{p}_input`: called with ``r`` holding the "
        "base inputs and the feedback, it may overwrite ``r``; a nonzero return stops the "
        "run with ``ERR_CONTROLLER``.")
    add("")

    add("Structs")
    add("-------")
    add("")
    for s in iface.structs:
        add(f".. c:struct:: {p}_{s.name}")
        add("")
        add(f"   {_escape(s.doc.replace('<p>', p).replace('<P>', P))}")
        add(f"   (C++: ``{s.cxx_name}<S>``.)")
        add("")
        for f in s.fields:
            count = f"[{P}_{f.count}]" if f.count else ""
            ctype = _ctype(f.ctype, p)
            sep = "" if ctype.endswith("*") else " "
            add(f"   .. c:member:: {ctype}{sep}{f.name}{count}")
            add("")
            default = ("16 machine epsilons of the scalar type" if f.default == "eps16"
                       else f"``{f.default}``")
            add(f"      {_escape(f.doc.replace('<P>', P))}. Default {default}.")
            add("")

    add("Functions")
    add("---------")
    add("")
    add(f"Every function is prefixed by the model's name (here ``{p}``). The prototypes "
        "are rendered by the macro that writes the generated header.")
    add("")
    for fn in iface.functions:
        proto = macros.prototype(iface, fn).strip()
        add(f".. c:function:: {proto}")
        add("")
        add(f"   {_escape(fn.doc.replace('<p>', p).replace('<P>', P))}")
        add("")
        for a in fn.params:
            add(f"   :param {a.name}: {_param_text(a, p, P)}")
        if fn.ret == "int":
            add("   :returns: ``0`` (``OK``) or a negative status code (below)")
        elif fn.ret.startswith("const char"):
            add("   :returns: a static string")
        if fn.work:
            add(f"   :work: the runtime sizes its work arrays with "
                f"``GEN_RT_MODEL_{fn.work}_WORK`` at compile time (no heap)")
        if fn.verb in abi.DERIVATIVE_VERBS:
            add(f"   :derivative kernels: yes (``{p}_lin.c``)")
        add("")

    add("Status codes")
    add("------------")
    add("")
    add(f"Read from ``csrc/gen_rt_status.h``; ``{p}_status_message(code)`` returns the "
        "message, the Python bindings raise the exception.")
    add("")
    add(".. list-table::")
    add("   :header-rows: 1")
    add("   :widths: 30 8 47 15")
    add("")
    add("   * - name")
    add("     - value")
    add("     - message")
    add("     - Python")
    for s in iface.statuses:
        exc = EXCEPTIONS.get(s.name)
        py = "(none)" if exc is None else (
            f":class:`gen.{exc.__name__}`" if exc.__module__.startswith("gen")
            else f"``{exc.__name__}``")
        add(f"   * - ``{P}_{s.name}``")
        add(f"     - ``{s.value}``")
        add(f"     - {_escape(s.message)}")
        add(f"     - {py}")
    add("")
    return L


class CApiDirective(SphinxDirective):
    has_content = False
    option_spec = {"prefix": directives.unchanged, "real": directives.unchanged}

    def run(self):
        prefix = self.options.get("prefix", "pendulum_kane")
        real = self.options.get("real", "double")
        lines = c_api_lines(prefix, real)
        self.env.note_dependency(abi.__file__)
        node = nodes.section()
        node.document = self.state.document
        self.state.nested_parse(StringList(lines, source="gen/codegen/abi.py"), self.content_offset,
                                node, match_titles=True)
        return node.children


def setup(app):
    app.add_directive("eomgen-c-api", CApiDirective)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
