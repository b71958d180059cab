/* agilesat FMI 2.0 guard: the binary of every agilesat FMU.
 *
 * It forwards each FMI 2.0 co-simulation call to pythonfmu's binary, shipped beside it as
 * pythonfmu-export.so, and fixes two things pythonfmu 0.7.0 cannot do from Python:
 *
 *  - Status.  A Python slave can only return OK or Discard, and any exception becomes
 *    fmi2Fatal.  Our slave logs bad calls at fmi2Error instead; the shim intercepts the
 *    logger and returns the worst status logged during the call.
 *  - Logging.  pythonfmu drops every message, errors included, unless debug logging is on.
 *    The shim keeps pythonfmu's logging on and applies the host's wish itself: warnings
 *    and errors always reach the host, OK-level messages only with logging on (and the
 *    category enabled), except OK-level messages of category "logStatusWarning" (warnings
 *    a user asked not to fail the call with): those always reach the host, as warnings
 *    (the message's status fmi2Warning; the call's status stays what it is).
 *
 *  - Exit.  At process exit pythonfmu's ELF destructor (onLibraryUnload, run by _dl_fini)
 *    calls finalizePythonInterpreter(), which resets a static std::shared_ptr that the exit
 *    handlers have already destroyed: a double free that corrupts the heap at random (the
 *    library cannot be unloaded earlier: its GNU-unique C++ symbols make it NODELETE).
 *    The shim calls finalizePythonInterpreter() itself from an exit handler registered
 *    right after loading the library, so before pythonfmu's own (handlers run in reverse
 *    order); the later calls then find the pointer already null.
 *
 *  - Python.  In a host that does not run Python itself, it loads and initializes the
 *    building environment's Python before pythonfmu needs it (see ensure_python).
 *
 *  - Handles and arguments.  pythonfmu dereferences whatever it is given.  The shim
 *    keeps a registry of live instances and of the FMU states each handed out, and checks
 *    every handle and pointer before forwarding: a freed, NULL, foreign or made-up
 *    instance or state, a NULL array with n > 0, a too-small serialization buffer all get
 *    fmi2Error (with a message when the instance is known) and never reach pythonfmu.
 *  - Derivatives.  fmi2SetRealInputDerivatives and fmi2GetRealOutputDerivatives, which
 *    pythonfmu 0.7.0 does not implement, reach the slave as calls on reserved value
 *    references (see derivative_call).
 *  - Fatal.  After an fmi2Fatal (pythonfmu's answer to an exception it caught, after which
 *    its instance is broken) every call but fmi2FreeInstance is refused with fmi2Error.
 *  - Late calls.  Once Python is finalized or the process is exiting, calls return at
 *    once (fmi2Error; fmi2FreeInstance does nothing): a host calling from a static
 *    destructor would otherwise take the GIL of a dead interpreter inside pythonfmu.
 *  - Speed.  Valid gets and sets in step mode, and once the model's kernels run compiled
 *    fmi2DoStep and the evaluation of the outputs, are served in C from the slave's arrays
 *    without entering Python: the fast paths, fast_paths.c (this file only asks them, and
 *    forwards what they leave).  Every other call, and any the model leaves to its Python,
 *    is forwarded as before, so the slave keeps every check and message.
 *
 *  - Resources.  fmuResourceLocation is decoded here (a percent-encoded file URI, as FMI
 *    2.0 asks hosts to pass it) and handed to pythonfmu as a plain file URI, after checking
 *    that it is this FMU's resources directory: pythonfmu 0.7.0 does not decode it and
 *    segfaults on a location without its resources (a path with a comma, which fmpy
 *    encodes, or a wrong location); such a location gets fmi2Error and a message instead.
 *
 * It also checks the GUID against modelDescription.xml and against the GUID the binary was
 * built with (same_guid), as FMI 2.0 asks of an FMU.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <locale.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "shim.h"

#define INNER_LIBRARY "pythonfmu-export.so"

/* ---- the forwarded library ------------------------------------------------------- */
#define FMI2_FUNCTIONS(X)                                                                 \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment)                         \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate)         \
    X(fmi2Reset) X(fmi2GetReal) X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString)      \
    X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean) X(fmi2SetString)                   \
    X(fmi2GetFMUstate) X(fmi2SetFMUstate) X(fmi2FreeFMUstate)                             \
    X(fmi2SerializedFMUstateSize) X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate)     \
    X(fmi2GetDirectionalDerivative) X(fmi2SetRealInputDerivatives)                        \
    X(fmi2GetRealOutputDerivatives) X(fmi2DoStep) X(fmi2CancelStep) X(fmi2GetStatus)      \
    X(fmi2GetRealStatus) X(fmi2GetIntegerStatus) X(fmi2GetBooleanStatus)                  \
    X(fmi2GetStringStatus)

static struct {
#define DECLARE(name) void *name;
    FMI2_FUNCTIONS(DECLARE)
#undef DECLARE
} inner;

static pthread_once_t load_once = PTHREAD_ONCE_INIT;
static char load_error[8400];
static void (*inner_finalize)(void);
static int (*python_initialized)(void);   /* Py_IsInitialized of the interpreter we use */
static volatile int finalized;            /* our exit handler has run */

/* atexit() in a shared object is tied to it: this runs at process exit and at dlclose. */
static void finalize_inner(void) {
    finalized = 1;
    if (inner_finalize) inner_finalize();
}

/* True once the process is exiting or the host's Python has been finalized: then no call
 * may enter pythonfmu (PyGILState_Ensure on a finalized interpreter crashes). */
static int python_gone(void) {
    return finalized || (python_initialized && !python_initialized());
}

