/*
 * test_fmi2_glue.c - the FMI 2.0 glue (csrc/fmu) driven directly, on the
 * seed pendulum (Kane; q = [q2, q1], u = [u2, u1], L = 1, gravity g along
 * +x), exported with the start state q2 = 0.6, q1 = 0.8: every error path
 * (bad token, NULL arguments, unknown value references, non-finite values,
 * calls in the wrong mode, a singular state) gives fmi2Error and a message
 * through the logger, never a crash; the numbers of the normal paths
 * against closed forms. Built with the FMU's own sources, the strict flags
 * and ASan/UBSan by tests/features/test_fmu.py.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"
#include "gen_fmu.h"

static char last[4096];
static int n_logged;

/* FMI 2.0's logger: the message is a printf format */
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    va_list ap;
    (void)env;
    (void)name;
    (void)status;
    (void)category;
    va_start(ap, message);
    vsnprintf(last, sizeof last, message, ap);
    va_end(ap);
    ++n_logged;
}

static int failures;
#define CHECK(cond)                                                                     \
    do {                                                                                \
        if (!(cond)) {                                                                  \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n  last message: %s\n", __FILE__,  \
                    __LINE__, #cond, last);                                             \
            ++failures;                                                                 \
        }                                                                               \
    } while (0)
#define LOGGED(text) CHECK(strstr(last, text) != NULL)

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

enum { Q2 = 1, Q1, U2, U1, DQ2, DU2, L_, M_, G_, LAM, FC, FV };

static double get(fmi2Component c, fmi2ValueReference vr)
{
    double v = NAN;
    CHECK(fmi2GetReal(c, &vr, 1, &v) == fmi2OK);
    return v;
}

static fmi2Status set(fmi2Component c, fmi2ValueReference vr, double v)
{
    return fmi2SetReal(c, &vr, 1, &v);
}

static void test_layout(void)
{
    /* the value references this test assumes are the FMU's */
    CHECK(GEN_FMU_VR_X == Q2 && GEN_FMU_VR_DER == DQ2 && GEN_FMU_VR_P == L_ &&
          GEN_FMU_VR_OUT == LAM && GEN_FMU_NVR == FV + 1);
    CHECK(strcmp(fmi2GetVersion(), "2.0") == 0);
    CHECK(strcmp(fmi2GetTypesPlatform(), fmi2TypesPlatform) == 0);
}

static void test_instantiate(void)
{
    fmi2Component c;
    /* a token that is not this FMU's, full of printf directives: refused,
     * and the logger's formatting reads no argument that is not there */
    n_logged = 0;
    c = fmi2Instantiate("p", fmi2CoSimulation, "%s%s%n%d{bad}", "", &callbacks, fmi2False,
                        fmi2False);
    CHECK(c == NULL);
    CHECK(n_logged == 1);
    LOGGED("is not this FMU's");
    LOGGED("%s%s%n%d{bad}");
    CHECK(fmi2Instantiate("p", fmi2CoSimulation, NULL, "", &callbacks, fmi2False, fmi2False) ==
          NULL);
    LOGGED("(NULL)");
    CHECK(fmi2Instantiate("p", fmi2CoSimulation, GEN_FMU_TOKEN, "", NULL, fmi2False,
                          fmi2False) == NULL);
    CHECK(fmi2Instantiate("p", (fmi2Type)7, GEN_FMU_TOKEN, "", &callbacks, fmi2False,
                          fmi2False) == NULL);
    LOGGED("fmuType");
    /* no instance: an error, no crash */
    CHECK(fmi2DoStep(NULL, 0, 0.1, fmi2True) == fmi2Error);
    CHECK(fmi2GetReal(NULL, NULL, 0, NULL) == fmi2Error);
    CHECK(fmi2SetContinuousStates(NULL, NULL, 0) == fmi2Error);
    fmi2FreeInstance(NULL);
}

static void test_cs(void)
{
    fmi2ValueReference vr[3] = {Q1, FC, 99};
    double v[3], q1, q2, u1, u2;
    double t = 0, h = 0.01;
    int k;
    fmi2Component c = fmi2Instantiate("cs", fmi2CoSimulation, GEN_FMU_TOKEN, "", &callbacks,
                                      fmi2False, fmi2False);
    CHECK(c != NULL);
    if (!c) return;
    /* before initialization */
    CHECK(fmi2GetReal(c, vr, 1, v) == fmi2Error);
    LOGGED("not allowed in the instantiated state");
    CHECK(set(c, 99, 1.0) == fmi2Error);
    LOGGED("unknown value reference 99");
    CHECK(set(c, Q2, NAN) == fmi2Error);
    LOGGED("the value of q2");
    CHECK(set(c, Q2, INFINITY) == fmi2Error);
    CHECK(set(c, DQ2, 1.0) == fmi2Error);
    LOGGED("der(q2)");
    LOGGED("the FMU computes it");
    CHECK(set(c, 0, 1.0) == fmi2Error);
    CHECK(fmi2SetReal(c, NULL, 1, v) == fmi2Error);
    LOGGED("is NULL");
    CHECK(fmi2SetInteger(c, vr, 1, NULL) == fmi2Error);
    LOGGED("no variables of type Integer");
    CHECK(fmi2SetInteger(c, vr, 0, NULL) == fmi2OK);
    CHECK(fmi2DoStep(c, 0, h, fmi2True) == fmi2Error);
    CHECK(set(c, U2, 0.5) == fmi2OK);
    CHECK(fmi2SetupExperiment(c, fmi2True, 1e-10, 0.0, fmi2False, 0.0) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK);
    /* consistent: q1 from q2 on the circle, u1 from the radial constraint */
    q2 = get(c, Q2);
    q1 = get(c, Q1);
    u2 = get(c, U2);
    u1 = get(c, U1);
    CHECK(fabs(q2 - 0.6) < 1e-15 && fabs(q1 - 0.8) < 1e-15);
    CHECK(fabs(u2 - 0.5) < 1e-15 && fabs(u1 + 0.6 * 0.5 / 0.8) < 1e-14);
    CHECK(get(c, DQ2) == u2);
    /* the mixed-up array: the first unknown value reference fails it */
    CHECK(fmi2GetReal(c, vr, 3, v) == fmi2Error);
    LOGGED("unknown value reference 99");
    CHECK(fabs(v[0] - 0.8) < 1e-15 && fabs(v[1]) < 1e-15);
    /* parameters: L holds the constraint (fixed), m does not (tunable) */
    CHECK(set(c, L_, 2.0) == fmi2Error);
    LOGGED("fixed constant");
    CHECK(get(c, L_) == 1.0);
    CHECK(set(c, M_, 2.0) == fmi2OK);
    CHECK(set(c, Q2, 0.1) == fmi2Error);
    LOGGED("after initialization");
    for (k = 0; k < 100; ++k) {
        CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2OK);
        t = (k + 1) * h;
    }
    q2 = get(c, Q2);
    q1 = get(c, Q1);
    CHECK(fabs(q1 * q1 + q2 * q2 - 1.0) < 1e-13);
    CHECK(fabs(get(c, FC)) < 1e-13 && fabs(get(c, FV)) < 1e-12);
    CHECK(isfinite(get(c, LAM)));
    /* steps follow each other */
    CHECK(fmi2DoStep(c, t + 0.5, h, fmi2True) == fmi2Error);
    LOGGED("is not the FMU's time");
    CHECK(fmi2DoStep(c, t, -h, fmi2True) == fmi2Error);
    CHECK(fmi2DoStep(c, t, NAN, fmi2True) == fmi2Error);
    CHECK(fmi2DoStep(c, t, 0.0, fmi2True) == fmi2OK);
    CHECK(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, v) == fmi2OK && v[0] == t);
    {   /* FMU states: save, step on, restore, step again: the same numbers,
         * also through serialization; a foreign or cut state is refused */
        fmi2FMUstate st = NULL, st2 = NULL;
        fmi2ValueReference xs[4] = {Q2, Q1, U2, U1};
        double a[4], b[4];
        size_t size = 0;
        fmi2Byte *bytes;
        CHECK(fmi2GetFMUstate(c, NULL) == fmi2Error);
        CHECK(fmi2GetFMUstate(c, &st) == fmi2OK && st != NULL);
        for (k = 0; k < 10; ++k) CHECK(fmi2DoStep(c, t + k * h, h, fmi2False) == fmi2OK);
        CHECK(fmi2GetReal(c, xs, 4, a) == fmi2OK);
        CHECK(fmi2SerializedFMUstateSize(c, st, &size) == fmi2OK && size > 64);
        bytes = (fmi2Byte *)malloc(size);
        CHECK(bytes != NULL);
        if (!bytes) return;
        CHECK(fmi2SerializeFMUstate(c, st, bytes, size) == fmi2OK);
        CHECK(fmi2SetFMUstate(c, st) == fmi2OK);
        for (k = 0; k < 10; ++k) CHECK(fmi2DoStep(c, t + k * h, h, fmi2False) == fmi2OK);
        CHECK(fmi2GetReal(c, xs, 4, b) == fmi2OK && memcmp(a, b, sizeof a) == 0);
        CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &st2) == fmi2OK && st2 != NULL);
        CHECK(fmi2SetFMUstate(c, st2) == fmi2OK);
        for (k = 0; k < 10; ++k) CHECK(fmi2DoStep(c, t + k * h, h, fmi2False) == fmi2OK);
        CHECK(fmi2GetReal(c, xs, 4, b) == fmi2OK && memcmp(a, b, sizeof a) == 0);
        CHECK(fmi2DeSerializeFMUstate(c, bytes, size - 1, &st2) == fmi2Error);
        LOGGED("was not saved by this FMU");
        bytes[3] ^= 1;
        CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &st2) == fmi2Error);
        CHECK(fmi2SerializeFMUstate(c, st, bytes, size - 1) == fmi2Error);
        free(bytes);
        CHECK(fmi2FreeFMUstate(c, &st) == fmi2OK && st == NULL);
        CHECK(fmi2FreeFMUstate(c, &st2) == fmi2OK && st2 == NULL);
        t += 10 * h;
    }
    CHECK(fmi2SetRealInputDerivatives(c, vr, 0, NULL, NULL) == fmi2Error);
    CHECK(fmi2Terminate(c) == fmi2OK);
    CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2Error);
    LOGGED("terminated");
    /* reset: the start values again, and a second run; a tolerance below
     * what double resolves is raised, with a warning */
    CHECK(fmi2Reset(c) == fmi2OK);
    CHECK(fmi2SetupExperiment(c, fmi2True, 1e-20, 0.0, fmi2False, 0.0) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK);
    LOGGED("below what the model's double arithmetic resolves; 1e-14 is used");
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK);
    CHECK(get(c, Q2) == 0.6 && get(c, U2) == 0.0 && get(c, M_) == 1.0);
    CHECK(fmi2DoStep(c, 0, h, fmi2True) == fmi2OK);
    fmi2FreeInstance(c);
}

