/*
 * gen_fmu.c - the FMI glue of an eomgen model, independent of the FMI
 * version (see gen_fmu.h). Every failure is a status and a message to the
 * importer's logger, never a crash: value references, sizes, modes and
 * values are checked before use.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "gen_fmu.h"
#if GEN_FMU_NH > 0
#include "gen_rt.h"
#endif

/* the variables' names by value reference (messages), and the model's
 * partition and start values, from gen_fmu_model.h */
static const char *const gen_fmu_names[GEN_FMU_NVR] = GEN_FMU_NAMES;
static const int gen_fmu_ind[GEN_FMU_DIM_(GEN_FMU_NS)] = GEN_FMU_IND;
static const int gen_fmu_tunable[GEN_FMU_DIM_(GEN_FMU_NP)] = GEN_FMU_TUNABLE;
static const double gen_fmu_x_start[GEN_FMU_NX] = GEN_FMU_X_START;
static const double gen_fmu_p_start[GEN_FMU_DIM_(GEN_FMU_NP)] = GEN_FMU_P_START;

#define GEN_FMU_ALL_MODES 0x7f

static const char *mode_name(int mode)
{
    switch (mode) {
    case GEN_FMU_INSTANTIATED: return "the instantiated state (before initialization)";
    case GEN_FMU_INIT: return "initialization mode";
    case GEN_FMU_EVENT: return "event mode";
    case GEN_FMU_CONT: return "continuous-time mode";
    case GEN_FMU_STEP: return "step mode";
    case GEN_FMU_TERMINATED: return "the terminated state";
    default: return "the error state (after a failed call: only reset or free the instance)";
    }
}

void gen_fmu_log(gen_fmu *c, int status, const char *category, const char *message)
{
    if (!c || !c->log) return;
    if (status == GEN_FMU_OK && !c->debug) return;
    c->log(c->layer, status, category, message);
}

/* format a message into c->message and log it with status; returns status */
static int say(gen_fmu *c, int status, const char *text)
{
    const char *category = status >= GEN_FMU_ERROR ? "logStatusError"
                           : status == GEN_FMU_WARNING ? "logStatusWarning" : "logAll";
    gen_fmu_log(c, status, category, text);
    return status;
}

static int fail(gen_fmu *c, const char *text)
{
    return say(c, GEN_FMU_ERROR, text);
}

/* "q2 = 0.5, q1 = 0.8, ..." of the state into buf */
static void state_text(const gen_fmu_real *x, char *buf, size_t size)
{
    size_t used = 0;
    int i;
    buf[0] = '\0';
    for (i = 0; i < GEN_FMU_NX && used + 1 < size; ++i) {
        int w = snprintf(buf + used, size - used, "%s%s = %.17g", i ? ", " : "",
                         gen_fmu_names[GEN_FMU_VR_X + i], (double)x[i]);
        if (w < 0) break;
        used += (size_t)w;
    }
}

static void set_start(gen_fmu *c)
{
    int i;
    c->time = 0;
    c->tolerance = 0;
    for (i = 0; i < GEN_FMU_NX; ++i) c->x[i] = (gen_fmu_real)gen_fmu_x_start[i];
    for (i = 0; i < GEN_FMU_DIM_(GEN_FMU_NR); ++i) c->r[i] = 0;
    for (i = 0; i < GEN_FMU_DIM_(GEN_FMU_NP); ++i) c->p[i] = (gen_fmu_real)gen_fmu_p_start[i];
    c->fresh = 0;
    c->solved = 0;
    memset(&c->stats, 0, sizeof c->stats);
    c->stats.terminal = -1;
}

void gen_fmu_setup(gen_fmu *c, int kind, const char *name, int debug, gen_fmu_log_fn log,
                   void *layer)
{
    if (!c) return;
    memset(c, 0, sizeof *c);
    c->kind = kind;
    c->debug = debug;
    c->log = log;
    c->layer = layer;
    if (name) {
        strncpy(c->name, name, sizeof c->name - 1);
        c->name[sizeof c->name - 1] = '\0';
    }
    set_start(c);
    c->mode = GEN_FMU_INSTANTIATED;
}

