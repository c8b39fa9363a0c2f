/*
 * test_cli_outputs.c — every output of `irrcache render` is checked before the render starts (issue
 * "Hardening", item 1): an -o, --aov, --stats, --records-json or --save-cache path that is an existing
 * folder, a device or pipe, has a missing folder, cannot be created, or is the same file as another
 * output (or the scene, a file the scene reads — a mesh, its MTL file, a texture —, or the --load-cache
 * file, which only --save-cache may rewrite) is refused with exit 2 and one line naming the option and the
 * path, and nothing is written. When one output fails at the end all the same (here: a file-size limit), the others are
 * written, the exit status is 1 and the message names the one that failed; no temporary file is left.
 */
#include "test_util.h"
#include "test_files.h"

#include "irrcache/image.h"
#include "irrcache/version.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#define CLI IC_CLI_PATH
#define DIR_ IC_TEST_TMP "/cli_outputs"
#define ERR DIR_ "/stderr.txt"
#define QUAD IC_SOURCE_DIR "/tests/scenes/quad_light.obj"
#define CORNELL IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"
#define SMALL " --width 16 --height 16 --spp 1 -q"

static char err_text[8192];

static void read_err(void)
{
    FILE *f = fopen(ERR, "r");
    size_t n = f ? fread(err_text, 1, sizeof err_text - 1, f) : 0;
    err_text[n] = 0;
    if (f)
        fclose(f);
}

/* Runs `irrcache ARGS` (stderr captured); the exit status, or -1 if it crashed. */
static int run(const char *args)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "%s %s 2>%s >/dev/null", CLI, args, ERR);
    int st = system(cmd);
    read_err();
    return st != -1 && WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static int exists(const char *p)
{
    struct stat s;
    return stat(p, &s) == 0;
}

static int lines(const char *s)
{
    int n = 0;
    for (; *s; ++s)
        n += *s == '\n';
    return n;
}


/* 1 if files a and b hold the same bytes (up to 1 MiB each). */
static int same_bytes(const char *a, const char *b)
{
    static char ta[1 << 20], tb[1 << 20];
    size_t na = test_read_text(a, ta, sizeof ta), nb = test_read_text(b, tb, sizeof tb);
    return na > 0 && na == nb && !memcmp(ta, tb, na);
}

/* A refused command line of scene: exit 2, one line naming option and path (and `what`), no image written. */
static void refused_in(const char *scene, const char *label, const char *args, const char *option, const char *path,
                       const char *what)
{
    remove(DIR_ "/good.pfm");
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "render %s -o %s/good.pfm %s", scene, DIR_, args);
    int rc = run(cmd);
    CHECK(rc == 2, "%s: exit %d, expected 2 (%s)", label, rc, err_text);
    CHECK(lines(err_text) == 1, "%s: one line: %s", label, err_text);
    char want[1024];
    snprintf(want, sizeof want, "%s %s", option, path);
    CHECK(strstr(err_text, want) != NULL, "%s: names '%s': %s", label, want, err_text);
    CHECK(strstr(err_text, what) != NULL, "%s: says '%s': %s", label, what, err_text);
    CHECK(!exists(DIR_ "/good.pfm"), "%s: nothing rendered or written", label);
    CHECK(test_count_temporaries(DIR_) == 0, "%s: no temporary file left", label);
}

static void refused(const char *label, const char *args, const char *option, const char *path, const char *what)
{
    refused_in(QUAD, label, args, option, path, what);
}

/* Runs the command with a file-size limit and SIGXFSZ ignored, so that a write beyond the limit fails
 * with EFBIG (as on a full disk) instead of killing the process. */
