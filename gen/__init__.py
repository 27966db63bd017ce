"""eomgen: turn sympy.physics.mechanics equations of motion into fast,
verified C simulators.

    model = gen.Model.from_kanes(km, constants={...}, name="pend")
    gen.generate(model, "out/")            # C sources + CMake project
    sim = gen.compile(model)               # a model library, numpy in and out
    t, x = sim.simulate(x0, 5.0, 1e-3)    # a gen.Solution: sol.outputs, sol.events, ...
    A, B = sim.linearize(x_op)
    res = sim.ensemble(x0, 5.0, 1e-3, p=gen.Sampler(1).draw(10**5, m=("uniform", 0.8, 1.2)))
    A, B = gen.linearize_symbolic(model, {q1: L, q2: 0})   # sympy matrices
    gen.export_fmu(model, "pend.fmu", fmi_version="3.0")   # FMI 2.0/3.0, ME and CS
    sol = gen.OptimalControl(model, 101, 2.0, objective=F**2, ...).solve()   # IPOPT
"""
from ._version import __version__

from .errors import (BuildError, ConvergenceError, DivergenceError, EomgenError,  # noqa: E402
                     InputError, MissingDependencyError, ModelError, SingularError, SolverError,
                     UnusedConstantWarning, UnusedInputWarning, MasslessSpeedWarning)
from .solution import Event, Solution  # noqa: E402
from .bindings import Simulator  # noqa: E402
from .model import Model  # noqa: E402
from .render import generate  # noqa: E402
from .pipeline import compile  # noqa: E402,A001
from .symbolic import linearize_symbolic  # noqa: E402
from .verify import VerifyReport, verify  # noqa: E402
from .control import LinearFeedback  # noqa: E402
from .tracking import TrajectoryTracker  # noqa: E402
from .fmu import export_fmu  # noqa: E402
from .ensemble import At, EnsembleResult, Final, Max, Mean, Min, Sampler  # noqa: E402
from .hybrid import Impact, Reset  # noqa: E402
from .ocp import OptimalControl, OptimalSolution  # noqa: E402

__all__ = ["Model", "generate", "compile", "Simulator", "Solution", "Event", "EomgenError",
           "ModelError", "BuildError", "InputError", "MissingDependencyError",
           "SolverError", "SingularError", "ConvergenceError", "DivergenceError", "UnusedConstantWarning", "UnusedInputWarning", "MasslessSpeedWarning", "linearize_symbolic", "verify", "VerifyReport", "LinearFeedback",
           "TrajectoryTracker", "export_fmu", "Sampler", "At", "Min", "Max", "Mean", "Final", "EnsembleResult",
           "Impact", "Reset", "OptimalControl", "OptimalSolution", "__version__"]


def __getattr__(name):
    # gen.pydy (the PyDy drop-in) and gen.casadi (CasADi external functions) are
    # loaded on first use: `import gen` stays as it was
    if name in ("pydy", "casadi"):
        import importlib
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'gen' has no attribute {name!r}")
