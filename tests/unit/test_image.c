/*
 * test_image.c — image I/O round trips, metrics against hand-computed values, heat maps, and bad
 * input (missing, truncated, garbage and unwritable files) for src/image.
 */
#include "irrcache/defaults.h"
#include "irrcache/image.h"

#include "test_exr_write.h"
#include "image/image_internal.h"
#include "test_util.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>

#ifndef IC_TEST_TMP
#define IC_TEST_TMP "/tmp"
#endif
#define SCRATCH IC_TEST_TMP "/image"

static const char *scratch(const char *name)
{
    static char path[4][512]; /* a few paths alive at once */
    static int next;
    char *p = path[next++ % 4];
    snprintf(p, sizeof path[0], "%s/%s", SCRATCH, name);
    return p;
}

/* Deterministic test pattern: gradients, HDR highlights, exact zeros; odd sizes. */
static ic_image pattern(int w, int h, float peak)
{
    ic_image img;
    ic_image_create(&img, w, h);
    uint32_t s = 12345u;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float *p = img.rgb + 3 * ((size_t)y * (size_t)w + (size_t)x);
            s = s * 1664525u + 1013904223u;
            float noise = (float)(s >> 8) / 16777216.0f;
            p[0] = peak * (float)x / (float)(w - 1);
            p[1] = peak * (float)y / (float)(h - 1) * noise;
            p[2] = (x + y) % 7 == 0 ? 0.0f : peak * noise * noise;
        }
    return img;
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* Nonzero if a temporary sibling "<name>.tmp.*" of SCRATCH/<name> is left over. */
static int temp_left_behind(const char *name)
{
    char prefix[256];
    snprintf(prefix, sizeof prefix, "%s.tmp.", name);
    DIR *d = opendir(SCRATCH);
    if (!d)
        return 0;
    int found = 0;
    for (struct dirent *e; (e = readdir(d));)
        if (strncmp(e->d_name, prefix, strlen(prefix)) == 0)
            found = 1;
    closedir(d);
    return found;
}

static void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *fp = fopen(path, "wb");
    if (fp) {
        fwrite(data, 1, n, fp);
        fclose(fp);
    }
}

static void test_create_free(void)
{
    ic_image img = {0};
    ic_image_free(&img); /* zeroed: no-op */
    ic_image_free(NULL);
    CHECK(ic_image_create(&img, 0, 5) == IC_ERR_INVALID_ARG, "zero width accepted");
    CHECK(ic_image_create(&img, 4, -1) == IC_ERR_INVALID_ARG, "negative height accepted");
    CHECK(ic_image_create(&img, 3, 2) == IC_OK && img.rgb && img.width == 3 && img.height == 2, "create 3x2");
    int zero = 1;
    for (int i = 0; i < 18; ++i)
        zero &= img.rgb[i] == 0.0f;
    CHECK(zero, "create does not zero-fill");
    ic_image_free(&img);
    CHECK(img.rgb == NULL && img.width == 0, "free does not zero the struct");

    CHECK(ic_image_is_writable_format("a/b.EXR") && ic_image_is_writable_format("x.pfm") &&
              ic_image_is_writable_format("x.hdr") && ic_image_is_writable_format("x.png"),
          "known extensions");
    CHECK(!ic_image_is_writable_format("x.jpg") && !ic_image_is_writable_format("x") &&
              !ic_image_is_writable_format("dir.png/x") && !ic_image_is_writable_format(NULL),
          "unknown extensions");
}

static void test_srgb(void)
{
    CHECK(ic_linear_to_srgb8(0.0f) == 0 && ic_linear_to_srgb8(1.0f) == 255 && ic_linear_to_srgb8(7.0f) == 255,
          "srgb8 ends");
    CHECK(ic_linear_to_srgb8(-1.0f) == 0 && ic_linear_to_srgb8(NAN) == 0, "srgb8 of negative/NaN");
    CHECK_NEAR(ic_linear_to_srgb(0.5f), 0.735357f, 1e-5, "sRGB(0.5)");
    CHECK_NEAR(ic_srgb_to_linear(0.5f), 0.214041f, 1e-5, "linear(0.5)");
    int exact = 1;
    for (int v = 0; v < 256; ++v)
        exact &= ic_linear_to_srgb8(ic_srgb8_to_linear((uint8_t)v)) == v;
    CHECK(exact, "8-bit sRGB does not round-trip through linear");
}

static int bit_equal(const ic_image *a, const ic_image *b)
{
    return a->width == b->width && a->height == b->height &&
           memcmp(a->rgb, b->rgb, (size_t)a->width * (size_t)a->height * 3 * sizeof(float)) == 0;
}

static void test_round_trips(void)
{
    ic_error err = {0};
    ic_image src = pattern(37, 23, 1000.0f), back = {0};
    src.rgb[5] = 1e-30f; /* denormal-ish and tiny values survive float formats */
    src.rgb[7] = -2.5f;  /* negative values too */

    /* EXR float: lossless. */
    CHECK(ic_image_write(scratch("rt_float.exr"), &src, NULL, &err) == IC_OK, "write exr: %s", err.message);
    CHECK(ic_image_read(scratch("rt_float.exr"), &back, &err) == IC_OK, "read exr: %s", err.message);
    CHECK(bit_equal(&src, &back), "EXR float round trip is not bit-exact");
    ic_image_free(&back);

    /* EXR half: within half precision (11-bit significand) for values in half's normal range. */
    ic_image_write_options half = {.exr_half = 1};
    ic_image hsrc = pattern(37, 23, 1000.0f);
    CHECK(ic_image_write(scratch("rt_half.exr"), &hsrc, &half, &err) == IC_OK, "write half exr: %s", err.message);
    CHECK(ic_image_read(scratch("rt_half.exr"), &back, &err) == IC_OK, "read half exr: %s", err.message);
    if (back.rgb) {
        int ok = back.width == 37 && back.height == 23;
        double worst = 0.0;
        for (size_t i = 0; ok && i < 37 * 23 * 3; ++i) {
            double tol = fmax(fabs(hsrc.rgb[i]) / 2048.0, 6e-8);
            worst = fmax(worst, fabs(hsrc.rgb[i] - back.rgb[i]) / tol);
        }
        CHECK(ok && worst <= 1.0, "EXR half error %.3g × half precision", worst);
        /* Half files are smaller than float ones. */
        struct stat sh, sf;
        CHECK(stat(scratch("rt_half.exr"), &sh) == 0 && stat(scratch("rt_float.exr"), &sf) == 0 &&
                  sh.st_size < sf.st_size,
              "half EXR is not smaller than float EXR");
    }
    ic_image_free(&back);
    ic_image_free(&hsrc);

    /* EXR half beyond half's range: a finite value is clamped to ±65504, the largest finite half (the
     * conversion alone made it ±Inf, which diff then scored as 0), in the image and in its layers, over
     * two chunks; Inf and NaN stay. */
    ic_image big = {0}, layer = {0};
    CHECK(ic_image_create(&big, 3, 20) == IC_OK && ic_image_create(&layer, 3, 20) == IC_OK, "big images");
    const float in[8] = {1e5f, 70000.0f, 65519.0f, -1e6f, 65504.0f, 1.5f, INFINITY, NAN};
    const float want[8] = {65504.0f, 65504.0f, 65504.0f, -65504.0f, 65504.0f, 1.5f, INFINITY, NAN};
    for (int i = 0; big.rgb && layer.rgb && i < 3 * 20 * 3; ++i)
        big.rgb[i] = layer.rgb[i] = in[i % 8];
    ic_image_layer layers[1] = {{"extra", &layer}};
    ic_image_write_options half_layers = {.exr_half = 1, .layers = layers, .layer_count = 1};
    CHECK(ic_image_write(scratch("big_half.exr"), &big, &half_layers, &err) == IC_OK, "write big half: %s",
          err.message);
    ic_image lback = {0};
    CHECK(ic_image_read(scratch("big_half.exr"), &back, &err) == IC_OK &&
              ic_image_read_layer(scratch("big_half.exr"), "extra", &lback, &err) == IC_OK,
          "read big half: %s", err.message);
    int clamped = back.rgb && lback.rgb;
    for (int i = 0; clamped && i < 3 * 20 * 3; ++i) {
        float w = want[i % 8];
        clamped &= isnan(w) ? isnan(back.rgb[i]) && isnan(lback.rgb[i]) : back.rgb[i] == w && lback.rgb[i] == w;
    }
    CHECK(clamped, "EXR half: finite values beyond 65504 are clamped to it, Inf and NaN kept (1e5 -> %g)",
          back.rgb ? back.rgb[0] : 0.0f);
    ic_image_free(&back);
    ic_image_free(&lback);
    ic_image_free(&big);
    ic_image_free(&layer);

    /* EXR over several chunks (ZIP groups 16 lines) and one-pixel images. */
    ic_image tall = pattern(3, 100, 4.0f), one = pattern(1, 1, 1.0f);
    one.rgb[0] = 0.25f;
    CHECK(ic_image_write(scratch("tall.exr"), &tall, NULL, &err) == IC_OK, "write tall exr: %s", err.message);
    CHECK(ic_image_read(scratch("tall.exr"), &back, &err) == IC_OK && bit_equal(&tall, &back), "tall EXR: %s",
          err.message);
    ic_image_free(&back);
    CHECK(ic_image_write(scratch("one.exr"), &one, NULL, &err) == IC_OK, "write 1x1 exr: %s", err.message);
    CHECK(ic_image_read(scratch("one.exr"), &back, &err) == IC_OK && bit_equal(&one, &back), "1x1 EXR: %s",
          err.message);
    ic_image_free(&back);
    ic_image_free(&tall);
    ic_image_free(&one);

    /* PFM: lossless, and stored bottom row first. */
    CHECK(ic_image_write(scratch("rt.pfm"), &src, NULL, &err) == IC_OK, "write pfm: %s", err.message);
    CHECK(ic_image_read(scratch("rt.pfm"), &back, &err) == IC_OK, "read pfm: %s", err.message);
    CHECK(bit_equal(&src, &back), "PFM round trip is not bit-exact");
    ic_image_free(&back);
    FILE *fp = fopen(scratch("rt.pfm"), "rb");
    if (fp) {
        char header[64] = {0};
        size_t header_len = strlen("PF\n37 23\n-1.0\n");
        float first[3] = {0};
        size_t got = fread(header, 1, header_len, fp);
        got += fread(first, sizeof(float), 3, fp);
        fclose(fp);
        CHECK(got == header_len + 3 && strcmp(header, "PF\n37 23\n-1.0\n") == 0, "PFM header: %s", header);
        CHECK(memcmp(first, src.rgb + (size_t)22 * 37 * 3, sizeof first) == 0, "PFM does not start with the bottom row");
    }

    /* Radiance HDR: within RGBE precision (1/128 of the pixel's largest channel; 1% asked). */
    CHECK(ic_image_write(scratch("rt.hdr"), &src, NULL, &err) == IC_OK, "write hdr: %s", err.message);
    CHECK(ic_image_read(scratch("rt.hdr"), &back, &err) == IC_OK, "read hdr: %s", err.message);
    if (back.rgb) {
        int ok = back.width == 37 && back.height == 23;
        double worst = 0.0;
        for (size_t p = 0; ok && p < 37 * 23; ++p) {
            float biggest = fmaxf(src.rgb[3 * p], fmaxf(src.rgb[3 * p + 1], src.rgb[3 * p + 2]));
            for (int c = 0; c < 3; ++c) {
                double want = fmax(src.rgb[3 * p + (size_t)c], 0.0); /* negative is written as 0 */
                if (biggest > 1e-20f)
                    worst = fmax(worst, fabs(want - back.rgb[3 * p + (size_t)c]) / biggest);
            }
        }
        CHECK(ok && worst <= 0.01, "HDR relative error %.4g", worst);
    }
    ic_image_free(&back);

    /* PNG: within one 8-bit sRGB step; exposure doubles per stop. */
    ic_image ldr = pattern(37, 23, 1.0f);
    CHECK(ic_image_write(scratch("rt.png"), &ldr, NULL, &err) == IC_OK, "write png: %s", err.message);
    CHECK(ic_image_read(scratch("rt.png"), &back, &err) == IC_OK, "read png: %s", err.message);
    if (back.rgb) {
        double worst = 0.0;
        for (size_t i = 0; i < 37 * 23 * 3; ++i)
            worst = fmax(worst, fabs(ic_linear_to_srgb(ldr.rgb[i]) - ic_linear_to_srgb(back.rgb[i])));
        CHECK(back.width == 37 && back.height == 23 && worst <= 0.5 / 255.0 + 1e-6, "PNG sRGB error %.4g", worst);
    }
    ic_image_free(&back);
    ic_image quarter;
    ic_image_create(&quarter, 2, 2);
    for (int i = 0; i < 12; ++i)
        quarter.rgb[i] = 0.25f;
    ic_image_write_options bright = {.exposure = 1.0f};
    CHECK(ic_image_write(scratch("exposure.png"), &quarter, &bright, &err) == IC_OK, "write png: %s", err.message);
    CHECK(ic_image_read(scratch("exposure.png"), &back, &err) == IC_OK && back.rgb &&
              ic_linear_to_srgb8(back.rgb[0]) == ic_linear_to_srgb8(0.5f),
          "PNG exposure +1 of 0.25 should read back as 0.5");
    ic_image_free(&back);
    ic_image_free(&quarter);
    ic_image_free(&ldr);

    /* The format comes from the content, not the name. */
    rename(scratch("rt.pfm"), scratch("renamed.dat"));
    CHECK(ic_image_read(scratch("renamed.dat"), &back, &err) == IC_OK && bit_equal(&src, &back),
          "PFM content under another extension: %s", err.message);
    ic_image_free(&back);
    ic_image_free(&src);
}

