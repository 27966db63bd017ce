"""Issue 8, name hygiene: symbols named like C keywords and C library
functions, or holding characters C does not allow (a prime, brackets, a
dot, a comment terminator, a quote, unicode), and names that collide
after sanitizing, still generate correct code; the generated files use
the sanitized identifiers and the header documents the mapping."""
import os
import subprocess

import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen
from gen.intake.model import c_name, c_names
from helpers import rel_err


def test_c_name_rules():
    assert c_name("theta'") == "theta_p"
    assert c_name("x[0]") == "x_0"
    assert c_name("a.b") == "a_b"
    assert c_name("θ") == "u03b8"
    assert c_name("1abc") == "_1abc"
    assert c_name("a*/b") == "a_b"
    assert c_name('"q"') == "q"
    assert c_names(["a.b", "a_b", "a b"]) == ["a_b", "a_b_2", "a_b_3"]


@pytest.fixture(scope="module")
def hostile():
    """A damped, sprung particle in the plane with a driving force; every
    name is hostile."""
    qa, qb = me.dynamicsymbols("x[0] θ")
    ua, ub = me.dynamicsymbols("y0 theta'")
    F = me.dynamicsymbols("int")
    mass, k, c, g, ab1, ab2, cm = sm.symbols('gamma exp time index a.b a_b a*/b')
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", qa * N.x + qb * N.y)
    P.set_vel(N, ua * N.x + ub * N.y)
    loads = [(P, (-k * qa - c * ua + F + ab1 - ab2 * cm) * N.x
              + (-k * qb - c * ub - mass * g) * N.y)]
    KM = me.KanesMethod(N, q_ind=[qa, qb], u_ind=[ua, ub],
                        kd_eqs=[qa.diff() - ua, qb.diff() - ub])
    KM.kanes_equations([me.Particle("pa", P, mass)], loads)
    vals = {mass: 2.0, k: 3.0, c: 0.5, g: 9.81, ab1: 0.25, ab2: 0.75, cm: 1.5}
    model = gen.Model.from_kanes(KM, constants=vals, inputs=[F], name="hostile")
    return KM, model, vals, (qa, qb, ua, ub, F)


def test_hostile_names_sanitized_and_unique(hostile):
    _, model, _, _ = hostile
    assert model.state_names == ["x_0", "u03b8", "y0", "theta_p"]
    assert model.state_labels == ["x[0]", "θ", "y0", "theta'"]
    assert model.input_names == ["int"]
    assert model.constant_names == ["gamma", "exp", "time", "index", "a_b", "a_b_2", "a_b_3"]


def test_hostile_names_compile_and_compute(hostile, tmp_path):
    KM, model, vals, (qa, qb, ua, ub, F) = hostile
    paths = gen.generate(model, tmp_path)
    for path in paths:
        if path.suffix == ".c":
            proc = subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic",
                                   "-c", str(path), "-o", os.devnull, "-I", str(tmp_path)],
                                  capture_output=True, text=True)
            assert proc.returncode == 0, proc.stderr
    sim = gen.compile(model)
    rhs = sm.lambdify([qa, qb, ua, ub, F], KM.mass_matrix_full.LUsolve(KM.forcing_full)
                      .xreplace(vals), "numpy")
    rng = np.random.default_rng(0)
    for _ in range(5):
        x = rng.uniform(-1, 1, 4)
        r = rng.uniform(-1, 1)
        assert rel_err(sim.rhs(0.0, x, r=[r]), np.ravel(rhs(*x, r)).astype(float)) < 1e-14
    # dict access by the sanitized names and by the sympy spelling
    x1 = sim.consistent_state({"x_0": 0.3, "θ": -0.2, "theta_p": 1.0})
    assert list(x1) == [0.3, -0.2, 0.0, 1.0]
    A, _ = sim.linearize({"x[0]": 0.0, "u03b8": 0.0}, r=[0.0])
    assert np.allclose(sorted(np.linalg.eigvals(A).real), [-0.125] * 4, atol=1e-12)


