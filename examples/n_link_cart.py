"""The n-link pendulum on a cart, the benchmark model of this field
(the same physics as ``pydy.models.n_link_pendulum_on_cart``): a cart of
mass m0 on a horizontal track, pushed by a force F, carrying a chain of n
point masses m1..mn on massless links of lengths l0..l(n-1).

q = [q0 (cart position), q1..qn (absolute link angles from the upward
vertical)], u = q'. Upright (q = 0) is an unstable equilibrium.
Model file: ``model()`` gives n = 2; ``model(n=8)`` any n.
"""
import sympy as sm
from sympy.physics import mechanics as me

import gen


def defaults(n):
    """Constant values: g, then m0..mn, then l0..l(n-1)."""
    vals = {"g": 9.81}
    vals.update({f"m{i}": 1.0 for i in range(n + 1)})
    vals.update({f"l{i}": 1.0 for i in range(n)})
    return vals


def derive(n=2):
    """Return (KanesMethod, symbols dict) for an n-link pendulum on a cart."""
    if int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    q = me.dynamicsymbols(f"q:{n + 1}")
    u = me.dynamicsymbols(f"u:{n + 1}")
    F = me.dynamicsymbols("F")
    m = sm.symbols(f"m:{n + 1}")
    l = sm.symbols(f"l:{n}")
    g = sm.symbols("g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P0", q[0] * N.x)
    P.set_vel(N, u[0] * N.x)
    particles = [me.Particle("Pa0", P, m[0])]
    loads = [(P, F * N.x - m[0] * g * N.y)]
    cart = P
    for i in range(n):
        B = N.orientnew(f"B{i}", "Axis", [q[i + 1], N.z])
        B.set_ang_vel(N, u[i + 1] * N.z)
        Pi = P.locatenew(f"P{i + 1}", l[i] * B.y)
        Pi.v2pt_theory(P, N, B)
        particles.append(me.Particle(f"Pa{i + 1}", Pi, m[i + 1]))
        loads.append((Pi, -m[i + 1] * g * N.y))
        P = Pi
    kde = [qi.diff() - ui for qi, ui in zip(q, u)]
    KM = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kde)
    KM.kanes_equations(particles, loads)
    energy = sum(pa.kinetic_energy(N) for pa in particles)
    energy += sum(pa.mass * g * pa.point.pos_from(O).dot(N.y) for pa in particles)
    energy = energy.subs({qi.diff(): ui for qi, ui in zip(q, u)})
    syms = dict(q=q, u=u, F=F, m=m, l=l, g=g, frame=N, cart=cart, energy=energy)
    return KM, syms


def model(n=2, name=None, **over):
    KM, s = derive(n)
    by_name = {str(c): c for c in (s["g"], *s["m"], *s["l"])}
    vals = dict(defaults(n), **over)
    unknown = set(vals) - set(by_name)
    if unknown:
        raise ValueError(f"unknown constants {sorted(unknown)}; known: {sorted(by_name)}")
    return gen.Model.from_kanes(KM, constants={by_name[k]: v for k, v in vals.items()},
                                inputs=[s["F"]], name=name or f"cart{n}",
                                energy=s["energy"])
