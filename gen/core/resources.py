"""Where the templates and the C runtime live: inside the installed
package (gen/templates, gen/csrc in a wheel) or beside it in a checkout.

csrc/ is folders by role (runtime/: the library every model links;
derivatives/: the derivative algorithms; program/: the standalone
simulator's; products/<name>/: a product's library; host/: the Python host
module's; eigen/: the Eigen face's). A file's name is unique across them
(the gen_rt_, gen_fmu_, gen_host_ prefixes), and a generated project holds
them side by side, so they are asked for by name: csrc_file("gen_rt.h").
"""
from __future__ import annotations

import threading
from pathlib import Path

__all__ = ["templates_dir", "csrc_dir", "csrc_file", "csrc_include_dirs"]

# the package folder (gen/): core/ is one below it
_HERE = Path(__file__).resolve().parent.parent
_lock = threading.Lock()
_index = {}           # csrc folder -> {file name: path}, read once


def _find(name):
    for cand in (_HERE / name, _HERE.parent / name):
        if cand.is_dir():
            return cand
    raise FileNotFoundError(
        f"eomgen cannot find its '{name}' directory (looked in {_HERE / name} and "
        f"{_HERE.parent / name}); reinstall the package")


def templates_dir() -> Path:
    return _find("templates")


def csrc_dir() -> Path:
    return _find("csrc")


def _files():
    root = csrc_dir()
    with _lock:
        index = _index.get(root)
        if index is None:
            index = {}
            for p in sorted(root.rglob("*")):
                if p.suffix in (".c", ".h", ".hpp") and p.is_file():
                    if p.name in index:
                        raise FileNotFoundError(f"csrc/ holds two files named {p.name}: "
                                                f"{index[p.name]} and {p}")
                    index[p.name] = p
            _index[root] = index
        return index


def csrc_file(name) -> Path:
    """The path of a runtime file by its name ("gen_rt_linalg.c"), in
    whichever folder of csrc/ it lives."""
    try:
        return _files()[Path(name).name]
    except KeyError:
        raise FileNotFoundError(f"eomgen's C runtime has no file {name} (in {csrc_dir()}); "
                                f"reinstall the package") from None


def csrc_include_dirs():
    """Every folder of csrc/ that holds a header (the -I list of a build
    that compiles the runtime in place rather than from a flat copy)."""
    return sorted({p.parent for p in _files().values() if p.suffix == ".h"})
