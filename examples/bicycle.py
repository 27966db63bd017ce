"""The Whipple (Carvallo-Whipple) bicycle, checked against the benchmark of
Meijaard, Papadopoulos, Ruina and Schwab, "Linearized dynamics equations for
the balance and steer of a bicycle: a benchmark and review", Proc. R. Soc. A
463 (2007) 1955-1982, doi:10.1098/rspa.2007.1857.

Four rigid bodies (rear frame with rider C, rear wheel D, front frame E, front
wheel F), knife-edge wheels rolling without slip on flat ground. Moore's
formulation and parameters (J. K. Moore, "Human control of a bicycle", PhD
dissertation, UC Davis 2012; PyDy's Carvallo-Whipple example uses the same),
derived here with ``KanesMethod`` in the structure of sympy's own
``test_kane3.py::test_bicycle`` (which ports a different, Autolev
parameterization):

- N inertial (z down, gravity +g N.z), A yaw (q3 about N.z), B roll (q4 about
  A.x), C rear-frame pitch (q5 about B.y), D rear wheel (q6 about C.y), E steer
  (q7 about C.z, the steer axis), F front wheel (q8 about E.y);
  q1, q2: rear contact point in the ground plane.
- u = q' for all eight coordinates. Independent speeds: roll u4, rear wheel u6,
  steer u7. Dependent: u1, u2, u3 (yaw), u5 (pitch), u8 (front wheel), from five
  nonholonomic constraints (no slip at both contacts, A.x and A.y; the front
  contact's vertical velocity, the time derivative of the holonomic
  constraint). The pitch q5 is the dependent coordinate of the holonomic
  constraint (the front wheel touches the ground).
- Geometry: d1 (rear wheel centre to the steer axis, perpendicular), d2 (along
  the steer axis between the two perpendiculars), d3 (front wheel centre to the
  steer axis), wheel radii rr, rf; mass centres l1, l2 (rear frame, from the
  rear wheel centre in C), l3, l4 (front frame, from the front wheel centre in
  E); inertias in C (ic..) and E (ie..), wheels id11 = id33, id22 and if11,
  if22; masses mc, md, me, mf; g.
- Inputs: roll torque T4 (on the rear frame about A.x, Meijaard's T_phi), rear
  wheel torque T6 (between rear frame and wheel), steer torque T7 (between
  rear and front frame, Meijaard's T_delta).

Upright rolling at speed v: q4 = q7 = 0, q5 = lambda (the steer axis tilt:
C.z is the steer axis), u6 = -v / rr, dependent speeds from the constraints.
The linearization on [q1 q2 q3 q4 q6 q7 q8 | u4 u6 u7] holds Meijaard's
lean/steer model in the rows and columns of (q4, q7, u4, u7); the other six
eigenvalues are zero (ignorable coordinates and the constant wheel rate).

Run ``python examples/bicycle.py`` for the eigenvalues against speed, the weave
and capsize speeds next to Meijaard's, and the timings of each step.

What was measured building it (sympy 1.14, 2 busy cores; times vary 2x
with the load):

- sympy is not the slow part of building the model: the constrained
  ``KanesMethod(...)`` takes 1.2-3 s, ``kanes_equations`` 2-6 s,
  ``Model.from_kanes`` (which forms the unconstrained equations again from
  ``km.bodies``/``km.loads`` and ignores sympy's elimination) 3-10 s,
  ``gen.compile`` 14-43 s from an empty cache (kernel generation 5-17 s, gcc
  7-23 s), ``sim.linearize`` 15-25 us a call. sympy's own linearization is
  the slow step: ``KM.to_linearizer()`` alone takes 52 s.
- sympy's symbolic elimination of the dependent speeds (the default
  ``constraint_solver='LU'``, no pivoting on symbolic entries) depends on the
  order of the velocity constraints. Written as (rear x, rear y, front x,
  front y, front z) against (u1, u2, u3, u5, u8), the fourth pivot vanishes
  on the whole constraint manifold (1e-14 at every consistent state, 1 off
  it): ``KM.mass_matrix``/``KM.forcing`` are NaN upright and rounding noise
  elsewhere (accelerations 40 % off, energy not conserved). In the order
  used here, (rear x, rear y, front z, front y, front x) against (u1, u2, u5,
  u3, u8), the pivots are about (1, 1, -w, w, rf) and sympy's equations agree
  with eomgen's to 1e-14 (tests/physics/test_bicycle.py). eomgen's numbers do not
  depend on that order: it eliminates with a pivoted LU at run time.
"""
import math
import time

