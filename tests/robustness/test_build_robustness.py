"""Issue 14: builds that scale and a build cache that survives concurrency,
kills and read-only folders.

- the host build of a 20-link cart (its linearize keeps ~60 KB of work
  arrays on the stack) succeeds: the -Wstack-usage bound is the embedded
  profile's (cross builds, `eomgen report`, `--stack-limit BYTES`), not the
  host's;
- two `eomgen build` runs into one folder both end with a working binary
  (a lock on the folder; libm linked by name, no find_library);
- a temporary build directory left by a killed build is removed by the next
  build, a live one is not;
- a cache that cannot be written is one BuildError naming EOMGEN_CACHE and
  the folder (the CLI: one line, exit 1);
- `eomgen cache` / `eomgen cache clear`.

Tests run as root, which ignores permission bits: the unwritable cache is a
path under a regular file (ENOTDIR) and, for EROFS, a monkeypatched mkdtemp.
"""
import errno
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import gen
import gen.core.cache
import gen.toolchain.footprint
import gen.codegen.render
from conftest import require_tool

ROOT = Path(__file__).resolve().parents[2]
SEED = str(ROOT / "examples" / "seed_pendulum.py")


def eomgen(*args, cache=None, cwd=None):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    if cache is not None:
        env["EOMGEN_CACHE"] = str(cache)
    return subprocess.run([sys.executable, "-m", "gen", *args], capture_output=True, text=True,
                          env=env, cwd=cwd)


def _cart_file(tmp_path, n):
    f = tmp_path / f"cart{n}.py"
    f.write_text(f"import sys\nsys.path.insert(0, {str(ROOT / 'examples')!r})\n"
                 f"import n_link_cart\n\n\ndef model():\n    return n_link_cart.model({n})\n")
    return f


def _sim_matrix(text, label):
    """A matrix printed by <name>_sim --linearize: 'A (r x c)' then r rows."""
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith(f"{label} ("))
    r, c = map(int, re.match(rf"{label} \((\d+) x (\d+)\)", lines[i]).groups())
    rows = [[float(v) for v in ln.split()[1:]] for ln in lines[i + 1:i + 1 + r]]
    return np.array(rows).reshape(r, c)


def _dead_pid():
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


# ------------------------------------------------------------ stack limit
def test_stack_limit_is_the_embedded_profiles():
    """The generated CMake bounds frames when cross-compiling (8192 by
    default), not on the host; libm by name, never a cached find_library."""
    import seed_pendulum
    files = gen.codegen.render.render_files(seed_pendulum.kane_model())
    text = files["CMakeLists.txt"]
    cross = re.search(r"if\(CMAKE_CROSSCOMPILING\)\s+set\(PENDULUM_KANE_STACK_LIMIT_DEFAULT "
                      r"(\d+)\)\s+else\(\)\s+set\(PENDULUM_KANE_STACK_LIMIT_DEFAULT (\d+)\)", text)
    assert cross and cross.groups() == (str(gen.toolchain.footprint.DEFAULT_STACK_LIMIT), "0")
    assert "PENDULUM_KANE_STACK_LIMIT GREATER 0" in text
    assert "find_library(" not in text and "PUBLIC m)" in text


def test_footprint_rejects_a_negative_stack_limit(kane_model):
    with pytest.raises(gen.toolchain.footprint.FootprintError, match="stack_limit"):
        gen.toolchain.footprint.report(kane_model, target="host", stack_limit=-1)


@pytest.mark.slow
def test_cli_rejects_a_negative_stack_limit(tmp_path):
    for cmd in ("build", "report"):
        args = [cmd, SEED, "--stack-limit", "-5"] + (["-o", str(tmp_path / "o")]
                                                      if cmd == "build" else [])
        p = eomgen(*args)
        assert p.returncode == 2 and "--stack-limit" in p.stderr, p.stderr


