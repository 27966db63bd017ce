"""The host module and the runtime's objects built at install time.

The first model on an empty cache used to build, inside the user's first
``gen.compile``, the Python host module (gen/toolchain/host.py) and the
runtime's objects (gen/toolchain/build.py's ``_runtime_objects``): about 4-5 s
of compiling that every new user, CI job and container paid. The wheel's
build hook (``hatch_build.py`` at the checkout's root) runs :func:`prebuild`
once: it builds both, for double, and Jinja's compiled templates, into ``gen/_prebuilt`` (a wheel's
``gen/_prebuilt``, or the checkout's own for an editable install), laid out
as the cache lays them out (``host_double_<key>``, ``runtime_<key>``).

The cache looks there before it compiles (gen.core.cache.shipped): an entry is
used only under the very key the cache would build it under (the eomgen
version, the Python, numpy's version, the compiler's name and version, the
flags, every runtime source), so a changed compiler, Python or numpy
rebuilds into the cache as before. Nothing there is ever written after the
install.

    python -m gen.toolchain.prebuilt DEST     # what the build hook runs
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

__all__ = ["prebuild"]

# (stdlib only: the build hook loads this file alone, without the package)

# what is kept there: the cache's entries that every model shares
_KEPT = ("host_", "runtime_", "templates_")


def prebuild(dest, python=None, timeout=600):
    """Build the host module and the runtime's objects (double) into dest,
    in a child process of `python` (this one by default) whose cache is
    dest, then keep only those entries. Returns the names kept; raises
    RuntimeError with the child's output when the build fails."""
    dest = Path(dest).resolve()
    dest.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, EOMGEN_CACHE=str(dest))
    root = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join([root] + ([env["PYTHONPATH"]]
                                                  if env.get("PYTHONPATH") else []))
    proc = subprocess.run([python or sys.executable, "-c", _CHILD],
                          env=env, capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"eomgen's prebuild failed:\n{proc.stdout}\n{proc.stderr}")
    kept = []
    for entry in dest.iterdir():
        if entry.is_dir() and entry.name.startswith(_KEPT):
            kept.append(entry.name)
        elif entry.is_dir():
            shutil.rmtree(entry)
        else:
            entry.unlink()
    return sorted(kept)


# the child (EOMGEN_CACHE = dest), a script of its own: the host module,
# then a model of one spring, whose build compiles the runtime's objects
_CHILD = """
import sympy as sm
import gen
import gen.core.cache
gen.core.cache.PREBUILT = gen.core.cache.PREBUILT / "none"   # build them, take none
from gen.toolchain.host import host_module
host_module("double")
t = sm.Symbol("t")
q, u = sm.Function("q")(t), sm.Function("u")(t)
model = gen.Model.from_matrices(sm.Matrix([[1]]), sm.Matrix([-q]), [q], [u],
                                sm.Matrix([q.diff(t) - u]), name="prebuild")
_, x = gen.compile(model).simulate([1.0, 0.0], 1e-3, 1e-3)
assert abs(x[-1][0] - 1.0) < 1e-5, x
"""


if __name__ == "__main__":
    if len(sys.argv) == 2:
        print("\n".join(prebuild(sys.argv[1])))
    else:
        sys.exit("usage: python -m gen.toolchain.prebuilt DEST")
