"""The estimator product's backend: a Kalman filter's library (gen.EKF,
gen.UKF, gen/design/estimator): the filter model's C sources (the model
with its estimated constants promoted to coordinates, rendered by the C
backend), the generated measurement kernels and the workspace's wiring in
<name>.c, over the hand-written filters of csrc/products/estimator
(gen_rt_kalman.c) and the shared runtime."""
from __future__ import annotations

from .base import C_FLAGS, C_LIN_FLAGS, RUNTIME_SOURCES, ProductBackend, c_compiler
from ..product_abi import CConst, CEnum, CFunction, ProductInterface

__all__ = ["EstimatorBackend", "LAYOUT"]

#: the entries of <name>_layout's out array, in order: the workspace's size,
#: then the offsets of its arrays and scalars (the Python face's views)
LAYOUT = ("size", "x", "xf", "P", "Q", "R", "params", "inputs", "y", "S", "status", "rejected", "t",
          "period", "gate", "alpha", "beta", "kappa", "kind", "substeps", "theta",
          "noise_sd", "count", "n_predict", "n_update")

# the workspace's member of each layout entry (the others: the same name)
_MEMBERS = {"params": "p", "inputs": "r", "t": "k.t", "period": "k.period", "gate": "k.gate",
            "alpha": "k.alpha", "beta": "k.beta", "kappa": "k.kappa", "kind": "k.kind",
            "substeps": "k.substeps", "count": "loop.count", "n_predict": "k.n_predict",
            "n_update": "k.n_update"}

_WS = ("void *", "ws")


def _fn(name, params, doc):
    return CFunction(name, "int", params, doc)


