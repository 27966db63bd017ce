"""A model file for `eomgen build` (tests/robustness/test_wheel.py)."""
import sympy as sm
from sympy.physics import mechanics as me

import gen


def model():
    q, u = me.dynamicsymbols("q u")
    k, m = sm.symbols("k m")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, u * N.x)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u])
    km.kanes_equations([me.Particle("mass", P, m)], [(P, -k * q * N.x)])
    return gen.Model.from_kanes(km, constants={k: 4.0, m: 1.0}, name="wheel_spring")
