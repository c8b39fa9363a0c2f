/*
 * irrcache/image.h — images in and out, and the error metrics every quality claim uses.
 *
 * An ic_image is linear RGB float, row-major, top row first, 3 floats per pixel. Reading picks the
 * format from the file's content/extension: OpenEXR (.exr), PFM (.pfm), Radiance RGBE (.hdr), and
 * 8-bit PNG/JPEG (sRGB, converted to linear). Writing picks the format from the extension:
 * .exr (linear half/float RGB), .pfm, .hdr (linear), .png (exposure, then sRGB, clamped). Files are
 * written to a temporary name and renamed, so a failed write never leaves a partial file.
 *
 * Ownership: ic_image_create / ic_image_read allocate pixels; ic_image_free releases them
 * (ic_image_free on a zeroed image is a no-op).
 */
#ifndef IRRCACHE_IMAGE_H
#define IRRCACHE_IMAGE_H

#include "irrcache/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Linear RGB float image. */
typedef struct ic_image {
    int width, height;
    float *rgb;            /* width*height*3 floats */
} ic_image;

/* Write options; zero means default. */
/* One layer of a multi-layer OpenEXR (ic_image_write_options.layers): channels "<name>.R", ".G", ".B". */
typedef struct ic_image_layer {
    const char *name;      /* e.g. "indirect": non-empty, no '.', < 200 bytes */
    const ic_image *image; /* the same size as the image written */
} ic_image_layer;

/* One text attribute of an OpenEXR header (ic_image_write_options.meta). */
typedef struct ic_image_meta {
    const char *name;      /* attribute name, e.g. "irrcache:seed" (non-empty, < 256 bytes) */
    const char *value;     /* UTF-8 text */
} ic_image_meta;

typedef struct ic_image_write_options {
    float exposure;        /* stops applied before tone mapping LDR outputs (default 0) */
    int exr_half;          /* 1: EXR as 16-bit half (finite values clamped to ±65504, the largest finite half;
                              Inf and NaN kept), 0 (default): 32-bit float */
    const ic_image_meta *meta; /* EXR: text attributes written to the header (other formats ignore them);
                              every EXR also gets the chromaticities of its linear Rec. 709 / sRGB primaries
                              and D65 white */
    uint32_t meta_count;
    const ic_image_layer *layers; /* EXR: further images written as layers of the same file, beside its R, G,
                              B (readers that know no layers see the image alone); other formats ignore them */
    uint32_t layer_count;
} ic_image_write_options;

/* Largest image accepted anywhere (created, read, or rendered: ic_render_options.max_image_pixels can raise
 * its limit up to this one); keeps width*height*3*sizeof(float) far from overflow and stops a corrupt
 * header from asking for gigabytes. */
#define IC_IMAGE_MAX_SIDE 65536
#define IC_IMAGE_MAX_PIXELS ((size_t)1 << 28) /* 16384 x 16384 */

/* Allocates a zero-filled w×h image: IC_ERR_INVALID_ARG for a size of 0 or beyond IC_IMAGE_MAX_SIDE or
 * IC_IMAGE_MAX_PIXELS, IC_ERR_OOM when the memory is not there. */
ic_result ic_image_create(ic_image *img, int width, int height);
/* Releases pixels and zeroes the struct. */
void ic_image_free(ic_image *img);
/* Reads an image (EXR, PFM, HDR, PNG, JPEG) as linear RGB. */
ic_result ic_image_read(const char *path, ic_image *out, ic_error *err);
/* The same, refusing (IC_ERR_UNSUPPORTED) an image whose header gives more than max_pixels pixels before
 * anything is allocated for it (0: no limit but the library's own); the message ends with `raise`, what
 * to do ("raise --max-texture-pixels"; NULL: "use a smaller image"). */
ic_result ic_image_read_max(const char *path, size_t max_pixels, const char *raise, ic_image *out, ic_error *err);
/* ic_image_read_max for a texture: an 8-bit PNG or JPEG comes back as its sRGB bytes, 3 a pixel, rows top
 * first, in *srgb8 (release with free()), out then holding its width and height and no pixels; any other image
 * as ic_image_read_max reads it, *srgb8 NULL. Those bytes are what ic_image_read_max would have made linear
 * with ic_srgb8_to_linear. */