int gen_fmu_check_token(gen_fmu *c, const char *token)
{
    if (token && strcmp(token, GEN_FMU_TOKEN) == 0) return GEN_FMU_OK;
    snprintf(c->message, sizeof c->message,
             "the instantiation token %s%.200s%s is not this FMU's (%s): the "
             "modelDescription.xml and the binary of '%s' do not belong together",
             token ? "'" : "", token ? token : "(NULL)", token ? "'" : "", GEN_FMU_TOKEN,
             GEN_FMU_MODEL_NAME);
    return fail(c, c->message);
}

int gen_fmu_allowed(gen_fmu *c, const char *fn, int modes)
{
    if (!c) return GEN_FMU_ERROR;
    if (c->mode & modes) return GEN_FMU_OK;
    snprintf(c->message, sizeof c->message, "%s is not allowed in %s", fn, mode_name(c->mode));
    return fail(c, c->message);
}

/* a status of the model's C API as an FMU error message; returns ERROR */
static int model_failed(gen_fmu *c, const char *fn, const char *what, int status)
{
    char state[300];
    state_text(c->x, state, sizeof state);
    snprintf(c->message, sizeof c->message, "%s: %s at t = %.17g failed: %s (status %d); "
             "state: %s", fn, what, c->time, GEN_FMU_M(status_message)(status), status, state);
    return fail(c, c->message);
}

/* the dependent coordinates and speeds from the independent ones (the
 * dependent entries are the starting guess); x unchanged on failure */
static int solve_dependent(gen_fmu *c, const char *fn)
{
    int st;
    if (c->solved) return GEN_FMU_OK;
#if GEN_FMU_MC > 0 || GEN_FMU_MV > 0
    st = GEN_FMU_M(consistent_state)((gen_fmu_real)c->time, c->p, 0, 0, c->x);
    if (st) {
        char state[300];
        state_text(c->x, state, sizeof state);
        snprintf(c->message, sizeof c->message,
                 "%s: the dependent coordinates and speeds (%s) cannot be solved from the "
                 "independent ones at t = %.17g: %s (status %d). State (the dependent entries "
                 "are the starting guess): %s", fn, GEN_FMU_DEP_TEXT, c->time,
                 GEN_FMU_M(status_message)(st), st, state);
        return fail(c, c->message);
    }
#else
    (void)fn;
    (void)st;
#endif
    c->solved = 1;
    return GEN_FMU_OK;
}

/* dx, lam and the outputs at (time, x, r, p) */
static int refresh(gen_fmu *c, const char *fn)
{
    int st;
    gen_fmu_real t = (gen_fmu_real)c->time;
    if (c->fresh) return GEN_FMU_OK;
    if ((st = solve_dependent(c, fn))) return st;
#if GEN_FMU_NH > 0
    {
        int k, any = 0;
        for (k = 0; k < GEN_FMU_NH; ++k) any |= c->h_active[k];
        if (any)   /* the contacts held as constraints (gen_rt_hybrid.c) */
            st = gen_rt_hybrid_rhs(GEN_FMU_RUNTIME_MODEL(), t, c->x, c->r, c->p, c->h_active,
                                   c->h_work, c->h_iwork, c->dx, NULL);
        else
            st = GEN_FMU_M(eval_rhs)(t, c->x, c->r, c->p, c->dx, GEN_FMU_MV > 0 ? c->lam : NULL);
    }
#else
    st = GEN_FMU_M(eval_rhs)(t, c->x, c->r, c->p, c->dx, GEN_FMU_MV > 0 ? c->lam : NULL);
#endif
    if (st) return model_failed(c, fn, "the right-hand side", st);
#if GEN_FMU_NOUT_Y > 0
    st = GEN_FMU_M(eval_outputs)(t, c->x, c->r, c->p, c->out);
    if (st) return model_failed(c, fn, "the outputs", st);
#endif
#if GEN_FMU_NOUT_LAM > 0
    memcpy(c->out + GEN_FMU_NOUT_Y, c->lam, sizeof(gen_fmu_real) * GEN_FMU_MV);
#endif
#if GEN_FMU_NOUT_FC > 0
    st = GEN_FMU_M(eval_constraints)(c->x, c->p, t, c->out + GEN_FMU_NOUT_Y + GEN_FMU_NOUT_LAM);
    if (st) return model_failed(c, fn, "the configuration constraints", st);
#endif
#if GEN_FMU_NOUT_FV > 0
    st = GEN_FMU_M(eval_velocity_constraints)(c->x, c->x + GEN_FMU_NQ, c->p, t,
                                              c->out + GEN_FMU_NOUT_Y + GEN_FMU_NOUT_LAM +
                                                  GEN_FMU_NOUT_FC);
    if (st) return model_failed(c, fn, "the velocity constraints", st);
#endif
    c->fresh = 1;
    return GEN_FMU_OK;
}

