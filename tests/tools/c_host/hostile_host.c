/* A C host that makes late calls: it drives one FMU as a C tool does, then calls
 * fmi2Terminate and fmi2FreeInstance after the Python interpreter the FMU runs in is gone.
 *
 *     hostile_host DIR MODEL_IDENTIFIER GUID finalize|destructor
 *
 * DIR is the extracted FMU.  finalize: the host finalizes the embedded Python itself (as a
 * tool that also embeds Python does at shutdown), then makes the calls.  destructor: the
 * calls come from a static destructor, after exit() has run the exit handlers.  Each
 * call's status is printed; exit code 0 if the process got through, 1 on a bad setup.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_abi.h"

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    fprintf(stderr, "[%s] status %d %s: %s\n", instance ? instance : "?", (int)status,
            category ? category : "", message ? message : "");
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
static void *library;
static fmi2Component component;

static void *function(const char *name) {
    void *f = dlsym(library, name);
    if (!f) {
        fprintf(stderr, "the FMU lacks %s\n", name);
        exit(1);
    }
    return f;
}

static void late_calls(const char *when) {
    fmi2Status (*terminate)(fmi2Component) = function("fmi2Terminate");
    void (*free_instance)(fmi2Component) = function("fmi2FreeInstance");
    printf("%s: fmi2Terminate %d\n", when, (int)terminate(component));
    free_instance(component);
    printf("%s: fmi2FreeInstance returned\n", when);
    fflush(stdout);
}

static void at_destruction(void) __attribute__((destructor));
static void at_destruction(void) {
    if (component) late_calls("destructor");
}

int main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: hostile_host DIR MODEL_IDENTIFIER GUID finalize|destructor\n");
        return 1;
    }
    char path[PATH_MAX], resources[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", argv[1], argv[2]);
    snprintf(resources, sizeof resources, "file://%s/resources", argv[1]);
    if (!(library = dlopen(path, RTLD_NOW | RTLD_LOCAL))) {
        fprintf(stderr, "cannot load %s: %s\n", path, dlerror());
        return 1;
    }
    fmi2Component (*instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String,
                                 const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean) =
        function("fmi2Instantiate");
    fmi2Status (*setup)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean,
                        fmi2Real) = function("fmi2SetupExperiment");
    fmi2Status (*enter)(fmi2Component) = function("fmi2EnterInitializationMode");
    fmi2Status (*exit_)(fmi2Component) = function("fmi2ExitInitializationMode");
    component = instantiate("late", fmi2CoSimulation, argv[3], resources, &callbacks,
                            fmi2False, fmi2False);
    if (!component) {
        fprintf(stderr, "fmi2Instantiate returned NULL\n");
        return 1;
    }
    int statuses[3];
    statuses[0] = (int)setup(component, 0, 0.0, 0.0, 0, 0.0);
    statuses[1] = (int)enter(component);
    statuses[2] = (int)exit_(component);
    printf("setup %d enter %d exit %d\n", statuses[0], statuses[1], statuses[2]);
    fflush(stdout);
    if (strcmp(argv[4], "finalize") == 0) {
        int (*ensure)(void) = dlsym(RTLD_DEFAULT, "PyGILState_Ensure");
        int (*finalize)(void) = dlsym(RTLD_DEFAULT, "Py_FinalizeEx");
        if (!ensure || !finalize) {
            fprintf(stderr, "no embedded Python found\n");
            return 1;
        }
        ensure();
        printf("Py_FinalizeEx %d\n", finalize());
        late_calls("after finalize");
        component = NULL;
    }
    return 0;   /* destructor: at_destruction makes the calls */
}
