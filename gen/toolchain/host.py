"""The Python host module: one compiled cffi module per scalar type (and
Python ABI) through which the bindings call every model.

A model is compiled into a plain shared library (gen.build: its kernels,
the runtime, and ``<name>_api.c``, a constant table of its sizes and public
functions). The host module holds, for every public function of gen/codegen/abi.py,
a C function that takes that table first and calls through it, plus the
batch loops. So a model's build compiles no Python binding code at all (no
Python headers, no per-model wrapper: that was the largest fixed cost of a
build), and the host is compiled once per installation into the cache
(``host_<real>_<key>``, keyed by everything it is compiled from).

    host = host_module("double")          # the cffi module (ffi, lib)
    api = open_model(path, name, host)    # the model's table, a cdata pointer
    host.lib.eomgen_eval_rhs(api, t, x, r, p, dxdt, lam)

A product's library (an optimal control problem's, gen/codegen/backends/
ProductBackend) has no plugin table: it is opened in cffi's ABI mode with
the cdef rendered from its interface description (load_product,
open_library).
"""
from __future__ import annotations

import contextlib
import ctypes
import hashlib
import importlib.util
import io
import os
import shutil
import sys
import sysconfig
import threading
from pathlib import Path

from .._version import __version__
from ..codegen.abi import ABI_TAG, host_interface
from ..core.cache import cache_dir, cache_error, find_entry_file, new_build_dir, publish, shipped
from ..core.errors import BuildError

__all__ = ["host_module", "host_sources", "host_object", "open_model", "open_library", "load",
           "load_product", "HOST_FLAGS"]

# the host is glue: every call forwards to the model's table
HOST_FLAGS = ["-O2"]
_lock = threading.Lock()
_modules = {}          # real -> loaded module
_libraries = {}        # path -> ctypes handle (kept open for the process)
_products = {}         # (path, cdef) -> (ffi, lib) of open_library


# hand-written parts of the host (csrc/host): declarations, definitions, and
# whether the definitions use Python's and numpy's C API (the fast path of
# Simulator.rhs) rather than plain C
HOST_PARTS = [("gen_host_interrupt.h", "gen_host_interrupt.c", False),
              ("gen_host_ensemble.h", "gen_host_ensemble.c", False),
              ("gen_host_fast.h", "gen_host_fast.c", True)]


def host_sources(real="double", hand_written=True, python=True):
    """(cdef, C source) of the host module for a scalar type: the
    forwarders rendered from the interface description, then (unless
    hand_written=False) the hand-written parts (csrc/host: the ensemble
    loop, and unless python=False the fast path of Simulator.rhs, which
    needs Python's and numpy's headers)."""
    from ..codegen.templating import template_env
    from ..core.resources import csrc_dir
    env = template_env()
    iface = host_interface(real)
    decl = env.get_template("cffi/host.h.j2").render(iface=iface, real=real)
    extra_decl, extra_src = [], []
    for h, c, uses_python in HOST_PARTS if hand_written else ():
        if uses_python and not python:
            continue
        extra_decl.append((csrc_dir() / "host" / h).read_text())
        extra_src.append((csrc_dir() / "host" / c).read_text())
    decl = decl + "\n" + "\n".join(extra_decl)
    source = env.get_template("cffi/host.c.j2").render(iface=iface, real=real,
                                                       declarations=decl)
    return decl, source + "\n" + "\n".join(extra_src)


def _numpy_include():
    import numpy
    return numpy.get_include()


def _numpy_version():
    import numpy
    return numpy.__version__


def _key(real, cdef, source):
    h = hashlib.sha256()
    for part in (__version__, ABI_TAG, real, sys.version, sysconfig.get_config_var("EXT_SUFFIX")
                 or "", sysconfig.get_config_var("CC") or "", os.environ.get("CC", ""),
                 " ".join(HOST_FLAGS), _numpy_version(), "full-api", cdef, source):
        # (numpy's version, not the folder of its headers: a wheel's host is
        # built at install time in another environment, gen/toolchain/prebuilt.py)
        h.update(str(part).encode() + b"\0")
    return h.hexdigest()[:16]


def host_module(real="double"):
    """The host module for real ("double" or "float"), built into the cache
    on first use (once per installation; concurrent builders both succeed)
    and imported once per process."""
    with _lock:
        mod = _modules.get(real)
        if mod is not None:
            return mod
        mod = _modules[real] = _build_and_load(real)
        return mod


def host_object(host, ptr):
    """The Python object a host function returned as a new reference in a
    ``void *`` (the CPython fast paths of csrc/host/gen_host_fast.c), the
    reference taken over; None for NULL."""
    if ptr == host.ffi.NULL:
        return None
    addr = int(host.ffi.cast("uintptr_t", ptr))
    obj = ctypes.cast(ctypes.c_void_p(addr), ctypes.py_object).value
    ctypes.pythonapi.Py_DecRef(ctypes.py_object(obj))     # the new reference made in C
    return obj


