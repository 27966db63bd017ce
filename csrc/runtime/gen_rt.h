/*
 * gen_rt.h - the eomgen C runtime: small dense linear algebra, integrators,
 * constraint projection and constrained linearization.
 *
 * No model knowledge lives here; generated model code calls these functions.
 * Matrices are row-major: element (i, j) of an m x n matrix a is a[i*n + j].
 * Every function returns an int status: GEN_RT_OK (0) or a negative code.
 * No heap, no globals, no stdio: all memory belongs to the caller.
 *
 * The scalar type is gen_rt_real: double unless GEN_RT_REAL_FLOAT is defined.
 */
#ifndef GEN_RT_H
#define GEN_RT_H

#include <limits.h>   /* on glibc: its version macros, for GEN_RT_CLONES */
#include "gen_rt_config.h"

/* GEN_RT_CLONES: put before the definition of a large straight-line kernel
 * (the generator does, for the right-hand side of a large model). On x86-64
 * Linux with glibc, GCC >= 6 or clang >= 14, and a baseline target (no
 * -mavx given), the compiler builds the function twice, for the baseline
 * and for AVX, and the loader picks one by the CPU it runs on (an ifunc):
 * the same library runs on every x86-64, and on an AVX machine (every
 * x86-64 since 2011 but some low-end Atoms) the kernel runs in the VEX
 * encoding's three-operand form. The arithmetic is the same IEEE
 * arithmetic (no FMA: -ffp-contract=off); what changes is the code: no
 * register copies, a third smaller, which is what bounds a kernel larger
 * than the instruction cache (n = 16 links of the cart: 83 -> 59 kB, the
 * right-hand side 35% faster; bench/README). Elsewhere, or with
 * GEN_RT_NO_CLONES defined, it is empty. */
#if !defined(GEN_RT_NO_CLONES) && defined(__x86_64__) && defined(__linux__) \
    && defined(__GLIBC__) && !defined(__AVX__)                               \
    && ((defined(__clang__) && __clang_major__ >= 14)                        \
        || (!defined(__clang__) && defined(__GNUC__) && __GNUC__ >= 6))
#define GEN_RT_CLONES __attribute__((target_clones("avx", "default")))
#define GEN_RT_CLONES_ON 1
#else
#define GEN_RT_CLONES
#define GEN_RT_CLONES_ON 0
#endif

/* GEN_RT_LANES: 1 where the generated kernels may compute twin statements
 * side by side in two-lane vectors of doubles, gen_rt_v2d (GCC's and
 * clang's vector extension; SSE2 or AVX on x86-64, NEON on AArch64): each
 * lane computes what its scalar statement computes, bit for bit
 * (gen/codegen/lanes.py), so the choice changes speed, never a result.
 * 0 (the scalar statements) elsewhere, in a float build or with
 * GEN_RT_NO_LANES defined. */
#if !defined(GEN_RT_NO_LANES) && !defined(GEN_RT_REAL_FLOAT) && defined(__GNUC__) \
    && (defined(__x86_64__) || defined(__aarch64__))                             \
    && (defined(__clang__) || __GNUC__ >= 5)
#define GEN_RT_LANES 1
typedef double gen_rt_v2d __attribute__((vector_size(16)));
#else
#define GEN_RT_LANES 0
#endif

/* GEN_RT_CLONE_UNIT: a build that compiles a model's kernels file twice, in
 * parallel, defines it to 1 in one compile and to 2 in the other (gen.compile
 * does: the two versions of a large kernel are most of a model's compile
 * time). GEN_RT_CLONE_PART is what the compile holds:
 * 0  the whole file (GEN_RT_CLONE_UNIT undefined; or 1 where GEN_RT_CLONES
 *    is empty), a large kernel cloned by target_clones where it is active;
 * 1  (unit 1, GEN_RT_CLONES active) the baseline version, the ifunc that
 *    picks a version by the CPU as target_clones' own does, and every other
 *    kernel;
 * 2  (unit 2, GEN_RT_CLONES active) the AVX version alone;
 * 3  (unit 2 elsewhere) nothing.
 * Each version is compiled from the same code with the same target as
 * target_clones compiles it. */
#if defined(GEN_RT_CLONE_UNIT) && GEN_RT_CLONES_ON
#define GEN_RT_CLONE_PART GEN_RT_CLONE_UNIT
#elif defined(GEN_RT_CLONE_UNIT) && GEN_RT_CLONE_UNIT == 2
#define GEN_RT_CLONE_PART 3
#else
#define GEN_RT_CLONE_PART 0
#endif

/* GEN_RT_INTERNAL: a function that a model's translation units share and
 * its API does not export (the kernels): hidden in a shared library, so a
 * call to it is direct, not through the PLT, and the library exports only
 * its API. Empty where the compiler has no visibility attribute. */
#if defined(__GNUC__) && (defined(__ELF__) || defined(__APPLE__))
#define GEN_RT_INTERNAL __attribute__((visibility("hidden")))
#else
#define GEN_RT_INTERNAL
#endif

