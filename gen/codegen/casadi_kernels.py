"""The CasADi face's data, from a gen.Model alone: the function table
(which functions the generated library holds: names, inputs and outputs
with their sparsity in CasADi's compressed column storage, and each
function as the runtime's gen_rt_cs_fn), the derivative kernels the
runtime differentiates with (csrc/derivatives), the template's context
and the cffi cdef of the functions. Read by the casadi backend
(gen/codegen/backends/) to render the library and by gen.casadi to load
it; it imports no later stage of the pipeline."""
from __future__ import annotations

from ..intake.hybrid import KIND_IMPACT
from .templating import template_env

__all__ = ["NAMES", "HYBRID_PREFIXES", "STEP_METHODS", "MODES", "function_specs",
           "hybrid_bases", "derivative_kernels", "hybrid_derivative_kernels", "kernel_context",
           "library_context", "cdef"]

#: the functions, in the order of the dict functions() returns (then, for a
#: hybrid model, guard_<name> and map_<name> of each declaration in order)
NAMES = ("rhs", "implicit", "step", "outputs", "constraints")

#: the kinds of a hybrid model's functions (hybrid_bases): guard_<name>, map_<name>
HYBRID_PREFIXES = ("guard_", "map_")

#: the methods of step (functions(model, step=...)): the library symbol of
#: each (<model>_<symbol>); "rodas4" for unconstrained models only
STEP_METHODS = {"rk4": "step", "rodas4": "step_rodas4"}

#: what each derivative function computes of its base function (the
#: runtime's GEN_RT_CS_<MODE>, csrc/derivatives/gen_rt_casadi.h), by prefix
MODES = {"jac_": "jac", "fwd1_": "fwd", "adj1_": "adj", "jac_jac_": "jac_jac",
         "jac_fwd1_": "jac_fwd", "jac_adj1_": "jac_adj"}


def _dense(m, n):
    """CasADi's compressed column storage of a dense m x n matrix."""
    return [m, n, *[j * m for j in range(n + 1)], *[i for _ in range(n) for i in range(m)]]


def _zero(m, n):
    """CasADi's compressed column storage of an m x n structural zero."""
    return [m, n, *([0] * (n + 1))]


def _holds_t(model):
    """Whether the model's equations hold the time explicitly (then
    step_rodas4 needs df/dt; otherwise it is zero)."""
    m = model
    mats = [m.Kqd, m.Ku, m.kf, m.M, m.f]
    if m.mv:
        mats += [m.A, m.a]
    return any(m.t in getattr(e, "free_symbols", ()) for e in mats)


def _bases(model, rodas4):
    """The base functions the library holds: [(name, inputs [(name, size,
    default)], outputs [(name, size)])]. A missing r, p or h is NaN (the
    call fails), t is 0."""
    m = model
    nx, nr, np_, mc, mv, ny = m.nx, m.nr, m.np, m.mc, m.mv, len(m.output_names)
    nan = "NAN"
    x_, r_, p_, t_ = ("x", nx, 0), ("r", nr, nan if nr else 0), ("p", np_, nan if np_ else 0), \
        ("t", 1, 0)
    step = ([x_, r_, p_, t_, ("h", 1, nan)], [("x_next", nx)])
    base = {
        "rhs": ([x_, r_, p_, t_], [("xdot", nx)]),
        "implicit": ([x_, ("xdot", nx, 0), r_, p_, t_], [("residual", nx + mc + mv)]),
        "step": step,
        "outputs": ([x_, r_, p_, t_], [("y", ny)]),
        "constraints": ([x_, p_, t_], [("c", mc + mv)]),
    }
    have = [n for n in NAMES if (n != "outputs" or ny) and (n != "constraints" or mc + mv)]
    if rodas4 and not (mc or mv):
        # one RODAS4 step (gen_rt_rodas4_trial), first derivatives only
        base["step_rodas4"] = step
        have.append("step_rodas4")
    return [(n, *base[n]) for n in have]


