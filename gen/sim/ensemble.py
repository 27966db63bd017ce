"""Ensembles: many simulations of one model, run in C in chunks on every
core (or on a Dask cluster) and reduced as they finish.

    res = sim.ensemble(x0, t_end, dt, p={"m": masses}, reduce="final")
    res.final                  # (N, nx), NaN rows for the runs that failed
    res.failures               # [(index, status name, t, x_last), ...]

What comes back is what ``reduce`` asks for, never every row of every run
(memory in proportion to the result):

- ``"final"`` (default): the state at t_end, (N, nx);
- ``gen.At(times, names)``: states or outputs at output times, (N, len(times), len(names));
- ``gen.Min(names)``, ``gen.Max(names)``, ``gen.Mean(names)``: over the output rows, (N, len(names));
- a Python function ``f(t, X) -> array``: called once per chunk on the chunk's full
  trajectories (X (n, rows, nx); only a chunk's rows are ever held), its results concatenated;
- a dict ``{key: reducer}``: several at once (``res[key]``).

Runs are independent: the numbers do not depend on the chunks, the threads
or the machine that ran them (a run is exactly ``sim.simulate`` of its own
x0, p, r). A run that fails (a singular configuration, a divergence) gets
its status and last state in ``res.status`` / ``res.failures``; the others
complete.

With ``client=`` a ``dask.distributed.Client`` the chunks run on the
cluster's workers. The model reaches a worker by content: the task carries
the model library's sources (a few hundred kB, scattered once); the worker
builds them into its own cache (gen.build, keyed by content: a second
ensemble of the same model compiles nothing) and loads them. A worker needs
eomgen, numpy, cffi and a C compiler (the same as gen.compile), not sympy
and not the model's derivation.
"""
from __future__ import annotations

import functools
import os
import sys
import threading
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..codegen.abi import JACOBIAN_METHODS
from ..core.errors import InputError
from ..core.optional import require
from ..core.status import status_name
from .interrupt import call, count as interrupt_count
from .options import fill_sim_options, finite_or_raise, plan_rows

__all__ = ["Sampler", "At", "Min", "Max", "Mean", "Final", "EnsembleResult", "run_ensemble"]


# ------------------------------------------------------------------ reducers
@dataclass(frozen=True)
class Final:
    """The state at t_end: (N, nx)."""


@dataclass(frozen=True)
class At:
    """Reducer: states or outputs at given output times.

    Parameters
    ----------
    times : float or sequence of float
        The times, each taken at the nearest output row (t0 + k dt, or
        t_end); a UserWarning names a time that is not an output time and
        the row's time used.
    names : sequence of str, optional
        States or outputs by name (None: every state).

    Notes
    -----
    Gives an array (N, len(times), len(names)).
    """
    times: tuple
    names: tuple | None = None

    def __init__(self, times, names=None):
        object.__setattr__(self, "times", tuple(float(t) for t in np.atleast_1d(times)))
        object.__setattr__(self, "names", None if names is None else tuple(names))


@dataclass(frozen=True)
class _Over:
    names: tuple | None = None

    def __init__(self, names=None):
        object.__setattr__(self, "names", None if names is None else
                           tuple([names] if isinstance(names, str) else names))


class Min(_Over):
    """The smallest value over the output rows of each named state or
    output (None: every state): (N, len(names))."""


class Max(_Over):
    """The largest value over the output rows: (N, len(names))."""


class Mean(_Over):
    """The mean over the output rows: (N, len(names))."""


