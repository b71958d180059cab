/* The master's macro-step loop, compiled (orchestration/cosim/loop.py builds and loads it).

   One macro step n (t_n = start + n * step) is a fixed program of operations that
   orchestration/cosim/loop.py derives from the schedule once (its Python loop runs the
   same program where this one cannot be compiled, with the same arithmetic):

     SET_*    gather buffer[i] = values[index[i]], then fmi2Set*(component, vrs, n, buffer)
     GET_*    fmi2Get*(component, vrs, n, buffer), then scatter values[index[i]] = buffer[i]
     DO_STEP  fmi2DoStep(component, t_n, h, fmi2True)   (h = step * every, from Python)

   and, for input/output derivative links (orchestration/cosim/derivatives.py; components at
   the base step only):

     GET_DERIVATIVES  fmi2GetRealOutputDerivatives(component, vrs, n, orders, buffer), then
                      slopes[index[i]] = buffer[i]
     SET_DERIVATIVES  buffer[i] = (values[index[i]] - previous[index[i]]) / h where
                      interpolated[i], else slopes[index[i]]; then
                      fmi2SetRealInputDerivatives(component, vrs, n, orders, buffer)
     SET_PREVIOUS     SET_REAL gathering from previous (the values at t_n)
     KEEP_PREVIOUS    previous = values (n of them), at the start of a step

   An operation of a component with its own step (every > 1 base steps) runs only at the
   steps its ``when`` says: AT_STEP when n is a multiple of every (it steps from t_n),
   AT_READ when n + 1 is (its outputs are due at t_{n+1}), or either.  After each step the
   row (t_{n+1}, values) is written to rows.  The function pointers are fmpy's bound FMI
   functions; nothing here loads or owns an FMU.

   agilesat_loop runs steps first .. last - 1 and returns how many it completed: all of
   them, fewer once ``budget`` seconds have passed (so that the caller can record rows,
   report progress and look at signals between chunks), or at the first call that returns
   more than fmi2Warning: then failure[0] is that operation's index, failure[1] its
   status, and the failing step's row is not written.  *clock holds t_n of the step under
   way (the time the FMU log messages are stamped with).  No floating-point contraction
   (built with -ffp-contract=off): t_n and every value are the Python loop's, bit for bit. */

#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

/* CPython's own float formatting (what repr(float) calls; resolved in the Python process
   that loads this library through ctypes.PyDLL, holding the GIL). */
extern char *PyOS_double_to_string(double value, char format, int precision, int flags, int *type);
extern void PyMem_Free(void *pointer);
#define PY_DTSF_ADD_DOT_0 0x02

enum { SET_REAL, GET_REAL, SET_INTEGER, GET_INTEGER, DO_STEP,
       GET_DERIVATIVES, SET_DERIVATIVES, SET_PREVIOUS, KEEP_PREVIOUS };
enum { AT_STEP = 1, AT_READ = 2, AT_START = 4 };

typedef int (*real_call)(void *, const unsigned int *, size_t, double *);
typedef int (*integer_call)(void *, const unsigned int *, size_t, int *);
typedef int (*step_call)(void *, double, double, int);
typedef int (*derivative_call)(void *, const unsigned int *, size_t, const int *, double *);

struct operation {
    int32_t kind, when;
    int64_t every;
    void *function, *component;
    const unsigned int *vrs;
    int64_t n;
    const int64_t *index;
    void *buffer;
    double h;
    const int *orders;              /* derivative operations: the orders (all 1) */
    double *slopes, *previous;      /* the output derivatives, the values at t_n */
    const unsigned char *interpolated;
};

