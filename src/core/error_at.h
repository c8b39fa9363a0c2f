/*
 * error_at.h — errors that name the place in an input file: "path:line: message", the form every scene
 * and mesh reader reports in (one line, so that an editor or a terminal can jump to it).
 */
#ifndef IC_CORE_ERROR_AT_H
#define IC_CORE_ERROR_AT_H

#include "irrcache/common.h"

#include <stdarg.h>

/* Fills err (if non-NULL) with code and "path:line: " followed by the printf-style message; returns code. */
ic_result ic_error_vset_at(ic_error *err, ic_result code, const char *path, int line, const char *fmt, va_list ap);
ic_result ic_error_set_at(ic_error *err, ic_result code, const char *path, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

#endif
