"""The 3D chain of rigid rods on spherical joints (examples/chain3d.py):
issue 17's large 3D model, checked against independent references.

- the right-hand side against sympy's own Kane equations (M and f of the
  KanesMethod lambdified, the Euler-rate kinematics solved by numpy);
- energy conservation over a 2 s DOPRI5 run (the chain is conservative);
- the linearization at rest against the planar chain of compound pendulums
  (the swings about x and about y decouple from each other and from the
  twists, which have no restoring torque): frequencies from the closed-form
  M and K of a hanging chain of uniform rods, in numpy;
- gimbal lock of one rod's 1-2-3 angles (q_i2 = 90 deg) as
  ERR_SINGULAR_KINEMATICS, not a number.

The fast tier uses 3 rods; the 12-rod chain (36 degrees of freedom) is slow.
"""
import numpy as np
import pytest
import sympy as sm

import gen
from helpers import rel_err

import chain3d


def _planar_frequencies(n, vals):
    """Small-oscillation frequencies of n uniform rods hanging in a plane,
    absolute angles th_i: x_Gi = sum_{k<i} l_k th_k + l_i/2 th_i, so
    M_jk = sum_i m_i a_ij a_ik + I_j delta_jk and K_jj = g sum_i m_i a_ij
    with a_ij = l_j (j < i), l_i / 2 (j = i), 0 (j > i)."""
    m = np.array([vals[f"m{i}"] for i in range(n)])
    l = np.array([vals[f"l{i}"] for i in range(n)])
    inertia = np.array([vals[f"Ixx{i}"] for i in range(n)])
    a = np.zeros((n, n))
    for i in range(n):
        a[i, :i] = l[:i]
        a[i, i] = l[i] / 2
    M = a.T @ np.diag(m) @ a + np.diag(inertia)
    K = np.diag(vals["g"] * (m @ a))
    return np.sort(np.sqrt(np.linalg.eigvals(np.linalg.solve(M, K)).real))


@pytest.fixture(scope="module", params=[3, pytest.param(12, marks=pytest.mark.slow)],
                ids=lambda n: f"n{n}")
def chain(request):
    n = request.param
    KM, s = chain3d.derive(n)
    vals = chain3d.defaults(n)
    consts = [s["g"], *s["m"], *s["l"], *s["Ixx"], *s["Iyy"], *s["Izz"]]
    model = gen.Model.from_kanes(KM, constants={c: vals[str(c)] for c in consts},
                                 name=f"chain3d_{n}", energy=s["energy"])
    return n, KM, s, vals, gen.compile(model)


def test_rhs_matches_sympy(chain):
    n, KM, s, vals, sim = chain
    sub = {c: vals[str(c)] for c in [s["g"], *s["m"], *s["l"], *s["Ixx"], *s["Iyy"], *s["Izz"]]}
    q, u = s["q"], s["u"]
    qd = [qi.diff() for qi in q]
    M = sm.lambdify([q], KM.mass_matrix.xreplace(sub), "numpy", cse=True)
    f = sm.lambdify([q, u], KM.forcing.xreplace(sub), "numpy", cse=True)
    # sympy's own symbolic q'(q, u) (the explicit kinematics)
    kd = KM.kindiffdict()
    qdot_of = sm.lambdify([q, u], sm.Matrix([kd[v] for v in qd]), "numpy", cse=True)
    rng = np.random.default_rng(3)
    for _ in range(3):
        x = np.concatenate([rng.uniform(-0.6, 0.6, 3 * n), rng.uniform(-1, 1, 3 * n)])
        qv, uv = x[:3 * n], x[3 * n:]
        qdot = np.asarray(qdot_of(qv, uv), float).ravel()
        udot = np.linalg.solve(np.asarray(M(qv), float), np.asarray(f(qv, uv), float).ravel())
        assert rel_err(sim.rhs(0.0, x), np.concatenate([qdot, udot])) < 1e-11


def test_energy_is_conserved(chain):
    n, KM, s, vals, sim = chain
    x0 = np.zeros(sim.nx)
    x0[0], x0[4] = 0.4, -0.3                 # rod 0 about x, rod 1 about y
    x0[3 * n + 2] = 2.0                      # and rod 0 spinning about its axis
    t, X = sim.simulate(x0, 2.0, 0.01, method="dopri5", rtol=1e-11, atol=1e-12)
    E = np.array([sim.energy(x) for x in X])
    assert np.max(np.abs(E - E[0])) < 1e-8 * max(1.0, abs(E[0]))


def test_linearization_at_rest_is_the_planar_chain_twice(chain):
    n, KM, s, vals, sim = chain
    A, B = sim.linearize(np.zeros(sim.nx))
    lam = np.linalg.eigvals(A)
    assert np.max(np.abs(lam.real)) < 1e-9                   # undamped
    w = np.sort(np.abs(lam.imag))
    twist = w[:2 * n]                                         # n twists: a double zero each
    assert np.max(twist) < 1e-6
    swing = w[2 * n:][::2]                                    # +-i w, x and y planes: 4 each
    ref = _planar_frequencies(n, vals)
    assert rel_err(swing[::2], ref) < 1e-10
    assert rel_err(swing[1::2], ref) < 1e-10


def test_gimbal_lock_is_a_singular_kinematics_status(chain):
    n, KM, s, vals, sim = chain
    x = np.zeros(sim.nx)
    x[1] = np.pi / 2                         # rod 0's second angle at 90 deg
    with pytest.raises(gen.SingularError, match="SINGULAR_KINEMATICS"):
        sim.rhs(0.0, x)
