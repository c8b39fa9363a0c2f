/*
 * rgbe.c — Radiance RGBE (.hdr) read and write.
 *
 * Ward's shared-exponent encoding (Graphics Gems II, "Real Pixels"): each pixel is three 8-bit
 * mantissas and one exponent taken from the largest channel, so every channel is stored to within
 * 1/128 of the pixel's largest channel. Scanlines are written flat (not run-length encoded), which
 * every reader accepts: a flat pixel can never look like the RLE marker (2, 2, <128) because the
 * largest mantissa is always ≥ 128. Negative, NaN and infinite values are written as 0 (as the
 * metrics count them), values above 1e38 as 1e38. The header names the pixels' primaries (PRIMARIES=).
 *
 * The reader (ours rather than stb_image's, so that a truncated or corrupt file is an error instead of
 * black rows) accepts flat, old-style and new-style run-length encoded scanlines, the standard
 * "-Y height +X width" orientation, and divides by the header's cumulative EXPOSURE so values are
 * the radiance the file describes. XYZE files and other orientations are refused. Header lines may be of
 * any length (command histories); a FORMAT= or EXPOSURE= line too long to read whole is refused.
 */
#include "image_internal.h"
#include "core/read_file.h"

#include "core/atomic_file.h"

#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The primaries and white of the pixels (ITU-R BT.709, D65, as the EXR outputs' chromaticities say), in the
 * header line Radiance's tools read (ra_xyze, pcond): without it a picture is taken to be in Radiance's own
 * standard primaries, whose green (0.290, 0.600) and equal-energy white (1/3, 1/3) are not sRGB's. */
#define RGBE_PRIMARIES "PRIMARIES= 0.6400 0.3300 0.3000 0.6000 0.1500 0.0600 0.3127 0.3290"

/* Largest value written; keeps the exponent byte (e + 128) within 255. */
#define RGBE_MAX 1e38f

static float rgbe_clamp(float v)
{
    if (!(v > 0.0f) || isinf(v)) /* negative, zero, NaN or infinite */
        return 0.0f;
    return v > RGBE_MAX ? RGBE_MAX : v;
}

static void encode_rgbe(const float rgb[3], unsigned char out[4])
{
    float r = rgbe_clamp(rgb[0]), g = rgbe_clamp(rgb[1]), b = rgbe_clamp(rgb[2]);
    float v = fmaxf(r, fmaxf(g, b));
    if (v < 1e-32f) {
        out[0] = out[1] = out[2] = out[3] = 0;
        return;
    }
    int e;
    /* v = m * 2^e with m in [0.5, 1): v * (256 / 2^e) lies in [128, 256). Truncation as in Radiance,
     * whose reader adds half a unit back. */
    float scale = (float)(frexp((double)v, &e) * 256.0 / (double)v);
    out[0] = (unsigned char)fminf(r * scale, 255.0f);
    out[1] = (unsigned char)fminf(g * scale, 255.0f);
    out[2] = (unsigned char)fminf(b * scale, 255.0f);
    out[3] = (unsigned char)(e + 128);
}

ic_result ic_image_write_hdr(const char *path, const ic_image *img, ic_error *err)
{
    ic_atomic_file f;
    ic_result r = ic_atomic_file_open(&f, path, err);
    if (r != IC_OK)
        return r;
    fprintf(f.fp, "#?RADIANCE\n# written by irrcache\nFORMAT=32-bit_rle_rgbe\n%s\n\n-Y %d +X %d\n", RGBE_PRIMARIES,
            img->height, img->width);
    const size_t row_bytes = (size_t)img->width * 4;
    unsigned char *row = malloc(row_bytes);
    if (!row) {
        ic_atomic_file_abort(&f);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory writing the image", path);
    }
    for (int y = 0; y < img->height; ++y) {
        const float *src = img->rgb + (size_t)y * (size_t)img->width * 3;
        for (int x = 0; x < img->width; ++x)
            encode_rgbe(src + (size_t)x * 3, row + (size_t)x * 4);
        if (fwrite(row, 1, row_bytes, f.fp) != row_bytes)
            break; /* ferror is set; commit reports it and removes the temporary file */
    }
    free(row);
    return ic_atomic_file_commit(&f, err);
}

