"""Issue 14: auxiliary speeds (KanesMethod u_auxiliary) and the reaction
forces along them: Model.from_kanes finds the unknown forces, the generated
code solves the auxiliary equations F reactions + g = 0 at u' from the
right-hand side, sim.auxiliary_forces returns them.

References: sympy's own auxiliary_eqs (lambdified; u' from numpy.linalg.solve
of mass_matrix_full / forcing_full; the reactions by a linear solve), and the
pin force of a simple pendulum computed by hand."""
import numpy as np
import pytest
import sympy as sm
from sympy.physics import mechanics as me

import gen
from gen.core.errors import ModelError
from helpers import rel_err

t = me.dynamicsymbols._t


# ------------------------------------------------------------------ models
def rolling_disc(normal=True):
    """sympy's test_aux (test_kane.py): a disc rolling on the ground, the
    contact point's velocity along L.x and Y.z x L.x as auxiliary speeds
    u4, u5 carrying the contact forces f1, f2; with normal=True a third
    auxiliary speed u6 along Y.z (up) carries the normal force f3."""
    q1, q2, q3, u1, u2, u3 = me.dynamicsymbols('q1 q2 q3 u1 u2 u3')
    u4, u5, u6, f1, f2, f3 = me.dynamicsymbols('u4 u5 u6 f1 f2 f3')
    r, m, g = sm.symbols('r m g')
    N = me.ReferenceFrame('N')
    Y = N.orientnew('Y', 'Axis', [q1, N.z])
    L = Y.orientnew('L', 'Axis', [q2, Y.x])
    R = L.orientnew('R', 'Axis', [q3, L.y])
    w_R_N_qd = R.ang_vel_in(N)
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    C = me.Point('C')
    vel = u4 * L.x + u5 * (Y.z ^ L.x)
    force = f1 * L.x + f2 * (Y.z ^ L.x)
    uaux = [u4, u5]
    if normal:
        vel, force, uaux = vel + u6 * Y.z, force + f3 * Y.z, uaux + [u6]
    C.set_vel(N, vel)
    Dmc = C.locatenew('Dmc', r * L.z)
    Dmc.v2pt_theory(C, N, R)
    Dmc.a2pt_theory(C, N, R)
    inertia = me.inertia(L, m / 4 * r**2, m / 2 * r**2, m / 4 * r**2)
    kd = [me.dot(R.ang_vel_in(N) - w_R_N_qd, uv) for uv in L]
    loads = [(Dmc, - m * g * Y.z), (C, force)]
    body = me.RigidBody('BodyD', Dmc, R, m, (inertia, Dmc))
    km = me.KanesMethod(N, q_ind=[q1, q2, q3], u_ind=[u1, u2, u3], kd_eqs=kd,
                        u_auxiliary=uaux)
    km.kanes_equations([body], loads)
    reactions = [f1, f2, f3] if normal else [f1, f2]
    return km, {r: 0.35, m: 2.5, g: 9.81}, reactions


def box_on_ground(friction=True):
    """sympy's test_box_on_ground (test_system_class.py): a particle sliding
    on the ground, the vertical speed ua auxiliary, the normal force N along
    it; F is an input. With friction the forcing holds -mu N."""
    g, m, mu = sm.symbols('g m mu')
    q, u, ua = me.dynamicsymbols('q u ua')
    Nf, F = me.dynamicsymbols('N F', positive=True)
    P = me.Particle("P", mass=m)
    system = me.System()
    system.add_bodies(P)
    P.masscenter.set_pos(system.fixed_point, q * system.x)
    P.masscenter.set_vel(system.frame, u * system.x + ua * system.y)
    system.q_ind, system.u_ind, system.u_aux = [q], [u], [ua]
    system.kdes = [q.diff(t) - u]
    system.apply_uniform_gravity(-g * system.y)
    if friction:
        system.add_loads(me.Force(P, Nf * system.y), me.Force(P, F * system.x - mu * Nf * system.x))
        consts = {g: 9.81, m: 1.7, mu: 0.3}
    else:
        system.add_loads(me.Force(P, Nf * system.y), me.Force(P, F * system.x))
        consts = {g: 9.81, m: 1.7}
    system.validate_system()
    system.form_eoms()
    return system, consts, F, Nf


def pin_pendulum():
    """A simple pendulum (angle theta from the downward vertical N.x, rod
    length L, bob mass m) whose pivot O moves with two auxiliary speeds
    along the rod (A.x, from the pivot to the bob) and across it (A.y),
    carrying the pin force R1 A.x + R2 A.y on the pendulum. By hand:
    R1 = -m (g cos(theta) + L theta'^2) (the pin pulls the bob towards the
    pivot) and R2 = 0 (the bob swings freely)."""
    th, w, ua1, ua2, R1, R2 = me.dynamicsymbols('theta omega ua1 ua2 R1 R2')
    m, g, L = sm.symbols('m g L')
    N = me.ReferenceFrame('N')
    A = N.orientnew('A', 'Axis', [th, N.z])
    A.set_ang_vel(N, w * N.z)
    O = me.Point('O')
    O.set_vel(N, ua1 * A.x + ua2 * A.y)
    P = O.locatenew('P', L * A.x)
    P.v2pt_theory(O, N, A)
    bob = me.Particle('bob', P, m)
    km = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w],
                        u_auxiliary=[ua1, ua2])
    km.kanes_equations([bob], [(P, m * g * N.x), (O, R1 * A.x + R2 * A.y)])
    return km, {m: 1.3, g: 9.81, L: 0.8}, (R1, R2)


