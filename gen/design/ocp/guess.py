"""The first iterate of a transcribed problem: the user's guess of the
states, inputs, parameters and duration, and the transcription's added
unknowns made consistent with it before IPOPT starts (issue 47).

The slopes s = [q', u'] and the velocity constraints' multipliers lam at
every collocation point are solved from the model's own equations at the
guessed state and input (the point equations are linear in them: one
Newton step on each point's small block, a couple more when the
acceleration constraints hold there), the Hermite-Simpson midpoint states
are the Hermite interpolant of the nodes' states and slopes, and the
midpoint velocity corrections mu are zero. The first iterate's
infeasibility is then the defects' alone, as in a transcription with the
explicit right-hand side (CasADi's, opty's), not the model's equations
violated by the size of their forces."""
from __future__ import annotations

import numpy as np

from ...core.errors import InputError
from .solution import OptimalSolution

__all__ = ["start_point", "consistent", "row_scaling"]


def _boundary_states(ocp):
    """The initial and final states of the default guess (zero where not
    given; the final values default to the initial ones)."""
    nx = ocp.model.nx
    x0, x1 = np.zeros(nx), np.zeros(nx)
    for (_, i), v in ocp._values("initial").items():
        x0[i] = x1[i] = v
    for (_, i), v in ocp._values("final").items():
        x1[i] = v
    return x0, x1


def _read_dict(ocp, guess, X, R, z):
    """A dict guess {state or input: value or array over the nodes (every
    phase's, in order), parameter: value, "duration": T (or one per
    phase)} into X, R and z's parameters and durations."""
    nm, lay, N = ocp._names, ocp._lay, ocp._lay.NN
    for k, v in guess.items():
        if isinstance(k, str) and k == "duration":
            d = np.atleast_1d(np.asarray(v, dtype=object))
            if d.size not in (1, lay.phases):
                raise InputError(f"guess['duration'] must be a number or one per phase "
                                 f"({lay.phases}), got {_short(v)}")
            z[lay.Ts] = [_finite(e, "guess['duration']") for e in np.broadcast_to(d, (lay.phases,))]
            continue
        kind, i = nm.key(k, "guess")
        try:
            v = np.broadcast_to(np.asarray(v, float), (N,))
        except (TypeError, ValueError):
            raise InputError(f"guess[{k}] must be a number or an array of the {N} nodes' "
                             f"values, got {_short(v)}") from None
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise InputError(f"guess[{k}][{bad[0]}] = {v[bad[0]]}: not a finite number")
        if kind == "x":
            X[:, i] = v
        elif kind == "r":
            R[:, i] = v
        elif kind == "p" and i in ocp._pf:
            z[lay.P[ocp._pf.index(i)]] = float(v[0])
        elif kind == "p":
            raise InputError(f"guess: {k} is a known constant, not one of the parameters to "
                             "identify (change ocp.constants instead)")
        else:
            raise InputError(f"guess: {k} is an output; a guess gives states, inputs, "
                             "parameters to identify and 'duration'")


def _short(v):
    s = repr(v)
    return s if len(s) < 60 else s[:57] + "..."


def _finite(v, what):
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be a number, got {_short(v)}") from None
    if not np.isfinite(f):
        raise InputError(f"{what} = {f}: not a finite number")
    return f


