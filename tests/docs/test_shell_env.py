"""Issue 32: `source scripts/env.sh` (the README's fast-tier command) changes no
shell option of the shell that sources it. Before the fix it left `set -euo
pipefail` on, so the next failing command closed an interactive terminal.

The venv is a stand-in (a `python` that succeeds, an install stamp newer than
pyproject.toml), so env.sh takes its no-install path: no network, no pip."""
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")


@pytest.fixture
def fake_venv(tmp_path):
    venv = tmp_path / "venv"
    (venv / "bin").mkdir(parents=True)
    py = venv / "bin" / "python"
    py.write_text("#!/bin/sh\nexit 0\n")
    py.chmod(0o755)
    stamp = venv / ".eomgen-installed"
    stamp.touch()
    t = (ROOT / "pyproject.toml").stat().st_mtime + 10
    os.utime(stamp, (t, t))
    return venv


def _bash(script, venv):
    env = dict(os.environ, EOMGEN_VENV=str(venv))
    return subprocess.run(["bash", "-c", script], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=60)


@pytest.mark.parametrize("opts", ["set +euo pipefail", "set -euo pipefail", "set -u"])
def test_sourcing_changes_no_shell_option(fake_venv, opts):
    script = (f"{opts}; before=\"$- $(shopt -po pipefail)\"; "
              "source scripts/env.sh; rc=$?; "
              "after=\"$- $(shopt -po pipefail)\"; "
              "echo \"rc=$rc\"; echo \"before=$before\"; echo \"after=$after\"; "
              "echo \"path=$PATH\"; if type _eomgen_env >/dev/null 2>&1; then echo leaked; fi")
    p = _bash(script, fake_venv)
    assert p.returncode == 0, p.stderr
    lines = dict(ln.split("=", 1) for ln in p.stdout.splitlines() if "=" in ln)
    assert lines["rc"] == "0"
    assert lines["before"] == lines["after"]
    assert lines["path"].split(":")[0] == str(fake_venv / "bin")
    assert "leaked" not in p.stdout


def test_a_failing_command_after_sourcing_keeps_the_shell_alive(fake_venv):
    p = _bash("set +e; source scripts/env.sh; false; echo alive; "
              "grep -q no-such-text scripts/env.sh; echo still alive; "
              "echo \"${NO_SUCH_VARIABLE_EOMGEN}\" >/dev/null; echo unset ok; echo \"$-\"",
              fake_venv)
    assert p.returncode == 0, p.stderr
    out = p.stdout.splitlines()
    assert out[:3] == ["alive", "still alive", "unset ok"]
    assert "e" not in out[3] and "u" not in out[3]


def test_a_failed_setup_returns_1_and_still_changes_no_option(tmp_path):
    # a venv whose python cannot run: env.sh tries to (re)create it and fails;
    # python3 -m venv on a path under a regular file cannot succeed
    blocker = tmp_path / "file"
    blocker.write_text("")
    p = _bash("set +e; source scripts/env.sh; echo \"rc=$?\"; echo \"$-\"; "
              "shopt -po pipefail; echo done", blocker / "venv")
    assert p.returncode == 0, p.stderr
    out = p.stdout.splitlines()
    assert out[0] == "rc=1"
    assert "e" not in out[1] and "u" not in out[1]
    assert out[2:] == ["set +o pipefail", "done"]
    assert "env.sh:" in p.stderr
