/*
 * exr.c — OpenEXR read and write through the OpenEXR Core C API (libOpenEXRCore, 3.1).
 *
 * Writing: one scanline part, channels R, G, B as 32-bit float or 16-bit half, ZIP compression
 * (lossless, so float round trips are bit-exact), written to a temporary name and renamed.
 * Reading: the first part of a scanline or tiled file (its full-resolution level); the data window
 * becomes the image; R, G, B (missing ones read as 0) or, failing those, Y (grey); half and float
 * channels are converted to float by our own unpacker (unpack_to_float says why). Deep images and UINT
 * or sub-sampled colour channels are refused with a message.
 * The library's own error printing is silenced: this module only reports through ic_error.
 */
#include "image_internal.h"

#include "core/atomic_file.h"

#include <OpenEXR/openexr.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The library would print to stderr; we report through the result codes instead. */
static void silent_error_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    (void)code;
    (void)msg;
}

static exr_context_initializer_t context_initializer(void)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = silent_error_handler;
    init.flags = EXR_CONTEXT_FLAG_SILENT_HEADER_PARSE | EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    return init;
}

/* ---------------------------------------------------------------------------------------------- */
/* Reading                                                                                        */

/* Which channel of our RGB triple an EXR channel feeds: 0..2, or -1 to skip it. With a layer, only its
 * channels "<layer>.R" … count; without, only the unprefixed ones. */
static int rgb_slot(const char *name, const char *layer, int grey)
{
    if (layer) {
        size_t n = strlen(layer);
        if (strncmp(name, layer, n) != 0 || name[n] != '.')
            return -1;
        name += n + 1;
    }
    if (grey)
        return strcmp(name, "Y") == 0 ? 0 : -1;
    if (strcmp(name, "R") == 0)
        return 0;
    if (strcmp(name, "G") == 0)
        return 1;
    if (strcmp(name, "B") == 0)
        return 2;
    return -1;
}

static ic_result exr_read_failed(const char *path, exr_result_t rv, ic_error *err)
{
    const char *why = exr_get_default_error_message(rv);
    if (rv == EXR_ERR_FILE_ACCESS)
        return ic_error_set(err, IC_ERR_IO, "%s: cannot read (%s); check the path and its permissions", path, why);
    if (rv == EXR_ERR_OUT_OF_MEMORY)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory reading OpenEXR; free memory or use a smaller image",
                            path);
    return ic_error_set(err, IC_ERR_CORRUPT, "%s: cannot read OpenEXR (%s); the file is truncated or corrupt, re-create it",
                        path, why);
}

/* Checks the part's layout and finds whether it is RGB or grey. */
static ic_result check_layout(const char *path, exr_const_context_t ctxt, const char *layer, int *grey, ic_error *err)
{
    exr_storage_t storage;
    exr_result_t rv = exr_get_storage(ctxt, 0, &storage);
    if (rv != EXR_ERR_SUCCESS)
        return exr_read_failed(path, rv, err);
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED)
        return ic_error_set(err, IC_ERR_UNSUPPORTED,
                            "%s: deep OpenEXR is not supported; save it as a scanline or tiled OpenEXR", path);

    const exr_attr_chlist_t *channels = NULL;
    rv = exr_get_channels(ctxt, 0, &channels);
    if (rv != EXR_ERR_SUCCESS)
        return exr_read_failed(path, rv, err);
    int has_rgb = 0, has_y = 0;
    for (int i = 0; i < channels->num_channels; ++i) {
        const exr_attr_chlist_entry_t *ch = &channels->entries[i];
        int is_rgb = rgb_slot(ch->name.str, layer, 0) >= 0, is_y = rgb_slot(ch->name.str, layer, 1) >= 0;
        if (!is_rgb && !is_y)
            continue;
        if (ch->pixel_type == EXR_PIXEL_UINT || ch->x_sampling != 1 || ch->y_sampling != 1)
            return ic_error_set(err, IC_ERR_UNSUPPORTED,
                                "%s: channel %s is UINT or sub-sampled, which is not supported; save it as half or float "
                                "without sub-sampling",
                                path, ch->name.str);
        has_rgb |= is_rgb;
        has_y |= is_y;
    }
    if (!has_rgb && !has_y && layer)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: no layer %s (channels %s.R, .G, .B) in the first part",
                            path, layer, layer);
    if (!has_rgb && !has_y)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: no R, G, B or Y channel in the first part; save the colour "
                            "as R, G, B channels", path);
    *grey = !has_rgb;
    return IC_OK;
}

