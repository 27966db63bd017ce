"""Proof that compiled code is the model: every generated function against
sympy's own evaluation of the model at random states.

The reference side never touches eomgen's kernels, CSE or printer: it
lambdifies the canonical model's matrices (sympy's printer, numpy), solves
the constrained dynamics with numpy, and linearizes with
``gen.linearize_symbolic`` (sympy arithmetic at the operating point).

    report = gen.verify(model, samples=20)               # builds from the model
    report = gen.verify(model, sources="out/pendulum")   # checks a generated folder
    print(report.table()); report.ok
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import sympy as sm

from ..core.errors import EomgenError
from ..intake.model import require_model

__all__ = ["verify", "VerifyReport"]


@dataclass
class VerifyReport:
    """The result of :func:`gen.verify`: one row per function.

    Attributes
    ----------
    model, backend, real : str
        What was checked.
    tol : float
        The relative tolerance.
    samples : int
        Random states per function.
    rows : list of (str, float, int)
        (function, max relative error, points).
    failures : list of str
        Functions that failed to run.
    seconds : float
        How long it took.
    """
    model: str
    backend: str
    real: str
    tol: float
    samples: int
    rows: list = field(default_factory=list)    # (function, max rel err, points)
    seconds: float = 0.0
    failures: list = field(default_factory=list)

    @property
    def ok(self):
        """True when every function agrees within the tolerance and none failed."""
        return not self.failures and all(err <= self.tol for _, err, _ in self.rows)

    def table(self):
        """The report as the command line prints it.

        Returns
        -------
        str
            One line per function (max relative error, points, ok/FAIL) and a
            verdict.
        """
        w = max([len(r[0]) for r in self.rows] + [8])
        lines = [f"verify '{self.model}' ({self.backend}, {self.real}) against sympy: "
                 f"{self.samples} random states, tolerance {self.tol:.0e}",
                 f"{'function':<{w}}  {'max rel err':>11}  {'points':>6}  result"]
        for name, err, n in self.rows:
            lines.append(f"{name:<{w}}  {err:11.2e}  {n:6d}  "
                         f"{'ok' if err <= self.tol else 'FAIL'}")
        for f in self.failures:
            lines.append(f"FAIL {f}")
        lines.append(("all functions agree" if self.ok else "MISMATCH: the compiled code is "
                      "not this model") + f" ({self.seconds:.1f} s)")
        return "\n".join(lines)


def _rel(c, s):
    c = np.asarray(c, dtype=float)
    s = np.asarray(s, dtype=float)
    if c.shape != s.shape:
        return float("inf")
    if c.size == 0:
        return 0.0
    if not np.all(np.isfinite(c)):
        return float("inf")
    scale = float(np.max(np.abs(s)))
    d = float(np.max(np.abs(c - s)))
    return d / scale if scale > 0 else d


def _reference(model):
    """numpy callables of the canonical model, by sympy's lambdify."""
    m = model
    args = list(m.q) + list(m.u) + list(m.r) + list(m.p) + [m.t]
    U = sm.Matrix(m.u)

    def lam(expr):
        return sm.lambdify(args, expr, modules="numpy")

    ref = {"M": lam(m.M), "f": lam(m.f), "Kqd": lam(m.Kqd), "kr": lam(-(m.Ku * U + m.kf))}
    if m.mc:
        ref["fc"] = lam(m.fc)
        ref["Jc"] = lam(m.fc.jacobian(m.q))
    if m.mv:
        ref["A"] = lam(m.A)
        ref["b"] = lam(m.b)
        # a holds q' as symbols (m.qd) when the kinematics are implicit
        ref["a"] = sm.lambdify(args + list(m.qd), m.a, modules="numpy")
    if m.energy is not None:
        ref["E"] = lam(sm.Matrix([m.energy]))
    if getattr(m, "na", 0):
        # auxiliary equations F reactions + g = 0, over the arguments and u'
        ref["auxF"] = sm.lambdify(args + list(m.ud), m.aux_F, modules="numpy")
        ref["auxg"] = sm.lambdify(args + list(m.ud), m.aux_g, modules="numpy")
    if getattr(m, "aux_G", None) is not None:
        # reactions inside the motion: M u' = f + G R, and the auxiliary
        # equations (linear in u') C u' + F R + g0 = 0
        zero = {s: 0 for s in m.ud}
        ref["auxG"] = lam(m.aux_G)
        ref["auxC"] = lam(m.aux_g.jacobian(list(m.ud)))
        ref["auxg0"] = lam(m.aux_g.xreplace(zero))
        ref["auxH"] = lam(m.aux_F)
    return ref


