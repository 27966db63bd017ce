/*
 * gen_rt_eigen.hpp - the C++17/Eigen runtime of eomgen (hand-written, one
 * header, model-agnostic). The generated <model>.hpp supplies a model traits
 * type and forwards its typed API to gen_rt::Runtime<Model, S>, S the scalar
 * type (float and double may be used in one program).
 *
 * The traits type (the contract between the generated header and this one):
 *
 *   struct Model {
 *     static constexpr int NQ, NU, NX, NR, NP, MC, MV, NS, NQI, NUI;
 *     static constexpr bool HAS_ENERGY, EXPLICIT_KINEMATICS;
 *     static constexpr gen_rt::Accel ACCEL;  // ACCEL_SPD (MV == 0: LDLT of M),
 *         // ACCEL_PARTITIONED (Kane: dependent speeds eliminated), ACCEL_KKT (Lagrange)
 *     q_ind[k], q_dep[j], u_ind[k], u_dep[j]: static constexpr int arrays
 *         (or references to them), at least max(n, 1) long;
 *     // the kernels, over any scalar S; row-major arrays; all noexcept:
 *     template <class S> static void mass_matrix(const S *q, const S *p, S t, S *M);
 *     template <class S> static void forcing(const S *q, const S *u, const S *r,
 *                                            const S *p, S t, S *f);
 *     template <class S> static void kinematics(const S *q, const S *u, const S *p, S t,
 *                                               S *Kqd, S *qd);
 *         // explicit: qd = q' (Kqd unused, may be null); implicit: Kqd (NQ x NQ)
 *         // and qd = kr, the right side of Kqd q' = kr
 *     template <class S> static void rhs_terms(const S *q, const S *u, const S *r,
 *         const S *p, S t, S *Kqd, S *qd, S *M, S *f, S *A, S *a);
 *         // kinematics as above, M, f, and A, a only when MV > 0
 *     template <class S> static void constraints(const S *q, const S *p, S t, S *fc);
 *     template <class S> static void constraint_jacobian(const S *q, const S *p, S t,
 *                                                        S *fc, S *Jc);
 *     template <class S> static void velocity_constraints(const S *q, const S *u,
 *                                                         const S *p, S t, S *fv);
 *     template <class S> static void velocity_constraint_matrix(const S *q, const S *p,
 *                                                               S t, S *A, S *b);
 *     template <class S> static void energy(const S *q, const S *u, const S *p, S t, S *E);
 *         // the last five: no-ops when the model has none (they are not called then)
 *     template <class S> static void lin_terms(const S *q, const S *u, const S *qd,
 *         const S *ud, const S *lam, const S *r, const S *p, S t, const LinOut<S> &o);
 *         // writes the Jacobian blocks the model has; the others are 0 x n
 *     // optional (velocity constraints with implicit kinematics): the term a of
 *     // the acceleration constraint at the solved q' (rhs_terms writes a at q' = 0),
 *     // and lin_terms writes o.Sqd = dS/dq'
 *     static constexpr bool HAS_ACCEL_TERMS = true;
 *     template <class S> static void accel_terms(const S *q, const S *u, const S *qd,
 *                                                const S *p, S t, S *a);
 *     // optional (outputs): NY > 0 outputs y and their Jacobians Yq (NY x NQ),
 *     // Yu (NY x NU), Yr (NY x NR, null when NR == 0)
 *     static constexpr int NY;
 *     template <class S> static void outputs(const S *q, const S *u, const S *r,
 *                                            const S *p, S t, S *y);
 *     template <class S> static void output_jacobian(const S *q, const S *u, const S *r,
 *                                                    const S *p, S t, S *Yq, S *Yu, S *Yr);
 *     // optional (auxiliary speeds, Kane's u_auxiliary): NA > 0 reaction forces
 *     static constexpr int NA;
 *     template <class S> static void auxiliary(const S *q, const S *u, const S *ud,
 *         const S *r, const S *p, S t, S *F, S *g);  // F reactions + g = 0, F NA x NA
 *   };
 *
 * The integration options and statistics are the generated header's structs
 * (rendered from gen/abi.py), template parameters of Runtime::advance and
 * Runtime::simulate, simulate_input and simulate_events, as are the input
 * and event descriptions (the fields used are listed at Runtime).
 *
 * The simulation engine (RK4 on the output grid; DOPRI5 and RODAS4 by
 * their error control with dense output; events) is the C runtime's
 * (gen_rt_simulate.c, gen_rt_integrate.c) with the same arithmetic in the
 * same order, and the tableaus are the C runtime's headers
 * (gen_rt_dopri5.h, gen_rt_rodas4.h) expanded over S: both backends take the
 * same steps.
 *
 * Error policy: every function is noexcept and returns an int status, 0
 * (OK) or a negative code of gen_rt_status.h (the C runtime's codes and
 * messages). Nothing throws, nothing allocates (fixed-size Eigen objects on
 * the stack; no Eigen::Dynamic), no mutable globals: every function is
 * reentrant.
 *
 * Factorizations (Eigen): LDLT for the symmetric positive definite systems
 * (mass matrix, reduced mass matrix T^T M T, A A^T, J J^T of the projection:
 * a matrix that is not positive definite reports ERR_SINGULAR),
 * PartialPivLU for the general ones (KKT matrix, dependent-coordinate and
 * dependent-speed partitions, kinematic matrix; a diagonal kinematic matrix
 * is divided out). A pivot below pivot_rtol * scale reports ERR_SINGULAR, as
 * the C runtime does.
 */
#ifndef GEN_RT_EIGEN_HPP
#define GEN_RT_EIGEN_HPP

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>

#include "gen_rt_dopri5.h"
#include "gen_rt_rodas4.h"
#include "gen_rt_expm.hpp"
#include "gen_rt_status.h"

#if !EIGEN_VERSION_AT_LEAST(3, 4, 0)
#error "gen_rt_eigen.hpp needs Eigen 3.4 or later"
#endif

