"""Render a model to files: plan -> Jinja2 context (plain strings, ints,
lists and the interface description) -> templates. The list of templates
is data; writes are atomic (a temporary directory moved into place) and
deterministic (no timestamps).

    plan = gen.plan.ir.plan(model)
    rendered = render(plan, real="double", backend="c")
    rendered.files        # {file name: text}: the project (sources, CMake, main.c)
    rendered.interface    # gen.codegen.abi.Interface: what the bindings need
    render(plan, project=False).files    # only what gen.build compiles

A product's library renders through the same call: its face's ProductPlan
(gen/codegen/product_abi.py) and its backend (a ProductBackend):

    rendered = render(product_plan, backend="ocp")
    rendered.interface    # its ProductInterface, bound: its headers and its cdef
    product_cdef(rendered.interface)      # the cdef gen.toolchain.host.load_product opens it with
"""
from __future__ import annotations

import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path


from .._version import __version__
from .abi import interface
from .templating import fmt_real, template_env
from .backends import C_TEMPLATES, RUNTIME_SOURCES, get_backend
from ..core.errors import ModelError
from ..plan.ir import DERIVATIVE_KERNELS, plan as make_plan
from ..intake.model import require_model
from ..sym.printers import kernel_statements, print_kernel_body
from .lanes import lanes_body
from ..core.resources import csrc_file
from ..plan.ldlt import demand_order, ldlt_statements, ldlt_work_index, ldlt_program
from ..plan.small import BIND, c_lines, kernel_program

__all__ = ["Rendered", "render", "render_files", "generate", "write_atomic", "template_env",
           "model_sources", "product_cdef"]

# the kernels of <name>_lin.c (C backend)
LIN_KERNELS = DERIVATIVE_KERNELS


def model_sources(name):
    """The model's own C files in a generated C project (with the runtime's
    RUNTIME_SOURCES, what a program linking the model compiles; the plugin
    table <name>_api.c is extra)."""
    return [f.format(name=name) for f, _, role in C_TEMPLATES
            if role in ("model", "lin") and f.endswith(".c") and f != "{name}_api.c"]

_KERNEL_DOCS = {
    "mass_matrix": "M(q)",
    "forcing": "f(q, u, r, t)",
    "kinematics": "q' (or Kqd and its right-hand side)",
    "rhs_terms": "everything the right-hand side needs",
    "constraints": "f_c(q)",
    "constraint_jacobian": "f_c(q) and d f_c/dq",
    "velocity_constraint_matrix": "A(q), b(q, t)",
    "velocity_constraints": "A(q) u + b",
    "energy": "total energy",
    "auxiliary": "F and g of the auxiliary equations F reactions + g = 0",
    "accel_terms": "the acceleration-constraint term a at the q' solved at run time",
    "outputs": "the outputs y(q, u, r, t)",
    "output_jacobian": "dy/dq, dy/du, dy/dr",
    "lin_terms": "Jacobian blocks of the linearization",
    "hybrid_values": "the gaps and guards of hybrid={...}",
    "hybrid_jacobian": "the gaps' rates g' = W u + w",
    "hybrid_bias": "the gaps' acceleration bias h: g'' = W u' + h",
    "hybrid_reset": "the states after the reset maps",
    "reaction_terms": "G, C, H, g0 of the coupled solve [M, -G; C, H] [u'; R] = [f; -g0]",
    "reaction_lin": "Jacobians of the reactions' share of the dynamic and auxiliary residuals",
}


@dataclass
class Rendered:
    """The output of rendering: the files (the whole project, or with
    project=False only what gen.build compiles) and the interface
    description. derivatives: whether the derivative kernels are among the
    files (else the build links <name>_lin_stub.c in their place). backend:
    the backend's name (gen/codegen/backends/); includes: folders of headers the
    build compiles against that are not among the files (the FMI headers)."""
    files: dict
    interface: object
    backend: str
    real: str
    derivatives: bool = True
    timings: dict = field(default_factory=dict)
    includes: tuple = ()