import numpy as np
import sympy as sm
from sympy.physics import mechanics as mec

import gen

# Meijaard et al. 2007, Table 1: the benchmark bicycle.
BENCHMARK = {
    "w": 1.02, "c": 0.08, "lam": math.pi / 10, "g": 9.81,
    "rR": 0.3, "mR": 2.0, "IRxx": 0.0603, "IRyy": 0.12,
    "xB": 0.3, "zB": -0.9, "mB": 85.0,
    "IBxx": 9.2, "IByy": 11.0, "IBzz": 2.8, "IBxz": 2.4,
    "xH": 0.9, "zH": -0.7, "mH": 4.0,
    "IHxx": 0.05892, "IHyy": 0.06, "IHzz": 0.00708, "IHxz": -0.00756,
    "rF": 0.35, "mF": 3.0, "IFxx": 0.1405, "IFyy": 0.28,
}

MOORE_NAMES = ("d1 d2 d3 rr rf l1 l2 l3 l4 mc md me mf ic11 ic22 ic33 ic31 "
               "id11 id22 ie11 ie22 ie33 ie31 if11 if22 g").split()


def benchmark_to_moore(p=None):
    """Moore's parameters from Meijaard's (a dict with the keys of
    BENCHMARK; missing keys take the benchmark values).

    Meijaard's axes at the upright reference: x forward, y right, z down,
    rear contact at the origin; the steer axis, tilted back by lam, meets the
    ground at x = w + c and points down along s = (sin lam, 0, cos lam). At
    pitch q5 = lam Moore's rear frame has C.z = s and C.x = (cos lam, 0,
    -sin lam), so every length is a projection on C.x or C.z and every
    inertia a rotation about y by lam."""
    b = dict(BENCHMARK, **(p or {}))
    w, c, lam, rR, rF = b["w"], b["c"], b["lam"], b["rR"], b["rF"]
    cl, sl = math.cos(lam), math.sin(lam)
    ex = np.array([cl, 0.0, -sl])      # C.x in Meijaard's axes
    ez = np.array([sl, 0.0, cl])       # C.z: the steer axis, downwards
    rear = np.array([0.0, 0.0, -rR])   # rear wheel centre
    front = np.array([w, 0.0, -rF])    # front wheel centre
    axis = np.array([w + c, 0.0, 0.0])  # steer axis at the ground
    # rear centre + d1 C.x lies on the steer axis; so does front - d3 C.x
    d1 = -float((rear - axis) @ ex)
    d3 = float((front - axis) @ ex)
    d2 = float((front - rear) @ ez)
    rB = np.array([b["xB"], 0.0, b["zB"]]) - rear
    rH = np.array([b["xH"], 0.0, b["zH"]]) - front
    Rot = np.vstack([ex, [0.0, 1.0, 0.0], ez])   # rows: C axes in Meijaard's

    def rotate(Ixx, Iyy, Izz, Ixz):
        I = np.array([[Ixx, 0.0, Ixz], [0.0, Iyy, 0.0], [Ixz, 0.0, Izz]])
        return Rot @ I @ Rot.T

    IC = rotate(b["IBxx"], b["IByy"], b["IBzz"], b["IBxz"])
    IE = rotate(b["IHxx"], b["IHyy"], b["IHzz"], b["IHxz"])
    return {
        "d1": d1, "d2": d2, "d3": d3, "rr": rR, "rf": rF,
        "l1": float(rB @ ex), "l2": float(rB @ ez),
        "l3": float(rH @ ex), "l4": float(rH @ ez),
        "mc": b["mB"], "md": b["mR"], "me": b["mH"], "mf": b["mF"],
        "ic11": float(IC[0, 0]), "ic22": float(IC[1, 1]), "ic33": float(IC[2, 2]),
        "ic31": float(IC[2, 0]),
        "id11": b["IRxx"], "id22": b["IRyy"],
        "ie11": float(IE[0, 0]), "ie22": float(IE[1, 1]), "ie33": float(IE[2, 2]),
        "ie31": float(IE[2, 0]),
        "if11": b["IFxx"], "if22": b["IFyy"], "g": b["g"],
    }


