"""The FMU backend: the C model with the FMI glue (csrc/products/fmu),
compiled against the importer's FMI headers, for gen.export_fmu."""
from __future__ import annotations

from .base import C_FLAGS, C_LIN_FLAGS, LIB_SUFFIX, c_compiler
from .c import C_TEMPLATES, CBackend

__all__ = ["FMU_MODEL_TEMPLATES", "FMU_TEMPLATES", "FMU_GLUE", "FmuBackend"]

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
