/* A plain C FMI 2.0 co-simulation host, as Simulink, Dymola or any C/C++ tool drives an
 * FMU: dlopen() the binary of each extracted FMU and call the FMI 2.0 C API.  No Python
 * is involved on the host side.
 *
 *     fmi2_host SCRIPT RESULTS.csv [--reload-per-instance]
 *
 * --reload-per-instance: before each fmi2Instantiate, the host closes the binary of that
 * FMU (every handle it holds on it: the library is unloaded unless it cannot be) and loads
 * it again, as ECOS's loader does, while the instances made before live on.
 *
 * SCRIPT is a list of calls, one per line (tests/tools/c_host/script.py writes it from a system;
 * paths without spaces):
 *
 *     fmu ID DIR MODEL_IDENTIFIER GUID INSTANCE   load DIR/binaries/linux64/MODEL_IDENTIFIER.so
 *     slots N                       N value slots (doubles), all 0
 *     column SLOT NAME              record SLOT in the results under NAME
 *     instantiate ID                fmi2Instantiate (co-simulation, logging off)
 *     setup ID START STOP           fmi2SetupExperiment
 *     set ID R|I|B VR VALUE         fmi2SetReal/Integer/Boolean of one variable
 *     set ID S VR TEXT              fmi2SetString (TEXT: the rest of the line)
 *     enter ID | exit ID | terminate ID
 *     get ID R|I|B VR SLOT          slot <- variable
 *     put ID R|I|B VR SLOT          variable <- slot
 *     step ID                       fmi2DoStep(t, h): inside a loop only
 *     record                        write the time and the recorded slots (in a loop: t + H)
 *     loop N START H ... end        repeat the calls between for k = 0..N-1, t = START + k H
 *
 * Every status is checked: anything but fmi2OK/fmi2Warning stops the run with exit code 2,
 * naming the instance, call and time; the rows recorded so far stay in RESULTS.csv.  The
 * FMUs' log messages go to stderr.  Exit code 1: a bad script or an FMU that cannot load.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_abi.h"

#define MAX_FMUS 32
#define MAX_LINES 100000

typedef fmi2Status (*ArrayCall)(fmi2Component, const fmi2ValueReference *, size_t, void *);

typedef struct {
    char name[1024], path[PATH_MAX + 300];
    void *library;
    fmi2Component component;
    char guid[128], resources[PATH_MAX + 32];
    fmi2Component (*instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String,
                                 const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
    fmi2Status (*setup)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real);
    fmi2Status (*enter)(fmi2Component), (*exit_)(fmi2Component), (*terminate)(fmi2Component);
    fmi2Status (*do_step)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
    void (*free_instance)(fmi2Component);
    ArrayCall get[3], set[3];       /* Real, Integer, Boolean */
    fmi2Status (*set_string)(fmi2Component, const fmi2ValueReference *, size_t,
                             const fmi2String *);
} Fmu;

static Fmu fmus[MAX_FMUS];
static int n_fmus;
static double *slots;
static int n_slots, *columns, n_columns;
static char **column_names;
static FILE *results;
static double now, reached;   /* time of the current step, time it reaches */
static int reload_per_instance;

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    va_list args;
    va_start(args, message);
    fprintf(stderr, "[%s] status %d %s: ", instance ? instance : "?", (int)status,
            category ? category : "");
    vfprintf(stderr, message ? message : "", args);
    fputc('\n', stderr);
    va_end(args);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static void die(int code, const char *format, ...) {
    va_list args;
    va_start(args, format);
    fprintf(stderr, "fmi2_host: ");
    vfprintf(stderr, format, args);
    fputc('\n', stderr);
    va_end(args);
    if (results) fclose(results);
    exit(code);
}

static void check(const Fmu *f, const char *call, fmi2Status status) {
    if (status > fmi2Warning)
        die(2, "%s: %s at t=%.17g returned status %d", f->name, call, now, (int)status);
}

static void *symbol(Fmu *f, const char *name) {
    void *s = dlsym(f->library, name);
    if (!s) die(1, "%s: the binary does not export %s", f->name, name);
    return s;
}

/* dlopen the FMU's binary and resolve its functions. */
static void open_library(Fmu *f) {
    f->library = dlopen(f->path, RTLD_NOW | RTLD_LOCAL);
    if (!f->library) die(1, "%s: cannot load %s: %s", f->name, f->path, dlerror());
    f->instantiate = symbol(f, "fmi2Instantiate");
    f->setup = symbol(f, "fmi2SetupExperiment");
    f->enter = symbol(f, "fmi2EnterInitializationMode");
    f->exit_ = symbol(f, "fmi2ExitInitializationMode");
    f->terminate = symbol(f, "fmi2Terminate");
    f->do_step = symbol(f, "fmi2DoStep");
    f->free_instance = symbol(f, "fmi2FreeInstance");
    const char *types[3] = {"Real", "Integer", "Boolean"};
    for (int k = 0; k < 3; k++) {
        char name[32];
        snprintf(name, sizeof name, "fmi2Get%s", types[k]);
        f->get[k] = (ArrayCall)symbol(f, name);
        snprintf(name, sizeof name, "fmi2Set%s", types[k]);
        f->set[k] = (ArrayCall)symbol(f, name);
    }
    f->set_string = symbol(f, "fmi2SetString");
}

