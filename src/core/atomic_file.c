/* atomic_file.c — temporary file + rename (atomic_file.h). */
#include "atomic_file.h"
#include "path.h"
#include "hash.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static atomic_uint tmp_counter;

/* Temporary names in use, for ic_remove_temporary_files, which a signal handler may call: fixed slots
 * (no allocation), a slot's name complete before its state says so, lock-free atomics only (the
 * operations C11 7.14.1.1 and POSIX allow in a handler). */
#define TEMP_SLOTS 64
enum { SLOT_FREE, SLOT_CLAIMED, SLOT_READY };
static atomic_int slot_state[TEMP_SLOTS];
static char slot_name[TEMP_SLOTS][4096];

static void temp_register(const char *name)
{
    if (strlen(name) >= sizeof slot_name[0])
        return;
    for (int k = 0; k < TEMP_SLOTS; ++k) {
        int expected = SLOT_FREE;
        if (atomic_compare_exchange_strong(&slot_state[k], &expected, SLOT_CLAIMED)) {
            memcpy(slot_name[k], name, strlen(name) + 1);
            atomic_store(&slot_state[k], SLOT_READY);
            return;
        }
    }
    /* All slots busy (64 files being written at once): this one is simply not cleaned up by a signal. */
}

void ic_atomic_temp_release(const char *tmp)
{
    for (int k = 0; k < TEMP_SLOTS; ++k) {
        if (atomic_load(&slot_state[k]) == SLOT_READY && !strcmp(slot_name[k], tmp)) {
            atomic_store(&slot_state[k], SLOT_FREE);
            return;
        }
    }
}

void ic_remove_temporary_files(void)
{
    for (int k = 0; k < TEMP_SLOTS; ++k)
        if (atomic_load(&slot_state[k]) == SLOT_READY)
            (void)unlink(slot_name[k]);
}

/* The tag in a temporary's name: TAG_LEN lower-case hex digits that say which machine (boot) and pid
 * namespace wrote it, so that its pid is read where it means something (machine_tag). */
#define TAG_LEN 8
/* The longest tail a temporary's name adds: ".tmp.", the tag, ".", a pid and ".", a counter (up to 10 digits
 * each). */
#define TEMP_TAIL_MAX (5 + TAG_LEN + 1 + 10 + 1 + 10)
/* What a shortened name ends in: "~" and 16 hex digits of a hash of the whole name. */
#define SHORT_MARK 17

/* Whether the n bytes at s are all lower-case hex digits. */
static int is_hex(const char *s, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
            return 0;
    return 1;
}

/* This process's tag (TAG_LEN hex digits and a NUL, into tag): a hash of this boot of this machine's kernel
 * (/proc/sys/kernel/random/boot_id, random at each boot) and of this process's pid namespace
 * (/proc/self/ns/pid, "pid:[inode]", unique within that boot). A pid means a process only there: another
 * machine sharing the folder (NFS) or a container with its own pid namespace has pids this process cannot
 * see, so their temporaries must never be judged by kill(pid, 0). 1 when both were read; 0 when one could not
 * be (no /proc): the tag is then a hash of the host name, which two machines or containers may share, so no
 * temporary can be known to be this namespace's, and none is removed. */
static int machine_tag(char tag[TAG_LEN + 1])
{
    char boot[64], ns[64], host[256];
    int fd = open("/proc/sys/kernel/random/boot_id", O_RDONLY | O_CLOEXEC);
    ssize_t boot_len = fd >= 0 ? read(fd, boot, sizeof boot) : -1;
    if (fd >= 0)
        close(fd);
    ssize_t ns_len = readlink("/proc/self/ns/pid", ns, sizeof ns);
    int known = boot_len > 0 && ns_len > 0;
    uint64_t hash = IC_FNV64_OFFSET;
    if (known)
        hash = ic_fnv1a64(ic_fnv1a64(hash, boot, (size_t)boot_len), ns, (size_t)ns_len);
    else if (gethostname(host, sizeof host) == 0)
        hash = ic_fnv1a64(hash, host, strnlen(host, sizeof host));
    snprintf(tag, TAG_LEN + 1, "%08x", (unsigned)(hash ^ hash >> 32));
    return known;
}