def derive(kanes_equations=True, constraint_solver="LU", timings=None):
    """(KanesMethod, symbols) of the Whipple bicycle.

    kanes_equations=False returns the method before ``kanes_equations``
    (the bodies and loads are in the symbols dict). constraint_solver:
    KanesMethod's, for sympy's own elimination of the dependent speeds
    (eomgen does not use it). timings: a dict that receives the seconds of
    each sympy step."""
    tick = time.perf_counter()
    q1, q2, q3, q4, q5, q6, q7, q8 = q = mec.dynamicsymbols("q1:9")
    u1, u2, u3, u4, u5, u6, u7, u8 = u = mec.dynamicsymbols("u1:9")
    T4, T6, T7 = mec.dynamicsymbols("T4 T6 T7")
    p = dict(zip(MOORE_NAMES, sm.symbols(MOORE_NAMES, real=True)))
    d1, d2, d3, rr, rf = (p[k] for k in ("d1", "d2", "d3", "rr", "rf"))
    l1, l2, l3, l4 = (p[k] for k in ("l1", "l2", "l3", "l4"))
    mc, md, me_, mf, g = (p[k] for k in ("mc", "md", "me", "mf", "g"))

    N = mec.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q3, N.z])      # yaw
    B = A.orientnew("B", "Axis", [q4, A.x])      # roll
    C = B.orientnew("C", "Axis", [q5, B.y])      # rear frame pitch
    D = C.orientnew("D", "Axis", [q6, C.y])      # rear wheel
    E = C.orientnew("E", "Axis", [q7, C.z])      # steer, about the steer axis
    F = E.orientnew("F", "Axis", [q8, E.y])      # front wheel
    A.set_ang_vel(N, u3 * N.z)
    B.set_ang_vel(A, u4 * A.x)
    C.set_ang_vel(B, u5 * B.y)
    D.set_ang_vel(C, u6 * C.y)
    E.set_ang_vel(C, u7 * C.z)
    F.set_ang_vel(E, u8 * E.y)

    O = mec.Point("O")
    O.set_vel(N, 0)
    dn = O.locatenew("dn", q1 * N.x + q2 * N.y)          # rear contact (geometric)
    dn.set_vel(N, u1 * N.x + u2 * N.y)
    do = dn.locatenew("do", -rr * B.z)                   # rear wheel centre
    do.v2pt_theory(dn, N, B)
    co = do.locatenew("co", l1 * C.x + l2 * C.z)         # rear frame mass centre
    co.v2pt_theory(do, N, C)
    ce = do.locatenew("ce", d1 * C.x)                    # on the steer axis
    ce.v2pt_theory(do, N, C)
    fo = ce.locatenew("fo", d2 * E.z + d3 * E.x)         # front wheel centre
    fo.v2pt_theory(ce, N, E)
    eo = fo.locatenew("eo", l3 * E.x + l4 * E.z)         # front frame mass centre
    eo.v2pt_theory(fo, N, E)
    # front contact: from the wheel centre, down in the wheel plane
    fn = fo.locatenew("fn", rf * E.y.cross(A.z).cross(E.y).normalize())
    fn.v2pt_theory(fo, N, F)                             # the wheel's material point

    # no slip: the wheels' material points at the contacts are at rest
    v_rear = do.vel(N) + D.ang_vel_in(N).cross(dn.pos_from(do))
    v_front = fn.vel(N)
    # in the order of the dependent speeds [u1, u2, u5, u3, u8] they solve
    # for: each pivot of sympy's (unpivoted, symbolic) LU elimination is then
    # regular (about 1, 1, -w, w, rf upright); see the module docstring
    f_v = sm.Matrix([v_rear.dot(A.x), v_rear.dot(A.y),
                     v_front.dot(A.z), v_front.dot(A.y), v_front.dot(A.x)])
    # holonomic: the front contact is on the ground
    f_c = sm.Matrix([fn.pos_from(dn).dot(A.z)])

    IC = mec.inertia(C, p["ic11"], p["ic22"], p["ic33"], 0, 0, p["ic31"])
    IE = mec.inertia(E, p["ie11"], p["ie22"], p["ie33"], 0, 0, p["ie31"])
    # wheels: symmetric about the axle, so their dyadics are written in the
    # frames that do not spin (no q6, q8 in the equations)
    ID = mec.inertia(C, p["id11"], p["id22"], p["id11"])
    IF = mec.inertia(E, p["if11"], p["if22"], p["if11"])
    bodies = [mec.RigidBody("rear_frame", co, C, mc, (IC, co)),
              mec.RigidBody("rear_wheel", do, D, md, (ID, do)),
              mec.RigidBody("front_frame", eo, E, me_, (IE, eo)),
              mec.RigidBody("front_wheel", fo, F, mf, (IF, fo))]
    loads = [(co, mc * g * A.z), (do, md * g * A.z), (eo, me_ * g * A.z),
             (fo, mf * g * A.z),
             (C, T4 * A.x - T6 * C.y - T7 * C.z), (D, T6 * C.y), (E, T7 * C.z)]
    kde = [qi.diff() - ui for qi, ui in zip(q, u)]
    t_setup = time.perf_counter() - tick

    tick = time.perf_counter()
    KM = mec.KanesMethod(N, q_ind=[q1, q2, q3, q4, q6, q7, q8], q_dependent=[q5],
                         u_ind=[u4, u6, u7], u_dependent=[u1, u2, u5, u3, u8],
                         kd_eqs=kde, configuration_constraints=f_c,
                         velocity_constraints=f_v, constraint_solver=constraint_solver)
    t_init = time.perf_counter() - tick
    t_eqs = None
    if kanes_equations:
        tick = time.perf_counter()
        KM.kanes_equations(bodies, loads)
        t_eqs = time.perf_counter() - tick
    if timings is not None:
        timings.update({"kinematics": t_setup, "KanesMethod.__init__": t_init,
                        "kanes_equations": t_eqs})
    qd = {qi.diff(): ui for qi, ui in zip(q, u)}
    energy = sum(bd.kinetic_energy(N) for bd in bodies).xreplace(qd)
    energy -= g * sum(bd.mass * bd.masscenter.pos_from(O).dot(N.z) for bd in bodies)
    syms = dict(p, q=tuple(q), u=tuple(u), T=(T4, T6, T7), N=N, frames=(A, B, C, D, E, F),
                bodies=bodies, loads=loads, f_c=f_c, f_v=f_v, energy=energy,
                points=dict(dn=dn, do=do, co=co, ce=ce, fo=fo, eo=eo, fn=fn))
    return KM, syms