#ifdef __cplusplus
extern "C" {
#endif

#ifdef GEN_RT_REAL_FLOAT
typedef float gen_rt_real;
#define GEN_RT_EPS 1.1920929e-07F
#define GEN_RT_C(x) x##F
#else
typedef double gen_rt_real;
#define GEN_RT_EPS 2.220446049250313e-16
#define GEN_RT_C(x) x
#endif

/* Status codes, shared by the runtime and every generated model: one enum
 * constant per line of the table in gen_rt_status.h (GEN_RT_OK = 0,
 * GEN_RT_ERR_NULL = -1, ...). */
#include "gen_rt_status.h"
#define GEN_RT_STATUS_ENUM_(name, value, text) GEN_RT_##name = (value),
enum gen_rt_status { GEN_RT_STATUS_TABLE(GEN_RT_STATUS_ENUM_) GEN_RT_STATUS_END_ = 1 };
#undef GEN_RT_STATUS_ENUM_
#define GEN_RT_STATUS_MIN (-17)

/* The integration methods, the table holds, the stack bound and the structs
 * of the public API (gen_rt_sim_options, gen_rt_sim_stats, gen_rt_input,
 * gen_rt_events, gen_rt_controller_fn): rendered from gen/codegen/abi.py, the one
 * description of the interface, which every model's header also comes from. */
#include "gen_rt_abi.h"

/* A state with an entry beyond this magnitude has diverged: a model that
 * evaluates to NaN/inf there reports GEN_RT_ERR_DIVERGED, not a singular
 * configuration. */
#ifndef GEN_RT_DIVERGED_ABS
#ifdef GEN_RT_REAL_FLOAT
#define GEN_RT_DIVERGED_ABS GEN_RT_C(1e15)
#else
#define GEN_RT_DIVERGED_ABS GEN_RT_C(1e150)
#endif
#endif

/* A human-readable message for a status code (static storage, never NULL). */
const char *gen_rt_status_message(int status);

/* Relative pivot threshold below which a factorization reports singular. */
#ifndef GEN_RT_PIVOT_RTOL
#ifdef GEN_RT_REAL_FLOAT
#define GEN_RT_PIVOT_RTOL GEN_RT_C(1e-6)
#else
#define GEN_RT_PIVOT_RTOL GEN_RT_C(1e-12)
#endif
#endif

/* The largest |coefficient| of a dependent speed in the independent ones
 * that the partitioned solve accepts (beyond it the partition is singular
 * there): gen_rt_accel_partitioned and a model's straight-line solve
 * (gen/plan/small.py) test the same bound. */
#ifndef GEN_RT_PARTITION_CMAX
#ifdef GEN_RT_REAL_FLOAT
#define GEN_RT_PARTITION_CMAX GEN_RT_C(1e5)
#else
#define GEN_RT_PARTITION_CMAX GEN_RT_C(1e9)
#endif
#endif

/* 1 if all n values are finite. */
int gen_rt_all_finite(int n, const gen_rt_real *v);

/* The same, inline and branch-free: for the argument checks of the
 * generated functions, where n is often a constant the compiler unrolls.
 * x * 0 is 0 for a finite x and NaN for NaN and inf, so the sums are NaN
 * iff one value is not finite (no libm). Four independent sums: a quarter
 * of the dependency chain, and lanes a vectorizer can pack (clang does at
 * -O2); at n = 4 links of the cart, 2 -> 4 sums made eval_rhs about 7%
 * faster (bench/README). */
static inline int gen_rt_finite_n(int n, const gen_rt_real *v)
{
    gen_rt_real a[4] = {0, 0, 0, 0};
    int i;
    for (i = 0; i + 3 < n; i += 4) {
        a[0] += v[i] * 0;
        a[1] += v[i + 1] * 0;
        a[2] += v[i + 2] * 0;
        a[3] += v[i + 3] * 0;
    }
    for (; i < n; ++i) a[0] += v[i] * 0;
    a[0] = (a[0] + a[1]) + (a[2] + a[3]);
    return a[0] == a[0];
}

/* ---- dense linear algebra (gen_rt_linalg.c) --------------------------- */

/* LU with partial pivoting, in place: a (n x n) becomes L\U, piv[n] the
 * row permutation. scale > 0 is the magnitude the pivots are judged
 * against (pass 0 to use max |a_ij|); a pivot with
 * |p| <= GEN_RT_PIVOT_RTOL * scale gives GEN_RT_ERR_SINGULAR. */
int gen_rt_lu_factor(int n, gen_rt_real *a, int *piv, gen_rt_real scale);
/* Solve with a factor from gen_rt_lu_factor; b is n x nrhs, overwritten. */
int gen_rt_lu_solve(int n, const gen_rt_real *lu, const int *piv, int nrhs,
                    gen_rt_real *b);
/* The same with the transpose: a^T x = b (b n x nrhs, overwritten). */
int gen_rt_lu_solve_t(int n, const gen_rt_real *lu, const int *piv, int nrhs,
                      gen_rt_real *b);
/* Cholesky a = L L^T in place (lower triangle holds L). Not positive
 * definite, or a pivot below GEN_RT_PIVOT_RTOL * max diag: SINGULAR. */
int gen_rt_chol_factor(int n, gen_rt_real *a);
int gen_rt_chol_solve(int n, const gen_rt_real *l, int nrhs, gen_rt_real *b);
/* c (m x n) = a (m x k) * b (k x n) */
void gen_rt_matmul(int m, int k, int n, const gen_rt_real *a,
                   const gen_rt_real *b, gen_rt_real *c);
gen_rt_real gen_rt_max_abs(int n, const gen_rt_real *v);

/* ---- constrained accelerations (gen_rt_dynamics.c) --------------------
 * Model form:  M(q) u' = f(q,u,r,t) + A(q)^T lam,   A(q) u' + a(q,u,t) = 0
 * with n speeds and m velocity constraints (A is m x n).            */

/* Work length (reals) for gen_rt_accel_kkt and gen_rt_accel_partitioned. */
#define GEN_RT_ACCEL_WORK(n, m) (((n) + (m)) * ((n) + (m) + 1) + 2 * (n) * (n) + 4 * (n) + 1)
#define GEN_RT_ACCEL_IWORK(n, m) ((n) + (m) + 1)

/* Reactions inside the motion (the auxiliary speeds' reaction forces R
 * entering the dynamics, friction -mu N): M u' = f + G R and the auxiliary
 * equations C u' + H R + g0 = 0 solved as one linear system
 *   [M, -G; C, H] [u'; R] = [f; -g0]
 * by pivoted LU (G: n x na, C: na x n, H: na x na). R may be NULL. Work:
 * GEN_RT_REACTIONS_WORK(n, na) reals, n + na ints. GEN_RT_ERR_SINGULAR_REACTIONS
 * when the system is singular (or its solution overflows),
 * GEN_RT_ERR_NONFINITE_MODEL when a block is not finite. */
#define GEN_RT_REACTIONS_WORK(n, na) (((n) + (na)) * ((n) + (na) + 1) + 1)
int gen_rt_accel_reactions(int n, int na, const gen_rt_real *M, const gen_rt_real *f,
                           const gen_rt_real *G, const gen_rt_real *C, const gen_rt_real *H,
                           const gen_rt_real *g0, gen_rt_real *work, int *iwork,
                           gen_rt_real *ud, gen_rt_real *R);
/* The same matrix applied inversely to nc columns: B ((n + na) x nc,
 * row-major) becomes [M, -G; C, H]^-1 B (the derivatives of the coupled
 * solve by the implicit function theorem). Work: GEN_RT_REACTIONS_WORK. */
int gen_rt_reactions_columns(int n, int na, const gen_rt_real *M, const gen_rt_real *G,
                             const gen_rt_real *C, const gen_rt_real *H, int nc,
                             gen_rt_real *work, int *iwork, gen_rt_real *B);
/* The linearization blocks of such a model made those of the coupled solve
 * (the implicit function theorem): with the dynamic residual M u' - f - G R
 * and the auxiliary residual C u' + H R + g0 at the solved u' and R, Rq, Ru,
 * Rr (nu x nq, nu x nu, nu x nr) hold the first one's Jacobians at fixed R
 * without the reactions' share, Xq, Xu, Xr that share (-d(G R)/d.), Pq, Pu,
 * Pr the second one's Jacobians. On return Rq, Ru, Rr are the first nu rows
 * of [M, -G; C, H]^-1 [Rq + Xq, Ru + Xu, Rr + Xr; Pq, Pu, Pr] and Mout the
 * identity, so that M du' = -(Rq dq + Ru du + Rr dr) (what gen_rt_linearize
 * and the Jacobian solve) gives the coupled solve's derivative. Xr, Pr, Rr
 * may be NULL when nr == 0. Work: GEN_RT_REACTIONS_LIN_WORK reals, nu + na
 * ints. */
#define GEN_RT_REACTIONS_LIN_WORK(nq, nu, nr, na)                               \
    (((nu) + (na)) * ((nq) + (nu) + (nr)) + GEN_RT_REACTIONS_WORK(nu, na))
int gen_rt_reactions_lin(int nq, int nu, int nr, int na, const gen_rt_real *M,
                         const gen_rt_real *G, const gen_rt_real *C, const gen_rt_real *H,
                         const gen_rt_real *Xq, const gen_rt_real *Xu, const gen_rt_real *Xr,
                         const gen_rt_real *Pq, const gen_rt_real *Pu, const gen_rt_real *Pr,
                         gen_rt_real *work, int *iwork, gen_rt_real *Rq, gen_rt_real *Ru,
                         gen_rt_real *Rr, gen_rt_real *Mout);

/* Multiplier form: solve [M, -A^T; A, 0] [u'; lam] = [f; -a] with pivoted LU.
 * lam may be NULL. */
int gen_rt_accel_kkt(int n, int m, const gen_rt_real *M, const gen_rt_real *f,
                     const gen_rt_real *A, const gen_rt_real *a,
                     gen_rt_real *work, int *iwork, gen_rt_real *ud,
                     gen_rt_real *lam);
/* Kane form with a partition: u_dep = columns dep[m] of A, u_ind = ind[n-m].
 * Eliminates the dependent accelerations through A_dep (singular when the
 * partition is), solves the n-m reduced equations, then recovers the
 * multipliers lam = (A A^T)^-1 A (M u' - f) when lam != NULL. */
int gen_rt_accel_partitioned(int n, int m, const int *ind, const int *dep,
                             const gen_rt_real *M, const gen_rt_real *f,
                             const gen_rt_real *A, const gen_rt_real *a,
                             gen_rt_real *work, int *iwork, gen_rt_real *ud,
                             gen_rt_real *lam);

/* ---- projection onto the constraint manifold (gen_rt_project.c) ------- */

/* Minimum-norm correction dx = -J^T (J J^T)^-1 res, applied to x (length n):
 * J is m x n. Used for one Gauss-Newton step on the coordinates and for the
 * (linear) velocity projection. work: m*m + m reals. */
int gen_rt_min_norm_correct(int m, int n, const gen_rt_real *J,
                            const gen_rt_real *res, gen_rt_real *work,
                            gen_rt_real *x);
#define GEN_RT_MIN_NORM_WORK(m, n) ((m) * (m) + (m) + 1)

/* ---- integrators (gen_rt_integrate.c) --------------------------------- */

typedef int (*gen_rt_rhs_fn)(void *ctx, gen_rt_real t, const gen_rt_real *x,
                             gen_rt_real *dxdt);

/* Classic fourth-order Runge-Kutta step, x updated in place.
 * work: GEN_RT_RK4_WORK(nx) reals. */
#define GEN_RT_RK4_WORK(nx) (5 * (nx))
int gen_rt_rk4_step(gen_rt_rhs_fn f, void *ctx, int nx, gen_rt_real t,
                    gen_rt_real h, gen_rt_real *work, gen_rt_real *x);

/* Dormand-Prince 5(4): the engine's scratch for one trial step, the seven
 * stages k, y and ynew of gen_rt_dopri5_trial. */
#define GEN_RT_DOPRI5_WORK(nx) (9 * (nx))

/* The steps of the adaptive simulation engine (gen_rt_engine.c drives them):
 * gen_rt_err_norm is the scaled RMS norm of an error estimate d,
 * sqrt(mean((d_i / (atol + rtol max(|x_i|, |xnew_i|)))^2)). */
gen_rt_real gen_rt_err_norm(int nx, const gen_rt_real *x, const gen_rt_real *xnew,
                            const gen_rt_real *d, gen_rt_real rtol, gen_rt_real atol);
/* One DOPRI5 trial step of size h from (t, x): k (7 nx) holds f(t, x) in
 * its first nx entries on entry and the seven stages on return (k7 =
 * f(t + h, ynew)); y (nx) is scratch; *err the error norm. */
int gen_rt_dopri5_trial(gen_rt_rhs_fn f, void *ctx, int nx, gen_rt_real t, gen_rt_real h,
                        const gen_rt_real *x, gen_rt_real rtol, gen_rt_real atol,
                        gen_rt_real *k, gen_rt_real *y, gen_rt_real *ynew, gen_rt_real *err);
/* The continuous extension of order 4 of that step at t + theta h,
 * theta in [0, 1] (exact at both ends). */
void gen_rt_dopri5_dense(int nx, gen_rt_real h, gen_rt_real theta, const gen_rt_real *x,
                         const gen_rt_real *ynew, const gen_rt_real *k, gen_rt_real *out);
/* The cubic Hermite interpolant of a step (x0, f0 at t; x1, f1 at t + h)
 * at t + theta h: the dense output of RK4 and RODAS4 steps. */
void gen_rt_hermite(int nx, gen_rt_real h, gen_rt_real theta, const gen_rt_real *x0,
                    const gen_rt_real *f0, const gen_rt_real *x1, const gen_rt_real *f1,
                    gen_rt_real *out);
/* One RODAS4 trial step (gen_rt_rodas4.h) from (t, x) with f0 = f(t, x),
 * the Jacobian J = df/dx (nx x nx, row-major) and df/dt (NULL: the
 * right-hand side does not depend on t): ynew and the error norm *err.
 * GEN_RT_ERR_SINGULAR with *err = -1 when I/(h gamma) - J is (a smaller
 * step may cure it; the model's own failures leave *err >= 0). work:
 * GEN_RT_RODAS4_WORK(nx) reals; iwork: nx ints. Five evaluations of f. */
#define GEN_RT_RODAS4_WORK(nx) ((nx) * (nx) + 7 * (nx))
int gen_rt_rodas4_trial(gen_rt_rhs_fn f, void *ctx, int nx, gen_rt_real t, gen_rt_real h,
                        const gen_rt_real *x, const gen_rt_real *f0, const gen_rt_real *J,
                        const gen_rt_real *dfdt, gen_rt_real rtol, gen_rt_real atol,
                        gen_rt_real *work, int *iwork, gen_rt_real *ynew, gen_rt_real *err);

/* ---- constrained linearization (gen_rt_linearize.c) -------------------
 * Linearizes  Kqd q' + k(q,u) = 0,  M u' - f - A^T lam = 0 (R),
 * A u' + a = 0 (S),  f_c(q) = 0,  A u + b = 0  about an operating point,
 * eliminating dependent coordinates and speeds through the constraint
 * Jacobians and the accelerations and multipliers through the KKT matrix
 * (the method of Peterson, Gede and Hubbard). Output: A_lin (ns x ns),
 * B_lin (ns x nr) for the independent state [q_ind; u_ind], ns = nq-mc+nu-mv. */
typedef struct {
    int nq, nu, mc, mv, nr;
    const int *q_ind, *q_dep, *u_ind, *u_dep;
} gen_rt_lin_dims;

typedef struct {
    const gen_rt_real *Kqd; /* nq x nq: d(kin)/d(q') */
    const gen_rt_real *Kq;  /* nq x nq: d(kin)/dq at fixed q', u */
    const gen_rt_real *Ku;  /* nq x nu */
    const gen_rt_real *M;   /* nu x nu */
    const gen_rt_real *Rq;  /* nu x nq: dR/dq at fixed u', lam */
    const gen_rt_real *Ru;  /* nu x nu */
    const gen_rt_real *Rr;  /* nu x nr (may be NULL when nr == 0) */
    const gen_rt_real *A;   /* mv x nu */
    const gen_rt_real *Sq;  /* mv x nq */
    const gen_rt_real *Su;  /* mv x nu */
    const gen_rt_real *Vq;  /* mv x nq: d(A u + b)/dq */
    const gen_rt_real *Jc;  /* mc x nq: d f_c / dq */
    const gen_rt_real *Sqd; /* mv x nq: dS/dq' when the acceleration-constraint term
                             * holds q' (implicit kinematics); NULL otherwise */
    /* optional outputs y(q, u, r): ny > 0 with Yq (ny x nq), Yu (ny x nu), Yr
     * (ny x nr) gives C_lin (ny x ns) = dy/dx_ind and D_lin (ny x nr) = dy/dr
     * (written when C_lin is not NULL) */
    int ny;
    const gen_rt_real *Yq, *Yu, *Yr;
    gen_rt_real *C_lin, *D_lin;
} gen_rt_lin_blocks;

#define GEN_RT_LIN_WORK(nq, nu, mc, mv, nr)                                   \
    ((nq) * ((nq) - (mc)) + (mc) * (mc) + (mc) * ((nq) - (mc)) +             \
     (nu) * ((nu) - (mv)) + (nu) * ((nq) - (mc)) + (mv) * (mv) +             \
     (mv) * ((nq) - (mc) + (nu) - (mv)) +                                    \
     2 * (nq) * ((nq) - (mc) + (nu) - (mv)) +                                \
     ((nu) + (mv)) * ((nu) + (mv)) +                                         \
     ((nu) + (mv)) * ((nq) - (mc) + (nu) - (mv) + (nr)) +                    \
     (nu) * ((nq) - (mc) + (nu) - (mv)) + (nu) * ((nq) - (mc)) +             \
     (mv) * ((nq) - (mc)) + (nq) * (nq) + 8)
#define GEN_RT_LIN_IWORK(nq, nu, mc, mv) ((nq) + (nu) + (mc) + (mv) + 1)

int gen_rt_linearize(const gen_rt_lin_dims *d, const gen_rt_lin_blocks *b,
                     gen_rt_real *work, int *iwork, gen_rt_real *A_lin,
                     gen_rt_real *B_lin);

/* ---- a model, and everything done with it (gen_rt_model.c) -----------
 * (the simulation engine behind step_rk4, advance and simulate*:
 * gen_rt_input.c, gen_rt_engine.c, gen_rt_events.c, gen_rt_simulate.c)
 * A generated model is a gen_rt_model: its sizes, its coordinate partition,
 * its kernels (straight-line code printed by the generator) and which
 * acceleration solve it uses (decided by the generator). The functions
 * below are the model-agnostic algorithms of the public API; the generated
 * wrappers check the arguments, put the work arrays on their stack (sized
 * by the GEN_RT_MODEL_*_WORK macros: constant expressions, no VLAs) and
 * call them. Inputs are assumed checked (non-NULL, finite). */

/* which solve gives u' from M u' = f + A^T lam (the generator decides) */
#define GEN_RT_ACCEL_PARTITIONED 0 /* Kane: dependent speeds eliminated (gen_rt_accel_partitioned) */
#define GEN_RT_ACCEL_KKT 1         /* Lagrange: KKT system with the multipliers */
#define GEN_RT_ACCEL_LDLT 2        /* no constraints, symmetric M: the model's unrolled LDL^T */
#define GEN_RT_ACCEL_LU 3          /* no constraints, general M: pivoted LU */

/* outputs of the linearization kernel (the blocks of gen_rt_lin_blocks);
 * the kernel writes the blocks the model has */
typedef struct {
    gen_rt_real *Kqd, *Ku, *M, *A, *Kq, *Rq, *Ru, *Rr, *Sq, *Su, *Vq, *Jc, *Sqd;
} gen_rt_lin_out;

/* Hybrid behaviour of a model (hybrid={...}, gen/intake/hybrid.py; the engine in
 * gen_rt_hybrid.c and gen_rt_events.c): n declarations, each an impact
 * (a gap g(q, t) >= 0) or a reset (a guard of the state and a map). */
#define GEN_RT_HYBRID_IMPACT 0
#define GEN_RT_HYBRID_RESET 1
typedef struct gen_rt_hybrid {
    int n;
    const int *kind;            /* n: GEN_RT_HYBRID_IMPACT or _RESET */
    const int *direction;       /* n: -1 closing (downwards), +1, 0 both */
    const int *reset_index;     /* n: the row block of reset's map (-1: an impact) */
    const gen_rt_real *restitution; /* n: e in [0, 1] (impacts) */
    const gen_rt_real *rest_speed;  /* n: the Zeno rule's impact speed (impacts) */
    /* g (n): every gap and guard */
    void (*values)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                   gen_rt_real t, gen_rt_real *g);
    /* W (n x nu), w (n): g' = W u + w (zero rows for resets) */
    void (*jacobian)(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                     gen_rt_real *W, gen_rt_real *w);
    /* h (n): g'' = W u' + h */
    void (*bias)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                 gen_rt_real t, gen_rt_real *h);
    /* xr (nreset x nx): the state after each reset's map; NULL: no reset */
    void (*reset)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                  gen_rt_real t, gen_rt_real *xr);
} gen_rt_hybrid;

