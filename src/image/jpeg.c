/*
 * jpeg.c — reading JPEG (ITU-T T.81, JFIF) through libjpeg: baseline, progressive and arithmetic-coded,
 * greyscale or colour (YCbCr or RGB), 8 bits per sample, converted from sRGB to linear RGB.
 *
 * libjpeg reports errors through its error manager, which by default prints and exits; here every error
 * and every warning ends the decode through a longjmp back to where it began, and the library's message
 * becomes the one-line error. A warning is libjpeg's word for damaged data it would otherwise
 * paper over (entropy-coded data that runs out is filled with zeros, a missing EOI is assumed, extraneous
 * bytes are skipped), so a damaged file is refused rather than shown half grey. Nothing is printed.
 *
 * The header's size is checked against the caller's pixel limit before libjpeg allocates its buffers
 * (a progressive image keeps every coefficient, about 2 bytes per sample). CMYK and YCCK files (Adobe's
 * four-channel JPEGs) are refused: converting them needs the ink profile they were separated with. The
 * EXIF orientation tag is not applied: pixels are read in stored order, as every other format is.
 */
#include "image_internal.h"

#include <limits.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <jpeglib.h>

/* Progressive scans accepted. T.81 Annex G lets each component's coefficients be sent band by band and
 * bit plane by bit plane, up to a few thousand scans, but encoders write about ten; each scan is a pass
 * over the whole coefficient buffer, so a small file of thousands of empty scans over a large image would
 * take minutes to decode. */
#define MAX_SCANS 500

/* libjpeg's error manager with the jump back to the decode, and the first message it reported. */
typedef struct decode_failure {
    struct jpeg_error_mgr mgr; /* first: libjpeg hands back a pointer to it */
    jmp_buf back;
    char message[JMSG_LENGTH_MAX];
} decode_failure;

static void fail(j_common_ptr cinfo)
{
    decode_failure *f = (decode_failure *)cinfo->err;
    (*cinfo->err->format_message)(cinfo, f->message);
    longjmp(f->back, 1);
}

/* Warnings (msg_level -1) end the decode like errors; trace messages (0 and up) are dropped. */
static void on_message(j_common_ptr cinfo, int msg_level)
{
    if (msg_level < 0)
        fail(cinfo);
}

/* libjpeg's own printing, never used: every message goes through fail. */
static void print_nothing(j_common_ptr cinfo)
{
    (void)cinfo;
}

/* libjpeg's progress hook, called as it reads: ends the decode past MAX_SCANS. */
static void count_scans(j_common_ptr cinfo)
{
    j_decompress_ptr d = (j_decompress_ptr)cinfo;
    if (d->input_scan_number > MAX_SCANS) {
        decode_failure *f = (decode_failure *)cinfo->err;
        snprintf(f->message, sizeof f->message, "more than %d scans", MAX_SCANS);
        longjmp(f->back, 1);
    }
}

/* One decode: libjpeg's state and what it reports, kept outside the function that calls setjmp so that
 * nothing a longjmp skips over is an automatic variable of that function (C11 §7.13.2.1). */
typedef struct decode_job {
    struct jpeg_decompress_struct cinfo;
    decode_failure failure;
    struct jpeg_progress_mgr progress;
    const char *name;
    const ic_image_limit *lim;
    ic_image *out;
    ic_error *err;
} decode_job;

/* Checks the header and decodes into d->out; on failure returns the error (d->out left for the caller to
 * free). A libjpeg error or warning returns through the longjmp with IC_ERR_PARSE. */