namespace gen_rt {

// --------------------------------------------------------------- status
#define GEN_RT_EIGEN_ENUM(name, value, text) name = value,
enum Status : int { GEN_RT_STATUS_TABLE(GEN_RT_EIGEN_ENUM) };
#undef GEN_RT_EIGEN_ENUM

/* The message of a status code (the C runtime's text). */
inline const char *status_message(int status) noexcept
{
    switch (status) {
#define GEN_RT_EIGEN_CASE(name, value, text) \
    case value: return text;
        GEN_RT_STATUS_TABLE(GEN_RT_EIGEN_CASE)
#undef GEN_RT_EIGEN_CASE
    default: return GEN_RT_STATUS_UNKNOWN;
    }
}

enum Method : int { METHOD_RK4 = 0, METHOD_DOPRI5 = 1, METHOD_RODAS4 = 2 };

/* How the accelerations are solved (Model::ACCEL). */
enum Accel : int { ACCEL_SPD = 0, ACCEL_PARTITIONED = 1, ACCEL_KKT = 2 };

// ---------------------------------------------------------------- types
// Row-major unless a column vector (Eigen requires that), so data() is row-major.
template <typename S, int R, int C>
using Mat = Eigen::Matrix<S, R, C, C == 1 ? Eigen::ColMajor : Eigen::RowMajor>;

/* Numerical thresholds per scalar type (the C runtime's values). */
template <typename S>
struct Tolerances {
    static constexpr bool single = std::is_same<S, float>::value;
    static constexpr S eps = std::numeric_limits<S>::epsilon();
    static constexpr S pivot_rtol = single ? S(1e-6) : S(1e-12);
    static constexpr S partition_cmax = single ? S(1e5) : S(1e9);
    static constexpr S diverged_abs = single ? S(1e15) : S(1e150); // GEN_RT_DIVERGED_ABS
};

/* A controller for simulate_input (the C runtime's gen_rt_controller_fn):
 * r holds the inputs so far and may be overwritten; nonzero stops the run
 * with ERR_CONTROLLER. */
template <typename S>
using ControllerFn = int (*)(void *ctx, S t, const S *x, S *r);
constexpr int HOLD_ZOH = 0, HOLD_LINEAR = 1;

/* The outputs of Model::lin_terms (row-major blocks; those the model does
 * not have are 0 x n and their pointers may be null). */
template <typename S>
struct LinOut {
    S *Kqd, *Ku, *M, *A, *Kq, *Rq, *Ru, *Rr, *Sq, *Su, *Vq, *Jc;
    S *Sqd; // MV x NQ, only with Model::HAS_ACCEL_TERMS (else null)
};

/* Model::HAS_ACCEL_TERMS, or false: the acceleration-constraint term a holds
 * q' (velocity constraints with implicit kinematics), and
 * Model::accel_terms(q, u, qd, p, t, a) gives it once q' is solved. */
template <class M, class = void>
struct AccelTerms {
    static constexpr bool value = false;
};
template <class M>
struct AccelTerms<M, std::void_t<decltype(M::HAS_ACCEL_TERMS)>> {
    static constexpr bool value = M::HAS_ACCEL_TERMS;
};

/* Model::NA, or 0 when the traits type has no auxiliary speeds. */
template <class M, class = void>
struct AuxiliaryCount {
    static constexpr int value = 0;
};
template <class M>
struct AuxiliaryCount<M, std::void_t<decltype(M::NA)>> {
    static constexpr int value = M::NA;
};

/* Model::NY (outputs y with Model::outputs and Model::output_jacobian), or 0. */
template <class M, class = void>
struct OutputCount {
    static constexpr int value = 0;
};
template <class M>
struct OutputCount<M, std::void_t<decltype(M::NY)>> {
    static constexpr int value = M::NY;
};

// ------------------------------------------------------------------ helpers
template <typename Derived>
inline bool finite(const Eigen::MatrixBase<Derived> &v) noexcept
{
    return v.allFinite();
}

template <typename S, typename std::enable_if<std::is_arithmetic<S>::value, int>::type = 0>
inline bool finite(S v) noexcept
{
    return v - v == S(0);
}

/* x = a^-1 b by partial-pivot LU; ERR_SINGULAR when a pivot is below
 * pivot_rtol * scale (scale <= 0: max |a_ij|), as gen_rt_lu_factor. A 1 x 1
 * system is a division (the same arithmetic; it also keeps GCC 12's
 * -Warray-bounds quiet about Eigen's row swaps in 1 x 1 permutations). */
template <typename S, int N, int K, int O1, int O2>
inline int lu_solve(const Eigen::Matrix<S, N, N> &a, S scale,
                    const Eigen::Matrix<S, N, K, O1> &b, Eigen::Matrix<S, N, K, O2> &x) noexcept
{
    if (!(scale > 0)) scale = a.cwiseAbs().maxCoeff();
    if (!(scale > 0)) return ERR_SINGULAR;
    const S tol = Tolerances<S>::pivot_rtol * scale;
    if constexpr (N == 1) {
        if (!(std::abs(a(0, 0)) > tol)) return ERR_SINGULAR; // also NaN
        x = b / a(0, 0);
    } else {
        const Eigen::PartialPivLU<Eigen::Matrix<S, N, N>> lu(a);
        for (int k = 0; k < N; ++k)
            if (!(std::abs(lu.matrixLU()(k, k)) > tol)) return ERR_SINGULAR; // also NaN
        x = lu.solve(b);
    }
    return OK;
}

/* x = a^-1 b for a symmetric positive definite a, by LDLT; ERR_SINGULAR when
 * a is not positive definite or a pivot is below pivot_rtol * max diag. */
template <typename S, int N, int K, int O1, int O2>
inline int spd_solve(const Eigen::Matrix<S, N, N> &a, const Eigen::Matrix<S, N, K, O1> &b,
                     Eigen::Matrix<S, N, K, O2> &x) noexcept
{
    const S tol = Tolerances<S>::pivot_rtol * a.diagonal().cwiseAbs().maxCoeff();
    if constexpr (N == 1) {
        if (!(a(0, 0) > tol)) return ERR_SINGULAR;
        x = b / a(0, 0);
    } else {
        const Eigen::LDLT<Eigen::Matrix<S, N, N>> ldlt(a);
        if (ldlt.info() != Eigen::Success) return ERR_SINGULAR;
        for (int k = 0; k < N; ++k)
            if (!(ldlt.vectorD()[k] > tol)) return ERR_SINGULAR;
        x = ldlt.solve(b);
    }
    return OK;
}

/* Minimum-norm correction x -= J^T (J J^T)^-1 res (LDLT of J J^T). */
template <typename S, int M, int N>
inline int min_norm_correct(const Mat<S, M, N> &J, const Mat<S, M, 1> &res,
                            Mat<S, N, 1> &x) noexcept
{
    const Eigen::Matrix<S, M, M> G = J * J.transpose();
    Mat<S, M, 1> y;
    const int st = spd_solve(G, res, y);
    if (st) return st;
    x -= J.transpose() * y;
    return OK;
}

// ------------------------------------------------------------ integrators
// The pieces of the simulation engine, each the C runtime's function of the
// same name (gen_rt_integrate.c) with the same arithmetic in the same
// order, so that both backends take the same steps.

/* the C runtime's max, min and abs (a NaN argument: the other one) */
template <typename S>
inline S rt_max(S a, S b) noexcept
{
    return a > b ? a : b;
}
template <typename S>
inline S rt_min(S a, S b) noexcept
{
    return a < b ? a : b;
}
template <typename S>
inline S rt_abs(S a) noexcept
{
    return a < 0 ? -a : a;
}

/* Classic fourth-order Runge-Kutta step (gen_rt_rk4_step); f(t, x, dx)
 * returns a status; x unchanged on failure; k1 = f(t, x) on return. */
template <typename S, int N, typename F>
inline int rk4_step(F &&f, S t, S h, Mat<S, N, 1> &x, Mat<S, N, 1> &k1) noexcept
{
    Mat<S, N, 1> k2, k3, k4, y;
    const S h2 = S(0.5) * h;
    int st;
    if ((st = f(t, x, k1))) return st;
    y = x + h2 * k1;
    if ((st = f(t + h2, y, k2))) return st;
    y = x + h2 * k2;
    if ((st = f(t + h2, y, k3))) return st;
    y = x + h * k3;
    if ((st = f(t + h, y, k4))) return st;
    y = x + (h / S(6)) * (k1 + S(2) * (k2 + k3) + k4);
    if (!finite(y)) return ERR_DIVERGED; // finite stages, overflow
    x = y;
    return OK;
}

template <typename S, int N, typename F>
inline int rk4_step(F &&f, S t, S h, Mat<S, N, 1> &x) noexcept
{
    Mat<S, N, 1> k1;
    return rk4_step<S, N>(f, t, h, x, k1);
}

/* The Dormand-Prince 5(4) tableau of gen_rt_dopri5.h in the scalar type. */
template <typename S>
struct Dopri5Tableau {
#define GEN_RT_EIGEN_COEF(name, num, den) static constexpr S name = S(num) / S(den);
    GEN_RT_DOPRI5_TABLEAU(GEN_RT_EIGEN_COEF)
#undef GEN_RT_EIGEN_COEF
};

/* The RODAS4 tableau of gen_rt_rodas4.h in the scalar type. */
template <typename S>
struct Rodas4Tableau {
#define GEN_RT_EIGEN_COEF(name, value) static constexpr S name = S(value);
    GEN_RT_RODAS4_TABLEAU(GEN_RT_EIGEN_COEF)
#undef GEN_RT_EIGEN_COEF
};

/* The scaled RMS norm of an error estimate d (gen_rt_err_norm):
 * sqrt(mean((d_i / (atol + rtol max(|x_i|, |xnew_i|)))^2)); NaN propagates. */
template <typename S, int N>
inline S err_norm(const Mat<S, N, 1> &x, const Mat<S, N, 1> &xnew, const Mat<S, N, 1> &d, S rtol,
                  S atol) noexcept
{
    S s = 0;
    for (int i = 0; i < N; ++i) {
        const S sc = atol + rtol * rt_max(std::abs(x[i]), std::abs(xnew[i]));
        const S r = d[i] / sc;
        s += r * r;
    }
    return std::sqrt(s / static_cast<S>(N));
}

/* One DOPRI5 trial step of size h from (t, x) (gen_rt_dopri5_trial): k[0]
 * holds f(t, x) on entry, k[1..6] the other stages on return (k[6] =
 * f(t + h, ynew)); y is scratch; err the error norm. */
template <typename S, int N, typename F>
inline int dopri5_trial(F &&f, S t, S h, const Mat<S, N, 1> &x, S rtol, S atol,
                        Mat<S, N, 1> (&k)[7], Mat<S, N, 1> &y, Mat<S, N, 1> &ynew,
                        S &err) noexcept
{
    using T = Dopri5Tableau<S>;
    const Mat<S, N, 1> &k1 = k[0];
    Mat<S, N, 1> &k2 = k[1], &k3 = k[2], &k4 = k[3], &k5 = k[4], &k6 = k[5], &k7 = k[6];
    int st;
    for (int i = 0; i < N; ++i) y[i] = x[i] + h * T::A21 * k1[i];
    if ((st = f(t + T::C2 * h, y, k2))) return st;
    for (int i = 0; i < N; ++i) y[i] = x[i] + h * (T::A31 * k1[i] + T::A32 * k2[i]);
    if ((st = f(t + T::C3 * h, y, k3))) return st;
    for (int i = 0; i < N; ++i)
        y[i] = x[i] + h * (T::A41 * k1[i] + T::A42 * k2[i] + T::A43 * k3[i]);
    if ((st = f(t + T::C4 * h, y, k4))) return st;
    for (int i = 0; i < N; ++i)
        y[i] = x[i] + h * (T::A51 * k1[i] + T::A52 * k2[i] + T::A53 * k3[i] + T::A54 * k4[i]);
    if ((st = f(t + T::C5 * h, y, k5))) return st;
    for (int i = 0; i < N; ++i)
        y[i] = x[i] + h * (T::A61 * k1[i] + T::A62 * k2[i] + T::A63 * k3[i] + T::A64 * k4[i] +
                           T::A65 * k5[i]);
    if ((st = f(t + h, y, k6))) return st;
    for (int i = 0; i < N; ++i)
        ynew[i] = x[i] + h * (T::B1 * k1[i] + T::B3 * k3[i] + T::B4 * k4[i] + T::B5 * k5[i] +
                              T::B6 * k6[i]);
    if (!finite(ynew)) return ERR_DIVERGED; // finite stages, overflow
    if ((st = f(t + h, ynew, k7))) return st;
    for (int i = 0; i < N; ++i)
        y[i] = h * (T::E1 * k1[i] + T::E3 * k3[i] + T::E4 * k4[i] + T::E5 * k5[i] +
                    T::E6 * k6[i] + T::E7 * k7[i]);
    err = err_norm<S, N>(x, ynew, y, rtol, atol);
    return OK;
}

/* The continuous extension of order 4 of that step at t + theta h
 * (gen_rt_dopri5_dense; exact at theta = 0 and 1). */
template <typename S, int N>
inline void dopri5_dense(S h, S theta, const Mat<S, N, 1> &x, const Mat<S, N, 1> &ynew,
                         const Mat<S, N, 1> (&k)[7], Mat<S, N, 1> &out) noexcept
{
    using T = Dopri5Tableau<S>;
    const Mat<S, N, 1> &k1 = k[0], &k3 = k[2], &k4 = k[3], &k5 = k[4], &k6 = k[5], &k7 = k[6];
    const S th1 = S(1.0) - theta;
    for (int i = 0; i < N; ++i) {
        const S ydiff = ynew[i] - x[i], bspl = h * k1[i] - ydiff;
        const S c4 = ydiff - h * k7[i] - bspl;
        const S c5 = h * (T::D1 * k1[i] + T::D3 * k3[i] + T::D4 * k4[i] + T::D5 * k5[i] +
                          T::D6 * k6[i] + T::D7 * k7[i]);
        out[i] = x[i] + theta * (ydiff + th1 * (bspl + theta * (c4 + th1 * c5)));
    }
}

/* The cubic Hermite interpolant of a step (x0, f0 at t; x1, f1 at t + h) at
 * t + theta h (gen_rt_hermite): the dense output of RK4 and RODAS4. */
template <typename S, int N>
inline void hermite(S h, S theta, const Mat<S, N, 1> &x0, const Mat<S, N, 1> &f0,
                    const Mat<S, N, 1> &x1, const Mat<S, N, 1> &f1, Mat<S, N, 1> &out) noexcept
{
    const S th1 = S(1.0) - theta;
    for (int i = 0; i < N; ++i) {
        const S ydiff = x1[i] - x0[i], bspl = h * f0[i] - ydiff;
        const S c4 = ydiff - h * f1[i] - bspl;
        out[i] = x0[i] + theta * (ydiff + th1 * (bspl + theta * c4));
    }
}

/* LU with partial pivoting in place, and its solve: the C runtime's
 * gen_rt_lu_factor (scale = max |a_ij|) and gen_rt_lu_solve (one right-hand
 * side), the same arithmetic (RODAS4's iteration matrix, so that both
 * backends' steps agree). */
template <typename S, int N>
inline int lu_factor_inplace(Mat<S, N, N> &a, int (&piv)[N]) noexcept
{
    S scale = 0;
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) {
            const S v = rt_abs(a(i, j));
            if (v > scale) scale = v;
        }
    if (!(scale > 0)) return ERR_SINGULAR;
    const S tol = Tolerances<S>::pivot_rtol * scale;
    for (int k = 0; k < N; ++k) {
        int p = k;
        S best = rt_abs(a(k, k));
        for (int i = k + 1; i < N; ++i) {
            const S v = rt_abs(a(i, k));
            if (v > best) {
                best = v;
                p = i;
            }
        }
        piv[k] = p;
        if (!(best > tol)) return ERR_SINGULAR; // also catches NaN
        if (p != k)
            for (int j = 0; j < N; ++j) std::swap(a(k, j), a(p, j));
        for (int i = k + 1; i < N; ++i) {
            const S l = a(i, k) / a(k, k);
            a(i, k) = l;
            if (l != 0)
                for (int j = k + 1; j < N; ++j) a(i, j) -= l * a(k, j);
        }
    }
    return OK;
}

template <typename S, int N>
inline void lu_solve_inplace(const Mat<S, N, N> &lu, const int (&piv)[N], Mat<S, N, 1> &b) noexcept
{
    for (int k = 0; k < N; ++k)
        if (piv[k] != k) std::swap(b[k], b[piv[k]]);
    for (int i = 0; i < N; ++i) // forward: unit lower
        for (int k = 0; k < i; ++k) {
            const S l = lu(i, k);
            if (l != 0) b[i] -= l * b[k];
        }
    for (int i = N - 1; i >= 0; --i) { // backward: upper
        for (int k = i + 1; k < N; ++k) {
            const S uik = lu(i, k);
            if (uik != 0) b[i] -= uik * b[k];
        }
        b[i] /= lu(i, i);
    }
}

/* The scratch of one RODAS4 trial step. */
template <typename S, int N>
struct Rodas4Work {
    Mat<S, N, 1> K[6], y;
    Mat<S, N, N> G;
    int piv[N];
};

/* One RODAS4 trial step (gen_rt_rodas4.h) from (t, x) with f0 = f(t, x),
 * the Jacobian J = df/dx and df/dt (gen_rt_rodas4_trial): ynew and the
 * error norm err; ERR_SINGULAR with err < 0 when I/(h gamma) - J is
 * singular. Five evaluations of f. */
template <typename S, int N, typename F>
inline int rodas4_trial(F &&f, S t, S h, const Mat<S, N, 1> &x, const Mat<S, N, 1> &f0,
                        const Mat<S, N, N> &J, const Mat<S, N, 1> &dfdt, S rtol, S atol,
                        Rodas4Work<S, N> &w, Mat<S, N, 1> &ynew, S &err) noexcept
{
    using T = Rodas4Tableau<S>;
    Mat<S, N, 1> &K1 = w.K[0], &K2 = w.K[1], &K3 = w.K[2], &K4 = w.K[3], &K5 = w.K[4],
                 &K6 = w.K[5], &y = w.y;
    const S hg = S(1.0) / (h * T::GAMMA), ih = S(1.0) / h;
    int st;
    // G = I / (h gamma) - J, factored once for the six stages
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) w.G(i, j) = (i == j ? hg : S(0)) - J(i, j);
    err = -1; // marks a failure of G's factorization
    if ((st = lu_factor_inplace<S, N>(w.G, w.piv))) return st;
    err = 0;
    for (int i = 0; i < N; ++i) K1[i] = f0[i] + h * T::GAMMA * dfdt[i];
    lu_solve_inplace<S, N>(w.G, w.piv, K1);
    for (int i = 0; i < N; ++i) y[i] = x[i] + T::A21 * K1[i];
    if ((st = f(t + T::ALPHA2 * h, y, K2))) return st;
    for (int i = 0; i < N; ++i) K2[i] += ih * (T::C21 * K1[i]) + h * T::GAMMA2 * dfdt[i];
    lu_solve_inplace<S, N>(w.G, w.piv, K2);
    for (int i = 0; i < N; ++i) y[i] = x[i] + T::A31 * K1[i] + T::A32 * K2[i];
    if ((st = f(t + T::ALPHA3 * h, y, K3))) return st;
    for (int i = 0; i < N; ++i)
        K3[i] += ih * (T::C31 * K1[i] + T::C32 * K2[i]) + h * T::GAMMA3 * dfdt[i];
    lu_solve_inplace<S, N>(w.G, w.piv, K3);
    for (int i = 0; i < N; ++i) y[i] = x[i] + T::A41 * K1[i] + T::A42 * K2[i] + T::A43 * K3[i];
    if ((st = f(t + T::ALPHA4 * h, y, K4))) return st;
    for (int i = 0; i < N; ++i)
        K4[i] += ih * (T::C41 * K1[i] + T::C42 * K2[i] + T::C43 * K3[i]) +
                 h * T::GAMMA4 * dfdt[i];
    lu_solve_inplace<S, N>(w.G, w.piv, K4);
    for (int i = 0; i < N; ++i)
        y[i] = x[i] + T::A51 * K1[i] + T::A52 * K2[i] + T::A53 * K3[i] + T::A54 * K4[i];
    if ((st = f(t + h, y, K5))) return st;
    for (int i = 0; i < N; ++i)
        K5[i] += ih * (T::C51 * K1[i] + T::C52 * K2[i] + T::C53 * K3[i] + T::C54 * K4[i]);
    lu_solve_inplace<S, N>(w.G, w.piv, K5);
    for (int i = 0; i < N; ++i) y[i] += K5[i]; // Y_6 = Y_5 + K_5
    if ((st = f(t + h, y, K6))) return st;
    for (int i = 0; i < N; ++i)
        K6[i] += ih * (T::C61 * K1[i] + T::C62 * K2[i] + T::C63 * K3[i] + T::C64 * K4[i] +
                       T::C65 * K5[i]);
    lu_solve_inplace<S, N>(w.G, w.piv, K6);
    for (int i = 0; i < N; ++i) ynew[i] = y[i] + K6[i];
    if (!finite(ynew)) return ERR_DIVERGED;
    err = err_norm<S, N>(x, ynew, K6, rtol, atol);
    return OK;
}

