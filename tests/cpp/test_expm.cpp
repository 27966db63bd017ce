// test_expm.cpp - gen_rt::expm and gen_rt::c2d_zoh (csrc/eigen/gen_rt_expm.hpp)
// on their own (this file includes no other runtime header), in double and
// float, with the heap forbidden (EIGEN_RUNTIME_NO_MALLOC; assertions on).
// Built and run by tests/test_expm.py:
//   test_expm            closed forms and status codes; exit status 1 on a failure
//   test_expm compare [float]  reads matrices from stdin, prints exp / c2d
//                        results (compared with scipy by the Python test)
// -DTEST_EXPM_COMPARE_ONLY builds only the comparison (a quicker compile).
#ifndef EIGEN_RUNTIME_NO_MALLOC
#define EIGEN_RUNTIME_NO_MALLOC
#endif
#undef NDEBUG

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "gen_rt_expm.hpp"

namespace {

namespace st = gen_rt::expm_detail;
static_assert(st::OK == 0 && st::ERR_NONFINITE_INPUT == -2 && st::ERR_BAD_ARG == -7 &&
                  st::ERR_DIVERGED == -11,
              "the codes of gen_rt_status.h");

struct NoHeap {
    NoHeap() { Eigen::internal::set_is_malloc_allowed(false); }
    ~NoHeap() { Eigen::internal::set_is_malloc_allowed(true); }
};

template <class S, int R, int C>
using RowMat = Eigen::Matrix<S, R, C, (C == 1 && R != 1) ? Eigen::ColMajor : Eigen::RowMajor>;

#ifndef TEST_EXPM_COMPARE_ONLY
int failures = 0, checks = 0;

#define CHECK(cond)                                                                \
    do {                                                                           \
        ++checks;                                                                  \
        if (!(cond)) {                                                             \
            ++failures;                                                            \
            std::fprintf(stderr, "%s:%d: FAILED (%s): %s\n", __FILE__, __LINE__,  \
                         single ? "float" : "double", #cond);                      \
        }                                                                          \
    } while (0)

#define CHECK_ERR(err, tol)                                                        \
    do {                                                                           \
        const double e_ = (err), t_ = (tol);                                       \
        ++checks;                                                                  \
        if (!(e_ <= t_)) {                                                         \
            ++failures;                                                            \
            std::fprintf(stderr, "%s:%d: FAILED (%s): %s = %.3g > %.3g\n",         \
                         __FILE__, __LINE__, single ? "float" : "double", #err, e_, \
                         t_);                                                      \
        }                                                                          \
    } while (0)

// max |got - ref| / max |ref| (got in S, ref in double)
template <class D1, class D2>
double rel_err(const Eigen::MatrixBase<D1> &got, const Eigen::MatrixBase<D2> &ref)
{
    const double rmax = ref.cwiseAbs().maxCoeff();
    const double e = (got.template cast<double>() - ref).cwiseAbs().maxCoeff();
    return rmax > 0 ? e / rmax : e;
}

template <class S>
void closed_forms()
{
    constexpr bool single = std::is_same<S, float>::value;
    const double tol = single ? 1e-5 : 1e-13;
    using Md2 = Eigen::Matrix<double, 2, 2>;
    NoHeap no_heap;

    // rotations exp([0, th; -th, 0]) = [cos, sin; -sin, cos]
    for (double th0 : {1e-3, 0.3, 1.0, 2.5, 10.0, 100.0}) {
        Eigen::Matrix<S, 2, 2> A, E;
        A << S(0), S(th0), -S(th0), S(0);
        const double th = double(A(0, 1));
        Md2 ref;
        ref << std::cos(th), std::sin(th), -std::sin(th), std::cos(th);
        CHECK((gen_rt::expm<S, 2>(A, E)) == 0); // the explicit form deduces the rest
        CHECK_ERR(rel_err(E, ref), tol * (th > 1 ? th : 1));
    }

    // strictly upper triangular: I + N + N^2/2 + N^3/6, row-major storage
    for (double c : {0.01, 0.5, 3.0, 25.0}) {
        RowMat<S, 4, 4> A, E;
        A.setZero();
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j) A(i, j) = S(c * std::sin(1.0 + 3 * i + j));
        const Eigen::Matrix4d N = A.template cast<double>();
        const Eigen::Matrix4d ref =
            Eigen::Matrix4d::Identity() + N + N * N / 2.0 + N * N * N / 6.0;
        CHECK(gen_rt::expm(A, E) == 0);
        CHECK_ERR(rel_err(E, ref), tol);
        CHECK(E(3, 0) == S(0) && E(2, 1) == S(0) && E(1, 0) == S(0));
    }

    // diagonal: exp per entry, zeros stay exactly zero
    {
        const double d[6] = {-20.0, -3.0, 0.0, 0.5, 2.0, 7.0};
        Eigen::Matrix<S, 6, 6> A = Eigen::Matrix<S, 6, 6>::Zero(), E;
        for (int i = 0; i < 6; ++i) A(i, i) = S(d[i]);
        CHECK(gen_rt::expm(A, E) == 0);
        for (int i = 0; i < 6; ++i) {
            CHECK_ERR(std::abs(double(E(i, i)) / std::exp(d[i]) - 1), tol);
            for (int j = 0; j < 6; ++j)
                if (j != i) CHECK(E(i, j) == S(0));
        }
    }

    // 1 x 1, and E the same object as A
    {
        Eigen::Matrix<S, 1, 1> a;
        a(0, 0) = S(-2.5);
        CHECK(gen_rt::expm(a, a) == 0);
        CHECK_ERR(std::abs(double(a(0, 0)) / std::exp(-2.5) - 1), tol);
    }

    // a skew-symmetric 6 x 6 of 1-norm 50: exp(A) exp(-A) = I, orthogonal
    {
        Eigen::Matrix<double, 6, 6> Sk = Eigen::Matrix<double, 6, 6>::Zero();
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < i; ++j) {
                Sk(i, j) = std::cos(7.0 * i + 3.0 * j);
                Sk(j, i) = -Sk(i, j);
            }
        Sk *= 50.0 / Sk.cwiseAbs().colwise().sum().maxCoeff();
        const Eigen::Matrix<S, 6, 6> A = Sk.cast<S>(), Am = -A;
        Eigen::Matrix<S, 6, 6> E, Em;
        CHECK(gen_rt::expm(A, E) == 0);
        CHECK(gen_rt::expm(Am, Em) == 0);
        const Eigen::Matrix<double, 6, 6> I6 = Eigen::Matrix<double, 6, 6>::Identity();
        const Eigen::Matrix<double, 6, 6> Ed = E.template cast<double>(),
                                          Emd = Em.template cast<double>();
        CHECK_ERR(rel_err((Ed * Emd).eval(), I6), 50 * tol);
        CHECK_ERR(rel_err((Ed.transpose() * Ed).eval(), I6), 50 * tol);
        CHECK_ERR(rel_err(Emd, Ed.transpose().eval()), 50 * tol);
    }

