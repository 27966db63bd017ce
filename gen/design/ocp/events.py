"""Trajectories across events, and periodic trajectories (issue 46):
``gen.OptimalControl(..., events=[e1, e2, ...], periodic=True)``.

One phase per event, each of N nodes and its own duration (free within
the duration's bounds). Phase j ends on its event's guard:
``guard(x_j[N-1]) = 0`` at its last node, crossing in the event's
direction (the guard's rate through the last node's slopes, ``dg/dt >= 0``
upwards, ``<= 0`` downwards), and the event's map carries the state into
the next phase, ``x_j+1[0] = map(x_j[N-1])``; with ``periodic=True`` the
state after the last event's map is the initial state (a limit cycle; the
passive walker's gait, the rimless wheel's steady state); without an
event, ``periodic=True`` asks ``x[0] = x[N-1]``. Each is a family of generated kernels like the rest of
the transcription (values, Jacobian, exact Hessian). The guard is held at
the last node only: a crossing earlier in the phase is not excluded (the
walker's swing foot scuffs through its guard at mid-stance, downwards).

An event is a ``gen.Reset`` (its map) or a ``gen.Impact`` (its impulse:
the runtime's impact solve written as equations with the impulse an
unknown, q+ = q, M (u+ - u) = W^T imp, W u+ + w = -e (W u + w)), on an
unconstrained model; constrained models are refused with the reason.
"""
from __future__ import annotations

import warnings

import numpy as np
import sympy as sm

from ...core.errors import InputError
from ...intake.hybrid import KIND_RESET

__all__ = ["Phase", "read_events", "jump_phases", "event_families", "assemble_events",
           "solution_phases"]

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
    """(the HybridDecls of the events, in order, periodic as a bool) of
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
    return [decls[e] for e in events], bool(periodic)


def _distinct(events):
    """The events' distinct declarations, in order of first use."""
    out = []
    for d in events:
        if all(d.name != o.name for o in out):
            out.append(d)
    return out


def jump_phases(events, periodic):
    """The phases whose event carries the state into a next phase (or,
    periodic, the first), and the impulse unknown of each that is an
    impact: ([phase], {phase: impulse index})."""
    js = list(range(len(events) - 1)) + ([len(events) - 1] if events and periodic else [])
    imp = [j for j in js if events[j].kind != KIND_RESET]
    return js, {j: i for i, j in enumerate(imp)}


def _impact_jump(m, d, x, xa, t):
    """The impulse's equations of an impact (the runtime's impact solve,
    gen_rt_hybrid.c, on an unconstrained model) between the state x before
    and xa after, with the impulse imp0 an unknown: q+ = q,
    M (u+ - u) = W^T imp0, W u+ + w = -e (W u + w), where the gap's rate
    is g' = W u + w through the kinematic equations."""
    q, u = list(m.q), list(m.u)
    qa, ua = xa[:m.nq], xa[m.nq:]
    qdot = (sm.Matrix(m.qdot) if m.qdot is not None
            else m.Kqd.LUsolve(-(m.Ku * sm.Matrix(u) + m.kf)))
    g = d.expr
    gdot = sum((g.diff(a) * b for a, b in zip(q, qdot)), sm.S.Zero) + g.diff(t)
    W = sm.Matrix([[gdot.diff(b) for b in u]])
    w = gdot.xreplace({b: 0 for b in u})
    lam = sm.Dummy("imp0")
    mom = m.M * (sm.Matrix(ua) - sm.Matrix(u)) - W.T * lam
    vel = (W * sm.Matrix(ua))[0] + w + d.restitution * ((W * sm.Matrix(u))[0] + w)
    return x + xa + [lam], [a - b for a, b in zip(qa, q)] + list(mom) + [vel]


