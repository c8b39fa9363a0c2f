/*
 * text.h — text meant to be read back: well-formed UTF-8 (RFC 3629) for the JSON files the command line
 * writes and the settings text a cache file keeps, floats as the shortest decimal that reads back as
 * the same float, and messages kept on one line.
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

/* Keeps a message on one line whatever it quotes: each control byte of the NUL-terminated text (a newline
 * or a carriage return in a file's name, an escape sequence) is rewritten as \xNN, in place, as far as
 * the buffer's size and IC_TEXT_ONE_LINE_MAX allow (the rest is cut). */
enum { IC_TEXT_ONE_LINE_MAX = 1024 };
void ic_text_one_line(char *text, size_t size);

#endif