# a right-hand-side kernel of at least this many statements is compiled
# twice, for the baseline and for AVX (GEN_RT_CLONES): past the instruction
# cache the VEX encoding's smaller code pays (cart, eval_rhs: n = 8 links,
# 512 statements, 22% faster; n = 10 25%; n = 16 35%), below it nothing is
# gained and the compile time would double (n = 4: 178 statements)
CLONE_MIN_STATEMENTS = 300


def _wiring_mass_solve(mass_plan, kctx):
    """The plan of <name>.c's own M u' = f (the runtime's mass_solve:
    linearize's u' and the general path, not the right-hand side, which the
    fused kernel solves). A model whose right-hand side is large enough for
    GEN_RT_CLONES, with a dense M, takes it from the runtime's LDL^T in
    loops (gen_rt_ldlt.h: the same operations in the same order as the
    unrolled statements, so the same bits) rather than unrolled again: the
    wiring's compile was then its unrolled solve's (n = 8 cart: clang
    0.23 -> 0.12 s)."""
    if (mass_plan is None or mass_plan["loop"] or not mass_plan["dense"]
            or not any(k.get("clones") for k in kctx)):
        return mass_plan
    return {**mass_plan, "loop": True}


def _kernel_context(kernels, printer, fused=None, small=None, twins=()):
    """Kernels as data: names, arguments, outputs and the printed body
    (print_kernel_body). fused: the plan of the unrolled LDL^T
    (solvers.ldlt_program) when rhs_terms is the fused right-hand side: its
    body is then the solve's statements with the kernel's temporaries and
    its M and f (as locals m_<k>, f_<k>) each where the solve first reads
    them (solvers.demand_order; the solve's statements as (name, expression),
    declared by the template), "fill" the work array's entries (the looped
    solve), "stores" its other outputs' stores, and "bound" lists M and f
    for the template's stores. small: the straight-line solve of a small
    constrained model (gen.plan.small's Program) when rhs_terms is its fused
    right-hand side: its body is then the kernel's statements with M, f, A
    and a as locals (small.BIND), "solve" the program's lines after them.
    twins: the model's twin speeds: the right-hand side's body also in two
    lanes ("lanes", gen.codegen.lanes; None when it has none)."""
    out = []
    for k in kernels.values():
        ctx = {
            "name": k.name,
            "args": [{"name": a.name, "scalar": a.scalar} for a in k.args],
            "outputs": [o.name for o in k.outputs],
            "doc": _KERNEL_DOCS.get(k.name, k.name),
            "n_assign": len(k.assignments),
            "solve": None,
        }
        if small is not None and k.name == "rhs_terms":
            temps, stores = kernel_statements(k, printer, bind=BIND, reads=False)
            ctx["body"] = ["    " + t for _, t, _ in temps]
            ctx["fill"] = []
            ctx["stores"] = ["    " + line for line in stores]
            ctx["bound"] = [{"name": o.name, "local": BIND[o.name], "size": len(o.exprs)}
                            for o in k.outputs if o.name in BIND]
            ctx["solve"] = c_lines(small, real=printer.real_type)
            n_lines = len(ctx["body"]) + len(ctx["stores"]) + len(ctx["solve"])
        elif fused is not None and k.name == "rhs_terms":
            bind = {"M": "m_", "f": "f_"}
            temps, stores = kernel_statements(k, printer, bind=bind, reads=not fused["loop"])
            ctx["fill"] = []
            if fused["loop"]:
                # a large dense M: its lower triangle and f into the work
                # array of the runtime's LDL^T in loops (gen_rt_ldlt.h)
                n = fused["n"]
                ctx["fill"] = ([(ldlt_work_index(n, i, j), f"m_{i * n + j}")
                                for j in range(n) for i in range(j, n)]
                               + [(ldlt_work_index(n, i), f"f_{i}") for i in range(n)])
                body = [t for _, t, _ in temps]
            else:
                body = demand_order(ldlt_statements(fused, M=lambda i: f"m_{i}",
                                                    f=lambda i: f"f_{i}"), temps)
            ctx["body"] = [("    " + line) if isinstance(line, str) else line for line in body]
            ctx["stores"] = ["    " + line for line in stores]
            ctx["bound"] = [{"name": o.name, "local": bind[o.name], "size": len(o.exprs)}
                            for o in k.outputs if o.name in bind]
            n_lines = len(ctx["body"]) + len(ctx["fill"]) + len(ctx["stores"])
        else:
            ctx["body"] = print_kernel_body(k, printer)
            n_lines = len(ctx["body"])
        ctx["lanes"] = None
        if k.name == "rhs_terms" and small is None and twins and printer.real_type == "double":
            ctx["lanes"] = _lanes(k, ctx, printer, twins)
        # the right-hand side of a large model: built for the baseline and
        # for AVX, picked at load time (GEN_RT_CLONES in gen_rt.h)
        ctx["clones"] = k.name == "rhs_terms" and n_lines >= CLONE_MIN_STATEMENTS
        out.append(ctx)
    return out


