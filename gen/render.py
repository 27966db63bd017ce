"""Render a model to files: kernels -> Jinja2 context (plain strings, ints
and lists) -> templates. The list of templates is data; writes are atomic
(a temporary directory moved into place) and deterministic (no
timestamps)."""
from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

import jinja2

from . import __version__
from .errors import ModelError
from .ir import build_kernels, mass_structure
from .solvers import ldlt_solve_c
from .printers import ModelCPrinter, ModelCxxPrinter, print_kernel_body
from .resources import csrc_dir, templates_dir

__all__ = ["generate", "api_functions", "cdef_text", "RUNTIME_SOURCES", "STATUSES", "BACKENDS"]

RUNTIME_SOURCES = ["gen_rt_status.c", "gen_rt_linalg.c", "gen_rt_dynamics.c",
                   "gen_rt_project.c", "gen_rt_integrate.c", "gen_rt_linearize.c"]
RUNTIME_HEADERS = ["gen_rt.h"]

# (macro suffix, value, message) - mirrors csrc/gen_rt.h
STATUSES = [
    ("OK", 0, "ok"),
    ("ERR_NULL", -1, "a required pointer argument is NULL"),
    ("ERR_NONFINITE_INPUT", -2, "an input value is NaN or infinite"),
    ("ERR_SINGULAR", -3, "singular or badly conditioned system at this state"),
    ("ERR_NO_CONVERGENCE", -4, "constraint Newton iteration did not converge"),
    ("ERR_STEP_UNDERFLOW", -5, "adaptive step size underflow"),
    ("ERR_MAX_STEPS", -6, "step budget exhausted"),
    ("ERR_BAD_ARG", -7, "argument out of range"),
    ("ERR_NONFINITE_MODEL", -8, "model expressions are NaN/inf at this state"),
    ("ERR_OUTPUT_FULL", -9, "output buffer too small"),
]

# (C file name, template) for the C backend: the list is data.
C_TEMPLATES = [
    ("{name}.h", "c/model.h.j2"),
    ("{name}.c", "c/model.c.j2"),
    ("main.c", "c/main.c.j2"),
    ("CMakeLists.txt", "c/CMakeLists.txt.j2"),
    ("arm-none-eabi.cmake", "c/arm-none-eabi.cmake.j2"),   # Cortex-M4F toolchain file
]

# The C++17/Eigen backend: the typed API (header-only templates over the
# scalar type), an extern "C" layer with the C backend's API (the same
# header, rendered from the same template and the same api_functions list),
# and the same standalone simulator main.c linked against that layer.
EIGEN_TEMPLATES = [
    ("{name}.h", "c/model.h.j2"),
    ("{name}.hpp", "eigen/model.hpp.j2"),
    ("{name}.cpp", "eigen/model.cpp.j2"),
    ("main.c", "c/main.c.j2"),
    ("CMakeLists.txt", "eigen/CMakeLists.txt.j2"),
]
# the C++ sources of the extern "C" library (compiled by gen.build)
EIGEN_SOURCES = ["{name}.cpp"]

BACKENDS = {"c": C_TEMPLATES, "eigen": EIGEN_TEMPLATES}

# the model prefix is also the C++ namespace of the Eigen backend
CXX_RESERVED = frozenset("""
alignas alignof and and_eq asm auto bitand bitor bool break case catch char char8_t
char16_t char32_t class compl concept const consteval constexpr constinit const_cast
continue co_await co_return co_yield decltype default delete do double dynamic_cast
else enum explicit export extern false float for friend goto if inline int long
mutable namespace new noexcept not not_eq nullptr operator or or_eq private
protected public register reinterpret_cast requires return short signed sizeof
static static_assert static_cast struct switch template this thread_local throw
true try typedef typeid typename union unsigned using virtual void volatile
wchar_t while xor xor_eq std Eigen eomgen detail
""".split())