static void test_pfm_variants(void)
{
    ic_error err = {0};
    ic_image img = {0};
    /* Grey, big-endian ("Pf", positive scale), 2x1: values 1.0 and 2.0. */
    const unsigned char grey_be[] = {'P', 'f', '\n', '2', ' ', '1', '\n', '1', '.', '0', '\n',
                                     0x3f, 0x80, 0x00, 0x00, 0x40, 0x00, 0x00, 0x00};
    write_bytes(scratch("grey_be.pfm"), grey_be, sizeof grey_be);
    CHECK(ic_image_read(scratch("grey_be.pfm"), &img, &err) == IC_OK, "grey big-endian PFM: %s", err.message);
    CHECK(img.rgb && img.width == 2 && img.height == 1 && img.rgb[0] == 1.0f && img.rgb[2] == 1.0f &&
              img.rgb[3] == 2.0f && img.rgb[5] == 2.0f,
          "grey big-endian PFM values");
    ic_image_free(&img);

    /* NaN and Inf pixels read without trouble, bit for bit. */
    float pixels[6] = {NAN, 1.0f, INFINITY, 0.5f, -INFINITY, 0.25f};
    unsigned char file[64];
    const char *header = "PF\n2 1\n-1.0\n";
    size_t n = strlen(header);
    memcpy(file, header, n);
    memcpy(file + n, pixels, sizeof pixels); /* the test host is little-endian (x86-64, arm64) */
    write_bytes(scratch("nan.pfm"), file, n + sizeof pixels);
    CHECK(ic_image_read(scratch("nan.pfm"), &img, &err) == IC_OK, "NaN PFM: %s", err.message);
    if (img.rgb) {
        CHECK(isnan(img.rgb[0]) && isinf(img.rgb[2]) && img.rgb[1] == 1.0f, "NaN/Inf values");
        /* And the other writers and the metrics cope with them. */
        CHECK(ic_image_write(scratch("nan.hdr"), &img, NULL, &err) == IC_OK, "HDR with NaN: %s", err.message);
        CHECK(ic_image_write(scratch("nan.png"), &img, NULL, &err) == IC_OK, "PNG with NaN: %s", err.message);
        CHECK(ic_image_write(scratch("nan.exr"), &img, NULL, &err) == IC_OK, "EXR with NaN: %s", err.message);
        ic_image ref, heat = {0};
        ic_image_create(&ref, 2, 1);
        ic_image_metrics m;
        CHECK(ic_image_compare(&img, &ref, &m, &err) == IC_OK, "compare with NaN: %s", err.message);
        CHECK(m.nonfinite == 3 && isfinite(m.rmse) && isfinite(m.relmse) && isfinite(m.psnr_hdr) &&
                  isfinite(m.psnr_ldr) && isfinite(m.ssim),
              "metrics with NaN: nonfinite %ld rmse %g ssim %g", m.nonfinite, m.rmse, m.ssim);
        CHECK(ic_image_heatmap(&img, &ref, 0.0f, &heat, &err) == IC_OK && heat.rgb && heat.rgb[0] == 1.0f &&
                  heat.rgb[1] == 0.0f && heat.rgb[2] == 1.0f,
              "NaN pixel is magenta in the heat map");
        ic_image_free(&heat);
        ic_image_free(&ref);
    }
    ic_image_free(&img);
}

/* Run-length encoded Radiance pictures (what rpict and most tools write), and EXPOSURE. */
static void test_hdr_variants(void)
{
    ic_error err = {0};
    ic_image img = {0};
    /* 8x2, new-style RLE: row 0 = one run per component (R 128, G 64, B 0, E 129), row 1 = literals. */
    const char *header = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=2\n\n-Y 2 +X 8\n";
    unsigned char file[256];
    size_t n = strlen(header);
    memcpy(file, header, n);
    const unsigned char row0[] = {2, 2, 0, 8, 128 + 8, 128, 128 + 8, 64, 128 + 8, 0, 128 + 8, 129};
    memcpy(file + n, row0, sizeof row0);
    n += sizeof row0;
    const unsigned char row1[] = {2, 2, 0, 8, 8, 128, 129, 130, 131, 132, 133, 134, 135, 128 + 8, 0, 128 + 8, 0,
                                  128 + 8, 128};
    memcpy(file + n, row1, sizeof row1);
    n += sizeof row1;
    write_bytes(scratch("rle.hdr"), file, n);
    CHECK(ic_image_read(scratch("rle.hdr"), &img, &err) == IC_OK, "RLE hdr: %s", err.message);
    if (img.rgb) {
        /* (m + 0.5) · 2^(e − 136) / EXPOSURE */
        CHECK_NEAR(img.rgb[0], 128.5 / 128.0 / 2.0, 1e-7, "R of row 0");
        CHECK_NEAR(img.rgb[7 * 3 + 1], 64.5 / 128.0 / 2.0, 1e-7, "G of row 0");
        CHECK_NEAR(img.rgb[7 * 3 + 2], 0.5 / 128.0 / 2.0, 1e-7, "B of row 0");
        CHECK_NEAR(img.rgb[(8 + 5) * 3], 133.5 / 256.0 / 2.0, 1e-7, "R of row 1, pixel 5");
    }
    ic_image_free(&img);
    /* The same file cut inside the second row. */
    write_bytes(scratch("rle-cut.hdr"), file, n - 5);
    CHECK(ic_image_read(scratch("rle-cut.hdr"), &img, &err) == IC_ERR_CORRUPT && strstr(err.message, "rle-cut.hdr"),
          "cut RLE hdr: %s", err.message);
    ic_image_free(&img);

    /* A 5000-character command history line (rpict and pcomb write their whole command lines) before the
     * lines that matter: read as the file above, EXPOSURE included. Lines over 511 characters were
     * refused as a malformed header. Then a FORMAT= or EXPOSURE= line too long to read is refused, naming
     * its line. */
    enum { LONG = 5000 };
    static unsigned char big[LONG + 512];
    const char *history = "#?RADIANCE\npcomb -e 'lo=li(1)' ";
    size_t h = strlen(history);
    memcpy(big, history, h);
    memset(big + h, 'x', LONG - (h - 11));
    h += LONG - (h - 11);
    big[h++] = '\n';
    memcpy(big + h, file + 11, n - 11); /* the RLE file after its "#?RADIANCE" line */
    write_bytes(scratch("history.hdr"), big, h + n - 11);
    CHECK(ic_image_read(scratch("history.hdr"), &img, &err) == IC_OK, "hdr with a long header line: %s", err.message);
    if (img.rgb) {
        CHECK_NEAR(img.rgb[0], 128.5 / 128.0 / 2.0, 1e-7, "R of row 0 after a long header line");
        CHECK_NEAR(img.rgb[(8 + 5) * 3], 133.5 / 256.0 / 2.0, 1e-7, "R of row 1, pixel 5 after a long header line");
    }
    ic_image_free(&img);
    static const char *const keys[] = {"EXPOSURE=2", "FORMAT=32-bit_rle_rgbe"};
    for (int k = 0; k < 2; ++k) {
        h = (size_t)snprintf((char *)big, sizeof big, "#?RADIANCE\n%s", keys[k]);
        memset(big + h, ' ', LONG);
        h += LONG;
        h += (size_t)snprintf((char *)big + h, sizeof big - h, "\n\n-Y 1 +X 1\n\x80\x80\x80\x81");
        write_bytes(scratch("long-key.hdr"), big, h);
        ic_result r = ic_image_read(scratch("long-key.hdr"), &img, &err);
        char words[64];
        snprintf(words, sizeof words, "long-key.hdr:2: this %.*s line has", (int)(strchr(keys[k], '=') - keys[k] + 1),
                 keys[k]);
        CHECK(r == IC_ERR_PARSE && strstr(err.message, words), "long %s line: %s (%s)", keys[k], ic_result_name(r),
              err.message);
        ic_image_free(&img);
    }

    /* Old-style runs: (1,1,1,n) repeats the previous pixel. */
    const char *old_header = "#?RGBE\n\n-Y 1 +X 5\n";
    n = strlen(old_header);
    memcpy(file, old_header, n);
    const unsigned char old_rle[] = {128, 0, 0, 129, 1, 1, 1, 3, 0, 0, 0, 0};
    memcpy(file + n, old_rle, sizeof old_rle);
    write_bytes(scratch("old-rle.hdr"), file, n + sizeof old_rle);
    CHECK(ic_image_read(scratch("old-rle.hdr"), &img, &err) == IC_OK, "old RLE hdr: %s", err.message);
    CHECK(img.rgb && img.rgb[3 * 3] == img.rgb[0] && img.rgb[0] > 0.9f && img.rgb[4 * 3] == 0.0f,
          "old RLE values");
    ic_image_free(&img);
}