static void load(int id, const char *dir, const char *model_identifier, const char *guid,
                 const char *instance) {
    if (id != n_fmus || id >= MAX_FMUS) die(1, "fmu ids must count 0, 1, ... < %d", MAX_FMUS);
    Fmu *f = &fmus[n_fmus++];
    char absolute[PATH_MAX];
    snprintf(f->name, sizeof f->name, "%s", instance);
    snprintf(f->guid, sizeof f->guid, "%s", guid);
    if (!realpath(dir, absolute)) die(1, "%s: no directory %s", instance, dir);
    snprintf(f->resources, sizeof f->resources, "file://%s/resources", absolute);
    snprintf(f->path, sizeof f->path, "%s/binaries/linux64/%s.so", absolute, model_identifier);
    open_library(f);
}

/* --reload-per-instance: every handle on f's binary closed (unloaded, unless it cannot
 * be), then opened again, functions resolved anew for every FMU of that binary. */
static void reload(Fmu *f) {
    for (int i = 0; i < n_fmus; i++)
        if (!strcmp(fmus[i].path, f->path) && dlclose(fmus[i].library))
            die(1, "%s: dlclose: %s", fmus[i].name, dlerror());
    for (int i = 0; i < n_fmus; i++)
        if (!strcmp(fmus[i].path, f->path)) open_library(&fmus[i]);
}

static Fmu *fmu(int id) {
    if (id < 0 || id >= n_fmus) die(1, "no fmu %d", id);
    return &fmus[id];
}

static int type_index(char type) {
    const char *at = strchr("RIB", type);
    if (!type || !at) die(1, "type must be R, I or B, got %c", type);
    return (int)(at - "RIB");
}

static double *slot(int k) {
    if (k < 0 || k >= n_slots) die(1, "no slot %d", k);
    return &slots[k];
}

/* One variable between a slot and the FMU, converting Integer/Boolean to and from double. */
static void transfer(Fmu *f, int get, char type, fmi2ValueReference vr, double *value) {
    int k = type_index(type);
    fmi2Status status;
    if (k == 0) {
        status = (get ? f->get[0] : f->set[0])(f->component, &vr, 1, value);
    } else {
        if (!get && !(*value >= INT_MIN && *value <= INT_MAX))
            die(1, "%s: value %g is not an Integer/Boolean", f->name, *value);
        int integer = (int)*value;
        status = (get ? f->get[k] : f->set[k])(f->component, &vr, 1, &integer);
        if (get) *value = integer;
    }
    const char *calls[2][3] = {{"fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean"},
                               {"fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean"}};
    check(f, calls[get != 0][k], status);
}

static void record(double time) {
    fprintf(results, "%.17g", time);
    for (int i = 0; i < n_columns; i++) fprintf(results, ",%.17g", slots[columns[i]]);
    fputc('\n', results);
    fflush(results);
}

static void header(void) {
    fprintf(results, "time");
    for (int i = 0; i < n_columns; i++) fprintf(results, ",\"%s\"", column_names[i]);
    fputc('\n', results);
}

