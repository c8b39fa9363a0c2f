/* text.c — text meant to be read back (text.h). */
#include "text.h"

#include <stdio.h>
#include <stdlib.h>

size_t ic_utf8_sequence(const unsigned char *s, size_t left)
{
    unsigned char c = s[0];
    if (c < 0x80)
        return 1;
    unsigned char lo = 0x80, hi = 0xBF;
    size_t n;
    if (c >= 0xC2 && c <= 0xDF) {
        n = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
        n = 3;
        lo = c == 0xE0 ? 0xA0 : 0x80;
        hi = c == 0xED ? 0x9F : 0xBF;
    } else if (c >= 0xF0 && c <= 0xF4) {
        n = 4;
        lo = c == 0xF0 ? 0x90 : 0x80;
        hi = c == 0xF4 ? 0x8F : 0xBF;
    } else {
        return 0;
    }
    if (n > left || s[1] < lo || s[1] > hi)
        return 0;
    for (size_t i = 2; i < n; ++i)
        if (s[i] < 0x80 || s[i] > 0xBF)
            return 0;
    return n;
}

const char *ic_float_text(float x, char buf[32])
{
    for (int digits = 6; digits <= 9; ++digits) {
        snprintf(buf, 32, "%.*g", digits, (double)x);
        if (strtof(buf, NULL) == x)
            break;
    }
    return buf;
}

void ic_text_one_line(char *text, size_t size)
{
    size_t n = 0;
    while (n < size && text[n] != '\0' && !((unsigned char)text[n] < 0x20 || text[n] == 0x7f))
        ++n;
    if (n == size || text[n] == '\0')
        return;
    char out[IC_TEXT_ONE_LINE_MAX];
    const size_t room = size < sizeof out ? size : sizeof out;
    size_t o = 0;
    for (size_t i = 0; i < size && text[i] != '\0' && o + 1 < room; ++i) {
        unsigned char c = (unsigned char)text[i];
        if (c < 0x20 || c == 0x7f) {
            if (o + 5 >= room)
                break;
            o += (size_t)snprintf(out + o, room - o, "\\x%02x", c);
        } else {
            out[o++] = (char)c;
        }
    }
    out[o] = '\0';
    snprintf(text, size, "%s", out);
}
