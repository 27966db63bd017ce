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

__all__ = ["EventPlan", "plan_events"]

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
        # n + k (declaration k) and n + nh + k (lift-off of contact k)
        nh = getattr(sim, "nh", 0)
        self.log_names = list(names)
        if nh:
            from ..intake.hybrid import hybrid_iwork_len, hybrid_work_len
            self.log_names += list(sim.hybrid_names)
            self.log_names += [f"{n}.liftoff" for n in sim.hybrid_names]
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