int gen_fmu_enter_init(gen_fmu *c, int tolerance_defined, double tolerance, double start_time)
{
    if (gen_fmu_allowed(c, "EnterInitializationMode", GEN_FMU_INSTANTIATED)) return GEN_FMU_ERROR;
    if (!isfinite(start_time)) return fail(c, "EnterInitializationMode: the start time is not finite");
    if (tolerance_defined && !(tolerance > 0 && tolerance < 1)) {
        snprintf(c->message, sizeof c->message, "EnterInitializationMode: the tolerance "
                 "%.17g is not in (0, 1)", tolerance);
        return fail(c, c->message);
    }
    c->tolerance = tolerance_defined ? tolerance : 0;
    if (tolerance_defined && tolerance < GEN_FMU_MIN_TOLERANCE) {
        /* what the scalar type can resolve (float: about 1e-5) */
        snprintf(c->message, sizeof c->message, "EnterInitializationMode: the tolerance %g "
                 "is below what the model's %s arithmetic resolves; %g is used", tolerance,
                 sizeof(gen_fmu_real) == sizeof(float) ? "float" : "double",
                 GEN_FMU_MIN_TOLERANCE);
        say(c, GEN_FMU_WARNING, c->message);
        c->tolerance = GEN_FMU_MIN_TOLERANCE;
    }
    c->time = start_time;
    c->fresh = 0;
    c->solved = 0;
    c->mode = GEN_FMU_INIT;
    return GEN_FMU_OK;
}

static int bad_count(gen_fmu *c, const char *fn, size_t n, int want, const char *what);

/* ---- hybrid={...}: event indicators and jumps ------------------------ */
#if GEN_FMU_NH > 0
/* the indicators at (time, x) into c->h_v */
static int hybrid_values(gen_fmu *c, const char *fn)
{
    int st;
    if ((st = solve_dependent(c, fn))) return st;
    st = gen_rt_hybrid_values(GEN_FMU_RUNTIME_MODEL(), (gen_fmu_real)c->time, c->x, c->r, c->p,
                              c->h_active, c->h_work, c->h_iwork, c->h_v);
    if (st) return model_failed(c, fn, "the hybrid event indicators", st);
    return GEN_FMU_OK;
}

/* an indicator this far from zero is on a side (the importer's root
 * finding leaves it within rounding of zero at an event) */
static gen_fmu_real side_tol(const gen_fmu *c)
{
    gen_fmu_real s = 1;
    int i;
    for (i = 0; i < GEN_FMU_NX; ++i) s = s > fabs((double)c->x[i]) ? s : (gen_fmu_real)fabs((double)c->x[i]);
    return (gen_fmu_real)(sizeof(gen_fmu_real) == sizeof(float) ? 1e-4 : 1e-9) * s;
}

/* a start on the wrong side of a declaration (gen_rt_hybrid_penetrated:
 * an impact's gap past zero in its closing direction, a reset's guard
 * inside the region its direction fires on) is refused, naming it and its
 * value: the importer would run through the contact */
