/*
 * test_fmi3_glue.c - the FMI 3.0 glue (csrc/fmu) driven directly, on the
 * seed pendulum (Kane; q = [q2, q1], u = [u2, u1], L = 1, gravity g along
 * +x) exported with the start state q2 = 0.6, q1 = 0.8: error paths give
 * fmi3Error and a message, never a crash; the normal paths against closed
 * forms. Built with the FMU's own sources, the strict flags and ASan/UBSan
 * by tests/features/test_fmu.py.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "fmi3Functions.h"
#include "gen_fmu.h"

static char last[4096];
static int n_logged;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message)
{
    (void)env;
    (void)status;
    (void)category;
    strncpy(last, message, sizeof last - 1);
    last[sizeof last - 1] = '\0';
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

enum { Q2 = 1, Q1, U2, U1, DQ2, DU2, L_, M_, G_, LAM, FC, FV };

static double get(fmi3Instance c, fmi3ValueReference vr)
{
    double v = NAN;
    CHECK(fmi3GetFloat64(c, &vr, 1, &v, 1) == fmi3OK);
    return v;
}

static fmi3Status set(fmi3Instance c, fmi3ValueReference vr, double v)
{
    return fmi3SetFloat64(c, &vr, 1, &v, 1);
}

static fmi3Instance cs(const char *token)
{
    return fmi3InstantiateCoSimulation("cs", token, "", fmi3False, fmi3False, fmi3False,
                                       fmi3False, NULL, 0, NULL, logger, NULL);
}

static void test_instantiate(void)
{
    CHECK(strcmp(fmi3GetVersion(), "3.0") == 0);
    CHECK(cs("{not-it}") == NULL);
    LOGGED("is not this FMU's");
    CHECK(cs(NULL) == NULL);
    CHECK(fmi3InstantiateScheduledExecution("se", GEN_FMU_TOKEN, "", fmi3False, fmi3False, NULL,
                                            logger, NULL, NULL, NULL) == NULL);
    LOGGED("no Scheduled Execution");
    CHECK(fmi3DoStep(NULL, 0, 0.1, fmi3True, NULL, NULL, NULL, NULL) == fmi3Error);
    CHECK(fmi3GetFloat64(NULL, NULL, 0, NULL, 0) == fmi3Error);
    fmi3FreeInstance(NULL);
}

static void test_cs(void)
{
    fmi3Boolean event, stop, early;
    double last_t, t = 0, h = 0.01, v[2];
    fmi3ValueReference vr[2] = {Q1, U1};
    fmi3Int32 i32[1];
    int k;
    fmi3Instance c = cs(GEN_FMU_TOKEN);
    CHECK(c != NULL);
    if (!c) return;
    CHECK(set(c, U2, 0.5) == fmi3OK);
    CHECK(fmi3SetFloat64(c, vr, 2, v, 1) == fmi3Error);
    LOGGED("nValues must equal nValueReferences");
    CHECK(fmi3GetInt32(c, vr, 1, i32, 1) == fmi3Error);
    LOGGED("no variables of type Int32");
    CHECK(fmi3EnterInitializationMode(c, fmi3True, 2.0, 0.0, fmi3False, 0.0) == fmi3Error);
    LOGGED("tolerance");
    CHECK(fmi3EnterInitializationMode(c, fmi3True, 1e-10, 0.0, fmi3False, 0.0) == fmi3OK);
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK);
    CHECK(fmi3GetFloat64(c, vr, 2, v, 2) == fmi3OK);
    CHECK(fabs(v[0] - 0.8) < 1e-15 && fabs(v[1] + 0.375) < 1e-14);
    CHECK(fmi3EnterEventMode(c) == fmi3Error);
    LOGGED("hasEventMode is false");
    CHECK(fmi3DoStep(c, t, h, fmi3True, NULL, &stop, &early, &last_t) == fmi3Error);
    for (k = 0; k < 100; ++k) {
        CHECK(fmi3DoStep(c, t, h, fmi3True, &event, &stop, &early, &last_t) == fmi3OK);
        t = (k + 1) * h;
        CHECK(!event && !stop && !early && fabs(last_t - t) < 1e-15);
    }
    CHECK(fabs(get(c, Q1) * get(c, Q1) + get(c, Q2) * get(c, Q2) - 1) < 1e-13);
    CHECK(set(c, L_, 3.0) == fmi3Error);
    LOGGED("fixed constant");
    CHECK(fmi3GetFMUState(c, NULL) == fmi3Error);
    {   /* an FMU state, serialized and back: the same numbers */
        fmi3FMUState st = NULL, st2 = NULL;
        fmi3Byte bytes[sizeof(gen_fmu) + 64];
        size_t size = 0;
        double a, b;
        CHECK(fmi3GetFMUState(c, &st) == fmi3OK);
        CHECK(fmi3SerializedFMUStateSize(c, st, &size) == fmi3OK && size == sizeof bytes);
        CHECK(fmi3SerializeFMUState(c, st, bytes, size) == fmi3OK);
        CHECK(fmi3DoStep(c, t, h, fmi3True, &event, &stop, &early, &last_t) == fmi3OK);
        a = get(c, Q2);
        CHECK(fmi3DeserializeFMUState(c, bytes, size, &st2) == fmi3OK);
        CHECK(fmi3SetFMUState(c, st2) == fmi3OK);
        CHECK(fmi3DoStep(c, t, h, fmi3True, &event, &stop, &early, &last_t) == fmi3OK);
        b = get(c, Q2);
        CHECK(a == b);
        CHECK(fmi3SetFMUState(c, st) == fmi3OK);       /* back to t */
        CHECK(fmi3FreeFMUState(c, &st) == fmi3OK && st == NULL);
        CHECK(fmi3FreeFMUState(c, &st2) == fmi3OK);
        bytes[0] = 'x';
        CHECK(fmi3DeserializeFMUState(c, bytes, size, &st2) == fmi3Error);
        LOGGED("was not saved by this FMU");
    }
    CHECK(fmi3Terminate(c) == fmi3OK);
    CHECK(fmi3Reset(c) == fmi3OK);
    CHECK(fmi3GetFloat64(c, vr, 1, v, 1) == fmi3Error);
    LOGGED("not allowed in the instantiated state");
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0, 0.0, fmi3False, 0) == fmi3OK);
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK);
    CHECK(get(c, Q2) == 0.6 && get(c, U2) == 0.0);
    fmi3FreeInstance(c);
}

