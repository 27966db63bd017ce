"""Hybrid behaviour declared on a model: impacts, resets and persistent contact.

``Model.from_kanes(..., hybrid={name: gen.Impact(gap, ...) or gen.Reset(guard, map)})``
(and the same keyword of ``from_lagrange``, ``from_system`` and
``from_matrices``). Everything declared runs in the C runtime
(``csrc/gen_rt_hybrid.c`` and the simulation engine of
``csrc/gen_rt_simulate.c``): this module checks the declarations, turns them
into the model's internal symbols and gives the generator the kernels'
expressions (:func:`hybrid_kernels`):

- ``hybrid_values(q, u, p, t) -> g`` (nh): every gap and guard;
- ``hybrid_jacobian(q, p, t) -> W (nh x nu), w (nh)``: a gap's rate
  ``g' = W u + w`` through the kinematic equations (zero rows for resets);
- ``hybrid_bias(q, u, p, t) -> h`` (nh): ``g'' = W u' + h``, the bias of a
  persistent contact held as a constraint;
- ``hybrid_reset(q, u, p, t) -> xr`` (nreset x nx): the maps of the resets.

See ``docs/guides/hybrid.md`` for the rules (impulse solve, Zeno, lift-off).
"""
from __future__ import annotations

import numbers

import sympy as sm

from ..core.errors import ModelError
from .sympy_compat import time_symbol

__all__ = ["Impact", "Reset", "attach_hybrid", "hybrid_kernels", "hybrid_symbols", "HybridDecl",
           "KIND_IMPACT", "KIND_RESET", "hybrid_work_len", "hybrid_iwork_len"]

KIND_IMPACT, KIND_RESET = 0, 1
_DIRECTIONS = (-1, 0, 1)


def _check_direction(direction, what):
    if isinstance(direction, bool) or not isinstance(direction, numbers.Integral) \
            or int(direction) not in _DIRECTIONS:
        raise ModelError(f"{what}: direction must be -1 (closing, downwards), 0 (both) or "
                         f"+1 (upwards), got {direction!r}")
    return int(direction)


def _scalar(expr, who, what):
    """expr as one sympy expression; a matrix, list or array is refused,
    naming its size (one declaration per gap or guard)."""
    shape = getattr(expr, "shape", None)
    if isinstance(expr, (list, tuple)):
        shape = (len(expr),)
    if shape is not None and shape != ():
        size = " x ".join(str(n) for n in shape)
        kind = "list" if isinstance(expr, (list, tuple)) else \
            "matrix" if isinstance(expr, sm.MatrixBase) else "array"
        raise ModelError(f"{who}: the {what} must be one scalar expression, got a {size} {kind} "
                         f"({expr}); declare one gen.{who.split('(')[0]} per {what.split('[')[0]} "
                         "under names of their own (hybrid={'a': ..., 'b': ...})")
    try:
        e = sm.sympify(expr)
    except (sm.SympifyError, TypeError) as err:
        raise ModelError(f"{who}: the {what} must be a sympy expression, got {expr!r}") from err
    if not isinstance(e, sm.Expr):
        raise ModelError(f"{who}: the {what} must be one scalar expression, got "
                         f"{type(e).__name__} ({e}); a gap or guard is an expression whose "
                         "zero crossing is the event (y, not y < 0)")
    return e


class Impact:
    """A unilateral contact: ``gap`` (a sympy expression of the coordinates,
    constants and t) must stay >= 0.

    When the gap reaches zero moving in ``direction`` (-1: closing), the
    generalized speeds jump by the impulse that makes its normal velocity
    ``-restitution`` times its value before, solved with the model's mass
    matrix, the gap's generated gradient and the model's own velocity
    constraints. With ``restitution == 0``, or when the impact speed is below
    ``rest_speed`` (the Zeno rule: a bouncing contact coming to rest), the
    contact persists: the gap is held at zero while its force pushes, and is
    released when that force would pull (lift-off, located as an event).

    Parameters
    ----------
    gap : sympy expression
        A function of the coordinates (and constants, t) only.
    restitution : float, optional
        The coefficient of restitution e in [0, 1].
    direction : {-1, 0, 1}, optional
        The crossing that is an impact: -1 (closing, the default), +1, 0 both.
    rest_speed : float, optional (keyword)
        The Zeno rule's speed: an impact slower than this holds the contact
        (default 1e-6, in the gap's units per unit time).

    Raises
    ------
    gen.ModelError
        For a restitution outside [0, 1], a direction not -1, 0 or 1, or a
        negative rest_speed (and, in the model builder, a gap that is not a
        function of the coordinates, naming the symbols).
    """

    kind = KIND_IMPACT

    def __init__(self, gap, restitution=0.0, direction=-1, *, rest_speed=1e-6):
        self.gap = _scalar(gap, "Impact", "gap")
        try:
            e = float(restitution)
        except (TypeError, ValueError):
            raise ModelError(f"Impact({self.gap}): restitution must be a number in [0, 1], "
                             f"got {restitution!r}") from None
        if not (0.0 <= e <= 1.0):
            raise ModelError(f"Impact({self.gap}): restitution must be in [0, 1], got "
                             f"{restitution!r}")
        self.restitution = e
        self.direction = _check_direction(direction, f"Impact({self.gap})")
        rs = float(rest_speed)
        if not (rs >= 0.0) or rs == float("inf"):
            raise ModelError(f"Impact({self.gap}): rest_speed must be a finite number >= 0, "
                             f"got {rest_speed!r}")
        self.rest_speed = rs

    def __repr__(self):
        return (f"Impact({self.gap}, restitution={self.restitution}, "
                f"direction={self.direction})")