/* IEEE 754 binary16 to float (exact: every half is a float). */
static float half_to_float(uint16_t h)
{
    const uint32_t sign = (uint32_t)(h & 0x8000u) << 16, exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
    uint32_t bits;
    if (exponent == 0x1f) /* infinity or NaN */
        bits = sign | 0x7f800000u | (mantissa << 13);
    else if (exponent != 0) /* normal: rebias 15 -> 127 */
        bits = sign | ((exponent + 112u) << 23) | (mantissa << 13);
    else { /* zero or subnormal: mantissa * 2^-24 */
        float f = ldexpf((float)mantissa, -24);
        return sign ? -f : f;
    }
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* Our own unpacker, in place of the library's: the unpacked chunk holds, line after line, each channel's
 * samples of that line (little-endian, channels in the file's order; a y-sub-sampled channel only on its
 * lines); the channels we want (half or float) become floats at decode_to_ptr, the others are stepped
 * over. OpenEXR Core 3.1's own choice of fast path ignores channels left out (decode_to_ptr NULL): a half
 * B and G beside a float channel we skip made it take a three-channel interleaved path that writes
 * through the skipped channel's NULL pointer. */
static exr_result_t unpack_to_float(exr_decode_pipeline_t *decode)
{
    const uint8_t *src = decode->unpacked_buffer;
    const uint8_t *const end = src ? src + decode->chunk.unpacked_size : src;
    for (int y = 0; y < decode->chunk.height; ++y) {
        const int file_y = decode->chunk.start_y + y;
        for (int c = 0; c < decode->channel_count; ++c) {
            const exr_coding_channel_info_t *ch = &decode->channels[c];
            if (ch->y_samples > 1 && file_y % ch->y_samples != 0)
                continue; /* no samples of this channel on this line */
            const size_t bytes = (size_t)ch->width * (size_t)ch->bytes_per_element;
            if (ch->width < 0 || (size_t)(end - src) < bytes)
                return EXR_ERR_CORRUPT_CHUNK;
            if (ch->decode_to_ptr) {
                uint8_t *out = ch->decode_to_ptr + (size_t)y * (size_t)ch->user_line_stride;
                for (int x = 0; x < ch->width; ++x, out += ch->user_pixel_stride) {
                    const uint8_t *s = src + (size_t)x * (size_t)ch->bytes_per_element;
                    float v;
                    if (ch->data_type == EXR_PIXEL_HALF)
                        v = half_to_float((uint16_t)(s[0] | s[1] << 8));
                    else if (ch->data_type == EXR_PIXEL_FLOAT) {
                        uint32_t bits = (uint32_t)s[0] | (uint32_t)s[1] << 8 | (uint32_t)s[2] << 16 |
                                        (uint32_t)s[3] << 24;
                        memcpy(&v, &bits, sizeof v);
                    } else
                        return EXR_ERR_INVALID_ARGUMENT; /* UINT: refused by check_layout before */
                    memcpy(out, &v, sizeof v);
                }
            }
            src += bytes;
        }
    }
    return EXR_ERR_SUCCESS;
}

/* Decodes one chunk whose pixels start at (col, row) of img (relative to the data window). */
static exr_result_t decode_chunk(exr_const_context_t ctxt, const exr_chunk_info_t *chunk, int col, int row,
                                 const char *layer, int grey, exr_decode_pipeline_t *decoder, int *initialized,
                                 ic_image *img)
{
    exr_result_t rv = *initialized ? exr_decoding_update(ctxt, 0, chunk, decoder)
                                   : exr_decoding_initialize(ctxt, 0, chunk, decoder);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    *initialized = 1;
    /* Uncompressed data is unpacked where it was read: a chunk shorter than its lines would leave the
     * library's unpack buffer unwritten (and longer is corrupt too). */
    exr_compression_t compression = EXR_COMPRESSION_NONE;
    rv = exr_get_compression(ctxt, 0, &compression);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    if (compression == EXR_COMPRESSION_NONE && chunk->packed_size != chunk->unpacked_size)
        return EXR_ERR_CORRUPT_CHUNK;
    if (col < 0 || row < 0 || col + chunk->width > img->width || row + chunk->height > img->height)
        return EXR_ERR_BAD_CHUNK_LEADER;
    const size_t line_floats = (size_t)img->width * 3;
    for (int c = 0; c < decoder->channel_count; ++c) {
        exr_coding_channel_info_t *ch = &decoder->channels[c];
        int slot = rgb_slot(ch->channel_name, layer, grey);
        if (slot < 0) {
            ch->decode_to_ptr = NULL; /* skipped */
            continue;
        }
        ch->decode_to_ptr = (uint8_t *)(img->rgb + (size_t)row * line_floats + (size_t)col * 3 + (size_t)slot);
        ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
        ch->user_line_stride = (int32_t)(line_floats * sizeof(float));
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
    }
    rv = exr_decoding_choose_default_routines(ctxt, 0, decoder);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    if (decoder->unpack_and_convert_fn) /* NULL only when the library reads straight into our pointers */
        decoder->unpack_and_convert_fn = unpack_to_float;
    return exr_decoding_run(ctxt, 0, decoder);
}

/* Every chunk of part 0 into img: line groups of a scanline file, or the full-resolution level's tiles
 * of a tiled one (mipmap and ripmap levels below it are not read). */
static ic_result decode_chunks(const char *path, exr_const_context_t ctxt, const exr_attr_box2i_t *window,
                               const char *layer, int grey, ic_image *img, ic_error *err)
{
    exr_storage_t storage;
    exr_result_t rv = exr_get_storage(ctxt, 0, &storage);
    exr_decode_pipeline_t decoder = EXR_DECODE_PIPELINE_INITIALIZER;
    int initialized = 0;
    if (rv == EXR_ERR_SUCCESS && storage == EXR_STORAGE_TILED) {
        int32_t tw = 0, th = 0;
        rv = exr_get_tile_sizes(ctxt, 0, 0, 0, &tw, &th);
        if (rv == EXR_ERR_SUCCESS && (tw <= 0 || th <= 0))
            rv = EXR_ERR_BAD_CHUNK_LEADER;
        const int tiles_x = rv == EXR_ERR_SUCCESS ? (img->width + tw - 1) / tw : 0;
        const int tiles_y = rv == EXR_ERR_SUCCESS ? (img->height + th - 1) / th : 0;
        for (int ty = 0; ty < tiles_y && rv == EXR_ERR_SUCCESS; ++ty)
            for (int tx = 0; tx < tiles_x && rv == EXR_ERR_SUCCESS; ++tx) {
                exr_chunk_info_t chunk;
                rv = exr_read_tile_chunk_info(ctxt, 0, tx, ty, 0, 0, &chunk);
                if (rv == EXR_ERR_SUCCESS)
                    rv = decode_chunk(ctxt, &chunk, tx * tw, ty * th, layer, grey, &decoder, &initialized, img);
            }
    } else if (rv == EXR_ERR_SUCCESS) {
        int lines_per_chunk = 0;
        rv = exr_get_scanlines_per_chunk(ctxt, 0, &lines_per_chunk);
        if (rv == EXR_ERR_SUCCESS && lines_per_chunk <= 0)
            rv = EXR_ERR_BAD_CHUNK_LEADER;
        for (int y = window->min.y; y <= window->max.y && rv == EXR_ERR_SUCCESS; y += lines_per_chunk) {
            exr_chunk_info_t chunk;
            rv = exr_read_scanline_chunk_info(ctxt, 0, y, &chunk);
            /* A chunk may start above the window (line groups are aligned to the file's origin). */
            if (rv == EXR_ERR_SUCCESS)
                rv = decode_chunk(ctxt, &chunk, 0, chunk.start_y - window->min.y, layer, grey, &decoder,
                                  &initialized, img);
        }
    }
    if (initialized)
        exr_decoding_destroy(ctxt, &decoder);
    if (rv != EXR_ERR_SUCCESS)
        return exr_read_failed(path, rv, err);

    if (grey)
        for (size_t i = 0; i < (size_t)img->width * (size_t)img->height; ++i)
            img->rgb[3 * i + 1] = img->rgb[3 * i + 2] = img->rgb[3 * i];
    return IC_OK;
}

ic_result ic_image_read_exr(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err)
{
    return ic_image_read_exr_layer(path, NULL, lim, out, err);
}

ic_result ic_image_read_exr_layer(const char *path, const char *layer, const ic_image_limit *lim, ic_image *out,
                                  ic_error *err)
{
    memset(out, 0, sizeof *out);
    exr_context_initializer_t init = context_initializer();
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_read(&ctxt, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctxt);
        return exr_read_failed(path, rv, err);
    }

    int grey = 0;
    exr_attr_box2i_t window;
    ic_result r = check_layout(path, ctxt, layer, &grey, err);
    if (r == IC_OK) {
        rv = exr_get_data_window(ctxt, 0, &window);
        r = rv == EXR_ERR_SUCCESS ? IC_OK : exr_read_failed(path, rv, err);
    }
    if (r == IC_OK) {
        /* 64-bit arithmetic: a corrupt window could overflow int. */
        int64_t width = (int64_t)window.max.x - window.min.x + 1, height = (int64_t)window.max.y - window.min.y + 1;
        if (width <= 0 || height <= 0 || width > IC_IMAGE_MAX_SIDE || height > IC_IMAGE_MAX_SIDE)
            r = ic_error_set(err, IC_ERR_PARSE, "%s: OpenEXR data window is empty or too large; check the file", path);
        else
            r = ic_image_create_for_file(path, out, (int)width, (int)height, lim, err);
    }
    if (r == IC_OK) {
        r = decode_chunks(path, ctxt, &window, layer, grey, out, err);
        if (r != IC_OK)
            ic_image_free(out);
    }
    exr_finish(&ctxt);
    return r;
}