@dataclass
class EnsembleResult:
    """What an ensemble returns. values: {key: array}, one per reducer (also
    as attributes: res.final, res[key]); status: (N,) 0 or the failing C
    status; failures: [(index, status name, t, x_last)] of the failed runs;
    t: the output times (rows of a run), made on first use when no reducer
    needed them (times: the array or the function that makes it: a reduced
    ensemble of 10^8-row runs holds no 10^8 times); seconds: the wall time."""
    values: dict
    status: np.ndarray
    t_last: np.ndarray
    x_last_failed: dict
    times: object
    seconds: float = 0.0
    chunks: int = 0
    extra: dict = field(default_factory=dict)

    def __getitem__(self, key):
        return self.values[key]

    @property
    def t(self):
        """The output times of a run (rows), np.ndarray (rows,)."""
        if callable(self.times):
            self.times = self.times()
        return self.times

    def __getattr__(self, key):
        values = self.__dict__.get("values", {})
        if key in values:
            return values[key]
        raise AttributeError(key)

    @property
    def n(self):
        """The number of runs N."""
        return len(self.status)

    @property
    def ok(self):
        """(N,) True for the runs that completed."""
        return self.status == 0

    @property
    def failures(self):
        """[(index, status name, t, last good state)] of the failed runs."""
        return [(int(i), status_name(int(self.status[i])), float(self.t_last[i]),
                 self.x_last_failed[int(i)]) for i in np.flatnonzero(self.status)]

    @property
    def runs_per_second(self):
        """Runs per second of wall time (NaN before the runs)."""
        return self.n / self.seconds if self.seconds > 0 else float("nan")


# ------------------------------------------------------------------ sampling
class Sampler:
    """Named random or gridded values for an ensemble's x0 and p.

    A spec is ("uniform", low, high), ("normal", mean, std), a number (the
    same for every run) or an array of N values; draw returns {name: (N,)}.
    The strings of the command line parse with Sampler.parse
    ("uniform:0.8:1.2", "normal:0:0.05", "0.3").

    Parameters
    ----------
    seed : int, optional
        The seed of the random generator (numpy's ``default_rng``): the same
        seed and the same specs, in the same order, give the same draws.

    Examples
    --------
    >>> s = gen.Sampler(seed=1)
    >>> p = s.draw(1000, m=("uniform", 0.8, 1.2), L=("normal", 1.0, 0.01))
    >>> g = gen.Sampler.grid(m=np.linspace(0.8, 1.2, 21), L=[0.9, 1.0, 1.1])  # 63 runs
    """

    KINDS = ("uniform", "normal")

    def __init__(self, seed=None):
        self.rng = np.random.default_rng(seed)

    def draw(self, n, **specs):
        """Draw n values of each named quantity.

        Parameters
        ----------
        n : int
            The number of runs.
        **specs
            ``name=spec``: ("uniform", low, high), ("normal", mean, std), a
            number, an array of n values, or a command-line string (see
            :meth:`parse`). Drawn in the order given.

        Returns
        -------
        dict
            ``{name: numpy.ndarray of shape (n,)}``.

        Raises
        ------
        ValueError
            When n < 1 or a spec is malformed.
        """
        n = int(n)
        if n < 1:
            raise InputError(f"the number of runs must be >= 1, got {n}")
        out = {}
        for name, spec in specs.items():   # in the order given: reproducible by seed
            out[name] = self._one(name, spec, n)
        return out

    def _one(self, name, spec, n):
        if isinstance(spec, str):
            spec = self.parse(spec)
        if isinstance(spec, tuple) and spec and isinstance(spec[0], str):
            kind, *args = spec
            if kind not in self.KINDS or len(args) != 2:
                raise InputError(f"{name}: a spec is ('uniform', low, high) or ('normal', mean, "
                                 f"std), got {spec!r}")
            a, b = float(args[0]), float(args[1])
            if kind == "uniform":
                if not b >= a:
                    raise InputError(f"{name}: uniform needs low <= high, got {a}, {b}")
                return self.rng.uniform(a, b, n)
            if not b >= 0:
                raise InputError(f"{name}: normal needs std >= 0, got {b}")
            return self.rng.normal(a, b, n)
        arr = np.asarray(spec, dtype=float)
        if arr.ndim == 0:
            return np.full(n, float(arr))
        if arr.shape != (n,):
            raise InputError(f"{name}: {arr.shape[0] if arr.ndim else 1} values for {n} runs")
        return arr

    @staticmethod
    def parse(text):
        """Parse a spec of the command line.

        Parameters
        ----------
        text : str
            ``"uniform:LOW:HIGH"``, ``"normal:MEAN:STD"`` or a number.

        Returns
        -------
        tuple or float
            ``("uniform", low, high)``, ``("normal", mean, std)`` or the number.

        Raises
        ------
        ValueError
            On any other text.
        """
        parts = str(text).split(":")
        if len(parts) == 1:
            try:
                return float(parts[0])
            except ValueError:
                raise InputError(f"{text!r} is neither a number nor uniform:LOW:HIGH or "
                                 "normal:MEAN:STD") from None
        if parts[0] not in Sampler.KINDS or len(parts) != 3:
            raise InputError(f"{text!r}: write uniform:LOW:HIGH or normal:MEAN:STD")
        try:
            return (parts[0], float(parts[1]), float(parts[2]))
        except ValueError:
            raise InputError(f"{text!r}: LOW/HIGH and MEAN/STD must be numbers") from None

    @staticmethod
    def grid(**axes):
        """The full grid of the axes, flattened in C order (the last name varies
        fastest).

        Parameters
        ----------
        **axes
            ``name=values``: the values of each axis.

        Returns
        -------
        dict
            ``{name: numpy.ndarray of shape (N,)}``, N the product of the lengths.
        """
        names = list(axes)
        vals = [np.asarray(axes[k], dtype=float).ravel() for k in names]
        mesh = np.meshgrid(*vals, indexing="ij")
        return {k: m.ravel() for k, m in zip(names, mesh)}


