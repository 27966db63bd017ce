"""The exception hierarchy of eomgen.

Every error the product raises on purpose is one of these; each names the
culprit (the symbol, the argument, the status and state) in its message.
"""


class EomgenError(Exception):
    """Base class of every eomgen error."""


class ModelError(EomgenError, ValueError):
    """The model cannot be generated correctly as given (unknown symbols,
    bad partition, unprintable expressions, bad name)."""


class InputError(EomgenError, ValueError):
    """An argument of a call is wrong: its shape, a NaN or infinite entry, a
    value out of range, or a run too large to keep. The message names the
    argument (``x0``, ``p``, ``r``, ``t_end``, ...), the entry and its value
    (``x0[2] = nan``).

    Parameters
    ----------
    message : str
        The message.
    argument : str, optional
        The argument's name (kept as ``argument``).
    index : int, optional
        The bad entry, when one is (``index``).
    value : optional
        Its value (``value``).
    """

    def __init__(self, message, argument=None, index=None, value=None):
        super().__init__(message)
        self.argument = argument
        self.index = index
        self.value = value


class BuildError(EomgenError, RuntimeError):
    """Compiling the generated code failed.

    Parameters
    ----------
    message : str
        What failed.
    log : str, optional
        The full compiler output (kept as ``log`` and appended to the
        message).
    """

    def __init__(self, message, log=""):
        super().__init__(message if not log else f"{message}\n--- compiler log ---\n{log}")
        self.log = log


class MissingDependencyError(EomgenError, ImportError):
    """An optional package a feature needs is not installed (the message
    names the pip command that installs it)."""


class SolverError(EomgenError, RuntimeError):
    """A generated C function returned a failure status.

    Parameters
    ----------
    message : str
        The message: the function, the status and its text, the time and the
        state.
    status : int, optional
        The negative C status code (kept as ``status``).
    status_name : str, optional
        Its name, ``"ERR_SINGULAR"`` (``status_name``).
    time : float, optional
        Where it happened, when known (``time``).
    state : numpy.ndarray, optional
        The last good state, when known (``state``).
    """

    def __init__(self, message, status=None, status_name=None, time=None, state=None):
        super().__init__(message)
        self.status = status
        self.status_name = status_name
        self.time = time
        self.state = state


class SingularError(SolverError):
    """The system to solve is singular or badly conditioned at this state
    (for example a coordinate partition that does not determine the
    dependent coordinates there), or the model expressions are."""


class ConvergenceError(SolverError):
    """Newton projection / consistent-state computation did not converge,
    or the adaptive integrator could not meet its tolerance."""


class DivergenceError(ConvergenceError):
    """The simulated state grew beyond the range of the scalar type
    (overflow): the model or the step is unstable, not singular."""


class UnusedConstantWarning(UserWarning):
    """A constant given in ``constants`` appears in no expression of the
    model (a misspelt or stale entry); it is kept as a parameter but has no
    effect on the results."""


class MasslessSpeedWarning(UserWarning):
    """Some speeds have an identically zero row in the mass matrix and no
    velocity constraint involves them: the equations do not determine
    their accelerations (a massless particle or body), so a simulation
    reports a singular configuration. Their mass matrix, forcing and
    linearization blocks are still generated."""


class UnusedInputWarning(UserWarning):
    """An input given in ``inputs`` appears in no expression of the model (a
    misspelt or stale entry); it is kept as an input but has no effect on
    the results."""
