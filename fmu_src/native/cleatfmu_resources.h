/* Resource locations (RFC 3986 file URIs) and the start-value file of a cleatfmu FMU. */
#ifndef CLEATFMU_RESOURCES_H
#define CLEATFMU_RESOURCES_H

#include "cleatfmu_names.h"

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

/* Read the file `name` of the FMU's resources folder into a NUL-terminated buffer (malloc'd, *buf) of
 * *size bytes (at most max_bytes); returns 0, or 1 with the reason in msg. */
int cleatfmu_read_resource(const char *resource_location, const char *name, size_t max_bytes, char **buf,
                           size_t *size, char *msg, size_t msg_size);
/* Next line of buf from *pos (in place, NUL-terminated, without CR), or NULL at the end. */
char *cleatfmu_next_line(char *buf, size_t size, size_t *pos);
/* A double from the 16 hexadecimal digits of its IEEE 754 bits ending at a NUL or space (*end: after them);
 * returns 0, or 1 if malformed. */
int cleatfmu_parse_bits(const char *s, double *value, const char **end);

#endif
