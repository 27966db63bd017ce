"""gen.intake.sympy_compat: every read of a private attribute of a sympy
mechanics object, on methods formed by the installed sympy, against what the
user gave the method (the kinematic rows, the constraints) or what the
Lagrangian gives by hand. A sympy release that renames or changes one of
them fails here, in the function that reads it."""
import sympy as sm
import sympy.physics.mechanics as me

from gen.intake import sympy_compat as sc


def _zero(expr):
    return sm.simplify(sm.expand(expr)) == 0


def _slider_on_parabola(aux=False):
    """A particle in the plane on y = x**2: x independent, y dependent (the
    configuration constraint), u2 dependent (its velocity constraint); with
    aux, an auxiliary speed along N.z."""
    x, y, u1, u2, u3 = me.dynamicsymbols("x y u1 u2 u3")
    m, g = sm.symbols("m g")
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, u1 * N.x + u2 * N.y + (u3 * N.z if aux else 0))
    kd = [x.diff(t) - u1, 2 * (y.diff(t) - u2)]
    km = me.KanesMethod(N, q_ind=[x], u_ind=[u1], kd_eqs=kd, q_dependent=[y],
                        configuration_constraints=[y - x**2], u_dependent=[u2],
                        velocity_constraints=[u2 - 2 * x * u1],
                        u_auxiliary=[u3] if aux else None)
    loads = [(P, -m * g * N.y)]
    return km, [me.Particle("p", P, m)], loads, dict(x=x, y=y, u1=u1, u2=u2, u3=u3, N=N,
                                                      kd=kd, t=t)


def test_time_symbol_is_the_t_of_dynamicsymbols():
    q = me.dynamicsymbols("q")
    assert sc.time_symbol() == q.args[0]
    assert q.diff(sc.time_symbol()) == sm.Derivative(q, q.args[0])


def test_kane_reads_are_what_the_user_gave():
    km, bodies, loads, s = _slider_on_parabola()
    assert not sc.kane_is_formed(km)
    km.kanes_equations(bodies, loads)
    assert sc.kane_is_formed(km)
    assert sc.kane_dependent_counts(km) == (1, 1)
    assert sc.kane_auxiliary_speeds(km) == []
    assert sc.kane_frame(km) is s["N"]
    # the kinematic rows as written (the 2 in the second row kept: not solved for q')
    Kqd, Ku, kf = sc.kane_kinematics(km)
    qd = sm.Matrix([s["x"].diff(s["t"]), s["y"].diff(s["t"])])
    rows = Kqd * qd + Ku * sm.Matrix([s["u1"], s["u2"]]) + kf
    assert all(_zero(a - b) for a, b in zip(rows, s["kd"]))
    assert Kqd == sm.diag(1, 2)
    assert sc.kane_qdot_map(km) == {qd[0]: s["u1"], qd[1]: s["u2"]}
    fc = sc.kane_configuration_constraints(km)
    assert fc.shape == (1, 1) and _zero(fc[0] - (s["y"] - s["x"]**2))
    A, b = sc.kane_velocity_constraints(km)
    vc = A * sm.Matrix([s["u1"], s["u2"]]) + b
    assert vc.shape == (1, 1) and _zero(vc[0] - (s["u2"] - 2 * s["x"] * s["u1"]))


def test_kane_auxiliary_speeds_and_no_constraints():
    km, bodies, loads, s = _slider_on_parabola(aux=True)
    km.kanes_equations(bodies, loads)
    assert sc.kane_auxiliary_speeds(km) == [s["u3"]]
    x, u = me.dynamicsymbols("x u")
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, u * N.x)
    free = me.KanesMethod(N, q_ind=[x], u_ind=[u], kd_eqs=[x.diff() - u])
    free.kanes_equations([me.Particle("p", P, 1)], [])
    assert sc.kane_dependent_counts(free) == (0, 0)
    assert sc.kane_configuration_constraints(free).shape == (0, 1)


def test_lagrange_reads_match_the_lagrangian():
    q1, q2 = me.dynamicsymbols("q1 q2")
    m, g, L = sm.symbols("m g L")
    t = sc.time_symbol()
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    P = O.locatenew("P", q1 * N.x + q2 * N.y)
    P.set_vel(N, P.pos_from(O).dt(N))
    p = me.Particle("p", P, m)
    p.potential_energy = m * g * q2
    hol = [q1**2 + q2**2 - L**2]
    lm = me.LagrangesMethod(me.Lagrangian(N, p), [q1, q2], hol_coneqs=hol, frame=N)
    lm.form_lagranges_equations()
    M, f = sc.lagrange_dynamics(lm)
    # d/dt(m q') = -dV/dq, without the multiplier terms
    assert M == sm.diag(m, m)
    assert all(_zero(a - b) for a, b in zip(f, [0, -m * g]))
    fc = sc.lagrange_holonomic(lm)
    assert fc.shape == (1, 1) and _zero(fc[0] - hol[0])
    free = me.LagrangesMethod(me.Lagrangian(N, p), [q1, q2], frame=N)
    free.form_lagranges_equations()
    assert sc.lagrange_holonomic(free).shape == (0, 1)
    assert q1.diff(t) in lm.coneqs[0].atoms(sm.Derivative)
