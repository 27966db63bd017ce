"""The optional dependencies, each in one extra of ``pip install eomgen[...]``,
imported on first use: a missing one is a MissingDependencyError that names
the feature, the package and the extra that installs it.

    scipy = require("scipy", "gen.TrajectoryTracker")
    cyipopt = require("cyipopt", "gen.OptimalControl")

EXTRAS is the one table (pyproject.toml's extras hold the same packages;
tests/unit/core/test_optional.py checks that they agree).
"""
from __future__ import annotations

import importlib

from .errors import MissingDependencyError

__all__ = ["EXTRAS", "require", "extra_of"]

# import name -> (the extra that installs it, the PyPI package)
EXTRAS = {
    "scipy": ("control", "scipy"),
    "control": ("control", "control"),
    "matplotlib": ("plot", "matplotlib"),
    "fmpy": ("fmu", "fmpy"),
    "casadi": ("casadi", "casadi"),
    "cyipopt": ("ocp", "cyipopt-wheels"),
    "dask": ("dask", "dask[distributed]"),
    "distributed": ("dask", "dask[distributed]"),
    "tqdm": ("ensemble", "tqdm"),
    "pandas": ("ensemble", "pandas"),
    "pyarrow": ("ensemble", "pyarrow"),
    "yourdfpy": ("robots", "yourdfpy"),
    "mujoco": ("robots", "mujoco"),
}


def extra_of(name):
    """(extra, package) of an optional import name."""
    top = name.split(".")[0]
    try:
        return EXTRAS[top]
    except KeyError:
        raise KeyError(f"{top} is not an optional dependency of eomgen (gen.core.optional."
                       f"EXTRAS)") from None


def require(name, feature):
    """The module `name` (an optional dependency), imported; when it is not
    installed, a MissingDependencyError naming the feature, the package
    and the extra."""
    extra, package = extra_of(name)
    try:
        return importlib.import_module(name)
    except ImportError as err:
        raise MissingDependencyError(
            f"{feature} needs {package}, which is not installed: pip install eomgen[{extra}] "
            f"(or pip install {package})") from err
