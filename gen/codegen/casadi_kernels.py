"""The CasADi face's function table: which functions the generated library
holds (names, inputs and outputs with their sparsity in CasADi's compressed
column storage, derivative blocks), from a gen.Model alone. Read by the
casadi backend (gen/codegen/backends.py) to render the library and by gen.casadi to
load it; it imports no stage of the pipeline."""
from __future__ import annotations

__all__ = ["NAMES", "STEP_METHODS", "function_specs", "sizes", "derivative_kernels",
           "kernel_context"]

#: the functions, in the order of the dict functions() returns
NAMES = ("rhs", "implicit", "step", "outputs", "constraints")

#: the methods of step (functions(model, step=...)): the library symbol of
#: each (<model>_<symbol>); "rodas4" for unconstrained models only
STEP_METHODS = {"rk4": "step", "rodas4": "step_rodas4"}


def _dense(m, n):
    """CasADi's compressed column storage of a dense m x n matrix."""
    return [m, n, *[j * m for j in range(n + 1)], *[i for _ in range(n) for i in range(m)]]


def _zero(m, n):
    """CasADi's compressed column storage of an m x n structural zero."""
    return [m, n, *([0] * (n + 1))]


def sizes(model):
    """The sizes the derivative code is written over: nw (q', u', lam),
    nz (q, u, r, p, t), mr (the most rows of a function), nv (the most
    differentiable inputs), wk (the scratch of one derivative call)."""
    m = model
    nx, ny = m.nx, len(m.output_names)
    nw, nz = nx + m.mv, nx + m.nr + m.np + 1
    mr = max(1, nx + m.mc + m.mv, ny)
    nv = nz + nx
    wk = (2 * nw * nw + 3 * nw * nz + 3 * nz * nz + 4 * nw + 2 * nz + mr * nz
          + 4 * nx * nv + 4 * nx * nv * nv + 2 * nz * nv + 4 * nx + 16
          + 4 * (nz + nw + nw * nw + nw * nz + nz * nv + nx * nv))     # step's adjoint sweep
    # step_rodas4's first derivatives: f0, Jf and the Hessians of f at z,
    # G = I/(h gamma) - Jf_x, the six stages and their derivatives
    wk = max(wk, 2 * nw * nw + nw * nz + 4 * nw + 2 * nz * nz + nw * nz + 16
             + nx * nz + nx * nz * nz + nx * nx + 6 * nx + 6 * nx * nv + nz * nv
             + nx * nv + 2 * nz + nx)
    return {"nw": nw, "nz": nz, "mr": mr, "nv": nv, "wk": wk,
            "sz_w": mr * nv + nv * nv + mr * nv * nv + nv + wk}


def _cmap(model, name):
    """Where each z = (q, u, r, p, t) column goes among a function's
    differentiable inputs (-1: not an input of it)."""
    m = model
    nx, nr, nz = m.nx, m.nr, m.nx + m.nr + m.np + 1
    if name == "implicit":
        return [j if j < nx else j + nx for j in range(nz)]
    if name == "constraints":
        return [j if j < nx else (-1 if j < nx + nr else j - nr) for j in range(nz)]
    return list(range(nz))


def _holds_t(model):
    """Whether the model's equations hold the time explicitly (then
    step_rodas4 needs df/dt; otherwise it is zero)."""
    m = model
    mats = [m.Kqd, m.Ku, m.kf, m.M, m.f]
    if m.mv:
        mats += [m.A, m.a]
    return any(m.t in getattr(e, "free_symbols", ()) for e in mats)