static ic_image constant(int w, int h, float v)
{
    ic_image img;
    ic_image_create(&img, w, h);
    for (size_t i = 0; i < (size_t)w * (size_t)h * 3; ++i)
        img.rgb[i] = v;
    return img;
}

static void test_metrics(void)
{
    ic_error err = {0};
    ic_image_metrics m;

    /* Identical images. */
    ic_image a = pattern(40, 30, 3.0f);
    CHECK(ic_image_compare(&a, &a, &m, &err) == IC_OK, "compare: %s", err.message);
    CHECK(m.rmse == 0.0 && m.relmse == 0.0 && m.ssim == 1.0 && m.nonfinite == 0, "identical: rmse %g ssim %.17g",
          m.rmse, m.ssim);
    CHECK(isinf(m.psnr_hdr) && m.psnr_hdr > 0 && isinf(m.psnr_ldr) && m.psnr_ldr > 0, "identical: PSNR not +inf");

    /* Constant offset: 0.6 against 0.5. */
    ic_image ref = constant(20, 10, 0.5f), img = constant(20, 10, 0.6f);
    CHECK(ic_image_compare(&img, &ref, &m, &err) == IC_OK, "compare: %s", err.message);
    double d = (double)0.6f - (double)0.5f;
    CHECK_NEAR(m.rmse, d, 1e-12, "rmse of constant offset");
    CHECK_NEAR(m.relmse, d * d / (0.25 + 0.01), 1e-12, "relmse of constant offset");
    CHECK_NEAR(m.psnr_hdr, 10.0 * log10(0.25 / (d * d)), 1e-9, "psnr_hdr of constant offset");
    double d8 = (double)ic_linear_to_srgb8(0.6f) - (double)ic_linear_to_srgb8(0.5f);
    CHECK_NEAR(m.psnr_ldr, 20.0 * log10(255.0 / d8), 1e-9, "psnr_ldr of constant offset");
    /* SSIM of two flat images: only the luminance term (2 mx my + C1) / (mx² + my² + C1) is left. */
    double mx = ic_linear_to_srgb8(0.6f), my = ic_linear_to_srgb8(0.5f), c1 = (0.01 * 255) * (0.01 * 255);
    CHECK_NEAR(m.ssim, (2 * mx * my + c1) / (mx * mx + my * my + c1), 1e-6, "ssim of flat images");
    ic_image_free(&img);
    ic_image_free(&ref);

    /* All-black reference: PSNR uses peak 1. */
    ref = constant(4, 4, 0.0f);
    img = constant(4, 4, 0.1f);
    CHECK(ic_image_compare(&img, &ref, &m, &err) == IC_OK && fabs(m.psnr_hdr - 20.0) < 1e-5,
          "psnr against black: %g", m.psnr_hdr);
    ic_image_free(&img);
    ic_image_free(&ref);

    /* SSIM falls as noise grows; PSNR too. */
    ic_image n1 = pattern(40, 30, 3.0f), n2 = pattern(40, 30, 3.0f);
    uint32_t s = 99u;
    for (size_t i = 0; i < 40 * 30 * 3; ++i) {
        s = s * 1664525u + 1013904223u;
        float u = (float)(s >> 8) / 16777216.0f - 0.5f;
        n1.rgb[i] = fmaxf(n1.rgb[i] + 0.02f * u, 0.0f);
        n2.rgb[i] = fmaxf(n2.rgb[i] + 0.2f * u, 0.0f);
    }
    ic_image_metrics m1, m2;
    CHECK(ic_image_compare(&n1, &a, &m1, &err) == IC_OK && ic_image_compare(&n2, &a, &m2, &err) == IC_OK, "compare");
    CHECK(m1.ssim < 1.0 && m2.ssim < m1.ssim && m2.psnr_ldr < m1.psnr_ldr && m2.rmse > m1.rmse,
          "noise: ssim %g then %g, psnr %g then %g", m1.ssim, m2.ssim, m1.psnr_ldr, m2.psnr_ldr);
    CHECK(m1.ssim > 0.0 && m2.ssim > -1.0, "ssim range");

    /* Images smaller than the SSIM window. */
    ic_image tiny = pattern(3, 2, 1.0f);
    CHECK(ic_image_compare(&tiny, &tiny, &m, &err) == IC_OK && m.ssim == 1.0, "3x2 ssim %g", m.ssim);

    /* Size mismatch. */
    CHECK(ic_image_compare(&tiny, &a, &m, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "40x30"),
          "size mismatch: %s", err.message);

    ic_image_free(&tiny);
    ic_image_free(&n1);
    ic_image_free(&n2);
    ic_image_free(&a);
}

/* The low-pass relMSE: a blur keeps a constant offset (a blotch larger than the kernel) and divides
 * independent pixel noise by about 4πσ² (the sum of the squared Gaussian weights). */
static void test_lowpass(void)
{
    ic_error err = {0};
    ic_image_metrics m;
    ic_image ref = constant(64, 48, 0.5f), img = constant(64, 48, 0.6f);
    CHECK(ic_image_compare(&img, &ref, &m, &err) == IC_OK, "compare: %s", err.message);
    CHECK_NEAR(m.relmse_lowpass, m.relmse, 1e-5 * m.relmse, "low-pass relMSE of a constant offset (float blur)");
    CHECK(ic_image_compare(&ref, &ref, &m, &err) == IC_OK && m.relmse_lowpass == 0.0, "identical: low-pass 0");
    /* Noise: ±0.1 at random in every channel. */
    uint32_t st = 12345u;
    for (size_t i = 0; i < 3 * (size_t)img.width * img.height; ++i) {
        st = st * 1664525u + 1013904223u;
        img.rgb[i] = 0.5f + ((st >> 31) ? 0.1f : -0.1f);
    }
    CHECK(ic_image_compare(&img, &ref, &m, &err) == IC_OK, "compare: %s", err.message);
    double expect = 1.0 / (4.0 * 3.14159265358979 * IC_LOWPASS_SIGMA * IC_LOWPASS_SIGMA);
    double ratio = m.relmse_lowpass / m.relmse;
    CHECK(ratio > 0.5 * expect && ratio < 2.0 * expect, "noise: low-pass/relMSE %.4g, expected about %.4g", ratio,
          expect);
    /* A blotch: a 16×16 patch 20 % too bright keeps most of its error. */
    ic_image_free(&img);
    img = constant(64, 48, 0.5f);
    for (int y = 16; y < 32; ++y)
        for (int x = 24; x < 40; ++x)
            for (int c = 0; c < 3; ++c)
                img.rgb[3 * ((size_t)y * img.width + x) + c] = 0.6f;
    CHECK(ic_image_compare(&img, &ref, &m, &err) == IC_OK && m.relmse_lowpass > 0.6 * m.relmse,
          "blotch: low-pass %.4g of relMSE %.4g", m.relmse_lowpass, m.relmse);
    ic_image_free(&img);
    ic_image_free(&ref);
}

static void test_heatmap(void)
{
    ic_error err = {0};
    ic_image ref = constant(8, 4, 1.0f), img = constant(8, 4, 1.0f), heat = {0};
    CHECK(ic_image_heatmap(&img, &ref, 0.0f, &heat, &err) == IC_OK, "heatmap: %s", err.message);
    int same = heat.rgb != NULL && heat.width == 8 && heat.height == 4;
    for (size_t i = 0; same && i < 32 * 3; ++i)
        same = heat.rgb[i] == heat.rgb[i % 3];
    CHECK(same && heat.rgb[2] > heat.rgb[0], "identical images: uniform blue-ish heat map");
    float low[3] = {heat.rgb[0], heat.rgb[1], heat.rgb[2]};
    ic_image_free(&heat);

    /* One pixel off by 100%: with max 0.5 it saturates (red end); the rest stays at the low end. */
    for (int c = 0; c < 3; ++c)
        img.rgb[3 * 9 + c] = 2.0f;
    CHECK(ic_image_heatmap(&img, &ref, 0.5f, &heat, &err) == IC_OK, "heatmap: %s", err.message);
    if (heat.rgb) {
        const float *hot = heat.rgb + 3 * 9;
        CHECK(hot[0] > hot[1] && hot[0] > hot[2], "saturated pixel is not red: %g %g %g", hot[0], hot[1], hot[2]);
        CHECK(heat.rgb[0] == low[0] && heat.rgb[1] == low[1] && heat.rgb[2] == low[2], "exact pixel not at low end");
    }
    ic_image_free(&heat);
    CHECK(ic_image_heatmap(&img, &ref, -1.0f, &heat, &err) == IC_ERR_INVALID_ARG, "negative max_err accepted");
    ic_image_free(&img);
    ic_image_free(&ref);
}

/* The blotch map: pixel noise blurred away, a low-frequency error kept with its sign. A 64 × 64 reference
 * of 1; the image has ±20 % checkerboard noise on every pixel (σ = 2 pixels leaves e^(−2π²σ²/4) ≈ 3·10⁻⁹
 * of it), a +10 % square at the top left and a −10 % one at the bottom right (16 × 16 each). */
