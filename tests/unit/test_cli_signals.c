/*
 * test_cli_signals.c — a signal during the final write leaves no temporary file (issue "Hardening",
 * item 5). The library registers each temporary name while it exists, and ic_remove_temporary_files
 * (async-signal-safe) removes them; the command installs a handler for SIGINT, SIGTERM, SIGHUP and
 * SIGXFSZ that calls it and re-raises the signal. Checked in a child that dies of SIGTERM or SIGINT in
 * the middle of an atomic write (the handler being the command's), and on the command itself killed by
 * SIGXFSZ when its output exceeds a file-size limit.
 */
#include "core/atomic_file.h"
#include "test_util.h"
#include "test_files.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#define DIR_ IC_TEST_TMP "/cli_signals"


static int exists(const char *p)
{
    struct stat s;
    return stat(p, &s) == 0;
}

static void handler(int sig)
{
    ic_remove_temporary_files();
    raise(sig);
}

/* In a child: the command's handler, an atomic write half done (and, with `exr_style`, a second
 * temporary made by name as the OpenEXR writer does), then the signal. */
static void die_while_writing(int sig, int exr_style)
{
    pid_t pid = fork();
    if (pid == 0) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = handler;
        sigemptyset(&sa.sa_mask);
        sa.sa_flags = SA_RESETHAND | SA_NODEFER;
        sigaction(sig, &sa, NULL);
        ic_atomic_file f;
        ic_error err;
        if (ic_atomic_file_open(&f, DIR_ "/out.bin", &err) != IC_OK)
            _exit(3);
        for (int k = 0; k < 1000; ++k)
            fputs("half-written data ", f.fp);
        fflush(f.fp);
        if (exr_style) {
            char tmp[4096];
            ic_atomic_temp_name(DIR_ "/out.exr", tmp, sizeof tmp);
            FILE *g = fopen(tmp, "wb");
            if (g)
                fputs("partial", g), fflush(g);
        }
        raise(sig);
        _exit(4); /* not reached */
    }
    int st = 0;
    waitpid(pid, &st, 0);
    CHECK(WIFSIGNALED(st) && WTERMSIG(st) == sig, "signal %d: the child died of it (status %#x)", sig, st);
    CHECK(test_count_temporaries(DIR_) == 0, "signal %d%s: no temporary file left", sig,
          exr_style ? " (two writes)" : "");
    CHECK(!exists(DIR_ "/out.bin") && !exists(DIR_ "/out.exr"), "signal %d: no output either", sig);
}

int main(void)
{
    CHECK(system("rm -rf '" DIR_ "' && mkdir -p '" DIR_ "'") == 0, "scratch folder");

    /* Registration follows the file: a committed or aborted write is forgotten. */
    ic_atomic_file f;
    ic_error err;
    CHECK(ic_atomic_file_open(&f, DIR_ "/done.bin", &err) == IC_OK, "open: %s", err.message);
    fputs("done", f.fp);
    CHECK(ic_atomic_file_commit(&f, &err) == IC_OK, "commit: %s", err.message);
    CHECK(ic_atomic_file_open(&f, DIR_ "/aborted.bin", &err) == IC_OK, "open: %s", err.message);
    ic_atomic_file_abort(&f);
    ic_remove_temporary_files();
    CHECK(exists(DIR_ "/done.bin") && test_count_temporaries(DIR_) == 0,
          "a committed file survives; nothing temporary");
    remove(DIR_ "/done.bin");

    die_while_writing(SIGTERM, 0);
    die_while_writing(SIGINT, 1);

    /* The command, killed by SIGXFSZ while its image exceeds a 16 kB file-size limit (48x48 PFM: 27 kB). */
    pid_t pid = fork();
    if (pid == 0) {
        struct rlimit rl = {16384, 16384};
        setrlimit(RLIMIT_FSIZE, &rl);
        signal(SIGXFSZ, SIG_DFL);
        int fd = open("/dev/null", O_WRONLY);
        dup2(fd, 2);
        execl(IC_CLI_PATH, "irrcache", "render", IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json", "-o",
              DIR_ "/big.pfm", "--width", "48", "--height", "48", "--spp", "1", "-q", (char *)NULL);
        _exit(127);
    }
    int st = 0;
    waitpid(pid, &st, 0);
    CHECK(WIFSIGNALED(st) && WTERMSIG(st) == SIGXFSZ, "the command died of SIGXFSZ (status %#x)", st);
    CHECK(test_count_temporaries(DIR_) == 0, "SIGXFSZ: the command left no temporary file");
    CHECK(!exists(DIR_ "/big.pfm"), "SIGXFSZ: no output");
    TEST_MAIN_END();
}