def _spec(p, base, prefix, ins, outs):
    """One function's entry: its symbol, inputs (name, sparsity, default),
    outputs (name, sparsity) and the runtime's description of it (base
    function, mode, the base's inputs: the template's gen_rt_cs_fn)."""
    mode = MODES.get(prefix)
    name = prefix + base[0]
    rt = base[3] if len(base) > 3 else base[0].upper()
    return {"sym": f"{prefix}{p}_{base[0]}", "kind": name, "name": name, "base": base[0],
            "mode": mode, "ins": ins, "outs": outs,
            "model": f"{p}_{base[4]}" if len(base) > 4 else f"{p}_cs", "phase": False,
            "c_fn": {"base": f"GEN_RT_CS_{rt}",
                     "mode": f"GEN_RT_CS_{(mode or 'value').upper()}",
                     "ins": [f"GEN_RT_CS_{a.upper()}" for a, _, _ in base[1]]}}


def _first(p, base):
    """The value and its first derivatives: <f>, jac_<f> (the blocks
    jac_<out>_<in>), fwd1_<f> (J times a forward seed per input), adj1_<f>
    (J^T times the output's adjoint seed)."""
    ins, outs = base[1], base[2]
    (yname, nrow), = outs
    nom = [(a, _dense(k, 1), 0) for a, k, _ in ins] + [(f"out_{yname}", _dense(nrow, 1), 0)]
    value = _spec(p, base, "", [(a, _dense(k, 1), d) for a, k, d in ins],
                  [(yname, _dense(nrow, 1))])
    del value["mode"]
    jac = _spec(p, base, "jac_", nom, [(f"jac_{yname}_{a}", _dense(nrow, k)) for a, k, _ in ins])
    fwd = _spec(p, base, "fwd1_", nom + [(f"fwd_{a}", _dense(k, 1), 0) for a, k, _ in ins],
                [(f"fwd_{yname}", _dense(nrow, 1))])
    adj = _spec(p, base, "adj1_", nom + [(f"adj_{yname}", _dense(nrow, 1), 0)],
                [(f"adj_{a}", _dense(k, 1)) for a, k, _ in ins])
    return [value, jac, fwd, adj]


def _second(p, base, first):
    """The Jacobians of jac_, fwd1_ and adj1_ (their outputs w.r.t. their
    inputs; CasADi's names): the second derivatives CasADi's Hessians are
    built from. A block w.r.t. a nominal output is a structural zero."""
    ins, outs = base[1], base[2]
    (yname, nrow), = outs
    nin = len(ins)
    jac, fwd, adj = first[1:]

    def block(name, rows, j, arg, zero_cols=0):
        """d(rows-long output)/d(input j of arg: name, sparsity): dense for
        an input or a seed, a structural zero for the nominal output (with
        sparsity[zero_cols] columns: jac_jac_'s have one)."""
        _, sp_, _ = arg
        if j != nin:
            return (name, _dense(rows, sp_[0]))
        return (name, _zero(rows, sp_[zero_cols]))
    outs_jj = [block(f"jac_{o}_{a[0]}", nrow * ins[i][1], j, a, 1)
               for i, (o, _) in enumerate(jac["outs"]) for j, a in enumerate(jac["ins"])]
    outs_jf = [block(f"jac_fwd_{yname}_{a[0]}", nrow, j, a) for j, a in enumerate(fwd["ins"])]
    outs_ja = [block(f"jac_adj_{ai}_{a[0]}", k, j, a)
               for ai, k, _ in ins for j, a in enumerate(adj["ins"])]

    def ins2(f):
        """f's inputs, then its outputs as inputs (out_<name>)."""
        return f["ins"] + [(f"out_{a}", sp_, 0) for a, sp_ in f["outs"]]
    return [_spec(p, base, "jac_jac_", ins2(jac), outs_jj),
            _spec(p, base, "jac_fwd1_", ins2(fwd), outs_jf),
            _spec(p, base, "jac_adj1_", ins2(adj), outs_ja)]


