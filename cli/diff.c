/*
 * diff.c — `irrcache diff A B`: error metrics of image A against the reference B (RMSE, relMSE,
 * PSNR on linear HDR and on 8-bit sRGB, SSIM; see include/irrcache/image.h), as a short table or
 * one JSON object, and optionally a false-colour heat map of the per-pixel relative error and a blotch map of
 * the low-pass error (signed: red brighter, blue darker; ic_image_blotch_map). The heat map's
 * scale is fixed (IC_DEFAULT_HEATMAP_MAX_ERROR, or --max-error), not fitted to the image, so the maps of
 * two images against one reference compare; the scale used is printed (table) or recorded (JSON).
 *
 * Exit status: 0 success, 1 an image could not be read or written or the sizes differ, 2 a usage
 * error. Every failure is one line on stderr: "irrcache diff: <file>: <problem>; <what to do>".
 */
#include "cli.h"
#include "json_out.h"
#include "options.h"

#include "irrcache/defaults.h"
#include "irrcache/image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define EXIT_IO 1
#define EXIT_USAGE 2
/* JSON has no infinity: identical images report this PSNR (documented in --help). */
#define PSNR_INFINITE 999.0
/* --max-error auto: the heat map's scale is this quantile of the image's own errors. */
#define AUTO_QUANTILE 0.99

/* The heat map's scale: relative error shown as full red, and where it came from. */
typedef struct heat_scale {
    float max_error;
    int automatic; /* 1: the image's 99th percentile (--max-error auto); 0: fixed */
} heat_scale;

/* --blotch-map: where (NULL: none) and its scale. */
typedef struct blotch_opts {
    const char *path;
    float max_error;
} blotch_opts;

static void print_help(FILE *out)
{
    fprintf(out, "usage: irrcache diff A B [options]\n"
          "\n"
          "Compares image A against the reference image B (same size). Formats: OpenEXR, PFM,\n"
          "Radiance HDR, PNG, JPEG (8-bit images are sRGB-decoded to linear first).\n"
          "\n"
          "Metrics: RMSE, relMSE (mean of (a-b)^2/(b^2+0.01)) and PSNR on linear values (peak = the\n"
          "reference's largest value, or 1 where that is 0 or less: an all-black reference); PSNR and\n"
          "SSIM (luma, 8x8 windows) on the 8-bit sRGB images.\n"
          "relMSE lp (relmse_lowpass) is the relMSE after a Gaussian blur of sigma = 2 pixels of both\n"
          "images: the low-frequency error (a cache's blotches) without the pixel noise.\n"
          "NaN/Inf values count as 0 and are reported. Identical images have PSNR infinity, printed\n"
          "as \"inf\" in the table and as 999 in JSON.\n"
          "Options take their value as --name VALUE or --name=VALUE; -- ends the options.\n"
          "\n"
          "options:\n");
    ic_cli_print_command_options(out, IC_CLI_DIFF, 24);
    fprintf(out, "\nexit status: 0 success, 1 unreadable/unwritable image or size mismatch, 2 usage error\n");
}

/* A metric as JSON: JSON has no infinity (identical images: PSNR_INFINITE). */
static void add_metric(cJSON *o, const char *key, double v)
{
    if (isinf(v) && v > 0)
        cJSON_AddNumberToObject(o, key, PSNR_INFINITE);
    else if (isfinite(v))
        cJSON_AddNumberToObject(o, key, v);
    else
        cJSON_AddNullToObject(o, key); /* never produced by ic_image_compare; kept valid JSON regardless */
}

