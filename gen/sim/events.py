"""Events during a simulation: ``sim.simulate(..., events={name: direction})``.

An event is a crossing of a level (zero unless given) by a state or an
output of the model, found between the ends of every integration step and
located on the step's dense output inside the generated C (the runtime's
``gen_rt_events``; README, "Events"). This module turns the Python
arguments into the ``<p>_events`` struct and the C log back into
``gen.Event(name, t, x)`` records.
"""
from __future__ import annotations

import numbers

import numpy as np

from ..core.errors import InputError

__all__ = ["EventPlan", "plan_events", "hybrid_error"]

_DIRECTIONS = (-1, 0, 1)


class EventPlan:
    """The ``<p>_events`` struct and the arrays it points to (kept alive
    for one C call): the spec of n events and a log of ``capacity`` rows."""

    def __init__(self, sim, names, which, direction, terminal, level, capacity):
        lib = sim.library
        self.sim = sim
        self.names = names
        self.which = np.asarray(which, dtype=np.intc)
        self.direction = np.asarray(direction, dtype=np.intc)
        self.terminal = np.asarray(terminal, dtype=np.intc)
        self.level = np.asarray(level, dtype=sim.dtype)
        self.struct = lib.new("events")
        s = self.struct
        s.n = len(names)
        if names:
            s.which = lib.array(self.which, "int[]")
            s.direction = lib.array(self.direction, "int[]")
            s.terminal = lib.array(self.terminal, "int[]")
            s.level = lib.array(self.level)
        # hybrid={...}: the engine's work, and the names of the log's rows
        # n + k (declaration k), n + nh + k (lift-off of contact k) and
        # n + 2 nh + k (contact k held from then on)
        nh = getattr(sim, "nh", 0)
        self.log_names = list(names)
        if nh:
            from ..intake.hybrid import hybrid_iwork_len, hybrid_work_len
            self.log_names += list(sim.hybrid_names)
            self.log_names += [f"{n}.liftoff" for n in sim.hybrid_names]
            self.log_names += [f"{n}.hold" for n in sim.hybrid_names]
            self.hwork = np.zeros(hybrid_work_len(sim.nq, sim.nu, sim.mv, nh), dtype=sim.dtype)
            self.hiwork = np.zeros(hybrid_iwork_len(sim.nq, sim.nu, sim.mv, nh), dtype=np.intc)
            s.hybrid_work = lib.array(self.hwork)
            s.hybrid_iwork = lib.array(self.hiwork, "int[]")
        self.resize(capacity)

    def resize(self, capacity):
        """A log of capacity rows (a rerun when more events were found)."""
        sim, lib, s = self.sim, self.sim.library, self.struct
        self.capacity = int(capacity)
        self.log_which = np.zeros(max(1, self.capacity), dtype=np.intc)
        self.log_t = np.zeros(max(1, self.capacity), dtype=sim.dtype)
        self.log_x = np.zeros((max(1, self.capacity), sim.nx), dtype=sim.dtype)
        self.log_x_after = np.zeros((max(1, self.capacity), sim.nx), dtype=sim.dtype)
        s.capacity = self.capacity
        s.log_which = lib.array(self.log_which, "int[]")
        s.log_t = lib.array(self.log_t)
        s.log_x = lib.array(self.log_x)
        s.log_x_after = lib.array(self.log_x_after)

    def found(self, n):
        """The first n logged events as [gen.Event(name, t, x)] (a hybrid
        jump also with x_after, the state after it)."""
        from .solution import Event, JumpEvent
        n = min(int(n), self.capacity)
        out = []
        for k in range(n):
            w = int(self.log_which[k])
            name, t, x = self.log_names[w], float(self.log_t[k]), self.log_x[k].astype(float).copy()
            if w < len(self.names):
                out.append(Event(name, t, x))
            else:
                out.append(JumpEvent(name, t, x, self.log_x_after[k].astype(float).copy()))
        return out


def _resolve(sim, name):
    """The C index of an event quantity: a state (0..nx-1) or an output
    (nx..nx+ny-1), by its C name or by the user's sympy spelling."""
    for names in (list(sim.state_names), list(sim.state_labels)):
        if name in names:
            return names.index(name)
    for names in (list(sim.output_names), list(sim.output_labels)):
        if name in names:
            return sim.nx + names.index(name)
    outs = f"; outputs {list(sim.output_names)}" if sim.output_names else \
        " (the model has no outputs: Model(..., outputs={name: expr}) adds some)"
    raise InputError(f"event {name!r} is neither a state nor an output of model "
                     f"'{sim.name}': states {list(sim.state_names)}{outs}")


