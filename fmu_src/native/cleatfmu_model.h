/* The model of a cleatfmu tire FMU, independent of the FMI version.
 *
 * Every variable's value is a double in values[value reference] (a Boolean is
 * 0.0 or 1.0); a kind with a state (the body) keeps it hidden in N_STATES more
 * doubles after the variables.  The kind's config.h defines MODEL_IDENTIFIER,
 * MODEL_KIND, N_VARIABLES, the VR_* value references and the variable table
 * (and optionally MODEL_BODY, MODEL_ROAD, MODEL_MAP, N_STATES, MODEL_FIXED_PARAMETERS).
 */
#ifndef CLEATFMU_MODEL_H
#define CLEATFMU_MODEL_H

#include "cleatfmu_names.h"

#include <stddef.h>

typedef enum { VT_REAL, VT_BOOLEAN } CleatfmuVarType;
typedef enum { VC_INPUT, VC_PARAMETER, VC_OUTPUT } CleatfmuVarCausality;
/* What a settable value must satisfy by itself. */
typedef enum { RULE_NONE, RULE_FINITE, RULE_POSITIVE, RULE_NONNEGATIVE, RULE_BOOLEAN } CleatfmuVarRule;

typedef struct {
    const char *name;
    CleatfmuVarType type;
    CleatfmuVarCausality causality;
    CleatfmuVarRule rule;
    const char *unit;
} CleatfmuVariable;

#include "config.h"

#ifndef MODEL_BODY
#define MODEL_BODY 0
#endif
#ifndef MODEL_ROAD
#define MODEL_ROAD 0
#endif
#ifndef MODEL_MAP
#define MODEL_MAP 0
#endif
#ifndef N_STATES
#define N_STATES 0
#endif
#ifndef MODEL_FIXED_PARAMETERS
#define MODEL_FIXED_PARAMETERS 0
#endif
/* Number of doubles of an instance's values: the variables, then the hidden state. */
#define N_VALUES (N_VARIABLES + N_STATES)

#define CLEATFMU_STR_(x) #x
#define CLEATFMU_STR(x) CLEATFMU_STR_(x)
#define MODEL_IDENTIFIER_STRING CLEATFMU_STR(MODEL_IDENTIFIER)
#define CLEATFMU_MESSAGE_SIZE 512

extern const CleatfmuVariable cleatfmu_variables[N_VARIABLES];

/* Why `value` cannot be stored in variable `vr` by itself (message into msg), or 0. */
int cleatfmu_value_problem(size_t vr, double value, char *msg, size_t n);
/* Why a complete set of values is invalid together (message into msg), or 0. */
int cleatfmu_set_problem(const double *values, char *msg, size_t n);
/* Load the kind's data from the FMU's resources (the road's profile, the tire map) into *data (NULL for a kind
 * without);
 * returns 0, or 1 with the reason in msg. */
int cleatfmu_load(const char *resource_location, void **data, char *msg, size_t n);
/* Free what cleatfmu_load allocated. */
void cleatfmu_unload(void *data);
/* Compute the outputs into values at `time` (with the kind's data): 0; 1 (message into msg) when an
 * output is not finite; 2 with a warning in msg, the outputs valid (the tire map: a speed that has just
 * left the tested range). */
int cleatfmu_evaluate(double *values, double time, const void *data, char *msg, size_t n);
/* Advance the hidden state over the step [time, time + step] (nothing for a stateless kind);
 * nonzero (message into msg) when the state becomes non-finite. */
int cleatfmu_step(double *values, double time, double step, char *msg, size_t n);
/* Value reference of the variable called `name`, or -1. */
int cleatfmu_find_variable(const char *name);

#endif