ic_result ic_image_read_texture(const char *path, size_t max_pixels, const char *raise, ic_image *out, uint8_t **srgb8,
                                ic_error *err);
/* Decodes a PNG or JPEG image held in memory (an image embedded in another file; name labels it in
 * messages), with the pixel limit of ic_image_read_max. */
ic_result ic_image_decode_memory(const void *data, size_t size, const char *name, size_t max_pixels, const char *raise,
                                 ic_image *out, ic_error *err);
/* Writes by extension (.exr .pfm .hdr .png); atomic. opt may be NULL. IC_ERR_INVALID_ARG for an EXR whose
 * layers or attributes OpenEXR refuses (a layer given twice, an attribute named like a header field of
 * another type: "channels", "compression" …). */
ic_result ic_image_write(const char *path, const ic_image *img, const ic_image_write_options *opt, ic_error *err);
/* Reads layer `layer` (channels "<layer>.R", ".G", ".B") of a multi-layer OpenEXR file as linear RGB. */
ic_result ic_image_read_layer(const char *path, const char *layer, ic_image *out, ic_error *err);
/* Reads the text attribute `name` of an OpenEXR file's first part into value (capacity cap, truncated,
 * always terminated): IC_OK, IC_ERR_INVALID_ARG when the file has no such text attribute, or the reader's
 * error for a file that is not a readable OpenEXR. */
ic_result ic_image_exr_attribute(const char *path, const char *name, char *value, size_t cap, ic_error *err);
/* Writes width×height 8-bit RGB bytes (row-major, top row first) as a PNG, as given (no curve) and tagged as sRGB
 * (its sRGB, gAMA and cHRM chunks); atomic. IC_ERR_INVALID_ARG for no bytes or a size ic_image_create refuses
 * (a side of 0 or over IC_IMAGE_MAX_SIDE…). */
ic_result ic_image_write_png8(const char *path, const uint8_t *rgb, int width, int height, ic_error *err);

/* --- false-colour maps (falsecolor.c): a grid of values as coloured cells with a legend --- */

/* The colour scale: t in [0, 1] (clamped; NaN as 0) → 8-bit sRGB, piecewise linear between six anchors,
 * dark blue (0) – blue – cyan – green – yellow – dark red (1) (docs/points.md gives them). */
void ic_falsecolor_scale(double t, uint8_t rgb[3]);

/* Layout options; zero means default. */
typedef struct ic_falsecolor_options {
    double max;            /* the value at the top of the scale [the largest value; 1 if none is > 0] */
    int cell_px;           /* pixels per cell side [480 / the larger grid side, clamped to 4–48] */
    const char *unit;      /* the legend's title, drawn in the built-in font: digits, '.', '-', '+', '/', '%', a–z, space
                              ["lux"] */
} ic_falsecolor_options;

/* Where ic_falsecolor_render put things (pixels). */
typedef struct ic_falsecolor_layout {
    int width, height;     /* the image */
    int map_x, map_y;      /* top-left corner of cell (0, 0) */
    int cell_px;           /* cell side */
    int bar_x, bar_y, bar_w, bar_h; /* the legend's colour bar: its top row is the scale's top */
    double max;            /* the scale's top value */
} ic_falsecolor_layout;

/* Renders values[row * cols + col] (row 0 at the top) as cols × rows cells coloured by
 * ic_falsecolor_scale(value / max), beside a legend: a colour bar with five labelled ticks (0, ¼, ½, ¾ and
 * the maximum, in a 3 × 5 bitmap font at twice its size) under the unit. *rgb_out (malloc'd, free() it)
 * holds layout->width × layout->height × 3 bytes on white. Fails with IC_ERR_INVALID_ARG for an empty grid
 * or a negative or non-finite max, IC_ERR_OOM. */
ic_result ic_falsecolor_render(const double *values, int cols, int rows, const ic_falsecolor_options *opt,
                               uint8_t **rgb_out, ic_falsecolor_layout *layout, ic_error *err);

