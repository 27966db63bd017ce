"""Finding Eigen 3.4 for the C++/Eigen backend: a real installation, never a
vendored copy. Looked for, in order: the EIGEN3_INCLUDE_DIR environment
variable, the cmeel-eigen wheel (``<site-packages>/cmeel.prefix``), a conda
environment, then the usual system directories (Debian/Ubuntu libeigen3-dev,
Homebrew, MacPorts)."""
from __future__ import annotations

import copy
import dataclasses
import os
import re
import site
import sys
import sysconfig

from ...core.errors import BuildError
from .base import (C_FLAGS, C_LIN_FLAGS, CXX_FLAGS, CXX_STRICT_FLAGS, RUNTIME_FLAGS, RUNTIME_HEADERS,
                   RUNTIME_MAIN, RUNTIME_SOURCES, c_compiler, cxx_compiler)
from .c import C_TEMPLATES, CBackend
from pathlib import Path

__all__ = ["find_eigen", "eigen_version", "MIN_VERSION", "render", "sources", "alt_name",
           "other_real", "EigenBackend", "EIGEN_TEMPLATES",
           "eigen_include_dir", "EIGEN_RUNTIME_HEADERS"]

MIN_VERSION = (3, 4, 0)
_SYSTEM_DIRS = ["/usr/include/eigen3", "/usr/local/include/eigen3",
                "/opt/homebrew/include/eigen3", "/opt/local/include/eigen3"]


def eigen_version(include_dir):
    """(world, major, minor) of the Eigen under include_dir, or None."""
    macros = Path(include_dir) / "Eigen" / "src" / "Core" / "util" / "Macros.h"
    try:
        text = macros.read_text(errors="replace")
    except OSError:
        return None
    v = []
    for part in ("WORLD", "MAJOR", "MINOR"):
        m = re.search(rf"#define\s+EIGEN_{part}_VERSION\s+(\d+)", text)
        if not m:
            return None
        v.append(int(m.group(1)))
    return tuple(v)


def _candidates():
    env = os.environ.get("EIGEN3_INCLUDE_DIR")
    if env:
        yield Path(env).expanduser()
    roots = [sysconfig.get_paths().get("purelib"), sysconfig.get_paths().get("platlib")]
    try:
        roots += site.getsitepackages() + [site.getusersitepackages()]
    except AttributeError:  # some virtualenvs
        pass
    roots += [p for p in sys.path if p.endswith("site-packages")]
    for r in roots:
        if r:
            yield Path(r) / "cmeel.prefix" / "include" / "eigen3"
    conda = os.environ.get("CONDA_PREFIX")
    if conda:
        yield Path(conda) / "include" / "eigen3"
    for d in _SYSTEM_DIRS:
        yield Path(d)


def find_eigen():
    """(include dir, version tuple) of the first Eigen >= 3.4 found, or
    (None, reason) when there is none."""
    seen = []
    for d in _candidates():
        if d in seen:
            continue
        seen.append(d)
        if (d / "Eigen" / "Dense").is_file():
            v = eigen_version(d)
            if v is not None and v >= MIN_VERSION:
                return d.resolve(), v
    return None, ("Eigen >= 3.4 not found (looked in: " + ", ".join(str(s) for s in seen)
                  + "); install libeigen3-dev (Debian/Ubuntu) or the cmeel-eigen wheel, "
                  "or set EIGEN3_INCLUDE_DIR")


# ------------------------------------------------------------ the backend
# The C++/Eigen backend is a typed face over the one C runtime: its library
# is the C backend's model and runtime for the build's scalar type (the C
# API <name>_*, the same files, so the same bits), the same model and
# runtime again for the other scalar type (<name>_s_* for float, <name>_d_*
# for double; the runtime's names prefixed by csrc/eigen/gen_rt_names.h in
# the translation units compiled with GEN_RT_ALT_REAL), and <name>.hpp, the
# header-only face: Eigen types in and out, the scalar a template parameter
# that picks the C functions of its type. No algorithm of its own.

