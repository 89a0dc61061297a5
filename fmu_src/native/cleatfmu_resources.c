/* Resource locations and the start-value file (see cleatfmu_resources.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cleatfmu_model.h"
#include "cleatfmu_resources.h"

#ifdef _WIN32
#include <windows.h>
#endif

#define MAX_PATH_BYTES 4096
#define MAX_START_FILE 65536

static int lower(int c) { return (c >= 'A' && c <= 'Z') ? c - 'A' + 'a' : c; }

static int prefix_nocase(const char *s, const char *prefix) {
    while (*prefix)
        if (lower((unsigned char)*s++) != *prefix++) return 0;
    return 1;
}

static int hex_digit(int c) {
    if (c >= '0' && c <= '9') return c - '0';
    c = lower(c);
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
}

int cleatfmu_uri_to_path(const char *uri, char *path, size_t path_size, char *msg, size_t msg_size) {
    const char *p = uri;
    size_t len = 0;
    if (uri == NULL || *uri == '\0') {
        snprintf(msg, msg_size, "no resource location given");
        return 1;
    }
    if (prefix_nocase(p, "file:")) {
        p += 5;
        if (p[0] == '/' && p[1] == '/') { /* authority */
            const char *host = p + 2, *end = strchr(host, '/');
            size_t host_len = end ? (size_t)(end - host) : strlen(host);
            if (host_len == 9 && prefix_nocase(host, "localhost")) {
                p = host + 9;
            } else if (host_len > 0) {
#ifdef _WIN32
                if (path_size < 3) goto too_long;
                path[len++] = '/'; /* UNC: //host/share/... */
                path[len++] = '/';
                p = host;
#else
                snprintf(msg, msg_size, "resource location %.200s: host %.*s is not this machine", uri,
                         (int)(host_len < 100 ? host_len : 100), host);
                return 1;
#endif
            } else {
                p = host;
            }
        }
        if (*p != '/' && len == 0) {
            snprintf(msg, msg_size, "resource location %.200s: not an absolute file URI", uri);
            return 1;
        }
        for (; *p; p++) {
            int c = (unsigned char)*p;
            if (c == '%') { /* a '%' not followed by two hex digits is kept (importers that do not encode) */
                int hi = hex_digit((unsigned char)p[1]), lo = hi < 0 ? -1 : hex_digit((unsigned char)p[2]);
                if (hi == 0 && lo == 0) {
                    snprintf(msg, msg_size, "resource location %.200s: %%00 in the path", uri);
                    return 1;
                }
                if (hi >= 0 && lo >= 0) {
                    c = hi * 16 + lo;
                    p += 2;
                }
            }
            if (len + 1 >= path_size) goto too_long;
            path[len++] = (char)c;
        }
        path[len] = '\0';
#ifdef _WIN32
        /* /C:/dir -> C:/dir */
        if (len >= 3 && path[0] == '/' && path[2] == ':' && path[1] != '/') {
            memmove(path, path + 1, len);
            len--;
        }
#endif
    } else {
        len = strlen(uri);
        if (len + 1 >= path_size) goto too_long;
        memcpy(path, uri, len + 1);
    }
    while (len > 1 && (path[len - 1] == '/' || path[len - 1] == '\\')) path[--len] = '\0';
    return 0;
too_long:
    snprintf(msg, msg_size, "resource location %.200s: path too long", uri);
    return 1;
}

static FILE *open_utf8(const char *path) {
#ifdef _WIN32
    wchar_t wide[MAX_PATH_BYTES];
    if (MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, path, -1, wide, MAX_PATH_BYTES) == 0) return NULL;
    return _wfopen(wide, L"rb");
#else
    return fopen(path, "rb");
#endif
}

int cleatfmu_parse_bits(const char *s, double *value, const char **end) {
    unsigned long long bits = 0;
    int i, d;
    for (i = 0; i < 16; i++) {
        d = hex_digit((unsigned char)s[i]);
        if (d < 0) return 1;
        bits = (bits << 4) | (unsigned long long)d;
    }
    if (s[16] != '\0' && s[16] != ' ') return 1;
    if (end != NULL) *end = s + 16;
    memcpy(value, &bits, sizeof *value);
    return 0;
}

