"""The eomgen program: its grammar and main().

One builder per subcommand (``_generate``, ``_build``, ``_simulate``, ...)
adds its arguments; the run flags of ``simulate`` and ``ensemble``
(``--method``, ``--rtol``, ...) are made from gen/sim/options.py's OPTIONS,
the one description of the run options (their names, defaults from the
interface description, and help text), by :func:`add_run_flags`; the
commands themselves are gen/cli/commands.py's.
"""
from __future__ import annotations

import argparse
import inspect
import os
import re
import sys

from .._version import __version__
from ..codegen import abi
from ..codegen.backends import backend_names
from ..core.errors import EomgenError
from ..export.fmu import export_fmu
from ..sim.options import OPTIONS
from .commands import (UsageError, cmd_build, cmd_cache, cmd_ensemble, cmd_fmu, cmd_generate,
                       cmd_linearize, cmd_report, cmd_simulate, cmd_verify)
from .output import Progress

__all__ = ["build_parser", "main", "add_run_flags", "run_flag"]

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


# ------------------------------------------------------------- run flags
_CHOICES = {"method": [*abi.METHODS, *abi.METHOD_ALIASES], "input_hold": list(abi.HOLDS)}
_TYPES = {"float": float, "int": int}


def run_flag(option):
    """The command line's flag of a run option (``--rtol``, ``--hold``)."""
    return option.flag or "--" + option.name.replace("_", "-")


def _plain(text):
    """reST of a docstring as plain text for --help."""
    text = re.sub(r":\w+:`([^`]*)`", r"\1", text).replace("``", "")
    return text.replace("%", "%%")


def add_run_flags(p, command):
    """The run flags of a subcommand: every option of gen.sim.options.OPTIONS
    that has one for it, its name, default and help from there."""
    g = p.add_argument_group("run options (those of gen.RunOptions)")
    for o in OPTIONS:
        if command not in o.cli:
            continue
        flag, text = run_flag(o), _plain(o.doc).rstrip(".")
        if o.type == "bool":
            on = bool(o.default)
            g.add_argument(flag, dest=o.name, action="store_false" if on else "store_true",
                           help=f"{text} (default {'on' if on else 'off'}; {flag} turns it "
                                f"{'off' if on else 'on'}).")
            continue
        shown = "none" if o.default is None else o.default
        g.add_argument(flag, dest=o.name, default=o.default, choices=_CHOICES.get(o.name),
                       type=_TYPES.get(o.type, str), help=f"{text} (default {shown}).")

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


# ------------------------------------------------------------ subcommands
_FILE = "model file (FILE.py or FILE.py:function)"


def _generate(sub, common):
    g = _sub(sub, "generate", "write the model's C (or C++/Eigen) sources and a CMake project",
             "eomgen generate examples/seed_pendulum.py -o out/pend --real float", common)
    g.add_argument("file", help=_FILE)
    g.add_argument("-o", "--output", required=True, help="output folder")
    g.add_argument("--backend", default="c", choices=backend_names("project"))
    _add_real(g)
    g.add_argument("--name", help="C prefix (default: the model's name)")
    g.set_defaults(fn=cmd_generate)


def _build(sub, common):
    b = _sub(sub, "build", "generate and build the standalone simulator with CMake; "
             "prints the binary's path",
             "eomgen build examples/seed_pendulum.py:lagrange_model -o out/pl", common)
    b.add_argument("file", help=_FILE)
    b.add_argument("-o", "--output", required=True, help="output folder (build in OUTPUT/build)")
    b.add_argument("--backend", default="c", choices=backend_names("project"))
    _add_real(b)
    b.add_argument("--stack-limit", type=int, default=None, metavar="BYTES",
                   help="fail the library build on a function frame above BYTES "
                        "(-Wstack-usage, GCC; the embedded profile's bound, "
                        f"{abi.STACK_LIMIT} by default when cross-compiling); default: no "
                        "bound on the host")
    b.set_defaults(fn=cmd_build)


def _simulate(sub, common):
    s = _sub(sub, "simulate", "simulate the compiled model; write CSV and/or a plot (states, "
             "constraint residuals, energy error)",
             "eomgen simulate examples/seed_pendulum.py --t-end 5 --x0 q2=0.5 --plot run.png",
             common)
    s.add_argument("file", help=_FILE)
    s.add_argument("--t-end", type=float, required=True, help="end time [s]")
    s.add_argument("--dt", type=float, default=0.01,
                   help="RK4 step, or the output interval of dopri5 and rodas4 (default 0.01)")
    s.add_argument("--x0", action="append", metavar="NAME=VALUE",
                   help="initial state entry (repeat); dependent entries are solved")
    s.add_argument("--param", action="append", metavar="NAME=VALUE", help="constant value")
    s.add_argument("--input", action="append", metavar="NAME=VALUE",
                   help="constant input value")
    s.add_argument("--input-csv", metavar="FILE",
                   help="inputs from a table: a header 't,<input names>' then rows; held "
                        "or interpolated inside C (--hold)")
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
    add_run_flags(s, "simulate")
    s.set_defaults(fn=cmd_simulate, backend="c")


