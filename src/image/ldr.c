/*
 * ldr.c — 8-bit images through stb: reading PNG and JPEG (8- or 16-bit sRGB, converted to linear)
 * and writing 8-bit sRGB PNG.
 *
 * Alpha is dropped on read and grey images are replicated to RGB. PNG output applies the exposure
 * (2^stops), then the sRGB curve, clamped to [0, 255]; NaN becomes 0.
 */
#include "image_internal.h"

#include "core/atomic_file.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stb_image.h>
#include <stb_image_write.h>

static ic_result decode_failed(const char *path, ic_error *err)
{
    const char *why = stbi_failure_reason();
    return ic_error_set(err, IC_ERR_PARSE, "%s: cannot decode image (%s); check that it is a valid PNG or JPEG file",
                        path, why ? why : "unknown reason");
}

ic_result ic_image_read_stb(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err)
{
    memset(out, 0, sizeof *out);
    int width = 0, height = 0, channels = 0;
    if (!stbi_info(path, &width, &height, &channels))
        return decode_failed(path, err);
    /* Validate the size before stb allocates for it. */
    ic_result r = ic_image_create_for_file(path, out, width, height, lim, err);
    if (r != IC_OK)
        return r;
    const size_t count = (size_t)width * (size_t)height * 3;

    if (stbi_is_16_bit(path)) {
        unsigned short *pixels = stbi_load_16(path, &width, &height, &channels, 3);
        if (!pixels) {
            ic_image_free(out);
            return decode_failed(path, err);
        }
        for (size_t i = 0; i < count; ++i)
            out->rgb[i] = ic_srgb_to_linear((float)pixels[i] / 65535.0f);
        stbi_image_free(pixels);
    } else {
        unsigned char *pixels = stbi_load(path, &width, &height, &channels, 3);
        if (!pixels) {
            ic_image_free(out);
            return decode_failed(path, err);
        }
        float to_linear[256];
        for (int v = 0; v < 256; ++v)
            to_linear[v] = ic_srgb8_to_linear((uint8_t)v);
        for (size_t i = 0; i < count; ++i)
            out->rgb[i] = to_linear[pixels[i]];
        stbi_image_free(pixels);
    }
    return IC_OK;
}

/* stb_image_write callback: append to the temporary file; errors surface through ferror. */
static void write_to_file(void *context, void *data, int size)
{
    if (size > 0)
        fwrite(data, 1, (size_t)size, (FILE *)context);
}

ic_result ic_image_write_png(const char *path, const ic_image *img, float exposure, ic_error *err)
{
    const size_t count = (size_t)img->width * (size_t)img->height * 3;
    unsigned char *pixels = malloc(count);
    if (!pixels)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory writing the image", path);
    const float scale = isfinite(exposure) ? exp2f(exposure) : 1.0f;
    for (size_t i = 0; i < count; ++i)
        pixels[i] = ic_linear_to_srgb8(img->rgb[i] * scale);

    ic_atomic_file f;
    ic_result r = ic_atomic_file_open(&f, path, err);
    if (r == IC_OK) {
        if (stbi_write_png_to_func(write_to_file, f.fp, img->width, img->height, 3, pixels, img->width * 3)) {
            r = ic_atomic_file_commit(&f, err);
        } else {
            ic_atomic_file_abort(&f);
            r = ic_error_set(err, IC_ERR_OOM, "%s: PNG encoding failed (out of memory); free memory and retry", path);
        }
    }
    free(pixels);
    return r;
}