def start_point(ocp, guess, lb, ub):
    """The first iterate z0 of ocp's assembled problem from the user's guess
    (None, a dict, an OptimalSolution or the whole vector), within the
    bounds lb, ub, the added unknowns consistent with it."""
    m, lay, N = ocp.model, ocp._lay, ocp._lay.NN
    z = np.zeros(lay.n)
    z[lay.Ts] = 0.5 * (lb[lay.Ts] + ub[lay.Ts])
    p = ocp._pvec()
    for j, i in enumerate(ocp._pf):
        z[lay.P[j]] = p[i]
    if isinstance(guess, OptimalSolution) and guess._z is not None \
            and guess._z.size == lay.n and guess._layout_key == ocp._layout_key():
        return np.clip(guess._z, lb, ub)                  # a warm start: as it was
    if not (guess is None or isinstance(guess, (dict, OptimalSolution))):
        g = np.asarray(guess, float).ravel()
        if g.size != lay.n:
            raise InputError(f"guess: an array must have the problem's {lay.n} unknowns, "
                             f"got {g.size}")
        if not np.all(np.isfinite(g)):
            raise InputError(f"guess[{int(np.flatnonzero(~np.isfinite(g))[0])}]: not a finite "
                             "number")
        return np.clip(g, lb, ub)
    tau = np.linspace(0.0, 1.0, N)
    x0, x1 = _boundary_states(ocp)
    X = x0[None, :] + tau[:, None] * (x1 - x0)[None, :]
    R = np.zeros((N, m.nr))
    RM = None
    if isinstance(guess, OptimalSolution) and lay.phases > 1:
        raise InputError("guess: a solution of another problem is a guess of a one-phase "
                         "problem only; give a dict (its phases' nodes in order)")
    if isinstance(guess, OptimalSolution):
        Tg = guess.t[-1]
        X, R = guess(tau * Tg), guess.input(tau * Tg).reshape(N, m.nr)
        if lay.RM:
            RM = guess.input((tau[:-1] + 0.5 / (N - 1)) * Tg).reshape(N - 1, m.nr)
        if ocp.free_time:
            z[lay.T] = Tg
        for j, v in enumerate(guess.p):
            z[lay.P[j]] = v
    elif isinstance(guess, dict):
        _read_dict(ocp, guess, X, R, z)
    for k in range(N):
        z[lay.X[k]] = X[k]
        z[lay.R[k]] = R[k]
    z = np.clip(z, lb, ub)
    if RM is None:
        RM = np.array([0.5 * (R[k] + R[k + 1]) for k in lay.mid_index])
    for k in range(len(lay.RM)):
        z[lay.RM[k]] = RM[k]
    consistent(ocp, z, lb, ub)
    return np.clip(z, lb, ub)


def _point_blocks(ocp, which):
    """For the collocation points of kind which ("node" or "mid"): their
    rows (the point equations, and the acceleration constraints at a
    node) and their own unknowns (slopes, multipliers), as index arrays
    (npoints, rows) and (npoints, unknowns)."""
    lay, rows0 = ocp._lay, ocp._rows0
    nx, mv = ocp.model.nx, ocp.model.mv
    acc = {}
    if "acceleration" in rows0:
        acc = dict(zip(range(ocp.nodes), rows0["acceleration"]))
    rows, cols, at = [], [], []
    for j, (xs, rs, s, lam, mu, c, (kind, k)) in enumerate(lay.points):
        if kind != which:
            continue
        r0 = rows0["point"][j]
        r = list(range(r0, r0 + nx))
        if kind == "node" and k in acc:
            r += list(range(acc[k], acc[k] + mv))
        rows.append(r)
        cols.append(list(s) + list(lam))
        at.append(k)
    return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64), at


