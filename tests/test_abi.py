"""The one description of the C interface (gen/abi.py) against what is
built from it and what it is read from:

- the status table is the runtime's (csrc/gen_rt_status.h), and the compiled
  C runtime, the compiled Eigen backend and the bindings agree with it code
  for code (identical messages on both backends);
- a struct field added to the description appears in the C header, the cffi
  cdef and the C++ header with no other edit (the documented check);
- the header, the cdef and the footprint's function list are the same list.
"""
import dataclasses
import re

import pytest

import gen
from gen import abi, host, bindings, render
from gen.ir import plan
from gen.resources import csrc_dir

from conftest import require_eigen

CODES = [s.value for s in abi.STATUSES] + [1, -10, -1000]


def test_table_is_the_runtimes():
    text = (csrc_dir() / "gen_rt_status.h").read_text()
    assert len(abi.STATUSES) == text.count("    X(")
    values = [s.value for s in abi.STATUSES]
    assert values == list(range(0, -len(values), -1))       # 0, -1, -2, ... no gaps
    assert abi.STATUSES[0].name == "OK"
    header = (csrc_dir() / "gen_rt.h").read_text()
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


def test_a_new_struct_field_appears_everywhere(monkeypatch, kane_model):
    """Add a field to sim_options in the description only; the C header, the
    host module's cdef (gen/host.py) and the C++ header all carry it."""
    structs = []
    for s in abi.STRUCTS:
        if s.name == "sim_options":
            s = dataclasses.replace(s, fields=s.fields + (
                abi.Field("probe_gain", "real", "a field added in one place", 0.5),))
        structs.append(s)
    monkeypatch.setattr(abi, "STRUCTS", tuple(structs))
    p = plan(kane_model)
    c = render.render(p, backend="c")
    e = render.render(p, backend="eigen")
    decl = re.compile(r"pendulum_kane_real probe_gain;")
    assert decl.search(c.files["pendulum_kane.h"])
    cdef, source = host.host_sources("double")
    assert re.search(r"eomgen_real probe_gain;", cdef) and cdef in source
    assert decl.search(e.files["pendulum_kane.h"])
    assert re.search(r"\bS probe_gain\b|\bScalar probe_gain\b", e.files["pendulum_kane.hpp"])
    import cffi
    cffi.FFI().cdef(cdef)                         # the cdef still parses


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
    from gen import footprint
    assert [f"pendulum_kane_{f.verb}" for f in footprint.FUNCTIONS] == names


def test_simulator_needs_no_sympy_model(kane_sim):
    """The Simulator is the module and the interface description only."""
    assert not hasattr(kane_sim, "model")
    it = kane_sim.interface
    assert (it.nq, it.nu, it.mc, it.mv) == (2, 2, 1, 1)
    assert kane_sim.state_names == ["q2", "q1", "u2", "u1"]
