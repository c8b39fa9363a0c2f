/*
 * test_cli_signals.c — a signal during the final write leaves no temporary file (issue "Hardening",
 * item 5). The library registers each temporary name while it exists, and ic_remove_temporary_files
 * (async-signal-safe) removes them; the command installs a handler for SIGINT, SIGTERM, SIGHUP and
 * SIGXFSZ that calls it and re-raises the signal. Checked in a child that dies of SIGTERM or SIGINT in
 * the middle of an atomic write (the handler being the command's), on the command itself sent SIGTERM or
 * SIGINT the moment its image's temporary file appears, and killed by SIGXFSZ when its output exceeds a
 * file-size limit.
 *
 * Long renders (issue "An installable library", item 5): SIGINT or SIGTERM during the final render or
 * inside a cache construction pass (batch, adaptive, lazy) ends the command soon with complete, partial
 * outputs and 128 + the signal (under --time too, within the pass that runs); --checkpoint writes complete, readable images while the render runs and
 * leaves the final image as it would be without.
 */
#include "core/atomic_file.h"
#include "irrcache/image.h"
#include "test_util.h"
#include "test_files.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
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

/* The command itself, sent `sig` while it writes its image: a 2048 x 2048 PFM (48 MB) is rendered with one
 * sample a pixel, and the signal goes the moment its temporary file appears in the folder. The write may
 * finish first on a fast disk: up to five tries, and one must catch it. */
static void command_killed_while_writing(int sig)
{
    const char *dir = DIR_ "/writing";
    mkdir(dir, 0755);
    int caught = 0;
    for (int attempt = 0; attempt < 5 && !caught; ++attempt) {
        unlink(DIR_ "/writing/big.pfm");
        pid_t pid = fork();
        if (pid == 0) {
            signal(SIGINT, SIG_DFL);
            signal(SIGTERM, SIG_DFL);
            int fd = open("/dev/null", O_WRONLY);
            dup2(fd, 2);
            execl(IC_CLI_PATH, "irrcache", "render", IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json", "-o",
                  DIR_ "/writing/big.pfm", "--width", "2048", "--height", "2048", "--spp", "1", "--threads", "2",
                  "-q", (char *)NULL);
            _exit(127);
        }
        int st = 0, done = 0;
        while (!done) {
            if (test_count_temporaries(dir) > 0) {
                kill(pid, sig);
                waitpid(pid, &st, 0);
                done = 1;
            } else if (waitpid(pid, &st, WNOHANG) == pid) {
                done = 2; /* ended before a temporary file was seen */
            } else {
                usleep(200);
            }
        }
        if (WIFSIGNALED(st) && WTERMSIG(st) == sig) {
            caught = 1;
            printf("signal %d: reached the command during its write at try %d\n", sig, attempt + 1);
            CHECK(test_count_temporaries(dir) == 0, "signal %d during the command's write: no temporary file left",
                  sig);
            CHECK(!exists(DIR_ "/writing/big.pfm"), "signal %d during the command's write: no output", sig);
        } else {
            CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0, "signal %d: the command ended otherwise (status %#x)", sig,
                  st);
        }
    }
    CHECK(caught, "signal %d reached the command during its write in one of five tries", sig);
    CHECK(test_count_temporaries(dir) == 0, "signal %d: no temporary file left after the tries", sig);
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Waits for pid for at most `limit` seconds (then kills it: a hang); returns the exit status, -1 if it
 * died of a signal or had to be killed, and the seconds waited in *waited. */
