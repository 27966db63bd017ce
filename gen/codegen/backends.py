"""Backends: the faces of the one engine, one object each, in one registry.

A backend is what differs between the outputs of a plan (after SymForce's
per-language config objects): the printer of its kernels, its templates
(data: (file, template, role)), the runtime files its project carries, its
compile recipe (the compilers, the flags, which of its files are C and
which C++, the runtime sources it links) and its capabilities. Everything
else (the plan, the rendering loop, the build cache, the loading) is
shared: gen/codegen/render.py and gen/toolchain/build.py ask the backend and never compare
its name.

    b = get_backend("eigen")       # the object; unknown -> ModelError naming the known ones
    b.printer(symbol_map, "double")
    b.units("pend", files, derivatives=True)   # what gen.build compiles, and how

    C      "c"      C99 over the C runtime (csrc/): gen.compile, gen.generate
    Eigen  "eigen"  C++17 over Eigen 3.4, an extern "C" layer with the C API
    FMU    "fmu"    the C model with the FMI glue, for gen.export_fmu (gen/export/fmu.py)
    CasADi "casadi" the C model with CasADi's external-function wrappers (gen/export/casadi.py)

and the products' libraries (ProductBackend: rendered from a face's
ProductPlan, their C interface described once, gen/codegen/product_abi.py):

    OCP     "ocp"     an optimal control problem's kernels over the node loop
                      (csrc/products/ocp, gen/design/ocp)
    Tracker "tracker" a trajectory tracker's const tables (gen/design/tracking.py)

A new backend is a subclass here (its templates under templates/<name>/)
and one line in BACKENDS.
"""
from __future__ import annotations

import copy
import math
import os
import shutil
import sys
import sysconfig
from pathlib import Path

import numpy as np

from . import eigen as eigen_face
from .eigen import CXX_RESERVED, eigen_version, find_eigen
from .product_abi import CConst, CEnum, CField, CFunction, CStruct, ProductInterface
from ..core.errors import BuildError, ModelError
from ..sym.printers import ModelCPrinter

__all__ = ["Backend", "CBackend", "EigenBackend", "FmuBackend", "CasadiBackend", "ProductBackend",
           "OcpBackend", "TrackerBackend", "BACKENDS", "get_backend",
           "backend_names", "c_compiler", "cxx_compiler", "eigen_include_dir",
           "RUNTIME_SOURCES", "RUNTIME_HEADERS", "RUNTIME_MAIN", "EIGEN_RUNTIME_HEADERS", "C_FLAGS",
           "C_LIN_FLAGS", "RUNTIME_FLAGS", "STRICT_FLAGS", "CXX_FLAGS", "CXX_STRICT_FLAGS",
           "LIB_SUFFIX", "CXX_RESERVED", "DERIVATIVE_SOURCES", "DERIVATIVE_HEADERS",
           "DERIVATIVE_FLAGS"]

# ------------------------------------------------------------ the runtime
# the C runtime every C-backend model links (csrc/)
RUNTIME_SOURCES = ["gen_rt_status.c", "gen_rt_linalg.c", "gen_rt_dynamics.c",
                   "gen_rt_project.c", "gen_rt_integrate.c", "gen_rt_linearize.c",
                   "gen_rt_model.c", "gen_rt_input.c", "gen_rt_engine.c", "gen_rt_events.c",
                   "gen_rt_simulate.c", "gen_rt_expm.c", "gen_rt_sens.c", "gen_rt_hybrid.c"]
RUNTIME_HEADERS = ["gen_rt.h", "gen_rt_status.h", "gen_rt_dopri5.h", "gen_rt_rodas4.h", "gen_rt_expm.h",
                   "gen_rt_sens.h", "gen_rt_ldlt.h", "gen_rt_private.h"]
# the derivative algorithms over a model's kernels and CasADi's calling
# convention over them (csrc/derivatives): the CasADi library's
DERIVATIVE_SOURCES = ["gen_rt_deriv.c", "gen_rt_casadi.c"]
DERIVATIVE_HEADERS = ["gen_rt_deriv.h", "gen_rt_casadi.h"]
# added for them (compiled with each library): clang's loop strength
# reduction over gen_rt_deriv.c's unrolled loop nests took 1.2 s of CPU per
# library, 0.5 s without unrolling, for the same per-call times (cart-pole
# jac_ of step 1.1-1.2 us, jac_adj1_ 4.2-4.4 us, jac_jac_ 13.4-14.5 us)
DERIVATIVE_FLAGS = ["-fno-unroll-loops"]
# the standalone simulator's runtime (main.c's program: the project's binary
# only, never a library's)
RUNTIME_MAIN = ["gen_rt_main.c", "gen_rt_main.h"]
# the C++ runtime of the Eigen backend and the tables it shares with the C one
# the Eigen face's own runtime header (beside the C runtime, which it links
# once per scalar type; gen/codegen/eigen.py)
EIGEN_RUNTIME_HEADERS = list(eigen_face.RUNTIME_HEADERS)

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


