/*
 * gen_rt_private.h - the runtime's own: the small helpers its files share
 * (static inline, written once here), the KKT assembly, and the pieces the
 * simulation engine's files share (gen_rt_input.c, gen_rt_engine.c,
 * gen_rt_events.c, gen_rt_simulate.c).
 *
 * Not part of the API: a generated model includes gen_rt.h, never this.
 * Every function declared here is GEN_RT_INTERNAL (hidden in a shared
 * library) and, having external linkage, is renamed for the second scalar
 * type by csrc/eigen/gen_rt_names.h like the public ones.
 */
#ifndef GEN_RT_PRIVATE_H
#define GEN_RT_PRIVATE_H

#include <math.h>
#include <stddef.h>

#include "gen_rt.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- small helpers ----------------------------------------------------
 * (the largest magnitude: rt_max_abs, with the LU below) */

/* 1 if the n values are finite (n <= 0: 1): gen_rt_finite_n of gen_rt.h,
 * inline and branch-free (gen_rt_all_finite is the same test out of line) */
static inline int rt_finite(int n, const gen_rt_real *v)
{
    return gen_rt_finite_n(n, v);
}

/* dst[0..n) = src[0..n) */
static inline void rt_copy(int n, const gen_rt_real *src, gen_rt_real *dst)
{
    int i;
    for (i = 0; i < n; ++i) dst[i] = src[i];
}

/* dst[0..n) = 0 */
static inline void rt_zero(int n, gen_rt_real *dst)
{
    int i;
    for (i = 0; i < n; ++i) dst[i] = 0;
}

/* the next n reals of a work array *w (a bump allocator over the caller's
 * work: the pieces follow one another in the order taken) */
static inline gen_rt_real *rt_take(gen_rt_real **w, int n)
{
    gen_rt_real *r = *w;
    *w += n;
    return r;
}

/* |a|, max and min without libm (NaN: as the comparisons fall) */
static inline gen_rt_real rt_abs(gen_rt_real a) { return a < 0 ? -a : a; }
static inline gen_rt_real rt_max(gen_rt_real a, gen_rt_real b) { return a > b ? a : b; }
static inline gen_rt_real rt_min(gen_rt_real a, gen_rt_real b) { return a < b ? a : b; }

/* the libm calls of the scalar type */
#ifdef GEN_RT_REAL_FLOAT
#define RT_POW powf
#define RT_FABS fabsf
#define RT_SQRT sqrtf
#else
#define RT_POW pow
#define RT_FABS fabs
#define RT_SQRT sqrt
#endif

/* a model's state length nx = nq + nu */
#define RT_NX(m) ((m)->nq + (m)->nu)

/* ---- dense LU (gen_rt_linalg.c) --------------------------------------
 * The algorithms of gen_rt_max_abs, gen_rt_lu_factor, gen_rt_lu_solve and
 * gen_rt_lu_solve_t, written once here: gen_rt_linalg.c defines those
 * over them, and the CasADi library's derivatives
 * (csrc/derivatives/gen_rt_deriv_inline.h) compile them into its own
 * functions, with the model's sizes as constants. The same operations in
 * the same order: the same bits either way. */
#if defined(__GNUC__)
#define RT_ALWAYS_INLINE static inline __attribute__((always_inline))
#else
#define RT_ALWAYS_INLINE static inline
#endif

RT_ALWAYS_INLINE gen_rt_real rt_max_abs(int n, const gen_rt_real *v)
{
    gen_rt_real m = 0;
    int i;
    for (i = 0; i < n; ++i) {
        gen_rt_real a = rt_abs(v[i]);
        if (a > m) m = a;
    }
    return m;
}

RT_ALWAYS_INLINE int rt_lu_factor(int n, gen_rt_real *a, int *piv, gen_rt_real scale)
{
    int i, j, k;
    gen_rt_real tol;
    if (n < 0) return GEN_RT_ERR_BAD_ARG;
    if (n == 0) return GEN_RT_OK;
    if (!a || !piv) return GEN_RT_ERR_NULL;
    if (!(scale > 0)) scale = rt_max_abs(n * n, a);
    if (!(scale > 0)) return GEN_RT_ERR_SINGULAR;
    tol = GEN_RT_PIVOT_RTOL * scale;
    for (k = 0; k < n; ++k) {
        int p = k;
        gen_rt_real best = rt_abs(a[k * n + k]);
        for (i = k + 1; i < n; ++i) {
            gen_rt_real v = rt_abs(a[i * n + k]);
            if (v > best) { best = v; p = i; }
        }
        piv[k] = p;
        if (!(best > tol)) return GEN_RT_ERR_SINGULAR; /* also catches NaN */
        if (p != k) {
            for (j = 0; j < n; ++j) {
                gen_rt_real tmp = a[k * n + j];
                a[k * n + j] = a[p * n + j];
                a[p * n + j] = tmp;
            }
        }
        for (i = k + 1; i < n; ++i) {
            gen_rt_real l = a[i * n + k] / a[k * n + k];
            a[i * n + k] = l;
            if (l != 0) {
                for (j = k + 1; j < n; ++j) a[i * n + j] -= l * a[k * n + j];
            }
        }
    }
    return GEN_RT_OK;
}

