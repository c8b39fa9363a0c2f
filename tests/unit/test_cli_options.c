/*
 * test_cli_options.c — the option tables of `irrcache render`, `points` and `diff` and what comes from them:
 * README.md's option tables are exactly each command's `--help-markdown`, each number option's help shows
 * the range its parser checks, --help fits in 100 columns and lists the exit codes,
 * --name=value means the same as --name value, `--` ends the options, and each kind of bad value is a
 * usage error (exit 2) with one line naming the option. What goes to a standard output that cannot be
 * written (help, version, tables) exits 1 with one line saying so.
 */
#include "test_files.h"
#include "test_util.h"

#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#define CLI IC_CLI_PATH
#define CORNELL IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"
#define TMP IC_TEST_TMP "/cli_options"

static char out_text[1 << 17], err_text[8192];

/* Runs `irrcache ARGS`, stdout into out_text and stderr into err_text; returns the exit status. */
static int run(const char *args)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s %s >%s.out 2>%s.err", CLI, args, TMP, TMP);
    int st = system(cmd);
    test_read_text(TMP ".out", out_text, sizeof out_text);
    test_read_text(TMP ".err", err_text, sizeof err_text);
    return st == -1 || !WIFEXITED(st) ? -1 : WEXITSTATUS(st);
}

static int lines(const char *s)
{
    int n = 0;
    for (; *s; ++s)
        n += *s == '\n';
    return n;
}

/* `render CORNELL -o ... ARGS` is a usage error: exit 2 and one line that says `says`. */
static void usage_error(const char *args, const char *says)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "render " CORNELL " -o " TMP "_bad.exr %s", args);
    int rc = run(cmd);
    CHECK(rc == 2 && lines(err_text) == 1 && strstr(err_text, says), "%s: exit %d, '%s'", args, rc, err_text);
}

/* --help's text with its wrapping undone: each line break and the indent after it become one space. */
static void unwrap(char *s)
{
    char *w = s;
    for (const char *r = s; *r; ++r) {
        if (*r == '\n') {
            while (r[1] == ' ')
                ++r;
            *w++ = ' ';
        } else {
            *w++ = *r;
        }
    }
    *w = 0;
}

/* README.md's tables between "<!-- MARKER:begin" and "<!-- MARKER:end -->" are `irrcache COMMAND
 * --help-markdown`: render's, points' and diff's. */
static void readme_matches_table(void)
{
    static const char *const tables[][2] = {
        {"options", "render"}, {"points-options", "points"}, {"diff-options", "diff"}};
    static char readme[1 << 18];
    CHECK(test_read_text(IC_SOURCE_DIR "/README.md", readme, sizeof readme) > 0, "README.md readable");
    for (size_t k = 0; k < sizeof tables / sizeof tables[0]; ++k) {
        char begin[64], end[64], cmd[64];
        snprintf(begin, sizeof begin, "<!-- %s:begin", tables[k][0]);
        snprintf(end, sizeof end, "<!-- %s:end -->", tables[k][0]);
        const char *b = strstr(readme, begin), *e = strstr(readme, end);
        CHECK(b && e && b < e, "README.md has the %s markers", tables[k][0]);
        if (!b || !e || b > e)
            continue;
        b = strchr(b, '\n') + 1;
        snprintf(cmd, sizeof cmd, "%s --help-markdown", tables[k][1]);
        CHECK(run(cmd) == 0, "%s exits 0", cmd);
        size_t n = strlen(out_text);
        int same = (size_t)(e - b) == n && !strncmp(b, out_text, n);
        CHECK(same, "README.md's %s tables are `irrcache %s` (run bash scripts/update-readme-options.sh)",
              tables[k][0], cmd);
        if (k == 0)
            CHECK(strstr(out_text, "--accuracy A`") && strstr(out_text, "`--strategy batch\\|lazy\\|adaptive`"),
                  "the tables list the cache options, with '|' escaped");
    }
}