def function_specs(model, hessians=True, rodas4=True):
    """The functions of a model's CasADi library, as the template's data:
    [{"sym", "kind", "name", "base", "mode", "ins": [(name, sparsity,
    default)], "outs": [(name, sparsity)], "c_fn"}]. For each function <f>:
    jac_<f>, fwd1_<f> and adj1_<f> (first derivatives, every input; "mode"
    "jac", "fwd", "adj"), and jac_jac_<f>, jac_fwd1_<f> and jac_adj1_<f>
    (their Jacobians: the second derivatives CasADi's Hessians are built
    from; "jac_jac", "jac_fwd", "jac_adj"); the values have no "mode".
    "c_fn" is the runtime's description of the function
    (csrc/derivatives/gen_rt_casadi.h, gen_rt_cs_fn), which computes it.
    step of a constrained model has no derivatives (its projection has no
    derivative kernels). An unconstrained model also has step_rodas4 (one
    RODAS4 step of the runtime, functions(model, step="rodas4")) with
    jac_, fwd1_ and adj1_ only. hessians=False leaves out every jac_jac_,
    jac_fwd1_ and jac_adj1_ (functions(model, hessians=False));
    rodas4=False leaves out step_rodas4.
    """
    m = model
    specs = []
    hybrid = bool(getattr(m, "hybrid", None))
    for base in _bases(m, rodas4) + hybrid_bases(m):
        first = _first(m.name, base)
        if hybrid and base[0] in STEP_METHODS.values():
            first[0]["phase"] = True   # the value refuses a step across a guard
        if base[0] == "step" and (m.mc or m.mv):
            specs.append(first[0])  # the projection has no derivative kernels
            continue
        specs += first
        if hessians and base[0] != "step_rodas4":
            specs += _second(m.name, base, first)
    return specs


def hybrid_bases(model):
    """A hybrid model's functions of each declaration (hybrid={...}), as
    _bases' entries with the runtime's base and the C model that computes
    them (the template's gen_rt_cs_model of the declaration):

    guard_<name>(x, p, t) -> g          the gap or guard (explicit: CONSTRAINTS
                                        of a model whose one constraint it is)
    map_<name>(x, p, t) -> x_after      a reset's map (explicit, CONSTRAINTS of
                                        nx rows), or an impact's impulse map
                                        (implicit: RHS of a model whose
                                        equations are the impulse's)
    """
    m = model
    x_, p_, t_ = ("x", m.nx, 0), ("p", m.np, "NAN" if m.np else 0), ("t", 1, 0)
    out = []
    for k, d in enumerate(getattr(m, "hybrid", None) or []):
        out.append((f"guard_{d.name}", [x_, p_, t_], [("g", 1)], "CONSTRAINTS", f"cs_g{k}"))
        out.append((f"map_{d.name}", [x_, p_, t_], [("x_after", m.nx)],
                    "RHS" if d.kind == KIND_IMPACT else "CONSTRAINTS", f"cs_m{k}"))
    return out


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

    cs_w0(z) -> Rw, R0                Rw = dR/dw, R0 = R(z, 0)
    cs_wz(z, ws) -> Rz                dR/dz at w = ws
    cs_wh(z, ws, mu) -> H, W          d2(mu^T R)/dz2, d(Rw^T mu)/dz
    cs_y1(z) -> J, cs_yh(z, mu) -> H  the outputs (models with outputs)
    cs_c1(z) -> J, cs_ch(z, mu) -> H  [f_c; A u + b] (constrained models)

each over one array z = (q, u, r, p, t): the kernels of the runtime's
gen_rt_deriv_model and gen_rt_cs_model (csrc/derivatives), which compute
every derivative from them.

    hessians=False leaves out the second-derivative kernels (cs_wh, cs_yh,
    cs_ch: the costly ones); rhs_hessian (default: hessians) keeps cs_wh,
    which the RODAS4 step's first derivatives need.
    """
    import sympy as sm

    from ..plan.ir import Arg, make_jacobian_kernel, make_kernel
    m = model
    U = sm.Matrix(m.u)
    z = list(m.q) + list(m.u) + list(m.r) + list(m.p) + [m.t]
    Qd = [sm.Dummy(f"qd{i}") for i in range(m.nq)]
    Ud = [sm.Dummy(f"ud{i}") for i in range(m.nu)]
    Lam = [sm.Dummy(f"lam{i}") for i in range(m.mv)]
    w = Qd + Ud + Lam
    mu = [sm.Dummy(f"mu{i}") for i in range(len(w))]
    zargs = [Arg("z", tuple(z))]
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
        return _hess(name, F, args, z, wrt_extra)

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
    ks.update(hybrid_derivative_kernels(m, hessians))
    return ks


def _hess(name, F, args, z, wrt_extra=()):
    """A kernel of d2(mu^T F)/dz2 (and d(d(mu^T F)/d wrt_extra)/dz), mu the
    last argument's symbols."""
    import sympy as sm

    from ..plan.ir import make_jacobian_kernel
    from ..sym.graph import gradient
    lam = list(args[-1].symbols)
    L = sum((a * b for a, b in zip(lam, F)), sm.S.Zero)
    g = gradient(L, set(z) | set(wrt_extra))
    jacs = [("H", sm.Matrix([g.get(s, 0) for s in z]), z)]
    if wrt_extra:
        jacs.append(("W", sm.Matrix([g.get(s, 0) for s in wrt_extra]), z))
    return make_jacobian_kernel(name, args, [], jacs)