# --------------------------------------------------------------- reference
def sympy_reactions(km, consts, reactions, X, inputs=(), r_vals=None):
    """Reactions from sympy's auxiliary_eqs at the states X (rows [q, u]):
    u' from mass_matrix_full / forcing_full, then the auxiliary equations
    (linear in the reactions: F from unit reactions) solved."""
    q, u = list(km.q), list(km.u)
    ud = [s.diff(t) for s in u]
    uaux = list(km._uaux)
    zero = {s.diff(t): 0 for s in uaux}
    zero.update({s: 0 for s in uaux})
    aux = km.auxiliary_eqs.xreplace(zero).xreplace(consts)
    Mf = sm.lambdify(q + u + list(inputs), km.mass_matrix_full.xreplace(consts))
    ff = sm.lambdify(q + u + list(inputs), km.forcing_full.xreplace(consts))
    fa = sm.lambdify(q + u + ud + list(inputs) + list(reactions), aux)
    r_vals = list(r_vals if r_vals is not None else [])
    out = []
    for x in X:
        xd = np.linalg.solve(np.array(Mf(*x, *r_vals), dtype=float),
                             np.array(ff(*x, *r_vals), dtype=float).ravel())
        a = xd[len(q):]
        na = len(reactions)
        g0 = np.array(fa(*x, *a, *r_vals, *np.zeros(na)), dtype=float).ravel()
        F = np.column_stack([np.array(fa(*x, *a, *r_vals, *np.eye(na)[j]), dtype=float).ravel()
                             - g0 for j in range(na)])
        out.append(np.linalg.solve(F, -g0))
    return np.array(out)


def random_states(n, nx, seed):
    return np.random.default_rng(seed).uniform(-1.5, 1.5, (n, nx))


