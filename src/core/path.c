/* path.c — the folder part of a file path (path.h). */
#include "core/path.h"

#include <stdio.h>
#include <string.h>

void ic_path_dirname(const char *path, char *dir, size_t size)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, size, ".");
    else if (slash == path)
        snprintf(dir, size, "/");
    else
        snprintf(dir, size, "%.*s", (int)(slash - path), path);
}