typedef struct gen_rt_model {
    int nq, nu, nr, np, mc, mv;     /* nx = nq + nu, ns = nq - mc + nu - mv */
    int explicit_kinematics;        /* 1: kinematics gives q'; 0: Kqd q' = kr */
    int accel;                      /* GEN_RT_ACCEL_* */
    const int *q_ind, *q_dep, *u_ind, *u_dep;
    /* kernels; a kernel the model does not have (no constraints, no
     * energy) is NULL. Kqd is written only with implicit kinematics, A and a
     * only when mv > 0. */
    void (*mass_matrix)(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                        gen_rt_real *M);
    void (*forcing)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                    const gen_rt_real *p, gen_rt_real t, gen_rt_real *f);
    void (*kinematics)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                       gen_rt_real t, gen_rt_real *Kqd, gen_rt_real *qd);
    void (*rhs_terms)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                      const gen_rt_real *p, gen_rt_real t, gen_rt_real *Kqd,
                      gen_rt_real *qd, gen_rt_real *M, gen_rt_real *f, gen_rt_real *A,
                      gen_rt_real *a);
    void (*constraints)(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                        gen_rt_real *fc);
    void (*constraint_jacobian)(const gen_rt_real *q, const gen_rt_real *p, gen_rt_real t,
                                gen_rt_real *fc, gen_rt_real *Jc);
    void (*velocity_constraints)(const gen_rt_real *q, const gen_rt_real *u,
                                 const gen_rt_real *p, gen_rt_real t, gen_rt_real *fv);
    void (*velocity_constraint_matrix)(const gen_rt_real *q, const gen_rt_real *p,
                                       gen_rt_real t, gen_rt_real *A, gen_rt_real *b);
    void (*energy)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *p,
                   gen_rt_real t, gen_rt_real *E);
    void (*lin_terms)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *qd,
                      const gen_rt_real *ud, const gen_rt_real *lam, const gen_rt_real *r,
                      const gen_rt_real *p, gen_rt_real t, const gen_rt_lin_out *o);
    /* M x = f for GEN_RT_ACCEL_LDLT (a status; x written only on success) */
    int (*mass_solve)(const gen_rt_real *M, const gen_rt_real *f, gen_rt_real *x);
    /* auxiliary speeds (Kane's u_auxiliary): na reaction forces solving
     * F reactions + g = 0, F (na x na) and g (na) at q, u and the
     * accelerations ud; na == 0 and NULL when the model has none */
    int na;
    void (*auxiliary)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *ud,
                      const gen_rt_real *r, const gen_rt_real *p, gen_rt_real t,
                      gen_rt_real *F, gen_rt_real *g);
    /* the acceleration-constraint term a (mv) at q' (qd), for a model with
     * velocity constraints and implicit kinematics: a = d(A u + b)/dq q' +
     * d(A u + b)/dt holds q', which only the run time knows (rhs_terms then
     * writes a at q' = 0 and this overwrites it); NULL otherwise */
    void (*accel_terms)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *qd,
                        const gen_rt_real *p, gen_rt_real t, gen_rt_real *a);
    /* outputs y (ny) and their Jacobians Yq (ny x nq), Yu (ny x nu), Yr (ny x
     * nr); ny == 0 and NULL when the model has none */
    int ny;
    void (*outputs)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                    const gen_rt_real *p, gen_rt_real t, gen_rt_real *y);
    void (*output_jacobian)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                            const gen_rt_real *p, gen_rt_real t, gen_rt_real *Yq,
                            gen_rt_real *Yu, gen_rt_real *Yr);
    /* the right-hand side in one function (explicit kinematics): q' (qd)
     * and u' (ud) by the model's unrolled LDL^T (GEN_RT_ACCEL_LDLT), or for
     * a small constrained model by the runtime's partitioned or KKT solve
     * traced as straight-line code (the same results, bit for bit), M and f
     * kept in registers (also written where M and f are not NULL); a status
     * (GEN_RT_ERR_SINGULAR on a failed pivot or a value not finite, ud then
     * not written: the general path decides); NULL when the model has none
     * (then the runtime calls rhs_terms and mass_solve or its solve). A
     * constrained model's rhs_solve gives no multipliers. */
    int (*rhs_solve)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                     const gen_rt_real *p, gen_rt_real t, gen_rt_real *qd, gen_rt_real *M,
                     gen_rt_real *f, gen_rt_real *ud);
    /* impacts and resets (hybrid={...}); NULL when the model has none */
    const gen_rt_hybrid *hybrid;
    /* reactions inside the motion (na of them, mv == 0): u' (and the
     * reactions R when not NULL) from M and f of rhs_terms and the model's
     * coupled blocks (gen_rt_accel_reactions); a status. NULL when the
     * model's reactions do not enter its motion (or it has none). */
    int (*reaction_solve)(const gen_rt_real *q, const gen_rt_real *u, const gen_rt_real *r,
                          const gen_rt_real *p, gen_rt_real t, const gen_rt_real *M,
                          const gen_rt_real *f, gen_rt_real *ud, gen_rt_real *R);
} gen_rt_model;

