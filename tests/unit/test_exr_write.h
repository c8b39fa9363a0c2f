/*
 * test_exr_write.h — OpenEXR files written with OpenEXR's own API, as renderers and texture tools make
 * them: a tiled one, and a scanline one with extra channels beside the colour. For the tests that read
 * such files: test_image (the reader) and test_env_tiled (an environment map). The test links
 * OpenEXR::OpenEXRCore.
 */
#ifndef IC_TEST_EXR_WRITE_H
#define IC_TEST_EXR_WRITE_H

#include "irrcache/image.h"

#include <OpenEXR/openexr.h>

#include <stdlib.h>
#include <string.h>

/* The start of a chunk's encoding, once its chunk info is made: the pipeline set up on the first chunk,
 * updated on the next ones. */
static inline exr_result_t test_exr_begin(exr_context_t ctxt, int part, const exr_chunk_info_t *chunk,
                                          exr_encode_pipeline_t *enc, int *initialized)
{
    exr_result_t rv = *initialized ? exr_encoding_update(ctxt, part, chunk, enc)
                                   : exr_encoding_initialize(ctxt, part, chunk, enc);
    if (rv == EXR_ERR_SUCCESS)
        *initialized = 1;
    return rv;
}

/* The end of a chunk's encoding, once its channels' pointers are set: the library's routines, then run. */
static inline exr_result_t test_exr_encode(exr_context_t ctxt, int part, exr_encode_pipeline_t *enc)
{
    exr_result_t rv = exr_encoding_choose_default_routines(ctxt, part, enc);
    return rv == EXR_ERR_SUCCESS ? exr_encoding_run(ctxt, part, enc) : rv;
}

/* Closes the file; whether everything (rv, the last step before) succeeded. */
static inline int test_exr_finish(exr_context_t *ctxt, exr_encode_pipeline_t *enc, int initialized, exr_result_t rv)
{
    if (initialized)
        exr_encoding_destroy(*ctxt, enc);
    exr_result_t fin = exr_finish(ctxt);
    return rv == EXR_ERR_SUCCESS && fin == EXR_ERR_SUCCESS;
}

/* Writes img as a tiled OpenEXR (one level, tw × th tiles, the last row and column partial) with
 * OpenEXR's own API, in float or half: what renderers and texture tools produce. */
static inline int write_tiled_exr(const char *path, const ic_image *img, int tw, int th, int half)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init);
    int part = 0;
    const exr_pixel_type_t type = half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_part(ctxt, NULL, EXR_STORAGE_TILED, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctxt, part, img->width, img->height, EXR_COMPRESSION_ZIP);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_set_tile_descriptor(ctxt, part, (uint32_t)tw, (uint32_t)th, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN);
    static const char *const names[3] = {"B", "G", "R"};
    for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; ++c)
        rv = exr_add_channel(ctxt, part, names[c], type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctxt);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int initialized = 0;
    for (int ty = 0; ty * th < img->height && rv == EXR_ERR_SUCCESS; ++ty)
        for (int tx = 0; tx * tw < img->width && rv == EXR_ERR_SUCCESS; ++tx) {
            exr_chunk_info_t chunk;
            rv = exr_write_tile_chunk_info(ctxt, part, tx, ty, 0, 0, &chunk);
            if (rv == EXR_ERR_SUCCESS)
                rv = test_exr_begin(ctxt, part, &chunk, &enc, &initialized);
            if (rv != EXR_ERR_SUCCESS)
                break;
            for (int c = 0; c < enc.channel_count; ++c) {
                exr_coding_channel_info_t *ch = &enc.channels[c];
                int slot = ch->channel_name[0] == 'R' ? 0 : ch->channel_name[0] == 'G' ? 1 : 2;
                ch->encode_from_ptr =
                    (const uint8_t *)(img->rgb + 3 * ((size_t)ty * th * img->width + (size_t)tx * tw) + slot);
                ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
                ch->user_line_stride = 3 * img->width * (int32_t)sizeof(float);
                ch->user_data_type = EXR_PIXEL_FLOAT;
                ch->user_bytes_per_element = (int16_t)sizeof(float);
            }
            rv = test_exr_encode(ctxt, part, &enc);
        }
    return test_exr_finish(&ctxt, &enc, initialized, rv);
}

/* One channel of write_scanline_exr's file: its name, its type and its vertical sub-sampling; its value
 * at pixel (x, y) is img's R, G or B for those names (the first letter after an optional "layer."),
 * img's R for "Y", and extra(x, y) = 0.25 (x + 2y) + 1 for any other. */
typedef struct {
    const char *name;
    exr_pixel_type_t type;
    int y_sampling;
} test_exr_channel;

static inline float test_exr_extra(int x, int y)
{
    return 0.25f * (float)(x + 2 * y) + 1.0f;
}

/* Writes img as a scanline OpenEXR with the given channels (in any order: the library sorts them), with
 * OpenEXR's own API, as other tools write extra channels (alpha, depth, ids) beside the colour. */
static inline int write_scanline_exr(const char *path, const ic_image *img, const test_exr_channel *channels,
                                     int channel_count, exr_compression_t compression)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init);
    int part = 0;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_part(ctxt, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctxt, part, img->width, img->height, compression);
    for (int c = 0; c < channel_count && rv == EXR_ERR_SUCCESS; ++c)
        rv = exr_add_channel(ctxt, part, channels[c].name, channels[c].type, EXR_PERCEPTUALLY_LOGARITHMIC, 1,
                             channels[c].y_sampling);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctxt);
    int32_t lines = 1;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_scanlines_per_chunk(ctxt, part, &lines);
    /* The extra channels' values, whole image, as floats (the library converts to half). */
    float *extra = (float *)malloc(sizeof(float) * (size_t)img->width * (size_t)img->height);
    if (!extra)
        rv = EXR_ERR_OUT_OF_MEMORY;
    for (int y = 0; extra && y < img->height; ++y)
        for (int x = 0; x < img->width; ++x)
            extra[(size_t)y * img->width + x] = test_exr_extra(x, y);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int initialized = 0;
    for (int y = 0; y < img->height && rv == EXR_ERR_SUCCESS; y += lines) {
        exr_chunk_info_t chunk;
        rv = exr_write_scanline_chunk_info(ctxt, part, y, &chunk);
        if (rv == EXR_ERR_SUCCESS)
            rv = test_exr_begin(ctxt, part, &chunk, &enc, &initialized);
        if (rv != EXR_ERR_SUCCESS)
            break;
        for (int c = 0; c < enc.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            const char *n = strchr(ch->channel_name, '.') ? strchr(ch->channel_name, '.') + 1 : ch->channel_name;
            int slot = !strcmp(n, "R") || !strcmp(n, "Y") ? 0 : !strcmp(n, "G") ? 1 : !strcmp(n, "B") ? 2 : -1;
            if (slot >= 0) {
                ch->encode_from_ptr = (const uint8_t *)(img->rgb + 3 * (size_t)y * img->width + slot);
                ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
                ch->user_line_stride = 3 * img->width * (int32_t)sizeof(float);
            } else {
                ch->encode_from_ptr = (const uint8_t *)(extra + (size_t)y * img->width);
                ch->user_pixel_stride = (int32_t)sizeof(float);
                /* a sub-sampled channel's lines are every y_sampling-th line of the image */
                ch->user_line_stride = ch->y_samples * img->width * (int32_t)sizeof(float);
            }
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
        }
        rv = test_exr_encode(ctxt, part, &enc);
    }
    free(extra);
    return test_exr_finish(&ctxt, &enc, initialized, rv);
}

#endif
