"""The simulation engine from the command lines: --method rodas4 and
--event / --events-csv in the standalone binary (main.c) and in `eomgen
simulate`, against sim.simulate from Python (the same C runs) and against
the exact period of the pendulum."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gen
from conftest import build_binary
from helpers import pendulum_state, rel_err

ROOT = Path(__file__).resolve().parents[2]
SEED = str(ROOT / "examples" / "seed_pendulum.py")

L, G = 1.0, 9.81                     # the seed model's defaults
TH0 = np.radians(60.0)               # released from rest at 60 degrees
TOL = ["--rtol", "1e-12", "--atol", "1e-12"]


def quarter_period():
    """T/4 = sqrt(L/g) K(sin^2(theta0/2)): from rest at theta0 to the bottom."""
    from scipy.special import ellipk
    return np.sqrt(L / G) * ellipk(np.sin(TH0 / 2) ** 2)


@pytest.fixture(scope="module")
def binary(kane_binary):
    """The seed Kane pendulum's standalone simulator (conftest.py: one
    strict-flag CMake build per session)."""
    return kane_binary


@pytest.fixture(scope="module")
def x0():
    return pendulum_state(TH0, 0.0, L, "kane")


def run(exe, *args, rc=0):
    proc = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True)
    assert proc.returncode == rc, (args, proc.returncode, proc.stderr)
    return proc


def x0_args(x0):
    """The exact state (repr round-trips), not re-solved by the binary."""
    return ["--x0", ",".join(repr(float(v)) for v in x0), "--no-consistent"]


def rows(path, nx=4):
    """(t, X) of a trajectory CSV of the binary or of `eomgen simulate`."""
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return data[:, 0], data[:, 1:1 + nx]


def events_csv(path):
    """[(name, t, x)] of an events CSV; checks the header."""
    lines = Path(path).read_text().splitlines()
    assert lines[0] == "event,t,q2,q1,u2,u1"
    out = []
    for ln in lines[1:]:
        name, *vals = ln.split(",")
        out.append((name, float(vals[0]), np.array([float(v) for v in vals[1:]])))
    return out


def events_stderr(text):
    """[(name, t, x)] of the lines 'event NAME t=T q2=... ...' on stderr."""
    out = []
    for ln in text.splitlines():
        if not ln.startswith("event "):
            continue
        _, name, *fields = ln.split()
        kv = dict(f.split("=", 1) for f in fields)
        out.append((name, float(kv["t"]), np.array([float(kv[n]) for n in
                                                    ("q2", "q1", "u2", "u1")])))
    return out


def same_events(a, b, tol=1e-12):
    assert [e[0] for e in a] == [e[0] for e in b]
    ta, tb = np.array([e[1] for e in a]), np.array([e[1] for e in b])
    assert np.max(np.abs(ta - tb)) <= tol * max(1.0, np.max(np.abs(tb))), (ta, tb)
    assert rel_err(np.array([e[2] for e in a]), np.array([e[2] for e in b])) <= tol


def bitwise(*pairs):
    return all(np.array_equal(np.asarray(a), np.asarray(b)) for a, b in pairs)


# ------------------------------------------------------------- the binary
@pytest.mark.slow
def test_binary_events_match_python_and_the_exact_period(binary, kane_sim, x0, tmp_path):
    T4 = quarter_period()
    out, ev = tmp_path / "run.csv", tmp_path / "ev.csv"
    args = ["--t-end", 3, "--dt", 0.01, "--method", "dopri5", *TOL, *x0_args(x0),
            "--event", "q2:0"]
    run(binary, *args, "--output", out, "--events-csv", ev)
    t_b, X_b = rows(out)
    ev_b = events_csv(ev)
    sol = kane_sim.simulate(x0, 3.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12,
                            events={"q2": 0})
    t, X, found = sol.t, sol.x, sol.events
    assert len(t_b) == len(t) == 301
    assert rel_err(t_b, t) <= 1e-12 and rel_err(X_b, X) <= 1e-12
    same_events(ev_b, found)
    print("binary and Python bitwise equal:",
          bitwise((t_b, t), (X_b, X), *[(a[1], b[1]) for a, b in zip(ev_b, found)],
                  *[(a[2], b[2]) for a, b in zip(ev_b, found)]))
    # q2 = L sin(theta) through zero at T/4, 3T/4, 5T/4 (both directions)
    times = np.array([e[1] for e in ev_b])
    assert len(times) == 3 and [e[0] for e in ev_b] == ["q2"] * 3
    assert abs(times[0] - T4) / T4 < 1e-9, (times[0], T4)
    assert np.allclose(times, T4 * np.array([1, 3, 5]), rtol=1e-8, atol=0)
    for (_, _, x), sign in zip(ev_b, (-1, 1, -1)):   # at the bottom, swinging
        assert abs(x[0]) < 1e-12 and abs(x[1] - L) < 1e-12 and np.sign(x[2]) == sign
    # without --events-csv: the same events, one line each on stderr
    proc = run(binary, *args, "--output", tmp_path / "run2.csv")
    ev_s = events_stderr(proc.stderr)
    same_events(ev_s, ev_b, tol=0)
    assert proc.stderr.splitlines()[0].startswith("event q2 t=")


def test_binary_terminal_event_ends_the_rows(binary, kane_sim, x0, tmp_path):
    T4 = quarter_period()
    out, ev = tmp_path / "run.csv", tmp_path / "ev.csv"
    run(binary, "--t-end", 3, "--dt", 0.01, "--method", "dopri5", *TOL, *x0_args(x0),
        "--event", "q2:-1:terminal", "--event", "u2:up", "--output", out, "--events-csv", ev)
    t_b, X_b = rows(out)
    ev_b = events_csv(ev)
    sol = kane_sim.simulate(
                            x0, 3.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12,
                            events={"q2": -1, "u2": 1}, terminal={"q2": True})
    t, X, found, info = sol.t, sol.x, sol.events, sol.stats
    assert info["terminal"] == "q2"
    assert len(t_b) == len(t) == int(np.floor(T4 / 0.01)) + 2   # the grid, then the event
    assert rel_err(t_b, t) <= 1e-12 and rel_err(X_b, X) <= 1e-12
    same_events(ev_b, found)
    # u2 = L cos(theta) theta' starts at zero (not a crossing) and falls: it
    # rises through zero only at T/2, after the run ended
    assert [e[0] for e in ev_b] == ["q2"]
    assert abs(t_b[-1] - T4) / T4 < 1e-9 and t_b[-1] == ev_b[0][1]
    assert np.array_equal(X_b[-1], ev_b[0][2])


def test_binary_event_level_and_direction_words(binary, kane_sim, x0, tmp_path):
    """NAME=LEVEL:DIR: u2 = L cos(theta) theta' falls through -1, then q2 =
    L sin(theta) through 0.5 (at 30 degrees), which ends the run."""
    ev, out = tmp_path / "ev.csv", tmp_path / "r.csv"
    run(binary, "--t-end", 1, "--dt", 0.05, "--method", "dopri5", *TOL, *x0_args(x0),
        "--event", "q2=0.5:down:terminal", "--event", "u2=-1e0:-1", "--output", out,
        "--events-csv", ev)
    sol = kane_sim.simulate(x0, 1.0, 0.05, method="dopri5", rtol=1e-12, atol=1e-12,
                            events={"q2": (-1, 0.5), "u2": (-1, -1.0)},
                            terminal={"q2": True})
    t, X, found = sol.t, sol.x, sol.events
    ev_b = events_csv(ev)
    same_events(ev_b, found)
    assert rel_err(rows(out)[1], X) <= 1e-12
    assert [e[0] for e in ev_b] == ["u2", "q2"]
    assert abs(ev_b[0][2][2] + 1) < 1e-10 and abs(ev_b[1][2][0] - 0.5) < 1e-10
    # 30 degrees from 60, from rest: t = sqrt(L/g) (K(k) - F(asin(sin(15)/k), k)),
    # k = sin(30 degrees), the incomplete integral from 30 degrees to the bottom
    from scipy.special import ellipkinc
    k2 = np.sin(TH0 / 2) ** 2
    t30 = quarter_period() - np.sqrt(L / G) * ellipkinc(
        np.arcsin(np.sin(np.radians(15)) / np.sqrt(k2)), k2)
    assert abs(ev_b[1][1] - t30) / t30 < 1e-9, (ev_b[1][1], t30)
    # the direction words: up = +1 = 1, down = -1, both = 0
    for words in (("up", "+1", "1"), ("down", "-1"), ("both", "0")):
        texts = {run(binary, "--t-end", 1, "--dt", 0.05, "--method", "dopri5", *x0_args(x0),
                     "--event", f"q2:{w}").stderr for w in words}
        assert len(texts) == 1


def test_binary_rodas4_matches_python(binary, kane_sim, x0, tmp_path):
    out, out2 = tmp_path / "r.csv", tmp_path / "r2.csv"
    args = ["--t-end", 2, "--dt", 0.02, "--rtol", "1e-9", "--atol", "1e-11", *x0_args(x0)]
    run(binary, *args, "--method", "rodas4", "--output", out)
    run(binary, *args, "--method", "rodas", "--output", out2)
    assert out.read_text() == out2.read_text()          # the alias
    t_b, X_b = rows(out)
    t, X = kane_sim.simulate(x0, 2.0, 0.02, method="rodas4", rtol=1e-9, atol=1e-11)
    assert len(t_b) == 101
    assert rel_err(t_b, t) <= 1e-12 and rel_err(X_b, X) <= 1e-12
    print("rodas4: binary and Python bitwise equal:", bitwise((t_b, t), (X_b, X)))
    # and it is a different integrator than DOPRI5, agreeing to its tolerance
    _, X_d = kane_sim.simulate(x0, 2.0, 0.02, method="dopri5", rtol=1e-12, atol=1e-12)
    assert 0 < np.max(np.abs(X - X_d)) < 1e-6
    # with a terminal event too
    ev = tmp_path / "ev.csv"
    run(binary, *args, "--method", "rodas4", "--event", "q2:0:terminal", "--output", out,
        "--events-csv", ev)
    t_b, X_b = rows(out)
    sol = kane_sim.simulate(x0, 2.0, 0.02, method="rodas4", rtol=1e-9, atol=1e-11,
                            events={"q2": 0}, terminal=True)
    t, X, found = sol.t, sol.x, sol.events
    assert len(t_b) == len(t) < 101
    assert rel_err(X_b, X) <= 1e-12
    same_events(events_csv(ev), found)
    T4 = quarter_period()
    assert abs(found[0][1] - T4) / T4 < 1e-6


@pytest.mark.parametrize("event,needle", [
    ("theta:0", "states: q2 q1 u2 u1"),
    ("q2:sideways", "the direction must be"),
    ("q2:0:forever", "':terminal'"),
    ("q2", "NAME[=LEVEL]:DIR"),
    ("q2=high:1", "level is not a finite number"),
])
def test_binary_bad_events_exit_2(binary, event, needle):
    proc = run(binary, "--t-end", 1, "--event", event, rc=2)
    assert needle in proc.stderr, proc.stderr
    assert proc.stdout == ""


def test_binary_bad_event_options_exit_2(binary):
    proc = run(binary, "--t-end", 1, "--event", "theta:0", rc=2)
    assert "unknown state or output 'theta'" in proc.stderr
    assert "(the model has no outputs)" in proc.stderr
    assert "--events-csv needs" in run(binary, "--events-csv", "e.csv", rc=2).stderr
    assert "has an event already" in run(binary, "--event", "q2:1", "--event", "q2=1:-1",
                                         rc=2).stderr
    assert "rk4, dopri5 or rodas4" in run(binary, "--method", "rodas5", rc=2).stderr
    help_ = run(binary, "--help").stdout
    assert "--event NAME[=LEVEL]:DIR[:terminal]" in help_ and "rodas4" in help_
    assert "--events-csv FILE" in help_


# -------------------------------------------------------- eomgen simulate
def eomgen(*args, rc=0):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run([sys.executable, "-m", "gen", *map(str, args)], capture_output=True,
                          text=True, env=env)
    assert proc.returncode == rc, (args, proc.returncode, proc.stdout, proc.stderr)
    return proc


@pytest.mark.slow
def test_eomgen_simulate_events_match_the_binary(binary, kane_sim, x0, tmp_path):
    """The same run from `eomgen simulate` (through sim.simulate) and from the
    binary: the same rows, the same events, the same formats."""
    T4 = quarter_period()
    xs = ["--x0", f"q2={float(x0[0])!r}", "--x0", f"q1={float(x0[1])!r}"]   # both re-solve q1
    args = ["--t-end", 2.5, "--dt", 0.01, "--method", "dopri5", *TOL, *xs]
    csv, ev = tmp_path / "cli.csv", tmp_path / "cli_ev.csv"
    p = eomgen("simulate", SEED, *args, "--event", "q2:0", "--event", "u2:-1:terminal",
               "--csv", csv, "--events-csv", ev)
    assert f"wrote 3 events to {ev}" in p.stdout
    t_c, X_c = rows(csv)
    ev_c = events_csv(ev)
    run(binary, *args, "--event", "q2:0", "--event", "u2:-1:terminal",
        "--output", tmp_path / "b.csv", "--events-csv", tmp_path / "b_ev.csv")
    t_b, X_b = rows(tmp_path / "b.csv")
    ev_b = events_csv(tmp_path / "b_ev.csv")
    assert len(t_c) == len(t_b) and rel_err(t_c, t_b) <= 1e-12 and rel_err(X_c, X_b) <= 1e-12
    same_events(ev_c, ev_b)
    assert ev.read_text() == (tmp_path / "b_ev.csv").read_text() or rel_err(
        np.array([e[2] for e in ev_c]), np.array([e[2] for e in ev_b])) <= 1e-12
    # q2 down at T/4, up at 3T/4; u2 = L cos(theta) theta' starts at zero (not
    # a crossing), rises through zero at T/2 and falls through it at T: the end
    assert [e[0] for e in ev_c] == ["q2", "q2", "u2"]
    assert abs(ev_c[-1][1] - 4 * T4) / T4 < 1e-8 and t_c[-1] == ev_c[-1][1]
    # and from Python directly
    x = kane_sim.consistent_state(x0)
    sol = kane_sim.simulate(x, 2.5, 0.01, method="dopri5", rtol=1e-12, atol=1e-12,
                            events={"q2": 0, "u2": -1}, terminal={"u2": True})
    t, X, found = sol.t, sol.x, sol.events
    same_events(ev_c, found)
    assert rel_err(X_c, X) <= 1e-12
    # no --events-csv: the binary's lines on stderr; rodas4 (alias rodas) by name
    p = eomgen("simulate", SEED, "--t-end", 1, "--dt", 0.01, "--method", "rodas", *xs,
               "--event", "q2:down", "--csv", csv)
    ev_s = events_stderr(p.stderr)
    sol = kane_sim.simulate(x, 1.0, 0.01, method="rodas4", events={"q2": -1})
    t, X, found = sol.t, sol.x, sol.events
    same_events(ev_s, found)
    assert len(ev_s) == 1 and abs(ev_s[0][1] - T4) / T4 < 1e-6
    assert rel_err(rows(csv)[1], X) <= 1e-12


def test_eomgen_simulate_bad_event_exit_2():
    p = eomgen("simulate", SEED, "--t-end", 1, "--x0", "q2=0.5", "--x0", "q1=0.8",
               "--event", "theta:0", rc=2)
    assert "unknown state or output 'theta'" in p.stderr
    assert "states: q2, q1, u2, u1" in p.stderr and len(p.stderr.splitlines()) == 1


# ------------------------------------------------------ an output event
@pytest.mark.slow
def test_binary_event_on_an_output(tmp_path):
    """The cart-pole's tip height (an output) falling through a level: the
    binary resolves output names, as sim.simulate does."""
    import cart_pole
    m = cart_pole.model()
    exe = build_binary(m, tmp_path)
    sim = gen.compile(m)
    x0 = np.zeros(sim.nx)
    x0[sim.state_names.index("theta")] = 0.3
    ev = tmp_path / "ev.csv"
    proc = run(exe, "--t-end", 3, "--dt", 0.01, "--method", "dopri5", *TOL,
               "--x0", "theta=0.3", "--input", "F=0", "--event", "tip_y=0.5:down:terminal",
               "--events-csv", ev, "--output", tmp_path / "r.csv")
    assert proc.stderr == ""
    lines = ev.read_text().splitlines()
    assert lines[0] == "event,t," + ",".join(sim.state_names)
    name, *vals = lines[1].split(",")
    sol = sim.simulate(x0, 3.0, 0.01, method="dopri5", rtol=1e-12, atol=1e-12,
                       r=[0.0], events={"tip_y": (-1, 0.5)}, terminal=True)
    t, X, found = sol.t, sol.x, sol.events
    assert name == "tip_y" and len(lines) == 2 and len(found) == 1
    assert abs(float(vals[0]) - found[0][1]) <= 1e-12
    th = float(vals[1 + sim.state_names.index("theta")])
    assert abs(2 * cart_pole.DEFAULTS["l"] * np.cos(th) - 0.5) < 1e-9   # tip_y = 2 l cos
    assert "tip_y" in run(exe, "--help").stdout
    bad = run(exe, "--event", "tip_z:0", rc=2).stderr
    assert "outputs: tip_x tip_y" in bad
