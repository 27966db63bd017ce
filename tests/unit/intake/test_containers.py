"""Issue 14 (containers): Model.from_kanes / from_lagrange / from_system take
a sympy System, a JointsMethod or a PyDy System as well as the formed method.

Every System and JointsMethod model that sympy 1.14's own tests form
(sympy/physics/mechanics/tests/test_system_class.py, test_jointsmethod.py)
and the documentation's four-bar linkage (System, Kane, two holonomic
constraints) and multi-DOF holonomic system (JointsMethod; here also as a
System) go in as the user has them. The compiled rhs is compared at random
states (consistent states for constrained models) with numpy's solve of
sympy's own mass_matrix_full / forcing_full, in the Kane / Lagrange order
of the state ([q, u]; for Lagrange the first 2n entries, the rest of sympy's
solve being its multipliers).
"""
import warnings

import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me
from sympy.physics.mechanics import (
    Force, KanesMethod, LagrangesMethod, Particle, PinJoint, Point, PrismaticJoint,
    ReferenceFrame, RigidBody, System, TorqueActuator, dynamicsymbols, inertia)

import gen
from gen.core.errors import UnusedConstantWarning
from helpers import rel_err

t = dynamicsymbols._t
TOL = 1e-9


def _quiet(fn):
    """Build with sympy's deprecation warnings (Body, JointsMethod) off."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return fn()


def _body(*args, **kwargs):
    return _quiet(lambda: me.Body(*args, **kwargs))


def _joints_method(*args):
    return _quiet(lambda: me.JointsMethod(*args))


# ---------------------------------------------------------------- models
# Each builder returns a dict: obj (what the user passes), method (sympy's
# formed KanesMethod / LagrangesMethod, the reference), constants, inputs and
# optionally x0 (a state near a consistent configuration, for constraints).

def _moving_point_mass(eom_method=KanesMethod, **kwargs):
    """TestSystemBase._moving_point_mass, formed as test_form_eoms_calls_subclass
    and test_system_{kane,lagrange}_form_eoms_kwargs do."""
    q0, u0 = dynamicsymbols("q0 u0")
    m = sm.symbols("m")
    system = System(ReferenceFrame("frame"), Point("fixed_point"))
    system.q_ind = q0
    system.u_ind = u0
    system.kdes = u0 - q0.diff(t)
    p = Particle("p", mass=m)
    system.add_bodies(p)
    p.masscenter.set_pos(system.fixed_point, q0 * system.x)
    system.form_eoms(eom_method=eom_method, **kwargs)
    return dict(obj=system, method=system.eom_method, constants={m: 1.7}, inputs=[])


class MyKanesMethod(KanesMethod):
    pass


class MyLagrangesMethod(LagrangesMethod):
    pass


def _cart_pendulum_kanes(constrained=False):
    """TestSystemExamples.test_cart_pendulum_kanes (both stages)."""
    g, l, mc, mp, k = sm.symbols("g l mc mp k")
    F, qp, qc, up, uc = dynamicsymbols("F qp qc up uc")
    rail = RigidBody("rail")
    cart = RigidBody("cart", mass=mc)
    bob = Particle("bob", mass=mp)
    bob_frame = ReferenceFrame("bob_frame")
    system = System.from_newtonian(rail)
    slider = PrismaticJoint("slider", rail, cart, qc, uc, joint_axis=rail.x)
    pin = PinJoint("pin", cart, bob, qp, up, joint_axis=cart.z,
                   child_interframe=bob_frame, child_point=l * bob_frame.y)
    system.add_joints(slider, pin)
    system.apply_uniform_gravity(-g * system.y)
    system.add_loads((cart.masscenter, F * rail.x))
    system.add_actuators(TorqueActuator(k * qp, cart.z, bob_frame, cart))
    x0 = None
    if constrained:
        system.add_holonomic_constraints(
            sm.sympify(bob.masscenter.pos_from(rail.masscenter).dot(system.x)))
        system.q_ind, system.q_dep = qp, qc
        system.u_ind, system.u_dep = up, uc
        x0 = [0.4, -0.8 * np.sin(0.4), 0.3, -0.8 * np.cos(0.4) * 0.3]   # [qp, qc, up, uc]
    system.validate_system()
    system.form_eoms()
    return dict(obj=system, method=system.eom_method, inputs=[F], x0=x0,
                constants={g: 9.81, l: 0.8, mc: 1.3, mp: 0.6, k: 0.7})


def _cart_pendulum_lagrange(constrained=False):
    """TestSystemExamples.test_cart_pendulum_lagrange (both stages)."""
    g, l, mc, mp, k = sm.symbols("g l mc mp k")
    F, qp, qc = dynamicsymbols("F qp qc")
    qpd, qcd = dynamicsymbols("qp qc", 1)
    rail = RigidBody("rail")
    cart = RigidBody("cart", mass=mc)
    bob = Particle("bob", mass=mp)
    bob_frame = ReferenceFrame("bob_frame")
    system = System.from_newtonian(rail)
    slider = PrismaticJoint("slider", rail, cart, qc, qcd, joint_axis=rail.x)
    pin = PinJoint("pin", cart, bob, qp, qpd, joint_axis=cart.z,
                   child_interframe=bob_frame, child_point=l * bob_frame.y)
    system.add_joints(slider, pin)
    for body in system.bodies:
        body.potential_energy = body.mass * g * body.masscenter.pos_from(
            system.fixed_point).dot(system.y)
    system.add_loads((cart.masscenter, F * rail.x))
    system.add_actuators(TorqueActuator(k * qp, cart.z, bob_frame, cart))
    x0 = None
    if constrained:
        system.add_holonomic_constraints(
            sm.sympify(bob.masscenter.pos_from(rail.masscenter).dot(system.x)))
        system.q_ind, system.q_dep = qp, qc
        # q order of the System: [qc, qp] (joints) -> state [qc, qp, qc', qp']
        x0 = [-0.8 * np.sin(0.4), 0.4, -0.8 * np.cos(0.4) * 0.3, 0.3]
    system.validate_system(LagrangesMethod)
    system.form_eoms(LagrangesMethod)
    return dict(obj=system, method=system.eom_method, inputs=[F], x0=x0,
                constants={g: 9.81, l: 0.8, mc: 1.3, mp: 0.6, k: 0.7})


def _box_on_ground():
    """TestSystemExamples.test_box_on_ground (an auxiliary speed)."""
    g, m, mu = sm.symbols("g m mu")
    q, u, ua = dynamicsymbols("q u ua")
    N, F = dynamicsymbols("N F", positive=True)
    P = Particle("P", mass=m)
    system = System()
    system.add_bodies(P)
    P.masscenter.set_pos(system.fixed_point, q * system.x)
    P.masscenter.set_vel(system.frame, u * system.x + ua * system.y)
    system.q_ind, system.u_ind, system.u_aux = [q], [u], [ua]
    system.kdes = [q.diff(t) - u]
    system.apply_uniform_gravity(-g * system.y)
    system.add_loads(Force(P, N * system.y), Force(P, F * system.x - mu * N * system.x))
    system.validate_system()
    system.form_eoms()
    # N is the reaction along the auxiliary speed: sympy's forcing holds it,
    # the reference takes it from sympy's auxiliary equations
    km = system.eom_method
    n_sol = sm.solve(km.auxiliary_eqs, [N], dict=True)[0]
    return dict(obj=system, method=km, inputs=[F], reference_subs=n_sol,
                constants={g: 9.81, m: 1.0, mu: 0.3})


def _filled_system(with_speeds):
    """TestSystemBase._create_filled_system: sympy's tests only validate it;
    sympy cannot form its equations (rb1 is attached to nothing in the
    System's frame), so there is nothing to compare."""
    q, qd, ua = dynamicsymbols("q:6"), dynamicsymbols("q:6", 1), dynamicsymbols("ua:3")
    u = dynamicsymbols("u:6") if with_speeds else qd
    system = System(ReferenceFrame("frame"), Point("fixed_point"))
    bodies = sm.symbols("rb1:5", cls=RigidBody)
    system.add_joints(PinJoint("J1", bodies[0], bodies[1], q[0], u[0]),
                      PrismaticJoint("J2", bodies[1], bodies[2], q[1], u[1]),
                      PinJoint("J3", bodies[2], bodies[3], q[2], u[2]))
    system.add_coordinates(q[3], independent=[False])
    system.add_speeds(u[3], independent=False)
    if with_speeds:
        system.add_kdes(u[3] - qd[3])
        system.add_auxiliary_speeds(ua[0], ua[1])
    system.add_holonomic_constraints(q[2] - q[0] + q[1])
    system.add_nonholonomic_constraints(u[3] - qd[1] + u[2])
    system.u_ind = u[:2]
    system.u_dep = u[2:4]
    try:
        system.form_eoms(KanesMethod if with_speeds else LagrangesMethod)
    except ValueError as e:
        pytest.skip(f"sympy cannot form the equations of its filled test system: "
                    f"{' '.join(str(e).split())}")
    raise AssertionError("sympy now forms the filled system: add it to the comparison")


def _jm_jointsmethod():
    """test_jointsmethod: Body C on a pin; the force g*P.y acts on the fixed
    parent, so g appears in no equation (UnusedConstantWarning)."""
    P = _body("P")
    C = _body("C")
    pin = PinJoint("P1", P, C)
    C_ixx, g = sm.symbols("C_ixx g")
    P.apply_force(g * P.y)
    method = _joints_method(P, pin)
    method.form_eoms()
    return dict(obj=method, method=method.method, inputs=[],
                constants={C_ixx: 0.4, g: 9.81}, unused=["g"])


def _jm_rigid_body_particle():
    """test_rigid_body_particle_compatibility."""
    l, m, g = sm.symbols("l m g")
    C = RigidBody("C")
    b = Particle("b", mass=m)
    b_frame = ReferenceFrame("b_frame")
    q, u = dynamicsymbols("q u")
    P = PinJoint("P", C, b, coordinates=q, speeds=u, child_interframe=b_frame,
                 child_point=-l * b_frame.x, joint_axis=C.z)
    method = _joints_method(C, P)
    method.loads.append((b.masscenter, m * g * C.x))
    method.form_eoms()
    return dict(obj=method, method=method.method, inputs=[],
                constants={l: 0.9, m: 1.1, g: 9.81})


def _jm_double_pendulum():
    """test_complete_simple_double_pendulum."""
    q1, q2, u1, u2 = dynamicsymbols("q1 q2 u1 u2")
    m, l, g = sm.symbols("m l g")
    C = _body("C")
    PartP = _body("P", mass=m)
    PartR = _body("R", mass=m)
    J1 = PinJoint("J1", C, PartP, speeds=u1, coordinates=q1,
                  child_point=-l * PartP.x, joint_axis=C.z)
    J2 = PinJoint("J2", PartP, PartR, speeds=u2, coordinates=q2,
                  child_point=-l * PartR.x, joint_axis=PartP.z)
    PartP.apply_force(m * g * C.x)
    PartR.apply_force(m * g * C.x)
    method = _joints_method(C, J1, J2)
    method.form_eoms()
    return dict(obj=method, method=method.method, inputs=[],
                constants={m: 1.2, l: 0.7, g: 9.81})


def _jm_two_dof():
    """test_two_dof_joints."""
    q1, q2, u1, u2 = dynamicsymbols("q1 q2 u1 u2")
    m, c1, c2, k1, k2 = sm.symbols("m c1 c2 k1 k2")
    W = _body("W")
    B1 = _body("B1", mass=m)
    B2 = _body("B2", mass=m)
    J1 = PrismaticJoint("J1", W, B1, coordinates=q1, speeds=u1)
    J2 = PrismaticJoint("J2", B1, B2, coordinates=q2, speeds=u2)
    W.apply_force(k1 * q1 * W.x, reaction_body=B1)
    W.apply_force(c1 * u1 * W.x, reaction_body=B1)
    B1.apply_force(k2 * q2 * W.x, reaction_body=B2)
    B1.apply_force(c2 * u2 * W.x, reaction_body=B2)
    method = _joints_method(W, J1, J2)
    method.form_eoms()
    return dict(obj=method, method=method.method, inputs=[],
                constants={m: 1.5, c1: 0.2, c2: 0.3, k1: 4.0, k2: 2.5})


def _jm_simple_pendulum_lagrange():
    """test_simple_pedulum (LagrangesMethod through a JointsMethod)."""
    l, m, g = sm.symbols("l m g")
    C = _body("C")
    b = _body("b", mass=m)
    q = dynamicsymbols("q")
    P = PinJoint("P", C, b, speeds=q.diff(t), coordinates=q,
                 child_point=-l * b.x, joint_axis=C.z)
    b.potential_energy = -m * g * l * sm.cos(q)
    method = _joints_method(C, P)
    method.form_eoms(LagrangesMethod)
    return dict(obj=method, method=method.method, inputs=[],
                constants={l: 0.9, m: 1.1, g: 9.81})


def _jm_chaos_pendulum():
    """test_chaos_pendulum."""
    mA, mB, lA, lB, IAxx, IBxx, IByy, IBzz, g = sm.symbols(
        "mA, mB, lA, lB, IAxx, IBxx, IByy, IBzz, g")
    theta, phi, omega, alpha = dynamicsymbols("theta phi omega alpha")
    A = ReferenceFrame("A")
    B = ReferenceFrame("B")
    rod = _body("rod", mass=mA, frame=A, central_inertia=inertia(A, IAxx, IAxx, 0))
    plate = _body("plate", mass=mB, frame=B, central_inertia=inertia(B, IBxx, IByy, IBzz))
    C = _body("C")
    J1 = PinJoint("J1", C, rod, coordinates=theta, speeds=omega,
                  child_point=-lA * rod.z, joint_axis=C.y)
    J2 = PinJoint("J2", rod, plate, coordinates=phi, speeds=alpha,
                  parent_point=(lB - lA) * rod.z, joint_axis=rod.z)
    rod.apply_force(mA * g * C.z)
    plate.apply_force(mB * g * C.z)
    method = _joints_method(C, J1, J2)
    method.form_eoms()
    return dict(obj=method, method=method.method, inputs=[],
                constants={mA: 0.01, mB: 0.1, lA: 0.05, lB: 0.2, IAxx: 1e-5,
                           IBxx: 2.5e-4, IByy: 1.0e-4, IBzz: 3.5e-4, g: 9.81})


def _four_bar_parts():
    q1, q2, q3, u1, u2, u3 = dynamicsymbols("q1:4, u1:4")
    l1, l2, l3, l4, rho = sm.symbols("l1:5, rho")
    N = ReferenceFrame("N")
    consts = {l1: 0.13, l2: 0.24, l3: 0.21, l4: 0.34, rho: 997.0}
    # sympy's test: q and u that satisfy the loop
    x0 = [2.1, 0.6655470375077588, 2.527408138024188,
          0.2, -0.17963733938852067, 0.1309060540601612]
    return q1, q2, q3, u1, u2, u3, l1, l2, l3, l4, rho, N, consts, x0


def _jm_four_bar_manual():
    """test_four_bar_linkage_with_manual_constraints: the JointsMethod's
    kinematics closed with a KanesMethod built by hand (the constrained
    model) -- here given as that KanesMethod."""
    q1, q2, q3, u1, u2, u3, l1, l2, l3, l4, rho, N, consts, x0 = _four_bar_parts()
    inertias = [inertia(N, 0, 0, rho * l ** 3 / 12) for l in (l1, l2, l3, l4)]
    link1 = _body("Link1", frame=N, mass=rho * l1, central_inertia=inertias[0])
    link2 = _body("Link2", mass=rho * l2, central_inertia=inertias[1])
    link3 = _body("Link3", mass=rho * l3, central_inertia=inertias[2])
    link4 = _body("Link4", mass=rho * l4, central_inertia=inertias[3])
    joint1 = PinJoint("J1", link1, link2, coordinates=q1, speeds=u1, joint_axis=link1.z,
                      parent_point=l1 / 2 * link1.x, child_point=-l2 / 2 * link2.x)
    joint2 = PinJoint("J2", link2, link3, coordinates=q2, speeds=u2, joint_axis=link2.z,
                      parent_point=l2 / 2 * link2.x, child_point=-l3 / 2 * link3.x)
    joint3 = PinJoint("J3", link3, link4, coordinates=q3, speeds=u3, joint_axis=link3.z,
                      parent_point=l3 / 2 * link3.x, child_point=-l4 / 2 * link4.x)
    loop = link4.masscenter.pos_from(link1.masscenter) + l1 / 2 * link1.x + l4 / 2 * link4.x
    fh = sm.Matrix([loop.dot(link1.x), loop.dot(link1.y)])
    method = _joints_method(link1, joint1, joint2, joint3)
    qdots = sm.solve(method.kdes, [q1.diff(t), q2.diff(t), q3.diff(t)])
    fhd = fh.diff(t).subs(qdots)
    kane = KanesMethod(method.frame, q_ind=[q1], u_ind=[u1], q_dependent=[q2, q3],
                       u_dependent=[u2, u3], kd_eqs=method.kdes,
                       configuration_constraints=fh, velocity_constraints=fhd,
                       forcelist=method.loads, bodies=method.bodies)
    kane.kanes_equations()
    return dict(obj=kane, method=kane, inputs=[], constants=consts, x0=x0, joints=method)


def _jm_four_bar_open():
    """The same JointsMethod formed as it is (the open three-link chain)."""
    d = _jm_four_bar_manual()
    method = d["joints"]
    _quiet(method.form_eoms)
    # link 1 is the fixed frame: its length l1 enters no equation of the open chain
    return dict(obj=method, method=method.method, inputs=[], constants=d["constants"],
                unused=["l1"])


def _doc_four_bar():
    """sympy docs, 'A four bar linkage' (System, KanesMethod backend,
    two holonomic constraints close the loop)."""
    q1, q2, q3, u1, u2, u3, l1, l2, l3, l4, rho, N, consts, x0 = _four_bar_parts()
    mass_centers = [Point(f"mc{i}") for i in range(1, 5)]
    inertias = [me.Inertia.from_inertia_scalars(P, N, 0, 0, rho * l ** 3 / 12)
                for P, l in zip(mass_centers, (l1, l2, l3, l4))]
    link1 = RigidBody("Link1", frame=N, mass=rho * l1, masscenter=mass_centers[0],
                      inertia=inertias[0])
    link2 = RigidBody("Link2", mass=rho * l2, masscenter=mass_centers[1], inertia=inertias[1])
    link3 = RigidBody("Link3", mass=rho * l3, masscenter=mass_centers[2], inertia=inertias[2])
    link4 = RigidBody("Link4", mass=rho * l4, masscenter=mass_centers[3], inertia=inertias[3])
    system = System.from_newtonian(link1)
    joint1 = PinJoint("J1", link1, link2, coordinates=q1, speeds=u1,
                      parent_point=l1 / 2 * link1.x, child_point=-l2 / 2 * link2.x,
                      joint_axis=link1.z)
    joint2 = PinJoint("J2", link2, link3, coordinates=q2, speeds=u2,
                      parent_point=l2 / 2 * link2.x, child_point=-l3 / 2 * link3.x,
                      joint_axis=link2.z)
    joint3 = PinJoint("J3", link3, link4, coordinates=q3, speeds=u3,
                      parent_point=l3 / 2 * link3.x, child_point=-l4 / 2 * link4.x,
                      joint_axis=link3.z)
    system.add_joints(joint1, joint2, joint3)
    loop = link4.masscenter.pos_from(link1.masscenter) + l1 / 2 * link1.x + l4 / 2 * link4.x
    system.add_holonomic_constraints(loop.dot(link1.x), loop.dot(link1.y))
    system.q_ind = [q1]
    system.u_ind = [u1]
    system.q_dep = [q2, q3]
    system.u_dep = [u2, u3]
    system.validate_system()
    system.form_eoms()
    return dict(obj=system, method=system.eom_method, inputs=[], constants=consts, x0=x0)


def _multidof_symbols():
    q1, q2, q3, u1, u2, u3 = dynamicsymbols("q1, q2, q3, u1, u2, u3")
    l, k, c, g, kT = sm.symbols("l, k, c, g, kT")
    ma, mb, mc, IBzz = sm.symbols("ma, mb, mc, IBzz")
    F, T = dynamicsymbols("F, T")
    consts = {l: 0.6, k: 20.0, c: 0.4, g: 9.81, kT: 1.5, ma: 2.0, mb: 1.0, mc: 0.5,
              IBzz: 0.03}
    return q1, q2, q3, u1, u2, u3, l, k, c, g, kT, ma, mb, mc, IBzz, F, T, consts


def _doc_multidof_joints():
    """sympy docs, 'Multi Degree of Freedom Holonomic System' (JointsMethod
    with Body; the page's child_axis/parent_axis/*_joint_pos keywords are the
    removed spellings of joint_axis/parent_point/child_point)."""
    (q1, q2, q3, u1, u2, u3, l, k, c, g, kT, ma, mb, mc, IBzz, F, T,
     consts) = _multidof_symbols()
    wall = _body("N")
    block = _body("A", mass=ma)
    IB = inertia(block.frame, 0, 0, IBzz)
    compound_pend = _body("B", mass=mb, central_inertia=IB)
    simple_pend = _body("C", mass=mc)
    slider = PrismaticJoint("J1", wall, block, coordinates=q1, speeds=u1)
    rev1 = PinJoint("J2", block, compound_pend, coordinates=q2, speeds=u2,
                    joint_axis=block.z, child_point=l * 2 / 3 * compound_pend.y)
    rev2 = PinJoint("J3", compound_pend, simple_pend, coordinates=q3, speeds=u3,
                    joint_axis=compound_pend.z, parent_point=-l / 3 * compound_pend.y,
                    child_point=l * simple_pend.y)
    block.apply_force(F * block.x)
    block.apply_force(-k * q1 * block.x, reaction_body=wall)
    block.apply_force(-c * u1 * block.x, reaction_body=wall)
    compound_pend.apply_torque(T * compound_pend.z, reaction_body=block)
    simple_pend.apply_torque(-kT * q3 * simple_pend.z, reaction_body=compound_pend)
    block.apply_force(-wall.y * block.mass * g)
    compound_pend.apply_force(-wall.y * compound_pend.mass * g)
    simple_pend.apply_force(-wall.y * simple_pend.mass * g)
    method = _joints_method(wall, slider, rev1, rev2)
    method.form_eoms()
    return dict(obj=method, method=method.method, inputs=[F, T], constants=consts)


def _doc_multidof_system():
    """The same system written with System, RigidBody and Particle (the API
    the documentation teaches now; this rewrite is ours, the page in the docs
    corpus still uses Body and JointsMethod): the torques as Torque loads on
    the joint frames."""
    (q1, q2, q3, u1, u2, u3, l, k, c, g, kT, ma, mb, mc, IBzz, F, T,
     consts) = _multidof_symbols()
    wall = RigidBody("N")
    block = Particle("A", mass=ma)
    compound_pend = RigidBody("B", mass=mb)
    compound_pend.central_inertia = inertia(compound_pend.frame, 0, 0, IBzz)
    simple_pend = Particle("C", mass=mc)
    system = System.from_newtonian(wall)
    system.add_bodies(block, compound_pend, simple_pend)
    block_frame = ReferenceFrame("A_frame")
    slider = PrismaticJoint("J1", wall, block, coordinates=q1, speeds=u1,
                            child_interframe=block_frame)
    rev1 = PinJoint("J2", block, compound_pend, coordinates=q2, speeds=u2,
                    joint_axis=wall.z, child_point=l * 2 / 3 * compound_pend.y,
                    parent_interframe=block_frame)
    simple_pend_frame = ReferenceFrame("C_frame")
    rev2 = PinJoint("J3", compound_pend, simple_pend, coordinates=q3, speeds=u3,
                    joint_axis=compound_pend.z, parent_point=-l / 3 * compound_pend.y,
                    child_point=l * simple_pend_frame.y, child_interframe=simple_pend_frame)
    system.add_joints(slider, rev1, rev2)
    system.add_loads(
        me.Force(block, F * wall.x),
        me.Force(block, -k * q1 * wall.x),
        me.Force(block, -c * u1 * wall.x),
        me.Torque(compound_pend, T * wall.z),
        me.Torque(block_frame, -T * wall.z),
        me.Torque(simple_pend_frame, -kT * q3 * compound_pend.z),
        me.Torque(compound_pend, kT * q3 * compound_pend.z))
    system.apply_uniform_gravity(-g * wall.y)
    system.validate_system()
    system.form_eoms()
    return dict(obj=system, method=system.eom_method, inputs=[F, T], constants=consts)


MODELS = {
    # test_system_class.py
    "system_point_mass_kane": lambda: _moving_point_mass(),
    "system_point_mass_kane_explicit": lambda: _moving_point_mass(explicit_kinematics=True),
    "system_point_mass_lagrange": lambda: _moving_point_mass(LagrangesMethod),
    "sys_point_mass_kane_subclass": lambda: _moving_point_mass(MyKanesMethod),
    "sys_point_mass_lagrange_subclass": lambda: _moving_point_mass(MyLagrangesMethod),
    "sys_cart_pend_kanes": lambda: _cart_pendulum_kanes(),
    "sys_cart_pend_kanes_constrained": lambda: _cart_pendulum_kanes(True),
    "sys_cart_pend_lagrange": lambda: _cart_pendulum_lagrange(),
    "sys_cart_pend_lagrange_constrained": lambda: _cart_pendulum_lagrange(True),
    "system_box_on_ground": _box_on_ground,
    "system_filled_kane": lambda: _filled_system(True),
    "system_filled_lagrange": lambda: _filled_system(False),
    # test_jointsmethod.py
    "jm_jointsmethod": _jm_jointsmethod,
    "jm_rigid_body_particle": _jm_rigid_body_particle,
    "jm_double_pendulum": _jm_double_pendulum,
    "jm_two_dof": _jm_two_dof,
    "jm_simple_pendulum_lagrange": _jm_simple_pendulum_lagrange,
    "jm_chaos_pendulum": _jm_chaos_pendulum,
    "jm_four_bar_open": _jm_four_bar_open,
    "jm_four_bar_manual_constraints": _jm_four_bar_manual,
    # documentation
    "doc_four_bar": _doc_four_bar,
    "doc_multidof_joints": _doc_multidof_joints,
    "doc_multidof_system": _doc_multidof_system,
}
SLOW = {"jm_chaos_pendulum", "doc_multidof_joints", "jm_four_bar_open", "jm_two_dof",
        "sys_point_mass_kane_subclass", "sys_point_mass_lagrange_subclass",
        "system_point_mass_kane_explicit", "jm_four_bar_manual_constraints",
        # the fast tier keeps one model of each kind (System with Kane and with
        # Lagrange, constrained, JointsMethod, PyDy, auxiliary speeds, docs)
        "system_point_mass_lagrange", "sys_cart_pend_lagrange", "jm_rigid_body_particle",
        "jm_simple_pendulum_lagrange", "doc_multidof_system", "sys_cart_pend_kanes"}


# ------------------------------------------------------------ reference
def _reference(method, constants, inputs, subs=None):
    """x' from numpy's solve of sympy's mass_matrix_full / forcing_full, as a
    function of (t, x, r) with x = [q, u] (Lagrange: [q, q'])."""
    lagrange = isinstance(method, LagrangesMethod)
    q = list(method.q)
    u = [qi.diff(t) for qi in q] if lagrange else list(method.u)
    T = sm.Dummy("t")
    X = [sm.Dummy(f"x{i}") for i in range(len(q) + len(u))]
    R = [sm.Dummy(f"r{i}") for i in range(len(inputs))]
    sub = {}
    if lagrange:   # derivatives first: q'' is not an argument, q' is
        sub.update({qi.diff(t): X[len(q) + i] for i, qi in enumerate(q)})
    else:
        sub.update({qi.diff(t): sm.Dummy() for qi in q})   # must not remain
        sub.update({ui: X[len(q) + i] for i, ui in enumerate(u)})
    sub.update({qi: X[i] for i, qi in enumerate(q)})
    sub.update(dict(zip(inputs, R)))
    sub.update({c: sm.Float(v) for c, v in constants.items()})
    MM, FF = method.mass_matrix_full, method.forcing_full
    if subs:
        MM, FF = MM.subs(subs), FF.subs(subs)
    MM = MM.xreplace(sub).xreplace({t: T})
    FF = FF.xreplace(sub).xreplace({t: T})
    fM = sm.lambdify((T, X, R), MM, "numpy")
    fF = sm.lambdify((T, X, R), FF, "numpy")
    n = len(q) + len(u)

    def xdot(tt, x, r):
        M = np.array(fM(tt, list(x), list(r)), dtype=float)
        f = np.array(fF(tt, list(x), list(r)), dtype=float).reshape(-1)
        return np.linalg.solve(M, f)[:n]
    return xdot


def _build(d, via, **partition):
    kw = dict(constants=d["constants"], inputs=d["inputs"], name=via[1], **partition)
    lagrange = isinstance(d["method"], LagrangesMethod)
    if via[0] == "from_system":
        return gen.Model.from_system(d["obj"], **kw)
    if lagrange:
        return gen.Model.from_lagrange(d["obj"], **kw)
    return gen.Model.from_kanes(d["obj"], **kw)


def _compare(d, model, n=8, seed=0):
    sim = gen.compile(model)
    ref = _reference(d["method"], d["constants"], d["inputs"], d.get("reference_subs"))
    rng = np.random.default_rng(seed)
    constrained = model.mc or model.mv
    worst = 0.0
    for _ in range(n):
        if d.get("x0") is not None:
            x = np.array(d["x0"], dtype=float) + rng.uniform(-0.05, 0.05, sim.nx)
        else:
            x = rng.uniform(-1.5, 1.5, sim.nx)
        if constrained:
            x = sim.consistent_state(x)
            assert np.max(np.abs(sim.constraints(x[:sim.nq]))) < 1e-10
        r = rng.uniform(-1, 1, sim.nr)
        tt = float(rng.uniform(0, 1))
        got = sim.rhs(tt, x, r=r if sim.nr else None)
        want = ref(tt, x, r)
        assert np.all(np.isfinite(want)), want
        err = rel_err(got, want)
        worst = max(worst, err)
    return worst


RESULTS = {}


@pytest.mark.parametrize("key", [
    pytest.param(k, marks=pytest.mark.slow) if k in SLOW else k for k in MODELS])
def test_model_matches_sympy(key):
    d = MODELS[key]()
    expect_unused = d.get("unused", [])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = _build(d, ("from_system", key))
    unused = [w for w in caught if issubclass(w.category, UnusedConstantWarning)]
    assert len(unused) == (1 if expect_unused else 0), [str(w.message) for w in unused]
    for name in expect_unused:
        assert f"constant {name} appears in no expression" in str(unused[0].message)
    # the container and the method it holds give the same model
    part = {}
    if model.method == "lagrange":
        part = dict(q_ind=[model.q_orig[i] for i in model.q_ind],
                    q_dep=[model.q_orig[i] for i in model.q_dep],
                    qd_ind=[model.u_orig[i] for i in model.u_ind],
                    qd_dep=[model.u_orig[i] for i in model.u_dep])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnusedConstantWarning)
        direct = _build(dict(d, obj=d["method"]), ("direct", key), **part)
    assert model.fingerprint() == direct.fingerprint()
    worst = _compare(d, model)
    RESULTS[key] = worst
    print(f"{key}: max rel err {worst:.2e}")
    assert worst < TOL, (key, worst)


