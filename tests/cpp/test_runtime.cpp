// Unit tests of the C++ runtime csrc/eigen/gen_rt_eigen.hpp alone, on two
// hand-written model traits (no generator):
//   Oscillator<IMPLICIT>: m q'' = -k q - c q' + r, one input, its energy,
//     explicit kinematics q' = u, or implicit ones 2 q' = 2 u (an LU solve);
//   Pendulum: a planar pendulum in x, y with x^2 + y^2 = L^2 and
//     x vx + y vy = 0 (Kane partition: x, vx independent; y, vy dependent),
//     gravity along -y.
// The simulation engine (RODAS4, DOPRI5's dense output, events) on the
// oscillator. Checked against closed forms, for double and float in one program, with
// heap allocation forbidden around every runtime call. Prints "ok" and exits
// 0, or names each failure and exits 1.
#define EIGEN_RUNTIME_NO_MALLOC
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "gen_rt_eigen.hpp"

namespace {

int failures = 0;

void expect(bool ok, const char *what, double value = 0)
{
    std::printf("%s %s (%.3g)\n", ok ? "pass" : "FAIL", what, value);
    if (!ok) ++failures;
}

struct NoHeap {
    NoHeap() { Eigen::internal::set_is_malloc_allowed(false); }
    ~NoHeap() { Eigen::internal::set_is_malloc_allowed(true); }
};

// the integration options and statistics (the generated header renders
// them from gen/abi.py; the runtime takes any struct with these fields)
template <class S>
struct Options {
    int method = gen_rt::METHOD_RK4;
    int project = 1;
    S rtol = S(1e-8), atol = S(1e-10), h_init = S(0), h_min = S(0), h_max = S(0);
    long max_steps = 100000;
    S proj_tol = 16 * gen_rt::Tolerances<S>::eps;
    int proj_max_iter = 10;
    int every = 1, final_only = 0;
    const int *cancel = nullptr;
};

template <class S, int NX>
struct Stats {
    long n_accepted = 0, n_rejected = 0, n_rhs = 0, n_jac = 0;
    int n_out = 0, n_events = 0, terminal = -1;
    S t_last = S(0), h_next = S(0);
    gen_rt::Mat<S, NX, 1> x_last = gen_rt::Mat<S, NX, 1>::Zero();
};

// p = [m, k, c]
template <bool IMPLICIT>
struct Oscillator {
    static constexpr int NQ = 1, NU = 1, NX = 2, NR = 1, NP = 3, MC = 0, MV = 0, NS = 2,
                         NQI = 1, NUI = 1;
    static constexpr bool HAS_ENERGY = true, EXPLICIT_KINEMATICS = !IMPLICIT;
    static constexpr gen_rt::Accel ACCEL = gen_rt::ACCEL_SPD;
    static constexpr int q_ind[1] = {0}, q_dep[1] = {0}, u_ind[1] = {0}, u_dep[1] = {0};