def model(name="bicycle", timings=None, **over):
    """gen.Model of the benchmark bicycle; over: Meijaard's parameters
    (keys of BENCHMARK) or Moore's (MOORE_NAMES), by name."""
    bench = {k: v for k, v in over.items() if k in BENCHMARK}
    moore = {k: v for k, v in over.items() if k in MOORE_NAMES}
    unknown = set(over) - set(bench) - set(moore)
    if unknown:
        raise ValueError(f"unknown parameters {sorted(unknown)}; known: Meijaard's "
                         f"{sorted(BENCHMARK)} or Moore's {MOORE_NAMES}")
    vals = dict(benchmark_to_moore(bench), **moore)
    KM, s = derive(timings=timings)
    tick = time.perf_counter()
    m = gen.Model.from_kanes(KM, constants={s[k]: v for k, v in vals.items()},
                             inputs=list(s["T"]), name=name, energy=s["energy"])
    if timings is not None:
        timings["Model.from_kanes"] = time.perf_counter() - tick
    return m


# ---------------------------------------------------------------- analysis
LEAN_STEER = ("q4", "q7", "u4", "u7")     # Meijaard's (phi, delta, phi', delta')


def upright_pitch(vals=None):
    """The pitch q5 of the upright bicycle (q4 = q7 = 0) from the holonomic
    constraint rf - rr - (d1 + d3) sin q5 + d2 cos q5 = 0, in closed form
    (lam for the benchmark). vals: Moore's parameters (default: benchmark)."""
    v = benchmark_to_moore() if vals is None else vals
    R = math.hypot(v["d1"] + v["d3"], v["d2"])
    return math.atan2(v["d2"], v["d1"] + v["d3"]) + math.asin((v["rf"] - v["rr"]) / R)


