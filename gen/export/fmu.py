"""FMU export: a model as a Functional Mock-up Unit (FMI 2.0 or 3.0, Model
Exchange and/or Co-Simulation) that any FMI importer runs.

    gen.export_fmu(model, "pendulum.fmu", fmi_version="2.0", kind="both",
                   start={"q2": 0.6, "q1": 0.8}, units={"q1": "m"})

The FMU is a zip holding

- ``modelDescription.xml``: the variables (time, the state with its
  derivatives, the inputs, the constants as parameters, the outputs), the
  ModelStructure with the dependencies from the model's structure
  (gen/plan/dependencies.py), units and descriptions;
- ``sources/``: the model's C (its .c/.h, the derivative kernels and the
  runtime), the hand-written FMI glue (``csrc/fmu``) and ``gen_fmu_model.h``,
  the one generated file of the glue (sizes, value references, start
  values); FMI 3.0 adds ``sources/buildDescription.xml``, FMI 2.0 lists the
  files in ``<SourceFiles>``. The FMI headers are the importer's, as the
  standard has it;
- ``binaries/<platform>/<model>.so``: the same sources compiled for this
  machine with the system C compiler and FMPy's copy of the FMI headers.

Design (see README, "FMU export"): Model Exchange exposes the independent
state [q_ind, u_ind] as continuous states and solves the dependent
coordinates and speeds from them at every evaluation, so the importer
integrates an ODE without invariants; Co-Simulation integrates the full
state with eomgen's own integrator (DOPRI5 or RODAS4 with projection) at the
importer's tolerance.

Python decides everything here (variables, value references, dependencies,
start values, which outputs); the templates in ``templates/fmu`` only lay
it out, and the algorithms live in ``csrc/fmu``.
"""
from __future__ import annotations

import hashlib
import os
import platform
import re
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from .._version import __version__
from ..codegen.abi import ADAPTIVE_METHODS
from ..codegen.backends import get_backend
from ..toolchain.build import build
from ..plan.dependencies import dependencies
from ..core.errors import BuildError, MissingDependencyError, ModelError
from ..core.optional import require
from ..plan.ir import plan as make_plan
from ..intake.model import require_model
from ..codegen.render import Rendered, mode_for_umask, render
from ..codegen.templating import template_env
from ..core.resources import csrc_dir

__all__ = ["export_fmu", "describe", "fmi_headers", "platform_folder", "FmuDescription",
           "Variable", "MissingDependencyError", "FMI_VERSIONS", "KINDS", "CS_METHODS"]

FMI_VERSIONS = ("2.0", "3.0")
KINDS = ("cs", "me", "both")
CS_METHODS = ADAPTIVE_METHODS      # gen/codegen/abi.py