def api_functions(p):
    """The public C functions: (name, params, doc). Header and cffi cdef are
    both printed from this list."""
    R = f"{p}_real"
    c = f"const {R} *"
    return [
        (f"{p}_status_message", "int status", "Message for a status code.", "const char *"),
        (f"{p}_eval_mass_matrix", f"{c}q, {c}p, {R} t, {R} *M",
         "Mass matrix M(q) of the unconstrained equations, NU x NU."),
        (f"{p}_eval_forcing", f"{c}q, {c}u, {c}r, {c}p, {R} t, {R} *f",
         "Forcing f(q, u, r, t) of the unconstrained equations M u' = f + A^T lam, NU."),
        (f"{p}_eval_kinematics", f"{c}q, {c}u, {c}p, {R} t, {R} *qdot",
         "Coordinate rates q' from the kinematic differential equations, NQ."),
        (f"{p}_eval_constraints", f"{c}q, {c}p, {R} t, {R} *fc",
         "Configuration-constraint residuals f_c(q), MC."),
        (f"{p}_eval_constraint_jacobian", f"{c}q, {c}p, {R} t, {R} *Jc",
         "Configuration-constraint Jacobian d f_c / dq, MC x NQ."),
        (f"{p}_eval_velocity_constraints", f"{c}q, {c}u, {c}p, {R} t, {R} *fv",
         "Velocity-constraint residuals A(q) u + b(q, t), MV."),
        (f"{p}_eval_velocity_constraint_matrix", f"{c}q, {c}p, {R} t, {R} *A, {R} *b",
         "Velocity-constraint matrix A (MV x NU) and term b (MV)."),
        (f"{p}_eval_energy", f"{c}q, {c}u, {c}p, {R} t, {R} *E",
         "Total energy (only when the model was given one; else GEN_RT_ERR_BAD_ARG)."),
        (f"{p}_eval_rhs", f"{R} t, {c}x, {c}r, {c}p, {R} *dxdt, {R} *lam",
         "State derivative x' (NX) and, if lam != NULL, the multipliers (MV)."),
        (f"{p}_project", f"{R} t, {c}p, {R} tol, int max_iter, {R} *x",
         "Project x onto f_c = 0 (Gauss-Newton, minimum norm) and the velocity constraints; x unchanged on failure."),
        (f"{p}_consistent_state", f"{R} t, {c}p, {R} tol, int max_iter, {R} *x",
         "Solve the dependent coordinates and speeds from the independent ones (the dependent entries of x are the starting guess)."),
        (f"{p}_sim_options_default", f"{p}_sim_options *opts",
         "Fill opts with the defaults (RK4, projection on, rtol 1e-8, atol 1e-10).", "void"),
        (f"{p}_step_rk4", f"{R} t, {R} h, {c}r, {c}p, int project, {R} *x",
         "One classic RK4 step of size h from t, x updated in place (unchanged on failure)."),
        (f"{p}_advance", f"{R} t0, {R} t1, {c}r, {c}p, const {p}_sim_options *opts, {p}_sim_stats *stats, {R} *x",
         "Integrate x from t0 to t1 (one RK4 step, or adaptive DOPRI5 steps); stats accumulate."),
        (f"{p}_simulate_rows", f"{R} t0, {R} t_end, {R} dt",
         "Number of output rows simulate() writes for these times (or a negative status)."),
        (f"{p}_simulate", f"{c}x0, {R} t0, {R} t_end, {R} dt, {c}r, {c}p, const {p}_sim_options *opts, int capacity, {R} *t_out, {R} *x_out, {R} *lam_out",
         "Simulate from x0 with outputs every dt up to t_end (the last interval clipped): rows of t_out, x_out (NX each), lam_out (MV each, may be NULL). On failure the rows written are stats->n_out and stats->x_last holds the last good state.", "int", True),
        (f"{p}_linearize", f"{c}x_op, {c}r_op, {c}p, {R} t, {R} *A, {R} *B",
         "Linearize about any operating point: A (NS x NS) and B (NS x NR) for the independent state [q_ind, u_ind]."),
    ]


def _fn_entries(p):
    out = []
    for entry in api_functions(p):
        name, params, doc = entry[:3]
        ret = entry[3] if len(entry) > 3 else "int"
        if len(entry) > 4 and entry[4]:
            params = params + f", {p}_sim_stats *stats"
        out.append({"name": name, "params": params, "doc": doc, "ret": ret})
    return out


