/*
 * test_atomic_file.c — a temporary left by a SIGKILL during a write (<out>.tmp.<tag>.<pid>.<n>, no handler
 * ran) is removed by the next write of the same output, once its process is gone (issue "Hardening",
 * Signals): through the library's atomic file, through ic_atomic_temp_name (the EXR writer's path), and
 * through the command. A temporary of a live process, of another output, or a name not of the form is left
 * alone; so is one whose tag is another machine's or pid namespace's (its pid is not one this process can
 * see: a folder shared over NFS, two containers), one of the older form without a tag, and any when the tag
 * cannot be known (no /proc).
 *
 * An output that is a symbolic link is written through it: the link stays; one that is a pipe, a device or a
 * folder is refused, never replaced.
 *
 * Every atomic write syncs its temporary (fsync, wrapped here: -Wl,--wrap=fsync) before the rename, so a
 * crash after it cannot leave an empty file under the final name: the atomic file and the EXR writer.
 *
 * A file replaced keeps its permission bits (less setuid and setgid) and, where the writer may, its owner
 * and group, as sed -i and editors keep them: a private 0600 output took 0666 & ~umask from its
 * replacement. A new file takes 0666 & ~umask.
 *
 * A file whose name is legal but too long for the temporary's tail (a 250-byte name: NAME_MAX is 255) is
 * written through a shortened temporary beside it; the stale ones a dead process left are still found.
 */
#include "core/atomic_file.h"
#include "irrcache/image.h"
#include "test_util.h"
#include "test_files.h"

#include <errno.h>
#include <fcntl.h>
#include <grp.h>
#include <limits.h>
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

/* readlink, which plays another pid namespace (1: /proc/self/ns/pid reads another inode) or one without /proc
 * (2: it cannot be read) when fake_pid_ns says so. */
ssize_t __real_readlink(const char *path, char *buf, size_t size);
ssize_t __wrap_readlink(const char *path, char *buf, size_t size);
static int fake_pid_ns;

ssize_t __wrap_readlink(const char *path, char *buf, size_t size)
{
    if (fake_pid_ns && !strcmp(path, "/proc/self/ns/pid")) {
        if (fake_pid_ns == 2) {
            errno = ENOENT;
            return -1;
        }
        static const char other[] = "pid:[0]"; /* no namespace has inode 0 */
        size_t n = sizeof other - 1 < size ? sizeof other - 1 : size;
        memcpy(buf, other, n);
        return (ssize_t)n;
    }
    return __real_readlink(path, buf, size);
}

/* The tag of the temporary name tmp (<stem>.tmp.<tag>.<pid>.<n>) into tag (9 bytes), "" when tmp is not of
 * that form or its pid is not pid. */
static const char *tag_of(const char *tmp, long pid, char tag[9])
{
    const char *tail = NULL;
    for (const char *t = strstr(tmp, ".tmp."); t; t = strstr(t + 1, ".tmp."))
        tail = t + 5;
    char *end = NULL;
    tag[0] = 0;
    if (tail && strlen(tail) > 9 && tail[8] == '.' && strspn(tail, "0123456789abcdef") == 8 &&
        strtol(tail + 9, &end, 10) == pid && *end == '.')
        snprintf(tag, 9, "%.8s", tail);
    return tag;
}

/* This process's tag, read from the name ic_atomic_temp_name gives (the temporary removed again). */
static const char *own_tag(char tag[9])
{
    char tmp[4096];
    CHECK(ic_atomic_temp_name(IC_TEST_TMP "/atomic_file/tag.pfm", tmp, sizeof tmp) == 0, "a temporary name");
    remove(tmp);
    ic_atomic_temp_release(tmp);
    CHECK(*tag_of(tmp, (long)getpid(), tag), "the temporary's name is <out>.tmp.<8 hex digits>.<pid>.<n>: %s", tmp);
    return tag;
}