    // 16 x 16 (Eigen's blocked products and LU): 8 rotation blocks
    {
        Eigen::Matrix<S, 16, 16> A = Eigen::Matrix<S, 16, 16>::Zero(), E;
        Eigen::Matrix<double, 16, 16> ref = Eigen::Matrix<double, 16, 16>::Zero();
        for (int k = 0; k < 8; ++k) {
            const S w = S(0.7 * (k + 1));
            const double th = double(w);
            A(2 * k, 2 * k + 1) = w;
            A(2 * k + 1, 2 * k) = -w;
            ref(2 * k, 2 * k) = ref(2 * k + 1, 2 * k + 1) = std::cos(th);
            ref(2 * k, 2 * k + 1) = std::sin(th);
            ref(2 * k + 1, 2 * k) = -std::sin(th);
        }
        CHECK(gen_rt::expm(A, E) == 0);
        CHECK_ERR(rel_err(E, ref), 10 * tol);
    }

    // c2d: double integrator, Ad = [1, dt; 0, 1], Bd = b [dt^2/2; dt]
    for (double dt0 : {1e-3, 0.1, 1.0, 10.0})
        for (double b0 : {1.0, 1e6, 1e-6}) {
            Eigen::Matrix<S, 2, 2> A, Ad;
            Eigen::Matrix<S, 2, 1> B, Bd;
            A << S(0), S(1), S(0), S(0);
            B << S(0), S(b0);
            const S dt = S(dt0);
            const double h = double(dt), b = double(B(1));
            Md2 refA;
            refA << 1, h, 0, 1;
            const Eigen::Vector2d refB(b * h * h / 2, b * h);
            CHECK((gen_rt::c2d_zoh<S, 2, 1>(A, B, dt, Ad, Bd)) == 0);
            CHECK_ERR(rel_err(Ad, refA), tol / 10);
            CHECK_ERR(rel_err(Bd, refB), tol / 10);
        }