def hybrid_derivative_kernels(model, hessians=True):
    """The derivative kernels of a hybrid model's guard_ and map_ functions
    (hybrid_bases), over the same z = (q, u, r, p, t), for declaration k:

    cs_g<k>_1(z) -> J, cs_g<k>_h(z, mu) -> H      the gap or guard (explicit)
    cs_m<k>_1(z) -> J, cs_m<k>_h(z, mu) -> H      a reset's map (explicit)
    cs_m<k>_w0, _wz, _wh                          an impact's impulse map: the
        implicit function x+ = (q+, u+) of the equations the runtime's impulse
        solves (gen_rt_hybrid_impulse), linear in w = (q+, u+, mu, Lambda):
            q+ - q = 0,   M u+ - A^T mu - W_k^T Lambda - M u = 0,
            A u+ + b = 0,   W_k u+ + w_k + e_k (W_k u + w_k) = 0
        (the gap's rate g' = W_k u + w_k, e_k its restitution), differentiated
        by the runtime's implicit-function algorithms as x' is.
    hessians=False leaves out the second-derivative kernels (_h, _wh)."""
    import sympy as sm

    from ..intake.hybrid import hybrid_kernels
    from ..plan.ir import Arg, make_jacobian_kernel, make_kernel
    m = model
    decls = getattr(m, "hybrid", None) or []
    if not decls:
        return {}
    z = list(m.q) + list(m.u) + list(m.r) + list(m.p) + [m.t]
    zargs = [Arg("z", tuple(z))]
    kern = {name: dict(outs) for name, _, outs in hybrid_kernels(m)}
    W, w = kern["hybrid_jacobian"]["W"], kern["hybrid_jacobian"]["w"]
    U = sm.Matrix(m.u)
    ks = {}

    def explicit(stem, F):
        mu = Arg("mu", tuple(sm.Dummy(f"mu{i}") for i in range(F.shape[0])))
        ks[stem + "_1"] = make_jacobian_kernel(stem + "_1", zargs, [], [("J", F, z)])
        if hessians:
            ks[stem + "_h"] = _hess(stem + "_h", F, zargs + [mu], z)

    for k, d in enumerate(decls):
        explicit(f"cs_g{k}", sm.Matrix([d.expr]))
        if d.kind != KIND_IMPACT:
            explicit(f"cs_m{k}", sm.Matrix(d.xmap))
            continue
        Qp = [sm.Dummy(f"qp{i}") for i in range(m.nq)]
        Up = [sm.Dummy(f"up{i}") for i in range(m.nu)]
        Mu = [sm.Dummy(f"ma{i}") for i in range(m.mv)]
        Lam = sm.Dummy("lam")
        wv = Qp + Up + Mu + [Lam]
        Wk, wk, e = W[k, :], w[k], sm.Float(d.restitution)
        Upm = sm.Matrix(Up)
        R = sm.Matrix(Qp) - sm.Matrix(m.q)
        R2 = m.M * Upm - Wk.T * Lam - m.M * U
        if m.mv:
            R2 -= m.A.T * sm.Matrix(Mu)
        R = R.col_join(R2)
        if m.mv:
            R = R.col_join(m.A * Upm + m.b)
        R = R.col_join(sm.Matrix([(Wk * Upm)[0] + wk + e * ((Wk * U)[0] + wk)]))
        stem = f"cs_m{k}"
        ks[stem + "_w0"] = make_kernel(stem + "_w0", zargs, [
            ("Rw", R.jacobian(wv)), ("R0", R.xreplace({s: 0 for s in wv}))])
        ks[stem + "_wz"] = make_jacobian_kernel(stem + "_wz", zargs + [Arg("ws", tuple(wv))],
                                                [], [("Rz", R, z)])
        if hessians:
            mu = Arg("mu", tuple(sm.Dummy(f"mu{i}") for i in range(len(wv))))
            ks[stem + "_wh"] = _hess(stem + "_wh", R, zargs + [Arg("ws", tuple(wv)), mu], z,
                                     wv)
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


