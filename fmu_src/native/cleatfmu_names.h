/* Every function and table these sources share between their files, named after the FMU kind
 * (MODEL_IDENTIFIER of config.h): CleatfmuPointContact_ci_do_step, ...  Two kinds compiled from their
 * sources/ then link into one program side by side (with FMI2_FUNCTION_PREFIX / FMI3_FUNCTION_PREFIX set
 * per kind for the FMI functions), where the same names would clash or, from archives, silently resolve
 * to the first kind's.  Included first by every header of these sources. */
#ifndef CLEATFMU_NAMES_H
#define CLEATFMU_NAMES_H

#include "config.h"

#define CLEATFMU_PASTE_(a, b) a##_##b
#define CLEATFMU_PASTE(a, b) CLEATFMU_PASTE_(a, b)
#define CLEATFMU_NAME(name) CLEATFMU_PASTE(MODEL_IDENTIFIER, name)

#define ci_allowed CLEATFMU_NAME(ci_allowed)
#define ci_check_parameters CLEATFMU_NAME(ci_check_parameters)
#define ci_deserialize CLEATFMU_NAME(ci_deserialize)
#define ci_do_step CLEATFMU_NAME(ci_do_step)
#define ci_fail CLEATFMU_NAME(ci_fail)
#define ci_warn CLEATFMU_NAME(ci_warn)
#define ci_free CLEATFMU_NAME(ci_free)
#define ci_free_state CLEATFMU_NAME(ci_free_state)
#define ci_get CLEATFMU_NAME(ci_get)
#define ci_get_state CLEATFMU_NAME(ci_get_state)
#define ci_load CLEATFMU_NAME(ci_load)
#define ci_reset CLEATFMU_NAME(ci_reset)
#define ci_serialize CLEATFMU_NAME(ci_serialize)
#define ci_serialized_size CLEATFMU_NAME(ci_serialized_size)
#define ci_set CLEATFMU_NAME(ci_set)
#define ci_set_debug_logging CLEATFMU_NAME(ci_set_debug_logging)
#define ci_set_state CLEATFMU_NAME(ci_set_state)
#define cleatfmu_evaluate CLEATFMU_NAME(cleatfmu_evaluate)
#define cleatfmu_extended_tire CLEATFMU_NAME(cleatfmu_extended_tire)
#define cleatfmu_find_variable CLEATFMU_NAME(cleatfmu_find_variable)
#define cleatfmu_load CLEATFMU_NAME(cleatfmu_load)
#define cleatfmu_map_free CLEATFMU_NAME(cleatfmu_map_free)
#define cleatfmu_map_load CLEATFMU_NAME(cleatfmu_map_load)
#define cleatfmu_map_outputs CLEATFMU_NAME(cleatfmu_map_outputs)
#define cleatfmu_next_line CLEATFMU_NAME(cleatfmu_next_line)
#define cleatfmu_parse_bits CLEATFMU_NAME(cleatfmu_parse_bits)
#define cleatfmu_point_contact CLEATFMU_NAME(cleatfmu_point_contact)
#define cleatfmu_read_resource CLEATFMU_NAME(cleatfmu_read_resource)
#define cleatfmu_read_start_file CLEATFMU_NAME(cleatfmu_read_start_file)
#define cleatfmu_set_problem CLEATFMU_NAME(cleatfmu_set_problem)
#define cleatfmu_step CLEATFMU_NAME(cleatfmu_step)
#define cleatfmu_unload CLEATFMU_NAME(cleatfmu_unload)
#define cleatfmu_uri_to_path CLEATFMU_NAME(cleatfmu_uri_to_path)
#define cleatfmu_value_problem CLEATFMU_NAME(cleatfmu_value_problem)
#define cleatfmu_variables CLEATFMU_NAME(cleatfmu_variables)

#endif
