"""The options of a run: written once, checked in one place.

:class:`RunOptions` is the one list of the options of ``Simulator.simulate``
and ``Simulator.ensemble``. The defaults of the options the C engine reads
(``method``, ``rtol``, ``atol``, ``h_init``, ``h_min``, ``h_max``,
``max_steps``, ``project``, ``proj_tol``, ``proj_max_iter``, ``every``,
``final_only``, ``input_hold``) are the interface description's
(``gen/codegen/abi.py``: the fields of ``sim_options`` and ``input``, METHODS
and HOLDS), which the C header's ``<p>_sim_options_default`` is rendered
from too. :data:`OPTIONS` holds the text of each option: the docstrings of
RunOptions, ``simulate`` and ``ensemble`` and the command line's run flags
(``eomgen simulate --rtol``, gen/cli/program.py) are assembled from it.

``simulate`` and ``ensemble`` take ``options=RunOptions(...)`` and the most
used options as keywords (:data:`OPTION_NAMES`); :func:`run_options` merges
them (a keyword given explicitly wins) and checks the run's times.
:func:`plan_rows` then counts the rows a run keeps (``every=``,
``final_only=``) and refuses, before anything is allocated, a run past
``max_rows``, past the memory of the machine, or past the C runtime's limit
of output times.
"""
from __future__ import annotations

import difflib
import inspect
import math
import os
import sys
from dataclasses import dataclass, fields, replace

import numpy as np

from ..codegen import abi
from ..core.errors import InputError
from .docstrings import doc

__all__ = ["RunOptions", "Run", "Option", "OPTIONS", "OPTION_NAMES", "run_options",
           "options_signature", "fill_sim_options", "plan_rows", "memory_available",
           "finite_or_raise", "C_MAX_INTERVALS"]

# gen_rt_simulate_rows refuses more than 1e9 output intervals (an int count)
C_MAX_INTERVALS = 1e9

# ------------------------------------------------ the description's defaults
_C = {f.name: f for s in abi.STRUCTS if s.name == "sim_options" for f in s.fields}
_HOLD = next(f for s in abi.STRUCTS if s.name == "input" for f in s.fields if f.name == "hold")


def _c_default(name):
    """The default of a sim_options field as a Python value; "eps16" (16
    machine epsilons of the scalar type) is 0.0, which the engine reads as
    that (gen_rt_model_project: a tolerance <= 0 is 16 epsilons)."""
    f = _C[name]
    if f.default == "eps16":
        return 0.0
    return {"real": float, "int": int, "long": int}[f.ctype](f.default)


def _name_of(table, code):
    return next(k for k, v in table.items() if v == code)


# ---------------------------------------------------------------- checks
def _number(name, v):
    try:
        return float(v)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {v!r}", name, None, v) from None


def _positive(name, v):
    f = _number(name, v)
    if not (math.isfinite(f) and f > 0):
        raise InputError(f"{name} must be a positive number, got {name} = {f!r}", name, None, f)
    return f


def _finite(name, v):
    f = _number(name, v)
    if not math.isfinite(f):
        raise InputError(f"{name} must be a finite number, got {name} = {f!r}", name, None, f)
    return f


def _integer(name, v, low=1, none=False):
    if none and v is None:
        return None
    try:
        ok = not isinstance(v, bool) and int(v) == v and v >= low
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InputError(f"{name} must be {'None or ' if none else ''}an integer >= {low}, got "
                         f"{name} = {v!r}", name, None, v)
    return int(v)


def _method(name, v):
    try:
        return abi.method_name(v, name)      # the names and their aliases
    except ValueError as e:
        raise InputError(str(e), name, None, v) from None


def _hold(name, v):
    if v not in abi.HOLDS:
        raise InputError(f"{name} must be {' or '.join(map(repr, abi.HOLDS))}, got {v!r}",
                         name, None, v)
    return v


# -------------------------------------------------------------- the options
_KW = {"kw_only": True} if sys.version_info >= (3, 10) else {}


@dataclass(frozen=True, **_KW)
class RunOptions:
    # the docstring is assembled from OPTIONS below
    method: str = _name_of(abi.METHODS, _c_default("method"))
    rtol: float = _c_default("rtol")
    atol: float = _c_default("atol")
    h_init: float = _c_default("h_init")
    h_min: float = _c_default("h_min")
    h_max: float = _c_default("h_max")
    max_steps: int = _c_default("max_steps")
    project: bool = bool(_c_default("project"))
    proj_tol: float = _c_default("proj_tol")
    proj_max_iter: int = _c_default("proj_max_iter")
    t0: float = 0.0
    input_period: float | None = None
    input_hold: str = _name_of(abi.HOLDS, _HOLD.default)
    every: int = _c_default("every")
    final_only: bool = bool(_c_default("final_only"))
    max_rows: int | None = None
    events: dict | None = None
    terminal: object = False
    consistent: bool = False

    def __post_init__(self):
        for name, check in _CHECKS.items():
            v = getattr(self, name)
            if v is not _DEFAULTS[name]:        # a default is valid as it is
                object.__setattr__(self, name, check(name, v))
        if self.events is None and self.terminal is not False:
            raise InputError("terminal= needs events={name: direction}", "terminal", None,
                             self.terminal)


