"""A constrained body with implicit kinematics: the quadrotor's ZYX Euler
angles and body rates (examples/quadrotor.py) with a skate constraint, the
velocity of the mass centre along the body x axis is zero (vx dependent).

The acceleration constraint's term a = d/dt(A u + b) - A u' holds q'. With
sympy's kinematics q' must come from the implicit equations Kqd q' = kr:
sympy's symbolic solve of them is 0/0 at hover, so the generator keeps q'
as a run-time quantity there too (the runtime solves the kinematics, then
evaluates a at that q'). Reference: the same model with the textbook
Euler-rate equations written by hand (q' explicit, no division at hover).
"""
import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen

t = me.dynamicsymbols._t
DEFAULTS = {"m": 1.2, "g": 9.81, "Ixx": 0.02, "Iyy": 0.025, "Izz": 0.04}


def skate(kinematics="sympy", explicit_kinematics=True, name="skate"):
    psi, theta, phi, x, y, z = me.dynamicsymbols("psi theta phi x y z")
    p, q, r, vx, vy, vz = me.dynamicsymbols("p q r vx vy vz")
    T, tau1, tau2, tau3 = me.dynamicsymbols("T tau1 tau2 tau3")
    m, g, Ixx, Iyy, Izz = sm.symbols("m g Ixx Iyy Izz")
    N = me.ReferenceFrame("N")
    B = me.ReferenceFrame("B")
    B.orient_body_fixed(N, (psi, theta, phi), "zyx")
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y + z * N.z)
    if kinematics == "sympy":
        w = B.ang_vel_in(N)
        kd = [w.dot(B.x) - p, w.dot(B.y) - q, w.dot(B.z) - r]
    else:
        kd = [phi.diff(t) - (p + sm.sin(phi) * sm.tan(theta) * q + sm.cos(phi) * sm.tan(theta) * r),
              theta.diff(t) - (sm.cos(phi) * q - sm.sin(phi) * r),
              psi.diff(t) - (sm.sin(phi) / sm.cos(theta) * q + sm.cos(phi) / sm.cos(theta) * r)]
    kd += [x.diff(t) - vx, y.diff(t) - vy, z.diff(t) - vz]
    B.set_ang_vel(N, p * B.x + q * B.y + r * B.z)
    C.set_vel(N, vx * N.x + vy * N.y + vz * N.z)
    body = me.RigidBody("body", C, B, m, (me.inertia(B, Ixx, Iyy, Izz), C))
    loads = [(C, -m * g * N.z + T * B.z), (B, tau1 * B.x + tau2 * B.y + tau3 * B.z)]
    km = me.KanesMethod(N, q_ind=[psi, theta, phi, x, y, z], u_ind=[p, q, r, vy, vz],
                        u_dependent=[vx], velocity_constraints=[C.vel(N).dot(B.x)],
                        kd_eqs=kd, explicit_kinematics=explicit_kinematics)
    km.kanes_equations([body], loads)
    consts = {m: DEFAULTS["m"], g: DEFAULTS["g"], Ixx: DEFAULTS["Ixx"], Iyy: DEFAULTS["Iyy"],
              Izz: DEFAULTS["Izz"]}
    return gen.Model.from_kanes(km, constants=consts, inputs=[T, tau1, tau2, tau3], name=name)


@pytest.fixture(scope="module")
def sims():
    return {"sympy": gen.compile(skate("sympy", True, name="skate_sympy")),
            "sympy_implicit": gen.compile(skate("sympy", False, name="skate_implicit")),
            "euler": gen.compile(skate("euler", name="skate_euler"))}


HOVER_R = [DEFAULTS["m"] * DEFAULTS["g"], 0.0, 0.0, 0.0]


def test_the_generator_keeps_q_prime_symbolic_only_where_it_is_explicit():
    m = skate("sympy", True, name="skate_sympy")
    assert m.qdot is None and m.mv == 1
    # the acceleration-constraint term holds q' as a run-time quantity
    assert m.a.has(*m.qd)
    assert not skate("euler", name="skate_euler").a.has(*m.qd)


