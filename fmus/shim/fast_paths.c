/* The shim's fast paths: valid calls answered in C from the slave's arrays, without
 * entering Python (the slave's half: fmus/fast_paths.py; the flags and indices:
 * protocol.h, generated from fmus/protocol.py).  Each either serves a call completely, as
 * the slave would, or leaves it untouched to be forwarded: the slave then gives its status
 * and message.  The answer is the same either way; so are results, bit for bit.  Only the
 * instance's own fields are used: one instance per thread is safe, as FMI 2.0 allows.
 *
 * Handshake.  After fmi2Instantiate and fmi2Reset (pythonfmu then creates a new slave) the
 * shim asks the slave for FAST_PATH_N values of the reserved value reference FAST_PATH_VR
 * (no host can: plain calls on value references from DERIVATIVE_BASE up are refused): the
 * version, the address and length of model.values (value reference = offset) and the
 * addresses of kind[], control[] and block[], which the slave never replaces.
 * AGILESAT_SHIM_FAST=0 at that moment turns everything here off for the instance;
 * AGILESAT_SHIM_STEP=0 the C step path only.
 *
 * Fast get/set.  In step mode (STEP_MODE), a fmi2GetReal of Real scalars is served while
 * the outputs are valid (OUTPUTS_VALID), the same for fmi2GetInteger (KIND_INTEGER*: a whole
 * number fmi2Integer holds) and fmi2GetBoolean (KIND_BOOLEAN*: 0 or 1); a fmi2SetReal of
 * finite values to Real inputs is written in, and a fmi2SetInteger/fmi2SetBoolean to Integer
 * (Boolean) inputs as the slave writes them (the integer as a double, a Boolean as 1.0 or
 * 0.0), a feedthrough input (KIND_*FEEDTHROUGH) clearing OUTPUTS_VALID.
 *
 * The C step path.  Once the model's kernels run compiled, the slave arms (control[C_STEP],
 * control[C_OUTPUT]) the model's C entries (fmus/c_entries.py) in block[], with its state
 * array and a snapshot buffer.  A fmi2DoStep the slave would accept (step mode, a step size
 * positive and finite, the time continuous, its end not after the stop time) is served: the
 * step entry (nothing for a stateless model), the inputs brought to the step's end (those
 * whose derivative was set: inputs_to_step_end), the step's end, the outputs invalid.  A
 * get with the outputs invalid evaluates them with the output entry.  An entry returning
 * anything but 0, or non-finite outputs: the arrays are put back from the snapshot and the
 * call forwarded.  The snapshot holds the values and the state's first B_N_KEPT values:
 * the rest is the model's scratch, which whatever an entry left there does not change
 * (fmus/fast_paths.py).
 * C_DIRTY tells the slave, at its next call, to take over what was done here. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "shim.h"

static void *address(double x) {
    uintptr_t a = (uintptr_t)x;
    return x > 0 && x < 9007199254740992.0 && (double)a == x ? (void *)a : NULL;
}

void fast_paths_disconnect(FastPaths *f) {
    f->values = NULL;
    f->kind = NULL;
    f->control = NULL;
    f->block = NULL;
    f->n_values = 0;
    f->checked_rows = NULL;
    f->checked_n_rows = 0;
    f->armed_known = 0;
}

static int switched_off(const char *variable) {
    const char *value = getenv(variable);
    return value && strcmp(value, "0") == 0;
}

void fast_paths_connect(FastPaths *f, Ask ask, void *shim) {
    fast_paths_disconnect(f);
    if (switched_off("AGILESAT_SHIM_FAST")) return;
    f->step_path = !switched_off("AGILESAT_SHIM_STEP");
    fmi2ValueReference vr[FAST_PATH_N];
    fmi2Real got[FAST_PATH_N] = {0};
    for (int i = 0; i < FAST_PATH_N; i++) vr[i] = FAST_PATH_VR;
    if (!ask(shim, vr, FAST_PATH_N, got) || got[0] != FAST_PATH_VERSION) return;
    double *values = address(got[1]);
    unsigned char *kind = address(got[3]);
    int32_t *control = address(got[4]);
    double *block = address(got[5]);
    if (!values || !kind || !control || !block || !(got[2] >= 0 && got[2] < (double)MAX_VALUES))
        return;
    f->n_values = (size_t)got[2];
    f->kind = kind;
    f->control = control;
    f->block = block;
    f->values = values;
}

/* ---- the C step path ------------------------------------------------------------------ */