/* ---------------------------------------------------------------------------------------------- */
/* Writing                                                                                        */

/* Writes img to the (temporary) file `file`; returns the first library error (and, when the file could
 * not be created, the system's errno in *open_errno). */
/* The header's attributes beyond the required ones: the primaries of the linear sRGB data (ITU-R BT.709,
 * D65 white) and the caller's text attributes. */
static exr_result_t write_attributes(exr_context_t ctxt, int part, const ic_image_meta *meta, uint32_t meta_count)
{
    const exr_attr_chromaticities_t rec709 = {0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f};
    exr_result_t rv = exr_attr_set_chromaticities(ctxt, part, "chromaticities", &rec709);
    for (uint32_t i = 0; i < meta_count && rv == EXR_ERR_SUCCESS; ++i)
        rv = exr_attr_set_string(ctxt, part, meta[i].name, meta[i].value ? meta[i].value : "");
    return rv;
}

/* The image an output channel is encoded from, and its slot: the beauty for R, G, B, a layer for
 * "<layer>.R" …; NULL for a name that is neither. */
static const ic_image *channel_source(const char *name, const ic_image *img, const ic_image_write_options *opt,
                                      int *slot)
{
    if ((*slot = rgb_slot(name, NULL, 0)) >= 0)
        return img;
    for (uint32_t i = 0; i < opt->layer_count; ++i)
        if ((*slot = rgb_slot(name, opt->layers[i].name, 0)) >= 0)
            return opt->layers[i].image;
    return NULL;
}