    template <class S> static void mass_matrix(const S *, const S *p, S, S *M) noexcept
    {
        M[0] = p[0];
    }
    template <class S>
    static void forcing(const S *q, const S *u, const S *r, const S *p, S, S *f) noexcept
    {
        f[0] = -p[1] * q[0] - p[2] * u[0] + r[0];
    }
    template <class S>
    static void kinematics(const S *, const S *u, const S *, S, S *Kqd, S *qd) noexcept
    {
        if constexpr (IMPLICIT) {
            Kqd[0] = S(2);
            qd[0] = S(2) * u[0];
        } else {
            qd[0] = u[0];
        }
    }
    template <class S>
    static void rhs_terms(const S *q, const S *u, const S *r, const S *p, S t, S *Kqd, S *qd,
                          S *M, S *f, S *, S *) noexcept
    {
        kinematics(q, u, p, t, Kqd, qd);
        mass_matrix(q, p, t, M);
        forcing(q, u, r, p, t, f);
    }
    template <class S> static void constraints(const S *, const S *, S, S *) noexcept {}
    template <class S> static void constraint_jacobian(const S *, const S *, S, S *, S *) noexcept {}
    template <class S> static void velocity_constraints(const S *, const S *, const S *, S, S *) noexcept {}
    template <class S> static void velocity_constraint_matrix(const S *, const S *, S, S *, S *) noexcept {}
    template <class S>
    static void energy(const S *q, const S *u, const S *p, S, S *E) noexcept
    {
        *E = S(0.5) * p[0] * u[0] * u[0] + S(0.5) * p[1] * q[0] * q[0];
    }
    // kinematic residual Kqd q' - kr, R = M u' - f
    template <class S>
    static void lin_terms(const S *, const S *, const S *, const S *, const S *, const S *,
                          const S *p, S, const gen_rt::LinOut<S> &o) noexcept
    {
        o.Kqd[0] = IMPLICIT ? S(2) : S(1);
        o.Ku[0] = IMPLICIT ? S(-2) : S(-1);
        o.M[0] = p[0];
        o.Kq[0] = S(0);
        o.Rq[0] = p[1];
        o.Ru[0] = p[2];
        o.Rr[0] = S(-1);
    }
};

// The oscillator with two auxiliary speeds: F R + g(q, u') = 0 with the
// constant F = [[2, 1], [1, 3]] (the singular [[1, 2], [2, 4]] when q > 100)
// and g = [m u', q]; closed form R = -F^-1 g, F^-1 = [[3, -1], [-1, 2]] / 5
struct AuxOscillator : Oscillator<false> {
    static constexpr int NA = 2;
    template <class S>
    static void auxiliary(const S *q, const S *, const S *ud, const S *, const S *p, S, S *F,
                          S *g) noexcept
    {
        const bool sing = q[0] > 100;
        F[0] = sing ? S(1) : S(2);
        F[1] = sing ? S(2) : S(1);
        F[2] = sing ? S(2) : S(1);
        F[3] = sing ? S(4) : S(3);
        g[0] = p[0] * ud[0];
        g[1] = q[0];
    }
};

void test_auxiliary()
{
    using RT = gen_rt::Runtime<AuxOscillator, double>;
    using RT0 = gen_rt::Runtime<Oscillator<false>, double>;
    static_assert(RT::NA == 2 && RT0::NA == 0, "NA from the traits type");
    typename RT::Params p;
    p << 1.5, 4, 0.4;
    typename RT::Inputs r;
    r << 0.7;
    typename RT::State x(0.3, -0.2);
    typename RT::AuxiliaryForces R;
    expect(RT::eval_auxiliary_forces(0.0, x, r, p, R) == gen_rt::OK, "auxiliary forces: OK");
    const double ud = (-4 * 0.3 - 0.4 * -0.2 + 0.7) / 1.5, g0 = 1.5 * ud, g1 = 0.3;
    expect(std::fabs(R[0] + (3 * g0 - g1) / 5) < 1e-14 &&
               std::fabs(R[1] + (-g0 + 2 * g1) / 5) < 1e-14,
           "auxiliary forces: -F^-1 g at u' from the right-hand side", R[0]);
    // a model without auxiliary speeds: OK, nothing written
    typename RT0::AuxiliaryForces none;
    expect(RT0::eval_auxiliary_forces(0.0, x, r, p, none) == gen_rt::OK,
           "auxiliary forces: NA = 0 is OK");
    // singular F, and a non-finite input, leave R as it was
    const typename RT::AuxiliaryForces before = R;
    x[0] = 200;
    expect(RT::eval_auxiliary_forces(0.0, x, r, p, R) == gen_rt::ERR_SINGULAR && R == before,
           "auxiliary forces: singular F reported, R unchanged");
    x[0] = std::numeric_limits<double>::quiet_NaN();
    expect(RT::eval_auxiliary_forces(0.0, x, r, p, R) == gen_rt::ERR_NONFINITE_INPUT &&
               R == before,
           "auxiliary forces: NaN state refused, R unchanged");
}

// p = [L, m, g]; q = [x, y], u = [vx, vy]
struct Pendulum {
    static constexpr int NQ = 2, NU = 2, NX = 4, NR = 0, NP = 3, MC = 1, MV = 1, NS = 2,
                         NQI = 1, NUI = 1;
    static constexpr bool HAS_ENERGY = true, EXPLICIT_KINEMATICS = true;
    static constexpr gen_rt::Accel ACCEL = gen_rt::ACCEL_PARTITIONED;
    static constexpr int q_ind[1] = {0}, q_dep[1] = {1}, u_ind[1] = {0}, u_dep[1] = {1};