static int print_json(const ic_image *img, const ic_image_metrics *m, const char *heatmap, const heat_scale *hs,
                      const blotch_opts *bo)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "width", img->width);
    cJSON_AddNumberToObject(o, "height", img->height);
    add_metric(o, "rmse", m->rmse);
    add_metric(o, "relmse", m->relmse);
    add_metric(o, "relmse_lowpass", m->relmse_lowpass);
    add_metric(o, "psnr_hdr", m->psnr_hdr);
    add_metric(o, "psnr_ldr", m->psnr_ldr);
    add_metric(o, "ssim", m->ssim);
    cJSON_AddNumberToObject(o, "nonfinite", (double)m->nonfinite);
    if (heatmap) {
        cJSON_AddStringToObject(o, "heatmap", heatmap);
        cJSON_AddNumberToObject(o, "heatmap_max_error", hs->max_error);
        cJSON_AddStringToObject(o, "heatmap_scale", hs->automatic ? "p99" : "fixed");
    }
    if (bo->path) {
        cJSON_AddStringToObject(o, "blotch_map", bo->path);
        cJSON_AddNumberToObject(o, "blotch_max_error", bo->max_error);
    }
    return ic_cli_write_json("diff", NULL, o, 0);
}

/* The path of a map (`what`: "heat-map"), if given (an empty one the parser refused): a file name in a
 * format the command writes. Prints the usage error and returns 0 otherwise. */
static int map_path_ok(const char *what, const char *value)
{
    if (!value || ic_image_is_writable_format(value))
        return 1;
    ic_cli_eprintf("irrcache diff: %s: unknown %s format; name it .png (or .exr, .pfm, .hdr)\n", value, what);
    return 0;
}

static void print_db(FILE *out, const char *label, double db)
{
    if (isinf(db))
        fprintf(out, "%-10s inf (identical)\n", label);
    else
        fprintf(out, "%-10s %.2f dB\n", label, db);
}

static void print_table(FILE *out, const char *a, const char *b, const ic_image *img, const ic_image_metrics *m,
                        const char *heatmap, const heat_scale *hs, const blotch_opts *bo)
{
    fprintf(out, "%-10s %s\n%-10s %s\n%-10s %d x %d\n", "image", a, "reference", b, "size", img->width,
            img->height);
    fprintf(out, "%-10s %.6g\n%-10s %.6g\n%-10s %.6g\n", "RMSE", m->rmse, "relMSE", m->relmse, "relMSE lp",
            m->relmse_lowpass);
    print_db(out, "PSNR HDR", m->psnr_hdr);
    print_db(out, "PSNR LDR", m->psnr_ldr);
    fprintf(out, "%-10s %.5f\n", "SSIM", m->ssim);
    if (m->nonfinite > 0)
        fprintf(out, "%-10s %ld NaN/Inf values (counted as 0)\n", "nonfinite", m->nonfinite);
    if (heatmap)
        fprintf(out, "%-10s %s (relative error 0 = blue to %g = red: %s)\n", "heat map", heatmap,
                (double)hs->max_error, hs->automatic ? "this image's 99th percentile" : "fixed scale");
    if (bo->path)
        fprintf(out, "%-10s %s (low-pass relative error: red A brighter, blue darker, full at %g)\n", "blotches",
                bo->path, (double)bo->max_error);
}

/* --max-error auto: the image's 99th percentile (the default scale where the image has no error). */
static int heat_scale_resolve(heat_scale *hs, const ic_image *img, const ic_image *ref, ic_error *err)
{
    if (!hs->automatic)
        return 1;
    if (ic_image_heatmap_quantile(img, ref, AUTO_QUANTILE, &hs->max_error, err) != IC_OK)
        return 0;
    if (!(hs->max_error > 0.0f))
        hs->max_error = IC_DEFAULT_HEATMAP_MAX_ERROR;
    return 1;
}

/* 1 if a and b name the same file: the same inode where both exist, else the same path as written. */
static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    if (stat(a, &sa) == 0 && stat(b, &sb) == 0)
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    return strcmp(a, b) == 0;
}

