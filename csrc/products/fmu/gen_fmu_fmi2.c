/*
 * gen_fmu_fmi2.c - the FMI 2.0 interface (Model Exchange and Co-Simulation)
 * of an eomgen model, over the version-independent glue of gen_fmu.c.
 *
 * The FMI 2.0 headers (fmi2Functions.h, fmi2FunctionTypes.h,
 * fmi2TypesPlatform.h) are the importer's, as the standard has it: eomgen
 * takes them from the installed FMPy when it builds the binary.
 *
 * Every function checks its instance and arrays first; a failure is a
 * status (fmi2Error) and a message through the importer's logger.
 */
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"
#include "gen_fmu.h"

typedef struct {
    gen_fmu core;
    fmi2CallbackFunctions cb;
    char name[256];               /* the instance name as given (the logger's) */
    int tolerance_defined;
    double tolerance, start_time;
} fmi2_instance;

/* the importer's logger takes a printf format: '%' is doubled */
static void fmi2_log(void *layer, int status, const char *category, const char *message)
{
    fmi2_instance *s = (fmi2_instance *)layer;
    char text[1100];
    size_t i, j = 0;
    if (!s->cb.logger) return;
    for (i = 0; message[i] && j + 2 < sizeof text; ++i) {
        if (message[i] == '%') text[j++] = '%';
        text[j++] = message[i];
    }
    text[j] = '\0';
    s->cb.logger(s->cb.componentEnvironment, s->name, (fmi2Status)status, category, text);
}

#define INSTANCE(comp) ((fmi2_instance *)(comp))
/* the instance, or return fmi2Error when the importer passed none */
#define CORE(comp)                                                             \
    gen_fmu *c = (comp) ? &INSTANCE(comp)->core : NULL;                         \
    if (!c) return fmi2Error

static fmi2Status null_arg(gen_fmu *c, const char *fn, const char *what)
{
    char text[200];
    strcpy(text, fn);
    strcat(text, ": ");
    strncat(text, what, sizeof text - strlen(text) - 40);
    strcat(text, " is NULL");
    gen_fmu_log(c, GEN_FMU_ERROR, "logStatusError", text);
    return fmi2Error;
}

/* ---------------------------------------------------------------- common */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    CORE(comp);
    (void)categories;
    (void)nCategories;
    c->debug = loggingOn ? 1 : 0;
    return fmi2OK;
}

static fmi2Component refuse(fmi2_instance *s, const char *why)
{
    if (why) gen_fmu_log(&s->core, GEN_FMU_ERROR, "logStatusError", why);
    if (s->cb.freeMemory) s->cb.freeMemory(s);
    else free(s);
    return NULL;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    fmi2_instance *s;
    int kind = fmuType == fmi2ModelExchange ? GEN_FMU_ME : GEN_FMU_CS;
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions) return NULL;
    s = functions->allocateMemory ? (fmi2_instance *)functions->allocateMemory(1, sizeof *s)
                                  : (fmi2_instance *)calloc(1, sizeof *s);
    if (!s) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "fmi2Instantiate: out of memory");
        return NULL;
    }
    memset(s, 0, sizeof *s);
    s->cb = *functions;
    if (instanceName) {
        strncpy(s->name, instanceName, sizeof s->name - 1);
        s->name[sizeof s->name - 1] = '\0';
    }
    gen_fmu_setup(&s->core, kind, instanceName, loggingOn ? 1 : 0, fmi2_log, s);
    if (fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation)
        return refuse(s, "fmi2Instantiate: fmuType is neither fmi2ModelExchange nor "
                         "fmi2CoSimulation");
    if (gen_fmu_check_token(&s->core, fmuGUID)) return refuse(s, NULL);
    if (kind == GEN_FMU_ME && !GEN_FMU_HAS_ME)
        return refuse(s, "fmi2Instantiate: this FMU was exported without Model Exchange "
                         "(export it with kind='me' or 'both')");
    if (kind == GEN_FMU_CS && !GEN_FMU_HAS_CS)
        return refuse(s, "fmi2Instantiate: this FMU was exported without Co-Simulation "
                         "(export it with kind='cs' or 'both')");
    return s;
}

void fmi2FreeInstance(fmi2Component comp)
{
    fmi2_instance *s = INSTANCE(comp);
    if (!s) return;
    if (s->cb.freeMemory) s->cb.freeMemory(s);
    else free(s);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    CORE(comp);
    (void)stopTimeDefined;
    (void)stopTime;
    if (gen_fmu_allowed(c, "fmi2SetupExperiment", GEN_FMU_INSTANTIATED)) return fmi2Error;
    INSTANCE(comp)->tolerance_defined = toleranceDefined ? 1 : 0;
    INSTANCE(comp)->tolerance = tolerance;
    INSTANCE(comp)->start_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_enter_init(c, INSTANCE(comp)->tolerance_defined,
                                          INSTANCE(comp)->tolerance, INSTANCE(comp)->start_time);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_exit_init(c);
}

