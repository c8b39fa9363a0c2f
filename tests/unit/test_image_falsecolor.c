/*
 * test_image_falsecolor.c — false-colour maps (ic_falsecolor_scale, ic_falsecolor_render,
 * ic_image_write_png8; the PNG read back with ic_image_read, bytes compared through the sRGB table):
 *   1. the scale: its end anchors, a midpoint between two anchors, clamping and NaN;
 *   2. a 4 × 3 map written as PNG decodes to the layout's size; every pixel of each cell has the scale's
 *      colour for the cell's value over the maximum; the bar runs from the top colour down to the bottom
 *      one; the legend has ink (its labels) and the page is white;
 *   3. the maximum defaults to the largest value; empty grids and negative maxima are refused;
 *   4. the five tick labels tell the ticks apart at any scale, 3e-12 to 4.2e12.
 */
#include "test_util.h"

#include "irrcache/image.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int same(const uint8_t *a, const uint8_t *b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

/* A decoded (linear) pixel against 8-bit sRGB bytes. */
static int same_linear(const float *p, const uint8_t *b)
{
    for (int k = 0; k < 3; ++k)
        if (fabsf(p[k] - ic_srgb8_to_linear(b[k])) > 1e-6f)
            return 0;
    return 1;
}

static void test_scale(void)
{
    uint8_t c[3];
    ic_falsecolor_scale(0.0, c);
    CHECK(c[0] == 0 && c[1] == 0 && c[2] == 96, "0: dark blue (%d %d %d)", c[0], c[1], c[2]);
    ic_falsecolor_scale(1.0, c);
    CHECK(c[0] == 192 && c[1] == 0 && c[2] == 0, "1: dark red (%d %d %d)", c[0], c[1], c[2]);
    ic_falsecolor_scale(0.5, c);
    CHECK(c[0] == 32 && c[1] == 210 && c[2] == 100, "0.5: halfway from cyan-ish to green (%d %d %d)", c[0], c[1],
          c[2]);
    uint8_t d[3];
    ic_falsecolor_scale(-3.0, d);
    ic_falsecolor_scale(0.0, c);
    CHECK(same(c, d), "below 0 clamps");
    ic_falsecolor_scale(7.0, d);
    ic_falsecolor_scale(1.0, c);
    CHECK(same(c, d), "above 1 clamps");
    ic_falsecolor_scale(NAN, d);
    ic_falsecolor_scale(0.0, c);
    CHECK(same(c, d), "NaN as 0");
}

static void test_map(void)
{
    enum { COLS = 4, ROWS = 3 };
    double v[COLS * ROWS];
    for (int k = 0; k < COLS * ROWS; ++k)
        v[k] = 37.5 * k; /* 0 … 412.5, above the scale's 400 at the end */
    ic_falsecolor_options opt = {0};
    opt.max = 400.0;
    uint8_t *rgb = NULL;
    ic_falsecolor_layout lay;
    ic_error err = {0};
    CHECK(ic_falsecolor_render(v, COLS, ROWS, &opt, &rgb, &lay, &err) == IC_OK, "renders: %s", err.message);
    if (!rgb)
        return;
    const char *path = IC_TEST_TMP "/falsecolor.png";
    CHECK(ic_image_write_png8(path, rgb, lay.width, lay.height, &err) == IC_OK, "writes: %s", err.message);
    free(rgb);
    ic_image img = {0};
    CHECK(ic_image_read(path, &img, &err) == IC_OK, "decodes: %s", err.message);
    int w = img.width, h = img.height;
    const float *png = img.rgb;
    CHECK(png && w == lay.width && h == lay.height, "decodes at the layout's %d x %d (%d x %d)", lay.width,
          lay.height, w, h);
    if (!png)
        return;
    CHECK(lay.cell_px == 48 && lay.max == 400.0, "cells of 480/4 clamped to 48 px, max as given");
    int bad = 0;
    for (int r = 0; r < ROWS; ++r)
        for (int c = 0; c < COLS; ++c) {
            uint8_t want[3];
            ic_falsecolor_scale(v[r * COLS + c] / 400.0, want);
            for (int y = 0; y < lay.cell_px; ++y)
                for (int x = 0; x < lay.cell_px; ++x) {
                    const float *p = png + 3 * ((size_t)(lay.map_y + r * lay.cell_px + y) * w +
                                                (size_t)(lay.map_x + c * lay.cell_px + x));
                    bad += !same_linear(p, want);
                }
        }
    CHECK(bad == 0, "every cell pixel has its value's colour (%d differ)", bad);
    uint8_t top[3], bottom[3];
    ic_falsecolor_scale(1.0 - 0.5 / lay.bar_h, top);
    ic_falsecolor_scale(0.5 / lay.bar_h, bottom);
    const float *pt = png + 3 * ((size_t)lay.bar_y * w + (size_t)lay.bar_x + 2);
    const float *pb = png + 3 * ((size_t)(lay.bar_y + lay.bar_h - 1) * w + (size_t)lay.bar_x + 2);
    CHECK(same_linear(pt, top) && same_linear(pb, bottom), "the bar: the scale's top at the top, its bottom at the bottom");
    int ink = 0;
    for (int y = 0; y < h; ++y)
        for (int x = lay.bar_x + lay.bar_w + 1; x < w; ++x) {
            const float *p = png + 3 * ((size_t)y * w + (size_t)x);
            ink += p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f;
        }
    CHECK(ink > 100, "labels are drawn (%d ink pixels)", ink);
    CHECK(png[0] == 1.0f && png[1] == 1.0f && png[2] == 1.0f, "white page");
    ic_image_free(&img);
}

