"""The checks of a model's pieces, each raising a ModelError (or warning)
in the user's own names: constants' values, outputs, the symbols an
expression may hold, the partition into independent and dependent
coordinates and speeds; and the readable name of a symbol."""
from __future__ import annotations

import re

import sympy as sm
from sympy.physics import mechanics as me

from ..core.errors import ModelError
from ..sym.dag import scan

__all__ = ["sym_name", "user_stacklevel", "warn_unused", "constant_value", "outputs_of",
           "check_expressions", "check_partition", "check_kept_by_kinematics"]


def sym_name(s) -> str:
    """A readable name for a symbol or function of time: 'q1' for q1(t)."""
    if isinstance(s, sm.Function) or (isinstance(s, sm.Expr) and s.is_Function):
        return type(s).__name__ if not hasattr(s, "func") else str(s.func)
    return str(s)


def user_stacklevel():
    """warnings.warn's stacklevel, from the function calling this, of the
    first frame outside the gen package (the user's call), whichever of its
    subpackages the frames between are in."""
    import os
    import sys
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep
    f, level = sys._getframe(1), 1
    while f is not None and os.path.abspath(f.f_code.co_filename).startswith(package):
        f, level = f.f_back, level + 1
    return level


def warn_unused(cls, model_name, kind, names, what):
    """Warn (cls) that the model's constants or inputs `names` appear in no
    expression; `what` lists where they were looked for and what follows."""
    if not names:
        return
    import warnings
    many = len(names) > 1
    warnings.warn(cls(f"model '{model_name}': {kind}{'s' if many else ''} {', '.join(names)} "
                      f"appear{'' if many else 's'} in no expression of the model {what}"),
                  stacklevel=user_stacklevel())


def constant_value(c, v):
    """The float value of constant c, or a ModelError naming c (as the user
    spelt it) and the value: NaN, infinite, complex, symbolic or not a
    number at all."""
    import math

    import numpy as np

    shown = repr(v) if isinstance(v, (str, bytes)) else str(v)

    def refuse(what):
        raise ModelError(f"constant {c} has a value {shown} that is {what}")

    finite_real = "; constants must be finite real numbers"
    if isinstance(v, (str, bytes)):
        refuse("not a number")
    if isinstance(v, (complex, np.complexfloating)) or (
            isinstance(v, np.ndarray) and v.dtype.kind == "c"):
        refuse("complex" + finite_real)
    if isinstance(v, sm.Basic):
        if not isinstance(v, sm.Expr):
            refuse("not a number")
        free = sorted(str(s) for s in v.free_symbols)
        if free:
            refuse(f"a sympy expression in {', '.join(free)}, not a number; give its "
                   "numeric value")
        if v.has(sm.nan):
            refuse("NaN" + finite_real)
        if v.has(sm.zoo, sm.oo, -sm.oo):
            refuse("infinite" + finite_real)
        re_, im_ = sm.N(v, 20).as_real_imag()
        if im_ != 0:
            refuse("complex" + finite_real)
        v = re_
    try:
        fv = float(v)
    except (TypeError, ValueError):
        refuse("not a number")
    if math.isnan(fv):
        refuse("NaN" + finite_real)
    if math.isinf(fv):
        refuse("infinite" + finite_real)
    return fv


def outputs_of(outputs):
    """(names, expressions) of outputs={name: expr} (or [(name, expr), ...])."""
    items = list(outputs.items()) if isinstance(outputs, dict) else list(outputs)
    names, exprs = [], []
    for item in items:
        try:
            name, expr = item
        except (TypeError, ValueError):
            raise ModelError("outputs must be a dict {name: expression} or a list of (name, "
                             f"expression) pairs, got {item!r}") from None
        if not isinstance(name, str) or not re.match(r"^[A-Za-z_][A-Za-z0-9_]*$", name):
            raise ModelError(f"output name {name!r} must be an identifier (letters, digits, "
                             "'_', not starting with a digit)")
        if isinstance(expr, me.Vector):
            raise ModelError(f"output {name!r} is a vector: give one scalar expression per "
                             "output (for example P.pos_from(O).dot(N.x))")
        try:
            e = sm.sympify(expr)
        except (sm.SympifyError, TypeError) as err:
            raise ModelError(f"output {name!r} is not a sympy expression: {err}") from None
        if not isinstance(e, sm.Expr):
            raise ModelError(f"output {name!r} must be a scalar sympy expression, got "
                             f"{type(e).__name__}")
        names.append(name)
        exprs.append(e)
    return names, exprs


