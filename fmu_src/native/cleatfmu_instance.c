/* An instance of a cleatfmu tire FMU (see cleatfmu_instance.h). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cleatfmu_instance.h"

#define STATE_MAGIC "CLEATFMU"
#define KIND_BYTES 32
/* Version of the serialized layout below (a state of another version is refused). */
#define STATE_VERSION 2UL
/* Serialized state: magic, kind (32 bytes), header (4 bytes LE: number of values | unchecked << 16 |
 * STATE_VERSION << 24),
 * time, values (the variables, then the hidden state; native little-endian doubles), and a 64-bit FNV-1a
 * checksum of all that (8 bytes LE): a corrupted or truncated copy is refused, not installed. */
#define PAYLOAD_SIZE (8 + KIND_BYTES + 4 + 8 * (1 + N_VALUES))
#define SERIALIZED_SIZE (PAYLOAD_SIZE + 8)

/* A snapshot belongs to the instance that made it, in that instance's list: freeing the instance frees the
 * snapshots the importer did not free (fmi2FreeInstance / fmi3FreeInstance free "all the allocated memory").
 * Its kind and number of values sit right after the magic, at the same offset in every kind's snapshot, so a
 * state of another kind (another layout and size) is recognised and refused before anything else is read. */
typedef struct Snapshot {
    char magic[8];
    char kind[KIND_BYTES];
    int n_values;
    double time;
    int unchecked;
    double values[N_VALUES];
    struct Snapshot *prev, *next;
    CleatfmuInstance *owner;
} Snapshot;

static Snapshot *new_snapshot(CleatfmuInstance *s) {
    Snapshot *snap = (Snapshot *)calloc(1, sizeof *snap);
    if (snap == NULL) return NULL;
    snap->owner = s;
    snap->next = (Snapshot *)s->states;
    if (snap->next) snap->next->prev = snap;
    s->states = snap;
    return snap;
}

static void delete_snapshot(Snapshot *snap) {
    if (snap->prev) snap->prev->next = snap->next;
    else snap->owner->states = snap->next;
    if (snap->next) snap->next->prev = snap->prev;
    memset(snap->magic, 0, 8);
    free(snap);
}

int ci_load(CleatfmuInstance *s, const char *token, const char *resource_location, char *msg, size_t n) {
    if (cleatfmu_read_start_file(resource_location, s->token, s->values, msg, n)) return 1;
    if (token == NULL || strcmp(token, s->token) != 0) {
        snprintf(msg, n, "instantiation token (GUID) %.80s does not match the FMU's %s", token ? token : "NULL",
                 s->token);
        return 1;
    }
    if (cleatfmu_set_problem(s->values, msg, n)) return 1;
    if (cleatfmu_load(resource_location, &s->data, msg, n)) return 1;
    memcpy(s->start, s->values, sizeof s->values);
    s->mode = CI_INSTANTIATED;
    s->stale = 1;
    return 0;
}

void ci_free(CleatfmuInstance *s) {
    if (s == NULL) return;
    while (s->states) delete_snapshot((Snapshot *)s->states);
    cleatfmu_unload(s->data);
    s->data = NULL;
    s->free_memory(s);
}