def _lanes(k, ctx, printer, twins):
    """The two-lane body of the right-hand side (gen.codegen.lanes), seeded
    by its outputs f for the twin speeds, or None."""
    f = next((o.exprs for o in k.outputs if o.name == "f"), None)
    if f is None:
        return None
    names = [printer._print(e) if e.is_Symbol else None for e in f]
    seeds = [(names[i], names[j]) for i, j in twins
             if max(i, j) < len(names) and names[i] and names[j]]
    after = ctx.get("stores", []) + [w[1] for w in ctx.get("fill", [])] + [
        f"{b['local']}{i}" for b in ctx.get("bound", []) for i in range(b["size"])]
    return lanes_body(ctx["body"], seeds, after)


def _symbol_map(model, kernels):
    sm_ = {}
    for i, s in enumerate(model.q):
        sm_[s] = f"q[{i}]"
    for i, s in enumerate(model.u):
        sm_[s] = f"u[{i}]"
    for i, s in enumerate(model.r):
        sm_[s] = f"r[{i}]"
    for i, s in enumerate(model.p):
        sm_[s] = f"p[{i}]"
    sm_[model.t] = "t"
    for k in kernels.values():
        for a in k.args:
            if a.scalar:
                continue
            for i, s in enumerate(a.symbols):
                sm_.setdefault(s, f"{a.name}[{i}]")
        for s, _ in k.assignments:
            sm_[s] = s.name
    return sm_


def _field_default(f, real):
    """A struct field's default value as a C literal."""
    if f.default == "eps16":
        return "16 * GEN_RT_EPS"
    if f.ctype == "real":
        return fmt_real(f.default, real)
    return f"{int(f.default)}L" if f.ctype == "long" else str(int(f.default))


def _comment_label(names, labels, i):
    """'; sympy: <label>' when the C name differs, safe inside a C comment."""
    lab = labels[i] if i < len(labels) else names[i]
    if lab == names[i]:
        return ""
    lab = (lab.replace("*/", "*\\/").replace("/*", "/\\*").replace("??", "?\\?")
           .replace("\\\n", " ").replace("\n", " ").replace("\r", " "))
    return f"; sympy: {lab}"