def upright_state(sim, v, vals=None, p=None):
    """The consistent state of upright rolling at forward speed v (m/s):
    q = 0 but for the pitch q5, rear wheel rate u6 = -v / rr; the pitch and
    the dependent speeds (u1 = v, u8 = -v / rf, the rest 0) come from
    sim.consistent_state (the closed-form pitch is only its first guess).
    vals: Moore's parameters (default: benchmark), p: sim's constants."""
    vals = benchmark_to_moore() if vals is None else vals
    names = list(sim.state_names)
    x = np.zeros(sim.nx)
    x[names.index("q5")] = upright_pitch(vals)
    x[names.index("u6")] = -v / vals["rr"]
    return sim.consistent_state(x, p=p)


def lean_steer_index(sim):
    """Indices of (q4, q7, u4, u7) in the state of sim.linearize."""
    names = list(sim.independent_state_names)
    return [names.index(n) for n in LEAN_STEER]


def linear_lean_steer(sim, v, vals=None, p=None):
    """(A4, B2, A, B): the linearization about upright rolling at speed v,
    A4 the (q4, q7, u4, u7) block, B2 its (u4, u7) rows against (T4, T7),
    and the full A, B on [q_ind, u_ind]."""
    A, B = sim.linearize(upright_state(sim, v, vals, p), p=p)
    k = lean_steer_index(sim)
    inputs = list(sim.input_names)
    B2 = B[np.ix_(k[2:], [inputs.index("T4"), inputs.index("T7")])]
    return A[np.ix_(k, k)], B2, A, B


def eigenvalues(sim, v, vals=None, p=None):
    """The four lean/steer eigenvalues at speed v, sorted by real part."""
    ev = np.linalg.eigvals(linear_lean_steer(sim, v, vals, p)[0])
    return ev[np.lexsort((ev.imag, ev.real))]


def meijaard_matrices(sim, v=5.0, vals=None, p=None):
    """Meijaard's M, C1, K0, K2 from eomgen's linearization: with
    M q'' + v C1 q' + (g K0 + v^2 K2) q = [T4, T7], the (u4, u7) rows of
    A and B are M^-1 [-(g K0 + v^2 K2), -v C1] and M^-1. Two speeds (0
    and v) separate K0 from K2."""
    g = (benchmark_to_moore() if vals is None else vals)["g"]
    A0, B0 = linear_lean_steer(sim, 0.0, vals, p)[:2]
    Av, Bv = linear_lean_steer(sim, v, vals, p)[:2]
    M = np.linalg.inv(Bv)
    K0 = -(M @ A0[2:, :2]) / g
    K2 = (-(M @ Av[2:, :2]) - g * K0) / v**2
    C1 = -(M @ Av[2:, 2:]) / v
    return M, C1, K0, K2