/* ---- the Python interpreter ----------------------------------------------------------
 * pythonfmu's binary uses libpython's symbols without linking libpython (PythonFMU#202,
 * #206) and, when no interpreter runs yet, calls Py_Initialize() with no idea of our
 * virtual environment, so numpy is not found.  We prepare the interpreter first:
 *  - A Python host (FMPy, libcosimpy, ctypes) already runs an interpreter in the global
 *    symbol scope: nothing to do; the model uses the host's interpreter and sys.path.
 *  - Any other host (a C/C++ master): load the libpython recorded at build time with
 *    RTLD_GLOBAL, so that pythonfmu's binary and numpy's extension modules bind to it, and
 *    initialize it as the build environment's python (program name = its absolute path,
 *    so Python finds the standard library and the virtual environment's pyvenv.cfg and
 *    site-packages exactly as that python does).  Then release the GIL: pythonfmu takes
 *    it with PyGILState_Ensure() from whatever thread the host calls in.  pythonfmu sees
 *    Py_IsInitialized() and leaves initialization and finalization alone.
 * The environment variables AGILESAT_LIBPYTHON and AGILESAT_PYTHON override the recorded
 * paths (another machine).  The interpreter ignores the host's PYTHON* variables
 * (Py_IgnoreEnvironmentFlag: the FMU's Python is the recorded one, not whatever the host's
 * PYTHONHOME points at), and the host's LC_CTYPE, which Py_InitializeEx sets to the
 * user's locale, is put back.  Only entry points of the stable ABI are used (dlsym, no
 * Python headers); Py_SetProgramName and Py_IgnoreEnvironmentFlag are deprecated since
 * 3.11/3.12 but kept in the ABI.  Py_InitializeEx has no error return: a Python whose
 * standard library is broken aborts the process (Python's own fatal error message). */
#ifndef AGILESAT_LIBPYTHON
#error "define AGILESAT_LIBPYTHON: path of the shared libpython of the building interpreter"
#endif
#ifndef AGILESAT_PYTHON
#error "define AGILESAT_PYTHON: sys.executable of the building environment"
#endif
#ifndef AGILESAT_PYTHON_VERSION
#error "define AGILESAT_PYTHON_VERSION: X.Y of the building Python"
#endif
#ifndef AGILESAT_PYTHON_MINIMUM
#error "define AGILESAT_PYTHON_MINIMUM: X.Y of the oldest Python agilesat runs on"
#endif

static const char *setting(const char *variable, const char *recorded) {
    const char *value = getenv(variable);
    return value && *value ? value : recorded;
}

/* The one message of every failure to start Python: what failed, then what the FMU needs
 * and both variables that point it at a Python (docs/hosts.md).  Any Python from the
 * oldest agilesat runs on will do, if its libpython and its environment (numpy's compiled
 * modules) are of one minor version. */
static int python_missing(char *err, size_t n, const char *problem) {
    snprintf(err, n, "%s. This FMU runs Python " AGILESAT_PYTHON_MINIMUM " or later with numpy "
             "(it was built with Python " AGILESAT_PYTHON_VERSION ", " AGILESAT_PYTHON "): in a "
             "host that does not run Python, set AGILESAT_LIBPYTHON to the shared libpython of "
             "a Python and AGILESAT_PYTHON to the python of an environment of the same minor "
             "version with numpy (and sgp4)", problem);
    return -1;
}

/* "X.Y" of a text that starts with a version ("3.12.1 (main, ...)", " = 3.11.7"), into
 * out; 0 if it does not. */
static int minor_version(const char *text, char *out, size_t n) {
    size_t i = 0;
    int dots = 0;
    while (*text == ' ' || *text == '=') text++;
    for (; text[i] && i + 1 < n; i++) {
        if (text[i] == '.' && ++dots == 2) break;
        if (text[i] != '.' && (text[i] < '0' || text[i] > '9')) break;
        out[i] = text[i];
    }
    out[i] = 0;
    return dots >= 1 && i >= 3 && out[i - 1] != '.';
}

/* The "X.Y" of the environment of ``python`` (ENV/bin/python): the version its
 * ENV/pyvenv.cfg states; 0 where there is none (not a virtual environment). */
static int environment_version(const char *python, char *out, size_t n) {
    char cfg[4200], line[512];
    snprintf(cfg, sizeof cfg - 16, "%s", python);
    for (int up = 0; up < 2; up++) {
        char *slash = strrchr(cfg, '/');
        if (!slash) return 0;
        *slash = 0;
    }
    strcat(cfg, "/pyvenv.cfg");
    FILE *file = fopen(cfg, "r");
    if (!file) return 0;
    int found = 0;
    while (!found && fgets(line, sizeof line, file)) {
        if (strncmp(line, "version", 7) != 0) continue;
        const char *value = line + 7;
        while (*value == '_' || (*value >= 'a' && *value <= 'z')) value++;  /* version_info */
        found = minor_version(value, out, n);
    }
    fclose(file);
    return found;
}

/* Once Python runs: 0 if it imports numpy, else the one message naming that Python. */
static int numpy_missing(char *err, size_t n) {
    int (*ensure)(void) = (int (*)(void))dlsym(RTLD_DEFAULT, "PyGILState_Ensure");
    void (*release)(int) = (void (*)(int))dlsym(RTLD_DEFAULT, "PyGILState_Release");
    void *(*import)(const char *) = (void *(*)(const char *))dlsym(RTLD_DEFAULT,
                                                                   "PyImport_ImportModule");
    void (*decref)(void *) = (void (*)(void *))dlsym(RTLD_DEFAULT, "Py_DecRef");
    void (*clear)(void) = (void (*)(void))dlsym(RTLD_DEFAULT, "PyErr_Clear");
    void *(*sys_object)(const char *) = (void *(*)(const char *))dlsym(RTLD_DEFAULT,
                                                                       "PySys_GetObject");
    const char *(*utf8)(void *) = (const char *(*)(void *))dlsym(RTLD_DEFAULT,
                                                                 "PyUnicode_AsUTF8");
    if (!ensure || !release || !import || !decref || !clear || !sys_object || !utf8) return 0;
    int gil = ensure();
    void *numpy = import("numpy");
    if (numpy) {
        decref(numpy);
        release(gil);
        return 0;
    }
    clear();
    char problem[4400];
    void *executable = sys_object("executable");  /* borrowed */
    const char *text = executable ? utf8(executable) : NULL;
    snprintf(problem, sizeof problem, "the Python it runs in, %.4096s, has no numpy",
             text && *text ? text : "(unknown)");
    if (!text) clear();
    release(gil);
    return python_missing(err, n, problem);
}