/* the options and statistics of advance/simulate (gen_rt_sim_options,
 * gen_rt_sim_stats) are in gen_rt_abi.h. Bounded output of simulate: every
 * opts.every-th output row and the last, or only the last (final_only);
 * every <= 1 keeps them all. */

/* Work arrays, by function: every macro takes the same arguments, the
 * model's sizes and its two solver choices:
 *   (nq, nu, mc, mv, nr, explicit_kinematics, accel)                     */
#define GEN_RT_MAX_(a, b) ((a) > (b) ? (a) : (b))
#define GEN_RT_NX_(nq, nu) ((nq) + (nu))
#define GEN_RT_NS_(nq, nu, mc, mv) ((nq) - (mc) + (nu) - (mv))
#define GEN_RT_MODEL_KIN_WORK(nq, nu, mc, mv, nr, ek, acc) ((ek) ? 1 : (nq) * (nq) + 1)
#define GEN_RT_MODEL_KIN_IWORK(nq, nu, mc, mv, nr, ek, acc) ((nq) + 1)
#define GEN_RT_MODEL_RHS_WORK(nq, nu, mc, mv, nr, ek, acc)                      \
    ((nu) * (nu) + (nu) + (mv) * (nu) + (mv) + ((ek) ? 0 : (nq) * (nq)) +        \
     ((acc) == GEN_RT_ACCEL_LDLT ? 0 : GEN_RT_ACCEL_WORK(nu, mv)) + 1)
