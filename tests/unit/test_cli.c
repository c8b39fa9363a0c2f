/*
 * test_cli.c — the irrcache command on bad input, one test per class (issue "Foundation", item 10):
 * malformed JSON, a missing mesh or texture, an unknown material or option, NaN vertices, a zero-area
 * light, impossible option values, an unwritable output. Each must give a non-zero exit, a single
 * line on stderr that names the file (and line where there is one), no crash, and no output file;
 * an existing output is left untouched. Also: degenerate triangles are dropped (not an error), a
 * good render writes every requested output and the stats JSON, and the JSON files stay valid JSON
 * whatever bytes the scene path holds, as do the EXR's text attributes.
 */
#include "test_util.h"
#include "test_files.h"

#include "core/text.h"
#include "irrcache/image.h"

#include <stdint.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#define CLI IC_CLI_PATH
#define SCENES IC_SOURCE_DIR "/tests/scenes/"
#define OUT IC_TEST_TMP "/cli_out.exr"
#define ERR IC_TEST_TMP "/cli_stderr.txt"

static char err_text[8192];

/* Runs the command line (stderr captured); returns the exit status, or -1 if it crashed. */
static int run(const char *args) { return test_run_quiet(ERR, err_text, sizeof err_text, "%s %s", CLI, args); }

typedef struct bad_case {
    const char *what;
    const char *args;       /* after "render" */
    int exit_code;
    const char *must_name;  /* text the message must contain (file name, file:line) */
} bad_case;

static void check_bad(const bad_case *c)
{
    remove(OUT);
    char args[2048];
    snprintf(args, sizeof args, "render %s -q", c->args);
    int rc = run(args);
    CHECK(rc == c->exit_code, "%s: exit %d, expected %d (stderr: %s)", c->what, rc, c->exit_code, err_text);
    CHECK(test_line_count(err_text) == 1, "%s: one line on stderr, got: %s", c->what, err_text);
    CHECK(strstr(err_text, c->must_name) != NULL, "%s: message names '%s': %s", c->what, c->must_name, err_text);
    CHECK(!test_file_exists(OUT), "%s: no output written", c->what);
}

/* cmd (a render that loads a cache file) is refused before rendering: exit 1, one line that says `says`, no
 * output. */
static void check_refusal(const char *cmd, const char *says)
{
    remove(OUT);
    CHECK(run(cmd) == 1 && strstr(err_text, says) && test_line_count(err_text) == 1 && !test_file_exists(OUT),
          "refused saying \"%s\": %s", says, err_text);
}

/* The JSON files (--stats, --records-json) go through cJSON's writer (the record list leaves out the hit
 * stage's records, which the stats count apart): a scene path with a double quote,
 * a backslash, control characters, non-ASCII UTF-8 and a byte that is not UTF-8 (written as U+FFFD)
 * still gives valid JSON, and counts are integers. Checked on the bytes, and with Python's strict
 * parser where python3 is installed. */
#define ODD_DIR IC_TEST_TMP "/cli_q\"b\\s\x01" "c\td\ne_\xc3\xa9_\xe9"
#define ODD_ESCAPED "cli_q\\\"b\\\\s\\u0001c\\td\\ne_\xc3\xa9_\xef\xbf\xbd/cornell-box.json\""
#define ODD_STATS IC_TEST_TMP "/cli_odd_stats.json"
#define ODD_RECORDS IC_TEST_TMP "/cli_odd_records.json"
#define ODD_CHECK IC_TEST_TMP "/cli_odd_check.py"

