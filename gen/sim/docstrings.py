"""The shared text of the Simulator's docstrings: one text per kind of
argument, return and error, assembled per method into a numpy-style
docstring (what ``help()``, the API reference and tests/docs/test_docs.py
read).

    doc("The mass matrix M(q).", params=["q", "p", "t="],
        returns=[("", "numpy.ndarray, shape (nu, nu)", "")], raises=["input", "solver"])

A parameter is a key of :data:`ARGS` or a tuple ``(name, type, text)``; a
key with a suffix (``"t="``, ``"r@op"``) names a variant of the argument
(``t`` as a keyword, ``r`` at an operating point).
"""
from __future__ import annotations

import inspect
import textwrap

__all__ = ["ARGS", "RAISES", "doc", "documented", "section"]

_X = "The state ``[q, u]`` (layout: ``state_names``)."
_OPT = "(None: the defaults given at model creation)"

# argument -> (type, text)
ARGS = {
    "q": ("array_like, shape (nq,)", "The coordinates."),
    "u": ("array_like, shape (nu,)", "The speeds."),
    "x": ("array_like, shape (nx,)", _X),
    "x@op": ("array_like, shape (nx,)", "The operating state (consistent with the "
             "constraints)."),
    "t": ("float", "Time."),
    "t=": ("float, optional", "Time (default 0), for models that depend on it."),
    "h": ("float", "The step size."),
    "r": ("array_like, shape (nr,), optional", "The inputs (None: zero)."),
    "r@op": ("array_like, shape (nr,), optional", "The operating inputs (None: zero)."),
    "p": ("array_like, shape (np,), optional", f"The constants {_OPT}."),
    "tol": ("float, optional", "Relative tolerance on the correction (0: 16 machine "
            "epsilons)."),
    "max_iter": ("int, optional", "Newton iterations (0: the default, 10)."),
    "dt@zoh": ("float, optional", "Return the zero-order-hold discretization over a step dt "
               "instead: ``Ad = exp(A dt)``, ``Bd = int_0^dt exp(A s) ds B`` (scaling and "
               "squaring, in C)."),
    # the batch calls: N states in one C call
    "t@N": ("float or array_like, shape (N,)", "The time(s)."),
    "X@N": ("array_like, shape (N, nx)", "The states."),
    "r@N": ("array_like, shape (nr,) or (N, nr), optional", "One input vector for all states "
            "or one row per state."),
    "p@N": ("array_like, shape (np,) or (N, np), optional", "One constant vector for all "
            "states or one row per state."),
    "x0": ("array_like, shape (nx,), or dict", "The initial state (consistent with the "
           "constraints: see :meth:`consistent_state`, or ``consistent=True``); a dict "
           "``{state name: value}`` sets the named entries, the others 0."),
    "t_end": ("float", "The final time (the last interval is clipped)."),
    "dt@run": ("float", "The RK4 step, or the output interval of the adaptive methods (they "
               "step by their error control alone and write the output times from their "
               "dense output)."),
    "options": ("gen.RunOptions, optional", "Every option of the run at once "
                "(``gen.RunOptions(method=\"dopri5\", rtol=1e-10, h_max=0.01)``), those above "
                "and those without a keyword here (``h_init``, ``h_min``, ``h_max``, "
                "``proj_tol``, ``proj_max_iter``). A keyword given explicitly wins over "
                "options; the other options are options'."),
}

# error -> (exception, text)
RAISES = {
    "input": ("gen.InputError", "On a wrong shape (the message names the expected one) or a "
              "NaN or infinite input (the message names the argument and the entry)."),
    "solver": ("gen.SolverError", "When the C function returns a failure status (a "
               ":class:`gen.SingularError` at a singular configuration, ...)."),
    "run": ("gen.InputError", "On a bad argument (shape, NaN, method, dt, a run longer than "
            "max_rows or than the memory available): the message names it."),
    "step": ("gen.SolverError", "When a step fails (:class:`gen.SingularError`, "
             ":class:`gen.ConvergenceError`, :class:`gen.DivergenceError`): the message "
             "names the time and the last good state."),
    "keyword": ("TypeError", "On a keyword that is not an option (the message names it)."),
}


def _entry(name, type_, text):
    head = f"{name} : {type_}" if name and type_ else (name or type_)
    body = textwrap.fill(text, 84, initial_indent="    ", subsequent_indent="    ") \
        if text else ""
    return head + ("\n" + body if body else "")


def section(title, entries):
    """A numpy-style section of (name, type, text) entries ("" when none)."""
    if not entries:
        return ""
    return f"{title}\n{'-' * len(title)}\n" + "\n".join(_entry(*e) for e in entries)


def _param(p):
    if isinstance(p, tuple):
        return p
    name = p.split("@")[0].rstrip("=")
    return (name,) + ARGS[p]


def doc(summary, params=(), returns=(), raises=("input", "solver"), notes=""):
    """A numpy-style docstring: the summary (a paragraph, or several), then
    the parameters (keys of ARGS or (name, type, text)), the returns
    ((name, type, text); name "" for one unnamed value), the errors (keys
    of RAISES or (exception, text)) and notes."""
    parts = [inspect.cleandoc(summary)]
    parts.append(section("Parameters", [_param(p) for p in params]))
    parts.append(section("Returns", list(returns)))
    errors = [RAISES[r] if isinstance(r, str) else r for r in raises]
    parts.append(section("Raises", [(exc, "", text) for exc, text in errors]))
    if notes:
        parts.append("Notes\n-----\n" + textwrap.fill(notes, 88))
    return "\n\n".join(p for p in parts if p) + "\n"


def documented(summary, params=(), returns=(), raises=("input", "solver"), notes=""):
    """A decorator: the function's docstring is :func:`doc` of these."""
    def decorate(fn):
        fn.__doc__ = doc(summary, params, returns, raises, notes)
        return fn
    return decorate
