/*
 * test_files.h — file-system helpers shared by the command-line tests.
 */
#ifndef IC_TEST_FILES_H
#define IC_TEST_FILES_H

#include <dirent.h>
#include <string.h>

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
