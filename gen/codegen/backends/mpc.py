"""The model predictive controller's backend (gen.MPC, gen/design/mpc):
the problem's data as const tables and its path constraints' and
residuals' kernels in <name>.c, over the hand-written real-time iterations
and QP solver (csrc/products/mpc: gen_rt_mpc.c, gen_rt_qp.c), calling the
model's own C (its <p>_step_sensitivity, <p>_consistent_state).

The library gen.MPC loads holds the model's C sources too (the plan's
files, rendered by the C backend): the same <name>.c runs in Python, in
sim.simulate's engine (<name>_controller, a gen_rt_controller_fn) and, with
the model's generated project, in a firmware (gen.MPC.to_c)."""
from __future__ import annotations

from .base import (C_FLAGS, C_LIN_FLAGS, RUNTIME_SOURCES, ProductBackend, c_compiler)
from ..product_abi import (CConst, CField, CFunction, CStruct, CTypedef, ProductInterface)

__all__ = ["MpcBackend", "MPC_RUNTIME"]

#: the MPC's hand-written runtime (csrc/products/mpc)
MPC_RUNTIME = ("gen_rt_mpc.c", "gen_rt_mpc.h", "gen_rt_qp.c", "gen_rt_qp.h",
               "gen_rt_mpc_status.h")

_MEM = "{name}_memory *"