def function_specs(model, hessians=True, rodas4=True):
    """The functions of a model's CasADi library, as the template's data:
    [{"sym", "kind", "ins": [(name, sparsity, default)], "outs": [(name,
    sparsity)], "sz_w", "sz_out", ...}]. For each function <f>: jac_<f>,
    fwd1_<f> and adj1_<f> (first derivatives, every input), and
    jac_jac_<f>, jac_fwd1_<f> and jac_adj1_<f> (their Jacobians: the second
    derivatives CasADi's Hessians are built from). "base", "mode",
    "blocks" (input index, offset among the differentiable inputs,
    columns) and "fill" (what each output of a second-derivative
    function holds) are what the template's code needs. step of a
    constrained model has no derivatives (its projection has no
    derivative kernels). An unconstrained model also has step_rodas4 (one
    RODAS4 step of the runtime, functions(model, step="rodas4")) with
    jac_, fwd1_ and adj1_ only; "t_dep" says whether its value needs df/dt.
    hessians=False leaves out every jac_jac_, jac_fwd1_ and jac_adj1_
    (functions(model, hessians=False)); rodas4=False leaves out step_rodas4.
    """
    m = model
    p = m.name
    nx, nr, np_, mc, mv, ny = m.nx, m.nr, m.np, m.mc, m.mv, len(m.output_names)
    nan = "NAN"
    # defaults: r, p, h are NaN when missing (the call fails), t is 0
    x_, r_, p_, t_ = ("x", nx, 0), ("r", nr, nan if nr else 0), ("p", np_, nan if np_ else 0), \
        ("t", 1, 0)
    base = {
        "rhs": ([x_, r_, p_, t_], [("xdot", nx)]),
        "implicit": ([x_, ("xdot", nx, 0), r_, p_, t_], [("residual", nx + mc + mv)]),
        "step": ([x_, r_, p_, t_, ("h", 1, nan)], [("x_next", nx)]),
        "outputs": ([x_, r_, p_, t_], [("y", ny)]),
        "constraints": ([x_, p_, t_], [("c", mc + mv)]),
    }
    have = [n for n in NAMES if (n != "outputs" or ny) and (n != "constraints" or mc + mv)]
    if rodas4 and not (mc or mv):
        # one RODAS4 step (gen_rt_rodas4_trial), first derivatives only
        base["step_rodas4"] = base["step"]
        have.append("step_rodas4")
    sz = sizes(m)
    sz_out = max(1, nx + mc + mv, ny)
    specs = []
    for n in have:
        ins, outs = base[n]
        specs.append({"sym": f"{p}_{n}", "kind": n, "name": n,
                      "ins": [(a, _dense(k, 1), d) for a, k, d in ins],
                      "outs": [(a, _dense(k, 1)) for a, k in outs],
                      "sz_w": sz["sz_w"] if n == "step_rodas4" else 0, "sz_out": sz_out,
                      "t_dep": n == "step_rodas4" and _holds_t(m)})
        nrow = outs[0][1]
        if n == "step" and (mc or mv):
            continue        # the projection has no derivative kernels: no derivatives
        # the inputs, side by side: (input index, offset, columns)
        offs, blocks = 0, []
        for i, (a, k, _) in enumerate(ins):
            blocks.append((i, offs, k))
            offs += k
        nv = offs
        common = {"base": n, "nrow": nrow, "nv": nv, "sz_out": sz_out, "sz_w": sz["sz_w"],
                  "cmap": _cmap(m, n)}
        nin, nout = len(ins), len(outs)
        yname = outs[0][0]
        nom = [(a, _dense(k, 1), 0) for a, k, _ in ins] + [(f"out_{a}", _dense(k, 1), 0)
                                                           for a, k in outs]
        jac_outs = [(f"jac_{yname}_{a}", _dense(nrow, k)) for a, k, _ in ins]
        # jac_<f>: the blocks jac_<out>_<in> (one output: block i is input i)
        specs.append({**common, "sym": f"jac_{p}_{n}", "kind": f"jac_{n}", "name": f"jac_{n}",
                      "mode": "jac", "ins": nom, "outs": jac_outs,
                      "blocks": blocks})
        # fwd1_<f>: J times the forward seeds of the inputs
        fwd_ins = nom + [(f"fwd_{a}", _dense(k, 1), 0) for a, k, _ in ins]
        fwd_outs = [(f"fwd_{yname}", _dense(nrow, 1))]
        specs.append({**common, "sym": f"fwd1_{p}_{n}", "kind": f"fwd1_{n}", "name": f"fwd1_{n}",
                      "mode": "fwd", "ins": fwd_ins, "outs": fwd_outs,
                                            "blocks": [(nin + nout + i, off, k) for i, off, k in blocks]})
        # adj1_<f>: J^T times the adjoint seed of the output
        adj_ins = nom + [(f"adj_{yname}", _dense(nrow, 1), 0)]
        adj_outs = [(f"adj_{a}", _dense(k, 1)) for a, k, _ in ins]
        specs.append({**common, "sym": f"adj1_{p}_{n}", "kind": f"adj1_{n}", "name": f"adj1_{n}",
                      "mode": "adj", "ins": adj_ins, "outs": adj_outs,
                      "blocks": blocks, "seed": nin + nout})
        if n == "step_rodas4" or not hessians:
            continue        # no second derivatives: CasADi says it cannot differentiate adj1_
        # second derivatives: the Jacobians of jac_, fwd1_ and adj1_ (their
        # outputs w.r.t. their inputs; CasADi's names), from the tensor
        # T[a][b][c] = d2 out_a / dv_b dv_c or, for adj1_, the Hessian of
        # adj^T out
        blk = {i: (off, k) for i, off, k in blocks}
        fill, outs2 = [], []
        for (oname, _), (i, oo, on) in zip(jac_outs, blocks):
            for a, sp_, _ in nom:
                j = [x[0] for x in nom].index(a)
                if j in blk:
                    fill.append(("T", oo, on, *blk[j]))
                    outs2.append((f"jac_{oname}_{a}", _dense(nrow * on, blk[j][1])))
                else:
                    fill.append(("zero",))
                    outs2.append((f"jac_{oname}_{a}", _zero(nrow * on, sp_[1])))
        specs.append({**common, "sym": f"jac_jac_{p}_{n}", "kind": f"jac_jac_{n}",
                      "name": f"jac_jac_{n}", "mode": "jj", "blocks": blocks,
                      "ins": nom + [(f"out_{a}", sp_, 0) for a, sp_ in jac_outs],
                      "outs": outs2, "fill": fill})
        fill, outs2 = [], []
        for j, (a, sp_, _) in enumerate(fwd_ins):
            nm = f"jac_fwd_{yname}_{a}"
            if j < nin:
                fill.append(("Tv", *blk[j]))
                outs2.append((nm, _dense(nrow, blk[j][1])))
            elif j >= nin + nout:
                fill.append(("J", *blk[j - nin - nout]))
                outs2.append((nm, _dense(nrow, blk[j - nin - nout][1])))
            else:
                fill.append(("zero",))
                outs2.append((nm, _zero(nrow, sp_[0])))
        specs.append({**common, "sym": f"jac_fwd1_{p}_{n}", "kind": f"jac_fwd1_{n}",
                      "name": f"jac_fwd1_{n}", "mode": "jf", "blocks": blocks,
                      "ins": fwd_ins + [(f"out_{a}", sp_, 0) for a, sp_ in fwd_outs],
                      "outs": outs2, "fill": fill, "seeds": [(nin + nout + i, off, k)
                                                              for i, off, k in blocks]})
        fill, outs2 = [], []
        for i, (ai, _, _) in enumerate(ins):
            for j, (a, sp_, _) in enumerate(adj_ins):
                nm = f"jac_adj_{ai}_{a}"
                if j < nin:
                    fill.append(("H", *blk[i], *blk[j]))
                    outs2.append((nm, _dense(blk[i][1], blk[j][1])))
                elif j == nin + nout:
                    fill.append(("JT", *blk[i]))
                    outs2.append((nm, _dense(blk[i][1], nrow)))
                else:
                    fill.append(("zero",))
                    outs2.append((nm, _zero(blk[i][1], sp_[0])))
        specs.append({**common, "sym": f"jac_adj1_{p}_{n}", "kind": f"jac_adj1_{n}",
                      "name": f"jac_adj1_{n}", "mode": "ja", "blocks": blocks,
                      "ins": adj_ins + [(f"out_{a}", sp_, 0) for a, sp_ in adj_outs],
                      "outs": outs2, "fill": fill, "seed": nin + nout})
    return specs


