"""The tracker product's backend: a trajectory tracker's const tables
(gen.TrajectoryTracker.to_c)."""
from __future__ import annotations

import math

import numpy as np

from ...core.errors import BuildError
from .base import ProductBackend
from ..product_abi import CConst, CFunction, ProductInterface
from ..templating import fmt_real

class TrackerBackend(ProductBackend):
    """A trajectory tracker's C (gen.TrajectoryTracker.to_c,
    gen/design/tracking.py): the reference and the gain schedule as const
    tables in <name>.c, its <name>_input and <name>_step over the model
    library's <p>_eval_input. It is compiled with its model's sources (a
    generated project, a firmware), never alone: rendered only."""
    name = "tracker"
    tag = "_tracker"
    templates = (("{name}.c", "tracker/tracker.c.j2", "product"),)
    interface = ProductInterface(
        product="tracker",
        doc="trajectory tracker of the model '{p}'",
        includes=('"{p}.h"',),
        macros=(
            CConst("{N}_N_GAIN", "{n_gain}",
                   "rows of the tables (the last: the terminal gain, held after the end)"),
            CConst("{N}_T0", "(({p}_real){t0})", "the time of row 0: {t0_text}"),
            CConst("{N}_PERIOD", "(({p}_real){period})",
                   "the sample period, the time between rows: {period_text}"),
            CConst("{N}_TABLE_BYTES", "{flash}",
                   "bytes of the const tables (flash): {table_bytes}")),
        functions=(
            CFunction("{name}_input", "void", (("{p}_input *", "in"),),
                      "Fill in (every field) with the tracker: the gain schedule and its "
                      "period."),
            CFunction("{name}_step", "int", (("{p}_real", "t"), ("const {p}_real *", "x"),
                                             ("{p}_real *", "r")),
                      "The inputs r ({P}_NR) at the sample time t from the state x "
                      "({P}_NX); 0 or a negative {P}_ERR_* status.")))

    def file_templates(self, iface):
        # its header's prose is its own (how to run it on a controller)
        return [("{name}.h", "tracker/tracker.h.j2", "product"), *self.templates]

    def names(self, plan, real):
        d = plan.data
        fp = d["footprint"]
        table = ", ".join(f"{k} {fp[k]}" for k in ("K", "x_ref", "r_ref", "bounds") if fp[k])
        return {**super().names(plan, real), "N": plan.name.upper(), "P": d["model"].upper(),
                "n_gain": d["n_gain"], "t0": fmt_real(d["t0"], real),
                "t0_text": repr(float(d["t0"])), "period": fmt_real(d["period"], real),
                "period_text": repr(float(d["period"])), "flash": fp["flash"],
                "table_bytes": table}

    def context(self, plan, iface, real):
        """The tables as rows of C literals (an infinite bound as HUGE_VAL)."""
        d = plan.data
        huge = "HUGE_VALF" if real == "float" else "HUGE_VAL"

        def lit(v):
            return fmt_real(v, real) if math.isfinite(v) else ("-" if v < 0 else "") + huge

        def rows(a, per):
            flat = [lit(float(v)) for v in np.asarray(a, dtype=float).ravel()]
            return [", ".join(flat[i:i + per]) for i in range(0, len(flat), per)]
        nr = d["nr"]
        return {"N": plan.name.upper(), "p": d["model"], "P": d["model"].upper(),
                "K_rows": rows(d["K"], d["ns"]), "x_rows": rows(d["x_op"], d["nx"]),
                "r_rows": rows(d["r_op"], max(nr, 1)),
                "r_min": None if d["r_min"] is None else rows(d["r_min"], nr)[0],
                "r_max": None if d["r_max"] is None else rows(d["r_max"], nr)[0]}

    def units(self, name, files, derivatives, includes=()):
        raise BuildError(f"the tracker {name!r} is compiled with its model's sources "
                         "(gen.generate, then TrajectoryTracker.to_c into the same folder), "
                         "not alone")