def test_rhs_at_hover_and_at_random_states_matches_hand_written_euler_rates(sims):
    ref = sims["euler"]
    rng = np.random.default_rng(4)
    states = [np.zeros(12)] + [rng.uniform(-1, 1, 12) for _ in range(20)]
    for x in states:
        x = ref.consistent_state(x)
        r = np.array(HOVER_R) + rng.uniform(-0.1, 0.1, 4)
        want = ref.rhs(0.0, x, r=r)
        lam0 = ref.multipliers(0.0, x, r=r)
        for k in ("sympy", "sympy_implicit"):
            got = sims[k].rhs(0.0, x, r=r)
            assert np.max(np.abs(got - want)) <= 1e-12 * (1 + np.max(np.abs(want))), (k, x)
            assert np.max(np.abs(sims[k].multipliers(0.0, x, r=r) - lam0)) <= 1e-11, k


def test_linearization_at_hover_matches(sims):
    x = np.zeros(12)
    A0, B0 = sims["euler"].linearize(x, r=HOVER_R)
    assert A0.shape == (11, 11)
    for k in ("sympy", "sympy_implicit"):
        A, B = sims[k].linearize(x, r=HOVER_R)
        assert np.max(np.abs(A - A0)) <= 1e-12 and np.max(np.abs(B - B0)) <= 1e-12, k
    # away from hover, where q' couples the constraint to the attitude
    x = sims["euler"].consistent_state(np.array([0.3, -0.2, 0.4, 0, 0, 1, 0.5, -0.3, 0.2,
                                                 0.0, 0.2, 0.1]))
    A0, B0 = sims["euler"].linearize(x, r=HOVER_R)
    for k in ("sympy", "sympy_implicit"):
        A, B = sims[k].linearize(x, r=HOVER_R)
        assert np.max(np.abs(A - A0)) <= 1e-10 * np.max(np.abs(A0)), k
        assert np.max(np.abs(B - B0)) <= 1e-12 * np.max(np.abs(B0)), k


@pytest.mark.slow
def test_flight_keeps_the_constraint_and_agrees(sims):
    x0 = sims["euler"].consistent_state(np.array([0.3, -0.2, 0.1, 0, 0, 1, 0.5, -0.3, 0.2,
                                                  0.0, 0.2, 0.0]))
    r = [12.0, 0.001, -0.002, 0.0005]
    _, X0 = sims["euler"].simulate(x0, 2.0, 1e-3, r=r)
    for k in ("sympy", "sympy_implicit"):
        _, X = sims[k].simulate(x0, 2.0, 1e-3, r=r)
        assert np.max(np.abs(X - X0)) <= 1e-9, k
        fv = [sims[k].velocity_constraints(xi[:6], xi[6:]) for xi in X]
        assert np.max(np.abs(fv)) < 1e-10


@pytest.mark.slow
def test_verify_against_sympy_and_the_symbolic_linearization(sims):
    report = gen.verify(skate("sympy", False, name="skate_implicit"), samples=5,
                        linearize_samples=2, sim=sims["sympy_implicit"])
    assert report.ok, report.table()


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_evaluates_a_at_the_solved_q_prime(sims):
    from conftest import require_eigen
    require_eigen()
    sim_e = gen.compile(skate("sympy", False, name="skate_implicit"), backend="eigen")
    ref = sims["sympy_implicit"]
    x = ref.consistent_state(np.array([0.3, -0.2, 0.4, 0, 0, 1, 0.5, -0.3, 0.2, 0.0, 0.2, 0.1]))
    for xx in (np.zeros(12), x):
        assert np.max(np.abs(sim_e.rhs(0.0, xx, r=HOVER_R) - ref.rhs(0.0, xx, r=HOVER_R))) < 1e-12
        A, B = sim_e.linearize(xx, r=HOVER_R)
        A0, B0 = ref.linearize(xx, r=HOVER_R)
        assert np.max(np.abs(A - A0)) <= 1e-10 * np.max(np.abs(A0))
        assert np.max(np.abs(B - B0)) <= 1e-12 * np.max(np.abs(B0))
