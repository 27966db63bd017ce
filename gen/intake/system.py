"""The containers of formed equations (a sympy ``System``, a ``JointsMethod``,
a PyDy ``System``) and ``Model.from_system``'s dispatch: to the Kane or
Lagrange adapter on the method a container holds, or, with
``formulation="recursive"`` or ``"crba"``, to the recursive formulation of a
sympy System's joint tree (:mod:`gen.intake.recursive`).

Model.from_kanes / from_lagrange / from_system accept the formed method or an
object holding one: a sympy System (``eom_method``), a JointsMethod
(``method``) or a PyDy System (``eom_method``, ``constants``,
``specifieds``). They never call ``form_eoms`` themselves: that call picks
the backend (Kane or Lagrange) and its options, which is the user's choice.
"""
from __future__ import annotations

import inspect

import sympy as sm
from sympy.physics import mechanics as me

from ..core.errors import ModelError
from ..sym.intern import Interner
from .lagrange import lagrange_partition

__all__ = ["is_pydy_system", "unwrap", "method_of", "pydy_defaults", "kane_of", "lagrange_of",
           "builder_of", "recursive_model", "CONSTRUCTORS"]

_ACCEPTED = {
    "kane": ("Model.from_kanes", "KanesMethod",
             "use Model.from_lagrange or Model.from_system"),
    "lagrange": ("Model.from_lagrange", "LagrangesMethod",
                 "use Model.from_kanes or Model.from_system"),
}

# what turns a sympy object into a gen.Model: the constructor to call first
CONSTRUCTORS = (("KanesMethod", "gen.Model.from_kanes(km, constants={...}, inputs=[...])"),
                ("LagrangesMethod", "gen.Model.from_lagrange(lm, constants={...}, "
                 "inputs=[...])"),
                ("JointsMethod", "gen.Model.from_system(method, constants={...}, "
                 "inputs=[...])"),
                ("System", "gen.Model.from_system(system, constants={...}, inputs=[...])"))

# the keywords every builder takes; the rest are the builder's own
_COMMON = ("km", "lm", "constants", "inputs", "name", "energy", "outputs", "hybrid")
_LAGRANGE_PARTITION = {"q_ind", "q_dep", "qd_ind", "qd_dep"}


def is_pydy_system(obj):
    """Whether obj is a PyDy System (or duck-types as one)."""
    try:
        from pydy.system import System as PydySystem
    except Exception:                          # pydy missing or broken
        PydySystem = None
    if PydySystem is not None and isinstance(obj, PydySystem):
        return True
    # duck type (a stand-in, or another pydy version): the three attributes
    # PyDy documents, and not sympy's System (which has no specifieds)
    return (not isinstance(obj, me.System) and hasattr(type(obj), "eom_method")
            and hasattr(obj, "constants") and hasattr(obj, "specifieds"))


def unwrap(obj):
    """(formed method or None, description of obj, container kind, what the
    user must call to form it). kind: None (a method itself), "system",
    "joints" or "pydy"."""
    if isinstance(obj, (me.KanesMethod, me.LagrangesMethod)):
        return obj, type(obj).__name__, None, None
    if isinstance(obj, me.System):
        m = obj.eom_method
        kind, label, call = "system", "System", "system.form_eoms()"
    elif isinstance(obj, me.JointsMethod):
        m = obj.method
        kind, label, call = "joints", "JointsMethod", "method.form_eoms()"
    elif is_pydy_system(obj):
        m = obj.eom_method
        kind, label, call = "pydy", "pydy System", "km.kanes_equations(bodies, loads)"
    else:
        return None, type(obj).__name__, None, None
    if m is None:
        return None, f"{label} without equations of motion", kind, call
    return m, f"{label} with a {type(m).__name__}", kind, call


def method_of(obj, want):
    """The formed KanesMethod (want="kane") or LagrangesMethod ("lagrange")
    held by obj, and obj's container kind; a ModelError naming what was given
    and what is accepted otherwise."""
    caller, cls_name, other = _ACCEPTED[want]
    m, desc, kind, call = unwrap(obj)
    accepted = (f"(accepted: a {cls_name}, or a sympy System, JointsMethod or pydy "
                "System holding one)")
    if m is None and kind is not None:
        raise ModelError(
            f"{caller} needs a {cls_name}, got {desc}: call {call} first (eomgen does not "
            f"form the equations itself: the backend is your choice) {accepted}")
    want_cls = me.KanesMethod if want == "kane" else me.LagrangesMethod
    if not isinstance(m, want_cls):
        hint = f": {other}" if isinstance(m, (me.KanesMethod, me.LagrangesMethod)) else ""
        raise ModelError(f"{caller} needs a {cls_name}, got {desc}{hint} {accepted}")
    return m, kind