class MpcBackend(ProductBackend):
    """A model predictive controller's library: <name>.c (the problem as
    const data, its kernels, the wiring to the model and to the runtime),
    its header, the MPC runtime, and, loaded by gen.MPC, the model's C
    sources (ProductPlan.files) compiled into the same library with hidden
    symbols, so that only the controller's functions are exported."""
    name = "mpc"
    tag = "_mpc"
    templates = (("{name}.c", "mpc/mpc.c.j2", "product"),)
    runtime_files = MPC_RUNTIME
    runtime_sources = tuple(RUNTIME_SOURCES)
    interface = ProductInterface(
        product="mpc",
        doc="model predictive controller of the model '{p}' (real-time iterations)",
        includes=('"{p}.h"', '"gen_rt_mpc.h"'),
        typedefs=(CTypedef("{name}_clock", "double (*{name}_clock)(void *ctx)",
                           "A monotonic clock in seconds (a cycle counter on a "
                           "microcontroller)."),),
        structs=(
            CStruct("{name}_memory", "The controller's memory: its options, the state kept "
                    "between calls and its workspace ({name}_memory_size() bytes; completed "
                    "below, for a static instance).", None),
            CStruct("{name}_info", "The outcome of the last call.", (
                CField("status", "int", "0, a positive {N}_* outcome or a negative error"),
                CField("qp_status", "int", "the last QP's"),
                CField("iterations", "int", "SQP iterations"),
                CField("qp_iterations", "int", "interior-point iterations, all QPs"),
                CField("t_prepare", "double", "seconds in the preparation phase (0: no clock)"),
                CField("t_feedback", "double", "seconds in the feedback phase"),
                CField("objective", "double", "the last QP's objective")))),
        macros=(
            CConst("{N}_HORIZON", "{horizon}", "shooting intervals N"),
            CConst("{N}_NX", "{nx}", "the model's full state"),
            CConst("{N}_NS", "{ns}", "the independent state (the cost's, the QP's)"),
            CConst("{N}_NR", "{nr}", "inputs"),
            CConst("{N}_PERIOD", "(({real}){period})", "the sample period: {period_text} s"),
            CConst("{N}_WORK_LEN", "GEN_RT_MPC_WORK({nx}, {ns}, {nr}, {horizon}, {nbx}, {nbu}, "
                   "{nh}, {ny})", "reals of workspace")),
        functions=(
            CFunction("{name}_memory_size", "int", (), "sizeof({name}_memory)."),
            CFunction("{name}_init", "int", ((_MEM, "mem"),),
                      "Fill mem with the generated options ({method}, max_iter {max_iter}, "
                      "time limit {time_limit_text}) and no iterate: the next call starts "
                      "from {start}."),
            CFunction("{name}_set_options", "int", (
                (_MEM, "mem"), ("int", "sqp"), ("int", "max_iter"), ("double", "tol"),
                ("double", "time_limit"), ("int", "qp_max_iter"), ("double", "qp_tol")),
                "Options: sqp (0: one iteration per call, 1: to convergence), its max_iter "
                "and step tolerance, the time budget of a call in seconds (<= 0: none; it "
                "needs a clock), the QP's iteration cap and tolerance."),
            CFunction("{name}_set_clock", "int", ((_MEM, "mem"), ("{name}_clock", "clock"),
                                                  ("void *", "clock_ctx")),
                      "The clock of the times and the time limit (NULL: none)."),
            CFunction("{name}_set_guess", "int", ((_MEM, "mem"), ("const {real} *", "x"),
                                                  ("const {real} *", "u")),
                      "The next call starts from x ((N + 1) x NX) and u (N x NR) (NULL: zero)."),
            CFunction("{name}_reset", "int", ((_MEM, "mem"),),
                      "Forget the iterate: the next call starts from {start}."),
            CFunction("{name}_prepare", "int", ((_MEM, "mem"), ("{real}", "t")),
                      "The preparation phase for the call at t: the last solution shifted, "
                      "the model's steps and sensitivities along it, the QP's data."),
            CFunction("{name}_feedback", "int", ((_MEM, "mem"), ("const {real} *", "x"),
                                                 ("{real} *", "u")),
                      "The feedback phase: the state x (NX) in, the control u (NR) out."),
            CFunction("{name}_step", "int", ((_MEM, "mem"), ("{real}", "t"),
                                             ("const {real} *", "x"), ("{real} *", "u")),
                      "One call at t: preparation (unless done for t) and feedback; u (NR) "
                      "is never NaN. 0 or a positive outcome: the control; negative: a "
                      "failure, u the previous solution's, shifted."),
            CFunction("{name}_controller", "int", (("void *", "mem"), ("{real}", "t"),
                                                   ("const {real} *", "x"), ("{real} *", "r")),
                      "{name}_step as a controller of the model's simulate_input (a "
                      "{p}_controller with ctx the memory): nonzero on a failure."),
            CFunction("{name}_solution", "int", (("const {name}_memory *", "mem"),
                                                 ("{real} *", "x"), ("{real} *", "u")),
                      "The predicted states x ((N + 1) x NX) and inputs u (N x NR)."),
            CFunction("{name}_get_info", "int", (("const {name}_memory *", "mem"),
                                             ("{name}_info *", "info")),
                      "The outcome of the last call."),
            CFunction("{name}_status_message", "const char *", (("int", "status"),),
                      "The message of a status.")))

    def file_templates(self, iface):
        # its header is its own (the memory's definition, how to run it)
        return [("{name}.h", "mpc/mpc.h.j2", "product"), *self.templates]

    def names(self, plan, real):
        d = plan.data
        return {**super().names(plan, real), "N": plan.name.upper(), "P": d["model"].upper(),
                "real": real, "horizon": d["N"], "nx": d["nx"], "ns": d["ns"], "nr": d["nr"],
                "period": repr(float(d["period"])), "period_text": repr(float(d["period"])),
                "nbx": d["nbx"], "nbu": d["nbu"], "nh": d["nh"], "ny": d["ny_"],
                "method": d["method"], "max_iter": d["max_iter"],
                "time_limit_text": (f"{d['time_limit']!r} s" if d["time_limit"] else "none"),
                "start": ("the measured state at every node" if d["constrained"]
                          else "zero states and inputs")}

    def context(self, plan, iface, real):
        """The tables as rows of C literals (an infinite bound as HUGE_VAL)."""
        from ..templating import fmt_real
        import math
        d = plan.data

        def lit(v):
            v = float(v)
            if math.isfinite(v):
                return fmt_real(v, real)
            # beyond GEN_RT_QP_INF: no bound
            return ("-" if v < 0 else "") + fmt_real(1e300 if real == "double" else 1e38, real)

        def row(a):
            return ", ".join(lit(v) for v in a) if len(a) else "0"
        tables = {k: row(d[k]) for k in ("Q", "R", "P", "W", "lbx", "ubx", "zx", "lbu", "ubu",
                                          "lh", "uh", "zh", "x_ref", "u_ref", "p")}
        ints = {k: ", ".join(str(int(v)) for v in d[k]) if len(d[k]) else "0"
                for k in ("ind", "idxbx", "idxbu")}
        return {"N": plan.name.upper(), "N_": d["N"], "p": d["model"], "P": d["model"].upper(),
                "period_text": repr(float(d["period"])),
                "t": tables, "i": ints, "lit_t_ref": fmt_real(d["t_ref"], real),
                "lit_dt_ref": fmt_real(d["dt_ref"], real),
                "lit_period": fmt_real(d["period"], real),
                "lit_tol": fmt_real(d["tol"], real), "lit_qp_tol": fmt_real(d["qp_tol"], real)}

    def cache_parts(self):
        return [*super().cache_parts(), "mpc: -DGEN_RT_MPC_POSIX_CLOCK, hidden model"]

    def units(self, name, files, derivatives, includes=()):
        """<name>.c exported, with the host's monotonic clock; the model's
        sources and the MPC runtime hidden (the library exports only the
        controller); the derivative kernels at -O1 as the C backend's."""
        cc = c_compiler()
        own = sorted((f for f in files if f.endswith(".c") and f not in RUNTIME_SOURCES),
                     key=lambda f: (-len(files[f].encode()), f))
        out = []
        for f in own:
            if f == f"{name}.c":
                flags = [*C_FLAGS, "-fPIC", "-DGEN_RT_MPC_POSIX_CLOCK"]
            else:
                flags = [*C_FLAGS, "-fPIC", "-fvisibility=hidden",
                         *(C_LIN_FLAGS if f.endswith("_lin.c") else [])]
            out.append((f, cc, flags))
        return out
