"""Build rendered sources into a library (a plain shared library: the
model's kernels, the runtime and, for a loadable backend, its plugin table
``<name>_api.c``; or a product's library, gen/codegen/backends/
ProductBackend) in the cache (gen/core/cache.py), keyed by the content of the
files, the backend's compile recipe and the generator version. Nothing is
rendered or loaded here: gen/pipeline.py renders, gen/toolchain/host.py loads.

What is compiled, with which compiler and flags, is the backend's recipe
(gen/codegen/backends/: Backend.units, runtime_sources); this module runs it,
the model's files two at a time, the runtime's objects from a cache shared
by every library and FMU binary of a scalar type.

A model may be built without its derivative kernels first (the largest
code, needed only by linearize, jacobian, step_sensitivity and RODAS4);
build_derivatives adds them on first use, reusing the model's objects, and
records the result next to the first build, so later processes load the
complete library directly.

A build happens in a private temporary directory of the cache and is
published with an atomic rename, so two processes building the same model
at once both succeed and load the same library. A failed compile raises
BuildError with the full compiler log.
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from .._version import __version__
from ..codegen.backends import (C_FLAGS, C_LIN_FLAGS, RUNTIME_FLAGS, RUNTIME_HEADERS, RUNTIME_SOURCES,
                       c_compiler, cxx_compiler, get_backend)
from ..core.cache import cache_dir, cache_error, new_build_dir, publish, shipped, write_marker
from ..core.errors import BuildError

__all__ = ["build", "build_derivatives", "Built", "compile_units", "link_library"]


@dataclass
class Built:
    """A compiled library: the file, its cache folder's name (the module
    name), the interface, whether it has the derivative kernels (else
    their stand-ins: build_derivatives makes the complete library), and the
    backend's name."""
    path: Path
    modname: str
    interface: object
    derivatives: bool = True
    backend: str = "c"

    @property
    def folder(self) -> Path:
        return self.path.parent


# in a folder built without the derivative kernels: the name of the folder
# of the complete library, once build_derivatives has made it
_DERIVED = "derivatives"


def _hash(*parts):
    h = hashlib.sha256()
    for part in parts:
        h.update(part if isinstance(part, bytes) else str(part).encode())
        h.update(b"\0")
    return h.hexdigest()[:16]


def _check_platform():
    if os.name != "posix":
        raise BuildError("gen.compile builds model libraries with a POSIX C compiler (cc "
                         "-shared) and does not support this platform yet: generate the "
                         "sources with gen.generate and build them with CMake")


def _find_library(folder: Path, filename: str):
    lib = folder / filename
    return lib if lib.is_file() else None


def build(rendered, verbose=False, timings=None):
    """Compile a Rendered (gen.codegen.render.render(..., project=False)) into a
    library in the cache, keyed by the content of everything compiled and
    the backend's recipe; return a Built. A library built without the
    derivative kernels whose complete twin exists (build_derivatives) gives
    the twin. Nothing is rendered here."""
    iface = rendered.interface
    name, files = iface.name, rendered.files
    backend = get_backend(rendered.backend)
    includes = tuple(str(d) for d in rendered.includes)
    _check_platform()
    t1 = time.perf_counter()
    parts = [__version__, *backend.cache_parts(), *includes]
    for k in sorted(files):
        parts += [k, files[k]]
    key = _hash(*parts)
    modname = f"_eomgen_{name}{backend.tag}_{key}"
    libfile = backend.library_file(modname, name)
    root = cache_dir()
    final = root / modname
    lib = _find_library(final, libfile)
    if lib is not None:
        built = Built(lib, modname, iface, rendered.derivatives, backend.name)
        if timings is not None:
            timings["compile"] = 0.0
            timings["cached"] = True
        return _derived(built) or built
    tmp = new_build_dir(root, modname)
    try:
        src = _write_sources(tmp, root, files)
        units = backend.units(name, files, rendered.derivatives, includes)
        own, runtime = compile_units(src, tmp / "obj", units, backend, name)
        so = link_library(backend.link_order(own, runtime), tmp / libfile, cxx=backend.link_cxx)
        # a library without its derivative kernels keeps its objects for them
        _store(tmp, final, so, src, keep_objects=not rendered.derivatives)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    lib = _find_library(final, libfile)
    if lib is None:
        raise BuildError(f"the built library for '{name}' is missing from {final}")
    if timings is not None:
        timings["compile"] = time.perf_counter() - t1
        timings["cached"] = False
    return Built(lib, modname, iface, rendered.derivatives, backend.name)


