/*
 * test_exr_write.h — writing a tiled OpenEXR with OpenEXR's own API (as renderers and texture tools make
 * them), for the tests that read such files: test_image (the reader) and test_env_tiled (an environment
 * map). The test links OpenEXR::OpenEXRCore.
 */
#ifndef IC_TEST_EXR_WRITE_H
#define IC_TEST_EXR_WRITE_H

#include "irrcache/image.h"

#include <OpenEXR/openexr.h>

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
                rv = initialized ? exr_encoding_update(ctxt, part, &chunk, &enc)
                                 : exr_encoding_initialize(ctxt, part, &chunk, &enc);
            if (rv != EXR_ERR_SUCCESS)
                break;
            initialized = 1;
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
            rv = exr_encoding_choose_default_routines(ctxt, part, &enc);
            if (rv == EXR_ERR_SUCCESS)
                rv = exr_encoding_run(ctxt, part, &enc);
        }
    if (initialized)
        exr_encoding_destroy(ctxt, &enc);
    exr_result_t fin = exr_finish(&ctxt);
    return rv == EXR_ERR_SUCCESS && fin == EXR_ERR_SUCCESS;
}

#endif
