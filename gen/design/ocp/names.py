"""The user's side of an optimal control problem: the model's symbols as
the user writes them (sympy objects or names) and the instance
constraints, read into the internal symbols of the transcription, each
unknown or non-differentiable one named in an InputError."""
from __future__ import annotations

import math

import sympy as sm
from sympy.physics import mechanics as me

from ...core.errors import InputError

__all__ = ["Names", "NONSMOOTH", "read_instance"]

# not twice differentiable: refused in an objective or a constraint
NONSMOOTH = (sm.Abs, sm.sign, sm.Heaviside, sm.floor, sm.ceiling, sm.Min, sm.Max,
             sm.Piecewise, sm.Mod)


class Names:
    """The model's symbols as the user writes them -> internal symbols."""

    def __init__(self, m):
        self.m = m
        self.sub = {}
        self.label = {}
        t_user = me.dynamicsymbols._t
        for orig, s, name in zip(list(m.q_orig) + list(m.u_orig), list(m.q) + list(m.u),
                                 m.state_names):
            self.sub[orig] = s
            self.label[s] = name
        for orig, s, name in zip(m.r_orig, m.r, m.input_names):
            self.sub[orig] = s
            self.label[s] = name
        for orig, s, name in zip(m.p_orig, m.p, m.constant_names):
            self.sub[orig] = s
            self.label[s] = name
        self.sub[t_user] = m.t
        self.label[m.t] = "t"
        self.states = list(m.q) + list(m.u)
        self.by_name = {}
        for i, n in enumerate(m.state_names):
            self.by_name[n] = ("x", i)
        for i, n in enumerate(m.input_names):
            self.by_name[n] = ("r", i)
        for i, n in enumerate(m.constant_names):
            self.by_name[n] = ("p", i)
        for i, n in enumerate(m.output_names):
            self.by_name.setdefault(n, ("y", i))
        self.state_funcs = {}       # theta (the function class) -> state index
        for i, orig in enumerate(list(m.q_orig) + list(m.u_orig)):
            if isinstance(orig, sm.core.function.AppliedUndef):
                self.state_funcs[orig.func] = i

    def key(self, k, what):
        """('x'|'r'|'p'|'y', index) of a user key: a sympy object or a name."""
        if isinstance(k, str):
            if k in self.by_name:
                return self.by_name[k]
            raise InputError(f"{what}: {k!r} is not a state, input or constant of model "
                             f"{self.m.name!r}")
        s = self.sub.get(sm.sympify(k))
        if s is not None:
            if s in self.m.q or s in self.m.u:
                return ("x", self.states.index(s))
            if s in self.m.r:
                return ("r", self.m.r.index(s))
            if s in self.m.p:
                return ("p", self.m.p.index(s))
        raise InputError(f"{what}: {k} is not a state, input or constant of model "
                         f"{self.m.name!r}")

    def user_symbols(self):
        """{name: the user's own object} of every state, input, constant and
        output, under its model name and its sympy name (a string is parsed
        in these)."""
        m, loc = self.m, {}
        origs = (list(m.q_orig) + list(m.u_orig), list(m.r_orig), list(m.p_orig))
        names = (m.state_names, m.input_names, m.constant_names)
        for objs, labels in zip(origs, names):
            for o, n in zip(objs, labels):
                own = o.func.__name__ if isinstance(o, sm.core.function.AppliedUndef) else str(o)
                loc.setdefault(own, o)
                loc.setdefault(n, o)
        for n in m.output_names:
            loc.setdefault(n, sm.Symbol(n))
        loc["t"] = me.dynamicsymbols._t
        return loc

    def parse(self, text, what):
        """A string read as a sympy expression in the model's own symbols
        (its states, inputs, constants and outputs by name, and t); refused
        naming the argument when it does not parse."""
        try:
            return sm.sympify(text, locals=self.user_symbols())
        except (sm.SympifyError, TypeError, SyntaxError) as err:
            raise InputError(f"{what} = {text!r} cannot be read as an expression in model "
                             f"{self.m.name!r}'s symbols ({type(err).__name__})") from None

    def number(self, v, what):
        """A user value as a float: a number, a sympy number or a string
        that evaluates to one in the model's symbols (``"pi"``); a
        non-finite one or one that holds symbols is refused naming what."""
        e = self.parse(v, what) if isinstance(v, str) else v
        try:
            f = float(e)
        except (TypeError, ValueError):
            raise InputError(f"{what} = {v!r} is not a number") from None
        if not math.isfinite(f):
            raise InputError(f"{what} = {v!r}: not a finite number")
        return f

    def expr(self, e, what, allow_y=False):
        """A user expression in internal symbols; unknown symbols are named,
        a string is parsed in the model's own symbols, a matrix refused."""
        if isinstance(e, str):
            e = self.parse(e, what)
        if isinstance(e, (sm.MatrixBase, sm.NDimArray, list, tuple)) \
                or tuple(getattr(e, "shape", ())) != ():
            shape = getattr(e, "shape", None) or (len(e),)
            raise InputError(f"{what} must be a scalar expression, got "
                             f"{type(e).__name__} of shape {tuple(shape)}")
        try:
            e = sm.sympify(e)
        except (sm.SympifyError, TypeError) as err:
            raise InputError(f"{what}: cannot read {e!r} as a sympy expression ({err})") from None
        bad = [a for a in e.atoms(*NONSMOOTH)] if e.has(*NONSMOOTH) else []
        if bad:
            raise InputError(
                f"{what} = {e} is not differentiable: it holds {bad[0].func.__name__} "
                f"({bad[0]}); IPOPT needs twice-differentiable functions. Write a smooth "
                "form instead (e.g. sqrt(x**2 + eps**2) for Abs(x), or a slack variable with "
                "a path constraint)")
        out = e.xreplace(self.sub)
        if allow_y and self.m.ny:
            out = out.xreplace({sm.Symbol(n): y for n, y in zip(self.m.output_names, self.m.y)})
        known = set(self.m.q) | set(self.m.u) | set(self.m.r) | set(self.m.p) | {self.m.t}
        unknown = sorted({str(s) for s in out.free_symbols if s not in known})
        undef = sorted({str(f) for f in out.atoms(sm.core.function.AppliedUndef)})
        if unknown or undef:
            raise InputError(f"{what} = {e} holds {', '.join(unknown + undef)}, not a state, "
                             f"input or constant of model {self.m.name!r} (nor t)")
        return out


