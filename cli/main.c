/*
 * main.c — the irrcache command: dispatches to sub-commands (render, diff, points). The CLI, not the
 * library, prints messages and chooses exit codes: 0 success, 1 a failure while working (I/O,
 * malformed input), 2 a usage error (unknown option, impossible value).
 */
#include "cli.h"

#include "irrcache/common.h"
#include "irrcache/version.h"

#include <signal.h>
#include <stdio.h>
#include <string.h>

volatile sig_atomic_t ic_cli_stop_signal = 0;
volatile sig_atomic_t ic_cli_rendering = 0;

/* The first SIGINT or SIGTERM while a render runs (ic_cli_rendering) only asks it to stop
 * (ic_cli_stop_signal, the render's cancel flag): the command then writes the image so far and exits
 * 128 + the signal. Any other signal of the list, and a second one, ends the program: a signal that ends
 * it while an output is being written must not leave its temporary file, so the library's temporary
 * files are removed (async-signal-safe), the default action restored and the signal raised again
 * (SA_NODEFER lets raise deliver it at once), so the parent still sees the signal. */
static void on_signal(int sig)
{
    if (ic_cli_rendering && !ic_cli_stop_signal && (sig == SIGINT || sig == SIGTERM)) {
        ic_cli_stop_signal = sig;
        return;
    }
    ic_remove_temporary_files();
    struct sigaction dfl;
    memset(&dfl, 0, sizeof dfl);
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    sigaction(sig, &dfl, NULL);
    raise(sig);
}

static void install_signal_handlers(void)
{
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGXFSZ};
    for (size_t i = 0; i < sizeof sigs / sizeof sigs[0]; ++i) {
        struct sigaction old;
        /* A signal ignored when the program starts stays ignored (POSIX: a background job's SIGINT; a
         * caller that wants EFBIG instead of SIGXFSZ). */
        if (sigaction(sigs[i], NULL, &old) != 0 || old.sa_handler == SIG_IGN)
            continue;
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigemptyset(&sa.sa_mask);
        sa.sa_flags = SA_NODEFER;
        sigaction(sigs[i], &sa, NULL);
    }
}

static void usage(FILE *f)
{
    fprintf(f,
            "irrcache %s — irradiance caching renderer\n"
            "\n"
            "usage:\n"
            "  irrcache render SCENE -o OUT [options]   render a scene (JSON scene file or .obj/.gltf/.glb/.ply,\n"
            "                                           also .gz)\n"
            "  irrcache diff IMAGE REFERENCE [options]  error metrics of IMAGE against REFERENCE\n"
            "  irrcache points SCENE --points FILE|-    irradiance and illuminance at sensor points\n"
            "  irrcache --help | --version\n"
            "\n"
            "Run 'irrcache COMMAND --help' (render, diff, points) for the options of each command.\n",
            IC_VERSION);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    install_signal_handlers();
    const char *cmd = argv[1];
    if (!strcmp(cmd, "render"))
        return ic_cli_render(argc - 1, argv + 1);
    if (!strcmp(cmd, "diff"))
        return ic_cli_diff(argc - 1, argv + 1);
    if (!strcmp(cmd, "points"))
        return ic_cli_points(argc - 1, argv + 1);
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        usage(stdout);
        return ic_cli_flush_stdout("irrcache");
    }
    if (!strcmp(cmd, "--version")) {
        /* The library's version, which a shared library may give differently from the headers'. */
        if (strcmp(ic_version(), IRRCACHE_VERSION_STRING) != 0)
            printf("irrcache %s (built with headers %s)\n", ic_version(), IRRCACHE_VERSION_STRING);
        else
            printf("irrcache %s\n", ic_version());
        return ic_cli_flush_stdout("irrcache");
    }
    ic_cli_eprintf("irrcache: unknown command '%s'; use 'render', 'diff' or 'points' (see irrcache --help)\n", cmd);
    return 2;
}