static void test_blotch_map(void)
{
    ic_error err = {0};
    const int W = 64;
    ic_image ref = constant(W, W, 1.0f), img = constant(W, W, 1.0f), map = {0};
    for (int y = 0; y < W; ++y)
        for (int x = 0; x < W; ++x) {
            float v = (x + y) % 2 ? 1.2f : 0.8f;
            if (x >= 8 && x < 24 && y >= 8 && y < 24)
                v *= 1.1f;
            if (x >= 40 && x < 56 && y >= 40 && y < 56)
                v *= 0.9f;
            for (int c = 0; c < 3; ++c)
                img.rgb[3 * ((size_t)y * W + x) + c] = v;
        }
    CHECK(ic_image_blotch_map(&img, &ref, 0.0f, &map, &err) == IC_OK && map.rgb && map.width == W,
          "blotch map: %s", err.message);
    if (map.rgb) {
        const float *bright = map.rgb + 3 * (16 * W + 16), *dark = map.rgb + 3 * (48 * W + 48),
                    *calm = map.rgb + 3 * (8 * W + 40);
        /* 10 % is past the default full scale (5 %): full red, full blue; the noise alone: black. */
        CHECK(bright[0] == 1.0f && bright[1] == 0.0f && bright[2] == 0.0f, "a brighter blotch is red: %g %g %g",
              bright[0], bright[1], bright[2]);
        CHECK(dark[0] == 0.0f && dark[1] == 0.0f && dark[2] == 1.0f, "a darker blotch is blue: %g %g %g", dark[0],
              dark[1], dark[2]);
        CHECK(calm[0] < 1e-3f && calm[2] < 1e-3f, "pixel noise is blurred away: %g %g", calm[0], calm[2]);
    }
    ic_image_free(&map);
    /* On a scale of 0.2 the blotch's 10 % (over |r| + 0.01) is half of full colour, sRGB-encoded. */
    CHECK(ic_image_blotch_map(&img, &ref, 0.2f, &map, &err) == IC_OK, "blotch map: %s", err.message);
    if (map.rgb)
        CHECK_NEAR(map.rgb[3 * (16 * W + 16)], ic_srgb_to_linear(0.1f / 1.01f / 0.2f), 2e-3,
                   "half the scale, half the ramp");
    ic_image_free(&map);
    CHECK(ic_image_blotch_map(&ref, &ref, 0.0f, &map, &err) == IC_OK && map.rgb, "identical: %s", err.message);
    int black = map.rgb != NULL;
    for (size_t i = 0; black && i < (size_t)W * W * 3; ++i)
        black = map.rgb[i] == 0.0f;
    CHECK(black, "identical images: an all-black map");
    ic_image_free(&map);
    CHECK(ic_image_blotch_map(&img, &ref, -1.0f, &map, &err) == IC_ERR_INVALID_ARG && !map.rgb,
          "a negative scale is refused");
    ic_image small = constant(8, 8, 1.0f);
    CHECK(ic_image_blotch_map(&small, &ref, 0.0f, &map, &err) == IC_ERR_INVALID_ARG && !map.rgb,
          "a size mismatch is refused");
    ic_image_free(&small);
    ic_image_free(&img);
    ic_image_free(&ref);
}

/* The default scale is fixed: two images whose pixel 5 has the same error, one with small errors elsewhere
 * and one with large ones, give pixel 5 the same colour (a scale fitted to each image, such as its 99th
 * percentile, would show it red in the first and green in the second). */
static void test_heatmap_fixed_scale(void)
{
    ic_error err = {0};
    ic_image ref = constant(8, 4, 1.0f), calm = constant(8, 4, 1.0f + 0.1f * 1.01f),
             wild = constant(8, 4, 1.0f + 0.8f * 1.01f), heat_calm = {0}, heat_wild = {0}, heat_default = {0};
    for (int c = 0; c < 3; ++c)
        calm.rgb[3 * 5 + c] = wild.rgb[3 * 5 + c] = 1.0f + 0.2f * 1.01f; /* relative error 0.2 */
    CHECK(ic_image_heatmap(&calm, &ref, 0.0f, &heat_calm, &err) == IC_OK &&
              ic_image_heatmap(&wild, &ref, 0.0f, &heat_wild, &err) == IC_OK &&
              ic_image_heatmap(&calm, &ref, IC_DEFAULT_HEATMAP_MAX_ERROR, &heat_default, &err) == IC_OK,
          "heat maps: %s", err.message);
    if (heat_calm.rgb && heat_wild.rgb && heat_default.rgb) {
        CHECK(!memcmp(heat_calm.rgb + 15, heat_wild.rgb + 15, 3 * sizeof(float)),
              "the same error, the same colour: %g %g %g vs %g %g %g", heat_calm.rgb[15], heat_calm.rgb[16],
              heat_calm.rgb[17], heat_wild.rgb[15], heat_wild.rgb[16], heat_wild.rgb[17]);
        CHECK(!memcmp(heat_calm.rgb, heat_default.rgb, sizeof(float) * 3 * 32), "max_err 0 is the default scale");
        CHECK(memcmp(heat_calm.rgb, heat_wild.rgb, 3 * sizeof(float)) != 0, "different errors, different colours");
    }
    float q_calm = 0.0f, q_wild = 0.0f;
    CHECK(ic_image_heatmap_quantile(&calm, &ref, 0.99, &q_calm, &err) == IC_OK &&
              ic_image_heatmap_quantile(&wild, &ref, 0.99, &q_wild, &err) == IC_OK,
          "quantiles: %s", err.message);
    CHECK_NEAR(q_calm, 0.1, 1e-5, "99th percentile of the calm image");
    CHECK_NEAR(q_wild, 0.8, 1e-5, "99th percentile of the wild image");
    CHECK(ic_image_heatmap_quantile(&calm, &ref, 1.5, &q_calm, &err) == IC_ERR_INVALID_ARG, "quantile above 1");
    ic_image_free(&heat_calm);
    ic_image_free(&heat_wild);
    ic_image_free(&heat_default);
    ic_image_free(&calm);
    ic_image_free(&wild);
    ic_image_free(&ref);
}

static void test_bad_input(void)
{
    ic_error err = {0};
    ic_image img = {0};

    /* Missing file. */
    const char *missing = scratch("does-not-exist.exr");
    CHECK(ic_image_read(missing, &img, &err) == IC_ERR_IO && strstr(err.message, "does-not-exist.exr"),
          "missing file: %s", err.message);
    CHECK(img.rgb == NULL, "failed read left pixels");

    /* Truncated EXR: the first half of a valid file. */
    ic_image src = pattern(64, 64, 2.0f);
    CHECK(ic_image_write(scratch("whole.exr"), &src, NULL, &err) == IC_OK, "write: %s", err.message);
    FILE *fp = fopen(scratch("whole.exr"), "rb");
    static unsigned char bytes[1 << 20];
    size_t n = fp ? fread(bytes, 1, sizeof bytes, fp) : 0;
    if (fp)
        fclose(fp);
    CHECK(n > 1000, "EXR file too small (%zu bytes)", n);
    write_bytes(scratch("truncated.exr"), bytes, n / 2);
    ic_result r = ic_image_read(scratch("truncated.exr"), &img, &err);
    CHECK(r != IC_OK && strstr(err.message, "truncated.exr"), "truncated EXR: %s (%s)", ic_result_name(r), err.message);
    CHECK(img.rgb == NULL, "failed read left pixels");
    /* Only the header survives. */
    write_bytes(scratch("header-only.exr"), bytes, 40);
    r = ic_image_read(scratch("header-only.exr"), &img, &err);
    CHECK(r != IC_OK && strstr(err.message, "header-only.exr"), "header-only EXR: %s", err.message);
    ic_image_free(&img);

    /* Garbage PFM headers. */
    const char *garbage[] = {"PF\nabc def\n-1.0\n", "PF\n2 2\n0\n", "PF\n-3 2\n-1.0\n", "PF\n2 2\n-1.0"};
    for (size_t i = 0; i < sizeof garbage / sizeof garbage[0]; ++i) {
        write_bytes(scratch("garbage.pfm"), garbage[i], strlen(garbage[i]));
        r = ic_image_read(scratch("garbage.pfm"), &img, &err);
        CHECK(r == IC_ERR_PARSE && strstr(err.message, "garbage.pfm"), "garbage PFM %zu: %s (%s)", i,
              ic_result_name(r), err.message);
    }
    /* A header promising more pixels than the file holds (and a huge size). */
    const char *short_pfm = "PF\n4 4\n-1.0\n\x01\x02\x03\x04";
    write_bytes(scratch("short.pfm"), short_pfm, strlen(short_pfm));
    CHECK(ic_image_read(scratch("short.pfm"), &img, &err) == IC_ERR_CORRUPT && strstr(err.message, "short.pfm"),
          "short PFM: %s", err.message);
    const char *huge_pfm = "PF\n60000 60000\n-1.0\n\x01\x02\x03\x04";
    write_bytes(scratch("huge.pfm"), huge_pfm, strlen(huge_pfm));
    CHECK(ic_image_read(scratch("huge.pfm"), &img, &err) == IC_ERR_CORRUPT, "huge PFM: %s", err.message);

    /* Not an image at all; empty; a PNG signature followed by junk. */
    write_bytes(scratch("junk.bin"), "hello, world", 12);
    CHECK(ic_image_read(scratch("junk.bin"), &img, &err) == IC_ERR_UNSUPPORTED && strstr(err.message, "junk.bin"),
          "junk: %s", err.message);
    write_bytes(scratch("empty.png"), "", 0);
    CHECK(ic_image_read(scratch("empty.png"), &img, &err) == IC_ERR_PARSE && strstr(err.message, "empty.png"),
          "empty: %s", err.message);
    write_bytes(scratch("bad.png"), "\x89PNG\r\n\x1a\nnot really", 18);
    CHECK(ic_image_read(scratch("bad.png"), &img, &err) == IC_ERR_PARSE && strstr(err.message, "bad.png"),
          "bad png: %s", err.message);
    const char *hdr_no_pixels = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 10 +X 10\n";
    write_bytes(scratch("bad.hdr"), hdr_no_pixels, strlen(hdr_no_pixels));
    CHECK(ic_image_read(scratch("bad.hdr"), &img, &err) == IC_ERR_CORRUPT && strstr(err.message, "bad.hdr"),
          "truncated hdr: %s", err.message);
    CHECK(img.rgb == NULL, "failed read left pixels");
    ic_image_free(&img);
    const char *hdr_xyze = "#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\x80\x80\x80\x80";
    write_bytes(scratch("xyze.hdr"), hdr_xyze, strlen(hdr_xyze));
    CHECK(ic_image_read(scratch("xyze.hdr"), &img, &err) == IC_ERR_UNSUPPORTED && strstr(err.message, "xyze.hdr"),
          "xyze hdr: %s", err.message);
    const char *hdr_flipped = "#?RADIANCE\n\n+Y 1 +X 1\n\x80\x80\x80\x80";
    write_bytes(scratch("flipped.hdr"), hdr_flipped, strlen(hdr_flipped));
    CHECK(ic_image_read(scratch("flipped.hdr"), &img, &err) == IC_ERR_UNSUPPORTED && strstr(err.message, "flipped.hdr"),
          "+Y hdr: %s", err.message);

    /* Unwritable outputs: a folder that does not exist, and a path that is a folder. Every format;
     * no temporary file may stay behind. */
    mkdir(scratch("isdir.exr"), 0755);
    mkdir(scratch("isdir.pfm"), 0755);
    mkdir(scratch("isdir.hdr"), 0755);
    mkdir(scratch("isdir.png"), 0755);
    const char *formats[] = {"exr", "pfm", "hdr", "png"};
    for (int i = 0; i < 4; ++i) {
        char name[64];
        snprintf(name, sizeof name, "no-such-dir/out.%s", formats[i]);
        r = ic_image_write(scratch(name), &src, NULL, &err);
        CHECK(r == IC_ERR_IO && strstr(err.message, name) && strstr(err.message, "writable"), "%s: %s (%s)", name,
              ic_result_name(r), err.message);
        snprintf(name, sizeof name, "isdir.%s", formats[i]);
        r = ic_image_write(scratch(name), &src, NULL, &err);
        CHECK(r == IC_ERR_IO && strstr(err.message, name), "%s: %s (%s)", name, ic_result_name(r), err.message);
        CHECK(!temp_left_behind(name), "a temporary file of %s was left behind", name);
    }
    CHECK(!file_exists(scratch("no-such-dir")), "no-such-dir was created");
    CHECK(ic_image_write(scratch("out.tiff"), &src, NULL, &err) == IC_ERR_UNSUPPORTED && strstr(err.message, "out.tiff"),
          "unknown extension: %s", err.message);
    CHECK(!file_exists(scratch("out.tiff")), "out.tiff written");
    ic_image empty = {0};
    CHECK(ic_image_write(scratch("empty.exr"), &empty, NULL, &err) == IC_ERR_INVALID_ARG, "empty image written");
    ic_image_free(&src);

    /* A good write replaces an existing file and leaves no temporary behind. */
    ic_image small = constant(2, 2, 0.5f);
    CHECK(ic_image_write(scratch("replace.exr"), &small, NULL, &err) == IC_OK, "write: %s", err.message);
    small.rgb[0] = 0.75f;
    CHECK(ic_image_write(scratch("replace.exr"), &small, NULL, &err) == IC_OK, "rewrite: %s", err.message);
    CHECK(ic_image_read(scratch("replace.exr"), &img, &err) == IC_OK && img.rgb && img.rgb[0] == 0.75f,
          "rewritten file not replaced");
    CHECK(!temp_left_behind("replace.exr"), "temporary left after a good write");
    ic_image_free(&img);
    ic_image_free(&small);
}

