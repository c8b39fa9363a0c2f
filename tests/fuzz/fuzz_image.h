/*
 * fuzz_image.h — the body of the image-reader harnesses: the input is written to the scratch folder and
 * read by one format's reader (src/image/image_internal.h) with a pixel limit of 2^20, so that a header
 * asking for a huge image is refused from the header, as --max-texture-pixels does. A PNG or JPEG reader
 * (bytes_too) reads it a second time as a texture's 8-bit bytes (ic_image_read_texture), which must give
 * the same image.
 */
#ifndef IC_FUZZ_IMAGE_H
#define IC_FUZZ_IMAGE_H

#include "fuzz_util.h"

#include "image/image_internal.h"

typedef ic_result (*fuzz_image_reader)(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err);

static inline int fuzz_image_read(const char *name, fuzz_image_reader reader, int bytes_too, const uint8_t *data,
                                  size_t size)
{
    char path[1024];
    fuzz_write(name, data, size, path, sizeof path);
    const ic_image_limit lim = {(size_t)1 << 20, NULL, NULL};
    ic_image img;
    memset(&img, 0, sizeof img);
    ic_error err;
    int ok = reader(path, &lim, &img, &err) == IC_OK;
    fuzz_report(ok, err.message);
    if (ok) {
        /* Touch every pixel, so that a short buffer shows up under ASan. */
        volatile float sum = 0.0f;
        for (size_t k = 0; k < (size_t)img.width * (size_t)img.height * 3; ++k)
            sum += img.rgb[k];
        (void)sum;
    }
    if (bytes_too) {
        uint8_t *bytes = NULL;
        const ic_image_limit as_bytes = {(size_t)1 << 20, NULL, &bytes};
        ic_image shape;
        memset(&shape, 0, sizeof shape);
        int ok8 = reader(path, &as_bytes, &shape, &err) == IC_OK;
        if (ok8 != ok)
            abort(); /* read as bytes or as floats: the same verdict */
        /* the bytes are the floats' sRGB bytes (a 16-bit PNG comes back as floats) */
        for (size_t k = 0; ok && bytes && k < (size_t)img.width * (size_t)img.height * 3; ++k)
            if (shape.width != img.width || shape.height != img.height || ic_srgb8_to_linear(bytes[k]) != img.rgb[k])
                abort();
        if (ok && !bytes && (shape.width != img.width || !shape.rgb))
            abort();
        free(bytes);
        ic_image_free(&shape);
    }
    ic_image_free(&img);
    return 0;
}

#endif