def _with_real_symbols(model):
    """The model over internal symbols assumed real, for the symbolic
    linearization: sympy then differentiates Abs to sign and sign, Heaviside
    to DiracDelta (0 away from the kink), not to re/im or unevaluated
    Derivative terms that cannot be evaluated at a point."""
    import dataclasses
    m = model
    old = list(m.q) + list(m.u) + list(m.r) + list(m.p) + [m.t]
    rep = {s: sm.Dummy(s.name, real=True) for s in old}
    kw = {"q": [rep[s] for s in m.q], "u": [rep[s] for s in m.u], "r": [rep[s] for s in m.r],
          "p": [rep[s] for s in m.p], "t": rep[m.t]}
    for f in dataclasses.fields(m):
        v = getattr(m, f.name)
        if f.name not in kw and isinstance(v, (sm.MatrixBase, sm.Expr)):
            kw[f.name] = v.xreplace(rep)
    return dataclasses.replace(m, **kw)


def _call(fn, x, r, p, t):
    return np.array(fn(*x, *r, *p, t), dtype=float)


def _rhs_reference(model, ref, x, r, p, t):
    m = model
    nu, mv = m.nu, m.mv
    qd = np.linalg.solve(_call(ref["Kqd"], x, r, p, t), _call(ref["kr"], x, r, p, t).ravel())
    M = _call(ref["M"], x, r, p, t)
    f = _call(ref["f"], x, r, p, t).ravel()
    K = np.zeros((nu + mv, nu + mv))
    K[:nu, :nu] = M
    z = np.zeros(nu + mv)
    z[:nu] = f
    if mv:
        A = _call(ref["A"], x, r, p, t)
        K[:nu, nu:] = -A.T
        K[nu:, :nu] = A
        z[nu:] = -np.array(ref["a"](*x, *r, *p, t, *(qd if m.qd else [])),
                            dtype=float).ravel()
    if "auxG" in ref:
        # the coupled solve [M, -G; C, H] [u'; R] = [f; -g0] (mv == 0): the
        # second part returned is the reactions
        na = m.na
        K = np.zeros((nu + na, nu + na))
        K[:nu, :nu] = M
        K[:nu, nu:] = -_call(ref["auxG"], x, r, p, t)
        K[nu:, :nu] = _call(ref["auxC"], x, r, p, t)
        K[nu:, nu:] = _call(ref["auxH"], x, r, p, t)
        z = np.concatenate([f, -_call(ref["auxg0"], x, r, p, t).ravel()])
    sol = np.linalg.solve(K, z)
    return np.concatenate([qd, sol[:nu]]), sol[nu:]


def verify(model, samples=20, backend="c", real="double", sources=None, seed=0, tol=None,
           linearize_samples=3, sim=None):
    """Compare every compiled function with sympy at random states.

    The reference never touches eomgen's kernels, CSE or printer: sympy's
    ``lambdify`` of the canonical model, numpy for the constrained solve,
    :func:`gen.linearize_symbolic` for A and B (:doc:`/guides/verification`).

    Parameters
    ----------
    model : gen.Model
        The model.
    samples : int, optional
        Random states per function.
    backend : {"c", "eigen"}, optional
        The backend to build.
    real : {"double", "float"}, optional
        The scalar type.
    sources : str or Path, optional
        A folder written by :func:`gen.generate` (possibly edited since): its
        sources are compiled and checked instead of freshly generated ones.
    seed : int, optional
        The random states' seed.
    tol : float, optional
        The relative tolerance (default 1e-9 in double, 2e-4 in float).
    linearize_samples : int, optional
        Operating points for ``linearize`` (symbolic, slower).
    sim : gen.sim.simulator.Simulator, optional
        An already compiled model to check instead.

    Returns
    -------
    gen.VerifyReport
        ``report.ok``, ``report.table()``.
    """
    require_model(model, "gen.verify")
    from ..pipeline import compile as compile_model

    t_start = time.perf_counter()
    if tol is None:
        tol = 1e-9 if real == "double" else 2e-4
    if sim is None:
        sim = compile_model(model, backend=backend, real=real, sources=sources)
    m = model
    rng = np.random.default_rng(seed)
    errs, points = {}, {}

    def note(name, value):
        errs[name] = max(errs.get(name, 0.0), value)
        points[name] = points.get(name, 0) + 1

    ref = _reference(m)
    m_real = _with_real_symbols(m)
    p = np.array(m.p_values, dtype=float)
    states, failures = _sample_states(sim, m, rng, samples)
    for k, (x, raw) in enumerate(states):
        r = rng.uniform(-1, 1, m.nr)
        t = float(rng.uniform(0, 1))
        try:
            _check_evaluations(sim, m, ref, x, raw, r, p, t, note)
            if k < linearize_samples:
                _check_linearize(sim, m_real, x, r, t, note)
        except (EomgenError, np.linalg.LinAlgError) as e:
            failures.append(f"state {k}: {type(e).__name__}: {e}")
    report = VerifyReport(model=m.name, backend=backend, real=real, tol=tol, samples=samples,
                          rows=[(name, errs[name], points[name]) for name in errs],
                          failures=failures)
    report.seconds = time.perf_counter() - t_start
    return report