# ------------------------------------------------------------------- tests
@pytest.mark.parametrize("normal", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_rolling_disc_matches_sympy_auxiliary_eqs(normal):
    km, consts, reactions = rolling_disc(normal)
    model = gen.Model.from_kanes(km, constants=consts, name="disc_aux")
    assert model.na == len(reactions)
    assert model.auxiliary_labels == [str(f.func) for f in reactions]
    sim = gen.compile(model)
    assert sim.na == len(reactions)
    assert sim.auxiliary_names == sim.auxiliary_labels == [str(f.func) for f in reactions]
    X = random_states(20, sim.nx, 14)
    ref = sympy_reactions(km, consts, reactions, X)
    got = np.array([sim.auxiliary_forces(0.0, x) for x in X])
    assert got.shape == (20, len(reactions))
    err = max(rel_err(g_, r_) for g_, r_ in zip(got, ref))
    assert err < 1e-12, err
    # the motion of the real speeds is the one without auxiliary speeds
    assert rel_err(sim.rhs(0.0, X[0]), np.linalg.solve(
        np.array(sm.lambdify(list(km.q) + list(km.u), km.mass_matrix_full.xreplace(consts))(*X[0]),
                 dtype=float),
        np.array(sm.lambdify(list(km.q) + list(km.u), km.forcing_full.xreplace(consts))(*X[0]),
                 dtype=float).ravel())) < 1e-12


def test_rolling_disc_normal_force_at_rest_is_the_weight():
    km, consts, _ = rolling_disc(normal=True)
    sim = gen.compile(gen.Model.from_kanes(km, constants=consts, name="disc_aux"))
    # upright (q2 = 0), at rest: no tangential force, the normal force is m g
    f = sim.auxiliary_forces(0.0, np.zeros(6))
    assert abs(f[0]) < 1e-14 and abs(f[1]) < 1e-14
    assert abs(f[2] - 2.5 * 9.81) < 1e-12 * 2.5 * 9.81


def test_pendulum_pin_force_by_hand():
    km, consts, (R1, R2) = pin_pendulum()
    m, g, L = (consts[s] for s in sorted(consts, key=lambda s: "mgL".index(str(s))))
    model = gen.Model.from_kanes(km, constants=consts, name="pin")
    assert model.na == 2 and model.auxiliary_labels == ["R1", "R2"]
    sim = gen.compile(model)
    X = random_states(50, 2, 7) * np.array([2.0, 3.0])
    got = np.array([sim.auxiliary_forces(0.0, x) for x in X])
    th, w = X[:, 0], X[:, 1]
    radial = -m * (g * np.cos(th) + L * w**2)
    assert rel_err(got[:, 0], radial) < 1e-12
    assert np.max(np.abs(got[:, 1])) < 1e-12 * np.max(np.abs(radial))
    # against sympy's own auxiliary equations as well
    assert rel_err(got, sympy_reactions(km, consts, (R1, R2), X)) < 1e-12


def test_reactions_argument_names_and_orders_them():
    km, consts, (R1, R2) = pin_pendulum()
    sim = gen.compile(gen.Model.from_kanes(km, constants=consts, name="pin",
                                           reactions=[R2, R1]))
    assert sim.auxiliary_names == ["R2", "R1"]
    x = np.array([0.4, -1.1])
    m, g, L = 1.3, 9.81, 0.8
    f = sim.auxiliary_forces(0.0, x)
    assert abs(f[1] + m * (g * np.cos(0.4) + L * 1.1**2)) < 1e-12 * 20


def test_box_on_ground_without_friction():
    system, consts, F, Nf = box_on_ground(friction=False)
    model = gen.Model.from_kanes(system, constants=consts, inputs=[F], name="box")
    assert model.na == 1 and model.auxiliary_labels == ["N"]
    sim = gen.compile(model)
    X = random_states(10, 2, 3)
    for x in X:
        for r in (None, [2.5]):
            np.testing.assert_allclose(sim.auxiliary_forces(0.0, x, r=r), [1.7 * 9.81],
                                       rtol=1e-14)
    km = system.eom_method
    ref = sympy_reactions(km, consts, [Nf], X, inputs=[F], r_vals=[2.5])
    got = np.array([sim.auxiliary_forces(0.0, x, r=[2.5]) for x in X])
    assert rel_err(got, ref) < 1e-12


def sympy_residuals(system, consts, F, Nf, x, r, xdot, n_val):
    """sympy's own equations at a state with eomgen's u' and reaction put
    in: the dynamic equations (mass_matrix u' - forcing) and the auxiliary
    equations, both zero when eomgen solved them together."""
    km = system.eom_method
    q, u, ua = km.q[0], km.u[0], km._uaux[0]
    sub = {u.diff(t): xdot[1], ua.diff(t): 0}
    sub2 = {q: x[0], u: x[1], ua: 0, F: r[0], Nf: n_val}
    dyn = (km.mass_matrix * sm.Matrix([u.diff(t)]) - km.forcing)
    vals = [float(e.xreplace(sub).xreplace(sub2).xreplace(consts))
            for e in list(dyn) + list(km.auxiliary_eqs)]
    return np.array(vals)


def test_box_on_ground_with_friction_solves_motion_and_reaction_together():
    # sympy's own model: the friction -mu N puts the normal reaction into the
    # motion; eomgen solves u' and N together
    system, consts, F, Nf = box_on_ground(friction=True)
    model = gen.Model.from_kanes(system, constants=consts, inputs=[F], name="box")
    sim = gen.compile(model)
    m, g, mu = 1.7, 9.81, 0.3
    for x in random_states(10, 2, 5):
        r = [np.random.default_rng(int(1e3 * abs(x[0]))).uniform(0, 20)]
        xd = sim.rhs(0.0, x, r=r)
        n_val = sim.auxiliary_forces(0.0, x, r=r)[0]
        assert abs(xd[1] - (r[0] - mu * m * g) / m) < 1e-14 * 20
        assert abs(n_val - m * g) < 1e-14 * 20
        res = sympy_residuals(system, consts, F, Nf, x, r, xd, n_val)
        assert np.max(np.abs(res)) < 1e-12 * m * g, res
    # the linearization carries the friction: d u'/d F = 1/m, the rest zero
    A, B = sim.linearize([0.0, 0.5], r=[3.0])
    np.testing.assert_allclose(B, [[0.0], [1 / m]], atol=1e-15)
    np.testing.assert_allclose(A, [[0.0, 1.0], [0.0, 0.0]], atol=1e-15)


def cart_pendulum_with_friction(signed=False):
    """A cart (mass mc, position x, speed v) sliding forward on the ground
    with friction -mu N on the normal force N (-mu N sign(v) with
    signed=True), which the swinging bob
    (mass mp, rod l, angle theta from the downward vertical) changes: the
    vertical speed ua of the cart is auxiliary and carries N (the problem of
    Florian, 'Correct equations for the dynamics of the cart-pole system',
    2007, with a point mass)."""
    x, th, v, w, ua, Nf, F = me.dynamicsymbols('x theta v omega ua N F')
    mc, mp, l, g, mu = sm.symbols('m_c m_p l g mu')
    N = me.ReferenceFrame('N')
    A = N.orientnew('A', 'Axis', [th, N.z])
    A.set_ang_vel(N, w * N.z)
    O = me.Point('O')
    C = O.locatenew('C', x * N.x)
    C.set_vel(N, v * N.x + ua * N.y)
    P = C.locatenew('P', -l * A.y)
    P.v2pt_theory(C, N, A)
    bodies = [me.Particle('cart', C, mc), me.Particle('bob', P, mp)]
    fric = mu * Nf * (sm.sign(v) if signed else 1)
    loads = [(C, -mc * g * N.y + Nf * N.y + (F - fric) * N.x),
             (P, -mp * g * N.y)]
    km = me.KanesMethod(N, q_ind=[x, th], u_ind=[v, w],
                        kd_eqs=[x.diff(t) - v, th.diff(t) - w], u_auxiliary=[ua])
    km.kanes_equations(bodies, loads)
    consts = {mc: 1.4, mp: 0.6, l: 0.7, g: 9.81, mu: 0.25}
    return km, consts, F, Nf


def newton_euler(x_state, F, mc=1.4, mp=0.6, l=0.7, g=9.81, mu=0.25, sg=1.0):
    """By hand: the bob at (x + l sin th, -l cos th) with rod tension T, the
    cart with N and friction mu N against +x; four linear equations in
    x'', th'', T, N."""
    _, th, v, w = x_state
    s, c = np.sin(th), np.cos(th)
    # unknowns [x'', th'', T, N]
    K = np.array([
        [mp, mp * l * c, s, 0.0],            # bob x: mp ax = -T sin th
        [0.0, mp * l * s, -c, 0.0],          # bob y: mp ay = T cos th - mp g
        [mc, 0.0, -s, mu * sg],              # cart x: mc x'' = F - mu N sgn + T sin th
        [0.0, 0.0, c, -1.0]])                # cart y: 0 = N - mc g - T cos th
    rhs = np.array([mp * l * w**2 * s, -mp * l * w**2 * c - mp * g, F, -mc * g])
    return np.linalg.solve(K, rhs)


def test_cart_pendulum_friction_on_varying_normal_force_by_hand():
    km, consts, F, Nf = cart_pendulum_with_friction()
    model = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="cartfric")
    assert model.auxiliary_labels == ["N"]
    sim = gen.compile(model)
    rng = np.random.default_rng(11)
    for _ in range(20):
        x = rng.uniform(-2, 2, 4)
        x[2] = abs(x[2])                    # sliding forward
        r = rng.uniform(-5, 5, 1)
        xdd, thdd, _, n_val = newton_euler(x, r[0])
        got = sim.rhs(0.0, x, r=r)
        np.testing.assert_allclose(got, [x[2], x[3], xdd, thdd], rtol=1e-12, atol=1e-12)
        assert abs(sim.auxiliary_forces(0.0, x, r=r)[0] - n_val) < 1e-12 * abs(n_val)
    # the linearization is the derivative of that rhs (central differences)
    x0, r0 = np.array([0.1, 0.8, 0.4, -0.3]), np.array([1.5])
    A, B = sim.linearize(x0, r=r0)
    h = 1e-6
    An = np.column_stack([(sim.rhs(0.0, x0 + h * e, r=r0) - sim.rhs(0.0, x0 - h * e, r=r0)) / (2 * h)
                          for e in np.eye(4)])
    assert rel_err(A, An) < 1e-8