/* The pid in a temporary name's tail "<tag>.<pid>.<n>" (a tag, then digits only), or 0 if the tail is not of
 * that form (an older "<pid>.<n>" is not). */
static long temp_pid(const char *tail)
{
    if (!is_hex(tail, TAG_LEN) || tail[TAG_LEN] != '.')
        return 0;
    tail += TAG_LEN + 1;
    const char *dot = strchr(tail, '.');
    if (!dot || dot == tail || dot - tail > 10 || !dot[1])
        return 0;
    for (const char *c = tail; *c; ++c)
        if (c != dot && (*c < '0' || *c > '9'))
            return 0;
    long pid = strtol(tail, NULL, 10);
    return pid > 0 && pid <= INT_MAX ? pid : 0;
}

/* The longest name a file in dir may have: its file system's (pathconf; eCryptfs takes 143 bytes), at most
 * NAME_MAX (255 bytes), NAME_MAX where the folder cannot say. */
static size_t name_max_in(const char *dir)
{
    long n = pathconf(dir, _PC_NAME_MAX);
    return n > 0 && n < NAME_MAX ? (size_t)n : NAME_MAX;
}

/* The temporaries' names of the file target are <stem>.tmp.<tag>.<pid>.<n>; the stem is target itself or, where
 * its name and that tail could exceed the longest name its folder takes (a legal 240-byte name: the open
 * failed with ENAMETOOLONG, so the file could not be written at all), target's folder and its name cut at a
 * UTF-8 character's start, then "~" and 16 hex digits of a hash (FNV-1a) of the whole name, so that two long
 * names that begin alike keep apart. The folder stays (the rename must stay on one file system); only target
 * decides the stem, never the process, so the temporaries a dead process left are found by it. 0, or
 * ENAMETOOLONG when target's own name is too long for its folder: refused now, not at the rename after all
 * the work. */
static int temp_stem(const char *target, char *out, size_t out_size)
{
    const char *slash = strrchr(target, '/');
    const char *base = slash ? slash + 1 : target;
    size_t base_len = strlen(base), name_max;
    char dir[4096];
    ic_path_dirname(target, dir, sizeof dir);
    name_max = name_max_in(dir);
    if (base_len > name_max)
        return ENAMETOOLONG;
    if (base_len + TEMP_TAIL_MAX <= name_max || name_max <= TEMP_TAIL_MAX + SHORT_MARK)
        return snprintf(out, out_size, "%s", target) < (int)out_size ? 0 : ENAMETOOLONG;
    size_t keep = name_max - TEMP_TAIL_MAX - SHORT_MARK;
    while (keep > 0 && ((unsigned char)base[keep] & 0xC0) == 0x80) /* a UTF-8 continuation byte */
        --keep;
    uint64_t hash = ic_fnv1a64(IC_FNV64_OFFSET, base, base_len);
    return snprintf(out, out_size, "%.*s%.*s~%016llx", (int)(base - target), target, (int)keep, base,
                    (unsigned long long)hash) < (int)out_size ? 0 : ENAMETOOLONG;
}

/* Whether stem is a shortened one (temp_stem): it ends in "~" and 16 lower-case hex digits. */
static int is_shortened(const char *stem)
{
    size_t n = strlen(stem);
    return n >= SHORT_MARK && stem[n - SHORT_MARK] == '~' && is_hex(stem + n - SHORT_MARK + 1, SHORT_MARK - 1);
}

