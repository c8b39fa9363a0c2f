/*
 * atomic_file.h — write a file under a temporary name and rename it into place.
 *
 * Nothing is ever left half-written: readers see either the old file or the complete new one.
 * Usage: ic_atomic_file f; ic_atomic_file_open(&f, path, err) → write to f.fp →
 * ic_atomic_file_commit(&f, err) (flushes, checks for write errors, renames) or
 * ic_atomic_file_abort(&f) (removes the temporary file). While a temporary file exists its name is
 * registered, so that a program's signal handler can remove it (ic_remove_temporary_files). A temporary
 * that a SIGKILL left (no handler runs) is removed by the next write of the same path, once its process
 * is gone, by a process of the same machine (this boot) and pid namespace only: its name has a tag that
 * says which, because another machine's pids (a folder shared over NFS) or another container's cannot be
 * seen from here, and one that looks dead may be writing now. A path that is a symbolic link is
 * followed: the file it leads to is written, the link stays; one that leads through this process's
 * descriptor of a file (/dev/stdout sent to a file) is written through that descriptor at its offset, as the
 * shell's redirection writes (so '>>' keeps what the file held), once the temporary holds all of it.
 * A path that is a folder, a device, a pipe or a socket is refused (IC_ERR_IO), never replaced.
 * A file replaced keeps its permission bits (less setuid and setgid) and, where the process may, its owner and
 * group, as sed -i keeps them; the temporary is the owner's alone until then. A new file takes 0666 & ~umask.
 * A name too long for the temporary's tail (a legal 240-byte name) gets a shortened temporary beside it.
 */
#ifndef IC_CORE_ATOMIC_FILE_H
#define IC_CORE_ATOMIC_FILE_H

#include "irrcache/common.h"

#include <stdio.h>

typedef struct ic_atomic_file {
    FILE *fp;              /* write here */
    char path[4096];       /* final destination, as the caller named it (messages say it) */
    char tmp_path[4096];   /* temporary sibling of the file written: <path>.tmp.<tag>.<pid>.<n> (tag: 8 hex
                              digits for this machine's boot and pid namespace; the name shortened where
                              that would be too long), or beside the file a link path leads to */
} ic_atomic_file;

/* Opens a temporary file beside path for binary writing. */
ic_result ic_atomic_file_open(ic_atomic_file *f, const char *path, ic_error *err);
/* Closes the temporary file and renames it to path; on any error removes it and reports. */
ic_result ic_atomic_file_commit(ic_atomic_file *f, ic_error *err);
/* Closes and removes the temporary file. Safe to call twice. */
void ic_atomic_file_abort(ic_atomic_file *f);
/* Builds a temporary sibling name for path (for writers that need a path, not a FILE*), creates it empty
 * and exclusively (O_EXCL: a link planted at the predictable name is never followed; a name taken is passed
 * over) and registers it for ic_remove_temporary_files (irrcache/common.h) until ic_atomic_rename or
 * ic_atomic_temp_release; the caller opens it by name (O_TRUNC is safe: it is this process's file). 0, or
 * an errno value with nothing created (ENAMETOOLONG for a name no file may have). First removes the
 * temporaries of path that dead processes left (<path>.tmp.<tag>.<pid>.<n> of this process's tag whose pid no
 * process has: a SIGKILL during a write); those of another tag or of the older form <path>.tmp.<pid>.<n> are
 * kept (their pid cannot be judged here), and all are kept when the tag cannot be known (no /proc);
 * ic_atomic_file_open does the same. */
int ic_atomic_temp_name(const char *path, char *out, size_t out_size);
/* The file that writing path replaces: path with its symbolic links followed (relative ones from the
 * link's folder), into out; 0, or an errno value (ELOOP, ENAMETOOLONG, readlink's) with out undefined. */
int ic_atomic_target(const char *path, char *out, size_t out_size);
/* Gives tmp the permissions of the file it replaces and syncs it to disk (fsync), then renames tmp to the
 * file it was named for (path, or the file the link path leads to; its bytes are written through the
 * descriptor when the link leads through one of this process's), removing tmp on failure; either way tmp is
 * released. path names it in messages. */
ic_result ic_atomic_rename(const char *tmp, const char *path, ic_error *err);
/* Forgets a temporary name the caller removed itself. */
void ic_atomic_temp_release(const char *tmp);
/* Reports (IC_ERR_IO) that path cannot be written for errno value e: what to do (a name too long, or a
 * folder missing or not writable). */
ic_result ic_atomic_write_error(const char *path, int e, ic_error *err);

#endif