def test_coulomb_friction_on_varying_normal_force_solved_with_the_motion_by_hand():
    # Coulomb friction -mu N sign(v) on a normal force that depends on the
    # accelerations: the matrix multiplying (u', N) depends on v, so u' and N
    # are solved together at run time (one linear system per evaluation)
    km, consts, F, _ = cart_pendulum_with_friction(signed=True)
    model = gen.Model.from_kanes(km, constants=consts, inputs=[F], name="cartfric_s")
    assert model.aux_G is not None
    sim = gen.compile(model)
    rng = np.random.default_rng(12)
    for _ in range(20):
        x = rng.uniform(-2, 2, 4)
        r = rng.uniform(-5, 5, 1)
        xdd, thdd, _, n_val = newton_euler(x, r[0], sg=np.sign(x[2]))
        got = sim.rhs(0.0, x, r=r)
        np.testing.assert_allclose(got, [x[2], x[3], xdd, thdd], rtol=1e-12, atol=1e-12)
        assert abs(sim.auxiliary_forces(0.0, x, r=r)[0] - n_val) < 1e-12 * abs(n_val)
    # the linearization (sliding: sign(v) is locally constant) is the
    # derivative of that rhs (central differences)
    x0, r0 = np.array([0.1, 0.8, 0.4, -0.3]), np.array([1.5])
    A, B = sim.linearize(x0, r=r0)
    h = 1e-6
    An = np.column_stack([(sim.rhs(0.0, x0 + h * e, r=r0) - sim.rhs(0.0, x0 - h * e, r=r0)) / (2 * h)
                          for e in np.eye(4)])
    Bn = ((sim.rhs(0.0, x0, r=r0 + h) - sim.rhs(0.0, x0, r=r0 - h)) / (2 * h))[:, None]
    assert rel_err(A, An) < 1e-8 and rel_err(B, Bn) < 1e-8


def test_reaction_along_a_turning_direction_solved_with_the_motion():
    # the reaction acts along B.y, which turns with q, while its auxiliary
    # speed is along N.y: the auxiliary equation R cos(q) - g = 0 gives
    # R = g / cos(q), and the motion u' = -R (sin(q) + 1/3); at cos(q) = 0
    # the reaction is not determined (the status names it)
    q, u, ua, R = me.dynamicsymbols('q u ua R')
    g = sm.Symbol('g')
    N = me.ReferenceFrame('N')
    B = N.orientnew('B', 'Axis', [q, N.z])
    P = me.Point('P')
    P.set_vel(N, u * N.x + ua * N.y)
    km = me.KanesMethod(N, q_ind=[q], u_ind=[u], kd_eqs=[q.diff(t) - u], u_auxiliary=[ua])
    km.kanes_equations([me.Particle('p', P, 1)],
                       [(P, R * B.y - sm.Rational(1, 3) * R * N.x - g * N.y)])
    sim = gen.compile(gen.Model.from_kanes(km, constants={g: 9.81}, name="turning"))
    for qv in (-1.2, -0.3, 0.0, 0.7, 1.4):
        x = [qv, 0.4]
        r_val = 9.81 / np.cos(qv)
        np.testing.assert_allclose(sim.rhs(0.0, x), [0.4, -r_val * (np.sin(qv) + 1 / 3)],
                                   rtol=1e-13, atol=1e-13)
        assert abs(sim.auxiliary_forces(0.0, x)[0] - r_val) < 1e-13 * abs(r_val)
    with pytest.raises(gen.SingularError, match=r"the reactions R\) \[ERR_SINGULAR_REACTIONS"):
        sim.rhs(0.0, [np.pi / 2, 0.4])