/* An input description with the fields the runtime reads (gen_rt.h,
 * gen_rt_input; the generated Input<S> is another): simulate and advance
 * run without one (a constant r). */
template <typename S>
struct BasicInput {
    const S *r = nullptr;
    int n_table = 0;
    const S *t_table = nullptr, *r_table = nullptr;
    int hold = HOLD_ZOH;
    const S *K = nullptr, *x_op = nullptr;
    ControllerFn<S> controller = nullptr;
    void *ctx = nullptr;
    S period = S(0);
};

/* An event description with the fields the runtime reads (gen_rt.h,
 * gen_rt_events; the generated Events<S> is another). */
template <typename S>
struct BasicEvents {
    int n = 0;
    const int *which = nullptr, *direction = nullptr, *terminal = nullptr;
    const S *level = nullptr;
    int capacity = 0;
    int *log_which = nullptr;
    S *log_t = nullptr, *log_x = nullptr;
};

// ------------------------------------------------------------- the runtime

/* Every model-agnostic algorithm over a model traits type (see the top of
 * this file), for the scalar type S. The generated header's typed API
 * forwards here; the names and semantics are that API's.
 *
 * advance and the simulate functions take the integration options and
 * statistics as template parameters (the generated header renders its
 * SimOptions and SimStats from gen/abi.py); the fields used:
 *   Opts:  int method (METHOD_RK4, METHOD_DOPRI5, METHOD_RODAS4), project
 *          (nonzero: project onto the constraints after each step), S rtol,
 *          atol, h_init, h_min, h_max, long max_steps, S proj_tol, int
 *          proj_max_iter, every, final_only, const int *cancel (the
 *          caller's flag, read before every step: nonzero stops the run
 *          with ERR_CANCELLED; nullptr: never);
 *   Stats: long n_accepted, n_rejected, n_rhs, n_jac, int n_out, n_events,
 *          terminal, S t_last, h_next, State x_last; a value-initialized
 *          Stats is all zeros but terminal (-1: no terminal event).
 * The inputs of simulate_input and simulate_events are any struct with the
 * fields of BasicInput, their events any with those of BasicEvents.
 *
 * The simulation engine is gen_rt_simulate.c's (the C runtime), ported step
 * for step with the same arithmetic in the same order: RK4 on the output
 * grid; DOPRI5 (FSAL, continuous extension) and RODAS4 (the model's
 * Jacobian) stepping by their error control alone (scaled RMS norm) and
 * writing the rows from their dense output; events located on it. Only the
 * model evaluations (right-hand side, Jacobian, projection: Eigen's
 * factorizations) round differently from the C backend's. */
template <class Model, class S>
struct Runtime {
    static constexpr int NQ = Model::NQ, NU = Model::NU, NX = Model::NX, NR = Model::NR,
                         NP = Model::NP, MC = Model::MC, MV = Model::MV, NS = Model::NS,
                         NQI = Model::NQI, NUI = Model::NUI;
    static_assert(NX == NQ + NU && NQI == NQ - MC && NUI == NU - MV && NS == NQI + NUI,
                  "inconsistent model sizes");
    static_assert((Model::ACCEL == ACCEL_SPD) == (MV == 0),
                  "ACCEL_SPD exactly when there are no velocity constraints");

    using Tol = Tolerances<S>;
    using State = Mat<S, NX, 1>;
    using Coords = Mat<S, NQ, 1>;
    using Speeds = Mat<S, NU, 1>;
    using Inputs = Mat<S, NR, 1>;
    using Params = Mat<S, NP, 1>;
    using Multipliers = Mat<S, MV, 1>;
    using ConfigResiduals = Mat<S, MC, 1>;
    using MassMatrix = Mat<S, NU, NU>;
    using ConstraintJacobian = Mat<S, MC, NQ>;
    using VelocityMatrix = Mat<S, MV, NU>;
    using StateMatrix = Mat<S, NS, NS>;
    using InputMatrix = Mat<S, NS, NR>;

    // ------------------------------------------------------------ internals

    /* q' from the kinematic equations */
    static int qdot_from(const Coords &q, const Speeds &u, const Params &p, S t,
                         Coords &qdot) noexcept
    {
        if constexpr (Model::EXPLICIT_KINEMATICS) {
            Model::kinematics(q.data(), u.data(), p.data(), t, static_cast<S *>(nullptr),
                              qdot.data());
            return finite(qdot) ? OK : ERR_SINGULAR_KINEMATICS;
        } else {
            Mat<S, NQ, NQ> Kqd;
            Coords kr;
            Model::kinematics(q.data(), u.data(), p.data(), t, Kqd.data(), kr.data());
            if (!finite(Kqd) || !finite(kr)) return ERR_SINGULAR_KINEMATICS;
            return lu_solve<S, NQ>(Kqd, S(0), kr, qdot) ? ERR_SINGULAR_KINEMATICS : OK;
        }
    }

    /* Multiplier form: [M, -A^T; A, 0] [u'; lam] = [f; -a] (partial-pivot LU). */
    static int accel_kkt(const MassMatrix &M, const Speeds &f, const VelocityMatrix &A,
                         const Multipliers &a, Speeds &ud, Multipliers *lam) noexcept
    {
        Eigen::Matrix<S, NU + MV, NU + MV> K;
        Eigen::Matrix<S, NU + MV, 1> z;
        K.template topLeftCorner<NU, NU>() = M;
        K.template topRightCorner<NU, MV>() = -A.transpose();
        K.template bottomLeftCorner<MV, NU>() = A;
        K.template bottomRightCorner<MV, MV>().setZero();
        z.template head<NU>() = f;
        z.template tail<MV>() = -a;
        Eigen::Matrix<S, NU + MV, 1> sol;
        const int st = lu_solve(K, S(0), z, sol);
        if (st) return st;
        if (!finite(sol)) return ERR_SINGULAR;
        ud = sol.template head<NU>();
        if (lam) *lam = sol.template tail<MV>();
        return OK;
    }

    /* Kane form: dependent accelerations eliminated through the partition
     * (A_dep, partial-pivot LU), reduced equations T^T M T ui' = T^T (f - M c)
     * (LDLT), multipliers from A A^T lam = A (M u' - f) (LDLT). */
    static int accel_partitioned(const MassMatrix &M, const Speeds &f, const VelocityMatrix &A,
                                 const Multipliers &a, Speeds &ud, Multipliers *lam) noexcept
    {
        Eigen::Matrix<S, MV, MV> Ad;
        Eigen::Matrix<S, MV, NUI + 1> C;
        for (int i = 0; i < MV; ++i) {
            for (int j = 0; j < MV; ++j) Ad(i, j) = A(i, Model::u_dep[j]);
            for (int k = 0; k < NUI; ++k) C(i, k) = -A(i, Model::u_ind[k]);
            C(i, NUI) = -a[i];
        }
        Eigen::Matrix<S, MV, NUI + 1> Cs;
        int st = lu_solve(Ad, A.cwiseAbs().maxCoeff(), C, Cs);
        if (st) return st;
        if (!finite(Cs)) return ERR_SINGULAR;
        if ((Cs.template leftCols<NUI>().cwiseAbs().array() > Tol::partition_cmax).any())
            return ERR_SINGULAR;
        Mat<S, NU, NUI> T = Mat<S, NU, NUI>::Zero();
        Speeds cf = Speeds::Zero();
        for (int k = 0; k < NUI; ++k) T(Model::u_ind[k], k) = S(1);
        for (int j = 0; j < MV; ++j) {
            for (int k = 0; k < NUI; ++k) T(Model::u_dep[j], k) = Cs(j, k);
            cf[Model::u_dep[j]] = Cs(j, NUI);
        }
        if constexpr (NUI > 0) {
            const Eigen::Matrix<S, NUI, NUI> Mr = T.transpose() * M * T;
            const Mat<S, NUI, 1> fr = T.transpose() * (f - M * cf);
            Mat<S, NUI, 1> ur;
            st = spd_solve<S, NUI, 1>(Mr, fr, ur);
            if (st) return st;
            ud = T * ur + cf;
        } else {
            ud = cf;
        }
        if (!finite(ud)) return ERR_SINGULAR;
        if (lam) {
            const Eigen::Matrix<S, MV, MV> AAt = A * A.transpose();
            const Multipliers y = A * (M * ud - f);
            st = spd_solve<S, MV, 1>(AAt, y, *lam);
            if (st) return st;
            if (!finite(*lam)) return ERR_SINGULAR; /* as the C runtime (fuzzer finding) */
        }
        return OK;
    }

    /* x' and (when lam != nullptr) the multipliers; inputs already checked */
    static int rhs_unchecked(S t, const State &x, const Inputs &r, const Params &p, State &dxdt,
                             Multipliers *lam) noexcept
    {
        const int st = rhs_impl(t, x, r, p, dxdt, lam);
        // a failure at a state that has run away is divergence (as gen_rt_model_rhs)
        if (st && (!finite(x) || x.cwiseAbs().maxCoeff() > Tolerances<S>::diverged_abs))
            return ERR_DIVERGED;
        return st;
    }

    static int rhs_impl(S t, const State &x, const Inputs &r, const Params &p, State &dxdt,
                        Multipliers *lam) noexcept
    {
        const S *q = x.data(), *u = x.data() + NQ;
        MassMatrix M;
        Speeds f, ud;
        Coords qd;
        VelocityMatrix A; // 0 x NU without velocity constraints
        Multipliers a;
        int st;
        if constexpr (Model::EXPLICIT_KINEMATICS) {
            Model::rhs_terms(q, u, r.data(), p.data(), t, static_cast<S *>(nullptr), qd.data(),
                             M.data(), f.data(), A.data(), a.data());
            if (!finite(qd)) return ERR_SINGULAR_KINEMATICS;
        } else {
            Mat<S, NQ, NQ> Kqd;
            Coords kr;
            Model::rhs_terms(q, u, r.data(), p.data(), t, Kqd.data(), kr.data(), M.data(),
                             f.data(), A.data(), a.data());
            if (!finite(Kqd) || !finite(kr)) return ERR_SINGULAR_KINEMATICS;
            if (lu_solve<S, NQ>(Kqd, S(0), kr, qd)) return ERR_SINGULAR_KINEMATICS;
        }
        if constexpr (MV > 0 && AccelTerms<Model>::value)
            Model::accel_terms(q, u, qd.data(), p.data(), t, a.data());
        if (!finite(M) || !finite(f)) return ERR_NONFINITE_MODEL;
        if constexpr (Model::ACCEL == ACCEL_SPD) {
            (void)lam;
            st = spd_solve<S, NU, 1>(M, f, ud);
            if (!st && !finite(ud)) st = ERR_SINGULAR;
        } else {
            if (!finite(A) || !finite(a)) return ERR_NONFINITE_MODEL;
            if constexpr (Model::ACCEL == ACCEL_PARTITIONED)
                st = accel_partitioned(M, f, A, a, ud, lam);
            else
                st = accel_kkt(M, f, A, a, ud, lam);
        }
        if (st) return st;
        dxdt.template head<NQ>() = qd;
        dxdt.template tail<NU>() = ud;
        return OK;
    }

    static int project_unchecked(S t, const Params &p, S tol, int max_iter, State &x) noexcept
    {
        if constexpr (MC > 0 || MV > 0) {
            State xc = x;
            if constexpr (MC > 0) {
                if (max_iter <= 0) max_iter = 10;
                if (!(tol > 0)) tol = 16 * Tol::eps;
                bool converged = false;
                for (int it = 0; it < max_iter; ++it) {
                    ConfigResiduals fc;
                    ConstraintJacobian Jc;
                    Model::constraint_jacobian(xc.data(), p.data(), t, fc.data(), Jc.data());
                    if (!finite(fc) || !finite(Jc)) return ERR_NONFINITE_MODEL;
                    Coords q = xc.template head<NQ>();
                    const Coords q0 = q;
                    const int st = min_norm_correct<S, MC, NQ>(Jc, fc, q);
                    if (st) return st;
                    xc.template head<NQ>() = q;
                    const S dmax = (q - q0).cwiseAbs().maxCoeff();
                    if (!(dmax == dmax)) return ERR_NONFINITE_MODEL;
                    if (dmax <= tol * (1 + q.cwiseAbs().maxCoeff())) {
                        converged = true;
                        break;
                    }
                }
                if (!converged) return ERR_NO_CONVERGENCE;
            } else {
                (void)tol;
                (void)max_iter;
            }
            if constexpr (MV > 0) {
                VelocityMatrix A;
                Multipliers b;
                Model::velocity_constraint_matrix(xc.data(), p.data(), t, A.data(), b.data());
                if (!finite(A) || !finite(b)) return ERR_NONFINITE_MODEL;
                Speeds u = xc.template tail<NU>();
                const Multipliers res = A * u + b;
                const int st = min_norm_correct<S, MV, NU>(A, res, u);
                if (st) return st;
                xc.template tail<NU>() = u;
            }
            if (!finite(xc)) return ERR_NONFINITE_MODEL;
            x = xc;
            return OK;
        } else {
            (void)t, (void)p, (void)tol, (void)max_iter, (void)x;
            return OK;
        }
    }

    // ------------------------------------------------------------ evaluation

    static int eval_mass_matrix(const Coords &q, const Params &p, S t, MassMatrix &M) noexcept
    {
        if (!finite(q) || !finite(p) || !finite(t)) return ERR_NONFINITE_INPUT;
        Model::mass_matrix(q.data(), p.data(), t, M.data());
        return finite(M) ? OK : ERR_NONFINITE_MODEL;
    }