/* armed(), read now. */
static int armed_now(const FastPaths *f, Armed *a) {
    const double *b = f->block;
    a->step = (StepEntry)address(b[B_STEP]);
    a->output = (OutputEntry)address(b[B_OUTPUT]);
    a->state = address(b[B_STATE]);
    a->saved = address(b[B_SAVED]);
    if (!a->state || !a->saved || !(b[B_N_STATE] >= 0 && b[B_N_STATE] < (double)MAX_VALUES) ||
        !(b[B_N_KEPT] >= 0 && b[B_N_KEPT] <= b[B_N_STATE]) ||
        !(b[B_OUTPUTS_START] >= 0 && b[B_OUTPUTS_START] <= b[B_OUTPUTS_STOP] &&
          b[B_OUTPUTS_STOP] <= (double)f->n_values))
        return 0;
    a->n_state = (size_t)b[B_N_STATE];
    a->n_kept = (size_t)b[B_N_KEPT];
    a->start = (size_t)b[B_OUTPUTS_START];
    a->stop = (size_t)b[B_OUTPUTS_STOP];
    return b[B_N_SAVED] >= (double)(f->n_values + a->n_kept);
}

/* The block's addresses and sizes, checked; 0 when they do not fit together.  The slave
 * rewrites them seldom (at arming, once per state array): the last answer is kept with the
 * fields it was read from (bit for bit) and given again while they are the same. */
static int armed(FastPaths *f, Armed *a) {
    const double *b = f->block;
    if (f->armed_known && memcmp(f->armed_fields, b + B_STEP, sizeof f->armed_fields) == 0 &&
        memcmp(&f->armed_kept, b + B_N_KEPT, sizeof f->armed_kept) == 0) {
        *a = f->armed;
        return f->armed_ok;
    }
    memcpy(f->armed_fields, b + B_STEP, sizeof f->armed_fields);
    memcpy(&f->armed_kept, b + B_N_KEPT, sizeof f->armed_kept);
    f->armed_ok = armed_now(f, &f->armed);
    f->armed_known = 1;
    *a = f->armed;
    return f->armed_ok;
}

static void snapshot(const FastPaths *f, const Armed *a) {
    memcpy(a->saved, f->values, f->n_values * sizeof(double));
    memcpy(a->saved + f->n_values, a->state, a->n_kept * sizeof(double));
}

static void restore(const FastPaths *f, const Armed *a) {
    memcpy(f->values, a->saved, f->n_values * sizeof(double));
    memcpy(a->state, a->saved + f->n_values, a->n_kept * sizeof(double));
}

/* model.output() by the output entry; 0 (everything put back) if it leaves it to the Python
 * or the outputs are not finite. */
static int output_in_c(FastPaths *f, const Armed *a) {
    if (!a->output) return 0;
    snapshot(f, a);
    int ok = a->output(f->values, (int64_t)f->n_values, a->state, (int64_t)a->n_state,
                       f->block[B_TIME]) == 0;
    for (size_t i = a->start; ok && i < a->stop; i++) ok = isfinite(f->values[i]);
    if (!ok) restore(f, a);
    else f->c_outputs++;
    return ok;
}

/* fmus/protocol.py continuous(): CPython's math.isclose (Modules/mathmodule.c) with the
 * protocol's tolerances. */
static int continuous(double t, double end) {
    if (t == end) return 1;
    if (isinf(t) || isinf(end)) return 0;
    double diff = fabs(end - t);
    return diff <= fabs(TIME_REL_TOL * end) || diff <= fabs(TIME_REL_TOL * t) ||
           diff <= TIME_ABS_TOL;
}

/* Model.inputs_to_step_end (components/model.py), operation for operation: the inputs
 * whose derivative was set moved to the step's end.  Rows of six offsets (value,
 * derivative, given, rate, the rate's derivative, the rate's given; -1: no rate), checked
 * against the value array: 0 (nothing changed) if one is outside it.  The slave makes the
 * rows once (fmus/fast_paths.py) and never changes them, so they are checked once per
 * address and count (a model with many inputs paid the check at every step). */