# (file name, template, role) of the backend's own files; the rest are the
# C backend's (gen/codegen/render.py C_TEMPLATES), rendered twice
TEMPLATES = [
    ("{name}.hpp", "eigen/model.hpp.j2", "model"),        # the typed face
    ("{name}.cpp", "eigen/model.cpp.j2", "model"),        # the face instantiated (a check)
    ("gen_rt_config.h", "eigen/gen_rt_config.h.j2", "model"),  # which scalar type a unit has
    ("CMakeLists.txt", "eigen/CMakeLists.txt.j2", "project"),
]
# copied from csrc/ beside the C runtime
EIGEN_RUNTIME_HEADERS = ["eigen/gen_rt_names.h"]
# the define that makes a translation unit the other scalar type's
ALT_DEFINE = "GEN_RT_ALT_REAL"
# BLAS's letters: the suffix of the second copy's prefix
_LETTER = {"float": "s", "double": "d"}


def other_real(real):
    """The scalar type of the second copy."""
    return "float" if real == "double" else "double"


def alt_name(name, real):
    """The C prefix of the second copy of a model built for `real`."""
    return f"{name}_{_LETTER[other_real(real)]}"


def _renamed(plan, name):
    """The plan with its model under another name (the C prefix)."""
    model = copy.copy(plan.model)
    model.name = name
    return dataclasses.replace(plan, model=model)


def render(plan, real, timings, project, only, *, render_c, env, c_templates,
           runtime_sources):
    """The Eigen backend's files (gen.codegen.render.render with backend="eigen",
    which passes its C backend's render function, template environment,
    template list and runtime sources): the C backend's files for `real`,
    the C model again for the other scalar type under alt_name's prefix,
    the face and the CMake project."""
    from ...core.resources import csrc_file
    name = plan.model.name
    if name in CXX_RESERVED:
        from ..core.errors import ModelError
        raise ModelError(f"model name {name!r} is a C++ keyword or reserved namespace; the "
                         f"Eigen backend uses the name as a namespace: choose another "
                         f"(for example 'my_{name}')")
    main = render_c(plan, real=real, backend="c", timings=timings, project=project, only=only)
    alt = alt_name(name, real)
    roles = set(only) if only else ({"model", "lin" if plan.derivatives else "stub"}
                                    | ({"project"} if project else set()))
    files = {k: v for k, v in main.files.items()
             if k not in ("CMakeLists.txt", "arm-none-eabi.cmake")}
    alt_roles = roles & {"model", "lin", "stub"}
    if alt_roles:
        second = render_c(_renamed(plan, alt), real=other_real(real), backend="c",
                          project=False, only=alt_roles)
        files.update({k: v for k, v in second.files.items()
                      if k not in ("gen_rt_config.h", f"{alt}_api.c")})
    ctx = context(main.interface, real, c_templates, runtime_sources)
    for fname, tname, role in TEMPLATES:
        if role in roles:
            files[fname.format(name=name)] = env.get_template(tname).render(**ctx)
    for src in EIGEN_RUNTIME_HEADERS if only is None else ():
        files[Path(src).name] = csrc_file(src).read_text()
    return dataclasses.replace(main, files=files, backend="eigen")


def sources(name, real, derivatives, c_templates):
    """What an Eigen build compiles: (C files of the build's scalar type as
    the C backend has them, C files of the other type (compiled with
    ALT_DEFINE, with the runtime's), C++ files); c_templates: the C
    backend's (file, template, role) list (gen/codegen/render.py C_TEMPLATES)."""
    roles = ("model", "lin" if derivatives else "stub")

    def model_c(n):
        return [f.format(name=n) for f, _, role in c_templates
                if f.endswith(".c") and role in roles and f != "{name}_api.c"]
    return model_c(name), model_c(alt_name(name, real)), [f"{name}.cpp"]


