"""Record the golden numbers of the seed pendulum (C backend, double) in
tests/golden/seed_numbers.json, checked bit for bit by tests/golden/test_golden_numbers.py.

Run it only when a change of the numbers is intended and explained (say why in the
commit that updates the JSON):

    python tests/golden/make_golden.py            # with the package to record on sys.path
    python tests/golden/make_golden.py -o OUT.json

Models: examples/seed_pendulum.py kane_model() and lagrange_model(), compiled with
gen.compile(model) (backend "c", real "double"). Every value goes through the public
Simulator API. Each record holds the call (method name, arguments, keyword arguments)
and its outputs; every float, input or output, is stored as float.hex() so that the
test replays exactly the same calls and compares exactly. The examples are taken from
the checkout the imported `gen` package lives in (falling back to this repository's).

The JSON also holds the platform's fingerprint (fingerprint(): machine, OS, C library,
compiler and its version, the C flags): the test compares bit for bit where it matches
and to a stated tolerance elsewhere. The fingerprint was added on 2026-11-27 to the
numbers recorded at 725e9d7, after a rerun here reproduced every one of them.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
OUT = HERE / "seed_numbers.json"
FORMAT = 1

# simulate(method="rk4"): keep every RK4_STRIDE-th output row plus the last one
RK4_STRIDE = 100


# --------------------------------------------------------------- fingerprint
# What decides the bits of the golden numbers: the machine's arithmetic, the
# C library (its libm: sin, cos, sqrt, atan2), the compiler, its version and
# the flags gen.compile passes. tests/golden/test_golden_numbers.py compares bit for
# bit only where these match the recorded ones, and to a stated tolerance
# elsewhere. Python's and numpy's versions are recorded for information only:
# every number is computed by the compiled C (numpy only carries the float64
# arrays), so they are not part of the match.
FINGERPRINT_KEYS = ("machine", "system", "libc", "compiler", "compiler_version", "c_flags")


def compiler_command():
    """The C compiler gen.compile runs, by its rule (gen/toolchain/build.py): $CC, else
    clang when it is installed, else the compiler Python was built with."""
    cc = os.environ.get("CC")
    if not cc:
        cc = "clang" if shutil.which("clang") else (sysconfig.get_config_var("CC") or "cc")
    return cc.split()[0]


def _compiler_version(cc):
    try:
        out = subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=30)
        return (out.stdout.strip().splitlines() or ["unknown"])[0]
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _c_flags():
    """The flags of a model's compile that matter for its numbers (the
    optimization and floating-point ones): gen's C_FLAGS and C_LIN_FLAGS,
    wherever the package keeps them."""
    import importlib
    for mod in ("gen.toolchain.build", "gen.build", "gen.pipeline", "gen.cache"):
        try:
            m = importlib.import_module(mod)
        except ImportError:
            continue
        if hasattr(m, "C_FLAGS"):
            return " ".join([*m.C_FLAGS, "lin:", *getattr(m, "C_LIN_FLAGS", [])])
    return "unknown"


def fingerprint():
    """The platform and compiler the golden numbers are computed with here."""
    import numpy
    try:    # the C library running (platform.libc_ver reads the executable's)
        libc = os.confstr("CS_GNU_LIBC_VERSION")
    except (AttributeError, ValueError, OSError):
        libc = None
    if not libc:
        name, version = platform.libc_ver()
        libc = f"{name or 'unknown'} {version}".strip()
    cc = compiler_command()
    return {"machine": platform.machine(), "system": platform.system(), "libc": libc,
            "compiler": os.path.basename(cc), "compiler_version": _compiler_version(cc),
            "c_flags": _c_flags(),
            # information only (not compared)
            "python": platform.python_version(), "numpy": numpy.__version__}


def fingerprint_differences(recorded, running):
    """The keys of FINGERPRINT_KEYS where two fingerprints differ (a missing
    fingerprint differs in every key)."""
    recorded = recorded or {}
    return [k for k in FINGERPRINT_KEYS if recorded.get(k) != running.get(k)]


# ------------------------------------------------------------------ encoding
def hexs(a):
    return [float(v).hex() for v in np.asarray(a, dtype=np.float64).ravel()]


def enc(v):
    """An argument as JSON: floats (and float arrays) as hex strings."""
    if isinstance(v, (bool, str, int)) or v is None:
        return v
    if isinstance(v, float):
        return {"float": v.hex()}
    a = np.asarray(v, dtype=np.float64)
    return {"array": hexs(a), "shape": list(a.shape)}


def dec(v):
    """The inverse of enc: the exact Python float / float64 array."""
    if isinstance(v, dict):
        if "float" in v:
            return float.fromhex(v["float"])
        return np.array([float.fromhex(h) for h in v["array"]],
                        dtype=np.float64).reshape(v["shape"])
    return v


def rows_kept(n, stride):
    return sorted(set(range(0, n, stride)) | {n - 1}) if n else []


def outputs(fn, result, keep_rows=None):
    """A call's result as a list of named parts: float parts carry shape and hex
    values, integer parts (solver statistics, row counts) their exact value."""
    if fn == "simulate":
        t, X = result[0], result[1]
        parts = [{"name": "n_rows", "int": int(len(t))}]
        idx = list(range(len(t))) if keep_rows is None else rows_kept(len(t), keep_rows)
        if keep_rows is not None:
            parts.append({"name": "rows", "int": idx})
        parts.append(_fpart("t", np.asarray(t)[idx]))
        parts.append(_fpart("X", np.asarray(X)[idx]))
        for extra in result[2:]:
            if isinstance(extra, dict):                    # return_stats
                for k in sorted(extra):
                    parts.append({"name": f"stats.{k}", "int": int(extra[k])})
            else:                                          # return_multipliers
                parts.append(_fpart("lam", np.asarray(extra)[idx]))
        return parts
    if isinstance(result, tuple):
        names = {"linearize": ("A", "B"), "velocity_constraint_matrix": ("A", "b")}.get(
            fn, tuple(f"out{i}" for i in range(len(result))))
        return [_fpart(n, r) for n, r in zip(names, result)]
    return [_fpart("out", result)]


def _fpart(name, a):
    if isinstance(a, float):
        return {"name": name, "shape": None, "hex": [a.hex()]}
    a = np.asarray(a)
    assert a.dtype == np.float64, (name, a.dtype)
    return {"name": name, "shape": list(a.shape), "hex": hexs(a)}


# the recorded stats (the Solution's stats has more keys: n_steps, ...)
STATS = ("n_accepted", "n_jac", "n_out", "n_rejected", "n_rhs")


def replay(sim, fn, args, kwargs):
    """A recorded call in today's API: the records name step_rk4 (now
    step(method="rk4")) and simulate's former return_multipliers= and
    return_stats= flags (now attributes of the gen.Solution), kept as the
    tuple they recorded: (t, X[, lam][, stats])."""
    kwargs = dict(kwargs)
    if fn == "step_rk4":
        return sim.step(*args, method="rk4", **kwargs)
    if fn == "simulate":
        lam = kwargs.pop("return_multipliers", False)
        stats = kwargs.pop("return_stats", False)
        sol = sim.simulate(*args, **kwargs)
        out = [sol.t, sol.x]
        if lam:
            out.append(sol.lam)
        if stats:
            out.append({k: sol.stats[k] for k in STATS})
        return tuple(out)
    return getattr(sim, fn)(*args, **kwargs)


def call(sim, rec):
    """Replay one record on a Simulator; returns the encoded outputs."""
    args = [dec(a) for a in rec["args"]]
    kwargs = {k: dec(v) for k, v in rec.get("kwargs", {}).items()}
    result = replay(sim, rec["fn"], args, kwargs)
    return outputs(rec["fn"], result, rec.get("keep_rows"))


# ------------------------------------------------------------------ the calls
def state_inputs(method):
    """The fixed inputs, as [q2, q1, u2, u1] (Kane) or [q1, q2, q1', q2']
    (Lagrange). Guesses go through consistent_state; the 'off' state is off the
    constraint manifold on purpose (for project, rhs and friends)."""
    def x(q1, q2, u1, u2):   # physical values -> the model's state layout
        if method == "kane":
            return np.array([q2, q1, u2, u1])
        return np.array([q1, q2, u1, u2])
    return {
        # consistent_state guesses: independent q2 (and u2), dependent entries a guess
        "guess_static": x(0.9, 0.3, 0.0, 0.0),
        "guess_moving": x(0.9, 0.3, 0.0, 0.7),
        "guess_hanging": x(0.98, 0.0, 0.0, 0.0),
        "guess_far": x(-0.4, -0.8, 0.3, -1.1),
        # deliberately off the manifold |q| = L = 1, A u + b = 0
        "off": x(0.97, 0.31, 0.2, 0.5),
    }


def build_records(sim, method):
    """The list of calls for one model. States that come out of
    consistent_state are fed as recorded hex inputs to the later calls, so
    every record replays on its own."""
    nq = sim.nq
    s = state_inputs(method)
    recs = []

    def add(fn, *args, keep_rows=None, **kwargs):
        rec = {"fn": fn, "args": [enc(a) for a in args],
               "kwargs": {k: enc(v) for k, v in kwargs.items()}}
        if keep_rows is not None:
            rec["keep_rows"] = keep_rows
        rec["out"] = call(sim, rec)                 # run from the encoded inputs
        recs.append(rec)
        return rec

    def first_out(rec):
        p = rec["out"][0]
        return np.array([float.fromhex(h) for h in p["hex"]]).reshape(p["shape"])

    states = {}
    for name in ("static", "moving", "hanging", "far"):
        states[name] = first_out(add("consistent_state", s[f"guess_{name}"]))
    states["off"] = s["off"]
    states["projected"] = first_out(add("project", s["off"]))
    p_alt = np.array([1.25, 0.8, 9.5])           # L, m, g (constant_names order)
    assert list(sim.constant_names) == ["L", "m", "g"], sim.constant_names

    for name in ("static", "moving", "far", "off"):
        x = states[name]
        q, u = x[:nq], x[nq:]
        add("rhs", 0.0, x)
        add("multipliers", 0.0, x)
        add("mass_matrix", q)
        add("forcing", q, u)
        add("kinematics", q, u)
        add("constraints", q)
        add("constraint_jacobian", q)
        add("velocity_constraints", q, u)
        add("velocity_constraint_matrix", q)
        add("energy", x)
    x = states["moving"]
    add("rhs", 0.5, x, p=p_alt)
    add("multipliers", 0.5, x, p=p_alt)
    add("forcing", x[:nq], x[nq:], p=p_alt)
    add("project", states["moving"] * 1.01)
    add("project", s["off"], p=p_alt)
    add("consistent_state", s["guess_moving"], p=p_alt)

    add("step_rk4", 0.0, states["moving"], 0.01)
    add("step_rk4", 0.3, states["moving"], 0.05, project=False)
    add("step_rk4", 0.0, states["far"], 0.02)

    for name in ("static", "moving", "hanging"):
        add("linearize", states[name])
    add("linearize", states["moving"], p=p_alt)

    add("simulate", states["moving"], 2.0, 1e-3, method="rk4", keep_rows=RK4_STRIDE)
    add("simulate", states["static"], 2.0, 1e-3, method="rk4", project=False,
        keep_rows=RK4_STRIDE)
    add("simulate", states["moving"], 2.0, 0.05, method="dopri5", rtol=1e-9, atol=1e-12,
        return_stats=True, return_multipliers=True)
    add("simulate", states["far"], 2.0, 0.05, method="dopri5", rtol=1e-9, atol=1e-12,
        return_stats=True)
    return recs


# ------------------------------------------------------------------ main
def _examples_dir(gen):
    cand = Path(gen.__file__).resolve().parent.parent / "examples"
    return cand if (cand / "seed_pendulum.py").is_file() else ROOT / "examples"


def _git_head(d):
    try:
        return subprocess.run(["git", "-C", str(d), "rev-parse", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except Exception:  # noqa: BLE001 - informational only
        return None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", default=str(OUT))
    a = ap.parse_args(argv)

    import gen
    ex = _examples_dir(gen)
    sys.path.insert(0, str(ex))
    import seed_pendulum as sp

    pkg = Path(gen.__file__).resolve().parent
    print(f"gen from {pkg}, examples from {ex}")
    doc = {
        "format": FORMAT,
        "about": "golden numbers of the seed pendulum, C backend, double; "
                 "floats are float.hex(); checked bit for bit by tests/golden/test_golden_numbers.py; "
                 "regenerate with tests/golden/make_golden.py only for an intended change",
        "recorded_with": {"commit": _git_head(pkg.parent), "python": platform.python_version(),
                          "numpy": np.__version__, "machine": platform.machine()},
        # bit for bit where this matches (tests/golden/test_golden_numbers.py)
        "fingerprint": fingerprint(),
        "rk4_stride": RK4_STRIDE,
        "models": {},
    }
    for key, factory, method in (("kane", sp.kane_model, "kane"),
                                 ("lagrange", sp.lagrange_model, "lagrange")):
        model = factory()
        sim = gen.compile(model)
        assert sim.real == "double" and sim.dtype == np.float64
        doc["models"][key] = {"factory": factory.__name__, "name": sim.name,
                              "state_names": list(sim.state_names),
                              "calls": build_records(sim, method)}
        n = sum(len(p.get("hex", ())) for r in doc["models"][key]["calls"] for p in r["out"])
        print(f"{key}: {len(doc['models'][key]['calls'])} calls, {n} float values")
    text = json.dumps(doc, indent=0, separators=(",", ":")) + "\n"
    Path(a.output).write_text(text)
    print(f"wrote {a.output} ({len(text) // 1024} KB)")


if __name__ == "__main__":
    main()