static void help_layout(void)
{
    CHECK(run("render --help") == 0, "--help exits 0");
    int longest = 0, at = 0;
    for (const char *p = out_text; *p; ++p) {
        at = *p == '\n' ? 0 : at + 1;
        longest = at > longest ? at : longest;
    }
    CHECK(longest <= 100, "--help lines within 100 columns (longest %d)", longest);
    CHECK(strstr(out_text, "exit status: 0") && strstr(out_text, "2 usage error"), "--help lists the exit codes");
    CHECK(strstr(out_text, "--min-radius-px P") && strstr(out_text, "[default: 3 px]"),
          "--help shows a default from irrcache/defaults.h with its unit");
}

/* Whatever the command prints on standard output is lost when that cannot be written (a full disk; here
 * /dev/full, where every write fails with ENOSPC): exit 1 and one line saying so, for the help of every
 * command, the version, and the diff table and points rows, not a silent exit 0. */
static void stdout_write_error(void)
{
    if (access("/dev/full", W_OK) != 0) {
        printf("skipped: no writable /dev/full\n");
        return;
    }
    static const char *const cases[] = {
        "--help", "-h", "help", "--version", "render --help", "render -h", "render --help-markdown",
        "diff --help", "points --help", "diff --help-markdown", "points --help-markdown",
        "diff " IC_SOURCE_DIR "/tests/scenes/checker2x2.pfm " IC_SOURCE_DIR "/tests/scenes/checker2x2.pfm",
        "points " IC_SOURCE_DIR "/tests/scenes/quad_light.obj --points " TMP "_pts.txt --integrator pt --samples 16",
        "points " IC_SOURCE_DIR "/tests/scenes/quad_light.obj --points " TMP "_pts.txt --integrator pt --samples 16 "
        "--format json",
    };
    FILE *f = fopen(TMP "_pts.txt", "w");
    CHECK(f != NULL, "points file");
    if (f) {
        fputs("0 0.5 0 0 1 0\n", f);
        fclose(f);
    }
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char cmd[2048];
        snprintf(cmd, sizeof cmd, "%s %s >/dev/full 2>%s.err", CLI, cases[i], TMP);
        int st = system(cmd);
        int rc = st == -1 || !WIFEXITED(st) ? -1 : WEXITSTATUS(st);
        test_read_text(TMP ".err", err_text, sizeof err_text);
        CHECK(rc == 1 && lines(err_text) == 1 && strstr(err_text, "standard output: write error"),
              "irrcache %s >/dev/full: exit %d, '%s'", cases[i], rc, err_text);
    }
    /* and the same to a file: exit 0, nothing on stderr */
    CHECK(run("--version") == 0 && !err_text[0] && !strncmp(out_text, "irrcache ", 9), "--version: '%s'", out_text);
}

/* Every limit that is a size or count takes K, M, G and T in either case (64k and 64m alike: 64M alone
 * was refused in lower case), the stats echo the number it means, its range holds with a suffix too, and
 * its help lists the suffixes that stay within its range. */
