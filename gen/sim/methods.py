"""The Simulator's evaluation methods, generated from the interface
description.

Each evaluation method is a thin wrapper of one C function of the model
library (``sim.mass_matrix(q)`` calls ``<p>_eval_mass_matrix``). What it
takes and returns is the C function's description in gen/codegen/abi.py
(its parameters' roles, names and sizes); :data:`EVALUATIONS` adds only what
Python needs beyond it: the method's name, its positional arguments, its
summary and the text of what differs from the shared text of
gen/sim/docstrings.py. :func:`method` makes each one, with its signature
(the positional arguments, then the C function's optional inputs r and p,
its time t when it is not positional, and its plain values), its docstring
and its body, written out as the hand-written methods were:

    def mass_matrix(self, q, *, p=None, t=0.0):
        q = self._vec(q, self.nq, 'coordinates q')
        p_ = self._params(p)
        outs = self._call('eval_mass_matrix', q, p_, t, t=t, state=None, named={'q': q, 'p': p_})
        return outs[0].reshape(self.nu, self.nu)
"""
from __future__ import annotations

import linecache
from dataclasses import dataclass, field

from ..codegen import abi
from ..core.errors import InputError
from .docstrings import ARGS, doc

__all__ = ["Evaluation", "EVALUATIONS", "method", "source", "LABELS"]

# the name a Python argument has in messages ("coordinates q must have shape (2,)")
LABELS = {"q": "coordinates q", "u": "speeds u", "x": "state x", "r": "inputs r",
          "p": "constants p"}
# the defaults of the keywords of an evaluation method
_DEFAULTS = {"r": None, "p": None, "t": 0.0, "tol": 0.0, "max_iter": 0}


@dataclass(frozen=True)
class Evaluation:
    """One evaluation method. returns: the C outputs (or the inout array)
    it returns, by name (empty: every output); texts: {argument or output:
    (type, text)} where the shared text does not fit; requires: an
    attribute of the Simulator that must be true (else ``refusal``);
    scalar: the one output is returned as a float."""
    name: str
    verb: str
    args: str
    summary: str
    returns: tuple = ()
    texts: dict = field(default_factory=dict)
    raises: tuple = ("input", "solver")
    requires: str | None = None
    refusal: str = ""
    scalar: bool = False

    @property
    def function(self):
        """The C function's description (abi.FUNCTIONS)."""
        return next(f for f in abi.FUNCTIONS if f.verb == self.verb)


_AUX = """The reaction forces along the auxiliary speeds (Kane's ``u_auxiliary``) at a
state: u' from the right-hand side, then the auxiliary equations ``F reactions + g =
0`` solved (reactions that enter the motion, friction on a normal force, come from the
same linear system as u'). When every force along the auxiliary directions is a
declared input, the force each direction still needs to keep its speed zero,
``-(Fr + Fr*)`` at the inputs given (zero when they are the reactions)."""

EVALUATIONS = {e.name: e for e in (
    Evaluation("mass_matrix", "eval_mass_matrix", "q",
               "The mass matrix M(q) of the unconstrained equations."),
    Evaluation("forcing", "eval_forcing", "q u",
               "The forcing f(q, u, r, t), with ``M u' = f + A^T lam``."),
    Evaluation("kinematics", "eval_kinematics", "q u",
               "The coordinate rates q' from the kinematic equations."),
    Evaluation("constraints", "eval_constraints", "q",
               "The configuration-constraint residuals f_c(q)."),
    Evaluation("constraint_jacobian", "eval_constraint_jacobian", "q",
               "The configuration-constraint Jacobian d f_c / dq."),
    Evaluation("velocity_constraints", "eval_velocity_constraints", "q u",
               "The velocity-constraint residuals A(q) u + b."),
    Evaluation("velocity_constraint_matrix", "eval_velocity_constraint_matrix", "q",
               "The velocity constraints as A(q) u + b(q, t) = 0."),
    Evaluation("energy", "eval_energy", "x", "The total energy at a state.", scalar=True,
               raises=(("gen.InputError", "When the model was given no energy expression, "
                        "or on a wrong shape or a NaN or infinite input."), "solver"),
               requires="has_energy", refusal="model '{name}' was built without energy=..."),
    Evaluation("multipliers", "eval_rhs", "t x",
               "The multipliers lam of the velocity constraints (:doc:`/guides/multipliers`).",
               returns=("lam",)),
    Evaluation("auxiliary_forces", "eval_auxiliary_forces", "t x", _AUX,
               texts={"F": ("", "In the order of ``auxiliary_names``; empty without auxiliary "
                            "speeds.")}),
    Evaluation("outputs", "eval_outputs", "t x",
               "The outputs y(q, u, r, t) given at model creation (``outputs={...}``).",
               texts={"y": ("", "Named by ``output_names``; empty for a model without "
                            "outputs.")}),
    Evaluation("hybrid_values", "eval_hybrid", "t x",
               "The gaps and guards of the hybrid declarations (``hybrid={...}``) at a state, "
               "every contact free: an impact's gap must stay >= 0 (:doc:`/guides/hybrid`).",
               texts={"g": ("", "In the order of ``hybrid_names``; empty for a model without "
                            "declarations.")}),
    Evaluation("project", "project", "x",
               "Project a state onto the configuration and velocity constraints "
               "(minimum-norm Gauss-Newton; independent of the partition).", returns=("x",)),
    Evaluation("consistent_state", "consistent_state", "x",
               "Solve the dependent coordinates and speeds from the independent ones "
               "(:doc:`/guides/partitions`).", returns=("x",),
               texts={"x": ("array_like, shape (nx,), or dict", "The state; its dependent "
                            "entries are Newton's starting guess (they pick the branch). A "
                            "dict ``{state name: value}`` sets the named entries, the others "
                            "0."),
                      "tol": ("float, optional", "Relative tolerance (0: 16 machine "
                              "epsilons)."),
                      "max_iter": ("int, optional", "Newton iterations (0: the default).")},
               raises=("input", ("gen.SingularError", "Where the partition does not "
                                 "determine the dependent entries."),
                       ("gen.ConvergenceError", "When Newton does not converge."))),
    Evaluation("jacobian", "jacobian", "t x",
               "The full-state Jacobian of the right-hand side, every entry of x free.",
               texts={"Jx": ("", "d x'/dx."), "Jr": ("", "d x'/dr.")}),
)}