fmi2Status fmi2Terminate(fmi2Component comp)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_terminate(c);
}

fmi2Status fmi2Reset(fmi2Component comp)
{
    CORE(comp);
    INSTANCE(comp)->tolerance_defined = 0;
    INSTANCE(comp)->start_time = 0;
    return (fmi2Status)gen_fmu_reset(c);
}

/* ------------------------------------------------------------ variables */
#define GET_MODES (GEN_FMU_INIT | GEN_FMU_EVENT | GEN_FMU_CONT | GEN_FMU_STEP | \
                   GEN_FMU_TERMINATED | GEN_FMU_FAILED)

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    size_t i;
    CORE(comp);
    if (gen_fmu_allowed(c, "fmi2GetReal", GET_MODES)) return fmi2Error;
    if (nvr && (!vr || !value)) return null_arg(c, "fmi2GetReal", "vr or value");
    for (i = 0; i < nvr; ++i)
        if (gen_fmu_get_real(c, "fmi2GetReal", vr[i], &value[i])) return fmi2Error;
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    size_t i;
    CORE(comp);
    if (nvr && (!vr || !value)) return null_arg(c, "fmi2SetReal", "vr or value");
    for (i = 0; i < nvr; ++i)
        if (gen_fmu_set_real(c, "fmi2SetReal", vr[i], value[i])) return fmi2Error;
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    CORE(comp);
    (void)vr;
    (void)value;
    return (fmi2Status)gen_fmu_no_such_variables(c, "fmi2GetInteger", nvr, "Integer");
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    CORE(comp);
    (void)vr;
    (void)value;
    return (fmi2Status)gen_fmu_no_such_variables(c, "fmi2GetBoolean", nvr, "Boolean");
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    CORE(comp);
    (void)vr;
    (void)value;
    return (fmi2Status)gen_fmu_no_such_variables(c, "fmi2GetString", nvr, "String");
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    CORE(comp);
    (void)vr;
    (void)value;
    return (fmi2Status)gen_fmu_no_such_variables(c, "fmi2SetInteger", nvr, "Integer");
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    CORE(comp);
    (void)vr;
    (void)value;
    return (fmi2Status)gen_fmu_no_such_variables(c, "fmi2SetBoolean", nvr, "Boolean");
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    CORE(comp);
    (void)vr;
    (void)value;
    return (fmi2Status)gen_fmu_no_such_variables(c, "fmi2SetString", nvr, "String");
}

/* ------------------------------------------- features this FMU has not */
static fmi2Status unsupported(fmi2Component comp, const char *fn, const char *why)
{
    char text[300];
    CORE(comp);
    strcpy(text, fn);
    strcat(text, " is not supported by this FMU: ");
    strncat(text, why, sizeof text - strlen(text) - 1);
    gen_fmu_log(c, GEN_FMU_ERROR, "logStatusError", text);
    return fmi2Error;
}

/* ------------------------------------------------------------ FMU states */
static void *state_alloc(fmi2_instance *s)
{
    return s->cb.allocateMemory ? s->cb.allocateMemory(1, GEN_FMU_STATE_SIZE)
                                : calloc(1, GEN_FMU_STATE_SIZE);
}

static void state_free(fmi2_instance *s, void *p)
{
    if (s->cb.freeMemory) s->cb.freeMemory(p);
    else free(p);
}

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    void *p;
    CORE(comp);
    if (!FMUstate) return null_arg(c, "fmi2GetFMUstate", "FMUstate");
    /* a state given back is overwritten in place */
    p = *FMUstate ? *FMUstate : state_alloc(INSTANCE(comp));
    if (!p) return null_arg(c, "fmi2GetFMUstate", "the memory for the state (out of memory)");
    gen_fmu_save(c, (unsigned char *)p);
    *FMUstate = p;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate FMUstate)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_restore(c, "fmi2SetFMUstate", (const unsigned char *)FMUstate,
                                       FMUstate ? GEN_FMU_STATE_SIZE : 0);
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    CORE(comp);
    if (!FMUstate) return null_arg(c, "fmi2FreeFMUstate", "FMUstate");
    if (*FMUstate) state_free(INSTANCE(comp), *FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate FMUstate, size_t *size)
{
    CORE(comp);
    (void)FMUstate;
    if (!size) return null_arg(c, "fmi2SerializedFMUstateSize", "size");
    *size = GEN_FMU_STATE_SIZE;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size)
{
    CORE(comp);
    if (gen_fmu_check_state(c, "fmi2SerializeFMUstate", (const unsigned char *)FMUstate,
                            FMUstate ? GEN_FMU_STATE_SIZE : 0))
        return fmi2Error;
    if (!serializedState || size < GEN_FMU_STATE_SIZE)
        return null_arg(c, "fmi2SerializeFMUstate", "serializedState (of at least "
                        "fmi2SerializedFMUstateSize bytes)");
    memcpy(serializedState, FMUstate, GEN_FMU_STATE_SIZE);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate *FMUstate)
{
    void *p;
    CORE(comp);
    if (!FMUstate) return null_arg(c, "fmi2DeSerializeFMUstate", "FMUstate");
    if (gen_fmu_check_state(c, "fmi2DeSerializeFMUstate",
                            (const unsigned char *)serializedState, size))
        return fmi2Error;
    p = *FMUstate ? *FMUstate : state_alloc(INSTANCE(comp));
    if (!p) return null_arg(c, "fmi2DeSerializeFMUstate", "the memory (out of memory)");
    memcpy(p, serializedState, GEN_FMU_STATE_SIZE);
    *FMUstate = p;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp,
                                        const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return unsupported(comp, "fmi2GetDirectionalDerivative",
                       "providesDirectionalDerivative is false");
}

