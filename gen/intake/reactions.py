"""Reaction forces along auxiliary speeds (Kane's ``u_auxiliary``): finding
them in the auxiliary equations, and, when they enter the motion (friction
``-mu*N`` on a normal reaction N), eliminating them symbolically or leaving
them to the run time's coupled solve, refused when that solve is singular at
every state.

The auxiliary equations are ``aux_F reactions + aux_g = 0`` (``aux_g`` holds
u'); a model whose reactions enter its forcing has ``M u' = f0 + G N``:

- ``eliminate_reactions(..., eliminate=True)`` (the default of
  ``Model.from_kanes(..., eliminate_reactions=True)``): when aux_F is
  constant and regular and N's share of the motion leaves the matrix of u'
  free of the speeds, ``N = -aux_F^-1 aux_g(u')`` goes into f exactly and its
  u' terms into M (the usual case: a reaction along its auxiliary direction
  on flat ground);
- otherwise (or with ``eliminate=False``) the reactions stay unknowns and the
  run time solves ``[M, -G; C, aux_F] [u'; N] = [f0; -g0]`` by pivoted LU at
  every evaluation (``gen_rt_accel_reactions``).
"""
from __future__ import annotations

import sympy as sm

from ..core.errors import ModelError
from .checks import sym_name
from .sympy_compat import time_symbol

__all__ = ["auxiliary_zero", "kane_auxiliary", "eliminate_reactions", "check_coupled_regular"]


def auxiliary_zero(uaux, t):
    """({uaux': 0}, {uaux: 0}): replace the derivatives first."""
    return ({s.diff(t): 0 for s in uaux}, {s: 0 for s in uaux})


def kane_auxiliary(km, q, u, uaux, inputs, reactions, t, zero):
    """(F, reactions, g, named) with km.auxiliary_eqs = F reactions + g (in
    the user's functions of time; u' appear in g). The reactions are the
    user's (reactions=[...]) or the functions of time in the auxiliary
    equations that are neither coordinates, speeds, their derivatives nor
    declared inputs, ordered by name; named are the symbols that name the
    auxiliary forces (the reactions).

    When none is found (every force along the auxiliary directions is a
    declared input or constant), there is nothing to solve for: F = I,
    reactions = [], g = the auxiliary equations, named = the auxiliary
    speeds, so that the auxiliary forces are minus the values of the
    auxiliary equations (Kane's Fr + Fr*) at the declared inputs: the
    generalized force each auxiliary direction still needs to keep its
    speed zero (the reaction an unknown force along it would take)."""
    eqs = sm.Matrix(km.auxiliary_eqs).xreplace(zero[0]).xreplace(zero[1])
    na = len(uaux)
    if eqs.shape[0] != na:
        raise ModelError(f"the KanesMethod has {len(uaux)} auxiliary speeds but "
                         f"{eqs.shape[0]} auxiliary equations")
    known = set(q) | set(u) | set(uaux) | set(inputs or [])
    if reactions is None:
        found = set()
        for e in eqs:
            for fn in e.atoms(sm.core.function.AppliedUndef):
                if fn.args == (t,) and fn not in known:
                    found.add(fn)
        reactions = sorted(found, key=sm.default_sort_key)
        where = "found in the auxiliary equations"
    else:
        reactions = list(reactions)
        where = "given in reactions=[...]"
        bad = [r_ for r_ in reactions if r_ in known
               or not (isinstance(r_, sm.Symbol)
                       or (isinstance(r_, sm.core.function.AppliedUndef) and r_.args == (t,)))]
        if bad or len(set(reactions)) != len(reactions):
            raise ModelError(
                f"reactions must be distinct symbols or functions of time that are not "
                f"coordinates, speeds or inputs; got {[sym_name(r_) for r_ in reactions]}")
    names = [sym_name(r_) for r_ in reactions]
    if not reactions and where.startswith("found"):
        # no unknown force: every force along the auxiliary directions is a
        # declared input (or constant). The model is well posed; what the
        # auxiliary equations give is the generalized force w each auxiliary
        # direction still needs, Fr + Fr* + w = 0 at the declared inputs (0
        # when they are the reactions; the reaction itself when an unknown
        # force along it is left out): F = I makes the runtime's solve of
        # F w + g = 0 return w = -g exactly
        return sm.eye(na), [], eqs, list(uaux)
    if len(reactions) != na:
        raise ModelError(
            f"{na} auxiliary speed(s) {[sym_name(s) for s in uaux]} but {len(reactions)} "
            f"reaction force(s) {where}: {names}; apply one unknown force (a "
            "dynamicsymbol) along each auxiliary direction, declare other functions of "
            "time in inputs=[...], or name the reactions with reactions=[...]")
    F = eqs.jacobian(reactions)
    nonlin = sorted({sym_name(r_) for r_ in reactions for e in F if e.has(r_)}
                    | {sym_name(r_) for r_ in reactions for e in eqs
                       if e.has(sm.Derivative(r_, t))})
    if nonlin:
        raise ModelError(f"the auxiliary equations are not linear in the reaction force(s) "
                         f"{', '.join(nonlin)}")
    g = eqs.xreplace({r_: 0 for r_ in reactions})
    return F, reactions, g, reactions