def read_instance(nm, model, cons):
    """Instance constraints (opty's form: expressions of states at given
    times): their expressions in dummies for the states at given times, and
    the ((state, time), dummy) of each dummy."""
    refs, exprs = {}, []
    for j, c in enumerate(cons):
        c = sm.sympify(c)
        rep = {}
        for f in c.atoms(sm.core.function.AppliedUndef):
            if f.func not in nm.state_funcs:
                continue
            (arg,) = f.args
            if arg == me.dynamicsymbols._t:
                raise InputError(f"constraints[{j}] = {c}: {f} is not at a given time; "
                                 "write the state at a time, e.g. theta.func(0)")
            if not arg.is_number:
                raise InputError(f"constraints[{j}] = {c}: the time of {f} must be a number")
            tv = float(arg)
            key = (nm.state_funcs[f.func], tv)
            if key not in refs:
                refs[key] = sm.Dummy(f"{f.func.__name__}_at_{len(refs)}")
            rep[f] = refs[key]
        exprs.append(_instance_expr(nm, model, c.xreplace(rep), refs, j, c))
    return exprs, list(refs.items())


def _instance_expr(nm, model, e, refs, j, c):
    e = e.xreplace(nm.sub)
    known = set(model.p) | set(refs.values())
    unknown = sorted({str(s) for s in e.free_symbols if s not in known})
    if unknown:
        raise InputError(f"constraints[{j}] = {c} holds {', '.join(unknown)}: an instance "
                         "constraint may hold states at given times and constants only")
    if e.has(*NONSMOOTH):
        raise InputError(f"constraints[{j}] = {c} is not differentiable")
    return e