static void test_me(void)
{
    double x[2], dx[2], nominal[2], g = 9.81;
    fmi2EventInfo info;
    fmi2Boolean enter, stop;
    fmi2Component c = fmi2Instantiate("me", fmi2ModelExchange, GEN_FMU_TOKEN, "", &callbacks,
                                      fmi2False, fmi2True);
    /* a second instance at the same time: instances share nothing */
    fmi2Component c2 = fmi2Instantiate("me2", fmi2ModelExchange, GEN_FMU_TOKEN, "", &callbacks,
                                       fmi2False, fmi2False);
    CHECK(c != NULL && c2 != NULL);
    if (!c || !c2) return;
    CHECK(set(c2, Q2, -0.6) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c2) == fmi2OK);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK);
    LOGGED("initialized at t = 0");    /* debug logging is on for c */
    CHECK(fmi2ExitInitializationMode(c2) == fmi2OK);
    CHECK(fmi2NewDiscreteStates(c, &info) == fmi2OK);
    CHECK(!info.newDiscreteStatesNeeded && !info.nextEventTimeDefined);
    CHECK(fmi2NewDiscreteStates(c, NULL) == fmi2Error);
    CHECK(fmi2GetDerivatives(c, dx, 2) == fmi2OK);        /* allowed in event mode */
    CHECK(fmi2EnterContinuousTimeMode(c) == fmi2OK);
    CHECK(fmi2NewDiscreteStates(c, &info) == fmi2Error);
    LOGGED("not allowed in continuous-time mode");
    CHECK(fmi2GetContinuousStates(c, x, 2) == fmi2OK);
    CHECK(x[0] == 0.6 && x[1] == 0.0);
    CHECK(fmi2GetContinuousStates(c, x, 4) == fmi2Error);
    LOGGED("4 continuous states given, this FMU has 2");
    CHECK(fmi2GetNominalsOfContinuousStates(c, nominal, 2) == fmi2OK && nominal[1] == 1.0);
    /* at rest at angle theta (sin = 0.6, cos = 0.8): q2'' = -g sin cos */
    CHECK(fmi2GetDerivatives(c, dx, 2) == fmi2OK);
    CHECK(dx[0] == 0.0 && fabs(dx[1] + g * 0.6 * 0.8) < 1e-12);
    /* moving: q2'' = -g sin cos - L sin theta'^2, with q2' = L cos theta' */
    x[0] = 0.6;
    x[1] = 0.4;
    CHECK(fmi2SetTime(c, 0.25) == fmi2OK);
    CHECK(fmi2SetContinuousStates(c, x, 2) == fmi2OK);
    CHECK(fmi2GetDerivatives(c, dx, 2) == fmi2OK);
    CHECK(dx[0] == 0.4 && fabs(dx[1] + g * 0.48 + 0.6 * (0.4 / 0.8) * (0.4 / 0.8)) < 1e-12);
    CHECK(fabs(get(c, U1) + 0.6 * 0.4 / 0.8) < 1e-14);
    CHECK(fabs(get(c, FC)) < 1e-15);
    /* the other instance kept its own state (q2 = -0.6 at rest) */
    CHECK(fmi2GetDerivatives(c2, dx, 2) == fmi2OK && fabs(dx[1] - g * 0.48) < 1e-12);
    /* a state the pendulum cannot reach (q2 > L): no q1 solves the
     * constraint (q2 = L itself is regular here: Newton from the last q1
     * stops at q1 ~ 1e-8, where f_c is zero to rounding) */
    x[0] = 2.0;
    x[1] = 0.0;
    CHECK(fmi2SetContinuousStates(c, x, 2) == fmi2OK);
    CHECK(fmi2GetDerivatives(c, dx, 2) == fmi2Error);
    LOGGED("cannot be solved from the independent ones");
    LOGGED("q2 = 2");
    /* and back to a regular state */
    x[0] = 0.6;
    CHECK(fmi2SetContinuousStates(c, x, 2) == fmi2OK);
    CHECK(fmi2GetDerivatives(c, dx, 2) == fmi2OK && fabs(dx[1] + g * 0.48) < 1e-12);
    /* bad arguments */
    x[1] = NAN;
    CHECK(fmi2SetContinuousStates(c, x, 2) == fmi2Error);
    LOGGED("the state u2 is not finite");
    CHECK(fmi2SetContinuousStates(c, x, 3) == fmi2Error);
    CHECK(fmi2SetContinuousStates(c, NULL, 2) == fmi2Error);
    CHECK(fmi2GetDerivatives(c, NULL, 2) == fmi2Error);
    CHECK(fmi2GetEventIndicators(c, NULL, 0) == fmi2OK);
    CHECK(fmi2GetEventIndicators(c, dx, 1) == fmi2Error);
    CHECK(fmi2CompletedIntegratorStep(c, fmi2True, &enter, &stop) == fmi2OK);
    CHECK(!enter && !stop);
    CHECK(fmi2SetTime(c, NAN) == fmi2Error);
    CHECK(fmi2DoStep(c, 0.25, 0.1, fmi2True) == fmi2Error);
    {   /* the other instance takes this one's state */
        fmi2FMUstate st = NULL;
        double dx2[2];
        CHECK(fmi2GetFMUstate(c, &st) == fmi2OK);
        CHECK(fmi2SetFMUstate(c2, st) == fmi2OK);
        CHECK(fmi2GetDerivatives(c2, dx2, 2) == fmi2OK && fabs(dx2[1] + g * 0.48) < 1e-12);
        CHECK(fmi2FreeFMUstate(c, &st) == fmi2OK);
    }
    CHECK(fmi2EnterEventMode(c) == fmi2OK);
    CHECK(set(c, G_, 1.0) == fmi2OK);                     /* tunable, in event mode */
    CHECK(fmi2Terminate(c) == fmi2OK);
    CHECK(fmi2Terminate(c2) == fmi2OK);
    fmi2FreeInstance(c);
    fmi2FreeInstance(c2);
}

