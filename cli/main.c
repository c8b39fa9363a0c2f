/*
 * main.c — the irrcache command: dispatches to sub-commands (render, diff). The CLI, not the
 * library, prints messages and chooses exit codes: 0 success, 1 a failure while working (I/O,
 * malformed input), 2 a usage error (unknown option, impossible value).
 */
#include "cli.h"

#include <stdio.h>
#include <string.h>

static void usage(FILE *f)
{
    fprintf(f,
            "irrcache %s — irradiance caching renderer\n"
            "\n"
            "usage:\n"
            "  irrcache render SCENE -o OUT [options]   render a scene (JSON scene file or .obj/.gltf/.glb/.ply,\n"
            "                                           also .gz)\n"
            "  irrcache diff IMAGE REFERENCE [options]  error metrics of IMAGE against REFERENCE\n"
            "  irrcache --help | --version\n"
            "\n"
            "Run 'irrcache render --help' or 'irrcache diff --help' for the options of each command.\n",
            IC_VERSION);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    if (!strcmp(cmd, "render"))
        return ic_cli_render(argc - 1, argv + 1);
    if (!strcmp(cmd, "diff"))
        return ic_cli_diff(argc - 1, argv + 1);
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "--version")) {
        printf("irrcache %s\n", IC_VERSION);
        return 0;
    }
    fprintf(stderr, "irrcache: unknown command '%s'; use 'render' or 'diff' (see irrcache --help)\n", cmd);
    return 2;
}