class Reset:
    """A jump of the state: when ``guard`` (a sympy expression of the state)
    crosses zero in ``direction``, the state becomes ``map``.

    Parameters
    ----------
    guard : sympy expression
        Of the coordinates, speeds, constants and t.
    map : dict
        ``{coordinate or speed: expression of the state before}``; entries
        not given keep their value. After the map, the state is projected
        onto the model's constraints; a map whose state violates them
        (beyond a small tolerance) stops the run with
        ``ERR_INCONSISTENT_RESET``.
    direction : {-1, 0, 1}, optional
        -1 (downwards, the default), +1 (upwards) or 0 (both).

    Raises
    ------
    gen.ModelError
        For a map that is not a non-empty dict or a direction not -1, 0 or
        1 (and, in the model builder, a map of something that is not a
        state, or an unknown symbol, naming them).
    """

    kind = KIND_RESET

    def __init__(self, guard, map, direction=-1):   # noqa: A002 (the issue's name)
        self.guard = _scalar(guard, "Reset", "guard")
        if not isinstance(map, dict) or not map:
            raise ModelError(f"Reset({self.guard}): map must be a non-empty dict "
                             f"{{state: expression}}, got {map!r}")
        self.map = {k: _scalar(v, f"Reset({self.guard})", f"map[{_label(k)}]")
                    for k, v in map.items()}
        self.direction = _check_direction(direction, f"Reset({self.guard})")
        self.restitution = 0.0
        self.rest_speed = 0.0

    def __repr__(self):
        return f"Reset({self.guard}, map={self.map}, direction={self.direction})"


class HybridDecl:
    """One declaration in the model's internal symbols."""

    def __init__(self, name, kind, expr, restitution, direction, rest_speed, xmap=None):
        self.name = name
        self.kind = kind
        self.expr = expr            # gap or guard, internal symbols
        self.restitution = restitution
        self.direction = direction
        self.rest_speed = rest_speed
        self.xmap = xmap            # Reset: nx expressions (the state after)

    def key(self):
        return (self.name, self.kind, sm.srepr(self.expr), self.restitution, self.direction,
                self.rest_speed, None if self.xmap is None else [sm.srepr(e) for e in self.xmap])


def hybrid_symbols(hybrid):
    """The user's symbols (constants, inputs, coordinates) that the
    declarations of ``hybrid={...}`` hold: a constant used only in a guard
    or a map is used (no UnusedConstantWarning). Empty for anything that is
    not a dict of declarations (attach_hybrid names the problem)."""
    out = set()
    if not isinstance(hybrid, dict):
        return out
    for d in hybrid.values():
        exprs = [d.gap] if isinstance(d, Impact) else \
            [d.guard, *d.map.values()] if isinstance(d, Reset) else []
        for e in exprs:
            out |= getattr(e, "free_symbols", set())
            out |= {a for a in getattr(e, "atoms", lambda *_: ())(sm.Function)
                    if isinstance(a, sm.core.function.AppliedUndef)}
    return out


def _user_names(model):
    return ", ".join(model.state_labels)


