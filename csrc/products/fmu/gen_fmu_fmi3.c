/*
 * gen_fmu_fmi3.c - the FMI 3.0 interface (Model Exchange and Co-Simulation)
 * of an eomgen model, over the version-independent glue of gen_fmu.c.
 *
 * The FMI 3.0 headers (fmi3Functions.h, fmi3FunctionTypes.h,
 * fmi3PlatformTypes.h) are the importer's, as the standard has it: eomgen
 * takes them from the installed FMPy when it builds the binary.
 *
 * Every function checks its instance and arrays first; a failure is a
 * status (fmi3Error) and a message through the importer's logger. The
 * variables are Float64 scalars: every other type, clocks, directional
 * derivatives, event mode in Co-Simulation and Scheduled Execution are
 * refused with a message.
 */
#include <stdlib.h>
#include <string.h>
#include "fmi3Functions.h"
#include "gen_fmu.h"

typedef struct {
    gen_fmu core;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logger;
} fmi3_instance;

static void fmi3_log(void *layer, int status, const char *category, const char *message)
{
    fmi3_instance *s = (fmi3_instance *)layer;
    if (s->logger) s->logger(s->env, (fmi3Status)status, category, message);
}

#define INSTANCE(inst) ((fmi3_instance *)(inst))
/* the instance, or return fmi3Error when the importer passed none */
#define CORE(inst)                                                             \
    gen_fmu *c = (inst) ? &INSTANCE(inst)->core : NULL;                         \
    if (!c) return fmi3Error

static fmi3Status refuse_call(gen_fmu *c, const char *fn, const char *why)
{
    char text[300];
    strcpy(text, fn);
    strcat(text, ": ");
    strncat(text, why, sizeof text - strlen(text) - 1);
    gen_fmu_log(c, GEN_FMU_ERROR, "logStatusError", text);
    return fmi3Error;
}

/* ---------------------------------------------------------------- common */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    CORE(instance);
    (void)nCategories;
    (void)categories;
    c->debug = loggingOn ? 1 : 0;
    return fmi3OK;
}

static fmi3Instance instantiate(int kind, fmi3String instanceName, fmi3String token,
                                fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                                fmi3LogMessageCallback logMessage)
{
    fmi3_instance *s = (fmi3_instance *)calloc(1, sizeof *s);
    if (!s) {
        if (logMessage) logMessage(env, fmi3Error, "logStatusError", "fmi3Instantiate: out of memory");
        return NULL;
    }
    s->env = env;
    s->logger = logMessage;
    gen_fmu_setup(&s->core, kind, instanceName, loggingOn ? 1 : 0, fmi3_log, s);
    if (gen_fmu_check_token(&s->core, token)) {
        free(s);
        return NULL;
    }
    if ((kind == GEN_FMU_ME && !GEN_FMU_HAS_ME) || (kind == GEN_FMU_CS && !GEN_FMU_HAS_CS)) {
        gen_fmu_log(&s->core, GEN_FMU_ERROR, "logStatusError",
                    kind == GEN_FMU_ME ? "fmi3InstantiateModelExchange: this FMU was exported "
                                         "without Model Exchange (export it with kind='me' or "
                                         "'both')"
                                       : "fmi3InstantiateCoSimulation: this FMU was exported "
                                         "without Co-Simulation (export it with kind='cs' or "
                                         "'both')");
        free(s);
        return NULL;
    }
    return s;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)resourcePath;
    (void)visible;
    return instantiate(GEN_FMU_ME, instanceName, instantiationToken, loggingOn,
                       instanceEnvironment, logMessage);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)resourcePath;
    (void)visible;
    (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    /* without event mode and early return (hasEventMode and
     * mightReturnEarlyFromDoStep are false) the flags change nothing */
    (void)eventModeUsed;
    (void)earlyReturnAllowed;
    return instantiate(GEN_FMU_CS, instanceName, instantiationToken, loggingOn,
                       instanceEnvironment, logMessage);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName,
                                               fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: this FMU has no Scheduled Execution");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    free(instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    CORE(instance);
    (void)stopTimeDefined;
    (void)stopTime;
    return (fmi3Status)gen_fmu_enter_init(c, toleranceDefined ? 1 : 0, tolerance, startTime);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_exit_init(c);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    CORE(instance);
    if (c->kind == GEN_FMU_CS)
        return refuse_call(c, "fmi3EnterEventMode", "this Co-Simulation FMU has no event mode "
                           "(hasEventMode is false)");
    if (gen_fmu_allowed(c, "fmi3EnterEventMode", GEN_FMU_EVENT | GEN_FMU_CONT)) return fmi3Error;
    c->mode = GEN_FMU_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_terminate(c);
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_reset(c);
}