/* Text attributes written to an EXR header come back as written (float and half), an attribute not
 * written is reported, a bad name is refused before anything is written, other formats ignore them. */
static void test_exr_metadata(void)
{
    ic_image img;
    CHECK(ic_image_create(&img, 5, 3) == IC_OK, "create");
    for (int i = 0; i < 15 * 3; ++i)
        img.rgb[i] = 0.25f * (float)i;
    const ic_image_meta meta[2] = {{"irrcache:note", "Λ·C = \"quoted\" text"}, {"owner", "tests"}};
    for (int half = 0; half <= 1; ++half) {
        ic_image_write_options wo = {0};
        wo.exr_half = half;
        wo.meta = meta;
        wo.meta_count = 2;
        ic_error err;
        CHECK(ic_image_write(SCRATCH "/meta.exr", &img, &wo, &err) == IC_OK, "write with metadata: %s", err.message);
        char v[256];
        CHECK(ic_image_exr_attribute(SCRATCH "/meta.exr", "irrcache:note", v, sizeof v, &err) == IC_OK &&
                  !strcmp(v, meta[0].value),
              "half %d: note reads back as %s", half, v);
        CHECK(ic_image_exr_attribute(SCRATCH "/meta.exr", "owner", v, sizeof v, &err) == IC_OK && !strcmp(v, "tests"),
              "half %d: owner reads back as %s", half, v);
        CHECK(ic_image_exr_attribute(SCRATCH "/meta.exr", "absent", v, sizeof v, &err) == IC_ERR_INVALID_ARG &&
                  v[0] == '\0',
              "half %d: an absent attribute", half);
        char small[6];
        CHECK(ic_image_exr_attribute(SCRATCH "/meta.exr", "owner", small, 3, &err) == IC_OK && !strcmp(small, "te"),
              "a small buffer truncates");
        ic_image back;
        CHECK(ic_image_read(SCRATCH "/meta.exr", &back, &err) == IC_OK && back.width == 5 &&
                  back.rgb[3 * 7 + 1] == img.rgb[3 * 7 + 1],
              "the pixels are untouched by the header");
        ic_image_free(&back);
    }
    /* Layers: two more images in the same file, read back by name; readers that know no layers see the image. */
    {
        ic_image l1, l2;
        CHECK(ic_image_create(&l1, 5, 3) == IC_OK && ic_image_create(&l2, 5, 3) == IC_OK, "layers");
        for (int i = 0; i < 15 * 3; ++i) {
            l1.rgb[i] = 1.0f + (float)i;
            l2.rgb[i] = -0.5f * (float)i;
        }
        const ic_image_layer layers[2] = {{"indirect", &l1}, {"density", &l2}};
        ic_image_write_options wo = {0};
        wo.layers = layers;
        wo.layer_count = 2;
        ic_error err;
        CHECK(ic_image_write(SCRATCH "/layers.exr", &img, &wo, &err) == IC_OK, "write layers: %s", err.message);
        ic_image a, b, c;
        CHECK(ic_image_read(SCRATCH "/layers.exr", &a, &err) == IC_OK &&
                  ic_image_read_layer(SCRATCH "/layers.exr", "indirect", &b, &err) == IC_OK &&
                  ic_image_read_layer(SCRATCH "/layers.exr", "density", &c, &err) == IC_OK,
              "read the image and its layers: %s", err.message);
        int same = 1;
        for (int i = 0; i < 15 * 3; ++i)
            same &= a.rgb[i] == img.rgb[i] && b.rgb[i] == l1.rgb[i] && c.rgb[i] == l2.rgb[i];
        CHECK(same, "image and layers read back bit for bit");
        ic_image_free(&a);
        ic_image_free(&b);
        ic_image_free(&c);
        CHECK(ic_image_read_layer(SCRATCH "/layers.exr", "glossy", &a, &err) == IC_ERR_UNSUPPORTED &&
                  strstr(err.message, "glossy"),
              "an absent layer is named: %s", err.message);
        CHECK(ic_image_read_layer(SCRATCH "/meta.pfm", "indirect", &a, &err) == IC_ERR_UNSUPPORTED, "a PFM has no layers");
        ic_image small;
        CHECK(ic_image_create(&small, 2, 2) == IC_OK, "small");
        const ic_image_layer wrong[1] = {{"indirect", &small}};
        wo.layers = wrong;
        wo.layer_count = 1;
        CHECK(ic_image_write(SCRATCH "/layers_bad.exr", &img, &wo, &err) == IC_ERR_INVALID_ARG,
              "a layer of another size is refused");
        const ic_image_layer dotted[1] = {{"in.direct", &l1}};
        wo.layers = dotted;
        CHECK(ic_image_write(SCRATCH "/layers_bad.exr", &img, &wo, &err) == IC_ERR_INVALID_ARG, "a dotted layer name is refused");
        ic_image_free(&small);
        ic_image_free(&l1);
        ic_image_free(&l2);
    }
    const ic_image_meta bad[1] = {{"", "x"}};
    ic_image_write_options wo = {0};
    wo.meta = bad;
    wo.meta_count = 1;
    ic_error err;
    CHECK(ic_image_write(SCRATCH "/bad_meta.exr", &img, &wo, &err) == IC_ERR_INVALID_ARG, "an empty name is refused");
    CHECK(access(SCRATCH "/bad_meta.exr", F_OK) != 0, "and nothing is written");
    wo.meta = meta;
    wo.meta_count = 2;
    CHECK(ic_image_write(SCRATCH "/meta.pfm", &img, &wo, &err) == IC_OK, "PFM ignores metadata");
    CHECK(ic_image_exr_attribute(SCRATCH "/meta.pfm", "owner", (char[4]){0}, 4, &err) != IC_OK,
          "a PFM is not an EXR");
    ic_image_free(&img);
}

/* What an embedding program may pass at the edges of the writers: 8-bit PNG sizes stb_image_write cannot
 * hold (a side of 0 overran its buffers and was reported written; a side over IC_IMAGE_MAX_SIDE was
 * written though no ic_image may have it), no pixels, no metrics to fill, arrays NULL with a count, and
 * EXR layers or attributes OpenEXR refuses (reported as an I/O failure, "check free disk space"): each is
 * IC_ERR_INVALID_ARG and writes nothing. */
