"""A quadrotor with ZYX Euler angles and body rates (examples/quadrotor.py):
the kinematic equations are taken in their implicit form and solved for q'
at run time, never through sympy's symbolic solve (0/0 at hover here).

- at hover, sympy's kinematics (KanesMethod explicit and implicit) linearize
  exactly like hand-written Euler-rate equations, and A holds the textbook
  couplings: x'' = g theta, y'' = -g phi, p' = tau1/Ixx, z'' = T/m;
- the three formulations fly the same 5 s with constant torques;
- at pitch +-90 degrees the status names the kinematics.
"""
import numpy as np
import pytest

import gen
import quadrotor as qr


@pytest.fixture(scope="module")
def sims():
    return {"sympy": gen.compile(qr.model("sympy", True, name="quad_sympy")),
            "sympy_implicit": gen.compile(qr.model("sympy", False, name="quad_implicit")),
            "euler": gen.compile(qr.model("euler", name="quad_euler"))}


def test_hover_linearization_matches_hand_written_euler_rates(sims):
    x, r = np.zeros(12), qr.hover_input()
    A0, B0 = sims["euler"].linearize(x, r=r)
    for k in ("sympy", "sympy_implicit"):
        A, B = sims[k].linearize(x, r=r)
        assert np.max(np.abs(A - A0)) <= 1e-12 and np.max(np.abs(B - B0)) <= 1e-12, k
    # the independent state is [psi, theta, phi, x, y, z, p, q, r, vx, vy, vz]
    g, m, I = qr.DEFAULTS["g"], qr.DEFAULTS["m"], qr.DEFAULTS
    assert A0[9, 1] == pytest.approx(g, rel=1e-14)            # vx' = g theta
    assert A0[10, 2] == pytest.approx(-g, rel=1e-14)          # vy' = -g phi
    assert np.allclose(A0[:6, 6:], np.eye(6)[[2, 1, 0, 3, 4, 5]], atol=1e-15)  # psi'=r, theta'=q, phi'=p
    assert B0[11, 0] == pytest.approx(1 / m, rel=1e-14)
    assert B0[6, 1] == pytest.approx(1 / I["Ixx"], rel=1e-14)
    assert B0[7, 2] == pytest.approx(1 / I["Iyy"], rel=1e-14)
    assert B0[8, 3] == pytest.approx(1 / I["Izz"], rel=1e-14)


def test_free_flight_agrees(sims):
    x0 = np.array([0.3, -0.2, 0.1, 0.0, 0.0, 1.0, 0.5, -0.3, 0.2, 0.1, 0.2, 0.0])
    r = [12.0, 0.001, -0.002, 0.0005]
    _, X0 = sims["euler"].simulate(x0, 5.0, 1e-3, r=r)
    assert np.abs(X0[-1, :3]).max() > 0.5            # it really tumbles
    for k in ("sympy", "sympy_implicit"):
        _, X = sims[k].simulate(x0, 5.0, 1e-3, r=r)
        assert np.max(np.abs(X - X0)) <= 1e-9, k


@pytest.mark.parametrize("pitch", [np.pi / 2, -np.pi / 2])
def test_gimbal_lock_names_the_kinematics(sims, pitch):
    x = np.zeros(12)
    x[1] = pitch
    for k in ("sympy", "sympy_implicit"):
        with pytest.raises(gen.SingularError) as e:
            sims[k].rhs(0.0, x)
        assert e.value.status_name == "ERR_SINGULAR_KINEMATICS"
        assert "singular kinematic equations" in str(e.value)
        with pytest.raises(gen.SingularError, match="kinematic"):
            sims[k].linearize(x, r=qr.hover_input())


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_solves_the_kinematics_too(sims):
    from conftest import require_eigen
    require_eigen()
    sim_e = gen.compile(qr.model("sympy", False, name="quad_implicit"), backend="eigen")
    x, r = np.zeros(12), qr.hover_input()
    A, B = sim_e.linearize(x, r=r)
    A0, B0 = sims["sympy_implicit"].linearize(x, r=r)
    assert np.max(np.abs(A - A0)) <= 1e-12 and np.max(np.abs(B - B0)) <= 1e-12
    x[1] = np.pi / 2
    with pytest.raises(gen.SingularError) as e:
        sim_e.rhs(0.0, x)
    assert e.value.status_name == "ERR_SINGULAR_KINEMATICS"