/* Removes the temporaries of the file whose stem (temp_stem) is stem that a dead process of this machine and
 * pid namespace (tag, machine_tag) left beside it: a SIGKILL (or a crash) during a write runs no handler, so
 * <stem>.tmp.<tag>.<pid>.<n> stays. One is stale when it has this tag and no process has its pid (kill(pid, 0)
 * fails with ESRCH); a live pid keeps its file, even if the pid was reused, so a concurrent writer of the same
 * output in this namespace is never disturbed. Another tag's temporaries are left alone: their pids are another
 * machine's (a folder shared over NFS) or another pid namespace's (a container), which kill cannot see, so
 * they cannot be known dead; their writer may be writing them now. So are temporaries of the older form
 * <stem>.tmp.<pid>.<n>, which say no machine, and those a boot before this one left (its boot id is gone).
 * Only regular files named exactly so are removed: a shortened stem finds the shortened names it gave. */
static void remove_stale_temporaries(const char *stem, const char *tag)
{
    const char *slash = strrchr(stem, '/');
    const char *base = slash ? slash + 1 : stem;
    char dir[4096];
    if (strlen(stem) >= sizeof dir)
        return;
    ic_path_dirname(stem, dir, sizeof dir);
    size_t base_len = strlen(base);
    DIR *d = base_len ? opendir(dir) : NULL;
    if (!d)
        return;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        if (strncmp(e->d_name, base, base_len) != 0 || strncmp(e->d_name + base_len, ".tmp.", 5) != 0 ||
            strncmp(e->d_name + base_len + 5, tag, TAG_LEN) != 0)
            continue;
        long pid = temp_pid(e->d_name + base_len + 5);
        if (pid == 0 || pid == (long)getpid() || kill((pid_t)pid, 0) == 0 || errno != ESRCH)
            continue;
        char full[8192];
        struct stat st;
        if (snprintf(full, sizeof full, "%s/%s", dir, e->d_name) < (int)sizeof full && lstat(full, &st) == 0 &&
            S_ISREG(st.st_mode))
            (void)unlink(full);
    }
    closedir(d);
}

/* Linux's fs.protected_symlinks rule, which the kernel applies when it follows a link itself and which a
 * link read with readlink would bypass: in a sticky folder anyone may write to (/tmp), a link is followed
 * only if this process or the folder's owner owns it. Otherwise another user's link /tmp/out.exr ->
 * /etc/passwd would have a root render replace /etc/passwd. */
static int may_follow(const char *link_path, const struct stat *link)
{
    char dir[4096];
    struct stat ds;
    ic_path_dirname(link_path, dir, sizeof dir);
    if (stat(dir, &ds) != 0 || !(ds.st_mode & S_ISVTX) || !(ds.st_mode & S_IWOTH))
        return 1;
    return link->st_uid == geteuid() || link->st_uid == ds.st_uid;
}

/* The descriptor a link in this process's /proc/<pid>/fd (or a thread's) stands for, or -1: /dev/stdout and
 * /dev/fd/N lead through one. */
static int descriptor_of(const char *link_path)
{
    char dir[4096], real[4096], own[64];
    const char *base = strrchr(link_path, '/');
    ic_path_dirname(link_path, dir, sizeof dir);
    if (!base || !realpath(dir, real))
        return -1;
    int len = snprintf(own, sizeof own, "/proc/%ld/", (long)getpid());
    size_t n = strlen(real);
    if (strncmp(real, own, (size_t)len) != 0 || n < 3 || strcmp(real + n - 3, "/fd") != 0 ||
        (n != (size_t)len + 2 && strncmp(real + len, "task/", 5) != 0))
        return -1;
    char *end = NULL;
    long fd = strtol(base + 1, &end, 10);
    return base[1] >= '0' && base[1] <= '9' && !*end && fd <= INT_MAX ? (int)fd : -1;
}

/* Symbolic links are followed (as a shell's > and fopen do, and git's lock files): renaming the temporary
 * onto the link itself would replace the link with a file, leaving its target as it was (an output
 * "latest.exr" linked to this version's file) or, run as root with stdout redirected to a file, turning
 * /dev/stdout (a link through /proc/self/fd/1) into a plain file for every later process. *descriptor
 * (if not NULL) is the descriptor of this process the links lead through, or -1. */
