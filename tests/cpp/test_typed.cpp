// The typed C++ API of the Eigen backend (namespace pend_e: the seed Kane
// pendulum), for double and float, against the C backend of the same model
// (pend_c_*), with heap allocation forbidden around every typed call.
// Prints "ok" and exits 0, or names each mismatch and exits 1.
#define EIGEN_RUNTIME_NO_MALLOC
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "pend_c.h"
#include "pend_e.hpp"

namespace pe = pend_e;

static int failures = 0;

static void expect(bool ok, const char *what, double value)
{
    if (!ok) {
        std::fprintf(stderr, "FAIL %s (%.3g)\n", what, value);
        ++failures;
    }
}

template <typename A, typename B>
static double rel(const A &a, const B &b)
{
    const double scale = b.cwiseAbs().maxCoeff();
    const double d = (a - b).cwiseAbs().maxCoeff();
    return scale > 0 ? d / scale : d;
}

struct NoHeap {
    NoHeap() { Eigen::internal::set_is_malloc_allowed(false); }
    ~NoHeap() { Eigen::internal::set_is_malloc_allowed(true); }
};

int main()
{
    static_assert(pe::NX == PEND_C_NX && pe::NS == PEND_C_NS && pe::MV == PEND_C_MV, "sizes");
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> angle(-1.3, 1.3), rate(-3.0, 3.0);
    const pe::Params<double> p = pe::default_params<double>();   // L, m, g
    const pe::Inputs<double> r;
    const double L = p[0], g = p[2];
    double worst_d = 0, worst_f = 0;

    for (int k = 0; k < 20; ++k) {
        const double th = angle(rng), thd = rate(rng);
        pe::State<double> x;   // [q2, q1, u2, u1] = [y, x, y', x'], gravity along +x
        x << L * std::sin(th), L * std::cos(th), L * std::cos(th) * thd, -L * std::sin(th) * thd;
        pe::State<double> dx = pe::State<double>::Zero(), xs = x;
        pe::Multipliers<double> lam = pe::Multipliers<double>::Zero();
        pe::StateMatrix<double> A = pe::StateMatrix<double>::Zero();
        pe::InputMatrix<double> B;
        pe::SimOptions<double> opts;
        opts.method = pe::METHOD_DOPRI5;
        pe::SimStats<double> stats;
        int st;
        {
            NoHeap guard;
            st = pe::eval_rhs(0.0, x, r, p, dx, lam);
            st |= pe::linearize(x, r, p, 0.0, A, B);
            st |= pe::advance(0.0, 0.2, r, p, opts, stats, xs);
        }
        expect(st == pe::OK, "typed calls return OK", st);

        double dxc[PEND_C_NX], lamc[1], Ac[PEND_C_NS * PEND_C_NS];
        double xc[PEND_C_NX];
        pend_c_sim_options oc;
        pend_c_sim_stats sc = pend_c_sim_stats();
        pend_c_sim_options_default(&oc);
        oc.method = PEND_C_METHOD_DOPRI5;
        for (int i = 0; i < PEND_C_NX; ++i) xc[i] = x[i];
        st = pend_c_eval_rhs(0.0, x.data(), nullptr, p.data(), dxc, lamc);
        st |= pend_c_linearize(x.data(), nullptr, p.data(), 0.0, Ac, nullptr);
        st |= pend_c_advance(0.0, 0.2, nullptr, p.data(), &oc, &sc, xc);
        expect(st == 0, "C calls return 0", st);

        const double e_rhs = rel(dx, Eigen::Map<const pe::State<double>>(dxc));
        const double e_lam = rel(lam, Eigen::Map<const pe::Multipliers<double>>(lamc));
        const double e_lin = rel(A, Eigen::Map<const pe::StateMatrix<double>>(Ac));
        const double e_adv = rel(xs, Eigen::Map<const pe::State<double>>(xc));
        worst_d = std::fmax(worst_d, std::fmax(std::fmax(e_rhs, e_lam), std::fmax(e_lin, e_adv)));
        expect(stats.n_accepted == sc.n_accepted, "same DOPRI5 step count", double(stats.n_accepted));

        // float: the same template, single precision
        const pe::State<float> xf = x.cast<float>();
        const pe::Params<float> pf = pe::default_params<float>();
        pe::State<float> dxf = pe::State<float>::Zero();
        pe::StateMatrix<float> Af = pe::StateMatrix<float>::Zero();
        pe::InputMatrix<float> Bf;
        {
            NoHeap guard;
            st = pe::eval_rhs(0.0f, xf, pe::Inputs<float>(), pf, dxf);
            st |= pe::linearize(xf, pe::Inputs<float>(), pf, 0.0f, Af, Bf);
        }
        expect(st == pe::OK, "float calls return OK", st);
        worst_f = std::fmax(worst_f, std::fmax(rel(dxf.cast<double>(), dx),
                                               rel(Af.cast<double>(), A)));
    }
    expect(worst_d < 1e-13, "typed double vs C backend", worst_d);
    expect(worst_f < 1e-4, "typed float vs double", worst_f);

    // physics: hanging at rest, A = [[0, 1], [-g/L, 0]]
    pe::State<double> hang;
    hang << 0.0, L, 0.0, 0.0;
    pe::StateMatrix<double> A = pe::StateMatrix<double>::Zero();
    pe::InputMatrix<double> B;
    expect(pe::linearize(hang, r, p, 0.0, A, B) == pe::OK, "linearize hanging", 0);
    pe::StateMatrix<double> exact;
    exact << 0.0, 1.0, -g / L, 0.0;
    expect(rel(A, exact) < 1e-13, "hanging A = [[0, 1], [-g/L, 0]]", rel(A, exact));

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
    expect(std::string(pe::status_message(pe::ERR_SINGULAR)).find("singular") != std::string::npos,
           "status message", 0);

    std::printf("typed API: max rel err vs C backend %.2e (double), float vs double %.2e\n",
                worst_d, worst_f);
    if (failures) return 1;
    std::printf("ok\n");
    return 0;
}