def _small_solve(b, plan):
    """The straight-line solve of a small constrained model (gen.plan.small's
    Program), or None: for a backend whose templates have the fused
    right-hand side, explicit kinematics and velocity constraints, the
    reactions outside the motion, and a system small enough. rhs_terms then
    also solves for u' by the runtime's partitioned or KKT solve traced as
    straight-line code, before the runtime's general path (which it matches
    bit for bit or leaves to)."""
    m, kernels = plan.model, plan.kernels
    if not (b.fused_rhs and plan.accel in ("partitioned", "kkt") and m.qdot is not None
            and m.mv > 0 and "rhs_terms" in kernels and getattr(m, "aux_G", None) is None):
        return None
    # every input of eval_rhs, tested finite with the solve's values: eval_rhs
    # tests them itself only when the fast path fails (the seed's Lagrange
    # model 12.7 -> 11.9 ns a call)
    sizes = {"q": m.nq, "u": m.nu, "r": m.nr, "p": m.np}
    inputs = [f"{a}[{i}]" for a in ("q", "u", "r", "p") for i in range(sizes[a])] + ["t"]
    return kernel_program(kernels["rhs_terms"], plan.accel, m.nu, m.mv, ind=m.u_ind,
                          dep=m.u_dep, inputs=inputs)


def build_context(plan, iface, timings=None, backend="c"):
    """The Jinja2 context of a plan: plain data and the interface."""
    t1 = time.perf_counter()
    b = get_backend(backend)
    m = plan.model
    kernels = plan.kernels
    real = iface.real
    printer = b.printer(_symbol_map(m, kernels), real)
    p = m.name
    # the fused right-hand side (gen_rt_model.rhs_solve; a backend whose
    # templates have it, explicit kinematics): rhs_terms also solves for u',
    # M and f in locals, by the unrolled LDL^T (unconstrained) or _small_solve
    fused = (b.fused_rhs and plan.accel == "ldlt" and m.qdot is not None
             and "rhs_terms" in kernels)
    mass_plan = ldlt_program(m.nu, plan.mass_nonzero) if plan.accel == "ldlt" else None
    small = _small_solve(b, plan)
    kctx = _kernel_context(kernels, printer, mass_plan if fused else None, small, m.twins)
    t2 = time.perf_counter()
    mx = lambda n: max(1, n)  # noqa: E731  C99 has no zero-length arrays
    nq, nu, nr, mc, mv = m.nq, m.nu, m.nr, m.mc, m.mv
    roles = []
    for i in range(nq):
        roles.append((i, m.state_names[i],
                      ("coordinate, independent" if i in m.q_ind else "coordinate, dependent")
                      + _comment_label(m.state_names, m.state_labels, i)))
    for j in range(nu):
        roles.append((nq + j, m.state_names[nq + j],
                      ("speed, independent" if j in m.u_ind else "speed, dependent")
                      + _comment_label(m.state_names, m.state_labels, nq + j)))
    opts = iface.struct("sim_options")
    ctx = {
        "iface": iface, "name": p, "p": p, "P": p.upper(), "R": f"{p}_real",
        "version": __version__, "real": real, "method": m.method,
        "method_doc": ("Kane's method (dependent speeds eliminated numerically)"
                       if m.method == "kane" else
                       "Lagrange's method (multipliers from the KKT system)"),
        "nq": nq, "nu": nu, "nx": m.nx, "nr": nr, "np": m.np, "mc": mc, "mv": mv, "ns": m.ns,
        "has_energy": 1 if m.energy is not None else 0,
        "explicit_kinematics": m.qdot is not None,
        "state_doc": roles,
        "inputs_doc": [(i, n + (f"  ({lab[2:]})" if lab else ""))
                       for i, n in enumerate(m.input_names)
                       for lab in [_comment_label(m.input_names, m.input_labels, i)]],
        "params_doc": [(i, n, fmt_real(v, "double")
                        + _comment_label(m.constant_names, m.constant_labels, i))
                       for i, (n, v) in enumerate(zip(m.constant_names, m.p_values))],
        "ind_doc": list(enumerate(m.independent_state_names)),
        "kernels": kctx,
        # the derivative kernels (the largest, used only by linearize, jacobian,
        # step_sensitivity and RODAS4) live in <name>_lin.c, a translation
        # unit of their own compiled in parallel with <name>.c
        "lin_kernels": [k for k in LIN_KERNELS if k in kernels],
        "has_accel_terms": "accel_terms" in kernels,
        # "unrolled": one lin_terms kernel writes every block; "jvp": lin_plain
        # writes the plain blocks and lin_jvp, called once per variable,
        # the columns of the Jacobian blocks (gen/plan/ir.py JVP_MIN_VARIABLES)
        "lin_mode": "jvp" if "lin_jvp" in kernels else "unrolled",
        "lin_outputs": ([o.name for o in kernels["lin_terms"].outputs] if "lin_terms" in kernels
                        else [o.name for o in kernels["lin_plain"].outputs]
                        if "lin_plain" in kernels else []),
        "jvp_outputs": ([o.name for o in kernels["lin_jvp"].outputs] if "lin_jvp" in kernels
                        else []),
        "has_sqd": "lin_jvp" in kernels and len(kernels["lin_jvp"].args[-1].symbols) > 0,
        "p_default": [fmt_real(v, real) for v in m.p_values],
        "p_default_double": [fmt_real(v, "double") for v in m.p_values],
        "defaults": {f.name: _field_default(f, real) for f in opts.fields},
        # the solver choice (made by the plan) as the runtime's constant, and
        # the arguments of the runtime's work-size macros
        "accel_c": iface.accel_macro,
        "mass_solve": mass_plan, "wiring_mass_solve": _wiring_mass_solve(mass_plan, kctx),
        "mass_solve_statements": (ldlt_statements(mass_plan)
                                  if mass_plan and not mass_plan["loop"] else None),
        "fused_rhs": fused or small is not None,
        "small_solve": small is not None,    # its solve: gen.plan.small's
        # reactions inside the motion, solved with u' (gen_rt_accel_reactions)
        "reactions_coupled": getattr(m, "aux_G", None) is not None,
        # q' is u itself (the usual q' = u): the fused right-hand side's q'
        # is finite when the checked state is, so only its u' is checked
        "qdot_is_u": (m.qdot is not None and m.nq == m.nu
                      and all(a == b for a, b in zip(m.qdot, m.u))),
        # array sizes (C99 and C++ have no zero-length arrays)
        "sz": {"nqi": mx(nq - mc), "nui": mx(nu - mv), "mc": mx(mc), "mv": mx(mv),
               "np": mx(m.np), "nr": mx(nr)},
        "q_ind": ", ".join(map(str, m.q_ind)) or "0",
        "q_dep": ", ".join(map(str, m.q_dep)) or "0",
        "u_ind": ", ".join(map(str, m.u_ind)) or "0",
        "u_dep": ", ".join(map(str, m.u_dep)) or "0",
        "state_names": m.state_names,
        "input_names": m.input_names,
        "constant_names": m.constant_names,
        "ind_names": m.independent_state_names,
        "runtime_sources": RUNTIME_SOURCES,
        # hybrid={...} (gen/intake/hybrid.py): the declarations as data
        "hybrid": _hybrid_context(m, real),
    }
    ctx.update(abi_context())
    ctx.update(b.context(m, kernels))
    if timings is not None:
        timings["printing"] = t2 - t1
    return ctx


