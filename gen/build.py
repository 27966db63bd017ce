"""Build generated sources into a model library (a plain shared library:
the model's kernels, the runtime and its plugin table ``<name>_api.c``) in a
cache keyed by the content of the generated files and the generator
version. Python calls every model through one host module (gen/host.py),
so a model's build compiles no Python binding code.

A model is compiled without its derivative kernels first (the largest
code, needed only by linearize, jacobian, step_sensitivity and RODAS4);
build_derivatives adds them on first use, reusing the model's objects, and
records the result next to the first build, so later processes load the
complete library directly.

Builds happen in a private temporary directory and are moved into the
cache with an atomic rename, so two processes building the same model at
once both succeed and load the same library. A failed compile raises
BuildError with the full compiler log.

The cache (cache_dir(): $EOMGEN_CACHE, else $XDG_CACHE_HOME/eomgen or
~/.cache/eomgen) holds one folder per built library (``_eomgen_<name>_<key>``),
the shared runtime objects (``runtime_<key>``) and the host modules
(``host_<real>_<key>``); everything in it can be deleted at any time
(cache_info, clear_cache). A build's temporary directory
is ``.<module>.<pid>.XXXX`` (with an ``owner`` file: pid and host); one left
by a killed process (dead pid on this host, or older than STALE_SECONDS) is
removed by the next build. A cache that cannot be written (read-only, full,
not a directory) is one BuildError naming the folder and EOMGEN_CACHE.
"""
from __future__ import annotations

import errno
import hashlib
import os
import re
import socket
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

from ._version import __version__
from .errors import BuildError, ModelError
from .eigen import eigen_version, find_eigen
from .ir import DERIVATIVE_KERNELS, plan as make_plan, with_derivatives
from .render import C_TEMPLATES, RUNTIME_HEADERS, RUNTIME_SOURCES, Rendered, plan_lin, render

__all__ = ["compile", "cache_dir", "build", "build_derivatives", "load", "Built", "cache_info",
           "clear_cache", "compile_objects", "link_library"]

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
BACKENDS = ("c", "eigen")


def cache_dir() -> Path:
    env = os.environ.get("EOMGEN_CACHE")
    if env:
        return Path(env).expanduser().resolve()
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "eomgen"


# a temporary build directory whose owner cannot be checked (other host, no
# owner file) is stale after this long; one whose process is dead at once
STALE_SECONDS = 30 * 60
# what eomgen puts in the cache: module folders, runtime objects, temporary dirs
_ENTRY = re.compile(r"^(_eomgen_\w+|runtime_[0-9a-f]{16}|host_(?:double|float)_[0-9a-f]{16}"
                    r"|templates_[0-9a-f]{16})$")
# (older eomgen versions wrote no pid: .<module>.XXXXXXXX, stale by age)
_TEMP = re.compile(r"^\.(_eomgen_\w+|runtime_[0-9a-f]{16}|host_(?:double|float)_[0-9a-f]{16})"
                   r"\.(?:(\d+)\.)?\w+$")


def _cache_error(e: OSError, folder: Path, what: str):
    """A BuildError for a cache that cannot be written, in one line."""
    why = e.strerror or str(e)
    if e.errno in (errno.ENOTDIR, errno.EEXIST):
        why = "it or a part of its path is not a directory"
    elif e.errno in (errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)):
        why = "no space left on the device"
    return BuildError(f"cannot {what} in the eomgen cache {folder} ({why}): set EOMGEN_CACHE to "
                      "a writable folder (or free space there)")


_CACHE_ERRNOS = {errno.EACCES, errno.EPERM, errno.EROFS, errno.ENOSPC, errno.ENOTDIR,
                 getattr(errno, "EDQUOT", errno.ENOSPC)}


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:   # alive, another user's
        return True
    except OSError:
        return False
    return True


def _temp_is_stale(path: Path, now=None) -> bool:
    """A temporary build directory left by a dead or long-gone process."""
    now = time.time() if now is None else now
    m = _TEMP.match(path.name)
    if m is None:
        return False
    try:
        age = now - path.stat().st_mtime
    except OSError:
        return False
    host, pid = None, (int(m.group(2)) if m.group(2) else None)
    try:
        fields = (path / "owner").read_text().split()
        pid, host = int(fields[0]), fields[1]
    except (OSError, ValueError, IndexError):
        pass
    if pid is not None and (host is None or host == socket.gethostname()):
        if not _pid_alive(pid):
            return True
        if host is not None:
            return age > 24 * 3600   # a reused pid does not keep it forever
    return age > STALE_SECONDS


