/*
 * gen_rt_expm.hpp - the matrix exponential and the zero-order-hold
 * discretization for the C++17/Eigen runtime: the algorithm of the C
 * runtime's gen_rt_expm.c (scaling and squaring with a diagonal Pade
 * approximant, N. J. Higham, SIAM J. Matrix Anal. Appl. 26(4), 2005) on
 * fixed-size Eigen matrices.
 *
 *   int gen_rt::expm(A, E)                     E = exp(A), A and E N x N
 *   int gen_rt::c2d_zoh(A, B, dt, Ad, Bd)      exp([A, B; 0, 0] dt) = [Ad, Bd; 0, I]
 *
 * The degree is the lowest of 3, 5, 7, 9, 13 whose theta bounds ||A||_1
 * (scaled by 2^-s to theta_13 beyond); S = float uses the single-precision
 * thetas and degrees 3, 5, 7; any other S the double ones.
 *
 * Error policy as gen_rt_eigen.hpp: noexcept, an int status 0 (OK) or a
 * negative code of gen_rt_status.h, outputs written only on success;
 * fixed-size Eigen objects only (no heap: EIGEN_RUNTIME_NO_MALLOC holds),
 * no mutable globals. The matrices may be row- or column-major.
 *
 * Stand-alone: it needs only Eigen and gen_rt_status.h, and it may be
 * included before or after gen_rt_eigen.hpp (its status constants live in
 * gen_rt::expm_detail, with the values of gen_rt::OK, gen_rt::ERR_*).
 */
#ifndef GEN_RT_EXPM_HPP
#define GEN_RT_EXPM_HPP

#include <cmath>
#include <type_traits>
#include <utility>

#include <Eigen/Core>

#include "gen_rt_status.h"