    static int eval_forcing(const Coords &q, const Speeds &u, const Inputs &r, const Params &p,
                            S t, Speeds &f) noexcept
    {
        if (!finite(q) || !finite(u) || !finite(r) || !finite(p) || !finite(t))
            return ERR_NONFINITE_INPUT;
        Model::forcing(q.data(), u.data(), r.data(), p.data(), t, f.data());
        return finite(f) ? OK : ERR_NONFINITE_MODEL;
    }

    static int eval_kinematics(const Coords &q, const Speeds &u, const Params &p, S t,
                               Coords &qdot) noexcept
    {
        if (!finite(q) || !finite(u) || !finite(p) || !finite(t)) return ERR_NONFINITE_INPUT;
        return qdot_from(q, u, p, t, qdot);
    }

    static int eval_constraints(const Coords &q, const Params &p, S t,
                                ConfigResiduals &fc) noexcept
    {
        if (!finite(q) || !finite(p) || !finite(t)) return ERR_NONFINITE_INPUT;
        if constexpr (MC > 0) {
            Model::constraints(q.data(), p.data(), t, fc.data());
            return finite(fc) ? OK : ERR_NONFINITE_MODEL;
        } else {
            (void)fc;
            return OK;
        }
    }

    static int eval_constraint_jacobian(const Coords &q, const Params &p, S t,
                                        ConstraintJacobian &Jc) noexcept
    {
        if (!finite(q) || !finite(p) || !finite(t)) return ERR_NONFINITE_INPUT;
        if constexpr (MC > 0) {
            ConfigResiduals fc;
            Model::constraint_jacobian(q.data(), p.data(), t, fc.data(), Jc.data());
            return finite(Jc) ? OK : ERR_NONFINITE_MODEL;
        } else {
            (void)Jc;
            return OK;
        }
    }

    static int eval_velocity_constraints(const Coords &q, const Speeds &u, const Params &p, S t,
                                         Multipliers &fv) noexcept
    {
        if (!finite(q) || !finite(u) || !finite(p) || !finite(t)) return ERR_NONFINITE_INPUT;
        if constexpr (MV > 0) {
            Model::velocity_constraints(q.data(), u.data(), p.data(), t, fv.data());
            return finite(fv) ? OK : ERR_NONFINITE_MODEL;
        } else {
            (void)fv;
            return OK;
        }
    }

    static int eval_velocity_constraint_matrix(const Coords &q, const Params &p, S t,
                                               VelocityMatrix &A, Multipliers &b) noexcept
    {
        if (!finite(q) || !finite(p) || !finite(t)) return ERR_NONFINITE_INPUT;
        if constexpr (MV > 0) {
            Model::velocity_constraint_matrix(q.data(), p.data(), t, A.data(), b.data());
            return (finite(A) && finite(b)) ? OK : ERR_NONFINITE_MODEL;
        } else {
            (void)A, (void)b;
            return OK;
        }
    }

    static int eval_energy(const Coords &q, const Speeds &u, const Params &p, S t, S &E) noexcept
    {
        if (!finite(q) || !finite(u) || !finite(p) || !finite(t)) return ERR_NONFINITE_INPUT;
        if constexpr (Model::HAS_ENERGY) {
            Model::energy(q.data(), u.data(), p.data(), t, &E);
            return finite(E) ? OK : ERR_NONFINITE_MODEL;
        } else {
            E = S(0);
            return ERR_BAD_ARG; // the model was generated without an energy expression
        }
    }

    static int eval_rhs(S t, const State &x, const Inputs &r, const Params &p, State &dxdt,
                        Multipliers *lam) noexcept
    {
        if (!finite(t) || !finite(x) || !finite(r) || !finite(p)) return ERR_NONFINITE_INPUT;
        return rhs_unchecked(t, x, r, p, dxdt, lam);
    }

    /* The NA reaction forces of the auxiliary speeds (gen_rt_model_eval_auxiliary_forces):
     * u' from the right-hand side, then F reactions = -g (partial-pivot LU); OK and
     * nothing written when the model has none. */
    static constexpr int NA = AuxiliaryCount<Model>::value;
    using AuxiliaryForces = Mat<S, NA, 1>;
    static int eval_auxiliary_forces(S t, const State &x, const Inputs &r, const Params &p,
                                     AuxiliaryForces &F) noexcept
    {
        if (!finite(t) || !finite(x) || !finite(r) || !finite(p)) return ERR_NONFINITE_INPUT;
        if constexpr (NA > 0) {
            State dx;
            const int st = rhs_unchecked(t, x, r, p, dx, nullptr);
            if (st) return st;
            Mat<S, NA, NA> Fr; // row-major, as the kernel writes it
            AuxiliaryForces g, sol;
            Model::auxiliary(x.data(), x.data() + NQ, dx.data() + NQ, r.data(), p.data(), t,
                             Fr.data(), g.data());
            if (!finite(Fr) || !finite(g)) return ERR_NONFINITE_MODEL;
            const Eigen::Matrix<S, NA, NA> Fm = Fr;
            const AuxiliaryForces rhs = -g;
            /* a singular F (finite): the reactions are not determined here */
            if (lu_solve<S, NA>(Fm, S(0), rhs, sol) || !finite(sol))
                return ERR_SINGULAR_REACTIONS;
            F = sol;
        } else {
            (void)F;
        }
        return OK;
    }

    // ------------------------------------------------- constraint manifold

    static int project(S t, const Params &p, S tol, int max_iter, State &x) noexcept
    {
        if (!finite(t) || !finite(p) || !finite(x)) return ERR_NONFINITE_INPUT;
        return project_unchecked(t, p, tol, max_iter, x);
    }

    static int consistent_state(S t, const Params &p, S tol, int max_iter, State &x) noexcept
    {
        if (!finite(t) || !finite(p) || !finite(x)) return ERR_NONFINITE_INPUT;
        if constexpr (MC > 0 || MV > 0) {
            State xc = x;
            int st;
            if constexpr (MC > 0) {
                if (max_iter <= 0) max_iter = 50;
                if (!(tol > 0)) tol = 16 * Tol::eps;
                bool converged = false;
                for (int it = 0; it < max_iter; ++it) {
                    ConfigResiduals fc;
                    ConstraintJacobian Jc;
                    Eigen::Matrix<S, MC, MC> Jd;
                    Model::constraint_jacobian(xc.data(), p.data(), t, fc.data(), Jc.data());
                    if (!finite(fc) || !finite(Jc)) return ERR_NONFINITE_MODEL;
                    for (int i = 0; i < MC; ++i)
                        for (int j = 0; j < MC; ++j) Jd(i, j) = Jc(i, Model::q_dep[j]);
                    ConfigResiduals dq;
                    st = lu_solve(Jd, Jc.cwiseAbs().maxCoeff(), fc, dq);
                    if (st) return st;
                    S dmax = 0;
                    for (int j = 0; j < MC; ++j) {
                        const S d = std::abs(dq[j]);
                        xc[Model::q_dep[j]] -= dq[j];
                        if (d > dmax) dmax = d;
                    }
                    if (!(dmax == dmax) || !finite(dq)) return ERR_NONFINITE_MODEL;
                    if (dmax <= tol * (1 + xc.template head<NQ>().cwiseAbs().maxCoeff())) {
                        converged = true;
                        break;
                    }
                }
                if (!converged) return ERR_NO_CONVERGENCE;
            } else {
                (void)tol, (void)max_iter;
            }
            if constexpr (MV > 0) {
                VelocityMatrix A;
                Multipliers b, rhs;
                Eigen::Matrix<S, MV, MV> Ad;
                Model::velocity_constraint_matrix(xc.data(), p.data(), t, A.data(), b.data());
                if (!finite(A) || !finite(b)) return ERR_NONFINITE_MODEL;
                for (int i = 0; i < MV; ++i) {
                    S s = -b[i];
                    for (int j = 0; j < NUI; ++j)
                        s -= A(i, Model::u_ind[j]) * xc[NQ + Model::u_ind[j]];
                    rhs[i] = s;
                    for (int j = 0; j < MV; ++j) Ad(i, j) = A(i, Model::u_dep[j]);
                }
                Multipliers ud;
                st = lu_solve(Ad, A.cwiseAbs().maxCoeff(), rhs, ud);
                if (st) return st;
                for (int j = 0; j < MV; ++j) xc[NQ + Model::u_dep[j]] = ud[j];
            }
            if (!finite(xc)) return ERR_NONFINITE_MODEL;
            x = xc;
            return OK;
        } else {
            (void)tol, (void)max_iter;
            return OK;
        }
    }

    // ---------------------------------------------------------- integration

    static int step_rk4(S t, S h, const Inputs &r, const Params &p, bool project,
                        State &x) noexcept
    {
        if (!finite(t) || !finite(h) || !finite(r) || !finite(p) || !finite(x))
            return ERR_NONFINITE_INPUT;
        auto f = [&](S tt, const State &xx, State &dx) noexcept {
            return rhs_unchecked(tt, xx, r, p, dx, nullptr);
        };
        State xn = x;
        int st = rk4_step<S>(f, t, h, xn);
        if (st) return st;
        if (project) {
            st = project_unchecked(t + h, p, 16 * Tol::eps, 10, xn);
            if (st) return st;
        }
        x = xn;
        return OK;
    }

    /* the options a run accepts (gen_rt_simulate.c: method_ok) */
    template <class Opts>
    static bool method_ok(const Opts &o) noexcept
    {
        if (o.method != METHOD_RK4 && o.method != METHOD_DOPRI5 && o.method != METHOD_RODAS4)
            return false;
        if (o.method != METHOD_RK4 &&
            (!(o.rtol >= 0) || !(o.atol >= 0) || !(o.rtol > 0 || o.atol > 0)))
            return false;
        return true;
    }

    /* Integrate x from t0 to t1 (gen_rt_model_advance): one RK4 step, or
     * DOPRI5 / RODAS4 steps by their error control (stats.h_next seeds the
     * first); stats accumulate; on failure x is the last good state. */
    template <class Opts, class Stats>
    static int advance(S t0, S t1, const Inputs &r, const Params &p, const Opts &opts,
                       Stats &stats, State &x) noexcept
    {
        if (!finite(t0) || !finite(t1) || !finite(r) || !finite(p) || !finite(x))
            return ERR_NONFINITE_INPUT;
        if (!(t1 >= t0) || !method_ok(opts)) return ERR_BAD_ARG;
        Engine<BasicInput<S>, BasicEvents<S>, Opts, Stats> e(p, opts, stats, &r, nullptr,
                                                                nullptr, t0, x);
        e.t_span = t1 - t0;
        S t = t0;
        while (t < t1) {
            const int st = e.step(t, t1);
            if (st) {
                stats.t_last = t;
                stats.x_last = e.x;
                stats.h_next = e.h_next;
                x = e.x;
                return st;
            }
            e.x = e.xn;
            t = e.t1;
        }
        stats.t_last = t1;
        stats.h_next = e.h_next;
        stats.x_last = e.x;
        x = e.x;
        return OK;
    }

    /* the rows simulate keeps of `rows` (gen_rt_simulate_rows_kept) */
    static int rows_kept(int rows, int every, int final_only) noexcept
    {
        if (rows <= 0) return rows;
        if (final_only) return 1;
        if (every <= 1) return rows;
        return (rows - 1) / every + 1 + ((rows - 1) % every != 0);
    }

    static int simulate_rows(S t0, S t_end, S dt) noexcept
    {
        if (!(dt > 0) || !(t_end >= t0) || !finite(t0) || !finite(t_end)) return ERR_BAD_ARG;
        if ((t_end - t0) / dt > S(1e9)) return ERR_BAD_ARG;
        long n = static_cast<long>((t_end - t0) / dt);
        if (t0 + static_cast<S>(n) * dt < t_end - S(1e-9) * dt) n += 1;
        return static_cast<int>(n + 1);
    }

    /* Simulate from x0 with output rows every dt up to t_end (the last
     * interval clipped): RK4 on the output grid, DOPRI5 and RODAS4 by their
     * error control with the rows from their dense output (gen_rt.h,
     * gen_rt_model_simulate). */
    template <class Opts, class Stats>
    static int simulate(const State &x0, S t0, S t_end, S dt, const Inputs &r, const Params &p,
                        const Opts &opts, int capacity, S *t_out, S *x_out, S *lam_out,
                        Stats &stats) noexcept
    {
        stats = Stats();
        stats.t_last = t0;
        stats.x_last = x0;
        if (!t_out || !x_out) return ERR_NULL;
        if (!finite(x0) || !finite(r) || !finite(p)) return ERR_NONFINITE_INPUT;
        return simulate_impl<BasicInput<S>, BasicEvents<S>>(
            x0, t0, t_end, dt, &r, nullptr, nullptr, p, opts, capacity, t_out, x_out, lam_out,
            nullptr, stats);
    }

    /* simulate() with the inputs from in (a table, a linear feedback, a
     * controller; continuous or sampled): see gen_rt.h, gen_rt_input; r_out
     * (NR per row, may be null) the inputs in effect from each row on */
    template <class In, class Opts, class Stats>
    static int simulate_input(const State &x0, S t0, S t_end, S dt, const In &in, const Params &p,
                              const Opts &opts, int capacity, S *t_out, S *x_out, S *lam_out,
                              S *r_out, Stats &stats) noexcept
    {
        stats = Stats();
        stats.t_last = t0;
        stats.x_last = x0;
        if (!t_out || !x_out) return ERR_NULL;
        if (!finite(x0) || !finite(p)) return ERR_NONFINITE_INPUT;
        const int st = input_check(in);
        if (st) return st;
        return simulate_impl<In, BasicEvents<S>>(x0, t0, t_end, dt, nullptr, &in, nullptr, p,
                                                 opts, capacity, t_out, x_out, lam_out, r_out,
                                                 stats);
    }