static int inputs_to_step_end(FastPaths *f, double h) {
    const double *rows = address(f->block[B_STEP_END]);
    double *v = f->values, n = (double)f->n_values;
    if (!rows) return f->block[B_N_STEP_END] == 0;
    if (!(f->block[B_N_STEP_END] > 0 && f->block[B_N_STEP_END] < (double)MAX_VALUES)) return 0;
    size_t n_rows = (size_t)f->block[B_N_STEP_END];
    if (rows != f->checked_rows || n_rows != f->checked_n_rows) {
        for (size_t i = 0; i < 6 * n_rows; i++) {
            double least = i % 6 < 3 || rows[i - i % 6 + 3] >= 0 ? 0 : -1;
            if (!(rows[i] >= least && rows[i] < n)) return 0;
        }
        f->checked_rows = rows;
        f->checked_n_rows = n_rows;
    }
    for (size_t i = 0; i < n_rows; i++) {
        const double *row = rows + 6 * i;
        size_t x = (size_t)row[0], d = (size_t)row[1], g = (size_t)row[2];
        if (row[3] >= 0) {
            size_t r = (size_t)row[3], c = (size_t)row[4], rg = (size_t)row[5];
            if (v[g] != 0.0 || v[rg] != 0.0) {
                double slope = v[g] != 0.0 ? v[d] : v[r];
                v[x] = v[x] + (slope * h + 0.5 * v[c] * h * h);
            }
        } else if (v[g] != 0.0) {
            v[x] = v[x] + v[d] * h;
        }
    }
    return 1;
}

int fast_do_step(FastPaths *f, double t, double h) {
    int32_t *control = f->control;
    Armed a;
    if (!f->values || !f->step_path || !control[STEP_MODE] || control[C_STEP] == C_STEP_PYTHON)
        return 0;
    if (!(isfinite(h) && h > 0.0) || !continuous(t, f->block[B_TIME]) || !armed(f, &a)) return 0;
    if (!(t + h <= f->block[B_STOP] || continuous(t + h, f->block[B_STOP]))) return 0;
    if (control[C_STEP] == C_STEP_ENTRY) {
        if (!a.step) return 0;
        snapshot(f, &a);
        if (a.step(f->values, (int64_t)f->n_values, a.state, (int64_t)a.n_state,
                   f->block[B_TIME], h) != 0 ||
            !inputs_to_step_end(f, h)) {
            restore(f, &a);
            f->c_fallbacks++;
            return 0;
        }
    } else if (!inputs_to_step_end(f, h)) {
        return 0;
    }
    f->block[B_TIME] = t + h;
    control[OUTPUTS_VALID] = 0;
    control[C_DIRTY] = 1;
    f->c_steps++;
    return 1;
}

/* ---- fast get/set --------------------------------------------------------------------- */
/* A get may be served: step mode and every value reference of the kind(s) asked for. */
static int gettable(const FastPaths *f, const fmi2ValueReference vr[], size_t n, int integer,
                    int boolean) {
    if (!f->values || !f->control[STEP_MODE]) return 0;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= f->n_values) return 0;
        unsigned char kind = f->kind[vr[i]];
        int is_integer = kind == KIND_INTEGER || kind == KIND_INTEGER_INPUT ||
                         kind == KIND_INTEGER_FEEDTHROUGH;
        int is_boolean = kind == KIND_BOOLEAN || kind == KIND_BOOLEAN_INPUT ||
                         kind == KIND_BOOLEAN_FEEDTHROUGH;
        if (integer ? !is_integer : boolean ? !is_boolean
                    : kind == KIND_OTHER || kind >= KIND_INTEGER)
            return 0;
    }
    return 1;
}

/* The outputs are valid, or evaluated here now (the slave's _read, with the output entry). */
static int outputs_ready(FastPaths *f) {
    int32_t *control = f->control;
    Armed a;
    if (control[OUTPUTS_VALID]) return 1;
    if (!f->step_path || !control[C_OUTPUT] || !armed(f, &a) || !output_in_c(f, &a)) return 0;
    control[OUTPUTS_VALID] = 1;
    return 1;
}

/* As the slave's int(x) of a whole number fmi2Integer holds (anything else is forwarded:
 * the slave refuses it, naming the variable). */
int fast_get_integer(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                     fmi2Integer value[]) {
    if (!gettable(f, vr, n, 1, 0) || !outputs_ready(f)) return 0;
    for (size_t i = 0; i < n; i++) {
        double x = f->values[vr[i]];
        if (!(x >= -2147483648.0 && x <= 2147483647.0 && x == trunc(x))) return 0;
    }
    for (size_t i = 0; i < n; i++) value[i] = (fmi2Integer)f->values[vr[i]];
    f->served++;
    return 1;
}

