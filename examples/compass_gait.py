"""A powered compass-gait walker on flat ground: the least-effort periodic
gait for a given step length, found by gen.OptimalControl across its heel
strike and replayed through the simulator.

    python examples/compass_gait.py [out.png]

A hip mass M_h and two legs of length l, each with a point mass m at a
distance b from the hip (b = l: Garcia's walker with finite feet), and a
motor at the hip: a torque tau on the swing leg, -tau on the stance leg
(g = l = 1). theta is the stance leg's angle from the vertical, phi the angle
between the legs (the swing leg at theta - phi), as in
examples/simplest_walker.py; the speeds are omega = theta' and
mu = phi' - 2 theta', the swing foot's approach to the ground. The motor's
torque tau is a state driven by its rate sigma, the input, so that it is
continuous. The heel strike is a ``gen.Reset``: when phi - 2 theta crosses
zero upwards (the swing foot reaches the ground ahead), the legs swap
(theta -> theta - phi, phi -> -phi, tau -> -tau: the same motor torque on
the other leg) and the speeds jump by conservation of angular momentum
through the impulse at the new foot: the whole walker's about the new stance
foot, and the trailing leg's about the hip (the old stance foot leaves the
ground without an impulse).
"""
import sys

import numpy as np
import sympy as sm
from sympy.physics import mechanics as me

import gen


def _walker():
    """The frames, points and particles in theta, phi and their speeds."""
    th, ph, tau = me.dynamicsymbols("theta phi tau")
    Mh, m, b, g, l = sm.symbols("M_h m b g l")
    N = me.ReferenceFrame("N")                                  # x forward, y up
    S = N.orientnew("S", "Axis", [th, N.z])                     # stance leg
    W = N.orientnew("W", "Axis", [th - ph, N.z])                # swing leg
    foot = me.Point("foot")
    foot.set_vel(N, 0)
    hip = foot.locatenew("hip", l * S.y)
    pS = hip.locatenew("pS", -b * S.y)
    pW = hip.locatenew("pW", -b * W.y)
    swing_foot = hip.locatenew("swing_foot", -l * W.y)
    for P in (hip, pS, pW, swing_foot):
        P.set_vel(N, P.pos_from(foot).dt(N))
    parts = [me.Particle("hip_mass", hip, Mh), me.Particle("stance_mass", pS, m),
             me.Particle("swing_mass", pW, m)]
    return dict(th=th, ph=ph, tau=tau, consts=(Mh, m, b, g, l), N=N, S=S, W=W, foot=foot,
                hip=hip, swing_foot=swing_foot, parts=parts)


def heelstrike_map(w):
    """The heel strike's map {theta, phi, theta', phi'} -> the state after it:
    the legs swap, and the speeds after solve the two angular-momentum
    balances (the walker's about the new stance foot, the trailing leg's
    about the hip) equal before and after."""
    th, ph, N = w["th"], w["ph"], w["N"]
    thd, phd = th.diff(), ph.diff()
    _, stance_mass, swing_mass = w["parts"]
    # before: in the old labels, about the swing foot and the hip
    H_all = me.angular_momentum(w["swing_foot"], N, *w["parts"]).dot(N.z)
    H_leg = me.angular_momentum(w["hip"], N, stance_mass).dot(N.z)
    # after: the same expressions about the new stance foot (the origin) and
    # the hip, of the new speeds a, c in the new angles
    a, c, th1, ph1 = sm.symbols("a c theta_1 phi_1")
    new = {thd: a, phd: c, th: th1, ph: ph1}
    H_all_1 = me.angular_momentum(w["foot"], N, *w["parts"]).dot(N.z).subs(new)
    H_leg_1 = me.angular_momentum(w["hip"], N, swing_mass).dot(N.z).subs(new)
    after = {th1: th - ph, ph1: -ph}
    lhs = sm.Matrix([H_all_1, H_leg_1]).xreplace(after)        # linear in a, c
    A = lhs.jacobian([a, c])
    ac = A.LUsolve(sm.Matrix([H_all, H_leg]))
    return {th: th - ph, ph: -ph, thd: ac[0], phd: ac[1]}


