/*
 * gen_fmu.h - the FMI glue of an eomgen model: one instance of the model as
 * an FMU (Model Exchange or Co-Simulation), independent of the FMI version.
 *
 * The FMI 2.0 and 3.0 layers (gen_fmu_fmi2.c, gen_fmu_fmi3.c) translate the
 * standard's calls into the functions below; this file and gen_fmu.c hold
 * what both need: the variables by value reference, the modes and which
 * call is allowed in which, consistent initialization, the Model Exchange
 * right-hand side on the independent state and the Co-Simulation step.
 *
 * The model comes from gen_fmu_model.h, written by eomgen for each FMU: the
 * model's prefix, sizes, partition, value-reference layout and start values
 * as macros. Nothing here knows a particular model.
 *
 * Value references (the layout eomgen writes into modelDescription.xml):
 *   0                          time
 *   GEN_FMU_VR_X + i           x[i], the full state [q, u] (i < NX)
 *   GEN_FMU_VR_DER + k         derivative of the independent state k (k < NS):
 *                              x[GEN_FMU_IND[k]]'
 *   GEN_FMU_VR_R + k           input r[k]
 *   GEN_FMU_VR_P + k           constant p[k]
 *   GEN_FMU_VR_OUT + k         output k: the model's outputs y, then the
 *                              multipliers lam, then the residuals f_c and
 *                              A u + b (the groups eomgen chose)
 *
 * Model Exchange exposes the independent state [q_ind, u_ind] as the
 * continuous states: the dependent coordinates and speeds are solved from
 * them (Newton from the last solution, then a linear solve) whenever the
 * importer sets new states, so the importer integrates an ODE without
 * invariants and the constraints hold at every evaluation.
 * Co-Simulation integrates the full state with the model's integrator
 * (adaptive, projection after every step) at the importer's tolerance.
 *
 * Memory: the instance is one struct (sizes fixed at compile time); the
 * FMI layers allocate it. No globals: every instance is independent.
 * Statuses are the FMI ones (both versions number them alike).
 */
#ifndef GEN_FMU_H
#define GEN_FMU_H

#include <stddef.h>
#include "gen_fmu_model.h"

#define GEN_FMU_OK 0
#define GEN_FMU_WARNING 1
#define GEN_FMU_DISCARD 2
#define GEN_FMU_ERROR 3
#define GEN_FMU_FATAL 4

/* interface types */
#define GEN_FMU_ME 1
#define GEN_FMU_CS 2

/* modes (the FMI state machine, both versions) */
#define GEN_FMU_INSTANTIATED 0x01
#define GEN_FMU_INIT 0x02       /* Initialization Mode */
#define GEN_FMU_EVENT 0x04      /* Event Mode (Model Exchange) */
#define GEN_FMU_CONT 0x08       /* Continuous-Time Mode (Model Exchange) */
#define GEN_FMU_STEP 0x10       /* Step Mode (Co-Simulation) */
#define GEN_FMU_TERMINATED 0x20
#define GEN_FMU_FAILED 0x40     /* after an error: only get, reset and free */

#define GEN_FMU_NOUT (GEN_FMU_NOUT_Y + GEN_FMU_NOUT_LAM + GEN_FMU_NOUT_FC + GEN_FMU_NOUT_FV)
#define GEN_FMU_VR_X 1
#define GEN_FMU_VR_DER (GEN_FMU_VR_X + GEN_FMU_NX)
#define GEN_FMU_VR_R (GEN_FMU_VR_DER + GEN_FMU_NS)
#define GEN_FMU_VR_P (GEN_FMU_VR_R + GEN_FMU_NR)
#define GEN_FMU_VR_OUT (GEN_FMU_VR_P + GEN_FMU_NP)
#define GEN_FMU_NVR (GEN_FMU_VR_OUT + GEN_FMU_NOUT)

/* C99 has no zero-length arrays */
#define GEN_FMU_DIM_(n) ((n) > 0 ? (n) : 1)

typedef GEN_FMU_REAL gen_fmu_real;

/* the smallest integration tolerance the scalar type resolves (a hundred
 * units of rounding); a smaller one asked for is raised to it */
#define GEN_FMU_MIN_TOLERANCE (sizeof(gen_fmu_real) == sizeof(float) ? 1e-5 : 1e-14)

/* how an FMI layer hands a message to the importer's logger */
typedef void (*gen_fmu_log_fn)(void *layer, int status, const char *category,
                               const char *message);