static void odd_path_json(void)
{
    unlink(ODD_DIR);
    remove(ODD_STATS);
    remove(ODD_RECORDS);
    CHECK(symlink(IC_SOURCE_DIR "/scenes/cornell-box", ODD_DIR) == 0, "symlink to the odd folder");
    int rc = run("render '" ODD_DIR "/cornell-box.json' -o " OUT " --integrator ic --width 16 --height 16 --spp 2 "
                 "--rays 64 --hit-records on -q --stats " ODD_STATS " --records-json " ODD_RECORDS
                 " --scenes-dir '" ODD_DIR "'");
    CHECK(rc == 0, "render through the odd path (exit %d: %s)", rc, err_text);
    static char js[1 << 15];
    FILE *f = fopen(ODD_STATS, "rb");
    size_t n = f ? fread(js, 1, sizeof js - 1, f) : 0;
    js[n] = 0;
    if (f)
        fclose(f);
    CHECK(strstr(js, ODD_ESCAPED) != NULL, "the scene path is escaped: %.300s", js);
    const char *rays = strstr(js, "\"rays\":\t");
    CHECK(rays && strspn(rays + 8, "0123456789") > 0 && rays[8 + strspn(rays + 8, "0123456789")] == ',',
          "rays is a plain integer: %.40s", rays ? rays : "(none)");
    CHECK(js[0] == '{' && strstr(js, "\n\t\"spp\":\t2,\n"), "pretty-printed, one key a line: %.120s", js);
    /* The EXR's text attributes are UTF-8 as well (OpenImageIO's Python binding refused the raw byte): the
     * scene's path, and the settings with --scenes-dir's. */
    static char attr[1 << 15];
    const char *names[2] = {"irrcache:scene", "irrcache:settings"};
    for (int k = 0; k < 2; ++k) {
        ic_error err;
        CHECK(ic_image_exr_attribute(OUT, names[k], attr, sizeof attr, &err) == IC_OK, "%s: %s", names[k],
              err.message);
        size_t at = 0, step = 1;
        while (attr[at] && (step = ic_utf8_sequence((const unsigned char *)attr + at, SIZE_MAX)) > 0)
            at += step;
        CHECK(!attr[at] && strstr(attr, "e_\xc3\xa9_\xef\xbf\xbd"),
              "%s is UTF-8, the byte that is not written as U+FFFD: %.200s", names[k], attr);
    }

    if (system("python3 -c '' >/dev/null 2>&1") != 0) {
        printf("python3 not found: the strict JSON parse of the odd-path outputs is skipped\n");
    } else {
        f = fopen(ODD_CHECK, "w");
        if (f) {
            fputs("import json, sys\n"
                  "s = json.load(open(sys.argv[1], encoding='utf-8'))\n"
                  "r = json.load(open(sys.argv[2], encoding='utf-8'))\n"
                  "want = 'cli_q\"b\\\\s\\x01c\\td\\ne_\\u00e9_\\ufffd/cornell-box.json'\n"
                  "keys = {'x', 'y', 'z', 'radius', 'a', 'px', 'py', 'radius_px', 'visible'}\n"
                  "ints = ['width', 'height', 'spp', 'threads', 'rays', 'records', 'passes', 'gather_rays',\n"
                  "        'hit_records']\n"
                  "ok = (s['scene'].endswith(want) and s['integrator'] == 'ic'\n"
                  "      and all(type(s[k]) is int for k in ints)\n"
                  "      and all(type(v) is int for v in s['records_per_pass'])\n"
                  "      and s['hit_records'] > 0 and isinstance(r, list)\n"
                  "      and len(r) == s['records'] - s['hit_records'] and all(set(x) == keys for x in r))\n"
                  "sys.exit(0 if ok else 1)\n",
                  f);
            fclose(f);
        }
        CHECK(system("python3 " ODD_CHECK " " ODD_STATS " " ODD_RECORDS) == 0,
              "stats and records parse as strict JSON with the exact path and integer counts");
    }
    unlink(ODD_DIR);
}

/* --records-json gives an image position only to records in front of the camera: a record behind it (the
 * sky-room's camera stands inside the room, and recursive lazy records lie on every wall) had px = py =
 * radius_px = 0, as if it sat at the top-left pixel. Which records are in front is decided here from the
 * scene's eye and target: (p − eye)·forward > 0. */
#define BEHIND_RECORDS IC_TEST_TMP "/cli_behind_records.json"
#define BEHIND_CHECK IC_TEST_TMP "/cli_behind_check.py"