def eigen_include_dir():
    """The Eigen 3.4 include directory the eigen backend compiles against
    (BuildError when there is none)."""
    d, why = find_eigen()
    if d is None:
        raise BuildError(f"the eigen backend needs Eigen 3.4: {why}")
    return d


# --------------------------------------------------------- the templates
# (file name, template, role) for the C backend: the list is data. role:
# "model" (compiled into the model library by gen.build), "lin" (the
# derivative kernels, compiled apart; a plan without them gets "stub"
# instead, which gen.build links until they are built), "project" (the CMake
# project and the standalone simulator: gen.generate only)
C_TEMPLATES = [
    ("{name}.h", "c/model.h.j2", "model"),
    ("{name}.c", "c/model.c.j2", "model"),
    ("{name}_kernels.c", "c/model_kern.c.j2", "model"),    # the kernels, compiled apart
    ("{name}_lin.c", "c/model_lin.c.j2", "lin"),          # the derivative kernels
    ("{name}_lin_stub.c", "c/model_lin_stub.c.j2", "stub"),  # ... until they are built
    ("{name}_kernels.h", "c/model_kernels.h.j2", "model"),   # the functions of _lin.c
    ("{name}_api.c", "c/model_api.c.j2", "model"),        # the plugin table (gen/toolchain/host.py)
    ("gen_rt_config.h", "c/gen_rt_config.h.j2", "model"),  # the runtime's scalar type
    ("gen_rt_abi.h", "c/gen_rt_abi.h.j2", "model"),  # the runtime's structs and codes (gen/codegen/abi.py)
    ("main.c", "c/main.c.j2", "project"),
    ("CMakeLists.txt", "c/CMakeLists.txt.j2", "project"),
    ("arm-none-eabi.cmake", "c/arm-none-eabi.cmake.j2", "project"),  # Cortex-M4F toolchain
]

# The C++17/Eigen backend's own templates (the face, its CMake project):
# gen/codegen/eigen.py; the rest of its files are the C backend's, rendered twice.
EIGEN_TEMPLATES = list(eigen_face.TEMPLATES)

# The FMU's model sources: the C backend's, without the plugin table (the
# FMU's entry points are FMI's) and the project; gen/export/fmu.py adds the FMI
# glue (csrc/fmu) and the files of FMU_TEMPLATES.
FMU_MODEL_TEMPLATES = [t for t in C_TEMPLATES
                       if t[2] != "project" and t[0] != "{name}_api.c"]
# (file in the FMU, template), per FMI version: the list is data
FMU_TEMPLATES = {
    "2.0": [("modelDescription.xml", "fmu/fmi2/modelDescription.xml.j2"),
            ("sources/gen_fmu_model.h", "fmu/gen_fmu_model.h.j2")],
    "3.0": [("modelDescription.xml", "fmu/fmi3/modelDescription.xml.j2"),
            ("sources/buildDescription.xml", "fmu/fmi3/buildDescription.xml.j2"),
            ("sources/gen_fmu_model.h", "fmu/gen_fmu_model.h.j2")],
}
# the hand-written glue (csrc/fmu): the core and one layer per FMI version
FMU_GLUE = {"2.0": ["gen_fmu.h", "gen_fmu.c", "gen_fmu_fmi2.c"],
            "3.0": ["gen_fmu.h", "gen_fmu.c", "gen_fmu_fmi3.c"]}

# (CXX_RESERVED, the names a face's namespace may not take: gen/codegen/eigen.py)


