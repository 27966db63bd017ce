"""eomgen command line: generate, build, simulate, linearize, verify and
report on a model file.

A model file is a Python file defining ``model()`` that returns a
``gen.Model``; ``FILE.py:function`` names another function. Exit codes:
0 success, 1 a failure (a model the generator refuses, a failed compile or
solve, a verification mismatch), 2 a usage error. No Python traceback
unless ``--debug``.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

from .._version import __version__

from ..codegen import abi
from .output import (MissingDependency, Progress, plot_simulation, print_csv,
                         print_events, print_linearization, write_csv, write_events_csv)
from ..codegen.backends import backend_names, get_backend
from ..core.errors import EomgenError

EXAMPLES = """examples:
  eomgen generate examples/seed_pendulum.py -o out/pend
  eomgen build examples/seed_pendulum.py:lagrange_model -o out/pend_lagrange
  eomgen simulate examples/seed_pendulum.py --t-end 5 --x0 q2=0.5 --csv run.csv --plot run.png
  eomgen simulate examples/seed_pendulum.py --t-end 5 --x0 q2=0.5 --method dopri5 --event q2:-1:terminal
  eomgen ensemble examples/seed_pendulum.py --samples 10000 --param L=uniform:0.8:1.2 --x0 q2=normal:0:0.3 --t-end 5 -o res.npz
  eomgen linearize examples/seed_pendulum.py --at q1=1 --at q2=0
  eomgen verify examples/seed_pendulum.py --samples 20
  eomgen generate examples/seed_pendulum.py -o out/pend_f --real float
  eomgen report examples/seed_pendulum.py --target cortex-m4f -o footprint.txt
  eomgen fmu examples/cart_pole.py -o cart_pole.fmu --fmi 3.0 --kind both
  eomgen cache            (where the build cache is, its size; eomgen cache clear empties it)