def critical_speeds(sim, vals=None, p=None, weave_bracket=(3.0, 5.0),
                    capsize_bracket=(5.5, 7.0), xtol=1e-14):
    """(weave speed, capsize speed): where the real part of the weave pair
    and of the capsize eigenvalue cross zero, by brentq on the largest real
    part of the lean/steer eigenvalues (positive below the weave speed, then
    the weave pair's; above, the capsize eigenvalue's)."""
    from scipy.optimize import brentq

    def abscissa(v):
        return float(np.max(eigenvalues(sim, v, vals, p).real))

    vw = brentq(abscissa, *weave_bracket, xtol=xtol, rtol=4 * np.finfo(float).eps)
    vc = brentq(abscissa, *capsize_bracket, xtol=xtol, rtol=4 * np.finfo(float).eps)
    return vw, vc


# Meijaard et al. 2007, Table 2 (p. 1971): the weave and capsize speeds of the
# benchmark (printed with 14 decimals), for the printout below. The tests keep
# their own copy of every published number (tests/physics/test_bicycle.py).
MEIJAARD_WEAVE_SPEED = 4.29238253634111
MEIJAARD_CAPSIZE_SPEED = 6.02426201538837


def main():
    timings = {}
    m = model(timings=timings)
    tick = time.perf_counter()
    sim = gen.compile(m)
    timings["gen.compile"] = time.perf_counter() - tick
    print("sympy / eomgen steps (s):")
    for k, v in timings.items():
        print(f"  {k:22s} {v:8.2f}")
    print("  build_info:", {k: (round(v, 2) if isinstance(v, float) else v)
                            for k, v in sim.build_info.items() if k != "module"})
    x5 = upright_state(sim, 5.0)
    tick = time.perf_counter()
    sim.linearize(x5)         # builds the derivative kernels if compile deferred them
    print(f"  first sim.linearize    {time.perf_counter() - tick:8.2f}")
    calls = []
    for _ in range(1000):
        tick = time.perf_counter()
        sim.linearize(x5)
        calls.append(time.perf_counter() - tick)
    print(f"  sim.linearize          {1e6 * np.median(calls):8.1f} us (median of 1000 calls)")

    print("\nlean/steer eigenvalues of the upright bicycle against forward speed v:")
    np.set_printoptions(linewidth=140)
    for v in np.arange(0.0, 10.01, 0.5):
        ev = eigenvalues(sim, v)
        print(f"  v = {v:5.2f} m/s:  " + "  ".join(f"{e.real:+.6f}{e.imag:+.6f}j" for e in ev))
    tick = time.perf_counter()
    vw, vc = critical_speeds(sim)
    took = time.perf_counter() - tick
    print(f"\n(brentq on the largest real part, {took:.2f} s)")
    print(f"  weave speed   {vw:.14f} m/s   Meijaard et al. 2007: {MEIJAARD_WEAVE_SPEED:.14f}"
          f"   rel. error {abs(vw / MEIJAARD_WEAVE_SPEED - 1):.1e}")
    print(f"  capsize speed {vc:.14f} m/s   Meijaard et al. 2007: {MEIJAARD_CAPSIZE_SPEED:.14f}"
          f"   rel. error {abs(vc / MEIJAARD_CAPSIZE_SPEED - 1):.1e}")
    M, C1, K0, K2 = meijaard_matrices(sim)
    np.set_printoptions(precision=14, suppress=True)
    print("\nMeijaard's M, C1, K0, K2 from the linearization:")
    for name, mat in (("M", M), ("C1", C1), ("K0", K0), ("K2", K2)):
        print(f"  {name} =", mat.tolist())


if __name__ == "__main__":
    main()