static void size_suffixes(void)
{
    static const struct { const char *option, *key, *value; double means; } cases[] = {
        {"--max-scene-bytes", "max_scene_bytes", "64m", 67108864.0},
        {"--max-scene-bytes", "max_scene_bytes", "1t", 1099511627776.0},
        {"--max-image-pixels", "max_image_pixels", "4k", 4096.0},
        {"--max-image-pixels", "max_image_pixels", "256m", 268435456.0},
        {"--max-texture-pixels", "max_texture_pixels", "256m", 268435456.0},
        {"--max-texture-pixels", "max_texture_pixels", "64K", 65536.0},
        {"--max-mesh-elements", "max_mesh_elements", "1g", 1073741824.0},
        {"--max-cache-bytes", "max_cache_bytes", "2G", 2147483648.0},
        {"--max-cache-bytes", "max_cache_bytes", "3", 3.0},
    };
    static char js[1 << 15];
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char cmd[1024], key[96];
        snprintf(cmd, sizeof cmd, "render " CORNELL " -o " TMP "_sz.pfm --width 8 --height 8 --spp 1 -q "
                 "--integrator ic --rays 16 --max-passes 1 %s %s --stats " TMP "_sz.json", cases[i].option,
                 cases[i].value);
        CHECK(run(cmd) == 0, "%s %s: %s", cases[i].option, cases[i].value, err_text);
        test_read_text(TMP "_sz.json", js, sizeof js);
        snprintf(key, sizeof key, "\"%s\":", cases[i].key);
        const char *k = strstr(js, key);
        CHECK(k && strtod(k + strlen(key), NULL) == cases[i].means, "%s %s means %.0f: %.60s", cases[i].option,
              cases[i].value, cases[i].means, k ? k : "(missing)");
    }
    static const struct { const char *args, *says; } refused[] = {
        {"--max-texture-pixels 1g", "--max-texture-pixels 1g: expected a whole number from 1 to 268435456; it may "
                                    "end in K or M (either case)"},
        {"--max-texture-pixels 257m", "--max-texture-pixels 257m"},
        /* no more than the library's images hold (IC_IMAGE_MAX_PIXELS): it would render, then fail */
        {"--max-image-pixels 257m", "--max-image-pixels 257m: expected a whole number from 1 to 268435456; it may "
                                    "end in K or M (either case)"},
        {"--max-mesh-elements 2g", "--max-mesh-elements 2g"},
        {"--max-scene-bytes 2t", "K, M, G or T (either case): times 2^10, 2^20, 2^30 or 2^40"},
        {"--max-scene-bytes 16777216T", "--max-scene-bytes 16777216T"},
        {"--max-scene-bytes 1.5m", "--max-scene-bytes 1.5m"},
        {"--max-scene-bytes 64mb", "--max-scene-bytes 64mb"},
        {"--max-scene-bytes m", "--max-scene-bytes m"},
    };
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; ++i)
        usage_error(refused[i].args, refused[i].says);
    CHECK(run("render --help") == 0, "--help");
    unwrap(out_text);
    const char *tex = strstr(out_text, "--max-texture-pixels N"), *bytes = strstr(out_text, "--max-scene-bytes N");
    CHECK(tex && bytes && strstr(tex, "N may end in K or M (either case)") &&
              strstr(bytes, "N may end in K, M, G or") && strstr(bytes, "T (either case)"),
          "the help lists each limit's suffixes");
}

/* A number option's help shows its range, the one the parser checks: each option's range error gives
 * "from A to B", and its help line (before its default) "[A, B]"; "(A, B]" where A itself is refused (a
 * number or off). A range is never broken across lines, and the README's tables have it in a column. */
static void help_ranges(void)
{
    static const struct { const char *option, *too_big; } checked[] = {
        {"--width", "70000"}, {"--spp", "99999999"}, {"--threads", "5000"}, {"--max-depth", "5000"},
        {"--exposure", "200"}, {"--accuracy", "101"}, {"--hsh-order", "17"}, {"--record-sets", "65"},
        {"--max-passes", "1001"}, {"--min-candidates", "2000000000"}, {"--final-accuracy-scale", "101"},
        {"--max-texture-pixels", "1G"}, {"--weber", "2"},
    };
    static char help[1 << 17];
    CHECK(run("render --help") == 0, "--help");
    unwrap(out_text);
    snprintf(help, sizeof help, "%s", out_text);
    for (size_t i = 0; i < sizeof checked / sizeof checked[0]; ++i) {
        char cmd[1024], lo[32] = "", hi[32] = "", want[96];
        snprintf(cmd, sizeof cmd, "render " CORNELL " -o " TMP "_r.exr --integrator ic %s %s", checked[i].option,
                 checked[i].too_big);
        CHECK(run(cmd) == 2, "%s %s refused", checked[i].option, checked[i].too_big);
        const char *from = strstr(err_text, " from ");
        CHECK(from && sscanf(from, " from %31s to %31[^;\n]", lo, hi) == 2, "%s: a range in '%s'", checked[i].option,
              err_text);
        snprintf(want, sizeof want, "[%s, %s] [default:", lo, hi);
        snprintf(cmd, sizeof cmd, " %s ", checked[i].option);
        const char *line = strstr(help, cmd), *def = line ? strstr(line, "[default:") : NULL,
                   *range = line ? strstr(line, want) : NULL;
        CHECK(range && range + strlen(want) - strlen("[default:") == def, "%s's help shows %s: %.300s",
              checked[i].option, want, line ? line : "(missing)");
    }
    static const char *const shown[] = {"random seed [0, 2^64 - 1] [default:", "[1, 2^40] [default: 67108864 (64M)]",
                                        "--radiance-max-exponent E ", "[0.001, 1e6] [default: 30]",
                                        "[1e-6, 1] [default: 0.001]", "[1e-30, 1e30] [default: scene diagonal / 8]"};
    for (size_t i = 0; i < sizeof shown / sizeof shown[0]; ++i)
        CHECK(strstr(help, shown[i]), "--help shows '%s'", shown[i]);
    const char *pg = strstr(help, " --pass-growth F|off ");
    CHECK(pg && strstr(pg, "(0, 1] [default: 0.") && strstr(pg, "(0, 1]") < strstr(pg, "[default:"),
          "--pass-growth's range excludes 0: %.200s", pg ? pg : "(missing)");
    CHECK(run("points --help") == 0 && strstr(out_text, "\n                     [0, 4096] [default: 0 (all cores)]"),
          "a range is wrapped whole (points --help, --threads): %s", out_text);
    CHECK(run("render --help-markdown") == 0 && strstr(out_text, "| option | range | default | meaning |") &&
              strstr(out_text, "| `--width N` | [1, 65536] | scene file, else 512 | image width |") &&
              strstr(out_text, "| `--strategy batch\\|lazy\\|adaptive` |  | batch |"),
          "the README's tables have a range column, empty for an option without a number");
}

