/*
 * test_atomic_file.c — a temporary left by a SIGKILL during a write (<out>.tmp.<pid>.<n>, no handler ran) is
 * removed by the next write of the same output, once its process is gone (issue "Hardening", Signals):
 * through the library's atomic file, through ic_atomic_temp_name (the EXR writer's path), and through the
 * command. A temporary of a live process, of another output, or a name not of the form is left alone.
 *
 * An output that is a symbolic link is written through it: the link stays; one that is a pipe, a device or a
 * folder is refused, never replaced.
 *
 * Every atomic write syncs its temporary (fsync, wrapped here: -Wl,--wrap=fsync) before the rename, so a
 * crash after it cannot leave an empty file under the final name: the atomic file and the EXR writer.
 */
#include "core/atomic_file.h"
#include "irrcache/image.h"
#include "test_util.h"
#include "test_files.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#define T IC_TEST_TMP "/atomic_file"
#define CLI IC_CLI_PATH
#define QUAD IC_SOURCE_DIR "/tests/scenes/quad_light.obj"

static int exists(const char *p)
{
    struct stat st;
    return lstat(p, &st) == 0;
}

static void touch(const char *p)
{
    FILE *f = fopen(p, "wb");
    CHECK(f != NULL, "write %s: %s", p, strerror(errno));
    if (f) {
        fputs("half-written", f);
        fclose(f);
    }
}

/* The first bytes of path as text ("" when it cannot be read). */
static const char *read_small(const char *path, char *text, size_t size)
{
    FILE *rf = fopen(path, "rb");
    text[0] = 0;
    if (rf) {
        text[fread(text, 1, size - 1, rf)] = 0;
        fclose(rf);
    }
    return text;
}

/* The pid of a process that has exited and been reaped: no process has it (until it is reused). */
static long dead_pid(void)
{
    pid_t p = fork();
    if (p == 0)
        _exit(0);
    CHECK(p > 0, "fork: %s", strerror(errno));
    if (p > 0)
        waitpid(p, NULL, 0);
    CHECK(p > 0 && kill(p, 0) != 0 && errno == ESRCH, "the child %ld is gone", (long)p);
    return (long)p;
}

/* Leaves the temporaries of out: a dead process's (two), a live one's, another output's, odd names. */
static void leave(const char *out, long dead, char stale[2][512], char keep[4][512])
{
    snprintf(stale[0], 512, "%s.tmp.%ld.0", out, dead);
    snprintf(stale[1], 512, "%s.tmp.%ld.17", out, dead);
    snprintf(keep[0], 512, "%s.tmp.%ld.0", out, (long)getppid()); /* alive: the test's parent */
    snprintf(keep[1], 512, "%s.other.tmp.%ld.0", out, dead);       /* another output's */
    snprintf(keep[2], 512, "%s.tmp.%ldx.0", out, dead);            /* not <pid>.<n> */
    snprintf(keep[3], 512, "%s.tmp.%ld", out, dead);               /* no counter */
    for (int i = 0; i < 2; ++i)
        touch(stale[i]);
    for (int i = 0; i < 4; ++i)
        touch(keep[i]);
}

static void check_cleaned(const char *what, char stale[2][512], char keep[4][512])
{
    for (int i = 0; i < 2; ++i)
        CHECK(!exists(stale[i]), "%s: the dead process's %s is removed", what, stale[i]);
    for (int i = 0; i < 4; ++i) {
        CHECK(exists(keep[i]), "%s: %s is kept", what, keep[i]);
        remove(keep[i]);
    }
}

/* fsync, counted, with the name of the last file it synced and whether the final name existed then. */
int __real_fsync(int fd);
int __wrap_fsync(int fd);
static int fsync_calls;
static char fsync_path[4096];

int __wrap_fsync(int fd)
{
    char link[64];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    ssize_t n = readlink(link, fsync_path, sizeof fsync_path - 1);
    fsync_path[n > 0 ? n : 0] = 0;
    ++fsync_calls;
    return __real_fsync(fd);
}

/* One write through `what`: fsync ran once, on a temporary of `out` (before the rename). */
static void check_synced(const char *what, const char *out, int calls_before)
{
    CHECK(fsync_calls == calls_before + 1 && strstr(fsync_path, out) && strstr(fsync_path, ".tmp."),
          "%s: the temporary is synced before the rename (%d fsync, last %s)", what, fsync_calls - calls_before,
          fsync_path);
}

