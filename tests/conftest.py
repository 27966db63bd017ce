# EOMGEN_UPDATE_GOLDEN=1 python -m pytest tests/golden/test_golden_sources.py rewrites the golden
# generated sources in tests/golden/sources/ instead of comparing (see that test's docstring).
# Markers (pyproject.toml): slow, eigen, embedded, fuzz; the fast tier is -m "not slow".
import os
import shutil
import sys
import tempfile
from pathlib import Path

# One BLAS thread per test process, set before numpy loads (here, and so in the
# pytest-xdist workers and the subprocesses the tests start): the workers already
# fill the cores, and OpenBLAS's own threads on the tests' small matrices then
# only wait for a core -- a 5x5 scipy expm took 8 ms of CPU instead of 0.02 ms
# with two workers on a busy 2-core machine. A value the caller set is kept.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
if "numpy" in sys.modules:     # too late to take effect: say so rather than be slow silently
    print("conftest.py: numpy was loaded before OPENBLAS_NUM_THREADS was set", file=sys.stderr)

import pytest  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "tests"))
if "EOMGEN_CACHE" not in os.environ:
    if os.environ.get("CI") == "true":
        os.environ["EOMGEN_CACHE"] = tempfile.mkdtemp(prefix="eomgen-test-cache-")
    else:
        # the cache is keyed by content, so a rerun reuses what did not change:
        # the fast tier's second run skips most compiles (CI starts empty)
        os.environ["EOMGEN_CACHE"] = str(ROOT / ".eomgen-test-cache")

import gen  # noqa: E402
import seed_pendulum  # noqa: E402


def require_tool(name):
    """Skip with a reason when an outside tool is missing, but fail under CI."""
    path = shutil.which(name)
    if path is None:
        if os.environ.get("CI") == "true":
            pytest.fail(f"{name} is required under CI=true but is not installed")
        pytest.skip(f"{name} not installed")
    return path


def require_eigen():
    """The Eigen 3.4 include dir; skip with a reason when missing, fail under CI."""
    from gen.codegen.backends.eigen import find_eigen
    d, why = find_eigen()
    if d is None:
        if os.environ.get("CI") == "true":
            pytest.fail(f"Eigen 3.4 is required under CI=true: {why}")
        pytest.skip(why)
    return d


# Markers of whole modules that other work owns, applied here so that those
# files need no edit: every test of test_eigen.py builds every example model
# for both backends up front (minutes of C++ compiles).
MODULE_MARKS = {"test_eigen.py": ("eigen", "slow")}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    for item in items:
        for mark in MODULE_MARKS.get(item.path.name, ()):
            item.add_marker(getattr(pytest.mark, mark))


@pytest.fixture(scope="session")
def kane_model():
    return seed_pendulum.kane_model()


@pytest.fixture(scope="session")
def lagrange_model():
    return seed_pendulum.lagrange_model()


def build_binary(model, out):
    """The model's standalone simulator, built from its generated CMake
    project under out (Release; the project's strict flags: -Wall -Wextra
    -Werror -pedantic)."""
    import subprocess
    require_tool("cmake")
    src, bld = out / "src", out / "build"
    gen.generate(model, src)
    subprocess.run(["cmake", "-S", str(src), "-B", str(bld), "-DCMAKE_BUILD_TYPE=Release"],
                   check=True, capture_output=True)
    subprocess.run(["cmake", "--build", str(bld)], check=True, capture_output=True)
    exe = bld / f"{model.name}_sim"
    assert exe.exists()
    return exe


@pytest.fixture(scope="session")
def kane_binary(tmp_path_factory, kane_model):
    """The seed Kane pendulum's standalone simulator (build_binary), shared
    by the binary tests of several modules. A build costs 6-8 s, so it is
    kept in the test cache keyed by the generated sources' content (CI
    starts with an empty cache and builds)."""
    import hashlib
    require_tool("cmake")
    src = tmp_path_factory.mktemp("kane_sources")
    gen.generate(kane_model, src)
    h = hashlib.sha256()
    for f in sorted(src.rglob("*")):
        if f.is_file():
            h.update(f.relative_to(src).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    name = f"{kane_model.name}_sim"
    kept = Path(os.environ["EOMGEN_CACHE"]) / "test-binaries" / h.hexdigest()[:16] / name
    if kept.exists():
        return kept
    exe = build_binary(kane_model, tmp_path_factory.mktemp("kane_project"))
    kept.parent.mkdir(parents=True, exist_ok=True)
    tmp = kept.with_name(f".{name}.{os.getpid()}")
    shutil.copy2(exe, tmp)
    os.replace(tmp, kept)            # whole or absent, also with two sessions at once
    return kept


@pytest.fixture(scope="session")
def kane_sim(kane_model):
    return gen.compile(kane_model)


@pytest.fixture(scope="session")
def lagrange_sim(lagrange_model):
    return gen.compile(lagrange_model)
