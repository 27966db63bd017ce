"""The C backend: C99 over the C runtime (csrc/), the model's kernels, its
wiring and the plugin table; gen.compile and gen.generate."""
from __future__ import annotations

from ...sym.printers import ModelCPrinter
from .base import (C_FLAGS, C_LIN_FLAGS, C_WIRING_FLAGS, RUNTIME_HEADERS, RUNTIME_MAIN, RUNTIME_SOURCES, Backend,
                   c_compiler)

__all__ = ["C_TEMPLATES", "CBackend"]

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


# a kernels unit at least this large (the right-hand side of a robot of some
# 30 joints: Talos, 390 kB), or with a large kernel's two versions, is
# compiled at -O1, as the derivative kernels are: clang's time on Talos's
# 3.8 -> 2.6 s of CPU, its right-hand side as fast (3.79 us at -O1, 3.90 us
# at -O2, medians of 3; bench/README.md "Robots"); the n = 16 cart's two
# units 0.35 + 0.30 -> 0.24 + 0.18 s, rhs_batch per state 568 -> 575 ns
# (n = 20: 1560 -> 1416 ns; gcc: 616 -> 619, 978 -> 1048 ns; speed guide)
LARGE_KERNELS = 256 * 1024


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
        kern = f"{name}_kernels.c"
        own = [(f"{name}_lin.c", C_LIN_FLAGS)] if derivatives else []
        text = files.get(kern, "")
        large = "GEN_RT_CLONES static" in text
        level = tuple(C_LIN_FLAGS) if large or len(text.encode()) >= LARGE_KERNELS else ()
        # the wiring first: compiled two at a time, its fixed cost (0.1-0.3 s
        # of clang) runs beside the kernels' units instead of after them
        # (n = 8 cart: the compile's wall 0.33 -> 0.25 s)
        own.append((f"{name}.c", C_WIRING_FLAGS if large else ()))
        if large:
            # a large kernel's two versions (GEN_RT_CLONES), compiled apart and in
            # parallel (GEN_RT_CLONE_UNIT in gen_rt.h): the same code, half the wait
            own += [(kern, ("-DGEN_RT_CLONE_UNIT=1", *level)),
                    (kern, ("-DGEN_RT_CLONE_UNIT=2", *level), f"{name}_kernels_avx.o")]
        else:
            own.append((kern, level))
        own.append((f"{name}_api.c", ()))
        if not derivatives:
            own.append((f"{name}_lin_stub.c", ()))
        return [(u[0], cc, [*C_FLAGS, "-fPIC", *u[1]], *u[2:]) for u in own]
