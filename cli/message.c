/* message.c — the command's messages on stderr, each kept on its own line whatever it quotes. */
#include "cli.h"

#include <stdarg.h>
#include <stdlib.h>

/* Writes text[0 … n) with each control byte as \xNN, but for a newline that ends the text. */
static void put_escaped(const char *text, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        unsigned char c = (unsigned char)text[i];
        if ((c < 0x20 || c == 0x7f) && !(c == '\n' && i + 1 == n))
            fprintf(stderr, "\\x%02x", c);
        else
            fputc(c, stderr);
    }
}

void ic_cli_eprintf(const char *fmt, ...)
{
    char local[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(local, sizeof local, fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    if ((size_t)n < sizeof local) {
        put_escaped(local, (size_t)n);
        return;
    }
    char *text = malloc((size_t)n + 1);
    if (!text) {
        /* No room to format it whole: the part that fits, and the mark of a cut. */
        put_escaped(local, sizeof local - 1);
        fputs("...\n", stderr);
        return;
    }
    va_start(ap, fmt);
    vsnprintf(text, (size_t)n + 1, fmt, ap);
    va_end(ap);
    put_escaped(text, (size_t)n);
    free(text);
}