def eliminate_reactions(M, f, aux, udots, coords, constrained=False, eliminate=True):
    """Reactions in the real speeds' equations (friction -mu*N on the normal
    reaction N of an auxiliary speed): M u' = f0 + G N and the auxiliary
    equations aux_F N + aux_g(u') = 0 form one linear system in (u', N).
    Returns (M, f, aux).

    When aux_F is constant and regular and N's share of the motion leaves
    the matrix multiplying u' free of the speeds (a reaction applied along
    its auxiliary direction on flat ground, the usual case), N =
    -aux_F^-1 aux_g(u') is put into f exactly, its u' terms move into M
    (which may then be unsymmetric; the runtime solves it by LU) and aux is
    returned as given. Otherwise (coefficients that depend on the
    configuration, the speeds or the time; a reaction that its own
    auxiliary direction does not determine) the reactions stay unknowns: f
    is returned at N = 0 and aux gains G = df/dN, and the runtime solves
    [M, -G; C, aux_F] [u'; N] = [f0; -g0] (C = d aux_g/du', g0 = aux_g at
    u' = 0) by pivoted LU at every evaluation (gen_rt_accel_reactions).

    eliminate=False sends every reaction inside the motion through the
    coupled solve, eliminable or not (``Model.from_kanes``'s
    ``eliminate_reactions``; bench/bench_reactions.py compares the two)."""
    t = time_symbol()
    F, reactions, g = aux[:3]
    names = [sym_name(r_) for r_ in reactions]
    inM = [n for r_, n in zip(reactions, names) if M.has(r_)]
    if inM:
        raise ModelError(f"the reaction force(s) {', '.join(inM)} appear in the mass matrix of "
                         "the real speeds; not supported")
    G = f.jacobian(reactions)
    nonlin = [n for r_, n in zip(reactions, names) if any(e.has(r_) for e in G)]
    if nonlin:
        raise ModelError(f"the forcing is not linear in the reaction force(s) "
                         f"{', '.join(nonlin)} (for example Abs(N) or a product of "
                         "reactions): eomgen solves the motion and the reactions together "
                         "and needs them to enter linearly")
    C = g.jacobian(udots)
    if any(e.has(*udots) for e in C):
        raise ModelError(f"the auxiliary equations of the reaction force(s) {', '.join(names)} "
                         "are not linear in the accelerations; not supported")
    if any(e.has(ud) for e in G for ud in udots):
        raise ModelError(f"the coefficients of the reaction force(s) {', '.join(names)} in the "
                         "forcing depend on the accelerations; not supported")
    varying = any(fn.args == (t,) for e in F
                  for fn in e.atoms(sm.core.function.AppliedUndef)) \
        or any(e.has(t) for e in F)
    if eliminate and not varying and sm.simplify(F.det()) != 0:
        sol = -F.LUsolve(g)
        f_sub = f.xreplace(dict(zip(reactions, sol)))
        J = f_sub.jacobian(udots)
        speeds = [fn for e in J for fn in e.atoms(sm.core.function.AppliedUndef)
                  if fn not in coords]
        if not any(e.has(ud) for e in J for ud in udots) and not speeds:
            zero = {ud: 0 for ud in udots}
            return M - J, f_sub.xreplace(zero), aux
    if constrained:
        raise ModelError(
            f"the reaction force(s) {', '.join(names)} appear in the equations of motion and "
            "must be solved together with the accelerations, which eomgen does for models "
            "without velocity constraints (dependent speeds); not supported here")
    f0 = f.xreplace({r_: 0 for r_ in reactions})
    check_coupled_regular(M, G, C, F, names)
    return M, f0, tuple(aux[:4]) + (G,)


def check_coupled_regular(M, G, C, H, names):
    """Refuse reactions that the coupled system [M, -G; C, H] leaves
    undetermined at every state (singular at three random points: a
    reaction that neither its auxiliary equations nor the accelerations
    fix), naming them; a system singular only at some configurations is the
    run time's GEN_RT_ERR_SINGULAR_REACTIONS."""
    import numpy as np
    K = sm.Matrix(sm.BlockMatrix([[M, -G], [C, H]]))
    atoms = set()
    for e in K:
        atoms |= {a for a in e.atoms(sm.core.function.AppliedUndef, sm.Symbol)}
    rng = np.random.default_rng(0)
    n = K.shape[0]
    for _ in range(3):
        vals = {a: sm.Float(rng.uniform(0.3, 1.3)) for a in atoms}
        try:
            Kn = np.array(K.xreplace(vals).evalf(), dtype=float)
        except (TypeError, ValueError):
            return                    # not a number at this point: left to the run time
        if np.all(np.isfinite(Kn)) and np.linalg.matrix_rank(Kn) == n:
            return
    raise ModelError(
        f"the reaction force(s) {', '.join(names)} enter the equations of motion but the "
        "auxiliary equations together with the motion do not determine them (the coupled "
        "system in the accelerations and the reactions is singular at random states): apply "
        "each reaction along its auxiliary direction")
