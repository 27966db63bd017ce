import numpy as np
import sympy as sm
from sympy.physics import mechanics as me
import gen
# a pendulum: angle theta from the downward vertical, rate omega, torque T at the pivot
theta, omega, T = me.dynamicsymbols("theta omega T")
m, l, g = sm.symbols("m l g")
N = me.ReferenceFrame("N")
A = N.orientnew("A", "Axis", [theta, N.z])
A.set_ang_vel(N, omega * N.z)
O = me.Point("O"); O.set_vel(N, 0)
P = O.locatenew("P", l * A.x); P.v2pt_theory(O, N, A)
km = me.KanesMethod(N, q_ind=[theta], u_ind=[omega], kd_eqs=[theta.diff() - omega])
km.kanes_equations([me.Particle("bob", P, m)], [(P, m * g * N.x), (A, T * N.z)])

model = gen.Model.from_kanes(km, constants={m: 1.0, l: 0.5, g: 9.81}, inputs=[T], name="pend")
sim = gen.compile(model)                          # C, compiled and loaded (cached by content)
t, X = sim.simulate([0.1, 0.0], 10.0, 1e-3)       # RK4 in C: (10001,), (10001, 2)
A_lin, B_lin = sim.linearize([0.0, 0.0])          # [[0, 1], [-g/l, 0]], [[0], [1/(m l^2)]]
print(np.linalg.eigvals(A_lin))                   # +-4.43j = +-sqrt(g/l) j