# option -> its check (the value normalized, or an InputError naming it)
_CHECKS = {"method": _method, "rtol": _positive, "atol": _positive, "h_init": _finite,
           "h_min": _finite, "h_max": _finite, "max_steps": _integer,
           "project": lambda _, v: bool(v), "proj_tol": _finite,
           "proj_max_iter": lambda n, v: _integer(n, v, 0), "t0": _finite,
           "input_hold": _hold, "every": _integer, "final_only": lambda _, v: bool(v),
           "max_rows": lambda n, v: _integer(n, v, 1, none=True),
           "consistent": lambda _, v: bool(v)}
_DEFAULTS = {f.name: f.default for f in fields(RunOptions)}


@dataclass(frozen=True, **_KW)
class Run(RunOptions):
    """The checked options of one run (or of every run of an ensemble):
    :class:`RunOptions` and the run's times t_end and dt (t0 is an option)."""
    t_end: float = 0.0
    dt: float = 0.0

    def __post_init__(self):
        super().__post_init__()
        self._times(self.t_end, self.dt)

    @classmethod
    def of(cls, options, t_end, dt):
        """The Run of checked options (a RunOptions) and the run's times."""
        run = object.__new__(cls)
        run.__dict__.update(options.__dict__)
        run._times(t_end, dt)
        return run

    def _times(self, t_end, dt):
        t_end, dt = _number("t_end", t_end), _number("dt", dt)
        if not (math.isfinite(dt) and dt > 0):
            raise InputError(f"dt must be a positive number, got dt = {dt!r}", "dt", None, dt)
        if not (math.isfinite(t_end) and t_end >= self.t0):
            raise InputError(f"t_end must be a number >= t0 = {self.t0}, got t_end = {t_end!r}",
                             "t_end", None, t_end)
        object.__setattr__(self, "t_end", t_end)
        object.__setattr__(self, "dt", dt)


# ------------------------------------------------------ the text of each one
@dataclass(frozen=True)
class Option:
    """The text of one option: its type and description (reST, numpy
    style), the commands of the command line that have a flag for it, and
    the flag when it is not ``--<name>``."""
    name: str
    type: str
    doc: str
    cli: tuple = ()
    flag: str | None = None

    @property
    def default(self):
        """The default (RunOptions', from the interface description)."""
        return RunOptions.__dataclass_fields__[self.name].default


_BOTH, _SIM = ("simulate", "ensemble"), ("simulate",)
_METHODS = "{" + ", ".join(f'"{m}"' for m in abi.METHODS) + "}"
OPTIONS = (
    Option("method", _METHODS, "Fixed-step RK4; DOPRI5 (explicit, adaptive); RODAS4 (alias "
           '``"rodas"``: linearly implicit, L-stable, for stiff models; it uses the generated '
           "Jacobian).", _BOTH),
    Option("rtol", "float", "The adaptive methods' relative tolerance.", _BOTH),
    Option("atol", "float", "The adaptive methods' absolute tolerance.", _BOTH),
    Option("h_init", "float", "The adaptive methods' first step (0: automatic).", _BOTH),
    Option("h_min", "float", "The adaptive methods' smallest step (0: automatic).", _BOTH),
    Option("h_max", "float", "The adaptive methods' largest step (0: unbounded).", _BOTH),
    Option("max_steps", "int", "The adaptive methods' step budget between two output rows.",
           _BOTH),
    Option("project", "bool", "Project onto the constraints after every step.", _BOTH,
           "--no-project"),
    Option("proj_tol", "float", "The projection's relative tolerance on the correction (0: 16 "
           "machine epsilons of the scalar type).", _BOTH),
    Option("proj_max_iter", "int", "The projection's Newton iterations (0: 10).", _BOTH),
    Option("t0", "float", "The initial time."),
    Option("input_period", "float", "The sampling period of a callable r (None: dt; 0: every "
           "stage)."),
    Option("input_hold", "{" + ", ".join(f'"{h}"' for h in abi.HOLDS) + "}",
           "How a table of inputs is held between its knots: the last knot's row, or linear "
           "interpolation.", _SIM, "--hold"),
    Option("every", "int", "Keep every k-th output row and the last (dropped in C; the "
           "integration is unchanged).", _SIM),
    Option("final_only", "bool", "Keep only the row at t_end.", _SIM),
    Option("max_rows", "int", "Refuse a run that would keep more rows (None: no bound but the "
           "memory available).", _SIM),
    Option("events", "dict", "``{name: direction}`` or ``{name: (direction, level)}``: "
           "crossings of a state or an output through zero (or level), upwards (+1), "
           "downwards (-1) or both (0), located on the dense output."),
    Option("terminal", "bool or dict", "The first crossing of a terminal event (all, or "
           "``{name: bool}``) ends the run; its state is the last row."),
    Option("consistent", "bool", "Solve the dependent states of x0 first "
           "(:meth:`Simulator.consistent_state`)."),
)
assert [o.name for o in OPTIONS] == [f.name for f in fields(RunOptions)]

