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
 * Runtime::simulate (the fields used are listed at Runtime).
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

enum Method : int { METHOD_RK4 = 0, METHOD_DOPRI5 = 1 };

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

/* Classic fourth-order Runge-Kutta step (gen_rt_rk4_step); f(t, x, dx)
 * returns a status; x unchanged on failure. */
template <typename S, int N, typename F>
inline int rk4_step(F &&f, S t, S h, Mat<S, N, 1> &x) noexcept
{
    Mat<S, N, 1> k1, k2, k3, k4, y;
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

/* The Dormand-Prince 5(4) tableau of gen_rt_dopri5.h in the scalar type. */
template <typename S>
struct Dopri5Tableau {
#define GEN_RT_EIGEN_COEF(name, num, den) static constexpr S name = S(num) / S(den);
    GEN_RT_DOPRI5_TABLEAU(GEN_RT_EIGEN_COEF)
#undef GEN_RT_EIGEN_COEF
};

template <typename S>
struct Dopri5Stats {
    long n_accepted = 0, n_rejected = 0, n_rhs = 0;
    S h_last = S(0);
};

/* Dormand-Prince 5(4) with the C runtime's step-size control
 * (gen_rt_dopri5_integrate): integrates x from t0 to t1 exactly; f(t, x, dx)
 * and post(t, x) (applied after each accepted step when use_post) return a
 * status; o: the options (rtol, atol, h_init, h_min, h_max, max_steps, see
 * Runtime); on error x holds the last accepted state and t_reached its time. */
template <typename S, int N, typename F, typename P, typename Opts>
inline int dopri5_integrate(F &&f, P &&post, bool use_post, S t0, S t1, const Opts &o,
                            Dopri5Stats<S> &stats, S &t_reached, Mat<S, N, 1> &x) noexcept
{
    using T = Dopri5Tableau<S>;
    Mat<S, N, 1> k1, k2, k3, k4, k5, k6, k7, y, ynew;
    S t = t0, h;
    const S span = t1 - t0;
    long attempts = 0;
    bool rejected_last = false;
    int st;
    t_reached = t0;
    if (!(o.rtol >= 0) || !(o.atol >= 0) || !(o.rtol > 0 || o.atol > 0) || !(span >= 0))
        return ERR_BAD_ARG;
    if (span == 0) return OK;
    const long max_steps = o.max_steps > 0 ? o.max_steps : 100000L;
    const S hmin = o.h_min > 0 ? o.h_min
                               : S(64.0) * Tolerances<S>::eps * std::max(S(1.0), std::abs(t1));
    if ((st = f(t, x, k1))) return st;
    stats.n_rhs += 1;
    if (o.h_init > 0) h = o.h_init;
    else if (stats.h_last > 0) h = stats.h_last;
    else {
        // Hairer's starting-step heuristic, max norms
        S d0 = 0, d1 = 0;
        for (int i = 0; i < N; ++i) {
            const S sc = o.atol + o.rtol * std::abs(x[i]);
            d0 = std::max(d0, std::abs(x[i]) / sc);
            d1 = std::max(d1, std::abs(k1[i]) / sc);
        }
        h = (d0 < S(1e-5) || d1 < S(1e-5)) ? S(1e-6) : S(0.01) * d0 / d1;
        h = std::min(h, span);
    }
    if (o.h_max > 0) h = std::min(h, o.h_max);
    while (t < t1) {
        S err = 0, hs;
        const S h_nat = h;
        bool last = false;
        if (attempts >= max_steps) { t_reached = t; return ERR_MAX_STEPS; }
        ++attempts;
        if (t + h >= t1 || t + S(1.0001) * h >= t1) { h = t1 - t; last = true; }
        // one trial step
        st = OK;
        y = x + h * T::A21 * k1;
        if (!st) st = f(t + T::C2 * h, y, k2);
        if (!st) {
            y = x + h * (T::A31 * k1 + T::A32 * k2);
            st = f(t + T::C3 * h, y, k3);
        }
        if (!st) {
            y = x + h * (T::A41 * k1 + T::A42 * k2 + T::A43 * k3);
            st = f(t + T::C4 * h, y, k4);
        }
        if (!st) {
            y = x + h * (T::A51 * k1 + T::A52 * k2 + T::A53 * k3 + T::A54 * k4);
            st = f(t + T::C5 * h, y, k5);
        }
        if (!st) {
            y = x + h * (T::A61 * k1 + T::A62 * k2 + T::A63 * k3 + T::A64 * k4 + T::A65 * k5);
            st = f(t + h, y, k6);
        }
        if (!st) {
            ynew = x + h * (T::B1 * k1 + T::B3 * k3 + T::B4 * k4 + T::B5 * k5 + T::B6 * k6);
            st = f(t + h, ynew, k7);
        }
        if (!st) {
            for (int i = 0; i < N; ++i) {
                const S d = h * (T::E1 * k1[i] + T::E3 * k3[i] + T::E4 * k4[i] + T::E5 * k5[i] +
                                 T::E6 * k6[i] + T::E7 * k7[i]);
                const S sc = o.atol + o.rtol * std::max(std::abs(x[i]), std::abs(ynew[i]));
                const S rr = std::abs(d) / sc;
                if (!(rr <= err)) err = rr; // NaN propagates into err
            }
        }
        stats.n_rhs += 6;
        if (st || !(err <= S(1.0))) {
            // rejected: a failed evaluation counts as an infinite error
            stats.n_rejected += 1;
            if (st == 0 && err == err)
                hs = h * std::max(S(0.2), S(0.9) * std::pow(err, -S(0.2)));
            else
                hs = h * S(0.25);
            if (hs < hmin) {
                t_reached = t;
                return st ? st : ERR_STEP_UNDERFLOW;
            }
            h = hs;
            rejected_last = true;
            continue;
        }
        // accepted
        t = last ? t1 : t + h;
        x = ynew;
        stats.n_accepted += 1;
        if (use_post) {
            if ((st = post(t, x))) { t_reached = t; return st; }
        }
        {
            S fac = err > 0 ? S(0.9) * std::pow(err, -S(0.2)) : S(5.0);
            fac = std::min(rejected_last ? S(1.0) : S(5.0), std::max(S(0.2), fac));
            h = h * fac;
            // a clipped final step says little about the natural step
            stats.h_last = (last && fac >= S(1.0)) ? std::max(h, h_nat) : h;
        }
        if (o.h_max > 0) h = std::min(h, o.h_max);
        rejected_last = false;
        if (t < t1) {
            if ((st = f(t, x, k1))) { t_reached = t; return st; }
            stats.n_rhs += 1;
        }
    }
    t_reached = t1;
    return OK;
}

// ------------------------------------------------------------- the runtime

/* Every model-agnostic algorithm over a model traits type (see the top of
 * this file), for the scalar type S. The generated header's typed API
 * forwards here; the names and semantics are that API's.
 *
 * advance and simulate take the integration options and statistics as
 * template parameters (the generated header renders its SimOptions and
 * SimStats from gen/abi.py); the fields used:
 *   Opts:  int method (METHOD_RK4, METHOD_DOPRI5), project (nonzero: project
 *          onto the constraints after each step), S rtol, atol, h_init, h_min,
 *          h_max, long max_steps, S proj_tol, int proj_max_iter;
 *   Stats: long n_accepted, n_rejected, n_rhs, int n_out, S t_last, h_next,
 *          State x_last; a value-initialized Stats is all zeros. */
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
            if (lu_solve<S, NA>(Fm, S(0), rhs, sol)) return ERR_SINGULAR;
            if (!finite(sol)) return ERR_NONFINITE_MODEL;
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

    template <class Opts, class Stats>
    static int advance(S t0, S t1, const Inputs &r, const Params &p, const Opts &opts,
                       Stats &stats, State &x) noexcept
    {
        if (!finite(t0) || !finite(t1) || !finite(r) || !finite(p) || !finite(x))
            return ERR_NONFINITE_INPUT;
        if (!(t1 >= t0)) return ERR_BAD_ARG;
        auto f = [&](S tt, const State &xx, State &dx) noexcept {
            return rhs_unchecked(tt, xx, r, p, dx, nullptr);
        };
        return integrate_f(f, p, t0, t1, opts, stats, x);
    }

    /* one integration t0 -> t1 over the right-hand side f (one RK4 step or
     * DOPRI5 steps), projection after each step when asked */
    template <class F, class Opts, class Stats>
    static int integrate_f(F &f, const Params &p, S t0, S t1, const Opts &opts, Stats &stats,
                           State &x) noexcept
    {
        auto post = [&](S tt, State &xx) noexcept {
            return project_unchecked(tt, p, opts.proj_tol, opts.proj_max_iter, xx);
        };
        int st;
        if (opts.method == METHOD_RK4) {
            State xn = x;
            st = rk4_step<S>(f, t0, t1 - t0, xn);
            stats.n_rhs += 4;
            if (!st && opts.project) st = post(t1, xn);
            if (st) {
                stats.t_last = t0;
                stats.x_last = x;
                return st;
            }
            x = xn;
            stats.n_accepted += 1;
        } else if (opts.method == METHOD_DOPRI5) {
            Dopri5Stats<S> s;
            S t_reached = t0;
            s.h_last = stats.h_next;
            st = dopri5_integrate<S>(f, post, opts.project, t0, t1, opts, s, t_reached, x);
            stats.n_accepted += s.n_accepted;
            stats.n_rejected += s.n_rejected;
            stats.n_rhs += s.n_rhs;
            stats.h_next = s.h_last;
            if (st) {
                stats.t_last = t_reached;
                stats.x_last = x;
                return st;
            }
        } else {
            return ERR_BAD_ARG;
        }
        stats.t_last = t1;
        stats.x_last = x;
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

    static bool keep_row(int k, int rows, int every, int final_only) noexcept
    {
        return final_only ? k == rows - 1 : (every <= 1 || k % every == 0 || k == rows - 1);
    }

    static int simulate_rows(S t0, S t_end, S dt) noexcept
    {
        if (!(dt > 0) || !(t_end >= t0) || !finite(t0) || !finite(t_end)) return ERR_BAD_ARG;
        if ((t_end - t0) / dt > S(1e9)) return ERR_BAD_ARG;
        long n = static_cast<long>((t_end - t0) / dt);
        if (t0 + static_cast<S>(n) * dt < t_end - S(1e-9) * dt) n += 1;
        return static_cast<int>(n + 1);
    }

    template <class Opts, class Stats>
    static int simulate(const State &x0, S t0, S t_end, S dt, const Inputs &r, const Params &p,
                        const Opts &opts, int capacity, S *t_out, S *x_out, S *lam_out,
                        Stats &stats) noexcept
    {
        constexpr int LAM_STRIDE = MV > 0 ? MV : 1;
        if (!t_out || !x_out) return ERR_NULL;
        if (!finite(x0) || !finite(r) || !finite(p)) return ERR_NONFINITE_INPUT;
        State x = x0, dx;
        Multipliers lam;
        int st;
        stats = Stats();
        stats.t_last = t0;
        stats.x_last = x0;
        const int rows = simulate_rows(t0, t_end, dt);
        if (rows < 0) return rows;
        if (opts.every < 0 || opts.final_only < 0) return ERR_BAD_ARG;
        if (capacity < rows_kept(rows, opts.every, opts.final_only)) return ERR_OUTPUT_FULL;
        if (opts.project) {
            st = project_unchecked(t0, p, opts.proj_tol, opts.proj_max_iter, x);
            if (st) return st;
        }
        S t_prev = t0;
        for (int k = 0; k < rows; ++k) {
            const S tk = (k == rows - 1) ? t_end : t0 + static_cast<S>(k) * dt;
            if (k > 0) {
                st = advance(t_prev, tk, r, p, opts, stats, x);
                if (st) return st;
            }
            st = rhs_unchecked(tk, x, r, p, dx, &lam);
            if (st) {
                stats.t_last = tk;
                stats.x_last = x;
                return st;
            }
            if (keep_row(k, rows, opts.every, opts.final_only)) {
                const long j = stats.n_out;
                t_out[j] = tk;
                for (int i = 0; i < NX; ++i) x_out[j * NX + i] = x[i];
                if (lam_out)
                    for (int i = 0; i < MV; ++i) lam_out[j * LAM_STRIDE + i] = lam[i];
                stats.n_out = static_cast<int>(j) + 1;
            }
            t_prev = tk;
        }
        return OK;
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

    /* simulate() with the inputs from in (a table, a linear feedback, a
     * controller; continuous or sampled): see gen_rt.h, gen_rt_input */
    template <class In, class Opts, class Stats>
    static int simulate_input(const State &x0, S t0, S t_end, S dt, const In &in, const Params &p,
                              const Opts &opts, int capacity, S *t_out, S *x_out, S *lam_out,
                              S *r_out, Stats &stats) noexcept
    {
        constexpr int LAM_STRIDE = MV > 0 ? MV : 1;
        stats = Stats();
        stats.t_last = t0;
        stats.x_last = x0;
        if (!t_out || !x_out) return ERR_NULL;
        if (!finite(x0) || !finite(p)) return ERR_NONFINITE_INPUT;
        int st = input_check(in);
        if (st) return st;
        const bool sampled = in.period > 0;
        Inputs r_buf = Inputs::Zero(), r_held = Inputs::Zero();
        S t_seg = t0, t_sampled = t0;
        bool has_sample = false;
        auto is_sample = [&](S t) noexcept {
            if (!sampled) return false;
            const S k = static_cast<S>(static_cast<long>((t - t0) / in.period + S(0.5)));
            return (t - (t0 + k * in.period)) <= time_tol(t) &&
                   (t0 + k * in.period - t) <= time_tol(t);
        };
        auto next_break = [&](S t, S t1) noexcept {
            S tb = t1;
            const S tol = time_tol(t);
            if (sampled) {
                const long k = static_cast<long>((t - t0) / in.period) + 1;
                S ts = t0 + static_cast<S>(k) * in.period;
                if (ts <= t + tol) ts = t0 + static_cast<S>(k + 1) * in.period;
                if (ts < tb - time_tol(tb)) tb = ts;
            }
            if (in.n_table > 0) {
                int k = table_row(in.n_table, in.t_table, t + tol);
                if (in.t_table[k] <= t + tol) ++k;
                if (k < in.n_table) {
                    const S tk = in.t_table[k];
                    if (tk > t + tol && tk < tb - time_tol(tb)) tb = tk;
                }
            }
            return tb;
        };
        int cb_status = OK;
        auto f = [&](S tt, const State &xx, State &dx) noexcept {
            if (sampled) return rhs_unchecked(tt, xx, r_held, p, dx, nullptr);
            Inputs rr;
            const int s2 = input_at(in, tt, t_seg, xx, rr);
            if (s2) {
                cb_status = s2;
                return s2;
            }
            return rhs_unchecked(tt, xx, rr, p, dx, nullptr);
        };
        (void)cb_status;
        State x = x0, dx;
        Multipliers lam;
        const int rows = simulate_rows(t0, t_end, dt);
        if (rows < 0) return rows;
        if (opts.every < 0 || opts.final_only < 0) return ERR_BAD_ARG;
        if (capacity < rows_kept(rows, opts.every, opts.final_only)) return ERR_OUTPUT_FULL;
        if (opts.project) {
            st = project_unchecked(t0, p, opts.proj_tol, opts.proj_max_iter, x);
            if (st) return st;
        }
        S t_prev = t0;
        for (int k = 0; k < rows; ++k) {
            const S tk = (k == rows - 1) ? t_end : t0 + static_cast<S>(k) * dt;
            if (k > 0) {
                S t = t_prev;
                while (t < tk) {
                    const S tb = next_break(t, tk);
                    if (is_sample(t) && !(has_sample && t_sampled == t)) {
                        has_sample = true;
                        t_sampled = t;
                        st = input_at(in, t, t, x, r_held);
                        if (st) {
                            stats.t_last = t;
                            stats.x_last = x;
                            return st;
                        }
                    }
                    t_seg = t;
                    st = integrate_f(f, p, t, tb, opts, stats, x);
                    if (st) return st;
                    t = tb;
                }
            }
            Inputs *rk = &r_buf;
            if (sampled) {
                rk = &r_held;
                if (k == 0 || is_sample(tk)) {
                    has_sample = true;
                    t_sampled = tk;
                    st = input_at(in, tk, tk, x, r_held);
                } else {
                    st = OK;
                }
            } else {
                st = input_at(in, tk, tk, x, r_buf);
            }
            if (!st) st = rhs_unchecked(tk, x, *rk, p, dx, &lam);
            if (st) {
                stats.t_last = tk;
                stats.x_last = x;
                return st;
            }
            if (keep_row(k, rows, opts.every, opts.final_only)) {
                const long j = stats.n_out;
                t_out[j] = tk;
                for (int i = 0; i < NX; ++i) x_out[j * NX + i] = x[i];
                if (lam_out)
                    for (int i = 0; i < MV; ++i) lam_out[j * LAM_STRIDE + i] = lam[i];
                if (r_out)
                    for (int i = 0; i < NR; ++i) r_out[j * NR + i] = (*rk)[i];
                stats.n_out = static_cast<int>(j) + 1;
            }
            t_prev = tk;
        }
        return OK;
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
        Model::mass_matrix(q.data(), p.data(), t, M.data());
        Model::forcing(q.data(), u.data(), r_op.data(), p.data(), t, f.data());
        if (!finite(M) || !finite(f)) return ERR_NONFINITE_MODEL;
        if constexpr (MV > 0) {
            // accelerations and multipliers at the operating point (KKT, as the C API)
            Multipliers a;
            {
                Coords qdt;
                MassMatrix Mt;
                Speeds ft;
                Mat<S, NQ, NQ> Kt;
                Model::rhs_terms(q.data(), u.data(), r_op.data(), p.data(), t, Kt.data(),
                                 qdt.data(), Mt.data(), ft.data(), A.data(), a.data());
            }
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
};

} // namespace gen_rt

#endif /* GEN_RT_EIGEN_HPP */