def test_errors_name_the_symbols():
    km, consts, (R1, R2) = pin_pendulum()
    with pytest.raises(ModelError, match=r"2 auxiliary speed\(s\).*1 reaction.*\['R1'\]"):
        gen.Model.from_kanes(km, constants=consts, reactions=[R1])
    # an undeclared input in the auxiliary equations looks like another reaction
    th, w, ua, R, Fx = me.dynamicsymbols('theta omega ua R Fx')
    N = me.ReferenceFrame('N')
    P = me.Point('P')
    P.set_vel(N, w * N.x + ua * N.y)
    km1 = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w], u_auxiliary=[ua])
    km1.kanes_equations([me.Particle('p', P, 1)], [(P, (R + Fx) * N.y)])
    with pytest.raises(ModelError, match=r"1 auxiliary speed\(s\).*2 reaction.*\['Fx', 'R'\]"):
        gen.Model.from_kanes(km1, name="box")
    sim = gen.compile(gen.Model.from_kanes(km1, inputs=[Fx], name="box"))
    assert sim.auxiliary_names == ["R"]
    assert abs(sim.auxiliary_forces(0.0, [0.0, 1.0], r=[0.75])[0] + 0.75) < 1e-15
    # not linear in the reactions
    th, w, ua, R = me.dynamicsymbols('theta omega ua R')
    N = me.ReferenceFrame('N')
    P = me.Point('P')
    P.set_vel(N, w * N.x + ua * N.y)
    km2 = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w], u_auxiliary=[ua])
    km2.kanes_equations([me.Particle('p', P, 1)], [(P, R**2 * N.y)])
    with pytest.raises(ModelError, match="not linear in the reaction force.*R"):
        gen.Model.from_kanes(km2)


def test_model_without_auxiliary_speeds(kane_sim):
    assert kane_sim.na == 0
    assert kane_sim.auxiliary_names == [] and kane_sim.auxiliary_labels == []
    out = kane_sim.auxiliary_forces(0.0, np.zeros(kane_sim.nx))
    assert out.shape == (0,)


def test_singular_reaction_matrix_is_reported():
    # two auxiliary speeds along the same direction: F is singular
    th, w, ua1, ua2, R1, R2 = me.dynamicsymbols('theta omega ua1 ua2 R1 R2')
    N = me.ReferenceFrame('N')
    P = me.Point('P')
    P.set_vel(N, w * N.x + ua1 * N.y + ua2 * N.y)
    km = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w],
                        u_auxiliary=[ua1, ua2])
    km.kanes_equations([me.Particle('p', P, 1)], [(P, R1 * N.y + R2 * N.y)])
    sim = gen.compile(gen.Model.from_kanes(km, name="sing"))
    with pytest.raises(gen.SingularError,
                       match=r"not determined at this state.*\(the reactions R1, R2\) "
                             r"\[ERR_SINGULAR_REACTIONS\]") as e:
        sim.auxiliary_forces(0.0, [0.1, 0.2])
    assert e.value.status == -14 and e.value.status_name == "ERR_SINGULAR_REACTIONS"
    # the motion itself is regular there
    np.testing.assert_allclose(sim.rhs(0.0, [0.1, 0.2]), [0.2, 0.0], atol=1e-15)


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_matches_c():
    from conftest import require_eigen
    require_eigen()
    km, consts, reactions = rolling_disc(normal=True)
    model = gen.Model.from_kanes(km, constants=consts, name="disc_aux")
    c, e = gen.compile(model), gen.compile(model, backend="eigen")
    X = random_states(10, 6, 5)
    ref = sympy_reactions(km, consts, reactions, X)
    got = np.array([e.auxiliary_forces(0.0, x) for x in X])
    assert rel_err(got, ref) < 1e-12
    assert rel_err(got, [c.auxiliary_forces(0.0, x) for x in X]) < 1e-13