int ci_fail(CleatfmuInstance *s, const char *fmt, ...) {
    char text[CLEATFMU_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (s->log_errors && s->log) s->log(s, CI_ERROR, "logStatusError", text);
    return CI_ERROR;
}

void ci_warn(CleatfmuInstance *s, const char *text) {
    if (s->log_warnings && s->log) s->log(s, CI_WARNING, "logStatusWarning", text);
}

int ci_allowed(CleatfmuInstance *s, const char *function, int modes) {
    if (s == NULL) return 0;
    if (!(s->mode & modes)) {
        ci_fail(s, "%s: not allowed in this state (call sequence)", function);
        return 0;
    }
    if (s->log_calls && s->log) s->log(s, CI_OK, "logCalls", function);
    return 1;
}

int ci_set_debug_logging(CleatfmuInstance *s, int on, size_t n, const char *const categories[]) {
    size_t i;
    if (n == 0) {
        s->log_errors = s->log_calls = on ? 1 : 0;
        s->log_warnings = MODEL_MAP && on;
        return CI_OK;
    }
    if (categories == NULL) return ci_fail(s, "SetDebugLogging: NULL categories");
    for (i = 0; i < n; i++) {
        if (categories[i] && strcmp(categories[i], "logStatusError") == 0) s->log_errors = on ? 1 : 0;
        else if (categories[i] && strcmp(categories[i], "logCalls") == 0) s->log_calls = on ? 1 : 0;
        else if (MODEL_MAP && categories[i] && strcmp(categories[i], "logStatusWarning") == 0)
            s->log_warnings = on ? 1 : 0;
        else return ci_fail(s, "SetDebugLogging: unknown log category %s", categories[i] ? categories[i] : "NULL");
    }
    return CI_OK;
}

int ci_check_parameters(CleatfmuInstance *s) {
    char msg[CLEATFMU_MESSAGE_SIZE];
    if (s->unchecked) {
        if (cleatfmu_set_problem(s->values, msg, sizeof msg)) return ci_fail(s, "parameters rejected: %s", msg);
        s->unchecked = 0;
    }
    return CI_OK;
}

static int update(CleatfmuInstance *s) {
    char msg[CLEATFMU_MESSAGE_SIZE];
    int rc;
    if (!s->stale) return CI_OK;
    if (ci_check_parameters(s) != CI_OK) return CI_ERROR;
    rc = cleatfmu_evaluate(s->values, s->time, s->data, msg, sizeof msg);
    if (rc == 1) return ci_fail(s, "%s", msg);
    s->stale = 0;
    if (rc == 2) ci_warn(s, msg);
    return CI_OK;
}

int ci_reset(CleatfmuInstance *s) {
    memcpy(s->values, s->start, sizeof s->values);
    s->mode = CI_INSTANTIATED;
    s->time = 0.0;
    s->stale = 1;
    s->unchecked = 0;
    return CI_OK;
}

static const char *type_name(CleatfmuVarType type) { return type == VT_REAL ? "Real (Float64)" : "Boolean"; }

int ci_get(CleatfmuInstance *s, const char *function, CleatfmuVarType type, const unsigned int *vr, size_t nvr,
           double *reals, void *flags, void (*put_flag)(void *flags, size_t i, int value)) {
    size_t i;
    if (!ci_allowed(s, function, CI_READABLE)) return CI_ERROR;
    if (nvr > 0 && (vr == NULL || (type == VT_REAL ? (void *)reals : flags) == NULL))
        return ci_fail(s, "%s: NULL array", function);
    for (i = 0; i < nvr; i++)
        if (!(type == VT_REAL && vr[i] == CI_VR_TIME)
            && (vr[i] >= N_VARIABLES || cleatfmu_variables[vr[i]].type != type))
            return ci_fail(s, "%s: value reference %u is not a %s variable", function, vr[i], type_name(type));
    if (nvr > 0 && update(s) != CI_OK) return CI_ERROR;
    for (i = 0; i < nvr; i++) {
        if (type == VT_REAL) reals[i] = vr[i] == CI_VR_TIME ? s->time : s->values[vr[i]];
        else put_flag(flags, i, s->values[vr[i]] != 0.0);
    }
    return CI_OK;
}

int ci_set(CleatfmuInstance *s, const char *function, CleatfmuVarType type, const unsigned int *vr, size_t nvr,
           const double *reals, const void *flags, int (*get_flag)(const void *flags, size_t i)) {
    char msg[CLEATFMU_MESSAGE_SIZE];
    size_t i;
    int parameters = 0;
    if (!ci_allowed(s, function, CI_SETTABLE)) return CI_ERROR;
    if (nvr > 0 && (vr == NULL || (type == VT_REAL ? (const void *)reals : flags) == NULL))
        return ci_fail(s, "%s: NULL array", function);
    for (i = 0; i < nvr; i++) {
        double value;
        if (vr[i] >= N_VARIABLES || cleatfmu_variables[vr[i]].type != type
            || cleatfmu_variables[vr[i]].causality == VC_OUTPUT)
            return ci_fail(s, "%s: value reference %u is not a %s input or parameter", function, vr[i],
                           type_name(type));
        if (MODEL_FIXED_PARAMETERS && cleatfmu_variables[vr[i]].causality == VC_PARAMETER
            && !(s->mode & (CI_INSTANTIATED | CI_INITIALIZATION)))
            return ci_fail(s, "%s: %s is a fixed parameter, settable only before initialization ends", function,
                           cleatfmu_variables[vr[i]].name);
        if (type == VT_BOOLEAN && get_flag(flags, i) < 0)
            return ci_fail(s, "%s: %s: must be a Boolean: rejected", function, cleatfmu_variables[vr[i]].name);
        value = type == VT_REAL ? reals[i] : (double)get_flag(flags, i);
        if (cleatfmu_value_problem(vr[i], value, msg, sizeof msg))
            return ci_fail(s, "%s: %s: rejected", function, msg);
        if (cleatfmu_variables[vr[i]].causality == VC_PARAMETER) parameters = 1;
    }
    for (i = 0; i < nvr; i++) s->values[vr[i]] = type == VT_REAL ? reals[i] : (double)get_flag(flags, i);
    if (nvr > 0) s->stale = 1;
    if (parameters) s->unchecked = 1;
    return CI_OK;
}

int ci_do_step(CleatfmuInstance *s, const char *function, double current, double step) {
    if (!ci_allowed(s, function, CI_STEP)) return CI_ERROR;
    if (!(step >= 0.0) || !isfinite(current) || !isfinite(step) || !isfinite(current + step))
        return ci_fail(s, "%s: invalid communication point %.17g or step size %.17g (the step must end at a "
                          "finite time)", function, current, step);
    if (ci_check_parameters(s) != CI_OK) return CI_ERROR;
    if (N_STATES > 0) {
        char msg[CLEATFMU_MESSAGE_SIZE];
        if (cleatfmu_step(s->values, current, step, msg, sizeof msg)) return ci_fail(s, "%s: %s", function, msg);
    }
    s->time = current + step;
    s->stale = 1;                  /* outputs may follow the state or the clock */
    return CI_OK;
}

/* ---------------------------------------------------------------- FMU state */

static void kind_bytes(char kind[KIND_BYTES]) {
    memset(kind, 0, KIND_BYTES);
    strncpy(kind, MODEL_KIND, KIND_BYTES - 1);
}

static int is_snapshot(const void *state) {
    char kind[KIND_BYTES];
    const Snapshot *snap = (const Snapshot *)state;
    if (state == NULL || memcmp(snap->magic, STATE_MAGIC, 8) != 0) return 0;
    kind_bytes(kind);
    return memcmp(snap->kind, kind, KIND_BYTES) == 0 && snap->n_values == N_VALUES;
}

static void stamp(Snapshot *snap) {
    memcpy(snap->magic, STATE_MAGIC, 8);
    kind_bytes(snap->kind);
    snap->n_values = N_VALUES;
}

static unsigned long long fnv1a(const unsigned char *data, size_t n) {
    unsigned long long h = 1469598103934665603ULL;
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= data[i];
        h *= 1099511628211ULL;
    }
    return h;
}