# ------------------------------------------------------------ the types
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
        return [" ".join(C_FLAGS + ["lin:"] + C_LIN_FLAGS), c_compiler()]

    def units(self, name, files, derivatives, includes=()):
        """What gen.build compiles of files (the rendered sources), the
        largest first: [(file, compiler, flags)]; the runtime_sources come
        from the shared runtime objects."""
        raise NotImplementedError

    def diagnose(self, name, units):
        """(compiler, flags, files) that rerun a failed compile for a
        readable log (strict warnings, no Python)."""
        return (c_compiler(), STRICT_FLAGS,
                [f for f, _, _ in units if f.startswith(name)] + list(self.runtime_sources))

    def library_file(self, modname, name):
        """The library's file name in its cache folder."""
        return modname + LIB_SUFFIX

    def link_order(self, own, runtime):
        """The objects in link order (own: the units' objects in order)."""
        return [*own, *runtime]


class CBackend(Backend):
    """C99 over the C runtime: the model's kernels, its wiring and the
    plugin table, the derivative kernels in a unit of their own (-O1)
    that may be built on first use."""
    name = "c"
    templates = tuple(C_TEMPLATES)
    runtime_files = tuple(RUNTIME_SOURCES + RUNTIME_HEADERS)
    project_runtime_files = tuple(RUNTIME_MAIN)
    runtime_sources = tuple(RUNTIME_SOURCES)
    lin = "auto"
    lazy_derivatives = True
    fused_rhs = True
    stack_limit = True

    def printer(self, symbol_map, real):
        return ModelCPrinter(symbol_map, real)

    def units(self, name, files, derivatives, includes=()):
        cc = c_compiler()
        own = [(f"{name}_lin.c", C_LIN_FLAGS)] if derivatives else []
        own += [(f"{name}_kernels.c", ()), (f"{name}.c", ()), (f"{name}_api.c", ())]
        if not derivatives:
            own.append((f"{name}_lin_stub.c", ()))
        return [(f, cc, [*C_FLAGS, "-fPIC", *extra]) for f, extra in own]


class EigenBackend(CBackend):
    """C++17 over Eigen 3.4, a typed face over the one C runtime
    (gen/codegen/eigen.py): its library is the C backend's for the build's scalar
    type (the same files, the same API, the same bits), the C model and
    runtime again for the other scalar type under a prefixed name, and the
    face, <name>.hpp (Eigen types in and out, the scalar a template
    parameter), instantiated in <name>.cpp."""
    name = "eigen"
    templates = tuple(EIGEN_TEMPLATES)
    runtime_files = tuple(RUNTIME_SOURCES + RUNTIME_HEADERS + EIGEN_RUNTIME_HEADERS)
    project_runtime_files = tuple(RUNTIME_MAIN)
    runtime_sources = tuple(RUNTIME_SOURCES)
    # the plan of the C backend's (its library is the C backend's)
    lin = "auto"
    lazy_derivatives = False
    stack_limit = False
    composite = True
    tag = "_eigen"
    link_cxx = True

    def render(self, plan, real, timings, project, only, *, render_c, env):
        """The C backend's files for real, the C model again for the other
        scalar type, the face and the project (render_c: gen.codegen.render.render)."""
        return eigen_face.render(plan, real, timings, project, only, render_c=render_c,
                                  env=env, c_templates=C_TEMPLATES,
                                  runtime_sources=RUNTIME_SOURCES)

    def include_dir(self):
        """Eigen's include directory (gen/codegen/eigen.py finds it)."""
        return eigen_include_dir()

    def cache_parts(self):
        d = self.include_dir()
        # the backend, its flags and the Eigen it compiles against
        return [*super().cache_parts(),
                f"backend={self.name}\0{' '.join(CXX_FLAGS)}\0{cxx_compiler()}\0"
                f"eigen={d}:{eigen_version(d)}\0face"]

    def units(self, name, files, derivatives, includes=()):
        """The C backend's units, then the other scalar type's model and
        runtime (compiled with gen/codegen/eigen.py's ALT_DEFINE: the runtime's names
        prefixed) and the face (C++): [(file, compiler, flags, object)]."""
        cc = c_compiler()
        real = "float" if f"{eigen_face.alt_name(name, 'float')}.c" in files else "double"
        _, alt, cxx = eigen_face.sources(name, real, derivatives, C_TEMPLATES)
        alt_flag = "-D" + eigen_face.ALT_DEFINE
        units = [(f, c, fl, Path(f).stem + ".o")
                 for f, c, fl in super().units(name, files, derivatives, includes)]
        units += [(f, cc, [*C_FLAGS, "-fPIC", alt_flag,
                           *(C_LIN_FLAGS if f.endswith("_lin.c") else ())],
                   "alt_" + Path(f).stem + ".o") for f in alt]
        units += [(f, cc, [*RUNTIME_FLAGS, alt_flag], "alt_" + Path(f).stem + ".o")
                  for f in RUNTIME_SOURCES]
        units += [(f, cxx_compiler(), [*CXX_FLAGS, "-fPIC", "-isystem", str(self.include_dir())],
                   Path(f).stem + "_cxx.o") for f in cxx]
        return units

    def diagnose(self, name, units):
        cxx = [u[0] for u in units if u[0].endswith(".cpp")]
        return (cxx_compiler(), [*CXX_STRICT_FLAGS, "-isystem", str(self.include_dir())], cxx)


