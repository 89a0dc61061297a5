/* An instance of a cleatfmu tire FMU, shared by the FMI 2.0 and FMI 3.0 layers.
 *
 * Modes and call-sequence checks, values, direct-feedthrough evaluation, the
 * checks of refused values, FMU state snapshots and their serialization, and
 * logging through the importer's callback.  Statuses are the FMI ones (equal in
 * FMI 2.0 and 3.0): 0 OK, 3 Error.
 */
#ifndef CLEATFMU_INSTANCE_H
#define CLEATFMU_INSTANCE_H

#include "cleatfmu_names.h"

#include <stddef.h>

#include "cleatfmu_model.h"
#include "cleatfmu_resources.h"

/* Value reference of the (read-only) independent variable time, after the kind's variables. */
#define CI_VR_TIME N_VARIABLES

#define CI_OK 0
#define CI_WARNING 1
#define CI_ERROR 3

typedef enum {
    CI_INSTANTIATED = 1, CI_INITIALIZATION = 2, CI_STEP = 4, CI_TERMINATED = 8
} CleatfmuMode;

#define CI_ANY_MODE (CI_INSTANTIATED | CI_INITIALIZATION | CI_STEP | CI_TERMINATED)
#define CI_READABLE (CI_INITIALIZATION | CI_STEP | CI_TERMINATED)
#define CI_SETTABLE (CI_INSTANTIATED | CI_INITIALIZATION | CI_STEP)

struct CleatfmuInstance;
/* Deliver one formatted message to the importer (the FMI layer's adapter). */
typedef void (*CleatfmuLogFunction)(const struct CleatfmuInstance *s, int status, const char *category,
                                    const char *message);
typedef void (*CleatfmuFunction)(void);

typedef struct CleatfmuInstance {
    CleatfmuLogFunction log;       /* adapter of the FMI layer */
    CleatfmuFunction callback;     /* the importer's logger */
    void *environment;             /* the importer's environment pointer */
    void (*free_memory)(void *);   /* frees this instance (the importer's, or free) */
    char name[128];
    int log_errors, log_calls, log_warnings;
    CleatfmuMode mode;
    double time;
    int stale, unchecked;
    double values[N_VALUES];       /* the variables, then the hidden state */
    double start[N_VALUES];
    char token[CLEATFMU_GUID_SIZE];
    void *data;                    /* the kind's data from the resources (the road's profile), or NULL */
    void *states;                  /* the FMU state snapshots not yet freed (freed with the instance) */
} CleatfmuInstance;

/* Read the start values of the FMU at `resource_location` and check `token` against
 * the FMU's; fills s->values, s->start (returns 0) or msg (returns 1). */
int ci_load(CleatfmuInstance *s, const char *token, const char *resource_location, char *msg, size_t n);
/* Free the instance, its FMU state snapshots not yet freed and the kind's data (cleatfmu_load). */
void ci_free(CleatfmuInstance *s);
/* Log a formatted error (category logStatusError) and return CI_ERROR. */
int ci_fail(CleatfmuInstance *s, const char *fmt, ...);
/* Log a warning (status warning, category logStatusWarning); the call that found it still succeeds. */
void ci_warn(CleatfmuInstance *s, const char *text);
/* Is `s` an instance in one of `modes`?  Logs the call (logCalls) or the violation. */
int ci_allowed(CleatfmuInstance *s, const char *function, int modes);
/* Set log categories (logStatusError, logCalls; and logStatusWarning for a kind that warns, the tire map):
 * n == 0 sets all; returns CI_OK or CI_ERROR for an unknown category. */
int ci_set_debug_logging(CleatfmuInstance *s, int on, size_t n, const char *const categories[]);
int ci_check_parameters(CleatfmuInstance *s);
int ci_reset(CleatfmuInstance *s);
/* Read variables of `type`: reals[i] (VT_REAL) or flags[i] = 0/1 through put_flag. */
int ci_get(CleatfmuInstance *s, const char *function, CleatfmuVarType type, const unsigned int *vr, size_t nvr,
           double *reals, void *flags, void (*put_flag)(void *flags, size_t i, int value));
/* Set variables of `type` all or nothing; flags read through get_flag (returns 0, 1, or -1 if not a Boolean). */
int ci_set(CleatfmuInstance *s, const char *function, CleatfmuVarType type, const unsigned int *vr, size_t nvr,
           const double *reals, const void *flags, int (*get_flag)(const void *flags, size_t i));
int ci_do_step(CleatfmuInstance *s, const char *function, double current, double step);

/* FMU state snapshots and their serialization (the same bytes for FMI 2.0 and 3.0). */
int ci_get_state(CleatfmuInstance *s, const char *function, void **state);
int ci_set_state(CleatfmuInstance *s, const char *function, const void *state);
int ci_free_state(CleatfmuInstance *s, const char *function, void **state);
size_t ci_serialized_size(void);
int ci_serialize(CleatfmuInstance *s, const char *function, const void *state, unsigned char *buffer, size_t size);
int ci_deserialize(CleatfmuInstance *s, const char *function, const unsigned char *buffer, size_t size,
                   void **state);

#endif
