/* atomic_file.c — temporary file + rename (atomic_file.h). */
#include "atomic_file.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static atomic_uint tmp_counter;

void ic_atomic_temp_name(const char *path, char *out, size_t out_size)
{
    unsigned n = atomic_fetch_add(&tmp_counter, 1u);
    snprintf(out, out_size, "%s.tmp.%ld.%u", path, (long)getpid(), n);
}

ic_result ic_atomic_rename(const char *tmp, const char *path, ic_error *err)
{
    if (rename(tmp, path) != 0) {
        int e = errno;
        remove(tmp);
        return ic_error_set(err, IC_ERR_IO, "%s: cannot write (%s); check that the folder exists and is writable",
                            path, strerror(e));
    }
    return IC_OK;
}

ic_result ic_atomic_file_open(ic_atomic_file *f, const char *path, ic_error *err)
{
    memset(f, 0, sizeof *f);
    if (!path || !*path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "empty output path; give a file name");
    if (strlen(path) + 32 >= sizeof f->path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: output path too long", path);
    snprintf(f->path, sizeof f->path, "%s", path);
    ic_atomic_temp_name(path, f->tmp_path, sizeof f->tmp_path);
    f->fp = fopen(f->tmp_path, "wb");
    if (!f->fp)
        return ic_error_set(err, IC_ERR_IO, "%s: cannot write (%s); check that the folder exists and is writable",
                            path, strerror(errno));
    return IC_OK;
}

ic_result ic_atomic_file_commit(ic_atomic_file *f, ic_error *err)
{
    if (!f->fp)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: file is not open", f->path);
    int bad = ferror(f->fp);
    if (fclose(f->fp) != 0)
        bad = 1;
    f->fp = NULL;
    if (bad) {
        remove(f->tmp_path);
        return ic_error_set(err, IC_ERR_IO, "%s: write failed (disk full?); nothing was written", f->path);
    }
    return ic_atomic_rename(f->tmp_path, f->path, err);
}

void ic_atomic_file_abort(ic_atomic_file *f)
{
    if (f->fp) {
        fclose(f->fp);
        f->fp = NULL;
        remove(f->tmp_path);
    }
}