class FmuBackend(CBackend):
    """The C model for a Functional Mock-up Unit: the C backend's sources
    without the plugin table, the FMI glue, compiled against the importer's
    FMI headers (includes) with only the FMI functions exported; its
    library is <model>.so, the FMU's binary (gen/export/fmu.py)."""
    name = "fmu"
    templates = tuple(FMU_MODEL_TEMPLATES)
    lazy_derivatives = False
    loadable = False
    project = False
    project_runtime_files = ()
    stack_limit = False
    tag = "_fmu"
    fmu_templates = FMU_TEMPLATES
    glue = FMU_GLUE

    def cache_parts(self):
        return [*super().cache_parts(), f"backend={self.name}\0-fvisibility=hidden"]

    def units(self, name, files, derivatives, includes=()):
        cc = c_compiler()
        own = [f for f in files if f.endswith(".c") and not f.startswith("gen_rt_")]
        # the largest files first: the derivative kernels, the model
        own.sort(key=lambda f: (-len(files[f].encode()), f))
        inc = [x for d in includes for x in ("-isystem", str(d))]
        return [(f, cc, [*C_FLAGS, "-fPIC", "-fvisibility=hidden",
                         *(C_LIN_FLAGS if f == f"{name}_lin.c" else []), *inc]) for f in own]

    def library_file(self, modname, name):
        # FMI: binaries/<platform>/<modelIdentifier>.so
        return name + LIB_SUFFIX

    def link_order(self, own, runtime):
        return [*sorted(own), *runtime]


# The CasADi library's sources: the C backend's model (with its derivative
# kernels) without the plugin table, and the external-function wrappers
CASADI_TEMPLATES = [t for t in C_TEMPLATES if t[2] != "project" and t[0] != "{name}_api.c"] + [
    ("{name}_casadi.h", "casadi/casadi_ext.h.j2", "model"),
    ("{name}_casadi.c", "casadi/casadi_ext.c.j2", "model")]


class CasadiBackend(CBackend):
    """The C model as CasADi external functions (gen/export/casadi.py): the C
    backend's model and runtime, the derivative algorithms and CasADi's
    calling convention over them (csrc/derivatives: DERIVATIVE_SOURCES)
    and {name}_casadi.c, the functions' metadata and the wiring of the
    model's kernels and API to the runtime; one shared library for
    casadi.external, always with the derivative kernels. variant() gives
    the backend of a library without the second-derivative functions
    (gen.casadi.functions(model, hessians=False)) or the RODAS4 step."""
    name = "casadi"
    #: the second-derivative functions and kernels (jac_jac_, jac_fwd1_, jac_adj1_)
    hessians = True
    #: step_rodas4 (unconstrained models), whose first derivatives need the rhs Hessians
    rodas4 = True
    templates = tuple(CASADI_TEMPLATES)
    runtime_files = tuple(RUNTIME_SOURCES + RUNTIME_HEADERS + DERIVATIVE_SOURCES
                          + DERIVATIVE_HEADERS)
    lazy_derivatives = False
    loadable = False
    project = False
    project_runtime_files = ()
    stack_limit = False
    tag = "_casadi"

    def variant(self, hessians=True, rodas4=True):
        """This backend for a library with (or without) the second
        derivatives and the RODAS4 step; the same recipe, other sources."""
        b = copy.copy(self)
        b.hessians, b.rodas4 = bool(hessians), bool(rodas4)
        return b

    def context(self, model, kernels):
        from .casadi_kernels import library_context
        return library_context(model, lambda s: self.printer(s, "double"), self.hessians,
                               self.rodas4)

    def cache_parts(self):
        return [*super().cache_parts(),
                f"backend={self.name}\0{' '.join([*RUNTIME_FLAGS, *DERIVATIVE_FLAGS])}"]

    def units(self, name, files, derivatives, includes=()):
        cc = c_compiler()
        own = [(f"{name}_lin.c", C_LIN_FLAGS)] if derivatives else [(f"{name}_lin_stub.c", ())]
        own += [(f"{name}_kernels.c", ()), (f"{name}.c", ()), (f"{name}_casadi.c", ())]
        # the derivative runtime: compiled with the library (its objects are
        # not among the shared runtime's), hidden like the runtime's
        return [(f, cc, [*C_FLAGS, "-fPIC", *extra]) for f, extra in own] + \
            [(f, cc, [*RUNTIME_FLAGS, *DERIVATIVE_FLAGS]) for f in DERIVATIVE_SOURCES]

    def diagnose(self, name, units):
        cc, flags, files = super().diagnose(name, units)
        return cc, flags, [*files, *DERIVATIVE_SOURCES]