# the FMU as a backend (gen/codegen/backends/ FmuBackend): the model's sources
# (the C backend's, without the plugin table), the hand-written glue
# (csrc/fmu, FMU.glue) and the FMU's own templates (FMU.fmu_templates), built
# through gen.build into the cache like every other library
FMU = get_backend("fmu")
# the FMI headers the binary is compiled against (the importer's)
HEADERS = {"2.0": ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
           "3.0": ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")}
# zip entries carry this date (reproducible FMUs)
ZIP_DATE = (1980, 1, 1, 0, 0, 0)


# ----------------------------------------------------------- description
@dataclass
class Variable:
    """One scalar variable of the FMU. index is FMI 2.0's (1-based position
    in ModelVariables); derivative is the state's index (FMI 2.0) or value
    reference (FMI 3.0), rendered by the template the version needs."""
    name: str
    vr: int
    causality: str                  # independent, local, input, parameter, output
    variability: str                # continuous, fixed, tunable
    initial: str | None             # exact, approx, calculated or None
    start: str | None               # the start value as XML/C text
    description: str
    unit: str | None = None
    derivative_of: int | None = None    # vr of the state this is the derivative of
    index: int = 0
    derivative_index: int | None = None  # FMI 2.0: index of that state


@dataclass
class Unknown:
    """An entry of the ModelStructure: the variable and the knowns it
    depends on, by value reference (FMI 3.0) and by index (FMI 2.0),
    sorted."""
    vr: int
    dependencies: list
    index: int = 0
    dependency_indices: list = field(default_factory=list)


@dataclass
class FmuDescription:
    """Everything the FMU's files say, decided here and laid out by the
    templates."""
    fmi_version: str
    name: str                       # model name = modelIdentifier
    token: str                      # GUID / instantiationToken
    description: str
    me: bool
    cs: bool
    real: str
    cs_method: str
    variables: list
    outputs: list                   # [Unknown]
    derivatives: list               # [Unknown], in continuous-state order
    initial_unknowns: list          # [Unknown], by value reference
    units: list                     # [(name, [(BaseUnit attribute, value)] or None)]
    sources: list                   # file names in sources/
    ns: int
    nout: dict                      # counts of the output groups y, lam, fc, fv
    independent: list               # full-state index of each continuous state
    dependent: list                 # the others
    x_start: list                   # start values of x (text)
    p_start: list
    tunable: list                   # 1/0 per constant
    state_names: list
    default_tolerance: float = 1e-8
    generation_tool: str = f"eomgen {__version__}"
    by_vr: dict = field(default_factory=dict)
    # hybrid={...}: event indicators and the runtime's scratch (FMI 2.0 ME)
    nh: int = 0
    hwork: int = 1
    hiwork: int = 1


def _fmt(v):
    """A double as XML and C text (shortest round trip, always a C double)."""
    s = repr(float(v))
    if "e" not in s and "." not in s:
        s += ".0"
    return s


def _lookup(key, names, labels):
    if key in names:
        return names.index(key)
    if key in labels:
        return list(labels).index(key)
    return None


def _per_second(unit):
    """The unit of a derivative in Modelica's unit syntax: m -> m/s,
    m/s -> m/s2, rad/s2 -> rad/s3, N.m/rad -> N.m/(rad.s)."""
    if "/" not in unit:
        return f"{unit}/s"
    num, den = unit.rsplit("/", 1)
    m = re.fullmatch(r"s(\d*)", den)
    if m:
        return f"{num}/s{int(m.group(1) or 1) + 1}"
    den = den[1:-1] if den.startswith("(") and den.endswith(")") else den
    return f"{num}/({den}.s)"


# SI symbols of Modelica's unit syntax: {base unit: exponent}, factor to SI
_SI = {
    "m": ({"m": 1}, 1.0), "kg": ({"kg": 1}, 1.0), "g": ({"kg": 1}, 1e-3),
    "s": ({"s": 1}, 1.0), "A": ({"A": 1}, 1.0), "K": ({"K": 1}, 1.0),
    "mol": ({"mol": 1}, 1.0), "cd": ({"cd": 1}, 1.0), "rad": ({"rad": 1}, 1.0),
    "deg": ({"rad": 1}, 0.017453292519943295), "min": ({"s": 1}, 60.0),
    "h": ({"s": 1}, 3600.0), "Hz": ({"s": -1}, 1.0),
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0), "Pa": ({"kg": 1, "m": -1, "s": -2}, 1.0),
    "J": ({"kg": 1, "m": 2, "s": -2}, 1.0), "W": ({"kg": 1, "m": 2, "s": -3}, 1.0),
    "C": ({"A": 1, "s": 1}, 1.0), "V": ({"kg": 1, "m": 2, "s": -3, "A": -1}, 1.0),
}
_PREFIX = {"G": 1e9, "M": 1e6, "k": 1e3, "c": 1e-2, "m": 1e-3, "u": 1e-6, "n": 1e-9}
_BASE_ORDER = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def _base_unit(unit):
    """The SI decomposition of a unit in Modelica's syntax ("N.m/s2",
    "rad/(m.s)", "1/s", "mm"): [(attribute, value)] of an FMI BaseUnit, or
    None for a unit it does not know (then the unit is declared by name)."""
    def factors(text):
        exps, factor = {}, 1.0
        if text == "1":
            return exps, factor
        for part in text.split("."):
            m = re.fullmatch(r"([A-Za-z]+)([+-]?\d+)?", part)
            if not m:
                return None
            sym, power = m.group(1), int(m.group(2) or 1)
            if sym in _SI:
                base, f = _SI[sym]
            elif sym[0] in _PREFIX and sym[1:] in _SI:
                base, f = _SI[sym[1:]]
                f *= _PREFIX[sym[0]]
            else:
                return None
            for k, v in base.items():
                exps[k] = exps.get(k, 0) + v * power
            factor *= f ** power
        return exps, factor

    num, _, den = unit.partition("/")
    if num.startswith("(") and num.endswith(")"):
        num = num[1:-1]
    if den.startswith("(") and den.endswith(")"):
        den = den[1:-1]
    a = factors(num)
    b = factors(den) if den else ({}, 1.0)
    if a is None or b is None or "/" in den:
        return None
    exps = dict(a[0])
    for k, v in b[0].items():
        exps[k] = exps.get(k, 0) - v
    out = [(k, str(exps[k])) for k in _BASE_ORDER if exps.get(k)]
    factor = a[1] / b[1]
    if factor != 1.0:
        out.append(("factor", repr(factor)))
    return out