#define GEN_RT_MODEL_RHS_IWORK(nq, nu, mc, mv, nr, ek, acc) ((nq) + (nu) + (mv) + 1)
/* eval_rhs also keeps x' apart until it succeeds */
#define GEN_RT_MODEL_EVAL_RHS_WORK(nq, nu, mc, mv, nr, ek, acc)                 \
    (GEN_RT_NX_(nq, nu) + GEN_RT_MODEL_RHS_WORK(nq, nu, mc, mv, nr, ek, acc))
#define GEN_RT_MODEL_EVAL_RHS_IWORK(nq, nu, mc, mv, nr, ek, acc)                \
    GEN_RT_MODEL_RHS_IWORK(nq, nu, mc, mv, nr, ek, acc)
#define GEN_RT_MODEL_JAC_WORK(nq, nu, mc, mv, nr, ek, acc) ((mc) + 1)
#define GEN_RT_MODEL_PROJECT_WORK(nq, nu, mc, mv, nr, ek, acc)                  \
    (GEN_RT_NX_(nq, nu) + GEN_RT_MAX_((mc) * (mc) + (mc), (mv) * (mv) + (mv)) + 1 + \
     (mc) + (mc) * (nq) + (nq) + (mv) * (nu) + 2 * (mv))
#define GEN_RT_MODEL_CONSISTENT_WORK(nq, nu, mc, mv, nr, ek, acc)               \
    (GEN_RT_NX_(nq, nu) + (mc) + (mc) * (nq) + (mc) * (mc) + (mv) * (nu) + 2 * (mv) + \
     (mv) * (mv) + 1)
#define GEN_RT_MODEL_CONSISTENT_IWORK(nq, nu, mc, mv, nr, ek, acc) ((mc) + (mv) + 1)
/* what a right-hand side or a projection inside an integrator needs */
#define GEN_RT_MODEL_CB_WORK_(nq, nu, mc, mv, nr, ek, acc)                      \
    GEN_RT_MAX_(GEN_RT_MODEL_RHS_WORK(nq, nu, mc, mv, nr, ek, acc),             \
                GEN_RT_MODEL_PROJECT_WORK(nq, nu, mc, mv, nr, ek, acc))
/* the simulation engine's method scratch (gen_rt_engine.c): RK4 and the
 * end derivative, DOPRI5's stages, or RODAS4's f0, f1, df/dt, ynew, J, Jr,
 * stages and the Jacobian's work */
#define GEN_RT_ENGINE_WORK_(nq, nu, mc, mv, nr, ek, acc)                        \
    GEN_RT_MAX_(GEN_RT_MAX_(GEN_RT_RK4_WORK(GEN_RT_NX_(nq, nu)) + GEN_RT_NX_(nq, nu), \
                            GEN_RT_DOPRI5_WORK(GEN_RT_NX_(nq, nu))),            \
                4 * GEN_RT_NX_(nq, nu) + GEN_RT_NX_(nq, nu) * ((nr) + GEN_RT_NX_(nq, nu)) + 1 + \
                    GEN_RT_RODAS4_WORK(GEN_RT_NX_(nq, nu)) +                    \
                    GEN_RT_MAX_(GEN_RT_MODEL_JACOBIAN_WORK(nq, nu, mc, mv, nr, ek, acc), \
                                GEN_RT_NX_(nq, nu)))
/* advance, and the core of simulate: four states, the method, callbacks */
#define GEN_RT_MODEL_SIM_CORE_WORK_(nq, nu, mc, mv, nr, ek, acc)                \
    (4 * GEN_RT_NX_(nq, nu) + GEN_RT_ENGINE_WORK_(nq, nu, mc, mv, nr, ek, acc) + \
     GEN_RT_MODEL_CB_WORK_(nq, nu, mc, mv, nr, ek, acc))
#define GEN_RT_MODEL_STEP_WORK(nq, nu, mc, mv, nr, ek, acc)                     \
    (GEN_RT_RK4_WORK(GEN_RT_NX_(nq, nu)) + GEN_RT_NX_(nq, nu) +                 \
     GEN_RT_MODEL_CB_WORK_(nq, nu, mc, mv, nr, ek, acc))
#define GEN_RT_MODEL_STEP_IWORK(nq, nu, mc, mv, nr, ek, acc)                    \
    GEN_RT_MODEL_RHS_IWORK(nq, nu, mc, mv, nr, ek, acc)
#define GEN_RT_MODEL_ADVANCE_WORK(nq, nu, mc, mv, nr, ek, acc)                  \
    GEN_RT_MODEL_SIM_CORE_WORK_(nq, nu, mc, mv, nr, ek, acc)
/* the right-hand side's, and RODAS4's pivots */
#define GEN_RT_MODEL_ADVANCE_IWORK(nq, nu, mc, mv, nr, ek, acc)                 \
    (GEN_RT_MODEL_RHS_IWORK(nq, nu, mc, mv, nr, ek, acc) + GEN_RT_NX_(nq, nu) + 1)
#define GEN_RT_MODEL_SIMULATE_WORK(nq, nu, mc, mv, nr, ek, acc)                 \
    (2 * GEN_RT_NX_(nq, nu) + (mv) + 1 +                                        \
     GEN_RT_MODEL_SIM_CORE_WORK_(nq, nu, mc, mv, nr, ek, acc))
#define GEN_RT_MODEL_SIMULATE_IWORK(nq, nu, mc, mv, nr, ek, acc)                \
    GEN_RT_MODEL_ADVANCE_IWORK(nq, nu, mc, mv, nr, ek, acc)