RT_ALWAYS_INLINE int rt_lu_solve(int n, const gen_rt_real *lu, const int *piv, int nrhs,
                                gen_rt_real *b)
{
    int i, j, k;
    if (n < 0 || nrhs < 0) return GEN_RT_ERR_BAD_ARG;
    if (n == 0 || nrhs == 0) return GEN_RT_OK;
    if (!lu || !piv || !b) return GEN_RT_ERR_NULL;
    for (k = 0; k < n; ++k) {
        int p = piv[k];
        if (p != k) {
            for (j = 0; j < nrhs; ++j) {
                gen_rt_real tmp = b[k * nrhs + j];
                b[k * nrhs + j] = b[p * nrhs + j];
                b[p * nrhs + j] = tmp;
            }
        }
    }
    for (i = 0; i < n; ++i) {           /* forward: unit lower */
        for (k = 0; k < i; ++k) {
            gen_rt_real l = lu[i * n + k];
            if (l != 0) {
                for (j = 0; j < nrhs; ++j) b[i * nrhs + j] -= l * b[k * nrhs + j];
            }
        }
    }
    for (i = n - 1; i >= 0; --i) {      /* backward: upper */
        for (k = i + 1; k < n; ++k) {
            gen_rt_real uik = lu[i * n + k];
            if (uik != 0) {
                for (j = 0; j < nrhs; ++j) b[i * nrhs + j] -= uik * b[k * nrhs + j];
            }
        }
        for (j = 0; j < nrhs; ++j) b[i * nrhs + j] /= lu[i * n + i];
    }
    return GEN_RT_OK;
}

/* a^T x = b from P a = L U: U^T y = b, L^T c = y (unit diagonal), x = P^T c */
RT_ALWAYS_INLINE int rt_lu_solve_t(int n, const gen_rt_real *lu, const int *piv, int nrhs,
                                  gen_rt_real *b)
{
    int i, j, k;
    if (n < 0 || nrhs < 0) return GEN_RT_ERR_BAD_ARG;
    if (n == 0 || nrhs == 0) return GEN_RT_OK;
    if (!lu || !piv || !b) return GEN_RT_ERR_NULL;
    for (j = 0; j < nrhs; ++j) {
        for (i = 0; i < n; ++i) {
            gen_rt_real s = b[i * nrhs + j];
            for (k = 0; k < i; ++k) s -= lu[k * n + i] * b[k * nrhs + j];
            b[i * nrhs + j] = s / lu[i * n + i];
        }
        for (i = n - 1; i >= 0; --i) {
            gen_rt_real s = b[i * nrhs + j];
            for (k = i + 1; k < n; ++k) s -= lu[k * n + i] * b[k * nrhs + j];
            b[i * nrhs + j] = s;
        }
        for (k = n - 1; k >= 0; --k)
            if (piv[k] != k) {
                gen_rt_real tmp = b[k * nrhs + j];
                b[k * nrhs + j] = b[piv[k] * nrhs + j];
                b[piv[k] * nrhs + j] = tmp;
            }
    }
    return GEN_RT_OK;
}

/* ---- the KKT matrix (gen_rt_dynamics.c) -------------------------------
 * K ((n + m) x (n + m), row-major) = [M, -A^T; A, 0], M n x n, A m x n:
 * the matrix of M u' - A^T lam = f, A u' = -a (gen_rt_accel_kkt), and of
 * its derivatives (gen_rt_linearize, gen_rt_model_jacobian). A may be NULL
 * when m == 0. */
GEN_RT_INTERNAL void gen_rt_kkt_matrix(int n, int m, const gen_rt_real *M,
                                       const gen_rt_real *A, gen_rt_real *K);