A model file defines model() returning a gen.Model (or name a function: FILE.py:func).
Exit codes: 0 ok, 1 failure, 2 usage error. --debug shows Python tracebacks.
"""


class UsageError(Exception):
    """Wrong arguments: exit code 2, one line."""


# ------------------------------------------------------------ model files
def load_model(spec: str, progress=None):
    """Import a model file and call its function (default model())."""
    path, _, func = spec.partition(":")
    func = func or "model"
    p = Path(path)
    if not p.is_file():
        raise UsageError(f"model file not found: {path} (give a .py file that defines model())")
    if p.suffix != ".py":
        raise UsageError(f"{path} is not a Python file: a model file is a .py file defining "
                         "model()")
    sys.path.insert(0, str(p.resolve().parent))
    modname = f"_eomgen_modelfile_{abs(hash(str(p.resolve())))}"
    spec_ = importlib.util.spec_from_file_location(modname, str(p))
    mod = importlib.util.module_from_spec(spec_)
    progress = progress or Progress(quiet=True)
    with progress.stage(f"import {p.name}"):
        try:
            spec_.loader.exec_module(mod)
        except EomgenError:
            raise
        except Exception as e:
            raise EomgenError(f"importing {path} failed: {type(e).__name__}: {e}") from e
    fn = getattr(mod, func, None)
    if fn is None or not callable(fn):
        raise UsageError(f"{path} defines no function {func}(): a model file must define "
                         f"{func}() returning a gen.Model (or name one as {path}:function)")
    with progress.stage(f"derive the model ({func}())"):
        try:
            model = fn()
        except EomgenError:
            raise
        except Exception as e:
            raise EomgenError(f"{path}:{func}() failed: {type(e).__name__}: {e}") from e
    from ..intake.model import Model
    if not isinstance(model, Model):
        raise UsageError(f"{path}:{func}() returned {type(model).__name__}, not a gen.Model")
    return model


def _number(text, what):
    try:
        v = float(text)
    except ValueError:
        raise UsageError(f"{what}: {text!r} is not a number") from None
    if v != v or v in (float("inf"), float("-inf")):
        raise UsageError(f"{what}: {text!r} is not a finite number")
    return v


def _pairs(items, names, what, labels=()):
    """NAME=VALUE strings -> {index: value}; names may also be given in
    their sympy spelling (labels)."""
    out = {}
    for it in items or []:
        if "=" not in it:
            raise UsageError(f"{what} must be NAME=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        k = k.strip()
        if k in names:
            i = names.index(k)
        elif k in labels:
            i = list(labels).index(k)
        else:
            raise UsageError(f"unknown {what} name {k!r}; known: {', '.join(names) or 'none'}")
        out[i] = _number(v, f"{what} {k}")
    return out


def _compile(model, a, progress):
    """gen.compile, shown as one stage; --verbose adds the time of each."""
    from ..pipeline import compile as compile_model
    backend = getattr(a, "backend", "c") or "c"
    timings = {}
    with progress.stage("kernels, printing, templates, compile (cffi, cached)"):
        sim = compile_model(model, backend=backend, real=a.real, timings=timings)
    for k in ("kernels", "printing", "templates", "compile"):
        if k in timings and progress.verbose:
            print(f"eomgen:   {k:<32} {timings[k]:8.2f} s", file=progress.stream)
    return sim


def _state(sim, a, items):
    import numpy as np
    m = sim
    x = np.zeros(sim.nx)
    for i, v in _pairs(items, sim.state_names, "state", m.state_labels).items():
        x[i] = v
    p = sim.constants.copy()
    for i, v in _pairs(a.param, sim.constant_names, "constant", m.constant_labels).items():
        p[i] = v
    r = np.zeros(sim.nr)
    for i, v in _pairs(getattr(a, "input", None), sim.input_names, "input",
                       m.input_labels).items():
        r[i] = v
    if sim.mc or sim.mv:
        x = sim.consistent_state(x, p=p)
    return x, p, r


_DIRECTIONS = {"+1": 1, "1": 1, "up": 1, "-1": -1, "down": -1, "0": 0, "both": 0}


def _events(sim, items):
    """--event NAME[=LEVEL]:DIR[:terminal] strings -> (events, terminal) for
    sim.simulate: {C name: (direction, level)} and {C name: bool}, the names
    of the states or outputs (their sympy spelling accepted too), as the
    standalone binary reads them."""
    events, terminal = {}, {}
    known = (f"states: {', '.join(sim.state_names)}"
             + (f"; outputs: {', '.join(sim.output_names)}" if sim.ny
                else " (the model has no outputs)"))
    for it in items or []:
        head, sep, rest = it.partition(":")
        if not sep:
            raise UsageError(f"--event must be NAME[=LEVEL]:DIR[:terminal], got {it!r}")
        d, _, flag = rest.partition(":")
        name, eq, level = head.partition("=")
        name = name.strip()
        level = _number(level, f"--event {it!r}: the level") if eq else 0.0
        for names, labels in ((sim.state_names, sim.state_labels),
                              (sim.output_names, sim.output_labels)):
            if name in names or name in labels:
                name = names[list(names).index(name)] if name in names \
                    else names[list(labels).index(name)]
                break
        else:
            raise UsageError(f"--event: unknown state or output {name!r} in {it!r}; {known}")
        if d not in _DIRECTIONS:
            raise UsageError(f"--event {it!r}: the direction must be +1 (1, up), -1 (down) "
                             "or 0 (both)")
        if flag not in ("", "terminal") or (not flag and it.count(":") > 1):
            raise UsageError(f"--event {it!r}: expected ':terminal' after the direction")
        if name in events:
            raise UsageError(f"--event {it!r}: {name} has an event already")
        events[name] = (_DIRECTIONS[d], level)
        terminal[name] = flag == "terminal"
    return events, terminal


# ------------------------------------------------------------- subcommands
def cmd_generate(a, progress):
    from ..codegen.render import render_files, write_atomic
    m = load_model(a.file, progress)
    if a.name:
        from ..intake.model import validate_name
        try:
            m.name = validate_name(a.name)
        except EomgenError as e:
            raise UsageError(str(e)) from None
    timings = {}
    with progress.stage("kernels, printing, templates"):
        files = render_files(m, real=a.real, backend=a.backend, timings=timings)
    with progress.stage("write files"):
        paths = write_atomic(files, a.output)
    print(f"wrote {len(paths)} files to {a.output}")
    return 0


@contextlib.contextmanager
def _folder_lock(folder: Path, progress):
    """Hold an exclusive lock on an output folder (a file next to it: the
    folder itself is replaced by generate) while generating and building into
    it; a second `eomgen build` into the same folder waits. fcntl on POSIX;
    elsewhere no lock."""
    try:
        import fcntl
    except ImportError:   # not POSIX
        yield
        return
    folder.parent.mkdir(parents=True, exist_ok=True)
    lock = folder.parent / f".{folder.name}.eomgen-lock"
    with open(lock, "a") as fh:
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            with progress.stage(f"wait for another eomgen build of {folder}"):
                fcntl.flock(fh.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh.fileno(), fcntl.LOCK_UN)


def cmd_build(a, progress):
    from ..codegen.render import generate
    if a.stack_limit is not None and a.stack_limit < 0:
        raise UsageError(f"--stack-limit must be a number of bytes >= 0, got {a.stack_limit}")
    if a.stack_limit and not get_backend(a.backend).stack_limit:
        raise UsageError("--stack-limit bounds the C library's frames: it needs --backend c")
    m = load_model(a.file, progress)
    out = Path(a.output)
    bld = out / "build"
    cfg = ["cmake", "-S", str(out), "-B", str(bld), "-DCMAKE_BUILD_TYPE=Release"]
    if get_backend(a.backend).stack_limit:
        # always given, so that a limit from an earlier run is not kept in the cache
        cfg.append(f"-D{m.name.upper()}_STACK_LIMIT={a.stack_limit or 0}")
    with _folder_lock(out.resolve(), progress):
        with progress.stage("generate"):
            generate(m, a.output, real=a.real, backend=a.backend)
        with progress.stage("cmake configure"):
            r = subprocess.run(cfg, capture_output=True, text=True)
        if r.returncode == 0:
            with progress.stage("cmake build"):
                r = subprocess.run(["cmake", "--build", str(bld), "--parallel",
                                    str(os.cpu_count() or 1)], capture_output=True, text=True)
    if r.returncode != 0:
        raise EomgenError("the CMake build failed:\n" + r.stdout + r.stderr)
    exe = bld / f"{m.name}_sim"
    print(exe)
    return 0


def _megabytes(n):
    return f"{n / 1e6:.1f} MB" if n >= 1e5 else f"{n / 1e3:.1f} kB"


def cmd_cache(a, progress):
    from ..core.cache import cache_info, clear_cache
    if a.action == "clear":
        info = cache_info()
        removed, freed = clear_cache()
        print(f"removed {removed} entries ({_megabytes(freed)}) from {info['path']}")
        return 0
    info = cache_info()
    print(f"cache: {info['path']}" + ("" if info["exists"] else " (does not exist yet)"))
    print(f"entries: {info['entries']} ({info['modules']} compiled models, "
          f"{info['runtimes']} runtime builds"
          + (f", {info['temporary']} builds in progress or stale" if info["temporary"] else "")
          + ")")
    print(f"size: {_megabytes(info['bytes'])}")
    print("set by EOMGEN_CACHE (else $XDG_CACHE_HOME/eomgen or ~/.cache/eomgen); "
          "safe to delete: eomgen cache clear")
    return 0


def cmd_linearize(a, progress):
    m = load_model(a.file, progress)
    sim = _compile(m, a, progress)
    x, p, r = _state(sim, a, a.at)
    discrete = None
    with progress.stage("linearize"):
        A, B = sim.linearize(x, r=r, p=p)
        if getattr(a, "dt", None) is not None:
            if not a.dt > 0:
                raise UsageError(f"--dt must be positive, got {a.dt}")
            discrete = (a.dt,) + sim.linearize(x, r=r, p=p, dt=a.dt)
    print_linearization(sim, x, r, A, B, discrete)
    return 0


def cmd_simulate(a, progress):
    import numpy as np
    m = load_model(a.file, progress)
    sim = _compile(m, a, progress)
    events, terminal = _events(sim, getattr(a, "event", None))
    if getattr(a, "events_csv", None) and not events:
        raise UsageError("--events-csv needs at least one --event")
    x, p, r = _state(sim, a, a.x0)
    if not a.t_end > 0:
        raise UsageError(f"--t-end must be positive, got {a.t_end}")
    if not a.dt > 0:
        raise UsageError(f"--dt must be positive, got {a.dt}")
    varying = False
    if getattr(a, "input_csv", None):
        if a.input:
            raise UsageError("give the inputs either with --input or with --input-csv")
        r = _read_input_table(sim, a.input_csv)
        varying = True
    method = abi.method_name(a.method, "--method")
    kw = dict(events=events, terminal=terminal) if events else {}
    with progress.stage(f"simulate {a.t_end:g} s ({method})"):
        sol = sim.simulate(x, a.t_end, a.dt, method=method, r=r, p=p, rtol=a.rtol,
                           atol=a.atol, input_hold=getattr(a, "hold", "zoh"), **kw)
    t, X, lam, R = sol.t, sol.x, sol.lam, sol.r
    Y = np.column_stack([sol.outputs[k] for k in sim.output_names]) if sim.ny else \
        np.empty((len(t), 0))
    if events:   # as the binary: a CSV file, or one line per event on stderr
        found = sol.events
        if a.events_csv:
            Path(a.events_csv).resolve().parent.mkdir(parents=True, exist_ok=True)
            with progress.stage(f"write {a.events_csv}"):
                write_events_csv(a.events_csv, sim.state_names, found)
        else:
            print_events(sim.state_names, found)
    cols = ["t"] + sim.state_names
    data = [t[:, None], X]
    res_names, res = [], []
    if sim.mc:
        fc = np.array([sim.constraints(xi[:sim.nq], p=p) for xi in X])
        res_names += [f"fc{i}" for i in range(sim.mc)]
        res.append(fc)
    if sim.mv:
        fv = np.array([sim.velocity_constraints(xi[:sim.nq], xi[sim.nq:], p=p) for xi in X])
        res_names += [f"fv{i}" for i in range(sim.mv)]
        res.append(fv)
    E = None
    if m.energy is not None:
        E = np.array([sim.energy(xi, p=p) for xi in X])
    aux = None
    if sim.na:
        aux = np.array([sim.auxiliary_forces(ti, xi, r=ri, p=p) for ti, xi, ri in zip(t, X, R)])
    if sim.ny:    # the outputs, as the binary writes them
        aux = Y if aux is None else np.hstack([aux, Y])
    if varying:   # the inputs in effect from each row on, as the binary writes them
        aux = R if aux is None else np.hstack([aux, R])
    for out in (a.csv, a.plot):
        if out:
            Path(out).resolve().parent.mkdir(parents=True, exist_ok=True)
    if a.csv:
        with progress.stage(f"write {a.csv}"):
            write_csv(a.csv, sim, cols, data, lam, res_names, res, E, aux,
                      aux_names=(list(sim.auxiliary_names) + list(sim.output_names)
                                 + (list(sim.input_names) if varying else [])))
        print(f"wrote {len(t)} rows to {a.csv}")
    if a.plot:
        with progress.stage(f"plot {a.plot}"):
            try:
                plot_simulation(a.plot, m, sim, t, X, res_names, res, E, Y=Y,
                                R=R if varying else None)
            except MissingDependency as e:
                raise UsageError(str(e)) from None
        print(f"wrote {a.plot}")
    if a.events_csv and (a.csv or a.plot):   # (else stdout holds the trajectory)
        print(f"wrote {len(found)} events to {a.events_csv}")
    if not a.csv and not a.plot:
        extra = (list(sim.auxiliary_names) + list(sim.output_names)
                 + (list(sim.input_names) if varying else []))
        print_csv(cols + (extra if aux is not None else []),
                  np.hstack(data + ([aux] if aux is not None else [])))
    return 0


def _read_input_table(sim, path):
    """(t_grid, R) from a CSV with a header 't,<input names>' (any order)."""
    import numpy as np
    try:
        lines = [ln.strip() for ln in Path(path).read_text().splitlines()
                 if ln.strip() and not ln.lstrip().startswith("#")]
    except OSError as e:
        raise UsageError(f"cannot read the input table {path}: {e.strerror}") from None
    if not lines:
        raise UsageError(f"the input table {path} is empty")
    head = [h.strip() for h in lines[0].split(",")]
    if head[0] != "t":
        raise UsageError(f"{path}: the header must be 't,<input names>' "
                         f"(inputs: {', '.join(sim.input_names)}), got {lines[0]!r}")
    unknown = [h for h in head[1:] if h not in sim.input_names]
    missing = [n for n in sim.input_names if n not in head[1:]]
    if unknown or missing:
        raise UsageError(f"{path}: " + "; ".join(
            ([f"unknown input(s) {', '.join(unknown)}"] if unknown else [])
            + ([f"no column for input(s) {', '.join(missing)}"] if missing else []))
            + f" (inputs: {', '.join(sim.input_names)})")
    rows = []
    for k, ln in enumerate(lines[1:], start=2):
        try:
            vals = [float(v) for v in ln.split(",")]
        except ValueError:
            raise UsageError(f"{path}:{k}: not a row of numbers: {ln!r}") from None
        if len(vals) != len(head):
            raise UsageError(f"{path}:{k}: expected {len(head)} values, got {len(vals)}")
        rows.append(vals)
    if not rows:
        raise UsageError(f"the input table {path} has a header but no rows")
    data = np.array(rows)
    R = data[:, [head.index(n) for n in sim.input_names]]
    return data[:, 0], R


def _reducers_arg(items):
    """--reduce final | min:NAMES | max:NAMES | mean:NAMES | at:T1,T2[:NAMES]
    (repeat) -> {key: reducer} of sim.ensemble."""
    from ..sim.ensemble import At, Max, Mean, Min
    out = {}
    for it in items or ["final"]:
        kind, _, rest = it.partition(":")
        if kind == "final" and not rest:
            out["final"] = "final"
            continue
        if kind in ("min", "max", "mean"):
            if not rest:
                raise UsageError(f"--reduce {it!r}: give the names, {kind}:NAME[,NAME...]")
            out[f"{kind}"] = {"min": Min, "max": Max, "mean": Mean}[kind](rest.split(","))
            continue
        if kind == "at":
            times, _, names = rest.partition(":")
            if not times:
                raise UsageError(f"--reduce {it!r}: at:T1[,T2...][:NAME[,NAME...]]")
            ts = [_number(v, f"--reduce {it!r}: a time") for v in times.split(",")]
            out["at"] = At(ts, names.split(",") if names else None)
            continue
        raise UsageError(f"--reduce {it!r}: final, min:NAMES, max:NAMES, mean:NAMES or "
                         "at:TIMES[:NAMES]")
    return out


def _sampled(items, names, labels, what, sampler, n):
    """--param/--x0 NAME=SPEC (a number, uniform:LOW:HIGH, normal:MEAN:STD)
    -> {C name: (n,) values}, drawn in the order given."""
    from ..sim.ensemble import Sampler
    specs = {}
    for it in items or []:
        if "=" not in it:
            raise UsageError(f"--{what} must be NAME=VALUE or NAME=uniform:LOW:HIGH or "
                             f"NAME=normal:MEAN:STD, got {it!r}")
        k, v = (x.strip() for x in it.split("=", 1))
        if k in labels and k not in names:
            k = names[list(labels).index(k)]
        if k not in names:
            raise UsageError(f"unknown {what} name {k!r}; known: {', '.join(names) or 'none'}")
        try:
            specs[k] = Sampler.parse(v)
        except ValueError as e:
            raise UsageError(f"--{what} {it!r}: {e}") from None
    try:
        return sampler.draw(n, **specs) if specs else {}
    except ValueError as e:
        raise UsageError(f"--{what}: {e}") from None


def cmd_ensemble(a, progress):
    import numpy as np

    from ..sim.ensemble import Sampler
    m = load_model(a.file, progress)
    sim = _compile(m, a, progress)
    if a.samples < 1:
        raise UsageError(f"--samples must be at least 1, got {a.samples}")
    if not a.t_end > 0 or not a.dt > 0:
        raise UsageError("--t-end and --dt must be positive")
    sampler = Sampler(a.seed)
    x0 = _sampled(a.x0, sim.state_names, sim.state_labels, "x0", sampler, a.samples)
    p = _sampled(a.param, sim.constant_names, sim.constant_labels, "param", sampler, a.samples)
    r = _sampled(a.input, sim.input_names, sim.input_labels, "input", sampler, a.samples)
    reduce = _reducers_arg(a.reduce)
    client = None
    if a.scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise UsageError("--scheduler needs dask.distributed: pip install "
                                    "'eomgen[dask]'") from None
        client = Client(a.scheduler)
    out = Path(a.output)
    if out.suffix not in (".npz", ".parquet"):
        raise UsageError(f"-o {a.output}: write .npz or .parquet")
    n = a.samples
    with progress.stage(f"{n} runs of {a.t_end:g} s ({a.method})"):
        res = sim.ensemble(x0 or np.zeros((n, sim.nx)), a.t_end, a.dt, p=p or None, r=r or None,
                           reduce=reduce, client=client, chunk=a.chunk, method=a.method,
                           rtol=a.rtol, atol=a.atol, workers=a.workers,
                           consistent=not a.no_consistent and bool(sim.mc or sim.mv),
                           progress=None if not a.quiet else False)
    cols = {f"x0.{k}": v for k, v in x0.items()}
    cols.update({f"param.{k}": v for k, v in p.items()})
    cols.update({f"input.{k}": v for k, v in r.items()})
    cols["status"] = res.status
    with progress.stage(f"write {out}"):
        out.parent.mkdir(parents=True, exist_ok=True)
        if out.suffix == ".npz":
            np.savez(out, t=res.t, **cols, **{k: np.asarray(v) for k, v in res.values.items()})
        else:
            try:
                import pandas as pd
            except ImportError:
                raise UsageError("-o .parquet needs pandas and pyarrow: pip install "
                                        "pandas pyarrow (or write .npz)") from None
            for k, v in res.values.items():
                v = np.asarray(v).reshape(res.n, -1)
                for j in range(v.shape[1]):
                    cols[f"{k}.{j}" if v.shape[1] > 1 else k] = v[:, j]
            try:
                pd.DataFrame(cols).to_parquet(out)
            except ImportError as e:
                raise UsageError(f"-o .parquet: {e}") from None
    fails = res.failures
    print(f"{res.n} runs, {len(fails)} failed, {res.runs_per_second:.0f} runs/s -> {out}")
    for i, name, t, _x in fails[:10]:
        print(f"  run {i}: {name} at t = {t:.6g}", file=sys.stderr)
    if len(fails) > 10:
        print(f"  ... and {len(fails) - 10} more (status in {out})", file=sys.stderr)
    return 0


def cmd_verify(a, progress):
    from ..export.verify import verify
    m = load_model(a.file, progress)
    backends = {"both": backend_names("loadable")}.get(a.backend, [a.backend])
    ok = True
    for backend in backends:
        with progress.stage(f"verify {backend} against sympy ({a.samples} states)"):
            rep = verify(m, samples=a.samples, backend=backend, real=a.real,
                         sources=a.sources, tol=a.tol, seed=a.seed)
        print(rep.table())
        ok = ok and rep.ok
    return 0 if ok else 1


def cmd_fmu(a, progress):
    """eomgen fmu: the model as an FMU (gen.export_fmu)."""
    from ..export.fmu import export_fmu
    m = load_model(a.file, progress)
    start = {m.state_names[i]: v for i, v in
             _pairs(a.start, m.state_names, "state", m.state_labels).items()}
    units = {}
    names = m.state_names + m.input_names + m.constant_names + m.output_names
    labels = m.state_labels + m.input_labels + m.constant_labels + m.output_labels
    for it in a.unit or []:
        k, eq, unit = it.partition("=")
        if not eq or not unit.strip():
            raise UsageError(f"--unit must be NAME=UNIT, got {it!r}")
        if k.strip() not in names and k.strip() not in labels:
            raise UsageError(f"--unit: unknown name {k.strip()!r}; units go to states, inputs, "
                             f"constants and outputs: {', '.join(names)}")
        units[k.strip()] = unit.strip()
    kinds = {"cs": "Co-Simulation", "me": "Model Exchange",
             "both": "Model Exchange and Co-Simulation"}
    with progress.stage(f"export the FMU (FMI {a.fmi}, {kinds[a.kind]})"):
        path = export_fmu(m, a.output, fmi_version=a.fmi, kind=a.kind, real=a.real,
                          start=start, units=units, cs_method=a.cs_method,
                          binary=not a.no_binary)
    print(f"wrote {path} (FMI {a.fmi}, {kinds[a.kind]}"
          + (", sources only)" if a.no_binary else ", sources and a binary for this platform)"))
    return 0


def cmd_report(a, progress):
    import json
    from ..toolchain.footprint import format_table, report_many
    if a.stack_limit < 0:
        raise UsageError(f"--stack-limit must be a number of bytes >= 0 (0: no bound), "
                         f"got {a.stack_limit}")
    m = load_model(a.file, progress)
    reals = ["float", "double"] if a.real == "both" else [a.real]
    with progress.stage("build and measure the embedded library"):
        reps = report_many([(m, r) for r in reals], target=a.target, root=a.build_dir,
                           stack_limit=a.stack_limit)
    text = format_table(reps)
    if a.json:
        for rep in reps:
            rep.pop("table", None)
        Path(a.json).write_text(json.dumps(reps, indent=2) + "\n")
    if a.output:
        Path(a.output).write_text(text)
        print(f"wrote {a.output}")
    else:
        print(text, end="")
    return 0


# ------------------------------------------------------------------ parser
class _Parser(argparse.ArgumentParser):
    """Usage errors as one line and exit code 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: {message}\n")