/* The largest finite half (2^15 · (2 − 2^-10)): half outputs clamp finite values to ±this, which
 * OpenEXRCore's conversion would turn into ±Inf; Inf and NaN stay as they are. */
#define HALF_MAX 65504.0f

static float half_range(float v) { return isfinite(v) ? fminf(fmaxf(v, -HALF_MAX), HALF_MAX) : v; }

/* Writes the image and opt's layers and attributes as one part. *by_options: 1 when the failure came from
 * the caller's layers or attributes (a layer given twice, an attribute name OpenEXR keeps for a field of
 * another type: "channels", "compression" …), not from the file or memory. */
static exr_result_t write_part(const char *file, const ic_image *img, const ic_image_write_options *opt,
                               exr_compression_t compression, int *ambiguous, int *open_errno, int *by_options)
{
    *by_options = 0;
    const int is_half = opt->exr_half;
    const float *rgb = img->rgb;
    exr_context_initializer_t init = context_initializer();
    init.flags = 0; /* the read-only flags are not valid for writing */
    exr_context_t ctxt = NULL;
    errno = 0;
    exr_result_t rv = exr_start_write(&ctxt, file, EXR_WRITE_FILE_DIRECTLY, &init);
    *open_errno = errno;
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctxt);
        return rv;
    }
    int part = 0;
    const exr_pixel_type_t type = is_half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
    rv = exr_add_part(ctxt, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctxt, part, img->width, img->height, compression);
    static const char *const names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; ++c)
        rv = exr_add_channel(ctxt, part, names[c], type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    for (uint32_t l = 0; l < opt->layer_count && rv == EXR_ERR_SUCCESS; ++l)
        for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; ++c) {
            char name[300];
            snprintf(name, sizeof name, "%s.%s", opt->layers[l].name, names[c]);
            rv = exr_add_channel(ctxt, part, name, type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
            *by_options = rv != EXR_ERR_SUCCESS && rv != EXR_ERR_OUT_OF_MEMORY;
        }
    if (rv == EXR_ERR_SUCCESS) {
        rv = write_attributes(ctxt, part, opt->meta, opt->meta_count);
        *by_options = rv != EXR_ERR_SUCCESS && rv != EXR_ERR_OUT_OF_MEMORY;
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctxt);

    int lines_per_chunk = 0;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_scanlines_per_chunk(ctxt, part, &lines_per_chunk);
    exr_encode_pipeline_t encoder = EXR_ENCODE_PIPELINE_INITIALIZER;
    int initialized = 0;
    const size_t line_floats = (size_t)img->width * 3;
    /* Half: each chunk's channels, clamped to half's range, one slab a channel. */
    const size_t slab = (size_t)(lines_per_chunk > 0 ? lines_per_chunk : 1) * (size_t)img->width;
    float *clamped = NULL;
    if (rv == EXR_ERR_SUCCESS && is_half &&
        !(clamped = malloc(sizeof *clamped * slab * 3 * (1 + (size_t)opt->layer_count))))
        rv = EXR_ERR_OUT_OF_MEMORY;
    for (int y = 0; y < img->height && rv == EXR_ERR_SUCCESS; y += lines_per_chunk) {
        exr_chunk_info_t chunk;
        rv = exr_write_scanline_chunk_info(ctxt, part, y, &chunk);
        if (rv != EXR_ERR_SUCCESS)
            break;
        rv = initialized ? exr_encoding_update(ctxt, part, &chunk, &encoder)
                         : exr_encoding_initialize(ctxt, part, &chunk, &encoder);
        if (rv != EXR_ERR_SUCCESS)
            break;
        initialized = 1;
        for (int c = 0; c < encoder.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &encoder.channels[c];
            int slot;
            const ic_image *src = channel_source(ch->channel_name, img, opt, &slot);
            const float *from = (src ? src->rgb : rgb) + (size_t)y * line_floats + (size_t)(slot < 0 ? 0 : slot);
            ch->encode_from_ptr = (const uint8_t *)from;
            ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
            ch->user_line_stride = (int32_t)(line_floats * sizeof(float));
            if (clamped) {
                float *to = clamped + (size_t)c * slab;
                for (int row = 0; row < chunk.height; ++row)
                    for (int x = 0; x < img->width; ++x)
                        to[(size_t)row * img->width + x] = half_range(from[(size_t)row * line_floats + 3 * (size_t)x]);
                ch->encode_from_ptr = (const uint8_t *)to;
                ch->user_pixel_stride = (int32_t)sizeof(float);
                ch->user_line_stride = (int32_t)((size_t)img->width * sizeof(float));
            }
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
        }
        rv = exr_encoding_choose_default_routines(ctxt, part, &encoder);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_encoding_run(ctxt, part, &encoder);
        /* OpenEXR before 3.4.8 (Debian 12 ships 3.1.5) stores zlib output whose size equals the raw
         * chunk's as if it were raw, and readers decode garbage (openexr issue #2306). A compressed
         * chunk the size of the raw one is ambiguous: the caller then writes the file uncompressed. */
        if (rv == EXR_ERR_SUCCESS && compression != EXR_COMPRESSION_NONE &&
            encoder.compressed_bytes == encoder.packed_bytes) {
            *ambiguous = 1;
            break;
        }
    }
    if (initialized)
        exr_encoding_destroy(ctxt, &encoder);
    free(clamped);
    exr_result_t finish = exr_finish(&ctxt);
    return rv != EXR_ERR_SUCCESS ? rv : finish;
}

