"""Build generated sources with cffi (API mode, out of line) into a cache
keyed by the content of the generated files and the generator version.

Builds happen in a private temporary directory and are moved into the
cache with an atomic rename, so two processes building the same model at
once both succeed and load the same module. A failed compile raises
BuildError with the full compiler log.

The cache (cache_dir(): $EOMGEN_CACHE, else $XDG_CACHE_HOME/eomgen or
~/.cache/eomgen) holds one folder per built module (``_eomgen_<name>_<key>``)
and the shared runtime objects (``runtime_<key>``); everything in it can be
deleted at any time (cache_info, clear_cache). A build's temporary directory
is ``.<module>.<pid>.XXXX`` (with an ``owner`` file: pid and host); one left
by a killed process (dead pid on this host, or older than STALE_SECONDS) is
removed by the next build. A cache that cannot be written (read-only, full,
not a directory) is one BuildError naming the folder and EOMGEN_CACHE.
"""
from __future__ import annotations

import errno
import hashlib
import importlib.util
import os
import re
import socket
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from ._version import __version__
from .errors import BuildError, ModelError
from .eigen import eigen_version, find_eigen
from .ir import plan as make_plan
from .render import EIGEN_SOURCES, RUNTIME_HEADERS, RUNTIME_SOURCES, Rendered, plan_lin, render

__all__ = ["compile", "cache_dir", "build", "load", "Built", "cache_info", "clear_cache"]

C_FLAGS = ["-std=c99", "-O2", "-fno-strict-aliasing"]
# added for <name>_lin.c, the derivative kernels (see _c_objects)
C_LIN_FLAGS = ["-O1"]
STRICT_FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
# the C++/Eigen backend (Eigen's own headers are -isystem: their warnings are not ours)
CXX_FLAGS = ["-std=c++17", "-O2", "-fno-strict-aliasing"]
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
_ENTRY = re.compile(r"^(_eomgen_\w+|runtime_[0-9a-f]{16})$")
# (older eomgen versions wrote no pid: .<module>.XXXXXXXX, stale by age)
_TEMP = re.compile(r"^\.(_eomgen_\w+|runtime_[0-9a-f]{16})\.(?:(\d+)\.)?\w+$")


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
    """{"path", "exists", "modules", "runtimes", "temporary", "entries", "bytes"}
    of the build cache (only eomgen's entries are counted)."""
    root = cache_dir()
    ents = _entries(root)
    mods = [d for d in ents if d.name.startswith("_eomgen_")]
    rts = [d for d in ents if d.name.startswith("runtime_")]
    tmps = [d for d in ents if d.name.startswith(".")]
    return {"path": root, "exists": root.is_dir(), "modules": len(mods), "runtimes": len(rts),
            "temporary": len(tmps), "entries": len(mods) + len(rts),
            "bytes": sum(_size(d) for d in ents)}


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
    cc = os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc"
    return cc.split()[0]


def _cxx_compiler():
    cxx = os.environ.get("CXX") or sysconfig.get_config_var("CXX") or "g++"
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
    """A compiled cffi module: where it is, its name, its interface."""
    path: Path
    modname: str
    interface: object


