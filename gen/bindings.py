"""The numpy-facing simulator over a compiled model. C status codes become
exceptions from gen.errors; wrong shapes raise ValueError naming the
expected shape. Every call returns fresh arrays (safe with solve_ivp)."""
from __future__ import annotations

import numpy as np

from .errors import ConvergenceError, SingularError, SolverError

__all__ = ["Simulator"]

_STATUS_NAMES = {
    -1: "ERR_NULL", -2: "ERR_NONFINITE_INPUT", -3: "ERR_SINGULAR", -4: "ERR_NO_CONVERGENCE",
    -5: "ERR_STEP_UNDERFLOW", -6: "ERR_MAX_STEPS", -7: "ERR_BAD_ARG",
    -8: "ERR_NONFINITE_MODEL", -9: "ERR_OUTPUT_FULL",
}
_METHODS = {"rk4": 0, "dopri5": 1}


class Simulator:
    """A compiled model. Attributes: nq, nu, nx, nr, np, mc, mv, ns,
    state_names, input_names, constant_names, independent_state_names,
    constants (default values)."""

    def __init__(self, model, module, real="double"):
        self.model = model
        self._mod = module
        self._ffi = module.ffi
        self._lib = module.lib
        self._p = model.name
        self.real = real
        self.dtype = np.float64 if real == "double" else np.float32
        self._ctype = f"{model.name}_real"
        self.name = model.name
        self.method = model.method
        self.nq, self.nu, self.nx = model.nq, model.nu, model.nx
        self.nr, self.np, self.mc, self.mv = model.nr, model.np, model.mc, model.mv
        self.ns = model.ns
        self.state_names = list(model.state_names)
        self.input_names = list(model.input_names)
        self.constant_names = list(model.constant_names)
        self.independent_state_names = list(model.independent_state_names)
        self.constants = np.array(model.p_values, dtype=float)
        self.q_ind, self.q_dep = list(model.q_ind), list(model.q_dep)
        self.u_ind, self.u_dep = list(model.u_ind), list(model.u_dep)
        # per-call overhead: typed buffers without casts, functions looked up
        # once, the default constants converted once
        self._arr_t = f"{self._ctype}[]"
        self._dt = np.dtype(self.dtype)
        self._fns = {}
        self._p_default = np.ascontiguousarray(self.constants, dtype=self.dtype)

    # ------------------------------------------------------------ helpers
    def _fn(self, name):
        f = self._fns.get(name)
        if f is None:
            f = self._fns[name] = getattr(self._lib, f"{self._p}_{name}")
        return f

    def _vec(self, v, n, what, default=None):
        if (type(v) is np.ndarray and v.dtype is self._dt and v.shape == (n,)
                and v.flags.c_contiguous):
            return v                                   # fast path: no copy
        if v is None:
            if default is None:
                v = np.zeros(n)
            else:
                v = default
        if isinstance(v, dict):
            v = self._from_dict(v, what)
        a = np.ascontiguousarray(v, dtype=self.dtype)
        if a.ndim == 0 and n == 1:
            a = a.reshape(1)
        if a.shape != (n,):
            raise ValueError(f"{what} must have shape ({n},), got {np.shape(v)}")
        return a

    def _from_dict(self, d, what):
        kind = what.split()[0]
        names = {"state": self.state_names, "inputs": self.input_names,
                 "constants": self.constant_names}.get(kind)
        if names is None:
            raise ValueError(f"{what} cannot be given as a dict")
        labels = {"state": self.model.state_labels, "inputs": self.model.input_labels,
                  "constants": self.model.constant_labels}[kind]
        base = {"state": np.zeros(self.nx), "inputs": np.zeros(self.nr),
                "constants": self.constants.copy()}[what.split()[0]]
        for k, v in d.items():
            k = str(k)
            if k in names:
                base[names.index(k)] = float(v)
            elif k in labels:                  # the sympy spelling works too
                base[labels.index(k)] = float(v)
            else:
                raise ValueError(f"unknown name {k!r} in {what}; known: {names}")
        return base

    def _ptr(self, a):
        if a is None:
            return self._ffi.NULL
        return self._ffi.from_buffer(self._arr_t, a)

    def _check(self, status, where, t=None, state=None):
        if status == 0:
            return
        msg = self._ffi.string(self._fn("status_message")(status)).decode()
        name = _STATUS_NAMES.get(status, str(status))
        text = f"{self._p}_{where}: {msg} [{name}]"
        if t is not None:
            text += f" at t = {float(t):.17g}"
        if state is not None:
            pairs = ", ".join(f"{n}={float(v):.12g}" for n, v in zip(self.state_names, state))
            text += f", state: {pairs}"
        cls = SolverError
        if status in (-3, -8):
            cls = SingularError
        elif status in (-4, -5, -6):
            cls = ConvergenceError
        elif status in (-2, -7):
            raise ValueError(text)
        raise cls(text, status=status, status_name=name, time=t,
                  state=None if state is None else np.array(state, dtype=float))

    def _params(self, p):
        if p is None:
            return self._p_default
        return self._vec(p, self.np, "constants p", default=self.constants)

    # ------------------------------------------------------- evaluation
    def mass_matrix(self, q, p=None, t=0.0):
        """M(q), shape (nu, nu): unconstrained mass matrix."""
        q = self._vec(q, self.nq, "coordinates q")
        out = np.empty(self.nu * self.nu, dtype=self.dtype)
        st = self._fn("eval_mass_matrix")(self._ptr(q), self._ptr(self._params(p)), t, self._ptr(out))
        self._check(st, "eval_mass_matrix", t)
        return out.reshape(self.nu, self.nu)

    def forcing(self, q, u, r=None, p=None, t=0.0):
        """f(q, u, r, t), shape (nu,): M u' = f + A^T lam."""
        q = self._vec(q, self.nq, "coordinates q")
        u = self._vec(u, self.nu, "speeds u")
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        out = np.empty(self.nu, dtype=self.dtype)
        st = self._fn("eval_forcing")(self._ptr(q), self._ptr(u), self._ptr(r),
                                      self._ptr(self._params(p)), t, self._ptr(out))
        self._check(st, "eval_forcing", t)
        return out

    def kinematics(self, q, u, p=None, t=0.0):
        """q' from the kinematic equations, shape (nq,)."""
        q = self._vec(q, self.nq, "coordinates q")
        u = self._vec(u, self.nu, "speeds u")
        out = np.empty(self.nq, dtype=self.dtype)
        st = self._fn("eval_kinematics")(self._ptr(q), self._ptr(u), self._ptr(self._params(p)),
                                         t, self._ptr(out))
        self._check(st, "eval_kinematics", t)
        return out

    def constraints(self, q, p=None, t=0.0):
        """Configuration-constraint residuals f_c(q), shape (mc,)."""
        q = self._vec(q, self.nq, "coordinates q")
        out = np.zeros(max(1, self.mc), dtype=self.dtype)
        st = self._fn("eval_constraints")(self._ptr(q), self._ptr(self._params(p)), t, self._ptr(out))
        self._check(st, "eval_constraints", t)
        return out[:self.mc].copy()

    def constraint_jacobian(self, q, p=None, t=0.0):
        """d f_c / dq, shape (mc, nq)."""
        q = self._vec(q, self.nq, "coordinates q")
        out = np.zeros(max(1, self.mc * self.nq), dtype=self.dtype)
        st = self._fn("eval_constraint_jacobian")(self._ptr(q), self._ptr(self._params(p)), t,
                                                  self._ptr(out))
        self._check(st, "eval_constraint_jacobian", t)
        return out[:self.mc * self.nq].reshape(self.mc, self.nq).copy()

    def velocity_constraints(self, q, u, p=None, t=0.0):
        """A(q) u + b, shape (mv,)."""
        q = self._vec(q, self.nq, "coordinates q")
        u = self._vec(u, self.nu, "speeds u")
        out = np.zeros(max(1, self.mv), dtype=self.dtype)
        st = self._fn("eval_velocity_constraints")(self._ptr(q), self._ptr(u),
                                                   self._ptr(self._params(p)), t, self._ptr(out))
        self._check(st, "eval_velocity_constraints", t)
        return out[:self.mv].copy()

    def velocity_constraint_matrix(self, q, p=None, t=0.0):
        """(A, b): A shape (mv, nu), b shape (mv,)."""
        q = self._vec(q, self.nq, "coordinates q")
        A = np.zeros(max(1, self.mv * self.nu), dtype=self.dtype)
        b = np.zeros(max(1, self.mv), dtype=self.dtype)
        st = self._fn("eval_velocity_constraint_matrix")(self._ptr(q), self._ptr(self._params(p)),
                                                         t, self._ptr(A), self._ptr(b))
        self._check(st, "eval_velocity_constraint_matrix", t)
        return A[:self.mv * self.nu].reshape(self.mv, self.nu).copy(), b[:self.mv].copy()

    def energy(self, x, p=None, t=0.0):
        """Total energy at state x (models given an energy expression)."""
        if self.model.energy is None:
            raise ValueError(f"model '{self.name}' was built without energy=...")
        x = self._vec(x, self.nx, "state x")
        out = np.zeros(1, dtype=self.dtype)
        st = self._fn("eval_energy")(self._ptr(x[:self.nq]), self._ptr(x[self.nq:]),
                                     self._ptr(self._params(p)), t, self._ptr(out))
        self._check(st, "eval_energy", t, x)
        return float(out[0])

    def rhs(self, t, x, r=None, p=None):
        """x' (shape (nx,)), usable as solve_ivp's fun: rhs(t, x)."""
        x = self._vec(x, self.nx, "state x")
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        out = np.empty(self.nx, dtype=self.dtype)
        st = self._fn("eval_rhs")(t, self._ptr(x), self._ptr(r), self._ptr(self._params(p)),
                                  self._ptr(out), self._ffi.NULL)
        self._check(st, "eval_rhs", t, x)
        return out

    def multipliers(self, t, x, r=None, p=None):
        """Multipliers lam of the velocity constraints, shape (mv,)."""
        x = self._vec(x, self.nx, "state x")
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        out = np.empty(self.nx, dtype=self.dtype)
        lam = np.zeros(max(1, self.mv), dtype=self.dtype)
        st = self._fn("eval_rhs")(t, self._ptr(x), self._ptr(r), self._ptr(self._params(p)),
                                  self._ptr(out), self._ptr(lam))
        self._check(st, "eval_rhs", t, x)
        return lam[:self.mv].copy()

    # ---------------------------------------------------- the manifold
    def project(self, x, p=None, t=0.0, tol=0.0, max_iter=0):
        """x projected onto the configuration and velocity constraints."""
        x = self._vec(x, self.nx, "state x").copy()
        st = self._fn("project")(t, self._ptr(self._params(p)), tol, max_iter, self._ptr(x))
        self._check(st, "project", t, x)
        return x

    def consistent_state(self, x, p=None, t=0.0, tol=0.0, max_iter=0):
        """Dependent coordinates and speeds solved from the independent ones
        (the dependent entries of x are the starting guess). x may be a
        dict {state name: value}."""
        x = self._vec(x, self.nx, "state x").copy()
        st = self._fn("consistent_state")(t, self._ptr(self._params(p)), tol, max_iter,
                                          self._ptr(x))
        self._check(st, "consistent_state", t, x)
        return x

    # ------------------------------------------------------- simulation
    def simulate(self, x0, t_end, dt, method="rk4", rtol=1e-8, atol=1e-10, r=None, p=None,
                 project=True, t0=0.0, max_steps=100000, return_multipliers=False,
                 return_stats=False):
        """Simulate from x0 to t_end. dt is the RK4 step, or the output
        interval of the adaptive DOPRI5. Returns (t, X) with one row per
        output time (plus the multipliers and/or stats when asked)."""
        if method not in _METHODS:
            raise ValueError(f"method must be one of {sorted(_METHODS)}, got {method!r}")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number, got {dt!r}")
        if not (np.isfinite(t_end) and t_end >= t0):
            raise ValueError(f"t_end must be a number >= t0 = {t0}, got {t_end!r}")
        x0 = self._vec(x0, self.nx, "state x0")
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        rows = self._fn("simulate_rows")(t0, t_end, dt)
        if rows < 0:
            self._check(rows, "simulate_rows")
        opts = self._ffi.new(f"{self._p}_sim_options *")
        self._fn("sim_options_default")(opts)
        opts.method = _METHODS[method]
        opts.project = 1 if project else 0
        opts.rtol = rtol
        opts.atol = atol
        opts.max_steps = int(max_steps)
        stats = self._ffi.new(f"{self._p}_sim_stats *")
        t = np.empty(rows, dtype=self.dtype)
        X = np.empty((rows, self.nx), dtype=self.dtype)
        lam = np.empty((rows, max(1, self.mv)), dtype=self.dtype)
        st = self._fn("simulate")(self._ptr(x0), t0, t_end, dt, self._ptr(r),
                                  self._ptr(self._params(p)), opts, rows, self._ptr(t),
                                  self._ptr(X), self._ptr(lam), stats)
        if st != 0:
            last = np.array([stats.x_last[i] for i in range(self.nx)])
            self._check(st, "simulate", stats.t_last, last)
        out = [t, X]
        if return_multipliers:
            out.append(lam[:, :self.mv].copy())
        if return_stats:
            out.append({"n_accepted": stats.n_accepted, "n_rejected": stats.n_rejected,
                        "n_rhs": stats.n_rhs, "n_out": stats.n_out})
        return tuple(out)

    def step_rk4(self, t, x, h, r=None, p=None, project=True):
        """One RK4 step; returns the new state."""
        x = self._vec(x, self.nx, "state x").copy()
        r = None if r is None else self._vec(r, self.nr, "inputs r")
        st = self._fn("step_rk4")(t, h, self._ptr(r), self._ptr(self._params(p)),
                                  1 if project else 0, self._ptr(x))
        self._check(st, "step_rk4", t, x)
        return x

    # ---------------------------------------------------- linearization
    def linearize(self, x_op, r_op=None, p=None, t=0.0):
        """(A, B) about the operating point for the independent state
        [q_ind, u_ind] (sympy's A_and_B=True partition): A (ns, ns), B (ns, nr).
        The operating point need not be an equilibrium."""
        x = self._vec(x_op, self.nx, "state x_op")
        r = None if r_op is None else self._vec(r_op, self.nr, "inputs r_op")
        A = np.empty(self.ns * self.ns, dtype=self.dtype)
        B = np.zeros(max(1, self.ns * self.nr), dtype=self.dtype)
        st = self._fn("linearize")(self._ptr(x), self._ptr(r), self._ptr(self._params(p)), t,
                                   self._ptr(A), self._ptr(B))
        self._check(st, "linearize", t, x)
        return (A.reshape(self.ns, self.ns),
                B[:self.ns * self.nr].reshape(self.ns, self.nr).copy())

    def __repr__(self):
        return (f"<eomgen Simulator '{self.name}' ({self.method}, {self.real}): "
                f"nq={self.nq} nu={self.nu} nr={self.nr} np={self.np} mc={self.mc} mv={self.mv}>")