/* ------------------------------------------------------- Model Exchange */
fmi2Status fmi2EnterEventMode(fmi2Component comp)
{
    CORE(comp);
    if (gen_fmu_allowed(c, "fmi2EnterEventMode", GEN_FMU_EVENT | GEN_FMU_CONT)) return fmi2Error;
    c->mode = GEN_FMU_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component comp, fmi2EventInfo *eventInfo)
{
    CORE(comp);
    if (gen_fmu_allowed(c, "fmi2NewDiscreteStates", GEN_FMU_EVENT)) return fmi2Error;
    if (!eventInfo) return null_arg(c, "fmi2NewDiscreteStates", "eventInfo");
    /* no discrete states or time events; a hybrid model's jumps (impacts,
     * resets, lift-off) update the continuous states */
    {
        int changed = 0, again = 0, st = gen_fmu_new_discrete_states(c, &changed, &again);
        eventInfo->newDiscreteStatesNeeded = again ? fmi2True : fmi2False;
        eventInfo->terminateSimulation = fmi2False;
        eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
        eventInfo->valuesOfContinuousStatesChanged = changed ? fmi2True : fmi2False;
        eventInfo->nextEventTimeDefined = fmi2False;
        eventInfo->nextEventTime = 0;
        if (st) return (fmi2Status)st;
    }
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component comp)
{
    CORE(comp);
    if (gen_fmu_allowed(c, "fmi2EnterContinuousTimeMode", GEN_FMU_EVENT)) return fmi2Error;
    c->mode = GEN_FMU_CONT;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component comp,
                                       fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode,
                                       fmi2Boolean *terminateSimulation)
{
    CORE(comp);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (gen_fmu_allowed(c, "fmi2CompletedIntegratorStep", GEN_FMU_CONT)) return fmi2Error;
    if (!enterEventMode || !terminateSimulation)
        return null_arg(c, "fmi2CompletedIntegratorStep", "enterEventMode or terminateSimulation");
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return (fmi2Status)gen_fmu_completed_step(c);
}

fmi2Status fmi2SetTime(fmi2Component comp, fmi2Real time)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_set_time(c, time);
}

fmi2Status fmi2SetContinuousStates(fmi2Component comp, const fmi2Real x[], size_t nx)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_set_states(c, x, nx);
}

fmi2Status fmi2GetDerivatives(fmi2Component comp, fmi2Real derivatives[], size_t nx)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_get_derivatives(c, derivatives, nx);
}

fmi2Status fmi2GetEventIndicators(fmi2Component comp, fmi2Real eventIndicators[], size_t ni)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_event_indicators(c, eventIndicators, ni);
}

fmi2Status fmi2GetContinuousStates(fmi2Component comp, fmi2Real x[], size_t nx)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_get_states(c, x, nx);
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component comp, fmi2Real x_nominal[], size_t nx)
{
    CORE(comp);
    return (fmi2Status)gen_fmu_get_nominals(c, x_nominal, nx);
}

/* --------------------------------------------------------- Co-Simulation */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(comp, "fmi2SetRealInputDerivatives", "canInterpolateInputs is false "
                       "(inputs are held over a communication step)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[])
{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(comp, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0");
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    CORE(comp);
    (void)noSetFMUStatePriorToCurrentPoint;
    return (fmi2Status)gen_fmu_do_step(c, currentCommunicationPoint, communicationStepSize);
}

fmi2Status fmi2CancelStep(fmi2Component comp)
{
    return unsupported(comp, "fmi2CancelStep", "doStep never returns fmi2Pending");
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    (void)value;
    return unsupported(comp, "fmi2GetStatus", "doStep never returns fmi2Pending");
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value)
{
    CORE(comp);
    if (s == fmi2LastSuccessfulTime && value) {
        *value = c->time;
        return fmi2OK;
    }
    return unsupported(comp, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is reported");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    return unsupported(comp, "fmi2GetIntegerStatus", "no integer status");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value)
{
    CORE(comp);
    if (s == fmi2Terminated && value) {
        *value = fmi2False;
        return fmi2OK;
    }
    return unsupported(comp, "fmi2GetBooleanStatus", "only fmi2Terminated is reported");
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    return unsupported(comp, "fmi2GetStringStatus", "no string status");
}