/* ---- the simulation engine ---------------------------------------------
 * gen_rt_input.c   the inputs during a run (tables, feedback, schedules,
 *                  bounds, controllers, sampling)
 * gen_rt_engine.c  the integrators' callback, one RK4 step, and one
 *                  accepted step of RK4, DOPRI5 or RODAS4 with its dense
 *                  output and error control
 * gen_rt_events.c  events and hybrid jumps located in a step
 * gen_rt_simulate.c advance, simulate, simulate_input and simulate_events:
 *                  the steps between output rows
 * As in gen_rt_model.c: inputs are assumed checked by the caller, work
 * arrays are the caller's, sized by the GEN_RT_MODEL_*_WORK macros. */

/* the methods and holds of gen/codegen/abi.py (gen_rt_abi.h) are those the
 * engine implements (gen_rt_engine_method_ok, gen_rt_engine_step,
 * gen_rt_input_check): one added there fails the build here */
#if GEN_RT_METHOD_COUNT != 3 || GEN_RT_HOLD_COUNT != 2
#error "gen/codegen/abi.py lists a method or table hold that the engine does not implement"
#endif

/* what the integrators' callbacks see */
typedef struct {
    const gen_rt_model *m;
    const gen_rt_real *r, *p;
    gen_rt_real proj_tol;
    int proj_max_iter;
    gen_rt_real *work;  /* GEN_RT_MODEL_CB_WORK_ reals, shared by rhs and projection */
    int *iwork;
    /* inputs from a description (NULL: r is constant) */
    const gen_rt_input *in;
    gen_rt_real *r_buf;   /* nr: r at the current evaluation (continuous) */
    gen_rt_real *r_held;  /* nr: r held since the last sample (period > 0) */
    gen_rt_real t_seg;    /* start of the current sub-interval: a ZOH table's row */
    gen_rt_real t0;       /* start of the simulation: samples at t0 + k period */
    gen_rt_real t_sampled; /* time of the held sample (each sample is taken once) */
    int sampled;          /* 1 once a sample is held */
    /* hybrid={...}: the contacts held as constraints (gen_rt_hybrid.c) */
    int n_active;         /* 0: the model's own right-hand side */
    const int *active;    /* nh flags */
    gen_rt_real *hw;      /* GEN_RT_HYBRID_WORK */
    int *hiw;             /* GEN_RT_HYBRID_IWORK */
} gen_rt_sim_ctx;

/* how a step can be evaluated inside: the DOPRI5 continuous extension,
 * a cubic Hermite interpolant (RK4, RODAS4), or not at all */
enum { GEN_RT_DENSE_NONE, GEN_RT_DENSE_DOPRI5, GEN_RT_DENSE_HERMITE };

/* the engine: the run's context, the current step and its dense output,
 * the error control's state, the events' and the hybrid jumps' buffers */
typedef struct {
    gen_rt_sim_ctx *c;
    const gen_rt_sim_options *o;
    const gen_rt_events *ev;
    gen_rt_sim_stats *s;
    int nx, ny, need_y, dense_kind;
    gen_rt_real t_span;   /* t_end - t0: the scale of the first step */
    gen_rt_real *x;       /* the current state */
    gen_rt_real *xn;      /* the state after the step (projected) */
    gen_rt_real *xa, *xi, *xe; /* states inside the step */
    gen_rt_real *ya, *yb, *yi; /* outputs (ny) for output events */
    gen_rt_real *iw;      /* the method's scratch: GEN_RT_ENGINE_WORK_ reals */
    int *piv;             /* nx: RODAS4's pivots */
    /* the step just taken: from (t, x) to (t1, xn), h = t1 - t */
    gen_rt_real t, t1, h;
    const gen_rt_real *d_x1, *d_k, *d_f0, *d_f1;
    /* adaptive state */
    gen_rt_real h_next;   /* next trial step (<= 0: choose) */
    int rejected_last, f0_valid;
    gen_rt_real err_old;  /* DOPRI5's PI control: the last accepted error */
    long attempts;        /* since the last output row */
    /* hybrid={...}: nh declarations, event functions nev.. after the nev
     * user events (gen_rt_hybrid.c) */
    const gen_rt_hybrid *hy;
    int nev, nh;
    int *active, *rows;   /* nh: contacts held; the impulse's gaps */
    gen_rt_real *hw, *hva, *hvb, *hvi, *gd, *er, *xb; /* nh x 5, nx */
    int *hiw;
} gen_rt_engine;

/* a time within a relative rounding of a sample or knot counts as it */
static inline gen_rt_real rt_time_tol(gen_rt_real t)
{
    gen_rt_real a = t < 0 ? -t : t;
    return 64 * GEN_RT_EPS * (a > 1 ? a : 1);
}