int ci_get_state(CleatfmuInstance *s, const char *function, void **state) {
    Snapshot *snap;
    if (!ci_allowed(s, function, CI_ANY_MODE)) return CI_ERROR;
    if (state == NULL) return ci_fail(s, "%s: NULL pointer", function);
    if (*state != NULL && !is_snapshot(*state)) return ci_fail(s, "%s: not an FMU state of this FMU", function);
    snap = *state ? (Snapshot *)*state : new_snapshot(s);
    if (snap == NULL) return ci_fail(s, "%s: out of memory", function);
    stamp(snap);
    snap->time = s->time;
    snap->unchecked = s->unchecked;
    memcpy(snap->values, s->values, sizeof s->values);
    *state = snap;
    return CI_OK;
}

int ci_set_state(CleatfmuInstance *s, const char *function, const void *state) {
    const Snapshot *snap = (const Snapshot *)state;
    if (!ci_allowed(s, function, CI_ANY_MODE)) return CI_ERROR;
    if (!is_snapshot(state)) return ci_fail(s, "%s: not an FMU state of this FMU", function);
    memcpy(s->values, snap->values, sizeof s->values);
    s->time = snap->time;
    s->unchecked = snap->unchecked;
    s->stale = 1;
    return CI_OK;
}

int ci_free_state(CleatfmuInstance *s, const char *function, void **state) {
    if (!ci_allowed(s, function, CI_ANY_MODE)) return CI_ERROR;
    if (state && *state) {
        if (!is_snapshot(*state)) return ci_fail(s, "%s: not an FMU state of this FMU", function);
        delete_snapshot((Snapshot *)*state);
        *state = NULL;
    }
    return CI_OK;
}