static void test_writer_arguments(void)
{
    ic_error err;
    const char *png = SCRATCH "/arguments.png", *exr = SCRATCH "/arguments.exr";
    remove(png);
    remove(exr);
    const int wide = IC_IMAGE_MAX_SIDE + 1;
    uint8_t *bytes = calloc((size_t)wide * 3, 1);
    CHECK(ic_image_write_png8(png, bytes, 0, 2, &err) == IC_ERR_INVALID_ARG, "a PNG 0 pixels wide: %s",
          ic_result_name(err.code));
    CHECK(ic_image_write_png8(png, bytes, wide, 1, &err) == IC_ERR_INVALID_ARG, "a PNG %d pixels wide: %s", wide,
          ic_result_name(err.code));
    CHECK(ic_image_write_png8(png, NULL, 2, 2, &err) == IC_ERR_INVALID_ARG, "a PNG without pixels");
    CHECK(access(png, F_OK) != 0, "a refused PNG was written");
    CHECK(ic_image_write_png8(png, bytes, 4, 2, &err) == IC_OK, "a 4 x 2 PNG: %s", err.message);
    free(bytes);

    ic_image img = {0};
    CHECK(ic_image_create(&img, 4, 3) == IC_OK, "create");
    CHECK(ic_image_compare(&img, &img, NULL, &err) == IC_ERR_INVALID_ARG, "metrics into NULL");
    ic_image_write_options wo = {0};
    wo.meta_count = 1;
    CHECK(ic_image_write(exr, &img, &wo, &err) == IC_ERR_INVALID_ARG, "one attribute and no array");
    wo.meta_count = 0;
    wo.layer_count = 2;
    CHECK(ic_image_write(exr, &img, &wo, &err) == IC_ERR_INVALID_ARG, "two layers and no array");
    const ic_image_layer twice[2] = {{"indirect", &img}, {"indirect", &img}};
    wo.layers = twice;
    CHECK(ic_image_write(exr, &img, &wo, &err) == IC_ERR_INVALID_ARG, "a layer given twice: %s (%s)",
          ic_result_name(err.code), err.message);
    wo.layer_count = 0;
    const char *fields[3] = {"channels", "compression", "dataWindow"};
    for (int k = 0; k < 3; ++k) {
        const ic_image_meta field = {fields[k], "text"};
        wo.meta = &field;
        wo.meta_count = 1;
        CHECK(ic_image_write(exr, &img, &wo, &err) == IC_ERR_INVALID_ARG, "a text attribute named %s: %s (%s)",
              fields[k], ic_result_name(err.code), err.message);
    }
    CHECK(access(exr, F_OK) != 0, "a refused EXR was written");
    ic_image_free(&img);
}

static uint32_t crc32_png(const unsigned char *b, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i) {
        c ^= b[i];
        for (int k = 0; k < 8; ++k)
            c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return c ^ 0xFFFFFFFFu;
}

/* Writes img as a PNG to path and reads the file back into png[4096]: its length in *n and the offset of
 * its first IDAT chunk, or 0 if it has none. */
static size_t png_with_idat(const char *path, const ic_image *img, unsigned char png[4096], size_t *n)
{
    ic_error err;
    CHECK(ic_image_write(path, img, NULL, &err) == IC_OK, "write PNG: %s", err.message);
    FILE *f = fopen(path, "rb");
    *n = f ? fread(png, 1, 4096, f) : 0;
    if (f)
        fclose(f);
    size_t at = 8;
    while (at + 8 <= *n && memcmp(png + at + 4, "IDAT", 4) != 0)
        at += 12 + ((size_t)png[at] << 24 | (size_t)png[at + 1] << 16 | (size_t)png[at + 2] << 8 | png[at + 3]);
    CHECK(at + 8 <= *n, "the PNG has an IDAT chunk");
    return at + 8 <= *n ? at : 0;
}

/* An empty IDAT chunk is valid PNG (the image data is all IDATs concatenated) but made stb_image 2.27
 * offset a NULL pointer (fuzz target image_png): the reader drops it first and decodes the same pixels. */
static void test_png_empty_idat(void)
{
    ic_image img;
    CHECK(ic_image_create(&img, 6, 4) == IC_OK, "create");
    for (int i = 0; i < 6 * 4 * 3; ++i)
        img.rgb[i] = (float)(i % 7) / 7.0f;
    ic_error err;
    unsigned char png[4096], with[4096 + 12];
    size_t n = 0, at = png_with_idat(SCRATCH "/idat.png", &img, png, &n);
    if (!at) {
        ic_image_free(&img);
        return;
    }
    /* An empty IDAT (length 0, type, CRC of the type) before the first one. */
    memcpy(with, png, at);
    unsigned char empty[12] = {0, 0, 0, 0, 'I', 'D', 'A', 'T', 0, 0, 0, 0};
    uint32_t crc = crc32_png(empty + 4, 4);
    empty[8] = (unsigned char)(crc >> 24);
    empty[9] = (unsigned char)(crc >> 16);
    empty[10] = (unsigned char)(crc >> 8);
    empty[11] = (unsigned char)crc;
    memcpy(with + at, empty, 12);
    memcpy(with + at + 12, png + at, n - at);
    ic_image a, b;
    CHECK(ic_image_decode_memory(png, n, "plain.png", 0, NULL, &a, &err) == IC_OK, "plain PNG decodes: %s", err.message);
    CHECK(ic_image_decode_memory(with, n + 12, "empty-idat.png", 0, NULL, &b, &err) == IC_OK,
          "a PNG with an empty IDAT decodes: %s", err.message);
    int same = a.rgb && b.rgb && a.width == b.width && a.height == b.height;
    for (int i = 0; same && i < 6 * 4 * 3; ++i)
        same = a.rgb[i] == b.rgb[i];
    CHECK(same, "the same pixels with and without the empty IDAT");
    ic_image_free(&a);
    ic_image_free(&b);
    ic_image_free(&img);
}

/* A PNG chunk whose length runs past the end of the file (stb_image 2.27 grew its buffer to a declared
 * 1 GB IDAT, 2 GB, before reading it: fuzz target image_png) is refused naming the file; so is one cut
 * inside its CRC. The same PNG whole still reads. */
static void test_png_chunk_overrun(void)
{
    ic_image img;
    CHECK(ic_image_create(&img, 5, 3) == IC_OK, "create");
    ic_error err;
    unsigned char png[4096];
    size_t n = 0, at = png_with_idat(SCRATCH "/chunks.png", &img, png, &n);
    ic_image_free(&img);
    if (!at)
        return;
    size_t idat_len = (size_t)png[at] << 24 | (size_t)png[at + 1] << 16 | (size_t)png[at + 2] << 8 | png[at + 3];
    CHECK(ic_image_decode_memory(png, n, "whole.png", 0, NULL, &img, &err) == IC_OK, "whole: %s", err.message);
    ic_image_free(&img);
    CHECK(ic_image_decode_memory(png, at + 8 + idat_len + 2, "cut.png", 0, NULL, &img, &err) == IC_ERR_PARSE &&
              strstr(err.message, "cut.png") && strstr(err.message, "truncated"),
          "a PNG cut in an IDAT's CRC: %s", err.message);
    png[at] = 0x41; /* about 1 GB */
    write_bytes(scratch("overrun.png"), png, n);
    CHECK(ic_image_read(scratch("overrun.png"), &img, &err) == IC_ERR_PARSE && strstr(err.message, "overrun.png") &&
              strstr(err.message, "truncated") && img.rgb == NULL,
          "an IDAT declaring 1 GB: %s", err.message);
}

static uint32_t be32_at(const unsigned char *b)
{
    return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3];
}

/* Every PNG written (a rendered image through ic_image_write, the false-colour and record maps through
 * ic_image_write_png8) holds sRGB-encoded bytes and says so as ISO/IEC 15948 asks: an sRGB chunk (rendering
 * intent 0..3) and, beside it for readers that know only those, gAMA 45455 and the sRGB cHRM (§11.3.3.5), all
 * before IDAT; each chunk's CRC is right (checked here bit by bit, not with the writer's table) and the pixels
 * read back the same. Without them (stb_image_write writes none) a reader guessed the colour space. */
static void test_png_colour_chunks(void)
{
    ic_image img;
    CHECK(ic_image_create(&img, 5, 3) == IC_OK, "create");
    uint8_t bytes[5 * 3 * 3];
    for (int i = 0; i < 5 * 3 * 3; ++i) {
        img.rgb[i] = (float)i / 45.0f;
        bytes[i] = (uint8_t)(17 * i);
    }
    ic_error err;
    CHECK(ic_image_write_png8(SCRATCH "/colour8.png", bytes, 5, 3, &err) == IC_OK, "write png8: %s", err.message);
    const char *paths[2] = {SCRATCH "/colour.png", SCRATCH "/colour8.png"};
    for (int k = 0; k < 2; ++k) {
        unsigned char png[4096];
        size_t n = 0;
        if (k == 0)
            png_with_idat(paths[0], &img, png, &n);
        else {
            FILE *f = fopen(paths[1], "rb");
            n = f ? fread(png, 1, sizeof png, f) : 0;
            if (f)
                fclose(f);
        }
        long at_srgb = -1, at_gama = -1, at_chrm = -1, at_idat = -1;
        int crcs_ok = 1, iend = 0;
        uint32_t gamma = 0, chrm[8] = {0};
        int intent = -1;
        for (size_t at = 8; at + 12 <= n && !iend;) {
            const uint32_t len = be32_at(png + at);
            if (len > n - at - 12)
                break;
            const unsigned char *type = png + at + 4, *data = png + at + 8;
            crcs_ok &= crc32_png(type, 4 + (size_t)len) == be32_at(data + len);
            if (!memcmp(type, "sRGB", 4) && len == 1) {
                at_srgb = (long)at;
                intent = data[0];
            } else if (!memcmp(type, "gAMA", 4) && len == 4) {
                at_gama = (long)at;
                gamma = be32_at(data);
            } else if (!memcmp(type, "cHRM", 4) && len == 32) {
                at_chrm = (long)at;
                for (int c = 0; c < 8; ++c)
                    chrm[c] = be32_at(data + 4 * c);
            } else if (!memcmp(type, "IDAT", 4) && at_idat < 0) {
                at_idat = (long)at;
            }
            iend = !memcmp(type, "IEND", 4);
            at += 12 + (size_t)len;
        }
        CHECK(iend && crcs_ok, "%s: chunks end with IEND and every CRC matches", paths[k]);
        CHECK(at_srgb > 0 && at_srgb < at_idat && intent >= 0 && intent <= 3, "%s: an sRGB chunk before IDAT",
              paths[k]);
        CHECK(at_gama > 0 && at_gama < at_idat && gamma == 45455, "%s: gAMA 45455 before IDAT (%u)", paths[k],
              gamma);
        const uint32_t srgb_chrm[8] = {31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000};
        CHECK(at_chrm > 0 && at_chrm < at_idat && !memcmp(chrm, srgb_chrm, sizeof chrm),
              "%s: cHRM with the sRGB white and primaries before IDAT", paths[k]);
        ic_image back;
        CHECK(ic_image_read(paths[k], &back, &err) == IC_OK && back.width == 5 && back.height == 3,
              "%s reads back: %s", paths[k], err.message);
        int same = back.rgb != NULL;
        for (int i = 0; same && i < 5 * 3 * 3; ++i)
            same = ic_linear_to_srgb8(back.rgb[i]) == (k ? bytes[i] : ic_linear_to_srgb8(img.rgb[i]));
        CHECK(same, "%s: the same pixels", paths[k]);
        ic_image_free(&back);
    }
    ic_image_free(&img);
}

