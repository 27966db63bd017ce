"""gen.EKF and gen.UKF next to filterpy 2.0 on the same model, in one run
(issue 44): one predict and one update of the cart-pole (examples/cart_pole.py,
the cart position and the angle measured, the force known), called from
Python.

    python bench/bench_estimator.py [--repeat 7] [--json out.json]

Rows, per filter kind (EKF, UKF), in microseconds per predict + update:

- filterpy, numpy model: filterpy's ExtendedKalmanFilter / UnscentedKalmanFilter
  with the model as the tests give it (tests/features/test_estimator.py):
  sympy's mass_matrix_full and forcing_full lambdified, RK4 in numpy, the
  EKF's F by complex-step differentiation of that step (4 complex steps);
- filterpy, eomgen's step: the same filterpy filters with the model in C
  (sim.step_sensitivity for the EKF's x and F, sim.step for the UKF's sigma
  points): filterpy's own matrix algebra and Python calls;
- gen: ekf.predict(r); ekf.update(z) (two C calls through the host module's
  CPython functions, csrc/host/gen_host_fast.c);
- gen, step: ekf.step(z, r) (the same in one C call);
- gen, batch: ekf.filter over a recording (one C call), per step.

Each row's time is the median of --repeat runs (interleaved); a run times a
block of steps on a recording of the cart-pole pushed by a known force, by
the wall clock or (--clock cpu) by the process's CPU time, which leaves out
the time other jobs on a shared machine hold the core (not their effect on
the caches).
Ratios are the peer's time over gen's (predict + update from Python), in the
same run. Nothing is asserted.
"""
import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import sympy as sm

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))

import cart_pole as cp  # noqa: E402
import gen  # noqa: E402

DT = 0.01
Q = np.diag([1e-8, 1e-8, 1e-6, 1e-6])
R = np.array([1e-4, 1e-4])
X0, P0 = np.array([0.05, 0.1, 0.0, 0.0]), np.diag([1e-2, 1e-2, 1e-1, 1e-1])
H = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])


class NumpyModel:
    """sympy's equations lambdified, RK4 in numpy, complex-step Jacobian."""

    def __init__(self, km, s):
        vals = {s[k]: v for k, v in cp.DEFAULTS.items()}
        X, F = sm.symbols("X0:4"), sm.Symbol("F_in")
        sub = dict(zip([s["x"], s["theta"], s["v"], s["omega"]], X))
        sub[s["F"]] = F
        self.M = sm.lambdify([X, F], km.mass_matrix_full.subs(vals).xreplace(sub), "numpy")
        self.f = sm.lambdify([X, F], km.forcing_full.subs(vals).xreplace(sub), "numpy")

    def rhs(self, x, r):
        dt = complex if np.iscomplexobj(x) else float
        return np.linalg.solve(np.array(self.M(x, r), dtype=dt),
                               np.array(self.f(x, r), dtype=dt).ravel())

    def step(self, x, r, h=DT):
        k1 = self.rhs(x, r)
        k2 = self.rhs(x + h / 2 * k1, r)
        k3 = self.rhs(x + h / 2 * k2, r)
        k4 = self.rhs(x + h * k3, r)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def jacobian(self, x, r, eps=1e-30):
        J = np.zeros((4, 4))
        for j in range(4):
            xc = x.astype(complex)
            xc[j] += 1j * eps
            J[:, j] = self.step(xc, r).imag / eps
        return J


def recording(sim, n):
    t = DT * np.arange(n)
    Rin = 0.5 * np.sin(0.5 * t)[:, None]
    sol = sim.simulate([0.0, 0.15, 0.0, 0.0], t[-1], DT, r=(t, Rin), input_hold="zoh")
    rng = np.random.default_rng(0)
    return t, sol.x[:, :2] + 0.01 * rng.normal(size=(n, 2)), Rin


def filterpy_ekf(step, jac):
    from filterpy.kalman import ExtendedKalmanFilter

    class EKF(ExtendedKalmanFilter):
        def predict_x(self, u=0):
            self.x = step(self.x, u)

    f = EKF(4, 2)
    f.x, f.P, f.Q, f.R = X0.copy(), P0.copy(), Q, np.diag(R)

    def run(Z, Rin):
        for k in range(1, len(Z)):
            f.F = jac(f.x, Rin[k - 1, 0])
            f.predict(u=Rin[k - 1, 0])
            f.update(Z[k], HJacobian=lambda x: H, Hx=lambda x: H @ x)
    return run