# the options that simulate and ensemble also take as keywords, in their order
OPTION_NAMES = ("method", "rtol", "atol", "project", "t0", "max_steps", "input_period",
                "input_hold", "every", "final_only", "max_rows", "events", "terminal",
                "consistent")
_BY_NAME = {o.name: o for o in OPTIONS}


def option_params(names):
    """(name, "type, optional", description with its default) of the named
    options: their entries in a numpy-style Parameters section."""
    out = []
    for n in names:
        o = _BY_NAME[n]
        out.append((n, f"{o.type}, optional", f"{o.doc} Default: ``{o.default!r}``."))
    return out


RunOptions.__doc__ = doc(
    """The options of a run of :meth:`Simulator.simulate` (and of every run of
    :meth:`Simulator.ensemble`), checked when made: ``sim.simulate(x0, t_end, dt,
    options=gen.RunOptions(method="dopri5", rtol=1e-10))``. The defaults of the
    options the C engine reads are the interface description's (the C header's
    ``<p>_sim_options_default`` has the same). Give them by name; a RunOptions is
    frozen (``dataclasses.replace(opts, rtol=1e-6)`` makes another).""",
    params=option_params([o.name for o in OPTIONS]),
    raises=[("gen.InputError", "On a bad value: the message names the option and the "
             "value."), ("TypeError", "On a name that is not an option.")])


_DEFAULT_OPTIONS = RunOptions()


# ------------------------------------------------------------ using them
def run_options(t_end, dt, options=None, given=None, where="Simulator.simulate"):
    """The checked :class:`Run` of a call: ``options`` (a RunOptions, or
    None: the defaults) with the keywords ``given`` explicitly over it.

    Raises
    ------
    TypeError
        On a keyword that is not an option of ``where``'s (it names it, and
        the option it may have meant).
    gen.InputError
        On a bad value; the message names the argument and the value.
    """
    if options is None:
        options = _DEFAULT_OPTIONS
    elif not isinstance(options, RunOptions):
        raise InputError(f"options must be a gen.RunOptions, got {type(options).__name__}",
                         "options", None, options)
    if given:
        for k in given:
            if k not in OPTION_NAMES:
                raise TypeError(f"{where}() got an unexpected keyword argument {k!r}"
                                + _hint(k))
        options = replace(options, **given)
    return Run.of(options, t_end, dt)