def attach_hybrid(model, hybrid):
    """Check ``hybrid={name: Impact | Reset}`` and store it on the model
    (``model.hybrid``, a list of HybridDecl in the dict's order)."""
    if hybrid is None:
        return model
    if not isinstance(hybrid, dict) or not hybrid:
        raise ModelError(f"model '{model.name}': hybrid must be a non-empty dict "
                         f"{{name: gen.Impact(...) or gen.Reset(...)}}, got {hybrid!r}")
    if getattr(model, "aux_G", None) is not None and any(
            isinstance(d, Impact) for d in hybrid.values()):
        names = ", ".join(_label(x) for x in model.reaction_orig)
        raise ModelError(f"model '{model.name}': gen.Impact on a model whose reactions ({names}) "
                         f"enter its motion is not supported (the impulse and the held contact "
                         f"would leave out the coupled reaction solve); gen.Reset is")
    ctx = _Symbols(model)
    decls = []
    for name, d in hybrid.items():
        if not isinstance(name, str) or not name.isidentifier():
            raise ModelError(f"model '{model.name}': hybrid names must be identifiers, got "
                             f"{name!r}")
        if not isinstance(d, (Impact, Reset)):
            raise ModelError(f"model '{model.name}': hybrid[{name!r}] must be gen.Impact or "
                             f"gen.Reset, got {d!r}")
        decls.append(_impact(ctx, name, d) if isinstance(d, Impact) else _reset(ctx, name, d))
    model.hybrid = decls
    return model


class _Symbols:
    """The user's symbols of a model and its internal ones, both ways."""

    def __init__(self, model):
        t = time_symbol()
        self.model = model
        self.qdots = [qo.diff(t) for qo in model.q_orig]
        sub = dict(zip(self.qdots, model.u)) if model.method == "lagrange" else \
            dict(zip(model.u_orig, model.u))
        sub.update(dict(zip(model.q_orig, model.q)))
        sub.update(dict(zip(model.p_orig, model.p)))
        sub.update(dict(zip(model.r_orig, model.r)))
        sub[t] = model.t
        self.sub, self.back = sub, {v: k for k, v in sub.items()}
        self.states = list(model.q_orig) + (self.qdots if model.method == "lagrange"
                                            else list(model.u_orig))
        self.Q, self.U = set(model.q), set(model.u)
        self.P, self.R = set(model.p), set(model.r)

    def labels(self, symbols):
        """The user's spelling of internal symbols, sorted."""
        return sorted(_label(self.back.get(s, s)) for s in symbols)

    def no_inputs(self, name, what, user_expr, e, rule):
        """Refuse an input in a gap, guard or map, naming the user's input."""
        bad = self.labels(e.free_symbols & self.R)
        if bad:
            m = self.model
            raise ModelError(f"model '{m.name}': the {what} of {name!r} ({user_expr}) holds the "
                             f"input(s) {', '.join(bad)}; {rule} (the engine evaluates it "
                             "without the inputs)")


def _impact(ctx, name, d):
    """The HybridDecl of an Impact, its gap checked: a scalar function of
    the coordinates (and constants, t)."""
    m = ctx.model
    e = d.gap.xreplace(ctx.sub)
    bad_u = ctx.labels(e.free_symbols & ctx.U)
    bad_u += [_label(qd) for qd in ctx.qdots if d.gap.has(qd)]
    if bad_u:
        raise ModelError(
            f"model '{m.name}': the gap of impact {name!r} ({d.gap}) must be a function of the "
            f"coordinates, but it holds the speed(s) {', '.join(bad_u)}; coordinates: "
            f"{', '.join(_label(s) for s in m.q_orig)}")
    ctx.no_inputs(name, "gap", d.gap, e, "a gap is a function of the coordinates")
    _check_known(ctx, name, "gap", d.gap, e, ctx.Q | ctx.P | {m.t})
    if e.is_number:
        raise ModelError(f"model '{m.name}': the gap of impact {name!r} ({d.gap}) is constant; "
                         "a gap is a function of the coordinates "
                         f"{', '.join(_label(s) for s in m.q_orig)}")
    return HybridDecl(name, KIND_IMPACT, e, d.restitution, d.direction, d.rest_speed)


def _reset(ctx, name, d):
    """The HybridDecl of a Reset, its guard and map checked: functions of the
    state (and constants, t), the map's keys states."""
    m = ctx.model
    allowed = ctx.Q | ctx.U | ctx.P | {m.t}
    e = d.guard.xreplace(ctx.sub)
    ctx.no_inputs(name, "guard", d.guard, e, "a guard is a function of the state, the "
                  "constants and t")
    _check_known(ctx, name, "guard", d.guard, e, allowed)
    xmap = list(m.q) + list(m.u)
    for k, v in d.map.items():
        if k not in ctx.states:
            raise ModelError(f"model '{m.name}': the map of reset {name!r} sets {_label(k)}, "
                             f"which is not a state; the states are {_user_names(m)}")
        ve = v.xreplace(ctx.sub)
        ctx.no_inputs(name, f"map[{_label(k)}]", v, ve, "a map is a function of the state "
                      "before the jump, the constants and t")
        _check_known(ctx, name, f"map[{_label(k)}]", v, ve, allowed)
        xmap[ctx.states.index(k)] = ve
    return HybridDecl(name, KIND_RESET, e, 0.0, d.direction, 0.0, xmap)


