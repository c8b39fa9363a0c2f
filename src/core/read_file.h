/*
 * read_file.h — opening an input file only once it is known to be a regular file of bounded size.
 *
 * A FIFO would block the open or the read forever, a folder or /dev/zero would be read without end:
 * the file is opened without blocking, checked with fstat (so nothing can swap it between the check
 * and the read), and its size compared with the caller's limit before anything is allocated.
 */
#ifndef IC_CORE_READ_FILE_H
#define IC_CORE_READ_FILE_H

#include "irrcache/common.h"

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* Reads the whole of path (what: "scene file", "cache file", for messages) into a malloc'd buffer with a
 * NUL after its last byte. Refuses a path that is not a regular file ("is a folder", "is not a regular
 * file") and one larger than max_bytes (the message gives both sizes in bytes, then limit_hint: what to
 * do, e.g. the option that raises the limit). If the open
 * itself fails, *open_errno (may be NULL) receives its errno and IC_ERR_IO is returned. */
ic_result ic_read_regular_file(const char *path, const char *what, uint64_t max_bytes, const char *limit_hint,
                               char **data, size_t *size, int *open_errno, ic_error *err);

/* Opens path for reading as ic_read_regular_file does (without blocking on a FIFO; a folder, pipe, device
 * or socket refused with the same messages, what naming the file's role: "image", "mesh file") and
 * returns it as a blocking stream in *fp; IC_ERR_IO with "cannot open" if the open fails. */
ic_result ic_open_regular_file(const char *path, const char *what, FILE **fp, ic_error *err);

#endif