def build_derivatives(base: Built, lin_source: str, timings=None):
    """The complete library of a model built without its derivative kernels
    (base): <name>_lin.c (lin_source) compiled and linked with base's own
    objects and the runtime's; cached, and recorded in base's folder so that
    build() of base's sources finds it. Returns its Built."""
    if base.derivatives:
        return base
    t1 = time.perf_counter()
    backend = get_backend(base.backend)
    name = base.interface.name
    key = _hash(base.modname, " ".join(C_FLAGS + ["lin:"] + C_LIN_FLAGS), lin_source)
    modname = f"_eomgen_{name}{backend.tag}_{key}"
    libfile = backend.library_file(modname, name)
    root = cache_dir()
    final = root / modname
    lib = _find_library(final, libfile)
    if lib is None:
        core = base.folder
        tmp = new_build_dir(root, modname)
        try:
            src = tmp / "src"
            try:
                shutil.copytree(core / "src", src)
                (src / f"{name}_lin_stub.c").unlink(missing_ok=True)
                (src / f"{name}_lin.c").write_text(lin_source)
                (tmp / "obj").mkdir()
            except OSError as e:
                raise cache_error(e, root, "write the sources") from None
            # (the units as the model's build chose them, from its sources)
            units = backend.units(name, {f.name: f.read_text() for f in src.glob("*.c")}, True)
            lin = [u for u in units if u[0] == f"{name}_lin.c"]
            objs = tmp / "obj"
            mine = [core / "obj" / (u[3] if len(u) > 3 else Path(u[0]).stem + ".o")
                    for u in units if u not in lin]
            if not all(o.is_file() for o in mine):
                # an older or pruned cache folder: compile the model again
                own, runtime = compile_units(src, objs, units, backend, name)
            else:
                own, runtime = compile_units(src, objs, lin, backend, name)
                own = own + mine
            so = link_library(backend.link_order(own, runtime), tmp / libfile,
                              cxx=backend.link_cxx)
            _store(tmp, final, so, src, keep_objects=False)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        lib = _find_library(final, libfile)
        if lib is None:
            raise BuildError(f"the built library for '{name}' is missing from {final}")
    write_marker(base.folder / _DERIVED, modname)
    if timings is not None:
        timings["compile_derivatives"] = time.perf_counter() - t1
    return Built(lib, modname, base.interface, True, base.backend)


def _derived(built: Built):
    """The complete twin of a library built without derivatives, if made."""
    if built.derivatives:
        return None
    try:
        modname = (built.folder / _DERIVED).read_text().strip()
    except OSError:
        return None
    if not re.fullmatch(r"_eomgen_\w+", modname):
        return None
    libfile = get_backend(built.backend).library_file(modname, built.interface.name)
    lib = _find_library(cache_dir() / modname, libfile)
    return None if lib is None else Built(lib, modname, built.interface, True, built.backend)


def _store(tmp: Path, final: Path, so: Path, src: Path, keep_objects: bool):
    """Move a finished build into the cache (gen.core.cache.publish)."""
    root = final.parent
    dest = tmp / final.name
    try:
        dest.mkdir()
        shutil.copy2(so, dest / so.name)
        shutil.copytree(src, dest / "src")
        if keep_objects:
            shutil.copytree(tmp / "obj", dest / "obj")
    except OSError as e:
        raise cache_error(e, root, "store the library") from None
    publish(dest, final, lambda: (final / so.name).is_file())


def _cc_object(cc, src: Path, fname: str, obj: Path, flags):
    """Compile src/fname into obj, run in src with relative names: no path
    of this machine in the object (an FMU's binary is reproducible)."""
    cmd = [cc, *flags, "-I", ".", "-c", fname, "-o", str(obj)]
    try:
        proc = subprocess.run(cmd, cwd=src, capture_output=True, text=True)
    except OSError as e:
        raise BuildError(f"the compiler {cc!r} cannot be run: {e}") from None
    if proc.returncode != 0:
        raise BuildError(f"compiling {fname} failed",
                         "$ " + " ".join(cmd) + "\n" + proc.stdout + proc.stderr)
    return obj


def _compile_log(src_dir: Path, sources, compiler, flags):
    """Compile the sources alone (no Python) to capture a readable log."""
    logs = []
    ok = True
    for s in sources:
        cmd = [compiler, *flags, "-c", str(src_dir / s), "-o", os.devnull, "-I", str(src_dir)]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0 or proc.stderr.strip():
            logs.append("$ " + " ".join(cmd) + "\n" + proc.stdout + proc.stderr)
        ok = ok and proc.returncode == 0
    return ok, "\n".join(logs)


