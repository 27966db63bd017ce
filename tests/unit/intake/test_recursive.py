"""Issue 37: Model.from_system(system, formulation="recursive") forms the
equations of a sympy System's joint tree itself (gen.recursive: ABA for an
open tree, CRBA + RNEA with constraints; both checked).

Reference: sympy's own System.form_eoms() (Kane) on an identical System built
separately, its mass_matrix_full / forcing_full lambdified and solved with
numpy at random states; the linearization from lambdified symbolic Jacobians
of the same (A = M^-1 (dF/dx - dM/dx x')). Every comparison is to 1e-12."""
import os
import threading
import time

import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me

import gen

T = me.dynamicsymbols._t
TOL = 1e-12
# the generic trees hold constants some cases do not use (a slider's inertia),
# and sympy warns on its own velocity-path choice for the joint points
pytestmark = [pytest.mark.filterwarnings("ignore::gen.UnusedConstantWarning"),
              pytest.mark.filterwarnings("ignore::gen.UnusedInputWarning"),
              pytest.mark.filterwarnings("ignore:\\s*Velocity of:UserWarning")]


def _tree(spec, name="t", gravity=True, loads=True, actuator=True):
    """A System of len(spec) rigid bodies: spec[i] = (parent index or -1 for
    the ground, joint class name, axis name 'x'|'y'|'z'|'xz'). Every body has
    a full inertia tensor, offset joint points, and (loads=True) a force at its
    joint's child point, a torque on its frame; (actuator=True) a torque
    actuator on the first joint driven by the input T0."""
    ground = me.RigidBody("G")
    N = ground.frame
    system = me.System.from_newtonian(ground)
    g = sm.Symbol("g")
    consts = {g: 9.81}
    rng = np.random.default_rng(len(spec) * 7 + 3)
    bodies, inputs = [], []
    for i, (par, kind, ax) in enumerate(spec):
        m, l, d, c = sm.symbols(f"m{i} l{i} d{i} c{i}")
        Ixx, Iyy, Izz, Ixy, Iyz, Izx = sm.symbols(f"Ixx{i} Iyy{i} Izz{i} Ixy{i} Iyz{i} Izx{i}")
        B = me.ReferenceFrame(f"B{i}")
        mc = me.Point(f"mc{i}")
        body = me.RigidBody(f"b{i}", masscenter=mc, frame=B, mass=m,
                            inertia=(me.inertia(B, Ixx, Iyy, Izz, Ixy, Iyz, Izx), mc))
        a = rng.uniform(-0.3, 0.3, (3, 3))
        Iv = a @ a.T + np.diag(rng.uniform(0.5, 1.5, 3))
        consts.update({m: rng.uniform(0.5, 2.0), l: rng.uniform(0.5, 1.5),
                       d: rng.uniform(-0.3, 0.3), c: rng.uniform(-1, 1),
                       Ixx: Iv[0, 0], Iyy: Iv[1, 1], Izz: Iv[2, 2], Ixy: Iv[0, 1],
                       Iyz: Iv[1, 2], Izx: Iv[2, 0]})
        parent = ground if par < 0 else bodies[par]
        P = parent.frame
        axis = {"x": P.x, "y": P.y, "z": P.z, "xz": (P.x + P.z) / sm.sqrt(2)}[ax]
        ppt = parent.masscenter.locatenew(f"P{i}", l * P.x + d * P.y)
        cpt = body.masscenter.locatenew(f"C{i}", -l / 2 * B.x + d * B.z)
        if kind == "pin":
            q, u = me.dynamicsymbols(f"q{i} u{i}")
            j = me.PinJoint(f"J{i}", parent, body, q, u, ppt, cpt, joint_axis=axis)
        elif kind == "prismatic":
            q, u = me.dynamicsymbols(f"q{i} u{i}")
            j = me.PrismaticJoint(f"J{i}", parent, body, q, u, ppt, cpt, joint_axis=axis)
        elif kind == "cylindrical":
            q, u, q2, u2 = me.dynamicsymbols(f"q{i} u{i} qt{i} ut{i}")
            j = me.CylindricalJoint(f"J{i}", parent, body, rotation_coordinate=q,
                                    translation_coordinate=q2, rotation_speed=u,
                                    translation_speed=u2, parent_point=ppt,
                                    child_point=cpt, joint_axis=axis)
        elif kind == "planar":
            q, u = me.dynamicsymbols(f"q{i} u{i}")
            qa, qb, ua, ub = me.dynamicsymbols(f"qa{i} qb{i} ua{i} ub{i}")
            j = me.PlanarJoint(f"J{i}", parent, body, rotation_coordinate=q,
                               planar_coordinates=[qa, qb], rotation_speed=u,
                               planar_speeds=[ua, ub], parent_point=ppt, child_point=cpt)
        elif kind == "spherical":
            q, qb, qc = me.dynamicsymbols(f"q{i} qb{i} qc{i}")
            u, ub, uc = me.dynamicsymbols(f"u{i} ub{i} uc{i}")
            j = me.SphericalJoint(f"J{i}", parent, body, coordinates=[q, qb, qc],
                                  speeds=[u, ub, uc], parent_point=ppt, child_point=cpt)
        elif kind == "weld":
            q = u = sm.S.Zero
            j = me.WeldJoint(f"J{i}", parent, body, parent_point=ppt, child_point=cpt)
        else:
            raise AssertionError(kind)
        system.add_joints(j)
        bodies.append(body)
        if loads:
            system.add_loads(me.Force(j.child_point, c * N.x + c * u * B.y),
                             me.Torque(B, c * q * B.z + c / 3 * N.y))
    if gravity:
        system.apply_uniform_gravity(-g * N.y)
    if actuator:
        r0 = me.dynamicsymbols("T0")
        inputs.append(r0)
        system.add_actuators(me.TorqueActuator(r0, bodies[0].frame.z, bodies[0], ground))
    return system, consts, inputs


