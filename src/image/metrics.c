/*
 * metrics.c — error metrics of an image against a reference, and false-colour error maps
 * (include/irrcache/image.h).
 *
 * HDR metrics (RMSE, relMSE as in pbrt / Rousselle et al. 2011, PSNR with the reference's peak) are
 * computed on linear values in double precision. LDR metrics use the 8-bit sRGB images that a PNG
 * would hold, because that is what Frolov et al. 2012 report (§1 and Table 2: PSNR ≈ 40 dB): PSNR with
 * peak 255, and SSIM (Wang, Bovik, Sheikh, Simoncelli 2004, "Image quality assessment: from error
 * visibility to structural similarity") on the luma 0.299 R' + 0.587 G' + 0.114 B' of those images,
 * with uniform 8×8 windows moved one pixel at a time (the paper's §III-B variant), population
 * (1/N) statistics and C1 = (0.01·255)², C2 = (0.03·255)²; the result is the mean over all windows.
 *
 * NaN and ±Inf values are counted in ic_image_metrics.nonfinite and treated as 0, so every metric
 * stays finite (a NaN pixel in a render then shows up as error against a bright reference).
 */
#include "irrcache/image.h"

#include "irrcache/defaults.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Relative-error denominators: keep dark pixels from dominating (pbrt's relMSE convention). */
#define RELMSE_EPSILON 0.01
#define HEATMAP_EPSILON 0.01f
#define SSIM_WINDOW 8
#define LOWPASS_RADIUS 6 /* 3 σ of IC_LOWPASS_SIGMA, in pixels */

static float finite_or_zero(float v, long *nonfinite)
{
    if (isfinite(v))
        return v;
    ++*nonfinite;
    return 0.0f;
}

/* Luma of an 8-bit sRGB pixel (Rec. 601 weights on gamma-encoded values, as SSIM is usually run). */
static float srgb8_luma(const uint8_t *p)
{
    return 0.299f * (float)p[0] + 0.587f * (float)p[1] + 0.114f * (float)p[2];
}

/* Mean SSIM of two luma images (w×h, values 0..255) over all SSIM_WINDOW² windows (smaller if the
 * image is). Window sums come from running column sums, so memory is O(w) beyond the inputs. */