int main(void)
{
    CHECK(system("rm -rf '" T "' && mkdir -p '" T "'") == 0, "make %s", T);
    long dead = dead_pid();
    char stale[2][512], keep[4][512];

    /* the atomic file (PNG, PFM, HDR, the cache file, the JSON outputs) */
    leave(T "/out.pfm", dead, stale, keep);
    ic_atomic_file f;
    ic_error err;
    memset(&err, 0, sizeof err);
    CHECK(ic_atomic_file_open(&f, T "/out.pfm", &err) == IC_OK, "open: %s", err.message);
    fputs("data", f.fp);
    int calls = fsync_calls;
    CHECK(ic_atomic_file_commit(&f, &err) == IC_OK, "commit: %s", err.message);
    CHECK(exists(T "/out.pfm"), "the output is written");
    check_synced("atomic file", "/out.pfm", calls);
    check_cleaned("atomic file", stale, keep);

    /* a temporary name for a writer that needs a path (the EXR writer) */
    leave(T "/out.exr", dead, stale, keep);
    char tmp[4096];
    ic_atomic_temp_name(T "/out.exr", tmp, sizeof tmp);
    remove(tmp);
    ic_atomic_temp_release(tmp);
    check_cleaned("temporary name", stale, keep);

    /* A link planted at the temporary's name, which is predictable (<path>.tmp.<pid>.<n>; another user's, in
     * a shared folder such as /tmp, where fs.protected_symlinks may be off), is not followed: opened with
     * O_TRUNC, the output went into the file the link leads to, and the rename left the link as the output.
     * The temporary is created exclusively (O_EXCL) and a name taken is passed over: the atomic file and the
     * EXR writer. */
    for (int k = 0; k < 2; ++k) {
        const char *out = k ? T "/planted.exr" : T "/planted.pfm";
        ic_atomic_temp_name(out, tmp, sizeof tmp);
        remove(tmp);
        ic_atomic_temp_release(tmp);
        char planted[4200];
        const char *dot = strrchr(tmp, '.');
        snprintf(planted, sizeof planted, "%.*s.%lu", (int)(dot - tmp), tmp, strtoul(dot + 1, NULL, 10) + 1);
        FILE *vf = fopen(T "/victim.txt", "w");
        CHECK(vf && fputs("victim\n", vf) >= 0 && fclose(vf) == 0, "a victim");
        CHECK(symlink(T "/victim.txt", planted) == 0, "a link at the next temporary's name %s", planted);
        memset(&err, 0, sizeof err);
        ic_result prc;
        if (k) {
            ic_image one;
            CHECK(ic_image_create(&one, 2, 2) == IC_OK, "image");
            prc = ic_image_write(out, &one, NULL, &err);
            ic_image_free(&one);
        } else if ((prc = ic_atomic_file_open(&f, out, &err)) == IC_OK) {
            fputs("output", f.fp);
            prc = ic_atomic_file_commit(&f, &err);
        }
        struct stat pst;
        char victim[64];
        CHECK(prc == IC_OK && lstat(out, &pst) == 0 && S_ISREG(pst.st_mode), "%s: written as a file (%s)", out,
              err.message);
        CHECK(!strcmp(read_small(T "/victim.txt", victim, sizeof victim), "victim\n"),
              "%s: the file the planted link leads to is untouched: '%s'", out, victim);
        remove(planted);
    }

    /* the EXR writer (OpenEXR writes and closes the temporary by name) */
    ic_image img;
    CHECK(ic_image_create(&img, 4, 4) == IC_OK, "image");
    calls = fsync_calls;
    CHECK(ic_image_write(T "/synced.exr", &img, NULL, &err) == IC_OK && exists(T "/synced.exr"), "EXR: %s",
          err.message);
    check_synced("EXR", "/synced.exr", calls);
    ic_image_free(&img);

    /* A path that is a symbolic link (relative, through a chain, or dangling into an existing folder) is
     * written through: the link stays, the file it leads to takes the data, the temporary lies beside that
     * file (the rename had replaced the link with a plain file and left the target as it was). Through the
     * atomic file and the EXR writer's temporary name. */
    CHECK(system("mkdir -p '" T "/links/sub' && cd '" T "/links' && echo old > sub/real.pfm && "
                 "ln -sf sub/real.pfm link.pfm && ln -sf ../link.pfm sub/chain.pfm && ln -sf sub/new.exr new.exr") == 0,
          "links");
    CHECK(ic_atomic_file_open(&f, T "/links/sub/chain.pfm", &err) == IC_OK, "open through links: %s", err.message);
    fputs("new data", f.fp);
    CHECK(ic_atomic_file_commit(&f, &err) == IC_OK, "commit through links: %s", err.message);
    struct stat ls;
    CHECK(lstat(T "/links/link.pfm", &ls) == 0 && S_ISLNK(ls.st_mode) && lstat(T "/links/sub/chain.pfm", &ls) == 0 &&
              S_ISLNK(ls.st_mode), "the links stay links");
    char text[64];
    CHECK(!strcmp(read_small(T "/links/sub/real.pfm", text, sizeof text), "new data"),
          "the file the links lead to holds the new data: '%s'", text);
    ic_image small;
    CHECK(ic_image_create(&small, 2, 2) == IC_OK, "image");
    CHECK(ic_image_write(T "/links/new.exr", &small, NULL, &err) == IC_OK, "EXR through a dangling link: %s",
          err.message);
    CHECK(lstat(T "/links/new.exr", &ls) == 0 && S_ISLNK(ls.st_mode) && exists(T "/links/sub/new.exr"),
          "the EXR is written where the dangling link leads, the link stays");
    ic_image_free(&small);
    char target[4096];
    CHECK(ic_atomic_target(T "/links/sub/chain.pfm", target, sizeof target) == 0 &&
              !strcmp(target, T "/links/sub/../sub/real.pfm"),
          "the chain's target: %s", target);

    /* Links are followed as the kernel follows them under fs.protected_symlinks: in a sticky folder anyone
     * may write to (/tmp), only a link this process or the folder's owner owns; another user's link
     * /tmp/out.exr -> /etc/passwd must not have a root render replace /etc/passwd (readlink, unlike open,
     * bypasses the kernel's rule). Another user's link needs root to make (lchown): skipped otherwise. */
    CHECK(system("mkdir -p '" T "/shared' && chmod 1777 '" T "/shared' && echo secret > '" T "/secret.pfm' && "
                 "ln -sf ../secret.pfm '" T "/shared/theirs.pfm' && ln -sf ../secret.pfm '" T "/shared/mine.pfm'") == 0,
          "a shared folder");
    if (geteuid() == 0 && lchown(T "/shared/theirs.pfm", 12345, 12345) == 0) {
        memset(&err, 0, sizeof err);
        ic_result rc = ic_atomic_file_open(&f, T "/shared/theirs.pfm", &err);
        if (rc == IC_OK)
            ic_atomic_file_commit(&f, &err);
        CHECK(rc == IC_ERR_IO && strstr(err.message, "cannot be followed"), "another user's link in a sticky "
              "folder is not followed (%s: %s)", ic_result_name(rc), err.message);
        CHECK(!strcmp(read_small(T "/secret.pfm", text, sizeof text), "secret\n"),
              "the file it leads to is untouched: '%s'", text);
        CHECK(lstat(T "/shared/theirs.pfm", &ls) == 0 && S_ISLNK(ls.st_mode), "the link stays");
        CHECK(ic_atomic_target(T "/shared/theirs.pfm", target, sizeof target) == EACCES, "ic_atomic_target: EACCES");
    } else {
        printf("not root: another user's link in a sticky folder is not checked\n");
    }
    CHECK(ic_atomic_file_open(&f, T "/shared/mine.pfm", &err) == IC_OK, "own link: %s", err.message);
    fputs("mine", f.fp);
    CHECK(ic_atomic_file_commit(&f, &err) == IC_OK, "own link: %s", err.message);
    CHECK(!strcmp(read_small(T "/secret.pfm", text, sizeof text), "mine") && lstat(T "/shared/mine.pfm", &ls) == 0 && S_ISLNK(ls.st_mode),
          "this process's own link in a sticky folder is followed: '%s'", text);

    /* A path that is not a file (a pipe, a device, a folder) is refused, never replaced: the rename put a
     * plain file in the place of the node (run as root, an image or cache written to /dev/null turned it into
     * a file for every later process). Through the atomic file (at the open, before anything is written) and
     * through the EXR writer's temporary name (at the rename); no temporary is left. A device node only
     * where this user may make one. */
    CHECK(system("mkdir -p '" T "/nodes/folder.pfm' && mkfifo '" T "/nodes/pipe.pfm' '" T "/nodes/pipe.exr'") == 0,
          "nodes");
    const int has_device = system("mknod '" T "/nodes/null.pfm' c 1 3 2>/dev/null") == 0;
    const char *nodes[4] = {T "/nodes/pipe.pfm", T "/nodes/folder.pfm", T "/nodes/pipe.exr", T "/nodes/null.pfm"};
    const char *says[4] = {"not a regular file", "is a folder", "not a regular file", "not a regular file"};
    CHECK(ic_image_create(&small, 2, 2) == IC_OK, "image");
    for (int k = 0; k < (has_device ? 4 : 3); ++k) {
        struct stat before, after;
        lstat(nodes[k], &before);
        memset(&err, 0, sizeof err);
        ic_result rc = k == 2 ? ic_image_write(nodes[k], &small, NULL, &err) : ic_atomic_file_open(&f, nodes[k], &err);
        if (rc == IC_OK && k != 2)
            ic_atomic_file_commit(&f, &err);
        CHECK(rc == IC_ERR_IO && strstr(err.message, says[k]) && strstr(err.message, nodes[k]),
              "%s: refused (%s: %s)", nodes[k], ic_result_name(rc), err.message);
        CHECK(lstat(nodes[k], &after) == 0 && (after.st_mode & S_IFMT) == (before.st_mode & S_IFMT),
              "%s: still what it was", nodes[k]);
    }
    ic_image_free(&small);
    CHECK(test_count_temporaries(T "/nodes") == 0, "no temporary left beside the nodes");
    /* A link to a pipe through /proc/self/fd (/dev/stdout piped to another program): the link reads
     * "pipe:[N]", no name, so the pipe is found by following it as the kernel does. */
    int fds[2];
    CHECK(pipe(fds) == 0, "pipe");
    char fd_link[64];
    snprintf(fd_link, sizeof fd_link, "/proc/self/fd/%d", fds[1]);
    CHECK(symlink(fd_link, T "/nodes/stdout.pfm") == 0, "a link through /proc/self/fd");
    memset(&err, 0, sizeof err);
    ic_result prc = ic_atomic_file_open(&f, T "/nodes/stdout.pfm", &err);
    if (prc == IC_OK)
        ic_atomic_file_abort(&f);
    CHECK(prc == IC_ERR_IO && strstr(err.message, "not a regular file"), "a link to a pipe is refused as one (%s: %s)",
          ic_result_name(prc), err.message);
    close(fds[0]);
    close(fds[1]);
    /* A link through this process's descriptor of a file (/dev/stdout with the output sent to a file, here
     * opened to append, as '>>' opens it) is written through that descriptor, at its offset, as the shell's
     * redirection writes: renaming onto the file it leads to replaced that file, losing what it held, and
     * what the descriptor wrote afterwards went to a file no name led to. The atomic file and the EXR writer. */
    for (int k = 0; k < 2; ++k) {
        const char *log_path = k ? T "/nodes/log2.txt" : T "/nodes/log.txt";
        const char *link = k ? T "/nodes/log.exr" : T "/nodes/log.pfm";
        FILE *lf = fopen(log_path, "w");
        CHECK(lf && fputs("before\n", lf) >= 0 && fclose(lf) == 0, "a log");
        int lfd = open(log_path, O_WRONLY | O_APPEND);
        snprintf(fd_link, sizeof fd_link, "/proc/self/fd/%d", lfd);
        CHECK(lfd >= 0 && symlink(fd_link, link) == 0, "a link through /proc/self/fd to a file");
        memset(&err, 0, sizeof err);
        ic_result lrc = IC_ERR_IO;
        if (k == 0 && (lrc = ic_atomic_file_open(&f, link, &err)) == IC_OK) {
            fputs("output\n", f.fp);
            lrc = ic_atomic_file_commit(&f, &err);
        }
        if (k == 1) {
            CHECK(ic_image_create(&small, 2, 2) == IC_OK, "image");
            lrc = ic_image_write(link, &small, NULL, &err);
            ic_image_free(&small);
        }
        CHECK(lrc == IC_OK, "%s: written through the descriptor (%s)", link, err.message);
        CHECK(write(lfd, "after\n", 6) == 6, "the descriptor writes on");
        close(lfd);
        char log_text[64];
        struct stat lst;
        read_small(log_path, log_text, sizeof log_text);
        CHECK(k ? strncmp(log_text, "before\nv/1\x01", 11) == 0 && stat(log_path, &lst) == 0 && lst.st_size > 64
                : strcmp(log_text, "before\noutput\nafter\n") == 0,
              "%s: what the file held, the output, then what the descriptor wrote after: '%s'", log_path, log_text);
    }
    CHECK(test_count_temporaries(T "/nodes") == 0, "no temporary left beside the log");

    /* the command: a rerun after a SIGKILL during its write */
    leave(T "/render.png", dead, stale, keep);
    int st = system(CLI " render " QUAD " -o " T "/render.png --width 4 --height 4 --spp 1 -q");
    CHECK(st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 0, "render");
    CHECK(exists(T "/render.png"), "the image is written");
    check_cleaned("irrcache render", stale, keep);
    TEST_MAIN_END();
}