static void test_defaults_and_errors(void)
{
    double v[2] = {3.0, 12.0};
    uint8_t *rgb = NULL;
    ic_falsecolor_layout lay;
    ic_error err = {0};
    CHECK(ic_falsecolor_render(v, 2, 1, NULL, &rgb, &lay, &err) == IC_OK && lay.max == 12.0,
          "max defaults to the largest value");
    free(rgb);
    ic_falsecolor_options opt = {0};
    opt.max = -1.0;
    CHECK(ic_falsecolor_render(v, 2, 1, &opt, &rgb, &lay, &err) == IC_ERR_INVALID_ARG && !rgb, "negative max refused");
    CHECK(ic_falsecolor_render(v, 0, 1, NULL, &rgb, &lay, &err) == IC_ERR_INVALID_ARG && !rgb, "empty grid refused");
}

/* The five tick labels differ from each other whatever the scale's top (a scale to 0.0004 once read 0.000 at
 * every tick): each label's band of rows beside its tick, compared pixel by pixel. */
static void test_labels(void)
{
    const double tops[] = {0.0004, 4e-6, 3e-12, 0.037, 0.7, 7.5, 75.0, 750.0, 4.2e12};
    for (size_t t = 0; t < sizeof tops / sizeof tops[0]; ++t) {
        double v[2] = {0.0, tops[t]};
        uint8_t *rgb = NULL;
        ic_falsecolor_layout lay;
        ic_error err = {0};
        if (ic_falsecolor_render(v, 2, 1, NULL, &rgb, &lay, &err) != IC_OK) {
            CHECK(0, "top %g: %s", tops[t], err.message);
            continue;
        }
        const int x0 = lay.bar_x + lay.bar_w + 5, band = 10; /* past the tick; the glyphs' height */
        int y[5], ink[5] = {0}, same = 0;
        for (int k = 0; k < 5; ++k)
            y[k] = lay.bar_y + (int)lround((1.0 - k / 4.0) * (lay.bar_h - 1)) - band / 2;
        for (int k = 0; k < 5; ++k)
            for (int r = 0; r < band; ++r)
                for (int x = x0; x < lay.width; ++x)
                    ink[k] += rgb[3 * ((size_t)(y[k] + r) * (size_t)lay.width + (size_t)x)] == 0;
        for (int a = 0; a < 5; ++a)
            for (int b = a + 1; b < 5; ++b) {
                int differ = 0;
                for (int r = 0; r < band && !differ; ++r)
                    differ = memcmp(rgb + 3 * ((size_t)(y[a] + r) * (size_t)lay.width + (size_t)x0),
                                    rgb + 3 * ((size_t)(y[b] + r) * (size_t)lay.width + (size_t)x0),
                                    3 * (size_t)(lay.width - x0)) != 0;
                same += !differ;
            }
        CHECK(same == 0 && ink[0] > 0 && ink[4] > 0, "top %g: the five labels differ (%d pairs alike)", tops[t], same);
        free(rgb);
    }
}

int main(void)
{
    test_labels();
    test_scale();
    test_map();
    test_defaults_and_errors();
    TEST_MAIN_END();
}
