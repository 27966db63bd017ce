"""The commands of the eomgen command line: generate, build, simulate,
ensemble, linearize, verify, report, fmu and cache on a model file (their
arguments: gen/cli/program.py).

A model file is a Python file defining ``model()`` that returns a
``gen.Model``; ``FILE.py:function`` names another function. Exit codes:
0 success, 1 a failure (a model the generator refuses, a failed compile or
solve, a verification mismatch), 2 a usage error. No Python traceback
unless ``--debug``.
"""
from __future__ import annotations

import contextlib
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

from ..codegen.backends import backend_names, get_backend
from ..core.errors import EomgenError, InputError, MissingDependencyError
from ..core.optional import require
from ..sim.options import OPTIONS, RunOptions
from .output import (Progress, plot_simulation, print_csv, print_events, print_linearization,
                     write_csv, write_events_csv)


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


def _run_options(a, command):
    """The gen.RunOptions of the run flags of a command (gen/cli/program.py
    makes them from the same OPTIONS); a bad value is a usage error naming
    its flag."""
    given = {o.name: getattr(a, o.name) for o in OPTIONS if command in o.cli}
    try:
        return RunOptions(**given)
    except InputError as e:
        o = next((o for o in OPTIONS if o.name == e.argument), None)
        flag = (o.flag or "--" + o.name.replace("_", "-")) if o else e.argument
        raise UsageError(f"{flag}: {e}") from None


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
    opts = _run_options(a, "simulate")
    kw = dict(events=events, terminal=terminal) if events else {}
    with progress.stage(f"simulate {a.t_end:g} s ({opts.method})"):
        sol = sim.simulate(x, a.t_end, a.dt, r=r, p=p, options=opts, **kw)
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
            except MissingDependencyError as e:
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
    opts = _run_options(a, "ensemble")
    client = None
    if a.scheduler:
        client = _optional("distributed", "--scheduler").Client(a.scheduler)
    out = Path(a.output)
    if out.suffix not in (".npz", ".parquet"):
        raise UsageError(f"-o {a.output}: write .npz or .parquet")
    n = a.samples
    with progress.stage(f"{n} runs of {a.t_end:g} s ({opts.method})"):
        res = sim.ensemble(x0 or np.zeros((n, sim.nx)), a.t_end, a.dt, p=p or None, r=r or None,
                           reduce=reduce, client=client, chunk=a.chunk, workers=a.workers,
                           options=opts,
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
            pd = _optional("pandas", "-o .parquet")
            _optional("pyarrow", "-o .parquet")
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


def _optional(name, feature):
    """An optional dependency of a command; missing, a usage error naming
    the extra that installs it (gen.core.optional)."""
    try:
        return require(name, feature)
    except MissingDependencyError as e:
        raise UsageError(str(e)) from None


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
