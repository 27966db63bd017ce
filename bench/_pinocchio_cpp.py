"""Helper of bench/bench_recursive.py: Pinocchio's ABA timed in C++.

Builds bench/_pinocchio_aba.cpp against the headers of the ``pin`` wheel
(``<site-packages>/cmeel.prefix/include``), the wheel's Boost (cmeel-boost)
and an Eigen 3.4 (the wheel ships none: cmeel-eigen's if installed, else
``pkg-config eigen3``, else /usr/include/eigen3), with the compile
definitions the wheel's CMake target ``pinocchio::pinocchio_default`` sets
(``lib/cmake/pinocchio/pinocchioTargets.cmake``: Boost.MPL's list and vector
limits raised to 30 for the joint variant). Two variants:

- ``"header"``: header-only, all of Pinocchio's templates instantiated in
  the driver with the given flags (default ``-O2 -DNDEBUG``: the C driver's
  -O2, asserts off);
- ``"shipped"``: ``PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION``, linked to the
  wheel's ``libpinocchio_default.so``: the aba instance (on
  ``Eigen::Ref<const VectorXd>``) the Python binding calls, as the wheel's
  maintainers compiled it.

A driver is built once per (source, command) into a cache folder
(``$XDG_CACHE_HOME/eomgen-bench`` or ``~/.cache/eomgen-bench``; a build takes
1-3 CPU-minutes: Pinocchio's joint variant) and serves every model: the
model comes on its standard input (``model_text``)."""
from __future__ import annotations

import hashlib
import os
import shutil
import statistics
import subprocess
from pathlib import Path

import numpy as np

SOURCE = Path(__file__).with_name("_pinocchio_aba.cpp")
# pinocchioTargets.cmake's INTERFACE_COMPILE_DEFINITIONS of pinocchio_default
DEFINES = ("-DBOOST_MPL_LIMIT_LIST_SIZE=30", "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30",
           "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS", "-DBOOST_FUSION_INVOKE_MAX_ARITY=12")
DEFAULT_FLAGS = ("-O2", "-DNDEBUG")


class DriverError(RuntimeError):
    """The C++ driver could not be built or run here (the message says why)."""


def cmeel_prefix():
    """The ``cmeel.prefix`` folder the imported ``pinocchio`` lives in."""
    import pinocchio
    for parent in Path(pinocchio.__file__).resolve().parents:
        if parent.name == "cmeel.prefix":
            return parent
    raise DriverError(f"pinocchio at {pinocchio.__file__} is not from a cmeel wheel "
                      "(no cmeel.prefix folder above it): no headers to build against")


def eigen_include(prefix):
    """(folder, how found) of the Eigen 3 headers to build with."""
    own = prefix / "include" / "eigen3"
    if (own / "Eigen" / "Core").exists():
        return own, "cmeel-eigen"
    if shutil.which("pkg-config"):
        r = subprocess.run(["pkg-config", "--cflags-only-I", "eigen3"],
                           capture_output=True, text=True)
        for tok in r.stdout.split() if r.returncode == 0 else ():
            if (Path(tok[2:]) / "Eigen" / "Core").exists():
                return Path(tok[2:]), "pkg-config eigen3"
    for d in ("/usr/include/eigen3", "/usr/local/include/eigen3"):
        if (Path(d) / "Eigen" / "Core").exists():
            return Path(d), d
    raise DriverError("no Eigen 3 headers (pip install cmeel-eigen, or apt-get install "
                      "libeigen3-dev): the pin wheel ships none")


def eigen_version(folder):
    text = (Path(folder) / "Eigen" / "src" / "Core" / "util" / "Macros.h").read_text()
    import re
    v = [re.search(rf"#define EIGEN_{k}_VERSION\s+(\d+)", text) for k in ("WORLD", "MAJOR", "MINOR")]
    return ".".join(m.group(1) for m in v) if all(v) else "?"


def _cache_dir():
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "eomgen-bench"


