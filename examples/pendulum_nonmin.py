"""The seed document, end to end: build the nonminimal-coordinates pendulum
with Kane's and with Lagrange's method exactly as the document does,
generate C99, compile it, print the compiled linearization next to
sympy's, simulate, and build and run the standalone binary with CMake.

    python examples/pendulum_nonmin.py [--out DIR] [--no-binary]
"""
import argparse
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import gen  # noqa: E402
import seed_pendulum as sp  # noqa: E402


def sympy_linearizations():
    """The document's two linearizations, as sympy prints them."""
    KM, s = sp.derive_kane()
    q_op = {s["q1"]: s["L"], s["q2"]: 0}
    u_op = {s["u1"]: 0, s["u2"]: 0}
    ud_op = {s["u1"].diff(s["t"]): 0, s["u2"].diff(s["t"]): 0}
    A_k, B_k, _ = KM.linearize(op_point=[q_op, u_op, ud_op], A_and_B=True, new_method=True,
                               simplify=True)
    LM, s2 = sp.derive_lagrange()
    t = s2["t"]
    op = {s2["q1"]: s2["L"], s2["q2"]: 0, s2["q1d"]: 0, s2["q2d"]: 0,
          s2["q1d"].diff(t): 0, s2["q2d"].diff(t): 0}
    op.update(LM.solve_multipliers(op_point=op))
    A_l, B_l, _ = LM.linearize([s2["q2"]], [s2["q2d"]], [s2["q1"]], [s2["q1d"]], op_point=op,
                               A_and_B=True)
    return (A_k, B_k, s), (A_l, B_l, s2)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/pendulum", help="where to write the generated projects")
    ap.add_argument("--no-binary", action="store_true", help="skip the CMake binary")
    args = ap.parse_args(argv)
    out = Path(args.out)
    L, g = 1.0, 9.81
    np.set_printoptions(precision=6, suppress=True)

    t0 = time.perf_counter()
    (A_k, B_k, s), (A_l, B_l, s2) = sympy_linearizations()
    print(f"sympy linearization (symbolic, {time.perf_counter() - t0:.1f} s for both):")
    print("  Kane     A =", A_k.tolist(), " B =", B_k.shape)
    print("  Lagrange A =", A_l.tolist(), " B =", B_l.shape)

    for label, build in (("Kane", sp.kane_model), ("Lagrange", sp.lagrange_model)):
        t0 = time.perf_counter()
        model = build(L=L, g=g)
        t1 = time.perf_counter()
        gen.generate(model, out / model.name)
        sim = gen.compile(model)
        t2 = time.perf_counter()
        hanging = ([0.0, L, 0.0, 0.0] if model.method == "kane" else [L, 0.0, 0.0, 0.0])
        A, B = sim.linearize(hanging)
        print(f"\n{label}: model '{model.name}' ({t1 - t0:.2f} s to form), generated and compiled "
              f"in {t2 - t1:.2f} s -> {out / model.name}")
        print("  state layout:", sim.state_names, " independent:", sim.independent_state_names)
        print("  compiled linearize at hanging rest: A =", (A + 0.0).tolist(), " B shape", B.shape)
        A_ref = (A_k if model.method == "kane" else A_l).subs({s["g"]: g, s["L"]: L,
                                                               s2["g"]: g, s2["L"]: L})
        print("  sympy's A at the same numbers:      ", np.array(A_ref.evalf(), dtype=float).tolist())
        th0 = np.radians(30.0)
        x0 = (np.array([L * np.sin(th0), L * np.cos(th0), 0, 0]) if model.method == "kane"
              else np.array([L * np.cos(th0), L * np.sin(th0), 0, 0]))
        t, X = sim.simulate(x0, 3.0, 0.001, method="rk4")
        y = X[:, sim.state_names.index("q2")]
        x = X[:, sim.state_names.index("q1")]
        print(f"  simulated 3 s (RK4, dt 1 ms) from a 30 degree release: final angle "
              f"{np.degrees(np.arctan2(y[-1], x[-1])):.6f} deg, "
              f"max |x^2+y^2-L^2| = {np.max(np.abs(x**2 + y**2 - L**2)):.2e}")

    if not args.no_binary:
        if shutil.which("cmake") is None:
            print("\ncmake not found: skipping the standalone binary")
            return 0
        src = out / "pendulum_kane"
        bld = out / "pendulum_kane_build"
        subprocess.run(["cmake", "-S", str(src), "-B", str(bld), "-DCMAKE_BUILD_TYPE=Release"],
                       check=True, stdout=subprocess.DEVNULL)
        subprocess.run(["cmake", "--build", str(bld)], check=True, stdout=subprocess.DEVNULL)
        exe = bld / "pendulum_kane_sim"
        csv = out / "pendulum_kane.csv"
        t0 = time.perf_counter()
        subprocess.run([str(exe), "--t-end", "10", "--dt", "0.001", "--x0", "q2=0.5",
                        "--x0", "q1=0.8660254037844386", "--output", str(csv)], check=True)
        dt = time.perf_counter() - t0
        rows = csv.read_text().splitlines()
        print(f"\nbinary {exe}: simulated 10 s in {dt * 1000:.1f} ms, {len(rows) - 1} rows -> {csv}")
        print("  " + rows[0])
        print("  " + rows[-1])
        print("binary's linearization at hanging rest:")
        res = subprocess.run([str(exe), "--linearize", "--x0", "q1=1"], check=True,
                             capture_output=True, text=True)
        print("  " + res.stdout.replace("\n", "\n  ").rstrip())
    return 0


if __name__ == "__main__":
    sys.exit(main())