def context(iface, real, c_templates, runtime_sources):
    """The Jinja2 context of the face."""
    from ..._version import __version__
    from ..abi import METHODS
    name = iface.name
    alt = alt_name(name, real)
    main_c, alt_c, cxx = sources(name, real, True, c_templates)

    def lit(v, r):
        s = repr(float(v))
        return s + "F" if r == "float" else s
    sizes = iface.sizes
    return {
        "iface": iface, "name": name, "p": name, "P": name.upper(), "version": __version__,
        "real": real, "alt_real": other_real(real), "alt": alt, "ALT": alt.upper(),
        "alt_define": ALT_DEFINE,
        # (scalar type, C prefix): the build's own first
        "copies": [(real, name), (other_real(real), alt)],
        "sizes": sizes, "methods": sorted(METHODS.items(), key=lambda kv: kv[1]),
        "p_default": {r: [lit(v, r) for v in iface.constants] for r in ("float", "double")},
        "partition": {k: getattr(iface, k) for k in ("q_ind", "q_dep", "u_ind", "u_dep")},
        "runtime_sources": runtime_sources,
        "model_sources": main_c, "alt_sources": alt_c, "cxx_sources": cxx,
        "eigen_type": _eigen_type,
        "structs": {s.name: s.cxx_name for s in iface.structs},
    }


# the face's name of a C array size (gen/codegen/abi.py size expressions)
_TYPES = {"NX": "State", "NQ": "Coords", "NU": "Speeds", "NR": "Inputs", "NP": "Params",
          "MV": "Multipliers", "MC": "ConfigResiduals", "NA": "AuxiliaryForces",
          "NY": "Outputs", "NH": "HybridValues", "NU*NU": "MassMatrix", "MC*NQ": "ConstraintJacobian",
          "MV*NU": "VelocityMatrix", "NS*NS": "StateMatrix", "NS*NR": "InputMatrix",
          "NY*NS": "OutputMatrix", "NY*NR": "FeedthroughMatrix"}


def _eigen_type(size, scalar="S"):
    """The fixed-size Eigen type of an array parameter of size `size`."""
    if size in _TYPES:
        return f"{_TYPES[size]}<{scalar}>"
    rows, _, cols = size.partition("*")
    return f"Mat<{scalar}, {rows}, {cols or 1}>"


# the model prefix is also the C++ namespace of the face
CXX_RESERVED = frozenset("""
alignas alignof and and_eq asm auto bitand bitor bool break case catch char char8_t
char16_t char32_t class compl concept const consteval constexpr constinit const_cast
continue co_await co_return co_yield decltype default delete do double dynamic_cast
else enum explicit export extern false float for friend goto if inline int long
mutable namespace new noexcept not not_eq nullptr operator or or_eq private
protected public register reinterpret_cast requires return short signed sizeof
static static_assert static_cast struct switch template this thread_local throw
true try typedef typeid typename union unsigned using virtual void volatile
wchar_t while xor xor_eq std Eigen eomgen detail gen_rt
""".split())


# ------------------------------------------------------------ the backend
# the C++ runtime of the Eigen backend and the tables it shares with the C one
# the Eigen face's own runtime header (beside the C runtime, which it links
# once per scalar type; gen/codegen/eigen.py)

# The C++17/Eigen backend's own templates (the face, its CMake project):
# gen/codegen/eigen.py; the rest of its files are the C backend's, rendered twice.
EIGEN_TEMPLATES = list(TEMPLATES)

def eigen_include_dir():
    """The Eigen 3.4 include directory the eigen backend compiles against
    (BuildError when there is none)."""
    d, why = find_eigen()
    if d is None:
        raise BuildError(f"the eigen backend needs Eigen 3.4: {why}")
    return d


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
        return render(plan, real, timings, project, only, render_c=render_c,
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
        real = "float" if f"{alt_name(name, 'float')}.c" in files else "double"
        _, alt, cxx = sources(name, real, derivatives, C_TEMPLATES)
        alt_flag = "-D" + ALT_DEFINE
        units = [(*u[:3], u[3] if len(u) > 3 else Path(u[0]).stem + ".o")
                 for u in super().units(name, files, derivatives, includes)]
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