def cdef_text(model, real="double"):
    """The cffi cdef, from the same function list as the header."""
    p = model.name
    lines = [f"typedef {real} {p}_real;"]
    lines.append("typedef struct { int method; int project; %s_real rtol; %s_real atol; "
                 "%s_real h_init; %s_real h_min; %s_real h_max; long max_steps; "
                 "%s_real proj_tol; int proj_max_iter; } %s_sim_options;" % ((p,) * 7))
    lines.append("typedef struct { long n_accepted; long n_rejected; long n_rhs; int n_out; "
                 "%s_real t_last; %s_real h_next; %s_real x_last[%d]; } %s_sim_stats;"
                 % (p, p, p, model.nx, p))
    for fn in _fn_entries(p):
        lines.append(f"{fn['ret']} {fn['name']}({fn['params']});")
    return "\n".join(lines) + "\n"


def _kernel_context(kernels, printer, p, R=None):
    R = R or f"{p}_real"
    out = []
    docs = {
        "mass_matrix": "M(q)",
        "forcing": "f(q, u, r, t)",
        "kinematics": "q' (or Kqd and its right-hand side)",
        "rhs_terms": "everything the right-hand side needs",
        "constraints": "f_c(q)",
        "constraint_jacobian": "f_c(q) and d f_c/dq",
        "velocity_constraint_matrix": "A(q), b(q, t)",
        "velocity_constraints": "A(q) u + b",
        "energy": "total energy",
        "lin_terms": "Jacobian blocks of the linearization",
    }
    for k in kernels.values():
        params = []
        voids = []
        for a in k.args:
            if a.scalar:
                params.append(f"{R} {a.name}")
            else:
                params.append(f"const {R} *{a.name}")
            voids.append(a.name)
        for o in k.outputs:
            params.append(f"{R} *out_{o.name}")
        out.append({
            "name": k.name,
            "params": ", ".join(params),
            "voids": voids,
            "body": print_kernel_body(k, printer),
            "doc": docs.get(k.name, k.name),
            "n_assign": len(k.assignments),
        })
    return out


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


def _fmt_real(v, real):
    s = repr(float(v))
    if "e" not in s and "." not in s and "inf" not in s and "nan" not in s:
        s += ".0"
    return s + ("F" if real == "float" else "")