# ------------------------------------------------------------------ inputs
def _expand(sim, v, width, names, labels, base, what):
    """(array (1 or N, width)) of one value, an (N, width) array or a dict
    {name: scalar or (N,)} over base."""
    if isinstance(v, dict):
        lens = {len(np.atleast_1d(a)) for a in v.values()}
        lens.discard(1)
        if len(lens) > 1:
            raise InputError(f"{what}: arrays of different lengths {sorted(lens)}")
        n = lens.pop() if lens else 1
        out = np.tile(np.asarray(base, dtype=float), (n, 1))
        for k, a in v.items():
            k = str(k)
            if k in names:
                j = names.index(k)
            elif k in labels:
                j = labels.index(k)
            else:
                raise InputError(f"unknown name {k!r} in {what}; known: {names}")
            out[:, j] = np.broadcast_to(np.asarray(a, dtype=float), (n,))
        return out
    a = np.asarray(v, dtype=float)
    if a.ndim == 1 and a.shape == (width,):
        return a[None, :]
    if a.ndim == 2 and a.shape[1] == width:
        return a
    if a.ndim == 0 and width == 1:
        return a.reshape(1, 1)
    raise InputError(f"{what} must be {width} values, an (N, {width}) array or a dict of "
                     f"names {names}; got shape {a.shape}")


def _quantities(sim, names):
    """Indices into [x, y] of state or output names (None: every state)."""
    if names is None:
        return list(range(sim.nx))
    out = []
    for k in names:
        k = str(k)
        if k in sim.state_names:
            out.append(sim.state_names.index(k))
        elif k in sim.state_labels:
            out.append(sim.state_labels.index(k))
        elif k in sim.output_names:
            out.append(sim.nx + sim.output_names.index(k))
        elif k in sim.output_labels:
            out.append(sim.nx + sim.output_labels.index(k))
        else:
            raise InputError(f"unknown quantity {k!r}; states {sim.state_names}, outputs "
                             f"{sim.output_names}")
    return out