def test_from_kanes_and_from_lagrange_take_containers():
    """from_kanes / from_lagrange given the container forward to the method
    (same model as from_system)."""
    d = _cart_pendulum_kanes()
    a = gen.Model.from_kanes(d["obj"], constants=d["constants"], inputs=d["inputs"], name="c")
    b = gen.Model.from_system(d["obj"], constants=d["constants"], inputs=d["inputs"], name="c")
    assert a.fingerprint() == b.fingerprint()
    d = _cart_pendulum_lagrange(True)
    a = gen.Model.from_lagrange(d["obj"], constants=d["constants"], inputs=d["inputs"],
                                name="c")
    # the System's own partition: qp independent, qc dependent
    assert [a.state_labels[i] for i in a.q_ind] == ["qp"]
    assert [a.state_labels[i] for i in a.q_dep] == ["qc"]
    assert [a.state_labels[a.nq + i] for i in a.u_dep] == ["qc_d"]
    # a partition given by the user wins over the System's
    qp, qc = dynamicsymbols("qp qc")
    b = gen.Model.from_system(d["obj"], constants=d["constants"], inputs=d["inputs"],
                              name="c", q_ind=[qc], q_dep=[qp], qd_ind=[qc.diff(t)],
                              qd_dep=[qp.diff(t)])
    assert [b.state_labels[i] for i in b.q_dep] == ["qp"]
    # the System's speeds, when they are the q' split as the constraints need
    # (here on purpose not as the coordinates are)
    system = d["obj"]
    system.u_ind, system.u_dep = [qc.diff(t)], [qp.diff(t)]
    system.form_eoms(LagrangesMethod)
    c = gen.Model.from_system(system, constants=d["constants"], inputs=d["inputs"], name="c")
    assert [c.state_labels[i] for i in c.q_dep] == ["qc"]
    assert [c.state_labels[c.nq + i] for i in c.u_ind] == ["qc_d"]
    assert [c.state_labels[c.nq + i] for i in c.u_dep] == ["qp_d"]