static void records_behind_camera(void)
{
    remove(BEHIND_RECORDS);
    int rc = run("render " IC_SOURCE_DIR "/scenes/interiors/sky-room.json -o " OUT " --integrator ic --strategy lazy "
                 "--recursive --bounces 2 --rays 64 --width 16 --height 12 --spp 1 -q --records-json " BEHIND_RECORDS);
    CHECK(rc == 0, "sky-room with --records-json (exit %d: %s)", rc, err_text);
    static char js[1 << 20];
    size_t n = test_read_text(BEHIND_RECORDS, js, sizeof js);
    CHECK(n > 0 && n < sizeof js - 1, "the record list read (%zu bytes)", n);
    CHECK(!strstr(js, "\"radius_px\":\t0,"), "no record with a zero radius in pixels");
    if (system("python3 -c '' >/dev/null 2>&1") != 0) {
        printf("python3 not found: the records' sides of the camera are not checked\n");
        return;
    }
    CHECK(test_write_text(BEHIND_CHECK,
                          "import json, sys\n"
                          "r = json.load(open(sys.argv[1]))\n"
                          "eye, target = (0.5, 1.55, 0.45), (3.0, 1.2, 3.6)\n"
                          "f = [t - e for t, e in zip(target, eye)]\n"
                          "side = [sum((p - e) * g for p, e, g in zip((x['x'], x['y'], x['z']), eye, f)) for x in r]\n"
                          "behind = [x for x, s in zip(r, side) if s < -1e-3]\n"
                          "front = [x for x, s in zip(r, side) if s > 1e-3]\n"
                          "ok = (len(behind) > 0 and all('px' not in x and 'py' not in x and 'radius_px' not in x\n"
                          "                              and not x['visible'] for x in behind)\n"
                          "      and all(x['radius_px'] > 0 for x in front))\n"
                          "print(len(r), 'records,', len(behind), 'behind the camera')\n"
                          "sys.exit(0 if ok else 1)\n"),
          "write the check");
    CHECK(system("python3 " BEHIND_CHECK " " BEHIND_RECORDS) == 0,
          "records behind the camera have no image position, those in front a positive radius in pixels");
}

/* Every key --stats and --records-json write is in docs/outputs.md's tables (`key` in a row), so that a
 * script's author finds each: a batch cache with radiance records, hit records and elliptical records, an
 * adaptive one with adaptive sampling, the path tracer. Keys inside "settings" (the option table's own
 * names) and "phases" (described together) are left out. */
#define DOC_STATS IC_TEST_TMP "/cli_doc_stats_%d.json"
#define DOC_RECORDS IC_TEST_TMP "/cli_doc_records.json"
#define DOC_CHECK IC_TEST_TMP "/cli_doc_check.py"