typedef struct {
    int kind;                   /* GEN_FMU_ME or GEN_FMU_CS */
    int mode;                   /* GEN_FMU_INSTANTIATED, ... */
    int debug;                  /* the importer's loggingOn */
    gen_fmu_log_fn log;
    void *layer;                /* the FMI layer's context for log */
    char name[64];              /* the instance name (for messages; may be cut) */
    double time;
    double tolerance;           /* the importer's, <= 0: the model's defaults */
    gen_fmu_real x[GEN_FMU_NX];
    gen_fmu_real r[GEN_FMU_DIM_(GEN_FMU_NR)];
    gen_fmu_real p[GEN_FMU_DIM_(GEN_FMU_NP)];
    /* derived from (time, x, r, p) when fresh is set */
    int fresh;
    int solved;                 /* ME: the dependent entries of x belong to the
                                 * independent ones */
    gen_fmu_real dx[GEN_FMU_NX];
    gen_fmu_real lam[GEN_FMU_DIM_(GEN_FMU_MV)];
    gen_fmu_real out[GEN_FMU_DIM_(GEN_FMU_NOUT)];
    GEN_FMU_M(sim_options) opts;
    GEN_FMU_M(sim_stats) stats;
    /* hybrid={...} (GEN_FMU_NH > 0): the contacts held, the side of each
     * indicator at the last completed step (+1, -1, 0 unknown) and the
     * runtime's scratch */
    int h_active[GEN_FMU_DIM_(GEN_FMU_NH)];
    int h_side[GEN_FMU_DIM_(GEN_FMU_NH)];
    int h_rows[GEN_FMU_DIM_(GEN_FMU_NH)];
    gen_fmu_real h_v[GEN_FMU_DIM_(GEN_FMU_NH)];
    gen_fmu_real h_scratch[3 * GEN_FMU_DIM_(GEN_FMU_NH)];
    gen_fmu_real h_work[GEN_FMU_HWORK];
    int h_iwork[GEN_FMU_HIWORK];
    char message[512];
} gen_fmu;

/* Set an instance up after allocation: start values, mode Instantiated.
 * name may be NULL. */
void gen_fmu_setup(gen_fmu *c, int kind, const char *name, int debug, gen_fmu_log_fn log,
                   void *layer);
/* GEN_FMU_OK when token is this FMU's; logs and GEN_FMU_ERROR otherwise */
int gen_fmu_check_token(gen_fmu *c, const char *token);
/* A message to the importer: always for warnings and errors, otherwise
 * only with debug logging on. */
void gen_fmu_log(gen_fmu *c, int status, const char *category, const char *message);

/* Is the call `fn` allowed in the current mode (a mask of GEN_FMU_* modes)?
 * GEN_FMU_OK, or logs and returns GEN_FMU_ERROR naming fn. */
int gen_fmu_allowed(gen_fmu *c, const char *fn, int modes);

int gen_fmu_enter_init(gen_fmu *c, int tolerance_defined, double tolerance, double start_time);
/* consistent initialization: the dependent coordinates and speeds from the
 * independent ones (GEN_FMU_ERROR with a logged message when they cannot be
 * solved: a singular or unreachable configuration) */
int gen_fmu_exit_init(gen_fmu *c);
int gen_fmu_terminate(gen_fmu *c);
/* back to Instantiated with the start values */
int gen_fmu_reset(gen_fmu *c);

/* one variable by value reference; fn names the FMI call in messages */
int gen_fmu_get_real(gen_fmu *c, const char *fn, unsigned long vr, double *value);
int gen_fmu_set_real(gen_fmu *c, const char *fn, unsigned long vr, double value);
/* a call that names value references of a type this FMU has none of */
int gen_fmu_no_such_variables(gen_fmu *c, const char *fn, size_t n, const char *type);

/* Model Exchange: the continuous states are the independent state (NS) */
int gen_fmu_set_time(gen_fmu *c, double time);
int gen_fmu_set_states(gen_fmu *c, const double *x, size_t n);
int gen_fmu_get_states(gen_fmu *c, double *x, size_t n);
int gen_fmu_get_derivatives(gen_fmu *c, double *dx, size_t n);
int gen_fmu_get_nominals(gen_fmu *c, double *nominal, size_t n);

/* Model Exchange with hybrid={...}: the event indicators (NH: a gap or
 * guard, a held contact's force), the sides they are on after a completed
 * step, and the jumps at an event (*changed: the states jumped; *again:
 * call again, another declaration may fire) */
int gen_fmu_event_indicators(gen_fmu *c, double *z, size_t n);
int gen_fmu_completed_step(gen_fmu *c);
int gen_fmu_new_discrete_states(gen_fmu *c, int *changed, int *again);

/* Co-Simulation: integrate from t to t + h (t must be the instance's time) */
int gen_fmu_do_step(gen_fmu *c, double t, double h);

/* FMU states (Get/SetFMUState and their serialization): everything of an
 * instance but its importer (logger, debug flag, name) in
 * GEN_FMU_STATE_SIZE bytes, which begin with a header naming this FMU
 * (a state of another FMU or version is refused). */
#define GEN_FMU_STATE_SIZE (sizeof(gen_fmu) + 64)
void gen_fmu_save(const gen_fmu *c, unsigned char *state);
/* GEN_FMU_OK when state (size bytes) is a state of this FMU and interface */
int gen_fmu_check_state(gen_fmu *c, const char *fn, const unsigned char *state, size_t size);
int gen_fmu_restore(gen_fmu *c, const char *fn, const unsigned char *state, size_t size);

#endif /* GEN_FMU_H */
