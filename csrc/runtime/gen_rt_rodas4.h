/*
 * gen_rt_rodas4.h - the coefficients of RODAS4 (Hairer and Wanner, Solving
 * Ordinary Differential Equations II, 2nd ed., Springer 1996, section VI.4:
 * a stiffly accurate, L-stable Rosenbrock method of order 4 with an
 * embedded order-3 solution, 6 stages), once for both runtimes: the C
 * runtime (gen_rt_integrate.c) and the C++ runtime (eigen/gen_rt_eigen.hpp)
 * expand X(NAME, value) with their own scalar type.
 *
 * The form (that of Hairer's rodas and of KPP/FATODE): with the Jacobian J
 * and df/dt at (t0, y0), G = I/(h GAMMA) - J, for stages i = 1..6
 *   Y_i = y0 + sum_{j<i} A_ij K_j,
 *   G K_i = f(t0 + ALPHA_i h, Y_i) + sum_{j<i} (C_ij / h) K_j + h GAMMA_i df/dt,
 *   y1 = y0 + sum_j M_j K_j  (= Y_6 + K_6: stiffly accurate),
 *   error estimate = K_6 (the difference to the embedded solution).
 * The tests check orders 4 and 3 numerically (tests/unit/runtime/test_engine.py).
 */
#ifndef GEN_RT_RODAS4_H
#define GEN_RT_RODAS4_H

#define GEN_RT_RODAS4_TABLEAU(X)                                               \
    X(GAMMA, 0.25)                                                             \
    X(ALPHA2, 0.386) X(ALPHA3, 0.21) X(ALPHA4, 0.63)                           \
    X(GAMMA2, -0.1043) X(GAMMA3, 0.1035) X(GAMMA4, -0.3620000000000023E-01)    \
    X(A21, 0.1544000000000000E+01)                                             \
    X(A31, 0.9466785280815826) X(A32, 0.2557011698983284)                      \
    X(A41, 0.3314825187068521E+01) X(A42, 0.2896124015972201E+01)              \
    X(A43, 0.9986419139977817)                                                 \
    X(A51, 0.1221224509226641E+01) X(A52, 0.6019134481288629E+01)              \
    X(A53, 0.1253708332932087E+02) X(A54, -0.6878860361058950)                 \
    X(C21, -0.5668800000000000E+01)                                            \
    X(C31, -0.2430093356833875E+01) X(C32, -0.2063599157091915)                \
    X(C41, -0.1073529058151375) X(C42, -0.9594562251023355E+01)                \
    X(C43, -0.2047028614809616E+02)                                            \
    X(C51, 0.7496443313967647E+01) X(C52, -0.1024680431464352E+02)             \
    X(C53, -0.3399990352819905E+02) X(C54, 0.1170890893206160E+02)             \
    X(C61, 0.8083246795921522E+01) X(C62, -0.7981132988064893E+01)             \
    X(C63, -0.3152159432874371E+02) X(C64, 0.1631930543123136E+02)             \
    X(C65, -0.6058818238834054E+01)

/* Stage 6 evaluates at Y_5 + K_5 (A6j = M_j for j < 5, A65 = 1) and
 * y1 = Y_6 + K_6; stages 5 and 6 evaluate at t0 + h. */

#endif /* GEN_RT_RODAS4_H */