def build_context(model, real="double", kernels=None, timings=None, backend="c"):
    if real not in ("double", "float"):
        raise ModelError(f"real must be 'double' or 'float', got {real!r}")
    t0 = time.perf_counter()
    if kernels is None:
        kernels = build_kernels(model)
    t1 = time.perf_counter()
    if backend == "eigen":
        printer = ModelCxxPrinter(_symbol_map(model, kernels), "Scalar")
    else:
        printer = ModelCPrinter(_symbol_map(model, kernels), real)
    p = model.name
    m = model
    mx = lambda n: max(1, n)  # noqa: E731  C99 has no zero-length arrays
    nq, nu, nx, nr, np_, mc, mv = m.nq, m.nu, m.nx, m.nr, m.np, m.mc, m.mv
    sz = {
        "nqi": mx(nq - mc), "nui": mx(nu - mv), "mc": mx(mc), "mv": mx(mv),
        "np": mx(np_), "nr": mx(nr),
        "A": mx(mv * nu), "Rr": mx(nu * nr), "Sq": mx(mv * nq), "Su": mx(mv * nu),
        "Jc": mx(mc * nq),
        "accel_work": (nu + mv) * (nu + mv + 1) + 2 * nu * nu + 4 * nu + 1,
        "accel_iwork": nu + mv + 1,
        "rk4_work": 5 * nx,
        "dopri_work": 9 * nx,
        "minnorm_work": max(mc * mc + mc, mv * mv + mv) + 1,
    }
    niq, niu = nq - mc, nu - mv
    ns = niq + niu
    sz["lin_work"] = (nq * niq + mc * mc + mc * niq + nu * niu + nu * niq + mv * mv + mv * ns
                      + 2 * nq * ns + (nu + mv) ** 2 + (nu + mv) * (ns + nr) + nu * ns
                      + nu * niq + mv * niq + nq * nq + 8)
    sz["lin_iwork"] = nq + nu + mc + mv + 1
    kctx = _kernel_context(kernels, printer, p,
                           "Scalar" if backend == "eigen" else None)
    t2 = time.perf_counter()
    lin_names = {"Kqd": "Kqd", "Ku": "Ku", "M": "M", "A": "A", "Kq": "Kq", "Rq": "Rq",
                 "Ru": "Ru", "Rr": "Rr", "Sq": "Sq", "Su": "Su", "Vq": "Vq", "Jc": "Jc"}
    lin_call = ", ".join(lin_names[o.name] for o in kernels["lin_terms"].outputs)
    def sympy_name(names, labels, i):
        """' (sympy: <label>)' when the C name differs, safe inside a C comment."""
        lab = labels[i] if i < len(labels) else names[i]
        if lab == names[i]:
            return ""
        lab = (lab.replace("*/", "*\\/").replace("/*", "/\\*").replace("??", "?\\?")
               .replace("\\\n", " ").replace("\n", " ").replace("\r", " "))
        return f"; sympy: {lab}"

    roles = []
    for i in range(nq):
        roles.append((i, m.state_names[i],
                      ("coordinate, independent" if i in m.q_ind else "coordinate, dependent")
                      + sympy_name(m.state_names, m.state_labels, i)))
    for j in range(nu):
        roles.append((nq + j, m.state_names[nq + j],
                      ("speed, independent" if j in m.u_ind else "speed, dependent")
                      + sympy_name(m.state_names, m.state_labels, nq + j)))
    ctx = {
        "name": p, "p": p, "P": p.upper(), "version": __version__, "real": real,
        "method": m.method,
        "method_doc": ("Kane's method (dependent speeds eliminated numerically)"
                       if m.method == "kane" else
                       "Lagrange's method (multipliers from the KKT system)"),
        "nq": nq, "nu": nu, "nx": nx, "nr": nr, "np": np_, "mc": mc, "mv": mv, "ns": ns,
        "has_energy": 1 if m.energy is not None else 0,
        "statuses": STATUSES,
        "state_doc": roles,
        "inputs_doc": [(i, n + (f"  ({lab[2:]})" if lab else ""))
                       for i, n in enumerate(m.input_names)
                       for lab in [sympy_name(m.input_names, m.input_labels, i)]],
        "params_doc": [(i, n, _fmt_real(v, "double")
                        + sympy_name(m.constant_names, m.constant_labels, i))
                       for i, (n, v) in enumerate(zip(m.constant_names, m.p_values))],
        "ind_doc": list(enumerate(m.independent_state_names)),
        "functions": _fn_entries(p),
        "kernels": kctx,
        "explicit_kinematics": m.qdot is not None,
        "q_ind": ", ".join(map(str, m.q_ind)) or "0",
        "q_dep": ", ".join(map(str, m.q_dep)) or "0",
        "u_ind": ", ".join(map(str, m.u_ind)) or "0",
        "u_dep": ", ".join(map(str, m.u_dep)) or "0",
        "p_default": ", ".join(_fmt_real(v, real) for v in m.p_values) or "0",
        "sz": sz,
        "lin_call_outputs": lin_call,
        "state_names": m.state_names,
        "input_names": m.input_names,
        "constant_names": m.constant_names,
        "lam_names": [f"lam{i}" for i in range(mv)],
        "fc_names": [f"fc{i}" for i in range(mc)],
        "ind_names": m.independent_state_names,
        "runtime_sources": RUNTIME_SOURCES,
        "p_values_c": [_fmt_real(v, real) for v in m.p_values],
        "mass_solve": _mass_solve_code(m, real),
    }
    if backend == "eigen":
        ctx.update(_eigen_context(model, kernels))
    if timings is not None:
        timings["kernels"] = t1 - t0
        timings["printing"] = t2 - t1
    return ctx


def _mass_solve_code(model, real):
    """The unrolled LDL^T solve of an unconstrained model with a symmetric
    mass matrix ("" otherwise: constrained models use the runtime's
    pivoted LU on the augmented systems)."""
    if model.mv:
        return ""
    symmetric, nonzero = mass_structure(model)
    if not symmetric:
        return ""
    return ldlt_solve_c(model.name, model.nu, nonzero, f"{model.name}_real")


