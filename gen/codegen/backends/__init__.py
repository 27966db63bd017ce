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
    MPC     "mpc"     a model predictive controller over the model's C and the RTI and
                      QP runtime (csrc/products/mpc, gen/design/mpc)
    Estimator "estimator" a Kalman filter over the model's step (csrc/products/estimator,
                      gen/design/estimator)

A new backend is a module here, a subclass of Backend or ProductBackend
(gen/codegen/backends/base.py) with its templates under templates/<name>/,
and one line in BACKENDS below.
"""
from __future__ import annotations

from ...core.errors import ModelError
from .base import (C_FLAGS, C_LIN_FLAGS, CXX_FLAGS, CXX_STRICT_FLAGS, DERIVATIVE_HEADERS,
                   LIB_SUFFIX, RUNTIME_FLAGS, RUNTIME_HEADERS, RUNTIME_MAIN, RUNTIME_SOURCES,
                   STRICT_FLAGS, Backend, ProductBackend, c_compiler, cxx_compiler)
from .c import C_TEMPLATES, CBackend
from .casadi import CasadiBackend
from .estimator import EstimatorBackend
from .eigen import CXX_RESERVED, EIGEN_RUNTIME_HEADERS, EigenBackend, eigen_include_dir
from .fmu import FmuBackend
from .mpc import MpcBackend
from .ocp import OcpBackend
from .tracker import TrackerBackend

__all__ = ["Backend", "CBackend", "EigenBackend", "FmuBackend", "CasadiBackend", "ProductBackend",
           "OcpBackend", "TrackerBackend", "MpcBackend", "EstimatorBackend", "BACKENDS",
           "get_backend",
           "backend_names", "c_compiler", "cxx_compiler", "eigen_include_dir", "C_TEMPLATES",
           "RUNTIME_SOURCES", "RUNTIME_HEADERS", "RUNTIME_MAIN", "EIGEN_RUNTIME_HEADERS", "C_FLAGS",
           "C_LIN_FLAGS", "RUNTIME_FLAGS", "STRICT_FLAGS", "CXX_FLAGS", "CXX_STRICT_FLAGS",
           "LIB_SUFFIX", "CXX_RESERVED", "DERIVATIVE_HEADERS"]


#: the registry: every backend, by name
BACKENDS = {b.name: b for b in (CBackend(), EigenBackend(), FmuBackend(), CasadiBackend(),
                                OcpBackend(), TrackerBackend(), MpcBackend(),
                                EstimatorBackend())}


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