static ic_result mean_ssim(const float *x, const float *y, int w, int h, double *out)
{
    const int wx = w < SSIM_WINDOW ? w : SSIM_WINDOW, wy = h < SSIM_WINDOW ? h : SSIM_WINDOW;
    const double n = (double)wx * (double)wy;
    const double c1 = (0.01 * 255.0) * (0.01 * 255.0), c2 = (0.03 * 255.0) * (0.03 * 255.0);
    /* Column sums over the current band of wy rows, per quantity: Σx, Σy, Σx², Σy², Σxy. */
    enum { SX, SY, SXX, SYY, SXY, QUANTITIES };
    double *col = calloc((size_t)w * QUANTITIES, sizeof *col);
    if (!col)
        return IC_ERR_OOM;

    double total = 0.0;
    long windows = 0;
    for (int row = 0; row < h; ++row) {
        /* Add the new row to the band and drop the one that left it. */
        for (int k = 0; k < 2; ++k) {
            const int r = k == 0 ? row : row - wy;
            if (r < 0)
                continue;
            const double sign = k == 0 ? 1.0 : -1.0;
            const float *xr = x + (size_t)r * (size_t)w, *yr = y + (size_t)r * (size_t)w;
            for (int i = 0; i < w; ++i) {
                const double a = xr[i], b = yr[i];
                double *c = col + (size_t)i * QUANTITIES;
                c[SX] += sign * a;
                c[SY] += sign * b;
                c[SXX] += sign * a * a;
                c[SYY] += sign * b * b;
                c[SXY] += sign * a * b;
            }
        }
        if (row < wy - 1)
            continue;
        /* Slide the window along the band. */
        double s[QUANTITIES] = {0};
        for (int i = 0; i < w; ++i) {
            for (int q = 0; q < QUANTITIES; ++q) {
                s[q] += col[(size_t)i * QUANTITIES + (size_t)q];
                if (i >= wx)
                    s[q] -= col[(size_t)(i - wx) * QUANTITIES + (size_t)q];
            }
            if (i < wx - 1)
                continue;
            const double mx = s[SX] / n, my = s[SY] / n;
            const double vx = fmax(s[SXX] / n - mx * mx, 0.0), vy = fmax(s[SYY] / n - my * my, 0.0);
            const double cov = s[SXY] / n - mx * my;
            total += ((2.0 * mx * my + c1) * (2.0 * cov + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
            ++windows;
        }
    }
    free(col);
    *out = windows > 0 ? total / (double)windows : 1.0;
    return IC_OK;
}

/* Separable Gaussian of σ = IC_LOWPASS_SIGMA (radius 3σ, edges clamped) of an RGB image into out;
 * tmp holds one image. Non-finite values count as 0, as in the other metrics. */
static void gaussian_blur(const float *in, int w, int h, float *tmp, float *out)
{
#define R LOWPASS_RADIUS
    float k[2 * R + 1], sum = 0.0f;
    for (int i = -R; i <= R; ++i)
        sum += k[i + R] = (float)exp(-0.5 * (double)(i * i) / (IC_LOWPASS_SIGMA * IC_LOWPASS_SIGMA));
    for (int i = 0; i <= 2 * R; ++i)
        k[i] /= sum;
    long ignored = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                float acc = 0.0f;
                for (int i = -R; i <= R; ++i) {
                    int xx = x + i < 0 ? 0 : x + i >= w ? w - 1 : x + i;
                    acc += k[i + R] * finite_or_zero(in[3 * ((size_t)y * w + xx) + c], &ignored);
                }
                tmp[3 * ((size_t)y * w + x) + c] = acc;
            }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                float acc = 0.0f;
                for (int i = -R; i <= R; ++i) {
                    int yy = y + i < 0 ? 0 : y + i >= h ? h - 1 : y + i;
                    acc += k[i + R] * tmp[3 * ((size_t)yy * w + x) + c];
                }
                out[3 * ((size_t)y * w + x) + c] = acc;
            }
#undef R
}

/* relMSE of the blurred images (ic_image_metrics.relmse_lowpass); returns IC_ERR_OOM if out of memory. */
static ic_result lowpass_relmse(const ic_image *img, const ic_image *ref, double *out)
{
    size_t count = 3 * (size_t)img->width * (size_t)img->height;
    float *buf = malloc(sizeof *buf * count * 3);
    if (!buf)
        return IC_ERR_OOM;
    float *a = buf, *b = buf + count, *tmp = buf + 2 * count;
    gaussian_blur(img->rgb, img->width, img->height, tmp, a);
    gaussian_blur(ref->rgb, ref->width, ref->height, tmp, b);
    double sum = 0.0;
    for (size_t i = 0; i < count; ++i) {
        double d = (double)a[i] - (double)b[i];
        sum += d * d / ((double)b[i] * (double)b[i] + RELMSE_EPSILON);
    }
    free(buf);
    *out = sum / (double)count;
    return IC_OK;
}

static ic_result check_pair(const ic_image *img, const ic_image *ref, ic_error *err)
{
    if (!img || !ref || !img->rgb || !ref->rgb || img->width <= 0 || img->height <= 0)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "image comparison needs two non-empty images");
    if (img->width != ref->width || img->height != ref->height)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "image is %dx%d but the reference is %dx%d; compare images of the same size", img->width,
                            img->height, ref->width, ref->height);
    return IC_OK;
}