/* Execute lines [first, last); t, h: the step in a loop (h = 0 outside). */
static void run(char **lines, int first, int last, double t, double h) {
    for (int i = first; i < last; i++) {
        char op[32], name[1024], type;
        int id, k, n, end;
        unsigned vr;
        double a, b;
        const char *line = lines[i];
        if (sscanf(line, "%31s", op) != 1 || op[0] == '#') continue;
        if (!strcmp(op, "loop")) {
            if (sscanf(line, "loop %d %lf %lf", &n, &a, &b) != 3) die(1, "bad line: %s", line);
            int depth = 1;
            for (end = i + 1; end < last && depth; end++) {
                if (!strncmp(lines[end], "loop", 4)) depth++;
                if (!strcmp(lines[end], "end")) depth--;
            }
            if (depth) die(1, "loop without end");
            for (k = 0; k < n; k++) {
                now = a + k * b;
                reached = a + (k + 1) * b;
                run(lines, i + 1, end - 1, now, b);
            }
            now = reached;
            i = end - 1;
        } else if (!strcmp(op, "fmu")) {
            char dir[PATH_MAX], identifier[256], guid[128];
            if (sscanf(line, "fmu %d %4095s %255s %127s %1023s", &id, dir, identifier, guid,
                       name) != 5)
                die(1, "bad line: %s", line);
            load(id, dir, identifier, guid, name);
        } else if (!strcmp(op, "slots")) {
            if (sscanf(line, "slots %d", &n_slots) != 1 || n_slots <= 0) die(1, "bad: %s", line);
            slots = calloc((size_t)n_slots, sizeof *slots);
            columns = calloc((size_t)n_slots, sizeof *columns);
            column_names = calloc((size_t)n_slots, sizeof *column_names);
            if (!slots || !columns || !column_names) die(1, "out of memory");
        } else if (!strcmp(op, "column")) {
            if (sscanf(line, "column %d %1023s", &k, name) != 2 || n_columns >= n_slots)
                die(1, "bad line: %s", line);
            slot(k);
            columns[n_columns] = k;
            if (!(column_names[n_columns++] = strdup(name))) die(1, "out of memory");
        } else if (!strcmp(op, "instantiate")) {
            if (sscanf(line, "instantiate %d", &id) != 1) die(1, "bad line: %s", line);
            Fmu *f = fmu(id);
            if (reload_per_instance) reload(f);
            f->component = f->instantiate(f->name, fmi2CoSimulation, f->guid, f->resources,
                                          &callbacks, fmi2False, fmi2False);
            if (!f->component) die(2, "%s: fmi2Instantiate returned NULL", f->name);
        } else if (!strcmp(op, "setup")) {
            if (sscanf(line, "setup %d %lf %lf", &id, &a, &b) != 3) die(1, "bad line: %s", line);
            now = a;
            check(fmu(id), "fmi2SetupExperiment",
                  fmu(id)->setup(fmu(id)->component, fmi2False, 0.0, a, fmi2True, b));
        } else if (!strcmp(op, "set")) {
            int text = 0;
            if (sscanf(line, "set %d %c %u %n", &id, &type, &vr, &text) != 3 || !text)
                die(1, "bad line: %s", line);
            if (type == 'S') {
                fmi2String value = line + text;
                check(fmu(id), "fmi2SetString",
                      fmu(id)->set_string(fmu(id)->component, &vr, 1, &value));
            } else {
                if (sscanf(line + text, "%lf", &a) != 1) die(1, "bad line: %s", line);
                transfer(fmu(id), 0, type, vr, &a);
            }
        } else if (!strcmp(op, "get") || !strcmp(op, "put")) {
            if (sscanf(line + 3, " %d %c %u %d", &id, &type, &vr, &k) != 4)
                die(1, "bad line: %s", line);
            transfer(fmu(id), op[0] == 'g', type, vr, slot(k));
        } else if (!strcmp(op, "enter") || !strcmp(op, "exit") || !strcmp(op, "terminate")) {
            if (sscanf(line, "%*s %d", &id) != 1) die(1, "bad line: %s", line);
            Fmu *f = fmu(id);
            fmi2Status (*call)(fmi2Component) =
                op[0] == 'e' ? (op[1] == 'n' ? f->enter : f->exit_) : f->terminate;
            check(f, op, call(f->component));
        } else if (!strcmp(op, "step")) {
            if (sscanf(line, "step %d", &id) != 1 || h <= 0) die(1, "bad line: %s", line);
            check(fmu(id), "fmi2DoStep", fmu(id)->do_step(fmu(id)->component, t, h, fmi2True));
        } else if (!strcmp(op, "record")) {
            if (ftell(results) == 0) header();
            record(h > 0 ? reached : now);
        } else {
            die(1, "unknown call: %s", line);
        }
    }
}

int main(int argc, char **argv) {
    reload_per_instance = argc == 4 && !strcmp(argv[3], "--reload-per-instance");
    if (argc != 3 && !reload_per_instance)
        die(1, "usage: fmi2_host SCRIPT RESULTS.csv [--reload-per-instance]");
    FILE *script = fopen(argv[1], "r");
    if (!script) die(1, "cannot read %s", argv[1]);
    results = fopen(argv[2], "w");
    if (!results) die(1, "cannot write %s", argv[2]);
    char **lines = calloc(MAX_LINES, sizeof *lines), buffer[8192];
    int n = 0;
    if (!lines) die(1, "out of memory");
    while (fgets(buffer, sizeof buffer, script)) {
        if (n == MAX_LINES) die(1, "%s: more than %d lines", argv[1], MAX_LINES);
        buffer[strcspn(buffer, "\r\n")] = '\0';
        if (!(lines[n++] = strdup(buffer))) die(1, "out of memory");
    }
    fclose(script);
    run(lines, 0, n, 0.0, 0.0);
    for (int i = 0; i < n_fmus; i++)
        if (fmus[i].component) fmus[i].free_instance(fmus[i].component);
    fclose(results);
    return 0;
}