static double seconds(void) {
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

static int due(const struct operation *op, int64_t n) {
    if (op->when == AT_START) return n == 0;
    if (op->every == 1) return 1;
    return ((op->when & AT_STEP) && n % op->every == 0) ||
           ((op->when & AT_READ) && (n + 1) % op->every == 0);
}

static int run(const struct operation *op, double *values, double t) {
    int64_t i;
    switch (op->kind) {
    case SET_REAL: {
        double *buffer = op->buffer;
        for (i = 0; i < op->n; i++) buffer[i] = values[op->index[i]];
        return ((real_call)op->function)(op->component, op->vrs, (size_t)op->n, buffer);
    }
    case GET_REAL: {
        double *buffer = op->buffer;
        int status = ((real_call)op->function)(op->component, op->vrs, (size_t)op->n, buffer);
        if (status <= 1)
            for (i = 0; i < op->n; i++) values[op->index[i]] = buffer[i];
        return status;
    }
    case SET_INTEGER: { /* truncation as numpy's cast; the values are Integer outputs, integral */
        int *buffer = op->buffer;
        for (i = 0; i < op->n; i++) buffer[i] = (int)values[op->index[i]];
        return ((integer_call)op->function)(op->component, op->vrs, (size_t)op->n, buffer);
    }
    case GET_INTEGER: {
        int *buffer = op->buffer;
        int status = ((integer_call)op->function)(op->component, op->vrs, (size_t)op->n, buffer);
        if (status <= 1)
            for (i = 0; i < op->n; i++) values[op->index[i]] = (double)buffer[i];
        return status;
    }
    case DO_STEP:
        return ((step_call)op->function)(op->component, t, op->h, 1);
    case GET_DERIVATIVES: {
        double *buffer = op->buffer;
        int status = ((derivative_call)op->function)(op->component, op->vrs, (size_t)op->n,
                                                     op->orders, buffer);
        if (status <= 1)
            for (i = 0; i < op->n; i++) op->slopes[op->index[i]] = buffer[i];
        return status;
    }
    case SET_DERIVATIVES: {
        double *buffer = op->buffer;
        for (i = 0; i < op->n; i++) {
            int64_t j = op->index[i];
            buffer[i] = op->interpolated[i] ? (values[j] - op->previous[j]) / op->h
                                            : op->slopes[j];
        }
        return ((derivative_call)op->function)(op->component, op->vrs, (size_t)op->n,
                                               op->orders, buffer);
    }
    case SET_PREVIOUS: {
        double *buffer = op->buffer;
        for (i = 0; i < op->n; i++) buffer[i] = op->previous[op->index[i]];
        return ((real_call)op->function)(op->component, op->vrs, (size_t)op->n, buffer);
    }
    case KEEP_PREVIOUS:
        memcpy(op->previous, values, (size_t)op->n * sizeof *values);
        return 0;
    }
    return 3; /* unknown operation: fmi2Error (loop.py never builds one) */
}

int64_t agilesat_loop(const struct operation *ops, int64_t n_ops, double *values,
                      int64_t n_values, double start, double step, int64_t first, int64_t last,
                      double budget, double *rows, double *clock, int64_t *failure) {
    double began = seconds();
    int64_t n, k, j;
    for (n = first; n < last; n++) {
        double t = start + (double)n * step;
        double *row = rows + (n - first) * (n_values + 1);
        *clock = t;
        for (k = 0; k < n_ops; k++) {
            if (!due(&ops[k], n)) continue;
            int status = run(&ops[k], values, t);
            if (status > 1) {
                failure[0] = k;
                failure[1] = status;
                return n - first;
            }
        }
        row[0] = start + (double)(n + 1) * step;
        for (j = 0; j < n_values; j++) row[j + 1] = values[j];
        if (seconds() - began >= budget) return n + 1 - first;
    }
    return last - first;
}

/* The CSV lines of n_rows rows of width values: each value as Python's repr(float), comma
   separated, each line ended by a newline (orchestration/output/recorder.py writes the same in
   Python).  Returns the bytes written to out, or -1 if size is too small or memory ran
   out.  Needs the GIL (PyOS_double_to_string allocates with PyMem). */
int64_t agilesat_csv(const double *rows, int64_t n_rows, int64_t width, char *out,
                     int64_t size) {
    int64_t used = 0, i, j;
    for (i = 0; i < n_rows; i++) {
        for (j = 0; j < width; j++) {
            char *text = PyOS_double_to_string(rows[i * width + j], 'r', 0, PY_DTSF_ADD_DOT_0,
                                               NULL);
            if (text == NULL) return -1;
            size_t length = strlen(text);
            if (used + (int64_t)length + 1 > size) {
                PyMem_Free(text);
                return -1;
            }
            memcpy(out + used, text, length);
            PyMem_Free(text);
            used += (int64_t)length;
            out[used++] = j + 1 < width ? ',' : '\n';
        }
    }
    return used;
}
