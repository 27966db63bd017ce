"""eomgen command line: generate, build, simulate, linearize a model file.

A model file is a Python file defining model() -> gen.Model, or name
another function as FILE.py:function.
"""
from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import time
from pathlib import Path

from . import __version__
from .errors import EomgenError

EXAMPLES = """examples:
  eomgen generate examples/seed_pendulum.py -o out/pend
  eomgen build examples/seed_pendulum.py:lagrange_model -o out/pend_lagrange
  eomgen linearize examples/seed_pendulum.py --at q1=1 --at q2=0
  eomgen simulate examples/seed_pendulum.py --t-end 5 --x0 q2=0.5 --x0 q1=0.8 --csv run.csv
"""


class UsageError(Exception):
    pass


def load_model(spec: str):
    path, _, func = spec.partition(":")
    func = func or "model"
    p = Path(path)
    if not p.is_file():
        raise UsageError(f"model file not found: {path}")
    sys.path.insert(0, str(p.resolve().parent))
    modname = f"_eomgen_modelfile_{abs(hash(str(p.resolve())))}"
    spec_ = importlib.util.spec_from_file_location(modname, str(p))
    mod = importlib.util.module_from_spec(spec_)
    spec_.loader.exec_module(mod)
    fn = getattr(mod, func, None)
    if fn is None or not callable(fn):
        raise UsageError(f"{path} defines no function {func}() returning a gen.Model")
    return fn()


def _pairs(items, names, what):
    out = {}
    for it in items or []:
        if "=" not in it:
            raise UsageError(f"{what} must be NAME=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        if k not in names:
            raise UsageError(f"unknown {what} name {k!r}; known: {', '.join(names)}")
        try:
            out[k] = float(v)
        except ValueError:
            raise UsageError(f"{what} {k}: {v!r} is not a number") from None
    return out


def _compiled_state(file, real, state_items, param_items):
    """Compile the model file; the consistent state and constants from
    NAME=VALUE lists."""
    import numpy as np
    from .build import compile as gcompile
    sim = gcompile(load_model(file), real=real)
    x = np.zeros(sim.nx)
    for k, v in _pairs(state_items, sim.state_names, "state").items():
        x[sim.state_names.index(k)] = v
    p = sim.constants.copy()
    for k, v in _pairs(param_items, sim.constant_names, "constant").items():
        p[sim.constant_names.index(k)] = v
    if sim.mc or sim.mv:
        x = sim.consistent_state(x, p=p)
    return sim, x, p


def cmd_generate(a):
    from .render import generate
    m = load_model(a.file)
    if a.name:
        m.name = a.name
    t0 = time.perf_counter()
    paths = generate(m, a.output, backend=a.backend, real=a.real)
    print(f"wrote {len(paths)} files to {a.output} in {time.perf_counter() - t0:.2f} s")
    return 0


def cmd_build(a):
    from .render import generate
    m = load_model(a.file)
    generate(m, a.output, real=a.real)
    bld = Path(a.output) / "build"
    r = subprocess.run(["cmake", "-S", a.output, "-B", str(bld), "-DCMAKE_BUILD_TYPE=Release"],
                       capture_output=True, text=True)
    if r.returncode == 0:
        r = subprocess.run(["cmake", "--build", str(bld)], capture_output=True, text=True)
    if r.returncode != 0:
        print(r.stdout + r.stderr, file=sys.stderr)
        raise EomgenError("the CMake build failed")
    print(bld / f"{m.name}_sim")
    return 0


def cmd_linearize(a):
    import numpy as np
    sim, x, p = _compiled_state(a.file, a.real, a.at, a.param)
    A, B = sim.linearize(x, p=p)
    names = sim.independent_state_names
    w = max(len(n) for n in names) + 2
    print("operating point:", ", ".join(f"{n}={v:.12g}" for n, v in zip(sim.state_names, x)))
    print("A =")
    print(" " * w + "".join(f"{n:>16}" for n in names))
    for n, row in zip(names, A):
        print(f"{n:<{w}}" + "".join(f"{v:16.9g}" for v in row))
    print("B =" + (" (no inputs)" if sim.nr == 0 else ""))
    if sim.nr:
        print(" " * w + "".join(f"{n:>16}" for n in sim.input_names))
        for n, row in zip(names, B):
            print(f"{n:<{w}}" + "".join(f"{v:16.9g}" for v in row))
    print("eigenvalues of A:", " ".join(f"{complex(e):.9g}" for e in np.linalg.eigvals(A)))
    return 0


def cmd_simulate(a):
    sim, x, p = _compiled_state(a.file, a.real, a.x0, a.param)
    t, X = sim.simulate(x, a.t_end, a.dt, method=a.method, p=p)
    out = open(a.csv, "w") if a.csv else sys.stdout
    try:
        out.write(",".join(["t"] + sim.state_names) + "\n")
        for ti, xi in zip(t, X):
            out.write(",".join(f"{v:.17g}" for v in [ti, *xi]) + "\n")
    finally:
        if a.csv:
            out.close()
    if a.csv:
        print(f"wrote {len(t)} rows to {a.csv}")
    return 0


def build_parser():
    ap = argparse.ArgumentParser(
        prog="eomgen", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Generate verified C simulators from sympy.physics.mechanics models.",
        epilog=EXAMPLES)
    ap.add_argument("--version", action="version", version=f"eomgen {__version__}")
    ap.add_argument("--debug", action="store_true", help="show Python tracebacks")
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("generate", help="write C sources and a CMake project")
    g.add_argument("file")
    g.add_argument("-o", "--output", required=True)
    g.add_argument("--backend", default="c", choices=["c"])
    g.add_argument("--real", default="double", choices=["double"])
    g.add_argument("--name")
    g.set_defaults(fn=cmd_generate)
    b = sub.add_parser("build", help="generate and build the standalone binary with CMake")
    b.add_argument("file")
    b.add_argument("-o", "--output", required=True)
    b.add_argument("--real", default="double", choices=["double"])
    b.set_defaults(fn=cmd_build)
    li = sub.add_parser("linearize", help="print A and B at a state")
    li.add_argument("file")
    li.add_argument("--at", action="append", metavar="NAME=VALUE")
    li.add_argument("--param", action="append", metavar="NAME=VALUE")
    li.add_argument("--real", default="double", choices=["double"])
    li.set_defaults(fn=cmd_linearize)
    s = sub.add_parser("simulate", help="simulate and write CSV")
    s.add_argument("file")
    s.add_argument("--t-end", type=float, required=True)
    s.add_argument("--dt", type=float, default=0.01)
    s.add_argument("--method", default="rk4", choices=["rk4", "dopri5"])
    s.add_argument("--x0", action="append", metavar="NAME=VALUE")
    s.add_argument("--param", action="append", metavar="NAME=VALUE")
    s.add_argument("--csv")
    s.add_argument("--real", default="double", choices=["double"])
    s.set_defaults(fn=cmd_simulate)
    return ap


def main(argv=None):
    ap = build_parser()
    a = ap.parse_args(argv)
    try:
        return a.fn(a)
    except UsageError as e:
        print(f"eomgen: {e}", file=sys.stderr)
        return 2
    except EomgenError as e:
        if a.debug:
            raise
        print(f"eomgen: {e}", file=sys.stderr)
        return 1