/* ---------------------------------------------------------------------------------------------- */
/* Reading                                                                                        */

/* Reads one header line (without its newline), keeping its first size − 1 characters in line and
 * skipping the rest: headers carry command histories of any length (rpict, pcomb), while the lines read
 * here are short. *length gets the whole line's length; 0 at the end of the file before a newline. */
static int read_line(FILE *fp, char *line, size_t size, size_t *length)
{
    size_t n = 0;
    int c;
    while ((c = getc(fp)) != EOF && c != '\n') {
        if (n + 1 < size)
            line[n] = (char)c;
        ++n;
    }
    line[n < size ? n : size - 1] = '\0';
    *length = n;
    return c == '\n';
}

/* Reads the header up to and including the resolution line. */
static ic_result read_header(const char *path, FILE *fp, int *width, int *height, double *exposure, ic_error *err)
{
    char line[512];
    size_t length;
    if (!read_line(fp, line, sizeof line, &length) || strncmp(line, "#?", 2) != 0)
        return ic_error_set(err, IC_ERR_PARSE, "%s: not a Radiance picture (no \"#?\" line); re-create the file", path);
    *exposure = 1.0;
    for (int number = 2;; ++number) {
        if (!read_line(fp, line, sizeof line, &length))
            return ic_error_set(err, IC_ERR_CORRUPT, "%s: truncated or malformed Radiance header; re-create the file",
                                path);
        if (length == 0)
            break; /* end of header */
        int format = strncmp(line, "FORMAT=", 7) == 0, exposure_line = strncmp(line, "EXPOSURE=", 9) == 0;
        if ((format || exposure_line) && length >= sizeof line)
            return ic_error_set(err, IC_ERR_PARSE, "%s:%d: this %s line has %zu characters, more than the %zu read; "
                                "shorten it to its value", path, number, format ? "FORMAT=" : "EXPOSURE=", length,
                                sizeof line - 1);
        if (format && strcmp(line + 7, "32-bit_rle_rgbe") != 0)
            return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: Radiance format \"%s\" is not supported; convert it to "
                                "32-bit_rle_rgbe (ra_xyze -r)", path, line + 7);
        if (exposure_line) {
            double e = strtod(line + 9, NULL);
            if (isfinite(e) && e > 0.0)
                *exposure *= e; /* cumulative, per the format */
        }
    }
    /* EXPOSURE lines multiply: their product must stay a positive finite number (1e-300 made every
     * pixel infinite). */
    if (!(*exposure > 1e-30 && *exposure < 1e30))
        return ic_error_set(err, IC_ERR_CORRUPT, "%s: the header's EXPOSURE lines multiply to %g, outside 1e-30 to "
                            "1e30; fix or remove them", path, *exposure);
    char y_sign, x_sign, y_axis, x_axis, hs[16], ws[16];
    int got = read_line(fp, line, sizeof line, &length) && length < sizeof line;
    if (got && sscanf(line, "%cY %15s %cX %15s", &y_sign, hs, &x_sign, ws) == 4) {
        /* The sizes as numbers that fit an int, not %d (which wraps 4294967300 to 4). */
        char *e1 = NULL, *e2 = NULL;
        errno = 0;
        long h = strtol(hs, &e1, 10), w = strtol(ws, &e2, 10);
        if (errno || *e1 || *e2 || h < 0 || w < 0 || h > INT_MAX || w > INT_MAX)
            return ic_error_set(err, IC_ERR_PARSE, "%s: resolution line \"%s\" has a size that is not a whole "
                                "number up to %d; re-create the file", path, line, INT_MAX);
        *height = (int)h;
        *width = (int)w;
    } else {
        if (got && sscanf(line, "%c%c %*d %c%c %*d", &y_sign, &y_axis, &x_sign, &x_axis) == 4)
            return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: picture orientation \"%s\" is not supported; re-orient it "
                                "to \"-Y height +X width\" (pflip, protate)", path, line);
        return ic_error_set(err, IC_ERR_PARSE, "%s: missing or malformed resolution line; re-create the file", path);
    }
    if (y_sign != '-' || x_sign != '+')
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: picture orientation \"%s\" is not supported; re-orient it to "
                            "\"-Y height +X width\" (pflip)", path, line);
    return IC_OK;
}

