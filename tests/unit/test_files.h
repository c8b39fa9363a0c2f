/*
 * test_files.h — file-system helpers shared by the command-line tests.
 */
#ifndef IC_TEST_FILES_H
#define IC_TEST_FILES_H

#include <dirent.h>
#include <stdio.h>
#include <string.h>

/* Reads up to size − 1 bytes of path into buf, terminated ("" when it cannot be read); returns the count. */
static inline size_t test_read_text(const char *path, char *buf, size_t size)
{
    FILE *f = fopen(path, "rb");
    size_t n = f ? fread(buf, 1, size - 1, f) : 0;
    buf[n] = 0;
    if (f)
        fclose(f);
    return n;
}

/* Files under dir whose name holds ".tmp." (left-over temporaries of an atomic write). */
static inline int test_count_temporaries(const char *dir)
{
    int n = 0;
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d));)
        n += strstr(e->d_name, ".tmp.") != NULL;
    if (d)
        closedir(d);
    return n;
}

#endif
