"""Issue 47's misreadings at intake: an empty System, a massless body that
carries a joint, a model with no speeds, each refused with a message in the
user's names (they passed with nx = 0 and failed in the C compiler, or said
"the forcing contain nan" and named no body).

Reference for the accepted case (a massless body whose joint still moves a
massive child): sympy's own System.form_eoms() (Kane) on the same tree, its
M^-1 f evaluated with numpy."""
import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me

import gen

pytestmark = pytest.mark.filterwarnings("ignore:\\s*Velocity of:UserWarning")


def _two_pins(m_upper, m_lower):
    """A double pendulum of rigid bodies upper, lower on pins j1 (ground to
    upper, about z) and j2 (upper to lower, about upper's x: a universal
    joint when upper is massless), each body's mass and inertia (about z and
    x) the given numbers."""
    g, l = sm.symbols("g l")
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    ground = me.RigidBody("ground")
    bodies = []
    for name, mass in (("upper", m_upper), ("lower", m_lower)):
        b = me.RigidBody(name, mass=mass)
        b.inertia = (me.inertia(b.frame, mass, mass / 2, mass), b.masscenter)
        bodies.append(b)
    upper, lower = bodies
    j1 = me.PinJoint("j1", ground, upper, coordinates=q1, speeds=u1,
                     child_point=l * upper.frame.y, joint_axis=ground.frame.z)
    j2 = me.PinJoint("j2", upper, lower, coordinates=q2, speeds=u2,
                     child_point=l * lower.frame.y, joint_axis=upper.frame.x)
    system = me.System.from_newtonian(ground)
    system.add_joints(j1, j2)
    system.apply_uniform_gravity(-g * ground.frame.y)
    return system, {g: 9.81, l: 0.7}


def test_an_empty_system_is_refused_naming_it():
    system = me.System()
    msg = ("Model.from_system: the System of frame 'inertial_frame' and fixed point "
           "'inertial_point' is empty: no joints, coordinates or speeds, so the model would "
           "have no state; add bodies and joints (System.add_joints) first")
    for formulation in ("recursive", "crba"):
        with pytest.raises(gen.ModelError) as e:
            gen.Model.from_system(system, formulation=formulation)
        assert str(e.value) == msg


def test_a_model_without_speeds_is_refused():
    with pytest.raises(gen.ModelError) as e:
        gen.Model.from_matrices(sm.zeros(0, 0), sm.zeros(0, 1), [], [], sm.zeros(0, 1),
                                name="nothing")
    assert str(e.value) == ("model 'nothing' has no speeds, so no state: nothing to simulate "
                            "(an empty System or method?)")


def test_a_massless_body_carrying_a_joint_is_refused_naming_it():
    system, consts = _two_pins(1, 0)
    for formulation in ("recursive", "crba"):
        with pytest.raises(gen.ModelError) as e:
            gen.Model.from_system(system, constants=consts, formulation=formulation)
        assert str(e.value) == (
            "body 'lower' has no mass or inertia that its joint 'j2' moves (nor has any body "
            "beyond it), so the equations do not determine the acceleration of u2: give it a "
            "mass or inertia, or weld it to its parent (WeldJoint)")


@pytest.mark.slow
def test_a_massless_body_moving_a_massive_child_is_taken():
    """The check is on what the joint moves, not the body's own mass: a
    massless link between two pins (a universal joint) is a model, and its
    accelerations are sympy's."""
    system, consts = _two_pins(0, 1)
    model = gen.Model.from_system(system, constants=consts, formulation="recursive")
    ref, _ = _two_pins(0, 1)
    ref.form_eoms()
    x = {s: v for s, v in zip(list(ref.q) + list(ref.u), (0.3, -0.4, 0.5, 0.2))}
    M = np.array(ref.mass_matrix.xreplace(consts).xreplace(x), dtype=float)
    f = np.array(ref.forcing.xreplace(consts).xreplace(x), dtype=float).ravel()
    # the model's own symbols: states q, u, then the constants in its order
    sub = dict(zip(model.q + model.u, (0.3, -0.4, 0.5, 0.2)))
    sub.update(zip(model.p, model.p_values))
    ours = np.array(model.f.doit().xreplace(sub), dtype=float).ravel()
    assert np.allclose(ours, np.linalg.solve(M, f), rtol=1e-12, atol=1e-12)