/* A tag not this process's: its first digit changed. */
static const char *other_tag(const char *tag, char other[9])
{
    snprintf(other, 9, "%c%s", tag[0] == 'f' ? '0' : 'f', tag + 1);
    return other;
}

#define KEEP 6
/* Leaves the temporaries of out: a dead process's of this tag (two), a live one's, another output's, odd
 * names, a dead pid of another tag (another machine's or pid namespace's: alive there, perhaps) and one of the
 * older form without a tag (which says no machine). */
static void leave(const char *out, long dead, char stale[2][512], char keep[KEEP][512])
{
    char tag[9], other[9];
    own_tag(tag);
    snprintf(stale[0], 512, "%s.tmp.%s.%ld.0", out, tag, dead);
    snprintf(stale[1], 512, "%s.tmp.%s.%ld.17", out, tag, dead);
    snprintf(keep[0], 512, "%s.tmp.%s.%ld.0", out, tag, (long)getppid()); /* alive: the test's parent */
    snprintf(keep[1], 512, "%s.other.tmp.%s.%ld.0", out, tag, dead);       /* another output's */
    snprintf(keep[2], 512, "%s.tmp.%s.%ldx.0", out, tag, dead);            /* not <pid>.<n> */
    snprintf(keep[3], 512, "%s.tmp.%s.%ld", out, tag, dead);               /* no counter */
    snprintf(keep[4], 512, "%s.tmp.%s.%ld.0", out, other_tag(tag, other), dead); /* another namespace's */
    snprintf(keep[5], 512, "%s.tmp.%ld.0", out, dead);                     /* the older form, no tag */
    for (int i = 0; i < 2; ++i)
        touch(stale[i]);
    for (int i = 0; i < KEEP; ++i)
        touch(keep[i]);
}