static void output_keys_documented(void)
{
    if (system("python3 -c '' >/dev/null 2>&1") != 0) {
        printf("python3 not found: the documentation of the JSON keys is not checked\n");
        return;
    }
    const char *runs[3] = {
        "--integrator ic --rays 64 --radiance-cache on --error hessian --record-shape elliptical --min-radius-px 0.5 "
        "--records-json " DOC_RECORDS, "--integrator ic --rays 64 --strategy adaptive --spp 8", ""};
    char cmd[2048], files[3][512];
    for (int k = 0; k < 3; ++k) {
        snprintf(files[k], sizeof files[k], DOC_STATS, k);
        snprintf(cmd, sizeof cmd, "render " IC_SOURCE_DIR "/scenes/cornell-box-glossy/cornell-box-glossy-20.json "
                 "-o " OUT " --width 32 --height 32 --spp 1 -q --stats %s %s", files[k], runs[k]);
        int rc = run(cmd);
        CHECK(rc == 0, "render %d for the keys (exit %d: %s)", k, rc, err_text);
    }
    CHECK(test_write_text(DOC_CHECK,
                          "import json, re, sys\n"
                          "doc = open(sys.argv[1], encoding='utf-8').read()\n"
                          "rows = set(re.findall(r'`([a-z_]+)`', ''.join(l for l in doc.splitlines(True)\n"
                          "                                              if l.startswith('|'))))\n"
                          "keys = set()\n"
                          "def walk(o):\n"
                          "    if isinstance(o, dict):\n"
                          "        for k, v in o.items():\n"
                          "            keys.add(k)\n"
                          "            if k not in ('settings', 'phases'):\n"
                          "                walk(v)\n"
                          "    elif isinstance(o, list):\n"
                          "        for v in o:\n"
                          "            walk(v)\n"
                          "for f in sys.argv[2:]:\n"
                          "    walk(json.load(open(f, encoding='utf-8')))\n"
                          "missing = sorted(keys - rows)\n"
                          "print('undocumented keys:', missing) if missing else None\n"
                          "sys.exit(1 if missing else 0)\n"),
          "write the check");
    snprintf(cmd, sizeof cmd, "python3 " DOC_CHECK " " IC_SOURCE_DIR "/docs/outputs.md %s %s %s " DOC_RECORDS,
             files[0], files[1], files[2]);
    CHECK(system(cmd) == 0, "every key of --stats and --records-json is in docs/outputs.md");
    static char js[1 << 21];
    test_read_text(DOC_RECORDS, js, sizeof js);
    CHECK(strstr(js, "\"radiance\":") && strstr(js, "\"ellipse_ratio\":"),
          "the record list holds radiance and elliptical records, whose keys are checked too");
}

