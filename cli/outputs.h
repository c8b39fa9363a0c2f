/* outputs.h — the files a render writes, checked before it starts (render.c). */
#ifndef IC_CLI_OUTPUTS_H
#define IC_CLI_OUTPUTS_H

/* One file the command will write: the option that named it ("-o", "--stats", …) and its path. */
typedef struct ic_cli_output {
    const char *option;
    const char *path;
} ic_cli_output;

/* Checks, before any rendering, that every output can be written: not an existing folder or other
 * non-regular file, its folder exists and takes a new file, and no two outputs (nor an output and the
 * scene file `input`, which may be NULL) are the same file. Returns 1, or prints one line naming the
 * option, the path and what to do, and returns 0. */
int ic_cli_check_outputs(const ic_cli_output *outs, int count, const char *input);

#endif
