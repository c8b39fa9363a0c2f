/*
 * image.c — the ic_image type: creation with bounded sizes, freeing, and creation for a reader that
 * reports a bad size against its file (include/irrcache/image.h, image_internal.h).
 */
#include "image_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


int ic_image_size_allowed(int width, int height)
{
    return width > 0 && height > 0 && width <= IC_IMAGE_MAX_SIDE && height <= IC_IMAGE_MAX_SIDE &&
           (size_t)width * (size_t)height <= IC_IMAGE_MAX_PIXELS;
}

ic_result ic_image_create(ic_image *img, int width, int height)
{
    if (!img)
        return IC_ERR_INVALID_ARG;
    memset(img, 0, sizeof *img);
    if (!ic_image_size_allowed(width, height))
        return IC_ERR_INVALID_ARG;
    img->rgb = calloc((size_t)width * (size_t)height * 3, sizeof(float));
    if (!img->rgb)
        return IC_ERR_OOM;
    img->width = width;
    img->height = height;
    return IC_OK;
}

void ic_image_release(ic_image *img, const ic_image_limit *lim)
{
    ic_image_free(img);
    if (lim && lim->srgb8) {
        free(*lim->srgb8);
        *lim->srgb8 = NULL;
    }
}

void ic_image_free(ic_image *img)
{
    if (!img)
        return;
    free(img->rgb);
    memset(img, 0, sizeof *img);
}

ic_result ic_image_check_size(const char *path, int width, int height, const ic_image_limit *lim, ic_error *err)
{
    if (lim && lim->max_pixels > 0 && width > 0 && height > 0 &&
        (size_t)width * (size_t)height > lim->max_pixels)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: %dx%d is %zu pixels, more than the limit of %zu; %s", path,
                            width, height, (size_t)width * (size_t)height, lim->max_pixels,
                            lim->raise ? lim->raise : "use a smaller image");
    return IC_OK;
}

ic_result ic_image_create_for_file(const char *path, ic_image *img, int width, int height, const ic_image_limit *lim,
                                   ic_error *err)
{
    ic_result r = ic_image_check_size(path, width, height, lim, err);
    if (r != IC_OK)
        return r;
    if (lim && lim->srgb8) {
        memset(img, 0, sizeof *img);
        if (!ic_image_size_allowed(width, height))
            r = IC_ERR_INVALID_ARG;
        else if (!(*lim->srgb8 = malloc((size_t)width * (size_t)height * 3)))
            r = IC_ERR_OOM;
        else {
            img->width = width;
            img->height = height;
        }
    } else {
        r = ic_image_create(img, width, height);
    }
    if (r == IC_ERR_INVALID_ARG)
        return ic_error_set(err, IC_ERR_PARSE, "%s: image size %dx%d is invalid or larger than %dx%d or %zu pixels; "
                            "check the file", path, width, height, IC_IMAGE_MAX_SIDE, IC_IMAGE_MAX_SIDE,
                            IC_IMAGE_MAX_PIXELS);
    if (r != IC_OK)
        return ic_error_set(err, r, "%s: out of memory for a %dx%d image; free memory or use a smaller image", path,
                            width, height);
    return IC_OK;
}