def event_families(m, pf, events, periodic):
    """The families (name, locals, expressions) of each distinct event's
    guard, its rate and its jump (the next phase's first state against the
    map, or an impact's impulse equations), and of the periodicity without
    an event."""
    q, u, t = list(m.q), list(m.u), m.t
    x = q + u
    out = []
    jumps = {events[j].name for j in jump_phases(events, periodic)[0]}
    for i, d in enumerate(_distinct(events)):
        g = d.expr
        out.append((f"guard{i}", x + pf + [t], [g]))
        if d.direction:
            qd = [sm.Dummy(f"qd{i}") for i in range(m.nq)]
            ud = [sm.Dummy(f"ud{i}") for i in range(m.nu)]
            rate = (sum((g.diff(a) * b for a, b in zip(q, qd)), sm.S.Zero)
                    + sum((g.diff(a) * b for a, b in zip(u, ud)), sm.S.Zero) + g.diff(t))
            out.append((f"rate{i}", x + qd + ud + pf + [t], [rate]))
        if d.name in jumps:
            xa = [sm.Dummy(f"xa{i}") for i in range(len(x))]
            if d.kind == KIND_RESET:
                out.append((f"jump{i}", x + xa + pf + [t],
                            [a - b for a, b in zip(xa, d.xmap)]))
            else:
                loc, rows = _impact_jump(m, d, x, xa, t)
                out.append((f"jump{i}", loc + pf + [t], rows))
    if periodic and not events:
        xa = [sm.Dummy(f"xa{i}") for i in range(len(x))]
        out.append(("periodic", x + xa + pf + [t], [a - b for a, b in zip(xa, x)]))
    return out


def assemble_events(a, ocp):
    """Each phase's event rows at its last node (the guard, its rate, the
    jump into the next phase's first node, or the first phase's with
    periodic=True), and the periodicity without an event."""
    lay, N, events = a.lay, ocp.nodes, ocp._events
    index = {d.name: i for i, d in enumerate(_distinct(events))}
    impulse = jump_phases(events, ocp.periodic)[1]
    for j, d in enumerate(events):
        i, k = index[d.name], j * N + N - 1
        last = [(lay.X[k], 1.0)]
        f = a.fam(f"guard{i}")
        a.block(f"guard{i}").add(a.gather(f, last, [], lay.tnode(k)), row0=a.con_rows(f))
        if d.direction:
            f = a.fam(f"rate{i}")
            lo, hi = ([0.0], [BIG]) if d.direction > 0 else ([-BIG], [0.0])
            a.block(f"rate{i}").add(a.gather(f, last, [], lay.tnode(k), lay.node_point[k][0]),
                                    row0=a.con_rows(f, lo, hi))
        if j < len(events) - 1 or ocp.periodic:
            nxt = lay.X[k + 1] if j < len(events) - 1 else lay.X[0]
            f = a.fam(f"jump{i}")
            ex = {("xa", r): [(int(c), 1.0)] for r, c in enumerate(nxt)}
            if j in impulse:
                ex[("imp", 0)] = [(int(lay.L[impulse[j]]), 1.0)]
            a.block(f"jump{i}").add(a.gather(f, last, [], lay.tnode(k), extra=ex),
                                    row0=a.con_rows(f))
    if "periodic" in a.fams:
        f = a.fam("periodic")
        ex = {("xa", i): [(int(j), 1.0)] for i, j in enumerate(lay.X[0])}
        a.block("periodic").add(a.gather(f, [(lay.X[N - 1], 1.0)], [], lay.tnode(N - 1),
                                         extra=ex), row0=a.con_rows(f))


def solution_phases(ocp, sol):
    """The phases of a solution: each phase's N nodes, the event that ends
    it and the state after its map (evaluated from the model's own map)."""
    m, N = ocp.model, ocp.nodes
    args = list(m.q) + list(m.u) + list(m.p) + [m.t]
    out = []
    for j in range(max(1, len(ocp._events))):
        sl = slice(j * N, (j + 1) * N)
        d = ocp._events[j] if ocp._events else None
        x_after = None
        if d is not None and d.kind == KIND_RESET:
            f = sm.lambdify(args, list(d.xmap), modules="numpy")
            x_after = np.array(f(*sol.x[sl][-1], *sol.constants, sol.t[sl][-1]), float)
        elif d is not None:
            x_after = _impact_after(m, d, args, sol.x[sl][-1], sol.constants, sol.t[sl][-1])
        out.append(Phase(sol.t[sl], sol.x[sl], sol.r[sl], None if d is None else d.name,
                         x_after))
    return out


def _impact_after(m, d, args, x, p, t):
    """The state after an impact at x, solved numerically from its impulse's
    equations (_impact_jump) with the model's mass matrix."""
    xa = [sm.Dummy(f"xa{i}") for i in range(m.nx)]
    loc, rows = _impact_jump(m, d, list(m.q) + list(m.u), xa, m.t)
    unk = xa[m.nq:] + [loc[-1]]
    A, b = sm.linear_eq_to_matrix(rows[m.nq:], unk)
    fA, fb = (sm.lambdify(args, e, modules="numpy") for e in (A, b))
    sol = np.linalg.solve(np.array(fA(*x, *p, t), float), np.array(fb(*x, *p, t), float).ravel())
    return np.concatenate([x[:m.nq], sol[:m.nu]])
