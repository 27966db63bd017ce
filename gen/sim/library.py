"""The compiled model library under a Simulator, as eomgen's own modules
reach it.

:class:`ModelLibrary` (``sim.library``) is what the modules that fill the C
structs themselves (gen/sim/ensemble.py, inputs.py, events.py) use instead
of the Simulator's private names; :func:`fast_rhs` makes the host module's
CPython fast paths of ``rhs`` and ``rhs_batch``.
"""
from __future__ import annotations

from ..toolchain.host import host_object

__all__ = ["ModelLibrary", "fast_rhs"]


def fast_rhs(host, api, which="rhs"):
    """The host module's CPython fast path of rhs (which="rhs") or
    rhs_batch ("rhs_batch"), bound to the table api
    (csrc/host/gen_host_fast.c); None where the host has none."""
    make = getattr(host.lib, f"eomgen_fast_{which}_new", None)
    if make is None:
        return None
    return host_object(host, make(api))


class ModelLibrary:
    """The compiled model library under a Simulator (``sim.library``): what
    eomgen's own modules that fill the C structs themselves need
    (gen.sim.ensemble, gen.sim.inputs, gen.sim.events), without the
    Simulator's private names.

    Attributes
    ----------
    ffi : cffi.FFI
        The host module's ffi (its struct and type declarations).
    host : object
        The host module's lib: its functions (``eomgen_<verb>``, each taking
        the table first) and constants (``EOMGEN_REDUCE_FINAL``, ...).
    real_array : str
        The cffi type of an array of the model's reals (``"eomgen_real[]"``).
    """

    real_array = "eomgen_real[]"

    def __init__(self, sim):
        self._sim = sim
        self.ffi = sim._ffi
        self.host = sim._lib

    @property
    def table(self):
        """The model's plugin table (``const eomgen_api *``); it changes once,
        when :meth:`ensure_derivatives` switches to the complete library."""
        return self._sim._api

    def new(self, struct):
        """A zeroed C struct of the interface: ``"sim_options"``, ``"input"``,
        ``"events"``, ``"sim_stats"`` (sized for the model), or any struct the
        host declares (``"ensemble"`` is ``eomgen_ensemble``)."""
        return self._sim._new(struct)

    def function(self, name):
        """The model's C function ``<p>_<name>``, its table bound: call it with
        the C function's own arguments. A derivative kernel is built first
        where the library has none yet."""
        return self._sim._fn(name)

    def call(self, name, *args):
        """Call the host's ``eomgen_<name>`` (a host-only loop such as
        ``ensemble_run``) with the current table first."""
        return getattr(self.host, f"eomgen_{name}")(self._sim._api, *args)

    def array(self, a, ctype=None):
        """A C pointer over the buffer of the numpy array a (no copy; keep a
        alive for the call): the model's reals, or ctype (``"int[]"``)."""
        return self.ffi.from_buffer(ctype or self.real_array, a)

    def check(self, status, where, t=None, state=None, args=None):
        """Raise the gen exception of a nonzero C status (see
        :class:`gen.SolverError`); nothing for 0."""
        self._sim._check(status, where, t, state, args)

    def ensure_derivatives(self):
        """Build (or load from the cache) the derivative kernels now, where
        they are not compiled in yet (RODAS4 and the linearizations need
        them)."""
        self._sim._need_derivatives()