def constrained_rolling_disc():
    """examples/rolling_disc.py (two nonholonomic constraints: dependent
    speeds u4, u5, a drive torque T as input) with an auxiliary vertical
    speed ua of the disc (centre and contact point) carrying the normal
    force fN at the contact point: the path
    through the unconstrained equations and the runtime's elimination of
    the dependent speeds."""
    q1, q2, q3, x, y = me.dynamicsymbols("q1 q2 q3 x y")
    u1, u2, u3, u4, u5 = me.dynamicsymbols("u1:6")
    ua, fN, T = me.dynamicsymbols("ua fN T")
    m, r, g = sm.symbols("m r g")
    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    qd = {q1.diff(): u1, q2.diff(): u2, q3.diff(): u3, x.diff(): u4, y.diff(): u5}
    R.set_ang_vel(N, R.ang_vel_in(N).subs(qd))
    L.set_ang_vel(N, L.ang_vel_in(N).subs(qd))
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)
    Dmc = C.locatenew("Dmc", r * L.z)
    Dmc.set_vel(N, Dmc.pos_from(O).dt(N).subs(qd) + ua * N.z)
    v_contact = Dmc.vel(N) + R.ang_vel_in(N).cross(C.pos_from(Dmc))
    f_v = sm.Matrix([v_contact.dot(Y.x), v_contact.dot(Y.y)]).applyfunc(sm.expand)
    I_disc = me.inertia(L, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4)
    disc = me.RigidBody("disc", Dmc, R, m, (I_disc, Dmc))
    kde = [q1.diff() - u1, q2.diff() - u2, q3.diff() - u3, x.diff() - u4, y.diff() - u5]
    km = me.KanesMethod(N, q_ind=[q1, q2, q3, x, y], u_ind=[u1, u2, u3],
                        u_dependent=[u4, u5], kd_eqs=kde, velocity_constraints=f_v,
                        u_auxiliary=[ua])
    # the normal force acts at the disc's material point at the contact
    # (no vertical velocity from the real speeds, ua from the auxiliary one)
    Cm = me.Point("Cm")
    Cm.set_vel(N, v_contact)
    km.kanes_equations([disc], [(Dmc, -m * g * N.z), (Cm, fN * N.z), (R, T * L.y),
                                (L, -T * L.y)])
    return km, {m: 1.2, r: 0.3, g: 9.81}, [fN], T


@pytest.mark.slow
def test_constrained_model_matches_sympy_auxiliary_eqs():
    km, consts, reactions, T = constrained_rolling_disc()
    model = gen.Model.from_kanes(km, constants=consts, inputs=[T], name="cdisc")
    assert model.mv == 2 and model.na == 1
    sim = gen.compile(model)
    X = np.array([sim.consistent_state(x) for x in random_states(10, sim.nx, 21)])
    ref = sympy_reactions(km, consts, reactions, X, inputs=[T], r_vals=[0.4])
    got = np.array([sim.auxiliary_forces(0.0, x, r=[0.4]) for x in X])
    assert rel_err(got, ref) < 1e-12, rel_err(got, ref)


@pytest.mark.slow
def test_standalone_csv_has_one_column_per_reaction(tmp_path):
    import shutil
    import subprocess
    from gen.codegen.render import generate
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    km, consts, _ = pin_pendulum()
    model = gen.Model.from_kanes(km, constants=consts, name="pin")
    generate(model, tmp_path / "src")
    src = sorted(str(p) for p in (tmp_path / "src").glob("*.c"))
    exe = tmp_path / "pin_sim"
    subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1",
                    "-I", str(tmp_path / "src"), *src, "-lm", "-o", str(exe)], check=True)
    out = subprocess.run([str(exe), "--t-end", "0.05", "--dt", "0.01", "--x0", "theta=0.5",
                          "--x0", "omega=1.5"], capture_output=True, text=True, check=True).stdout
    lines = out.splitlines()
    assert lines[0].split(",") == ["t", "theta", "omega", "R1", "R2"]
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    m, g, L = 1.3, 9.81, 0.8
    radial = -m * (g * np.cos(data[:, 1]) + L * data[:, 2]**2)
    assert rel_err(data[:, 3], radial) < 1e-12
    assert np.max(np.abs(data[:, 4])) < 1e-12 * np.max(np.abs(radial))


@pytest.mark.slow
def test_verify_checks_the_auxiliary_forces():
    km, consts, _ = rolling_disc(normal=True)
    report = gen.verify(gen.Model.from_kanes(km, constants=consts, name="disc_aux"), samples=5,
                        linearize_samples=1)
    assert report.ok, report.table()
    assert "eval_auxiliary_forces" in report.table()