    template <class S> static void mass_matrix(const S *, const S *p, S, S *M) noexcept
    {
        M[0] = p[1], M[1] = S(0), M[2] = S(0), M[3] = p[1];
    }
    template <class S>
    static void forcing(const S *, const S *, const S *, const S *p, S, S *f) noexcept
    {
        f[0] = S(0), f[1] = -p[1] * p[2];
    }
    template <class S>
    static void kinematics(const S *, const S *u, const S *, S, S *, S *qd) noexcept
    {
        qd[0] = u[0], qd[1] = u[1];
    }
    template <class S>
    static void rhs_terms(const S *q, const S *u, const S *r, const S *p, S t, S *Kqd, S *qd,
                          S *M, S *f, S *A, S *a) noexcept
    {
        kinematics(q, u, p, t, Kqd, qd);
        mass_matrix(q, p, t, M);
        forcing(q, u, r, p, t, f);
        A[0] = q[0], A[1] = q[1];
        a[0] = u[0] * u[0] + u[1] * u[1]; // d/dt (A u) = A u' + a
    }
    template <class S> static void constraints(const S *q, const S *p, S, S *fc) noexcept
    {
        fc[0] = q[0] * q[0] + q[1] * q[1] - p[0] * p[0];
    }
    template <class S>
    static void constraint_jacobian(const S *q, const S *p, S t, S *fc, S *Jc) noexcept
    {
        constraints(q, p, t, fc);
        Jc[0] = S(2) * q[0], Jc[1] = S(2) * q[1];
    }
    template <class S>
    static void velocity_constraints(const S *q, const S *u, const S *, S, S *fv) noexcept
    {
        fv[0] = q[0] * u[0] + q[1] * u[1];
    }
    template <class S>
    static void velocity_constraint_matrix(const S *q, const S *, S, S *A, S *b) noexcept
    {
        A[0] = q[0], A[1] = q[1], b[0] = S(0);
    }
    template <class S>
    static void energy(const S *q, const S *u, const S *p, S, S *E) noexcept
    {
        *E = S(0.5) * p[1] * (u[0] * u[0] + u[1] * u[1]) + p[1] * p[2] * q[1];
    }
    // R = M u' - f - A^T lam, S = A u' + a, V = A u + b
    template <class S>
    static void lin_terms(const S *q, const S *u, const S *, const S *ud, const S *lam,
                          const S *, const S *p, S, const gen_rt::LinOut<S> &o) noexcept
    {
        for (int i = 0; i < 4; ++i) {
            const bool diag = i == 0 || i == 3;
            o.Kqd[i] = diag ? S(1) : S(0);
            o.Ku[i] = diag ? S(-1) : S(0);
            o.M[i] = diag ? p[1] : S(0);
            o.Kq[i] = S(0);
            o.Rq[i] = diag ? -lam[0] : S(0);
            o.Ru[i] = S(0);
        }
        o.A[0] = q[0], o.A[1] = q[1];
        o.Sq[0] = ud[0], o.Sq[1] = ud[1];
        o.Su[0] = S(2) * u[0], o.Su[1] = S(2) * u[1];
        o.Vq[0] = u[0], o.Vq[1] = u[1];
        o.Jc[0] = S(2) * q[0], o.Jc[1] = S(2) * q[1];
    }
};

// ------------------------------------------------------------------ tests

void test_status()
{
    bool same = true;
#define CHECK_TEXT(name, value, text) \
    same = same && gen_rt::name == value && std::strcmp(gen_rt::status_message(value), text) == 0;
    GEN_RT_STATUS_TABLE(CHECK_TEXT)
#undef CHECK_TEXT
    expect(same, "status codes and messages are the table's");
    expect(std::strcmp(gen_rt::status_message(gen_rt::ERR_OUTPUT_FULL),
                       "the output buffer is too small") == 0,
           "ERR_OUTPUT_FULL message");
    expect(std::strcmp(gen_rt::status_message(-1000), "unknown status code") == 0 &&
               std::strcmp(gen_rt::status_message(1), GEN_RT_STATUS_UNKNOWN) == 0,
           "unknown status message");
}

void test_linalg()
{
    NoHeap guard;
    Eigen::Matrix3d a;
    a << 2, 1, -1, -3, -1, 2, -2, 1, 2;
    Eigen::Vector3d b(8, -11, -3), x = Eigen::Vector3d::Zero();
    int st = gen_rt::lu_solve(a, 0.0, b, x);
    expect(st == gen_rt::OK && (x - Eigen::Vector3d(2, 3, -1)).cwiseAbs().maxCoeff() < 1e-14,
           "lu_solve: known solution", (x - Eigen::Vector3d(2, 3, -1)).norm());
    Eigen::Matrix<double, 3, 2> B, X = Eigen::Matrix<double, 3, 2>::Zero();
    B << 8, 1, -11, 0, -3, 0;
    st = gen_rt::lu_solve(a, 0.0, B, X);
    expect(st == gen_rt::OK && ((a * X - B).cwiseAbs().maxCoeff() < 1e-13),
           "lu_solve: several right-hand sides", (a * X - B).norm());
    Eigen::Matrix3d s;
    s << 1, 2, 3, 2, 4, 6, 1, 0, 1; // rank 2
    expect(gen_rt::lu_solve(s, 0.0, b, x) == gen_rt::ERR_SINGULAR, "lu_solve: singular status");
    expect(gen_rt::lu_solve(Eigen::Matrix3d::Zero().eval(), 0.0, b, x) == gen_rt::ERR_SINGULAR,
           "lu_solve: zero matrix");
    Eigen::Matrix<double, 1, 1> one, y1 = Eigen::Matrix<double, 1, 1>::Zero();
    one << 1e-20;
    expect(gen_rt::lu_solve(one, 1.0, Eigen::Matrix<double, 1, 1>::Ones().eval(), y1) ==
               gen_rt::ERR_SINGULAR,
           "lu_solve 1x1: pivot below pivot_rtol * scale");
    Eigen::Matrix3d spd;
    spd << 4, 1, 0, 1, 3, 1, 0, 1, 2;
    st = gen_rt::spd_solve(spd, b, x);
    expect(st == gen_rt::OK && (spd * x - b).cwiseAbs().maxCoeff() < 1e-13, "spd_solve",
           (spd * x - b).norm());
    Eigen::Matrix3d indef = spd;
    indef(2, 2) = -2;
    expect(gen_rt::spd_solve(indef, b, x) == gen_rt::ERR_SINGULAR,
           "spd_solve: not positive definite is singular");
    // minimum-norm correction onto x0 + x1 = 1 from the origin: (0.5, 0.5)
    gen_rt::Mat<double, 1, 2> J;
    J << 1, 1;
    gen_rt::Mat<double, 1, 1> res;
    res << -1;
    gen_rt::Mat<double, 2, 1> v = gen_rt::Mat<double, 2, 1>::Zero();
    st = gen_rt::min_norm_correct<double, 1, 2>(J, res, v);
    expect(st == gen_rt::OK && std::abs(v[0] - 0.5) < 1e-15 && std::abs(v[1] - 0.5) < 1e-15,
           "min_norm_correct");
}

// closed form of the damped oscillator from q = 1, u = 0 (m = 1, k = 4, c = 0.4)
void exact(double t, double &q, double &u)
{
    const double a = 0.2, wd = std::sqrt(4.0 - a * a);
    q = std::exp(-a * t) * (std::cos(wd * t) + a / wd * std::sin(wd * t));
    u = -std::exp(-a * t) * (wd + a * a / wd) * std::sin(wd * t);
}

template <class Model, class S>
double rk4_error(int n)
{
    using RT = gen_rt::Runtime<Model, S>;
    typename RT::Params p;
    p << S(1), S(4), S(0.4);
    const typename RT::Inputs r = RT::Inputs::Zero();
    typename RT::State x(S(1), S(0));
    Options<S> o; // RK4, one step per advance
    Stats<S, RT::NX> stats;
    const S T = S(2), h = T / S(n);
    int st = 0;
    {
        NoHeap guard;
        for (int k = 0; k < n && !st; ++k)
            st = RT::advance(S(k) * h, S(k + 1) * h, r, p, o, stats, x);
    }
    if (st || stats.n_accepted != n || stats.n_rhs != 4L * n) return 1e300;
    double q, u;
    exact(2.0, q, u);
    return std::fmax(std::abs(double(x[0]) - q), std::abs(double(x[1]) - u));
}

template <class Model>
void test_oscillator(const char *tag)
{
    using RT = gen_rt::Runtime<Model, double>;
    char what[160];
    // RK4: order 4 from two step sizes
    const double e1 = rk4_error<Model, double>(40), e2 = rk4_error<Model, double>(80);
    const double order = std::log2(e1 / e2);
    std::snprintf(what, sizeof what, "%s: RK4 error at h = 0.05 (%.2e) and order ~4", tag, e1);
    expect(e1 < 1e-5 && order > 3.8 && order < 4.2, what, order);

    // DOPRI5 to T = 2 against the closed form, and the energy decay
    typename RT::Params p;
    p << 1, 4, 0.4;
    const typename RT::Inputs r = RT::Inputs::Zero();
    typename RT::State x(1.0, 0.0);
    Options<double> o;
    o.method = gen_rt::METHOD_DOPRI5;
    o.rtol = 1e-11;
    o.atol = 1e-13;
    Stats<double, 2> stats;
    double q, u, E0 = 0, E1 = 0;
    int st;
    {
        NoHeap guard;
        st = RT::eval_energy(x.template head<1>(), x.template tail<1>(), p, 0.0, E0);
        st |= RT::advance(0.0, 2.0, r, p, o, stats, x);
        st |= RT::eval_energy(x.template head<1>(), x.template tail<1>(), p, 2.0, E1);
    }
    exact(2.0, q, u);
    const double e = std::fmax(std::abs(x[0] - q), std::abs(x[1] - u));
    std::snprintf(what, sizeof what, "%s: DOPRI5 error vs closed form (%ld steps)", tag,
                  stats.n_accepted);
    expect(st == gen_rt::OK && e < 1e-9 && stats.t_last == 2.0 && stats.h_next > 0, what, e);
    std::snprintf(what, sizeof what, "%s: energy 0.5 u^2 + 2 q^2 (E0 = 2, E1 < E0)", tag);
    expect(E0 == 2.0 && E1 < E0 && E1 > 0, what, E1);

    // rhs and linearize: A = [[0, 1], [-k/m, -c/m]], B = [0; 1/m]
    typename RT::State xs(0.3, -0.7), dx = RT::State::Zero();
    typename RT::Inputs r1;
    r1 << 0.5;
    typename RT::StateMatrix A = RT::StateMatrix::Zero();
    typename RT::InputMatrix B = RT::InputMatrix::Zero();
    {
        NoHeap guard;
        st = RT::eval_rhs(0.0, xs, r1, p, dx, nullptr);
        st |= RT::linearize(xs, r1, p, 0.0, A, B);
    }
    const double e_rhs = std::fmax(std::abs(dx[0] + 0.7), std::abs(dx[1] - (-1.2 + 0.28 + 0.5)));
    std::snprintf(what, sizeof what, "%s: rhs", tag);
    expect(st == gen_rt::OK && e_rhs < 1e-15, what, e_rhs);
    typename RT::StateMatrix Ae;
    Ae << 0, 1, -4, -0.4;
    const double e_lin = std::fmax((A - Ae).cwiseAbs().maxCoeff(), std::abs(B[0]) + std::abs(B[1] - 1));
    std::snprintf(what, sizeof what, "%s: linearize A, B", tag);
    expect(e_lin < 1e-15, what, e_lin);

    // simulate: rows, the last row clipped to t_end, the states of advance
    double t_out[8], x_out[16];
    Stats<double, 2> ss;
    o.method = gen_rt::METHOD_RK4;
    {
        NoHeap guard;
        st = RT::simulate(typename RT::State(1.0, 0.0), 0.0, 0.25, 0.04, r, p, o, 8, t_out,
                          x_out, nullptr, ss);
    }
    exact(0.25, q, u);
    std::snprintf(what, sizeof what, "%s: simulate rows (8, the last at t_end)", tag);
    expect(st == gen_rt::OK && RT::simulate_rows(0.0, 0.25, 0.04) == 8 && ss.n_out == 8 &&
               std::abs(t_out[6] - 0.24) < 1e-15 && t_out[7] == 0.25 && std::abs(x_out[14] - q) < 1e-6,
           what, ss.n_out);
    expect(RT::simulate(typename RT::State(1.0, 0.0), 0.0, 0.25, 0.04, r, p, o, 7, t_out, x_out,
                        nullptr, ss) == gen_rt::ERR_OUTPUT_FULL,
           "simulate: capacity too small");
    expect(RT::simulate_rows(0.0, 1.0, 0.0) == gen_rt::ERR_BAD_ARG, "simulate_rows: dt = 0");
    // statuses: non-finite input, bad method, no constraints to project on
    typename RT::State bad(std::nan(""), 0.0);
    expect(RT::eval_rhs(0.0, bad, r, p, dx, nullptr) == gen_rt::ERR_NONFINITE_INPUT,
           "NaN input status");
    o.method = 7;
    expect(RT::advance(0.0, 1.0, r, p, o, stats, xs) == gen_rt::ERR_BAD_ARG, "unknown method");
    typename RT::State xp = xs;
    expect(RT::project(0.0, p, 0.0, 0, xp) == gen_rt::OK && xp == xs,
           "project without constraints: identity");
}

void test_float()
{
    // the float instantiation of the same runtime, in the same program
    using Model = Oscillator<false>;
    using RT = gen_rt::Runtime<Model, float>;
    RT::Params p;
    p << 1.0f, 4.0f, 0.4f;
    RT::State x(1.0f, 0.0f);
    Options<float> o;
    o.method = gen_rt::METHOD_DOPRI5;
    o.rtol = 1e-6f;
    o.atol = 1e-7f;
    Stats<float, 2> stats;
    int st;
    {
        NoHeap guard;
        st = RT::advance(0.0f, 2.0f, RT::Inputs::Zero(), p, o, stats, x);
    }
    double q, u;
    exact(2.0, q, u);
    const double e = std::fmax(std::abs(x[0] - q), std::abs(x[1] - u));
    expect(st == gen_rt::OK && e < 1e-4, "float: DOPRI5 error vs closed form", e);
    const double e4 = rk4_error<Model, float>(40);
    expect(e4 < 1e-4, "float: RK4 error at h = 0.05", e4);
}

void test_pendulum()
{
    using RT = gen_rt::Runtime<Pendulum, double>;
    const double L = 1.5, m = 2.0, g = 9.81;
    RT::Params p(L, m, g);
    // projection onto x^2 + y^2 = L^2 and x vx + y vy = 0, idempotent
    RT::State x;
    x << 0.4, -1.3, 0.8, 0.5;
    RT::State xp = x, xpp = x;
    RT::ConfigResiduals fc = RT::ConfigResiduals::Zero();
    RT::Multipliers fv = RT::Multipliers::Zero();
    int st;
    {
        NoHeap guard;
        st = RT::project(0.0, p, 0.0, 0, xp);
        xpp = xp;
        st |= RT::project(0.0, p, 0.0, 0, xpp);
        st |= RT::eval_constraints(xp.head<2>(), p, 0.0, fc);
        st |= RT::eval_velocity_constraints(xp.head<2>(), xp.tail<2>(), p, 0.0, fv);
    }
    expect(st == gen_rt::OK && std::abs(fc[0]) < 1e-12 && std::abs(fv[0]) < 1e-12,
           "project: on the constraints", std::fmax(std::abs(fc[0]), std::abs(fv[0])));
    expect((xpp - xp).cwiseAbs().maxCoeff() < 1e-15, "project: idempotent",
           (xpp - xp).cwiseAbs().maxCoeff());
    // the speeds: the orthogonal projection onto the tangent of the projected q
    const Eigen::Vector2d qp = xp.head<2>(), u0 = x.tail<2>();
    const Eigen::Vector2d ut = u0 - qp * (qp.dot(u0) / qp.squaredNorm());
    expect((xp.tail<2>() - ut).cwiseAbs().maxCoeff() < 1e-14, "project: speeds made tangential",
           (xp.tail<2>() - ut).cwiseAbs().maxCoeff());

    // consistent_state keeps the independent x, vx; y < 0 branch from the guess
    RT::State xc;
    xc << 0.9, -1.0, 0.6, 0.0;
    {
        NoHeap guard;
        st = RT::consistent_state(0.0, p, 0.0, 0, xc);
    }
    const double yc = -std::sqrt(L * L - 0.81), vyc = -0.9 * 0.6 / yc;
    expect(st == gen_rt::OK && xc[0] == 0.9 && xc[2] == 0.6 && std::abs(xc[1] - yc) < 1e-14 &&
               std::abs(xc[3] - vyc) < 1e-14,
           "consistent_state: y, vy solved", std::abs(xc[1] - yc));

    // hanging at rest: u' = 0, lam = -m g / L (A^T lam holds the weight)
    RT::State hang(0.0, -L, 0.0, 0.0), dx = RT::State::Zero();
    RT::Multipliers lam = RT::Multipliers::Zero();
    RT::StateMatrix A = RT::StateMatrix::Zero();
    RT::InputMatrix B;
    {
        NoHeap guard;
        st = RT::eval_rhs(0.0, hang, RT::Inputs(), p, dx, &lam);
        st |= RT::linearize(hang, RT::Inputs(), p, 0.0, A, B);
    }
    expect(st == gen_rt::OK && dx.cwiseAbs().maxCoeff() < 1e-15 &&
               std::abs(lam[0] + m * g / L) < 1e-13,
           "hanging at rest: rhs and multiplier", lam[0]);
    RT::StateMatrix Ae;
    Ae << 0, 1, -g / L, 0;
    expect((A - Ae).cwiseAbs().maxCoeff() < 1e-13, "hanging: A = [[0, 1], [-g/L, 0]]",
           (A - Ae).cwiseAbs().maxCoeff());

    // moving: the accelerations keep the second derivative of the constraint
    // x x'' + y y'' + v^2 = 0, and the angle obeys the pendulum equation
    RT::State mv;
    const double th = 0.7, w = 1.9;
    mv << L * std::sin(th), -L * std::cos(th), L * std::cos(th) * w, L * std::sin(th) * w;
    {
        NoHeap guard;
        st = RT::eval_rhs(0.0, mv, RT::Inputs(), p, dx, &lam);
    }
    const double acc = mv[0] * dx[2] + mv[1] * dx[3] + mv[2] * mv[2] + mv[3] * mv[3];
    const double thdd = -g / L * std::sin(th); // the pendulum equation
    const double tang = (std::cos(th) * dx[2] + std::sin(th) * dx[3]) / L;
    expect(st == gen_rt::OK && std::abs(acc) < 1e-12 && std::abs(tang - thdd) < 1e-12,
           "moving: accelerations on the circle, theta'' = -g/L sin theta",
           std::fmax(std::abs(acc), std::abs(tang - thdd)));

    // DOPRI5 with projection: the energy and the constraints hold
    Options<double> o;
    o.method = gen_rt::METHOD_DOPRI5;
    o.rtol = 1e-10;
    o.atol = 1e-12;
    Stats<double, 4> stats;
    double E0 = 0, E1 = 0;
    RT::State xs = mv;
    {
        NoHeap guard;
        st = RT::eval_energy(xs.head<2>(), xs.tail<2>(), p, 0.0, E0);
        st |= RT::advance(0.0, 3.0, RT::Inputs(), p, o, stats, xs);
        st |= RT::eval_energy(xs.head<2>(), xs.tail<2>(), p, 3.0, E1);
        st |= RT::eval_constraints(xs.head<2>(), p, 3.0, fc);
    }
    expect(st == gen_rt::OK && std::abs(E1 - E0) < 1e-8 * std::abs(E0) && std::abs(fc[0]) < 1e-13,
           "DOPRI5 + projection: energy and constraint kept", std::abs(E1 - E0));

    // the partition is singular at y = 0 (y dependent); a failed step leaves x unchanged
    RT::State side(L, 0.0, 0.0, 1.0);
    const RT::State side0 = side;
    expect(RT::eval_rhs(0.0, side, RT::Inputs(), p, dx, nullptr) == gen_rt::ERR_SINGULAR,
           "singular partition status");
    expect(RT::step_rk4(0.0, 0.01, RT::Inputs(), p, true, side) == gen_rt::ERR_SINGULAR &&
               side == side0,
           "failed step leaves x unchanged");
    // Newton without convergence budget: one iteration from far away
    RT::State far(3.0, -4.0, 0.0, 0.0);
    expect(RT::project(0.0, p, 1e-300, 1, far) == gen_rt::ERR_NO_CONVERGENCE &&
               far == RT::State(3.0, -4.0, 0.0, 0.0),
           "project: no convergence, x unchanged");
}


// the simulation engine: RODAS4 with the model Jacobian, the dense output
// of DOPRI5, and a terminal event located on it (the oscillator's closed form)
void test_engine()
{
    using RT = gen_rt::Runtime<Oscillator<false>, double>;
    typename RT::Params p;
    p << 1, 4, 0.4;
    const typename RT::Inputs r = RT::Inputs::Zero();
    double q, u;
    exact(2.0, q, u);
    // RODAS4 by advance: the closed form, one Jacobian per accepted step
    typename RT::State x(1.0, 0.0);
    Options<double> o;
    o.method = gen_rt::METHOD_RODAS4;
    o.rtol = 1e-9;
    o.atol = 1e-11;
    Stats<double, 2> stats;
    int st;
    {
        NoHeap guard;
        st = RT::advance(0.0, 2.0, r, p, o, stats, x);
    }
    double e = std::fmax(std::abs(x[0] - q), std::abs(x[1] - u));
    expect(st == gen_rt::OK && e < 1e-7 && stats.n_jac == stats.n_accepted && stats.n_jac > 10,
           "RODAS4: error vs closed form, one Jacobian per step", e);
    // DOPRI5 rows every 0.25 from the continuous extension, steps by error alone
    double t_out[9], x_out[18];
    Stats<double, 2> ss;
    o.method = gen_rt::METHOD_DOPRI5;
    o.rtol = 1e-10;
    o.atol = 1e-12;
    {
        NoHeap guard;
        st = RT::simulate(typename RT::State(1.0, 0.0), 0.0, 2.0, 0.25, r, p, o, 9, t_out, x_out,
                          nullptr, ss);
    }
    e = 0;
    for (int k = 0; k < 9; ++k) {
        exact(t_out[k], q, u);
        e = std::fmax(e, std::fmax(std::abs(x_out[2 * k] - q), std::abs(x_out[2 * k + 1] - u)));
    }
    expect(st == gen_rt::OK && ss.n_out == 9 && t_out[8] == 2.0 && e < 1e-8 &&
               ss.n_accepted > 9 && ss.n_jac == 0,
           "DOPRI5 dense output rows vs closed form", e);
    // the first downward zero of q, terminal: t = (pi - atan(wd / a)) / wd
    const double a = 0.2, wd = std::sqrt(4.0 - a * a);
    const double tz = (std::acos(-1.0) - std::atan(wd / a)) / wd;
    const int which[1] = {0}, dir[1] = {-1}, term[1] = {1};
    int log_which[2] = {-1, -1};
    double log_t[2] = {0, 0}, log_x[4] = {0, 0, 0, 0};
    gen_rt::BasicEvents<double> ev;
    ev.n = 1;
    ev.which = which;
    ev.direction = dir;
    ev.terminal = term;
    ev.capacity = 2;
    ev.log_which = log_which;
    ev.log_t = log_t;
    ev.log_x = log_x;
    gen_rt::BasicInput<double> in;
    for (int method : {gen_rt::METHOD_DOPRI5, gen_rt::METHOD_RODAS4, gen_rt::METHOD_RK4}) {
        Stats<double, 2> se;
        o.method = method;
        {
            NoHeap guard;
            st = RT::simulate_events(typename RT::State(1.0, 0.0), 0.0, 2.0, 0.25, in, ev, p, o,
                                     9, t_out, x_out, nullptr, nullptr, se);
        }
        const double tol = method == gen_rt::METHOD_RK4 ? 2e-3 : 1e-8; // RK4: h = 0.25
        char what[120];
        std::snprintf(what, sizeof what, "event (method %d): terminal at the zero of q, last row",
                      method);
        expect(st == gen_rt::OK && se.n_events == 1 && se.terminal == 0 && log_which[0] == 0 &&
                   std::abs(log_t[0] - tz) < tol && std::abs(log_x[0]) < tol &&
                   se.n_out == 5 && t_out[4] == log_t[0] && x_out[8] == log_x[0] &&
                   se.t_last == log_t[0],
               what, log_t[0] - tz);
    }
    // bad event descriptions
    Stats<double, 2> sb;
    const int bad_which[1] = {2};
    ev.which = bad_which;
    expect(RT::simulate_events(typename RT::State(1.0, 0.0), 0.0, 2.0, 0.25, in, ev, p, o, 9,
                               t_out, x_out, nullptr, nullptr, sb) == gen_rt::ERR_BAD_ARG,
           "event on a state that does not exist: ERR_BAD_ARG");
    // float: the same engine in single precision
    using RTf = gen_rt::Runtime<Oscillator<false>, float>;
    typename RTf::State xf(1.0f, 0.0f);
    Options<float> of;
    of.method = gen_rt::METHOD_RODAS4;
    of.rtol = 1e-5f;
    of.atol = 1e-6f;
    Stats<float, 2> sf;
    {
        NoHeap guard;
        st = RTf::advance(0.0f, 2.0f, RTf::Inputs::Zero(), RTf::Params(1.0f, 4.0f, 0.4f), of, sf,
                          xf);
    }
    exact(2.0, q, u);
    e = std::fmax(std::abs(xf[0] - q), std::abs(xf[1] - u));
    expect(st == gen_rt::OK && e < 1e-3, "float: RODAS4 error vs closed form", e);
}
} // namespace

int main()
{
    test_status();
    test_linalg();
    test_oscillator<Oscillator<false>>("oscillator");
    test_oscillator<Oscillator<true>>("oscillator, implicit kinematics");
    test_float();
    test_pendulum();
    test_auxiliary();
    test_engine();
    if (failures) {
        std::printf("%d failures\n", failures);
        return 1;
    }
    std::printf("ok\n");
    return 0;
}