def _hint(name):
    if name in _BY_NAME:
        return f": give it as options=gen.RunOptions({name}=...)"
    close = difflib.get_close_matches(name, list(OPTION_NAMES), n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


def options_signature(func, names=OPTION_NAMES):
    """func's signature with its ``**keywords`` replaced by the named
    options (keyword-only, RunOptions' defaults) before ``options``: what
    ``inspect.signature``, ``help()`` and the API reference show."""
    sig = inspect.signature(func)
    params = [p for p in sig.parameters.values() if p.kind is not p.VAR_KEYWORD]
    at = next(i for i, p in enumerate(params) if p.name == "options")
    opts = [inspect.Parameter(n, inspect.Parameter.KEYWORD_ONLY, default=_BY_NAME[n].default)
            for n in names]
    return sig.replace(parameters=params[:at] + opts + params[at:])


# the options the C struct sim_options has: (name, the C value of a Python one)
_C_FIELDS = [(name, (lambda v: abi.METHODS[v]) if name == "method" else
              float if f.ctype == "real" else int)
             for name, f in _C.items() if name in _DEFAULTS]


def fill_sim_options(struct, run, rows=True):
    """Write a run's options into a C ``sim_options`` struct (filled with
    ``sim_options_default`` first): every field that is an option (with
    rows=False not ``every`` and ``final_only``, which an ensemble keeps by
    its reducers)."""
    for name, c_value in _C_FIELDS:
        if rows or name not in ("every", "final_only"):
            setattr(struct, name, c_value(getattr(run, name)))


# ------------------------------------------------------------- the rows
def memory_available():
    """Bytes of memory this process can still use: MemAvailable of
    /proc/meminfo where there is one, else the physical memory; None when
    unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, OSError, ValueError):
        return None


def _size(nbytes):
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("kiB", 2**10)):
        if nbytes >= scale:
            return f"{nbytes / scale:.1f} {unit}"
    return f"{nbytes} bytes"


def plan_rows(opts, full_rows, row_bytes, kept_rows, what="this run", runs=1):
    """The rows a run keeps, after every= and final_only=; refuses, naming
    the count and the ways out, a run past max_rows, past the memory
    available, or past the C runtime's limit of output times.

    Parameters
    ----------
    opts : Run
    full_rows : int or None
        The output times of the run (``simulate_rows``), or None where the C
        count refused the run (past its limit): counted here.
    row_bytes : int
        The bytes a kept row takes (every array of a row, over all runs).
    kept_rows : callable
        ``kept_rows(full, every, final_only)``: the model library's
        ``simulate_rows_kept``, the one place the kept-row count is computed
        (``sim.library.function("simulate_rows_kept")``). A run past the C
        limit (refused below) is counted here only for its message.
    """
    intervals = (opts.t_end - opts.t0) / opts.dt
    if full_rows is None or full_rows < 0:
        full_rows = int(math.ceil(intervals * (1 - 1e-12))) + 1 if math.isfinite(intervals) \
            else float("inf")
    if full_rows == float("inf"):
        kept = 1 if opts.final_only else full_rows
    elif full_rows > C_MAX_INTERVALS:       # refused below: counted for the message only
        kept = 1 if opts.final_only else -(-int(full_rows) // opts.every)
    else:
        kept = int(kept_rows(int(full_rows), opts.every, 1 if opts.final_only else 0))
    ways = "every=k (keep every k-th row), final_only=True (only the last row) or a larger dt"
    full_txt = f"{full_rows:,}" if full_rows != float("inf") else "infinitely many"
    kept_txt = f"{kept:,}" if kept != float("inf") else "infinitely many"
    if opts.max_rows is not None and kept > opts.max_rows:
        raise InputError(f"{what} would keep {kept_txt} rows ({full_txt} output times from t0 = "
                         f"{opts.t0} to t_end = {opts.t_end} every dt = {opts.dt}, every="
                         f"{opts.every}), more than max_rows={opts.max_rows}: use {ways}",
                         "max_rows", None, opts.max_rows)
    need = kept * row_bytes * runs
    avail = memory_available()
    if avail is not None and need > avail:
        raise InputError(f"{what} would keep {kept_txt} rows ({full_txt} output times from t0 = "
                         f"{opts.t0} to t_end = {opts.t_end} every dt = {opts.dt}), "
                         f"{_size(need)}, more than the {_size(avail)} of memory available: "
                         f"use {ways}, or max_rows= to refuse such runs", "t_end", None,
                         opts.t_end)
    if intervals > C_MAX_INTERVALS:
        raise InputError(f"{what} has {full_txt} output times (t_end - t0 = "
                         f"{opts.t_end - opts.t0} over dt = {opts.dt}), more than the "
                         f"{C_MAX_INTERVALS:.0e} output intervals a run may have: use a larger "
                         "dt (the adaptive methods step by their error control; dt is only "
                         "their output interval) or split the run", "dt", None, opts.dt)
    return int(kept), int(full_rows)


def finite_or_raise(name, a, labels=None):
    """Raise gen.InputError naming the first NaN or infinite entry of a
    (``x0[2] = nan (theta_p)``)."""
    a = np.asarray(a)
    if a.size and not np.all(np.isfinite(a)):
        idx = np.argwhere(~np.isfinite(a))[0]
        flat = int(np.ravel_multi_index(tuple(idx), a.shape)) if a.ndim > 1 else int(idx[0])
        where = ", ".join(str(int(i)) for i in idx)
        value = a[tuple(idx)]
        names = []
        if a.ndim == 2:
            names.append(f"run {int(idx[0])}")
        if labels is not None and len(idx) and int(idx[-1]) < len(labels):
            names.append(labels[int(idx[-1])])
        label = f" ({', '.join(names)})" if names else ""
        raise InputError(f"{name}[{where}] = {float(value)!r}{label}: a NaN or infinite "
                         f"entry; every entry of {name} must be finite", name, flat,
                         float(value))