def test_host_configure_has_no_stack_bound_and_no_notfound(tmp_path, kane_model):
    require_tool("cmake")
    gen.generate(kane_model, tmp_path / "src")
    r = subprocess.run(["cmake", "-S", tmp_path / "src", "-B", tmp_path / "b",
                        "-DPENDULUM_KANE_BUILD_SIM=OFF"], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    cache = (tmp_path / "b" / "CMakeCache.txt").read_text()
    assert "PENDULUM_KANE_STACK_LIMIT:STRING=0" in cache
    assert "M_LIBRARY" not in cache
    r = subprocess.run(["cmake", "-S", tmp_path / "src", "-B", tmp_path / "b",
                        "-DPENDULUM_KANE_STACK_LIMIT=lots"], capture_output=True, text=True)
    assert r.returncode != 0 and "must be a number of bytes" in r.stderr


@pytest.mark.slow
def test_build_stack_limit_option(tmp_path):
    """--stack-limit BYTES on `eomgen build` bounds the library's frames;
    the next build without it has no bound again (not kept in the CMake
    cache)."""
    require_tool("cmake")
    out = tmp_path / "pend"
    p = eomgen("build", SEED, "-o", str(out), "--stack-limit", "16")
    assert p.returncode == 1 and "stack usage" in p.stderr, p.stderr
    p = eomgen("build", SEED, "-o", str(out))
    assert p.returncode == 0, p.stderr
    assert Path(p.stdout.strip().splitlines()[-1]).is_file()


@pytest.mark.slow
def test_host_build_of_a_20_link_cart(tmp_path):
    """`eomgen build` of model(20) (its linearize frame is far above the
    embedded 8192 B) succeeds on the host; the binary's linearization is
    gen.compile's to 1e-10."""
    require_tool("cmake")
    import n_link_cart
    f = _cart_file(tmp_path, 20)
    t0 = time.perf_counter()
    p = eomgen("build", str(f), "-o", str(tmp_path / "cart20"))
    took = time.perf_counter() - t0
    assert p.returncode == 0, p.stderr[-3000:]
    exe = Path(p.stdout.strip().splitlines()[-1])
    print(f"eomgen build of the 20-link cart: {took:.1f} s")
    at = {"q0": 0.3, "q1": 0.1, "q2": -0.2, "q5": 0.4, "q20": -0.1, "u1": 0.5, "u3": -0.7}
    x0 = [a for k, v in at.items() for a in ("--x0", f"{k}={v}")]
    r = subprocess.run([str(exe), "--linearize", *x0, "--input", "F=1.5"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    A_bin, B_bin = _sim_matrix(r.stdout, "A"), _sim_matrix(r.stdout, "B")
    sim = gen.compile(n_link_cart.model(20))
    x = np.zeros(sim.nx)
    for k, v in at.items():
        x[sim.state_names.index(k)] = v
    A, B = sim.linearize(x, r=np.array([1.5]))
    assert A.shape == A_bin.shape == (42, 42) and B.shape == B_bin.shape == (42, 1)
    # the binary prints 12 significant digits
    scale = max(1.0, float(np.abs(A).max()))
    assert np.abs(A_bin - A).max() <= 1e-10 * scale
    assert np.abs(B_bin - B).max() <= 1e-10 * max(1.0, float(np.abs(B).max()))
    run = subprocess.run([str(exe), "--t-end", "0.05", "--dt", "0.01", "--x0", "q1=0.1"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert len(run.stdout.splitlines()) == 7


# ------------------------------------------------------------ concurrency
@pytest.mark.slow
def test_two_builds_into_one_folder(tmp_path):
    """Two `eomgen build` processes into the same folder at once: both exit
    0 with a working binary (the second waits for the first's lock)."""
    require_tool("cmake")
    out = tmp_path / "pend"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    procs = [subprocess.Popen([sys.executable, "-m", "gen", "build", SEED, "-o", str(out)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
             for _ in range(2)]
    results = [p.communicate() + (p.returncode,) for p in procs]
    for so, se, rc in results:
        assert rc == 0, se[-3000:]
        exe = Path(so.strip().splitlines()[-1])
        r = subprocess.run([str(exe), "--t-end", "0.1", "--x0", "q2=0.5", "--x0", "q1=0.8"],
                           capture_output=True, text=True)
        assert r.returncode == 0 and r.stdout.startswith("t,q2,q1,u2,u1"), r.stderr
    assert "M_LIBRARY" not in (out / "build" / "CMakeCache.txt").read_text()


# ------------------------------------------------- killed builds, the cache
def _fake_temp(root, pid, age=0.0, owner=True, name="_eomgen_fake_0123456789abcdef"):
    d = root / f".{name}.{pid}.k3j4h5g6" if pid is not None else root / f".{name}.k3j4h5g6"
    (d / "src").mkdir(parents=True)
    (d / "src" / "fake.c").write_text("int x;\n")
    if owner and pid is not None:
        import socket
        (d / "owner").write_text(f"{pid} {socket.gethostname()} 0\n")
    if age:
        t = time.time() - age
        os.utime(d, (t, t))
    return d


@pytest.mark.slow
def test_stale_temp_dirs_are_cleaned_by_the_next_build(tmp_path, monkeypatch, kane_model):
    cache = tmp_path / "cache"
    cache.mkdir()
    monkeypatch.setenv("EOMGEN_CACHE", str(cache))
    dead = _fake_temp(cache, _dead_pid())
    dead_no_owner = _fake_temp(cache, _dead_pid(), owner=False,
                               name="_eomgen_other_fedcba9876543210")
    legacy_old = _fake_temp(cache, None, age=2 * gen.core.cache.STALE_SECONDS,
                            name="_eomgen_legacy_00112233445566ff")
    legacy_new = _fake_temp(cache, None, name="_eomgen_recent_00112233445566ff")
    live = _fake_temp(cache, os.getpid(), name="_eomgen_live_0123456789abcdef")
    other = cache / ".not_ours"
    other.mkdir()
    sim = gen.compile(kane_model)
    assert sim.build_info["cached"] is False
    for d in (dead, dead_no_owner, legacy_old):
        assert not d.exists(), d
    for d in (live, legacy_new, other):
        assert d.exists(), d
    # nothing of the build itself is left behind
    left = sorted(p.name for p in cache.iterdir() if p.name.startswith("."))
    assert left == sorted([live.name, legacy_new.name, other.name])


def test_unwritable_cache_is_one_clear_error(tmp_path, monkeypatch, kane_model):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    bad = blocker / "cache"
    monkeypatch.setenv("EOMGEN_CACHE", str(bad))
    with pytest.raises(gen.BuildError) as ei:
        gen.compile(kane_model)
    msg = str(ei.value)
    assert "EOMGEN_CACHE" in msg and str(bad) in msg and "\n" not in msg
    assert not isinstance(ei.value.__cause__, OSError) or ei.value.__suppress_context__

    # a read-only file system (root ignores chmod: the error is simulated)
    ro = tmp_path / "ro"
    ro.mkdir()
    monkeypatch.setenv("EOMGEN_CACHE", str(ro))

    def read_only(*a, **k):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(ro))
    monkeypatch.setattr(gen.core.cache.tempfile, "mkdtemp", read_only)
    with pytest.raises(gen.BuildError, match="EOMGEN_CACHE") as ei:
        gen.compile(kane_model)
    assert str(ro) in str(ei.value) and os.strerror(errno.EROFS) in str(ei.value)


def test_cli_unwritable_cache_is_one_line(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    p = eomgen("linearize", SEED, "--at", "q1=1", cache=blocker / "cache")
    assert p.returncode == 1, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "EOMGEN_CACHE" in lines[0] and str(blocker) in lines[0], lines
    assert "Traceback" not in p.stderr


@pytest.mark.slow
def test_cache_subcommand(tmp_path):
    cache = tmp_path / "c"
    p = eomgen("cache", cache=cache)
    assert p.returncode == 0 and str(cache) in p.stdout and "entries: 0" in p.stdout
    mod = cache / "_eomgen_pend_0123456789abcdef"
    mod.mkdir(parents=True)
    (mod / "_eomgen_pend_0123456789abcdef.so").write_bytes(b"x" * 3000)
    rt = cache / "runtime_0123456789abcdef"
    rt.mkdir()
    (rt / "gen_rt.o").write_bytes(b"y" * 2000)
    stale = _fake_temp(cache, _dead_pid())
    live = _fake_temp(cache, os.getpid(), name="_eomgen_live_0123456789abcdef")
    keep = cache / "notes.txt"
    keep.write_text("not eomgen's")
    info = gen.core.cache.cache_info()   # the test session's cache: just the shape
    assert {"path", "entries", "bytes"} <= set(info)
    p = eomgen("cache", "info", cache=cache)
    assert p.returncode == 0, p.stderr
    assert str(cache) in p.stdout and "entries: 2 " in p.stdout and "EOMGEN_CACHE" in p.stdout
    assert re.search(r"size: 5\.\d kB", p.stdout), p.stdout
    p = eomgen("cache", "clear", cache=cache)
    assert p.returncode == 0 and "removed 3 entries" in p.stdout, p.stdout
    assert not mod.exists() and not rt.exists() and not stale.exists()
    assert keep.exists() and live.exists()   # not ours / a build in progress
    p = eomgen("cache", cache=cache)
    assert "entries: 0" in p.stdout
    p = eomgen("cache", "bogus", cache=cache)
    assert p.returncode == 2


@pytest.mark.slow
def test_compile_killed_half_way_is_cleaned(tmp_path, monkeypatch, kane_model):
    """kill -9 of a process compiling into the cache leaves its temporary
    directory; the next build (another process) removes it."""
    cache = tmp_path / "cache"
    env = dict(os.environ, EOMGEN_CACHE=str(cache),
               PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    code = ("import sys; sys.path.insert(0, %r); import gen, n_link_cart; "
            "gen.compile(n_link_cart.model(4))" % str(ROOT / "examples"))
    proc = subprocess.Popen([sys.executable, "-c", code], env=env)
    deadline = time.time() + 120
    temps = []
    while time.time() < deadline and proc.poll() is None and not temps:
        temps = [p for p in cache.glob("._eomgen_*") if (p / "src").is_dir()] \
            if cache.is_dir() else []
        time.sleep(0.05)
    proc.kill()
    proc.wait()
    if not temps:
        pytest.skip("the compile finished before it could be killed")
    assert all(t.exists() for t in temps)
    monkeypatch.setenv("EOMGEN_CACHE", str(cache))
    gen.compile(kane_model)
    assert not any(t.exists() for t in temps)
    assert not list(cache.glob(".*"))


def test_runtime_object_cache_key_covers_every_runtime_file(tmp_path, monkeypatch):
    """The cached runtime objects are keyed by every runtime source and
    header: changing any one of them (gen_rt_rodas4.h, say) gives another
    cache folder, never stale objects."""
    import shutil
    from gen.toolchain import build as b
    from gen.codegen.backends import RUNTIME_HEADERS, RUNTIME_SOURCES, c_compiler
    from gen.core.resources import csrc_file
    monkeypatch.setenv("EOMGEN_CACHE", str(tmp_path / "cache"))
    # (not the objects built at install time: the cache's own key is checked)
    monkeypatch.setattr("gen.core.cache.PREBUILT", tmp_path / "no-prebuilt")
    src = tmp_path / "src"
    src.mkdir()
    for f in RUNTIME_SOURCES + RUNTIME_HEADERS + ["gen_rt_config.h", "gen_rt_abi.h"]:
        shutil.copy(csrc_file(f), src / f)
    cc = c_compiler()
    _, base = b._runtime_objects(src, cc)
    for f in RUNTIME_SOURCES + RUNTIME_HEADERS:
        text = (src / f).read_text()
        (src / f).write_text(text + "\n/* changed */\n")
        _, folder = b._runtime_objects(src, cc)
        assert folder != base, f
        (src / f).write_text(text)
    assert b._runtime_objects(src, cc)[1] == base
