"""The one description of a product library's C interface (an optimal-control
problem's kernels, a trajectory tracker's tables, the next products'), as
plain data, the model's (gen/codegen/abi.py) for the products.

A product's backend (gen/codegen/backends/) holds its ProductInterface:
the enums, structs and macros its runtime shares with the caller, and the
functions of its library, with names that hold the placeholders of the
build ({name}: the library's C prefix, and those of the plan's names, such
as {p} the model's prefix). gen.codegen.render binds it to one build
(ProductInterface.bind) and renders it into the library's headers
(templates/common/product.h.j2, product_types.h.j2) and into the cffi cdef
that loads it (templates/cffi/product.cdef.j2, gen.toolchain.host.load_product):
one description, every declaration rendered from it.

    iface = OcpBackend.interface.bind(name="cart_ocp")
    iface.function("cart_ocp_eval").params     # (("const gen_rt_ocp_block *", "blocks"), ...)
    iface.value("GEN_RT_OCP_HESSIAN")          # 4

A product's plan (ProductPlan) is what its face hands the render stage:
the library's name, the names and values its interface is bound with, the
kernels (gen.plan.ir Kernel objects, printed by the backend's printer) and
the plain data its templates lay out.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

__all__ = ["CConst", "CEnum", "CField", "CStruct", "CTypedef", "CFunction", "ProductInterface",
           "ProductPlan", "bind_text"]


_PLACEHOLDER = re.compile(r"\{(\w+)\}")


def bind_text(text, names):
    """text with each {key} of names replaced by its value; other braces
    (C's, a doc's) are left as they are."""
    if text is None:
        return None
    return _PLACEHOLDER.sub(lambda m: str(names[m.group(1)]) if m.group(1) in names
                            else m.group(0), text)


@dataclass(frozen=True)
class CConst:
    """A named constant: an enum member (value an int) or a macro (value
    its C text)."""
    name: str
    value: object
    doc: str = ""


@dataclass(frozen=True)
class CEnum:
    """An anonymous enum of named int constants."""
    doc: str
    members: tuple


@dataclass(frozen=True)
class CField:
    """A struct field: its C type as written ("const int *", "double")."""
    name: str
    ctype: str
    doc: str = ""


@dataclass(frozen=True)
class CStruct:
    """A typedef'd struct; fields None: an opaque one (``typedef struct
    name name;``: the library's header completes it, the cdef passes
    pointers to it)."""
    name: str
    doc: str
    fields: tuple | None


@dataclass(frozen=True)
class CTypedef:
    """A typedef other than a struct's: its name and its C declaration
    (``double (*{name}_clock)(void *ctx)``)."""
    name: str
    decl: str
    doc: str = ""


@dataclass(frozen=True)
class CFunction:
    """A function of the library: params are (C type, name) pairs."""
    name: str
    ret: str
    params: tuple
    doc: str = ""

    def _args(self):
        return [f"{t}{'' if t.endswith('*') else ' '}{n}" for t, n in self.params] or ["void"]

    @property
    def signature(self):
        """The C prototype without its semicolon, on one line."""
        return f"{self.ret} {self.name}({', '.join(self._args())})"

    def wrapped(self, width=96):
        """The prototype broken into lines of at most width characters,
        the parameters aligned after the parenthesis."""
        head = f"{self.ret} {self.name}("
        lines, line = [], head
        args = self._args()
        for i, a in enumerate(args):
            piece = a + (", " if i < len(args) - 1 else ")")
            if len(line) + len(piece.rstrip()) > width and line.strip() != head.strip():
                lines.append(line.rstrip())
                line = " " * len(head)
            line += piece
        return "\n".join(lines + [line])


@dataclass(frozen=True)
class ProductInterface:
    """The C interface of one product's library.

    product: the product's name (its backend's); name: the library's C
    prefix once bound ("{name}" before); doc: what the library is;
    includes: headers its declarations need (C spelling, '"x.h"' or
    '<x.h>'); types_header: the file the types (enums, structs) are rendered
    into when its hand-written runtime includes them (None: into the
    library's header); macros: #define constants of the library's header.
    """
    product: str
    doc: str
    name: str = "{name}"
    includes: tuple = ()
    types_header: str | None = None
    typedefs: tuple = ()
    enums: tuple = ()
    structs: tuple = ()
    macros: tuple = ()
    functions: tuple = ()

    def bind(self, **names):
        """This description with every placeholder ({name}, {p}, ...)
        replaced by the build's values."""
        b = lambda s: bind_text(s, names)  # noqa: E731
        return replace(
            self, name=b(self.name), doc=b(self.doc),
            includes=tuple(b(i) for i in self.includes),
            typedefs=tuple(CTypedef(b(t.name), b(t.decl), b(t.doc)) for t in self.typedefs),
            enums=tuple(CEnum(b(e.doc), tuple(CConst(b(c.name), c.value, b(c.doc))
                                              for c in e.members)) for e in self.enums),
            structs=tuple(CStruct(b(s.name), b(s.doc), None if s.fields is None else tuple(
                CField(b(f.name), b(f.ctype), b(f.doc)) for f in s.fields))
                for s in self.structs),
            macros=tuple(CConst(b(c.name), b(str(c.value)), b(c.doc)) for c in self.macros),
            functions=tuple(CFunction(b(f.name), b(f.ret),
                                      tuple((b(t), b(n)) for t, n in f.params), b(f.doc))
                            for f in self.functions))

    @property
    def header(self):
        """The library's header file name."""
        return f"{self.name}.h"

    def function(self, name):
        """The CFunction of a C name."""
        for f in self.functions:
            if f.name == name:
                return f
        raise KeyError(f"{self.product} interface has no function {name!r}")

    def value(self, name):
        """The value of an enum member or macro by its C name."""
        for c in [c for e in self.enums for c in e.members] + list(self.macros):
            if c.name == name:
                return c.value
        raise KeyError(f"{self.product} interface has no constant {name!r}")

    @property
    def public_names(self):
        """The C names of the library's functions."""
        return [f.name for f in self.functions]


@dataclass
class ProductPlan:
    """What a product's face hands the render stage (gen.codegen.render.render
    with the product's backend).

    name: the library's C prefix (its files and symbols); names: the other
    values its interface is bound with ({p}: the model's prefix, ...);
    kernels: gen.plan.ir Kernel objects (printed by the backend's printer as
    static functions <name>_<kernel name>); data: plain values for its
    templates and its backend's context; files: sources rendered by another
    backend that the library compiles with its own ({file name: text}: a
    model's C sources, for a product that calls the model)."""
    name: str
    names: dict = field(default_factory=dict)
    kernels: list = field(default_factory=list)
    data: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)
