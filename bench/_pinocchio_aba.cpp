// Pinocchio's articulated body algorithm timed in C++, for
// bench/bench_recursive.py (built and run by bench/_pinocchio_cpp.py).
//
// The model comes on standard input, written by _pinocchio_cpp.model_text
// from the Python `pin` model itself (so the two are the same tree, to the
// last bit of every parameter):
//
//   njoints                       (joints past the universe)
//   per joint: kind [a0 a1 a2] parent R00 R01 R02 R10 .. R22 t0 t1 t2
//              mass c0 c1 c2 I00 I01 I02 I10 .. I22
//     (kind: JointModelRX/RY/RZ/PX/PY/PZ, RUBX/RUBY/RUBZ, FreeFlyer,
//      Spherical, or RevoluteUnaligned/PrismaticUnaligned followed by the
//      axis a; R, t: the joint's placement in its parent; mass, c, I: the
//      joint's body, inertia about c)
//   g0 g1 g2                      (model.gravity.linear)
//   q (nq)  v (nv)  tau (nv)
//   iters reps
//
// It prints "ddq" and aba's result at (q, v, tau) (%.17g), then per repeat
// "aba <seconds per call>": iters calls of aba from the initial state, each
// after moving x[1] of x = (q, v) by 1e-12 and adding ddq's last entry to a
// volatile sink, as bench/_cdriver.py's driver times <name>_eval_rhs.
//
// Built two ways (bench/_pinocchio_cpp.py): header-only, every template
// instantiated here with the flags given (by default -O2 -DNDEBUG, the C
// driver's -O2); or with -DPINBENCH_SHIPPED and
// PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION, calling the aba instance that
// libpinocchio_default.so ships (the one the Python binding calls).
#include <time.h>

#include <cstdio>
#include <iostream>
#include <string>

#include "pinocchio/multibody.hpp"
#include "pinocchio/algorithm/aba.hpp"

static double now() {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void read(std::istream &in, double *p, int k);

// kinds with an axis (RevoluteUnaligned, PrismaticUnaligned) read it next
static pinocchio::JointModel joint_of(const std::string &kind, std::istream &in) {
    using namespace pinocchio;
    if (kind == "JointModelRX") return JointModelRX();
    if (kind == "JointModelRY") return JointModelRY();
    if (kind == "JointModelRZ") return JointModelRZ();
    if (kind == "JointModelPX") return JointModelPX();
    if (kind == "JointModelPY") return JointModelPY();
    if (kind == "JointModelPZ") return JointModelPZ();
    if (kind == "JointModelRUBX") return JointModelRUBX();
    if (kind == "JointModelRUBY") return JointModelRUBY();
    if (kind == "JointModelRUBZ") return JointModelRUBZ();
    if (kind == "JointModelFreeFlyer") return JointModelFreeFlyer();
    if (kind == "JointModelSpherical") return JointModelSpherical();
    if (kind == "JointModelRevoluteUnaligned" || kind == "JointModelPrismaticUnaligned") {
        double a[3];
        read(in, a, 3);
        Eigen::Vector3d axis(a[0], a[1], a[2]);
        if (kind == "JointModelRevoluteUnaligned") return JointModelRevoluteUnaligned(axis);
        return JointModelPrismaticUnaligned(axis);
    }
    throw std::runtime_error("joint kind not taken by the driver: " + kind);
}

static void read(std::istream &in, double *p, int k) {
    for (int i = 0; i < k; ++i)
        if (!(in >> p[i])) throw std::runtime_error("short input");
}

int main() try {
    std::istream &in = std::cin;
    pinocchio::Model model;
    int nj;
    if (!(in >> nj)) throw std::runtime_error("no joint count");
    for (int j = 0; j < nj; ++j) {
        std::string kind;
        int parent;
        double R[9], t[3], m, c[3], I[9];
        if (!(in >> kind)) throw std::runtime_error("short input");
        pinocchio::JointModel jm = joint_of(kind, in);
        if (!(in >> parent)) throw std::runtime_error("short input");
        read(in, R, 9);
        read(in, t, 3);
        read(in, &m, 1);
        read(in, c, 3);
        read(in, I, 9);
        Eigen::Matrix3d Rm, Im;
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                Rm(a, b) = R[3 * a + b];
                Im(a, b) = I[3 * a + b];
            }
        pinocchio::SE3 place(Rm, Eigen::Vector3d(t[0], t[1], t[2]));
        pinocchio::JointIndex id = model.addJoint(
            (pinocchio::JointIndex)parent, jm, place, "J" + std::to_string(j));
        model.appendBodyToJoint(id, pinocchio::Inertia(m, Eigen::Vector3d(c[0], c[1], c[2]), Im),
                                pinocchio::SE3::Identity());
    }
    double g[3];
    read(in, g, 3);
    model.gravity.linear(Eigen::Vector3d(g[0], g[1], g[2]));
    const int nq = model.nq, nv = model.nv;
    Eigen::VectorXd q0(nq), v0(nv), tau(nv);
    read(in, q0.data(), nq);
    read(in, v0.data(), nv);
    read(in, tau.data(), nv);
    long iters;
    int reps;
    if (!(in >> iters >> reps)) throw std::runtime_error("no iters/reps");

    pinocchio::Data data(model);
    Eigen::VectorXd q = q0, v = v0;
    // the state entry the C driver moves: x[1] of x = (q, v)
    double *moved = nq > 1 ? &q[1] : &v[1 - nq];
#ifdef PINBENCH_SHIPPED
    typedef Eigen::Ref<const Eigen::VectorXd> CRef;
    const CRef qr(q), vr(v), taur(tau);
#define ABA() pinocchio::aba(model, data, qr, vr, taur)
#else
#define ABA() pinocchio::aba(model, data, q, v, tau)
#endif
    ABA();
    std::printf("ddq");
    for (int i = 0; i < nv; ++i) std::printf(" %.17g", data.ddq[i]);
    std::printf("\n");
    volatile double sink = 0;
    for (int rep = 0; rep < reps; ++rep) {
        q = q0;
        v = v0;
        double t0 = now();
        for (long i = 0; i < iters; ++i) {
            *moved += 1e-12;
            ABA();
            sink += data.ddq[nv - 1];
        }
        double t1 = now();
        std::printf("aba %.9g\n", (t1 - t0) / iters);
    }
    return sink == 12345.0;
} catch (const std::exception &e) {
    std::fprintf(stderr, "_pinocchio_aba: %s\n", e.what());
    return 2;
}
