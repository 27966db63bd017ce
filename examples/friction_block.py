"""A block sliding on the ground with Coulomb friction on its normal force
(sympy's test_system_class.test_box_on_ground): a particle of mass m at
position q on the ground, pushed by a force F along the ground, friction
-mu N against the motion (sliding forward), gravity -m g. The vertical
speed ua is an auxiliary speed: the normal force N acts along it and is
found in sympy's auxiliary equation N - m g = 0. N also enters the motion
through the friction, so eomgen solves u' and N together:

    u' = F/m - mu g,    N = m g.

    python examples/friction_block.py                   # simulate, print N
    eomgen simulate examples/friction_block.py --t-end 1 --x0 u=0.5 \\
        --input F=4 --csv block.csv                     # the N column is m g
"""
import argparse

import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen

DEFAULTS = {"m": 1.7, "g": 9.81, "mu": 0.3}


def derive():
    """(sympy System, F, N, constants {symbol: value}) of the block."""
    t = me.dynamicsymbols._t
    g, m, mu = sm.symbols("g m mu")
    q, u, ua = me.dynamicsymbols("q u ua")
    N, F = me.dynamicsymbols("N F")
    P = me.Particle("P", mass=m)
    system = me.System()
    system.add_bodies(P)
    P.masscenter.set_pos(system.fixed_point, q * system.x)
    P.masscenter.set_vel(system.frame, u * system.x + ua * system.y)
    system.q_ind, system.u_ind, system.u_aux = [q], [u], [ua]
    system.kdes = [q.diff(t) - u]
    system.apply_uniform_gravity(-g * system.y)
    system.add_loads(me.Force(P, N * system.y), me.Force(P, F * system.x - mu * N * system.x))
    system.validate_system()
    system.form_eoms()
    return system, F, N, {g: DEFAULTS["g"], m: DEFAULTS["m"], mu: DEFAULTS["mu"]}


def model():
    """The gen.Model: state [q, u], input F, the reaction N
    (sim.auxiliary_forces, the CSV's N column)."""
    system, F, _, consts = derive()
    return gen.Model.from_kanes(system, constants=consts, inputs=[F], name="friction_block")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--force", type=float, default=8.0, help="the push F [N]")
    ap.add_argument("--t-end", type=float, default=1.0)
    a = ap.parse_args(argv)
    sim = gen.compile(model())
    m, g, mu = DEFAULTS["m"], DEFAULTS["g"], DEFAULTS["mu"]
    t, X = sim.simulate([0.0, 0.5], a.t_end, 0.01, r=[a.force])
    N = np.array([sim.auxiliary_forces(ti, xi, r=[a.force]) for ti, xi in zip(t, X)])[:, 0]
    accel = (X[-1, 1] - X[0, 1]) / (t[-1] - t[0])
    print(f"u' = {accel:.12g} (F/m - mu g = {a.force / m - mu * g:.12g})")
    print(f"N  = {N.min():.12g} .. {N.max():.12g} (m g = {m * g:.12g})")
    return accel, N


if __name__ == "__main__":
    main()
