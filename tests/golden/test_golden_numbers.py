"""Golden numbers: the seed pendulum's results stay BIT-IDENTICAL (C backend, double) on
the platform they were recorded on, and within a stated tolerance elsewhere.

tests/golden/seed_numbers.json holds, for examples/seed_pendulum.py kane_model() and
lagrange_model() compiled with gen.compile(model), a list of public Simulator calls
(rhs, multipliers, mass_matrix, forcing, kinematics, constraints, constraint_jacobian,
velocity_constraints, velocity_constraint_matrix, energy, consistent_state, project,
step_rk4, linearize, simulate with rk4 and dopri5 and their solver statistics) with
their inputs and outputs, every float stored as float.hex(). Each test replays one
call with the current package and compares every output bit for bit (hex strings, so
even the sign of a zero counts) and every integer (row counts, n_rhs, n_accepted,
n_rejected) exactly.

Bit for bit where they were recorded: the JSON's "fingerprint" (machine, OS, C library
and version, compiler and version, the compile flags; tests/golden/make_golden.py
fingerprint()) is compared with this machine's. Where any of them differs, another libm
or compiler may round differently though nothing is wrong, so each float is compared
to a stated tolerance instead (TOLERANCE below: 1e-12 relative to the part's largest
magnitude, at least 1, looser for the long runs), the solver statistics within 10% (at
least 3), the row counts still exactly; the test output says which comparison ran (a
GoldenToleranceWarning, a printed line and the golden_comparison property, with -rA).

The numbers were recorded from commit cbe7a5e, before the generator refactor.
A failure means the refactor changed the numbers. `python tests/golden/make_golden.py`
regenerates the JSON (from whatever `gen` is importable); run it ONLY when a change of
the numbers is intended, and explain that change in the commit that updates the file.
"""
import copy
import functools
import json
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

GOLDEN = Path(__file__).resolve().parents[1] / "golden" / "seed_numbers.json"
DATA = json.loads(GOLDEN.read_text())
sys.path.insert(0, str(GOLDEN.parent))
import make_golden  # noqa: E402  (tests/golden/make_golden.py: the fingerprint)

# Off the recorded platform: each float part g of a call is compared to the recorded w
# as max |g - w| <= rtol * max(max |w|, 1) (the seed's quantities are of order 1; a
# residual that is rounding noise at a consistent state passes). rtol by call:
TOLERANCE = {
    "default": 1e-12,           # one evaluation, one RK4 step, a Newton projection
    "linearize": 1e-10,         # solves with the mass matrix and the constraint partition
    "simulate:rk4": 1e-9,       # 2000 steps: rounding differences accumulate
    "simulate:dopri5": 1e-6,    # rtol 1e-9 runs: another rounding may move a step
}
STATS_RTOL, STATS_ATOL = 0.1, 3    # solver statistics (n_rhs, n_accepted, n_rejected)


class GoldenToleranceWarning(UserWarning):
    """The golden numbers are compared to a tolerance, not bit for bit."""


@functools.lru_cache(maxsize=1)
def running_fingerprint():
    return make_golden.fingerprint()


def comparison():
    """("bitwise", why) where this machine's fingerprint matches the recorded one,
    else ("tolerance", why)."""
    recorded = DATA.get("fingerprint")
    running = running_fingerprint()
    diff = make_golden.fingerprint_differences(recorded, running)
    if not diff:
        return "bitwise", ("golden numbers compared bit for bit: this platform matches the "
                           "recorded fingerprint")
    what = "; ".join(f"{k}: recorded {(recorded or {}).get(k)!r}, here {running.get(k)!r}"
                     for k in diff)
    return "tolerance", (f"golden numbers compared to a tolerance, not bit for bit "
                         f"(relative {TOLERANCE['default']:g}, linearize "
                         f"{TOLERANCE['linearize']:g}, rk4 runs {TOLERANCE['simulate:rk4']:g}, "
                         f"dopri5 runs {TOLERANCE['simulate:dopri5']:g}): the platform differs "
                         f"from the recorded one in {what}")


