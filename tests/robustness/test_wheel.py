"""A wheel built from the repo carries templates/ and csrc/ and works when
installed outside the checkout."""
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = r"""
import sys, gen, pathlib
sys.path.insert(0, sys.argv[2])
import seed_pendulum as sp
assert pathlib.Path(gen.__file__).resolve().is_relative_to(pathlib.Path(sys.argv[1]).resolve()), gen.__file__
paths = gen.generate(sp.lagrange_model(name="wheel_pend"), "gen_out")
names = sorted(p.name for p in paths)
assert "wheel_pend.c" in names and "gen_rt_linalg.c" in names, names
A, B = gen.compile(sp.lagrange_model(name="wheel_pend")).linearize([1.0, 0, 0, 0])
print("A", A.tolist())
"""


@pytest.mark.slow
def test_wheel_contents_and_install(tmp_path):
    wheels = tmp_path / "wheels"
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                        "-q", "-w", str(wheels), str(ROOT)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    (whl,) = list(wheels.glob("eomgen-*.whl"))
    names = zipfile.ZipFile(whl).namelist()
    for need in ("gen/templates/c/model.c.j2", "gen/templates/c/model.h.j2",
                 "gen/templates/common/macros.j2", "gen/csrc/runtime/gen_rt.h",
                 "gen/csrc/runtime/gen_rt_linearize.c", "gen/csrc/runtime/gen_rt_model.c",
                 "gen/csrc/runtime/gen_rt_status.h", "gen/csrc/products/ocp/gen_rt_ocp.c",
                 "gen/templates/ocp/ocp.c.j2", "gen/csrc/eigen/gen_rt_names.h",
                 "gen/templates/cffi/host.h.j2", "gen/intake/model.py"):
        assert need in names, need
    assert any(n.endswith("entry_points.txt") for n in names)
    site = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target",
                        str(site), str(whl)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = dict(os.environ, PYTHONPATH=str(site), EOMGEN_CACHE=str(tmp_path / "cache"))
    r = subprocess.run([sys.executable, "-c", SCRIPT, str(site), str(ROOT / "examples")],
                       cwd=work, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "A [[" in r.stdout