# ------------------------------------------------------------ refusals
def test_wrong_backend_names_what_was_given():
    d = _cart_pendulum_lagrange()
    with pytest.raises(gen.ModelError) as e:
        gen.Model.from_kanes(d["obj"], constants=d["constants"], inputs=d["inputs"])
    assert str(e.value) == (
        "Model.from_kanes needs a KanesMethod, got System with a LagrangesMethod: use "
        "Model.from_lagrange or Model.from_system (accepted: a KanesMethod, or a sympy "
        "System, JointsMethod or pydy System holding one)")
    d = _cart_pendulum_kanes()
    with pytest.raises(gen.ModelError) as e:
        gen.Model.from_lagrange(d["obj"], constants=d["constants"], inputs=d["inputs"])
    assert str(e.value) == (
        "Model.from_lagrange needs a LagrangesMethod, got System with a KanesMethod: use "
        "Model.from_kanes or Model.from_system (accepted: a LagrangesMethod, or a sympy "
        "System, JointsMethod or pydy System holding one)")
    d = _jm_simple_pendulum_lagrange()
    with pytest.raises(gen.ModelError, match=r"got JointsMethod with a LagrangesMethod: use "
                                             r"Model\.from_lagrange or Model\.from_system"):
        gen.Model.from_kanes(d["obj"], constants=d["constants"])
    with pytest.raises(gen.ModelError, match=r"got LagrangesMethod: use Model\.from_lagrange"):
        gen.Model.from_kanes(d["method"], constants=d["constants"])
    for bad in (3.0, "km", None, sm.Matrix([1])):
        with pytest.raises(gen.ModelError) as e:
            gen.Model.from_system(bad)
        assert str(e.value) == (
            f"Model.from_system needs a KanesMethod or LagrangesMethod, got "
            f"{type(bad).__name__} (accepted: a KanesMethod or LagrangesMethod, or a sympy "
            "System, JointsMethod or pydy System holding one)")