static int ensure_python(char *err, size_t n) {
    char problem[4600];
    int (*is_initialized)(void) = (int (*)(void))dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    python_initialized = is_initialized;
    if (is_initialized && is_initialized()) return 0;   /* the host runs Python */
    void *lib = RTLD_DEFAULT;
    const char *path = setting("AGILESAT_LIBPYTHON", AGILESAT_LIBPYTHON);
    if (!is_initialized) {
        if (!*path)
            return python_missing(err, n, "the Python this FMU was built with has no shared "
                                  "libpython");
        lib = dlopen(path, RTLD_NOW | RTLD_GLOBAL);
        if (!lib) {
            snprintf(problem, sizeof problem, "cannot load the libpython %.2048s (%.2048s)",
                     path, dlerror());
            return python_missing(err, n, problem);
        }
        is_initialized = (int (*)(void))dlsym(lib, "Py_IsInitialized");
        python_initialized = is_initialized;
        if (is_initialized && is_initialized()) return 0;
    }
    const char *python = setting("AGILESAT_PYTHON", AGILESAT_PYTHON);
    wchar_t *(*decode)(const char *, size_t *) =
        (wchar_t *(*)(const char *, size_t *))dlsym(lib, "Py_DecodeLocale");
    void (*set_program_name)(const wchar_t *) =
        (void (*)(const wchar_t *))dlsym(lib, "Py_SetProgramName");
    void (*initialize)(int) = (void (*)(int))dlsym(lib, "Py_InitializeEx");
    void *(*save_thread)(void) = (void *(*)(void))dlsym(lib, "PyEval_SaveThread");
    int *ignore_environment = (int *)dlsym(lib, "Py_IgnoreEnvironmentFlag");
    if (!is_initialized || !decode || !set_program_name || !initialize || !save_thread)
        return python_missing(err, n, "the loaded libpython lacks the embedding API "
                              "(Py_DecodeLocale, Py_SetProgramName, Py_InitializeEx, "
                              "PyEval_SaveThread)");
    if (access(python, X_OK) != 0) {
        snprintf(problem, sizeof problem, "it runs Python as %.4096s, which does not exist "
                 "here", python);
        return python_missing(err, n, problem);
    }
    const char *(*get_version)(void) = (const char *(*)(void))dlsym(lib, "Py_GetVersion");
    char library[16], environment[16];
    if (get_version && minor_version(get_version(), library, sizeof library) &&
        environment_version(python, environment, sizeof environment) &&
        strcmp(library, environment) != 0) {
        snprintf(problem, sizeof problem, "the libpython %.2048s is Python %s and the "
                 "environment of %.2048s is Python %s", path, library, python, environment);
        return python_missing(err, n, problem);
    }
    wchar_t *program = decode(python, NULL);   /* kept: must outlive the interpreter */
    if (!program) {
        snprintf(problem, sizeof problem, "cannot decode the path %.4096s", python);
        return python_missing(err, n, problem);
    }
    char *host_ctype = strdup(setlocale(LC_CTYPE, NULL));
    if (ignore_environment) *ignore_environment = 1;
    set_program_name(program);
    initialize(0);                  /* 0: the host keeps its signal handlers */
    if (host_ctype) setlocale(LC_CTYPE, host_ctype);
    free(host_ctype);
    save_thread();
    return 0;
}

