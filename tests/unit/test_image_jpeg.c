/*
 * test_image_jpeg.c — the JPEG reader (src/image/jpeg.c) on files written here with libjpeg's encoder:
 * baseline, progressive, arithmetic-coded and greyscale files decode to the source within the encoder's
 * quantisation error, and the progressive and arithmetic-coded files to exactly the baseline's pixels
 * (the same quantised coefficients, only entropy-coded differently: T.81 Annexes F and G); damaged,
 * oversized and CMYK files are refused with a one-line message naming the file.
 */
#include "irrcache/image.h"

#include "image/image_internal.h"
#include "test_util.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <jpeglib.h>

#ifndef IC_TEST_TMP
#define IC_TEST_TMP "/tmp"
#endif
#define SCRATCH IC_TEST_TMP "/image_jpeg"
#define W 37 /* not a multiple of the 16-pixel MCU of 2x2 chroma subsampling: partial blocks at the edges */
#define H 23

/* PROGRESSIVE: libjpeg's usual scan script (10 scans); BANDS: one scan per AC coefficient of each component
 * (190 scans); BIT_PLANES: each of those in three bit planes (568 scans, T.81 §G.1.1.1.2), more than the
 * reader's limit of 500. */
enum jpeg_kind { BASELINE, PROGRESSIVE, ARITHMETIC, BANDS, BIT_PLANES };

/* A smooth source (each channel varies along its own axis, so a flip, transpose or channel swap shows),
 * 1 or 3 channels. */
static void source(uint8_t *px, int channels)
{
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            uint8_t *p = px + (size_t)channels * ((size_t)y * W + (size_t)x);
            p[0] = (uint8_t)(30 + 190 * x / (W - 1));
            if (channels == 3) {
                p[1] = (uint8_t)(50 + 160 * y / (H - 1));
                p[2] = (uint8_t)(200 - 120 * (x + y) / (W + H - 2));
            }
        }
}

/* Writes px (W×H, channels 1 grey, 3 RGB, 4 CMYK; for 4, ycck picks YCCK over CMYK in the file) at
 * quality 95 with libjpeg; an APP1 EXIF block with orientation 6 (rotate 90°) when exif. 1 on success. */
static int write_jpeg(const char *path, const uint8_t *px, int channels, enum jpeg_kind kind, int ycck, int exif)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return 0;
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr jerr;
    c.err = jpeg_std_error(&jerr);
    jpeg_create_compress(&c);
    jpeg_stdio_dest(&c, f);
    c.image_width = W;
    c.image_height = H;
    c.input_components = channels;
    c.in_color_space = channels == 1 ? JCS_GRAYSCALE : channels == 3 ? JCS_RGB : JCS_CMYK;
    jpeg_set_defaults(&c);
    if (channels == 4)
        jpeg_set_colorspace(&c, ycck ? JCS_YCCK : JCS_CMYK);
    jpeg_set_quality(&c, 95, TRUE);
    if (kind == PROGRESSIVE)
        jpeg_simple_progression(&c);
    static jpeg_scan_info scans[1 + 3 * 63 * 3];
    if (kind == BANDS || kind == BIT_PLANES) {
        int count = 0;
        scans[count++] = (jpeg_scan_info){3, {0, 1, 2, 0}, 0, 0, 0, 0}; /* DC of all three */
        for (int comp = 0; comp < 3; ++comp)
            for (int k = 1; k < 64; ++k) {
                if (kind == BANDS) {
                    scans[count++] = (jpeg_scan_info){1, {comp, 0, 0, 0}, k, k, 0, 0};
                    continue;
                }
                scans[count++] = (jpeg_scan_info){1, {comp, 0, 0, 0}, k, k, 0, 2}; /* bits 2 and up */
                scans[count++] = (jpeg_scan_info){1, {comp, 0, 0, 0}, k, k, 2, 1}; /* bit 1 */
                scans[count++] = (jpeg_scan_info){1, {comp, 0, 0, 0}, k, k, 1, 0}; /* bit 0 */
            }
        c.scan_info = scans;
        c.num_scans = count;
    }
    c.arith_code = kind == ARITHMETIC;
    jpeg_start_compress(&c, TRUE);
    if (exif) {
        /* "Exif\0\0", a big-endian TIFF header, one IFD entry: Orientation (0x0112), SHORT, 1, value 6. */
        static const JOCTET app1[] = {'E', 'x', 'i', 'f', 0, 0, 'M', 'M', 0, 42, 0, 0, 0, 8, 0, 1,
                                      0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, 6, 0, 0, 0, 0, 0, 0};
        jpeg_write_marker(&c, JPEG_APP0 + 1, app1, sizeof app1);
    }
    while (c.next_scanline < c.image_height) {
        JSAMPROW row = (JSAMPROW)(px + (size_t)c.next_scanline * W * (size_t)channels);
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    return fclose(f) == 0;
}

