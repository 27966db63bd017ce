"""Ctrl-C during long C calls (issue 32).

A simulation, an ensemble or a batch call runs in C with the GIL released,
and Python runs a signal handler only between bytecodes of the main thread:
without help, Ctrl-C is acted on only when the C call returns (96 s late in
a long ``simulate``).

The C runtime knows nothing of signals: a run stops before its next step
when the cancellation flag its caller owns (``sim_options.cancel``) is
nonzero, with the status ``ERR_CANCELLED``; a NULL flag (the embedded build,
the C API's default) is never cancelled. This module is the caller's side in
Python. :func:`call` makes a long call with a flag from the host module's
SIGINT relay (``csrc/host/gen_host_interrupt.c``): a C signal handler that
sets the flag of every call in progress, then calls the handler it replaced
(Python's own, which raises ``KeyboardInterrupt`` in the main thread when the
call returns). The C work stops within one step; the call's outputs are
dropped (the caller never returns them), so nothing half-written is handed
back; the process stays usable.

Why a signal relay rather than running the call in a worker thread while the
main thread waits in short ``join`` slices: a thread's start and join cost
about 200 us on a loaded machine (a persistent worker's hand-off about
110 us), several times a short ``simulate`` (33 us for the seed pendulum's
10 rows). The relay costs three C calls a call (arm, with a sigaction
query, and release: 3.7 us measured on the same loaded machine, where the
simulate took 50 to 300 us). It is installed by the first call over
Python's handler (again when Python has set its handler since, as ipykernel
does around a cell), and used only while the Python-level handler is
:func:`signal.default_int_handler` (a program with its own SIGINT handler,
or one ignoring SIGINT, keeps it). One relay serves the process (the first
host module's; see :func:`_relay_of`).

Limits: 64 calls in progress at once get a flag (more run uncancellable); a
second Ctrl-C landing between arming and the call can leak one slot; where
there is no sigaction (Windows) calls run as before. Short calls (``rhs``,
``mass_matrix``, ...: microseconds) are not wrapped.
"""
from __future__ import annotations

import threading

import _signal   # signal's C functions: getsignal without the enum wrapper (10 us)

__all__ = ["call", "count"]


class _Relay:
    """The process's one relay: the host module that owns it and those that
    follow it. Read without the lock (a reference read is atomic); set only
    under it."""

    def __init__(self):
        self.lock = threading.Lock()
        self.owner = None      # (lib, ffi) of the host module whose relay the process uses
        self.followers = {}    # id(lib) -> (lib, ffi): modules that take the owner's flags


_relay = _Relay()


def _relay_of(lib, ffi):
    """(owner lib, owner ffi) of the process's one relay. The first host
    module used is the owner; another (the float host next to the double
    one) never installs its own (two relays chained over each other could
    call each other forever): its batch loops follow the owner's counter and
    its runs get the owner's flags."""
    owner = _relay.owner
    if owner is not None and (owner[0] is lib or id(lib) in _relay.followers):
        return owner
    with _relay.lock:
        owner = _relay.owner
        if owner is None:
            owner = _relay.owner = (lib, ffi)
        elif owner[0] is not lib and id(lib) not in _relay.followers:
            counter = int(owner[1].cast("uintptr_t", owner[0].eomgen_interrupt_counter()))
            lib.eomgen_interrupt_follow(ffi.cast("void *", counter))
            _relay.followers[id(lib)] = (lib, ffi)
        return owner


def _armed(lib, ffi=None):
    """(owner lib, slot) of the relay for one call; slot -1: no relay
    (SIGINT is not Python's default handler, or the platform has none)."""
    if _signal.getsignal(_signal.SIGINT) is not _signal.default_int_handler:
        return lib, -1
    owner = _relay_of(lib, ffi)[0]
    return owner, owner.eomgen_interrupt_arm()


def count(sim):
    """The number of SIGINTs the process's relay has seen (0 where there is
    none yet): a baseline for :func:`call`'s ``since``."""
    lib, ffi = sim.library.host, sim.library.ffi
    owner = _relay.owner[0] if _relay.owner is not None else lib
    return int(owner.eomgen_interrupt_count())


def call(sim, opts, fn, *args, since=None):
    """``fn(*args)``, a long C call of ``sim``'s host module, cancellable by
    Ctrl-C: ``opts`` (a ``sim_options`` struct, or None for a batch loop,
    which watches the relay itself) gets the call's cancellation flag. A
    SIGINT during the call stops the C work and raises ``KeyboardInterrupt``
    (Python's handler raises it in the main thread; in another thread this
    function does). since: a :func:`count` taken when the work began (an
    ensemble's chunks on threads): a SIGINT that came after it, before this
    call was armed, cancels the call at once, as one during it does."""
    lib, ffi = sim.library.host, sim.library.ffi
    owner, slot = lib, -1
    try:
        owner, slot = _armed(lib, ffi)
        if slot < 0:
            return fn(*args)
        if opts is not None:
            flag = owner.eomgen_interrupt_flag(slot)
            if owner is not lib:     # the owner's int, as this module's pointer
                flag = ffi.cast("int *", int(_relay.owner[1].cast("uintptr_t", flag)))
            opts.cancel = flag
            if since is not None and int(owner.eomgen_interrupt_count()) != since:
                flag[0] = 1      # interrupted before this call was armed
        result = fn(*args)
    finally:
        hit = owner.eomgen_interrupt_release(slot) if slot >= 0 else 0
        if slot >= 0 and opts is not None:
            opts.cancel = ffi.NULL
    if hit:
        _interrupted()
    return result


def _pending():
    """A Python-level call: the main thread's pending signal handlers run
    here at the latest (the SIGINT that set the flag raises its
    KeyboardInterrupt)."""
    return None


def _interrupted():
    if threading.current_thread() is threading.main_thread():
        _pending()
    raise KeyboardInterrupt("interrupted: the C call was cancelled (SIGINT)")
