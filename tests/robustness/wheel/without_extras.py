"""Each product that needs an extra, run from the wheel installed without
its extras (tests/robustness/test_wheel.py): it must raise
gen.MissingDependencyError naming the extra. Prints `missing <extra>` per
product."""
import re
import sys
from pathlib import Path

import numpy as np

import gen

sys.path.insert(0, str(Path(__file__).resolve().parent))
from products import URDF, pendulum  # noqa: E402


def attempt(what, call):
    try:
        call()
    except gen.MissingDependencyError as e:
        extra = re.search(r"pip install eomgen\[(\w+)\]", str(e))
        assert extra, str(e)
        print("missing", what, extra.group(1))
        return
    raise AssertionError(f"{what} ran without its extra")


def main():
    tmp = Path(sys.argv[1])
    model, (theta, omega, T) = pendulum("bare_pend")
    sim = gen.compile(model)                      # the core needs no extra
    assert np.allclose(sim.linearize([0.0, 0.0])[0], [[0, 1], [-19.62, 0]])
    attempt("ocp", lambda: gen.OptimalControl(
        model, 11, 1.0, objective=T**2, initial={theta: 0, omega: 0},
        final={theta: 0.1, omega: 0}).solve())
    t = np.linspace(0, 1, 11)
    attempt("tracker", lambda: gen.TrajectoryTracker(
        sim, t, np.zeros((11, 2)), np.zeros((11, 1)), np.eye(2), np.eye(1), 0.1))
    attempt("casadi", lambda: gen.casadi.functions(model))
    attempt("fmu", lambda: gen.export_fmu(model, tmp / "bare.fmu"))
    attempt("statespace", lambda: sim.to_statespace([0.0, 0.0]))
    attempt("robots", lambda: gen.Model.from_urdf(URDF, name="bare_urdf"))


if __name__ == "__main__":
    main()
