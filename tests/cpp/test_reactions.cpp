// The typed C++ face of a model whose reaction enters its motion
// (namespace bead_e: tests/physics/test_reactions_coupled.py's bead on a curved
// track, the normal force N solved with omega'), double and float in one
// program, heap allocation forbidden around every typed call:
// - for each state on stdin ("theta omega F" per line) prints, for both
//   types, x' (eval_rhs), N (eval_auxiliary_forces) and the linearization
//   (A, B) as hex floats ("<type> <what> v ..."), which the Python test
//   compares with Newton's law solved by sympy;
// - at the vertical (theta = pi/2) both functions must return
//   ERR_SINGULAR_REACTIONS and leave their outputs unwritten.
// Exits 0 after printing "ok", or names each failure and exits 1.
#define EIGEN_RUNTIME_NO_MALLOC
#include <cmath>
#include <cstdio>

#include "bead_e.hpp"

namespace be = bead_e;

static int failures = 0;

static void expect(bool ok, const char *what)
{
    if (!ok) {
        std::fprintf(stderr, "FAIL %s\n", what);
        ++failures;
    }
}

struct NoHeap {
    NoHeap() { Eigen::internal::set_is_malloc_allowed(false); }
    ~NoHeap() { Eigen::internal::set_is_malloc_allowed(true); }
};

template <typename D>
static void print(const char *type, const char *what, int k, const Eigen::MatrixBase<D> &v)
{
    std::printf("%s %s %d", type, what, k);
    for (int i = 0; i < v.size(); ++i) std::printf(" %a", double(v.derived().data()[i]));
    std::printf("\n");
}

template <typename S>
static void at(const char *type, int k, double th, double w, double F)
{
    be::State<S> x, dx;
    be::Inputs<S> r;
    be::AuxiliaryForces<S> N;
    be::StateMatrix<S> A;
    be::InputMatrix<S> B;
    const be::Params<S> p = be::default_params<S>();
    x << S(th), S(w);
    r << S(F);
    int s1, s2, s3;
    {
        NoHeap guard;
        s1 = be::eval_rhs(S(0), x, r, p, dx);
        s2 = be::eval_auxiliary_forces(S(0), x, r, p, N);
        s3 = be::linearize(x, r, p, S(0), A, B);
    }
    expect(s1 == 0 && s2 == 0 && s3 == 0, "a regular state");
    print(type, "rhs", k, dx);
    print(type, "N", k, N);
    print(type, "A", k, A);
    print(type, "B", k, B);
}

template <typename S>
static void singular(void)
{
    be::State<S> x, dx;
    be::Inputs<S> r;
    be::AuxiliaryForces<S> N;
    const be::Params<S> p = be::default_params<S>();
    x << S(std::acos(-1.0) / 2), S(1);
    r << S(0);
    dx.setConstant(S(7));
    N.setConstant(S(7));
    NoHeap guard;
    expect(be::eval_rhs(S(0), x, r, p, dx) == be::ERR_SINGULAR_REACTIONS, "rhs singular status");
    expect(be::eval_auxiliary_forces(S(0), x, r, p, N) == be::ERR_SINGULAR_REACTIONS,
           "eval_auxiliary_forces singular status");
    expect(dx(0) == S(7) && dx(1) == S(7) && N(0) == S(7), "outputs unwritten on failure");
}

int main()
{
    double th, w, F;
    int k = 0;
    while (std::scanf("%lf %lf %lf", &th, &w, &F) == 3) {
        at<double>("double", k, th, w, F);
        at<float>("float", k, th, w, F);
        ++k;
    }
    singular<double>();
    singular<float>();
    if (failures) return 1;
    std::printf("ok\n");
    return 0;
}
