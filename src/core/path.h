/*
 * path.h — the folder part of a file path, for the writers (core), the scene loaders and the command line.
 */
#ifndef IC_CORE_PATH_H
#define IC_CORE_PATH_H

#include <stddef.h>

/* The folder of path: its text before the last '/', "/" for a file at the root, "." for a bare name. */
void ic_path_dirname(const char *path, char *dir, size_t size);

#endif