size_t ci_serialized_size(void) { return SERIALIZED_SIZE; }

int ci_serialize(CleatfmuInstance *s, const char *function, const void *state, unsigned char *buffer, size_t size) {
    const Snapshot *snap = (const Snapshot *)state;
    char kind[KIND_BYTES];
    unsigned long header;
    unsigned long long sum;
    int i;
    if (!ci_allowed(s, function, CI_ANY_MODE)) return CI_ERROR;
    if (!is_snapshot(state)) return ci_fail(s, "%s: not an FMU state of this FMU", function);
    if (buffer == NULL || size < SERIALIZED_SIZE)
        return ci_fail(s, "%s: buffer of %u bytes, %u needed", function, (unsigned)size, (unsigned)SERIALIZED_SIZE);
    kind_bytes(kind);
    memcpy(buffer, STATE_MAGIC, 8);
    memcpy(buffer + 8, kind, KIND_BYTES);
    header = (unsigned long)N_VALUES | (snap->unchecked ? 0x10000UL : 0UL) | (STATE_VERSION << 24);
    for (i = 0; i < 4; i++) buffer[8 + KIND_BYTES + i] = (unsigned char)((header >> (8 * i)) & 0xffUL);
    memcpy(buffer + 12 + KIND_BYTES, &snap->time, 8);
    memcpy(buffer + 20 + KIND_BYTES, snap->values, 8 * N_VALUES);
    sum = fnv1a(buffer, PAYLOAD_SIZE);
    for (i = 0; i < 8; i++) buffer[PAYLOAD_SIZE + i] = (unsigned char)((sum >> (8 * i)) & 0xffULL);
    return CI_OK;
}

int ci_deserialize(CleatfmuInstance *s, const char *function, const unsigned char *buffer, size_t size,
                   void **state) {
    char kind[KIND_BYTES], msg[CLEATFMU_MESSAGE_SIZE];
    unsigned long header = 0;
    Snapshot *snap, tmp;
    unsigned long long sum = 0;
    size_t vr;
    int i;
    if (!ci_allowed(s, function, CI_ANY_MODE)) return CI_ERROR;
    kind_bytes(kind);
    if (buffer != NULL && size == SERIALIZED_SIZE) {
        for (i = 3; i >= 0; i--) header = (header << 8) | buffer[8 + KIND_BYTES + i];
        for (i = 7; i >= 0; i--) sum = (sum << 8) | buffer[PAYLOAD_SIZE + i];
    }
    if (buffer == NULL || state == NULL || size != SERIALIZED_SIZE || memcmp(buffer, STATE_MAGIC, 8) != 0
        || memcmp(buffer + 8, kind, KIND_BYTES) != 0 || (header & 0xffffUL) != N_VALUES || ((header >> 17) & 0x7fUL) != 0
        || (header >> 24) != STATE_VERSION)
        return ci_fail(s, "%s: not a serialized state of FMU kind %s", function, MODEL_KIND);
    if (sum != fnv1a(buffer, PAYLOAD_SIZE))
        return ci_fail(s, "%s: the serialized state is corrupted (its checksum does not match)", function);
    if (*state != NULL && !is_snapshot(*state)) return ci_fail(s, "%s: not an FMU state of this FMU", function);
    stamp(&tmp);
    tmp.unchecked = (header & 0x10000UL) != 0;
    memcpy(&tmp.time, buffer + 12 + KIND_BYTES, 8);
    memcpy(tmp.values, buffer + 20 + KIND_BYTES, 8 * N_VALUES);
    for (vr = 0; vr < N_VARIABLES; vr++)
        if (cleatfmu_variables[vr].causality != VC_OUTPUT && cleatfmu_value_problem(vr, tmp.values[vr], msg, sizeof msg))
            return ci_fail(s, "%s: %s", function, msg);
    snap = *state ? (Snapshot *)*state : new_snapshot(s);
    if (snap == NULL) return ci_fail(s, "%s: out of memory", function);
    stamp(snap);
    snap->time = tmp.time;
    snap->unchecked = tmp.unchecked;
    memcpy(snap->values, tmp.values, sizeof tmp.values);
    *state = snap;
    return CI_OK;
}
