/* read_file.c — reading a bounded regular file (read_file.h). */
#include "read_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* "N bytes", with the size in MiB or GiB beside a large N. */
static void size_text(uint64_t n, char *out, size_t size)
{
    if (n >= (1ull << 30))
        snprintf(out, size, "%llu bytes (%.1f GiB)", (unsigned long long)n, (double)n / 1073741824.0);
    else if (n >= (1ull << 20))
        snprintf(out, size, "%llu bytes (%.1f MiB)", (unsigned long long)n, (double)n / 1048576.0);
    else
        snprintf(out, size, "%llu bytes", (unsigned long long)n);
}

/* Opens path without blocking and checks with fstat that it is a regular file; *fd and *st on success. */
static ic_result open_checked(const char *path, const char *what, int *fd_out, struct stat *st, int *open_errno,
                              ic_error *err)
{
    /* O_NONBLOCK: opening a FIFO without a writer returns at once instead of waiting for one. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        int e = errno;
        if (open_errno)
            *open_errno = e;
        return ic_error_set(err, IC_ERR_IO, "%s: cannot open the %s (%s); check the path", path, what, strerror(e));
    }
    if (fstat(fd, st) != 0) {
        int e = errno;
        close(fd);
        return ic_error_set(err, IC_ERR_IO, "%s: cannot read the %s (%s); check the file", path, what, strerror(e));
    }
    if (S_ISDIR(st->st_mode)) {
        close(fd);
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: is a folder, not a %s; give the path of the file in it",
                            path, what);
    }
    if (!S_ISREG(st->st_mode)) {
        close(fd);
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "%s: is not a regular file (a pipe, device or socket); give the path of a %s", path,
                            what);
    }
    *fd_out = fd;
    return IC_OK;
}

ic_result ic_open_regular_file(const char *path, const char *what, FILE **fp, ic_error *err)
{
    *fp = NULL;
    int fd;
    struct stat st;
    ic_result r = open_checked(path, what, &fd, &st, NULL, err);
    if (r != IC_OK)
        return r;
    int flags = fcntl(fd, F_GETFL);
    if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0 || (*fp = fdopen(fd, "rb")) == NULL) {
        int e = errno;
        close(fd);
        return ic_error_set(err, IC_ERR_IO, "%s: cannot open the %s (%s); check the file", path, what, strerror(e));
    }
    return IC_OK;
}

ic_result ic_read_regular_file(const char *path, const char *what, uint64_t max_bytes, const char *limit_hint,
                               char **data, size_t *size, int *open_errno, ic_error *err)
{
    *data = NULL;
    *size = 0;
    if (open_errno)
        *open_errno = 0;
    int fd;
    struct stat st;
    ic_result r0 = open_checked(path, what, &fd, &st, open_errno, err);
    if (r0 != IC_OK)
        return r0;
    if ((uint64_t)st.st_size > max_bytes || (uint64_t)st.st_size >= SIZE_MAX) {
        close(fd);
        char have[64], limit[64];
        size_text((uint64_t)st.st_size, have, sizeof have);
        size_text(max_bytes, limit, sizeof limit);
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: the %s is %s, more than the limit of %s; %s", path, what,
                            have, limit, limit_hint);
    }
    size_t n = (size_t)st.st_size;
    char *buf = malloc(n + 1);
    if (!buf) {
        close(fd);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory reading the %s (%zu bytes)", path, what, n);
    }
    /* A regular file never blocks; clear O_NONBLOCK anyway so that reads are plain. */
    int flags = fcntl(fd, F_GETFL);
    if (flags >= 0)
        (void)fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(fd, buf + got, n - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        got += (size_t)r;
    }
    int e = errno;
    close(fd);
    if (got != n) {
        free(buf);
        return ic_error_set(err, IC_ERR_IO, "%s: cannot read the %s (%s); check the file and the disk", path, what,
                            got < n && e ? strerror(e) : "it changed while being read");
    }
    buf[n] = '\0';
    *data = buf;
    *size = n;
    return IC_OK;
}
