/*
 * irrcache/common.h — types shared by every public irrcache header.
 *
 * Result codes, the error record that carries a one-line, user-facing message (what failed, where:
 * file:line, and what to do), a plain float 3-vector, and the progress callback. The library never
 * prints and never exits: fallible calls return an ic_result and, when given a non-NULL ic_error,
 * fill it with a message the caller may show.
 */
#ifndef IRRCACHE_COMMON_H
#define IRRCACHE_COMMON_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Result of every fallible call. */
typedef enum ic_result {
    IC_OK = 0,             /* success */
    IC_ERR_INVALID_ARG,    /* an argument or option is out of range or inconsistent */
    IC_ERR_IO,             /* a file could not be opened, read or written */
    IC_ERR_PARSE,          /* a file is malformed (scene, mesh, image, cache) */
    IC_ERR_OOM,            /* an allocation failed */
    IC_ERR_UNSUPPORTED,    /* a valid request this build cannot serve */
    IC_ERR_MISMATCH,       /* a cache file was made for other parameters or another scene */
    IC_ERR_CORRUPT,        /* a file failed its checksum or is truncated */
    IC_ERR_INTERNAL        /* a broken invariant: a bug */
} ic_result;

/* Error details: the code and a one-line message (no trailing newline). */
typedef struct ic_error {
    ic_result code;        /* same as the returned result */
    char message[1024];    /* "file:line: what went wrong; what to do" */
} ic_error;

/* Name of a result code ("IC_ERR_IO" …), never NULL. */
const char *ic_result_name(ic_result r);

/* Fills err (if non-NULL) with code and a printf-style message; returns code. */
ic_result ic_error_set(ic_error *err, ic_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Plain 3-vector of floats (positions, normals, RGB). */
typedef struct ic_vec3 {
    float x, y, z;
} ic_vec3;

/* Progress report: phase name, fraction done in [0,1]. Called from one thread at a time. */
typedef void (*ic_progress_fn)(void *user, const char *phase, double fraction);

/* Removes every temporary file the library is writing at this moment (outputs are written under a
 * temporary name and renamed into place). Async-signal-safe: meant for a program's handler of SIGINT,
 * SIGTERM or SIGXFSZ, which then re-raises the signal with its default action. The library itself never
 * installs a signal handler. */
void ic_remove_temporary_files(void);

#ifdef __cplusplus
}
#endif
#endif