static int refuse_penetrated(gen_fmu *c, const char *fn)
{
    static const char *const names[GEN_FMU_NH] = GEN_FMU_HYBRID_NAMES;
    static const int kinds[GEN_FMU_NH] = GEN_FMU_HYBRID_KINDS;
    gen_fmu_real g[GEN_FMU_NH];
    int which = -1, st, reset;
    st = gen_rt_hybrid_penetrated(GEN_FMU_RUNTIME_MODEL(), (gen_fmu_real)c->time, c->x, c->p,
                                  g, &which);
    if (st != GEN_RT_ERR_PENETRATED) return st ? model_failed(c, fn, "the hybrid gaps", st)
                                               : GEN_FMU_OK;
    reset = kinds[which] == GEN_RT_HYBRID_RESET;
    snprintf(c->message, sizeof c->message, "%s: the start is inside the %s of %s '%s': its "
             "%s is %.12g at t = %.17g, %s zero, the side its %s (ERR_PENETRATED: the state "
             "would run through it)", fn, reset ? "guard region" : "contact",
             reset ? "reset" : "impact", names[which], reset ? "guard" : "gap",
             (double)g[which], c->time, g[which] < 0 ? "below" : "above",
             reset ? "crossing fires into" : "impact closes onto");
    return fail(c, c->message);
}

static void update_sides(gen_fmu *c)
{
    gen_fmu_real tol = side_tol(c);
    int k;
    for (k = 0; k < GEN_FMU_NH; ++k) {
        if (c->h_v[k] > tol) c->h_side[k] = 1;
        else if (c->h_v[k] < -tol) c->h_side[k] = -1;
    }
}
#endif

int gen_fmu_event_indicators(gen_fmu *c, double *z, size_t n)
{
    const char *fn = "GetEventIndicators";
    if (n == 0 && GEN_FMU_NH == 0) return GEN_FMU_OK;
    if (gen_fmu_allowed(c, fn, GEN_FMU_INIT | GEN_FMU_EVENT | GEN_FMU_CONT |
                        GEN_FMU_TERMINATED | GEN_FMU_FAILED))
        return GEN_FMU_ERROR;
    if (n != (size_t)GEN_FMU_NH) return bad_count(c, fn, n, GEN_FMU_NH, "event indicators");
#if GEN_FMU_NH > 0
    {
        int k, st;
        if (!z) return fail(c, "GetEventIndicators: the output array is NULL");
        if ((st = hybrid_values(c, fn))) return st;
        for (k = 0; k < GEN_FMU_NH; ++k) z[k] = (double)c->h_v[k];
    }
#else
    (void)z;
#endif
    return GEN_FMU_OK;
}

int gen_fmu_completed_step(gen_fmu *c)
{
#if GEN_FMU_NH > 0
    int st;
    if ((st = hybrid_values(c, "CompletedIntegratorStep"))) return st;
    update_sides(c);
#else
    (void)c;
#endif
    return GEN_FMU_OK;
}