    // c2d: mass-spring-damper (see tests/c/test_expm.c for the closed form)
    for (double c : {0.0, 1.5, 6.0})
        for (double dt0 : {0.01, 0.1, 1.0, 3.0}) {
            RowMat<S, 2, 2> A, Ad;
            Eigen::Matrix<S, 2, 1> B, Bd;
            A << S(0), S(1), S(-25.0), S(-c / 2);
            B << S(0), S(0.5);
            const S dt = S(dt0);
            const double km = -double(A(1, 0)), cm = -double(A(1, 1)), im = double(B(1));
            const double h = double(dt), w0 = std::sqrt(km), s = cm / 2;
            const double wd = std::sqrt(w0 * w0 - s * s), e = std::exp(-s * h);
            const double co = std::cos(wd * h), si = std::sin(wd * h);
            Md2 refA;
            refA << e * (co + s / wd * si), e * si / wd, -e * w0 * w0 * si / wd,
                e * (co - s / wd * si);
            const Eigen::Vector2d refB((1 - refA(0, 0)) / km * im, refA(0, 1) * im);
            CHECK(gen_rt::c2d_zoh(A, B, dt, Ad, Bd) == 0);
            CHECK_ERR(rel_err(Ad, refA), tol * (h > 1 ? h : 1));
            CHECK_ERR(rel_err(Bd, refB), tol * (h > 1 ? h : 1));
        }

    // c2d with NR = 0: Ad = exp(A dt) of a diagonal A
    {
        Eigen::Matrix<S, 3, 3> A = Eigen::Matrix<S, 3, 3>::Zero(), Ad;
        const Eigen::Matrix<S, 3, 0> B;
        Eigen::Matrix<S, 3, 0> Bd;
        A.diagonal() << S(-4), S(0.25), S(1.5);
        CHECK(gen_rt::c2d_zoh(A, B, 0.5, Ad, Bd) == 0); // dt a double literal
        const Eigen::Vector3d want(std::exp(-2.0), std::exp(0.125), std::exp(0.75));
        CHECK_ERR(rel_err(Ad.diagonal(), want), tol);
        CHECK(Ad(0, 1) == S(0) && Ad(2, 0) == S(0));
    }

