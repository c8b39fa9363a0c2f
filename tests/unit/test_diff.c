/*
 * test_diff.c — the `irrcache diff` sub-command: JSON and table output, exit codes, error lines
 * and the heat map, whose default scale is fixed (two images' maps against one reference compare), and the
 * blotch map.
 *
 * cli/diff.c, json_out.c and options.c (the option tables) are compiled into this test (they depend on the
 * image library and cJSON only), so the command is tested without building the whole renderer; stdout and
 * stderr are captured through files.
 */
#include "../../cli/diff.c"
#include "../../cli/json_out.c"
#include "../../cli/options.c"
#include "../../cli/message.c"

#include "test_util.h"

#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef IC_TEST_TMP
#define IC_TEST_TMP "/tmp"
#endif
#define SCRATCH IC_TEST_TMP "/diff"

static char out_text[8192], err_text[8192];

static void slurp(const char *path, char *buf, size_t size)
{
    buf[0] = '\0';
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return;
    size_t n = fread(buf, 1, size - 1, fp);
    buf[n] = '\0';
    fclose(fp);
}

/* Runs ic_cli_diff with the given arguments (after "diff"), capturing stdout and stderr. */
static int run_diff(int count, const char *const *args)
{
    char *argv[16];
    argv[0] = (char *)"diff";
    for (int i = 0; i < count && i < 15; ++i)
        argv[i + 1] = (char *)args[i];
    fflush(stdout);
    fflush(stderr);
    int saved_out = dup(STDOUT_FILENO), saved_err = dup(STDERR_FILENO);
    FILE *out = fopen(SCRATCH "/stdout.txt", "wb"), *err = fopen(SCRATCH "/stderr.txt", "wb");
    if (saved_out < 0 || saved_err < 0 || !out || !err) {
        fprintf(stderr, "cannot capture output\n");
        exit(1);
    }
    dup2(fileno(out), STDOUT_FILENO);
    dup2(fileno(err), STDERR_FILENO);
    int status = ic_cli_diff(count + 1, argv);
    fflush(stdout);
    fflush(stderr);
    dup2(saved_out, STDOUT_FILENO);
    dup2(saved_err, STDERR_FILENO);
    close(saved_out);
    close(saved_err);
    fclose(out);
    fclose(err);
    slurp(SCRATCH "/stdout.txt", out_text, sizeof out_text);
    slurp(SCRATCH "/stderr.txt", err_text, sizeof err_text);
    return status;
}

/* Value of "key": in a one-line JSON object, NAN if absent. */
static double json_value(const char *json, const char *key)
{
    char pattern[64];
    snprintf(pattern, sizeof pattern, "\"%s\":", key);
    const char *at = strstr(json, pattern);
    return at ? strtod(at + strlen(pattern), NULL) : NAN;
}

static void write_constant(const char *path, int w, int h, float v)
{
    ic_image img;
    ic_error err;
    ic_image_create(&img, w, h);
    for (size_t i = 0; i < (size_t)w * (size_t)h * 3; ++i)
        img.rgb[i] = v;
    if (ic_image_write(path, &img, NULL, &err) != IC_OK)
        fprintf(stderr, "%s\n", err.message);
    ic_image_free(&img);
}

/* A 16x12 image at 1 + 1.01 e (relative error e against 1) with pixel 5 at relative error 0.2. */
static void write_errors(const char *path, float e)
{
    ic_image img;
    ic_error err;
    ic_image_create(&img, 16, 12);
    for (size_t i = 0; i < (size_t)16 * 12 * 3; ++i)
        img.rgb[i] = 1.0f + 1.01f * (i / 3 == 5 ? 0.2f : e);
    if (ic_image_write(path, &img, NULL, &err) != IC_OK)
        fprintf(stderr, "%s\n", err.message);
    ic_image_free(&img);
}

