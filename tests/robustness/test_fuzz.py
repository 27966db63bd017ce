"""Issue 8: the generated C API under AddressSanitizer and
UndefinedBehaviorSanitizer with hostile inputs (a seeded sweep of extreme
values and NULL pointers), and a coverage-guided libFuzzer run for a
bounded time. Rules checked by tests/fuzz/harness.c: known statuses only,
status 0 means finite outputs, a failed call leaves x unchanged, NULL is
refused. tests/fuzz/regressions holds inputs that once broke a rule (the
rolling disc's multipliers overflowing while its accelerations stayed
finite); they seed the corpus of every run."""
import re
import subprocess
from pathlib import Path

import pytest

import four_bar
import gen
from gen.codegen.render import model_sources
import rolling_disc
import seed_pendulum as sp
from helpers import load_test_file
from conftest import require_eigen, require_tool

pytestmark = pytest.mark.fuzz

HARNESS = Path(__file__).resolve().parents[1] / "fuzz" / "harness.c"


def _box_friction():
    """sympy's box on the ground with friction -mu N: an auxiliary speed
    whose reaction is in the motion (eval_auxiliary_forces, NA = 1)."""
    box_on_ground = load_test_file("physics/test_auxiliary.py").box_on_ground
    system, consts, F, _ = box_on_ground(friction=True)
    return gen.Model.from_kanes(system, constants=consts, inputs=[F], name="box_fric")


def _bead_coupled():
    """A bead on a curved track whose normal force N enters the motion with
    a coefficient in theta and omega: u' and N from one linear system per
    call (gen_rt_accel_reactions; singular where the track is vertical)."""
    bead_kane = load_test_file("physics/test_reactions_coupled.py").bead_kane
    km, consts, F, _ = bead_kane("vertical")
    return gen.Model.from_kanes(km, constants=consts, inputs=[F], name="bead_cpl")


MODELS = {"kane": sp.kane_model, "lagrange": sp.lagrange_model,
          "rolling_disc": rolling_disc.model, "four_bar": four_bar.model,
          "box_friction": _box_friction, "bead_coupled": _bead_coupled}


def _build(model, out, cc, flags, extra=()):
    gen.generate(model, out)
    p = model.name
    srcs = [str(HARNESS)] + [str(out / f) for f in model_sources(p)] + sorted(
        str(f) for f in out.glob("gen_rt_*.c"))
    exe = out / "harness"
    cmd = [cc, "-std=c99", "-g", "-O1", "-I", str(out), f'-DMODEL_H="{p}.h"',
           f"-DP(x)={p}_##x", f"-DPU(x)={p.upper()}_##x", *flags, *extra, *srcs,
           "-o", str(exe), "-lm"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return exe


SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer"]


# every model with the slow tests (a sanitizer build of each)
@pytest.mark.slow
@pytest.mark.parametrize("key", sorted(MODELS))
def test_hostile_inputs_under_sanitizers(tmp_path, key):
    exe = _build(MODELS[key](), tmp_path, "gcc", SAN)
    r = subprocess.run([str(exe), "3000"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr[-3000:]
    assert "3000 cases, all rules held" in r.stdout
    assert "runtime error" not in r.stderr


@pytest.mark.slow
@pytest.mark.eigen
@pytest.mark.parametrize("key", ["rolling_disc", "box_friction", "bead_coupled"])
def test_eigen_backend_under_sanitizers(tmp_path, key):
    """The C++/Eigen backend's library (the C model and runtime for both
    scalar types, the second copy's names prefixed, and the face
    instantiated) obeys the same rules through its C API."""
    from gen.codegen.backends.eigen import ALT_DEFINE, sources
    from gen.codegen.render import C_TEMPLATES, RUNTIME_SOURCES
    inc = require_eigen()
    model = MODELS[key]()
    out = tmp_path
    gen.generate(model, out, backend="eigen")
    p = model.name
    main, alt, cxx = sources(p, "double", True, C_TEMPLATES)
    units = [(HARNESS, "gcc", "-std=c99", "harness")]
    units += [(out / f, "gcc", "-std=c99", Path(f).stem) for f in main + RUNTIME_SOURCES]
    units += [(out / f, "gcc", f"-D{ALT_DEFINE}", "alt_" + Path(f).stem)
              for f in alt + RUNTIME_SOURCES]
    units += [(out / f, "g++", "-std=c++17", Path(f).stem + "_cxx") for f in cxx]
    objs = []
    for src, cc, std, stem in units:
        obj = out / (stem + ".o")
        cmd = [cc, std, "-g", "-O0", "-I", str(out), "-isystem", str(inc),
               f'-DMODEL_H="{p}.h"', f"-DP(x)={p}_##x", f"-DPU(x)={p.upper()}_##x", *SAN,
               "-c", str(src), "-o", str(obj)]
        r = subprocess.run(cmd, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        objs.append(str(obj))
    exe = out / "harness"
    r = subprocess.run(["g++", *SAN, *objs, "-o", str(exe), "-lm"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    r = subprocess.run([str(exe), "1500"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr[-3000:]
    assert "1500 cases, all rules held" in r.stdout


@pytest.mark.slow
@pytest.mark.parametrize("key", ["kane", "rolling_disc"])
def test_libfuzzer_bounded_run(tmp_path, key):
    clang = require_tool("clang")
    exe = _build(MODELS[key](), tmp_path, clang, ["-fsanitize=fuzzer,address,undefined",
                                                  "-fno-sanitize-recover=all"], ["-DFUZZ"])
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    # inputs that once failed start the corpus (regressions)
    for seed in (HARNESS.parent / "regressions").glob(f"{key}-*.bin"):
        (corpus / seed.name).write_bytes(seed.read_bytes())
    # the seed pendulum: a million inputs (the acceptance bar); the rolling disc
    # (velocity constraints, an input): ten thousand (a count, not a time: the
    # machine's speed decides how many inputs fit into a time)
    budget = ["-runs=1000000", "-max_total_time=600"] if key == "kane" else \
        ["-runs=10000", "-max_total_time=300"]
    r = subprocess.run([str(exe), str(corpus), *budget, "-seed=7", "-max_len=256",
                        f"-artifact_prefix={tmp_path}/",        # crash files stay out of cwd
                        "-print_final_stats=1", "-rss_limit_mb=2048"],
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-4000:]
    runs = int(re.search(r"stat::number_of_executed_units:\s+(\d+)", r.stderr).group(1))
    cov = re.findall(r"cov: (\d+)", r.stderr)
    print(f"\nlibFuzzer {key}: {runs} inputs, coverage {cov[-1] if cov else '?'} edges, "
          f"corpus {len(list(corpus.iterdir()))} files")
    assert runs >= (1000000 if key == "kane" else 10000)
