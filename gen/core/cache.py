"""The build cache: one folder holding everything eomgen compiles, keyed by
content, so a second build of the same thing is a lookup.

The cache (cache_dir(): $EOMGEN_CACHE, else $XDG_CACHE_HOME/eomgen or
~/.cache/eomgen) holds one folder per built library (``_eomgen_<name>_<key>``,
gen/toolchain/build.py), the shared runtime objects (``runtime_<key>``), the host
modules (``host_<real>_<key>``, gen/toolchain/host.py) and Jinja's compiled templates
(``templates_<key>``, gen/codegen/render.py); everything in it can be deleted at any
time (cache_info, clear_cache).

Entries are made in a private temporary directory (new_build_dir:
``.<entry>.<pid>.XXXX`` with an ``owner`` file, pid and host) and published
with an atomic rename (publish), so two processes building the same entry
at once both succeed and use the same files. A temporary directory left by
a killed process (dead pid on this host, or older than STALE_SECONDS) is
removed by the next build (clean_stale). A cache that cannot be written
(read-only, full, not a directory) is one BuildError naming the folder and
EOMGEN_CACHE (cache_error).
"""
from __future__ import annotations

import errno
import os
import re
import shutil
import socket
import tempfile
import time
from pathlib import Path

from .errors import BuildError

__all__ = ["cache_dir", "cache_error", "clean_stale", "new_build_dir", "make_temp", "publish",
           "write_marker", "find_entry_file", "cache_info", "clear_cache", "STALE_SECONDS",
           "PREBUILT", "shipped"]


# the package's folder of the entries every model shares (the host module,
# the runtime's objects, the compiled templates), built at install time by
# gen/toolchain/prebuilt.py; read only
PREBUILT = Path(__file__).resolve().parents[1] / "_prebuilt"


def shipped(name: str):
    """The folder of the cache entry `name` built at install time (its
    folder under the very name the cache would give it: the same key), or
    None."""
    folder = PREBUILT / name
    return folder if folder.is_dir() else None


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


def cache_error(e: OSError, folder: Path, what: str):
    """A BuildError for a cache that cannot be written, in one line."""
    why = e.strerror or str(e)
    if e.errno in (errno.ENOTDIR, errno.EEXIST):
        why = "it or a part of its path is not a directory"
    elif e.errno in (errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)):
        why = "no space left on the device"
    return BuildError(f"cannot {what} in the eomgen cache {folder} ({why}): set EOMGEN_CACHE to "
                      "a writable folder (or free space there)")


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


def make_temp(root: Path, entry: str) -> Path:
    """A private build directory in the cache, named and marked with our pid."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{entry}.{os.getpid()}.", dir=root))
    (tmp / "owner").write_text(f"{os.getpid()} {socket.gethostname()} {time.time():.0f}\n")
    return tmp


def new_build_dir(root: Path, entry: str) -> Path:
    """make_temp in root (created), after removing stale ones; a cache that
    cannot be written is a BuildError (cache_error)."""
    try:
        root.mkdir(parents=True, exist_ok=True)
        clean_stale(root)
        return make_temp(root, entry)
    except OSError as e:
        raise cache_error(e, root, "create a build directory") from None


def publish(staged: Path, final: Path, ready, what="store the library"):
    """Move a finished entry (staged, a folder beside final in the cache)
    into place with an atomic rename. A concurrent builder that got there
    first wins (both are identical): ready() says whether final already
    holds a complete entry; otherwise the failure is a cache_error."""
    try:
        os.rename(staged, final)
    except OSError as e:
        if not ready():
            raise cache_error(e, final.parent, what) from None


def write_marker(path: Path, text: str):
    """Write a small file atomically; a read-only cache keeps working (the
    marker is an optimization: what it points to is found by its key)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    except OSError:
        try:
            tmp.unlink()
        except OSError:
            pass


def find_entry_file(folder: Path, prefix: str, suffixes=(".so", ".pyd", ".dylib")):
    """The file of a cache folder whose name starts with prefix and ends in
    one of suffixes (a compiled module), or None."""
    if not folder.is_dir():
        return None
    for f in folder.iterdir():
        if f.name.startswith(prefix) and f.suffix in suffixes:
            return f
    return None


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
            raise cache_error(e, root, f"delete {d.name}") from None
        removed += 1
        freed += size
    return removed, freed
