/*
 * gen_rt_status.h - the status table of the eomgen runtime: one line per
 * code, X(NAME, value, "message"). It is the one source of the codes and
 * their messages: the C runtime (gen_rt.h, gen_rt_status.c), the C++
 * runtime (eigen/gen_rt_eigen.hpp) and the generator (gen/codegen/abi.py reads this file)
 * all take them from here. Add a code here and nowhere else.
 */
#ifndef GEN_RT_STATUS_H
#define GEN_RT_STATUS_H

#define GEN_RT_STATUS_TABLE(X)                                                          \
    X(OK, 0, "ok")                                                                      \
    X(ERR_NULL, -1, "a required pointer argument is NULL")                              \
    X(ERR_NONFINITE_INPUT, -2, "an input value is NaN or infinite")                     \
    X(ERR_SINGULAR, -3, "singular system: the matrix to solve is singular or too "      \
                        "badly conditioned at this state (for a partitioned model: "    \
                        "the dependent coordinates/speeds are not determined here)")    \
    X(ERR_NO_CONVERGENCE, -4, "Newton iteration on the configuration constraints did "  \
                              "not converge")                                           \
    X(ERR_STEP_UNDERFLOW, -5, "step size underflow: the adaptive integrator could not " \
                              "meet the tolerance")                                     \
    X(ERR_MAX_STEPS, -6, "maximum number of integration steps exceeded")                \
    X(ERR_BAD_ARG, -7, "an argument is out of range (size, step or tolerance)")         \
    X(ERR_NONFINITE_MODEL, -8, "the model expressions evaluate to NaN or infinity at "  \
                               "this state (a singular configuration of the model)")    \
    X(ERR_OUTPUT_FULL, -9, "the output buffer is too small")                            \
    X(ERR_SINGULAR_KINEMATICS, -10, "singular kinematic equations: q' cannot be solved "  \
                                    "from Kqd(q) q' + Ku(q) u + kf = 0 at this "          \
                                    "configuration (with Euler angles: gimbal lock)")  \
    X(ERR_DIVERGED, -11, "the state diverged: it grew beyond the range of the scalar "  \
                         "type (overflow) during integration")                          \
    X(ERR_CONTROLLER, -12, "the controller callback returned an error")                \
    X(ERR_CANCELLED, -13, "cancelled: the caller set the cancellation flag of the "     \
                          "options (sim_options.cancel)")                              \
    X(ERR_SINGULAR_REACTIONS, -14, "the reaction forces of the auxiliary speeds are "   \
                                   "not determined at this state: the matrix of their " \
                                   "auxiliary equations is singular")                 \
    X(ERR_INCONSISTENT_RESET, -15, "a reset's map gives a state that violates the "     \
                                   "model's constraints (hybrid={...}: gen.Reset)")         \
    X(ERR_PENETRATED, -16, "the run starts on the wrong side of a hybrid declaration "   \
                           "(hybrid={...}): an impact's gap past zero in its closing "   \
                           "direction, or a reset's guard inside the region its "       \
                           "direction fires on")                                        \
    X(ERR_GUARD_CROSSED, -17, "a step crosses a hybrid guard in its direction: the "     \
                              "function integrates one phase and never jumps (split the " \
                              "trajectory at the guard: guard_<name>, map_<name>)")

/* the message of a code outside the table */
#define GEN_RT_STATUS_UNKNOWN "unknown status code"

#endif /* GEN_RT_STATUS_H */