static ic_result decode(decode_job *d, const unsigned char *bytes, size_t n)
{
    if (setjmp(d->failure.back))
        return ic_error_set(d->err, IC_ERR_PARSE, "%s: cannot decode the JPEG (%s); check the file or re-save it",
                            d->name, d->failure.message[0] ? d->failure.message : "unknown reason");
    struct jpeg_decompress_struct *cinfo = &d->cinfo;
    jpeg_create_decompress(cinfo);
    cinfo->progress = &d->progress;
    jpeg_mem_src(cinfo, bytes, (unsigned long)n);
    jpeg_read_header(cinfo, TRUE);

    switch (cinfo->jpeg_color_space) {
    case JCS_GRAYSCALE:
        cinfo->out_color_space = JCS_GRAYSCALE; /* replicated to RGB below */
        break;
    case JCS_YCbCr:
    case JCS_RGB:
        cinfo->out_color_space = JCS_RGB;
        break;
    case JCS_CMYK:
    case JCS_YCCK:
        return ic_error_set(d->err, IC_ERR_UNSUPPORTED, "%s: a CMYK JPEG is not supported; convert it to RGB",
                            d->name);
    default:
        return ic_error_set(d->err, IC_ERR_UNSUPPORTED, "%s: a JPEG of %d components in no known colour space is not "
                            "supported; convert it to RGB or greyscale", d->name, cinfo->num_components);
    }
    /* The header's size, checked before libjpeg allocates for it; JPEG sides are at most 65535. */
    ic_result r = ic_image_create_for_file(d->name, d->out, (int)cinfo->image_width, (int)cinfo->image_height, d->lim,
                                           d->err);
    if (r != IC_OK)
        return r;

    jpeg_start_decompress(cinfo);
    const int channels = cinfo->output_components;
    if ((channels != 1 && channels != 3) || cinfo->output_width != (JDIMENSION)d->out->width ||
        cinfo->output_height != (JDIMENSION)d->out->height)
        return ic_error_set(d->err, IC_ERR_PARSE, "%s: libjpeg decodes %ux%u pixels of %d components for a %dx%d "
                            "header; re-save the image", d->name, (unsigned)cinfo->output_width,
                            (unsigned)cinfo->output_height, channels, d->out->width, d->out->height);
    JSAMPARRAY row = (*cinfo->mem->alloc_sarray)((j_common_ptr)cinfo, JPOOL_IMAGE,
                                                 cinfo->output_width * (JDIMENSION)channels, 1);
    float to_linear[256];
    for (int v = 0; v < 256; ++v)
        to_linear[v] = ic_srgb8_to_linear((uint8_t)v);
    const size_t width = (size_t)d->out->width;
    uint8_t *bytes_out = d->lim && d->lim->srgb8 ? *d->lim->srgb8 : NULL;
    while (cinfo->output_scanline < cinfo->output_height) {
        const size_t at = (size_t)cinfo->output_scanline * width * 3;
        jpeg_read_scanlines(cinfo, row, 1);
        if (bytes_out) {
            for (size_t x = 0; x < width; ++x)
                for (size_t c = 0; c < 3; ++c)
                    bytes_out[at + 3 * x + c] = row[0][channels == 3 ? 3 * x + c : x];
            continue;
        }
        float *dst = d->out->rgb + at;
        for (size_t x = 0; x < width; ++x)
            for (size_t c = 0; c < 3; ++c)
                dst[3 * x + c] = to_linear[row[0][channels == 3 ? 3 * x + c : x]];
    }
    /* Reads on to EOI, so that a file cut after its last scan is refused too. */
    jpeg_finish_decompress(cinfo);
    return IC_OK;
}

ic_result ic_image_decode_jpeg(const unsigned char *bytes, size_t n, const char *name, const ic_image_limit *lim,
                               ic_image *out, ic_error *err)
{
    memset(out, 0, sizeof *out);
#if ULONG_MAX < SIZE_MAX
    if (n > ULONG_MAX)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: image of %zu bytes is too large to decode", name, n);
#endif
    decode_job d;
    memset(&d, 0, sizeof d);
    d.name = name;
    d.lim = lim;
    d.out = out;
    d.err = err;
    d.cinfo.err = jpeg_std_error(&d.failure.mgr);
    d.failure.mgr.error_exit = fail;
    d.failure.mgr.emit_message = on_message;
    d.failure.mgr.output_message = print_nothing;
    d.progress.progress_monitor = count_scans;
    ic_result r = decode(&d, bytes, n);
    jpeg_destroy_decompress(&d.cinfo); /* also after a failed jpeg_create_decompress: mem is NULL then */
    if (r != IC_OK)
        ic_image_release(out, lim);
    return r;
}