def _solve_points(ocp, z, which, iterations=3):
    """The slopes and multipliers of the points of kind which, solved from
    the point (and acceleration) equations at z's states and inputs, in
    place: Newton on each point's block (the point equations are linear in
    them), least squares where a block is singular or not square."""
    rows, cols, _ = _point_blocks(ocp, which)
    if not rows.size:
        return
    P, nr, nc = rows.shape[0], rows.shape[1], cols.shape[1]
    n, m = ocp._lay.n, ocp._m_rows
    rpoint = np.full(m, -1, np.int64)
    rlocal = np.full(m, -1, np.int64)
    rpoint[rows.ravel()] = np.repeat(np.arange(P), nr)
    rlocal[rows.ravel()] = np.tile(np.arange(nr), P)
    cpoint = np.full(n, -1, np.int64)
    clocal = np.full(n, -1, np.int64)
    cpoint[cols.ravel()] = np.repeat(np.arange(P), nc)
    clocal[cols.ravel()] = np.tile(np.arange(nc), P)
    jr, jc = ocp._jrows.astype(np.int64), ocp._jcols.astype(np.int64)
    mine = (rpoint[jr] >= 0) & (rpoint[jr] == cpoint[jc])
    jr, jc = jr[mine], jc[mine]
    for _ in range(iterations):
        g = ocp.evaluate(z, "constraints")
        b = g[rows]
        ok = np.all(np.isfinite(b), axis=1)
        if np.abs(b[ok]).max(initial=0.0) <= 1e-12 * max(1.0, np.abs(z[cols[ok]]).max(initial=0)):
            break
        vals = ocp.evaluate(z, "jacobian")[mine]
        B = np.zeros((P, nr, nc))
        np.add.at(B, (rpoint[jr], rlocal[jr], clocal[jc]), vals)
        ok &= np.all(np.isfinite(B), axis=(1, 2))
        step = np.zeros((P, nc))
        if ok.any():
            step[ok] = -np.einsum("pij,pj->pi", np.linalg.pinv(B[ok]), b[ok])
        step[~np.all(np.isfinite(step), axis=1)] = 0.0
        z[cols] += step


def consistent(ocp, z, lb, ub):
    """The slopes, multipliers and (Hermite-Simpson) midpoint states of z
    made consistent with its nodes' states and inputs, in place: first the
    nodes' points, then the midpoint states from the Hermite interpolant,
    then the midpoints' points; the midpoint velocity corrections zero."""
    lay, N = ocp._lay, ocp.nodes
    for k in list(lay.node_point) + list(lay.mid_point):
        pts = lay.node_point.get(k), lay.mid_point.get(k)
        for pt in pts:
            if pt is not None:
                z[pt[0]] = 0.0
                z[pt[1]] = 0.0
                z[pt[2]] = 0.0
    _solve_points(ocp, z, "node")
    if lay.XM:
        for k, i in lay.mid_index.items():
            h = z[lay.Ts[k // N]] / (N - 1)
            x0, x1 = z[lay.X[k]], z[lay.X[k + 1]]
            s0, s1 = z[lay.node_point[k][0]], z[lay.node_point[k + 1][0]]
            xm = 0.5 * (x0 + x1) + h / 8 * (s0 - s1)
            z[lay.XM[i]] = np.clip(xm, lb[lay.XM[i]], ub[lay.XM[i]])
    _solve_points(ocp, z, "mid")


def row_scaling(ocp, z):
    """IPOPT's constraint scaling (user-scaling): each point row in the
    units of a state's change over one interval, h over its largest
    derivative by its own point's slopes (h over the mass matrix's
    diagonal for the dynamics, h for the kinematics), so that the model's
    equations and the defects (a change of state over an interval) weigh
    alike, and so do their multipliers; the other rows 1. Unscaled, the
    point rows' multipliers are h times the defects' and IPOPT's first
    iterates stall (the brachistochrone of issue 47)."""
    lay, N = ocp._lay, ocp.nodes
    g = np.ones(ocp._m_rows)
    h = np.mean(z[lay.Ts]) / (N - 1)      # the phases' mean step: a scale
    jr, jc = ocp._jrows.astype(np.int64), ocp._jcols.astype(np.int64)
    J = np.abs(ocp.evaluate(z, "jacobian"))
    slope = np.zeros(lay.n, bool)
    for pt in list(lay.node_point.values()) + list(lay.mid_point.values()):
        slope[pt[0]] = True
    prow = np.zeros(ocp._m_rows, bool)
    nx = ocp.model.nx
    for r0 in ocp._rows0["point"]:
        prow[r0:r0 + nx] = True
    d = np.zeros(ocp._m_rows)
    sel = slope[jc] & prow[jr] & np.isfinite(J)
    np.maximum.at(d, jr[sel], J[sel])
    g[prow] = np.where(d[prow] > 0, h / np.maximum(d[prow], 1e-300), h)
    return g