def _linearize(sub, common):
    li = _sub(sub, "linearize", "print A and B (labelled) and the eigenvalues of A at a state",
              "eomgen linearize examples/seed_pendulum.py --at q1=-1", common)
    li.add_argument("file", help=_FILE)
    li.add_argument("--at", action="append", metavar="NAME=VALUE",
                    help="operating-point entry (repeat); dependent entries are solved")
    li.add_argument("--param", action="append", metavar="NAME=VALUE", help="constant value")
    li.add_argument("--input", action="append", metavar="NAME=VALUE", help="input value")
    li.add_argument("--dt", type=float, metavar="TS",
                    help="also print the zero-order-hold discretization Ad, Bd over TS")
    _add_real(li)
    li.set_defaults(fn=cmd_linearize, backend="c")


def _verify(sub, common):
    v = _sub(sub, "verify", "check every compiled function against sympy's own evaluation "
             "of the model at random states; exit 1 on a mismatch",
             "eomgen verify examples/seed_pendulum.py --samples 50 --sources out/pend", common)
    v.add_argument("file", help=_FILE)
    v.add_argument("--samples", type=int, default=20, help="random states (default 20)")
    v.add_argument("--backend", default="c", choices=[*backend_names("loadable"), "both"])
    v.add_argument("--sources", help="check the sources in this generated folder instead")
    v.add_argument("--tol", type=float, help="relative tolerance (default 1e-9; float 2e-4)")
    v.add_argument("--seed", type=int, default=0, help="random seed")
    _add_real(v)
    v.set_defaults(fn=cmd_verify)


def _report(sub, common):
    rp = _sub(sub, "report", "flash and worst-case stack of the embedded library",
              "eomgen report examples/seed_pendulum.py --target cortex-m4f -o footprint.txt",
              common)
    rp.add_argument("file", help=_FILE)
    _add_real(rp, default="both", both=True)
    rp.add_argument("--target", default="cortex-m4f", choices=["cortex-m4f", "host"])
    rp.add_argument("--stack-limit", type=int, default=abi.STACK_LIMIT, metavar="BYTES",
                    help="-Wstack-usage bound on every function frame (default "
                         f"{abi.STACK_LIMIT}; 0: no bound)")
    rp.add_argument("--build-dir", help="keep the build here (default: a temporary directory)")
    rp.add_argument("-o", "--output", help="write the table to this file (footprint.txt)")
    rp.add_argument("--json", metavar="FILE", help="also write the reports as JSON")
    rp.set_defaults(fn=cmd_report)


def _fmu(sub, common):
    fm = _sub(sub, "fmu", "export the model as an FMU (FMI 2.0 or 3.0, Model Exchange and/or "
              "Co-Simulation) for Simulink, Dymola, OpenModelica, FMPy...; needs "
              "pip install eomgen[fmu]",
              "eomgen fmu examples/seed_pendulum.py -o pend.fmu --fmi 3.0 --start q2=0.6 "
              "--start q1=0.8", common)
    fm.add_argument("file", help=_FILE)
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
    cs_default = inspect.signature(export_fmu).parameters["cs_method"].default
    fm.add_argument("--cs-method", default=cs_default, choices=list(abi.ADAPTIVE_METHODS),
                    help=f"the Co-Simulation integrator (default {cs_default}; rodas4 for "
                         "stiff models)")
    fm.add_argument("--no-binary", action="store_true",
                    help="sources only (compile with the importer, e.g. FMPy)")
    _add_real(fm)
    fm.set_defaults(fn=cmd_fmu)


def _ensemble(sub, common):
    en = _sub(sub, "ensemble", "many runs of the compiled model over sampled parameters and "
              "initial states, in C on every core or on a Dask cluster; write the reduced "
              "results (.npz or .parquet)",
              "eomgen ensemble examples/seed_pendulum.py --samples 100000 --param "
              "L=uniform:0.8:1.2 --x0 q2=normal:0:0.05 --t-end 5 --reduce final -o res.npz",
              common)
    en.add_argument("file", help=_FILE)
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
    add_run_flags(en, "ensemble")
    en.set_defaults(fn=cmd_ensemble, backend="c")


def _cache(sub, common):
    ca = _sub(sub, "cache", "show where eomgen's build cache is, its entries and size; "
              "'clear' deletes eomgen's entries from it",
              "eomgen cache clear", common)
    ca.add_argument("action", nargs="?", default="info", choices=["info", "clear"],
                    help="info (default) or clear")
    ca.set_defaults(fn=cmd_cache)


# the subcommands, in the order they are added (their order in --help's list)
SUBCOMMANDS = {"generate": _generate, "build": _build, "simulate": _simulate,
               "linearize": _linearize, "verify": _verify, "report": _report, "fmu": _fmu,
               "ensemble": _ensemble, "cache": _cache}
_METAVAR = "{generate,build,simulate,ensemble,linearize,verify,report,fmu,cache}"


def build_parser():
    """The command line's parser: the options of every subcommand, then one
    subparser per subcommand (SUBCOMMANDS)."""
    common = _common(defaults=False)
    ap = _Parser(prog="eomgen", formatter_class=argparse.RawDescriptionHelpFormatter,
                 description="Generate verified C simulators from sympy.physics.mechanics "
                             "models.", epilog=EXAMPLES, parents=[_common(defaults=True)])
    ap.add_argument("--version", action="version", version=f"eomgen {__version__}")
    sub = ap.add_subparsers(dest="cmd", required=True, parser_class=_Parser, metavar=_METAVAR)
    for add in SUBCOMMANDS.values():
        add(sub, common)
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