def _check_unit(name, unit):
    if not isinstance(unit, str) or not unit.strip() or any(c in unit for c in "\r\n\t") \
            or unit != unit.strip():
        raise ModelError(f"the unit of {name} must be a non-empty string without spaces at "
                         f"its ends or line breaks (Modelica syntax such as 'm/s2', 'N.m'), "
                         f"got {unit!r}")
    return unit


def _unique(name, taken):
    while name in taken:
        name += "_"
    taken.add(name)
    return name


def _token(model, parts):
    h = hashlib.sha256()
    for p in [model.fingerprint(), __version__] + [repr(p) for p in parts]:
        h.update(p.encode())
        h.update(b"\0")
    d = h.hexdigest()
    return "{" + f"{d[:8]}-{d[8:12]}-{d[12:16]}-{d[16:20]}-{d[20:32]}" + "}"


def _start_state(model, start):
    """The start state x0: the given entries (C names or sympy labels),
    zero for the others. The dependent entries are the guess from which the
    FMU solves them at initialization (initial="approx")."""
    import numpy as np
    m = model
    x0 = [0.0] * m.nx
    for key, value in (start or {}).items():
        i = _lookup(key, m.state_names, m.state_labels)
        if i is None:
            raise ModelError(f"start: unknown state {key!r}; the states are "
                             f"{', '.join(m.state_names)}")
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ModelError(f"start: the value of {key} must be a number, got {value!r}") \
                from None
        if not np.isfinite(v):
            raise ModelError(f"start: the value of {key} must be finite, got {value!r}")
        x0[i] = v
    return x0


def _check_options(m, fmi_version, kind, real, cs_method):
    """A ModelError naming a bad option (a hybrid model exports as FMI 2.0
    Model Exchange only)."""
    if fmi_version not in FMI_VERSIONS:
        raise ModelError(f"fmi_version must be one of {', '.join(FMI_VERSIONS)}, "
                         f"got {fmi_version!r}")
    if kind not in KINDS:
        raise ModelError(f"kind must be one of {', '.join(KINDS)} (Co-Simulation, Model "
                         f"Exchange or both), got {kind!r}")
    if real not in ("double", "float"):
        raise ModelError(f"real must be 'double' or 'float', got {real!r}")
    if cs_method not in CS_METHODS:
        raise ModelError(f"cs_method must be one of {', '.join(CS_METHODS)}, got {cs_method!r}")
    nh = len(getattr(m, "hybrid", []) or [])
    if nh and (fmi_version != "2.0" or kind != "me"):
        raise ModelError(
            f"model '{m.name}' is hybrid (hybrid={{{', '.join(d.name for d in m.hybrid)}}}): "
            "its impacts and resets export as FMI 2.0 Model Exchange (event indicators and "
            f"the state update at the event): kind='me', fmi_version='2.0' (got "
            f"kind={kind!r}, fmi_version={fmi_version!r})")
    return nh


def _units(m, units):
    """{(group, index): unit} of units, by any name of a state ("x"), input
    ("r"), constant ("p") or output ("y")."""
    unit_of = {}
    groups = [("x", m.state_names, m.state_labels), ("r", m.input_names, m.input_labels),
              ("p", m.constant_names, m.constant_labels), ("y", m.output_names, m.output_labels)]
    for key, unit in (units or {}).items():
        for g, names, labels in groups:
            i = _lookup(key, names, labels)
            if i is not None:
                unit_of[(g, i)] = _check_unit(key, unit)
                break
        else:
            known = [n for _, names, _ in groups for n in names]
            raise ModelError(f"units: unknown name {key!r}; units go to states, inputs, "
                             f"constants and outputs: {', '.join(known)}")
    return unit_of