# shapes of the linearization blocks (names of the lin_terms kernel outputs)
_LIN_SHAPES = {"Kqd": ("NQ", "NQ"), "Ku": ("NQ", "NU"), "M": ("NU", "NU"), "A": ("MV", "NU"),
               "Kq": ("NQ", "NQ"), "Rq": ("NU", "NQ"), "Ru": ("NU", "NU"), "Rr": ("NU", "NR"),
               "Sq": ("MV", "NQ"), "Su": ("MV", "NU"), "Vq": ("MV", "NQ"), "Jc": ("MC", "NQ")}
# the blocks the C backend checks for NaN/inf before the elimination
_LIN_CHECKED = ("Kq", "Rq", "Ru", "Sq", "Su", "Jc", "Vq", "Rr")


def _eigen_context(model, kernels):
    """What the C++ templates need beyond the C context."""
    m = model
    if m.name in CXX_RESERVED:
        raise ModelError(f"model name {m.name!r} is a C++ keyword or reserved namespace; the "
                         f"Eigen backend uses the name as a namespace: choose another "
                         f"(for example 'my_{m.name}')")
    return {
        "nqi": m.nq - m.mc, "nui": m.nu - m.mv,
        "p_default_cxx": ", ".join(f"Scalar({_fmt_real(v, 'double')})" for v in m.p_values)
                         or "Scalar(0)",
        "lin_call_cxx": ", ".join(f"{o.name}.data()" for o in kernels["lin_terms"].outputs),
        "lin_decls": [(o.name,) + _LIN_SHAPES[o.name]
                      for o in kernels["lin_terms"].outputs if o.name not in ("M", "A")],
        "lin_checks": [(o.name,) + _LIN_SHAPES[o.name]
                       for o in kernels["lin_terms"].outputs if o.name in _LIN_CHECKED],
        "cxx_sources": [f.format(name=m.name) for f in EIGEN_SOURCES],
        # the C API by verb, so the extern "C" layer prints its signatures from api_functions
        "fns": {fn["name"][len(m.name) + 1:]: fn for fn in _fn_entries(m.name)},
    }


def _env():
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
        undefined=jinja2.StrictUndefined, autoescape=False)


def render_files(model, real="double", backend="c", timings=None):
    """{file name: text} for a model (nothing written)."""
    if backend not in BACKENDS:
        raise ModelError(f"unknown backend {backend!r}: choose one of {sorted(BACKENDS)}")
    if backend == "eigen":
        return _render_eigen(model, real, timings)
    ctx = build_context(model, real=real, timings=timings)
    env = _env()
    files = {}
    t0 = time.perf_counter()
    for fname, tname in C_TEMPLATES:
        files[fname.format(name=model.name)] = env.get_template(tname).render(**ctx)
    for src in RUNTIME_SOURCES + RUNTIME_HEADERS:
        files[src] = (csrc_dir() / src).read_text()
    files["gen_rt_config.h"] = (
        "/* gen_rt_config.h - runtime configuration written by eomgen. Do not edit. */\n"
        "#ifndef GEN_RT_CONFIG_H\n#define GEN_RT_CONFIG_H\n"
        + ("#define GEN_RT_REAL_FLOAT\n" if real == "float" else "")
        + "#endif\n")
    if timings is not None:
        timings["templates"] = time.perf_counter() - t0
    return files


def _render_eigen(model, real, timings):
    ctx = build_context(model, real=real, timings=timings, backend="eigen")
    env = _env()
    t0 = time.perf_counter()
    files = {fname.format(name=model.name): env.get_template(tname).render(**ctx)
             for fname, tname in EIGEN_TEMPLATES}
    if timings is not None:
        timings["templates"] = time.perf_counter() - t0
    return files


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
    """Write the model's sources, a CMake project and a standalone simulator
    into out_dir; return the paths written. backend="c": C99 model and the C
    runtime; backend="eigen": a C++17 header over Eigen 3.4 (scalar type a
    template parameter) plus an extern "C" layer with the C backend's API."""
    files = render_files(model, real=real, backend=backend, timings=timings)
    return write_atomic(files, out_dir)