def _hybrid_context(m, real):
    """The hybrid declarations for model.c.j2 (None: the model has none)."""
    decls = getattr(m, "hybrid", None) or []
    if not decls:
        return None
    from ..intake.hybrid import KIND_RESET, hybrid_iwork_len, hybrid_work_len
    resets = [i for i, d in enumerate(decls) if d.kind == KIND_RESET]
    return {
        "n": len(decls),
        "names": [d.name for d in decls],
        "kind": [d.kind for d in decls],
        "direction": [d.direction for d in decls],
        "restitution": [fmt_real(d.restitution, real) for d in decls],
        "rest_speed": [fmt_real(d.rest_speed, real) for d in decls],
        # the row block of each declaration in hybrid_reset's output (-1: none)
        "reset_index": [resets.index(i) if i in resets else -1 for i in range(len(decls))],
        "has_reset": bool(resets),
        # the engine's scratch (GEN_RT_HYBRID_WORK / _IWORK of gen_rt.h)
        "work": hybrid_work_len(m.nq, m.nu, m.mv, len(decls)),
        "iwork": hybrid_iwork_len(m.nq, m.nu, m.mv, len(decls)),
    }


def abi_context():
    """The facts of gen/codegen/abi.py a template renders with no model: the method
    and hold codes, the stack bound, the structs (read at call time)."""
    from . import abi
    return {
        "methods": sorted(abi.METHODS.items(), key=lambda kv: kv[1]),
        "method_names": (sorted(abi.METHODS.items(), key=lambda kv: kv[1])
                         + [(a, abi.METHODS[n]) for a, n in abi.METHOD_ALIASES.items()]),
        "holds": sorted(abi.HOLDS.items(), key=lambda kv: kv[1]),
        "stack_limit": abi.STACK_LIMIT,
        "abi_structs": abi.check_structs(abi.STRUCTS),
    }