def rtol_of(rec):
    if rec["fn"] == "simulate":
        return TOLERANCE[f"simulate:{rec['kwargs'].get('method', 'rk4')}"]
    return TOLERANCE.get(rec["fn"], TOLERANCE["default"])


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


# a recorded call in today's API: the recorder's own translation (tests/golden/make_golden.py)
STATS = make_golden.STATS


def call_recorded(sim, fn, args, kwargs):
    return make_golden.replay(sim, fn, args, kwargs)


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


@pytest.fixture(scope="module")
def mode():
    """The comparison on this platform; a warning when it is not bit for bit."""
    how, why = comparison()
    if how != "bitwise":
        warnings.warn(why, GoldenToleranceWarning)
    return how, why


def compare(rec, got, how):
    """The problems of the outputs got against the record rec: bit for bit (how ==
    "bitwise") or to the record's tolerance (how == "tolerance")."""
    want = rec["out"]
    if [p["name"] for p in got] != [p["name"] for p in want]:
        return [f"outputs {[p['name'] for p in got]}, recorded {[p['name'] for p in want]}"]
    rtol = rtol_of(rec)
    problems = []
    for g, w in zip(got, want):
        if "int" in w:
            if g["int"] == w["int"]:
                continue
            if (how == "tolerance" and w["name"].startswith("stats.")
                    and abs(g["int"] - w["int"]) <= max(STATS_ATOL, STATS_RTOL * abs(w["int"]))):
                continue
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
        with np.errstate(invalid="ignore"):
            err = np.abs(gv - wv)
        err[np.isnan(gv) & np.isnan(wv)] = 0.0
        if how == "tolerance":
            bound = rtol * max(float(np.max(np.abs(wv), initial=0.0)), 1.0)
            if np.all(err <= bound):
                continue
            k = int(np.argmax(np.where(np.isnan(err), np.inf, err)))
            problems.append(f"{w['name']}: max |difference| {float(err[k]):.3e} > tolerance "
                            f"{bound:.3e} (relative {rtol:g}; at flat index {k}: got "
                            f"{gv[k]!r}, recorded {wv[k]!r})")
            continue
        bad = [k for k, (a, b) in enumerate(zip(g["hex"], w["hex"])) if a != b]
        k = bad[0]
        problems.append(f"{w['name']}: {len(bad)} of {len(wv)} values differ, max abs "
                        f"difference {float(np.max(err)):.3e} (first at flat index {k}: got "
                        f"{g['hex'][k]} = {gv[k]!r}, recorded {w['hex'][k]} = {wv[k]!r})")
    return problems


def replay(sim, rec):
    args = [_dec(a) for a in rec["args"]]
    kwargs = {k: _dec(v) for k, v in rec["kwargs"].items()}
    return _outputs(rec["fn"], call_recorded(sim, rec["fn"], args, kwargs), rec.get("keep_rows"))


@pytest.mark.parametrize("model, i", CASES)
def test_bit_identical(sims, mode, model, i, record_property):
    how, why = mode
    record_property("golden_comparison", how)
    print(why)
    rec = DATA["models"][model]["calls"][i]
    problems = compare(rec, replay(sims[model], rec), how)
    where = f"{rec['fn']} on the {model} model, call #{i}: {_describe(rec)}"
    what = "bit-identical to" if how == "bitwise" else f"within tolerance ({why}) of"
    assert not problems, f"{where} is not {what} the golden numbers:\n  " + \
        "\n  ".join(problems)


# ------------------------------------------------------------- the fingerprint
def test_fingerprint_recorded():
    """The JSON says where its bits hold, in every key that decides them."""
    fp = DATA["fingerprint"]
    for k in make_golden.FINGERPRINT_KEYS:
        assert fp.get(k) and fp[k] != "unknown", (k, fp)
    here = running_fingerprint()
    assert set(make_golden.FINGERPRINT_KEYS) <= set(here)


FOREIGN = {"machine": "aarch64", "compiler_version": "gcc (GCC) 99.1"}


