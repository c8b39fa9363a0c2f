/* outputs.c — checking the outputs of a command before it starts (outputs.h). */
#include "outputs.h"
#include "cli.h"

#include "core/atomic_file.h"
#include "core/path.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define FAIL(o, ...)                                                                                  \
    (ic_cli_eprintf("%s: %s %s: ", command, (o)->option, (o)->path), ic_cli_eprintf(__VA_ARGS__), \
     fputc('\n', stderr), 0)

/* Splits path into its folder (ic_path_dirname) and its last component. */
static void split_path(const char *path, char *dir, size_t dir_size, const char **base)
{
    const char *slash = strrchr(path, '/');
    ic_path_dirname(path, dir, dir_size);
    *base = slash ? slash + 1 : path;
}

/* The canonical path of the file target (an output's path, its symbolic links followed): its folder's real
 * path and its name, so that two spellings of one file ("a.exr", "./a.exr", "x/../a.exr", a folder reached
 * through a link) compare equal. */
static void canonical(const char *target, char *canon, size_t canon_size)
{
    const char *base;
    char dir[PATH_MAX], real[PATH_MAX];
    split_path(target, dir, sizeof dir, &base);
    if (!realpath(dir, real))
        snprintf(real, sizeof real, "%s", dir);
    snprintf(canon, canon_size, "%s/%.*s", real, NAME_MAX, base); /* a name is at most NAME_MAX bytes */
}

/* One output on its own; on success canon holds its canonical path (canonical). */
static int check_one(const char *command, const ic_cli_output *o, char *canon, size_t canon_size)
{
    const char *base;
    char dir[PATH_MAX], target[PATH_MAX];
    if (!o->path[0])
        return FAIL(o, "empty path; give a file name");
    if (strlen(o->path) >= sizeof dir - 64)
        return FAIL(o, "path too long; use a shorter path");
    /* A symbolic link is written through (core/atomic_file.h): its target is the file checked. */
    int e = ic_atomic_target(o->path, target, sizeof target);
    if (e == ELOOP)
        return FAIL(o, "is a loop of symbolic links; give a file name");
    if (e == EACCES)
        return FAIL(o, "is another user's symbolic link in a shared folder, not followed (as the kernel's "
                    "protected_symlinks would not); give another name");
    if (e != 0 || strlen(target) >= sizeof dir - 64)
        return FAIL(o, "is a symbolic link that cannot be followed (%s); give a file name",
                    e ? strerror(e) : "its target's name is too long");
    split_path(target, dir, sizeof dir, &base);
    struct stat st;
    if (stat(o->path, &st) == 0) {
        if (S_ISDIR(st.st_mode))
            return FAIL(o, "is a folder; give a file name (for example %s%s%s)", o->path,
                        o->path[strlen(o->path) - 1] == '/' ? "" : "/",
                        o->example                         ? o->example
                        : !strcmp(o->option, "--save-cache") ? "records.icc"
                        : !strcmp(o->option, "-o")         ? "image.exr"
                                                           : "out.json");
        if (!S_ISREG(st.st_mode))
            return FAIL(o, "is not a regular file (a device, pipe or socket); give a file name");
    }
    if (!base[0] || !strcmp(base, ".") || !strcmp(base, ".."))
        return FAIL(o, "names a folder, not a file; give a file name");
    struct stat ds;
    if (stat(dir, &ds) != 0)
        return FAIL(o, "folder %s %s; create it first or choose another", dir,
                    errno == ENOENT ? "does not exist" : strerror(errno));
    if (!S_ISDIR(ds.st_mode))
        return FAIL(o, "%s is not a folder; choose another path", dir);
    /* Creating the temporary file is the only sure test (permissions, a read-only file system, ACLs). */
    ic_atomic_file f;
    ic_error err;
    if (ic_atomic_file_open(&f, o->path, &err) != IC_OK)
        return errno == ENAMETOOLONG
                   ? FAIL(o, "file name too long for folder %s (most file systems take a name of up to %d bytes); "
                          "use a shorter name", dir, NAME_MAX)
                   : FAIL(o, "cannot create a file in folder %s (%s); choose a writable folder", dir, strerror(errno));
    ic_atomic_file_abort(&f);
    canonical(target, canon, canon_size);
    return 1;
}