def _outputs_and_tunable(m):
    """The counts of the output groups (the model's outputs, else the
    multipliers and constraint residuals) and 1/0 per constant: tunable
    unless the constraints hold it (a new value would leave the state
    inconsistent)."""
    if m.ny:
        nout = {"y": m.ny, "lam": 0, "fc": 0, "fv": 0}
    else:
        nout = {"y": 0, "lam": m.mv, "fc": m.mc, "fv": m.mv}
    in_constraints = set()
    for mat in (m.fc, m.A, m.b):
        for e in mat:
            in_constraints |= e.free_symbols
    return nout, [0 if s in in_constraints else 1 for s in m.p]


class _Refs:
    """The value references: time 0, then the states, the derivatives of
    the independent ones, the inputs, the constants, the outputs."""

    def __init__(self, m):
        self.x = 1
        self.der = self.x + m.nx
        self.r = self.der + m.ns
        self.p = self.r + m.nr
        self.out = self.p + m.np

    def of(self, knowns, with_parameters):
        """The sorted value references of (kind, index) knowns."""
        out = []
        for kind, i in knowns:
            if kind == "x":
                out.append(self.x + i)
            elif kind == "r":
                out.append(self.r + i)
            elif with_parameters:
                out.append(self.p + i)
        return sorted(out)


def _state_variables(m, add, vr, x0, independent, tunable, unit_of):
    """Time, the states, their derivatives, the inputs and the constants."""
    add(name="time", vr=0, causality="independent", variability="continuous", initial=None,
        start=None, description="time")
    for i in range(m.nx):
        what = "coordinate" if i < m.nq else "speed"
        ind = i in independent
        desc = (f"{m.state_labels[i]}: {'independent' if ind else 'dependent'} {what}"
                + (" (a continuous state)" if ind else
                   " (solved from the independent state and the constraints at every "
                   "evaluation; the start value is the guess)"))
        add(name=m.state_names[i], vr=vr.x + i, causality="local", variability="continuous",
            initial="exact" if ind else "approx", start=_fmt(x0[i]), description=desc,
            unit=unit_of.get(("x", i)))
    for k, i in enumerate(independent):
        u = unit_of.get(("x", i))
        add(name=f"der({m.state_names[i]})", vr=vr.der + k, causality="local",
            variability="continuous", initial="calculated", start=None,
            description=f"time derivative of {m.state_labels[i]}",
            unit=_per_second(u) if u else None, derivative_of=vr.x + i)
    for k in range(m.nr):
        add(name=m.input_names[k], vr=vr.r + k, causality="input", variability="continuous",
            initial=None, start="0.0", description=f"input {m.input_labels[k]}",
            unit=unit_of.get(("r", k)))
    for k in range(m.np):
        add(name=m.constant_names[k], vr=vr.p + k, causality="parameter",
            variability="tunable" if tunable[k] else "fixed", initial="exact",
            start=_fmt(m.p_values[k]),
            description=f"constant {m.constant_labels[k]}"
            + ("" if tunable[k] else " (fixed: the constraints hold it)"),
            unit=unit_of.get(("p", k)))


def _output_variables(m, add, vr, nout, deps, unit_of):
    """The outputs (the model's, or the multipliers and the constraint
    residuals); returns the knowns each depends on."""
    groups = [("y", lambda j: m.output_names[j], lambda j: f"output {m.output_labels[j]}",
               deps.output),
              ("lam", lambda j: f"lam{j}",
               lambda j: f"multiplier of velocity constraint {j} (M u' = f + A^T lam)",
               deps.multiplier),
              ("fc", lambda j: f"fc{j}",
               lambda j: f"residual of configuration constraint {j}, f_c(q, t)",
               deps.constraint),
              ("fv", lambda j: f"fv{j}",
               lambda j: f"residual of velocity constraint {j}, A(q) u + b(q, t)",
               deps.velocity_constraint)]
    out_deps = []
    for g, name, desc, dep in groups:
        for j in range(nout[g]):
            add(name=name(j), vr=vr.out + len(out_deps), causality="output",
                variability="continuous", initial="calculated", start=None,
                description=desc(j), unit=unit_of.get(("y", j)) if g == "y" else None)
            out_deps.append(dep[j])
    return out_deps


