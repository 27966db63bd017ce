"""Golden numbers: the seed pendulum's results stay BIT-IDENTICAL (C backend, double).

tests/golden/seed_numbers.json holds, for examples/seed_pendulum.py kane_model() and
lagrange_model() compiled with gen.compile(model), a list of public Simulator calls
(rhs, multipliers, mass_matrix, forcing, kinematics, constraints, constraint_jacobian,
velocity_constraints, velocity_constraint_matrix, energy, consistent_state, project,
step_rk4, linearize, simulate with rk4 and dopri5 and their solver statistics) with
their inputs and outputs, every float stored as float.hex(). Each test replays one
call with the current package and compares every output bit for bit (hex strings, so
even the sign of a zero counts) and every integer (row counts, n_rhs, n_accepted,
n_rejected) exactly.

The numbers were recorded from commit cbe7a5e, before the generator refactor.
A failure means the refactor changed the numbers. `python tests/golden/make_golden.py`
regenerates the JSON (from whatever `gen` is importable); run it ONLY when a change of
the numbers is intended, and explain that change in the commit that updates the file.
"""
import json
from pathlib import Path

import numpy as np
import pytest

GOLDEN = Path(__file__).resolve().parent / "golden" / "seed_numbers.json"
DATA = json.loads(GOLDEN.read_text())


def _dec(v):
    """A recorded argument: {"float": hex}, {"array": [hex], "shape": [...]} or plain."""
    if isinstance(v, dict):
        if "float" in v:
            return float.fromhex(v["float"])
        return np.array([float.fromhex(h) for h in v["array"]],
                        dtype=np.float64).reshape(v["shape"])
    return v


def _hex(a):
    return [float(v).hex() for v in np.asarray(a, dtype=np.float64).ravel()]


def _fpart(name, a):
    if isinstance(a, float):
        return {"name": name, "shape": None, "hex": [a.hex()], "dtype": "float"}
    a = np.asarray(a)
    return {"name": name, "shape": list(a.shape), "hex": _hex(a), "dtype": str(a.dtype)}


def _outputs(fn, result, keep_rows):
    """The result in the recorded form (see tests/golden/make_golden.py)."""
    if fn == "simulate":
        t, X = result[0], result[1]
        n = len(t)
        parts = [{"name": "n_rows", "int": n}]
        if keep_rows is None:
            idx = list(range(n))
        else:
            idx = sorted(set(range(0, n, keep_rows)) | {n - 1}) if n else []
            parts.append({"name": "rows", "int": idx})
        parts += [_fpart("t", np.asarray(t)[idx]), _fpart("X", np.asarray(X)[idx])]
        for extra in result[2:]:
            if isinstance(extra, dict):
                parts += [{"name": f"stats.{k}", "int": int(extra[k])} for k in sorted(extra)]
            else:
                parts.append(_fpart("lam", np.asarray(extra)[idx]))
        return parts
    if isinstance(result, tuple):
        names = {"linearize": ("A", "B"), "velocity_constraint_matrix": ("A", "b")}.get(
            fn, tuple(f"out{i}" for i in range(len(result))))
        return [_fpart(n, r) for n, r in zip(names, result)]
    return [_fpart("out", result)]


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


def _describe(rec):
    args = []
    for a in rec["args"]:
        v = _dec(a)
        args.append(np.array2string(v, precision=6) if isinstance(v, np.ndarray) else repr(v))
    args += [f"{k}={_dec(v)!r}" for k, v in rec["kwargs"].items()]
    return f"{rec['fn']}({', '.join(args)})"


CASES = [pytest.param(model, i, id=f"{model}-{i:02d}-{rec['fn']}")
         for model, m in DATA["models"].items() for i, rec in enumerate(m["calls"])]


@pytest.fixture(scope="module")
def sims(request):
    out = {}
    for model, m in DATA["models"].items():
        sim = request.getfixturevalue(f"{model}_sim")      # conftest: gen.compile(seed model)
        assert sim.name == m["name"] and list(sim.state_names) == m["state_names"], \
            f"{model}: compiled model {sim.name} {sim.state_names} is not the recorded one"
        assert sim.real == "double"
        out[model] = sim
    return out


def test_golden_file_is_complete():
    assert set(DATA["models"]) == {"kane", "lagrange"}
    for m in DATA["models"].values():
        fns = {r["fn"] for r in m["calls"]}
        assert {"rhs", "multipliers", "mass_matrix", "forcing", "constraints",
                "constraint_jacobian", "velocity_constraint_matrix", "consistent_state",
                "project", "step_rk4", "linearize", "simulate", "energy"} <= fns
        methods = {r["kwargs"].get("method") for r in m["calls"] if r["fn"] == "simulate"}
        assert methods == {"rk4", "dopri5"}


@pytest.mark.parametrize("model, i", CASES)
def test_bit_identical(sims, model, i):
    rec = DATA["models"][model]["calls"][i]
    fn = rec["fn"]
    args = [_dec(a) for a in rec["args"]]
    kwargs = {k: _dec(v) for k, v in rec["kwargs"].items()}
    got = _outputs(fn, replay(sims[model], fn, args, kwargs), rec.get("keep_rows"))
    want = rec["out"]
    where = f"{fn} on the {model} model, call #{i}: {_describe(rec)}"
    assert [p["name"] for p in got] == [p["name"] for p in want], \
        f"{where}: outputs {[p['name'] for p in got]}, recorded {[p['name'] for p in want]}"
    problems = []
    for g, w in zip(got, want):
        if "int" in w:
            if g["int"] != w["int"]:
                problems.append(f"{w['name']}: got {g['int']}, recorded {w['int']}")
            continue
        if g["dtype"] not in ("float64", "float"):
            problems.append(f"{w['name']}: dtype {g['dtype']}, recorded float64")
            continue
        if g["shape"] != w["shape"]:
            problems.append(f"{w['name']}: shape {g['shape']}, recorded {w['shape']}")
            continue
        if g["hex"] == w["hex"]:
            continue
        gv = np.array([float.fromhex(h) for h in g["hex"]])
        wv = np.array([float.fromhex(h) for h in w["hex"]])
        bad = [k for k, (a, b) in enumerate(zip(g["hex"], w["hex"])) if a != b]
        with np.errstate(invalid="ignore"):
            diff = float(np.max(np.abs(gv - wv)))
        k = bad[0]
        problems.append(f"{w['name']}: {len(bad)} of {len(wv)} values differ, max abs "
                        f"difference {diff:.3e} (first at flat index {k}: got {g['hex'][k]} "
                        f"= {gv[k]!r}, recorded {w['hex'][k]} = {wv[k]!r})")
    assert not problems, f"{where} is not bit-identical to the golden numbers:\n  " + \
        "\n  ".join(problems)
