"""The one description of the generated C interface.

Everything a generated model exposes is described here once, as plain
data: the public functions (name, parameters with their role and shape,
return type, documentation), the batch entry points of the Python module,
the structs (options and statistics of the integrators), the status codes
with their messages, and the model's plain metadata (names, sizes,
partition, default constants). The C header, the cffi cdef and the
typed C++ face of the Eigen backend are rendered from it; the bindings map status codes to exceptions with it; the footprint
report lists its public functions from it.

The status table itself is the runtime's (``csrc/gen_rt_status.h``): it is
read from there, so the C runtime and this description cannot disagree.

    iface = abi.interface(model, real="double")
    iface.functions            # [Function], in header order
    iface.struct("sim_options").fields
    iface.size("NU*NU")        # 4 for the seed pendulum
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

from ..core.status import (STATUS_UNKNOWN, STATUSES, Status, status_message, status_name,
                           status_value)

__all__ = ["Status", "Field", "Struct", "Param", "Function", "Interface", "STATUSES",
           "STRUCTS", "FUNCTIONS", "BATCH_FUNCTIONS", "METHODS", "METHOD_ALIASES",
           "ADAPTIVE_METHODS", "JACOBIAN_METHODS", "HOLDS", "STACK_LIMIT", "method_name",
           "method_code", "hold_code", "check_structs", "status_name", "status_value",
           "status_message", "interface", "host_interface", "ABI_TAG", "DERIVATIVE_VERBS"]


# ------------------------------------------------------- codes and bounds
# These facts are written here once. The runtime's own copy (csrc/gen_rt_abi.h:
# GEN_RT_METHOD_*, GEN_RT_HOLD_*, the structs) and every model's header
# (<P>_METHOD_*, <P>_HOLD_*) are rendered from them (templates/c/
# gen_rt_abi.h.j2, model.h.j2); tests/unit/codegen/test_abi.py pins the committed
# csrc/gen_rt_abi.h to this file.

# integration methods: name -> value of <P>_METHOD_<NAME> / sim_options.method
METHODS = {"rk4": 0, "dopri5": 1, "rodas4": 2}
# other spellings a user may give (Python, the command line, the binary)
METHOD_ALIASES = {"rodas": "rodas4"}
# the adaptive methods (error control, dense output: the FMU's co-simulation
# choices), and those that evaluate the Jacobian (the derivative kernels)
ADAPTIVE_METHODS = ("dopri5", "rodas4")
JACOBIAN_METHODS = ("rodas4",)
# table holds: name -> value of <P>_HOLD_<NAME> / input.hold
HOLDS = {"zoh": 0, "linear": 1}
# the embedded profile's bound on every function frame, in bytes
# (-Wstack-usage when cross-compiling, gen.footprint, `eomgen report`)
STACK_LIMIT = 8192


def method_name(method, arg="method"):
    """The canonical name of an integration method ("rodas" -> "rodas4");
    a ValueError naming the argument for an unknown one."""
    name = METHOD_ALIASES.get(method, method) if isinstance(method, str) else method
    if name not in METHODS:
        raise ValueError(f"{arg} must be one of {sorted(METHODS)}, got {method!r}")
    return name


def method_code(method, arg="method"):
    """The value of sim_options.method for a method name or alias."""
    return METHODS[method_name(method, arg)]


def hold_code(hold, arg="input_hold"):
    """The value of input.hold for a hold name."""
    if hold not in HOLDS:
        raise ValueError(f"{arg} must be one of {sorted(HOLDS)}, got {hold!r}")
    return HOLDS[hold]


# ------------------------------------------------------------------- structs
@dataclass(frozen=True)
class Field:
    name: str
    ctype: str              # "int", "long", "real", "creal*" (const real array),
                            # "cint*" (const int array), "cvint*" (a const
                            # volatile int: a flag another thread sets), "int*", "real*" (arrays
                            # written), "controller" (the callback) or "void*"
    doc: str
    default: object = 0     # a number, or "eps16" (16 machine epsilons of the scalar type)
    count: str | None = None    # an array of this many (a size such as "NX")


@dataclass(frozen=True)
class Struct:
    name: str               # <p>_<name> in C, a CamelCase template in C++
    cxx_name: str
    doc: str
    fields: tuple


STRUCTS = (
    Struct("sim_options", "SimOptions", "Integration options (fill with <p>_sim_options_default).", (
        Field("method", "int", "<P>_METHOD_RK4 (on the output grid), <P>_METHOD_DOPRI5 or "
              "<P>_METHOD_RODAS4 (adaptive, dense output)", 0),
        Field("project", "int", "1: project onto the constraints after each step", 1),
        Field("rtol", "real", "adaptive: relative tolerance", 1e-8),
        Field("atol", "real", "adaptive: absolute tolerance", 1e-10),
        Field("h_init", "real", "adaptive: first step, <= 0: automatic", 0.0),
        Field("h_min", "real", "adaptive: minimum step, <= 0: automatic", 0.0),
        Field("h_max", "real", "adaptive: maximum step, <= 0: unbounded", 0.0),
        Field("max_steps", "long", "adaptive: step budget between two output rows", 100000),
        Field("proj_tol", "real", "projection: relative tolerance on the correction", "eps16"),
        Field("proj_max_iter", "int", "projection: Newton iterations", 10),
        Field("every", "int", "simulate: keep every k-th output row and the last (<= 1: all)", 1),
        Field("final_only", "int", "simulate: 1 keeps only the row at t_end", 0),
        # issue 32 (Ctrl-C): the caller-owned cancellation flag (gen_rt.h reads it
        # through a volatile pointer; gen/sim/interrupt.py sets it on SIGINT)
        Field("cancel", "cvint*", "flag owned by the caller, read before every step: nonzero "
              "stops the run with <P>_ERR_CANCELLED (NULL: never cancelled)", 0),
    )),
    Struct("input", "Input", "Inputs during a simulation (simulate_input): a constant or a "
           "table, a linear feedback on the independent state, a controller callback; "
           "continuous or sampled. Zero-fill it (memset) and set what you use.", (
        Field("r", "creal*", "NR constant inputs (NULL: zero); the base of the feedback", 0),
        Field("n_table", "int", "> 0: the base from a table of n_table rows instead", 0),
        Field("t_table", "creal*", "n_table strictly increasing times", 0),
        Field("r_table", "creal*", "n_table x NR inputs, row-major", 0),
        Field("hold", "int", "table: <P>_HOLD_ZOH (the last knot's row) or <P>_HOLD_LINEAR", 0),
        Field("K", "creal*", "NR x NS gain on the independent state (NULL: none): "
              "r = base - K (x_ind - x_op_ind)", 0),
        Field("x_op", "creal*", "NX operating state of the gain (NULL: zero)", 0),
        Field("controller", "controller", "called last with r holding the above; may "
              "overwrite r; nonzero return: ERR_CONTROLLER (NULL: none)", 0),
        Field("ctx", "void*", "passed to the controller", 0),
        Field("period", "real", "0: r evaluated at every stage; > 0: sampled at t0 + k period "
              "and held", 0.0),
        # issue 34 (trajectory tracking): a time-varying gain, zero-filled: none
        Field("n_gain", "int", "> 0: a gain schedule of n_gain rows: K is n_gain x NR x NS, "
              "x_op n_gain x NX and r (when not NULL) n_gain x NR, row k used from t_gain + k "
              "dt_gain on (row 0 before, the last row after)", 0),
        Field("t_gain", "real", "schedule: the time of row 0", 0.0),
        Field("dt_gain", "real", "schedule: the time between rows (> 0)", 0.0),
        Field("r_min", "creal*", "NR lower bounds the inputs are clipped to after the "
              "feedback (NULL: none; -inf: unbounded)", 0),
        Field("r_max", "creal*", "NR upper bounds, likewise (NULL: none; inf: unbounded)", 0),
    )),
    Struct("events", "Events", "Events of simulate_events: crossings of a level by a state or "
           "an output, located on the dense output; the log of those found. Zero-fill it and "
           "set what you use.", (
        Field("n", "int", "number of event functions", 0),
        Field("which", "cint*", "n: 0..NX-1 the state x[which], NX..NX+NY-1 the output "
              "y[which - NX]", 0),
        Field("direction", "cint*", "n: +1 crossing upwards, -1 downwards, 0 both", 0),
        Field("terminal", "cint*", "n (NULL: none): nonzero ends the run at the event", 0),
        Field("level", "creal*", "n (NULL: zero): the level crossed", 0),
        Field("capacity", "int", "events the log holds", 0),
        Field("log_which", "int*", "capacity: the event's index i", 0),
        Field("log_t", "real*", "capacity: its time", 0),
        Field("log_x", "real*", "capacity x NX: its state (the dense output, projected)", 0),
        # issue 35 (hybrid={...}): impacts, resets and contact run in the engine
        # with this work; logged as events n.. (n + k: declaration k, n + NH + k:
        # lift-off of contact k)
        Field("log_x_after", "real*", "capacity x NX (NULL: not kept): the state after a "
              "hybrid event's jump (impact, reset), else as log_x", 0),
        Field("hybrid_work", "real*", "GEN_RT_HYBRID_WORK(NQ, NU, MV, NH) reals: the "
              "engine's hybrid scratch (a model with hybrid={...} needs it)", 0),
        Field("hybrid_iwork", "int*", "GEN_RT_HYBRID_IWORK(NQ, NU, MV, NH) ints", 0),
    )),
    Struct("sim_stats", "SimStats", "Integration statistics (advance accumulates them).", (
        Field("n_accepted", "long", "accepted steps"),
        Field("n_rejected", "long", "rejected steps (dopri5)"),
        Field("n_rhs", "long", "right-hand-side evaluations"),
        Field("n_jac", "long", "Jacobian evaluations (rodas4)"),
        Field("n_out", "int", "output rows written"),
        Field("n_events", "int", "events found (simulate_events; the log holds the first "
              "capacity)"),
        Field("terminal", "int", "the terminal event that ended the run, -1: none", -1),
        Field("t_last", "real", "time of the last good state", 0.0),
        Field("h_next", "real", "adaptive: step size to continue with", 0.0),
        Field("x_last", "real", "last good state (on failure: where it failed)", 0.0, "NX"),
    )),
)


STRUCT_NAMES = tuple(s.name for s in STRUCTS)


def check_structs(structs):
    """A counted field (an array of a model's size) must be its struct's
    last: the runtime sees it as a pointer to the caller's array and the
    Python host as a flexible array member, so only the fields before it
    share one layout on every side."""
    for s in structs:
        for f in s.fields[:-1]:
            if f.count:
                raise ValueError(f"gen/codegen/abi.py: {s.name}.{f.name} is an array of {f.count} but "
                                 f"not the last field of {s.name}: add fields before it")
    return structs


# ----------------------------------------------------------------- functions
@dataclass(frozen=True)
class Param:
    """One parameter. role:
    in        const real array of `size` values: NULL -> ERR_NULL, NaN/inf -> ERR_NONFINITE_INPUT
    in?       the same, NULL allowed: replaced by `default` ("p": the default constants,
              "r": zero inputs) before the checks
    scalar    a real number checked for NaN/inf
    value     a plain value passed through unchecked (tolerances, counts, flags)
    inout     a real array read and written (checked like `in`)
    out       a real array written; NULL -> ERR_NULL when its size is not zero
    out?      an optional output (NULL: not computed)
    struct    const struct pointer: NULL -> ERR_NULL      (ctype: the struct's name)
    struct?   const struct pointer: NULL -> the defaults
    struct_out  a struct written: NULL -> ERR_NULL
    """
    name: str
    ctype: str              # "real", "int", or a struct name
    role: str
    size: str | None = None  # an expression in NQ, NU, NX, NR, NP, MC, MV, NS, NA ("NU*NU")
    default: str | None = None


@dataclass(frozen=True)
class Function:
    verb: str               # the C name is <p>_<verb>
    params: tuple
    doc: str
    ret: str = "int"        # "int" (a status), "void" or "const char *"
    work: str | None = None  # the runtime's work-size macros: GEN_RT_MODEL_<work>_WORK/_IWORK
    iwork: bool = False
    work_args: str | None = None  # sizes the work macros take beyond the model's ("NA")
    model: bool = True      # False: no model; the function is the runtime's gen_rt_<verb>,
                            # called with the same arguments and nothing checked


def _params(spec):
    """'q:in:NQ, p:in?:NP=p, t:scalar, M:out:NU*NU' -> (Param, ...); ctype
    is real unless given as name:role:size:ctype."""
    out = []
    for item in spec.split(","):
        item = item.strip()
        if not item:
            continue
        head, _, default = item.partition("=")
        parts = head.split(":")
        name, role = parts[0], parts[1]
        size = parts[2] if len(parts) > 2 and parts[2] else None
        ctype = parts[3].strip() if len(parts) > 3 else "real"
        out.append(Param(name, ctype, role, size, default or None))
    return tuple(out)


FUNCTIONS = (
    Function("status_message", _params("status:value::int"), "Message for a status code.",
             ret="const char *", model=False),
    Function("eval_mass_matrix", _params("q:in:NQ, p:in?:NP=p, t:scalar, M:out:NU*NU"),
             "Mass matrix M(q) of the unconstrained equations, NU x NU."),
    Function("eval_forcing", _params("q:in:NQ, u:in:NU, r:in?:NR=r, p:in?:NP=p, t:scalar, f:out:NU"),
             "Forcing f(q, u, r, t) of the unconstrained equations M u' = f + A^T lam, NU."),
    Function("eval_kinematics", _params("q:in:NQ, u:in:NU, p:in?:NP=p, t:scalar, qdot:out:NQ"),
             "Coordinate rates q' from the kinematic differential equations, NQ.",
             work="KIN", iwork=True),
    Function("eval_constraints", _params("q:in:NQ, p:in?:NP=p, t:scalar, fc:out:MC"),
             "Configuration-constraint residuals f_c(q), MC."),
    Function("eval_constraint_jacobian", _params("q:in:NQ, p:in?:NP=p, t:scalar, Jc:out:MC*NQ"),
             "Configuration-constraint Jacobian d f_c / dq, MC x NQ.", work="JAC"),
    Function("eval_velocity_constraints",
             _params("q:in:NQ, u:in:NU, p:in?:NP=p, t:scalar, fv:out:MV"),
             "Velocity-constraint residuals A(q) u + b(q, t), MV."),
    Function("eval_velocity_constraint_matrix",
             _params("q:in:NQ, p:in?:NP=p, t:scalar, A:out:MV*NU, b:out:MV"),
             "Velocity-constraint matrix A (MV x NU) and term b (MV)."),
    Function("eval_energy", _params("q:in:NQ, u:in:NU, p:in?:NP=p, t:scalar, E:out:1"),
             "Total energy (only when the model was given one; else GEN_RT_ERR_BAD_ARG)."),
    Function("eval_rhs", _params("t:scalar, x:in:NX, r:in?:NR=r, p:in?:NP=p, dxdt:out:NX, lam:out?:MV"),
             "State derivative x' (NX) and, if lam != NULL, the multipliers (MV).",
             work="EVAL_RHS", iwork=True),
    Function("eval_auxiliary_forces",
             _params("t:scalar, x:in:NX, r:in?:NR=r, p:in?:NP=p, F:out:NA"),
             "Reaction forces along the auxiliary speeds (Kane's u_auxiliary), NA: u' from the "
             "right-hand side, then F_aux reactions = -g_aux; reactions that enter the motion "
             "come with u' from one linear system (GEN_RT_ERR_SINGULAR_REACTIONS when either "
             "solve is singular); with no unknown force along them (all declared inputs) the "
             "force each direction still needs, -g_aux at the inputs given; NA == 0: nothing "
             "written.",
             work="AUX", iwork=True, work_args="NA"),
    Function("project", _params("t:scalar, p:in?:NP=p, tol:value, max_iter:value::int, x:inout:NX"),
             "Project x onto f_c = 0 (Gauss-Newton, minimum norm) and the velocity constraints; "
             "x unchanged on failure.", work="PROJECT"),
    Function("consistent_state",
             _params("t:scalar, p:in?:NP=p, tol:value, max_iter:value::int, x:inout:NX"),
             "Solve the dependent coordinates and speeds from the independent ones (the "
             "dependent entries of x are the starting guess).", work="CONSISTENT", iwork=True),
    Function("sim_options_default", _params("opts:struct_out::sim_options"),
             "Fill opts with the defaults (RK4, projection on, rtol 1e-8, atol 1e-10).",
             ret="void"),
    Function("step_rk4", _params("t:scalar, h:scalar, r:in?:NR=r, p:in?:NP=p, project:value::int, "
                                 "x:inout:NX"),
             "One classic RK4 step of size h from t, x updated in place (unchanged on failure).",
             work="STEP", iwork=True),
    Function("advance", _params("t0:scalar, t1:scalar, r:in?:NR=r, p:in?:NP=p, "
                                "opts:struct::sim_options, stats:struct_out::sim_stats, x:inout:NX"),
             "Integrate x from t0 to t1 (one RK4 step, or adaptive DOPRI5 or RODAS4 steps); "
             "stats accumulate.", work="ADVANCE", iwork=True),
    Function("simulate_rows", _params("t0:value, t_end:value, dt:value"),
             "Number of output times of simulate() for these times (or a negative status).",
             model=False),
    Function("simulate_rows_kept", _params("rows:value::int, every:value::int, "
                                           "final_only:value::int"),
             "The rows simulate() writes (its capacity) of simulate_rows()'s rows with "
             "opts.every and opts.final_only: every k-th and the last (every <= 1: all), or 1 "
             "with final_only; a negative rows (a status) returned as is.",
             model=False),
    Function("simulate", _params("x0:in:NX, t0:value, t_end:value, dt:value, r:in?:NR=r, p:in?:NP=p, "
                                 "opts:struct?::sim_options, capacity:value::int, t_out:rows, "
                                 "x_out:rows, lam_out:out?, stats:struct_out::sim_stats"),
             "Simulate from x0 with outputs every dt up to t_end (the last interval clipped): "
             "rows of t_out, x_out (NX each), lam_out (MV each, may be NULL). On failure the rows "
             "written are stats->n_out and stats->x_last holds the last good state.",
             work="SIMULATE", iwork=True),
    Function("simulate_input",
             _params("x0:in:NX, t0:value, t_end:value, dt:value, in:struct::input, "
                     "p:in?:NP=p, opts:struct?::sim_options, capacity:value::int, t_out:rows, "
                     "x_out:rows, lam_out:out?, r_out:out?, stats:struct_out::sim_stats"),
             "simulate() with the inputs from in (a table, a linear feedback, a controller "
             "callback; continuous or sampled): r_out (NR per row, may be NULL) gets the "
             "inputs in effect from each output time on.",
             work="SIMULATE_INPUT", iwork=True),
    Function("simulate_events",
             _params("x0:in:NX, t0:value, t_end:value, dt:value, in:struct::input, "
                     "ev:struct::events, p:in?:NP=p, opts:struct?::sim_options, "
                     "capacity:value::int, t_out:rows, x_out:rows, lam_out:out?, r_out:out?, "
                     "stats:struct_out::sim_stats"),
             "simulate_input() with events (ev): crossings logged in ev's log, a terminal "
             "event ends the run with its state as the last row (stats->terminal).",
             work="SIMULATE_EVENTS", iwork=True, work_args="NY"),
    Function("linearize", _params("x_op:in:NX, r_op:in?:NR=r, p:in?:NP=p, t:scalar, "
                                  "A:out:NS*NS, B:out:NS*NR"),
             "Linearize about any operating point: A (NS x NS) and B (NS x NR) for the independent "
             "state [q_ind, u_ind].", work="LINEARIZE", iwork=True),
    Function("jacobian",
             _params("t:scalar, x:in:NX, r:in?:NR=r, p:in?:NP=p, Jx:out:NX*NX, Jr:out:NX*NR"),
             "The full-state Jacobian of the right-hand side, d x'/dx (NX x NX) and d x'/dr "
             "(NX x NR), every entry of x free (dependent entries included).",
             work="JACOBIAN", iwork=True),
    Function("step_sensitivity",
             _params("t:scalar, h:scalar, r:in?:NR=r, p:in?:NP=p, x:inout:NX, Fx:out:NS*NS, "
                     "Fr:out:NS*NR"),
             "One classic RK4 step of size h without projection (x updated; unchanged on "
             "failure) and its exact derivatives by the variational equations: Fx = dx1_ind/"
             "dx_ind (NS x NS) with the dependent entries of x following the constraints to "
             "first order, Fr = dx1_ind/dr (NS x NR).",
             work="STEP_SENS", iwork=True),
    Function("eval_input", _params("t:scalar, x:in:NX, in:struct::input, r:out:NR"),
             "The inputs at (t, x) from in without sampling (the base at t, the feedback of "
             "the gain or of the schedule's row at t, the controller): one step of a digital "
             "controller, called at its sample times; NR values."),
    Function("eval_outputs", _params("t:scalar, x:in:NX, r:in?:NR=r, p:in?:NP=p, y:out:NY"),
             "The outputs y(q, u, r, t), NY (the model's outputs={...}); NY == 0: nothing "
             "written."),
    # issue 46: the gaps and guards of hybrid={...} (a start's check names its value)
    Function("eval_hybrid", _params("t:scalar, x:in:NX, p:in?:NP=p, g:out:NH"),
             "The gaps and guards of the hybrid declarations (hybrid={...}) at (t, x), NH in "
             "declaration order, every contact free; NH == 0: nothing written."),
    Function("linearize_outputs",
             _params("x_op:in:NX, r_op:in?:NR=r, p:in?:NP=p, t:scalar, A:out:NS*NS, B:out:NS*NR, "
                     "C:out:NY*NS, D:out:NY*NR"),
             "linearize() and the outputs' C = dy/dx_ind (NY x NS), D = dy/dr (NY x NR), "
             "the dependent entries following the constraints as for A.",
             work="LINEARIZE_OUTPUTS", iwork=True, work_args="NY"),
    Function("linearize_discrete", _params("x_op:in:NX, r_op:in?:NR=r, p:in?:NP=p, t:scalar, "
                                           "dt:scalar, Ad:out:NS*NS, Bd:out:NS*NR"),
             "The zero-order-hold discretization of the linearization over a step dt: "
             "Ad = exp(A dt) (NS x NS), Bd = int_0^dt exp(A s) ds B (NS x NR), by scaling and "
             "squaring (GEN_RT_ERR_BAD_ARG unless dt > 0).",
             work="LINEARIZE_DISCRETE", iwork=True),
)

# Loops over the public API compiled into the Python module (not into the
# model library): one call evaluates N states with the GIL released. They
# return the index of the first failing state (its status in *status) or -1.
# Strides are in elements; 0: the same vector for every state.
# C types of the batch parameters, over the model's real type
_CR, _R, _I = "const real *", "real *", "int *"
BATCH_FUNCTIONS = (
    Function("rhs_batch", _params(f"n:value::int, t:value::{_CR}, t_stride:value::int, "
                                  f"x:value::{_CR}, r:value::{_CR}, r_stride:value::int, "
                                  f"p:value::{_CR}, p_stride:value::int, dxdt:value::{_R}, "
                                  f"status:value::{_I}"), "x' for n states."),
    Function("outputs_batch", _params(f"n:value::int, t:value::{_CR}, t_stride:value::int, "
                                      f"x:value::{_CR}, r:value::{_CR}, r_stride:value::int, "
                                      f"p:value::{_CR}, p_stride:value::int, y:value::{_R}, "
                                      f"status:value::{_I}"), "the outputs y for n states."),
    Function("mass_matrix_batch", _params(f"n:value::int, q:value::{_CR}, q_stride:value::int, "
                                          f"p:value::{_CR}, p_stride:value::int, M:value::{_R}, "
                                          f"status:value::{_I}"),
             "M(q) for n configurations."),
    Function("linearize_batch", _params(f"n:value::int, x:value::{_CR}, r:value::{_CR}, "
                                        f"r_stride:value::int, p:value::{_CR}, "
                                        f"p_stride:value::int, t:value, A:value::{_R}, "
                                        f"B:value::{_R}, status:value::{_I}"),
             "(A, B) at n operating points."),
)


def _abi_tag():
    """A tag of the plugin table's layout (<name>_api.c and the Python host
    module): it changes with any function, parameter or struct field, so a
    host never calls a model through a table of another layout."""
    import hashlib
    h = hashlib.sha256()
    for s in STRUCTS:
        h.update(repr((s.name, [(f.name, f.ctype, f.count) for f in s.fields])).encode())
    for f in FUNCTIONS + BATCH_FUNCTIONS:
        h.update(repr((f.verb, f.ret, [(a.name, a.ctype, a.role) for a in f.params])).encode())
    return "eomgen-abi-" + h.hexdigest()[:16]


ABI_TAG = _abi_tag()


# ---------------------------------------------------------------- interface
@dataclass
class Interface:
    """The interface of one generated model: the shared description bound to
    its prefix, scalar type and sizes, plus its metadata. Plain data: what
    the bindings need at run time, with no sympy object."""
    name: str
    real: str
    method: str                     # "kane" or "lagrange"
    sizes: dict                     # NQ, NU, NX, NR, NP, MC, MV, NS, NA, NY, NH
    state_names: list
    state_labels: list
    input_names: list
    input_labels: list
    constant_names: list
    constant_labels: list
    independent_state_names: list
    q_ind: list
    q_dep: list
    u_ind: list
    u_dep: list
    constants: list                 # default values
    has_energy: bool
    explicit_kinematics: bool
    accel: str                      # "partitioned", "kkt", "ldlt" or "lu"
    functions: tuple = FUNCTIONS
    batch_functions: tuple = BATCH_FUNCTIONS
    structs: tuple = STRUCTS
    statuses: tuple = field(default_factory=lambda: tuple(STATUSES))
    # reaction forces of the auxiliary speeds (NA of them): C-safe names and
    # the user's sympy spelling
    auxiliary_names: list = field(default_factory=list)
    auxiliary_labels: list = field(default_factory=list)
    # the outputs y (NY of them): C-safe names and the user's names
    output_names: list = field(default_factory=list)
    output_labels: list = field(default_factory=list)
    # hybrid={...} (gen/intake/hybrid.py): the declarations' names and kinds
    hybrid_names: list = field(default_factory=list)
    hybrid_kinds: list = field(default_factory=list)

    # sizes as attributes: iface.nq, iface.nx, ...
    def __getattr__(self, key):
        sizes = self.__dict__.get("sizes")
        if sizes is not None and key.upper() in sizes and key.islower():
            return sizes[key.upper()]
        raise AttributeError(key)

    def size(self, expr):
        """The value of a size expression ("NU*NU", "1", None -> 0)."""
        if expr is None:
            return 0
        return int(eval(expr, {"__builtins__": {}}, dict(self.sizes)))

    def struct(self, name):
        return next(s for s in self.structs if s.name == name)

    @property
    def abi_tag(self):
        """ABI_TAG: the plugin table's layout."""
        return ABI_TAG

    @property
    def struct_verbs(self):
        """The functions that take a struct (the plugin table passes those
        as void pointers through a trampoline)."""
        return [f for f in self.functions
                if any(a.ctype in STRUCT_NAMES for a in f.params)]

    def function(self, verb):
        return next(f for f in self.functions + self.batch_functions if f.verb == verb)

    @property
    def public_names(self):
        """The C names of the public functions (the footprint's list)."""
        return [f"{self.name}_{f.verb}" for f in self.functions]

    def work_dims(self):
        """The arguments of the runtime's GEN_RT_MODEL_*_WORK macros."""
        s = self.sizes
        return (f"{s['NQ']}, {s['NU']}, {s['MC']}, {s['MV']}, {s['NR']}, "
                f"{1 if self.explicit_kinematics else 0}, {self.accel_macro}")

    @property
    def accel_macro(self):
        """The runtime's constant for the solver: GEN_RT_ACCEL_PARTITIONED, ..."""
        return "GEN_RT_ACCEL_" + self.accel.upper()

    def work_args(self, fn):
        """The arguments of fn's GEN_RT_MODEL_<work>_WORK macros."""
        extra = [str(self.size(a)) for a in (fn.work_args or "").split(",") if a.strip()]
        return ", ".join([self.work_dims()] + extra)

    def checks(self, fn):
        """The argument checks of a function in parameter order, as
        (kind, name, n): kind in default_p, default_r (NULL takes the
        default, which is finite by construction; a given array is checked
        like in), in, real, out, null."""
        out = []
        for a in fn.params:
            n = self.size(a.size)
            if a.role == "in?":
                out.append(("default_" + a.default, a.name, n))
            elif a.role in ("in", "inout"):
                out.append(("in", a.name, n))
            elif a.role == "scalar":
                out.append(("real", a.name, 0))
            elif a.role == "out" and n > 0:
                out.append(("out", a.name, n))
            elif a.role in ("rows", "struct", "struct_out"):
                out.append(("null", a.name, 0))
            elif a.role == "struct?":
                out.append(("default_opts", a.name, 0))
        return out


def interface(model, real="double", accel="lu"):
    """The Interface of a canonical model (gen.Model); accel: the Plan's."""
    m = model
    sizes = {"NQ": m.nq, "NU": m.nu, "NX": m.nx, "NR": m.nr, "NP": m.np, "MC": m.mc,
             "MV": m.mv, "NS": m.ns, "NA": getattr(m, "na", 0), "NY": getattr(m, "ny", 0),
             "NH": len(getattr(m, "hybrid", None) or [])}
    return Interface(
        name=m.name, real=real, method=m.method, sizes=sizes,
        state_names=list(m.state_names), state_labels=list(m.state_labels),
        input_names=list(m.input_names), input_labels=list(m.input_labels),
        constant_names=list(m.constant_names), constant_labels=list(m.constant_labels),
        independent_state_names=list(m.independent_state_names),
        q_ind=list(m.q_ind), q_dep=list(m.q_dep), u_ind=list(m.u_ind), u_dep=list(m.u_dep),
        constants=[float(v) for v in m.p_values], has_energy=m.energy is not None,
        explicit_kinematics=m.qdot is not None,
        accel=accel, functions=FUNCTIONS, batch_functions=BATCH_FUNCTIONS,
        structs=check_structs(STRUCTS), statuses=tuple(STATUSES),
        auxiliary_names=list(getattr(m, "auxiliary_names", [])),
        auxiliary_labels=list(getattr(m, "auxiliary_labels", [])),
        output_names=list(getattr(m, "output_names", [])),
        output_labels=list(getattr(m, "output_labels", [])),
        hybrid_names=[d.name for d in getattr(m, "hybrid", [])],
        hybrid_kinds=[d.kind for d in getattr(m, "hybrid", [])])


def host_interface(real="double"):
    """The Interface of the Python host module (gen.build): the shared
    description under the prefix "eomgen", for models of every size."""
    sizes = {k: 0 for k in ("NQ", "NU", "NX", "NR", "NP", "MC", "MV", "NS", "NA", "NY", "NH")}
    return Interface(
        name="eomgen", real=real, method="", sizes=sizes, state_names=[], state_labels=[],
        input_names=[], input_labels=[], constant_names=[], constant_labels=[],
        independent_state_names=[], q_ind=[], q_dep=[], u_ind=[], u_dep=[], constants=[],
        has_energy=False, explicit_kinematics=True, accel="lu", functions=FUNCTIONS,
        batch_functions=BATCH_FUNCTIONS, structs=check_structs(STRUCTS))


# the functions that call the derivative kernels (<name>_lin.c): a model
# compiled without them (gen.compile builds them on first use) must have them
# before these run; advance and the simulations need them only with RODAS4
DERIVATIVE_VERBS = frozenset({"linearize", "jacobian", "step_sensitivity", "linearize_outputs",
                              "linearize_discrete", "linearize_batch"})
