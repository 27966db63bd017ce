"""sympy's test_implicit_kinematics body (sympy/physics/mechanics/tests/
test_kane.py): a rigid body whose attitude is a unit quaternion
lambda_0..3, with body-frame velocities and body rates as speeds. The unit
norm is a configuration constraint (lambda_0 dependent) with no dependent
speed: its time derivative is one of the kinematic equations. eomgen keeps
the norm by projection and linearizes on [lambda_1..3, position, speeds].

    model()          # thrust F_z and torque T_z along B.z as inputs
"""
import gen

from sympy import Matrix, S, symbols
from sympy.physics.mechanics import (KanesMethod, Point, ReferenceFrame, RigidBody,
                                     dynamicsymbols, inertia)


def derive():
    NED = ReferenceFrame('NED')
    NED_o = Point('NED_o')
    NED_o.set_vel(NED, 0)
    q_att = dynamicsymbols('lambda_0:4', real=True)
    B = NED.orientnew('B', 'Quaternion', q_att)
    q_pos = dynamicsymbols('B_x:z')
    B_cm = NED_o.locatenew('B_cm', q_pos[0]*B.x + q_pos[1]*B.y + q_pos[2]*B.z)
    q_ind = q_att[1:] + q_pos
    q_dep = [q_att[0]]
    kinematic_eqs = []
    B_ang_vel = B.ang_vel_in(NED)
    P, Q, R = dynamicsymbols('P Q R')
    B.set_ang_vel(NED, P*B.x + Q*B.y + R*B.z)
    B_ang_vel_kd = (B.ang_vel_in(NED) - B_ang_vel).simplify()
    kinematic_eqs += [B_ang_vel_kd & B.x, B_ang_vel_kd & B.y, B_ang_vel_kd & B.z]
    B_cm_vel = B_cm.vel(NED)
    U, V, W = dynamicsymbols('U V W')
    B_cm.set_vel(NED, U*B.x + V*B.y + W*B.z)
    B_ref_vel_kd = (B_cm.vel(NED) - B_cm_vel)
    kinematic_eqs += [B_ref_vel_kd & B.x, B_ref_vel_kd & B.y, B_ref_vel_kd & B.z]
    u_ind = [U, V, W, P, Q, R]
    q_att_vec = Matrix(q_att)
    config_cons = [(q_att_vec.T*q_att_vec)[0] - 1]
    kinematic_eqs = kinematic_eqs + [(q_att_vec.T * q_att_vec.diff())[0]]
    KM = KanesMethod(NED, q_ind, u_ind, q_dependent=q_dep, kd_eqs=kinematic_eqs,
                     configuration_constraints=config_cons, velocity_constraints=[],
                     u_dependent=[], u_auxiliary=[], explicit_kinematics=False)
    M_B = symbols('M_B')
    J_B = inertia(B, *[S(f'J_B_{ax}')*(1 if ax[0] == ax[1] else -1)
                       for ax in ['xx', 'yy', 'zz', 'xy', 'yz', 'xz']])
    J_B = J_B.subs({S('J_B_xy'): 0, S('J_B_yz'): 0})
    RB = RigidBody('RB', B_cm, B, M_B, (J_B, B_cm))
    T_z, F_z = dynamicsymbols('T_z F_z')
    force_list = [(RB.masscenter, RB.mass*S('g')*NED.z), (RB.frame, T_z*B.z),
                  (RB.masscenter, F_z*B.z)]
    KM.kanes_equations([RB], force_list)
    consts = {M_B: 1.5, S('g'): 9.81, S('J_B_xx'): 0.1, S('J_B_yy'): 0.12, S('J_B_zz'): 0.2,
              S('J_B_xz'): 0.01}
    return KM, consts, [T_z, F_z]


def model(name="quaternion_body"):
    km, consts, inputs = derive()
    return gen.Model.from_kanes(km, constants=consts, inputs=inputs, name=name)
