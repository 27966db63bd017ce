"""A product's C interface is data (gen/codegen/product_abi.py): bound to
one build, and rendered into its headers and its cffi cdef by the same
macros (templates/common/product.j2)."""
import cffi
import pytest

from gen.codegen.backends import get_backend
from gen.codegen.product_abi import CFunction, bind_text
from gen.codegen.render import product_cdef
from gen.codegen.templating import template_env


def test_bind_replaces_the_placeholders_only():
    assert bind_text("{name}_eval(x) { return {p}; } {other}", {"name": "q", "p": 3}) == \
        "q_eval(x) { return 3; } {other}"
    iface = get_backend("ocp").interface.bind(name="cart_ocp", model="cart")
    assert iface.name == "cart_ocp" and iface.public_names == ["cart_ocp_eval",
                                                                "cart_ocp_work_len"]
    assert "{" not in iface.doc and "'cart'" in iface.doc
    assert iface.value("GEN_RT_OCP_HESSIAN") == 4
    with pytest.raises(KeyError, match="no constant 'GEN_RT_OCP_NONE'"):
        iface.value("GEN_RT_OCP_NONE")
    # the unbound description is left as it was
    assert get_backend("ocp").interface.name == "{name}"


def test_a_long_prototype_wraps_and_stays_the_same_declaration():
    f = CFunction("p_eval", "int", tuple(("const double *", f"a{i}") for i in range(12)))
    text = f.wrapped(60)
    assert all(len(line) <= 60 for line in text.splitlines()) and text.count("\n") >= 3
    assert " ".join(text.split()).replace("( ", "(") == f.signature
    assert CFunction("p_len", "int", ()).signature == "int p_len(void)"


def test_the_cdef_is_the_headers_declarations():
    """cffi parses the cdef; it declares the struct's fields in the
    description's order and every function with the header's prototype."""
    iface = get_backend("ocp").interface.bind(name="cart_ocp", model="cart")
    cdef = product_cdef(iface)
    ffi = cffi.FFI()
    ffi.cdef(cdef)
    (struct,) = iface.structs
    assert [name for name, _ in ffi.typeof(struct.name).fields] == [f.name for f in struct.fields]
    header = template_env().get_template("common/product.h.j2").render(iface=iface,
                                                                       version="0")
    flat = " ".join(header.split()).replace("( ", "(")
    for f in iface.functions:
        assert f"{f.signature};" in flat and f"{f.signature};" in cdef
    assert '#include "gen_rt_ocp_abi.h"' in header       # its types: the runtime's header
    types = template_env().get_template("common/product_types.h.j2").render(iface=iface,
                                                                            version="0")
    assert "} gen_rt_ocp_block;" in types and "GEN_RT_OCP_JACOBIAN = 3," in types
    assert "cart" not in types                    # the same for every build


def test_the_tracker_interface_names_its_model():
    iface = get_backend("tracker").interface.bind(
        name="swingup", p="cart_pole", N="SWINGUP", P="CART_POLE", n_gain=3, t0="0.0",
        t0_text="0.0", period="0.01", period_text="0.01", flash=24, table_bytes="K 8")
    assert [f.signature for f in iface.functions] == [
        "void swingup_input(cart_pole_input *in)",
        "int swingup_step(cart_pole_real t, const cart_pole_real *x, cart_pole_real *r)"]
    assert iface.includes == ('"cart_pole.h"',)
    assert iface.value("SWINGUP_PERIOD") == "((cart_pole_real)0.01)"
