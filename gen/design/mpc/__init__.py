"""Nonlinear model predictive control on the target (issue 43): real-time
iterations over the model's own discrete step, in C.

    mpc = gen.MPC(model, horizon=20, period=0.05, Q=[10, 10, 1, 1], R=[0.1],
                  bounds={F: (-20, 20), x: (-1, 1)}, reference=(x_up, [0.0]))
    u = mpc(x, t=0.0)                  # the control; mpc.x, mpc.u, mpc.status, mpc.times
    sol = sim.simulate(x0, 5.0, 1e-3, controller=mpc)   # the loop closed in C
    mpc.to_c("out/cart_pole")          # a firmware module, static workspace, no heap

The problem (N intervals of one period, N + 1 states):

    min  sum_{k<N} period (|x_k - x_ref(t_k)|^2_Q + |u_k - u_ref(t_k)|^2_R
                           + sum_i w_i y_i(x_k, u_k)^2) + |x_N - x_ref(t_N)|^2_P
         + penalty * (the soft constraints' violations)
    s.t. x_0 = x (the measured state), x_{k+1} = F(x_k, u_k),
         bounds on the inputs (hard) and on the independent states (soft, L1),
         path constraints lo <= h(x_k, u_k) <= hi (linearized at each
         iteration; soft where h holds a state, hard on the inputs alone)

on the independent state x_ind = [q_ind, u_ind] (a constrained model's
dependent coordinates and speeds follow its constraints, as in
``sim.linearize``), with t_k = t + k period. The stage costs are weighted
by the period (a quadrature of the integral) and P is not, as in acados.
F is the model's own discrete step: ``substeps`` classic RK4 steps of
period / substeps with the inputs held, with its exact sensitivities (the
runtime's step_sensitivity). The Hessian is the cost's Gauss-Newton one;
the QP, stage-wise, is solved by a primal-dual interior point whose Newton
systems are Riccati recursions (HPIPM's design; csrc/products/mpc/
gen_rt_qp.c), with no heap, in float or double.

The iterates: the first call starts from zero states and inputs (acados's
default; a constrained model, whose constraints zero would violate, from
the measured state at every node and the reference's inputs), unless a
guess is given (``mpc.reset(x, u)``); each later call from the previous
solution shifted by one interval, the last repeated. method="rti" does one
SQP iteration per call (a preparation phase, the new state, a feedback
phase), method="sqp" iterates to convergence, at most max_iter. A time
limit (seconds per call) ends a call with the best control so far and the
status TIME_LIMIT; the control returned is never NaN.

Modules: problem (the arguments, checked), reference (the reference as a
table), plan (the MPC backend's ProductPlan: kernels, data, the model's C
sources), controller (gen.MPC).
"""
from .controller import MPC, MPCTimes, STATUSES, status_name

__all__ = ["MPC", "MPCTimes", "STATUSES", "status_name"]