int gen_fmu_new_discrete_states(gen_fmu *c, int *changed, int *again)
{
    *changed = 0;
    *again = 0;
#if GEN_FMU_NH > 0
    {
        const char *fn = "NewDiscreteStates";
        const gen_rt_model *m = GEN_FMU_RUNTIME_MODEL();
        gen_fmu_real tol;
        int k, st;
        if ((st = hybrid_values(c, fn))) return st;
        tol = side_tol(c);
        for (k = 0; k < GEN_FMU_NH; ++k) {
            int dir = m->hybrid->direction[k], what = 0, fire;
            gen_fmu_real v = c->h_v[k];
            if (c->h_active[k]) {
                fire = !(v > 0);          /* lift-off: the force would pull */
            } else if (m->hybrid->kind[k] == GEN_RT_HYBRID_IMPACT) {
                /* a gap at (or past) zero: an impact if it is closing
                 * (gen_rt_hybrid_jump tells; a gap opening is left alone) */
                fire = (dir <= 0 && v <= tol) || (dir >= 0 && v >= -tol);
            } else {
                /* a guard crossed from the side it was on at the last
                 * completed step (a reset's map may land on the guard) */
                fire = (dir <= 0 && c->h_side[k] > 0 && v <= tol) ||
                       (dir >= 0 && c->h_side[k] < 0 && v >= -tol);
            }
            if (!fire) continue;
            st = gen_rt_hybrid_jump(m, (gen_fmu_real)c->time, c->r, c->p, k, 0, 0, NULL,
                                    c->h_active, c->h_rows, c->h_scratch, c->h_work,
                                    c->h_iwork, c->x, &what);
            if (st) return model_failed(c, fn, "the hybrid jump", st);
            if (!what) continue;
            c->h_side[k] = 0;            /* at zero: its side is known again once it leaves */
            c->fresh = 0;
            c->solved = 0;               /* a reset is projected by the consistent state */
            *changed = 1;
            *again = 1;                  /* another declaration may fire at this state */
            if (c->debug) {
                snprintf(c->message, sizeof c->message, "hybrid event %d (%s) at t = %.17g", k,
                         what == GEN_RT_HYBRID_LIFTOFF ? "lift-off" : "jump", c->time);
                say(c, GEN_FMU_OK, c->message);
            }
            if ((st = solve_dependent(c, fn))) return st;
            return GEN_FMU_OK;
        }
    }
#else
    (void)c;
#endif
    return GEN_FMU_OK;
}

int gen_fmu_exit_init(gen_fmu *c)
{
    const char *fn = "ExitInitializationMode";
    int st;
    if (gen_fmu_allowed(c, fn, GEN_FMU_INIT)) return GEN_FMU_ERROR;
    c->fresh = 0;
#if GEN_FMU_NH > 0
    {
        int k;
        for (k = 0; k < GEN_FMU_NH; ++k) c->h_active[k] = c->h_side[k] = 0;
        if ((st = hybrid_values(c, fn)) || (st = refuse_penetrated(c, fn))) {
            c->mode = GEN_FMU_FAILED;
            return st;
        }
        update_sides(c);
    }
#endif
    if ((st = refresh(c, fn))) {
        c->mode = GEN_FMU_FAILED;
        return st;
    }
    GEN_FMU_M(sim_options_default)(&c->opts);
    c->opts.method = GEN_FMU_CS_METHOD;
    c->opts.project = 1;
    if (c->tolerance > 0) {
        c->opts.rtol = (gen_fmu_real)c->tolerance;
        c->opts.atol = (gen_fmu_real)c->tolerance;
    }
    memset(&c->stats, 0, sizeof c->stats);
    c->stats.terminal = -1;
    c->mode = c->kind == GEN_FMU_ME ? GEN_FMU_EVENT : GEN_FMU_STEP;
    if (c->debug) {
        snprintf(c->message, sizeof c->message, "initialized at t = %.17g", c->time);
        say(c, GEN_FMU_OK, c->message);
    }
    return GEN_FMU_OK;
}

int gen_fmu_terminate(gen_fmu *c)
{
    if (gen_fmu_allowed(c, "Terminate", GEN_FMU_EVENT | GEN_FMU_CONT | GEN_FMU_STEP |
                        GEN_FMU_INIT | GEN_FMU_FAILED))
        return GEN_FMU_ERROR;
    if (c->mode != GEN_FMU_FAILED) c->mode = GEN_FMU_TERMINATED;
    return GEN_FMU_OK;
}

int gen_fmu_reset(gen_fmu *c)
{
    if (!c) return GEN_FMU_ERROR;
    set_start(c);
    c->mode = GEN_FMU_INSTANTIATED;
    return GEN_FMU_OK;
}

static int bad_vr(gen_fmu *c, const char *fn, unsigned long vr)
{
    snprintf(c->message, sizeof c->message, "%s: unknown value reference %lu (this FMU's "
             "are 0..%d)", fn, vr, GEN_FMU_NVR - 1);
    return fail(c, c->message);
}

