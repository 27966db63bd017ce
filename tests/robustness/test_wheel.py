"""The wheel is the product (issue 42): built from the checkout, installed
into a fresh virtual environment with its declared dependencies, it runs
every product once there (tests/robustness/wheel/products.py: simulate,
the Eigen backend, an FMU, CasADi, optimal control with its tracker, a
hybrid model, the recursive formulation) and `eomgen build`; installed
without its extras, each product that needs one names it."""
import os
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import numpy as np
import pytest

from conftest import require_eigen, require_tool

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent / "wheel"
EXTRAS = "control,ocp,casadi,fmu,robots"

# the products that need an extra, run without it (wheel/without_extras.py)
WITHOUT = {"ocp": "ocp", "tracker": "control", "casadi": "casadi", "fmu": "fmu",
           "statespace": "control", "robots": "robots"}


# the first model in a fresh process, right after the install (issue 47): the
# host module, the runtime's objects and the compiled templates come with the
# wheel, so the cache gains none of them
FIRST_MODEL = """
import os, sys
from pathlib import Path
import sympy as sm
import gen
t = sm.Symbol("t")
q, u = sm.Function("q")(t), sm.Function("u")(t)
m = gen.Model.from_matrices(sm.Matrix([[1]]), sm.Matrix([-4 * q]), [q], [u],
                            sm.Matrix([q.diff(t) - u]), name="first47")
_, x = gen.compile(m).simulate([1.0, 0.0], 1.5707963267948966, 1e-3)
assert abs(x[-1][0] + 1.0) < 1e-9, x[-1]
print(" ".join(sorted(p.name for p in Path(os.environ["EOMGEN_CACHE"]).iterdir())))
"""


def _run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    assert r.returncode == 0, f"$ {' '.join(map(str, cmd))}\n{r.stdout}\n{r.stderr}"
    return r.stdout


def _wheel(out, prebuild):
    env = dict(os.environ, EOMGEN_PREBUILD="1" if prebuild else "0")
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
          "-w", str(out), str(ROOT)], env=env)
    (whl,) = out.glob("eomgen-*.whl")
    return whl


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """The wheel as pip builds it: the host and runtime compiled at install time."""
    return _wheel(tmp_path_factory.mktemp("wheels"), prebuild=True)


@pytest.fixture(scope="module")
def pure_wheel(tmp_path_factory):
    """The wheel without the install-time build (EOMGEN_PREBUILD=0): its
    sources, for the fast tier."""
    return _wheel(tmp_path_factory.mktemp("pure"), prebuild=False)


def test_wheel_carries_the_templates_and_the_runtime(pure_wheel):
    names = set(zipfile.ZipFile(pure_wheel).namelist())
    tracked = _run(["git", "ls-files", "templates", "csrc"], cwd=ROOT).split()
    missing = [f for f in tracked if f"gen/{f}" not in names]
    assert missing == []
    modules = _run(["git", "ls-files", "gen"], cwd=ROOT).split()
    assert [f for f in modules if f.endswith(".py") and f not in names] == []
    assert any(n.endswith("entry_points.txt") for n in names)


@pytest.mark.slow
def test_wheel_ships_the_host_and_runtime_built_at_install_time(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    kinds = {n.split("/")[2].split("_")[0] for n in names if n.startswith("gen/_prebuilt/")}
    assert kinds == {"host", "runtime", "templates"}
    assert not wheel.name.endswith("-none-any.whl")          # a platform wheel


@pytest.mark.slow
def test_every_product_runs_from_the_installed_wheel(wheel, tmp_path):
    require_tool("cmake")
    require_eigen()
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True).create(env_dir)
    py = env_dir / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.update(EOMGEN_CACHE=str(tmp_path / "cache"), MPLBACKEND="Agg")
    work = tmp_path / "elsewhere"
    work.mkdir()
    # the wheel alone: the core runs, a product without its extra names the extra
    _run([py, "-m", "pip", "install", "-q", str(wheel)], env=env)
    made = _run([py, "-c", FIRST_MODEL], cwd=work, env=env).split()
    assert [e for e in made if e.startswith(("host_", "runtime_", "templates_"))] == [], made
    out = _run([py, str(HERE / "without_extras.py"), str(tmp_path)], cwd=work, env=env)
    named = dict(line.split()[1:] for line in out.splitlines() if line.startswith("missing "))
    assert named == WITHOUT, out
    # with the extras: every product once
    _run([py, "-m", "pip", "install", "-q", f"{wheel}[{EXTRAS}]"], env=env)
    out = _run([py, str(HERE / "products.py"), str(tmp_path)], cwd=work, env=env)
    done = [line.split()[1] for line in out.splitlines() if line.startswith("ok ")]
    assert done == ["simulate", "eigen", "fmu", "casadi", "ocp+tracker", "hybrid", "recursive",
                    "mpc", "estimator", "robots"]
    # the command line: a standalone binary from a model file
    exe = Path(_run([env_dir / "bin" / "eomgen", "build", str(HERE / "model_file.py"), "-o",
                     str(tmp_path / "spring")], cwd=work, env=env).split()[-1])
    csv = _run([exe, "--t-end", "1.5707963267948966", "--dt", "0.001", "--x0", "1,0"],
               cwd=work)
    last = np.array(csv.strip().splitlines()[-1].split(","), dtype=float)
    assert abs(last[1] + 1.0) < 1e-9, last        # q'' = -4 q has period pi: q(pi/2) = -1