int ic_cli_diff(int argc, char **argv)
{
    const char *paths[2] = {NULL, NULL};
    int npaths = 0, options_done = 0;
    ic_diff_args opt; /* by its table (options.h) */
    ic_cli_command_defaults(IC_CLI_DIFF, &opt);

    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        int rc;
        if (options_done || arg[0] != '-' || arg[1] == '\0') {
            if (npaths == 2) {
                ic_cli_eprintf("irrcache diff: %s: unexpected extra argument; give exactly two images (A and the "
                        "reference B)\n", arg);
                return EXIT_USAGE;
            }
            paths[npaths++] = arg;
        } else if (strcmp(arg, "--") == 0) {
            options_done = 1;
        } else if ((rc = ic_cli_parse_command_option(IC_CLI_DIFF, argc, argv, &i, &opt)) < 0) {
            if (rc == -1 - IC_DIFF_ARG_HELP_MARKDOWN)
                ic_cli_print_command_markdown(stdout, IC_CLI_DIFF);
            else
                print_help(stdout);
            return ic_cli_flush_stdout("irrcache diff");
        } else if (rc) {
            return EXIT_USAGE;
        }
    }
    if (!map_path_ok("heat-map", opt.heatmap) || !map_path_ok("blotch-map", opt.blotch_map))
        return EXIT_USAGE;
    const char *heatmap = opt.heatmap;
    int json = opt.json;
    heat_scale scale = {opt.max_error, opt.max_error == 0.0f}; /* 0: --max-error auto */
    blotch_opts blotch = {opt.blotch_map, opt.blotch_max_error};
    if (npaths != 2) {
        ic_cli_eprintf("irrcache diff: expected two images (A and the reference B), got %d; see irrcache diff "
                "--help\n", npaths);
        return EXIT_USAGE;
    }

    ic_error err = {0};
    ic_image img = {0}, ref = {0}, heat = {0}, blot = {0};
    ic_image_metrics metrics;
    int status = EXIT_IO;
    /* A map must not overwrite an input, nor the other map (it silently replaced the image compared). */
    const char *maps[2] = {heatmap, blotch.path};
    for (int k = 0; k < 2; ++k) {
        const char *clash = !maps[k] ? NULL
                            : same_file(maps[k], paths[0]) ? paths[0]
                            : same_file(maps[k], paths[1]) ? paths[1]
                            : k == 1 && maps[0] && same_file(maps[1], maps[0]) ? "--heatmap"
                                                                    : NULL;
        if (clash) {
            ic_cli_eprintf("irrcache diff: %s %s: the same file as %s; give the map its own name\n",
                    k ? "--blotch-map" : "--heatmap", maps[k], clash);
            return EXIT_USAGE;
        }
    }
    if (ic_image_read(paths[0], &img, &err) != IC_OK || ic_image_read(paths[1], &ref, &err) != IC_OK) {
        ic_cli_eprintf("irrcache diff: %s\n", err.message);
    } else if (img.width != ref.width || img.height != ref.height) {
        ic_cli_eprintf("irrcache diff: %s: size %dx%d differs from the reference %s (%dx%d); compare images of the "
                "same size\n", paths[0], img.width, img.height, paths[1], ref.width, ref.height);
    } else if (ic_image_compare(&img, &ref, &metrics, &err) != IC_OK) {
        ic_cli_eprintf("irrcache diff: %s: %s\n", paths[0], err.message);
    } else if (heatmap && (!heat_scale_resolve(&scale, &img, &ref, &err) ||
                           ic_image_heatmap(&img, &ref, scale.max_error, &heat, &err) != IC_OK ||
                           ic_image_write(heatmap, &heat, NULL, &err) != IC_OK)) {
        ic_cli_eprintf("irrcache diff: %s\n", err.message);
    } else if (blotch.path && (ic_image_blotch_map(&img, &ref, blotch.max_error, &blot, &err) != IC_OK ||
                               ic_image_write(blotch.path, &blot, NULL, &err) != IC_OK)) {
        ic_cli_eprintf("irrcache diff: %s\n", err.message);
    } else {
        status = 0;
        if (json && !print_json(&img, &metrics, heatmap, &scale, &blotch))
            status = EXIT_IO;
        else if (!json) {
            print_table(stdout, paths[0], paths[1], &img, &metrics, heatmap, &scale, &blotch);
            if (ic_cli_flush_stdout("irrcache diff")) /* a full disk or /dev/full: the table is lost */
                status = EXIT_IO;
        }
    }
    ic_image_free(&blot);
    ic_image_free(&heat);
    ic_image_free(&ref);
    ic_image_free(&img);
    return status;
}
