"""Canonical model: what a simulator needs, extracted from a formed
``sympy.physics.mechanics`` object and validated.

Every model, Kane or Lagrange, is held in one form (all expressions in
plain sympy symbols, no functions of time):

    kinematics    Kqd(q) q' + Ku(q) u + kf(q, t) = 0           (nq rows)
    dynamics      M(q) u' = f(q, u, r, t) + A(q)^T lam          (nu rows)
    velocity      A(q) u + b(q, t) = 0                          (mv rows)
    acceleration  A(q) u' + a(q, u, t) = 0                      (mv rows)
    configuration f_c(q, t) = 0                                 (mc rows)

M and f are the *unconstrained* equations for all speeds: the dependent
speeds are eliminated (Kane) or the multipliers solved for (Lagrange)
numerically at run time, never symbolically (sympy's symbolic elimination
can divide by zero at regular configurations, ../shared/NOTES-sympy.md 1).

State layout: x = [q, u]. For Kane models q = [q_ind, q_dep] and
u = [u_ind, u_dep] in the KanesMethod's order; for Lagrange models
q is the LagrangesMethod's coordinate order and u = q'.

Multiplier sign: M u' = f + A^T lam with A = d(velocity constraints)/du.
For a LagrangesMethod this lam equals the multiplier part of the solution of
sympy's ``mass_matrix_full`` / ``forcing_full`` system (and of ``LM.rhs()``),
the negative of what ``LM.solve_multipliers`` returns (sympy issue 30215).

The C naming rules (validate_name, c_name, c_names) live in gen.core.names
and are re-exported here.

This module holds the Model: its fields, sizes, names and fingerprint, and
the builders users call (from_kanes, from_lagrange, from_system,
from_matrices), each a thin front: the adapters (gen.intake.kane, lagrange,
matrices; system for the containers and from_system's dispatch) turn a sympy
object into Equations, and gen.intake.canonical's passes turn those into the
validated Model.
"""
from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field

import sympy as sm
from sympy.physics import mechanics as me

from ..core.errors import ModelError
from ..core.names import C_KEYWORDS, C_LIBRARY_NAMES, c_name, c_names, validate_name  # noqa: F401
from ..sym.dag import graph_srepr
from .canonical import finish
from .checks import user_stacklevel  # noqa: F401 (gen.sim's warnings)
from .kane import kane_equations
from .lagrange import lagrange_equations
from .matrices import matrices_equations
from .system import (CONSTRUCTORS, builder_of, is_pydy_system, kane_of, lagrange_of,
                     recursive_model)


def _size(fget, doc):
    """A size of the model (nq, nu, ...) as a property with its doc."""
    fget.__doc__ = doc
    return property(fget, doc=doc)


# the builders' shared parameters and result, written once: a docstring line
# ".. shared:: name energy" stands for those blocks (shared_doc)
SHARED_DOC = {
    "name": """\
name : str, optional
    The model's name: the prefix of every C symbol (``[a-z][a-z0-9_]*``,
    not a C keyword or a C library name).
""",
    "energy": """\
energy : sympy expression, optional
    The total energy, for diagnostics (``sim.energy``, the CSV).
""",
    "outputs": """\
outputs : dict, optional
    ``{name: expression}`` of quantities to measure (sensor readings,
    point positions) in the coordinates, speeds, inputs, constants and t
    (``sim.outputs``; ``linearize_outputs`` gives C and D).
""",
    "hybrid": """\
hybrid : dict, optional
    ``{name: gen.Impact(gap, ...) or gen.Reset(guard, map, ...)}``:
    impacts and resets, run in C with the rest of the model; every jump
    is logged in ``sol.events`` (``docs/guides/hybrid.md``).
""",
    "returns": """\
Returns
-------
Model
    The canonical model, validated.
""",
}


