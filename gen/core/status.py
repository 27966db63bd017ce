"""The runtime's status codes, read from ``csrc/runtime/gen_rt_status.h`` (the
one table, an X-macro the C runtime compiles), and the exception each
failure status raises in Python.

    status_name(-3)              # 'ERR_SINGULAR'
    status_value("ERR_SINGULAR") # -3
    status_message(-3)           # the runtime's message
    exception_for("ERR_SINGULAR")  # gen.SingularError
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import (ConvergenceError, DivergenceError, InputError, SingularError,
                     SolverError)
from .resources import csrc_file

__all__ = ["Status", "STATUSES", "STATUS_UNKNOWN", "EXCEPTIONS", "status_name", "status_value",
           "status_message", "exception_for"]


@dataclass(frozen=True)
class Status:
    name: str          # "ERR_SINGULAR" (C: GEN_RT_ERR_SINGULAR, <P>_ERR_SINGULAR)
    value: int
    message: str


def _read_statuses():
    """The table of csrc/gen_rt_status.h: X(NAME, value, "message" "...")."""
    text = csrc_file("gen_rt_status.h").read_text()
    body = text[text.index("#define GEN_RT_STATUS_TABLE(X)"):].split("\n\n")[0]
    body = body.replace("\\\n", " ")
    out = []
    for m in re.finditer(r'X\((\w+),\s*(-?\d+),\s*((?:"(?:[^"\\]|\\.)*"\s*)+)\)', body):
        message = "".join(re.findall(r'"((?:[^"\\]|\\.)*)"', m.group(3)))
        out.append(Status(m.group(1), int(m.group(2)), message))
    unknown = re.search(r'#define GEN_RT_STATUS_UNKNOWN "([^"]*)"', text).group(1)
    return out, unknown


STATUSES, STATUS_UNKNOWN = _read_statuses()
_BY_VALUE = {s.value: s for s in STATUSES}


def status_name(code):
    """'ERR_SINGULAR' for -3 (GEN_RT_ERR_SINGULAR in C); the number as text
    for a code not in the table."""
    s = _BY_VALUE.get(code)
    return s.name if s else str(code)


def status_value(name):
    """-3 for 'ERR_SINGULAR'."""
    return next(s.value for s in STATUSES if s.name == name)


def status_message(code):
    s = _BY_VALUE.get(code)
    return s.message if s else STATUS_UNKNOWN


# the exception each failure status raises (every status has one:
# tests/unit/codegen/test_abi.py checks it)
EXCEPTIONS = {
    "ERR_NULL": SolverError,
    "ERR_NONFINITE_INPUT": InputError,
    "ERR_SINGULAR": SingularError,
    "ERR_NO_CONVERGENCE": ConvergenceError,
    "ERR_STEP_UNDERFLOW": ConvergenceError,
    "ERR_MAX_STEPS": ConvergenceError,
    "ERR_BAD_ARG": InputError,
    "ERR_NONFINITE_MODEL": SingularError,
    "ERR_OUTPUT_FULL": SolverError,
    "ERR_SINGULAR_KINEMATICS": SingularError,
    "ERR_DIVERGED": DivergenceError,
    "ERR_CONTROLLER": SolverError,
    "ERR_CANCELLED": KeyboardInterrupt,   # Ctrl-C (gen/sim/interrupt.py)
    "ERR_SINGULAR_REACTIONS": SingularError,
    "ERR_INCONSISTENT_RESET": SolverError,
    "ERR_PENETRATED": InputError,         # a start inside a contact (hybrid={...})
    "ERR_GUARD_CROSSED": SolverError,     # a CasADi step across a guard
}


def exception_for(name):
    """The exception class of a status name (SolverError for one not listed)."""
    return EXCEPTIONS.get(name, SolverError)