/* ------------------------------------------------------------ variables */
#define GET_MODES (GEN_FMU_INIT | GEN_FMU_EVENT | GEN_FMU_CONT | GEN_FMU_STEP | \
                   GEN_FMU_TERMINATED | GEN_FMU_FAILED)

static fmi3Status counts(gen_fmu *c, const char *fn, size_t nvr, size_t nvalues,
                         const void *vr, const void *values)
{
    if (nvr && (!vr || !values)) return refuse_call(c, fn, "valueReferences or values is NULL");
    if (nvalues != nvr)
        return refuse_call(c, fn, "nValues must equal nValueReferences (every variable of "
                           "this FMU is a scalar)");
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues)
{
    size_t i;
    CORE(instance);
    if (gen_fmu_allowed(c, "fmi3GetFloat64", GET_MODES)) return fmi3Error;
    if (counts(c, "fmi3GetFloat64", nValueReferences, nValues, valueReferences, values))
        return fmi3Error;
    for (i = 0; i < nValueReferences; ++i)
        if (gen_fmu_get_real(c, "fmi3GetFloat64", valueReferences[i], &values[i]))
            return fmi3Error;
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    size_t i;
    CORE(instance);
    if (counts(c, "fmi3SetFloat64", nValueReferences, nValues, valueReferences, values))
        return fmi3Error;
    for (i = 0; i < nValueReferences; ++i)
        if (gen_fmu_set_real(c, "fmi3SetFloat64", valueReferences[i], values[i]))
            return fmi3Error;
    return fmi3OK;
}