CASES = {
    "pend1": [(-1, "pin", "z")],
    "pend3": [(-1, "pin", "z"), (0, "pin", "z"), (1, "pin", "z")],
    "slider1": [(-1, "prismatic", "x")],
    "cartpole": [(-1, "prismatic", "x"), (0, "pin", "z")],
    "chain3d4": [(-1, "pin", "y"), (0, "pin", "x"), (1, "prismatic", "xz"), (2, "pin", "z")],
    "tree5": [(-1, "pin", "z"), (0, "pin", "x"), (0, "prismatic", "y"), (1, "pin", "xz"),
              (2, "pin", "y")],
    "cylinder2": [(-1, "cylindrical", "z"), (0, "pin", "x")],
    "planar2": [(-1, "planar", "x"), (0, "pin", "y")],
    "spherical2": [(-1, "spherical", "x"), (0, "pin", "z")],
    "weld3": [(-1, "pin", "z"), (0, "weld", "x"), (1, "prismatic", "y")],
    "mixed5": [(-1, "spherical", "x"), (0, "cylindrical", "y"), (0, "weld", "z"),
               (2, "planar", "x"), (1, "prismatic", "xz")],
    "tree6": [(-1, "prismatic", "z"), (0, "pin", "y"), (1, "pin", "x"), (1, "pin", "z"),
              (3, "prismatic", "x"), (0, "pin", "xz")],
    # 10 bodies: a chain (parallel pins and a slider at its end: sympy's own
    # form_eoms of a 10-deep 3D chain, the reference, takes far too long)
    # and a shallow tree holding every joint type
    "chain10": [(-1, "pin", "z")] + [(i, "pin", "z") for i in range(8)]
               + [(8, "prismatic", "x")],
    "tree10": [(-1, "pin", "z"), (0, "spherical", "x"), (0, "prismatic", "y"),
               (0, "cylindrical", "x"), (0, "planar", "x"), (0, "weld", "z"), (5, "pin", "x"),
               (1, "pin", "xz"), (2, "pin", "y"), (3, "prismatic", "z")],
}