namespace gen_rt {
namespace expm_detail {

// the status codes (OK, ERR_NULL, ...) of gen_rt_status.h
#define GEN_RT_EXPM_STATUS_(name, value, text) inline constexpr int name = (value);
GEN_RT_STATUS_TABLE(GEN_RT_EXPM_STATUS_)
#undef GEN_RT_EXPM_STATUS_

template <class T>
struct type_identity {
    using type = T;
};

template <class S, int N>
using Square = Eigen::Matrix<S, N, N>;

// Pade coefficients b_0..b_m (b_m = 1) of the diagonal [m/m] approximant
inline constexpr double b3[] = {120.0, 60.0, 12.0, 1.0};
inline constexpr double b5[] = {30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0};
inline constexpr double b7[] = {17297280.0, 8648640.0, 1995840.0, 277200.0,
                                25200.0,    1512.0,    56.0,      1.0};
inline constexpr double b9[] = {17643225600.0, 8821612800.0, 2075673600.0, 302702400.0,
                                30270240.0,    2162160.0,    110880.0,     3960.0,
                                90.0,          1.0};
inline constexpr double b13[] = {64764752532480000.0, 32382376266240000.0,
                                 7771770303897600.0,  1187353796428800.0,
                                 129060195264000.0,   10559470521600.0,
                                 670442572800.0,      33522128640.0,
                                 1323241920.0,        40840800.0,
                                 960960.0,            16380.0,
                                 182.0,               1.0};

// degrees and thetas (Higham 2005, Table 2.3), per precision
struct Degree {
    int m;
    double theta;
    const double *b;
};
inline constexpr Degree degrees_double[] = {{3, 1.495585217958292e-2, b3},
                                            {5, 2.539398330063230e-1, b5},
                                            {7, 9.504178996162932e-1, b7},
                                            {9, 2.097847961257068, b9},
                                            {13, 5.371920351148152, b13}};
inline constexpr Degree degrees_float[] = {{3, 4.258730016922831e-1, b3},
                                           {5, 1.880152677804762, b5},
                                           {7, 3.925724783138660, b7}};

// the pivot threshold of the C runtime (GEN_RT_PIVOT_RTOL)
template <class S>
constexpr S pivot_rtol() noexcept
{
    return std::is_same<S, float>::value ? S(1e-6) : S(1e-12);
}

// max column sum of |a| (inf when a sum overflows)
template <class Derived>
typename Derived::Scalar norm1(const Eigen::MatrixBase<Derived> &a) noexcept
{
    return a.cwiseAbs().colwise().sum().maxCoeff();
}

// x = den^-1 x by LU with partial pivoting, in place (den overwritten): the
// arithmetic of gen_rt_lu_factor / gen_rt_lu_solve, with its pivot test
// (|pivot| <= pivot_rtol * max |den_ij|: ERR_SINGULAR)
template <class S, int N>
int lu_solve_inplace(Square<S, N> &den, Square<S, N> &x) noexcept
{
    const S scale = den.cwiseAbs().maxCoeff();
    if (!(scale > S(0))) return ERR_SINGULAR;
    const S tol = pivot_rtol<S>() * scale;
    for (int k = 0; k < N; ++k) {
        int p = k;
        S best = std::abs(den(k, k));
        for (int i = k + 1; i < N; ++i) {
            const S v = std::abs(den(i, k));
            if (v > best) {
                best = v;
                p = i;
            }
        }
        if (!(best > tol)) return ERR_SINGULAR; // also NaN
        if (p != k) {
            for (int j = 0; j < N; ++j) {
                std::swap(den(k, j), den(p, j));
                std::swap(x(k, j), x(p, j));
            }
        }
        for (int i = k + 1; i < N; ++i) {
            const S l = den(i, k) / den(k, k);
            if (l != S(0)) {
                for (int j = k + 1; j < N; ++j) den(i, j) -= l * den(k, j);
                for (int j = 0; j < N; ++j) x(i, j) -= l * x(k, j);
            }
        }
    }
    for (int i = N - 1; i >= 0; --i) {
        for (int k = i + 1; k < N; ++k) {
            const S u = den(i, k);
            if (u != S(0))
                for (int j = 0; j < N; ++j) x(i, j) -= u * x(k, j);
        }
        for (int j = 0; j < N; ++j) x(i, j) /= den(i, i);
    }
    return OK;
}

// U and V, the odd and even parts of p_m(a), for m = 3, 5, 7, 9
template <class S, int N>
void pade_low(const Square<S, N> &a, int m, const double *b, Square<S, N> &U,
              Square<S, N> &V) noexcept
{
    using M = Square<S, N>;
    const M I = M::Identity();
    const M A2 = a.lazyProduct(a);
    M P = S(b[1]) * I + S(b[3]) * A2;
    V = S(b[0]) * I + S(b[2]) * A2;
    M Ak = A2;
    for (int j = 2; 2 * j < m; ++j) {
        const M next = Ak.lazyProduct(A2); // A^4, A^6, A^8
        Ak = next;
        P += S(b[2 * j + 1]) * Ak;
        V += S(b[2 * j]) * Ak;
    }
    U = a.lazyProduct(P);
}

// the same for m = 13 (Higham 2005, (2.11)); b = b13
template <class S, int N>
void pade_13(const Square<S, N> &a, const double *b, Square<S, N> &U, Square<S, N> &V) noexcept
{
    using M = Square<S, N>;
    const M I = M::Identity();
    const M A2 = a.lazyProduct(a);
    const M A4 = A2.lazyProduct(A2);
    const M A6 = A4.lazyProduct(A2);
    M T = S(b[13]) * A6 + S(b[11]) * A4 + S(b[9]) * A2;
    M W = A6.lazyProduct(T);
    W += S(b[7]) * A6 + S(b[5]) * A4 + S(b[3]) * A2 + S(b[1]) * I;
    U = a.lazyProduct(W);
    T = S(b[12]) * A6 + S(b[10]) * A4 + S(b[8]) * A2;
    V = A6.lazyProduct(T);
    V += S(b[6]) * A6 + S(b[4]) * A4 + S(b[2]) * A2 + S(b[0]) * I;
}

// exp(a) by the Pade approximant of degree d.m, then s squarings. The
// products are Eigen's coefficient-based ones (lazyProduct): no GEMM kernel
// to instantiate per size, and nothing on the heap.
template <class S, int N>
int pade_square(const Square<S, N> &a, const Degree &d, int s, Square<S, N> &E) noexcept
{
    using M = Square<S, N>;
    M U, V;
    if constexpr (std::is_same<S, float>::value) {
        pade_low<S, N>(a, d.m, d.b, U, V); // degrees 3, 5, 7 only
    } else {
        if (d.m == 13)
            pade_13<S, N>(a, d.b, U, V);
        else
            pade_low<S, N>(a, d.m, d.b, U, V);
    }
    // r_m = (V - U)^-1 (V + U)
    M den = V - U;
    M R = V + U;
    const int st = lu_solve_inplace<S, N>(den, R);
    if (st != OK) return st;
    for (int i = 0; i < s; ++i) {
        const M R2 = R.lazyProduct(R);
        R = R2;
    }
    if (!R.allFinite()) return ERR_DIVERGED;
    E = R;
    return OK;
}

template <class S, int N>
int expm_impl(const Square<S, N> &A, Square<S, N> &E) noexcept
{
    static_assert(N > 0, "gen_rt::expm needs a fixed size N > 0 (no Eigen::Dynamic)");
    constexpr bool single = std::is_same<S, float>::value;
    const Degree *deg = single ? degrees_float : degrees_double;
    const int ndeg = single ? int(sizeof degrees_float / sizeof degrees_float[0])
                            : int(sizeof degrees_double / sizeof degrees_double[0]);
    if (!A.allFinite()) return ERR_NONFINITE_INPUT;
    const S nrm = norm1(A);
    int k = 0;
    while (k < ndeg - 1 && !(nrm <= S(deg[k].theta))) ++k;
    int s = 0;
    if (k == ndeg - 1) {
        // the least s with ||A||_1 / 2^s <= theta_max (an overflowed norm,
        // inf, stops the doubling at inf)
        S t = S(deg[k].theta);
        while (nrm > t) {
            t *= S(2);
            ++s;
        }
    }
    if (s > 0) {
        S f(1);
        for (int i = 0; i < s; ++i) f *= S(0.5);
        const Square<S, N> As = A * f; // exact: a power of two
        return pade_square<S, N>(As, deg[k], s, E);
    }
    return pade_square<S, N>(A, deg[k], 0, E);
}

} // namespace expm_detail

/* E = exp(A) for a fixed-size N x N matrix (N > 0). Statuses:
 * ERR_NONFINITE_INPUT (A holds NaN or inf), ERR_SINGULAR (the Pade
 * denominator; not for finite A), ERR_DIVERGED (exp(A) overflows S).
 * E may be the same object as A. */
template <class S, int N, int OA, int OE>
int expm(const Eigen::Matrix<S, N, N, OA, N, N> &A, Eigen::Matrix<S, N, N, OE, N, N> &E) noexcept
{
    static_assert(N != Eigen::Dynamic, "gen_rt::expm needs fixed-size matrices");
    const expm_detail::Square<S, N> a = A;
    expm_detail::Square<S, N> e;
    const int st = expm_detail::expm_impl<S, N>(a, e);
    if (st == expm_detail::OK) E = e;
    return st;
}

/* Zero-order hold: exp([A, B; 0, 0] dt) = [Ad, Bd; 0, I], A NS x NS, B NS x NR
 * (NR may be 0). dt must be finite and > 0 (ERR_BAD_ARG); A, B finite
 * (ERR_NONFINITE_INPUT); ERR_SINGULAR and ERR_DIVERGED as expm (DIVERGED
 * also when A dt or B dt overflows). B is brought to the magnitude of A by
 * a power of two before the exponential and Bd scaled back, as the C
 * runtime does. */
template <class S, int NS, int NR, int OA, int OB, int OAd, int OBd>
int c2d_zoh(const Eigen::Matrix<S, NS, NS, OA, NS, NS> &A,
            const Eigen::Matrix<S, NS, NR, OB, NS, NR> &B,
            typename expm_detail::type_identity<S>::type dt,
            Eigen::Matrix<S, NS, NS, OAd, NS, NS> &Ad,
            Eigen::Matrix<S, NS, NR, OBd, NS, NR> &Bd) noexcept
{
    static_assert(NS != Eigen::Dynamic && NR != Eigen::Dynamic,
                  "gen_rt::c2d_zoh needs fixed-size matrices");
    static_assert(NS > 0 && NR >= 0, "gen_rt::c2d_zoh needs NS > 0 and NR >= 0");
    constexpr int N = NS + NR;
    namespace ed = expm_detail;
    if (!(dt > S(0)) || !(dt - dt == S(0))) return ed::ERR_BAD_ARG; // NaN, <= 0, inf
    if (!A.allFinite()) return ed::ERR_NONFINITE_INPUT;
    ed::Square<S, N> M = ed::Square<S, N>::Zero();
    M.template topLeftCorner<NS, NS>() = A * dt;
    S back(1);
    if constexpr (NR > 0) {
        if (!B.allFinite()) return ed::ERR_NONFINITE_INPUT;
        M.template topRightCorner<NS, NR>() = B * dt;
        if (!M.allFinite()) return ed::ERR_DIVERGED;
        // Bd is linear in B: ||B dt||_1 down to ||A dt||_1 (or 1) by 2^-h
        const S an = ed::norm1(M.template topLeftCorner<NS, NS>());
        S bn = ed::norm1(M.template topRightCorner<NS, NR>());
        const S target = an > S(0) ? an : S(1);
        S f(1);
        for (int h = 0; bn > target && h < 100; ++h) {
            bn *= S(0.5);
            f *= S(0.5);
            back *= S(2);
        }
        if (back != S(1)) M.template topRightCorner<NS, NR>() *= f;
    } else {
        (void)B;
    }
    if (!M.allFinite()) return ed::ERR_DIVERGED;
    ed::Square<S, N> E;
    const int st = ed::expm_impl<S, N>(M, E);
    if (st != ed::OK) return st;
    if constexpr (NR > 0) {
        if (back != S(1)) {
            E.template topRightCorner<NS, NR>() *= back;
            if (!E.allFinite()) return ed::ERR_DIVERGED;
        }
        Bd = E.template topRightCorner<NS, NR>();
    } else {
        (void)Bd;
    }
    Ad = E.template topLeftCorner<NS, NS>();
    return ed::OK;
}

} // namespace gen_rt

#endif /* GEN_RT_EXPM_HPP */