def shared_doc(fn):
    """fn with each ".. shared:: key ..." line of its docstring replaced by
    the SHARED_DOC blocks of those keys, at the line's indentation."""
    out = []
    for line in (fn.__doc__ or "").splitlines():
        m = re.fullmatch(r"(\s*)\.\. shared:: ([a-z ]+)", line)
        if m is None:
            out.append(line)
            continue
        for key in m.group(2).split():
            out += [m.group(1) + row if row else row for row in SHARED_DOC[key].splitlines()]
    fn.__doc__ = "\n".join(out)
    return fn

__all__ = ["Model", "validate_name", "c_name", "c_names", "require_model", "user_stacklevel"]


@dataclass
class Model:
    """A validated, canonical model (see the module docstring for the form).

    Build one with :meth:`from_kanes` or :meth:`from_lagrange`."""

    name: str
    method: str                      # "kane" | "lagrange"
    # sympy objects as the user knows them (functions of time / symbols)
    q_orig: list
    u_orig: list
    r_orig: list
    p_orig: list
    p_values: list
    # internal plain symbols, same order as the originals
    q: list
    u: list
    r: list
    p: list
    t: sm.Symbol
    q_ind: list                      # indices into q
    q_dep: list
    u_ind: list                      # indices into u
    u_dep: list
    # expressions in the internal symbols
    Kqd: sm.Matrix
    Ku: sm.Matrix
    kf: sm.Matrix
    M: sm.Matrix
    f: sm.Matrix
    A: sm.Matrix
    b: sm.Matrix
    fc: sm.Matrix
    qdot: sm.Matrix | None           # explicit q' (when Kqd is diagonal), else None
    energy: sm.Expr | None = None    # total energy, if known
    # names as identifiers ([A-Za-z_][A-Za-z0-9_]*, unique): what generated
    # files, the CLI and the Python API use
    state_names: list = field(default_factory=list)
    input_names: list = field(default_factory=list)
    constant_names: list = field(default_factory=list)
    # the names as sympy prints them (may hold any character)
    state_labels: list = field(default_factory=list)
    input_labels: list = field(default_factory=list)
    constant_labels: list = field(default_factory=list)
    # auxiliary speeds (Kane's u_auxiliary): the reaction forces along them
    # solve aux_F reactions + aux_g = 0 (NA rows, aux_F square), with aux_F
    # and aux_g in q, u, ud (the internal symbols of u'), r, p, t
    aux_F: sm.Matrix | None = None
    aux_g: sm.Matrix | None = None
    # reactions inside the dynamics, solved with u' at run time (one linear
    # system in [u', reactions] per evaluation): f holds them at zero and
    # M u' = f + aux_G reactions (NU x NA, in q, u, r, p, t); None when the
    # reactions do not enter the motion or were eliminated symbolically
    aux_G: sm.Matrix | None = None
    ud: list = field(default_factory=list)
    reaction_orig: list = field(default_factory=list)
    auxiliary_names: list = field(default_factory=list)   # C-safe, unique
    auxiliary_labels: list = field(default_factory=list)  # as sympy prints them
    # internal symbols of q' in the acceleration-constraint term a, when the
    # kinematics are implicit (qdot is None) and there are velocity
    # constraints; empty otherwise (a is then a function of q, u, t)
    qd: list = field(default_factory=list)
    # outputs y(q, u, r, p, t) (from_kanes(..., outputs={name: expr})): NY rows
    y: sm.Matrix = field(default_factory=lambda: sm.zeros(0, 1))
    output_names: list = field(default_factory=list)    # C-safe, unique
    output_labels: list = field(default_factory=list)   # as the user named them
    # hybrid={name: gen.Impact | gen.Reset} (gen/intake/hybrid.py): HybridDecl in order
    hybrid: list = field(default_factory=list)
    # pairs (i, j) of speed indices whose equations are alike (a robot's
    # mirrored limbs: gen.intake.aba.twin_speeds): the generator computes
    # their right-hand side side by side (gen.codegen.lanes); empty when none
    twins: list = field(default_factory=list)

    # ------------------------------------------------------------------ sizes
    @property
    def a(self):
        """The acceleration-constraint term a = d(A u + b)/dq q' + d(A u +
        b)/dt (A u' + a = 0), in q' = qdot(q, u) with explicit kinematics, else
        in the symbols qd. Formed on first use (the derivative kernels, the
        symbolic references); the right-hand side's code computes it as a
        directional derivative on its own graph (gen.plan.ir.core_kernels)."""
        a = self.__dict__.get("_a")
        if a is None:
            from ..sym.graph import gradient
            if not self.mv:
                a = sm.zeros(0, 1)
            else:
                fv = self.A * sm.Matrix(self.u) + self.b
                qdot = list(self.qdot) if self.qdot is not None else list(self.qd)
                rows = []
                for e in fv:
                    # one reverse sweep per row (a symbolic Jacobian of A u + b
                    # walks each row once per coordinate)
                    g = gradient(e, set(self.q) | {self.t})
                    rows.append(sm.Add(*[g[x] * v for x, v in zip(self.q, qdot) if x in g])
                                + g.get(self.t, sm.S.Zero))
                a = sm.Matrix(rows)
            self.__dict__["_a"] = a
        return a

    # sizes (C: <P>_NQ, ...), each one expression of the model's fields
    nq = _size(lambda m: len(m.q), doc="Number of generalized coordinates q.")
    nu = _size(lambda m: len(m.u), doc="Number of generalized speeds u.")
    nx = _size(lambda m: m.nq + m.nu, doc="Size of the state x = [q, u].")
    ny = _size(lambda m: m.y.shape[0], doc="Number of outputs.")
    na = _size(lambda m: 0 if m.aux_F is None else m.aux_F.shape[0],
               doc="Number of auxiliary speeds (= reaction forces).")
    nr = _size(lambda m: len(m.r), doc="Number of inputs r.")
    np = _size(lambda m: len(m.p), doc="Number of constants p.")
    mc = _size(lambda m: m.fc.shape[0],
               doc="Number of configuration constraints f_c(q) = 0 (dependent coordinates).")
    mv = _size(lambda m: m.A.shape[0],
               doc="Number of velocity constraints A u + b = 0 (multipliers).")
    ns = _size(lambda m: m.nq - m.mc + m.nu - m.mv,
               doc="Size of the independent state [q_ind, u_ind] (linearization).")

    @property
    def independent_state_names(self):
        """The names of the independent state [q_ind, u_ind], the state of ``linearize``."""
        return ([self.state_names[i] for i in self.q_ind]
                + [self.state_names[self.nq + i] for i in self.u_ind])

    def fingerprint(self) -> str:
        """A hash of everything generation depends on.

        Returns
        -------
        str
            Hex digest; equal models give equal fingerprints.
        """
        h = hashlib.sha256()
        parts = [self.name, self.method, repr(self.q_ind), repr(self.q_dep),
                 repr(self.u_ind), repr(self.u_dep), repr(self.state_names),
                 repr(self.input_names), repr(self.constant_names)]
        sub = {s: sm.Symbol(f"_q{i}") for i, s in enumerate(self.q)}
        sub.update({s: sm.Symbol(f"_u{i}") for i, s in enumerate(self.u)})
        sub.update({s: sm.Symbol(f"_r{i}") for i, s in enumerate(self.r)})
        sub.update({s: sm.Symbol(f"_p{i}") for i, s in enumerate(self.p)})
        sub[self.t] = sm.Symbol("_t")
        sub.update({s: sm.Symbol(f"_qd{i}") for i, s in enumerate(self.qd)})
        # (a follows from A, b and the kinematics)
        for mat in (self.Kqd, self.Ku, self.kf, self.M, self.f, self.A, self.b, self.fc):
            parts.append(graph_srepr(mat, sub))
        if self.energy is not None:
            parts.append(sm.srepr(self.energy.xreplace(sub)))
        if self.ny:
            parts += [repr(self.output_names), sm.srepr(self.y.xreplace(sub))]
        if self.na:
            sub.update({s: sm.Symbol(f"_ud{i}") for i, s in enumerate(self.ud)})
            parts += [repr(self.auxiliary_names), sm.srepr(self.aux_F.xreplace(sub)),
                      sm.srepr(self.aux_g.xreplace(sub))]
            if self.aux_G is not None:
                parts += ["coupled", sm.srepr(self.aux_G.xreplace(sub))]
        for d in self.hybrid:
            xm = None if d.xmap is None else [sm.srepr(e.xreplace(sub)) for e in d.xmap]
            parts.append(repr((d.name, d.kind, sm.srepr(d.expr.xreplace(sub)), d.restitution,
                               d.direction, d.rest_speed, xm)))
        for part in parts:
            h.update(part.encode())
            h.update(b"\0")
        return h.hexdigest()

    # ------------------------------------------------------------ builders
    @classmethod
    @shared_doc
    def from_kanes(cls, km, constants=None, inputs=None, name="model",
                   energy=None, reactions=None, outputs=None, hybrid=None,
                   eliminate_reactions=True):
        """Build from a ``KanesMethod`` after ``kanes_equations``.

        Parameters
        ----------
        km : KanesMethod, sympy System, JointsMethod or PyDy System
            The formed equations of motion. A sympy ``System`` or
            ``JointsMethod`` after ``form_eoms()`` with the Kane backend, or a
            PyDy ``System`` (whose ``constants`` and ``specifieds`` give
            constants and inputs when these are None), go in too; see
            :meth:`from_system`.
        constants : dict, optional
            ``{symbol: value}`` for every parameter, finite real numbers (a
            constant that appears in no expression gives a
            :class:`gen.UnusedConstantWarning`).
        inputs : list, optional
            Symbols or functions of time that are the inputs r, in this order.
        .. shared:: name energy
        reactions : list, optional
            With ``u_auxiliary``: the unknown reaction forces (functions of time),
            in the order wanted; by default found in ``km.auxiliary_eqs`` and
            ordered by name. When the auxiliary equations hold no unknown force
            (every force along the auxiliary directions is a declared input or
            constant), the model is built all the same and
            ``sim.auxiliary_forces`` gives, for each auxiliary speed (named
            after it), the generalized force that direction still needs to
            keep its speed zero, minus the value of its auxiliary equation
            (Kane's Fr + Fr*) at the declared inputs: zero when they are the
            forces the auxiliary direction carries, and with the declared
            force along it at zero, the reaction itself (the number the model
            with that force left unknown gives). Reactions that enter the
            motion (friction ``-mu*N``) are eliminated exactly when their
            auxiliary coefficients are constant, else solved with u' at run
            time, one linear system per evaluation (:doc:`/guides/model`).
        eliminate_reactions : bool, optional
            True (the default): reactions inside the motion whose auxiliary
            coefficients are constant and regular, and whose share of the
            motion leaves the matrix of u' free of the speeds, are eliminated
            symbolically (exact; M stays a matrix of q alone). False: every
            reaction inside the motion is solved with u' at run time (the
            coupled solve, ``model.aux_G``), eliminable or not: the same
            numbers, by another route (``bench/bench_reactions.py`` compares
            the two).
        .. shared:: outputs hybrid

        .. shared:: returns

        Raises
        ------
        gen.ModelError
            When the model cannot be generated correctly as given: a free symbol
            that is neither a coordinate, a speed, an input nor a constant, a
            non-finite constant, a bad name or partition, an expression the
            generator cannot print (the message names the culprit).
        """
        validate_name(name)
        km, constants, inputs = kane_of(km, constants, inputs)
        eqs = kane_equations(km, inputs, reactions, eliminate_reactions)
        return finish(cls, eqs, name=name, constants=constants, inputs=inputs, energy=energy,
                      outputs=outputs, hybrid=hybrid)

    @classmethod
    @shared_doc
    def from_lagrange(cls, lm, q_ind=None, qd_ind=None, q_dep=None, qd_dep=None,
                      constants=None, inputs=None, name="model", energy=None, outputs=None,
                      hybrid=None):
        """Build from a ``LagrangesMethod`` after ``form_lagranges_equations``.

        The state is x = [q, q'] in the method's coordinate order.

        Parameters
        ----------
        lm : LagrangesMethod, sympy System or JointsMethod
            The formed equations of motion (a ``System`` or ``JointsMethod``
            after ``form_eoms(LagrangesMethod)`` goes in too).
        q_ind, q_dep : list, optional
            The partition of the coordinates, as for sympy's
            ``LagrangesMethod.linearize`` (:doc:`/guides/partitions`); with a
            System and no partition, the System's own.
        qd_ind, qd_dep : list, optional
            Their derivatives (with a System: its u_ind/u_dep when they are the
            coordinate derivatives, else q_ind'/q_dep').
        constants : dict, optional
            ``{symbol: value}`` for every parameter, finite real numbers (a
            constant that appears in no expression gives a
            :class:`gen.UnusedConstantWarning`).
        inputs : list, optional
            Symbols or functions of time that are the inputs r, in this order.
        .. shared:: name energy outputs hybrid

        .. shared:: returns

        Raises
        ------
        gen.ModelError
            When the model cannot be generated correctly as given: a free symbol
            that is neither a coordinate, a speed, an input nor a constant, a
            non-finite constant, a bad name or partition, an expression the
            generator cannot print (the message names the culprit).
        """
        validate_name(name)
        part = dict(q_ind=q_ind, q_dep=q_dep, qd_ind=qd_ind, qd_dep=qd_dep)
        lm, part, constants, inputs = lagrange_of(lm, part, constants, inputs)
        eqs = lagrange_equations(lm, **part)
        return finish(cls, eqs, name=name, constants=constants, inputs=inputs, energy=energy,
                      outputs=outputs, hybrid=hybrid)

    @classmethod
    @shared_doc
    def from_system(cls, obj, constants=None, inputs=None, name="model", energy=None,
                    outputs=None, formulation="kane", hybrid=None, **partition):
        """Build from whatever holds formed equations of motion.

        Dispatches to :meth:`from_kanes` or :meth:`from_lagrange` on the formed
        method; with ``formulation="recursive"``, forms the equations of a sympy
        System's joint tree itself (:mod:`gen.intake.recursive`).

        Parameters
        ----------
        obj : KanesMethod, LagrangesMethod, sympy System, JointsMethod or PyDy System
            After ``kanes_equations`` / ``form_lagranges_equations`` /
            ``form_eoms()`` (either backend).
        constants : dict, optional
            As for :meth:`from_kanes`; for a PyDy System, None takes its
            ``constants`` dict.
        inputs : list, optional
            As for :meth:`from_kanes`; for a PyDy System, None takes its specified
            quantities.
        .. shared:: name energy outputs hybrid
        formulation : {"kane", "recursive", "crba"}, optional
            ``"kane"``: the equations the method formed (``form_eoms()`` first).
            ``"recursive"``: a sympy System's joint tree, its equations formed
            here (no ``form_eoms()`` needed, none called), the System's kdes as
            the kinematics (:mod:`gen.intake.recursive`; trees of rigid bodies and
            sympy's joints). An open tree (no constraints, no ``hybrid``): u' by
            the articulated body algorithm, the model's mass matrix the identity
            and its forcing u' (``sim.mass_matrix`` is I); with constraints or
            ``hybrid``: the mass matrix by the composite rigid body algorithm,
            the forcing by recursive Newton-Euler. ``"crba"``: the same tree,
            always by CRBA + RNEA, for the physical mass matrix and forcing
            (``sim.mass_matrix`` is M; a slower build and rhs from n ~ 20).
        **partition
            The further keywords of the builder: q_ind, q_dep, qd_ind, qd_dep for
            Lagrange models (a sympy System's own partition is the default), those
            of :meth:`from_kanes` for Kane models (reactions,
            eliminate_reactions).

        .. shared:: returns

        Raises
        ------
        gen.ModelError
            As :meth:`from_kanes`; also for a System whose ``form_eoms()`` was not
            called (or whose equations were reset by a later change): eomgen never
            forms the equations itself.
        """
        options = dict(constants=constants, inputs=inputs, name=name, energy=energy,
                       outputs=outputs, hybrid=hybrid)
        if formulation in ("recursive", "crba"):
            return recursive_model(cls, obj, formulation, partition, **options)
        if formulation != "kane":
            raise ModelError(f"formulation={formulation!r} for Model.from_system: "
                             "accepted are 'kane', 'recursive' and 'crba'")
        return builder_of(cls, obj, partition)(obj, **options, **partition)

    # ---- robots from their files (gen.intake.robots) ----
    @classmethod
    def from_urdf(cls, source, base="fixed", formulation="recursive", constants="numeric",
                  name=None, hybrid=None, inputs="torques", mimic="constraints", gravity=None):
        """Build from a URDF file: its bodies and joints as a sympy System
        (``gen.load_urdf(...).system``), then :meth:`from_system`.

        Parameters
        ----------
        source : str or path
            A file path, or the URDF's XML itself.
        base : {"fixed", "floating"}, optional
            ``"floating"``: the root link on a free joint ``base``, coordinates
            ``base_x, base_y, base_z, base_qx, base_qy, base_qz, base_qw``
            (position, quaternion scalar last) and speeds ``base_vx ... base_wz``
            (body axes), as Pinocchio's free flyer (docs/guides/robots.md).
        formulation : {"recursive", "crba", "kane"}, optional
            As for :meth:`from_system` (``"kane"`` forms the System's equations
            first: small robots only).
        constants : {"numeric", "symbolic"}, optional
            ``"symbolic"``: each link's mass ``m_<link>``, centre of mass
            ``c_<link>_x/y/z`` and inertia ``I_<link>_xx ... _zz`` as run-time
            constants, valued from the file.
        name : str, optional
            The model's C prefix; made from the robot's name by default.
        hybrid : None, "limits" or dict, optional
            ``"limits"``: the joint limits as impacts (``gen.Impact``, named
            ``<joint>_lower`` and ``<joint>_upper``); a dict as for
            :meth:`from_system`.
        inputs : "torques", None or list of joint names, optional
            A torque ``tau_<joint>`` (a force for a prismatic joint) for each
            one-dof joint, for none, or for those named.
        mimic : {"constraints", "ignore"}, optional
            Mimic joints as holonomic constraints (dependent coordinates, last),
            or as independent joints (Pinocchio's default).
        gravity : 3 numbers, optional
            In the world's axes; ``(0, 0, -9.81)`` by default.

        Returns
        -------
        Model
            The state ``[q, u]``: the joints in the order of Pinocchio's
            ``buildModelFromUrdf``, ``q_<joint>`` and ``u_<joint>`` (an angle for
            a continuous joint).

        Raises
        ------
        gen.ModelError
            Malformed XML (its line), a kinematic loop, an unknown joint type,
            a moving joint over a massless subtree, naming the link or joint
            and its line.
        gen.MissingDependencyError
            Without yourdfpy (``pip install eomgen[robots]``).
        """
        from .robots import load_urdf
        robot = load_urdf(source, base=base, constants=constants, mimic=mimic,
                          gravity=gravity, inputs=inputs)
        return cls.from_system(robot.system, **robot.model_options(formulation, name, hybrid))

    @classmethod
    def from_mjcf(cls, source, base=None, formulation="recursive", constants="numeric",
                  name=None, hybrid=None, inputs="torques", gravity=None):
        """Build from an MJCF file compiled by MuJoCo (its defaults, classes
        and includes resolved by MuJoCo's own compiler): its bodies and
        joints as a sympy System (``gen.load_mjcf(...).system``), then
        :meth:`from_system`. The state follows MuJoCo's joint order; a free
        joint and a ball joint hold a quaternion scalar last (MuJoCo's is
        scalar first) and body-axes speeds (docs/guides/robots.md). The
        rigid-body dynamics only: contacts, joint damping, armature, springs,
        actuators, tendons and equality constraints are not modelled.

        Parameters
        ----------
        source : str or path
            A file path, or the MJCF's XML itself.
        base : {None, "fixed", "floating"}, optional
            ``None``: the file's joints (a body with a ``<freejoint/>`` is
            floating). ``"fixed"``: every free joint welded, its body where
            the file places it (``pos``, ``quat``), as if the
            ``<freejoint/>`` were removed. ``"floating"``: every body of the
            world without a joint gets a free joint ``base`` (``<body>_base``
            when several do; coordinates and speeds as :meth:`from_urdf`'s),
            as if it had a ``<freejoint/>``; a free body stays free, a body of
            the world on another joint is refused.
        formulation, constants, name, hybrid, inputs
            As for :meth:`from_urdf` (``hybrid="limits"``: the joints' ranges
            where MuJoCo limits them); there is no ``mimic`` (MJCF has no
            mimic joints; its joint equality constraints are not modelled).
        gravity : 3 numbers, optional
            The file's ``<option gravity>`` by default.

        Returns
        -------
        Model

        Raises
        ------
        gen.ModelError
            What MuJoCo's compiler refuses (its message and line), or a moving
            joint over a massless subtree.
        gen.MissingDependencyError
            Without mujoco (``pip install eomgen[robots]``).
        """
        from .robots import load_mjcf
        robot = load_mjcf(source, base=base, constants=constants, gravity=gravity,
                          inputs=inputs)
        return cls.from_system(robot.system, **robot.model_options(formulation, name, hybrid))

    # ---- from matrices (gen.pydy: PyDy's forms; any M, f and kinematics) ----
    @classmethod
    @shared_doc
    def from_matrices(cls, mass_matrix, forcing, coordinates, speeds, kinematics,
                      constants=None, inputs=None, name="model", energy=None, outputs=None,
                      hybrid=None, _constraints=None):
        """Build from the equations themselves, without a formed method.

        ``mass_matrix * speeds' = forcing``, with the kinematic equations
        ``kinematics = 0`` (as ``KanesMethod``'s ``kd_eqs``: linear in the
        coordinate derivatives and in the speeds, one row per coordinate).
        No constraints: the speeds are all independent.

        Parameters
        ----------
        mass_matrix : sympy Matrix, shape (nu, nu)
            M(q, t); it must not depend on the speeds or the inputs.
        forcing : sympy Matrix, shape (nu, 1)
            f(q, u, r, t).
        coordinates, speeds : list
            The coordinates q and speeds u (functions of time), in the order of
            the kinematic rows and of the mass matrix's rows and columns.
        kinematics : sympy Matrix, shape (nq, 1)
            Expressions that vanish, ``q' - G(q, u)`` for explicit kinematics.
        constants, inputs, name, energy, outputs, hybrid
            As for :meth:`from_kanes`.
        _constraints : tuple, optional
            Internal (``gen.intake.recursive``): a System's constraints as
            ``(fc, A, b, nq_dep, nu_dep)``, the dependent coordinates and speeds
            last; not for users.

        .. shared:: returns

        Raises
        ------
        gen.ModelError
            As :meth:`from_kanes`; also when a shape does not match or the
            kinematics are not linear in q' and u (the row is named).
        """
        validate_name(name)
        eqs = matrices_equations(mass_matrix, forcing, coordinates, speeds, kinematics,
                                 _constraints)
        return finish(cls, eqs, name=name, constants=constants, inputs=inputs, energy=energy,
                      outputs=outputs, hybrid=hybrid)


def require_model(obj, caller):
    """obj itself when it is a gen.Model; otherwise a ModelError that says
    what was given and, for a sympy mechanics object, the constructor to
    call first (gen.compile(km) used to fail with "AttributeError: ... has
    no attribute 'M'")."""
    if isinstance(obj, Model):
        return obj
    kind = type(obj).__name__
    for name, ctor in CONSTRUCTORS:
        cls = getattr(me, name, None)
        if (cls is not None and isinstance(obj, cls)) or (name == "System"
                                                          and is_pydy_system(obj)):
            raise ModelError(
                f"{caller} takes a gen.Model, got a sympy {kind}: make the model first with "
                f"{ctor}, then {caller}(model, ...)")
    raise ModelError(f"{caller} takes a gen.Model (from gen.Model.from_kanes, from_lagrange "
                     f"or from_system), got {kind}")