    /* simulate_input() with the events of ev (gen_rt.h, gen_rt_events):
     * crossings located on the dense output and logged; a terminal one ends
     * the run with its state as the last row (stats.terminal). */
    template <class In, class Ev, class Opts, class Stats>
    static int simulate_events(const State &x0, S t0, S t_end, S dt, const In &in, const Ev &ev,
                               const Params &p, const Opts &opts, int capacity, S *t_out,
                               S *x_out, S *lam_out, S *r_out, Stats &stats) noexcept
    {
        stats = Stats();
        stats.t_last = t0;
        stats.x_last = x0;
        if (!t_out || !x_out) return ERR_NULL;
        if (!finite(x0) || !finite(p)) return ERR_NONFINITE_INPUT;
        const int st = input_check(in);
        if (st) return st;
        return simulate_impl<In, Ev>(x0, t0, t_end, dt, nullptr, &in, &ev, p, opts, capacity,
                                     t_out, x_out, lam_out, r_out, stats);
    }


    // ------------------------------------------------ Jacobian and step sensitivity

    using JacobianX = Mat<S, NX, NX>;
    using JacobianR = Mat<S, NX, NR>;

    /* d f/dx (NX x NX) and d f/dr (NX x NR) of the right-hand side at (t, x,
     * r), every entry of x free (gen_rt_model_jacobian, gen_rt_sens.c): q'
     * rows from the kinematics, u' rows from the KKT system with the
     * multipliers, at the right-hand side's own q', u', lam. A, Vq, Jc are
     * returned for the elimination when asked. */
    static int jacobian_at(S t, const State &x, const Inputs &r, const Params &p,
                           const State &dx, const Multipliers &lam, JacobianX &Jx, JacobianR &Jr,
                           VelocityMatrix *A_out = nullptr, Mat<S, MV, NQ> *Vq_out = nullptr,
                           Mat<S, MC, NQ> *Jc_out = nullptr) noexcept
    {
        const Coords q = x.template head<NQ>(), qd = dx.template head<NQ>();
        const Speeds u = x.template tail<NU>(), ud = dx.template tail<NU>();
        Mat<S, NQ, NQ> Kqd, Kq;
        Mat<S, NQ, NU> Ku;
        Mat<S, NU, NQ> Rq;
        Mat<S, NU, NU> Ru;
        Mat<S, NU, NR> Rr;
        MassMatrix M;
        VelocityMatrix A;
        Mat<S, MV, NQ> Sq, Vq;
        Mat<S, MV, NU> Su;
        Mat<S, MC, NQ> Jc;
        Mat<S, MV, NQ> Sqd = Mat<S, MV, NQ>::Zero();
        const LinOut<S> out{Kqd.data(), Ku.data(), M.data(), A.data(), Kq.data(), Rq.data(),
                            Ru.data(),  Rr.data(), Sq.data(), Su.data(), Vq.data(), Jc.data(),
                            AccelTerms<Model>::value ? Sqd.data() : nullptr};
        Model::lin_terms(q.data(), u.data(), qd.data(), ud.data(), lam.data(), r.data(),
                         p.data(), t, out);
        if (!finite(Kqd) || !finite(Kq) || !finite(Ku) || !finite(M) || !finite(Rq) ||
            !finite(Ru) || !finite(Rr) || !finite(A) || !finite(Sq) || !finite(Su) ||
            !finite(Vq) || !finite(Jc) || !finite(Sqd))
            return ERR_NONFINITE_MODEL;
        // q' rows: Kqd dq' = -[Kq | Ku] [dq; du]
        Mat<S, NQ, NX> T;
        T.template leftCols<NQ>() = -Kq;
        T.template rightCols<NU>() = -Ku;
        Mat<S, NQ, NX> Dq;
        const Eigen::Matrix<S, NQ, NQ> Kf = Kqd;
        if (lu_solve(Kf, S(0), T, Dq)) return ERR_SINGULAR_KINEMATICS;
        // u' rows: [M, -A^T; A, 0] [du'; dlam] = -[Rq Ru Rr; Sq + Sqd Dq, Su + Sqd Dq, 0]
        constexpr int N = NU + MV, NC = NX + NR;
        Eigen::Matrix<S, N, N> K;
        K.template topLeftCorner<NU, NU>() = M;
        if constexpr (MV > 0) {
            K.template topRightCorner<NU, MV>() = -A.transpose();
            K.template bottomLeftCorner<MV, NU>() = A;
            K.template bottomRightCorner<MV, MV>().setZero();
        }
        Mat<S, N, NC> G, Z;
        G.template block<NU, NQ>(0, 0) = -Rq;
        G.template block<NU, NU>(0, NQ) = -Ru;
        if constexpr (NR > 0) G.template block<NU, NR>(0, NX) = -Rr;
        if constexpr (MV > 0) {
            G.template block<MV, NQ>(NU, 0) = -Sq;
            G.template block<MV, NU>(NU, NQ) = -Su;
            if constexpr (NR > 0) G.template block<MV, NR>(NU, NX).setZero();
            if constexpr (AccelTerms<Model>::value) G.template block<MV, NX>(NU, 0) -= Sqd * Dq;
        }
        int st = lu_solve(K, S(0), G, Z);
        if (st) return st;
        if (!finite(Dq) || !finite(Z)) return ERR_SINGULAR;
        Jx.template topRows<NQ>() = Dq;
        Jx.template bottomRows<NU>() = Z.template block<NU, NX>(0, 0);
        Jr.setZero();
        if constexpr (NR > 0) Jr.template bottomRows<NU>() = Z.template block<NU, NR>(0, NX);
        if (A_out) *A_out = A;
        if (Vq_out) *Vq_out = Vq;
        if (Jc_out) *Jc_out = Jc;
        return OK;
    }

    static int jacobian(S t, const State &x, const Inputs &r, const Params &p, JacobianX &Jx,
                        JacobianR &Jr) noexcept
    {
        if (!finite(t) || !finite(x) || !finite(r) || !finite(p)) return ERR_NONFINITE_INPUT;
        return jacobian_unchecked(t, x, r, p, Jx, Jr);
    }

    /* the same, inputs assumed finite (gen_rt_model_jacobian: RODAS4's) */
    static int jacobian_unchecked(S t, const State &x, const Inputs &r, const Params &p,
                                  JacobianX &Jx, JacobianR &Jr) noexcept
    {
        State dx;
        Multipliers lam = Multipliers::Zero();
        const int st = rhs_unchecked(t, x, r, p, dx, &lam);
        if (st) return st;
        return jacobian_at(t, x, r, p, dx, lam, Jx, Jr);
    }

    /* One RK4 step without projection (x updated, unchanged on failure) and
     * its exact derivatives on the independent state: Fx = P_ind Fx_full E,
     * Fr = P_ind Fr_full, E = [Q, 0; Uq, Uu] at x (gen_rt_model_step_sensitivity) */
    static int step_sensitivity(S t, S h, const Inputs &r, const Params &p, State &x,
                                StateMatrix &Fx, InputMatrix &Fr) noexcept
    {
        if (!finite(t) || !finite(h) || !finite(r) || !finite(p) || !finite(x))
            return ERR_NONFINITE_INPUT;
        constexpr int NC = NX + NR;
        const S h2 = S(0.5) * h;
        State k[4], y;
        Multipliers lam = Multipliers::Zero();
        JacobianX Jx;
        JacobianR Jr;
        Mat<S, NX, NC> D, Ssum, Y;
        Mat<S, NX, NS> E = Mat<S, NX, NS>::Zero();
        VelocityMatrix A;
        Mat<S, MV, NQ> Vq;
        Mat<S, MC, NQ> Jc;
        int st;
        for (int s = 0; s < 4; ++s) {
            const S ts = s == 0 ? t : (s == 3 ? t + h : t + h2);
            const S c = s == 3 ? h : h2;
            if (s == 0) y = x;
            else y = x + c * k[s - 1];
            if ((st = rhs_unchecked(ts, y, r, p, k[s], &lam))) return st;
            if ((st = jacobian_at(ts, y, r, p, k[s], lam, Jx, Jr, s == 0 ? &A : nullptr,
                                  s == 0 ? &Vq : nullptr, s == 0 ? &Jc : nullptr)))
                return st;
            if (s == 0) {
                if ((st = elimination(A, Vq, Jc, E))) return st;
                D.template leftCols<NX>() = Jx;
                if constexpr (NR > 0) D.template rightCols<NR>() = Jr;
                Ssum = D;
            } else {
                Y = c * D;
                for (int i = 0; i < NX; ++i) Y(i, i) += S(1);
                Mat<S, NX, NC> Dn = Jx * Y;
                if constexpr (NR > 0) Dn.template rightCols<NR>() += Jr;
                D = Dn;
                Ssum += (s == 3 ? S(1) : S(2)) * D;
            }
        }
        y = x + (h / S(6)) * (k[0] + S(2) * (k[1] + k[2]) + k[3]);
        if (!finite(y)) return ERR_DIVERGED;
        Mat<S, NX, NC> F = (h / S(6)) * Ssum;
        for (int i = 0; i < NX; ++i) F(i, i) += S(1);
        StateMatrix fx;
        InputMatrix fr;
        for (int kk = 0; kk < NS; ++kk) {
            const int row = kk < NQI ? Model::q_ind[kk] : NQ + Model::u_ind[kk - NQI];
            fx.row(kk) = F.row(row).template leftCols<NX>() * E;
            if constexpr (NR > 0) fr.row(kk) = F.row(row).template rightCols<NR>();
        }
        if (!finite(fx) || !finite(fr)) return ERR_DIVERGED;
        x = y;
        Fx = fx;
        Fr = fr;
        return OK;
    }

    /* E = [Q, 0; Uq, Uu] (NX x NS): an independent perturbation and the
     * dependent one that keeps the constraints to first order */
    static int elimination(const VelocityMatrix &A, const Mat<S, MV, NQ> &Vq,
                           const Mat<S, MC, NQ> &Jc, Mat<S, NX, NS> &E) noexcept
    {
        E.setZero();
        for (int k = 0; k < NQI; ++k) E(Model::q_ind[k], k) = S(1);
        for (int k = 0; k < NUI; ++k) E(NQ + Model::u_ind[k], NQI + k) = S(1);
        if constexpr (MC > 0) {
            Eigen::Matrix<S, MC, MC> Jd;
            Mat<S, MC, NQI> X, Xs;
            for (int i = 0; i < MC; ++i) {
                for (int j = 0; j < MC; ++j) Jd(i, j) = Jc(i, Model::q_dep[j]);
                for (int k = 0; k < NQI; ++k) X(i, k) = Jc(i, Model::q_ind[k]);
            }
            const int st = lu_solve(Jd, Jc.cwiseAbs().maxCoeff(), X, Xs);
            if (st) return st;
            for (int j = 0; j < MC; ++j)
                for (int k = 0; k < NQI; ++k) E(Model::q_dep[j], k) = -Xs(j, k);
        }
        if constexpr (MV > 0) {
            Eigen::Matrix<S, MV, MV> Ad;
            Mat<S, MV, NS> Y, Ys;
            const Mat<S, MV, NS> VqE = Vq * E.template topRows<NQ>();
            for (int i = 0; i < MV; ++i) {
                for (int j = 0; j < MV; ++j) Ad(i, j) = A(i, Model::u_dep[j]);
                for (int k = 0; k < NQI; ++k) Y(i, k) = VqE(i, k);
                for (int k = 0; k < NUI; ++k) Y(i, NQI + k) = A(i, Model::u_ind[k]);
            }
            const int st = lu_solve(Ad, A.cwiseAbs().maxCoeff(), Y, Ys);
            if (st) return st;
            for (int j = 0; j < MV; ++j)
                for (int k = 0; k < NS; ++k) E(NQ + Model::u_dep[j], k) = -Ys(j, k);
        }
        return finite(E) ? OK : ERR_SINGULAR;
    }

    // ---------------------------------------------- inputs during a simulation

    /* the last knot k with T[k] <= t (0 before the first) */
    static int table_row(int n, const S *T, S t) noexcept
    {
        if (t < T[0]) return 0;
        if (t >= T[n - 1]) return n - 1;
        int lo = 0, hi = n - 1;
        while (hi - lo > 1) {
            const int mid = lo + (hi - lo) / 2;
            if (T[mid] <= t) lo = mid;
            else hi = mid;
        }
        return lo;
    }

    /* base (constant or table, a ZOH table at t_zoh), feedback, controller
     * at t (gen_rt_model.c: input_at, the same arithmetic) */
    template <class In>
    static int input_at(const In &in, S t, S t_zoh, const State &x, Inputs &r) noexcept
    {
        if (in.n_table > 0) {
            const S *T = in.t_table, *R = in.r_table;
            const int n = in.n_table;
            if (in.hold == HOLD_LINEAR && n > 1 && t > T[0] && t < T[n - 1]) {
                const int k = table_row(n, T, t);
                const S w = (t - T[k]) / (T[k + 1] - T[k]);
                for (int i = 0; i < NR; ++i)
                    r[i] = R[static_cast<long>(k) * NR + i] +
                           w * (R[static_cast<long>(k + 1) * NR + i] -
                                R[static_cast<long>(k) * NR + i]);
            } else {
                const int k = table_row(n, T, in.hold == HOLD_LINEAR ? t : t_zoh);
                for (int i = 0; i < NR; ++i) r[i] = R[static_cast<long>(k) * NR + i];
            }
        } else {
            for (int i = 0; i < NR; ++i) r[i] = in.r ? in.r[i] : S(0);
        }
        if (in.K) {
            for (int i = 0; i < NR; ++i) {
                S s = 0;
                for (int j = 0; j < NS; ++j) {
                    const int idx = j < NQI ? Model::q_ind[j] : NQ + Model::u_ind[j - NQI];
                    s += in.K[static_cast<long>(i) * NS + j] *
                         (x[idx] - (in.x_op ? in.x_op[idx] : S(0)));
                }
                r[i] -= s;
            }
        }
        if (in.controller && in.controller(in.ctx, t, x.data(), r.data())) return ERR_CONTROLLER;
        if (!finite(r)) return ERR_NONFINITE_INPUT;
        return OK;
    }