class _Ref:
    """sympy's form_eoms solution of the same System, evaluated with numpy."""

    def __init__(self, spec, with_jac):
        system, consts, inputs = _tree(spec)
        system.form_eoms()
        self.x = list(system.q) + list(system.u)
        Mf, Ff = system.mass_matrix_full, system.forcing_full
        self.p = list(consts)
        self.pv = [consts[s] for s in self.p]
        xs = sm.symbols(f"x:{len(self.x)}")
        rs = sm.symbols(f"r:{len(inputs)}")
        sub = dict(zip(self.x, xs)) | dict(zip(inputs, rs))
        Mf, Ff = Mf.xreplace(sub), Ff.xreplace(sub)
        args = (xs, rs, self.p)
        self._M = sm.lambdify(args, Mf, "numpy")
        self._F = sm.lambdify(args, Ff, "numpy")
        if with_jac:
            self._dF = sm.lambdify(args, Ff.jacobian(list(xs) + list(rs)), "numpy")
            self._dM = [sm.lambdify(args, Mf.diff(s), "numpy") for s in xs]
        self.nq = len(system.q)

    def rhs(self, x, r):
        return np.linalg.solve(self._M(x, r, self.pv), self._F(x, r, self.pv).ravel())

    def mass(self, x):
        n = self.nq
        return np.asarray(self._M(x, [0.0], self.pv), float)[n:, n:]

    def linear(self, x, r):
        Mv = np.asarray(self._M(x, r, self.pv), float)
        xd = np.linalg.solve(Mv, self._F(x, r, self.pv).ravel())
        J = np.asarray(self._dF(x, r, self.pv), float)
        nx = len(x)
        for k in range(nx):
            J[:, k] -= np.asarray(self._dM[k](x, r, self.pv), float) @ xd
        AB = np.linalg.solve(Mv, J)
        return AB[:, :nx], AB[:, nx:]


def _compile(spec, name):
    system, consts, inputs = _tree(spec)
    model = gen.Model.from_system(system, constants=consts, inputs=inputs, name=name,
                                  formulation="recursive")
    return model, gen.compile(model)


def _compile_crba(spec, name, **kw):
    """The same tree by CRBA + RNEA (formulation="crba": the physical
    M u' = f; "recursive" takes ABA for an open tree)."""
    system, consts, inputs = _tree(spec, **kw)
    model = gen.Model.from_system(system, constants=consts, inputs=inputs, name=name,
                                  formulation="crba")
    return model, gen.compile(model)


# the larger trees (each > 8 s: sympy's form_eoms reference dominates) run in the
# slow tier; pin, prismatic and weld joints keep a case in the fast one, the
# cylindrical, planar and spherical joints are in the slow one
SLOW_CASES = {"tree5", "spherical2", "chain3d4", "mixed5", "tree6", "planar2", "cylinder2",
              "chain10", "tree10"}


@pytest.mark.parametrize("case", [pytest.param(c, marks=pytest.mark.slow) if c in SLOW_CASES
                                  else c for c in sorted(CASES)])
def test_rhs_and_mass_matrix_match_form_eoms(case):
    """ABA (from_system's choice for an open tree: M = I, f = u') and CRBA +
    RNEA (equations_of_tree: the physical M and f) against form_eoms."""
    spec = CASES[case]
    model, sim = _compile(spec, f"rec_{case}")
    cmodel, csim = _compile_crba(spec, f"crba_{case}")
    ref = _Ref(spec, with_jac=model.nq <= 5)
    nq = model.nq
    assert model.nu == nq and nq == ref.nq
    assert [str(s) for s in model.q_orig + model.u_orig] == [str(s) for s in ref.x]
    assert model.M == sm.eye(nq)
    rng = np.random.default_rng(1)
    for _ in range(5):
        x = rng.uniform(-1.5, 1.5, 2 * nq)
        r = rng.uniform(-1, 1, 1)
        want = ref.rhs(x, r)
        for s_ in (sim, csim):
            got = s_.rhs(0.0, x, r=r)
            assert np.max(np.abs(got - want)) <= TOL * max(1.0, np.max(np.abs(want))), (got, want)
        assert np.array_equal(sim.mass_matrix(x[:nq]), np.eye(nq))
        Mw = ref.mass(x)
        Mg = csim.mass_matrix(x[:nq])
        assert np.max(np.abs(Mg - Mw)) <= TOL * max(1.0, np.max(np.abs(Mw)))
        if nq <= 5:
            A, B = sim.linearize(x, r=r)
            Aw, Bw = ref.linear(x, r)
            scale = max(1.0, np.max(np.abs(Aw)))
            assert np.max(np.abs(A - Aw)) <= 1e-10 * scale, np.max(np.abs(A - Aw))
            assert np.max(np.abs(B - Bw)) <= 1e-10 * scale