/* No output is one of the inputs (the same real path, or the same device and inode: a hard link), but the
 * one each may let rewrite it. canon: the outputs' canonical paths (canonical). Returns 1, or prints the
 * line and returns 0. */
static int check_inputs(const char *command, const ic_cli_output *outs, char (*canon)[PATH_MAX + 256], int count,
                        const ic_cli_input *inputs, int input_count)
{
    char real[PATH_MAX];
    int ok = 1;
    for (int k = 0; k < input_count && ok; ++k) {
        const ic_cli_input *in = &inputs[k];
        /* "-" reads standard input, which may be sent from a file ('--points - < in.txt'). */
        const int is_stdin = in->path && !strcmp(in->path, "-");
        if (!in->path || !realpath(is_stdin ? "/dev/stdin" : in->path, real))
            continue;
        struct stat is, os;
        const int has_inode = stat(real, &is) == 0;
        for (int i = 0; i < count && ok; ++i) {
            const int same = !strcmp(canon[i], real) || (has_inode && stat(outs[i].path, &os) == 0 &&
                                                         os.st_dev == is.st_dev && os.st_ino == is.st_ino);
            if (same && !(in->may_rewrite && !strcmp(outs[i].option, in->may_rewrite)))
                ok = is_stdin ? FAIL(&outs[i], "is %s - (standard input, sent from %s); writing it would destroy "
                                     "it, give another name", in->what, real)
                              : FAIL(&outs[i], "is %s %s; writing it would destroy it, give another name", in->what,
                                     in->path);
        }
    }
    return ok;
}

int ic_cli_check_outputs(const char *command, const ic_cli_output *outs, int count, const ic_cli_input *inputs,
                         int input_count)
{
    char(*canon)[PATH_MAX + 256] = calloc((size_t)count + 1, sizeof *canon);
    if (!canon) {
        ic_cli_eprintf("%s: out of memory checking the outputs\n", command);
        return 0;
    }
    int ok = 1;
    for (int i = 0; i < count && ok; ++i) {
        ok = check_one(command, &outs[i], canon[i], sizeof canon[i]);
        for (int j = 0; j < i && ok; ++j)
            if (!strcmp(canon[i], canon[j]))
                ok = FAIL(&outs[i], "the same file as %s %s; give each output its own name", outs[j].option,
                          outs[j].path);
    }
    ok = ok && check_inputs(command, outs, canon, count, inputs, input_count);
    free(canon);
    return ok;
}

int ic_cli_check_scene_files(const char *command, const ic_cli_output *outs, int count, const ic_scene *scene)
{
    const uint32_t n = ic_scene_file_count(scene);
    char(*canon)[PATH_MAX + 256] = calloc((size_t)count + 1, sizeof *canon);
    ic_cli_input *ins = calloc((size_t)n + 1, sizeof *ins);
    int ok = canon && ins;
    if (!ok)
        ic_cli_eprintf("%s: out of memory checking the outputs\n", command);
    for (int i = 0; i < count && ok; ++i) {
        char target[PATH_MAX];
        /* checked before the scene was loaded: a link that cannot be followed now is compared as written */
        if (ic_atomic_target(outs[i].path, target, sizeof target) != 0)
            snprintf(target, sizeof target, "%s", outs[i].path);
        canonical(target, canon[i], sizeof canon[i]);
    }
    for (uint32_t k = 0; k < n && ok; ++k)
        ins[k] = (ic_cli_input){"a file the scene reads,", ic_scene_file(scene, k), NULL};
    ok = ok && check_inputs(command, outs, canon, count, ins, (int)n);
    free(ins);
    free(canon);
    return ok;
}