def build(rendered: Rendered, verbose=False, timings=None):
    """Compile a Rendered (gen.render.render) into a cffi extension in the
    cache, keyed by the content of everything compiled; return a Built.
    Nothing is rendered here."""
    iface = rendered.interface
    name, backend, files = iface.name, rendered.backend, rendered.files
    if backend not in BACKENDS:
        raise ModelError(f"unknown backend {backend!r}: choose one of {list(BACKENDS)}")
    t1 = time.perf_counter()
    eigen_dir = eigen_include_dir() if backend == "eigen" else None
    cdef, wrapper = rendered.cdef, rendered.module_source
    h = hashlib.sha256()
    h.update(__version__.encode())
    h.update(sys.version.encode())
    h.update(" ".join(C_FLAGS + ["lin:"] + C_LIN_FLAGS).encode())
    if backend != "c":
        # the backend, its flags and the Eigen it compiles against
        h.update(f"\0backend={backend}\0{' '.join(CXX_FLAGS)}\0eigen={eigen_dir}:"
                 f"{eigen_version(eigen_dir)}\0".encode())
    h.update(cdef.encode())
    h.update(wrapper.encode())
    for k in sorted(files):
        h.update(k.encode() + b"\0" + files[k].encode() + b"\0")
    key = h.hexdigest()[:16]
    modname = (f"_eomgen_{name}_{key}" if backend == "c"
               else f"_eomgen_{name}_{backend}_{key}")
    root = cache_dir()
    final = root / modname
    so = _find_module(final, modname)
    if so is not None:
        if timings is not None:
            timings["compile"] = 0.0
            timings["cached"] = True
        return Built(so, modname, iface)
    try:
        root.mkdir(parents=True, exist_ok=True)
        clean_stale(root)
        tmp = _make_temp(root, modname)
    except OSError as e:
        raise _cache_error(e, root, "create a build directory") from None
    try:
        src = tmp / "src"
        try:
            src.mkdir()
            for fname, text in files.items():
                (src / fname).write_text(text)
        except OSError as e:
            raise _cache_error(e, root, "write the sources") from None
        import cffi
        ffi = cffi.FFI()
        try:
            ffi.cdef(cdef)
        except Exception as e:  # cffi's CDefError and parse errors
            raise BuildError(f"internal error: the cffi declarations do not parse: {e}", cdef) from e
        if backend == "c":
            own = [f"{name}.c", f"{name}_lin.c"] + RUNTIME_SOURCES
            # the model and the runtime as objects, compiled in parallel (the
            # runtime's objects are shared by every model with the same runtime
            # sources, scalar type and flags); cffi then compiles its wrapper
            ffi.set_source(modname, wrapper, include_dirs=[str(src)],
                           extra_compile_args=list(C_FLAGS), libraries=["m"])
            # cffi's wrapper is compiled with the model and the runtime, all in
            # parallel, then linked here (cffi's own compile would come after)
            wrap = None
            if _can_link_directly():
                try:
                    import contextlib
                    import io
                    wrap = tmp / f"{modname}.c"
                    with contextlib.redirect_stdout(io.StringIO()):   # cffi says "generating"
                        ffi.emit_c_code(str(wrap))
                except OSError as e:
                    raise _cache_error(e, root, "write the sources") from None
            try:
                objects = _c_objects(name, src, tmp, wrap)
            except OSError as e:
                raise _cache_error(e, root, "compile") from None
            if wrap is None:
                ffi.set_source(modname, wrapper, extra_objects=[str(o) for o in objects],
                               include_dirs=[str(src)], extra_compile_args=list(C_FLAGS),
                               libraries=["m"])
        else:
            # all C++: the extern "C" layer over the typed API, and cffi's wrapper
            own = [s.format(name=name) for s in EIGEN_SOURCES]
            ffi.set_source(modname, wrapper,
                           sources=[str(src / s) for s in own], source_extension=".cpp",
                           include_dirs=[str(src)],
                           extra_compile_args=[*CXX_FLAGS, "-isystem", str(eigen_dir)],
                           libraries=["stdc++", "m"])
        bdir = tmp / "build"
        try:
            bdir.mkdir()
        except OSError as e:
            raise _cache_error(e, root, "compile") from None
        try:
            if backend == "c" and wrap is not None:
                so_path = _link_module(modname, objects, bdir)
            else:
                so_path = ffi.compile(tmpdir=str(bdir), verbose=verbose)
        except Exception as e:
            if isinstance(e, OSError) and e.errno in _CACHE_ERRNOS:
                raise _cache_error(e, root, "compile") from None
            if backend == "c":
                ok, log = _compile_log(src, own)
            else:
                ok, log = _compile_log(src, own, ["-isystem", str(eigen_dir)],
                                       compiler=_cxx_compiler(), flags=CXX_STRICT_FLAGS)
            raise BuildError(f"compiling the model '{name}' failed ({type(e).__name__}: {e})",
                             log or str(e)) from None
        dest_tmp = tmp / modname
        try:
            dest_tmp.mkdir()
            shutil.copy2(so_path, dest_tmp / Path(so_path).name)
            shutil.copytree(src, dest_tmp / "src")
        except OSError as e:
            raise _cache_error(e, root, "store the module") from None
        try:
            os.rename(dest_tmp, final)
        except OSError as e:
            # another process won the race: use its build
            if _find_module(final, modname) is None:
                raise _cache_error(e, root, "store the module") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    so = _find_module(final, modname)
    if so is None:
        raise BuildError(f"the built module for '{name}' is missing from {final}")
    if timings is not None:
        timings["compile"] = time.perf_counter() - t1
        timings["cached"] = False
    return Built(so, modname, iface)