def _structure(variables, vr, deps, out_deps):
    """The ModelStructure (outputs, derivatives, initial unknowns) and the
    variables by value reference, FMI 2.0's indices filled in."""
    for pos, v in enumerate(variables):
        v.index = pos + 1
    outputs = [Unknown(vr.out + j, vr.of(d, False)) for j, d in enumerate(out_deps)]
    derivatives = [Unknown(vr.der + k, vr.of(d, False)) for k, d in enumerate(deps.derivative)]
    initial = ([Unknown(vr.der + k, vr.of(d, True)) for k, d in enumerate(deps.derivative)]
               + [Unknown(vr.out + j, vr.of(d, True)) for j, d in enumerate(out_deps)])
    initial.sort(key=lambda u: u.vr)
    by_vr = {v.vr: v for v in variables}
    for v in variables:
        if v.derivative_of is not None:
            v.derivative_index = by_vr[v.derivative_of].index
    for u in outputs + derivatives + initial:
        u.index = by_vr[u.vr].index
        u.dependency_indices = [by_vr[k].index for k in u.dependencies]
    return outputs, derivatives, initial, by_vr


def describe(model, fmi_version="2.0", kind="both", real="double", start=None, units=None,
             cs_method="dopri5"):
    """The FmuDescription of a model (see export_fmu for the arguments)."""
    m = model
    nh = _check_options(m, fmi_version, kind, real, cs_method)
    x0 = _start_state(m, start)
    deps = dependencies(m)
    independent = list(deps.independent)
    dependent = [i for i in range(m.nx) if i not in independent]
    unit_of = _units(m, units)
    nout, tunable = _outputs_and_tunable(m)
    taken, variables, vr = set(), [], _Refs(m)

    def add(**kw):
        kw["name"] = _unique(kw["name"], taken)
        variables.append(Variable(**kw))

    _state_variables(m, add, vr, x0, independent, tunable, unit_of)
    out_deps = _output_variables(m, add, vr, nout, deps, unit_of)
    outputs, derivatives, initial, by_vr = _structure(variables, vr, deps, out_deps)
    unit_names = [(u, _base_unit(u)) for u in sorted({v.unit for v in variables if v.unit})]
    token = _token(m, [fmi_version, kind, real, cs_method, x0, sorted(unit_of.items())])
    d = FmuDescription(
        fmi_version=fmi_version, name=m.name, token=token,
        description=(f"{m.name}: equations of motion from sympy.physics.mechanics "
                     f"({'Kane' if m.method == 'kane' else 'Lagrange'}), generated by eomgen"),
        me=kind in ("me", "both"), cs=kind in ("cs", "both"), real=real, cs_method=cs_method,
        variables=variables, outputs=outputs, derivatives=derivatives, initial_unknowns=initial,
        units=unit_names, sources=[], ns=m.ns, nout=nout, independent=independent,
        dependent=dependent, x_start=[_fmt(v) for v in x0],
        p_start=[_fmt(v) for v in m.p_values], tunable=tunable,
        state_names=list(m.state_names),
        # the importer's default tolerance (float resolves about 1e-5)
        default_tolerance=1e-8 if real == "double" else 1e-5)
    d.by_vr = by_vr
    if nh:
        from ..intake.hybrid import hybrid_iwork_len, hybrid_work_len
        d.nh = nh
        d.hwork = hybrid_work_len(m.nq, m.nu, m.mv, nh)
        d.hiwork = hybrid_iwork_len(m.nq, m.nu, m.mv, nh)
        d.hybrid_names = [h.name for h in m.hybrid]     # a refused start names its own
        d.hybrid_kinds = [h.kind for h in m.hybrid]
    return d


