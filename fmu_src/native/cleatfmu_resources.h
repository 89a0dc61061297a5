/* Resource locations (RFC 3986 file URIs) and the start-value file of a cleatfmu FMU. */
#ifndef CLEATFMU_RESOURCES_H
#define CLEATFMU_RESOURCES_H

#include <stddef.h>

/* Name of the start-value file in the FMU's resources folder. */
#define CLEATFMU_START_FILE "cleatfmu_start.txt"
#define CLEATFMU_GUID_SIZE 64

/* Decode a resource location into a local path without trailing separator:
 * file:///path, file:/path, file://localhost/path (and file://host/share as a
 * UNC path on Windows), percent-encoded UTF-8 (a '%' without two hex digits
 * is kept as it is); a location without scheme is taken as a path.  Returns 0, or 1 with the reason in msg. */
int cleatfmu_uri_to_path(const char *uri, char *path, size_t path_size, char *msg, size_t msg_size);

/* Read <resource location>/cleatfmu_start.txt: the FMU's GUID and the start value of
 * every input and parameter into values (value-reference order); returns 0, or 1 with
 * the reason in msg. */
int cleatfmu_read_start_file(const char *resource_location, char guid[CLEATFMU_GUID_SIZE], double *values,
                             char *msg, size_t msg_size);

#endif