/* Pixel 5 of the heat map at path (-1s if unreadable). */
static void heat_pixel(const char *path, float rgb[3])
{
    ic_image map = {0};
    ic_error err;
    rgb[0] = rgb[1] = rgb[2] = -1.0f;
    if (ic_image_read(path, &map, &err) == IC_OK && map.width == 16 && map.height == 12)
        memcpy(rgb, map.rgb + 3 * 5, 3 * sizeof(float));
    ic_image_free(&map);
}

/* Two images whose pixel 5 has the same error, one with small errors elsewhere and one with large ones:
 * with the default scale their heat maps give pixel 5 the same colour, and both record the scale; with
 * --max-error auto (each image's 99th percentile) they do not. */
static void heat_maps_compare(void)
{
    const char *ref = SCRATCH "/ones.exr", *calm = SCRATCH "/calm.exr", *wild = SCRATCH "/wild.exr",
               *heat_calm = SCRATCH "/calm.heat.png", *heat_wild = SCRATCH "/wild.heat.png";
    write_constant(ref, 16, 12, 1.0f);
    write_errors(calm, 0.1f);
    write_errors(wild, 0.8f);
    float a[3], b[3];
    const char *calm_args[] = {calm, ref, "--json", "--heatmap", heat_calm};
    CHECK(run_diff(5, calm_args) == 0, "calm: %s", err_text);
    CHECK(json_value(out_text, "heatmap_max_error") == (double)IC_DEFAULT_HEATMAP_MAX_ERROR &&
              strstr(out_text, "\"heatmap_scale\":\"fixed\""),
          "the default scale is recorded: %s", out_text);
    const char *wild_args[] = {wild, ref, "--heatmap", heat_wild};
    CHECK(run_diff(4, wild_args) == 0, "wild: %s", err_text);
    CHECK(strstr(out_text, "wild.heat.png (relative error 0 = blue to 0.5 = red: fixed scale)"),
          "the table prints the scale: %s", out_text);
    heat_pixel(heat_calm, a);
    heat_pixel(heat_wild, b);
    CHECK(a[0] >= 0.0f && !memcmp(a, b, sizeof a), "the same error, the same colour: %g %g %g vs %g %g %g", a[0],
          a[1], a[2], b[0], b[1], b[2]);

    const char *calm_auto[] = {calm, ref, "--json", "--heatmap", heat_calm, "--max-error", "auto"};
    CHECK(run_diff(7, calm_auto) == 0 && strstr(out_text, "\"heatmap_scale\":\"p99\""), "auto: %s %s", out_text,
          err_text);
    CHECK_NEAR(json_value(out_text, "heatmap_max_error"), 0.1, 1e-5, "auto records the image's 99th percentile");
    const char *wild_auto[] = {wild, ref, "--heatmap", heat_wild, "--max-error=0"};
    CHECK(run_diff(5, wild_auto) == 0 && strstr(out_text, "this image's 99th percentile"), "0 is auto: %s", out_text);
    heat_pixel(heat_calm, a);
    heat_pixel(heat_wild, b);
    CHECK(memcmp(a, b, sizeof a) != 0, "per-image scales colour the same error differently");
}

static int one_line(const char *s)
{
    const char *nl = strchr(s, '\n');
    return nl && nl[1] == '\0';
}