static void check_cleaned(const char *what, char stale[2][512], char keep[KEEP][512])
{
    for (int i = 0; i < 2; ++i)
        CHECK(!exists(stale[i]), "%s: the dead process's %s is removed", what, stale[i]);
    for (int i = 0; i < KEEP; ++i) {
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


/* The permission bits of path (-1 when it cannot be read). */
static int mode_of(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (int)(st.st_mode & 07777) : -1;
}

/* Writes text to path through the atomic file, or a 2x2 image through the EXR writer for a .exr path. */
static ic_result write_out(const char *path, const char *text, ic_error *err)
{
    memset(err, 0, sizeof *err);
    size_t n = strlen(path);
    if (n > 4 && !strcmp(path + n - 4, ".exr")) {
        ic_image img;
        ic_result r = ic_image_create(&img, 2, 2);
        if (r == IC_OK)
            r = ic_image_write(path, &img, NULL, err);
        ic_image_free(&img);
        return r;
    }
    ic_atomic_file f;
    ic_result r = ic_atomic_file_open(&f, path, err);
    if (r == IC_OK) {
        fputs(text, f.fp);
        r = ic_atomic_file_commit(&f, err);
    }
    return r;
}

/* Writes name (relative to folder) as user uid, group gid and, when group is not 0, that group too: a child
 * that drops root's rights; 0 when written. Relative names: the user may not search the folders above. */
static int write_as(const char *folder, const char *name, uid_t uid, gid_t gid, gid_t group)
{
    pid_t child = fork();
    if (child == 0) {
        ic_error err;
        if (chdir(folder) != 0 || setgroups(group ? 1 : 0, &group) != 0 || setgid(gid) != 0 || setuid(uid) != 0)
            _exit(3);
        _exit(write_out(name, "theirs", &err) == IC_OK ? 0 : 4);
    }
    int status = -1;
    return child > 0 && waitpid(child, &status, 0) == child && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/* A replaced file keeps its mode (setuid and setgid dropped) and, as root, its owner and group; a link's
 * target keeps its own; a new file takes 0666 & ~umask. Through the atomic file and the EXR writer. */
static void check_permissions(void)
{
    CHECK(system("mkdir -p '" T "/perm'") == 0, "a folder");
    ic_error err;
    mode_t old_mask = umask(027);
    const char *news[2] = {T "/perm/new.pfm", T "/perm/new.exr"};
    for (int k = 0; k < 2; ++k)
        CHECK(write_out(news[k], "new", &err) == IC_OK && mode_of(news[k]) == (0666 & ~027),
              "%s: a new file takes 0666 & ~umask (umask 027): %o (%s)", news[k], mode_of(news[k]), err.message);
    umask(022);
    const char *olds[5] = {T "/perm/group.pfm", T "/perm/private.pfm", T "/perm/setid.pfm", T "/perm/private.exr",
                           T "/perm/read_only.pfm"};
    const int modes[5] = {0640, 0600, 06750, 0640, 0400}, kept[5] = {0640, 0600, 0750, 0640, 0400};
    for (int k = 0; k < 5; ++k) {
        touch(olds[k]);
        CHECK(chmod(olds[k], (mode_t)modes[k]) == 0, "chmod %s", olds[k]);
        CHECK(write_out(olds[k], "replaced", &err) == IC_OK, "%s: written (%s)", olds[k], err.message);
        CHECK(mode_of(olds[k]) == kept[k], "%s: mode %o kept as %o: %o", olds[k], modes[k], kept[k], mode_of(olds[k]));
    }
    char text[64];
    CHECK(!strcmp(read_small(T "/perm/read_only.pfm", text, sizeof text), "replaced"), "0400: replaced: '%s'", text);
    /* through a link: the mode of the file it leads to, the link stays */
    touch(T "/perm/target.pfm");
    CHECK(chmod(T "/perm/target.pfm", 0600) == 0 && symlink("target.pfm", T "/perm/link.pfm") == 0, "a link");
    struct stat ls;
    CHECK(write_out(T "/perm/link.pfm", "through", &err) == IC_OK && mode_of(T "/perm/target.pfm") == 0600 &&
              lstat(T "/perm/link.pfm", &ls) == 0 && S_ISLNK(ls.st_mode),
          "through a link: the target keeps 0600: %o (%s)", mode_of(T "/perm/target.pfm"), err.message);
    CHECK(test_count_temporaries(T "/perm") == 0, "no temporary left");
    /* As root, the owner and group are kept too (root in a container may lack the right to give files away). */
    touch(T "/perm/theirs.pfm");
    if (geteuid() != 0 || chown(T "/perm/theirs.pfm", 12345, 12346) != 0) {
        printf("not root (or may not give files away): owners and groups are not checked\n");
        umask(old_mask);
        return;
    }
    struct stat st;
    CHECK(chmod(T "/perm/theirs.pfm", 0640) == 0, "chmod");
    CHECK(write_out(T "/perm/theirs.pfm", "root", &err) == IC_OK && stat(T "/perm/theirs.pfm", &st) == 0 &&
              st.st_uid == 12345 && st.st_gid == 12346 && (st.st_mode & 07777) == 0640,
          "as root: owner, group and mode kept: %ld:%ld %o (%s)", (long)st.st_uid, (long)st.st_gid,
          (unsigned)(st.st_mode & 07777), err.message);
    /* Another user (not root) who may write the folder: the owner becomes the writer, who holds the owner's
     * bits alone. In the file's group, the writer keeps the group (0660 stays 0660, group 12346); not in it,
     * the writer's own group must not get the old group's access: it gets what the file gave everyone,
     * nothing here (0660 becomes 0600; 0664, 0644). */
    CHECK(system("mkdir -p '" T "/perm/open' && chmod 0777 '" T "/perm/open'") == 0, "an open folder");
    const char *shared[3] = {"member.pfm", "outsider.pfm", "outsider_r.pfm"};
    const int shared_mode[3] = {0660, 0660, 0664}, shared_kept[3] = {0660, 0600, 0644};
    const gid_t shared_gid[3] = {12346, 23457, 23457};
    for (int k = 0; k < 3; ++k) {
        char p[512];
        snprintf(p, sizeof p, T "/perm/open/%s", shared[k]);
        touch(p);
        CHECK(chown(p, 12345, 12346) == 0 && chmod(p, (mode_t)shared_mode[k]) == 0, "chown");
        int status = write_as(T "/perm/open", shared[k], 23456, 23457, k == 0 ? 12346 : 0);
        CHECK(status == 0, "%s: another user writes (status %d)", shared[k], status);
        CHECK(stat(p, &st) == 0 && st.st_uid == 23456 && st.st_gid == shared_gid[k] &&
                  (st.st_mode & 07777) == (mode_t)shared_kept[k],
              "%s: %o by another user: %ld:%ld %o, expected 23456:%ld %o", shared[k], shared_mode[k], (long)st.st_uid,
              (long)st.st_gid, (unsigned)(st.st_mode & 07777), (long)shared_gid[k], shared_kept[k]);
    }
    umask(old_mask);
}

/* The temporary is opened again by name at the rename, to take the old file's permissions: one that someone
 * who may write the folder replaced meanwhile with a link (symbolic or hard) to another file is refused, and
 * that file keeps its mode (given the old file's 0666 before) and its bytes; a pipe put there does not hold
 * the write up. The output is left as it was, no temporary stays. */
static void check_replaced_temporary(void)
{
    CHECK(system("mkdir -p '" T "/swap'") == 0, "a folder");
    const char *out = T "/swap/out.pfm", *victim = T "/swap/victim.txt";
    ic_error err;
    char tmp[4096], text[64];
    CHECK(write_out(out, "old", &err) == IC_OK && chmod(out, 0666) == 0, "the output (%s)", err.message);
    touch(victim);
    CHECK(chmod(victim, 0600) == 0, "chmod %s", victim);
    const char *how[3] = {"a symbolic link", "a hard link", "a pipe"};
    for (int k = 0; k < 3; ++k) {
        CHECK(ic_atomic_temp_name(out, tmp, sizeof tmp) == 0 && remove(tmp) == 0, "a temporary");
        CHECK((k == 0 ? symlink(victim, tmp) : k == 1 ? link(victim, tmp) : mkfifo(tmp, 0600)) == 0, "%s: %s",
              how[k], strerror(errno));
        memset(&err, 0, sizeof err);
        alarm(10); /* a pipe opened for reading would wait for a writer */
        ic_result r = ic_atomic_rename(tmp, out, &err);
        alarm(0);
        struct stat st;
        CHECK(r == IC_ERR_IO && strstr(err.message, "replaced during the write"), "%s in its place: refused: %s",
              how[k], err.message);
        CHECK(mode_of(victim) == 0600 && !strcmp(read_small(victim, text, sizeof text), "half-written"),
              "%s in its place: the file it leads to keeps its mode 0600: %o", how[k], mode_of(victim));
        CHECK(lstat(out, &st) == 0 && S_ISREG(st.st_mode) && !strcmp(read_small(out, text, sizeof text), "old"),
              "%s in its place: the output is not replaced: '%s'", how[k], text);
    }
    /* The same through a descriptor (/dev/stdout sent to a file): the temporary is read back by name and its
     * bytes written to the descriptor, so a link in its place sent the victim's contents there. */
    const char *log_path = T "/swap/log.txt", *fd_out = T "/swap/log.pfm";
    FILE *lf = fopen(log_path, "w");
    CHECK(lf && fclose(lf) == 0, "a log");
    int lfd = open(log_path, O_WRONLY | O_APPEND);
    char fd_link[64];
    snprintf(fd_link, sizeof fd_link, "/proc/self/fd/%d", lfd);
    CHECK(lfd >= 0 && symlink(fd_link, fd_out) == 0, "a link through /proc/self/fd to a file");
    CHECK(ic_atomic_temp_name(fd_out, tmp, sizeof tmp) == 0 && remove(tmp) == 0, "a temporary");
    CHECK(symlink(victim, tmp) == 0, "a symbolic link in its place: %s", strerror(errno));
    memset(&err, 0, sizeof err);
    ic_result r = ic_atomic_rename(tmp, fd_out, &err);
    close(lfd);
    CHECK(r == IC_ERR_IO && strstr(err.message, "replaced during the write"), "through a descriptor, a link in "
          "the temporary's place: refused: %s", err.message);
    CHECK(!strcmp(read_small(log_path, text, sizeof text), ""), "the descriptor's file got nothing: '%s'", text);
    remove(fd_out);
    CHECK(test_count_temporaries(T "/swap") == 0, "no temporary left");
}

/* A name of 250 bytes (legal: NAME_MAX is 255) is written although "<name>.tmp.<tag>.<pid>.<n>" is longer
 * than a name may be: the temporary's name is shortened, beside the file. Through the atomic file and the EXR
 * writer; no temporary is left, and a dead process's shortened temporary is removed by the next write of the
 * same file, not of another long name that begins alike. A name over NAME_MAX is refused at the open. */
static void check_long_names(long dead)
{
    CHECK(system("mkdir -p '" T "/long'") == 0, "a folder");
    char names[3][512], tag[9], other[9];
    own_tag(tag);
    other_tag(tag, other);
    for (int k = 0; k < 3; ++k) {
        char base[256];
        memset(base, 'a' + k, sizeof base);
        snprintf(base + 246, 10, k == 2 ? "b.exr" : "b.pfm");
        if (k == 1)
            base[245] = 'c'; /* begins as names[0] does */
        memset(base, 'a', 240);
        snprintf(names[k], sizeof names[k], T "/long/%s", base);
    }
    CHECK(strlen(strrchr(names[0], '/') + 1) == 251, "a 251-byte name: %zu", strlen(strrchr(names[0], '/') + 1));
    ic_error err;
    char text[64];
    for (int k = 0; k < 3; ++k) {
        CHECK(write_out(names[k], "long", &err) == IC_OK, "a 251-byte name is written (%s)", err.message);
        if (k < 2)
            CHECK(!strcmp(read_small(names[k], text, sizeof text), "long"), "and reads back: '%s'", text);
        else
            CHECK(mode_of(names[k]) >= 0, "the EXR is there");
    }
    CHECK(test_count_temporaries(T "/long") == 0, "no temporary left: %d", test_count_temporaries(T "/long"));
    /* The shortened temporaries of the two .pfm names, as a dead process would have left them; and one of
     * another tag (a dead pid here, perhaps a live one where it was written), which stays. */
    char tmp[2][4096], stale[2][4200], foreign[4200];
    for (int k = 0; k < 2; ++k) {
        CHECK(ic_atomic_temp_name(names[k], tmp[k], sizeof tmp[k]) == 0, "a temporary name");
        remove(tmp[k]);
        ic_atomic_temp_release(tmp[k]);
        const char *tmp_base = strrchr(tmp[k], '/') + 1;
        CHECK(strlen(tmp_base) <= NAME_MAX && strstr(tmp_base, ".tmp."), "a temporary name of at most NAME_MAX: %s",
              tmp_base);
        char *tail = strstr(tmp[k], ".tmp.");
        CHECK(!strcmp(tag_of(tmp[k], (long)getpid(), text), tag), "the shortened name has the tag: %s", tmp_base);
        snprintf(stale[k], sizeof stale[k], "%.*s.tmp.%s.%ld.3", (int)(tail - tmp[k]), tmp[k], tag, dead);
        touch(stale[k]);
        if (k == 0) {
            snprintf(foreign, sizeof foreign, "%.*s.tmp.%s.%ld.3", (int)(tail - tmp[k]), tmp[k], other, dead);
            touch(foreign);
        }
    }
    ic_result r;
    CHECK(strcmp(tmp[0], tmp[1]) != 0, "two long names that begin alike have distinct temporaries");
    CHECK(write_out(names[0], "again", &err) == IC_OK, "rewrite (%s)", err.message);
    CHECK(!exists(stale[0]) && exists(stale[1]), "the dead process's temporary of this name is removed, the other "
          "name's is kept");
    CHECK(exists(foreign) && remove(foreign) == 0, "another tag's temporary of this name is kept");
    CHECK(write_out(names[1], "again", &err) == IC_OK && !exists(stale[1]), "and the other's by its own write");
    /* A shortened temporary cannot say its file: that is the one the path leads to at the rename. A link
     * changed during the write to lead to another file is refused, nothing written; a name that fits still
     * says its file, the one the link led to when the write began (as before). */
    CHECK(symlink(names[0], T "/long/relink.pfm") == 0, "a link to a long name");
    ic_atomic_file lf;
    CHECK(ic_atomic_file_open(&lf, T "/long/relink.pfm", &err) == IC_OK, "open through the link (%s)", err.message);
    if (lf.fp)
        fputs("relinked", lf.fp);
    CHECK(remove(T "/long/relink.pfm") == 0 && symlink(names[1], T "/long/relink.pfm") == 0, "the link changed");
    memset(&err, 0, sizeof err);
    r = ic_atomic_file_commit(&lf, &err);
    CHECK(r == IC_ERR_IO && strstr(err.message, "changed during the write"), "refused: %s", err.message);
    CHECK(!strcmp(read_small(names[0], text, sizeof text), "again") &&
              !strcmp(read_small(names[1], text, sizeof text), "again"), "neither file is written");
    touch(T "/long/short_a.pfm");
    CHECK(remove(T "/long/relink.pfm") == 0 && symlink("short_a.pfm", T "/long/relink.pfm") == 0, "a short link");
    CHECK(ic_atomic_file_open(&lf, T "/long/relink.pfm", &err) == IC_OK, "open through the link (%s)", err.message);
    if (lf.fp)
        fputs("relinked", lf.fp);
    CHECK(remove(T "/long/relink.pfm") == 0 && symlink("short_b.pfm", T "/long/relink.pfm") == 0, "the link changed");
    CHECK(ic_atomic_file_commit(&lf, &err) == IC_OK && !strcmp(read_small(T "/long/short_a.pfm", text, sizeof text),
          "relinked") && !exists(T "/long/short_b.pfm"), "the file the link led to is written: '%s'", text);
    /* 256 bytes: no file may have that name; refused before anything is written. */
    char over[600];
    snprintf(over, sizeof over, "%s", names[0]);
    char *base = strrchr(over, '/') + 1;
    memset(base, 'z', 256);
    base[256] = 0;
    ic_atomic_file f;
    memset(&err, 0, sizeof err);
    r = ic_atomic_file_open(&f, over, &err);
    if (r == IC_OK)
        ic_atomic_file_abort(&f);
    CHECK(r == IC_ERR_IO && strstr(err.message, "too long") && strstr(err.message, "use a shorter name"),
          "a 256-byte name is refused, saying what to do: %s", err.message);
    CHECK(test_count_temporaries(T "/long") == 0, "no temporary left");
}

/* Two writers of one output that cannot see each other's pids: another machine sharing the folder (NFS) or
 * another pid namespace (a container), played by a child whose /proc/self/ns/pid reads another inode. Its
 * temporary, under a pid that is dead here, survives this process's write of the output (which deleted it,
 * and so the other writer's output, when a pid alone judged it), and its rename still succeeds. A child
 * without /proc (the namespace cannot be known) removes nothing, not even a dead pid's of its own tag. */
static void check_other_namespace(long dead)
{
    const char *out = T "/shared.pfm";
    char tmp[4096], tag[9], theirs[9], text[64];
    own_tag(tag);
    int fds[2];
    CHECK(pipe(fds) == 0, "pipe");
    pid_t child = fork();
    if (child == 0) { /* the other writer: creates its temporary, writes, and is gone from this namespace */
        close(fds[0]);
        fake_pid_ns = 1;
        int made = ic_atomic_temp_name(out, tmp, sizeof tmp);
        FILE *tf = made == 0 ? fopen(tmp, "wb") : NULL;
        int ok = tf && fputs("theirs", tf) >= 0 && fclose(tf) == 0;
        _exit(ok && write(fds[1], tmp, strlen(tmp) + 1) == (ssize_t)strlen(tmp) + 1 ? 0 : 1);
    }
    close(fds[1]);
    memset(tmp, 0, sizeof tmp);
    ssize_t got = child > 0 ? read(fds[0], tmp, sizeof tmp - 1) : -1;
    close(fds[0]);
    int status = -1;
    CHECK(child > 0 && waitpid(child, &status, 0) == child && WIFEXITED(status) && WEXITSTATUS(status) == 0 &&
              got > 0, "the other namespace's writer made its temporary");
    CHECK(*tag_of(tmp, (long)child, theirs) && strcmp(theirs, tag) != 0, "another pid namespace has another tag: "
          "%s (this one's %s)", tmp, tag);
    CHECK(kill(child, 0) != 0 && errno == ESRCH, "its pid %ld is dead here", (long)child);
    ic_error err;
    CHECK(write_out(out, "ours", &err) == IC_OK, "this process writes the output (%s)", err.message);
    CHECK(exists(tmp), "the other namespace's temporary is kept: %s", tmp);
    memset(&err, 0, sizeof err);
    CHECK(ic_atomic_rename(tmp, out, &err) == IC_OK && !strcmp(read_small(out, text, sizeof text), "theirs"),
          "and its rename succeeds: '%s' (%s)", text, err.message);

    /* No /proc: the tag says the host only, so even a dead pid of the same tag may be another container's. */
    child = fork();
    if (child == 0) {
        fake_pid_ns = 2;
        char mine[4096], fallback[9], left[4200];
        ic_error cerr;
        if (ic_atomic_temp_name(out, mine, sizeof mine) != 0 || !*tag_of(mine, (long)getpid(), fallback))
            _exit(1);
        remove(mine);
        ic_atomic_temp_release(mine);
        snprintf(left, sizeof left, "%s.tmp.%s.%ld.0", out, fallback, dead);
        touch(left);
        if (write_out(out, "no proc", &cerr) != IC_OK)
            _exit(2);
        int kept = exists(left);
        remove(left);
        _exit(kept ? 0 : 3);
    }
    CHECK(child > 0 && waitpid(child, &status, 0) == child && WIFEXITED(status) && WEXITSTATUS(status) == 0,
          "without /proc, a dead pid's temporary of the same tag is kept (status %d)",
          WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    CHECK(!strcmp(read_small(out, text, sizeof text), "no proc"), "and the output is written: '%s'", text);
    CHECK(test_count_temporaries(T) == 0, "no temporary left");
}

int main(void)
{
    CHECK(system("rm -rf '" T "' && mkdir -p '" T "'") == 0, "make %s", T);
    long dead = dead_pid();
    char stale[2][512], keep[KEEP][512];

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

    /* A link planted at the temporary's name, which is predictable (<path>.tmp.<tag>.<pid>.<n>; another user's, in
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

    check_permissions();
    check_replaced_temporary();
    check_long_names(dead);
    check_other_namespace(dead);

    /* the command: a rerun after a SIGKILL during its write */
    leave(T "/render.png", dead, stale, keep);
    int st = system(CLI " render " QUAD " -o " T "/render.png --width 4 --height 4 --spp 1 -q");
    CHECK(st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 0, "render");
    CHECK(exists(T "/render.png"), "the image is written");
    check_cleaned("irrcache render", stale, keep);
    TEST_MAIN_END();
}