static void load_inner(void) {
    if (ensure_python(load_error, sizeof load_error) != 0) return;
    if (numpy_missing(load_error, sizeof load_error) != 0) return;
    Dl_info info;
    if (!dladdr((void *)&load_inner, &info) || !info.dli_fname) {
        snprintf(load_error, sizeof load_error, "cannot locate the FMU binary (dladdr)");
        return;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s", info.dli_fname);
    char *slash = strrchr(path, '/');
    snprintf(slash ? slash + 1 : path, sizeof path - (slash ? (size_t)(slash + 1 - path) : 0),
             "%s", INNER_LIBRARY);
    void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        snprintf(load_error, sizeof load_error, "cannot load %s: %s", path, dlerror());
        return;
    }
#define RESOLVE(name)                                                                     \
    if (!(inner.name = dlsym(handle, #name))) {                                           \
        snprintf(load_error, sizeof load_error, "%s lacks %s", path, #name);              \
        return;                                                                           \
    }
    FMI2_FUNCTIONS(RESOLVE)
#undef RESOLVE
    inner_finalize = (void (*)(void))dlsym(handle, "finalizePythonInterpreter");
    atexit(finalize_inner);
}

/* ---- instances and states ------------------------------------------------------------
 * Every handle a host passes is checked against the live instances (and each instance's
 * live states) before anything is forwarded: NULL, freed, foreign or made-up handles get
 * fmi2Error (logged when the instance is known) and never reach pythonfmu, which would
 * dereference them.  States are our own small records around pythonfmu's (a Python object
 * per state), so fmi2GetFMUstate can reuse a handle and fmi2FreeInstance frees an
 * instance's states with it. */
typedef struct State {
    void *inner;                 /* pythonfmu's state */
    struct State *next;
} State;

typedef struct Shim {
    fmi2Component inner;
    fmi2CallbackFunctions host;  /* what the host gave us */
    fmi2CallbackFunctions ours;  /* what pythonfmu sees: our logger, us as environment */
    char *name;
    int logging_on;
    char **categories;
    size_t n_categories;
    fmi2Status worst;            /* worst status logged during the current call */
    int fatal;                   /* a call returned fmi2Fatal: only fmi2FreeInstance now */
    State *states;
    FastPaths fast;              /* fast_paths.c */
    struct Shim *next;
} Shim;

/* The live instances: a list changed and searched under the lock, and the first N_SEEN of
 * them also in seen[], which every FMI call searches without it (an uncontended lock and
 * unlock cost more than the rest of a fast get).  A slot is written under the lock, with
 * a release store once the instance is complete (linked) and cleared before it is
 * unlinked and freed; read with an acquire load, a slot holding c says c was live at that
 * moment, all a lookup under the lock said either (FMI 2.0 leaves one instance's calls to
 * one thread at a time).  A call on anything not found there searches the list. */
#define N_SEEN 64
static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER;
static Shim *instances;
static Shim *seen[N_SEEN];
static size_t n_seen;  /* slots ever used: seen[n_seen..] are all NULL */

static void register_instance(Shim *s) {
    pthread_mutex_lock(&registry_lock);
    s->next = instances;
    instances = s;
    for (size_t i = 0; i < N_SEEN; i++) {
        if (seen[i]) continue;
        __atomic_store_n(&seen[i], s, __ATOMIC_RELEASE);
        if (i >= n_seen) __atomic_store_n(&n_seen, i + 1, __ATOMIC_RELEASE);
        break;
    }
    pthread_mutex_unlock(&registry_lock);
}

static Shim *find_instance(fmi2Component c, int unlink) {
    if (c && !unlink) {
        size_t n = __atomic_load_n(&n_seen, __ATOMIC_ACQUIRE);
        for (size_t i = 0; i < n; i++)
            if (__atomic_load_n(&seen[i], __ATOMIC_ACQUIRE) == c) return c;
    }
    pthread_mutex_lock(&registry_lock);
    Shim **at = &instances;
    while (*at && *at != c) at = &(*at)->next;
    Shim *s = *at;
    if (s && unlink) {
        for (size_t i = 0; i < N_SEEN; i++)
            if (seen[i] == s) __atomic_store_n(&seen[i], NULL, __ATOMIC_RELEASE);
        *at = s->next;
    }
    pthread_mutex_unlock(&registry_lock);
    return s;
}

FastPaths *fast_paths_of(fmi2Component c) {
    Shim *s = find_instance(c, 0);
    return s ? &s->fast : NULL;
}

static int category_enabled(const Shim *s, const char *category) {
    if (s->n_categories == 0) return 1;
    for (size_t i = 0; i < s->n_categories; i++)
        if (category && strcmp(s->categories[i], category) == 0) return 1;
    return 0;
}

/* FMI 2.0: the message is a printf format for the host; escape '%' in plain text. */
static void host_log(const Shim *s, fmi2Status status, const char *category, const char *text) {
    if (!s->host.logger) return;
    size_t n = strlen(text), extra = 0;
    for (size_t i = 0; i < n; i++) extra += text[i] == '%';
    char *escaped = malloc(n + extra + 1);
    if (!escaped) return;
    char *out = escaped;
    for (size_t i = 0; i < n; i++) {
        *out++ = text[i];
        if (text[i] == '%') *out++ = '%';
    }
    *out = '\0';
    s->host.logger(s->host.componentEnvironment, s->name, status, category ? category : "",
                   escaped);
    free(escaped);
}

static fmi2Status refuse(Shim *s, const char *call, const char *why) {
    char text[512];
    snprintf(text, sizeof text, "%s: %s", call, why);
    host_log(s, fmi2Error, "logStatusError", text);
    return fmi2Error;
}

/* The slave logs limit and saturation conditions at status OK with category
 * "logStatusWarning" when the user asks for warnings that do not fail the call (hosts that
 * treat fmi2Warning from fmi2DoStep as failure, OMSimulator): those always reach the host,
 * as messages of status fmi2Warning (a host logs them as warnings), and leave the call's
 * status OK. */
static void shim_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                        fmi2String category, fmi2String message, ...) {
    (void)instance;
    Shim *s = env;
    if (status > s->worst && status != fmi2Pending) s->worst = status;
    int warning_as_ok = status == fmi2OK && category && !strcmp(category, "logStatusWarning");
    if (status == fmi2OK && !warning_as_ok && (!s->logging_on || !category_enabled(s, category)))
        return;
    host_log(s, warning_as_ok ? fmi2Warning : status, category, message ? message : "");
}

static void free_categories(Shim *s) {
    for (size_t i = 0; i < s->n_categories; i++) free(s->categories[i]);
    free(s->categories);
    s->categories = NULL;
    s->n_categories = 0;
}

/* The resources directory that fmuResourceLocation names, as a path: a file URI
 * ("file:///p", "file://localhost/p", "file:/p") percent-decoded (RFC 3986; FMI 2.0
 * section 2.1.5: hosts encode, fmpy for instance turns ',' into %2C), anything else taken
 * as a plain path.  0 if it does not fit or is not a local file URI.  pythonfmu 0.7.0
 * takes the location as a path without decoding it, and dereferences NULL when its
 * resources are not there (it segfaults the host): the shim hands it the decoded path,
 * and only once it has checked that the resources are there (resources_ok). */
static int hex_digit(char c) {
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

static int resource_path(const char *uri, char *path, size_t n) {
    const char *p = uri;
    int encoded = strncmp(p, "file:", 5) == 0;
    if (strncmp(p, "file://", 7) == 0) {
        p += 7;
        if (*p != '/') {  /* an authority: only this machine's */
            if (strncmp(p, "localhost/", 10) != 0) return 0;
            p += 9;
        }
    } else if (encoded) {
        p += 5;
    }
    size_t k = 0;
    for (; *p; p++) {
        if (k + 1 >= n) return 0;
        if (encoded && p[0] == '%' && hex_digit(p[1]) && hex_digit(p[2])) {
            char hex[3] = {p[1], p[2], 0};
            path[k++] = (char)strtol(hex, NULL, 16);
            p += 2;
        } else {
            path[k++] = *p;
        }
    }
    while (k > 1 && path[k - 1] == '/') k--;
    path[k] = '\0';
    return k > 0;
}

/* The location is this FMU's resources directory (pythonfmu's slavemodule.txt is in it)
 * and the GUID in its ../modelDescription.xml is the one the host passes; else 0 and why. */
static int resources_ok(const char *uri, const char *path, const char *guid, char *why,
                        size_t n) {
    char file[4200];
    snprintf(file, sizeof file, "%s/slavemodule.txt", path);
    FILE *f = fopen(file, "rb");
    if (!f) {
        snprintf(why, n, "fmuResourceLocation %.1024s is not this FMU's resources directory "
                 "(%.1024s: %s)", uri, file, strerror(errno));
        return 0;
    }
    fclose(f);
    if (!guid) return 1;
    snprintf(file, sizeof file, "%s/../modelDescription.xml", path);
    f = fopen(file, "rb");
    if (!f) return 1; /* cannot check; not an error */
    char head[8192];
    size_t got = fread(head, 1, sizeof head - 1, f);
    fclose(f);
    head[got] = '\0';
    const char *at = strstr(head, "guid=\"");
    if (!at) return 1;
    at += 6;
    const char *end = strchr(at, '"');
    if (!end) return 1;
    if ((size_t)(end - at) == strlen(guid) && strncmp(at, guid, end - at) == 0) return 1;
    snprintf(why, n, "GUID mismatch: the host passed %s but modelDescription.xml declares %.*s",
             guid, (int)(end - at), at);
    return 0;
}

/* The instance behind c, ready for a call; NULL (the call returns fmi2Error) when c is not
 * a live instance, after a fatal error, or once Python has shut down (a host calling from
 * a static destructor or an exit handler: pythonfmu would take the GIL of a finalized
 * interpreter).  Nothing is logged then: the host's logger may itself be Python. */
static Shim *enter(fmi2Component c, const char *call) {
    if (python_gone()) return NULL;
    Shim *s = find_instance(c, 0);
    if (!s) return NULL;
    if (s->fatal) {
        refuse(s, call, "refused: an earlier call returned fmi2Fatal, only fmi2FreeInstance "
               "is allowed now");
        return NULL;
    }
    s->worst = fmi2OK;
    return s;
}

/* The worse of a forwarded call's status and the worst status logged during it. */
static fmi2Status leave(Shim *s, fmi2Status status) {
    if (status < s->worst) status = s->worst;
    if (status == fmi2Fatal) s->fatal = 1;
    return status;
}

#define INNER(type, fn) ((type)inner.fn)

/* The fast paths' handshake question, as pythonfmu's fmi2GetReal (see Ask in shim.h). */
static int ask_slave(void *shim, const fmi2ValueReference vr[], size_t n, fmi2Real got[]) {
    typedef fmi2Status (*Get)(fmi2Component, const fmi2ValueReference *, size_t, fmi2Real *);
    Shim *s = shim;
    fmi2Status status = INNER(Get, fmi2GetReal)(s->inner, vr, n, got);
    fmi2Status worst = s->worst;
    s->worst = fmi2OK;
    return status == fmi2OK && worst == fmi2OK;
}

/* The GUID the slave says this binary was built with (fmus/protocol.py fmu_guid: its
 * code's content hash), asked as fmi2GetString of FAST_PATH_VR, against the host's: FMI 2.0
 * section 2.1.5 makes the GUID the tie between modelDescription.xml and the binary, and a
 * modelDescription.xml edited or taken from another build names another.  1 if they are
 * the same (or the slave does not say), else 0 and why. */
static int same_guid(Shim *s, const char *guid, char *why, size_t n) {
    typedef fmi2Status (*F)(fmi2Component, const fmi2ValueReference *, size_t, fmi2String *);
    fmi2ValueReference vr = FAST_PATH_VR;
    fmi2String own = NULL;
    fmi2Status status = INNER(F, fmi2GetString)(s->inner, &vr, 1, &own);
    s->worst = fmi2OK;
    if (status != fmi2OK || !own || !*own || (guid && strcmp(own, guid) == 0)) return 1;
    snprintf(why, n, "fmi2Instantiate: GUID %.100s is not this FMU's: its binary was built as "
             "%.100s (its modelDescription.xml is not the one built with it; FMI 2.0 section "
             "2.1.5)", guid ? guid : "(NULL)", own);
    return 0;
}

/* ---- FMI 2.0 API -------------------------------------------------------------------- */
EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                                     fmi2String resources, const fmi2CallbackFunctions *cb,
                                     fmi2Boolean visible, fmi2Boolean logging_on) {
    Shim probe = {0};
    if (cb) probe.host = *cb;
    probe.name = (char *)(name ? name : "");
    if (!name || !resources) {
        host_log(&probe, fmi2Error, "logStatusError", name ? "fmuResourceLocation is NULL"
                 : "instanceName is NULL");
        return NULL;
    }
    if (type != fmi2CoSimulation) {
        host_log(&probe, fmi2Error, "logStatusError",
                 "this FMU supports co-simulation only (fmi2CoSimulation)");
        return NULL;
    }
    char why[2400], path[4096], location[4104];
    if (!resource_path(resources, path, sizeof path)) {
        snprintf(why, sizeof why, "fmuResourceLocation %.1024s is not a local file URI or path",
                 resources);
        host_log(&probe, fmi2Error, "logStatusError", why);
        return NULL;
    }
    if (!resources_ok(resources, path, guid, why, sizeof why)) {
        host_log(&probe, fmi2Error, "logStatusError", why);
        return NULL;
    }
    snprintf(location, sizeof location, "file://%s", path);
    pthread_once(&load_once, load_inner);
    if (load_error[0]) {
        host_log(&probe, fmi2Fatal, "logStatusFatal", load_error);
        return NULL;
    }
    if (python_gone()) return NULL;
    Shim *s = calloc(1, sizeof *s);
    if (!s || !(s->name = strdup(name))) {
        free(s);
        host_log(&probe, fmi2Error, "logStatusError", "out of memory");
        return NULL;
    }
    s->host = probe.host;
    s->ours = probe.host;
    s->ours.logger = shim_logger;
    s->ours.componentEnvironment = s;
    s->logging_on = logging_on;
    typedef fmi2Component (*F)(fmi2String, fmi2Type, fmi2String, fmi2String,
                               const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
    s->inner = INNER(F, fmi2Instantiate)(name, type, guid, location, &s->ours, visible,
                                         fmi2True);
    if (!s->inner || !same_guid(s, guid, why, sizeof why)) {
        if (s->inner) {
            host_log(&probe, fmi2Error, "logStatusError", why);
            INNER(void (*)(fmi2Component), fmi2FreeInstance)(s->inner);
        }
        free(s->name);
        free(s);
        return NULL;
    }
    fast_paths_connect(&s->fast, ask_slave, s);
    register_instance(s);
    return s;
}

static void free_inner_state(Shim *s, void *state) {
    typedef fmi2Status (*F)(fmi2Component, fmi2FMUstate *);
    INNER(F, fmi2FreeFMUstate)(s->inner, &state);
}

/* pythonfmu's instance is freed unless it raised (fmi2Fatal): then it has already released
 * its Python objects, and its destructor would release them a second time
 * (PySlaveInstance::handle_py_exception, pythonfmu 0.7.0), so it is left alone. */
EXPORT void fmi2FreeInstance(fmi2Component c) {
    if (python_gone()) return;
    Shim *s = find_instance(c, 1);
    if (!s) return;
    while (s->states) {
        State *state = s->states;
        s->states = state->next;
        free_inner_state(s, state->inner);
        free(state);
    }
    if (!s->fatal) INNER(void (*)(fmi2Component), fmi2FreeInstance)(s->inner);
    free_categories(s);
    free(s->name);
    free(s);
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n,
                                      const fmi2String categories[]) {
    Shim *s = enter(c, "fmi2SetDebugLogging");
    if (!s) return fmi2Error;
    if (n > 0 && !categories) return refuse(s, "fmi2SetDebugLogging", "categories is NULL");
    for (size_t i = 0; i < n; i++)
        if (!categories[i]) return refuse(s, "fmi2SetDebugLogging", "a category is NULL");
    free_categories(s);
    s->logging_on = on;
    if (n > 0) {
        s->categories = calloc(n, sizeof *s->categories);
        if (!s->categories) return fmi2Error;
        for (size_t i = 0; i < n; i++)
            if ((s->categories[i] = strdup(categories[i]))) s->n_categories = i + 1;
    }
    return fmi2OK;
}

EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tol_defined, fmi2Real tol,
                                      fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    typedef fmi2Status (*F)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean,
                            fmi2Real);
    Shim *s = enter(c, "fmi2SetupExperiment");
    if (!s) return fmi2Error;
    return leave(s, INNER(F, fmi2SetupExperiment)(s->inner, tol_defined, tol, start,
                                                  stop_defined, stop));
}

#define FORWARD_NOARGS(fn)                                                                \
    EXPORT fmi2Status fn(fmi2Component c) {                                               \
        Shim *s = enter(c, #fn);                                                          \
        if (!s) return fmi2Error;                                                         \
        return leave(s, INNER(fmi2Status (*)(fmi2Component), fn)(s->inner));              \
    }
FORWARD_NOARGS(fmi2EnterInitializationMode)
FORWARD_NOARGS(fmi2ExitInitializationMode)
FORWARD_NOARGS(fmi2Terminate)
FORWARD_NOARGS(fmi2CancelStep)

/* pythonfmu 0.7.0 resets by creating a new slave (PySlaveInstance::initialize): the fast
 * path is off during the call and learns the new slave's arrays after it. */
EXPORT fmi2Status fmi2Reset(fmi2Component c) {
    Shim *s = enter(c, "fmi2Reset");
    if (!s) return fmi2Error;
    fast_paths_disconnect(&s->fast);
    fmi2Status status = leave(s, INNER(fmi2Status (*)(fmi2Component), fmi2Reset)(s->inner));
    if (status <= fmi2Warning) {
        fmi2Status worst = s->worst;
        fast_paths_connect(&s->fast, ask_slave, s);
        s->worst = worst;
    }
    return status;
}

static int bad_arrays(Shim *s, const char *call, size_t n, const void *vr, const void *value) {
    if (n == 0) return 0;
    if (!vr || !value) {
        refuse(s, call, "the value reference or value array is NULL");
        return 1;
    }
    if (n > MAX_VALUES) {
        refuse(s, call, "too many values in one call");
        return 1;
    }
    return 0;
}

static int not_served(FastPaths *f, const fmi2ValueReference vr[], size_t n, const void *value) {
    (void)f, (void)vr, (void)n, (void)value;
    return 0;
}

#define FORWARD_ARRAY(fn, type, check_strings, served)                                      \
    EXPORT fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t n,        \
                         type value[]) {                                                  \
        typedef fmi2Status (*F)(fmi2Component, const fmi2ValueReference *, size_t, type *); \
        Shim *s = enter(c, #fn);                                                          \
        if (!s) return fmi2Error;                                                         \
        if (bad_arrays(s, #fn, n, vr, value)) return fmi2Error;                           \
        for (size_t i = 0; check_strings && i < n; i++)                                   \
            if (!((const void *const *)value)[i]) return refuse(s, #fn, "a string is NULL"); \
        if (served(&s->fast, vr, n, value)) return fmi2OK;                                \
        return leave(s, INNER(F, fn)(s->inner, vr, n, value));                            \
    }
/* Value references from DERIVATIVE_BASE up carry the derivative calls to the slave (see
 * "input and output derivatives" below); a plain fmi2GetReal/fmi2SetReal may not use them. */
#define FORWARD_REAL(fn, type, served)                                                      \
    EXPORT fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t n,        \
                         type value[]) {                                                  \
        typedef fmi2Status (*F)(fmi2Component, const fmi2ValueReference *, size_t, type *); \
        Shim *s = enter(c, #fn);                                                          \
        if (!s) return fmi2Error;                                                         \
        if (bad_arrays(s, #fn, n, vr, value)) return fmi2Error;                           \
        for (size_t i = 0; i < n; i++)                                                    \
            if (vr[i] >= DERIVATIVE_BASE) return refuse(s, #fn, "unknown value reference"); \
        if (served(&s->fast, vr, n, value)) return fmi2OK;                                \
        return leave(s, INNER(F, fn)(s->inner, vr, n, value));                            \
    }
FORWARD_REAL(fmi2GetReal, fmi2Real, fast_get_real)
FORWARD_REAL(fmi2SetReal, const fmi2Real, fast_set_real)
FORWARD_ARRAY(fmi2GetInteger, fmi2Integer, 0, fast_get_integer)
FORWARD_ARRAY(fmi2GetBoolean, fmi2Boolean, 0, fast_get_boolean)
FORWARD_ARRAY(fmi2GetString, fmi2String, 0, not_served)
FORWARD_ARRAY(fmi2SetInteger, const fmi2Integer, 0, fast_set_integer)
FORWARD_ARRAY(fmi2SetBoolean, const fmi2Boolean, 0, fast_set_boolean)
FORWARD_ARRAY(fmi2SetString, const fmi2String, 1, not_served)

/* ---- FMU states --------------------------------------------------------------------- */
static State **find_state(Shim *s, fmi2FMUstate state) {
    State **at = &s->states;
    while (*at && *at != state) at = &(*at)->next;
    return *at ? at : NULL;
}

static State *known_state(Shim *s, const char *call, fmi2FMUstate state) {
    State **at = state ? find_state(s, state) : NULL;
    if (!at) refuse(s, call, "not an FMU state of this instance (NULL, freed, or from "
                    "another instance or FMU)");
    return at ? *at : NULL;
}

static State *add_state(Shim *s, void *inner_state) {
    State *state = calloc(1, sizeof *state);
    if (!state) {
        free_inner_state(s, inner_state);
        refuse(s, "fmi2GetFMUstate", "out of memory");
        return NULL;
    }
    state->inner = inner_state;
    state->next = s->states;
    s->states = state;
    return state;
}

EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *out) {
    typedef fmi2Status (*F)(fmi2Component, fmi2FMUstate *);
    Shim *s = enter(c, "fmi2GetFMUstate");
    if (!s) return fmi2Error;
    if (!out) return refuse(s, "fmi2GetFMUstate", "the FMUstate pointer is NULL");
    State *reuse = NULL;
    if (*out && !(reuse = known_state(s, "fmi2GetFMUstate", *out))) return fmi2Error;
    void *got = NULL;
    fmi2Status status = leave(s, INNER(F, fmi2GetFMUstate)(s->inner, &got));
    if (status > fmi2Warning || !got) {
        if (got && !s->fatal) free_inner_state(s, got);
        return status > fmi2Warning ? status : fmi2Error;
    }
    if (reuse) {
        free_inner_state(s, reuse->inner);
        reuse->inner = got;
    } else if (!(reuse = add_state(s, got))) {
        return fmi2Error;
    }
    *out = reuse;
    return status;
}

EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    typedef fmi2Status (*F)(fmi2Component, fmi2FMUstate);
    Shim *s = enter(c, "fmi2SetFMUstate");
    if (!s) return fmi2Error;
    State *known = known_state(s, "fmi2SetFMUstate", state);
    if (!known) return fmi2Error;
    return leave(s, INNER(F, fmi2SetFMUstate)(s->inner, known->inner));
}

/* FMI 2.0 section 2.1.8: a NULL *FMUstate is ignored. */
EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Shim *s = enter(c, "fmi2FreeFMUstate");
    if (!s) return fmi2Error;
    if (!state) return refuse(s, "fmi2FreeFMUstate", "the FMUstate pointer is NULL");
    if (!*state) return fmi2OK;
    State **at = find_state(s, *state);
    if (!at) return refuse(s, "fmi2FreeFMUstate", "not an FMU state of this instance (freed, "
                           "or from another instance or FMU)");
    State *known = *at;
    *at = known->next;
    free_inner_state(s, known->inner);
    free(known);
    *state = NULL;
    return leave(s, fmi2OK);
}

static fmi2Status inner_size(Shim *s, void *state, size_t *n) {
    typedef fmi2Status (*F)(fmi2Component, fmi2FMUstate, size_t *);
    *n = 0;
    return leave(s, INNER(F, fmi2SerializedFMUstateSize)(s->inner, state, n));
}

static fmi2Status inner_serialize(Shim *s, void *state, fmi2Byte *bytes, size_t n) {
    typedef fmi2Status (*F)(fmi2Component, fmi2FMUstate, fmi2Byte *, size_t);
    return leave(s, INNER(F, fmi2SerializeFMUstate)(s->inner, state, bytes, n));
}

EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *n) {
    Shim *s = enter(c, "fmi2SerializedFMUstateSize");
    if (!s) return fmi2Error;
    State *known = known_state(s, "fmi2SerializedFMUstateSize", state);
    if (!known) return fmi2Error;
    if (!n) return refuse(s, "fmi2SerializedFMUstateSize", "the size pointer is NULL");
    return inner_size(s, known->inner, n);
}

/* pythonfmu copies exactly n bytes of the state, whatever its length: the buffer must hold
 * the whole state (a shorter one would give a truncated state); a longer one is padded
 * with NUL bytes, which deserialization accepts. */
EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                        size_t n) {
    Shim *s = enter(c, "fmi2SerializeFMUstate");
    if (!s) return fmi2Error;
    State *known = known_state(s, "fmi2SerializeFMUstate", state);
    if (!known) return fmi2Error;
    if (!bytes) return refuse(s, "fmi2SerializeFMUstate", "the byte buffer is NULL");
    size_t need;
    fmi2Status status = inner_size(s, known->inner, &need);
    if (status > fmi2Warning) return status;
    if (n < need) {
        char why[160];
        snprintf(why, sizeof why, "the buffer of %zu bytes is too small: the state needs %zu "
                 "bytes (fmi2SerializedFMUstateSize)", n, need);
        return refuse(s, "fmi2SerializeFMUstate", why);
    }
    memset(bytes + need, 0, n - need);
    fmi2Status copied = inner_serialize(s, known->inner, bytes, need);
    return copied > status ? copied : status;
}

/* The slave never raises on bad bytes (pythonfmu would make that fatal): it returns a
 * rejected state, whose serialization is a NUL byte followed by the reason. */
EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t n,
                                          fmi2FMUstate *out) {
    typedef fmi2Status (*F)(fmi2Component, const fmi2Byte *, size_t, fmi2FMUstate *);
    static const char call[] = "fmi2DeSerializeFMUstate";
    Shim *s = enter(c, call);
    if (!s) return fmi2Error;
    if (!out || (!bytes && n > 0)) return refuse(s, call, "a NULL pointer argument");
    void *got = NULL;
    fmi2Status status = leave(s, INNER(F, fmi2DeSerializeFMUstate)(s->inner, bytes ? bytes : "",
                                                                   n, &got));
    if (status > fmi2Warning || !got) {
        if (got && !s->fatal) free_inner_state(s, got);
        return status > fmi2Warning ? status : fmi2Error;
    }
    fmi2Byte first = 0;
    size_t size = 0;
    if (inner_size(s, got, &size) > fmi2Warning || size == 0 ||
        inner_serialize(s, got, &first, 1) > fmi2Warning || first == '\0') {
        char *reason = size > 1 ? malloc(size + 1) : NULL;
        if (reason && inner_serialize(s, got, reason, size) <= fmi2Warning) {
            reason[size] = '\0';
            refuse(s, call, reason + 1);
        } else {
            refuse(s, call, "not a state of this FMU");
        }
        free(reason);
        if (!s->fatal) free_inner_state(s, got);
        return fmi2Error;
    }
    State *state = add_state(s, got);
    if (!state) return fmi2Error;
    *out = state;
    return status;
}

EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c,
                                               const fmi2ValueReference unknowns[], size_t nu,
                                               const fmi2ValueReference knowns[], size_t nk,
                                               const fmi2Real dv_known[], fmi2Real dv_unknown[]) {
    typedef fmi2Status (*F)(fmi2Component, const fmi2ValueReference *, size_t,
                            const fmi2ValueReference *, size_t, const fmi2Real *, fmi2Real *);
    Shim *s = enter(c, "fmi2GetDirectionalDerivative");
    if (!s) return fmi2Error;
    return leave(s, INNER(F, fmi2GetDirectionalDerivative)(s->inner, unknowns, nu, knowns, nk,
                                                           dv_known, dv_unknown));
}

/* ---- input and output derivatives ----------------------------------------------------
 * pythonfmu 0.7.0's binary answers both calls "not supported" without reaching Python.  The
 * slave implements them (fmus/slave.py: which variables have a declared derivative, the
 * order, the mode, finite values), and the shim passes each (vr, order) on to it as the
 * value reference DERIVATIVE_BASE + (order << ORDER_SHIFT) + vr of an fmi2SetReal or
 * fmi2GetReal.  Refused here: NULL arrays with n > 0, an order outside 0..MAX_ORDER, a
 * value reference too large for any variable (the slave refuses every order but 1, naming
 * the variable). */
static fmi2Status derivative_call(Shim *s, const char *call, const fmi2ValueReference vr[],
                                  size_t n, const fmi2Integer order[], void *value,
                                  int setting) {
    typedef fmi2Status (*Set)(fmi2Component, const fmi2ValueReference *, size_t,
                              const fmi2Real *);
    typedef fmi2Status (*Get)(fmi2Component, const fmi2ValueReference *, size_t, fmi2Real *);
    if (bad_arrays(s, call, n, vr, value)) return fmi2Error;
    if (n > 0 && !order) return refuse(s, call, "the order array is NULL");
    fmi2ValueReference *codes = malloc((n ? n : 1) * sizeof *codes);
    if (!codes) return refuse(s, call, "out of memory");
    for (size_t i = 0; i < n; i++) {
        char why[200];
        if (order[i] < 0 || order[i] > MAX_ORDER)
            snprintf(why, sizeof why, "order[%zu] = %d for value reference %u: 1 is the first "
                     "derivative, the only one this FMU has", i, order[i], vr[i]);
        else if (vr[i] >= (1u << ORDER_SHIFT))
            snprintf(why, sizeof why, "unknown value reference %u", vr[i]);
        else {
            codes[i] = DERIVATIVE_BASE + ((fmi2ValueReference)order[i] << ORDER_SHIFT) + vr[i];
            continue;
        }
        free(codes);
        return refuse(s, call, why);
    }
    fmi2Status status = setting
        ? INNER(Set, fmi2SetReal)(s->inner, codes, n, (const fmi2Real *)value)
        : INNER(Get, fmi2GetReal)(s->inner, codes, n, (fmi2Real *)value);
    free(codes);
    return leave(s, status);
}

EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                              size_t n, const fmi2Integer order[],
                                              const fmi2Real value[]) {
    Shim *s = enter(c, "fmi2SetRealInputDerivatives");
    if (!s) return fmi2Error;
    return derivative_call(s, "fmi2SetRealInputDerivatives", vr, n, order, (void *)value, 1);
}

EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                               size_t n, const fmi2Integer order[],
                                               fmi2Real value[]) {
    Shim *s = enter(c, "fmi2GetRealOutputDerivatives");
    if (!s) return fmi2Error;
    return derivative_call(s, "fmi2GetRealOutputDerivatives", vr, n, order, value, 0);
}

EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_set_prior) {
    typedef fmi2Status (*F)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
    Shim *s = enter(c, "fmi2DoStep");
    if (!s) return fmi2Error;
    if (fast_do_step(&s->fast, t, h)) return fmi2OK;
    return leave(s, INNER(F, fmi2DoStep)(s->inner, t, h, no_set_prior));
}

#define FORWARD_STATUS(fn, type)                                                          \
    EXPORT fmi2Status fn(fmi2Component c, const fmi2StatusKind kind, type *value) {       \
        typedef fmi2Status (*F)(fmi2Component, fmi2StatusKind, type *);                   \
        Shim *s = enter(c, #fn);                                                          \
        if (!s) return fmi2Error;                                                         \
        if (!value) return refuse(s, #fn, "the value pointer is NULL");                   \
        return leave(s, INNER(F, fn)(s->inner, kind, value));                             \
    }
FORWARD_STATUS(fmi2GetStatus, fmi2Status)
FORWARD_STATUS(fmi2GetRealStatus, fmi2Real)
FORWARD_STATUS(fmi2GetIntegerStatus, fmi2Integer)
FORWARD_STATUS(fmi2GetBooleanStatus, fmi2Boolean)
FORWARD_STATUS(fmi2GetStringStatus, fmi2String)