def _reducers(sim, reduce, rows, t0, dt, t_rows=None):
    """{key: (kind, sel, at_rows, shape of one run, python fn)}."""
    lib = sim.library.host
    if reduce is None or isinstance(reduce, str):
        if reduce not in (None, "final", "rows"):
            raise InputError(f"reduce must be 'final', 'rows', gen.At/Min/Max/Mean, a function "
                             f"f(t, X) or a dict of them, got {reduce!r}", "reduce", None, reduce)
        reduce = {"rows": "rows"} if reduce == "rows" else {"final": Final()}
    elif not isinstance(reduce, dict):
        key = ("final" if isinstance(reduce, Final) else "at" if isinstance(reduce, At) else
               type(reduce).__name__.lower() if isinstance(reduce, _Over) else "user")
        reduce = {key: reduce}
    out = {}
    for key, rd in reduce.items():
        if isinstance(rd, str) and rd == "final" or isinstance(rd, Final):
            out[key] = (lib.EOMGEN_REDUCE_FINAL, [], [], (sim.nx,), None)
        elif isinstance(rd, str) and rd == "rows":
            out[key] = (lib.EOMGEN_REDUCE_ROWS, [], [], (rows, sim.nx), None)
        elif isinstance(rd, At):
            sel = _quantities(sim, rd.names)
            at = [int(round((t - t0) / dt)) for t in rd.times]
            if any(not 0 <= k < rows for k in at):
                raise InputError(f"At: times {rd.times} outside the run [{t0}, t_end]")
            if t_rows is not None:   # the nearest row; a warning when it is not the time asked
                at = _snap_warn(rd.times, t_rows, dt)
            out[key] = (lib.EOMGEN_REDUCE_AT, sel, at, (len(at), len(sel)), None)
        elif isinstance(rd, _Over):
            kind = {"Min": lib.EOMGEN_REDUCE_MIN, "Max": lib.EOMGEN_REDUCE_MAX,
                    "Mean": lib.EOMGEN_REDUCE_MEAN}[type(rd).__name__]
            sel = _quantities(sim, rd.names)
            out[key] = (kind, sel, [], (len(sel),), None)
        elif callable(rd):
            out[key] = (lib.EOMGEN_REDUCE_ROWS, [], [], (rows, sim.nx), rd)
        else:
            raise InputError(f"reduce[{key!r}]: not a reducer: {rd!r}")
    return out


def _snap_warn(times, t_rows, dt):
    """The output rows nearest the times of gen.At; a warning names each
    time that is not an output time and the row's time used instead."""
    at = [int(np.argmin(np.abs(t_rows - t))) for t in times]
    off = [(t, float(t_rows[k])) for t, k in zip(times, at)
           if abs(t_rows[k] - t) > 1e-9 * dt + 4 * np.finfo(float).eps * abs(t)]
    if off:
        import warnings

        from ..intake.model import user_stacklevel
        pairs = ", ".join(f"t = {t:.12g} -> {u:.12g}" for t, u in off)
        warnings.warn(f"gen.At: not an output time (t0 + k dt, dt = {dt:g}, and t_end), the "
                      f"nearest output row is used: {pairs}; ask for output times, or choose "
                      "dt so that they are", UserWarning, stacklevel=user_stacklevel())
    return at


