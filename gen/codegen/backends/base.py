"""What every backend shares: the runtime's file lists, the compile flags,
the compilers, and the types Backend (a face of the engine over a model's
plan) and ProductBackend (a product's library over its face's plan). One
module per backend beside this one; gen.codegen.backends is the registry."""
from __future__ import annotations

import os
import shutil
import sys
import sysconfig

from ...sym.printers import ModelCPrinter

__all__ = ["Backend", "ProductBackend", "c_compiler", "cxx_compiler", "RUNTIME_SOURCES",
           "RUNTIME_HEADERS", "RUNTIME_MAIN", "C_FLAGS", "C_LIN_FLAGS", "C_WIRING_FLAGS",
           "RUNTIME_FLAGS", "STRICT_FLAGS", "CXX_FLAGS", "CXX_STRICT_FLAGS", "LIB_SUFFIX", "DERIVATIVE_HEADERS"]

# ------------------------------------------------------------ the runtime
# the C runtime every C-backend model links (csrc/)
RUNTIME_SOURCES = ["gen_rt_status.c", "gen_rt_linalg.c", "gen_rt_dynamics.c",
                   "gen_rt_project.c", "gen_rt_integrate.c", "gen_rt_linearize.c",
                   "gen_rt_model.c", "gen_rt_input.c", "gen_rt_engine.c", "gen_rt_events.c",
                   "gen_rt_simulate.c", "gen_rt_expm.c", "gen_rt_sens.c", "gen_rt_hybrid.c"]
RUNTIME_HEADERS = ["gen_rt.h", "gen_rt_status.h", "gen_rt_dopri5.h", "gen_rt_rodas4.h", "gen_rt_expm.h",
                   "gen_rt_sens.h", "gen_rt_ldlt.h", "gen_rt_private.h"]
# the derivative algorithms over a model's kernels and CasADi's calling
# convention over them (csrc/derivatives), as the CasADi library holds them:
# headers of static inline functions (*_inline.h) that its own file compiles
# with its model as a constant (the sizes unrolled, the kernels called
# directly); gen_rt_deriv_extern.c and gen_rt_casadi_extern.c, the same functions with the
# model a run-time value, are the C runtime's (CMake, tests/c), not the
# library's
DERIVATIVE_HEADERS = ["gen_rt_deriv.h", "gen_rt_casadi.h", "gen_rt_deriv_inline.h",
                      "gen_rt_casadi_inline.h"]
# the standalone simulator's runtime (main.c's program: the project's binary
# only, never a library's)
RUNTIME_MAIN = ["gen_rt_main.c", "gen_rt_main.h"]

# ------------------------------------------------------------- the flags
# -ffp-contract=off: no fused multiply-add where the target has one (GCC's
# default for ISO C already; clang's is to contract), so every compiler and
# target computes the same IEEE operations. -fno-math-errno: the generated
# code never reads errno (it checks for NaN and inf), so the math functions
# need not set it; the compilers then pair sin and cos of one angle into one
# sincos call and inline sqrt, with the same IEEE results (the golden numbers
# are bit for bit). clang's eval_rhs of the 4-link cart took 1.19-1.21x gcc's
# without it (eight libm calls where gcc makes four), 1.05-1.07x with it.
C_FLAGS = ["-std=c99", "-O2", "-fno-strict-aliasing", "-ffp-contract=off", "-fno-math-errno"]
# added for <name>_lin.c, the derivative kernels: gcc's time on their
# straight-line code is the largest cost of a build, and -O1 takes a quarter
# less (n = 20 cart: 8.8 -> 6.6 s) for a linearize 4-12% slower; IEEE
# semantics are the same at every level (no -ffast-math), so the numbers are
# too (tests/golden/seed_numbers.json, bit for bit)
C_LIN_FLAGS = ["-O1"]
# added for <name>.c, the wiring, of a model with a large kernel (the C
# backend's units): calls into the runtime (compiled apart at -O2) and the
# unrolled mass-matrix solve, which the right-hand side does not use (its
# fused kernel solves M u' = f itself): -O1 halves its compile (n = 16 cart:
# 0.70 -> 0.39 s of gcc) with its rhs, linearize and step_sensitivity as fast
# (docs/guides/speed.md). A small model keeps -O2: there eval_rhs's own
# wiring is a measurable share of a call (the seed's Lagrange model).
C_WIRING_FLAGS = ["-O1"]
# the runtime's objects (shared by every model library and FMU binary of a
# scalar type): position independent, and hidden, so that a library exports
# only its model's own functions
RUNTIME_FLAGS = [*C_FLAGS, "-fPIC", "-fvisibility=hidden"]
STRICT_FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
# the C++/Eigen backend (Eigen's own headers are -isystem: their warnings are not ours)
CXX_FLAGS = ["-std=c++17", "-O2", "-fno-strict-aliasing", "-ffp-contract=off",
             "-fno-math-errno"]
CXX_STRICT_FLAGS = ["-std=c++17", "-Wall", "-Wextra", "-Werror", "-pedantic"]
# a shared library's file name ends in this on this platform
LIB_SUFFIX = ".dylib" if sys.platform == "darwin" else ".so"


def c_compiler():
    """$CC; else clang when it is installed (it compiles a model's large
    straight-line kernels about three times faster than GCC: n = 20 cart
    right-hand side 3.1 -> 1.0 s; the arithmetic is the same IEEE
    arithmetic, -ffp-contract=off, and the golden numbers are bit for bit
    the same); else the compiler Python was built with."""
    cc = os.environ.get("CC")
    if not cc:
        cc = "clang" if shutil.which("clang") else (sysconfig.get_config_var("CC") or "cc")
    return cc.split()[0]