/* the getters and setters of the types this FMU has no variables of */
#define NO_GET(T, type)                                                                  \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                          type values[], size_t nValues)                                 \
    {                                                                                    \
        CORE(instance);                                                                  \
        (void)vr;                                                                        \
        (void)values;                                                                    \
        (void)nValues;                                                                   \
        return (fmi3Status)gen_fmu_no_such_variables(c, "fmi3Get" #T, nvr, #T);          \
    }
#define NO_SET(T, type)                                                                  \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                          const type values[], size_t nValues)                           \
    {                                                                                    \
        CORE(instance);                                                                  \
        (void)vr;                                                                        \
        (void)values;                                                                    \
        (void)nValues;                                                                   \
        return (fmi3Status)gen_fmu_no_such_variables(c, "fmi3Set" #T, nvr, #T);          \
    }

NO_GET(Float32, fmi3Float32)
NO_GET(Int8, fmi3Int8)
NO_GET(UInt8, fmi3UInt8)
NO_GET(Int16, fmi3Int16)
NO_GET(UInt16, fmi3UInt16)
NO_GET(Int32, fmi3Int32)
NO_GET(UInt32, fmi3UInt32)
NO_GET(Int64, fmi3Int64)
NO_GET(UInt64, fmi3UInt64)
NO_GET(Boolean, fmi3Boolean)
NO_GET(String, fmi3String)
NO_SET(Float32, fmi3Float32)
NO_SET(Int8, fmi3Int8)
NO_SET(UInt8, fmi3UInt8)
NO_SET(Int16, fmi3Int16)
NO_SET(UInt16, fmi3UInt16)
NO_SET(Int32, fmi3Int32)
NO_SET(UInt32, fmi3UInt32)
NO_SET(Int64, fmi3Int64)
NO_SET(UInt64, fmi3UInt64)
NO_SET(Boolean, fmi3Boolean)
NO_SET(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[],
                         size_t nValues)
{
    CORE(instance);
    (void)valueReferences;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return (fmi3Status)gen_fmu_no_such_variables(c, "fmi3GetBinary", nValueReferences, "Binary");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues)
{
    CORE(instance);
    (void)valueReferences;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return (fmi3Status)gen_fmu_no_such_variables(c, "fmi3SetBinary", nValueReferences, "Binary");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[])
{
    CORE(instance);
    (void)valueReferences;
    (void)values;
    return (fmi3Status)gen_fmu_no_such_variables(c, "fmi3GetClock", nValueReferences, "Clock");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[])
{
    CORE(instance);
    (void)valueReferences;
    (void)values;
    return (fmi3Status)gen_fmu_no_such_variables(c, "fmi3SetClock", nValueReferences, "Clock");
}

/* ------------------------------------------- features this FMU has not */
#define UNSUPPORTED(inst, fn, why)                                             \
    do {                                                                       \
        CORE(inst);                                                            \
        return refuse_call(c, fn, why);                                        \
    } while (0)

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference;
    (void)nDependencies;
    UNSUPPORTED(instance, "fmi3GetNumberOfVariableDependencies", "not supported: the "
                "dependencies are in the ModelStructure of modelDescription.xml");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies)
{
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    UNSUPPORTED(instance, "fmi3GetVariableDependencies", "not supported: the dependencies "
                "are in the ModelStructure of modelDescription.xml");
}

/* ------------------------------------------------------------ FMU states */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    void *p;
    CORE(instance);
    if (!FMUState) return refuse_call(c, "fmi3GetFMUState", "FMUState is NULL");
    /* a state given back is overwritten in place */
    p = *FMUState ? *FMUState : calloc(1, GEN_FMU_STATE_SIZE);
    if (!p) return refuse_call(c, "fmi3GetFMUState", "out of memory");
    gen_fmu_save(c, (unsigned char *)p);
    *FMUState = p;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_restore(c, "fmi3SetFMUState", (const unsigned char *)FMUState,
                                       FMUState ? GEN_FMU_STATE_SIZE : 0);
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    CORE(instance);
    if (!FMUState) return refuse_call(c, "fmi3FreeFMUState", "FMUState is NULL");
    free(*FMUState);
    *FMUState = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                      size_t *size)
{
    CORE(instance);
    (void)FMUState;
    if (!size) return refuse_call(c, "fmi3SerializedFMUStateSize", "size is NULL");
    *size = GEN_FMU_STATE_SIZE;
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size)
{
    CORE(instance);
    if (gen_fmu_check_state(c, "fmi3SerializeFMUState", (const unsigned char *)FMUState,
                            FMUState ? GEN_FMU_STATE_SIZE : 0))
        return fmi3Error;
    if (!serializedState || size < GEN_FMU_STATE_SIZE)
        return refuse_call(c, "fmi3SerializeFMUState", "serializedState is NULL or smaller "
                           "than fmi3SerializedFMUStateSize");
    memcpy(serializedState, FMUState, GEN_FMU_STATE_SIZE);
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState)
{
    void *p;
    CORE(instance);
    if (!FMUState) return refuse_call(c, "fmi3DeserializeFMUState", "FMUState is NULL");
    if (gen_fmu_check_state(c, "fmi3DeserializeFMUState",
                            (const unsigned char *)serializedState, size))
        return fmi3Error;
    p = *FMUState ? *FMUState : calloc(1, GEN_FMU_STATE_SIZE);
    if (!p) return refuse_call(c, "fmi3DeserializeFMUState", "out of memory");
    memcpy(p, serializedState, GEN_FMU_STATE_SIZE);
    *FMUState = p;
    return fmi3OK;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    UNSUPPORTED(instance, "fmi3GetDirectionalDerivative",
                "not supported (providesDirectionalDerivatives is false)");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    UNSUPPORTED(instance, "fmi3GetAdjointDerivative",
                "not supported (providesAdjointDerivatives is false)");
}