/* A double from exactly the 16 hexadecimal digits of its IEEE 754 bits (locale-independent, exact). */
static int parse_bits(const char *s, double *value) {
    const char *end;
    return cleatfmu_parse_bits(s, value, &end) || *end != '\0';
}

char *cleatfmu_next_line(char *buf, size_t size, size_t *pos) {
    char *line;
    if (*pos >= size) return NULL;
    line = buf + *pos;
    while (*pos < size && buf[*pos] != '\n') (*pos)++;
    if (*pos < size) buf[(*pos)++] = '\0';
    if (line[0] != '\0' && line[strlen(line) - 1] == '\r') line[strlen(line) - 1] = '\0';
    return line;
}

int cleatfmu_read_resource(const char *resource_location, const char *name, size_t max_bytes, char **buf,
                           size_t *size, char *msg, size_t msg_size) {
    char path[MAX_PATH_BYTES];
    size_t n, len = strlen(name);
    FILE *f;
    *buf = NULL;
    if (len + 2 >= sizeof path
        || cleatfmu_uri_to_path(resource_location, path, sizeof path - len - 2, msg, msg_size))
        return 1;
    n = strlen(path);
    path[n] = '/';
    memcpy(path + n + 1, name, len + 1);
    f = open_utf8(path);
    if (f == NULL) {
        snprintf(msg, msg_size, "cannot open %.300s (resource location %.300s)", path, resource_location);
        return 1;
    }
    *buf = (char *)malloc(max_bytes + 1);
    if (*buf == NULL) {
        fclose(f);
        snprintf(msg, msg_size, "out of memory");
        return 1;
    }
    *size = fread(*buf, 1, max_bytes + 1, f);
    fclose(f);
    if (*size > max_bytes) {
        free(*buf);
        *buf = NULL;
        snprintf(msg, msg_size, "%s: larger than %lu bytes", name, (unsigned long)max_bytes);
        return 1;
    }
    (*buf)[*size] = '\0';
    return 0;
}

int cleatfmu_read_start_file(const char *resource_location, char guid[CLEATFMU_GUID_SIZE], double *values,
                             char *msg, size_t msg_size) {
    char *buf, *line;
    size_t size, pos = 0;
    int seen[N_VARIABLES] = {0}, vr, status = 1;
    guid[0] = '\0';
    if (cleatfmu_read_resource(resource_location, CLEATFMU_START_FILE, MAX_START_FILE, &buf, &size, msg, msg_size))
        return 1;
    line = cleatfmu_next_line(buf, size, &pos);
    if (line == NULL || strcmp(line, "cleatfmu-start 1 " MODEL_KIND) != 0) {
        snprintf(msg, msg_size, "%s: not a start-value file of FMU kind %s", CLEATFMU_START_FILE, MODEL_KIND);
        goto done;
    }
    while ((line = cleatfmu_next_line(buf, size, &pos)) != NULL) {
        char *space = strchr(line, ' ');
        double value;
        if (line[0] == '\0' || line[0] == '#') continue;
        if (space == NULL) {
            snprintf(msg, msg_size, "%s: malformed line %.100s", CLEATFMU_START_FILE, line);
            goto done;
        }
        *space = '\0';
        if (strcmp(line, "guid") == 0) {
            if (strlen(space + 1) >= CLEATFMU_GUID_SIZE) {
                snprintf(msg, msg_size, "%s: GUID too long", CLEATFMU_START_FILE);
                goto done;
            }
            strcpy(guid, space + 1);
            continue;
        }
        vr = cleatfmu_find_variable(line);
        if (vr < 0 || cleatfmu_variables[vr].causality == VC_OUTPUT || parse_bits(space + 1, &value)) {
            snprintf(msg, msg_size, "%s: %.100s is not an input or parameter with a number", CLEATFMU_START_FILE,
                     line);
            goto done;
        }
        values[vr] = value;
        seen[vr] = 1;
    }
    for (vr = 0; vr < N_VARIABLES; vr++) {
        if (cleatfmu_variables[vr].causality != VC_OUTPUT && !seen[vr]) {
            snprintf(msg, msg_size, "%s: no start value of %s", CLEATFMU_START_FILE, cleatfmu_variables[vr].name);
            goto done;
        }
    }
    if (guid[0] == '\0') {
        snprintf(msg, msg_size, "%s: no GUID", CLEATFMU_START_FILE);
        goto done;
    }
    status = 0;
done:
    free(buf);
    return status;
}