def test_header_documents_the_name_mapping(hostile, tmp_path):
    _, model, _, _ = hostile
    gen.generate(model, tmp_path)
    h = (tmp_path / "hostile.h").read_text()
    assert "x[0] = x_0  (coordinate, independent; sympy: x[0])" in h
    assert "x[3] = theta_p  (speed, independent; sympy: theta')" in h
    assert "u03b8" in h and "sympy: θ" in h
    assert "a_b_3" in h and "sympy: a*\\/b" in h           # no comment terminator
    assert "r[0] = int" in h


def _double_pendulum(names):
    """A double pendulum (point masses, rods, a torsional spring at the
    pivot) with every symbol named as given."""
    q1, q2 = me.dynamicsymbols(f"{names['q1']} {names['q2']}")
    u1, u2 = me.dynamicsymbols(f"{names['u1']} {names['u2']}")
    m1, m2, l1, l2, g, k = (sm.Symbol(names[s]) for s in ("m1", "m2", "l1", "l2", "g", "k"))
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = N.orientnew("B", "Axis", [q2, N.z])
    A.set_ang_vel(N, u1 * N.z)
    B.set_ang_vel(N, u2 * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P1 = O.locatenew("P1", -l1 * A.y)
    P1.v2pt_theory(O, N, A)
    P2 = P1.locatenew("P2", -l2 * B.y)
    P2.v2pt_theory(P1, N, B)
    KM = me.KanesMethod(N, q_ind=[q1, q2], u_ind=[u1, u2],
                        kd_eqs=[q1.diff() - u1, q2.diff() - u2])
    KM.kanes_equations([me.Particle("p1", P1, m1), me.Particle("p2", P2, m2)],
                       [(P1, -m1 * g * N.y), (P2, -m2 * g * N.y), (A, -k * q1 * N.z)])
    vals = {m1: 1.0, m2: 0.7, l1: 1.2, l2: 0.8, g: 9.81, k: 2.5}
    return gen.Model.from_kanes(KM, constants=vals, name=names["name"])


@pytest.mark.slow
def test_double_pendulum_with_hostile_names_linearizes_like_plain():
    """Issue 8: int, double, y0, j1, gamma, lambda, E, I, x[0], theta'."""
    hostile = dict(q1="x[0]", q2="theta'", u1="int", u2="double", m1="y0", m2="j1",
                   l1="gamma", l2="lambda", g="E", k="I", name="dp_hostile")
    plain = dict(q1="q1", q2="q2", u1="u1", u2="u2", m1="m1", m2="m2", l1="l1", l2="l2",
                 g="g", k="k", name="dp_plain")
    mh, mp = _double_pendulum(hostile), _double_pendulum(plain)
    assert mh.state_names == ["x_0", "theta_p", "int", "double"]
    assert mh.constant_names == ["y0", "j1", "gamma", "lambda", "E", "I"]
    sh, sp_ = gen.compile(mh), gen.compile(mp)
    rng = np.random.default_rng(3)
    for x in [np.zeros(4)] + [rng.uniform(-1, 1, 4) for _ in range(5)]:
        Ah, _ = sh.linearize(x)
        Ap, _ = sp_.linearize(x)
        assert np.array_equal(Ah, Ap)
        assert np.array_equal(sh.rhs(0.0, x), sp_.rhs(0.0, x))
    # and it is the physics: hanging at rest, small-oscillation frequencies
    # from the 2x2 generalized eigenproblem of K and M
    A, _ = sh.linearize(np.zeros(4))
    m1, m2, l1, l2, g, k = 1.0, 0.7, 1.2, 0.8, 9.81, 2.5
    M = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2], [m2 * l1 * l2, m2 * l2**2]])
    K = np.array([[(m1 + m2) * g * l1 + k, 0.0], [0.0, m2 * g * l2]])
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)
    lam = np.linalg.eigvals(A)
    assert np.max(np.abs(lam.real)) < 1e-9
    w2_A = np.sort(lam.imag[lam.imag > 0] ** 2)
    assert np.allclose(w2_A, w2, rtol=1e-9)