int gen_fmu_get_real(gen_fmu *c, const char *fn, unsigned long vr, double *value)
{
    int st;
    if (vr >= (unsigned long)GEN_FMU_NVR) return bad_vr(c, fn, vr);
    if (vr == 0) {
        *value = c->time;
    } else if (vr < (unsigned long)GEN_FMU_VR_DER) {
        if ((st = solve_dependent(c, fn))) return st;
        *value = (double)c->x[vr - GEN_FMU_VR_X];
    } else if (vr < (unsigned long)GEN_FMU_VR_R) {
        if ((st = refresh(c, fn))) return st;
        *value = (double)c->dx[gen_fmu_ind[vr - GEN_FMU_VR_DER]];
    } else if (vr < (unsigned long)GEN_FMU_VR_P) {
        *value = (double)c->r[vr - GEN_FMU_VR_R];
    } else if (vr < (unsigned long)GEN_FMU_VR_OUT) {
        *value = (double)c->p[vr - GEN_FMU_VR_P];
    } else {
        if ((st = refresh(c, fn))) return st;
        *value = (double)c->out[vr - GEN_FMU_VR_OUT];
    }
    return GEN_FMU_OK;
}

static int cannot_set(gen_fmu *c, const char *fn, unsigned long vr, const char *why)
{
    snprintf(c->message, sizeof c->message, "%s: %s (value reference %lu) cannot be set %s",
             fn, gen_fmu_names[vr], vr, why);
    return fail(c, c->message);
}

int gen_fmu_set_real(gen_fmu *c, const char *fn, unsigned long vr, double value)
{
    const int before = GEN_FMU_INSTANTIATED | GEN_FMU_INIT;
    if (vr >= (unsigned long)GEN_FMU_NVR) return bad_vr(c, fn, vr);
    if (vr == 0 || (vr >= (unsigned long)GEN_FMU_VR_DER && vr < (unsigned long)GEN_FMU_VR_R) ||
        vr >= (unsigned long)GEN_FMU_VR_OUT)
        return cannot_set(c, fn, vr, "(the FMU computes it)");
    if (!isfinite(value)) {
        snprintf(c->message, sizeof c->message, "%s: the value of %s (value reference %lu) "
                 "is not finite (%g)", fn, gen_fmu_names[vr], vr, value);
        return fail(c, c->message);
    }
    if (vr < (unsigned long)GEN_FMU_VR_DER) {
        if (!(c->mode & before))
            return cannot_set(c, fn, vr, "after initialization (a state is set before "
                              "ExitInitializationMode; Model Exchange sets the independent "
                              "states with SetContinuousStates)");
        c->x[vr - GEN_FMU_VR_X] = (gen_fmu_real)value;
        c->solved = 0;
    } else if (vr < (unsigned long)GEN_FMU_VR_P) {
        if (!(c->mode & (before | GEN_FMU_EVENT | GEN_FMU_CONT | GEN_FMU_STEP)))
            return cannot_set(c, fn, vr, c->mode == GEN_FMU_TERMINATED ? "after termination"
                              : "after a failed call (reset the instance)");
        c->r[vr - GEN_FMU_VR_R] = (gen_fmu_real)value;
    } else {
        int k = (int)(vr - GEN_FMU_VR_P);
        int ok = before | (gen_fmu_tunable[k] ? (GEN_FMU_EVENT | GEN_FMU_STEP) : 0);
        if (!(c->mode & ok))
            return cannot_set(c, fn, vr, gen_fmu_tunable[k]
                              ? "in this mode (a tunable constant is set in event mode or "
                                "between steps)"
                              : "after initialization: it is a fixed constant (it enters the "
                                "constraints, so a new value would leave the state "
                                "inconsistent)");
        c->p[k] = (gen_fmu_real)value;
        if (c->mode & before) c->solved = 0;
    }
    c->fresh = 0;
    return GEN_FMU_OK;
}

int gen_fmu_no_such_variables(gen_fmu *c, const char *fn, size_t n, const char *type)
{
    if (n == 0) return GEN_FMU_OK;
    snprintf(c->message, sizeof c->message, "%s: this FMU has no variables of type %s "
             "(its variables are all Real/Float64)", fn, type);
    return fail(c, c->message);
}