ic_result ic_image_compare(const ic_image *img, const ic_image *ref, ic_image_metrics *m, ic_error *err)
{
    ic_result r = check_pair(img, ref, err);
    if (r != IC_OK)
        return r;
    if (!m)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "image comparison: no metrics to fill");
    memset(m, 0, sizeof *m);
    const size_t pixels = (size_t)img->width * (size_t)img->height, count = pixels * 3;

    uint8_t *ldr = malloc(count * 2);
    float *luma = malloc(pixels * 2 * sizeof *luma);
    if (!ldr || !luma) {
        free(ldr);
        free(luma);
        return ic_error_set(err, IC_ERR_OOM, "out of memory comparing %dx%d images", img->width, img->height);
    }
    uint8_t *ldr_img = ldr, *ldr_ref = ldr + count;

    double sum_sq = 0.0, sum_rel = 0.0, sum_sq_ldr = 0.0, peak = 0.0;
    for (size_t i = 0; i < count; ++i) {
        float a = finite_or_zero(img->rgb[i], &m->nonfinite), b = finite_or_zero(ref->rgb[i], &m->nonfinite);
        double d = (double)a - (double)b;
        sum_sq += d * d;
        sum_rel += d * d / ((double)b * (double)b + RELMSE_EPSILON);
        peak = fmax(peak, (double)b);
        ldr_img[i] = ic_linear_to_srgb8(a);
        ldr_ref[i] = ic_linear_to_srgb8(b);
        double d8 = (double)ldr_img[i] - (double)ldr_ref[i];
        sum_sq_ldr += d8 * d8;
    }
    const double mse = sum_sq / (double)count, mse_ldr = sum_sq_ldr / (double)count;
    if (peak <= 0.0)
        peak = 1.0; /* all-black reference: the nominal white */
    m->rmse = sqrt(mse);
    m->relmse = sum_rel / (double)count;
    m->psnr_hdr = mse > 0.0 ? 10.0 * log10(peak * peak / mse) : INFINITY;
    m->psnr_ldr = mse_ldr > 0.0 ? 10.0 * log10(255.0 * 255.0 / mse_ldr) : INFINITY;

    for (size_t p = 0; p < pixels; ++p) {
        luma[p] = srgb8_luma(ldr_img + 3 * p);
        luma[pixels + p] = srgb8_luma(ldr_ref + 3 * p);
    }
    r = mean_ssim(luma, luma + pixels, img->width, img->height, &m->ssim);
    if (r == IC_OK)
        r = lowpass_relmse(img, ref, &m->relmse_lowpass);
    free(ldr);
    free(luma);
    if (r != IC_OK)
        return ic_error_set(err, r, "out of memory comparing %dx%d images", img->width, img->height);
    return IC_OK;
}

/* ---------------------------------------------------------------------------------------------- */
/* Heat map                                                                                       */

/* A perceptually ordered blue → cyan → green → yellow → red ramp (shaped like Google's "Turbo"),
 * as sRGB display values at evenly spaced stops. */
static void ramp_srgb(float t, float rgb[3])
{
    static const float stops[9][3] = {
        {0.19f, 0.07f, 0.23f}, {0.27f, 0.42f, 0.89f}, {0.16f, 0.73f, 0.93f}, {0.10f, 0.93f, 0.65f},
        {0.49f, 0.99f, 0.31f}, {0.85f, 0.87f, 0.21f}, {0.98f, 0.55f, 0.14f}, {0.87f, 0.25f, 0.04f},
        {0.48f, 0.02f, 0.01f},
    };
    float u = t * 8.0f;
    int i = (int)u;
    if (i >= 8)
        i = 7;
    float f = u - (float)i;
    for (int c = 0; c < 3; ++c)
        rgb[c] = stops[i][c] + (stops[i + 1][c] - stops[i][c]) * f;
}

static float linear_luma(const float *p)
{
    return 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Per-pixel relative luma error, NaN where either pixel holds NaN/Inf. */
static float relative_error(const ic_image *img, const ic_image *ref, size_t p)
{
    float a = linear_luma(img->rgb + 3 * p), b = linear_luma(ref->rgb + 3 * p);
    return fabsf(a - b) / (fabsf(b) + HEATMAP_EPSILON);
}

ic_result ic_image_heatmap_quantile(const ic_image *img, const ic_image *ref, double q, float *value, ic_error *err)
{
    if (value)
        *value = 0.0f;
    ic_result r = check_pair(img, ref, err);
    if (r != IC_OK)
        return r;
    if (!value || !(q >= 0.0 && q <= 1.0))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "heat map: the quantile must be in [0, 1]");
    const size_t pixels = (size_t)img->width * (size_t)img->height;
    float *sorted = malloc(pixels * sizeof *sorted);
    if (!sorted)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for a %dx%d heat map", img->width, img->height);
    size_t finite = 0;
    for (size_t p = 0; p < pixels; ++p) {
        float e = relative_error(img, ref, p);
        if (isfinite(e))
            sorted[finite++] = e;
    }
    if (finite > 0) {
        qsort(sorted, finite, sizeof *sorted, compare_floats);
        *value = sorted[(size_t)(q * (double)(finite - 1))];
    }
    free(sorted);
    return IC_OK;
}

