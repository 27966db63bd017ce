"""The one description of the C interface (gen/codegen/abi.py) against what is
built from it and what it is read from:

- the status table is the runtime's (csrc/gen_rt_status.h), and the compiled
  C runtime, the compiled Eigen backend and the bindings agree with it code
  for code (identical messages on both backends);
- a struct field added to the description appears in the C header, the cffi
  cdef and the C++ header with no other edit (the documented check);
- the header, the cdef and the footprint's function list are the same list.
"""
import dataclasses
import os
import re
import shutil
import subprocess

import pytest

import gen
from gen.codegen import abi
from gen.toolchain import host
from gen.sim import simulator as bindings
from gen.codegen import render
from gen.plan.ir import plan
from gen.core.resources import csrc_dir, csrc_file

from conftest import require_eigen

CODES = [s.value for s in abi.STATUSES] + [1, -10, -1000]


def test_table_is_the_runtimes():
    text = csrc_file("gen_rt_status.h").read_text()
    assert len(abi.STATUSES) == text.count("    X(")
    values = [s.value for s in abi.STATUSES]
    assert values == list(range(0, -len(values), -1))       # 0, -1, -2, ... no gaps
    assert abi.STATUSES[0].name == "OK"
    header = csrc_file("gen_rt.h").read_text()
    assert f"#define GEN_RT_STATUS_MIN ({min(values)})" in header


def test_every_failure_status_has_an_exception():
    names = {s.name for s in abi.STATUSES if s.value}
    assert set(bindings.EXCEPTIONS) == names


def _messages(sim):
    f = sim._fn("status_message")
    return {k: sim._ffi.string(f(k)).decode() for k in CODES}


def test_c_runtime_messages_are_the_table(kane_sim):
    got = _messages(kane_sim)
    for k in CODES:
        assert got[k] == abi.status_message(k), k
    assert got[-1000] == abi.STATUS_UNKNOWN


@pytest.mark.slow
@pytest.mark.eigen
def test_eigen_messages_equal_c(kane_model, kane_sim):
    require_eigen()
    sim_e = gen.compile(kane_model, backend="eigen")
    assert _messages(sim_e) == _messages(kane_sim)


def test_generated_status_macros_are_the_table(kane_model):
    files = render.render_files(kane_model)
    h = files[f"{kane_model.name}.h"]
    for s in abi.STATUSES:
        assert f"#define PENDULUM_KANE_{s.name} ({s.value})" in h


# fields added to the description only, one per kind of struct use: an
# option read by the runtime (with a default), a statistic written back, an
# input field passed through
PROBES = {"sim_options": abi.Field("probe_gain", "real", "a field added in one place", 0.5),
          "sim_stats": abi.Field("probe_count", "long", "a statistic added in one place", 0),
          "input": abi.Field("probe_flag", "int", "an input field added in one place", 0)}


def _add_field(s, f):
    """s with f added last, or just before a counted field (which stays last)."""
    n = len(s.fields) - (1 if s.fields and s.fields[-1].count else 0)
    return dataclasses.replace(s, fields=s.fields[:n] + (f,) + s.fields[n:])


def _probed_structs():
    return tuple(_add_field(s, PROBES[s.name]) if s.name in PROBES else s for s in abi.STRUCTS)


def test_a_counted_field_stays_last(monkeypatch, kane_model):
    """A field after a counted one (sim_stats.x_last) would lie at another
    offset in the runtime (a pointer) and the host (a flexible array): the
    description refuses it, naming the field."""
    structs = tuple(dataclasses.replace(s, fields=s.fields + (PROBES["sim_stats"],))
                    if s.name == "sim_stats" else s for s in abi.STRUCTS)
    monkeypatch.setattr(abi, "STRUCTS", structs)
    with pytest.raises(ValueError, match=r"sim_stats\.x_last is an array of NX but not the last"):
        render.render_files(kane_model)