int main(void)
{
    if (mkdir(IC_TEST_TMP, 0755) != 0 && errno != EEXIST)
        perror(IC_TEST_TMP);
    if (mkdir(SCRATCH, 0755) != 0 && errno != EEXIST)
        perror(SCRATCH);
    const char *ref = SCRATCH "/ref.exr", *same = SCRATCH "/same.pfm", *off = SCRATCH "/off.exr",
               *small = SCRATCH "/small.exr", *heat = SCRATCH "/heat.png";
    write_constant(ref, 16, 12, 0.5f);
    write_constant(same, 16, 12, 0.5f);
    write_constant(off, 16, 12, 0.6f);
    write_constant(small, 8, 8, 0.5f);
    remove(heat);

    /* A map may not overwrite an image compared, nor the other map (--heatmap A replaced A, exit 0). */
    {
        const char *onto_input[] = {off, ref, "--heatmap", off};
        FILE *f = fopen(off, "rb");
        long before = f && fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
        if (f)
            fclose(f);
        CHECK(run_diff(4, onto_input) == 2 && strstr(err_text, "the same file as") && one_line(err_text),
              "--heatmap onto an input: usage error: %s", err_text);
        f = fopen(off, "rb");
        long after = f && fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -2;
        if (f)
            fclose(f);
        CHECK(before == after, "the input is untouched (%ld bytes, then %ld)", before, after);
        const char *two_maps[] = {off, ref, "--heatmap", heat, "--blotch-map", heat};
        CHECK(run_diff(6, two_maps) == 2 && strstr(err_text, "--blotch-map") && strstr(err_text, "--heatmap"),
              "the two maps on one file: usage error: %s", err_text);
    }

    /* Identical images: one JSON object, infinite PSNR as 999.0. */
    const char *identical[] = {same, ref, "--json"};
    CHECK(run_diff(3, identical) == 0, "identical: %s", err_text);
    CHECK(out_text[0] == '{' && one_line(out_text) && strstr(out_text, "}\n"), "not one JSON line: %s", out_text);
    CHECK(json_value(out_text, "rmse") == 0.0 && json_value(out_text, "relmse") == 0.0 &&
              json_value(out_text, "ssim") == 1.0 && json_value(out_text, "width") == 16.0 &&
              json_value(out_text, "height") == 12.0,
          "identical JSON: %s", out_text);
    CHECK(strstr(out_text, "\"psnr_hdr\":999") && strstr(out_text, "\"psnr_ldr\":999"), "infinite PSNR: %s",
          out_text);
    CHECK(err_text[0] == '\0', "stderr not empty: %s", err_text);

    /* Constant offset: known values; a heat map is written. */
    const char *offset[] = {off, ref, "--json", "--heatmap", heat, "--max-error=0.5"};
    CHECK(run_diff(6, offset) == 0, "offset: %s", err_text);
    double d = (double)0.6f - 0.5;
    CHECK_NEAR(json_value(out_text, "rmse"), d, 1e-8, "rmse");
    CHECK_NEAR(json_value(out_text, "psnr_hdr"), 10.0 * log10(0.25 / (d * d)), 1e-6, "psnr_hdr");
    ic_image map = {0};
    ic_error err;
    CHECK(ic_image_read(heat, &map, &err) == IC_OK && map.width == 16 && map.height == 12, "heat map: %s",
          err.message);
    ic_image_free(&map);

    /* The JSON parses (strictly: one object, nothing after it) with every metric a number, and a
     * heat-map path with a quote, a backslash, control characters, UTF-8 and a non-UTF-8 byte comes
     * back exactly (the byte as U+FFFD). */
    const char *odd_heat = SCRATCH "/heat q\"b\\s\x01" "c\td_\xc3\xa9_\xe9.png";
    const char *odd_heat_json = SCRATCH "/heat q\"b\\s\x01" "c\td_\xc3\xa9_\xef\xbf\xbd.png";
    const char *odd[] = {off, ref, "--json", "--heatmap", odd_heat};
    CHECK(run_diff(5, odd) == 0, "odd heat-map path: %s", err_text);
    CHECK(one_line(out_text), "one JSON line: %s", out_text);
    const char *end = NULL;
    cJSON *parsed = cJSON_ParseWithOpts(out_text, &end, 0);
    CHECK(cJSON_IsObject(parsed) && end && !strcmp(end, "\n"), "diff --json parses: %s", out_text);
    const char *metric_keys[] = {"width", "height", "rmse", "relmse", "relmse_lowpass", "psnr_hdr", "psnr_ldr",
                                 "ssim", "nonfinite"};
    for (size_t k = 0; k < sizeof metric_keys / sizeof metric_keys[0]; ++k)
        CHECK(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(parsed, metric_keys[k])), "%s is a number: %s",
              metric_keys[k], out_text);
    const char *hm = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(parsed, "heatmap"));
    CHECK(hm && !strcmp(hm, odd_heat_json), "heatmap path round-trips: %s", out_text);
    CHECK(strstr(out_text, "\"width\":16,") && strstr(out_text, "\"nonfinite\":0"), "integers print as integers: %s",
          out_text);
    cJSON_Delete(parsed);
    if (system("python3 -c '' >/dev/null 2>&1") == 0)
        CHECK(system("python3 -c 'import json, sys; d = json.load(open(sys.argv[1], encoding=\"utf-8\")); "
                     "sys.exit(0 if d[\"heatmap\"].endswith(\"_\\u00e9_\\ufffd.png\") else 1)' " SCRATCH
                     "/stdout.txt") == 0,
              "diff --json is strict JSON (python3): %s", out_text);
    else
        printf("python3 not found: the strict parse of diff --json is skipped\n");
    remove(odd_heat);

    heat_maps_compare();

    /* The blotch map: written, recorded in the JSON and the table, a uniform offset (A brighter by 20 %)
     * red all over at the default scale. */
    const char *blotch = SCRATCH "/blotch.png";
    remove(blotch);
    const char *blotch_args[] = {off, ref, "--json", "--blotch-map", blotch};
    CHECK(run_diff(5, blotch_args) == 0 && strstr(out_text, "\"blotch_map\":\"" SCRATCH "/blotch.png\"") &&
              json_value(out_text, "blotch_max_error") == (double)IC_DEFAULT_BLOTCH_MAX_ERROR,
          "blotch map in the JSON: %s %s", out_text, err_text);
    CHECK(ic_image_read(blotch, &map, &err) == IC_OK && map.width == 16 && map.height == 12 && map.rgb[0] > 0.99f &&
              map.rgb[2] == 0.0f,
          "blotch map: red where A is brighter: %s", err.message);
    ic_image_free(&map);
    const char *blotch_table[] = {off, ref, "--blotch-map", blotch, "--blotch-max-error", "0.5"};
    CHECK(run_diff(6, blotch_table) == 0 && strstr(out_text, "blotch.png (low-pass relative error") &&
              strstr(out_text, "full at 0.5)"),
          "the table names the blotch map and its scale: %s", out_text);

    /* `--` ends the options: what follows is an image path even if it starts with "--". */
    const char *dashdash[] = {"--json", "--", off, ref};
    CHECK(run_diff(4, dashdash) == 0 && out_text[0] == '{', "--json -- A B: %s", err_text);
    const char *dash_path[] = {off, "--", "--json"};
    CHECK(run_diff(3, dash_path) == 1 && one_line(err_text) && strstr(err_text, "--json") && out_text[0] == '\0',
          "after --, --json is a file name: %s", err_text);

    /* The table. */
    const char *table[] = {off, ref};
    CHECK(run_diff(2, table) == 0, "table: %s", err_text);
    CHECK(strstr(out_text, "RMSE") && strstr(out_text, "PSNR LDR") && strstr(out_text, "SSIM") &&
              strstr(out_text, "off.exr"),
          "table: %s", out_text);

    /* Help lists every option with its default. */
    const char *help[] = {"--help"};
    CHECK(run_diff(1, help) == 0, "help exit");
    CHECK(strstr(out_text, "--json") && strstr(out_text, "--heatmap") && strstr(out_text, "--max-error") &&
              strstr(out_text, "--blotch-map") && strstr(out_text, "--blotch-max-error") &&
              strstr(out_text, "default") && strstr(out_text, "999 in JSON"),
          "help: %s", out_text);
    CHECK(strstr(out_text, "exit status: 0 success, 1 ") && strstr(out_text, "2 usage error"),
          "help lists the exit codes: %s", out_text);
    /* PSNR HDR's peak as metrics.c takes it: 1 for an all-black reference, not its largest value 0. */
    CHECK(strstr(out_text, "or 1 where that is 0 or less: an all-black reference"),
          "help gives PSNR HDR's peak for an all-black reference: %s", out_text);

    /* Usage errors: exit 2, one line on stderr naming the culprit, nothing on stdout. */
    const char *unknown[] = {off, ref, "--bogus"};
    CHECK(run_diff(3, unknown) == 2 && one_line(err_text) && strstr(err_text, "irrcache diff: --bogus:") &&
              out_text[0] == '\0',
          "unknown option: %s", err_text);
    const char *one[] = {off};
    CHECK(run_diff(1, one) == 2 && one_line(err_text), "one image: %s", err_text);
    const char *three[] = {off, ref, ref};
    CHECK(run_diff(3, three) == 2 && one_line(err_text), "three images: %s", err_text);
    const char *no_value[] = {off, ref, "--heatmap"};
    CHECK(run_diff(3, no_value) == 2 && strstr(err_text, "--heatmap"), "missing value: %s", err_text);
    const char *bad_format[] = {off, ref, "--heatmap", SCRATCH "/heat.jpg"};
    CHECK(run_diff(4, bad_format) == 2 && strstr(err_text, "heat.jpg"), "heat-map format: %s", err_text);
    const char *bad_blotch_format[] = {off, ref, "--blotch-map", SCRATCH "/blotch.jpg"};
    CHECK(run_diff(4, bad_blotch_format) == 2 && one_line(err_text) && strstr(err_text, "blotch.jpg"),
          "blotch-map format: %s", err_text);
    /* an empty path is said to be one, not an unknown format */
    const char *empty_heat[] = {off, ref, "--heatmap", ""}, *empty_blotch[] = {off, ref, "--blotch-map="};
    CHECK(run_diff(4, empty_heat) == 2 && one_line(err_text) &&
              strstr(err_text, "--heatmap '': the output path is empty"),
          "empty heat-map path: %s", err_text);
    CHECK(run_diff(3, empty_blotch) == 2 && one_line(err_text) &&
              strstr(err_text, "--blotch-map '': the output path is empty"),
          "empty blotch-map path: %s", err_text);
    const char *bad_blotch_max[] = {off, ref, "--blotch-map", blotch, "--blotch-max-error", "0"};
    CHECK(run_diff(6, bad_blotch_max) == 2 && one_line(err_text) && strstr(err_text, "--blotch-max-error 0"),
          "a blotch scale of 0: %s", err_text);
    const char *bad_max[] = {off, ref, "--max-error", "lots"};
    CHECK(run_diff(4, bad_max) == 2 && strstr(err_text, "lots"), "bad --max-error: %s", err_text);

    /* I/O and format errors: exit 1. */
    const char *missing[] = {SCRATCH "/missing.exr", ref, "--json"};
    CHECK(run_diff(3, missing) == 1 && one_line(err_text) && strstr(err_text, "irrcache diff: ") &&
              strstr(err_text, "missing.exr:") && out_text[0] == '\0',
          "missing file: %s", err_text);
    const char *mismatch[] = {small, ref};
    CHECK(run_diff(2, mismatch) == 1 && one_line(err_text) && strstr(err_text, "small.exr") &&
              strstr(err_text, "8x8") && strstr(err_text, "16x12"),
          "size mismatch: %s", err_text);
    const char *unwritable[] = {off, ref, "--heatmap", SCRATCH "/no-such-dir/heat.png"};
    CHECK(run_diff(4, unwritable) == 1 && one_line(err_text) && strstr(err_text, "heat.png"),
          "unwritable heat map: %s", err_text);
    TEST_MAIN_END();
}