# ------------------------------------------- issue 33: no unknown reaction
# Every force along the auxiliary directions declared an input: nothing to
# solve for, the model is built all the same, and sim.auxiliary_forces gives
# the value of each auxiliary equation (Kane's Fr + Fr*) at the inputs given,
# one per auxiliary speed, named after it.
def rolling_disc_aux_dep():
    """sympy's test_kane2.test_aux_dep, its KanesMethod as written there: a
    rolling disc with a dependent coordinate q3 (configuration constraint),
    three dependent speeds u3, u4, u5 (velocity constraints) and three
    auxiliary speeds ua0..ua2 of the contact point P carrying the contact
    force Fx A.x + Fy A.y + Fz A.z (plain symbols, declared inputs here)."""
    r, m, g, I, J = sm.symbols('r m g I J')
    Fx, Fy, Fz = sm.symbols('Fx Fy Fz')
    q = me.dynamicsymbols('q:4')
    qd = [qi.diff(t) for qi in q]
    u = me.dynamicsymbols('u:6')
    ua = me.dynamicsymbols('ua:3')
    N = me.ReferenceFrame('N')
    A = N.orientnew('A', 'Axis', [q[0], N.z])
    B = A.orientnew('B', 'Axis', [q[1], A.x])
    C = B.orientnew('C', 'Axis', [q[2], B.y])
    C.set_ang_vel(N, u[0] * B.x + u[1] * B.y + u[2] * B.z)
    C.set_ang_acc(N, C.ang_vel_in(N).diff(t, B) + me.cross(B.ang_vel_in(N), C.ang_vel_in(N)))
    P = me.Point('P')
    P.set_vel(N, ua[0] * A.x + ua[1] * A.y + ua[2] * A.z)
    O = P.locatenew('O', q[3] * A.z + r * sm.sin(q[1]) * A.y)
    O.set_vel(N, u[3] * A.x + u[4] * A.y + u[5] * A.z)
    O.set_acc(N, O.vel(N).diff(t, A) + me.cross(A.ang_vel_in(N), O.vel(N)))
    w_c_n_qd = qd[0] * A.z + qd[1] * B.x + qd[2] * B.y
    v_o_n_qd = O.pos_from(P).diff(t, A) + me.cross(A.ang_vel_in(N), O.pos_from(P))
    kindiffs = sm.Matrix([me.dot(w_c_n_qd - C.ang_vel_in(N), uv) for uv in B]
                         + [me.dot(v_o_n_qd - O.vel(N), A.z)])
    f_c = sm.Matrix([me.dot(-r * B.z, A.z) - q[3]])
    f_v = sm.Matrix([me.dot(O.vel(N) - (P.vel(N) + me.cross(C.ang_vel_in(N), O.pos_from(P))),
                            ai).expand() for ai in A])
    disc = me.RigidBody('disc', O, C, m, (me.inertia(B, I, J, I), O))
    loads = [(O, m * g * A.z), (P, Fx * A.x + Fy * A.y + Fz * A.z)]
    km = me.KanesMethod(N, q_ind=q[:3], u_ind=u[:3], kd_eqs=kindiffs, q_dependent=q[3:],
                        configuration_constraints=f_c, u_dependent=u[3:],
                        velocity_constraints=f_v, u_auxiliary=ua)
    km.kanes_equations([disc], loads)
    return km, {r: 0.3, m: 1.2, g: 9.81, I: 0.027, J: 0.054}, [Fx, Fy, Fz]


def sympy_auxiliary_values(km, consts, X, inputs, r_vals):
    """sympy's own auxiliary equations at the states X with the inputs
    given: u' from numpy.linalg.solve of mass_matrix_full / forcing_full,
    then km.auxiliary_eqs evaluated (the auxiliary speeds and their
    derivatives zero)."""
    q, u = list(km.q), list(km.u)
    ud = [s.diff(t) for s in u]
    uaux = list(km._uaux)
    zero = {s.diff(t): 0 for s in uaux}
    zero.update({s: 0 for s in uaux})
    args = q + u + list(inputs)
    Mf = sm.lambdify(args, km.mass_matrix_full.xreplace(zero).xreplace(consts))
    ff = sm.lambdify(args, km.forcing_full.xreplace(zero).xreplace(consts))
    fa = sm.lambdify(q + u + ud + list(inputs),
                     km.auxiliary_eqs.xreplace(zero).xreplace(consts))
    out = []
    for x in X:
        xd = np.linalg.solve(np.array(Mf(*x, *r_vals), dtype=float),
                             np.array(ff(*x, *r_vals), dtype=float).ravel())
        out.append(np.array(fa(*x, *xd[len(q):], *r_vals), dtype=float).ravel())
    return np.array(out)


def test_sympy_test_aux_with_declared_forces():
    # sympy's test_aux (KM2): f1, f2 along u4, u5 declared inputs
    km, consts, (f1, f2) = rolling_disc(normal=False)
    model = gen.Model.from_kanes(km, constants=consts, inputs=[f1, f2], name="disc_in")
    assert model.na == 2 and model.auxiliary_labels == ["u4", "u5"]
    sim = gen.compile(model)
    assert sim.auxiliary_names == ["u4", "u5"] and sim.nr == 2
    X = random_states(20, sim.nx, 33)
    R = np.random.default_rng(33).uniform(-3, 3, (20, 2))
    got = np.array([sim.auxiliary_forces(0.0, x, r=r) for x, r in zip(X, R)])
    # the force each direction still needs: minus sympy's Fr + Fr*
    ref = -np.array([sympy_auxiliary_values(km, consts, [x], [f1, f2], r)[0]
                     for x, r in zip(X, R)])
    assert rel_err(got, ref) < 1e-12, rel_err(got, ref)
    # the force along u4 enters Fr + Fr* as f1 itself: a unit more of it is a
    # unit less needed
    x, r = X[0], R[0]
    d = sim.auxiliary_forces(0.0, x, r=r + [1.0, 0.0]) - sim.auxiliary_forces(0.0, x, r=r)
    np.testing.assert_allclose(d, [-1.0, 0.0], atol=1e-12)
    # with the declared forces at zero, the forces needed are the reactions
    # of the model that leaves them unknown
    # where the declared forces are the reactions (from the reaction model),
    # the auxiliary equations hold: zero
    react = gen.compile(gen.Model.from_kanes(km, constants=consts, name="disc_aux"))
    w = react.auxiliary_forces(0.0, x)
    np.testing.assert_allclose(sim.auxiliary_forces(0.0, x, r=[0.0, 0.0]), w, rtol=1e-12,
                               atol=1e-12 * np.max(np.abs(w)))
    assert np.max(np.abs(sim.auxiliary_forces(0.0, x, r=w))) < 1e-12 * max(1.0, np.max(np.abs(w)))


