"""PyDy drop-in: a PyDy script switched to eomgen by one argument.

    from pydy.codegen.ode_function_generators import generate_ode_function
    import gen.export.pydy
    rhs = generate_ode_function(forcing, q, u, constants, mass_matrix=M,
                                coordinate_derivatives=G, specifieds=r,
                                generator=gen.pydy.ODEFunctionGenerator)
    xdot = rhs(x, t, r_values, p_values)

or ``pydy_system.generate_ode_function(generator=gen.pydy.ODEFunctionGenerator)``.

:class:`ODEFunctionGenerator` takes the arguments of PyDy's generators (the
three forms: x' = F; M x' = F with the kinematics inside M; M u' = F with
q' = G) and returns a function with PyDy's call signature and results:
``rhs(x, t, r, p)`` (``rhs(x, t, p)`` without specifieds, ``rhs(t, x, ...)``
with ``time_first=True``), p an array or a dict, r an array, a function
``r(x, t)`` or a dict as PyDy documents. The equations become a
:class:`gen.Model` (:meth:`gen.Model.from_matrices`), compiled by
:func:`gen.compile` (cached by content), and each call is one C call that
returns a fresh array (PyDy's own generated functions return the same array
every call, which a caller keeping results, such as ``solve_ivp``'s
``dense_output``, sees change under it).

This module needs neither PyDy nor Cython: PyDy's ``generate_ode_function``
only calls the class and its ``generate()``.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

from ..core.errors import InputError, ModelError
from ..intake.model import Model

__all__ = ["ODEFunctionGenerator", "generate_ode_function"]

# the options of PyDy's own generators (Cython, lambdify): accepted so that a
# script switched from them runs unchanged. cse: eomgen always CSEs;
# force_c_contiguous: every array is converted as needed; prefix, tmp_dir:
# the build is cached by content (gen.compile); verbose: the compiler's commands.
_PYDY_OPTIONS = ("cse", "force_c_contiguous", "prefix", "tmp_dir", "verbose")
_SOLVERS = ("numpy", "scipy")


def _column(x, what):
    m = sm.Matrix(x)
    if m.shape[1] != 1 and m.shape[0] == 1:
        m = m.T
    if m.shape[1] != 1:
        raise ModelError(f"{what} must be a column of expressions, got shape {m.shape}")
    return m


def _shown(s):
    """A symbol as the user spells it: q for q(t)."""
    return str(s.func) if isinstance(s, sm.Function) or getattr(s, "is_Function", False) \
        else str(s)


def _is_zero(e):
    return e == 0 or e.is_zero is True


def _sorted_order(items, given_as_sequence):
    """The order the model keeps items in: the user's when given as a
    sequence, else by name (a set's iteration order changes from process to
    process, the compile cache would miss every time)."""
    if given_as_sequence:
        return list(range(len(items)))
    return sorted(range(len(items)), key=lambda i: str(items[i]))


class ODEFunctionGenerator:
    """PyDy's ODE-function generator, compiled by eomgen.

    Pass the class as ``generator=`` to PyDy's ``generate_ode_function`` or
    ``System.generate_ode_function``, or call it yourself and then
    :meth:`generate`.

    Parameters
    ----------
    right_hand_side : sympy Matrix, shape (n, 1)
        The forcing: F of x' = F (no mass matrix), of M x' = F (a full mass
        matrix) or of M u' = F (with ``coordinate_derivatives``).
    coordinates, speeds : sequence of functions of time
        q and u; x = [q, u].
    constants : sequence or set of sympy Symbols, optional
        The constants; p is in this order (a set's iteration order, as PyDy).
    mass_matrix : sympy Matrix, optional
        The full mass matrix (n_states square, the kinematics in its first
        rows: ``KanesMethod.mass_matrix_full``) or, with
        ``coordinate_derivatives``, the mass matrix of the speeds.
    coordinate_derivatives : sympy Matrix, shape (nq, 1), optional
        q' = G(q, u, t, p) (the minimal form).
    specifieds : sequence or set of functions of time, optional
        The specified inputs r, in this order.
    linear_sys_solver : {"numpy", "scipy"} or "sympy[:method]" or callable, optional
        The strings all mean the solve in C (a symmetric factorization for a
        symmetric mass matrix, LU otherwise); a function ``solve(A, b)`` is called
        with the speeds' mass matrix and forcing, as PyDy calls it.
    constants_arg_type : {None, "array", "dictionary"}, optional
    specifieds_arg_type : {None, "array", "function", "dictionary"}, optional
        What p and r will be; None accepts every kind at each call.
    time_first : bool, optional
        ``rhs(t, x, ...)`` instead of ``rhs(x, t, ...)``.
    name : str, optional
        The C prefix of the compiled model (default ``"pydy"``).
    backend : {"c", "eigen"}, optional
        As for :func:`gen.compile`.
    cse, force_c_contiguous, prefix, tmp_dir, verbose
        The options of PyDy's Cython and lambdify generators, accepted so that
        a switched script runs unchanged; only ``verbose`` has an effect (the
        compiler's commands).

    Raises
    ------
    gen.ModelError
        (a ``ValueError``) naming the argument and its value when the
        arguments do not describe one of PyDy's three forms, or an option is
        unknown. Never a ``TypeError``: PyDy's ``generate_ode_function``
        would take that for "not a generator class".
    """

    def __init__(self, right_hand_side, coordinates, speeds, constants=(),
                 mass_matrix=None, coordinate_derivatives=None, specifieds=None,
                 linear_sys_solver="numpy", constants_arg_type=None,
                 specifieds_arg_type=None, time_first=False, name="pydy", backend="c",
                 **options):
        unknown = sorted(set(options) - set(_PYDY_OPTIONS))
        if unknown:
            raise ModelError(
                f"unknown argument(s) {', '.join(unknown)} for gen.pydy.ODEFunctionGenerator: "
                f"accepted are PyDy's ({', '.join(_PYDY_OPTIONS)}) and name, backend")
        self.options = dict(options)
        self.name = name
        self.backend = backend
        self.time_first = bool(time_first)
        self.coordinates = list(coordinates)
        self.speeds = list(speeds)
        constants = () if constants is None else constants
        self.constants = list(constants)
        self._p_order = _sorted_order(self.constants, isinstance(constants, Sequence))
        if specifieds is not None and len(specifieds) == 0:
            specifieds = None
        self.specifieds = None if specifieds is None else list(specifieds)
        self._r_order = (None if specifieds is None else
                         _sorted_order(self.specifieds, isinstance(specifieds, Sequence)))
        self.num_coordinates = len(self.coordinates)
        self.num_speeds = len(self.speeds)
        self.num_states = self.num_coordinates + self.num_speeds
        self.num_constants = len(self.constants)
        self.num_specifieds = 0 if self.specifieds is None else len(self.specifieds)

        if constants_arg_type not in (None, "array", "dictionary"):
            raise ModelError(f"constants_arg_type = {constants_arg_type!r} is not one of "
                             "None, 'array', 'dictionary'")
        if specifieds_arg_type not in (None, "array", "function", "dictionary"):
            raise ModelError(f"specifieds_arg_type = {specifieds_arg_type!r} is not one of "
                             "None, 'array', 'function', 'dictionary'")
        self.constants_arg_type = constants_arg_type
        self.specifieds_arg_type = None if self.specifieds is None else specifieds_arg_type

        self.linear_sys_solver = linear_sys_solver
        if callable(linear_sys_solver):
            self._solve = linear_sys_solver
        elif isinstance(linear_sys_solver, str) and (
                linear_sys_solver in _SOLVERS or linear_sys_solver.startswith("sympy")):
            self._solve = None                       # in C
        else:
            raise ModelError(f"linear_sys_solver = {linear_sys_solver!r} is not a valid "
                             "solver: 'numpy', 'scipy', 'sympy[:method]' or a function "
                             "solve(A, b)")

        nq, nu, n = self.num_coordinates, self.num_speeds, self.num_states
        F = _column(right_hand_side, "right_hand_side")
        if coordinate_derivatives is not None:
            self.system_type = "min mass matrix"
            if mass_matrix is None:
                raise ModelError("coordinate_derivatives given without mass_matrix: the "
                                 "minimal form is M(q) u' = F, q' = G")
            M, G = sm.Matrix(mass_matrix), _column(coordinate_derivatives,
                                                  "coordinate_derivatives")
            self._check_shape("mass_matrix", M.shape, (nu, nu))
            self._check_shape("right_hand_side", F.shape, (nu, 1))
            self._check_shape("coordinate_derivatives", G.shape, (nq, 1))
            self.mass_matrix, self.coordinate_derivatives = M, G
        elif mass_matrix is not None:
            self.system_type = "full mass matrix"
            M = sm.Matrix(mass_matrix)
            self._check_shape("mass_matrix", M.shape, (n, n))
            self._check_shape("right_hand_side", F.shape, (n, 1))
            self.mass_matrix, self.coordinate_derivatives = M, None
        else:
            self.system_type = "full rhs"
            self._check_shape("right_hand_side", F.shape, (n, 1))
            self.mass_matrix, self.coordinate_derivatives = None, None
        self.right_hand_side = F

    def _check_shape(self, what, got, want):
        if tuple(got) != tuple(want):
            raise ModelError(
                f"{what} has shape {tuple(got)}, expected {tuple(want)} for {self.num_coordinates} "
                f"coordinate(s) and {self.num_speeds} speed(s) ({self.system_type} form)")

    # ------------------------------------------------------------ the model
    def equations(self):
        """The equations of the speeds, from whichever form was given.

        Returns
        -------
        tuple of sympy Matrix
            (M, f, kinematics): ``M u' = f`` and ``kinematics = 0``, linear in
            q' and u (``q' - G`` for the minimal form and x' = F).

        Raises
        ------
        gen.ModelError
            When a full mass matrix couples the kinematic rows with u' or the
            dynamic rows with q' (the block and an entry are named).
        """
        nq, nu = self.num_coordinates, self.num_speeds
        t = me.dynamicsymbols._t
        qd = sm.Matrix([qi.diff(t) for qi in self.coordinates])
        F = self.right_hand_side
        if self.system_type == "min mass matrix":
            return self.mass_matrix, F, qd - self.coordinate_derivatives
        if self.system_type == "full rhs":
            return sm.eye(nu), F[nq:, :], qd - F[:nq, :]
        M = self.mass_matrix
        for block, rows, cols in (("[:nq, nq:] (kinematic rows, u')", slice(0, nq),
                                   slice(nq, nq + nu)),
                                  ("[nq:, :nq] (dynamic rows, q')", slice(nq, nq + nu),
                                   slice(0, nq))):
            bad = [e for e in M[rows, cols] if not _is_zero(e)]
            if bad:
                raise ModelError(
                    f"mass_matrix{block} is not zero ({bad[0]}): the full form must be "
                    "[[K(q), 0], [0, M(q)]] in x = [q, u], with the kinematics in the first "
                    f"{nq} rows (KanesMethod.mass_matrix_full)")
        return M[nq:, nq:], F[nq:, :], M[:nq, :nq] * qd - F[:nq, :]

    def model(self):
        """The :class:`gen.Model` of the equations.

        Returns
        -------
        gen.Model
            Through :meth:`gen.Model.from_matrices`; constants and specifieds in
            the order given, or by name when given as a set. The constants'
            values are placeholders (every call of ``rhs`` passes p).
        """
        M, f, kin = self.equations()
        consts = [self.constants[i] for i in self._p_order]
        inputs = ([] if self.specifieds is None else
                  [self.specifieds[i] for i in self._r_order])
        # the values are placeholders: every call passes p
        return Model.from_matrices(M, f, self.coordinates, self.speeds, kin,
                                   constants={c: 1.0 for c in consts}, inputs=inputs,
                                   name=self.name)

    # ------------------------------------------------------------- generate
    def generate(self):
        """Compile (cached by content) and return ``rhs``.

        Returns
        -------
        function
            ``rhs(x, t, r, p)`` (PyDy's signature: ``rhs(x, t, p)`` without
            specifieds, ``(t, x, ...)`` with ``time_first``); a fresh
            ``numpy.ndarray`` of shape (n_states,) per call. Its attributes
            ``simulator`` (the compiled :class:`gen.sim.simulator.Simulator`, in the
            model's order of constants and inputs) and ``model`` (the
            :class:`gen.Model`) give the rest of eomgen; ``constants`` and
            ``specifieds`` are the orders of the arrays p and r.
        """
        from ..pipeline import compile as gen_compile
        model = self.model()
        sim = gen_compile(model, backend=self.backend,
                          verbose=bool(self.options.get("verbose", False)))
        rhs = self._rhs_function(sim)
        rhs.simulator = sim
        rhs.model = model
        rhs.constants = list(self.constants)         # the order of an array p
        rhs.specifieds = list(self.specifieds or ())  # the order of an array r
        rhs.__doc__ = self._rhs_doc()
        return rhs

    # -------------------------------------------------- the call's arguments
    def _converters(self):
        """(p_of(p), r_of(x, t, r)): p and r as the model's float arrays, from
        every kind PyDy documents (r_of is None without specifieds)."""
        nc, nr = self.num_constants, self.num_specifieds
        pidx = np.array(self._p_order, dtype=np.intp)
        p_id = self._p_order == list(range(nc))
        constants = self.constants
        pkind, rkind, tf = self.constants_arg_type, self.specifieds_arg_type, self.time_first

        def p_of(p):
            if type(p) is np.ndarray and p.shape == (nc,) and pkind != "dictionary":
                return p if p_id else p.take(pidx)
            if isinstance(p, dict) and pkind != "array":
                try:
                    a = np.array([p[c] for c in constants], dtype=float)
                except KeyError as e:
                    raise ModelError(f"p has no value for the constant {e.args[0]}") from None
            elif pkind == "dictionary":
                raise ModelError(f"p must be a dict (constants_arg_type='dictionary'), got "
                                 f"{type(p).__name__}")
            else:
                a = np.asarray(p, dtype=float)
                if a.shape != (nc,):
                    raise ModelError(f"p must have shape ({nc},) (the constants {constants}), "
                                     f"got {a.shape}")
            return a if p_id else a.take(pidx)

        if self.specifieds is None:
            return p_of, None
        ridx = np.array(self._r_order, dtype=np.intp)
        r_id = self._r_order == list(range(nr))
        index = {s: i for i, s in enumerate(self.specifieds)}
        specifieds = self.specifieds

        def from_dict(x, t, r):
            vals = np.full(nr, np.nan)
            for k, v in r.items():
                keys = k if isinstance(k, tuple) else (k,)
                try:
                    idx = [index[s] for s in keys]
                except KeyError as e:
                    raise ModelError(f"r has a key {e.args[0]} that is not a specified "
                                     f"({specifieds})") from None
                vals[idx] = (v(t, x) if tf else v(x, t)) if callable(v) else v
            if np.isnan(vals).any():
                missing = [s for s, v in zip(specifieds, vals) if np.isnan(v)]
                raise ModelError(f"r gives no value (or NaN) for the specified(s) {missing}")
            return vals

        def r_of(x, t, r):
            if type(r) is np.ndarray and r.shape == (nr,) and rkind in (None, "array"):
                return r if r_id else r.take(ridx)
            if rkind == "dictionary" or (rkind is None and isinstance(r, dict)):
                a = from_dict(x, t, r)
            else:
                if rkind == "function" or (rkind is None and callable(r)):
                    r = r(t, x) if tf else r(x, t)
                a = np.asarray(r, dtype=float).reshape(-1)
                if a.shape != (nr,):
                    raise ModelError(f"r must give {nr} value(s) (the specifieds "
                                     f"{specifieds}), got shape {np.shape(r)}")
            return a if r_id else a.take(ridx)
        return p_of, r_of

    def _nonfinite(self, x, r, p):
        """After the C call refused a NaN or infinite value: an InputError
        naming it as the caller gave it (a state of x, a specified of r, a
        constant of p, by its symbol and its index in the caller's order);
        r and p as the call converted them (the model's order)."""
        rows = [("p", p, [self.constants[i] for i in self._p_order], self._p_order,
                 "constant"),
                ("r", r, [self.specifieds[i] for i in self._r_order] if self.specifieds
                 else [], self._r_order, "specified"),
                ("x", x, self.coordinates + self.speeds, None, "state")]
        for arg, a, syms, order, kind in rows:
            a = np.zeros(0) if a is None else np.asarray(a, dtype=float).reshape(-1)
            bad = np.flatnonzero(~np.isfinite(a))
            if bad.size:
                i = int(bad[0])
                j = i if order is None else int(order[i])
                raise InputError(
                    f"the {kind} {_shown(syms[i])} of {arg} is {float(a[i])!r}: every "
                    f"{kind} must be finite", arg, j, float(a[i])) from None

    # ------------------------------------------------------------- the rhs
    def _rhs_function(self, sim):
        nq, ns = self.num_coordinates, self.num_states
        has_r, has_p = self.specifieds is not None, self.num_constants > 0
        solve, tf = self._solve, self.time_first
        p_of, r_of = self._converters()
        # one state through rhs_batch: its CPython fast path takes p (rhs's
        # takes only t, x, r: with p it converts in Python, 4-5x the call);
        # the same C function, a fresh (1, nx) array per call
        batch = sim.rhs_batch
        nonfinite = self._nonfinite

        def sim_rhs(t, x, r=None, p=None):
            try:
                X = x.reshape(1, ns)
            except AttributeError:
                X = np.asarray(x, dtype=float).reshape(1, -1)
            except ValueError:
                X = None
            if X is None or X.shape != (1, ns):
                raise ValueError(f"x must have shape ({ns},), got {np.shape(x)}")
            if solve is None:
                try:
                    return batch(t, X, r=r, p=p)[0]
                except InputError as e:
                    if "ERR_NONFINITE_INPUT" in str(e):
                        nonfinite(X[0], r, p)
                    raise
            # the user's linear solver, on the speeds' M u' = f
            x = X[0].astype(float)
            q, u = x[:nq], x[nq:]
            M = sim.mass_matrix(q, p=p, t=t)
            f = sim.forcing(q, u, r=r, p=p, t=t)
            out = np.empty(ns)
            out[:nq] = sim.kinematics(q, u, p=p, t=t)
            out[nq:] = np.asarray(solve(M, f), dtype=float).reshape(-1)
            return out

        n_args = 3 + has_r
        min_args = n_args - (0 if has_p else 1)
        usage = f"rhs takes {'(t, x' if tf else '(x, t'}{', r' if has_r else ''}, p)"

        if has_r and has_p:
            def rhs(*args):
                if len(args) != 4:
                    raise TypeError(f"{usage}, {len(args)} argument(s) given")
                x, t = (args[1], args[0]) if tf else (args[0], args[1])
                return sim_rhs(t, x, r=r_of(x, t, args[2]), p=p_of(args[3]))
        elif has_p:
            def rhs(*args):
                if len(args) != 3:
                    raise TypeError(f"{usage}, {len(args)} argument(s) given")
                x, t = (args[1], args[0]) if tf else (args[0], args[1])
                return sim_rhs(t, x, p=p_of(args[2]))
        else:
            # no constants: p may be left out (PyDy ignores it)
            def rhs(*args):
                if not min_args <= len(args) <= n_args:
                    raise TypeError(f"{usage}, {len(args)} argument(s) given")
                x, t = (args[1], args[0]) if tf else (args[0], args[1])
                r = r_of(x, t, args[2]) if has_r else None
                return sim_rhs(t, x, r=r, p=np.zeros(0))
        return rhs

    def _rhs_doc(self):
        def lst(syms):
            return "\n".join(f"        - {s}" for s in syms) or "        (none)"
        xt = "t, x" if self.time_first else "x, t"
        sig = f"{xt}, r, p" if self.specifieds is not None else f"{xt}, p"
        doc = (f"Returns x' = f({sig}), compiled by eomgen (a fresh array per call).\n\n"
               f"Parameters\n==========\nx : ndarray, shape({self.num_states},)\n"
               f"    The states, in order:\n{lst(self.coordinates + self.speeds)}\n"
               "t : float\n    The time.\n")
        if self.specifieds is not None:
            doc += (f"r : ndarray shape({self.num_specifieds},), function r({xt}) or "
                    f"dictionary\n    The specifieds, in order:\n{lst(self.specifieds)}\n")
        doc += (f"p : ndarray shape({self.num_constants},) or dictionary\n"
                f"    The constants, in order:\n{lst(self.constants)}\n\n"
                f"Returns\n=======\ndx : ndarray, shape({self.num_states},)\n")
        return doc


def generate_ode_function(*args, **kwargs):
    """``ODEFunctionGenerator(*args, **kwargs).generate()``: PyDy's
    ``generate_ode_function`` with eomgen as the generator, for scripts that
    import the function from here instead of passing ``generator=``."""
    return ODEFunctionGenerator(*args, **kwargs).generate()
