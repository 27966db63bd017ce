"""A controller in C from another library (gen.sim.inputs.CController, the
way a product such as an MPC closes the loop in sim.simulate): a PD law
compiled apart and called by the engine gives the run of the same law as a
gen.LinearFeedback, bit for bit; its failure stops the run with
ERR_CONTROLLER; its period samples it."""
import subprocess

import cffi
import numpy as np
import pytest

import gen
from gen.codegen.backends import C_FLAGS, c_compiler
from gen.sim.inputs import CController

LAW = r"""
/* r = -K (x - x_op) on the pendulum's [theta, omega]; ctx: K[2], x_op[2], fail_after */
typedef struct { double K[2]; double x_op[2]; double fail_after; int calls; } pd_ctx;
int pd(void *vctx, double t, const double *x, double *r)
{
    pd_ctx *c = (pd_ctx *)vctx;
    c->calls++;
    if (t > c->fail_after) return 1;
    r[0] = r[0] - (c->K[0] * (x[0] - c->x_op[0]) + c->K[1] * (x[1] - c->x_op[1]));
    return 0;
}
"""
CDEF = ("typedef struct { double K[2]; double x_op[2]; double fail_after; int calls; } pd_ctx;"
        "int pd(void *vctx, double t, const double *x, double *r);")


class PD:
    """A face in the way a product's is: c_controller gives the engine its C."""

    def __init__(self, lib, ffi, K, x_op, fail_after=np.inf, period=0.0):
        self.ffi, self.lib, self.period = ffi, lib, period
        self.ctx = ffi.new("pd_ctx *", {"K": K, "x_op": x_op, "fail_after": fail_after})

    def c_controller(self, sim):
        addr = int(self.ffi.cast("uintptr_t", self.ffi.addressof(self.lib, "pd")))
        return CController(addr, int(self.ffi.cast("uintptr_t", self.ctx)), self, self.period)


@pytest.fixture(scope="module")
def law(tmp_path_factory):
    d = tmp_path_factory.mktemp("pd")
    (d / "pd.c").write_text(LAW)
    subprocess.run([c_compiler(), *C_FLAGS, "-fPIC", "-shared", str(d / "pd.c"), "-o",
                    str(d / "pd.so")], check=True)
    ffi = cffi.FFI()
    ffi.cdef(CDEF)
    return ffi, ffi.dlopen(str(d / "pd.so"))


@pytest.fixture(scope="module")
def pend():
    import sympy as sm
    from sympy.physics import mechanics as me
    theta, omega, T = me.dynamicsymbols("theta omega T")
    m, l, g = sm.symbols("m l g")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [theta, N.z])
    A.set_ang_vel(N, omega * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    km = me.KanesMethod(N, q_ind=[theta], u_ind=[omega], kd_eqs=[theta.diff() - omega])
    km.kanes_equations([me.Particle("bob", P, m)], [(P, m * g * N.x), (A, T * N.z)])
    return gen.compile(gen.Model.from_kanes(km, constants={m: 1.0, l: 0.5, g: 9.81},
                                            inputs=[T], name="cctl_pend"))


def test_a_c_controller_closes_the_loop_as_the_same_linear_feedback(law, pend):
    ffi, lib = law
    K, x_op = [20.0, 4.0], [0.5, 0.0]
    for period in (0.0, 0.01):
        pd = PD(lib, ffi, K, x_op, period=period)
        r_op = [9.81 * 0.5 * np.sin(0.5)]
        got = pend.simulate([0.0, 0.0], 2.0, 1e-3, r=r_op, controller=pd)
        ref = pend.simulate([0.0, 0.0], 2.0, 1e-3, controller=gen.LinearFeedback(
            K=[K], x_op=x_op, r_op=r_op, period=period or None))
        assert np.array_equal(got.x, ref.x) and np.array_equal(got.r, ref.r), period
        assert abs(got.x[-1, 0] - 0.5) < 1e-3 and pd.ctx.calls > 0


def test_a_failing_c_controller_stops_the_run_with_its_status(law, pend):
    ffi, lib = law
    with pytest.raises(gen.SolverError, match="ERR_CONTROLLER|controller") as e:
        pend.simulate([0.1, 0.0], 1.0, 1e-3, controller=PD(lib, ffi, [1.0, 1.0], [0, 0],
                                                           fail_after=0.25))
    assert e.value.status_name == "ERR_CONTROLLER" and 0.24 < e.value.time <= 0.25


def test_a_bad_c_controller_is_refused(law, pend):
    class Bad:
        def c_controller(self, sim):
            return (1, 2)
    with pytest.raises(TypeError, match="must return a gen.sim.inputs.CController"):
        pend.simulate([0.1, 0.0], 1.0, 1e-3, controller=Bad())
    ffi, lib = law
    with pytest.raises(gen.InputError, match="has its own period"):
        pend.simulate([0.1, 0.0], 1.0, 1e-3, controller=PD(lib, ffi, [1, 1], [0, 0]),
                      input_period=0.1)