/* The same for `points` and `diff`, whose own options have their tables too (options.h): each number
 * option's help shows the range its parser's error gives, "from A to B" as "[A, B]", "in (A, B]" as
 * itself; every number option of their tables is here. */
static void command_help_ranges(void)
{
    static const struct { const char *command, *option, *bad; } checked[] = {
        {"points", "--samples", "99999999"}, {"points", "--light-samples", "0"}, {"points", "--max-points", "4g"},
        {"points", "--spacing", "0"}, {"points", "--height", "-1"}, {"points", "--map-max", "0"},
        {"points", "--grid", "0 0 0 1 1 2e18"}, {"diff", "--max-error", "4e38"}, {"diff", "--blotch-max-error", "0"},
    };
    static char help[2][sizeof out_text], line[4096];
    CHECK(run("points --help") == 0, "points --help");
    memcpy(help[0], out_text, sizeof out_text);
    CHECK(run("diff --help") == 0, "diff --help");
    memcpy(help[1], out_text, sizeof out_text);
    for (size_t i = 0; i < sizeof checked / sizeof checked[0]; ++i) {
        int is_points = !strcmp(checked[i].command, "points");
        char cmd[1024], lo[32] = "", hi[32] = "", want[96] = "";
        snprintf(cmd, sizeof cmd, "%s %s %s %s", checked[i].command,
                 is_points ? CORNELL " --points " TMP "_none.txt" : CORNELL " " CORNELL, checked[i].option,
                 checked[i].bad);
        CHECK(run(cmd) == 2 && lines(err_text) == 1, "%s %s %s refused: %s", checked[i].command, checked[i].option,
              checked[i].bad, err_text);
        const char *from = strstr(err_text, " from "), *in = strstr(err_text, " in (");
        if (from && sscanf(from, " from %31s to %31[^;,\n]", lo, hi) == 2)
            snprintf(want, sizeof want, "[%s, %s] [default:", lo, hi);
        else if (in && sscanf(in, " in (%31[^]]", lo) == 1)
            snprintf(want, sizeof want, "(%s] [default:", lo);
        CHECK(want[0], "%s %s: a range in '%s'", checked[i].command, checked[i].option, err_text);
        /* the option's entry: from its name at the start of a line to the next option's, unwrapped */
        snprintf(cmd, sizeof cmd, "\n  %s ", checked[i].option);
        const char *start = strstr(help[!is_points], cmd), *next = start ? strstr(start + 1, "\n  -") : NULL;
        size_t n = !start ? 0 : next ? (size_t)(next - start) : strlen(start);
        snprintf(line, sizeof line, "%.*s", (int)(n < sizeof line ? n : sizeof line - 1), start ? start : "");
        unwrap(line);
        const char *def = strstr(line, "[default:"), *range = strstr(line, want);
        CHECK(want[0] && range && range + strlen(want) - strlen("[default:") == def, "%s --help shows %s for %s: %s",
              checked[i].command, want, checked[i].option, start ? line : "(missing)");
    }
    for (int k = 0; k < 2; ++k) {
        int longest = 0, at = 0;
        for (const char *p = help[k]; *p; ++p) {
            at = *p == '\n' ? 0 : at + 1;
            longest = at > longest ? at : longest;
        }
        CHECK(longest <= 100, "%s --help lines within 100 columns (longest %d)", k ? "diff" : "points", longest);
    }
    CHECK(strstr(help[1], "--max-error E|auto ") && run("diff " CORNELL " " CORNELL " --max-error lots") == 2 &&
              strstr(err_text, "from 0 to 3e38, or auto"),
          "--max-error takes auto: %s", err_text);
}