static int follow_links(const char *path, char *out, size_t out_size, int *descriptor)
{
    if (descriptor)
        *descriptor = -1;
    if (snprintf(out, out_size, "%s", path) >= (int)out_size)
        return ENAMETOOLONG;
    for (int hops = 0;; ++hops) {
        struct stat st;
        if (lstat(out, &st) != 0 || !S_ISLNK(st.st_mode))
            return 0; /* a file, a folder, or nothing yet: the name to write */
        if (hops == 40) /* SYMLOOP_MAX's usual value */
            return ELOOP;
        if (!may_follow(out, &st))
            return EACCES;
        if (descriptor && *descriptor < 0)
            *descriptor = descriptor_of(out);
        char link[4096];
        ssize_t n = readlink(out, link, sizeof link - 1);
        if (n < 0)
            return errno;
        link[n] = '\0';
        /* A relative target is relative to the link's folder. */
        const char *slash = strrchr(out, '/');
        int dir_len = link[0] == '/' || !slash ? 0 : (int)(slash - out + 1);
        char next[4096];
        if (snprintf(next, sizeof next, "%.*s%s", dir_len, out, link) >= (int)sizeof next ||
            snprintf(out, out_size, "%s", next) >= (int)out_size)
            return ENAMETOOLONG;
    }
}

int ic_atomic_target(const char *path, char *out, size_t out_size)
{
    return follow_links(path, out, out_size, NULL);
}

/* The file writing path replaces, into target (4096 bytes): a loop of links or a target too long to name
 * gives the link's own name (the open or rename says why it fails). */
static void temp_target(const char *path, char *target)
{
    if (ic_atomic_target(path, target, 4096) != 0 || strlen(target) + TEMP_TAIL_MAX >= 4096)
        snprintf(target, 4096, "%s", path);
}

/* Names and creates the temporary of path, beside the file it leads to: <stem>.tmp.<tag>.<pid>.<n>
 * (temp_stem, machine_tag), created exclusively (O_EXCL), so that what already has the name is never opened:
 * the name is predictable, and a link planted there (another user's, in a shared folder such as /tmp, where
 * fs.protected_symlinks may be off) would have had the output written into the file it leads to. A name taken
 * is passed over. The descriptor, or -1 with errno (nothing created, out not registered). */