static void test_singular_init(void)
{
    double v;
    fmi2ValueReference vr = Q1;
    fmi2Component c = fmi2Instantiate("bad", fmi2CoSimulation, GEN_FMU_TOKEN, "", &callbacks,
                                      fmi2False, fmi2False);
    CHECK(c != NULL);
    if (!c) return;
    /* q2 = L: the pendulum horizontal, where q1 = 0 cannot be solved for */
    CHECK(set(c, Q2, 1.0) == fmi2OK && set(c, Q1, 0.0) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK);
    n_logged = 0;
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error);
    CHECK(n_logged == 1);
    LOGGED("ExitInitializationMode: the dependent coordinates and speeds (q1, u1) cannot be "
           "solved");
    CHECK(fmi2DoStep(c, 0, 0.1, fmi2True) == fmi2Error);
    LOGGED("the error state");
    CHECK(fmi2GetReal(c, &vr, 1, &v) == fmi2Error);       /* still not solvable */
    CHECK(fmi2Terminate(c) == fmi2OK);
    fmi2FreeInstance(c);
    /* beyond the reach of the pendulum: no solution at all */
    c = fmi2Instantiate("far", fmi2ModelExchange, GEN_FMU_TOKEN, "", &callbacks, fmi2False,
                        fmi2False);
    CHECK(c != NULL);
    if (!c) return;
    CHECK(set(c, Q2, 2.0) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK);
    CHECK(fmi2ExitInitializationMode(c) == fmi2Error);
    LOGGED("cannot be solved");
    fmi2FreeInstance(c);
}

int main(void)
{
    test_layout();
    test_instantiate();
    test_cs();
    test_me();
    test_singular_init();
    if (failures) {
        fprintf(stderr, "%d checks failed\n", failures);
        return 1;
    }
    printf("fmi2 glue: all checks passed\n");
    return 0;
}