/* What a false-colour map of img against ref (a heat map, a blotch map) checks first: the pair, the output
 * and its scale *max_err (finite, ≥ 0; 0 becomes the default def). */
static ic_result map_arguments(const ic_image *img, const ic_image *ref, float *max_err, float def, ic_image *out,
                               const char *what, ic_error *err)
{
    if (out)
        memset(out, 0, sizeof *out);
    ic_result r = check_pair(img, ref, err);
    if (r != IC_OK)
        return r;
    if (!out || !(*max_err >= 0.0f) || !isfinite(*max_err)) /* also NaN */
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: maximum error must be finite and >= 0 (0 = the default %g)",
                            what, (double)def);
    if (*max_err == 0.0f)
        *max_err = def;
    return IC_OK;
}

ic_result ic_image_blotch_map(const ic_image *img, const ic_image *ref, float max_err, ic_image *out, ic_error *err)
{
    ic_result r = map_arguments(img, ref, &max_err, IC_DEFAULT_BLOTCH_MAX_ERROR, out, "blotch map", err);
    if (r != IC_OK)
        return r;
    const size_t pixels = (size_t)img->width * (size_t)img->height, count = 3 * pixels;
    float *buf = malloc(sizeof *buf * count * 3);
    r = buf ? ic_image_create(out, img->width, img->height) : IC_ERR_OOM;
    if (r != IC_OK) {
        free(buf);
        return ic_error_set(err, r, "out of memory for a %dx%d blotch map", img->width, img->height);
    }
    float *a = buf, *b = buf + count, *tmp = buf + 2 * count;
    gaussian_blur(img->rgb, img->width, img->height, tmp, a);
    gaussian_blur(ref->rgb, ref->width, ref->height, tmp, b);
    for (size_t p = 0; p < pixels; ++p) {
        float ya = linear_luma(a + 3 * p), yb = linear_luma(b + 3 * p);
        float t = fminf(fabsf(ya - yb) / (fabsf(yb) + HEATMAP_EPSILON) / max_err, 1.0f);
        float *dst = out->rgb + 3 * p;
        dst[0] = ya > yb ? ic_srgb_to_linear(t) : 0.0f;
        dst[1] = 0.0f;
        dst[2] = ya < yb ? ic_srgb_to_linear(t) : 0.0f;
    }
    free(buf);
    return IC_OK;
}

ic_result ic_image_heatmap(const ic_image *img, const ic_image *ref, float max_err, ic_image *out, ic_error *err)
{
    ic_result r = map_arguments(img, ref, &max_err, IC_DEFAULT_HEATMAP_MAX_ERROR, out, "heat map", err);
    if (r != IC_OK)
        return r;
    r = ic_image_create(out, img->width, img->height);
    if (r != IC_OK)
        return ic_error_set(err, r, "out of memory for a %dx%d heat map", img->width, img->height);
    const size_t pixels = (size_t)img->width * (size_t)img->height;
    for (size_t p = 0; p < pixels; ++p) {
        float *dst = out->rgb + 3 * p, e = relative_error(img, ref, p);
        if (!isfinite(e)) {
            dst[0] = 1.0f; /* magenta: NaN/Inf in an input */
            dst[1] = 0.0f;
            dst[2] = 1.0f;
            continue;
        }
        float t = fminf(e / max_err, 1.0f), display[3];
        ramp_srgb(t, display);
        for (int c = 0; c < 3; ++c)
            dst[c] = ic_srgb_to_linear(display[c]);
    }
    return IC_OK;
}