def filterpy_ukf(step):
    from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter
    pts = MerweScaledSigmaPoints(4, alpha=0.1, beta=2.0, kappa=0.0)
    f = UnscentedKalmanFilter(4, 2, DT, hx=lambda x: x[:2], fx=lambda x, dt, u: step(x, u),
                              points=pts)
    f.x, f.P, f.Q, f.R = X0.copy(), P0.copy(), Q, np.diag(R)

    def run(Z, Rin):
        for k in range(1, len(Z)):
            f.predict(u=Rin[k - 1, 0])
            f.update(Z[k])
    return run


def ours(kf):
    def run(Z, Rin):
        kf.reset(X0, P0, t0=0.0)
        for k in range(1, len(Z)):
            kf.predict(Rin[k - 1])
            kf.update(Z[k])
    return run


def ours_step(kf):
    def run(Z, Rin):
        kf.reset(X0, P0, t0=0.0)
        for k in range(1, len(Z)):
            kf.step(Z[k], Rin[k - 1])
    return run


def ours_batch(kf):
    def run(Z, Rin):
        kf.reset(X0, P0, t0=0.0)
        kf.filter(DT * np.arange(len(Z)), Z, Rin)
    return run


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--json")
    ap.add_argument("--clock", choices=["wall", "cpu"], default="wall")
    a = ap.parse_args(argv)
    clock = time.perf_counter if a.clock == "wall" else time.process_time
    km, s = cp.derive()
    model = cp.model()
    sim = gen.compile(model)
    nm = NumpyModel(km, s)

    def c_step(x, u):
        return sim.step(0.0, x, DT, r=[u], project=False)

    def c_jac(x, u):
        return sim.step_sensitivity(0.0, x, DT, r=[u])[1]

    z = {"x_m": s["x"], "th_m": s["theta"]}
    ekf = gen.EKF(model, z, DT, Q, R, X0, P0, gate=None)
    ukf = gen.UKF(model, z, DT, Q, R, X0, P0, alpha=0.1, gate=None)
    t, Z, Rin = recording(sim, 2001)
    blocks = {  # (steps per timed block, function)
        ("EKF", "filterpy, numpy model"): (100, filterpy_ekf(nm.step, nm.jacobian)),
        ("EKF", "filterpy, eomgen's step"): (400, filterpy_ekf(c_step, c_jac)),
        ("EKF", "gen: predict + update"): (2000, ours(ekf)),
        ("EKF", "gen: step (one call)"): (2000, ours_step(ekf)),
        ("EKF", "gen: filter (one C call)"): (2000, ours_batch(ekf)),
        ("UKF", "filterpy, numpy model"): (100, filterpy_ukf(nm.step)),
        ("UKF", "filterpy, eomgen's step"): (400, filterpy_ukf(c_step)),
        ("UKF", "gen: predict + update"): (2000, ours(ukf)),
        ("UKF", "gen: step (one call)"): (2000, ours_step(ukf)),
        ("UKF", "gen: filter (one C call)"): (2000, ours_batch(ukf)),
    }
    times = {k: [] for k in blocks}
    for _ in range(a.repeat):
        for key, (n, run) in blocks.items():
            t0 = clock()
            run(Z[:n + 1], Rin[:n + 1])
            times[key].append((clock() - t0) / n * 1e6)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"cart-pole, position and angle measured; microseconds per predict + update "
          f"(median of {a.repeat}, {a.clock} clock); ratio = time / gen's predict + update")
    out = {}
    for kind in ("EKF", "UKF"):
        base = med[(kind, "gen: predict + update")]
        print(f"\n{kind}")
        for (k, label), v in med.items():
            if k == kind:
                print(f"  {label:28s} {v:10.2f} us   x{v / base:8.1f}")
                out[f"{kind}: {label}"] = {"us": v, "ratio": v / base}
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
