// The typed C++ face of the Eigen backend (namespace pend_e: the seed Kane
// pendulum), double and float in one program, with heap allocation
// forbidden around every typed call:
// - double against the C backend of the same model (pend_c_*), bit for bit:
//   rhs, multipliers, linearize, an RK4 step, DOPRI5 and RODAS4 (advance and
//   simulate);
// - the physics: the hanging pendulum's A = [[0, 1], [-g/L, 0]] in both types;
// - statuses: NaN input, the singular partition, x unchanged on failure;
// - then prints, for both types, the rhs, multipliers, linearization and
//   DOPRI5/RODAS4 runs from one state as hex floats ("<type> <what> v ..."),
//   which tests/features/test_eigen.py compares bit for bit with the C backend built
//   for that type (float: the second copy in this library, pend_e_s_*).
// Exits 0 after printing "ok", or names each mismatch and exits 1.
#define EIGEN_RUNTIME_NO_MALLOC
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "pend_c.h"
#include "pend_e.hpp"

namespace pe = pend_e;

static int failures = 0;

static void expect(bool ok, const char *what, double value)
{
    if (!ok) {
        std::fprintf(stderr, "FAIL %s (%.17g)\n", what, value);
        ++failures;
    }
}

template <typename D>
static bool same_bits(const Eigen::MatrixBase<D> &a, const double *b)
{
    return std::memcmp(a.derived().data(), b, sizeof(double) * a.size()) == 0;
}

struct NoHeap {
    NoHeap() { Eigen::internal::set_is_malloc_allowed(false); }
    ~NoHeap() { Eigen::internal::set_is_malloc_allowed(true); }
};

template <typename S, typename D>
static void print(const char *type, const char *what, const Eigen::MatrixBase<D> &v)
{
    std::printf("%s %s", type, what);
    for (int i = 0; i < v.size(); ++i) std::printf(" %a", double(v.derived().data()[i]));
    std::printf("\n");
}

// The numbers tests/features/test_eigen.py checks against the C backend of type S.
template <typename S>
static void report(const char *type)
{
    pe::State<S> x;
    x << S(0.5), S(0.8), S(0.3), S(-0.1875);
    const pe::Params<S> p = pe::default_params<S>();
    const pe::Inputs<S> r;
    pe::State<S> dx;
    pe::Multipliers<S> lam;
    pe::StateMatrix<S> A;
    pe::InputMatrix<S> B;
    int st;
    {
        NoHeap guard;
        st = pe::consistent_state(S(0), p, S(0), 0, x);
        st |= pe::eval_rhs(S(0), x, r, p, dx, lam);
        st |= pe::linearize(x, r, p, S(0), A, B);
    }
    expect(st == pe::OK, "report: consistent_state, eval_rhs, linearize", st);
    print<S>(type, "x", x);
    print<S>(type, "rhs", dx);
    print<S>(type, "lam", lam);
    print<S>(type, "A", A);
    for (const int method : {pe::METHOD_DOPRI5, pe::METHOD_RODAS4}) {
        pe::SimOptions<S> o;
        o.method = method;
        o.rtol = S(1e-6);
        o.atol = S(1e-8);
        pe::SimStats<S> s;
        S t_out[11], x_out[11 * pe::NX];
        {
            NoHeap guard;
            st = pe::simulate(x, S(0), S(1), S(0.1), r, p, o, 11, t_out, x_out, nullptr, s);
        }
        expect(st == pe::OK && s.n_out == 11, "report: simulate", st);
        print<S>(type, method == pe::METHOD_DOPRI5 ? "dopri5" : "rodas4",
                 Eigen::Map<const Eigen::Matrix<S, 11 * pe::NX, 1>>(x_out));
    }
}