int main(void)
{
    const bad_case cases[] = {
        {"malformed JSON", SCENES "malformed.json -o " OUT, 1, "malformed.json:5:"},
        {"missing mesh", SCENES "missing_mesh.json -o " OUT, 1, "missing_mesh.json:"},
        {"missing texture", SCENES "missing_texture.obj -o " OUT, 1, "missing_texture"},
        {"unknown material", SCENES "unknown_material.json -o " OUT, 1, "unknown_material.json:"},
        {"unknown key", SCENES "unknown_key.json -o " OUT, 1, "unknown_key.json:"},
        {"NaN vertex", SCENES "nan_vertex.json -o " OUT, 1, "nan_vertex.obj:6:"},
        {"NaN texture coordinate", SCENES "nan_uv.obj -o " OUT, 1, "nan_uv.obj:8: texture coordinate (vt) 3"},
        {"infinite normal", SCENES "nan_normal.obj -o " OUT, 1, "nan_normal.obj:7: normal (vn) 2"},
        {"NaN glTF normal", SCENES "nan_normal.gltf -o " OUT, 1, "nan_normal.gltf: vertex 2 of mesh 'tri'"},
        {"zero-area light", SCENES "zero_area_light.json -o " OUT, 1, "zero_area_light"},
        {"bad resolution in scene", SCENES "bad_resolution.json -o " OUT, 1, "bad_resolution.json:"},
        {"missing scene file", SCENES "no_such_scene.json -o " OUT, 1, "no_such_scene.json"},
        {"unknown option", SCENES "plain_quad.obj -o " OUT " --frobnicate", 2, "--frobnicate"},
        {"zero spp", SCENES "plain_quad.obj -o " OUT " --spp 0", 2, "--spp"},
        /* capped as the scene file caps them (IC_MAX_SPP, IC_MAX_LIGHT_SAMPLES): refused before the scene is read */
        {"spp above the cap", SCENES "no_such_scene.json -o " OUT " --spp 16777217", 2,
         "--spp 16777217: expected an integer from 1 to 16777216"},
        {"light samples above the cap", SCENES "no_such_scene.json -o " OUT " --integrator ic --light-samples 65537", 2,
         "--light-samples 65537: expected an integer from 1 to 65536"},
        {"texture over --max-texture-pixels", SCENES "plain_quad.obj -o " OUT " --max-texture-pixels 3", 1,
         "raise the limit with --max-texture-pixels"},
        {"scene over --max-scene-bytes", IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json -o " OUT
         " --max-scene-bytes 100", 1, "raise the limit with --max-scene-bytes"},
        {"image over --max-image-pixels", SCENES "plain_quad.obj -o " OUT " --width 64 --height 65 --max-image-pixels 4K",
         1, "an image of 64 x 65 = 4160 pixels, more than the limit of 4096"},
        {"image over the default limit", SCENES "plain_quad.obj -o " OUT " --width 16384 --height 16384", 1,
         "raise the limit with --max-image-pixels"},
        /* beyond what the library's images hold: refused before the render, not out of memory after it */
        {"image over the library's largest", SCENES "plain_quad.obj -o " OUT " --width 16384 --height 16385 "
         "--max-image-pixels 256M", 1, "more than 268435456 (16384 x 16384), the largest image the library holds"},
        {"--max-scene-bytes of 0", SCENES "plain_quad.obj -o " OUT " --max-scene-bytes 0", 2,
         "--max-scene-bytes 0: expected a whole number from 1 to"},
        {"--max-scene-bytes with an unknown suffix", SCENES "plain_quad.obj -o " OUT " --max-scene-bytes 64Q", 2,
         "--max-scene-bytes 64Q"},
        {"--max-cache-bytes without ic", SCENES "plain_quad.obj -o " OUT " --max-cache-bytes 1M", 2,
         "--integrator ic"},
        {"max depth above the cap", SCENES "no_such_scene.json -o " OUT " --max-depth 1025", 2, "--max-depth 1025"},
        {"non-numeric width", SCENES "plain_quad.obj -o " OUT " --width abc", 2, "--width"},
        {"negative time", SCENES "plain_quad.obj -o " OUT " --time -1", 2, "--time"},
        {"unknown integrator", SCENES "plain_quad.obj -o " OUT " --integrator xyz", 2, "xyz"},
        {"unknown strategy", SCENES "plain_quad.obj -o " OUT " --integrator ic --strategy xyz", 2, "xyz"},
        {"cache option without ic", SCENES "plain_quad.obj -o " OUT " --accuracy 0.2", 2, "--integrator ic"},
        {"unknown output format", SCENES "plain_quad.obj -o " IC_TEST_TMP "/x.bmp", 2, "x.bmp"},
        /* an empty path is said to be one (it was "unknown image format"); so is an empty name or file */
        {"empty output path", SCENES "plain_quad.obj -o ''", 2, "--output '': the output path is empty"},
        {"empty output path after =", SCENES "plain_quad.obj --output=", 2, "--output '': the output path is empty"},
        {"empty --view", SCENES "plain_quad.obj -o " OUT " --view ''", 2, "--view '': the value is empty"},
        {"empty --stats", SCENES "plain_quad.obj -o " OUT " --stats=", 2, "--stats '': the value is empty"},
        {"unwritable output", SCENES "plain_quad.obj -o " IC_TEST_TMP "/no/such/dir/x.exr", 2, "no/such/dir/x.exr"},
        {"no output", SCENES "plain_quad.obj", 2, "-o"},
        /* the command's own messages keep to one line whatever a path holds (a newline as \x0a) */
        {"output path with a newline", SCENES "plain_quad.obj -o '" IC_TEST_TMP "/no/such/dir/a\nb.exr'", 2,
         "/no/such/dir/a\\x0ab.exr"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i)
        check_bad(&cases[i]);

    /* A points file whose name holds an escape sequence and a carriage return: named with them as \xNN, on one
     * line, and nothing sent to the terminal that would clear it. */
    int prc = run("points " SCENES "plain_quad.obj --points '" IC_TEST_TMP "/no_such\x1b[2J\rpoints.txt'");
    CHECK(prc == 1 && test_line_count(err_text) == 1 && strstr(err_text, "no_such\\x1b[2J\\x0dpoints.txt") &&
              !strchr(err_text, '\x1b') && !strchr(err_text, '\r'),
          "a points file's odd name is escaped (exit %d): %s", prc, err_text);

    /* Nothing lost: a failed render leaves an existing output as it was. */
    FILE *f = fopen(OUT, "w");
    fputs("precious", f);
    fclose(f);
    run("render " SCENES "malformed.json -o " OUT " -q");
    f = fopen(OUT, "r");
    char buf[16] = {0};
    CHECK(f && fread(buf, 1, 15, f) == 8 && !strcmp(buf, "precious"), "existing output untouched after a failure");
    if (f)
        fclose(f);

    /* A good render: every output and the stats, degenerate triangles dropped without an error. */
    remove(OUT);
    int rc = run("render " SCENES "degenerate.json -o " OUT " -o " IC_TEST_TMP "/cli_out.png --spp 2 --width 16 "
                 "--height 16 -q --stats " IC_TEST_TMP "/cli_stats.json");
    CHECK(rc == 0, "degenerate triangles are not an error (exit %d: %s)", rc, err_text);
    CHECK(test_file_exists(OUT) && test_file_exists(IC_TEST_TMP "/cli_out.png"), "both outputs written");
    f = fopen(IC_TEST_TMP "/cli_stats.json", "r");
    char stats[4096] = {0};
    if (f) {
        size_t n = fread(stats, 1, sizeof stats - 1, f);
        stats[n] = 0;
        fclose(f);
    }
    CHECK(strstr(stats, "\"seconds\"") && strstr(stats, "\"rays\"") && strstr(stats, "\"rays_per_second\"") &&
              strstr(stats, "\"phases\""),
          "stats JSON has seconds, rays, rays_per_second, phases: %s", stats);

    /* A Mitsuba scene with an element irrcache does not render: rendered, with one warning line naming it. */
    rc = run("render " SCENES "mitsuba_warn.xml -o " OUT " --spp 1 --width 8 --height 8 -q");
    CHECK(rc == 0 && strstr(err_text, "warning: ") && strstr(err_text, "mitsuba_warn.xml:3: <shape type=\"hair\">") &&
              test_line_count(err_text) == 1,
          "one warning line for the unsupported shape (exit %d): %s", rc, err_text);
    rc = run("render " SCENES "mitsuba_warn.xml -o " OUT " --camera front -q");
    CHECK(rc == 1 && strstr(err_text, "--camera front"), "--camera is refused for a Mitsuba scene: %s", err_text);

    /* A scene nothing lights: rendered (exit 0) with a one-line warning that the image is black. */
    rc = run("render " SCENES "no_light.json -o " OUT " --spp 1 -q");
    CHECK(rc == 0 && strstr(err_text, "warning: ") && strstr(err_text, "no_light.json has no light") &&
              strstr(err_text, "black") && test_line_count(err_text) == 1,
          "no light: a warning (exit %d: %s)", rc, err_text);
    rc = run("render " SCENES "quad_light.obj -o " OUT " --spp 1 --width 8 --height 8 -q");
    CHECK(rc == 0 && err_text[0] == '\0', "a lit scene: no warning (exit %d: %s)", rc, err_text);

    /* Cache files: records saved by one run render the same image when loaded by the next; a file made
     * with other gathering settings, or a truncated one, is refused without writing an output. */
    const char *ic = "render " IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json --integrator ic --width 24 "
                     "--height 24 --spp 2 -q ";
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "%s -o %s/ic_a.pfm --save-cache %s/ic.icc", ic, IC_TEST_TMP, IC_TEST_TMP);
    CHECK(run(cmd) == 0, "render and save the cache: %s", err_text);
    snprintf(cmd, sizeof cmd, "%s -o %s/ic_b.pfm --load-cache %s/ic.icc", ic, IC_TEST_TMP, IC_TEST_TMP);
    CHECK(run(cmd) == 0, "render from the saved cache: %s", err_text);
    FILE *fa = fopen(IC_TEST_TMP "/ic_a.pfm", "rb"), *fb = fopen(IC_TEST_TMP "/ic_b.pfm", "rb");
    static char ba[1 << 16], bb[1 << 16];
    size_t na = fa ? fread(ba, 1, sizeof ba, fa) : 0, nb = fb ? fread(bb, 1, sizeof bb, fb) : 1;
    CHECK(na > 0 && na == nb && memcmp(ba, bb, na) == 0, "loaded cache renders the identical image");
    if (fa)
        fclose(fa);
    if (fb)
        fclose(fb);
    /* Another seed re-uses the records (the seed is not part of the cache's identity) and draws new
     * final-render samples: the image changes. */
    /* --max-cache-bytes: below the file's size it is refused naming the option; "8M" is far above it. */
    remove(OUT);
    snprintf(cmd, sizeof cmd, "%s -o %s --load-cache %s/ic.icc --max-cache-bytes 100", ic, OUT, IC_TEST_TMP);
    CHECK(run(cmd) == 1 && strstr(err_text, "--max-cache-bytes") && test_line_count(err_text) == 1 &&
              !test_file_exists(OUT),
          "a cache over --max-cache-bytes refused: %s", err_text);
    snprintf(cmd, sizeof cmd, "%s -o %s --load-cache %s/ic.icc --max-cache-bytes 8M", ic, OUT, IC_TEST_TMP);
    CHECK(run(cmd) == 0, "--max-cache-bytes 8M loads it: %s", err_text);
    snprintf(cmd, sizeof cmd, "%s -o %s/ic_c.pfm --load-cache %s/ic.icc --seed 5", ic, IC_TEST_TMP, IC_TEST_TMP);
    CHECK(run(cmd) == 0, "render from the saved cache with another seed: %s", err_text);
    FILE *fc = fopen(IC_TEST_TMP "/ic_c.pfm", "rb");
    static char bc[1 << 16];
    size_t nc = fc ? fread(bc, 1, sizeof bc, fc) : 0;
    CHECK(nc == na && memcmp(ba, bc, na) != 0, "another seed over the same records gives another sample of the image");
    if (fc)
        fclose(fc);
    remove(OUT);
    /* The refusal names the setting that differs, both values (--rays 100 is 6 x 17 strata), what to do. */
    snprintf(cmd, sizeof cmd, "%s -o %s --load-cache %s/ic.icc --rays 100", ic, OUT, IC_TEST_TMP);
    check_refusal(cmd, "ic.icc: made without --rays, this run has --rays 102 (6 x 17 strata); rerun without --rays, "
                       "or build the cache again instead of loading it");
    snprintf(cmd, sizeof cmd, "%s -o %s --save-cache %s/ic_rays.icc --rays 300 --no-gradients", ic, OUT, IC_TEST_TMP);
    CHECK(run(cmd) == 0, "save with --rays 300: %s", err_text);
    snprintf(cmd, sizeof cmd, "%s -o %s --load-cache %s/ic_rays.icc --rays 200 --no-gradients", ic, OUT, IC_TEST_TMP);
    check_refusal(cmd, "ic_rays.icc: made with --rays 300 (10 x 30 strata), this run has --rays 200 (8 x 25 strata); "
                       "rerun with --rays 300 (10 x 30 strata), or build");
    snprintf(cmd, sizeof cmd, "%s -o %s --load-cache %s/ic_rays.icc --rays 300", ic, OUT, IC_TEST_TMP);
    check_refusal(cmd, "made with --no-gradients, which this run does not give; rerun with --no-gradients,");
    snprintf(cmd, sizeof cmd, "%s -o %s --load-cache %s/ic_rays.icc --rays 300 --no-gradients", ic, OUT, IC_TEST_TMP);
    CHECK(run(cmd) == 0 && test_file_exists(OUT), "rerun as the message says: loads (%s)", err_text);
    /* The scene changed since the cache was saved (the floor moved): said so, naming the scene file. */
    {
        const char *mtl = "newmtl emitter\nKd 0 0 0\nKe 10 10 10\nnewmtl grey\nKd 0.5 0.5 0.5\n";
        const char *obj = "mtllib cli_moved.mtl\nv -0.5 1 0.25\nv 0.5 1 0.25\nv 0.5 1 -0.25\nv -0.5 1 -0.25\n"
                          "v -2 %s -2\nv -2 %s 2\nv 2 %s 2\nv 2 %s -2\nusemtl emitter\nf 4 3 2 1\nusemtl grey\n"
                          "f 5 6 7 8\n";
        char text[512];
        snprintf(text, sizeof text, obj, "0", "0", "0", "0");
        CHECK(test_write_text(IC_TEST_TMP "/cli_moved.mtl", mtl) && test_write_text(IC_TEST_TMP "/cli_moved.obj", text),
              "scene files");
        const char *moved = "render " IC_TEST_TMP "/cli_moved.obj --integrator ic --width 16 --height 16 --spp 1 "
                            "--rays 64 -q -o " OUT " ";
        snprintf(cmd, sizeof cmd, "%s --save-cache %s/ic_moved.icc", moved, IC_TEST_TMP);
        CHECK(run(cmd) == 0, "save for the first floor: %s", err_text);
        snprintf(text, sizeof text, obj, "-0.1", "-0.1", "-0.1", "-0.1");
        CHECK(test_write_text(IC_TEST_TMP "/cli_moved.obj", text), "move the floor");
        snprintf(cmd, sizeof cmd, "%s --load-cache %s/ic_moved.icc", moved, IC_TEST_TMP);
        check_refusal(cmd, "ic_moved.icc: made for another scene (" IC_TEST_TMP "/cli_moved.obj, or a file it names, "
                           "changed since the cache was saved); render the scene as it was, or build the cache again");
    }
    remove(OUT);
    FILE *full = fopen(IC_TEST_TMP "/ic.icc", "rb"), *cut = fopen(IC_TEST_TMP "/ic_cut.icc", "wb");
    if (full && cut) {
        char chunk[512];
        size_t n = fread(chunk, 1, sizeof chunk, full);
        fwrite(chunk, 1, n, cut);
    }
    if (full)
        fclose(full);
    if (cut)
        fclose(cut);
    snprintf(cmd, sizeof cmd, "%s -o %s --load-cache %s/ic_cut.icc", ic, OUT, IC_TEST_TMP);
    CHECK(run(cmd) == 1 && strstr(err_text, "ic_cut.icc") && !test_file_exists(OUT), "truncated cache refused: %s",
          err_text);

    /* Adaptive sampling it cannot do is refused before anything is rendered. */
    snprintf(cmd, sizeof cmd, "%s -o %s --adaptive-sampling on --time 1", ic, OUT);
    CHECK(run(cmd) == 2 && strstr(err_text, "--time") && test_line_count(err_text) == 1 && !test_file_exists(OUT),
          "--adaptive-sampling on with --time refused: %s", err_text);
    snprintf(cmd, sizeof cmd, "%s -o %s --adaptive-sampling on --spp 4", ic, OUT);
    CHECK(run(cmd) == 2 && strstr(err_text, "--spp") && test_line_count(err_text) == 1 && !test_file_exists(OUT),
          "--adaptive-sampling on with 4 spp refused: %s", err_text);
    snprintf(cmd, sizeof cmd, "%s -o %s --adaptive-sampling maybe", ic, OUT);
    CHECK(run(cmd) == 2 && strstr(err_text, "on|off") && !test_file_exists(OUT),
          "--adaptive-sampling maybe refused: %s", err_text);

    /* A large-emitter threshold that is not a share of the hemisphere is refused. */
    const char *bad_shares[] = {"abc", "0", "-0.1", "2"};
    for (int k = 0; k < 4; ++k) {
        snprintf(cmd, sizeof cmd, "%s -o %s --large-emitters %s", ic, OUT, bad_shares[k]);
        CHECK(run(cmd) == 2 && strstr(err_text, "--large-emitters") && test_line_count(err_text) == 1 &&
                  !test_file_exists(OUT),
              "--large-emitters %s refused: %s", bad_shares[k], err_text);
    }

    odd_path_json();
    records_behind_camera();
    output_keys_documented();

    /* Help lists every option with its default. */
    rc = run("render --help >" IC_TEST_TMP "/cli_help.txt");
    CHECK(rc == 0, "render --help exits 0");
    TEST_MAIN_END();
}