static int run_limited(const char *args, rlim_t limit)
{
    pid_t pid = fork();
    if (pid == 0) {
        struct rlimit rl = {limit, limit};
        setrlimit(RLIMIT_FSIZE, &rl);
        signal(SIGXFSZ, SIG_IGN);
        int fd = open(ERR, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 2);
        execl("/bin/sh", "sh", "-c", args, (char *)NULL);
        _exit(127);
    }
    int st = 0;
    waitpid(pid, &st, 0);
    read_err();
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

int main(void)
{
    CHECK(system("rm -rf '" DIR_ "' && mkdir -p '" DIR_ "/folder.pfm' '" DIR_ "/folder.json' '" DIR_
                 "/cachedir'") == 0,
          "scratch folders");
    mkfifo(DIR_ "/fifo.pfm", 0644);

    /* An existing folder, for every kind of output. */
    refused("-o folder", "-o " DIR_ "/folder.pfm" SMALL, "-o", DIR_ "/folder.pfm", "is a folder");
    refused("--stats folder", "--stats " DIR_ "/folder.json" SMALL, "--stats", DIR_ "/folder.json", "is a folder");
    refused("--records-json folder", "--integrator ic --records-json " DIR_ "/folder.json" SMALL, "--records-json",
            DIR_ "/folder.json", "is a folder");
    refused("--save-cache folder", "--integrator ic --save-cache " DIR_ "/cachedir" SMALL, "--save-cache",
            DIR_ "/cachedir", "is a folder");
    /* AOVs go next to the first output (good.pfm): good.records.png is a folder. */
    mkdir(DIR_ "/good.records.png", 0755);
    refused("--aov folder", "--integrator ic --aov records" SMALL, "--aov records", DIR_ "/good.records.png",
            "is a folder");
    rmdir(DIR_ "/good.records.png");
    /* A pipe is not a file to write an image into. */
    refused("-o fifo", "-o " DIR_ "/fifo.pfm" SMALL, "-o", DIR_ "/fifo.pfm", "not a regular file");
    /* A missing folder and one that takes no new file (/proc refuses even root). */
    refused("-o missing folder", "-o " DIR_ "/no/such/x.exr" SMALL, "-o", DIR_ "/no/such/x.exr", "does not exist");
    refused("--stats missing folder", "--stats " DIR_ "/no/s.json" SMALL, "--stats", DIR_ "/no/s.json",
            "does not exist");
    refused("--save-cache missing folder", "--integrator ic --save-cache " DIR_ "/no/c.icc" SMALL, "--save-cache",
            DIR_ "/no/c.icc", "does not exist");
    refused("--records-json unwritable", "--integrator ic --records-json /proc/self/r.json" SMALL,
            "--records-json", "/proc/self/r.json", "cannot create");
    /* A name no file may have (256 bytes; NAME_MAX is 255) is refused as too long, not as an unwritable
     * folder; one of 250 bytes (and its --stats, 255) is written, although its temporary's name
     * "<name>.tmp.<tag>.<pid>.<n>" is too long to be one: the temporary's is shortened. */
    {
        char name[300], args[2048], path[600];
        memset(name, 'n', 256);
        snprintf(name + 252, sizeof name - 252, ".pfm");
        snprintf(path, sizeof path, DIR_ "/%s", name);
        snprintf(args, sizeof args, "-o %s" SMALL, path);
        refused("-o name too long", args, "-o", path, "file name too long");
        CHECK(strstr(err_text, "shorter name") != NULL, "says what to do: %s", err_text);
        snprintf(name + 246, sizeof name - 246, ".pfm");
        snprintf(path, sizeof path, DIR_ "/%s", name);
        snprintf(args, sizeof args, "render %s -o %s --stats %s.json" SMALL, QUAD, path, path);
        int rc = run(args);
        CHECK(rc == 0 && exists(path), "a 250-byte -o and a 255-byte --stats are written (exit %d): %s", rc, err_text);
        CHECK(test_count_temporaries(DIR_) == 0, "no temporary left beside it");
        remove(path);
        strcat(path, ".json");
        remove(path);
    }
    /* Two outputs that are one file, however spelled; an output that is the scene. */
    refused("-o twice", "-o " DIR_ "/../cli_outputs/good.pfm" SMALL, "-o", DIR_ "/../cli_outputs/good.pfm",
            "the same file as -o " DIR_ "/good.pfm");
    refused("--stats = --records-json", "--integrator ic --stats " DIR_ "/s.json --records-json " DIR_ "/./s.json" SMALL,
            "--records-json", DIR_ "/./s.json", "the same file as --stats");
    refused("--save-cache = -o", "--integrator ic --save-cache " DIR_ "/good.pfm" SMALL, "--save-cache",
            DIR_ "/good.pfm", "the same file as -o");
    refused("--stats = scene", "--stats " QUAD SMALL, "--stats", QUAD, "scene file");

    /* Nor an output that is a file the scene reads: its mesh, material library or texture (one named only
     * by the mesh's MTL file, or by the scene file), whether as written, as another spelling or as a hard
     * link. Each is refused once the scene is loaded, before the render, and left byte for byte. */
    {
        CHECK(system("mkdir -p '" DIR_ "/read' && cp '" QUAD "' '" IC_SOURCE_DIR "/tests/scenes/quad_light.mtl' '"
                     DIR_ "/read/'") == 0,
              "a scene folder");
        CHECK(run("render " QUAD " -o " DIR_ "/read/wood.png" SMALL) == 0, "a texture (%s)", err_text);
        CHECK(test_write_text(DIR_ "/read/scene.json", "{\n  \"meshes\": [ { \"path\": \"quad_light.obj\" } ],\n"
                              "  \"materials\": { \"grey\": { \"kd_texture\": \"wood.png\" } }\n}\n"),
              "the scene file");
        CHECK(system("cd '" DIR_ "/read' && cp quad_light.obj mesh.keep && cp quad_light.mtl mtl.keep && "
                     "cp wood.png wood.keep && ln -f quad_light.obj hard.obj") == 0,
              "copies to compare with, a hard link");
        const char *scene = DIR_ "/read/scene.json";
        refused_in(scene, "-o = texture", "-o " DIR_ "/read/wood.png" SMALL, "-o", DIR_ "/read/wood.png",
                   "is a file the scene reads");
        CHECK(strstr(err_text, "give another name") != NULL, "says what to do: %s", err_text);
        refused_in(scene, "--stats = mesh", "--stats " DIR_ "/read/quad_light.obj" SMALL, "--stats",
                   DIR_ "/read/quad_light.obj", "is a file the scene reads");
        refused_in(scene, "--records-json = MTL", "--integrator ic --records-json " DIR_ "/read/../read/quad_light.mtl"
                   SMALL, "--records-json", DIR_ "/read/../read/quad_light.mtl", "is a file the scene reads");
        refused_in(scene, "--save-cache = mesh's hard link", "--integrator ic --save-cache " DIR_ "/read/hard.obj"
                   SMALL, "--save-cache", DIR_ "/read/hard.obj", "is a file the scene reads");
        refused_in(DIR_ "/read/quad_light.obj", "a bare mesh's MTL", "--stats " DIR_ "/read/quad_light.mtl" SMALL,
                   "--stats", DIR_ "/read/quad_light.mtl", "is a file the scene reads");
        CHECK(same_bytes(DIR_ "/read/quad_light.obj", DIR_ "/read/mesh.keep") &&
                  same_bytes(DIR_ "/read/quad_light.mtl", DIR_ "/read/mtl.keep") &&
                  same_bytes(DIR_ "/read/wood.png", DIR_ "/read/wood.keep"),
              "the mesh, its MTL file and the texture are intact");
        CHECK(test_count_temporaries(DIR_ "/read") == 0, "no temporary file left beside them");
        /* Outputs of other names in the same folder are written. */
        int rc = run("render " DIR_ "/read/scene.json -o " DIR_ "/read/image.png --stats " DIR_ "/read/stats.json"
                     SMALL);
        CHECK(rc == 0 && exists(DIR_ "/read/image.png") && exists(DIR_ "/read/stats.json"),
              "other outputs beside the scene's files are written (exit %d: %s)", rc, err_text);
    }

    /* The cache a render loads is an input: an output other than --save-cache that is that file would
     * destroy it (the render wrote its stats over the cache it had just read). --save-cache may rewrite it:
     * the same bytes. */
    {
        const char *made = CLI " render " QUAD " --integrator ic --rays 32 -o " DIR_ "/made.pfm --save-cache " DIR_
                           "/in.icc" SMALL " 2>" ERR;
        CHECK(system(made) == 0, "a cache to load");
        static char before[1 << 22], after[1 << 22];
        size_t n_before = test_read_text(DIR_ "/in.icc", before, sizeof before), n_after;
        CHECK(n_before > 100 && n_before < sizeof before - 1, "the cache read (%zu bytes)", n_before);
        refused("--stats = --load-cache", "--integrator ic --rays 32 --load-cache " DIR_ "/in.icc --stats " DIR_
                "/./in.icc" SMALL, "--stats", DIR_ "/./in.icc", "is the --load-cache file");
        refused("--records-json = --load-cache", "--integrator ic --rays 32 --load-cache " DIR_ "/in.icc --records-json "
                DIR_ "/in.icc" SMALL, "--records-json", DIR_ "/in.icc", "is the --load-cache file");
        n_after = test_read_text(DIR_ "/in.icc", after, sizeof after);
        CHECK(n_after == n_before && !memcmp(before, after, n_before), "the loaded cache is intact");
        int rc = run("render " QUAD " --integrator ic --rays 32 -o " DIR_ "/made.pfm --load-cache " DIR_
                     "/in.icc --save-cache " DIR_ "/in.icc" SMALL);
        CHECK(rc == 0, "--save-cache onto the --load-cache file is allowed (exit %d: %s)", rc, err_text);
        n_after = test_read_text(DIR_ "/in.icc", after, sizeof after);
        CHECK(n_after == n_before && !memcmp(before, after, n_before), "saving the loaded cache again gives the same bytes");
    }

    /* An output that is a symbolic link is written through it: the link stays and its target takes the
     * file (the rename had replaced the link with a plain file, leaving the target as it was). Links count
     * when outputs are compared with each other and with the inputs; a loop of links is refused. */
    {
        CHECK(system("mkdir -p '" DIR_ "/links/sub' && cd '" DIR_ "/links' && echo old > sub/real.json && "
                     "ln -sf sub/real.json link.json && ln -sf ../link.json sub/chain.json && "
                     "ln -sf loop1 loop2 && ln -sf loop2 loop1 && ln -sf '" QUAD "' scene.obj && "
                     "ln -sf /proc/self/fd/1 stdout.json") == 0,
              "links");
        int rc = run("render " QUAD " -o " DIR_ "/links/img.pfm --stats " DIR_ "/links/sub/chain.json" SMALL);
        struct stat ls;
        CHECK(rc == 0 && lstat(DIR_ "/links/link.json", &ls) == 0 && S_ISLNK(ls.st_mode) &&
                  lstat(DIR_ "/links/sub/chain.json", &ls) == 0 && S_ISLNK(ls.st_mode),
              "the links stay links (exit %d: %s)", rc, err_text);
        char text[8192];
        CHECK(test_read_text(DIR_ "/links/sub/real.json", text, sizeof text) > 10 && text[0] == '{',
              "the stats are in the file the links lead to");
        CHECK(test_count_temporaries(DIR_ "/links") == 0 && test_count_temporaries(DIR_ "/links/sub") == 0,
              "no temporary file left");
        refused("--stats = --records-json through a link", "--integrator ic --stats " DIR_ "/links/sub/real.json "
                "--records-json " DIR_ "/links/link.json" SMALL, "--records-json", DIR_ "/links/link.json",
                "the same file as --stats");
        refused("--stats linked to the scene", "--stats " DIR_ "/links/scene.obj" SMALL, "--stats",
                DIR_ "/links/scene.obj", "scene file");
        refused("--stats a loop of links", "--stats " DIR_ "/links/loop1" SMALL, "--stats", DIR_ "/links/loop1",
                "loop of symbolic links");
        /* Another user's link in a sticky folder anyone may write to is not followed (the kernel's
         * protected_symlinks rule; test_atomic_file): root is needed to make one. */
        if (geteuid() == 0 && system("mkdir -p '" DIR_ "/links/shared' && chmod 1777 '" DIR_ "/links/shared' && "
                                     "ln -sf ../sub/real.json '" DIR_ "/links/shared/theirs.json'") == 0 &&
            lchown(DIR_ "/links/shared/theirs.json", 12345, 12345) == 0)
            refused("--stats another user's link", "--stats " DIR_ "/links/shared/theirs.json" SMALL, "--stats",
                    DIR_ "/links/shared/theirs.json", "another user's symbolic link in a shared folder");
        /* --stats /dev/stdout with stdout sent to a file: /dev/stdout is a link through /proc/self/fd/1 (run
         * as root, replacing it broke /dev/stdout for every later process). Here a link of the same kind. */
        char cmd[2048];
        snprintf(cmd, sizeof cmd, "%s render %s -o %s/links/img.pfm --stats %s/links/stdout.json%s >%s/links/out.txt "
                 "2>%s", CLI, QUAD, DIR_, DIR_, SMALL, DIR_, ERR);
        rc = system(cmd);
        read_err();
        CHECK(rc == 0 && lstat(DIR_ "/links/stdout.json", &ls) == 0 && S_ISLNK(ls.st_mode),
              "a link through /proc/self/fd/1 stays a link (%d: %s)", rc, err_text);
        CHECK(test_read_text(DIR_ "/links/out.txt", text, sizeof text) > 10 && text[0] == '{',
              "the stats are in the file stdout was sent to");
        /* Sent to append ('>>', a script's log): written through the descriptor, after what the file held
         * (renaming onto the file replaced it: the log was lost). */
        CHECK(system("echo 'a line before' > '" DIR_ "/links/log.txt'") == 0, "a log");
        snprintf(cmd, sizeof cmd, "%s render %s -o %s/links/img.pfm --stats %s/links/stdout.json%s >>%s/links/log.txt "
                 "2>%s", CLI, QUAD, DIR_, DIR_, SMALL, DIR_, ERR);
        rc = system(cmd);
        read_err();
        CHECK(rc == 0 && test_read_text(DIR_ "/links/log.txt", text, sizeof text) > 24 &&
                  !strncmp(text, "a line before\n{", 15),
              "--stats /dev/stdout >> log: the log keeps its line, the stats follow (%d: %s): '%.40s'", rc, err_text,
              text);
    }

    /* A failure at the end costs only that output: the PFM (48x48: 27 kB) exceeds the 16 kB limit, the
     * PNG and the stats (a few kB) are still written; exit 3 (rendered, an output failed) names the failed one. */
    const char *cmd = CLI " render " CORNELL " -o " DIR_ "/end/big.pfm -o " DIR_ "/end/small.png --stats " DIR_
                      "/end/stats.json --width 48 --height 48 --spp 1 -q";
    CHECK(system("mkdir -p '" DIR_ "/end'") == 0, "end folder");
    int rc = run_limited(cmd, 16384);
    CHECK(rc == 3, "a late failure exits 3 (got %d: %s)", rc, err_text);
    CHECK(strstr(err_text, "-o " DIR_ "/end/big.pfm") && strstr(err_text, "could not be written"),
          "the message names the failed output: %s", err_text);
    CHECK(!strstr(err_text, "small.png") && !strstr(err_text, "stats.json"), "only the failed one is named: %s",
          err_text);
    CHECK(strstr(err_text, "the other outputs were written"), "it says the others were written: %s", err_text);
    CHECK(!exists(DIR_ "/end/big.pfm"), "the failed output is not there");
    /* The only output failing: no others to speak of. */
    rc = run_limited(CLI " render " CORNELL " -o " DIR_ "/end/big.pfm --width 48 --height 48 --spp 1 -q", 16384);
    CHECK(rc == 3 && strstr(err_text, "could not be written") && !strstr(err_text, "other outputs"),
          "the only output failed: no word of other outputs (exit %d: %s)", rc, err_text);
    CHECK(exists(DIR_ "/end/small.png"), "the PNG given after it is written");
    CHECK(exists(DIR_ "/end/stats.json"), "the stats are written");
    CHECK(test_count_temporaries(DIR_ "/end") == 0, "no temporary file left");

    /* A cache file that cannot be written (over the limit at save time) costs only itself: the render
     * goes on, its image is written, exit 3 names --save-cache. */
    const char *save = CLI " render " CORNELL " --integrator ic -o " DIR_ "/save/img.png --save-cache " DIR_
                       "/save/c.irc --width 48 --height 48 --spp 1 -q";
    CHECK(system("mkdir -p '" DIR_ "/save'") == 0, "save folder");
    rc = run_limited(save, 16384);
    CHECK(rc == 3, "a failed --save-cache exits 3 (got %d: %s)", rc, err_text);
    CHECK(strstr(err_text, "--save-cache " DIR_ "/save/c.irc") != NULL, "the message names the cache file: %s",
          err_text);
    CHECK(exists(DIR_ "/save/img.png") && !exists(DIR_ "/save/c.irc"), "the image is written, the cache is not");
    CHECK(test_count_temporaries(DIR_ "/save") == 0, "no temporary file left");
    /* EXR outputs, the AOVs' included, say how they were made (issue "An installable library", EXR metadata). */
    CHECK(system("mkdir -p '" DIR_ "/meta'") == 0, "meta folder");
    rc = run("render " CORNELL " --integrator ic --seed 42 --width 16 --height 16 --spp 2 --adaptive-sampling off -q -o "
             DIR_ "/meta/m.exr --aov indirect");
    CHECK(rc == 0, "render with EXR metadata (got %d: %s)", rc, err_text);
    /* The first output is an EXR: the indirect AOV is its layer "indirect", not a file of its own. */
    CHECK(!exists(DIR_ "/meta/m.indirect.exr"), "no separate indirect file beside an EXR output");
    {
        ic_image beauty, layer;
        ic_error e;
        CHECK(ic_image_read(DIR_ "/meta/m.exr", &beauty, &e) == IC_OK &&
                  ic_image_read_layer(DIR_ "/meta/m.exr", "indirect", &layer, &e) == IC_OK,
              "the EXR's image and its indirect layer read: %s", e.message);
        int le = beauty.rgb && layer.rgb && layer.width == beauty.width, any = 0;
        for (int i = 0; le && i < 16 * 16 * 3; ++i) {
            le &= layer.rgb[i] <= beauty.rgb[i] + 1e-4f; /* one term of the image: never more than all of it */
            any |= layer.rgb[i] > 0.0f;
        }
        CHECK(le && any, "the indirect layer is part of the image, and not black");
        ic_image_free(&beauty);
        ic_image_free(&layer);
    }
    /* A PFM first output keeps separate AOV files. */
    rc = run("render " CORNELL " --integrator ic --width 16 --height 16 --spp 1 -q -o " DIR_ "/meta/p.pfm --aov indirect");
    CHECK(rc == 0 && exists(DIR_ "/meta/p.indirect.exr"), "a PFM output's indirect AOV is its own file (%d: %s)", rc,
          err_text);
    const char *files[1] = {DIR_ "/meta/m.exr"};
    for (int f = 0; f < 1; ++f) {
        char v[4096];
        ic_error e;
        CHECK(ic_image_exr_attribute(files[f], "irrcache:version", v, sizeof v, &e) == IC_OK && !strcmp(v, ic_version()),
              "%s: version %s", files[f], v);
        CHECK(ic_image_exr_attribute(files[f], "irrcache:seed", v, sizeof v, &e) == IC_OK && !strcmp(v, "42"),
              "%s: seed %s", files[f], v);
        CHECK(ic_image_exr_attribute(files[f], "irrcache:spp", v, sizeof v, &e) == IC_OK && !strcmp(v, "2"),
              "%s: spp %s", files[f], v);
        CHECK(ic_image_exr_attribute(files[f], "irrcache:integrator", v, sizeof v, &e) == IC_OK && !strcmp(v, "ic"),
              "%s: integrator %s", files[f], v);
        CHECK(ic_image_exr_attribute(files[f], "irrcache:scene_fnv1a64", v, sizeof v, &e) == IC_OK && strlen(v) == 16,
              "%s: scene hash %s", files[f], v);
        CHECK(ic_image_exr_attribute(files[f], "irrcache:seconds", v, sizeof v, &e) == IC_OK && atof(v) > 0.0,
              "%s: seconds %s", files[f], v);
        CHECK(ic_image_exr_attribute(files[f], "irrcache:settings", v, sizeof v, &e) == IC_OK &&
                  strstr(v, "\"seed\"") && strstr(v, "42"),
              "%s: settings %s", files[f], v);
        CHECK(ic_image_exr_attribute(files[f], "irrcache:nothing", v, sizeof v, &e) == IC_ERR_INVALID_ARG,
              "%s: a missing attribute is reported", files[f]);
    }
    /* The colour-coded AOVs ignore --exposure: the a_i map's colours are its legend's, the records' marks
     * theirs, at any exposure; the image itself does change. */
    {
        static char bytes[2][3][1 << 16];
        size_t n[2][3];
        const char *names[3] = {DIR_ "/meta/e.png", DIR_ "/meta/e.amap.png", DIR_ "/meta/e.records.png"};
        for (int e = 0; e < 2; ++e) {
            rc = run(e ? "render " CORNELL " --integrator ic --rays 32 --width 24 --height 24 --spp 1 -q -o "
                         DIR_ "/meta/e.png --aov amap,records --exposure 3"
                       : "render " CORNELL " --integrator ic --rays 32 --width 24 --height 24 --spp 1 -q -o "
                         DIR_ "/meta/e.png --aov amap,records --exposure 0");
            CHECK(rc == 0, "render with --aov amap,records at exposure %d (got %d: %s)", 3 * e, rc, err_text);
            for (int k = 0; k < 3; ++k) {
                FILE *f = fopen(names[k], "rb");
                n[e][k] = f ? fread(bytes[e][k], 1, sizeof bytes[e][k], f) : 0;
                if (f)
                    fclose(f);
            }
        }
        CHECK(n[0][0] > 0 && (n[0][0] != n[1][0] || memcmp(bytes[0][0], bytes[1][0], n[0][0])),
              "--exposure 3 changes the image");
        for (int k = 1; k < 3; ++k)
            CHECK(n[0][k] > 0 && n[0][k] == n[1][k] && !memcmp(bytes[0][k], bytes[1][k], n[0][k]),
                  "%s: the same bytes at --exposure 0 and 3", names[k]);
    }
    /* --half: the same image in half the bytes, within half's precision. */
    rc = run("render " CORNELL " --width 16 --height 16 --spp 2 --seed 3 -q -o " DIR_ "/meta/f.exr");
    CHECK(rc == 0, "float EXR (got %d: %s)", rc, err_text);
    rc = run("render " CORNELL " --width 16 --height 16 --spp 2 --seed 3 -q --half -o " DIR_ "/meta/h.exr");
    CHECK(rc == 0, "half EXR (got %d: %s)", rc, err_text);
    {
        ic_image fimg, himg;
        ic_error e;
        CHECK(ic_image_read(DIR_ "/meta/f.exr", &fimg, &e) == IC_OK && ic_image_read(DIR_ "/meta/h.exr", &himg, &e) == IC_OK,
              "both read back");
        double worst = 0.0;
        for (int i = 0; i < 16 * 16 * 3; ++i)
            worst = fmax(worst, fabs(himg.rgb[i] - fimg.rgb[i]) / (fabs(fimg.rgb[i]) + 1e-6));
        CHECK(worst < 1e-3, "half differs from float by %.2e at worst (half's epsilon is 9.8e-4)", worst);
        struct stat sf, sh;
        CHECK(stat(DIR_ "/meta/f.exr", &sf) == 0 && stat(DIR_ "/meta/h.exr", &sh) == 0 && sh.st_size < sf.st_size,
              "the half file is smaller");
        ic_image_free(&fimg);
        ic_image_free(&himg);
    }
    TEST_MAIN_END();
}
