"""A backend is a type (issue 31): one object per backend in one registry
(gen/codegen/backends/), asked by rendering and the build, never compared by
name; and the pipeline's modules import one way."""
import ast
from pathlib import Path

import pytest

import gen
from gen.codegen.backends import C_FLAGS
from gen.codegen.backends import (BACKENDS, Backend, CBackend, EigenBackend, FmuBackend, OcpBackend,
                                  ProductBackend, TrackerBackend, backend_names, get_backend)

GEN = Path(gen.__file__).resolve().parent


def test_one_object_per_backend_in_one_registry():
    assert list(BACKENDS) == ["c", "eigen", "fmu", "casadi", "ocp", "tracker", "mpc",
                             "estimator"]
    assert type(get_backend("c")) is CBackend
    assert type(get_backend("eigen")) is EigenBackend
    assert type(get_backend("fmu")) is FmuBackend
    b = get_backend("eigen")
    assert get_backend(b) is b                      # the object is accepted as well
    assert backend_names("loadable") == ["c", "eigen"]
    assert backend_names("project") == ["c", "eigen"]
    # the products' libraries: rendered from a face's plan, never gen.compile'd
    assert backend_names("product") == ["ocp", "tracker", "mpc", "estimator"]
    assert type(get_backend("ocp")) is OcpBackend and type(get_backend("tracker")) is TrackerBackend
    assert all(isinstance(b, ProductBackend) == b.product for b in BACKENDS.values())
    # the capabilities the pipeline asks for
    assert [n for n, b in BACKENDS.items() if b.lazy_derivatives] == ["c"]
    assert [n for n, b in BACKENDS.items() if b.link_cxx] == ["eigen"]
    assert get_backend("c").lin == "auto" and get_backend("eigen").lin == "auto"   # the C library


def test_unknown_backend_names_the_known_ones(kane_model, tmp_path):
    with pytest.raises(gen.ModelError, match=r"unknown backend 'cuda': choose one of "
                                             r"\['c', 'eigen', 'fmu', 'casadi', 'ocp', "
                                             r"'tracker', 'mpc', 'estimator'\]"):
        get_backend("cuda")
    # a product's library is not a model's
    with pytest.raises(gen.ModelError, match=r"unknown backend 'ocp': choose one of "
                                             r"\['c', 'eigen'\]"):
        gen.compile(kane_model, backend="ocp")
    # gen.compile loads a library with a plugin table: the FMU has none
    with pytest.raises(gen.ModelError, match=r"unknown backend 'fmu': choose one of "
                                             r"\['c', 'eigen'\]"):
        gen.compile(kane_model, backend="fmu")
    with pytest.raises(gen.ModelError, match=r"unknown backend 'fmu': choose one of "
                                             r"\['c', 'eigen'\]"):
        gen.generate(kane_model, tmp_path / "out", backend="fmu")
    assert not (tmp_path / "out").exists()


def test_recipe_is_data_of_the_backend():
    """What the build compiles, with which compiler: the C backend's own
    files in C (the derivative kernels at -O1, or their stand-ins), the
    FMU's with only the FMI functions exported and the FMI headers."""
    c = get_backend("c")
    lazy = [f for f, _, _ in c.units("m", {}, derivatives=False)]
    assert lazy == ["m.c", "m_kernels.c", "m_api.c", "m_lin_stub.c"]
    full = c.units("m", {}, derivatives=True)
    assert full[0][0] == "m_lin.c" and "-O1" in full[0][2]
    files = {"m.c": "x" * 10, "m_lin.c": "x" * 100, "gen_rt_model.c": "x", "gen_fmu.c": "xx",
             "m.h": ""}
    fmu = get_backend("fmu").units("m", files, True, includes=("/fmi",))
    assert [f for f, _, _ in fmu] == ["m_lin.c", "m.c", "gen_fmu.c"]   # largest first
    assert all("-fvisibility=hidden" in fl and fl[-2:] == ["-isystem", "/fmi"]
               for _, _, fl in fmu)
    assert get_backend("fmu").library_file("_eomgen_m_fmu_0", "m").startswith("m.")
    # a product compiles its own files and its runtime's, largest first,
    # position independent with the model library's flags
    ocp = get_backend("ocp")
    units = ocp.units("p", {"p.c": "x" * 50, "gen_rt_ocp.c": "x" * 5, "p.h": "", "gen_rt_ocp.h": ""},
                      True)
    assert [(f, fl) for f, _, fl in units] == [("p.c", [*C_FLAGS, "-fPIC"]),
                                               ("gen_rt_ocp.c", [*C_FLAGS, "-fPIC"])]
    assert "backend=ocp" in ocp.cache_parts()
    # its templates are data: its own, then the headers of its interface
    iface = ocp.interface.bind(name="p", model="m")
    assert ocp.file_templates(iface) == [("{name}.c", "ocp/ocp.c.j2", "product"),
                                         ("{name}.h", "common/product.h.j2", "product"),
                                         ("gen_rt_ocp_abi.h", "common/product_types.h.j2",
                                          "product")]
    assert ocp.runtime_files == ("gen_rt_ocp.c", "gen_rt_ocp.h", "gen_rt_status.h")


def _sources():
    return sorted(GEN.rglob("*.py"))


def test_no_backend_name_compared_outside_the_registry():
    bad = [f"{p.name}:{i}" for p in _sources() if "backends" not in p.parts
           for i, line in enumerate(p.read_text().splitlines(), 1)
           if "backend ==" in line or "backend !=" in line]
    assert bad == []
    # BACKENDS is defined once
    defs = [p.relative_to(GEN).as_posix() for p in _sources()
            for node in ast.walk(ast.parse(p.read_text())) if isinstance(node, ast.Assign)
            for t in node.targets if isinstance(t, ast.Name) and t.id == "BACKENDS"]
    assert defs == ["codegen/backends/__init__.py"]
    assert issubclass(CBackend, Backend)