def _keywords(ev):
    """The keyword arguments of an evaluation method, in order: r, p, t
    (when not positional), then the C function's plain values."""
    pos = ev.args.split()
    c = [a.name for a in ev.function.params if a.role in ("in?", "scalar", "value")]
    return [k for k in ("r", "p", "t") if k in c and k not in pos] + \
        [k for k in c if k not in ("r", "p", "t")]


def _outputs(ev):
    """(name, size) of what the method returns, from the C parameters."""
    params = ev.function.params
    names = ev.returns or [a.name for a in params if a.role in ("out", "out?")]
    return [(a.name, a.size) for n in names for a in params if a.name == n]


def _shape(size):
    dims = [d.lower() for d in size.split("*")]
    return "(" + ", ".join(dims) + ("," if len(dims) == 1 else "") + ")"


def docstring(ev):
    """The evaluation method's docstring, from the shared text."""
    pos = ev.args.split()
    params = []
    for name in pos + _keywords(ev):
        key = name if name in pos or name != "t" else "t="
        params.append((name,) + ev.texts.get(name, ARGS[key]))
    outs = _outputs(ev)
    if ev.scalar:
        returns = [("", "float", "")]
    else:
        returns = [(name if len(outs) > 1 else "", "numpy.ndarray, shape " + _shape(size),
                    ev.texts.get(name, ("", ""))[1]) for name, size in outs]
    return doc(ev.summary, params, returns, ev.raises)


def _size(expr):
    """A size of the description as the Simulator's attribute ("NU" ->
    "self.nu")."""
    return f"self.{expr.lower()}"


def source(ev):
    """The Python source of an evaluation method, from the C function's
    parameters in their order: each array input converted (``self._vec``,
    its shape checked and its name in the message), p and r given their
    defaults, the C function called with fresh outputs (``self._call``, a
    failure status raised with the time, the state and the inputs), and
    the outputs returned in their shapes."""
    pos, kws = ev.args.split(), _keywords(ev)
    sig = ", ".join(["self"] + pos + ["*"] + [f"{k}={_DEFAULTS[k]!r}" for k in kws])
    body, call, named = [], [], []
    if ev.requires:
        body.append(f"if not self.{ev.requires}:\n"
                    f"        raise InputError({ev.refusal!r}.format(name=self.name))")
    for a in ev.function.params:
        if a.role in ("out", "out?"):
            continue
        if a.role == "in?":
            conv = "self._params(p)" if a.name == "p" else "self._inputs(r)"
            body.append(f"{a.name}_ = {conv}")
            call.append(f"{a.name}_")
            named.append((a.name, f"{a.name}_"))
        elif a.role in ("in", "inout") and a.name in pos:
            copy = ".copy()" if a.role == "inout" else ""
            body.append(f"{a.name} = self._vec({a.name}, {_size(a.size)}, "
                        f"{LABELS[a.name]!r}){copy}")
            call.append(a.name)
            named.append((a.name, a.name))
        elif a.role == "in":           # q or u of the state x
            if ("x", "x") not in named:
                body.append(f"x = self._vec(x, self.nx, {LABELS['x']!r})")
                named.append(("x", "x"))
            call.append("x[:self.nq].copy()" if a.name == "q" else "x[self.nq:].copy()")
        else:                          # the time, a plain value
            call.append(a.name)
    has_t = any(a.name == "t" for a in ev.function.params)
    state = "x" if ("x", "x") in named else "None"
    given = ", ".join(f"{k!r}: {v}" for k, v in named)
    body.append(f"outs = self._call({ev.verb!r}, {', '.join(call)}, t={'t' if has_t else None}, "
                f"state={state}, named={{{given}}})")
    written = [a.name for a in ev.function.params if a.role in ("out", "out?")]
    rets = []
    for name, size in _outputs(ev):
        v = f"outs[{written.index(name)}]" if name in written else name
        if ev.scalar:
            v = f"float({v}[0])"
        elif "*" in size:
            v += f".reshape({', '.join(_size(d) for d in size.split('*'))})"
        rets.append(v)
    body.append("return " + ", ".join(rets))
    return f"def {ev.name}({sig}):\n" + "".join(f"    {line}\n" for line in body)


def method(ev, module):
    """The method of an Evaluation: its signature, its docstring and its
    body (:func:`source`), compiled under a file name of its own that
    linecache knows (tracebacks and ``inspect.getsource`` show it)."""
    src = source(ev)
    filename = f"<gen.sim.methods: Simulator.{ev.name}>"
    ns = {"InputError": InputError}
    exec(compile(src, filename, "exec"), ns)   # noqa: S102
    linecache.cache[filename] = (len(src), None, src.splitlines(True), filename)
    fn = ns[ev.name]
    fn.__doc__ = docstring(ev)
    fn.__module__ = module
    fn.__qualname__ = f"Simulator.{ev.name}"
    return fn
