"""A trajectory that ends on an event, and periodic trajectories (issue 46):
``gen.OptimalControl(..., events=[name], periodic=True)``.

The phase ends on the event's guard: ``guard(x[N-1]) = 0`` at the last
node, crossing in the event's direction (the guard's rate through the last
node's slopes, ``dg/dt >= 0`` upwards, ``<= 0`` downwards), and the event's
map carries the state across it: with ``periodic=True``, the state after
the map is the initial state, ``x[0] = map(x[N-1])`` (a limit cycle; the
passive walker's gait); without an event, ``periodic=True`` asks
``x[0] = x[N-1]``. Each is a family of generated kernels like the rest of
the transcription (values, Jacobian, exact Hessian). The guard is held at
the last node only: a crossing earlier in the phase is not excluded (the
walker's swing foot scuffs through its guard at mid-stance, downwards).

One event (one phase) for now, a ``gen.Reset`` on an unconstrained model;
several events (a phase each, its own duration), impacts and constrained
models are refused with the reason.
"""
from __future__ import annotations

import warnings

import numpy as np
import sympy as sm

from ...core.errors import InputError
from ...intake.hybrid import KIND_RESET

__all__ = ["Phase", "read_events", "event_families", "assemble_events", "solution_phases"]

BIG = 1e20


class Phase:
    """One phase of a solution: its node times ``t``, states ``x`` and
    inputs ``r``, the ``event`` that ends it (a name, or None) and
    ``x_after``, the state after the event's map (None without an event)."""

    def __init__(self, t, x, r, event, x_after):
        self.t, self.x, self.r, self.event, self.x_after = t, x, r, event, x_after

    def __repr__(self):
        return (f"Phase(t=[{self.t[0]:.6g}, {self.t[-1]:.6g}], nodes={len(self.t)}, "
                f"event={self.event!r})")


def read_events(ocp, events, periodic):
    """(the HybridDecl of the one event or None, periodic as a bool) of
    OptimalControl's events= and periodic=, refused naming the reason."""
    m = ocp.model
    if not isinstance(periodic, (bool, np.bool_)):
        raise InputError(f"periodic must be True or False, got {periodic!r}")
    decls = {d.name: d for d in (getattr(m, "hybrid", None) or [])}
    if events is None:
        events = []
    if isinstance(events, str) or not isinstance(events, (list, tuple)):
        raise InputError(f"events must be a list of model {m.name!r}'s hybrid names, got "
                         f"{events!r}")
    for e in events:
        if e not in decls:
            known = ", ".join(decls) or "none: the model has no hybrid declarations"
            raise InputError(f"events: {e!r} is not a hybrid declaration of model {m.name!r} "
                             f"(its declarations: {known})")
    if len(events) > 1:
        raise InputError(f"events={list(events)!r}: one event (one phase) is supported so far; "
                         "a sequence of phases is not")
    if (events or periodic) and (m.mc or m.mv):
        raise InputError(f"events and periodic: model {m.name!r} has constraints; ending on an "
                         "event or a periodic trajectory is supported on unconstrained models")
    if events and ocp.method == "midpoint":
        raise InputError("events: the guard's crossing is checked through the last node's "
                         "slopes, which method='midpoint' has not; use 'hermite-simpson', "
                         "'trapezoidal' or 'backward-euler'")
    if decls and not events:
        warnings.warn(f"model {m.name!r} has hybrid declarations ({', '.join(decls)}) that "
                      "events= does not name: the trajectory is optimised as if they were not "
                      "there, and may cross their guards without their jumps",
                      UserWarning, stacklevel=3)
    d = decls[events[0]] if events else None
    if d is not None and d.kind != KIND_RESET:
        raise InputError(f"events: {d.name!r} is a gen.Impact; ending a phase on an impact is "
                         "not supported yet (declare its jump as a gen.Reset)")
    return d, bool(periodic)


def event_families(m, pf, decl, periodic):
    """The families (name, locals, expressions) of the event's guard, its
    rate and the periodicity."""
    q, u, t = list(m.q), list(m.u), m.t
    x = q + u
    out = []
    if decl is not None:
        g = decl.expr
        out.append(("guard", x + pf + [t], [g]))
        if decl.direction:
            qd = [sm.Dummy(f"qd{i}") for i in range(m.nq)]
            ud = [sm.Dummy(f"ud{i}") for i in range(m.nu)]
            rate = (sum((g.diff(a) * b for a, b in zip(q, qd)), sm.S.Zero)
                    + sum((g.diff(a) * b for a, b in zip(u, ud)), sm.S.Zero) + g.diff(t))
            out.append(("guard_rate", x + qd + ud + pf + [t], [rate]))
    if periodic:
        xa = [sm.Dummy(f"xa{i}") for i in range(len(x))]
        after = list(decl.xmap) if decl is not None else x
        out.append(("periodic", x + xa + pf + [t], [a - b for a, b in zip(xa, after)]))
    return out


def assemble_events(a, ocp):
    """The event rows at the last node and the periodicity's (x[0] against
    the state after the map at x[N-1])."""
    lay, N = a.lay, ocp.nodes
    last = [(lay.X[N - 1], 1.0)]
    if "guard" in a.fams:
        f = a.fam("guard")
        a.block("guard").add(a.gather(f, last, [], 1.0), row0=a.con_rows(f))
    if "guard_rate" in a.fams:
        f = a.fam("guard_rate")
        lo, hi = ([0.0], [BIG]) if ocp._event.direction > 0 else ([-BIG], [0.0])
        a.block("guard_rate").add(a.gather(f, last, [], 1.0, lay.node_point[N - 1][0]),
                                  row0=a.con_rows(f, lo, hi))
    if "periodic" in a.fams:
        f = a.fam("periodic")
        ex = {("xa", i): [(int(j), 1.0)] for i, j in enumerate(lay.X[0])}
        a.block("periodic").add(a.gather(f, last, [], 1.0, extra=ex), row0=a.con_rows(f))


def solution_phases(ocp, sol):
    """The phases of a solution: one, ending on the event (its state after
    the map evaluated from the model's own map)."""
    d = ocp._event
    x_after = None
    if d is not None:
        m = ocp.model
        args = list(m.q) + list(m.u) + list(m.p) + [m.t]
        f = sm.lambdify(args, list(d.xmap), modules="numpy")
        x_after = np.array(f(*sol.x[-1], *sol.constants, sol.t[-1]), float)
    return [Phase(sol.t, sol.x, sol.r, None if d is None else d.name, x_after)]