static void test_me(void)
{
    size_t n;
    double x[2] = {0.6, 0.4}, dx[2], g = 9.81;
    fmi3Boolean a, b, c_, d_, e;
    double next;
    fmi3Instance c = fmi3InstantiateModelExchange("me", GEN_FMU_TOKEN, "", fmi3False, fmi3False,
                                                  NULL, logger);
    CHECK(c != NULL);
    if (!c) return;
    CHECK(fmi3GetNumberOfContinuousStates(c, &n) == fmi3OK && n == 2);
    CHECK(fmi3GetNumberOfEventIndicators(c, &n) == fmi3OK && n == 0);
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0, 0.0, fmi3False, 0) == fmi3OK);
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK);
    CHECK(fmi3UpdateDiscreteStates(c, &a, &b, &c_, &d_, &e, &next) == fmi3OK);
    CHECK(!a && !b && !c_ && !d_ && !e);
    CHECK(fmi3EnterContinuousTimeMode(c) == fmi3OK);
    CHECK(fmi3SetContinuousStates(c, x, 2) == fmi3OK);
    CHECK(fmi3GetContinuousStateDerivatives(c, dx, 2) == fmi3OK);
    CHECK(dx[0] == 0.4 && fabs(dx[1] + g * 0.48 + 0.6 * 0.25) < 1e-12);
    x[0] = 2.0;     /* beyond the pendulum's reach: no q1 solves the constraint */
    x[1] = 0.0;
    CHECK(fmi3SetContinuousStates(c, x, 2) == fmi3OK);
    CHECK(fmi3GetContinuousStateDerivatives(c, dx, 2) == fmi3Error);
    LOGGED("cannot be solved from the independent ones");
    CHECK(fmi3GetContinuousStateDerivatives(c, dx, 1) == fmi3Error);
    CHECK(fmi3CompletedIntegratorStep(c, fmi3True, &a, NULL) == fmi3Error);
    CHECK(fmi3Terminate(c) == fmi3OK);
    fmi3FreeInstance(c);
}

static void test_singular_init(void)
{
    fmi3Instance c = cs(GEN_FMU_TOKEN);
    CHECK(c != NULL);
    if (!c) return;
    CHECK(set(c, Q2, 1.0) == fmi3OK && set(c, Q1, 0.0) == fmi3OK);
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0, 0.0, fmi3False, 0) == fmi3OK);
    n_logged = 0;
    CHECK(fmi3ExitInitializationMode(c) == fmi3Error);
    CHECK(n_logged == 1);
    LOGGED("cannot be solved from the independent ones");
    fmi3FreeInstance(c);
}

int main(void)
{
    test_instantiate();
    test_cs();
    test_me();
    test_singular_init();
    if (failures) {
        fprintf(stderr, "%d checks failed\n", failures);
        return 1;
    }
    printf("fmi3 glue: all checks passed\n");
    return 0;
}