    template <class In>
    static int input_check(const In &in) noexcept
    {
        if (in.n_table < 0 || (in.hold != HOLD_ZOH && in.hold != HOLD_LINEAR)) return ERR_BAD_ARG;
        if (!finite(in.period) || in.period < 0) return ERR_BAD_ARG;
        if (in.n_table > 0) {
            if (!in.t_table || (NR > 0 && !in.r_table)) return ERR_NULL;
            for (int i = 0; i < in.n_table; ++i)
                if (!finite(in.t_table[i])) return ERR_NONFINITE_INPUT;
            for (long i = 0; i < static_cast<long>(in.n_table) * NR; ++i)
                if (!finite(in.r_table[i])) return ERR_NONFINITE_INPUT;
            for (int i = 1; i < in.n_table; ++i)
                if (!(in.t_table[i] > in.t_table[i - 1])) return ERR_BAD_ARG;
        } else if (in.r) {
            for (int i = 0; i < NR; ++i)
                if (!finite(in.r[i])) return ERR_NONFINITE_INPUT;
        }
        if (in.K)
            for (int i = 0; i < NR * NS; ++i)
                if (!finite(in.K[i])) return ERR_NONFINITE_INPUT;
        if (in.x_op)
            for (int i = 0; i < NX; ++i)
                if (!finite(in.x_op[i])) return ERR_NONFINITE_INPUT;
        return OK;
    }

    static S time_tol(S t) noexcept
    {
        const S a = t < 0 ? -t : t;
        return 64 * Tol::eps * (a > 1 ? a : S(1));
    }

    // -------------------------------------------------------- linearization

    /* A (NS x NS) and B (NS x NR) for the independent state [q_ind, u_ind]
     * about any operating point, by the elimination of Peterson, Gede and
     * Hubbard done numerically. */
    /* the zero-order-hold discretization of the linearization over dt:
     * Ad = exp(A dt), Bd = int_0^dt exp(A s) ds B (gen_rt::c2d_zoh) */
    static int linearize_discrete(const State &x_op, const Inputs &r_op, const Params &p, S t,
                                  S dt, StateMatrix &Ad, InputMatrix &Bd) noexcept
    {
        if (!finite(dt) || !(dt > 0)) return ERR_BAD_ARG;
        StateMatrix A;
        InputMatrix B;
        const int st = linearize(x_op, r_op, p, t, A, B);
        if (st) return st;
        return c2d_zoh(A, B, dt, Ad, Bd);
    }

    static constexpr int NY = OutputCount<Model>::value;
    using Outputs = Mat<S, NY, 1>;
    using OutputMatrix = Mat<S, NY, NS>;
    using FeedthroughMatrix = Mat<S, NY, NR>;

    /* the outputs y(q, u, r, t) (gen_rt_model_eval_outputs); OK and nothing
     * written when the model has none */
    static int eval_outputs(S t, const State &x, const Inputs &r, const Params &p,
                            Outputs &y) noexcept
    {
        if (!finite(t) || !finite(x) || !finite(r) || !finite(p)) return ERR_NONFINITE_INPUT;
        if constexpr (NY > 0) {
            Outputs yy;
            Model::outputs(x.data(), x.data() + NQ, r.data(), p.data(), t, yy.data());
            if (!finite(yy)) return ERR_NONFINITE_MODEL;
            y = yy;
        } else {
            (void)y;
        }
        return OK;
    }

    static int linearize(const State &x_op, const Inputs &r_op, const Params &p, S t,
                         StateMatrix &A_lin, InputMatrix &B_lin) noexcept
    {
        return linearize_impl(x_op, r_op, p, t, A_lin, B_lin, nullptr, nullptr);
    }

    /* linearize, and C = dy/dx_ind, D = dy/dr of the outputs */
    static int linearize_outputs(const State &x_op, const Inputs &r_op, const Params &p, S t,
                                 StateMatrix &A_lin, InputMatrix &B_lin, OutputMatrix &C_lin,
                                 FeedthroughMatrix &D_lin) noexcept
    {
        return linearize_impl(x_op, r_op, p, t, A_lin, B_lin, &C_lin, &D_lin);
    }

    static int linearize_impl(const State &x_op, const Inputs &r_op, const Params &p, S t,
                              StateMatrix &A_lin, InputMatrix &B_lin, OutputMatrix *C_lin,
                              FeedthroughMatrix *D_lin) noexcept
    {
        if (!finite(x_op) || !finite(r_op) || !finite(p) || !finite(t))
            return ERR_NONFINITE_INPUT;
        const Coords q = x_op.template head<NQ>();
        const Speeds u = x_op.template tail<NU>();
        Coords qd;
        Speeds f, ud;
        MassMatrix M;
        Multipliers lam = Multipliers::Zero();
        VelocityMatrix A; // 0 x NU without velocity constraints
        int st = qdot_from(q, u, p, t, qd);
        if (st) return st;
        Multipliers a;
        {
            // M, f (and A, a) from the joint right-hand-side kernel; its
            // kinematics outputs are not needed here
            Coords qdt;
            Mat<S, NQ, NQ> Kt;
            Model::rhs_terms(q.data(), u.data(), r_op.data(), p.data(), t, Kt.data(), qdt.data(),
                             M.data(), f.data(), A.data(), a.data());
        }
        if (!finite(M) || !finite(f)) return ERR_NONFINITE_MODEL;
        if constexpr (MV > 0) {
            // accelerations and multipliers at the operating point (KKT, as the C API)
            if constexpr (AccelTerms<Model>::value)
                Model::accel_terms(q.data(), u.data(), qd.data(), p.data(), t, a.data());
            if (!finite(A) || !finite(a)) return ERR_NONFINITE_MODEL;
            if ((st = accel_kkt(M, f, A, a, ud, &lam))) return st;
        } else {
            if ((st = spd_solve<S, NU, 1>(M, f, ud))) return st;
            if (!finite(ud)) return ERR_SINGULAR;
        }
        // Jacobian blocks of the linearization (those the model lacks are 0 x n)
        Mat<S, NQ, NQ> Kqd, Kq;
        Mat<S, NQ, NU> Ku;
        Mat<S, NU, NQ> Rq;
        Mat<S, NU, NU> Ru;
        Mat<S, NU, NR> Rr;
        Mat<S, MV, NQ> Sq, Vq;
        Mat<S, MV, NU> Su;
        Mat<S, MC, NQ> Jc;
        Mat<S, MV, NQ> Sqd = Mat<S, MV, NQ>::Zero();
        const LinOut<S> out{Kqd.data(), Ku.data(), M.data(), A.data(), Kq.data(), Rq.data(),
                            Ru.data(),  Rr.data(), Sq.data(), Su.data(), Vq.data(), Jc.data(),
                            AccelTerms<Model>::value ? Sqd.data() : nullptr};
        Model::lin_terms(q.data(), u.data(), qd.data(), ud.data(), lam.data(), r_op.data(),
                         p.data(), t, out);
        if (!finite(Kq) || !finite(Rq) || !finite(Ru) || !finite(Rr) || !finite(Sq) ||
            !finite(Su) || !finite(Vq) || !finite(Jc) || !finite(Sqd))
            return ERR_NONFINITE_MODEL;

        // 1. coordinates: dq = Q dq_ind
        Mat<S, NQ, NQI> Q = Mat<S, NQ, NQI>::Zero();
        for (int k = 0; k < NQI; ++k) Q(Model::q_ind[k], k) = S(1);
        if constexpr (MC > 0) {
            Eigen::Matrix<S, MC, MC> Jd;
            Mat<S, MC, NQI> X;
            for (int i = 0; i < MC; ++i) {
                for (int j = 0; j < MC; ++j) Jd(i, j) = Jc(i, Model::q_dep[j]);
                for (int k = 0; k < NQI; ++k) X(i, k) = Jc(i, Model::q_ind[k]);
            }
            Mat<S, MC, NQI> Xs;
            if ((st = lu_solve(Jd, Jc.cwiseAbs().maxCoeff(), X, Xs))) return st;
            for (int j = 0; j < MC; ++j)
                for (int k = 0; k < NQI; ++k) Q(Model::q_dep[j], k) = -Xs(j, k);
        }
        // 2. speeds: du = Uq dq_ind + Uu du_ind
        Mat<S, NU, NUI> Uu = Mat<S, NU, NUI>::Zero();
        Mat<S, NU, NQI> Uq = Mat<S, NU, NQI>::Zero();
        for (int k = 0; k < NUI; ++k) Uu(Model::u_ind[k], k) = S(1);
        if constexpr (MV > 0) {
            const Mat<S, MV, NQI> VqQ = Vq * Q;
            Eigen::Matrix<S, MV, MV> Ad;
            Mat<S, MV, NS> Y;
            for (int i = 0; i < MV; ++i) {
                for (int j = 0; j < MV; ++j) Ad(i, j) = A(i, Model::u_dep[j]);
                for (int k = 0; k < NUI; ++k) Y(i, k) = A(i, Model::u_ind[k]);
                for (int k = 0; k < NQI; ++k) Y(i, NUI + k) = VqQ(i, k);
            }
            Mat<S, MV, NS> Ys;
            if ((st = lu_solve(Ad, A.cwiseAbs().maxCoeff(), Y, Ys))) return st;
            for (int j = 0; j < MV; ++j) {
                for (int k = 0; k < NUI; ++k) Uu(Model::u_dep[j], k) = -Ys(j, k);
                for (int k = 0; k < NQI; ++k) Uq(Model::u_dep[j], k) = -Ys(j, NUI + k);
            }
        }
        // 3. kinematics: dq' = Dq [dq_ind; du_ind], Dq = -Kqd^-1 [Kq Q + Ku Uq | Ku Uu]
        Mat<S, NQ, NS> T1;
        T1.template leftCols<NQI>() = -(Kq * Q + Ku * Uq);
        T1.template rightCols<NUI>() = -(Ku * Uu);
        Mat<S, NQ, NS> Dq;
        if constexpr (Model::EXPLICIT_KINEMATICS) {
            // the kinematic matrix is diagonal here (explicit q')
            const S tol = Tol::pivot_rtol * Kqd.cwiseAbs().maxCoeff();
            for (int i = 0; i < NQ; ++i) {
                if (!(std::abs(Kqd(i, i)) > tol)) return ERR_SINGULAR;
                Dq.row(i) = T1.row(i) / Kqd(i, i);
            }
        } else {
            if ((st = lu_solve<S, NQ>(Kqd, S(0), T1, Dq))) return st;
        }
        // 4. dynamics: [M, -A^T; A, 0] [du'; dlam] = -[R; S] (rows of the right-hand side)
        Mat<S, NU + MV, NS + NR> G, Z;
        G.template block<NU, NQI>(0, 0) = -(Rq * Q + Ru * Uq);
        G.template block<NU, NUI>(0, NQI) = -(Ru * Uu);
        if constexpr (NR > 0) G.template block<NU, NR>(0, NS) = -Rr;
        if constexpr (MV > 0) {
            G.template block<MV, NQI>(NU, 0) = -(Sq * Q + Su * Uq);
            G.template block<MV, NUI>(NU, NQI) = -(Su * Uu);
            G.template block<MV, NR>(NU, NS).setZero();
            // S holds q' (implicit kinematics): its share through dq' = Dq
            if constexpr (AccelTerms<Model>::value) G.template block<MV, NS>(NU, 0) -= Sqd * Dq;
            Eigen::Matrix<S, NU + MV, NU + MV> K;
            K.template topLeftCorner<NU, NU>() = M;
            K.template topRightCorner<NU, MV>() = -A.transpose();
            K.template bottomLeftCorner<MV, NU>() = A;
            K.template bottomRightCorner<MV, MV>().setZero();
            if ((st = lu_solve(K, S(0), G, Z))) return st;
        } else {
            if ((st = spd_solve<S, NU, NS + NR>(M, G, Z))) return st;
        }
        // 5. the independent rows
        for (int k = 0; k < NQI; ++k) {
            A_lin.row(k) = Dq.row(Model::q_ind[k]);
            B_lin.row(k).setZero();
        }
        for (int k = 0; k < NUI; ++k) {
            A_lin.row(NQI + k) = Z.row(Model::u_ind[k]).template head<NS>();
            B_lin.row(NQI + k) = Z.row(Model::u_ind[k]).template tail<NR>();
        }
        if (!finite(A_lin) || !finite(B_lin)) return ERR_SINGULAR;
        // 6. outputs: dy = [Yq Q + Yu Uq | Yu Uu] dx_ind + Yr dr
        if constexpr (NY > 0) {
            if (C_lin) {
                Mat<S, NY, NQ> Yq;
                Mat<S, NY, NU> Yu;
                Mat<S, NY, NR> Yr;
                Model::output_jacobian(q.data(), u.data(), r_op.data(), p.data(), t, Yq.data(),
                                       Yu.data(), NR > 0 ? Yr.data() : nullptr);
                OutputMatrix C;
                C.template leftCols<NQI>() = Yq * Q + Yu * Uq;
                C.template rightCols<NUI>() = Yu * Uu;
                if (!finite(C) || !finite(Yr)) return ERR_NONFINITE_MODEL;
                *C_lin = C;
                if (D_lin) *D_lin = Yr;
            }
        } else {
            (void)C_lin;
            (void)D_lin;
        }
        return OK;
    }

