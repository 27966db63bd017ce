/*
 * gen_rt_mpc_status.h - the status table of the model predictive controller
 * and its QP solver (gen_rt_mpc.c, gen_rt_qp.c), beyond the runtime's
 * (gen_rt_status.h, whose negative codes they also return: a failure of
 * the model's step): one line per code, X(NAME, value, "message"). The one
 * source of the codes and their messages: the C (GEN_RT_MPC_<NAME>,
 * gen_rt_mpc_status_message) and gen/design/mpc (which reads this file).
 *
 * A positive code is an outcome with a control (the best one there is);
 * a negative code is a failure: the control is then the previous
 * solution's, shifted (never NaN).
 */
#ifndef GEN_RT_MPC_STATUS_H
#define GEN_RT_MPC_STATUS_H

#define GEN_RT_MPC_STATUS_TABLE(X)                                                      \
    X(MAX_ITER, 1, "the SQP iterations reached max_iter before convergence: the "       \
                   "control of the last iterate")                                      \
    X(TIME_LIMIT, 2, "the time budget ran out: the control of the best iterate so far")  \
    X(ERR_QP_MAX_ITER, -101, "the QP solver reached its iteration cap without "          \
                             "converging (an infeasible or badly conditioned QP)")       \
    X(ERR_QP_SINGULAR, -102, "the QP's Hessian block of the inputs is not positive "     \
                             "definite at a stage of the Riccati recursion")            \
    X(ERR_QP_NONFINITE, -103, "the QP's data or iterates hold NaN or infinity")          \
    X(ERR_NO_CLOCK, -104, "a time limit was set but no clock was given")

/* the message of a code in neither table */
#define GEN_RT_MPC_STATUS_UNKNOWN "unknown status code"

#define GEN_RT_MPC_STATUS_ENUM_(name, value, text) GEN_RT_MPC_##name = (value),
enum gen_rt_mpc_status { GEN_RT_MPC_STATUS_TABLE(GEN_RT_MPC_STATUS_ENUM_) GEN_RT_MPC_OK = 0 };
#undef GEN_RT_MPC_STATUS_ENUM_

#endif /* GEN_RT_MPC_STATUS_H */