ic_result ic_image_write_exr(const char *path, const ic_image *img, const ic_image_write_options *opt, ic_error *err)
{
    if ((opt->meta_count && !opt->meta) || (opt->layer_count && !opt->layers))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: %u EXR attributes and %u layers, but no array of %s", path,
                            opt->meta_count, opt->layer_count, opt->meta_count && !opt->meta ? "attributes" : "layers");
    for (uint32_t i = 0; i < opt->meta_count; ++i)
        if (!opt->meta[i].name || !*opt->meta[i].name || strlen(opt->meta[i].name) >= 256)
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: EXR attribute %u has an empty or too long name", path,
                                i);
    for (uint32_t i = 0; i < opt->layer_count; ++i) {
        const ic_image *l = opt->layers[i].image;
        const char *n = opt->layers[i].name;
        if (!n || !*n || strlen(n) >= 200 || strchr(n, '.'))
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: EXR layer %u has an empty, too long or dotted name", path,
                                i);
        if (!l || !l->rgb || l->width != img->width || l->height != img->height)
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: EXR layer %s is empty or not the image's size", path, n);
    }
    char tmp[4096];
    if (strlen(path) + 32 >= sizeof tmp)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: output path too long; use a shorter path", path);
    int made = ic_atomic_temp_name(path, tmp, sizeof tmp);
    if (made != 0)
        return ic_atomic_write_error(path, made, err);

    int open_errno = 0, ambiguous = 0, by_options = 0;
    exr_result_t rv = write_part(tmp, img, opt, EXR_COMPRESSION_ZIP, &ambiguous, &open_errno, &by_options);
    if (rv == EXR_ERR_SUCCESS && ambiguous) {
        remove(tmp);
        rv = write_part(tmp, img, opt, EXR_COMPRESSION_NONE, &ambiguous, &open_errno, &by_options);
    }
    if (rv != EXR_ERR_SUCCESS) {
        remove(tmp); /* the library deletes it on most errors; make sure */
        ic_atomic_temp_release(tmp);
        if (by_options)
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: OpenEXR refuses the layers or attributes given (%s): "
                                "give each layer once, and attributes names other than the header's own fields "
                                "(channels, compression, dataWindow, …)", path, exr_get_default_error_message(rv));
        if (rv == EXR_ERR_FILE_ACCESS && open_errno)
            return ic_atomic_write_error(path, open_errno, err);
        if (rv == EXR_ERR_FILE_ACCESS)
            return ic_error_set(err, IC_ERR_IO, "%s: cannot write (%s); check that the folder exists and is writable",
                                path, exr_get_default_error_message(rv));
        if (rv == EXR_ERR_OUT_OF_MEMORY)
            return ic_error_set(err, IC_ERR_OOM, "%s: out of memory writing OpenEXR; free memory and retry", path);
        return ic_error_set(err, IC_ERR_IO, "%s: writing OpenEXR failed (%s); check free disk space and retry", path,
                            exr_get_default_error_message(rv));
    }
    return ic_atomic_rename(tmp, path, err);
}

ic_result ic_image_exr_attribute(const char *path, const char *name, char *value, size_t cap, ic_error *err)
{
    if (!path || !name || !value || cap == 0)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "EXR attribute: no path, name or buffer");
    value[0] = '\0';
    exr_context_initializer_t init = context_initializer();
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_read(&ctxt, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctxt);
        return exr_read_failed(path, rv, err);
    }
    const exr_attribute_t *attr = NULL;
    rv = exr_get_attribute_by_name(ctxt, 0, name, &attr);
    ic_result r = IC_OK;
    if (rv != EXR_ERR_SUCCESS || !attr || attr->type != EXR_ATTR_STRING || !attr->string)
        r = ic_error_set(err, IC_ERR_INVALID_ARG, "%s: no text attribute %s", path, name);
    else
        snprintf(value, cap, "%.*s", (int)attr->string->length, attr->string->str ? attr->string->str : "");
    exr_finish(&ctxt);
    return r;
}