    // ------------------------------------------------------------ the engine
    // gen_rt_simulate.c in C++: the same steps, the same arithmetic.

    /* how a step is evaluated inside: the DOPRI5 continuous extension, a
     * cubic Hermite interpolant (RK4, RODAS4), or not at all */
    enum Dense : int { DENSE_NONE, DENSE_DOPRI5, DENSE_HERMITE };

    /* the state of a run: the inputs (in == nullptr: the constant *r), the
     * events (ev == nullptr: none), the step just taken from (t, x) to
     * (t1, xn), the method's scratch and the adaptive state */
    template <class In, class Ev, class Opts, class Stats>
    struct Engine {
        const Params &p;
        const Opts &o;
        Stats &s;
        const Inputs *r;
        const In *in;
        const Ev *ev;
        Inputs r_held = Inputs::Zero(); // held since the last sample (period > 0)
        S t_seg, t0, t_sampled;         // start of the sub-interval and of the run; the sample
        bool sampled = false;
        bool need_y = false;
        int dense = DENSE_NONE;
        S t_span = 0;                   // t_end - t0: the scale of the first step
        State x, xn, xa, xi, xe;        // now, after the step, inside the step
        Outputs ya, yb, yi;             // outputs for output events
        State k[7], y, ynew;            // DOPRI5's stages (RK4: k[0] = f at the start)
        State f0, f1, dfdt;             // RODAS4 (f1: also RK4's f at the end)
        JacobianX J;
        JacobianR Jr;
        Rodas4Work<S, NX> rw;
        S t = 0, t1 = 0, h = 0;
        const State *d_f0 = nullptr, *d_f1 = nullptr; // the Hermite interpolant's slopes
        S h_next;
        bool rejected_last = false, f0_valid = false;
        S err_old = S(1e-4);            // DOPRI5's PI control: the last accepted error
        long attempts = 0;              // since the last output row

        Engine(const Params &p_, const Opts &o_, Stats &s_, const Inputs *r_, const In *in_,
               const Ev *ev_, S t0_, const State &x0) noexcept
            : p(p_), o(o_), s(s_), r(r_), in(in_), ev(ev_), t_seg(t0_), t0(t0_), t_sampled(t0_),
              x(x0), h_next(s_.h_next)
        {
            if constexpr (NY > 0) {
                if (ev && ev->n > 0)
                    for (int i = 0; i < ev->n; ++i) need_y = need_y || ev->which[i] >= NX;
            }
        }

        /* the right-hand side with the inputs of the run (rhs_cb) */
        int rhs(S tt, const State &xx, State &dx) const noexcept
        {
            if (in && !(in->period > 0)) {
                Inputs rr;
                const int st = input_at(*in, tt, t_seg, xx, rr);
                if (st) return st;
                return rhs_unchecked(tt, xx, rr, p, dx, nullptr);
            }
            return rhs_unchecked(tt, xx, in ? r_held : *r, p, dx, nullptr);
        }

        /* the input in effect at (tt, xx) during the current step */
        int inputs_now(S tt, const State &xx, Inputs &rr) const noexcept
        {
            if (!in) {
                rr = *r;
                return OK;
            }
            if (in->period > 0) {
                rr = r_held;
                return OK;
            }
            return input_at(*in, tt, t_seg, xx, rr);
        }

        /* is tt a sample time t0 + k period? */
        bool is_sample(S tt) const noexcept
        {
            const S per = in->period;
            if (!(per > 0)) return false;
            const S kk = static_cast<S>(static_cast<long>((tt - t0) / per + S(0.5)));
            return (tt - (t0 + kk * per)) <= time_tol(tt) && (t0 + kk * per - tt) <= time_tol(tt);
        }

        /* the end of the sub-interval from tt towards tb1: the next sample or knot */
        S next_break(S tt, S tb1) const noexcept
        {
            S tb = tb1;
            const S tol = time_tol(tt);
            if (in->period > 0) {
                const long kk = static_cast<long>((tt - t0) / in->period) + 1;
                S ts = t0 + static_cast<S>(kk) * in->period;
                if (ts <= tt + tol) ts = t0 + static_cast<S>(kk + 1) * in->period;
                if (ts < tb - time_tol(tb)) tb = ts;
            }
            if (in->n_table > 0) {
                int kk = table_row(in->n_table, in->t_table, tt + tol);
                if (in->t_table[kk] <= tt + tol) ++kk;
                if (kk < in->n_table) {
                    const S tk = in->t_table[kk];
                    if (tk > tt + tol && tk < tb - time_tol(tb)) tb = tk;
                }
            }
            return tb;
        }

        /* a sample of the inputs at tt from xx (each sample time once) */
        int sample(S tt, const State &xx) noexcept
        {
            if (!in || !(in->period > 0) || !is_sample(tt) || (sampled && t_sampled == tt))
                return OK;
            sampled = true;
            t_sampled = tt;
            f0_valid = false;
            return input_at(*in, tt, tt, xx, r_held);
        }

        int project(S tt, State &xx) const noexcept
        {
            if (!o.project) return OK;
            return project_unchecked(tt, p, o.proj_tol, o.proj_max_iter, xx);
        }

        /* the state at t + theta h inside the step just taken (not projected) */
        void dense_at(S theta, State &out) const noexcept
        {
            if (theta >= 1) {
                out = xn;
                return;
            }
            if (dense == DENSE_DOPRI5)
                dopri5_dense<S, NX>(h, theta, x, ynew, k, out);
            else
                hermite<S, NX>(h, theta, x, *d_f0, xn, *d_f1, out);
        }

        /* the RMS norm of v scaled by atol + rtol |xx| */
        S scaled_rms(const State &xx, const State &v) const noexcept
        {
            S sum = 0;
            for (int i = 0; i < NX; ++i) {
                const S rr = v[i] / (o.atol + o.rtol * rt_abs(xx[i]));
                sum += rr * rr;
            }
            return std::sqrt(sum / static_cast<S>(NX));
        }

        /* The starting step of Hairer's hinit (and SciPy's
         * select_initial_step): h0 from |x| / |f|, one Euler step to estimate
         * the second derivative, then h = min(100 h0, (0.01 / max(|f|,
         * |f'|))^(1/q)), bounded by the span; into h_next. One evaluation of
         * f (y1, f1: scratch). */
        int first_step(S tt, const State &xx, const State &fx, int q, State &y1,
                       State &fy) noexcept
        {
            if (o.h_init > 0) {
                h_next = o.h_init;
                return OK;
            }
            const S d0 = scaled_rms(xx, xx), d1 = scaled_rms(xx, fx);
            S h0 = (d0 < S(1e-5) || d1 < S(1e-5)) ? S(1e-6) : S(0.01) * d0 / d1;
            if (t_span > 0) h0 = rt_min(h0, t_span);
            for (int i = 0; i < NX; ++i) y1[i] = xx[i] + h0 * fx[i];
            const int st = rhs(tt + h0, y1, fy);
            if (st) return st;
            s.n_rhs += 1;
            for (int i = 0; i < NX; ++i) fy[i] -= fx[i];
            const S d2 = scaled_rms(xx, fy) / h0;
            S h1;
            if (d1 <= S(1e-15) && d2 <= S(1e-15))
                h1 = rt_max(S(1e-6), h0 * S(1e-3));
            else
                h1 = std::pow(S(0.01) / rt_max(d1, d2), S(1.0) / static_cast<S>(q));
            S hh = rt_min(100 * h0, h1);
            if (t_span > 0) hh = rt_min(hh, t_span);
            h_next = hh;
            return OK;
        }

        /* err^(-1/q): the step-size factor's power, q = 5 (DOPRI5) or 4 (RODAS4) */
        static S inv_root(S err, int q) noexcept
        {
            return std::pow(err, S(-1.0) / static_cast<S>(q));
        }

        /* after a trial: the next step size; true when the step is accepted.
         * q = 5, DOPRI5: Hairer's PI controller (beta = 0.04), factor in
         * [0.2, 10]; q = 4, RODAS4: err^(-1/4), factor in [0.2, 6]; safety
         * 0.9; no increase right after a rejection; a failed evaluation
         * shrinks the step by 4 (gen_rt_simulate.c: control_) */
        bool control(int st, S err, S hh, bool last, int q) noexcept
        {
            const S h_nat = h_next;
            const S fac_max = q == 5 ? S(10.0) : S(6.0);
            S fac;
            if (st || !(err <= S(1.0))) {
                s.n_rejected += 1;
                if (st == 0 && err == err)
                    fac = rt_max(S(0.2), S(0.9) * inv_root(err, q));
                else
                    fac = S(0.25); // a failed evaluation: shrink towards it
                h_next = hh * fac;
                rejected_last = true;
                return false;
            }
            if (q == 5) {
                const S e0 = rt_max(err, S(1e-10));
                fac = S(0.9) * std::pow(e0, -S(0.17)) * std::pow(err_old, S(0.04));
                err_old = rt_max(err, S(1e-4));
            } else {
                fac = err > 0 ? S(0.9) * inv_root(err, q) : fac_max;
            }
            fac = rt_min(rejected_last ? S(1.0) : fac_max, rt_max(S(0.2), fac));
            // a clipped step says little about the natural step
            h_next = (last && fac >= S(1.0)) ? rt_max(hh * fac, h_nat) : hh * fac;
            if (o.h_max > 0) h_next = rt_min(h_next, o.h_max);
            rejected_last = false;
            s.n_accepted += 1;
            return true;
        }

        /* the trial step: hh, within the step budget and above hmin */
        // the caller's cancellation flag (Opts::cancel, NULL: never) is set
        bool cancelled() const noexcept
        {
            return o.cancel != nullptr && *static_cast<const volatile int *>(o.cancel) != 0;
        }

        // the next trial step from t towards t_stop: hh, and last when it is
        // clipped to reach t_stop (a step within 0.01% of it stretches to it)
        int trial_size(S t, S t_stop, S hmin, S &hh, bool &last) noexcept
        {
            const long max_steps = o.max_steps > 0 ? o.max_steps : 100000L;
            if (cancelled()) return ERR_CANCELLED;
            if (attempts >= max_steps) return ERR_MAX_STEPS;
            if (h_next < hmin) return ERR_STEP_UNDERFLOW;
            attempts += 1;
            hh = h_next;
            last = false;
            if (t + hh >= t_stop || t + S(1.0001) * hh >= t_stop) {
                hh = t_stop - t;
                last = true;
            }
            return OK;
        }

