"""What the eomgen command line shows and writes: the progress display on
stderr, labelled matrices and eigenvalues, trajectories as CSV (file or
stdout) and as a PNG plot (matplotlib). gen.cli parses the arguments and
runs the subcommands; it calls these for their output.
"""
from __future__ import annotations

import sys
import time

from ..core.optional import require

__all__ = ["Progress", "format_matrix", "print_linearization", "write_csv", "print_csv",
           "write_events_csv", "print_events", "plot_simulation"]


# --------------------------------------------------------------- progress
class Progress:
    """Stage lines on stderr: shown while running on a terminal, silent
    when stderr is not a terminal or with --quiet; --verbose prints every
    stage with its time (even when not a terminal)."""

    def __init__(self, quiet=False, verbose=False, stream=None):
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.quiet = quiet
        self.verbose = verbose and not quiet
        self.live = self.tty and not quiet
        self.times = []

    def stage(self, name):
        return _Stage(self, name)

    def record(self, name, seconds):
        self.times.append((name, seconds))
        if self.verbose:
            print(f"eomgen: {name:<34} {seconds:8.2f} s", file=self.stream)

    def summary(self):
        if self.verbose and self.times:
            total = sum(t for _, t in self.times)
            print(f"eomgen: {'total':<34} {total:8.2f} s", file=self.stream)


class _Stage:
    def __init__(self, progress, name):
        self.p = progress
        self.name = name

    def __enter__(self):
        self.t0 = time.perf_counter()
        if self.p.live and not self.p.verbose:
            print(f"\reomgen: {self.name} ...\033[K", end="", file=self.p.stream, flush=True)
        return self

    def __exit__(self, *exc):
        dt = time.perf_counter() - self.t0
        if self.p.live and not self.p.verbose:
            print("\r\033[K", end="", file=self.p.stream, flush=True)
        if exc[0] is None:
            self.p.record(self.name, dt)
        return False


# ---------------------------------------------------------- matrices, CSV
def format_matrix(rows, cols, M, w):
    """M as text, labelled: the column names on top, each row's name (in a
    column w wide) first; -0 printed as 0."""
    out = [" " * w + "".join(f"{c:>16}" for c in cols)]
    for name, row in zip(rows, M):
        out.append(f"{name:<{w}}" + "".join(f"{v + 0.0:16.9g}" for v in row))  # no -0
    return "\n".join(out)


def print_linearization(sim, x, r, A, B, discrete=None):
    """The operating point, A and B labelled by state and input names, and
    the eigenvalues of A (sorted; no negative zeros); with discrete =
    (dt, Ad, Bd) also the zero-order-hold discretization."""
    import numpy as np
    names = sim.independent_state_names
    w = max(len(n) for n in names + sim.input_names + ["x"]) + 2
    print("operating point:", ", ".join(f"{n}={v:.12g}" for n, v in zip(sim.state_names, x)))
    if sim.nr:
        print("inputs:", ", ".join(f"{n}={v:.12g}" for n, v in zip(sim.input_names, r)))
    print("A =")
    print(format_matrix(names, names, A, w))
    print("B =" + (" (no inputs)" if sim.nr == 0 else ""))
    if sim.nr:
        print(format_matrix(names, sim.input_names, B, w))
    ev = np.linalg.eigvals(A)
    ev = ev[np.lexsort((ev.imag, ev.real))]
    print("eigenvalues of A:", "  ".join(f"{e.real + 0.0:.9g}{e.imag + 0.0:+.9g}j" for e in ev))
    if discrete is not None:
        dt, Ad, Bd = discrete
        print(f"zero-order hold, dt = {dt:g}:")
        print("Ad =")
        print(format_matrix(names, names, Ad, w))
        print("Bd =" + (" (no inputs)" if sim.nr == 0 else ""))
        if sim.nr:
            print(format_matrix(names, sim.input_names, Bd, w))


