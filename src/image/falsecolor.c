/*
 * falsecolor.c — false-colour maps of a grid of values (a work plane's illuminance, as lighting designers
 * read them and as Radiance's falsecolor draws them): one coloured square per cell and a legend, a colour
 * bar with labelled ticks in a built-in 3 × 5 bitmap font, so that no font library is needed.
 */
#include "image_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The scale's anchors: t and its sRGB colour; linear in between. Dark ends so that both extremes read
 * against the white page. */
static const struct {
    double t;
    uint8_t rgb[3];
} anchors[] = {{0.0, {0, 0, 96}},     {0.2, {0, 64, 255}},  {0.4, {0, 200, 200}},
               {0.6, {64, 220, 0}},   {0.8, {255, 200, 0}}, {1.0, {192, 0, 0}}};
#define ANCHOR_COUNT (sizeof anchors / sizeof anchors[0])

void ic_falsecolor_scale(double t, uint8_t rgb[3])
{
    if (!(t > 0.0))
        t = 0.0; /* NaN too */
    if (t > 1.0)
        t = 1.0;
    size_t k = 0;
    while (k + 2 < ANCHOR_COUNT && t > anchors[k + 1].t)
        ++k;
    double f = (t - anchors[k].t) / (anchors[k + 1].t - anchors[k].t);
    for (int c = 0; c < 3; ++c)
        rgb[c] = (uint8_t)lround(anchors[k].rgb[c] + f * (anchors[k + 1].rgb[c] - anchors[k].rgb[c]));
}

/* ------------------------------------------------------------------------------------------------ */
/* the font: each glyph 5 rows of 3 pixels, row 0 in the top bits, the leftmost pixel the row's high bit */

#define G(a, b, c, d, e) (unsigned short)(((a) << 12) | ((b) << 9) | ((c) << 6) | ((d) << 3) | (e))

static unsigned short glyph(char ch)
{
    static const unsigned short digits[10] = {
        G(7, 5, 5, 5, 7), G(2, 6, 2, 2, 7), G(7, 1, 7, 4, 7), G(7, 1, 7, 1, 7), G(5, 5, 7, 1, 1),
        G(7, 4, 7, 1, 7), G(7, 4, 7, 5, 7), G(7, 1, 1, 1, 1), G(7, 5, 7, 5, 7), G(7, 5, 7, 1, 7)};
    static const unsigned short letters[26] = {
        G(2, 5, 7, 5, 5), G(6, 5, 6, 5, 6), G(3, 4, 4, 4, 3), G(6, 5, 5, 5, 6), G(7, 4, 6, 4, 7), /* a–e */
        G(7, 4, 6, 4, 4), G(3, 4, 5, 5, 3), G(5, 5, 7, 5, 5), G(7, 2, 2, 2, 7), G(1, 1, 1, 5, 2), /* f–j */
        G(5, 5, 6, 5, 5), G(4, 4, 4, 4, 7), G(5, 7, 7, 5, 5), G(6, 5, 5, 5, 5), G(2, 5, 5, 5, 2), /* k–o */
        G(6, 5, 6, 4, 4), G(2, 5, 5, 6, 3), G(6, 5, 6, 5, 5), G(3, 4, 2, 1, 6), G(7, 2, 2, 2, 2), /* p–t */
        G(5, 5, 5, 5, 7), G(5, 5, 5, 5, 2), G(5, 5, 7, 7, 5), G(5, 5, 2, 5, 5), G(5, 5, 2, 2, 2), /* u–y */
        G(7, 1, 2, 4, 7)};                                                                         /* z */
    if (ch >= '0' && ch <= '9')
        return digits[ch - '0'];
    if (ch >= 'a' && ch <= 'z')
        return letters[ch - 'a'];
    if (ch >= 'A' && ch <= 'Z')
        return letters[ch - 'A'];
    switch (ch) {
    case '.':
        return G(0, 0, 0, 0, 2);
    case '-':
        return G(0, 0, 7, 0, 0);
    case '+':
        return G(0, 2, 7, 2, 0);
    case '/':
        return G(1, 1, 2, 4, 4);
    case '%':
        return G(5, 1, 2, 4, 5);
    default:
        return 0; /* space and anything else: blank */
    }
}

#define FONT_SCALE 2                     /* each font pixel drawn as 2 × 2 */
#define GLYPH_W (3 * FONT_SCALE)
#define GLYPH_H (5 * FONT_SCALE)
#define ADVANCE (GLYPH_W + FONT_SCALE)   /* one font pixel between glyphs */
#define LABEL_GAP 12                     /* from the bar to its labels: a 4-pixel tick, then space */

typedef struct canvas {
    uint8_t *rgb;
    int w, h;
} canvas;

static void put(canvas *cv, int x, int y, const uint8_t c[3])
{
    if (x < 0 || y < 0 || x >= cv->w || y >= cv->h)
        return;
    memcpy(cv->rgb + 3 * ((size_t)y * (size_t)cv->w + (size_t)x), c, 3);
}

static void fill(canvas *cv, int x0, int y0, int w, int h, const uint8_t c[3])
{
    for (int y = y0; y < y0 + h; ++y)
        for (int x = x0; x < x0 + w; ++x)
            put(cv, x, y, c);
}