/* The largest and the mean difference, in 8-bit sRGB levels, between a decoded image and its source. */
static void compare(const ic_image *img, const uint8_t *px, int channels, int *max_diff, double *mean_diff)
{
    *max_diff = 0;
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)W * H; ++i)
        for (int c = 0; c < 3; ++c) {
            int want = px[(size_t)channels * i + (size_t)(channels == 3 ? c : 0)];
            int d = abs((int)ic_linear_to_srgb8(img->rgb[3 * i + (size_t)c]) - want);
            *max_diff = d > *max_diff ? d : *max_diff;
            sum += d;
        }
    *mean_diff = sum / (3.0 * W * H);
}

static int same_pixels(const ic_image *a, const ic_image *b)
{
    if (!a->rgb || !b->rgb || a->width != b->width || a->height != b->height)
        return 0;
    return memcmp(a->rgb, b->rgb, (size_t)a->width * (size_t)a->height * 3 * sizeof(float)) == 0;
}

static unsigned char *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    unsigned char *b = malloc(1 << 16);
    *n = f && b ? fread(b, 1, 1 << 16, f) : 0;
    if (f)
        fclose(f);
    return b;
}

static void spill(const char *path, const unsigned char *b, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (f) {
        fwrite(b, 1, n, f);
        fclose(f);
    }
}

/* A refusal: the result, the file named, one line. */
static int refused(ic_result got, ic_result want, const ic_error *err, const char *name)
{
    if (getenv("IC_TEST_VERBOSE"))
        printf("%s\n", err->message);
    return got == want && strstr(err->message, name) && !strchr(err->message, '\n');
}

/* Quality 95 on a smooth image: the quantisation error of T.81's example tables scaled to quality 95
 * (steps of 2 to 5 levels on the lowest frequencies), and the 2x2 chroma subsampling, stay within a few
 * levels; the bounds leave room for rounding through linear float and back. */
#define MAX_LEVELS 8
#define MEAN_LEVELS 1.5

static void test_decodes(void)
{
    uint8_t rgb[W * H * 3], grey[W * H];
    source(rgb, 3);
    source(grey, 1);
    ic_image img[3];
    ic_error err;
    const char *names[3] = {SCRATCH "/baseline.jpg", SCRATCH "/progressive.jpg", SCRATCH "/arithmetic.jpg"};
    for (int k = BASELINE; k <= ARITHMETIC; ++k) {
        CHECK(write_jpeg(names[k], rgb, 3, (enum jpeg_kind)k, 0, 0), "write %s", names[k]);
        CHECK(ic_image_read(names[k], &img[k], &err) == IC_OK && img[k].width == W && img[k].height == H,
              "%s decodes: %s", names[k], err.message);
        int max_diff = 999;
        double mean_diff = 999.0;
        if (img[k].rgb)
            compare(&img[k], rgb, 3, &max_diff, &mean_diff);
        CHECK(max_diff <= MAX_LEVELS && mean_diff <= MEAN_LEVELS, "%s: %d levels at most, %.3f on average", names[k],
              max_diff, mean_diff);
        if (getenv("IC_TEST_VERBOSE"))
            printf("%s: %d levels at most, %.3f on average\n", names[k], max_diff, mean_diff);
    }
    CHECK(same_pixels(&img[BASELINE], &img[PROGRESSIVE]), "progressive decodes to the baseline's pixels");
    CHECK(same_pixels(&img[BASELINE], &img[ARITHMETIC]), "arithmetic-coded decodes to the baseline's pixels");
    ic_image bands;
    CHECK(write_jpeg(SCRATCH "/bands.jpg", rgb, 3, BANDS, 0, 0), "write bands.jpg");
    CHECK(ic_image_read(SCRATCH "/bands.jpg", &bands, &err) == IC_OK && same_pixels(&bands, &img[BASELINE]),
          "190 scans decode to the baseline's pixels: %s", err.message);
    ic_image_free(&bands);

    /* From memory (an image embedded in a glTF file): the same pixels as from the file. */
    size_t n = 0;
    unsigned char *bytes = slurp(names[BASELINE], &n);
    ic_image mem;
    CHECK(ic_image_decode_memory(bytes, n, "embedded.jpg", 0, NULL, &mem, &err) == IC_OK &&
              same_pixels(&mem, &img[BASELINE]),
          "decoded from memory: %s", err.message);
    ic_image_free(&mem);
    free(bytes);

    /* EXIF orientation is not applied: the stored pixels, as without the tag. */
    CHECK(write_jpeg(SCRATCH "/exif.jpg", rgb, 3, BASELINE, 0, 1), "write exif.jpg");
    ic_image exif;
    CHECK(ic_image_read(SCRATCH "/exif.jpg", &exif, &err) == IC_OK && same_pixels(&exif, &img[BASELINE]),
          "an EXIF orientation leaves the pixels in stored order: %s", err.message);
    ic_image_free(&exif);

    /* Greyscale (one component), baseline and progressive: R = G = B, close to the source. */
    for (int k = BASELINE; k <= PROGRESSIVE; ++k) {
        const char *name = k == BASELINE ? SCRATCH "/grey.jpg" : SCRATCH "/grey_progressive.jpg";
        CHECK(write_jpeg(name, grey, 1, (enum jpeg_kind)k, 0, 0), "write %s", name);
        ic_image g;
        CHECK(ic_image_read(name, &g, &err) == IC_OK && g.width == W && g.height == H, "%s decodes: %s", name,
              err.message);
        int max_diff = 999, grey_rgb = g.rgb != NULL;
        double mean_diff = 999.0;
        if (g.rgb) {
            compare(&g, grey, 1, &max_diff, &mean_diff);
            for (size_t i = 0; i < (size_t)W * H; ++i)
                grey_rgb &= g.rgb[3 * i] == g.rgb[3 * i + 1] && g.rgb[3 * i] == g.rgb[3 * i + 2];
        }
        CHECK(grey_rgb, "%s: R = G = B", name);
        CHECK(max_diff <= MAX_LEVELS && mean_diff <= MEAN_LEVELS, "%s: %d levels at most, %.3f on average", name,
              max_diff, mean_diff);
        if (getenv("IC_TEST_VERBOSE"))
            printf("%s: %d levels at most, %.3f on average\n", name, max_diff, mean_diff);
        ic_image_free(&g);
    }
    for (int k = BASELINE; k <= ARITHMETIC; ++k)
        ic_image_free(&img[k]);
}

