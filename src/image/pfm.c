/*
 * pfm.c — Portable Float Map read and write.
 *
 * Format: "PF" (RGB) or "Pf" (grey), width, height, scale (negative: little-endian, positive:
 * big-endian; its magnitude is ignored), one whitespace byte, then 32-bit floats with the BOTTOM
 * row first. Our images are top row first, so rows are flipped both ways. Values are copied
 * bit-exactly, NaN and Inf included (the metrics and writers decide what to do with them).
 */
#include "image_internal.h"
#include "core/read_file.h"

#include "core/atomic_file.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int host_is_little_endian(void)
{
    const uint32_t one = 1;
    unsigned char first;
    memcpy(&first, &one, 1);
    return first == 1;
}

static float swap_float(float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    u = (u >> 24) | ((u >> 8) & 0xff00u) | ((u << 8) & 0xff0000u) | (u << 24);
    memcpy(&v, &u, sizeof v);
    return v;
}

ic_result ic_image_read_pfm(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err)
{
    memset(out, 0, sizeof *out);
    FILE *fp;
    ic_result opened = ic_open_regular_file(path, "PNG, JPEG, EXR, HDR or PFM file", &fp, err);
    if (opened != IC_OK)
        return opened;

    char kind[3] = {0}, wtext[16] = {0}, htext[16] = {0};
    int width = 0, height = 0;
    double scale = 0.0;
    int ws = 0;
    /* The sizes read as text and converted with a range check: %d wraps 4294967297 to 1. */
    int sized = fscanf(fp, "%2s %15s %15s %lf", kind, wtext, htext, &scale) == 4;
    if (sized) {
        char *e1 = NULL, *e2 = NULL;
        errno = 0;
        long w = strtol(wtext, &e1, 10), h = strtol(htext, &e2, 10);
        sized = !errno && !*e1 && !*e2 && w >= INT_MIN && w <= INT_MAX && h >= INT_MIN && h <= INT_MAX;
        width = sized ? (int)w : 0;
        height = sized ? (int)h : 0;
    }
    if (!sized || kind[0] != 'P' ||
        (kind[1] != 'F' && kind[1] != 'f') || !isfinite(scale) || scale == 0.0 ||
        ((ws = fgetc(fp)) != '\n' && ws != ' ' && ws != '\t' && ws != '\r')) {
        fclose(fp);
        return ic_error_set(err, IC_ERR_PARSE,
                            "%s: malformed PFM header (expected \"PF\" or \"Pf\", width, height, non-zero scale); "
                            "re-create the file",
                            path);
    }
    const int channels = kind[1] == 'F' ? 3 : 1;
    ic_result r = IC_OK;
    if (width > 0 && height > 0 && width <= IC_IMAGE_MAX_SIDE && height <= IC_IMAGE_MAX_SIDE) {
        /* Check the length before allocating, so a truncated or lying header is reported as such. */
        long data_start = ftell(fp);
        long file_end = (data_start >= 0 && fseek(fp, 0, SEEK_END) == 0) ? ftell(fp) : -1;
        size_t expected = (size_t)width * (size_t)height * (size_t)channels * sizeof(float);
        if (file_end < 0 || fseek(fp, data_start, SEEK_SET) != 0)
            r = ic_error_set(err, IC_ERR_IO, "%s: cannot seek in the file; read it from a regular file", path);
        else if ((size_t)(file_end - data_start) < expected)
            r = ic_error_set(err, IC_ERR_CORRUPT,
                             "%s: truncated PFM (%dx%d needs %zu bytes of pixels, found %ld); re-create the file", path,
                             width, height, expected, file_end - data_start);
    }
    if (r == IC_OK)
        r = ic_image_create_for_file(path, out, width, height, lim, err);
    if (r != IC_OK) {
        fclose(fp);
        return r;
    }
    const int swap = (scale < 0.0) != host_is_little_endian();
    const size_t row_values = (size_t)width * (size_t)channels;
    float *row = malloc(row_values * sizeof *row);
    if (!row) {
        fclose(fp);
        ic_image_free(out);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory reading the image", path);
    }
    for (int file_y = 0; file_y < height; ++file_y) {
        if (fread(row, sizeof *row, row_values, fp) != row_values) {
            int io = ferror(fp);
            free(row);
            fclose(fp);
            ic_image_free(out);
            if (io)
                return ic_error_set(err, IC_ERR_IO, "%s: read error; check the file and the disk", path);
            return ic_error_set(err, IC_ERR_CORRUPT,
                                "%s: truncated PFM (%dx%d needs %zu bytes of pixels); re-create the file", path, width,
                                height, (size_t)width * (size_t)height * (size_t)channels * sizeof(float));
        }
        float *dst = out->rgb + (size_t)(height - 1 - file_y) * (size_t)width * 3;
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c) {
                float v = row[(size_t)x * (size_t)channels + (size_t)(channels == 3 ? c : 0)];
                dst[(size_t)x * 3 + (size_t)c] = swap ? swap_float(v) : v;
            }
    }
    free(row);
    fclose(fp);
    return IC_OK;
}

ic_result ic_image_write_pfm(const char *path, const ic_image *img, ic_error *err)
{
    ic_atomic_file f;
    ic_result r = ic_atomic_file_open(&f, path, err);
    if (r != IC_OK)
        return r;
    /* Scale -1: little-endian. Floats are written byte by byte so the file is the same on any host. */
    fprintf(f.fp, "PF\n%d %d\n-1.0\n", img->width, img->height);
    const size_t row_bytes = (size_t)img->width * 3 * 4;
    unsigned char *row = malloc(row_bytes);
    if (!row) {
        ic_atomic_file_abort(&f);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory writing the image", path);
    }
    for (int y = img->height - 1; y >= 0; --y) {
        const float *src = img->rgb + (size_t)y * (size_t)img->width * 3;
        for (size_t i = 0; i < (size_t)img->width * 3; ++i) {
            uint32_t u;
            memcpy(&u, &src[i], sizeof u);
            row[4 * i + 0] = (unsigned char)(u & 0xff);
            row[4 * i + 1] = (unsigned char)((u >> 8) & 0xff);
            row[4 * i + 2] = (unsigned char)((u >> 16) & 0xff);
            row[4 * i + 3] = (unsigned char)(u >> 24);
        }
        if (fwrite(row, 1, row_bytes, f.fp) != row_bytes)
            break; /* ferror is set; commit reports it and removes the temporary file */
    }
    free(row);
    return ic_atomic_file_commit(&f, err);
}