def test_parameters_stay_run_time_constants():
    spec = CASES["cartpole"]
    model, sim = _compile(spec, "rec_cartpole")
    ref = _Ref(spec, with_jac=False)
    names = [str(s) for s in model.p_orig]
    rng = np.random.default_rng(5)
    pv = np.array(ref.pv) * rng.uniform(0.8, 1.2, len(ref.pv))
    order = [names.index(str(s)) for s in ref.p]
    p = np.empty(len(names))
    p[order] = pv
    ref.pv = list(pv)
    x = rng.uniform(-1, 1, 4)
    want = ref.rhs(x, [0.3])
    got = sim.rhs(0.0, x, r=[0.3], p=p)
    assert np.max(np.abs(got - want)) <= TOL * max(1.0, np.max(np.abs(want)))


def test_kane_stays_default():
    system, consts, inputs = _tree(CASES["pend1"])
    with pytest.raises(gen.ModelError, match="form_eoms"):
        gen.Model.from_system(system, constants=consts, inputs=inputs)
    system.form_eoms()
    m = gen.Model.from_system(system, constants=consts, inputs=inputs)
    ref = gen.Model.from_system(system, constants=consts, inputs=inputs, formulation="kane")
    assert m.fingerprint() == ref.fingerprint()
    with pytest.raises(gen.ModelError, match="formulation='newton'"):
        gen.Model.from_system(system, formulation="newton")


