"""Finding Eigen 3.4 for the C++/Eigen backend: a real installation, never a
vendored copy. Looked for, in order: the EIGEN3_INCLUDE_DIR environment
variable, the cmeel-eigen wheel (``<site-packages>/cmeel.prefix``), a conda
environment, then the usual system directories (Debian/Ubuntu libeigen3-dev,
Homebrew, MacPorts)."""
from __future__ import annotations

import os
import re
import site
import sys
import sysconfig
from pathlib import Path

__all__ = ["find_eigen", "eigen_version", "MIN_VERSION"]

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
