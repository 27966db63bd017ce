"""The pipeline from a model to a loaded Simulator, one stage per module:

    model -> plan (gen/plan/ir.py) -> render (gen/codegen/render.py) -> build (gen/toolchain/build.py)
          -> load (gen/toolchain/host.py) -> Simulator (gen/sim/simulator.py)

compile() runs it (gen.compile is this function); product() runs the same
stages for a product's library (a face's ProductPlan, gen/design):
render -> build -> gen.toolchain.host.load_product. A model is compiled
without its derivative kernels when its backend can add them later
(Backend.lazy_derivatives): the Simulator gets derive(), which plans and
renders them (derivatives_source), builds the complete library
(gen.toolchain.build.build_derivatives) and loads it, on first use.
build_product() runs plan -> render -> build for a product's library that
is not a Simulator (gen.casadi's), its path kept for the process.
"""
from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import replace
from pathlib import Path

from .codegen.backends import get_backend
from .sim.simulator import Simulator
from .toolchain.build import build, build_derivatives
from .core.errors import ModelError
from .toolchain.host import load, load_product
from .plan.ir import DERIVATIVE_KERNELS, plan as make_plan, with_derivatives
from .intake.model import require_model
from .codegen.render import render

__all__ = ["compile", "derivatives_source", "simulator", "product", "build_product",
           "MEMO_SIZE"]


def derivatives_source(plan, real="double", timings=None):
    """<name>_lin.c of a plan made without derivatives (the kernels are
    generated now: sympy's share of what a first linearize costs)."""
    t0 = time.perf_counter()
    full = with_derivatives(plan)
    t1 = time.perf_counter()
    lin_only = replace(full, kernels={k: v for k, v in full.kernels.items()
                                      if k in DERIVATIVE_KERNELS})
    tm = {}
    files = render(lin_only, real=real, backend="c", project=False, only={"lin"}, timings=tm)
    if timings is not None:
        timings["kernels_derivatives"] = t1 - t0
        timings["printing_derivatives"] = tm.get("printing", 0.0) + tm.get("templates", 0.0)
    return files.files[f"{plan.model.name}_lin.c"]


def simulator(built, derive=None):
    """The Simulator of a Built (gen.toolchain.build.build): its library loaded
    through the host module (gen.toolchain.host.load)."""
    host, api = load(built)
    return Simulator(host, api, built.interface, derivatives=derive)


def compile(model, backend="c", real="double", verbose=False, sources=None,  # noqa: A001
            timings=None, derivatives="lazy"):
    """Generate, build (cached by content) and load a model.

    The one path from a model to compiled code (the command line and
    :func:`gen.verify` call it).

    Parameters
    ----------
    model : gen.Model
        The model.
    backend : {"c", "eigen"} or gen.codegen.backends.Backend, optional
        C99 over the C runtime, or C++17 over Eigen 3.4 through its
        ``extern "C"`` layer (the same API, the same Simulator).
    real : {"double", "float"}, optional
        The scalar type.
    verbose : bool, optional
        Print the compiler's commands.
    sources : str or Path, optional
        A folder written by :func:`gen.generate` (possibly edited since): its
        files are compiled instead of freshly generated ones.
    timings : dict, optional
        Receives the time of each stage (kernels, printing, templates,
        compile; later the derivatives') and whether the build was cached.
    derivatives : {"lazy", True}, optional
        ``"lazy"`` (C backend): the derivative kernels (linearize, jacobian,
        step_sensitivity, RODAS4) are built on their first use; True: now.
        The Eigen backend always builds them.

    Returns
    -------
    gen.sim.simulator.Simulator
        The loaded model library.

    Raises
    ------
    gen.BuildError
        When the compiler fails (with its full log).
    gen.ModelError
        When ``sources`` does not hold this model's files.
    """
    require_model(model, "gen.compile")
    b = get_backend(backend, need="loadable")
    if derivatives not in ("lazy", True):
        raise ModelError(f"derivatives must be 'lazy' or True, got {derivatives!r}")
    timings = {} if timings is None else timings
    lazy = b.lazy_derivatives and sources is None and derivatives == "lazy"
    t0 = time.perf_counter()
    plan = make_plan(model, lin=b.lin, derivatives=not lazy)
    timings["kernels"] = time.perf_counter() - t0
    rendered = render(plan, real=real, backend=b, timings=timings, project=False)
    if sources is not None:
        rendered.files = _read_sources(sources, rendered.files, model.name, b)
        rendered.derivatives = True
    built = build(rendered, verbose=verbose, timings=timings)
    t0 = time.perf_counter()

    def derive():
        tm = {}
        lin = derivatives_source(plan, real=real, timings=tm)
        full = build_derivatives(built, lin, timings=tm)
        return load(full)[1], full, tm

    sim = simulator(built, derive=None if built.derivatives else derive)
    timings["load"] = time.perf_counter() - t0
    sim.build_info = {"module": str(built.path), "derivatives": built.derivatives, **timings,
                      "backend": b.name}
    return sim