def build_driver(variant="header", cxx="g++", flags=DEFAULT_FLAGS):
    """Path of the built driver (built now unless cached); DriverError says
    why not. Returns (exe, info) with info = {'cmd': ..., 'eigen': ...}."""
    if variant not in ("header", "shipped"):
        raise ValueError(variant)
    if shutil.which(cxx) is None:
        raise DriverError(f"no C++ compiler {cxx!r} on PATH")
    prefix = cmeel_prefix()
    inc = prefix / "include"
    if not (inc / "pinocchio" / "algorithm" / "aba.hpp").exists():
        raise DriverError(f"no pinocchio/algorithm/aba.hpp under {inc}")
    eig, how = eigen_include(prefix)
    cmd = [cxx, "-std=c++17", *flags, *DEFINES]
    libs = []
    if variant == "shipped":
        cmd.append("-DPINBENCH_SHIPPED")
        cmd.append("-DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION")
        libdir = prefix / "lib"
        libs = [f"-L{libdir}", "-lpinocchio_default", f"-Wl,-rpath,{libdir}"]
    cmd += [f"-I{inc}", f"-I{eig}", str(SOURCE)]
    key = hashlib.sha256((SOURCE.read_text() + "\0" + " ".join(cmd + libs)).encode()).hexdigest()[:16]
    folder = _cache_dir() / f"pinocchio_aba_{variant}_{key}"
    exe = folder / "pinocchio_aba"
    info = {"cmd": " ".join(cmd + ["-o", "pinocchio_aba"] + libs), "eigen": f"{eigen_version(eig)} ({how})",
            "variant": variant, "flags": " ".join(flags)}
    if exe.exists():
        return exe, info
    folder.mkdir(parents=True, exist_ok=True)
    tmp = folder / "pinocchio_aba.tmp"
    proc = subprocess.run(cmd + ["-o", str(tmp)] + libs, capture_output=True, text=True)
    if proc.returncode != 0:
        raise DriverError("the C++ build failed:\n$ " + " ".join(cmd + libs) + "\n"
                          + proc.stderr[-3000:])
    tmp.rename(exe)
    return exe, info


def model_text(model, q, v, tau, iters, reps):
    """The driver's input for the Python ``pin`` model (see the .cpp)."""
    lines = [str(model.njoints - 1)]
    for j in range(1, model.njoints):
        M, Y = model.jointPlacements[j], model.inertias[j]
        vals = [*M.rotation.ravel(), *M.translation, Y.mass, *Y.lever, *Y.inertia.ravel()]
        kind = model.joints[j].shortname()
        if kind in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
            kind += " " + " ".join(repr(float(a)) for a in model.joints[j].extract().axis)
        lines.append(f"{kind} {model.parents[j]} " + " ".join(repr(float(a)) for a in vals))
    lines.append(" ".join(repr(float(a)) for a in model.gravity.linear))
    for vec in (q, v, tau):
        lines.append(" ".join(repr(float(a)) for a in vec))
    lines.append(f"{int(iters)} {int(reps)}")
    return "\n".join(lines) + "\n"


def iters_for(nx):
    """bench/_cdriver.py's calls per repeat for a state of size nx."""
    return max(500, int(2e6 / nx ** 2))


def run_driver(exe, model, q, v, tau, reps=11, iters=None):
    """{'aba': median s per call, 'aba_min', 'samples', 'ddq'} from one run."""
    if iters is None:
        iters = iters_for(model.nq + model.nv)
    r = subprocess.run([str(exe)], input=model_text(model, q, v, tau, iters, reps),
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise DriverError(f"the C++ driver exited with {r.returncode}: {r.stderr[-2000:]}")
    samples, ddq = [], None
    for line in r.stdout.splitlines():
        k, *vals = line.split()
        if k == "ddq":
            ddq = np.array([float(a) for a in vals])
        elif k == "aba":
            samples.append(float(vals[0]))
    return {"aba": statistics.median(samples), "aba_min": min(samples),
            "samples": samples, "ddq": ddq, "iters": iters}