def check_expressions(mat, what, allowed, inputs=()):
    """Refuse free symbols, leftover derivatives and unknown functions,
    naming the culprit (and, when inputs holds the same name as a plain
    Symbol where the model has a function of time, or the other way round,
    the mix-up)."""
    free, derivs, undef = scan(mat)
    extra = free - allowed
    functions = {str(r_.func): r_ for r_ in inputs if isinstance(r_, sm.core.function.AppliedUndef)}
    for s_ in sorted(extra, key=str):
        if str(s_) in functions:    # the other mix-up: T(t) declared, the plain T used
            raise ModelError(
                f"the {what} contain {s_}, a plain Symbol, but inputs=[...] gives "
                f"{functions[str(s_)]}, a function of time (a dynamicsymbol): declare the "
                "input as the model writes it (the same object), or use "
                f"dynamicsymbols('{s_}') in the model")
    if extra:
        names = sorted(str(s) for s in extra)
        raise ModelError(
            f"the {what} contain symbol(s) {', '.join(names)} that are neither coordinates, "
            "speeds, inputs nor constants: give them a value in constants={...} or list "
            "them in inputs=[...]")
    if derivs:
        raise ModelError(
            f"the {what} contain derivative term(s) {sorted(map(str, derivs))[:3]}: "
            "express them through the speeds (kinematic equations) or declare them")
    plain = {str(r_): r_ for r_ in inputs if isinstance(r_, sm.Symbol)}
    for fn in sorted(undef, key=str):
        name = str(fn.func)
        if name in plain:
            raise ModelError(
                f"the {what} contain {name}(t), a function of time (a dynamicsymbol), but "
                f"inputs=[...] gives {name}, a plain Symbol: the model uses {name}(t); list "
                f"dynamicsymbols('{name}') in inputs=[...] (sympy.physics.mechanics) "
                f"instead of Symbol('{name}')")
        raise ModelError(
            f"the {what} contain {fn.func}(t), a function of time that is not a "
            "coordinate, "
            "speed or declared input: list it in inputs=[...]")
    # printability (in the user's spelling) is checked before this by
    # gen.sym.printers.check_printable, which knows every function it prints


def check_partition(model):
    """The dependent coordinates/speeds must be determined by the
    constraints: square blocks, of full rank at a sample point."""
    import random
    rng = random.Random(1234)
    if model.mc != len(model.q_dep):
        raise ModelError(f"{model.mc} configuration constraints but {len(model.q_dep)} "
                         "dependent coordinates")
    if model.mv != len(model.u_dep):
        raise ModelError(f"{model.mv} velocity constraints but {len(model.u_dep)} dependent speeds")
    if model.mv < model.mc:
        check_kept_by_kinematics(model, rng)
    syms = model.q + model.p + [model.t]
    checks = []
    if model.mc:
        J = model.fc.jacobian(model.q)
        checks.append((J[:, model.q_dep], "configuration constraints", "dependent coordinates",
                       [model.state_names[i] for i in model.q_dep]))
    if model.mv:
        checks.append((model.A[:, model.u_dep], "velocity constraints", "dependent speeds",
                       [model.state_names[model.nq + i] for i in model.u_dep]))
    for block, cname, dname, names in checks:
        ok = False
        for _attempt in range(5):
            vals = {s: rng.uniform(0.3, 1.7) for s in syms}
            try:
                num = sm.Matrix(block.xreplace(vals)).evalf()
                import numpy as np
                arr = np.array(num.tolist(), dtype=float)
            except (TypeError, ValueError):
                continue
            if not np.all(np.isfinite(arr)):
                continue
            if np.linalg.matrix_rank(arr) == arr.shape[0]:
                ok = True
                break
        if not ok:
            raise ModelError(
                f"the {cname} do not determine the {dname} {names}: their Jacobian "
                f"with respect to them is rank-deficient at random sample points; "
                "choose another partition")


def check_kept_by_kinematics(model, rng):
    """With fewer velocity constraints than configuration constraints
    (a unit quaternion whose norm's derivative is one of the kinematic
    equations), the time derivative of f_c must vanish by the kinematic
    equations alone: d f_c/dt = Jc q'(q, u) + df_c/dt = 0 at any q and u.
    Checked numerically at random points; the run time keeps f_c = 0 by
    projection, and the linearization is on [q_ind, u_ind]."""
    import numpy as np
    U = sm.Matrix(model.u)
    Jc = model.fc.jacobian(model.q)
    ft = model.fc.diff(model.t)
    worst, scale = 0.0, 1.0
    for _attempt in range(4):
        vals = {s: rng.uniform(0.3, 1.7) for s in model.q + model.u + model.p + model.r + [model.t]}
        try:
            K = np.array(model.Kqd.xreplace(vals).evalf().tolist(), dtype=float)
            rhs = -np.array((model.Ku * U + model.kf).xreplace(vals).evalf().tolist(),
                            dtype=float).ravel()
            qd = np.linalg.solve(K, rhs)
            J = np.array(Jc.xreplace(vals).evalf().tolist(), dtype=float)
            d = J @ qd + np.array(ft.xreplace(vals).evalf().tolist(), dtype=float).ravel()
        except (TypeError, ValueError, np.linalg.LinAlgError):
            continue
        worst = max(worst, float(np.max(np.abs(d))))
        scale = max(scale, float(np.max(np.abs(J))) * float(np.max(np.abs(qd))))
    if not worst <= 1e-9 * scale:
        raise ModelError(
            f"{model.mc} configuration constraints but only {model.mv} velocity constraints, "
            "and the time derivative of the configuration constraints does not follow from "
            "the kinematic equations (|d f_c/dt| = "
            f"{worst:.3g} at a sample point): give each configuration constraint its time "
            "derivative among the velocity constraints (with a dependent speed), or among "
            "the kinematic equations")
