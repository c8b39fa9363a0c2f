/* outputs.h — the files a command writes, checked before it starts (render.c, points.c). */
#ifndef IC_CLI_OUTPUTS_H
#define IC_CLI_OUTPUTS_H

#include "irrcache/render.h"

/* One file the command will write: the option that named it ("-o", "--stats", …) and its path. */
typedef struct ic_cli_output {
    const char *option;
    const char *path;
    const char *example;   /* a file name to suggest when path is a folder (NULL: render's, by option) */
} ic_cli_output;

/* A file the command reads, which no output may overwrite: what it is ("the scene file") and its path
 * (NULL: none; "-": standard input, the file it is sent from, if any). */
typedef struct ic_cli_input {
    const char *what;
    const char *path;
    const char *may_rewrite; /* the one output option that may write it (render's --save-cache onto the
                                --load-cache file: the same records), or NULL */
} ic_cli_input;

/* Checks, before any work, that every output can be written: not an existing folder or other non-regular
 * file, its folder exists and takes a new file, and no two outputs (nor an output and an input) are the
 * same file, symbolic links followed. Returns 1, or prints one line, "COMMAND: OPTION PATH: problem; what
 * to do", and returns 0. */
int ic_cli_check_outputs(const char *command, const ic_cli_output *outs, int count, const ic_cli_input *inputs,
                         int input_count);

/* Checks, once the scene is loaded and before the work, that no output is one of the files it read
 * (ic_scene_file: its meshes, material libraries, buffers, textures, environment maps, ...): the same real
 * path, or the same device and inode. Returns 1, or prints the line as ic_cli_check_outputs does and
 * returns 0. */
int ic_cli_check_scene_files(const char *command, const ic_cli_output *outs, int count, const ic_scene *scene);

#endif