/* simulate_input: simulate's, plus the inputs held and evaluated */
#define GEN_RT_MODEL_SIMULATE_INPUT_WORK(nq, nu, mc, mv, nr, ek, acc)           \
    (GEN_RT_MODEL_SIMULATE_WORK(nq, nu, mc, mv, nr, ek, acc) + 2 * (nr) + 2)
#define GEN_RT_MODEL_SIMULATE_INPUT_IWORK(nq, nu, mc, mv, nr, ek, acc)          \
    GEN_RT_MODEL_SIMULATE_IWORK(nq, nu, mc, mv, nr, ek, acc)
/* simulate_events: simulate_input's, plus outputs at three points */
#define GEN_RT_MODEL_SIMULATE_EVENTS_WORK(nq, nu, mc, mv, nr, ek, acc, ny)      \
    (GEN_RT_MODEL_SIMULATE_INPUT_WORK(nq, nu, mc, mv, nr, ek, acc) + 3 * (ny) + 3)
#define GEN_RT_MODEL_SIMULATE_EVENTS_IWORK(nq, nu, mc, mv, nr, ek, acc, ny)     \
    GEN_RT_MODEL_SIMULATE_IWORK(nq, nu, mc, mv, nr, ek, acc)
#define GEN_RT_MODEL_LINEARIZE_WORK(nq, nu, mc, mv, nr, ek, acc)                \
    ((nq) + (nu) + (mv) + 1 + (nu) * (nu) + (nu) + (mv) * (nu) + (mv) +          \
     2 * (nq) * (nq) + (nq) * (nu) + (nu) * (nq) + (nu) * (nu) + (nu) * (nr) +   \
     3 * (mv) * (nq) + (mv) * (nu) + (mc) * (nq) +                               \
     GEN_RT_MAX_(GEN_RT_MAX_(GEN_RT_ACCEL_WORK(nu, mv), GEN_RT_MODEL_KIN_WORK(nq, nu, mc, mv, nr, ek, acc)), \
                 (nq) + (nu) * (nu) + (nu) + (nq) * (nq)) +                      \
     GEN_RT_LIN_WORK(nq, nu, mc, mv, nr) + 8)
#define GEN_RT_MODEL_LINEARIZE_IWORK(nq, nu, mc, mv, nr, ek, acc)               \
    GEN_RT_MAX_(GEN_RT_LIN_IWORK(nq, nu, mc, mv), GEN_RT_ACCEL_IWORK(nu, mv) + (nq))

/* eval_auxiliary_forces takes the number of reactions na as well */
#define GEN_RT_MODEL_AUX_WORK(nq, nu, mc, mv, nr, ek, acc, na)                  \
    ((na) ? GEN_RT_NX_(nq, nu) + (na) * (na) + (na) +                           \
                GEN_RT_MODEL_RHS_WORK(nq, nu, mc, mv, nr, ek, acc) : 1)
#define GEN_RT_MODEL_AUX_IWORK(nq, nu, mc, mv, nr, ek, acc, na)                 \
    GEN_RT_MAX_(GEN_RT_MODEL_RHS_IWORK(nq, nu, mc, mv, nr, ek, acc), (na) + 1)

int gen_rt_model_eval_mass_matrix(const gen_rt_model *m, const gen_rt_real *q,
                                  const gen_rt_real *p, gen_rt_real t, gen_rt_real *M);
int gen_rt_model_eval_forcing(const gen_rt_model *m, const gen_rt_real *q,
                              const gen_rt_real *u, const gen_rt_real *r,
                              const gen_rt_real *p, gen_rt_real t, gen_rt_real *f);
/* q' from the kinematic equations (an LU solve when they are implicit) */
int gen_rt_model_eval_kinematics(const gen_rt_model *m, const gen_rt_real *q,
                                 const gen_rt_real *u, const gen_rt_real *p, gen_rt_real t,
                                 gen_rt_real *work, int *iwork, gen_rt_real *qdot);
int gen_rt_model_eval_constraints(const gen_rt_model *m, const gen_rt_real *q,
                                  const gen_rt_real *p, gen_rt_real t, gen_rt_real *fc);
int gen_rt_model_eval_constraint_jacobian(const gen_rt_model *m, const gen_rt_real *q,
                                          const gen_rt_real *p, gen_rt_real t,
                                          gen_rt_real *work, gen_rt_real *Jc);
int gen_rt_model_eval_velocity_constraints(const gen_rt_model *m, const gen_rt_real *q,
                                           const gen_rt_real *u, const gen_rt_real *p,
                                           gen_rt_real t, gen_rt_real *fv);
int gen_rt_model_eval_velocity_constraint_matrix(const gen_rt_model *m,
                                                 const gen_rt_real *q,
                                                 const gen_rt_real *p, gen_rt_real t,
                                                 gen_rt_real *A, gen_rt_real *b);
/* GEN_RT_ERR_BAD_ARG (and E = 0) when the model has no energy */
int gen_rt_model_eval_energy(const gen_rt_model *m, const gen_rt_real *q,
                             const gen_rt_real *u, const gen_rt_real *p, gen_rt_real t,
                             gen_rt_real *E);
/* x' (and the multipliers when lam != NULL) written straight into dxdt,
 * which holds garbage on failure: the integrators' right-hand side */
int gen_rt_model_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                     const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                     int *iwork, gen_rt_real *dxdt, gen_rt_real *lam);
/* the same, dxdt written only on success */
int gen_rt_model_eval_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                          const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *work,
                          int *iwork, gen_rt_real *dxdt, gen_rt_real *lam);
/* the m->na reaction forces of the auxiliary speeds at (t, x): u' from the
 * right-hand side, then F reactions = -g by pivoted LU (GEN_RT_ERR_SINGULAR
 * when F is); nothing written (GEN_RT_OK) when the model has none */
int gen_rt_model_eval_auxiliary_forces(const gen_rt_model *m, gen_rt_real t,
                                       const gen_rt_real *x, const gen_rt_real *r,
                                       const gen_rt_real *p, gen_rt_real *work, int *iwork,
                                       gen_rt_real *F);
/* x onto f_c = 0 (Gauss-Newton, minimum norm) and A u + b = 0; x unchanged
 * on failure; tol <= 0 and max_iter <= 0 mean 16 eps and 10 */
int gen_rt_model_project(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *p,
                         gen_rt_real tol, int max_iter, gen_rt_real *work, gen_rt_real *x);
/* dependent coordinates (Newton) and speeds (linear solve) from the
 * independent ones; x unchanged on failure; defaults 16 eps and 50 */
int gen_rt_model_consistent_state(const gen_rt_model *m, gen_rt_real t,
                                  const gen_rt_real *p, gen_rt_real tol, int max_iter,
                                  gen_rt_real *work, int *iwork, gen_rt_real *x);
/* one classic RK4 step of size h with r held, projected when project != 0
 * (gen_rt_engine.c) */
int gen_rt_model_step_rk4(const gen_rt_model *m, gen_rt_real t, gen_rt_real h,
                          const gen_rt_real *r, const gen_rt_real *p, int project,
                          gen_rt_real *work, int *iwork, gen_rt_real *x);
/* x from t0 to t1 by the engine with r held, no rows (gen_rt_simulate.c) */
int gen_rt_model_advance(const gen_rt_model *m, gen_rt_real t0, gen_rt_real t1,
                         const gen_rt_real *r, const gen_rt_real *p,
                         const gen_rt_sim_options *o, gen_rt_real *work, int *iwork,
                         gen_rt_sim_stats *s, gen_rt_real *x);
/* the output times of simulate from t0 to t_end every dt (the last interval
 * clipped), or GEN_RT_ERR_BAD_ARG */
