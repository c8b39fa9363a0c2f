/*
 * image_internal.h — the per-format readers and writers behind ic_image_read / ic_image_write.
 *
 * Each reader fills a fresh ic_image (the caller frees it on success; on failure the image is left
 * zeroed) and each writer writes through a temporary file that is renamed into place only when the
 * whole file was written. Messages follow common.h: "<path>: <what went wrong>; <what to do>".
 */
#ifndef IC_IMAGE_INTERNAL_H
#define IC_IMAGE_INTERNAL_H

#include "irrcache/image.h"

/* The caller's limit on the pixels of an image read (ic_image_read_max): max_pixels 0 is none. */
typedef struct ic_image_limit {
    size_t max_pixels;
    const char *raise;     /* what to do when it is exceeded, or NULL */
    uint8_t **srgb8;       /* non-NULL: an 8-bit PNG or JPEG comes back as its bytes here (3 a pixel, rows top
                              first; free()), the image then holding its size and no pixels (ic_image_read_texture) */
} ic_image_limit;

/* 1 for a size an image may have: sides 1 … IC_IMAGE_MAX_SIDE, at most IC_IMAGE_MAX_PIXELS. */
int ic_image_size_allowed(int width, int height);
/* IC_OK if width x height is within lim (may be NULL); else reports it against path, naming the limit. */
ic_result ic_image_check_size(const char *path, int width, int height, const ic_image_limit *lim, ic_error *err);
/* ic_image_create for a reader: reports a bad size, one over lim (may be NULL) or a failed allocation
 * against path. With lim->srgb8, *lim->srgb8 gets room for the 8-bit bytes instead (img: the size, no pixels). */
ic_result ic_image_create_for_file(const char *path, ic_image *img, int width, int height, const ic_image_limit *lim,
                                   ic_error *err);
/* Frees what a reader made of an image it then refused: the pixels, and the bytes of lim->srgb8. */
void ic_image_release(ic_image *img, const ic_image_limit *lim);

/* OpenEXR (Core C API): first part, scanline, R/G/B (A ignored) or Y, half or float. */
ic_result ic_image_read_exr(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err);
/* The channels "<layer>.R" … of one layer of an EXR (layer NULL: its R, G, B, as ic_image_read_exr). */
ic_result ic_image_read_exr_layer(const char *path, const char *layer, const ic_image_limit *lim, ic_image *out,
                                  ic_error *err);
/* OpenEXR: RGB channels as 16-bit half (is_half) or 32-bit float, ZIP compressed (lossless). */
ic_result ic_image_write_exr(const char *path, const ic_image *img, const ic_image_write_options *opt, ic_error *err);

/* Portable float map ("PF" colour, "Pf" grey), either byte order; rows are stored bottom first. */
ic_result ic_image_read_pfm(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err);
/* Portable float map, little-endian, colour. */
ic_result ic_image_write_pfm(const char *path, const ic_image *img, ic_error *err);

/* Radiance RGBE (.hdr): flat and run-length encoded scanlines, "-Y h +X w" orientation. */
ic_result ic_image_read_hdr(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err);
/* Radiance RGBE (.hdr), flat (not run-length encoded) scanlines. */
ic_result ic_image_write_hdr(const char *path, const ic_image *img, ic_error *err);

/* 8/16-bit PNG (through stb_image) and JPEG (ic_image_decode_jpeg), told apart by their first bytes; sRGB,
 * converted to linear. */
ic_result ic_image_read_ldr(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err);
/* The same for PNG or JPEG bytes in memory; name labels them in messages. */
ic_result ic_image_decode_ldr(const unsigned char *bytes, size_t n, const char *name, const ic_image_limit *lim,
                              ic_image *out, ic_error *err);
/* JPEG through libjpeg: baseline, progressive or arithmetic-coded, greyscale (replicated to RGB) or colour;
 * CMYK refused; every libjpeg error or warning (damaged data) is an IC_ERR_PARSE naming the file. */
ic_result ic_image_decode_jpeg(const unsigned char *bytes, size_t n, const char *name, const ic_image_limit *lim,
                               ic_image *out, ic_error *err);
/* 8-bit sRGB PNG after scaling by 2^exposure. */
ic_result ic_image_write_png(const char *path, const ic_image *img, float exposure, ic_error *err);

#endif
