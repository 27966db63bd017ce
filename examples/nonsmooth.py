"""Non-smooth models: quadratic drag, Coulomb friction, and sympy's own
``CoulombKineticFriction`` actuator (its docstring example).

    eomgen simulate examples/nonsmooth.py --t-end 3 --x0 v=0          # drag_model
    eomgen simulate examples/nonsmooth.py:friction_model --x0 v=2
    eomgen linearize examples/nonsmooth.py:actuator_model --at x=0.5

Each function returns a ``gen.Model``; ``derive_*`` return the formed
``KanesMethod`` and its symbols, for tests that need the sympy objects.
"""
import sympy as sm
from sympy.physics import mechanics as me

import gen

DRAG = {"m": 2.0, "g": 9.81, "c": 0.5}          # terminal speed sqrt(m g / c) = 6.264 m/s
FRICTION = {"m": 2.0, "g": 9.81, "mu": 0.3}
ACTUATOR = {"m": 1.0, "g": 9.81, "k": 40.0, "mu_k": 0.2, "v_s": 0.1, "sigma": 0.5}


def _particle_on_line(name):
    x, v = me.dynamicsymbols("x v")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew(name, x * N.x)
    P.set_vel(N, v * N.x)
    return x, v, N, P


def derive_drag():
    """A particle falling (along +x) with quadratic drag -c |v| v."""
    m, g, c = sm.symbols("m g c", positive=True)
    x, v, N, P = _particle_on_line("P")
    KM = me.KanesMethod(N, q_ind=[x], u_ind=[v], kd_eqs=[x.diff() - v])
    KM.kanes_equations([me.Particle("ball", P, m)], [(P, (m * g - c * sm.Abs(v) * v) * N.x)])
    return KM, {"x": x, "v": v, "m": m, "g": g, "c": c}


def derive_friction():
    """A block sliding on a floor with Coulomb friction -mu m g sign(v)."""
    m, g, mu = sm.symbols("m g mu", positive=True)
    x, v, N, P = _particle_on_line("P")
    KM = me.KanesMethod(N, q_ind=[x], u_ind=[v], kd_eqs=[x.diff() - v])
    KM.kanes_equations([me.Particle("block", P, m)], [(P, -mu * m * g * sm.sign(v) * N.x)])
    return KM, {"x": x, "v": v, "m": m, "g": g, "mu": mu}


def derive_actuator():
    """sympy's CoulombKineticFriction docstring example: a block on a spring
    with kinetic friction (mu_s = mu_k: no Stribeck term) and viscous
    friction. Its forcing is
    -k x + (-g m mu_k sign(v sign(x)) - sigma v sign(x)) x/|x|
    (undefined at x = 0 exactly, as sympy's expression is)."""
    from sympy.physics.mechanics import CoulombKineticFriction, LinearPathway, LinearSpring
    x, v = me.dynamicsymbols("x, v", real=True)
    m, g, k, mu_k, v_s, sigma = sm.symbols("m, g, k, mu_k, v_s, sigma")
    N = me.ReferenceFrame("N")
    O, P = me.Point("O"), me.Point("P")
    O.set_vel(N, 0)
    P.set_pos(O, x * N.x)
    pathway = LinearPathway(O, P)
    friction = CoulombKineticFriction(mu_k, m * g, pathway, v_s=v_s, sigma=sigma, mu_s=mu_k)
    spring = LinearSpring(k, pathway)
    block = me.Particle("block", point=P, mass=m)
    KM = me.KanesMethod(N, (x,), (v,), kd_eqs=(x.diff() - v,))
    KM.kanes_equations([block], friction.to_loads() + spring.to_loads())
    return KM, {"x": x, "v": v, "m": m, "g": g, "k": k, "mu_k": mu_k, "v_s": v_s,
                "sigma": sigma}


def _model(derive, values, name):
    KM, s = derive()
    # a constant that the expressions do not use (v_s without a Stribeck term) is
    # still a parameter; give only those that appear
    used = set().union(*(e.free_symbols for e in KM.forcing)) | KM.mass_matrix.free_symbols
    return gen.Model.from_kanes(KM, constants={s[k]: v for k, v in values.items() if s[k] in used},
                                name=name)


def drag_model():
    return _model(derive_drag, DRAG, "drag")


def friction_model():
    return _model(derive_friction, FRICTION, "coulomb_block")


def actuator_model():
    return _model(derive_actuator, ACTUATOR, "kinetic_friction")


model = drag_model