        /* one accepted step from (t_, x) towards t_stop: t1, xn (projected)
         * and what dense_at needs; a failure leaves x untouched */
        int step(S t_, S t_stop) noexcept
        {
            auto f = [this](S tt, const State &xx, State &dx) noexcept { return rhs(tt, xx, dx); };
            const S hmin = o.h_min > 0 ? o.h_min
                                       : 64 * Tol::eps * rt_max(S(1.0), rt_abs(t_stop));
            int st;
            t = t_;
            if (cancelled()) return ERR_CANCELLED;
            if (o.method == METHOD_RK4) {
                const S hh = t_stop - t;
                xn = x;
                st = rk4_step<S, NX>(f, t, hh, xn, k[0]);
                s.n_rhs += 4;
                if (!st) st = project(t_stop, xn);
                if (st) return st;
                s.n_accepted += 1;
                t1 = t_stop;
                h = hh;
                dense = DENSE_NONE;
                if (ev && ev->n > 0) {
                    // the Hermite interpolant for events: f at the end as well
                    if ((st = rhs(t_stop, xn, f1))) return st;
                    s.n_rhs += 1;
                    dense = DENSE_HERMITE;
                    d_f0 = &k[0];
                    d_f1 = &f1;
                }
                return OK;
            }
            if (o.method == METHOD_DOPRI5) {
                if (f0_valid) {
                    k[0] = k[6]; // first same as last
                } else {
                    if ((st = rhs(t, x, k[0]))) return st;
                    s.n_rhs += 1;
                    f0_valid = true;
                }
                if (h_next <= 0 && (st = first_step(t, x, k[0], 5, y, ynew))) return st;
                if (o.h_max > 0) h_next = rt_min(h_next, o.h_max);
                for (;;) {
                    S hh, err = 0;
                    bool last = false;
                    if ((st = trial_size(t, t_stop, hmin, hh, last))) return st;
                    st = dopri5_trial<S, NX>(f, t, hh, x, o.rtol, o.atol, k, y, ynew, err);
                    s.n_rhs += 6;
                    if (!control(st, err, hh, last, 5)) {
                        if (h_next < hmin) return st ? st : ERR_STEP_UNDERFLOW;
                        continue;
                    }
                    t1 = last ? t_stop : t + hh;
                    h = hh;
                    break;
                }
                xn = ynew;
                if ((st = project(t1, xn))) return st;
                // k7 = f(t1, ynew) starts the next step unless projection moved it
                for (int i = 0; i < NX; ++i)
                    if (xn[i] != ynew[i]) {
                        f0_valid = false;
                        break;
                    }
                dense = DENSE_DOPRI5;
                return OK;
            }
            if (o.method == METHOD_RODAS4) {
                Inputs rr;
                if (f0_valid) {
                    f0 = f1;
                } else {
                    if ((st = rhs(t, x, f0))) return st;
                    s.n_rhs += 1;
                }
                // J = df/dx of the closed loop: the model's, and a continuous
                // linear feedback's through df/dr (a controller's is not known)
                if ((st = inputs_now(t, x, rr))) return st;
                if ((st = jacobian_unchecked(t, x, rr, p, J, Jr))) return st;
                s.n_jac += 1;
                if constexpr (NR > 0) {
                    if (in && !(in->period > 0) && in->K) {
                        for (int j = 0; j < NS; ++j) {
                            const int col = j < NQI ? Model::q_ind[j] : NQ + Model::u_ind[j - NQI];
                            for (int a = 0; a < NX; ++a) {
                                S sum = 0;
                                for (int b = 0; b < NR; ++b)
                                    sum += Jr(a, b) * in->K[static_cast<long>(b) * NS + j];
                                J(a, col) -= sum;
                            }
                        }
                    }
                }
                // df/dt by a forward difference (the inputs' time dependence too),
                // with Hairer's increment sqrt(eps max(1e-5, |t|))
                const S dt = std::sqrt(Tol::eps * rt_max(S(1e-5), rt_abs(t)));
                if ((st = rhs(t + dt, x, y))) return st;
                s.n_rhs += 1;
                for (int i = 0; i < NX; ++i) dfdt[i] = (y[i] - f0[i]) / dt;
                if (h_next <= 0 && (st = first_step(t, x, f0, 4, ynew, y))) return st;
                if (o.h_max > 0) h_next = rt_min(h_next, o.h_max);
                for (;;) {
                    S hh, err = 0;
                    bool last = false;
                    if ((st = trial_size(t, t_stop, hmin, hh, last))) return st;
                    st = rodas4_trial<S, NX>(f, t, hh, x, f0, J, dfdt, o.rtol, o.atol, rw, ynew,
                                             err);
                    s.n_rhs += 5;
                    if (st == ERR_SINGULAR && err < 0) {
                        // I/(h gamma) - J singular: a property of this step
                        // size, not of the model; rejected like a large error
                        st = OK;
                        err = S(1e30);
                    }
                    if (!st && err <= S(1.0)) {
                        // f at the new state: the interpolant's end and the next
                        // f0 (a failure there rejects the step)
                        const S tn = last ? t_stop : t + hh;
                        xn = ynew;
                        st = project(tn, xn);
                        if (!st) {
                            st = rhs(tn, xn, f1);
                            s.n_rhs += 1;
                        }
                    }
                    if (!control(st, err, hh, last, 4)) {
                        if (h_next < hmin) return st ? st : ERR_STEP_UNDERFLOW;
                        continue;
                    }
                    t1 = last ? t_stop : t + hh;
                    h = hh;
                    break;
                }
                f0_valid = true;
                dense = DENSE_HERMITE;
                d_f0 = &f0;
                d_f1 = &f1;
                return OK;
            }
            return ERR_BAD_ARG;
        }

        // ---- events

        /* the outputs at (tt, xx) with the inputs of the current step */
        int outputs(S tt, const State &xx, Outputs &yy) const noexcept
        {
            if constexpr (NY > 0) {
                if (!need_y) return OK;
                Inputs rr;
                const int st = inputs_now(tt, xx, rr);
                if (st) return st;
                Model::outputs(xx.data(), xx.data() + NQ, rr.data(), p.data(), tt, yy.data());
                return finite(yy) ? OK : ERR_NONFINITE_MODEL;
            } else {
                (void)tt, (void)xx, (void)yy;
                return OK;
            }
        }

        S event_g(int i, const State &xx, const Outputs &yy) const noexcept
        {
            const int w = ev->which[i];
            S v;
            if constexpr (NY > 0)
                v = w < NX ? xx[w] : yy[w - NX];
            else
                (void)yy, v = xx[w];
            return v - (ev->level ? ev->level[i] : S(0));
        }

        static bool crosses(int dir, S ga, S gb) noexcept
        {
            return (dir >= 0 && ga < 0 && gb >= 0) || (dir <= 0 && ga > 0 && gb <= 0);
        }

        /* the crossing of event i in (lo, hi] on the dense output (Illinois,
         * with a bisection every third iteration): the end of the final
         * bracket on the side of ghi, to a few units of rounding in t */
        int event_root(int i, S lo, S hi, S glo, S ghi, S &theta) noexcept
        {
            const S tol = 4 * Tol::eps * rt_max(S(1.0), rt_max(rt_abs(t), rt_abs(t1)));
            int side = 0, st;
            for (int it = 0; it < 300 && ghi != 0; ++it) {
                if ((hi - lo) * rt_abs(h) <= tol) break;
                S mid = hi - ghi * (hi - lo) / (ghi - glo);
                if (it % 3 == 2 || !(mid > lo && mid < hi)) mid = S(0.5) * (lo + hi);
                if (!(mid > lo && mid < hi)) break;
                dense_at(mid, xi);
                if ((st = outputs(t + mid * h, xi, yi))) return st;
                const S gm = event_g(i, xi, yi);
                if (gm == 0) {
                    hi = mid;
                    break;
                }
                if ((gm > 0) == (ghi > 0)) {
                    hi = mid;
                    ghi = gm;
                    if (side == 1) glo *= S(0.5);
                    side = 1;
                } else {
                    lo = mid;
                    glo = gm;
                    if (side == -1) ghi *= S(0.5);
                    side = -1;
                }
            }
            theta = hi;
            return OK;
        }

        /* the events in the step just taken, in time order: logged, and stop
         * set (with te, xe) at the first terminal one */
        int events(bool &stop, S &te) noexcept
        {
            S a = 0;
            int st;
            stop = false;
            if (!ev || ev->n <= 0) return OK;
            if ((st = outputs(t, x, ya))) return st;
            if ((st = outputs(t1, xn, yb))) return st;
            xa = x;
            while (a < 1) {
                int best = -1;
                S th_best = 2;
                for (int i = 0; i < ev->n; ++i) {
                    const S ga = event_g(i, xa, ya), gb = event_g(i, xn, yb);
                    S th;
                    if (!crosses(ev->direction[i], ga, gb)) continue;
                    if ((st = event_root(i, a, 1, ga, gb, th))) return st;
                    if (th < th_best) {
                        th_best = th;
                        best = i;
                    }
                }
                if (best < 0) break;
                const S t_ev = th_best >= 1 ? t1 : t + th_best * h;
                dense_at(th_best, xe);
                if (th_best < 1 && (st = project(t_ev, xe))) return st;
                if (s.n_events < ev->capacity) {
                    ev->log_which[s.n_events] = best;
                    ev->log_t[s.n_events] = t_ev;
                    for (int i = 0; i < NX; ++i)
                        ev->log_x[static_cast<long>(s.n_events) * NX + i] = xe[i];
                }
                s.n_events += 1;
                if (ev->terminal && ev->terminal[best]) {
                    stop = true;
                    te = t_ev;
                    s.terminal = best;
                    return OK;
                }
                a = th_best;
                // search on from the dense output at the event (not the
                // projected state logged: projection may move the value back
                // across the level, and the same crossing would be found again)
                dense_at(a, xa);
                if (a < 1 && (st = outputs(t_ev, xa, ya))) return st;
            }
            return OK;
        }
    };

    template <class Ev>
    static int events_check(const Ev *ev) noexcept
    {
        if (!ev || ev->n == 0) return OK;
        if (ev->n < 0 || ev->capacity < 0) return ERR_BAD_ARG;
        if (!ev->which || !ev->direction) return ERR_NULL;
        if (ev->capacity > 0 && (!ev->log_which || !ev->log_t || !ev->log_x)) return ERR_NULL;
        if (ev->level)
            for (int i = 0; i < ev->n; ++i)
                if (!finite(ev->level[i])) return ERR_NONFINITE_INPUT;
        for (int i = 0; i < ev->n; ++i) {
            if (ev->which[i] < 0 || ev->which[i] >= NX + NY) return ERR_BAD_ARG;
            if (ev->direction[i] < -1 || ev->direction[i] > 1) return ERR_BAD_ARG;
        }
        return OK;
    }

    /* what simulate writes: the rows and where they go */
    struct RowSink {
        int rows, capacity;
        S t0, t_end, dt;
        S *t_out, *x_out, *lam_out, *r_out;

        S row_time(int k) const noexcept
        {
            return (k == rows - 1) ? t_end : t0 + static_cast<S>(k) * dt;
        }
    };

    /* row k at tk with state xr: the inputs in effect from tk on, the
     * multipliers, stored if kept */
    template <class E>
    static int emit_row(E &e, const RowSink &out, int k, bool last, S tk,
                        const State &xr) noexcept
    {
        constexpr int LAM_STRIDE = MV > 0 ? MV : 1;
        Inputs rk;
        State dx;
        Multipliers lam;
        int st;
        if (e.in) {
            if (e.in->period > 0) {
                rk = e.r_held;
            } else {
                if ((st = input_at(*e.in, tk, tk, xr, rk))) return st;
            }
        } else {
            rk = *e.r;
        }
        if ((st = rhs_unchecked(tk, xr, rk, e.p, dx, &lam))) return st;
        e.attempts = 0;
        const auto &op = e.o;
        if (op.final_only ? last : (op.every <= 1 || k % op.every == 0 || last)) {
            const long j = e.s.n_out;
            if (j >= out.capacity) return ERR_OUTPUT_FULL;
            out.t_out[j] = tk;
            for (int i = 0; i < NX; ++i) out.x_out[j * NX + i] = xr[i];
            if (out.lam_out)
                for (int i = 0; i < MV; ++i) out.lam_out[j * LAM_STRIDE + i] = lam[i];
            if (out.r_out)
                for (int i = 0; i < NR; ++i) out.r_out[j * NR + i] = rk[i];
            e.s.n_out = static_cast<int>(j) + 1;
        }
        return OK;
    }

    /* simulate, simulate_input and simulate_events (gen_rt_simulate.c:
     * simulate_): in == nullptr for the constant *r, ev == nullptr for no
     * events; stats already reset */
    template <class In, class Ev, class Opts, class Stats>
    static int simulate_impl(const State &x0, S t0, S t_end, S dt, const Inputs *r, const In *in,
                             const Ev *ev, const Params &p, const Opts &opts, int capacity,
                             S *t_out, S *x_out, S *lam_out, S *r_out, Stats &stats) noexcept
    {
        int st;
        const int rows = simulate_rows(t0, t_end, dt);
        if (rows < 0) return rows;
        if (opts.every < 0 || opts.final_only < 0 || !method_ok(opts)) return ERR_BAD_ARG;
        if (capacity < rows_kept(rows, opts.every, opts.final_only)) return ERR_OUTPUT_FULL;
        if ((st = events_check(ev))) return st;
        Engine<In, Ev, Opts, Stats> e(p, opts, stats, r, in, ev, t0, x0);
        e.t_span = t_end - t0;
        const RowSink out{rows, capacity, t0, t_end, dt, t_out, x_out, lam_out, r_out};
        S t = t0;
        auto fail_at = [&stats](S tf, const State &xf) noexcept {
            stats.t_last = tf;
            stats.x_last = xf;
        };
        if ((st = e.project(t0, e.x))) return st;
        if (in && in->period > 0 && (st = e.sample(t0, e.x))) return fail_at(t0, e.x), st;
        if ((st = emit_row(e, out, 0, rows == 1, t0, e.x))) return fail_at(t0, e.x), st;
        int k = 1;
        while (k < rows) {
            S t_stop = opts.method == METHOD_RK4 ? out.row_time(k) : t_end;
            bool stop = false;
            S te = 0;
            if (in) t_stop = e.next_break(t, t_stop);
            if ((st = e.sample(t, e.x))) return fail_at(t, e.x), st;
            e.t_seg = t;
            if ((st = e.step(t, t_stop))) return fail_at(t, e.x), st;
            if ((st = e.events(stop, te))) return fail_at(t, e.x), st;
            // a sample at t1 comes first: the rows at t1 show the new input
            if (!stop && (st = e.sample(e.t1, e.xn))) return fail_at(t, e.x), st;
            while (k < rows) {
                const S tk = out.row_time(k), tol1 = time_tol(e.t1);
                const State *xr = &e.xn;
                if (stop ? !(tk < te - time_tol(te)) : !(tk <= e.t1 + tol1)) break;
                if (tk < e.t1 - tol1) {
                    // inside the step: the dense output, projected
                    e.dense_at((tk - t) / e.h, e.xi);
                    if (!finite(e.xi)) return fail_at(t, e.x), ERR_DIVERGED;
                    if ((st = e.project(tk, e.xi))) return fail_at(t, e.x), st;
                    xr = &e.xi;
                }
                if ((st = emit_row(e, out, k, k == rows - 1, tk, *xr))) return fail_at(t, e.x), st;
                ++k;
            }
            if (stop) {
                // the run ends at the terminal event: its state is the last row
                if ((st = emit_row(e, out, k, true, te, e.xe))) return fail_at(t, e.x), st;
                stats.t_last = te;
                stats.h_next = e.h_next;
                stats.x_last = e.xe;
                return OK;
            }
            // the inputs may change at a break: f at t1 is evaluated afresh
            if (in && t_stop < t_end && e.t1 == t_stop) e.f0_valid = false;
            e.x = e.xn;
            t = e.t1;
        }
        stats.t_last = t_end;
        stats.h_next = e.h_next;
        stats.x_last = e.x;
        return OK;
    }
};

} // namespace gen_rt

#endif /* GEN_RT_EIGEN_HPP */