int gen_rt_simulate_rows(gen_rt_real t0, gen_rt_real t_end, gen_rt_real dt);
/* the rows simulate writes of those (what its capacity must hold) with
 * opts.every and opts.final_only; a negative rows (a status) as is. The one
 * place this is computed: the bindings call it through <p>_simulate_rows_kept. */
int gen_rt_simulate_rows_kept(int rows, int every, int final_only);
int gen_rt_model_simulate(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                          gen_rt_real t_end, gen_rt_real dt, const gen_rt_real *r,
                          const gen_rt_real *p, const gen_rt_sim_options *o, int capacity,
                          gen_rt_real *work, int *iwork, gen_rt_real *t_out,
                          gen_rt_real *x_out, gen_rt_real *lam_out, gen_rt_sim_stats *s);
/* ---- inputs during a simulation: tables, feedback, controllers --------
 * Where the inputs r come from at each evaluation of the right-hand side:
 *   base       the constant r (NULL: zero) or, with n_table > 0, the table
 *              (t_table strictly increasing, r_table n_table rows of nr):
 *              GEN_RT_HOLD_ZOH holds the row of the last knot at or before t,
 *              GEN_RT_HOLD_LINEAR interpolates; both hold the first and last
 *              rows outside the table. Knots are step boundaries.
 *   feedback   with K (nr x ns, row-major, on the independent state
 *              [q_ind, u_ind], the state of linearize) and x_op (nx, NULL:
 *              zero): r = base - K (x_ind - x_op_ind);
 *   controller with controller != NULL, called last with r holding the
 *              above; it may overwrite r (a nonzero return stops the run with
 *              GEN_RT_ERR_CONTROLLER).
 *   schedule   with n_gain > 0, K, x_op and r (when not NULL) hold n_gain
 *              rows (nr x ns, nx and nr values each): row k is used from
 *              t_gain + k dt_gain on (row 0 before, the last row after the
 *              end), a time-varying feedback such as a trajectory tracker's
 *              (gen/design/tracking.py). Row changes are step boundaries.
 *   bounds     with r_min / r_max (nr each, NULL: none; infinite entries
 *              allowed), base and feedback clipped to [r_min, r_max]
 *              before the controller is called.
 *   period     0: r is evaluated at every right-hand-side evaluation (a
 *              continuous controller); > 0: r is evaluated at t0 + k period
 *              (from the state there) and held until the next sample (a
 *              digital controller); the integrator steps to every sample. */
/* (gen_rt_input, gen_rt_controller_fn and GEN_RT_HOLD_*: gen_rt_abi.h) */

/* the inputs at (t, x) from in (sampling aside: the base at t, feedback,
 * the schedule's row at t, bounds, controller): one step of a digital
 * controller. A bad description is GEN_RT_ERR_BAD_ARG (unsorted table,
 * unknown hold, negative period, a schedule without dt_gain > 0, r_min >
 * r_max) or _NONFINITE_INPUT. */
int gen_rt_model_eval_input(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                            const gen_rt_input *in, gen_rt_real *r);
/* simulate with inputs from in; r_out (nr per row, may be NULL) gets the
 * inputs in effect from each output time on */
int gen_rt_model_simulate_input(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                                gen_rt_real t_end, gen_rt_real dt, const gen_rt_input *in,
                                const gen_rt_real *p, const gen_rt_sim_options *o,
                                int capacity, gen_rt_real *work, int *iwork,
                                gen_rt_real *t_out, gen_rt_real *x_out, gen_rt_real *lam_out,
                                gen_rt_real *r_out, gen_rt_sim_stats *s);

/* ---- events during a simulation (simulate_events) ----------------------
 * Event i is a crossing of level[i] (NULL: zero) by the state x[which[i]]
 * (0 <= which[i] < nx) or by the output y[which[i] - nx] (nx <= which[i] <
 * nx + ny): direction[i] = +1 counts crossings from below (g < 0 before,
 * g >= 0 after, g = value - level), -1 from above, 0 both. Crossings are
 * found between the ends of every step and located on the step's dense
 * output (DOPRI5's continuous extension; a cubic Hermite interpolant for
 * RK4 and RODAS4) to a few units of rounding in t; the state logged is the
 * dense output there, projected onto the constraints. Two crossings of the
 * same event inside one step are not seen (as with any step-end test).
 * The log holds the first capacity events in time order: log_which[k]
 * (the event's index i), log_t[k] and log_x[k nx .. k nx + nx - 1];
 * stats->n_events counts them all. With terminal != NULL and terminal[i]
 * nonzero, the first crossing of event i ends the run there: its state is
 * the last output row and stats->terminal = i. */
/* (gen_rt_events: gen_rt_abi.h) */
int gen_rt_model_simulate_events(const gen_rt_model *m, const gen_rt_real *x0, gen_rt_real t0,
                                 gen_rt_real t_end, gen_rt_real dt, const gen_rt_input *in,
                                 const gen_rt_events *ev, const gen_rt_real *p,
                                 const gen_rt_sim_options *o, int capacity, gen_rt_real *work,
                                 int *iwork, gen_rt_real *t_out, gen_rt_real *x_out,
                                 gen_rt_real *lam_out, gen_rt_real *r_out, gen_rt_sim_stats *s);

int gen_rt_model_linearize(const gen_rt_model *m, const gen_rt_real *x_op,
                           const gen_rt_real *r_op, const gen_rt_real *p, gen_rt_real t,
                           gen_rt_real *work, int *iwork, gen_rt_real *A_lin,
                           gen_rt_real *B_lin);
/* the outputs y(q, u, r, t) (ny): OK and nothing written when ny == 0 */
int gen_rt_model_eval_outputs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                              const gen_rt_real *r, const gen_rt_real *p, gen_rt_real *y);
/* linearize, and C (ny x ns) = dy/dx_ind, D (ny x nr) = dy/dr for the
 * outputs (the dependent entries follow the constraints, as for A) */
#define GEN_RT_MODEL_LINEARIZE_OUTPUTS_WORK(nq, nu, mc, mv, nr, ek, acc, ny)     \
    (GEN_RT_MODEL_LINEARIZE_WORK(nq, nu, mc, mv, nr, ek, acc) +                 \
     (ny) * ((nq) + (nu) + (nr)) + 1)
#define GEN_RT_MODEL_LINEARIZE_OUTPUTS_IWORK(nq, nu, mc, mv, nr, ek, acc, ny)    \
    GEN_RT_MODEL_LINEARIZE_IWORK(nq, nu, mc, mv, nr, ek, acc)
int gen_rt_model_linearize_outputs(const gen_rt_model *m, const gen_rt_real *x_op,
                                   const gen_rt_real *r_op, const gen_rt_real *p,
                                   gen_rt_real t, gen_rt_real *work, int *iwork,
                                   gen_rt_real *A_lin, gen_rt_real *B_lin, gen_rt_real *C_lin,
                                   gen_rt_real *D_lin);
/* the zero-order-hold discretization of the linearization over a step dt:
 * Ad = exp(A dt), Bd = int_0^dt exp(A s) ds B (gen_rt_c2d_zoh, gen_rt_expm.h) */
#define GEN_RT_MODEL_LINEARIZE_DISCRETE_WORK(nq, nu, mc, mv, nr, ek, acc)       \
    (GEN_RT_NS_(nq, nu, mc, mv) * (GEN_RT_NS_(nq, nu, mc, mv) + (nr)) + 1 +     \
     GEN_RT_MAX_(GEN_RT_MODEL_LINEARIZE_WORK(nq, nu, mc, mv, nr, ek, acc),      \
                 GEN_RT_C2D_WORK(GEN_RT_NS_(nq, nu, mc, mv), nr)))