def runtime_abi_header():
    """The text of gen_rt_abi.h (csrc/ holds a copy for the runtime built
    alone; every model renders its own)."""
    return template_env().get_template("c/gen_rt_abi.h.j2").render(**abi_context())


def render(plan, real="double", backend="c", timings=None, project=True, only=None):
    """Render a Plan (gen.plan.ir.plan) to a Rendered: the project's files and
    the interface description. project=False: only what gen.build compiles
    (the model library's sources, with the derivative kernels when the plan
    has them, else their stand-ins). only: a set of template roles ("model",
    "lin", "stub", "project") to render, nothing else (no runtime files).
    Nothing is written and nothing is stored on the model.

    With a product's backend (Backend.product), plan is the face's
    ProductPlan (gen/codegen/product_abi.py): the Rendered holds its files
    (its templates, the headers of its interface, its runtime files) and
    its bound ProductInterface; project and only do not apply."""
    if real not in ("double", "float"):
        raise ModelError(f"real must be 'double' or 'float', got {real!r}")
    b = get_backend(backend)
    timings = {} if timings is None else timings
    if b.product:            # a product's library (a ProductPlan)
        return _render_product(plan, b, real, timings)
    if b.composite:          # the Eigen face: the C backend's files and its own
        return b.render(plan, real, timings, project, only, render_c=render,
                        env=template_env())
    iface = interface(plan.model, real=real, accel=plan.accel)
    ctx = build_context(plan, iface, timings=timings, backend=b)
    env = template_env()
    t0 = time.perf_counter()
    name = plan.model.name
    if project and not plan.derivatives:
        raise ModelError("a generated project has the derivative kernels: render a plan made "
                         "with derivatives=True")
    roles = {"model", "lin" if plan.derivatives else "stub"} | ({"project"} if project else set())
    files = {fname.format(name=name): env.get_template(tname).render(**ctx)
             for fname, tname, role in b.templates if role in (only or roles)}
    for src in (b.runtime_files + (b.project_runtime_files if project else ())
                if only is None else ()):
        files[Path(src).name] = csrc_file(src).read_text()
    timings["templates"] = time.perf_counter() - t0
    return Rendered(files, iface, b.name, real, plan.derivatives, timings)


def _product_kernel(kernel, backend, real):
    """A product's kernel as data: its name, its output's name and its
    printed statements (the arguments are arrays, read as <arg>[i])."""
    smap = {}
    for a in kernel.args:
        for i, s in enumerate(a.symbols):
            smap[s] = f"{a.name}[{i}]"
    for s, _ in kernel.assignments:
        smap[s] = s.name
    temps, stores = kernel_statements(kernel, backend.printer(smap, real), reads=False)
    return {"name": kernel.name, "out": f"out_{kernel.outputs[0].name}",
            "lines": [line for _, line, _ in temps] + stores}