    // statuses; outputs untouched on failure
    {
        const S nan = std::numeric_limits<S>::quiet_NaN();
        const S inf = std::numeric_limits<S>::infinity();
        Eigen::Matrix<S, 2, 2> A, E, Ad;
        Eigen::Matrix<S, 2, 1> B, Bd;
        A << S(1), S(2), S(3), S(4);
        B << S(1), S(0);
        E.setConstant(S(7));
        Ad.setConstant(S(7));
        Bd.setConstant(S(7));
        Eigen::Matrix<S, 2, 2> bad = A;
        bad(1, 0) = nan;
        CHECK(gen_rt::expm(bad, E) == st::ERR_NONFINITE_INPUT);
        bad(1, 0) = -inf;
        CHECK(gen_rt::expm(bad, E) == st::ERR_NONFINITE_INPUT);
        bad << S(1000), S(0), S(0), S(1); // e^1000 overflows float and double
        CHECK(gen_rt::expm(bad, E) == st::ERR_DIVERGED);
        CHECK((E.array() == S(7)).all());
        bad(0, 0) = S(-1000); // underflows to 0: fine
        CHECK(gen_rt::expm(bad, E) == 0);
        CHECK(E(0, 0) == S(0));
        for (S dt : {S(0), S(-0.1), nan, inf, -inf})
            CHECK(gen_rt::c2d_zoh(A, B, dt, Ad, Bd) == st::ERR_BAD_ARG);
        bad = A;
        bad(0, 1) = nan;
        CHECK(gen_rt::c2d_zoh(bad, B, S(0.1), Ad, Bd) == st::ERR_NONFINITE_INPUT);
        Eigen::Matrix<S, 2, 1> Bbad = B;
        Bbad(1) = inf;
        CHECK(gen_rt::c2d_zoh(A, Bbad, S(0.1), Ad, Bd) == st::ERR_NONFINITE_INPUT);
        bad.setZero();
        bad(0, 0) = std::numeric_limits<S>::max(); // A dt overflows
        CHECK(gen_rt::c2d_zoh(bad, B, S(10), Ad, Bd) == st::ERR_DIVERGED);
        CHECK((Ad.array() == S(7)).all() && (Bd.array() == S(7)).all());
    }
}

#endif // TEST_EXPM_COMPARE_ONLY

// the comparison with scipy: reads a 5 x 5 A, a 3 x 3 A3, a 3 x 2 B3 and dt,
// prints the status and exp(A), then the status, Ad and Bd of the c2d, then
// the status and Ad of the c2d with NR = 0
template <class S>
int compare()
{
    Eigen::Matrix<S, 5, 5> A, E;
    RowMat<S, 3, 3> A3, Ad, Ad0;
    RowMat<S, 3, 2> B3, Bd;
    Eigen::Matrix<S, 3, 0> B0, Bd0;
    double v, dt;
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j) {
            if (std::scanf("%lf", &v) != 1) return 2;
            A(i, j) = S(v);
        }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            if (std::scanf("%lf", &v) != 1) return 2;
            A3(i, j) = S(v);
        }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 2; ++j) {
            if (std::scanf("%lf", &v) != 1) return 2;
            B3(i, j) = S(v);
        }
    if (std::scanf("%lf", &dt) != 1) return 2;
    int st1, st2, st3;
    {
        NoHeap no_heap;
        st1 = gen_rt::expm(A, E);
        st2 = gen_rt::c2d_zoh(A3, B3, S(dt), Ad, Bd);
        st3 = gen_rt::c2d_zoh(A3, B0, S(dt), Ad0, Bd0);
    }
    auto put = [](const auto &m) {
        for (int i = 0; i < m.rows(); ++i)
            for (int j = 0; j < m.cols(); ++j) std::printf(" %.17g", double(m(i, j)));
        std::printf("\n");
    };
    std::printf("%d", st1);
    put(E);
    std::printf("%d", st2);
    put(Ad);
    put(Bd);
    std::printf("%d", st3);
    put(Ad0);
    return 0;
}

} // namespace

int main(int argc, char **argv)
{
    if (argc > 1 && std::strcmp(argv[1], "compare") == 0) {
        const bool single = argc > 2 && std::strcmp(argv[2], "float") == 0;
        return single ? compare<float>() : compare<double>();
    }
#ifdef TEST_EXPM_COMPARE_ONLY
    std::fprintf(stderr, "built with TEST_EXPM_COMPARE_ONLY: only 'compare'\n");
    return 2;
#else
    closed_forms<double>();
    closed_forms<float>();
    std::printf("test_expm.cpp: %d checks, %d failed\n", checks, failures);
    return failures ? 1 : 0;
#endif
}