def _sample_states(sim, m, rng, samples):
    """(the random states (x, raw): raw uniform in [-1, 1], x it made
    consistent on a constrained model; failures): up to 20 tries a state."""
    states, failures = [], []
    tries = 0
    while len(states) < samples and tries < 20 * samples:
        tries += 1
        raw = rng.uniform(-1, 1, m.nx)
        x = raw
        if m.mc or m.mv:
            try:
                x = sim.consistent_state(raw)
            except EomgenError:
                continue
        states.append((x, raw))
    if len(states) < samples:
        failures.append(f"only {len(states)} of {samples} random states were consistent")
    return states, failures


def _check_evaluations(sim, m, ref, x, raw, r, p, t, note):
    """Every evaluation at one state against the reference (residuals at
    raw, off the manifold, where they are not ~0); note(name, error)."""
    q, u = x[:m.nq], x[m.nq:]
    qr, ur = raw[:m.nq], raw[m.nq:]
    note("eval_mass_matrix", _rel(sim.mass_matrix(q, t=t), _call(ref["M"], x, r, p, t)))
    note("eval_forcing", _rel(sim.forcing(q, u, r=r, t=t), _call(ref["f"], x, r, p, t).ravel()))
    xd_ref, lam_ref = _rhs_reference(m, ref, x, r, p, t)
    note("eval_kinematics", _rel(sim.kinematics(q, u, t=t), xd_ref[:m.nq]))
    if m.mc:
        note("eval_constraints", _rel(sim.constraints(qr, t=t),
                                      _call(ref["fc"], raw, r, p, t).ravel()))
        note("eval_constraint_jacobian", _rel(sim.constraint_jacobian(q, t=t),
                                              _call(ref["Jc"], x, r, p, t)))
    if m.mv:
        A_ref = _call(ref["A"], x, r, p, t)
        b_ref = _call(ref["b"], x, r, p, t).ravel()
        A_c, b_c = sim.velocity_constraint_matrix(q, t=t)
        note("eval_velocity_constraint_matrix", max(_rel(A_c, A_ref), _rel(b_c, b_ref)))
        fv_ref = _call(ref["A"], raw, r, p, t) @ ur + _call(ref["b"], raw, r, p, t).ravel()
        note("eval_velocity_constraints", _rel(sim.velocity_constraints(qr, ur, t=t), fv_ref))
    if m.energy is not None:
        note("eval_energy", _rel([sim.energy(x, t=t)], _call(ref["E"], x, r, p, t).ravel()))
    note("eval_rhs", _rel(sim.rhs(t, x, r=r), xd_ref))
    if m.mv:
        note("eval_rhs (multipliers)", _rel(sim.multipliers(t, x, r=r), lam_ref))
    if getattr(m, "aux_G", None) is not None:
        note("eval_auxiliary_forces", _rel(sim.auxiliary_forces(t, x, r=r), lam_ref))
    elif getattr(m, "na", 0):
        ud = xd_ref[m.nq:]
        Fa = np.array(ref["auxF"](*x, *r, *p, t, *ud), dtype=float)
        ga = np.array(ref["auxg"](*x, *r, *p, t, *ud), dtype=float).ravel()
        note("eval_auxiliary_forces", _rel(sim.auxiliary_forces(t, x, r=r),
                                           np.linalg.solve(Fa, -ga)))


def _check_linearize(sim, m_real, x, r, t, note):
    """linearize at one operating point against gen.linearize_symbolic."""
    from ..plan.linearize import linearize_symbolic
    m = m_real
    op = dict(zip(m.state_names, x))
    A_s, B_s = linearize_symbolic(m, op, r_op=dict(zip(m.input_names, r)),
                                  constants="values", t=t, simplify=False)
    A_c, B_c = sim.linearize(x, r=r, t=t)
    e = _rel(A_c, np.array(A_s.evalf(), dtype=float))
    if m.nr:
        e = max(e, _rel(B_c, np.array(B_s.evalf(), dtype=float)))
    note("linearize", e)