def test_unformed_containers_say_form_eoms():
    system = System()
    for fn in (gen.Model.from_kanes, gen.Model.from_lagrange, gen.Model.from_system):
        with pytest.raises(gen.ModelError, match=r"got System without equations of motion: "
                                                 r"call system\.form_eoms\(\) first"):
            fn(system)
    # formed, then changed: sympy resets eom_method, so it is unformed again
    d = _cart_pendulum_kanes()
    d["obj"].add_loads((d["obj"].fixed_point, 0 * d["obj"].x))
    with pytest.raises(gen.ModelError, match=r"call system\.form_eoms\(\) first"):
        gen.Model.from_system(d["obj"], constants=d["constants"], inputs=d["inputs"])
    q = dynamicsymbols("q")
    P, C = _body("P"), _body("C")
    jm = _joints_method(P, PinJoint("P1", P, C, coordinates=q))
    with pytest.raises(gen.ModelError, match=r"got JointsMethod without equations of "
                                             r"motion: call method\.form_eoms\(\) first"):
        gen.Model.from_kanes(jm)


def test_kane_partition_arguments_refused():
    d = _cart_pendulum_kanes()
    qp = dynamicsymbols("qp")
    with pytest.raises(gen.ModelError, match=r"q_ind given for a Kane model \(System with a "
                                             r"KanesMethod\)"):
        gen.Model.from_system(d["obj"], constants=d["constants"], inputs=d["inputs"],
                              q_ind=[qp])
    d = _cart_pendulum_lagrange()
    with pytest.raises(gen.ModelError, match=r"unknown argument\(s\) u_ind for "
                                             r"Model\.from_system with System with a "
                                             r"LagrangesMethod: accepted are q_ind, "
                                             r"qd_ind, q_dep, qd_dep"):
        gen.Model.from_system(d["obj"], constants=d["constants"], inputs=d["inputs"],
                              u_ind=[qp])


