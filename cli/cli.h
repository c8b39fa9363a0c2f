/* cli.h — sub-commands of the irrcache command; each returns the process exit status. */
#ifndef IC_CLI_H
#define IC_CLI_H

#include <errno.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include <signal.h>

/* Set by the signal handler (main.c): the first SIGINT or SIGTERM while ic_cli_rendering is set, which the
 * render reads as its cancel flag (render.c). */
extern volatile sig_atomic_t ic_cli_stop_signal;
extern volatile sig_atomic_t ic_cli_rendering;

/* irrcache render SCENE -o OUT [options] */
int ic_cli_render(int argc, char **argv);
/* irrcache diff A B [--json] [--heatmap FILE.png] [--blotch-map FILE.png] (options: options.h) */
int ic_cli_diff(int argc, char **argv);
/* irrcache points SCENE --points FILE|- [-o FILE] [--format text|csv|json] (options: options.h) */
int ic_cli_points(int argc, char **argv);

struct ic_scene;
/* Prints on stderr, as "WHO: warning: ...", what loading the scene at path approximated or left out
 * (ic_scene_warnings, one line each) and that it has no light, if so, with the outcome ("the image will
 * be black") (render.c). */
void ic_cli_scene_warnings(const char *who, const struct ic_scene *scene, const char *path, const char *outcome);

/* Prints a message on stderr like fprintf, with every control byte the formatted text holds written as
 * \xNN, but for a newline that ends it: a file name that holds a newline, a carriage return or an escape
 * sequence cannot split the message over lines or drive the terminal (message.c). The progress lines,
 * whose carriage returns are meant, are printed directly. */
void ic_cli_eprintf(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

/* Flushes standard output and checks it for a write error (a full disk, /dev/full): what was printed
 * there (help, a table, results) is otherwise lost without a word. Returns 0, or 1 (the exit status of a
 * failure while working) after the line "WHO: standard output: write error (reason)" on stderr. Inline
 * because test_diff compiles diff.c on its own. */
static inline int ic_cli_flush_stdout(const char *who)
{
    int e = fflush(stdout) != 0 ? errno : 0;
    if (!e && !ferror(stdout))
        return 0;
    fprintf(stderr, "%s: standard output: write error%s%s%s\n", who, e ? " (" : "", e ? strerror(e) : "", e ? ")" : "");
    return 1;
}

/* Seconds on the monotonic clock (the progress lines' elapsed time). */
static inline double ic_cli_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