def _render_product(plan, b, real, timings):
    """A product's files: the plan's files (another backend's, such as the
    model's sources), its templates and its interface's headers over the
    plan's data, its printed kernels and its backend's context, and its
    runtime files (b: a ProductBackend)."""
    t0 = time.perf_counter()
    iface = b.interface.bind(**b.names(plan, real))
    ctx = {**plan.data, "iface": iface, "name": plan.name, "version": __version__,
           "real": real, "kernels": [_product_kernel(k, b, real) for k in plan.kernels]}
    t1 = time.perf_counter()
    ctx.update(b.context(plan, iface, real))
    env = template_env()
    files = dict(plan.files)
    files.update({fname.format(name=plan.name): env.get_template(tname).render(**ctx)
                  for fname, tname, _ in b.file_templates(iface)})
    for src in b.runtime_files:
        files[Path(src).name] = csrc_file(src).read_text()
    timings["printing"] = t1 - t0
    timings["templates"] = time.perf_counter() - t1
    return Rendered(files, iface, b.name, real, True, timings)


def product_cdef(iface):
    """The cffi cdef of a product's library, rendered from its bound
    ProductInterface by the macros of its headers."""
    return template_env().get_template("cffi/product.cdef.j2").render(iface=iface)


def render_files(model, real="double", backend="c", timings=None):
    """{file name: text} of a model (nothing written)."""
    b = get_backend(backend)
    timings = {} if timings is None else timings
    t0 = time.perf_counter()
    plan = make_plan(model, lin=b.lin)
    timings["kernels"] = time.perf_counter() - t0
    return render(plan, real=real, backend=b, timings=timings).files


def current_umask():
    """The process's umask, read without changing it where the system shows
    it (Linux: /proc/self/status), else by setting and restoring it."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def mode_for_umask(directory=False):
    """The mode a file (0o666) or a folder (0o777) created with open() or
    mkdir() gets under the current umask: what a temporary file or folder
    (0o600 / 0o700) moved into place must be given."""
    return (0o777 if directory else 0o666) & ~current_umask()


def write_atomic(files, out_dir):
    """Write files into out_dir through a temporary sibling directory that
    is moved into place only when complete; a failure leaves out_dir as it
    was. Files already in out_dir that we do not generate are kept."""
    out = Path(out_dir).resolve()
    if out.exists() and not out.is_dir():
        raise ModelError(f"output path {out} exists and is not a directory")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    try:
        # mkdtemp's folder is 0700: the folder moved into place gets the mode
        # of the one it replaces, or of a new folder under the umask
        os.chmod(tmp, (out.stat().st_mode & 0o7777) if out.is_dir()
                 else mode_for_umask(directory=True))
        if out.exists():
            for item in out.iterdir():
                if item.name not in files:
                    if item.is_dir():
                        shutil.copytree(item, tmp / item.name, symlinks=True)
                    else:
                        shutil.copy2(item, tmp / item.name)
        for fname, text in files.items():
            with open(tmp / fname, "w", encoding="utf-8", newline="\n") as fh:
                fh.write(text)
        old = None
        if out.exists():
            old = out.parent / f".{out.name}.old-{os.getpid()}-{time.monotonic_ns()}"
            os.rename(out, old)
        os.rename(tmp, out)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return [out / f for f in files]


def generate(model, out_dir, backend="c", real="double", timings=None):
    """Write the model's sources, a CMake project and a standalone simulator.

    Parameters
    ----------
    model : gen.Model
        The model.
    out_dir : str or Path
        The folder to write into (created; files written atomically, the same
        model gives the same bytes).
    backend : {"c", "eigen"}, optional
        ``"c"``: the C99 model over the C runtime; ``"eigen"``: a C++17 header
        over Eigen 3.4 (the scalar type a template parameter) on the C++
        runtime, plus an ``extern "C"`` layer with the C backend's API.
    real : {"double", "float"}, optional
        The scalar type (``float``: the embedded profile).
    timings : dict, optional
        Receives the time of each stage.

    Returns
    -------
    list of Path
        The paths written.
    """
    require_model(model, "gen.generate")
    files = render_files(model, real=real, backend=get_backend(backend, need="project"),
                         timings=timings)
    return write_atomic(files, out_dir)