def write_csv(path, sim, cols, data, lam, res_names, res, E, aux=None, aux_names=None):
    """The trajectory as CSV: the columns cols of data, then the multipliers
    (when the model has velocity constraints), the constraint residuals, the
    energy when present and the reaction forces of the auxiliary speeds
    (aux: rows of sim.auxiliary_names, as the standalone binary writes)."""
    import numpy as np
    extra = [lam] if sim.mv else []
    names = list(sim.auxiliary_names) if aux_names is None else list(aux_names)
    has_aux = aux is not None and len(names) > 0
    table = np.hstack(data + extra + res + ([E[:, None]] if E is not None else [])
                      + ([aux] if has_aux else []))
    header = cols + [f"lam{i}" for i in range(sim.mv)] + res_names + \
        (["energy"] if E is not None else []) + (names if has_aux else [])
    with open(path, "w") as fh:
        fh.write(",".join(header) + "\n")
        for row in table:
            fh.write(",".join(f"{v:.17g}" for v in row) + "\n")


def print_csv(cols, table):
    """Rows of numbers as CSV on stdout (full precision)."""
    print(",".join(cols))
    for row in table:
        print(",".join(f"{v:.17g}" for v in row))


def write_events_csv(path, state_names, events):
    """Events [(name, t, x)] as CSV 'event,t,<state names>', one row each
    (the standalone binary's --events-csv)."""
    with open(path, "w") as fh:
        fh.write(",".join(["event", "t"] + list(state_names)) + "\n")
        for name, t, x in events:
            fh.write(",".join([name, f"{t:.17g}"] + [f"{v:.17g}" for v in x]) + "\n")


def print_events(state_names, events, stream=None):
    """Events [(name, t, x)] one line each, 'event NAME t=T q1=... ...', on
    stderr (the standalone binary's default)."""
    stream = stream or sys.stderr
    for name, t, x in events:
        print(f"event {name} t={t:.17g} "
              + " ".join(f"{n}={v:.17g}" for n, v in zip(state_names, x)), file=stream)


# ------------------------------------------------------------------- plot
def plot_simulation(path, m, sim, t, X, res_names, res, E, Y=None, R=None):
    """A PNG of the states, the outputs, the inputs (when they vary), the
    constraint residuals (log scale) and the relative energy error, one
    panel each (those present). A gen.MissingDependencyError without
    matplotlib (the command line reports it as a usage error)."""
    matplotlib = require("matplotlib", "--plot")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    has_y = Y is not None and sim.ny > 0
    has_r = R is not None and sim.nr > 0
    panels = 1 + has_y + has_r + bool(res) + (E is not None)
    fig, axes = plt.subplots(panels, 1, figsize=(8, 2.6 * panels + 0.6), sharex=True,
                             squeeze=False)
    axes = axes[:, 0]
    ax = axes[0]
    for i, n in enumerate(sim.state_names):
        ax.plot(t, X[:, i], label=n, lw=1.2, ls="-" if i < sim.nq else "--")
    ax.set_ylabel("state")
    ax.legend(loc="upper right", ncol=min(4, sim.nx), fontsize=8)
    ax.set_title(f"{m.name}: simulation ({m.method}, nq={sim.nq}, nu={sim.nu}, "
                 f"{sim.mc} configuration / {sim.mv} velocity constraints)", fontsize=10)
    k = 1
    for show, data, names, label in ((has_y, Y, sim.output_names, "output"),
                                     (has_r, R, sim.input_names, "input")):
        if not show:
            continue
        ax = axes[k]
        k += 1
        for i, n in enumerate(names):
            ax.plot(t, data[:, i], label=n, lw=1.2)
        ax.set_ylabel(label)
        ax.legend(loc="upper right", ncol=min(4, len(names)), fontsize=8)
    if res:
        ax = axes[k]
        k += 1
        R = np.hstack(res)
        floor = 1e-17                      # exact zeros drawn at the floor
        for i, n in enumerate(res_names):
            ax.semilogy(t, np.maximum(np.abs(R[:, i]), floor), label=f"|{n}|", lw=1)
        ax.set_ylim(floor / 2, max(1e-12, 10 * float(np.max(np.abs(R)))))
        ax.set_ylabel("constraint residual")
        ax.legend(loc="upper right", ncol=4, fontsize=8)
    if E is not None:
        ax = axes[k]
        scale = max(abs(E[0]), 1e-300)
        ax.plot(t, (E - E[0]) / scale, lw=1, color="k")
        ax.set_ylabel("(E - E0) / |E0|")
    axes[-1].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
