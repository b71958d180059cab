/* A stand-in for pythonfmu's binary, to test the shim without a slave: the shim forwards
 * to it as to pythonfmu-export.so.  fmi2DoStep logs what a slave logs for a warning a user
 * asked not to fail the step with (status OK, category "logStatusWarning") and an ordinary
 * debug message (status OK, category "logAll"), and returns fmi2OK.  Every other FMI
 * function exists and does nothing. */
#include "fmi2_abi.h"

static fmi2CallbackFunctions callbacks;
static int component;

void *fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                      const fmi2CallbackFunctions *f, fmi2Boolean visible, fmi2Boolean logging) {
    (void)name, (void)type, (void)guid, (void)resources, (void)visible, (void)logging;
    callbacks = *f;
    return &component;
}

fmi2Status fmi2DoStep(void *c, fmi2Real t, fmi2Real h, fmi2Boolean no_set_prior) {
    (void)c, (void)t, (void)h, (void)no_set_prior;
    callbacks.logger(callbacks.componentEnvironment, "fake", fmi2OK, "logStatusWarning",
                     "gimbal rate command limited");
    callbacks.logger(callbacks.componentEnvironment, "fake", fmi2OK, "logAll", "debug detail");
    return fmi2OK;
}

#define NOTHING(name) int name(void) { return fmi2OK; }
NOTHING(fmi2FreeInstance) NOTHING(fmi2SetupExperiment) NOTHING(fmi2EnterInitializationMode)
NOTHING(fmi2ExitInitializationMode) NOTHING(fmi2Terminate) NOTHING(fmi2Reset)
NOTHING(fmi2GetReal) NOTHING(fmi2GetInteger) NOTHING(fmi2GetBoolean) NOTHING(fmi2GetString)
NOTHING(fmi2SetReal) NOTHING(fmi2SetInteger) NOTHING(fmi2SetBoolean) NOTHING(fmi2SetString)
NOTHING(fmi2GetFMUstate) NOTHING(fmi2SetFMUstate) NOTHING(fmi2FreeFMUstate)
NOTHING(fmi2SerializedFMUstateSize) NOTHING(fmi2SerializeFMUstate)
NOTHING(fmi2DeSerializeFMUstate) NOTHING(fmi2GetDirectionalDerivative)
NOTHING(fmi2SetRealInputDerivatives) NOTHING(fmi2GetRealOutputDerivatives)
NOTHING(fmi2CancelStep) NOTHING(fmi2GetStatus) NOTHING(fmi2GetRealStatus)
NOTHING(fmi2GetIntegerStatus) NOTHING(fmi2GetBooleanStatus) NOTHING(fmi2GetStringStatus)
