"""The CasADi backend: the C model as CasADi external functions, the
derivative algorithms of csrc/derivatives and CasADi's calling convention
over them, compiled into the library's own file for its model
(gen.casadi)."""
from __future__ import annotations

import copy

from .base import (C_FLAGS, C_LIN_FLAGS, DERIVATIVE_HEADERS, RUNTIME_HEADERS, RUNTIME_SOURCES,
                   c_compiler)
from .c import C_TEMPLATES, CBackend

__all__ = ["CASADI_TEMPLATES", "CasadiBackend"]

# The CasADi library's sources: the C backend's model (with its derivative
# kernels) without the plugin table, and the external-function wrappers
CASADI_TEMPLATES = [t for t in C_TEMPLATES if t[2] != "project" and t[0] != "{name}_api.c"] + [
    ("{name}_casadi.h", "casadi/casadi_ext.h.j2", "model"),
    ("{name}_casadi.c", "casadi/casadi_ext.c.j2", "model")]


class CasadiBackend(CBackend):
    """The C model as CasADi external functions (gen/export/casadi.py): the C
    backend's model and runtime, and {name}_casadi.c, the functions'
    metadata and the wiring of the model's kernels and API to the runtime's
    derivative algorithms and CasADi's calling convention over them
    (csrc/derivatives: DERIVATIVE_HEADERS, static inline functions the file
    compiles with its model as a constant); one shared library for
    casadi.external, always with the derivative kernels. variant() gives
    the backend of a library without the second-derivative functions
    (gen.casadi.functions(model, hessians=False)) or the RODAS4 step."""
    name = "casadi"
    #: the second-derivative functions and kernels (jac_jac_, jac_fwd1_, jac_adj1_)
    hessians = True
    #: step_rodas4 (unconstrained models), whose first derivatives need the rhs Hessians
    rodas4 = True
    templates = tuple(CASADI_TEMPLATES)
    runtime_files = tuple(RUNTIME_SOURCES + RUNTIME_HEADERS + DERIVATIVE_HEADERS)
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
        from ..casadi_kernels import library_context
        return library_context(model, lambda s: self.printer(s, "double"), self.hessians,
                               self.rodas4)

    def cache_parts(self):
        return [*super().cache_parts(), f"backend={self.name}"]

    def units(self, name, files, derivatives, includes=()):
        cc = c_compiler()
        own = [(f"{name}_lin.c", C_LIN_FLAGS)] if derivatives else [(f"{name}_lin_stub.c", ())]
        # {name}_casadi.c: the derivative algorithms compiled for the model
        # (the runtime's gen_rt_*_inline.h), the largest unit
        own = [(f"{name}_casadi.c", ())] + own + [(f"{name}_kernels.c", ()), (f"{name}.c", ())]
        return [(f, cc, [*C_FLAGS, "-fPIC", *extra]) for f, extra in own]
