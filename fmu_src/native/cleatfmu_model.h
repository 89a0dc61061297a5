/* The model of a cleatfmu tire FMU, independent of the FMI version.
 *
 * Every variable's value is a double in values[value reference] (a Boolean is
 * 0.0 or 1.0).  The kind's config.h defines MODEL_IDENTIFIER, MODEL_KIND,
 * N_VARIABLES, the VR_* value references and the variable table.
 */
#ifndef CLEATFMU_MODEL_H
#define CLEATFMU_MODEL_H

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

#define CLEATFMU_STR_(x) #x
#define CLEATFMU_STR(x) CLEATFMU_STR_(x)
#define MODEL_IDENTIFIER_STRING CLEATFMU_STR(MODEL_IDENTIFIER)
#define CLEATFMU_MESSAGE_SIZE 512

extern const CleatfmuVariable cleatfmu_variables[N_VARIABLES];

/* Why `value` cannot be stored in variable `vr` by itself (message into msg), or 0. */
int cleatfmu_value_problem(size_t vr, double value, char *msg, size_t n);
/* Why a complete set of values is invalid together (message into msg), or 0. */
int cleatfmu_set_problem(const double *values, char *msg, size_t n);
/* Compute the outputs into values; nonzero (message into msg) when an output is not finite. */
int cleatfmu_evaluate(double *values, char *msg, size_t n);
/* Value reference of the variable called `name`, or -1. */
int cleatfmu_find_variable(const char *name);

#endif