static void test_refusals(void)
{
    uint8_t rgb[W * H * 3];
    source(rgb, 3);
    ic_image img;
    ic_error err;

    /* Cut files: libjpeg would fill the missing data with grey and warn; the warning is an error. */
    const char *whole[2] = {SCRATCH "/baseline.jpg", SCRATCH "/progressive.jpg"};
    const char *cut[2] = {"cut_baseline.jpg", "cut_progressive.jpg"};
    for (int k = 0; k < 2; ++k) {
        size_t n = 0;
        unsigned char *b = slurp(whole[k], &n);
        char path[512];
        snprintf(path, sizeof path, "%s/%s", SCRATCH, cut[k]);
        for (int part = 0; part < 2; ++part) {
            size_t keep = part == 0 ? n / 2 : n - 2; /* half the file; all but its EOI */
            spill(path, b, keep);
            ic_result r = ic_image_read(path, &img, &err);
            CHECK(refused(r, IC_ERR_PARSE, &err, cut[k]) && img.rgb == NULL, "%s cut to %zu of %zu bytes: %s (%s)",
                  cut[k], keep, n, ic_result_name(r), err.message);
        }
        free(b);
    }

    /* 568 scans: refused at the 501st. */
    CHECK(write_jpeg(SCRATCH "/bit_planes.jpg", rgb, 3, BIT_PLANES, 0, 0), "write bit_planes.jpg");
    ic_result r = ic_image_read(SCRATCH "/bit_planes.jpg", &img, &err);
    CHECK(refused(r, IC_ERR_PARSE, &err, "bit_planes.jpg") && strstr(err.message, "more than 500 scans"), "%s (%s)",
          ic_result_name(r), err.message);

    /* The input on which stb_image 2.27 shifted by 32 (entropy-coded data that runs out). */
    const char *shift = IC_SOURCE_DIR "/tests/fuzz/regress/image_png/stb_grow_buffer_shift.jpg";
    r = ic_image_read(shift, &img, &err);
    CHECK(refused(r, IC_ERR_PARSE, &err, "stb_grow_buffer_shift.jpg"), "%s (%s)", ic_result_name(r), err.message);
    r = ic_image_read_ldr(shift, NULL, &img, &err);
    CHECK(refused(r, IC_ERR_PARSE, &err, "stb_grow_buffer_shift.jpg"), "%s (%s)", ic_result_name(r), err.message);

    /* The Huffman table of 257 codes on which stb_image 2.27 wrote past its arrays (libjpeg stops at damage
     * before it), and the first table of the baseline file made to declare 257 codes (T.81 §B.2.4.2 allows
     * 256): libjpeg refuses the table. */
    const char *dht = IC_SOURCE_DIR "/tests/fuzz/regress/image_png/stb_build_huffman_oob.jpg";
    r = ic_image_read(dht, &img, &err);
    CHECK(refused(r, IC_ERR_PARSE, &err, "stb_build_huffman_oob.jpg"), "%s (%s)", ic_result_name(r), err.message);
    size_t n = 0;
    unsigned char *b = slurp(SCRATCH "/baseline.jpg", &n);
    size_t at = 2;
    while (at + 21 < n && !(b[at] == 0xFF && b[at + 1] == 0xC4))
        at += 2 + ((size_t)b[at + 2] << 8 | b[at + 3]);
    CHECK(at + 21 < n, "the baseline file has a DHT segment");
    if (at + 21 < n) {
        b[at + 20] = 255; /* L16 of the first table (after the length and Tc/Th bytes); L15 below */
        b[at + 19] = 2;
        spill(SCRATCH "/dht257.jpg", b, n);
        r = ic_image_read(SCRATCH "/dht257.jpg", &img, &err);
        CHECK(refused(r, IC_ERR_PARSE, &err, "dht257.jpg") && strstr(err.message, "Huffman"), "%s (%s)",
              ic_result_name(r), err.message);
    }
    free(b);
    /* The same after a fill byte (FF FF D8): not a JPEG's first bytes, so not an image at all. */
    const char *filled = IC_SOURCE_DIR "/tests/fuzz/regress/image_png/stb_build_huffman_fill_bytes.jpg";
    r = ic_image_read(filled, &img, &err);
    CHECK(refused(r, IC_ERR_UNSUPPORTED, &err, "stb_build_huffman_fill_bytes.jpg"), "%s (%s)", ic_result_name(r),
          err.message);
    r = ic_image_read_ldr(filled, NULL, &img, &err);
    CHECK(refused(r, IC_ERR_PARSE, &err, "stb_build_huffman_fill_bytes.jpg"), "%s (%s)", ic_result_name(r),
          err.message);

    /* A header claiming 40000x40000 (its SOF0 patched) is refused by the pixel limit, and 65000x65000 by
     * the library's own, from the header: the image is never allocated. */
    b = slurp(SCRATCH "/baseline.jpg", &n);
    size_t sof = 2;
    while (sof + 9 < n && !(b[sof] == 0xFF && b[sof + 1] == 0xC0))
        sof += 2 + ((size_t)b[sof + 2] << 8 | b[sof + 3]);
    CHECK(sof + 9 < n, "the baseline file has an SOF0 segment");
    if (sof + 9 < n) {
        b[sof + 5] = 40000 >> 8; /* height */
        b[sof + 6] = 40000 & 255;
        b[sof + 7] = 40000 >> 8; /* width */
        b[sof + 8] = 40000 & 255;
        spill(SCRATCH "/huge.jpg", b, n);
        r = ic_image_read_max(SCRATCH "/huge.jpg", (size_t)1 << 20, "raise the limit", &img, &err);
        CHECK(refused(r, IC_ERR_UNSUPPORTED, &err, "huge.jpg") && strstr(err.message, "40000x40000") &&
                  strstr(err.message, "limit of 1048576") && strstr(err.message, "raise the limit"),
              "%s (%s)", ic_result_name(r), err.message);
        b[sof + 5] = b[sof + 7] = 65000 >> 8;
        b[sof + 6] = b[sof + 8] = 65000 & 255;
        spill(SCRATCH "/huge.jpg", b, n);
        r = ic_image_read(SCRATCH "/huge.jpg", &img, &err);
        CHECK(refused(r, IC_ERR_PARSE, &err, "huge.jpg") && strstr(err.message, "65000x65000") &&
                  strstr(err.message, "268435456 pixels"), "%s (%s)",
              ic_result_name(r), err.message);
    }
    free(b);

    /* CMYK and YCCK: refused, not converted (that needs the ink profile). */
    uint8_t cmyk[W * H * 4];
    for (size_t i = 0; i < sizeof cmyk; ++i)
        cmyk[i] = (uint8_t)(i * 7);
    for (int ycck = 0; ycck <= 1; ++ycck) {
        const char *name = ycck ? "ycck.jpg" : "cmyk.jpg";
        char path[512];
        snprintf(path, sizeof path, "%s/%s", SCRATCH, name);
        CHECK(write_jpeg(path, cmyk, 4, BASELINE, ycck, 0), "write %s", name);
        r = ic_image_read(path, &img, &err);
        CHECK(refused(r, IC_ERR_UNSUPPORTED, &err, name) && strstr(err.message, "CMYK"), "%s (%s)",
              ic_result_name(r), err.message);
    }
}

int main(void)
{
    if (mkdir(IC_TEST_TMP, 0755) != 0 && errno != EEXIST)
        perror(IC_TEST_TMP);
    if (mkdir(SCRATCH, 0755) != 0 && errno != EEXIST)
        perror(SCRATCH);
    test_decodes();
    test_refusals();
    TEST_MAIN_END();
}