/* A Radiance picture names its primaries (PRIMARIES= line of the header, rx ry gx gy bx by wx wy): without
 * one, Radiance's tools take its own standard (green at 0.290 0.600, equal-energy white), not the Rec. 709 /
 * D65 the pixels are in. The line agrees with the chromaticities the same image's EXR header carries. */
static void test_hdr_primaries(void)
{
    ic_image img = constant(3, 2, 0.5f);
    ic_error err;
    CHECK(ic_image_write(SCRATCH "/prims.hdr", &img, NULL, &err) == IC_OK, "write hdr: %s", err.message);
    CHECK(ic_image_write(SCRATCH "/prims.exr", &img, NULL, &err) == IC_OK, "write exr: %s", err.message);
    ic_image_free(&img);
    FILE *f = fopen(SCRATCH "/prims.hdr", "rb");
    char line[256];
    float prims[8];
    int found = 0, format = 0;
    while (f && fgets(line, sizeof line, f) && strcmp(line, "\n") != 0) {
        format |= !strcmp(line, "FORMAT=32-bit_rle_rgbe\n");
        if (!strncmp(line, "PRIMARIES=", 10))
            found += sscanf(line + 10, "%f %f %f %f %f %f %f %f", &prims[0], &prims[1], &prims[2], &prims[3],
                            &prims[4], &prims[5], &prims[6], &prims[7]) == 8;
    }
    if (f)
        fclose(f);
    CHECK(format && found == 1, "the HDR header has its FORMAT and one PRIMARIES line of 8 numbers");
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctxt = NULL;
    exr_attr_chromaticities_t chr;
    const exr_attribute_t *attr = NULL;
    int read = exr_start_read(&ctxt, SCRATCH "/prims.exr", &init) == EXR_ERR_SUCCESS &&
               exr_get_attribute_by_name(ctxt, 0, "chromaticities", &attr) == EXR_ERR_SUCCESS && attr &&
               attr->type == EXR_ATTR_CHROMATICITIES;
    if (read)
        chr = *attr->chromaticities;
    exr_finish(&ctxt);
    CHECK(read, "the EXR has chromaticities");
    if (read && found == 1) {
        const float want[8] = {chr.red_x, chr.red_y, chr.green_x, chr.green_y, chr.blue_x, chr.blue_y,
                               chr.white_x, chr.white_y};
        int agree = 1;
        for (int c = 0; c < 8; ++c)
            agree &= fabsf(prims[c] - want[c]) < 1e-4f;
        CHECK(agree, "HDR PRIMARIES %g %g %g %g %g %g %g %g agree with the EXR's chromaticities", prims[0], prims[1],
              prims[2], prims[3], prims[4], prims[5], prims[6], prims[7]);
    }
    CHECK(ic_image_read(SCRATCH "/prims.hdr", &img, &err) == IC_OK && img.width == 3 && fabsf(img.rgb[0] - 0.5f) < 0.004f,
          "the HDR with its PRIMARIES line reads back: %s", err.message);
    ic_image_free(&img);
}

/* Tiled OpenEXR (environment maps are often tiled) reads as the same pixels as it was written, float and
 * half, with partial tiles at the right and bottom edges. */
static void test_tiled_exr(void)
{
    ic_image img;
    CHECK(ic_image_create(&img, 37, 21) == IC_OK, "create");
    for (int i = 0; i < 37 * 21 * 3; ++i)
        img.rgb[i] = 0.125f * (float)(i % 97) + 0.5f * (float)(i % 3); /* exact in half */
    for (int half = 0; half <= 1; ++half) {
        CHECK(write_tiled_exr(SCRATCH "/tiled.exr", &img, 16, 8, half), "tiled EXR written (half %d)", half);
        ic_image back;
        ic_error err;
        CHECK(ic_image_read(SCRATCH "/tiled.exr", &back, &err) == IC_OK, "tiled EXR reads (half %d): %s", half,
              err.message);
        int diff = back.width != img.width || back.height != img.height;
        for (int i = 0; !diff && i < 37 * 21 * 3; ++i)
            diff = back.rgb[i] != img.rgb[i];
        CHECK(!diff, "tiled EXR pixels (half %d) equal what was written", half);
        ic_image_free(&back);
    }
    ic_image_free(&img);
}

/* A scanline OpenEXR whose colour channels sit beside channels we do not read (alpha, depth, sub-sampled
 * ones), in half and float mixed, reads as its colour, exactly (every value is exact in half). The first
 * case made OpenEXR Core 3.1's own unpacker write through a NULL pointer (its three-channel fast path
 * counted the skipped float channel); a fuzzer found it. */
static void test_exr_extra_channels(void)
{
    const exr_pixel_type_t H = EXR_PIXEL_HALF, F = EXR_PIXEL_FLOAT;
    const struct {
        test_exr_channel ch[4];
        int count, grey;
        exr_compression_t compression;
    } cases[] = {
        {{{"B", H, 1}, {"G", H, 1}, {"X", F, 1}}, 3, 0, EXR_COMPRESSION_NONE},
        {{{"B", H, 1}, {"G", H, 1}, {"X", F, 1}}, 3, 0, EXR_COMPRESSION_ZIP},
        {{{"A", F, 1}, {"B", H, 1}, {"G", H, 1}, {"R", H, 1}}, 4, 0, EXR_COMPRESSION_ZIPS},
        {{{"B", F, 1}, {"G", H, 1}, {"R", F, 1}, {"Z", H, 1}}, 4, 0, EXR_COMPRESSION_NONE},
        {{{"R", H, 1}, {"G", H, 1}, {"B", H, 1}, {"s", H, 2}}, 4, 0, EXR_COMPRESSION_NONE},
        {{{"Y", H, 1}, {"Z", F, 1}}, 2, 1, EXR_COMPRESSION_RLE},
    };
    ic_image img;
    CHECK(ic_image_create(&img, 29, 6) == IC_OK, "create");
    for (int i = 0; i < 29 * 6 * 3; ++i)
        img.rgb[i] = 0.125f * (float)(i % 89) + 0.5f * (float)(i % 3) + 0.25f; /* exact in half */
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        CHECK(write_scanline_exr(SCRATCH "/extra.exr", &img, cases[k].ch, cases[k].count, cases[k].compression),
              "EXR with extra channels written (case %zu)", k);
        ic_image back;
        ic_error err;
        CHECK(ic_image_read(SCRATCH "/extra.exr", &back, &err) == IC_OK, "case %zu reads: %s", k, err.message);
        int has[3] = {0, 0, 0};
        for (int c = 0; c < cases[k].count; ++c)
            for (int s = 0; s < 3; ++s)
                has[s] |= !strcmp(cases[k].ch[c].name, (const char *[]){"R", "G", "B"}[s]);
        int diff = back.width != img.width || back.height != img.height;
        for (int i = 0; !diff && i < 29 * 6 * 3; ++i) {
            float want = cases[k].grey ? img.rgb[i - i % 3] : has[i % 3] ? img.rgb[i] : 0.0f;
            diff = back.rgb[i] != want;
        }
        CHECK(!diff, "case %zu: the colour read back is what was written (missing channels 0)", k);
        ic_image_free(&back);
    }

    /* An uncompressed chunk whose size field is 4 bytes short of its lines: refused (the library would
     * leave the rest of its buffer unwritten and we would read it). The first offset-table entry is the
     * one 64-bit value equal to its own position plus the table's length (one chunk per line). */
    CHECK(write_scanline_exr(SCRATCH "/short.exr", &img, cases[0].ch, cases[0].count, EXR_COMPRESSION_NONE),
          "uncompressed EXR written");
    unsigned char bytes[8192];
    FILE *fp = fopen(SCRATCH "/short.exr", "rb");
    size_t n = fp ? fread(bytes, 1, sizeof bytes, fp) : 0;
    if (fp)
        fclose(fp);
    size_t chunk = 0;
    for (size_t p = 0; !chunk && p + 8 <= n; ++p) {
        uint64_t v = 0;
        for (int b = 7; b >= 0; --b)
            v = v << 8 | bytes[p + (size_t)b];
        if (v == p + 8 * 6 && v + 8 <= n)
            chunk = (size_t)v;
    }
    CHECK(chunk > 0 && n < sizeof bytes, "the first chunk of the uncompressed EXR found");
    if (chunk > 0) {
        bytes[chunk + 4] -= 4; /* its size: 29 × (2 + 2 + 4) = 232 bytes, so no borrow */
        write_bytes(SCRATCH "/short.exr", bytes, n);
        ic_image back;
        ic_error err;
        ic_result r = ic_image_read(SCRATCH "/short.exr", &back, &err);
        CHECK(r == IC_ERR_CORRUPT && strstr(err.message, "short.exr") && back.rgb == NULL,
              "an uncompressed chunk shorter than its lines: %s (%s)", ic_result_name(r), err.message);
    }
    ic_image_free(&img);
}

/* Writes head (hn bytes), then fill zero bytes, then tail (tn bytes). */
static void write_padded(const char *path, const void *head, size_t hn, size_t fill, const void *tail, size_t tn)
{
    FILE *fp = fopen(path, "wb");
    CHECK(fp != NULL, "cannot create %s", path);
    if (!fp)
        return;
    static const unsigned char zeros[65536];
    fwrite(head, 1, hn, fp);
    for (size_t left = fill; left > 0;) {
        size_t k = left < sizeof zeros ? left : sizeof zeros;
        fwrite(zeros, 1, k, fp);
        left -= k;
    }
    fwrite(tail, 1, tn, fp);
    fclose(fp);
}

/* A PNG or JPEG is judged by its header before it is read into memory: a file far larger than its declared
 * pixels can need (or with no size in its header) is refused, a size beyond the caller's limit too, while a
 * megabyte of metadata beside one pixel still reads. */