# ------------------------------------------------------------- rendering
def render_fmu(model, description, real="double", headers=()):
    """(files, rendered): {path in the FMU: text} of the sources and XML
    files (no binary), and the Rendered of its sources/ that gen.build
    compiles (the FMU backend; headers: the FMI headers' folder)."""
    d = description
    rendered = render(make_plan(model, lin=FMU.lin), real=real, backend=FMU, project=False)
    files = {f"sources/{name}": text for name, text in sorted(rendered.files.items())}
    glue = csrc_dir() / "products" / "fmu"
    for name in FMU.glue[d.fmi_version]:
        files[f"sources/{name}"] = (glue / name).read_text()
    names = sorted(Path(p).name for p in files) + ["gen_fmu_model.h"]
    d.sources = [n for n in sorted(set(names)) if n.endswith(".c")]
    env = template_env()
    P = model.name.upper()
    ctx = {"d": d, "P": P, "version": __version__,
           "method_macro": f"{P}_METHOD_{d.cs_method.upper()}",
           "names": [v.name for v in sorted(d.variables, key=lambda v: v.vr)],
           "dep_text": ", ".join(d.state_names[i] for i in d.dependent) or "none"}
    for path, template in FMU.fmu_templates[d.fmi_version]:
        files[path] = env.get_template(template).render(**ctx)
    sources = {p[len("sources/"):]: text for p, text in files.items()
               if p.startswith("sources/")}
    rendered = Rendered(sources, rendered.interface, FMU.name, real, True,
                        includes=tuple(str(h) for h in headers))
    return files, rendered


def render_fmu_files(model, description, real="double"):
    """{path in the FMU: text} of the sources and XML files (no binary)."""
    return render_fmu(model, description, real=real)[0]


# ---------------------------------------------------------------- binary
def fmi_headers(fmi_version):
    """The folder holding the FMI headers of this version, from the
    installed FMPy (a maintained copy of the standard's headers)."""
    fmpy = require("fmpy", "gen.export_fmu (the FMI headers are FMPy's)")
    folder = Path(fmpy.__file__).parent / "c-code"
    missing = [h for h in HEADERS[fmi_version] if not (folder / h).is_file()]
    if missing:
        raise MissingDependencyError(
            f"the installed FMPy ({folder.parent}) has no {', '.join(missing)}: reinstall it "
            "(pip install --force-reinstall eomgen[fmu])")
    return folder


def platform_folder(fmi_version):
    """binaries/<this> of the running machine: FMI 2.0's platform name or
    FMI 3.0's platform tuple."""
    system = platform.system()
    machine = platform.machine().lower()
    arch = {"amd64": "x86_64", "x86_64": "x86_64", "arm64": "aarch64",
            "aarch64": "aarch64", "i386": "x86", "i686": "x86"}.get(machine, machine)
    os_name = {"Linux": "linux", "Darwin": "darwin", "Windows": "windows"}.get(system)
    if os_name is None:
        raise BuildError(f"no FMI platform name for {system} {machine}: export with "
                         "binary=False (a source FMU) and compile it on the target")
    if fmi_version == "3.0":
        return f"{arch}-{os_name}"
    fmi2 = {("x86_64", "linux"): "linux64", ("x86", "linux"): "linux32",
            ("x86_64", "darwin"): "darwin64", ("x86_64", "windows"): "win64",
            ("x86", "windows"): "win32"}.get((arch, os_name))
    if fmi2 is None:
        raise BuildError(f"FMI 2.0 defines no platform name for {system} {machine}: "
                         "export FMI 3.0 or with binary=False (a source FMU)")
    return fmi2


def _binary(rendered):
    """The FMU's shared library: the sources/ of the FMU built by gen.build
    (the FMU backend's recipe: gen.compile's flags, position independent,
    only the FMI functions exported, so two FMUs in one process cannot
    clash), cached by content like every other library. Returns its file."""
    if platform.system() == "Windows":
        raise BuildError("building the FMU's binary on Windows is not supported: export with "
                         "binary=False (a source FMU) and compile it with the importer")
    try:
        return build(rendered).path
    except BuildError as e:
        raise BuildError(f"compiling the FMU's binary failed: {e}") from None


