"""Issue 47: the first model on an empty cache compiled the host module and
the runtime's objects (4-6 s, 25 s on a loaded machine) inside the user's
first gen.compile. They are built at install time
(gen/toolchain/prebuilt.py, run by hatch_build.py) and the cache takes them
from the package under the key it would build them under.

Here: prebuild into a folder, then, in a fresh process whose cache is empty
and whose package folder of prebuilt entries is that folder, the first
model builds only itself (no host, runtime or template entry is made in the
cache) and runs: a spring q'' = -q against cos(t). The wheel's own check is
tests/robustness/test_wheel.py's."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from gen.toolchain.prebuilt import prebuild

ROOT = Path(__file__).resolve().parents[2]

CHILD = """
import os, sys
from pathlib import Path
import numpy as np, sympy as sm
import gen.core.cache as cache
cache.PREBUILT = Path(sys.argv[1])
import gen
t = sm.Symbol("t")
q, u = sm.Function("q")(t), sm.Function("u")(t)
m = gen.Model.from_matrices(sm.Matrix([[2]]), sm.Matrix([-2 * q]), [q], [u],
                            sm.Matrix([q.diff(t) - u]), name="spring47")
tt, x = gen.compile(m).simulate([1.0, 0.0], 1.0, 1e-3)
assert abs(x[-1][0] - np.cos(1.0)) < 1e-9, x[-1]
print(" ".join(sorted(p.name for p in Path(os.environ["EOMGEN_CACHE"]).iterdir())))
"""


@pytest.mark.slow
def test_first_model_takes_the_prebuilt_host_runtime_and_templates(tmp_path):
    kept = prebuild(tmp_path / "prebuilt")
    assert [k.split("_")[0] for k in kept] == ["host", "runtime", "templates"]
    env = dict(os.environ, EOMGEN_CACHE=str(tmp_path / "cache"), PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", CHILD, str(tmp_path / "prebuilt")], env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    made = out.stdout.split()
    assert [e for e in made if e.startswith(("host_", "runtime_", "templates_"))] == []
    assert len([e for e in made if e.startswith("_eomgen_spring47")]) == 1