static void value_forms(void)
{
    /* The same render with --name value, with --name=value, and with the scene after `--`: same stats. */
    static char a[1 << 14], b[1 << 14], c[1 << 14];
    const char *common = "--integrator ic --width 24 --height 24 --spp 2 --rays 64 -q";
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "render " CORNELL " -o " TMP "_a.exr %s --accuracy 0.5 --stats " TMP "_a.json", common);
    CHECK(run(cmd) == 0, "render with --name value: %s", err_text);
    snprintf(cmd, sizeof cmd, "render " CORNELL " -o " TMP "_b.exr %s --accuracy=0.5 --stats=" TMP "_b.json", common);
    CHECK(run(cmd) == 0, "render with --name=value: %s", err_text);
    snprintf(cmd, sizeof cmd, "render -o " TMP "_c.exr %s --accuracy=0.5 --stats " TMP "_c.json -- " CORNELL, common);
    CHECK(run(cmd) == 0, "render with the scene after --: %s", err_text);
    test_read_text(TMP "_a.json", a, sizeof a);
    test_read_text(TMP "_b.json", b, sizeof b);
    test_read_text(TMP "_c.json", c, sizeof c);
    const char *ra = strstr(a, "\"records\""), *rb = strstr(b, "\"records\""), *rc = strstr(c, "\"records\"");
    CHECK(ra && rb && rc && atoi(ra + 10) > 0 && atoi(ra + 10) == atoi(rb + 10) && atoi(ra + 10) == atoi(rc + 10),
          "the three forms build the same cache");
    CHECK(run("render -o " TMP "_d.exr -- --not-an-option.json") == 1 && strstr(err_text, "--not-an-option.json"),
          "after --, a name starting with '-' is the scene: %s", err_text);
}