def _write_zip(entries, path):
    """A zip of {name: bytes} with fixed dates and modes, names sorted:
    the same model gives the same bytes. Written atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    os.close(fd)
    try:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zf:
            for name in sorted(entries):
                info = zipfile.ZipInfo(name, date_time=ZIP_DATE)
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = (0o755 if name.startswith("binaries/") else 0o644) << 16
                info.create_system = 3
                zf.writestr(info, entries[name])
        os.chmod(tmp, mode_for_umask())   # mkstemp's 0600 -> the umask's (0644 under 022)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _check_start(path, d):
    """Initialize the FMU once with FMPy (the importer the tests use) at its
    start values: a start state whose dependent coordinates cannot be solved
    is refused here, with the FMU's own message, not left to the user's
    first simulation."""
    simulate_fmu = require("fmpy", "gen.export_fmu").simulate_fmu
    messages = []

    def logger(*args):
        messages.append(args[-1].decode("utf-8", "replace") if isinstance(args[-1], bytes)
                        else str(args[-1]))

    try:
        # start = stop: initialization and the outputs there, no step
        simulate_fmu(str(path), fmi_type="CoSimulation" if d.cs else "ModelExchange",
                     start_time=0.0, stop_time=0.0, output_interval=1.0, logger=logger)
    except Exception as e:          # FMPy raises its own exception types
        why = "; ".join(messages) or str(e)
        dep = [d.state_names[i] for i in d.dependent]
        ind = [d.state_names[i] for i in d.independent]
        raise ModelError(
            f"the FMU does not initialize at its start values: {why}. Give a start state "
            f"with start={{...}}: the independent entries ({', '.join(ind)}) and a guess for "
            f"the dependent ones ({', '.join(dep)}) near a state the model reaches") from None


def export_fmu(model, path, fmi_version="2.0", kind="both", real="double", start=None,
               units=None, cs_method="dopri5", binary=True):
    """Write the model as a Functional Mock-up Unit (a zip) (:doc:`/guides/fmu`).

    Needs FMPy for the FMI headers (``pip install eomgen[fmu]``).

    Parameters
    ----------
    model : gen.Model
        The model.
    path : str or Path
        The FMU to write.
    fmi_version : {"2.0", "3.0"}, optional
        The FMI version.
    kind : {"cs", "me", "both"}, optional
        Co-Simulation, Model Exchange or both.
    real : {"double", "float"}, optional
        The model's scalar type (the FMU's variables are doubles either way).
    start : dict, optional
        The start state ``{name: value}`` (C names or the sympy spelling; the
        others zero). The independent entries are exact; the dependent
        coordinates and speeds are solved from them at initialization, the
        values given being the guess (which branch of the constraints).
    units : dict, optional
        ``{name of a state, input, constant or output: unit}`` in Modelica's
        unit syntax (``"m"``, ``"rad/s"``, ``"N.m"``); derivatives get /s.
    cs_method : {"dopri5", "rodas4"}, optional
        The Co-Simulation integrator (``"rodas4"`` for stiff models).
    binary : bool, optional
        Compile ``binaries/<platform>/<name>.so`` for this machine (needs a C
        compiler); False gives a source-only FMU (not initialized here).

    Returns
    -------
    Path
        The FMU written.

    Raises
    ------
    gen.ModelError
        On a bad option, an unknown name in start or units, or a start state
        that cannot be made consistent (the FMU is initialized once here).
    gen.core.errors.MissingDependencyError
        When FMPy is not installed (the message names the pip command).
    gen.BuildError
        When the binary does not compile.
    """
    require_model(model, "gen.export_fmu")
    from ..intake.model import Model
    if not isinstance(model, Model):
        raise ModelError(f"export_fmu needs a gen.Model, got {type(model).__name__}")
    if not str(path).endswith(".fmu"):
        raise ModelError(f"the FMU's file name must end in .fmu, got {str(path)!r}")
    d = describe(model, fmi_version=fmi_version, kind=kind, real=real, start=start,
                 units=units, cs_method=cs_method)
    headers = fmi_headers(fmi_version)
    files, rendered = render_fmu(model, d, real=real, headers=[headers])
    entries = {k: v.encode("utf-8") for k, v in files.items()}
    if not binary:
        return _write_zip(entries, path)
    folder = platform_folder(fmi_version)
    lib = _binary(rendered)
    entries[f"binaries/{folder}/{lib.name}"] = lib.read_bytes()
    # checked under a temporary name: a refused FMU leaves an older file as it was
    path = Path(path)
    trial = path.parent / f".{path.stem}.{os.getpid()}.trial.fmu"
    try:
        _write_zip(entries, trial)
        _check_start(trial, d)
        os.replace(trial, path)
    finally:
        trial.unlink(missing_ok=True)
    return path