# ------------------------------------------------------------ PyDy
def _pydy_system(d, **kw):
    pydy_system = pytest.importorskip("pydy.system")
    return _quiet(lambda: pydy_system.System(d["method"], **kw))


def test_pydy_system_gives_constants_and_inputs():
    d = _cart_pendulum_kanes()
    F = d["inputs"][0]
    psys = _pydy_system(d, constants=d["constants"], specifieds={F: 0.0})
    a = gen.Model.from_system(psys, name="pydy_cart")
    b = gen.Model.from_kanes(psys, name="pydy_cart")
    direct = gen.Model.from_kanes(d["method"], constants=d["constants"], inputs=[F],
                                  name="pydy_cart")
    assert a.fingerprint() == b.fingerprint() == direct.fingerprint()
    assert a.p_values == [9.81, 0.8, 1.3, 0.6, 0.7]
    assert a.input_labels == ["F"]
    assert _compare(d, a, n=4) < TOL
    # given constants / inputs win over the pydy System's
    c = gen.Model.from_kanes(psys, constants=dict(d["constants"], **{}), inputs=[F],
                             name="pydy_cart")
    assert c.fingerprint() == direct.fingerprint()


def test_pydy_system_specifieds_without_values_are_inputs():
    d = _doc_multidof_system()
    F, T = d["inputs"]
    psys = _pydy_system(d, constants=d["constants"], specifieds={T: 1.0})
    m = gen.Model.from_system(psys, name="pydy_multidof")
    assert m.input_labels == ["T", "F"]   # the specifieds' keys, then the rest by name


def test_pydy_system_missing_constant_named():
    d = _cart_pendulum_kanes()
    consts = dict(d["constants"])
    g = sm.Symbol("g")
    del consts[g]
    psys = _pydy_system(d, constants=consts)
    with pytest.raises(gen.ModelError, match=r"symbol\(s\) g that are neither"):
        gen.Model.from_system(psys)


class PydyLike:
    """A stand-in with PyDy System's duck type (eom_method, constants,
    specifieds), for pydy versions this test does not know."""

    def __init__(self, km, constants, specifieds):
        self._km, self.constants, self.specifieds = km, constants, specifieds

    @property
    def eom_method(self):
        return self._km


def test_pydy_duck_type():
    d = _cart_pendulum_kanes()
    F = d["inputs"][0]
    m = gen.Model.from_system(PydyLike(d["method"], d["constants"], {(F,): [0.0]}),
                              name="duck")
    assert m.input_labels == ["F"] and m.p_values == [9.81, 0.8, 1.3, 0.6, 0.7]
    with pytest.raises(gen.ModelError, match=r"got pydy System with a LagrangesMethod: use "
                                             r"Model\.from_lagrange"):
        gen.Model.from_kanes(PydyLike(_cart_pendulum_lagrange()["method"], {}, {}))