#define GEN_RT_MODEL_LINEARIZE_DISCRETE_IWORK(nq, nu, mc, mv, nr, ek, acc)      \
    GEN_RT_MAX_(GEN_RT_MODEL_LINEARIZE_IWORK(nq, nu, mc, mv, nr, ek, acc),      \
                GEN_RT_C2D_IWORK(GEN_RT_NS_(nq, nu, mc, mv), nr))
int gen_rt_model_linearize_discrete(const gen_rt_model *m, const gen_rt_real *x_op,
                                    const gen_rt_real *r_op, const gen_rt_real *p,
                                    gen_rt_real t, gen_rt_real dt, gen_rt_real *work,
                                    int *iwork, gen_rt_real *Ad, gen_rt_real *Bd);

/* ---- hybrid models: impacts, resets, contact (gen_rt_hybrid.c) --------
 * The simulation engine (simulate_events) locates the gaps and guards of
 * m->hybrid as events and calls these at them. Work (reals, ints): */
#define GEN_RT_HYBRID_CORE_WORK(nq, nu, mv, nh)                                  \
    ((nu) * (nu) + 2 * (nu) + 3 * ((mv) + (nh)) + ((mv) + (nh)) * (nu) + (nq) * (nq) + \
     (nq) + (nh) * (nu) + 2 * (nh) + GEN_RT_ACCEL_WORK(nu, (mv) + (nh)))
#define GEN_RT_HYBRID_FN_WORK(nq, nu, mv, nh)                                    \
    GEN_RT_MAX_(GEN_RT_HYBRID_CORE_WORK(nq, nu, mv, nh) + 2 * (nh) + (nq) + (nu) + 1, \
                (nh) * ((nq) + (nu)) + (nq) + (nu) + 1)
#define GEN_RT_HYBRID_FN_IWORK(nq, nu, mv, nh) ((nq) + GEN_RT_ACCEL_IWORK(nu, (mv) + (nh)))
/* the engine's: the functions' and its own (values at three points, the
 * state before a jump; the active contacts, the closing set and the
 * contacts held before a jump) */
#define GEN_RT_HYBRID_WORK(nq, nu, mv, nh)                                       \
    (GEN_RT_HYBRID_FN_WORK(nq, nu, mv, nh) + 5 * (nh) + 2 * ((nq) + (nu)) + 8)
#define GEN_RT_HYBRID_IWORK(nq, nu, mv, nh) (GEN_RT_HYBRID_FN_IWORK(nq, nu, mv, nh) + 3 * (nh) + 4)
/* a reset's map must meet the constraints to this (relative to the state) */
#ifndef GEN_RT_HYBRID_RESET_TOL
#ifdef GEN_RT_REAL_FLOAT
#define GEN_RT_HYBRID_RESET_TOL GEN_RT_C(1e-3)
#else
#define GEN_RT_HYBRID_RESET_TOL GEN_RT_C(1e-6)
#endif
#endif
/* x' (and the contact forces lam_c, nh, 0 where inactive; may be NULL)
 * with the active contacts held as constraints */
int gen_rt_hybrid_rhs(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                      const gen_rt_real *r, const gen_rt_real *p, const int *active,
                      gen_rt_real *work, int *iwork, gen_rt_real *dxdt, gen_rt_real *lam_c);
/* the event values (nh): an inactive declaration's gap or guard, an active
 * contact's force (lift-off where it falls through zero) */
int gen_rt_hybrid_values(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                         const gen_rt_real *r, const gen_rt_real *p, const int *active,
                         gen_rt_real *work, int *iwork, gen_rt_real *v);
/* the gaps' rates g' = W u + w (nh) */
int gen_rt_hybrid_rates(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                        const gen_rt_real *p, gen_rt_real *work, int *iwork,
                        gen_rt_real *gd);
/* the impulse of the gaps rows[k] != 0 with restitutions e (nh): x's
 * speeds updated; impulse (nh, may be NULL) gets the gaps' impulses. When
 * the solve's matrices (M, A, W, w) or its result are not finite
 * (GEN_RT_ERR_NONFINITE_MODEL), x's speeds are the result, or NaN */
int gen_rt_hybrid_impulse(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *p,
                          const int *rows, const gen_rt_real *e, gen_rt_real *work,
                          int *iwork, gen_rt_real *x, gen_rt_real *impulse);
/* x <- the map of reset k, checked against the constraints
 * (GEN_RT_ERR_INCONSISTENT_RESET) and projected (pwork: the projection's);
 * a map that is not finite (GEN_RT_ERR_NONFINITE_MODEL) or violates the
 * constraints is still written to x, so the caller can name its entries */
int gen_rt_hybrid_reset(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *p, int k,
                        gen_rt_real proj_tol, int proj_max_iter, gen_rt_real *pwork,
                        gen_rt_real *work, gen_rt_real *x);
/* The jump of declaration k at (t, x), as the engine and the FMU make it:
 * a held contact's lift-off (*what = GEN_RT_HYBRID_LIFTOFF), a reset
 * (GEN_RT_HYBRID_RESET + 1; projected when pwork, the projection's work,
 * is not NULL) or an impact (GEN_RT_HYBRID_IMPACT + 1) with every gap
 * closing at the same time and the contacts held, which the Zeno rule
 * (e = 0, or slower than rest_speed) holds from then on (active, nh flags).
 * *what = 0: a gap that is not closing (grazing), x unchanged. rows (nh
 * ints) and scratch (3 nh reals) are the caller's. */
#define GEN_RT_HYBRID_LIFTOFF 3
/* the log's entries of a jump (simulate_events; n user events, nh
 * declarations): n + k the jump of declaration k (an impact or a reset),
 * n + nh + k the lift-off of contact k, n + 2 nh + k contact k held from
 * then on (after an impact, by the Zeno rule or e = 0) */
#define GEN_RT_HYBRID_LOG_LIFTOFF 1
#define GEN_RT_HYBRID_LOG_HOLD 2
int gen_rt_hybrid_jump(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *r,
                       const gen_rt_real *p, int k, gen_rt_real proj_tol, int proj_max_iter,
                       gen_rt_real *pwork, int *active, int *rows, gen_rt_real *scratch,
                       gen_rt_real *work, int *iwork, gen_rt_real *x, int *what);
/* the gaps and guards g (nh) at (t, x), every contact free: OK and nothing
 * written for a model without declarations; GEN_RT_ERR_NONFINITE_MODEL
 * when one is NaN or infinite */
int gen_rt_model_eval_hybrid(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                             const gen_rt_real *p, gen_rt_real *g);
/* A start at (t, x) on the wrong side of a declaration with a direction:
 * a gap or guard past zero (by more than 1024 eps of the state's size) in
 * the direction its crossing fires on (an impact's gap below zero when it
 * closes downwards). GEN_RT_ERR_PENETRATED with *which = the first such
 * declaration (its value g[*which]), else OK and *which = -1. g: nh. */
int gen_rt_hybrid_penetrated(const gen_rt_model *m, gen_rt_real t, const gen_rt_real *x,
                             const gen_rt_real *p, gen_rt_real *g, int *which);
/* A step from (t0, x0) to (t1, x1) across a declaration: its gap or guard
 * from strictly before zero to strictly past it in its direction (a step
 * that ends on zero, or starts on or past it, is none).
 * GEN_RT_ERR_GUARD_CROSSED with *which = the first such (g: its values at
 * both ends, 2 nh), else OK and *which = -1. */
int gen_rt_hybrid_crossed(const gen_rt_model *m, gen_rt_real t0, const gen_rt_real *x0,
                          gen_rt_real t1, const gen_rt_real *x1, const gen_rt_real *p,
                          gen_rt_real *g, int *which);

#ifdef __cplusplus
}
#endif
/* the matrix exponential (linearize_discrete's work sizes use its macros)
 * and the step sensitivities */
#include "gen_rt_expm.h"
#include "gen_rt_sens.h"
#endif /* GEN_RT_H */