int gen_fmu_set_time(gen_fmu *c, double time)
{
    if (gen_fmu_allowed(c, "SetTime", GEN_FMU_EVENT | GEN_FMU_CONT)) return GEN_FMU_ERROR;
    if (!isfinite(time)) return fail(c, "SetTime: the time is not finite");
    if (time != c->time) {
        c->time = time;
        c->fresh = 0;
        c->solved = 0;   /* the constraints may depend on t */
    }
    return GEN_FMU_OK;
}

static int bad_count(gen_fmu *c, const char *fn, size_t n, int want, const char *what)
{
    snprintf(c->message, sizeof c->message, "%s: %lu %s given, this FMU has %d", fn,
             (unsigned long)n, what, want);
    return fail(c, c->message);
}

int gen_fmu_set_states(gen_fmu *c, const double *x, size_t n)
{
    const char *fn = "SetContinuousStates";
    int k;
    if (gen_fmu_allowed(c, fn, GEN_FMU_EVENT | GEN_FMU_CONT)) return GEN_FMU_ERROR;
    if (n != (size_t)GEN_FMU_NS) return bad_count(c, fn, n, GEN_FMU_NS, "continuous states");
    if (n && !x) return fail(c, "SetContinuousStates: the states are NULL");
    for (k = 0; k < GEN_FMU_NS; ++k) {
        if (!isfinite(x[k])) {
            snprintf(c->message, sizeof c->message, "%s: the state %s is not finite (%g)",
                     fn, gen_fmu_names[GEN_FMU_VR_X + gen_fmu_ind[k]], x[k]);
            return fail(c, c->message);
        }
    }
    for (k = 0; k < GEN_FMU_NS; ++k) c->x[gen_fmu_ind[k]] = (gen_fmu_real)x[k];
    c->fresh = 0;
    c->solved = 0;
    return GEN_FMU_OK;
}

int gen_fmu_get_states(gen_fmu *c, double *x, size_t n)
{
    const char *fn = "GetContinuousStates";
    int k;
    if (gen_fmu_allowed(c, fn, GEN_FMU_INIT | GEN_FMU_EVENT | GEN_FMU_CONT |
                        GEN_FMU_TERMINATED | GEN_FMU_FAILED))
        return GEN_FMU_ERROR;
    if (n != (size_t)GEN_FMU_NS) return bad_count(c, fn, n, GEN_FMU_NS, "continuous states");
    if (n && !x) return fail(c, "GetContinuousStates: the output array is NULL");
    for (k = 0; k < GEN_FMU_NS; ++k) x[k] = (double)c->x[gen_fmu_ind[k]];
    return GEN_FMU_OK;
}

int gen_fmu_get_derivatives(gen_fmu *c, double *dx, size_t n)
{
    const char *fn = "GetDerivatives";
    int k, st;
    if (gen_fmu_allowed(c, fn, GEN_FMU_INIT | GEN_FMU_EVENT | GEN_FMU_CONT |
                        GEN_FMU_TERMINATED | GEN_FMU_FAILED))
        return GEN_FMU_ERROR;
    if (n != (size_t)GEN_FMU_NS) return bad_count(c, fn, n, GEN_FMU_NS, "derivatives");
    if (n && !dx) return fail(c, "GetDerivatives: the output array is NULL");
    if ((st = refresh(c, fn))) return st;
    for (k = 0; k < GEN_FMU_NS; ++k) dx[k] = (double)c->dx[gen_fmu_ind[k]];
    return GEN_FMU_OK;
}

int gen_fmu_get_nominals(gen_fmu *c, double *nominal, size_t n)
{
    const char *fn = "GetNominalsOfContinuousStates";
    int k;
    if (gen_fmu_allowed(c, fn, GEN_FMU_ALL_MODES)) return GEN_FMU_ERROR;
    if (n != (size_t)GEN_FMU_NS) return bad_count(c, fn, n, GEN_FMU_NS, "nominals");
    if (n && !nominal) return fail(c, "GetNominalsOfContinuousStates: the output array is NULL");
    for (k = 0; k < GEN_FMU_NS; ++k) nominal[k] = 1.0;
    return GEN_FMU_OK;
}