def _sub(sub, name, help_, example, common):
    return sub.add_parser(name, help=help_, description=help_ + ".",
                          epilog="example:\n  " + example,
                          formatter_class=argparse.RawDescriptionHelpFormatter,
                          parents=[common])


def _add_real(p, default="double", both=False):
    choices = ["double", "float"] + (["both"] if both else [])
    p.add_argument("--real", default=default, choices=choices,
                   help=f"scalar type of the generated code (default {default})")


def _common(defaults):
    """--quiet/--verbose/--debug, accepted before and after the subcommand
    (the subcommand's copies must not reset what was given before it)."""
    c = argparse.ArgumentParser(add_help=False)
    d = {} if defaults else {"default": argparse.SUPPRESS}
    c.add_argument("--quiet", "-q", action="store_true", help="no progress display", **d)
    c.add_argument("--verbose", "-v", action="store_true",
                   help="print every stage with its time", **d)
    c.add_argument("--debug", action="store_true", help="show Python tracebacks", **d)
    return c


def build_parser():
    common = _common(defaults=False)
    ap = _Parser(prog="eomgen", formatter_class=argparse.RawDescriptionHelpFormatter,
                 description="Generate verified C simulators from sympy.physics.mechanics "
                             "models.", epilog=EXAMPLES, parents=[_common(defaults=True)])
    ap.add_argument("--version", action="version", version=f"eomgen {__version__}")
    sub = ap.add_subparsers(dest="cmd", required=True, parser_class=_Parser,
                            metavar="{generate,build,simulate,ensemble,linearize,verify,report,fmu,"
                                    "cache}")

    g = _sub(sub, "generate", "write the model's C (or C++/Eigen) sources and a CMake project",
             "eomgen generate examples/seed_pendulum.py -o out/pend --real float", common)
    g.add_argument("file", help="model file (FILE.py or FILE.py:function)")
    g.add_argument("-o", "--output", required=True, help="output folder")
    g.add_argument("--backend", default="c", choices=backend_names("project"))
    _add_real(g)
    g.add_argument("--name", help="C prefix (default: the model's name)")
    g.set_defaults(fn=cmd_generate)

    b = _sub(sub, "build", "generate and build the standalone simulator with CMake; "
             "prints the binary's path",
             "eomgen build examples/seed_pendulum.py:lagrange_model -o out/pl", common)
    b.add_argument("file", help="model file (FILE.py or FILE.py:function)")
    b.add_argument("-o", "--output", required=True, help="output folder (build in OUTPUT/build)")
    b.add_argument("--backend", default="c", choices=backend_names("project"))
    _add_real(b)
    b.add_argument("--stack-limit", type=int, default=None, metavar="BYTES",
                   help="fail the library build on a function frame above BYTES "
                        "(-Wstack-usage, GCC; the embedded profile's bound, "
                        f"{abi.STACK_LIMIT} by default when cross-compiling); default: no "
                        "bound on the host")
    b.set_defaults(fn=cmd_build)

    s = _sub(sub, "simulate", "simulate the compiled model; write CSV and/or a plot (states, "
             "constraint residuals, energy error)",
             "eomgen simulate examples/seed_pendulum.py --t-end 5 --x0 q2=0.5 --plot run.png",
             common)
    s.add_argument("file", help="model file (FILE.py or FILE.py:function)")
    s.add_argument("--t-end", type=float, required=True, help="end time [s]")
    s.add_argument("--dt", type=float, default=0.01,
                   help="RK4 step, or the output interval of dopri5 and rodas4 (default 0.01)")
    s.add_argument("--method", default="rk4", choices=[*abi.METHODS, *abi.METHOD_ALIASES],
                   help="rk4 (default), dopri5 or rodas4 (alias rodas: implicit, for stiff "
                        "models)")
    s.add_argument("--rtol", type=float, default=1e-8,
                   help="dopri5/rodas4 relative tolerance (default 1e-8)")
    s.add_argument("--atol", type=float, default=1e-10,
                   help="dopri5/rodas4 absolute tolerance (default 1e-10)")
    s.add_argument("--x0", action="append", metavar="NAME=VALUE",
                   help="initial state entry (repeat); dependent entries are solved")
    s.add_argument("--param", action="append", metavar="NAME=VALUE", help="constant value")
    s.add_argument("--input", action="append", metavar="NAME=VALUE",
                   help="constant input value")
    s.add_argument("--input-csv", metavar="FILE",
                   help="inputs from a table: a header 't,<input names>' then rows; held "
                        "(--hold zoh, default) or interpolated (--hold linear) inside C")
    s.add_argument("--hold", default="zoh", choices=list(abi.HOLDS),
                   help="the input table between rows")
    s.add_argument("--event", action="append", metavar="NAME[=LEVEL]:DIR[:terminal]",
                   help="log the crossings of LEVEL (default 0) by a state or an output NAME; "
                        "DIR +1 (or 1, up), -1 (down) or 0 (both); terminal: the first "
                        "crossing ends the run, its state the last row (repeat)")
    s.add_argument("--events-csv", metavar="FILE",
                   help="write the events as CSV 'event,t,<states>' (default: one line "
                        "'event NAME t=T <state>' per event on stderr)")
    s.add_argument("--csv", help="write the trajectory (t, states, lam, residuals, energy, "
                        "reaction forces, inputs when they vary)")
    s.add_argument("--plot", help="write a PNG plot")
    _add_real(s)
    s.set_defaults(fn=cmd_simulate, backend="c")

    li = _sub(sub, "linearize", "print A and B (labelled) and the eigenvalues of A at a state",
              "eomgen linearize examples/seed_pendulum.py --at q1=-1", common)
    li.add_argument("file", help="model file (FILE.py or FILE.py:function)")
    li.add_argument("--at", action="append", metavar="NAME=VALUE",
                    help="operating-point entry (repeat); dependent entries are solved")
    li.add_argument("--param", action="append", metavar="NAME=VALUE", help="constant value")
    li.add_argument("--input", action="append", metavar="NAME=VALUE", help="input value")
    li.add_argument("--dt", type=float, metavar="TS",
                    help="also print the zero-order-hold discretization Ad, Bd over TS")
    _add_real(li)
    li.set_defaults(fn=cmd_linearize, backend="c")

    v = _sub(sub, "verify", "check every compiled function against sympy's own evaluation "
             "of the model at random states; exit 1 on a mismatch",
             "eomgen verify examples/seed_pendulum.py --samples 50 --sources out/pend", common)
    v.add_argument("file", help="model file (FILE.py or FILE.py:function)")
    v.add_argument("--samples", type=int, default=20, help="random states (default 20)")
    v.add_argument("--backend", default="c", choices=[*backend_names("loadable"), "both"])
    v.add_argument("--sources", help="check the sources in this generated folder instead")
    v.add_argument("--tol", type=float, help="relative tolerance (default 1e-9; float 2e-4)")
    v.add_argument("--seed", type=int, default=0, help="random seed")
    _add_real(v)
    v.set_defaults(fn=cmd_verify)

    rp = _sub(sub, "report", "flash and worst-case stack of the embedded library",
              "eomgen report examples/seed_pendulum.py --target cortex-m4f -o footprint.txt",
              common)
    rp.add_argument("file", help="model file (FILE.py or FILE.py:function)")
    _add_real(rp, default="both", both=True)
    rp.add_argument("--target", default="cortex-m4f", choices=["cortex-m4f", "host"])
    rp.add_argument("--stack-limit", type=int, default=abi.STACK_LIMIT, metavar="BYTES",
                    help="-Wstack-usage bound on every function frame (default "
                         f"{abi.STACK_LIMIT}; 0: no bound)")
    rp.add_argument("--build-dir", help="keep the build here (default: a temporary directory)")
    rp.add_argument("-o", "--output", help="write the table to this file (footprint.txt)")
    rp.add_argument("--json", metavar="FILE", help="also write the reports as JSON")
    rp.set_defaults(fn=cmd_report)

    fm = _sub(sub, "fmu", "export the model as an FMU (FMI 2.0 or 3.0, Model Exchange and/or "
              "Co-Simulation) for Simulink, Dymola, OpenModelica, FMPy...; needs "
              "pip install eomgen[fmu]",
              "eomgen fmu examples/seed_pendulum.py -o pend.fmu --fmi 3.0 --start q2=0.6 "
              "--start q1=0.8", common)
    fm.add_argument("file", help="model file (FILE.py or FILE.py:function)")
    fm.add_argument("-o", "--output", required=True, help="the FMU file (NAME.fmu)")
    fm.add_argument("--fmi", default="2.0", choices=["2.0", "3.0"],
                    help="FMI version (default 2.0)")
    fm.add_argument("--kind", default="both", choices=["cs", "me", "both"],
                    help="Co-Simulation, Model Exchange or both (default)")
    fm.add_argument("--start", action="append", metavar="NAME=VALUE",
                    help="start value of a state (repeat); the dependent coordinates and "
                         "speeds are solved from the independent ones, the values given are "
                         "the guess")
    fm.add_argument("--unit", action="append", metavar="NAME=UNIT",
                    help="unit of a state, input, constant or output (repeat), Modelica "
                         "syntax: m, rad/s, N.m")
    fm.add_argument("--cs-method", default="dopri5", choices=list(abi.ADAPTIVE_METHODS),
                    help="the Co-Simulation integrator (default dopri5; rodas4 for stiff "
                         "models)")
    fm.add_argument("--no-binary", action="store_true",
                    help="sources only (compile with the importer, e.g. FMPy)")
    _add_real(fm)
    fm.set_defaults(fn=cmd_fmu)

    en = _sub(sub, "ensemble", "many runs of the compiled model over sampled parameters and "
              "initial states, in C on every core or on a Dask cluster; write the reduced "
              "results (.npz or .parquet)",
              "eomgen ensemble examples/seed_pendulum.py --samples 100000 --param "
              "L=uniform:0.8:1.2 --x0 q2=normal:0:0.05 --t-end 5 --reduce final -o res.npz",
              common)
    en.add_argument("file", help="model file (FILE.py or FILE.py:function)")
    en.add_argument("--samples", type=int, required=True, help="number of runs")
    en.add_argument("--param", action="append", metavar="NAME=SPEC",
                    help="a constant: a number, uniform:LOW:HIGH or normal:MEAN:STD (repeat)")
    en.add_argument("--x0", action="append", metavar="NAME=SPEC",
                    help="an initial-state entry, as --param (others 0; dependent entries "
                         "solved unless --no-consistent)")
    en.add_argument("--input", action="append", metavar="NAME=SPEC",
                    help="a constant input, as --param")
    en.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    en.add_argument("--t-end", type=float, required=True, help="end time [s]")
    en.add_argument("--dt", type=float, default=1e-3, help="RK4 step or output interval "
                    "(default 1e-3)")
    en.add_argument("--method", default="rk4", choices=[*abi.METHODS, *abi.METHOD_ALIASES])
    en.add_argument("--rtol", type=float, default=1e-8)
    en.add_argument("--atol", type=float, default=1e-10)
    en.add_argument("--reduce", action="append",
                    metavar="final|min:NAMES|max:NAMES|mean:NAMES|at:TIMES[:NAMES]",
                    help="what to keep of each run (repeat; default final)")
    en.add_argument("--no-consistent", action="store_true",
                    help="take the sampled states as they are")
    en.add_argument("--chunk", type=int, help="runs per C call (default: a few per worker)")
    en.add_argument("--workers", type=int, help="threads (default: every core)")
    en.add_argument("--scheduler", metavar="ADDRESS",
                    help="run the chunks on a Dask cluster (tcp://host:8786)")
    en.add_argument("-o", "--output", required=True, help="results file (.npz or .parquet)")
    _add_real(en)
    en.set_defaults(fn=cmd_ensemble, backend="c")

    ca = _sub(sub, "cache", "show where eomgen's build cache is, its entries and size; "
              "'clear' deletes eomgen's entries from it",
              "eomgen cache clear", common)
    ca.add_argument("action", nargs="?", default="info", choices=["info", "clear"],
                    help="info (default) or clear")
    ca.set_defaults(fn=cmd_cache)
    return ap