@pytest.mark.slow
def test_sympy_test_aux_dep_with_declared_forces():
    # sympy's test_kane2.test_aux_dep: dependent coordinate and speeds, three
    # auxiliary speeds, the contact force symbols declared inputs
    km, consts, forces = rolling_disc_aux_dep()
    model = gen.Model.from_kanes(km, constants=consts, inputs=forces, name="auxdep")
    assert model.mc == 1 and model.mv == 3 and model.na == 3
    assert model.auxiliary_labels == ["ua0", "ua1", "ua2"]
    sim = gen.compile(model)
    rng = np.random.default_rng(5)
    worst, n = 0.0, 0
    for x in random_states(8, sim.nx, 8):
        x = sim.consistent_state(x)
        r = rng.uniform(-3, 3, 3)
        ref = -sympy_auxiliary_values(km, consts, [x], forces, r)[0]
        got = sim.auxiliary_forces(0.0, x, r=r)
        assert np.max(np.abs(ref)) > 0.1
        worst = max(worst, rel_err(got, ref))
        n += 1
    assert n == 8 and worst < 1e-12, worst


def test_sympy_box_on_ground_with_normal_force_declared():
    # sympy's test_box_on_ground with N among the inputs: the motion is
    # u' = (F - mu N)/m and the auxiliary equation N - m g (sympy's aux_eqs);
    # the force the vertical direction still needs is m g - N
    system, consts, F, Nf = box_on_ground(friction=True)
    model = gen.Model.from_kanes(system, constants=consts, inputs=[F, Nf], name="box_in")
    assert model.na == 1 and model.auxiliary_labels == ["ua"]
    sim = gen.compile(model)
    m, g, mu = 1.7, 9.81, 0.3
    rng = np.random.default_rng(9)
    for x in random_states(10, 2, 9):
        r = rng.uniform(0, 30, 2)
        assert abs(sim.rhs(0.0, x, r=r)[1] - (r[0] - mu * r[1]) / m) < 1e-14 * 30
        fa = sim.auxiliary_forces(0.0, x, r=r)
        assert abs(fa[0] - (m * g - r[1])) < 1e-14 * 30
        ref = -sympy_auxiliary_values(system.eom_method, consts, [x], [F, Nf], r)[0]
        assert rel_err(fa, ref) < 1e-12
    # with N = m g the auxiliary equation holds and the block slides at F/m - mu g
    r = [5.0, m * g]
    assert abs(sim.auxiliary_forces(0.0, [0.0, 1.0], r=r)[0]) < 1e-14
    assert abs(sim.rhs(0.0, [0.0, 1.0], r=r)[1] - (5.0 / m - mu * g)) < 1e-14


def test_partly_declared_forces_are_still_refused():
    # f1 declared, f2 not: one unknown force for two auxiliary speeds is
    # ambiguous, refused with the names
    km, consts, (f1, f2) = rolling_disc(normal=False)
    with pytest.raises(ModelError, match=r"2 auxiliary speed\(s\).*1 reaction.*\['f2'\]"):
        gen.Model.from_kanes(km, constants=consts, inputs=[f1], name="disc_half")


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_with_declared_forces_matches_c():
    from conftest import require_eigen
    require_eigen()
    km, consts, (f1, f2) = rolling_disc(normal=False)
    model = gen.Model.from_kanes(km, constants=consts, inputs=[f1, f2], name="disc_in")
    c, e = gen.compile(model), gen.compile(model, backend="eigen")
    assert e.auxiliary_names == ["u4", "u5"]
    X = random_states(10, 6, 12)
    R = np.random.default_rng(12).uniform(-3, 3, (10, 2))
    got = np.array([e.auxiliary_forces(0.0, x, r=r) for x, r in zip(X, R)])
    ref = -np.array([sympy_auxiliary_values(km, consts, [x], [f1, f2], r)[0]
                     for x, r in zip(X, R)])
    assert rel_err(got, ref) < 1e-12
    assert rel_err(got, [c.auxiliary_forces(0.0, x, r=r) for x, r in zip(X, R)]) < 1e-13


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_backend_reports_singular_reactions():
    from conftest import require_eigen
    require_eigen()
    th, w, ua1, ua2, R1, R2 = me.dynamicsymbols('theta omega ua1 ua2 R1 R2')
    N = me.ReferenceFrame('N')
    P = me.Point('P')
    P.set_vel(N, w * N.x + ua1 * N.y + ua2 * N.y)
    km = me.KanesMethod(N, q_ind=[th], u_ind=[w], kd_eqs=[th.diff(t) - w],
                        u_auxiliary=[ua1, ua2])
    km.kanes_equations([me.Particle('p', P, 1)], [(P, R1 * N.y + R2 * N.y)])
    sim = gen.compile(gen.Model.from_kanes(km, name="sing"), backend="eigen")
    with pytest.raises(gen.SingularError, match=r"\(the reactions R1, R2\) "
                                                r"\[ERR_SINGULAR_REACTIONS\]"):
        sim.auxiliary_forces(0.0, [0.1, 0.2])