/* As the slave's bool(x) of 0 or 1 (anything else is forwarded, as above). */
int fast_get_boolean(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                     fmi2Boolean value[]) {
    if (!gettable(f, vr, n, 0, 1) || !outputs_ready(f)) return 0;
    for (size_t i = 0; i < n; i++)
        if (!(f->values[vr[i]] == 0.0 || f->values[vr[i]] == 1.0)) return 0;
    for (size_t i = 0; i < n; i++) value[i] = f->values[vr[i]] != 0.0;
    f->served++;
    return 1;
}

int fast_get_real(FastPaths *f, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
    if (!gettable(f, vr, n, 0, 0) || !outputs_ready(f)) {
        f->forwarded++;
        return 0;
    }
    for (size_t i = 0; i < n; i++) value[i] = f->values[vr[i]];
    f->served++;
    return 1;
}

int fast_set_real(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                  const fmi2Real value[]) {
    int ok = f->values && f->control[STEP_MODE], feeds = 0;
    for (size_t i = 0; ok && i < n; i++) {
        unsigned char kind = vr[i] < f->n_values ? f->kind[vr[i]] : KIND_OTHER;
        ok = isfinite(value[i]) && (kind == KIND_INPUT || kind == KIND_FEEDTHROUGH);
        feeds |= kind == KIND_FEEDTHROUGH;
    }
    if (!ok) {
        f->forwarded++;
        return 0;
    }
    for (size_t i = 0; i < n; i++) f->values[vr[i]] = value[i];
    if (feeds) f->control[OUTPUTS_VALID] = 0;
    f->served++;
    return 1;
}

/* Sets of Integer (Boolean) inputs: as the slave's _write of float(v) (1.0 if v else 0.0). */
static int set_whole(FastPaths *f, const fmi2ValueReference vr[], size_t n, const int value[],
                     unsigned char input, unsigned char feedthrough, int boolean) {
    int ok = f->values && f->control[STEP_MODE], feeds = 0;
    for (size_t i = 0; ok && i < n; i++) {
        unsigned char kind = vr[i] < f->n_values ? f->kind[vr[i]] : KIND_OTHER;
        ok = kind == input || kind == feedthrough;
        feeds |= kind == feedthrough;
    }
    if (!ok) {
        f->forwarded++;
        return 0;
    }
    for (size_t i = 0; i < n; i++)
        f->values[vr[i]] = boolean ? (value[i] != 0 ? 1.0 : 0.0) : (double)value[i];
    if (feeds) f->control[OUTPUTS_VALID] = 0;
    f->served++;
    return 1;
}

int fast_set_integer(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                     const fmi2Integer value[]) {
    return set_whole(f, vr, n, value, KIND_INTEGER_INPUT, KIND_INTEGER_FEEDTHROUGH, 0);
}

int fast_set_boolean(FastPaths *f, const fmi2ValueReference vr[], size_t n,
                     const fmi2Boolean value[]) {
    return set_whole(f, vr, n, value, KIND_BOOLEAN_INPUT, KIND_BOOLEAN_FEEDTHROUGH, 1);
}

/* ---- counts, for tests and benchmarks ------------------------------------------------- */
/* Instance c's fmi2GetReal/fmi2SetReal calls served here and forwarded to the slave; 0 when
 * c is not a live instance, -1 when the fast paths are off. */
EXPORT int agilesat_shim_counters(fmi2Component c, unsigned long long counts[2]) {
    FastPaths *f = fast_paths_of(c);
    if (!f || !counts) return 0;
    counts[0] = f->served;
    counts[1] = f->forwarded;
    return f->values ? 1 : -1;
}

/* Instance c's fmi2DoStep calls served here, outputs evaluated here and steps whose entry
 * left them to the slave; 0 when c is not a live instance, -1 when the C step path is off. */
EXPORT int agilesat_shim_step_counters(fmi2Component c, unsigned long long counts[3]) {
    FastPaths *f = fast_paths_of(c);
    if (!f || !counts) return 0;
    counts[0] = f->c_steps;
    counts[1] = f->c_outputs;
    counts[2] = f->c_fallbacks;
    return f->values && f->step_path ? 1 : -1;
}