int main()
{
    static_assert(pe::NX == PEND_C_NX && pe::NS == PEND_C_NS && pe::MV == PEND_C_MV, "sizes");
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> angle(-1.3, 1.3), rate(-3.0, 3.0);
    const pe::Params<double> p = pe::default_params<double>();   // L, m, g
    const pe::Inputs<double> r;
    const double L = p[0], g = p[2];
    int differ = 0;

    for (int k = 0; k < 20; ++k) {
        const double th = angle(rng), thd = rate(rng);
        pe::State<double> x;   // [q2, q1, u2, u1] = [y, x, y', x'], gravity along +x
        x << L * std::sin(th), L * std::cos(th), L * std::cos(th) * thd, -L * std::sin(th) * thd;
        pe::State<double> dx, x4 = x;
        pe::Multipliers<double> lam;
        pe::StateMatrix<double> A;
        pe::InputMatrix<double> B;
        int st;
        for (const int method : {pe::METHOD_DOPRI5, pe::METHOD_RODAS4}) {
            pe::State<double> xs = x;
            pe::SimOptions<double> opts;
            opts.method = method;
            pe::SimStats<double> stats;
            {
                NoHeap guard;
                st = pe::advance(0.0, 0.2, r, p, opts, stats, xs);
            }
            double xc[PEND_C_NX];
            pend_c_sim_options oc;
            pend_c_sim_stats sc = pend_c_sim_stats();
            sc.terminal = -1;
            pend_c_sim_options_default(&oc);
            oc.method = method;
            for (int i = 0; i < PEND_C_NX; ++i) xc[i] = x[i];
            st |= pend_c_advance(0.0, 0.2, nullptr, p.data(), &oc, &sc, xc);
            expect(st == 0, "advance returns 0", st);
            differ += !same_bits(xs, xc);
            expect(stats.n_accepted == sc.n_accepted && stats.n_rhs == sc.n_rhs
                   && stats.n_jac == sc.n_jac, "same step, rhs and Jacobian counts",
                   double(stats.n_accepted));
        }
        {
            NoHeap guard;
            st = pe::eval_rhs(0.0, x, r, p, dx, lam);
            st |= pe::linearize(x, r, p, 0.0, A, B);
            st |= pe::step_rk4(0.0, 0.01, r, p, true, x4);
        }
        expect(st == pe::OK, "typed calls return OK", st);
        double dxc[PEND_C_NX], lamc[1], Ac[PEND_C_NS * PEND_C_NS], x4c[PEND_C_NX];
        for (int i = 0; i < PEND_C_NX; ++i) x4c[i] = x[i];
        st = pend_c_eval_rhs(0.0, x.data(), nullptr, p.data(), dxc, lamc);
        st |= pend_c_linearize(x.data(), nullptr, p.data(), 0.0, Ac, nullptr);
        st |= pend_c_step_rk4(0.0, 0.01, nullptr, p.data(), 1, x4c);
        expect(st == 0, "C calls return 0", st);
        differ += !same_bits(dx, dxc) + !same_bits(lam, lamc) + !same_bits(A, Ac)
                  + !same_bits(x4, x4c);

        // float: the same templates, the second copy of the model
        const pe::State<float> xf = x.cast<float>();
        const pe::Params<float> pf = pe::default_params<float>();
        pe::State<float> dxf;
        pe::StateMatrix<float> Af;
        pe::InputMatrix<float> Bf;
        {
            NoHeap guard;
            st = pe::eval_rhs(0.0f, xf, pe::Inputs<float>(), pf, dxf);
            st |= pe::linearize(xf, pe::Inputs<float>(), pf, 0.0f, Af, Bf);
        }
        expect(st == pe::OK, "float calls return OK", st);
        const double e = std::fmax((dxf.cast<double>() - dx).cwiseAbs().maxCoeff()
                                   / dx.cwiseAbs().maxCoeff(),
                                   (Af.cast<double>() - A).cwiseAbs().maxCoeff()
                                   / A.cwiseAbs().maxCoeff());
        expect(e < 1e-4, "float near double", e);
    }
    expect(differ == 0, "double face and C backend differ in bits (count)", differ);

    // physics: hanging at rest, A = [[0, 1], [-g/L, 0]], both types
    pe::State<double> hang;
    hang << 0.0, L, 0.0, 0.0;
    pe::StateMatrix<double> A, exact;
    pe::InputMatrix<double> B;
    exact << 0.0, 1.0, -g / L, 0.0;
    expect(pe::linearize(hang, r, p, 0.0, A, B) == pe::OK, "linearize hanging", 0);
    expect((A - exact).cwiseAbs().maxCoeff() < 1e-13, "hanging A (double)",
           (A - exact).cwiseAbs().maxCoeff());
    pe::StateMatrix<float> Af;
    pe::InputMatrix<float> Bf;
    expect(pe::linearize(pe::State<float>(hang.cast<float>()), pe::Inputs<float>(),
                         pe::default_params<float>(), 0.0f, Af, Bf) == pe::OK,
           "linearize hanging (float)", 0);
    expect((Af.cast<double>() - exact).cwiseAbs().maxCoeff() < 1e-5, "hanging A (float)",
           (Af.cast<double>() - exact).cwiseAbs().maxCoeff());

    // statuses: non-finite input, singular partition (q1 = 0), unchanged x on failure
    pe::State<double> bad = hang, dx = hang;
    bad[0] = std::nan("");
    expect(pe::eval_rhs(0.0, bad, r, p, dx) == pe::ERR_NONFINITE_INPUT, "NaN input status", 0);
    pe::State<double> sing;
    sing << 1.0, 0.0, 0.0, 1.0;
    const pe::State<double> sing0 = sing;
    const int s1 = pe::eval_rhs(0.0, sing, r, p, dx);
    expect(s1 == pe::ERR_SINGULAR || s1 == pe::ERR_NONFINITE_MODEL, "singular status", s1);
    const int s2 = pe::step_rk4(0.0, 0.01, r, p, true, sing);
    expect(s2 < 0 && sing == sing0, "failed step leaves x unchanged", s2);
    pe::State<float> singf = sing0.cast<float>();
    const int s3 = pe::step_rk4(0.0f, 0.01f, pe::Inputs<float>(), pe::default_params<float>(),
                                true, singf);
    expect(s3 < 0 && singf == sing0.cast<float>(), "float: failed step leaves x unchanged", s3);
    expect(std::string(pe::status_message(pe::ERR_SINGULAR)).find("singular") != std::string::npos,
           "status message", 0);

    report<double>("double");
    report<float>("float");
    if (failures) return 1;
    std::printf("ok: the double face equals the C backend bit for bit at 20 states\n");
    return 0;
}