#define NO_CONFIG "not supported: this FMU has no structural parameters"
#define NO_CLOCKS "not supported: this FMU has no clocks"

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    UNSUPPORTED(instance, "fmi3EnterConfigurationMode", NO_CONFIG);
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    UNSUPPORTED(instance, "fmi3ExitConfigurationMode", NO_CONFIG);
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    (void)qualifiers;
    UNSUPPORTED(instance, "fmi3GetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[],
                                   fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    UNSUPPORTED(instance, "fmi3GetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    UNSUPPORTED(instance, "fmi3GetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[],
                                fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    UNSUPPORTED(instance, "fmi3GetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    UNSUPPORTED(instance, "fmi3SetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    UNSUPPORTED(instance, "fmi3SetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    UNSUPPORTED(instance, "fmi3SetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    UNSUPPORTED(instance, "fmi3SetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    CORE(instance);
    (void)c;
    return fmi3OK;   /* no discrete states */
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime)
{
    CORE(instance);
    if (gen_fmu_allowed(c, "fmi3UpdateDiscreteStates", GEN_FMU_EVENT)) return fmi3Error;
    if (!discreteStatesNeedUpdate || !terminateSimulation || !nominalsOfContinuousStatesChanged ||
        !valuesOfContinuousStatesChanged || !nextEventTimeDefined || !nextEventTime)
        return refuse_call(c, "fmi3UpdateDiscreteStates", "an output argument is NULL");
    /* no discrete states, no time or state events */
    *discreteStatesNeedUpdate = fmi3False;
    *terminateSimulation = fmi3False;
    *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = fmi3False;
    *nextEventTimeDefined = fmi3False;
    *nextEventTime = 0;
    return fmi3OK;
}

/* ------------------------------------------------------- Model Exchange */
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    CORE(instance);
    if (gen_fmu_allowed(c, "fmi3EnterContinuousTimeMode", GEN_FMU_EVENT)) return fmi3Error;
    c->mode = GEN_FMU_CONT;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation)
{
    CORE(instance);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (gen_fmu_allowed(c, "fmi3CompletedIntegratorStep", GEN_FMU_CONT)) return fmi3Error;
    if (!enterEventMode || !terminateSimulation)
        return refuse_call(c, "fmi3CompletedIntegratorStep", "an output argument is NULL");
    *enterEventMode = fmi3False;
    *terminateSimulation = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_set_time(c, time);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_set_states(c, continuousStates, nContinuousStates);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_get_derivatives(c, derivatives, nContinuousStates);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators)
{
    CORE(instance);
    (void)eventIndicators;
    if (nEventIndicators == 0) return fmi3OK;
    return refuse_call(c, "fmi3GetEventIndicators", "this FMU has no event indicators");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_get_states(c, continuousStates, nContinuousStates);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    CORE(instance);
    return (fmi3Status)gen_fmu_get_nominals(c, nominals, nContinuousStates);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    CORE(instance);
    if (!nEventIndicators)
        return refuse_call(c, "fmi3GetNumberOfEventIndicators", "nEventIndicators is NULL");
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    CORE(instance);
    if (!nContinuousStates)
        return refuse_call(c, "fmi3GetNumberOfContinuousStates", "nContinuousStates is NULL");
    *nContinuousStates = (size_t)GEN_FMU_NS;
    return fmi3OK;
}

/* --------------------------------------------------------- Co-Simulation */
fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    UNSUPPORTED(instance, "fmi3EnterStepMode", "this Co-Simulation FMU has no event mode "
                "(hasEventMode is false): it is in step mode after ExitInitializationMode");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t nValues)
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)orders;
    (void)values;
    (void)nValues;
    UNSUPPORTED(instance, "fmi3GetOutputDerivatives",
                "not supported (maxOutputDerivativeOrder is 0)");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    int st;
    CORE(instance);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return refuse_call(c, "fmi3DoStep", "an output argument is NULL");
    st = gen_fmu_do_step(c, currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = c->time;
    return (fmi3Status)st;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference;
    (void)activationTime;
    UNSUPPORTED(instance, "fmi3ActivateModelPartition", "this FMU has no Scheduled Execution");
}