class EstimatorBackend(ProductBackend):
    """A Kalman filter's library: the filter model's sources (plan.files),
    <name>.c (the measurement kernels, the workspace's layout and the
    functions below over gen_rt_kalman.c) and <name>.h (the workspace
    struct, static in a firmware), compiled with the shared runtime's
    objects. The model's files and the filters are hidden: the library
    exports <name>_* only."""
    name = "estimator"
    tag = "_est"
    templates = (("{name}.c", "estimator/estimator.c.j2", "product"),)
    runtime_files = ("gen_rt_kalman.c", "gen_rt_kalman.h")
    runtime_sources = tuple(RUNTIME_SOURCES)
    interface = ProductInterface(
        product="estimator",
        doc="a Kalman filter over the model '{model}' (gen.EKF / gen.UKF)",
        includes=("<stdint.h>",),
        enums=(CEnum("the entries of {name}_layout's out: the workspace's size, then the "
                     "offsets of its fields", tuple(
                         CConst(f"{{N}}_AT_{k.upper()}", i) for i, k in enumerate(LAYOUT))
                     + (CConst("{N}_AT_END", len(LAYOUT), "the number of entries"),)),),
        functions=(
            _fn("{name}_layout", (("long *", "out"), ("int", "len")),
                "The workspace's size and the offsets of its fields ({N}_AT_*; out holds "
                "len >= {N}_AT_END entries). Returns 0 or GEN_RT_ERR_BAD_ARG."),
            _fn("{name}_init", (_WS,),
                "Wire a workspace ({name}_workspace, the caller's: static, on the stack or "
                "allocated): zero it, the constants at the model's values, an EKF with one "
                "substep. Set the period, x, P, Q, R (and the settings), then {name}_start."),
            _fn("{name}_start", (_WS,),
                "Start (or restart) the filter from the workspace's x, P and settings "
                "(gen_rt_kalman_start): the dependent entries of x completed."),
            _fn("{name}_predict", (_WS, ("const {real} *", "r")),
                "One prediction over the period with the inputs r (NR) held."),
            _fn("{name}_update", (_WS, ("const {real} *", "z")),
                "One update with the measurements z (NZ; NaN: missing): the innovations, "
                "their variances and statuses in the workspace."),
            _fn("{name}_step", (_WS, ("const {real} *", "z"), ("const {real} *", "r")),
                "{name}_predict(ws, r) then {name}_update(ws, z)."),
            _fn("{name}_run", (_WS, ("int", "rows"), ("const {real} *", "Z"),
                               ("const {real} *", "Rin"), ("{real} *", "X"),
                               ("{real} *", "Xfull"), ("{real} *", "P"), ("{real} *", "Y"),
                               ("int *", "status"), ("int *", "done")),
                "A recording (gen_rt_kalman_run): row 0 updates with Z[0], row i > 0 "
                "predicts with Rin[i - 1], then updates with Z[i]; the outputs per row "
                "(each may be NULL)."),
            _fn("{name}_law", (_WS, ("const {real} *", "K"), ("const {real} *", "x_op"),
                               ("const {real} *", "r_op"), ("const {real} *", "r_min"),
                               ("const {real} *", "r_max"), ("int", "n_gain"),
                               ("{real}", "t_gain"), ("{real}", "dt_gain")),
                "The closed loop's feedback on the estimate (a gen_rt_input on the filter's "
                "model: K on its independent state, x_op its full state; the arrays stay "
                "the caller's)."),
            _fn("{name}_inner", (_WS, ("uintptr_t", "fn"), ("void *", "ctx")),
                "Or a controller in C (a gen_rt_controller_fn's address) called on the "
                "estimate in the plant's layout."),
            _fn("{name}_loop", (_WS, ("uint64_t", "seed"), ("int", "capacity"),
                                ("{real} *", "log_t"), ("{real} *", "log_x"),
                                ("{real} *", "log_sd")),
                "Reset the closed loop: the noise generator seeded, the log (capacity rows "
                "of t, the filter state and its standard deviations; 0: none)."),
            _fn("{name}_control", (("void *", "ws"), ("{real}", "t"), ("const {real} *", "x"),
                                   ("{real} *", "r")),
                "The closed loop as the engine's controller (gen_rt_controller_fn, context "
                "the workspace): measure x, filter, set r (gen_rt_kalman_control)."),
        ))

    def names(self, plan, real):
        return {**super().names(plan, real), "model": plan.data["model"],
                "N": plan.name.upper(), "real": real}

    def context(self, plan, iface, real):
        d = plan.data
        mx = lambda n: max(1, int(n))  # noqa: E731  (C99: no zero-length arrays)
        return {"N": plan.name.upper(), "layout": [(k, _MEMBERS.get(k, k)) for k in LAYOUT[1:]],
                "sz": {"nx": mx(d["nx"]), "ns": mx(d["ns"]), "ns2": mx(d["ns"] ** 2),
                       "nz": mx(d["nz"]), "np": mx(d["np"]), "nr": mx(d["nr"]),
                       "ne": mx(d["ne"])},
                "has_defaults": "defaults" in d}

    def file_templates(self, iface):
        # its own header: the interface's declarations and the workspace
        # struct, whose array sizes are the runtime's macros
        return list(self.templates) + [("{name}.h", "estimator/estimator.h.j2", "product")]

    def cache_parts(self):
        return [*super().cache_parts(), "hidden:" + " ".join(C_LIN_FLAGS)]

    def units(self, name, files, derivatives, includes=()):
        """The model's files (its derivative kernels at -O1) and the
        filters hidden, <name>.c exporting the library's functions; the
        runtime's objects are the shared ones."""
        cc = c_compiler()
        own = sorted((f for f in files if f.endswith(".c") and f not in RUNTIME_SOURCES),
                     key=lambda f: (-len(files[f].encode()), f))
        out = []
        for f in own:
            flags = [*C_FLAGS, "-fPIC"]
            if f != f"{name}.c":
                flags.append("-fvisibility=hidden")
            if f.endswith("_lin.c"):
                flags += C_LIN_FLAGS
            out.append((f, cc, flags))
        return out