def _label(s):
    """A symbol as the user wrote it: y for y(t), y' for its derivative."""
    if isinstance(s, sm.Derivative):
        return _label(s.expr) + "'"
    if isinstance(s, sm.core.function.AppliedUndef):
        return s.func.__name__
    return str(s)


def _check_known(ctx, name, what, user_expr, e, allowed):
    """Refuse a symbol that is not the model's, in the user's spelling."""
    m = ctx.model
    unknown = e.free_symbols - allowed
    fns = {a for a in e.atoms(sm.Function) if isinstance(a, sm.core.function.AppliedUndef)}
    if unknown or fns:
        names = sorted(set(ctx.labels(unknown)) | {_label(f) for f in fns})
        raise ModelError(
            f"model '{m.name}': the {what} of {name!r} ({user_expr}) holds unknown "
            f"symbol(s) {', '.join(names)}: neither a coordinate "
            f"({', '.join(_label(s) for s in m.q_orig)}), a speed nor a constant "
            f"({', '.join(str(s) for s in m.p_orig) or 'none'})")


def _qdot(model):
    if model.qdot is not None:
        return sm.Matrix(model.qdot)
    U = sm.Matrix(model.u)
    return model.Kqd.LUsolve(-(model.Ku * U + model.kf))


def hybrid_kernels(model):
    """The hybrid kernels' outputs: [(kernel name, args, [(out name, Matrix)])]
    with args a subset of "q", "u", "p", "t"."""
    decls = getattr(model, "hybrid", None) or []
    if not decls:
        return []
    U = sm.Matrix(model.u)
    qdot = _qdot(model)
    g = sm.Matrix([d.expr for d in decls])
    W, w, h = [], [], []
    for d in decls:
        if d.kind != KIND_IMPACT:
            W.append([sm.S.Zero] * model.nu)
            w.append(sm.S.Zero)
            h.append(sm.S.Zero)
            continue
        grad = [d.expr.diff(q) for q in model.q]
        gdot = sum((gi * qd for gi, qd in zip(grad, qdot)), sm.S.Zero) + d.expr.diff(model.t)
        row = [gdot.diff(ui) for ui in model.u]
        w0 = gdot.xreplace({ui: 0 for ui in model.u})
        W.append(row)
        w.append(w0)
        # g'' = W u' + h: h = d(gdot)/dq q' + d(gdot)/dt at u' = 0
        h.append(sum((gdot.diff(q) * qd for q, qd in zip(model.q, qdot)), sm.S.Zero)
                 + gdot.diff(model.t))
    out = [("hybrid_values", "qupt", [("g", g)]),
           ("hybrid_jacobian", "qpt", [("W", sm.Matrix(W)), ("w", sm.Matrix(w))]),
           ("hybrid_bias", "qupt", [("h", sm.Matrix(h))])]
    resets = [d for d in decls if d.kind == KIND_RESET]
    if resets:
        xr = sm.Matrix([e for d in resets for e in d.xmap])
        out.append(("hybrid_reset", "qupt", [("xr", xr)]))
    return out


def _accel_work(n, m):
    return (n + m) * (n + m + 1) + 2 * n * n + 4 * n + 1


def hybrid_work_len(nq, nu, mv, nh):
    """Reals of the engine's hybrid scratch: GEN_RT_HYBRID_WORK of
    csrc/gen_rt.h (tests/features/test_hybrid.py checks the two agree)."""
    core = (nu * nu + 2 * nu + 3 * (mv + nh) + (mv + nh) * nu + nq * nq + nq + nh * nu + 2 * nh
            + _accel_work(nu, mv + nh))
    fn = max(core + 2 * nh + nq + nu + 1, nh * (nq + nu) + nq + nu + 1)
    return fn + 5 * nh + 2 * (nq + nu) + 8


def hybrid_iwork_len(nq, nu, mv, nh):
    """Ints of the engine's hybrid scratch: GEN_RT_HYBRID_IWORK."""
    return nq + (nu + mv + nh + 1) + 3 * nh + 4