def clean_stale(root=None):
    """Remove the temporary build directories of killed builds; returns the
    paths removed. Errors (a read-only cache) are ignored."""
    root = Path(root) if root is not None else cache_dir()
    removed = []
    try:
        items = list(root.iterdir())
    except OSError:
        return removed
    now = time.time()
    for d in items:
        if d.name.startswith(".") and d.is_dir() and _temp_is_stale(d, now):
            shutil.rmtree(d, ignore_errors=True)
            if not d.exists():
                removed.append(d)
    return removed


def _make_temp(root: Path, modname: str) -> Path:
    """A private build directory in the cache, named and marked with our pid."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{modname}.{os.getpid()}.", dir=root))
    (tmp / "owner").write_text(f"{os.getpid()} {socket.gethostname()} {time.time():.0f}\n")
    return tmp


def _entries(root: Path):
    """eomgen's entries in the cache folder (module folders, runtime objects,
    temporary build directories), nothing else."""
    try:
        items = sorted(root.iterdir())
    except FileNotFoundError:
        return []
    return [d for d in items if _ENTRY.match(d.name) or _TEMP.match(d.name)]


def _size(path: Path) -> int:
    if path.is_symlink() or not path.is_dir():
        try:
            return path.lstat().st_size
        except OSError:
            return 0
    total = 0
    for dirpath, _dirs, fnames in os.walk(path):
        for f in fnames:
            try:
                total += os.lstat(os.path.join(dirpath, f)).st_size
            except OSError:
                pass
    return total


def cache_info():
    """{"path", "exists", "modules", "runtimes", "hosts", "temporary", "entries",
    "bytes"} of the build cache (only eomgen's entries are counted)."""
    root = cache_dir()
    ents = _entries(root)
    mods = [d for d in ents if d.name.startswith("_eomgen_")]
    rts = [d for d in ents if d.name.startswith("runtime_")]
    hosts = [d for d in ents if d.name.startswith("host_")]
    tmps = [d for d in ents if d.name.startswith(".")]
    return {"path": root, "exists": root.is_dir(), "modules": len(mods), "runtimes": len(rts),
            "hosts": len(hosts), "temporary": len(tmps),
            "entries": len(mods) + len(rts) + len(hosts), "bytes": sum(_size(d) for d in ents)}


def clear_cache():
    """Delete eomgen's entries from the cache (other files are left, and so
    are the temporary directories of builds running now); returns
    (entries removed, bytes freed). Modules already loaded keep working."""
    root = cache_dir()
    removed, freed = 0, 0
    for d in _entries(root):
        if d.name.startswith(".") and not _temp_is_stale(d):
            continue   # a build in progress
        size = _size(d)
        try:
            if d.is_dir() and not d.is_symlink():
                shutil.rmtree(d)
            else:
                d.unlink()
        except OSError as e:
            raise _cache_error(e, root, f"delete {d.name}") from None
        removed += 1
        freed += size
    return removed, freed


def _compiler():
    """$CC; else clang when it is installed (it compiles a model's large
    straight-line kernels about three times faster than GCC: n = 20 cart
    right-hand side 3.1 -> 1.0 s; the arithmetic is the same IEEE
    arithmetic, -ffp-contract=off, and the golden numbers are bit for bit
    the same); else the compiler Python was built with."""
    cc = os.environ.get("CC")
    if not cc:
        cc = "clang" if shutil.which("clang") else (sysconfig.get_config_var("CC") or "cc")
    return cc.split()[0]


def _cxx_compiler():
    """$CXX; else clang++ when it is installed (as _compiler); else the
    C++ compiler Python was built with, or g++."""
    cxx = os.environ.get("CXX")
    if not cxx:
        cxx = ("clang++" if shutil.which("clang++")
               else (sysconfig.get_config_var("CXX") or "g++"))
    return cxx.split()[0]


def _compile_log(src_dir: Path, sources, extra_flags=(), compiler=None, flags=STRICT_FLAGS):
    """Compile the sources alone (no Python) to capture a readable log."""
    logs = []
    ok = True
    for s in sources:
        cmd = [compiler or _compiler(), *flags, *extra_flags, "-c", str(src_dir / s), "-o",
               os.devnull, "-I", str(src_dir)]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0 or proc.stderr.strip():
            logs.append("$ " + " ".join(cmd) + "\n" + proc.stdout + proc.stderr)
        ok = ok and proc.returncode == 0
    return ok, "\n".join(logs)


def eigen_include_dir():
    """The Eigen 3.4 include directory the eigen backend compiles against
    (BuildError when there is none)."""
    d, why = find_eigen()
    if d is None:
        raise BuildError(f"the eigen backend needs Eigen 3.4: {why}")
    return d


@dataclass
class Built:
    """A compiled model library: the file, its cache folder's name (the
    module name), the interface, and whether it has the derivative kernels
    (else their stand-ins: build_derivatives makes the complete library)."""
    path: Path
    modname: str
    interface: object
    derivatives: bool = True
    backend: str = "c"

    @property
    def folder(self) -> Path:
        return self.path.parent


# the library file in a module folder
_LIB_SUFFIX = ".dylib" if sys.platform == "darwin" else ".so"
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


def build(rendered: Rendered, verbose=False, timings=None):
    """Compile a Rendered (gen.render.render(..., project=False)) into a
    model library in the cache, keyed by the content of everything
    compiled; return a Built. A library built without the derivative
    kernels whose complete twin exists (build_derivatives) gives the twin.
    Nothing is rendered here."""
    iface = rendered.interface
    name, backend, files = iface.name, rendered.backend, rendered.files
    if backend not in BACKENDS:
        raise ModelError(f"unknown backend {backend!r}: choose one of {list(BACKENDS)}")
    _check_platform()
    t1 = time.perf_counter()
    eigen_dir = eigen_include_dir() if backend == "eigen" else None
    parts = [__version__, " ".join(C_FLAGS + ["lin:"] + C_LIN_FLAGS), _compiler()]
    if backend != "c":
        # the backend, its flags and the Eigen it compiles against
        parts.append(f"backend={backend}\0{' '.join(CXX_FLAGS)}\0{_cxx_compiler()}\0"
                     f"eigen={eigen_dir}:{eigen_version(eigen_dir)}\0face")
    for k in sorted(files):
        parts += [k, files[k]]
    key = _hash(*parts)
    modname = (f"_eomgen_{name}_{key}" if backend == "c"
               else f"_eomgen_{name}_{backend}_{key}")
    root = cache_dir()
    final = root / modname
    lib = _find_library(final, modname)
    if lib is not None:
        built = Built(lib, modname, iface, rendered.derivatives, backend)
        if timings is not None:
            timings["compile"] = 0.0
            timings["cached"] = True
        return _derived(built) or built
    tmp = _new_build_dir(root, modname)
    try:
        src = tmp / "src"
        try:
            src.mkdir()
            for fname, text in files.items():
                (src / fname).write_text(text)
            (tmp / "obj").mkdir()
        except OSError as e:
            raise _cache_error(e, root, "write the sources") from None
        lin = f"{name}_lin.c" if rendered.derivatives else f"{name}_lin_stub.c"
        own = [(f"{name}_lin.c", C_LIN_FLAGS)] if rendered.derivatives else []
        own += [(f"{name}_kernels.c", ()), (f"{name}.c", ()), (f"{name}_api.c", ())]
        if not rendered.derivatives:
            own.append((lin, ()))
        objects = compile_objects(src, tmp / "obj", _own(own), name)
        if backend == "eigen":   # the C objects above, the second copy and the face
            objects += _eigen_objects(src, tmp / "obj", name, rendered, eigen_dir)
        so = _link(modname, objects, tmp, cxx=backend == "eigen")
        _store(tmp, final, modname, so, src, keep_objects=(backend == "c"
                                                           and not rendered.derivatives))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    lib = _find_library(final, modname)
    if lib is None:
        raise BuildError(f"the built library for '{name}' is missing from {final}")
    if timings is not None:
        timings["compile"] = time.perf_counter() - t1
        timings["cached"] = False
    return Built(lib, modname, iface, rendered.derivatives, backend)


def build_derivatives(base: Built, lin_source: str, timings=None):
    """The complete library of a model built without its derivative kernels
    (base): <name>_lin.c (lin_source) compiled and linked with base's own
    objects and the runtime's; cached, and recorded in base's folder so that
    build() of base's sources finds it. Returns its Built."""
    if base.derivatives:
        return base
    t1 = time.perf_counter()
    name = base.interface.name
    key = _hash(base.modname, " ".join(C_FLAGS + ["lin:"] + C_LIN_FLAGS), lin_source)
    modname = f"_eomgen_{name}_{key}"
    root = cache_dir()
    final = root / modname
    lib = _find_library(final, modname)
    if lib is None:
        core = base.folder
        tmp = _new_build_dir(root, modname)
        try:
            src = tmp / "src"
            try:
                shutil.copytree(core / "src", src)
                (src / f"{name}_lin_stub.c").unlink(missing_ok=True)
                (src / f"{name}_lin.c").write_text(lin_source)
                (tmp / "obj").mkdir()
            except OSError as e:
                raise _cache_error(e, root, "write the sources") from None
            mine = [core / "obj" / f"{f}.o" for f in (f"{name}_kernels", name, f"{name}_api")]
            if not all(o.is_file() for o in mine):
                # an older or pruned cache folder: compile the model again
                objects = compile_objects(src, tmp / "obj", _own([
                    (f"{name}_lin.c", C_LIN_FLAGS), (f"{name}_kernels.c", ()), (f"{name}.c", ()),
                    (f"{name}_api.c", ())]), name)
            else:
                objects = compile_objects(src, tmp / "obj",
                                          _own([(f"{name}_lin.c", C_LIN_FLAGS)]), name)
                objects = objects[:1] + mine + objects[1:]
            so = _link(modname, objects, tmp, cxx=False)
            _store(tmp, final, modname, so, src, keep_objects=False)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        lib = _find_library(final, modname)
        if lib is None:
            raise BuildError(f"the built library for '{name}' is missing from {final}")
    _write_atomic(base.folder / _DERIVED, modname)
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
    lib = _find_library(cache_dir() / modname, modname)
    return None if lib is None else Built(lib, modname, built.interface, True, built.backend)


def _write_atomic(path: Path, text: str):
    tmp = path.with_name(f".{path.name}.{os.getpid()}")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    except OSError:
        # a read-only cache keeps working: the twin is found by its key
        try:
            tmp.unlink()
        except OSError:
            pass


def _new_build_dir(root: Path, modname: str) -> Path:
    try:
        root.mkdir(parents=True, exist_ok=True)
        clean_stale(root)
        return _make_temp(root, modname)
    except OSError as e:
        raise _cache_error(e, root, "create a build directory") from None


def _store(tmp: Path, final: Path, modname: str, so: Path, src: Path, keep_objects: bool):
    """Move a finished build into the cache (atomic rename; a concurrent
    builder that got there first wins, both are identical)."""
    root = final.parent
    dest = tmp / modname
    try:
        dest.mkdir()
        shutil.copy2(so, dest / so.name)
        shutil.copytree(src, dest / "src")
        if keep_objects:
            shutil.copytree(tmp / "obj", dest / "obj")
    except OSError as e:
        raise _cache_error(e, root, "store the library") from None
    try:
        os.rename(dest, final)
    except OSError as e:
        if _find_library(final, modname) is None:
            raise _cache_error(e, root, "store the library") from None


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


def _runtime_objects(src: Path, cc: str):
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
    for name in sorted(RUNTIME_SOURCES) + sorted(RUNTIME_HEADERS) + ["gen_rt_config.h"]:
        h.update(name.encode() + b"\0" + (src / name).read_bytes() + b"\0")
    folder = cache_dir() / f"runtime_{h.hexdigest()[:16]}"
    objs = [folder / (Path(s).stem + ".o") for s in RUNTIME_SOURCES]
    if all(o.is_file() for o in objs):
        return objs, None
    return None, folder


def _link(modname, objects, tmp: Path, cxx=False) -> Path:
    """cc -shared: the model library from its objects."""
    return link_library(objects, tmp / (modname + _LIB_SUFFIX), cxx=cxx)


def link_library(objects, out: Path, cxx=False) -> Path:
    """cc -shared objects -lm -o out."""
    cc = _cxx_compiler() if cxx else _compiler()
    cmd = [cc, "-shared", *[str(o) for o in objects], "-lm", "-o", str(out)]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        raise BuildError(f"the compiler {cc!r} cannot be run: {e}") from None
    if proc.returncode != 0:
        raise BuildError(f"linking {out.name} failed",
                         "$ " + " ".join(cmd) + "\n" + proc.stdout + proc.stderr)
    return out


def compile_objects(src: Path, objdir: Path, own, name):
    """Compile a model's own C files (own: [(file, flags)], the largest
    first) and, unless cached, the runtime, two at a time; return the object
    files to link (own first, in order, then the runtime's). gen.build's
    model libraries and gen.fmu's binaries both come through here."""
    from concurrent.futures import ThreadPoolExecutor
    cc = _compiler()
    runtime, rt_folder = _runtime_objects(src, cc)
    jobs = [(f, objdir / (Path(f).stem + ".o"), list(flags)) for f, flags in own]
    n_own = len(jobs)
    if runtime is None:
        rt_tmp = objdir.parent / "runtime"
        rt_tmp.mkdir()
        jobs += [(s, rt_tmp / (Path(s).stem + ".o"), RUNTIME_FLAGS) for s in RUNTIME_SOURCES]
    with ThreadPoolExecutor(max_workers=max(1, min(len(jobs), os.cpu_count() or 1))) as ex:
        futures = [ex.submit(_cc_object, cc, src, f, o, fl) for f, o, fl in jobs]
        try:
            results = [f.result() for f in futures]
        except BuildError as err:
            ok, log = _compile_log(src, [f for f, _ in own if f.startswith(name)]
                                   + RUNTIME_SOURCES)
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
    return [*results[:n_own], *runtime]


def _own(files_flags):
    """[(file, C_FLAGS + -fPIC + extra)] for the model library's own files."""
    return [(f, [*C_FLAGS, "-fPIC", *extra]) for f, extra in files_flags]


def _eigen_objects(src: Path, objdir: Path, name, rendered, eigen_dir):
    """The Eigen backend's objects beyond the C backend's (gen/eigen.py):
    the model and the runtime for the other scalar type (GEN_RT_ALT_REAL:
    its names prefixed) and the face instantiated, in parallel."""
    from concurrent.futures import ThreadPoolExecutor
    from .eigen import ALT_DEFINE, sources
    cxx, cc = _cxx_compiler(), _compiler()
    _, alt, own = sources(name, rendered.real, rendered.derivatives, C_TEMPLATES)
    (objdir / "alt").mkdir()
    alt_flag = "-D" + ALT_DEFINE
    jobs = [(cxx, f, objdir / (Path(f).stem + "_cxx.o"),   # <name>.c has <name>.o
             [*CXX_FLAGS, "-fPIC", "-isystem", str(eigen_dir)]) for f in own]
    jobs += [(cc, f, objdir / "alt" / (Path(f).stem + ".o"),
              [*C_FLAGS, "-fPIC", alt_flag, *(C_LIN_FLAGS if f.endswith("_lin.c") else ())])
             for f in alt]
    jobs += [(cc, f, objdir / "alt" / (Path(f).stem + ".o"), [*RUNTIME_FLAGS, alt_flag])
             for f in RUNTIME_SOURCES]
    with ThreadPoolExecutor(max_workers=max(1, min(len(jobs), os.cpu_count() or 1))) as ex:
        futures = [ex.submit(_cc_object, c, src, f, o, fl) for c, f, o, fl in jobs]
        try:
            return [f.result() for f in futures]
        except BuildError as err:
            ok, log = _compile_log(src, own, ["-isystem", str(eigen_dir)],
                                   compiler=cxx, flags=CXX_STRICT_FLAGS)
            raise BuildError(f"compiling the model '{name}' failed", log or err.log) from None


def _find_library(folder: Path, modname: str):
    lib = folder / (modname + _LIB_SUFFIX)
    return lib if lib.is_file() else None


# a module folder of the cache (the host module's: gen/host.py)
def _find_module(folder: Path, modname: str):
    if not folder.is_dir():
        return None
    for f in folder.iterdir():
        if f.name.startswith(modname) and f.suffix in (".so", ".pyd", ".dylib"):
            return f
    return None


def load(built: Built):
    """(host module, table): the model library's plugin table as a pointer
    of the host module for its scalar type (gen/host.py)."""
    from .host import host_module, open_model
    host = host_module(built.interface.real)
    return host, open_model(built.path, built.interface.name, host)


def derivatives_source(plan, real="double", timings=None):
    """<name>_lin.c of a plan made without derivatives (the kernels are
    generated now: sympy's share of what a first linearize costs)."""
    t0 = time.perf_counter()
    full = with_derivatives(plan)
    t1 = time.perf_counter()
    lin_only = replace(full, kernels={k: v for k, v in full.kernels.items()
                                      if k in DERIVATIVE_KERNELS})
    tm = {}
    files = render(lin_only, real=real, backend="c", project=False, only={"lin"}, timings=tm)
    if timings is not None:
        timings["kernels_derivatives"] = t1 - t0
        timings["printing_derivatives"] = tm.get("printing", 0.0) + tm.get("templates", 0.0)
    return files.files[f"{plan.model.name}_lin.c"]


def compile(model, backend="c", real="double", verbose=False, sources=None,  # noqa: A001
            timings=None, derivatives="lazy"):
    """Generate, build (cached by content) and load a model.

    The one path from a model to compiled code (the command line and
    :func:`gen.verify` call it).

    Parameters
    ----------
    model : gen.Model
        The model.
    backend : {"c", "eigen"}, optional
        C99 over the C runtime, or the same C library under a typed C++17
        face over Eigen 3.4 (gen/eigen.py; the same API, the same bits).
    real : {"double", "float"}, optional
        The scalar type.
    verbose : bool, optional
        Print the compiler's commands.
    sources : str or Path, optional
        A folder written by :func:`gen.generate` (possibly edited since): its
        files are compiled instead of freshly generated ones.
    timings : dict, optional
        Receives the time of each stage (kernels, printing, templates,
        compile; later the derivatives') and whether the build was cached.
    derivatives : {"lazy", True}, optional
        ``"lazy"`` (C backend): the derivative kernels (linearize, jacobian,
        step_sensitivity, RODAS4) are built on their first use; True: now.
        The Eigen backend always builds them.

    Returns
    -------
    gen.bindings.Simulator
        The loaded model library.

    Raises
    ------
    gen.BuildError
        When the compiler fails (with its full log).
    gen.ModelError
        When ``sources`` does not hold this model's files.
    """
    from .bindings import Simulator
    if backend not in BACKENDS:
        raise ModelError(f"unknown backend {backend!r}: choose one of {list(BACKENDS)}")
    if derivatives not in ("lazy", True):
        raise ModelError(f"derivatives must be 'lazy' or True, got {derivatives!r}")
    timings = {} if timings is None else timings
    lazy = backend == "c" and sources is None and derivatives == "lazy"
    t0 = time.perf_counter()
    plan = make_plan(model, lin=plan_lin(backend), derivatives=not lazy)
    timings["kernels"] = time.perf_counter() - t0
    rendered = render(plan, real=real, backend=backend, timings=timings, project=False)
    if sources is not None:
        rendered.files = _read_sources(sources, rendered.files, model.name, backend)
        rendered.derivatives = True
    built = build(rendered, verbose=verbose, timings=timings)
    t0 = time.perf_counter()
    host, api = load(built)
    timings["load"] = time.perf_counter() - t0
    def derive():
        tm = {}
        lin = derivatives_source(plan, real=real, timings=tm)
        full = build_derivatives(built, lin, timings=tm)
        return load(full)[1], full, tm

    sim = Simulator(host, api, built.interface,
                    derivatives=None if built.derivatives else derive)
    sim.build_info = {"module": str(built.path), "derivatives": built.derivatives, **timings}
    if backend != "c":
        sim.build_info["backend"] = backend
    return sim


def _read_sources(folder, expected, name, backend="c"):
    """The files of a generated folder that the build compiles: those
    rendering produces, with the derivative kernels (<name>_lin.c) in place
    of their stand-ins."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ModelError(f"sources folder {folder} does not exist")
    names = [f for f in expected if f != f"{name}_lin_stub.c"]
    if backend == "c" and f"{name}_lin.c" not in names:
        names.append(f"{name}_lin.c")
    files = {}
    for fname in names:
        path = folder / fname
        if not path.is_file():
            raise ModelError(f"{path} is missing: {folder} is not a generated '{name}' project")
        files[fname] = path.read_text()
    return files