def _strict_cc():
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        pytest.skip("no C compiler")
    return [cc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1"]


# prints the layout of the model's public structs, then runs advance once
# with the defaults: the probe option's default reaches the caller, and the
# runtime's statistic comes back through the copy generated from the list
_HARNESS = r"""
#include <stddef.h>
#include <stdio.h>
#include "pendulum_kane.h"
int main(void)
{
    pendulum_kane_sim_options o;
    pendulum_kane_sim_stats s = {0};
    pendulum_kane_real x[PENDULUM_KANE_NX] = {0.1, 0.2, 0, 0};
    int st;
%(layout)s
    pendulum_kane_sim_options_default(&o);
    printf("default probe_gain %%g\n", (double)o.probe_gain);
    s.probe_count = 41;
    st = pendulum_kane_advance(0, 0.01, NULL, NULL, &o, &s, x);
    printf("advance %%d n_rhs %%ld probe_count %%ld\n", st, s.n_rhs, s.probe_count);
    return 0;
}
"""


def test_a_new_struct_field_appears_everywhere(monkeypatch, kane_model, tmp_path):
    """Fields added to the structs in the description only (gen/codegen/abi.py) reach
    the model's header, the runtime's header (gen_rt_abi.h, rendered into
    every model), the copy between them, the cffi cdef (gen/toolchain/host.py: the
    same offsets as the C compiler's) and the C++ header, with no other
    edit; the model and the runtime compile with them under the strict flags
    and run."""
    monkeypatch.setattr(abi, "STRUCTS", _probed_structs())
    p = plan(kane_model)
    c = render.render(p, backend="c", project=False)
    e = render.render(p, backend="eigen")
    h, rt, body = c.files["pendulum_kane.h"], c.files["gen_rt_abi.h"], c.files["pendulum_kane.c"]
    cdef, source = host.host_sources("double")
    assert cdef in source
    ctype = {"real": ("pendulum_kane_real", "gen_rt_real", "eomgen_real"),
             "long": ("long",) * 3, "int": ("int",) * 3}
    for sname, f in PROBES.items():
        pub, run, hst = ctype[f.ctype]
        assert re.search(rf"\b{pub} {f.name};", struct_body(h, f"pendulum_kane_{sname}")), sname
        assert re.search(rf"\b{run} {f.name};", struct_body(rt, f"gen_rt_{sname}")), sname
        assert re.search(rf"\b{hst} {f.name};", struct_body(cdef, f"eomgen_{sname}")), sname
        assert f"{f.name}_rt" not in body
        # copied in (and a statistic back out) by the code generated from the list
        arg = {"sim_options": "opts", "sim_stats": "stats", "input": "in"}[sname]
        assert f"{arg}_rt.{f.name} = {arg}->{f.name};" in body
        if sname == "sim_stats":
            assert f"{arg}->{f.name} = {arg}_rt.{f.name};" in body
    # the C++ face: typed structs declaring the field and converted from the
    # C ones field by field, or the C header's structs themselves (a face over
    # the C runtime); test_a_new_struct_field_compiles_in_the_cxx_face builds it
    hpp, cpp = e.files["pendulum_kane.hpp"], e.files["pendulum_kane.cpp"]
    assert ((re.search(r"\b(S|Scalar) probe_gain\b", hpp) and "probe_gain" in cpp)
            or '#include "pendulum_kane.h"' in hpp)
    assert "pendulum_kane_real probe_gain;" in e.files["pendulum_kane.h"]

    # compile the model with the runtime, and a harness printing the public
    # layout the C compiler gives
    import cffi
    ffi = cffi.FFI()
    ffi.cdef(cdef)
    fields = [(s.name, f.name) for s in abi.STRUCTS for f in s.fields if not f.count]
    layout = "\n".join(f'    printf("{s} {f} %lu\\n", '
                       f'(unsigned long)offsetof(pendulum_kane_{s}, {f}));' for s, f in fields)
    layout += "\n" + "\n".join(
        f'    printf("{s.name} sizeof %lu\\n", (unsigned long)sizeof(pendulum_kane_{s.name}));'
        for s in abi.STRUCTS if not any(f.count for f in s.fields))
    files = dict(c.files, **{"harness.c": _HARNESS % {"layout": layout}})
    render.write_atomic(files, tmp_path)
    cc = _strict_cc()
    objs = []
    for name in sorted(files):
        if name.endswith(".c"):
            obj = tmp_path / (name[:-2] + ".o")
            proc = subprocess.run([*cc, "-c", name, "-o", str(obj)], cwd=tmp_path,
                                  capture_output=True, text=True)
            assert proc.returncode == 0, name + "\n" + proc.stderr
            objs.append(str(obj))
    exe = tmp_path / "harness"
    subprocess.run([cc[0], *objs, "-lm", "-o", str(exe)], check=True)
    out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.split("\n")
    got = dict((" ".join(w[:-1]), w[-1]) for w in (line.split() for line in out) if w)
    for s, f in fields:
        assert int(got[f"{s} {f}"]) == ffi.offsetof(f"eomgen_{s}", f), (s, f)
    for s in abi.STRUCTS:
        if not any(f.count for f in s.fields):
            assert int(got[f"{s.name} sizeof"]) == ffi.sizeof(f"eomgen_{s.name}"), s.name
    assert float(got["default probe_gain"]) == 0.5
    tail = [line for line in out if line.startswith("advance")][0].split()
    assert tail[1] == "0" and int(tail[3]) == 4          # one RK4 step: four evaluations
    assert tail[5] == "41"                                 # the caller's value, back unchanged


@pytest.mark.slow
@pytest.mark.eigen
def test_a_new_struct_field_compiles_in_the_cxx_face(monkeypatch, kane_model, tmp_path):
    """The C++/Eigen face rendered with the added fields compiles (C++17,
    strict warnings): nothing of it had to be edited by hand."""
    inc = require_eigen()
    cxx = shutil.which(os.environ.get("CXX", "c++")) or pytest.skip("no C++ compiler")
    monkeypatch.setattr(abi, "STRUCTS", _probed_structs())
    e = render.render(plan(kane_model), backend="eigen")
    render.write_atomic(e.files, tmp_path)
    for name in sorted(e.files):
        if name.endswith(".cpp"):
            proc = subprocess.run([cxx, "-std=c++17", "-Wall", "-Wextra", "-Werror",
                                   "-fsyntax-only", "-isystem", str(inc), "-I", ".", name],
                                  cwd=tmp_path, capture_output=True, text=True)
            assert proc.returncode == 0, name + "\n" + proc.stderr[-4000:]


def struct_body(text, name):
    """The field declarations of `typedef struct { ... } name;` in text."""
    m = re.search(r"typedef struct \{([^}]*)\} %s;" % re.escape(name), text)
    assert m, name
    return m.group(1)


def test_runtime_abi_header_is_current():
    """csrc/gen_rt_abi.h (the runtime built alone: ctest, firmware) is what
    gen/codegen/abi.py renders; EOMGEN_UPDATE_GOLDEN=1 rewrites it."""
    path = csrc_file("gen_rt_abi.h")
    want = render.runtime_abi_header()
    if os.environ.get("EOMGEN_UPDATE_GOLDEN", "") not in ("", "0"):
        path.write_text(want)
    assert path.read_text() == want, ("csrc/gen_rt_abi.h differs from gen/codegen/abi.py: "
                                      "EOMGEN_UPDATE_GOLDEN=1 python -m pytest tests/unit/codegen/test_abi.py")


def test_codes_and_bounds_come_from_the_description(kane_model):
    """Method and hold codes, the method aliases and the stack bound are
    gen/codegen/abi.py's in the model's header, the runtime's header, the CMake
    project, the footprint, the command line and the Python checks."""
    files = render.render_files(kane_model)
    h, rt = files["pendulum_kane.h"], files["gen_rt_abi.h"]
    for name, v in abi.METHODS.items():
        assert f"#define PENDULUM_KANE_METHOD_{name.upper()} {v}\n" in h
        assert f"#define GEN_RT_METHOD_{name.upper()} {v}\n" in rt
    for name, v in abi.HOLDS.items():
        assert f"#define PENDULUM_KANE_HOLD_{name.upper()} {v}\n" in h
        assert f"#define GEN_RT_HOLD_{name.upper()} {v}\n" in rt
    names = dict(abi.METHODS, **{a: abi.METHODS[n] for a, n in abi.METHOD_ALIASES.items()})
    assert ("#define GEN_RT_METHOD_NAMES(X) "
            + " ".join(f'X("{k}", {v})' for k, v in names.items()) + "\n") in rt
    assert f"#define GEN_RT_STACK_LIMIT {abi.STACK_LIMIT}\n" in rt
    assert f"_STACK_LIMIT_DEFAULT {abi.STACK_LIMIT})" in files["CMakeLists.txt"]
    from gen.toolchain import footprint
    assert footprint.DEFAULT_STACK_LIMIT == abi.STACK_LIMIT
    assert abi.method_code("rodas") == abi.method_code("rodas4") == 2
    with pytest.raises(ValueError, match=r"method must be one of .* got 'rk5'"):
        abi.method_code("rk5")
    with pytest.raises(ValueError, match=r"input_hold must be one of .* got 'cubic'"):
        abi.hold_code("cubic")
    # no module of gen/ writes these facts again
    for path in sorted((csrc_dir().parent / "gen").glob("*.py")):
        if path.name == "abi.py":
            continue
        text = path.read_text()
        # (an alias table or a list of choices; the docs may name the alias)
        assert not re.search(r"""\{\s*["']rodas["']\s*:|["']rodas["']\s*[\],)]""", text), path.name
        assert "8192" not in text, path.name
        assert not re.search(r"""\{\s*["']zoh["']\s*:""", text), path.name


@pytest.mark.parametrize("every", [1, 2, 3, 7, 10])
def test_simulate_rows_kept_is_the_runtimes(kane_sim, every):
    """The rows simulate keeps (every k-th and the last, or the last) come
    from one C function, <p>_simulate_rows_kept, which the bindings call:
    against a count of the rule itself, and against the rows a run writes."""
    f = kane_sim._fn("simulate_rows_kept")
    for rows in [1, 2, 3, 9, 10, 11, 100, 101]:
        want = sum(1 for k in range(rows) if k % every == 0 or k == rows - 1)
        assert f(rows, every, 0) == want, (rows, every)
        assert f(rows, every, 1) == 1
    assert f(-3, every, 0) == -3 and f(-3, every, 1) == -3     # a status as is
    rows = kane_sim._fn("simulate_rows")(0.0, 1.0, 0.01)
    res = kane_sim.simulate([0.1, 0.2, 0, 0], 1.0, 0.01, every=every)
    t = res[0] if isinstance(res, tuple) else res.t
    assert len(t) == f(rows, every, 0)


def _compile_one(tmp_path, files, name):
    render.write_atomic(files, tmp_path)
    return subprocess.run([*_strict_cc(), "-c", name, "-o", "/dev/null"], cwd=tmp_path,
                          capture_output=True, text=True)


@pytest.mark.parametrize("tamper", ["code", "order", "missing"])
def test_model_pinned_to_the_runtime_description(kane_model, tmp_path, tamper):
    """A model built against a runtime of another description fails to
    compile (the negative-array checks of <name>.c, C99: no _Static_assert):
    another method code, two fields swapped, a field missing."""
    files = render.render_files(kane_model)
    ok = _compile_one(tmp_path / "ok", files, "pendulum_kane.c")
    assert ok.returncode == 0, ok.stderr
    rt = files["gen_rt_abi.h"]
    if tamper == "code":
        rt = rt.replace("#define GEN_RT_METHOD_RODAS4 2", "#define GEN_RT_METHOD_RODAS4 3")
    elif tamper == "order":
        rt = re.sub(r"(    gen_rt_real rtol;[^\n]*\n)(    gen_rt_real atol;[^\n]*\n)", r"\2\1", rt)
    else:
        rt = re.sub(r"    int final_only;[^\n]*\n", "", rt)
    assert rt != files["gen_rt_abi.h"]
    bad = _compile_one(tmp_path / "bad", dict(files, **{"gen_rt_abi.h": rt}), "pendulum_kane.c")
    assert bad.returncode != 0
    assert ("abi_matches_runtime" in bad.stderr) or ("final_only" in bad.stderr)


def test_runtime_pinned_to_the_methods_it_implements(kane_model, tmp_path):
    """A method added to gen/codegen/abi.py that gen_rt_simulate.c does not implement
    fails the runtime's build with a message saying so."""
    files = render.render_files(kane_model)
    ok = _compile_one(tmp_path / "ok", files, "gen_rt_simulate.c")
    assert ok.returncode == 0, ok.stderr
    rt = files["gen_rt_abi.h"].replace("#define GEN_RT_METHOD_COUNT 3",
                                       "#define GEN_RT_METHOD_COUNT 4")
    bad = _compile_one(tmp_path / "bad", dict(files, **{"gen_rt_abi.h": rt}), "gen_rt_simulate.c")
    assert bad.returncode != 0 and "does not implement" in bad.stderr


def test_header_table_cdef_and_footprint_list_one_function_list(kane_model):
    """The header, the plugin table (<name>_api.c, in order), the host
    module's functions and the footprint's list are the same list."""
    r = render.render(plan(kane_model))
    names = r.interface.public_names
    table = r.files["pendulum_kane_api.c"]
    body = table[table.index("pendulum_kane_api = {"):]
    at = [body.index(f"{n},") if f"{n}," in body else body.index(f"{n}\n") for n in
          (f"pendulum_kane_{'api_' if f in r.interface.struct_verbs else ''}{f.verb}"
           for f in r.interface.functions)]
    assert at == sorted(at)
    cdef, source = host.host_sources("double")
    for fn in r.interface.functions + r.interface.batch_functions:
        if fn in r.interface.functions:
            assert re.search(rf"\bpendulum_kane_{fn.verb}\(", r.files["pendulum_kane.h"])
        assert re.search(rf"\beomgen_{fn.verb}\(const eomgen_api \*api", cdef), fn.verb
        assert re.search(rf"\beomgen_{fn.verb}\(const eomgen_api \*api[^;]*\)\n\{{", source)
    from gen.toolchain import footprint
    assert [f"pendulum_kane_{f.verb}" for f in footprint.FUNCTIONS] == names


def test_simulator_needs_no_sympy_model(kane_sim):
    """The Simulator is the module and the interface description only."""
    assert not hasattr(kane_sim, "model")
    it = kane_sim.interface
    assert (it.nq, it.nu, it.mc, it.mv) == (2, 2, 1, 1)
    assert kane_sim.state_names == ["q2", "q1", "u2", "u1"]