def main(argv=None):
    """Run the command line; returns the exit status. Every eomgen error,
    a refused or too large run (ValueError, MemoryError) and a file error is
    one line on stderr, never a traceback (--debug shows it). A closed pipe
    (``eomgen ... | head``) ends the run quietly with 141 (128 + SIGPIPE,
    what a program killed by the signal reports), as Python's documentation
    recommends: stdout is pointed at devnull so that the interpreter's own
    flush at exit does not fail again."""
    try:
        rc = _main(argv)
        sys.stdout.flush()    # a closed pipe shows here at the latest
        return rc
    except BrokenPipeError:
        _stdout_to_devnull()
        return 141


def _stdout_to_devnull():
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def _one_line(cmd, text):
    """eomgen CMD: the first line of text (the rest: --verbose)."""
    first, _, rest = text.partition("\n")
    print(f"eomgen {cmd}: {first}", file=sys.stderr)
    return rest


def _main(argv=None):
    ap = build_parser()
    a = ap.parse_args(argv)
    if getattr(a, "samples", 1) is not None and getattr(a, "samples", 1) < 1:
        print(f"eomgen {a.cmd}: --samples must be at least 1", file=sys.stderr)
        return 2
    progress = Progress(quiet=a.quiet, verbose=a.verbose)
    try:
        rc = a.fn(a, progress)
        progress.summary()
        return rc
    except BrokenPipeError:
        raise                 # main(): quiet
    except UsageError as e:
        if a.debug:
            raise
        print(f"eomgen {a.cmd}: {e}", file=sys.stderr)
        return 2
    except (EomgenError, OSError, ValueError) as e:
        # ValueError: a refused argument or run (gen.InputError is one)
        if a.debug:
            raise
        text = str(e) or type(e).__name__
        rest = _one_line(a.cmd, text)
        if rest and (a.verbose or "compiler log" in text or "CMake" in text.partition("\n")[0]):
            print(rest, file=sys.stderr)
        return 1
    except MemoryError as e:
        if a.debug:
            raise
        detail = f" ({e})" if str(e) else ""
        way_out = ("the run is too large for this machine; keep fewer rows (a larger --dt, "
                   "a shorter --t-end)" if a.cmd in ("simulate", "ensemble")
                   else "the job is too large for this machine")
        _one_line(a.cmd, f"out of memory{detail}: {way_out}")
        return 1
    except KeyboardInterrupt:
        print("eomgen: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
