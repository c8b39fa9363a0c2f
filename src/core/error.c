/* error.c — result names and the one-line error record (include/irrcache/common.h). */
#include "irrcache/common.h"

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
        err->code = code;
    }
    return code;
}
