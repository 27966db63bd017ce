"""The options of a run, checked in one place.

``Simulator.simulate`` and ``Simulator.ensemble`` take the same option
keywords; both hand them to :func:`run_options`, which checks every one
(the message names the argument and its value) and returns a
:class:`RunOptions`. :func:`plan_rows` then counts the rows a run keeps
(``every=``, ``final_only=``) and refuses, before anything is allocated, a
run past ``max_rows``, past the memory of the machine, or past the C
runtime's limit of output times.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from ..codegen.abi import method_name
from ..core.errors import InputError

__all__ = ["RunOptions", "run_options", "plan_rows", "memory_available", "C_MAX_INTERVALS",
           "OPTION_NAMES"]

# gen_rt_simulate_rows refuses more than 1e9 output intervals (an int count)
C_MAX_INTERVALS = 1e9

# the option keywords shared by simulate, ensemble and the batch calls
OPTION_NAMES = ("method", "rtol", "atol", "project", "t0", "max_steps", "input_period",
                "input_hold", "every", "final_only", "max_rows", "events", "terminal",
                "consistent")


@dataclass(frozen=True)
class RunOptions:
    """The checked options of one run (or of every run of an ensemble)."""
    method: str = "rk4"
    rtol: float = 1e-8
    atol: float = 1e-10
    project: bool = True
    t0: float = 0.0
    t_end: float = 0.0
    dt: float = 0.0
    max_steps: int = 100000
    input_period: float | None = None
    input_hold: str = "zoh"
    every: int = 1
    final_only: bool = False
    max_rows: int | None = None
    events: dict | None = None
    terminal: object = False
    consistent: bool = False


def _number(name, v):
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {v!r}", name, None, v) from None
    return f


def run_options(t_end, dt, method="rk4", rtol=1e-8, atol=1e-10, project=True, t0=0.0,
                max_steps=100000, input_period=None, input_hold="zoh", every=1,
                final_only=False, max_rows=None, events=None, terminal=False,
                consistent=False):
    """Check the options of a run; return them as a :class:`RunOptions`.

    Raises
    ------
    gen.InputError
        On a bad value; the message names the argument and the value.
    """
    try:
        method = method_name(method)            # gen/codegen/abi.py: the names and their aliases
    except ValueError as e:
        raise InputError(str(e), "method", None, method) from None
    t0 = _number("t0", t0)
    t_end = _number("t_end", t_end)
    dt = _number("dt", dt)
    if not math.isfinite(t0):
        raise InputError(f"t0 must be a finite number, got t0 = {t0!r}", "t0", None, t0)
    if not (math.isfinite(dt) and dt > 0):
        raise InputError(f"dt must be a positive number, got dt = {dt!r}", "dt", None, dt)
    if not (math.isfinite(t_end) and t_end >= t0):
        raise InputError(f"t_end must be a number >= t0 = {t0}, got t_end = {t_end!r}",
                         "t_end", None, t_end)
    for name, v in (("rtol", rtol), ("atol", atol)):
        v = _number(name, v)
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"{name} must be a positive number, got {name} = {v!r}", name,
                             None, v)
    if isinstance(max_steps, bool) or int(max_steps) != max_steps or max_steps < 1:
        raise InputError(f"max_steps must be an integer >= 1, got max_steps = {max_steps!r}",
                         "max_steps", None, max_steps)
    if isinstance(every, bool) or int(every) != every or every < 1:
        raise InputError(f"every must be an integer >= 1, got every = {every!r}", "every",
                         None, every)
    if max_rows is not None and (isinstance(max_rows, bool) or int(max_rows) != max_rows
                                 or max_rows < 1):
        raise InputError(f"max_rows must be None or an integer >= 1, got max_rows = "
                         f"{max_rows!r}", "max_rows", None, max_rows)
    if input_hold not in ("zoh", "linear"):
        raise InputError(f"input_hold must be 'zoh' or 'linear', got {input_hold!r}",
                         "input_hold", None, input_hold)
    if events is None and terminal is not False:
        raise InputError("terminal= needs events={name: direction}", "terminal", None, terminal)
    return RunOptions(method=method, rtol=float(rtol), atol=float(atol), project=bool(project),
                      t0=t0, t_end=t_end, dt=dt, max_steps=int(max_steps),
                      input_period=input_period, input_hold=input_hold, every=int(every),
                      final_only=bool(final_only),
                      max_rows=None if max_rows is None else int(max_rows), events=events,
                      terminal=terminal, consistent=bool(consistent))


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
    opts : RunOptions
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