/* Reads one scanline of width RGBE pixels into line (width*4 bytes). Returns 0 on a short read or a
 * malformed run. */
static int read_scanline(FILE *fp, unsigned char *line, int width)
{
    unsigned char first[4];
    if (fread(first, 1, 4, fp) != 4)
        return 0;
    if (width >= 8 && width < 0x8000 && first[0] == 2 && first[1] == 2 && !(first[2] & 0x80)) {
        /* New-style RLE: the four components one after the other, each as runs and literals. */
        if (((int)first[2] << 8 | first[3]) != width)
            return 0;
        for (int c = 0; c < 4; ++c) {
            for (int x = 0; x < width;) {
                int count = fgetc(fp);
                if (count == EOF || count == 0)
                    return 0;
                if (count > 128) {
                    count -= 128;
                    int value = fgetc(fp);
                    if (value == EOF || x + count > width)
                        return 0;
                    for (; count > 0; --count)
                        line[4 * x++ + c] = (unsigned char)value;
                } else {
                    if (x + count > width)
                        return 0;
                    for (; count > 0; --count) {
                        int value = fgetc(fp);
                        if (value == EOF)
                            return 0;
                        line[4 * x++ + c] = (unsigned char)value;
                    }
                }
            }
        }
        return 1;
    }
    /* Flat pixels, possibly with old-style runs: (1, 1, 1, n) repeats the previous pixel n << shift times. */
    int shift = 0;
    for (int x = 0; x < width;) {
        unsigned char px[4];
        if (x == 0)
            memcpy(px, first, 4);
        else if (fread(px, 1, 4, fp) != 4)
            return 0;
        if (px[0] == 1 && px[1] == 1 && px[2] == 1) {
            if (x == 0 || shift > 16)
                return 0;
            long repeat = (long)px[3] << shift;
            if (repeat > width - x)
                return 0;
            for (; repeat > 0; --repeat, ++x)
                memcpy(line + 4 * x, line + 4 * (x - 1), 4);
            shift += 8;
        } else {
            memcpy(line + 4 * x++, px, 4);
            shift = 0;
        }
    }
    return 1;
}

ic_result ic_image_read_hdr(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err)
{
    memset(out, 0, sizeof *out);
    FILE *fp;
    ic_result opened = ic_open_regular_file(path, "PNG, JPEG, EXR, HDR or PFM file", &fp, err);
    if (opened != IC_OK)
        return opened;
    int width = 0, height = 0;
    double exposure = 1.0;
    ic_result r = read_header(path, fp, &width, &height, &exposure, err);
    if (r == IC_OK)
        r = ic_image_create_for_file(path, out, width, height, lim, err);
    unsigned char *line = r == IC_OK ? malloc((size_t)width * 4) : NULL;
    if (r == IC_OK && !line)
        r = ic_error_set(err, IC_ERR_OOM, "%s: out of memory reading the image", path);
    for (int y = 0; r == IC_OK && y < height; ++y) {
        if (!read_scanline(fp, line, width)) {
            r = ic_error_set(err, IC_ERR_CORRUPT, "%s: truncated or corrupt pixel data at scanline %d of %d; re-create "
                             "the file", path, y + 1, height);
            break;
        }
        float *dst = out->rgb + (size_t)y * (size_t)width * 3;
        for (int x = 0; x < width; ++x) {
            const unsigned char *px = line + 4 * x;
            /* Radiance decodes to the middle of the mantissa's interval: (m + 0.5) · 2^(e-136). */
            double scale = px[3] ? ldexp(1.0, (int)px[3] - 136) / exposure : 0.0;
            for (int c = 0; c < 3; ++c) {
                double v = px[3] ? ((double)px[c] + 0.5) * scale : 0.0;
                if (v > FLT_MAX) { /* a large exponent over a small EXPOSURE: beyond a float */
                    r = ic_error_set(err, IC_ERR_CORRUPT, "%s: pixel (%d, %d) decodes to %g, beyond the range of a "
                                     "float; check the file's EXPOSURE lines", path, x, y, v);
                    break;
                }
                dst[3 * x + c] = (float)v;
            }
            if (r != IC_OK)
                break;
        }
    }
    free(line);
    fclose(fp);
    if (r != IC_OK)
        ic_image_free(out);
    return r;
}