def test_recursive_never_forms_equations(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("called")
    monkeypatch.setattr(me.KanesMethod, "kanes_equations", boom)
    monkeypatch.setattr(me.System, "form_eoms", boom)
    system, consts, inputs = _tree(CASES["tree5"])
    model = gen.Model.from_system(system, constants=consts, inputs=inputs,
                                  formulation="recursive")
    assert model.nu == 5


# ---------------------------------------------------------------- bad input
def test_unsupported_joint_names_it():
    class OddJoint(me.PinJoint):
        pass
    ground = me.RigidBody("G")
    system = me.System.from_newtonian(ground)
    b = me.RigidBody("b")
    q, u = me.dynamicsymbols("q u")
    system.add_joints(OddJoint("odd", ground, b, q, u))
    with pytest.raises(gen.ModelError, match="joint 'odd' is a OddJoint"):
        gen.Model.from_system(system, formulation="recursive")


def test_body_not_connected_names_it():
    system, consts, inputs = _tree(CASES["pend1"], actuator=False)
    system.add_bodies(me.RigidBody("floater"))
    with pytest.raises(gen.ModelError, match="body 'floater' is not connected"):
        gen.Model.from_system(system, constants=consts, formulation="recursive")
    # a joint hanging from a body that is nobody's child and not the ground
    ground = me.RigidBody("G")
    system = me.System.from_newtonian(ground)
    a, b = me.RigidBody("a"), me.RigidBody("b")
    q, u = me.dynamicsymbols("q u")
    system.add_joints(me.PinJoint("J", a, b, q, u))
    with pytest.raises(gen.ModelError, match="body 'a' .*not connected"):
        gen.Model.from_system(system, formulation="recursive")


def test_load_on_unknown_point_names_it():
    system, consts, inputs = _tree(CASES["pend1"], actuator=False)
    stray = me.Point("stray")
    system.add_loads(me.Force(stray, system.frame.x))
    with pytest.raises(gen.ModelError, match="point 'stray'"):
        gen.Model.from_system(system, constants=consts, formulation="recursive")


def test_constraints_need_their_dependent_coordinates():
    system, consts, inputs = _tree(CASES["pend3"], actuator=False)
    q0 = system.q[0]
    system.add_coordinates(me.dynamicsymbols("qx"), independent=False)
    system.add_holonomic_constraints(q0 - system.q[-1])
    with pytest.raises(gen.ModelError, match="1 holonomic.*0 dependent speed"):
        gen.Model.from_system(system, constants=consts, formulation="recursive")


# ----------------------------------------------------------- loop closures
def _four_bar():
    """sympy's four-bar linkage (test_four_bar_linkage_with_manual_constraints)
    as a System: three PinJoints from the fixed link, the loop closed by two
    holonomic constraints, q2, q3, u2, u3 dependent; gravity along -N.y."""
    q1, q2, q3, u1, u2, u3 = me.dynamicsymbols("q1:4, u1:4")
    l1, l2, l3, l4, rho, g = sm.symbols("l1:5, rho, g")
    link1 = me.RigidBody("Link1")
    links = [me.RigidBody(f"Link{i}", mass=rho * l) for i, l in ((2, l2), (3, l3), (4, l4))]
    for b, l in zip(links, (l2, l3, l4)):
        b.inertia = (me.inertia(b.frame, 0, 0, rho * l ** 3 / 12), b.masscenter)
    link2, link3, link4 = links
    system = me.System.from_newtonian(link1)
    system.add_joints(
        me.PinJoint("J1", link1, link2, coordinates=q1, speeds=u1, joint_axis=link1.z,
                    parent_point=l1 / 2 * link1.x, child_point=-l2 / 2 * link2.x),
        me.PinJoint("J2", link2, link3, coordinates=q2, speeds=u2, joint_axis=link2.z,
                    parent_point=l2 / 2 * link2.x, child_point=-l3 / 2 * link3.x),
        me.PinJoint("J3", link3, link4, coordinates=q3, speeds=u3, joint_axis=link3.z,
                    parent_point=l3 / 2 * link3.x, child_point=-l4 / 2 * link4.x))
    system.q_ind, system.q_dep = [q1], [q2, q3]
    system.u_ind, system.u_dep = [u1], [u2, u3]
    loop = link4.masscenter.pos_from(link1.masscenter) + l1 / 2 * link1.x + l4 / 2 * link4.x
    system.add_holonomic_constraints(loop.dot(link1.x), loop.dot(link1.y))
    system.apply_uniform_gravity(-g * link1.frame.y)
    consts = {l1: 0.13, l2: 0.24, l3: 0.21, l4: 0.34, rho: 997.0, g: 9.81}
    return system, consts


@pytest.mark.slow
def test_four_bar_loop_closure_matches_form_eoms():
    """The loop goes through the runtime's constraint machinery (dependent
    coordinates and speeds, the partitioned solve, projection): rhs against
    sympy's form_eoms (mass_matrix_full with the velocity-constraint rows,
    solved with numpy) at consistent states, to 1e-12; the constraints and
    the energy kept over a simulation."""
    system, consts = _four_bar()
    model = gen.Model.from_system(system, constants=consts, name="rec_fourbar",
                                  formulation="recursive")
    assert (model.nq, model.nu, model.mc, model.mv) == (3, 3, 2, 2)
    sim = gen.compile(model)
    ref, rconsts = _four_bar()
    ref.form_eoms()
    xs = sm.symbols("x:6")
    sub = dict(zip(list(ref.q) + list(ref.u), xs))
    Mf = sm.lambdify([xs], ref.mass_matrix_full.xreplace(sub).xreplace(rconsts), "numpy")
    Ff = sm.lambdify([xs], ref.forcing_full.xreplace(sub).xreplace(rconsts), "numpy")
    # sympy's test state (q and u on the loop), then others made consistent
    x0 = np.array([2.1, 0.6655470375077588, 2.527408138024188,
                   0.2, -0.17963733938852067, 0.1309060540601612])
    rng = np.random.default_rng(5)
    states = [sim.consistent_state(x0, tol=1e-15)]
    for _ in range(3):
        guess = x0 + np.concatenate([rng.uniform(-0.1, 0.1, 3), rng.uniform(-1, 1, 3)])
        states.append(sim.consistent_state(guess, tol=1e-15))
    for x in states:
        assert np.max(np.abs(sim.constraints(x[:3]))) < 1e-13
        want = np.linalg.solve(Mf(x), np.asarray(Ff(x), float).ravel())
        got = sim.rhs(0.0, x)
        assert np.max(np.abs(got - want)) <= TOL * max(1.0, np.max(np.abs(want))), (got, want)
    # energy: kinetic of the three moving links + potential, from the constants
    x1 = states[1]
    t, X = sim.simulate(x1, 2.0, 0.01, method="dopri5", rtol=1e-10, atol=1e-12)
    res = np.array([sim.constraints(x[:3]) for x in X])
    assert np.max(np.abs(res)) < 1e-9
    assert np.ptp(X[:, 0]) > 0.1                  # it moved
    E = sm.lambdify([xs], _four_bar_energy(ref).xreplace(sub).xreplace(rconsts), "numpy")
    En = np.array([E(x) for x in X])
    assert np.max(np.abs(En - En[0])) <= 1e-7 * max(1.0, np.max(np.abs(En)))


def _four_bar_energy(system):
    N = system.frame
    ke = sum(b.kinetic_energy(N) for b in system.bodies if b.frame != N)
    g = sm.Symbol("g")
    pe = sum(b.mass * g * b.masscenter.pos_from(system.fixed_point).dot(N.y)
             for b in system.bodies if b.frame != N)
    return ke + pe


# ---------------------------------------------------------------- Pinocchio
def _pinocchio_model(system, consts):
    """The same tree as a Pinocchio model: joint i's frame at its parent point,
    with the parent body's axes at q = 0; the body's inertia and mass centre in
    that frame (all numbers from the System at q = 0 and the constants)."""
    try:
        import pinocchio as pin
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("Pinocchio (pip install pin) is required under CI=true")
        pytest.skip("Pinocchio not installed (pip install pin)")
    model = pin.Model()
    ids = {}
    qzero = {q: 0 for q in system.q}

    def num(mat):
        return np.array(sm.Matrix(mat).xreplace(qzero).xreplace(consts).evalf(), float)

    for j in system.joints:
        parent, child = j.parent, j.child
        E0T = num(parent.frame.dcm(child.frame))                 # parent axes <- child
        a = num(j.parent_point.pos_from(parent.masscenter).to_matrix(parent.frame)).ravel()
        rcc = num(child.masscenter.pos_from(j.child_point).to_matrix(child.frame)).ravel()
        axis = num(j.joint_axis.to_matrix(parent.frame)).ravel()
        axis /= np.linalg.norm(axis)
        if parent in ids:
            pid, pE0T, prcc = ids[parent]
            place = pin.SE3(pE0T, pE0T @ (prcc + a))
        else:
            pid, place = 0, pin.SE3(np.eye(3), a)
        jm = (pin.JointModelRevoluteUnaligned(axis) if isinstance(j, me.PinJoint)
              else pin.JointModelPrismaticUnaligned(axis))
        jid = model.addJoint(pid, jm, place, j.name)
        I = num(child.central_inertia.to_matrix(child.frame))
        model.appendBodyToJoint(jid, pin.Inertia(float(child.mass.xreplace(consts)),
                                                 E0T @ rcc, E0T @ I @ E0T.T), pin.SE3.Identity())
        ids[child] = (jid, E0T, rcc)
    model.gravity.linear = np.array([0.0, -consts[sm.Symbol("g")], 0.0])
    return pin, model


def _humanoid():
    """31 DOF: a sliding torso with five limbs of six pins, axes turning."""
    axes = ["z", "x", "y", "xz", "y", "x"]
    spec = [(-1, "prismatic", "y")]
    for limb in range(5):
        par = 0
        for k in range(6):
            spec.append((par, "pin", axes[(k + limb) % 6]))
            par = len(spec) - 1
    return spec


@pytest.mark.parametrize("which", [
    pytest.param("tree7", marks=pytest.mark.slow),
    pytest.param("humanoid31", marks=pytest.mark.slow)])
def test_pinocchio_aba_matches_rhs(which):
    spec = {"tree7": [(-1, "pin", "y"), (0, "pin", "x"), (1, "prismatic", "xz"),
                      (1, "pin", "z"), (0, "prismatic", "z"), (4, "pin", "xz"),
                      (3, "pin", "x")],
            "humanoid31": _humanoid()}[which]
    system, consts, _ = _tree(spec, loads=False, actuator=False)
    pin, pmodel = _pinocchio_model(system, consts)
    system, consts, _ = _tree(spec, loads=False, actuator=False)
    model = gen.Model.from_system(system, constants=consts, name=f"rec_{which}",
                                  formulation="recursive")
    sim = gen.compile(model)
    _, csim = _compile_crba(spec, f"crba_{which}", loads=False, actuator=False)
    data = pmodel.createData()
    n = model.nq
    assert pmodel.nq == n
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = rng.uniform(-1.5, 1.5, 2 * n)
        want = pin.aba(pmodel, data, x[:n], x[n:], np.zeros(n))
        got = sim.rhs(0.0, x)[n:]
        assert np.max(np.abs(got - want)) <= TOL * max(1.0, np.max(np.abs(want))), (got, want)
        # M's columns from Pinocchio's RNEA: tau(q, 0, e_k) - tau(q, 0, 0)
        z = np.zeros(n)
        tau0 = pin.rnea(pmodel, data, x[:n], z, z).copy()
        Mw = np.column_stack([pin.rnea(pmodel, data, x[:n], z, np.eye(n)[k]) - tau0
                              for k in range(n)])
        assert np.max(np.abs(csim.mass_matrix(x[:n]) - Mw)) <= TOL * np.max(np.abs(Mw))
        got = csim.rhs(0.0, x)[n:]
        assert np.max(np.abs(got - want)) <= TOL * max(1.0, np.max(np.abs(want))), (got, want)


def test_recursive_needs_a_system():
    system, consts, inputs = _tree(CASES["pend1"])
    system.form_eoms()
    with pytest.raises(gen.ModelError, match="needs a sympy System, got KanesMethod"):
        gen.Model.from_system(system.eom_method, formulation="recursive")
    with pytest.raises(gen.ModelError, match="q_ind.*formulation='recursive'"):
        gen.Model.from_system(system, formulation="recursive", q_ind=[])


# ------------------------------------------------------- builds in threads
def _limbs(n_limbs, depth):
    """A sliding torso with n_limbs limbs of depth pins, axes turning (the
    humanoid's shape, smaller)."""
    axes = ["z", "x", "y", "xz", "y", "x"]
    spec = [(-1, "prismatic", "y")]
    for limb in range(n_limbs):
        par = 0
        for k in range(depth):
            spec.append((par, "pin", axes[(k + limb) % 6]))
            par = len(spec) - 1
    return spec


# three different trees: two open trees by ABA, one sharing the other's
# first limb (the same symbols: a build that saw the other's opaque nodes as
# its own would compare the two graphs down their depth), and the shorter
# one by CRBA + RNEA (a physical mass matrix)
THREADED = {"thr_a": (_limbs(2, 5), "recursive"), "thr_b": (_limbs(1, 5), "recursive"),
            "thr_c": (_limbs(1, 5), "crba")}


def _threaded_build(name):
    spec, formulation = THREADED[name]
    system, consts, inputs = _tree(spec)
    return gen.Model.from_system(system, constants=consts, inputs=inputs, name=name,
                                 formulation=formulation)


def _numbers(model, rng):
    sim = gen.compile(model)
    n = model.nq
    out = []
    for _ in range(4):
        x = rng.uniform(-1.5, 1.5, 2 * n)
        out += [sim.rhs(0.0, x, r=[0.4]), sim.mass_matrix(x[:n])]
    return out


@pytest.mark.slow      # about 10 s: six builds of 6 to 11 bodies
def test_builds_in_threads_equal_builds_in_sequence():
    """Each recursive build keeps its opaque nodes in its own interner, and
    nodes of different builds never compare equal: three builds of different
    trees in three threads of one process give the same models (fingerprints,
    the expression graphs) and the same numbers, to the bit, as the same
    builds one after the other. With the interner shared by the process (and
    cleared by each build at its start and end, with sympy's cache), the two
    ABA builds compared each other's nodes down their graphs: on the code
    before issue 42 the threaded builds of these trees did not finish in 25
    minutes (the sequence takes a few seconds; with limbs of 4 pins they took
    150 s)."""
    seq = {name: _threaded_build(name) for name in THREADED}
    got, errors = {}, []
    start = threading.Barrier(len(THREADED))

    def run(name):
        try:
            start.wait()
            model = _threaded_build(name)
            got[name] = (model, model.fingerprint())    # a walk of the whole graph
        except BaseException as e:      # noqa: BLE001 - reported below
            errors.append((name, e))

    threads = [threading.Thread(target=run, args=(n,), daemon=True) for n in THREADED]
    for th in threads:
        th.start()
    deadline = time.monotonic() + 300    # a guard against a hang, not a timing: ~5 s here
    for th in threads:
        th.join(max(0.0, deadline - time.monotonic()))
    # (names and strings only in what an assertion shows: the repr of a model
    # prints its graph as a tree)
    assert not errors, [(name, repr(e)) for name, e in errors]
    missing = sorted(set(THREADED) - set(got))
    assert missing == [], ("builds (and their fingerprints) not finished in 300 s: the "
                           "threads interfere")
    for name in THREADED:
        fp, want_fp = got[name][1], seq[name].fingerprint()
        assert fp == want_fp, name
        want = _numbers(seq[name], np.random.default_rng(11))
        have = _numbers(got[name][0], np.random.default_rng(11))
        assert all(np.array_equal(a, b) for a, b in zip(have, want)), name
    # and the numbers are the tree's (ABA against CRBA + RNEA on the same tree)
    rng = np.random.default_rng(2)
    aba, crba = gen.compile(got["thr_b"][0]), gen.compile(got["thr_c"][0])
    for _ in range(3):
        x = rng.uniform(-1.5, 1.5, 2 * got["thr_b"][0].nq)
        want = crba.rhs(0.0, x, r=[0.4])
        assert np.max(np.abs(aba.rhs(0.0, x, r=[0.4]) - want)) <= TOL * max(
            1.0, np.max(np.abs(want)))


def test_a_build_leaves_sympys_cache_alone(monkeypatch):
    """The recursive build does not wipe sympy's process-wide cache (other
    threads' and the user's work live in it)."""
    import sympy.core.cache as cache

    def boom():
        raise AssertionError("sympy's cache cleared")
    monkeypatch.setattr(cache, "clear_cache", boom)
    for _ in range(2):      # the same tree twice in one process: its nodes left in the cache
        model = _threaded_build("thr_b")
    assert model.nu == 6


def _uneven_weights(spec):
    """_tree(spec) without uniform gravity: body 0 weighs m0 g along -N.y,
    body 1 nothing, the last body m g along -N.y plus a push c along N.x at
    its mass centre (world-axes loads the articulated body algorithm turns
    into each body's axes, not a base acceleration)."""
    system, consts, inputs = _tree(spec, gravity=False)
    g = next(s for s in consts if s.name == "g")
    N = system.frame
    b0, b2 = system.bodies[0], system.bodies[len(spec) - 1]
    c = next(s for s in consts if s.name == f"c{len(spec) - 1}")
    system.add_loads(me.Force(b0.masscenter, -b0.mass * g * N.y),
                     me.Force(b2.masscenter, -b2.mass * g * N.y + c * N.x))
    return system, consts, inputs


def test_aba_with_uneven_world_loads_matches_form_eoms():
    """Gravity on some bodies only (and a world push): ABA in the bodies' own
    axes takes the loads through the bodies' rotations instead of the base's
    acceleration; against sympy's form_eoms of the same System to 1e-12."""
    spec = [(-1, "pin", "y"), (0, "pin", "x"), (1, "pin", "z")]
    system, consts, inputs = _uneven_weights(spec)
    model = gen.Model.from_system(system, constants=consts, inputs=inputs, name="rec_uneven",
                                  formulation="recursive")
    assert model.M == sm.eye(3)
    sim = gen.compile(model)
    ref_sys, _, ref_in = _uneven_weights(spec)
    ref_sys.form_eoms()
    x_s = list(ref_sys.q) + list(ref_sys.u)
    assert [str(s) for s in model.q_orig + model.u_orig] == [str(s) for s in x_s]
    xs, rs, p = sm.symbols("x:6"), sm.symbols("r:1"), list(consts)
    sub = dict(zip(x_s, xs)) | dict(zip(ref_in, rs))
    Mf = sm.lambdify((xs, rs, p), ref_sys.mass_matrix_full.xreplace(sub), "numpy")
    Ff = sm.lambdify((xs, rs, p), ref_sys.forcing_full.xreplace(sub), "numpy")
    pv = [consts[s] for s in p]
    rng = np.random.default_rng(3)
    for _ in range(3):
        x, r = rng.uniform(-1.5, 1.5, 6), rng.uniform(-1, 1, 1)
        want = np.linalg.solve(Mf(x, r, pv), Ff(x, r, pv).ravel())
        got = sim.rhs(0.0, x, r=r)
        assert np.max(np.abs(got - want)) <= TOL * max(1.0, np.max(np.abs(want))), (got, want)
