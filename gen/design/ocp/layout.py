"""Layout and assembly of a transcribed problem: where every unknown lives
in the decision vector z, the instances of every family (what each
gathers from z, its rows, its data), and the index tables the node loop
(csrc/products/ocp/gen_rt_ocp.c) scatters through into IPOPT's arrays.
Everything here is data the library reads at run time: bounds, boundary
values, fit data and the duration change without a rebuild."""
from __future__ import annotations

import math

import numpy as np

from ...core.errors import InputError
from .events import assemble_events, jump_phases

__all__ = ["Layout", "Block", "Assembly", "assemble", "cost_points", "index_tables"]


class Layout:
    """Where every unknown lives in the decision vector z, and the
    collocation points."""

    def __init__(self, method, N, nq, nu, nr, mv, mc, npf, phases=1, impulses=0):
        nx = nq + nu
        self.N, self.nx, self.nr, self.phases = N, nx, nr, phases
        self.NN = NN = N * phases          # every phase's N nodes, in order
        n = 0

        def take(k):
            nonlocal n
            a = list(range(n, n + k))      # plain ints: assembly indexes them often
            n += k
            return a
        node_pt = {"backward-euler": lambda k: k > 0, "midpoint": lambda k: False,
                   "trapezoidal": lambda k: True, "hermite-simpson": lambda k: True}[method]
        mid_pt = method in ("midpoint", "hermite-simpson")
        self.X, self.R, self.XM, self.RM = [], [], [], []
        self.points = []        # (x terms, r terms, s, lam, mu, time terms, own state)
        self.node_point, self.mid_point, self.mid_index = {}, {}, {}
        for k in range(NN):
            kl = k % N
            self.X.append(take(nx))
            self.R.append(take(nr))
            if node_pt(kl):
                self.node_point[k] = (take(nx), take(mv), take(0))
            if kl < N - 1 and mid_pt:
                self.mid_index[k] = len(self.mid_index)
                if method == "hermite-simpson":
                    self.XM.append(take(nx))
                    self.RM.append(take(nr))
                # (slopes, multipliers, the midpoint's velocity correction)
                self.mid_point[k] = (take(nx), take(mv),
                                     take(mc if method == "hermite-simpson" else 0))
        self.P = take(npf)
        self.Ts = take(phases)             # each phase's duration
        self.T = int(self.Ts[0])
        self.L = take(impulses)            # the impacts' impulses ending phases
        self.n = n
        for k in range(NN):
            if k in self.node_point:
                s, lam, mu = self.node_point[k]
                self.points.append(([(self.X[k], 1.0)], [(self.R[k], 1.0)], s, lam, mu,
                                    self.tnode(k), ("node", k)))
            if k in self.mid_point:
                s, lam, mu = self.mid_point[k]
                if method == "hermite-simpson":
                    i = self.mid_index[k]
                    xs, rs = [(self.XM[i], 1.0)], [(self.RM[i], 1.0)]
                else:
                    xs = [(self.X[k], 0.5), (self.X[k + 1], 0.5)]
                    rs = [(self.R[k], 0.5), (self.R[k + 1], 0.5)]
                self.points.append((xs, rs, s, lam, mu, self.tnode(k, 0.5), ("mid", k)))

    def tnode(self, k, frac=0.0):
        """The time at node k (plus frac intervals) as terms of z: the
        durations of the phases before k's and the fraction of its own."""
        ph, kl = divmod(k, self.N)
        return ([(int(self.Ts[i]), 1.0) for i in range(ph)]
                + [(int(self.Ts[ph]), (kl + frac) / (self.N - 1))])

    def h(self, k):
        """The terms of the step h of the interval at node k (its phase's
        duration)."""
        return [(int(self.Ts[k // self.N]), 1.0)]


class Block:
    """One family's instances: gathers, data, rows (assembled to arrays)."""

    def __init__(self, fi, fam):
        self.fi, self.fam = fi, fam
        self.gathers, self.data, self.row0 = [], [], []

    def add(self, gather, data=(), row0=-1):
        assert len(gather) == len(self.fam["locals"]), (self.fam["name"], len(gather))
        self.gathers.append(gather)
        self.data.append(list(data))
        self.row0.append(row0)


class Assembly:
    """The problem being assembled: its blocks (in the order of their
    first instance), its constraint rows and their bounds."""

    def __init__(self, meta, lay):
        self.fams = {f["name"]: (fi, f) for fi, f in enumerate(meta)}
        self.lay = lay
        self.blocks = {}
        self.rows = 0
        self.row_lo, self.row_hi = [], []

    def fam(self, name):
        return self.fams[name][1]

    def block(self, name):
        if name not in self.blocks:
            fi, f = self.fams[name]
            self.blocks[name] = Block(fi, f)
        return self.blocks[name]

    def con_rows(self, f, lo=None, hi=None):
        """The first of f's next constraint rows, with their bounds (0: an
        equality)."""
        r0 = self.rows
        self.rows += f["nrow"]
        self.row_lo.extend(lo if lo is not None else [0.0] * f["nrow"])
        self.row_hi.extend(hi if hi is not None else [0.0] * f["nrow"])
        return r0

    def gather(self, f, xs, rs, c, s=None, lam=None, extra=None, T=None):
        """Each local of f as terms (z index, coefficient): the states and
        inputs from xs and rs (sums of (index array, coefficient)), the
        slopes s, the multipliers lam, the time as terms c (a number: c T),
        the duration T as terms (default the first phase's), the rest from
        extra {(role, i): terms}."""
        lay = self.lay
        g = []
        for role, i in f["locals"]:
            if role == "x":
                g.append([(int(idx[i]), cf) for idx, cf in xs])
            elif role == "r":
                g.append([(int(idx[i]), cf) for idx, cf in rs])
            elif role == "s":
                g.append([(int(s[i]), 1.0)])
            elif role == "lam":
                g.append([(int(lam[i]), 1.0)])
            elif role == "pf":
                g.append([(int(lay.P[i]), 1.0)])
            elif role == "t":
                g.append(list(c) if isinstance(c, list) else [(lay.T, c)])
            elif role == "T":
                g.append(list(T) if T is not None else [(lay.T, 1.0)])
            else:
                g.append(extra[(role, i)])
        return g


def _points(a, ocp):
    """The point equations at every collocation point, the manifold at the
    nodes (but those the boundary values fix) and the acceleration
    constraints at the nodes."""
    lay, NN = a.lay, a.lay.NN
    pt = a.fam("point")
    for xs, rs, s, lam, mu, c, own in lay.points:
        a.block("point").add(a.gather(pt, xs, rs, c, s, lam), row0=a.con_rows(pt))
    skip = ocp._fixed_manifold_nodes()
    for name in ("velocity", "holonomic"):
        if name not in a.fams:
            continue
        mf = a.fam(name)
        for k in range(NN):
            if k not in skip[name]:
                a.block(name).add(a.gather(mf, [(lay.X[k], 1.0)], [], lay.tnode(k)),
                                  row0=a.con_rows(mf))
    if "acceleration" in a.fams:
        af = a.fam("acceleration")
        for k in range(NN):
            a.block("acceleration").add(
                a.gather(af, [(lay.X[k], 1.0)], [], lay.tnode(k), lay.node_point[k][0]),
                row0=a.con_rows(af))


def _defects(a, ocp):
    lay, nx = a.lay, ocp.model.nx
    df = a.fam("defect")
    for k in range(lay.NN - 1):
        if (k + 1) % lay.N == 0:
            continue                # a phase's last node: the events join the next
        ex = {}
        for i in range(nx):
            ex[("xa", i)] = [(int(lay.X[k][i]), 1.0)]
            ex[("xb", i)] = [(int(lay.X[k + 1][i]), 1.0)]
            if k in lay.node_point:
                ex[("sa", i)] = [(int(lay.node_point[k][0][i]), 1.0)]
            if k + 1 in lay.node_point:
                ex[("sb", i)] = [(int(lay.node_point[k + 1][0][i]), 1.0)]
            if k in lay.mid_point:
                ex[("sm", i)] = [(int(lay.mid_point[k][0][i]), 1.0)]
            if lay.XM:
                ex[("xm", i)] = [(int(lay.XM[lay.mid_index[k]][i]), 1.0)]
        if k in lay.mid_point:
            for i, g in enumerate(lay.mid_point[k][2]):
                ex[("mu", i)] = [(int(g), 1.0)]
        a.block("defect").add(a.gather(df, [], [], 0.0, extra=ex, T=lay.h(k)),
                              row0=a.con_rows(df))


def _costs(a, ocp):
    """The running cost (the method's quadrature weights, times h in the
    kernel), the terminal cost and the path constraints."""
    lay, N = a.lay, a.lay.NN
    if "cost" in a.fams:
        cf = a.fam("cost")
        for xs, rs, s, lam, mu, c, k0 in cost_points(ocp.method, lay.N, lay):
            a.block("cost").add(a.gather(cf, xs, rs, c, T=lay.h(k0)), data=[s])
    if "terminal" in a.fams:
        tf = a.fam("terminal")
        a.block("terminal").add(a.gather(tf, [(lay.X[N - 1], 1.0)], [(lay.R[N - 1], 1.0)], 1.0,
                                         T=lay.tnode(N - 1)))
    if "path" in a.fams:
        pf_ = a.fam("path")
        lo = [v for v, _ in ocp.path_bounds]
        hi = [v for _, v in ocp.path_bounds]
        for k in range(N):
            a.block("path").add(a.gather(pf_, [(lay.X[k], 1.0)], [(lay.R[k], 1.0)], lay.tnode(k)),
                                row0=a.con_rows(pf_, lo, hi))


def _instance(a, ocp):
    """The instance constraints, each state at its node."""
    if "instance" not in a.fams:
        return
    lay, N = a.lay, ocp.nodes
    inf = a.fam("instance")
    ex = {}
    T_fixed = None if ocp.free_time else float(ocp.duration)
    for j, ((i, tv), _) in enumerate(ocp._inst_refs):
        if T_fixed is None:
            if tv != 0:
                raise InputError("with a free final time, instance constraints may "
                                 "refer to t = 0 only (use final= for the end)")
            k = 0
        else:
            kf = tv / T_fixed * (N - 1)
            k = int(round(kf))
            if abs(kf - k) > 1e-9 * max(1, N) or not 0 <= k < N:
                raise InputError(f"constraints: the time {tv} is not a node time "
                                 f"(nodes at multiples of {T_fixed / (N - 1)!r} in "
                                 f"[0, {T_fixed}])")
        ex[("inst", j)] = [(int(lay.X[k][i]), 1.0)]
    a.block("instance").add(a.gather(inf, [], [], 0.0, extra=ex), row0=a.con_rows(inf))


def _fits(a, ocp):
    """The fit data, each sample's state interpolated linearly between its
    nodes."""
    lay, N = a.lay, ocp.nodes
    for j in range(len(ocp._fit_keys)):
        name = f"fit{j}"
        ff = a.fam(name)
        td, vals = ocp._fit_data(j)
        Tf = float(ocp.duration)
        for tk, vk in zip(td, vals):
            s = tk / Tf * (N - 1)
            k = min(int(math.floor(s)), N - 2)
            al = s - k
            xs = [(lay.X[k], 1 - al), (lay.X[k + 1], al)]
            rs = [(lay.R[k], 1 - al), (lay.R[k + 1], al)]
            a.block(name).add(a.gather(ff, xs, rs, tk / Tf), data=[vk])


def assemble(ocp, meta):
    """The Assembly of an OptimalControl's problem at its current data
    (bounds, boundary values, duration, fit data): its layout, its blocks
    and rows (meta: the families as data, transcription.ocp_plan)."""
    m = ocp.model
    lay = Layout(ocp.method, ocp.nodes, m.nq, m.nu, m.nr, m.mv, m.mc, len(ocp._pf),
                 max(1, len(ocp._events)), len(jump_phases(ocp._events, ocp.periodic)[1]))
    a = Assembly(meta, lay)
    _points(a, ocp)
    _defects(a, ocp)
    assemble_events(a, ocp)
    _costs(a, ocp)
    _instance(a, ocp)
    _fits(a, ocp)
    return a


def cost_points(method, N, lay):
    """(x terms, r terms, weight, -, -, time terms, a node of its phase) of
    the running cost's quadrature, phase by phase of N nodes (weights in
    units of h)."""
    out = []
    for p0 in range(0, lay.NN, N):
        X, R = lay.X[p0:p0 + N], lay.R[p0:p0 + N]
        if method == "backward-euler":
            for k in range(1, N):
                out.append(([(X[k], 1.0)], [(R[k], 1.0)], 1.0, 0, 0, lay.tnode(p0 + k), p0))
        elif method == "midpoint":
            for k in range(N - 1):
                out.append(([(X[k], .5), (X[k + 1], .5)], [(R[k], .5), (R[k + 1], .5)], 1.0,
                            0, 0, lay.tnode(p0 + k, .5), p0))
        else:
            node_w = 0.5 if method == "trapezoidal" else 1 / 6
            for k in range(N):
                w = node_w * (1 if k in (0, N - 1) else 2)
                out.append(([(X[k], 1.0)], [(R[k], 1.0)], w, 0, 0, lay.tnode(p0 + k), p0))
            if method == "hermite-simpson":
                for k in range(N - 1):
                    i = lay.mid_index[p0 + k]
                    out.append(([(lay.XM[i], 1.0)], [(lay.RM[i], 1.0)], 4 / 6, 0, 0,
                                lay.tnode(p0 + k, .5), p0))
    return out


def _block_arrays(b, jac_slots, hess_slots):
    """One block's index tables (the fields of gen_rt_ocp_block), its
    Jacobian and Hessian nonzeros numbered in jac_slots and hess_slots."""
    f = b.fam
    gstart, gidx, gcoef = [0], [], []
    jstart, jloc, jslot, jcoef = [0], [], [], []
    hstart, hloc, hslot, hcoef = [0], [], [], []
    hfull = {}
    for e, (a, c) in enumerate(f["hess"]):
        hfull.setdefault(a, []).append((c, e))
        if a != c:
            hfull.setdefault(c, []).append((a, e))
    for g, r0 in zip(b.gathers, b.row0):
        for terms in g:
            for idx, cf in terms:
                gidx.append(idx)
                gcoef.append(cf)
            gstart.append(len(gidx))
        for e, (row, a) in enumerate(f["jac"]):
            for idx, cf in g[a]:
                if idx < 0 or cf == 0:
                    continue
                if r0 < 0:
                    slot = idx
                else:
                    slot = jac_slots.setdefault((r0 + row, idx), len(jac_slots))
                jloc.append(e)
                jslot.append(slot)
                jcoef.append(cf)
        jstart.append(len(jloc))
        for a, lst in hfull.items():
            for c, e in lst:
                for ia, ca in g[a]:
                    if ia < 0 or ca == 0:
                        continue
                    for ic, cc in g[c]:
                        if ic < 0 or cc == 0 or ia < ic:
                            continue
                        slot = hess_slots.setdefault((ia, ic), len(hess_slots))
                        hloc.append(e)
                        hslot.append(slot)
                        hcoef.append(ca * cc)
        hstart.append(len(hloc))
    i32 = np.int32
    return dict(
        gstart=np.array(gstart, i32), gidx=np.array(gidx, i32), gcoef=np.array(gcoef, float),
        data=np.array(b.data, float).ravel() if f["nd"] else None,
        row0=np.array(b.row0, i32),
        jstart=np.array(jstart, i32), jloc=np.array(jloc, i32), jslot=np.array(jslot, i32),
        jcoef=np.array(jcoef, float),
        hstart=np.array(hstart, i32), hloc=np.array(hloc, i32), hslot=np.array(hslot, i32),
        hcoef=np.array(hcoef, float))


def index_tables(blocks):
    """(the index tables of every block, the Jacobian's (rows, cols), the
    Hessian's (rows, cols)): the sparsity IPOPT is told, in slot order."""
    jac_slots, hess_slots = {}, {}
    arrays = [_block_arrays(b, jac_slots, hess_slots) for b in blocks]
    jk = sorted(jac_slots, key=jac_slots.get)
    hk = sorted(hess_slots, key=hess_slots.get)
    return (arrays, (np.array([r for r, _ in jk], np.int32), np.array([c for _, c in jk], np.int32)),
            (np.array([r for r, _ in hk], np.int32), np.array([c for _, c in hk], np.int32)))