static void bad_values(void)
{
    static const struct { const char *args, *names; } cases[] = {
        {"--spp=0", "--spp"},
        {"--spp=", "--spp"},
        {"--quiet=yes", "--quiet"},
        {"--width 70000", "--width"},
        {"--threads 1e9", "--threads"},
        {"--threads 1000000000", "--threads"},
        {"--accuracy=-1 --integrator ic", "--accuracy"},
        {"--integrator=xyz", "pt|ic"},
        {"--aov indirect,nope --integrator ic", "nope"},
        {"--max-passes 4", "--integrator ic"},
        {"--integrator ic --strategy lazy --max-passes 4", "applies to --strategy batch only"},
        {"--integrator ic --weber 0.01", "applies to --strategy adaptive only"},
        {"--integrator ic --max-radius-px 1", "--min-radius-px 3 (its default) is larger"},
        {"--integrator ic --record-shape elliptical", "add --error hessian"},
        {"--integrator ic --error hessian --gather progressive", "--gather stratified or hemicube"},
        {"--recursive --integrator ic", "--strategy lazy"},
        {"--min-radius-px 9 --max-radius-px 4 --integrator ic", "--min-radius-px"},
        {"--seed -3", "--seed"},
        {"--seed ' -1'", "may not start with white space"},
        {"--width ' 5'", "--width"},
        {"--frobnicate=3", "--frobnicate"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i)
        usage_error(cases[i].args, cases[i].names);
}

/* The stats JSON goes through cJSON's writer: a scene path with a quote, a backslash and non-ASCII
 * letters comes out escaped, and the file parses; the settings echo what was given and the defaults. */
static void stats_json(void)
{
    const char *dir = TMP "_we\"ird\\dir_é";
    unlink(dir);
    CHECK(symlink(IC_SOURCE_DIR "/scenes/cornell-box", dir) == 0, "symlink %s", dir);
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "render '%s/cornell-box.json' -o " TMP "_s.exr --width 16 --height 16 --spp 2 -q "
             "--integrator=ic --rays 64 --seed 007 --stats " TMP "_s.json", dir);
    CHECK(run(cmd) == 0, "render through the odd path: %s", err_text);
    static char js[1 << 15];
    test_read_text(TMP "_s.json", js, sizeof js);
    CHECK(strstr(js, "_we\\\"ird\\\\dir_é/cornell-box.json\""), "the path is escaped: %.200s", js);
    CHECK(strstr(js, "\"settings\"") && strstr(js, "\"rays\":\t64") && strstr(js, "\"max_passes\":\t30") &&
              strstr(js, "\"integrator\":\t\"ic\""),
          "the settings: given values and defaults");
    CHECK(system("python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); "
                 "sys.exit(0 if d[\"settings\"][\"spp\"] == 2 and d[\"settings\"][\"seed\"] == 7 and \"we\\\"ird\" in d[\"scene\"] else 1)' "
                 TMP "_s.json") == 0,
          "the stats file parses as JSON");
    unlink(dir);
    /* Every strategy's stats have the same phases around its own: load first, the final render last. */
    const char *strategies[] = {"batch", "lazy", "adaptive"};
    for (int i = 0; i < 3; ++i) {
        snprintf(cmd, sizeof cmd, "render " CORNELL " -o " TMP "_p.exr --width 16 --height 16 --spp 2 -q "
                 "--integrator ic --rays 64 --strategy %s --stats " TMP "_p.json", strategies[i]);
        CHECK(run(cmd) == 0, "render with %s: %s", strategies[i], err_text);
        test_read_text(TMP "_p.json", js, sizeof js);
        const char *ph = strstr(js, "\"phases\"");
        CHECK(ph && strstr(ph, "\"load\"") && strstr(ph, "\"accel\"") && strstr(ph, "\"gathering\"") &&
                  strstr(ph, "\"final render\""),
              "%s: load, accel, gathering and final render phases: %.400s", strategies[i], ph ? ph : js);
    }
}

/* --min-radius-px 0 is no floor, as its help says: it gave the default 3 px (the library reads 0 as
 * "default"), the same records and bytes. A tiny floor and 0 agree; the default makes fewer records. */
static void radius_floor_zero(void)
{
    static char js[1 << 15];
    int records[3] = {-1, -1, -1};
    const char *floors[3] = {"0", "0.001", "3"};
    for (int k = 0; k < 3; ++k) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "render " CORNELL " -o " TMP "_rf.pfm --width 48 --height 48 --spp 1 -q --integrator "
                 "ic --rays 64 --min-radius-px %s --stats " TMP "_rf.json", floors[k]);
        CHECK(run(cmd) == 0, "--min-radius-px %s: %s", floors[k], err_text);
        test_read_text(TMP "_rf.json", js, sizeof js);
        const char *r = strstr(js, "\"records\":");
        records[k] = r ? atoi(r + strlen("\"records\":")) : -1;
    }
    CHECK(records[0] > 0 && records[0] == records[1] && records[2] < records[0],
          "records with floors 0, 0.001, 3 px: %d, %d, %d", records[0], records[1], records[2]);
    CHECK(run("render " CORNELL " -o " TMP "_rf.pfm --integrator ic --max-radius-px 0") == 2 &&
              strstr(err_text, "--max-radius-px 0"),
          "--max-radius-px 0 (no image at all) refused: %s", err_text);
}

