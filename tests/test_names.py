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
from gen.model import c_name, c_names
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
        assert rel_err(sim.rhs(0.0, x, [r]), np.ravel(rhs(*x, r)).astype(float)) < 1e-14
    # dict access by the sanitized names and by the sympy spelling
    x1 = sim.consistent_state({"x_0": 0.3, "θ": -0.2, "theta_p": 1.0})
    assert list(x1) == [0.3, -0.2, 0.0, 1.0]
    A, _ = sim.linearize({"x[0]": 0.0, "u03b8": 0.0}, r_op=[0.0])
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
