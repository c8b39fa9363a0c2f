/*
 * image_io.c — the format dispatch of ic_image_read / ic_image_write (include/irrcache/image.h).
 *
 * Reading sniffs the file's first bytes (the extension may lie: a renamed .exr is still read);
 * writing picks the format from the extension. The per-format code lives in exr.c, pfm.c, rgbe.c,
 * ldr.c (PNG through stb) and jpeg.c (JPEG through libjpeg).
 */
#include "image_internal.h"
#include "core/read_file.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

/* Lower-case extension of path including the dot ("" if none), into ext[8]. */
static void extension_of(const char *path, char ext[8])
{
    ext[0] = '\0';
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash) || strlen(dot) >= 8)
        return;
    size_t i = 0;
    for (; dot[i]; ++i)
        ext[i] = (char)((dot[i] >= 'A' && dot[i] <= 'Z') ? dot[i] - 'A' + 'a' : dot[i]);
    ext[i] = '\0';
}

int ic_image_is_writable_format(const char *path)
{
    if (!path)
        return 0;
    char ext[8];
    extension_of(path, ext);
    return !strcmp(ext, ".exr") || !strcmp(ext, ".pfm") || !strcmp(ext, ".hdr") || !strcmp(ext, ".png");
}

ic_result ic_image_read(const char *path, ic_image *out, ic_error *err)
{
    return ic_image_read_max(path, 0, NULL, out, err);
}

ic_result ic_image_read_layer(const char *path, const char *layer, ic_image *out, ic_error *err)
{
    if (!out || !path || !*path || !layer || !*layer)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "ic_image_read_layer: no path, layer or output image");
    memset(out, 0, sizeof *out);
    char ext[8];
    extension_of(path, ext);
    if (strcmp(ext, ".exr") != 0)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: only OpenEXR files have layers", path);
    const ic_image_limit limit = {0, NULL, NULL};
    return ic_image_read_exr_layer(path, layer, &limit, out, err);
}

/* ic_image_read_max's reading with its limit (lim->srgb8: an 8-bit PNG or JPEG as bytes). */
static ic_result read_limited(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err)
{
    const ic_image_limit floats = {lim->max_pixels, lim->raise, NULL}; /* the float formats' */
    if (!out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "ic_image_read: no output image given");
    memset(out, 0, sizeof *out);
    if (!path || !*path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "empty image path; give a file name");

    FILE *fp;
    /* never blocks on a FIFO; a folder or device is refused by name */
    ic_result opened = ic_open_regular_file(path, "PNG, JPEG, EXR, HDR or PFM file", &fp, err);
    if (opened != IC_OK)
        return opened;
    unsigned char magic[4] = {0};
    size_t n = fread(magic, 1, sizeof magic, fp);
    int read_error = ferror(fp);
    fclose(fp);
    if (read_error)
        return ic_error_set(err, IC_ERR_IO, "%s: cannot read (I/O error); check the file and the disk", path);
    if (n == 0)
        return ic_error_set(err, IC_ERR_PARSE, "%s: file is empty; re-create the image", path);

    if (n == 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01)
        return ic_image_read_exr(path, &floats, out, err);
    if (n >= 3 && magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f') &&
        (magic[2] == '\n' || magic[2] == '\r' || magic[2] == ' ' || magic[2] == '\t'))
        return ic_image_read_pfm(path, &floats, out, err);
    if (n >= 2 && magic[0] == '#' && magic[1] == '?')
        return ic_image_read_hdr(path, &floats, out, err);
    if ((n == 4 && magic[0] == 0x89 && magic[1] == 'P' && magic[2] == 'N' && magic[3] == 'G') || /* PNG */
        (n >= 3 && magic[0] == 0xff && magic[1] == 0xd8 && magic[2] == 0xff))               /* JPEG */
        return ic_image_read_ldr(path, lim, out, err);
    return ic_error_set(err, IC_ERR_UNSUPPORTED,
                        "%s: not an image format irrcache reads; convert it to OpenEXR, PFM, Radiance HDR, "
                        "PNG or JPEG",
                        path);
}

ic_result ic_image_read_max(const char *path, size_t max_pixels, const char *raise, ic_image *out, ic_error *err)
{
    const ic_image_limit limit = {max_pixels, raise, NULL};
    return read_limited(path, &limit, out, err);
}

ic_result ic_image_read_texture(const char *path, size_t max_pixels, const char *raise, ic_image *out, uint8_t **srgb8,
                                ic_error *err)
{
    if (!srgb8)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "ic_image_read_texture: nowhere to put the bytes");
    *srgb8 = NULL;
    const ic_image_limit limit = {max_pixels, raise, srgb8};
    return read_limited(path, &limit, out, err);
}

ic_result ic_image_decode_memory(const void *data, size_t size, const char *name, size_t max_pixels, const char *raise,
                                 ic_image *out, ic_error *err)
{
    const ic_image_limit limit = {max_pixels, raise, NULL};
    if (!out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "ic_image_decode_memory: no output image given");
    memset(out, 0, sizeof *out);
    const unsigned char *m = data;
    if (!name)
        name = "(image in memory)";
    if (!m || size == 0)
        return ic_error_set(err, IC_ERR_PARSE, "%s: the image is empty", name);
    if ((size >= 4 && m[0] == 0x89 && m[1] == 'P' && m[2] == 'N' && m[3] == 'G') ||
        (size >= 3 && m[0] == 0xff && m[1] == 0xd8 && m[2] == 0xff))
        return ic_image_decode_ldr(m, size, name, &limit, out, err);
    return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: an embedded image must be PNG or JPEG; convert it", name);
}

ic_result ic_image_write(const char *path, const ic_image *img, const ic_image_write_options *opt, ic_error *err)
{
    static const ic_image_write_options defaults = {0};
    if (!opt)
        opt = &defaults;
    if (!path || !*path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "empty output path; give a file name");
    if (!img || !img->rgb || img->width <= 0 || img->height <= 0)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: nothing to write (empty image)", path);

    char ext[8];
    extension_of(path, ext);
    if (!strcmp(ext, ".exr"))
        return ic_image_write_exr(path, img, opt, err);
    if (!strcmp(ext, ".pfm"))
        return ic_image_write_pfm(path, img, err);
    if (!strcmp(ext, ".hdr"))
        return ic_image_write_hdr(path, img, err);
    if (!strcmp(ext, ".png"))
        return ic_image_write_png(path, img, opt->exposure, err);
    return ic_error_set(err, IC_ERR_UNSUPPORTED,
                        "%s: unknown image extension; use .exr, .pfm, .hdr or .png", path);
}