static int wait_bounded(pid_t pid, double limit, double *waited)
{
    double t0 = now_seconds();
    int st = 0;
    for (;;) {
        pid_t got = waitpid(pid, &st, WNOHANG);
        if (got == pid)
            break;
        if (got < 0 && errno != EINTR)
            return -1;
        if (now_seconds() - t0 > limit) {
            kill(pid, SIGKILL);
            waitpid(pid, &st, 0);
            *waited = now_seconds() - t0;
            return -1;
        }
        nanosleep(&(struct timespec){0, 10000000}, NULL);
    }
    *waited = now_seconds() - t0;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* A file-size limit for the renders start_render starts (0: none), their writes past it failing with EFBIG. */
static rlim_t render_file_limit;
/* 1: start_render's renders print their summary line (no -q). */
static int render_summary;

/* Starts `irrcache render -o DIR_/int.exr -o DIR_/int.png --stats DIR_/int.json -q ARGS…` in a child with
 * SIGINT and SIGTERM at their default (so the command installs its handler); stderr goes to
 * DIR_/int.err. */
static pid_t start_render(const char *const *args)
{
    pid_t pid = fork();
    if (pid == 0) {
        signal(SIGINT, SIG_DFL);
        signal(SIGTERM, SIG_DFL);
        if (render_file_limit) {
            struct rlimit rl = {render_file_limit, render_file_limit};
            setrlimit(RLIMIT_FSIZE, &rl);
            signal(SIGXFSZ, SIG_IGN);
        }
        int fd = open(DIR_ "/int.err", O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 2);
        const char *argv[32] = {"irrcache", "render", IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json", "-o",
                                DIR_ "/int.exr", "-o", DIR_ "/int.png", "--stats", DIR_ "/int.json"};
        int n = 9;
        if (!render_summary)
            argv[n++] = "-q";
        for (int k = 0; args[k] && n < 31; ++k)
            argv[n++] = args[k];
        argv[n] = NULL;
        execv(IC_CLI_PATH, (char *const *)argv);
        _exit(127);
    }
    return pid;
}

/* Sends `sig` to a render (start_render) after `delay` seconds and returns its exit status (-1 if it died
 * of a signal, or did not end within 30 s of the signal: a hang, not a slow machine); *after gets the
 * seconds from the signal to the exit. */
static int interrupt_render_timed(int sig, double delay, const char *const *args, double *after)
{
    pid_t pid = start_render(args);
    struct timespec ts = {(time_t)delay, (long)((delay - (double)(time_t)delay) * 1e9)};
    nanosleep(&ts, NULL);
    kill(pid, sig);
    return wait_bounded(pid, 30.0, after);
}

static int interrupt_render(int sig, double delay, const char *const *args)
{
    double after;
    return interrupt_render_timed(sig, delay, args, &after);
}

static long file_size(const char *p)
{
    struct stat s;
    return stat(p, &s) == 0 ? (long)s.st_size : -1;
}

/* SIGINT or SIGTERM during a long render (issue "An installable library", long renders): the command
 * stops at the next tile, writes every output with the image so far (marked partial), replacing an
 * older file only by a complete new one, leaves no temporary file, and exits 128 + the signal. During
 * cache construction it stops construction and writes a one-sample preview. */
static void test_interrupted_render(void)
{
    FILE *old = fopen(DIR_ "/int.png", "wb");
    if (old)
        fputs("an older output", old), fclose(old);
    const char *final[] = {"--width", "256", "--height", "256", "--spp", "4096", "--adaptive-sampling", "off", NULL};
    render_summary = 1;
    int rc = interrupt_render(SIGINT, 1.5, final);
    render_summary = 0;
    char err_text[2048];
    test_read_text(DIR_ "/int.err", err_text, sizeof err_text);
    CHECK(rc == 130, "SIGINT: exit 130 (got %d: %s)", rc, err_text);
    CHECK(strstr(err_text, "interrupted by SIGINT") != NULL, "SIGINT: says so: %s", err_text);
    /* The summary line is there; its sample count is the mean the tiles hold, and the render is not called
     * adaptive (it said '(adaptive, up to 4096 in a pixel)' of a render with --adaptive-sampling off). */
    CHECK(strstr(err_text, "irrcache: 256x256") && !strstr(err_text, "adaptive"),
          "SIGINT: the summary does not call the render adaptive: %s", err_text);
    ic_image img;
    ic_error err;
    CHECK(ic_image_read(DIR_ "/int.exr", &img, &err) == IC_OK && img.width == 256, "the partial EXR reads: %s",
          err.message);
    double sum = 0.0;
    int black = 0;
    for (int i = 0; img.rgb && i < 256 * 256; ++i) {
        float v = img.rgb[3 * i] + img.rgb[3 * i + 1] + img.rgb[3 * i + 2];
        sum += v;
        black += v == 0.0f;
    }
    CHECK(sum > 0.0 && black > 0, "part of the image is rendered (sum %g), part is not (%d black pixels)", sum, black);
    ic_image_free(&img);
    char v[256];
    CHECK(ic_image_exr_attribute(DIR_ "/int.exr", "irrcache:partial", v, sizeof v, &err) == IC_OK &&
              strstr(v, "interrupted"),
          "the EXR is marked partial: %s", v);
    CHECK(file_size(DIR_ "/int.png") > 100 && ic_image_read(DIR_ "/int.png", &img, &err) == IC_OK,
          "the older PNG is replaced by a complete one: %s", err.message);
    ic_image_free(&img);
    char json[8192];
    test_read_text(DIR_ "/int.json", json, sizeof json);
    CHECK(strstr(json, "\"interrupted\"") != NULL, "the stats say interrupted");
    CHECK(test_count_temporaries(DIR_) == 0, "no temporary file left");

    /* During cache construction (many rays per record): a preview of one sample per pixel. */
    const char *construction[] = {"--integrator", "ic", "--width", "96", "--height", "96", "--rays", "20000",
                                  "--spp", "64", NULL};
    rc = interrupt_render(SIGTERM, 1.5, construction);
    test_read_text(DIR_ "/int.err", err_text, sizeof err_text);
    CHECK(rc == 143, "SIGTERM during construction: exit 143 (got %d: %s)", rc, err_text);
    CHECK(strstr(err_text, "preview") != NULL, "SIGTERM during construction: a preview: %s", err_text);
    CHECK(ic_image_read(DIR_ "/int.exr", &img, &err) == IC_OK && img.width == 96, "the preview reads: %s",
          err.message);
    ic_image_free(&img);
    CHECK(test_count_temporaries(DIR_) == 0, "no temporary file left");
}

/* SIGTERM during a render whose PFM then exceeds a 16 kB file-size limit (a full disk): the stats are
 * written, the image named as not written, and the exit status is still 143, with no claim that the
 * render finished (it exited 3, 'the render finished but 1 output could not be written'). */
static void test_interrupted_output_failed(void)
{
    const char *final[] = {"--width", "256", "--height", "256", "--spp", "4096", "--adaptive-sampling", "off", "-o",
                           DIR_ "/int.pfm", NULL}; /* the PFM: 786 kB whatever the image */
    remove(DIR_ "/int.json");
    render_file_limit = 16384;
    int rc = interrupt_render(SIGTERM, 1.5, final);
    render_file_limit = 0;
    char err_text[2048], json[8192] = "";
    test_read_text(DIR_ "/int.err", err_text, sizeof err_text);
    test_read_text(DIR_ "/int.json", json, sizeof json);
    CHECK(rc == 143, "SIGTERM, outputs failing: exit 143 (got %d: %s)", rc, err_text);
    CHECK(strstr(err_text, "interrupted by SIGTERM") && strstr(err_text, "was interrupted but") &&
              strstr(err_text, "could not be written (") && strstr(err_text, "-o " DIR_ "/int.pfm") &&
              !strstr(err_text, "finished"),
          "SIGTERM, outputs failing: says the render was interrupted and names the failures: %s", err_text);
    CHECK(strstr(json, "\"interrupted\"") != NULL, "SIGTERM, outputs failing: the stats are written");
    CHECK(test_count_temporaries(DIR_) == 0, "SIGTERM, outputs failing: no temporary file left");
}

/* SIGTERM during a render under --time: its passes double, so the one running lasts about as long as all
 * before it (seconds here); the render stops at its next tile, not at the pass's end or the budget's, and
 * writes the image so far, every pixel the mean of the samples it holds (a tile the last pass did not reach
 * keeps the earlier passes'), and says so. The bound, 1.5 s, is below what finishing the pass would take
 * (seconds; 2 s here when the cancel flag was read between passes only, and the message claimed black
 * tiles) yet far above a tile's time (0.1 s). */
static void test_interrupted_budget(void)
{
    const char *args[] = {"--width", "128", "--height", "128", "--time", "60", "--threads", "2", NULL};
    double after = 0.0;
    int rc = interrupt_render_timed(SIGTERM, 6.0, args, &after);
    char err_text[2048], json[8192], v[256] = "";
    test_read_text(DIR_ "/int.err", err_text, sizeof err_text);
    test_read_text(DIR_ "/int.json", json, sizeof json);
    ic_error err;
    CHECK(ic_image_exr_attribute(DIR_ "/int.exr", "irrcache:partial", v, sizeof v, &err) == IC_OK &&
              strstr(v, "interrupted"), "--time: marked partial: %s", v);
    printf("--time 60, SIGTERM after 6 s: exit %d, %.2f s after the signal\n", rc, after);
    CHECK(rc == 143 && after < 1.5, "--time: SIGTERM ends the render within 1.5 s (exit %d after %.1f s): %s", rc,
          after, err_text);
    CHECK(strstr(err_text, "interrupted by SIGTERM") && strstr(err_text, "samples per pixel") &&
              !strstr(err_text, "black"),
          "--time: says how many samples the pixels hold (none is black): %s", err_text);
    /* Black pixels: those whose samples all miss the box; a complete render of 16 samples has at least as
     * many as one of more samples. */
    int black[2] = {0, 0}, finite = 1, read = 1;
    ic_image img;
    for (int k = 0; k < 2 && read; ++k) {
        if (k == 1) {
            const char *full[] = {"--width", "128", "--height", "128", "--spp", "16", NULL};
            double waited;
            CHECK(wait_bounded(start_render(full), 300.0, &waited) == 0, "a complete render of 16 samples");
        }
        read = ic_image_read(DIR_ "/int.exr", &img, &err) == IC_OK && img.width == 128 && img.height == 128;
        for (int i = 0; read && i < 128 * 128; ++i) {
            const float *p = &img.rgb[3 * i];
            finite &= isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
            black[k] += p[0] + p[1] + p[2] == 0.0f;
        }
        if (read)
            ic_image_free(&img);
    }
    CHECK(read && finite && black[0] <= black[1],
          "--time: the partial image is whole, no tile left black (%d black pixels; %d in a complete render): %s",
          black[0], black[1], read ? "" : err.message);
    CHECK(strstr(json, "\"interrupted\"") != NULL, "--time: the stats say interrupted");
    CHECK(test_count_temporaries(DIR_) == 0, "--time: no temporary file left");
}

/* SIGINT inside the first construction pass of each strategy (the pass alone takes minutes here: 20,000
 * rays per record): the command stops within a few gathers and writes a complete preview from the
 * records made so far. The bound is a hang detector, not a timing. */
static void test_interrupted_construction(void)
{
    static const char *const strategies[] = {"batch", "adaptive", "lazy"};
    for (int k = 0; k < 3; ++k) {
        const char *args[] = {"--integrator", "ic", "--strategy", strategies[k], "--width", "96", "--height", "96",
                              "--rays", "20000", "--spp", "64", "--threads", "2", "--save-cache", DIR_ "/int.icc", NULL};
        unlink(DIR_ "/int.icc");
        double after = 0.0;
        int rc = interrupt_render_timed(SIGINT, 1.5, args, &after);
        char err_text[2048], json[8192];
        test_read_text(DIR_ "/int.err", err_text, sizeof err_text);
        test_read_text(DIR_ "/int.json", json, sizeof json);
        printf("%s: SIGINT inside construction: exit %d, %.2f s after the signal\n", strategies[k], rc, after);
        CHECK(rc == 130, "%s: SIGINT during construction: exit 130 within 30 s (got %d after %.1f s: %s)",
              strategies[k], rc, after, err_text);
        CHECK(strstr(err_text, "preview") != NULL, "%s: a preview: %s", strategies[k], err_text);
        ic_image img;
        ic_error err;
        double sum = 0.0;
        int finite = 1;
        int read = ic_image_read(DIR_ "/int.exr", &img, &err) == IC_OK;
        for (int i = 0; read && i < 96 * 96 * 3; ++i) {
            finite &= isfinite(img.rgb[i]) != 0;
            sum += img.rgb[i];
        }
        CHECK(read && img.width == 96 && finite && sum > 0.0, "%s: the preview is a complete image (sum %g): %s",
              strategies[k], sum, read ? "" : err.message);
        if (read)
            ic_image_free(&img);
        char v[256] = "";
        CHECK(ic_image_exr_attribute(DIR_ "/int.exr", "irrcache:partial", v, sizeof v, &err) == IC_OK &&
                  strstr(v, "interrupted"), "%s: marked partial: %s", strategies[k], v);
        CHECK(strstr(json, "\"interrupted\"") != NULL && !strstr(json, "\"cut_by_time\":true"),
              "%s: the stats say interrupted (not cut by time)", strategies[k]);
        CHECK(test_count_temporaries(DIR_) == 0, "%s: no temporary file left", strategies[k]);
        /* An interrupted construction's records are not saved: a later --load-cache would take them for a
         * whole cache (a file of hit records only rendered without a word). */
        CHECK(!test_file_exists(DIR_ "/int.icc") && strstr(err_text, "--save-cache") && strstr(err_text, "incomplete"),
              "%s: no cache file from an interrupted construction, and it says so: %s", strategies[k], err_text);
    }
}

/* --checkpoint: while the render runs, its outputs appear as complete images marked "checkpoint"; the
 * final outputs replace them, unmarked, and are those of the same render without checkpoints. */
static void test_checkpoints(void)
{
    remove(DIR_ "/int.exr");
    remove(DIR_ "/int.png");
    remove(DIR_ "/int.pfm");
    const char *args[] = {"--width", "64", "--height", "64", "--spp", "128", "--threads", "2", "--checkpoint",
                          "0.05", "-o", DIR_ "/int.pfm", NULL};
    pid_t pid = start_render(args);
    int seen = 0, unreadable = 0, st = 0, seen_format[3] = {0, 0, 0};
    double t0 = now_seconds();
    while (waitpid(pid, &st, WNOHANG) == 0) {
        char v[256] = "";
        ic_error err;
        if (ic_image_exr_attribute(DIR_ "/int.exr", "irrcache:partial", v, sizeof v, &err) == IC_OK &&
            strstr(v, "checkpoint")) {
            /* Every output there is reads whole (the PNG and the PFM follow the EXR's first write). */
            const char *paths[] = {DIR_ "/int.exr", DIR_ "/int.png", DIR_ "/int.pfm"};
            for (int k = 0; k < 3; ++k) {
                ic_image img;
                if (k > 0 && file_size(paths[k]) < 0)
                    continue;
                int ok = ic_image_read(paths[k], &img, &err) == IC_OK;
                ok = ok && img.width == 64 && img.height == 64;
                if (ok)
                    ic_image_free(&img);
                seen_format[k] += ok;
                unreadable += !ok;
            }
            ++seen;
        }
        if (now_seconds() - t0 > 300.0) { /* a hang */
            kill(pid, SIGKILL);
            waitpid(pid, &st, 0);
            break;
        }
        nanosleep(&(struct timespec){0, 5000000}, NULL);
    }
    char err_text[2048];
    test_read_text(DIR_ "/int.err", err_text, sizeof err_text);
    CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0, "--checkpoint: the render succeeds (status %#x): %s", st, err_text);
    printf("--checkpoint 0.05: %d checkpoint reads while rendering\n", seen);
    CHECK(seen > 0 && seen_format[0] && seen_format[1] && seen_format[2],
          "--checkpoint: checkpoints appeared while the render ran (EXR, PNG, PFM: %d, %d, %d)", seen_format[0],
          seen_format[1], seen_format[2]);
    CHECK(unreadable == 0, "--checkpoint: every checkpoint seen was a complete image in every format (%d of %d not)",
          unreadable, seen);
    char v[256] = "";
    ic_error err;
    CHECK(ic_image_exr_attribute(DIR_ "/int.exr", "irrcache:partial", v, sizeof v, &err) == IC_ERR_INVALID_ARG,
          "--checkpoint: the final EXR is not marked partial (%s)", v);
    CHECK(test_count_temporaries(DIR_) == 0, "--checkpoint: no temporary file left");
    CHECK(rename(DIR_ "/int.pfm", DIR_ "/checkpointed.pfm") == 0, "keep the checkpointed render's image");
    const char *plain[] = {"--width", "64", "--height", "64", "--spp", "128", "--threads", "1", "-o",
                           DIR_ "/int.pfm", NULL};
    double waited;
    CHECK(wait_bounded(start_render(plain), 300.0, &waited) == 0, "the render without checkpoints succeeds");
    FILE *a = fopen(DIR_ "/int.pfm", "rb"), *b = fopen(DIR_ "/checkpointed.pfm", "rb");
    int same = a && b;
    for (int ca = 0, cb = 0; same && ca != EOF;) {
        ca = fgetc(a);
        cb = fgetc(b);
        same = ca == cb;
    }
    if (a)
        fclose(a);
    if (b)
        fclose(b);
    CHECK(same, "--checkpoint (2 threads) gives the bytes of the render without it (1 thread)");
}

