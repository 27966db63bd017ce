"""Optimal control by direct collocation on the model's implicit equations
(issue 34): trajectories, free final times and parameter identification,
solved by IPOPT (cyipopt) with the exact Hessian of the Lagrangian.

    ocp = gen.OptimalControl(model, 101, 2.0, objective=F**2,
                             bounds={F: (-20, 20), x: (-1.5, 1.5)},
                             initial={x: 0, theta: sm.pi, v: 0, omega: 0},
                             final={x: 0, theta: 0, v: 0, omega: 0})
    sol = ocp.solve()                  # a gen.OptimalSolution
    sol.objective, sol.t, sol.x, sol.r, sol(0.5)

The transcription. Every collocation point (the nodes, the midpoints, or
both: the method decides) carries the slopes s = [q', u'] of the state as
unknowns, and the model's implicit equations hold there:

    kinematics   Kqd(q) q' + Ku(q) u + kf(q, t) = 0
    dynamics     M(q) u' - f(q, u, r, p, t) - A(q)^T lam = 0

with lam the velocity constraints' multipliers (unknowns at every point;
for Kane's method M and f are the unconstrained equations of all the
speeds, so A^T lam is the constraint force). Constrained models
(method "hermite-simpson" only, OpenSim Moco's form) keep the
configuration, velocity and acceleration constraints f_c(q) = 0,
A u + b = 0 and A u' + a = 0 at every node, and a velocity correction
Jc(q)^T mu of the midpoint's coordinate slopes in Simpson's rule (mu zero
for the DAE): the model stays a DAE and nothing is inverted symbolically.
At an end node whose initial or final values give all of q (and u), the
configuration (and velocity) rows are checked on those values and left
out: kept, they would repeat the fixed values and IPOPT's equality
constraints would be linearly dependent. The
defects tie the states to the slopes, linearly (h = T/(N-1)):

    backward-euler   x[k+1] - x[k] - h s[k+1]                   (points: nodes 1..N-1)
    midpoint         x[k+1] - x[k] - h s[k+1/2], at the point ((x[k] + x[k+1])/2,
                     (r[k] + r[k+1])/2)                          (points: midpoints)
    trapezoidal      x[k+1] - x[k] - h/2 (s[k] + s[k+1])         (points: nodes)
    hermite-simpson  separated form: the midpoint state x[k+1/2] and input
                     r[k+1/2] are unknowns with
                     x[k+1/2] - (x[k] + x[k+1])/2 - h/8 (s[k] - s[k+1]) = 0,
                     x[k+1] - x[k] - h/6 (s[k] + 4 s[k+1/2] + s[k+1]) = 0
                                                                 (points: nodes and midpoints)

Backward Euler and midpoint are opty's transcriptions (the slopes,
eliminated, give its defects). The running cost is integrated by the
method's rule (h sum over nodes 1..N-1; h sum over midpoints; trapezoid;
Simpson) and the final time T is always a variable, fixed by its bounds
when ``duration`` is a number.

The C. Each piece (the point equations, the manifold, the defects, the
running and terminal costs, the path and instance constraints, the fits)
is a family of three generated kernels over its local variables: values,
the sparse Jacobian, and the lower triangle of the Hessian of
sum_i lam_i g_i, from one CSE'd graph each (gen.plan.ir). The runtime
(csrc/products/ocp/gen_rt_ocp.c) loops over the instances of every family
in C, once per IPOPT callback: it gathers each instance's locals from the
decision vector, calls the kernels and scatters into IPOPT's arrays through
index tables this package computes. Bounds, initial and final values,
known constants, path bounds, the duration and the fit data are arguments
of those calls, never compiled in.

The library is a product of the one pipeline (gen.pipeline.product): the
families' kernels are the OCP backend's plan (gen/codegen/backends/
OcpBackend), rendered with its templates (templates/ocp) and its
interface (the gen_rt_ocp_block struct, <prefix>_eval, <prefix>_work_len:
described once, rendered into its headers and its cdef), built and cached
by content like a model library and opened by gen.toolchain.host.

The modules: names (the user's symbols), transcription (the families and
their kernels), layout (the decision vector, the assembly, the index
tables), ipopt (the IPOPT problem), problem (OptimalControl), solution
(OptimalSolution).
"""
from .problem import OptimalControl
from .solution import OptimalSolution
from .transcription import METHODS

__all__ = ["OptimalControl", "OptimalSolution", "METHODS"]