def cxx_compiler():
    """$CXX; else clang++ when it is installed (as c_compiler); else the
    C++ compiler Python was built with, or g++."""
    cxx = os.environ.get("CXX")
    if not cxx:
        cxx = ("clang++" if shutil.which("clang++")
               else (sysconfig.get_config_var("CXX") or "g++"))
    return cxx.split()[0]


class Backend:
    """One face of the engine. Subclasses set the class attributes and
    override what differs; gen.render and gen.build use only these."""
    name = ""
    #: (file name with {name}, template, role) rendered for this backend
    templates = ()
    #: runtime files (under csrc/) copied into its sources
    runtime_files = ()
    #: runtime files a generated project adds for its standalone binary
    project_runtime_files = ()
    #: runtime C sources linked into its library (objects shared in the cache)
    runtime_sources = ()
    #: how the plan generates the Jacobian blocks (gen/plan/ir.py plan(lin=...))
    lin = "auto"
    #: the derivative kernels may be built on first use (gen.compile)
    lazy_derivatives = False
    #: the right-hand side kernel may fuse the unrolled LDL^T (templates/c)
    fused_rhs = False
    #: gen.compile can load its library (it has the plugin table)
    loadable = True
    #: gen.generate writes a project (CMake, main.c) for it
    project = True
    #: it renders through its own render() (a composite of other backends'
    #: files), not by its template list alone
    composite = False
    #: its CMake project bounds the library's frames (<P>_STACK_LIMIT)
    stack_limit = False
    #: what names its cache folder: _eomgen_<model><tag>_<key>
    tag = ""
    #: its library links with the C++ compiler
    link_cxx = False
    #: a product's library (ProductBackend): rendered from a ProductPlan
    product = False

    def __repr__(self):
        return f"<backend {self.name!r}>"

    def printer(self, symbol_map, real):
        """The sympy printer of its kernels."""
        raise NotImplementedError

    def context(self, model, kernels):
        """What its templates need beyond the shared context."""
        return {}

    def cache_parts(self):
        """What its build depends on besides the files (flags, compilers,
        libraries): part of the cache key."""
        return [" ".join(C_FLAGS + ["lin:"] + C_LIN_FLAGS + ["wiring:"] + C_WIRING_FLAGS),
                c_compiler()]

    def units(self, name, files, derivatives, includes=()):
        """What gen.build compiles of files (the rendered sources), the
        largest first: [(file, compiler, flags)]; the runtime_sources come
        from the shared runtime objects."""
        raise NotImplementedError

    def diagnose(self, name, units):
        """(compiler, flags, files) that rerun a failed compile for a
        readable log (strict warnings, no Python)."""
        return (c_compiler(), STRICT_FLAGS,
                list(dict.fromkeys(u[0] for u in units if u[0].startswith(name))) + list(self.runtime_sources))

    def library_file(self, modname, name):
        """The library's file name in its cache folder."""
        return modname + LIB_SUFFIX

    def link_order(self, own, runtime):
        """The objects in link order (own: the units' objects in order)."""
        return [*own, *runtime]


class ProductBackend(Backend):
    """A product's library (gen/design: optimal control, tracking; the next
    products'): rendered by gen.codegen.render.render from the ProductPlan
    its face makes, through its templates (data, as every backend's) and
    the headers of its interface; built by gen.toolchain.build.build by its
    recipe and cached by content like a model library; opened by
    gen.toolchain.host.load_product with the cdef of the same interface.

    A product sets: name; interface (gen/codegen/product_abi.py, the one
    description of its C interface); templates, its own files ((file with
    {name}, template, role)); runtime_files, its hand-written runtime
    (csrc/products/<name>/), copied beside them and compiled with them;
    and overrides names() (the values its interface is bound with) and
    context() (what its templates need beyond the plan's data) when it
    needs to."""
    product = True
    loadable = False
    project = False
    lazy_derivatives = False
    stack_limit = False
    #: ProductInterface: its C interface, with placeholders ({name}, ...)
    interface = None
    #: its runtime files are compiled with its own files, not shared
    runtime_sources = ()

    def printer(self, symbol_map, real):
        return ModelCPrinter(symbol_map, real)

    def names(self, plan, real):
        """The values its interface is bound with: {name} the library's
        prefix and the plan's names."""
        return {"name": plan.name, **plan.names}

    def context(self, plan, iface, real):
        """What its templates need beyond the shared context (the plan's
        data, the printed kernels, the bound interface)."""
        return {}

    def file_templates(self, iface):
        """(file, template, role) of everything it renders: its own
        templates and the headers of its interface (the library's header,
        and its types' header when its runtime includes them)."""
        out = list(self.templates) + [("{name}.h", "common/product.h.j2", "product")]
        if iface.types_header:
            out.append((iface.types_header, "common/product_types.h.j2", "product"))
        return out

    def cache_parts(self):
        return [*super().cache_parts(), f"backend={self.name}"]

    def units(self, name, files, derivatives, includes=()):
        """Every C file, its own and its runtime's, the largest first, as
        position-independent C."""
        cc = c_compiler()
        own = sorted((f for f in files if f.endswith(".c")),
                     key=lambda f: (-len(files[f].encode()), f))
        return [(f, cc, [*C_FLAGS, "-fPIC"]) for f in own]