def _runtime_objects(src: Path, cc: str, sources=RUNTIME_SOURCES):
    """The runtime's object files, from a cache shared by every model
    library and FMU binary: keyed by the runtime sources, the scalar-type
    header, the flags and the compiler. Returns (objects ready, or None and
    the folder to publish them in)."""
    h = hashlib.sha256()
    h.update(__version__.encode() + b"\0" + " ".join([cc, *RUNTIME_FLAGS]).encode())
    try:
        h.update(subprocess.run([cc, "--version"], capture_output=True, text=True).stdout.encode())
    except OSError as e:
        raise BuildError(f"the C compiler {cc!r} cannot be run: {e}") from None
    # every runtime source and header (a header missing here would leave
    # stale objects in the cache when it changes)
    for name in (sorted(RUNTIME_SOURCES) + sorted(RUNTIME_HEADERS)
                 + ["gen_rt_config.h", "gen_rt_abi.h"]):
        h.update(name.encode() + b"\0" + (src / name).read_bytes() + b"\0")
    folder = cache_dir() / f"runtime_{h.hexdigest()[:16]}"
    objs = [folder / (Path(s).stem + ".o") for s in sources]
    if all(o.is_file() for o in objs):
        return objs, None
    pre = shipped(folder.name)                     # built at install time
    if pre is not None and all((pre / o.name).is_file() for o in objs):
        return [pre / o.name for o in objs], None
    return None, folder


def link_library(objects, out: Path, cxx=False) -> Path:
    """cc -shared objects -lm -o out."""
    cc = cxx_compiler() if cxx else c_compiler()
    cmd = [cc, "-shared", *[str(o) for o in objects], "-lm", "-o", str(out)]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        raise BuildError(f"the compiler {cc!r} cannot be run: {e}") from None
    if proc.returncode != 0:
        raise BuildError(f"linking {out.name} failed",
                         "$ " + " ".join(cmd) + "\n" + proc.stdout + proc.stderr)
    return out


def compile_units(src: Path, objdir: Path, units, backend, name):
    """Compile a build's own files (units: [(file, compiler, flags)], the
    largest first, Backend.units) and, unless cached, the backend's runtime
    sources, two at a time; return (own objects in order, runtime objects).
    A failure is one BuildError with the strict compile's log
    (Backend.diagnose)."""
    from concurrent.futures import ThreadPoolExecutor
    rt_sources = list(backend.runtime_sources)
    runtime, rt_folder = [], None
    cc = c_compiler()
    if rt_sources:
        runtime, rt_folder = _runtime_objects(src, cc, rt_sources)
    # a unit is (file, compiler, flags) or (file, compiler, flags, object name)
    jobs = [(u[1], u[0], objdir / (u[3] if len(u) > 3 else Path(u[0]).stem + ".o"), list(u[2]))
            for u in units]
    n_own = len(jobs)
    if runtime is None:
        rt_tmp = objdir.parent / "runtime"
        rt_tmp.mkdir()
        jobs += [(cc, s, rt_tmp / (Path(s).stem + ".o"), RUNTIME_FLAGS) for s in rt_sources]
    with ThreadPoolExecutor(max_workers=max(1, min(len(jobs), os.cpu_count() or 1))) as ex:
        futures = [ex.submit(_cc_object, c, src, f, o, fl) for c, f, o, fl in jobs]
        try:
            results = [f.result() for f in futures]
        except BuildError as err:
            compiler, flags, files = backend.diagnose(name, units)
            _, log = _compile_log(src, files, compiler, flags)
            raise BuildError(f"compiling the model '{name}' failed", log or err.log) from None
    if runtime is None:
        # publish the runtime objects for the next model (atomic rename; a
        # concurrent builder that got there first wins, both are identical)
        try:
            rt_folder.parent.mkdir(parents=True, exist_ok=True)
            os.rename(rt_tmp, rt_folder)
            runtime = [rt_folder / Path(o).name for o in results[n_own:]]
        except OSError:
            runtime = results[n_own:]
            if all((rt_folder / Path(o).name).is_file() for o in runtime):
                runtime = [rt_folder / Path(o).name for o in runtime]
    return results[:n_own], runtime


def _write_sources(tmp, root, files):
    """Write files {name: text} into tmp/src and make tmp/obj; the source
    folder. An OS error is the cache's (cache_error, naming root)."""
    src = tmp / "src"
    try:
        src.mkdir()
        for fname, text in files.items():
            (src / fname).write_text(text)
        (tmp / "obj").mkdir()
    except OSError as e:
        raise cache_error(e, root, "write the sources") from None
    return src
