/* The shim's two halves and what they share: the FMI forwarding (agilesat_fmi2.c) and the
 * fast paths (fast_paths.c), which answer calls from the slave's arrays without entering
 * Python.  The forwarding knows the fast paths only through the functions below: each
 * returns 1 when it served the call (the caller returns fmi2OK), 0 to forward it. */
#ifndef AGILESAT_SHIM_H
#define AGILESAT_SHIM_H

#include <stddef.h>
#include <stdint.h>

#include "fmi2_abi.h"
#include "protocol.h"

#define EXPORT __attribute__((visibility("default")))

/* The oldest glibc the toolchain can target: every glibc function the shim calls bound to
 * its x86-64 baseline version GLIBC_2.2.5, not to the newest of the building machine (dl*
 * and pthread_once moved into libc in 2.34 with new versions; memcpy got one in 2.14).
 * Linked with libdl and libpthread kept (--no-as-needed), an older glibc resolves them
 * there, a newer one in libc's compatibility symbols.  tests/fmus/test_portability.py
 * checks the binary's symbol versions; pythonfmu's binary beside it needs more (docs/hosts.md). */
#if defined(__x86_64__) && defined(__GLIBC__)
__asm__(".symver dlopen,dlopen@GLIBC_2.2.5");
__asm__(".symver dlsym,dlsym@GLIBC_2.2.5");
__asm__(".symver dlerror,dlerror@GLIBC_2.2.5");
__asm__(".symver dladdr,dladdr@GLIBC_2.2.5");
__asm__(".symver pthread_once,pthread_once@GLIBC_2.2.5");
__asm__(".symver memcpy,memcpy@GLIBC_2.2.5");
#endif

/* Largest array a call may pass (pythonfmu indexes with int and builds Python lists). */
#define MAX_VALUES ((size_t)1 << 24)

/* The C step path's entries (fmus/c_entries.py): the step entry gets the model's time and
 * the step size, the output entry the time. */
typedef int32_t (*StepEntry)(double *values, int64_t n_values, double *state, int64_t n_state,
                             double t, double dt);
typedef int32_t (*OutputEntry)(double *values, int64_t n_values, double *state,
                               int64_t n_state, double t);

/* What the block arms (fast_paths.c armed()): the entries, the state and snapshot arrays. */
typedef struct {
    StepEntry step;
    OutputEntry output;
    double *state, *saved;
    size_t n_state, n_kept, start, stop;   /* outputs: values[start:stop] */
} Armed;

/* An instance's fast paths: the slave's arrays (NULL values when off) and the counts. */
typedef struct {
    double *values;              /* the slave's model.values */
    size_t n_values;
    const unsigned char *kind;   /* per value reference: KIND_* */
    int32_t *control;            /* the flags (protocol.h): the slave's */
    double *block;               /* the step's end, the C step path's addresses: the slave's */
    int step_path;               /* the C step path is on (AGILESAT_SHIM_STEP) */
    const double *checked_rows;  /* the step-end rows found inside the value array ... */
    size_t checked_n_rows;       /* ... and how many (checked once, not at every step) */
    int armed_known, armed_ok;   /* armed(): the last answer, ... */
    Armed armed;
    double armed_fields[B_OUTPUTS_STOP - B_STEP + 1], armed_kept;  /* ... from these fields */
    unsigned long long served, forwarded;           /* fmi2GetReal/fmi2SetReal calls */
    unsigned long long c_steps, c_outputs, c_fallbacks;  /* the C step path's */
} FastPaths;

/* Asks the slave for n Reals of the value references vr (pythonfmu's fmi2GetReal): 1 when it
 * answered fmi2OK and logged nothing. */
typedef int (*Ask)(void *shim, const fmi2ValueReference vr[], size_t n, fmi2Real got[]);

void fast_paths_connect(FastPaths *f, Ask ask, void *shim);
void fast_paths_disconnect(FastPaths *f);
int fast_get_real(FastPaths *f, const fmi2ValueReference vr[], size_t n, fmi2Real value[]);
int fast_set_real(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                  const fmi2Real value[]);
int fast_set_integer(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                     const fmi2Integer value[]);
int fast_set_boolean(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                     const fmi2Boolean value[]);
int fast_get_integer(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                     fmi2Integer value[]);
int fast_get_boolean(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                     fmi2Boolean value[]);
int fast_do_step(FastPaths *f, double t, double h);

/* agilesat_fmi2.c: the fast paths of the live instance c, or NULL. */
FastPaths *fast_paths_of(fmi2Component c);

#endif