def library_context(model, printer_for, hessians=True, rodas4=True):
    """What templates/casadi needs beyond the C model's context: the
    functions (function_specs), the derivative kernels (kernel_context) and
    the model as the runtime's gen_rt_cs_model (its sizes, whether f holds
    t, and the C names of its kernels and of its API functions, "0" for
    none)."""
    m = model
    rodas4_here = rodas4 and not (m.mc or m.mv)
    kernels = kernel_context(m, printer_for, hessians, hessians or rodas4_here)
    have = {k["name"] for k in kernels}
    ny = len(m.output_names)

    def name(c, there=True):
        return f"{m.name}_{c}" if there else "0"
    events = _hybrid_models(m, have)
    sizes = [(m.mc, m.mv, ny)] + [(e["mc"], e["mv"], 0) for e in events]
    work = [f"GEN_RT_CS_WORK({m.nx}, {m.nr}, {m.np}, {a}, {b}, {c})" for a, b, c in sizes]
    iwork = [f"GEN_RT_CS_IWORK({m.nx}, {m.nr}, {m.np}, {b})" for _, b, _ in sizes]
    return {
        "cs_functions": function_specs(m, hessians, rodas4),
        "cs_kernels": kernels,
        "cs": {"ny": ny, "nz": m.nx + m.nr + m.np + 1, "nw": m.nx + m.mv,
               "t_dep": int(_holds_t(m)),
               "kernels": [name(k, k in have) for k in ("cs_w0", "cs_wz", "cs_wh", "cs_y1",
                                                         "cs_c1", "cs_yh", "cs_ch")],
               "api": [name("eval_rhs"), name("step_rk4"), name("jacobian"),
                       name("eval_outputs", ny), name("eval_constraints", m.mc),
                       name("eval_velocity_constraints", m.mv)],
               # every function's work: the most any model below needs
               "work": _max_of(work), "iwork": _max_of(iwork)},
        "cs_hybrid": events,
    }


def _max_of(terms):
    """A C expression of the largest of terms (GEN_RT_MAX_)."""
    out = terms[-1]
    for t in reversed(terms[:-1]):
        out = f"GEN_RT_MAX_({t}, {out})"
    return out


def _hybrid_models(model, have):
    """The template's gen_rt_cs_model of each hybrid function (hybrid_bases):
    its C name, sizes (mc, mv: the rows of a constraint-like function, the
    impulse's extra multiplier), the deriv model's nw and kernels, the
    explicit kernels and the value function; and what that value function
    reads: the declaration k, a reset's block of the maps, an impact's
    restitution (the runtime model's own)."""
    m, p = model, model.name
    out = []

    def k_(name):
        return f"{p}_{name}" if name in have else "0"
    for k, d in enumerate(getattr(m, "hybrid", None) or []):
        base = {"k": k, "d_kernels": ["0", "0", "0"], "nw": m.nx, "mc": 0, "mv": 0,
                "c1": "0", "ch": "0", "constraints": "0", "rhs": "0"}
        out.append(dict(base, name=f"{p}_cs_g{k}", what="guard", mc=1, c1=k_(f"cs_g{k}_1"),
                        ch=k_(f"cs_g{k}_h"), constraints=f"{p}_cs_guard_{k}"))
        if d.kind == KIND_IMPACT:
            out.append(dict(base, name=f"{p}_cs_m{k}", what="impulse", mv=m.mv + 1,
                            nw=m.nx + m.mv + 1, rhs=f"{p}_cs_impulse_{k}",
                            d_kernels=[k_(f"cs_m{k}_{w}") for w in ("w0", "wz", "wh")]))
        else:
            ridx = sum(1 for e in m.hybrid[:k] if e.kind != KIND_IMPACT)
            out.append(dict(base, name=f"{p}_cs_m{k}", what="reset", mc=m.nx, ridx=ridx,
                            c1=k_(f"cs_m{k}_1"), ch=k_(f"cs_m{k}_h"),
                            constraints=f"{p}_cs_reset_{k}"))
    return out


def cdef(specs):
    """The cffi cdef of functions of a library (function_specs entries):
    their declarations as <name>_casadi.h has them (the same macro,
    templates/casadi/casadi_decl.j2), with casadi_real = double and
    casadi_int = long long."""
    return template_env().get_template("casadi/casadi.cdef.j2").render(cs_functions=specs)
