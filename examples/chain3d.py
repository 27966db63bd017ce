"""A 3D chain of n rigid rods joined by spherical joints, hanging from a
fixed point (issue 17's "3D chain of rigid bodies"): 3n coordinates and 3n
speeds, 12 bodies by default (36 degrees of freedom, 72 states).

Formulation (the one that keeps sympy's derivation polynomial in n): each
rod's orientation is its own body-fixed 1-2-3 rotation from the ground frame
N (absolute angles q_i1..q_i3, not angles relative to the previous rod), and
its generalized speeds are its angular velocity's components in its own
frame (u_i = w_i . b_i). The velocities then need no Euler rates, and the
kinematic equations Kqd(q) q' = u are implicit (the Euler-rate matrix, solved
numerically in the generated C; singular at q_i2 = +-90 deg, gimbal lock,
reported as ERR_SINGULAR_KINEMATICS).

Rod i: mass m_i, length l_i, inertia (Ixx_i, Iyy_i, Izz_i) about its mass
centre in its own frame (z along the rod); its upper end is the lower end of
rod i - 1 (rod 0 hangs from O). Gravity -g N.z. Hanging at rest (q = 0) is a
stable equilibrium; the twist about each rod's own axis has no restoring
torque (zero eigenvalues), and the swings in the x and y planes are those of
the planar chain of compound pendulums (tests/physics/test_chain3d.py).

Model file: ``model()`` gives n = 12; ``model(n=4)`` any n.
"""
import sympy as sm
from sympy.physics import mechanics as me

import gen


def defaults(n):
    """Uniform slender rods: m = 1 kg, l = 0.5 m, radius 0.02 m."""
    vals = {"g": 9.81}
    for i in range(n):
        m, l, r = 1.0, 0.5, 0.02
        vals.update({f"m{i}": m, f"l{i}": l, f"Ixx{i}": m * (3 * r * r + l * l) / 12,
                     f"Iyy{i}": m * (3 * r * r + l * l) / 12, f"Izz{i}": m * r * r / 2})
    return vals


def derive(n=12):
    """(KanesMethod after kanes_equations, symbols dict) of the n-rod chain."""
    if int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    g = sm.symbols("g")
    m, l = sm.symbols(f"m:{n}"), sm.symbols(f"l:{n}")
    Ixx, Iyy, Izz = (sm.symbols(f"{s}:{n}") for s in ("Ixx", "Iyy", "Izz"))
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    joint = O
    bodies, loads, kdes, qs, us, frames, centres = [], [], [], [], [], [], []
    for i in range(n):
        q = me.dynamicsymbols(f"q{i}_1:4")
        u = me.dynamicsymbols(f"u{i}_1:4")
        B = me.ReferenceFrame(f"B{i}")
        B.orient_body_fixed(N, q, "123")
        w = B.ang_vel_in(N)                 # in the Euler rates
        kdes += [w.dot(B.x) - u[0], w.dot(B.y) - u[1], w.dot(B.z) - u[2]]
        B.set_ang_vel(N, u[0] * B.x + u[1] * B.y + u[2] * B.z)
        G = joint.locatenew(f"G{i}", -l[i] / 2 * B.z)
        G.v2pt_theory(joint, N, B)
        below = joint.locatenew(f"J{i + 1}", -l[i] * B.z)
        below.v2pt_theory(joint, N, B)
        bodies.append(me.RigidBody(f"rod{i}", G, B, m[i],
                                   (me.inertia(B, Ixx[i], Iyy[i], Izz[i]), G)))
        loads.append((G, -m[i] * g * N.z))
        qs += q
        us += u
        frames.append(B)
        centres.append(G)
        joint = below
    KM = me.KanesMethod(N, q_ind=qs, u_ind=us, kd_eqs=kdes)
    KM.kanes_equations(bodies, loads)
    energy = sum(b.kinetic_energy(N) + b.mass * g * b.masscenter.pos_from(O).dot(N.z)
                 for b in bodies)
    syms = dict(q=qs, u=us, g=g, m=m, l=l, Ixx=Ixx, Iyy=Iyy, Izz=Izz, frame=N, origin=O,
                frames=frames, centres=centres, tip=joint, energy=energy)
    return KM, syms


def model(n=12, name=None, **over):
    KM, s = derive(n)
    consts = [s["g"], *s["m"], *s["l"], *s["Ixx"], *s["Iyy"], *s["Izz"]]
    by_name = {str(c): c for c in consts}
    vals = dict(defaults(n), **over)
    unknown = set(vals) - set(by_name)
    if unknown:
        raise ValueError(f"unknown constants {sorted(unknown)}; known: {sorted(by_name)}")
    N, O = s["frame"], s["origin"]
    tip = s["tip"].pos_from(O)
    return gen.Model.from_kanes(
        KM, constants={by_name[k]: v for k, v in vals.items()}, name=name or f"chain{n}",
        energy=s["energy"],
        outputs={"tip_x": tip.dot(N.x), "tip_y": tip.dot(N.y), "tip_z": tip.dot(N.z)})


if __name__ == "__main__":
    import time

    import numpy as np
    n = 12
    t0 = time.perf_counter()
    mdl = model(n)
    t1 = time.perf_counter()
    tm = {}
    sim = gen.compile(mdl, timings=tm)
    t2 = time.perf_counter()
    print(f"{n} rods, {sim.nx} states: derive + extract {t1 - t0:.1f} s, generate + compile "
          f"{t2 - t1:.1f} s ({', '.join(f'{k} {v:.2f}' for k, v in tm.items() if k != 'cached')})")
    x0 = np.zeros(sim.nx)
    x0[0], x0[3 + 1] = 0.4, -0.3             # rod 0 swung about x, rod 1 about y
    t, X = sim.simulate(x0, 2.0, 1e-3)
    E = np.array([sim.energy(x) for x in X])
    print(f"2 s RK4 at 1 ms: relative energy drift {np.max(np.abs(E - E[0])) / abs(E[0]):.2e}, "
          f"tip at t = 2: {sim.outputs(t[-1], X[-1])}")
    A, B = sim.linearize(np.zeros(sim.nx))
    w = np.sort(np.sqrt(np.abs(np.linalg.eigvals(A).real ** 2 + np.linalg.eigvals(A).imag ** 2)))
    print("lowest swing frequencies (rad/s):", np.unique(np.round(w[w > 1e-6], 6))[:6])