# ------------------------------------------------------------------ a chunk
def run_chunk(sim, job, since=None):
    """One chunk in C (the GIL released): job holds the chunk's x0, p, r
    (arrays of its runs, or one row for all), the shared settings and the
    reducers; returns {"status", "t_last", "x_last", "values"}."""
    library = sim.library
    ffi, lib = library.ffi, library.host
    n, nx, rows, run = job["n"], sim.nx, job["rows"], job["run"]
    if run.method in JACOBIAN_METHODS:
        library.ensure_derivatives()
    keep = []

    def arr(a, dtype=None):
        a = np.ascontiguousarray(a, dtype=dtype or sim.dtype)
        keep.append(a)
        return a

    def ptr(a, t=None):
        return library.array(a, t)

    e = library.new("ensemble")
    e.n = n
    x0 = arr(job["x0"])
    e.x0, e.x0_stride = ptr(x0), (nx if len(x0) > 1 else 0)
    if job["p"] is not None:
        p = arr(job["p"])
        e.p, e.p_stride = ptr(p), (sim.np if len(p) > 1 else 0)
    if job["r"] is not None:
        r = arr(job["r"])
        e.r, e.r_stride = ptr(r), (sim.nr if len(r) > 1 else 0)
    from .inputs import plan_inputs
    plan = plan_inputs(sim, job["r_shared"], job["controller"], run.dt, run.method,
                       run.input_period, run.input_hold)
    if plan is not None:
        e.input = plan.struct
    hybrid = None
    if getattr(sim, "nh", 0):
        # hybrid={...}: every run through simulate_events with the engine's
        # hybrid work (this chunk's own), as sim.simulate runs it
        from .events import plan_events
        hybrid = plan_events(sim, None, capacity=0)
        e.events = hybrid.struct
    opts = library.new("sim_options")
    library.function("sim_options_default")(opts)
    fill_sim_options(opts, run, rows=False)   # every and final_only: the reducers'
    e.opts = opts
    e.t0, e.t_end, e.dt = run.t0, run.t_end, run.dt
    e.rows = rows
    reducers = job["reducers"]
    e.final_only = int(all(k == lib.EOMGEN_REDUCE_FINAL for k, *_ in reducers.values()))
    e.consistent = int(run.consistent)
    cap = 1 if e.final_only else rows
    t_buf, x_buf = arr(np.empty(cap)), arr(np.empty((cap, nx)))
    r_buf = arr(np.empty((cap, max(1, sim.nr)))) if plan is not None else None
    x_start, y_buf = arr(np.empty(nx)), arr(np.empty(max(1, sim.ny)))
    e.t_buf, e.x_buf, e.x_start, e.y_buf = ptr(t_buf), ptr(x_buf), ptr(x_start), ptr(y_buf)
    if r_buf is not None:
        e.r_buf = ptr(r_buf)
    stats = library.new("sim_stats")
    e.stats = stats
    status = arr(np.zeros(n, dtype=np.intc), np.intc)
    t_last, x_last = arr(np.empty(n)), arr(np.empty((n, nx)))
    e.status, e.t_last, e.x_last = ptr(status, "int[]"), ptr(t_last), ptr(x_last)
    rds = ffi.new("eomgen_reducer[]", max(1, len(reducers)))
    values = {}
    for i, (key, (kind, sel, at, shape, fn)) in enumerate(reducers.items()):
        out = arr(np.empty((n,) + shape))
        values[key] = out
        rds[i].kind = kind
        s_ = arr(np.asarray(sel, dtype=np.intc), np.intc)
        a_ = arr(np.asarray(at, dtype=np.intc), np.intc)
        rds[i].n_sel, rds[i].sel = len(sel), ptr(s_, "int[]")
        rds[i].n_rows, rds[i].rows = len(at), ptr(a_, "int[]")
        rds[i].out = ptr(out)
    e.n_reducers, e.reducers = len(reducers), rds
    call(sim, opts, library.host.eomgen_ensemble_run, library.table, e,   # the C call of a chunk
         since=since)                   # (Ctrl-C: gen/sim/interrupt.py)
    if plan is not None and plan.error is not None:
        raise plan.error
    t_rows = job["t_rows"]
    for key, (kind, sel, at, shape, fn) in reducers.items():
        if fn is not None:
            values[key] = np.asarray(fn(t_rows, values[key]))
    failed = np.flatnonzero(status)
    return {"status": status, "t_last": t_last, "values": values,
            "x_last": {int(i): x_last[i].astype(float).copy() for i in failed}}


# ------------------------------------------------------------------ the call
def _output_times(t0, dt, t_end, rows):
    return np.minimum(t0 + dt * np.arange(rows), t_end)


def _rows(sim, x0, p, r):
    lens = {len(a) for a in (x0, p, r) if a is not None}
    lens.discard(1)
    if len(lens) > 1:
        raise InputError(f"x0, p and r give different numbers of runs: {sorted(lens)}")
    return lens.pop() if lens else 1


def _slice(a, i0, i1):
    return None if a is None else (a if len(a) == 1 else a[i0:i1])


def _progress(total, enabled):
    """A tqdm bar over the runs on a terminal (enabled None: when stderr is
    one and tqdm is installed), else nothing."""
    if enabled is False or (enabled is None and not sys.stderr.isatty()):
        return None
    try:
        tqdm = require("tqdm", "Simulator.ensemble(progress=True)")
    except ImportError:
        if enabled:
            raise
        return None
    return tqdm.tqdm(total=total, unit="run", smoothing=0.1)


