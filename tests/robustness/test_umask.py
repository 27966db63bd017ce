"""Issue 32: written files and folders follow the umask. Before the fix,
under umask 022 export_fmu wrote the .fmu as 0600 (tempfile.mkstemp's mode
kept through the atomic rename) and generate created its folder as 0700
(mkdtemp's)."""
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

import gen
from gen.codegen.render import current_umask, write_atomic

ROOT = Path(__file__).resolve().parents[2]
SEED = str(ROOT / "examples" / "seed_pendulum.py")

pytestmark = pytest.mark.skipif(os.name != "posix", reason="POSIX modes")


def mode(p):
    return stat.S_IMODE(os.stat(p).st_mode)


@pytest.fixture(params=[0o022, 0o027, 0o077, 0o002])
def umask(request):
    old = os.umask(request.param)
    try:
        yield request.param
    finally:
        os.umask(old)


def test_current_umask_reads_without_changing(umask):
    assert current_umask() == umask
    assert current_umask() == umask


def test_generate_folder_and_files_follow_the_umask(tmp_path, umask, kane_model):
    out = tmp_path / "a" / "pend"
    paths = gen.generate(kane_model, out)
    assert mode(out) == 0o777 & ~umask
    assert mode(out.parent) == 0o777 & ~umask
    files = [Path(p) for p in (paths if isinstance(paths, (list, tuple)) else out.iterdir())]
    assert files and all(f.is_file() for f in files)
    for f in files:
        assert mode(f) == 0o666 & ~umask, f


def test_regenerating_keeps_the_folder_mode(tmp_path, umask):
    out = tmp_path / "proj"
    out.mkdir()
    os.chmod(out, 0o751)
    (out / "notes.txt").write_text("kept")
    os.chmod(out / "notes.txt", 0o600)
    write_atomic({"a.c": "int a;\n"}, out)
    assert mode(out) == 0o751
    assert mode(out / "notes.txt") == 0o600 and (out / "notes.txt").read_text() == "kept"
    assert mode(out / "a.c") == 0o666 & ~umask


def test_fmu_follows_the_umask(tmp_path, umask, kane_model):
    path = gen.export_fmu(kane_model, tmp_path / "pend.fmu", binary=False)
    assert mode(path) == 0o666 & ~umask


@pytest.mark.slow
def test_cli_generate_under_umask_022(tmp_path):
    """(Slow tier: `eomgen generate` calls gen.generate, whose modes under umask
    0o022 test_generate_folder_and_files_follow_the_umask checks in process.)"""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    out = tmp_path / "cli"
    p = subprocess.run([sys.executable, "-m", "gen", "generate", SEED, "-o", str(out)],
                       capture_output=True, text=True, env=env, umask=0o022)
    assert p.returncode == 0, p.stderr
    assert mode(out) == 0o755
    assert {mode(f) for f in out.iterdir() if f.is_file()} == {0o644}