def product(plan, backend, real="double", timings=None):
    """A product's library through the pipeline: its ProductPlan rendered
    by its backend (gen.codegen.render.render), built and cached by content
    (gen.toolchain.build.build) and opened with the cdef of its interface
    (gen.toolchain.host.load_product). Returns (Built, ffi, lib)."""
    b = get_backend(backend, need="product")
    timings = {} if timings is None else timings
    rendered = render(plan, real=real, backend=b, timings=timings)
    built = build(rendered, timings=timings)
    ffi, lib = load_product(built)
    return built, ffi, lib


def _read_sources(folder, expected, name, backend):
    """The files of a generated folder that the build compiles: those
    rendering produces, with the derivative kernels (<name>_lin.c) in place
    of their stand-ins."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ModelError(f"sources folder {folder} does not exist")
    names = [f for f in expected if f != f"{name}_lin_stub.c"]
    lin = [f.format(name=name) for f, _, role in backend.templates if role == "lin"]
    names += [f for f in lin if f not in names]
    files = {}
    for fname in names:
        path = folder / fname
        if not path.is_file():
            raise ModelError(f"{path} is missing: {folder} is not a generated '{name}' project")
        files[fname] = path.read_text()
    return files


# ------------------------------------------------ products built once per process
#: the product libraries built in this process (build_product): key -> path,
#: at most MEMO_SIZE, the least recently used dropped first
MEMO_SIZE = 32
_built = OrderedDict()
_built_lock = threading.Lock()


def build_product(model, backend, key=(), real="double", verbose=False):
    """The path of a product library of a model (plan -> render -> build
    with a backend that is not loaded as a Simulator: gen.casadi's), built
    into the content-keyed cache on first use. A second request in the same
    process skips planning and rendering, which for a product's derivative
    kernels can cost much more than the cache's lookup (the Whipple
    bicycle's CasADi library: 14 s of sympy without its Hessians, 0.1 s for
    the cart-pole): the paths are kept by (the model's fingerprint, the
    backend's name, key: what else the rendered files depend on, such as
    the backend variant's options, real), at most MEMO_SIZE of them, under
    a lock. A path whose library left the cache (gen.clear_cache) is built
    again. Two threads asking for the same new library may both build it
    (the cache publishes atomically; the files are the same)."""
    b = get_backend(backend)
    memo = (model.fingerprint(), b.name, tuple(key), real)
    with _built_lock:
        path = _built.get(memo)
    if path is not None and path.exists():
        return path
    plan = make_plan(model, lin=b.lin, derivatives=True)
    path = build(render(plan, real=real, backend=b, project=False), verbose=verbose).path
    with _built_lock:
        _built[memo] = path
        _built.move_to_end(memo)
        while len(_built) > MEMO_SIZE:
            _built.popitem(last=False)
    return path