def _cc_object(cc, src: Path, obj: Path, include: Path, extra=()):
    cmd = [cc, *C_FLAGS, "-fPIC", "-I", str(include), *extra, "-c", str(src), "-o", str(obj)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise BuildError(f"compiling {src.name} failed",
                         "$ " + " ".join(cmd) + "\n" + proc.stdout + proc.stderr)
    return obj


def _runtime_objects(src: Path, cc: str):
    """The runtime's object files, from a cache shared by every model: keyed
    by the runtime sources, the scalar-type header, the flags and the
    compiler. Returns (objects ready, sources still to compile into dir)."""
    h = hashlib.sha256()
    h.update(__version__.encode() + b"\0" + " ".join([cc, *C_FLAGS, "-fPIC"]).encode())
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


def _can_link_directly():
    """Link the extension with the C compiler here (Linux, macOS): the
    wrapper then compiles in parallel with the model."""
    import sysconfig
    return ((sys.platform.startswith("linux") or sys.platform == "darwin")
            and bool(sysconfig.get_config_var("EXT_SUFFIX")))


def _link_module(modname, objects, bdir: Path):
    """cc -shared: the extension module from its objects."""
    import sysconfig
    cc = _compiler()
    out = bdir / (modname + sysconfig.get_config_var("EXT_SUFFIX"))
    cmd = [cc, "-shared", *[str(o) for o in objects], "-lm", "-o", str(out)]
    if sys.platform == "darwin":
        cmd[2:2] = ["-undefined", "dynamic_lookup"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise BuildError(f"linking {out.name} failed",
                         "$ " + " ".join(cmd) + "\n" + proc.stdout + proc.stderr)
    return str(out)


def _c_objects(name, src: Path, tmp: Path, wrap: Path | None = None):
    """Compile the model's C file, cffi's wrapper (when given) and (unless
    cached) the runtime, two at a time; return the object files to link."""
    from concurrent.futures import ThreadPoolExecutor
    cc = _compiler()
    objdir = tmp / "obj"
    objdir.mkdir()
    runtime, rt_folder = _runtime_objects(src, cc)
    # the derivative kernels first (the largest file starts first), at -O1:
    # gcc's time on their straight-line code is the largest cost of a build,
    # and -O1 takes a quarter less (n = 20 cart: 8.8 -> 6.6 s) for a
    # linearize 4-12% slower (52 -> 54 us; n = 10: 10.7 -> 12.0 us); IEEE
    # semantics are the same at every level (no -ffast-math), so the numbers
    # are too (tests/golden/seed_numbers.json, bit for bit)
    jobs = [(src / f"{name}_lin.c", objdir / f"{name}_lin.o", tuple(C_LIN_FLAGS)),
            (src / f"{name}.c", objdir / f"{name}.o", ())]
    if wrap is not None:
        import sysconfig
        paths = sysconfig.get_paths()
        py = sorted({paths["include"], paths["platinclude"]})
        jobs.append((wrap, objdir / (wrap.stem + ".o"),
                     tuple(a for d in py for a in ("-I", d))))
    own = len(jobs)
    if runtime is None:
        rt_tmp = tmp / "runtime"
        rt_tmp.mkdir()
        jobs += [(src / s, rt_tmp / (Path(s).stem + ".o"), ()) for s in RUNTIME_SOURCES]
    with ThreadPoolExecutor(max_workers=max(1, min(len(jobs), os.cpu_count() or 1))) as ex:
        futures = [ex.submit(_cc_object, cc, s, o, src, e) for s, o, e in jobs]
        try:
            results = [f.result() for f in futures]
        except BuildError:
            ok, log = _compile_log(src, [f"{name}.c", f"{name}_lin.c"] + RUNTIME_SOURCES)
            raise BuildError(f"compiling the model '{name}' failed", log) from None
    if runtime is None:
        # publish the runtime objects for the next model (atomic rename; a
        # concurrent builder that got there first wins, both are identical)
        rt_folder.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.rename(rt_tmp, rt_folder)
            runtime = [rt_folder / Path(o).name for o in results[own:]]
        except OSError:
            runtime = results[own:]
            if all((rt_folder / Path(o).name).is_file() for o in runtime):
                runtime = [rt_folder / Path(o).name for o in runtime]
    return [*results[:own], *runtime]


def _find_module(folder: Path, modname: str):
    if not folder.is_dir():
        return None
    for f in folder.iterdir():
        if f.name.startswith(modname) and f.suffix in (".so", ".pyd", ".dylib"):
            return f
    return None


def load(built: Built):
    """Import a Built's extension module (once per process)."""
    so, modname = built.path, built.modname
    if modname in sys.modules:
        return sys.modules[modname]
    spec = importlib.util.spec_from_file_location(modname, str(so))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    sys.modules[modname] = mod
    return mod


def compile(model, backend="c", real="double", verbose=False, sources=None,  # noqa: A001
            timings=None):
    """Generate, build through cffi (cached) and return a Simulator: the one
    path from a model to compiled code (the CLI and gen.verify call it).

    backend: "c" (C99 model + C runtime) or "eigen" (C++17 over Eigen 3.4,
    through its extern "C" layer: the same API, the same Simulator).
    real: "double" or "float".
    sources: a folder written by gen.generate (possibly edited since): its
    files are compiled instead of freshly generated ones.
    timings: a dict that receives the time of each stage (kernels, printing,
    templates, compile) and whether the build was cached."""
    from .bindings import Simulator
    if backend not in BACKENDS:
        raise ModelError(f"unknown backend {backend!r}: choose one of {list(BACKENDS)}")
    timings = {} if timings is None else timings
    t0 = time.perf_counter()
    plan = make_plan(model, lin=plan_lin(backend))
    timings["kernels"] = time.perf_counter() - t0
    rendered = render(plan, real=real, backend=backend, timings=timings)
    if sources is not None:
        rendered.files = _read_sources(sources, rendered.files, model.name)
    built = build(rendered, verbose=verbose, timings=timings)
    sim = Simulator(load(built), built.interface)
    sim.build_info = {"module": str(built.path), **timings}
    if backend != "c":
        sim.build_info["backend"] = backend
    return sim


def _read_sources(folder, expected, name):
    """The files of a generated folder, by the names rendering produces."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ModelError(f"sources folder {folder} does not exist")
    files = {}
    for fname in expected:
        path = folder / fname
        if not path.is_file():
            raise ModelError(f"{path} is missing: {folder} is not a generated '{name}' project")
        files[fname] = path.read_text()
    return files