def pydy_defaults(obj):
    """(constants, inputs) of a PyDy System: its constants dict as given, and
    its specified quantities (the keys of its specifieds, then any other
    specified symbol it knows, by name)."""
    constants = dict(obj.constants or {})
    spec = obj.specifieds or {}
    inputs = []
    if "symbols" in spec and "values" in spec:
        inputs = list(spec["symbols"])
    else:
        for k in spec:
            inputs.extend(k if isinstance(k, tuple) else [k])
    rest = getattr(obj, "specifieds_symbols", None) or ()
    inputs += sorted((s for s in rest if s not in inputs), key=str)
    return constants, inputs


def kane_of(obj, constants, inputs):
    """(KanesMethod, constants, inputs) of what Model.from_kanes was given:
    a PyDy System's constants and specifieds stand for those left None."""
    km, kind = method_of(obj, "kane")
    if kind == "pydy":
        pd_constants, pd_inputs = pydy_defaults(obj)
        constants = pd_constants if constants is None else constants
        inputs = pd_inputs if inputs is None else inputs
    return km, constants, inputs


def lagrange_of(obj, partition, constants, inputs):
    """(LagrangesMethod, partition, constants, inputs) of what
    Model.from_lagrange was given: a sympy System's own partition where the
    user gave none, a PyDy System's constants and specifieds for those left
    None."""
    lm, kind = method_of(obj, "lagrange")
    if kind == "system":
        partition = lagrange_partition(obj, lm, partition)
    elif kind == "pydy":
        pd_constants, pd_inputs = pydy_defaults(obj)
        constants = pd_constants if constants is None else constants
        inputs = pd_inputs if inputs is None else inputs
    return lm, partition, constants, inputs


def builder_of(cls, obj, partition):
    """cls.from_kanes or cls.from_lagrange, whichever the method obj holds
    needs, with the further keywords (partition) checked against the
    builder's own."""
    m, desc, kind, call = unwrap(obj)
    needs = "Model.from_system needs a KanesMethod or LagrangesMethod"
    accepted = ("(accepted: a KanesMethod or LagrangesMethod, or a sympy System, "
                "JointsMethod or pydy System holding one)")
    if m is None and kind is not None:
        raise ModelError(f"{needs}, got {desc}: call {call} first {accepted}")
    if isinstance(m, me.KanesMethod):
        builder = cls.from_kanes
        given = sorted(set(partition) & _LAGRANGE_PARTITION)
        if given:
            raise ModelError(
                f"{', '.join(given)} given for a Kane model ({desc}): the "
                "partition of a KanesMethod is its own (q_ind/q_dependent, "
                "u_ind/u_dependent)")
    elif isinstance(m, me.LagrangesMethod):
        builder = cls.from_lagrange
    else:
        raise ModelError(f"{needs}, got {desc} {accepted}")
    # the builder's own further keywords (partition, reactions, ...)
    extra = [k for k in inspect.signature(builder).parameters if k not in _COMMON]
    bad = sorted(set(partition) - set(extra))
    if bad:
        raise ModelError(
            f"unknown argument(s) {', '.join(bad)} for Model.from_system with {desc}: "
            f"accepted are {', '.join(extra) or 'none'}")
    return builder


def recursive_model(cls, system, formulation, partition, **options):
    """Model.from_system(system, formulation="recursive" | "crba"): the
    equations of a sympy System's joint tree formed here, with one Interner
    for this build (gen.intake.recursive), handed to cls.from_matrices;
    options: constants, inputs, name, energy, outputs, hybrid."""
    if partition:
        raise ModelError(
            f"unknown argument(s) {', '.join(sorted(partition))} for "
            f"Model.from_system with formulation={formulation!r}: accepted are none")
    if isinstance(system, me.System) and not len(system.q) and not len(system.u):
        raise ModelError(
            f"Model.from_system: the System of frame {system.frame.name!r} and fixed point "
            f"{system.fixed_point.name!r} is empty: no joints, coordinates or speeds, so "
            "the model would have no state; add bodies and joints "
            "(System.add_joints) first")
    from .aba import accelerations_of_tree
    from .recursive import check_joints_move, constraints_of_tree, equations_of_tree
    cons = constraints_of_tree(system)
    interner = Interner()
    if cons is None and not options.get("hybrid") and formulation == "recursive":
        # an open tree: u' by the articulated body algorithm, the model's M
        # the identity (gen.intake.recursive's docstring)
        ud, q, u, kdes, twins = accelerations_of_tree(system, interner)
        M, f = sm.eye(len(u)), ud
    else:
        M, f, q, u, kdes = equations_of_tree(system, interner)
        twins = []
        if cons is None:
            check_joints_move(system, M, u)
    model = cls.from_matrices(M, f, q, u, kdes, _constraints=cons, **options)
    model.twins = twins
    return model
