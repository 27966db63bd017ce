"""Issue 32: the command line prints one line, never a traceback, for every
eomgen error (a huge run's refusal and a MemoryError included), exits
non-zero, and is quiet on a closed pipe (``eomgen ... | head`` ended with
"[Errno 32] Broken pipe" and exit 1)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

import gen
import gen.cli
from gen.sim.simulator import Simulator

ROOT = Path(__file__).resolve().parents[2]
SEED = str(ROOT / "examples" / "seed_pendulum.py")
X0 = ["--x0", "q2=0.5", "--x0", "q1=0.8"]


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def eomgen(*args):
    return subprocess.run([sys.executable, "-m", "gen", *args], capture_output=True, text=True,
                          env=_env(), timeout=300)


def test_a_run_past_the_size_limit_is_one_line():
    # 1e10 output rows: past the C runtime's limit, refused before any allocation
    p = eomgen("simulate", SEED, "--t-end", "1e6", "--dt", "1e-4", *X0)
    assert p.returncode == 1, (p.stdout, p.stderr)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("eomgen simulate: "), p.stderr
    assert "Traceback" not in p.stderr
    assert p.stdout == ""


def test_memory_error_is_one_line(monkeypatch, capsys):
    def huge(self, *a, **k):
        raise MemoryError("Unable to allocate 59.6 GiB for an array with shape (1000000001, 8)")
    monkeypatch.setattr(Simulator, "simulate", huge)
    rc = gen.cli.main(["simulate", SEED, "--t-end", "1e5", "--dt", "1e-4"] + X0)
    err = capsys.readouterr().err
    assert rc == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("eomgen simulate: out of memory (Unable to allocate 59.6 GiB")
    assert "--dt" in lines[0]


@pytest.mark.parametrize("exc", [gen.SolverError("ERR_SINGULAR at t = 1"),
                                 gen.ModelError("unknown symbol k"),
                                 ValueError("x0 must have shape (4,), got (3,)")])
def test_every_gen_error_is_one_line_exit_1(monkeypatch, capsys, exc):
    def fail(self, *a, **k):
        raise exc
    monkeypatch.setattr(Simulator, "simulate", fail)
    rc = gen.cli.main(["simulate", SEED, "--t-end", "1"] + X0)
    err = capsys.readouterr().err
    assert rc == 1
    assert err == f"eomgen simulate: {exc}\n"


def test_debug_still_shows_the_traceback(monkeypatch):
    def fail(self, *a, **k):
        raise MemoryError("big")
    monkeypatch.setattr(Simulator, "simulate", fail)
    with pytest.raises(MemoryError):
        gen.cli.main(["--debug", "simulate", SEED, "--t-end", "1"] + X0)


def test_a_closed_pipe_is_quiet():
    """`eomgen linearize ... | head -0`: the reader is gone before eomgen
    writes; no message, no 'Exception ignored', exit 141 (128 + SIGPIPE)."""
    proc = subprocess.Popen([sys.executable, "-m", "gen", "linearize", SEED, "--at", "q1=1", "--at", "q2=0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env())
    proc.stdout.close()            # the reader exits at once
    err = proc.stderr.read().decode()
    rc = proc.wait(timeout=300)
    assert err == "", err
    assert rc in (0, 141)


@pytest.mark.slow
def test_head_in_a_shell_pipeline_is_quiet(tmp_path):
    """The user's own words: `eomgen ... | head -n 2` shows two lines, no error.
    (Slow tier: the fast tier's test_a_closed_pipe_is_quiet takes the same
    broken-pipe path, one Python start-up and sympy import less.)"""
    cmd = (f"{sys.executable} -m gen linearize {SEED} --at q1=1 --at q2=0 2>{tmp_path / 'err'} "
           f"| head -n 2; echo \"status=${{PIPESTATUS[0]}}\"")
    p = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, env=_env(),
                       timeout=300)
    out = p.stdout.splitlines()
    assert len(out) == 3 and out[0].startswith("operating point:"), p.stdout
    assert out[2] in ("status=0", "status=141")
    assert (tmp_path / "err").read_text() == ""
