/* error.c — result names and the one-line error record (include/irrcache/common.h, core/error_at.h). */
#include "irrcache/common.h"
#include "core/error_at.h"

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

/* Keeps a message on one line whatever it quotes: a control byte (a newline or a carriage return in a
 * file's name, an escape sequence) is written as \xNN, as far as the message's room allows. */
static void one_line(char *message, size_t size)
{
    size_t n = 0;
    while (n < size && message[n] != '\0' && !((unsigned char)message[n] < 0x20 || message[n] == 0x7f))
        ++n;
    if (n == size || message[n] == '\0')
        return;
    char out[sizeof ((ic_error *)0)->message];
    size_t o = 0;
    for (size_t i = 0; i < size && message[i] != '\0' && o + 1 < sizeof out; ++i) {
        unsigned char c = (unsigned char)message[i];
        if (c < 0x20 || c == 0x7f) {
            if (o + 5 >= sizeof out)
                break;
            o += (size_t)snprintf(out + o, sizeof out - o, "\\x%02x", c);
        } else {
            out[o++] = (char)c;
        }
    }
    out[o] = '\0';
    snprintf(message, size, "%s", out);
}

ic_result ic_error_set(ic_error *err, ic_result code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
        one_line(err->message, sizeof err->message);
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
        one_line(err->message, sizeof err->message);
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
