/* error.c — result names and the one-line error record (include/irrcache/common.h, core/error_at.h). */
#include "irrcache/common.h"
#include "core/error_at.h"
#include "core/text.h"

#include <stdarg.h>
#include <stdio.h>

const char *ic_result_name(ic_result r)
{
    switch (r) {
    case IC_OK: return "IC_OK";
    case IC_ERR_INVALID_ARG: return "IC_ERR_INVALID_ARG";
    case IC_ERR_IO: return "IC_ERR_IO";
    case IC_ERR_PARSE: return "IC_ERR_PARSE";
    case IC_ERR_OOM: return "IC_ERR_OOM";
    case IC_ERR_UNSUPPORTED: return "IC_ERR_UNSUPPORTED";
    case IC_ERR_MISMATCH: return "IC_ERR_MISMATCH";
    case IC_ERR_CORRUPT: return "IC_ERR_CORRUPT";
    case IC_ERR_INTERNAL: return "IC_ERR_INTERNAL";
    }
    return "IC_ERR_UNKNOWN";
}

ic_result ic_error_set(ic_error *err, ic_result code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
        ic_text_one_line(err->message, sizeof err->message);
        err->code = code;
    }
    return code;
}

ic_result ic_error_vset_at(ic_error *err, ic_result code, const char *path, int line, const char *fmt, va_list ap)
{
    if (err) {
        int n = snprintf(err->message, sizeof err->message, "%s:%d: ", path ? path : "?", line);
        if (n >= 0 && (size_t)n < sizeof err->message)
            vsnprintf(err->message + n, sizeof err->message - (size_t)n, fmt, ap);
        ic_text_one_line(err->message, sizeof err->message);
        err->code = code;
    }
    return code;
}

ic_result ic_error_set_at(ic_error *err, ic_result code, const char *path, int line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ic_result r = ic_error_vset_at(err, code, path, line, fmt, ap);
    va_end(ap);
    return r;
}