/* The stats' passes (into *passes, -1 if missing) and the entries of their records_per_pass (-1 if missing). */
static int per_pass_entries(const char *js, int *passes)
{
    const char *p = strstr(js, "\"passes\":"), *per = strstr(js, "\"records_per_pass\":");
    const char *open = per ? strchr(per, '[') : NULL, *close = open ? strchr(open, ']') : NULL;
    *passes = p ? atoi(p + strlen("\"passes\":")) : -1;
    int entries = close ? 1 : -1; /* a number, then one a ',' */
    for (const char *q = open; close && q < close; ++q)
        entries += *q == ',';
    return entries;
}

/* Construction that a limit cuts short says so: a warning line and "cut_short" in the stats. */
static void cut_short(void)
{
    static char js[1 << 15];
    const char *base = "render " CORNELL " -o " TMP "_cs.exr --width 48 --height 48 --spp 2 -q --integrator ic "
                       "--rays 64 --stats " TMP "_cs.json";
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s --max-passes 1", base);
    CHECK(run(cmd) == 0, "render with --max-passes 1: %s", err_text);
    test_read_text(TMP "_cs.json", js, sizeof js);
    CHECK(strstr(js, "\"cut_short\":\ttrue") && strstr(err_text, "warning") && strstr(err_text, "--max-passes") &&
              lines(err_text) == 1,
          "one pass is cut short and says so: '%s'", err_text);
    /* The warning names the limit as given, and the passes as the stats count them: pass 0 (the geometry's
     * candidates) and the one pass after it; records_per_pass has one entry a pass. It said "(2 passes)" as
     * the limit. */
    int passes, entries = per_pass_entries(js, &passes);
    char want[160];
    snprintf(want, sizeof want, "stopped at its pass limit, --max-passes 1 (after the geometry pass 0: %d passes in "
             "the stats)", passes);
    CHECK(passes == 2 && entries == passes && strstr(err_text, want), "stats passes %d (%d entries), warning '%s'",
          passes, entries, err_text);
    /* More than 32 passes (the stats kept 32, the rest vanished): every pass has its entry. Here construction
     * never converges (a candidate a pass is enough, no growth test), so it runs to the bound: 41 passes. */
    CHECK(run("render " CORNELL " -o " TMP "_cs.pfm --width 32 --height 32 --spp 1 -q --integrator ic --rays 16 "
              "--accuracy 0.05 --max-passes 40 --min-candidates 1 --pass-growth off --stats " TMP "_cs.json") == 0,
          "render with --max-passes 40: %s", err_text);
    test_read_text(TMP "_cs.json", js, sizeof js);
    entries = per_pass_entries(js, &passes);
    CHECK(passes == 41 && entries == passes && !strstr(js, "passes_without_entry"),
          "41 passes, each with its records_per_pass entry (%d passes, %d entries)", passes, entries);
    snprintf(cmd, sizeof cmd, "%s --max-passes 100 --min-candidates 1000000", base);
    CHECK(run(cmd) == 0, "render that converges: %s", err_text);
    test_read_text(TMP "_cs.json", js, sizeof js);
    CHECK(strstr(js, "\"cut_short\":\tfalse") && !strstr(err_text, "warning"), "a converged build does not warn");
    /* The records' extents: positive, ordered, and within the pixel bounds' reach of the box (scene
     * diagonal about 3.5 units). */
    const char *ext = strstr(js, "\"record_extent\"");
    double lo = -1.0, mean = -1.0, hi = -1.0;
    CHECK(ext && sscanf(ext, "\"record_extent\":\t{\n\t\t\"min\":\t%lf,\n\t\t\"mean\":\t%lf,\n\t\t\"max\":\t%lf", &lo,
                        &mean, &hi) == 3,
          "record_extent in the stats: %.200s", ext ? ext : js);
    CHECK(lo > 0.0 && lo <= mean && mean <= hi && hi < 3.5, "record extents ordered: %g %g %g", lo, mean, hi);
}

int main(void)
{
    radius_floor_zero();
    cut_short();
    stats_json();
    readme_matches_table();
    help_layout();
    stdout_write_error();
    size_suffixes();
    help_ranges();
    command_help_ranges();
    value_forms();
    bad_values();
    TEST_MAIN_END();
}
