"""A PyDy script switched to eomgen by one argument.

The usual PyDy workflow (a ``pydy.system.System``: constants, specifieds as
functions of the state and time, initial conditions, times, ``integrate``)
on PyDy's own double pendulum on a cart with a cart force and joint
torques. The one change that makes eomgen generate, compile and evaluate the
right-hand side::

    sys.generate_ode_function(generator="cython")                       # before
    sys.generate_ode_function(generator=gen.pydy.ODEFunctionGenerator)  # after

Everything else (odeint, the arguments, the results) stays PyDy's.

    python examples/pydy_switch.py                 # eomgen, then PyDy's lambdify, compared
    python examples/pydy_switch.py --generator cython
"""
import sys
import time

import numpy as np
from pydy.models import n_link_pendulum_on_cart

import gen
import gen.pydy  # noqa: F401  (gen.pydy also loads on first use)


def simulate(generator=gen.pydy.ODEFunctionGenerator, n=2, t_end=5.0):
    """(times, states, build seconds) of PyDy's n-link pendulum on a cart
    integrated by PyDy's System.integrate (odeint) over the rhs that
    ``generator`` builds."""
    system = n_link_pendulum_on_cart(n, cart_force=True, joint_torques=True)
    coords, speeds = system.coordinates, system.speeds
    constants = {c: 1.0 for c in system.constants_symbols}
    constants.update({c: 9.81 for c in system.constants_symbols if c.name == "g"})
    system.constants = constants
    F, torques = None, []
    for s in system.specifieds_symbols:
        if s.func.__name__ == "F":
            F = s
        else:
            torques.append(s)
    torques.sort(key=lambda s: s.func.__name__)
    # a push on the cart that decays, and joint torques as feedback on the
    # state (functions of (x, t), PyDy's dict form with a tuple key)
    system.specifieds = {F: lambda x, t: 2.0 * np.exp(-t),
                         tuple(torques): lambda x, t: -0.5 * x[n + 2:2 * n + 2]}
    system.initial_conditions = {**{q: 0.0 for q in coords},
                                 **{u: 0.0 for u in speeds}, coords[1]: 0.3}
    system.times = np.linspace(0.0, t_end, int(round(t_end * 100)) + 1)
    t0 = time.perf_counter()
    system.generate_ode_function(generator=generator)        # <- the one argument
    build = time.perf_counter() - t0
    X = system.integrate(rtol=1e-10, atol=1e-12)
    return system.times, X, build


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    other = argv[argv.index("--generator") + 1] if "--generator" in argv else "lambdify"
    t, X, build = simulate(gen.pydy.ODEFunctionGenerator)
    _, Y, build_other = simulate(other)
    diff = float(np.max(np.abs(X - Y)))
    print(f"eomgen: built in {build:.2f} s; PyDy {other}: {build_other:.2f} s")
    print(f"final state (eomgen):  {np.array2string(X[-1], precision=6)}")
    print(f"final state ({other}): {np.array2string(Y[-1], precision=6)}")
    print(f"max |difference| over {len(t)} samples: {diff:.2e}")
    return diff


if __name__ == "__main__":
    main()