static void text(canvas *cv, int x, int y, const char *s)
{
    static const uint8_t ink[3] = {0, 0, 0};
    for (; *s; ++s, x += ADVANCE) {
        unsigned short g = glyph(*s);
        for (int r = 0; r < 5; ++r)
            for (int c = 0; c < 3; ++c)
                if (g >> (3 * (4 - r) + (2 - c)) & 1)
                    fill(cv, x + c * FONT_SCALE, y + r * FONT_SCALE, FONT_SCALE, FONT_SCALE, ink);
    }
}

/* A tick's label: as many decimals as the scale needs to tell five ticks apart, the top's leading digit and
 * two more (below 1 the labels once kept three decimals, so a scale to 0.0004 read 0.000 at every tick);
 * below 10^-4 and from 10^9 on, three significant digits in exponent form, which stay short. */
static void label(double v, double max, char *out, size_t size)
{
    if (max < 1e-4 || max >= 1e9) {
        snprintf(out, size, "%.3g", v);
        return;
    }
    int lead = (int)floor(log10(max)); /* the place of the top's leading digit */
    snprintf(out, size, "%.*f", lead >= 2 ? 0 : 2 - lead, v);
}

ic_result ic_falsecolor_render(const double *values, int cols, int rows, const ic_falsecolor_options *opt,
                               uint8_t **rgb_out, ic_falsecolor_layout *lay, ic_error *err)
{
    *rgb_out = NULL;
    if (!values || cols <= 0 || rows <= 0 || cols > 100000 || rows > 100000)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "false-colour map: an empty or too large grid (%d x %d)", cols,
                            rows);
    double max = opt ? opt->max : 0.0;
    if (!(max >= 0.0) || !isfinite(max))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "false-colour map: the scale's maximum %g must be >= 0 and finite",
                            max);
    if (max == 0.0) {
        for (size_t i = 0; i < (size_t)cols * (size_t)rows; ++i)
            if (isfinite(values[i]) && values[i] > max)
                max = values[i];
        if (max == 0.0)
            max = 1.0;
    }
    const char *unit = opt && opt->unit ? opt->unit : "lux";
    int longest = (int)strlen(unit);
    char labels[5][32];
    for (int k = 0; k < 5; ++k) {
        label(max * k / 4.0, max, labels[k], sizeof labels[k]);
        int n = (int)strlen(labels[k]);
        longest = n > longest ? n : longest;
    }
    const int margin = 10, big = cols > rows ? cols : rows;
    int cell = opt && opt->cell_px > 0 ? opt->cell_px : 480 / big;
    cell = cell < 4 ? 4 : cell > 48 ? 48 : cell;
    memset(lay, 0, sizeof *lay);
    lay->cell_px = cell;
    lay->max = max;
    lay->map_x = margin;
    lay->map_y = margin + GLYPH_H + 6; /* under the unit's row */
    long map_w = (long)cols * cell, map_h = (long)rows * cell;
    if (map_w > 16384 || map_h > 16384)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "false-colour map: %ld x %ld pixels is too large; give fewer cells or a smaller cell size",
                            map_w, map_h);
    lay->bar_x = margin + (int)map_w + 20;
    lay->bar_y = lay->map_y;
    lay->bar_w = 16;
    lay->bar_h = map_h > 150 ? (int)map_h : 150;
    lay->width = lay->bar_x + lay->bar_w + LABEL_GAP + longest * ADVANCE + margin;
    lay->height = lay->map_y + (map_h > lay->bar_h ? (int)map_h : lay->bar_h) + GLYPH_H / 2 + margin;
    canvas cv = {malloc((size_t)lay->width * (size_t)lay->height * 3), lay->width, lay->height};
    if (!cv.rgb)
        return ic_error_set(err, IC_ERR_OOM, "false-colour map: out of memory for %d x %d pixels", lay->width,
                            lay->height);
    memset(cv.rgb, 255, (size_t)lay->width * (size_t)lay->height * 3);
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) {
            uint8_t col[3];
            ic_falsecolor_scale(values[(size_t)r * (size_t)cols + (size_t)c] / max, col);
            fill(&cv, lay->map_x + c * cell, lay->map_y + r * cell, cell, cell, col);
        }
    for (int y = 0; y < lay->bar_h; ++y) {
        uint8_t col[3];
        ic_falsecolor_scale(1.0 - (y + 0.5) / lay->bar_h, col);
        fill(&cv, lay->bar_x, lay->bar_y + y, lay->bar_w, 1, col);
    }
    static const uint8_t ink[3] = {0, 0, 0};
    text(&cv, lay->bar_x, margin, unit);
    for (int k = 0; k < 5; ++k) {
        int y = lay->bar_y + (int)lround((1.0 - k / 4.0) * (lay->bar_h - 1));
        fill(&cv, lay->bar_x + lay->bar_w, y, 4, 1, ink);
        text(&cv, lay->bar_x + lay->bar_w + LABEL_GAP, y - GLYPH_H / 2, labels[k]);
    }
    *rgb_out = cv.rgb;
    return IC_OK;
}