# ------------------------------------------------------------ the products
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


class OcpBackend(ProductBackend):
    """A direct-collocation problem's library (gen.OptimalControl,
    gen/design/ocp): the generated kernels of every family of the problem
    (values, sparse Jacobian, Hessian of the Lagrangian) in <name>.c, over
    the hand-written node loop (csrc/products/ocp/gen_rt_ocp.c), which
    gathers each instance's locals and scatters into IPOPT's arrays through
    the caller's index tables (gen_rt_ocp_block)."""
    name = "ocp"
    tag = ""
    templates = (("{name}.c", "ocp/ocp.c.j2", "product"),)
    runtime_files = ("gen_rt_ocp.c", "gen_rt_ocp.h", "gen_rt_status.h")
    interface = ProductInterface(
        product="ocp",
        doc="the optimal-control kernels of the model '{model}' over the node loop",
        types_header="gen_rt_ocp_abi.h",
        enums=(CEnum("what gen_rt_ocp_eval (a library's <prefix>_eval) computes", (
            CConst("GEN_RT_OCP_OBJECTIVE", 0, "the objective, out[0]"),
            CConst("GEN_RT_OCP_GRADIENT", 1, "its gradient, one per unknown"),
            CConst("GEN_RT_OCP_CONSTRAINTS", 2, "the constraints, one per row"),
            CConst("GEN_RT_OCP_JACOBIAN", 3, "the nonzeros of their Jacobian"),
            CConst("GEN_RT_OCP_HESSIAN", 4, "the nonzeros of the lower triangle of the "
                   "Hessian of the Lagrangian"))),),
        structs=(CStruct(
            "gen_rt_ocp_block", "One family's instances: where each gathers its locals "
            "from z, its rows, and where its Jacobian and Hessian nonzeros go.", (
                CField("family", "int", "index into the families"),
                CField("ninst", "int", "instances"),
                CField("gstart", "const int *", "ninst*nv + 1"),
                CField("gidx", "const int *", "z index, or -1 for the constant 1"),
                CField("gcoef", "const double *"),
                CField("data", "const double *", "ninst*nd"),
                CField("row0", "const int *", "ninst: first constraint row, < 0: objective"),
                CField("jstart", "const int *", "ninst + 1"),
                CField("jloc", "const int *", "local Jacobian nonzero"),
                CField("jslot", "const int *", "global Jacobian nonzero (or gradient entry)"),
                CField("jcoef", "const double *"),
                CField("hstart", "const int *", "ninst + 1"),
                CField("hloc", "const int *"),
                CField("hslot", "const int *"),
                CField("hcoef", "const double *"))),),
        functions=(
            CFunction("{name}_eval", "int", (
                ("const gen_rt_ocp_block *", "blocks"), ("int", "nblocks"),
                ("const double *", "z"), ("const double *", "p"), ("int", "what"),
                ("const double *", "lam"), ("double", "sigma"), ("double *", "work"),
                ("int", "nout"), ("double *", "out")),
                "The problem's what (GEN_RT_OCP_*) at the unknowns z, p the known constants: "
                "out (nout) zeroed, then filled by the blocks' instances. lam: the "
                "constraint multipliers and sigma the objective's factor (Hessian only); "
                "work: {name}_work_len() doubles. Returns 0, GEN_RT_ERR_NULL, or a "
                "kernel's negative status."),
            CFunction("{name}_work_len", "int", (),
                      "The doubles of work {name}_eval needs.")))

    def names(self, plan, real):
        return {**super().names(plan, real), "model": plan.data["model"]}


