"""The C runtime's own tests (tests/c, built by the top-level CMake and run
by ctest), in double and under AddressSanitizer + UBSan."""
import subprocess
from pathlib import Path

import pytest

from conftest import require_tool

ROOT = Path(__file__).resolve().parents[3]


SANITIZE = pytest.param(["-DEOMGEN_SANITIZE=ON"], marks=[pytest.mark.fuzz, pytest.mark.slow],
                        id="asan-ubsan")


@pytest.mark.parametrize("flags", [pytest.param([], id="double"), SANITIZE,
                                   pytest.param(["-DEOMGEN_REAL_FLOAT=ON"], id="float",
                                                marks=pytest.mark.slow)])
def test_runtime_ctest(tmp_path, flags):
    require_tool("cmake")
    require_tool("ctest")
    bld = tmp_path / "build"
    r = subprocess.run(["cmake", "-S", str(ROOT), "-B", str(bld), *flags], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run(["cmake", "--build", str(bld), "-j2"], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run(["ctest", "--test-dir", str(bld), "--output-on-failure"],
                       capture_output=True, text=True)
    print(r.stdout[-3000:])
    assert r.returncode == 0, r.stdout + r.stderr
    assert "tests passed" in r.stdout
