"""eomgen: turn sympy.physics.mechanics equations of motion into fast,
verified C simulators.

    model = gen.Model.from_kanes(km, constants={...}, name="pend")
    gen.generate(model, "out/")            # C sources + CMake project
    sim = gen.compile(model)               # a model library, numpy in and out
    t, x = sim.simulate(x0, 5.0, 1e-3)    # a gen.Solution: sol.outputs, sol.events, ...
    sol = sim.simulate(x0, 5.0, 1e-2, options=gen.RunOptions(method="dopri5", rtol=1e-10))
    A, B = sim.linearize(x_op)
    res = sim.ensemble(x0, 5.0, 1e-3, p=gen.Sampler(1).draw(10**5, m=("uniform", 0.8, 1.2)))
    A, B = gen.linearize_symbolic(model, {q1: L, q2: 0})   # sympy matrices
    gen.export_fmu(model, "pend.fmu", fmi_version="3.0")   # FMI 2.0/3.0, ME and CS
    sol = gen.OptimalControl(model, 101, 2.0, objective=F**2, ...).solve()   # IPOPT
    ekf = gen.EKF(model, {"x_m": x}, 0.01, Q, R, x0, P0); ekf.step(z, r)   # Kalman filters in C
"""
import importlib.abc
import importlib.util
import sys

from ._version import __version__

from .core.errors import (BuildError, ConvergenceError, DivergenceError, EomgenError,  # noqa: E402
                     InputError, MissingDependencyError, ModelError, SingularError, SolverError,
                     UnusedConstantWarning, UnusedInputWarning, MasslessSpeedWarning)
from .sim.solution import Event, Solution  # noqa: E402
from .sim.options import RunOptions  # noqa: E402
from .sim.simulator import Simulator  # noqa: E402
from .intake.model import Model  # noqa: E402
from .codegen.render import generate  # noqa: E402
from .pipeline import compile  # noqa: E402,A001
from .plan.linearize import linearize_symbolic  # noqa: E402
from .export.verify import VerifyReport, verify  # noqa: E402
from .sim.inputs import LinearFeedback  # noqa: E402
from .design.tracking import TrajectoryTracker  # noqa: E402
from .export.fmu import export_fmu  # noqa: E402
from .sim.ensemble import At, EnsembleResult, Final, Max, Mean, Min, Sampler  # noqa: E402
from .intake.hybrid import Impact, Reset  # noqa: E402
from .design.ocp import OptimalControl, OptimalSolution  # noqa: E402
from .design.mpc import MPC  # noqa: E402
from .design.estimator import EKF, UKF  # noqa: E402
from .intake.robots import Robot, load_mjcf, load_urdf  # noqa: E402

__all__ = ["Model", "generate", "compile", "Simulator", "Solution", "Event", "RunOptions",
           "EomgenError",
           "ModelError", "BuildError", "InputError", "MissingDependencyError",
           "SolverError", "SingularError", "ConvergenceError", "DivergenceError", "UnusedConstantWarning", "UnusedInputWarning", "MasslessSpeedWarning", "linearize_symbolic", "verify", "VerifyReport", "LinearFeedback",
           "TrajectoryTracker", "export_fmu", "Sampler", "At", "Min", "Max", "Mean", "Final", "EnsembleResult",
           "Impact", "Reset", "OptimalControl", "OptimalSolution", "MPC", "EKF", "UKF", "Robot",
           "load_urdf", "load_mjcf", "__version__"]


# gen.casadi and gen.pydy (the products users name as modules: CasADi external
# functions, the PyDy drop-in) live in gen.export and are loaded on first
# use, as attributes (gen.casadi.functions) and as modules (import gen.export.pydy):
# `import gen` stays as it was
_LAZY = {"casadi": "gen.export.casadi", "pydy": "gen.export.pydy"}


def __getattr__(name):
    if name in _LAZY:
        import importlib
        return importlib.import_module(_LAZY[name])
    raise AttributeError(f"module 'gen' has no attribute {name!r}")


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """`import gen.export.casadi` loads gen.export.casadi (one module, two names)."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname in {f"{__name__}.{k}" for k in _LAZY}:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        module = importlib.import_module(_LAZY[spec.name.rpartition(".")[2]])
        self._own = (module.__name__, module.__spec__, module.__loader__)
        return module

    def exec_module(self, module):
        # the import system gave the module the alias's names: give it back its own
        module.__name__, module.__spec__, module.__loader__ = self._own


sys.meta_path.append(_Alias())