def _foreign(monkeypatch, **over):
    fp = dict(DATA["fingerprint"], **over)
    monkeypatch.setattr(sys.modules[__name__], "running_fingerprint", lambda: fp)


def test_comparison_follows_the_fingerprint(monkeypatch):
    _foreign(monkeypatch)                       # the recorded platform: bits
    assert comparison()[0] == "bitwise"
    _foreign(monkeypatch, **FOREIGN)
    how, why = comparison()
    assert how == "tolerance"
    assert f"machine: recorded {DATA['fingerprint']['machine']!r}, here 'aarch64'" in why
    assert "aarch64" in why and "gcc (GCC) 99.1" in why and "1e-12" in why
    _foreign(monkeypatch, numpy="0.1", python="2.7")   # information only
    assert comparison()[0] == "bitwise"
    monkeypatch.setitem(DATA, "fingerprint", None)     # a JSON without one: tolerance
    assert comparison()[0] == "tolerance"


def _record(model, fn, method=None):
    return next(r for r in DATA["models"][model]["calls"] if r["fn"] == fn
                and (method is None or r["kwargs"].get("method") == method))


def _perturbed(rec, name, rel, k=0):
    """The record's outputs with value k of the part name times (1 + rel)."""
    got = copy.deepcopy(rec["out"])
    part = next(p for p in got if p["name"] == name)
    part["dtype"] = "float64"
    v = float.fromhex(part["hex"][k])
    part["hex"][k] = (v * (1 + rel) if v else rel).hex()
    for p in got:
        p.setdefault("dtype", "float64")
    return got


@pytest.mark.parametrize("fn, method, name, small, large", [
    ("rhs", None, "out", 1e-14, 1e-9),
    ("linearize", None, "A", 1e-13, 1e-7),
    ("simulate", "rk4", "X", 1e-11, 1e-6),
    ("simulate", "dopri5", "X", 1e-8, 1e-4),
])
def test_tolerance_catches_a_wrong_number(fn, method, name, small, large):
    """The fallback is not a pass: a value off by more than the tolerance fails, one
    off by less passes (where bit for bit it would fail)."""
    rec = _record("kane", fn, method)
    part = next(p for p in rec["out"] if p["name"] == name)
    k = max(range(len(part["hex"])), key=lambda j: abs(float.fromhex(part["hex"][j])))
    assert compare(rec, _perturbed(rec, name, small, k), "tolerance") == []
    assert compare(rec, _perturbed(rec, name, small, k), "bitwise")
    problems = compare(rec, _perturbed(rec, name, large, k), "tolerance")
    assert len(problems) == 1 and problems[0].startswith(f"{name}: max |difference|")
    assert compare(rec, _perturbed(rec, name, 0.0, k), "bitwise") == []


def test_tolerance_on_integers():
    rec = _record("kane", "simulate", "dopri5")
    for name, delta, ok in (("stats.n_rhs", 3, True), ("stats.n_rhs", None, False),
                            ("n_rows", 1, False)):
        got = copy.deepcopy(rec["out"])
        for p in got:
            p.setdefault("dtype", "float64")
        part = next(p for p in got if p["name"] == name)
        part["int"] += delta if delta is not None else part["int"] // 2
        assert (compare(rec, got, "tolerance") == []) == ok, (name, delta)
        assert compare(rec, got, "bitwise")


def test_foreign_platform_end_to_end(sims, monkeypatch):
    """With a foreign fingerprint the replay of real calls passes to the tolerance and
    says so; a recorded value moved beyond it is caught."""
    _foreign(monkeypatch, **FOREIGN)
    how, why = comparison()
    assert how == "tolerance"
    for fn in ("rhs", "linearize"):
        rec = _record("lagrange", fn)
        got = replay(sims["lagrange"], rec)
        assert compare(rec, got, how) == []
        wrong = dict(rec, out=_perturbed(rec, rec["out"][0]["name"], 1e-6))
        assert compare(wrong, got, how)