# ----------------------------------------------------- the derivative kernels
# Every derivative the library has comes from kernels generated here from the
# model's expressions, over z = (q, u, r, p, t), the inputs of the right-hand
# side. x' is the solution w = (q', u', lam) of the equations the runtime
# solves, R(z, w) = 0, linear in w:
#     Kqd q' + Ku u + kf = 0,  M u' - f - A^T lam = 0,  A u' + a(q', ...) = 0
# (the last two rows with velocity constraints only). With Rw = dR/dw:
#     dw/dz = -Rw^-1 dR/dz,
#     d2(lam^T w)/dz2 = -(d2(mu^T R)/dz2 + W^T dw/dz + (dw/dz)^T W),
#     Rw^T mu = lam,  W = d(Rw^T mu)/dz
# (the second-order adjoint of the implicit function; exact, no finite
# differences). The outputs y(z) and the constraints [f_c; A u + b] are
# explicit: their Jacobians and the Hessians of lam^T y, lam^T c directly.

def derivative_kernels(model, hessians=True, rhs_hessian=None):
    """The CasADi library's derivative kernels (gen.plan.ir.Kernel, named
    cs_*), from the model's expressions alone:

    cs_w0(q, u, r, p, t) -> Rw, R0        Rw = dR/dw, R0 = R(z, 0)
    cs_wz(q, u, r, p, t, ws) -> Rz        dR/dz at w = ws
    cs_wh(q, u, r, p, t, ws, mu) -> H, W  d2(mu^T R)/dz2, d(Rw^T mu)/dz
    cs_y1(z) -> J, cs_yh(z, mu) -> H      the outputs (models with outputs)
    cs_c1(z) -> J, cs_ch(z, mu) -> H      [f_c; A u + b] (constrained models)

    hessians=False leaves out the second-derivative kernels (cs_wh, cs_yh,
    cs_ch: the costly ones); rhs_hessian (default: hessians) keeps cs_wh,
    which the RODAS4 step's first derivatives need.
    """
    import sympy as sm

    from ..plan.ir import Arg, make_jacobian_kernel, make_kernel
    from ..sym.graph import gradient
    m = model
    U = sm.Matrix(m.u)
    z = list(m.q) + list(m.u) + list(m.r) + list(m.p) + [m.t]
    Qd = [sm.Dummy(f"qd{i}") for i in range(m.nq)]
    Ud = [sm.Dummy(f"ud{i}") for i in range(m.nu)]
    Lam = [sm.Dummy(f"lam{i}") for i in range(m.mv)]
    w = Qd + Ud + Lam
    mu = [sm.Dummy(f"mu{i}") for i in range(len(w))]
    zargs = [Arg("q", tuple(m.q)), Arg("u", tuple(m.u)), Arg("r", tuple(m.r)),
             Arg("p", tuple(m.p)), Arg("t", (m.t,), scalar=True)]
    Aw, Amu = Arg("ws", tuple(w)), Arg("mu", tuple(mu))
    R = m.Kqd * sm.Matrix(Qd) + m.Ku * U + m.kf
    R = R.col_join(m.M * sm.Matrix(Ud) - m.f - (m.A.T * sm.Matrix(Lam) if m.mv else 0 * U))
    if m.mv:
        qd_model = list(getattr(m, "qd", []) or [])
        R = R.col_join(m.A * sm.Matrix(Ud) + m.a.xreplace(dict(zip(qd_model, Qd))))
    ks = {}
    ks["cs_w0"] = make_kernel("cs_w0", zargs, [("Rw", R.jacobian(w)),
                                               ("R0", R.xreplace({s: 0 for s in w}))])
    ks["cs_wz"] = make_jacobian_kernel("cs_wz", zargs + [Aw], [], [("Rz", R, z)])

    def hess(name, F, args, wrt_extra=()):
        """d2(mu^T F)/dz2 (and d(d(mu^T F)/d wrt_extra)/dz)."""
        lam = list(args[-1].symbols)
        L = sum((a * b for a, b in zip(lam, F)), sm.S.Zero)
        g = gradient(L, set(z) | set(wrt_extra))
        jacs = [("H", sm.Matrix([g.get(s, 0) for s in z]), z)]
        if wrt_extra:
            jacs.append(("W", sm.Matrix([g.get(s, 0) for s in wrt_extra]), z))
        return make_jacobian_kernel(name, args, [], jacs)

    keep_wh = hessians if rhs_hessian is None else rhs_hessian
    if keep_wh:
        ks["cs_wh"] = hess("cs_wh", R, zargs + [Aw, Amu], w)
    if m.output_names:
        y = m.y
        ly = Arg("mu", tuple(sm.Dummy(f"ly{i}") for i in range(y.shape[0])))
        ks["cs_y1"] = make_jacobian_kernel("cs_y1", zargs, [], [("J", y, z)])
        if hessians:
            ks["cs_yh"] = hess("cs_yh", y, zargs + [ly])
    if m.mc or m.mv:
        c = sm.Matrix(m.fc if m.mc else sm.zeros(0, 1))
        if m.mv:
            c = c.col_join(m.A * U + m.b)
        lc = Arg("mu", tuple(sm.Dummy(f"lc{i}") for i in range(c.shape[0])))
        ks["cs_c1"] = make_jacobian_kernel("cs_c1", zargs, [], [("J", c, z)])
        if hessians:
            ks["cs_ch"] = hess("cs_ch", c, zargs + [lc])
    return ks


def kernel_context(model, printer_for, hessians=True, rhs_hessian=None):
    """The derivative kernels as the template's data (the C backend's kernel
    context: name, args, outputs, body); printer_for(symbol_map) gives the
    backend's printer. hessians, rhs_hessian: derivative_kernels'."""
    from ..sym.printers import print_kernel_body
    ks = derivative_kernels(model, hessians, rhs_hessian)
    out = []
    for k in ks.values():
        smap = {model.t: "t"}
        for a in k.args:
            if not a.scalar:
                smap.update({s: f"{a.name}[{i}]" for i, s in enumerate(a.symbols)})
        smap.update({s: s.name for s, _ in k.assignments})
        out.append({"name": k.name, "args": [{"name": a.name, "scalar": a.scalar} for a in k.args],
                    "outputs": [o.name for o in k.outputs], "n_assign": len(k.assignments),
                    "body": print_kernel_body(k, printer_for(smap))})
    return out
