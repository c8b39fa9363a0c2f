/*
 * test_files.h — file-system and command helpers shared by the tests.
 */
#ifndef IC_TEST_FILES_H
#define IC_TEST_FILES_H

#include <dirent.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

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

/* Writes text to path; 1 on success. */
static inline int test_write_text(const char *path, const char *text)
{
    FILE *fp = fopen(path, "w");
    if (!fp)
        return 0;
    fputs(text, fp);
    return fclose(fp) == 0;
}

/* 1 if something exists at path. */
static inline int test_file_exists(const char *path)
{
    struct stat s;
    return stat(path, &s) == 0;
}

/* The number of newlines in s. */
static inline int test_line_count(const char *s)
{
    int n = 0;
    for (; *s; ++s)
        n += *s == '\n';
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

/* Runs the shell command line cmd with its stderr sent to err_path and read back into text (size bytes,
 * NUL-terminated); returns the exit status, or -1 if the command crashed or could not run. */
static inline int test_run_capture(const char *cmd, const char *err_path, char *text, size_t size)
{
    char line[8192];
    snprintf(line, sizeof line, "%s 2>%s", cmd, err_path);
    int st = system(line);
    test_read_text(err_path, text, size);
    if (st == -1 || !WIFEXITED(st))
        return -1;
    return WEXITSTATUS(st);
}

/* test_run_capture of the command line printf-style fmt makes, its stdout discarded. */
static inline int test_run_quiet(const char *err_path, char *text, size_t size, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static inline int test_run_quiet(const char *err_path, char *text, size_t size, const char *fmt, ...)
{
    char cmd[8000];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    if (n >= 0 && (size_t)n < sizeof cmd)
        snprintf(cmd + n, sizeof cmd - (size_t)n, " >/dev/null");
    return test_run_capture(cmd, err_path, text, size);
}

#endif