def model(Mh=1.0, m=0.5, b=0.5, name="compass_gait"):
    """The gen.Model: states theta, phi, their speeds omega, nu, and the hip
    torque tau, driven by its rate sigma (the input): tau is continuous, and
    the motor's torque, between the legs, is continuous across the strike
    (tau on the swing leg becomes -tau on it after the legs swap). The heel
    strike is a gen.Reset named "heelstrike"."""
    w = _walker()
    th, ph, tau, N = w["th"], w["ph"], w["tau"], w["N"]
    Mh_, m_, b_, g, l = w["consts"]
    for P in w["parts"]:
        P.potential_energy = P.mass * g * P.point.pos_from(w["foot"]).dot(N.y)
    L = me.Lagrangian(N, *w["parts"])
    loads = [(w["W"], tau * N.z), (w["S"], -tau * N.z)]
    lm = me.LagrangesMethod(L, [th, ph], forcelist=loads, frame=N)
    lm.form_lagranges_equations()
    # the speeds: omega = theta' and mu = phi' - 2 theta', the guard's rate
    # (the swing foot's approach to the ground, which powered_gait gives)
    om, mu, sigma = me.dynamicsymbols("omega mu sigma")
    speeds = {th.diff(): om, ph.diff(): mu + 2 * om}
    Tm = sm.Matrix([[1, 0], [2, 1]])                    # q'' = Tm [omega', mu']
    Mq = Tm.T * lm.mass_matrix.xreplace(speeds) * Tm
    fq = Tm.T * lm.forcing.xreplace(speeds)
    M = sm.diag(Mq, sm.Matrix([[1]]))
    f = sm.Matrix([fq[0], fq[1], sigma])
    jump = {k: v.xreplace(speeds) for k, v in heelstrike_map(w).items()}
    strike = {th: jump[th], ph: jump[ph], om: jump[th.diff()],
              mu: jump[ph.diff()] - 2 * jump[th.diff()], tau: -tau}
    return gen.Model.from_matrices(
        M, f, [th, ph], [om, mu, tau], sm.Matrix([th.diff() - om, ph.diff() - mu - 2 * om]),
        constants={Mh_: Mh, m_: m, b_: b, g: 1.0, l: 1.0}, inputs=[sigma], name=name,
        hybrid={"heelstrike": gen.Reset(ph - 2 * th, strike, direction=1)})


def powered_gait(model, step=0.5, time=2.0, approach=0.2, nodes=41, eps=0.1, guess=None,
                 tol=1e-10):
    """The least-effort gait of step length ``step`` (between the feet at the
    strike: 2 l sin(theta)) in the step time ``time``: one phase ending on
    the heel strike, periodic, minimising the integral of tau^2 + eps
    sigma^2 over the step (eps: a small price on the torque's rate). The
    step time is given: the effort falls as the step slows."""
    th, mu = model.q_orig[0], model.u_orig[1]
    tau, sigma = model.u_orig[2], model.r_orig[0]
    a = float(np.arcsin(step / 2))
    if guess is None:
        s = np.linspace(0, 1, nodes)
        guess = {"theta": a * (1 - 2 * s), "phi": 2 * a * np.cos(np.pi * s),
                 "omega": -2 * a * np.ones(nodes) / time,
                 "mu": -2 * np.pi * a / time * np.sin(np.pi * s), "duration": time}
    ocp = gen.OptimalControl(model, nodes, (time, time), objective=tau**2 + eps * sigma**2,
                             method="hermite-simpson", events=["heelstrike"], periodic=True,
                             initial={th: a}, final={mu: approach})
    return ocp, ocp.solve(guess, tol=tol, print_level=0)


def main():
    walker = model()
    ocp, sol = powered_gait(walker, nodes=81, tol=1e-12)
    T = sol.t[-1]
    print(f"{sol.message}; step 0.5 in {T}: integral of tau^2 "
          f"{np.trapezoid(sol.x[:, 4] ** 2, sol.t):.6f}, max |tau| {np.abs(sol.x[:, 4]).max():.4f}")
    run = ocp.simulator.simulate(sol.x[0], 1.05 * T, 0.01, r=lambda t, x: sol.input(min(t, T)),
                                 method="dopri5", input_period=0, rtol=1e-13, atol=1e-13)
    (strike,) = [e for e in run.events if e.name == "heelstrike"]
    print(f"replayed: the strike {strike.t - T:.1e} from the optimum's, the state after it "
          f"{np.abs(strike.x_after - sol.x[0]).max():.1e} from the start")
    if len(sys.argv) > 1:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.2))
        for k in range(3):                 # the motor's torque on leg A: tau, -tau, tau
            sign = 1 if k % 2 == 0 else -1
            ax1.plot(sol.t + k * T, sign * sol.x[:, 4], "C0")
            ax1.axvline((k + 1) * T, color="k", lw=0.5, ls=":")
        ax1.set(xlabel="t (√(l/g))", ylabel="hip torque on leg A (Mgl)",
                title="the motor's torque over three steps")
        ax2.plot(run.t, run.x[:, 0], label="θ (stance), replayed")
        ax2.plot(run.t, run.x[:, 1], label="φ (between the legs), replayed")
        ax2.plot(sol.t, sol.x[:, 0], ".", ms=3, color="C0")
        ax2.plot(sol.t, sol.x[:, 1], ".", ms=3, color="C1")
        ax2.set(xlabel="t (√(l/g))", ylabel="angle (rad)", title="a step and its heel strike")
        ax2.legend(fontsize=7, loc="lower left")
        fig.tight_layout()
        fig.savefig(sys.argv[1], dpi=80)


if __name__ == "__main__":
    main()
