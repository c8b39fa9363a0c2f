/*
 * text.h — text meant to be read back: well-formed UTF-8 (RFC 3629) for the JSON files the command line
 * writes and the settings text a cache file keeps, and floats as the shortest decimal that reads back
 * as the same float.
 */
#ifndef IC_CORE_TEXT_H
#define IC_CORE_TEXT_H

#include <stddef.h>

/* Length of the well-formed UTF-8 sequence at s (no overlong forms, no surrogates, at most U+10FFFF), or 0
 * if s does not start one within its `left` bytes (left ≥ 1). A NUL-terminated string may pass SIZE_MAX:
 * a sequence cut by the NUL fails on it, and nothing past it is read. */
size_t ic_utf8_sequence(const unsigned char *s, size_t left);

/* The shortest decimal of x (6 to 9 significant digits, %g) that reads back as the same float: 0.8 reads
 * "0.8", not the 0.800000012 its float is; returns buf. */
const char *ic_float_text(float x, char buf[32]);

#endif