/* gen_rt_input.c: the inputs at t (base, feedback, bounds, controller; a
 * ZOH table's and the gain schedule's row at t_zoh) */
GEN_RT_INTERNAL int gen_rt_input_at(const gen_rt_model *m, const gen_rt_input *in,
                                    gen_rt_real t, gen_rt_real t_zoh, const gen_rt_real *x,
                                    gen_rt_real *r);
/* the description checked (GEN_RT_ERR_NULL, _BAD_ARG, _NONFINITE_INPUT) */
GEN_RT_INTERNAL int gen_rt_input_check(const gen_rt_model *m, const gen_rt_input *in);
/* the gain schedule's row at t */
GEN_RT_INTERNAL int gen_rt_input_gain_row(const gen_rt_input *in, gen_rt_real t);
/* *r: the input in effect at (t, x) during the current step */
GEN_RT_INTERNAL int gen_rt_input_now(gen_rt_sim_ctx *c, gen_rt_real t, const gen_rt_real *x,
                                     const gen_rt_real **r);
/* a sample of the inputs at t from x when t is a sample time not yet taken
 * (*taken = 1) */
GEN_RT_INTERNAL int gen_rt_input_sample(gen_rt_sim_ctx *c, gen_rt_real t, const gen_rt_real *x,
                                        int *taken);
/* the end of the sub-interval from t towards t1: the next sample or knot */
GEN_RT_INTERNAL gen_rt_real gen_rt_input_next_break(const gen_rt_sim_ctx *c, gen_rt_real t,
                                                    gen_rt_real t1);

/* gen_rt_engine.c: a context with constant inputs r from t0 (no inputs
 * description, no contacts held, no work yet) */
GEN_RT_INTERNAL void gen_rt_sim_ctx_init(gen_rt_sim_ctx *c, const gen_rt_model *m,
                                         const gen_rt_real *r, const gen_rt_real *p,
                                         gen_rt_real proj_tol, int proj_max_iter,
                                         gen_rt_real t0);
/* the engine over the caller's work: layout shared by advance and simulate */
GEN_RT_INTERNAL void gen_rt_engine_init(gen_rt_engine *e, gen_rt_sim_ctx *c,
                                        const gen_rt_sim_options *o, const gen_rt_events *ev,
                                        gen_rt_sim_stats *s, gen_rt_real *x, gen_rt_real *w,
                                        int *iwork, gen_rt_real *ybuf);
/* 1 when o names a method the engine has, with usable tolerances */
GEN_RT_INTERNAL int gen_rt_engine_method_ok(const gen_rt_sim_options *o);
/* one accepted step from (t, e->x) towards t_stop: e->t1, e->xn (projected)
 * and what gen_rt_engine_dense needs. A failure leaves e->x untouched. */
GEN_RT_INTERNAL int gen_rt_engine_step(gen_rt_engine *e, gen_rt_real t, gen_rt_real t_stop);
/* the state at t + theta h inside the step just taken (not projected) */
GEN_RT_INTERNAL void gen_rt_engine_dense(const gen_rt_engine *e, gen_rt_real theta,
                                         gen_rt_real *out);
/* x projected onto the constraints when the options ask for it */
GEN_RT_INTERNAL int gen_rt_engine_project(gen_rt_engine *e, gen_rt_real t, gen_rt_real *x);

/* gen_rt_events.c: the events description checked (with a hybrid model's
 * work) */
GEN_RT_INTERNAL int gen_rt_events_check(const gen_rt_model *m, const gen_rt_events *ev);
/* the start of a run at (t0, x) of a hybrid model, before its first row:
 * refused (GEN_RT_ERR_PENETRATED, logged as the declaration's event with
 * x) when x is on the wrong side of a declaration (gen_rt_hybrid_penetrated);
 * an impact whose gap is at zero and closing or at rest is made at t0
 * (logged, x the state after it, the contacts it holds held) */
GEN_RT_INTERNAL int gen_rt_events_start(gen_rt_engine *e, gen_rt_real t0, gen_rt_real *x);
/* the events in the step just taken, in time order: logged, and *stop set
 * (with *te, e->xe) at the first terminal one; *jump set (with *te and the
 * state after in e->xe) at the first hybrid jump */
GEN_RT_INTERNAL int gen_rt_events_step(gen_rt_engine *e, int *stop, int *jump, gen_rt_real *te);

#ifdef __cplusplus
}
#endif
#endif /* GEN_RT_PRIVATE_H */