static void test_ldr_header_first(void)
{
    ic_image img, back;
    ic_error err;
    CHECK(ic_image_create(&img, 1, 1) == IC_OK, "create");
    img.rgb[0] = img.rgb[1] = img.rgb[2] = 0.5f;
    CHECK(ic_image_write(scratch("one.png"), &img, NULL, &err) == IC_OK, "write: %s", err.message);
    ic_image_free(&img);
    unsigned char png[512];
    FILE *fp = fopen(scratch("one.png"), "rb");
    size_t n = fp ? fread(png, 1, sizeof png, fp) : 0;
    if (fp)
        fclose(fp);
    CHECK(n > 33 && n < sizeof png && !memcmp(png + 12, "IHDR", 4), "a 1x1 PNG of %zu bytes", n);
    /* after the signature and IHDR (33 bytes), a private ancillary chunk "prVt" of L zero bytes (and CRC) */
    for (int big = 0; big <= 1; ++big) {
        const size_t len = big ? (size_t)17 << 20 : (size_t)1 << 20;
        unsigned char head[33 + 8];
        memcpy(head, png, 33);
        const unsigned char chunk[8] = {(unsigned char)(len >> 24), (unsigned char)(len >> 16),
                                        (unsigned char)(len >> 8), (unsigned char)len, 'p', 'r', 'V', 't'};
        memcpy(head + 33, chunk, 8);
        write_padded(scratch("padded.png"), head, sizeof head, len + 4, png + 33, n - 33);
        ic_result r = ic_image_read(scratch("padded.png"), &back, &err);
        if (big)
            CHECK(r == IC_ERR_PARSE && strstr(err.message, "padded.png") && strstr(err.message, "1x1 pixels") &&
                      back.rgb == NULL,
                  "a 1x1 PNG with 17 MiB of metadata: %s (%s)", ic_result_name(r), err.message);
        else
            CHECK(r == IC_OK && back.width == 1 && back.height == 1, "a 1x1 PNG with 1 MiB of metadata: %s",
                  err.message);
        ic_image_free(&back);
    }
    remove(scratch("padded.png"));

    /* a JPEG with no frame header before its scan, 17 MiB long */
    const unsigned char nosof[] = {0xFF, 0xD8, 0xFF, 0xFE, 0x00, 0x04, 'h', 'i', 0xFF, 0xDA, 0x00, 0x08};
    write_padded(scratch("nosof.jpg"), nosof, sizeof nosof, (size_t)17 << 20, "\xFF\xD9", 2);
    ic_result r = ic_image_read(scratch("nosof.jpg"), &back, &err);
    CHECK(r == IC_ERR_PARSE && strstr(err.message, "nosof.jpg") && strstr(err.message, "no image size"),
          "a 17 MiB JPEG without a frame header: %s (%s)", ic_result_name(r), err.message);
    remove(scratch("nosof.jpg"));

    /* a frame header of 3000 x 2000 behind 60 kB of APP1 (Exif) and a fill byte: over a limit of 10^6 pixels */
    unsigned char app[] = {0xFF, 0xD8, 0xFF, 0xE1, 0xEA, 0x62}; /* 60,002 bytes: its length and 60,000 more */
    const unsigned char sof[] = {0xFF, 0xFF, 0xC2, 0x00, 0x11, 0x08, 0x07, 0xD0, 0x0B, 0xB8, 0x03, 0x01, 0x22,
                                 0x00, 0x02, 0x11, 0x01, 0x03, 0x11, 0x01, 0xFF, 0xD9};
    write_padded(scratch("big.jpg"), app, sizeof app, 60000, sof, sizeof sof);
    r = ic_image_read_max(scratch("big.jpg"), 1000000, "raise the limit", &back, &err);
    CHECK(r == IC_ERR_UNSUPPORTED && strstr(err.message, "3000x2000") && strstr(err.message, "raise the limit"),
          "a 3000x2000 JPEG over a 10^6-pixel limit: %s (%s)", ic_result_name(r), err.message);
}

/* Damage that used to decode as some image: a PNG's pixel data with a flipped byte (stb_image checks no
 * CRC), a PNG without its IEND, sizes that %d wrapped (4294967297 read as 1), an EXPOSURE that made every
 * pixel infinite. Each is refused, naming the file and the trouble. */
static void test_damaged_files(void)
{
    ic_image img, back;
    ic_error err;
    CHECK(ic_image_create(&img, 6, 4) == IC_OK, "create");
    for (int i = 0; i < 6 * 4 * 3; ++i)
        img.rgb[i] = (float)(i % 5) / 5.0f;
    unsigned char png[4096];
    size_t n = 0, at = png_with_idat(SCRATCH "/crc.png", &img, png, &n);
    ic_image_free(&img);
    if (at) {
        png[at + 8 + 2] ^= 0x10; /* a byte of the IDAT's data; its CRC unchanged */
        write_bytes(SCRATCH "/crc.png", png, n);
        ic_result r = ic_image_read(SCRATCH "/crc.png", &back, &err);
        CHECK(r == IC_ERR_CORRUPT && strstr(err.message, "crc.png") && strstr(err.message, "'IDAT'") &&
                  strstr(err.message, "fails its CRC check"),
              "a flipped byte in the pixel data: %s (%s)", ic_result_name(r), err.message);
        ic_image_free(&back);
        png[at + 8 + 2] ^= 0x10;
        write_bytes(SCRATCH "/noiend.png", png, n - 12); /* IEND is the last 12 bytes */
        r = ic_image_read(SCRATCH "/noiend.png", &back, &err);
        CHECK(r == IC_ERR_CORRUPT && strstr(err.message, "noiend.png") && strstr(err.message, "without its IEND"),
              "no IEND: %s (%s)", ic_result_name(r), err.message);
        ic_image_free(&back);
    }
    static const struct {
        const char *name, *text, *words;
    } cases[] = {
        {"wrap.pfm", "PF\n4294967297 1\n-1.0\n", "malformed PFM header"},
        {"wrap.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4294967300 +X 4\n", "not a whole number"},
        {"exposure.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1e-300\n\n-Y 1 +X 1\n\x80\x80\x80\xff",
         "EXPOSURE lines multiply to 1e-300"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s", SCRATCH, cases[k].name);
        write_bytes(path, (const unsigned char *)cases[k].text, strlen(cases[k].text));
        ic_result r = ic_image_read(path, &back, &err);
        CHECK(r != IC_OK && strstr(err.message, cases[k].name) && strstr(err.message, cases[k].words),
              "%s refused with '%s': %s", cases[k].name, cases[k].words, err.message);
        ic_image_free(&back);
    }
}

/* ic_image_read_texture: an 8-bit PNG or JPEG (colour or greyscale) comes back as the bytes whose sRGB values
 * ic_image_read_max gives, every other file as ic_image_read_max reads it; a damaged one is refused alike. */
static void expect_texture_bytes(const char *path, int want_bytes)
{
    ic_image floats, shape;
    ic_error err;
    uint8_t *bytes = (uint8_t *)"";
    CHECK(ic_image_read_max(path, 0, NULL, &floats, &err) == IC_OK, "%s: %s", path, err.message);
    CHECK(ic_image_read_texture(path, 0, NULL, &shape, &bytes, &err) == IC_OK, "%s as a texture: %s", path,
          err.message);
    CHECK((bytes != NULL) == want_bytes && shape.width == floats.width && shape.height == floats.height,
          "%s: bytes %d (want %d), %dx%d against %dx%d", path, bytes != NULL, want_bytes, shape.width, shape.height,
          floats.width, floats.height);
    size_t n = (size_t)floats.width * (size_t)floats.height * 3, differ = 0;
    for (size_t k = 0; k < n; ++k)
        differ += bytes ? ic_srgb8_to_linear(bytes[k]) != floats.rgb[k] : shape.rgb[k] != floats.rgb[k];
    CHECK(differ == 0 && (!bytes || !shape.rgb), "%s: %zu of %zu values differ", path, differ, n);
    free(bytes);
    ic_image_free(&shape);
    ic_image_free(&floats);
}

static void test_texture_bytes(void)
{
    ic_image img = pattern(13, 7, 1.0f);
    ic_error err;
    CHECK(ic_image_write_png(scratch("texture.png"), &img, 0.0f, &err) == IC_OK, "%s", err.message);
    CHECK(ic_image_write_pfm(scratch("texture.pfm"), &img, &err) == IC_OK, "%s", err.message);
    ic_image_free(&img);
    expect_texture_bytes(scratch("texture.png"), 1);
    expect_texture_bytes(scratch("texture.pfm"), 0);
    static const char *const jpegs[] = {"rgb_8x8.jpg", "grey_4x4.jpg", "progressive_37x23.jpg", "grey_4x4.png"};
    for (size_t k = 0; k < sizeof jpegs / sizeof jpegs[0]; ++k) {
        char path[1024];
        snprintf(path, sizeof path, "%s/tests/fuzz/corpus/image_png/%s", IC_SOURCE_DIR, jpegs[k]);
        expect_texture_bytes(path, 1);
    }
    uint8_t *bytes = NULL;
    ic_image out;
    CHECK(ic_image_read_texture(scratch("texture.png"), 0, NULL, &out, NULL, &err) == IC_ERR_INVALID_ARG,
          "no place for the bytes: refused");
    /* a JPEG cut short, and an image over the pixel limit: refused with nothing left allocated (ASan) */
    char path[1024];
    snprintf(path, sizeof path, "%s/tests/fuzz/corpus/image_png/rgb_8x8.jpg", IC_SOURCE_DIR);
    FILE *fp = fopen(path, "rb");
    unsigned char head[200];
    size_t got = fp ? fread(head, 1, sizeof head, fp) : 0;
    if (fp)
        fclose(fp);
    write_bytes(scratch("cut.jpg"), head, got);
    CHECK(ic_image_read_texture(scratch("cut.jpg"), 0, NULL, &out, &bytes, &err) == IC_ERR_PARSE && !bytes,
          "a cut JPEG: refused, no bytes (%s)", err.message);
    CHECK(ic_image_read_texture(path, 10, "raise it", &out, &bytes, &err) == IC_ERR_UNSUPPORTED && !bytes &&
              strstr(err.message, "raise it"),
          "a JPEG over the pixel limit: refused, no bytes (%s)", err.message);
}

int main(void)
{
    if (mkdir(IC_TEST_TMP, 0755) != 0 && errno != EEXIST)
        perror(IC_TEST_TMP);
    if (mkdir(SCRATCH, 0755) != 0 && errno != EEXIST)
        perror(SCRATCH);
    test_create_free();
    test_srgb();
    test_round_trips();
    test_pfm_variants();
    test_hdr_variants();
    test_metrics();
    test_lowpass();
    test_blotch_map();
    test_heatmap();
    test_heatmap_fixed_scale();
    test_bad_input();
    test_exr_metadata();
    test_writer_arguments();
    test_tiled_exr();
    test_exr_extra_channels();
    test_ldr_header_first();
    test_png_empty_idat();
    test_png_chunk_overrun();
    test_png_colour_chunks();
    test_hdr_primaries();
    test_damaged_files();
    test_texture_bytes();
    TEST_MAIN_END();
}