def _build_and_load(real):
    cdef, source = host_sources(real)
    key = _key(real, cdef, source)
    modname = f"_eomgen_host_{real}_{key}"
    root = cache_dir()
    final = root / f"host_{real}_{key}"
    so = find_entry_file(final, modname)
    if so is None and shipped(final.name) is not None:
        so = find_entry_file(shipped(final.name), modname)     # built at install time
    if so is None:
        tmp = new_build_dir(root, f"host_{real}_{key}")
        try:
            import cffi
            ffi = cffi.FFI()
            ffi.cdef(cdef)
            ffi.set_source(modname, source, extra_compile_args=list(HOST_FLAGS),
                           include_dirs=[_numpy_include()],
                           # the fast path is a METH_FASTCALL function with
                           # numpy's C API: the full API of this Python
                           py_limited_api=False,
                           define_macros=[("_CFFI_NO_LIMITED_API", None)])
            try:
                with contextlib.redirect_stdout(io.StringIO()):
                    built = ffi.compile(tmpdir=str(tmp / "build"))
            except Exception as e:  # noqa: BLE001 - the compiler's own error, with its log
                raise BuildError(f"compiling eomgen's host module ({real}) failed: {e}",
                                 str(e)) from None
            dest = tmp / final.name
            try:
                dest.mkdir()
                shutil.copy2(built, dest / Path(built).name)
            except OSError as e:
                if find_entry_file(final, modname) is None:
                    raise cache_error(e, root, "store the host module") from None
            publish(dest, final, lambda: find_entry_file(final, modname) is not None,
                    what="store the host module")
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        so = find_entry_file(final, modname)
        if so is None:
            raise BuildError(f"eomgen's host module is missing from {final}")
    if modname in sys.modules:
        return sys.modules[modname]
    spec = importlib.util.spec_from_file_location(modname, str(so))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    sys.modules[modname] = mod
    return mod


def open_model(path, name, host, real_size=None):
    """The plugin table <name>_api of the shared library at path, as a
    ``const eomgen_api *`` of the host module; the library stays loaded for
    the life of the process. A table of another layout (ABI_TAG) or scalar
    size is a BuildError."""
    path = str(path)
    with _lock:
        lib = _libraries.get(path)
        if lib is None:
            try:
                lib = ctypes.CDLL(path, mode=getattr(os, "RTLD_LOCAL", 0))
            except OSError as e:
                raise BuildError(f"cannot load the model library {path}: {e}") from None
            _libraries[path] = lib
    try:
        addr = ctypes.addressof(ctypes.c_char.in_dll(lib, f"{name}_api"))
    except ValueError:
        raise BuildError(f"{path} has no table {name}_api: not an eomgen model library "
                         f"for '{name}'") from None
    ffi = host.ffi
    api = ffi.cast("const eomgen_api *", addr)
    tag = ffi.string(api.abi).decode()
    if tag != ABI_TAG:
        raise BuildError(f"the model library {path} has the table layout {tag}, this eomgen "
                         f"expects {ABI_TAG}: rebuild it (eomgen cache clear)")
    want = ffi.sizeof("eomgen_real")
    if api.real_size != want:
        raise BuildError(f"the model library {path} is built for {api.real_size}-byte reals, "
                         f"the host for {want}-byte reals")
    return api


def load(built):
    """(host module, table): a built model library's plugin table
    (gen.toolchain.build.Built) as a pointer of the host module for its scalar type."""
    host = host_module(built.interface.real)
    return host, open_model(built.path, built.interface.name, host)


def load_product(built):
    """(ffi, lib): a built product library (gen.toolchain.build.Built of a
    ProductBackend's render) opened with the cdef rendered from its
    interface (gen.codegen.render.product_cdef)."""
    from ..codegen.render import product_cdef
    return open_library(built.path, product_cdef(built.interface))


def open_library(path, cdef):
    """(ffi, lib): a product's shared library (an OCP's, a CasADi
    function's) opened through cffi's ABI mode with the cdef rendered from
    its interface description. One pair per (path, cdef), kept open for the
    life of the process; a library that cannot be loaded is a BuildError
    naming it."""
    key = (str(path), cdef)
    with _lock:
        hit = _products.get(key)
        if hit is not None:
            return hit
        import cffi
        ffi = cffi.FFI()
        ffi.cdef(cdef)
        try:
            lib = ffi.dlopen(str(path))
        except OSError as e:
            raise BuildError(f"cannot load the library {path}: {e}") from None
        _products[key] = (ffi, lib)
        return ffi, lib