def plan_events(sim, events, terminal=False, capacity=256):
    """The EventPlan of simulate's ``events`` and ``terminal`` arguments.

    events: {name: direction} or {name: (direction, level)}, name a state
    or an output, direction +1 (upwards), -1 (downwards) or 0 (both).
    terminal: True or False for all, or {name: bool} (names not given are
    not terminal)."""
    if events is None and getattr(sim, "nh", 0):
        return EventPlan(sim, [], [], [], [], [], capacity)
    if not isinstance(events, dict) or not events:
        raise TypeError("events must be a non-empty dict {name: direction} (direction +1, -1 or "
                        f"0, or (direction, level)), got {events!r}")
    if isinstance(terminal, dict):
        unknown = set(terminal) - set(events)
        if unknown:
            raise InputError(f"terminal names events that are not in events: {sorted(unknown)}")
        term = [bool(terminal.get(k, False)) for k in events]
    elif isinstance(terminal, (bool, np.bool_)):
        term = [bool(terminal)] * len(events)
    else:
        raise TypeError(f"terminal must be True, False or a dict {{event name: bool}}, got "
                        f"{terminal!r}")
    names, which, direction, level = [], [], [], []
    for name, spec in events.items():
        d, lev = (spec if isinstance(spec, tuple) else (spec, 0.0))
        if isinstance(d, bool) or not isinstance(d, numbers.Integral) or int(d) not in _DIRECTIONS:
            raise InputError(f"event {name!r}: the direction must be +1 (upwards), -1 "
                             f"(downwards) or 0 (both), got {d!r}")
        lev = float(lev)
        if not np.isfinite(lev):
            raise InputError(f"event {name!r}: the level must be a finite number, got {lev!r}")
        names.append(str(name))
        which.append(_resolve(sim, str(name)))
        direction.append(int(d))
        level.append(lev)
    return EventPlan(sim, names, which, direction, term, level, capacity)


def _pairs(sim, x):
    return ", ".join(f"{n}={float(v):.12g}" for n, v in zip(sim.state_names, x))


def hybrid_error(sim, plan, status, n_events, p, where):
    """The error of a run that a hybrid declaration stopped (its last log
    entry: the declaration, the time, the state before and the map's), in
    the user's names, or None for another failure.

    - ERR_PENETRATED: the start is past a declaration's zero in its
      direction (an impact's gap below zero): the declaration and its value;
    - ERR_NONFINITE_MODEL, ERR_SINGULAR, ERR_INCONSISTENT_RESET at a jump:
      the declaration, the state before it and the entries of the map (or
      of the speeds after an impulse) that are not finite.
    """
    from ..core.errors import InputError, SingularError, SolverError
    from ..core.status import status_message, status_name
    nh = getattr(sim, "nh", 0)
    name = status_name(status)
    if plan is None or not nh or n_events < 1 or n_events > plan.capacity:
        return None
    k = n_events - 1
    j = int(plan.log_which[k]) - len(plan.names)
    if not 0 <= j < nh:
        return None
    decl, t = sim.hybrid_names[j], float(plan.log_t[k])
    x, xa = plan.log_x[k].astype(float), plan.log_x_after[k].astype(float)
    reset = sim.hybrid_kinds[j] == 1
    what = f"reset {decl!r}" if reset else f"impact {decl!r}"
    if name == "ERR_PENETRATED":
        g = float(sim.hybrid_values(t, x, p=p)[j])
        side = "below" if g < 0 else "above"
        if reset:
            text = (f"the run starts inside the guard region of {what}: its guard is {g:.12g} "
                    f"at t = {t:.17g}, {side} zero, the side its crossing fires into (the "
                    "reset would not fire where it should); start on the other side of its "
                    "guard")
        else:
            text = (f"the run starts inside the contact of {what}: its gap is {g:.12g} at "
                    f"t = {t:.17g}, {side} zero, the side its impact closes onto (the motion "
                    "would run through it); start with the gap on its open side, or at zero")
        return InputError(f"{sim.name}_{where}: {text} [ERR_PENETRATED], state: "
                          f"{_pairs(sim, x)}", "x0", None, g)
    if name not in ("ERR_NONFINITE_MODEL", "ERR_SINGULAR", "ERR_INCONSISTENT_RESET"):
        return None
    bad = [f"{n} = {float(v)!r}" for n, v in zip(sim.state_names, xa) if not np.isfinite(v)]
    if reset and name == "ERR_INCONSISTENT_RESET":
        body = (f"the map of {what} at t = {t:.17g} gives a state that violates the model's "
                f"constraints: {_pairs(sim, xa)}")
    elif reset:
        body = f"the map of {what} is not finite at t = {t:.17g}: {', '.join(bad)}"
    elif bad:
        body = (f"the impulse of {what} is not finite at t = {t:.17g}: the speeds after it "
                f"{', '.join(bad)} (the mass matrix, or the gap's gradient, is NaN or "
                "infinite, or the impulse's system singular, at the state before it)")
    else:
        body = f"the impulse of {what} at t = {t:.17g}: {status_message(status)}"
    text = f"{sim.name}_{where}: {body} [{name}], the state before it: {_pairs(sim, x)}"
    cls = SingularError if name in ("ERR_NONFINITE_MODEL", "ERR_SINGULAR") else SolverError
    return cls(text, status=status, status_name=name, time=t, state=x)