def run_ensemble(sim, x0, opts, r=None, p=None, controller=None, reduce="final", client=None,
                 chunk=None, workers=None, progress=None):
    """Simulator.ensemble (its docstring); opts: the checked gen.sim.options.Run."""
    if opts.events is not None:
        raise InputError("events= is not available in an ensemble: simulate the runs that "
                         "need events one by one (sim.simulate(..., events=...))", "events")
    if opts.every != 1:
        raise InputError(f"every={opts.every}: an ensemble keeps what its reducers ask for "
                         "(reduce='final', gen.At, ...); give every=1", "every", None,
                         opts.every)
    if opts.final_only and not (reduce is None or reduce == "final"
                                or isinstance(reduce, Final)):
        raise InputError("final_only=True keeps the final state only: give reduce='final' "
                         f"(got reduce={reduce!r})", "final_only")
    t0, t_end, dt = opts.t0, opts.t_end, opts.dt
    if callable(r) and not isinstance(r, tuple):
        raise InputError("an ensemble runs in C without the GIL: give r as constants (one row, "
                         "or one per run), a table (t_grid, R) or a gen.LinearFeedback "
                         "controller, not a Python function", "r")
    X0 = _expand(sim, x0, sim.nx, sim.state_names, sim.state_labels, np.zeros(sim.nx),
                 "x0")
    P = None if p is None else _expand(sim, p, sim.np, sim.constant_names,
                                       sim.constant_labels, sim.constants, "p")
    table = isinstance(r, tuple) and len(r) == 2
    R = None if (r is None or table) else _expand(sim, r, sim.nr, sim.input_names,
                                                  sim.input_labels, np.zeros(sim.nr), "r")
    if R is not None and controller is not None:
        raise InputError("give the inputs at the operating point as LinearFeedback(r_op=...), "
                         "not also as r", "r")
    labels = {"x0": sim.state_names, "p": sim.constant_names, "r": sim.input_names}
    for name, a in (("x0", X0), ("p", P), ("r", R)):
        if a is not None:
            finite_or_raise(name, a, labels[name])
    n = _rows(sim, X0, P, R)
    full = sim.library.function("simulate_rows")(t0, t_end, dt)
    # every row of a run is kept only for a "rows" or a Python reducer: the
    # same checks as simulate's (max_rows, memory, the C limit) before
    # anything is allocated
    keeps_rows = reduce == "rows" or callable(reduce) or (
        isinstance(reduce, dict) and any(v == "rows" or (callable(v) and not isinstance(
            v, (Final, At, _Over))) for v in reduce.values()))
    check = opts if keeps_rows else replace(opts, final_only=True)
    row_bytes = np.dtype(sim.dtype).itemsize * (1 + sim.nx)
    _, rows = plan_rows(check, full if full >= 0 else None, row_bytes,
                        sim.library.function("simulate_rows_kept"),
                        what="every run of this ensemble" if keeps_rows else "this ensemble",
                        runs=n if keeps_rows else 1)
    # the output times only where a reducer reads them (rows kept, gen.At's
    # rows): a final state of 10^8-row runs needs none of their 10^8 times
    times = functools.partial(_output_times, t0, dt, t_end, rows)    # (picklable)
    reads_t = keeps_rows or isinstance(reduce, At) or (
        isinstance(reduce, dict) and any(isinstance(v, At) for v in reduce.values()))
    t_rows = times() if reads_t else None
    reducers = _reducers(sim, reduce, rows, t0, dt, t_rows)
    workers = workers or os.cpu_count() or 1
    if chunk is None:
        # a few chunks per worker (load balance), and a chunk's full rows (a
        # Python reducer's input) within ~64 MB
        per_run = rows * sim.nx * 8 if any(v[4] for v in reducers.values()) else 64
        chunk = int(max(1, min(-(-n // (4 * workers)), 20000, 64e6 // per_run)))
    chunk = int(chunk)
    if chunk < 1:
        raise InputError(f"chunk must be >= 1, got {chunk}")
    bounds = [(i, min(n, i + chunk)) for i in range(0, n, chunk)]
    shared = dict(rows=rows, t_rows=t_rows, run=opts, r_shared=r if table else None,
                  controller=controller, reducers=reducers)
    jobs = [dict(shared, n=i1 - i0, x0=_slice(X0, i0, i1), p=_slice(P, i0, i1),
                 r=_slice(R, i0, i1)) for i0, i1 in bounds]
    bar = _progress(n, progress)
    start = time.perf_counter()
    try:
        if client is None:
            results = _run_local(sim, jobs, workers, bar)
        else:
            results = _run_dask(sim, jobs, client, bar)
    finally:
        if bar is not None:
            bar.close()
    seconds = time.perf_counter() - start
    status = np.concatenate([res["status"] for res in results]).astype(int)
    t_last = np.concatenate([res["t_last"] for res in results]).astype(float)
    x_failed = {}
    for (i0, _), res in zip(bounds, results):
        x_failed.update({i0 + k: v for k, v in res["x_last"].items()})
    values = {k: np.concatenate([res["values"][k] for res in results])
              for k in reducers}
    return EnsembleResult(values, status, t_last, x_failed, times if t_rows is None else t_rows,
                          seconds, len(jobs))


def _run_local(sim, jobs, workers, bar):
    from concurrent.futures import ThreadPoolExecutor
    lock = threading.Lock()

    since = interrupt_count(sim)     # a Ctrl-C from here on stops every chunk, started or not

    def one(job):
        res = run_chunk(sim, job, since=since)
        if bar is not None:
            with lock:
                bar.update(job["n"])
        return res

    if workers == 1 or len(jobs) == 1:
        return [one(j) for j in jobs]
    ex = ThreadPoolExecutor(max_workers=workers)
    try:
        return list(ex.map(one, jobs))
    except BaseException:
        # Ctrl-C (or a failed chunk): the chunks not started never start; the
        # running ones stop at their cancellation flag (gen/sim/interrupt.py)
        ex.shutdown(wait=True, cancel_futures=True)
        raise
    finally:
        ex.shutdown(wait=True)


# ------------------------------------------------------------------ Dask
def model_bundle(sim):
    """What a worker needs to build or load the model: the model library's
    sources (as compiled, from the build cache), its interface and build
    settings. Plain data (picklable), a few hundred kB."""
    from pathlib import Path
    info = getattr(sim, "build_info", {}) or {}
    module = info.get("module")
    if not module:
        raise InputError("this Simulator was not made by gen.compile: its sources are unknown")
    src = Path(module).parent / "src"
    files = {f.name: f.read_text() for f in sorted(src.iterdir()) if f.is_file()}
    backend = info.get("backend", "c")
    derivatives = bool(info.get("derivatives", True))
    # the class pickles by reference (its module and name): this module
    # needs no import of gen.bindings
    return {"files": files, "interface": sim.interface, "backend": backend,
            "real": sim.real, "derivatives": derivatives, "name": sim.name,
            "simulator": type(sim)}


_loaded = {}
_loaded_lock = threading.Lock()


def simulator_from_bundle(bundle):
    """The Simulator of a bundle in this process: built into this machine's
    eomgen cache if it is not there (by content), loaded once per process."""
    from ..toolchain.build import build
    from ..toolchain.host import load
    from ..codegen.render import Rendered
    rendered = Rendered(dict(bundle["files"]), bundle["interface"], bundle["backend"],
                        bundle["real"], bundle["derivatives"])
    tm = {}
    built = build(rendered, timings=tm)
    with _loaded_lock:
        sim = _loaded.get(built.modname)
        if sim is None:
            host, api = load(built)
            sim = _loaded[built.modname] = bundle["simulator"](host, api, built.interface)
            sim.build_info = {"module": str(built.path), "derivatives": built.derivatives,
                              "cached": tm.get("cached"), "compile": tm.get("compile")}
    return sim


def _dask_task(bundle, job):
    sim = simulator_from_bundle(bundle)
    return run_chunk(sim, job)


def _run_dask(sim, jobs, client, bar):
    if jobs and jobs[0]["run"].method in JACOBIAN_METHODS:
        sim.library.ensure_derivatives()     # the workers get the complete library
    # one future for the whole bundle, under a key of this call's own: a
    # dict given to scatter itself would be scattered value by value under
    # the dict's keys ("files", "name", ...), shared by every model on the
    # cluster; a content key would be shared by two calls, and the first
    # call's release could drop the data the second one is about to use
    (bundle,) = client.scatter([model_bundle(sim)], broadcast=True, hash=False)
    futures = client.map(_dask_task, [bundle] * len(jobs), jobs, pure=False)
    if bar is not None:
        from distributed import as_completed
        size = {f.key: j["n"] for f, j in zip(futures, jobs)}
        for f in as_completed(futures):
            bar.update(size[f.key])
    return client.gather(futures)