/* Nonzero if the extension of path is one ic_image_write knows. */
int ic_image_is_writable_format(const char *path);

/* Linear → 8-bit sRGB of one channel value after exposure scaling (clamped). */
uint8_t ic_linear_to_srgb8(float v);
/* 8-bit sRGB → linear. */
float ic_srgb8_to_linear(uint8_t v);
/* sRGB transfer function on [0,1] (IEC 61966-2-1), both directions; values outside [0,1] are clamped,
 * NaN maps to 0. */
float ic_linear_to_srgb(float v);
float ic_srgb_to_linear(float v);

/* Error metrics of an image against a reference of the same size. */
#define IC_LOWPASS_SIGMA 2.0 /* pixels: white noise drops ~1/(4πσ²) = 1/50, a blotch of 10+ px stays */

typedef struct ic_image_metrics {
    double rmse;           /* root-mean-square error over all channels, linear HDR */
    double relmse;         /* mean of (a-r)^2 / (r^2 + 0.01) over all channels (pbrt/Rousselle convention) */
    double relmse_lowpass; /* the same after a Gaussian blur of σ = IC_LOWPASS_SIGMA pixels of both images: the
                              low-frequency error (an interpolated cache's blotches) without pixel noise */
    double psnr_hdr;       /* 10 log10(peak^2 / MSE), peak = max reference channel value, linear HDR */
    double psnr_ldr;       /* PSNR of the 8-bit sRGB images (peak 255), as Frolov et al. 2012 report */
    double ssim;           /* mean SSIM of the luma of the 8-bit sRGB images (8×8 windows, Wang et al. 2004 constants) */
    long nonfinite;        /* channel values (of img or ref) that were NaN or ±Inf; they count as 0 above */
} ic_image_metrics;

/* Compares img against ref (same size) and fills m. Identical images give rmse 0, ssim 1 and
 * psnr_* = +INFINITY. An all-zero reference uses peak 1 for psnr_hdr. */
ic_result ic_image_compare(const ic_image *img, const ic_image *ref, ic_image_metrics *m, ic_error *err);

/* False-colour map of per-pixel relative error |a-r| / (|r| + 0.01) (luma), 0 → blue … ≥ max_err → red
 * (max_err 0 = IC_DEFAULT_HEATMAP_MAX_ERROR, irrcache/defaults.h); written into out (allocated). The scale
 * is the caller's, never taken from the images, so heat maps of two images against one reference compare:
 * a pixel with the same error has the same colour in both. The colours are linear so that an sRGB output
 * (PNG) shows the ramp as designed; pixels where either image is NaN/Inf are magenta. */
ic_result ic_image_heatmap(const ic_image *img, const ic_image *ref, float max_err, ic_image *out, ic_error *err);

/* Map of the low-frequency error that relmse_lowpass measures, signed: both images blurred by the same
 * Gaussian (σ = IC_LOWPASS_SIGMA pixels), then (a − r)/(|r| + 0.01) of their luma, red where img is
 * brighter than ref and blue where it is darker, black where they agree, full colour at ±max_err and
 * beyond (0 = IC_DEFAULT_BLOTCH_MAX_ERROR). Pixel noise is blurred away, so what shows is an interpolated
 * cache's blotches and any bias. Written into out (allocated); the colours are linear, so that an sRGB
 * output shows the ramp as designed. Non-finite input values count as 0, as in the metrics. */
ic_result ic_image_blotch_map(const ic_image *img, const ic_image *ref, float max_err, ic_image *out, ic_error *err);

/* The q-quantile (q in [0, 1]) of the per-pixel relative error ic_image_heatmap shows, over the finite
 * pixels (0 if there are none): a scale fitted to one image (`irrcache diff --max-error auto` uses q = 0.99),
 * which makes that image's heat map use the whole ramp but not compare with another's. */
ic_result ic_image_heatmap_quantile(const ic_image *img, const ic_image *ref, double q, float *value, ic_error *err);

#ifdef __cplusplus
}
#endif
#endif