int gen_fmu_do_step(gen_fmu *c, double t, double h)
{
    const char *fn = "DoStep";
    int st;
    double t1 = t + h;
    if (gen_fmu_allowed(c, fn, GEN_FMU_STEP)) return GEN_FMU_ERROR;
    if (!isfinite(t) || !isfinite(h) || h < 0) {
        snprintf(c->message, sizeof c->message, "%s: the communication point %g and step "
                 "size %g must be finite and the step size >= 0", fn, t, h);
        return fail(c, c->message);
    }
    if (fabs(t - c->time) > 1e-9 * (1.0 + fabs(t) + fabs(h))) {
        snprintf(c->message, sizeof c->message, "%s: the communication point %.17g is not the "
                 "FMU's time %.17g (steps must follow each other)", fn, t, c->time);
        return fail(c, c->message);
    }
    if (h == 0) return GEN_FMU_OK;
    st = GEN_FMU_M(advance)((gen_fmu_real)c->time, (gen_fmu_real)t1, c->r, c->p, &c->opts,
                            &c->stats, c->x);
    c->fresh = 0;
    if (st) {
        char state[300];
        double t_fail = (double)c->stats.t_last;
        state_text(c->x, state, sizeof state);
        snprintf(c->message, sizeof c->message, "%s: the integration from t = %.17g to %.17g "
                 "failed at t = %.17g: %s (status %d); last good state: %s", fn, c->time, t1,
                 t_fail, GEN_FMU_M(status_message)(st), st, state);
        c->time = t_fail;
        c->mode = GEN_FMU_FAILED;
        return fail(c, c->message);
    }
    c->time = t1;
    return GEN_FMU_OK;
}

/* the header of a saved state: a fixed tag, then the token (NUL-padded) */
static void state_header(unsigned char *h)
{
    memset(h, 0, 64);
    memcpy(h, "eomgen-fmu-state", 16);
    strncpy((char *)h + 16, GEN_FMU_TOKEN, 47);
}

void gen_fmu_save(const gen_fmu *c, unsigned char *state)
{
    state_header(state);
    memcpy(state + 64, c, sizeof *c);
}

int gen_fmu_check_state(gen_fmu *c, const char *fn, const unsigned char *state, size_t size)
{
    unsigned char h[64];
    gen_fmu saved;
    state_header(h);
    if (!state || size != GEN_FMU_STATE_SIZE || memcmp(state, h, 64) != 0) {
        snprintf(c->message, sizeof c->message, "%s: the FMU state (%lu bytes) was not saved "
                 "by this FMU (%s, %lu bytes)", fn, (unsigned long)size, GEN_FMU_MODEL_NAME,
                 (unsigned long)GEN_FMU_STATE_SIZE);
        return fail(c, c->message);
    }
    memcpy(&saved, state + 64, sizeof saved);
    if (saved.kind != c->kind) {
        snprintf(c->message, sizeof c->message, "%s: the FMU state was saved by a %s "
                 "instance, this one is %s", fn, saved.kind == GEN_FMU_ME ? "Model Exchange"
                 : "Co-Simulation", c->kind == GEN_FMU_ME ? "Model Exchange" : "Co-Simulation");
        return fail(c, c->message);
    }
    return GEN_FMU_OK;
}

int gen_fmu_restore(gen_fmu *c, const char *fn, const unsigned char *state, size_t size)
{
    gen_fmu saved;
    if (gen_fmu_check_state(c, fn, state, size)) return GEN_FMU_ERROR;
    memcpy(&saved, state + 64, sizeof saved);
    /* the importer's side stays this instance's */
    saved.log = c->log;
    saved.layer = c->layer;
    saved.debug = c->debug;
    memcpy(saved.name, c->name, sizeof saved.name);
    *c = saved;
    return GEN_FMU_OK;
}
