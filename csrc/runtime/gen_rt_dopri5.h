/*
 * gen_rt_dopri5.h - the Dormand-Prince 5(4) tableau, once for both runtimes:
 * X(NAME, numerator, denominator). The C runtime (gen_rt_integrate.c) and
 * the C++ runtime (eigen/gen_rt_eigen.hpp) expand it with their own scalar type,
 * so the coefficients are written in one place. D1..D7 are the
 * coefficients of the continuous extension of order 4 (Hairer, Norsett and
 * Wanner, Solving ODEs I, 2nd ed., section II.6; Hairer's dopri5).
 */
#ifndef GEN_RT_DOPRI5_H
#define GEN_RT_DOPRI5_H

#define GEN_RT_DOPRI5_TABLEAU(X)                                               \
    X(C2, 0.2, 1.0) X(C3, 0.3, 1.0) X(C4, 0.8, 1.0) X(C5, 8.0, 9.0)            \
    X(A21, 0.2, 1.0)                                                           \
    X(A31, 3.0, 40.0) X(A32, 9.0, 40.0)                                        \
    X(A41, 44.0, 45.0) X(A42, -56.0, 15.0) X(A43, 32.0, 9.0)                   \
    X(A51, 19372.0, 6561.0) X(A52, -25360.0, 2187.0) X(A53, 64448.0, 6561.0)   \
    X(A54, -212.0, 729.0)                                                      \
    X(A61, 9017.0, 3168.0) X(A62, -355.0, 33.0) X(A63, 46732.0, 5247.0)        \
    X(A64, 49.0, 176.0) X(A65, -5103.0, 18656.0)                               \
    X(B1, 35.0, 384.0) X(B3, 500.0, 1113.0) X(B4, 125.0, 192.0)                \
    X(B5, -2187.0, 6784.0) X(B6, 11.0, 84.0)                                   \
    X(E1, 71.0, 57600.0) X(E3, -71.0, 16695.0) X(E4, 71.0, 1920.0)             \
    X(E5, -17253.0, 339200.0) X(E6, 22.0, 525.0) X(E7, -1.0, 40.0)           \
    X(D1, -12715105075.0, 11282082432.0) X(D3, 87487479700.0, 32700410799.0)   \
    X(D4, -10690763975.0, 1880347072.0) X(D5, 701980252875.0, 199316789632.0)  \
    X(D6, -1453857185.0, 822651844.0) X(D7, 69997945.0, 29380423.0)

#endif /* GEN_RT_DOPRI5_H */