/* --checkpoint with the final images over a 16 kB file-size limit (a disk that fills): a mostly black
 * checkpoint fits, the final image does not. The output keeps the last checkpoint, a complete partial image,
 * and the command says so instead of leaving it to pass for the final image ('nothing was written' alone);
 * each output's failing checkpoints are said once, not at every checkpoint. */
static void test_checkpoint_held(void)
{
    remove(DIR_ "/int.exr");
    remove(DIR_ "/int.png");
    const char *args[] = {"--width", "128", "--height", "128", "--spp", "256", "--threads", "2", "--checkpoint",
                          "0.02", NULL};
    render_file_limit = 16384;
    double waited;
    int rc = wait_bounded(start_render(args), 300.0, &waited);
    render_file_limit = 0;
    char err_text[8192];
    test_read_text(DIR_ "/int.err", err_text, sizeof err_text);
    CHECK(rc == 3, "--checkpoint, final images over the limit: exit 3 (got %d: %s)", rc, err_text);
    int said = 0, held = 0, whole = 1;
    for (const char *p = err_text; (p = strstr(p, "--checkpoint: -o")) != NULL; ++p)
        ++said;
    const char *paths[] = {DIR_ "/int.exr", DIR_ "/int.png"};
    for (int k = 0; k < 2; ++k) {
        char line[256];
        snprintf(line, sizeof line, "-o %s holds this run's last checkpoint", paths[k]);
        if (!strstr(err_text, line))
            continue;
        ++held;
        ic_image img;
        ic_error err;
        int ok = ic_image_read(paths[k], &img, &err) == IC_OK && img.width == 128 && img.height == 128;
        if (ok)
            ic_image_free(&img);
        whole &= ok;
    }
    CHECK(held > 0 && whole, "--checkpoint: an output left with a checkpoint is named (%d) and whole: %s", held,
          err_text);
    CHECK(said <= 2, "--checkpoint: a failing output's checkpoints are said once each (%d lines)", said);
    CHECK(test_count_temporaries(DIR_) == 0, "--checkpoint over the limit: no temporary file left");
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
    command_killed_while_writing(SIGTERM);
    command_killed_while_writing(SIGINT);

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
    test_interrupted_render();
    test_interrupted_output_failed();
    test_interrupted_budget();
    test_interrupted_construction();
    test_checkpoints();
    test_checkpoint_held();
    TEST_MAIN_END();
}