class TrackerBackend(ProductBackend):
    """A trajectory tracker's C (gen.TrajectoryTracker.to_c,
    gen/design/tracking.py): the reference and the gain schedule as const
    tables in <name>.c, its <name>_input and <name>_step over the model
    library's <p>_eval_input. It is compiled with its model's sources (a
    generated project, a firmware), never alone: rendered only."""
    name = "tracker"
    tag = "_tracker"
    templates = (("{name}.c", "tracker/tracker.c.j2", "product"),)
    interface = ProductInterface(
        product="tracker",
        doc="trajectory tracker of the model '{p}'",
        includes=('"{p}.h"',),
        macros=(
            CConst("{N}_N_GAIN", "{n_gain}",
                   "rows of the tables (the last: the terminal gain, held after the end)"),
            CConst("{N}_T0", "(({p}_real){t0})", "the time of row 0: {t0_text}"),
            CConst("{N}_PERIOD", "(({p}_real){period})",
                   "the sample period, the time between rows: {period_text}"),
            CConst("{N}_TABLE_BYTES", "{flash}",
                   "bytes of the const tables (flash): {table_bytes}")),
        functions=(
            CFunction("{name}_input", "void", (("{p}_input *", "in"),),
                      "Fill in (every field) with the tracker: the gain schedule and its "
                      "period."),
            CFunction("{name}_step", "int", (("{p}_real", "t"), ("const {p}_real *", "x"),
                                             ("{p}_real *", "r")),
                      "The inputs r ({P}_NR) at the sample time t from the state x "
                      "({P}_NX); 0 or a negative {P}_ERR_* status.")))

    def file_templates(self, iface):
        # its header's prose is its own (how to run it on a controller)
        return [("{name}.h", "tracker/tracker.h.j2", "product"), *self.templates]

    def names(self, plan, real):
        from .render import fmt_real
        d = plan.data
        fp = d["footprint"]
        table = ", ".join(f"{k} {fp[k]}" for k in ("K", "x_ref", "r_ref", "bounds") if fp[k])
        return {**super().names(plan, real), "N": plan.name.upper(), "P": d["model"].upper(),
                "n_gain": d["n_gain"], "t0": fmt_real(d["t0"], real),
                "t0_text": repr(float(d["t0"])), "period": fmt_real(d["period"], real),
                "period_text": repr(float(d["period"])), "flash": fp["flash"],
                "table_bytes": table}

    def context(self, plan, iface, real):
        """The tables as rows of C literals (an infinite bound as HUGE_VAL)."""
        from .render import fmt_real
        d = plan.data
        huge = "HUGE_VALF" if real == "float" else "HUGE_VAL"

        def lit(v):
            return fmt_real(v, real) if math.isfinite(v) else ("-" if v < 0 else "") + huge

        def rows(a, per):
            flat = [lit(float(v)) for v in np.asarray(a, dtype=float).ravel()]
            return [", ".join(flat[i:i + per]) for i in range(0, len(flat), per)]
        nr = d["nr"]
        return {"N": plan.name.upper(), "p": d["model"], "P": d["model"].upper(),
                "K_rows": rows(d["K"], d["ns"]), "x_rows": rows(d["x_op"], d["nx"]),
                "r_rows": rows(d["r_op"], max(nr, 1)),
                "r_min": None if d["r_min"] is None else rows(d["r_min"], nr)[0],
                "r_max": None if d["r_max"] is None else rows(d["r_max"], nr)[0]}

    def units(self, name, files, derivatives, includes=()):
        raise BuildError(f"the tracker {name!r} is compiled with its model's sources "
                         "(gen.generate, then TrajectoryTracker.to_c into the same folder), "
                         "not alone")


#: the registry: every backend, by name
BACKENDS = {b.name: b for b in (CBackend(), EigenBackend(), FmuBackend(), CasadiBackend(),
                                OcpBackend(), TrackerBackend())}


def backend_names(need=None):
    """The known backends' names; need: only those with that capability
    ("loadable", "project")."""
    return [n for n, b in BACKENDS.items() if need is None or getattr(b, need)]


def get_backend(backend, need=None):
    """The Backend of a name (or the object itself). An unknown name, or
    one without the capability need ("loadable": gen.compile loads it;
    "project": gen.generate writes it), is a ModelError listing the known
    ones."""
    b = backend if isinstance(backend, Backend) else BACKENDS.get(backend)
    if b is None or (need is not None and not getattr(b, need)):
        raise ModelError(f"unknown backend {backend!r}: choose one of {backend_names(need)}")
    return b