static int create_temp(const char *path, char *out, size_t out_size)
{
    char target[4096], stem[4096];
    temp_target(path, target);
    int e = temp_stem(target, stem, sizeof stem);
    if (e != 0) {
        errno = e;
        return -1;
    }
    char tag[TAG_LEN + 1];
    if (machine_tag(tag))
        remove_stale_temporaries(stem, tag);
    /* Replacing a file, the temporary is its owner's alone until it takes that file's permissions
     * (keep_permissions): created readable by others, it could be opened by someone the file kept out, who
     * would then read what is written. A new file takes 0666 & ~umask, as fopen gives. */
    struct stat old;
    mode_t mode = lstat(target, &old) == 0 && S_ISREG(old.st_mode) ? 0600 : 0666;
    for (int tries = 0;; ++tries) {
        unsigned n = atomic_fetch_add(&tmp_counter, 1u);
        if (snprintf(out, out_size, "%s.tmp.%s.%ld.%u", stem, tag, (long)getpid(), n) >= (int)out_size) {
            errno = ENAMETOOLONG;
            return -1;
        }
        temp_register(out); /* before it exists: a signal from now on removes it */
        int fd = open(out, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
        int e = errno;
        if (fd >= 0)
            return fd;
        ic_atomic_temp_release(out);
        errno = e;
        if (e != EEXIST || tries == 63)
            return -1;
    }
}

int ic_atomic_temp_name(const char *path, char *out, size_t out_size)
{
    int fd = create_temp(path, out, out_size);
    if (fd < 0)
        return errno;
    close(fd);
    return 0;
}

/* The file a temporary takes the place of: its name less ".tmp.<tag>.<pid>.<n>" (ic_atomic_temp_name), which
 * is path or, when path is a symbolic link, the file it led to when the write began. A shortened name
 * (temp_stem) cannot say its file: that is the one path leads to now, whose stem it must be. 0, or -1 when
 * it is not (path's link was changed during the write to lead elsewhere). */
static int final_name(const char *tmp, const char *path, char *out, size_t out_size)
{
    const char *tail = NULL;
    for (const char *t = strstr(tmp, ".tmp."); t; t = strstr(t + 1, ".tmp."))
        tail = t;
    if (!tail || !temp_pid(tail + 5)) {
        snprintf(out, out_size, "%s", path);
        return 0;
    }
    snprintf(out, out_size, "%.*s", (int)(tail - tmp), tmp);
    if (!is_shortened(out))
        return 0;
    char target[4096], stem[4096];
    temp_target(path, target);
    if (temp_stem(target, stem, sizeof stem) != 0 || strcmp(stem, out) != 0)
        return -1;
    snprintf(out, out_size, "%s", target);
    return 0;
}

/* Refuses to put a file in the place of something that is not one (dest: the name the temporary would take,
 * path: the caller's, for the message). A rename over a device, pipe or socket replaces the node itself:
 * run as root, an image or cache written to /dev/null turned it into a plain file for every later process.
 * A link left at dest is a loop of links, or one too long to follow. */
static ic_result check_replaceable(const char *dest, const char *path, ic_error *err)
{
    struct stat st;
    /* What path leads to as the kernel follows it first: a pipe behind /dev/stdout (/proc/self/fd/1 reads
     * "pipe:[N]") has no name to resolve to. */
    if ((stat(path, &st) != 0 || S_ISREG(st.st_mode)) && (lstat(dest, &st) != 0 || S_ISREG(st.st_mode)))
        return IC_OK;
    if (S_ISDIR(st.st_mode))
        return ic_error_set(err, IC_ERR_IO, "%s: is a folder; give a file name", path);
    if (S_ISLNK(st.st_mode))
        return ic_error_set(err, IC_ERR_IO, "%s: is a symbolic link that cannot be followed (a loop, a target too "
                            "long, or another user's link in a shared folder such as /tmp); give a file name", path);
    return ic_error_set(err, IC_ERR_IO, "%s: is not a regular file (a device, pipe or socket); give a file "
                        "name", path);
}

/* The refusal when what has the temporary's name is no longer the file written (finish_file's 3). */
static ic_result replaced_error(const char *path, ic_error *err)
{
    return ic_error_set(err, IC_ERR_IO, "%s: its temporary file was replaced during the write (a link put in its "
                        "place); nothing was written; write it in a folder only you may write", path);
}

/* tmp's bytes written to descriptor fd at its offset (as a shell's redirection writes them): a file that the
 * process's own descriptor leads to (/dev/stdout sent to a file) is shared with whoever opened it, who may
 * have written to it before ('>>', a script's log) and write after; a rename would replace it, losing the
 * first and sending the second to a file no name leads to. Not atomic: a stream takes what it is given. */
static ic_result write_to_descriptor(const char *tmp, int fd, const char *path, ic_error *err)
{
    /* Read back by name, so guarded as finish_file is: a link put in the temporary's place would have sent
     * the file it leads to (another user's, or any file for root) to the descriptor. */
    int in = open(tmp, O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    struct stat st;
    if (in >= 0 && (fstat(in, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink != 1)) {
        close(in);
        in = -1;
        errno = ELOOP;
    }
    if (in < 0 && errno == ELOOP)
        return replaced_error(path, err);
    if (in < 0)
        return ic_error_set(err, IC_ERR_IO, "%s: write failed (%s); nothing was written", path, strerror(errno));
    char buf[65536];
    unsigned long long done = 0;
    ic_result r = IC_OK;
    for (ssize_t got; r == IC_OK && (got = read(in, buf, sizeof buf)) != 0;) {
        if (got < 0 && errno == EINTR)
            continue;
        for (ssize_t at = 0; r == IC_OK && got > 0 && at < got;) {
            ssize_t put = write(fd, buf + at, (size_t)(got - at));
            if (put < 0 && errno == EINTR)
                continue;
            if (put <= 0)
                r = ic_error_set(err, IC_ERR_IO, "%s: cannot write through descriptor %d (%s) after %llu bytes; give "
                                 "a file name", path, fd, put < 0 ? strerror(errno) : "no progress", done);
            else {
                at += put;
                done += (unsigned long long)put;
            }
        }
        if (got < 0)
            r = ic_error_set(err, IC_ERR_IO, "%s: write failed (%s) after %llu bytes", path, strerror(errno), done);
    }
    close(in);
    return r;
}

/* Gives the temporary (descriptor fd) the permissions of the file old it replaces, as sed -i and editors
 * keep them (a private 0600 output became 0666 & ~umask): its mode less setuid and setgid (a copy must not
 * run as another's program) and, where this process may (root; a group it is in), its owner and group. A
 * temporary left with this process's owner is no more open than the file (the owner's bits reach the writer
 * alone); one left with this process's group would hand the old group's access to another group's members,
 * so the group's bits are cut to what the file gave everyone. Anything the mode still grants beyond that (a
 * file system that ignored fchmod) is an error: the file would be more open than the one it replaces.
 * Access control lists and extended attributes are not copied. 0, or -1 with errno. */
static int keep_permissions(int fd, const struct stat *old)
{
    struct stat now;
    if (fstat(fd, &now) != 0)
        return -1;
    if ((now.st_uid != old->st_uid || now.st_gid != old->st_gid) && fchown(fd, old->st_uid, old->st_gid) != 0)
        (void)fchown(fd, (uid_t)-1, old->st_gid); /* not root: the group, if this process is in it */
    if (fstat(fd, &now) != 0)
        return -1;
    mode_t mode = old->st_mode & (S_ISVTX | S_IRWXU | S_IRWXG | S_IRWXO);
    if (now.st_gid != old->st_gid)
        mode &= ~(mode_t)S_IRWXG | (mode & S_IRWXO) << 3;
    int e = fchmod(fd, mode) != 0 ? errno : EPERM;
    if (fstat(fd, &now) != 0)
        return -1;
    if (now.st_mode & (S_IRWXU | S_IRWXG | S_IRWXO) & ~mode) {
        errno = e;
        return -1;
    }
    return 0;
}

/* The temporary made ready to take the final name: the permissions of the file it replaces (old, NULL for
 * a new file), then its data and those on disk (fsync), so that a crash soon after the rename leaves the old
 * file or the whole new one, not an empty or truncated one (on ext4 and XFS the rename can reach the disk
 * before the data). A file system without fsync (EINVAL, EROFS) is passed over. It is opened again by name,
 * so what has the name must still be a file of one link, not followed: in a folder others may write (not
 * sticky), one could have put a link to their victim in its place (another member's file in a group's
 * folder; as root, any file), which would have taken old's owner and mode (keep_permissions), or a pipe,
 * whose open would wait (O_NONBLOCK). 0; 1 when it cannot be synced, 2 when it cannot take old's
 * permissions, with errno; 3 when it is not a file of one link. */
static int finish_file(const char *tmp, const struct stat *old)
{
    int fd = open(tmp, O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    if (fd < 0)
        return errno == ELOOP ? 3 : 1;
    struct stat st;
    int r = fstat(fd, &st) != 0 ? 1 : !S_ISREG(st.st_mode) || st.st_nlink != 1 ? 3 : 0;
    if (r == 0 && old && keep_permissions(fd, old) != 0)
        r = 2;
    if (r == 0 && fsync(fd) != 0 && errno != EINVAL && errno != EROFS)
        r = 1;
    int e = errno;
    close(fd);
    errno = e;
    return r;
}

/* Removes the temporary tmp and forgets its name. */
static void discard(const char *tmp)
{
    remove(tmp);
    ic_atomic_temp_release(tmp);
}

ic_result ic_atomic_rename(const char *tmp, const char *path, ic_error *err)
{
    char dest[4096];
    if (final_name(tmp, path, dest, sizeof dest) != 0) {
        discard(tmp);
        return ic_error_set(err, IC_ERR_IO, "%s: its symbolic link was changed during the write; nothing was "
                            "written; write it again", path);
    }
    ic_result r = check_replaceable(dest, path, err);
    if (r != IC_OK) {
        discard(tmp);
        return r;
    }
    char target[4096];
    int fd = -1;
    if (follow_links(path, target, sizeof target, &fd) == 0 && fd >= 0) {
        r = write_to_descriptor(tmp, fd, path, err);
        discard(tmp);
        return r;
    }
    struct stat old;
    int failed = finish_file(tmp, lstat(dest, &old) == 0 && S_ISREG(old.st_mode) ? &old : NULL);
    int e = errno;
    if (failed) {
        discard(tmp);
        if (failed == 3)
            return replaced_error(path, err);
        return ic_error_set(err, IC_ERR_IO, failed == 2 ? "%s: cannot give the new file the old one's permissions "
                            "(%s); nothing was written; remove the old file or write to a file system that keeps "
                            "permissions" : "%s: write failed (%s); nothing was written", path, strerror(e));
    }
    if (rename(tmp, dest) != 0) {
        e = errno;
        discard(tmp);
        return ic_atomic_write_error(path, e, err);
    }
    ic_atomic_temp_release(tmp);
    return IC_OK;
}

ic_result ic_atomic_write_error(const char *path, int e, ic_error *err)
{
    if (e == ENAMETOOLONG)
        return ic_error_set(err, IC_ERR_IO, "%s: file name too long (most file systems take a name of up to %d "
                            "bytes, a path of up to %d); use a shorter name", path, NAME_MAX, PATH_MAX - 1);
    return ic_error_set(err, IC_ERR_IO, "%s: cannot write (%s); check that the folder exists and is writable", path,
                        strerror(e));
}

ic_result ic_atomic_file_open(ic_atomic_file *f, const char *path, ic_error *err)
{
    memset(f, 0, sizeof *f);
    if (!path || !*path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "empty output path; give a file name");
    if (strlen(path) + 32 >= sizeof f->path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: output path too long", path);
    snprintf(f->path, sizeof f->path, "%s", path);
    char target[4096];
    if (ic_atomic_target(path, target, sizeof target) != 0)
        snprintf(target, sizeof target, "%s", path);
    ic_result r = check_replaceable(target, path, err);
    if (r != IC_OK)
        return r;
    int fd = create_temp(path, f->tmp_path, sizeof f->tmp_path);
    f->fp = fd >= 0 ? fdopen(fd, "wb") : NULL;
    if (!f->fp) {
        int e = errno;
        if (fd >= 0) {
            close(fd);
            discard(f->tmp_path);
        }
        ic_atomic_write_error(path, e, err);
        errno = e; /* the command's output check says it its own way */
        return IC_ERR_IO;
    }
    return IC_OK;
}

ic_result ic_atomic_file_commit(ic_atomic_file *f, ic_error *err)
{
    if (!f->fp)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: file is not open", f->path);
    int bad = ferror(f->fp);
    if (fclose(f->fp) != 0)
        bad = 1;
    f->fp = NULL;
    if (bad) {
        discard(f->tmp_path);
        return ic_error_set(err, IC_ERR_IO, "%s: write failed (disk full?); nothing was written", f->path);
    }
    return ic_atomic_rename(f->tmp_path, f->path, err);
}

void ic_atomic_file_abort(ic_atomic_file *f)
{
    if (f->fp) {
        fclose(f->fp);
        f->fp = NULL;
        discard(f->tmp_path);
    }
}
